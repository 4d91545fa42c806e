/*
 * libFuzzer harness: whole N5 stores (src/io/store/n5.c through the Zarr
 * reader and pyramid): the attributes.json of a dataset (dimensions,
 * blockSize, dataType, compression) or of a multiscale group (scales,
 * downsamplingFactors, resolution, pixelResolution, axes, units, COSEM
 * multiscales), and the blocks (their big-endian headers: mode, dimensions,
 * sizes, element counts; the compressed voxels). The input is fuzz_zarr.c's
 * container of files, and the reads are its: the store read whole, then
 * opened whole and out of core, a box of every level read. The one harness
 * source, built three times (corpus: tests/fuzz/corpus/n5, seeded by
 * tests/fuzz/make_corpus_n5.py from stores tensorstore writes).
 */
#define FUZZ_STORE_N5 1
#include "fuzz_zarr.c"
