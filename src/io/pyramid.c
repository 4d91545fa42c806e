/*
 * Multiresolution pyramids out of core (src/io/pyramid.h, vv_pyramid; a
 * source of kind VV_SOURCE_PYRAMID, include/volvis/source.h): the levels
 * of one channel at one time step of an OME-Zarr store, a BigDataViewer /
 * Imaris HDF5 file or a .vvb with levels (their stores, src/io/pyramid.h),
 * read by boxes of voxels through the process's one cache of decoded
 * pieces (src/core/cache.h), within its budget.
 *
 * Opening reads the metadata only (the store's) and the coarsest level,
 * whose voxels give the proxy and, without a window in the metadata, the
 * value range. A box of a level is assembled from the chunks it overlaps:
 * those in the cache are used as they are, the others are fetched from the
 * store (decoded on every core when the store allows, one scratch buffer a
 * thread) and kept, least recently used first out. The min and max of every chunk decoded are
 * remembered (a few bytes a chunk), so a later frame skips transparent boxes unread. Each chunk's
 * reads within one frame are counted (frames are marked by the renderer through the source's frame
 * method).
 *
 * The frame's plan, which chooses the chunk evicted and fetches chunks
 * ahead, the loader (vv_pyramid_request) and the multiresolution source
 * interface are in pyramid_load.c; the state both files share, in
 * pyramid_internal.h. One mutex, the cache's, guards the chunks, the plan,
 * the queue and the statistics; reading and decoding run outside it.
 */
#include <limits.h>
#include <malloc.h>
#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "core/cache.h"
#include "core/internal.h"
#include "io/pyramid.h"
#include "io/pyramid_internal.h"
#include "volvis/bricks.h"

#define PY_MAX_LEVEL_CHUNKS ((uint64_t)1 << 26)

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
static void
drop_chunk(vv_pyramid *p, py_chunk *c) {
    vv_cache_remove(p->cache, &c->ce);
    free_chunk(p, c);
}

/* The cache evicts chunk @p e to make room (for this pyramid or another
 * source): out of the index (lock held). */
