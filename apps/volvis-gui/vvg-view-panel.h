/*
 * VvgViewPanel: the World's view typed as numbers (the Navigator moves it
 * too, and the numbers follow ten times a second): eye and look-at point
 * (world units), field of view (degrees) and projection; buttons for the
 * front, side and top presets and Frame all (the window's actions). The
 * image size is the scene view's own (it fills the window); a final render
 * takes any size in its window. Every edit is one undo step. UI thread only.
 */
#ifndef VVG_VIEW_PANEL_H
#define VVG_VIEW_PANEL_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_VIEW_PANEL (vvg_view_panel_get_type())
G_DECLARE_FINAL_TYPE(VvgViewPanel, vvg_view_panel, VVG, VIEW_PANEL, GtkBox)

/** The panel for the view of @p doc (a reference is held). */
GtkWidget *vvg_view_panel_new(VvgDocument *doc);

G_END_DECLS
#endif
