/* VvgCutPanel: the list of global and per-object cut planes (vvg-cut-panel.h). */
#include "vvg-cut-panel.h"
#include "vvg-widgets.h"

#include <math.h>
#include <string.h>

#define MAX_OFF 32

/* A plane switched off: kept here, out of the World, until switched on. */
typedef struct off_plane {
    int object; /* -1: global */
    vv_cut_plane plane;
} off_plane;

struct _VvgCutPanel {
    GtkBox parent;
    VvgDocument *doc;
    VvgSceneView *scene; /* borrowed */
    GtkWidget *list, *scope, *px, *py, *pz, *nx, *ny, *nz, *edit_title;
    gboolean updating;
    guint refresh_source;
    int sel_object, sel_plane; /* the plane the numbers edit; sel_plane -1: none */
    off_plane off[MAX_OFF];
    int n_off;
    char shown[4096]; /* the list as last built, to rebuild only on a change */
};

G_DEFINE_TYPE(VvgCutPanel, vvg_cut_panel, GTK_TYPE_BOX)

/* The list of planes (object -1: global), or NULL. */
static vv_cut_plane *
planes_of(VvgCutPanel *self, int object, int *n) {
    vv_world *w = vvg_document_world(self->doc);
    if (object < 0) {
        *n = w->n_cut_planes;
        return w->cut_planes;
    }
    if (object >= w->n_objects)
        return NULL;
    *n = w->objects[object]->n_cut_planes;
    return w->objects[object]->cut_planes;
}

static vv_cut_plane *
selected(VvgCutPanel *self) {
    int n = 0;
    vv_cut_plane *l = planes_of(self, self->sel_object, &n);
    return l && self->sel_plane >= 0 && self->sel_plane < n ? &l[self->sel_plane] : NULL;
}

/* The numbers of the selected plane (they follow its handle in the view). */
static void
fill_numbers(VvgCutPanel *self) {
    const vv_cut_plane *p = selected(self);
    gboolean was = self->updating;
    self->updating = TRUE;
    if (p) {
        vvg_set_spin(self->px, p->point.x);
        vvg_set_spin(self->py, p->point.y);
        vvg_set_spin(self->pz, p->point.z);
        vvg_set_spin(self->nx, p->normal.x);
        vvg_set_spin(self->ny, p->normal.y);
        vvg_set_spin(self->nz, p->normal.z);
    }
    gtk_label_set_text(GTK_LABEL(self->edit_title),
                       p ? "Selected plane (the handle moves it too)" : "New plane");
    self->updating = was;
    vvg_scene_view_set_cut_plane(self->scene, self->sel_object, p ? self->sel_plane : -1);
}

static void rebuild(VvgCutPanel *self);

static void
row_selected(GtkListBox *box, GtkListBoxRow *r, gpointer user) {
    (void)box;
    VvgCutPanel *self = user;
    if (self->updating || !r)
        return;
    int plane = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(r), "plane"));
    if (plane < 0)
        return; /* a plane switched off: nothing to edit */
    self->sel_object = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(r), "object"));
    self->sel_plane = plane;
    fill_numbers(self);
}

static void
remove_plane(VvgCutPanel *self, int object, int plane) {
    int n = 0;
    vv_cut_plane *l = planes_of(self, object, &n);
    if (!l || plane < 0 || plane >= n)
        return;
    vvg_document_begin_edit(self->doc, "remove cut plane");
    l = planes_of(self, object, &n);
    memmove(&l[plane], &l[plane + 1], (size_t)(n - plane - 1) * sizeof *l);
    if (object < 0)
        vvg_document_world(self->doc)->n_cut_planes--;
    else
        vvg_document_world(self->doc)->objects[object]->n_cut_planes--;
    self->sel_plane = -1;
    vvg_document_changed(self->doc);
}

static void
remove_clicked(GtkButton *b, gpointer user) {
    VvgCutPanel *self = user;
    int object = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "object"));
    int plane = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "plane"));
    int off = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "off"));
    if (plane < 0 && off >= 0 && off < self->n_off) { /* a plane switched off: forget it */
        memmove(&self->off[off], &self->off[off + 1],
                (size_t)(self->n_off - off - 1) * sizeof self->off[0]);
        self->n_off--;
        rebuild(self);
        return;
    }
    remove_plane(self, object, plane);
}

