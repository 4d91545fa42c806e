/* VvgSceneView: the scene view and the Navigator (vvg-scene-view.h). */
#define _GNU_SOURCE /* syscall(SYS_gettid) for the render thread's priority */
#include "vvg-scene-view.h"
#include "vvg-scene-overlay.h"
#include "vvg-widgets.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

/* Seconds a preview frame may take so the view holds 24 frames a second
 * (the target is 20, with room for the load of a shared machine), leaving
 * time for showing it. */
#define PREVIEW_BUDGET (1.0 / 24.0 - 0.006)
/* Volumes of at most this many voxels (256^3) are never drawn as boxes. */
#define SURFACES_ABOVE_VOXELS (256.0 * 256.0 * 256.0)

/* ThreadSanitizer builds (VOLVIS_TSAN, scripts/tsan.sh) count the frames
 * for the report and can inject a race; other builds have neither. */
#ifdef VVG_TSAN
#define TSAN_COUNT(counter) (self->tsan_##counter++)
#else
#define TSAN_COUNT(counter) ((void)0)
#endif

static gint64 start_us;

void
vvg_scene_view_set_start_time(gint64 us) {
    start_us = us;
}

/* ---- the worker --------------------------------------------------------- */

/* The files out of core a frame draws objects from (the visible objects'
 * sources, a reference each): for sharpening (vv_source_wait) and the
 * Navigator's cache line. */
typedef struct src_set {
    vv_source *s[VV_SOURCES_MAX];
    int n;
} src_set;

static void
src_set_clear(src_set *s) {
    for (int i = 0; i < s->n; i++)
        vv_source_free(s->s[i]);
    s->n = 0;
}

/* @p dst (empty) holding its own references to @p src's sources. */
static void
src_set_ref(src_set *dst, const src_set *src) {
    for (int i = 0; i < src->n; i++)
        dst->s[i] = vv_source_ref(src->s[i]);
    dst->n = src->n;
}

/* One request: a snapshot and the representations to draw in turn. */
typedef struct job {
    guint64 gen;
    vv_world *world;
    int n_kinds;
    vv_preview_kind kinds[3];
    gboolean refine; /* cancelled by any newer state */
    gint64 posted_us;
    src_set src; /* the visible objects' files out of core (none: all in memory) */
} job;

/* One finished frame, posted to the UI thread. */
typedef struct frame {
    VvgSceneView *view; /* a reference is held */
    guint64 gen;
    vv_preview_kind kind;
    gboolean refine;
    int width, height;
    GBytes *pixels; /* RGBA8 */
    float *depth;   /* full frames: depth per pixel (vv_image), for picking */
    vv_view camera; /* the view it was rendered with */
    double render_ms;
    gint64 posted_us;
    gint64 rendered_us; /* when the renderer finished */
    char error[512];
    /* drawn out of core: the sources, the nodes per level, those pending, stalled */
    src_set src;
    int nodes[VV_LOD_MAX_LEVELS], pending, stalled;
    char lod_note[128]; /* why the files were not drawn out of core ("" when they were) */
} frame;

struct _VvgSceneView {
    GtkWidget parent;
    VvgDocument *doc;
    VvgMarks *marks;
    gulong changed_id;

    /* worker */
    GThread *thread;
    GMutex lock;
    GCond cond;
    job *pending;         /* newest request not yet taken */
    vv_world *last_world; /* the last refined state, for warm_previews (under lock) */
    gboolean quit;        /* written under lock, atomically: cancel_cb reads it without */
    guint64 cancel_below; /* refinement of a generation below this stops (atomic) */
    vv_preview *preview;  /* worker only */
    char preview_renderer[32];
    vv_preview_policy policy; /* under lock: written by the worker, read by the UI */

    /* UI */
    guint64 gen;       /* of the World's current state */
    guint64 shown_gen; /* of the frame on screen */
    int shown_kind;
    GdkTexture *texture;
    gboolean texture_logged;
    double shown_render_ms;
    float *shown_depth; /* of the full frame on screen, or NULL */
    vv_view shown_view;
    VvgPickFunc pick_fn;
    gpointer pick_user;
    gboolean dragged;
    gint64 shown_latency_us;
    gint64 shown_rendered_us; /* when the renderer finished the frame on screen */
    guint refine_source;
    int refine_delay_ms;
    gboolean moving;
    VvgNavTarget target;
    int light;
    int cut_object, cut_plane; /* vvg_scene_view_set_cut_plane */
    double drag_last_x, drag_last_y;
    int drag_button;
    GdkModifierType drag_mods;
    double full_ms;
    FILE *frame_log;
    char last_error[512];
    /* the frame on screen's files out of core and what it drew */
    src_set shown_src;
    int shown_nodes[VV_LOD_MAX_LEVELS], shown_pending, shown_stalled;
    char shown_lod_note[128];

    /* flight */
    gboolean flight;
    double yaw_rate, pitch_rate, roll_rate, throttle;
    guint tick_id;
    gint64 last_tick_us;

#ifdef VVG_TSAN
    gboolean tsan_inject_race;                        /* VOLVIS_TSAN_INJECT_RACE=1 */
    guint64 tsan_posted, tsan_cancelled, tsan_warmed; /* worker only */
    guint64 tsan_shown, tsan_dropped;                 /* UI only */
#endif
};

G_DEFINE_TYPE(VvgSceneView, vvg_scene_view, GTK_TYPE_WIDGET)

static void
job_free(job *j) {
    if (!j)
        return;
    vv_world_free(j->world);
    src_set_clear(&j->src);
    g_free(j);
}

static void
frame_free(frame *f) {
    g_object_unref(f->view);
    if (f->pixels)
        g_bytes_unref(f->pixels);
    g_free(f->depth);
    src_set_clear(&f->src);
    g_free(f);
}

typedef struct cancel_ctx {
    VvgSceneView *view;
    guint64 gen;
    gboolean refine;
} cancel_ctx;

/* A refinement stops as soon as the state changes; a preview is always
 * finished (while input streams in, every preview would be outdated before
 * it is done, and none would ever be shown); both stop when the view goes. */
static int
cancel_cb(void *user, double fraction) {
    (void)fraction;
    cancel_ctx *c = user;
    if (__atomic_load_n(&c->view->quit, __ATOMIC_RELAXED))
        return 1;
    guint64 below = __atomic_load_n(&c->view->cancel_below, __ATOMIC_RELAXED);
    return c->refine && c->gen < below;
}

static gboolean show_frame(gpointer data);
static gboolean tick_cb(GtkWidget *widget, GdkFrameClock *clock, gpointer user);