static void
client_drop(vv_cache_client *cl, vv_cache_entry *e) {
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

/* Chunk entry @p c (position @p cc) read from the store into its block,
 * one reader at a time when the store is not parallel; any thread, the
 * pyramid's lock not held. */
vv_status
py_read_chunk(vv_pyramid *p, py_chunk *c, const int cc[3], unsigned char *scratch, int *missing,
              uint64_t *file_bytes) {
    const vv_store *st = &p->store;
    if (!st->parallel)
        pthread_mutex_lock(&p->store_lock);
    const vv_status s = st->read_chunk(st->ctx, c->level, cc, scratch, c->blk->data, c->org,
                                       c->blk->dims, missing, file_bytes);
    if (!st->parallel)
        pthread_mutex_unlock(&p->store_lock);
    if (s == VV_OK)
        vv_volume_update_range(c->blk);
    return s;
}

/* Fetches the chunks in @p todo (n >= 1 of them, their blocks allocated)
 * from the store, on every core when it allows, file bytes and missing
 * flags per chunk into @p file_bytes and @p missing; the first failing
 * chunk's error in order. */
static vv_status
decode_chunks(vv_pyramid *p, py_chunk **todo, int n, uint64_t *file_bytes, int *missing) {
    const vv_store *st = &p->store;
    long long first = -1;
    vv_status first_status = VV_OK;
    char first_msg[1024] = "";
    const int nthreads = !st->parallel || st->scratch > ((size_t)64 << 20) || n < 2 ? 1
                         : omp_get_max_threads() < n ? omp_get_max_threads()
                                                     : n;
#pragma omp parallel num_threads(nthreads)
    {
        unsigned char *buf = st->scratch ? malloc(st->scratch) : NULL;
#pragma omp for schedule(dynamic, 1)
        for (int i = 0; i < n; i++) {
            py_chunk *c = todo[i];
            const py_level *cl = &p->lv[c->level];
            int cc[3];
            for (int k = 0; k < 3; k++)
                cc[k] = c->org[k] / cl->cdims[k];
            vv_status cs =
                buf || !st->scratch
                    ? py_read_chunk(p, c, cc, buf, &missing[i], &file_bytes[i])
                    : vv_error_set(VV_ERR_NOMEM, "out of memory for a chunk of %zu bytes",
                                   st->scratch);
            if (cs != VV_OK) {
#pragma omp critical(vv_pyramid_err)
                if (first < 0 || i < first) {
                    first = i;
                    first_status = cs;
                    snprintf(first_msg, sizeof first_msg, "%s", vv_error_message());
                }
            }
        }
        free(buf);
    }
    if (first >= 0)
        return vv_error_set(first_status, "%s", first_msg);
    return VV_OK;
}

/* Copies the part of chunk block @p c inside box lo .. of @p out. */
static void
copy_block(const py_chunk *c, const int lo[3], vv_volume *out) {
    const size_t vs = vv_voxel_type_size(out->type);
    int a[3], b[3];
    for (int k = 0; k < 3; k++) {
        a[k] = c->org[k] > lo[k] ? c->org[k] : lo[k];
        const int ce = c->org[k] + c->blk->dims[k] - 1, oe = lo[k] + out->dims[k] - 1;
        b[k] = ce < oe ? ce : oe;
    }
    const size_t n = (size_t)(b[0] - a[0] + 1) * vs;
    const unsigned char *src = c->blk->data;
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
    e->bytes = (uint64_t)e->n[0] * (uint64_t)e->n[1] * (uint64_t)e->n[2] * l->esize;
    e->state = PY_NEW;
    e->ce.pins = 1;
    return e;
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
        l->cmin[e->L] = (float)e->blk->range[0];
        l->cmax[e->L] = (float)e->blk->range[1];
        l->known[e->L] = 1;
    }
    p->arrivals++;
}

/* Unpins entry @p e; a failed one nobody holds leaves the cache. */
void
py_unpin(vv_pyramid *p, py_chunk *e) {
    if (--e->ce.pins == 0 && e->state == PY_FAILED)
        drop_chunk(p, e);
}

/* Box lo .. hi of @p level into @p out from the cache (lock held; it is
 * released while chunks are decoded): the chunks missing are reserved in
 * the cache (PY_NEW) and decoded here, those a loader is decoding are
 * waited for, and one whose loader failed is decoded again here. */
static vv_status
assemble(vv_pyramid *p, int level, const int lo[3], const int hi[3], vv_volume *out) {
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
                if ((s = vv_volume_new(&e->blk, e->n, l->type)) != VV_OK)
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
        copy_block(use[i], lo, out);
    for (int i = 0; i < nu; i++)
        py_unpin(p, use[i]);
    free(use);
    free(todo);
    free(fbytes);
    free(missing);
    return s;
}

/* The header of a level: its geometry with the store's range. */
static void
set_geometry(vv_volume *v, const vv_pyramid *p, const py_level *l) {
    memcpy(v->spacing, l->hdr->spacing, sizeof v->spacing);
    memcpy(v->origin, l->hdr->origin, sizeof v->origin);
    memcpy(v->direction, l->hdr->direction, sizeof v->direction);
    v->unit = l->hdr->unit;
    v->modification = l->hdr->modification;
    v->range[0] = p->range[0];
    v->range[1] = p->range[1];
}

/* Box lo .. hi of @p level into a new volume; @p planned: a read of the
 * frame's plan (the renderer's, through the multiresolution view), which
 * moves the plan on and asks the store for the next boxes' chunks ahead;
 * any other read (a slice, a measurement, another thread) leaves the plan
 * as it is. */
