/*
 * VvgApplication: the volvis-gui GtkApplication. Opens the files named on the
 * command line (volvis-gui FILE...), owns the application actions
 * ("app.quit", Ctrl+Q, asking first when there are unsaved changes) and the
 * keyboard shortcuts of every window action. UI thread only.
 */
#ifndef VVG_APPLICATION_H
#define VVG_APPLICATION_H

#include <gtk/gtk.h>

G_BEGIN_DECLS

#define VVG_TYPE_APPLICATION (vvg_application_get_type())
G_DECLARE_FINAL_TYPE(VvgApplication, vvg_application, VVG, APPLICATION, GtkApplication)

VvgApplication *vvg_application_new(void);

G_END_DECLS
#endif
