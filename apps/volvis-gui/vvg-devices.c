/* VvgDevices: input devices driving the GUI through the DUI (vvg-devices.h). */
#include "vvg-devices.h"

#include <glib-unix.h>
#include <math.h>
#include <string.h>
#include <unistd.h>

/* Full deflection of a 6-DOF device (gain 1): radians a second of orbit and
 * roll, view heights a second of pan, and e-fold zoom rate (ln 2: twice as
 * close a second). */
#define ROT_RATE (G_PI / 2)
#define PAN_RATE 0.5
#define ZOOM_RATE G_LN2
/* Seconds of quiet after which device motion starts a new undo step. */
#define BURST_GAP_US 500000
/* Longest time one integration step covers (a stalled main loop must not jump). */
#define MAX_STEP 0.1
#define TICK_MS 16
/* Device ids are 1..64 (VV_ERR_LIMIT beyond). */
#define MAX_ID 64

struct _VvgDevices {
    GObject parent;
    GtkWindow *window; /* weak */
    VvgDocument *doc;  /* a reference */
    gulong changed_id, destroy_id;
    GApplication *app; /* a reference: quitting shuts the devices down */
    gulong shutdown_id;
    vv_input_manager *m;
    guint fd_source, timeout_source, tick_source;
    char *listen_path;
    gboolean recording;
    gboolean list_dirty;
    gboolean replaying;                     /* a replay had events to feed at the last dispatch */
    gboolean dispatching, shutdown_pending; /* shut down from inside a dispatch */

    /* 6-DOF rates held per device id, and where the integration stands */
    double held[MAX_ID + 1][6];
    gint64 held_since_us;
    /* undo bursts */
    gint64 last_move_us;
    gboolean burst_open;
    gboolean emitting;
    GHashTable *warned; /* command names without an action, warned once */
};

G_DEFINE_TYPE(VvgDevices, vvg_devices, G_TYPE_OBJECT)

enum { SIGNAL_DEVICES_CHANGED, N_SIGNALS };
static guint signals[N_SIGNALS];

static gboolean
fail(GError **error, const char *fallback) {
    const char *msg = vv_error_message();
    g_set_error_literal(error, VVG_ERROR, 1, msg && *msg ? msg : fallback);
    vv_error_clear();
    return FALSE;
}

static gboolean
stopped(VvgDevices *self, GError **error) {
    if (self->m)
        return FALSE;
    g_set_error_literal(error, VVG_ERROR, 1, "the input devices are closed");
    return TRUE;
}

/* ---- applying actions to the World ---------------------------------------- */

/* Opens an undo step when device motion starts after a quiet spell or after
 * any other edit of the World. */
static void
begin_burst(VvgDevices *self, gint64 now_us) {
    if (!self->burst_open || now_us - self->last_move_us > BURST_GAP_US)
        vvg_document_begin_edit(self->doc, "device motion");
    self->burst_open = TRUE;
    self->last_move_us = now_us;
}

static void
emit_changed(VvgDevices *self) {
    self->emitting = TRUE;
    vvg_document_changed(self->doc);
    self->emitting = FALSE;
}

/* One Navigator motion of the view (vv_nav_apply). */
static void
nav_view(vv_world *w, vv_nav_motion m) {
    vv_nav_target t = {VV_NAV_TARGET_VIEW, 0, -1};
    if (vv_nav_apply(w, &t, &m) != VV_OK)
        g_debug("volvis-gui: device motion: %s", vv_error_message());
}

/* Moves the view for motion v (tx ty tz rx ry rz): rates applied over dt
 * seconds, or (dt < 0) a mouse's drag distance in units of ppu pixels. */
