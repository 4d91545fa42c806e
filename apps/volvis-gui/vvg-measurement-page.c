/* VvgMeasurementPage: histograms, areas, volumes and distances (vvg-measurement-page.h). */
#include "vvg-measurement-page.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

struct _VvgMeasurementPage {
    GtkBox parent;
    VvgDocument *doc;
    VvgSceneView *scene; /* borrowed */
    VvgMarks *marks;
    GtkWidget *hist_result, *iso_result, *dist_result, *iso_button;
    GtkWidget *measure_iso, *measure_method, *measure_seed, *seed_i, *seed_j, *seed_k;
    GtkWidget *pa[3], *pb[3], *measure_text, *histogram, *hist_log;
    vv_histogram *hist;
};

G_DEFINE_TYPE(VvgMeasurementPage, vvg_measurement_page, GTK_TYPE_BOX)

/* A result: under its button (@p where, may be NULL) and appended to the
 * page's log, where all results can be selected and copied. */
static void
measure_print(VvgMeasurementPage *self, GtkWidget *where, const char *text) {
    GtkTextBuffer *b = gtk_text_view_get_buffer(GTK_TEXT_VIEW(self->measure_text));
    GtkTextIter end;
    gtk_text_buffer_get_end_iter(b, &end);
    gtk_text_buffer_insert(b, &end, text, -1);
    if (where) {
        g_autofree char *line = g_strstrip(g_strdup(text));
        gtk_label_set_text(GTK_LABEL(where), line);
        gtk_widget_set_visible(where, TRUE);
    }
}

static void
copy_results(GtkButton *b, gpointer user) {
    (void)b;
    VvgMeasurementPage *self = user;
    GtkTextBuffer *buf = gtk_text_view_get_buffer(GTK_TEXT_VIEW(self->measure_text));
    GtkTextIter s0, s1;
    gtk_text_buffer_get_bounds(buf, &s0, &s1);
    g_autofree char *all = gtk_text_buffer_get_text(buf, &s0, &s1, FALSE);
    gdk_clipboard_set_text(gtk_widget_get_clipboard(GTK_WIDGET(self)), all);
}

static void
hist_draw(GtkDrawingArea *area, cairo_t *cr, int W, int H, gpointer user) {
    (void)area;
    VvgMeasurementPage *self = user;
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    if (!self->hist)
        return;
    gboolean lg = gtk_check_button_get_active(GTK_CHECK_BUTTON(self->hist_log));
    double mx = 1;
    for (int i = 0; i < self->hist->nbins; i++) {
        double c = lg ? log10(1.0 + (double)self->hist->counts[i]) : (double)self->hist->counts[i];
        mx = c > mx ? c : mx;
    }
    cairo_set_source_rgb(cr, 0.2, 0.3, 0.6);
    for (int i = 0; i < self->hist->nbins; i++) {
        double c = lg ? log10(1.0 + (double)self->hist->counts[i]) : (double)self->hist->counts[i];
        double h = c / mx * (H - 4);
        cairo_rectangle(cr, (double)i * W / self->hist->nbins, H - h, (double)W / self->hist->nbins,
                        h);
    }
    cairo_fill(cr);
}

/* The histogram of an object out of core: level 0 of its file, read box by
 * box in a thread through the object's source (thread-safe; its pieces in
 * the process's one cache, within the memory limit). */
typedef struct hist_job {
    vv_source *source; /* a reference */
    char name[VV_NAME_MAX];
    vv_histogram *hist;
    int dims[3];
    vv_status status;
    char error[512];
} hist_job;

static void
hist_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    hist_job *j = data;
    const vv_volume *h0 = vv_source_level(j->source, 0);
    memcpy(j->dims, h0->dims, sizeof j->dims);
    vv_error_clear();
    j->status = vv_measure_histogram_boxes(&j->hist, h0, vv_source_box, j->source, 128, 0, 0, NULL);
    if (j->status != VV_OK)
        g_strlcpy(j->error, vv_error_message(), sizeof j->error);
}

static void
hist_job_free(gpointer p) {
    hist_job *j = p;
    vv_histogram_free(j->hist);
    vv_source_free(j->source);
    g_free(j);
}