/* The job's World with its objects out of core drawn from their files
 * (vv_renderer_render chooses: a pyramid by level of detail, a bricked file
 * brick by brick, the others from memory, each a layer), at the kind's
 * image size with the World's renderer (its settings applied): a
 * progressive frame from what the cache holds, asking the pyramids'
 * loaders for the rest (converged 0), or the converged frame, which reads
 * what it needs (1). VV_ERR_UNSUPPORTED when the renderer has no region
 * method or the World is not one that layers draw (overlapping composite
 * objects, geometry, several objects by the ray tracer): the caller then
 * draws the proxies in memory. */
static vv_status
render_out_of_core(VvgSceneView *self, const job *j, frame *f, int converged, vv_render_options *ro,
                   vv_image *img) {
    const vv_world *w = j->world;
    vv_renderer *r = vv_preview_final_renderer(self->preview);
    vv_status s = vv_renderer_apply_settings(r, &w->render);
    if (s != VV_OK)
        return s;
    if (!(vv_renderer_get_info(r)->caps & VV_RENDERER_REGION))
        return vv_error_set(VV_ERR_UNSUPPORTED, "%s draws no regions",
                            vv_renderer_get_info(r)->name);
    vv_view v = w->view;
    v.width = img->width;
    v.height = img->height;
    vv_lod lod;
    vv_lod_init(&lod);
    lod.progressive = !converged;
    lod.background = 1;
    lod.load_budget = 0;
    ro->lod = &lod;
    s = vv_renderer_render(r, w, &v, ro, img);
    ro->lod = NULL;
    if (s == VV_OK) {
        memcpy(f->nodes, lod.nodes, sizeof f->nodes);
        f->pending = lod.pending;
        f->stalled = lod.stalled;
        src_set_ref(&f->src, &j->src);
    }
    return s;
}

/* @p w with every object's file out of core dropped (vv_object_set_volume
 * of its own proxy): the proxies drawn in memory. NULL when it cannot be
 * made. */
static vv_world *
world_in_memory(const vv_world *w) {
    vv_world *m = NULL;
    if (vv_world_clone(&m, w) != VV_OK)
        return NULL;
    for (int i = 0; i < m->n_objects; i++)
        if (vvg_object_source(m->objects[i]))
            (void)vv_object_set_volume(m->objects[i], m->objects[i]->volume);
    return m;
}

/* Draws one representation of a job (a pyramid's converged frame when
 * @p converged); NULL when cancelled. */
static frame *
render_one(VvgSceneView *self, const job *j, vv_preview_kind kind, int converged) {
    frame *f = g_new0(frame, 1);
    f->view = g_object_ref(self);
    f->gen = j->gen;
    f->kind = kind;
    f->refine = j->refine;
    f->posted_us = j->posted_us;
    const vv_world *w = j->world;
    const char *rname = vv_world_renderer(w);
    vv_status s = VV_OK;
    vv_error_clear();
    if (!self->preview || strcmp(rname, self->preview_renderer) != 0) {
        vv_preview_free(self->preview);
        self->preview = NULL;
        s = vv_preview_new(&self->preview, rname);
        if (s == VV_OK)
            g_strlcpy(self->preview_renderer, rname, sizeof self->preview_renderer);
    }
    vv_image *img = NULL;
    int iw = 1, ih = 1;
    vv_preview_size(kind, w->view.width, w->view.height, &iw, &ih);
    if (s == VV_OK && kind == VV_PREVIEW_FULL) {
        s = vv_renderer_apply_settings(vv_preview_final_renderer(self->preview), &w->render);
    }
    if (s == VV_OK)
        s = vv_image_new(&img, iw, ih);
    cancel_ctx cc = {self, j->gen, j->refine};
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.quality = vv_render_settings_quality(&w->render);
    ro.progress.fn = cancel_cb;
    ro.progress.user = &cc;
#ifdef VVG_TSAN
    /* the injected race: the policy entry of this kind written without
     * the lock while the UI thread reads the policy under it */
    if (self->tsan_inject_race) {
        volatile double *entry = &self->policy.seconds[kind];
        *entry = *entry;
    }
#endif
    gint64 t0 = g_get_monotonic_time();
    gboolean drawn = FALSE;
    vv_world *mem = NULL; /* the proxies in memory, when out of core cannot draw w */
    if (s == VV_OK && j->src.n > 0) {
        s = render_out_of_core(self, j, f, converged, &ro, img);
        drawn = s == VV_OK || s == VV_ERR_CANCELLED;
        if (s == VV_ERR_UNSUPPORTED) { /* the proxies in memory, and why */
            g_strlcpy(f->lod_note, vv_error_message(), sizeof f->lod_note);
            vv_error_clear();
            mem = world_in_memory(w);
            s = mem ? VV_OK : VV_ERR_NOMEM;
        }
    }
    if (s == VV_OK && !drawn)
        s = vv_preview_render(self->preview, mem ? mem : w, &w->view, kind, &ro, img);
    vv_world_free(mem);
    gint64 t1 = g_get_monotonic_time();
    f->rendered_us = t1;
    double secs = (t1 - t0) * 1e-6;
    if (s == VV_ERR_CANCELLED) {
        vv_image_free(img);
        frame_free(f);
        return NULL;
    }
    f->render_ms = secs * 1e3;
    if (s != VV_OK) {
        g_strlcpy(f->error, vv_error_message(), sizeof f->error);
        vv_image_free(img);
        return f;
    }
    if (!vv_preview_last_warmup(self->preview)) {
        g_mutex_lock(&self->lock);
        vv_preview_policy_record(&self->policy, kind, secs);
        g_mutex_unlock(&self->lock);
    }
    size_t n = (size_t)iw * ih * 4;
    guint8 *px = g_malloc(n);
    vv_image_to_8bit(img, 4, 1.0, px);
    /* opaque: the background is composited in (as `volvis render` writes RGB) */
    for (size_t i = 3; i < n; i += 4)
        px[i] = 255;
    f->pixels = g_bytes_new_take(px, n);
    f->width = iw;
    f->height = ih;
    f->camera = w->view;
    if (kind == VV_PREVIEW_FULL)
        f->depth = g_memdup2(img->depth, sizeof(float) * (size_t)iw * ih);
    vv_image_free(img);
    return f;
}

/* After a refinement, while nothing else is asked for, the reduced surfaces
 * (PARC boxes, coarse Marching Cubes) of the state on screen are built and
 * timed off screen, so that the first drag does not stall on building them
 * and the policy knows their times. */
