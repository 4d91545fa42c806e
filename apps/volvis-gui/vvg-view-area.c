/* VvgViewArea: start page, or the 3-D view alone or four-up (vvg-view-area.h). */
#include "vvg-view-area.h"

#include "vvg-slice-view.h"
#include "vvg-start-page.h"

struct _VvgViewArea {
    GtkBox parent;
    VvgDocument *doc;
    GtkWidget *stack, *start, *grid, *slices[3];
    int layout;
};

G_DEFINE_TYPE(VvgViewArea, vvg_view_area, GTK_TYPE_BOX)

static void
update(VvgViewArea *self) {
    gboolean empty = vvg_document_world(self->doc)->n_objects == 0;
    const char *want = empty ? "start" : "views";
    if (g_strcmp0(gtk_stack_get_visible_child_name(GTK_STACK(self->stack)), want))
        gtk_stack_set_visible_child_name(GTK_STACK(self->stack), want);
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    update(user);
}

static void
vvg_view_area_dispose(GObject *o) {
    VvgViewArea *self = VVG_VIEW_AREA(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    G_OBJECT_CLASS(vvg_view_area_parent_class)->dispose(o);
}

static void
vvg_view_area_class_init(VvgViewAreaClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_view_area_dispose;
}

static void
vvg_view_area_init(VvgViewArea *self) {
    gtk_widget_set_hexpand(GTK_WIDGET(self), TRUE);
    gtk_widget_set_vexpand(GTK_WIDGET(self), TRUE);
    self->layout = 1;
}

GtkWidget *
vvg_view_area_new(VvgDocument *doc, VvgSceneView *scene, VvgMarks *marks) {
    VvgViewArea *self = g_object_new(VVG_TYPE_VIEW_AREA, NULL);
    self->doc = g_object_ref(doc);
    self->stack = gtk_stack_new();
    gtk_widget_set_hexpand(self->stack, TRUE);
    gtk_widget_set_vexpand(self->stack, TRUE);
    self->start = vvg_start_page_new();
    gtk_stack_add_named(GTK_STACK(self->stack), self->start, "start");
    self->grid = gtk_grid_new();
    gtk_grid_set_row_homogeneous(GTK_GRID(self->grid), TRUE);
    gtk_grid_set_column_homogeneous(GTK_GRID(self->grid), TRUE);
    gtk_grid_set_row_spacing(GTK_GRID(self->grid), 2);
    gtk_grid_set_column_spacing(GTK_GRID(self->grid), 2);
    gtk_grid_attach(GTK_GRID(self->grid), GTK_WIDGET(scene), 0, 0, 1, 1);
    static const int at[3][2] = {{1, 0}, {0, 1}, {1, 1}};
    for (int i = 0; i < 3; i++) {
        self->slices[i] = vvg_slice_view_new(doc, marks, (vv_slice_axis)i);
        gtk_grid_attach(GTK_GRID(self->grid), self->slices[i], at[i][0], at[i][1], 1, 1);
        gtk_widget_set_visible(self->slices[i], FALSE);
    }
    gtk_stack_add_named(GTK_STACK(self->stack), self->grid, "views");
    gtk_box_append(GTK_BOX(self), self->stack);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(doc_changed), self);
    update(self);
    return GTK_WIDGET(self);
}

void
vvg_view_area_set_layout(VvgViewArea *self, int views) {
    self->layout = views == 4 ? 4 : 1;
    for (int i = 0; i < 3; i++)
        gtk_widget_set_visible(self->slices[i], self->layout == 4);
}

int
vvg_view_area_layout(VvgViewArea *self) {
    return self->layout;
}

GtkWidget *
vvg_view_area_slice_view(VvgViewArea *self, int i) {
    return i >= 0 && i < 3 ? self->slices[i] : NULL;
}

void
vvg_view_area_refresh_recent(VvgViewArea *self) {
    vvg_start_page_refresh(VVG_START_PAGE(self->start));
}
