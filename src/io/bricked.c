/*
 * Bricked volumes read on demand (include/volvis/bricks.h): the .vvb format
 * (docs/file-formats.md), raw and raw-encoded NRRD files read by pread, and
 * a least-recently-used cache of bricks within a memory budget.
 *
 * .vvb layout, little-endian: a 256-byte header ("VOLVISB1", header size,
 * brick side in cells, dims, voxel type, coarse flag, unit, space, spacing,
 * origin, direction, value range, index offset, brick count), then the
 * index, 48 bytes a brick (i fastest): data offset and size, min and max
 * (float64), coarse level offset and size; then the bricks, each the voxels
 * of its box with one ghost voxel beyond each face (clipped to the volume),
 * i fastest, and its coarse level (every 4th voxel of its cells, from lo).
 * With codec 1 (header offset 200) every brick's voxels are one zstd frame,
 * decoded in-process (libzstd, into a buffer of the box's size, checked
 * before and after), and every brick has its coarse level, uncompressed.
 */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <zstd.h>

#include "core/cache.h"
#include "core/internal.h"
#include "io/bricked.h"
#include "io/bricked_internal.h"
#include "io/pyramid.h"
#include "volvis/sys/format.h"

#define VVB_MAGIC "VOLVISB1"
#define VVB_HEADER 256
#define VVB_RECORD 48
#define VVB_COARSE 4 /* coarse level: every 4th voxel */
#define VVB_CODEC_ZSTD 1
#define VVB_ZSTD_LEVEL 3
#define VVB_CHUNK 64        /* a pyramid level's chunk side, voxels */
#define VVB_LEVEL_RECORD 32 /* the level table: dims, chunk side, index offset, count */
#define VVB_CHUNK_RECORD 32 /* a level's index: offset, size, min, max */

/* A chunk of a pyramid level (levels 1 and up; level 0 is the bricks). */
typedef struct vvb_chunk {
    uint64_t offset, bytes;
    double vmin, vmax;
} vvb_chunk;

typedef struct vvb_level {
    int dims[3], nc[3]; /* voxels, chunks along each axis */
    int n;              /* chunks */
    vvb_chunk *c;       /* i fastest */
} vvb_level;

typedef struct brick_entry {
    uint64_t offset, bytes;               /* .vvb: the brick's voxels in the file */
    uint64_t coarse_offset, coarse_bytes; /* .vvb: its coarse level (0 bytes: none) */
    double vmin, vmax;
    vv_volume *vol;    /* cached, or NULL */
    vv_cache_entry ce; /* its place in the process's cache while vol is held */
    int loads;
} brick_entry;

struct vv_bricked {
    char *path;      /* as opened */
    char *data_path; /* the file holding the voxels */
    int fd;
    int vvb;            /* 1: .vvb, else raw layout (raw or NRRD) */
    uint64_t data_off;  /* raw layout: offset of voxel (0, 0, 0) */
    int swap;           /* voxels need byte swapping */
    uint64_t file_size; /* of data_path */
    vv_volume *header;  /* one voxel, the geometry and range; dims the volume's */
    int nb[3];
    int n;
    brick_entry *e;
    int has_coarse;
    int zstd;                            /* .vvb: bricks are zstd frames */
    int n_levels;                        /* .vvb: pyramid levels, level 0 (the bricks) included */
    vvb_level lv[VV_PYRAMID_MAX_LEVELS]; /* lv[1 .. n_levels - 1] */
    /* the cached bricks live in the process's cache (src/core/cache.h);
     * its lock guards them and the counts */
    vv_cache *cache;
    vv_cache_client cl;
    vv_bricked_stats st;
};

/* ---- little-endian fields ------------------------------------------------ */

static void
put_u32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static void
put_u64(unsigned char *p, uint64_t v) {
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static void
put_f64(unsigned char *p, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    put_u64(p, v);
}
static uint32_t
get_u32(const unsigned char *p) {
    uint32_t v = 0;
    for (int i = 0; i < 4; i++)
        v |= (uint32_t)p[i] << (8 * i);
    return v;
}
static uint64_t
get_u64(const unsigned char *p) {
    uint64_t v = 0;
    for (int i = 0; i < 8; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}
static double
get_f64(const unsigned char *p) {
    uint64_t v = get_u64(p);
    double d;
    memcpy(&d, &v, 8);
    return d;
}

static void
swap_bytes(void *data, size_t count, size_t vs) {
    unsigned char *b = data;
    for (size_t i = 0; i < count; i++, b += vs)
        for (size_t k = 0; k < vs / 2; k++) {
            unsigned char t = b[k];
            b[k] = b[vs - 1 - k];
            b[vs - 1 - k] = t;
        }
}

/* pread of exactly n bytes at off (uncounted: any thread). */
static vv_status
pread_exact(const vv_bricked *b, void *buf, size_t n, uint64_t off, const char *what) {
    size_t done = 0;
    while (done < n) {
        ssize_t r = pread(b->fd, (char *)buf + done, n - done, (off_t)(off + done));
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return vv_error_set(VV_ERR_IO, "%s: %s: %s", vv_path_basename(b->data_path), what,
                                strerror(errno));
        if (r == 0)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: %s: the file ends at byte %llu (reading %zu bytes at %llu)",
                                vv_path_basename(b->data_path), what,
                                (unsigned long long)(off + done), n, (unsigned long long)off);
        done += (size_t)r;
    }
    return VV_OK;
}

/* pread_exact, counted in the statistics. */
static vv_status
read_at(vv_bricked *b, void *buf, size_t n, uint64_t off, const char *what) {
    const vv_status s = pread_exact(b, buf, n, off, what);
    if (s == VV_OK)
        __atomic_fetch_add(&b->st.bytes_read, (uint64_t)n, __ATOMIC_RELAXED);
    return s;
}

/* ---- geometry -------------------------------------------------------------- */

static void
brick_boxes(const vv_bricked *b, int index, vv_brick_info *in) {
    int c[3] = {index % b->nb[0], (index / b->nb[0]) % b->nb[1], index / (b->nb[0] * b->nb[1])};
    for (int a = 0; a < 3; a++) {
        const int last = b->header->dims[a] - 1;
        in->lo[a] = c[a] * VV_BRICK_CELLS;
        in->hi[a] = in->lo[a] + VV_BRICK_CELLS < last ? in->lo[a] + VV_BRICK_CELLS : last;
        in->slo[a] = in->lo[a] > 0 ? in->lo[a] - 1 : 0;
        in->shi[a] = in->hi[a] < last ? in->hi[a] + 1 : last;
    }
}

static uint64_t
box_voxels(const int lo[3], const int hi[3]) {
    return (uint64_t)(hi[0] - lo[0] + 1) * (uint64_t)(hi[1] - lo[1] + 1) *
           (uint64_t)(hi[2] - lo[2] + 1);
}

/* Coarse level of a brick: every VVB_COARSE-th voxel from lo to hi. */
static void
coarse_dims(const vv_brick_info *in, int cd[3]) {
    for (int a = 0; a < 3; a++)
        cd[a] = (in->hi[a] - in->lo[a]) / VVB_COARSE + 1;
}

/* The bytes one brick holds while rendered: its voxels, the ray caster's
 * 16-bit or float copy and cached gradients (src/render/sample.h). */
static uint64_t
working_set(const vv_bricked *b, uint64_t voxels) {
    const uint64_t vs = vv_voxel_type_size(b->header->type);
    return voxels * (vs + 4 + 4);
}

int
vv_bricked_levels(const vv_bricked *b) {
    return b->n_levels > 1 ? b->n_levels : 1;
}

int
vv_bricked_count(const vv_bricked *b) {
    return b->n;
}

void
vv_bricked_info(const vv_bricked *b, int index, vv_brick_info *info) {
    brick_boxes(b, index, info);
    info->vmin = (float)b->e[index].vmin;
    info->vmax = (float)b->e[index].vmax;
}

void
vv_bricked_note_skip(vv_bricked *b) {
    __atomic_fetch_add(&b->st.skipped, (uint64_t)1, __ATOMIC_RELAXED);
}

const vv_volume *
vv_bricked_header(const vv_bricked *b) {
    return b->header;
}

void
vv_bricked_grid(const vv_bricked *b, int nb[3]) {
    memcpy(nb, b->nb, sizeof b->nb);
}

static const vv_volume *
src_header(void *user) {
    return vv_bricked_header(user);
}

static void
src_grid(void *user, int nb[3]) {
    vv_bricked_grid(user, nb);
}

static void
src_info(void *user, int index, vv_brick_info *out) {
    vv_bricked_info(user, index, out);
}

static vv_status
src_load(void *user, int index, vv_volume **out) {
    return vv_bricked_load(user, index, out);
}

static void
src_skip(void *user) {
    vv_bricked_note_skip(user);
}

void
vv_bricked_source(vv_bricked *b, vv_brick_source *out) {
    memset(out, 0, sizeof *out);
    out->version = VV_BRICK_SOURCE_VERSION;
    out->user = b;
    out->header = src_header;
    out->grid = src_grid;
    out->info = src_info;
    out->load = src_load;
    out->note_skip = src_skip;
}

void
vv_bricked_stats_get(const vv_bricked *b, vv_bricked_stats *s) {
    vv_cache_lock(b->cache);
    *s = b->st;
    s->evictions = b->cl.evictions;
    s->peak_bytes = b->cl.peak;
    s->held_bytes = b->cl.held;
    vv_cache_unlock(b->cache);
    s->max_loads = 0;
    for (int i = 0; i < b->n; i++)
        s->max_loads = b->e[i].loads > s->max_loads ? b->e[i].loads : s->max_loads;
}

const char *
vv_bricked_path(const vv_bricked *b) {
    return b->path;
}

vv_cache *
vv_bricked_cache(const vv_bricked *b) {
    return b->cache;
}

void
vv_bricked_free(vv_bricked *b) {
    if (!b)
        return;
    if (b->cache) {
        vv_cache_lock(b->cache);
        for (int i = 0; b->e && i < b->n; i++)
            if (b->e[i].vol) {
                vv_cache_remove(b->cache, &b->e[i].ce);
                vv_volume_free(b->e[i].vol);
            }
        vv_cache_unlock(b->cache);
        vv_cache_client_remove(&b->cl);
        vv_cache_free(b->cache);
    }
    free(b->e);
    for (int l = 1; l < VV_PYRAMID_MAX_LEVELS; l++)
        free(b->lv[l].c);
    if (b->fd >= 0)
        close(b->fd);
    vv_volume_free(b->header);
    free(b->path);
    free(b->data_path);
    free(b);
}

/* ---- reading a brick ------------------------------------------------------- */

/* The @p bytes at @p off of a .vvb -- a brick's stored box or a level's
 * chunk, of @p want bytes -- into @p dst (as stored: little-endian): one
 * pread, then with zstd one frame decoded into exactly @p want bytes.
 * Uncounted: any thread. */
static vv_status
read_piece(const vv_bricked *b, uint64_t off, uint64_t bytes, void *dst, uint64_t want,
           const char *what) {
    if (!b->zstd)
        return pread_exact(b, dst, (size_t)want, off, what);
    void *z = malloc((size_t)bytes);
    if (!z)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = pread_exact(b, z, (size_t)bytes, off, what);
    if (s == VV_OK) {
        const unsigned long long fs = ZSTD_getFrameContentSize(z, (size_t)bytes);
        const unsigned long long zb = bytes, zo = off;
        if (fs == ZSTD_CONTENTSIZE_ERROR)
            s = vv_error_set(VV_ERR_FORMAT, "%s: %llu bytes at offset %llu are not a zstd frame",
                             what, zb, zo);
        else if (fs == ZSTD_CONTENTSIZE_UNKNOWN)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: the zstd frame at offset %llu does not give its size", what, zo);
        else if (fs != (unsigned long long)want)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: the zstd frame at offset %llu holds %llu bytes; its box needs "
                             "%llu",
                             what, zo, fs, (unsigned long long)want);
        else {
            const size_t r = ZSTD_decompress(dst, (size_t)want, z, (size_t)bytes);
            if (ZSTD_isError(r) || r != (size_t)want)
                s = vv_error_set(VV_ERR_FORMAT,
                                 "%s: the zstd frame of %llu bytes at offset %llu: %s", what, zb,
                                 zo, ZSTD_isError(r) ? ZSTD_getErrorName(r) : "short");
        }
    }
    free(z);
    return s;
}

