/*
 * OME-Zarr writer (vv_ome_zarr_write): an OME-NGFF 0.5 store (Zarr v3),
 * or with ngff_version 4 an OME-NGFF 0.4 store (Zarr v2), with the
 * multiscales metadata, as napari, Fiji (n5-zarr, MoBIE), BigDataViewer,
 * zarr-python, tensorstore and ome-zarr-py read it.
 *
 * Layout of 0.4 (a folder):
 *   .zgroup                 {"zarr_format": 2}
 *   .zattrs                 multiscales (axes z, y, x with the unit; one
 *                           dataset per level with its scale and
 *                           translation), omero (one channel, its window)
 *   <level>/.zarray         shape [nz, ny, nx], the chunk shape (64^3 unless
 *                           asked, clipped to the level), the voxel type
 *                           little-endian, C order, "/" as the dimension
 *                           separator, the compressor (zlib level 1 by
 *                           default; gzip, zstd, blosc) or none
 *   <level>/<cz>/<cy>/<cx>  one chunk, full chunk shape (edges padded with
 *                           the fill value 0), as Zarr v2 stores them
 * Layout of 0.5:
 *   zarr.json               a group; attributes.ome: version "0.5",
 *                           multiscales and omero as above
 *   <level>/zarr.json       an array: shape, data_type, a regular chunk grid
 *                           (the chunk shape, or the shard shape when
 *                           sharded), chunk key encoding "default" with
 *                           "/", fill value 0, codecs [bytes little-endian,
 *                           the compressor (zstd level 1 by default; gzip,
 *                           blosc lz4 with byte shuffle) or none], or
 *                           [sharding_indexed {the inner chunk shape, those
 *                           codecs, index codecs [bytes, crc32c], index at
 *                           the end}], dimension names z, y, x
 *   <level>/c/<z>/<y>/<x>   one chunk (padded as above), or one shard: its
 *                           inner chunks in C order, then the index (per
 *                           inner chunk its offset and size, 64-bit
 *                           little-endian; both all ones for an inner chunk
 *                           wholly outside the array, which is not written),
 *                           then the index's CRC-32C
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
 * temporary folder beside the target ("<path>.tmp-<owner>", named by
 * vv_tmp_name), synced, then exchanged with an existing store (renameat2
 * RENAME_EXCHANGE) or renamed into place; the old store is removed after.
 * The temporary folders of writers of the same path that were killed are
 * removed first (vv_tmp_sweep), those of writers still running are not.
 * An existing path that is not a Zarr store (no .zgroup, .zattrs, .zarray
 * or zarr.json) is never replaced. Chunks (shards) are gathered and compressed on every core
 * (vv_parallel_for).
 *
 * What OME-Zarr cannot hold: a direction matrix (the record's fits).
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

#include <blosc.h>
#include <jansson.h>
#include <zlib.h>
#include <zstd.h>

#include "core/crc32c.h"
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
/* The most inner chunks of one shard (its index is 16 bytes each, held). */
#define ZARR_SHARD_CHUNKS_MAX (1 << 20)

/* ---- what is written ---------------------------------------------------------- */

typedef enum zw_codec { ZW_NONE, ZW_ZLIB, ZW_GZIP, ZW_ZSTD, ZW_BLOSC } zw_codec;

#define ZARR_LEVEL 1       /* zlib, gzip, zstd: fast, as the v2 writer always was */
#define ZARR_BLOSC_LEVEL 5 /* blosc's (and numcodecs') default */

/* The store's format: Zarr v3 (NGFF 0.5) or v2 (0.4), the codec, the chunk
 * and shard shapes asked for (x, y, z; shard 0: none). */
typedef struct zarr_spec {
    int v3;
    zw_codec codec;
    int chunk[3], shard[3];
    int sharded;
} zarr_spec;

/* The spec of @p opt (NULL: the defaults); VV_ERR_INVALID naming the option. */
static vv_status
spec_of(const vv_save_options *opt, zarr_spec *z) {
    memset(z, 0, sizeof *z);
    const int ngff = opt && opt->ngff_version ? opt->ngff_version : VV_OME_ZARR_DEFAULT_NGFF;
    if (ngff != 4 && ngff != 5)
        return vv_error_set(VV_ERR_INVALID, "OME-NGFF 0.%d (written: 0.4, 0.5)", ngff);
    z->v3 = ngff == 5;
    const char *c = opt ? opt->codec : NULL;
    if (!c)
        z->codec = opt && opt->compress == 0 ? ZW_NONE : z->v3 ? ZW_ZSTD : ZW_ZLIB;
    else if (!strcmp(c, "none"))
        z->codec = ZW_NONE;
    else if (!strcmp(c, "zlib") && !z->v3)
        z->codec = ZW_ZLIB;
    else if (!strcmp(c, "gzip"))
        z->codec = ZW_GZIP;
    else if (!strcmp(c, "zstd"))
        z->codec = ZW_ZSTD;
    else if (!strcmp(c, "blosc"))
        z->codec = ZW_BLOSC;
    else
        return vv_error_set(VV_ERR_INVALID, "codec '%s' (OME-Zarr 0.%d: zstd, blosc, gzip%s, none)",
                            c, ngff, z->v3 ? "" : ", zlib");
    for (int i = 0; i < 3; i++) {
        const int ch = opt ? opt->chunk[i] : 0, sh = opt ? opt->shard[i] : 0;
        if (ch < 0 || ch > 4096)
            return vv_error_set(VV_ERR_INVALID, "chunk shape %d (1 .. 4096)", ch);
        z->chunk[i] = ch ? ch : ZARR_CHUNK;
        if (sh < 0 || (sh && sh % z->chunk[i]))
            return vv_error_set(VV_ERR_INVALID,
                                "shard shape %d is not a multiple of the chunk's %d", sh,
                                z->chunk[i]);
        z->shard[i] = sh;
        z->sharded |= sh > 0;
    }
    if (z->sharded && !z->v3)
        return vv_error_set(VV_ERR_INVALID, "sharding needs OME-NGFF 0.5 (Zarr v3)");
    for (int i = 0; z->sharded && i < 3; i++)
        if (!z->shard[i])
            z->shard[i] = z->chunk[i];
    if (z->sharded && (uint64_t)(z->shard[0] / z->chunk[0]) * (z->shard[1] / z->chunk[1]) *
                              (z->shard[2] / z->chunk[2]) >
                          ZARR_SHARD_CHUNKS_MAX)
        return vv_error_set(VV_ERR_INVALID, "a shard of more than %d chunks",
                            ZARR_SHARD_CHUNKS_MAX);
    return VV_OK;
}

