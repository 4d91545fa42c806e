/*
 * Multiresolution pyramids out of core (src/io/store/pyramid.h, vv_pyramid; a
 * source of kind VV_SOURCE_PYRAMID, include/volvis/source.h): the levels
 * of one channel at one time step of an OME-Zarr store, a BigDataViewer /
 * Imaris HDF5 file or a .vvb with levels (their stores, src/io/store/pyramid.h),
 * read by boxes of voxels through the process's one cache of decoded
 * pieces (src/core/cache.h), within its budget.
 *
 * Here, its chunks and boxes: a box of a level is assembled from the
 * chunks it overlaps: those in the cache are used as they are, the others
 * are fetched from the store (decoded on every core when the store allows,
 * one scratch buffer a thread) and kept, least recently used first out.
 * The min and max of every chunk decoded are remembered (a few bytes a
 * chunk), so a later frame skips transparent boxes unread. Each chunk's
 * reads within one frame are counted (frames are marked by the renderer
 * through the source's frame method). Also the levels' geometry, the
 * statistics, and a store's level read whole (vv_store_read_level).
 *
 * Above it, calling down: the frame's plan, which chooses the chunk
 * evicted and fetches chunks ahead, the loader (vv_pyramid_request) and
 * the multiresolution source interface (pyramid_load.c); opening, which
 * reads the metadata only (the store's) and the coarsest level, and
 * freeing (pyramid_open.c). The state the three files share is in
 * pyramid_internal.h. One mutex, the cache's, guards the chunks, the plan,
 * the queue and the statistics; reading and decoding run outside it.
 */
#include <limits.h>
#include <malloc.h>
#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "core/cache.h"
#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/pyramid.h"
#include "io/store/pyramid_internal.h"
#include "volvis/bricks.h"

/* Chunk @p c out of the pyramid's index and freed (out of the cache
 * already). */
static void
free_chunk(vv_pyramid *p, py_chunk *c) {
    py_chunk **pp = &p->bucket[py_bucket_of(c->level, c->L)];
    while (*pp != c)
        pp = &(*pp)->hnext;
    *pp = c->hnext;
    p->n_ready -= c->state == PY_READY;
    vv_volume_free(c->blk);
    free(c);
}

/* Chunk @p c out of the cache and the index (lock held). */
void
py_drop_chunk(vv_pyramid *p, py_chunk *c) {
    vv_cache_remove(p->cache, &c->ce);
    free_chunk(p, c);
}

/* The cache evicts chunk @p e to make room (for this pyramid or another
 * source): out of the index (lock held). */
void
py_client_drop(vv_cache_client *cl, vv_cache_entry *e) {
    vv_pyramid *p = (vv_pyramid *)((char *)cl - offsetof(vv_pyramid, cl));
    free_chunk(p, (py_chunk *)e);
    p->st.evictions++;
}

/* The chunk box of chunk position c: its first voxel and size inside the level. */
static void
chunk_box(const py_level *l, const int c[3], int org[3], int n[3]) {
    for (int k = 0; k < 3; k++) {
        org[k] = c[k] * l->cdims[k];
        const int e = org[k] + l->cdims[k];
        n[k] = (e > l->dims[k] ? l->dims[k] : e) - org[k];
    }
}

/* Notes a read of chunk L of level @p level in this frame. */
static void
count_read(vv_pyramid *p, int level, uint64_t L, uint64_t file_bytes) {
    py_level *l = &p->lv[level];
    p->st.chunk_reads[level]++;
    p->st.bytes_read += file_bytes;
    if (!l->read_frame)
        return;
    if (l->read_frame[L] != p->frame) {
        l->read_frame[L] = p->frame;
        l->frame_reads[L] = 0;
    }
    if (l->frame_reads[L] < UINT16_MAX)
        l->frame_reads[L]++;
    if (l->frame_reads[L] > p->st.max_reads_per_frame)
        p->st.max_reads_per_frame = l->frame_reads[L];
}

