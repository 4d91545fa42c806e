/* Form-building helpers shared by the GUI's pages (vvg-widgets.h). */
#include "vvg-widgets.h"

#include <math.h>

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

GtkWidget *
vvg_section_folded(GtkWidget *box, const char *title) {
    GtkWidget *grid = gtk_grid_new();
    gtk_grid_set_row_spacing(GTK_GRID(grid), 3);
    gtk_grid_set_column_spacing(GTK_GRID(grid), 6);
    GtkWidget *e = gtk_expander_new(NULL);
    GtkWidget *l = gtk_label_new(NULL);
    char *m = g_markup_printf_escaped("<b>%s</b>", title);
    gtk_label_set_markup(GTK_LABEL(l), m);
    g_free(m);
    gtk_expander_set_label_widget(GTK_EXPANDER(e), l);
    gtk_expander_set_child(GTK_EXPANDER(e), grid);
    gtk_widget_set_margin_top(e, 8);
    vvg_name(e, title);
    gtk_box_append(GTK_BOX(box), e);
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

/* Runs in the capture phase on the value's own widget, before the value
 * sees the wheel (the event's target is the value even when the pointer
 * has since moved off it: GTK updates the widget under the pointer on
 * motion only). */
static gboolean
wheel_capture(GtkEventControllerScroll *c, double dx, double dy, gpointer user) {
    (void)dx;
    (void)user;
    GtkWidget *value = gtk_event_controller_get_widget(GTK_EVENT_CONTROLLER(c));
    GtkRoot *root = gtk_widget_get_root(value);
    GtkWidget *focus = root ? gtk_root_get_focus(root) : NULL;
    if (focus && (focus == value || gtk_widget_is_ancestor(focus, value)))
        return FALSE; /* focused: the value takes the wheel */
    GtkWidget *sw = gtk_widget_get_ancestor(value, GTK_TYPE_SCROLLED_WINDOW);
    if (sw) {
        GtkAdjustment *adj = gtk_scrolled_window_get_vadjustment(GTK_SCROLLED_WINDOW(sw));
        double page = gtk_adjustment_get_page_size(adj);
        /* a notch scrolls as GtkScrolledWindow scrolls it: page^(2/3) */
        gtk_adjustment_set_value(adj, gtk_adjustment_get_value(adj) + dy * pow(page, 2.0 / 3.0));
    }
    return TRUE;
}

void
vvg_wheel_when_focused(GtkWidget *w) {
    if (g_object_get_data(G_OBJECT(w), "vvg-wheel"))
        return;
    GtkEventController *c = gtk_event_controller_scroll_new(GTK_EVENT_CONTROLLER_SCROLL_VERTICAL |
                                                            GTK_EVENT_CONTROLLER_SCROLL_DISCRETE);
    gtk_event_controller_set_propagation_phase(c, GTK_PHASE_CAPTURE);
    g_signal_connect(c, "scroll", G_CALLBACK(wheel_capture), NULL);
    gtk_widget_add_controller(w, c);
    g_object_set_data(G_OBJECT(w), "vvg-wheel", c);
}

void
vvg_wheel_when_focused_all(GtkWidget *root) {
    if (GTK_IS_SPIN_BUTTON(root) || GTK_IS_RANGE(root) || GTK_IS_DROP_DOWN(root)) {
        vvg_wheel_when_focused(root);
        return;
    }
    for (GtkWidget *c = gtk_widget_get_first_child(root); c; c = gtk_widget_get_next_sibling(c))
        vvg_wheel_when_focused_all(c);
}

void
vvg_label_for(GtkWidget *w, GtkWidget *label) {
    gtk_accessible_update_relation(GTK_ACCESSIBLE(w), GTK_ACCESSIBLE_RELATION_LABELLED_BY, label,
                                   NULL, -1);
}

void
vvg_name(GtkWidget *w, const char *name) {
    gtk_accessible_update_property(GTK_ACCESSIBLE(w), GTK_ACCESSIBLE_PROPERTY_LABEL, name, -1);
}

GtkWidget *
vvg_row(GtkWidget *grid, const char *label, GtkWidget *w) {
    int r = vvg_grid_rows(grid);
    GtkWidget *l = gtk_label_new(label);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_grid_attach(GTK_GRID(grid), l, 0, r, 1, 1);
    gtk_widget_set_hexpand(w, TRUE);
    gtk_grid_attach(GTK_GRID(grid), w, 1, r, 1, 1);
    vvg_label_for(w, l);
    /* the button inside a colour button or a drop-down is what takes the
     * focus: it carries the name too */
    GtkWidget *inner = gtk_widget_get_first_child(w);
    if (inner && (GTK_IS_COLOR_BUTTON(w) || GTK_IS_DROP_DOWN(w)))
        vvg_label_for(inner, l);
    vvg_wheel_when_focused_all(w);
    return w;
}

GtkWidget *
vvg_spin(double lo, double hi, double step, int digits, double value) {
    GtkWidget *s = gtk_spin_button_new_with_range(lo, hi, step);
    gtk_spin_button_set_digits(GTK_SPIN_BUTTON(s), (guint)digits);
    /* as wide as a value usually needs, not as the range's widest value: the
     * side bar stays narrow and the views get the window; the
     * field scrolls a longer value */
    gtk_editable_set_width_chars(GTK_EDITABLE(s), 7);
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(s), value);
    vvg_wheel_when_focused(s);
    return s;
}

