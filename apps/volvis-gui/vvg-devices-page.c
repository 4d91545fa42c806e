/* VvgDevicesPage: the "Input devices" page (vvg-devices-page.h). */
#define _DEFAULT_SOURCE /* S_ISSOCK */
#include "vvg-devices-page.h"
#include "vvg-widgets.h"

#include <errno.h>
#include <string.h>
#include <sys/stat.h>

#include "vvg-devices.h"

struct _VvgDevicesPage {
    GtkWidget parent;
    VvgDevices *devices; /* a reference; the window owns it too */
    gulong changed_id;
    GtkWidget *scroll;
    GtkWidget *list;
    GtkWidget *status;
    GtkWidget *socket_entry, *replay_entry, *record_entry, *record_button, *auto_start;
    guint rebuild_idle, start_idle, auto_source;
};

G_DEFINE_TYPE(VvgDevicesPage, vvg_devices_page, GTK_TYPE_WIDGET)

/* The application choices; "" is every application (unassigned). */
static const char *const app_names[] = {"all applications", "navigator", "none", NULL};
static const char *const app_values[] = {"", "navigator", "none"};

/* The method choices, as the API offers them. */
enum { M_DIRECT, M_DOMINANT, M_SNAP, M_TWO_HAND };
static const char *const method_names[] = {"direct mapping", "dominant axis", "snap-drag",
                                           "two-hand", NULL};

/* ---- helpers ------------------------------------------------------------------ */

/* A dialog with the library's message; also on stderr, for scripts and tests. */
static void
show_error(VvgDevicesPage *self, const char *what, const char *message) {
    vvg_show_error(GTK_WIDGET(self), what, message);
}

/* Shows *err (cleared) under @p what when @p ok is FALSE; returns ok. A
 * pointer, not the GError itself: arguments are evaluated in any order. */
static gboolean
check(VvgDevicesPage *self, gboolean ok, GError **err, const char *what) {
    if (!ok)
        show_error(self, what, *err ? (*err)->message : "unknown error");
    g_clear_error(err);
    return ok;
}

static GtkWidget *
heading(GtkWidget *box, const char *title) {
    GtkWidget *l = gtk_label_new(NULL);
    char *m = g_markup_printf_escaped("<b>%s</b>", title);
    gtk_label_set_markup(GTK_LABEL(l), m);
    g_free(m);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_widget_set_margin_top(l, 8);
    gtk_box_append(GTK_BOX(box), l);
    return l;
}

static GtkWidget *
hbox(GtkWidget *parent) {
    GtkWidget *b = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(parent), b);
    return b;
}

static GtkWidget *
dim_label(const char *text) {
    GtkWidget *l = gtk_label_new(text);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_label_set_wrap(GTK_LABEL(l), TRUE);
    gtk_widget_add_css_class(l, "dim-label");
    return l;
}

static int
device_id(gpointer widget) {
    return GPOINTER_TO_INT(g_object_get_data(G_OBJECT(widget), "device-id"));
}

static void
update_status(VvgDevicesPage *self) {
    GString *s = g_string_new(NULL);
    const char *sock = vvg_devices_listen_path(self->devices);
    if (sock)
        g_string_append_printf(s, "listening on %s", sock);
    if (vvg_devices_recording(self->devices))
        g_string_append_printf(s, "%srecording to %s", s->len ? "; " : "",
                               gtk_editable_get_text(GTK_EDITABLE(self->record_entry)));
    vv_input_manager *m = vvg_devices_manager(self->devices);
    if (m && vv_input_manager_replay_pending(m))
        g_string_append_printf(s, "%sreplaying", s->len ? "; " : "");
    gtk_label_set_text(GTK_LABEL(self->status), s->str);
    g_string_free(s, TRUE);
    gtk_button_set_label(GTK_BUTTON(self->record_button),
                         vvg_devices_recording(self->devices) ? "Stop" : "Record");
}

