/* VvgAnimatorPage: the Animator page (vvg-animator-page.h): its widgets, the
 * animation's summary and timeline, sequences, camera and time-step keys, New,
 * Open and Save. Play, Record flight and the final render are
 * vvg-animator-play.c. */
#include "vvg-animator-play.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The timeline's background: also what tests/gui/animator_session.sh looks
 * for in a screenshot to find the page's controls. */
#define TIMELINE_R 31
#define TIMELINE_G 42
#define TIMELINE_B 51

G_DEFINE_TYPE(VvgAnimatorPage, vvg_animator_page, GTK_TYPE_BOX)

/* ---- small helpers --------------------------------------------------------- */

static double
spin_value(GtkWidget *s) {
    return gtk_spin_button_get_value(GTK_SPIN_BUTTON(s));
}

/* A row of buttons of equal width spanning the page (the GUI test clicks
 * them at fractions of the timeline's width). */
static GtkWidget *
button_row(GtkWidget *box) {
    GtkWidget *r = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_set_homogeneous(GTK_BOX(r), TRUE);
    gtk_box_append(GTK_BOX(box), r);
    return r;
}

static GtkWidget *
add_button(GtkWidget *row_box, GtkWidget *b, GCallback cb, gpointer user) {
    g_signal_connect(b, GTK_IS_TOGGLE_BUTTON(b) ? "toggled" : "clicked", cb, user);
    gtk_widget_set_hexpand(b, TRUE);
    gtk_box_append(GTK_BOX(row_box), b);
    return b;
}

/* A one-line label: the rows below it stay where they are. */
static GtkWidget *
line_label(void) {
    GtkWidget *l = gtk_label_new("");
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_label_set_ellipsize(GTK_LABEL(l), PANGO_ELLIPSIZE_END);
    return l;
}

static GtkWindow *
parent_window(VvgAnimatorPage *self) {
    GtkRoot *root = gtk_widget_get_root(GTK_WIDGET(self));
    return root && GTK_IS_WINDOW(root) ? GTK_WINDOW(root) : NULL;
}

static void
show_error(VvgAnimatorPage *self, const char *what, const char *message) {
    vvg_show_error(GTK_WIDGET(self), what, message);
}

/* A copy of the library's message before anything else can replace it. */
void
vvg_animator_show_library_error(VvgAnimatorPage *self, const char *what) {
    char m[1024];
    g_strlcpy(m, vv_error_message(), sizeof m);
    show_error(self, what, m);
}

static char *
dup_malloc(const char *s) {
    /* strings the library frees with free() */
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

/* A one-line label's text; the tooltip holds the whole text when the line is cut. */
void
vvg_animator_set_label_tip(GtkWidget *label, const char *text) {
    gtk_label_set_text(GTK_LABEL(label), text);
    gtk_widget_set_tooltip_text(label, text[0] ? text : NULL);
}

/* The page's status line: what was opened, saved or recorded. */
void
vvg_animator_set_status(VvgAnimatorPage *self, const char *text) {
    vvg_animator_set_label_tip(self->anim_status, text);
}

/* ---- the animation and its summary ---------------------------------------------- */

static char *
track_text(const vv_anim_track *t) {
    static const char *const interp[] = {"spline", "linear", "step"};
    GString *s = g_string_new(NULL);
    g_string_append_printf(s, "%s (%s%s): %d key%s at", t->property,
                           t->interp >= 0 && t->interp <= 2 ? interp[t->interp] : "?",
                           t->closed ? ", closed" : "", t->n_keys, t->n_keys == 1 ? "" : "s");
    for (int k = 0; k < t->n_keys && k < 12; k++)
        g_string_append_printf(s, "%s %.4g", k ? "," : "", t->keys[k].time);
    if (t->n_keys > 12)
        g_string_append(s, ", …");
    g_string_append(s, " s");
    return g_string_free(s, FALSE);
}

static char *
sequence_text(const vv_anim_sequence *q) {
    switch (q->type) {
    case VV_SEQ_ORBIT:
        return g_strdup_printf("orbit the camera by %g° (from azimuth %g°, elevation %g°, zoom %g)",
                               q->degrees, q->azimuth, q->elevation, q->zoom);
    case VV_SEQ_ROTATE_OBJECT:
        return g_strdup_printf("rotate %s by %g° about (%g, %g, %g)", q->object, q->degrees,
                               q->axis.x, q->axis.y, q->axis.z);
    case VV_SEQ_FLY:
        return g_strdup_printf("fly by (%g, %g, %g) world units", q->offset.x, q->offset.y,
                               q->offset.z);
    case VV_SEQ_SWEEP_CUT:
        return g_strdup_printf("sweep a cut plane from (%g, %g, %g) along (%g, %g, %g) by %g "
                               "world units",
                               q->point.x, q->point.y, q->point.z, q->normal.x, q->normal.y,
                               q->normal.z, q->distance);
    }
    return g_strdup("unknown sequence");
}

static void
rebuild_list(VvgAnimatorPage *self) {
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(self->list)))
        gtk_list_box_remove(GTK_LIST_BOX(self->list), c);
    const vv_animation *a = self->anim;
    for (int i = 0; i < a->n_tracks + a->n_sequences; i++) {
        char *text = i < a->n_tracks ? track_text(&a->tracks[i])
                                     : sequence_text(&a->sequences[i - a->n_tracks]);
        GtkWidget *l = gtk_label_new(text);
        gtk_label_set_xalign(GTK_LABEL(l), 0);
        gtk_label_set_wrap(GTK_LABEL(l), TRUE);
        gtk_label_set_wrap_mode(GTK_LABEL(l), PANGO_WRAP_WORD_CHAR);
        gtk_list_box_append(GTK_LIST_BOX(self->list), l);
        g_free(text);
    }
    if (a->n_tracks + a->n_sequences == 0) {
        GtkWidget *l = gtk_label_new("empty: add a sequence, camera keys or a flight");
        gtk_list_box_append(GTK_LIST_BOX(self->list), l);
        GtkListBoxRow *r = gtk_list_box_get_row_at_index(GTK_LIST_BOX(self->list), 0);
        gtk_list_box_row_set_selectable(r, FALSE);
        gtk_list_box_row_set_activatable(r, FALSE);
    }
}

