/*
 * VvgTf2dEditor: the 2-D transfer-function editor of Object Control: widgets
 * over data value (x) x gradient magnitude (y, 0 at the bottom), drawn over
 * the selected volume's joint histogram (log counts), as in Kniss,
 * Kindlmann and Hansen 2002. Click a widget to select it, drag to move it,
 * Shift+drag to resize it (a rectangle's upper corner, a triangle's width and
 * height), right click to delete it. Each press is one undo step; the view
 * updates live while dragging. UI thread only.
 */
#ifndef VVG_TF2D_EDITOR_H
#define VVG_TF2D_EDITOR_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_TF2D_EDITOR (vvg_tf2d_editor_get_type())
G_DECLARE_FINAL_TYPE(VvgTf2dEditor, vvg_tf2d_editor, VVG, TF2D_EDITOR, GtkWidget)

VvgTf2dEditor *vvg_tf2d_editor_new(VvgDocument *doc);
/**
 * Adds a widget to the selected volume's 2-D transfer function (one undo
 * step): a rectangle over the middle of the value range and the lower half
 * of the gradient range, or a triangle at the middle value; it becomes the
 * selected widget and the object switches to 2-D segmentation.
 */
void vvg_tf2d_editor_add(VvgTf2dEditor *ed, vv_tf2d_shape shape);
/** Sets the selected widget's colour and opacity (one undo step); ignored without one. */
void vvg_tf2d_editor_set_style(VvgTf2dEditor *ed, const GdkRGBA *color, double opacity);
/** Index of the selected widget, or -1. */
int vvg_tf2d_editor_selected(VvgTf2dEditor *ed);

G_END_DECLS
#endif
