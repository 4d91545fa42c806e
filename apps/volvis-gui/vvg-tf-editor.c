/* VvgTfEditor: transfer-function editing over the histogram, with axes (vvg-tf-editor.h). */
#include "vvg-tf-editor.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "vvg-models.h"

#define STRIP 14.0  /* height of the colour strip, pixels */
#define LEFT 34.0   /* room for the opacity axis */
#define BOTTOM 16.0 /* room for the value axis under the strip */
#define TOP 6.0
#define RIGHT 8.0
#define RADIUS 6.0 /* pick radius of a point, pixels */
#define HIST_BINS 256

struct _VvgTfEditor {
    GtkBox parent;
    VvgDocument *doc;
    GtkWidget *canvas, *readout;
    GtkWidget *sel_box, *sel_title, *sel_value, *sel_opacity, *sel_color, *sel_delete;
    vv_tf drawn; /* the function last drawn, to skip redraws of unchanged ones */
    const vv_object *drawn_object;
    gboolean log, updating;
    GdkRGBA color;
    int drag_point;              /* opacity point being dragged, or -1 */
    int drag_color;              /* colour point being dragged, or -1 */
    int sel_point, sel_is_color; /* the point the numbers show, -1: none */
    double drag_x0, drag_y0;
    const vv_volume *hist_volume;
    uint64_t hist_modified, hist_total;
    uint64_t hist[HIST_BINS];
};

G_DEFINE_TYPE(VvgTfEditor, vvg_tf_editor, GTK_TYPE_BOX)

static vv_object *
volume_object(VvgTfEditor *ed) {
    vv_object *o = vvg_document_selected_object(ed->doc);
    return o && o->type == VV_OBJECT_VOLUME && o->volume ? o : NULL;
}

/* The transfer function edited: the channel picked on the Channels page
 * (vvg_document_edited_channel) of a multi-channel object, else the object's. */
static vv_tf *
edited_tf(VvgTfEditor *ed, vv_object *o) {
    int c = vvg_document_edited_channel(ed->doc);
    return c >= 0 && c < o->n_channels ? &o->channels[c].tf : &o->tf;
}

/* The voxels under the edited function (its histogram and value axis). */
static const vv_volume *
edited_volume(VvgTfEditor *ed, const vv_object *o) {
    int c = vvg_document_edited_channel(ed->doc);
    return c >= 0 && c < o->n_channels ? o->channels[c].volume : o->volume;
}

/* The plot's axes: data values along x, opacity up, in plot coordinates
 * (the canvas translated by LEFT, TOP). */
static vvg_tf_axes
axes(VvgTfEditor *ed, const vv_object *o) {
    double W = gtk_widget_get_width(ed->canvas), H = gtk_widget_get_height(ed->canvas);
    const vv_volume *v = edited_volume(ed, o);
    vvg_tf_axes a = {v->range[0], v->range[1], fmax(W - LEFT - RIGHT, 8),
                     fmax(H - TOP - STRIP - BOTTOM, 8)};
    if (!(a.vmax > a.vmin))
        a.vmax = a.vmin + 1;
    return a;
}

static void
update_histogram(VvgTfEditor *ed, const vv_volume *v) {
    if (ed->hist_volume == v && ed->hist_modified == v->modified)
        return;
    memset(ed->hist, 0, sizeof ed->hist);
    double hi = v->range[1] > v->range[0] ? v->range[1] : v->range[0] + 1;
    if (vv_volume_histogram(v, HIST_BINS, v->range[0], hi, ed->hist) != VV_OK)
        memset(ed->hist, 0, sizeof ed->hist);
    ed->hist_total = 0;
    for (int i = 0; i < HIST_BINS; i++)
        ed->hist_total += ed->hist[i];
    ed->hist_volume = v;
    ed->hist_modified = v->modified;
}

