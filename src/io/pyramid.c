/*
 * OME-Zarr pyramids out of core (include/volvis/bricks.h, vv_pyramid): the
 * multiscales levels of one channel at one time step, read by boxes of
 * voxels through a cache of decoded chunks within a memory limit.
 *
 * Opening reads the metadata only (.zattrs, each level's .zarray) and the
 * coarsest level, whose voxels give the proxy and, without an omero window,
 * the value range. A box of a level is assembled from the chunks it
 * overlaps: those in the cache are used as they are, the others are read
 * and decoded on every core (one buffer a thread) and kept, least recently
 * used first out. The min and max of every chunk decoded are remembered
 * (a few bytes a chunk), so a later frame skips transparent boxes unread.
 * Each chunk's reads within one frame are counted (frames are marked by
 * the renderer through the source's frame method).
 *
 * When the renderer plans its frame (the boxes it will read, in order),
 * each chunk's uses in the plan are known, and the chunk evicted is the
 * one needed again farthest ahead or never (Belady's optimal policy):
 * ghost voxels pull a node's neighbours' chunks in early, and they stay
 * until their own node when the limit allows. Unplanned reads evict the
 * least recently used.
 */
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "core/internal.h"
#include "io/zarr.h"
#include "volvis/bricks.h"

#define PY_BUCKETS 4096u
#define PY_MAX_LEVEL_CHUNKS ((uint64_t)1 << 26)

/* A chunk's uses in the frame's plan: the boxes (their order) needing it. */
typedef struct py_use {
    int level;
    uint64_t L;
    int *seq, n, cap, pos;
    struct py_use *hnext;
} py_use;

typedef struct py_chunk {
    int level;
    uint64_t L;
    py_use *use;      /* its uses in the plan, or NULL */
    int org[3], n[3]; /* the block's first voxel in the level, its size */
    vv_volume *blk;   /* the chunk's voxels inside the array */
    uint64_t bytes;
    int pins; /* boxes being assembled from it */
    struct py_chunk *prev, *next, *hnext;
} py_chunk;

typedef struct py_level {
    zr_array a;
    zr_layout J;
    vv_volume *hdr; /* geometry only: 1-voxel data, dims set to the level's */
    uint64_t n_chunks;
    float *cmin, *cmax;    /* per chunk, when known */
    uint8_t *known;        /* 1: cmin/cmax hold the chunk's range */
    uint32_t *read_frame;  /* the frame of the chunk's last read */
    uint16_t *frame_reads; /* its reads in that frame */
} py_level;

struct vv_pyramid {
    char path[4096];
    int n_levels;
    py_level lv[VV_PYRAMID_MAX_LEVELS];
    double range[2];
    uint64_t limit, capacity, held;
    int node_cells; /* the octree leaves' side the limit holds */
    py_chunk *bucket[PY_BUCKETS];
    py_chunk *mru, *lru; /* the LRU list, most recent first */
    uint32_t frame;
    /* the frame's plan: uses by chunk, the box being read */
    py_use *ubucket[PY_BUCKETS];
    int planned, cursor;
    vv_pyramid_stats st;
};

static unsigned
bucket_of(int level, uint64_t L) {
    uint64_t h = (L + 1) * 0x9E3779B97F4A7C15ull ^ (uint64_t)level * 0xBF58476D1CE4E5B9ull;
    return (unsigned)(h >> 52) & (PY_BUCKETS - 1);
}

static py_chunk *
find_chunk(const vv_pyramid *p, int level, uint64_t L) {
    for (py_chunk *c = p->bucket[bucket_of(level, L)]; c; c = c->hnext)
        if (c->level == level && c->L == L)
            return c;
    return NULL;
}

static void
lru_unlink(vv_pyramid *p, py_chunk *c) {
    if (c->prev)
        c->prev->next = c->next;
    else
        p->mru = c->next;
    if (c->next)
        c->next->prev = c->prev;
    else
        p->lru = c->prev;
    c->prev = c->next = NULL;
}

