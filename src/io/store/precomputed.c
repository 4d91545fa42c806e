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
 * image of x by y * z pixels, decoded by libturbojpeg), compressed_segmentation
 * (uint32 or uint64 ids, src/sliceview/compressed_segmentation/README.md: per
 * channel a 32-bit word offset, then a grid of blocks of
 * compressed_segmentation_block_size, each a 64-bit header -- its lookup
 * table's offset (24 bits, in 32-bit words), its bits a value (0, 1, 2, 4,
 * 8, 16 or 32), its packed values' offset (32 bits) -- the values packed
 * x fastest into little-endian 32-bit words, each an index into the
 * block's table of ids).
 *
 * A sharded scale (neuroglancer_uint64_sharded_v1, src/datasource/
 * precomputed/sharded.md) keeps its chunks in 2^shard_bits files
 * "KEY/<shard in hex>.shard". A chunk's id is the compressed Morton code of
 * its grid position (x's bit 0, y's, z's, then bit 1 of each, skipping the
 * bits no grid position has); hashed (identity, or murmurhash3_x86_128 of
 * the id shifted right by preshift_bits as 8 little-endian bytes, its low
 * 8 bytes), bits [0, minishard_bits) are its minishard, the next
 * shard_bits its shard. A shard begins with its index: (start, end) of
 * each minishard's index, 16 bytes each; a minishard index (raw or gzip)
 * is 3 x n little-endian numbers: the chunk ids, delta encoded; each
 * chunk's start, delta encoded from the previous chunk's end; the sizes.
 * Offsets count from the shard index's end. Both indexes are read by byte
 * ranges and kept in the array's index cache (zarr3.c); a chunk's bytes
 * (raw or gzip data_encoding) are one more range.
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
#include <zlib.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/pyramid.h"
#include "io/store/zarr.h"

/* the most scales an info may list, channels it may name */
#define PC_MAX_SCALES 32
#define PC_MAX_CHANNELS 1024
/* sharding: the most minishard bits (a shard index of 64 MiB), the bytes
 * a minishard index may hold decoded, the offsets a shard may reach */
#define PC_MAX_MINISHARD_BITS 22
#define PC_MAX_MINISHARD_INDEX ((size_t)64 << 20)
#define PC_MAX_OFFSET ((uint64_t)1 << 62)

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

/* The bits a grid of @p n cells along an axis gives the compressed Morton
 * code: those some position has set (2^b < n). */
static int
morton_bits(uint64_t n) {
    int b = 0;
    while (b < 63 && ((uint64_t)1 << b) < n)
        b++;
    return b;
}

/* The "sharding" of scale @p i (@p size voxels in chunks of @p cs) into
 * @p a. */