/* Brick @p index of a .vvb, its stored box of @p want bytes, into @p dst
 * (as stored), counted. */
static vv_status
read_vvb_brick(vv_bricked *b, int index, void *dst, uint64_t want, const char *what) {
    const brick_entry *e = &b->e[index];
    const vv_status s = read_piece(b, e->offset, e->bytes, dst, want, what);
    if (s == VV_OK)
        __atomic_fetch_add(&b->st.bytes_read, e->bytes, __ATOMIC_RELAXED);
    return s;
}

/* The voxels of box slo..shi into v (dims the box's). */
static vv_status
read_box(vv_bricked *b, int index, const vv_brick_info *in, vv_volume *v) {
    const size_t vs = vv_voxel_type_size(b->header->type);
    const uint64_t n = box_voxels(in->slo, in->shi);
    char what[96];
    if (index >= 0)
        snprintf(what, sizeof what, "brick %d", index);
    else
        snprintf(what, sizeof what, "box %d..%d x %d..%d x %d..%d", in->slo[0], in->shi[0],
                 in->slo[1], in->shi[1], in->slo[2], in->shi[2]);
    vv_status s = VV_OK;
    if (b->vvb) {
        s = read_vvb_brick(b, index, v->data, n * vs, what);
    } else {
        const int *d = b->header->dims;
        const size_t row = (size_t)(in->shi[0] - in->slo[0] + 1) * vs;
        char *dst = v->data;
        for (int k = in->slo[2]; k <= in->shi[2] && s == VV_OK; k++)
            for (int j = in->slo[1]; j <= in->shi[1] && s == VV_OK; j++) {
                const uint64_t off =
                    b->data_off + (((uint64_t)k * (uint64_t)d[1] + (uint64_t)j) * (uint64_t)d[0] +
                                   (uint64_t)in->slo[0]) *
                                      vs;
                s = read_at(b, dst, row, off, what);
                dst += row;
            }
    }
    if (s == VV_OK && b->swap && vs > 1)
        swap_bytes(v->data, (size_t)n, vs);
    return s;
}

/* One zstd frame of @p n bytes at @p src into @p dst (@p cap bytes): level 3,
 * its content size and a checksum in the frame (a scribbled frame fails to
 * decode rather than giving other voxels). The size, or a zstd error code. */
static size_t
zstd_frame(void *dst, size_t cap, const void *src, size_t n) {
    ZSTD_CCtx *c = ZSTD_createCCtx();
    if (!c)
        return (size_t)-1; /* ZSTD_isError: a generic error */
    size_t r = ZSTD_CCtx_setParameter(c, ZSTD_c_compressionLevel, VVB_ZSTD_LEVEL);
    if (!ZSTD_isError(r))
        r = ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 1);
    if (!ZSTD_isError(r))
        r = ZSTD_compress2(c, dst, cap, src, n);
    ZSTD_freeCCtx(c);
    return r;
}

/* ---- pyramid levels ------------------------------------------------------ */

/* The dims of each level of a volume of @p d voxels: level 0 is the volume,
 * each next level halves every axis longer than 1 (rounding up) until every
 * axis fits one chunk, as the OME-Zarr writer's levels; at most
 * VV_PYRAMID_MAX_LEVELS. Returns the count. */
static int
level_dims(const int d[3], int dims[VV_PYRAMID_MAX_LEVELS][3]) {
    memcpy(dims[0], d, sizeof dims[0]);
    int n = 1;
    while (n < VV_PYRAMID_MAX_LEVELS && (dims[n - 1][0] > VVB_CHUNK || dims[n - 1][1] > VVB_CHUNK ||
                                         dims[n - 1][2] > VVB_CHUNK)) {
        for (int a = 0; a < 3; a++)
            dims[n][a] = dims[n - 1][a] > 1 ? (dims[n - 1][a] + 1) / 2 : 1;
        n++;
    }
    return n;
}

/* Level @p l's geometry (l >= 1) from its dims, with its chunk grid. */
static void
level_grid(vvb_level *L, const int dims[3]) {
    L->n = 1;
    for (int a = 0; a < 3; a++) {
        L->dims[a] = dims[a];
        L->nc[a] = (dims[a] + VVB_CHUNK - 1) / VVB_CHUNK;
        L->n *= L->nc[a];
    }
}

/* Chunk @p i of level @p L: its first voxel and voxel counts. */
static void
chunk_box(const vvb_level *L, int i, int org[3], int n[3]) {
    const int c[3] = {i % L->nc[0], (i / L->nc[0]) % L->nc[1], i / (L->nc[0] * L->nc[1])};
    for (int a = 0; a < 3; a++) {
        org[a] = c[a] * VVB_CHUNK;
        n[a] = L->dims[a] - org[a] < VVB_CHUNK ? L->dims[a] - org[a] : VVB_CHUNK;
    }
}

/* The bytes of the largest piece of a level (a brick's stored box at level
 * 0, a chunk above): what read_level_box's @p piece holds. */
static uint64_t
piece_bytes(const vv_bricked *b) {
    uint64_t n = 1;
    for (int a = 0; a < 3; a++) {
        const int d = b->header->dims[a], side = VV_BRICK_CELLS + 3;
        n *= (uint64_t)(d < side ? d : side);
    }
    return n * vv_voxel_type_size(b->header->type);
}

/* Voxels lo .. lo + n - 1 of level @p level into @p dst (x fastest, host
 * byte order), from the bricks (level 0: each brick's own voxels lo .. hi)
 * or the level's chunks that the box overlaps, each read once into
 * @p piece (piece_bytes); *bytes adds the bytes read. Uncounted in the
 * statistics: any thread. */
static vv_status
read_level_box(const vv_bricked *b, int level, const int lo[3], const int n[3], unsigned char *dst,
               unsigned char *piece, uint64_t *bytes) {
    const size_t vs = vv_voxel_type_size(b->header->type);
    const vvb_level *L = level > 0 ? &b->lv[level] : NULL;
    const int *grid = L ? L->nc : b->nb;
    int c0[3], c1[3];
    for (int a = 0; a < 3; a++) {
        const int side = L ? VVB_CHUNK : VV_BRICK_CELLS;
        c0[a] = lo[a] / side < grid[a] - 1 ? lo[a] / side : grid[a] - 1;
        c1[a] = (lo[a] + n[a] - 1) / side < grid[a] - 1 ? (lo[a] + n[a] - 1) / side : grid[a] - 1;
    }
    for (int ck = c0[2]; ck <= c1[2]; ck++)
        for (int cj = c0[1]; cj <= c1[1]; cj++)
            for (int ci = c0[0]; ci <= c1[0]; ci++) {
                const int i = (ck * grid[1] + cj) * grid[0] + ci;
                int own0[3], own1[3], st0[3], sn[3]; /* its own voxels; what is stored */
                uint64_t off, zbytes;
                char what[64];
                if (L) {
                    chunk_box(L, i, st0, sn);
                    for (int a = 0; a < 3; a++) {
                        own0[a] = st0[a];
                        own1[a] = st0[a] + sn[a] - 1;
                    }
                    off = L->c[i].offset;
                    zbytes = L->c[i].bytes;
                    snprintf(what, sizeof what, "level %d chunk %d", level, i);
                } else {
                    vv_brick_info in;
                    brick_boxes(b, i, &in);
                    for (int a = 0; a < 3; a++) {
                        own0[a] = in.lo[a];
                        own1[a] = in.hi[a];
                        st0[a] = in.slo[a];
                        sn[a] = in.shi[a] - in.slo[a] + 1;
                    }
                    off = b->e[i].offset;
                    zbytes = b->e[i].bytes;
                    snprintf(what, sizeof what, "brick %d", i);
                }
                const uint64_t nv = (uint64_t)sn[0] * sn[1] * sn[2];
                vv_status s = read_piece(b, off, zbytes, piece, nv * vs, what);
                if (s != VV_OK)
                    return s;
                *bytes += zbytes;
                if (b->swap && vs > 1)
                    swap_bytes(piece, (size_t)nv, vs);
                int g0[3], g1[3]; /* the overlap, inclusive */
                for (int a = 0; a < 3; a++) {
                    g0[a] = lo[a] > own0[a] ? lo[a] : own0[a];
                    g1[a] = lo[a] + n[a] - 1 < own1[a] ? lo[a] + n[a] - 1 : own1[a];
                }
                for (int k = g0[2]; k <= g1[2]; k++)
                    for (int j = g0[1]; j <= g1[1]; j++)
                        memcpy(dst + (((size_t)(k - lo[2]) * n[1] + (j - lo[1])) * n[0] +
                                      (g0[0] - lo[0])) *
                                         vs,
                               piece + (((size_t)(k - st0[2]) * sn[1] + (j - st0[1])) * sn[0] +
                                        (g0[0] - st0[0])) *
                                           vs,
                               (size_t)(g1[0] - g0[0] + 1) * vs);
            }
    return VV_OK;
}

/* The cache drops brick @p e's voxels to make room (lock held). */
static void
client_drop(vv_cache_client *cl, vv_cache_entry *ce) {
    (void)cl;
    brick_entry *e = (brick_entry *)((char *)ce - offsetof(brick_entry, ce));
    vv_volume_free(e->vol);
    e->vol = NULL;
}