static void
warm_previews(VvgSceneView *self) {
    static const vv_preview_kind kinds[] = {VV_PREVIEW_COARSE_MC, VV_PREVIEW_BOXES};
    for (size_t i = 0; i < G_N_ELEMENTS(kinds); i++) {
        g_mutex_lock(&self->lock);
        gboolean busy = self->pending != NULL || self->quit;
        /* surfaces are drawn only for large volumes whose 1/8 ray cast is too slow */
        double cast = self->policy.seconds[VV_PREVIEW_RAYCAST_8];
        gboolean known = self->policy.seconds[kinds[i]] >= 0 || cast < 0 ||
                         cast <= PREVIEW_BUDGET || !self->policy.allowed[kinds[i]];
        vv_world *w = busy || known ? NULL : self->last_world;
        /* a large volume's reduced surfaces take seconds to build, which a
         * drag starting meanwhile would wait for: they are left out */
        for (int o = 0; w && o < w->n_objects; o++) {
            const vv_volume *v = w->objects[o]->volume;
            if (v && (double)v->dims[0] * v->dims[1] * v->dims[2] > 64e6)
                w = NULL;
        }
        if (w)
            self->last_world = NULL;
        g_mutex_unlock(&self->lock);
        if (!w)
            return;
        job j = {0};
        j.world = w;
        j.gen = 0;
        /* twice: the first builds, the second is timed and learnt */
        for (int r = 0; r < 2; r++) {
            frame *f = render_one(self, &j, kinds[i], 0);
            if (f) {
                TSAN_COUNT(warmed);
                frame_free(f);
            } else {
                TSAN_COUNT(cancelled);
            }
        }
        g_mutex_lock(&self->lock);
        if (!self->last_world)
            self->last_world = w;
        else
            vv_world_free(w);
        g_mutex_unlock(&self->lock);
    }
}

/* A full frame out of core with nodes pending: while the state stands, the
 * frame is drawn again each time the pyramids' loaders bring chunks (the
 * image sharpens), until nothing is pending; when a loader stalls (the view
 * needs more than the memory limit holds) or makes no progress, the
 * converged frame streams the rest. A newer request ends it. */
static void
sharpen_out_of_core(VvgSceneView *self, const job *j) {
    int last = INT_MAX, idle = 0;
    for (;;) {
        int loading = 0;
        for (int i = 0; i < j->src.n; i++)
            loading += vv_source_wait(j->src.s[i], 0.25 / j->src.n);
        g_mutex_lock(&self->lock);
        const gboolean newer = self->pending != NULL || self->quit;
        g_mutex_unlock(&self->lock);
        if (newer || cancel_cb(&(cancel_ctx){self, j->gen, j->refine}, 0))
            return;
        frame *f = render_one(self, j, VV_PREVIEW_FULL, 0);
        if (!f)
            return;
        const int pending = f->pending, stalled = f->stalled, ok = f->src.n > 0;
        g_idle_add_full(G_PRIORITY_DEFAULT, show_frame, f, NULL);
        if (!ok || pending == 0)
            return;
        idle = loading == 0 && pending >= last ? idle + 1 : 0;
        last = pending;
        if (stalled || idle >= 3) {
            f = render_one(self, j, VV_PREVIEW_FULL, 1);
            if (f)
                g_idle_add_full(G_PRIORITY_DEFAULT, show_frame, f, NULL);
            return;
        }
    }
}

static gpointer
worker_main(gpointer data) {
    VvgSceneView *self = data;
#ifdef __linux__
    /* The renderer's threads (OpenMP's, created from this one, inherit it)
     * yield to the UI thread and the display server, which have a frame to
     * show: on 2 cores they would otherwise wait for a time slice. */
    if (setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), 4) != 0)
        g_debug("volvis-gui: the render thread keeps its priority");
#endif
    for (;;) {
        g_mutex_lock(&self->lock);
        while (!self->pending && !self->quit)
            g_cond_wait(&self->cond, &self->lock);
        if (self->quit) {
            g_mutex_unlock(&self->lock);
            break;
        }
        job *j = self->pending;
        self->pending = NULL;
        g_mutex_unlock(&self->lock);
        for (int k = 0; k < j->n_kinds; k++) {
            if (cancel_cb(&(cancel_ctx){self, j->gen, j->refine}, 0))
                break;
            frame *f = render_one(self, j, j->kinds[k], 0);
            if (!f) {
                TSAN_COUNT(cancelled);
                break;
            }
            const gboolean sharpen =
                j->kinds[k] == VV_PREVIEW_FULL && f->src.n > 0 && f->pending > 0;
            TSAN_COUNT(posted);
            /* at the priority of input events: a stream of motion events
             * must not hold back the frames they cause */
            g_idle_add_full(G_PRIORITY_DEFAULT, show_frame, f, NULL);
            /* a newer request pre-empts the rest of a refinement */
            g_mutex_lock(&self->lock);
            gboolean newer = self->pending != NULL;
            g_mutex_unlock(&self->lock);
            if (newer)
                break;
            if (sharpen)
                sharpen_out_of_core(self, j);
        }
        gboolean refined = j->refine;
        if (refined) {
            g_mutex_lock(&self->lock);
            vv_world_free(self->last_world);
            self->last_world = j->world; /* kept for warm_previews */
            j->world = NULL;
            g_mutex_unlock(&self->lock);
        }
        job_free(j);
        if (refined)
            warm_previews(self);
    }
    vv_preview_free(self->preview);
    self->preview = NULL;
    return NULL;
}

static void
post_job(VvgSceneView *self, job *j) {
    if (!self->thread) { /* stopped */
        job_free(j);
        return;
    }
    g_mutex_lock(&self->lock);
    job_free(self->pending);
    self->pending = j;
    g_cond_signal(&self->cond);
    g_mutex_unlock(&self->lock);
}

/* ---- UI side ------------------------------------------------------------ */

/* With VOLVIS_FRAME_DIR set, the pixels of each full-quality frame put on
 * screen are written to DIR/full.png (atomically), for tests that compare
 * them with `volvis render` of the saved session. */
static void
save_shown(VvgSceneView *self, const frame *f) {
    (void)self;
    const char *dir = g_getenv("VOLVIS_FRAME_DIR");
    if (!dir || !*dir)
        return;
    vv_image *img = NULL;
    if (vv_image_new(&img, f->width, f->height) != VV_OK)
        return;
    const guint8 *px = g_bytes_get_data(f->pixels, NULL);
    for (size_t i = 0; i < (size_t)f->width * f->height * 4; i++)
        img->rgba[i] = px[i] / 255.0f;
    char *path = g_build_filename(dir, "full.png", NULL);
    if (vv_image_write_png(img, path, 1.0, 0) != VV_OK)
        g_warning("volvis-gui: VOLVIS_FRAME_DIR: %s", vv_error_message());
    g_free(path);
    vv_image_free(img);
}