static vv_status
sharding_of(zr_array *a, json_t *sh, int i, const int64_t size[3], const int64_t cs[3]) {
    const char *t = json_string_value(json_object_get(sh, "@type"));
    if (!json_is_object(sh) || !t || strcmp(t, "neuroglancer_uint64_sharded_v1"))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "info: scale %d: sharding \"%.60s\" (neuroglancer_uint64_sharded_v1 "
                            "is read)",
                            i, t ? t : "(no @type)");
    static const char *const bits[] = {"preshift_bits", "minishard_bits", "shard_bits"};
    int v[3];
    for (int k = 0; k < 3; k++) {
        json_t *b = json_object_get(sh, bits[k]);
        if (!json_is_integer(b) || json_integer_value(b) < 0 || json_integer_value(b) > 64)
            return vv_error_set(VV_ERR_FORMAT, "info: scale %d: sharding %s is not 0 .. 64", i,
                                bits[k]);
        v[k] = (int)json_integer_value(b);
    }
    if (v[1] + v[2] > 64)
        return vv_error_set(VV_ERR_FORMAT,
                            "info: scale %d: sharding minishard_bits + shard_bits = %d, over 64", i,
                            v[1] + v[2]);
    if (v[1] > PC_MAX_MINISHARD_BITS)
        return vv_error_set(VV_ERR_LIMIT,
                            "info: scale %d: sharding minishard_bits %d (a shard index of "
                            "%llu MiB; at most %d bits are read)",
                            i, v[1], (unsigned long long)((16ull << v[1]) >> 20),
                            PC_MAX_MINISHARD_BITS);
    const char *h = json_string_value(json_object_get(sh, "hash"));
    if (!h || (strcmp(h, "identity") && strcmp(h, "murmurhash3_x86_128")))
        return vv_error_set(VV_ERR_FORMAT,
                            "info: scale %d: sharding hash \"%.40s\" (identity or "
                            "murmurhash3_x86_128)",
                            i, h ? h : "(none)");
    static const char *const encs[] = {"minishard_index_encoding", "data_encoding"};
    int gz[2];
    for (int k = 0; k < 2; k++) {
        json_t *e = json_object_get(sh, encs[k]);
        const char *es = json_string_value(e);
        if (e && (!es || (strcmp(es, "raw") && strcmp(es, "gzip"))))
            return vv_error_set(VV_ERR_FORMAT,
                                "info: scale %d: sharding %s \"%.40s\" (raw or gzip)", i, encs[k],
                                es ? es : "(not a string)");
        gz[k] = es && !strcmp(es, "gzip");
    }
    int total = 0;
    for (int k = 0; k < 3; k++)
        total += a->pc_zbits[k] =
            morton_bits(((uint64_t)size[k] + (uint64_t)cs[k] - 1) / (uint64_t)cs[k]);
    if (total > 64)
        return vv_error_set(VV_ERR_FORMAT,
                            "info: scale %d: a chunk grid whose Morton code needs %d bits", i,
                            total);
    a->pc_preshift = v[0];
    a->pc_mbits = v[1];
    a->pc_sbits = v[2];
    a->pc_murmur = !strcmp(h, "murmurhash3_x86_128");
    a->pc_index_gzip = gz[0];
    a->pc_data_gzip = gz[1];
    if (!a->cache && !(a->cache = zr_index_cache_new()))
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a shard index cache");
    a->pc_shard = 1;
    return VV_OK;
}

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
    a->pc_shard = 0;
    json_t *sh = json_object_get(sc, "sharding");
    if (sh && !json_is_null(sh) && (s = sharding_of(a, sh, i, size, cs)) != VV_OK)
        return s;
    if (!enc ||
        (strcmp(enc, "raw") && strcmp(enc, "jpeg") && strcmp(enc, "compressed_segmentation")))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "info: scale %d: encoding \"%.40s\" (raw, jpeg and "
                            "compressed_segmentation are read)",
                            i, enc ? enc : "(none)");
    if (!strcmp(enc, "compressed_segmentation")) {
        int64_t bs[3];
        if (a->type != VV_U32 && !(a->type == VV_F64 && a->conv64 == 2))
            return vv_error_set(VV_ERR_FORMAT,
                                "info: scale %d: compressed_segmentation holds uint32 or uint64, "
                                "not %s",
                                i, dt);
        if (!ints_of(json_object_get(sc, "compressed_segmentation_block_size"), 3, bs, 1, 1 << 16))
            return vv_error_set(VV_ERR_FORMAT,
                                "info: scale %d: compressed_segmentation_block_size is not 3 "
                                "sizes (1 .. 65536)",
                                i);
        for (int k = 0; k < 3; k++)
            a->pc_block[k] = (int)bs[k];
        enc = "cseg";
    }
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

/* ---- sharding ------------------------------------------------------------------- */

static uint64_t
low_mask(int bits) {
    return bits >= 64 ? UINT64_MAX : ((uint64_t)1 << bits) - 1;
}

static uint32_t
rotl32(uint32_t x, int r) {
    return (x << r) | (x >> (32 - r));
}

static uint32_t
fmix32(uint32_t h) {
    h ^= h >> 16;
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    h ^= h >> 16;
    return h;
}

/* MurmurHash3_x86_128 (Austin Appleby's, seed 0) of the 8 little-endian
 * bytes of @p key: the low 8 bytes of the hash, little-endian. */
static uint64_t
murmur3_x86_128_low(uint64_t key) {
    uint32_t h1 = 0, h2 = 0, h3 = 0, h4 = 0;
    uint32_t k1 = (uint32_t)key, k2 = (uint32_t)(key >> 32);
    k2 *= 0xab0e9789u; /* the 8-byte tail: bytes 4..7, then 0..3 */
    k2 = rotl32(k2, 16);
    k2 *= 0x38b34ae5u;
    h2 ^= k2;
    k1 *= 0x239b961bu;
    k1 = rotl32(k1, 15);
    k1 *= 0xab0e9789u;
    h1 ^= k1;
    h1 ^= 8;
    h2 ^= 8;
    h3 ^= 8;
    h4 ^= 8;
    h1 += h2 + h3 + h4;
    h2 += h1;
    h3 += h1;
    h4 += h1;
    h1 = fmix32(h1);
    h2 = fmix32(h2);
    h3 = fmix32(h3);
    h4 = fmix32(h4);
    h1 += h2 + h3 + h4;
    h2 += h1;
    return (uint64_t)h1 | (uint64_t)h2 << 32;
}

