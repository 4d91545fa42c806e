/*
 * N5 (the Saalfeld lab's format: github.com/saalfeldlab/n5, "N5 specification"),
 * read through the Zarr reader's zr_array (zarr.h): an N5 dataset is a Zarr
 * array whose axes are listed fastest first, whose chunks ("blocks") carry a
 * big-endian header and big-endian voxels, and whose blocks at the array's end
 * hold only the voxels inside it.
 *
 * A dataset is a folder (or a URL) with an attributes.json naming its
 * dimensions, blockSize, dataType (uint8 .. uint64, int8 .. int64, float32,
 * float64) and compression ({"type": "raw" | "gzip" | "bzip2" | "xz" |
 * "blosc" | "zstd"}, or version 0's "compressionType"). Its blocks lie at
 * "i/j/k" (the block's grid position, N5 order). A block is mode (u16: 0
 * default, 1 varlength; 2, object blocks, is refused), the number of
 * dimensions (u16), the block's size along each (u32; a block at the end of
 * the array is cut to it), for varlength the number of elements (u32), then
 * the voxels, compressed, big-endian, the first dimension fastest.
 *
 * A multiscale group (n5-viewer, BigDataViewer's exports, Neuroglancer's and
 * tensorstore's writers, Janelia's COSEM/OpenOrganelle) holds its levels as
 * datasets s0 .. sN: each level's downsamplingFactors (or the group's
 * "scales"; else the ratio of the levels' dimensions), the group's
 * "resolution" or "pixelResolution" (else s0's) and "units" give the
 * spacing; a COSEM group's "multiscales" give each level's scale and
 * translation outright. The group is read as the OME-NGFF multiscales it
 * amounts to (zr_n5_root), so that levels, axes, spacing and the pyramid
 * source are the Zarr reader's: a level downsampled by f is shifted by
 * (f - 1) / 2 voxels of level 0 (its voxels' centres, as averaging
 * downsamplers make them).
 */
#include <bzlib.h>
#include <jansson.h>
#include <lzma.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>
#include <zstd.h>

#include <blosc.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/pyramid.h"
#include "io/store/zarr.h"
#include "volvis/sys/source.h"

/* the most levels a multiscale group is looked through for (s0 .. s31) */
#define N5_MAX_LEVELS 32

