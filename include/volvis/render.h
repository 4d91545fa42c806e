/*
 * VolVis rendering: one interface for every rendering method, and a registry.
 *
 * A renderer turns a World plus a View into an image (RGBA float + depth,
 * see image.h). Each method implements vv_renderer_ops and is listed in the
 * registry (src/render/registry.c); callers pick one by name ("raycast") and
 * never special-case a method.
 *
 * Thread-safety: one vv_renderer must not render from two threads at once;
 * distinct renderers are independent. A renderer may cache per-volume data
 * (gradients, subvolume min/max) between renders; the cache is keyed on the
 * volume and its `modified` counter and holds a reference to the volume.
 */
#ifndef VOLVIS_RENDER_H
#define VOLVIS_RENDER_H

#include "core.h"
#include "image.h"
#include "model.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Options of one render call. */
typedef struct vv_render_options {
    int threads;          /**< <= 0: vv_threads_get() */
    int quality;          /**< 0 draft .. 2 final; methods may ignore it (raytrace: 0 no
                               shadow or secondary rays, 1 one ray a pixel, 2 supersampled) */
    vv_progress progress; /**< reports the fraction of image tiles done; may cancel */
} vv_render_options;

/** threads 0, quality 2, no progress callback. */
void vv_render_options_init(vv_render_options *o);

/** The table every rendering method implements. */
typedef struct vv_renderer_ops {
    const char *name;        /**< registry key, e.g. "raycast" */
    const char *description; /**< one line for --help */
    vv_status (*create)(void **state);
    /** Sets a method-specific option from text; VV_ERR_INVALID for unknown keys. */
    vv_status (*set_option)(void *state, const char *key, const char *value);
    vv_status (*render)(void *state, const vv_world *world, const vv_view *view,
                        const vv_render_options *opt, vv_image *out);
    void (*destroy)(void *state);
    /**
     * The method's --set options with their defaults, and what --quality
     * means to it, as plain text for --help ("key (default), ..."); may be
     * NULL.
     */
    const char *options;
} vv_renderer_ops;

typedef struct vv_renderer vv_renderer;

/** The registry: a NULL-terminated array of every method built in. */
const vv_renderer_ops *const *vv_renderer_registry(void);

/** Creates the method called @p name. Errors: VV_ERR_INVALID (unknown name), VV_ERR_NOMEM. */
vv_status vv_renderer_new(vv_renderer **out, const char *name);
/** Releases a renderer and its caches (and their volume references). Accepts NULL. */
void vv_renderer_free(vv_renderer *r);
/** The method's registry name ("raycast"); owned by the library. */
const char *vv_renderer_name(const vv_renderer *r);
/**
 * Sets a method-specific option from text (for raycast: early_termination,
 * gradient_budget_mb, empty_space_skipping, simd; for raytrace: shadows,
 * max_depth, samples, jitter, seed, adaptive, adaptive_threshold, parc,
 * shadow_grid, early_termination; for radiosity: tolerance, error, near,
 * patch_size, grid, diffuse_voxels, max_shots, levels; docs/rendering.md).
 * Errors: VV_ERR_INVALID for an unknown key or a bad value, with a message.
 */
vv_status vv_renderer_set_option(vv_renderer *r, const char *key, const char *value);

/**
 * Renders @p world seen through @p view into @p out, which must be
 * view->width x view->height. @p opt may be NULL (defaults). Errors:
 * VV_ERR_INVALID (size mismatch, bad World), VV_ERR_NOMEM, VV_ERR_CANCELLED.
 */
vv_status vv_renderer_render(vv_renderer *r, const vv_world *world, const vv_view *view,
                             const vv_render_options *opt, vv_image *out);

/**
 * The renderer a World's render settings name (vv_render_settings, in
 * model.h): their renderer, or "raycast" when none is set. Never NULL; the
 * pointer is into @p rs or static.
 */
const char *vv_render_settings_renderer(const vv_render_settings *rs);
/** Their quality level, or 2 (final) when none is set. */
int vv_render_settings_quality(const vv_render_settings *rs);
/**
 * Passes every option of @p rs to @p r in order (vv_renderer_set_option),
 * so a renderer draws what `volvis render` of the saved scene draws.
 * Errors: VV_ERR_INVALID for an option the renderer refuses, with its key.
 */
vv_status vv_renderer_apply_settings(vv_renderer *r, const vv_render_settings *rs);
/**
 * A new renderer as @p rs asks for it: vv_renderer_new of
 * vv_render_settings_renderer, then vv_renderer_apply_settings. On failure
 * *out is NULL. Errors: those of both.
 */
vv_status vv_renderer_new_from_settings(vv_renderer **out, const vv_render_settings *rs);

/**
 * The surface a surface-drawing method shows for a volume object: in iso
 * mode its isovalue (colour material.color); threshold-segmented, its
 * threshold; else the lowest value at which the transfer function's opacity
 * reaches half its maximum over the volume's range, coloured by the transfer
 * function there. Returns 0 (and leaves @p iso unset) when the transfer
 * function is transparent over the whole range. Used by the `surface`
 * renderer and the Navigator's previews so they show the same surface.
 */
int vv_object_surface_value(const vv_object *obj, double *iso, vv_vec3 *color);

#ifdef __cplusplus
}
#endif
#endif