static gboolean
show_frame(gpointer data) {
    frame *f = data;
    VvgSceneView *self = f->view;
    if (!self->doc) { /* disposed */
        frame_free(f);
        return G_SOURCE_REMOVE;
    }
    /* never a frame older than the one on screen, and never a refinement
     * of a state that has changed since */
    if (f->gen < self->shown_gen || (f->refine && f->gen != self->gen)) {
        TSAN_COUNT(dropped);
        frame_free(f);
        return G_SOURCE_REMOVE;
    }
    if (f->error[0]) {
        if (strcmp(f->error, self->last_error) != 0) {
            g_strlcpy(self->last_error, f->error, sizeof self->last_error);
            g_warning("volvis-gui: render: %s", f->error);
        }
        frame_free(f);
        return G_SOURCE_REMOVE;
    }
    self->last_error[0] = '\0';
    /* at the same state, a better representation replaces a worse one only */
    if (f->gen == self->shown_gen && self->texture && (int)f->kind < self->shown_kind) {
        TSAN_COUNT(dropped);
        frame_free(f);
        return G_SOURCE_REMOVE;
    }
    g_clear_object(&self->texture);
    self->texture =
        gdk_memory_texture_new(f->width, f->height, GDK_MEMORY_R8G8B8A8, f->pixels, 4 * f->width);
    self->texture_logged = FALSE;
    self->shown_gen = f->gen;
    self->shown_kind = f->kind;
    self->shown_render_ms = f->render_ms;
    self->shown_latency_us = g_get_monotonic_time() - f->posted_us;
    self->shown_rendered_us = f->rendered_us;
    g_free(self->shown_depth);
    self->shown_depth = NULL;
    self->shown_view = f->camera;
    src_set_clear(&self->shown_src);
    self->shown_src = f->src;
    f->src.n = 0;
    memcpy(self->shown_nodes, f->nodes, sizeof self->shown_nodes);
    self->shown_pending = f->pending;
    self->shown_stalled = f->stalled;
    g_strlcpy(self->shown_lod_note, f->lod_note, sizeof self->shown_lod_note);
    if (f->kind == VV_PREVIEW_FULL) {
        self->full_ms = f->render_ms;
        save_shown(self, f);
        self->shown_depth = f->depth;
        f->depth = NULL;
    }
    TSAN_COUNT(shown);
    gtk_widget_queue_draw(GTK_WIDGET(self));
    frame_free(f);
    return G_SOURCE_REMOVE;
}

static job *
new_job(VvgSceneView *self, gboolean refine) {
    vv_world *w = vvg_document_snapshot(self->doc);
    if (!w)
        return NULL;
    job *j = g_new0(job, 1);
    j->gen = self->gen;
    j->world = w;
    j->refine = refine;
    j->posted_us = g_get_monotonic_time();
    /* the visible volumes that show files out of core: drawn from them (by
     * level of detail, by bricks), the other objects in memory beside them */
    for (int i = 0; i < w->n_objects && j->src.n < VV_SOURCES_MAX; i++) {
        vv_source *src = w->objects[i]->visible ? vvg_object_source(w->objects[i]) : NULL;
        if (src)
            j->src.s[j->src.n++] = vv_source_ref(src);
    }
    return j;
}

static gboolean
refine_cb(gpointer data) {
    VvgSceneView *self = data;
    self->refine_source = 0;
    self->moving = FALSE;
    job *j = new_job(self, TRUE);
    if (!j)
        return G_SOURCE_REMOVE;
    /* 1/2 first when the frame on screen is coarser and the full frame is
     * slow (or not known yet), then the full frame */
    g_mutex_lock(&self->lock);
    double half = self->policy.seconds[VV_PREVIEW_RAYCAST_2];
    g_mutex_unlock(&self->lock);
    /* (the first time, or when the final frame is slow and the 1/2 step
     * quick: it must not delay the final frame by more than a few frames) */
    if ((self->shown_kind < VV_PREVIEW_RAYCAST_2 || self->shown_gen != self->gen) &&
        (self->full_ms <= 0 || (self->full_ms > 300 && half >= 0 && half <= 0.04)))
        j->kinds[j->n_kinds++] = VV_PREVIEW_RAYCAST_2;
    j->kinds[j->n_kinds++] = VV_PREVIEW_FULL;
    post_job(self, j);
    return G_SOURCE_REMOVE;
}

/* The World changed: draw a preview now and refine after the delay. */
static gboolean sync_size(VvgSceneView *self);

static void
state_changed(VvgSceneView *self) {
    sync_size(self);
    self->gen++;
    __atomic_store_n(&self->cancel_below, self->gen, __ATOMIC_RELAXED);
    self->moving = TRUE;
    if (vvg_document_world(self->doc)->n_objects == 0) {
        /* nothing to render: the background alone */
        g_clear_object(&self->texture);
        self->shown_gen = self->gen;
        gtk_widget_queue_draw(GTK_WIDGET(self));
        return;
    }
    /* volumes up to 256^3 are always cast (at 1/8 size at worst): boxes and
     * surfaces only stand in for larger ones whose 1/8 cast misses the budget */
    const vv_world *wd = vvg_document_world(self->doc);
    double voxels = 0;
    for (int i = 0; i < wd->n_objects; i++) {
        const vv_volume *v = wd->objects[i]->volume;
        if (v && wd->objects[i]->visible)
            voxels = fmax(voxels, (double)v->dims[0] * v->dims[1] * v->dims[2]);
    }
    g_mutex_lock(&self->lock);
    for (int k = VV_PREVIEW_BBOX; k <= VV_PREVIEW_COARSE_MC; k++)
        self->policy.allowed[k] = voxels > SURFACES_ABOVE_VOXELS;
    vv_preview_kind k = vv_preview_policy_choose(&self->policy, PREVIEW_BUDGET);
    g_mutex_unlock(&self->lock);
    job *j = new_job(self, FALSE);
    if (j) {
        j->kinds[j->n_kinds++] = k;
        post_job(self, j);
    }
    if (self->refine_source)
        g_source_remove(self->refine_source);
    self->refine_source = g_timeout_add(self->refine_delay_ms, refine_cb, self);
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    state_changed(VVG_SCENE_VIEW(user));
}

void
vvg_scene_view_refresh(VvgSceneView *self) {
    state_changed(self);
}

/* ---- geometry of the view on screen ---------------------------------------- */

/* Where the image is drawn: its top-left corner and scale (<= 1) in the widget. */
static void
image_rect(VvgSceneView *self, double *x0, double *y0, double *scale) {
    const vv_world *w = vvg_document_world(self->doc);
    int ww = gtk_widget_get_width(GTK_WIDGET(self)), wh = gtk_widget_get_height(GTK_WIDGET(self));
    double vw = w->view.width, vh = w->view.height;
    double s = fmin(1.0, fmin(ww / vw, wh / vh));
    *scale = s > 0 ? s : 1;
    *x0 = floor((ww - vw * s) / 2);
    *y0 = floor((wh - vh * s) / 2);
}