/* Adds @p p to the World's or object @p object's planes (no undo step of its own). */
static gboolean
add_to(VvgCutPanel *self, int object, vv_cut_plane p) {
    vv_world *w = vvg_document_world(self->doc);
    if (object >= 0 && object < w->n_objects) {
        vv_object *o = w->objects[object];
        if (o->n_cut_planes >= VV_MAX_CUT_PLANES)
            return FALSE;
        o->cut_planes[o->n_cut_planes++] = p;
        return TRUE;
    }
    return vv_world_add_cut_plane(w, p.point, p.normal) == VV_OK;
}

/* On: the plane goes back into the World; off: out of it, kept here. */
static void
enable_toggled(GtkCheckButton *b, gpointer user) {
    VvgCutPanel *self = user;
    if (self->updating)
        return;
    int object = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "object"));
    int plane = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "plane"));
    int off = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "off"));
    if (gtk_check_button_get_active(b) && off >= 0 && off < self->n_off) {
        off_plane op = self->off[off];
        vvg_document_begin_edit(self->doc, "switch a cut plane on");
        if (add_to(self, op.object, op.plane)) {
            memmove(&self->off[off], &self->off[off + 1],
                    (size_t)(self->n_off - off - 1) * sizeof self->off[0]);
            self->n_off--;
        }
        vvg_document_changed(self->doc);
    } else if (!gtk_check_button_get_active(b) && plane >= 0 && self->n_off < MAX_OFF) {
        int n = 0;
        vv_cut_plane *l = planes_of(self, object, &n);
        if (!l || plane >= n)
            return;
        self->off[self->n_off++] = (off_plane){object, l[plane]};
        remove_plane(self, object, plane);
    }
}

static void
add_row(VvgCutPanel *self, const char *owner, int k, const vv_cut_plane *p, int object, int plane,
        int off) {
    GtkWidget *row = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    GtkWidget *on = gtk_check_button_new();
    gtk_check_button_set_active(GTK_CHECK_BUTTON(on), plane >= 0);
    g_autofree char *name = g_strdup_printf("%s plane %d", owner, k);
    g_autofree char *on_name = g_strdup_printf("%s on", name);
    vvg_name(on, on_name);
    g_autofree char *text =
        g_strdup_printf("%s: (%.4g, %.4g, %.4g) facing (%.3g, %.3g, %.3g)", name, p->point.x,
                        p->point.y, p->point.z, p->normal.x, p->normal.y, p->normal.z);
    GtkWidget *label = gtk_label_new(text);
    gtk_label_set_xalign(GTK_LABEL(label), 0);
    gtk_label_set_ellipsize(GTK_LABEL(label), PANGO_ELLIPSIZE_END);
    gtk_widget_set_hexpand(label, TRUE);
    if (plane < 0)
        gtk_widget_add_css_class(label, "dim-label");
    GtkWidget *rm = gtk_button_new_with_label("Remove");
    g_autofree char *rm_name = g_strdup_printf("remove %s", name);
    vvg_name(rm, rm_name);
    GObject *objs[2] = {G_OBJECT(on), G_OBJECT(rm)};
    for (int i = 0; i < 2; i++) {
        g_object_set_data(objs[i], "object", GINT_TO_POINTER(object));
        g_object_set_data(objs[i], "plane", GINT_TO_POINTER(plane));
        g_object_set_data(objs[i], "off", GINT_TO_POINTER(off));
    }
    g_signal_connect(on, "toggled", G_CALLBACK(enable_toggled), self);
    g_signal_connect(rm, "clicked", G_CALLBACK(remove_clicked), self);
    gtk_box_append(GTK_BOX(row), on);
    gtk_box_append(GTK_BOX(row), label);
    gtk_box_append(GTK_BOX(row), rm);
    gtk_list_box_append(GTK_LIST_BOX(self->list), row);
    GtkWidget *r = gtk_widget_get_parent(row); /* the GtkListBoxRow made for it */
    if (GTK_IS_LIST_BOX_ROW(r)) {
        g_object_set_data(G_OBJECT(r), "object", GINT_TO_POINTER(object));
        g_object_set_data(G_OBJECT(r), "plane", GINT_TO_POINTER(plane));
        if (object == self->sel_object && plane == self->sel_plane && plane >= 0)
            gtk_list_box_select_row(GTK_LIST_BOX(self->list), GTK_LIST_BOX_ROW(r));
    }
}

