/*
 * VvLightsPanel: the World's lights (VolVis paper, section 4: lights are
 * manipulated like objects): the light being edited, its type
 * (directional, point, headlight), colour and intensity; Add and Remove;
 * the ambient light and the background colour. The light chosen here is
 * the one a "selected light" drag in the scene view moves. Every edit is
 * one undo step. Installs the actions "add-light" and "remove-light" in the
 * given action map (the window's: "win.add-light"). UI thread only.
 */
#ifndef VV_LIGHTS_PANEL_H
#define VV_LIGHTS_PANEL_H

#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VV_TYPE_LIGHTS_PANEL (vv_lights_panel_get_type())
G_DECLARE_FINAL_TYPE(VvLightsPanel, vv_lights_panel, VV, LIGHTS_PANEL, GtkBox)

/**
 * The panel for the World of @p doc (a reference is held); @p scene is told
 * which light a drag moves; the actions go into @p actions (both borrowed:
 * the window owns them and the panel).
 */
GtkWidget *vv_lights_panel_new(VvDocument *doc, VvSceneView *scene, GActionMap *actions);

G_END_DECLS
#endif