gboolean
vvg_scene_view_pick(VvgSceneView *self, double x, double y, vv_vec3 *world) {
    if (!self->shown_depth || self->shown_gen != self->gen || !self->texture)
        return FALSE;
    double x0, y0, s;
    image_rect(self, &x0, &y0, &s);
    const vv_view *v = &self->shown_view;
    int px = (int)floor((x - x0) / s), py = (int)floor((y - y0) / s);
    if (px < 0 || py < 0 || px >= v->width || py >= v->height)
        return FALSE;
    float d = self->shown_depth[(size_t)py * v->width + px];
    if (!isfinite(d))
        return FALSE;
    vv_ray ray = vv_view_ray(v, px, py);
    *world = vv_ray_at(ray, d);
    return TRUE;
}

void
vvg_scene_view_pick_next(VvgSceneView *self, VvgPickFunc fn, gpointer user) {
    self->pick_fn = fn;
    self->pick_user = user;
    gtk_widget_set_cursor_from_name(GTK_WIDGET(self), fn ? "crosshair" : NULL);
}

/* The cut plane a VVG_NAV_CUT drag moves: the selected object's last local
 * one, else the World's last global one; NULL when there is none. With
 * @p t, also its vv_nav_apply target. */
static vv_cut_plane *
target_plane(VvgSceneView *self, vv_nav_target *t) {
    vv_world *w = vvg_document_world(self->doc);
    vv_object *o = vvg_document_selected_object(self->doc);
    vv_nav_target nt = {VV_NAV_TARGET_CUT, -1, -1};
    vv_cut_plane *pl = NULL;
    int co = self->cut_object, cp = self->cut_plane;
    if (cp >= 0 && co < w->n_objects &&
        cp < (co < 0 ? w->n_cut_planes : w->objects[co]->n_cut_planes)) {
        nt.index = co;
        nt.plane = cp;
        pl = co < 0 ? &w->cut_planes[cp] : &w->objects[co]->cut_planes[cp];
    } else if (o && o->n_cut_planes > 0) {
        nt.index = vvg_document_selected(self->doc);
        pl = &o->cut_planes[o->n_cut_planes - 1];
    } else if (w->n_cut_planes > 0) {
        pl = &w->cut_planes[w->n_cut_planes - 1];
    }
    if (pl && t)
        *t = nt;
    return pl;
}

/* ---- drawing -------------------------------------------------------------- */

static void
log_frame(VvgSceneView *self) {
    if (!self->frame_log || self->texture_logged || !self->texture)
        return;
    self->texture_logged = TRUE;
    gint64 now = g_get_monotonic_time();
    double ms = (now - start_us) * 1e-3;
    /* the GUI's own time a frame: from the renderer's end to this paint */
    fprintf(self->frame_log, "%.3f %s %dx%d %.3f %.3f %lu %.3f\n", ms,
            vv_preview_kind_name((vv_preview_kind)self->shown_kind),
            gdk_texture_get_width(self->texture), gdk_texture_get_height(self->texture),
            self->shown_render_ms, self->shown_latency_us * 1e-3, (unsigned long)self->shown_gen,
            (now - self->shown_rendered_us) * 1e-3);
    fflush(self->frame_log);
}

/* The anatomical frame and unit of the selected volume (else the first). */
static void
volume_frame(VvgSceneView *self, vv_space *space, const char **units) {
    const vv_world *w = vvg_document_world(self->doc);
    const vv_object *o = vvg_document_selected_object(self->doc);
    for (int i = 0; (!o || !o->volume) && i < w->n_objects; i++)
        o = w->objects[i];
    *space = o && o->volume ? o->volume->space : VV_SPACE_UNKNOWN;
    *units = vvg_unit_label(o ? o->volume : NULL);
}

static void
draw_overlays(VvgSceneView *self, GtkSnapshot *snapshot, int ww, int wh) {
    VvgSceneOverlay ov;
    memset(&ov, 0, sizeof ov);
    ov.world = vvg_document_world(self->doc);
    ov.view = &ov.world->view;
    image_rect(self, &ov.x0, &ov.y0, &ov.scale);
    ov.width = ww;
    ov.height = wh;
    ov.target = self->target;
    ov.moving_plane = self->target == VVG_NAV_CUT ? target_plane(self, NULL) : NULL;
    ov.light = self->light;
    ov.marks = self->marks;
    volume_frame(self, &ov.space, &ov.units);
    cairo_t *cr = gtk_snapshot_append_cairo(snapshot, &GRAPHENE_RECT_INIT(0, 0, ww, wh));
    vvg_scene_overlay_draw(cr, &ov);
    cairo_destroy(cr);
}

static void
vvg_scene_view_snapshot(GtkWidget *widget, GtkSnapshot *snapshot) {
    VvgSceneView *self = VVG_SCENE_VIEW(widget);
    int ww = gtk_widget_get_width(widget), wh = gtk_widget_get_height(widget);
    const vv_world *w = vvg_document_world(self->doc);
    vv_vec3 bg = w->background;
    GdkRGBA bgc = {(float)bg.x, (float)bg.y, (float)bg.z, 1};
    gtk_snapshot_append_color(snapshot, &bgc, &GRAPHENE_RECT_INIT(0, 0, ww, wh));
    if (!self->texture || w->n_objects == 0)
        return;
    /* the view's image: the widget's size (times its scale), centred */
    double x0, y0, sc;
    image_rect(self, &x0, &y0, &sc);
    graphene_rect_t r = GRAPHENE_RECT_INIT((float)x0, (float)y0, (float)(w->view.width * sc),
                                           (float)(w->view.height * sc));
    gtk_snapshot_append_texture(snapshot, self->texture, &r);
    draw_overlays(self, snapshot, ww, wh);
    log_frame(self);
}

/* The view renders at the widget's size in device pixels: the World's view
 * follows it (no undo step, the session stays saved; a saved session
 * renders through the CLI at this size). TRUE when it changed. */
static gboolean
sync_size(VvgSceneView *self) {
    int scale = gtk_widget_get_scale_factor(GTK_WIDGET(self));
    int w = gtk_widget_get_width(GTK_WIDGET(self)) * scale;
    int h = gtk_widget_get_height(GTK_WIDGET(self)) * scale;
    if (w < 16 || h < 16)
        return FALSE;
    const vv_view *v = &vvg_document_world(self->doc)->view;
    if (v->width == w && v->height == h)
        return FALSE;
    vvg_document_set_view_size(self->doc, w, h);
    return TRUE;
}

static void
vvg_scene_view_size_allocate(GtkWidget *widget, int width, int height, int baseline) {
    GTK_WIDGET_CLASS(vvg_scene_view_parent_class)->size_allocate(widget, width, height, baseline);
    VvgSceneView *self = VVG_SCENE_VIEW(widget);
    if (self->doc && sync_size(self))
        state_changed(self);
}

