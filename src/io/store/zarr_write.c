/*
 * OME-Zarr writer (vv_ome_zarr_write): a Zarr v2 store with the OME-NGFF
 * 0.4 multiscales metadata, as napari, Fiji (n5-zarr, MoBIE), BigDataViewer
 * and zarr-python read it.
 *
 * Layout (a folder):
 *   .zgroup                 {"zarr_format": 2}
 *   .zattrs                 multiscales (axes z, y, x with the unit; one
 *                           dataset per level with its scale and
 *                           translation), omero (one channel, its window)
 *   <level>/.zarray         shape [nz, ny, nx], chunks of at most 64^3, the
 *                           voxel type little-endian, C order, "/" as the
 *                           dimension separator, zlib level 1 (numcodecs'
 *                           "zlib") unless uncompressed
 *   <level>/<cz>/<cy>/<cx>  one chunk, full chunk shape (edges padded with
 *                           the fill value 0), as Zarr v2 stores them
 *
 * Levels: level 0 is the volume; each next level halves every axis longer
 * than 1 (rounding up) until every axis fits one chunk. A voxel of the next
 * level is the mean of the 2x2x2 voxels under it (those inside the volume;
 * integers rounded to nearest), or for a label volume the first of them
 * (labels are never averaged). The scale of level l is the spacing times
 * its factor; the translation puts each voxel's centre at the centre of the
 * voxels it summarises.
 *
 * Writing is atomic for the store as a whole: everything goes into a
 * temporary folder beside the target ("<path>.tmp-XXXXXX"), synced, then
 * exchanged with an existing store (renameat2 RENAME_EXCHANGE) or renamed
 * into place; the old store is removed after. An existing path that is not
 * a Zarr store (no .zgroup, .zattrs or .zarray) is never replaced. Chunks
 * are gathered and compressed on every core (vv_parallel_for).
 *
 * What OME-Zarr 0.4 cannot hold: a direction matrix (the record's fits).
 */
#define _GNU_SOURCE /* renameat2, syncfs */
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>
#include <zlib.h>

#include "core/internal.h"
#include "core/parallel_for.h"
#include "io/io_internal.h"
#include "io/store/pyramid.h"
#include "io/store/zarr.h"
#include "io/write_check.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

#define ZARR_CHUNK 64
#define ZARR_MAX_LEVELS 24

/* ---- folders ------------------------------------------------------------------ */

/* A path inside the store; vv_ome_zarr_write has checked that the target's
 * name leaves room for every one (ZARR_PATH_MAX). */
#define ZARR_PATH_MAX 4096
static void
store_path(char *out, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out, ZARR_PATH_MAX, fmt, ap);
    va_end(ap);
}

static int
remove_entry(const char *p, const struct stat *st, int flag, struct FTW *ftw) {
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(p) != 0 && errno != ENOENT ? -1 : 0;
}

/* Removes the tree at @p path (ours: a temporary or a replaced store). */
static void
remove_tree(const char *path) {
    nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* 1 when @p dir holds Zarr metadata. */
static int
is_zarr_store(const char *dir) {
    static const char *const names[] = {".zgroup", ".zattrs", ".zarray"};
    char p[ZARR_PATH_MAX];
    for (int i = 0; i < 3; i++) {
        store_path(p, "%s/%s", dir, names[i]);
        if (access(p, F_OK) == 0)
            return 1;
    }
    return 0;
}

/* ---- metadata ----------------------------------------------------------------- */

static const char *
zarr_dtype(vv_voxel_type t) {
    static const char *const names[] = {"|u1", "|i1", "<u2", "<i2", "<u4", "<i4", "<f4", "<f8"};
    return (unsigned)t <= VV_F64 ? names[t] : NULL;
}

/* OME-NGFF's unit of length (UDUNITS-2 names), NULL when unknown. */
static const char *
ngff_unit(vv_unit u) {
    switch (u) {
    case VV_UNIT_METER:
        return "meter";
    case VV_UNIT_MM:
        return "millimeter";
    case VV_UNIT_MICRON:
        return "micrometer";
    case VV_UNIT_FOOT:
        return "foot";
    case VV_UNIT_INCH:
        return "inch";
    default:
        return NULL;
    }
}

static vv_status
write_json(const char *dir, const char *name, json_t *j) {
    char p[ZARR_PATH_MAX];
    store_path(p, "%s/%s", dir, name);
    int rc =
        j ? json_dump_file(j, p, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17))
          : -1;
    json_decref(j);
    if (rc != 0)
        return vv_error_set(VV_ERR_IO, "%s: cannot write: %s", name, strerror(errno ? errno : EIO));
    return VV_OK;
}

