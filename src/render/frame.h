/*
 * The frame runner's and the region contract's helpers, internal to
 * src/render (src/render/frame.c): adaptive image-space refinement, the
 * checks and Worlds of a region render, and the partial images' clearing and
 * combining. The renderers and the drivers of src/render share them; a
 * renderer outside src/render sees the contract itself in
 * include/volvis/sys/renderer.h (vv_frame_run, vv_region_image, ...).
 */
#ifndef VV_RENDER_FRAME_H
#define VV_RENDER_FRAME_H

#include "volvis/render.h"
#include "volvis/sys/renderer.h"

/** Frees what @p r holds and empties it. */
void vv_region_rays_free(vv_region_rays *r);

/**
 * Combines whole partial images: @p front becomes front combined with
 * @p back (same size and op); a back that has a classify (SUM) gives it to
 * front, which vv_region_image_finish then classifies with, and so does a
 * back that has a supersample. Thread-safe
 * for distinct images.
 */
void vv_region_image_combine(vv_region_image *front, const vv_region_image *back);

/** vv_region_image_combine over pixels x0 <= x < x1, y0 <= y < y1 only. */
void vv_region_image_combine_rect(vv_region_image *front, const vv_region_image *back, int x0,
                                  int y0, int x1, int y1);

/**
 * The checks every region method starts with: @p rg->object is the World's
 * only visible object, without a solid texture; *op receives how its
 * partial images combine (vv_region_op_for its mode).
 * Errors: VV_ERR_UNSUPPORTED naming the object.
 */
vv_status vv_render_region_check(const vv_world *w, const vv_render_region *rg, vv_region_op *op);

/**
 * vv_render_region_check, then *part = the region's object with its volume
 * replaced by the region's voxels (a shallow copy: nothing in it is
 * released; it lives as long as @p w and @p rg). A multi-channel object
 * drawn by the composite rule takes the region's channel_voxels: *chan a
 * new array of its channels with those volumes (the part's channels; free
 * it after the part), else NULL. Errors as vv_render_region_check;
 * VV_ERR_UNSUPPORTED (a multi-channel object without channel voxels, or
 * under the additive or maximum rule), VV_ERR_NOMEM.
 */
vv_status vv_render_region_part(const vv_world *w, const vv_render_region *rg, vv_region_op *op,
                                vv_object *part, vv_channel **chan);

/** Frees what vv_render_region_world kept in @p rw (its part's channels). */
void vv_region_world_release(vv_region_world *rw);

/**
 * vv_render_region_part into @p out->part, and @p out->world a shallow copy
 * of @p w showing it alone. Errors as vv_render_region_check.
 */
vv_status vv_render_region_world(const vv_world *w, const vv_render_region *rg, vv_region_op *op,
                                 vv_region_world *out);

/**
 * The World's ambient light and background as floats for a frame; with
 * @p region non-zero the background is 0 (partial images of a region are
 * composited first and the background is added once, by
 * vv_region_image_finish).
 */
static inline void
vv_frame_colours(const vv_world *w, int region, float ambient[3], float background[3]) {
    ambient[0] = (float)w->ambient.x;
    ambient[1] = (float)w->ambient.y;
    ambient[2] = (float)w->ambient.z;
    background[0] = region ? 0.0f : (float)w->background.x;
    background[1] = region ? 0.0f : (float)w->background.y;
    background[2] = region ? 0.0f : (float)w->background.z;
}

/** vv_region_image_clear over pixels x0 <= x < x1, y0 <= y < y1 only. */
void vv_region_image_clear_rect(vv_region_image *img, int x0, int y0, int x1, int y1);

/** Limits @p job to the pixel rectangle of region @p rg (none when it has none). */
void vv_frame_job_region(vv_frame_job *job, const vv_render_region *rg);

/** Per-thread scratch vv_frame_refine_tile needs (vv_frame_job.scratch_bytes). */
size_t vv_frame_refine_scratch_bytes(void);

/** The tolerance the renderers use at @p quality (0, 1, 2): 1/16, 1/64, 1/1024. */
float vv_frame_refine_tolerance(int quality);

/**
 * Whether a frame at @p quality refines (never a region render, @p region
 * not 0: its pixels are composited with other ranks' by depth and key),
 * and with what tolerance (*tolerance, set either way). Mode auto refines
 * at quality 0 and 1, and at quality 2 when @p final_pays (the renderer's
 * word that refinement at vv_frame_refine_tolerance(2) costs no measurable
 * accuracy for this frame: raycast's frames of composite objects).
 */
int vv_frame_refine_for(const vv_frame_refine_settings *s, int quality, int region, int final_pays,
                        float *tolerance);

/**
 * Fills tile @p t of a @p width x @p height image (@p rgba: 4 floats a
 * pixel, @p depth: one; row-major, the vv_image layout) by adaptive
 * image-space refinement (Levoy, "Volume Rendering by Adaptive
 * Refinement", The Visual Computer 6(1), 1990): @p fn casts the pixels of
 * a lattice of every VV_FRAME_REFINE_LATTICE-th pixel; a lattice cell whose
 * corners differ by at most 8 x @p tolerance in every channel gets its
 * centre cast, and if the centre is within @p tolerance of the corners'
 * bilinear interpolation the cell's other pixels are that interpolation;
 * otherwise the cell is cut in four and each quarter is tested the same
 * way, down to single pixels. A tile where most lattice cells differ
 * beyond the range is cast whole. The tile casts its own right and bottom
 * lattice corners (the next tile's first column and row), so its pixels
 * depend on it alone. The tile must be at most VV_FRAME_TILE square (the
 * default) and t->scratch hold vv_frame_refine_scratch_bytes(); it writes
 * the tile's pixels only (a larger tile, or no scratch: every pixel cast).
 * Thread-safe for disjoint tiles.
 */
void vv_frame_refine_tile(const vv_frame_tile *t, int width, int height, float tolerance,
                          vv_frame_pixel_fn fn, void *user, void *work, float *rgba, float *depth);

#endif
