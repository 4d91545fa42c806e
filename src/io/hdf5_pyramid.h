/*
 * HDF5 pyramids (BigDataViewer, Imaris) through libhdf5, not installed:
 * the reader the sandboxed child serves boxes from (vv_sandbox_boxes_*,
 * src/io/sandbox.c) and the pyramid's store uses in-process with
 * VOLVIS_SANDBOX=0 (src/io/hdf5_pyramid.c: the layouts, geometry and
 * conventions).
 */
#ifndef VOLVIS_IO_HDF5_PYRAMID_H
#define VOLVIS_IO_HDF5_PYRAMID_H

#include "volvis/volume.h"

/** One level as the reader found it. */
typedef struct vv_h5p_level {
    int dims[3];       /**< voxels along x, y, z */
    int cdims[3];      /**< the chunk box the store reads by (the dataset's chunks) */
    int type;          /**< vv_voxel_type */
    double spacing[3]; /**< level-0 voxels (BigDataViewer) or the file's units (Imaris) */
    double origin[3];  /**< the centre of voxel 0 */
    int unit;          /**< vv_unit of the spacing (Imaris's Unit; else unknown) */
    int has_range;     /**< 1: range is the data's (Imaris's HistogramMin/Max) */
    double range[2];
} vv_h5p_level;

typedef struct h5p h5p;

/**
 * Opens BigDataViewer or Imaris file @p path for @p channel and @p time
 * (-1: the first). Errors: VV_ERR_IO (not HDF5), VV_ERR_FORMAT (neither
 * layout, a dataset of the wrong rank or inconsistent levels),
 * VV_ERR_UNSUPPORTED (a voxel type), VV_ERR_INVALID (channel or step out
 * of range), VV_ERR_LIMIT; not prefixed with the file.
 */
vv_status vv_h5p_open(h5p **out, const char *path, int channel, int time);
void vv_h5p_close(h5p *h);
/** Levels (1 .. VV_PYRAMID_MAX_LEVELS); the channel and time-step counts. */
int vv_h5p_levels(const h5p *h, int *n_channels, int *n_times);
/** Level @p level's description, or NULL. */
const vv_h5p_level *vv_h5p_level_info(const h5p *h, int level);
/**
 * Voxels lo .. lo + dims - 1 of @p level into @p dst (x fastest, the
 * level's type). Errors: VV_ERR_INVALID (outside the level), VV_ERR_FORMAT
 * (libhdf5 failed: a corrupt chunk or an unavailable filter).
 */
vv_status vv_h5p_read_box(h5p *h, int level, const int lo[3], const int dims[3], void *dst);
/** A level's spacing, origin, unit and modification into @p v. */
void vv_h5p_geometry(const vv_h5p_level *L, vv_volume *v);

#endif
