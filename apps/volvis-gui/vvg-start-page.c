/* VvgStartPage: Open, Import raw, Browse DICOM and the recent files (vvg-start-page.h). */
#include "vvg-start-page.h"

#define MAX_RECENT 8

struct _VvgStartPage {
    GtkBox parent;
    GtkWidget *recent_box, *recent_title;
    gulong changed_id;
};

G_DEFINE_TYPE(VvgStartPage, vvg_start_page, GTK_TYPE_BOX)

static gint
by_time(gconstpointer a, gconstpointer b) {
    GDateTime *ta = gtk_recent_info_get_modified((GtkRecentInfo *)a);
    GDateTime *tb = gtk_recent_info_get_modified((GtkRecentInfo *)b);
    return -g_date_time_compare(ta, tb);
}

void
vvg_start_page_refresh(VvgStartPage *self) {
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(self->recent_box)))
        gtk_box_remove(GTK_BOX(self->recent_box), c);
    GtkRecentManager *rm = gtk_recent_manager_get_default();
    GList *items = g_list_sort(gtk_recent_manager_get_items(rm), by_time);
    const char *app = g_get_application_name();
    int n = 0;
    for (GList *l = items; l && n < MAX_RECENT; l = l->next) {
        GtkRecentInfo *info = l->data;
        if (!app || !gtk_recent_info_has_application(info, app) || !gtk_recent_info_is_local(info))
            continue;
        char *path = g_filename_from_uri(gtk_recent_info_get_uri(info), NULL, NULL);
        if (path && g_file_test(path, G_FILE_TEST_EXISTS)) {
            g_autofree char *base = g_path_get_basename(path);
            GtkWidget *b = gtk_button_new_with_label(base);
            gtk_widget_set_tooltip_text(b, path);
            gtk_actionable_set_action_name(GTK_ACTIONABLE(b), "win.open-file");
            gtk_actionable_set_action_target(GTK_ACTIONABLE(b), "s", path);
            gtk_box_append(GTK_BOX(self->recent_box), b);
            n++;
        }
        g_free(path);
    }
    g_list_free_full(items, (GDestroyNotify)gtk_recent_info_unref);
    gtk_widget_set_visible(self->recent_title, n > 0);
}

void
vvg_start_page_add_recent(const char *path) {
    g_autofree char *uri = g_filename_to_uri(path, NULL, NULL);
    if (uri)
        gtk_recent_manager_add_item(gtk_recent_manager_get_default(), uri);
}

static void
recent_changed(GtkRecentManager *rm, gpointer user) {
    (void)rm;
    vvg_start_page_refresh(user);
}

static void
vvg_start_page_dispose(GObject *o) {
    VvgStartPage *self = VVG_START_PAGE(o);
    if (self->changed_id) {
        g_signal_handler_disconnect(gtk_recent_manager_get_default(), self->changed_id);
        self->changed_id = 0;
    }
    G_OBJECT_CLASS(vvg_start_page_parent_class)->dispose(o);
}

static void
vvg_start_page_class_init(VvgStartPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_start_page_dispose;
}

static GtkWidget *
big_button(const char *label, const char *action) {
    GtkWidget *b = gtk_button_new_with_label(label);
    gtk_actionable_set_action_name(GTK_ACTIONABLE(b), action);
    gtk_widget_add_css_class(b, "suggested-action");
    return b;
}

static void
vvg_start_page_init(VvgStartPage *self) {
    GtkBox *box = GTK_BOX(self);
    gtk_orientable_set_orientation(GTK_ORIENTABLE(self), GTK_ORIENTATION_VERTICAL);
    gtk_box_set_spacing(box, 10);
    gtk_widget_set_halign(GTK_WIDGET(self), GTK_ALIGN_CENTER);
    gtk_widget_set_valign(GTK_WIDGET(self), GTK_ALIGN_CENTER);
    GtkWidget *title = gtk_label_new(NULL);
    gtk_label_set_markup(GTK_LABEL(title), "<span size='x-large' weight='bold'>VolVis</span>");
    gtk_box_append(box, title);
    GtkWidget *hint = gtk_label_new("Open a volume, a mesh or a session, or drop files here.");
    gtk_widget_add_css_class(hint, "dim-label");
    gtk_box_append(box, hint);
    gtk_box_append(box, big_button("Open a file…", "win.open"));
    GtkWidget *row = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 8);
    gtk_widget_set_halign(row, GTK_ALIGN_CENTER);
    GtkWidget *raw = gtk_button_new_with_label("Import raw…");
    gtk_actionable_set_action_name(GTK_ACTIONABLE(raw), "win.import-raw");
    GtkWidget *dicom = gtk_button_new_with_label("Browse DICOM…");
    gtk_actionable_set_action_name(GTK_ACTIONABLE(dicom), "win.browse-dicom");
    gtk_box_append(GTK_BOX(row), raw);
    gtk_box_append(GTK_BOX(row), dicom);
    gtk_box_append(box, row);
    self->recent_title = gtk_label_new(NULL);
    gtk_label_set_markup(GTK_LABEL(self->recent_title), "<b>Recent files</b>");
    gtk_widget_set_margin_top(self->recent_title, 12);
    gtk_box_append(box, self->recent_title);
    self->recent_box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_accessible_update_relation(GTK_ACCESSIBLE(self->recent_box),
                                   GTK_ACCESSIBLE_RELATION_LABELLED_BY, self->recent_title, NULL,
                                   -1);
    gtk_box_append(box, self->recent_box);
    self->changed_id = g_signal_connect(gtk_recent_manager_get_default(), "changed",
                                        G_CALLBACK(recent_changed), self);
    vvg_start_page_refresh(self);
}

GtkWidget *
vvg_start_page_new(void) {
    return g_object_new(VVG_TYPE_START_PAGE, NULL);
}
