/* VvgSliceView: an axial, coronal, sagittal or oblique slice view (vvg-slice-view.h). */
#include "vvg-slice-view.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

struct _VvgSliceView {
    GtkBox parent;
    VvgDocument *doc;
    VvgMarks *marks;
    vv_slice_axis axis;
    GtkWidget *orientation, *canvas, *readout;
    gboolean updating;

    /* the last samples and the image made of them */
    vv_slice_plane plane;
    vv_mat4 placed;          /* the object's index-to-world when sampled */
    const vv_volume *volume; /* compared only */
    uint64_t modified;
    float *values;
    size_t n_values;
    /* a multi-channel object: every channel's samples (channel 0's also in
     * values), the channels' volumes sampled and the styles blended */
    int n_channels;
    float *channel_values[VV_MAX_CHANNELS];
    const vv_volume *channel_volume[VV_MAX_CHANNELS];
    vv_tf *channel_tf; /* VV_MAX_CHANNELS, on the heap: GObject instances stay under 64 KiB */
    int channel_visible[VV_MAX_CHANNELS];
    cairo_surface_t *surface;
    double surface_window, surface_level;
    gboolean have_plane;
    double sample_ms;

    FILE *log; /* VOLVIS_SLICE_LOG: a line per resampling */

    /* input */
    int drag_button;
    gboolean drag_wl;
    double wl_start[2], drag_x, drag_y;
};

G_DEFINE_TYPE(VvgSliceView, vvg_slice_view, GTK_TYPE_BOX)

/* Slicer's colours: axial red, coronal green, sagittal yellow; oblique cyan. */
static const double axis_rgb[4][3] = {
    {0.95, 0.35, 0.35}, {0.45, 0.85, 0.45}, {0.95, 0.85, 0.3}, {0.3, 0.85, 0.95}};

/* The volume object shown: the selected one, else the first volume. */
static const vv_object *
shown_object(VvgSliceView *self) {
    vv_object *o = vvg_document_selected_object(self->doc);
    if (o && o->volume && o->type == VV_OBJECT_VOLUME)
        return o;
    vv_world *w = vvg_document_world(self->doc);
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->volume && w->objects[i]->type == VV_OBJECT_VOLUME)
            return w->objects[i];
    return NULL;
}

static vv_vec3
box_centre(const vv_object *o) {
    vv_box b = vv_object_world_box(o);
    return vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
}

/* The cut plane an oblique view follows: the one chosen in the Cut planes
 * list, else the selected object's last local one, else the World's last
 * global one. */
static const vv_cut_plane *
oblique_plane(VvgSliceView *self) {
    vv_world *w = vvg_document_world(self->doc);
    vv_object *o = vvg_document_selected_object(self->doc);
    int co, cp;
    vvg_marks_cut_plane(self->marks, &co, &cp); /* the one chosen in the Cut planes list */
    if (cp >= 0 && co < w->n_objects &&
        cp < (co < 0 ? w->n_cut_planes : w->objects[co]->n_cut_planes))
        return co < 0 ? &w->cut_planes[cp] : &w->objects[co]->cut_planes[cp];
    if (o && o->n_cut_planes > 0)
        return &o->cut_planes[o->n_cut_planes - 1];
    return w->n_cut_planes > 0 ? &w->cut_planes[w->n_cut_planes - 1] : NULL;
}

