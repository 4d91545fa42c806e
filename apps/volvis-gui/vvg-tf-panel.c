/* VvgTfPanel: segmentation and transfer functions of the selected object (vvg-tf-panel.h). */
#include "vvg-tf-panel.h"
#include "vvg-widgets.h"

#include "vvg-marks.h"
#include "vvg-preset-gallery.h"
#include "vvg-tf-editor.h"
#include "vvg-tf2d-editor.h"

struct _VvgTfPanel {
    GtkBox parent;
    VvgDocument *doc;
    gboolean updating; /* set while widgets are filled from the World */
    GtkWidget *seg_mode, *threshold, *render_mode, *isovalue, *attenuation, *step;
    VvgTfEditor *tf_editor;
    VvgTf2dEditor *tf2d_editor;
    GtkWidget *w2d_color, *w2d_opacity;
    GtkWidget *editing; /* which channel of a multi-channel object the editor edits */
    VvgMarks *marks;    /* the slice views' window and level */
    GtkWidget *wl_title, *wl_grid, *window, *level;
};

G_DEFINE_TYPE(VvgTfPanel, vvg_tf_panel, GTK_TYPE_BOX)

/* The window and level rows from the marks (the slice views' automatic
 * values until they are set). */
static void
fill_window(VvgTfPanel *self, const vv_object *o) {
    gboolean grey = o && o->volume && o->n_channels == 0;
    gtk_widget_set_visible(self->wl_title, grey);
    gtk_widget_set_visible(self->wl_grid, grey);
    if (!grey)
        return;
    double win, lev;
    vvg_marks_window_for(self->marks, o->volume, &win, &lev);
    double lo = o->volume->range[0], hi = o->volume->range[1];
    double span = hi > lo ? hi - lo : 1;
    gtk_spin_button_set_range(GTK_SPIN_BUTTON(self->window), span * 1e-4, span * 4);
    gtk_spin_button_set_range(GTK_SPIN_BUTTON(self->level), lo - span, hi + span);
    vvg_set_spin(self->window, win);
    vvg_set_spin(self->level, lev);
}

static void
fill(VvgTfPanel *self) {
    self->updating = TRUE;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (o) {
        gtk_drop_down_set_selected(GTK_DROP_DOWN(self->seg_mode), o->segmentation);
        if (o->volume) {
            double lo = o->volume->range[0], hi = o->volume->range[1];
            gtk_spin_button_set_range(GTK_SPIN_BUTTON(self->threshold), lo, hi > lo ? hi : lo + 1);
            gtk_spin_button_set_range(GTK_SPIN_BUTTON(self->isovalue), lo, hi > lo ? hi : lo + 1);
        }
        vvg_set_spin(self->threshold, o->threshold);
        gtk_drop_down_set_selected(GTK_DROP_DOWN(self->render_mode), o->mode);
        vvg_set_spin(self->isovalue, o->isovalue);
        vvg_set_spin(self->attenuation, o->attenuation);
        vvg_set_spin(self->step, o->step);
    }
    fill_window(self, o);
    int c = vvg_document_edited_channel(self->doc);
    gtk_widget_set_visible(self->editing, c >= 0);
    if (c >= 0) {
        g_autofree char *t = g_strdup_printf(
            "Editing channel \"%s\" (another: its \"edit TF\" on the Channels and time page)",
            o->channels[c].name);
        gtk_label_set_text(GTK_LABEL(self->editing), t);
    }
    self->updating = FALSE;
}

/* The segmentation widgets applied to the selected object: one undo step. */
static void
apply(VvgTfPanel *self) {
    vv_object *o = vvg_document_selected_object(self->doc);
    if (self->updating || !o)
        return;
    vvg_document_begin_edit(self->doc, "segmentation");
    o->segmentation = (vv_segmentation)gtk_drop_down_get_selected(GTK_DROP_DOWN(self->seg_mode));
    o->threshold = vvg_spin_value(self->threshold);
    o->mode = (vv_render_mode)gtk_drop_down_get_selected(GTK_DROP_DOWN(self->render_mode));
    o->isovalue = vvg_spin_value(self->isovalue);
    o->attenuation = vvg_spin_value(self->attenuation);
    o->step = vvg_spin_value(self->step);
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

static void
log_toggled(GtkCheckButton *b, gpointer user) {
    VvgTfPanel *self = user;
    vvg_tf_editor_set_log(self->tf_editor, gtk_check_button_get_active(b));
}

static void
tf_color_set(GtkColorButton *b, gpointer user) {
    VvgTfPanel *self = user;
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(b), &c);
    vvg_tf_editor_set_color(self->tf_editor, &c);
}