/* One level of the pyramid. */
typedef struct zarr_level {
    int dims[3];      /* x, y, z */
    int factor[3];    /* voxels of level 0 per voxel, per axis */
    const void *data; /* level 0: the volume's; others owned */
    void *owned;
} zarr_level;

static json_t *
xyz_reversed(const double a[3]) {
    return json_pack("[f, f, f]", a[2], a[1], a[0]);
}

static vv_status
write_zattrs(const char *dir, const vv_volume *v, const zarr_level *lv, int n, int label,
             const char *name) {
    const char *unit = ngff_unit(v->unit);
    json_t *axes = json_array();
    static const char *const an[3] = {"z", "y", "x"};
    for (int i = 0; i < 3; i++) {
        json_t *a = json_pack("{s:s, s:s}", "name", an[i], "type", "space");
        if (unit)
            json_object_set_new(a, "unit", json_string(unit));
        json_array_append_new(axes, a);
    }
    json_t *sets = json_array();
    for (int l = 0; l < n; l++) {
        double scale[3], tr[3];
        for (int i = 0; i < 3; i++) {
            scale[i] = v->spacing[i] * lv[l].factor[i];
            tr[i] = v->origin[i] + (label ? 0 : 0.5 * (lv[l].factor[i] - 1) * v->spacing[i]);
        }
        char path[16];
        snprintf(path, sizeof path, "%d", l);
        json_array_append_new(sets, json_pack("{s:s, s:[{s:s, s:o}, {s:s, s:o}]}", "path", path,
                                              "coordinateTransformations", "type", "scale", "scale",
                                              xyz_reversed(scale), "type", "translation",
                                              "translation", xyz_reversed(tr)));
    }
    json_t *ms = json_pack("{s:s, s:s, s:o, s:o, s:s, s:{s:s}}", "version", "0.4", "name", name,
                           "axes", axes, "datasets", sets, "type", label ? "nearest" : "local_mean",
                           "metadata", "method",
                           label ? "VolVis: the first voxel of each 2x2x2 block"
                                 : "VolVis: the mean of each 2x2x2 block");
    json_t *omero = json_pack("{s:s, s:[{s:s, s:s, s:b, s:{s:f, s:f, s:f, s:f}}], s:{s:s}}", "name",
                              name, "channels", "label", name, "color", "FFFFFF", "active", 1,
                              "window", "min", v->range[0], "max", v->range[1], "start",
                              v->range[0], "end", v->range[1], "rdefs", "model", "greyscale");
    json_t *root = json_pack("{s:[o], s:o}", "multiscales", ms, "omero", omero);
    if (label && root)
        json_object_set_new(root, "image-label", json_pack("{s:s}", "version", "0.4"));
    return write_json(dir, ".zattrs", root);
}

static vv_status
write_zarray(const char *dir, const vv_volume *v, const zarr_level *l, const int chunk[3],
             int compress) {
    json_t *comp = compress ? json_pack("{s:s, s:i}", "id", "zlib", "level", 1) : json_null();
    json_t *j =
        json_pack("{s:i, s:[i, i, i], s:[i, i, i], s:s, s:o, s:i, s:s, s:n, s:s}", "zarr_format", 2,
                  "shape", l->dims[2], l->dims[1], l->dims[0], "chunks", chunk[2], chunk[1],
                  chunk[0], "dtype", zarr_dtype(v->type), "compressor", comp, "fill_value", 0,
                  "order", "C", "filters", "dimension_separator", "/");
    return write_json(dir, ".zarray", j);
}

/* ---- levels ------------------------------------------------------------------- */

typedef struct down_job {
    const zarr_level *src;
    zarr_level *dst;
    vv_voxel_type type;
    int label;
    int step[3]; /* 2 on halved axes, 1 on axes of one voxel */
} down_job;

/* Slices [k0, k1) of the next level. */
static void
down_body(void *ctx, long k0, long k1, int worker) {
    (void)worker;
    const down_job *j = ctx;
    const int *sd = j->src->dims, *dd = j->dst->dims;
    vv_pyr_reduce_box b = {.src = j->src->data,
                           .type = j->type,
                           .src_dims = {sd[0], sd[1], sd[2]},
                           .src_n = {sd[0], sd[1], sd[2]},
                           .step = {j->step[0], j->step[1], j->step[2]},
                           .label = j->label,
                           .lo = {0, 0, (int)k0},
                           .n = {dd[0], dd[1], (int)(k1 - k0)},
                           .dst_dims = {dd[0], dd[1]}};
    vv_pyr_reduce(&b,
                  (char *)j->dst->owned + (size_t)k0 * dd[0] * dd[1] * vv_voxel_type_size(j->type));
}

