/*
 * VvgWindow: the VolVis main window (the paper's Figure 3): a header bar
 * (Open, Save, Undo, Redo, the layout, the application menu), the view area
 * (the 3-D scene view of the Navigator that fills it, alone or beside three
 * slice views; a start page while the World is empty) and a side bar with a
 * page per component: Objects, Transfer function, View, Lights, Cut planes,
 * Rendering, Measurement, Modeling, Filtering, Animator, Input devices. Every command is a named
 * action
 * ("win.open", "win.save", "win.undo", ...), so menus, shortcuts, devices
 * and tests drive the same code. UI thread only.
 */
#ifndef VVG_WINDOW_H
#define VVG_WINDOW_H

#include "vvg-document.h"
#include "vvg-scene-view.h"

G_BEGIN_DECLS

#define VVG_TYPE_WINDOW (vvg_window_get_type())
G_DECLARE_FINAL_TYPE(VvgWindow, vvg_window, VVG, WINDOW, GtkApplicationWindow)

VvgWindow *vvg_window_new(GtkApplication *app);
/** Opens a file (or a URL) into the window's World on the UI thread, blocking until the
 *  door returns; on failure shows an error dialog. File > Open URL… opens on a worker
 *  thread instead (vvg-window.c, open_async). UI thread. */
void vvg_window_open(VvgWindow *win, const char *path);
/**
 * Save volume as… without the chooser: writes the selected volume object
 * (else the first volume) to @p path in the format of its extension, on a
 * worker thread, atomically; errors and what the format could not hold
 * are shown in dialogs.
 */
void vvg_window_save_volume(VvgWindow *win, const char *path);
/**
 * Offers to restore the newest autosave whose process is gone (a crash or
 * a kill): a dialog "Restore the last session?" with Restore (the World as
 * it was, untitled, unsaved) and Discard (the folders removed). Nothing
 * when there is none. Called once at start.
 */
void vvg_window_offer_restore(VvgWindow *win);
VvgDocument *vvg_window_document(VvgWindow *win);
/** The window's 3-D view (owned by the window). */
VvgSceneView *vvg_window_scene_view(VvgWindow *win);
/**
 * Asks before unsaved changes are lost (Save, Close without saving,
 * Cancel), then calls @p done(user) when the window may close: at once when
 * there is nothing unsaved, after a successful save with Save.
 */
void vvg_window_confirm_close(VvgWindow *win, void (*done)(void *user), void *user);

G_END_DECLS
#endif