static void
add_rectangle(GtkButton *b, gpointer user) {
    (void)b;
    VvgTfPanel *self = user;
    vvg_tf2d_editor_add(self->tf2d_editor, VV_TF2D_RECTANGLE);
    fill(self);
}

static void
add_triangle(GtkButton *b, gpointer user) {
    (void)b;
    VvgTfPanel *self = user;
    vvg_tf2d_editor_add(self->tf2d_editor, VV_TF2D_TRIANGLE);
    fill(self);
}

static void
w2d_style(GtkColorButton *b, gpointer user) {
    (void)b;
    VvgTfPanel *self = user;
    if (self->updating)
        return;
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(self->w2d_color), &c);
    vvg_tf2d_editor_set_style(self->tf2d_editor, &c, vvg_spin_value(self->w2d_opacity));
}

static void
w2d_style_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    w2d_style(NULL, user);
}

/* window or level typed: the slice views' (no undo step: the marks are the
 * views' display, not the World's) */
static void
on_window(GtkSpinButton *s, gpointer user) {
    (void)s;
    VvgTfPanel *self = user;
    if (self->updating)
        return;
    self->updating = TRUE;
    vvg_marks_set_window(self->marks, vvg_spin_value(self->window), vvg_spin_value(self->level));
    self->updating = FALSE;
}

static void
marks_changed(VvgMarks *m, gpointer user) {
    (void)m;
    VvgTfPanel *self = user;
    if (self->updating)
        return;
    self->updating = TRUE;
    fill_window(self, vvg_document_selected_object(self->doc));
    self->updating = FALSE;
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    fill(user);
}