/* The level after @p src. */
static vv_status
next_level(const zarr_level *src, zarr_level *dst, vv_voxel_type t, int label) {
    down_job j = {src, dst, t, label, {1, 1, 1}};
    for (int i = 0; i < 3; i++) {
        j.step[i] = src->dims[i] > 1 ? 2 : 1;
        dst->dims[i] = (src->dims[i] + j.step[i] - 1) / j.step[i];
        dst->factor[i] = src->factor[i] * j.step[i];
    }
    dst->owned = malloc((size_t)dst->dims[0] * dst->dims[1] * dst->dims[2] * vv_voxel_type_size(t));
    if (!dst->owned)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    dst->data = dst->owned;
    vv_parallel_for(dst->dims[2], 1, 0, down_body, &j, NULL);
    return VV_OK;
}

/* ---- chunks ------------------------------------------------------------------- */

/* Where a level's voxels come from when they are not in memory: level 0
 * from the caller's box reader (one box a row of chunks, one call at a
 * time: row_body), a further level from the level before it, read back from
 * the store being written (the 2x2x2 blocks under one chunk) and reduced as
 * next_level does (feed_chunk). */
typedef struct box_feed {
    vv_box_reader read; /* level 0; NULL: the level before */
    void *ctx;
    pthread_mutex_t lock; /* read and range */
    /* level 0's rows are read in order (a reader of slabs of slices, or a
     * stream, sees each slab once): row r waits for next_row == r, or for
     * abandon (a worker stopped early: the write fails) */
    pthread_cond_t turn;
    long next_row;
    int abandon;
    double range[2]; /* of the voxels read (level 0) */
    int have_range;
    vv_status status;       /* the reader's first failure */
    char message[1024];     /* its text (the error is the reading thread's) */
    const zarr_level *prev; /* the level before, written in prev_dir */
    const char *prev_dir;
    int prev_chunk[3], step[3], label;
} box_feed;

typedef struct chunk_job {
    const char *dir; /* the level's folder */
    const zarr_level *l;
    vv_voxel_type type;
    int chunk[3], n[3]; /* chunk shape, chunks per axis (x, y, z) */
    int compress;
    int failed;     /* the first errno, or -1 for out of memory, -2 the feed's status */
    box_feed *feed; /* NULL: l->data in memory */
} chunk_job;

/* Reads chunk file @p p of @p raw_n bytes (zlib when @p compress) into
 * @p raw; 0 or an errno (EILSEQ: not a chunk of that size). */