static void
draw_histogram(VvgTfEditor *ed, cairo_t *cr, const vvg_tf_axes *a) {
    /* the largest bin but the first (background) sets the scale */
    double maxc = 1;
    for (int i = 1; i < HIST_BINS; i++) {
        double c = ed->log ? log1p((double)ed->hist[i]) : (double)ed->hist[i];
        maxc = c > maxc ? c : maxc;
    }
    cairo_set_source_rgb(cr, 0.35, 0.35, 0.4);
    for (int i = 0; i < HIST_BINS; i++) {
        double c = ed->log ? log1p((double)ed->hist[i]) : (double)ed->hist[i];
        double h = fmin(1.0, c / maxc) * a->height;
        cairo_rectangle(cr, i * a->width / HIST_BINS, a->height - h, a->width / HIST_BINS + 0.5, h);
    }
    cairo_fill(cr);
}

/* Ticks and labels: opacity 0, 0.5, 1 on the left; round data values under
 * the colour strip. */
static void
draw_axes(cairo_t *cr, const vvg_tf_axes *a) {
    cairo_set_font_size(cr, 10);
    cairo_set_source_rgb(cr, 0.75, 0.75, 0.78);
    cairo_set_line_width(cr, 1);
    for (int k = 0; k <= 2; k++) {
        double op = 0.5 * k, y = floor(vvg_tf_y(a, op)) + 0.5;
        char t[16];
        snprintf(t, sizeof t, "%g", op);
        cairo_move_to(cr, -LEFT + 4, y + 4);
        cairo_show_text(cr, t);
        cairo_move_to(cr, -4, y);
        cairo_line_to(cr, 0, y);
    }
    cairo_stroke(cr);
    double span = a->vmax - a->vmin;
    double step = pow(10, floor(log10(span / 4)));
    if (span / step > 10)
        step *= span / step > 20 ? 5 : 2;
    double last_right = -1e9;
    for (double v = ceil(a->vmin / step) * step; v <= a->vmax + 1e-9 * span; v += step) {
        double x = floor(vvg_tf_x(a, v)) + 0.5;
        char t[24];
        snprintf(t, sizeof t, "%g", fabs(v) < 1e-9 * span ? 0.0 : v);
        cairo_text_extents_t e;
        cairo_text_extents(cr, t, &e);
        double tx = fmin(fmax(x - e.width / 2, -LEFT + 2), a->width + RIGHT - e.width - 1);
        cairo_move_to(cr, x, a->height + STRIP);
        cairo_line_to(cr, x, a->height + STRIP + 3);
        cairo_stroke(cr);
        if (tx > last_right + 4) {
            cairo_move_to(cr, tx, a->height + STRIP + BOTTOM - 2);
            cairo_show_text(cr, t);
            last_right = tx + e.width;
        }
    }
}

static void
draw_function(VvgTfEditor *ed, cairo_t *cr, const vvg_tf_axes *a, const vv_tf *tf) {
    for (int x = 0; x < (int)a->width; x++) { /* the colour strip */
        vv_vec3 c = vv_tf_eval_color(tf, vvg_tf_value(a, x + 0.5));
        cairo_set_source_rgb(cr, c.x, c.y, c.z);
        cairo_rectangle(cr, x, a->height, 1, STRIP);
        cairo_fill(cr);
    }
    for (int i = 0; i < tf->n_color; i++) {
        double x = vvg_tf_x(a, tf->color[i].value);
        gboolean sel = ed->sel_is_color && ed->sel_point == i;
        cairo_set_source_rgb(cr, sel ? 1 : 0.9, sel ? 0.3 : 0.9, sel ? 0.3 : 0.9);
        cairo_move_to(cr, x, a->height);
        cairo_line_to(cr, x - 5, a->height + STRIP);
        cairo_line_to(cr, x + 5, a->height + STRIP);
        cairo_close_path(cr);
        cairo_stroke(cr);
    }
    cairo_set_source_rgb(cr, 1.0, 0.8, 0.2); /* the opacity curve */
    cairo_set_line_width(cr, 1.5);
    for (int x = 0; x < (int)a->width; x++) {
        double y = vvg_tf_y(a, vv_tf_eval_opacity(tf, vvg_tf_value(a, x + 0.5)));
        (x == 0 ? cairo_move_to : cairo_line_to)(cr, x, y);
    }
    cairo_stroke(cr);
    for (int i = 0; i < tf->n_opacity; i++) {
        double x = vvg_tf_x(a, tf->opacity[i].value), y = vvg_tf_y(a, tf->opacity[i].opacity);
        cairo_arc(cr, x, y, 4, 0, 2 * G_PI);
        vv_vec3 c = vv_tf_eval_color(tf, tf->opacity[i].value);
        cairo_set_source_rgb(cr, c.x, c.y, c.z);
        cairo_fill_preserve(cr);
        gboolean sel = !ed->sel_is_color && ed->sel_point == i;
        cairo_set_source_rgb(cr, sel || i == ed->drag_point ? 1 : 0.2, 0.2, 0.2);
        cairo_stroke(cr);
    }
}

