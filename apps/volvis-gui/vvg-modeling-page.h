/*
 * VvgModelingPage: the Modeling page (VolVis paper, section 4, Modeling): a
 * voxelized primitive (sphere, box, torus, cylinder, cone) or a mesh file,
 * of a given size, position and rotation, volume-sampled at a given
 * resolution on a worker thread with a progress bar and added as an
 * isosurface object; and the CSG union, intersection or difference of two
 * objects made on the page (their models combined and volume-sampled again,
 * the two operands hidden; one undo step). Installs the actions "voxelize"
 * and "csg" in the given action map. UI thread only.
 */
#ifndef VVG_MODELING_PAGE_H
#define VVG_MODELING_PAGE_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_MODELING_PAGE (vvg_modeling_page_get_type())
G_DECLARE_FINAL_TYPE(VvgModelingPage, vvg_modeling_page, VVG, MODELING_PAGE, GtkBox)

/** The page for @p doc (a reference is held); actions go into @p actions (borrowed). */
GtkWidget *vvg_modeling_page_new(VvgDocument *doc, GActionMap *actions);

G_END_DECLS
#endif
