/*
 * OME-Zarr (not installed): the reader (zarr_read.c) for the format record
 * in zarr_write.c, and what the pyramid source (zarr_pyramid.c) shares
 * with it: the parsed metadata of one level's array and its chunk reads.
 */
#ifndef VOLVIS_IO_ZARR_H
#define VOLVIS_IO_ZARR_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/io.h"
#include "volvis/sys/format.h"

#define ZR_MAX_DIM 5
#define ZR_JSON_MAX (16u << 20)
#define ZR_CHUNK_MAX ((uint64_t)1 << 30)
/* The most chunks a whole read looks for (each a file to open). */
#define ZR_READ_CHUNKS_MAX (1 << 20)

typedef struct zr_axis {
    char name[32];
    int kind; /* 0 space, 1 channel, 2 time */
    char unit[32];
} zr_axis;

/* One level's array and what the metadata says of it. */
typedef struct zr_array {
    char dir[4096];
    char real[4096]; /* the store's real path: chunks must resolve beneath it ("": unknown) */
    int ndim;
    uint64_t shape[ZR_MAX_DIM], chunks[ZR_MAX_DIM];
    vv_voxel_type type;
    int swap; /* stored in the other byte order */
    size_t esize;
    char codec[16]; /* "" raw, zlib, gzip, zstd, blosc */
    char sep;
    double fill;
    zr_axis axes[ZR_MAX_DIM];
    double scale[ZR_MAX_DIM], trans[ZR_MAX_DIM];
} zr_array;

/* How one channel at one time step of an array maps onto a volume: the
 * channel and time axes (-1: none), the array axes of the volume's i, j, k
 * (k -1 for a 2-D array), its dims, the chunk strides (elements, C order)
 * and counts per array axis, the chunk's bytes, the chunk box (cdims) and
 * chunk counts (nchunks) along i, j, k. */
typedef struct zr_layout {
    const zr_array *a;
    int cax, tax, vax[3], dims[3];
    uint64_t ch, tp, nc, nt;
    uint64_t cstride[ZR_MAX_DIM], nchunk[ZR_MAX_DIM];
    size_t cbytes;
    int cdims[3], nchunks[3];
} zr_layout;

/* The metadata of level @p level of the store at @p root into @p a (its
 * folder, .zarray, axes, scale and translation), the channel's omero name
 * and colour into @p info (may be NULL), the number of levels into
 * *n_levels (may be NULL; 1 for a plain array). Errors as vv_ome_zarr_read
 * (not prefixed). */
vv_status vv_zr_parse_store(const char *root, int level, zr_array *a, int channel,
                            vv_load_info *info, int *n_levels);

/* The layout of channel @p channel at step @p time (-1: 0) of @p a. Errors:
 * VV_ERR_UNSUPPORTED (axes), VV_ERR_LIMIT, VV_ERR_INVALID (out of range). */
vv_status vv_zr_layout(const zr_array *a, int channel, int time, zr_layout *J);

/* The volume's spacing, origin (the level's scale and translation along
 * i, j, k), unit and modification (original) from @p J's array. */
void vv_zr_geometry(const zr_layout *J, vv_volume *v);

/* The spatial chunk index (C order over the array's spatial axes) of the
 * chunk at position c (along i, j, k). */
uint64_t vv_zr_chunk_linear(const zr_layout *J, const int c[3]);

/* Spatial chunk @p L at the layout's channel and step: read and decoded
 * into @p buf (J->cbytes), its voxels inside the array copied into @p dst,
 * an array of ddims voxels (i fastest) whose voxel (0, 0, 0) is the
 * volume's voxel dorg (it must hold the chunk's part inside the array).
 * *missing (may be NULL) = 1 when the chunk file is absent (the fill
 * value); *file_bytes (may be NULL) = the bytes read from the file.
 * Errors: VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_LIMIT, VV_ERR_NOMEM, naming the
 * chunk's file. Reentrant. */
vv_status vv_zr_copy_chunk(const zr_layout *J, uint64_t L, unsigned char *buf, unsigned char *dst,
                           const int dorg[3], const int ddims[3], int *missing,
                           uint64_t *file_bytes);

/* Reads and decodes chunk file @p path into @p out (exactly @p n bytes); 0
 * with *missing = 1 when the file does not exist; *file_bytes (may be NULL)
 * the bytes read. */
vv_status vv_zr_read_chunk(const zr_array *a, const char *path, unsigned char *out, size_t n,
                           int *missing, uint64_t *file_bytes);

/* @p n voxels of type @p t at @p dst set to @p x (the fill value, cast). */
void vv_zr_fill(void *dst, size_t n, vv_voxel_type t, double x);

/**
 * Reads channel opt->channel at step opt->time of level opt->level of the OME-Zarr
 * store (or plain Zarr v2 array) at folder @p path, with vv_volume_load's
 * contract; opt->info gets the channel and time counts, the omero name and
 * colour and the time between steps. Errors (prefixed "zarr: NAME"):
 * VV_ERR_FORMAT (malformed metadata, a chunk that does not decode to its
 * size), VV_ERR_UNSUPPORTED (dtype, compressor, filters, F order, axes),
 * VV_ERR_LIMIT, VV_ERR_INVALID (a channel or step out of range), VV_ERR_IO,
 * VV_ERR_NOMEM. Reentrant.
 */
vv_status vv_ome_zarr_read(vv_volume **out, const char *path, const vv_load_options *opt);

/** A folder holding a .zarray, or a .zattrs with "multiscales" (deep 0 only). */
int vv_ome_zarr_looks_like(const vv_format_probe *p, int deep);

#endif
