/*
 * VvgTfPanel: segmentation of the selected object (VolVis paper, section 4,
 * Object Control): by transfer function, threshold, 2-D transfer function or
 * labels; the render mode (composite, MIP, MinIP, X-ray, isosurface), the
 * isovalue and the sample step; the 1-D transfer-function editor over the
 * volume's histogram with its presets; the 2-D transfer-function editor over
 * value x gradient magnitude. Every edit is one undo step of the document;
 * the slice views' window and level (of a one-channel volume), which are the
 * views' display and not the World's, are set without one.
 * UI thread only.
 */
#ifndef VVG_TF_PANEL_H
#define VVG_TF_PANEL_H

#include "vvg-document.h"
#include "vvg-marks.h"

G_BEGIN_DECLS

#define VVG_TYPE_TF_PANEL (vvg_tf_panel_get_type())
G_DECLARE_FINAL_TYPE(VvgTfPanel, vvg_tf_panel, VVG, TF_PANEL, GtkBox)

/** The panel for the selected object of @p doc and the slice views'
 * window and level in @p marks (a reference to each is held). */
GtkWidget *vvg_tf_panel_new(VvgDocument *doc, VvgMarks *marks);

G_END_DECLS
#endif