/* ---- the device list ------------------------------------------------------------ */

static void rebuild(VvgDevicesPage *self);

static gboolean
rebuild_idle_cb(gpointer user) {
    VvgDevicesPage *self = user;
    self->rebuild_idle = 0;
    rebuild(self);
    return G_SOURCE_REMOVE;
}

/* Later: never destroy the widget whose signal is being handled. */
static void
queue_rebuild(VvgDevicesPage *self) {
    if (!self->rebuild_idle)
        self->rebuild_idle = g_idle_add(rebuild_idle_cb, self);
}

static void
app_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvgDevicesPage *self = user;
    guint i = gtk_drop_down_get_selected(GTK_DROP_DOWN(o));
    if (i >= G_N_ELEMENTS(app_values))
        return;
    GError *err = NULL;
    check(self, vvg_devices_assign(self->devices, device_id(o), app_values[i], &err), &err,
          "Cannot assign the device");
}

/* The method of device @p id as the page shows it. */
static gboolean
get_method(VvgDevicesPage *self, int id, vv_input_method *mt) {
    vv_input_manager *m = vvg_devices_manager(self->devices);
    return m && vv_input_manager_get_method(m, id, mt) == VV_OK;
}

/* A device leaving two-hand mode takes its partner out of it too. */
static void
unpair(VvgDevicesPage *self, int id, const vv_input_method *old) {
    vv_input_method pm;
    if (old->kind != VV_METHOD_TWO_HAND || !get_method(self, old->partner, &pm) ||
        pm.kind != VV_METHOD_TWO_HAND || pm.partner != id)
        return;
    pm.kind = VV_METHOD_DIRECT;
    GError *err = NULL;
    check(self, vvg_devices_set_method(self->devices, old->partner, &pm, &err), &err,
          "Cannot change the partner's simulation method");
}

static void
method_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvgDevicesPage *self = user;
    int id = device_id(o);
    vv_input_method mt, old;
    if (!get_method(self, id, &mt))
        return;
    old = mt;
    GError *err = NULL;
    switch (gtk_drop_down_get_selected(GTK_DROP_DOWN(o))) {
    case M_DIRECT:
    case M_DOMINANT:
        mt.kind = VV_METHOD_DIRECT;
        mt.dominant_axis = gtk_drop_down_get_selected(GTK_DROP_DOWN(o)) == M_DOMINANT;
        break;
    case M_SNAP:
        mt.kind = VV_METHOD_SNAP_DRAG;
        break;
    case M_TWO_HAND:
        if (old.kind != VV_METHOD_TWO_HAND)
            check(self, vvg_devices_pair(self->devices, id, NULL, &err), &err,
                  "Cannot use two-hand gestures");
        queue_rebuild(self); /* the partner's row, or back to what it was */
        return;
    default:
        return;
    }
    unpair(self, id, &old);
    check(self, vvg_devices_set_method(self->devices, id, &mt, &err), &err,
          "Cannot set the simulation method");
    if (old.kind == VV_METHOD_TWO_HAND)
        queue_rebuild(self);
}

static void
sensitivity_changed(GtkSpinButton *s, gpointer user) {
    VvgDevicesPage *self = user;
    int id = device_id(s);
    vv_input_method mt;
    if (!get_method(self, id, &mt))
        return;
    const char *field = g_object_get_data(G_OBJECT(s), "field");
    double v = gtk_spin_button_get_value(s);
    if (!strcmp(field, "dead_zone"))
        mt.dead_zone = v;
    else if (!strcmp(field, "exponent"))
        mt.exponent = v;
    else
        mt.gain = v;
    GError *err = NULL;
    check(self, vvg_devices_set_method(self->devices, id, &mt, &err), &err,
          "Cannot set the sensitivity");
}

