/* VvTfEditor: transfer-function editing over the histogram (vv-tf-editor.h). */
#include "vv-tf-editor.h"

#include <math.h>
#include <string.h>

#include "vvg-models.h"

#define STRIP 14.0 /* height of the colour strip, pixels */
#define RADIUS 6.0 /* pick radius of a point, pixels */
#define HIST_BINS 256

struct _VvTfEditor {
    GtkWidget parent;
    VvDocument *doc;
    vv_tf drawn; /* the function last drawn, to skip redraws of unchanged ones */
    const vv_object *drawn_object;
    gboolean log;
    GdkRGBA color;
    int drag_point; /* opacity point being dragged, or -1 */
    int drag_color; /* colour point being dragged, or -1 */
    double drag_x0, drag_y0;
    const vv_volume *hist_volume;
    uint64_t hist_modified;
    uint64_t hist[HIST_BINS];
};

G_DEFINE_TYPE(VvTfEditor, vv_tf_editor, GTK_TYPE_WIDGET)

static vv_object *
volume_object(VvTfEditor *ed) {
    vv_object *o = vv_document_selected_object(ed->doc);
    return o && o->type == VV_OBJECT_VOLUME && o->volume ? o : NULL;
}

static vvg_tf_axes
axes(VvTfEditor *ed, const vv_object *o) {
    vvg_tf_axes a = {o->volume->range[0], o->volume->range[1], gtk_widget_get_width(GTK_WIDGET(ed)),
                     gtk_widget_get_height(GTK_WIDGET(ed)) - STRIP};
    if (!(a.vmax > a.vmin))
        a.vmax = a.vmin + 1;
    return a;
}

static void
update_histogram(VvTfEditor *ed, const vv_volume *v) {
    if (ed->hist_volume == v && ed->hist_modified == v->modified)
        return;
    memset(ed->hist, 0, sizeof ed->hist);
    double hi = v->range[1] > v->range[0] ? v->range[1] : v->range[0] + 1;
    if (vv_volume_histogram(v, HIST_BINS, v->range[0], hi, ed->hist) != VV_OK)
        memset(ed->hist, 0, sizeof ed->hist);
    ed->hist_volume = v;
    ed->hist_modified = v->modified;
}

static void
vv_tf_editor_snapshot(GtkWidget *w, GtkSnapshot *snapshot) {
    VvTfEditor *ed = VV_TF_EDITOR(w);
    double W = gtk_widget_get_width(w), H = gtk_widget_get_height(w);
    cairo_t *cr = gtk_snapshot_append_cairo(snapshot, &GRAPHENE_RECT_INIT(0, 0, W, H));
    cairo_set_source_rgb(cr, 0.12, 0.12, 0.14);
    cairo_paint(cr);
    vv_object *o = volume_object(ed);
    ed->drawn_object = o;
    if (!o) {
        cairo_destroy(cr);
        return;
    }
    ed->drawn = o->tf;
    update_histogram(ed, o->volume);
    vvg_tf_axes a = axes(ed, o);
    /* histogram: the largest bin but the first (background) sets the scale */
    double maxc = 1;
    for (int i = 1; i < HIST_BINS; i++) {
        double c = ed->log ? log1p((double)ed->hist[i]) : (double)ed->hist[i];
        maxc = c > maxc ? c : maxc;
    }
    cairo_set_source_rgb(cr, 0.35, 0.35, 0.4);
    for (int i = 0; i < HIST_BINS; i++) {
        double c = ed->log ? log1p((double)ed->hist[i]) : (double)ed->hist[i];
        double h = fmin(1.0, c / maxc) * a.height;
        cairo_rectangle(cr, i * a.width / HIST_BINS, a.height - h, a.width / HIST_BINS + 0.5, h);
    }
    cairo_fill(cr);
    const vv_tf *tf = &o->tf;
    /* colour strip */
    for (int x = 0; x < (int)a.width; x++) {
        vv_vec3 c = vv_tf_eval_color(tf, vvg_tf_value(&a, x + 0.5));
        cairo_set_source_rgb(cr, c.x, c.y, c.z);
        cairo_rectangle(cr, x, a.height, 1, STRIP);
        cairo_fill(cr);
    }
    for (int i = 0; i < tf->n_color; i++) {
        double x = vvg_tf_x(&a, tf->color[i].value);
        cairo_set_source_rgb(cr, 1, 1, 1);
        cairo_move_to(cr, x, a.height);
        cairo_line_to(cr, x - 5, H);
        cairo_line_to(cr, x + 5, H);
        cairo_close_path(cr);
        cairo_stroke(cr);
    }
    /* opacity curve and points */
    cairo_set_source_rgb(cr, 1.0, 0.8, 0.2);
    cairo_set_line_width(cr, 1.5);
    for (int x = 0; x < (int)a.width; x++) {
        double y = vvg_tf_y(&a, vv_tf_eval_opacity(tf, vvg_tf_value(&a, x + 0.5)));
        if (x == 0)
            cairo_move_to(cr, x, y);
        else
            cairo_line_to(cr, x, y);
    }
    cairo_stroke(cr);
    for (int i = 0; i < tf->n_opacity; i++) {
        double x = vvg_tf_x(&a, tf->opacity[i].value), y = vvg_tf_y(&a, tf->opacity[i].opacity);
        cairo_arc(cr, x, y, 4, 0, 2 * G_PI);
        vv_vec3 c = vv_tf_eval_color(tf, tf->opacity[i].value);
        cairo_set_source_rgb(cr, c.x, c.y, c.z);
        cairo_fill_preserve(cr);
        cairo_set_source_rgb(cr, i == ed->drag_point ? 1 : 0.2, 0.2, 0.2);
        cairo_stroke(cr);
    }
    cairo_destroy(cr);
}

