/*
 * VvgSceneView: the window's scene view and the Navigator (VolVis paper,
 * section 4). It shows the document's World, turns mouse, scroll and key
 * input into view, object and light manipulation, and keeps the frame rate
 * by drawing reduced-resolution previews while things move
 * (vv_preview_policy), refining to the selected renderer at full quality
 * when input stops.
 *
 * Rendering runs on a worker thread on a snapshot of the World; the UI
 * thread only posts work and shows finished frames. A frame for a state
 * older than the one on screen is never shown, and refinement for an old
 * state is cancelled as soon as new input arrives.
 *
 * With VOLVIS_FRAME_LOG=FILE set, one line is appended per frame put on
 * screen: "<ms since start> <representation> <W>x<H> <render ms> <latency ms>
 * <state> <gui ms>": the state is the number of World changes the frame
 * shows, the GUI time runs from the renderer's end to the paint
 * (docs/gui.md). UI thread only, except where noted.
 */
#ifndef VVG_SCENE_VIEW_H
#define VVG_SCENE_VIEW_H

#include "vvg-document.h"
#include "vvg-marks.h"

G_BEGIN_DECLS

#define VVG_TYPE_SCENE_VIEW (vvg_scene_view_get_type())
G_DECLARE_FINAL_TYPE(VvgSceneView, vvg_scene_view, VVG, SCENE_VIEW, GtkWidget)

/** What a drag moves. */
typedef enum VvgNavTarget {
    VVG_NAV_VIEW = 0,   /**< the camera (trackball, pan, zoom) */
    VVG_NAV_OBJECT = 1, /**< the selected object */
    VVG_NAV_LIGHT = 2,  /**< the selected light */
    VVG_NAV_CUT = 3     /**< the cut plane chosen with vvg_scene_view_set_cut_plane (else the
                            selected object's last one, else the last global one): a drag
                            moves it along its normal, Shift+drag turns the normal */
} VvgNavTarget;

/** The view of @p doc with the marks of @p marks drawn over it (references are held). */
VvgSceneView *vvg_scene_view_new(VvgDocument *doc, VvgMarks *marks);
void vvg_scene_view_set_target(VvgSceneView *view, VvgNavTarget target);
/**
 * The cut plane a VVG_NAV_CUT drag moves: plane @p plane of object @p object
 * (-1: the World's global planes); @p plane -1 (or a plane that no longer
 * exists): the selected object's last one, else the last global one.
 */
void vvg_scene_view_set_cut_plane(VvgSceneView *view, int object, int plane);
/** The light a VVG_NAV_LIGHT drag moves. */
void vvg_scene_view_set_light(VvgSceneView *view, int index);
/** Forces a representation while moving (a vv_preview_kind), or -1 for automatic. */
void vvg_scene_view_set_preview(VvgSceneView *view, int kind);
/** Delay in milliseconds after the last input before refinement starts (0..2000). */
void vvg_scene_view_set_refine_delay(VvgSceneView *view, int ms);
/** Flight-simulator keys (arrows: yaw and pitch, Q/E: roll, W/S: throttle) on or off. */
void vvg_scene_view_set_flight(VvgSceneView *view, gboolean on);
/** Milliseconds the last full-quality frame took to render (0 before the first). */
double vvg_scene_view_full_ms(VvgSceneView *view);
/** Representation name of the frame on screen ("" before the first). */
const char *vvg_scene_view_shown(VvgSceneView *view);
/**
 * What the frame on screen drew from files out of core (the objects'
 * sources: pyramids by level of detail, bricked files by bricks), for the
 * Navigator: the pieces the process's one cache holds against its one
 * memory limit (vv_cache_stats), the chunks loading, the chunks and bricks
 * read, the levels the frame used (nodes per level) and how many nodes are
 * still drawn coarser than their level ("converged" when none); why the
 * proxies were drawn in memory instead; "" when the frame on screen drew
 * nothing out of core. Newly allocated (g_free).
 */
char *vvg_scene_view_cache_status(VvgSceneView *view);
/** Re-renders now (the World changed outside a drag). */
void vvg_scene_view_refresh(VvgSceneView *view);

/**
 * The world point under widget position (x, y) on the frame on screen: the
 * first visible surface along the pixel's ray, from the depth of the last
 * full-quality frame. FALSE when nothing is there or the frame on screen is
 * not a full-quality one of the current state.
 */
gboolean vvg_scene_view_pick(VvgSceneView *view, double x, double y, vv_vec3 *world);
/** Called with the picked world point by the next click in the view (instead of a drag). */
typedef void (*VvgPickFunc)(gpointer user, vv_vec3 world);
/** Arms a one-shot pick: the next click in the view calls @p fn (NULL disarms). */
void vvg_scene_view_pick_next(VvgSceneView *view, VvgPickFunc fn, gpointer user);

/** Microseconds of g_get_monotonic_time() at which the process started (for the frame log). */
void vvg_scene_view_set_start_time(gint64 us);

/**
 * Stops the render thread: the frame being drawn is cancelled and the
 * thread joined; the view keeps what is on screen and draws nothing more.
 * The window calls it when it goes: a frame being drawn holds a reference
 * to the view, so the view's own dispose (which stops the thread too) can
 * come after the window's, or never before the process exits. Idempotent.
 */
void vvg_scene_view_stop(VvgSceneView *view);

G_END_DECLS
#endif
