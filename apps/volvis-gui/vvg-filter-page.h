/*
 * VvgFilterPage: the Filtering page of the side bar (the paper's "Modeling
 * and Filtering" stage, Figure 1; library in include/volvis/filter.h). A
 * filter chain in the command line's syntax ("--gaussian 1.5 --threshold
 * 300: --largest 1"), typed or built a step at a time from the list of
 * filters with their arguments and units, is applied to the selected
 * volume object on a worker thread, with a progress bar and Cancel. The
 * result replaces the object's volume in one undo step; the chain is added
 * to the object's filters (geometry.filters), so a saved session reloads
 * the file and filters it again. A label volume (--components) is shown by
 * label (segmentation "labels"). The object's transfer function is kept; a
 * mask or a new value range gets a ramp over its values only when "adapt the
 * transfer function" is on. UI thread only.
 */
#ifndef VVG_FILTER_PAGE_H
#define VVG_FILTER_PAGE_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_FILTER_PAGE (vvg_filter_page_get_type())
G_DECLARE_FINAL_TYPE(VvgFilterPage, vvg_filter_page, VVG, FILTER_PAGE, GtkBox)

/** The page for the World of @p doc (a reference is held). */
GtkWidget *vvg_filter_page_new(VvgDocument *doc);

G_END_DECLS
#endif