/* A level's chunk shape (the asked one clipped to the level) and unit (the
 * shard, clipped to the level's chunks; the chunk when not sharded). */
static void
level_grid(const zarr_spec *z, const int dims[3], int chunk[3], int unit[3]) {
    for (int i = 0; i < 3; i++) {
        chunk[i] = dims[i] < z->chunk[i] ? dims[i] : z->chunk[i];
        const int cover = (dims[i] + chunk[i] - 1) / chunk[i] * chunk[i];
        unit[i] = z->sharded ? (z->shard[i] < cover ? z->shard[i] : cover) : chunk[i];
    }
}

/* 1 when a level of @p dims needs a next one. */
static int
level_needs_next(const zarr_spec *z, const int dims[3]) {
    return dims[0] > z->chunk[0] || dims[1] > z->chunk[1] || dims[2] > z->chunk[2];
}

/* ---- codecs ------------------------------------------------------------------- */

/* The most bytes @p n raw bytes encode to. */
static size_t
codec_bound(zw_codec c, size_t n) {
    switch (c) {
    case ZW_ZLIB:
    case ZW_GZIP:
        return compressBound((uLong)n) + 32;
    case ZW_ZSTD:
        return ZSTD_compressBound(n);
    case ZW_BLOSC:
        return n + BLOSC_MAX_OVERHEAD;
    default:
        return n;
    }
}

/* @p n bytes at @p src encoded into @p dst (@p cap bytes: codec_bound);
 * the size, or 0 on failure. */
