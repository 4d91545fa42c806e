/* VvgViewPanel: the view as numbers (vvg-view-panel.h). */
#include "vvg-view-panel.h"
#include "vvg-widgets.h"

struct _VvgViewPanel {
    GtkBox parent;
    VvgDocument *doc;
    gboolean updating;
    guint placement_source;
    GtkWidget *eye[3], *at[3];
    GtkWidget *fov, *projection;
};

G_DEFINE_TYPE(VvgViewPanel, vvg_view_panel, GTK_TYPE_BOX)

static void
fill(VvgViewPanel *self) {
    gboolean was = self->updating;
    self->updating = TRUE;
    const vv_view *v = &vvg_document_world(self->doc)->view;
    double ev[3] = {v->eye.x, v->eye.y, v->eye.z};
    double av[3] = {v->at.x, v->at.y, v->at.z};
    for (int i = 0; i < 3; i++) {
        vvg_set_spin(self->eye[i], ev[i]);
        vvg_set_spin(self->at[i], av[i]);
    }
    vvg_set_spin(self->fov, vv_rad_to_deg(v->fov));
    gtk_drop_down_set_selected(GTK_DROP_DOWN(self->projection), v->projection);
    self->updating = was;
}

/* The widgets applied to the view: one undo step. */
static void
apply(VvgViewPanel *self) {
    if (self->updating)
        return;
    vv_world *w = vvg_document_world(self->doc);
    vvg_document_begin_edit(self->doc, "view");
    vv_view nv = w->view;
    nv.eye = vv_vec3_make(vvg_spin_value(self->eye[0]), vvg_spin_value(self->eye[1]),
                          vvg_spin_value(self->eye[2]));
    nv.at = vv_vec3_make(vvg_spin_value(self->at[0]), vvg_spin_value(self->at[1]),
                         vvg_spin_value(self->at[2]));
    nv.fov = vv_deg_to_rad(vvg_spin_value(self->fov));
    nv.projection = (vv_projection)gtk_drop_down_get_selected(GTK_DROP_DOWN(self->projection));
    if (vv_nav_view_valid(&nv)) /* an eye on the look-at point is refused */
        w->view = nv;
    vvg_document_changed(self->doc);
}

static void
on_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    apply(user);
}

static void
on_dropdown(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    apply(user);
}

static gboolean
placement_due(gpointer user) {
    VvgViewPanel *self = user;
    self->placement_source = 0;
    fill(self);
    return G_SOURCE_REMOVE;
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgViewPanel *self = user;
    /* during a drag the World changes a hundred times a second: the numbers
     * follow ten times a second */
    if (!self->placement_source)
        self->placement_source = g_timeout_add(100, placement_due, self);
}

static void
vvg_view_panel_dispose(GObject *o) {
    VvgViewPanel *self = VVG_VIEW_PANEL(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    if (self->placement_source) {
        g_source_remove(self->placement_source);
        self->placement_source = 0;
    }
    G_OBJECT_CLASS(vvg_view_panel_parent_class)->dispose(o);
}

static void
vvg_view_panel_class_init(VvgViewPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_view_panel_dispose;
}

static void
vvg_view_panel_init(VvgViewPanel *self) {
    vvg_vbox_init(GTK_WIDGET(self));
}

static GtkWidget *
wire_spin(VvgViewPanel *self, GtkWidget *s) {
    g_signal_connect(s, "value-changed", G_CALLBACK(on_spin), self);
    return s;
}

GtkWidget *
vvg_view_panel_new(VvgDocument *doc) {
    VvgViewPanel *self = g_object_new(VVG_TYPE_VIEW_PANEL, NULL);
    self->doc = g_object_ref(doc);
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "View");
    const char *en[] = {"eye x", "eye y", "eye z"}, *an[] = {"look at x", "look at y", "look at z"};
    for (int i = 0; i < 3; i++)
        self->eye[i] = vvg_row(g, en[i], wire_spin(self, vvg_spin0(-1e7, 1e7, 1, 3)));
    for (int i = 0; i < 3; i++)
        self->at[i] = vvg_row(g, an[i], wire_spin(self, vvg_spin0(-1e7, 1e7, 1, 3)));
    self->fov = vvg_row(g, "field of view (°)", wire_spin(self, vvg_spin0(1, 170, 1, 1)));
    static const char *const projs[] = {"perspective", "orthographic", NULL};
    self->projection = vvg_row(g, "projection", gtk_drop_down_new_from_strings(projs));
    g_signal_connect(self->projection, "notify::selected", G_CALLBACK(on_dropdown), self);
    GtkWidget *vb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(vb), vvg_action_button("Front", "win.view-front"));
    gtk_box_append(GTK_BOX(vb), vvg_action_button("Side", "win.view-side"));
    gtk_box_append(GTK_BOX(vb), vvg_action_button("Top", "win.view-top"));
    gtk_box_append(GTK_BOX(vb), vvg_action_button("Frame all", "win.frame-all"));
    gtk_box_append(GTK_BOX(self), vb);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    fill(self);
    return GTK_WIDGET(self);
}