/* Bricks are read in no planned order: the cache never asks (planned stays 0). */
static int
client_next_use(vv_cache_client *cl, vv_cache_entry *ce) {
    (void)cl;
    (void)ce;
    return INT_MAX;
}

vv_status
vv_bricked_load(vv_bricked *b, int index, vv_volume **out) {
    *out = NULL;
    if (index < 0 || index >= b->n)
        return vv_error_set(VV_ERR_INVALID, "bricks: no brick %d", index);
    brick_entry *e = &b->e[index];
    vv_cache_lock(b->cache);
    if (e->vol) {
        vv_cache_touch(b->cache, &e->ce);
        b->st.hits++;
        *out = vv_volume_ref(e->vol);
        vv_cache_unlock(b->cache);
        return VV_OK;
    }
    vv_brick_info in;
    brick_boxes(b, index, &in);
    const uint64_t bytes = box_voxels(in.slo, in.shi) * vv_voxel_type_size(b->header->type);
    vv_cache_make_room(b->cache, bytes, 0);
    vv_cache_unlock(b->cache);
    int dims[3];
    for (int a = 0; a < 3; a++)
        dims[a] = in.shi[a] - in.slo[a] + 1;
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, b->header->type);
    if (s == VV_OK)
        s = read_box(b, index, &in, v);
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_error_prefix(s, "bricks: %s", vv_path_basename(b->path));
    }
    /* the whole volume's frame and range (a region's voxels, sys/renderer.h) */
    memcpy(v->spacing, b->header->spacing, sizeof v->spacing);
    memcpy(v->origin, b->header->origin, sizeof v->origin);
    memcpy(v->direction, b->header->direction, sizeof v->direction);
    v->range[0] = b->header->range[0];
    v->range[1] = b->header->range[1];
    v->unit = b->header->unit;
    v->space = b->header->space;
    vv_cache_lock(b->cache);
    if (e->vol) { /* another thread read it meanwhile */
        vv_volume_free(v);
        v = e->vol;
    } else {
        vv_cache_make_room(b->cache, bytes, 0);
        e->vol = v;
        e->loads++;
        b->st.loads++;
        e->ce.ready = 1;
        vv_cache_insert(b->cache, &b->cl, &e->ce, bytes);
    }
    *out = vv_volume_ref(v);
    vv_cache_unlock(b->cache);
    return VV_OK;
}

/* ---- opening ---------------------------------------------------------------- */

/* The brick grid of b's header dims into b->nb and b->n (no entries yet);
 * VV_ERR_LIMIT over 2^26 bricks. */
static vv_status
brick_grid(vv_bricked *b) {
    for (int a = 0; a < 3; a++) {
        const int cells = b->header->dims[a] > 1 ? b->header->dims[a] - 1 : 1;
        b->nb[a] = (cells + VV_BRICK_CELLS - 1) / VV_BRICK_CELLS;
    }
    const uint64_t n = (uint64_t)b->nb[0] * (uint64_t)b->nb[1] * (uint64_t)b->nb[2];
    if (n > (uint64_t)1 << 26)
        return vv_error_set(VV_ERR_LIMIT, "bricks: %llu bricks", (unsigned long long)n);
    b->n = (int)n;
    return VV_OK;
}

/* brick_grid, then the bricks' entries. */
static vv_status
alloc_bricks(vv_bricked *b) {
    vv_status s = brick_grid(b);
    if (s != VV_OK)
        return s;
    b->e = calloc((size_t)b->n, sizeof *b->e);
    if (!b->e)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    return VV_OK;
}

/* The budget: the largest brick's working set is reserved, the cache holds
 * the rest with every other source's pieces. */
static vv_status
set_budget(vv_bricked *b) {
    const uint64_t limit = vv_cache_limit(b->cache);
    uint64_t biggest = 0;
    for (int i = 0; i < b->n; i++) {
        vv_brick_info in;
        brick_boxes(b, i, &in);
        const uint64_t v = box_voxels(in.slo, in.shi);
        biggest = v > biggest ? v : biggest;
    }
    const uint64_t vs = vv_voxel_type_size(b->header->type);
    const uint64_t need = biggest * vs + working_set(b, biggest);
    if (limit < need)
        return vv_error_set(VV_ERR_LIMIT,
                            "bricks: memory limit of %llu bytes is smaller than one brick (%llu "
                            "bytes of voxels and %llu to render it)",
                            (unsigned long long)limit, (unsigned long long)(biggest * vs),
                            (unsigned long long)working_set(b, biggest));
    b->cl.reserve = working_set(b, biggest);
    b->cl.next_use = client_next_use;
    b->cl.drop = client_drop;
    vv_cache_client_add(b->cache, &b->cl);
    return VV_OK;
}

/* Row j of slice 0 of @p v as doubles. */
static void
get_row(const vv_volume *v, int j, double *row) {
    const size_t n = (size_t)v->dims[0], base = (size_t)j * n;
    switch (v->type) {
    case VV_U8:
        for (size_t i = 0; i < n; i++)
            row[i] = ((const uint8_t *)v->data)[base + i];
        return;
    case VV_U16:
        for (size_t i = 0; i < n; i++)
            row[i] = ((const uint16_t *)v->data)[base + i];
        return;
    case VV_I16:
        for (size_t i = 0; i < n; i++)
            row[i] = ((const int16_t *)v->data)[base + i];
        return;
    case VV_F32:
        for (size_t i = 0; i < n; i++)
            row[i] = ((const float *)v->data)[base + i];
        return;
    default:
        for (size_t i = 0; i < n; i++)
            row[i] = vv_volume_get(v, (int)i, j, 0);
    }
}

/* Raw layout: one streaming pass, a slice at a time, for the value range
 * and every brick's min/max over the voxels it reads. */
static vv_status
scan_raw(vv_bricked *b) {
    const int *d = b->header->dims;
    const vv_voxel_type t = b->header->type;
    const size_t vs = vv_voxel_type_size(t);
    const size_t slice = (size_t)d[0] * (size_t)d[1];
    void *buf = malloc(slice * vs);
    double *row = malloc(sizeof(double) * (size_t)d[0]);
    if (!buf || !row) {
        free(buf);
        free(row);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < b->n; i++) {
        b->e[i].vmin = INFINITY;
        b->e[i].vmax = -INFINITY;
    }
    double lo = INFINITY, hi = -INFINITY;
    vv_status s = VV_OK;
    vv_volume tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.dims[0] = d[0];
    tmp.dims[1] = d[1];
    tmp.dims[2] = 1;
    tmp.type = t;
    tmp.data = buf;
    /* per axis, the bricks whose read box holds index x: at most two */
    int *cand[3];
    for (int a = 0; a < 3; a++) {
        cand[a] = malloc(sizeof(int) * 2 * (size_t)d[a]);
        if (!cand[a]) {
            for (int q = 0; q < a; q++)
                free(cand[q]);
            free(buf);
            free(row);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        for (int x = 0; x < d[a]; x++) {
            int n = 0;
            cand[a][2 * x] = cand[a][2 * x + 1] = -1;
            for (int c = x / VV_BRICK_CELLS - 1; c <= x / VV_BRICK_CELLS && n < 2; c++) {
                if (c < 0 || c >= b->nb[a])
                    continue;
                const int blo = c * VV_BRICK_CELLS, last = d[a] - 1;
                const int bhi = blo + VV_BRICK_CELLS < last ? blo + VV_BRICK_CELLS : last;
                const int slo = blo > 0 ? blo - 1 : 0, shi = bhi < last ? bhi + 1 : last;
                if (x >= slo && x <= shi)
                    cand[a][2 * x + n++] = c;
            }
            /* the last brick of an axis may reach the end from further back */
            const int c2 = x / VV_BRICK_CELLS + 1;
            if (n < 2 && c2 < b->nb[a] && x >= c2 * VV_BRICK_CELLS - 1)
                cand[a][2 * x + n++] = c2;
        }
    }
    double *bmn = malloc(sizeof(double) * (size_t)b->nb[0]);
    double *bmx = malloc(sizeof(double) * (size_t)b->nb[0]);
    if (!bmn || !bmx)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int k = 0; k < d[2] && s == VV_OK; k++) {
        s = read_at(b, buf, slice * vs, b->data_off + (uint64_t)k * slice * vs, "scan");
        if (s != VV_OK)
            break;
        if (b->swap && vs > 1)
            swap_bytes(buf, slice, vs);
        for (int j = 0; j < d[1]; j++) {
            get_row(&tmp, j, row);
            for (int bi = 0; bi < b->nb[0]; bi++) {
                bmn[bi] = INFINITY;
                bmx[bi] = -INFINITY;
            }
            for (int i = 0; i < d[0]; i++) {
                const double x = row[i];
                if (x != x)
                    continue;
                for (int q = 0; q < 2; q++) {
                    const int bi = cand[0][2 * i + q];
                    if (bi < 0)
                        break;
                    bmn[bi] = x < bmn[bi] ? x : bmn[bi];
                    bmx[bi] = x > bmx[bi] ? x : bmx[bi];
                }
            }
            for (int bi = 0; bi < b->nb[0]; bi++) {
                lo = bmn[bi] < lo ? bmn[bi] : lo;
                hi = bmx[bi] > hi ? bmx[bi] : hi;
                for (int qk = 0; qk < 2; qk++)
                    for (int qj = 0; qj < 2; qj++) {
                        const int bk = cand[2][2 * k + qk], bj = cand[1][2 * j + qj];
                        if (bk < 0 || bj < 0)
                            continue;
                        brick_entry *e = &b->e[(bk * b->nb[1] + bj) * b->nb[0] + bi];
                        e->vmin = bmn[bi] < e->vmin ? bmn[bi] : e->vmin;
                        e->vmax = bmx[bi] > e->vmax ? bmx[bi] : e->vmax;
                    }
            }
        }
    }
    free(bmn);
    free(bmx);
    for (int a = 0; a < 3; a++)
        free(cand[a]);
    free(buf);
    free(row);
    if (s != VV_OK)
        return s;
    if (!(lo <= hi))
        lo = hi = 0;
    b->header->range[0] = lo;
    b->header->range[1] = hi;
    return VV_OK;
}

static vv_status
open_data(vv_bricked *b, const char *path) {
    b->fd = open(path, O_RDONLY);
    if (b->fd < 0)
        return vv_error_set(VV_ERR_IO, "%s: %s", vv_path_basename(path), strerror(errno));
    struct stat st;
    if (fstat(b->fd, &st) != 0)
        return vv_error_set(VV_ERR_IO, "%s: %s", vv_path_basename(path), strerror(errno));
    b->file_size = (uint64_t)st.st_size;
    return VV_OK;
}