static GtkWidget *
grid_row(GtkWidget *grid, int r, const char *label, GtkWidget *w) {
    GtkWidget *l = gtk_label_new(label);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_grid_attach(GTK_GRID(grid), l, 0, r, 1, 1);
    gtk_widget_set_hexpand(w, TRUE);
    gtk_grid_attach(GTK_GRID(grid), w, 1, r, 1, 1);
    return w;
}

static GtkWidget *
sensitivity_spin(VvgDevicesPage *self, int id, const char *field, double lo, double hi, double step,
                 int digits, double value) {
    GtkWidget *s = gtk_spin_button_new_with_range(lo, hi, step);
    gtk_spin_button_set_digits(GTK_SPIN_BUTTON(s), (guint)digits);
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(s), value);
    g_object_set_data(G_OBJECT(s), "device-id", GINT_TO_POINTER(id));
    g_object_set_data(G_OBJECT(s), "field", (gpointer)field);
    g_signal_connect(s, "value-changed", G_CALLBACK(sensitivity_changed), self);
    return s;
}

static GtkWidget *
device_row(VvgDevicesPage *self, const vv_input_device_desc *d) {
    GtkWidget *box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 2);
    gtk_widget_set_margin_top(box, 4);
    gtk_widget_set_margin_bottom(box, 4);
    GtkWidget *title = gtk_label_new(NULL);
    char *m = g_markup_printf_escaped("<b>%s</b>  %s <small>(%s)</small>",
                                      vv_input_kind_name(d->kind), d->name, d->driver);
    gtk_label_set_markup(GTK_LABEL(title), m);
    g_free(m);
    gtk_label_set_xalign(GTK_LABEL(title), 0);
    gtk_label_set_ellipsize(GTK_LABEL(title), PANGO_ELLIPSIZE_END);
    gtk_box_append(GTK_BOX(box), title);
    if (!strcmp(d->driver, "gui")) {
        /* the manager always has them; the scene view handles this input itself */
        gtk_box_append(GTK_BOX(box), dim_label("the scene view's own (see Navigating)"));
        return box;
    }
    vv_input_method mt;
    if (!get_method(self, d->id, &mt))
        return box;
    GtkWidget *g = gtk_grid_new();
    gtk_grid_set_row_spacing(GTK_GRID(g), 2);
    gtk_grid_set_column_spacing(GTK_GRID(g), 6);
    gtk_box_append(GTK_BOX(box), g);

    GtkStringList *apps = gtk_string_list_new(app_names);
    guint app = 2;
    for (guint i = 0; i < G_N_ELEMENTS(app_values); i++)
        if (!strcmp(d->app, app_values[i]))
            app = i;
    if (app == 2 && strcmp(d->app, "none") != 0) { /* assigned elsewhere (another tool) */
        gtk_string_list_append(apps, d->app);
        app = 3;
    }
    GtkWidget *ad = gtk_drop_down_new(G_LIST_MODEL(apps), NULL);
    gtk_drop_down_set_selected(GTK_DROP_DOWN(ad), app);
    g_object_set_data(G_OBJECT(ad), "device-id", GINT_TO_POINTER(d->id));
    g_signal_connect(ad, "notify::selected", G_CALLBACK(app_changed), self);
    grid_row(g, 0, "application", ad);

    guint meth = mt.kind == VV_METHOD_SNAP_DRAG  ? M_SNAP
                 : mt.kind == VV_METHOD_TWO_HAND ? M_TWO_HAND
                 : mt.dominant_axis              ? M_DOMINANT
                                                 : M_DIRECT;
    GtkWidget *md = gtk_drop_down_new_from_strings(method_names);
    gtk_drop_down_set_selected(GTK_DROP_DOWN(md), meth);
    g_object_set_data(G_OBJECT(md), "device-id", GINT_TO_POINTER(d->id));
    g_signal_connect(md, "notify::selected", G_CALLBACK(method_changed), self);
    grid_row(g, 1, "method", md);

    grid_row(g, 2, "dead zone",
             sensitivity_spin(self, d->id, "dead_zone", 0, 0.95, 0.01, 2, mt.dead_zone));
    grid_row(g, 3, "response exponent",
             sensitivity_spin(self, d->id, "exponent", 1, 10, 0.5, 1, mt.exponent));
    grid_row(g, 4, "gain", sensitivity_spin(self, d->id, "gain", 0.05, 20, 0.05, 2, mt.gain));
    if (mt.kind == VV_METHOD_TWO_HAND) {
        char *t = g_strdup_printf("paired with device %d", mt.partner);
        gtk_grid_attach(GTK_GRID(g), dim_label(t), 0, 5, 2, 1);
        g_free(t);
    }
    return box;
}

