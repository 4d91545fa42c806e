/*
 * The scene view's insides (internal to VvgSceneView): its fields, shared by
 * vvg-scene-view.c (the widget: the image and overlays on screen, picking,
 * mouse, scroll and flight-key input, the Navigator's settings) and
 * vvg-scene-render.c (the render thread: requests, previews, refinement,
 * sharpening out of core, finished frames handed to the UI thread). UI
 * thread only, except where noted.
 */
#ifndef VVG_SCENE_RENDER_H
#define VVG_SCENE_RENDER_H

#include "vvg-scene-view.h"

G_BEGIN_DECLS

/* Seconds a preview frame may take so the view holds 24 frames a second
 * (the target is 20, with room for the load of a shared machine), leaving
 * time for showing it. */
#define VVG_PREVIEW_BUDGET (1.0 / 24.0 - 0.006)

/* The files out of core a frame draws objects from (the visible objects'
 * sources, a reference each): for sharpening (vv_source_wait) and the
 * Navigator's cache line. */
typedef struct VvgSourceSet {
    vv_source *s[VV_SOURCES_MAX];
    int n;
} VvgSourceSet;

/** Releases the references @p s holds and empties it. */
void vvg_source_set_clear(VvgSourceSet *s);

/** One request to the render thread (vvg-scene-render.c). */
typedef struct VvgSceneJob VvgSceneJob;

struct _VvgSceneView {
    GtkWidget parent;
    VvgDocument *doc;
    VvgMarks *marks;
    gulong changed_id;

    /* worker */
    GThread *thread;
    GMutex lock;
    GCond cond;
    VvgSceneJob *pending; /* newest request not yet taken */
    vv_world *last_world; /* the last refined state, for warm_previews (under lock) */
    gboolean quit;        /* written under lock, atomically: cancel_cb reads it without */
    guint64 cancel_below; /* refinement of a generation below this stops (atomic) */
    vv_preview *preview;  /* worker only */
    char preview_renderer[32];
    /* worker only: why the gpu renderer failed in this view ("" while it has
     * not): the CPU ray caster draws its frames from then on */
    char gpu_failed[256];
    vv_preview_policy policy; /* under lock: written by the worker, read by the UI */

    /* UI */
    guint64 gen;       /* of the World's current state */
    guint64 shown_gen; /* of the frame on screen */
    int shown_kind;
    GdkTexture *texture;
    gboolean texture_logged;
    double shown_render_ms;
    float *shown_depth; /* of the full frame on screen, or NULL */
    vv_view shown_view;
    VvgPickFunc pick_fn;
    gpointer pick_user;
    gboolean dragged;
    gint64 shown_latency_us;
    gint64 shown_rendered_us; /* when the renderer finished the frame on screen */
    guint refine_source;
    int refine_delay_ms;
    gboolean moving;
    VvgNavTarget target;
    int light;
    int cut_object, cut_plane; /* vvg_scene_view_set_cut_plane */
    double drag_last_x, drag_last_y;
    int drag_button;
    GdkModifierType drag_mods;
    double full_ms;
    FILE *frame_log;
    char last_error[512];
    /* the frame on screen's files out of core and what it drew */
    VvgSourceSet shown_src;
    int shown_nodes[VV_LOD_MAX_LEVELS], shown_pending, shown_stalled;
    char shown_lod_note[128];
    char shown_gpu_note[256]; /* the frame on screen's gpu_failed ("" none) */

    /* flight */
    gboolean flight;
    double yaw_rate, pitch_rate, roll_rate, throttle;
    guint tick_id;
    gint64 last_tick_us;

#ifdef VVG_TSAN
    gboolean tsan_inject_race;                        /* VOLVIS_TSAN_INJECT_RACE=1 */
    guint64 tsan_posted, tsan_cancelled, tsan_warmed; /* worker only */
    guint64 tsan_shown, tsan_dropped;                 /* UI only */
#endif
};

/** Starts the render thread (vvg_scene_view_stop stops it). */
void vvg_scene_render_start(VvgSceneView *self);
/**
 * Asks the render thread for the document's World as it is now, drawn as
 * the @p n_kinds representations of @p kinds in turn (at most 3); a
 * refinement (@p refine) stops as soon as the state changes. It replaces a
 * request the thread has not taken yet.
 */
void vvg_scene_render_post(VvgSceneView *self, gboolean refine, const vv_preview_kind *kinds,
                           int n_kinds);

G_END_DECLS
#endif
