/*
 * VvViewArea: the window's view area. While the World is empty it shows the
 * start page (VvStartPage); otherwise the 3-D scene view alone (1-up) or
 * beside three slice views (4-up, as 3D Slicer's four-up layout: the 3-D
 * view and the axial view above, the coronal and sagittal views below).
 * UI thread only.
 */
#ifndef VV_VIEW_AREA_H
#define VV_VIEW_AREA_H

#include "vvg-marks.h"
#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VV_TYPE_VIEW_AREA (vv_view_area_get_type())
G_DECLARE_FINAL_TYPE(VvViewArea, vv_view_area, VV, VIEW_AREA, GtkBox)

/** The area for @p doc with @p scene and slice views linked by @p marks (references held). */
GtkWidget *vv_view_area_new(VvDocument *doc, VvSceneView *scene, VvMarks *marks);
/** 1 (the 3-D view alone) or 4 (four-up). */
void vv_view_area_set_layout(VvViewArea *area, int views);
int vv_view_area_layout(VvViewArea *area);
/** The slice view @p i (0 axial, 1 coronal, 2 sagittal at start). */
GtkWidget *vv_view_area_slice_view(VvViewArea *area, int i);
/** Reads the recent files of the start page again. */
void vv_view_area_refresh_recent(VvViewArea *area);

G_END_DECLS
#endif
