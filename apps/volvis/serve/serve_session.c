/*
 * Sessions of `volvis serve`: one World each (or one for all with
 * --shared), edited by the service thread as messages arrive and drawn by
 * the session's render thread. The render thread draws snapshots
 * (vv_world_clone) through one vv_preview: while the view moves, the
 * reduced ray cast the Navigator's frame-rate policy picks (the GUI's
 * preview policy, include/volvis/navigator.h); when it stops, the full
 * frame of the World's renderer, which is what `volvis render` of the
 * saved session draws. Each finished frame replaces the session's frame
 * slot: a frame not yet sent when a newer one is ready is never sent.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <turbojpeg.h>
#include <unistd.h>

#include "serve.h"

/* Seconds a frame may take while moving so the page gets 20 frames a
 * second, with room for encoding and sending. */
#define SRV_PREVIEW_BUDGET 0.042
/* Input older than this counts as stopped even without a last "moving":
 * false (a client that vanished mid-drag). */
#define SRV_STILL_AFTER 0.5
/* While moving, at most 30 frames a second (as trame adapts between 12 and
 * 30): more would cost bandwidth and the page shows no more on most displays. */
#define SRV_MIN_PERIOD (1.0 / 30)
#define SRV_JPEG_MOVING 60
#define SRV_JPEG_STILL 90
/* Chunks a progressive frame of a file out of core may read, and the steps
 * of a still frame before the converged one. */
#define SRV_PROGRESSIVE_CHUNKS 64
#define SRV_PROGRESSIVE_STEPS 32

struct srv_session {
    srv_server *srv;
    uint64_t id;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    pthread_t thread;
    int thread_started;
    int quit;
    int finished; /* the render thread has ended (atomic) */

    /* the World and what the page shows of it (under lock) */
    vv_world *world;
    vv_view home_view;
    char name[256];
    char file[4096]; /* the file open (a real path) */
    char preset[64];
    double window, level; /* auto window of the first volume */
    uint64_t gen;         /* edits of the World */
    long long input_seq;  /* the last nav.seq applied */
    int moving;
    double last_input;
    int width, height; /* the page's view */

    /* the newest frame (under lock) */
    srv_buf *frame;
    uint64_t frame_seq;

    /* requests to the render thread (under lock) */
    char open_path[4096];
    int open_pending;
    uint64_t open_client;
    int time_pending; /* -1 none */
    uint64_t png_client;
    int thumbs_size;
    uint64_t thumbs_client;
    uint64_t drawn_gen;  /* the newest frame's */
    uint64_t sharp_gen;  /* the newest full frame's */
    uint64_t cancel_gen; /* a frame of a generation below this stops (atomic) */
    double last_preview; /* when the last frame drawn while moving began */

    srv_client *clients;
    int n_clients;

    /* render thread only */
    vv_preview *preview;
    char preview_renderer[32];
    vv_preview_policy policy;
    tjhandle tj;
    uint8_t *pix; /* YUV 4:2:0 planes of the frame being encoded (vv_pixels8) */
    size_t pix_cap;
    const vv_image *pix_of; /* the image the render left in pix (vv_pixels8), or NULL */
    vv_time_steps *ts;
    int time_steps, time;
    vv_image *full; /* the last full frame, of full_gen */
    uint64_t full_gen;

    /* service thread only */
    tjhandle tj_slice;
};

static double
now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---- buffers ------------------------------------------------------------------------- */

srv_buf *
srv_buf_text(const char *text, size_t len) {
    srv_buf *b = calloc(1, sizeof *b);
    if (!b || !(b->data = malloc(SRV_PRE + len + 1))) {
        free(b);
        return NULL;
    }
    memcpy(b->data + SRV_PRE, text, len);
    b->len = len;
    b->refs = 1;
    return b;
}

srv_buf *
srv_buf_binary(const char kind[4], const char *header, const void *payload, size_t n) {
    size_t h = strlen(header);
    srv_buf *b = calloc(1, sizeof *b);
    if (!b || !(b->data = malloc(SRV_PRE + 8 + h + n))) {
        free(b);
        return NULL;
    }
    unsigned char *p = b->data + SRV_PRE;
    memcpy(p, kind, 4);
    p[4] = (unsigned char)(h & 0xff);
    p[5] = (unsigned char)((h >> 8) & 0xff);
    p[6] = (unsigned char)((h >> 16) & 0xff);
    p[7] = (unsigned char)((h >> 24) & 0xff);
    memcpy(p + 8, header, h);
    if (n)
        memcpy(p + 8 + h, payload, n);
    b->len = 8 + h + n;
    b->binary = 1;
    b->refs = 1;
    return b;
}

srv_buf *
srv_buf_ref(srv_buf *b) {
    if (b)
        atomic_fetch_add_explicit((_Atomic int *)&b->refs, 1, memory_order_relaxed);
    return b;
}

void
srv_buf_unref(srv_buf *b) {
    if (b && atomic_fetch_sub_explicit((_Atomic int *)&b->refs, 1, memory_order_acq_rel) == 1) {
        free(b->data);
        free(b);
    }
}

int
srv_jpeg(void *handle, const uint8_t *pixels, int width, int height, int quality, int grey,
         unsigned char **out, unsigned long *size) {
    *out = NULL;
    *size = 0;
    return tjCompress2((tjhandle)handle, pixels, width, 0, height, grey ? TJPF_GRAY : TJPF_RGBX,
                       out, size, grey ? TJSAMP_GRAY : TJSAMP_420, quality, TJFLAG_FASTDCT) == 0
               ? 0
               : -1;
}

int
srv_jpeg_yuv420(void *handle, const uint8_t *yuv, int width, int height, int quality,
                unsigned char **out, unsigned long *size) {
    *out = NULL;
    *size = 0;
    const size_t pw = (size_t)width + (size_t)(width & 1),
                 ph = (size_t)height + (size_t)(height & 1);
    const unsigned char *planes[3] = {yuv, yuv + pw * ph, yuv + pw * ph + (pw / 2) * (ph / 2)};
    return tjCompressFromYUVPlanes((tjhandle)handle, planes, width, NULL, height, TJSAMP_420, out,
                                   size, quality, TJFLAG_FASTDCT) == 0
               ? 0
               : -1;
}

/* ---- replies ---------------------------------------------------------------------------- */

/* Queues @p b (a reference taken) for client @p c; under s->lock. */
static void
queue_to(srv_client *c, srv_buf *b) {
    if (!b)
        return;
    if (c->n_queue == SRV_QUEUE_MAX) {
        c->overflowed = 1;
        if (!c->close_code) {
            c->close_code = 1008;
            snprintf(c->close_reason, sizeof c->close_reason,
                     "more than %d replies waiting: the client does not read", SRV_QUEUE_MAX);
        }
        return;
    }
    c->queue[c->n_queue++] = srv_buf_ref(b);
}

static srv_client *
client_by_id(srv_session *s, uint64_t id) {
    for (srv_client *c = s->clients; c; c = c->next)
        if (c->id == id)
            return c;
    return NULL;
}

/* A JSON reply to one client (id) or to all (0); under s->lock. Steals @p o. */
static void
reply_json(srv_session *s, uint64_t to, json_t *o) {
    char *text = o ? json_dumps(o, JSON_COMPACT) : NULL;
    json_decref(o);
    if (!text)
        return;
    srv_buf *b = srv_buf_text(text, strlen(text));
    free(text);
    for (srv_client *c = s->clients; c; c = c->next)
        if (to == 0 || c->id == to)
            queue_to(c, b);
    srv_buf_unref(b);
}

