/*
 * Many chunks of a Zarr array copied into a volume or into blocks
 * (vv_zr_copy_chunks, zarr.h): from a local store chunk by chunk on the
 * threads (pread), from a remote one (a URL) in batches with many requests
 * in flight.
 *
 * A remote read is a pipeline. The plan: each chunk's read unit (an inner
 * chunk when sharded) and where its bytes are; a sharded array's shard
 * indexes are read first (zr3_locate_many: each shard's once, a window of
 * them at a time); inner chunks whose bytes follow each other in a shard
 * are merged into runs, one range request each (runs()). Then two
 * fetching threads of our own each take the next window of
 * bs_http_in_flight() / 2 runs in the caller's order and put the whole
 * window in flight through zr_store_get_many (one libcurl multi handle;
 * up to bs_http_in_flight() requests at once in all), while
 * the decoding threads (the caller's count, threads of our own: OpenMP
 * gives one inside a renderer's parallel region) decode the windows that
 * came back. The encoded bytes held -- reserved for a window in flight
 * (its exact ranges when sharded, else an estimate of a chunk's encoded
 * size), then counted as received until decoded -- stay under a quarter
 * of the memory budget: a fetcher waits for the decoders before starting a
 * window past it (one window always runs). Absent chunks (no shard, an
 * empty inner chunk) are the fill value without a request. Nested shards
 * are read chunk by chunk (copy_each). A sharded precomputed scale is read
 * the same way: zr_pc_locate_many reads its shard and minishard indexes,
 * its chunks' ranges are merged into runs within a shard.
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/zarr.h"

#define ZB_KEY 2200
#define ZB_FETCHERS 2
/* A run: at most these bytes (its cap at least ZB_RUN_MIN) and chunks in
 * one request. */
#define ZB_RUN_MAX ((uint64_t)8 << 20)
#define ZB_RUN_MIN ((uint64_t)256 << 10)
#define ZB_RUN_CHUNKS 4096

struct zb_job;

/* A precomputed scale in shards (neuroglancer_uint64_sharded_v1): its
 * chunks located like a Zarr shard's inner chunks, but in a shard named
 * by hash (zr_pc_key of the chunk itself). */
static int
pc_sharded(const zr_array *a) {
    return a->zarr_format == ZR_PRECOMPUTED && a->pc_shard;
}

/* Chunks read as byte ranges of shards, located first. */
static int
sharded(const zr_array *a) {
    return a->nshard == 1 || pc_sharded(a);
}

/* A run of a window as its read's bs_get.stale sees it. */
typedef struct zb_ask {
    const struct zb_job *j;
    uint64_t r;
} zb_ask;

/* One window of runs put in flight together, then decoded: run r's
 * response holds its chunks' bytes back to back. */
typedef struct zb_win {
    struct zb_win *next;
    int n;            /* runs */
    uint64_t members; /* chunks in all */
    uint64_t taken, left;
    uint64_t *run; /* the runs' numbers */
    bs_get *g;
    zb_ask *ask;
    char *keys;
    uint64_t held; /* bytes received, not yet decoded */
} zb_win;

typedef struct zb_job {
    const zr_layout *J;
    const uint64_t *L;
    unsigned char *dst;
    const int *dorg, *ddims;
    zr_dest *each;
    int stale; /* 1: some of each has a stale callback */
    double range[2];
    /* the plan, by position: read-unit index, range, absent */
    uint64_t *idx, *off, *len;
    unsigned char *missing;
    uint64_t *fetch, nfetch; /* positions to fetch, in order */
    /* runs: chunks of one object whose byte ranges follow each other, one
     * request each: run r is fetch[rfirst[r] .. rfirst[r] + rcount[r]) of
     * the order sorted by object and offset (order), bytes [roff, roff + rlen) */
    uint64_t *order, *rfirst, *rcount, *roff, *rlen, nrun;
    uint64_t *direct; /* positions absent (the fill value) */
    uint64_t ndirect;
    atomic_ullong next_direct;
    uint64_t max;      /* the most encoded bytes a read unit may take */
    uint64_t estimate; /* reserved for a unit whose size is not known */
    int window;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    uint64_t next_fetch, held, limit; /* next_fetch: the next run */
    zb_win *head, *tail;
    int fetchers_live, abort;
    long long first; /* the first failing position */
    vv_status first_status;
    char first_msg[1024];
} zb_job;