static void
canvas_draw(GtkDrawingArea *area, cairo_t *cr, int W, int H, gpointer user) {
    (void)area;
    VvgTfEditor *ed = user;
    cairo_set_source_rgb(cr, 0.12, 0.12, 0.14);
    cairo_paint(cr);
    vv_object *o = volume_object(ed);
    ed->drawn_object = o;
    if (!o) {
        cairo_set_source_rgb(cr, 0.6, 0.6, 0.6);
        cairo_move_to(cr, 12, H / 2.0);
        cairo_show_text(cr, "select a volume object");
        (void)W;
        return;
    }
    ed->drawn = *edited_tf(ed, o);
    update_histogram(ed, edited_volume(ed, o));
    vvg_tf_axes a = axes(ed, o);
    cairo_translate(cr, LEFT, TOP);
    draw_histogram(ed, cr, &a);
    draw_axes(cr, &a);
    draw_function(ed, cr, &a, edited_tf(ed, o));
}

/* ---- the selected point's numbers ---------------------------------------------------- */

static void
fill_selection(VvgTfEditor *ed) {
    vv_object *o = volume_object(ed);
    const vv_tf *tf = o ? edited_tf(ed, o) : NULL;
    int n = !tf ? 0 : ed->sel_is_color ? tf->n_color : tf->n_opacity;
    gboolean on = tf && ed->sel_point >= 0 && ed->sel_point < n;
    gtk_widget_set_sensitive(ed->sel_box, on);
    if (!on) {
        gtk_label_set_text(GTK_LABEL(ed->sel_title), "Selected point: none (click one)");
        return;
    }
    ed->updating = TRUE;
    const vv_volume *v = edited_volume(ed, o);
    double lo = v->range[0], hi = v->range[1] > lo ? v->range[1] : lo + 1;
    gtk_spin_button_set_range(GTK_SPIN_BUTTON(ed->sel_value), lo, hi);
    if (ed->sel_is_color) {
        vvg_set_spin(ed->sel_value, tf->color[ed->sel_point].value);
        GdkRGBA c = vvg_rgba(tf->color[ed->sel_point].color);
        gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(ed->sel_color), &c);
        gtk_widget_set_sensitive(ed->sel_opacity, FALSE);
        gtk_widget_set_sensitive(ed->sel_color, TRUE);
        gtk_label_set_text(GTK_LABEL(ed->sel_title), "Selected colour point");
    } else {
        vvg_set_spin(ed->sel_value, tf->opacity[ed->sel_point].value);
        vvg_set_spin(ed->sel_opacity, tf->opacity[ed->sel_point].opacity);
        gtk_widget_set_sensitive(ed->sel_opacity, TRUE);
        gtk_widget_set_sensitive(ed->sel_color, FALSE);
        gtk_label_set_text(GTK_LABEL(ed->sel_title), "Selected opacity point");
    }
    ed->updating = FALSE;
}

/* Typed numbers of the selected point: one undo step each, the point kept
 * between its neighbours as a drag keeps it. */