static vv_status
open_raw_layout(vv_bricked *b, int scan) {
    vv_status s = open_data(b, b->data_path);
    if (s != VV_OK)
        return s;
    const uint64_t bytes = (uint64_t)b->header->dims[0] * (uint64_t)b->header->dims[1] *
                           (uint64_t)b->header->dims[2] * vv_voxel_type_size(b->header->type);
    if (b->data_off > b->file_size || b->file_size - b->data_off < bytes) {
        /* the data file named when it is not the file opened (a detached NRRD) */
        const char *dn = vv_path_basename(b->data_path);
        const int other = strcmp(dn, vv_path_basename(b->path)) != 0;
        return vv_error_set(VV_ERR_FORMAT,
                            "%s%s%llu bytes of voxels from offset %llu run past the end of the "
                            "file (%llu bytes)",
                            other ? dn : "", other ? ": " : "", (unsigned long long)bytes,
                            (unsigned long long)b->data_off, (unsigned long long)b->file_size);
    }
    if ((s = alloc_bricks(b)) != VV_OK)
        return s;
    if (scan)
        return scan_raw(b);
    for (int i = 0; i < b->n; i++) {
        b->e[i].vmin = -INFINITY;
        b->e[i].vmax = INFINITY;
    }
    return VV_OK;
}

/* What is wrong with a piece of a .vvb -- a brick's voxels or a level's
 * chunk -- of @p bytes at @p off, whose box (@p box names it) holds @p want
 * bytes: 0 when nothing, else 1 and the phrase in @p why: its size against
 * the box's (raw: equal; zstd: 1 to the compression bound), or where it
 * runs past the end of the file. */
static int
piece_problem(const vv_bricked *b, uint64_t off, uint64_t bytes, uint64_t want, const char *box,
              char *why, size_t cap) {
    const uint64_t bound = b->zstd ? ZSTD_compressBound((size_t)want) : want;
    if (b->zstd ? bytes == 0 || bytes > bound : bytes != want)
        snprintf(why, cap, " has %llu bytes; its box %s needs %s%llu", (unsigned long long)bytes,
                 box, b->zstd ? "compressed 1 to " : "", (unsigned long long)bound);
    else if (off < VVB_HEADER || off > b->file_size || b->file_size - off < bytes)
        snprintf(why, cap, ": %llu bytes at offset %llu run past the end of the file (%llu bytes)",
                 (unsigned long long)bytes, (unsigned long long)off,
                 (unsigned long long)b->file_size);
    else
        return 0;
    return 1;
}

/* The pyramid levels of a .vvb: @p n levels in all (0 and 1: the bricks
 * only), the table at @p table_off; each level's dims must be the halving
 * rule's (level_dims), its index and chunks inside the file. */
static vv_status
open_levels(vv_bricked *b, uint32_t n, uint64_t table_off) {
    b->n_levels = 1;
    if (n <= 1)
        return VV_OK;
    int dims[VV_PYRAMID_MAX_LEVELS][3];
    const int want = level_dims(b->header->dims, dims);
    if (n != (uint32_t)want)
        return vv_error_set(VV_ERR_FORMAT, "%u pyramid levels; %dx%dx%d voxels make %d", n,
                            dims[0][0], dims[0][1], dims[0][2], want);
    const uint64_t tbytes = (uint64_t)(n - 1) * VVB_LEVEL_RECORD;
    if (table_off < VVB_HEADER || table_off > b->file_size || b->file_size - table_off < tbytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "level table of %llu bytes at offset %llu runs past the end of the "
                            "file (%llu bytes)",
                            (unsigned long long)tbytes, (unsigned long long)table_off,
                            (unsigned long long)b->file_size);
    unsigned char t[VV_PYRAMID_MAX_LEVELS * VVB_LEVEL_RECORD];
    vv_status s = read_at(b, t, (size_t)tbytes, table_off, "level table");
    const size_t vs = vv_voxel_type_size(b->header->type);
    for (int l = 1; l < want && s == VV_OK; l++) {
        const unsigned char *r = t + (size_t)(l - 1) * VVB_LEVEL_RECORD;
        vvb_level *L = &b->lv[l];
        level_grid(L, dims[l]);
        const uint64_t ioff = get_u64(r + 16), count = get_u64(r + 24);
        if (get_u32(r) != (uint32_t)dims[l][0] || get_u32(r + 4) != (uint32_t)dims[l][1] ||
            get_u32(r + 8) != (uint32_t)dims[l][2] || get_u32(r + 12) != VVB_CHUNK ||
            count != (uint64_t)L->n)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: %ux%ux%u voxels in %llu chunks of %u (expected "
                                "%dx%dx%d in %d of %d)",
                                l, get_u32(r), get_u32(r + 4), get_u32(r + 8),
                                (unsigned long long)count, get_u32(r + 12), dims[l][0], dims[l][1],
                                dims[l][2], L->n, VVB_CHUNK);
        const uint64_t ibytes = count * VVB_CHUNK_RECORD;
        if (ioff < VVB_HEADER || ioff > b->file_size || b->file_size - ioff < ibytes)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: index of %llu bytes at offset %llu runs past the end "
                                "of the file (%llu bytes)",
                                l, (unsigned long long)ibytes, (unsigned long long)ioff,
                                (unsigned long long)b->file_size);
        unsigned char *idx = malloc((size_t)ibytes);
        L->c = calloc((size_t)L->n, sizeof *L->c);
        if (!idx || !L->c) {
            free(idx);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        s = read_at(b, idx, (size_t)ibytes, ioff, "level index");
        for (int i = 0; i < L->n && s == VV_OK; i++) {
            const unsigned char *e = idx + (size_t)i * VVB_CHUNK_RECORD;
            vvb_chunk *c = &L->c[i];
            c->offset = get_u64(e);
            c->bytes = get_u64(e + 8);
            c->vmin = get_f64(e + 16);
            c->vmax = get_f64(e + 24);
            int o[3], cn[3];
            chunk_box(L, i, o, cn);
            const uint64_t cw = (uint64_t)cn[0] * cn[1] * cn[2] * vs;
            char box[64], why[256];
            snprintf(box, sizeof box, "of %dx%dx%d voxels", cn[0], cn[1], cn[2]);
            if (piece_problem(b, c->offset, c->bytes, cw, box, why, sizeof why))
                s = vv_error_set(VV_ERR_FORMAT, "level %d: chunk %d%s", l, i, why);
            else if (!(c->vmin <= c->vmax))
                s = vv_error_set(VV_ERR_FORMAT, "level %d: chunk %d: min %g > max %g", l, i,
                                 c->vmin, c->vmax);
        }
        free(idx);
    }
    if (s == VV_OK)
        b->n_levels = want;
    return s;
}

static vv_status
open_vvb(vv_bricked *b) {
    vv_status s = open_data(b, b->data_path);
    if (s != VV_OK)
        return s;
    unsigned char h[VVB_HEADER];
    if (b->file_size < VVB_HEADER)
        return vv_error_set(VV_ERR_FORMAT, "file of %llu bytes is shorter than the header",
                            (unsigned long long)b->file_size);
    if ((s = read_at(b, h, VVB_HEADER, 0, "header")) != VV_OK)
        return s;
    if (memcmp(h, VVB_MAGIC, 8) != 0)
        return vv_error_set(VV_ERR_FORMAT, "not a .vvb file (no \"%s\" magic)", VVB_MAGIC);
    const uint32_t hsize = get_u32(h + 8), cells = get_u32(h + 12);
    int dims[3];
    for (int a = 0; a < 3; a++)
        dims[a] = (int)get_u32(h + 16 + 4 * a);
    const uint32_t type = get_u32(h + 28);
    if (hsize != VVB_HEADER || cells != VV_BRICK_CELLS)
        return vv_error_set(VV_ERR_FORMAT, "header size %u, brick side %u (expected %d, %d)", hsize,
                            cells, VVB_HEADER, VV_BRICK_CELLS);
    if (type > VV_F64)
        return vv_error_set(VV_ERR_FORMAT, "voxel type %u", type);
    uint64_t vbytes;
    if ((s = vv_volume_check_limits(dims, (vv_voxel_type)type, &vbytes)) != VV_OK)
        return s;
    const int one[3] = {1, 1, 1};
    if ((s = vv_volume_new(&b->header, one, (vv_voxel_type)type)) != VV_OK)
        return s;
    vv_volume *v = b->header;
    memcpy(v->dims, dims, sizeof dims);
    b->has_coarse = get_u32(h + 32) != 0;
    const uint32_t codec = get_u32(h + 200);
    if (codec > VVB_CODEC_ZSTD)
        return vv_error_set(VV_ERR_FORMAT, "unknown brick codec %u (0 raw, 1 zstd)", codec);
    b->zstd = codec == VVB_CODEC_ZSTD;
    if (b->zstd && !b->has_coarse)
        return vv_error_set(VV_ERR_FORMAT, "zstd bricks without coarse levels");
    v->unit = (vv_unit)get_u32(h + 36);
    v->space = (vv_space)get_u32(h + 40);
    for (int a = 0; a < 3; a++) {
        v->spacing[a] = get_f64(h + 48 + 8 * a);
        v->origin[a] = get_f64(h + 72 + 8 * a);
    }
    for (int a = 0; a < 9; a++)
        v->direction[a] = get_f64(h + 96 + 8 * a);
    v->range[0] = get_f64(h + 168);
    v->range[1] = get_f64(h + 176);
    for (int a = 0; a < 3; a++)
        if (!(v->spacing[a] > 0) || !isfinite(v->spacing[a]) || !isfinite(v->origin[a]))
            return vv_error_set(VV_ERR_FORMAT, "bad spacing or origin on axis %d", a);
    if (!(v->range[0] <= v->range[1]))
        return vv_error_set(VV_ERR_FORMAT, "bad value range %g..%g", v->range[0], v->range[1]);
    const uint64_t index_off = get_u64(h + 184), count = get_u64(h + 192);
    /* the entries are allocated once the file is known to hold the index */
    if ((s = brick_grid(b)) != VV_OK)
        return s;
    if (count != (uint64_t)b->n)
        return vv_error_set(VV_ERR_FORMAT, "index of %llu bricks; %dx%dx%d voxels need %d",
                            (unsigned long long)count, dims[0], dims[1], dims[2], b->n);
    const uint64_t ibytes = count * VVB_RECORD;
    if (index_off < VVB_HEADER || index_off > b->file_size || b->file_size - index_off < ibytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "index of %llu bytes at offset %llu runs past the end of the file "
                            "(%llu bytes)",
                            (unsigned long long)ibytes, (unsigned long long)index_off,
                            (unsigned long long)b->file_size);
    if (!(b->e = calloc((size_t)b->n, sizeof *b->e)))
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    unsigned char *idx = malloc((size_t)ibytes);
    if (!idx)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    s = read_at(b, idx, (size_t)ibytes, index_off, "index");
    const size_t vs = vv_voxel_type_size(v->type);
    for (int i = 0; i < b->n && s == VV_OK; i++) {
        const unsigned char *r = idx + (size_t)i * VVB_RECORD;
        brick_entry *e = &b->e[i];
        e->offset = get_u64(r);
        e->bytes = get_u64(r + 8);
        e->vmin = get_f64(r + 16);
        e->vmax = get_f64(r + 24);
        e->coarse_offset = get_u64(r + 32);
        e->coarse_bytes = get_u64(r + 40);
        vv_brick_info in;
        brick_boxes(b, i, &in);
        const uint64_t want = box_voxels(in.slo, in.shi) * vs;
        int cd[3];
        coarse_dims(&in, cd);
        const uint64_t cwant = b->has_coarse ? (uint64_t)cd[0] * cd[1] * cd[2] * vs : 0;
        char box[96], why[256];
        snprintf(box, sizeof box, "%d..%d x %d..%d x %d..%d", in.slo[0], in.shi[0], in.slo[1],
                 in.shi[1], in.slo[2], in.shi[2]);
        if (piece_problem(b, e->offset, e->bytes, want, box, why, sizeof why))
            s = vv_error_set(VV_ERR_FORMAT, "index: brick %d (%d,%d,%d)%s", i,
                             in.lo[0] / VV_BRICK_CELLS, in.lo[1] / VV_BRICK_CELLS,
                             in.lo[2] / VV_BRICK_CELLS, why);
        else if (e->coarse_bytes != cwant ||
                 (cwant && (e->coarse_offset > b->file_size ||
                            b->file_size - e->coarse_offset < e->coarse_bytes)))
            s = vv_error_set(VV_ERR_FORMAT,
                             "index: brick %d: coarse level of %llu bytes at offset %llu (expected "
                             "%llu bytes within the file)",
                             i, (unsigned long long)e->coarse_bytes,
                             (unsigned long long)e->coarse_offset, (unsigned long long)cwant);
        else if (!(e->vmin <= e->vmax))
            s = vv_error_set(VV_ERR_FORMAT, "index: brick %d: min %g > max %g", i, e->vmin,
                             e->vmax);
    }
    free(idx);
    if (s == VV_OK)
        s = open_levels(b, get_u32(h + 204), get_u64(h + 208));
    return s;
}

