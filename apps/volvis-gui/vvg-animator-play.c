/*
 * The Animator page's actions in time (internal to VvgAnimatorPage,
 * vvg-animator-play.h): Play (the animation evaluated 30 times a second from
 * the World at Play and shown as the document's transient World), Record
 * flight (the view sampled at 30 Hz, thinned into the current animation) and
 * the final render to a file on a worker thread (progress, Cancel, resume),
 * with the buttons each of them leaves pressable. The page's widgets, the
 * animation's summary, the timeline and the editing of the animation are
 * vvg-animator-page.c.
 */
#include "vvg-animator-play.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>

/* Play and flight recording both run at 30 frames a second. */
#define TICK_MS 33
/* Play asks for a frame at the display's rate; the scene view shows as many
 * as its previews can draw (at least 30 a second), each at its own time */
#define PLAY_TICK_MS 16

/* A final render on the worker thread; the UI reads the atomics on a timer. */
struct VvgAnimatorJob {
    VvgAnimatorPage *page; /* not a reference: the page joins the thread before it goes */
    vv_animation *anim;    /* owned snapshots */
    vv_world *world;
    GHashTable *series; /* the time steps of objects[i].time tracks (vvg_world_apply_time) */
    char *output;
    int resume;
    int frames;
    GThread *thread;
    int cancel;      /* atomic */
    double fraction; /* atomic: overall fraction done */
    int frames_done; /* atomic */
    gint64 start_us;
    vv_status status;
    vv_anim_render_stats stats;
    char error[1024];
};

/* ---- Play ------------------------------------------------------------------------------ */

void
vvg_animator_update_sensitivity(VvgAnimatorPage *self) {
    if (self->disposed)
        return;
    gboolean playing = self->play_source != 0, recording = self->recorder != NULL;
    gtk_widget_set_sensitive(self->play, !playing && !recording);
    gtk_widget_set_sensitive(self->stop, playing);
    gtk_widget_set_sensitive(self->record, !playing);
    gtk_widget_set_sensitive(self->render, self->job == NULL);
    gtk_widget_set_sensitive(self->cancel, self->job != NULL);
}

/* Ends Play: @p restore puts the World back as it was at Play, else the
 * World keeps the frame shown (an edit took over). */
void
vvg_animator_stop_playback(VvgAnimatorPage *self, gboolean restore) {
    if (self->play_source) {
        g_source_remove(self->play_source);
        self->play_source = 0;
    }
    if (self->doc && vvg_document_transient(self->doc))
        vvg_document_end_transient(self->doc, restore);
    vv_world_free(self->base);
    self->base = NULL;
    vv_animation_free(self->playing);
    self->playing = NULL;
    if (!self->disposed) {
        vvg_animator_update_sensitivity(self);
        vvg_animator_update_time_label(self);
    }
}

/* Shows the animation at time @p t; on failure the message is in @p err. */
static gboolean
show_play_frame(VvgAnimatorPage *self, double t, char *err, size_t cap) {
    vv_world *w = NULL;
    vv_error_clear();
    if (vv_animation_eval(self->playing, self->base, t, &w) != VV_OK) {
        g_strlcpy(err, vv_error_message(), cap);
        return FALSE;
    }
    g_autoptr(GError) terr = NULL;
    if (!vvg_world_apply_time(self->series, w, self->base, &terr)) { /* objects[i].time */
        g_strlcpy(err, terr->message, cap);
        vv_world_free(w);
        return FALSE;
    }
    self->play_time = t;
    vvg_document_show_transient(self->doc, w);
    vvg_animator_update_time_label(self);
    return TRUE;
}

static gboolean
play_tick(gpointer data) {
    VvgAnimatorPage *self = data;
    if (!vvg_document_transient(self->doc)) {
        /* an edit, undo or redo ended the transient World: it wins */
        self->play_source = 0;
        vvg_animator_stop_playback(self, FALSE);
        return G_SOURCE_REMOVE;
    }
    double t = (g_get_monotonic_time() - self->play_start_us) * 1e-6;
    double dur = self->playing->duration;
    if (t >= dur) {
        if (!gtk_check_button_get_active(GTK_CHECK_BUTTON(self->loop))) {
            self->play_source = 0;
            vvg_animator_stop_playback(self, TRUE);
            return G_SOURCE_REMOVE;
        }
        t = fmod(t, dur);
    }
    char err[1024];
    if (!show_play_frame(self, t, err, sizeof err)) {
        self->play_source = 0;
        vvg_animator_stop_playback(self, TRUE);
        vvg_show_error(GTK_WIDGET(self), "Cannot play the animation", err);
        return G_SOURCE_REMOVE;
    }
    return G_SOURCE_CONTINUE;
}