/* The plane of this view at the canvas's size; FALSE when there is none. */
static gboolean
current_plane(VvgSliceView *self, const vv_object *obj, vv_slice_plane *p) {
    int scale = gtk_widget_get_scale_factor(self->canvas);
    int w = gtk_widget_get_width(self->canvas) * scale,
        h = gtk_widget_get_height(self->canvas) * scale;
    if (w < 8 || h < 8)
        return FALSE;
    vv_vec3 c;
    if (!vvg_marks_cursor(self->marks, &c))
        c = box_centre(obj);
    vv_status s;
    if (self->axis == VV_SLICE_OBLIQUE) {
        const vv_cut_plane *cp = oblique_plane(self);
        if (!cp)
            return FALSE;
        s = vv_slice_plane_oblique(p, obj->volume->space, cp->point, cp->normal, w, h, 1);
    } else {
        s = vv_slice_plane_standard(p, self->axis, obj->volume->space, c, w, h, 1);
    }
    if (s != VV_OK)
        return FALSE;
    vv_slice_plane_fit(p, vv_object_world_box(obj), 0.03);
    return TRUE;
}

/* Samples again when the plane, the volume or its placement changed. */
static void
update_samples(VvgSliceView *self, const vv_object *obj, const vv_slice_plane *p) {
    vv_mat4 m = vv_object_index_to_world(obj);
    gboolean same_channels = obj->n_channels == self->n_channels;
    for (int c = 0; same_channels && c < obj->n_channels; c++)
        same_channels = obj->channels[c].volume == self->channel_volume[c];
    if (self->have_plane && self->volume == obj->volume && same_channels &&
        self->modified == obj->volume->modified && !memcmp(&m, &self->placed, sizeof m) &&
        !memcmp(p, &self->plane, sizeof *p))
        return;
    size_t n = (size_t)p->width * p->height;
    if (n != self->n_values || obj->n_channels != self->n_channels) {
        g_free(self->values);
        self->values = g_new(float, n);
        self->n_values = n;
        for (int c = 0; c < VV_MAX_CHANNELS; c++)
            g_clear_pointer(&self->channel_values[c], g_free);
        for (int c = 0; c < obj->n_channels; c++)
            self->channel_values[c] = g_new(float, n);
        self->n_channels = obj->n_channels;
    }
    gint64 t0 = g_get_monotonic_time();
    /* an object out of core is sampled from its file (vv_slice_sample) */
    vv_error_clear();
    gboolean ok = vv_slice_sample(obj, p, self->values) == VV_OK;
    if (!ok && vvg_object_source(obj))
        g_warning("volvis-gui: slice views: %s", vv_error_message());
    for (int c = 0; ok && c < obj->n_channels; c++) {
        ok = vv_slice_sample_channel(obj, c, p, self->channel_values[c]) == VV_OK;
        self->channel_volume[c] = obj->channels[c].volume;
    }
    if (!ok) {
        self->have_plane = FALSE;
        return;
    }
    self->sample_ms = (g_get_monotonic_time() - t0) * 1e-3;
    if (self->log) {
        vv_vec3 nrm = vv_slice_plane_normal(p);
        fprintf(self->log, "%.3f %s %dx%d %.3f %.6g\n", g_get_monotonic_time() * 1e-3,
                vv_slice_axis_name(self->axis), p->width, p->height, self->sample_ms,
                vv_vec3_dot(nrm, p->center));
        fflush(self->log);
    }
    self->plane = *p;
    self->placed = m;
    self->volume = obj->volume;
    self->modified = obj->volume->modified;
    self->have_plane = TRUE;
    g_clear_pointer(&self->surface, cairo_surface_destroy);
}

/* A new image of the plane's size in place of the last; its pixels and row stride. */
static unsigned char *
new_surface(VvgSliceView *self, int *stride) {
    g_clear_pointer(&self->surface, cairo_surface_destroy);
    self->surface =
        cairo_image_surface_create(CAIRO_FORMAT_RGB24, self->plane.width, self->plane.height);
    cairo_surface_flush(self->surface);
    *stride = cairo_image_surface_get_stride(self->surface);
    return cairo_image_surface_get_data(self->surface);
}

/* The channels of a multi-channel object blended by their transfer
 * functions (vv_slice_blend_channels), again only when one changed. */
