/*
 * VvgAnimatorPage: the Animator page of the side bar (VolVis paper, section 4
 * "Manipulation": the Animator; library in include/volvis/animate.h). It
 * owns the current animation (vv_animation) and shows its keyframe tracks
 * and sequences; makes it from transformation sequences without keyframes
 * (orbit the camera, rotate the selected object, fly, sweep a cut plane),
 * from camera keys taken from the document's view ("Add camera key") or
 * from a recorded flight path (the view sampled at 30 Hz while the user
 * navigates, thinned by vv_flight_recorder_finish); opens and saves
 * animation files (docs/animation-format.md).
 *
 * Play previews the animation in real time at 30 frames a second: each
 * frame is vv_animation_eval of the World as it was at Play, shown with
 * vvg_document_show_transient (no undo steps), so the scene view draws its
 * Navigator previews; Stop puts the World back exactly. An edit during Play
 * stops it, keeping the frame shown.
 *
 * Render writes the final animation (PNG sequence, MP4 or WebM) with
 * vv_animation_render on a worker thread, from snapshots of the World and
 * the animation, with the World's renderer, options and quality (the
 * Rendering page), a progress bar with the time left and Cancel; an
 * interrupted render resumes (the library keeps finished frames).
 * UI thread only.
 */
#ifndef VVG_ANIMATOR_PAGE_H
#define VVG_ANIMATOR_PAGE_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_ANIMATOR_PAGE (vvg_animator_page_get_type())
G_DECLARE_FINAL_TYPE(VvgAnimatorPage, vvg_animator_page, VVG, ANIMATOR_PAGE, GtkBox)

/** The page for the World of @p doc (a reference is held). */
GtkWidget *vvg_animator_page_new(VvgDocument *doc);
/** The current animation (owned by the page; valid until it is replaced). */
const vv_animation *vvg_animator_page_animation(VvgAnimatorPage *page);
/** TRUE while Play runs. */
gboolean vvg_animator_page_playing(VvgAnimatorPage *page);

G_END_DECLS
#endif
