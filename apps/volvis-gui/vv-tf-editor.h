/*
 * VvTfEditor: the 1-D transfer-function editor of Object Control (VolVis
 * paper, section 4), drawn over the selected volume's histogram (linear or
 * log scale). Opacity points: click on empty space adds one, drag moves it,
 * right click deletes it. Colour points live in the strip along the bottom:
 * click adds one in the current colour, drag moves it, right click deletes
 * it. Every press is one undo step of the document; the view updates live
 * while dragging. UI thread only.
 */
#ifndef VV_TF_EDITOR_H
#define VV_TF_EDITOR_H

#include "vv-document.h"

G_BEGIN_DECLS

#define VV_TYPE_TF_EDITOR (vv_tf_editor_get_type())
G_DECLARE_FINAL_TYPE(VvTfEditor, vv_tf_editor, VV, TF_EDITOR, GtkWidget)

VvTfEditor *vv_tf_editor_new(VvDocument *doc);
/** Logarithmic histogram on or off. */
void vv_tf_editor_set_log(VvTfEditor *ed, gboolean log);
/** The colour new colour points get. */
void vv_tf_editor_set_color(VvTfEditor *ed, const GdkRGBA *color);

G_END_DECLS
#endif
