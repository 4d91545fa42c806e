/*
 * Neuroglancer precomputed volumes (github.com/google/neuroglancer,
 * src/datasource/precomputed/volume.md), read through the Zarr reader's
 * zr_array (zarr.h) as N5 is (n5.c).
 *
 * A volume is a folder (or a URL) whose `info` JSON names its type
 * ("image" or "segmentation"), data_type (uint8, int8, uint16, int16,
 * uint32, int32, uint64, float32), num_channels and scales, finest first:
 * each a key (the folder of its chunks beneath the volume), size and
 * voxel_offset (voxels, x, y, z), resolution (nanometres a voxel),
 * chunk_sizes (the first is read) and encoding. A chunk of a scale is the
 * file "x0-x1_y0-y1_z0-z1" of its key (voxel_offset-based voxel ranges,
 * cut at the scale's end); its voxels are x fastest, then y, z and the
 * channel, little-endian: the array's axes are c, z, y, x (C order).
 *
 * Encodings read: raw (the voxels, or a gzip stream of them, as servers and
 * cloud-volume store them compressed), jpeg (uint8, 1 or 3 channels: an
 * image of x by y * z pixels, decoded by libturbojpeg). compressed_segmentation
 * and sharded scales (neuroglancer_uint64_sharded_v1) are refused by name.
 *
 * The info is read as the OME-NGFF multiscales it amounts to
 * (zr_pc_root): a level's spacing is its resolution in nanometres, its
 * origin the centre of its first voxel ((voxel_offset + 1/2) resolution,
 * less half a level-0 voxel, so that level 0's origin is voxel_offset
 * times its resolution, as a volume's origin is its first voxel's centre);
 * a segmentation is a label image (its ids in label colours, 0 clear).
 */
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <turbojpeg.h>

#include "core/internal.h"
#include "io/store/pyramid.h"
#include "io/store/zarr.h"

/* the most scales an info may list, channels it may name */
#define PC_MAX_SCALES 32
#define PC_MAX_CHANNELS 1024

/* @p n integers of JSON array @p j into @p out, each in [lo, hi]. */
static int
ints_of(json_t *j, int n, int64_t *out, int64_t lo, int64_t hi) {
    if (!json_is_array(j) || (int)json_array_size(j) != n)
        return 0;
    for (int i = 0; i < n; i++) {
        json_t *x = json_array_get(j, (size_t)i);
        if (!json_is_integer(x) || json_integer_value(x) < lo || json_integer_value(x) > hi)
            return 0;
        out[i] = json_integer_value(x);
    }
    return 1;
}

/* The three finite positive numbers of JSON array @p j into @p out. */
static int
res_of(json_t *j, double *out) {
    if (!json_is_array(j) || json_array_size(j) != 3)
        return 0;
    for (int i = 0; i < 3; i++) {
        json_t *x = json_array_get(j, (size_t)i);
        out[i] = json_number_value(x);
        if (!json_is_number(x) || !isfinite(out[i]) || out[i] <= 0 || out[i] > 1e15)
            return 0;
    }
    return 1;
}

/* Scale @p i of the info @p info checked: its key, size, voxel_offset,
 * resolution; errors name the scale and the field. */
static vv_status
scale_of(json_t *info, int i, const char **key, int64_t size[3], int64_t off[3], double res[3]) {
    json_t *sc = json_array_get(json_object_get(info, "scales"), (size_t)i);
    *key = json_string_value(json_object_get(sc, "key"));
    if (!json_is_object(sc))
        return vv_error_set(VV_ERR_FORMAT, "info: scale %d is not an object", i);
    if (!*key || !**key)
        return vv_error_set(VV_ERR_FORMAT, "info: scale %d has no key", i);
    if (!ints_of(json_object_get(sc, "size"), 3, size, 1, (int64_t)1 << 40))
        return vv_error_set(VV_ERR_FORMAT, "info: scale %d: size is not 3 sizes (1 .. 2^40)", i);
    json_t *vo = json_object_get(sc, "voxel_offset");
    if (!vo)
        off[0] = off[1] = off[2] = 0;
    else if (!ints_of(vo, 3, off, -((int64_t)1 << 40), (int64_t)1 << 40))
        return vv_error_set(VV_ERR_FORMAT,
                            "info: scale %d: voxel_offset is not 3 integers (|v| <= 2^40)", i);
    if (!res_of(json_object_get(sc, "resolution"), res))
        return vv_error_set(VV_ERR_FORMAT, "info: scale %d: resolution is not 3 positive numbers",
                            i);
    return VV_OK;
}

