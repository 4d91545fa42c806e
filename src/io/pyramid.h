/*
 * A pyramid's store: the format's side of vv_pyramid (src/io/pyramid.c;
 * include/volvis/bricks.h). The cache, the frame's plan, the statistics and
 * the source interface are the pyramid's; a store only says what its
 * levels are and fetches one chunk's voxels. Two formats have one:
 * OME-Zarr (src/io/zarr_pyramid.c) and the HDF5 pyramids of BigDataViewer
 * and Imaris (src/io/hdf5_pyramid.c). Either is opened in long-lived
 * sandboxed readers, two a thread, behind a store that forwards each
 * chunk and fetches the plan's next ones ahead (vv_sandbox_store_open,
 * src/io/sandbox.c), or in this process with VOLVIS_SANDBOX=0. A remote store (HTTP) would be a
 * third format: a chunk fetcher behind read_chunk.
 */
#ifndef VOLVIS_IO_PYRAMID_H
#define VOLVIS_IO_PYRAMID_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/bricks.h"

/** One level of a store. */
typedef struct pyr_store_level {
    /**
     * The level's geometry as a volume of one voxel whose dims are set to
     * the level's (dims, type, spacing, origin of its voxel 0, direction,
     * unit); owned by the store until vv_pyramid_open_store takes it.
     */
    vv_volume *hdr;
    int cdims[3]; /**< the chunk box (voxels along x, y, z), >= 1 */
} pyr_store_level;

/** A pyramid's store (filled by its opener; the pyramid takes it whole). */
typedef struct pyr_store {
    const char *name; /**< the format's name for errors ("zarr", "hdf5") */
    void *ctx;        /**< the store's state, freed by close */
    int n_levels;     /**< 1 .. VV_PYRAMID_MAX_LEVELS, finest first */
    pyr_store_level lv[VV_PYRAMID_MAX_LEVELS];
    int n_channels, n_times; /**< for vv_load_info */
    int has_range;           /**< 1: range is the data's (an omero window) */
    double range[2];
    size_t scratch; /**< bytes of scratch each read_chunk call needs (0: none) */
    int parallel;   /**< 1: read_chunk may run on several threads at once (else the pyramid
                         serializes it, its loader's reads included) */
    /**
     * Chunk @p c (chunk indices along x, y, z) of @p level: its voxels
     * inside the level, box org .. org + dims - 1, written to @p dst (x
     * fastest, the level's type); @p scratch holds the store's scratch
     * bytes. *missing: 1 when the chunk is absent and was filled with the
     * fill value; *file_bytes: the bytes read from storage. Errors:
     * VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_NOMEM, VV_ERR_LIMIT (naming the
     * chunk).
     */
    vv_status (*read_chunk)(void *ctx, int level, const int c[3], unsigned char *scratch,
                            unsigned char *dst, const int org[3], const int dims[3], int *missing,
                            uint64_t *file_bytes);
    void (*close)(void *ctx);
    /**
     * Optional (NULL): start fetching chunk @p c of @p level ahead of its
     * read_chunk, without waiting (a later read_chunk of it takes the
     * result; one of another chunk may drop it). 1: asked (or already
     * asked); 0: nothing free to ask, stop. Called from the frame's thread,
     * never during its own read_chunk calls (the pyramid's loader threads
     * may be reading meanwhile: read_chunk may then take a reader asked
     * ahead and drop what it fetched).
     */
    int (*prefetch)(void *ctx, int level, const int c[3]);
    /**
     * Optional (NULL): the range of chunk @p c of @p level's voxels as the
     * store's index gives it before any voxel is read (a .vvb: its chunks'
     * min and max; level 0's from its bricks, a superset); 1 when known.
     * Asked once per chunk when the pyramid opens, so that empty space is
     * skipped before its chunks are read; a chunk decoded later gives its
     * own range.
     */
    int (*chunk_range)(void *ctx, int level, const int c[3], double *lo, double *hi);
} pyr_store;