vv_status
py_box_read(vv_pyramid *p, int level, const int lo[3], const int hi[3], vv_volume **out,
            int planned) {
    if (!p || !out || level < 0 || level >= p->n_levels)
        return vv_error_set(VV_ERR_INVALID, "pyramid: bad arguments");
    *out = NULL;
    const py_level *l = &p->lv[level];
    int dims[3];
    for (int k = 0; k < 3; k++) {
        if (lo[k] < 0 || hi[k] < lo[k] || hi[k] >= l->dims[k])
            return vv_error_set(VV_ERR_INVALID, "pyramid: box %d..%d outside level %d's %d voxels",
                                lo[k], hi[k], level, l->dims[k]);
        dims[k] = hi[k] - lo[k] + 1;
    }
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, l->type);
    pthread_mutex_lock(p->lock);
    if (s == VV_OK)
        s = assemble(p, level, lo, hi, v);
    if (s == VV_OK && planned)
        py_prefetch_ahead(p);
    if (planned && p->cl.planned)
        p->cursor++;
    pthread_mutex_unlock(p->lock);
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_pyramid_prefix(s, p->store.name, p->path);
    }
    set_geometry(v, p, l);
    *out = v;
    return VV_OK;
}

vv_status
vv_pyramid_read_box(vv_pyramid *p, int level, const int lo[3], const int hi[3], vv_volume **out) {
    return py_box_read(p, level, lo, hi, out, 0);
}

vv_status
vv_pyramid_proxy(vv_pyramid *p, int level, vv_volume **out) {
    if (!p || !out || level < 0 || level >= p->n_levels)
        return vv_error_set(VV_ERR_INVALID, "pyramid: no level %d for a proxy", level);
    const int top = p->n_levels - 1;
    const vv_volume *h = p->lv[top].hdr, *f = p->lv[level].hdr;
    const int lo[3] = {0, 0, 0}, hi[3] = {h->dims[0] - 1, h->dims[1] - 1, h->dims[2] - 1};
    const vv_status s = vv_pyramid_read_box(p, top, lo, hi, out);
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

/* ---- opening ------------------------------------------------------------------ */

void
vv_pyramid_free(vv_pyramid *p) {
    if (!p)
        return;
    py_stop_loaders(p);
    free(p->queue);
    pthread_mutex_lock(p->lock);
    py_clear_plan(p);
    py_each_chunk(p, drop_chunk);
    pthread_mutex_unlock(p->lock);
    vv_cache_client_remove(&p->cl);
    vv_cache_free(p->cache);
    for (int i = 0; i < p->n_levels; i++) {
        py_level *l = &p->lv[i];
        vv_volume_free(l->hdr);
        free(l->cmin);
        free(l->cmax);
        free(l->known);
        free(l->read_frame);
        free(l->frame_reads);
    }
    vv_store_close(&p->store);
    pthread_mutex_destroy(&p->store_lock);
    pthread_cond_destroy(&p->work);
    pthread_cond_destroy(&p->arrived);
    free(p);
}

/* Level @p i's layout, header and chunk tables from the store's level;
 * each level must have level 0's type and no more voxels. */
static vv_status
open_level(vv_pyramid *p, int i) {
    py_level *l = &p->lv[i];
    vv_store_level *sl = &p->store.lv[i];
    if (!sl->hdr)
        return vv_error_set(VV_ERR_FORMAT, "level %d: no geometry", i);
    l->type = sl->hdr->type;
    l->esize = vv_voxel_type_size(l->type);
    for (int k = 0; k < 3; k++) {
        l->dims[k] = sl->hdr->dims[k];
        l->cdims[k] = sl->cdims[k];
        if (l->dims[k] < 1 || l->cdims[k] < 1)
            return vv_error_set(VV_ERR_FORMAT, "level %d: %d voxels in chunks of %d along axis %d",
                                i, l->dims[k], l->cdims[k], k);
        l->nchunks[k] = (l->dims[k] + l->cdims[k] - 1) / l->cdims[k];
    }
    if (i > 0) {
        const py_level *l0 = &p->lv[0];
        if (l->type != l0->type)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: its type differs from level 0's (inconsistent "
                                "multiscales)",
                                i);
        for (int k = 0; k < 3; k++)
            if (l->dims[k] > l0->dims[k])
                return vv_error_set(VV_ERR_FORMAT,
                                    "level %d: %d voxels along axis %d, more than level 0's %d "
                                    "(inconsistent multiscales)",
                                    i, l->dims[k], k, l0->dims[k]);
    }
    uint64_t n = 1;
    for (int k = 0; k < 3; k++)
        n *= (uint64_t)l->nchunks[k];
    l->n_chunks = n;
    if (n <= PY_MAX_LEVEL_CHUNKS) {
        l->cmin = malloc(sizeof(float) * n);
        l->cmax = malloc(sizeof(float) * n);
        l->known = calloc(n, 1);
        l->read_frame = calloc(n, sizeof(uint32_t));
        l->frame_reads = calloc(n, sizeof(uint16_t));
        if (!l->cmin || !l->cmax || !l->known || !l->read_frame || !l->frame_reads)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        /* ranges the store's index gives before any chunk is read */
        for (uint64_t L = 0; p->store.chunk_range && L < n; L++) {
            const int c[3] = {(int)(L % (uint64_t)l->nchunks[0]),
                              (int)(L / (uint64_t)l->nchunks[0] % (uint64_t)l->nchunks[1]),
                              (int)(L / ((uint64_t)l->nchunks[0] * (uint64_t)l->nchunks[1]))};
            double lo, hi;
            if (p->store.chunk_range(p->store.ctx, i, c, &lo, &hi) && lo <= hi) {
                l->cmin[L] = (float)lo;
                l->cmax[L] = (float)hi;
                l->known[L] = 1;
            }
        }
    }
    l->hdr = sl->hdr; /* taken */
    sl->hdr = NULL;
    return VV_OK;
}