/* The list's text, to rebuild it only when a plane changed. */
static void
describe(VvgCutPanel *self, char *out, size_t size) {
    vv_world *w = vvg_document_world(self->doc);
    GString *s = g_string_new(NULL);
    for (int i = 0; i < w->n_cut_planes; i++)
        g_string_append_printf(s, "g%a,%a,%a,%a,%a,%a;", w->cut_planes[i].point.x,
                               w->cut_planes[i].point.y, w->cut_planes[i].point.z,
                               w->cut_planes[i].normal.x, w->cut_planes[i].normal.y,
                               w->cut_planes[i].normal.z);
    for (int o = 0; o < w->n_objects; o++)
        for (int i = 0; i < w->objects[o]->n_cut_planes; i++)
            g_string_append_printf(s, "o%d:%a,%a,%a,%a;", o, w->objects[o]->cut_planes[i].point.x,
                                   w->objects[o]->cut_planes[i].point.y,
                                   w->objects[o]->cut_planes[i].point.z,
                                   w->objects[o]->cut_planes[i].normal.z);
    g_string_append_printf(s, "off%d sel%d,%d", self->n_off, self->sel_object, self->sel_plane);
    g_strlcpy(out, s->str, size);
    g_string_free(s, TRUE);
}

static void
rebuild(VvgCutPanel *self) {
    char now[sizeof self->shown];
    describe(self, now, sizeof now);
    if (!strcmp(now, self->shown))
        return;
    g_strlcpy(self->shown, now, sizeof self->shown);
    self->updating = TRUE;
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(self->list)))
        gtk_list_box_remove(GTK_LIST_BOX(self->list), c);
    vv_world *w = vvg_document_world(self->doc);
    if (!selected(self))
        self->sel_plane = -1;
    for (int i = 0; i < w->n_cut_planes; i++)
        add_row(self, "global", i + 1, &w->cut_planes[i], -1, i, -1);
    for (int o = 0; o < w->n_objects; o++)
        for (int i = 0; i < w->objects[o]->n_cut_planes; i++)
            add_row(self, w->objects[o]->name, i + 1, &w->objects[o]->cut_planes[i], o, i, -1);
    for (int k = 0; k < self->n_off; k++) {
        const char *owner = self->off[k].object < 0 || self->off[k].object >= w->n_objects
                                ? "global"
                                : w->objects[self->off[k].object]->name;
        add_row(self, owner, k + 1, &self->off[k].plane, self->off[k].object, -1, k);
    }
    self->updating = FALSE;
    fill_numbers(self);
}

static gboolean
refresh_due(gpointer user) {
    VvgCutPanel *self = user;
    self->refresh_source = 0;
    rebuild(self);
    fill_numbers(self);
    return G_SOURCE_REMOVE;
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgCutPanel *self = user;
    /* a handle drag changes the plane a hundred times a second: the list and
     * the numbers follow ten times a second */
    if (!self->refresh_source)
        self->refresh_source = g_timeout_add(100, refresh_due, self);
}

/* Typed numbers move the selected plane: one undo step each. */
static void
numbers_changed(GtkSpinButton *s, gpointer user) {
    (void)s;
    VvgCutPanel *self = user;
    if (self->updating || !selected(self))
        return;
    vv_vec3 n =
        vv_vec3_make(vvg_spin_value(self->nx), vvg_spin_value(self->ny), vvg_spin_value(self->nz));
    if (!(vv_vec3_length(n) > 0))
        return;
    vvg_document_begin_edit(self->doc, "move cut plane");
    vv_cut_plane *p = selected(self);
    p->point =
        vv_vec3_make(vvg_spin_value(self->px), vvg_spin_value(self->py), vvg_spin_value(self->pz));
    p->normal = vv_vec3_normalize(n);
    vvg_document_changed(self->doc);
}

static void
act_add_cut(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgCutPanel *self = user;
    vv_world *w = vvg_document_world(self->doc);
    gboolean local = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->scope)) == 1;
    int object = local ? vvg_document_selected(self->doc) : -1;
    /* through the World's centre facing +z, unless numbers were typed for a new plane */
    vv_box b = vv_world_bounds(w);
    vv_cut_plane cp = {vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5), vv_vec3_make(0, 0, 1)};
    if (!selected(self)) {
        cp.point = vv_vec3_make(vvg_spin_value(self->px), vvg_spin_value(self->py),
                                vvg_spin_value(self->pz));
        vv_vec3 n = vv_vec3_make(vvg_spin_value(self->nx), vvg_spin_value(self->ny),
                                 vvg_spin_value(self->nz));
        if (!(vv_vec3_length(n) > 0)) {
            vvg_show_error(GTK_WIDGET(self), "Cannot add the cut plane", "the normal is zero");
            return;
        }
        cp.normal = vv_vec3_normalize(n);
    }
    vvg_document_begin_edit(self->doc, "add cut plane");
    if (!add_to(self, object, cp))
        vvg_show_error(GTK_WIDGET(self), "Cannot add the cut plane",
                       "the list of cut planes is full");
    int n = 0;
    planes_of(self, object, &n);
    self->sel_object = object;
    self->sel_plane = n - 1;
    vvg_document_changed(self->doc);
    rebuild(self);
}

