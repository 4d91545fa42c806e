/* VvgTf2dEditor: 2-D transfer-function widgets over the joint histogram (vvg-tf2d-editor.h). */
#include "vvg-tf2d-editor.h"

#include <math.h>
#include <string.h>

#define HIST_V 256
#define HIST_G 128
#define PICK 6.0

struct _VvgTf2dEditor {
    GtkWidget parent;
    VvgDocument *doc;
    vv_tf2d drawn; /* the function last drawn, to skip redraws of unchanged ones */
    const vv_object *drawn_object;
    int selected;
    gboolean resize;
    double x0, y0;        /* drag start, pixels */
    vv_tf2d_widget start; /* the widget as it was at the press */
    const vv_volume *hist_volume;
    uint64_t hist_modified;
    double gmax;           /* gradient-magnitude range shown: [0, gmax] */
    cairo_surface_t *hist; /* HIST_V x HIST_G grey image, row 0 the largest gradient */
    guint hist_idle;       /* the joint histogram is waited for */
};

G_DEFINE_TYPE(VvgTf2dEditor, vvg_tf2d_editor, GTK_TYPE_WIDGET)

static vv_object *
volume_object(VvgTf2dEditor *ed) {
    vv_object *o = vvg_document_selected_object(ed->doc);
    return o && o->type == VV_OBJECT_VOLUME && o->volume ? o : NULL;
}

/* Draws the joint histogram @p h (log counts) into the editor's image. */
static void
set_histogram(VvgTf2dEditor *ed, const vv_volume *v, const vv_histogram2d *h) {
    if (ed->hist)
        cairo_surface_destroy(ed->hist);
    ed->hist = cairo_image_surface_create(CAIRO_FORMAT_RGB24, HIST_V, HIST_G);
    ed->hist_volume = v;
    ed->hist_modified = v->modified;
    ed->gmax = 1;
    if (!h)
        return;
    ed->gmax = h->gradient_hi > 0 ? h->gradient_hi : 1;
    double mx = 1;
    for (int i = 0; i < HIST_V * HIST_G; i++)
        mx = fmax(mx, log1p((double)h->counts[i]));
    cairo_surface_flush(ed->hist);
    unsigned char *px = cairo_image_surface_get_data(ed->hist);
    int stride = cairo_image_surface_get_stride(ed->hist);
    for (int g = 0; g < HIST_G; g++)
        for (int x = 0; x < HIST_V; x++) {
            double c = log1p((double)h->counts[g * HIST_V + x]) / mx;
            uint32_t grey = (uint32_t)(30 + 200 * c);
            uint32_t *p = (uint32_t *)(px + (HIST_G - 1 - g) * stride) + x;
            *p = grey << 16 | grey << 8 | grey;
        }
    cairo_surface_mark_dirty(ed->hist);
}

static void
update_histogram(VvgTf2dEditor *ed, const vv_volume *v) {
    if (ed->hist && ed->hist_volume == v && ed->hist_modified == v->modified)
        return;
    vv_histogram2d *h = NULL;
    if (vv_histogram2d_compute(&h, v, HIST_V, HIST_G, 0, 0, 0) != VV_OK)
        h = NULL;
    set_histogram(ed, v, h);
    vv_histogram2d_free(h);
}

/* The joint histogram (a gradient per voxel) is computed on a worker
 * thread: the UI never waits for it. */
typedef struct hist_job {
    vv_volume *volume; /* a reference is held */
    vv_histogram2d *h;
} hist_job;

static void
hist_job_free(gpointer p) {
    hist_job *j = p;
    vv_volume_free(j->volume);
    vv_histogram2d_free(j->h);
    g_free(j);
}

static void
hist_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    hist_job *j = data;
    if (vv_histogram2d_compute(&j->h, j->volume, HIST_V, HIST_G, 0, 0, 0) != VV_OK)
        j->h = NULL;
}