/* The bytes a node of @p cells cells a side holds while rendered (its box:
 * the cells, a ghost voxel beyond each face and the half-voxel shifts of
 * coarser levels): the box, the ray caster's 16-bit or float copy and
 * cached gradients (src/render/sample.h); and in *chunks the bytes of
 * the decoded chunks such a box overlaps at most (any level). */
static uint64_t
working_set(const vv_pyramid *p, int cells, uint64_t *chunks) {
    uint64_t v = 1, worst = 0;
    for (int k = 0; k < 3; k++) {
        const int d = p->lv[0].dims[k], box = cells + 5;
        v *= (uint64_t)(d < box ? d : box);
    }
    for (int i = 0; i < p->n_levels; i++) {
        const py_level *l = &p->lv[i];
        uint64_t c = l->esize;
        for (int k = 0; k < 3; k++) {
            const int box = cells + 5, cd = l->cdims[k];
            int n = (box + cd - 1) / cd + 1;
            n = n < l->nchunks[k] ? n : l->nchunks[k];
            c *= (uint64_t)n * (uint64_t)(cd < l->dims[k] ? cd : l->dims[k]);
        }
        worst = c > worst ? c : worst;
    }
    *chunks = worst;
    return v * (p->lv[0].esize + 4 + 4 + p->lv[0].esize);
}

