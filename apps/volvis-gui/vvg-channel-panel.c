/* VvgChannelPanel: channels and time steps of the selected object (vvg-channel-panel.h). */
#include "vvg-channel-panel.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define HIST_BINS 128
#define PLAY_MS 100 /* 10 time steps a second */

typedef struct channel_row {
    VvgChannelPanel *panel;
    int c;
    GtkWidget *show, *color, *edit, *hist, *lo, *hi, *gamma;
    const vv_volume *hist_volume;
    uint64_t hist_modified;
    double bins[HIST_BINS], hist_lo, hist_hi; /* log counts, 0..1 */
} channel_row;

struct _VvgChannelPanel {
    GtkBox parent;
    VvgDocument *doc;
    gboolean updating; /* set while widgets are filled from the World */
    GtkWidget *summary, *blend_box, *blend, *rows;
    channel_row *row; /* VV_MAX_CHANNELS (GObject instances stay under 64 KiB) */
    int n_rows;
    char *signature; /* the channels the rows were built for */
    GtkWidget *time_box, *time_scale, *play, *time_label;
    guint play_source;
};

G_DEFINE_TYPE(VvgChannelPanel, vvg_channel_panel, GTK_TYPE_BOX)

static vv_object *
volume_object(VvgChannelPanel *self) {
    vv_object *o = vvg_document_selected_object(self->doc);
    return o && o->type == VV_OBJECT_VOLUME && o->volume ? o : NULL;
}

/* The row's channel of the selected object, or NULL when it has no such channel. */
static vv_channel *
row_channel(channel_row *r) {
    vv_object *o = volume_object(r->panel);
    return o && r->c < o->n_channels ? &o->channels[r->c] : NULL;
}

static void fill(VvgChannelPanel *self);

/* ---- the histogram under the contrast sliders ------------------------------------- */

static void
update_histogram(channel_row *r, const vv_volume *v) {
    /* while time plays the histogram of the step it started from stays (a
     * histogram a step would cost more than the step's read); stop_playing
     * redraws it for the step shown */
    if (r->hist_volume == v && r->hist_modified == v->modified)
        return;
    if (r->hist_volume && r->panel->play_source)
        return;
    uint64_t h[HIST_BINS];
    r->hist_lo = v->range[0];
    r->hist_hi = v->range[1] > v->range[0] ? v->range[1] : v->range[0] + 1;
    if (vv_volume_histogram(v, HIST_BINS, r->hist_lo, r->hist_hi, h) != VV_OK) {
        vv_error_clear();
        memset(h, 0, sizeof h);
    }
    double top = 0;
    for (int i = 0; i < HIST_BINS; i++)
        top = fmax(top, log1p((double)h[i]));
    for (int i = 0; i < HIST_BINS; i++)
        r->bins[i] = top > 0 ? log1p((double)h[i]) / top : 0;
    r->hist_volume = v;
    r->hist_modified = v->modified;
}

/* The channel's histogram (log counts, grey), its contrast function in its
 * colour (opacity relative to the highest) and the limits as lines. */