/* A failure at plan position @p pos kept when it is the first (mu held). */
static void
fail_locked(zb_job *j, uint64_t pos, vv_status s, const char *msg) {
    if (j->first < 0 || (long long)pos < j->first) {
        j->first = (long long)pos;
        j->first_status = s;
        snprintf(j->first_msg, sizeof j->first_msg, "%.1000s", msg);
    }
    j->abort = 1;
    pthread_cond_broadcast(&j->cv);
}

static void
win_free(zb_win *w) {
    if (!w)
        return;
    for (int i = 0; w->g && i < w->n; i++)
        free(w->g[i].out);
    free(w->run);
    free(w->g);
    free(w->ask);
    free(w->keys);
    free(w);
}

/* The bytes reserved for run @p r in flight. */
static uint64_t
reserve(const zb_job *j, uint64_t r) {
    return j->rlen[r] != ZR_ALL ? j->rlen[r] : j->estimate;
}

/* 1 when chunk @p p's caller wants it no more (zr_dest.stale). */
static int
unwanted(const zb_job *j, uint64_t p) {
    const zr_dest *d = j->each ? &j->each[p] : NULL;
    return d && d->stale && d->stale(d->stale_u, d->stale_i);
}

/* bs_get.stale of a run: 1 when none of its chunks is wanted. */
static int
run_stale(void *u) {
    const zb_ask *a = u;
    const zb_job *j = a->j;
    for (uint64_t k = 0; k < j->rcount[a->r]; k++)
        if (!unwanted(j, j->fetch[j->order[j->rfirst[a->r] + k]]))
            return 0;
    return 1;
}

/* A fetching thread: windows of the plan in order, each put in flight
 * whole (a run none of whose chunks is wanted any more dropped: not
 * sent, or abandoned in flight), then queued for the decoders. */
static void *
fetcher(void *u) {
    zb_job *j = u;
    const zr_array *a = j->J->a;
    pthread_mutex_lock(&j->mu);
    while (!j->abort && j->next_fetch < j->nrun) {
        /* the window: up to j->window chunks within the limit (one at least) */
        uint64_t w = 0, need = 0;
        while (j->next_fetch + w < j->nrun && w < (uint64_t)j->window) {
            const uint64_t r = reserve(j, j->next_fetch + w);
            if (w > 0 && need + r > j->limit)
                break;
            need += r;
            w++;
        }
        if (j->held > 0 && j->held + need > j->limit) {
            pthread_cond_wait(&j->cv, &j->mu); /* the decoders free some first */
            continue;
        }
        const uint64_t at = j->next_fetch;
        j->next_fetch += w;
        j->held += need;
        pthread_mutex_unlock(&j->mu);
        zb_win *win = calloc(1, sizeof *win);
        vv_status s = VV_OK;
        if (win) {
            win->n = (int)w;
            win->run = malloc(w * sizeof *win->run);
            win->g = calloc(w, sizeof *win->g);
            win->ask = calloc(w, sizeof *win->ask);
            win->keys = malloc(w * ZB_KEY);
        }
        if (!win || !win->run || !win->g || !win->ask || !win->keys)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory for %llu chunk reads",
                             (unsigned long long)w);
        for (uint64_t i = 0; s == VV_OK && i < w; i++) {
            const uint64_t r = at + i, p = j->fetch[j->order[j->rfirst[r]]];
            uint64_t top[ZR_MAX_DIM];
            const uint64_t *x = j->idx + p * ZR_MAX_DIM;
            for (int d = 0; d < a->ndim; d++) /* the shard's position when sharded */
                top[d] = a->nshard ? x[d] * a->chunks[d] / a->cshape[0][d] : x[d];
            char *key = win->keys + i * ZB_KEY;
            zr_chunk_key(a, top, key, ZB_KEY);
            win->run[i] = r;
            win->members += j->rcount[r];
            /* one chunk: at most what its codecs make of it; a run: its exact bytes */
            win->ask[i] = (zb_ask){j, r};
            win->g[i] = (bs_get){.key = key,
                                 .off = j->roff[r],
                                 .len = j->rlen[r],
                                 .max = j->rcount[r] > 1 ? j->rlen[r] : j->max,
                                 .stale = j->stale ? run_stale : NULL,
                                 .stale_u = &win->ask[i]};
        }
        if (s == VV_OK)
            s = zr_store_get_many(a, win->g, (int)w);
        pthread_mutex_lock(&j->mu);
        j->held -= need;
        if (s != VV_OK) {
            fail_locked(j, j->fetch[j->order[j->rfirst[at]]], s, vv_error_message());
            pthread_mutex_unlock(&j->mu);
            win_free(win);
            pthread_mutex_lock(&j->mu);
            continue;
        }
        win->left = win->members;
        for (int i = 0; i < win->n; i++)
            win->held += win->g[i].n;
        j->held += win->held;
        if (j->tail)
            j->tail->next = win;
        else
            j->head = win;
        j->tail = win;
        pthread_cond_broadcast(&j->cv);
    }
    j->fetchers_live--;
    pthread_cond_broadcast(&j->cv);
    pthread_mutex_unlock(&j->mu);
    return NULL;
}

