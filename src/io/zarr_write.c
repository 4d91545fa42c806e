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
#include "io/zarr.h"
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

static double
load_voxel(const void *d, vv_voxel_type t, size_t i) {
    switch (t) {
    case VV_U8:
        return ((const uint8_t *)d)[i];
    case VV_I8:
        return ((const int8_t *)d)[i];
    case VV_U16:
        return ((const uint16_t *)d)[i];
    case VV_I16:
        return ((const int16_t *)d)[i];
    case VV_U32:
        return ((const uint32_t *)d)[i];
    case VV_I32:
        return ((const int32_t *)d)[i];
    case VV_F32:
        return ((const float *)d)[i];
    default:
        return ((const double *)d)[i];
    }
}

static void
store_voxel(void *d, vv_voxel_type t, size_t i, double x) {
    if (t != VV_F32 && t != VV_F64)
        x = floor(x + 0.5); /* the mean of integers, rounded to nearest */
    switch (t) {
    case VV_U8:
        ((uint8_t *)d)[i] = (uint8_t)x;
        break;
    case VV_I8:
        ((int8_t *)d)[i] = (int8_t)x;
        break;
    case VV_U16:
        ((uint16_t *)d)[i] = (uint16_t)x;
        break;
    case VV_I16:
        ((int16_t *)d)[i] = (int16_t)x;
        break;
    case VV_U32:
        ((uint32_t *)d)[i] = (uint32_t)x;
        break;
    case VV_I32:
        ((int32_t *)d)[i] = (int32_t)x;
        break;
    case VV_F32:
        ((float *)d)[i] = (float)x;
        break;
    default:
        ((double *)d)[i] = x;
        break;
    }
}

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
    size_t es = vv_voxel_type_size(j->type);
    for (long k = k0; k < k1; k++)
        for (int y = 0; y < dd[1]; y++)
            for (int x = 0; x < dd[0]; x++) {
                size_t o = ((size_t)k * dd[1] + y) * dd[0] + x;
                int x0 = x * j->step[0], y0 = y * j->step[1], z0 = (int)k * j->step[2];
                if (j->label) {
                    size_t i = ((size_t)z0 * sd[1] + y0) * sd[0] + x0;
                    memcpy((char *)j->dst->owned + o * es, (const char *)j->src->data + i * es, es);
                    continue;
                }
                double sum = 0;
                int n = 0;
                for (int dz = 0; dz < j->step[2] && z0 + dz < sd[2]; dz++)
                    for (int dy = 0; dy < j->step[1] && y0 + dy < sd[1]; dy++)
                        for (int dx = 0; dx < j->step[0] && x0 + dx < sd[0]; dx++, n++)
                            sum +=
                                load_voxel(j->src->data, j->type,
                                           ((size_t)(z0 + dz) * sd[1] + y0 + dy) * sd[0] + x0 + dx);
                store_voxel(j->dst->owned, j->type, o, sum / n);
            }
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

typedef struct chunk_job {
    const char *dir; /* the level's folder */
    const zarr_level *l;
    vv_voxel_type type;
    int chunk[3], n[3]; /* chunk shape, chunks per axis (x, y, z) */
    int compress;
    int failed; /* the first errno, or -1 for out of memory */
} chunk_job;

static void
chunk_body(void *ctx, long c0, long c1, int worker) {
    (void)worker;
    chunk_job *j = ctx;
    size_t es = vv_voxel_type_size(j->type);
    size_t raw_n = (size_t)j->chunk[0] * j->chunk[1] * j->chunk[2] * es;
    uLong cap = compressBound((uLong)raw_n);
    unsigned char *raw = calloc(1, raw_n), *z = j->compress ? malloc(cap) : NULL;
    for (long c = c0; c < c1 && raw && (z || !j->compress) && !j->failed; c++) {
        int cx = (int)(c % j->n[0]), cy = (int)(c / j->n[0] % j->n[1]),
            cz = (int)(c / ((long)j->n[0] * j->n[1]));
        int x0 = cx * j->chunk[0], y0 = cy * j->chunk[1], z0 = cz * j->chunk[2];
        int w = j->l->dims[0] - x0 < j->chunk[0] ? j->l->dims[0] - x0 : j->chunk[0];
        memset(raw, 0, raw_n); /* the padding of edge chunks: the fill value */
        for (int k = 0; k < j->chunk[2] && z0 + k < j->l->dims[2]; k++)
            for (int y = 0; y < j->chunk[1] && y0 + y < j->l->dims[1]; y++)
                memcpy(raw + ((size_t)k * j->chunk[1] + y) * j->chunk[0] * es,
                       (const char *)j->l->data +
                           (((size_t)(z0 + k) * j->l->dims[1] + y0 + y) * j->l->dims[0] + x0) * es,
                       (size_t)w * es);
        const unsigned char *out = raw;
        size_t out_n = raw_n;
        if (j->compress) {
            uLongf zn = cap;
            if (compress2(z, &zn, raw, (uLong)raw_n, 1) != Z_OK) {
                j->failed = -1;
                break;
            }
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
        if (err) {
            j->failed = err;
            break;
        }
    }
    if (!raw || (j->compress && !z))
        j->failed = -1;
    free(raw);
    free(z);
}

static vv_status
write_level(const char *root, int index, const vv_volume *v, const zarr_level *l, int compress) {
    char dir[ZARR_PATH_MAX];
    store_path(dir, "%s/%d", root, index);
    chunk_job j = {dir, l, v->type, {0}, {0}, compress, 0};
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
    vv_parallel_for((long)j.n[0] * j.n[1] * j.n[2], 4, 0, chunk_body, &j, NULL);
    if (j.failed == -1)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
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
        s = write_level(tmp, n - 1, v, &lv[n - 1], opt->compress != 0);
        if (s == VV_OK)
            s = next_level(&lv[n - 1], &lv[n], v->type, opt->label);
        if (s == VV_OK) {
            free(lv[n - 1].owned); /* a level is needed until the next is made */
            lv[n - 1].owned = NULL;
            n++;
        }
    }
    if (s == VV_OK)
        s = write_level(tmp, n - 1, v, &lv[n - 1], opt->compress != 0);
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

vv_status
vv_ome_zarr_write(const vv_volume *v, const char *path, const vv_save_options *opt) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "ome-zarr: NULL argument");
    vv_save_options defaults;
    if (!opt) {
        vv_save_options_init(&defaults);
        opt = &defaults;
    }
    vv_status s = VV_OK;
    struct stat st;
    int exists = lstat(path, &st) == 0;
    if (!v->data)
        s = vv_error_set(VV_ERR_INVALID, "volume has no data");
    else if (!zarr_dtype(v->type))
        s = vv_error_set(VV_ERR_UNSUPPORTED, "voxel type %d cannot be written", (int)v->type);
    else if (opt->label && (v->type == VV_F32 || v->type == VV_F64))
        s = vv_error_set(VV_ERR_UNSUPPORTED, "a label volume holds integers, not %s",
                         vv_voxel_type_name(v->type));
    for (int i = 0; s == VV_OK && i < 3; i++)
        if (!(v->spacing[i] > 0) || !isfinite(v->spacing[i]) || !isfinite(v->origin[i]))
            s = vv_error_set(VV_ERR_INVALID, "axis %d: spacing %g, origin %g", i, v->spacing[i],
                             v->origin[i]);
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
        s = write_store(v, path, tmp, opt);
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

const vv_volume_format vv_volume_format_ome_zarr = {
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
};
