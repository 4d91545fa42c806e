/*
 * The time steps of a file, read step by step into a cache bounded by bytes,
 * with one background thread that reads the next step ahead (the volume
 * source of a time series: DESIGN.md, "Volume sources").
 */
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/internal.h"
#include "volvis/io.h"

enum { STEP_EMPTY, STEP_READING, STEP_READY, STEP_FAILED };

typedef struct step {
    int state;
    vv_volume *volume; /* STEP_READY: the cache's reference */
    uint64_t last_use; /* the use clock at the last ask */
    vv_status status;  /* STEP_FAILED */
    char *message;     /* STEP_FAILED: the read's error trace */
} step;

struct vv_time_series {
    char *path;
    vv_load_options opt;
    vv_load_info info;
    int n;
    int dims[3];
    vv_voxel_type type;
    uint64_t step_bytes, cache_bytes;
    step *steps;
    pthread_mutex_t lock;
    pthread_cond_t changed; /* a step's state changed, or a prefetch was asked */
    uint64_t clock;
    int reads;
    int pending; /* the step the thread reads next, -1: none */
    int quit;
    int has_thread;
    pthread_t thread;
    /* raw layout (vv_load_info.has_raw_layout): steps read by offset */
    int raw_fd;        /* -1: every step through vv_volume_load */
    uint64_t raw_base; /* offset of this channel's step 0 */
    vv_volume *step0;  /* geometry of every step (a reference) */
    vv_volume *spare;  /* an evicted step's volume nobody else holds, for the next read */
};

/* Drops the least recently used ready steps until the cache holds at most
 * cache_bytes, keeping @p keep. Under the lock. */
static void
evict(vv_time_series *ts, int keep) {
    for (;;) {
        uint64_t held = 0;
        int oldest = -1;
        for (int t = 0; t < ts->n; t++) {
            if (ts->steps[t].state != STEP_READY)
                continue;
            held += ts->step_bytes;
            if (t != keep && (oldest < 0 || ts->steps[t].last_use < ts->steps[oldest].last_use))
                oldest = t;
        }
        if (held <= ts->cache_bytes || oldest < 0)
            return;
        vv_volume *v = ts->steps[oldest].volume;
        /* held by the cache alone (no reference handed out is left): its
         * memory, already paged in, takes the next step read by offset */
        int refs = atomic_load_explicit((_Atomic int *)&v->refcount, memory_order_acquire);
        if (ts->raw_fd >= 0 && !ts->spare && refs == 1 && !v->release)
            ts->spare = v;
        else
            vv_volume_free(v);
        ts->steps[oldest].volume = NULL;
        ts->steps[oldest].state = STEP_EMPTY;
    }
}

/* Step @p t by offset (the raw layout): pread into the spare volume when
 * there is one, else a new one; step 0's geometry. */
