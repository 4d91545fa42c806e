/*
 * The loader, the frame's plan and the multiresolution source of a
 * pyramid (src/io/store/pyramid.h; its state in pyramid_internal.h), on its
 * chunks and boxes (pyramid.c); opened and freed by pyramid_open.c.
 *
 * When the renderer plans its frame (the boxes it will read, in order),
 * each chunk's uses in the plan are known, and the chunk evicted is the
 * one needed again farthest ahead or never (Belady's optimal policy):
 * ghost voxels pull a node's neighbours' chunks in early, and they stay
 * until their own node when the limit allows. Unplanned reads evict the
 * least recently used. With a plan, after each box the chunks of the next
 * few boxes that are not cached are asked of the store ahead (when it can
 * fetch in the background: the sandboxed readers), so that they are
 * decoded while the renderer draws.
 *
 * The loader (vv_pyramid_request): a few threads read a queue of chunks
 * into the same cache, soonest first; a new request replaces the queue.
 * A chunk being read by anyone sits in the cache reserved and pinned
 * (PY_LOADING): a frame needing it waits on the arrival condition rather
 * than reading it twice. One mutex, the cache's, guards the chunks, the
 * plan, the queue and the statistics; reading and decoding run outside it.
 */
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/cache.h"
#include "core/internal.h"
#include "io/store/pyramid.h"
#include "io/store/pyramid_internal.h"
#include "volvis/bricks.h"

/* ---- the frame's plan -------------------------------------------------------------- */

static void
forget_use(vv_pyramid *p, py_chunk *c) {
    (void)p;
    c->use = NULL;
}

void
py_clear_plan(vv_pyramid *p) {
    for (unsigned b = 0; b < PY_BUCKETS; b++)
        while (p->ubucket[b]) {
            py_use *u = p->ubucket[b];
            p->ubucket[b] = u->hnext;
            free(u->seq);
            free(u);
        }
    py_each_chunk(p, forget_use);
    p->cl.planned = 0;
    p->cursor = 0;
    free(p->plan_box);
    p->plan_box = NULL;
    p->plan_n = 0;
}

/* The boxes of a frame's plan or request kept as the last ones (lock
 * held; a box out of range left out); none kept when out of memory. */
static void
keep_last(vv_pyramid *p, int n, const int *level, const int *lo, const int *hi) {
    if (n <= 0)
        return;
    int *b = malloc(sizeof(int) * 7 * (size_t)n);
    if (!b)
        return;
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (level[i] < 0 || level[i] >= p->n_levels)
            continue;
        b[7 * m] = level[i];
        memcpy(b + 7 * m + 1, lo + 3 * i, sizeof(int) * 3);
        memcpy(b + 7 * m + 4, hi + 3 * i, sizeof(int) * 3);
        m++;
    }
    free(p->last_box);
    p->last_box = b;
    p->last_n = m;
}

/* The plan's next box needing chunk @p c from the box being read on;
 * INT_MAX: none. */
static int
next_use(const vv_pyramid *p, py_chunk *c) {
    py_use *u = c->use;
    if (!u)
        return INT_MAX;
    while (u->pos < u->n && u->seq[u->pos] < p->cursor)
        u->pos++;
    return u->pos < u->n ? u->seq[u->pos] : INT_MAX;
}

/* The cache asks when the plan needs chunk @p e next (lock held). */
int
py_client_next_use(vv_cache_client *cl, vv_cache_entry *e) {
    vv_pyramid *p = (vv_pyramid *)((char *)cl - offsetof(vv_pyramid, cl));
    return next_use(p, (py_chunk *)e);
}

/* The plan's boxes after the one just read (at most PY_LOOKAHEAD of them):
 * their chunks not cached are asked of the store ahead (its prefetch),
 * nearest in the plan first, until it has no reader free. The store
 * decodes them while the renderer draws this box. */
