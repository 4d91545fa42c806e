/*
 * VolVis Animator (Avila et al., "VolVis: A Diversified Volume Visualization
 * System", IEEE Visualization '94, section 4 "Manipulation": the Animator):
 * sequences of transformations of the objects, lights and view, either as
 * keyframe tracks or as the common sequences without keyframes (orbit the
 * camera, rotate an object, fly along a line, sweep a cut plane); flight
 * paths recorded in the Navigator; evaluation into World snapshots that any
 * renderer can draw (preview); and the final render of every frame to a PNG
 * sequence or a video (MP4/H.264, WebM/VP9), resumable and cancellable.
 * File format: docs/animation-format.md.
 *
 * Time is in seconds. Frame k of an animation of N frames at F frames per
 * second is drawn at time k / F; N = round(duration * F), so frame N - 1 is
 * the last one (a 360° orbit of N frames does not repeat its first frame).
 *
 * Units: as in the World (world units, radians) for every key value; the
 * file format uses degrees for angles (fov, orientation angles) and converts.
 * The sequences' angles (vv_anim_sequence.degrees) are degrees: the final
 * frame of `volvis animate --orbit` then equals the still of `volvis render
 * --azimuth` bit for bit.
 *
 * Thread-safety: an animation is a plain value; many threads may evaluate
 * one animation at once while nobody edits it. Functions are reentrant.
 */
#ifndef VOLVIS_ANIMATE_H
#define VOLVIS_ANIMATE_H

#include "core.h"
#include "image.h"
#include "math.h"
#include "model.h"
#include "render.h"
#include "video.h"