/* Position @p p's chunk (of read @p g; NULL: absent) decoded from its
 * @p m bytes at @p src with scratch @p buf and copied into place; a
 * failure kept. */
static void
decode_one(zb_job *j, uint64_t p, const bs_get *g, const unsigned char *src, size_t m,
           unsigned char *buf, double *range) {
    const zr_layout *J = j->J;
    const uint64_t *x = j->idx + p * ZR_MAX_DIM;
    vv_status s = VV_OK;
    const int missing = !g || g->missing;
    if (!buf)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory for a chunk of %zu bytes", J->cbytes);
    else if (!missing) {
        char what[ZB_KEY + 64];
        if (sharded(J->a))
            snprintf(what, sizeof what, "%s: inner chunk at bytes %llu..%llu", g->key,
                     (unsigned long long)j->off[p], (unsigned long long)(j->off[p] + j->len[p]));
        else
            snprintf(what, sizeof what, "%s", g->key);
        s = vv_zr_decode_unit(J->a, x, src, m, buf, J->cbytes, what);
    }
    zr_dest *d = j->each ? &j->each[p] : NULL;
    if (s == VV_OK && d) {
        d->missing = missing;
        d->file_bytes = missing ? 0 : m;
        vv_zr_place_unit(J, x, buf, missing, d->dst, d->org, d->dims, d->range);
    } else if (s == VV_OK)
        vv_zr_place_unit(J, x, buf, missing, j->dst, j->dorg, j->ddims, range);
    else {
        pthread_mutex_lock(&j->mu);
        fail_locked(j, p, s, vv_error_message());
        pthread_mutex_unlock(&j->mu);
    }
}

/* A decoding thread: the absent chunks, then the windows as they come;
 * the value range of what it copied merged into the job's at the end. */
static void *
decoder(void *u) {
    zb_job *j = u;
    double range[2] = {INFINITY, -INFINITY};
    unsigned char *buf = malloc(j->J->cbytes);
    for (uint64_t k; (k = atomic_fetch_add(&j->next_direct, 1)) < j->ndirect;)
        decode_one(j, j->direct[k], NULL, NULL, 0, buf, range);
    pthread_mutex_lock(&j->mu);
    for (;;) {
        zb_win *w = j->head;
        while (w && w->taken == w->members)
            w = w->next;
        if (!w) {
            if (j->fetchers_live == 0)
                break;
            pthread_cond_wait(&j->cv, &j->mu);
            continue;
        }
        /* member k of the window: its run, its place in the run */
        uint64_t k = w->taken++;
        int i = 0;
        while (k >= j->rcount[w->run[i]])
            k -= j->rcount[w->run[i++]];
        const int skip = j->abort;
        pthread_mutex_unlock(&j->mu);
        const uint64_t r = w->run[i], p = j->fetch[j->order[j->rfirst[r] + k]];
        const bs_get *g = &w->g[i];
        if (!skip && g->cancelled) /* nobody wanted it: not read */
            j->each[p].cancelled = 1;
        else if (!skip && g->missing) /* the object went since its index was read */
            decode_one(j, p, NULL, NULL, 0, buf, range);
        else if (!skip && j->rcount[r] == 1)
            decode_one(j, p, g, g->out, g->n, buf, range);
        else if (!skip && j->off[p] - j->roff[r] + j->len[p] <= g->n)
            decode_one(j, p, g, g->out + (j->off[p] - j->roff[r]), (size_t)j->len[p], buf, range);
        else if (!skip) {
            pthread_mutex_lock(&j->mu);
            char msg[ZB_KEY + 64];
            snprintf(msg, sizeof msg, "%s: %zu bytes, not the range asked", g->key, g->n);
            fail_locked(j, p, VV_ERR_FORMAT, msg);
            pthread_mutex_unlock(&j->mu);
        }
        pthread_mutex_lock(&j->mu);
        if (--w->left == 0) { /* every chunk of it decoded: gone */
            j->held -= w->held;
            zb_win **pp = &j->head, *prev = NULL;
            while (*pp != w) {
                prev = *pp;
                pp = &(*pp)->next;
            }
            *pp = w->next;
            if (j->tail == w)
                j->tail = prev;
            win_free(w);
        }
        pthread_cond_broadcast(&j->cv);
    }
    j->range[0] = range[0] < j->range[0] ? range[0] : j->range[0];
    j->range[1] = range[1] > j->range[1] ? range[1] : j->range[1];
    pthread_mutex_unlock(&j->mu);
    free(buf);
    return NULL;
}