static vv_status
read_raw_step(vv_time_series *ts, int t, vv_volume **out) {
    vv_volume *v = NULL;
    pthread_mutex_lock(&ts->lock);
    v = ts->spare;
    ts->spare = NULL;
    pthread_mutex_unlock(&ts->lock);
    vv_status s = v ? VV_OK : vv_volume_new(&v, ts->dims, ts->type);
    if (s != VV_OK)
        return vv_error_prefix(s, "time series: %s: time step %d", vv_path_basename(ts->path), t);
    uint64_t off = ts->raw_base + (uint64_t)t * ts->info.raw_step_bytes;
    unsigned char *p = v->data;
    for (uint64_t done = 0; done < ts->step_bytes;) {
        size_t want = ts->step_bytes - done > ((size_t)1 << 30) ? (size_t)1 << 30
                                                                : (size_t)(ts->step_bytes - done);
        ssize_t got = pread(ts->raw_fd, p + done, want, (off_t)(off + done));
        if (got <= 0) {
            int e = errno;
            vv_volume_free(v);
            return vv_error_set(
                got < 0 ? VV_ERR_IO : VV_ERR_FORMAT,
                "time series: %s: time step %d: %s at byte %llu", vv_path_basename(ts->path), t,
                got < 0 ? strerror(e) : "the file ends", (unsigned long long)(off + done));
        }
        done += (uint64_t)got;
    }
    size_t vs = vv_voxel_type_size(ts->type);
    if (vs > 1 && (ts->info.raw_big_endian ? 1 : 0) == vv_host_is_little_endian())
        vv_byteswap(p, ts->step_bytes / vs, vs);
    const vv_volume *g = ts->step0;
    memcpy(v->spacing, g->spacing, sizeof v->spacing);
    memcpy(v->origin, g->origin, sizeof v->origin);
    memcpy(v->direction, g->direction, sizeof v->direction);
    v->unit = g->unit;
    v->data_origin = g->data_origin;
    v->modification = g->modification;
    v->space = g->space;
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

/* Reads step @p t, which the caller marked STEP_READING, without the lock;
 * stores the result under it and wakes the waiters. */
static void
read_step(vv_time_series *ts, int t) {
    vv_load_options o = ts->opt;
    o.time = t;
    o.info = NULL;
    vv_volume *v = NULL;
    vv_status s = ts->raw_fd >= 0 ? read_raw_step(ts, t, &v) : vv_volume_load(&v, ts->path, &o);
    if (s == VV_OK && (v->dims[0] != ts->dims[0] || v->dims[1] != ts->dims[1] ||
                       v->dims[2] != ts->dims[2] || v->type != ts->type)) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "time series: %s: time step %d is %d x %d x %d %s, step 0 is %d x %d x "
                         "%d %s (every step of a series has one shape)",
                         vv_path_basename(ts->path), t, v->dims[0], v->dims[1], v->dims[2],
                         vv_voxel_type_name(v->type), ts->dims[0], ts->dims[1], ts->dims[2],
                         vv_voxel_type_name(ts->type));
        vv_volume_free(v);
        v = NULL;
    }
    char *msg = s == VV_OK ? NULL : strdup(vv_error_message());
    pthread_mutex_lock(&ts->lock);
    step *st = &ts->steps[t];
    ts->reads++;
    if (s == VV_OK) {
        st->state = STEP_READY;
        st->volume = v;
        st->last_use = ++ts->clock;
        evict(ts, t);
    } else {
        st->state = STEP_FAILED;
        st->status = s;
        st->message = msg;
    }
    pthread_cond_broadcast(&ts->changed);
    pthread_mutex_unlock(&ts->lock);
}

static void *
prefetch_main(void *arg) {
    vv_time_series *ts = arg;
    pthread_mutex_lock(&ts->lock);
    for (;;) {
        while (!ts->quit && ts->pending < 0)
            pthread_cond_wait(&ts->changed, &ts->lock);
        if (ts->quit)
            break;
        int t = ts->pending;
        ts->pending = -1;
        if (ts->steps[t].state != STEP_EMPTY)
            continue;
        ts->steps[t].state = STEP_READING;
        pthread_mutex_unlock(&ts->lock);
        read_step(ts, t);
        pthread_mutex_lock(&ts->lock);
    }
    pthread_mutex_unlock(&ts->lock);
    return NULL;
}

vv_status
vv_time_series_open(vv_time_series **out, const char *path, const vv_load_options *opt,
                    uint64_t cache_bytes) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "time series: NULL argument");
    *out = NULL;
    vv_time_series *ts = calloc(1, sizeof *ts);
    if (!ts || !(ts->path = strdup(path))) {
        free(ts);
        return vv_error_set(VV_ERR_NOMEM, "time series: out of memory");
    }
    if (opt)
        ts->opt = *opt;
    else
        vv_load_options_init(&ts->opt);
    ts->opt.time = 0;
    ts->opt.info = &ts->info;
    vv_volume *v0 = NULL;
    vv_status s = vv_volume_load(&v0, path, &ts->opt);
    ts->opt.info = NULL;
    if (s == VV_OK && !(ts->steps = calloc((size_t)ts->info.n_times, sizeof *ts->steps)))
        s = vv_error_set(VV_ERR_NOMEM, "time series: out of memory");
    if (s != VV_OK) {
        vv_volume_free(v0);
        free(ts->path);
        free(ts);
        return s;
    }
    ts->n = ts->info.n_times;
    memcpy(ts->dims, v0->dims, sizeof ts->dims);
    ts->type = v0->type;
    ts->step_bytes = vv_volume_voxel_count(v0) * vv_voxel_type_size(v0->type);
    ts->cache_bytes = cache_bytes ? cache_bytes : 3 * ts->step_bytes;
    ts->steps[0].state = STEP_READY;
    ts->steps[0].volume = v0;
    ts->steps[0].last_use = ++ts->clock;
    ts->reads = 1;
    ts->pending = -1;
    ts->raw_fd = -1;
    /* the raw layout, when the reader found one that the file's size holds:
     * later steps by offset in this process (the header was parsed in the
     * sandbox; what is read here is bytes at checked offsets) */
    const vv_load_info *in = &ts->info;
    int ch = ts->opt.channel < 0 ? 0 : ts->opt.channel;
    struct stat sb;
    int fd = in->has_raw_layout && in->raw_step_bytes == ts->step_bytes && ts->n > 1
                 ? open(path, O_RDONLY | O_CLOEXEC)
                 : -1;
    uint64_t size =
        fd >= 0 && fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) ? (uint64_t)sb.st_size : 0;
    int fits = fd >= 0 && in->raw_offset <= size &&
               (ch == 0 || in->raw_channel_bytes <= (size - in->raw_offset) / (uint64_t)ch);
    uint64_t base = fits ? in->raw_offset + (uint64_t)ch * in->raw_channel_bytes : 0;
    if (fits && base <= size && (uint64_t)ts->n <= (size - base) / ts->step_bytes) {
        ts->raw_fd = fd;
        ts->raw_base = base;
        ts->step0 = vv_volume_ref(v0);
    } else if (fd >= 0) {
        close(fd);
    }
    pthread_mutex_init(&ts->lock, NULL);
    pthread_cond_init(&ts->changed, NULL);
    evict(ts, 0);
    *out = ts;
    return VV_OK;
}