void
vvg_animator_play_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    if (self->play_source || self->recorder)
        return;
    vv_world *w = vvg_document_world(self->doc);
    vv_error_clear();
    if (vv_animation_validate(self->anim) != VV_OK ||
        vv_animation_check_world(self->anim, w) != VV_OK) {
        vvg_animator_show_library_error(self, "Cannot play the animation");
        return;
    }
    vv_error_clear();
    if (vv_animation_clone(&self->playing, self->anim) != VV_OK ||
        !(self->base = vvg_document_snapshot(self->doc))) {
        vvg_animator_show_library_error(self, "Cannot play the animation");
        vvg_animator_stop_playback(self, TRUE);
        return;
    }
    self->play_start_us = g_get_monotonic_time();
    char err[1024];
    if (!show_play_frame(self, 0, err, sizeof err)) {
        vvg_animator_stop_playback(self, TRUE);
        vvg_show_error(GTK_WIDGET(self), "Cannot play the animation", err);
        return;
    }
    self->play_source = g_timeout_add(PLAY_TICK_MS, play_tick, self);
    vvg_animator_update_sensitivity(self);
}

void
vvg_animator_stop_clicked(GtkButton *b, gpointer user) {
    (void)b;
    vvg_animator_stop_playback(user, TRUE);
}

/* The World changed: Play stops when an edit ended its transient World. */
void
vvg_animator_doc_changed(VvgDocument *doc, gpointer user) {
    VvgAnimatorPage *self = user;
    if (self->play_source && !vvg_document_transient(doc))
        vvg_animator_stop_playback(self, FALSE);
    const vv_world *w = vvg_document_world(doc);
    const vv_render_settings *rs = &w->render;
    char text[256];
    snprintf(text, sizeof text, "%s, quality %d, %d×%d pixels (Rendering page)",
             rs->renderer[0] ? rs->renderer : "raycast", rs->quality >= 0 ? rs->quality : 2,
             w->view.width, w->view.height);
    gtk_label_set_text(GTK_LABEL(self->render_info), text);
}

/* ---- flight recording ------------------------------------------------------------ */

static gboolean
record_tick(gpointer data) {
    VvgAnimatorPage *self = data;
    double t = (g_get_monotonic_time() - self->record_start_us) * 1e-6;
    /* a sample the recorder refuses (a non-finite view) is skipped */
    vv_flight_recorder_add(self->recorder, t, &vvg_document_world(self->doc)->view);
    char text[96];
    snprintf(text, sizeof text, "recording the view: %d samples, %.1f s",
             vv_flight_recorder_count(self->recorder), t);
    gtk_label_set_text(GTK_LABEL(self->time_label), text);
    return G_SOURCE_CONTINUE;
}

/* Stops recording; @p finish makes the samples the current animation,
 * ending with the view as it is now: the 30 Hz samples may miss the last
 * moves of a drag (a busy machine delays the timer past them). */
void
vvg_animator_stop_recording(VvgAnimatorPage *self, gboolean finish) {
    if (finish && self->recorder)
        record_tick(self);
    if (self->record_source) {
        g_source_remove(self->record_source);
        self->record_source = 0;
    }
    if (!self->recorder)
        return;
    if (finish) {
        /* thinning tolerances: a thousandth of the scene, a quarter degree */
        vv_box b = vv_world_bounds(vvg_document_world(self->doc));
        double size = vv_vec3_length(vv_vec3_sub(b.max, b.min));
        double pos_tol = size > 0 && isfinite(size) ? 1e-3 * size : 1e-3;
        vv_animation *a = NULL;
        int n = vv_flight_recorder_count(self->recorder);
        vv_error_clear();
        if (vv_flight_recorder_finish(self->recorder, pos_tol, vv_deg_to_rad(0.25), self->anim->fps,
                                      &a) != VV_OK) {
            vvg_animator_show_library_error(self, "No flight path");
        } else {
            int keys = a->n_tracks > 0 ? a->tracks[0].n_keys : 0;
            vvg_animator_set_animation(self, a);
            char text[128];
            snprintf(text, sizeof text, "recorded flight: %d samples, %d keys kept", n, keys);
            vvg_animator_set_status(self, text);
        }
    }
    vv_flight_recorder_free(self->recorder);
    self->recorder = NULL;
    if (!self->disposed) {
        vvg_animator_update_time_label(self);
        self->updating = TRUE;
        gtk_toggle_button_set_active(GTK_TOGGLE_BUTTON(self->record), FALSE);
        self->updating = FALSE;
        vvg_animator_update_sensitivity(self);
    }
}

