/*
 * The per-format entry points of io: each format's reader and writer as its
 * row of the format table (src/io/formats.c) calls it. They are not public
 * (DESIGN.md, "The door"): a front end reads through vv_volume_load, vv_open,
 * vv_grid_load or vv_mesh_load and writes through vv_volume_save_with,
 * vv_volume_save_boxes or vv_mesh_save, so a third-party parser is never
 * reachable around the sandbox. The files of io call them; so do the tests
 * and fuzz harnesses of one format's parser, which want that parser alone,
 * in this process.
 *
 * Contracts are those of the table's entry points (include/volvis/io.h):
 * *out owned by the caller and NULL on error, errors traced with the format
 * and file name, writers atomic. Thread-safety: reentrant; calls into Teem
 * are serialised internally.
 */
#ifndef VV_IO_INTERNAL_H
#define VV_IO_INTERNAL_H

#include "volvis/bricks.h"
#include "volvis/grid.h"
#include "volvis/io.h"
#include "volvis/mesh.h"
#include "volvis/sys/format.h"
#include "volvis/sys/source.h"

/* ---- volumes: readers and writers ----------------------------------------- */

/** SLC, plain or run-length compressed. */
vv_status vv_slc_read(vv_volume **out, const char *path);
/** Writes 8-bit SLC, RLE-compressed when @p rle, with a maximum-projection icon. */
vv_status vv_slc_write(const vv_volume *v, const char *path, int rle);

/** NRRD through Teem (attached or detached header, lists, patterns). */
vv_status vv_nrrd_read(vv_volume **out, const char *path);
/** Writes NRRD with gzip encoding (raw when @p gzip is 0), spacing and origin. */
vv_status vv_nrrd_write(const vv_volume *v, const char *path, int gzip);

/** NIfTI-1/NIfTI-2 (.nii, .nii.gz, .hdr/.img) through nifti_clib; scaling applied. */
vv_status vv_nifti_read(vv_volume **out, const char *path);
/**
 * Writes NIfTI-1 (NIfTI-2 when opt->nifti_version is 2 or an axis is over
 * 32767 voxels) as one file: .nii, or .nii.gz gzip-compressed. Voxel type,
 * spacing, origin and direction are kept (an LPS volume's world turned into
 * NIfTI's RAS); sform always, qform when the direction is orthonormal;
 * intent NIFTI_INTENT_LABEL when opt->label. Atomic. @p opt may be NULL.
 * Errors: VV_ERR_UNSUPPORTED (another extension; a float label volume;
 * NIfTI-1 asked for a volume it cannot hold), VV_ERR_INVALID, VV_ERR_IO.
 */
vv_status vv_nifti_write(const vv_volume *v, const char *path, const vv_save_options *opt);
/** MetaImage .mhd (detached data) or .mha (LOCAL data), optionally zlib-compressed. */
vv_status vv_mhd_read(vv_volume **out, const char *path);
/**
 * Writes MetaImage: .mha (one file) or .mhd with its data beside it (.raw,
 * or .zraw when compressed), every voxel type, spacing, origin and
 * direction (a RAS volume's world turned into ITK's LPS); zlib-compressed
 * unless @p compress is 0. Atomic (an .mhd's data file is removed when its
 * header cannot be written). Errors: VV_ERR_UNSUPPORTED (another
 * extension), VV_ERR_INVALID, VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_mhd_write(const vv_volume *v, const char *path, int compress);
/** VTK legacy STRUCTURED_POINTS, BINARY (big-endian) or ASCII, first SCALARS array
 *  (its first component; vv_volume_load's channel picks another of its 1..4). */
