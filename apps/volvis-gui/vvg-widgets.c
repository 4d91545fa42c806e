/* Form-building helpers shared by the GUI's pages (vvg-widgets.h). */
#include "vvg-widgets.h"

GtkWidget *
vvg_section(GtkWidget *box, const char *title) {
    GtkWidget *l = gtk_label_new(NULL);
    char *m = g_markup_printf_escaped("<b>%s</b>", title);
    gtk_label_set_markup(GTK_LABEL(l), m);
    g_free(m);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_widget_set_margin_top(l, 8);
    gtk_box_append(GTK_BOX(box), l);
    GtkWidget *grid = gtk_grid_new();
    gtk_grid_set_row_spacing(GTK_GRID(grid), 3);
    gtk_grid_set_column_spacing(GTK_GRID(grid), 6);
    gtk_box_append(GTK_BOX(box), grid);
    return grid;
}

int
vvg_grid_rows(GtkWidget *grid) {
    int n = 0;
    for (GtkWidget *c = gtk_widget_get_first_child(grid); c; c = gtk_widget_get_next_sibling(c)) {
        int r;
        gtk_grid_query_child(GTK_GRID(grid), c, NULL, &r, NULL, NULL);
        n = r + 1 > n ? r + 1 : n;
    }
    return n;
}

GtkWidget *
vvg_row(GtkWidget *grid, const char *label, GtkWidget *w) {
    int r = vvg_grid_rows(grid);
    GtkWidget *l = gtk_label_new(label);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_grid_attach(GTK_GRID(grid), l, 0, r, 1, 1);
    gtk_widget_set_hexpand(w, TRUE);
    gtk_grid_attach(GTK_GRID(grid), w, 1, r, 1, 1);
    return w;
}

GtkWidget *
vvg_spin(double lo, double hi, double step, int digits, double value) {
    GtkWidget *s = gtk_spin_button_new_with_range(lo, hi, step);
    gtk_spin_button_set_digits(GTK_SPIN_BUTTON(s), (guint)digits);
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(s), value);
    return s;
}

void
vvg_show_error(GtkWidget *any, const char *what, const char *message) {
    if (!message || !*message)
        message = "unknown error";
    g_printerr("volvis-gui: %s: %s\n", what, message);
    GtkRoot *root = any ? gtk_widget_get_root(any) : NULL;
    GtkWidget *d = gtk_message_dialog_new(root && GTK_IS_WINDOW(root) ? GTK_WINDOW(root) : NULL,
                                          GTK_DIALOG_MODAL | GTK_DIALOG_DESTROY_WITH_PARENT,
                                          GTK_MESSAGE_ERROR, GTK_BUTTONS_CLOSE, "%s", what);
    gtk_message_dialog_format_secondary_text(GTK_MESSAGE_DIALOG(d), "%s", message);
    gtk_window_set_title(GTK_WINDOW(d), "VolVis: error");
    g_signal_connect(d, "response", G_CALLBACK(gtk_window_destroy), NULL);
    gtk_widget_show(d);
}