/* The voxels of one channel of entry @p c, bytes. */
static size_t
plane_bytes(const py_chunk *c) {
    return (size_t)c->n[0] * (size_t)c->n[1] * (size_t)c->n[2] * vv_voxel_type_size(c->blk->type);
}

/* Entry @p c's block read: each channel's range measured into c->rng
 * (one channel: the block's own range too). */
static void
measure_block(const vv_pyramid *p, py_chunk *c) {
    if (p->n_ch <= 1) {
        vv_volume_update_range(c->blk);
        c->rng[0][0] = (float)c->blk->range[0];
        c->rng[0][1] = (float)c->blk->range[1];
        return;
    }
    const size_t pb = plane_bytes(c), n = pb / vv_voxel_type_size(c->blk->type);
    double all[2] = {INFINITY, -INFINITY};
    for (int k = 0; k < p->n_ch; k++) {
        double r[2] = {INFINITY, -INFINITY};
        vv_range_accumulate(c->blk->type, (const unsigned char *)c->blk->data + (size_t)k * pb, n,
                            r);
        c->rng[k][0] = (float)r[0];
        c->rng[k][1] = (float)r[1];
        all[0] = r[0] < all[0] ? r[0] : all[0];
        all[1] = r[1] > all[1] ? r[1] : all[1];
    }
    vv_volume_set_range(c->blk, all);
}

/* Chunk entry @p c (position @p cc) read from the store into its block,
 * one reader at a time when the store is not parallel; any thread, the
 * pyramid's lock not held. */
vv_status
py_read_chunk(vv_pyramid *p, py_chunk *c, const int cc[3], unsigned char *scratch, int *missing,
              uint64_t *file_bytes) {
    const vv_store *st = &p->store;
    if (!st->parallel)
        pthread_mutex_lock(&p->store_lock);
    const vv_status s = st->read_chunk(st->ctx, c->level, cc, scratch, c->blk->data, c->org, c->n,
                                       missing, file_bytes);
    if (!st->parallel)
        pthread_mutex_unlock(&p->store_lock);
    if (s == VV_OK)
        measure_block(p, c);
    return s;
}

/* A batch of chunks being read: the next to take, the first failure in order. */
typedef struct dc_job {
    vv_pyramid *p;
    py_chunk **todo;
    int n;
    uint64_t *file_bytes;
    int *missing;
    atomic_int next;
    pthread_mutex_t lock;
    long long first;
    vv_status first_status;
    char first_msg[1024];
} dc_job;

/* Chunk @p i of @p j read with scratch @p buf; a failure kept when it is
 * the first in order. */
static void
dc_one(dc_job *j, int i, unsigned char *buf) {
    const vv_store *st = &j->p->store;
    py_chunk *c = j->todo[i];
    const py_level *cl = &j->p->lv[c->level];
    int cc[3];
    for (int k = 0; k < 3; k++)
        cc[k] = c->org[k] / cl->cdims[k];
    vv_status cs =
        buf || !st->scratch
            ? py_read_chunk(j->p, c, cc, buf, &j->missing[i], &j->file_bytes[i])
            : vv_error_set(VV_ERR_NOMEM, "out of memory for a chunk of %zu bytes", st->scratch);
    if (cs != VV_OK) {
        pthread_mutex_lock(&j->lock);
        if (j->first < 0 || i < j->first) {
            j->first = i;
            j->first_status = cs;
            snprintf(j->first_msg, sizeof j->first_msg, "%s", vv_error_message());
        }
        pthread_mutex_unlock(&j->lock);
    }
}

/* A thread of a store whose reads wait on the network: chunks of @p u
 * taken one at a time until none is left. */
static void *
dc_worker(void *u) {
    dc_job *j = u;
    const vv_store *st = &j->p->store;
    unsigned char *buf = st->scratch ? malloc(st->scratch) : NULL;
    for (int i; (i = atomic_fetch_add(&j->next, 1)) < j->n;)
        dc_one(j, i, buf);
    free(buf);
    return NULL;
}