/* The compressed Morton code of the chunk at @p idx (c, z, y, x). */
static uint64_t
chunk_id(const zr_array *a, const uint64_t *idx) {
    const uint64_t g[3] = {idx[3], idx[2], idx[1]};
    uint64_t code = 0;
    int j = 0;
    for (int b = 0; b < 64; b++) {
        int any = 0;
        for (int d = 0; d < 3; d++)
            if (b < a->pc_zbits[d]) {
                code |= ((g[d] >> b) & 1) << j++;
                any = 1;
            }
        if (!any)
            break;
    }
    return code;
}

/* The hashed id of the chunk at @p idx: its minishard in the low bits. */
static uint64_t
hashed_id(const zr_array *a, const uint64_t *idx) {
    const uint64_t id = chunk_id(a, idx);
    const uint64_t x = a->pc_preshift >= 64 ? 0 : id >> a->pc_preshift;
    return a->pc_murmur ? murmur3_x86_128_low(x) : x;
}

uint64_t
zr_pc_shard_of(const zr_array *a, const uint64_t *idx) {
    const uint64_t h = hashed_id(a, idx);
    return a->pc_mbits >= 64 ? 0 : (h >> a->pc_mbits) & low_mask(a->pc_sbits);
}

/* A gzip stream of @p m bytes inflated into a new buffer *out of *n
 * bytes (at most @p cap). */
static vv_status
inflate_alloc(const unsigned char *src, size_t m, size_t cap, unsigned char **out, size_t *n,
              const char *what) {
    *out = NULL;
    *n = 0;
    if (m > UINT32_MAX)
        return vv_error_set(VV_ERR_LIMIT, "%s: a gzip stream of %zu bytes", what, m);
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit2(&z, 32 + MAX_WBITS) != Z_OK)
        return vv_error_set(VV_ERR_NOMEM, "%s: no gzip decoder", what);
    size_t have = m * 4 + 4096 < cap ? m * 4 + 4096 : cap + 1;
    unsigned char *buf = malloc(have);
    vv_status s = buf ? VV_OK : vv_error_set(VV_ERR_NOMEM, "%s: out of memory", what);
    z.next_in = (unsigned char *)src;
    z.avail_in = (uInt)m;
    size_t used = 0;
    while (s == VV_OK) {
        z.next_out = buf + used;
        z.avail_out = (uInt)(have - used < UINT32_MAX ? have - used : UINT32_MAX);
        const size_t before = z.avail_out;
        const int r = inflate(&z, Z_NO_FLUSH);
        used += before - z.avail_out;
        if (used > cap)
            s = vv_error_set(VV_ERR_FORMAT, "%s: the gzip stream decodes to more than %zu bytes",
                             what, cap);
        else if (r == Z_STREAM_END)
            break;
        else if (r != Z_OK && r != Z_BUF_ERROR)
            s = vv_error_set(VV_ERR_FORMAT, "%s: the gzip stream does not decode (%s)", what,
                             z.msg ? z.msg : "corrupt");
        else if (r == Z_BUF_ERROR && z.avail_in == 0)
            s = vv_error_set(VV_ERR_FORMAT, "%s: the gzip stream ends early", what);
        else if (used == have) {
            const size_t more = have * 2 < cap + 1 ? have * 2 : cap + 1;
            unsigned char *nb = more > have ? realloc(buf, more) : NULL;
            if (!nb)
                s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", what);
            else {
                buf = nb;
                have = more;
            }
        }
    }
    inflateEnd(&z);
    if (s != VV_OK) {
        free(buf);
        return s;
    }
    *out = buf;
    *n = used;
    return VV_OK;
}

/* Shard @p key's index (2^minishard_bits (start, end) pairs, @p raw) checked
 * into a new *ent: each ends at or after its start, below PC_MAX_OFFSET, no
 * two minishard indexes overlapping. */