static void
rebuild(VvgDevicesPage *self) {
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(self->list)))
        gtk_list_box_remove(GTK_LIST_BOX(self->list), c);
    vv_input_manager *m = vvg_devices_manager(self->devices);
    int n = m ? vv_input_manager_device_count(m) : 0;
    for (int i = 0; i < n; i++) {
        vv_input_device_desc d;
        if (vv_input_manager_device_get(m, i, &d) == VV_OK && d.present)
            gtk_list_box_append(GTK_LIST_BOX(self->list), device_row(self, &d));
    }
    update_status(self);
}

static void
devices_changed(VvgDevices *devices, gpointer user) {
    (void)devices;
    queue_rebuild(user);
}

/* ---- drivers ------------------------------------------------------------------------ */

static void
spacenav_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgDevicesPage *self = user;
    GError *err = NULL;
    check(self, vvg_devices_open_spacenav(self->devices, &err), &err, "No 3-D mouse");
}

static void
controllers_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgDevicesPage *self = user;
    GError *err = NULL;
    check(self, vvg_devices_open_controllers(self->devices, &err), &err,
          "Cannot open game controllers");
}

static void
listen_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgDevicesPage *self = user;
    GError *err = NULL;
    const char *path = gtk_editable_get_text(GTK_EDITABLE(self->socket_entry));
    check(self, vvg_devices_listen(self->devices, path, &err), &err, "Cannot listen");
    update_status(self);
}

static void
replay_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgDevicesPage *self = user;
    GError *err = NULL;
    const char *path = gtk_editable_get_text(GTK_EDITABLE(self->replay_entry));
    check(self, vvg_devices_replay(self->devices, path, &err), &err, "Cannot replay the recording");
    update_status(self);
}

static void
record_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgDevicesPage *self = user;
    GError *err = NULL;
    if (vvg_devices_recording(self->devices))
        check(self, vvg_devices_record_stop(self->devices, &err), &err,
              "Cannot write the recording");
    else
        check(self,
              vvg_devices_record_start(
                  self->devices, gtk_editable_get_text(GTK_EDITABLE(self->record_entry)), &err),
              &err, "Cannot record");
    update_status(self);
}

static void
choose_response(GtkNativeDialog *d, int response, gpointer user) {
    GtkWidget *entry = user;
    if (response == GTK_RESPONSE_ACCEPT) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(d));
        char *p = f ? g_file_get_path(f) : NULL;
        if (p)
            gtk_editable_set_text(GTK_EDITABLE(entry), p);
        g_free(p);
        if (f)
            g_object_unref(f);
    }
    g_object_unref(d);
    g_object_unref(entry);
}

static void
choose_clicked(GtkButton *b, gpointer user) {
    GtkWidget *entry = user;
    gboolean save = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "save"));
    GtkRoot *root = gtk_widget_get_root(GTK_WIDGET(b));
    GtkFileChooserNative *d = gtk_file_chooser_native_new(
        save ? "Record input to" : "Replay input from",
        GTK_IS_WINDOW(root) ? GTK_WINDOW(root) : NULL,
        save ? GTK_FILE_CHOOSER_ACTION_SAVE : GTK_FILE_CHOOSER_ACTION_OPEN,
        save ? "_Select" : "_Open", "_Cancel");
    if (save)
        gtk_file_chooser_set_current_name(GTK_FILE_CHOOSER(d), "session.vvin");
    g_signal_connect(d, "response", G_CALLBACK(choose_response), g_object_ref(entry));
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