/* read_many's stale for a loader's window (py_read_many). */
typedef struct py_ask {
    vv_pyramid *p;
    py_chunk **chunks;
} py_ask;

static int
py_stale(void *u, int i) {
    const py_ask *a = u;
    pthread_mutex_lock(a->p->lock);
    const py_chunk *e = a->chunks[i];
    const int stale = e->ce.pins <= 1 && e->ce.want != a->p->cl.want;
    pthread_mutex_unlock(a->p->lock);
    return stale;
}

vv_status
py_read_many(vv_pyramid *p, py_chunk **chunks, int n, int nthreads, uint64_t *file_bytes,
             int *missing, int *cancelled) {
    const vv_store *st = &p->store;
    if (n < 1)
        return VV_OK;
    const int nch = p->n_ch > 1 ? p->n_ch : 1;
    int *c = calloc(9 * (size_t)n, sizeof(int));
    unsigned char **dst = calloc((size_t)n, sizeof *dst);
    double *range = calloc(2 * (size_t)n * (size_t)nch, sizeof *range);
    if (!c || !dst || !range) {
        free(c);
        free(dst);
        free(range);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %d chunks", n);
    }
    int *org = c + 3 * n, *dims = c + 6 * n;
    const py_level *l = &p->lv[chunks[0]->level];
    for (int i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) {
            c[3 * i + k] = chunks[i]->org[k] / l->cdims[k];
            org[3 * i + k] = chunks[i]->org[k];
            dims[3 * i + k] = chunks[i]->n[k];
        }
        dst[i] = chunks[i]->blk->data;
    }
    py_ask ask = {p, chunks};
    if (cancelled)
        memset(cancelled, 0, sizeof *cancelled * (size_t)n);
    const vv_status s =
        st->read_many(st->ctx, chunks[0]->level, n, c, dst, org, dims, nthreads, missing,
                      file_bytes, range, cancelled ? py_stale : NULL, &ask, cancelled);
    for (int i = 0; s == VV_OK && i < n; i++) { /* taken as the store copied them in */
        if (cancelled && cancelled[i])
            continue;
        double all[2] = {INFINITY, -INFINITY};
        for (int k = 0; k < nch; k++) {
            const double *r = range + 2 * ((size_t)i * (size_t)nch + (size_t)k);
            chunks[i]->rng[k][0] = (float)r[0];
            chunks[i]->rng[k][1] = (float)r[1];
            all[0] = r[0] < all[0] ? r[0] : all[0];
            all[1] = r[1] > all[1] ? r[1] : all[1];
        }
        vv_volume_set_range(chunks[i]->blk, all);
    }
    free(c);
    free(dst);
    free(range);
    return s;
}

/* The chunks of @p chunks (n >= 2, one level) through the store's read_many,
 * decoded on every core. */
static vv_status
read_many(vv_pyramid *p, py_chunk **chunks, int n, uint64_t *file_bytes, int *missing) {
    int nthreads = vv_threads_get();
    /* each decoding thread holds a chunk's scratch: at most a quarter of the budget */
    const uint64_t quarter = vv_memory_budget_get() / 4, per = p->store.scratch;
    if (per && (uint64_t)nthreads * per > quarter)
        nthreads = quarter / per > 1 ? (int)(quarter / per) : 1;
    return py_read_many(p, chunks, n, nthreads < 1 ? 1 : nthreads, file_bytes, missing, NULL);
}

/* Fetches the chunks in @p todo (n >= 1 of them, their blocks allocated)
 * from the store, on every core when it allows, file bytes and missing
 * flags per chunk into @p file_bytes and @p missing; the first failing
 * chunk's error in order. A store whose reads wait on the network
 * (parallel > 1) is read by that many threads of our own: OpenMP would
 * give one thread inside a renderer's parallel region. */