static void
hist_draw(GtkDrawingArea *area, cairo_t *cr, int W, int H, gpointer user) {
    (void)area;
    channel_row *r = user;
    cairo_set_source_rgb(cr, 0.12, 0.12, 0.14);
    cairo_paint(cr);
    vv_channel *ch = row_channel(r);
    if (!ch || !ch->volume)
        return;
    update_histogram(r, ch->volume);
    const double bw = (double)W / HIST_BINS;
    cairo_set_source_rgb(cr, 0.45, 0.45, 0.48);
    for (int i = 0; i < HIST_BINS; i++) {
        double h = r->bins[i] * (H - 2);
        cairo_rectangle(cr, i * bw, H - h, bw, h);
    }
    cairo_fill(cr);
    const vv_tf *tf = &ch->tf;
    double peak = 0;
    for (int i = 0; i < tf->n_opacity; i++)
        peak = fmax(peak, tf->opacity[i].opacity);
    double lo, hi;
    vv_vec3 col;
    vv_tf_get_contrast(tf, &lo, &hi, NULL, NULL, &col);
    cairo_set_source_rgb(cr, col.x, col.y, col.z);
    cairo_set_line_width(cr, 2);
    for (int x = 0; x <= W; x++) {
        double v = r->hist_lo + (r->hist_hi - r->hist_lo) * x / W;
        double k = peak > 0 ? vv_tf_eval_opacity(tf, v) / peak : 0;
        if (x == 0)
            cairo_move_to(cr, x, H - 1 - k * (H - 3));
        else
            cairo_line_to(cr, x, H - 1 - k * (H - 3));
    }
    cairo_stroke(cr);
    cairo_set_line_width(cr, 1);
    const double lim[2] = {lo, hi};
    for (int k = 0; k < 2; k++) {
        double x = (lim[k] - r->hist_lo) / (r->hist_hi - r->hist_lo) * W;
        cairo_move_to(cr, floor(x) + 0.5, 0);
        cairo_line_to(cr, floor(x) + 0.5, H);
    }
    cairo_set_source_rgba(cr, 1, 1, 1, 0.7);
    cairo_stroke(cr);
}

/* ---- edits ------------------------------------------------------------------------ */

static void
show_toggled(GtkCheckButton *b, gpointer user) {
    channel_row *r = user;
    if (r->panel->updating || !row_channel(r))
        return;
    vvg_document_begin_edit(r->panel->doc, "channel visibility");
    vv_channel *ch = row_channel(r);
    ch->visible = gtk_check_button_get_active(b);
    vvg_document_changed(r->panel->doc);
}

/* A new colour for every colour point: the contrast shape stays. */
static void
color_set(GtkColorButton *b, gpointer user) {
    channel_row *r = user;
    if (r->panel->updating || !row_channel(r))
        return;
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(b), &c);
    vvg_document_begin_edit(r->panel->doc, "channel colour");
    vv_tf *tf = &row_channel(r)->tf;
    if (tf->n_color == 0)
        (void)vv_tf_add_color(tf, 0, vvg_vec3(&c));
    for (int i = 0; i < tf->n_color; i++)
        tf->color[i].color = vvg_vec3(&c);
    vvg_document_changed(r->panel->doc);
    gtk_widget_queue_draw(r->hist);
}

/* The limits and gamma as the channel's contrast function (its colour and
 * highest opacity kept); a drag is one undo step. */
static void
contrast_changed(GtkWidget *w, gpointer user) {
    (void)w;
    channel_row *r = user;
    vv_channel *ch = row_channel(r);
    if (r->panel->updating || !ch)
        return;
    double lo = gtk_range_get_value(GTK_RANGE(r->lo)), hi = gtk_range_get_value(GTK_RANGE(r->hi));
    double gamma = vvg_spin_value(r->gamma);
    if (!(hi > lo))
        return; /* the limits crossed: nothing until they part again */
    double op;
    vv_vec3 col;
    vv_tf_get_contrast(&ch->tf, NULL, NULL, NULL, &op, &col);
    if (!(op > 0))
        op = 0.5;
    vvg_document_begin_edit_merging(r->panel->doc, "channel contrast");
    ch = row_channel(r);
    vv_error_clear();
    if (vv_tf_set_contrast(&ch->tf, lo, hi, gamma, op, col, ch->tf.opacity_unit_distance) !=
        VV_OK) {
        vvg_show_error(GTK_WIDGET(r->panel), "Cannot set the contrast", vv_error_message());
        return;
    }
    vvg_document_changed(r->panel->doc);
    gtk_widget_queue_draw(r->hist);
}

static void
edit_toggled(GtkCheckButton *b, gpointer user) {
    channel_row *r = user;
    if (r->panel->updating || !gtk_check_button_get_active(b))
        return;
    vvg_document_set_edited_channel(r->panel->doc, r->c);
}

