/*
 * Bricked volumes read on demand (include/volvis/bricks.h; src/io/store/bricked.h):
 * a .vvb (its header, index and levels read by vvb_read.c), a raw file or a
 * raw-encoded NRRD file read by pread, brick by brick, into the process's
 * cache of pieces (src/core/cache.h) within its budget, and served as a
 * brick source (sys/source.h) to the region driver. Opening a raw layout
 * streams it once, a slice at a time, for the value range and the bricks'
 * min/max; the coarse whole volume (vv_bricked_proxy) comes from a .vvb's
 * coarse levels or from every f-th voxel. The file it reads (vvb_file),
 * the .vvb's layout and the reading of its pieces are vvb_read.c's
 * (vvb_layout.h); the bricks held in the cache are this file's.
 *
 * Thread-safety: loading bricks and reading boxes from several threads at
 * once (the cache's lock guards the bricks held and the counts).
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

#include "core/cache.h"
#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/bricked.h"
#include "io/store/bricked_internal.h"
#include "io/store/pyramid.h"
#include "io/store/vvb_layout.h"
#include "volvis/sys/format.h"

/* A brick's voxels while the cache holds them. */
typedef struct brick_slot {
    vv_volume *vol;    /* cached, or NULL */
    vv_cache_entry ce; /* its place in the process's cache while vol is held */
    int loads;
} brick_slot;

struct vv_bricked {
    char *path;        /* as opened */
    vvb_file f;        /* the file holding the voxels, its geometry and bricks' min/max */
    int vvb;           /* 1: .vvb, else raw layout (raw or NRRD) */
    uint64_t data_off; /* raw layout: offset of voxel (0, 0, 0) */
    brick_slot *slot;  /* f.n of them, i fastest */
    /* the cached bricks live in the process's cache (src/core/cache.h);
     * its lock guards them and the counts */
    vv_cache *cache;
    vv_cache_client cl;
    vv_bricked_stats st; /* bytes_read: f's */
};

/* ---- geometry -------------------------------------------------------------- */

/* The bytes one brick holds while rendered: its voxels, the ray caster's
 * 16-bit or float copy and cached gradients (src/render/sample.h). */
static uint64_t
working_set(const vv_bricked *b, uint64_t voxels) {
    const uint64_t vs = vv_voxel_type_size(b->f.header->type);
    return voxels * (vs + 4 + 4);
}

int
vv_bricked_levels(const vv_bricked *b) {
    return b->f.n_levels > 1 ? b->f.n_levels : 1;
}

int
vv_bricked_count(const vv_bricked *b) {
    return b->f.n;
}

void
vv_bricked_info(const vv_bricked *b, int index, vv_brick_info *info) {
    vvb_brick_boxes(b->f.header->dims, b->f.nb, index, info);
    info->vmin = (float)b->f.e[index].vmin;
    info->vmax = (float)b->f.e[index].vmax;
}

void
vv_bricked_note_skip(vv_bricked *b) {
    __atomic_fetch_add(&b->st.skipped, (uint64_t)1, __ATOMIC_RELAXED);
}

const vv_volume *
vv_bricked_header(const vv_bricked *b) {
    return b->f.header;
}

void
vv_bricked_grid(const vv_bricked *b, int nb[3]) {
    memcpy(nb, b->f.nb, sizeof b->f.nb);
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
    s->bytes_read = __atomic_load_n(&b->f.bytes_read, __ATOMIC_RELAXED);
    s->evictions = b->cl.evictions;
    s->peak_bytes = b->cl.peak;
    s->held_bytes = b->cl.held;
    vv_cache_unlock(b->cache);
    s->max_loads = 0;
    for (int i = 0; i < b->f.n; i++)
        s->max_loads = b->slot[i].loads > s->max_loads ? b->slot[i].loads : s->max_loads;
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
        for (int i = 0; b->slot && i < b->f.n; i++)
            if (b->slot[i].vol) {
                vv_cache_remove(b->cache, &b->slot[i].ce);
                vv_volume_free(b->slot[i].vol);
            }
        vv_cache_unlock(b->cache);
        vv_cache_client_remove(&b->cl);
        vv_cache_free(b->cache);
    }
    free(b->slot);
    vvb_file_close(&b->f);
    free(b->path);
    free(b);
}

/* ---- reading a brick ------------------------------------------------------- */