static uint32_t
be32(const unsigned char *p) {
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* ---- attributes ------------------------------------------------------------- */

/* @p nd sizes of JSON array @p j (each 1 .. 2^40) into @p out, N5 order. */
static int
sizes_of(json_t *j, int nd, uint64_t *out) {
    if (!json_is_array(j) || (int)json_array_size(j) != nd)
        return 0;
    for (int i = 0; i < nd; i++) {
        json_t *x = json_array_get(j, (size_t)i);
        if (!json_is_integer(x) || json_integer_value(x) < 1 || json_integer_value(x) > (1LL << 40))
            return 0;
        out[i] = (uint64_t)json_integer_value(x);
    }
    return 1;
}

/* @p nd finite positive numbers of JSON array @p j into @p out. */
static int
numbers_of(json_t *j, int nd, double *out) {
    if (!json_is_array(j) || (int)json_array_size(j) != nd)
        return 0;
    for (int i = 0; i < nd; i++) {
        json_t *x = json_array_get(j, (size_t)i);
        const double v = json_number_value(x);
        if (!json_is_number(x) || !isfinite(v) || v <= 0 || v > 1e30)
            return 0;
        out[i] = v;
    }
    return 1;
}

/* The resolution (N5 order) and unit of attributes @p at: "resolution"
 * (with "units"), or "pixelResolution" (an object of dimensions and unit,
 * or an array). 1 when found. */
static int
resolution_of(json_t *at, int nd, double *res, char unit[][32]) {
    json_t *pr = json_object_get(at, "pixelResolution");
    json_t *r = json_object_get(at, "resolution");
    const char *u = NULL;
    int ok = 0;
    if (numbers_of(r, nd, res))
        ok = 1;
    else if (json_is_object(pr) && numbers_of(json_object_get(pr, "dimensions"), nd, res)) {
        ok = 1;
        u = json_string_value(json_object_get(pr, "unit"));
    } else if (numbers_of(pr, nd, res))
        ok = 1;
    json_t *units = json_object_get(at, "units");
    for (int i = 0; ok && i < nd; i++) {
        const char *ui = json_string_value(json_array_get(units, (size_t)i));
        snprintf(unit[i], 32, "%s", ui ? ui : u ? u : "");
    }
    return ok;
}

/* The axis names (N5 order) of attributes @p at's "axes" into @p names; 1
 * when it lists @p nd names. */
static int
axes_of(json_t *at, int nd, char names[][32]) {
    json_t *ax = json_object_get(at, "axes");
    if (!json_is_array(ax) || (int)json_array_size(ax) != nd)
        return 0;
    for (int i = 0; i < nd; i++) {
        const char *s = json_string_value(json_array_get(ax, (size_t)i));
        if (!s || !*s)
            return 0;
        snprintf(names[i], 32, "%s", s);
    }
    return 1;
}

static const struct {
    const char *name;
    vv_voxel_type type;
    int conv64;
} n5_types[] = {{"uint8", VV_U8, 0},    {"int8", VV_I8, 0},     {"uint16", VV_U16, 0},
                {"int16", VV_I16, 0},   {"uint32", VV_U32, 0},  {"int32", VV_I32, 0},
                {"float32", VV_F32, 0}, {"float64", VV_F64, 0}, {"int64", VV_F64, 1},
                {"uint64", VV_F64, 2}};

vv_status
zr_n5_parse_array(zr_array *a, void *jv) {
    json_t *j = jv;
    a->zarr_format = ZR_N5;
    a->nshard = 0;
    a->conv64 = 0;
    a->fill = 0;
    a->sep = '/';
    a->codec[0] = '\0';
    a->n5_has_res = 0;
    json_t *dims = json_object_get(j, "dimensions"), *bs = json_object_get(j, "blockSize");
    if (!json_is_array(dims) || json_array_size(dims) < 2 || json_array_size(dims) > ZR_MAX_DIM)
        return vv_error_set(VV_ERR_FORMAT,
                            "attributes.json: dimensions is not 2 to %d sizes (not an N5 dataset)",
                            ZR_MAX_DIM);
    const int nd = (int)json_array_size(dims);
    uint64_t d[ZR_MAX_DIM], b[ZR_MAX_DIM];
    if (!sizes_of(dims, nd, d))
        return vv_error_set(VV_ERR_FORMAT, "attributes.json: dimensions: not %d sizes", nd);
    if (!sizes_of(bs, nd, b))
        return vv_error_set(VV_ERR_FORMAT, "attributes.json: blockSize: not %d sizes", nd);
    a->ndim = nd;
    for (int i = 0; i < nd; i++) { /* N5 lists the fastest axis first */
        a->shape[i] = d[nd - 1 - i];
        a->chunks[i] = b[nd - 1 - i];
        a->axes[i].name[0] = '\0';
    }
    const char *dt = json_string_value(json_object_get(j, "dataType"));
    size_t m = 0;
    while (dt && m < sizeof n5_types / sizeof n5_types[0] && strcmp(dt, n5_types[m].name))
        m++;
    if (!dt || m == sizeof n5_types / sizeof n5_types[0])
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "attributes.json: dataType \"%.40s\" (supported: uint8 .. uint64, "
                            "int8 .. int64, float32, float64)",
                            dt ? dt : "(none)");
    a->type = n5_types[m].type;
    a->conv64 = n5_types[m].conv64;
    a->esize = vv_voxel_type_size(a->type);
    a->swap = a->esize > 1 && vv_host_is_little_endian(); /* N5 is big-endian */
    /* compression: an object with its type, or version 0's compressionType */
    json_t *comp = json_object_get(j, "compression");
    const char *ct = json_is_object(comp)
                         ? json_string_value(json_object_get(comp, "type"))
                         : json_string_value(json_object_get(j, "compressionType"));
    if (comp && !json_is_object(comp))
        return vv_error_set(VV_ERR_FORMAT, "attributes.json: compression is not an object");
    if (!ct || !strcmp(ct, "raw"))
        a->codec[0] = '\0';
    else if (!strcmp(ct, "gzip") || !strcmp(ct, "bzip2") || !strcmp(ct, "xz") ||
             !strcmp(ct, "blosc") || !strcmp(ct, "zstd"))
        snprintf(a->codec, sizeof a->codec, "%s", ct);
    else
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "attributes.json: compression \"%.40s\" (supported: raw, gzip, bzip2, "
                            "xz, blosc, zstd)",
                            ct);
    /* the dataset's own axis names, resolution and units (applied when it
     * is opened alone) */
    char names[ZR_MAX_DIM][32], unit[ZR_MAX_DIM][32];
    double res[ZR_MAX_DIM];
    if (axes_of(j, nd, names))
        for (int i = 0; i < nd; i++)
            snprintf(a->axes[i].name, sizeof a->axes[i].name, "%s", names[nd - 1 - i]);
    if (resolution_of(j, nd, res, unit)) {
        a->n5_has_res = 1;
        for (int i = 0; i < nd; i++)
            a->n5_res[i] = res[nd - 1 - i];
        snprintf(a->n5_unit, sizeof a->n5_unit, "%s", unit[0]);
    }
    return VV_OK;
}

