/*
 * `mpirun -n N volvis serve ...`: rank 0 is the server; every frame of
 * every session is rendered by all ranks through the parallel module
 * (include/volvis/parallel.h: each rank its brick, composited to rank 0).
 *
 * MPI is initialised for funnelled use, so only rank 0's main thread (the
 * libwebsockets service thread) calls it: a session's render thread posts
 * its frame as a job and waits; the service thread, woken, announces the
 * frame to the other ranks (one broadcast of what the frame needs: the
 * session, its file, the view and the volume object's rendering state, all
 * plain values) and renders it with them. The other ranks keep a World per
 * session, opened from the same file the way rank 0 opened it, and apply
 * the announced state before each frame. While the view moves a frame is
 * the same World through a view of 1/2, 1/4 or 1/8 the size (the
 * Navigator's policy picks, as without MPI); when it stops, the full size.
 * The ranks draw with the World's method (a scene's "render": {"renderer":
 * ...}, such as gpu: each rank on its own device) where it has the region
 * contract, else with the default ray caster.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "serve.h"

/* What every rank needs to draw one frame; plain values only (the same
 * binary on every rank). */
typedef struct mpi_frame {
    int command; /* 1 a frame, 0 stop */
    int quality;
    char renderer[64]; /* rank 0's World's method (vv_world_renderer) */
    unsigned long long session;
    char path[4096];
    vv_view view;
    int has_object;
    vv_render_mode mode;
    double isovalue;
    vv_tf tf;
    vv_segmentation segmentation;
    double threshold;
    double step;
    int shading;
    int visible;
    vv_material material;
} mpi_frame;

struct srv_mpi_job {
    const vv_world *world;
    vv_view view;
    int quality;
    uint64_t session;
    const char *path;
    vv_image *out;
    vv_status status;
    char error[512];
    int done;
    srv_mpi_job *next;
};

static pthread_cond_t job_done = PTHREAD_COND_INITIALIZER;
static srv_mpi_job *jobs, **jobs_tail = &jobs;
static vv_parallel *par;
/* the method par draws with when vv_parallel_new makes its own (NULL) */
#define PAR_DEFAULT "raycast"
static vv_renderer *par_ren;            /* what par draws with (NULL: its own) */
static char par_name[64] = PAR_DEFAULT; /* the method the frames last named */

/* par drawing with the method @p name, the World's (its render settings
 * @p settings applied), made anew when the method changes: every rank
 * does the same for the same frame, so they draw alike. A method without
 * the region contract draws as before, by the default ray caster. Errors:
 * those of making the renderer (par unchanged). */
static vv_status
use_renderer(const char *name, const vv_render_settings *settings) {
    if (!strcmp(name, par_name))
        return VV_OK; /* the frame before's: par as it is, nothing made */
    vv_renderer *ren = NULL;
    vv_status s = VV_OK;
    if (strcmp(name, PAR_DEFAULT) != 0) {
        s = vv_renderer_new(&ren, name);
        if (s == VV_OK && !(vv_renderer_get_info(ren)->caps & VV_RENDERER_REGION)) {
            vv_renderer_free(ren);
            ren = NULL;
        }
    }
    if (s == VV_OK && ren)
        s = vv_renderer_apply_settings(ren, settings);
    vv_parallel *np = NULL;
    if (s == VV_OK)
        s = vv_parallel_new(&np, ren, NULL);
    if (s != VV_OK) {
        vv_renderer_free(ren);
        return s;
    }
    vv_parallel_free(par);
    vv_renderer_free(par_ren);
    par = np;
    par_ren = ren;
    snprintf(par_name, sizeof par_name, "%s", name);
    return VV_OK;
}

vv_status
srv_mpi_render(srv_server *srv, uint64_t session, const char *path, const vv_world *w,
               const vv_view *view, int quality, vv_image *out) {
    srv_mpi_job job;
    memset(&job, 0, sizeof job);
    job.world = w;
    job.view = *view;
    job.quality = quality;
    job.session = session;
    job.path = path;
    job.out = out;
    pthread_mutex_lock(&srv->lock);
    if (srv->stopping) {
        pthread_mutex_unlock(&srv->lock);
        return vv_error_set(VV_ERR_CANCELLED, "the server stops");
    }
    *jobs_tail = &job;
    jobs_tail = &job.next;
    pthread_mutex_unlock(&srv->lock);
    srv_wake(srv);
    pthread_mutex_lock(&srv->lock);
    while (!job.done)
        pthread_cond_wait(&job_done, &srv->lock);
    pthread_mutex_unlock(&srv->lock);
    if (job.status != VV_OK)
        return vv_error_set(job.status, "%s", job.error);
    return VV_OK;
}

/* The frame of @p f on this rank's World @p w (collective). */
static vv_status
render_frame(const mpi_frame *f, vv_world *w, vv_status local, vv_image *out) {
    if (local == VV_OK)
        local = use_renderer(f->renderer, &w->render);
    vv_status s = vv_parallel_agree(local);
    if (s != VV_OK)
        return s;
    w->view = f->view;
    vv_object *o = srv_first_volume(w);
    if (o && f->has_object) {
        o->mode = f->mode;
        o->isovalue = f->isovalue;
        o->tf = f->tf;
        o->segmentation = f->segmentation;
        o->threshold = f->threshold;
        o->step = f->step;
        o->shading = f->shading;
        o->material = f->material;
    }
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.quality = f->quality;
    vv_lod lod;
    vv_lod_init(&lod);
    ro.lod = &lod;
    return vv_parallel_render(par, w, &w->view, &ro, out, NULL);
}

