/*
 * VvApplication: the volvis-gui GtkApplication. Opens the files named on the
 * command line (volvis-gui FILE...), owns the application actions
 * ("app.quit", Ctrl+Q, asking first when there are unsaved changes) and the
 * keyboard shortcuts of every window action. UI thread only.
 */
#ifndef VV_APPLICATION_H
#define VV_APPLICATION_H

#include <gtk/gtk.h>

G_BEGIN_DECLS

#define VV_TYPE_APPLICATION (vv_application_get_type())
G_DECLARE_FINAL_TYPE(VvApplication, vv_application, VV, APPLICATION, GtkApplication)

VvApplication *vv_application_new(void);

G_END_DECLS
#endif
