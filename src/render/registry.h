/* The operation tables of the built-in rendering methods (internal). */
#ifndef VV_RENDER_REGISTRY_H
#define VV_RENDER_REGISTRY_H

#include "volvis/render.h"
#include "volvis/sys/renderer.h"

/** Direct volume ray casting (src/render/raycast). */
extern const vv_renderer_ops vv_raycast_ops;
/** Volumetric ray tracing with global effects (src/render/raytrace). */
extern const vv_renderer_ops vv_raytrace_ops;

/** Geometry rendering of isosurfaces and geometric objects (src/render/raster). */
extern const vv_renderer_ops vv_raster_ops;

/** Volumetric radiosity (src/render/radiosity). */
extern const vv_renderer_ops vv_radiosity_ops;

/** Compression-domain Fourier projection (src/render/fourier). */
extern const vv_renderer_ops vv_fourier_ops;

/** Cell-by-cell ray casting of irregular grids (src/render/irregular). */
extern const vv_renderer_ops vv_irregular_ops;

/** Object-order volume rendering by splatting (src/render/splat). */
extern const vv_renderer_ops vv_splat_ops;

/** Direct volume ray casting on a Vulkan device (src/render/gpu). */
extern const vv_renderer_ops vv_gpu_ops;

/** The method state behind @p r (what its create returned); borrowed. */
void *vv_renderer_state(const vv_renderer *r);

/** The number of entries of a static option table. */
#define VV_OPTIONS_COUNT(table) ((int)(sizeof(table) / sizeof((table)[0])))

/**
 * A new renderer as @p rs asks for it: vv_renderer_new of
 * vv_render_settings_renderer, then vv_renderer_apply_settings. On failure
 * *out is NULL. Errors: those of both.
 */
vv_status vv_renderer_new_from_settings(vv_renderer **out, const vv_render_settings *rs);

#endif