static void
update_channel_surface(VvgSliceView *self, const vv_object *obj) {
    gboolean same = self->surface != NULL && self->channel_tf != NULL;
    for (int c = 0; same && c < obj->n_channels; c++)
        same = obj->channels[c].visible == self->channel_visible[c] &&
               !memcmp(&obj->channels[c].tf, &self->channel_tf[c], sizeof(vv_tf));
    if (same)
        return;
    int w = self->plane.width, h = self->plane.height, stride;
    unsigned char *data = new_surface(self, &stride);
    const float *rows[VV_MAX_CHANNELS];
    for (int y = 0; y < h; y++) {
        for (int c = 0; c < obj->n_channels; c++)
            rows[c] = self->channel_values[c] + (size_t)y * w;
        unsigned char *px = data + (size_t)y * stride;
        vv_slice_blend_channels(obj, rows, (size_t)w, vv_vec3_make(0, 0, 0), px);
        for (int x = 0; x < w;
             x++) { /* RGBA bytes to CAIRO_FORMAT_RGB24's native-endian 0x00RRGGBB words */
            unsigned char *q = px + 4 * (size_t)x;
            guint32 word = (guint32)q[0] << 16 | (guint32)q[1] << 8 | q[2];
            memcpy(q, &word, 4);
        }
    }
    cairo_surface_mark_dirty(self->surface);
    if (!self->channel_tf)
        self->channel_tf = g_new0(vv_tf, VV_MAX_CHANNELS);
    for (int c = 0; c < obj->n_channels; c++) {
        self->channel_tf[c] = obj->channels[c].tf;
        self->channel_visible[c] = obj->channels[c].visible;
    }
}

/* The grey image of the samples at the marks' window and level; a
 * multi-channel object's channels blended in their colours. */
static void
update_surface(VvgSliceView *self, const vv_object *obj) {
    if (obj->n_channels > 0) {
        update_channel_surface(self, obj);
        return;
    }
    double win, lev;
    vvg_marks_window_for(self->marks, obj->volume, &win, &lev);
    if (self->surface && win == self->surface_window && lev == self->surface_level)
        return;
    int w = self->plane.width, h = self->plane.height, stride;
    unsigned char *data = new_surface(self, &stride);
    for (int y = 0; y < h; y++) /* grey, black outside: the byte order does not matter */
        vv_slice_window_level(self->values + (size_t)y * w, (size_t)w, win, lev,
                              vv_vec3_make(0, 0, 0), data + (size_t)y * stride);
    cairo_surface_mark_dirty(self->surface);
    self->surface_window = win;
    self->surface_level = lev;
}

/* "value 43 at voxel (125, 102, 54), (120.5, 98, 60) mm" for the cursor. */
static void
update_readout(VvgSliceView *self, const vv_object *obj) {
    char text[320];
    vv_vec3 c;
    if (!obj) {
        snprintf(text, sizeof text, "no volume");
    } else if (self->axis == VV_SLICE_OBLIQUE && !oblique_plane(self)) {
        snprintf(text, sizeof text, "oblique: add a cut plane (Cut planes page)");
    } else {
        if (!vvg_marks_cursor(self->marks, &c))
            c = box_centre(obj);
        double ijk[3];
        double v = vv_slice_probe(obj, c, ijk); /* out of core: from level 0 of the file */
        const char *unit = vvg_unit_label(obj->volume);
        if (isnan(v))
            snprintf(text, sizeof text, "%s: outside the volume at (%.6g, %.6g, %.6g) %s",
                     vv_slice_axis_name(self->axis), c.x, c.y, c.z, unit);
        else
            snprintf(text, sizeof text,
                     "%s: value %.6g at voxel (%.6g, %.6g, %.6g), (%.6g, %.6g, %.6g) %s",
                     vv_slice_axis_name(self->axis), v, ijk[0], ijk[1], ijk[2], c.x, c.y, c.z,
                     unit);
    }
    if (g_strcmp0(gtk_label_get_text(GTK_LABEL(self->readout)), text))
        gtk_label_set_text(GTK_LABEL(self->readout), text);
}