static void
vvg_tf_panel_dispose(GObject *o) {
    VvgTfPanel *self = VVG_TF_PANEL(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    if (self->marks) {
        g_signal_handlers_disconnect_by_data(self->marks, self);
        g_clear_object(&self->marks);
    }
    G_OBJECT_CLASS(vvg_tf_panel_parent_class)->dispose(o);
}

static void
vvg_tf_panel_class_init(VvgTfPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_tf_panel_dispose;
}

static void
vvg_tf_panel_init(VvgTfPanel *self) {
    vvg_vbox_init(GTK_WIDGET(self));
}

static GtkWidget *
wire_spin(VvgTfPanel *self, GtkWidget *s) {
    g_signal_connect(s, "value-changed", G_CALLBACK(on_spin), self);
    return s;
}

static GtkWidget *
wire_drop(VvgTfPanel *self, const char *const *items) {
    GtkWidget *d = gtk_drop_down_new_from_strings(items);
    g_signal_connect(d, "notify::selected", G_CALLBACK(on_dropdown), self);
    return d;
}

/* The 1-D editor, its switches and its presets. */
static void
build_tf(VvgTfPanel *self) {
    GtkWidget *box = GTK_WIDGET(self);
    self->editing = gtk_label_new("");
    gtk_label_set_wrap(GTK_LABEL(self->editing), TRUE);
    gtk_label_set_xalign(GTK_LABEL(self->editing), 0);
    gtk_box_append(GTK_BOX(box), self->editing);
    self->tf_editor = vvg_tf_editor_new(self->doc);
    gtk_box_append(GTK_BOX(box), GTK_WIDGET(self->tf_editor));
    GtkWidget *tb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    GtkWidget *lg = gtk_check_button_new_with_label("log histogram");
    g_signal_connect(lg, "toggled", G_CALLBACK(log_toggled), self);
    GtkWidget *tc = gtk_color_button_new();
    gtk_widget_set_tooltip_text(tc, "colour of new colour points");
    g_signal_connect(tc, "color-set", G_CALLBACK(tf_color_set), self);
    GtkWidget *tl = gtk_label_new("new colour");
    vvg_label_for(tc, tl);
    vvg_label_for(gtk_widget_get_first_child(tc), tl);
    gtk_box_append(GTK_BOX(tb), lg);
    gtk_box_append(GTK_BOX(tb), tl);
    gtk_box_append(GTK_BOX(tb), tc);
    gtk_box_append(GTK_BOX(box), tb);
    vvg_section(box, "Presets (thumbnails of this volume)");
    gtk_box_append(GTK_BOX(box), vvg_preset_gallery_new(self->doc));
}

/* The 2-D transfer function over value x gradient magnitude. */
static void
build_tf2d(VvgTfPanel *self) {
    GtkWidget *g =
        vvg_section(GTK_WIDGET(self), "2-D transfer function (value × gradient magnitude)");
    self->tf2d_editor = vvg_tf2d_editor_new(self->doc);
    gtk_grid_attach(GTK_GRID(g), GTK_WIDGET(self->tf2d_editor), 0, 0, 2, 1);
    GtkWidget *wb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    GtkWidget *add_r = gtk_button_new_with_label("Add rectangle");
    GtkWidget *add_t = gtk_button_new_with_label("Add triangle");
    g_signal_connect(add_r, "clicked", G_CALLBACK(add_rectangle), self);
    g_signal_connect(add_t, "clicked", G_CALLBACK(add_triangle), self);
    gtk_box_append(GTK_BOX(wb), add_r);
    gtk_box_append(GTK_BOX(wb), add_t);
    gtk_grid_attach(GTK_GRID(g), wb, 0, 1, 2, 1);
    self->w2d_color = vvg_row(g, "widget colour", gtk_color_button_new());
    self->w2d_opacity = vvg_row(g, "widget opacity", vvg_spin(0, 1, 0.05, 2, 0.5));
    g_signal_connect(self->w2d_color, "color-set", G_CALLBACK(w2d_style), self);
    g_signal_connect(self->w2d_opacity, "value-changed", G_CALLBACK(w2d_style_spin), self);
}

GtkWidget *
vvg_tf_panel_new(VvgDocument *doc, VvgMarks *marks) {
    VvgTfPanel *self = g_object_new(VVG_TYPE_TF_PANEL, NULL);
    self->doc = g_object_ref(doc);
    self->marks = g_object_ref(marks);
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "Segmentation");
    /* in vv_segmentation's order; "labels": a label volume (Filtering) */
    static const char *const segs[] = {"transfer function", "threshold", "2-D transfer function",
                                       "labels", NULL};
    self->seg_mode = vvg_row(g, "by", wire_drop(self, segs));
    self->threshold = vvg_row(g, "threshold", wire_spin(self, vvg_spin0(-1e9, 1e9, 1, 2)));
    /* in vv_render_mode's order */
    static const char *const modes[] = {"composite",      "MIP", "MinIP", "X-ray", "isosurface",
                                        "attenuated MIP", NULL};
    self->render_mode = vvg_row(g, "mode", wire_drop(self, modes));
    self->isovalue = vvg_row(g, "isovalue", wire_spin(self, vvg_spin0(-1e9, 1e9, 1, 2)));
    /* napari's slider spans 0..0.5 */
    self->attenuation = vvg_row(g, "attenuation", wire_spin(self, vvg_spin0(0, 5, 0.01, 3)));
    self->step = vvg_row(g, "sample step", wire_spin(self, vvg_spin0(0.05, 8, 0.05, 2)));
    /* what a right drag in a slice view sets, typed */
    g = vvg_section(GTK_WIDGET(self), "Slice views: window and level");
    self->wl_grid = g;
    self->wl_title = gtk_widget_get_prev_sibling(g); /* the section's title */
    self->window = vvg_row(g, "window", vvg_spin(1e-4, 1e9, 1, 2, 1));
    self->level = vvg_row(g, "level", vvg_spin0(-1e9, 1e9, 1, 2));
    g_signal_connect(self->window, "value-changed", G_CALLBACK(on_window), self);
    g_signal_connect(self->level, "value-changed", G_CALLBACK(on_window), self);
    g_signal_connect(marks, "changed", G_CALLBACK(marks_changed), self);
    build_tf(self);
    build_tf2d(self);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), self);
    fill(self);
    return GTK_WIDGET(self);
}