static void
vvg_scene_view_measure(GtkWidget *widget, GtkOrientation o, int for_size, int *min, int *nat,
                       int *min_base, int *nat_base) {
    (void)widget;
    (void)for_size;
    /* small: the view takes what the window gives it */
    *min = 96;
    *nat = o == GTK_ORIENTATION_HORIZONTAL ? 320 : 240;
    *min_base = *nat_base = -1;
}

/* ---- input ------------------------------------------------------------------ */

static void
begin_interaction(VvgSceneView *self, const char *label) {
    vvg_document_begin_edit(self->doc, label);
}

/* A drag of (dx, dy) widget pixels, through the Navigator (vv_nav_apply):
 * left drag rotates, Shift or the middle or right button pans, Ctrl zooms
 * (an object scales); Alt moves the selected object. A cut plane slides
 * along its normal, Shift turns it. */
static void
apply_motion(VvgSceneView *self, double dx, double dy) {
    vv_world *w = vvg_document_world(self->doc);
    /* widget pixels to view pixels (the image may be shown scaled down) */
    double x0, y0, s;
    image_rect(self, &x0, &y0, &s);
    dx /= s;
    dy /= s;
    gboolean shift = (self->drag_mods & GDK_SHIFT_MASK) != 0;
    gboolean pan = self->drag_button == 3 || self->drag_button == 2 || shift;
    gboolean zoom = (self->drag_mods & GDK_CONTROL_MASK) != 0;
    VvgNavTarget target = self->target;
    if (self->drag_mods & GDK_ALT_MASK)
        target = VVG_NAV_OBJECT;
    vv_nav_target t = {VV_NAV_TARGET_VIEW, 0, -1};
    vv_nav_motion m = {.kind = zoom  ? VV_NAV_ZOOM
                               : pan ? VV_NAV_PAN
                                     : VV_NAV_ROTATE,
                       .dx = dx,
                       .dy = dy,
                       .factor = exp(-dy / 200.0)};
    if (target == VVG_NAV_OBJECT && vvg_document_selected(self->doc) >= 0) {
        t.kind = VV_NAV_TARGET_OBJECT;
        t.index = vvg_document_selected(self->doc);
    } else if (target == VVG_NAV_CUT) {
        if (!target_plane(self, &t))
            return;
        m.kind = shift ? VV_NAV_ROTATE : VV_NAV_PAN;
    } else if (target == VVG_NAV_LIGHT) {
        if (self->light < 0 || self->light >= w->n_lights)
            return;
        t.kind = VV_NAV_TARGET_LIGHT;
        t.index = self->light;
        m.kind = VV_NAV_ROTATE; /* a light follows any drag */
    }
    if (vv_nav_apply(w, &t, &m) != VV_OK)
        return;
    vvg_document_changed(self->doc);
}

static void
drag_begin(GtkGestureDrag *g, double x, double y, gpointer user) {
    VvgSceneView *self = user;
    self->drag_last_x = 0;
    self->drag_last_y = 0;
    self->drag_button = (int)gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(g));
    self->drag_mods = gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(g));
    (void)x;
    (void)y;
    self->dragged = FALSE;
    gtk_widget_grab_focus(GTK_WIDGET(self));
}

static void
drag_end(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    VvgSceneView *self = user;
    if (self->flight && self->drag_button == 1) /* the mouse stick is let go */
        self->yaw_rate = self->pitch_rate = 0;
    if (self->dragged || !self->pick_fn || fabs(ox) > 3 || fabs(oy) > 3)
        return;
    double sx, sy;
    gtk_gesture_drag_get_start_point(g, &sx, &sy);
    vv_vec3 p;
    if (!vvg_scene_view_pick(self, sx, sy, &p))
        return; /* stays armed: nothing under the pointer yet */
    VvgPickFunc fn = self->pick_fn;
    gpointer u = self->pick_user;
    vvg_scene_view_pick_next(self, NULL, NULL);
    fn(u, p);
}

static void
drag_update(GtkGestureDrag *g, double ox, double oy, gpointer user) {
    (void)g;
    VvgSceneView *self = user;
    double dx = ox - self->drag_last_x, dy = oy - self->drag_last_y;
    self->drag_last_x = ox;
    self->drag_last_y = oy;
    if (dx == 0 && dy == 0)
        return;
    if (self->flight && self->drag_button == 1 &&
        !(self->drag_mods & (GDK_SHIFT_MASK | GDK_CONTROL_MASK | GDK_ALT_MASK))) {
        /* flight with the mouse: the drag is a stick, its offset from the
         * press sets the yaw and pitch rates (a quarter turn a second at
         * 200 pixels) until the button is released */
        double k = (VV_PI / 2) / 200.0;
        self->yaw_rate = CLAMP(-ox * k, -VV_PI, VV_PI);
        self->pitch_rate = CLAMP(-oy * k, -VV_PI, VV_PI);
        if (!self->dragged) {
            self->dragged = TRUE;
            begin_interaction(self, "fly");
        }
        if (!self->tick_id) {
            self->last_tick_us = 0;
            self->tick_id = gtk_widget_add_tick_callback(GTK_WIDGET(self), tick_cb, self, NULL);
        }
        return;
    }
    if (!self->dragged) {
        self->dragged = TRUE;
        begin_interaction(self, self->target == VVG_NAV_OBJECT  ? "move object"
                                : self->target == VVG_NAV_LIGHT ? "move light"
                                : self->target == VVG_NAV_CUT   ? "move cut plane"
                                                                : "move view");
    }
    apply_motion(self, dx, dy);
}

static gboolean
scroll_cb(GtkEventControllerScroll *c, double dx, double dy, gpointer user) {
    (void)c;
    (void)dx;
    VvgSceneView *self = user;
    if (!isfinite(dy) || dy == 0)
        return FALSE;
    begin_interaction(self, "zoom");
    vv_nav_motion m = {.kind = VV_NAV_ZOOM, .factor = pow(1.1, -dy)};
    vv_nav_target t = {VV_NAV_TARGET_VIEW, 0, -1};
    if (vv_nav_apply(vvg_document_world(self->doc), &t, &m) == VV_OK)
        vvg_document_changed(self->doc);
    return TRUE;
}

