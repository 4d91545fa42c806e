/*
 * VvgDevicesPage: the window's "Input devices" page (docs/gui.md). It lists
 * the devices of the window's VvgDevices (kind, name, driver) with, for each,
 * the application it is assigned to (all applications, navigator, none),
 * its simulation method (direct mapping, dominant axis, snap-drag, two-hand)
 * and its sensitivity (dead zone, response exponent, gain); and it opens
 * drivers: the 3-D mouse, game controllers, a network socket, a replay of
 * a recording, and records a session. Errors are shown in a dialog with the
 * library's message.
 *
 * At start, VOLVIS_INPUT_SOCKET=PATH listens on PATH and
 * VOLVIS_INPUT_REPLAY=FILE replays FILE (for tests and scripts). UI thread only.
 */
#ifndef VVG_DEVICES_PAGE_H
#define VVG_DEVICES_PAGE_H

#include "vvg-window.h"

G_BEGIN_DECLS

#define VVG_TYPE_DEVICES_PAGE (vvg_devices_page_get_type())
G_DECLARE_FINAL_TYPE(VvgDevicesPage, vvg_devices_page, VVG, DEVICES_PAGE, GtkWidget)

/**
 * The page for @p win: creates the window's VvgDevices (owned by the window,
 * stopped when it is destroyed) driving its document.
 */
GtkWidget *vvg_devices_page_new(VvgWindow *win);

G_END_DECLS
#endif