static void
hist_done(GObject *src, GAsyncResult *res, gpointer user) {
    (void)user;
    VvgMeasurementPage *self = VVG_MEASUREMENT_PAGE(src);
    hist_job *j = g_task_get_task_data(G_TASK(res));
    if (j->status != VV_OK) {
        gtk_label_set_text(GTK_LABEL(self->hist_result), "failed");
        vvg_show_error(GTK_WIDGET(self), "Histogram failed", j->error);
        return;
    }
    vv_histogram_free(self->hist);
    self->hist = j->hist;
    j->hist = NULL;
    char t[320];
    snprintf(t, sizeof t,
             "histogram of %s (level 0, %d x %d x %d, read out of core): %llu voxels, min %g, "
             "max %g, mean %g, sd %g\n",
             j->name, j->dims[0], j->dims[1], j->dims[2], (unsigned long long)self->hist->total,
             self->hist->min, self->hist->max, self->hist->mean, self->hist->sd);
    measure_print(self, self->hist_result, t);
    gtk_widget_queue_draw(self->histogram);
}

static void
act_histogram(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgMeasurementPage *self = user;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (!o || !o->volume) {
        vvg_show_error(GTK_WIDGET(self), "No histogram", "select a volume object first");
        return;
    }
    vv_source *src = vvg_object_source(o);
    if (src) { /* out of core: level 0, not the proxy */
        hist_job *j = g_new0(hist_job, 1);
        j->source = vv_source_ref(src);
        g_strlcpy(j->name, o->name, sizeof j->name);
        gtk_label_set_text(GTK_LABEL(self->hist_result), "reading level 0…");
        gtk_widget_set_visible(self->hist_result, TRUE);
        GTask *task = g_task_new(self, NULL, hist_done, NULL);
        g_task_set_task_data(task, j, hist_job_free);
        g_task_run_in_thread(task, hist_thread);
        g_object_unref(task);
        return;
    }
    vv_histogram_free(self->hist);
    self->hist = NULL;
    vv_error_clear();
    if (vv_measure_histogram(&self->hist, o->volume, 128, 0, 0, NULL) != VV_OK) {
        vvg_show_error(GTK_WIDGET(self), "Histogram failed", vv_error_message());
        return;
    }
    char t[256];
    snprintf(t, sizeof t, "histogram of %s: %llu voxels, min %g, max %g, mean %g, sd %g\n", o->name,
             (unsigned long long)self->hist->total, self->hist->min, self->hist->max,
             self->hist->mean, self->hist->sd);
    measure_print(self, self->hist_result, t);
    gtk_widget_queue_draw(self->histogram);
}

typedef struct measure_job {
    vv_volume *volume;
    vv_mat4 placed; /* the object's transform: the region mesh into the World */
    vv_mesh *region;
    const char *units;
    double iso;
    vv_isosurface_measure_options opt;
    vv_isosurface_measure result;
    char name[VV_NAME_MAX];
    char proxy[160];   /* out of core: what was measured instead of level 0 (else empty) */
    vv_source *source; /* out of core, no seed: level 0 of this file, read box by box */
    vv_status status;
    char error[512];
} measure_job;

static void
measure_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    measure_job *j = data;
    vv_error_clear();
    if (j->source) { /* level 0 out of core, through the object's source */
        j->status =
            vv_measure_isosurface_boxes(&j->result, vv_source_level(j->source, 0), vv_source_box,
                                        j->source, j->iso, j->opt.method, NULL);
        if (j->status != VV_OK)
            g_strlcpy(j->error, vv_error_message(), sizeof j->error);
        return;
    }
    j->status = vv_measure_isosurface(&j->result, j->volume, j->iso, &j->opt);
    /* the surface-tracked section is drawn in the views */
    if (j->status == VV_OK && j->opt.has_seed && j->opt.method == VV_MEASURE_MC &&
        vv_measure_isosurface_mesh(&j->region, j->volume, j->iso, &j->opt) == VV_OK) {
        for (size_t i = 0; i < j->region->n_vertices; i++) {
            float *q = j->region->positions + 3 * i;
            vv_vec3 w = vv_mat4_mul_point(j->placed, vv_vec3_make(q[0], q[1], q[2]));
            q[0] = (float)w.x;
            q[1] = (float)w.y;
            q[2] = (float)w.z;
        }
    }
    if (j->status != VV_OK)
        g_strlcpy(j->error, vv_error_message(), sizeof j->error);
}

static void
measure_job_free(gpointer p) {
    measure_job *j = p;
    vv_source_free(j->source);
    vv_volume_free(j->volume);
    vv_mesh_free(j->region);
    g_free(j);
}