static void
blend_changed(GObject *d, GParamSpec *p, gpointer user) {
    (void)p;
    VvgChannelPanel *self = user;
    vv_object *o = volume_object(self);
    guint b = gtk_drop_down_get_selected(GTK_DROP_DOWN(d));
    if (self->updating || !o || o->n_channels < 1 || b > VV_BLEND_MAXIMUM || (guint)o->blend == b)
        return;
    vvg_document_begin_edit(self->doc, "channel blend");
    volume_object(self)->blend = (vv_channel_blend)b;
    vvg_document_changed(self->doc);
}

/* ---- time ------------------------------------------------------------------------- */

static void stop_playing(VvgChannelPanel *self);

/* A step that could not be read: said once, Play stopped, the slider back
 * at the step shown. */
static void
step_failed(VvgDocument *doc, const char *message, gpointer user) {
    (void)doc;
    VvgChannelPanel *self = user;
    stop_playing(self);
    vvg_show_error(GTK_WIDGET(self), "Cannot show the time step", message);
    fill(self);
}

/* The slider asks for a step; it is read off the interface's thread and
 * shown when it arrives (vvg_document_request_time: the latest ask wins). */
static void
time_changed(GtkRange *range, gpointer user) {
    VvgChannelPanel *self = user;
    vv_object *o = volume_object(self);
    int t = (int)lrint(gtk_range_get_value(range));
    if (self->updating || !o)
        return;
    vvg_document_request_time(self->doc, t, step_failed, self);
}

static void
stop_playing(VvgChannelPanel *self) {
    if (self->play_source) {
        g_source_remove(self->play_source);
        self->play_source = 0;
        /* paused: the histograms of the step shown (they stayed while it played) */
        for (int c = 0; c < self->n_rows; c++)
            if (self->row[c].hist)
                gtk_widget_queue_draw(self->row[c].hist);
    }
    if (self->play && gtk_toggle_button_get_active(GTK_TOGGLE_BUTTON(self->play))) {
        self->updating = TRUE;
        gtk_toggle_button_set_active(GTK_TOGGLE_BUTTON(self->play), FALSE);
        self->updating = FALSE;
    }
}

static gboolean
play_tick(gpointer user) {
    VvgChannelPanel *self = user;
    vv_object *o = volume_object(self);
    int steps = vvg_document_time_steps(self->doc, o);
    if (steps < 2) {
        self->play_source = 0;
        stop_playing(self);
        return G_SOURCE_REMOVE;
    }
    /* the next step after the one shown, once the last one asked is in
     * (a step slower to read than a tick holds Play back, never queues) */
    if (!vvg_document_time_pending(self->doc))
        vvg_document_request_time(self->doc, (o->time + 1) % steps, step_failed, self);
    return G_SOURCE_CONTINUE;
}

static void
play_toggled(GtkToggleButton *b, gpointer user) {
    VvgChannelPanel *self = user;
    if (self->updating)
        return;
    if (gtk_toggle_button_get_active(b) && !self->play_source)
        self->play_source = g_timeout_add(PLAY_MS, play_tick, self);
    else if (!gtk_toggle_button_get_active(b))
        stop_playing(self);
    gtk_button_set_label(GTK_BUTTON(b), gtk_toggle_button_get_active(b) ? "Pause" : "Play");
}

/* ---- building and filling --------------------------------------------------------- */

static GtkWidget *
limit_scale(channel_row *r, const char *what, const char *name) {
    GtkWidget *s = gtk_scale_new_with_range(GTK_ORIENTATION_HORIZONTAL, 0, 1, 1);
    gtk_scale_set_draw_value(GTK_SCALE(s), TRUE);
    gtk_scale_set_value_pos(GTK_SCALE(s), GTK_POS_RIGHT);
    gtk_widget_set_hexpand(s, TRUE);
    g_autofree char *a11y = g_strdup_printf("%s of %s", what, name);
    vvg_name(s, a11y);
    vvg_wheel_when_focused(s);
    g_signal_connect(s, "value-changed", G_CALLBACK(contrast_changed), r);
    return s;
}

/* One channel: its name (visibility), colour, "edit" (the Transfer function
 * page's channel), histogram, limits and gamma. */