/* ---- a multiscale group as OME-NGFF multiscales ---------------------------- */

/* The kind of axis @p name: 0 space, 1 channel, 2 time, -1 unknown. */
static int
kind_of(const char *name) {
    if (!strcmp(name, "x") || !strcmp(name, "y") || !strcmp(name, "z"))
        return 0;
    if (!strcmp(name, "c") || !strcmp(name, "channel"))
        return 1;
    if (!strcmp(name, "t") || !strcmp(name, "time"))
        return 2;
    return -1;
}

/* A COSEM group's multiscales (each dataset's "transform": axes, scale,
 * translate, units, in the array's order) as OME-NGFF datasets; NULL when
 * @p ms is not one. */
static json_t *
cosem_multiscales(json_t *ms) {
    json_t *dsl = json_object_get(ms, "datasets");
    if (!json_is_array(dsl) || !json_array_size(dsl) ||
        !json_is_object(json_object_get(json_array_get(dsl, 0), "transform")))
        return NULL;
    json_t *out = json_object(), *nd = json_array(), *axes = json_array();
    size_t i;
    json_t *ds;
    json_array_foreach(dsl, i, ds) {
        json_t *t = json_object_get(ds, "transform");
        json_t *sc = json_object_get(t, "scale"), *tr = json_object_get(t, "translate");
        json_t *e = json_object();
        json_object_set(e, "path", json_object_get(ds, "path"));
        json_t *ct = json_array();
        if (sc)
            json_array_append_new(ct, json_pack("{s:s,s:O}", "type", "scale", "scale", sc));
        if (tr)
            json_array_append_new(ct,
                                  json_pack("{s:s,s:O}", "type", "translation", "translation", tr));
        json_object_set_new(e, "coordinateTransformations", ct);
        json_array_append_new(nd, e);
        if (i == 0) {
            json_t *an = json_object_get(t, "axes"), *un = json_object_get(t, "units");
            size_t k;
            json_t *name;
            json_array_foreach(an, k, name) {
                const char *s = json_string_value(name);
                const char *u = json_string_value(json_array_get(un, k));
                const int kind = s ? kind_of(s) : -1;
                json_array_append_new(axes, json_pack("{s:s,s:s,s:s}", "name", s ? s : "?", "type",
                                                      kind == 1   ? "channel"
                                                      : kind == 2 ? "time"
                                                                  : "space",
                                                      "unit", u ? u : ""));
            }
        }
    }
    json_object_set_new(out, "datasets", nd);
    if (json_array_size(axes))
        json_object_set_new(out, "axes", axes);
    else
        json_decref(axes);
    return out;
}

