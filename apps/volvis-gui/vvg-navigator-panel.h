/*
 * VvgNavigatorPanel: the Navigator's settings (VolVis paper, section 4):
 * what a drag in the scene view moves (view, selected object, selected
 * light, cut plane), the preview representation drawn while things move,
 * the delay before refinement, and the flight-simulator keys. They are
 * settings of the scene view, not of the World: no undo steps. UI thread only.
 */
#ifndef VVG_NAVIGATOR_PANEL_H
#define VVG_NAVIGATOR_PANEL_H

#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VVG_TYPE_NAVIGATOR_PANEL (vvg_navigator_panel_get_type())
G_DECLARE_FINAL_TYPE(VvgNavigatorPanel, vvg_navigator_panel, VVG, NAVIGATOR_PANEL, GtkBox)

/** The settings of @p scene (borrowed: the window owns both). */
GtkWidget *vvg_navigator_panel_new(VvgSceneView *scene);
/** Shows and sets what a drag moves (the window's Alt+1..4). */
void vvg_navigator_panel_set_target(VvgNavigatorPanel *panel, VvgNavTarget target);

G_END_DECLS
#endif