static GtkWidget *
build_row(VvgChannelPanel *self, int c, const vv_channel *ch, GtkWidget *group) {
    channel_row *r = &self->row[c];
    memset(r, 0, sizeof *r);
    r->panel = self;
    r->c = c;
    GtkWidget *box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 2);
    gtk_widget_set_margin_top(box, 6);
    GtkWidget *head = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 6);
    r->show = gtk_check_button_new_with_label(ch->name);
    g_autofree char *show = g_strdup_printf("show %s", ch->name);
    vvg_name(r->show, show);
    gtk_widget_set_hexpand(r->show, TRUE);
    g_signal_connect(r->show, "toggled", G_CALLBACK(show_toggled), r);
    r->color = gtk_color_button_new();
    g_autofree char *colour = g_strdup_printf("colour of %s", ch->name);
    vvg_name(r->color, colour);
    vvg_name(gtk_widget_get_first_child(r->color), colour);
    g_signal_connect(r->color, "color-set", G_CALLBACK(color_set), r);
    r->edit = gtk_check_button_new_with_label("edit TF");
    if (group)
        gtk_check_button_set_group(GTK_CHECK_BUTTON(r->edit), GTK_CHECK_BUTTON(group));
    g_autofree char *edit = g_strdup_printf("edit transfer function of %s", ch->name);
    vvg_name(r->edit, edit);
    gtk_widget_set_tooltip_text(r->edit, "the Transfer function page edits this channel");
    g_signal_connect(r->edit, "toggled", G_CALLBACK(edit_toggled), r);
    gtk_box_append(GTK_BOX(head), r->show);
    gtk_box_append(GTK_BOX(head), r->edit);
    gtk_box_append(GTK_BOX(head), r->color);
    gtk_box_append(GTK_BOX(box), head);
    r->hist = gtk_drawing_area_new();
    gtk_widget_set_size_request(r->hist, 260, 44);
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(r->hist), hist_draw, r, NULL);
    g_autofree char *hist = g_strdup_printf("histogram of %s", ch->name);
    vvg_name(r->hist, hist);
    gtk_box_append(GTK_BOX(box), r->hist);
    GtkWidget *g = gtk_grid_new();
    gtk_grid_set_column_spacing(GTK_GRID(g), 6);
    r->lo = limit_scale(r, "lower contrast limit", ch->name);
    r->hi = limit_scale(r, "upper contrast limit", ch->name);
    r->gamma = vvg_spin(0.05, 20, 0.05, 2, 1);
    g_autofree char *gamma = g_strdup_printf("gamma of %s", ch->name);
    vvg_name(r->gamma, gamma);
    g_signal_connect(r->gamma, "value-changed", G_CALLBACK(contrast_changed), r);
    const char *labels[3] = {"low", "high", "gamma"};
    GtkWidget *ws[3] = {r->lo, r->hi, r->gamma};
    for (int k = 0; k < 3; k++) {
        GtkWidget *l = gtk_label_new(labels[k]);
        gtk_label_set_xalign(GTK_LABEL(l), 0);
        gtk_grid_attach(GTK_GRID(g), l, 0, k, 1, 1);
        gtk_grid_attach(GTK_GRID(g), ws[k], 1, k, 1, 1);
    }
    gtk_box_append(GTK_BOX(box), g);
    return box;
}

/* "3\nnuclei\nmembranes\n...": rows are rebuilt when this changes. */
static char *
signature(const vv_object *o) {
    GString *s = g_string_new(NULL);
    g_string_append_printf(s, "%d", o ? o->n_channels : 0);
    for (int c = 0; o && c < o->n_channels; c++)
        g_string_append_printf(s, "\n%s", o->channels[c].name);
    return g_string_free(s, FALSE);
}

static void
rebuild(VvgChannelPanel *self, const vv_object *o) {
    GtkWidget *child;
    while ((child = gtk_widget_get_first_child(self->rows)))
        gtk_box_remove(GTK_BOX(self->rows), child);
    self->n_rows = o ? o->n_channels : 0;
    GtkWidget *group = NULL;
    for (int c = 0; c < self->n_rows; c++) {
        gtk_box_append(GTK_BOX(self->rows), build_row(self, c, &o->channels[c], group));
        if (!group)
            group = self->row[c].edit;
    }
}

