/* VvgNavigatorPanel: the Navigator's settings (vvg-navigator-panel.h). */
#include "vvg-navigator-panel.h"
#include "vvg-widgets.h"

#include <string.h>

struct _VvgNavigatorPanel {
    GtkBox parent;
    VvgSceneView *scene; /* borrowed */
    GtkWidget *target;
    GtkWidget *cache; /* what the frame on screen drew out of core */
    guint cache_tick;
};

G_DEFINE_TYPE(VvgNavigatorPanel, vvg_navigator_panel, GTK_TYPE_BOX)

static void
target_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvgNavigatorPanel *self = user;
    vvg_scene_view_set_target(self->scene,
                              (VvgNavTarget)gtk_drop_down_get_selected(GTK_DROP_DOWN(o)));
}

static void
preview_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvgNavigatorPanel *self = user;
    vvg_scene_view_set_preview(self->scene, (int)gtk_drop_down_get_selected(GTK_DROP_DOWN(o)) - 1);
}

static void
delay_changed(GtkSpinButton *s, gpointer user) {
    VvgNavigatorPanel *self = user;
    vvg_scene_view_set_refine_delay(self->scene, (int)gtk_spin_button_get_value(s));
}

static void
flight_toggled(GtkCheckButton *b, gpointer user) {
    VvgNavigatorPanel *self = user;
    vvg_scene_view_set_flight(self->scene, gtk_check_button_get_active(b));
    gtk_widget_grab_focus(GTK_WIDGET(self->scene));
}

/* The cache's state, four times a second (the loader fills it meanwhile). */
static gboolean
cache_tick(gpointer user) {
    VvgNavigatorPanel *self = user;
    g_autofree char *t = vvg_scene_view_cache_status(self->scene);
    if (strcmp(gtk_label_get_text(GTK_LABEL(self->cache)), t) != 0)
        gtk_label_set_text(GTK_LABEL(self->cache), t);
    gtk_widget_set_visible(self->cache, t[0] != '\0');
    return G_SOURCE_CONTINUE;
}

static void
vvg_navigator_panel_dispose(GObject *o) {
    VvgNavigatorPanel *self = VVG_NAVIGATOR_PANEL(o);
    if (self->cache_tick) {
        g_source_remove(self->cache_tick);
        self->cache_tick = 0;
    }
    G_OBJECT_CLASS(vvg_navigator_panel_parent_class)->dispose(o);
}

static void
vvg_navigator_panel_class_init(VvgNavigatorPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_navigator_panel_dispose;
}

static void
vvg_navigator_panel_init(VvgNavigatorPanel *self) {
    vvg_vbox_init(GTK_WIDGET(self));
}

GtkWidget *
vvg_navigator_panel_new(VvgSceneView *scene) {
    VvgNavigatorPanel *self = g_object_new(VVG_TYPE_NAVIGATOR_PANEL, NULL);
    self->scene = scene;
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "Navigator");
    static const char *const targets[] = {"view", "selected object", "selected light", "cut plane",
                                          NULL};
    self->target = vvg_row(g, "drag moves", gtk_drop_down_new_from_strings(targets));
    g_signal_connect(self->target, "notify::selected", G_CALLBACK(target_changed), self);
    static const char *const previews[] = {"automatic",    "bounding boxes", "PARC boxes",
                                           "coarse MC",    "ray cast 1/8",   "ray cast 1/4",
                                           "ray cast 1/2", "full quality",   NULL};
    GtkWidget *pv = vvg_row(g, "preview", gtk_drop_down_new_from_strings(previews));
    g_signal_connect(pv, "notify::selected", G_CALLBACK(preview_changed), self);
    GtkWidget *dl = vvg_row(g, "refine after (ms)", vvg_spin(0, 2000, 10, 0, 100));
    g_signal_connect(dl, "value-changed", G_CALLBACK(delay_changed), self);
    GtkWidget *fl = gtk_check_button_new_with_label("flight simulator keys (arrows, Q/E, W/S)");
    g_signal_connect(fl, "toggled", G_CALLBACK(flight_toggled), self);
    gtk_grid_attach(GTK_GRID(g), fl, 0, vvg_grid_rows(g), 2, 1);
    /* a file out of core: the cache, the levels drawn, what is pending */
    self->cache = gtk_label_new("");
    gtk_label_set_xalign(GTK_LABEL(self->cache), 0);
    gtk_label_set_wrap(GTK_LABEL(self->cache), TRUE);
    gtk_label_set_max_width_chars(GTK_LABEL(self->cache), 40);
    gtk_widget_set_visible(self->cache, FALSE);
    gtk_grid_attach(GTK_GRID(g), self->cache, 0, vvg_grid_rows(g), 2, 1);
    self->cache_tick = g_timeout_add(250, cache_tick, self);
    return GTK_WIDGET(self);
}

void
vvg_navigator_panel_set_target(VvgNavigatorPanel *self, VvgNavTarget target) {
    gtk_drop_down_set_selected(GTK_DROP_DOWN(self->target), (guint)target);
}