/* The chunk by chunk read (a local store; nested shards): @p nthreads
 * threads, each its own buffer; the first failure in order. */
static vv_status
copy_each(const zr_layout *J, const uint64_t *L, uint64_t n, unsigned char *dst, const int dorg[3],
          const int ddims[3], zr_dest *each, int nthreads, double *range) {
    long long first = -1;
    vv_status first_status = VV_OK;
    char first_msg[1024] = "";
    double all[2] = {INFINITY, -INFINITY};
#pragma omp parallel num_threads(nthreads)
    {
        unsigned char *buf = malloc(J->cbytes);
        double mine[2] = {INFINITY, -INFINITY};
#pragma omp for schedule(dynamic, 1)
        for (long long i = 0; i < (long long)n; i++) {
            const uint64_t c = L ? L[i] : (uint64_t)i;
            zr_dest *d = each ? &each[i] : NULL;
            if (d && d->stale && d->stale(d->stale_u, d->stale_i)) {
                d->cancelled = 1; /* nobody wants it any more */
                continue;
            }
            vv_status cs = !buf ? vv_error_set(VV_ERR_NOMEM,
                                               "out of memory for a chunk of %zu bytes", J->cbytes)
                           : d  ? vv_zr_copy_chunk(J, c, buf, d->dst, d->org, d->dims, &d->missing,
                                                   &d->file_bytes, d->range)
                                : vv_zr_copy_chunk(J, c, buf, dst, dorg, ddims, NULL, NULL,
                                                  range ? mine : NULL);
            if (cs != VV_OK) {
#pragma omp critical(vv_zarr_err)
                if (first < 0 || i < first) {
                    first = i;
                    first_status = cs;
                    snprintf(first_msg, sizeof first_msg, "%s", vv_error_message());
                }
            }
        }
        free(buf);
#pragma omp critical(vv_zarr_range)
        {
            all[0] = mine[0] < all[0] ? mine[0] : all[0];
            all[1] = mine[1] > all[1] ? mine[1] : all[1];
        }
    }
    if (first >= 0)
        return vv_error_set(first_status, "%s", first_msg);
    if (range) {
        range[0] = all[0] < range[0] ? all[0] : range[0];
        range[1] = all[1] > range[1] ? all[1] : range[1];
    }
    return VV_OK;
}

/* A chunk to fetch by its object and offset; a run by the first chunk
 * asked of it. */
typedef struct zb_key {
    uint64_t obj, off, i;
} zb_key;

static int
cmp_key(const void *x, const void *y) {
    const zb_key *a = x, *b = y;
    if (a->obj != b->obj)
        return a->obj < b->obj ? -1 : 1;
    if (a->off != b->off)
        return a->off < b->off ? -1 : 1;
    return a->i < b->i ? -1 : a->i > b->i;
}

typedef struct zb_run {
    uint64_t first, count, off, len, min;
} zb_run;

static int
cmp_run(const void *x, const void *y) {
    const zb_run *a = x, *b = y;
    return a->min < b->min ? -1 : a->min > b->min;
}

/* The runs of @p j's chunks to fetch: a sharded array's inner chunks whose
 * bytes follow each other in one shard merged (at most a quarter of
 * the read over the requests in flight, within ZB_RUN_MIN .. ZB_RUN_MAX
 * bytes, and ZB_RUN_CHUNKS chunks: one request where zarr-python writes a
 * shard's chunks back to back; never a byte more than the chunks'), the
 * runs ordered by the first chunk asked of each (the caller's order kept);
 * every other chunk a run of its own. */