void
srv_session_send_latest(srv_session *s, srv_client *c, const char *text) {
    srv_buf *b = srv_buf_text(text, strlen(text));
    if (!b)
        return;
    pthread_mutex_lock(&s->lock);
    srv_buf *old = c->latest;
    c->latest = b;
    pthread_mutex_unlock(&s->lock);
    srv_buf_unref(old);
}

static void reply_error(srv_session *s, uint64_t to, const char *fmt, ...) VV_PRINTF(3, 4);

static void
reply_error(srv_session *s, uint64_t to, const char *fmt, ...) {
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    for (char *p = msg; *p; p++)
        if (*p == '\n')
            *p = ';';
    fprintf(stderr, "volvis: serve: %s\n", msg);
    reply_json(s, to, json_pack("{s:s, s:s}", "type", "error", "message", msg));
}

/* ---- the World ------------------------------------------------------------------------- */

vv_object *
srv_first_volume(const vv_world *w) {
    for (int i = 0; w && i < w->n_objects; i++)
        if (w->objects[i]->type == VV_OBJECT_VOLUME && w->objects[i]->volume)
            return w->objects[i];
    return NULL;
}

/* A guess of the voxels' unit: CT in Hounsfield units (as the CT presets take them). */
static const char *
value_unit(const vv_volume *v) {
    return v && v->range[0] <= -200 && v->range[1] >= 200 && vv_voxel_type_size(v->type) >= 2 ? "HU"
                                                                                              : "";
}

static const char *
mode_name(vv_render_mode m) {
    switch (m) {
    case VV_MODE_COMPOSITE:
        return "composite";
    case VV_MODE_MIP:
        return "mip";
    case VV_MODE_ISO:
        return "iso";
    case VV_MODE_MINIP:
        return "minip";
    case VV_MODE_XRAY:
        return "xray";
    case VV_MODE_ATTENUATED_MIP:
        return "attenuated-mip";
    default:
        return "other";
    }
}

/* The plane of slice @p index along @p axis of @p o, sampling @p w x @p h pixels; *count
 * the slices along the axis. 0 or -1. */
static int
slice_plane(const vv_object *o, vv_slice_axis axis, int index, int w, int h, vv_slice_plane *pl,
            int *count) {
    vv_box box = vv_object_world_box(o);
    vv_vec3 c = vv_vec3_scale(vv_vec3_add(box.min, box.max), 0.5);
    if (vv_slice_plane_standard(pl, axis, o->volume->space, c, w, h, 1.0) != VV_OK)
        return -1;
    vv_vec3 n = vv_slice_plane_normal(pl);
    double step = vv_slice_step(o, n);
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 8; k++) {
        vv_vec3 q = vv_vec3_make(k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y,
                                 k & 4 ? box.max.z : box.min.z);
        double d = vv_vec3_dot(q, n);
        lo = fmin(lo, d);
        hi = fmax(hi, d);
    }
    if (!(step > 0) || !isfinite(lo) || !isfinite(hi))
        return -1;
    double nn = floor((hi - lo) / step + 1e-6) + 1;
    *count = nn > 1 << 20 ? 1 << 20 : (int)nn;
    if (index >= *count)
        index = *count - 1;
    double d = lo + index * step;
    pl->center = vv_vec3_add(c, vv_vec3_scale(n, d - vv_vec3_dot(c, n)));
    vv_slice_plane_fit(pl, box, 0.02);
    return 0;
}

/* The slice index along @p axis through world point @p p. */
static int
slice_index_at(const vv_object *o, vv_slice_axis axis, vv_vec3 p) {
    vv_slice_plane pl;
    int count = 0;
    if (slice_plane(o, axis, 0, 16, 16, &pl, &count))
        return 0;
    vv_vec3 n = vv_slice_plane_normal(&pl);
    double step = vv_slice_step(o, n);
    double k = floor((vv_vec3_dot(vv_vec3_sub(p, pl.center), n)) / step + 0.5);
    return k < 0 ? 0 : k >= count ? count - 1 : (int)k;
}

/* "#rrggbb" of a channel's colour. */
static void
channel_color(const vv_channel *ch, char out[8]) {
    vv_vec3 c = vv_vec3_make(1, 1, 1);
    vv_tf_get_contrast(&ch->tf, NULL, NULL, NULL, NULL, &c);
    int r = (int)lround(fmin(1, fmax(0, c.x)) * 255), g = (int)lround(fmin(1, fmax(0, c.y)) * 255),
        b = (int)lround(fmin(1, fmax(0, c.z)) * 255);
    snprintf(out, 8, "#%02x%02x%02x", r, g, b);
}

/* The `state` message; under s->lock. */
static json_t *
state_json(srv_session *s) {
    const vv_world *w = s->world;
    const vv_object *o = srv_first_volume(w);
    const vv_volume *v = o ? o->volume : NULL;
    json_t *presets = json_array();
    for (const char *const *p = vv_tf_preset_names(); *p; p++)
        json_array_append_new(presets, json_string(*p));
    json_t *channels = json_array();
    for (int i = 0; o && i < o->n_channels; i++) {
        char hex[8];
        channel_color(&o->channels[i], hex);
        json_array_append_new(channels, json_pack("{s:s, s:b, s:s}", "name", o->channels[i].name,
                                                  "visible", o->channels[i].visible, "color", hex));
    }
    json_t *st = json_pack("{s:s, s:s, s:i, s:i, s:o, s:s}", "type", "state", "name", s->name,
                           "width", s->width, "height", s->height, "presets", presets, "renderer",
                           w ? vv_world_renderer(w) : "");
    json_object_set_new(st, "mode", json_string(o ? mode_name(o->mode) : "composite"));
    json_object_set_new(st, "isovalue", json_real(o ? o->isovalue : 0));
    json_object_set_new(st, "preset", s->preset[0] ? json_string(s->preset) : json_null());
    json_object_set_new(st, "channels", channels);
    json_object_set_new(st, "time_steps", json_integer(s->time_steps > 0 ? s->time_steps : 1));
    json_object_set_new(st, "time", json_integer(s->time));
    json_object_set_new(st, "shared", json_boolean(s->srv->shared));
    const char *slash = strrchr(s->srv->root, '/');
    json_object_set_new(st, "root", json_string(slash && slash[1] ? slash + 1 : s->srv->root));
    if (v) {
        json_object_set_new(st, "dims", json_pack("[i, i, i]", v->dims[0], v->dims[1], v->dims[2]));
        json_object_set_new(st, "spacing",
                            json_pack("[f, f, f]", v->spacing[0], v->spacing[1], v->spacing[2]));
        json_object_set_new(st, "unit", json_string(vv_volume_length_unit(v)));
        json_object_set_new(st, "value_unit", json_string(value_unit(v)));
        json_object_set_new(st, "range", json_pack("[f, f]", v->range[0], v->range[1]));
        json_object_set_new(st, "window", json_real(s->window));
        json_object_set_new(st, "level", json_real(s->level));
        json_t *sl = json_object();
        static const vv_slice_axis axes[] = {VV_SLICE_AXIAL, VV_SLICE_CORONAL, VV_SLICE_SAGITTAL};
        for (int a = 0; a < 3; a++) {
            vv_slice_plane pl;
            int count = 0;
            if (slice_plane(o, axes[a], 0, 16, 16, &pl, &count))
                count = 0;
            json_object_set_new(sl, vv_slice_axis_name(axes[a]), json_integer(count));
        }
        json_object_set_new(st, "slices", sl);
    } else {
        json_object_set_new(st, "dims", json_null());
    }
    return st;
}