/* Where world point @p w is in the canvas (widget pixels). */
static void
to_canvas(VvgSliceView *self, vv_vec3 w, double *x, double *y) {
    int scale = gtk_widget_get_scale_factor(self->canvas);
    vv_slice_plane_from_world(&self->plane, w, x, y, NULL);
    *x /= scale;
    *y /= scale;
}

static void
draw_mark(cairo_t *cr, VvgSliceView *self, vv_vec3 p, double r, double g, double b) {
    double x, y, d;
    vv_slice_plane_from_world(&self->plane, p, &x, &y, &d);
    int scale = gtk_widget_get_scale_factor(self->canvas);
    /* drawn full within two pixels of the slice, faint further away */
    double near = fabs(d) <= 2 * self->plane.pixel;
    cairo_set_source_rgba(cr, r, g, b, near ? 1.0 : 0.35);
    cairo_arc(cr, x / scale, y / scale, near ? 5 : 3, 0, 2 * G_PI);
    cairo_fill(cr);
}

/* Where the surface-tracked region cuts the slice: a segment per triangle. */
static void
draw_region(cairo_t *cr, VvgSliceView *self, const vv_mesh *m) {
    vv_vec3 n = vv_slice_plane_normal(&self->plane);
    double off = vv_vec3_dot(n, self->plane.center);
    cairo_set_source_rgba(cr, 1.0, 0.4, 1.0, 0.9);
    cairo_set_line_width(cr, 1.5);
    for (size_t t = 0; t < m->n_triangles; t++) {
        vv_vec3 v[3];
        double d[3];
        for (int k = 0; k < 3; k++) {
            const float *q = m->positions + 3 * (size_t)m->triangles[3 * t + (size_t)k];
            v[k] = vv_vec3_make(q[0], q[1], q[2]);
            d[k] = vv_vec3_dot(n, v[k]) - off;
        }
        vv_vec3 pts[2];
        int np = 0;
        for (int k = 0; k < 3 && np < 2; k++) {
            int l = (k + 1) % 3;
            if ((d[k] < 0) != (d[l] < 0)) {
                double s = d[k] / (d[k] - d[l]);
                pts[np++] = vv_vec3_add(v[k], vv_vec3_scale(vv_vec3_sub(v[l], v[k]), s));
            }
        }
        if (np == 2) {
            double x0, y0, x1, y1;
            to_canvas(self, pts[0], &x0, &y0);
            to_canvas(self, pts[1], &x1, &y1);
            cairo_move_to(cr, x0, y0);
            cairo_line_to(cr, x1, y1);
        }
    }
    cairo_stroke(cr);
}