/* A new bricked volume of @p path in @p cache, nothing opened yet. */
static vv_status
bricked_new(vv_bricked **out, const char *path, vv_cache *cache) {
    *out = NULL;
    vv_bricked *b = calloc(1, sizeof *b);
    if (!b)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    b->cache = vv_cache_ref(cache ? cache : vv_cache_process());
    b->fd = -1;
    if (!(b->path = strdup(path))) {
        vv_bricked_free(b);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    *out = b;
    return VV_OK;
}

/* @p b opened (budget set) or freed with the error named after @p path. */
static vv_status
bricked_done(vv_bricked **out, vv_bricked *b, vv_status s, const char *path) {
    if (s == VV_OK)
        s = set_budget(b);
    if (s != VV_OK) {
        vv_bricked_free(b);
        return vv_error_prefix(s, "bricks: %s", vv_path_basename(path));
    }
    *out = b;
    return VV_OK;
}

vv_status
vv_bricked_open_layout(vv_bricked **out, const char *path, vv_volume *header, char *data_path,
                       uint64_t offset, int big_endian, vv_cache *cache, int scan) {
    *out = NULL;
    vv_bricked *b = NULL;
    vv_status s = bricked_new(&b, path, cache);
    if (s != VV_OK) {
        vv_volume_free(header);
        free(data_path);
        return s;
    }
    b->header = header;
    b->data_path = data_path;
    b->data_off = offset;
    b->swap = (big_endian ? 1 : 0) == vv_host_is_little_endian();
    if ((s = vv_volume_check_limits(header->dims, header->type, NULL)) == VV_OK)
        s = open_raw_layout(b, scan);
    return bricked_done(out, b, s, path);
}

/* A .vvb file by its bricks. */
static vv_status
vvb_open(vv_bricked **out, const char *path, vv_cache *cache) {
    vv_bricked *b = NULL;
    vv_status s = bricked_new(&b, path, cache);
    if (s != VV_OK)
        return s;
    b->vvb = 1;
    b->swap = !vv_host_is_little_endian();
    s = (b->data_path = strdup(path)) ? open_vvb(b) : vv_error_set(VV_ERR_NOMEM, "out of memory");
    return bricked_done(out, b, s, path);
}

/* The .vvb row's open_bricks. */
static vv_status
vvb_open_bricks(vv_source **out, const char *path, int header_only, vv_cache *cache) {
    (void)header_only; /* its index has the ranges */
    vv_bricked *b = NULL;
    vv_status s = vvb_open(&b, path, cache);
    return s == VV_OK ? vv_bricked_source_new(out, b, "vvb") : s;
}

/* @p path by bricks: a .vvb (its magic), a raw file when @p raw, else the
 * raw layout of the row detection finds (an uncompressed NRRD). */
static vv_status
bricked_open(vv_bricked **out, const char *path, const vv_raw_params *raw, vv_cache *cache,
             int scan) {
    *out = NULL;
    const size_t n = strlen(path);
    if (!raw && (vv_vvb_probe(path) || (n > 4 && strcmp(path + n - 4, ".vvb") == 0)))
        return vvb_open(out, path, cache); /* named .vvb: its magic checked */
    vv_volume *h = NULL;
    char *data = NULL;
    uint64_t off = 0;
    int big = 0;
    vv_status s;
    if (raw) {
        s = vv_raw_layout(path, raw, &h, &data, &off, &big);
    } else {
        const vv_format_record *r =
            vv_format_record_of(vv_format_detect_kind(path, VV_DATA_VOLUME, 0));
        vv_load_options lo;
        vv_load_options_init(&lo);
        s = !r || !r->raw_layout
                ? vv_error_set(VV_ERR_FORMAT, "%s: not a file read by bricks (.vvb, raw, raw NRRD)",
                               vv_path_basename(path))
                : r->raw_layout(path, &lo, &h, &data, &off, &big);
        if (s == VV_ERR_UNSUPPORTED)
            s = VV_ERR_FORMAT; /* "must be converted first" */
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "bricks: %s", vv_path_basename(path));
    return vv_bricked_open_layout(out, path, h, data, off, big, cache, scan);
}

vv_status
vv_bricked_open(vv_bricked **out, const char *path, const vv_raw_params *raw, vv_cache *cache) {
    return bricked_open(out, path, raw, cache, 1);
}

vv_status
vv_bricked_open_header(vv_bricked **out, const char *path, const vv_raw_params *raw,
                       vv_cache *cache) {
    return bricked_open(out, path, raw, cache, 0);
}

void
vv_bricked_set_range(vv_bricked *b, double lo, double hi) {
    b->header->range[0] = lo;
    b->header->range[1] = hi;
}

vv_status
vv_bricked_box(void *bricked, const int lo[3], const int hi[3], vv_volume **out) {
    return vv_bricked_read_box(bricked, lo, hi, out);
}

vv_status
vv_bricked_read_box(vv_bricked *b, const int lo[3], const int hi[3], vv_volume **out) {
    *out = NULL;
    const int *d = b->header->dims;
    int dims[3];
    for (int a = 0; a < 3; a++) {
        if (lo[a] < 0 || hi[a] >= d[a] || lo[a] > hi[a])
            return vv_error_set(VV_ERR_INVALID, "bricks: box %d..%d outside 0..%d on axis %d",
                                lo[a], hi[a], d[a] - 1, a);
        dims[a] = hi[a] - lo[a] + 1;
    }
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, b->header->type);
    if (s != VV_OK)
        return s;
    const size_t vs = vv_voxel_type_size(b->header->type);
    if (!b->vvb) {
        vv_brick_info in;
        memcpy(in.slo, lo, sizeof in.slo);
        memcpy(in.shi, hi, sizeof in.shi);
        s = read_box(b, -1, &in, v);
    } else {
        /* every brick overlapping the box, read whole, its overlap copied */
        for (int i = 0; i < b->n && s == VV_OK; i++) {
            vv_brick_info in;
            brick_boxes(b, i, &in);
            int ol[3], oh[3], ok = 1;
            for (int a = 0; a < 3; a++) {
                ol[a] = in.slo[a] > lo[a] ? in.slo[a] : lo[a];
                oh[a] = in.shi[a] < hi[a] ? in.shi[a] : hi[a];
                ok &= ol[a] <= oh[a];
            }
            if (!ok)
                continue;
            const int bd[3] = {in.shi[0] - in.slo[0] + 1, in.shi[1] - in.slo[1] + 1,
                               in.shi[2] - in.slo[2] + 1};
            const uint64_t bbytes = box_voxels(in.slo, in.shi) * vs;
            char *buf = malloc((size_t)bbytes);
            if (!buf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            char what[64];
            snprintf(what, sizeof what, "brick %d", i);
            s = read_vvb_brick(b, i, buf, bbytes, what);
            if (s == VV_OK && b->swap && vs > 1)
                swap_bytes(buf, (size_t)(bbytes / vs), vs);
            const size_t row = (size_t)(oh[0] - ol[0] + 1) * vs;
            for (int k = ol[2]; s == VV_OK && k <= oh[2]; k++)
                for (int j = ol[1]; j <= oh[1]; j++)
                    memcpy(
                        (char *)v->data +
                            (((size_t)(k - lo[2]) * dims[1] + (size_t)(j - lo[1])) * dims[0] +
                             (size_t)(ol[0] - lo[0])) *
                                vs,
                        buf + (((size_t)(k - in.slo[2]) * bd[1] + (size_t)(j - in.slo[1])) * bd[0] +
                               (size_t)(ol[0] - in.slo[0])) *
                                  vs,
                        row);
            free(buf);
        }
    }
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_error_prefix(s, "bricks: %s", vv_path_basename(b->path));
    }
    memcpy(v->spacing, b->header->spacing, sizeof v->spacing);
    memcpy(v->origin, b->header->origin, sizeof v->origin);
    memcpy(v->direction, b->header->direction, sizeof v->direction);
    v->range[0] = b->header->range[0];
    v->range[1] = b->header->range[1];
    v->unit = b->header->unit;
    v->space = b->header->space;
    *out = v;
    return VV_OK;
}

/* ---- the coarse whole volume ---------------------------------------------- */