/* ---- opening files (render thread) --------------------------------------------------------- */

int
srv_open_world(const srv_server *srv, const char *path, vv_world **out, vv_world_open_info *info,
               char *why, size_t cap) {
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    if (srv->memory_limit) {
        /* out of core where the file can be (a pyramid by its levels, level of detail
         * by screen-space error), whole where it cannot (a gzip NRRD) */
        o.memory = VV_WORLD_OUT_OF_CORE_IF_ABLE;
        o.memory_limit = srv->memory_limit;
        o.levels = 1;
    }
    o.distributed = vv_parallel_launched(); /* the ranks of `mpirun volvis serve` */
    o.all_channels = 1; /* a file of several channels: all of them, as one object */
    o.slice_window = 1;
    vv_error_clear();
    vv_status st = vv_world_open(out, path, &o, info);
    if (st != VV_OK) {
        const char *m = vv_error_message();
        snprintf(why, cap, "%s", m && *m ? m : "cannot open the file");
        return -1;
    }
    return 0;
}

/* A volume file's time steps into s->ts (more than one), one process only. */
static void
open_time_steps(srv_session *s, const char *path, vv_object *o, const vv_world_open_info *info) {
    s->time_steps = 1;
    s->time = 0;
    if (s->srv->ranks > 1 || !o || o->source || info->input != VV_INPUT_VOLUME || info->n_times < 2)
        return;
    vv_error_clear();
    if (vv_time_steps_open(&s->ts, path, NULL, o) != VV_OK) {
        vv_error_clear();
        return;
    }
    s->time_steps = vv_time_steps_count(s->ts);
}

/* Opens s->open_path for the render thread: called without the lock. */
static void
do_open(srv_session *s, const char *path, uint64_t client) {
    char why[1024];
    vv_world *w = NULL;
    vv_time_steps_free(s->ts);
    s->ts = NULL;
    vv_world_open_info opened;
    /* a scene's files: inside the root, or URLs the server was given */
    if (!srv_is_url(path) &&
        srv_scene_confined(s->srv->root, path, s->srv->urls, s->srv->n_urls, s->srv->prefixes,
                           s->srv->n_prefixes, why, sizeof why)) {
        pthread_mutex_lock(&s->lock);
        reply_error(s, client, "open: %s", why);
        pthread_mutex_unlock(&s->lock);
        srv_wake(s->srv); /* the service thread sends it now, not at its next wake */
        return;
    }
    if (srv_open_world(s->srv, path, &w, &opened, why, sizeof why)) {
        pthread_mutex_lock(&s->lock);
        reply_error(s, client, "%s", why);
        pthread_mutex_unlock(&s->lock);
        srv_wake(s->srv);
        return;
    }
    double win = 1, lev = 0;
    vv_object *o = srv_first_volume(w);
    if (o) {
        win = opened.window;
        lev = opened.level;
    }
    open_time_steps(s, path, o, &opened);
    pthread_mutex_lock(&s->lock);
    vv_world_free(s->world);
    s->world = w;
    if (s->width > 0) {
        w->view.width = s->width;
        w->view.height = s->height;
    } else {
        s->width = w->view.width;
        s->height = w->view.height;
    }
    s->home_view = w->view;
    /* the name: the last component (a URL's, a store's trailing "/" left out) */
    size_t pn = strlen(path);
    while (pn > 1 && path[pn - 1] == '/')
        pn--;
    const char *slash = memrchr(path, '/', pn);
    const char *base = slash ? slash + 1 : path;
    snprintf(s->name, sizeof s->name, "%.*s",
             (int)(pn - (size_t)(base - path)) > 255 ? 255 : (int)(pn - (size_t)(base - path)),
             base);
    snprintf(s->file, sizeof s->file, "%s", path);
    s->preset[0] = '\0';
    s->window = win;
    s->level = lev;
    s->moving = 0;
    s->gen++;
    reply_json(s, 0, state_json(s));
    pthread_mutex_unlock(&s->lock);
    srv_wake(s->srv); /* the state goes out now, not with the first frame's wake */
    vv_image_free(s->full);
    s->full = NULL;
    vv_preview_policy_init(&s->policy);
}

/* ---- drawing (render thread) ---------------------------------------------------------------- */

typedef struct cancel_ctx {
    srv_session *s;
    uint64_t gen;
    int cancellable; /* a full frame stops when the World changes; a preview never */
} cancel_ctx;

static int
cancel_cb(void *user, double fraction) {
    (void)fraction;
    cancel_ctx *c = user;
    if (__atomic_load_n(&c->s->quit, __ATOMIC_RELAXED))
        return 1;
    return c->cancellable && __atomic_load_n(&c->s->cancel_gen, __ATOMIC_RELAXED) > c->gen;
}

/* The preview renderer for World @p w (its renderer and render settings). */
static vv_status
ensure_preview(srv_session *s, const vv_world *w) {
    const char *name = vv_world_renderer(w);
    if (s->preview && strcmp(s->preview_renderer, name) == 0)
        return VV_OK;
    vv_preview_free(s->preview);
    s->preview = NULL;
    vv_status st = vv_preview_new(&s->preview, name);
    if (st == VV_OK)
        st = vv_renderer_apply_settings(vv_preview_final_renderer(s->preview), &w->render);
    if (st != VV_OK) {
        vv_preview_free(s->preview);
        s->preview = NULL;
        return st;
    }
    snprintf(s->preview_renderer, sizeof s->preview_renderer, "%s", name);
    vv_preview_policy_init(&s->policy);
    return VV_OK;
}

/* Room in the render thread's 8-bit buffer for a frame of @p w x @p h
 * pixels in YUV 4:2:0 (grown as needed: no page faults a frame). 0, or -1
 * out of memory. */
static int
pix_room(srv_session *s, int w, int h) {
    size_t need = vv_pixels8_bytes(VV_PIXELS8_YUV420, w, h);
    if (need > s->pix_cap) {
        uint8_t *p = realloc(s->pix, need);
        if (!p)
            return -1;
        s->pix = p;
        s->pix_cap = need;
    }
    return 0;
}

/* @p img as JPEG's YUV 4:2:0 planes (vv_pixels8): what its render left in
 * the buffer (converted by the tiles that drew it), or converted now (an
 * MPI frame; the PNG, which must equal the CLI's, goes through
 * vv_image_write_png). */
static uint8_t *
pixels(srv_session *s, const vv_image *img) {
    if (img == s->pix_of) {
        s->pix_of = NULL; /* once: the address may be another image's later */
        return s->pix;
    }
    if (pix_room(s, img->width, img->height) != 0)
        return NULL;
        /* pairs of rows on every core: the frame was just written by all of
         * them, each holds part of it in its cache */
#pragma omp parallel for schedule(static)
    for (int y = 0; y < img->height; y += 2)
        vv_image_rect_to_yuv420(img, 0, y, img->width, y + 2 < img->height ? y + 2 : img->height,
                                s->pix);
    return s->pix;
}