int
srv_mpi_service(srv_server *srv) {
    int n = 0;
    for (;;) {
        pthread_mutex_lock(&srv->lock);
        srv_mpi_job *j = jobs;
        if (j) {
            jobs = j->next;
            if (!jobs)
                jobs_tail = &jobs;
        }
        if (j && srv->stopping) {
            /* the other ranks may be gone: no frame, the thread waiting is released */
            j->status = VV_ERR_CANCELLED;
            snprintf(j->error, sizeof j->error, "the server stops");
            j->done = 1;
            pthread_cond_broadcast(&job_done);
            pthread_mutex_unlock(&srv->lock);
            continue;
        }
        pthread_mutex_unlock(&srv->lock);
        if (!j)
            return n;
        mpi_frame *f = calloc(1, sizeof *f);
        vv_world *w = NULL;
        vv_status s = f ? vv_world_clone(&w, j->world) : VV_ERR_NOMEM;
        if (f) {
            f->command = 1;
            f->quality = j->quality;
            f->session = (unsigned long long)j->session;
            snprintf(f->path, sizeof f->path, "%s", j->path);
            f->view = j->view;
            snprintf(f->renderer, sizeof f->renderer, "%s", vv_world_renderer(j->world));
            const vv_object *o = srv_first_volume(j->world);
            if (o) {
                f->has_object = 1;
                f->mode = o->mode;
                f->isovalue = o->isovalue;
                f->tf = o->tf;
                f->segmentation = o->segmentation;
                f->threshold = o->threshold;
                f->step = o->step;
                f->shading = o->shading;
                f->material = o->material;
            }
            vv_error_clear();
            s = vv_parallel_broadcast(f, sizeof *f);
            if (s == VV_OK)
                s = render_frame(f, w, w ? VV_OK : VV_ERR_NOMEM, j->out);
        }
        pthread_mutex_lock(&srv->lock);
        j->status = s;
        if (s != VV_OK)
            snprintf(j->error, sizeof j->error, "%s", vv_error_message());
        j->done = 1;
        pthread_cond_broadcast(&job_done);
        pthread_mutex_unlock(&srv->lock);
        vv_world_free(w);
        free(f);
        n++;
    }
}

void
srv_mpi_stop(void) {
    mpi_frame *f = calloc(1, sizeof *f);
    if (f) {
        vv_parallel_broadcast(f, sizeof *f); /* command 0 */
        free(f);
    }
    vv_parallel_free(par);
    par = NULL;
    vv_renderer_free(par_ren);
    par_ren = NULL;
}

vv_status
srv_mpi_start(void) {
    vv_error_clear();
    vv_status s = vv_parallel_new(&par, NULL, NULL);
    return vv_parallel_agree(s);
}

/* A World a worker keeps for one session. */
typedef struct worker_world {
    unsigned long long session;
    char path[4096];
    vv_world *w;
    unsigned long long used;
} worker_world;

#define WORKER_WORLDS 8

int
srv_mpi_worker(srv_server *srv) {
    worker_world worlds[WORKER_WORLDS];
    memset(worlds, 0, sizeof worlds);
    unsigned long long tick = 0;
    mpi_frame *f = calloc(1, sizeof *f);
    if (!f)
        return CLI_EXIT_FAIL;
    for (;;) {
        if (vv_parallel_broadcast(f, sizeof *f) != VV_OK || f->command == 0)
            break;
        /* this session's World, opened again when its file changed */
        worker_world *ww = NULL, *lru = &worlds[0];
        for (int i = 0; i < WORKER_WORLDS; i++) {
            if (worlds[i].w && worlds[i].session == f->session) {
                ww = &worlds[i];
                break;
            }
            if (worlds[i].used < lru->used)
                lru = &worlds[i];
        }
        if (!ww) {
            ww = lru;
            vv_world_free(ww->w);
            memset(ww, 0, sizeof *ww);
            ww->session = f->session;
        }
        ww->used = ++tick;
        vv_status local = VV_OK;
        if (!ww->w || strcmp(ww->path, f->path) != 0) {
            char why[1024];
            vv_world_free(ww->w);
            ww->w = NULL;
            snprintf(ww->path, sizeof ww->path, "%s", f->path);
            if (srv_open_world(srv, f->path, &ww->w, NULL, why, sizeof why))
                local = vv_error_set(VV_ERR_IO, "%s", why);
        }
        if (!ww->w) {
            /* agree on the failure: rank 0 reports it */
            vv_parallel_agree(local == VV_OK ? VV_ERR_IO : local);
            continue;
        }
        render_frame(f, ww->w, local, NULL);
    }
    for (int i = 0; i < WORKER_WORLDS; i++)
        vv_world_free(worlds[i].w);
    free(f);
    vv_parallel_free(par);
    par = NULL;
    vv_renderer_free(par_ren);
    par_ren = NULL;
    return CLI_EXIT_OK;
}