/* A path entry with a "…" chooser button and an action button. */
static GtkWidget *
path_row(GtkWidget *box, const char *text, gboolean save, const char *button, GCallback cb,
         gpointer user, GtkWidget **button_out) {
    GtkWidget *r = hbox(box);
    GtkWidget *e = gtk_entry_new();
    gtk_editable_set_text(GTK_EDITABLE(e), text ? text : "");
    gtk_widget_set_hexpand(e, TRUE);
    g_autofree char *ename = g_strdup_printf("%s file", button);
    vvg_name(e, ename);
    gtk_box_append(GTK_BOX(r), e);
    GtkWidget *ch = gtk_button_new_with_label("…");
    g_autofree char *chname = g_strdup_printf("choose the %s file", button);
    vvg_name(ch, chname);
    gtk_widget_set_tooltip_text(ch, "choose a file");
    g_object_set_data(G_OBJECT(ch), "save", GINT_TO_POINTER(save));
    g_signal_connect(ch, "clicked", G_CALLBACK(choose_clicked), e);
    gtk_box_append(GTK_BOX(r), ch);
    GtkWidget *b = gtk_button_new_with_label(button);
    g_signal_connect(b, "clicked", cb, user);
    gtk_box_append(GTK_BOX(r), b);
    if (button_out)
        *button_out = b;
    return e;
}

/* ---- devices present at start ---------------------------------------------------------- */

/* The GUI's settings file ($XDG_CONFIG_HOME/volvis/gui.ini). */
static char *
settings_path(void) {
    return g_build_filename(g_get_user_config_dir(), "volvis", "gui.ini", NULL);
}

/* "Use devices present at start": on unless the settings say off or
 * VOLVIS_NO_AUTO_DEVICES is set. */
static gboolean
auto_devices_enabled(void) {
    const char *env = g_getenv("VOLVIS_NO_AUTO_DEVICES");
    if (env && *env && strcmp(env, "0"))
        return FALSE;
    g_autofree char *path = settings_path();
    g_autoptr(GKeyFile) kf = g_key_file_new();
    if (!g_key_file_load_from_file(kf, path, G_KEY_FILE_NONE, NULL))
        return TRUE;
    GError *err = NULL;
    gboolean on = g_key_file_get_boolean(kf, "devices", "use-at-start", &err);
    if (err) {
        g_error_free(err);
        return TRUE;
    }
    return on;
}

static void
auto_start_toggled(GtkCheckButton *b, gpointer user) {
    (void)user;
    g_autofree char *path = settings_path();
    g_autofree char *dir = g_path_get_dirname(path);
    g_autoptr(GKeyFile) kf = g_key_file_new();
    g_key_file_load_from_file(kf, path, G_KEY_FILE_KEEP_COMMENTS, NULL);
    g_key_file_set_boolean(kf, "devices", "use-at-start", gtk_check_button_get_active(b));
    GError *err = NULL;
    /* g_key_file_save_to_file writes a temporary file and renames it */
    if (g_mkdir_with_parents(dir, 0700) != 0 || !g_key_file_save_to_file(kf, path, &err)) {
        g_warning("volvis-gui: cannot save %s: %s", path, err ? err->message : g_strerror(errno));
        g_clear_error(&err);
    }
}

/* A spacenavd socket where libspnav looks for it. */
static gboolean
spacenav_present(void) {
    const char *p = g_getenv("SPNAV_SOCKET");
    struct stat st;
    return stat(p && *p ? p : "/var/run/spnav.sock", &st) == 0 && S_ISSOCK(st.st_mode);
}