/* The voxels of box slo..shi into dst (dims the box's). */
vv_status
vvb_read_stored(vv_bricked *b, int index, const vv_brick_info *in, void *dst) {
    const size_t vs = vv_voxel_type_size(b->f.header->type);
    const uint64_t n = vvb_box_voxels(in->slo, in->shi);
    char what[96];
    if (index >= 0)
        snprintf(what, sizeof what, "brick %d", index);
    else
        snprintf(what, sizeof what, "box %d..%d x %d..%d x %d..%d", in->slo[0], in->shi[0],
                 in->slo[1], in->shi[1], in->slo[2], in->shi[2]);
    vv_status s = VV_OK;
    if (b->vvb) {
        s = vvb_read_brick(&b->f, index, dst, n * vs, what);
    } else {
        const int *d = b->f.header->dims;
        const size_t row = (size_t)(in->shi[0] - in->slo[0] + 1) * vs;
        char *row_dst = dst;
        for (int k = in->slo[2]; k <= in->shi[2] && s == VV_OK; k++)
            for (int j = in->slo[1]; j <= in->shi[1] && s == VV_OK; j++) {
                const uint64_t off =
                    b->data_off + (((uint64_t)k * (uint64_t)d[1] + (uint64_t)j) * (uint64_t)d[0] +
                                   (uint64_t)in->slo[0]) *
                                      vs;
                s = vvb_read_at(&b->f, row_dst, row, off, what);
                row_dst += row;
            }
    }
    if (s == VV_OK && b->f.swap && vs > 1)
        vvb_swap_bytes(dst, (size_t)n, vs);
    return s;
}

int
vvb_is_vvb(const vv_bricked *b) {
    return b->vvb;
}

/* The cache drops brick @p e's voxels to make room (lock held). */
static void
client_drop(vv_cache_client *cl, vv_cache_entry *ce) {
    (void)cl;
    brick_slot *e = (brick_slot *)((char *)ce - offsetof(brick_slot, ce));
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
    if (index < 0 || index >= b->f.n)
        return vv_error_set(VV_ERR_INVALID, "bricks: no brick %d", index);
    brick_slot *e = &b->slot[index];
    vv_cache_lock(b->cache);
    if (e->vol) {
        vv_cache_touch(b->cache, &e->ce);
        b->st.hits++;
        *out = vv_volume_ref(e->vol);
        vv_cache_unlock(b->cache);
        return VV_OK;
    }
    vv_brick_info in;
    vvb_brick_boxes(b->f.header->dims, b->f.nb, index, &in);
    const uint64_t bytes = vvb_box_voxels(in.slo, in.shi) * vv_voxel_type_size(b->f.header->type);
    vv_cache_make_room(b->cache, bytes, 0);
    vv_cache_unlock(b->cache);
    int dims[3];
    for (int a = 0; a < 3; a++)
        dims[a] = in.shi[a] - in.slo[a] + 1;
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, b->f.header->type);
    if (s == VV_OK)
        s = vvb_read_stored(b, index, &in, v->data);
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_error_prefix(s, "bricks: %s", vv_path_basename(b->path));
    }
    /* the whole volume's frame and range (a region's voxels, sys/renderer.h) */
    vv_volume_take_geometry(v, b->f.header);
    v->range[0] = b->f.header->range[0];
    v->range[1] = b->f.header->range[1];
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

/* vvb_brick_grid, then the bricks' entries. */
static vv_status
alloc_bricks(vv_bricked *b) {
    vv_status s = vvb_brick_grid(b->f.header->dims, b->f.nb, &b->f.n);
    if (s != VV_OK)
        return s;
    b->f.e = calloc((size_t)b->f.n, sizeof *b->f.e);
    if (!b->f.e)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    return VV_OK;
}

/* The budget: the largest brick's working set is reserved, the cache holds
 * the rest with every other source's pieces. */
