/*
 * VolVis Navigator: interactive manipulation of the view, of objects and of
 * lights, and the reduced-resolution previews drawn while things move (the
 * paper's Navigator, Avila et al., IEEE Visualization '94, section 4: "the
 * user can translate, scale and rotate every volume, light and the view ...
 * in a manner similar to a flight simulator", with PARC subvolume boxes and a
 * coarse Marching Cubes surface as fast representations).
 *
 * Two parts, both free of any toolkit:
 *  - the manipulation maths (trackball, pan, zoom, flight simulator, object
 *    and light dragging) on vv_view, vv_object and vv_light values. Every
 *    input is sanitised: NaN or infinite input is ignored and magnitudes are
 *    clamped (a 10^6-pixel jump turns the view by at most one turn), and a
 *    result that would not be finite leaves the value unchanged, so the
 *    camera can never become NaN;
 *  - vv_preview: draws a World snapshot in one of the representations
 *    (bounding boxes, PARC boxes, coarse Marching Cubes, the ray caster at
 *    1/4 or 1/2 resolution, or the full renderer), and the policy that picks
 *    the representation holding a frame-time budget from measured times.
 *
 * Units: pixels for mouse motion, radians for angles, world units for
 * distances, seconds for time. Thread-safety: the maths functions are pure.
 * A vv_preview must be used by one thread at a time; previews are
 * independent.
 */
#ifndef VOLVIS_NAVIGATOR_H
#define VOLVIS_NAVIGATOR_H

#include "core.h"
#include "image.h"
#include "model.h"
#include "render.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest mouse motion, in pixels, one call takes; larger motion is clamped. */
#define VV_NAV_MAX_PIXELS 4096.0

/* ---- view manipulation ------------------------------------------------- */

/**
 * Trackball rotation of the view about its look-at point for a mouse drag of
 * (@p dx, @p dy) pixels in a @p width x @p height view: the scene turns with
 * the mouse (a drag to the left turns the front of the object to the left),
 * 180 degrees for a drag across the view's height. Implemented with
 * vv_view_orbit (the up vector turns with the elevation, so there is no
 * gimbal lock at the poles). Non-finite or absurd motion is clamped.
 */
void vv_nav_view_rotate(vv_view *view, double dx, double dy);

/**
 * Pans the view (eye and look-at together) so that the point at the look-at
 * distance follows the mouse by (@p dx, @p dy) pixels.
 */
void vv_nav_view_pan(vv_view *view, double dx, double dy);

/**
 * Zooms by @p factor (> 1 moves closer): the eye moves towards the look-at
 * point (perspective) or ortho_height shrinks (orthographic). The factor is
 * clamped to [1/16, 16] a call, and the eye never reaches the look-at point
 * (distance at least 1e-6 of what it was).
 */
void vv_nav_view_zoom(vv_view *view, double factor);

/**
 * Flight-simulator motion over @p dt seconds: yaw (about the view's up),
 * pitch (about its right axis) and roll (about the viewing direction) at the
 * given rates (radians per second, each clamped to ±2π), then the eye and
 * the look-at point move forward by @p speed * @p dt world units (speed
 * clamped to ±1e9, dt to [0, 1]). The look-at distance is kept.
 */
void vv_nav_view_fly(vv_view *view, double yaw, double pitch, double roll, double speed, double dt);

/** 1 when every field of @p view is finite and the camera is not degenerate. */
int vv_nav_view_valid(const vv_view *view);

/* ---- objects and lights ------------------------------------------------ */

/**
 * Rotates @p obj about its world-box centre as the trackball would turn the
 * scene for a drag of (dx, dy) pixels seen through @p view (screen axes).
 */
void vv_nav_object_rotate(vv_object *obj, const vv_view *view, double dx, double dy);

/** Moves @p obj in the view plane so that it follows the mouse by (dx, dy) pixels. */
void vv_nav_object_translate(vv_object *obj, const vv_view *view, double dx, double dy);

/** Scales @p obj by @p factor (clamped to [1/16, 16] a call) about its world-box centre. */
void vv_nav_object_scale(vv_object *obj, double factor);

/**
 * Drags a light: a point light moves in the view plane through @p view's
 * look-at point (it follows the mouse); a directional light's direction turns
 * as the trackball would turn it. A headlight stops being one (it now keeps
 * its direction in the World).
 */
void vv_nav_light_drag(vv_light *light, const vv_view *view, double dx, double dy);

/* ---- previews ----------------------------------------------------------- */