static vv_status
runs(zb_job *j) {
    const zr_array *a = j->J->a;
    const uint64_t n = j->nfetch;
    j->order = malloc((n ? n : 1) * sizeof *j->order);
    j->rfirst = malloc((n ? n : 1) * sizeof *j->rfirst);
    j->rcount = malloc((n ? n : 1) * sizeof *j->rcount);
    j->roff = malloc((n ? n : 1) * sizeof *j->roff);
    j->rlen = malloc((n ? n : 1) * sizeof *j->rlen);
    zb_key *k = malloc((n ? n : 1) * sizeof *k);
    zb_run *r = malloc((n ? n : 1) * sizeof *r);
    vv_status s = j->order && j->rfirst && j->rcount && j->roff && j->rlen && k && r
                      ? VV_OK
                      : vv_error_set(VV_ERR_NOMEM, "out of memory for %llu chunk reads",
                                     (unsigned long long)n);
    for (uint64_t i = 0; s == VV_OK && i < n; i++) {
        const uint64_t p = j->fetch[i], *x = j->idx + p * ZR_MAX_DIM;
        uint64_t obj = pc_sharded(a) ? zr_pc_shard_of(a, x) : 0;
        for (int d = 0; a->nshard == 1 && d < a->ndim; d++) {
            const uint64_t grid = (a->shape[d] + a->cshape[0][d] - 1) / a->cshape[0][d];
            obj = obj * grid + x[d] * a->chunks[d] / a->cshape[0][d];
        }
        k[i] = (zb_key){sharded(a) ? obj : i, j->off[p], i};
    }
    if (s == VV_OK && sharded(a))
        qsort(k, (size_t)n, sizeof *k, cmp_key);
    /* a run's bytes: at most ZB_RUN_MAX, and small enough that the read is
     * four requests in flight deep (a few large runs would leave the
     * connections idle and the decoders waiting), at least ZB_RUN_MIN */
    uint64_t total = 0;
    for (uint64_t i = 0; s == VV_OK && sharded(a) && i < n; i++)
        total += j->len[j->fetch[i]];
    uint64_t cap = total / (4 * (uint64_t)bs_http_in_flight());
    cap = cap < ZB_RUN_MIN ? ZB_RUN_MIN : cap > ZB_RUN_MAX ? ZB_RUN_MAX : cap;
    uint64_t nr = 0;
    for (uint64_t i = 0; s == VV_OK && i < n; i++) {
        const uint64_t p = j->fetch[k[i].i];
        j->order[i] = k[i].i;
        zb_run *last = nr ? &r[nr - 1] : NULL;
        const uint64_t lp = last ? j->fetch[k[i - 1].i] : 0;
        if (last && sharded(a) && k[i].obj == k[i - 1].obj && j->len[p] != ZR_ALL &&
            j->off[p] == j->off[lp] + j->len[lp] && last->len + j->len[p] <= cap &&
            last->count < ZB_RUN_CHUNKS) {
            last->count++;
            last->len += j->len[p];
            last->min = k[i].i < last->min ? k[i].i : last->min;
        } else {
            r[nr++] = (zb_run){i, 1, j->off[p], j->len[p], k[i].i};
        }
    }
    if (s == VV_OK)
        qsort(r, (size_t)nr, sizeof *r, cmp_run);
    for (uint64_t i = 0; s == VV_OK && i < nr; i++) {
        j->rfirst[i] = r[i].first;
        j->rcount[i] = r[i].count;
        j->roff[i] = r[i].off;
        j->rlen[i] = r[i].len;
    }
    j->nrun = s == VV_OK ? nr : 0;
    free(k);
    free(r);
    return s;
}

/* The remote read's plan into @p j: each chunk's read unit and range, the
 * shard indexes read first, the runs. */
