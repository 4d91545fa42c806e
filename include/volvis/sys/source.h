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

#ifdef __cplusplus
}
#endif
#endif