/*
 * Draws @p w as @p kind into a new image (*out). A World out of core is
 * drawn from what is resident plus at most @p progressive chunks read now
 * (its nodes still drawn coarser than their level in *pending), or with
 * @p progressive 0 converged (every chunk the view wants read), as `volvis
 * render` draws it. A World in memory ignores both.
 */
static vv_status
draw(srv_session *s, const vv_world *w, vv_preview_kind kind, uint64_t gen, int cancellable,
     int progressive, int *pending, vv_image **out) {
    *out = NULL;
    s->pix_of = NULL;
    if (pending)
        *pending = 0;
    vv_status st = ensure_preview(s, w);
    if (st != VV_OK)
        return st;
    int iw, ih;
    vv_preview_size(kind, w->view.width, w->view.height, &iw, &ih);
    vv_image *img = NULL;
    if ((st = vv_image_new(&img, iw, ih)) != VV_OK)
        return st;
    if (s->srv->ranks > 1) {
        /* every rank draws its brick: a reduced frame is the view at the reduced size */
        vv_view view = w->view;
        view.width = iw;
        view.height = ih;
        st = srv_mpi_render(s->srv, s->id, s->file, w, &view,
                            kind == VV_PREVIEW_FULL ? vv_render_settings_quality(&w->render) : 0,
                            img);
        if (st != VV_OK) {
            vv_image_free(img);
            return st;
        }
        *out = img;
        return VV_OK;
    }
    cancel_ctx cc = {s, gen, cancellable};
    vv_render_options ro;
    vv_render_options_init(&ro);
    /* the frame in 8 bits, JPEG's YUV 4:2:0, written by the tiles that drew
     * it (no pass of its own, and no colour pass in the encoder) */
    vv_pixels8 p8 = {.width = iw, .height = ih, .format = VV_PIXELS8_YUV420};
    if (pix_room(s, iw, ih) == 0) {
        p8.yuv = s->pix;
        ro.pixels8 = &p8;
    }
    ro.threads = s->srv->threads;
    ro.quality = vv_render_settings_quality(&w->render);
    ro.progress.fn = cancel_cb;
    ro.progress.user = &cc;
    vv_lod lod;
    vv_lod_init(&lod);
    if (progressive > 0) {
        lod.progressive = 1;
        lod.load_budget = progressive;
    }
    ro.lod = &lod;
    vv_error_clear();
    st = vv_preview_render(s->preview, w, &w->view, kind, &ro, img);
    if (st != VV_OK) {
        vv_image_free(img);
        return st;
    }
    if (pending)
        *pending = lod.pending;
    if (ro.pixels8)
        s->pix_of = img;
    *out = img;
    return VV_OK;
}

/* Encodes @p img as a FRME and makes it the session's newest frame. */
static void
publish(srv_session *s, const vv_image *img, vv_preview_kind kind, int sharp, long long input_seq,
        double render_s) {
    int quality = kind == VV_PREVIEW_FULL ? SRV_JPEG_STILL : SRV_JPEG_MOVING;
    double t0 = now_s();
    const uint8_t *yuv = pixels(s, img);
    if (!yuv)
        return;
    unsigned char *jpeg = NULL;
    unsigned long size = 0;
    int rc = srv_jpeg_yuv420(s->tj, yuv, img->width, img->height, quality, &jpeg, &size);
    double encode_s = now_s() - t0;
    if (rc) {
        tjFree(jpeg);
        return;
    }
    pthread_mutex_lock(&s->lock);
    char header[512];
    snprintf(header, sizeof header,
             "{\"seq\":%llu,\"input_seq\":%lld,\"kind\":\"%s\",\"sharp\":%s,\"width\":%d,"
             "\"height\":%d,\"render_ms\":%.2f,\"encode_ms\":%.2f,\"quality\":%d}",
             (unsigned long long)(s->frame_seq + 1), input_seq, vv_preview_kind_name(kind),
             sharp ? "true" : "false", img->width, img->height, render_s * 1e3, encode_s * 1e3,
             quality);
    srv_buf *b = srv_buf_binary("FRME", header, jpeg, size);
    if (b) {
        srv_buf_unref(s->frame);
        s->frame = b;
        s->frame_seq++;
    }
    pthread_mutex_unlock(&s->lock);
    tjFree(jpeg);
    srv_wake(s->srv);
}

/* PNG bytes of @p img as vv_image_write_png writes them (the CLI's writer,
 * which writes files only: through a private folder under $TMPDIR, removed
 * before returning). 0, or -1 with nothing left behind. */
static int
png_bytes(const vv_image *img, unsigned char **out, size_t *n) {
    const char *tmp = getenv("TMPDIR");
    char dir[4096];
    if ((size_t)snprintf(dir, sizeof dir, "%s/volvis-serve-XXXXXX", tmp && *tmp ? tmp : "/tmp") >=
            sizeof dir ||
        !mkdtemp(dir))
        return -1;
    char path[4096 + 16];
    snprintf(path, sizeof path, "%s/view.png", dir);
    int rc = -1;
    vv_error_clear();
    if (vv_image_write_png(img, path, 1.0, 0) == VV_OK) {
        FILE *f = fopen(path, "rb");
        struct stat st;
        if (f && fstat(fileno(f), &st) == 0 && st.st_size > 0 &&
            (*out = malloc((size_t)st.st_size))) {
            *n = fread(*out, 1, (size_t)st.st_size, f);
            rc = *n == (size_t)st.st_size ? 0 : -1;
            if (rc) {
                free(*out);
                *out = NULL;
            }
        }
        if (f)
            fclose(f);
        unlink(path);
    }
    rmdir(dir);
    return rc;
}

/* One preset's thumbnail of snapshot @p w. */
static void
thumbnail(srv_session *s, const vv_world *base, const char *name, int size, uint64_t client) {
    vv_world *w = NULL;
    if (vv_world_clone(&w, base) != VV_OK)
        return;
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->type == VV_OBJECT_VOLUME && o->volume && o->n_channels == 0) {
            vv_tf_preset(&o->tf, name, o->volume);
            o->segmentation = VV_SEG_TRANSFER_FUNCTION;
            if (o->mode != VV_MODE_COMPOSITE)
                o->mode = VV_MODE_COMPOSITE;
        }
    }
    w->view = s->home_view;
    w->view.width = size;
    w->view.height = size;
    vv_image *img = NULL;
    if (draw(s, w, VV_PREVIEW_FULL, 0, 0, 0, NULL, &img) == VV_OK) {
        const uint8_t *yuv = pixels(s, img);
        unsigned char *jpeg = NULL;
        unsigned long jn = 0;
        if (yuv) {
            if (srv_jpeg_yuv420(s->tj, yuv, img->width, img->height, 85, &jpeg, &jn) == 0) {
                char header[256];
                snprintf(header, sizeof header, "{\"name\":\"%s\",\"width\":%d,\"height\":%d}",
                         name, img->width, img->height);
                srv_buf *b = srv_buf_binary("THMB", header, jpeg, jn);
                pthread_mutex_lock(&s->lock);
                srv_client *c = client_by_id(s, client);
                if (c)
                    queue_to(c, b);
                pthread_mutex_unlock(&s->lock);
                srv_buf_unref(b);
                srv_wake(s->srv);
            }
        }
        tjFree(jpeg);
    }
    vv_image_free(img);
    vv_world_free(w);
}