static void
selection_edited(VvgTfEditor *ed) {
    vv_object *o = volume_object(ed);
    if (ed->updating || !o || ed->sel_point < 0)
        return;
    vvg_document_begin_edit(ed->doc, "edit transfer-function point");
    o = volume_object(ed);
    vv_tf *tf = edited_tf(ed, o);
    double v = vvg_spin_value(ed->sel_value);
    if (ed->sel_is_color && ed->sel_point < tf->n_color) {
        int i = ed->sel_point;
        double lo = i > 0 ? tf->color[i - 1].value : -INFINITY;
        double hi = i + 1 < tf->n_color ? tf->color[i + 1].value : INFINITY;
        tf->color[i].value = fmin(fmax(v, lo), hi);
        GdkRGBA c;
        gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(ed->sel_color), &c);
        tf->color[ed->sel_point].color = vvg_vec3(&c);
    } else if (!ed->sel_is_color && ed->sel_point < tf->n_opacity) {
        int i = ed->sel_point;
        double lo = i > 0 ? tf->opacity[i - 1].value : -INFINITY;
        double hi = i + 1 < tf->n_opacity ? tf->opacity[i + 1].value : INFINITY;
        tf->opacity[i].value = fmin(fmax(v, lo), hi);
        tf->opacity[i].opacity = fmin(fmax(vvg_spin_value(ed->sel_opacity), 0), 1);
    }
    vvg_document_changed(ed->doc);
    fill_selection(ed);
    gtk_widget_queue_draw(ed->canvas);
}

static void
sel_spin_changed(GtkSpinButton *s, gpointer user) {
    (void)s;
    selection_edited(user);
}

static void
sel_color_set(GtkColorButton *b, gpointer user) {
    (void)b;
    selection_edited(user);
}

static void
sel_delete_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgTfEditor *ed = user;
    vv_object *o = volume_object(ed);
    if (!o || ed->sel_point < 0)
        return;
    vvg_document_begin_edit(ed->doc, "delete transfer-function point");
    o = volume_object(ed);
    if (ed->sel_is_color)
        vvg_tf_delete_color(edited_tf(ed, o), ed->sel_point);
    else
        vvg_tf_delete_point(edited_tf(ed, o), ed->sel_point);
    ed->sel_point = -1;
    vvg_document_changed(ed->doc);
    fill_selection(ed);
    gtk_widget_queue_draw(ed->canvas);
}

/* ---- input ------------------------------------------------------------------------- */

static void
pressed(GtkGestureClick *g, int n_press, double x, double y, gpointer user) {
    (void)n_press;
    VvgTfEditor *ed = user;
    vv_object *o = volume_object(ed);
    ed->drag_point = ed->drag_color = -1;
    if (!o)
        return;
    x -= LEFT;
    y -= TOP;
    guint button = gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(g));
    vvg_tf_axes a = axes(ed, o);
    gboolean in_strip = y > a.height;
    vvg_document_begin_edit(ed->doc, "edit transfer function");
    o = volume_object(ed); /* unchanged by begin_edit, which copies */
    vv_tf *tf = edited_tf(ed, o);
    if (in_strip) {
        int i = vvg_tf_hit_color(tf, &a, x, RADIUS);
        if (button == 3) {
            vvg_tf_delete_color(tf, i);
        } else if (i >= 0) {
            ed->drag_color = i;
        } else {
            vv_vec3 c = {ed->color.red, ed->color.green, ed->color.blue};
            ed->drag_color = vvg_tf_add_color(tf, &a, x, c);
        }
        ed->sel_is_color = TRUE;
        ed->sel_point = button == 3 ? -1 : ed->drag_color;
    } else {
        int i = vvg_tf_hit(tf, &a, x, y, RADIUS);
        if (button == 3)
            vvg_tf_delete_point(tf, i);
        else if (i >= 0)
            ed->drag_point = i;
        else
            ed->drag_point = vvg_tf_add_point(tf, &a, x, y);
        ed->sel_is_color = FALSE;
        ed->sel_point = button == 3 ? -1 : ed->drag_point;
    }
    vvg_document_changed(ed->doc);
    fill_selection(ed);
    gtk_widget_queue_draw(ed->canvas);
}