vv_status vv_vtk_read(vv_volume **out, const char *path);
/**
 * Writes VTK legacy STRUCTURED_POINTS, BINARY (big-endian voxels, as the
 * format defines them), every voxel type, origin and spacing; the format has
 * no direction matrix, so an oblique volume is written axis-aligned (the
 * format record's fits says so first). Atomic. Errors: VV_ERR_INVALID (no
 * data, non-finite geometry), VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_vtk_write(const vv_volume *v, const char *path);
/**
 * Writes VTK XML image data (.vti, as ParaView reads it): WholeExtent,
 * Origin, Spacing and Direction (row-major, VTK >= 9), the voxels as one
 * point-data array "scalars" of the volume's type in one appended block,
 * zlib-compressed in VTK's block layout when @p compress, raw otherwise;
 * the host's byte order, UInt64 headers. Atomic. Errors: as vv_vtk_write.
 */
vv_status vv_vti_write(const vv_volume *v, const char *path, int compress);
/**
 * Writes @p v as an OME-Zarr 0.4 store (a Zarr v2 folder, src/io/store/zarr_write.c):
 * levels 0..L, each half the previous along every axis longer than one
 * voxel, until every axis fits a chunk; a voxel of the next level is the
 * mean of its 2x2x2 voxels (rounded for integers) or, with opt->label, the
 * first of them. Arrays [z][y][x] in C order, chunks of at most 64^3,
 * little-endian voxels of the volume's type, zlib level 1 unless
 * opt->compress is 0; "/" dimension separator. Metadata: multiscales with
 * axes z, y, x (space; the unit as OME-NGFF names it when known), each
 * level's scale (spacing x factor) and translation (origin, shifted to the
 * centre of the averaged voxels), omero (one channel, the value range as
 * its window), image-label for labels. No direction matrix (the record's
 * fits says so). Atomic: written into "<path>.tmp-<owner>" (vv_tmp_name),
 * synced, then renamed into place or exchanged with an old store (an
 * existing path that is not a Zarr store is refused and left as it is);
 * temporaries of writers of @p path that were killed are removed first. Chunks are written on
 * every core. @p opt may be NULL. Errors: VV_ERR_INVALID (no data, a
 * non-positive spacing), VV_ERR_UNSUPPORTED (a float label volume), VV_ERR_IO
 * (nothing is left behind), VV_ERR_NOMEM.
 */
vv_status vv_ome_zarr_write(const vv_volume *v, const char *path, const vv_save_options *opt);

/**
 * Writes @p m as VTK XML PolyData (.vtp): Float32 points, per-vertex normals
 * ("Normals") and scalars (named @p scalar_name, "scalars" when NULL: the
 * label or the field the surface was extracted from) when the mesh has
 * them, the triangles as Int64 connectivity and offsets, one raw appended
 * block each. Atomic. Errors: VV_ERR_INVALID (empty mesh, a name that is not
 * plain text), VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_vtp_write(const vv_mesh *m, const char *path, const char *scalar_name);
/**
 * Raw voxels described by @p params (borrowed). The file must hold at least
 * header_skip + the volume's bytes; VV_ERR_FORMAT names both sizes otherwise.
 */
vv_status vv_raw_read(vv_volume **out, const char *path, const vv_raw_params *params);

/**
 * A TIFF stack: @p path is a multi-page TIFF (also BigTIFF) or a folder whose
 * .tif/.tiff files (sorted by name, digit runs compared as numbers) are the
 * pages in order. Pages must agree in size and sample type: 8/16/32-bit
 * integers (signed or not) and 32/64-bit floats, striped or tiled, any
 * compression libtiff decodes (none, LZW, deflate, PackBits, ...). OME-TIFF
 * (PhysicalSizeX/Y/Z, SizeZ/SizeC/SizeT, DimensionOrder) and ImageJ
 * hyperstacks (images/channels/slices/frames, spacing, unit, X/YResolution)
 * give the spacing and the channel layout; the volume is the first time
 * point of channel @p channel (-1: 0), which also picks a sample of a
 * multi-sample (RGB) page. Errors name the file, the page and the strip or
 * tile: VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_LIMIT (sizes are checked before
 * allocation), VV_ERR_UNSUPPORTED, VV_ERR_INVALID (channel out of range).
 */
vv_status vv_tiff_read(vv_volume **out, const char *path, int channel);