static vv_status
decode_chunks(vv_pyramid *p, py_chunk **todo, int n, uint64_t *file_bytes, int *missing) {
    const vv_store *st = &p->store;
    int one_level = 1;
    for (int i = 1; i < n; i++)
        one_level &= todo[i]->level == todo[0]->level;
    if (st->read_many && n > 1 && one_level)
        /* the store fetches them together (a remote one: many requests in
         * flight) while the cores decode */
        return read_many(p, todo, n, file_bytes, missing);
    dc_job j = {.p = p,
                .todo = todo,
                .n = n,
                .file_bytes = file_bytes,
                .missing = missing,
                .first = -1,
                .first_status = VV_OK};
    atomic_init(&j.next, 0);
    pthread_mutex_init(&j.lock, NULL);
    const int big = st->scratch > ((size_t)64 << 20);
    if (st->parallel > 1 && !big && n > 1) {
        int want = st->parallel < n ? st->parallel : n;
        /* each thread holds a chunk's scratch: at most a quarter of the budget */
        const uint64_t quarter = vv_memory_budget_get() / 4;
        if (st->scratch && (uint64_t)want * st->scratch > quarter)
            want = quarter / st->scratch > 1 ? (int)(quarter / st->scratch) : 1;
        pthread_t th[64];
        int started = 0;
        for (int t = 1; t < want && t < 64; t++)
            if (pthread_create(&th[started], NULL, dc_worker, &j) == 0)
                started++;
        dc_worker(&j);
        for (int t = 0; t < started; t++)
            pthread_join(th[t], NULL);
    } else {
        const int nthreads = !st->parallel || big || n < 2 ? 1
                             : omp_get_max_threads() < n   ? omp_get_max_threads()
                                                           : n;
#pragma omp parallel num_threads(nthreads)
        {
            unsigned char *buf = st->scratch ? malloc(st->scratch) : NULL;
#pragma omp for schedule(dynamic, 1)
            for (int i = 0; i < n; i++)
                dc_one(&j, i, buf);
            free(buf);
        }
    }
    pthread_mutex_destroy(&j.lock);
    if (j.first >= 0)
        return vv_error_set(j.first_status, "%s", j.first_msg);
    return VV_OK;
}

/* Copies the part of channel @p ch of chunk block @p c inside box lo .. of @p out. */
static void
copy_block(const py_chunk *c, int ch, const int lo[3], vv_volume *out) {
    const size_t vs = vv_voxel_type_size(out->type);
    int a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = c->org[k] > lo[k] ? c->org[k] : lo[k];
        const int ce = c->org[k] + c->n[k] - 1, oe = lo[k] + out->dims[k] - 1;
        b[k] = ce < oe ? ce : oe;
    }
    const size_t n = (size_t)(b[0] - a[0] + 1) * vs;
    const unsigned char *src = (const unsigned char *)c->blk->data + (size_t)ch * plane_bytes(c);
    unsigned char *dst = out->data;
    for (int z = a[2]; z <= b[2]; z++)
        for (int y = a[1]; y <= b[1]; y++) {
            const size_t si =
                (((size_t)(z - c->org[2]) * (size_t)c->blk->dims[1] + (size_t)(y - c->org[1])) *
                     (size_t)c->blk->dims[0] +
                 (size_t)(a[0] - c->org[0])) *
                vs;
            const size_t di = (((size_t)(z - lo[2]) * (size_t)out->dims[1] + (size_t)(y - lo[1])) *
                                   (size_t)out->dims[0] +
                               (size_t)(a[0] - lo[0])) *
                              vs;
            memcpy(dst + di, src + si, n);
        }
}

/* A new cache entry for chunk @p c (position) of level @p level in state
 * PY_NEW, pinned once, not yet in the cache; NULL when out of memory. */
