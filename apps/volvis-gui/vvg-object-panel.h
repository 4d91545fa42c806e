/*
 * VvgObjectPanel: Object Control for the selected object (VolVis paper,
 * section 4): its placement (position and uniform scale, world units; the
 * Navigator moves it too and the numbers follow; the scale pivots on the
 * object's centre; the up axis, Z as stored or Y turned to Z for meshes from
 * Y-up exporters), colour and material
 * (ambient, diffuse, specular, shininess, reflectance, transparency),
 * textures (a PNG image with planar, cylindrical or spherical projection;
 * a checker, wood or marble solid texture) and the shading flags of the
 * ray tracer. Every edit is one undo step of the document. UI thread only.
 */
#ifndef VVG_OBJECT_PANEL_H
#define VVG_OBJECT_PANEL_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_OBJECT_PANEL (vvg_object_panel_get_type())
G_DECLARE_FINAL_TYPE(VvgObjectPanel, vvg_object_panel, VVG, OBJECT_PANEL, GtkBox)

/** The panel for the selected object of @p doc (a reference is held). */
GtkWidget *vvg_object_panel_new(VvgDocument *doc);

G_END_DECLS
#endif