static void
move_view(VvgDevices *self, const double v[6], double dt, double ppu) {
    int any = 0;
    for (int i = 0; i < 6; i++)
        any |= v[i] != 0;
    if (!any)
        return;
    begin_burst(self, g_get_monotonic_time());
    vv_world *w = vvg_document_world(self->doc);
    double h = w->view.height > 0 ? w->view.height : 512;
    if (dt < 0) {
        /* the mouse's own mapping (docs/input.md) undone: dx -> ry, dy -> rx,
         * right drag (tx, -ty), middle drag and wheel tz; applied as the
         * scene view applies a drag of that many pixels */
        if (v[3] != 0 || v[4] != 0)
            nav_view(w, (vv_nav_motion){.kind = VV_NAV_ROTATE, .dx = v[4] * ppu, .dy = v[3] * ppu});
        if (v[0] != 0 || v[1] != 0)
            nav_view(w, (vv_nav_motion){.kind = VV_NAV_PAN, .dx = v[0] * ppu, .dy = -v[1] * ppu});
        if (v[2] != 0)
            nav_view(w, (vv_nav_motion){.kind = VV_NAV_ZOOM, .factor = exp(-v[2])});
    } else {
        /* a rotation drag turns 180 degrees across the view's height */
        double px_per_rad = h / G_PI;
        if (v[3] != 0 || v[4] != 0)
            nav_view(w, (vv_nav_motion){.kind = VV_NAV_ROTATE,
                                        .dx = v[4] * ROT_RATE * dt * px_per_rad,
                                        .dy = v[3] * ROT_RATE * dt * px_per_rad});
        if (v[5] != 0)
            nav_view(w, (vv_nav_motion){.kind = VV_NAV_FLY, .roll = v[5] * ROT_RATE, .dt = dt});
        if (v[0] != 0 || v[1] != 0)
            nav_view(w, (vv_nav_motion){.kind = VV_NAV_PAN,
                                        .dx = v[0] * PAN_RATE * h * dt,
                                        .dy = -v[1] * PAN_RATE * h * dt});
        if (v[2] != 0)
            nav_view(w,
                     (vv_nav_motion){.kind = VV_NAV_ZOOM, .factor = exp(-v[2] * ZOOM_RATE * dt)});
    }
    emit_changed(self);
}

static gboolean
any_held(const VvgDevices *self) {
    for (int id = 0; id <= MAX_ID; id++)
        for (int i = 0; i < 6; i++)
            if (self->held[id][i] != 0)
                return TRUE;
    return FALSE;
}

/* Applies the held rates from the last integration up to now. */
static void
integrate(VvgDevices *self) {
    gint64 now = g_get_monotonic_time();
    double dt = (now - self->held_since_us) * 1e-6;
    self->held_since_us = now;
    if (!(dt > 0))
        return;
    if (dt > MAX_STEP)
        dt = MAX_STEP;
    double v[6] = {0};
    for (int id = 0; id <= MAX_ID; id++)
        for (int i = 0; i < 6; i++)
            v[i] += self->held[id][i];
    move_view(self, v, dt, 0);
}

static gboolean
tick_cb(gpointer user) {
    VvgDevices *self = user;
    integrate(self);
    if (any_held(self))
        return G_SOURCE_CONTINUE;
    self->tick_source = 0;
    return G_SOURCE_REMOVE;
}

static void
set_held(VvgDevices *self, int id, const double v[6]) {
    if (id < 0 || id > MAX_ID)
        return;
    integrate(self); /* the previous rates up to now */
    memcpy(self->held[id], v, sizeof self->held[id]);
    if (any_held(self) && !self->tick_source)
        self->tick_source = g_timeout_add(TICK_MS, tick_cb, self);
}

/* Two-hand gesture: the scene turns with the hands (device axes taken as
 * the view's: x right, y up, z towards the viewer) and scales with their
 * distance. */
static void
two_hand(VvgDevices *self, const vv_input_action *a) {
    gboolean turn = fabs(a->rotation.w) < 1 - 1e-12;
    gboolean zoom = isfinite(a->scale) && a->scale > 0 && a->scale != 1;
    if (!turn && !zoom)
        return;
    begin_burst(self, g_get_monotonic_time());
    vv_world *w = vvg_document_world(self->doc);
    if (turn)
        nav_view(w, (vv_nav_motion){.kind = VV_NAV_TURN, .rotation = a->rotation});
    if (zoom)
        nav_view(w, (vv_nav_motion){.kind = VV_NAV_ZOOM, .factor = a->scale});
    emit_changed(self);
}

static void
command(VvgDevices *self, const char *name) {
    char action[VV_INPUT_COMMAND_MAX];
    g_strlcpy(action, name, sizeof action);
    for (char *p = action; *p; p++)
        if (*p == '.')
            *p = '-';
    GAction *a =
        self->window ? g_action_map_lookup_action(G_ACTION_MAP(self->window), action) : NULL;
    if (a && !g_action_get_parameter_type(a)) { /* a command carries no parameter */
        g_action_activate(a, NULL);
        return;
    }
    if (!g_hash_table_contains(self->warned, name)) {
        g_hash_table_add(self->warned, g_strdup(name));
        g_warning("volvis-gui: input command '%s' has no window action 'win.%s'; ignored", name,
                  action);
    }
}

