/*
 * VvImageWindow: a final render in its own window (the Rendering page's
 * Render button). The render runs on a worker thread on a snapshot of the
 * World with the World's renderer, options and quality (exactly what
 * `volvis render` of the saved session does), with a progress bar, the time
 * left, Cancel, and Save as PNG. Closing the window cancels the render.
 * UI thread only.
 */
#ifndef VV_IMAGE_WINDOW_H
#define VV_IMAGE_WINDOW_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VV_TYPE_IMAGE_WINDOW (vv_image_window_get_type())
G_DECLARE_FINAL_TYPE(VvImageWindow, vv_image_window, VV, IMAGE_WINDOW, GtkWindow)

/** Starts rendering @p world (taken: the window frees it) in a new window. */
VvImageWindow *vv_image_window_new(GtkWindow *parent, vv_world *world);
/** Writes the finished image as PNG (RGB, gamma 1, as `volvis render`). */
gboolean vv_image_window_save(VvImageWindow *win, const char *path, GError **error);

G_END_DECLS
#endif