static gboolean
tick_cb(GtkWidget *widget, GdkFrameClock *clock, gpointer user) {
    (void)widget;
    VvgSceneView *self = user;
    gint64 now = gdk_frame_clock_get_frame_time(clock);
    double dt = self->last_tick_us ? (now - self->last_tick_us) * 1e-6 : 0.0;
    self->last_tick_us = now;
    if (self->yaw_rate == 0 && self->pitch_rate == 0 && self->roll_rate == 0 &&
        self->throttle == 0) {
        self->tick_id = 0;
        self->last_tick_us = 0;
        return G_SOURCE_REMOVE;
    }
    vv_world *w = vvg_document_world(self->doc);
    /* throttle in scene sizes a second */
    vv_box b = vv_world_bounds(w);
    double size = vv_vec3_length(vv_vec3_sub(b.max, b.min));
    if (!(size > 0))
        size = 1;
    vv_nav_motion m = {.kind = VV_NAV_FLY,
                       .yaw = self->yaw_rate,
                       .pitch = self->pitch_rate,
                       .roll = self->roll_rate,
                       .speed = self->throttle * 0.25 * size,
                       .dt = dt};
    vv_nav_target t = {VV_NAV_TARGET_VIEW, 0, -1};
    if (vv_nav_apply(w, &t, &m) == VV_OK)
        vvg_document_changed(self->doc);
    return G_SOURCE_CONTINUE;
}

static gboolean
flight_key(VvgSceneView *self, guint key, gboolean down) {
    double rate = down ? 0.6 : 0.0; /* radians a second */
    switch (key) {
    case GDK_KEY_Left:
        self->yaw_rate = rate;
        break;
    case GDK_KEY_Right:
        self->yaw_rate = -rate;
        break;
    case GDK_KEY_Up:
        self->pitch_rate = rate;
        break;
    case GDK_KEY_Down:
        self->pitch_rate = -rate;
        break;
    case GDK_KEY_q:
        self->roll_rate = -rate;
        break;
    case GDK_KEY_e:
        self->roll_rate = rate;
        break;
    case GDK_KEY_w:
        self->throttle = down ? 1.0 : 0.0;
        break;
    case GDK_KEY_s:
        self->throttle = down ? -1.0 : 0.0;
        break;
    default:
        return FALSE;
    }
    if (down && !self->tick_id) {
        begin_interaction(self, "fly");
        self->last_tick_us = 0;
        self->tick_id = gtk_widget_add_tick_callback(GTK_WIDGET(self), tick_cb, self, NULL);
    }
    return TRUE;
}

static gboolean
key_pressed(GtkEventControllerKey *c, guint key, guint code, GdkModifierType mods, gpointer user) {
    (void)c;
    (void)code;
    VvgSceneView *self = user;
    if (!self->flight || (mods & (GDK_CONTROL_MASK | GDK_ALT_MASK)))
        return FALSE;
    return flight_key(self, key, TRUE);
}

static void
key_released(GtkEventControllerKey *c, guint key, guint code, GdkModifierType mods, gpointer user) {
    (void)c;
    (void)code;
    (void)mods;
    VvgSceneView *self = user;
    if (self->flight)
        flight_key(self, key, FALSE);
}

/* ---- life cycle ---------------------------------------------------------- */

void
vvg_scene_view_stop(VvgSceneView *self) {
    if (self->thread) {
        g_mutex_lock(&self->lock);
        /* atomic: cancel_cb reads it without the lock, on the renderer's threads */
        __atomic_store_n(&self->quit, TRUE, __ATOMIC_RELAXED);
        __atomic_store_n(&self->cancel_below, G_MAXUINT64, __ATOMIC_RELAXED);
        g_cond_signal(&self->cond);
        g_mutex_unlock(&self->lock);
        g_thread_join(self->thread);
        self->thread = NULL;
#ifdef VVG_TSAN
        g_printerr("volvis-gui: render thread: %" G_GUINT64_FORMAT
                   " frames posted, %" G_GUINT64_FORMAT " cancelled, %" G_GUINT64_FORMAT
                   " drawn off screen; UI: %" G_GUINT64_FORMAT " shown, %" G_GUINT64_FORMAT
                   " dropped as stale or worse\n",
                   self->tsan_posted, self->tsan_cancelled, self->tsan_warmed, self->tsan_shown,
                   self->tsan_dropped);
#endif
    }
    job_free(self->pending);
    self->pending = NULL;
    vv_world_free(self->last_world);
    self->last_world = NULL;
}

static void
vvg_scene_view_dispose(GObject *o) {
    VvgSceneView *self = VVG_SCENE_VIEW(o);
    vvg_scene_view_stop(self);
    if (self->refine_source) {
        g_source_remove(self->refine_source);
        self->refine_source = 0;
    }
    if (self->doc) {
        g_signal_handler_disconnect(self->doc, self->changed_id);
        g_clear_object(&self->doc);
    }
    if (self->marks) {
        g_signal_handlers_disconnect_by_data(self->marks, self);
        g_clear_object(&self->marks);
    }
    g_clear_object(&self->texture);
    g_free(self->shown_depth);
    self->shown_depth = NULL;
    src_set_clear(&self->shown_src);
    if (self->frame_log) {
        fclose(self->frame_log);
        self->frame_log = NULL;
    }
    G_OBJECT_CLASS(vvg_scene_view_parent_class)->dispose(o);
}

static void
vvg_scene_view_finalize(GObject *o) {
    VvgSceneView *self = VVG_SCENE_VIEW(o);
    g_mutex_clear(&self->lock);
    g_cond_clear(&self->cond);
    G_OBJECT_CLASS(vvg_scene_view_parent_class)->finalize(o);
}

static void
vvg_scene_view_class_init(VvgSceneViewClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_scene_view_dispose;
    G_OBJECT_CLASS(klass)->finalize = vvg_scene_view_finalize;
    GTK_WIDGET_CLASS(klass)->snapshot = vvg_scene_view_snapshot;
    GTK_WIDGET_CLASS(klass)->measure = vvg_scene_view_measure;
    GTK_WIDGET_CLASS(klass)->size_allocate = vvg_scene_view_size_allocate;
}

