/*
 * The scene view's render thread (internal to VvgSceneView,
 * vvg-scene-render.h): the requests the UI thread posts (a snapshot of the
 * World and the representations to draw in turn), the worker that draws them
 * (previews, the refinement, the reduced surfaces warmed off screen, a frame
 * out of core sharpened as the pyramids' chunks arrive), and the hand-off of
 * finished frames to the UI thread, which shows the newest and drops the
 * stale. The widget, its drawing and its input are vvg-scene-view.c.
 */
#define _GNU_SOURCE /* syscall(SYS_gettid) for the render thread's priority */
#include "vvg-scene-render.h"

#include <limits.h>
#include <string.h>
#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

/* ThreadSanitizer builds (VOLVIS_TSAN, scripts/tsan.sh) count the frames
 * for the report and can inject a race; other builds have neither. */
#ifdef VVG_TSAN
#define TSAN_COUNT(counter) (self->tsan_##counter++)
#else
#define TSAN_COUNT(counter) ((void)0)
#endif

/* ---- the worker --------------------------------------------------------- */

void
vvg_source_set_clear(VvgSourceSet *s) {
    for (int i = 0; i < s->n; i++)
        vv_source_free(s->s[i]);
    s->n = 0;
}

/* @p dst (empty) holding its own references to @p src's sources. */
static void
src_set_ref(VvgSourceSet *dst, const VvgSourceSet *src) {
    for (int i = 0; i < src->n; i++)
        dst->s[i] = vv_source_ref(src->s[i]);
    dst->n = src->n;
}

/* One request: a snapshot and the representations to draw in turn. */
struct VvgSceneJob {
    guint64 gen;
    vv_world *world;
    int n_kinds;
    vv_preview_kind kinds[3];
    gboolean refine; /* cancelled by any newer state */
    gint64 posted_us;
    VvgSourceSet src; /* the visible objects' files out of core (none: all in memory) */
};

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
    VvgSourceSet src;
    int nodes[VV_LOD_MAX_LEVELS], pending, stalled;
    char lod_note[128]; /* why the files were not drawn out of core ("" when they were) */
    char
        gpu_note[256]; /* why the gpu renderer did not draw it ("" when it did, or was not asked) */
} frame;

static void
job_free(VvgSceneJob *j) {
    if (!j)
        return;
    vv_world_free(j->world);
    vvg_source_set_clear(&j->src);
    g_free(j);
}