#ifdef __cplusplus
extern "C" {
#endif

#define VV_ANIM_PATH_MAX 128

/** How the local parameter of the segment leaving a key is reshaped (per key). */
typedef enum vv_anim_easing {
    VV_EASE_LINEAR = 0, /**< u */
    VV_EASE_IN = 1,     /**< u^2: starts slowly */
    VV_EASE_OUT = 2,    /**< 1 - (1 - u)^2: ends slowly */
    VV_EASE_IN_OUT = 3  /**< 3u^2 - 2u^3: both */
} vv_anim_easing;

/** What the values of a track are (set from its property). */
typedef enum vv_anim_kind {
    VV_ANIM_SCALAR = 0, /**< value[0] */
    VV_ANIM_VEC3 = 1,   /**< value[0..2] (positions, directions, colours) */
    VV_ANIM_QUAT = 2,   /**< value[0..3] = w, x, y, z, a rotation (normalised on use) */
    VV_ANIM_TF = 3      /**< tf: a whole transfer function */
} vv_anim_kind;

/** How a track interpolates between keys. */
typedef enum vv_anim_interp {
    VV_INTERP_SPLINE = 0, /**< Kochanek–Bartels (scalars, vectors); squad (quaternions) */
    VV_INTERP_LINEAR = 1, /**< straight lines (scalars, vectors); slerp (quaternions) */
    VV_INTERP_STEP = 2    /**< hold each key's value until the next key */
} vv_anim_interp;

/** One keyframe. */
typedef struct vv_anim_key {
    double time;     /**< seconds; strictly increasing along a track */
    double value[4]; /**< see vv_anim_kind; units of the World (radians for view.fov) */
    vv_tf *tf;       /**< VV_ANIM_TF: owned by the track (vv_animation_free frees it) */
    /** Kochanek–Bartels parameters of this key, each in [-1, 1]; all 0 gives
     * Catmull–Rom. Used by VV_INTERP_SPLINE on scalar and vector tracks. */
    double tension, continuity, bias;
    vv_anim_easing easing; /**< of the segment from this key to the next */
} vv_anim_key;

/** Where a track writes (parsed from the property path; filled by vv_animation_add_track). */
typedef struct vv_anim_target {
    int scope;                /**< internal: view, global, light, cut plane, object */
    int index;                /**< light, cut plane or object index; -1: object by name */
    char object[VV_NAME_MAX]; /**< object name when index is -1 */
    int field;                /**< internal field code */
    int sub;                  /**< local cut plane index of an object */
} vv_anim_target;

/**
 * A keyframe track: one property over time. Properties (docs/animation-format.md):
 * "view.eye", "view.at", "view.up", "view.fov", "view.ortho_height",
 * "background", "ambient", "lights[i].position|direction|color|intensity",
 * "cut_planes[i].point|normal", and for an object addressed as "objects[i]"
 * or "objects.NAME": ".position", ".orientation", ".scale", ".tf",
 * ".isovalue", ".threshold", ".step", ".time" (the time step, rounded to
 * the nearest: a grid's field NAME<T>, a volume's step as prepare_frame of
 * vv_anim_render_options loads it), ".material.color|ambient|diffuse|
 * specular|shininess|reflectance|transparency", ".cut_planes[j].point|normal".
 */
typedef struct vv_anim_track {
    char property[VV_ANIM_PATH_MAX];
    vv_anim_kind kind;
    vv_anim_target target;
    vv_anim_interp interp;
    /** 1: a closed path, its last key equal to its first; the spline wraps
     * round the seam (C1 there: the tangent at the seam is the same from both
     * sides). Times outside the keys are clamped, closed or not. */
    int closed;
    int n_keys;
    int cap_keys;
    vv_anim_key *keys; /**< owned, sorted by time */
} vv_anim_track;

/** The transformation sequences that need no keyframes. */
typedef enum vv_anim_sequence_type {
    VV_SEQ_ORBIT = 0,         /**< orbit the camera about the view's up axis */
    VV_SEQ_ROTATE_OBJECT = 1, /**< spin an object about an axis through its centre */
    VV_SEQ_FLY = 2,           /**< move the camera (eye and look-at point) along a line */
    VV_SEQ_SWEEP_CUT = 3      /**< move a new global cut plane along its normal */
} vv_anim_sequence_type;

/**
 * A sequence, running over the whole animation: at fraction f = t / duration
 * (frame k of N: exactly k / N) of the way,
 *  - ORBIT: the view becomes vv_anim_view_turn(base view, azimuth + degrees·f,
 *    elevation, zoom) with the angles converted from degrees; azimuth,
 *    elevation and zoom are the still view's own turn (`volvis render
 *    --azimuth --elevation --zoom`), 0, 0 and 1 to orbit the World's view;
 *  - ROTATE_OBJECT: object `object` turns by degrees·f about `axis` (world
 *    direction) through the centre of its world box in the base World;
 *  - FLY: eye and look-at point move by offset·f (world units);
 *  - SWEEP_CUT: a global cut plane with `normal` through point + normal·
 *    (distance·f) is appended to the World's cut planes.
 * Sequences are applied after the keyframe tracks, in order.
 */
typedef struct vv_anim_sequence {
    vv_anim_sequence_type type;
    double degrees;                  /**< ORBIT, ROTATE_OBJECT: total angle, degrees */
    double azimuth, elevation, zoom; /**< ORBIT: the base turn (degrees, degrees, factor > 0) */
    char object[VV_NAME_MAX];        /**< ROTATE_OBJECT: object name */
    vv_vec3 axis;                    /**< ROTATE_OBJECT: rotation axis (non-zero) */
    vv_vec3 offset;                  /**< FLY: total displacement, world units */
    vv_vec3 point, normal;           /**< SWEEP_CUT: start plane (normal non-zero) */
    double distance;                 /**< SWEEP_CUT: total travel along the unit normal */
} vv_anim_sequence;

/** An animation: tracks and sequences over [0, duration) at fps frames per second. */
typedef struct vv_animation {
    char *scene;     /**< scene file it animates, relative to the animation file; may be NULL */
    double fps;      /**< frames per second, > 0 (default 30) */
    double duration; /**< seconds, > 0 */
    int n_tracks;
    int cap_tracks;
    vv_anim_track *tracks; /**< owned */
    int n_sequences;
    int cap_sequences;
    vv_anim_sequence *sequences; /**< owned */
} vv_animation;

/** An empty animation: 30 fps, duration 1 s, no tracks. Errors: VV_ERR_NOMEM. */
vv_status vv_animation_new(vv_animation **out);
/** Releases the animation, its tracks, keys and key transfer functions. Accepts NULL. */
void vv_animation_free(vv_animation *a);
/** A deep copy. Errors: VV_ERR_NOMEM. */
vv_status vv_animation_clone(vv_animation **out, const vv_animation *a);

/** Number of frames: round(duration * fps), at least 1. */
int vv_animation_frame_count(const vv_animation *a);

/**
 * Appends an empty track for @p property (see vv_anim_track) and stores its
 * index in *index (may be NULL); the kind and target are parsed from the
 * property. Interpolation spline, not closed. Errors: VV_ERR_INVALID (unknown
 * property, with the reason), VV_ERR_NOMEM.
 */
vv_status vv_animation_add_track(vv_animation *a, const char *property, int *index);

/**
 * Inserts @p key into track @p track in time order (a copy; for a TF track
 * key->tf is copied, the caller keeps its own). Errors: VV_ERR_INVALID (a key
 * at the same time already, non-finite values, TF key without tf or tf on
 * another kind), VV_ERR_NOMEM.
 */
vv_status vv_anim_track_add_key(vv_anim_track *track, const vv_anim_key *key);

/** A key at @p time with zero tension, continuity and bias, linear easing, value 0. */
void vv_anim_key_init(vv_anim_key *key, double time);

/** Appends a sequence (copied). Errors: VV_ERR_INVALID (bad fields), VV_ERR_NOMEM. */
vv_status vv_animation_add_sequence(vv_animation *a, const vv_anim_sequence *seq);

/**
 * Checks every track and sequence: at least one key, keys in strictly
 * increasing time, finite values, KB parameters in [-1, 1], closed tracks
 * with equal first and last keys, positive fps and duration. Errors:
 * VV_ERR_INVALID naming the track and key ("tracks[1] view.eye: keys[2]:
 * time 1.5 is not after 2").
 */
vv_status vv_animation_validate(const vv_animation *a);

/**
 * Checks that every track and sequence finds its target in @p world (object
 * names and indices, light and cut plane indices, volume objects for tf and
 * isovalue) so that a final render can fail before its first frame. Errors:
 * VV_ERR_INVALID naming the track.
 */
vv_status vv_animation_check_world(const vv_animation *a, const vv_world *world);

/**
 * The value of track @p track at @p time into @p value (4 doubles; for a TF
 * track pass @p tf, else it may be NULL). Keys are hit exactly. Errors:
 * VV_ERR_INVALID (no keys).
 */
vv_status vv_anim_track_eval(const vv_anim_track *track, double time, double value[4], vv_tf *tf);

/**
 * The World at @p time: a vv_world_clone of @p base (borrowed, unchanged)
 * with the animation applied; for previews and the final render. The caller
 * frees *out. Thread-safe for concurrent calls on one animation and base.
 * Errors: VV_ERR_INVALID (a target is missing, see vv_animation_check_world),
 * VV_ERR_NOMEM.
 */
vv_status vv_animation_eval(const vv_animation *a, const vv_world *base, double time,
                            vv_world **out);

/**
 * The World of frame @p frame (0 .. frame count - 1): time frame / fps, and
 * the sequences at fraction exactly frame / N. Errors: as vv_animation_eval,
 * VV_ERR_INVALID for a frame out of range.
 */
vv_status vv_animation_eval_frame(const vv_animation *a, const vv_world *base, int frame,
                                  vv_world **out);

/**
 * The view change of `volvis render --azimuth --elevation --zoom` (all
 * radians here except the zoom factor): vv_view_orbit by azimuth and elevation
 * unless both are 0, then the eye moved towards `at` to 1/zoom of its distance
 * and ortho_height divided by zoom unless zoom is 1.
 */
void vv_anim_view_turn(vv_view *view, double azimuth, double elevation, double zoom);

/* ---- files ---------------------------------------------------------------- */

/**
 * Loads an animation file (JSON, docs/animation-format.md, at most 16 MiB).
 * Unknown keys and properties, keys out of order, non-finite numbers, empty
 * tracks are errors. Errors: VV_ERR_IO, VV_ERR_LIMIT, VV_ERR_FORMAT with the
 * file, line, column and the path of the key ("orbit.json:14:9:
 * tracks[0].keys[2].time: time 1 is not after 2 (track view.eye)").
 */
vv_status vv_animation_load(vv_animation **out, const char *path);

/**
 * Writes @p a as an animation file, atomically (angles in degrees, every
 * key with its parameters). Errors: VV_ERR_IO, VV_ERR_INVALID (fails
 * vv_animation_validate).
 */
vv_status vv_animation_save(const vv_animation *a, const char *path);

/* ---- flight paths ------------------------------------------------------------ */

typedef struct vv_flight_recorder vv_flight_recorder;

/** A new, empty recorder. Errors: VV_ERR_NOMEM. */
vv_status vv_flight_recorder_new(vv_flight_recorder **out);
/** Releases a recorder. Accepts NULL. */
void vv_flight_recorder_free(vv_flight_recorder *r);
/**
 * Adds the camera at @p time (seconds, e.g. from a 30 Hz timer in the
 * Navigator; strictly increasing). Errors: VV_ERR_INVALID (time not after the
 * last sample, non-finite view), VV_ERR_NOMEM. Not thread-safe.
 */
vv_status vv_flight_recorder_add(vv_flight_recorder *r, double time, const vv_view *view);
/** Number of samples so far. */
int vv_flight_recorder_count(const vv_flight_recorder *r);

/**
 * Turns the samples into an editable animation: tracks view.eye, view.at,
 * view.up (and view.fov when it changed), spline-interpolated, with keys at
 * the samples that Douglas–Peucker-like thinning keeps: a sample is dropped
 * when, on the straight (time-linear) path between the kept samples around
 * it, the eye and look-at point are within @p position_tolerance (world
 * units) and the camera orientation within @p angle_tolerance (radians) and
 * the fov within angle_tolerance. The first and last samples are always
 * kept. Times start at 0; duration = last time + 1 / fps. The recorder is
 * left unchanged. Errors: VV_ERR_INVALID (fewer than 2 samples, negative
 * tolerances, fps <= 0), VV_ERR_NOMEM.
 */
vv_status vv_flight_recorder_finish(const vv_flight_recorder *r, double position_tolerance,
                                    double angle_tolerance, double fps, vv_animation **out);

/* ---- final render ------------------------------------------------------------ */

/** Options of vv_animation_render. */
typedef struct vv_anim_render_options {
    /**
     * Output: a PNG sequence pattern with one integer conversion
     * ("out/frame_%04d.png"), an existing directory (frames
     * DIR/frame_%04d.png), or a video file ending in .mp4 (H.264) or .webm
     * (VP9). Required.
     */
    const char *output;
    vv_render_options render; /**< per frame (its progress is ignored; see progress below) */
    double gamma;             /**< 8-bit conversion (default 1) */
    int alpha;                /**< PNG sequences: 1 writes RGBA */
    int resume;               /**< 1 (default): keep complete frames of an interrupted run */
    vv_video_options video;   /**< codec quality and threads; fps comes from the animation */
    /**
     * Overall progress, (frames done + fraction of the current frame) / N;
     * returning non-zero cancels (VV_ERR_CANCELLED; the frames written so far
     * are kept for a resume, no partial video is left). During a frame it
     * may be called from the renderer's threads, never from two at once.
     */
    vv_progress progress;
    /** Called after each frame is ready, from the calling thread (may be NULL);
     * reused 1 for a complete PNG frame of an earlier run (a video's kept
     * frames are not shown again). The image is borrowed for the call. */
    void (*on_frame)(void *user, int frame, const vv_image *img, int reused);
    void *on_frame_user;
    /**
     * Renders frame @p frame (its World snapshot @p w and view) into @p out
     * in place of vv_renderer_render (NULL: the renderer); the distributed
     * `volvis animate` under mpirun renders through it (vv_parallel_render).
     */
    vv_status (*render_frame)(void *user, int frame, const vv_world *w, const vv_view *view,
                              const vv_render_options *ro, vv_image *out);
    void *render_frame_user;
    /**
     * Called with frame @p frame's World snapshot @p w (the caller's alone,
     * freed after the frame) before it is drawn, from the calling thread;
     * may change it: `volvis animate` puts the time step an object's
     * ".time" track asks for into the object (vv_time_series_get,
     * vv_object_replace_volumes). NULL: nothing. An error stops the render.
     */
    vv_status (*prepare_frame)(void *user, int frame, vv_world *w);
    void *prepare_frame_user;
} vv_anim_render_options;

/** output NULL, default render options, gamma 1, RGB, resume on, default video options. */
void vv_anim_render_options_init(vv_anim_render_options *o);

/** What vv_animation_render did. */
typedef struct vv_anim_render_stats {
    int frames;      /**< frames in the animation */
    int rendered;    /**< frames rendered in this run */
    int reused;      /**< complete frames found from an earlier run */
    double render_s; /**< wall seconds spent in the renderer */
    double total_s;  /**< wall seconds of the whole call */
} vv_anim_render_stats;

/**
 * The final render (VolVis paper, section 4: preview, then render with an
 * accurate renderer to make a movie): every frame in order, each a
 * vv_animation_eval_frame of @p base drawn by @p renderer (borrowed; it is
 * OpenMP-parallel and uses every core unless render.threads says otherwise),
 * deterministic for a given input.
 *
 * PNG sequence: each frame is written atomically; with resume, a frame whose
 * PNG exists and decodes at the right size is not rendered again. Video: the
 * codec and the output directory are checked, and the temporary video file
 * beside the output opened, before the first frame; frames are also kept as
 * PNGs in the work folder "OUTPUT.frames/" (so an interrupted run resumes),
 * encoded on a second thread while the next frame renders, and the work
 * folder is deleted once the video is complete and renamed into place.
 *
 * Errors: VV_ERR_INVALID (bad options, animation, targets), VV_ERR_IO
 * (unwritable output), VV_ERR_UNSUPPORTED (no codec, video without FFmpeg),
 * VV_ERR_CANCELLED, or the renderer's error; nothing is left at @p output
 * unless the call succeeded (PNG frames written before a failure stay).
 * @p stats may be NULL.
 */
vv_status vv_animation_render(const vv_animation *a, const vv_world *base, vv_renderer *renderer,
                              const vv_anim_render_options *opt, vv_anim_render_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
