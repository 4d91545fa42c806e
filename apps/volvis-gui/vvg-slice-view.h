/*
 * VvgSliceView: one slice view of multiplanar reconstruction beside the 3-D
 * view (3D Slicer's red, yellow and green views): the axial, coronal,
 * sagittal or oblique slice (the selected cut plane's) of the selected
 * volume object, sampled by the library (include/volvis/slice.h: what
 * `volvis slice` writes) at the widget's size and scale, windowed to grey.
 *
 * Linked through VvgMarks: the three orthogonal slices pass through one
 * cursor, drawn as a crosshair in each; a click or drag with the left
 * button moves it (the other views follow) and the line under the image
 * reads the voxel value there with its voxel index and world position in
 * the file's units; a right-button drag (or Ctrl + left) sets window
 * (horizontal) and level (vertical) for all views; the wheel scrolls
 * through slices one voxel at a time. The edges are labelled with the
 * anatomical directions (R/L, A/P, S/I) or the World's axes. Measurement
 * points and the surface-tracked region are drawn where they cut the
 * slice. With VOLVIS_SLICE_LOG=FILE set, a line is appended each time a
 * view samples its slice again: "<monotonic ms> <axis> <W>x<H> <sample ms>
 * <position along the normal>" (bench/bench_gui.py reads it). UI thread only.
 */
#ifndef VVG_SLICE_VIEW_H
#define VVG_SLICE_VIEW_H

#include "vvg-document.h"
#include "vvg-marks.h"

G_BEGIN_DECLS

#define VVG_TYPE_SLICE_VIEW (vvg_slice_view_get_type())
G_DECLARE_FINAL_TYPE(VvgSliceView, vvg_slice_view, VVG, SLICE_VIEW, GtkBox)

/** A view of @p axis for @p doc, linked by @p marks (references are held). */
GtkWidget *vvg_slice_view_new(VvgDocument *doc, VvgMarks *marks, vv_slice_axis axis);
/** Shows another orientation. */
void vvg_slice_view_set_axis(VvgSliceView *view, vv_slice_axis axis);
vv_slice_axis vvg_slice_view_axis(VvgSliceView *view);
/** The readout line (for tests and the screen reader: the label's text). */
const char *vvg_slice_view_readout(VvgSliceView *view);
/** Milliseconds the last resampling took (0 before the first). */
double vvg_slice_view_sample_ms(VvgSliceView *view);

G_END_DECLS
#endif