#define PY_LOOKAHEAD 4
static void
prefetch_ahead(vv_pyramid *p) {
    if (!p->cl.planned || !p->store.prefetch || !p->plan_box)
        return;
    for (int b = p->cursor + 1; b < p->plan_n && b <= p->cursor + PY_LOOKAHEAD; b++) {
        const int *box = p->plan_box + 7 * b, level = box[0];
        const py_level *l = &p->lv[level];
        int c0[3], c1[3];
        py_chunk_span(l, box + 1, box + 4, c0, c1);
        for (int z = c0[2]; z <= c1[2]; z++)
            for (int y = c0[1]; y <= c1[1]; y++)
                for (int x = c0[0]; x <= c1[0]; x++) {
                    const int c[3] = {x, y, z};
                    if (!py_find_chunk(p, level, py_chunk_linear(l, c)) &&
                        !p->store.prefetch(p->store.ctx, level, c))
                        return;
                }
    }
}

/* py_box_read's @p planned: a box of the plan read (lock held), the next
 * boxes' chunks asked ahead, the plan moved on to the next box. */
static void
plan_box_read(vv_pyramid *p, vv_status s) {
    if (s == VV_OK)
        prefetch_ahead(p);
    if (p->cl.planned)
        p->cursor++;
}

/* ---- the loader ------------------------------------------------------------------ */

/* A loader thread: takes the queue's chunks soonest first, reserves each in
 * the cache (PY_LOADING, so that a frame needing it waits instead of
 * reading it twice), decodes it without the lock and makes it ready; stops
 * taking when the cache is full of chunks the request wants (the rest
 * stay missing: a frame draws them coarser). */
/* Batched loading (a store with read_many: a remote one): the loaders each
 * take a window of up to this many queued chunks of one level, in the
 * queue's order, and have the store fetch them together. */
static int
load_window(const vv_pyramid *p) {
    const int w = p->store.parallel / (p->n_loaders > 0 ? p->n_loaders : 1);
    return w < 1 ? 1 : w > 256 ? 256 : w;
}

/* Entry @p e read (status @p s) by a loader: ready, or failed (lock held). */
static void
loaded(vv_pyramid *p, py_chunk *e, vv_status s, uint64_t fbytes, int missing) {
    if (s == VV_OK) {
        py_entry_ready(p, e, fbytes, missing);
        p->st.loaded++;
    } else {
        e->state = PY_FAILED;
        vv_volume_free(e->blk);
        e->blk = NULL;
        p->st.load_errors++;
        p->arrivals++;
    }
    py_unpin(p, e);
}

/* The next chunk of the queue that is neither held nor being read, made
 * an entry being read (PY_LOADING), its position in its level's grid in
 * @p c; NULL when the queue is done, when its next request is not of
 * @p level (>= 0: a window reads one level), or when the cache is full
 * (the rest of the queue then waits for the next request). Lock held. */
static py_chunk *
take_queued(vv_pyramid *p, int level, int c[3]) {
    while (p->q_pos < p->q_n) {
        const py_req q = p->queue[p->q_pos];
        if (level >= 0 && q.level != level)
            return NULL;
        p->q_pos++;
        const py_level *l = &p->lv[q.level];
        if (py_find_chunk(p, q.level, q.L))
            continue; /* held, or being read */
        c[0] = (int)(q.L % (uint64_t)l->nchunks[0]);
        c[1] = (int)(q.L / (uint64_t)l->nchunks[0] % (uint64_t)l->nchunks[1]);
        c[2] = (int)(q.L / ((uint64_t)l->nchunks[0] * (uint64_t)l->nchunks[1]));
        py_chunk *x = py_new_entry(p, q.level, c);
        if (!x || !vv_cache_make_room(p->cache, x->bytes, 1) || py_alloc_block(p, x) != VV_OK) {
            if (x)
                vv_volume_free(x->blk);
            free(x);
            vv_error_clear();
            p->st.load_stopped += (uint64_t)(p->q_n - p->q_pos + 1);
            p->q_pos = p->q_n; /* full: the rest waits for the next request */
            p->stalled = 1;
            pthread_cond_broadcast(&p->arrived);
            return NULL;
        }
        x->state = PY_LOADING;
        x->ce.want = p->cl.want;
        py_insert_entry(p, x);
        return x;
    }
    return NULL;
}