py_chunk *
py_new_entry(const vv_pyramid *p, int level, const int c[3]) {
    const py_level *l = &p->lv[level];
    py_chunk *e = calloc(1, sizeof *e);
    if (!e)
        return NULL;
    e->level = level;
    e->L = py_chunk_linear(l, c);
    chunk_box(l, c, e->org, e->n);
    e->bytes = (uint64_t)e->n[0] * (uint64_t)e->n[1] * (uint64_t)e->n[2] * l->esize *
               (uint64_t)(p->n_ch > 1 ? p->n_ch : 1);
    e->state = PY_NEW;
    e->ce.pins = 1;
    return e;
}

vv_status
py_alloc_block(const vv_pyramid *p, py_chunk *e) {
    const int d[3] = {e->n[0], e->n[1], e->n[2] * (p->n_ch > 1 ? p->n_ch : 1)};
    return vv_volume_new(&e->blk, d, p->lv[e->level].type);
}

/* Entry @p e into the cache (its bytes held, most recently used) and the
 * pyramid's index. */
void
py_insert_entry(vv_pyramid *p, py_chunk *e) {
    const unsigned b = py_bucket_of(e->level, e->L);
    e->use = p->cl.planned ? py_find_use(p, e->level, e->L) : NULL;
    e->hnext = p->bucket[b];
    p->bucket[b] = e;
    e->ce.ready = 1; /* a chunk being read stays pinned by its reader */
    vv_cache_insert(p->cache, &p->cl, &e->ce, e->bytes);
}

/* Entry @p e decoded (by this thread or a loader; lock held): ready, its
 * range known, the read counted. */
void
py_entry_ready(vv_pyramid *p, py_chunk *e, uint64_t file_bytes, int missing) {
    py_level *l = &p->lv[e->level];
    e->state = PY_READY;
    p->n_ready++;
    count_read(p, e->level, e->L, file_bytes);
    p->st.missing += (uint64_t)missing;
    if (l->known) {
        const int nch = p->n_ch > 1 ? p->n_ch : 1;
        for (int k = 0; k < nch; k++) {
            l->cmin[e->L * (uint64_t)nch + (uint64_t)k] = e->rng[k][0];
            l->cmax[e->L * (uint64_t)nch + (uint64_t)k] = e->rng[k][1];
        }
        l->known[e->L] = 1;
    }
    p->arrivals++;
}

/* Unpins entry @p e; a failed one nobody holds leaves the cache. */
void
py_unpin(vv_pyramid *p, py_chunk *e) {
    if (--e->ce.pins == 0 && e->state == PY_FAILED)
        py_drop_chunk(p, e);
}

/* Box lo .. hi of @p level into @p out[0 .. nout) (channels ch0 ..) from
 * the cache (lock held; it is released while chunks are decoded): the
 * chunks missing are reserved in the cache (PY_NEW) and decoded here,
 * those a loader is decoding are waited for, and one whose loader failed
 * is decoded again here. */