static vv_status
parse_shard_index(const zr_array *a, const char *key, const unsigned char *raw,
                  uint64_t **ent_out) {
    const uint64_t count = (uint64_t)1 << a->pc_mbits;
    uint64_t *ent = malloc(count * 16), *sorted = malloc(count * 16);
    vv_status s = ent && sorted ? VV_OK : vv_error_set(VV_ERR_NOMEM, "%s: out of memory", key);
    for (uint64_t i = 0; s == VV_OK && i < count; i++) {
        ent[2 * i] = zr_le64(raw + 16 * i);
        ent[2 * i + 1] = zr_le64(raw + 16 * i + 8);
        if (ent[2 * i + 1] < ent[2 * i] || ent[2 * i + 1] > PC_MAX_OFFSET)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: shard index: minishard %llu's index at bytes %llu..%llu", key,
                             (unsigned long long)i, (unsigned long long)ent[2 * i],
                             (unsigned long long)ent[2 * i + 1]);
    }
    uint64_t ns = 0;
    for (uint64_t i = 0; s == VV_OK && i < count; i++)
        if (ent[2 * i + 1] > ent[2 * i]) {
            sorted[2 * ns] = ent[2 * i];
            sorted[2 * ns++ + 1] = ent[2 * i + 1];
        }
    if (s == VV_OK)
        qsort(sorted, (size_t)ns, 16, zr_cmp_range);
    for (uint64_t i = 1; s == VV_OK && i < ns; i++)
        if (sorted[2 * i] < sorted[2 * i - 1])
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: shard index: minishard indexes overlap at byte %llu", key,
                             (unsigned long long)sorted[2 * i]);
    free(sorted);
    if (s != VV_OK) {
        free(ent);
        return s;
    }
    *ent_out = ent;
    return VV_OK;
}

/* Minishard @p mini's index (@p m decoded bytes at @p raw, stored at shard
 * bytes [@p lo, @p hi)) into a new *ent of *count (chunk id, start, size),
 * sorted by id: ids rising, every chunk between the shard index's end and
 * PC_MAX_OFFSET, none overlapping the minishard index itself. */
static vv_status
parse_minishard(const zr_array *a, const char *key, uint64_t mini, const unsigned char *raw,
                size_t m, uint64_t lo, uint64_t hi, uint64_t **ent_out, uint64_t *count) {
    if (m % 24)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: minishard %llu's index has %zu bytes, not 24 a chunk", key,
                            (unsigned long long)mini, m);
    const uint64_t n = m / 24, ib = (uint64_t)16 << a->pc_mbits;
    uint64_t *ent = malloc((n ? n : 1) * 24);
    if (!ent)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", key);
    uint64_t id = 0, end = ib;
    for (uint64_t i = 0; i < n; i++) {
        const uint64_t did = zr_le64(raw + 8 * i), doff = zr_le64(raw + 8 * (n + i)),
                       size = zr_le64(raw + 8 * (2 * n + i));
        const uint64_t start = end + doff;
        if ((i && did == 0) || did > UINT64_MAX - id || doff > PC_MAX_OFFSET ||
            size > PC_MAX_OFFSET || start > PC_MAX_OFFSET - size ||
            (start < hi && start + size > lo)) {
            free(ent);
            return vv_error_set(VV_ERR_FORMAT, "%s: minishard %llu's index: chunk %llu (%s)", key,
                                (unsigned long long)mini, (unsigned long long)i,
                                i && did == 0           ? "the same id twice"
                                : did > UINT64_MAX - id ? "its id past 2^64"
                                : start < hi && start + size > lo && start <= PC_MAX_OFFSET - size
                                    ? "its bytes overlap the minishard index"
                                    : "its bytes past 2^62");
        }
        id += did;
        ent[3 * i] = id;
        ent[3 * i + 1] = start;
        ent[3 * i + 2] = size;
        end = start + size;
    }
    *ent_out = ent;
    *count = n;
    return VV_OK;
}