/* A loader's window of the queue (read_many; lock held): up to
 * load_window chunks of the first one's level reserved in the cache
 * (PY_LOADING) into @p e, read together without the lock, made ready.
 * Stops the queue as loader_main does when the cache is full. A chunk a
 * newer request no longer wants (and no frame waits on) is dropped while
 * its fetch is in flight (cancelled_in_flight): out of the cache, as a
 * failed one nobody holds, asked again by any later request. */
static void
load_batch(vv_pyramid *p, py_chunk **e, uint64_t *fbytes, int *missing, int *cancelled) {
    const int w = load_window(p);
    int n = 0, level = -1, c[3];
    py_chunk *x;
    while (n < w && (x = take_queued(p, level, c)) != NULL) {
        level = x->level;
        e[n++] = x;
    }
    if (n == 0)
        return;
    p->in_flight += n;
    pthread_mutex_unlock(p->lock);
    /* decoded on this thread: the other loaders' windows are in flight meanwhile */
    const vv_status s = py_read_many(p, e, n, 1, fbytes, missing, cancelled);
    pthread_mutex_lock(p->lock);
    p->in_flight -= n;
    if (s != VV_OK)
        vv_error_clear(); /* a frame reading them reports the error */
    for (int i = 0; i < n; i++)
        if (s == VV_OK && cancelled[i]) {
            e[i]->state = PY_FAILED; /* gone with the reader's pin; a frame now waiting reads it */
            vv_volume_free(e[i]->blk);
            e[i]->blk = NULL;
            p->st.cancelled_in_flight++;
            p->arrivals++;
            py_unpin(p, e[i]);
        } else
            loaded(p, e[i], s, s == VV_OK ? fbytes[i] : 0, s == VV_OK ? missing[i] : 0);
    pthread_cond_broadcast(&p->arrived);
}

static void *
loader_main(void *arg) {
    vv_pyramid *p = arg;
    unsigned char *scratch = p->store.scratch ? malloc(p->store.scratch) : NULL;
    const int batched = p->store.read_many != NULL;
    const int w = batched ? 256 : 0;
    py_chunk **win = batched ? malloc(sizeof *win * (size_t)w) : NULL;
    uint64_t *wbytes = batched ? malloc(sizeof *wbytes * (size_t)w) : NULL;
    int *wmiss = batched ? malloc(sizeof *wmiss * (size_t)w) : NULL;
    int *wgone = batched ? malloc(sizeof *wgone * (size_t)w) : NULL;
    pthread_mutex_lock(p->lock);
    while (!p->quit) {
        if (batched && win && wbytes && wmiss && wgone && p->q_pos < p->q_n) {
            load_batch(p, win, wbytes, wmiss, wgone);
            continue;
        }
        if (p->q_pos >= p->q_n || (p->store.scratch && !scratch)) {
            pthread_cond_wait(&p->work, p->lock);
            continue;
        }
        int c[3];
        py_chunk *e = take_queued(p, -1, c);
        if (!e)
            continue; /* the queue done, or the cache full */
        p->in_flight++;
        pthread_mutex_unlock(p->lock);
        int missing = 0;
        uint64_t fbytes = 0;
        const vv_status s = py_read_chunk(p, e, c, scratch, &missing, &fbytes);
        pthread_mutex_lock(p->lock);
        p->in_flight--;
        if (s != VV_OK)
            vv_error_clear(); /* a frame reading it reports the error */
        loaded(p, e, s, fbytes, missing);
        pthread_cond_broadcast(&p->arrived);
    }
    pthread_mutex_unlock(p->lock);
    free(scratch);
    free(win);
    free(wbytes);
    free(wmiss);
    free(wgone);
    return NULL;
}

/* The loader's threads, started at the first request (lock held): a few
 * (the cores, at most 4), one when the store reads one chunk at a time, as
 * many as the store says when its reads wait on the network (a remote
 * store's requests in flight). */
