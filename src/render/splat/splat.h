/*
 * The splatting renderer's internal interface (src/render/splat/splat.c):
 * what a render did, for the tests and bench/bench_splat. Not part of the
 * public API; the renderer itself is used through volvis/render.h as
 * "splat".
 */
#ifndef VV_RENDER_SPLAT_H
#define VV_RENDER_SPLAT_H

#include <stdint.h>

#include "volvis/render.h"

/** Counts of the last render of a splat renderer (summed over objects). */
typedef struct vv_splat_stats {
    uint64_t voxels;     /**< voxels of the rendered volume objects */
    uint64_t listed;     /**< voxels in the splat lists (the rest skipped as empty) */
    uint64_t footprints; /**< footprints rasterised (kernel slices, or whole kernels in X-ray) */
    uint64_t culled;     /**< footprints skipped by the occlusion map */
    uint64_t sheets;     /**< sheets composited (summed over image bands) */
    int lists_built;     /**< voxel lists built by this render (0: all reused) */
} vv_splat_stats;

/**
 * The counts of @p r's last render, or NULL when @p r is not the "splat"
 * renderer. Borrowed: valid until the next render or vv_renderer_free.
 */
const vv_splat_stats *vv_splat_stats_get(const vv_renderer *r);

/**
 * The X-ray line integrals of @p r's last render: width x height floats,
 * row-major, row 0 at the top, each the integral along the pixel's ray
 * (world units) of the kernel-reconstructed values (real units) of the
 * X-ray objects, summed over them; over the whole image this integrates to
 * sum(voxel values) x the kernel's integral (the volume of a voxel in
 * world units), within the pixel sampling of the footprints (energy
 * conservation). NULL when the last render had no X-ray object or @p r is
 * not "splat". Borrowed, like vv_splat_stats_get.
 */
const float *vv_splat_xray_integral(const vv_renderer *r);

#endif