/* ---- the info as OME-NGFF multiscales --------------------------------------- */

vv_status
zr_pc_root(const zr_array *a, void *info_v, void **za_out) {
    (void)a;
    json_t *info = info_v;
    *za_out = NULL;
    json_t *scales = json_object_get(info, "scales");
    const int n = json_is_array(scales) ? (int)json_array_size(scales) : 0;
    if (n < 1)
        return vv_error_set(VV_ERR_FORMAT, "info: no scales (not a precomputed volume)");
    if (n > PC_MAX_SCALES)
        return vv_error_set(VV_ERR_LIMIT, "info: %d scales (at most %d)", n, PC_MAX_SCALES);
    const char *type = json_string_value(json_object_get(info, "type"));
    if (type && strcmp(type, "image") && strcmp(type, "segmentation"))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "info: type \"%.40s\" (an image or a segmentation is read)", type);
    double r0[3] = {1, 1, 1};
    json_t *dsl = json_array();
    vv_status s = VV_OK;
    for (int i = 0; i < n && s == VV_OK; i++) {
        const char *key;
        int64_t size[3], off[3];
        double res[3];
        if ((s = scale_of(info, i, &key, size, off, res)) != VV_OK)
            break;
        if (i == 0)
            memcpy(r0, res, sizeof r0);
        /* axes c, z, y, x */
        json_t *sc = json_pack("[f,f,f,f]", 1.0, res[2], res[1], res[0]);
        json_t *tr = json_array();
        json_array_append_new(tr, json_real(0.0));
        for (int k = 2; k >= 0; k--)
            json_array_append_new(tr, json_real(((double)off[k] + 0.5) * res[k] - 0.5 * r0[k]));
        json_array_append_new(dsl, json_pack("{s:s,s:[{s:s,s:o},{s:s,s:o}]}", "path", key,
                                             "coordinateTransformations", "type", "scale", "scale",
                                             sc, "type", "translation", "translation", tr));
    }
    if (s != VV_OK) {
        json_decref(dsl);
        return s;
    }
    json_t *axes =
        json_pack("[{s:s,s:s},{s:s,s:s,s:s},{s:s,s:s,s:s},{s:s,s:s,s:s}]", "name", "c", "type",
                  "channel", "name", "z", "type", "space", "unit", "nanometer", "name", "y", "type",
                  "space", "unit", "nanometer", "name", "x", "type", "space", "unit", "nanometer");
    json_t *za = json_pack("{s:[{s:o,s:o}]}", "multiscales", "axes", axes, "datasets", dsl);
    if (type && !strcmp(type, "segmentation"))
        json_object_set_new(za, "image-label", json_object());
    *za_out = za;
    return VV_OK;
}

/* ---- one scale as an array ---------------------------------------------------- */

static const struct {
    const char *name;
    vv_voxel_type type;
    int conv64;
} pc_types[] = {{"uint8", VV_U8, 0},    {"int8", VV_I8, 0},    {"uint16", VV_U16, 0},
                {"int16", VV_I16, 0},   {"uint32", VV_U32, 0}, {"int32", VV_I32, 0},
                {"float32", VV_F32, 0}, {"uint64", VV_F64, 2}};