static vv_status
start_loaders(vv_pyramid *p) {
    int n = p->store.parallel > 1 ? p->store.parallel : p->store.parallel ? vv_threads_get() : 1;
    /* a store that fetches batches: two loaders, each a window of half the
     * requests in flight, one decoding while the other's are fetched */
    if (p->store.read_many && n > 2)
        n = 2;
    n = n < 1 ? 1 : n > PY_LOADERS_MAX ? PY_LOADERS_MAX : n;
    if (p->store.parallel <= 1 && n > 4)
        n = 4;
    /* each loader holds a chunk's scratch: at most a quarter of the budget */
    const uint64_t quarter = vv_memory_budget_get() / 4;
    if (p->store.scratch && (uint64_t)n * p->store.scratch > quarter)
        n = quarter / p->store.scratch > 1 ? (int)(quarter / p->store.scratch) : 1;
    if (p->store.scratch > ((size_t)64 << 20))
        n = 1;
    for (int i = 0; i < n; i++) {
        if (pthread_create(&p->loader[i], NULL, loader_main, p) != 0)
            return p->n_loaders ? VV_OK
                                : vv_error_set(VV_ERR_NOMEM, "cannot start the loader's threads");
        p->n_loaders++;
    }
    return VV_OK;
}

/* A small open-addressed set of (level, L) keys, to queue each chunk once. */
static int
seen_add(uint64_t *set, uint64_t mask, int level, uint64_t L) {
    const uint64_t key = (L << 4 | (uint64_t)level) + 1;
    for (uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> 20 & mask;; h = (h + 1) & mask) {
        if (set[h] == key)
            return 0;
        if (!set[h]) {
            set[h] = key;
            return 1;
        }
    }
}

vv_status
vv_pyramid_request(vv_pyramid *p, int n, const int *level, const int *lo, const int *hi) {
    if (!p || n < 0 || (n > 0 && (!level || !lo || !hi)))
        return vv_error_set(VV_ERR_INVALID, "pyramid: bad request arguments");
    /* the chunks, each once, in the boxes' order */
    uint64_t count = 0;
    for (int i = 0; i < n; i++) {
        if (level[i] < 0 || level[i] >= p->n_levels)
            return vv_error_set(VV_ERR_INVALID, "pyramid: request of level %d (0 .. %d)", level[i],
                                p->n_levels - 1);
        const py_level *l = &p->lv[level[i]];
        uint64_t m = 1;
        for (int k = 0; k < 3; k++) {
            if (lo[3 * i + k] < 0 || hi[3 * i + k] < lo[3 * i + k] || hi[3 * i + k] >= l->dims[k])
                return vv_error_set(VV_ERR_INVALID,
                                    "pyramid: request box %d..%d outside level %d's %d voxels",
                                    lo[3 * i + k], hi[3 * i + k], level[i], l->dims[k]);
            m *= (uint64_t)(hi[3 * i + k] / l->cdims[k] - lo[3 * i + k] / l->cdims[k] + 1);
        }
        count += m;
    }
    if (count > (uint64_t)1 << 24)
        return vv_error_set(VV_ERR_LIMIT, "pyramid: a request of %llu chunks (at most %d)",
                            (unsigned long long)count, 1 << 24);
    uint64_t slots = 16;
    while (slots < 2 * count)
        slots *= 2;
    uint64_t *seen = calloc((size_t)slots, sizeof *seen);
    py_req *q = malloc(sizeof *q * (size_t)(count ? count : 1));
    if (!seen || !q) {
        free(seen);
        free(q);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    pthread_mutex_lock(p->lock);
    p->cl.want++;
    int nq = 0;
    for (int i = 0; i < n; i++) {
        const py_level *l = &p->lv[level[i]];
        int c0[3], c1[3];
        py_chunk_span(l, lo + 3 * i, hi + 3 * i, c0, c1);
        for (int z = c0[2]; z <= c1[2]; z++)
            for (int y = c0[1]; y <= c1[1]; y++)
                for (int x = c0[0]; x <= c1[0]; x++) {
                    const int c[3] = {x, y, z};
                    const uint64_t L = py_chunk_linear(l, c);
                    if (!seen_add(seen, slots - 1, level[i], L))
                        continue;
                    py_chunk *e = py_find_chunk(p, level[i], L);
                    if (e && e->state != PY_FAILED)
                        e->ce.want = p->cl.want; /* held: kept by the loader */
                    else
                        q[nq++] = (py_req){level[i], L};
                }
    }
    p->st.cancelled += (uint64_t)(p->q_n - p->q_pos); /* what the view made stale */
    keep_last(p, n, level, lo, hi);
    p->stalled = 0;
    free(p->queue);
    p->queue = q;
    p->q_n = nq;
    p->q_pos = 0;
    vv_status s = VV_OK;
    if (nq > 0 && p->n_loaders == 0)
        s = start_loaders(p);
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(p->lock);
    free(seen);
    return s;
}

vv_status
vv_pyramid_request_like(vv_pyramid *p, vv_pyramid *like) {
    if (!p || !like)
        return vv_error_set(VV_ERR_INVALID, "pyramid: NULL argument");
    if (p->n_levels != like->n_levels)
        return vv_error_set(VV_ERR_UNSUPPORTED, "pyramid: read-ahead between %d and %d levels",
                            p->n_levels, like->n_levels);
    for (int l = 0; l < p->n_levels; l++)
        for (int k = 0; k < 3; k++)
            if (p->lv[l].dims[k] != like->lv[l].dims[k])
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "pyramid: read-ahead between levels of other sizes");
    pthread_mutex_lock(like->lock);
    const int n = like->last_n;
    int *b = n > 0 ? malloc(sizeof(int) * 7 * (size_t)n) : NULL;
    if (b)
        memcpy(b, like->last_box, sizeof(int) * 7 * (size_t)n);
    pthread_mutex_unlock(like->lock);
    if (n > 0 && !b)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    int *lv = malloc(sizeof(int) * (size_t)(n ? n : 1)),
        *lo = malloc(sizeof(int) * 3 * (size_t)(n ? n : 1)),
        *hi = malloc(sizeof(int) * 3 * (size_t)(n ? n : 1));
    vv_status s = lv && lo && hi ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; s == VV_OK && i < n; i++) {
        lv[i] = b[7 * i];
        memcpy(lo + 3 * i, b + 7 * i + 1, sizeof(int) * 3);
        memcpy(hi + 3 * i, b + 7 * i + 4, sizeof(int) * 3);
    }
    if (s == VV_OK && n > 0)
        s = vv_pyramid_request(p, n, lv, lo, hi);
    free(b);
    free(lv);
    free(lo);
    free(hi);
    return s;
}