/* The time the timeline's head shows: Play's, else the key time. */
static double
head_time(VvgAnimatorPage *self) {
    return self->playing ? self->play_time : spin_value(self->key_time);
}

void
vvg_animator_update_time_label(VvgAnimatorPage *self) {
    const vv_animation *a = self->playing ? self->playing : self->anim;
    int n = vv_animation_frame_count(a);
    double t = head_time(self);
    double fd = floor(t * a->fps + 1e-9);
    int f = fd < 0 ? 0 : fd >= n - 1 ? n - 1 : (int)fd;
    char text[160];
    snprintf(text, sizeof text, "%st = %.2f s of %.2f s, frame %d of %d",
             self->playing ? "playing: " : "", t, a->duration, f, n);
    gtk_label_set_text(GTK_LABEL(self->time_label), text);
    gtk_widget_queue_draw(self->timeline);
}

static void
fill_timing(VvgAnimatorPage *self) {
    self->updating = TRUE;
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(self->fps), self->anim->fps);
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(self->frames), vv_animation_frame_count(self->anim));
    self->updating = FALSE;
}

static void
refresh(VvgAnimatorPage *self) {
    fill_timing(self);
    rebuild_list(self);
    vvg_animator_update_time_label(self);
}

/* Takes @p a as the current animation. */
void
vvg_animator_set_animation(VvgAnimatorPage *self, vv_animation *a) {
    vv_animation_free(self->anim);
    self->anim = a;
    refresh(self);
}

/* A copy of @p a without track @p skip_track and sequence @p skip_seq (-1:
 * none), through the public API (the library owns the keys' memory). */
static vv_status
copy_without(const vv_animation *a, int skip_track, int skip_seq, vv_animation **out) {
    *out = NULL;
    vv_animation *c = NULL;
    vv_status s = vv_animation_new(&c);
    if (s != VV_OK)
        return s;
    c->fps = a->fps;
    c->duration = a->duration;
    if (a->scene && !(c->scene = dup_malloc(a->scene)))
        s = VV_ERR_NOMEM;
    for (int i = 0; s == VV_OK && i < a->n_tracks; i++) {
        if (i == skip_track)
            continue;
        const vv_anim_track *t = &a->tracks[i];
        int idx = -1;
        s = vv_animation_add_track(c, t->property, &idx);
        for (int k = 0; s == VV_OK && k < t->n_keys; k++)
            s = vv_anim_track_add_key(&c->tracks[idx], &t->keys[k]);
        if (s == VV_OK) {
            c->tracks[idx].interp = t->interp;
            c->tracks[idx].closed = t->closed;
        }
    }
    for (int i = 0; s == VV_OK && i < a->n_sequences; i++)
        if (i != skip_seq)
            s = vv_animation_add_sequence(c, &a->sequences[i]);
    if (s != VV_OK) {
        vv_animation_free(c);
        return s;
    }
    *out = c;
    return VV_OK;
}