vv_status
zr_n5_root(const zr_array *a, void *attrs_v, void **za_out) {
    json_t *at = attrs_v;
    *za_out = NULL;
    if (json_object_get(at, "dimensions") || json_object_get(at, "dataType") ||
        json_object_get(at, "blockSize"))
        return VV_OK; /* a dataset: a plain array (its parser names what it lacks) */
    /* NGFF multiscales kept in an N5 group (coordinateTransformations), or
     * COSEM's (transform) */
    json_t *ms0 = json_array_get(json_object_get(at, "multiscales"), 0);
    json_t *d0 = json_array_get(json_object_get(ms0, "datasets"), 0);
    if (json_object_get(d0, "coordinateTransformations")) {
        *za_out = json_incref(at);
        return VV_OK;
    }
    json_t *cosem = ms0 ? cosem_multiscales(ms0) : NULL;
    if (cosem) {
        *za_out = json_pack("{s:[o]}", "multiscales", cosem);
        return VV_OK;
    }
    /* s0 .. sN: each level's attributes */
    json_t *scales = json_object_get(at, "scales");
    int count = json_is_array(scales) ? (int)json_array_size(scales) : N5_MAX_LEVELS;
    if (count > N5_MAX_LEVELS)
        return vv_error_set(VV_ERR_LIMIT, "attributes.json: %d scales (at most %d)", count,
                            N5_MAX_LEVELS);
    json_t *lv[N5_MAX_LEVELS] = {0};
    vv_status s = VV_OK;
    int n = 0;
    for (; n < count; n++) {
        char key[1200];
        snprintf(key, sizeof key, "%s%ss%d/attributes.json", a->prefix, a->prefix[0] ? "/" : "", n);
        lv[n] = zr_load_json(a, key, key, 1, &s);
        if (s != VV_OK || !lv[n])
            break;
    }
    if (s == VV_OK && n == 0)
        s = vv_error_set(VV_ERR_FORMAT,
                         "attributes.json: an N5 group without a dataset s0 (open a dataset or "
                         "a multiscale group of datasets s0, s1, ...)");
    if (s == VV_OK && json_is_array(scales) && n < count)
        s = vv_error_set(VV_ERR_FORMAT, "attributes.json: %d scales, but no dataset s%d", count, n);
    json_t *dims0 = json_object_get(lv[0], "dimensions");
    const int nd = s == VV_OK ? (int)json_array_size(dims0) : 0;
    uint64_t d0s[ZR_MAX_DIM];
    if (s == VV_OK && (nd < 2 || nd > ZR_MAX_DIM || !sizes_of(dims0, nd, d0s)))
        s = vv_error_set(VV_ERR_FORMAT, "s0/attributes.json: dimensions is not 2 to %d sizes",
                         ZR_MAX_DIM);
    /* names (N5 order): the group's axes, s0's, else t, c, z, y, x reversed */
    char names[ZR_MAX_DIM][32], unit[ZR_MAX_DIM][32];
    double res[ZR_MAX_DIM];
    static const char *const xyzct[5] = {"x", "y", "z", "c", "t"};
    if (s == VV_OK && !axes_of(at, nd, names) && !axes_of(lv[0], nd, names))
        for (int i = 0; i < nd; i++)
            snprintf(names[i], 32, "%s", xyzct[i]);
    if (s == VV_OK && !resolution_of(at, nd, res, unit) && !resolution_of(lv[0], nd, res, unit))
        for (int i = 0; i < nd; i++) {
            res[i] = 1;
            unit[i][0] = '\0';
        }
    json_t *ms = NULL;
    if (s == VV_OK) {
        json_t *axes = json_array(), *dsl = json_array();
        for (int i = nd - 1; i >= 0; i--) {
            const int kind = kind_of(names[i]);
            json_t *ax = json_pack("{s:s,s:s}", "name", names[i], "type",
                                   kind == 1   ? "channel"
                                   : kind == 2 ? "time"
                                               : "space");
            if (unit[i][0] && kind == 0)
                json_object_set_new(ax, "unit", json_string(unit[i]));
            json_array_append_new(axes, ax);
        }
        for (int l = 0; l < n && s == VV_OK; l++) {
            double f[ZR_MAX_DIM];
            uint64_t dl[ZR_MAX_DIM];
            json_t *sl = json_array_get(scales, (size_t)l);
            if (!sizes_of(json_object_get(lv[l], "dimensions"), nd, dl)) {
                s = vv_error_set(VV_ERR_FORMAT, "s%d/attributes.json: dimensions is not %d sizes",
                                 l, nd);
                break;
            }
            if (!numbers_of(json_object_get(lv[l], "downsamplingFactors"), nd, f) &&
                !numbers_of(sl, nd, f))
                for (int i = 0; i < nd; i++) /* the ratio of the level's dimensions */
                    f[i] = fmax(1.0, round((double)d0s[i] / (double)dl[i]));
            json_t *sc = json_array(), *tr = json_array();
            for (int i = nd - 1; i >= 0; i--) {
                const int spatial = kind_of(names[i]) <= 0;
                json_array_append_new(sc, json_real(spatial ? res[i] * f[i] : 1.0));
                json_array_append_new(tr, json_real(spatial ? 0.5 * (f[i] - 1) * res[i] : 0.0));
            }
            char path[16];
            snprintf(path, sizeof path, "s%d", l);
            json_array_append_new(dsl,
                                  json_pack("{s:s,s:[{s:s,s:o},{s:s,s:o}]}", "path", path,
                                            "coordinateTransformations", "type", "scale", "scale",
                                            sc, "type", "translation", "translation", tr));
        }
        ms = json_pack("{s:o,s:o}", "axes", axes, "datasets", dsl);
    }
    for (int l = 0; l < N5_MAX_LEVELS; l++)
        json_decref(lv[l]);
    if (s != VV_OK) {
        json_decref(ms);
        return s;
    }
    *za_out = json_pack("{s:[o]}", "multiscales", ms);
    return VV_OK;
}

