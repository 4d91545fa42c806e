/*
 * VvgImageWindow: a final render in its own window (the Rendering page's
 * Render button). The render runs on a worker thread on a snapshot of the
 * World with the World's renderer, options and quality (exactly what
 * `volvis render` of the saved session does), with a progress bar, the time
 * left, Cancel, and Save as PNG. Closing the window cancels the render.
 * UI thread only.
 */
#ifndef VVG_IMAGE_WINDOW_H
#define VVG_IMAGE_WINDOW_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_IMAGE_WINDOW (vvg_image_window_get_type())
G_DECLARE_FINAL_TYPE(VvgImageWindow, vvg_image_window, VVG, IMAGE_WINDOW, GtkWindow)

/** Starts rendering @p world (taken: the window frees it) in a new window. */
VvgImageWindow *vvg_image_window_new(GtkWindow *parent, vv_world *world);
/** Writes the finished image as PNG (RGB, gamma 1, as `volvis render`). */
gboolean vvg_image_window_save(VvgImageWindow *win, const char *path, GError **error);

G_END_DECLS
#endif