vv_status
zr_pc_locate(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], uint64_t *off, uint64_t *len,
             int *missing, uint64_t *file_bytes) {
    *missing = 0;
    const uint64_t h = hashed_id(a, idx), cid = chunk_id(a, idx);
    const uint64_t mini = h & low_mask(a->pc_mbits), shard = zr_pc_shard_of(a, idx);
    const uint64_t ib = (uint64_t)16 << a->pc_mbits;
    char key[2200];
    zr_pc_key(a, idx, key, sizeof key);
    uint64_t o[2], size = 0;
    vv_status s = VV_OK;
    if (!zr_index_cache_find(a->cache, 0, shard, mini, o, &size)) {
        unsigned char *raw = NULL;
        size_t m = 0;
        s = zr_store_get(a, key, 0, ib, ib, &raw, &m, NULL, missing);
        if (s != VV_OK || *missing)
            return s;
        if (file_bytes)
            *file_bytes += m;
        uint64_t *ent = NULL;
        s = m == ib ? parse_shard_index(a, key, raw, &ent)
                    : vv_error_set(VV_ERR_FORMAT, "%s: a shard of %zu bytes, its index has %llu",
                                   key, m, (unsigned long long)ib);
        free(raw);
        if (s != VV_OK)
            return s;
        o[0] = ent[2 * mini];
        o[1] = ent[2 * mini + 1];
        zr_index_cache_put(a->cache, 0, shard, ent, (uint64_t)1 << a->pc_mbits, 0, 2);
    }
    if (o[0] == o[1]) { /* an empty minishard */
        *missing = 1;
        return VV_OK;
    }
    const uint64_t mid = a->pc_mbits >= 64 ? mini : shard << a->pc_mbits | mini;
    uint64_t c[2];
    int r = zr_index_cache_search(a->cache, 1, mid, cid, c);
    if (r == 0) {
        const uint64_t lo = ib + o[0], hi = ib + o[1];
        if (o[1] - o[0] > PC_MAX_MINISHARD_INDEX)
            return vv_error_set(VV_ERR_LIMIT, "%s: minishard %llu's index of %llu bytes", key,
                                (unsigned long long)mini, (unsigned long long)(o[1] - o[0]));
        unsigned char *raw = NULL, *dec = NULL;
        size_t m = 0, dm = 0;
        s = zr_store_get(a, key, lo, hi - lo, hi - lo, &raw, &m, NULL, NULL);
        if (s != VV_OK)
            return s;
        if (file_bytes)
            *file_bytes += m;
        char what[2300];
        snprintf(what, sizeof what, "%s: minishard %llu's index", key, (unsigned long long)mini);
        if (a->pc_index_gzip)
            s = inflate_alloc(raw, m, PC_MAX_MINISHARD_INDEX, &dec, &dm, what);
        uint64_t *ent = NULL, n = 0;
        if (s == VV_OK)
            s = parse_minishard(a, key, mini, dec ? dec : raw, dec ? dm : m, lo, hi, &ent, &n);
        free(raw);
        free(dec);
        if (s != VV_OK)
            return s;
        r = -1;
        for (uint64_t i = 0; i < n; i++) /* ids rise: the one asked, or none */
            if (ent[3 * i] == cid) {
                c[0] = ent[3 * i + 1];
                c[1] = ent[3 * i + 2];
                r = 1;
                break;
            }
        zr_index_cache_put(a->cache, 1, mid, ent, n, 0, 3);
    }
    if (r < 0) {
        *missing = 1;
        return VV_OK;
    }
    *off = c[0];
    *len = c[1];
    return VV_OK;
}

static int
cmp_u64(const void *x, const void *y) {
    const uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return a < b ? -1 : a > b;
}

/* The @p n distinct sorted numbers of @p v (n of them) kept at its start:
 * their count. */
static uint64_t
unique(uint64_t *v, uint64_t n) {
    qsort(v, (size_t)n, sizeof *v, cmp_u64);
    uint64_t k = 0;
    for (uint64_t i = 0; i < n; i++)
        if (!k || v[i] != v[k - 1])
            v[k++] = v[i];
    return k;
}

/* Reads @p n objects' ranges @p g (keys, offsets and lengths set) a
 * window of requests in flight at a time; each @p done(u, g) after its
 * window came back (its buffer then freed). */
static vv_status
get_windows(const zr_array *a, bs_get *g, uint64_t n,
            vv_status (*done)(const zr_array *a, bs_get *g, void *u), void *u) {
    const int window = bs_http_in_flight() > 0 ? bs_http_in_flight() : 1;
    vv_status s = VV_OK;
    for (uint64_t k = 0; s == VV_OK && k < n; k += (uint64_t)window) {
        const int w = n - k < (uint64_t)window ? (int)(n - k) : window;
        s = zr_store_get_many(a, g + k, w);
        for (int i = 0; i < w; i++) {
            if (s == VV_OK)
                s = done(a, &g[k + (uint64_t)i], u);
            free(g[k + (uint64_t)i].out);
            g[k + (uint64_t)i].out = NULL;
        }
    }
    return s;
}