static void
remove_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    GtkListBoxRow *r = gtk_list_box_get_selected_row(GTK_LIST_BOX(self->list));
    int i = r ? gtk_list_box_row_get_index(r) : -1;
    int nt = self->anim->n_tracks;
    if (i < 0 || i >= nt + self->anim->n_sequences)
        return;
    vv_animation *c = NULL;
    vv_error_clear();
    if (copy_without(self->anim, i < nt ? i : -1, i < nt ? -1 : i - nt, &c) != VV_OK) {
        vvg_animator_show_library_error(self, "Cannot remove it");
        return;
    }
    vvg_animator_set_animation(self, c);
}

static void
fps_changed(GtkSpinButton *s, gpointer user) {
    VvgAnimatorPage *self = user;
    if (self->updating)
        return;
    /* the keys are in seconds: the duration stays, the frame count follows */
    self->anim->fps = gtk_spin_button_get_value(s);
    fill_timing(self);
    vvg_animator_update_time_label(self);
}

static void
frames_changed(GtkSpinButton *s, gpointer user) {
    VvgAnimatorPage *self = user;
    if (self->updating)
        return;
    self->anim->duration = gtk_spin_button_get_value(s) / self->anim->fps;
    vvg_animator_update_time_label(self);
}

/* ---- the timeline ------------------------------------------------------------------- */

static void
timeline_draw(GtkDrawingArea *area, cairo_t *cr, int W, int H, gpointer user) {
    (void)area;
    VvgAnimatorPage *self = user;
    const vv_animation *a = self->anim;
    cairo_set_source_rgb(cr, TIMELINE_R / 255.0, TIMELINE_G / 255.0, TIMELINE_B / 255.0);
    cairo_paint(cr);
    double dur = a->duration > 0 ? a->duration : 1;
    /* second marks (or coarser) along the bottom */
    double step = pow(10, ceil(log10(dur / 20)));
    step = step < 1 ? 1 : step;
    cairo_set_source_rgb(cr, 0.40, 0.47, 0.53);
    cairo_set_line_width(cr, 1);
    for (double t = 0; t <= dur + 1e-9; t += step) {
        double x = floor(t / dur * (W - 1)) + 0.5;
        cairo_move_to(cr, x, H - 6);
        cairo_line_to(cr, x, H);
    }
    cairo_stroke(cr);
    /* one lane per sequence (a bar: it runs over the whole animation) and
     * per track (a mark at each key) */
    int lanes = a->n_tracks + a->n_sequences;
    double lh = lanes > 0 ? fmin(8, (H - 10.0) / lanes) : 8;
    double y = 2;
    cairo_set_source_rgb(cr, 115 / 255.0, 191 / 255.0, 115 / 255.0); /* the test looks for it */
    for (int i = 0; i < a->n_sequences; i++, y += lh)
        cairo_rectangle(cr, 0, y, W, fmax(1, lh - 1));
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 242 / 255.0, 209 / 255.0, 77 / 255.0);
    for (int i = 0; i < a->n_tracks; i++, y += lh)
        for (int k = 0; k < a->tracks[i].n_keys; k++) {
            double x = a->tracks[i].keys[k].time / dur * (W - 1);
            cairo_rectangle(cr, x - 1.5, y, 3, fmax(1, lh - 1));
        }
    cairo_fill(cr);
    /* the head */
    double x = floor(fmin(fmax(head_time(self) / dur, 0), 1) * (W - 1)) + 0.5;
    cairo_set_source_rgb(cr, 1.0, 0.45, 0.1);
    cairo_move_to(cr, x, 0);
    cairo_line_to(cr, x, H);
    cairo_stroke(cr);
}

/* A click on the timeline sets the key time (to a frame's time). */
static void
timeline_pressed(GtkGestureClick *g, int n, double x, double y, gpointer user) {
    (void)g;
    (void)n;
    (void)y;
    VvgAnimatorPage *self = user;
    int W = gtk_widget_get_width(self->timeline);
    if (W < 2)
        return;
    double t = fmin(fmax(x / (W - 1), 0), 1) * self->anim->duration;
    t = round(t * self->anim->fps) / self->anim->fps;
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(self->key_time), t);
    vvg_animator_update_time_label(self);
}