static void
measure_done(GObject *src, GAsyncResult *res, gpointer user) {
    (void)user;
    VvgMeasurementPage *self = VVG_MEASUREMENT_PAGE(src);
    measure_job *j = g_task_get_task_data(G_TASK(res));
    gtk_widget_set_sensitive(self->iso_button, TRUE);
    if (j->status != VV_OK) {
        gtk_label_set_text(GTK_LABEL(self->iso_result), "failed");
        vvg_show_error(GTK_WIDGET(self), "Measurement failed", j->error);
        return;
    }
    const char *u = j->units;
    char t[704];
    snprintf(t, sizeof t,
             "%s isovalue %g (%s%s): area %.6g %s², volume %.6g %s³, %llu voxels, %zu "
             "triangles%s\n",
             j->name, j->iso, j->result.method == VV_MEASURE_MC ? "marching cubes" : "voxel count",
             j->opt.has_seed ? ", surface-tracked" : "", j->result.area, u, j->result.volume, u,
             (unsigned long long)j->result.voxels, j->result.n_triangles, j->proxy);
    measure_print(self, self->iso_result, t);
    vvg_marks_set_region(self->marks, j->region);
}

static void
act_measure(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgMeasurementPage *self = user;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (!o) {
        vvg_show_error(GTK_WIDGET(self), "Nothing to measure", "select an object first");
        return;
    }
    if (o->type == VV_OBJECT_MESH) {
        double vol = 0;
        vv_error_clear();
        vv_status s = vv_measure_mesh_volume(o->geometry.mesh, &vol);
        char t[256];
        snprintf(t, sizeof t, "%s mesh: area %.6g units², volume %s%.6g units³\n", o->name,
                 vv_mesh_area(o->geometry.mesh), s == VV_OK ? "" : "(open mesh) ",
                 s == VV_OK ? vol : NAN);
        measure_print(self, self->iso_result, t);
        return;
    }
    if (!o->volume)
        return;
    measure_job *j = g_new0(measure_job, 1);
    j->volume = vv_volume_ref(o->volume);
    j->placed = vv_object_matrix(o);
    j->units = vvg_unit_label(o->volume);
    gtk_label_set_text(GTK_LABEL(self->iso_result), "measuring…");
    gtk_widget_set_visible(self->iso_result, TRUE);
    gtk_widget_set_sensitive(self->iso_button, FALSE);
    j->iso = vvg_spin_value(self->measure_iso);
    g_strlcpy(j->name, o->name, sizeof j->name);
    vv_isosurface_measure_options_init(&j->opt);
    j->opt.method = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->measure_method)) == 1
                        ? VV_MEASURE_VOXEL
                        : VV_MEASURE_MC;
    if (gtk_check_button_get_active(GTK_CHECK_BUTTON(self->measure_seed))) {
        j->opt.has_seed = 1;
        j->opt.seed[0] = vvg_spin_value(self->seed_i);
        j->opt.seed[1] = vvg_spin_value(self->seed_j);
        j->opt.seed[2] = vvg_spin_value(self->seed_k);
    }
    vv_source *src = vvg_object_source(o);
    if (src) { /* out of core: the whole surface by level 0 box by box; a section the proxy */
        const vv_volume *h0 = vv_source_level(src, 0);
        if (!j->opt.has_seed) {
            j->source = vv_source_ref(src);
            snprintf(j->proxy, sizeof j->proxy, " -- level 0 (%d x %d x %d), read out of core",
                     h0->dims[0], h0->dims[1], h0->dims[2]);
        } else {
            snprintf(j->proxy, sizeof j->proxy,
                     " -- of the coarse proxy (%d x %d x %d voxels); level 0 (%d x %d x %d) is "
                     "out of core",
                     o->volume->dims[0], o->volume->dims[1], o->volume->dims[2], h0->dims[0],
                     h0->dims[1], h0->dims[2]);
        }
    }
    GTask *task = g_task_new(self, NULL, measure_done, NULL);
    g_task_set_task_data(task, j, measure_job_free);
    g_task_run_in_thread(task, measure_thread);
    g_object_unref(task);
}

/* Picking in the view: the next click sets the seed voxel or a point. */
static void
picked_seed(gpointer user, vv_vec3 p) {
    VvgMeasurementPage *self = user;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (!o || !o->volume)
        return;
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(vv_object_index_to_world(o), &ok);
    if (!ok)
        return;
    vv_vec3 ijk = vv_mat4_mul_point(inv, p);
    vvg_set_spin(self->seed_i, round(ijk.x));
    vvg_set_spin(self->seed_j, round(ijk.y));
    vvg_set_spin(self->seed_k, round(ijk.z));
    gtk_check_button_set_active(GTK_CHECK_BUTTON(self->measure_seed), TRUE);
    vvg_marks_set_point(self->marks, VVG_MARK_SEED, p);
    char t[200];
    snprintf(t, sizeof t, "picked voxel (%.0f, %.0f, %.0f) at (%g, %g, %g) %s\n", round(ijk.x),
             round(ijk.y), round(ijk.z), p.x, p.y, p.z, vvg_unit_label(o->volume));
    measure_print(self, self->iso_result, t);
}