/* ---- blocks ---------------------------------------------------------------------- */

void
zr_n5_key(const zr_array *a, const uint64_t *idx, char *key, size_t cap) {
    int len = snprintf(key, cap, "%s", a->prefix);
    for (int i = a->ndim - 1; i >= 0 && len >= 0 && len < (int)cap; i--)
        len += snprintf(key + len, cap - (size_t)len, "%s%llu", len ? "/" : "",
                        (unsigned long long)idx[i]);
}

int
zr_gunzip(const unsigned char *src, size_t m, unsigned char *out, size_t n) {
    if (m > UINT32_MAX || n > UINT32_MAX)
        return 0;
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit2(&z, 32 + MAX_WBITS) != Z_OK)
        return 0;
    z.next_in = (unsigned char *)src;
    z.avail_in = (uInt)m;
    z.next_out = out;
    z.avail_out = (uInt)n;
    const int ok = inflate(&z, Z_FINISH) == Z_STREAM_END && z.avail_out == 0;
    inflateEnd(&z);
    return ok;
}

/* The compressed voxels @p src (@p m bytes) decoded by the dataset's
 * compression into exactly @p n bytes at @p out. */
static vv_status
n5_inflate(const zr_array *a, const unsigned char *src, size_t m, unsigned char *out, size_t n,
           const char *what) {
    const char *c = a->codec;
    int ok = 0;
    if (!c[0]) {
        ok = m == n;
        if (ok)
            memcpy(out, src, n);
    } else if (!strcmp(c, "gzip")) { /* gzip, or zlib with useZlib: either header */
        ok = zr_gunzip(src, m, out, n);
    } else if (!strcmp(c, "bzip2")) {
        unsigned int got = (unsigned int)n;
        ok = m <= UINT32_MAX && n <= UINT32_MAX &&
             BZ2_bzBuffToBuffDecompress((char *)out, &got, (char *)src, (unsigned int)m, 0, 0) ==
                 BZ_OK &&
             got == n;
    } else if (!strcmp(c, "xz")) {
        uint64_t memlimit = (uint64_t)256 << 20;
        size_t in_pos = 0, out_pos = 0;
        ok = lzma_stream_buffer_decode(&memlimit, 0, NULL, src, &in_pos, m, out, &out_pos, n) ==
                 LZMA_OK &&
             out_pos == n;
    } else if (!strcmp(c, "zstd")) {
        const size_t r = ZSTD_decompress(out, n, src, m);
        ok = !ZSTD_isError(r) && r == n;
    } else { /* blosc */
        size_t nb = 0;
        ok = blosc_cbuffer_validate(src, m, &nb) == 0 && nb == n &&
             blosc_decompress_ctx(src, out, n, 1) == (int)n;
    }
    if (!ok)
        return vv_error_set(VV_ERR_FORMAT, "%s: the %s block does not decode to %zu bytes", what,
                            c[0] ? c : "raw", n);
    return VV_OK;
}