/* Subscriber for application "navigator". */
static void
on_navigator(void *user, const vv_input_action *a) {
    VvgDevices *self = user;
    switch (a->kind) {
    case VV_ACTION_MOTION: {
        vv_input_device_desc d;
        int found = 0;
        for (int i = 0; i < vv_input_manager_device_count(self->m) && !found; i++)
            found = vv_input_manager_device_get(self->m, i, &d) == VV_OK && d.id == a->device;
        if (found && d.kind == VV_INPUT_MOUSE) {
            double ppu = d.info && d.info->pixels_per_unit > 0 ? d.info->pixels_per_unit : 200;
            move_view(self, a->motion, -1, ppu);
        } else {
            set_held(self, a->device, a->motion);
        }
        break;
    }
    case VV_ACTION_COMMAND:
        command(self, a->command);
        break;
    case VV_ACTION_TWO_HAND:
        two_hand(self, a);
        break;
    default:
        break;
    }
}

/* Subscriber for every application: the device list. */
static void
on_any(void *user, const vv_input_action *a) {
    VvgDevices *self = user;
    if (a->kind == VV_ACTION_DEVICE_REMOVED) {
        static const double zero[6] = {0};
        set_held(self, a->device, zero);
    }
    if (a->kind == VV_ACTION_DEVICE_ADDED || a->kind == VV_ACTION_DEVICE_REMOVED)
        self->list_dirty = TRUE;
}

static void
flush_list(VvgDevices *self) {
    if (!self->list_dirty)
        return;
    self->list_dirty = FALSE;
    g_signal_emit(self, signals[SIGNAL_DEVICES_CHANGED], 0);
}

/* ---- the main loop ------------------------------------------------------------ */

static gboolean timeout_cb(gpointer user);

/* The manager's next deadline as a GLib timeout (none: only its descriptor). */
static void
rearm(VvgDevices *self) {
    if (self->timeout_source) {
        g_source_remove(self->timeout_source);
        self->timeout_source = 0;
    }
    if (!self->m)
        return;
    double t = vv_input_manager_timeout(self->m, vv_input_now());
    if (t < 0)
        return;
    double ms = ceil(t * 1000);
    guint delay = ms > 0 ? (ms < 60000 ? (guint)ms : 60000u) : 0u;
    self->timeout_source = g_timeout_add(delay, timeout_cb, self);
}

static void
dispatch(VvgDevices *self) {
    if (!self->m)
        return;
    g_object_ref(self);
    self->dispatching = TRUE;
    vv_input_manager_dispatch(self->m, vv_input_now());
    self->dispatching = FALSE;
    if (self->shutdown_pending)
        vvg_devices_shutdown(self);
    if (self->m && self->replaying && !vv_input_manager_replay_pending(self->m))
        self->list_dirty = TRUE; /* the page's status: the replay is over */
    self->replaying = self->m && vv_input_manager_replay_pending(self->m);
    rearm(self);
    flush_list(self);
    g_object_unref(self);
}

static gboolean
timeout_cb(gpointer user) {
    VvgDevices *self = user;
    self->timeout_source = 0;
    dispatch(self);
    return G_SOURCE_REMOVE;
}

static gboolean
fd_cb(int fd, GIOCondition cond, gpointer user) {
    (void)fd;
    (void)cond;
    dispatch(user);
    return G_SOURCE_CONTINUE;
}

/* ---- life cycle ------------------------------------------------------------------- */

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgDevices *self = user;
    /* an edit not ours (undo, a drag, a command) ends the motion's undo step */
    if (!self->emitting)
        self->burst_open = FALSE;
}

static void
window_destroyed(GtkWidget *w, gpointer user) {
    (void)w;
    vvg_devices_shutdown(user);
}

/* Quitting does not destroy the windows: shut down here too, so that a
 * recording is written and the socket file removed. */
static void
app_shutdown(GApplication *app, gpointer user) {
    (void)app;
    vvg_devices_shutdown(user);
}