/**
 * Writes @p v to @p path as a multi-page TIFF through libtiff, atomically:
 * page k is slice k (dims[0] x dims[1] pixels, one sample, row 0 first),
 * in the voxel type (8/16/32-bit integers with SampleFormat UINT or INT,
 * 32/64-bit IEEE floats), strips of at most 256 KiB, compressed by
 * opt->codec (deflate by default; integers with horizontal
 * differencing). A name ending .ome.tif or .ome.tiff gets OME-XML (OME
 * 2016-06: Pixels XYZCT, PhysicalSizeX/Y/Z in the volume's unit, "pixel"
 * when unknown, a Plane per slice with its position), any other name
 * ImageJ's keys (slices, spacing, unit, the origin in voxels) and
 * X/YResolution = 1 / spacing. BigTIFF when opt->bigtiff or the voxels
 * reach 3.75 GiB. The direction matrix is not held (the record's fits
 * says so). @p opt may be NULL (the defaults). Errors: VV_ERR_INVALID (no
 * data, a non-positive spacing, an unknown codec), VV_ERR_UNSUPPORTED (a
 * codec this libtiff lacks), VV_ERR_IO (with libtiff's message; nothing is
 * left behind), VV_ERR_NOMEM. Reentrant.
 */
vv_status vv_tiff_write(const vv_volume *v, const char *path, const vv_save_options *opt);

/**
 * Reads series @p series (1-based as listed by vv_dicom_list; 0: the only
 * one) of @p path into a volume. Slices are sorted by Image Position
 * (Patient) along the slice normal (cross product of Image Orientation
 * (Patient)'s row and column directions); the slice spacing is the distance
 * between positions, and uneven spacing, a missing slice or two slices at one
 * position are errors naming the files and the gap. Rescale Slope and
 * Intercept are applied (CT in Hounsfield units): the volume is i16/u16/i32
 * when every slope is 1 and every intercept an integer and the rescaled range
 * fits, else f32. Multi-frame files (enhanced CT/MR, one file per series)
 * take their frame positions from the per-frame functional groups. Geometry:
 * direction columns are the row direction, the column direction and the
 * slice normal, origin the first slice's position, both converted from
 * DICOM's LPS to RAS (x and y negated) with space VV_SPACE_RAS, unit mm.
 * Compressed transfer syntaxes (JPEG baseline/extended/lossless, JPEG-LS,
 * JPEG 2000, RLE, deflate) are decoded by GDCM. @p channel picks a sample of
 * multi-sample (RGB) images (-1: 0). No patient identifier is kept.
 * Errors name the file: VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_LIMIT,
 * VV_ERR_UNSUPPORTED, VV_ERR_INVALID (series out of range).
 */
vv_status vv_dicom_read(vv_volume **out, const char *path, int series, int channel);

/** Like vv_dicom_read for an explicit list of @p n DICOM files. */
vv_status vv_dicom_read_files(vv_volume **out, const char *const *files, int n, int series,
                              int channel);

/* ---- volumes written box by box ------------------------------------------- */

/**
 * Writes the OME-Zarr store of vv_ome_zarr_write (the same levels, chunks
 * and bytes) from a volume that need not fit in memory: level 0 a row of
 * chunks (the volume's width x 64 x 64 voxels) at a time from @p read,
 * called from one thread at a time, and each further level from the level
 * before, read back from the store being written (the 2x2x2 blocks under
 * each of its chunks). Memory a thread: one row of chunks for level 0, about
 * nine chunks for the others (128^3 voxels of the level before, one chunk
 * and their compressed bytes), whatever the volume's depth. @p hdr gives the
 * dims, type, spacing, origin and unit (its voxels are never read); the
 * omero window is the range of the voxels read. Chunks are compressed and
 * written on every core. Atomic as vv_ome_zarr_write. Errors: those of
 * vv_ome_zarr_write, the reader's first error (nothing is left behind),
 * VV_ERR_INVALID (a box of another shape or type from @p read).
 */