void
vvg_animator_record_toggled(GtkToggleButton *b, gpointer user) {
    VvgAnimatorPage *self = user;
    if (self->updating)
        return;
    if (!gtk_toggle_button_get_active(b)) {
        vvg_animator_stop_recording(self, TRUE);
        return;
    }
    if (self->recorder || self->play_source)
        return;
    vv_error_clear();
    if (vv_flight_recorder_new(&self->recorder) != VV_OK) {
        vvg_animator_show_library_error(self, "Cannot record");
        vvg_animator_stop_recording(self, FALSE);
        return;
    }
    self->record_start_us = g_get_monotonic_time();
    record_tick(self);
    self->record_source = g_timeout_add(TICK_MS, record_tick, self);
    vvg_animator_update_sensitivity(self);
}

/* ---- the final render ----------------------------------------------------------------- */

static void
job_free(VvgAnimatorJob *j) {
    if (!j)
        return;
    vv_animation_free(j->anim);
    vv_world_free(j->world);
    if (j->series)
        g_hash_table_unref(j->series);
    g_free(j->output);
    g_free(j);
}

static int
render_progress(void *user, double fraction) {
    VvgAnimatorJob *j = user;
    __atomic_store(&j->fraction, &fraction, __ATOMIC_RELAXED);
    return __atomic_load_n(&j->cancel, __ATOMIC_RELAXED);
}

static void
render_frame_done(void *user, int frame, const vv_image *img, int reused) {
    (void)img;
    (void)reused;
    VvgAnimatorJob *j = user;
    __atomic_store_n(&j->frames_done, frame + 1, __ATOMIC_RELAXED);
}

static gboolean render_done(gpointer data);

/* A frame's World before it is drawn: the time steps its objects[i].time
 * tracks ask for (the worker thread's own series). */
static vv_status
render_prepare(void *user, int frame, vv_world *w) {
    (void)frame;
    VvgAnimatorJob *j = user;
    g_autoptr(GError) err = NULL;
    if (!vvg_world_apply_time(j->series, w, j->world, &err))
        return vv_error_set(VV_ERR_IO, "%s", err->message);
    return VV_OK;
}

static gpointer
render_main(gpointer data) {
    VvgAnimatorJob *j = data;
    const vv_world *w = j->world;
    vv_renderer *r = NULL;
    vv_error_clear();
    /* the World's renderer with its options and quality, as `volvis animate` */
    vv_status s = vv_renderer_new_for_world(&r, w);
    if (s == VV_OK) {
        vv_anim_render_options o;
        vv_anim_render_options_init(&o);
        o.output = j->output;
        o.render.quality = vv_render_settings_quality(&w->render);
        o.resume = j->resume;
        o.progress.fn = render_progress;
        o.progress.user = j;
        o.on_frame = render_frame_done;
        o.on_frame_user = j;
        o.prepare_frame = render_prepare;
        o.prepare_frame_user = j;
        j->series = vvg_time_cache_new();
        s = vv_animation_render(j->anim, w, r, &o, &j->stats);
    }
    j->status = s;
    if (s != VV_OK)
        g_strlcpy(j->error, vv_error_message(), sizeof j->error);
    vv_renderer_free(r);
    g_idle_add(render_done, g_object_ref(j->page));
    return NULL;
}

