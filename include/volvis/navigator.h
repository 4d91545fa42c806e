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

/* ---- one entry point: a motion applied to a part of the World ------------ */

/**
 * Image position of world point @p p seen through @p view, in pixels of the
 * view's width x height (the inverse of vv_view_ray: pixel (px, py) covers
 * [px, px + 1) x [py, py + 1), so the centre of pixel (i, j) is (i + 0.5,
 * j + 0.5) here). Returns 0 (and leaves the outputs alone) for a point on or
 * behind the eye plane of a perspective view, or when the result would not
 * be finite. Pure; thread-safe.
 */
int vv_nav_view_project(const vv_view *view, vv_vec3 p, double *px, double *py);

/** What a motion moves (vv_nav_apply). */
typedef enum vv_nav_target_kind {
    VV_NAV_TARGET_VIEW = 0,   /**< the camera */
    VV_NAV_TARGET_OBJECT = 1, /**< World object `index` */
    VV_NAV_TARGET_LIGHT = 2,  /**< World light `index` */
    VV_NAV_TARGET_CUT = 3     /**< a cut plane: object `index`'s local plane `plane`, or
                                   (index -1) the World's global plane `plane`; `plane`
                                   -1 is the last one of the list */
} vv_nav_target_kind;

/** A part of the World to move. */
typedef struct vv_nav_target {
    vv_nav_target_kind kind;
    int index; /**< object or light index; VV_NAV_TARGET_CUT: object, or -1 for global */
    int plane; /**< VV_NAV_TARGET_CUT: plane index, -1 for the last */
} vv_nav_target;

/** Kinds of motion (vv_nav_apply), in the units of the field they use. */
typedef enum vv_nav_motion_kind {
    /** Trackball by (dx, dy) pixels: the view orbits its look-at point
        (vv_nav_view_rotate), an object turns about its box centre, a light
        is dragged (vv_nav_light_drag), a cut plane's normal turns. */
    VV_NAV_ROTATE = 0,
    /** Pan by (dx, dy) pixels: the view pans (vv_nav_view_pan), an object or a
        point light follows the mouse in the view plane, a cut plane moves
        along its normal by the drag's component along the normal's image
        direction (a drag the length of the drawn handle, 0.15 of the eye
        distance, moves it that far). */
    VV_NAV_PAN = 1,
    /** Zoom by `factor` (> 1 closer): the view (vv_nav_view_zoom); an object
        scales about its box centre (vv_nav_object_scale). */
    VV_NAV_ZOOM = 2,
    /** Flight over `dt` seconds at rates `yaw`, `pitch`, `roll` (radians a
        second) and `speed` (world units a second): the view only
        (vv_nav_view_fly); roll alone is a device's twist. */
    VV_NAV_FLY = 3,
    /** A rotation `rotation` given in the view's axes (x right, y up, z
        towards the viewer): the scene turns by it about the look-at point
        (the camera the other way), as two hands turn a held object; the
        view only. */
    VV_NAV_TURN = 4
} vv_nav_motion_kind;

/** One motion (vv_nav_apply); only the fields of its kind are read. */
typedef struct vv_nav_motion {
    vv_nav_motion_kind kind;
    double dx, dy;                  /**< ROTATE, PAN: pixels of the view's image */
    double factor;                  /**< ZOOM: > 0 */
    double yaw, pitch, roll, speed; /**< FLY: radians a second, world units a second */
    double dt;                      /**< FLY: seconds, [0, 1] */
    vv_quat rotation;               /**< TURN: unit quaternion in view axes */
} vv_nav_motion;

/**
 * Applies @p motion to @p target of @p world seen through world->view: the
 * one function the GUI's mouse, the input devices (src/input delivers
 * actions, the GUI turns them into motions) and the tests drive (VolVis
 * paper, section 4, the Navigator). Each kind is the Navigator maths above
 * (inputs sanitised, a non-finite result leaves the World as it was). A
 * motion a target does not take (FLY or TURN on an object) changes
 * nothing and is not an error. Errors: VV_ERR_INVALID (NULL argument, no
 * such object, light or cut plane, an object motion on an object index out
 * of range, an invalid view); the World is then unchanged. Not thread-safe
 * for one World (it writes it); pure otherwise.
 */
