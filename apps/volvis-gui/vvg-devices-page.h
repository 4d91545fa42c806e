/*
 * VvDevicesPage: the window's "Input devices" page (docs/gui.md). It lists
 * the devices of the window's VvDevices (kind, name, driver) with, for each,
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
#ifndef VV_DEVICES_PAGE_H
#define VV_DEVICES_PAGE_H

#include "vvg-window.h"

G_BEGIN_DECLS

#define VV_TYPE_DEVICES_PAGE (vv_devices_page_get_type())
G_DECLARE_FINAL_TYPE(VvDevicesPage, vv_devices_page, VV, DEVICES_PAGE, GtkWidget)

/**
 * The page for @p win: creates the window's VvDevices (owned by the window,
 * stopped when it is destroyed) driving its document.
 */
GtkWidget *vv_devices_page_new(VvWindow *win);

G_END_DECLS
#endif