static int
read_chunk_file(const char *p, int compress, unsigned char *raw, size_t raw_n, unsigned char *z,
                size_t zcap) {
    int fd = open(p, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return errno;
    unsigned char *buf = compress ? z : raw;
    const size_t cap = compress ? zcap : raw_n;
    size_t got = 0;
    int err = 0;
    for (;;) {
        ssize_t r = read(fd, buf + got, cap - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            err = errno;
        if (r <= 0 || (got += (size_t)r) == cap)
            break;
    }
    close(fd);
    if (err)
        return err;
    if (!compress)
        return got == raw_n ? 0 : EILSEQ;
    uLongf n = (uLongf)raw_n;
    return uncompress(raw, &n, z, (uLong)got) == Z_OK && n == raw_n ? 0 : EILSEQ;
}

/* Voxels lo .. lo + n - 1 of the level before (f->prev, written) into
 * @p box (x fastest); @p cbuf and @p z hold one of its chunks. */
static int
read_prev_box(const box_feed *f, vv_voxel_type t, const int lo[3], const int n[3],
              unsigned char *box, unsigned char *cbuf, unsigned char *z, size_t zcap) {
    const size_t es = vv_voxel_type_size(t);
    const int *C = f->prev_chunk;
    const size_t raw_n = (size_t)C[0] * C[1] * C[2] * es;
    int a[3], b[3];
    for (int i = 0; i < 3; i++) {
        a[i] = lo[i] / C[i];
        b[i] = (lo[i] + n[i] - 1) / C[i];
    }
    for (int cz = a[2]; cz <= b[2]; cz++)
        for (int cy = a[1]; cy <= b[1]; cy++)
            for (int cx = a[0]; cx <= b[0]; cx++) {
                char p[ZARR_PATH_MAX];
                store_path(p, "%s/%d/%d/%d", f->prev_dir, cz, cy, cx);
                int err = read_chunk_file(p, z != NULL, cbuf, raw_n, z, zcap);
                if (err)
                    return err;
                const int c0[3] = {cx * C[0], cy * C[1], cz * C[2]};
                int g0[3], g1[3]; /* the overlap, in level voxels */
                for (int i = 0; i < 3; i++) {
                    g0[i] = lo[i] > c0[i] ? lo[i] : c0[i];
                    g1[i] = lo[i] + n[i] < c0[i] + C[i] ? lo[i] + n[i] : c0[i] + C[i];
                }
                for (int k = g0[2]; k < g1[2]; k++)
                    for (int y = g0[1]; y < g1[1]; y++)
                        memcpy(box + (((size_t)(k - lo[2]) * n[1] + (y - lo[1])) * n[0] +
                                      (g0[0] - lo[0])) *
                                         es,
                               cbuf + (((size_t)(k - c0[2]) * C[1] + (y - c0[1])) * C[0] +
                                       (g0[0] - c0[0])) *
                                          es,
                               (size_t)(g1[0] - g0[0]) * es);
            }
    return 0;
}

/* The chunk at @p o (@p e voxels inside the level) of a level after the
 * first into @p raw (chunk-shaped, cleared): the 2x2x2 blocks under it read
 * back from the level before into @p work (@p cbuf and @p z hold one of its
 * chunks). 0 or an errno (EILSEQ: a chunk read back is not the one written). */
static int
feed_chunk(chunk_job *j, const int o[3], const int e[3], unsigned char *raw, unsigned char *work,
           unsigned char *cbuf, unsigned char *z, size_t zcap) {
    box_feed *f = j->feed;
    /* the blocks under the chunk, in the level before */
    const int *sd = f->prev->dims, *st = f->step;
    int plo[3], pn[3];
    for (int i = 0; i < 3; i++) {
        plo[i] = o[i] * st[i];
        pn[i] = (o[i] + e[i]) * st[i] < sd[i] ? e[i] * st[i] : sd[i] - plo[i];
    }
    int err = read_prev_box(f, j->type, plo, pn, work, cbuf, z, zcap);
    if (err)
        return err;
    /* as down_body: the same voxels summed in the same order */
    vv_pyr_reduce_box b = {.src = work,
                           .type = j->type,
                           .src_dims = {sd[0], sd[1], sd[2]},
                           .src_lo = {plo[0], plo[1], plo[2]},
                           .src_n = {pn[0], pn[1], pn[2]},
                           .step = {st[0], st[1], st[2]},
                           .label = f->label,
                           .lo = {o[0], o[1], o[2]},
                           .n = {e[0], e[1], e[2]},
                           .dst_dims = {j->chunk[0], j->chunk[1]}};
    vv_pyr_reduce(&b, raw);
    return 0;
}

/* Chunk @p raw (chunk-shaped) compressed into @p z (when the job
 * compresses) and written as cz/cy/cx of the level; 0, an errno or -1 (out
 * of memory). */
static int
put_chunk(const chunk_job *j, int cx, int cy, int cz, const unsigned char *raw, size_t raw_n,
          unsigned char *z, uLong cap) {
    const unsigned char *out = raw;
    size_t out_n = raw_n;
    if (j->compress) {
        uLongf zn = cap;
        if (compress2(z, &zn, raw, (uLong)raw_n, 1) != Z_OK)
            return -1;
        out = z;
        out_n = zn;
    }
    char p[ZARR_PATH_MAX];
    store_path(p, "%s/%d/%d/%d", j->dir, cz, cy, cx);
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    size_t done = 0;
    while (fd >= 0 && done < out_n) {
        ssize_t r = write(fd, out + done, out_n - done);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        done += (size_t)r;
    }
    int err = fd < 0 || done < out_n ? (errno ? errno : EIO) : 0;
    if (fd >= 0 && close(fd) != 0 && !err)
        err = errno;
    return err;
}

/* Level 0 from the box reader, a row of chunks (all x, one y and z) at a
 * time: one read of the row's box (the reader's rows are the volume's full
 * width, so one pread a row of voxels rather than one a chunk's row), then
 * each chunk cut from it. Rows [r0, r1) of n[1] x n[2]. */
static void
row_body(void *ctx, long r0, long r1, int worker) {
    (void)worker;
    chunk_job *j = ctx;
    box_feed *f = j->feed;
    const size_t es = vv_voxel_type_size(j->type);
    const size_t raw_n = (size_t)j->chunk[0] * j->chunk[1] * j->chunk[2] * es;
    const uLong cap = compressBound((uLong)raw_n);
    unsigned char *raw = malloc(raw_n), *z = j->compress ? malloc(cap) : NULL;
    if (!raw || (j->compress && !z))
        j->failed = -1;
    const int *D = j->l->dims;
    for (long r = r0; r < r1 && !j->failed; r++) {
        const int cy = (int)(r % j->n[1]), cz = (int)(r / j->n[1]);
        const int y0 = cy * j->chunk[1], z0 = cz * j->chunk[2];
        const int h = D[1] - y0 < j->chunk[1] ? D[1] - y0 : j->chunk[1];
        const int d = D[2] - z0 < j->chunk[2] ? D[2] - z0 : j->chunk[2];
        const int lo[3] = {0, y0, z0}, hi[3] = {D[0] - 1, y0 + h - 1, z0 + d - 1};
        vv_volume *v = NULL;
        pthread_mutex_lock(&f->lock);
        while (f->next_row < r && !f->abandon)
            pthread_cond_wait(&f->turn, &f->lock);
        if (f->abandon) { /* the write failed (j->failed is set) */
            pthread_mutex_unlock(&f->lock);
            break;
        }
        vv_status s = f->status == VV_OK ? f->read(f->ctx, lo, hi, &v) : f->status;
        f->next_row = r + 1;
        pthread_cond_broadcast(&f->turn);
        if (s == VV_OK &&
            (!v || v->type != j->type || v->dims[0] != D[0] || v->dims[1] != h || v->dims[2] != d))
            s = vv_error_set(VV_ERR_INVALID, "the reader gave a box of another shape or type");
        if (s != VV_OK && f->status == VV_OK) {
            f->status = s;
            snprintf(f->message, sizeof f->message, "%s", vv_error_message());
        }
        pthread_mutex_unlock(&f->lock);
        if (s != VV_OK) {
            vv_volume_free(v);
            j->failed = -2;
            break;
        }
        /* the range of the voxels read, merged under the lock */
        double mn = INFINITY, mx = -INFINITY;
        for (size_t i = 0, n = (size_t)D[0] * h * d; i < n; i++) {
            const double x = vv_pyr_voxel(v->data, j->type, i);
            mn = x < mn ? x : mn;
            mx = x > mx ? x : mx;
        }
        pthread_mutex_lock(&f->lock);
        f->range[0] = !f->have_range || mn < f->range[0] ? mn : f->range[0];
        f->range[1] = !f->have_range || mx > f->range[1] ? mx : f->range[1];
        f->have_range = 1;
        pthread_mutex_unlock(&f->lock);
        for (int cx = 0; cx < j->n[0] && !j->failed; cx++) {
            const int x0 = cx * j->chunk[0];
            const int w = D[0] - x0 < j->chunk[0] ? D[0] - x0 : j->chunk[0];
            memset(raw, 0, raw_n); /* the padding of edge chunks: the fill value */
            for (int k = 0; k < d; k++)
                for (int y = 0; y < h; y++)
                    memcpy(raw + ((size_t)k * j->chunk[1] + y) * j->chunk[0] * es,
                           (const char *)v->data + (((size_t)k * h + y) * D[0] + x0) * es,
                           (size_t)w * es);
            int err = put_chunk(j, cx, cy, cz, raw, raw_n, z, cap);
            if (err)
                j->failed = err;
        }
        vv_volume_free(v);
    }
    if (j->failed) { /* rows this worker will not read: nobody waits for them */
        pthread_mutex_lock(&f->lock);
        f->abandon = 1;
        pthread_cond_broadcast(&f->turn);
        pthread_mutex_unlock(&f->lock);
    }
    free(raw);
    free(z);
}

static void
chunk_body(void *ctx, long c0, long c1, int worker) {
    (void)worker;
    chunk_job *j = ctx;
    size_t es = vv_voxel_type_size(j->type);
    size_t raw_n = (size_t)j->chunk[0] * j->chunk[1] * j->chunk[2] * es;
    uLong cap = compressBound((uLong)raw_n);
    unsigned char *raw = calloc(1, raw_n), *z = j->compress ? malloc(cap) : NULL;
    /* a further level from the store: the box of the level before under a
     * chunk, one of its chunks, and its compressed bytes */
    box_feed *f = j->feed;
    size_t work_n = 0, pchunk_n = 0, pcap = 0;
    if (f && !f->read) {
        work_n = (size_t)f->step[0] * f->step[1] * f->step[2] * raw_n;
        pchunk_n = (size_t)f->prev_chunk[0] * f->prev_chunk[1] * f->prev_chunk[2] * es;
        pcap = compressBound((uLong)pchunk_n);
    }
    unsigned char *work = work_n ? malloc(work_n) : NULL,
                  *pchunk = work_n ? malloc(pchunk_n) : NULL,
                  *pz = work_n && j->compress ? malloc(pcap) : NULL;
    if (work_n && (!work || !pchunk || (j->compress && !pz)))
        j->failed = -1;
    for (long c = c0; c < c1 && raw && (z || !j->compress) && !j->failed; c++) {
        int cx = (int)(c % j->n[0]), cy = (int)(c / j->n[0] % j->n[1]),
            cz = (int)(c / ((long)j->n[0] * j->n[1]));
        int x0 = cx * j->chunk[0], y0 = cy * j->chunk[1], z0 = cz * j->chunk[2];
        int w = j->l->dims[0] - x0 < j->chunk[0] ? j->l->dims[0] - x0 : j->chunk[0];
        memset(raw, 0, raw_n); /* the padding of edge chunks: the fill value */
        if (f) {
            const int o[3] = {x0, y0, z0};
            const int e[3] = {w,
                              j->l->dims[1] - y0 < j->chunk[1] ? j->l->dims[1] - y0 : j->chunk[1],
                              j->l->dims[2] - z0 < j->chunk[2] ? j->l->dims[2] - z0 : j->chunk[2]};
            int err = feed_chunk(j, o, e, raw, work, pchunk, pz, pcap);
            if (err) {
                j->failed = err;
                break;
            }
        } else
            for (int k = 0; k < j->chunk[2] && z0 + k < j->l->dims[2]; k++)
                for (int y = 0; y < j->chunk[1] && y0 + y < j->l->dims[1]; y++)
                    memcpy(raw + ((size_t)k * j->chunk[1] + y) * j->chunk[0] * es,
                           (const char *)j->l->data +
                               (((size_t)(z0 + k) * j->l->dims[1] + y0 + y) * j->l->dims[0] + x0) *
                                   es,
                           (size_t)w * es);
        int err = put_chunk(j, cx, cy, cz, raw, raw_n, z, cap);
        if (err) {
            j->failed = err;
            break;
        }
    }
    if (!raw || (j->compress && !z))
        j->failed = -1;
    free(raw);
    free(z);
    free(work);
    free(pchunk);
    free(pz);
}

static vv_status
write_level(const char *root, int index, const vv_volume *v, const zarr_level *l, int compress,
            box_feed *feed) {
    char dir[ZARR_PATH_MAX];
    store_path(dir, "%s/%d", root, index);
    chunk_job j = {dir, l, v->type, {0}, {0}, compress, 0, feed};
    for (int i = 0; i < 3; i++) {
        j.chunk[i] = l->dims[i] < ZARR_CHUNK ? l->dims[i] : ZARR_CHUNK;
        j.n[i] = (l->dims[i] + j.chunk[i] - 1) / j.chunk[i];
    }
    if (mkdir(dir, 0777) != 0)
        return vv_error_set(VV_ERR_IO, "%d: cannot make the folder: %s", index, strerror(errno));
    vv_status s = write_zarray(dir, v, l, j.chunk, compress);
    char p[ZARR_PATH_MAX];
    for (int cz = 0; s == VV_OK && cz < j.n[2]; cz++) {
        store_path(p, "%s/%d", dir, cz);
        if (mkdir(p, 0777) != 0)
            s = vv_error_set(VV_ERR_IO, "%d: cannot make a folder: %s", index, strerror(errno));
        for (int cy = 0; s == VV_OK && cy < j.n[1]; cy++) {
            store_path(p, "%s/%d/%d", dir, cz, cy);
            if (mkdir(p, 0777) != 0)
                s = vv_error_set(VV_ERR_IO, "%d: cannot make a folder: %s", index, strerror(errno));
        }
    }
    if (s != VV_OK)
        return s;
    if (feed && feed->read) /* level 0 from the reader: by rows of chunks */
        vv_parallel_for((long)j.n[1] * j.n[2], 1, 0, row_body, &j, NULL);
    else
        vv_parallel_for((long)j.n[0] * j.n[1] * j.n[2], 4, 0, chunk_body, &j, NULL);
    if (j.failed == -2)
        return vv_error_set(feed->status, "%s", feed->message);
    if (j.failed == -1)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (j.failed == EILSEQ)
        return vv_error_set(VV_ERR_IO,
                            "level %d: a chunk of level %d read back is not the one written", index,
                            index - 1);
    if (j.failed)
        return vv_error_set(VV_ERR_IO, "level %d: write failed: %s", index, strerror(j.failed));
    return VV_OK;
}

/* ---- the store ---------------------------------------------------------------- */

/* Syncs the file system that holds @p dir (every chunk at once). */
static vv_status
sync_store(const char *dir) {
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    int ok = fd >= 0 && syncfs(fd) == 0;
    int err = errno;
    if (fd >= 0)
        close(fd);
    return ok ? VV_OK : vv_error_set(VV_ERR_IO, "cannot sync: %s", strerror(err));
}

/* Moves the finished store @p tmp to @p path, exchanging it with an old
 * store there, which is removed after. */
static vv_status
put_in_place(const char *tmp, const char *path, int exists) {
    if (!exists) {
        if (rename(tmp, path) != 0)
            return vv_error_set(VV_ERR_IO, "cannot rename into place: %s", strerror(errno));
        return VV_OK;
    }
    if (renameat2(AT_FDCWD, tmp, AT_FDCWD, path, RENAME_EXCHANGE) != 0)
        return vv_error_set(VV_ERR_IO, "cannot replace the old store: %s", strerror(errno));
    remove_tree(tmp); /* now the old store */
    return VV_OK;
}

static vv_status
write_store(const vv_volume *v, const char *path, const char *tmp, const vv_save_options *opt) {
    zarr_level lv[ZARR_MAX_LEVELS];
    memset(lv, 0, sizeof lv);
    for (int i = 0; i < 3; i++) {
        lv[0].dims[i] = v->dims[i];
        lv[0].factor[i] = 1;
    }
    lv[0].data = v->data;
    int n = 1;
    vv_status s = VV_OK;
    while (s == VV_OK && n < ZARR_MAX_LEVELS &&
           (lv[n - 1].dims[0] > ZARR_CHUNK || lv[n - 1].dims[1] > ZARR_CHUNK ||
            lv[n - 1].dims[2] > ZARR_CHUNK)) {
        s = write_level(tmp, n - 1, v, &lv[n - 1], opt->compress != 0, NULL);
        if (s == VV_OK)
            s = next_level(&lv[n - 1], &lv[n], v->type, opt->label);
        if (s == VV_OK) {
            free(lv[n - 1].owned); /* a level is needed until the next is made */
            lv[n - 1].owned = NULL;
            n++;
        }
    }
    if (s == VV_OK)
        s = write_level(tmp, n - 1, v, &lv[n - 1], opt->compress != 0, NULL);
    for (int l = 0; l < n; l++)
        free(lv[l].owned);
    if (s == VV_OK)
        s = write_json(tmp, ".zgroup", json_pack("{s:i}", "zarr_format", 2));
    if (s == VV_OK) {
        char name[256];
        const char *base = vv_path_basename(path);
        size_t len = strcspn(base, ".");
        snprintf(name, sizeof name, "%.*s", (int)(len ? len : strlen(base)), base);
        s = write_zattrs(tmp, v, lv, n, opt->label, name);
    }
    return s;
}

/* The store from a volume read box by box: level 0 a chunk at a time from
 * @p read, each further level from the level before read back from @p tmp;
 * the omero window is the range of the voxels read. */
static vv_status
write_store_boxes(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                  const char *tmp, const vv_save_options *opt) {
    zarr_level lv[ZARR_MAX_LEVELS];
    memset(lv, 0, sizeof lv);
    int n = 1;
    for (int i = 0; i < 3; i++) {
        lv[0].dims[i] = hdr->dims[i];
        lv[0].factor[i] = 1;
    }
    while (n < ZARR_MAX_LEVELS &&
           (lv[n - 1].dims[0] > ZARR_CHUNK || lv[n - 1].dims[1] > ZARR_CHUNK ||
            lv[n - 1].dims[2] > ZARR_CHUNK)) {
        for (int i = 0; i < 3; i++) {
            const int step = lv[n - 1].dims[i] > 1 ? 2 : 1;
            lv[n].dims[i] = (lv[n - 1].dims[i] + step - 1) / step;
            lv[n].factor[i] = lv[n - 1].factor[i] * step;
        }
        n++;
    }
    box_feed f0;
    memset(&f0, 0, sizeof f0);
    f0.read = read;
    f0.ctx = ctx;
    pthread_mutex_init(&f0.lock, NULL);
    pthread_cond_init(&f0.turn, NULL);
    vv_status s = write_level(tmp, 0, hdr, &lv[0], opt->compress != 0, &f0);
    pthread_cond_destroy(&f0.turn);
    pthread_mutex_destroy(&f0.lock);
    char prev_dir[ZARR_PATH_MAX];
    for (int l = 1; s == VV_OK && l < n; l++) {
        box_feed f;
        memset(&f, 0, sizeof f);
        store_path(prev_dir, "%s/%d", tmp, l - 1);
        f.prev = &lv[l - 1];
        f.prev_dir = prev_dir;
        f.label = opt->label;
        for (int i = 0; i < 3; i++) {
            f.prev_chunk[i] = lv[l - 1].dims[i] < ZARR_CHUNK ? lv[l - 1].dims[i] : ZARR_CHUNK;
            f.step[i] = lv[l - 1].dims[i] > 1 ? 2 : 1;
        }
        s = write_level(tmp, l, hdr, &lv[l], opt->compress != 0, &f);
    }
    if (s == VV_OK)
        s = write_json(tmp, ".zgroup", json_pack("{s:i}", "zarr_format", 2));
    if (s == VV_OK) {
        vv_volume v = *hdr; /* the geometry, and the range of the voxels read */
        v.range[0] = f0.range[0];
        v.range[1] = f0.range[1];
        char name[256];
        const char *base = vv_path_basename(path);
        size_t len = strcspn(base, ".");
        snprintf(name, sizeof name, "%.*s", (int)(len ? len : strlen(base)), base);
        s = write_zattrs(tmp, &v, lv, n, opt->label, name);
    }
    return s;
}

static vv_status write_atomic(const vv_volume *v, vv_box_reader read, void *ctx, const char *path,
                              const vv_save_options *opt);

vv_status
vv_ome_zarr_write(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return write_atomic(v, NULL, NULL, path, opt);
}

vv_status
vv_ome_zarr_write_boxes(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                        const vv_save_options *opt) {
    if (!read)
        return vv_error_set(VV_ERR_INVALID, "ome-zarr: no box reader");
    return write_atomic(hdr, read, ctx, path, opt);
}

static vv_status
write_atomic(const vv_volume *v, vv_box_reader read, void *ctx, const char *path,
             const vv_save_options *opt) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "ome-zarr: NULL argument");
    vv_save_options defaults;
    if (!opt) {
        vv_save_options_init(&defaults);
        opt = &defaults;
    }
    struct stat st;
    int exists = lstat(path, &st) == 0;
    vv_status s = io_write_check_voxels(v, v->data || read, zarr_dtype(v->type) != NULL);
    if (s == VV_OK && opt->label && (v->type == VV_F32 || v->type == VV_F64))
        s = vv_error_set(VV_ERR_UNSUPPORTED, "a label volume holds integers, not %s",
                         vv_voxel_type_name(v->type));
    if (s == VV_OK)
        s = io_write_check_geometry(v, IO_WRITE_NO_DIRECTION);
    if (s == VV_OK && strlen(path) > ZARR_PATH_MAX - 128)
        s = vv_error_set(VV_ERR_INVALID, "the name is longer than %d bytes", ZARR_PATH_MAX - 128);
    if (s == VV_OK && exists && (!S_ISDIR(st.st_mode) || !is_zarr_store(path)))
        s = vv_error_set(VV_ERR_IO, "exists and is not a Zarr store (left as it is)");
    char *tmp = NULL;
    if (s == VV_OK) {
        size_t n = strlen(path) + 16;
        tmp = malloc(n);
        if (!tmp)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        else {
            snprintf(tmp, n, "%s.tmp-XXXXXX", path);
            if (!mkdtemp(tmp)) {
                s = vv_error_set(VV_ERR_IO, "cannot make a folder beside it: %s", strerror(errno));
                free(tmp);
                tmp = NULL;
            }
        }
    }
    if (s == VV_OK)
        s = read ? write_store_boxes(v, read, ctx, path, tmp, opt) : write_store(v, path, tmp, opt);
    if (s == VV_OK)
        s = sync_store(tmp);
    if (s == VV_OK)
        s = put_in_place(tmp, path, exists);
    if (s != VV_OK && tmp)
        remove_tree(tmp);
    free(tmp);
    if (s != VV_OK)
        return vv_error_prefix(s, "ome-zarr: %s", vv_path_basename(path));
    return VV_OK;
}