static void
act_clear_cuts(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgCutPanel *self = user;
    vvg_document_begin_edit(self->doc, "remove cut planes");
    vv_world *w = vvg_document_world(self->doc);
    w->n_cut_planes = 0;
    for (int o = 0; o < w->n_objects; o++)
        w->objects[o]->n_cut_planes = 0;
    self->n_off = 0;
    self->sel_plane = -1;
    vvg_document_changed(self->doc);
}

static void
vvg_cut_panel_dispose(GObject *o) {
    VvgCutPanel *self = VVG_CUT_PANEL(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    g_clear_handle_id(&self->refresh_source, g_source_remove);
    G_OBJECT_CLASS(vvg_cut_panel_parent_class)->dispose(o);
}

static void
vvg_cut_panel_class_init(VvgCutPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_cut_panel_dispose;
}

static void
vvg_cut_panel_init(VvgCutPanel *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    self->sel_plane = -1;
    self->sel_object = -1;
}

static GtkWidget *
number(VvgCutPanel *self, GtkWidget *g, const char *label, double lo, double hi, double v) {
    GtkWidget *s = vvg_row(g, label, vvg_spin(lo, hi, hi > 1 ? 1 : 0.1, hi > 1 ? 2 : 3, v));
    g_signal_connect(s, "value-changed", G_CALLBACK(numbers_changed), self);
    return s;
}

GtkWidget *
vvg_cut_panel_new(VvgDocument *doc, VvgSceneView *scene, GActionMap *actions) {
    VvgCutPanel *self = g_object_new(VVG_TYPE_CUT_PANEL, NULL);
    self->doc = g_object_ref(doc);
    self->scene = scene;
    const GActionEntry entries[] = {
        {"add-cut-plane", act_add_cut, NULL, NULL, NULL, {0}},
        {"clear-cut-planes", act_clear_cuts, NULL, NULL, NULL, {0}},
    };
    g_action_map_add_action_entries(actions, entries, G_N_ELEMENTS(entries), self);
    GtkWidget *box = GTK_WIDGET(self);
    GtkWidget *t = gtk_label_new(NULL);
    gtk_label_set_markup(GTK_LABEL(t), "<b>Cut planes</b> (click one to edit it and to move it "
                                       "with its handle: Alt+4)");
    gtk_label_set_wrap(GTK_LABEL(t), TRUE);
    gtk_label_set_xalign(GTK_LABEL(t), 0);
    gtk_box_append(GTK_BOX(box), t);
    self->list = gtk_list_box_new();
    vvg_label_for(self->list, t);
    g_signal_connect(self->list, "row-selected", G_CALLBACK(row_selected), self);
    gtk_box_append(GTK_BOX(box), self->list);
    GtkWidget *g = vvg_section(box, "Add");
    static const char *const scopes[] = {"global", "selected object", NULL};
    self->scope = vvg_row(g, "scope", gtk_drop_down_new_from_strings(scopes));
    GtkWidget *cb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(cb), vvg_action_button("Add cut plane", "win.add-cut-plane"));
    gtk_box_append(GTK_BOX(cb), vvg_action_button("Remove all", "win.clear-cut-planes"));
    gtk_box_append(GTK_BOX(box), cb);
    self->edit_title = gtk_label_new("");
    gtk_label_set_xalign(GTK_LABEL(self->edit_title), 0);
    gtk_widget_set_margin_top(self->edit_title, 8);
    gtk_box_append(GTK_BOX(box), self->edit_title);
    g = gtk_grid_new();
    gtk_grid_set_row_spacing(GTK_GRID(g), 3);
    gtk_grid_set_column_spacing(GTK_GRID(g), 6);
    gtk_box_append(GTK_BOX(box), g);
    self->px = number(self, g, "point x", -1e6, 1e6, 0);
    self->py = number(self, g, "point y", -1e6, 1e6, 0);
    self->pz = number(self, g, "point z", -1e6, 1e6, 0);
    self->nx = number(self, g, "normal x", -1, 1, 0);
    self->ny = number(self, g, "normal y", -1, 1, 0);
    self->nz = number(self, g, "normal z", -1, 1, 1);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(doc_changed), self);
    rebuild(self);
    return box;
}