vv_status vv_ome_zarr_write_boxes(const vv_volume *hdr, vv_box_reader read, void *ctx,
                                  const char *path, const vv_save_options *opt);

/**
 * Writes the in-memory volume @p v as a .vvb file (for formats that cannot
 * be read by bricks: compressed NRRD, SLC, NIfTI, ...); @p flags as
 * vv_bricked_write_vvb. Errors: VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_volume_write_vvb(const vv_volume *v, const char *path, unsigned flags);

/**
 * Writes a .vvb file of the volume @p hdr describes (dims, type, geometry;
 * its voxels are not read) from a box reader, one brick (with its ghost
 * voxels) at a time in brick order (i fastest, then j, then k): memory is
 * the reader's and a brick's (vv_slabs: one slab of 66 slices, the ghost
 * slices the next layer of bricks shares kept). @p flags as
 * vv_bricked_write_vvb. Atomic as it: on failure nothing is left. Errors:
 * VV_ERR_IO, VV_ERR_NOMEM, the reader's, VV_ERR_INVALID (a box of another
 * shape or type from @p read).
 */
vv_status vv_boxes_write_vvb(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                             unsigned flags, const vv_progress *progress);

/* ---- irregular grids: readers (the contract of vv_grid_load) ------------------ */

/** VTK legacy UNSTRUCTURED_GRID, ASCII or binary (also the 5.1 OFFSETS /
 *  CONNECTIVITY form). */
vv_status vv_grid_read_vtk(vv_grid **out, const char *path);
/** VTK XML UnstructuredGrid (.vtu, one piece) through libxml2: inline or
 *  appended, raw or base64, zlib; DOCTYPE and entities are refused. */
vv_status vv_grid_read_vtu(vv_grid **out, const char *path);
/** OpenDX native file: positions, connections (tetrahedra, cubes) and data,
 *  text or binary. */
vv_status vv_grid_read_dx(vv_grid **out, const char *path);
/** PLOT3D grid (.xyz / .bin) with its solution (.q) in @p q_path, which may
 *  be NULL (the grid alone); the layout (record markers, blocks, byte
 *  order, precision, IBLANK) is found from the file size. */
vv_status vv_grid_read_plot3d(vv_grid **out, const char *xyz_path, const char *q_path);
/** NetCDF with CF conventions (a spherical grid of cell data from
 *  longitude, latitude and depth axes); VV_ERR_UNSUPPORTED in a build
 *  without libnetcdf. */
vv_status vv_grid_read_netcdf(vv_grid **out, const char *path);

/* ---- the format table's helpers for its rows (src/io/formats.c) --------------------- */

/**
 * The format of @p path among those holding @p kind (-1: any), by asking
 * the records' looks_like once (signatures, then the deep tests unless
 * @p deep is 0): its id, or VV_FORMAT_UNKNOWN. The deep tests of
 * third-party formats may call their parsers: vv_open runs those in the
 * reader sandbox.
 */
vv_format vv_format_detect_kind(const char *path, int kind, int deep);

/**
 * For the folder tests of looks_like: calls @p match with each entry of
 * folder @p path (its path, its name, 1 for a folder), hidden entries
 * skipped and at most 4096 files looked at, until it returns 1. Returns 1
 * when an entry matched, 0 otherwise (also when the folder cannot be read).
 */
int vv_format_folder_any(const char *path,
                         int (*match)(const char *entry, const char *name, int is_dir, void *ctx),
                         void *ctx);

/** 1 when @p path ends in ".@p ext" (case-insensitive; @p ext may hold dots). */
int vv_format_path_has_ext(const char *path, const char *ext);

/**
 * Fills @p p for @p path: whether it is a folder, and for a file its first
 * VV_FORMAT_PROBE_BYTES bytes (decompressed when gzip) in @p buf, which must
 * hold VV_FORMAT_PROBE_BYTES + 1 bytes. Returns 0, or the errno of a file
 * that cannot be opened or read (the probe is then empty).
 */
int vv_format_probe_fill(vv_format_probe *p, const char *path, unsigned char *buf, char *text);

#endif