static vv_status
plan(zb_job *j, uint64_t n) {
    const zr_array *a = j->J->a;
    j->idx = malloc(n * ZR_MAX_DIM * sizeof *j->idx);
    j->off = malloc(n * sizeof *j->off);
    j->len = malloc(n * sizeof *j->len);
    j->missing = calloc(n, 1);
    j->fetch = malloc(n * sizeof *j->fetch);
    j->direct = malloc(n * sizeof *j->direct);
    if (!j->idx || !j->off || !j->len || !j->missing || !j->fetch || !j->direct)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %llu chunk reads",
                            (unsigned long long)n);
    for (uint64_t i = 0; i < n; i++) {
        vv_zr_unit_index(j->J, j->L ? j->L[i] : i, j->idx + i * ZR_MAX_DIM);
        j->off[i] = 0;
        j->len[i] = ZR_ALL; /* an unsharded chunk: its whole object */
    }
    if (sharded(a)) {
        const vv_status s = a->nshard == 1
                                ? zr3_locate_many(a, n, j->idx, j->off, j->len, j->missing,
                                                  bs_http_in_flight(), NULL)
                                : zr_pc_locate_many(a, n, j->idx, j->off, j->len, j->missing);
        if (s != VV_OK)
            return s;
    }
    for (uint64_t i = 0; i < n; i++) {
        if (j->missing[i])
            j->direct[j->ndirect++] = i;
        else
            j->fetch[j->nfetch++] = i;
    }
    return runs(j);
}

vv_status
vv_zr_copy_chunks(const zr_layout *J, const uint64_t *L, uint64_t n, unsigned char *dst,
                  const int dorg[3], const int ddims[3], zr_dest *each, int nthreads,
                  double *range) {
    const zr_array *a = J->a;
    if (nthreads < 1)
        nthreads = 1;
    if (!bs_is_url(a->root) || n == 0 || (a->zarr_format == 3 && a->nshard > 1))
        return copy_each(J, L, n, dst, dorg, ddims, each, nthreads, range); /* chunk by chunk */
    zb_job j = {.J = J,
                .L = L,
                .dst = dst,
                .dorg = dorg,
                .ddims = ddims,
                .each = each,
                .range = {INFINITY, -INFINITY},
                .first = -1};
    for (uint64_t i = 0; each && i < n; i++)
        j.stale |= each[i].stale != NULL;
    atomic_init(&j.next_direct, 0);
    pthread_mutex_init(&j.mu, NULL);
    pthread_cond_init(&j.cv, NULL);
    /* the encoded bytes a unit may take; what one whose size is not known
     * is reserved (its decoded size and an eighth: what a compressor that
     * does not compress adds) */
    j.max = a->zarr_format == 3 ? zr3_encoded_max(&a->chain[a->nshard], J->cbytes) : ZR_CHUNK_MAX;
    j.estimate = (uint64_t)J->cbytes + J->cbytes / 8 + 4096;
    if (j.estimate > j.max)
        j.estimate = j.max;
    j.limit = vv_memory_budget_get() / 4;
    const int flight = bs_http_in_flight();
    const int nf = flight >= ZB_FETCHERS ? ZB_FETCHERS : 1;
    j.window = flight / nf;
    vv_status s = plan(&j, n);
    pthread_t th[ZB_FETCHERS], dt[64];
    int started = 0, decoders = 0;
    if (s == VV_OK) {
        pthread_mutex_lock(&j.mu);
        for (int f = 0; f < nf; f++)
            if (pthread_create(&th[started], NULL, fetcher, &j) == 0)
                started++;
        j.fetchers_live = started;
        pthread_mutex_unlock(&j.mu);
        if (!started)
            s = vv_error_set(VV_ERR_NOMEM, "cannot start the fetching threads");
    }
    if (s == VV_OK) {
        /* decoding threads of our own: OpenMP would give one inside a
         * renderer's parallel region; the caller's thread is the first */
        for (int t = 1; t < nthreads && t < 64; t++)
            if (pthread_create(&dt[decoders], NULL, decoder, &j) == 0)
                decoders++;
        decoder(&j);
        for (int t = 0; t < decoders; t++)
            pthread_join(dt[t], NULL);
        for (int f = 0; f < started; f++)
            pthread_join(th[f], NULL);
        if (j.first >= 0)
            s = vv_error_set(j.first_status, "%s", j.first_msg);
        else if (range) {
            range[0] = j.range[0] < range[0] ? j.range[0] : range[0];
            range[1] = j.range[1] > range[1] ? j.range[1] : range[1];
        }
    }
    while (j.head) { /* after a failure: what was not decoded */
        zb_win *w = j.head;
        j.head = w->next;
        win_free(w);
    }
    free(j.idx);
    free(j.off);
    free(j.len);
    free(j.missing);
    free(j.fetch);
    free(j.direct);
    free(j.order);
    free(j.rfirst);
    free(j.rcount);
    free(j.roff);
    free(j.rlen);
    pthread_cond_destroy(&j.cv);
    pthread_mutex_destroy(&j.mu);
    return s;
}
