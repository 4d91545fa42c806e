/*
 * VvgMeasurementPage: the Measurement page (VolVis paper, section 4,
 * Measurement): the histogram of the selected volume (log scale switch);
 * isosurface area and volume by Marching Cubes or voxel counting, for the
 * whole volume or surface-tracked from a voxel (typed, or picked with a
 * click in the scene view), on a worker thread; the distance between two
 * points (typed or picked on the first visible surface of the final frame);
 * mesh area and volume. Each result shows under its button, in the
 * volume's units (vvg_unit_label: "mm", or "voxel units" when the file gives
 * none), and in the page's log, selectable, with a Copy button. Picked
 * points, the line between them and the surface-tracked region are drawn in
 * the 3-D and slice views (VvgMarks).
 * Installs the actions histogram, measure, distance, pick-seed, pick-a and
 * pick-b in the given action map. UI thread only.
 */
#ifndef VVG_MEASUREMENT_PAGE_H
#define VVG_MEASUREMENT_PAGE_H

#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VVG_TYPE_MEASUREMENT_PAGE (vvg_measurement_page_get_type())
G_DECLARE_FINAL_TYPE(VvgMeasurementPage, vvg_measurement_page, VVG, MEASUREMENT_PAGE, GtkBox)

/**
 * The page for @p doc and @p marks (references are held); points are picked
 * in @p scene; actions go into @p actions (both borrowed).
 */
GtkWidget *vvg_measurement_page_new(VvgDocument *doc, VvgSceneView *scene, VvgMarks *marks,
                                    GActionMap *actions);

G_END_DECLS
#endif