static void
pressed(GtkGestureClick *g, int n_press, double x, double y, gpointer user) {
    (void)n_press;
    VvTfEditor *ed = user;
    vv_object *o = volume_object(ed);
    ed->drag_point = ed->drag_color = -1;
    if (!o)
        return;
    guint button = gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(g));
    vvg_tf_axes a = axes(ed, o);
    gboolean in_strip = y > a.height;
    vv_document_begin_edit(ed->doc, "edit transfer function");
    o = volume_object(ed); /* unchanged by begin_edit, which copies */
    vv_tf *tf = &o->tf;
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
    } else {
        int i = vvg_tf_hit(tf, &a, x, y, RADIUS);
        if (button == 3)
            vvg_tf_delete_point(tf, i);
        else if (i >= 0)
            ed->drag_point = i;
        else
            ed->drag_point = vvg_tf_add_point(tf, &a, x, y);
    }
    vv_document_changed(ed->doc);
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

static void
drag_begin(GtkGestureDrag *g, double x, double y, gpointer user) {
    (void)g;
    VvTfEditor *ed = user;
    ed->drag_x0 = x;
    ed->drag_y0 = y;
}

static void
drag_update(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    (void)g;
    VvTfEditor *ed = user;
    vv_object *o = volume_object(ed);
    if (!o)
        return;
    vvg_tf_axes a = axes(ed, o);
    if (ed->drag_point >= 0)
        vvg_tf_move_point(&o->tf, ed->drag_point, &a, ed->drag_x0 + ox, ed->drag_y0 + oy);
    else if (ed->drag_color >= 0)
        vvg_tf_move_color(&o->tf, ed->drag_color, &a, ed->drag_x0 + ox);
    else
        return;
    vv_document_changed(ed->doc);
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

static void
doc_changed(VvDocument *doc, gpointer user) {
    (void)doc;
    VvTfEditor *ed = VV_TF_EDITOR(user);
    /* the World changes on every motion event of a drag in the view: redraw
     * only when this object's function did */
    vv_object *o = volume_object(ed);
    if (o && o == ed->drawn_object && memcmp(&o->tf, &ed->drawn, sizeof ed->drawn) == 0)
        return;
    gtk_widget_queue_draw(GTK_WIDGET(user));
}

static void
vv_tf_editor_dispose(GObject *obj) {
    VvTfEditor *ed = VV_TF_EDITOR(obj);
    if (ed->doc) {
        g_signal_handlers_disconnect_by_data(ed->doc, ed);
        g_clear_object(&ed->doc);
    }
    G_OBJECT_CLASS(vv_tf_editor_parent_class)->dispose(obj);
}

static void
vv_tf_editor_class_init(VvTfEditorClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vv_tf_editor_dispose;
    GTK_WIDGET_CLASS(klass)->snapshot = vv_tf_editor_snapshot;
}

static void
vv_tf_editor_init(VvTfEditor *ed) {
    ed->drag_point = ed->drag_color = -1;
    ed->color = (GdkRGBA){1, 1, 1, 1};
    gtk_widget_set_size_request(GTK_WIDGET(ed), 300, 140);
    gtk_widget_set_hexpand(GTK_WIDGET(ed), TRUE);
    GtkGesture *click = gtk_gesture_click_new();
    gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(click), 0);
    g_signal_connect(click, "pressed", G_CALLBACK(pressed), ed);
    gtk_widget_add_controller(GTK_WIDGET(ed), GTK_EVENT_CONTROLLER(click));
    GtkGesture *drag = gtk_gesture_drag_new();
    g_signal_connect(drag, "drag-begin", G_CALLBACK(drag_begin), ed);
    g_signal_connect(drag, "drag-update", G_CALLBACK(drag_update), ed);
    gtk_widget_add_controller(GTK_WIDGET(ed), GTK_EVENT_CONTROLLER(drag));
}

VvTfEditor *
vv_tf_editor_new(VvDocument *doc) {
    VvTfEditor *ed = g_object_new(VV_TYPE_TF_EDITOR, NULL);
    ed->doc = g_object_ref(doc);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), ed);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(doc_changed), ed);
    return ed;
}

void
vv_tf_editor_set_log(VvTfEditor *ed, gboolean log) {
    ed->log = log;
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

void
vv_tf_editor_set_color(VvTfEditor *ed, const GdkRGBA *color) {
    ed->color = *color;
}