/* ---- sequences and keys --------------------------------------------------------------- */

static const char *const seq_names[] = {"orbit the camera", "rotate the selected object",
                                        "fly along a line", "sweep a cut plane", NULL};
static const char *const seq_pages[] = {"orbit", "rotate", "fly", "sweep"};

static void
seq_type_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvgAnimatorPage *self = user;
    guint i = gtk_drop_down_get_selected(GTK_DROP_DOWN(o));
    if (i < G_N_ELEMENTS(seq_pages))
        gtk_stack_set_visible_child_name(GTK_STACK(self->seq_stack), seq_pages[i]);
}

static vv_vec3
axis_vector(guint i) {
    vv_vec3 a = vv_vec3_make(i % 3 == 0, i % 3 == 1, i % 3 == 2);
    return i >= 3 ? vv_vec3_scale(a, -1) : a;
}

static void
add_sequence_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.zoom = 1;
    const vv_world *w = vvg_document_world(self->doc);
    switch (gtk_drop_down_get_selected(GTK_DROP_DOWN(self->seq_type))) {
    case 0:
        q.type = VV_SEQ_ORBIT;
        q.degrees = spin_value(self->orbit_degrees);
        q.elevation = spin_value(self->orbit_elevation);
        break;
    case 1: {
        const vv_object *o = vvg_document_selected_object(self->doc);
        if (!o) {
            show_error(self, "No object to rotate", "select an object on the Manipulation page");
            return;
        }
        q.type = VV_SEQ_ROTATE_OBJECT;
        g_strlcpy(q.object, o->name, sizeof q.object);
        q.axis = axis_vector(gtk_drop_down_get_selected(GTK_DROP_DOWN(self->rot_axis)));
        q.degrees = spin_value(self->rot_degrees);
        break;
    }
    case 2:
        q.type = VV_SEQ_FLY;
        q.offset = vv_vec3_make(spin_value(self->fly[0]), spin_value(self->fly[1]),
                                spin_value(self->fly[2]));
        break;
    default: {
        /* a plane facing +axis (or -axis) swept across the World's bounds, as
         * `volvis animate --sweep-cut AXIS` does */
        guint i = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->sweep_axis));
        vv_box bx = vv_world_bounds(w);
        double lo[3] = {bx.min.x, bx.min.y, bx.min.z}, hi[3] = {bx.max.x, bx.max.y, bx.max.z};
        double c[3];
        int ax = (int)(i % 3);
        for (int k = 0; k < 3; k++)
            c[k] = 0.5 * (lo[k] + hi[k]);
        c[ax] = i >= 3 ? hi[ax] : lo[ax];
        q.type = VV_SEQ_SWEEP_CUT;
        q.point = vv_vec3_make(c[0], c[1], c[2]);
        q.normal = axis_vector(i);
        q.distance = hi[ax] - lo[ax];
        break;
    }
    }
    vv_error_clear();
    if (vv_animation_add_sequence(self->anim, &q) != VV_OK) {
        vvg_animator_show_library_error(self, "Cannot add the sequence");
        return;
    }
    refresh(self);
}

static vv_anim_track *
find_or_add_track(vv_animation *a, const char *property) {
    for (int i = 0; i < a->n_tracks; i++)
        if (strcmp(a->tracks[i].property, property) == 0)
            return &a->tracks[i];
    int idx = -1;
    if (vv_animation_add_track(a, property, &idx) != VV_OK)
        return NULL;
    return &a->tracks[idx];
}

/* Sets the key at @p time (replacing one at the same time). */
static vv_status
set_key(vv_anim_track *t, double time, const double v[4]) {
    t->closed = 0; /* a new key breaks a loop's first = last */
    for (int k = 0; k < t->n_keys; k++)
        if (fabs(t->keys[k].time - time) < 1e-9) {
            memcpy(t->keys[k].value, v, sizeof t->keys[k].value);
            return VV_OK;
        }
    vv_anim_key key;
    vv_anim_key_init(&key, time);
    memcpy(key.value, v, sizeof key.value);
    return vv_anim_track_add_key(t, &key);
}