static void
fill_row(channel_row *r, const vv_object *o, int edited) {
    const vv_channel *ch = &o->channels[r->c];
    gtk_check_button_set_active(GTK_CHECK_BUTTON(r->show), ch->visible);
    gtk_check_button_set_active(GTK_CHECK_BUTTON(r->edit), edited == r->c);
    double lo, hi, gamma;
    vv_vec3 col;
    vv_tf_get_contrast(&ch->tf, &lo, &hi, &gamma, NULL, &col);
    GdkRGBA rgba = vvg_rgba(col);
    gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(r->color), &rgba);
    double vmin = ch->volume->range[0], vmax = ch->volume->range[1];
    vmin = fmin(vmin, lo);
    vmax = fmax(fmax(vmax, hi), vmin + 1);
    int is_int = ch->volume->type != VV_F32 && ch->volume->type != VV_F64;
    double step = is_int ? 1 : (vmax - vmin) / 1000;
    GtkWidget *sc[2] = {r->lo, r->hi};
    const double val[2] = {lo, hi};
    for (int k = 0; k < 2; k++) {
        gtk_range_set_range(GTK_RANGE(sc[k]), vmin, vmax);
        gtk_range_set_increments(GTK_RANGE(sc[k]), step, step * 10);
        gtk_scale_set_digits(GTK_SCALE(sc[k]), is_int ? 0 : 3);
        if (gtk_range_get_value(GTK_RANGE(sc[k])) != val[k])
            gtk_range_set_value(GTK_RANGE(sc[k]), val[k]);
    }
    if (fabs(vvg_spin_value(r->gamma) - gamma) > 1e-6)
        vvg_set_spin(r->gamma, gamma);
    /* a label channel is coloured by label: no colour or contrast to set */
    GtkWidget *tf_widgets[4] = {r->color, r->lo, r->hi, r->gamma};
    for (int k = 0; k < 4; k++) {
        gtk_widget_set_sensitive(tf_widgets[k], !ch->labels);
        gtk_widget_set_tooltip_text(
            tf_widgets[k], ch->labels ? "A label channel: each label in its own colour" : NULL);
    }
    gtk_widget_queue_draw(r->hist);
}

static void
fill(VvgChannelPanel *self) {
    vv_object *o = volume_object(self);
    g_autofree char *sig = signature(o);
    if (g_strcmp0(sig, self->signature)) {
        g_free(self->signature);
        self->signature = g_steal_pointer(&sig);
        rebuild(self, o);
    }
    self->updating = TRUE;
    char text[256];
    if (!o)
        snprintf(text, sizeof text, "Select a volume object.");
    else if (o->n_channels < 1)
        snprintf(text, sizeof text,
                 "%s has one channel (its colours: the Transfer function page). Open a "
                 "multi-channel file (OME-TIFF, ImageJ hyperstack, NIfTI 5-D, NRRD) to see its "
                 "channels here.",
                 o->name);
    else
        snprintf(text, sizeof text, "%s: %d channels", o->name, o->n_channels);
    gtk_label_set_text(GTK_LABEL(self->summary), text);
    gtk_widget_set_visible(self->blend_box, o && o->n_channels > 0);
    if (o && o->n_channels > 0) {
        if (gtk_drop_down_get_selected(GTK_DROP_DOWN(self->blend)) != (guint)o->blend)
            gtk_drop_down_set_selected(GTK_DROP_DOWN(self->blend), (guint)o->blend);
        int edited = vvg_document_edited_channel(self->doc);
        for (int c = 0; c < self->n_rows; c++)
            fill_row(&self->row[c], o, edited);
    }
    int steps = vvg_document_time_steps(self->doc, o);
    gtk_widget_set_visible(self->time_box, steps > 1);
    if (steps > 1) {
        gtk_range_set_range(GTK_RANGE(self->time_scale), 0, steps - 1);
        /* while a step asked for is being read the slider stays where the
         * user put it; the label says the step shown */
        if (!vvg_document_time_pending(self->doc) &&
            lrint(gtk_range_get_value(GTK_RANGE(self->time_scale))) != o->time)
            gtk_range_set_value(GTK_RANGE(self->time_scale), o->time);
        snprintf(text, sizeof text, "step %d of %d", o->time + 1, steps);
        gtk_label_set_text(GTK_LABEL(self->time_label), text);
    } else {
        stop_playing(self);
    }
    self->updating = FALSE;
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    fill(user);
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgChannelPanel *self = user;
    stop_playing(self); /* time plays for the object it was started on */
    fill(self);
}

