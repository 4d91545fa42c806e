/*
 * The render drivers, internal to src/render: how vv_renderer_render
 * (registry.c) draws a World whose volume objects show files out of core
 * (their `source`, include/volvis/source.h), through the region contract of
 * any renderer that declares it (include/volvis/sys/renderer.h). Nothing
 * outside src/render calls them: vv_renderer_render chooses.
 *
 *   drv_render_sources  every visible object into a layer of its own, the
 *                       layers combined as the ray caster combines objects
 *                       (driver_sources.c); each layer is drawn by
 *   drv_render_bricks   a brick view (a bricked file, or an object in
 *                       memory as one brick): brick by brick, front to
 *                       back, each brick one region render (driver_region.c)
 *   drv_render_multires a pyramid by level of detail: an octree of nodes
 *                       front to back, each node one region render of the
 *                       level its screen-space error picks (driver_region.c)
 *
 * A driver draws with what its caller hands it (drv_renderer: the
 * method's operations and state, and how to have more of them for other
 * threads) and never calls the registry: vv_renderer_render hands it the
 * renderer it was given, the gpu renderer its own operations and state for
 * a volume over its device's memory.
 *
 * Thread-safety: as the renderer (one render at a time); the views are
 * used from the calling thread (the multiresolution driver renders several
 * nodes at once on its own threads, reading one at a time).
 */
#ifndef VV_RENDER_DRIVERS_H
#define VV_RENDER_DRIVERS_H

#include "volvis/render.h"
#include "volvis/sys/renderer.h"
#include "volvis/sys/source.h"

/** The renderer a driver draws with, handed in by its caller. */
typedef struct drv_renderer {
    const vv_renderer_ops *ops; /**< its name, capabilities and region method */
    void *state;                /**< the state ops draw with (borrowed) */
    /** Another renderer of the same method and options into *@p out, for
     *  another thread (drv_render_multires draws nodes at once); NULL:
     *  none, the nodes are drawn in turn. */
    vv_status (*clone)(const struct drv_renderer *r, struct drv_renderer *out);
    /** Frees what clone made. */
    void (*release)(struct drv_renderer *r);
    void *user; /**< the caller's, for clone and release */
} drv_renderer;

/**
 * What the drivers draw with for renderer @p r, into @p out, returned
 * (registry.c's, for vv_renderer_render and tests): its operations and
 * state, cloned by vv_renderer_clone (the clones freed by their release).
 */
const drv_renderer *drv_renderer_of(vv_renderer *r, drv_renderer *out);

/**
 * One region render of @p ops with @p state: the region contract's checks
 * of the arguments and the World, @p out cleared (over its rectangle with
 * clear_outside), its operation over and no supersampling until the method
 * sets them, then ops->render_region; errors prefixed with the method's
 * name. vv_renderer_render_region is this for a vv_renderer. Errors: those
 * vv_renderer_render_region documents.
 */
vv_status drv_render_region(const vv_renderer_ops *ops, void *state, const vv_world *w,
                            const vv_view *view, const vv_render_region *region,
                            const vv_render_options *opt, vv_region_image *out);

/** 1 when a visible volume object of @p w holds a source out of core. */
int drv_world_out_of_core(const vv_world *w);

/**
 * Every visible object of @p w into a layer of its own (the others hidden,
 * on a black background): an object showing a pyramid by
 * drv_render_multires (@p lod's inputs, may be NULL: vv_lod_init's), a
 * bricked file by drv_render_bricks, an object in memory as one region over
 * its whole volume; the layers combined per pixel as the ray caster
 * combines objects along a ray (render.h, vv_renderer_render), the
 * background last. @p lod's outputs are the sums over the objects
 * (stalled: any). Layers are of the view's size, 20 bytes a pixel each
 * (one object alone is drawn straight into @p out).
 * Errors: those vv_renderer_render documents for out of core.
 */
vv_status drv_render_sources(const drv_renderer *r, const vv_world *w, const vv_view *view,
                             const vv_render_options *opt, vv_lod *lod, vv_image *out);

/**
 * Object @p object of @p w (a volume object in any mode; no other visible
 * object) from the bricks of @p src, front to back through @p view, with
 * renderer @p r (VV_RENDERER_REGION; raycast draws every mode, raytrace no
 * xray, and iso only with the whole volume as the object's own): each
 * brick one region render, the partial images combined in that order
 * (over; max or min for mip and minip; the nearest crossing for iso; the
 * sums, then the mean classified, for xray; the maxima scaled through the
 * exponents in front, then classified, for attenuated-mip). The object's own volume gives
 * the renderer's whole-volume context (raytrace traces shadows through it);
 * the geometry comes from the source's header. Bricks whose min/max the
 * transfer function makes transparent are skipped unread (composite), and
 * so are those wholly below the isovalue (iso); every other brick is read
 * at most once a frame. The image is the in-memory render's up to the
 * rounding of compositing (bit for bit for mip, minip and xray; iso up to
 * the gradient of a crossing just before a brick; attenuated-mip up to the
 * rounding of its products). Errors:
 * VV_ERR_UNSUPPORTED (no region method, a mode it cannot split, other
 * visible objects), VV_ERR_INVALID, those of reading and rendering.
 */
vv_status drv_render_bricks(const drv_renderer *r, const vv_world *w, int object,
                            const vv_brick_source *src, const vv_view *view,
                            const vv_render_options *opt, vv_image *out);

/**
 * Object @p object of @p w from the pyramid @p src by level of detail: an
 * octree over level 0's cells (nodes of src->node_cells << d cells a side
 * at depth d) walked front to back from the root; a node whose chosen
 * level (@p lod) is at least its depth is one region render of that
 * level's voxels -- the node's box mapped into the level's index space
 * through the levels' scale and translation, one voxel beyond each face
 * read (two for iso) -- else its eight children are, nearest first. Nodes
 * tile level 0's box exactly, so neighbours at different levels meet
 * without cracks. Each level samples at the object's step in its own
 * voxels, opacity corrected for the step's world length (attenuated MIP's
 * exponents weighed by it: vv_render_region.step_scale). A node whose
 * min/max the source knows and the transfer function makes transparent
 * (composite), or wholly below the isovalue (iso), is skipped unread. With
 * level 0 everywhere the image is drv_render_bricks's of level 0 (bit for
 * bit for mip, minip, xray and iso against the in-memory render). The
 * object's transform and level 0's direction apply to every level. Errors
 * as drv_render_bricks; those of the source's reads.
 */
vv_status drv_render_multires(const drv_renderer *r, const vv_world *w, int object,
                              const vv_multires_source *src, const vv_view *view,
                              const vv_render_options *opt, vv_lod *lod, vv_image *out);

#endif