static vv_status
assemble(vv_pyramid *p, int level, const int lo[3], const int hi[3], int ch0, int nout,
         vv_volume **out) {
    py_level *l = &p->lv[level];
    int c0[3], c1[3];
    py_chunk_span(l, lo, hi, c0, c1);
    const int n = (c1[0] - c0[0] + 1) * (c1[1] - c0[1] + 1) * (c1[2] - c0[2] + 1);
    py_chunk **use = calloc((size_t)n, sizeof *use), **todo = calloc((size_t)n, sizeof *todo);
    uint64_t *fbytes = calloc((size_t)n, sizeof *fbytes);
    int *missing = calloc((size_t)n, sizeof *missing);
    vv_status s =
        use && todo && fbytes && missing ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    int nu = 0, nt = 0;
    uint64_t need = 0;
    /* the chunks: those held pinned, new entries for the others */
    for (int z = c0[2]; z <= c1[2] && s == VV_OK; z++)
        for (int y = c0[1]; y <= c1[1] && s == VV_OK; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                const int c[3] = {x, y, z};
                py_chunk *e = py_find_chunk(p, level, py_chunk_linear(l, c));
                if (e) {
                    vv_cache_touch(p->cache, &e->ce);
                    p->st.chunk_hits += e->state == PY_READY;
                    e->ce.pins++;
                } else if ((e = py_new_entry(p, level, c))) {
                    need += e->bytes;
                    todo[nt++] = e;
                } else {
                    s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                    break;
                }
                use[nu++] = e;
            }
    if (s == VV_OK && !vv_cache_make_room(p->cache, need, 0))
        s = vv_error_set(VV_ERR_LIMIT,
                         "memory limit of %llu bytes: the %d chunks of a box of level %d do not "
                         "fit",
                         (unsigned long long)p->limit, n, level);
    for (int i = 0; i < nu; i++) {
        if (s == VV_OK && use[i]->state == PY_NEW)
            py_insert_entry(p, use[i]);
        else if (s != VV_OK && use[i]->state == PY_NEW)
            free(use[i]); /* never in the cache */
        else if (s != VV_OK)
            py_unpin(p, use[i]);
    }
    if (s != VV_OK)
        nu = 0;
    /* decode the new and failed entries here; wait for the loaders' */
    while (s == VV_OK) {
        nt = 0;
        int waiting = 0;
        for (int i = 0; i < nu; i++) {
            py_chunk *e = use[i];
            if (e->state == PY_NEW || e->state == PY_FAILED) {
                e->state = PY_LOADING;
                vv_volume_free(e->blk);
                e->blk = NULL;
                if ((s = py_alloc_block(p, e)) != VV_OK)
                    e->state = PY_FAILED;
                todo[nt++] = e;
            } else if (e->state == PY_LOADING) {
                waiting = 1;
            }
        }
        if (s == VV_OK && nt > 0) {
            pthread_mutex_unlock(p->lock);
            s = decode_chunks(p, todo, nt, fbytes, missing);
            pthread_mutex_lock(p->lock);
        }
        for (int i = 0; i < nt; i++) {
            py_chunk *e = todo[i];
            if (s == VV_OK) {
                py_entry_ready(p, e, fbytes[i], missing[i]);
            } else {
                e->state = PY_FAILED;
                vv_volume_free(e->blk);
                e->blk = NULL;
            }
        }
        if (nt > 0)
            pthread_cond_broadcast(&p->arrived);
        if (s != VV_OK || (!waiting && nt == 0))
            break;
        if (waiting && nt == 0)
            pthread_cond_wait(&p->arrived, p->lock);
    }
    for (int i = 0; i < nu && s == VV_OK; i++)
        for (int k = 0; k < nout; k++)
            copy_block(use[i], ch0 + k, lo, out[k]);
    for (int i = 0; i < nu; i++)
        py_unpin(p, use[i]);
    free(use);
    free(todo);
    free(fbytes);
    free(missing);
    return s;
}

/* The header of a level: its geometry with channel @p ch's range. */
static void
set_geometry(vv_volume *v, const vv_pyramid *p, const py_level *l, int ch) {
    memcpy(v->spacing, l->hdr->spacing, sizeof v->spacing);
    memcpy(v->origin, l->hdr->origin, sizeof v->origin);
    memcpy(v->direction, l->hdr->direction, sizeof v->direction);
    v->unit = l->hdr->unit;
    v->modification = l->hdr->modification;
    v->range[0] = p->crange[ch][0];
    v->range[1] = p->crange[ch][1];
}

/* Box lo .. hi of @p level into a new volume; @p planned (not NULL): a
 * read of the frame's plan (the renderer's, through the multiresolution
 * view), called with the lock held once the box is assembled, which moves
 * the plan on and asks the store for the next boxes' chunks ahead
 * (pyramid_load.c); any other read (a slice, a measurement, another
 * thread) leaves the plan as it is. */