vv_status
vv_bricked_proxy(vv_bricked *b, int max_side, vv_volume **out) {
    *out = NULL;
    const int *d = b->header->dims;
    int f = 1;
    while ((d[0] - 1) / f + 1 > max_side || (d[1] - 1) / f + 1 > max_side ||
           (d[2] - 1) / f + 1 > max_side)
        f++;
    if (b->vvb && b->zstd && f == 1) {
        /* small enough whole, and zstd bricks cannot be read voxel by
         * voxel: the whole volume by bricks */
        const int lo[3] = {0, 0, 0}, hi[3] = {d[0] - 1, d[1] - 1, d[2] - 1};
        vv_status s = vv_bricked_read_box(b, lo, hi, out);
        if (s == VV_OK)
            vv_volume_update_range(*out);
        return s;
    }
    /* coarse levels hold every 4th voxel from each brick's corner */
    if (b->vvb && b->has_coarse && f > 1)
        f = (f + VVB_COARSE - 1) / VVB_COARSE * VVB_COARSE;
    int pd[3];
    for (int a = 0; a < 3; a++)
        pd[a] = (d[a] - 1) / f + 1;
    vv_volume *p = NULL;
    vv_status s = vv_volume_new(&p, pd, b->header->type);
    if (s != VV_OK)
        return s;
    const size_t vs = vv_voxel_type_size(b->header->type);
    for (int a = 0; a < 3; a++) {
        p->spacing[a] = pd[a] > 1 ? b->header->spacing[a] * (double)(d[a] - 1) / (pd[a] - 1)
                                  : b->header->spacing[a];
        p->origin[a] = b->header->origin[a];
    }
    memcpy(p->direction, b->header->direction, sizeof p->direction);
    p->unit = b->header->unit;
    p->space = b->header->space;
    char *dst = p->data;
    if (b->vvb && b->has_coarse && f > 1) {
        const int m = f / VVB_COARSE;
        for (int i = 0; i < b->n && s == VV_OK; i++) {
            vv_brick_info in;
            brick_boxes(b, i, &in);
            int cd[3];
            coarse_dims(&in, cd);
            char *cbuf = malloc((size_t)b->e[i].coarse_bytes);
            if (!cbuf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            s = read_at(b, cbuf, (size_t)b->e[i].coarse_bytes, b->e[i].coarse_offset, "coarse");
            if (s == VV_OK && b->swap && vs > 1)
                swap_bytes(cbuf, (size_t)(b->e[i].coarse_bytes / vs), vs);
            for (int k = 0; s == VV_OK && k < cd[2]; k += m)
                for (int j = 0; j < cd[1]; j += m)
                    for (int ii = 0; ii < cd[0]; ii += m) {
                        const int g[3] = {(in.lo[0] + VVB_COARSE * ii) / f,
                                          (in.lo[1] + VVB_COARSE * j) / f,
                                          (in.lo[2] + VVB_COARSE * k) / f};
                        if (g[0] >= pd[0] || g[1] >= pd[1] || g[2] >= pd[2])
                            continue;
                        memcpy(dst + (((size_t)g[2] * pd[1] + g[1]) * pd[0] + g[0]) * vs,
                               cbuf + (((size_t)k * cd[1] + j) * cd[0] + ii) * vs, vs);
                    }
            free(cbuf);
        }
    } else {
        /* rows of voxels by pread, every f-th */
        char *row = malloc((size_t)d[0] * vs);
        if (!row)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        for (int k = 0; k < pd[2] && s == VV_OK; k++)
            for (int j = 0; j < pd[1] && s == VV_OK; j++) {
                if (b->vvb) {
                    /* a .vvb without coarse levels: voxel by voxel from the bricks */
                    for (int i = 0; i < pd[0] && s == VV_OK; i++) {
                        const int g[3] = {i * f, j * f, k * f};
                        int c[3];
                        for (int a = 0; a < 3; a++) {
                            c[a] = g[a] / VV_BRICK_CELLS;
                            c[a] = c[a] < b->nb[a] ? c[a] : b->nb[a] - 1;
                        }
                        const int idx = (c[2] * b->nb[1] + c[1]) * b->nb[0] + c[0];
                        vv_brick_info in;
                        brick_boxes(b, idx, &in);
                        const uint64_t off =
                            b->e[idx].offset +
                            ((((uint64_t)(g[2] - in.slo[2]) * (in.shi[1] - in.slo[1] + 1)) +
                              (uint64_t)(g[1] - in.slo[1])) *
                                 (in.shi[0] - in.slo[0] + 1) +
                             (uint64_t)(g[0] - in.slo[0])) *
                                vs;
                        s = read_at(b, dst + (((size_t)k * pd[1] + j) * pd[0] + i) * vs, vs, off,
                                    "proxy");
                    }
                    continue;
                }
                const uint64_t off =
                    b->data_off +
                    ((uint64_t)k * f * (uint64_t)d[1] + (uint64_t)j * f) * (uint64_t)d[0] * vs;
                s = read_at(b, row, (size_t)d[0] * vs, off, "proxy");
                for (int i = 0; i < pd[0] && s == VV_OK; i++)
                    memcpy(dst + (((size_t)k * pd[1] + j) * pd[0] + i) * vs,
                           row + (size_t)i * f * vs, vs);
            }
        free(row);
        if (s == VV_OK && b->swap && vs > 1)
            swap_bytes(p->data, (size_t)pd[0] * pd[1] * pd[2], vs);
    }
    if (s != VV_OK) {
        vv_volume_free(p);
        return s;
    }
    vv_volume_update_range(p);
    *out = p;
    return VV_OK;
}

/* ---- writing .vvb --------------------------------------------------------- */

/* The pyramid levels after level 0's bricks (written to @p f, their
 * records in @p index): each level's chunks from the level before read
 * back from @p f and reduced (vv_pyr_reduce: OME-Zarr's levels, voxel for
 * voxel), each followed by its index; then the level table. *pos is the
 * file's end; *n_levels and *table_off get what the header says. Memory: a
 * chunk's 2x2x2 blocks (128^3 voxels) and one piece. */
static vv_status
write_levels(FILE *f, const char *path, const vv_volume *hdr, const int nb[3], int n, int zstd,
             const unsigned char *index, uint64_t *pos, int *n_levels, uint64_t *table_off,
             const vv_progress *progress) {
    int dims[VV_PYRAMID_MAX_LEVELS][3];
    const int nl = level_dims(hdr->dims, dims);
    *n_levels = 1;
    if (nl < 2)
        return VV_OK;
    vv_bricked rd; /* level 0 and the levels written so far, read back */
    memset(&rd, 0, sizeof rd);
    rd.fd = fileno(f);
    rd.data_path = (char *)path;
    rd.header = (vv_volume *)hdr;
    memcpy(rd.nb, nb, sizeof rd.nb);
    rd.n = n;
    rd.zstd = zstd;
    rd.swap = !vv_host_is_little_endian();
    const size_t vs = vv_voxel_type_size(hdr->type);
    const size_t work_n = (size_t)8 * VVB_CHUNK * VVB_CHUNK * VVB_CHUNK * vs,
                 chunk_n = (size_t)VVB_CHUNK * VVB_CHUNK * VVB_CHUNK * vs,
                 zcap = ZSTD_compressBound(chunk_n);
    rd.e = calloc((size_t)n, sizeof *rd.e);
    unsigned char *piece = malloc((size_t)piece_bytes(&rd)), *work = malloc(work_n),
                  *chunk = malloc(chunk_n), *z = zstd ? malloc(zcap) : NULL;
    unsigned char table[VV_PYRAMID_MAX_LEVELS * VVB_LEVEL_RECORD];
    memset(table, 0, sizeof table);
    vv_status s = rd.e && piece && work && chunk && (z || !zstd)
                      ? VV_OK
                      : vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < n && s == VV_OK; i++) {
        rd.e[i].offset = get_u64(index + (size_t)i * VVB_RECORD);
        rd.e[i].bytes = get_u64(index + (size_t)i * VVB_RECORD + 8);
    }
    uint64_t total = 0, done = 0;
    for (int l = 1; l < nl; l++) {
        vvb_level t;
        level_grid(&t, dims[l]);
        total += (uint64_t)t.n;
    }
    for (int l = 1; l < nl && s == VV_OK; l++) {
        if (fflush(f) != 0) {
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
            break;
        }
        vvb_level *L = &rd.lv[l];
        level_grid(L, dims[l]);
        if (!(L->c = calloc((size_t)L->n, sizeof *L->c))) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            break;
        }
        const int *sd = dims[l - 1];
        for (int i = 0; i < L->n && s == VV_OK; i++) {
            vv_pyr_reduce_box rb;
            memset(&rb, 0, sizeof rb);
            rb.src = work;
            rb.type = hdr->type;
            chunk_box(L, i, rb.lo, rb.n);
            for (int a = 0; a < 3; a++) {
                rb.src_dims[a] = sd[a];
                rb.step[a] = sd[a] > 1 ? 2 : 1;
                rb.src_lo[a] = rb.lo[a] * rb.step[a];
                rb.src_n[a] = (rb.lo[a] + rb.n[a]) * rb.step[a] < sd[a] ? rb.n[a] * rb.step[a]
                                                                        : sd[a] - rb.src_lo[a];
            }
            rb.dst_dims[0] = rb.n[0];
            rb.dst_dims[1] = rb.n[1];
            uint64_t got = 0;
            if ((s = read_level_box(&rd, l - 1, rb.src_lo, rb.src_n, work, piece, &got)) != VV_OK)
                break;
            vv_pyr_reduce(&rb, chunk);
            const size_t nv = (size_t)rb.n[0] * rb.n[1] * rb.n[2];
            vv_volume cv; /* the chunk, for its range (NaN left out) */
            memset(&cv, 0, sizeof cv);
            cv.type = hdr->type;
            cv.data = chunk;
            memcpy(cv.dims, rb.n, sizeof cv.dims);
            vv_volume_update_range(&cv);
            const double mn = cv.range[0], mx = cv.range[1];
            if (rd.swap)
                swap_bytes(chunk, nv, vs);
            const unsigned char *out = chunk;
            size_t out_n = nv * vs;
            if (zstd) {
                const size_t zn = zstd_frame(z, zcap, chunk, out_n);
                if (ZSTD_isError(zn)) {
                    s = vv_error_set(VV_ERR_IO, "%s: level %d chunk %d: zstd: %s", path, l, i,
                                     ZSTD_getErrorName(zn));
                    break;
                }
                out = z;
                out_n = zn;
            }
            if (fwrite(out, 1, out_n, f) != out_n) {
                s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
                break;
            }
            L->c[i] = (vvb_chunk){*pos, out_n, mn, mx};
            *pos += out_n;
            if (progress && vv_progress_report(progress, 0.875 + 0.125 * (double)++done / total))
                s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
        }
        /* the level's index, and its record in the table */
        unsigned char *idx = s == VV_OK ? malloc((size_t)L->n * VVB_CHUNK_RECORD) : NULL;
        if (s == VV_OK && !idx)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        for (int i = 0; i < L->n && s == VV_OK; i++) {
            unsigned char *e = idx + (size_t)i * VVB_CHUNK_RECORD;
            put_u64(e, L->c[i].offset);
            put_u64(e + 8, L->c[i].bytes);
            put_f64(e + 16, L->c[i].vmin);
            put_f64(e + 24, L->c[i].vmax);
        }
        if (s == VV_OK && fwrite(idx, VVB_CHUNK_RECORD, (size_t)L->n, f) != (size_t)L->n)
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
        free(idx);
        unsigned char *r = table + (size_t)(l - 1) * VVB_LEVEL_RECORD;
        for (int a = 0; a < 3; a++)
            put_u32(r + 4 * a, (uint32_t)L->dims[a]);
        put_u32(r + 12, VVB_CHUNK);
        put_u64(r + 16, *pos);
        put_u64(r + 24, (uint64_t)L->n);
        *pos += (uint64_t)L->n * VVB_CHUNK_RECORD;
    }
    const size_t tbytes = (size_t)(nl - 1) * VVB_LEVEL_RECORD;
    if (s == VV_OK && fwrite(table, 1, tbytes, f) != tbytes)
        s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
    if (s == VV_OK) {
        *table_off = *pos;
        *pos += tbytes;
        *n_levels = nl;
    }
    for (int l = 1; l < VV_PYRAMID_MAX_LEVELS; l++)
        free(rd.lv[l].c);
    free(rd.e);
    free(piece);
    free(work);
    free(chunk);
    free(z);
    return s;
}