vv_status
zr_pc_parse_array(zr_array *a, void *info_v) {
    json_t *info = info_v;
    a->zarr_format = ZR_PRECOMPUTED;
    a->nshard = 0;
    a->conv64 = 0;
    a->fill = 0;
    a->sep = '/';
    a->codec[0] = '\0';
    json_t *scales = json_object_get(info, "scales");
    int i = 0;
    const int n = json_is_array(scales) ? (int)json_array_size(scales) : 0;
    for (; i < n; i++) {
        const char *k =
            json_string_value(json_object_get(json_array_get(scales, (size_t)i), "key"));
        if (k && !strcmp(k, a->prefix))
            break;
    }
    if (i == n)
        return vv_error_set(VV_ERR_FORMAT, "info: no scale of key \"%.200s\"", a->prefix);
    const char *key;
    int64_t size[3], off[3], cs[3], nch = 0;
    double res[3];
    vv_status s = scale_of(info, i, &key, size, off, res);
    if (s != VV_OK)
        return s;
    json_t *sc = json_array_get(scales, (size_t)i);
    if (!ints_of(json_array_get(json_object_get(sc, "chunk_sizes"), 0), 3, cs, 1, 1 << 16))
        return vv_error_set(VV_ERR_FORMAT,
                            "info: scale %d: chunk_sizes[0] is not 3 sizes (1 .. 65536)", i);
    json_t *nc = json_object_get(info, "num_channels");
    nch = 1;
    if (nc && (!json_is_integer(nc) || json_integer_value(nc) < 1 ||
               json_integer_value(nc) > PC_MAX_CHANNELS))
        return vv_error_set(VV_ERR_FORMAT, "info: num_channels is not 1 .. %d", PC_MAX_CHANNELS);
    if (nc)
        nch = json_integer_value(nc);
    const char *dt = json_string_value(json_object_get(info, "data_type"));
    size_t m = 0;
    while (dt && m < sizeof pc_types / sizeof pc_types[0] && strcmp(dt, pc_types[m].name))
        m++;
    if (!dt || m == sizeof pc_types / sizeof pc_types[0])
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "info: data_type \"%.40s\" (supported: uint8, int8, uint16, int16, "
                            "uint32, int32, uint64, float32)",
                            dt ? dt : "(none)");
    a->type = pc_types[m].type;
    a->conv64 = pc_types[m].conv64;
    a->esize = vv_voxel_type_size(a->type);
    a->swap = a->esize > 1 && !vv_host_is_little_endian();
    const char *enc = json_string_value(json_object_get(sc, "encoding"));
    if (json_object_get(sc, "sharding"))
        return vv_error_set(
            VV_ERR_UNSUPPORTED,
            "info: scale %d (\"%.100s\") is sharded (neuroglancer_uint64_sharded_v1 "
            "is not read yet)",
            i, key);
    if (!enc || (strcmp(enc, "raw") && strcmp(enc, "jpeg")))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "info: scale %d: encoding \"%.40s\" (raw and jpeg are read; "
                            "compressed_segmentation is not yet)",
                            i, enc ? enc : "(none)");
    if (!strcmp(enc, "jpeg") && (a->type != VV_U8 || (nch != 1 && nch != 3)))
        return vv_error_set(VV_ERR_FORMAT,
                            "info: scale %d: jpeg holds uint8 of 1 or 3 channels, not %s of %lld",
                            i, dt, (long long)nch);
    snprintf(a->codec, sizeof a->codec, "%s", enc);
    a->ndim = 4; /* c, z, y, x */
    a->shape[0] = (uint64_t)nch;
    a->chunks[0] = (uint64_t)nch;
    for (int k = 0; k < 3; k++) {
        a->shape[3 - k] = (uint64_t)size[k];
        a->chunks[3 - k] = (uint64_t)cs[k];
        a->pc_off[k] = off[k];
    }
    return VV_OK;
}

void
zr_pc_key(const zr_array *a, const uint64_t *idx, char *key, size_t cap) {
    int len = snprintf(key, cap, "%s/", a->prefix);
    for (int k = 0; k < 3 && len >= 0 && len < (int)cap; k++) { /* x, y, z */
        const int ax = 3 - k;
        const int64_t b = a->pc_off[k] + (int64_t)(idx[ax] * a->chunks[ax]);
        const int64_t end = a->pc_off[k] + (int64_t)a->shape[ax];
        const int64_t e = b + (int64_t)a->chunks[ax] < end ? b + (int64_t)a->chunks[ax] : end;
        len += snprintf(key + len, cap - (size_t)len, "%s%lld-%lld", k ? "_" : "", (long long)b,
                        (long long)e);
    }
}

/* ---- chunks ---------------------------------------------------------------------- */

/* A jpeg chunk of @p cut voxels (c, z, y, x) decoded into @p out (channels
 * one after another). */