vv_status
zr_n5_decode(const zr_array *a, const unsigned char *src, size_t m, unsigned char *out, size_t n,
             const char *what) {
    const int nd = a->ndim;
    if (m < 4)
        return vv_error_set(VV_ERR_FORMAT, "%s: %zu bytes, shorter than an N5 block header", what,
                            m);
    const unsigned mode = (unsigned)src[0] << 8 | src[1], bnd = (unsigned)src[2] << 8 | src[3];
    if (mode > 1)
        return vv_error_set(VV_ERR_UNSUPPORTED, "%s: N5 block mode %u (only default and varlength)",
                            what, mode);
    if ((int)bnd != nd)
        return vv_error_set(VV_ERR_FORMAT, "%s: a block of %u dimensions in a dataset of %d", what,
                            bnd, nd);
    const size_t hdr = 4 + 4 * (size_t)nd + (mode == 1 ? 4 : 0);
    if (m < hdr)
        return vv_error_set(VV_ERR_FORMAT, "%s: %zu bytes, shorter than its %zu-byte header", what,
                            m, hdr);
    uint64_t bs[ZR_MAX_DIM], elems = 1;
    int whole = 1;
    for (int d = 0; d < nd; d++) { /* N5 order: the array's axis nd - 1 - d */
        bs[d] = be32(src + 4 + 4 * (size_t)d);
        const uint64_t full = a->chunks[nd - 1 - d];
        if (bs[d] < 1 || bs[d] > full)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: a block of %llu along dimension %d, the blockSize is %llu",
                                what, (unsigned long long)bs[d], d, (unsigned long long)full);
        whole &= bs[d] == full;
        elems *= bs[d];
    }
    if (mode == 1 && be32(src + hdr - 4) != elems)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: a varlength block of %u elements, its size holds %llu", what,
                            be32(src + hdr - 4), (unsigned long long)elems);
    const size_t bytes = (size_t)elems * a->esize;
    if (bytes > n)
        return vv_error_set(VV_ERR_FORMAT, "%s: a block of %zu bytes in a chunk of %zu", what,
                            bytes, n);
    if (whole)
        return n5_inflate(a, src + hdr, m - hdr, out, n, what);
    /* a block cut at the array's end: its voxels at the chunk's start */
    unsigned char *tmp = malloc(bytes);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory for %zu bytes", what, bytes);
    vv_status s = n5_inflate(a, src + hdr, m - hdr, tmp, bytes, what);
    if (s == VV_OK) {
        uint64_t cut[ZR_MAX_DIM]; /* the array's order */
        for (int i = 0; i < nd; i++)
            cut[i] = bs[nd - 1 - i];
        zr_place_cut(a, cut, tmp, out, n);
    }
    free(tmp);
    return s;
}

void
zr_place_cut(const zr_array *a, const uint64_t *cut, const unsigned char *src, unsigned char *out,
             size_t n) {
    const int nd = a->ndim;
    uint64_t elems = 1;
    for (int i = 0; i < nd; i++)
        elems *= cut[i];
    memset(out, 0, n);
    /* rows along the array's last axis: cut[nd - 1] voxels each */
    uint64_t pos[ZR_MAX_DIM] = {0}; /* array axes 0 .. nd - 2 */
    const size_t row = (size_t)cut[nd - 1] * a->esize;
    for (uint64_t r = 0; r < elems / cut[nd - 1]; r++) {
        uint64_t off = 0;
        for (int i = 0; i < nd - 1; i++)
            off = off * a->chunks[i] + pos[i];
        off *= a->chunks[nd - 1];
        memcpy(out + off * a->esize, src + r * row, row);
        for (int i = nd - 2; i >= 0; i--) { /* the next row, C order */
            if (++pos[i] < cut[i])
                break;
            pos[i] = 0;
        }
    }
}

/* ---- the format row -------------------------------------------------------------- */

int
vv_n5_looks_like(const vv_format_probe *p, int deep) {
    if (!p->is_dir || deep)
        return 0;
    /* a Zarr store beside (zarr.json, .zattrs, .zarray) is the Zarr row's */
    char f[4200], head[8193];
    struct stat st;
    static const char *const zarr[] = {"zarr.json", ".zattrs", ".zarray"};
    for (size_t i = 0; i < sizeof zarr / sizeof zarr[0]; i++) {
        snprintf(f, sizeof f, "%s/%s", p->path, zarr[i]);
        if (stat(f, &st) == 0)
            return 0;
    }
    if (!zr_file_head(p->path, "attributes.json", head, sizeof head)) {
        /* a multiscale group need not have attributes (BigDataViewer's
         * timepoint groups): its dataset s0 says */
        snprintf(f, sizeof f, "%s/s0/attributes.json", p->path);
        return stat(f, &st) == 0;
    }
    if (strstr(head, "\"dimensions\"") || strstr(head, "\"dataType\"") ||
        strstr(head, "\"blockSize\""))
        return 1; /* a dataset (its reader names what it lacks) */
    if (strstr(head, "\"n5\"") || strstr(head, "\"scales\"") || strstr(head, "\"multiscales\"") ||
        strstr(head, "\"downsamplingFactors\"") || strstr(head, "\"pixelResolution\""))
        return 1; /* a container or a multiscale group */
    snprintf(f, sizeof f, "%s/s0/attributes.json", p->path);
    return stat(f, &st) == 0;
}

