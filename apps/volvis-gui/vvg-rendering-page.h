/*
 * VvRenderingPage: the Rendering page (VolVis paper, section 5): the
 * renderer of the World (every renderer of the registry), its options and
 * the quality, and Render… (the window's final render). An option is
 * checked by the renderer before it is taken (Enter applies; empty means
 * the default). Every edit is one undo step. UI thread only.
 */
#ifndef VV_RENDERING_PAGE_H
#define VV_RENDERING_PAGE_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VV_TYPE_RENDERING_PAGE (vv_rendering_page_get_type())
G_DECLARE_FINAL_TYPE(VvRenderingPage, vv_rendering_page, VV, RENDERING_PAGE, GtkBox)

/** The page for the render settings of @p doc (a reference is held). */
GtkWidget *vv_rendering_page_new(VvDocument *doc);

G_END_DECLS
#endif