static void
draw_labels(cairo_t *cr, VvgSliceView *self, int W, int H) {
    cairo_set_source_rgb(cr, axis_rgb[self->axis][0], axis_rgb[self->axis][1],
                         axis_rgb[self->axis][2]);
    cairo_select_font_face(cr, "Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 13);
    const double pos[4][2] = {
        {W - 18.0, H / 2.0}, {4.0, H / 2.0}, {W / 2.0, 16.0}, {W / 2.0, H - 6.0}};
    for (int e = 0; e < 4; e++) {
        cairo_move_to(cr, pos[e][0], pos[e][1]);
        cairo_show_text(cr, self->plane.edge[e]);
    }
}

/* The crosshair, marks, region and edge labels over the image. */
static void
draw_overlays(cairo_t *cr, VvgSliceView *self, const vv_object *obj, int W, int H) {
    vv_vec3 c;
    if (!vvg_marks_cursor(self->marks, &c))
        c = box_centre(obj);
    double cx, cy;
    to_canvas(self, c, &cx, &cy);
    cairo_set_line_width(cr, 1);
    cairo_set_source_rgba(cr, axis_rgb[self->axis][0], axis_rgb[self->axis][1],
                          axis_rgb[self->axis][2], 0.8);
    cairo_move_to(cr, 0, floor(cy) + 0.5);
    cairo_line_to(cr, cx - 8, floor(cy) + 0.5);
    cairo_move_to(cr, cx + 8, floor(cy) + 0.5);
    cairo_line_to(cr, W, floor(cy) + 0.5);
    cairo_move_to(cr, floor(cx) + 0.5, 0);
    cairo_line_to(cr, floor(cx) + 0.5, cy - 8);
    cairo_move_to(cr, floor(cx) + 0.5, cy + 8);
    cairo_line_to(cr, floor(cx) + 0.5, H);
    cairo_stroke(cr);
    const vv_mesh *region = vvg_marks_region(self->marks);
    if (region)
        draw_region(cr, self, region);
    static const double mark_rgb[VVG_MARK_COUNT][3] = {{0.2, 1, 0.4}, {1, 0.6, 0.2}, {1, 0.3, 1}};
    vv_vec3 p[VVG_MARK_COUNT];
    gboolean has[VVG_MARK_COUNT];
    for (int k = 0; k < VVG_MARK_COUNT; k++) {
        has[k] = vvg_marks_point(self->marks, (VvgMark)k, &p[k]);
        if (has[k])
            draw_mark(cr, self, p[k], mark_rgb[k][0], mark_rgb[k][1], mark_rgb[k][2]);
    }
    if (has[VVG_MARK_A] && has[VVG_MARK_B]) {
        double ax, ay, bx, by;
        to_canvas(self, p[VVG_MARK_A], &ax, &ay);
        to_canvas(self, p[VVG_MARK_B], &bx, &by);
        cairo_set_source_rgba(cr, 1, 1, 0.3, 0.8);
        cairo_move_to(cr, ax, ay);
        cairo_line_to(cr, bx, by);
        cairo_stroke(cr);
    }
    draw_labels(cr, self, W, H);
}

static void
canvas_draw(GtkDrawingArea *area, cairo_t *cr, int W, int H, gpointer user) {
    (void)area;
    VvgSliceView *self = user;
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_paint(cr);
    const vv_object *obj = shown_object(self);
    update_readout(self, obj);
    vv_slice_plane p;
    if (!obj || !current_plane(self, obj, &p)) {
        self->have_plane = FALSE;
        cairo_set_source_rgb(cr, 0.6, 0.6, 0.6);
        cairo_move_to(cr, 12, H / 2.0);
        cairo_set_font_size(cr, 13);
        cairo_show_text(cr, !obj ? "no volume" : "oblique: add a cut plane");
        return;
    }
    update_samples(self, obj, &p);
    if (!self->have_plane)
        return;
    update_surface(self, obj);
    int scale = gtk_widget_get_scale_factor(self->canvas);
    cairo_save(cr);
    cairo_scale(cr, 1.0 / scale, 1.0 / scale);
    cairo_set_source_surface(cr, self->surface, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_paint(cr);
    cairo_restore(cr);
    draw_overlays(cr, self, obj, W, H);
}

static void
redraw(VvgSliceView *self) {
    gtk_widget_queue_draw(self->canvas);
    update_readout(self, shown_object(self));
}

/* ---- input ------------------------------------------------------------------- */

/* The world point under canvas position (x, y), in the plane on screen. */
static gboolean
canvas_world(VvgSliceView *self, double x, double y, vv_vec3 *out) {
    if (!self->have_plane)
        return FALSE;
    int scale = gtk_widget_get_scale_factor(self->canvas);
    *out = vv_slice_plane_to_world(&self->plane, x * scale, y * scale);
    return TRUE;
}

static void
drag_begin(GtkGestureDrag *g, double x, double y, gpointer user) {
    VvgSliceView *self = user;
    self->drag_button = (int)gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(g));
    GdkModifierType mods = gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(g));
    self->drag_wl = self->drag_button == 3 || (mods & GDK_CONTROL_MASK);
    self->drag_x = x;
    self->drag_y = y;
    const vv_object *obj = shown_object(self);
    if (!obj)
        return;
    if (self->drag_wl) {
        vvg_marks_window_for(self->marks, obj->volume, &self->wl_start[0], &self->wl_start[1]);
        return;
    }
    vv_vec3 w;
    if (canvas_world(self, x, y, &w))
        vvg_marks_set_cursor(self->marks, w);
}