int
vv_time_series_count(const vv_time_series *ts) {
    return ts ? ts->n : 0;
}

const vv_load_info *
vv_time_series_info(const vv_time_series *ts) {
    return ts ? &ts->info : NULL;
}

vv_status
vv_time_series_get(vv_time_series *ts, int t, vv_volume **out) {
    if (!ts || !out)
        return vv_error_set(VV_ERR_INVALID, "time series: NULL argument");
    *out = NULL;
    if (t < 0 || t >= ts->n)
        return vv_error_set(VV_ERR_INVALID,
                            "time series: %s: time step %d asked, it has %d (from 0)",
                            vv_path_basename(ts->path), t, ts->n);
    pthread_mutex_lock(&ts->lock);
    step *st = &ts->steps[t];
    while (st->state == STEP_READING)
        pthread_cond_wait(&ts->changed, &ts->lock);
    if (st->state == STEP_EMPTY) {
        st->state = STEP_READING;
        pthread_mutex_unlock(&ts->lock);
        read_step(ts, t);
        pthread_mutex_lock(&ts->lock);
    }
    vv_status s = VV_OK;
    if (st->state == STEP_READY) {
        st->last_use = ++ts->clock;
        *out = vv_volume_ref(st->volume);
    } else {
        s = vv_error_set(st->status, "%s", st->message ? st->message : "time step unreadable");
    }
    pthread_mutex_unlock(&ts->lock);
    return s;
}

void
vv_time_series_prefetch(vv_time_series *ts, int t) {
    if (!ts || t < 0 || t >= ts->n)
        return;
    pthread_mutex_lock(&ts->lock);
    if (ts->steps[t].state == STEP_EMPTY) {
        if (!ts->has_thread && pthread_create(&ts->thread, NULL, prefetch_main, ts) == 0)
            ts->has_thread = 1;
        ts->pending = t;
        pthread_cond_broadcast(&ts->changed);
    }
    pthread_mutex_unlock(&ts->lock);
}

void
vv_time_series_stats(vv_time_series *ts, int *reads, int *resident, uint64_t *bytes) {
    int r = 0, n = 0;
    if (ts) {
        pthread_mutex_lock(&ts->lock);
        r = ts->reads;
        for (int t = 0; t < ts->n; t++)
            n += ts->steps[t].state == STEP_READY;
        pthread_mutex_unlock(&ts->lock);
    }
    if (reads)
        *reads = r;
    if (resident)
        *resident = n;
    if (bytes)
        *bytes = ts ? (uint64_t)n * ts->step_bytes : 0;
}

void
vv_time_series_free(vv_time_series *ts) {
    if (!ts)
        return;
    pthread_mutex_lock(&ts->lock);
    ts->quit = 1;
    pthread_cond_broadcast(&ts->changed);
    pthread_mutex_unlock(&ts->lock);
    if (ts->has_thread)
        pthread_join(ts->thread, NULL);
    for (int t = 0; t < ts->n; t++) {
        vv_volume_free(ts->steps[t].volume);
        free(ts->steps[t].message);
    }
    vv_volume_free(ts->spare);
    vv_volume_free(ts->step0);
    if (ts->raw_fd >= 0)
        close(ts->raw_fd);
    pthread_mutex_destroy(&ts->lock);
    pthread_cond_destroy(&ts->changed);
    free(ts->steps);
    free(ts->path);
    free(ts);
}