/* Waits on s->cond (s->lock held) for at most @p seconds. */
static void
wait_for(srv_session *s, double seconds) {
    if (seconds < 0.001)
        seconds = 0.001;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    ts.tv_sec += (time_t)seconds;
    ts.tv_nsec += (long)((seconds - floor(seconds)) * 1e9);
    if (ts.tv_nsec >= 1000000000L) {
        ts.tv_sec++;
        ts.tv_nsec -= 1000000000L;
    }
    pthread_cond_timedwait(&s->cond, &s->lock, &ts);
}

static void *
render_main(void *arg) {
    srv_session *s = arg;
    s->tj = tjInitCompress();
    pthread_mutex_lock(&s->lock);
    while (!s->quit) {
        if (s->open_pending) {
            char path[4096];
            snprintf(path, sizeof path, "%s", s->open_path);
            uint64_t client = s->open_client;
            s->open_pending = 0;
            pthread_mutex_unlock(&s->lock);
            do_open(s, path, client);
            pthread_mutex_lock(&s->lock);
            continue;
        }
        vv_world *w = s->world;
        if (w && s->time_pending >= 0) {
            int t = s->time_pending;
            s->time_pending = -1;
            vv_object *o = srv_first_volume(w);
            if (o && s->time_steps > 1 && t < s->time_steps) {
                vv_error_clear();
                vv_status st = vv_time_steps_show(s->ts, o, t, t + 1 < s->time_steps ? t + 1 : -1);
                if (st == VV_OK) {
                    s->time = t;
                    s->gen++;
                    reply_json(s, 0, state_json(s));
                } else {
                    reply_error(s, 0, "time step %d: %s", t, vv_error_message());
                }
            }
            continue;
        }
        double t = now_s();
        int still = !s->moving || t - s->last_input > SRV_STILL_AFTER;
        vv_preview_kind kind;
        if (w && s->gen != s->drawn_gen && !still && t < s->last_preview + SRV_MIN_PERIOD) {
            wait_for(s, s->last_preview + SRV_MIN_PERIOD - t);
            continue;
        }
        if (w && s->gen != s->drawn_gen && !still) {
            kind = vv_preview_policy_choose(&s->policy, SRV_PREVIEW_BUDGET);
            s->last_preview = t;
        } else if (w && s->gen != s->sharp_gen && still)
            kind = VV_PREVIEW_FULL;
        else
            kind = VV_PREVIEW_COUNT; /* nothing to draw */
        if (kind != VV_PREVIEW_COUNT) {
            uint64_t gen = s->gen;
            long long seq = s->input_seq;
            vv_world *snap = NULL;
            vv_status st = vv_world_clone(&snap, w);
            pthread_mutex_unlock(&s->lock);
            vv_image *img = NULL;
            /* out of core, the still frame comes in progressive steps, each sent, until
             * nothing is pending: the converged frame is the sharp one */
            int steps = kind == VV_PREVIEW_FULL && s->srv->ranks == 1 && st == VV_OK &&
                        cli_world_out_of_core(snap);
            for (int pending = 1, k = 0; st == VV_OK; k++) {
                double t0 = now_s();
                /* after SRV_PROGRESSIVE_STEPS steps (a cache too small for the view
                 * stalls them), the converged frame at once */
                int last = steps && k == SRV_PROGRESSIVE_STEPS;
                st = draw(s, snap, kind, gen, kind == VV_PREVIEW_FULL,
                          kind != VV_PREVIEW_FULL || (steps && !last) ? SRV_PROGRESSIVE_CHUNKS : 0,
                          &pending, &img);
                double secs = now_s() - t0;
                if (st != VV_OK)
                    break;
                if (kind != VV_PREVIEW_FULL && !vv_preview_last_warmup(s->preview))
                    vv_preview_policy_record(&s->policy, kind, secs);
                int sharp = kind == VV_PREVIEW_FULL && (!steps || pending == 0 || last);
                publish(s, img, kind, sharp, seq, secs);
                if (kind != VV_PREVIEW_FULL || sharp)
                    break;
                vv_image_free(img);
                img = NULL;
                if (cancel_cb(&(cancel_ctx){s, gen, 1}, 0))
                    st = VV_ERR_CANCELLED;
            }
            if (st == VV_OK && kind == VV_PREVIEW_FULL) {
                vv_image_free(s->full);
                s->full = img;
                s->full_gen = gen;
                img = NULL;
            } else if (st != VV_OK && st != VV_ERR_CANCELLED) {
                pthread_mutex_lock(&s->lock);
                reply_error(s, 0, "render: %s", vv_error_message());
                pthread_mutex_unlock(&s->lock);
                srv_wake(s->srv);
            }
            vv_image_free(img);
            vv_world_free(snap);
            pthread_mutex_lock(&s->lock);
            if (st == VV_OK || st != VV_ERR_CANCELLED) {
                s->drawn_gen = gen;
                if (kind == VV_PREVIEW_FULL || st != VV_OK)
                    s->sharp_gen = gen;
            }
            continue;
        }
        if (w && s->png_client) {
            uint64_t client = s->png_client;
            s->png_client = 0;
            int fresh = s->full && s->full_gen == s->gen;
            uint64_t gen = s->gen;
            vv_world *snap = NULL;
            vv_status st = fresh ? VV_OK : vv_world_clone(&snap, w);
            pthread_mutex_unlock(&s->lock);
            if (!fresh && st == VV_OK) {
                vv_image *img = NULL;
                st = draw(s, snap, VV_PREVIEW_FULL, gen, 0, 0, NULL, &img);
                if (st == VV_OK) {
                    vv_image_free(s->full);
                    s->full = img;
                    s->full_gen = gen;
                }
            }
            vv_world_free(snap);
            unsigned char *png = NULL;
            size_t n = 0;
            if (st == VV_OK && png_bytes(s->full, &png, &n))
                st = vv_error_set(VV_ERR_IO, "cannot encode the PNG");
            pthread_mutex_lock(&s->lock);
            srv_client *c = client_by_id(s, client);
            if (st != VV_OK) {
                reply_error(s, client, "png: %s", vv_error_message());
            } else if (c) {
                char header[128];
                snprintf(header, sizeof header, "{\"width\":%d,\"height\":%d}", s->full->width,
                         s->full->height);
                srv_buf *b = srv_buf_binary("PNG_", header, png, n);
                queue_to(c, b);
                srv_buf_unref(b);
            }
            free(png);
            srv_wake(s->srv);
            continue;
        }
        if (w && s->thumbs_client) {
            uint64_t client = s->thumbs_client;
            int size = s->thumbs_size;
            s->thumbs_client = 0;
            vv_world *snap = NULL;
            vv_status st = vv_world_clone(&snap, w);
            pthread_mutex_unlock(&s->lock);
            for (const char *const *p = vv_tf_preset_names(); st == VV_OK && *p; p++) {
                thumbnail(s, snap, *p, size, client);
                pthread_mutex_lock(&s->lock);
                int newer = s->gen != s->drawn_gen || s->open_pending || s->quit;
                pthread_mutex_unlock(&s->lock);
                if (newer) /* the view goes first; the rest of the thumbnails later */
                    break;
            }
            vv_world_free(snap);
            pthread_mutex_lock(&s->lock);
            continue;
        }
        if (w && s->moving && s->gen != s->sharp_gen) {
            /* wake when the input is old enough to count as stopped */
            wait_for(s, s->last_input + SRV_STILL_AFTER - t + 0.005);
        } else {
            pthread_cond_wait(&s->cond, &s->lock);
        }
    }
    pthread_mutex_unlock(&s->lock);
    tjDestroy(s->tj);
    free(s->pix);
    __atomic_store_n(&s->finished, 1, __ATOMIC_RELEASE);
    srv_wake(s->srv);
    return NULL;
}