static vv_status
pyramid_open(vv_pyramid *p, vv_load_info *info) {
    vv_status s = VV_OK;
    if (p->store.n_levels < 1 || p->store.n_levels > VV_PYRAMID_MAX_LEVELS)
        return vv_error_set(VV_ERR_LIMIT, "%d levels (1 .. %d are read)", p->store.n_levels,
                            VV_PYRAMID_MAX_LEVELS);
    for (int i = 0; i < p->store.n_levels; i++) {
        s = open_level(p, i);
        p->n_levels = i + 1;
        if (s != VV_OK)
            return s;
    }
    p->limit = vv_cache_limit(p->cache);
    /* the largest node (64, 32, 16 or 8 cells) whose box, working set and
     * chunks fit the limit */
    uint64_t ws = 0, chunks = 0;
    int cells = VV_BRICK_CELLS;
    for (; cells >= 8; cells /= 2) {
        ws = working_set(p, cells, &chunks);
        if (ws + chunks <= p->limit)
            break;
    }
    if (cells < 8)
        return vv_error_set(VV_ERR_LIMIT,
                            "memory limit of %llu bytes is smaller than a box of 8 cells, its "
                            "working set and its chunks (%llu bytes)",
                            (unsigned long long)p->limit, (unsigned long long)(ws + chunks));
    p->node_cells = cells;
    /* boxes held at once (the driver renders that many nodes at a time, one
     * a thread): as many working sets as an eighth of the limit holds, at
     * most 8; the cache gets the rest */
    uint64_t boxes = ws > 0 ? p->limit / 8 / ws : 1;
    boxes = boxes < 1 ? 1 : boxes > 8 ? 8 : boxes;
    if (ws * boxes + chunks > p->limit)
        boxes = 1;
    p->boxes = (int)boxes;
    /* the cache holds the rest, with every other source's pieces */
    p->cl.reserve = ws * boxes;
    p->cl.next_use = py_client_next_use;
    p->cl.drop = client_drop;
    vv_cache_client_add(p->cache, &p->cl);
    /* the range: the store's (an omero window), else the coarsest level's */
    p->range[0] = 0;
    p->range[1] = 1;
    if (p->store.has_range) {
        p->range[0] = p->store.range[0];
        p->range[1] = p->store.range[1];
    } else {
        const py_level *c = &p->lv[p->n_levels - 1];
        const int lo[3] = {0, 0, 0}, hi[3] = {c->dims[0] - 1, c->dims[1] - 1, c->dims[2] - 1};
        vv_volume *v = NULL;
        if ((s = vv_pyramid_read_box(p, p->n_levels - 1, lo, hi, &v)) != VV_OK)
            return s;
        vv_volume_update_range(v);
        p->range[0] = v->range[0];
        p->range[1] = v->range[1];
        vv_volume_free(v);
    }
    for (int i = 0; i < p->n_levels; i++) {
        p->lv[i].hdr->range[0] = p->range[0];
        p->lv[i].hdr->range[1] = p->range[1];
    }
    if (info) {
        info->n_channels = p->store.n_channels;
        info->n_times = p->store.n_times;
        info->n_levels = p->n_levels;
    }
    return VV_OK;
}

vv_status
vv_pyramid_open_store(vv_pyramid **out, vv_store *st, const char *path, vv_cache *cache,
                      vv_load_info *info) {
    *out = NULL;
    char name[64]; /* st->name is the store's, closed on failure */
    snprintf(name, sizeof name, "%s", st->name ? st->name : "pyramid");
    vv_pyramid *p = strlen(path) < sizeof(((vv_pyramid *)0)->path) ? calloc(1, sizeof *p) : NULL;
    if (!p) {
        vv_store_close(st);
        return vv_error_set(VV_ERR_NOMEM, "%s: %s: out of memory", name, vv_path_basename(path));
    }
    snprintf(p->path, sizeof p->path, "%s", path);
    p->cache = vv_cache_ref(cache ? cache : vv_cache_process());
    p->lock = vv_cache_mutex(p->cache);
    pthread_mutex_init(&p->store_lock, NULL);
    pthread_cond_init(&p->work, NULL);
    pthread_cond_init(&p->arrived, NULL);
    p->store = *st; /* taken */
    memset(st, 0, sizeof *st);
    vv_status s = pyramid_open(p, info);
    if (s != VV_OK) {
        vv_pyramid_free(p);
        return vv_pyramid_prefix(s, name, path);
    }
    *out = p;
    return VV_OK;
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
    const int n = snprintf(head, sizeof head, "%s: %s:", name, vv_path_basename(path));
    if (n > 0 && n < (int)sizeof head && !strncmp(vv_error_message(), head, (size_t)n))
        return s;
    return vv_error_prefix(s, "%s: %s", name, vv_path_basename(path));
}