vv_status
py_box_read(vv_pyramid *p, int level, int channel, const int lo[3], const int hi[3],
            vv_volume **out, void (*planned)(vv_pyramid *p, vv_status s)) {
    const int nch = p && p->n_ch > 1 ? p->n_ch : 1;
    if (!p || !out || level < 0 || level >= p->n_levels || channel < -1 || channel >= nch)
        return vv_error_set(VV_ERR_INVALID, "pyramid: bad arguments");
    const int ch0 = channel < 0 ? 0 : channel, nout = channel < 0 ? nch : 1;
    for (int k = 0; k < nout; k++)
        out[k] = NULL;
    const py_level *l = &p->lv[level];
    int dims[3];
    for (int k = 0; k < 3; k++) {
        if (lo[k] < 0 || hi[k] < lo[k] || hi[k] >= l->dims[k])
            return vv_error_set(VV_ERR_INVALID, "pyramid: box %d..%d outside level %d's %d voxels",
                                lo[k], hi[k], level, l->dims[k]);
        dims[k] = hi[k] - lo[k] + 1;
    }
    vv_volume *v[VV_STORE_MAX_CHANNELS] = {NULL};
    vv_status s = VV_OK;
    for (int k = 0; k < nout && s == VV_OK; k++)
        s = vv_volume_new(&v[k], dims, l->type);
    pthread_mutex_lock(p->lock);
    if (s == VV_OK)
        s = assemble(p, level, lo, hi, ch0, nout, v);
    if (planned)
        planned(p, s);
    pthread_mutex_unlock(p->lock);
    if (s != VV_OK) {
        for (int k = 0; k < nout; k++)
            vv_volume_free(v[k]);
        return vv_pyramid_prefix(s, p->store.name, p->path);
    }
    for (int k = 0; k < nout; k++) {
        set_geometry(v[k], p, l, ch0 + k);
        out[k] = v[k];
    }
    return VV_OK;
}

vv_status
vv_pyramid_read_box(vv_pyramid *p, int level, const int lo[3], const int hi[3], vv_volume **out) {
    return py_box_read(p, level, 0, lo, hi, out, NULL);
}

int
vv_pyramid_channels(const vv_pyramid *p) {
    return p && p->n_ch > 1 ? p->n_ch : 1;
}

const vv_volume *
vv_pyramid_channel_level(const vv_pyramid *p, int channel, int level) {
    if (!p || level < 0 || level >= p->n_levels || channel < 0 || channel >= vv_pyramid_channels(p))
        return NULL;
    return channel == 0 ? p->lv[level].hdr : p->lv[level].chdr[channel];
}

vv_status
vv_pyramid_channel_read_box(vv_pyramid *p, int channel, int level, const int lo[3], const int hi[3],
                            vv_volume **out) {
    return py_box_read(p, level, channel, lo, hi, out, NULL);
}

vv_status
vv_pyramid_proxy(vv_pyramid *p, int level, vv_volume **out) {
    return vv_pyramid_channel_proxy(p, 0, level, out);
}

vv_status
vv_pyramid_channel_proxy(vv_pyramid *p, int channel, int level, vv_volume **out) {
    if (!p || !out || level < 0 || level >= p->n_levels)
        return vv_error_set(VV_ERR_INVALID, "pyramid: no level %d for a proxy", level);
    const int top = p->n_levels - 1;
    const vv_volume *h = p->lv[top].hdr, *f = p->lv[level].hdr;
    const int lo[3] = {0, 0, 0}, hi[3] = {h->dims[0] - 1, h->dims[1] - 1, h->dims[2] - 1};
    const vv_status s = py_box_read(p, top, channel, lo, hi, out, NULL);
    if (s != VV_OK)
        return s;
    vv_volume *v = *out;
    for (int k = 0; k < 3; k++) {
        v->origin[k] = f->origin[k];
        v->spacing[k] =
            h->dims[k] > 1 ? f->spacing[k] * (f->dims[k] - 1) / (h->dims[k] - 1) : f->spacing[k];
    }
    return VV_OK;
}

vv_status
vv_pyramid_level0_box(void *pyramid, const int lo[3], const int hi[3], vv_volume **out) {
    return vv_pyramid_read_box(pyramid, 0, lo, hi, out);
}