/* Where a brick's voxels come from while writing. */
typedef vv_status (*brick_source)(void *ctx, int index, const vv_brick_info *in, void *buf);

static vv_status
write_vvb(const char *path, const vv_volume *hdr, const int nb[3], int n, unsigned flags,
          brick_source src, void *ctx, const vv_progress *progress) {
    const size_t vs = vv_voxel_type_size(hdr->type);
    /* zstd bricks always come with coarse levels (previews read those) */
    const int zstd = (flags & VV_VVB_ZSTD) != 0;
    const int coarse = zstd || (flags & VV_VVB_COARSE);
    const int levels = (flags & VV_VVB_LEVELS) != 0;
    char *tmp = malloc(strlen(path) + 16);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    sprintf(tmp, "%s.tmp%d", path, (int)getpid());
    FILE *f = fopen(tmp, "w+b"); /* the levels read the bricks back */
    if (!f) {
        vv_status s = vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
        free(tmp);
        return s;
    }
    unsigned char *index = calloc((size_t)n, VVB_RECORD);
    vv_bricked geo;
    memset(&geo, 0, sizeof geo);
    geo.header = (vv_volume *)hdr;
    memcpy(geo.nb, nb, sizeof geo.nb);
    vv_status s = index ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    uint64_t pos = VVB_HEADER + (uint64_t)n * VVB_RECORD;
    double lo = INFINITY, hi = -INFINITY;
    void *buf = NULL, *cbuf = NULL, *zbuf = NULL;
    if (s == VV_OK && fseeko(f, (off_t)pos, SEEK_SET) != 0)
        s = vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
    for (int i = 0; i < n && s == VV_OK; i++) {
        vv_brick_info in;
        brick_boxes(&geo, i, &in);
        const uint64_t nv = box_voxels(in.slo, in.shi);
        free(buf);
        buf = malloc((size_t)(nv * vs));
        if (!buf) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            break;
        }
        if ((s = src(ctx, i, &in, buf)) != VV_OK)
            break;
        vv_volume tmpv;
        memset(&tmpv, 0, sizeof tmpv);
        tmpv.type = hdr->type;
        tmpv.data = buf;
        tmpv.dims[0] = in.shi[0] - in.slo[0] + 1;
        tmpv.dims[1] = in.shi[1] - in.slo[1] + 1;
        tmpv.dims[2] = in.shi[2] - in.slo[2] + 1;
        vv_volume_update_range(&tmpv); /* NaN left out; 0 and 0 when nothing else */
        const double mn = tmpv.range[0], mx = tmpv.range[1];
        lo = mn < lo ? mn : lo;
        hi = mx > hi ? mx : hi;
        unsigned char *r = index + (size_t)i * VVB_RECORD;
        put_f64(r + 16, mn);
        put_f64(r + 24, mx);
        if (!vv_host_is_little_endian())
            swap_bytes(buf, (size_t)nv, vs);
        const void *out = buf;
        size_t out_bytes = (size_t)(nv * vs);
        if (zstd) {
            const size_t bound = ZSTD_compressBound(out_bytes);
            free(zbuf);
            zbuf = malloc(bound);
            if (!zbuf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            const size_t zn = zstd_frame(zbuf, bound, buf, out_bytes);
            if (ZSTD_isError(zn)) {
                s = vv_error_set(VV_ERR_IO, "%s: brick %d: zstd: %s", path, i,
                                 ZSTD_getErrorName(zn));
                break;
            }
            out = zbuf;
            out_bytes = zn;
        }
        put_u64(r, pos);
        put_u64(r + 8, out_bytes);
        if (fwrite(out, 1, out_bytes, f) != out_bytes) {
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
            break;
        }
        pos += out_bytes;
        if (coarse) {
            int cd[3];
            coarse_dims(&in, cd);
            const size_t cn = (size_t)cd[0] * cd[1] * cd[2];
            free(cbuf);
            cbuf = malloc(cn * vs);
            if (!cbuf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            for (int k = 0; k < cd[2]; k++)
                for (int j = 0; j < cd[1]; j++)
                    for (int ii = 0; ii < cd[0]; ii++) {
                        const size_t sx = (size_t)(in.lo[0] + VVB_COARSE * ii - in.slo[0]);
                        const size_t sy = (size_t)(in.lo[1] + VVB_COARSE * j - in.slo[1]);
                        const size_t sz = (size_t)(in.lo[2] + VVB_COARSE * k - in.slo[2]);
                        memcpy((char *)cbuf + (((size_t)k * cd[1] + j) * cd[0] + ii) * vs,
                               (char *)buf + ((sz * tmpv.dims[1] + sy) * tmpv.dims[0] + sx) * vs,
                               vs);
                    }
            put_u64(r + 32, pos);
            put_u64(r + 40, cn * vs);
            if (fwrite(cbuf, vs, cn, f) != cn) {
                s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
                break;
            }
            pos += cn * vs;
        }
        if (progress && vv_progress_report(progress, (levels ? 0.875 : 1.0) * (double)(i + 1) / n))
            s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
    }
    free(buf);
    free(cbuf);
    free(zbuf);
    int n_levels = 1;
    uint64_t table_off = 0;
    if (s == VV_OK && levels)
        s = write_levels(f, path, hdr, nb, n, zstd, index, &pos, &n_levels, &table_off, progress);
    if (s == VV_OK) {
        unsigned char h[VVB_HEADER];
        memset(h, 0, sizeof h);
        memcpy(h, VVB_MAGIC, 8);
        put_u32(h + 8, VVB_HEADER);
        put_u32(h + 12, VV_BRICK_CELLS);
        for (int a = 0; a < 3; a++)
            put_u32(h + 16 + 4 * a, (uint32_t)hdr->dims[a]);
        put_u32(h + 28, (uint32_t)hdr->type);
        put_u32(h + 32, coarse ? 1 : 0);
        put_u32(h + 36, (uint32_t)hdr->unit);
        put_u32(h + 40, (uint32_t)hdr->space);
        for (int a = 0; a < 3; a++) {
            put_f64(h + 48 + 8 * a, hdr->spacing[a]);
            put_f64(h + 72 + 8 * a, hdr->origin[a]);
        }
        for (int a = 0; a < 9; a++)
            put_f64(h + 96 + 8 * a, hdr->direction[a]);
        if (!(lo <= hi))
            lo = hi = 0;
        put_f64(h + 168, lo);
        put_f64(h + 176, hi);
        put_u64(h + 184, VVB_HEADER);
        put_u64(h + 192, (uint64_t)n);
        put_u32(h + 200, zstd ? VVB_CODEC_ZSTD : 0);
        if (n_levels > 1) {
            put_u32(h + 204, (uint32_t)n_levels);
            put_u64(h + 208, table_off);
        }
        if (fseeko(f, 0, SEEK_SET) != 0 || fwrite(h, 1, sizeof h, f) != sizeof h ||
            fwrite(index, VVB_RECORD, (size_t)n, f) != (size_t)n)
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
    }
    free(index);
    if (fclose(f) != 0 && s == VV_OK)
        s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
    if (s == VV_OK && rename(tmp, path) != 0)
        s = vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
    if (s != VV_OK)
        remove(tmp);
    free(tmp);
    return s;
}

/* A bricked source being written as .vvb: a .vvb's bricks read one by one;
 * a raw layout's read a row of bricks at a time (every brick of one j and
 * k: one pread a row of the volume instead of one a row of each brick),
 * when that row is under 64 MiB. */
typedef struct bricked_feed {
    vv_bricked *b;
    vv_volume row; /* the row of bricks held: data NULL, or voxels 0 .. N-1 x slo .. shi */
    int rj, rk;    /* its brick j and k */
} bricked_feed;

static vv_status
source_bricked(void *ctx, int index, const vv_brick_info *in, void *buf) {
    bricked_feed *f = ctx;
    vv_bricked *b = f->b;
    const size_t vs = vv_voxel_type_size(b->header->type);
    const int *d = b->header->dims;
    const uint64_t row_bytes =
        (uint64_t)d[0] * (uint64_t)(VV_BRICK_CELLS + 3) * (uint64_t)(VV_BRICK_CELLS + 3) * vs;
    if (b->vvb || row_bytes > ((uint64_t)64 << 20)) {
        vv_volume v;
        memset(&v, 0, sizeof v);
        v.data = buf;
        v.type = b->header->type;
        return read_box(b, index, in, &v);
    }
    const int bj = (index / b->nb[0]) % b->nb[1], bk = index / (b->nb[0] * b->nb[1]);
    if (!f->row.data || f->rj != bj || f->rk != bk) {
        free(f->row.data);
        f->row.data = malloc((size_t)row_bytes);
        if (!f->row.data)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        vv_brick_info r = *in;
        r.slo[0] = 0;
        r.shi[0] = d[0] - 1;
        f->row.type = b->header->type;
        for (int a = 0; a < 3; a++)
            f->row.dims[a] = r.shi[a] - r.slo[a] + 1;
        f->rj = bj;
        f->rk = bk;
        const vv_status s = read_box(b, -1, &r, &f->row);
        if (s != VV_OK) {
            free(f->row.data);
            f->row.data = NULL;
            return s;
        }
    }
    const size_t n = (size_t)(in->shi[0] - in->slo[0] + 1) * vs;
    char *dst = buf;
    for (int k = 0; k < f->row.dims[2]; k++)
        for (int j = 0; j < f->row.dims[1]; j++, dst += n)
            memcpy(dst,
                   (const char *)f->row.data +
                       (((size_t)k * f->row.dims[1] + j) * f->row.dims[0] + in->slo[0]) * vs,
                   n);
    return VV_OK;
}

vv_status
vv_bricked_write_vvb(vv_bricked *src, const char *path, unsigned flags,
                     const vv_progress *progress) {
    bricked_feed f;
    memset(&f, 0, sizeof f);
    f.b = src;
    const vv_status s =
        write_vvb(path, src->header, src->nb, src->n, flags, source_bricked, &f, progress);
    free(f.row.data);
    return s;
}

static vv_status
source_memory(void *ctx, int index, const vv_brick_info *in, void *buf) {
    (void)index;
    const vv_volume *v = ctx;
    const size_t vs = vv_voxel_type_size(v->type);
    const size_t row = (size_t)(in->shi[0] - in->slo[0] + 1) * vs;
    char *dst = buf;
    for (int k = in->slo[2]; k <= in->shi[2]; k++)
        for (int j = in->slo[1]; j <= in->shi[1]; j++) {
            memcpy(dst,
                   (const char *)v->data +
                       (((size_t)k * v->dims[1] + j) * v->dims[0] + in->slo[0]) * vs,
                   row);
            dst += row;
        }
    return VV_OK;
}

/* A box reader's box of a brick (ghosts included) copied into @p buf. */
typedef struct box_source {
    vv_box_reader read;
    void *ctx;
    vv_voxel_type type;
} box_source;

static vv_status
source_boxes(void *ctx, int index, const vv_brick_info *in, void *buf) {
    (void)index;
    const box_source *bs = ctx;
    vv_volume *v = NULL;
    vv_status s = bs->read(bs->ctx, in->slo, in->shi, &v);
    if (s == VV_OK &&
        (!v || v->type != bs->type || v->dims[0] != in->shi[0] - in->slo[0] + 1 ||
         v->dims[1] != in->shi[1] - in->slo[1] + 1 || v->dims[2] != in->shi[2] - in->slo[2] + 1))
        s = vv_error_set(VV_ERR_INVALID, "the reader gave a box of another shape or type");
    if (s == VV_OK)
        memcpy(buf, v->data, box_voxels(in->slo, in->shi) * vv_voxel_type_size(v->type));
    vv_volume_free(v);
    return s;
}

/* write_vvb of the volume @p hdr describes, its brick grid made here (the
 * grid only: no entries). */
static vv_status
write_vvb_of(const vv_volume *hdr, const char *path, unsigned flags, brick_source src, void *ctx,
             const vv_progress *progress) {
    vv_bricked geo;
    memset(&geo, 0, sizeof geo);
    geo.header = (vv_volume *)hdr;
    vv_status s = brick_grid(&geo);
    if (s != VV_OK)
        return s;
    return write_vvb(path, hdr, geo.nb, geo.n, flags, src, ctx, progress);
}

vv_status
vv_boxes_write_vvb(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                   unsigned flags, const vv_progress *progress) {
    if (!hdr || !read || !path)
        return vv_error_set(VV_ERR_INVALID, "vvb: NULL argument");
    box_source bs = {read, ctx, hdr->type};
    return write_vvb_of(hdr, path, flags, source_boxes, &bs, progress);
}

vv_status
vv_volume_write_vvb(const vv_volume *v, const char *path, unsigned flags) {
    return write_vvb_of(v, path, flags, source_memory, (void *)v, NULL);
}

/* ---- a .vvb as a pyramid's store ------------------------------------------- */

int
vv_vvb_probe(const char *path) {
    unsigned char h[VVB_HEADER];
    const int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return 0;
    const ssize_t r = pread(fd, h, sizeof h, 0);
    close(fd);
    if (r != (ssize_t)sizeof h || memcmp(h, VVB_MAGIC, 8) != 0)
        return 0;
    const uint32_t n = get_u32(h + 204);
    return n > 1 && n <= VV_PYRAMID_MAX_LEVELS ? (int)n : 1;
}

static vv_status
vvb_store_read(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
               const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    (void)c;
    *missing = 0;
    uint64_t got = 0;
    const vv_status s = read_level_box(ctx, level, org, dims, dst, scratch, &got);
    *file_bytes = got;
    return s;
}

/* A chunk's range from the index: level 0's from the brick holding it (its
 * stored box: a superset), the others' their own. */
static int
vvb_store_range(void *ctx, int level, const int c[3], double *lo, double *hi) {
    const vv_bricked *b = ctx;
    if (level > 0) {
        const vvb_level *L = &b->lv[level];
        const vvb_chunk *e = &L->c[(c[2] * L->nc[1] + c[1]) * L->nc[0] + c[0]];
        *lo = e->vmin;
        *hi = e->vmax;
        return 1;
    }
    int bc[3];
    for (int a = 0; a < 3; a++)
        bc[a] = c[a] < b->nb[a] - 1 ? c[a] : b->nb[a] - 1;
    const brick_entry *e = &b->e[(bc[2] * b->nb[1] + bc[1]) * b->nb[0] + bc[0]];
    *lo = e->vmin;
    *hi = e->vmax;
    return 1;
}

static void
vvb_store_close(void *ctx) {
    vv_bricked_free(ctx);
}

vv_status
vv_vvb_pyramid_store(vv_store *st, const char *path, int channel, int time) {
    memset(st, 0, sizeof *st);
    st->name = "vvb";
    if (channel > 0 || time > 0)
        return vv_error_set(VV_ERR_INVALID,
                            "a .vvb holds one channel at one time step (asked "
                            "for channel %d, time step %d)",
                            channel, time);
    vv_bricked *b = calloc(1, sizeof *b);
    if (!b)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    b->fd = -1;
    b->vvb = 1;
    b->swap = !vv_host_is_little_endian();
    b->path = strdup(path);
    b->data_path = strdup(path);
    st->ctx = b;
    st->close = vvb_store_close;
    st->read_chunk = vvb_store_read;
    st->chunk_range = vvb_store_range;
    st->parallel = 1; /* pread and zstd into the caller's buffers */
    vv_status s =
        b->path && b->data_path ? open_vvb(b) : vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s != VV_OK)
        return s;
    st->scratch = (size_t)piece_bytes(b);
    st->n_levels = b->n_levels;
    const vv_volume *h = b->header;
    int f[3] = {1, 1, 1}; /* level-0 voxels per voxel of level l */
    for (int l = 0; l < b->n_levels && s == VV_OK; l++) {
        const int *d = l ? b->lv[l].dims : h->dims;
        int cd[3];
        for (int a = 0; a < 3; a++) {
            cd[a] = d[a] < VVB_CHUNK ? d[a] : VVB_CHUNK;
            if (l > 0 && (l > 1 ? b->lv[l - 1].dims[a] : h->dims[a]) > 1)
                f[a] *= 2;
        }
        if ((s = vv_store_set_level(st, l, h->type, d, cd)) != VV_OK)
            break;
        /* each voxel's centre at the centre of the level-0 voxels it
         * summarises, along the volume's axes */
        vv_volume *v = st->lv[l].hdr;
        memcpy(v->direction, h->direction, sizeof v->direction);
        memcpy(v->origin, h->origin, sizeof v->origin);
        for (int a = 0; a < 3; a++) {
            v->spacing[a] = h->spacing[a] * f[a];
            const double t = 0.5 * (f[a] - 1) * h->spacing[a];
            for (int r = 0; r < 3; r++)
                v->origin[r] += h->direction[3 * r + a] * t;
        }
        v->unit = h->unit;
        v->space = h->space;
        v->range[0] = h->range[0];
        v->range[1] = h->range[1];
        v->modification = VV_MOD_ORIGINAL;
    }
    st->n_channels = st->n_times = 1;
    st->has_range = 1;
    st->range[0] = h->range[0];
    st->range[1] = h->range[1];
    return s;
}