static vv_status
set_budget(vv_bricked *b) {
    const uint64_t limit = vv_cache_limit(b->cache);
    uint64_t biggest = 0;
    for (int i = 0; i < b->f.n; i++) {
        vv_brick_info in;
        vvb_brick_boxes(b->f.header->dims, b->f.nb, i, &in);
        const uint64_t v = vvb_box_voxels(in.slo, in.shi);
        biggest = v > biggest ? v : biggest;
    }
    const uint64_t vs = vv_voxel_type_size(b->f.header->type);
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
    const int *d = b->f.header->dims;
    const vv_voxel_type t = b->f.header->type;
    const size_t vs = vv_voxel_type_size(t);
    const size_t slice = (size_t)d[0] * (size_t)d[1];
    /* a slice of a volume of 65536^2 voxels across is gigabytes */
    char what[96];
    snprintf(what, sizeof what, "a slice of %d x %d %s (the scan for the value range)", d[0], d[1],
             vv_voxel_type_name(t));
    vv_status bs =
        vv_memory_budget_check((uint64_t)slice * vs + sizeof(double) * (uint64_t)d[0], what);
    if (bs != VV_OK)
        return bs;
    void *buf = malloc(slice * vs);
    double *row = malloc(sizeof(double) * (size_t)d[0]);
    if (!buf || !row) {
        free(buf);
        free(row);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < b->f.n; i++) {
        b->f.e[i].vmin = INFINITY;
        b->f.e[i].vmax = -INFINITY;
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
                if (c < 0 || c >= b->f.nb[a])
                    continue;
                const int blo = c * VV_BRICK_CELLS, last = d[a] - 1;
                const int bhi = blo + VV_BRICK_CELLS < last ? blo + VV_BRICK_CELLS : last;
                const int slo = blo > 0 ? blo - 1 : 0, shi = bhi < last ? bhi + 1 : last;
                if (x >= slo && x <= shi)
                    cand[a][2 * x + n++] = c;
            }
            /* the last brick of an axis may reach the end from further back */
            const int c2 = x / VV_BRICK_CELLS + 1;
            if (n < 2 && c2 < b->f.nb[a] && x >= c2 * VV_BRICK_CELLS - 1)
                cand[a][2 * x + n++] = c2;
        }
    }
    double *bmn = malloc(sizeof(double) * (size_t)b->f.nb[0]);
    double *bmx = malloc(sizeof(double) * (size_t)b->f.nb[0]);
    if (!bmn || !bmx)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int k = 0; k < d[2] && s == VV_OK; k++) {
        s = vvb_read_at(&b->f, buf, slice * vs, b->data_off + (uint64_t)k * slice * vs, "scan");
        if (s != VV_OK)
            break;
        if (b->f.swap && vs > 1)
            vvb_swap_bytes(buf, slice, vs);
        for (int j = 0; j < d[1]; j++) {
            get_row(&tmp, j, row);
            for (int bi = 0; bi < b->f.nb[0]; bi++) {
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
            for (int bi = 0; bi < b->f.nb[0]; bi++) {
                lo = bmn[bi] < lo ? bmn[bi] : lo;
                hi = bmx[bi] > hi ? bmx[bi] : hi;
                for (int qk = 0; qk < 2; qk++)
                    for (int qj = 0; qj < 2; qj++) {
                        const int bk = cand[2][2 * k + qk], bj = cand[1][2 * j + qj];
                        if (bk < 0 || bj < 0)
                            continue;
                        vvb_brick *e = &b->f.e[(bk * b->f.nb[1] + bj) * b->f.nb[0] + bi];
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
    b->f.header->range[0] = lo;
    b->f.header->range[1] = hi;
    return VV_OK;
}

static vv_status
open_raw_layout(vv_bricked *b, int scan) {
    vv_status s = vvb_open_data(&b->f, b->f.data_path);
    if (s != VV_OK)
        return s;
    const uint64_t bytes = (uint64_t)b->f.header->dims[0] * (uint64_t)b->f.header->dims[1] *
                           (uint64_t)b->f.header->dims[2] * vv_voxel_type_size(b->f.header->type);
    if (b->data_off > b->f.file_size || b->f.file_size - b->data_off < bytes) {
        /* the data file named when it is not the file opened (a detached NRRD) */
        const char *dn = vv_path_basename(b->f.data_path);
        const int other = strcmp(dn, vv_path_basename(b->path)) != 0;
        return vv_error_set(VV_ERR_FORMAT,
                            "%s%s%llu bytes of voxels from offset %llu run past the end of the "
                            "file (%llu bytes)",
                            other ? dn : "", other ? ": " : "", (unsigned long long)bytes,
                            (unsigned long long)b->data_off, (unsigned long long)b->f.file_size);
    }
    if ((s = alloc_bricks(b)) != VV_OK)
        return s;
    if (scan)
        return scan_raw(b);
    for (int i = 0; i < b->f.n; i++) {
        b->f.e[i].vmin = -INFINITY;
        b->f.e[i].vmax = INFINITY;
    }
    return VV_OK;
}

/* A new bricked volume of @p path in @p cache, nothing opened yet. */
static vv_status
bricked_new(vv_bricked **out, const char *path, vv_cache *cache) {
    *out = NULL;
    vv_bricked *b = calloc(1, sizeof *b);
    if (!b)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    b->cache = vv_cache_ref(cache ? cache : vv_cache_process());
    b->f.fd = -1;
    if (!(b->path = strdup(path))) {
        vv_bricked_free(b);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    *out = b;
    return VV_OK;
}

/* @p b opened (its bricks' slots made, budget set) or freed with the
 * error named after @p path. */
static vv_status
bricked_done(vv_bricked **out, vv_bricked *b, vv_status s, const char *path) {
    if (s == VV_OK && !(b->slot = calloc((size_t)b->f.n, sizeof *b->slot)))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
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
    b->f.header = header;
    b->f.data_path = data_path;
    b->data_off = offset;
    b->f.swap = (big_endian ? 1 : 0) == vv_host_is_little_endian();
    if ((s = vv_volume_check_limits(header->dims, header->type, NULL)) == VV_OK)
        s = open_raw_layout(b, scan);
    return bricked_done(out, b, s, path);
}

/* A .vvb file by its bricks. */
vv_status
vvb_open_bricked(vv_bricked **out, const char *path, vv_cache *cache) {
    vv_bricked *b = NULL;
    vv_status s = bricked_new(&b, path, cache);
    if (s != VV_OK)
        return s;
    b->vvb = 1;
    s = (b->f.data_path = strdup(path)) ? vvb_open_file(&b->f)
                                        : vv_error_set(VV_ERR_NOMEM, "out of memory");
    return bricked_done(out, b, s, path);
}

/* @p path by bricks: a .vvb (its magic), a raw file when @p raw, else the
 * raw layout of the row detection finds (an uncompressed NRRD). */
static vv_status
bricked_open(vv_bricked **out, const char *path, const vv_raw_params *raw, vv_cache *cache,
             int scan) {
    *out = NULL;
    const size_t n = strlen(path);
    if (!raw && (vv_vvb_probe(path) || (n > 4 && strcmp(path + n - 4, ".vvb") == 0)))
        return vvb_open_bricked(out, path, cache); /* named .vvb: its magic checked */
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
                ? vv_error_set(VV_ERR_FORMAT, "not a file read by bricks (.vvb, raw, raw NRRD)")
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
    b->f.header->range[0] = lo;
    b->f.header->range[1] = hi;
}

vv_status
vv_bricked_box(void *bricked, const int lo[3], const int hi[3], vv_volume **out) {
    return vv_bricked_read_box(bricked, lo, hi, out);
}

vv_status
vv_bricked_read_box(vv_bricked *b, const int lo[3], const int hi[3], vv_volume **out) {
    *out = NULL;
    const int *d = b->f.header->dims;
    int dims[3];
    for (int a = 0; a < 3; a++) {
        if (lo[a] < 0 || hi[a] >= d[a] || lo[a] > hi[a])
            return vv_error_set(VV_ERR_INVALID, "bricks: box %d..%d outside 0..%d on axis %d",
                                lo[a], hi[a], d[a] - 1, a);
        dims[a] = hi[a] - lo[a] + 1;
    }
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, b->f.header->type);
    if (s != VV_OK)
        return s;
    const size_t vs = vv_voxel_type_size(b->f.header->type);
    if (!b->vvb) {
        vv_brick_info in;
        memcpy(in.slo, lo, sizeof in.slo);
        memcpy(in.shi, hi, sizeof in.shi);
        s = vvb_read_stored(b, -1, &in, v->data);
    } else {
        /* every brick overlapping the box, read whole, its overlap copied */
        for (int i = 0; i < b->f.n && s == VV_OK; i++) {
            vv_brick_info in;
            vvb_brick_boxes(b->f.header->dims, b->f.nb, i, &in);
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
            const uint64_t bbytes = vvb_box_voxels(in.slo, in.shi) * vs;
            char *buf = malloc((size_t)bbytes);
            if (!buf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            char what[64];
            snprintf(what, sizeof what, "brick %d", i);
            s = vvb_read_brick(&b->f, i, buf, bbytes, what);
            if (s == VV_OK && b->f.swap && vs > 1)
                vvb_swap_bytes(buf, (size_t)(bbytes / vs), vs);
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
    vv_volume_take_geometry(v, b->f.header);
    v->range[0] = b->f.header->range[0];
    v->range[1] = b->f.header->range[1];
    *out = v;
    return VV_OK;
}

/* ---- the coarse whole volume ---------------------------------------------- */

vv_status
vv_bricked_proxy(vv_bricked *b, int max_side, vv_volume **out) {
    *out = NULL;
    const int *d = b->f.header->dims;
    int f = 1;
    while ((d[0] - 1) / f + 1 > max_side || (d[1] - 1) / f + 1 > max_side ||
           (d[2] - 1) / f + 1 > max_side)
        f++;
    if (b->vvb && b->f.zstd && f == 1) {
        /* small enough whole, and zstd bricks cannot be read voxel by
         * voxel: the whole volume by bricks */
        const int lo[3] = {0, 0, 0}, hi[3] = {d[0] - 1, d[1] - 1, d[2] - 1};
        vv_status s = vv_bricked_read_box(b, lo, hi, out);
        if (s == VV_OK)
            vv_volume_update_range(*out);
        return s;
    }
    /* coarse levels hold every 4th voxel from each brick's corner */
    if (b->vvb && b->f.has_coarse && f > 1)
        f = (f + VVB_COARSE - 1) / VVB_COARSE * VVB_COARSE;
    int pd[3];
    for (int a = 0; a < 3; a++)
        pd[a] = (d[a] - 1) / f + 1;
    vv_volume *p = NULL;
    vv_status s = vv_volume_new(&p, pd, b->f.header->type);
    if (s != VV_OK)
        return s;
    const size_t vs = vv_voxel_type_size(b->f.header->type);
    for (int a = 0; a < 3; a++) {
        p->spacing[a] = pd[a] > 1 ? b->f.header->spacing[a] * (double)(d[a] - 1) / (pd[a] - 1)
                                  : b->f.header->spacing[a];
        p->origin[a] = b->f.header->origin[a];
    }
    memcpy(p->direction, b->f.header->direction, sizeof p->direction);
    p->unit = b->f.header->unit;
    p->space = b->f.header->space;
    char *dst = p->data;
    if (b->vvb && b->f.has_coarse && f > 1) {
        const int m = f / VVB_COARSE;
        for (int i = 0; i < b->f.n && s == VV_OK; i++) {
            vv_brick_info in;
            vvb_brick_boxes(b->f.header->dims, b->f.nb, i, &in);
            int cd[3];
            vvb_coarse_dims(&in, cd);
            char *cbuf = malloc((size_t)b->f.e[i].coarse_bytes);
            if (!cbuf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            s = vvb_read_at(&b->f, cbuf, (size_t)b->f.e[i].coarse_bytes, b->f.e[i].coarse_offset,
                            "coarse");
            if (s == VV_OK && b->f.swap && vs > 1)
                vvb_swap_bytes(cbuf, (size_t)(b->f.e[i].coarse_bytes / vs), vs);
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
                            c[a] = c[a] < b->f.nb[a] ? c[a] : b->f.nb[a] - 1;
                        }
                        const int idx = (c[2] * b->f.nb[1] + c[1]) * b->f.nb[0] + c[0];
                        vv_brick_info in;
                        vvb_brick_boxes(b->f.header->dims, b->f.nb, idx, &in);
                        const uint64_t off =
                            b->f.e[idx].offset +
                            ((((uint64_t)(g[2] - in.slo[2]) * (in.shi[1] - in.slo[1] + 1)) +
                              (uint64_t)(g[1] - in.slo[1])) *
                                 (in.shi[0] - in.slo[0] + 1) +
                             (uint64_t)(g[0] - in.slo[0])) *
                                vs;
                        s = vvb_read_at(&b->f, dst + (((size_t)k * pd[1] + j) * pd[0] + i) * vs, vs,
                                        off, "proxy");
                    }
                    continue;
                }
                const uint64_t off =
                    b->data_off +
                    ((uint64_t)k * f * (uint64_t)d[1] + (uint64_t)j * f) * (uint64_t)d[0] * vs;
                s = vvb_read_at(&b->f, row, (size_t)d[0] * vs, off, "proxy");
                for (int i = 0; i < pd[0] && s == VV_OK; i++)
                    memcpy(dst + (((size_t)k * pd[1] + j) * pd[0] + i) * vs,
                           row + (size_t)i * f * vs, vs);
            }
        free(row);
        if (s == VV_OK && b->f.swap && vs > 1)
            vvb_swap_bytes(p->data, (size_t)pd[0] * pd[1] * pd[2], vs);
    }
    if (s != VV_OK) {
        vv_volume_free(p);
        return s;
    }
    vv_volume_update_range(p);
    *out = p;
    return VV_OK;
}
