/*
 * VvgTfEditor: the 1-D transfer-function editor of Object Control (VolVis
 * paper, section 4), drawn over the selected volume's histogram (linear or
 * log scale) with axes: opacity 0 .. 1 up the left, data values along the
 * bottom. Opacity points: click on empty space adds one, drag moves it,
 * right click deletes it. Colour points live in the strip along the bottom:
 * click adds one in the current colour, drag moves it, right click deletes
 * it. A line under the plot reads the value, opacity, colour and share of
 * voxels under the pointer; the point clicked last is the selected point,
 * whose value, opacity (or colour) can be typed and which Delete removes.
 * Every press or typed number is one undo step of the document; the view
 * updates live while dragging. UI thread only.
 */
#ifndef VVG_TF_EDITOR_H
#define VVG_TF_EDITOR_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_TF_EDITOR (vvg_tf_editor_get_type())
G_DECLARE_FINAL_TYPE(VvgTfEditor, vvg_tf_editor, VVG, TF_EDITOR, GtkBox)

VvgTfEditor *vvg_tf_editor_new(VvgDocument *doc);
/** Logarithmic histogram on or off. */
void vvg_tf_editor_set_log(VvgTfEditor *ed, gboolean log);
/** The colour new colour points get. */
void vvg_tf_editor_set_color(VvgTfEditor *ed, const GdkRGBA *color);

G_END_DECLS
#endif