/* ---- a .vvb as a volume format (vv_volume_load) ------------------------------ */

/* Level opt->level of the .vvb at @p path, whole, through its pyramid store. */
static vv_status
vvb_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    *out = NULL;
    vv_store st;
    vv_status s = vv_vvb_pyramid_store(&st, path, opt->channel, opt->time);
    const int level = opt->level > 0 ? opt->level : 0;
    if (s == VV_OK && level >= st.n_levels)
        s = vv_error_set(VV_ERR_INVALID, "level %d asked, the file has %d", level, st.n_levels);
    vv_volume *v = NULL;
    if (s == VV_OK)
        s = vv_volume_new(&v, st.lv[level].hdr->dims, st.lv[level].hdr->type);
    unsigned char *piece = s == VV_OK ? malloc(st.scratch) : NULL;
    if (s == VV_OK && !piece)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    const int zero[3] = {0, 0, 0};
    uint64_t bytes = 0;
    if (s == VV_OK)
        s = read_level_box(st.ctx, level, zero, v->dims, v->data, piece, &bytes);
    free(piece);
    if (s == VV_OK) {
        const vv_volume *h = st.lv[level].hdr;
        memcpy(v->spacing, h->spacing, sizeof v->spacing);
        memcpy(v->origin, h->origin, sizeof v->origin);
        memcpy(v->direction, h->direction, sizeof v->direction);
        v->unit = h->unit;
        v->space = h->space;
        v->modification = VV_MOD_ORIGINAL;
        vv_volume_update_range(v);
        if (opt->info) {
            opt->info->n_channels = opt->info->n_times = 1;
            opt->info->n_levels = st.n_levels;
        }
    }
    vv_store_close(&st);
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_error_prefix(s, "vvb: %s", vv_path_basename(path));
    }
    *out = v;
    return VV_OK;
}

/* The .vvb row's store (its levels). */
static vv_status
vvb_open_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    (void)info;
    return vv_vvb_pyramid_store(st, path, channel, time);
}

static vv_status
vvb_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_volume_write_vvb(v, path, opt->vvb_flags);
}

static vv_status
vvb_write_boxes_record(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                       const vv_save_options *opt) {
    return vv_boxes_write_vvb(hdr, read, ctx, path, opt->vvb_flags,
                              opt->progress.fn ? &opt->progress : NULL);
}

static int
vvb_looks_like(const vv_format_probe *p, int deep) {
    (void)deep;
    return !p->is_dir && p->n >= 8 && !memcmp(p->head, VVB_MAGIC, 8);
}

static const char *const vvb_extensions[] = {"vvb", NULL};

const vv_format_record vv_format_vvb = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "vvb",
    .title = ".vvb",
    .extensions = vvb_extensions,
    .doc = "VolVis's bricked volumes (volvis convert IN OUT.vvb): read whole, any pyramid level "
           "(--level); rendered out of core by bricks (volvis render) or by level of detail "
           "(--lod)",
    .flags = VV_FORMAT_FLAG_OUT_OF_CORE,
    .looks_like = vvb_looks_like,
    .read = vvb_read,
    .write = vvb_write_record,
    .write_boxes = vvb_write_boxes_record,
    .open_store = vvb_open_store,
    .open_bricks = vvb_open_bricks,
};
