/*
 * The Animator page's insides (internal to VvgAnimatorPage): its fields,
 * shared by vvg-animator-page.c (the widgets, the animation's summary, the
 * timeline, sequences, keys, New, Open and Save) and vvg-animator-play.c
 * (Play, Record flight and the final render). UI thread only.
 */
#ifndef VVG_ANIMATOR_PLAY_H
#define VVG_ANIMATOR_PLAY_H

#include "vvg-animator-page.h"

G_BEGIN_DECLS

/** A final render on its worker thread (vvg-animator-play.c). */
typedef struct VvgAnimatorJob VvgAnimatorJob;

struct _VvgAnimatorPage {
    GtkBox parent;
    VvgDocument *doc;
    gulong changed_id;
    vv_animation *anim; /* the current animation, owned */
    gboolean updating;  /* set while widgets are filled from the animation */
    gboolean disposed;

    GtkWidget *timeline, *play, *stop, *record, *loop, *time_label;
    GtkWidget *fps, *frames;
    GtkWidget *output, *resume, *render_info, *render, *cancel, *progress, *render_status;
    GtkWidget *list, *anim_status;
    GtkWidget *seq_type, *seq_stack;
    GtkWidget *orbit_degrees, *orbit_elevation, *rot_axis, *rot_degrees, *fly[3], *sweep_axis;
    GtkWidget *key_time;

    /* Play */
    guint play_source;
    vv_animation *playing; /* the copy being played */
    vv_world *base;        /* the World at Play: every frame is evaluated from it */
    GHashTable *series;    /* time series of objects[i].time tracks, kept a session */
    gint64 play_start_us;
    double play_time;

    /* flight recording */
    vv_flight_recorder *recorder;
    guint record_source;
    gint64 record_start_us;

    /* final render */
    VvgAnimatorJob *job;
    guint render_timer;
};

/* vvg-animator-play.c */

/**
 * Play, Stop, Record flight, Render and Cancel pressable as far as Play, a
 * recording and a render allow.
 */
void vvg_animator_update_sensitivity(VvgAnimatorPage *self);
/**
 * The document's "changed" handler (@p user: the page): Play stops when an
 * edit ended its transient World; the render line follows the Rendering page.
 */
void vvg_animator_doc_changed(VvgDocument *doc, gpointer user);
/**
 * Ends Play: @p restore puts the World back as it was at Play, else the World
 * keeps the frame shown.
 */
void vvg_animator_stop_playback(VvgAnimatorPage *self, gboolean restore);
/** Stops recording; @p finish makes the samples the current animation. */
void vvg_animator_stop_recording(VvgAnimatorPage *self, gboolean finish);
/** Cancels a final render and joins its thread (its finished frames stay for a resume). */
void vvg_animator_stop_render(VvgAnimatorPage *self);
/* the buttons' handlers (@p user: the page) */
void vvg_animator_play_clicked(GtkButton *b, gpointer user);
void vvg_animator_stop_clicked(GtkButton *b, gpointer user);
void vvg_animator_record_toggled(GtkToggleButton *b, gpointer user);
void vvg_animator_render_clicked(GtkButton *b, gpointer user);
void vvg_animator_cancel_clicked(GtkButton *b, gpointer user);

/* vvg-animator-page.c */

/**
 * The time label ("t = ... s of ... s, frame ... of ...": Play's time, else
 * the key time), and the timeline drawn again.
 */
void vvg_animator_update_time_label(VvgAnimatorPage *self);
/** Takes @p a as the current animation and shows it. */
void vvg_animator_set_animation(VvgAnimatorPage *self, vv_animation *a);
/** An error dialog for @p what with the library's message. */
void vvg_animator_show_library_error(VvgAnimatorPage *self, const char *what);
/** The page's status line: what was opened, saved or recorded. */
void vvg_animator_set_status(VvgAnimatorPage *self, const char *text);
/** A one-line label's text; the tooltip holds the whole text when the line is cut. */
void vvg_animator_set_label_tip(GtkWidget *label, const char *text);

G_END_DECLS
#endif