static void
drag_update(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    (void)g;
    VvgSliceView *self = user;
    if (self->drag_wl) {
        /* right: a wider window (twice as wide for 150 pixels); up: a higher level */
        double win = self->wl_start[0] * exp(ox / 150.0);
        double lev = self->wl_start[1] - oy * self->wl_start[0] / 300.0;
        vvg_marks_set_window(self->marks, win, lev);
        return;
    }
    vv_vec3 w;
    if (canvas_world(self, self->drag_x + ox, self->drag_y + oy, &w))
        vvg_marks_set_cursor(self->marks, w);
}

static gboolean
scroll_cb(GtkEventControllerScroll *ctl, double dx, double dy, gpointer user) {
    (void)ctl;
    (void)dx;
    VvgSliceView *self = user;
    const vv_object *obj = shown_object(self);
    if (!obj || !self->have_plane || !isfinite(dy) || dy == 0)
        return FALSE;
    vv_vec3 n = vv_slice_plane_normal(&self->plane);
    double step = vv_slice_step(obj, n);
    vv_vec3 c;
    if (!vvg_marks_cursor(self->marks, &c))
        c = box_centre(obj);
    if (self->axis == VV_SLICE_OBLIQUE)
        return FALSE; /* the cut plane moves it (Cut planes page, or its handle) */
    /* wheel up: towards the viewer of the image, one slice a notch */
    vvg_marks_set_cursor(self->marks, vv_vec3_add(c, vv_vec3_scale(n, -dy * step)));
    return TRUE;
}

static void set_names(VvgSliceView *self);

static void
orientation_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvgSliceView *self = user;
    if (self->updating)
        return;
    vvg_slice_view_set_axis(self, (vv_slice_axis)gtk_drop_down_get_selected(GTK_DROP_DOWN(o)));
}

static void
marks_changed(VvgMarks *m, gpointer user) {
    (void)m;
    redraw(user);
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    redraw(user);
}

/* ---- life cycle ---------------------------------------------------------------- */