static void
vvg_scene_view_init(VvgSceneView *self) {
    g_mutex_init(&self->lock);
    g_cond_init(&self->cond);
    vv_preview_policy_init(&self->policy);
    self->refine_delay_ms = 100;
    self->shown_kind = -1;
    self->cut_plane = -1;
#ifdef VVG_TSAN
    self->tsan_inject_race = g_strcmp0(g_getenv("VOLVIS_TSAN_INJECT_RACE"), "1") == 0;
    if (self->tsan_inject_race)
        g_printerr("volvis-gui: VOLVIS_TSAN_INJECT_RACE=1: the render thread writes the preview "
                   "policy without its lock\n");
#endif
    gtk_widget_set_focusable(GTK_WIDGET(self), TRUE);
    vvg_name(GTK_WIDGET(self), "3-D view");
    gtk_widget_set_hexpand(GTK_WIDGET(self), TRUE);
    gtk_widget_set_vexpand(GTK_WIDGET(self), TRUE);
    const char *log = g_getenv("VOLVIS_FRAME_LOG");
    if (log && *log) {
        self->frame_log = fopen(log, "a");
        if (!self->frame_log)
            g_warning("volvis-gui: VOLVIS_FRAME_LOG: cannot open %s", log);
    }
    /* left drag: rotate (Shift: pan, Ctrl: zoom); middle or right drag: pan */
    for (int button = 1; button <= 3; button++) {
        GtkGesture *drag = gtk_gesture_drag_new();
        gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(drag), (guint)button);
        g_signal_connect(drag, "drag-begin", G_CALLBACK(drag_begin), self);
        g_signal_connect(drag, "drag-update", G_CALLBACK(drag_update), self);
        g_signal_connect(drag, "drag-end", G_CALLBACK(drag_end), self);
        gtk_widget_add_controller(GTK_WIDGET(self), GTK_EVENT_CONTROLLER(drag));
    }
    GtkEventController *scroll = gtk_event_controller_scroll_new(
        GTK_EVENT_CONTROLLER_SCROLL_VERTICAL | GTK_EVENT_CONTROLLER_SCROLL_DISCRETE);
    g_signal_connect(scroll, "scroll", G_CALLBACK(scroll_cb), self);
    gtk_widget_add_controller(GTK_WIDGET(self), scroll);
    GtkEventController *keys = gtk_event_controller_key_new();
    g_signal_connect(keys, "key-pressed", G_CALLBACK(key_pressed), self);
    g_signal_connect(keys, "key-released", G_CALLBACK(key_released), self);
    gtk_widget_add_controller(GTK_WIDGET(self), keys);
}

static void
marks_changed(VvgMarks *m, gpointer user) {
    (void)m;
    gtk_widget_queue_draw(GTK_WIDGET(user));
}

VvgSceneView *
vvg_scene_view_new(VvgDocument *doc, VvgMarks *marks) {
    VvgSceneView *self = g_object_new(VVG_TYPE_SCENE_VIEW, NULL);
    self->doc = g_object_ref(doc);
    self->marks = g_object_ref(marks);
    g_signal_connect(marks, "changed", G_CALLBACK(marks_changed), self);
    self->changed_id = g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    self->thread = g_thread_new("volvis-render", worker_main, self);
    state_changed(self);
    return self;
}

void
vvg_scene_view_set_target(VvgSceneView *self, VvgNavTarget target) {
    self->target = target;
    gtk_widget_queue_draw(GTK_WIDGET(self));
}

void
vvg_scene_view_set_cut_plane(VvgSceneView *self, int object, int plane) {
    self->cut_object = object;
    self->cut_plane = plane;
    if (self->marks)
        vvg_marks_set_cut_plane(self->marks, object, plane);
    gtk_widget_queue_draw(GTK_WIDGET(self));
}

void
vvg_scene_view_set_light(VvgSceneView *self, int index) {
    self->light = index;
    gtk_widget_queue_draw(GTK_WIDGET(self));
}

void
vvg_scene_view_set_preview(VvgSceneView *self, int kind) {
    g_mutex_lock(&self->lock);
    self->policy.forced = kind >= 0 && kind < VV_PREVIEW_COUNT ? kind : -1;
    g_mutex_unlock(&self->lock);
}

void
vvg_scene_view_set_refine_delay(VvgSceneView *self, int ms) {
    self->refine_delay_ms = ms < 0 ? 0 : ms > 2000 ? 2000 : ms;
}

void
vvg_scene_view_set_flight(VvgSceneView *self, gboolean on) {
    self->flight = on;
    if (!on)
        self->yaw_rate = self->pitch_rate = self->roll_rate = self->throttle = 0;
}

double
vvg_scene_view_full_ms(VvgSceneView *self) {
    return self->full_ms;
}

char *
vvg_scene_view_cache_status(VvgSceneView *self) {
    if (self->shown_lod_note[0])
        return g_strdup_printf("the proxies in memory: %s", self->shown_lod_note);
    if (self->shown_src.n == 0)
        return g_strdup("");
    /* the sums over the files drawn (two objects of one file: counted once) */
    guint64 chunks = 0, bricks = 0;
    int loading = 0, pyramids = 0, bricked = 0;
    for (int i = 0; i < self->shown_src.n; i++) {
        int seen = 0;
        for (int k = 0; k < i; k++)
            seen |= self->shown_src.s[k] == self->shown_src.s[i];
        if (seen)
            continue;
        vv_source_stats st;
        vv_source_stats_get(self->shown_src.s[i], &st);
        for (int l = 0; l < VV_SOURCE_MAX_LEVELS; l++)
            chunks += st.chunk_reads[l];
        bricks += st.loads;
        loading += st.loading;
        pyramids += st.kind == VV_SOURCE_PYRAMID;
        bricked += st.kind == VV_SOURCE_BRICKS;
    }
    /* the one cache every file shares, and its one budget */
    const vv_cache *cache = vv_source_cache(self->shown_src.s[0]);
    vv_cache_stats cs;
    vv_cache_stats_get(cache ? cache : vv_cache_process(), &cs);
    GString *s = g_string_new(NULL);
    if (self->shown_src.n > 1)
        g_string_append_printf(s, "%d objects ", self->shown_src.n);
    g_string_append_printf(s, "out of core: %" G_GUINT64_FORMAT " %s held (%.1f of %.0f MiB)",
                           cs.entries,
                           pyramids && bricked ? "chunks and bricks"
                           : pyramids          ? "chunks"
                                               : "bricks",
                           (double)cs.held / 1048576.0, (double)cs.limit / 1048576.0);
    if (pyramids)
        g_string_append_printf(s, ", %d loading, %" G_GUINT64_FORMAT " chunks read", loading,
                               chunks);
    if (bricked)
        g_string_append_printf(s, ", %" G_GUINT64_FORMAT " bricks read", bricks);
    /* what it held at most, with the working sets reserved (never over the limit) */
    g_string_append_printf(s, ", at most %.1f MiB", (double)cs.peak / 1048576.0);
    gboolean levels = FALSE;
    for (int l = 0; l < VV_LOD_MAX_LEVELS; l++)
        if (self->shown_nodes[l] > 0) {
            g_string_append_printf(s, "%s %d (%d nodes)", levels ? "" : "; level in use:", l,
                                   self->shown_nodes[l]);
            levels = TRUE;
        }
    if (self->shown_pending > 0)
        g_string_append_printf(s, "; %d nodes still coarser%s", self->shown_pending,
                               self->shown_stalled ? " (more than the memory limit holds)" : "");
    else
        g_string_append(s, "; converged");
    return g_string_free(s, FALSE);
}

const char *
vvg_scene_view_shown(VvgSceneView *self) {
    return self->shown_kind < 0 ? "" : vv_preview_kind_name((vv_preview_kind)self->shown_kind);
}
