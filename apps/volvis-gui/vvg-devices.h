/*
 * VvgDevices: the GUI's side of the Device Unified Interface (include/volvis/input.h,
 * docs/input.md). It owns a vv_input_manager, watches its one descriptor in
 * the GLib main loop (g_unix_fd_add) and re-arms a timeout from
 * vv_input_manager_timeout after each dispatch, so an idle GUI sleeps. It
 * subscribes as application "navigator" and turns actions into edits of the
 * document's World:
 *
 *  - VV_ACTION_MOTION moves the view with the Navigator maths
 *    (include/volvis/navigator.h): rx, ry orbit the view about its look-at
 *    point (vv_nav_view_rotate), rz rolls it (vv_nav_view_fly), tx, ty pan
 *    (vv_nav_view_pan) and tz zooms (vv_nav_view_zoom; -tz is forward, moving
 *    closer). For 6-DOF devices the values are rates: each device's latest
 *    motion is held and integrated over the time it stays in effect, so a
 *    3-D mouse or a stick held still keeps turning the view (full deflection:
 *    90 degrees, half the view height of pan, or a zoom by 2 a second). A
 *    mouse's motion is a drag distance (1 = pixels_per_unit pixels) and is
 *    applied once, as the scene view applies a drag. A burst of motion
 *    (motion after more than 0.5 s of quiet, or after any other edit) is one
 *    undo step.
 *  - VV_ACTION_COMMAND "a.b" activates the window action "win.a-b" when the
 *    window has one (e.g. "view.reset" -> "win.view-reset"); other commands
 *    give one warning each.
 *  - VV_ACTION_TWO_HAND: its rotation turns the view about the look-at
 *    point, its scale zooms.
 *  - devices added or removed emit "devices-changed".
 *
 * UI thread only. The keyboard and mouse devices the manager always has are
 * not fed: the scene view handles its own input (docs/gui.md).
 */
#ifndef VVG_DEVICES_H
#define VVG_DEVICES_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_DEVICES (vvg_devices_get_type())
G_DECLARE_FINAL_TYPE(VvgDevices, vvg_devices, VVG, DEVICES, GObject)

/**
 * A manager with the information base of the default search (installed
 * share/volvis/devices, ~/.config/volvis/devices, $VOLVIS_DEVICE_DIR) whose
 * devices drive @p doc; commands activate the actions of @p window. Both are
 * borrowed: the window owns the result, and it stops (closes every driver,
 * writes a recording in progress) when the window is destroyed or
 * vvg_devices_shutdown is called. NULL with @p error set when the manager
 * cannot be created.
 */
VvgDevices *vvg_devices_new(GtkWindow *window, VvgDocument *doc, GError **error);
/** Closes every driver and stops (idempotent); later calls fail or do nothing. */
void vvg_devices_shutdown(VvgDevices *self);
/** The manager (borrowed), or NULL after shutdown. */
vv_input_manager *vvg_devices_manager(VvgDevices *self);

/** The 3-D mouse through spacenavd. */
gboolean vvg_devices_open_spacenav(VvgDevices *self, GError **error);
/** SDL2 game controllers (attached now or later). */
gboolean vvg_devices_open_controllers(VvgDevices *self, GError **error);
/** Listens on a Unix-domain socket for the network protocol (docs/input.md). */
gboolean vvg_devices_listen(VvgDevices *self, const char *path, GError **error);
/** The socket path listened on, or NULL. */
const char *vvg_devices_listen_path(VvgDevices *self);
/** Replays a recording at real speed, starting now. */
gboolean vvg_devices_replay(VvgDevices *self, const char *path, GError **error);
/** Starts recording every raw event to @p path (written when recording stops). */
gboolean vvg_devices_record_start(VvgDevices *self, const char *path, GError **error);
gboolean vvg_devices_record_stop(VvgDevices *self, GError **error);
gboolean vvg_devices_recording(VvgDevices *self);
/** vv_input_manager_assign: @p app "" means every application. */
gboolean vvg_devices_assign(VvgDevices *self, int id, const char *app, GError **error);
/** vv_input_manager_set_method. */
gboolean vvg_devices_set_method(VvgDevices *self, int id, const vv_input_method *method,
                                GError **error);
/**
 * Pairs device @p id for two-hand gestures with another present device
 * (one of the same kind first); *partner receives its id.
 */
gboolean vvg_devices_pair(VvgDevices *self, int id, int *partner, GError **error);

/** $XDG_RUNTIME_DIR/volvis-input.sock, else /tmp/volvis-input-UID.sock (g_free). */
char *vvg_devices_default_socket_path(void);

G_END_DECLS
#endif
