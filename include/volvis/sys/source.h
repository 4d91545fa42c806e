/*
 * VolVis volume sources, the implementor's side: what a bricked (and later
 * multiresolution) volume offers its consumers, so that the render driver
 * (src/render/bricks_render.c, vv_renderer_render_bricks) reads voxels
 * without knowing the file format, and a format reader (src/io: .vvb, raw,
 * NRRD; OME-Zarr and HDF5 pyramids next) serves them without knowing the
 * renderers. A version field first, as libgit2's plug-in structs.
 *
 * A source is a grid of bricks over a volume's index box. Brick b covers
 * the cells lo .. hi (voxel indices of its faces, shared with its
 * neighbours) and is read with one voxel more beyond each face (slo ..
 * shi, within the volume), so that trilinear samples and central
 * differences at its faces are the whole volume's; each brick has the min
 * and max of the voxels read (empty-space skipping before reading).
 *
 * A multiresolution source (vv_multires_source, below) serves a pyramid
 * of levels by boxes of voxels instead, for the level-of-detail driver
 * (vv_renderer_render_multires).
 *
 * Thread-safety: a source is used from one thread at a time.
 */
#ifndef VOLVIS_SYS_SOURCE_H
#define VOLVIS_SYS_SOURCE_H

#include "../core.h"
#include "../volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The version of vv_brick_source this header describes. */
#define VV_BRICK_SOURCE_VERSION 1

/** One brick's boxes and value range. */
typedef struct vv_brick_info {
    int lo[3], hi[3];   /**< the brick's cells: voxel indices lo .. hi (its faces) */
    int slo[3], shi[3]; /**< the voxels read: one beyond each face, within the volume */
    float vmin, vmax;   /**< min and max of the voxels read (data units) */
} vv_brick_info;

/** A bricked volume as its consumers see it; every method takes @p user. */
typedef struct vv_brick_source {
    int version; /**< VV_BRICK_SOURCE_VERSION */
    void *user;  /**< the source's state */
    /**
     * The volume's geometry as a volume whose voxels must not be read:
     * dims, type, spacing, origin, direction, value range, unit. Borrowed.
     */
    const vv_volume *(*header)(void *user);
    /** Bricks along each axis (brick index (i, j, k) = (k nb[1] + j) nb[0] + i). */
    void (*grid)(void *user, int nb[3]);
    /** Brick @p index's boxes and min/max. */
    void (*info)(void *user, int index, vv_brick_info *out);
    /**
     * Brick @p index as a new volume reference of its voxels slo .. shi with
     * the whole volume's spacing, origin, direction and value range (its
     * voxel (0, 0, 0) is the whole volume's voxel slo). Errors: VV_ERR_IO,
     * VV_ERR_FORMAT, VV_ERR_NOMEM.
     */
    vv_status (*load)(void *user, int index, vv_volume **out);
    /** Optional (NULL): counts a brick skipped unread (statistics). */
    void (*note_skip)(void *user);
} vv_brick_source;

/** The version of vv_multires_source this header describes. */
#define VV_MULTIRES_SOURCE_VERSION 2

/**
 * A multiresolution (pyramid) volume as its consumers see it: levels 0
 * (finest) .. n_levels - 1, each a regular grid of its own dims, spacing and
 * origin with the direction of level 0 (OME-Zarr multiscales, or one level:
 * a .vvb, raw or NRRD file), read by boxes of voxels through the source's
 * own chunk cache. Every method takes @p user. Thread-safety: a source is
 * used from one thread at a time (it may read with several).
 */
typedef struct vv_multires_source {
    int version;  /**< VV_MULTIRES_SOURCE_VERSION */
    void *user;   /**< the source's state */
    int n_levels; /**< >= 1 */
    /**
     * The side of the level-of-detail octree's leaves in level-0 cells (a
     * node reads about that many voxels of its level a side, plus ghosts):
     * the largest the source's memory limit holds with the chunks such a box
     * needs; 0: VV_BRICK_CELLS (64).
     */
    int node_cells;
    /**
     * Level @p level's geometry as a volume whose voxels must not be read:
     * dims, type, spacing, origin, direction, unit, and the value range of
     * the whole volume (the same at every level: it scales the transfer
     * function's tables, so every level's samples classify alike). Borrowed.
     */
    const vv_volume *(*level)(void *user, int level);
    /**
     * Voxels lo .. hi (inclusive; 0 <= lo <= hi < dims of the level) of
     * level @p level as a new volume reference whose voxel (0, 0, 0) is the
     * level's voxel lo, with the level's spacing, origin (of its voxel 0),
     * direction and the whole range. Errors: VV_ERR_IO, VV_ERR_FORMAT (a
     * chunk that does not decode), VV_ERR_LIMIT (the box and the chunks it
     * needs exceed the memory limit), VV_ERR_NOMEM.
     */
    vv_status (*read_box)(void *user, int level, const int lo[3], const int hi[3], vv_volume **out);
    /**
     * Optional (NULL): the min and max over voxels lo .. hi of @p level when
     * the source knows them without reading (an index, or chunks read
     * before): 1 and *vmin, *vmax set; 0 when unknown.
     */
    int (*box_range)(void *user, int level, const int lo[3], const int hi[3], float *vmin,
                     float *vmax);
    /** Optional (NULL): a frame begins (@p begin 1) or ends (0); for statistics. */
    void (*frame)(void *user, int begin);
    /**
     * Optional (NULL): the boxes the frame will read, in the order it reads
     * them (box i: level[i], voxels lo[3i .. 3i+2] .. hi[3i .. 3i+2],
     * inclusive); until the next plan or frame
     * end, read_box calls follow it one by one, and the source keeps the
     * chunks needed soonest (Belady's farthest-next-use eviction), so that
     * a chunk is read once a frame whenever the boxes' shared chunks fit.
     * Errors: VV_ERR_NOMEM (the reads then go unplanned).
     */
    vv_status (*plan)(void *user, int n, const int *level, const int *lo, const int *hi);
    /**
     * Optional (NULL): how many of the chunks holding voxels lo .. hi of
     * @p level are not in the source's cache (0: the box reads without I/O);
     * for progressive frames (vv_lod.progressive).
     */
    int (*missing_chunks)(void *user, int level, const int lo[3], const int hi[3]);
    /**
     * The boxes (read_box results, each with the renderer's working set for
     * it) the source's memory limit holds at once besides its cache: the
     * driver renders up to that many nodes at a time, one a thread (reads
     * stay one at a time and in the plan's order). 0 or 1: one.
     */
    int boxes;
    /* ---- version 2 ---- */
    /**
     * Optional (NULL): asks the source to load the chunks of these boxes in
     * the background (box i as in plan), soonest first in this order,
     * replacing whatever an earlier request left queued (a new view made it
     * stale); n 0 cancels. Returns at once; a later progressive frame finds
     * them resident (missing_chunks). Errors: VV_ERR_INVALID, VV_ERR_LIMIT,
     * VV_ERR_NOMEM.
     */
    vv_status (*request)(void *user, int n, const int *level, const int *lo, const int *hi);
    /**
     * Optional (NULL): 1 when the background loading of the newest request
     * stopped short because the source's cache is full of chunks it wants.
     */
    int (*stalled)(void *user);
} vv_multires_source;

#ifdef __cplusplus
}
#endif
#endif