static size_t
encode(zw_codec c, size_t es, const unsigned char *src, size_t n, unsigned char *dst, size_t cap) {
    switch (c) {
    case ZW_ZLIB: {
        uLongf zn = (uLongf)cap;
        return compress2(dst, &zn, src, (uLong)n, ZARR_LEVEL) == Z_OK ? (size_t)zn : 0;
    }
    case ZW_GZIP: {
        z_stream zs;
        memset(&zs, 0, sizeof zs);
        if (deflateInit2(&zs, ZARR_LEVEL, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
            return 0;
        zs.next_in = (Bytef *)src;
        zs.avail_in = (uInt)n;
        zs.next_out = dst;
        zs.avail_out = (uInt)cap;
        const int r = deflate(&zs, Z_FINISH);
        const size_t out = zs.total_out;
        deflateEnd(&zs);
        return r == Z_STREAM_END ? out : 0;
    }
    case ZW_ZSTD: {
        const size_t r = ZSTD_compress(dst, cap, src, n, ZARR_LEVEL);
        return ZSTD_isError(r) ? 0 : r;
    }
    case ZW_BLOSC: {
        const int r =
            blosc_compress_ctx(ZARR_BLOSC_LEVEL, BLOSC_SHUFFLE, es, n, src, dst, cap, "lz4", 0, 1);
        return r > 0 ? (size_t)r : 0;
    }
    default:
        memcpy(dst, src, n);
        return n;
    }
}

/* @p m bytes at @p src decoded into @p dst, exactly @p n bytes: 0 or EILSEQ. */
static int
decode(zw_codec c, const unsigned char *src, size_t m, unsigned char *dst, size_t n) {
    switch (c) {
    case ZW_ZLIB:
    case ZW_GZIP: {
        z_stream zs;
        memset(&zs, 0, sizeof zs);
        if (inflateInit2(&zs, c == ZW_GZIP ? 15 + 16 : 15) != Z_OK)
            return EILSEQ;
        zs.next_in = (Bytef *)src;
        zs.avail_in = (uInt)m;
        zs.next_out = dst;
        zs.avail_out = (uInt)n;
        const int r = inflate(&zs, Z_FINISH);
        const size_t out = zs.total_out;
        inflateEnd(&zs);
        return r == Z_STREAM_END && out == n ? 0 : EILSEQ;
    }
    case ZW_ZSTD: {
        const size_t r = ZSTD_decompress(dst, n, src, m);
        return !ZSTD_isError(r) && r == n ? 0 : EILSEQ;
    }
    case ZW_BLOSC:
        return blosc_decompress_ctx(src, dst, n, 1) == (int)n ? 0 : EILSEQ;
    default:
        if (m != n)
            return EILSEQ;
        memcpy(dst, src, n);
        return 0;
    }
}

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
    static const char *const names[] = {".zgroup", ".zattrs", ".zarray", "zarr.json"};
    char p[ZARR_PATH_MAX];
    for (int i = 0; i < 4; i++) {
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

/* Zarr v3's data_type of @p t (the order of vv_voxel_type, as zarr_dtype). */
static const char *
zarr3_dtype(vv_voxel_type t) {
    static const char *const names[] = {"uint8",  "int8",  "uint16",  "int16",
                                        "uint32", "int32", "float32", "float64"};
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
    case VV_UNIT_NM:
        return "nanometer";
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

static json_t *
zyx_ints(const int a[3]) {
    return json_pack("[i, i, i]", a[2], a[1], a[0]);
}

/* The store's group metadata: .zgroup and .zattrs (0.4), or zarr.json with
 * the same under attributes.ome (0.5). */
static vv_status
write_group(const char *dir, const zarr_spec *z, const vv_volume *v, const zarr_level *lv, int n,
            int label, const char *name) {
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
    json_t *ms = json_pack("{s:s, s:o, s:o, s:s, s:{s:s}}", "name", name, "axes", axes, "datasets",
                           sets, "type", label ? "nearest" : "local_mean", "metadata", "method",
                           label ? "VolVis: the first voxel of each 2x2x2 block"
                                 : "VolVis: the mean of each 2x2x2 block");
    if (ms && !z->v3) /* 0.4 dates each multiscales; 0.5 the ome object once */
        json_object_set_new(ms, "version", json_string("0.4"));
    json_t *omero = json_pack("{s:s, s:[{s:s, s:s, s:b, s:{s:f, s:f, s:f, s:f}}], s:{s:s}}", "name",
                              name, "channels", "label", name, "color", "FFFFFF", "active", 1,
                              "window", "min", v->range[0], "max", v->range[1], "start",
                              v->range[0], "end", v->range[1], "rdefs", "model", "greyscale");
    json_t *attrs = json_pack("{s:[o], s:o}", "multiscales", ms, "omero", omero);
    if (!z->v3) {
        if (label && attrs)
            json_object_set_new(attrs, "image-label", json_pack("{s:s}", "version", "0.4"));
        vv_status s = write_json(dir, ".zgroup", json_pack("{s:i}", "zarr_format", 2));
        if (s != VV_OK) {
            json_decref(attrs);
            return s;
        }
        return write_json(dir, ".zattrs", attrs);
    }
    json_t *ome = json_pack("{s:s}", "version", "0.5");
    if (ome && attrs)
        json_object_update(ome, attrs);
    json_decref(attrs);
    if (label && ome)
        json_object_set_new(ome, "image-label", json_object());
    return write_json(dir, "zarr.json",
                      json_pack("{s:i, s:s, s:{s:o}}", "zarr_format", 3, "node_type", "group",
                                "attributes", "ome", ome));
}

/* Zarr v3's codec objects for @p z's compressor of @p es-byte voxels
 * appended to @p a (bytes first). */
static json_t *
v3_codecs(const zarr_spec *z, size_t es) {
    json_t *a = json_pack("[{s:s, s:{s:s}}]", "name", "bytes", "configuration", "endian", "little");
    json_t *c = NULL;
    switch (z->codec) {
    case ZW_GZIP:
        c = json_pack("{s:s, s:{s:i}}", "name", "gzip", "configuration", "level", ZARR_LEVEL);
        break;
    case ZW_ZSTD:
        c = json_pack("{s:s, s:{s:i, s:b}}", "name", "zstd", "configuration", "level", ZARR_LEVEL,
                      "checksum", 0);
        break;
    case ZW_BLOSC:
        c = json_pack("{s:s, s:{s:s, s:i, s:s, s:i, s:i}}", "name", "blosc", "configuration",
                      "cname", "lz4", "clevel", ZARR_BLOSC_LEVEL, "shuffle", "shuffle", "typesize",
                      (int)es, "blocksize", 0);
        break;
    default:
        break;
    }
    if (c && a)
        json_array_append_new(a, c);
    return a;
}

/* The level's array metadata: .zarray (0.4) or zarr.json (0.5). */
static vv_status
write_array(const char *dir, const zarr_spec *z, const vv_volume *v, const zarr_level *l,
            const int chunk[3], const int unit[3]) {
    const size_t es = vv_voxel_type_size(v->type);
    if (!z->v3) {
        json_t *comp = NULL;
        switch (z->codec) {
        case ZW_ZLIB:
        case ZW_GZIP:
            comp = json_pack("{s:s, s:i}", "id", z->codec == ZW_ZLIB ? "zlib" : "gzip", "level",
                             ZARR_LEVEL);
            break;
        case ZW_ZSTD:
            comp = json_pack("{s:s, s:i}", "id", "zstd", "level", ZARR_LEVEL);
            break;
        case ZW_BLOSC:
            comp = json_pack("{s:s, s:s, s:i, s:i, s:i}", "id", "blosc", "cname", "lz4", "clevel",
                             ZARR_BLOSC_LEVEL, "shuffle", 1, "blocksize", 0);
            break;
        default:
            comp = json_null();
        }
        json_t *j = json_pack("{s:i, s:o, s:o, s:s, s:o, s:i, s:s, s:n, s:s}", "zarr_format", 2,
                              "shape", zyx_ints(l->dims), "chunks", zyx_ints(chunk), "dtype",
                              zarr_dtype(v->type), "compressor", comp, "fill_value", 0, "order",
                              "C", "filters", "dimension_separator", "/");
        return write_json(dir, ".zarray", j);
    }
    json_t *codecs = v3_codecs(z, es);
    if (z->sharded)
        codecs = json_pack("[{s:s, s:{s:o, s:o, s:[{s:s, s:{s:s}}, {s:s}], s:s}}]", "name",
                           "sharding_indexed", "configuration", "chunk_shape", zyx_ints(chunk),
                           "codecs", codecs, "index_codecs", "name", "bytes", "configuration",
                           "endian", "little", "name", "crc32c", "index_location", "end");
    json_t *j = json_pack(
        "{s:i, s:s, s:o, s:s, s:{s:s, s:{s:o}}, s:{s:s, s:{s:s}}, s:i, s:o, s:{}, s:[s, s, s]}",
        "zarr_format", 3, "node_type", "array", "shape", zyx_ints(l->dims), "data_type",
        zarr3_dtype(v->type), "chunk_grid", "name", "regular", "configuration", "chunk_shape",
        zyx_ints(unit), "chunk_key_encoding", "name", "default", "configuration", "separator", "/",
        "fill_value", 0, "codecs", codecs, "attributes", "dimension_names", "z", "y", "x");
    return write_json(dir, "zarr.json", j);
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

/* The dims and factors of the level after @p src; the steps into @p step. */
static void
next_dims(const zarr_level *src, zarr_level *dst, int step[3]) {
    for (int i = 0; i < 3; i++) {
        step[i] = src->dims[i] > 1 ? 2 : 1;
        dst->dims[i] = (src->dims[i] + step[i] - 1) / step[i];
        dst->factor[i] = src->factor[i] * step[i];
    }
}

/* The level after @p src. */
static vv_status
next_level(const zarr_level *src, zarr_level *dst, vv_voxel_type t, int label) {
    down_job j = {src, dst, t, label, {1, 1, 1}};
    next_dims(src, dst, j.step);
    dst->owned = malloc((size_t)dst->dims[0] * dst->dims[1] * dst->dims[2] * vv_voxel_type_size(t));
    if (!dst->owned)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    dst->data = dst->owned;
    vv_parallel_for(dst->dims[2], 1, 0, down_body, &j, NULL);
    return VV_OK;
}

/* ---- chunks ------------------------------------------------------------------- */

/* Where a level's voxels come from when they are not in memory: level 0
 * from the caller's box reader (one box a row of units -- chunks, or shards
 * -- one call at a time: row_body), a further level from the level before
 * it, read back from the store being written (the 2x2x2 blocks under one
 * chunk) and reduced as next_level does (feed_chunk). */
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
    int prev_chunk[3], prev_unit[3], step[3], label;
} box_feed;

typedef struct chunk_job {
    const char *dir; /* the level's folder */
    const zarr_level *l;
    const zarr_spec *spec;
    vv_voxel_type type;
    int chunk[3], unit[3]; /* chunk and unit (shard or chunk) shapes */
    int n[3], nin[3];      /* units per axis, chunks per unit and axis (x, y, z) */
    int failed;            /* the first errno, or -1 for out of memory, -2 the feed's status */
    box_feed *feed;        /* NULL: l->data in memory */
} chunk_job;

/* A worker's buffers: one chunk raw and encoded, a shard's index, and for a
 * level read back, the box under a chunk and a chunk of the level before
 * (raw and encoded). */
typedef struct chunk_bufs {
    unsigned char *raw, *z, *index;
    size_t raw_n, cap;
    unsigned char *work, *pchunk, *pz;
    size_t pchunk_n, pcap;
} chunk_bufs;

static void
bufs_free(chunk_bufs *b) {
    free(b->raw);
    free(b->z);
    free(b->index);
    free(b->work);
    free(b->pchunk);
    free(b->pz);
}

/* 0, or -1 out of memory. */
static int
bufs_alloc(const chunk_job *j, chunk_bufs *b) {
    memset(b, 0, sizeof *b);
    const size_t es = vv_voxel_type_size(j->type);
    b->raw_n = (size_t)j->chunk[0] * j->chunk[1] * j->chunk[2] * es;
    b->cap = codec_bound(j->spec->codec, b->raw_n);
    b->raw = malloc(b->raw_n);
    b->z = malloc(b->cap);
    if (j->spec->sharded)
        b->index = malloc((size_t)j->nin[0] * j->nin[1] * j->nin[2] * 16 + 4);
    const box_feed *f = j->feed;
    if (f && !f->read) {
        b->work = malloc((size_t)f->step[0] * f->step[1] * f->step[2] * b->raw_n);
        b->pchunk_n = (size_t)f->prev_chunk[0] * f->prev_chunk[1] * f->prev_chunk[2] * es;
        b->pcap = codec_bound(j->spec->codec, b->pchunk_n);
        b->pchunk = malloc(b->pchunk_n);
        b->pz = malloc(b->pcap);
    }
    if (!b->raw || !b->z || (j->spec->sharded && !b->index) ||
        (f && !f->read && (!b->work || !b->pchunk || !b->pz))) {
        bufs_free(b);
        memset(b, 0, sizeof *b);
        return -1;
    }
    return 0;
}

/* pread of exactly @p n bytes at @p off: 0 or an errno (EILSEQ: the file
 * ends first). */
static int
pread_all(int fd, void *buf, size_t n, off_t off) {
    size_t got = 0;
    while (got < n) {
        ssize_t r = pread(fd, (char *)buf + got, n - got, off + (off_t)got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return errno;
        if (r == 0)
            return EILSEQ;
        got += (size_t)r;
    }
    return 0;
}

static void
put_le64(unsigned char *p, uint64_t x) {
    for (int i = 0; i < 8; i++, x >>= 8)
        p[i] = (unsigned char)x;
}

/* Chunk (cx, cy, cz) of the level before (written) into b->pchunk: from its
 * file, or from its shard by the shard's index. 0 or an errno (EILSEQ: not
 * the chunk written). */
static int
read_prev_chunk(const box_feed *f, const zarr_spec *z, int cx, int cy, int cz, chunk_bufs *b) {
    char p[ZARR_PATH_MAX];
    const int *U = f->prev_unit, *C = f->prev_chunk;
    const int nin[3] = {U[0] / C[0], U[1] / C[1], U[2] / C[2]};
    if (z->sharded)
        store_path(p, "%s/c/%d/%d/%d", f->prev_dir, cz / nin[2], cy / nin[1], cx / nin[0]);
    else if (z->v3)
        store_path(p, "%s/c/%d/%d/%d", f->prev_dir, cz, cy, cx);
    else
        store_path(p, "%s/%d/%d/%d", f->prev_dir, cz, cy, cx);
    int fd = open(p, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return errno;
    struct stat st;
    int err = fstat(fd, &st) != 0 ? errno : 0;
    off_t off = 0;
    size_t m = (size_t)st.st_size;
    if (!err && z->sharded) {
        const size_t n_in = (size_t)nin[0] * nin[1] * nin[2];
        const size_t i = ((size_t)(cz % nin[2]) * nin[1] + cy % nin[1]) * nin[0] + cx % nin[0];
        unsigned char e[16];
        if ((size_t)st.st_size < n_in * 16 + 4)
            err = EILSEQ;
        else
            err = pread_all(fd, e, 16, st.st_size - 4 - (off_t)(n_in * 16) + (off_t)(i * 16));
        if (!err) {
            const uint64_t o = zr_le64(e), n = zr_le64(e + 8);
            if (o > (uint64_t)st.st_size || n > (uint64_t)st.st_size - o)
                err = EILSEQ; /* (all ones: never written for a chunk inside the level) */
            off = (off_t)o;
            m = (size_t)n;
        }
    }
    if (!err && m > b->pcap)
        err = EILSEQ;
    if (!err)
        err = pread_all(fd, b->pz, m, off);
    close(fd);
    return err ? err : decode(z->codec, b->pz, m, b->pchunk, b->pchunk_n);
}

/* Voxels lo .. lo + n - 1 of the level before (f->prev, written) into
 * b->work (x fastest). */
static int
read_prev_box(const box_feed *f, const zarr_spec *z, vv_voxel_type t, const int lo[3],
              const int n[3], chunk_bufs *bf) {
    const size_t es = vv_voxel_type_size(t);
    const int *C = f->prev_chunk;
    int a[3], b[3];
    for (int i = 0; i < 3; i++) {
        a[i] = lo[i] / C[i];
        b[i] = (lo[i] + n[i] - 1) / C[i];
    }
    for (int cz = a[2]; cz <= b[2]; cz++)
        for (int cy = a[1]; cy <= b[1]; cy++)
            for (int cx = a[0]; cx <= b[0]; cx++) {
                int err = read_prev_chunk(f, z, cx, cy, cz, bf);
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
                        memcpy(bf->work + (((size_t)(k - lo[2]) * n[1] + (y - lo[1])) * n[0] +
                                           (g0[0] - lo[0])) *
                                              es,
                               bf->pchunk + (((size_t)(k - c0[2]) * C[1] + (y - c0[1])) * C[0] +
                                             (g0[0] - c0[0])) *
                                                es,
                               (size_t)(g1[0] - g0[0]) * es);
            }
    return 0;
}

/* The chunk at @p o (@p e voxels inside the level) of a level after the
 * first into b->raw (chunk-shaped, cleared): the 2x2x2 blocks under it read
 * back from the level before. 0 or an errno (EILSEQ: a chunk read back is
 * not the one written). */
static int
feed_chunk(const chunk_job *j, const int o[3], const int e[3], chunk_bufs *bf) {
    const box_feed *f = j->feed;
    /* the blocks under the chunk, in the level before */
    const int *sd = f->prev->dims, *st = f->step;
    int plo[3], pn[3];
    for (int i = 0; i < 3; i++) {
        plo[i] = o[i] * st[i];
        pn[i] = (o[i] + e[i]) * st[i] < sd[i] ? e[i] * st[i] : sd[i] - plo[i];
    }
    int err = read_prev_box(f, j->spec, j->type, plo, pn, bf);
    if (err)
        return err;
    /* as down_body: the same voxels summed in the same order */
    vv_pyr_reduce_box b = {.src = bf->work,
                           .type = j->type,
                           .src_dims = {sd[0], sd[1], sd[2]},
                           .src_lo = {plo[0], plo[1], plo[2]},
                           .src_n = {pn[0], pn[1], pn[2]},
                           .step = {st[0], st[1], st[2]},
                           .label = f->label,
                           .lo = {o[0], o[1], o[2]},
                           .n = {e[0], e[1], e[2]},
                           .dst_dims = {j->chunk[0], j->chunk[1]}};
    vv_pyr_reduce(&b, bf->raw);
    return 0;
}

/* write(2) of all @p n bytes: 0 or an errno. */
static int
write_all(int fd, const unsigned char *p, size_t n) {
    size_t done = 0;
    while (done < n) {
        ssize_t r = write(fd, p + done, n - done);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return r < 0 ? errno : EIO;
        done += (size_t)r;
    }
    return 0;
}

/* Unit (ux, uy, uz) of the level -- a chunk, or a shard of chunks -- made
 * and written: each chunk's voxels from @p box (voxels borg .. borg +
 * bdims - 1 of the level, x fastest) or, with box NULL, from the level
 * before (feed_chunk); encoded; written as its file, or appended to the
 * shard's file, whose index and its CRC-32C end it. 0, an errno or -1 (out
 * of memory). */
static int
put_unit(const chunk_job *j, chunk_bufs *b, int ux, int uy, int uz, const unsigned char *box,
         const int borg[3], const int bdims[3]) {
    const size_t es = vv_voxel_type_size(j->type);
    const int *C = j->chunk, *D = j->l->dims;
    char p[ZARR_PATH_MAX];
    if (j->spec->v3)
        store_path(p, "%s/c/%d/%d/%d", j->dir, uz, uy, ux);
    else
        store_path(p, "%s/%d/%d/%d", j->dir, uz, uy, ux);
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0)
        return errno;
    int err = 0;
    uint64_t at = 0; /* the shard's bytes so far */
    size_t idx = 0;
    for (int iz = 0; iz < j->nin[2] && !err; iz++)
        for (int iy = 0; iy < j->nin[1] && !err; iy++)
            for (int ix = 0; ix < j->nin[0] && !err; ix++, idx++) {
                const int cx = ux * j->nin[0] + ix, cy = uy * j->nin[1] + iy,
                          cz = uz * j->nin[2] + iz;
                const int x0 = cx * C[0], y0 = cy * C[1], z0 = cz * C[2];
                if (x0 >= D[0] || y0 >= D[1] || z0 >= D[2]) { /* past the level: empty */
                    memset(b->index + idx * 16, 0xFF, 16);
                    continue;
                }
                const int e[3] = {D[0] - x0 < C[0] ? D[0] - x0 : C[0],
                                  D[1] - y0 < C[1] ? D[1] - y0 : C[1],
                                  D[2] - z0 < C[2] ? D[2] - z0 : C[2]};
                memset(b->raw, 0, b->raw_n); /* the padding of edge chunks: the fill value */
                if (box) {
                    for (int k = 0; k < e[2]; k++)
                        for (int y = 0; y < e[1]; y++)
                            memcpy(b->raw + ((size_t)k * C[1] + y) * C[0] * es,
                                   box + (((size_t)(z0 + k - borg[2]) * bdims[1] +
                                           (y0 + y - borg[1])) *
                                              bdims[0] +
                                          (x0 - borg[0])) *
                                             es,
                                   (size_t)e[0] * es);
                } else {
                    const int o[3] = {x0, y0, z0};
                    if ((err = feed_chunk(j, o, e, b)))
                        break;
                }
                const size_t zn = encode(j->spec->codec, es, b->raw, b->raw_n, b->z, b->cap);
                if (!zn) {
                    err = -1;
                    break;
                }
                err = write_all(fd, b->z, zn);
                if (j->spec->sharded) {
                    put_le64(b->index + idx * 16, at);
                    put_le64(b->index + idx * 16 + 8, zn);
                }
                at += zn;
            }
    if (!err && j->spec->sharded) {
        const size_t in = idx * 16;
        const uint32_t crc = vv_crc32c(0, b->index, in);
        for (int i = 0; i < 4; i++)
            b->index[in + i] = (unsigned char)(crc >> (8 * i));
        err = write_all(fd, b->index, in + 4);
    }
    if (close(fd) != 0 && !err)
        err = errno;
    return err;
}

/* Level 0 from the box reader, a row of units (all x, one y and z) at a
 * time: one read of the row's box (the reader's rows are the volume's full
 * width, so one pread a row of voxels rather than one a chunk's row), then
 * each unit cut from it. Rows [r0, r1) of n[1] x n[2]. */
static void
row_body(void *ctx, long r0, long r1, int worker) {
    (void)worker;
    chunk_job *j = ctx;
    box_feed *f = j->feed;
    chunk_bufs b;
    if (bufs_alloc(j, &b))
        j->failed = -1;
    const int *D = j->l->dims;
    for (long r = r0; r < r1 && !j->failed; r++) {
        const int uy = (int)(r % j->n[1]), uz = (int)(r / j->n[1]);
        const int y0 = uy * j->unit[1], z0 = uz * j->unit[2];
        const int h = D[1] - y0 < j->unit[1] ? D[1] - y0 : j->unit[1];
        const int d = D[2] - z0 < j->unit[2] ? D[2] - z0 : j->unit[2];
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
        const int borg[3] = {0, y0, z0}, bdims[3] = {D[0], h, d};
        for (int ux = 0; ux < j->n[0] && !j->failed; ux++) {
            int err = put_unit(j, &b, ux, uy, uz, v->data, borg, bdims);
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
    bufs_free(&b);
}

/* Units [c0, c1) from the level in memory, or from the level before. */
static void
unit_body(void *ctx, long c0, long c1, int worker) {
    (void)worker;
    chunk_job *j = ctx;
    chunk_bufs b;
    if (bufs_alloc(j, &b)) {
        j->failed = -1;
        return;
    }
    const int org[3] = {0, 0, 0};
    for (long c = c0; c < c1 && !j->failed; c++) {
        const int ux = (int)(c % j->n[0]), uy = (int)(c / j->n[0] % j->n[1]),
                  uz = (int)(c / ((long)j->n[0] * j->n[1]));
        int err = put_unit(j, &b, ux, uy, uz, j->feed ? NULL : j->l->data, org, j->l->dims);
        if (err)
            j->failed = err;
    }
    bufs_free(&b);
}

static vv_status
write_level(const char *root, int index, const zarr_spec *z, const vv_volume *v,
            const zarr_level *l, box_feed *feed) {
    char dir[ZARR_PATH_MAX];
    store_path(dir, "%s/%d", root, index);
    chunk_job j = {dir, l, z, v->type, {0}, {0}, {0}, {0}, 0, feed};
    level_grid(z, l->dims, j.chunk, j.unit);
    for (int i = 0; i < 3; i++) {
        j.n[i] = (l->dims[i] + j.unit[i] - 1) / j.unit[i];
        j.nin[i] = j.unit[i] / j.chunk[i];
    }
    if (mkdir(dir, 0777) != 0)
        return vv_error_set(VV_ERR_IO, "%d: cannot make the folder: %s", index, strerror(errno));
    vv_status s = write_array(dir, z, v, l, j.chunk, j.unit);
    char base[ZARR_PATH_MAX], p[ZARR_PATH_MAX];
    if (z->v3) {
        store_path(base, "%s/c", dir);
        if (s == VV_OK && mkdir(base, 0777) != 0)
            s = vv_error_set(VV_ERR_IO, "%d: cannot make a folder: %s", index, strerror(errno));
    } else
        store_path(base, "%s", dir);
    for (int cz = 0; s == VV_OK && cz < j.n[2]; cz++) {
        store_path(p, "%s/%d", base, cz);
        if (mkdir(p, 0777) != 0)
            s = vv_error_set(VV_ERR_IO, "%d: cannot make a folder: %s", index, strerror(errno));
        for (int cy = 0; s == VV_OK && cy < j.n[1]; cy++) {
            store_path(p, "%s/%d/%d", base, cz, cy);
            if (mkdir(p, 0777) != 0)
                s = vv_error_set(VV_ERR_IO, "%d: cannot make a folder: %s", index, strerror(errno));
        }
    }
    if (s != VV_OK)
        return s;
    if (feed && feed->read) {
        /* level 0 from the reader: by rows of units, each worker holding one
         * row's box (and the reader its slices): as many workers as a
         * quarter of the memory budget holds such boxes (a row of big shards
         * is many rows of chunks), at least one */
        const uint64_t row =
            (uint64_t)l->dims[0] * j.unit[1] * j.unit[2] * vv_voxel_type_size(v->type);
        const uint64_t fit = vv_memory_budget_get() / 4 / (row ? row : 1);
        const int threads = fit < (uint64_t)vv_threads_get() ? (fit ? (int)fit : 1) : 0;
        vv_parallel_for((long)j.n[1] * j.n[2], 1, threads, row_body, &j, NULL);
    } else
        vv_parallel_for((long)j.n[0] * j.n[1] * j.n[2], z->sharded ? 1 : 4, 0, unit_body, &j, NULL);
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

/* The store's name in its metadata: @p path's base name up to its first dot. */
static void
store_name(const char *path, char *name, size_t cap) {
    const char *base = vv_path_basename(path);
    size_t len = strcspn(base, ".");
    snprintf(name, cap, "%.*s", (int)(len ? len : strlen(base)), base);
}

static vv_status
write_store(const vv_volume *v, const char *path, const char *tmp, const zarr_spec *z,
            const vv_save_options *opt) {
    zarr_level lv[ZARR_MAX_LEVELS];
    memset(lv, 0, sizeof lv);
    for (int i = 0; i < 3; i++) {
        lv[0].dims[i] = v->dims[i];
        lv[0].factor[i] = 1;
    }
    lv[0].data = v->data;
    int n = 1;
    vv_status s = VV_OK;
    while (s == VV_OK && n < ZARR_MAX_LEVELS && level_needs_next(z, lv[n - 1].dims)) {
        s = write_level(tmp, n - 1, z, v, &lv[n - 1], NULL);
        if (s == VV_OK)
            s = next_level(&lv[n - 1], &lv[n], v->type, opt->label);
        if (s == VV_OK) {
            free(lv[n - 1].owned); /* a level is needed until the next is made */
            lv[n - 1].owned = NULL;
            n++;
        }
    }
    if (s == VV_OK)
        s = write_level(tmp, n - 1, z, v, &lv[n - 1], NULL);
    for (int l = 0; l < n; l++)
        free(lv[l].owned);
    if (s == VV_OK) {
        char name[256];
        store_name(path, name, sizeof name);
        s = write_group(tmp, z, v, lv, n, opt->label, name);
    }
    return s;
}

/* The store from a volume read box by box: level 0 a unit row at a time from
 * @p read, each further level from the level before read back from @p tmp;
 * the omero window is the range of the voxels read. */
static vv_status
write_store_boxes(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                  const char *tmp, const zarr_spec *z, const vv_save_options *opt) {
    zarr_level lv[ZARR_MAX_LEVELS];
    memset(lv, 0, sizeof lv);
    int n = 1;
    for (int i = 0; i < 3; i++) {
        lv[0].dims[i] = hdr->dims[i];
        lv[0].factor[i] = 1;
    }
    int step[3];
    while (n < ZARR_MAX_LEVELS && level_needs_next(z, lv[n - 1].dims)) {
        next_dims(&lv[n - 1], &lv[n], step);
        n++;
    }
    box_feed f0;
    memset(&f0, 0, sizeof f0);
    f0.read = read;
    f0.ctx = ctx;
    pthread_mutex_init(&f0.lock, NULL);
    pthread_cond_init(&f0.turn, NULL);
    vv_status s = write_level(tmp, 0, z, hdr, &lv[0], &f0);
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
        level_grid(z, lv[l - 1].dims, f.prev_chunk, f.prev_unit);
        for (int i = 0; i < 3; i++)
            f.step[i] = lv[l - 1].dims[i] > 1 ? 2 : 1;
        s = write_level(tmp, l, z, hdr, &lv[l], &f);
    }
    if (s == VV_OK) {
        vv_volume v = *hdr; /* the geometry, and the range of the voxels read */
        v.range[0] = f0.range[0];
        v.range[1] = f0.range[1];
        char name[256];
        store_name(path, name, sizeof name);
        s = write_group(tmp, z, &v, lv, n, opt->label, name);
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
    zarr_spec z;
    vv_status s = spec_of(opt, &z);
    if (s == VV_OK)
        s = io_write_check_voxels(v, v->data || read, zarr_dtype(v->type) != NULL);
    if (s == VV_OK) { /* level 0's chunks are the largest: what a reader allows */
        int c[3], u[3];
        level_grid(&z, v->dims, c, u);
        const uint64_t bytes = (uint64_t)c[0] * c[1] * c[2] * vv_voxel_type_size(v->type);
        if (bytes > ZR_CHUNK_MAX)
            s = vv_error_set(
                VV_ERR_INVALID, "a chunk of %d x %d x %d voxels is %llu bytes (at most %llu)", c[0],
                c[1], c[2], (unsigned long long)bytes, (unsigned long long)ZR_CHUNK_MAX);
    }
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
        /* the temporary stores of writers of this path that were killed */
        (void)vv_tmp_sweep(path);
        size_t n = strlen(path) + 64;
        tmp = malloc(n);
        if (!tmp)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        int made = 0, err = EEXIST;
        for (unsigned attempt = 0; tmp && !made && err == EEXIST && attempt < 100; attempt++) {
            if (vv_tmp_name(tmp, n, path, (long)getpid(), attempt) != 0)
                err = ENAMETOOLONG;
            else if (mkdir(tmp, 0777) == 0)
                made = 1;
            else
                err = errno;
        }
        if (tmp && !made) {
            s = vv_error_set(VV_ERR_IO, "cannot make a folder beside it: %s", strerror(err));
            free(tmp);
            tmp = NULL;
        }
    }
    if (s == VV_OK)
        s = read ? write_store_boxes(v, read, ctx, path, tmp, &z, opt)
                 : write_store(v, path, tmp, &z, opt);
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
                snprintf(why, cap, "OME-Zarr holds no direction matrix (written axis-aligned)");
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
    .doc = "OME-Zarr 0.1-0.5 / Zarr v2 and v3 (a folder): read, one level (0 unless --level), "
           "channel and time step (axes t, c, z, y, x in any order; v2: raw, zlib, gzip, zstd, "
           "blosc; v3: bytes, transpose, gzip, zstd, blosc, crc32c, sharding_indexed, read by "
           "inner chunk); written as OME-NGFF 0.5 "
           "(Zarr v3, optionally sharded) or 0.4: a pyramid of 2x2x2 means (labels: nearest), "
           "64^3 chunks, zstd (0.5) or zlib (0.4) unless --compress",
    .flags = VV_FORMAT_FLAG_FOLDER | VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = vv_ome_zarr_looks_like,
    .fits = zarr_fits,
    .read = vv_ome_zarr_read,
    .write = zarr_write_record,
    .write_boxes = zarr_write_boxes_record,
    .open_store = vv_zr_pyramid_store,
    .open_store_channels = vv_zr_pyramid_store_channels,
};