static vv_status
pc_jpeg(const uint64_t cut[4], const unsigned char *src, size_t m, unsigned char *out,
        const char *what) {
    tjhandle h = tjInitDecompress();
    if (!h)
        return vv_error_set(VV_ERR_NOMEM, "%s: no jpeg decoder", what);
    int w = 0, ht = 0, sub = 0, cs = 0;
    vv_status s = VV_OK;
    const uint64_t want_w = cut[3], want_h = cut[2] * cut[1], nch = cut[0];
    if (m > (size_t)1 << 31 || tjDecompressHeader3(h, src, (unsigned long)m, &w, &ht, &sub, &cs))
        s = vv_error_set(VV_ERR_FORMAT, "%s: not a jpeg image (%s)", what, tjGetErrorStr2(h));
    else if ((uint64_t)w != want_w || (uint64_t)ht != want_h)
        s = vv_error_set(VV_ERR_FORMAT, "%s: a jpeg of %d x %d pixels, the chunk's is %llu x %llu",
                         what, w, ht, (unsigned long long)want_w, (unsigned long long)want_h);
    const size_t px = (size_t)want_w * (size_t)want_h;
    unsigned char *rgb = s == VV_OK && nch == 3 ? malloc(px * 3) : NULL;
    if (s == VV_OK && nch == 3 && !rgb)
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", what);
    if (s == VV_OK && tjDecompress2(h, src, (unsigned long)m, nch == 3 ? rgb : out, w, 0, ht,
                                    nch == 3 ? TJPF_RGB : TJPF_GRAY, TJFLAG_ACCURATEDCT) != 0)
        s = vv_error_set(VV_ERR_FORMAT, "%s: the jpeg does not decode (%s)", what,
                         tjGetErrorStr2(h));
    if (s == VV_OK && rgb) /* interleaved to one channel after another */
        for (size_t i = 0; i < px; i++)
            for (int c = 0; c < 3; c++)
                out[(size_t)c * px + i] = rgb[3 * i + (size_t)c];
    free(rgb);
    tjDestroy(h);
    return s;
}

/* A raw chunk's @p bytes from @p src (@p m bytes: the voxels, or a gzip
 * stream of them). */
static vv_status
pc_raw(const unsigned char *src, size_t m, unsigned char *out, size_t bytes, const char *what) {
    if (m == bytes) {
        memcpy(out, src, bytes);
        return VV_OK;
    }
    if (m >= 2 && src[0] == 0x1f && src[1] == 0x8b) {
        if (zr_gunzip(src, m, out, bytes))
            return VV_OK;
        return vv_error_set(VV_ERR_FORMAT, "%s: the gzip stream does not decode to %zu bytes", what,
                            bytes);
    }
    return vv_error_set(VV_ERR_FORMAT, "%s: %zu bytes, a raw chunk of its size has %zu", what, m,
                        bytes);
}

vv_status
zr_pc_decode(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], const unsigned char *src, size_t m,
             unsigned char *out, size_t n, const char *what) {
    uint64_t cut[4], elems = 1;
    int whole = 1;
    for (int i = 0; i < 4; i++) {
        const uint64_t b = idx[i] * a->chunks[i];
        cut[i] = b >= a->shape[i]                 ? 0
                 : a->shape[i] - b < a->chunks[i] ? a->shape[i] - b
                                                  : a->chunks[i];
        whole &= cut[i] == a->chunks[i];
        elems *= cut[i];
    }
    const size_t bytes = (size_t)elems * a->esize;
    if (!elems || bytes > n)
        return vv_error_set(VV_ERR_FORMAT, "%s: a chunk outside the scale", what);
    unsigned char *dst = whole ? out : malloc(bytes);
    if (!dst)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory for %zu bytes", what, bytes);
    vv_status s = !strcmp(a->codec, "jpeg") ? pc_jpeg(cut, src, m, dst, what)
                                            : pc_raw(src, m, dst, bytes, what);
    if (s == VV_OK && !whole)
        zr_place_cut(a, cut, dst, out, n);
    if (!whole)
        free(dst);
    return s;
}

/* ---- the format row -------------------------------------------------------------- */

int
vv_pc_looks_like(const vv_format_probe *p, int deep) {
    char head[8193];
    if (!p->is_dir || deep || !zr_file_head(p->path, "info", head, sizeof head))
        return 0;
    return strstr(head, "neuroglancer_multiscale_volume") != NULL ||
           (strstr(head, "\"scales\"") && strstr(head, "\"data_type\""));
}

static const char *const pc_extensions[] = {NULL};

const vv_format_record vv_format_precomputed = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "precomputed",
    .title = "Neuroglancer precomputed",
    .extensions = pc_extensions,
    .doc = "Neuroglancer precomputed (a folder or a URL with an info file): its scales as "
           "levels (resolution in nm, voxel_offset), num_channels as channels, segmentations as "
           "label images; raw (also gzip) and jpeg chunks, unsharded; read like OME-Zarr: one "
           "level whole, or out of core by level of detail",
    .flags = VV_FORMAT_FLAG_FOLDER | VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = vv_pc_looks_like,
    .read = vv_pc_read,
    .open_store = vv_zr_pyramid_store,
    .open_store_channels = vv_zr_pyramid_store_channels,
};
