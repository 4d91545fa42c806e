/*
 * VvgLightsPanel: the World's lights (VolVis paper, section 4: lights are
 * manipulated like objects): the light being edited, its type
 * (directional, point, headlight), colour and intensity; Add and Remove;
 * the ambient light and the background colour. The light chosen here is
 * the one a "selected light" drag in the scene view moves. Every edit is
 * one undo step. Installs the actions "add-light" and "remove-light" in the
 * given action map (the window's: "win.add-light"). UI thread only.
 */
#ifndef VVG_LIGHTS_PANEL_H
#define VVG_LIGHTS_PANEL_H

#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VVG_TYPE_LIGHTS_PANEL (vvg_lights_panel_get_type())
G_DECLARE_FINAL_TYPE(VvgLightsPanel, vvg_lights_panel, VVG, LIGHTS_PANEL, GtkBox)

/**
 * The panel for the World of @p doc (a reference is held); @p scene is told
 * which light a drag moves; the actions go into @p actions (both borrowed:
 * the window owns them and the panel).
 */
GtkWidget *vvg_lights_panel_new(VvgDocument *doc, VvgSceneView *scene, GActionMap *actions);

G_END_DECLS
#endif