static void
frame_free(frame *f) {
    g_object_unref(f->view);
    if (f->pixels)
        g_bytes_unref(f->pixels);
    g_free(f->depth);
    vvg_source_set_clear(&f->src);
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

/* The job's World with its objects out of core drawn from their files
 * (vv_renderer_render chooses: a pyramid by level of detail, a bricked file
 * brick by brick, the others from memory, each a layer), at the kind's
 * image size with the World's renderer (its settings applied): a
 * progressive frame from what the cache holds, asking the pyramids'
 * loaders for the rest (converged 0), or the converged frame, which reads
 * what it needs (1). Where the renderer has no region method or the World
 * is not one that layers draw (overlapping composite objects, geometry,
 * several objects by the ray tracer), the renderer draws the proxies in
 * memory (vv_render_options.proxy_fallback) and f->lod_note says why. */
static vv_status
render_out_of_core(VvgSceneView *self, const VvgSceneJob *j, frame *f, int converged,
                   vv_render_options *ro, vv_image *img) {
    const vv_world *w = j->world;
    vv_renderer *r = vv_preview_final_renderer(self->preview);
    vv_status s = vv_renderer_apply_settings(r, &w->render);
    if (s != VV_OK)
        return s;
    vv_view v = w->view;
    v.width = img->width;
    v.height = img->height;
    vv_lod lod;
    vv_lod_init(&lod);
    lod.progressive = !converged;
    lod.background = 1;
    lod.load_budget = 0;
    ro->lod = &lod;
    ro->proxy_fallback = 1; /* the renderer draws the proxies where it cannot by regions */
    s = vv_renderer_render(r, w, &v, ro, img);
    ro->lod = NULL;
    g_strlcpy(f->lod_note, lod.note, sizeof f->lod_note);
    if (s == VV_OK) {
        memcpy(f->nodes, lod.nodes, sizeof f->nodes);
        f->pending = lod.pending;
        f->stalled = lod.stalled;
        src_set_ref(&f->src, &j->src);
    }
    return s;
}

/* Draws one representation of a job (a pyramid's converged frame when
 * @p converged); NULL when cancelled. */
static frame *
render_one(VvgSceneView *self, const VvgSceneJob *j, vv_preview_kind kind, int converged) {
    frame *f = g_new0(frame, 1);
    f->view = g_object_ref(self);
    f->gen = j->gen;
    f->kind = kind;
    f->refine = j->refine;
    f->posted_us = j->posted_us;
    const vv_world *w = j->world;
    const char *rname = vv_world_renderer(w);
    /* the gpu renderer failed in this view (no device, a device that
     * failed): the CPU ray caster draws instead, and the status says so */
    if (!strcmp(rname, "gpu") && self->gpu_failed[0])
        rname = "raycast";
    g_strlcpy(f->gpu_note, self->gpu_failed, sizeof f->gpu_note);
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
    if (s == VV_OK && j->src.n > 0) {
        s = render_out_of_core(self, j, f, converged, &ro, img);
        drawn = s == VV_OK || s == VV_ERR_CANCELLED;
    }
    if (s == VV_OK && !drawn)
        s = vv_preview_render(self->preview, w, &w->view, kind, &ro, img);
    gint64 t1 = g_get_monotonic_time();
    f->rendered_us = t1;
    double secs = (t1 - t0) * 1e-6;
    if (s == VV_ERR_CANCELLED) {
        vv_image_free(img);
        frame_free(f);
        return NULL;
    }
    f->render_ms = secs * 1e3;
    if (s != VV_OK && !strcmp(rname, "gpu") && !self->gpu_failed[0]) {
        /* once: from now on the frame is the CPU ray caster's */
        g_strlcpy(self->gpu_failed, vv_error_message(), sizeof self->gpu_failed);
        g_message("the gpu renderer failed (%s): the CPU ray caster draws instead",
                  self->gpu_failed);
        vv_image_free(img);
        frame_free(f);
        return render_one(self, j, kind, converged);
    }
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
                         cast <= VVG_PREVIEW_BUDGET || !self->policy.allowed[kinds[i]];
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
        VvgSceneJob j = {0};
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
sharpen_out_of_core(VvgSceneView *self, const VvgSceneJob *j) {
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
        VvgSceneJob *j = self->pending;
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
post_job(VvgSceneView *self, VvgSceneJob *j) {
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

/* ---- UI side: frames shown, requests posted ------------------------------ */

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
    vvg_source_set_clear(&self->shown_src);
    self->shown_src = f->src;
    f->src.n = 0;
    memcpy(self->shown_nodes, f->nodes, sizeof self->shown_nodes);
    self->shown_pending = f->pending;
    self->shown_stalled = f->stalled;
    g_strlcpy(self->shown_lod_note, f->lod_note, sizeof self->shown_lod_note);
    g_strlcpy(self->shown_gpu_note, f->gpu_note, sizeof self->shown_gpu_note);
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

static VvgSceneJob *
new_job(VvgSceneView *self, gboolean refine) {
    vv_world *w = vvg_document_snapshot(self->doc);
    if (!w)
        return NULL;
    VvgSceneJob *j = g_new0(VvgSceneJob, 1);
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

void
vvg_scene_render_post(VvgSceneView *self, gboolean refine, const vv_preview_kind *kinds,
                      int n_kinds) {
    VvgSceneJob *j = new_job(self, refine);
    if (!j)
        return;
    for (int k = 0; k < n_kinds && j->n_kinds < (int)G_N_ELEMENTS(j->kinds); k++)
        j->kinds[j->n_kinds++] = kinds[k];
    post_job(self, j);
}

/* ---- life cycle ---------------------------------------------------------- */

void
vvg_scene_render_start(VvgSceneView *self) {
    self->thread = g_thread_new("volvis-render", worker_main, self);
}

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