vv_status vv_nav_apply(vv_world *world, const vv_nav_target *target, const vv_nav_motion *motion);

/* ---- previews ----------------------------------------------------------- */

/** The representations a frame can be drawn with, cheapest first. */
typedef enum vv_preview_kind {
    VV_PREVIEW_BBOX = 0,      /**< bounding boxes of the objects, wireframe */
    VV_PREVIEW_BOXES = 1,     /**< PARC subvolume boxes (paper, section 4, first method) */
    VV_PREVIEW_COARSE_MC = 2, /**< coarse Marching Cubes, four edge positions (second method) */
    VV_PREVIEW_RAYCAST_8 = 3, /**< the ray caster at 1/8 resolution, step x 4, shown scaled up */
    VV_PREVIEW_RAYCAST_4 = 4, /**< the ray caster at 1/4 resolution, step x 4, shown scaled up */
    VV_PREVIEW_RAYCAST_2 = 5, /**< the ray caster at 1/2 resolution, step x 2 */
    VV_PREVIEW_FULL = 6       /**< the selected renderer at full resolution and quality */
} vv_preview_kind;
#define VV_PREVIEW_COUNT 7

/**
 * Name of a representation as in the frame log: "bbox", "boxes", "coarse_mc",
 * "raycast_1/8", "raycast_1/4", "raycast_1/2", "full". Never NULL.
 */
const char *vv_preview_kind_name(vv_preview_kind k);
/** Parses a name of vv_preview_kind_name. Errors: VV_ERR_INVALID. */
vv_status vv_preview_kind_parse(const char *name, vv_preview_kind *out);

/**
 * Image size in pixels of representation @p k for a @p width x @p height
 * view (1/8, 1/4 and 1/2 rounded up, at least 1).
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
 * that a first image appears at once; later reduced ray casts shade by
 * table (vv_render_options.fast_shading: the ray caster's shading=table,
 * >= 40 dB from Phong), the final representation as its renderer's
 * options say (Phong by default). Errors: those of the renderers,
 * VV_ERR_CANCELLED.
 */
vv_status vv_preview_render(vv_preview *p, const vv_world *world, const vv_view *view,
                            vv_preview_kind kind, const vv_render_options *opt, vv_image *out);

/**
 * The frame-rate policy. Times are learnt per representation (an
 * exponential average of its last frames); vv_preview_policy_choose picks
 * a ray cast of the data whenever one fits: the finest of 1/2, 1/4 and 1/8
 * resolution whose expected time fits the budget; surfaces (coarse
 * Marching Cubes, PARC boxes) or bounding boxes only when even the 1/8 cast
 * has been measured over it and they are much quicker. Until measured, each ray cast is expected to
 * take 4 times the next coarser one.
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
 * The representation to draw while moving within @p budget seconds a frame
 * (interaction shows the data, never boxes, where a reduced ray cast can
 * keep the rate): the finest allowed ray cast whose expected time
 * fits; with nothing measured, the 1/8 cast. When the 1/8 cast is measured
 * over the budget, the best allowed surface representation that fits and
 * takes less than half the 1/8 cast's time (a load that slows everything
 * gains nothing from boxes); bounding boxes, not yet measured, only when the
 * 1/8 cast takes more than 4 times the budget (data too large to cast);
 * otherwise still the 1/8 cast. Every 24th choice is the next finer ray cast
 * when it is expected within 1.5 times the budget (the 1/8 cast, tried
 * again from surfaces, within 4 times), so that estimates follow the
 * machine's load.
 */
vv_preview_kind vv_preview_policy_choose(vv_preview_policy *pol, double budget);

#ifdef __cplusplus
}
#endif
#endif