/**
 * A pyramid over store @p st, taken whole (closed and its headers freed on
 * error too), under a memory limit of @p memory_limit bytes (0: 1 GiB);
 * @p path names it in errors; *info (may be NULL) gets the channel, time
 * step and level counts. Errors as vv_pyramid_open.
 */
vv_status vv_pyramid_open_store(vv_pyramid **out, pyr_store *st, const char *path,
                                uint64_t memory_limit, vv_load_info *info);

/**
 * Level @p level's header (one voxel of @p type, its dims set to
 * @p dims; the caller sets its geometry) and chunk box @p cdims. Errors:
 * VV_ERR_NOMEM.
 */
vv_status vv_pyr_store_level(pyr_store *st, int level, vv_voxel_type type, const int dims[3],
                             const int cdims[3]);

/** Frees what a store holds (its headers and, through close, its state). */
void vv_pyr_store_close(pyr_store *st);

/** The OME-Zarr store of @p path (channel, time step, level 0's info). */
vv_status vv_zr_pyramid_store(pyr_store *st, const char *path, int channel, int time,
                              vv_load_info *info);

/**
 * The store of @p path read in this process: an HDF5 file's
 * (vv_h5_pyramid_store) or a Zarr store's (vv_zr_pyramid_store).
 */
vv_status vv_pyr_store_open_local(pyr_store *st, const char *path, int channel, int time,
                                  vv_load_info *info);

/** Voxel @p i of @p d (of type @p t) as a double. */
double vv_pyr_voxel(const void *d, vv_voxel_type t, size_t i);

/** A box of a pyramid's next level and the voxels under it (vv_pyr_reduce). */
typedef struct vv_pyr_reduce_box {
    const void *src;    /**< the level before's voxels src_lo .. src_lo + src_n - 1, x fastest */
    vv_voxel_type type; /**< of both levels */
    int src_dims[3];    /**< the level before's dims (blocks at its edges are cut) */
    int src_lo[3], src_n[3];
    int step[3];     /**< 2 on halved axes, 1 on axes of one voxel */
    int label;       /**< 1: the first voxel of a block instead of the mean (labels) */
    int lo[3], n[3]; /**< the box, in voxels of the next level */
    int dst_dims[2]; /**< dst's row length and rows a slice (dst holds voxel lo at 0) */
} vv_pyr_reduce_box;

/**
 * The box @p b of a pyramid's next level into @p dst: each voxel the mean
 * of the step[0] x step[1] x step[2] voxels under it that lie inside the
 * level before (summed in z, y, x order as doubles; integer types rounded to
 * nearest), or with label the first of them. What the OME-Zarr and .vvb
 * writers store, voxel for voxel the same. Thread-safe.
 */
void vv_pyr_reduce(const vv_pyr_reduce_box *b, void *dst);

/**
 * 0 when @p path is no .vvb file (its magic), else the pyramid levels its
 * header gives (1: the bricks only). Unchecked beyond that: a probe.
 */
int vv_vvb_probe(const char *path);

/**
 * The store of the .vvb file @p path (src/io/bricked.c), read in this
 * process: level 0 from its bricks, a chunk of 64^3 voxels from the brick
 * holding it, the levels above from their chunks. Channel and time step
 * must be 0 or -1. Errors: those of opening a .vvb (VV_ERR_FORMAT,
 * VV_ERR_IO, VV_ERR_LIMIT, VV_ERR_NOMEM), VV_ERR_INVALID.
 */
vv_status vv_vvb_pyramid_store(pyr_store *st, const char *path, int channel, int time);

/** 1 when @p path is an HDF5 file (its signature at offset 0). */
int vv_h5_is_hdf5(const char *path);

/** The store of a BigDataViewer HDF5 or Imaris file @p path, read in this process. */
vv_status vv_h5_pyramid_store(pyr_store *st, const char *path, int channel, int time);

#endif