static gboolean
render_tick(gpointer data) {
    VvgAnimatorPage *self = data;
    VvgAnimatorJob *j = self->job;
    if (!j)
        return G_SOURCE_CONTINUE;
    double f;
    __atomic_load(&j->fraction, &f, __ATOMIC_RELAXED);
    int done = __atomic_load_n(&j->frames_done, __ATOMIC_RELAXED);
    double el = (g_get_monotonic_time() - j->start_us) * 1e-6;
    char text[128];
    if (f > 0.02)
        snprintf(text, sizeof text, "frame %d of %d, %.0f %%, %.1f s left", done, j->frames,
                 100 * f, el * (1 - f) / f);
    else
        snprintf(text, sizeof text, "frame %d of %d, %.0f %%", done, j->frames, 100 * f);
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(self->progress), f);
    gtk_progress_bar_set_text(GTK_PROGRESS_BAR(self->progress), text);
    return G_SOURCE_CONTINUE;
}

static gboolean
render_done(gpointer data) {
    VvgAnimatorPage *self = data;
    VvgAnimatorJob *j = self->job;
    if (self->disposed || !j) {
        g_object_unref(self);
        return G_SOURCE_REMOVE;
    }
    g_thread_join(j->thread);
    self->job = NULL;
    if (self->render_timer) {
        g_source_remove(self->render_timer);
        self->render_timer = 0;
    }
    const vv_anim_render_stats *st = &j->stats;
    char text[1280];
    if (j->status == VV_OK) {
        gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(self->progress), 1);
        snprintf(text, sizeof text, "done in %.1f s", st->total_s);
        gtk_progress_bar_set_text(GTK_PROGRESS_BAR(self->progress), text);
        snprintf(text, sizeof text, "wrote %s: %d frames (%d rendered, %d kept from before)",
                 j->output, st->frames, st->rendered, st->reused);
        vvg_animator_set_label_tip(self->render_status, text);
    } else if (j->status == VV_ERR_CANCELLED) {
        gtk_progress_bar_set_text(GTK_PROGRESS_BAR(self->progress), "cancelled");
        snprintf(text, sizeof text,
                 "cancelled after %d of %d frames; Render again resumes (finished frames are "
                 "kept)",
                 st->rendered + st->reused, st->frames);
        vvg_animator_set_label_tip(self->render_status, text);
    } else {
        gtk_progress_bar_set_text(GTK_PROGRESS_BAR(self->progress), "failed");
        vvg_animator_set_label_tip(self->render_status, j->error);
        vvg_show_error(GTK_WIDGET(self), "Cannot render the animation", j->error);
    }
    job_free(j);
    vvg_animator_update_sensitivity(self);
    g_object_unref(self);
    return G_SOURCE_REMOVE;
}

void
vvg_animator_render_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    if (self->job)
        return;
    const char *out = gtk_editable_get_text(GTK_EDITABLE(self->output));
    if (!out[0]) {
        vvg_show_error(GTK_WIDGET(self), "Cannot render the animation", "no output file");
        return;
    }
    VvgAnimatorJob *j = g_new0(VvgAnimatorJob, 1);
    j->page = self;
    j->output = g_strdup(out);
    j->resume = gtk_check_button_get_active(GTK_CHECK_BUTTON(self->resume));
    vv_error_clear();
    /* during Play, the World as it was at Play */
    vv_status s =
        vv_world_clone(&j->world, self->base ? self->base : vvg_document_world(self->doc));
    if (s == VV_OK)
        s = vv_animation_clone(&j->anim, self->anim);
    if (s != VV_OK) {
        vvg_animator_show_library_error(self, "Cannot render the animation");
        job_free(j);
        return;
    }
    j->frames = vv_animation_frame_count(j->anim);
    j->start_us = g_get_monotonic_time();
    self->job = j;
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(self->progress), 0);
    gtk_progress_bar_set_text(GTK_PROGRESS_BAR(self->progress), "starting");
    vvg_animator_set_label_tip(self->render_status, "");
    self->render_timer = g_timeout_add(100, render_tick, self);
    j->thread = g_thread_new("volvis-animate", render_main, j);
    vvg_animator_update_sensitivity(self);
}

void
vvg_animator_cancel_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgAnimatorPage *self = user;
    if (self->job)
        __atomic_store_n(&self->job->cancel, 1, __ATOMIC_RELAXED);
}

void
vvg_animator_stop_render(VvgAnimatorPage *self) {
    if (self->job) {
        /* going away cancels the render; its finished frames stay for a resume */
        __atomic_store_n(&self->job->cancel, 1, __ATOMIC_RELAXED);
        g_thread_join(self->job->thread);
        job_free(self->job);
        self->job = NULL;
    }
    if (self->render_timer) {
        g_source_remove(self->render_timer);
        self->render_timer = 0;
    }
}
