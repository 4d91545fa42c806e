/*
 * VvgRenderingPage: the Rendering page (VolVis paper, section 5): the
 * renderer of the World (every renderer of the registry), its options and
 * the quality, and Render… (the window's final render). An option is
 * checked by the renderer before it is taken (Enter applies; empty means
 * the default). Every edit is one undo step. UI thread only.
 */
#ifndef VVG_RENDERING_PAGE_H
#define VVG_RENDERING_PAGE_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_RENDERING_PAGE (vvg_rendering_page_get_type())
G_DECLARE_FINAL_TYPE(VvgRenderingPage, vvg_rendering_page, VVG, RENDERING_PAGE, GtkBox)

/** The page for the render settings of @p doc (a reference is held). */
GtkWidget *vvg_rendering_page_new(VvgDocument *doc);

G_END_DECLS
#endif