/* A joystick or game pad on the system (what SDL would find). */
static gboolean
controller_present(void) {
    GDir *d = g_dir_open("/dev/input", 0, NULL);
    gboolean found = FALSE;
    for (const char *n; d && !found && (n = g_dir_read_name(d));)
        found = g_str_has_prefix(n, "js");
    if (d)
        g_dir_close(d);
    d = g_dir_open("/dev/input/by-id", 0, NULL);
    for (const char *n; d && !found && (n = g_dir_read_name(d));)
        found = strstr(n, "joystick") != NULL;
    if (d)
        g_dir_close(d);
    return found;
}

/* The devices present at start are used without a visit to this page, as
 * Blender and FreeCAD do; a failure is a warning, not a dialog. */
static gboolean
auto_start_cb(gpointer user) {
    VvgDevicesPage *self = user;
    self->auto_source = 0;
    GError *err = NULL;
    if (spacenav_present()) {
        if (vvg_devices_open_spacenav(self->devices, &err))
            update_status(self);
        else
            g_warning("volvis-gui: the 3-D mouse present at start: %s", err->message);
        g_clear_error(&err);
    }
    if (controller_present() && !vvg_devices_open_controllers(self->devices, &err)) {
        g_warning("volvis-gui: the game controllers present at start: %s", err->message);
        g_clear_error(&err);
    }
    return G_SOURCE_REMOVE;
}

/* VOLVIS_INPUT_SOCKET and VOLVIS_INPUT_REPLAY, once the window is up (errors in a dialog). */
static gboolean
start_cb(gpointer user) {
    VvgDevicesPage *self = user;
    self->start_idle = 0;
    const char *sock = g_getenv("VOLVIS_INPUT_SOCKET");
    if (sock && *sock) {
        gtk_editable_set_text(GTK_EDITABLE(self->socket_entry), sock);
        listen_clicked(NULL, self);
    }
    const char *replay = g_getenv("VOLVIS_INPUT_REPLAY");
    if (replay && *replay) {
        gtk_editable_set_text(GTK_EDITABLE(self->replay_entry), replay);
        replay_clicked(NULL, self);
    }
    /* after the first image: connecting takes a moment */
    if (auto_devices_enabled())
        self->auto_source = g_timeout_add(400, auto_start_cb, self);
    return G_SOURCE_REMOVE;
}

/* ---- life cycle ------------------------------------------------------------------------- */

static void
vvg_devices_page_dispose(GObject *o) {
    VvgDevicesPage *self = VVG_DEVICES_PAGE(o);
    g_clear_handle_id(&self->rebuild_idle, g_source_remove);
    g_clear_handle_id(&self->start_idle, g_source_remove);
    g_clear_handle_id(&self->auto_source, g_source_remove);
    if (self->devices) {
        g_signal_handler_disconnect(self->devices, self->changed_id);
        g_clear_object(&self->devices);
    }
    g_clear_pointer(&self->scroll, gtk_widget_unparent);
    G_OBJECT_CLASS(vvg_devices_page_parent_class)->dispose(o);
}

static void
vvg_devices_page_class_init(VvgDevicesPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_devices_page_dispose;
    gtk_widget_class_set_layout_manager_type(GTK_WIDGET_CLASS(klass), GTK_TYPE_BIN_LAYOUT);
}

static void
vvg_devices_page_init(VvgDevicesPage *self) {
    (void)self;
}