int
vv_pyramid_loading(vv_pyramid *p) {
    if (!p)
        return 0;
    pthread_mutex_lock(p->lock);
    const int n = p->q_n - p->q_pos + p->in_flight;
    pthread_mutex_unlock(p->lock);
    return n;
}

int
vv_pyramid_wait(vv_pyramid *p, double seconds) {
    if (!p)
        return 0;
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    const double t = seconds > 0 ? seconds : 0;
    until.tv_sec += (time_t)t;
    until.tv_nsec += (long)((t - floor(t)) * 1e9);
    if (until.tv_nsec >= 1000000000L) {
        until.tv_sec++;
        until.tv_nsec -= 1000000000L;
    }
    pthread_mutex_lock(p->lock);
    const uint64_t seen = p->arrivals;
    while (p->q_n - p->q_pos + p->in_flight > 0 && p->arrivals == seen)
        if (pthread_cond_timedwait(&p->arrived, p->lock, &until) != 0)
            break;
    const int n = p->q_n - p->q_pos + p->in_flight;
    pthread_mutex_unlock(p->lock);
    return n;
}

/* Stops the loader: the queue dropped, the chunks in flight finished. */
void
py_stop_loaders(vv_pyramid *p) {
    pthread_mutex_lock(p->lock);
    p->quit = 1;
    p->q_pos = p->q_n;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(p->lock);
    for (int i = 0; i < p->n_loaders; i++)
        pthread_join(p->loader[i], NULL);
    p->n_loaders = 0;
}

/* ---- the source interface ----------------------------------------------------- */

/* The chunks of level @p level under voxels @p lo .. @p hi: those not
 * read yet into @p missing, all of them returned (p->lock held). */
static int
count_chunks(const vv_pyramid *p, int level, const int lo[3], const int hi[3], int *missing) {
    const py_level *l = &p->lv[level];
    int c0[3], c1[3], n = 0, all = 0;
    py_chunk_span(l, lo, hi, c0, c1);
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                const int c[3] = {x, y, z};
                const py_chunk *e = py_find_chunk(p, level, py_chunk_linear(l, c));
                n += !e || e->state != PY_READY;
                all++;
            }
    *missing = n;
    return all;
}