const char *
vv_pyramid_path(const vv_pyramid *p) {
    return p->path;
}

vv_cache *
vv_pyramid_cache(const vv_pyramid *p) {
    return p->cache;
}

int
vv_pyramid_levels(const vv_pyramid *p) {
    return p ? p->n_levels : 0;
}

const vv_volume *
vv_pyramid_level(const vv_pyramid *p, int level) {
    return p && level >= 0 && level < p->n_levels ? p->lv[level].hdr : NULL;
}

void
vv_pyramid_stats_get(const vv_pyramid *p, vv_pyramid_stats *st) {
    if (!p || !st)
        return;
    vv_pyramid *q = (vv_pyramid *)p; /* the lock only */
    pthread_mutex_lock(q->lock);
    *st = p->st;
    st->loading = p->q_n - p->q_pos + p->in_flight;
    st->stalled = p->stalled;
    st->held_bytes = p->cl.held;
    st->peak_bytes = p->cl.peak;
    st->resident = p->n_ready;
    st->limit_bytes = vv_cache_capacity(p->cache) + p->cl.reserve;
    pthread_mutex_unlock(q->lock);
}

vv_status
vv_store_read_level(vv_store *st, int level, vv_volume **out) {
    *out = NULL;
    if (!st || level < 0 || level >= st->n_levels || !st->lv[level].hdr)
        return vv_error_set(VV_ERR_INVALID, "store: no level %d", level);
    const vv_volume *h = st->lv[level].hdr;
    const int *cd = st->lv[level].cdims;
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, h->dims, h->type);
    if (s != VV_OK)
        return s;
    size_t chunk = vv_voxel_type_size(h->type);
    for (int k = 0; k < 3; k++)
        chunk *= (size_t)(cd[k] < h->dims[k] ? cd[k] : h->dims[k]);
    unsigned char *buf = malloc(chunk), *scratch = st->scratch ? malloc(st->scratch) : NULL;
    if (!buf || (st->scratch && !scratch))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    const size_t vs = vv_voxel_type_size(h->type);
    for (int z = 0; s == VV_OK && z * cd[2] < h->dims[2]; z++)
        for (int y = 0; s == VV_OK && y * cd[1] < h->dims[1]; y++)
            for (int x = 0; s == VV_OK && x * cd[0] < h->dims[0]; x++) {
                const int c[3] = {x, y, z}, org[3] = {x * cd[0], y * cd[1], z * cd[2]};
                int n[3];
                for (int k = 0; k < 3; k++)
                    n[k] = (org[k] + cd[k] > h->dims[k] ? h->dims[k] : org[k] + cd[k]) - org[k];
                int missing = 0;
                uint64_t bytes = 0;
                s = st->read_chunk(st->ctx, level, c, scratch, buf, org, n, &missing, &bytes);
                for (int kz = 0; s == VV_OK && kz < n[2]; kz++)
                    for (int ky = 0; ky < n[1]; ky++)
                        memcpy((unsigned char *)v->data +
                                   (((size_t)(org[2] + kz) * (size_t)h->dims[1] +
                                     (size_t)(org[1] + ky)) *
                                        (size_t)h->dims[0] +
                                    (size_t)org[0]) *
                                       vs,
                               buf + ((size_t)kz * (size_t)n[1] + (size_t)ky) * (size_t)n[0] * vs,
                               (size_t)n[0] * vs);
            }
    free(buf);
    free(scratch);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_take_geometry(v, h);
    v->modification = VV_MOD_ORIGINAL;
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

vv_status
vv_pyramid_prefix(vv_status s, const char *name, const char *path) {
    char head[512];
    const int n = snprintf(head, sizeof head, "%s: %s:", name, bs_name(path));
    if (n > 0 && n < (int)sizeof head && !strncmp(vv_error_message(), head, (size_t)n))
        return s;
    return vv_error_prefix(s, "%s: %s", name, bs_name(path));
}