GtkWidget *
vvg_devices_page_new(VvgWindow *win) {
    VvgDevicesPage *self = g_object_new(VVG_TYPE_DEVICES_PAGE, NULL);
    GtkWidget *box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_widget_set_margin_start(box, 8);
    gtk_widget_set_margin_end(box, 8);
    gtk_widget_set_margin_bottom(box, 8);
    self->scroll = gtk_scrolled_window_new();
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(self->scroll), GTK_POLICY_NEVER,
                                   GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_child(GTK_SCROLLED_WINDOW(self->scroll), box);
    gtk_widget_set_vexpand(self->scroll, TRUE);
    gtk_widget_set_parent(self->scroll, GTK_WIDGET(self));

    GError *err = NULL;
    self->devices = vvg_devices_new(GTK_WINDOW(win), vvg_window_document(win), &err);
    if (!self->devices) {
        heading(box, "Input devices");
        char *t = g_strdup_printf("No input devices: %s", err->message);
        gtk_box_append(GTK_BOX(box), dim_label(t));
        g_free(t);
        g_error_free(err);
        return GTK_WIDGET(self);
    }
    /* the window owns the devices; the page keeps its own reference */
    g_object_set_data_full(G_OBJECT(win), "vvg-devices", g_object_ref(self->devices),
                           g_object_unref);
    self->changed_id =
        g_signal_connect(self->devices, "devices-changed", G_CALLBACK(devices_changed), self);

    heading(box, "Devices");
    self->list = gtk_list_box_new();
    gtk_list_box_set_selection_mode(GTK_LIST_BOX(self->list), GTK_SELECTION_NONE);
    gtk_box_append(GTK_BOX(box), self->list);
    gtk_box_append(GTK_BOX(box),
                   dim_label("6-DOF motion orbits (rx, ry), rolls (rz), pans (tx, ty) and "
                             "zooms (tz) the view; a burst of motion is one undo step."));

    heading(box, "Drivers");
    GtkWidget *r = hbox(box);
    GtkWidget *b = gtk_button_new_with_label("3-D mouse");
    gtk_widget_set_tooltip_text(b, "connect to spacenavd");
    g_signal_connect(b, "clicked", G_CALLBACK(spacenav_clicked), self);
    gtk_box_append(GTK_BOX(r), b);
    b = gtk_button_new_with_label("Game controllers");
    gtk_widget_set_tooltip_text(b, "SDL2 game controllers, attached now or later");
    g_signal_connect(b, "clicked", G_CALLBACK(controllers_clicked), self);
    gtk_box_append(GTK_BOX(r), b);
    self->auto_start =
        gtk_check_button_new_with_label("use the 3-D mouse and game controllers present at start");
    gtk_check_button_set_active(GTK_CHECK_BUTTON(self->auto_start), auto_devices_enabled());
    g_signal_connect(self->auto_start, "toggled", G_CALLBACK(auto_start_toggled), self);
    gtk_box_append(GTK_BOX(box), self->auto_start);

    heading(box, "Network socket");
    char *sock = vvg_devices_default_socket_path();
    self->socket_entry = gtk_entry_new();
    vvg_name(self->socket_entry, "socket path");
    gtk_editable_set_text(GTK_EDITABLE(self->socket_entry), sock);
    g_free(sock);
    gtk_widget_set_hexpand(self->socket_entry, TRUE);
    r = hbox(box);
    gtk_box_append(GTK_BOX(r), self->socket_entry);
    b = gtk_button_new_with_label("Listen");
    g_signal_connect(b, "clicked", G_CALLBACK(listen_clicked), self);
    gtk_box_append(GTK_BOX(r), b);

    heading(box, "Replay a recording (real speed)");
    self->replay_entry =
        path_row(box, NULL, FALSE, "Replay", G_CALLBACK(replay_clicked), self, NULL);

    heading(box, "Record the session");
    char *rec = g_build_filename(g_get_home_dir(), "volvis-input.vvin", NULL);
    self->record_entry =
        path_row(box, rec, TRUE, "Record", G_CALLBACK(record_clicked), self, &self->record_button);
    g_free(rec);

    self->status = dim_label("");
    gtk_widget_set_margin_top(self->status, 8);
    gtk_box_append(GTK_BOX(box), self->status);

    rebuild(self);
    self->start_idle = g_idle_add(start_cb, self);
    return GTK_WIDGET(self);
}