static void
add_key_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    const vv_view *v = &vvg_document_world(self->doc)->view;
    double t = spin_value(self->key_time);
    const char *props[] = {"view.eye", "view.at", "view.up", "view.fov"};
    const double values[4][4] = {{v->eye.x, v->eye.y, v->eye.z, 0},
                                 {v->at.x, v->at.y, v->at.z, 0},
                                 {v->up.x, v->up.y, v->up.z, 0},
                                 {v->fov, 0, 0, 0}};
    for (int i = 0; i < 4; i++) {
        vv_error_clear();
        vv_anim_track *tr = find_or_add_track(self->anim, props[i]);
        if (!tr || set_key(tr, t, values[i]) != VV_OK) {
            vvg_animator_show_library_error(self, "Cannot add the camera key");
            refresh(self);
            return;
        }
    }
    /* the key at t is a frame of the animation */
    double end = t + 1.0 / self->anim->fps;
    if (end > self->anim->duration + 1e-9)
        self->anim->duration = end;
    /* the next key a second later: navigate, add, navigate, add ... */
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(self->key_time), t + 1.0);
    refresh(self);
}

/* The selected volume object's time step (the Channels and time page's) as
 * a key of its objects[i].time track at the key time: linear between keys,
 * so that the steps between two keys play in order. */
static void
add_time_key_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    int i = vvg_document_selected(self->doc);
    vv_object *o = vvg_document_selected_object(self->doc);
    if (!o || o->type != VV_OBJECT_VOLUME || vvg_document_time_steps(self->doc, o) < 2) {
        vvg_show_error(GTK_WIDGET(self), "Cannot add a time-step key",
                       "Select a volume object read from a file with time steps (its step is set "
                       "on the Channels and time page).");
        return;
    }
    char prop[64];
    snprintf(prop, sizeof prop, "objects[%d].time", i);
    double t = spin_value(self->key_time);
    const double v[4] = {o->time, 0, 0, 0};
    vv_error_clear();
    vv_anim_track *tr = find_or_add_track(self->anim, prop);
    if (!tr || set_key(tr, t, v) != VV_OK) {
        vvg_animator_show_library_error(self, "Cannot add the time-step key");
        refresh(self);
        return;
    }
    tr->interp = VV_INTERP_LINEAR;
    double end = t + 1.0 / self->anim->fps;
    if (end > self->anim->duration + 1e-9)
        self->anim->duration = end;
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(self->key_time), t + 1.0);
    refresh(self);
}

/* ---- New, Open, Save ------------------------------------------------------------------- */

static void
new_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    vv_animation *a = NULL;
    vv_error_clear();
    if (vv_animation_new(&a) != VV_OK) {
        vvg_animator_show_library_error(self, "Cannot make an animation");
        return;
    }
    a->fps = spin_value(self->fps);
    a->duration = spin_value(self->frames) / a->fps;
    vvg_animator_set_animation(self, a);
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(self->key_time), 0);
    vvg_animator_set_status(self, "");
}

static void
open_response(GtkNativeDialog *d, int response, gpointer user) {
    VvgAnimatorPage *self = user;
    if (response == GTK_RESPONSE_ACCEPT && !self->disposed) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(d));
        char *path = f ? g_file_get_path(f) : NULL;
        if (path) {
            vv_animation *a = NULL;
            vv_error_clear();
            if (vv_animation_load(&a, path) != VV_OK) {
                g_autofree char *base = g_path_get_basename(path);
                g_autofree char *what = g_strdup_printf("Cannot open %s", base);
                vvg_animator_show_library_error(self, what);
            } else {
                vvg_animator_set_animation(self, a);
                g_autofree char *base = g_path_get_basename(path);
                g_autofree char *m = g_strdup_printf("opened %s", base);
                vvg_animator_set_status(self, m);
                gtk_widget_set_tooltip_text(self->anim_status, path);
            }
        }
        g_free(path);
        if (f)
            g_object_unref(f);
    }
    g_object_unref(d);
    g_object_unref(self);
}

static void
open_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    GtkFileChooserNative *d = gtk_file_chooser_native_new(
        "Open animation", parent_window(self), GTK_FILE_CHOOSER_ACTION_OPEN, "_Open", "_Cancel");
    GtkFileFilter *ff = gtk_file_filter_new();
    gtk_file_filter_set_name(ff, "Animation files (*.json)");
    gtk_file_filter_add_pattern(ff, "*.json");
    gtk_file_chooser_add_filter(GTK_FILE_CHOOSER(d), ff);
    g_object_unref(ff);
    g_signal_connect(d, "response", G_CALLBACK(open_response), g_object_ref(self));
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

/* The animation names the session's scene file (relative when beside it), so
 * that `volvis animate --animation FILE` renders it without an INPUT. */