static void
lru_push_front(vv_pyramid *p, py_chunk *c) {
    c->prev = NULL;
    c->next = p->mru;
    if (p->mru)
        p->mru->prev = c;
    p->mru = c;
    if (!p->lru)
        p->lru = c;
}

static void
drop_chunk(vv_pyramid *p, py_chunk *c) {
    lru_unlink(p, c);
    py_chunk **pp = &p->bucket[bucket_of(c->level, c->L)];
    while (*pp != c)
        pp = &(*pp)->hnext;
    *pp = c->hnext;
    p->held -= c->bytes;
    vv_volume_free(c->blk);
    free(c);
}

static py_use *
find_use(const vv_pyramid *p, int level, uint64_t L) {
    for (py_use *u = p->ubucket[bucket_of(level, L)]; u; u = u->hnext)
        if (u->level == level && u->L == L)
            return u;
    return NULL;
}

static void
clear_plan(vv_pyramid *p) {
    for (unsigned b = 0; b < PY_BUCKETS; b++)
        while (p->ubucket[b]) {
            py_use *u = p->ubucket[b];
            p->ubucket[b] = u->hnext;
            free(u->seq);
            free(u);
        }
    for (py_chunk *c = p->mru; c; c = c->next)
        c->use = NULL;
    p->planned = 0;
    p->cursor = 0;
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

/* Drops unpinned chunks until @p need more bytes fit: with a plan the one
 * needed farthest ahead (or never) first, else the least recently used;
 * 0 when they cannot fit. */
static int
make_room(vv_pyramid *p, uint64_t need) {
    while (p->held + need > p->capacity) {
        py_chunk *victim = NULL;
        int far = -1;
        for (py_chunk *c = p->lru; c; c = c->prev) {
            if (c->pins)
                continue;
            if (!p->planned) {
                victim = c;
                break;
            }
            const int nu = next_use(p, c);
            if (nu > far) {
                far = nu;
                victim = c;
                if (nu == INT_MAX)
                    break;
            }
        }
        if (!victim)
            return 0;
        drop_chunk(p, victim);
        p->st.evictions++;
    }
    return 1;
}

/* The chunk box of chunk position c: its first voxel and size inside the level. */
static void
chunk_box(const py_level *l, const int c[3], int org[3], int n[3]) {
    for (int k = 0; k < 3; k++) {
        org[k] = c[k] * l->J.cdims[k];
        const int e = org[k] + l->J.cdims[k];
        n[k] = (e > l->J.dims[k] ? l->J.dims[k] : e) - org[k];
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

/* Reads and decodes the chunks in @p todo (n >= 1 of them, their blocks
 * allocated) on every core, file bytes and missing flags per chunk into
 * @p file_bytes and @p missing; the first failing chunk's error in order. */
static vv_status
decode_chunks(vv_pyramid *p, py_chunk **todo, int n, uint64_t *file_bytes, int *missing) {
    const py_level *l = &p->lv[todo[0]->level];
    long long first = -1;
    vv_status first_status = VV_OK;
    char first_msg[1024] = "";
    const int nthreads = l->J.cbytes > ((size_t)64 << 20) || n < 2 ? 1
                         : omp_get_max_threads() < n               ? omp_get_max_threads()
                                                                   : n;
#pragma omp parallel num_threads(nthreads)
    {
        unsigned char *buf = malloc(l->J.cbytes);
#pragma omp for schedule(dynamic, 1)
        for (int i = 0; i < n; i++) {
            py_chunk *c = todo[i];
            const py_level *cl = &p->lv[c->level];
            vv_status cs =
                buf ? vv_zr_copy_chunk(&cl->J, c->L, buf, c->blk->data, c->org, c->blk->dims,
                                       &missing[i], &file_bytes[i])
                    : vv_error_set(VV_ERR_NOMEM, "out of memory for a chunk of %zu bytes",
                                   cl->J.cbytes);
            if (cs == VV_OK)
                vv_volume_update_range(c->blk);
            else {
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

/* The chunk positions c0 .. c1 overlapping voxels lo .. hi of a level. */
static void
chunk_span(const py_level *l, const int lo[3], const int hi[3], int c0[3], int c1[3]) {
    for (int k = 0; k < 3; k++) {
        c0[k] = lo[k] / l->J.cdims[k];
        c1[k] = hi[k] / l->J.cdims[k];
    }
}

static vv_status
assemble(vv_pyramid *p, int level, const int lo[3], const int hi[3], vv_volume *out) {
    py_level *l = &p->lv[level];
    int c0[3], c1[3];
    chunk_span(l, lo, hi, c0, c1);
    const int n = (c1[0] - c0[0] + 1) * (c1[1] - c0[1] + 1) * (c1[2] - c0[2] + 1);
    py_chunk **use = calloc((size_t)n, sizeof *use), **todo = calloc((size_t)n, sizeof *todo);
    uint64_t *fbytes = calloc((size_t)n, sizeof *fbytes);
    int *missing = calloc((size_t)n, sizeof *missing);
    vv_status s =
        use && todo && fbytes && missing ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    int nu = 0, nt = 0;
    uint64_t need = 0;
    const size_t vs = l->a.esize;
    for (int z = c0[2]; z <= c1[2] && s == VV_OK; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                const int c[3] = {x, y, z};
                const uint64_t L = vv_zr_chunk_linear(&l->J, c);
                py_chunk *e = find_chunk(p, level, L);
                if (e) {
                    lru_unlink(p, e);
                    lru_push_front(p, e);
                    p->st.chunk_hits++;
                } else {
                    e = calloc(1, sizeof *e);
                    if (!e) {
                        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                        break;
                    }
                    e->level = level;
                    e->L = L;
                    chunk_box(l, c, e->org, e->n);
                    e->bytes = (uint64_t)e->n[0] * (uint64_t)e->n[1] * (uint64_t)e->n[2] * vs;
                    need += e->bytes;
                    todo[nt++] = e;
                }
                e->pins++;
                use[nu++] = e;
            }
    if (s == VV_OK && !make_room(p, need))
        s = vv_error_set(VV_ERR_LIMIT,
                         "memory limit of %llu bytes: the %d chunks of a box of level %d do not "
                         "fit",
                         (unsigned long long)p->limit, n, level);
    for (int i = 0; i < nt && s == VV_OK; i++)
        s = vv_volume_new(&todo[i]->blk, todo[i]->n, l->a.type);
    if (s == VV_OK && nt > 0)
        s = decode_chunks(p, todo, nt, fbytes, missing);
    for (int i = 0; i < nu; i++)
        use[i]->pins--;
    for (int i = 0; i < nt; i++) {
        py_chunk *e = todo[i];
        if (s != VV_OK) {
            vv_volume_free(e->blk);
            free(e);
            continue;
        }
        const unsigned b = bucket_of(e->level, e->L);
        e->use = p->planned ? find_use(p, e->level, e->L) : NULL;
        e->hnext = p->bucket[b];
        p->bucket[b] = e;
        lru_push_front(p, e);
        p->held += e->bytes;
        count_read(p, level, e->L, fbytes[i]);
        p->st.missing += (uint64_t)missing[i];
        if (l->known) {
            l->cmin[e->L] = (float)e->blk->range[0];
            l->cmax[e->L] = (float)e->blk->range[1];
            l->known[e->L] = 1;
        }
    }
    if (p->held > p->st.peak_bytes)
        p->st.peak_bytes = p->held;
    for (int i = 0; i < nu && s == VV_OK; i++)
        copy_block(use[i], lo, out);
    free(use);
    free(todo);
    free(fbytes);
    free(missing);
    return s;
}

/* The header of a level: its geometry with the store's range. */
static void
set_geometry(vv_volume *v, const vv_pyramid *p, const py_level *l) {
    vv_zr_geometry(&l->J, v);
    v->range[0] = p->range[0];
    v->range[1] = p->range[1];
}

vv_status
vv_pyramid_read_box(vv_pyramid *p, int level, const int lo[3], const int hi[3], vv_volume **out) {
    if (!p || !out || level < 0 || level >= p->n_levels)
        return vv_error_set(VV_ERR_INVALID, "pyramid: bad arguments");
    *out = NULL;
    const py_level *l = &p->lv[level];
    int dims[3];
    for (int k = 0; k < 3; k++) {
        if (lo[k] < 0 || hi[k] < lo[k] || hi[k] >= l->J.dims[k])
            return vv_error_set(VV_ERR_INVALID, "pyramid: box %d..%d outside level %d's %d voxels",
                                lo[k], hi[k], level, l->J.dims[k]);
        dims[k] = hi[k] - lo[k] + 1;
    }
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, l->a.type);
    if (s == VV_OK)
        s = assemble(p, level, lo, hi, v);
    if (p->planned)
        p->cursor++;
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_error_prefix(s, "zarr: %s", vv_path_basename(p->path));
    }
    set_geometry(v, p, l);
    *out = v;
    return VV_OK;
}

static int
missing_chunks(const vv_pyramid *p, int level, const int lo[3], const int hi[3]) {
    const py_level *l = &p->lv[level];
    int c0[3], c1[3], n = 0;
    chunk_span(l, lo, hi, c0, c1);
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                const int c[3] = {x, y, z};
                n += !find_chunk(p, level, vv_zr_chunk_linear(&l->J, c));
            }
    return n;
}

static int
box_range(const vv_pyramid *p, int level, const int lo[3], const int hi[3], float *vmin,
          float *vmax) {
    const py_level *l = &p->lv[level];
    if (!l->known)
        return 0;
    int c0[3], c1[3];
    chunk_span(l, lo, hi, c0, c1);
    float a = INFINITY, b = -INFINITY;
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                const int c[3] = {x, y, z};
                const uint64_t L = vv_zr_chunk_linear(&l->J, c);
                if (!l->known[L])
                    return 0;
                a = l->cmin[L] < a ? l->cmin[L] : a;
                b = l->cmax[L] > b ? l->cmax[L] : b;
            }
    *vmin = a;
    *vmax = b;
    return 1;
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
    if (p && st)
        *st = p->st;
}

/* ---- the source interface ----------------------------------------------------- */

static const vv_volume *
src_level(void *user, int level) {
    return vv_pyramid_level(user, level);
}

static vv_status
src_read_box(void *user, int level, const int lo[3], const int hi[3], vv_volume **out) {
    return vv_pyramid_read_box(user, level, lo, hi, out);
}

static int
src_box_range(void *user, int level, const int lo[3], const int hi[3], float *vmin, float *vmax) {
    return box_range(user, level, lo, hi, vmin, vmax);
}

static int
src_missing(void *user, int level, const int lo[3], const int hi[3]) {
    return missing_chunks(user, level, lo, hi);
}

static void
src_frame(void *user, int begin) {
    vv_pyramid *p = user;
    clear_plan(p);
    if (begin) {
        p->frame++;
        p->st.frames++;
    }
}

/* Notes box @p seq's use of chunk (level, L). */
static vv_status
add_use(vv_pyramid *p, int level, uint64_t L, int seq) {
    py_use *u = find_use(p, level, L);
    if (!u) {
        if (!(u = calloc(1, sizeof *u)))
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        u->level = level;
        u->L = L;
        const unsigned b = bucket_of(level, L);
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

static vv_status
src_plan(void *user, int n, const int *level, const int *lo, const int *hi) {
    vv_pyramid *p = user;
    clear_plan(p);
    vv_status s = VV_OK;
    for (int i = 0; i < n && s == VV_OK; i++) {
        if (level[i] < 0 || level[i] >= p->n_levels)
            continue;
        const py_level *l = &p->lv[level[i]];
        int c0[3], c1[3];
        chunk_span(l, lo + 3 * i, hi + 3 * i, c0, c1);
        for (int z = c0[2]; z <= c1[2] && s == VV_OK; z++)
            for (int y = c0[1]; y <= c1[1] && s == VV_OK; y++)
                for (int x = c0[0]; x <= c1[0] && s == VV_OK; x++) {
                    const int c[3] = {x, y, z};
                    s = add_use(p, level[i], vv_zr_chunk_linear(&l->J, c), i);
                }
    }
    if (s != VV_OK) {
        clear_plan(p);
        return s;
    }
    for (py_chunk *c = p->mru; c; c = c->next)
        c->use = find_use(p, c->level, c->L);
    p->planned = 1;
    p->cursor = 0;
    return VV_OK;
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
}

/* ---- opening ------------------------------------------------------------------ */

void
vv_pyramid_free(vv_pyramid *p) {
    if (!p)
        return;
    clear_plan(p);
    while (p->mru)
        drop_chunk(p, p->mru);
    for (int i = 0; i < p->n_levels; i++) {
        py_level *l = &p->lv[i];
        vv_volume_free(l->hdr);
        free(l->cmin);
        free(l->cmax);
        free(l->known);
        free(l->read_frame);
        free(l->frame_reads);
    }
    free(p);
}

/* Level @p i's metadata, layout, header and chunk tables; each level must
 * have level 0's axes and type. */
static vv_status
open_level(vv_pyramid *p, int i, int channel, int time, vv_load_info *info) {
    py_level *l = &p->lv[i];
    vv_status s = vv_zr_parse_store(p->path, i, &l->a, channel, i == 0 ? info : NULL, NULL);
    if (s == VV_OK)
        s = vv_zr_layout(&l->a, channel, time, &l->J);
    if (s != VV_OK)
        return vv_error_prefix(s, "level %d", i);
    l->J.a = &l->a; /* the layout points into the level it describes */
    if (i > 0) {
        const py_level *l0 = &p->lv[0];
        if (l->a.ndim != l0->a.ndim || l->a.type != l0->a.type || l->J.cax != l0->J.cax ||
            l->J.tax != l0->J.tax || l->J.nc != l0->J.nc || l->J.nt != l0->J.nt)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: its axes, channels, steps or type differ from level 0's "
                                "(inconsistent multiscales)",
                                i);
        for (int k = 0; k < 3; k++)
            if (l->J.dims[k] > l0->J.dims[k])
                return vv_error_set(VV_ERR_FORMAT,
                                    "level %d: %d voxels along axis %d, more than level 0's %d "
                                    "(inconsistent multiscales)",
                                    i, l->J.dims[k], k, l0->J.dims[k]);
    }
    uint64_t n = 1;
    for (int k = 0; k < 3; k++)
        n *= (uint64_t)l->J.nchunks[k];
    l->n_chunks = n;
    if (n <= PY_MAX_LEVEL_CHUNKS) {
        l->cmin = malloc(sizeof(float) * n);
        l->cmax = malloc(sizeof(float) * n);
        l->known = calloc(n, 1);
        l->read_frame = calloc(n, sizeof(uint32_t));
        l->frame_reads = calloc(n, sizeof(uint16_t));
        if (!l->cmin || !l->cmax || !l->known || !l->read_frame || !l->frame_reads)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    const int one[3] = {1, 1, 1};
    if ((s = vv_volume_new(&l->hdr, one, l->a.type)) != VV_OK)
        return s;
    memcpy(l->hdr->dims, l->J.dims, sizeof l->hdr->dims); /* geometry only */
    return VV_OK;
}

/* The omero window's min and max of @p channel when the store names them. */
static int
omero_range(const char *path, int channel, double r[2]) {
    char f[4200];
    snprintf(f, sizeof f, "%s/.zattrs", path);
    json_error_t e;
    json_t *j = json_load_file(f, JSON_REJECT_DUPLICATES, &e);
    json_t *ch = json_array_get(json_object_get(json_object_get(j, "omero"), "channels"),
                                (size_t)(channel < 0 ? 0 : channel));
    json_t *w = json_object_get(ch, "window");
    json_t *mn = json_object_get(w, "min"), *mx = json_object_get(w, "max");
    int ok = json_is_number(mn) && json_is_number(mx) &&
             json_number_value(mx) >= json_number_value(mn) && isfinite(json_number_value(mn)) &&
             isfinite(json_number_value(mx));
    if (ok) {
        r[0] = json_number_value(mn);
        r[1] = json_number_value(mx);
    }
    json_decref(j);
    return ok;
}

/* The bytes a node of @p cells cells a side holds while rendered (its box:
 * the cells, a ghost voxel beyond each face and the half-voxel shifts of
 * coarser levels): the box, the ray caster's 16-bit or float copy and
 * cached gradients (src/render/volume_cache.h); and in *chunks the bytes of
 * the decoded chunks such a box overlaps at most (any level). */
static uint64_t
working_set(const vv_pyramid *p, int cells, uint64_t *chunks) {
    uint64_t v = 1, worst = 0;
    for (int k = 0; k < 3; k++) {
        const int d = p->lv[0].J.dims[k], box = cells + 5;
        v *= (uint64_t)(d < box ? d : box);
    }
    for (int i = 0; i < p->n_levels; i++) {
        const py_level *l = &p->lv[i];
        uint64_t c = l->a.esize;
        for (int k = 0; k < 3; k++) {
            const int box = cells + 5, cd = l->J.cdims[k];
            int n = (box + cd - 1) / cd + 1;
            n = n < l->J.nchunks[k] ? n : l->J.nchunks[k];
            c *= (uint64_t)n * (uint64_t)(cd < l->J.dims[k] ? cd : l->J.dims[k]);
        }
        worst = c > worst ? c : worst;
    }
    *chunks = worst;
    return v * (p->lv[0].a.esize + 4 + 4 + p->lv[0].a.esize);
}

static vv_status
pyramid_open(vv_pyramid *p, int channel, int time, uint64_t memory_limit, vv_load_info *info) {
    int n_levels = 1;
    zr_array probe;
    memset(&probe, 0, sizeof probe);
    vv_status s = vv_zr_parse_store(p->path, 0, &probe, channel, NULL, &n_levels);
    if (s != VV_OK)
        return s;
    if (n_levels > VV_PYRAMID_MAX_LEVELS)
        return vv_error_set(VV_ERR_LIMIT, "%d levels (at most %d are read)", n_levels,
                            VV_PYRAMID_MAX_LEVELS);
    for (int i = 0; i < n_levels; i++) {
        s = open_level(p, i, channel, time, info);
        p->n_levels = i + 1;
        if (s != VV_OK)
            return s;
    }
    p->limit = memory_limit ? memory_limit : (uint64_t)1 << 30;
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
    p->capacity = p->limit - ws;
    /* the range: the omero window's, else the coarsest level's */
    p->range[0] = 0;
    p->range[1] = 1;
    if (!omero_range(p->path, channel, p->range)) {
        const py_level *c = &p->lv[p->n_levels - 1];
        const int lo[3] = {0, 0, 0}, hi[3] = {c->J.dims[0] - 1, c->J.dims[1] - 1, c->J.dims[2] - 1};
        vv_volume *v = NULL;
        if ((s = vv_pyramid_read_box(p, p->n_levels - 1, lo, hi, &v)) != VV_OK)
            return s;
        vv_volume_update_range(v);
        p->range[0] = v->range[0];
        p->range[1] = v->range[1];
        vv_volume_free(v);
    }
    for (int i = 0; i < p->n_levels; i++)
        set_geometry(p->lv[i].hdr, p, &p->lv[i]);
    if (info) {
        info->n_channels = (int)p->lv[0].J.nc;
        info->n_times = (int)p->lv[0].J.nt;
        info->n_levels = p->n_levels;
    }
    return VV_OK;
}

vv_status
vv_pyramid_open(vv_pyramid **out, const char *path, int channel, int time, uint64_t memory_limit,
                vv_load_info *info) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "pyramid: NULL argument");
    *out = NULL;
    if (strlen(path) >= sizeof(((vv_pyramid *)0)->path))
        return vv_error_set(VV_ERR_LIMIT, "zarr: path too long");
    vv_pyramid *p = calloc(1, sizeof *p);
    if (!p)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    snprintf(p->path, sizeof p->path, "%s", path);
    vv_status s = pyramid_open(p, channel, time, memory_limit, info);
    if (s != VV_OK) {
        vv_pyramid_free(p);
        return vv_error_prefix(s, "zarr: %s", vv_path_basename(path));
    }
    *out = p;
    return VV_OK;
}