static void
drag_begin(GtkGestureDrag *g, double x, double y, gpointer user) {
    (void)g;
    VvgTfEditor *ed = user;
    ed->drag_x0 = x - LEFT;
    ed->drag_y0 = y - TOP;
}

static void
drag_update(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    (void)g;
    VvgTfEditor *ed = user;
    vv_object *o = volume_object(ed);
    if (!o)
        return;
    vvg_tf_axes a = axes(ed, o);
    if (ed->drag_point >= 0)
        vvg_tf_move_point(edited_tf(ed, o), ed->drag_point, &a, ed->drag_x0 + ox, ed->drag_y0 + oy);
    else if (ed->drag_color >= 0)
        vvg_tf_move_color(edited_tf(ed, o), ed->drag_color, &a, ed->drag_x0 + ox);
    else
        return;
    vvg_document_changed(ed->doc);
    fill_selection(ed);
    gtk_widget_queue_draw(ed->canvas);
}

/* The readout under the pointer: value, opacity, colour and the share of
 * voxels in that histogram bin. */
static void
motion(GtkEventControllerMotion *c, double x, double y, gpointer user) {
    (void)c;
    (void)y;
    VvgTfEditor *ed = user;
    vv_object *o = volume_object(ed);
    if (!o)
        return;
    vvg_tf_axes a = axes(ed, o);
    double px = fmin(fmax(x - LEFT, 0), a.width);
    double v = vvg_tf_value(&a, px);
    vv_vec3 col = vv_tf_eval_color(edited_tf(ed, o), v);
    int bin = (int)fmin(HIST_BINS - 1, fmax(0, (v - a.vmin) / (a.vmax - a.vmin) * HIST_BINS));
    char t[200];
    snprintf(t, sizeof t, "value %.5g · opacity %.3f · colour #%02X%02X%02X · %.2f%% of voxels", v,
             vv_tf_eval_opacity(edited_tf(ed, o), v), (unsigned)lrint(col.x * 255),
             (unsigned)lrint(col.y * 255), (unsigned)lrint(col.z * 255),
             ed->hist_total ? 100.0 * (double)ed->hist[bin] / (double)ed->hist_total : 0.0);
    gtk_label_set_text(GTK_LABEL(ed->readout), t);
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgTfEditor *ed = VVG_TF_EDITOR(user);
    /* the World changes on every motion event of a drag in the view: redraw
     * only when this object's function did */
    vv_object *o = volume_object(ed);
    if (o && o == ed->drawn_object && memcmp(edited_tf(ed, o), &ed->drawn, sizeof ed->drawn) == 0)
        return;
    if (o != ed->drawn_object)
        ed->sel_point = -1;
    fill_selection(ed);
    gtk_widget_queue_draw(ed->canvas);
}

static void
vvg_tf_editor_dispose(GObject *obj) {
    VvgTfEditor *ed = VVG_TF_EDITOR(obj);
    if (ed->doc) {
        g_signal_handlers_disconnect_by_data(ed->doc, ed);
        g_clear_object(&ed->doc);
    }
    G_OBJECT_CLASS(vvg_tf_editor_parent_class)->dispose(obj);
}

static void
vvg_tf_editor_class_init(VvgTfEditorClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_tf_editor_dispose;
}