/* ---- BigDataViewer's bdv.n5: setups as channels, timepoints as time steps ------------ */

/* The most setups and timepoints a bdv.n5 container is looked through for. */
#define BDV_N5_MAX 4096

/* 1 when folder @p dir/@p fmt exists (fmt takes @p i, then @p j if it names two). */
static int
bdv_dir(const char *dir, const char *fmt, int i, int j) {
    char f[4200];
    int n = snprintf(f, sizeof f, "%s/", dir);
    snprintf(f + n, sizeof f - (size_t)n, fmt, i, j);
    struct stat st;
    return stat(f, &st) == 0 && S_ISDIR(st.st_mode);
}

/*
 * 1 when local folder @p path is a BigDataViewer N5 container (its
 * "BigDataViewer N5 format": groups setup<S>/timepoint<T> each a multiscale
 * group s0 .. sN, the setup's attributes holding downsamplingFactors and
 * dataType): *n_setups the setups setup0, setup1, ... and *n_times the
 * timepoints of setup0 (timepoint0, timepoint1, ...), counted while they
 * follow on.
 */
static int
bdv_n5_layout(const char *path, int *n_setups, int *n_times) {
    if (bs_is_url(path) || !bdv_dir(path, "setup%d/timepoint%d/s0", 0, 0))
        return 0;
    int ns = 1, nt = 1;
    while (ns < BDV_N5_MAX && bdv_dir(path, "setup%d", ns, 0))
        ns++;
    while (nt < BDV_N5_MAX && bdv_dir(path, "setup0/timepoint%d", nt, 0))
        nt++;
    *n_setups = ns;
    *n_times = nt;
    return 1;
}

/* The group of setup @p setup at timepoint @p time of container @p path
 * into @p out; VV_ERR_INVALID naming what the container has. */
static vv_status
bdv_n5_group(const char *path, int setup, int time, int ns, int nt, char *out, size_t cap) {
    setup = setup < 0 ? 0 : setup;
    time = time < 0 ? 0 : time;
    if (setup >= ns)
        return vv_error_set(VV_ERR_INVALID, "channel %d asked, the container has %d setup%s", setup,
                            ns, ns == 1 ? "" : "s");
    if (time >= nt)
        return vv_error_set(VV_ERR_INVALID, "time step %d asked, the container has %d timepoint%s",
                            time, nt, nt == 1 ? "" : "s");
    if (!bdv_dir(path, "setup%d/timepoint%d", setup, time))
        return vv_error_set(VV_ERR_FORMAT, "no group setup%d/timepoint%d", setup, time);
    if ((size_t)snprintf(out, cap, "%s/setup%d/timepoint%d", path, setup, time) >= cap)
        return vv_error_set(VV_ERR_LIMIT, "path too long");
    return VV_OK;
}

/* @p info's counts and name for a bdv.n5 setup. */
static void
bdv_n5_info(vv_load_info *info, int setup, int ns, int nt) {
    if (!info)
        return;
    info->n_channels = ns;
    info->n_times = nt;
    if (!info->channel_name[0])
        snprintf(info->channel_name, sizeof info->channel_name, "setup%d", setup < 0 ? 0 : setup);
}

static vv_status
n5_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    int ns, nt;
    if (!bdv_n5_layout(path, &ns, &nt))
        return vv_n5_read(out, path, opt);
    char group[4200];
    vv_status s = bdv_n5_group(path, opt->channel, opt->time, ns, nt, group, sizeof group);
    if (s != VV_OK)
        return vv_error_prefix(s, "n5: %s", vv_path_basename(path));
    vv_load_options one = *opt;
    one.channel = 0;
    one.time = 0;
    if ((s = vv_n5_read(out, group, &one)) == VV_OK)
        bdv_n5_info(opt->info, opt->channel, ns, nt);
    return s;
}

