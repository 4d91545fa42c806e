/*
 * libFuzzer harness: whole Neuroglancer precomputed volumes
 * (src/io/store/precomputed.c through the Zarr reader and pyramid): the
 * info (type, data_type, num_channels, scales: key, size, voxel_offset,
 * resolution, chunk_sizes, encoding, sharding) and the chunk files of its
 * scales (raw, raw as a gzip stream, jpeg; cut at a scale's end). The input
 * is fuzz_zarr.c's container of files, and the reads are its: the volume
 * read whole, then opened whole and out of core, a box of every level read.
 * The one harness source, built three times (corpus:
 * tests/fuzz/corpus/precomputed, seeded by tests/fuzz/make_corpus_n5.py
 * from volumes tensorstore writes).
 */
#define FUZZ_STORE_PRECOMPUTED 1
#include "fuzz_zarr.c"