static void
set_scene(vv_animation *a, const char *anim_path, const char *scene_path) {
    free(a->scene);
    a->scene = NULL;
    if (!scene_path)
        return;
    g_autofree char *adir = g_path_get_dirname(anim_path);
    g_autofree char *acanon = g_canonicalize_filename(adir, NULL);
    g_autofree char *sdir = g_path_get_dirname(scene_path);
    g_autofree char *sbase = g_path_get_basename(scene_path);
    a->scene = dup_malloc(strcmp(acanon, sdir) == 0 ? sbase : scene_path);
}

static void
save_response(GtkNativeDialog *d, int response, gpointer user) {
    VvgAnimatorPage *self = user;
    if (response == GTK_RESPONSE_ACCEPT && !self->disposed) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(d));
        char *path = f ? g_file_get_path(f) : NULL;
        if (path) {
            if (!g_str_has_suffix(path, ".json")) {
                char *p = g_strconcat(path, ".json", NULL);
                g_free(path);
                path = p;
            }
            set_scene(self->anim, path, vvg_document_path(self->doc));
            vv_error_clear();
            if (vv_animation_save(self->anim, path) != VV_OK) {
                vvg_animator_show_library_error(self, "Cannot save the animation");
            } else {
                g_autofree char *base = g_path_get_basename(path);
                g_autofree char *m = g_strdup_printf("saved %s", base);
                vvg_animator_set_status(self, m);
                gtk_widget_set_tooltip_text(self->anim_status, path);
            }
        }
        g_free(path);
        if (f)
            g_object_unref(f);
    }
    g_object_unref(d);
    g_object_unref(self);
}

static void
save_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    GtkFileChooserNative *d = gtk_file_chooser_native_new(
        "Save animation", parent_window(self), GTK_FILE_CHOOSER_ACTION_SAVE, "_Save", "_Cancel");
    gtk_file_chooser_set_current_name(GTK_FILE_CHOOSER(d), "animation.json");
    g_signal_connect(d, "response", G_CALLBACK(save_response), g_object_ref(self));
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

/* ---- building the page -------------------------------------------------------------- */

static GtkWidget *
stack_grid(GtkWidget *stack, const char *name) {
    GtkWidget *g = gtk_grid_new();
    gtk_grid_set_row_spacing(GTK_GRID(g), 3);
    gtk_grid_set_column_spacing(GTK_GRID(g), 6);
    gtk_stack_add_named(GTK_STACK(stack), g, name);
    return g;
}