static int
missing_chunks(const vv_pyramid *p, int level, const int lo[3], const int hi[3]) {
    int n;
    count_chunks(p, level, lo, hi, &n);
    return n;
}

static int
src_resident(void *user, int level, const int lo[3], const int hi[3]) {
    vv_pyramid *p = user;
    int missing;
    pthread_mutex_lock(p->lock);
    const int all = count_chunks(p, level, lo, hi, &missing);
    pthread_mutex_unlock(p->lock);
    return all - missing;
}

static int
box_range(const vv_pyramid *p, int level, int ch, const int lo[3], const int hi[3], float *vmin,
          float *vmax) {
    const py_level *l = &p->lv[level];
    if (!l->known || ch < 0 || ch >= p->n_ch)
        return 0;
    int c0[3], c1[3];
    py_chunk_span(l, lo, hi, c0, c1);
    float a = INFINITY, b = -INFINITY;
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                const int c[3] = {x, y, z};
                const uint64_t L = py_chunk_linear(l, c);
                if (!l->known[L])
                    return 0;
                const uint64_t at = L * (uint64_t)p->n_ch + (uint64_t)ch;
                a = l->cmin[at] < a ? l->cmin[at] : a;
                b = l->cmax[at] > b ? l->cmax[at] : b;
            }
    *vmin = a;
    *vmax = b;
    return 1;
}

static const vv_volume *
src_level(void *user, int level) {
    return vv_pyramid_level(user, level);
}

static vv_status
src_read_box(void *user, int level, const int lo[3], const int hi[3], vv_volume **out) {
    return py_box_read(user, level, 0, lo, hi, out, plan_box_read);
}

static vv_status
src_read_channels(void *user, int level, const int lo[3], const int hi[3], vv_volume **out) {
    return py_box_read(user, level, -1, lo, hi, out, plan_box_read);
}

static int
src_channel_range(void *user, int channel, int level, const int lo[3], const int hi[3], float *vmin,
                  float *vmax) {
    vv_pyramid *p = user;
    pthread_mutex_lock(p->lock);
    const int r = box_range(p, level, channel, lo, hi, vmin, vmax);
    pthread_mutex_unlock(p->lock);
    return r;
}

static int
src_box_range(void *user, int level, const int lo[3], const int hi[3], float *vmin, float *vmax) {
    return src_channel_range(user, 0, level, lo, hi, vmin, vmax);
}

static vv_status
src_channel_read_box(void *user, int channel, int level, const int lo[3], const int hi[3],
                     vv_volume **out) {
    return py_box_read(user, level, channel, lo, hi, out, NULL);
}

static const vv_volume *
src_channel_level(void *user, int channel, int level) {
    return vv_pyramid_channel_level(user, channel, level);
}

static int
src_missing(void *user, int level, const int lo[3], const int hi[3]) {
    vv_pyramid *p = user;
    pthread_mutex_lock(p->lock);
    const int n = missing_chunks(p, level, lo, hi);
    pthread_mutex_unlock(p->lock);
    return n;
}

static void
src_frame(void *user, int begin) {
    vv_pyramid *p = user;
    pthread_mutex_lock(p->lock);
    py_clear_plan(p);
    if (begin) {
        p->frame++;
        p->st.frames++;
    }
    pthread_mutex_unlock(p->lock);
}

/* Notes box @p seq's use of chunk (level, L). */
static vv_status
add_use(vv_pyramid *p, int level, uint64_t L, int seq) {
    py_use *u = py_find_use(p, level, L);
    if (!u) {
        if (!(u = calloc(1, sizeof *u)))
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        u->level = level;
        u->L = L;
        const unsigned b = py_bucket_of(level, L);
        u->hnext = p->ubucket[b];
        p->ubucket[b] = u;
    }
    if (u->n == u->cap) {
        const int cap = u->cap ? 2 * u->cap : 4;
        int *seq2 = realloc(u->seq, sizeof(int) * (size_t)cap);
        if (!seq2)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        u->seq = seq2;
        u->cap = cap;
    }
    u->seq[u->n++] = seq;
    return VV_OK;
}

