/* VvCutPanel: global and per-object cut planes (vv-cut-panel.h). */
#include "vv-cut-panel.h"
#include "vvg-widgets.h"

struct _VvCutPanel {
    GtkBox parent;
    VvDocument *doc;
    GtkWidget *scope, *px, *py, *pz, *nx, *ny, *nz;
};

G_DEFINE_TYPE(VvCutPanel, vv_cut_panel, GTK_TYPE_BOX)

static void
act_add_cut(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvCutPanel *self = user;
    vv_vec3 pt =
        vv_vec3_make(vvg_spin_value(self->px), vvg_spin_value(self->py), vvg_spin_value(self->pz));
    vv_vec3 n =
        vv_vec3_make(vvg_spin_value(self->nx), vvg_spin_value(self->ny), vvg_spin_value(self->nz));
    if (!(vv_vec3_length(n) > 0)) {
        vvg_show_error(GTK_WIDGET(self), "Cannot add the cut plane", "the normal is zero");
        return;
    }
    vv_world *w = vv_document_world(self->doc);
    gboolean local = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->scope)) == 1;
    vv_object *o = vv_document_selected_object(self->doc);
    vv_document_begin_edit(self->doc, "add cut plane");
    if (local && o) {
        if (o->n_cut_planes < VV_MAX_CUT_PLANES)
            o->cut_planes[o->n_cut_planes++] = (vv_cut_plane){pt, vv_vec3_normalize(n)};
    } else if (vv_world_add_cut_plane(w, pt, n) != VV_OK) {
        vvg_show_error(GTK_WIDGET(self), "Cannot add the cut plane", vv_error_message());
    }
    vv_document_changed(self->doc);
}

static void
act_clear_cuts(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvCutPanel *self = user;
    vv_document_begin_edit(self->doc, "remove cut planes");
    vv_world *w = vv_document_world(self->doc);
    w->n_cut_planes = 0;
    vv_object *o = vv_document_selected_object(self->doc);
    if (o)
        o->n_cut_planes = 0;
    vv_document_changed(self->doc);
}

static void
vv_cut_panel_dispose(GObject *o) {
    VvCutPanel *self = VV_CUT_PANEL(o);
    g_clear_object(&self->doc);
    G_OBJECT_CLASS(vv_cut_panel_parent_class)->dispose(o);
}

static void
vv_cut_panel_class_init(VvCutPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vv_cut_panel_dispose;
}

static void
vv_cut_panel_init(VvCutPanel *self) {
    gtk_orientable_set_orientation(GTK_ORIENTABLE(self), GTK_ORIENTATION_VERTICAL);
    gtk_box_set_spacing(GTK_BOX(self), 4);
}

GtkWidget *
vv_cut_panel_new(VvDocument *doc, GActionMap *actions) {
    VvCutPanel *self = g_object_new(VV_TYPE_CUT_PANEL, NULL);
    self->doc = g_object_ref(doc);
    const GActionEntry entries[] = {
        {"add-cut-plane", act_add_cut, NULL, NULL, NULL, {0}},
        {"clear-cut-planes", act_clear_cuts, NULL, NULL, NULL, {0}},
    };
    g_action_map_add_action_entries(actions, entries, G_N_ELEMENTS(entries), self);
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "Cut planes");
    static const char *const scopes[] = {"global", "selected object", NULL};
    self->scope = vvg_row(g, "scope", gtk_drop_down_new_from_strings(scopes));
    self->px = vvg_row(g, "point x", vvg_spin0(-1e6, 1e6, 1, 2));
    self->py = vvg_row(g, "point y", vvg_spin0(-1e6, 1e6, 1, 2));
    self->pz = vvg_row(g, "point z", vvg_spin0(-1e6, 1e6, 1, 2));
    self->nx = vvg_row(g, "normal x", vvg_spin0(-1, 1, 0.1, 3));
    self->ny = vvg_row(g, "normal y", vvg_spin0(-1, 1, 0.1, 3));
    self->nz = vvg_row(g, "normal z", vvg_spin(-1, 1, 0.1, 3, 1));
    GtkWidget *cb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(cb), vvg_action_button("Add cut plane", "win.add-cut-plane"));
    gtk_box_append(GTK_BOX(cb), vvg_action_button("Remove all", "win.clear-cut-planes"));
    gtk_box_append(GTK_BOX(self), cb);
    return GTK_WIDGET(self);
}