static void
build(VvgAnimatorPage *self) {
    GtkWidget *box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_widget_set_margin_start(box, 8);
    gtk_widget_set_margin_end(box, 8);
    gtk_widget_set_margin_bottom(box, 8);
    gtk_widget_set_margin_top(box, 8);

    /* the animation's file, the timeline, Play, Stop, Record flight: the
     * rows of buttons span the page in equal parts (the GUI test finds them
     * from the timeline) */
    GtkWidget *r = button_row(box);
    add_button(r, gtk_button_new_with_label("New"), G_CALLBACK(new_clicked), self);
    add_button(r, gtk_button_new_with_label("Open…"), G_CALLBACK(open_clicked), self);
    add_button(r, gtk_button_new_with_label("Save…"), G_CALLBACK(save_clicked), self);
    self->timeline = gtk_drawing_area_new();
    gtk_widget_set_size_request(self->timeline, 280, 44);
    vvg_name(self->timeline, "timeline");
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(self->timeline), timeline_draw, self, NULL);
    GtkGesture *click = gtk_gesture_click_new();
    g_signal_connect(click, "pressed", G_CALLBACK(timeline_pressed), self);
    gtk_widget_add_controller(self->timeline, GTK_EVENT_CONTROLLER(click));
    gtk_widget_set_tooltip_text(self->timeline, "keys (yellow), sequences (green); a click sets "
                                                "the key time");
    gtk_box_append(GTK_BOX(box), self->timeline);
    r = button_row(box);
    self->play = add_button(r, gtk_button_new_with_label("Play"),
                            G_CALLBACK(vvg_animator_play_clicked), self);
    self->stop = add_button(r, gtk_button_new_with_label("Stop"),
                            G_CALLBACK(vvg_animator_stop_clicked), self);
    self->record = add_button(r, gtk_toggle_button_new_with_label("Record flight"),
                              G_CALLBACK(vvg_animator_record_toggled), self);
    gtk_widget_set_tooltip_text(self->record, "samples the view at 30 Hz while you navigate; "
                                              "off: the flight path becomes the animation");
    self->time_label = line_label();
    gtk_box_append(GTK_BOX(box), self->time_label);
    self->anim_status = line_label();
    gtk_label_set_ellipsize(GTK_LABEL(self->anim_status), PANGO_ELLIPSIZE_START);
    gtk_box_append(GTK_BOX(box), self->anim_status);
    GtkWidget *g = gtk_grid_new();
    gtk_grid_set_row_spacing(GTK_GRID(g), 3);
    gtk_grid_set_column_spacing(GTK_GRID(g), 6);
    gtk_box_append(GTK_BOX(box), g);
    self->fps = vvg_row(g, "frames per second", vvg_spin(0.01, 1000, 1, 2, 30));
    g_signal_connect(self->fps, "value-changed", G_CALLBACK(fps_changed), self);
    self->frames = vvg_row(g, "frames", vvg_spin(1, 1000000, 1, 0, 60));
    g_signal_connect(self->frames, "value-changed", G_CALLBACK(frames_changed), self);
    self->loop = gtk_check_button_new_with_label("loop Play");
    gtk_check_button_set_active(GTK_CHECK_BUTTON(self->loop), TRUE);
    gtk_grid_attach(GTK_GRID(g), self->loop, 0, vvg_grid_rows(g), 2, 1);

    /* final render */
    g = vvg_section(box, "Final render");
    self->output = vvg_row(g, "output", gtk_entry_new());
    gtk_widget_set_tooltip_text(self->output,
                                "NAME.mp4 (H.264), NAME.webm (VP9), a PNG pattern such as "
                                "frames/f_%04d.png, or an existing folder");
    g_autofree char *cwd = g_get_current_dir();
    g_autofree char *def = g_build_filename(cwd, "animation.mp4", NULL);
    gtk_editable_set_text(GTK_EDITABLE(self->output), def);
    self->resume = gtk_check_button_new_with_label("resume: keep the finished frames of an "
                                                   "interrupted render");
    gtk_check_button_set_active(GTK_CHECK_BUTTON(self->resume), TRUE);
    gtk_grid_attach(GTK_GRID(g), self->resume, 0, vvg_grid_rows(g), 2, 1);
    self->render_info = line_label();
    gtk_box_append(GTK_BOX(box), self->render_info);
    r = button_row(box);
    self->render = add_button(r, gtk_button_new_with_label("Render"),
                              G_CALLBACK(vvg_animator_render_clicked), self);
    self->cancel = add_button(r, gtk_button_new_with_label("Cancel"),
                              G_CALLBACK(vvg_animator_cancel_clicked), self);
    self->progress = gtk_progress_bar_new();
    gtk_progress_bar_set_show_text(GTK_PROGRESS_BAR(self->progress), TRUE);
    gtk_box_append(GTK_BOX(box), self->progress);
    self->render_status = line_label();
    gtk_label_set_ellipsize(GTK_LABEL(self->render_status), PANGO_ELLIPSIZE_MIDDLE);
    gtk_box_append(GTK_BOX(box), self->render_status);

    /* sequences without keyframes */
    g = vvg_section(box, "Sequence without keyframes (over the whole animation)");
    self->seq_type = vvg_row(g, "sequence", gtk_drop_down_new_from_strings(seq_names));
    g_signal_connect(self->seq_type, "notify::selected", G_CALLBACK(seq_type_changed), self);
    self->seq_stack = gtk_stack_new();
    gtk_box_append(GTK_BOX(box), self->seq_stack);
    g = stack_grid(self->seq_stack, "orbit");
    self->orbit_degrees = vvg_row(g, "degrees", vvg_spin(-1e5, 1e5, 15, 1, 360));
    self->orbit_elevation = vvg_row(g, "elevation (°)", vvg_spin(-89, 89, 5, 1, 0));
    g = stack_grid(self->seq_stack, "rotate");
    static const char *const axes3[] = {"x", "y", "z", NULL};
    self->rot_axis = vvg_row(g, "axis", gtk_drop_down_new_from_strings(axes3));
    gtk_drop_down_set_selected(GTK_DROP_DOWN(self->rot_axis), 2);
    self->rot_degrees = vvg_row(g, "degrees", vvg_spin(-1e5, 1e5, 15, 1, 360));
    g = stack_grid(self->seq_stack, "fly");
    static const char *const xyz[] = {"offset x", "offset y", "offset z"};
    for (int i = 0; i < 3; i++)
        self->fly[i] = vvg_row(g, xyz[i], vvg_spin(-1e7, 1e7, 10, 2, 0));
    g = stack_grid(self->seq_stack, "sweep");
    static const char *const axes6[] = {"x", "y", "z", "-x", "-y", "-z", NULL};
    self->sweep_axis = vvg_row(g, "across the World along", gtk_drop_down_new_from_strings(axes6));
    r = button_row(box);
    add_button(r, gtk_button_new_with_label("Add sequence"), G_CALLBACK(add_sequence_clicked),
               self);

    /* camera keys */
    g = vvg_section(box, "Keyframes (camera, time step)");
    self->key_time = vvg_row(g, "time (s)", vvg_spin(0, 1e5, 0.1, 2, 0));
    g_signal_connect_swapped(self->key_time, "value-changed",
                             G_CALLBACK(vvg_animator_update_time_label), self);
    r = button_row(box);
    add_button(r, gtk_button_new_with_label("Add camera key"), G_CALLBACK(add_key_clicked), self);
    add_button(r, gtk_button_new_with_label("Add time-step key"), G_CALLBACK(add_time_key_clicked),
               self);

    /* the animation: last, as it grows */
    vvg_section(box, "Tracks and sequences of the animation");
    self->list = gtk_list_box_new();
    GtkWidget *frame = gtk_frame_new(NULL);
    gtk_frame_set_child(GTK_FRAME(frame), self->list);
    gtk_box_append(GTK_BOX(box), frame);
    r = button_row(box);
    add_button(r, gtk_button_new_with_label("Remove selected"), G_CALLBACK(remove_clicked), self);

    GtkWidget *scroll = gtk_scrolled_window_new();
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(scroll), GTK_POLICY_NEVER,
                                   GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_child(GTK_SCROLLED_WINDOW(scroll), box);
    gtk_widget_set_vexpand(scroll, TRUE);
    gtk_box_append(GTK_BOX(self), scroll);
}