/* ---- the format record -------------------------------------------------------- */

static int
zarr_fits(const vv_volume *v, char *why, size_t cap) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            if (v->direction[r * 3 + c] != (r == c)) {
                snprintf(why, cap, "OME-Zarr 0.4 holds no direction matrix (written axis-aligned)");
                return 0;
            }
    return 1;
}

static vv_status
zarr_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_ome_zarr_write(v, path, opt);
}

static const char *const zarr_extensions[] = {"ome.zarr", "zarr", NULL};

static vv_status
zarr_write_boxes_record(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                        const vv_save_options *opt) {
    return vv_ome_zarr_write_boxes(hdr, read, ctx, path, opt);
}

const vv_format_record vv_format_ome_zarr = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "zarr",
    .title = "OME-Zarr",
    .extensions = zarr_extensions,
    .doc = "OME-Zarr 0.4 / Zarr v2 (a folder): read, level 0, one channel and time step (axes t, "
           "c, z, y, x in any order; raw, zlib, gzip, zstd, blosc chunks); written as a pyramid of "
           "2x2x2 means (labels: nearest), 64^3 chunks, zlib unless --no-compress",
    .flags = VV_FORMAT_FLAG_FOLDER | VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = vv_ome_zarr_looks_like,
    .fits = zarr_fits,
    .read = vv_ome_zarr_read,
    .write = zarr_write_record,
    .write_boxes = zarr_write_boxes_record,
    .open_store = vv_zr_pyramid_store,
};