/* The reads of zr_pc_locate_many's indexes: g[i] that of number num[i]
 * (a shard, or a minishard as shard << minishard_bits | minishard). */
typedef struct pc_batch {
    bs_get *g;
    uint64_t *num;
} pc_batch;

/* A shard index read by get_windows: kept (an absent shard as one of
 * empty minishards). */
static vv_status
shard_index_done(const zr_array *a, bs_get *g, void *u) {
    const pc_batch *b = u;
    const uint64_t count = (uint64_t)1 << a->pc_mbits, id = b->num[g - b->g];
    uint64_t *ent = NULL;
    vv_status s = VV_OK;
    if (g->missing)
        s = (ent = calloc((size_t)count, 16)) ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    else if (g->n != count * 16)
        s = vv_error_set(VV_ERR_FORMAT, "%s: a shard of %zu bytes, its index has %llu", g->key,
                         g->n, (unsigned long long)(count * 16));
    else
        s = parse_shard_index(a, g->key, g->out, &ent);
    if (s == VV_OK)
        zr_index_cache_put(a->cache, 0, id, ent, count, 0, 2);
    return s;
}

/* A minishard index read by get_windows: kept. */
static vv_status
minishard_done(const zr_array *a, bs_get *g, void *u) {
    const pc_batch *b = u;
    const uint64_t m = b->num[g - b->g];
    const uint64_t mini = m & low_mask(a->pc_mbits);
    char what[2300];
    snprintf(what, sizeof what, "%s: minishard %llu's index", g->key, (unsigned long long)mini);
    unsigned char *dec = NULL;
    size_t dm = 0;
    vv_status s = a->pc_index_gzip
                      ? inflate_alloc(g->out, g->n, PC_MAX_MINISHARD_INDEX, &dec, &dm, what)
                      : VV_OK;
    uint64_t *ent = NULL, n = 0;
    if (s == VV_OK)
        s = parse_minishard(a, g->key, mini, dec ? dec : g->out, dec ? dm : g->n, g->off,
                            g->off + g->len, &ent, &n);
    free(dec);
    if (s == VV_OK)
        zr_index_cache_put(a->cache, 1, m, ent, n, 0, 3);
    return s;
}

vv_status
zr_pc_locate_many(const zr_array *a, uint64_t n, const uint64_t *idx, uint64_t *off, uint64_t *len,
                  unsigned char *missing) {
    const uint64_t ib = (uint64_t)16 << a->pc_mbits;
    uint64_t *list = malloc((size_t)(n ? n : 1) * sizeof *list);
    bs_get *g = calloc((size_t)(n ? n : 1), sizeof *g);
    pc_batch b = {g, list};
    char *keys = malloc((size_t)(n ? n : 1) * 2200);
    vv_status s = list && g && keys ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    /* the shard indexes not kept, read together */
    uint64_t k = 0, o[2], size;
    for (uint64_t i = 0; s == VV_OK && i < n; i++) {
        const uint64_t *x = idx + i * ZR_MAX_DIM, sh = zr_pc_shard_of(a, x);
        if (!zr_index_cache_find(a->cache, 0, sh, hashed_id(a, x) & low_mask(a->pc_mbits), o,
                                 &size))
            list[k++] = sh;
    }
    if (s == VV_OK && k) {
        k = unique(list, k);
        for (uint64_t i = 0; i < k; i++) {
            char *key = keys + i * 2200;
            snprintf(key, 2200, "%s/%0*llx.shard", a->prefix, (a->pc_sbits + 3) / 4,
                     (unsigned long long)list[i]);
            g[i] = (bs_get){.key = key, .off = 0, .len = ib, .max = ib};
        }
        s = get_windows(a, g, k, shard_index_done, &b);
    }
    /* the minishard indexes not kept, read together */
    k = 0;
    for (uint64_t i = 0; s == VV_OK && i < n; i++) {
        const uint64_t *x = idx + i * ZR_MAX_DIM, h = hashed_id(a, x);
        const uint64_t mini = h & low_mask(a->pc_mbits), sh = zr_pc_shard_of(a, x);
        uint64_t c[2];
        if (zr_index_cache_find(a->cache, 0, sh, mini, o, &size) && o[1] > o[0] &&
            o[1] - o[0] <= PC_MAX_MINISHARD_INDEX) {
            const uint64_t mid = a->pc_mbits >= 64 ? mini : sh << a->pc_mbits | mini;
            if (!zr_index_cache_search(a->cache, 1, mid, chunk_id(a, x), c))
                list[k++] = mid;
        }
    }
    if (s == VV_OK && k) {
        k = unique(list, k);
        for (uint64_t i = 0; i < k; i++) {
            const uint64_t mid = list[i], mini = mid & low_mask(a->pc_mbits);
            const uint64_t sh = a->pc_mbits >= 64 ? 0 : mid >> a->pc_mbits;
            char *key = keys + i * 2200;
            snprintf(key, 2200, "%s/%0*llx.shard", a->prefix, (a->pc_sbits + 3) / 4,
                     (unsigned long long)sh);
            if (!zr_index_cache_find(a->cache, 0, sh, mini, o, &size))
                o[0] = o[1] = 0; /* evicted meanwhile: zr_pc_locate reads it */
            g[i] = (bs_get){.key = key, .off = ib + o[0], .len = o[1] - o[0], .max = o[1] - o[0]};
        }
        uint64_t kk = 0; /* the evicted left out */
        for (uint64_t i = 0; i < k; i++)
            if (g[i].len) {
                g[kk] = g[i];
                list[kk++] = list[i];
            }
        s = get_windows(a, g, kk, minishard_done, &b);
    }
    /* each chunk from the indexes kept (one read for any evicted) */
    for (uint64_t i = 0; s == VV_OK && i < n; i++) {
        int miss = 0;
        s = zr_pc_locate(a, idx + i * ZR_MAX_DIM, &off[i], &len[i], &miss, NULL);
        missing[i] = (unsigned char)miss;
    }
    free(list);
    free(g);
    free(keys);
    return s;
}