/* ---- life cycle --------------------------------------------------------------------- */

static void
vvg_animator_page_dispose(GObject *o) {
    VvgAnimatorPage *self = VVG_ANIMATOR_PAGE(o);
    self->disposed = TRUE;
    vvg_animator_stop_render(self);
    vvg_animator_stop_recording(self, FALSE);
    if (self->doc) {
        g_signal_handler_disconnect(self->doc, self->changed_id);
        /* the World as it was at Play, should the page go while playing */
        vvg_animator_stop_playback(self, TRUE);
        g_clear_object(&self->doc);
    }
    G_OBJECT_CLASS(vvg_animator_page_parent_class)->dispose(o);
}

static void
vvg_animator_page_finalize(GObject *o) {
    VvgAnimatorPage *self = VVG_ANIMATOR_PAGE(o);
    vv_animation_free(self->anim);
    g_hash_table_unref(self->series);
    G_OBJECT_CLASS(vvg_animator_page_parent_class)->finalize(o);
}

static void
vvg_animator_page_class_init(VvgAnimatorPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_animator_page_dispose;
    G_OBJECT_CLASS(klass)->finalize = vvg_animator_page_finalize;
}

static void
vvg_animator_page_init(VvgAnimatorPage *self) {
    gtk_orientable_set_orientation(GTK_ORIENTABLE(self), GTK_ORIENTATION_VERTICAL);
    if (vv_animation_new(&self->anim) != VV_OK)
        g_error("volvis-gui: out of memory");
    self->anim->fps = 30;
    self->anim->duration = 2; /* 60 frames */
    self->series = vvg_time_cache_new();
    build(self);
}

GtkWidget *
vvg_animator_page_new(VvgDocument *doc) {
    VvgAnimatorPage *self = g_object_new(VVG_TYPE_ANIMATOR_PAGE, NULL);
    self->doc = g_object_ref(doc);
    self->changed_id = g_signal_connect(doc, "changed", G_CALLBACK(vvg_animator_doc_changed), self);
    refresh(self);
    vvg_animator_doc_changed(doc, self);
    vvg_animator_update_sensitivity(self);
    return GTK_WIDGET(self);
}

const vv_animation *
vvg_animator_page_animation(VvgAnimatorPage *self) {
    return self->anim;
}

gboolean
vvg_animator_page_playing(VvgAnimatorPage *self) {
    return self->play_source != 0;
}