/* ---- sessions -------------------------------------------------------------------------------- */

srv_session *
srv_session_new(srv_server *srv) {
    srv_session *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->srv = srv;
    pthread_mutex_lock(&srv->lock);
    s->id = ++srv->next_session_id;
    pthread_mutex_unlock(&srv->lock);
    s->time_pending = -1;
    s->time_steps = 1;
    s->window = 1;
    pthread_mutex_init(&s->lock, NULL);
    pthread_cond_init(&s->cond, NULL);
    vv_preview_policy_init(&s->policy);
    s->tj_slice = tjInitCompress();
    if (srv->initial[0]) {
        snprintf(s->open_path, sizeof s->open_path, "%s", srv->initial);
        s->open_pending = 1;
    }
    if (!s->tj_slice || pthread_create(&s->thread, NULL, render_main, s) != 0) {
        if (s->tj_slice)
            tjDestroy(s->tj_slice);
        pthread_mutex_destroy(&s->lock);
        pthread_cond_destroy(&s->cond);
        free(s);
        return NULL;
    }
    s->thread_started = 1;
    return s;
}

void
srv_session_free(srv_session *s) {
    if (!s)
        return;
    pthread_mutex_lock(&s->lock);
    __atomic_store_n(&s->quit, 1, __ATOMIC_RELAXED);
    pthread_cond_signal(&s->cond);
    pthread_mutex_unlock(&s->lock);
    /* under MPI the render thread may wait for a frame of all ranks, which this
     * thread (the service thread) runs: run them until it has ended */
    while (s->thread_started && s->srv->ranks > 1 &&
           !__atomic_load_n(&s->finished, __ATOMIC_ACQUIRE)) {
        if (srv_mpi_service(s->srv) == 0)
            usleep(1000);
    }
    if (s->thread_started)
        pthread_join(s->thread, NULL);
    vv_preview_free(s->preview);
    vv_image_free(s->full);
    vv_time_steps_free(s->ts);
    vv_world_free(s->world);
    srv_buf_unref(s->frame);
    tjDestroy(s->tj_slice);
    pthread_mutex_destroy(&s->lock);
    pthread_cond_destroy(&s->cond);
    free(s);
}

void
srv_session_attach(srv_session *s, srv_client *c) {
    pthread_mutex_lock(&s->lock);
    c->session = s;
    c->next = s->clients;
    s->clients = c;
    s->n_clients++;
    pthread_mutex_unlock(&s->lock);
}

int
srv_session_detach(srv_session *s, srv_client *c) {
    pthread_mutex_lock(&s->lock);
    for (srv_client **p = &s->clients; *p; p = &(*p)->next)
        if (*p == c) {
            *p = c->next;
            s->n_clients--;
            break;
        }
    for (int i = 0; i < c->n_queue; i++)
        srv_buf_unref(c->queue[i]);
    c->n_queue = 0;
    srv_buf_unref(c->latest);
    c->latest = NULL;
    int left = s->n_clients;
    pthread_mutex_unlock(&s->lock);
    return left;
}

srv_buf *
srv_session_next_out(srv_session *s, srv_client *c) {
    srv_buf *b = NULL;
    pthread_mutex_lock(&s->lock);
    if (c->n_queue > 0) {
        b = c->queue[0];
        memmove(c->queue, c->queue + 1, (size_t)(c->n_queue - 1) * sizeof c->queue[0]);
        c->n_queue--;
    } else if (c->latest) {
        b = c->latest;
        c->latest = NULL;
    } else if (s->frame && s->frame_seq > c->sent_frame) {
        b = srv_buf_ref(s->frame);
        c->sent_frame = s->frame_seq;
    }
    pthread_mutex_unlock(&s->lock);
    return b;
}

int
srv_session_close_code(srv_session *s, srv_client *c, char *reason, size_t cap) {
    pthread_mutex_lock(&s->lock);
    int code = c->close_code;
    if (code)
        snprintf(reason, cap, "%s", c->close_reason);
    pthread_mutex_unlock(&s->lock);
    return code;
}

int
srv_session_has_out(srv_session *s, srv_client *c) {
    pthread_mutex_lock(&s->lock);
    int r =
        c->n_queue > 0 || c->latest || (s->frame && s->frame_seq > c->sent_frame) || c->close_code;
    pthread_mutex_unlock(&s->lock);
    return r;
}

/* A new state of the World to draw: a newer generation (under lock). */
static void
changed(srv_session *s) {
    s->gen++;
    __atomic_store_n(&s->cancel_gen, s->gen, __ATOMIC_RELAXED);
    pthread_cond_signal(&s->cond);
}

/* The slice image of @p m for client @p c (service thread, under lock). */
static void
send_slice(srv_session *s, srv_client *c, const srv_msg *m) {
    const vv_object *o = srv_first_volume(s->world);
    if (!o) {
        reply_error(s, c->id, "slice: no volume is open");
        return;
    }
    vv_slice_plane pl;
    int count = 0;
    if (slice_plane(o, m->axis, m->index, m->width, m->height, &pl, &count)) {
        reply_error(s, c->id, "slice: the volume has no %s slices", vv_slice_axis_name(m->axis));
        return;
    }
    double win = m->has_window ? m->window : s->window;
    double lev = m->has_window ? m->level : s->level;
    size_t n = (size_t)pl.width * pl.height;
    int channels = o->n_channels > 1 ? o->n_channels : 1;
    float *values = malloc((size_t)channels * n * sizeof *values);
    uint8_t *rgba = malloc(n * 4);
    uint8_t *pix = malloc(n);
    vv_status st = values && rgba && pix ? VV_OK : VV_ERR_NOMEM;
    if (st == VV_OK && channels > 1) {
        const float *per[VV_MAX_CHANNELS];
        for (int k = 0; k < channels && st == VV_OK; k++) {
            st = vv_slice_sample_channel(o, k, &pl, values + (size_t)k * n);
            per[k] = values + (size_t)k * n;
        }
        if (st == VV_OK)
            vv_slice_blend_channels(o, per, n, vv_vec3_make(0, 0, 0), rgba);
    } else if (st == VV_OK) {
        st = vv_slice_sample(o, &pl, values);
        if (st == VV_OK)
            vv_slice_window_level(values, n, win, lev, vv_vec3_make(0, 0, 0), rgba);
    }
    unsigned char *jpeg = NULL;
    unsigned long jn = 0;
    int grey = channels == 1;
    if (st == VV_OK) {
        for (size_t i = 0; grey && i < n; i++)
            pix[i] = rgba[4 * i];
        if (srv_jpeg(s->tj_slice, grey ? pix : rgba, pl.width, pl.height, SRV_JPEG_STILL, grey,
                     &jpeg, &jn))
            st = VV_ERR_IO;
    }
    if (st == VV_OK) {
        char header[512];
        snprintf(header, sizeof header,
                 "{\"axis\":\"%s\",\"index\":%d,\"count\":%d,\"width\":%d,\"height\":%d,"
                 "\"window\":%.9g,\"level\":%.9g,\"edges\":[\"%s\",\"%s\",\"%s\",\"%s\"]}",
                 vv_slice_axis_name(m->axis), m->index < count ? m->index : count - 1, count,
                 pl.width, pl.height, win, lev, pl.edge[0], pl.edge[1], pl.edge[2], pl.edge[3]);
        srv_buf *b = srv_buf_binary("SLCE", header, jpeg, jn);
        queue_to(c, b);
        srv_buf_unref(b);
    } else {
        reply_error(s, c->id, "slice: %s",
                    st == VV_ERR_NOMEM ? "out of memory" : vv_error_message());
    }
    tjFree(jpeg);
    free(values);
    free(rgba);
    free(pix);
}

