/*
 * VvgViewArea: the window's view area. While the World is empty it shows the
 * start page (VvgStartPage); otherwise the 3-D scene view alone (1-up) or
 * beside three slice views (4-up, as 3D Slicer's four-up layout: the 3-D
 * view and the axial view above, the coronal and sagittal views below).
 * UI thread only.
 */
#ifndef VVG_VIEW_AREA_H
#define VVG_VIEW_AREA_H

#include "vvg-marks.h"
#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VVG_TYPE_VIEW_AREA (vvg_view_area_get_type())
G_DECLARE_FINAL_TYPE(VvgViewArea, vvg_view_area, VVG, VIEW_AREA, GtkBox)

/** The area for @p doc with @p scene and slice views linked by @p marks (references held). */
GtkWidget *vvg_view_area_new(VvgDocument *doc, VvgSceneView *scene, VvgMarks *marks);
/** 1 (the 3-D view alone) or 4 (four-up). */
void vvg_view_area_set_layout(VvgViewArea *area, int views);
int vvg_view_area_layout(VvgViewArea *area);
/** The slice view @p i (0 axial, 1 coronal, 2 sagittal at start). */
GtkWidget *vvg_view_area_slice_view(VvgViewArea *area, int i);
/** Reads the recent files of the start page again. */
void vvg_view_area_refresh_recent(VvgViewArea *area);

G_END_DECLS
#endif
