/*
 * VvWindow: the VolVis main window (the paper's Figure 3): the scene view
 * (Navigator) in the middle and a side bar with one page per component of
 * the paper: Manipulation (object list, Object Control, Navigator),
 * Rendering, Measurement and Modeling. Every command is a named action
 * ("win.open", "win.save", "win.undo", ...), so menus, shortcuts, devices
 * and tests drive the same code. UI thread only.
 */
#ifndef VV_WINDOW_H
#define VV_WINDOW_H

#include "vv-document.h"

G_BEGIN_DECLS

#define VV_TYPE_WINDOW (vv_window_get_type())
G_DECLARE_FINAL_TYPE(VvWindow, vv_window, VV, WINDOW, GtkApplicationWindow)

VvWindow *vv_window_new(GtkApplication *app);
/** Opens a file into the window's World; on failure shows an error dialog. */
void vv_window_open(VvWindow *win, const char *path);
VvDocument *vv_window_document(VvWindow *win);
/**
 * Asks before discarding unsaved changes, then calls @p done(user) when the
 * window may close (at once when there is nothing unsaved).
 */
void vv_window_confirm_close(VvWindow *win, void (*done)(void *user), void *user);

G_END_DECLS
#endif