static void
find_uses(vv_pyramid *p, py_chunk *c) {
    c->use = py_find_use(p, c->level, c->L);
}

static vv_status
plan_locked(vv_pyramid *p, int n, const int *level, const int *lo, const int *hi) {
    py_clear_plan(p);
    vv_status s = VV_OK;
    for (int i = 0; i < n && s == VV_OK; i++) {
        if (level[i] < 0 || level[i] >= p->n_levels)
            continue;
        const py_level *l = &p->lv[level[i]];
        int c0[3], c1[3];
        py_chunk_span(l, lo + 3 * i, hi + 3 * i, c0, c1);
        for (int z = c0[2]; z <= c1[2] && s == VV_OK; z++)
            for (int y = c0[1]; y <= c1[1] && s == VV_OK; y++)
                for (int x = c0[0]; x <= c1[0] && s == VV_OK; x++) {
                    const int c[3] = {x, y, z};
                    s = add_use(p, level[i], py_chunk_linear(l, c), i);
                }
    }
    if (s != VV_OK) {
        py_clear_plan(p);
        return s;
    }
    py_each_chunk(p, find_uses);
    keep_last(p, n, level, lo, hi);
    if (p->store.prefetch && n > 0 && (p->plan_box = malloc(sizeof(int) * 7 * (size_t)n))) {
        for (int i = 0; i < n; i++) {
            const int ok = level[i] >= 0 && level[i] < p->n_levels;
            int *box = p->plan_box + 7 * i;
            box[0] = ok ? level[i] : 0;
            for (int k = 0; k < 3; k++) { /* a box out of range: an empty one at level 0 */
                box[1 + k] = ok ? lo[3 * i + k] : 0;
                box[4 + k] = ok ? hi[3 * i + k] : 0;
            }
        }
        p->plan_n = n;
    }
    p->cl.planned = 1;
    p->cursor = 0;
    return VV_OK;
}

/* A frame's plan (a frame drawn whole: every box read in this order).
 * A store whose reads wait on the network (read_many: a remote one) has
 * the plan's chunks asked of the loader as well, so that they stream in
 * with every request in flight, in the plan's order, while the frame
 * draws the boxes that arrived (it waits for those being fetched, reads
 * itself those not yet taken): box by box, the frame would wait a round
 * trip for each. */
static vv_status
src_plan(void *user, int n, const int *level, const int *lo, const int *hi) {
    vv_pyramid *p = user;
    pthread_mutex_lock(p->lock);
    const vv_status s = plan_locked(p, n, level, lo, hi);
    pthread_mutex_unlock(p->lock);
    if (s == VV_OK && p->store.read_many && n > 0 &&
        vv_pyramid_request(p, n, level, lo, hi) != VV_OK)
        vv_error_clear(); /* a hint: the frame reads what it needs */
    return s;
}

static vv_status
src_request(void *user, int n, const int *level, const int *lo, const int *hi) {
    return vv_pyramid_request(user, n, level, lo, hi);
}

static int
src_stalled(void *user) {
    vv_pyramid *p = user;
    pthread_mutex_lock(p->lock);
    const int r = p->stalled;
    pthread_mutex_unlock(p->lock);
    return r;
}

void
vv_pyramid_source(vv_pyramid *p, vv_multires_source *out) {
    memset(out, 0, sizeof *out);
    out->version = VV_MULTIRES_SOURCE_VERSION;
    out->user = p;
    out->n_levels = p->n_levels;
    out->node_cells = p->node_cells;
    out->level = src_level;
    out->read_box = src_read_box;
    out->box_range = src_box_range;
    out->frame = src_frame;
    out->plan = src_plan;
    out->missing_chunks = src_missing;
    out->boxes = p->boxes;
    out->request = src_request;
    out->stalled = src_stalled;
    out->n_channels = p->n_ch;
    out->resident_chunks = src_resident;
    if (p->n_ch > 1) {
        out->read_channels = src_read_channels;
        out->channel_range = src_channel_range;
        out->channel_level = src_channel_level;
        out->channel_read_box = src_channel_read_box;
    }
}