static void
picked_a(gpointer user, vv_vec3 p) {
    VvgMeasurementPage *self = user;
    vvg_set_spin(self->pa[0], p.x);
    vvg_set_spin(self->pa[1], p.y);
    vvg_set_spin(self->pa[2], p.z);
    vvg_marks_set_point(self->marks, VVG_MARK_A, p);
}

static void
picked_b(gpointer user, vv_vec3 p) {
    VvgMeasurementPage *self = user;
    vvg_set_spin(self->pb[0], p.x);
    vvg_set_spin(self->pb[1], p.y);
    vvg_set_spin(self->pb[2], p.z);
    vvg_marks_set_point(self->marks, VVG_MARK_B, p);
}

static void
act_pick_seed(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vvg_scene_view_pick_next(VVG_MEASUREMENT_PAGE(user)->scene, picked_seed, user);
}

static void
act_pick_a(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vvg_scene_view_pick_next(VVG_MEASUREMENT_PAGE(user)->scene, picked_a, user);
}

static void
act_pick_b(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vvg_scene_view_pick_next(VVG_MEASUREMENT_PAGE(user)->scene, picked_b, user);
}

static void
act_distance(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgMeasurementPage *self = user;
    vv_vec3 pa = vv_vec3_make(vvg_spin_value(self->pa[0]), vvg_spin_value(self->pa[1]),
                              vvg_spin_value(self->pa[2]));
    vv_vec3 pb = vv_vec3_make(vvg_spin_value(self->pb[0]), vvg_spin_value(self->pb[1]),
                              vvg_spin_value(self->pb[2]));
    vv_object *o = vvg_document_selected_object(self->doc);
    char t[256];
    snprintf(t, sizeof t, "distance (%g, %g, %g) - (%g, %g, %g): %.6g %s\n", pa.x, pa.y, pa.z, pb.x,
             pb.y, pb.z, vv_vec3_length(vv_vec3_sub(pa, pb)), vvg_unit_label(o ? o->volume : NULL));
    measure_print(self, self->dist_result, t);
    vvg_marks_set_point(self->marks, VVG_MARK_A, pa);
    vvg_marks_set_point(self->marks, VVG_MARK_B, pb);
}

static void
hist_log_toggled(GtkCheckButton *b, gpointer user) {
    (void)b;
    gtk_widget_queue_draw(VVG_MEASUREMENT_PAGE(user)->histogram);
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgMeasurementPage *self = user;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (o && o->volume) {
        double lo = o->volume->range[0], hi = o->volume->range[1];
        gtk_spin_button_set_range(GTK_SPIN_BUTTON(self->measure_iso), lo, hi > lo ? hi : lo + 1);
    }
}