static void
hist_done(GObject *src, GAsyncResult *res, gpointer user) {
    (void)user;
    VvgTf2dEditor *ed = VVG_TF2D_EDITOR(src);
    hist_job *j = g_task_get_task_data(G_TASK(res));
    ed->hist_idle = 0;
    if (!ed->doc)
        return; /* disposed */
    set_histogram(ed, j->volume, j->h);
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

/* Widget coordinates <-> data value and gradient magnitude. */
static double
px_x(VvgTf2dEditor *ed, const vv_object *o, double value) {
    double lo = o->volume->range[0], hi = o->volume->range[1];
    return (value - lo) / (hi > lo ? hi - lo : 1) * gtk_widget_get_width(GTK_WIDGET(ed));
}

static double
px_y(VvgTf2dEditor *ed, double grad) {
    return (1.0 - grad / ed->gmax) * gtk_widget_get_height(GTK_WIDGET(ed));
}

static double
data_dv(VvgTf2dEditor *ed, const vv_object *o, double dx) {
    double lo = o->volume->range[0], hi = o->volume->range[1];
    return dx / fmax(1, gtk_widget_get_width(GTK_WIDGET(ed))) * (hi > lo ? hi - lo : 1);
}

static double
data_dg(VvgTf2dEditor *ed, double dy) {
    return -dy / fmax(1, gtk_widget_get_height(GTK_WIDGET(ed))) * ed->gmax;
}

/* The widget's outline as a polygon of up to 4 points. */
static int
outline(VvgTf2dEditor *ed, const vv_object *o, const vv_tf2d_widget *w, double xs[4],
        double ys[4]) {
    if (w->shape == VV_TF2D_RECTANGLE) {
        xs[0] = xs[3] = px_x(ed, o, w->value[0]);
        xs[1] = xs[2] = px_x(ed, o, w->value[1]);
        ys[0] = ys[1] = px_y(ed, w->gradient[0]);
        ys[2] = ys[3] = px_y(ed, w->gradient[1]);
        return 4;
    }
    xs[0] = px_x(ed, o, w->center);
    ys[0] = px_y(ed, w->gradient[0]);
    xs[1] = px_x(ed, o, w->center - 0.5 * w->width);
    xs[2] = px_x(ed, o, w->center + 0.5 * w->width);
    ys[1] = ys[2] = px_y(ed, w->gradient[1]);
    return 3;
}

static void
vvg_tf2d_editor_snapshot(GtkWidget *widget, GtkSnapshot *snapshot) {
    VvgTf2dEditor *ed = VVG_TF2D_EDITOR(widget);
    double W = gtk_widget_get_width(widget), H = gtk_widget_get_height(widget);
    cairo_t *cr = gtk_snapshot_append_cairo(snapshot, &GRAPHENE_RECT_INIT(0, 0, W, H));
    cairo_set_source_rgb(cr, 0.12, 0.12, 0.14);
    cairo_paint(cr);
    vv_object *o = volume_object(ed);
    ed->drawn_object = o;
    if (!o) {
        cairo_destroy(cr);
        return;
    }
    ed->drawn = o->tf2d;
    if (!ed->hist || ed->hist_volume != o->volume || ed->hist_modified != o->volume->modified) {
        /* the joint histogram (gradients of every voxel) is made when the
         * UI is idle, after the view's first frames, not while it opens */
        if (!ed->hist_idle) {
            ed->hist_idle = 1;
            hist_job *j = g_new0(hist_job, 1);
            j->volume = vv_volume_ref(o->volume);
            GTask *task = g_task_new(ed, NULL, hist_done, NULL);
            g_task_set_task_data(task, j, hist_job_free);
            g_task_run_in_thread(task, hist_thread);
            g_object_unref(task);
        }
        cairo_destroy(cr);
        return;
    }
    cairo_save(cr);
    cairo_scale(cr, W / HIST_V, H / HIST_G);
    cairo_set_source_surface(cr, ed->hist, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_paint(cr);
    cairo_restore(cr);
    const vv_tf2d *tf = &o->tf2d;
    for (int i = 0; i < tf->n_widgets; i++) {
        const vv_tf2d_widget *w = &tf->widgets[i];
        double xs[4], ys[4];
        int n = outline(ed, o, w, xs, ys);
        cairo_move_to(cr, xs[0], ys[0]);
        for (int k = 1; k < n; k++)
            cairo_line_to(cr, xs[k], ys[k]);
        cairo_close_path(cr);
        cairo_set_source_rgba(cr, w->color.x, w->color.y, w->color.z, 0.25 + 0.5 * w->opacity);
        cairo_fill_preserve(cr);
        cairo_set_line_width(cr, i == ed->selected ? 2.5 : 1.0);
        cairo_set_source_rgb(cr, i == ed->selected ? 1 : 0.8, i == ed->selected ? 0.8 : 0.8,
                             i == ed->selected ? 0.2 : 0.8);
        cairo_stroke(cr);
    }
    cairo_destroy(cr);
}

/* The widget under (x, y): inside its outline's box (grown by PICK), the last drawn first. */
static int
hit(VvgTf2dEditor *ed, const vv_object *o, double x, double y) {
    for (int i = o->tf2d.n_widgets - 1; i >= 0; i--) {
        double xs[4], ys[4];
        int n = outline(ed, o, &o->tf2d.widgets[i], xs, ys);
        double x0 = xs[0], x1 = xs[0], y0 = ys[0], y1 = ys[0];
        for (int k = 1; k < n; k++) {
            x0 = fmin(x0, xs[k]);
            x1 = fmax(x1, xs[k]);
            y0 = fmin(y0, ys[k]);
            y1 = fmax(y1, ys[k]);
        }
        if (x >= x0 - PICK && x <= x1 + PICK && y >= y0 - PICK && y <= y1 + PICK)
            return i;
    }
    return -1;
}

static void
pressed(GtkGestureClick *g, int n, double x, double y, gpointer user) {
    (void)n;
    VvgTf2dEditor *ed = user;
    vv_object *o = volume_object(ed);
    if (!o)
        return;
    guint button = gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(g));
    GdkModifierType mods = gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(g));
    int i = hit(ed, o, x, y);
    ed->selected = i;
    if (i >= 0) {
        vvg_document_begin_edit(ed->doc, "edit 2-D transfer function");
        if (button == 3) {
            vv_tf2d *tf = &o->tf2d;
            memmove(&tf->widgets[i], &tf->widgets[i + 1],
                    (size_t)(tf->n_widgets - i - 1) * sizeof tf->widgets[0]);
            tf->n_widgets--;
            ed->selected = -1;
            vvg_document_changed(ed->doc);
        } else {
            ed->start = o->tf2d.widgets[i];
            ed->resize = (mods & GDK_SHIFT_MASK) != 0;
            ed->x0 = x;
            ed->y0 = y;
        }
    }
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

static void
drag_update(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    (void)g;
    VvgTf2dEditor *ed = user;
    vv_object *o = volume_object(ed);
    if (!o || ed->selected < 0 || ed->selected >= o->tf2d.n_widgets)
        return;
    vv_tf2d_widget w = ed->start;
    double dv = data_dv(ed, o, ox), dg = data_dg(ed, oy);
    if (ed->resize) {
        if (w.shape == VV_TF2D_RECTANGLE) {
            w.value[1] = fmax(w.value[0], w.value[1] + dv);
            w.gradient[1] = fmax(w.gradient[0], w.gradient[1] + dg);
        } else {
            w.width =
                fmax(1e-6 * (o->volume->range[1] - o->volume->range[0]) + 1e-12, w.width + 2 * dv);
            w.gradient[1] = fmax(w.gradient[0], w.gradient[1] + dg);
        }
    } else {
        /* move, keeping the gradient range inside [0, ...) */
        double sg = fmax(dg, -w.gradient[0]);
        w.value[0] += dv;
        w.value[1] += dv;
        w.center += dv;
        w.gradient[0] += sg;
        w.gradient[1] += sg;
    }
    if (vv_tf2d_widget_check(&w) != VV_OK)
        return;
    o->tf2d.widgets[ed->selected] = w;
    vvg_document_changed(ed->doc);
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

void
vvg_tf2d_editor_add(VvgTf2dEditor *ed, vv_tf2d_shape shape) {
    vv_object *o = volume_object(ed);
    if (!o)
        return;
    update_histogram(ed, o->volume);
    double lo = o->volume->range[0], hi = o->volume->range[1], span = hi > lo ? hi - lo : 1;
    vv_tf2d_widget w;
    vv_vec3 c = vv_vec3_make(1, 0.9, 0.8);
    if (shape == VV_TF2D_RECTANGLE)
        vv_tf2d_widget_init_rectangle(&w, lo + 0.4 * span, lo + 0.6 * span, 0, 0.5 * ed->gmax, c,
                                      0.5);
    else
        vv_tf2d_widget_init_triangle(&w, lo + 0.5 * span, 0.2 * span, 0.8 * ed->gmax, c, 0.5);
    vvg_document_begin_edit(ed->doc, "add 2-D transfer-function widget");
    if (o->segmentation != VV_SEG_TRANSFER_FUNCTION_2D && o->tf2d.n_widgets == 0)
        o->tf2d.opacity_unit_distance = o->tf.opacity_unit_distance;
    if (vv_tf2d_add_widget(&o->tf2d, &w) == VV_OK) {
        o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
        ed->selected = o->tf2d.n_widgets - 1;
    }
    vvg_document_changed(ed->doc);
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

void
vvg_tf2d_editor_set_style(VvgTf2dEditor *ed, const GdkRGBA *color, double opacity) {
    vv_object *o = volume_object(ed);
    if (!o || ed->selected < 0 || ed->selected >= o->tf2d.n_widgets)
        return;
    vvg_document_begin_edit(ed->doc, "2-D transfer-function widget style");
    vv_tf2d_widget *w = &o->tf2d.widgets[ed->selected];
    w->color = vv_vec3_make(color->red, color->green, color->blue);
    w->opacity = opacity < 0 ? 0 : opacity > 1 ? 1 : opacity;
    vvg_document_changed(ed->doc);
    gtk_widget_queue_draw(GTK_WIDGET(ed));
}

int
vvg_tf2d_editor_selected(VvgTf2dEditor *ed) {
    return ed->selected;
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgTf2dEditor *ed = VVG_TF2D_EDITOR(user);
    /* the World changes on every motion event of a drag in the view: redraw
     * only when this object's function did */
    vv_object *o = volume_object(ed);
    if (o && o == ed->drawn_object && memcmp(&o->tf2d, &ed->drawn, sizeof ed->drawn) == 0)
        return;
    gtk_widget_queue_draw(GTK_WIDGET(user));
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VVG_TF2D_EDITOR(user)->selected = -1;
    gtk_widget_queue_draw(GTK_WIDGET(user));
}

static void
vvg_tf2d_editor_dispose(GObject *obj) {
    VvgTf2dEditor *ed = VVG_TF2D_EDITOR(obj);
    if (ed->doc) {
        g_signal_handlers_disconnect_by_data(ed->doc, ed);
        g_clear_object(&ed->doc);
    }
    if (ed->hist) {
        cairo_surface_destroy(ed->hist);
        ed->hist = NULL;
    }
    G_OBJECT_CLASS(vvg_tf2d_editor_parent_class)->dispose(obj);
}

static void
vvg_tf2d_editor_class_init(VvgTf2dEditorClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_tf2d_editor_dispose;
    GTK_WIDGET_CLASS(klass)->snapshot = vvg_tf2d_editor_snapshot;
}

static void
vvg_tf2d_editor_init(VvgTf2dEditor *ed) {
    ed->selected = -1;
    ed->gmax = 1;
    gtk_widget_set_size_request(GTK_WIDGET(ed), 300, 140);
    gtk_widget_set_hexpand(GTK_WIDGET(ed), TRUE);
    GtkGesture *click = gtk_gesture_click_new();
    gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(click), 0);
    g_signal_connect(click, "pressed", G_CALLBACK(pressed), ed);
    gtk_widget_add_controller(GTK_WIDGET(ed), GTK_EVENT_CONTROLLER(click));
    GtkGesture *drag = gtk_gesture_drag_new();
    g_signal_connect(drag, "drag-update", G_CALLBACK(drag_update), ed);
    gtk_widget_add_controller(GTK_WIDGET(ed), GTK_EVENT_CONTROLLER(drag));
}

VvgTf2dEditor *
vvg_tf2d_editor_new(VvgDocument *doc) {
    VvgTf2dEditor *ed = g_object_new(VVG_TYPE_TF2D_EDITOR, NULL);
    ed->doc = g_object_ref(doc);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), ed);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), ed);
    return ed;
}
