/* VvgObjectList: the World's objects, visibility, names, selection (vvg-object-list.h). */
#include "vvg-object-list.h"
#include "vvg-widgets.h"

struct _VvgObjectList {
    GtkBox parent;
    VvgDocument *doc;
    GtkWidget *list, *buttons;
    gboolean updating; /* set while the rows are rebuilt */
};

G_DEFINE_TYPE(VvgObjectList, vvg_object_list, GTK_TYPE_BOX)

static void
visible_toggled(GtkCheckButton *b, gpointer user) {
    VvgObjectList *self = user;
    if (self->updating)
        return;
    int i = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "index"));
    vv_world *w = vvg_document_world(self->doc);
    if (i >= w->n_objects)
        return;
    vvg_document_begin_edit(self->doc, "visibility");
    w->objects[i]->visible = gtk_check_button_get_active(b);
    vvg_document_changed(self->doc);
}

static void
name_activated(GtkEntry *e, gpointer user) {
    VvgObjectList *self = user;
    int i = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(e), "index"));
    vv_world *w = vvg_document_world(self->doc);
    if (i >= w->n_objects)
        return;
    vvg_document_begin_edit(self->doc, "rename");
    g_strlcpy(w->objects[i]->name, gtk_editable_get_text(GTK_EDITABLE(e)),
              sizeof w->objects[i]->name);
    vvg_document_changed(self->doc);
}

static void
row_selected(GtkListBox *box, GtkListBoxRow *r, gpointer user) {
    (void)box;
    VvgObjectList *self = user;
    if (self->updating || !r)
        return;
    int i = gtk_list_box_row_get_index(r);
    if (i != vvg_document_selected(self->doc))
        vvg_document_select(self->doc, i);
}

static void
rebuild(VvgObjectList *self) {
    self->updating = TRUE;
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(self->list)))
        gtk_list_box_remove(GTK_LIST_BOX(self->list), c);
    vv_world *w = vvg_document_world(self->doc);
    for (int i = 0; i < w->n_objects; i++) {
        GtkWidget *r = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
        GtkWidget *vis = gtk_check_button_new();
        gtk_check_button_set_active(GTK_CHECK_BUTTON(vis), w->objects[i]->visible);
        gtk_widget_set_tooltip_text(vis, "visible");
        g_autofree char *vname = g_strdup_printf("visible: %s", w->objects[i]->name);
        vvg_name(vis, vname);
        g_object_set_data(G_OBJECT(vis), "index", GINT_TO_POINTER(i));
        g_signal_connect(vis, "toggled", G_CALLBACK(visible_toggled), self);
        GtkWidget *name = gtk_entry_new();
        gtk_editable_set_text(GTK_EDITABLE(name), w->objects[i]->name);
        gtk_widget_set_hexpand(name, TRUE);
        g_autofree char *nname = g_strdup_printf("name of object %d", i + 1);
        vvg_name(name, nname);
        g_object_set_data(G_OBJECT(name), "index", GINT_TO_POINTER(i));
        g_signal_connect(name, "activate", G_CALLBACK(name_activated), self);
        GtkWidget *type = gtk_label_new(vv_object_type_name(w->objects[i]->type));
        gtk_box_append(GTK_BOX(r), vis);
        gtk_box_append(GTK_BOX(r), name);
        gtk_box_append(GTK_BOX(r), type);
        gtk_list_box_append(GTK_LIST_BOX(self->list), r);
    }
    int sel = vvg_document_selected(self->doc);
    if (sel >= 0)
        gtk_list_box_select_row(GTK_LIST_BOX(self->list),
                                gtk_list_box_get_row_at_index(GTK_LIST_BOX(self->list), sel));
    self->updating = FALSE;
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    rebuild(user);
}

static void
vvg_object_list_dispose(GObject *o) {
    VvgObjectList *self = VVG_OBJECT_LIST(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    G_OBJECT_CLASS(vvg_object_list_parent_class)->dispose(o);
}

static void
vvg_object_list_class_init(VvgObjectListClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_object_list_dispose;
}

static void
vvg_object_list_init(VvgObjectList *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    GtkWidget *l = gtk_label_new(NULL);
    gtk_label_set_markup(GTK_LABEL(l), "<b>Objects</b>");
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_box_append(GTK_BOX(self), l);
    self->list = gtk_list_box_new();
    vvg_label_for(self->list, l);
    g_signal_connect(self->list, "row-selected", G_CALLBACK(row_selected), self);
    gtk_box_append(GTK_BOX(self), self->list);
    self->buttons = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(self->buttons), vvg_action_button("Open…", "win.open"));
    gtk_box_append(GTK_BOX(self->buttons), vvg_action_button("Delete", "win.delete-object"));
    gtk_box_append(GTK_BOX(self), self->buttons);
}

GtkWidget *
vvg_object_list_new(VvgDocument *doc) {
    VvgObjectList *self = g_object_new(VVG_TYPE_OBJECT_LIST, NULL);
    self->doc = g_object_ref(doc);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), self);
    rebuild(self);
    return GTK_WIDGET(self);
}

void
vvg_object_list_add_button(VvgObjectList *self, GtkWidget *button) {
    gtk_box_append(GTK_BOX(self->buttons), button);
}
