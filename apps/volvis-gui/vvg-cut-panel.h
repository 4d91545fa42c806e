/*
 * VvgCutPanel: cut planes (VolVis paper, section 4: global cut planes and
 * per-object ones) as a list: each plane with its point and normal, a check
 * that switches it on or off (a plane switched off leaves the World, so it
 * is neither drawn nor saved, and is kept in the list until switched on or
 * removed) and Remove. Add puts a plane through the World's centre (or the
 * point and normal typed while none is selected) into the World or the
 * selected object. Clicking a plane selects it: its numbers can be typed,
 * they follow its handle in the scene view (which moves the selected
 * plane, Alt+4) and the oblique slice view shows it. Every edit is one undo
 * step. Installs the actions "add-cut-plane" and "clear-cut-planes" in the
 * given action map. UI thread only.
 */
#ifndef VVG_CUT_PANEL_H
#define VVG_CUT_PANEL_H

#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VVG_TYPE_CUT_PANEL (vvg_cut_panel_get_type())
G_DECLARE_FINAL_TYPE(VvgCutPanel, vvg_cut_panel, VVG, CUT_PANEL, GtkBox)

/**
 * The panel for @p doc (a reference is held); the selected plane is the one
 * @p scene's cut-plane drag moves; actions go into @p actions (both borrowed).
 */
GtkWidget *vvg_cut_panel_new(VvgDocument *doc, VvgSceneView *scene, GActionMap *actions);

G_END_DECLS
#endif