void
vvg_devices_shutdown(VvgDevices *self) {
    if (self->dispatching) { /* the manager is in use: free it when dispatch returns */
        self->shutdown_pending = TRUE;
        return;
    }
    self->shutdown_pending = FALSE;
    g_clear_handle_id(&self->fd_source, g_source_remove);
    g_clear_handle_id(&self->timeout_source, g_source_remove);
    g_clear_handle_id(&self->tick_source, g_source_remove);
    memset(self->held, 0, sizeof self->held);
    if (self->m) {
        /* frees every driver: a recording is written, the socket removed */
        vv_input_manager_free(self->m);
        self->m = NULL;
        self->recording = FALSE;
    }
    if (self->window) {
        if (self->destroy_id)
            g_signal_handler_disconnect(self->window, self->destroy_id);
        self->destroy_id = 0;
        g_object_remove_weak_pointer(G_OBJECT(self->window), (gpointer *)&self->window);
        self->window = NULL;
    }
    if (self->doc) {
        g_signal_handler_disconnect(self->doc, self->changed_id);
        g_clear_object(&self->doc);
    }
    if (self->app) {
        g_signal_handler_disconnect(self->app, self->shutdown_id);
        g_clear_object(&self->app);
    }
}

static void
vvg_devices_dispose(GObject *o) {
    vvg_devices_shutdown(VVG_DEVICES(o));
    G_OBJECT_CLASS(vvg_devices_parent_class)->dispose(o);
}

static void
vvg_devices_finalize(GObject *o) {
    VvgDevices *self = VVG_DEVICES(o);
    g_free(self->listen_path);
    g_hash_table_destroy(self->warned);
    G_OBJECT_CLASS(vvg_devices_parent_class)->finalize(o);
}

static void
vvg_devices_class_init(VvgDevicesClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_devices_dispose;
    G_OBJECT_CLASS(klass)->finalize = vvg_devices_finalize;
    /* devices were added or removed (the list to show changed) */
    signals[SIGNAL_DEVICES_CHANGED] =
        g_signal_new("devices-changed", G_TYPE_FROM_CLASS(klass), G_SIGNAL_RUN_LAST, 0, NULL, NULL,
                     NULL, G_TYPE_NONE, 0);
}

static void
vvg_devices_init(VvgDevices *self) {
    self->warned = g_hash_table_new_full(g_str_hash, g_str_equal, g_free, NULL);
    self->held_since_us = g_get_monotonic_time();
}

VvgDevices *
vvg_devices_new(GtkWindow *window, VvgDocument *doc, GError **error) {
    VvgDevices *self = g_object_new(VVG_TYPE_DEVICES, NULL);
    if (vv_input_manager_new(&self->m, NULL) != VV_OK ||
        vv_input_manager_subscribe(self->m, "navigator", on_navigator, self, NULL) != VV_OK ||
        vv_input_manager_subscribe(self->m, NULL, on_any, self, NULL) != VV_OK) {
        fail(error, "cannot create the input manager");
        g_object_unref(self);
        return NULL;
    }
    self->window = window;
    g_object_add_weak_pointer(G_OBJECT(window), (gpointer *)&self->window);
    self->destroy_id = g_signal_connect(window, "destroy", G_CALLBACK(window_destroyed), self);
    self->doc = g_object_ref(doc);
    self->changed_id = g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    GApplication *app = g_application_get_default();
    if (app) {
        self->app = g_object_ref(app);
        self->shutdown_id = g_signal_connect(app, "shutdown", G_CALLBACK(app_shutdown), self);
    }
    self->fd_source = g_unix_fd_add(vv_input_manager_fd(self->m), G_IO_IN, fd_cb, self);
    rearm(self);
    return self;
}

vv_input_manager *
vvg_devices_manager(VvgDevices *self) {
    return self->m;
}

/* After a call that may add devices or change the manager's deadlines. */
static gboolean
after_call(VvgDevices *self, vv_status s, GError **error, const char *fallback) {
    self->replaying = vv_input_manager_replay_pending(self->m);
    rearm(self);
    self->list_dirty = TRUE;
    flush_list(self);
    return s == VV_OK ? TRUE : fail(error, fallback);
}

gboolean
vvg_devices_open_spacenav(VvgDevices *self, GError **error) {
    if (stopped(self, error))
        return FALSE;
    return after_call(self, vv_input_manager_open_spacenav(self->m, NULL), error,
                      "no 3-D mouse (spacenavd)");
}