static void
vvg_channel_panel_dispose(GObject *o) {
    VvgChannelPanel *self = VVG_CHANNEL_PANEL(o);
    stop_playing(self);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        vvg_document_forget_time_listener(self->doc, self); /* a read in flight tells no one */
        g_clear_object(&self->doc);
    }
    g_clear_pointer(&self->signature, g_free);
    g_clear_pointer(&self->row, g_free);
    G_OBJECT_CLASS(vvg_channel_panel_parent_class)->dispose(o);
}

static void
vvg_channel_panel_class_init(VvgChannelPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_channel_panel_dispose;
}

static void
vvg_channel_panel_init(VvgChannelPanel *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    self->row = g_new0(channel_row, VV_MAX_CHANNELS);
}

/* The time-step slider, Play and the step shown. */
static void
build_time(VvgChannelPanel *self) {
    self->time_box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    GtkWidget *g = vvg_section(self->time_box, "Time");
    self->time_scale = gtk_scale_new_with_range(GTK_ORIENTATION_HORIZONTAL, 0, 1, 1);
    gtk_scale_set_digits(GTK_SCALE(self->time_scale), 0);
    gtk_scale_set_draw_value(GTK_SCALE(self->time_scale), TRUE);
    gtk_widget_set_hexpand(self->time_scale, TRUE);
    vvg_row(g, "time step", self->time_scale);
    g_signal_connect(self->time_scale, "value-changed", G_CALLBACK(time_changed), self);
    GtkWidget *hb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 6);
    self->play = gtk_toggle_button_new_with_label("Play");
    vvg_name(self->play, "Play time steps");
    gtk_widget_set_tooltip_text(self->play, "play the time steps, 10 a second, round and round");
    g_signal_connect(self->play, "toggled", G_CALLBACK(play_toggled), self);
    self->time_label = gtk_label_new("");
    gtk_box_append(GTK_BOX(hb), self->play);
    gtk_box_append(GTK_BOX(hb), self->time_label);
    gtk_grid_attach(GTK_GRID(g), hb, 0, vvg_grid_rows(g), 2, 1);
    gtk_box_append(GTK_BOX(self), self->time_box);
}

GtkWidget *
vvg_channel_panel_new(VvgDocument *doc) {
    VvgChannelPanel *self = g_object_new(VVG_TYPE_CHANNEL_PANEL, NULL);
    self->doc = g_object_ref(doc);
    build_time(self); /* first: in reach above any number of channels */
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "Channels");
    self->summary = gtk_label_new("");
    gtk_label_set_wrap(GTK_LABEL(self->summary), TRUE);
    gtk_label_set_xalign(GTK_LABEL(self->summary), 0);
    gtk_grid_attach(GTK_GRID(g), self->summary, 0, 0, 2, 1);
    self->blend_box = gtk_grid_new();
    gtk_grid_set_column_spacing(GTK_GRID(self->blend_box), 6);
    /* in vv_channel_blend's order */
    static const char *const blends[] = {"composite", "additive", "maximum", NULL};
    self->blend = gtk_drop_down_new_from_strings(blends);
    g_signal_connect(self->blend, "notify::selected", G_CALLBACK(blend_changed), self);
    vvg_row(self->blend_box, "channel blend", self->blend);
    gtk_box_append(GTK_BOX(self), self->blend_box);
    self->rows = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_box_append(GTK_BOX(self), self->rows);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), self);
    fill(self);
    return GTK_WIDGET(self);
}