/* Value, opacity, colour and Delete of the selected point. */
static void
build_selection(VvgTfEditor *ed) {
    ed->sel_title = gtk_label_new("");
    gtk_label_set_xalign(GTK_LABEL(ed->sel_title), 0);
    gtk_box_append(GTK_BOX(ed), ed->sel_title);
    ed->sel_box = gtk_grid_new();
    gtk_grid_set_column_spacing(GTK_GRID(ed->sel_box), 6);
    gtk_grid_set_row_spacing(GTK_GRID(ed->sel_box), 3);
    ed->sel_value = vvg_row(ed->sel_box, "point value", vvg_spin(-1e9, 1e9, 1, 2, 0));
    ed->sel_opacity = vvg_row(ed->sel_box, "point opacity", vvg_spin(0, 1, 0.01, 3, 0));
    ed->sel_color = vvg_row(ed->sel_box, "point colour", gtk_color_button_new());
    ed->sel_delete = gtk_button_new_with_label("Delete point");
    gtk_grid_attach(GTK_GRID(ed->sel_box), ed->sel_delete, 0, vvg_grid_rows(ed->sel_box), 2, 1);
    g_signal_connect(ed->sel_value, "value-changed", G_CALLBACK(sel_spin_changed), ed);
    g_signal_connect(ed->sel_opacity, "value-changed", G_CALLBACK(sel_spin_changed), ed);
    g_signal_connect(ed->sel_color, "color-set", G_CALLBACK(sel_color_set), ed);
    g_signal_connect(ed->sel_delete, "clicked", G_CALLBACK(sel_delete_clicked), ed);
    gtk_box_append(GTK_BOX(ed), ed->sel_box);
}

static void
vvg_tf_editor_init(VvgTfEditor *ed) {
    gtk_orientable_set_orientation(GTK_ORIENTABLE(ed), GTK_ORIENTATION_VERTICAL);
    gtk_box_set_spacing(GTK_BOX(ed), 3);
    ed->drag_point = ed->drag_color = ed->sel_point = -1;
    ed->color = (GdkRGBA){1, 1, 1, 1};
    ed->canvas = gtk_drawing_area_new();
    gtk_widget_set_size_request(ed->canvas, 300, 190);
    gtk_widget_set_hexpand(ed->canvas, TRUE);
    vvg_name(ed->canvas, "transfer function editor");
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(ed->canvas), canvas_draw, ed, NULL);
    gtk_box_append(GTK_BOX(ed), ed->canvas);
    ed->readout = gtk_label_new("point at the editor for value, opacity and colour");
    gtk_label_set_xalign(GTK_LABEL(ed->readout), 0);
    gtk_label_set_ellipsize(GTK_LABEL(ed->readout), PANGO_ELLIPSIZE_END);
    vvg_name(ed->readout, "transfer function readout");
    gtk_box_append(GTK_BOX(ed), ed->readout);
    build_selection(ed);
    GtkGesture *click = gtk_gesture_click_new();
    gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(click), 0);
    g_signal_connect(click, "pressed", G_CALLBACK(pressed), ed);
    gtk_widget_add_controller(ed->canvas, GTK_EVENT_CONTROLLER(click));
    GtkGesture *drag = gtk_gesture_drag_new();
    g_signal_connect(drag, "drag-begin", G_CALLBACK(drag_begin), ed);
    g_signal_connect(drag, "drag-update", G_CALLBACK(drag_update), ed);
    gtk_widget_add_controller(ed->canvas, GTK_EVENT_CONTROLLER(drag));
    GtkEventController *mo = gtk_event_controller_motion_new();
    g_signal_connect(mo, "motion", G_CALLBACK(motion), ed);
    gtk_widget_add_controller(ed->canvas, mo);
}

VvgTfEditor *
vvg_tf_editor_new(VvgDocument *doc) {
    VvgTfEditor *ed = g_object_new(VVG_TYPE_TF_EDITOR, NULL);
    ed->doc = g_object_ref(doc);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), ed);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(doc_changed), ed);
    fill_selection(ed);
    return ed;
}

void
vvg_tf_editor_set_log(VvgTfEditor *ed, gboolean log) {
    ed->log = log;
    gtk_widget_queue_draw(ed->canvas);
}

void
vvg_tf_editor_set_color(VvgTfEditor *ed, const GdkRGBA *color) {
    ed->color = *color;
}