static void
vvg_measurement_page_dispose(GObject *o) {
    VvgMeasurementPage *self = VVG_MEASUREMENT_PAGE(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    g_clear_object(&self->marks);
    vv_histogram_free(self->hist);
    self->hist = NULL;
    G_OBJECT_CLASS(vvg_measurement_page_parent_class)->dispose(o);
}

static void
vvg_measurement_page_class_init(VvgMeasurementPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_measurement_page_dispose;
}

static void
vvg_measurement_page_init(VvgMeasurementPage *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    gtk_widget_set_margin_start(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_end(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_bottom(GTK_WIDGET(self), 8);
}

/* A selectable result line under a button, named for assistive technologies. */
static GtkWidget *
result_label(GtkWidget *box, const char *name) {
    GtkWidget *l = gtk_label_new("");
    gtk_label_set_selectable(GTK_LABEL(l), TRUE);
    gtk_label_set_wrap(GTK_LABEL(l), TRUE);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_widget_add_css_class(l, "monospace");
    vvg_name(l, name);
    gtk_widget_set_visible(l, FALSE);
    gtk_box_append(GTK_BOX(box), l);
    return l;
}

static void
build_isosurface(VvgMeasurementPage *self) {
    GtkWidget *box = GTK_WIDGET(self);
    GtkWidget *g = vvg_section(box, "Isosurface area and volume");
    self->measure_iso = vvg_row(g, "isovalue", vvg_spin0(-1e9, 1e9, 1, 2));
    static const char *const methods[] = {"marching cubes", "voxel counting", NULL};
    self->measure_method = vvg_row(g, "method", gtk_drop_down_new_from_strings(methods));
    self->measure_seed = gtk_check_button_new_with_label("surface-tracked from voxel");
    gtk_grid_attach(GTK_GRID(g), self->measure_seed, 0, vvg_grid_rows(g), 2, 1);
    self->seed_i = vvg_row(g, "i", vvg_spin0(0, 1e5, 1, 0));
    self->seed_j = vvg_row(g, "j", vvg_spin0(0, 1e5, 1, 0));
    self->seed_k = vvg_row(g, "k", vvg_spin0(0, 1e5, 1, 0));
    gtk_box_append(GTK_BOX(box),
                   vvg_action_button("Pick the seed voxel in the view", "win.pick-seed"));
    self->iso_button = vvg_action_button("Measure", "win.measure");
    gtk_box_append(GTK_BOX(box), self->iso_button);
    self->iso_result = result_label(box, "isosurface result");
}

static void
build_distance(VvgMeasurementPage *self) {
    GtkWidget *box = GTK_WIDGET(self);
    GtkWidget *g = vvg_section(box, "Distance (world units)");
    const char *ax[] = {"A x", "A y", "A z", "B x", "B y", "B z"};
    for (int i = 0; i < 3; i++)
        self->pa[i] = vvg_row(g, ax[i], vvg_spin0(-1e6, 1e6, 1, 3));
    for (int i = 0; i < 3; i++)
        self->pb[i] = vvg_row(g, ax[3 + i], vvg_spin0(-1e6, 1e6, 1, 3));
    GtkWidget *pb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(pb), vvg_action_button("Pick A", "win.pick-a"));
    gtk_box_append(GTK_BOX(pb), vvg_action_button("Pick B", "win.pick-b"));
    gtk_box_append(GTK_BOX(box), pb);
    gtk_box_append(GTK_BOX(box), vvg_action_button("Distance", "win.distance"));
    self->dist_result = result_label(box, "distance result");
}

GtkWidget *
vvg_measurement_page_new(VvgDocument *doc, VvgSceneView *scene, VvgMarks *marks,
                         GActionMap *actions) {
    VvgMeasurementPage *self = g_object_new(VVG_TYPE_MEASUREMENT_PAGE, NULL);
    self->doc = g_object_ref(doc);
    self->scene = scene;
    self->marks = g_object_ref(marks);
    const GActionEntry entries[] = {
        {"histogram", act_histogram, NULL, NULL, NULL, {0}},
        {"measure", act_measure, NULL, NULL, NULL, {0}},
        {"distance", act_distance, NULL, NULL, NULL, {0}},
        {"pick-seed", act_pick_seed, NULL, NULL, NULL, {0}},
        {"pick-a", act_pick_a, NULL, NULL, NULL, {0}},
        {"pick-b", act_pick_b, NULL, NULL, NULL, {0}},
    };
    g_action_map_add_action_entries(actions, entries, G_N_ELEMENTS(entries), self);
    GtkWidget *box = GTK_WIDGET(self);
    vvg_section(box, "Histogram");
    self->histogram = gtk_drawing_area_new();
    vvg_name(self->histogram, "histogram");
    gtk_widget_set_size_request(self->histogram, 280, 120);
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(self->histogram), hist_draw, self, NULL);
    gtk_box_append(GTK_BOX(box), self->histogram);
    self->hist_log = gtk_check_button_new_with_label("log scale");
    g_signal_connect(self->hist_log, "toggled", G_CALLBACK(hist_log_toggled), self);
    gtk_box_append(GTK_BOX(box), self->hist_log);
    gtk_box_append(GTK_BOX(box), vvg_action_button("Histogram", "win.histogram"));
    self->hist_result = result_label(box, "histogram result");
    build_isosurface(self);
    build_distance(self);
    GtkWidget *title = gtk_label_new(NULL);
    gtk_label_set_markup(GTK_LABEL(title), "<b>All results (select and copy)</b>");
    gtk_label_set_xalign(GTK_LABEL(title), 0);
    gtk_widget_set_margin_top(title, 8);
    gtk_box_append(GTK_BOX(box), title);
    self->measure_text = gtk_text_view_new();
    vvg_label_for(self->measure_text, title);
    gtk_text_view_set_editable(GTK_TEXT_VIEW(self->measure_text), FALSE);
    gtk_text_view_set_wrap_mode(GTK_TEXT_VIEW(self->measure_text), GTK_WRAP_WORD_CHAR);
    gtk_widget_set_size_request(self->measure_text, -1, 160);
    gtk_box_append(GTK_BOX(box), self->measure_text);
    GtkWidget *copy = gtk_button_new_with_label("Copy all results");
    g_signal_connect(copy, "clicked", G_CALLBACK(copy_results), self);
    gtk_box_append(GTK_BOX(box), copy);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), self);
    selection_changed(doc, self);
    return box;
}