GtkWidget *
vvg_spin0(double lo, double hi, double step, int digits) {
    return vvg_spin(lo, hi, step, digits, lo > 0 ? lo : hi < 0 ? hi : 0);
}

double
vvg_spin_value(GtkWidget *s) {
    return gtk_spin_button_get_value(GTK_SPIN_BUTTON(s));
}

void
vvg_set_spin(GtkWidget *s, double v) {
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(s), v);
}

GdkRGBA
vvg_rgba(vv_vec3 c) {
    return (GdkRGBA){(float)c.x, (float)c.y, (float)c.z, 1};
}

vv_vec3
vvg_vec3(const GdkRGBA *c) {
    return vv_vec3_make(c->red, c->green, c->blue);
}

GtkWidget *
vvg_action_button(const char *label, const char *action) {
    GtkWidget *b = gtk_button_new_with_label(label);
    gtk_actionable_set_action_name(GTK_ACTIONABLE(b), action);
    return b;
}

const char *
vvg_unit_label(const vv_volume *v) {
    return vv_volume_length_unit(v);
}

void
vvg_vbox_init(GtkWidget *box) {
    gtk_orientable_set_orientation(GTK_ORIENTABLE(box), GTK_ORIENTATION_VERTICAL);
    gtk_box_set_spacing(GTK_BOX(box), 4);
}

GtkWidget *
vvg_page_box(void) {
    GtkWidget *b = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_widget_set_margin_start(b, 8);
    gtk_widget_set_margin_end(b, 8);
    gtk_widget_set_margin_bottom(b, 8);
    return b;
}

void
vvg_close_on_escape(GtkWindow *window) {
    GtkEventController *sc = gtk_shortcut_controller_new();
    gtk_shortcut_controller_set_scope(GTK_SHORTCUT_CONTROLLER(sc), GTK_SHORTCUT_SCOPE_LOCAL);
    GtkShortcutAction *close = gtk_named_action_new("window.close");
    gtk_shortcut_controller_add_shortcut(
        GTK_SHORTCUT_CONTROLLER(sc),
        gtk_shortcut_new(
            gtk_alternative_trigger_new(gtk_shortcut_trigger_parse_string("Escape"),
                                        gtk_shortcut_trigger_parse_string("<Control>w")),
            close));
    gtk_widget_add_controller(GTK_WIDGET(window), sc);
}

GtkWidget *
vvg_scrolled(GtkWidget *child) {
    GtkWidget *s = gtk_scrolled_window_new();
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(s), GTK_POLICY_NEVER, GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_child(GTK_SCROLLED_WINDOW(s), child);
    gtk_widget_set_vexpand(s, TRUE);
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