static void
send_probe(srv_session *s, srv_client *c, const srv_msg *m) {
    const vv_object *o = srv_first_volume(s->world);
    vv_slice_plane pl;
    int count = 0;
    if (!o || slice_plane(o, m->axis, m->index, m->width, m->height, &pl, &count)) {
        reply_error(s, c->id, "probe: no volume is open");
        return;
    }
    vv_vec3 p = vv_slice_plane_to_world(&pl, m->x, m->y);
    double ijk[3];
    double v = vv_slice_probe(o, p, ijk);
    json_t *r = json_pack("{s:s, s:s, s:f, s:f, s:s, s:[f, f, f], s:[f, f, f], s:s}", "type",
                          "probe", "axis", vv_slice_axis_name(m->axis), "x", m->x, "y", m->y,
                          "value_unit", value_unit(o->volume), "ijk", ijk[0], ijk[1], ijk[2],
                          "world", p.x, p.y, p.z, "unit", vv_volume_length_unit(o->volume));
    json_object_set_new(r, "value", isnan(v) ? json_null() : json_real(v));
    json_t *idx = json_object();
    static const vv_slice_axis axes[] = {VV_SLICE_AXIAL, VV_SLICE_CORONAL, VV_SLICE_SAGITTAL};
    for (int a = 0; a < 3; a++)
        json_object_set_new(idx, vv_slice_axis_name(axes[a]),
                            json_integer(slice_index_at(o, axes[a], p)));
    json_object_set_new(r, "indices", idx);
    reply_json(s, c->id, r);
}

static int
entry_cmp(const void *a, const void *b) {
    json_t *x = *(json_t *const *)a, *y = *(json_t *const *)b;
    int dx = json_is_true(json_object_get(x, "dir")), dy = json_is_true(json_object_get(y, "dir"));
    if (dx != dy)
        return dy - dx;
    return strcmp(json_string_value(json_object_get(x, "name")),
                  json_string_value(json_object_get(y, "name")));
}

/* The listing of a folder under the root (at most 10000 entries; hidden ones left out). */
static void
send_listing(srv_session *s, srv_client *c, const srv_msg *m) {
    char full[4096], why[512];
    if (srv_path_resolve(s->srv->root, m->path, 1, full, sizeof full, why, sizeof why)) {
        reply_error(s, c->id, "list: %s", why);
        return;
    }
    /* the folder opened beneath the root (a link swapped in since the check cannot lead
     * out), its entries looked at through it */
    char rel[SRV_PATH_MAX];
    snprintf(rel, sizeof rel, "%s", m->path);
    for (size_t n = strlen(rel); n > 0 && rel[n - 1] == '/';)
        rel[--n] = '\0';
    int rootfd = open(s->srv->root, O_PATH | O_DIRECTORY | O_CLOEXEC);
    int dfd = rootfd < 0 ? -1 : srv_open_beneath(rootfd, rel, O_RDONLY | O_DIRECTORY);
    int err = errno;
    if (rootfd >= 0)
        close(rootfd);
    DIR *d = dfd < 0 ? NULL : fdopendir(dfd);
    if (!d) {
        if (dfd >= 0)
            close(dfd);
        reply_error(s, c->id, "list: '%s': %s", m->path,
                    err == EXDEV || err == ELOOP ? "leaves the root folder" : strerror(err));
        return;
    }
    enum { MAX_ENTRIES = 10000 };
    json_t **items = malloc(MAX_ENTRIES * sizeof *items);
    int n = 0;
    struct dirent *e;
    while (items && n < MAX_ENTRIES && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        struct stat st;
        /* a link is shown as what it leads to, and only when that is inside the root */
        int efd = srv_open_beneath(dirfd(d), e->d_name, O_PATH);
        int ok = efd >= 0 && fstat(efd, &st) == 0;
        if (efd >= 0)
            close(efd);
        if (!ok)
            continue;
        if (!S_ISDIR(st.st_mode) && !S_ISREG(st.st_mode))
            continue;
        char sub[PATH_MAX + 300];
        snprintf(sub, sizeof sub, "%s/%s", full, e->d_name);
        int store = S_ISDIR(st.st_mode) && srv_folder_is_store(sub);
        json_t *it = json_pack("{s:s, s:b, s:I, s:b}", "name", e->d_name, "dir",
                               S_ISDIR(st.st_mode) && !store, "size", (json_int_t)st.st_size,
                               "store", store);
        if (it)
            items[n++] = it;
    }
    closedir(d);
    if (items)
        qsort(items, (size_t)n, sizeof *items, entry_cmp);
    json_t *arr = json_array();
    for (int i = 0; i < n; i++)
        json_array_append_new(arr, items[i]);
    free(items);
    json_t *r = json_pack("{s:s, s:s, s:o}", "type", "listing", "path", m->path, "entries", arr);
    if (r && !rel[0]) {
        /* the top of the root: the URLs this server may open, and the prefixes */
        json_t *remote = json_array();
        for (int i = 0; i < s->srv->n_urls; i++)
            json_array_append_new(remote,
                                  json_pack("{s:s, s:b}", "url", s->srv->urls[i], "prefix", 0));
        for (int i = 0; i < s->srv->n_prefixes; i++)
            json_array_append_new(remote,
                                  json_pack("{s:s, s:b}", "url", s->srv->prefixes[i], "prefix", 1));
        json_object_set_new(r, "remote", remote);
    }
    reply_json(s, c->id, r);
}