static vv_status
n5_open_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    int ns, nt;
    if (!bdv_n5_layout(path, &ns, &nt))
        return vv_zr_pyramid_store(st, path, channel, time, info);
    memset(st, 0, sizeof *st);
    char group[4200];
    vv_status s = bdv_n5_group(path, channel, time, ns, nt, group, sizeof group);
    if (s == VV_OK)
        s = vv_zr_pyramid_store(st, group, 0, 0, info);
    if (s != VV_OK)
        return s;
    st->n_channels = ns;
    st->n_times = nt;
    bdv_n5_info(info, channel, ns, nt);
    return VV_OK;
}

static vv_status
n5_open_store_channels(vv_store *st, const char *path, int n, const int *channels, int time,
                       vv_load_info *info) {
    int ns, nt;
    if (!bdv_n5_layout(path, &ns, &nt))
        return vv_zr_pyramid_store_channels(st, path, n, channels, time, info);
    if (n < 1 || n > VV_STORE_MAX_CHANNELS)
        return vv_error_set(VV_ERR_INVALID, "%d channels asked (1 .. %d)", n,
                            VV_STORE_MAX_CHANNELS);
    /* each setup its own store, stacked (as BigDataViewer's HDF5 setups) */
    vv_store parts[VV_STORE_MAX_CHANNELS];
    memset(parts, 0, sizeof parts);
    vv_status s = VV_OK;
    int k = 0;
    for (; k < n && s == VV_OK; k++) {
        vv_load_info one;
        memset(&one, 0, sizeof one);
        s = n5_open_store(&parts[k], path, channels[k], time, info ? &info[k] : &one);
        if (s != VV_OK)
            s = vv_error_prefix(s, "setup%d", channels[k]);
    }
    if (s == VV_OK)
        return vv_store_stack(st, parts, n);
    for (int i = 0; i < k; i++)
        vv_store_close(&parts[i]);
    return s;
}

vv_status
vv_n5_bdv_store(vv_store *st, const char *path, int setup, int timepoint) {
    memset(st, 0, sizeof *st);
    char group[4200];
    if (!bdv_dir(path, "setup%d/timepoint%d", setup, timepoint))
        return vv_error_set(VV_ERR_FORMAT, "no group setup%d/timepoint%d", setup, timepoint);
    if ((size_t)snprintf(group, sizeof group, "%s/setup%d/timepoint%d", path, setup, timepoint) >=
        sizeof group)
        return vv_error_set(VV_ERR_LIMIT, "path too long");
    vv_status s = vv_zr_pyramid_store(st, group, 0, 0, NULL);
    if (s != VV_OK)
        return s;
    /* in level 0's voxels: its spacing and origin divided out */
    double sp0[3], o0[3];
    for (int k = 0; k < 3; k++) {
        sp0[k] = st->lv[0].hdr->spacing[k] > 0 ? st->lv[0].hdr->spacing[k] : 1;
        o0[k] = st->lv[0].hdr->origin[k];
    }
    for (int l = 0; l < st->n_levels; l++) {
        vv_volume *h = st->lv[l].hdr;
        for (int k = 0; k < 3; k++) {
            h->origin[k] = (h->origin[k] - o0[k]) / sp0[k];
            h->spacing[k] /= sp0[k];
        }
        for (int k = 0; k < 9; k++)
            h->direction[k] = k % 4 == 0;
        h->unit = VV_UNIT_UNKNOWN;
    }
    return VV_OK;
}

static const char *const n5_extensions[] = {"n5", NULL};

const vv_format_record vv_format_n5 = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "n5",
    .title = "N5",
    .extensions = n5_extensions,
    .doc = "N5 (a folder or a URL): a dataset (attributes.json: dimensions, blockSize, dataType "
           "uint8 .. uint64, int8 .. int64, float32, float64; compression raw, gzip, bzip2, xz, "
           "blosc, zstd; default and varlength blocks) or a multiscale group of datasets s0 .. sN "
           "(downsamplingFactors or scales, resolution or pixelResolution, axes, units; COSEM "
           "multiscales), read like OME-Zarr: one level, channel and time step whole, or out of "
           "core by level of detail; a BigDataViewer N5 container (setupS/timepointT groups) "
           "its setups as channels and its timepoints as time steps",
    .flags = VV_FORMAT_FLAG_FOLDER | VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = vv_n5_looks_like,
    .read = n5_read_record,
    .open_store = n5_open_store,
    .open_store_channels = n5_open_store_channels,
};