gboolean
vvg_devices_open_controllers(VvgDevices *self, GError **error) {
    if (stopped(self, error))
        return FALSE;
    return after_call(self, vv_input_manager_open_controllers(self->m), error,
                      "no game-controller driver");
}

gboolean
vvg_devices_listen(VvgDevices *self, const char *path, GError **error) {
    if (stopped(self, error))
        return FALSE;
    vv_status s = vv_input_manager_listen(self->m, path);
    if (s == VV_OK) {
        g_free(self->listen_path);
        self->listen_path = g_strdup(path);
    }
    return after_call(self, s, error, "cannot listen");
}

const char *
vvg_devices_listen_path(VvgDevices *self) {
    return self->listen_path;
}

gboolean
vvg_devices_replay(VvgDevices *self, const char *path, GError **error) {
    if (stopped(self, error))
        return FALSE;
    return after_call(self,
                      vv_input_manager_open_replay(self->m, path, vv_input_now(), 1.0, NULL, NULL),
                      error, "cannot replay");
}

gboolean
vvg_devices_record_start(VvgDevices *self, const char *path, GError **error) {
    if (stopped(self, error))
        return FALSE;
    if (vv_input_manager_record_start(self->m, path) != VV_OK)
        return fail(error, "cannot record");
    self->recording = TRUE;
    return TRUE;
}

gboolean
vvg_devices_record_stop(VvgDevices *self, GError **error) {
    if (stopped(self, error))
        return FALSE;
    self->recording = FALSE;
    if (vv_input_manager_record_stop(self->m) != VV_OK)
        return fail(error, "cannot write the recording");
    return TRUE;
}

gboolean
vvg_devices_recording(VvgDevices *self) {
    return self->recording;
}

gboolean
vvg_devices_assign(VvgDevices *self, int id, const char *app, GError **error) {
    if (stopped(self, error))
        return FALSE;
    if (vv_input_manager_assign(self->m, id, app) != VV_OK)
        return fail(error, "cannot assign the device");
    /* a device no longer ours stops moving the view */
    if (id >= 0 && id <= MAX_ID && app && *app && strcmp(app, "navigator") != 0) {
        static const double zero[6] = {0};
        set_held(self, id, zero);
    }
    return TRUE;
}

gboolean
vvg_devices_set_method(VvgDevices *self, int id, const vv_input_method *method, GError **error) {
    if (stopped(self, error))
        return FALSE;
    if (vv_input_manager_set_method(self->m, id, method) != VV_OK)
        return fail(error, "cannot set the simulation method");
    return TRUE;
}

gboolean
vvg_devices_pair(VvgDevices *self, int id, int *partner, GError **error) {
    if (stopped(self, error))
        return FALSE;
    vv_input_device_desc me, d;
    int n = vv_input_manager_device_count(self->m), have_me = 0;
    for (int i = 0; i < n && !have_me; i++)
        have_me = vv_input_manager_device_get(self->m, i, &me) == VV_OK && me.id == id;
    if (!have_me) {
        g_set_error(error, VVG_ERROR, 1, "no device %d", id);
        return FALSE;
    }
    int best = -1;
    for (int pass = 0; pass < 2 && best < 0; pass++)
        for (int i = 0; i < n && best < 0; i++)
            if (vv_input_manager_device_get(self->m, i, &d) == VV_OK && d.id != id && d.present &&
                strcmp(d.driver, "gui") != 0 && (pass == 1 || d.kind == me.kind))
                best = d.id;
    if (best < 0) {
        g_set_error(error, VVG_ERROR, 1,
                    "two-hand gestures need a second device to pair %s with (a replayed or "
                    "network data glove, for instance)",
                    me.name);
        return FALSE;
    }
    if (vv_input_manager_pair(self->m, id, best) != VV_OK)
        return fail(error, "cannot pair the devices");
    if (partner)
        *partner = best;
    return TRUE;
}

char *
vvg_devices_default_socket_path(void) {
    const char *run = g_getenv("XDG_RUNTIME_DIR");
    if (run && *run && g_file_test(run, G_FILE_TEST_IS_DIR))
        return g_build_filename(run, "volvis-input.sock", NULL);
    return g_strdup_printf("/tmp/volvis-input-%u.sock", (unsigned)getuid());
}