/** The representations a frame can be drawn with, cheapest first. */
typedef enum vv_preview_kind {
    VV_PREVIEW_BBOX = 0,      /**< bounding boxes of the objects, wireframe */
    VV_PREVIEW_BOXES = 1,     /**< PARC subvolume boxes (paper, section 4, first method) */
    VV_PREVIEW_COARSE_MC = 2, /**< coarse Marching Cubes, four edge positions (second method) */
    VV_PREVIEW_RAYCAST_4 = 3, /**< the ray caster at 1/4 resolution, step x 4, shown scaled up */
    VV_PREVIEW_RAYCAST_2 = 4, /**< the ray caster at 1/2 resolution, step x 2 */
    VV_PREVIEW_FULL = 5       /**< the selected renderer at full resolution and quality */
} vv_preview_kind;
#define VV_PREVIEW_COUNT 6

/**
 * Name of a representation as in the frame log: "bbox", "boxes", "coarse_mc",
 * "raycast_1/4", "raycast_1/2", "full". Never NULL.
 */
const char *vv_preview_kind_name(vv_preview_kind k);
/** Parses a name of vv_preview_kind_name. Errors: VV_ERR_INVALID. */
vv_status vv_preview_kind_parse(const char *name, vv_preview_kind *out);

/**
 * Image size in pixels of representation @p k for a @p width x @p height
 * view (1/4 and 1/2 rounded up, at least 1).
 */
void vv_preview_size(vv_preview_kind k, int width, int height, int *w, int *h);

typedef struct vv_preview vv_preview;

/**
 * A preview renderer that draws the final representation with the registry
 * renderer @p final_renderer (e.g. "raytrace"). Errors: VV_ERR_INVALID
 * (unknown renderer), VV_ERR_NOMEM.
 */
vv_status vv_preview_new(vv_preview **out, const char *final_renderer);
/**
 * 1 when the last vv_preview_render built caches (a volume's first ray cast,
 * first shaded ray cast, first full frame, or a new PARC or coarse grid), so
 * that its time is not what the next frame will take.
 */
int vv_preview_last_warmup(const vv_preview *p);
/** Releases a preview, its renderers and its cached surfaces. Accepts NULL. */
void vv_preview_free(vv_preview *p);
/** The final renderer (to set its options with vv_renderer_set_option); owned by @p p. */
vv_renderer *vv_preview_final_renderer(vv_preview *p);

/**
 * Draws @p world seen through @p view as representation @p kind into @p out,
 * which must be the size vv_preview_size gives. @p opt applies to the final
 * representation (its quality and progress); previews use quality 0 and the
 * progress only to cancel. Boxes and coarse Marching Cubes are built per
 * volume (their subvolume min/max and reduced grid once, cached by volume
 * and modification count) at the object's surface value: its isovalue in iso
 * mode, its threshold when threshold-segmented, else the lowest value at
 * which its transfer function's opacity rises above 0.01. They are drawn by
 * the `surface` renderer with the object's transform, material, cut planes
 * and the World's lights. The final representation is exactly what
 * vv_renderer_render of the final renderer gives (the same image `volvis
 * render` writes for the same World). The first reduced ray cast of a
 * volume is drawn without shading (its gradients are not cached yet), so
 * that a first image appears at once. Errors: those of the renderers,
 * VV_ERR_CANCELLED.
 */
vv_status vv_preview_render(vv_preview *p, const vv_world *world, const vv_view *view,
                            vv_preview_kind kind, const vv_render_options *opt, vv_image *out);

/**
 * The frame-rate policy. Times are learnt per representation (an
 * exponential average of its last frames); vv_preview_policy_choose picks
 * the best representation whose expected time fits the budget. The 1/2 ray
 * cast is expected to take 4 times the 1/4 one until it is measured.
 */
typedef struct vv_preview_policy {
    double seconds[VV_PREVIEW_COUNT]; /**< expected seconds a frame, < 0 when unknown */
    int forced;                       /**< >= 0: always this kind while moving; -1 automatic */
    int allowed[VV_PREVIEW_COUNT];    /**< 0 excludes a kind from the automatic choice */
    unsigned choices;                 /**< automatic choices made (every 24th probes a better
                                           representation again) */
} vv_preview_policy;

/** Nothing measured, automatic choice, every representation but the full one allowed. */
void vv_preview_policy_init(vv_preview_policy *pol);
/**
 * Learns that a frame of @p kind took @p seconds (ignored when not finite or
 * < 0). Frames that built caches (vv_preview_last_warmup) should not be
 * recorded: their time says nothing about the next frame.
 */
void vv_preview_policy_record(vv_preview_policy *pol, vv_preview_kind kind, double seconds);
/**
 * The representation to draw while moving within @p budget seconds a frame:
 * the best allowed one whose expected time fits; of those not measured yet
 * only the 1/4 ray cast (and bounding boxes) are tried, since the others
 * build surfaces first (measure them off screen); every 24th choice is the next
 * better one when it is expected within 1.5 times the budget, so that
 * estimates follow the machine's load.
 */
vv_preview_kind vv_preview_policy_choose(vv_preview_policy *pol, double budget);

#ifdef __cplusplus
}
#endif
#endif