static void
vvg_slice_view_dispose(GObject *o) {
    VvgSliceView *self = VVG_SLICE_VIEW(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    if (self->marks) {
        g_signal_handlers_disconnect_by_data(self->marks, self);
        g_clear_object(&self->marks);
    }
    g_clear_pointer(&self->surface, cairo_surface_destroy);
    g_clear_pointer(&self->values, g_free);
    for (int c = 0; c < VV_MAX_CHANNELS; c++)
        g_clear_pointer(&self->channel_values[c], g_free);
    g_clear_pointer(&self->channel_tf, g_free);
    g_clear_pointer(&self->log, fclose);
    G_OBJECT_CLASS(vvg_slice_view_parent_class)->dispose(o);
}

static void
vvg_slice_view_class_init(VvgSliceViewClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_slice_view_dispose;
}

static void
vvg_slice_view_init(VvgSliceView *self) {
    gtk_orientable_set_orientation(GTK_ORIENTABLE(self), GTK_ORIENTATION_VERTICAL);
    gtk_box_set_spacing(GTK_BOX(self), 2);
    static const char *const axes[] = {"axial", "coronal", "sagittal", "oblique (cut plane)", NULL};
    self->orientation = gtk_drop_down_new_from_strings(axes);
    gtk_widget_set_halign(self->orientation, GTK_ALIGN_START);
    g_signal_connect(self->orientation, "notify::selected", G_CALLBACK(orientation_changed), self);
    gtk_box_append(GTK_BOX(self), self->orientation);
    self->canvas = gtk_drawing_area_new();
    gtk_widget_set_vexpand(self->canvas, TRUE);
    gtk_widget_set_hexpand(self->canvas, TRUE);
    gtk_widget_set_size_request(self->canvas, 96, 96);
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(self->canvas), canvas_draw, self, NULL);
    gtk_box_append(GTK_BOX(self), self->canvas);
    self->readout = gtk_label_new("");
    gtk_label_set_xalign(GTK_LABEL(self->readout), 0);
    gtk_label_set_selectable(GTK_LABEL(self->readout), TRUE);
    gtk_label_set_ellipsize(GTK_LABEL(self->readout), PANGO_ELLIPSIZE_END);
    gtk_box_append(GTK_BOX(self), self->readout);
    for (int button = 1; button <= 3; button += 2) {
        GtkGesture *drag = gtk_gesture_drag_new();
        gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(drag), (guint)button);
        g_signal_connect(drag, "drag-begin", G_CALLBACK(drag_begin), self);
        g_signal_connect(drag, "drag-update", G_CALLBACK(drag_update), self);
        gtk_widget_add_controller(self->canvas, GTK_EVENT_CONTROLLER(drag));
    }
    GtkEventController *scroll = gtk_event_controller_scroll_new(
        GTK_EVENT_CONTROLLER_SCROLL_VERTICAL | GTK_EVENT_CONTROLLER_SCROLL_DISCRETE);
    g_signal_connect(scroll, "scroll", G_CALLBACK(scroll_cb), self);
    gtk_widget_add_controller(self->canvas, scroll);
    const char *log = g_getenv("VOLVIS_SLICE_LOG");
    if (log && *log && !(self->log = fopen(log, "a")))
        g_warning("volvis-gui: VOLVIS_SLICE_LOG: cannot open %s", log);
}

static void
set_names(VvgSliceView *self) {
    const char *n = vv_slice_axis_name(self->axis);
    g_autofree char *view = g_strdup_printf("%s view", n);
    g_autofree char *orient = g_strdup_printf("orientation of the %s view", n);
    g_autofree char *readout = g_strdup_printf("%s readout", n);
    vvg_name(self->canvas, view);
    vvg_name(self->orientation, orient);
    if (gtk_widget_get_first_child(self->orientation)) /* the button that takes the focus */
        vvg_name(gtk_widget_get_first_child(self->orientation), orient);
    vvg_name(self->readout, readout);
}

GtkWidget *
vvg_slice_view_new(VvgDocument *doc, VvgMarks *marks, vv_slice_axis axis) {
    VvgSliceView *self = g_object_new(VVG_TYPE_SLICE_VIEW, NULL);
    self->doc = g_object_ref(doc);
    self->marks = g_object_ref(marks);
    vvg_slice_view_set_axis(self, axis);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(doc_changed), self);
    g_signal_connect(marks, "changed", G_CALLBACK(marks_changed), self);
    return GTK_WIDGET(self);
}

void
vvg_slice_view_set_axis(VvgSliceView *self, vv_slice_axis axis) {
    self->axis = (int)axis >= 0 && axis <= VV_SLICE_OBLIQUE ? axis : VV_SLICE_AXIAL;
    self->updating = TRUE;
    gtk_drop_down_set_selected(GTK_DROP_DOWN(self->orientation), (guint)self->axis);
    self->updating = FALSE;
    self->have_plane = FALSE;
    set_names(self);
    redraw(self);
}

vv_slice_axis
vvg_slice_view_axis(VvgSliceView *self) {
    return self->axis;
}

const char *
vvg_slice_view_readout(VvgSliceView *self) {
    return gtk_label_get_text(GTK_LABEL(self->readout));
}

double
vvg_slice_view_sample_ms(VvgSliceView *self) {
    return self->sample_ms;
}