vv_status
zr_pc_read_sharded(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], unsigned char *out, size_t n,
                   int *missing, uint64_t *file_bytes) {
    uint64_t off = 0, len = 0, ib = 0;
    *missing = 0;
    if (file_bytes)
        *file_bytes = 0;
    vv_status s = zr_pc_locate(a, idx, &off, &len, missing, file_bytes ? &ib : NULL);
    if (file_bytes)
        *file_bytes = ib;
    if (s != VV_OK || *missing)
        return s;
    char key[2200];
    zr_pc_key(a, idx, key, sizeof key);
    unsigned char *src = NULL;
    size_t m = 0;
    s = zr_store_get(a, key, off, len, ZR_CHUNK_MAX, &src, &m, NULL, NULL);
    if (s != VV_OK)
        return s;
    if (file_bytes)
        *file_bytes += m;
    char what[2300];
    snprintf(what, sizeof what, "%s: chunk %llu at bytes %llu..%llu", key,
             (unsigned long long)chunk_id(a, idx), (unsigned long long)off,
             (unsigned long long)(off + len));
    s = vv_zr_decode_unit(a, idx, src, m, out, n, what);
    free(src);
    return s;
}

void
zr_pc_key(const zr_array *a, const uint64_t *idx, char *key, size_t cap) {
    if (a->pc_shard) {
        snprintf(key, cap, "%s/%0*llx.shard", a->prefix, (a->pc_sbits + 3) / 4,
                 (unsigned long long)zr_pc_shard_of(a, idx));
        return;
    }
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

static uint32_t
le32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* A compressed_segmentation chunk of @p cut voxels (c, z, y, x) decoded
 * into @p out (ids of a->esize bytes, little-endian, channels one after
 * another): every offset, bit count and table entry checked against the
 * chunk's @p m bytes. */
static vv_status
pc_cseg(const zr_array *a, const uint64_t cut[4], const unsigned char *src, size_t m,
        unsigned char *out, const char *what) {
    const uint64_t nch = cut[0], X = cut[3], Y = cut[2], Z = cut[1];
    const uint64_t bx = (uint64_t)a->pc_block[0], by = (uint64_t)a->pc_block[1],
                   bz = (uint64_t)a->pc_block[2];
    const uint64_t gx = (X + bx - 1) / bx, gy = (Y + by - 1) / by, gz = (Z + bz - 1) / bz;
    const size_t vb = a->esize, vw = vb / 4; /* an id's bytes and 32-bit words */
    const uint64_t words = m / 4;
    if (m % 4 || words < nch)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: compressed_segmentation of %zu bytes, not 32-bit words with an "
                            "offset a channel",
                            what, m);
    for (uint64_t c = 0; c < nch; c++) {
        const uint64_t base = le32(src + 4 * c);
        if (base > words || 2 * gx * gy * gz > words - base)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: compressed_segmentation channel %llu's blocks at word %llu "
                                "past the chunk's %llu",
                                what, (unsigned long long)c, (unsigned long long)base,
                                (unsigned long long)words);
        const unsigned char *w0 = src + 4 * base;
        const uint64_t nw = words - base;
        unsigned char *oc = out + (size_t)(c * Z * Y * X) * vb;
        for (uint64_t k = 0; k < gz; k++)
            for (uint64_t j = 0; j < gy; j++)
                for (uint64_t i = 0; i < gx; i++) {
                    const uint64_t h = zr_le64(w0 + 8 * (i + gx * (j + gy * k)));
                    const uint64_t table = h & 0xffffff, voff = h >> 32;
                    const unsigned bits = (unsigned)(h >> 24) & 0xff;
                    const uint64_t nval = bx * by * bz;
                    if (bits > 32 || (bits & (bits - 1)))
                        return vv_error_set(VV_ERR_FORMAT,
                                            "%s: compressed_segmentation block %llu,%llu,%llu: "
                                            "%u bits a value (0, 1, 2, 4, 8, 16 or 32)",
                                            what, (unsigned long long)i, (unsigned long long)j,
                                            (unsigned long long)k, bits);
                    if (voff > nw || (bits * nval + 31) / 32 > nw - voff || table >= nw)
                        return vv_error_set(VV_ERR_FORMAT,
                                            "%s: compressed_segmentation block %llu,%llu,%llu: "
                                            "its values or lookup table past the chunk",
                                            what, (unsigned long long)i, (unsigned long long)j,
                                            (unsigned long long)k);
                    const uint64_t ntab = (nw - table) / vw,
                                   mask = bits == 32 ? UINT32_MAX : ((uint64_t)1 << bits) - 1;
                    for (uint64_t z = 0; z < bz && k * bz + z < Z; z++)
                        for (uint64_t y = 0; y < by && j * by + y < Y; y++)
                            for (uint64_t x = 0; x < bx && i * bx + x < X; x++) {
                                uint64_t v = 0;
                                if (bits) {
                                    const uint64_t bo = bits * (x + bx * (y + by * z));
                                    v = (le32(w0 + 4 * (voff + bo / 32)) >> (bo % 32)) & mask;
                                }
                                if (v >= ntab)
                                    return vv_error_set(
                                        VV_ERR_FORMAT,
                                        "%s: compressed_segmentation block %llu,%llu,%llu: "
                                        "value %llu past its lookup table",
                                        what, (unsigned long long)i, (unsigned long long)j,
                                        (unsigned long long)k, (unsigned long long)v);
                                const uint64_t at =
                                    ((k * bz + z) * Y + j * by + y) * X + i * bx + x;
                                memcpy(oc + at * vb, w0 + 4 * (table + v * vw), vb);
                            }
                }
    }
    return VV_OK;
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
    unsigned char *dec = NULL;
    size_t dm = 0;
    if (a->pc_shard && a->pc_data_gzip) { /* the sharding's data_encoding */
        const size_t full =
            (size_t)a->chunks[0] * a->chunks[1] * a->chunks[2] * a->chunks[3] * a->esize;
        vv_status s = inflate_alloc(src, m, full * 4 + 65536, &dec, &dm, what);
        if (s != VV_OK)
            return s;
        src = dec;
        m = dm;
    }
    unsigned char *dst = whole ? out : malloc(bytes);
    if (!dst) {
        free(dec);
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory for %zu bytes", what, bytes);
    }
    vv_status s = !strcmp(a->codec, "jpeg")   ? pc_jpeg(cut, src, m, dst, what)
                  : !strcmp(a->codec, "cseg") ? pc_cseg(a, cut, src, m, dst, what)
                                              : pc_raw(src, m, dst, bytes, what);
    free(dec);
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
    .doc =
        "Neuroglancer precomputed (a folder or a URL with an info file): its scales as "
        "levels (resolution in nm, voxel_offset), num_channels as channels, segmentations as "
        "label images; raw (also gzip) and jpeg chunks, one file each or sharded "
        "(neuroglancer_uint64_sharded_v1); compressed_segmentation labels; read like OME-Zarr: one "
        "level whole, or out of core by level of detail",
    .flags = VV_FORMAT_FLAG_FOLDER | VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = vv_pc_looks_like,
    .read = vv_pc_read,
    .open_store = vv_zr_pyramid_store,
    .open_store_channels = vv_zr_pyramid_store_channels,
};
