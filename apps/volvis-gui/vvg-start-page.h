/*
 * VvgStartPage: what the view area shows while the World is empty: "Open a
 * file…", "Import raw…" and "Browse DICOM…" buttons (the window's actions)
 * and the files opened recently (GtkRecentManager entries of this
 * application), each a button that opens it ("win.open-file"). UI thread only.
 */
#ifndef VVG_START_PAGE_H
#define VVG_START_PAGE_H

#include <gtk/gtk.h>

G_BEGIN_DECLS

#define VVG_TYPE_START_PAGE (vvg_start_page_get_type())
G_DECLARE_FINAL_TYPE(VvgStartPage, vvg_start_page, VVG, START_PAGE, GtkBox)

GtkWidget *vvg_start_page_new(void);
/** Reads the recent files again (after a file was opened). */
void vvg_start_page_refresh(VvgStartPage *page);
/** Records @p path as opened by this application (for this page's list). */
void vvg_start_page_add_recent(const char *path);

G_END_DECLS
#endif