static void
save_session(srv_session *s, srv_client *c, const srv_msg *m) {
    char full[4096], why[512];
    if (!s->world) {
        reply_error(s, c->id, "save: nothing is open");
        return;
    }
    if (srv_path_resolve(s->srv->root, m->path, 2, full, sizeof full, why, sizeof why)) {
        reply_error(s, c->id, "save: %s", why);
        return;
    }
    /* a volume file's objects refer to it (by its real path); a scene's objects to theirs */
    int n = s->world->n_objects;
    const char **files = calloc((size_t)(n > 0 ? n : 1), sizeof *files);
    if (!files) {
        reply_error(s, c->id, "save: out of memory");
        return;
    }
    for (int i = 0; i < n; i++) {
        const vv_object *o = s->world->objects[i];
        if (o->type == VV_OBJECT_VOLUME && !o->geometry.source)
            files[i] = s->file;
    }
    /* written through its folder opened beneath the root (/proc/self/fd/N/NAME: the
     * temporary file and the rename go where the check looked, whatever link is swapped
     * in since) */
    char rel[SRV_PATH_MAX];
    snprintf(rel, sizeof rel, "%s", m->path);
    char *slash = strrchr(rel, '/');
    const char *base = slash ? slash + 1 : rel;
    if (slash)
        *slash = '\0';
    int rootfd = open(s->srv->root, O_PATH | O_DIRECTORY | O_CLOEXEC);
    int dfd = rootfd < 0 ? -1 : srv_open_beneath(rootfd, slash ? rel : "", O_PATH | O_DIRECTORY);
    if (rootfd >= 0)
        close(rootfd);
    char pinned[64 + SRV_PATH_MAX];
    if (dfd < 0) {
        free(files);
        reply_error(s, c->id, "save: '%s' leaves the root folder", m->path);
        return;
    }
    snprintf(pinned, sizeof pinned, "/proc/self/fd/%d/%s", dfd, base);
    vv_error_clear();
    vv_status st = vv_scene_save(s->world, pinned, files);
    close(dfd);
    free(files);
    if (st != VV_OK) {
        reply_error(s, c->id, "save: %s: %s", m->path, vv_error_message());
        return;
    }
    fprintf(stderr, "volvis: serve: saved %s\n", full);
    reply_json(s, c->id, json_pack("{s:s, s:s}", "type", "saved", "path", m->path));
}

int
srv_session_handle(srv_session *s, srv_client *c, const srv_msg *m) {
    pthread_mutex_lock(&s->lock);
    vv_world *w = s->world;
    switch (m->type) {
    case SRV_HELLO:
    case SRV_RESIZE:
        s->width = m->width;
        s->height = m->height;
        if (w) {
            w->view.width = m->width;
            w->view.height = m->height;
            changed(s);
        }
        if (m->type == SRV_HELLO) {
            /* nothing open (a folder served): the state still names the root and presets */
            reply_json(s, c->id, state_json(s));
            c->sent_frame = 0; /* the newest frame, even an older one, at once */
        }
        break;
    case SRV_NAV: {
        if (!w)
            break;
        vv_nav_target target = {VV_NAV_TARGET_VIEW, 0, 0};
        vv_nav_motion motion;
        memset(&motion, 0, sizeof motion);
        motion.kind = (vv_nav_motion_kind)m->motion;
        motion.dx = m->dx;
        motion.dy = m->dy;
        motion.factor = m->factor;
        if ((m->dx != 0 || m->dy != 0 || (m->motion == VV_NAV_ZOOM && m->factor != 1)) &&
            vv_nav_apply(w, &target, &motion) == VV_OK)
            changed(s);
        else if (!m->moving && s->moving)
            pthread_cond_signal(&s->cond); /* the end of a drag: sharpen */
        s->input_seq = m->seq;
        s->moving = m->moving;
        s->last_input = now_s();
        break;
    }
    case SRV_RESET_VIEW:
        if (w) {
            int wd = w->view.width, ht = w->view.height;
            w->view = s->home_view;
            w->view.width = wd;
            w->view.height = ht;
            s->moving = 0;
            changed(s);
        }
        break;
    case SRV_MODE:
        for (int i = 0; w && i < w->n_objects; i++) {
            vv_object *o = w->objects[i];
            if (o->type != VV_OBJECT_VOLUME)
                continue;
            o->mode = m->mode;
            if (m->has_isovalue)
                o->isovalue = m->isovalue;
        }
        if (w) {
            s->moving = 0;
            changed(s);
            reply_json(s, 0, state_json(s));
        }
        break;
    case SRV_PRESET: {
        int done = 0;
        for (int i = 0; w && i < w->n_objects; i++) {
            vv_object *o = w->objects[i];
            if (o->type != VV_OBJECT_VOLUME || !o->volume || o->n_channels > 1)
                continue;
            vv_error_clear();
            if (vv_tf_preset(&o->tf, m->name, o->volume) != VV_OK) {
                reply_error(s, c->id, "preset %s: %s", m->name, vv_error_message());
                continue;
            }
            o->segmentation = VV_SEG_TRANSFER_FUNCTION;
            done++;
        }
        if (done) {
            snprintf(s->preset, sizeof s->preset, "%s", m->name);
            s->moving = 0;
            changed(s);
            reply_json(s, 0, state_json(s));
        }
        break;
    }
    case SRV_CHANNEL: {
        vv_object *o = srv_first_volume(w);
        if (!o || m->index >= o->n_channels) {
            reply_error(s, c->id, "channel %d: the object has no such channel", m->index);
            break;
        }
        vv_channel *ch = &o->channels[m->index];
        if (m->has_visible)
            ch->visible = m->visible;
        if (m->has_color) {
            double lo, hi, gamma, op;
            vv_tf_get_contrast(&ch->tf, &lo, &hi, &gamma, &op, NULL);
            vv_tf_set_contrast(&ch->tf, lo, hi, gamma, op, m->color, ch->tf.opacity_unit_distance);
        }
        s->moving = 0;
        changed(s);
        reply_json(s, 0, state_json(s));
        break;
    }
    case SRV_TIME:
        if (m->index >= s->time_steps) {
            reply_error(s, c->id, "time step %d: the data has %d", m->index, s->time_steps);
            break;
        }
        s->time_pending = m->index;
        s->moving = 0;
        pthread_cond_signal(&s->cond);
        break;
    case SRV_SLICE:
        send_slice(s, c, m);
        break;
    case SRV_PROBE:
        send_probe(s, c, m);
        break;
    case SRV_PNG:
        s->png_client = c->id;
        pthread_cond_signal(&s->cond);
        break;
    case SRV_THUMBNAILS:
        s->thumbs_client = c->id;
        s->thumbs_size = m->size;
        pthread_cond_signal(&s->cond);
        break;
    case SRV_LIST:
        send_listing(s, c, m);
        break;
    case SRV_OPEN: {
        char full[4096], why[512];
        if (m->url[0]) {
            /* a URL: only one given on the command line or under --allow-url; the
             * normal form is what the door is handed, so what was checked is fetched */
            if (srv_url_normalize(m->url, full, sizeof full, why, sizeof why)) {
                reply_error(s, c->id, "open: %s", why);
                break;
            }
            if (!srv_url_allowed(full, s->srv->urls, s->srv->n_urls, s->srv->prefixes,
                                 s->srv->n_prefixes)) {
                reply_error(s, c->id,
                            "open: '%.300s' is not a URL this server was given (volvis serve "
                            "URL, or --allow-url PREFIX)",
                            full);
                break;
            }
        } else if (srv_path_resolve(s->srv->root, m->path, 0, full, sizeof full, why, sizeof why)) {
            reply_error(s, c->id, "open: %s", why);
            break;
        }
        snprintf(s->open_path, sizeof s->open_path, "%s", full);
        s->open_pending = 1;
        s->open_client = c->id;
        __atomic_store_n(&s->cancel_gen, s->gen + 1, __ATOMIC_RELAXED);
        pthread_cond_signal(&s->cond);
        break;
    }
    case SRV_SAVE:
        save_session(s, c, m);
        break;
    }
    pthread_mutex_unlock(&s->lock);
    return 0;
}
