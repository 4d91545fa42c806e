/*
 * Zarr v3 (https://zarr-specs.readthedocs.io/en/latest/v3/core/): an
 * array's zarr.json, its codec chains and sharded chunks, for the reader
 * in zarr_read.c.
 *
 * zarr.json: zarr_format 3, node_type "array", shape, data_type (bool,
 * int8..uint64, float32, float64; 64-bit integers are read as doubles,
 * float16 and others refused), chunk_grid "regular", chunk_key_encoding
 * "default" ("c/0/1/2", separator "/" or ".") or "v2" ("0.1.2"),
 * fill_value (a number, true/false, "NaN", "Infinity", "-Infinity" or the
 * bits in hex, "0x7fc00000"), codecs, dimension_names. No storage
 * transformers.
 *
 * Codecs, in the chain's order array -> array (transpose), array -> bytes
 * (bytes, either endian, or sharding_indexed), bytes -> bytes (gzip, zstd,
 * blosc, crc32c). A sharded array is read by inner chunk: the shard's
 * index (cached, a few per array), then the inner chunk's bytes by offset
 * and length; nested shards compose the ranges. A shard is never read
 * whole. Every decoded size is known beforehand and nothing decodes past
 * it (a decompression bomb ends as a one-line error).
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <blosc.h>
#include <jansson.h>
#include <zlib.h>
#include <zstd.h>

#include "core/crc32c.h"
#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/zarr.h"

/* ---- the shard index cache ---- */

#define ZR_CACHE_SLOTS 64

/* One shard's decoded index: count entries of w numbers each (Zarr:
 * (offset, length) of each inner chunk, C order over the shard's inner
 * chunk grid; precomputed.c: a shard index's minishard ranges, a
 * minishard's (chunk id, offset, size) sorted by id); the shard's size. */
typedef struct zr_index {
    int level;
    uint64_t id; /* the shard's linear index over its level's grid */
    uint64_t *ent;
    uint64_t count, size, tick;
    unsigned w;
} zr_index;

struct zr_index_cache {
    pthread_mutex_t mu;
    uint64_t tick, bytes;
    zr_index e[ZR_CACHE_SLOTS];
};

struct zr_index_cache *
zr_index_cache_new(void) {
    struct zr_index_cache *c = calloc(1, sizeof *c);
    if (c && pthread_mutex_init(&c->mu, NULL) != 0) {
        free(c);
        c = NULL;
    }
    return c;
}

void
zr3_cache_free(zr_array *a) {
    struct zr_index_cache *c = a->cache;
    if (!c)
        return;
    for (int i = 0; i < ZR_CACHE_SLOTS; i++)
        free(c->e[i].ent);
    pthread_mutex_destroy(&c->mu);
    free(c);
    a->cache = NULL;
}

/* The slot of (@p level, @p id), or NULL; c->mu held. */
static zr_index *
cache_slot(struct zr_index_cache *c, int level, uint64_t id) {
    for (int i = 0; i < ZR_CACHE_SLOTS; i++)
        if (c->e[i].ent && c->e[i].level == level && c->e[i].id == id)
            return &c->e[i];
    return NULL;
}

int
zr_index_cache_find(struct zr_index_cache *c, int level, uint64_t id, uint64_t p, uint64_t o[2],
                    uint64_t *size) {
    int hit = 0;
    pthread_mutex_lock(&c->mu);
    zr_index *e = cache_slot(c, level, id);
    if (e && e->w == 2 && p < e->count) {
        o[0] = e->ent[2 * p];
        o[1] = e->ent[2 * p + 1];
        *size = e->size;
        e->tick = ++c->tick;
        hit = 1;
    }
    pthread_mutex_unlock(&c->mu);
    return hit;
}

int
zr_index_cache_search(struct zr_index_cache *c, int level, uint64_t id, uint64_t key,
                      uint64_t o[2]) {
    int hit = 0;
    pthread_mutex_lock(&c->mu);
    zr_index *e = cache_slot(c, level, id);
    if (e && e->w == 3) {
        e->tick = ++c->tick;
        hit = -1;
        uint64_t lo = 0, hi = e->count;
        while (lo < hi) { /* the first entry whose id is not below key */
            const uint64_t mid = lo + (hi - lo) / 2;
            if (e->ent[3 * mid] < key)
                lo = mid + 1;
            else
                hi = mid;
        }
        if (lo < e->count && e->ent[3 * lo] == key) {
            o[0] = e->ent[3 * lo + 1];
            o[1] = e->ent[3 * lo + 2];
            hit = 1;
        }
    }
    pthread_mutex_unlock(&c->mu);
    return hit;
}

void
zr_index_cache_put(struct zr_index_cache *c, int level, uint64_t id, uint64_t *ent, uint64_t count,
                   uint64_t size, unsigned w) {
    const uint64_t bytes = count * w * 8;
    pthread_mutex_lock(&c->mu);
    if (cache_slot(c, level, id)) { /* another thread's */
        pthread_mutex_unlock(&c->mu);
        free(ent);
        return;
    }
    for (;;) {
        int victim = -1, empty = -1;
        for (int i = 0; i < ZR_CACHE_SLOTS; i++) {
            if (!c->e[i].ent)
                empty = empty < 0 ? i : empty;
            else if (victim < 0 || c->e[i].tick < c->e[victim].tick)
                victim = i;
        }
        if (empty >= 0 && c->bytes + bytes <= ZR_INDEX_CACHE_BYTES) {
            c->e[empty] = (zr_index){level, id, ent, count, size, ++c->tick, w};
            c->bytes += bytes;
            break;
        }
        if (victim < 0) { /* one index over the whole cache: not kept */
            free(ent);
            break;
        }
        c->bytes -= c->e[victim].count * c->e[victim].w * 8;
        free(c->e[victim].ent);
        c->e[victim].ent = NULL;
    }
    pthread_mutex_unlock(&c->mu);
}

/* ---- metadata ---- */

static int
is_a2b(int kind) {
    return kind == ZC_BYTES || kind == ZC_SHARD;
}

static int
is_b2b(int kind) {
    return kind == ZC_GZIP || kind == ZC_ZSTD || kind == ZC_BLOSC || kind == ZC_CRC32C;
}

static vv_status parse_chain(zr_array *a, json_t *codecs, int level, int index, const char *where);

/* sharding_indexed's configuration: the inner chunk shape at level + 1,
 * its codecs, the index's codecs and location. */
static vv_status
parse_sharding(zr_array *a, json_t *cfg, int level, const char *where) {
    if (level + 1 > ZR_MAX_NEST)
        return vv_error_set(VV_ERR_LIMIT, "zarr.json: %s: shards nested over %d deep", where,
                            ZR_MAX_NEST);
    json_t *cs = json_object_get(cfg, "chunk_shape");
    if (!json_is_array(cs) || (int)json_array_size(cs) != a->ndim)
        return vv_error_set(VV_ERR_FORMAT,
                            "zarr.json: %s: sharding_indexed chunk_shape is not %d sizes", where,
                            a->ndim);
    uint64_t count = 1;
    for (int i = 0; i < a->ndim; i++) {
        json_t *x = json_array_get(cs, (size_t)i);
        const uint64_t outer = a->cshape[level][i];
        if (!json_is_integer(x) || json_integer_value(x) < 1 ||
            (uint64_t)json_integer_value(x) > outer || outer % (uint64_t)json_integer_value(x))
            return vv_error_set(VV_ERR_FORMAT,
                                "zarr.json: %s: sharding_indexed chunk_shape %d does not divide "
                                "the shard's %llu",
                                where, i, (unsigned long long)outer);
        a->cshape[level + 1][i] = (uint64_t)json_integer_value(x);
        count *= outer / a->cshape[level + 1][i];
        if (count > ZR_SHARD_INNER_MAX)
            return vv_error_set(VV_ERR_LIMIT,
                                "zarr.json: %s: over %u inner chunks in one shard (its index)",
                                where, ZR_SHARD_INNER_MAX);
    }
    json_t *loc = json_object_get(cfg, "index_location");
    const char *ls = json_string_value(loc);
    if (loc && (!ls || (strcmp(ls, "end") && strcmp(ls, "start"))))
        return vv_error_set(VV_ERR_FORMAT,
                            "zarr.json: %s: index_location is not \"start\" or \"end\"", where);
    a->index_start[level] = ls && !strcmp(ls, "start");
    a->nshard = level + 1;
    vv_status s = parse_chain(a, json_object_get(cfg, "index_codecs"), level, 1, where);
    if (s == VV_OK)
        s = parse_chain(a, json_object_get(cfg, "codecs"), level + 1, 0, where);
    return s;
}

/* The codec list @p codecs into a->chain[level] (or a->index_chain[level]
 * when @p index), checked: array -> array codecs, exactly one array ->
 * bytes codec, bytes -> bytes codecs, in that order. */
static vv_status
parse_chain(zr_array *a, json_t *codecs, int level, int index, const char *where) {
    char w[160];
    snprintf(w, sizeof w, "%s%s%s", where, where[0] ? " " : "", index ? "index_codecs" : "codecs");
    if (!json_is_array(codecs) || json_array_size(codecs) == 0)
        return vv_error_set(VV_ERR_FORMAT, "zarr.json: %s: not a list of codecs", w);
    if (json_array_size(codecs) > ZR_MAX_CODECS)
        return vv_error_set(VV_ERR_LIMIT, "zarr.json: %s: %zu codecs (at most %d)", w,
                            json_array_size(codecs), ZR_MAX_CODECS);
    zr_chain *c = index ? &a->index_chain[level] : &a->chain[level];
    memset(c, 0, sizeof *c);
    int stage = 0; /* 0 array -> array, 1 after the array -> bytes codec */
    size_t i;
    json_t *e;
    json_array_foreach(codecs, i, e) {
        const char *name = json_string_value(json_object_get(e, "name"));
        json_t *cfg = json_object_get(e, "configuration");
        zr_codec *k = &c->c[c->n++];
        memset(k, 0, sizeof *k);
        if (!name)
            return vv_error_set(VV_ERR_FORMAT, "zarr.json: %s: codec %zu has no name", w, i);
        if (!strcmp(name, "bytes")) {
            k->kind = ZC_BYTES;
            const char *en = json_string_value(json_object_get(cfg, "endian"));
            if (en && strcmp(en, "little") && strcmp(en, "big"))
                return vv_error_set(VV_ERR_FORMAT,
                                    "zarr.json: %s: bytes endian \"%s\" (little or big)", w, en);
            if (!en && !index && a->esize > 1)
                return vv_error_set(VV_ERR_FORMAT,
                                    "zarr.json: %s: bytes codec without an endian for %zu-byte "
                                    "elements",
                                    w, a->esize);
            k->big = en && !strcmp(en, "big");
        } else if (!strcmp(name, "transpose")) {
            k->kind = ZC_TRANSPOSE;
            json_t *o = json_object_get(cfg, "order");
            int seen[ZR_MAX_DIM] = {0};
            if (!json_is_array(o) || (int)json_array_size(o) != a->ndim)
                return vv_error_set(VV_ERR_FORMAT, "zarr.json: %s: transpose order is not %d axes",
                                    w, a->ndim);
            for (int d = 0; d < a->ndim; d++) {
                json_t *x = json_array_get(o, (size_t)d);
                const json_int_t v = json_is_integer(x) ? json_integer_value(x) : -1;
                if (v < 0 || v >= a->ndim || seen[v]++)
                    return vv_error_set(VV_ERR_FORMAT,
                                        "zarr.json: %s: transpose order is not a permutation", w);
                k->order[d] = (int)v;
            }
        } else if (!strcmp(name, "gzip")) {
            k->kind = ZC_GZIP;
        } else if (!strcmp(name, "zstd")) {
            k->kind = ZC_ZSTD;
        } else if (!strcmp(name, "blosc")) {
            k->kind = ZC_BLOSC;
            const char *cn = json_string_value(json_object_get(cfg, "cname"));
            if (cn && blosc_compname_to_compcode(cn) < 0)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "zarr.json: %s: blosc cname \"%s\" (not in this Blosc)", w, cn);
        } else if (!strcmp(name, "crc32c")) {
            k->kind = ZC_CRC32C;
        } else if (!strcmp(name, "sharding_indexed")) {
            k->kind = ZC_SHARD;
            if (index)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "zarr.json: %s: a sharded shard index is not read", w);
        } else {
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "zarr.json: %s: codec \"%s\" (supported: bytes, transpose, gzip, "
                                "zstd, blosc, crc32c, sharding_indexed)",
                                w, name);
        }
        if (k->kind == ZC_TRANSPOSE && stage)
            return vv_error_set(VV_ERR_FORMAT,
                                "zarr.json: %s: transpose after the array-to-bytes codec", w);
        if (is_a2b(k->kind) && stage)
            return vv_error_set(VV_ERR_FORMAT, "zarr.json: %s: two array-to-bytes codecs", w);
        if (is_b2b(k->kind) && !stage)
            return vv_error_set(VV_ERR_FORMAT,
                                "zarr.json: %s: codec \"%s\" before the array-to-bytes codec", w,
                                name);
        if (is_a2b(k->kind))
            stage = 1;
    }
    if (!stage)
        return vv_error_set(
            VV_ERR_FORMAT, "zarr.json: %s: no array-to-bytes codec (bytes or sharding_indexed)", w);
    if (index) {
        for (int d = 0; d < c->n; d++)
            if (c->c[d].kind != ZC_BYTES && c->c[d].kind != ZC_CRC32C)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "zarr.json: %s: only bytes and crc32c are read in a shard "
                                    "index's codecs",
                                    w);
        return VV_OK;
    }
    /* the sharding codec, and what a range read of an inner chunk needs:
     * nothing around it (a transposed or compressed shard is read whole
     * by other readers; we refuse it) */
    for (int d = 0; d < c->n; d++)
        if (c->c[d].kind == ZC_SHARD) {
            if (c->n != 1)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "zarr.json: %s: sharding_indexed with other codecs around it "
                                    "(the shard could not be read by ranges)",
                                    w);
            char ww[160];
            snprintf(ww, sizeof ww, "%s%ssharding_indexed", where, where[0] ? " " : "");
            return parse_sharding(
                a, json_object_get(json_array_get(codecs, (size_t)d), "configuration"), level, ww);
        }
    /* the read unit's chain: its byte order */
    for (int d = 0; d < c->n; d++)
        if (c->c[d].kind == ZC_BYTES)
            a->swap = a->esize > 1 && c->c[d].big == vv_host_is_little_endian();
    return VV_OK;
}

/* fill_value of data type @p t (bits = a hex string's bits). */
static vv_status
parse_fill(zr_array *a, json_t *f, const char *dt) {
    a->fill = 0;
    const char *fs = json_string_value(f);
    if (json_is_null(f) || !f)
        return vv_error_set(VV_ERR_FORMAT, "zarr.json: no fill_value");
    if (json_is_boolean(f))
        a->fill = json_is_true(f);
    else if (json_is_number(f))
        a->fill = json_number_value(f);
    else if (fs && !strcmp(fs, "NaN"))
        a->fill = NAN;
    else if (fs && !strcmp(fs, "Infinity"))
        a->fill = INFINITY;
    else if (fs && !strcmp(fs, "-Infinity"))
        a->fill = -INFINITY;
    else if (fs && fs[0] == '0' && (fs[1] == 'x' || fs[1] == 'X') && strlen(fs) <= 18) {
        char *end = NULL;
        const unsigned long long bits = strtoull(fs + 2, &end, 16);
        if (!end || *end || !strcmp(dt, "float16"))
            return vv_error_set(VV_ERR_FORMAT, "zarr.json: fill_value \"%s\" is not hex bits", fs);
        if (!strcmp(dt, "float32")) {
            const uint32_t b = (uint32_t)bits;
            float x;
            memcpy(&x, &b, 4);
            a->fill = x;
        } else if (!strcmp(dt, "float64")) {
            double x;
            memcpy(&x, &bits, 8);
            a->fill = x;
        } else {
            a->fill = (double)bits;
        }
    } else
        return vv_error_set(VV_ERR_FORMAT,
                            "zarr.json: fill_value is not a number, a boolean, \"NaN\", "
                            "\"Infinity\", \"-Infinity\" or hex bits");
    return VV_OK;
}

vv_status
zr3_parse_array(zr_array *a, void *jv) {
    json_t *j = jv;
    a->zarr_format = 3;
    a->codec[0] = '\0';
    a->nshard = 0;
    a->conv64 = 0;
    a->swap = 0;
    json_t *fmt = json_object_get(j, "zarr_format"), *shape = json_object_get(j, "shape");
    const char *nt = json_string_value(json_object_get(j, "node_type"));
    if (!json_is_integer(fmt) || json_integer_value(fmt) != 3)
        return vv_error_set(VV_ERR_UNSUPPORTED, "zarr.json: zarr_format is not 3");
    if (!nt || strcmp(nt, "array"))
        return vv_error_set(VV_ERR_FORMAT, "zarr.json: node_type is not \"array\"");
    if (!json_is_array(shape) || json_array_size(shape) < 2 || json_array_size(shape) > ZR_MAX_DIM)
        return vv_error_set(VV_ERR_FORMAT, "zarr.json: shape is not 2 to %d sizes", ZR_MAX_DIM);
    a->ndim = (int)json_array_size(shape);
    /* the data type */
    static const struct {
        const char *k;
        vv_voxel_type t;
        int conv;
    } map[] = {{"bool", VV_U8, 0},    {"uint8", VV_U8, 0},    {"int8", VV_I8, 0},
               {"uint16", VV_U16, 0}, {"int16", VV_I16, 0},   {"uint32", VV_U32, 0},
               {"int32", VV_I32, 0},  {"float32", VV_F32, 0}, {"float64", VV_F64, 0},
               {"int64", VV_F64, 1},  {"uint64", VV_F64, 2}};
    const char *dt = json_string_value(json_object_get(j, "data_type"));
    size_t m = 0;
    while (dt && m < sizeof map / sizeof map[0] && strcmp(dt, map[m].k))
        m++;
    if (!dt || m == sizeof map / sizeof map[0])
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "zarr.json: data_type \"%.40s\" (supported: bool, int8..int64, "
                            "uint8..uint64, float32, float64)",
                            dt                                                ? dt
                            : json_is_object(json_object_get(j, "data_type")) ? "(an extension)"
                                                                              : "(none)");
    a->type = map[m].t;
    a->conv64 = map[m].conv;
    a->esize = vv_voxel_type_size(a->type);
    /* the chunk grid */
    json_t *g = json_object_get(j, "chunk_grid");
    const char *gn = json_string_value(json_object_get(g, "name"));
    json_t *cs = json_object_get(json_object_get(g, "configuration"), "chunk_shape");
    if (!gn || strcmp(gn, "regular"))
        return vv_error_set(VV_ERR_UNSUPPORTED, "zarr.json: chunk_grid \"%.40s\" (only regular)",
                            gn ? gn : "?");
    if (!json_is_array(cs) || (int)json_array_size(cs) != a->ndim)
        return vv_error_set(VV_ERR_FORMAT, "zarr.json: chunk_grid chunk_shape is not %d sizes",
                            a->ndim);
    for (int i = 0; i < a->ndim; i++) {
        json_t *x = json_array_get(shape, (size_t)i), *c = json_array_get(cs, (size_t)i);
        if (!json_is_integer(x) || !json_is_integer(c) || json_integer_value(x) < 1 ||
            json_integer_value(c) < 1 || json_integer_value(x) > (1LL << 40) ||
            json_integer_value(c) > (1LL << 40))
            return vv_error_set(VV_ERR_FORMAT, "zarr.json: axis %d: shape or chunk size not a size",
                                i);
        a->shape[i] = (uint64_t)json_integer_value(x);
        a->cshape[0][i] = (uint64_t)json_integer_value(c);
    }
    /* the chunk keys */
    json_t *ke = json_object_get(j, "chunk_key_encoding");
    const char *kn = json_string_value(json_object_get(ke, "name"));
    json_t *sep = json_object_get(json_object_get(ke, "configuration"), "separator");
    if (!kn || (strcmp(kn, "default") && strcmp(kn, "v2")))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "zarr.json: chunk_key_encoding \"%.40s\" (default or v2)",
                            kn ? kn : "?");
    a->key_default = !strcmp(kn, "default");
    a->sep = a->key_default ? '/' : '.';
    if (sep) {
        const char *ss = json_string_value(sep);
        if (!ss || (strcmp(ss, "/") && strcmp(ss, ".")))
            return vv_error_set(VV_ERR_FORMAT,
                                "zarr.json: chunk_key_encoding separator is not \"/\" or \".\"");
        a->sep = ss[0];
    }
    json_t *stt = json_object_get(j, "storage_transformers");
    if (stt && !(json_is_array(stt) && json_array_size(stt) == 0))
        return vv_error_set(VV_ERR_UNSUPPORTED, "zarr.json: storage_transformers are not read");
    vv_status s = parse_fill(a, json_object_get(j, "fill_value"), dt);
    if (s != VV_OK)
        return s;
    /* dimension_names: the axes' names unless the OME metadata names them */
    json_t *dn = json_object_get(j, "dimension_names");
    for (int i = 0; i < a->ndim; i++) {
        const char *n = json_string_value(json_array_get(dn, (size_t)i));
        snprintf(a->axes[i].name, sizeof a->axes[i].name, "%s", n ? n : "");
    }
    if ((s = parse_chain(a, json_object_get(j, "codecs"), 0, 0, "")) != VV_OK)
        return s;
    /* the read unit: the innermost chunk */
    for (int i = 0; i < a->ndim; i++)
        a->chunks[i] = a->cshape[a->nshard][i];
    if (a->nshard > 0 && !(a->cache = zr_index_cache_new()))
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    return VV_OK;
}

/* ---- decoding ---- */

/* One bytes-to-bytes codec undone: @p src (@p m bytes) into exactly @p n
 * bytes at @p out. */
static vv_status
decode_one(const zr_codec *k, const unsigned char *src, size_t m, unsigned char *out, size_t n,
           const char *what) {
    switch (k->kind) {
    case ZC_CRC32C: {
        if (m < 4 || m - 4 != n)
            return vv_error_set(VV_ERR_FORMAT, "%s: crc32c: %zu bytes, expected %zu and 4", what, m,
                                n);
        const uint32_t want = (uint32_t)src[n] | (uint32_t)src[n + 1] << 8 |
                              (uint32_t)src[n + 2] << 16 | (uint32_t)src[n + 3] << 24;
        if (vv_crc32c(0, src, n) != want)
            return vv_error_set(VV_ERR_FORMAT, "%s: crc32c checksum mismatch (damaged bytes)",
                                what);
        memmove(out, src, n);
        return VV_OK;
    }
    case ZC_GZIP: {
        z_stream z;
        memset(&z, 0, sizeof z);
        int r = Z_DATA_ERROR;
        size_t done = 0;
        if (m <= UINT32_MAX && n <= UINT32_MAX && inflateInit2(&z, 16 + MAX_WBITS) == Z_OK) {
            z.next_in = (unsigned char *)src;
            z.avail_in = (uInt)m;
            z.next_out = out;
            z.avail_out = (uInt)n;
            r = inflate(&z, Z_FINISH); /* never past n bytes */
            done = n - z.avail_out;
            inflateEnd(&z);
        }
        if (r != Z_STREAM_END || done != n)
            return vv_error_set(VV_ERR_FORMAT, "%s: the gzip stream does not decode to %zu bytes",
                                what, n);
        return VV_OK;
    }
    case ZC_ZSTD: {
        const unsigned long long fs = ZSTD_getFrameContentSize(src, m);
        size_t r = 0;
        if (fs == (unsigned long long)n || fs == ZSTD_CONTENTSIZE_UNKNOWN)
            r = ZSTD_decompress(out, n, src, m); /* bounded by n */
        if ((fs != (unsigned long long)n && fs != ZSTD_CONTENTSIZE_UNKNOWN) || ZSTD_isError(r) ||
            r != n)
            return vv_error_set(VV_ERR_FORMAT, "%s: the zstd frame does not decode to %zu bytes",
                                what, n);
        return VV_OK;
    }
    case ZC_BLOSC: {
        size_t nb = 0;
        if (n > INT32_MAX || blosc_cbuffer_validate(src, m, &nb) != 0 || nb != n ||
            blosc_decompress_ctx(src, out, n, 1) != (int)n)
            return vv_error_set(VV_ERR_FORMAT, "%s: the blosc buffer does not decode to %zu bytes",
                                what, n);
        return VV_OK;
    }
    }
    return vv_error_set(VV_ERR_FORMAT, "%s: not a bytes-to-bytes codec", what);
}

uint64_t
zr3_encoded_max(const zr_chain *c, size_t n) {
    uint64_t m = n;
    int packed = 0;
    for (int i = 0; i < c->n; i++) {
        if (c->c[i].kind == ZC_CRC32C)
            m += 4;
        else if (is_b2b(c->c[i].kind))
            packed = 1;
    }
    /* a compressor's worst case is a few bytes in a thousand over its
     * input (stored blocks, headers): half again and 64 KiB is generous */
    return packed ? m + m / 2 + 65536 : m;
}

vv_status
zr3_decode_bytes(const zr_chain *c, const unsigned char *src, size_t m, unsigned char *out,
                 size_t n, const char *what) {
    /* the size each bytes-to-bytes codec was given when encoding: the
     * chunk's, plus 4 for each crc32c before it */
    int first = 0;
    while (first < c->n && !is_b2b(c->c[first].kind))
        first++;
    if (first == c->n) {
        if (m != n)
            return vv_error_set(VV_ERR_FORMAT, "%s: %zu bytes, an uncompressed chunk has %zu", what,
                                m, n);
        memcpy(out, src, n);
        return VV_OK;
    }
    /* the size each codec was given when encoding: the chunk's, plus 4
     * for each crc32c before it, known up to the first compressor (after
     * one, a crc32c's input is what it is given less its 4 bytes) */
    size_t want[ZR_MAX_CODECS];
    int known[ZR_MAX_CODECS];
    size_t sz = n;
    int k = 1;
    for (int i = first; i < c->n; i++) {
        want[i] = sz;
        known[i] = k;
        if (c->c[i].kind == ZC_CRC32C)
            sz += 4;
        else
            k = 0;
    }
    const unsigned char *cur = src;
    size_t cm = m;
    unsigned char *owned = NULL;
    vv_status s = VV_OK;
    for (int i = c->n - 1; i >= first && s == VV_OK; i--) {
        if (!known[i] && c->c[i].kind != ZC_CRC32C) {
            s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: two compressors in one codec chain", what);
            break;
        }
        if (!known[i]) /* a crc32c after a compressor */
            want[i] = cm >= 4 ? cm - 4 : 0;
        unsigned char *dst = i == first ? out : malloc(want[i] ? want[i] : 1);
        if (!dst) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory for %zu bytes", want[i]);
            break;
        }
        s = decode_one(&c->c[i], cur, cm, dst, want[i], what);
        free(owned);
        owned = dst == out ? NULL : dst;
        cur = dst;
        cm = want[i];
    }
    free(owned);
    return s;
}

void
zr3_untranspose(const zr_chain *c, int ndim, const uint64_t *shape, size_t es, unsigned char *buf,
                unsigned char *tmp) {
    /* the transposes in reverse: each one's input shape is the shape
     * after the ones before it */
    int nt = 0, which[ZR_MAX_CODECS];
    for (int i = 0; i < c->n; i++)
        if (c->c[i].kind == ZC_TRANSPOSE)
            which[nt++] = i;
    for (int t = nt - 1; t >= 0; t--) {
        /* the decoded shape before transpose t: apply transposes 0..t-1 */
        uint64_t in[ZR_MAX_DIM] = {0}, enc[ZR_MAX_DIM] = {0};
        for (int d = 0; d < ndim; d++)
            in[d] = shape[d];
        for (int u = 0; u < t; u++) {
            uint64_t x[ZR_MAX_DIM];
            for (int d = 0; d < ndim; d++)
                x[d] = in[c->c[which[u]].order[d]];
            memcpy(in, x, sizeof x);
        }
        const int *ord = c->c[which[t]].order;
        for (int d = 0; d < ndim; d++)
            enc[d] = in[ord[d]];
        /* stride in the encoded array of each input axis */
        uint64_t es_[ZR_MAX_DIM], st[ZR_MAX_DIM];
        es_[ndim - 1] = 1;
        for (int d = ndim - 2; d >= 0; d--)
            es_[d] = es_[d + 1] * enc[d + 1];
        for (int d = 0; d < ndim; d++)
            st[ord[d]] = es_[d];
        uint64_t total = 1, pos[ZR_MAX_DIM] = {0};
        for (int d = 0; d < ndim; d++)
            total *= in[d];
        uint64_t src = 0;
        for (uint64_t q = 0; q < total; q++) {
            memcpy(tmp + q * es, buf + src * es, es);
            for (int d = ndim - 1; d >= 0; d--) { /* the next input position, C order */
                if (++pos[d] < in[d]) {
                    src += st[d];
                    break;
                }
                src -= st[d] * (in[d] - 1);
                pos[d] = 0;
            }
        }
        memcpy(buf, tmp, total * es);
    }
}

/* ---- sharded chunks ---- */

/* The bytes of a level-@p l shard index of @p count entries (with its
 * checksum) into *ib; *big = 1 when its numbers are big-endian. */
static void
index_size(const zr_array *a, int l, uint64_t count, uint64_t *ib, int *big) {
    const zr_chain *ic = &a->index_chain[l];
    *ib = count * 16;
    *big = 0;
    for (int i = 0; i < ic->n; i++) {
        if (ic->c[i].kind == ZC_CRC32C)
            *ib += 4;
        if (ic->c[i].kind == ZC_BYTES)
            *big = ic->c[i].big;
    }
}

/* Checks and decodes the raw index @p raw (@p m bytes) of a level-@p l
 * shard of @p len bytes whose index lies at @p ioff: *ent (2 count numbers,
 * free it). Entries past the shard's end, overlapping ones or overlapping
 * the index, and a bad checksum are refused. */
static vv_status
parse_index(const zr_array *a, int l, const char *key, const unsigned char *raw, size_t m,
            uint64_t len, uint64_t ioff, uint64_t count, uint64_t **ent_out) {
    const zr_chain *ic = &a->index_chain[l];
    uint64_t ib;
    int big;
    index_size(a, l, count, &ib, &big);
    uint64_t *ent = malloc((size_t)count * 16);
    if (!ent)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a shard index");
    char what[2300];
    snprintf(what, sizeof what, "%s: shard index", key);
    vv_status s = zr3_decode_bytes(ic, raw, m, (unsigned char *)ent, (size_t)count * 16, what);
    if (s == VV_OK && big == vv_host_is_little_endian())
        vv_byteswap(ent, count * 2, 8);
    /* every chunk inside the shard, clear of the index and of each other */
    uint64_t *r = s == VV_OK ? malloc((size_t)(count + 1) * 16) : NULL;
    if (s == VV_OK && !r)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory for a shard index");
    uint64_t nr = 0;
    for (uint64_t i = 0; s == VV_OK && i < count; i++) {
        const uint64_t o = ent[2 * i], n = ent[2 * i + 1];
        if (o == UINT64_MAX && n == UINT64_MAX)
            continue; /* an empty inner chunk: the fill value */
        if (o > len || n > len - o)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: shard index entry %llu: bytes %llu..%llu past the shard's end "
                             "(%llu bytes)",
                             key, (unsigned long long)i, (unsigned long long)o,
                             (unsigned long long)(o + n), (unsigned long long)len);
        else if (n > ZR_CHUNK_MAX)
            s = vv_error_set(VV_ERR_LIMIT, "%s: shard index entry %llu: %llu bytes (limit %llu)",
                             key, (unsigned long long)i, (unsigned long long)n,
                             (unsigned long long)ZR_CHUNK_MAX);
        else if (n > 0) {
            r[2 * nr] = o;
            r[2 * nr++ + 1] = n;
        }
    }
    if (s == VV_OK) {
        r[2 * nr] = ioff;
        r[2 * nr++ + 1] = ib;
        qsort(r, (size_t)nr, 16, zr_cmp_range);
        for (uint64_t i = 1; i < nr && s == VV_OK; i++)
            if (r[2 * i - 2] + r[2 * i - 1] > r[2 * i])
                s = vv_error_set(VV_ERR_FORMAT,
                                 "%s: shard index: inner chunks (or the index) overlap at byte "
                                 "%llu",
                                 key, (unsigned long long)r[2 * i]);
    }
    free(r);
    if (s != VV_OK) {
        free(ent);
        return s;
    }
    *ent_out = ent;
    return VV_OK;
}

/* The read of the index of a whole (level-0) shard @p key: a suffix (or,
 * index_location "start", a prefix) of its exact size. */
static void
index_get(const zr_array *a, const char *key, uint64_t count, bs_get *g) {
    uint64_t ib;
    int big;
    index_size(a, 0, count, &ib, &big);
    *g = (bs_get){.key = key, .off = a->index_start[0] ? 0 : ZR_SUFFIX, .len = ib, .max = ib};
}

/* Reads and checks the index of the shard at bytes [off, off + len) of
 * @p key (len ZR_ALL: the whole object, level 0) at sharding level @p l:
 * *ent (2 count numbers, free it) and the shard's size *size. */
static vv_status
load_index(const zr_array *a, int l, const char *key, uint64_t off, uint64_t len, uint64_t count,
           uint64_t **ent_out, uint64_t *size, int *missing, uint64_t *file_bytes) {
    uint64_t ib;
    int big;
    index_size(a, l, count, &ib, &big);
    unsigned char *raw = NULL;
    size_t m = 0;
    uint64_t ioff;
    vv_status s;
    if (len == ZR_ALL) {
        bs_get g;
        index_get(a, key, count, &g);
        s = zr_store_get_many(a, &g, 1);
        *missing = g.missing;
        raw = g.out;
        m = g.n;
        if (s != VV_OK || *missing)
            return s;
        len = g.size;
        ioff = a->index_start[l] ? 0 : g.size - ib;
    } else {
        if (len < ib)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: a nested shard of %llu bytes is smaller than its index (%llu)",
                                key, (unsigned long long)len, (unsigned long long)ib);
        ioff = a->index_start[l] ? 0 : len - ib;
        s = zr_store_get(a, key, off + ioff, ib, ib, &raw, &m, NULL, NULL);
        if (s != VV_OK)
            return s;
    }
    if (file_bytes)
        *file_bytes += m;
    s = parse_index(a, l, key, raw, m, len, ioff, count, ent_out);
    free(raw);
    if (s == VV_OK)
        *size = len;
    return s;
}

vv_status
zr3_read_sharded(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], unsigned char *out, size_t n,
                 int *missing, uint64_t *file_bytes) {
    *missing = 0;
    uint64_t e0[ZR_MAX_DIM], top[ZR_MAX_DIM];
    for (int i = 0; i < a->ndim; i++) {
        e0[i] = idx[i] * a->chunks[i];
        top[i] = e0[i] / a->cshape[0][i];
    }
    char key[2200];
    zr_chunk_key(a, top, key, sizeof key);
    uint64_t off = 0, len = ZR_ALL;
    for (int l = 0; l < a->nshard; l++) {
        uint64_t p = 0, id = 0, count = 1;
        for (int i = 0; i < a->ndim; i++) {
            const uint64_t per = a->cshape[l][i] / a->cshape[l + 1][i];
            const uint64_t grid = (a->shape[i] + a->cshape[l][i] - 1) / a->cshape[l][i];
            p = p * per + (e0[i] % a->cshape[l][i]) / a->cshape[l + 1][i];
            id = id * grid + e0[i] / a->cshape[l][i];
            count *= per;
        }
        uint64_t o[2], size = 0;
        if (!zr_index_cache_find(a->cache, l, id, p, o, &size)) {
            uint64_t *ent = NULL;
            vv_status s = load_index(a, l, key, off, len, count, &ent, &size, missing, file_bytes);
            if (s != VV_OK)
                return s;
            if (*missing) /* no shard: the fill value */
                return VV_OK;
            o[0] = ent[2 * p];
            o[1] = ent[2 * p + 1];
            zr_index_cache_put(a->cache, l, id, ent, count, size, 2);
        }
        if (o[0] == UINT64_MAX && o[1] == UINT64_MAX) {
            *missing = 1;
            return VV_OK;
        }
        off += o[0];
        len = o[1];
    }
    unsigned char *src = NULL;
    size_t m = 0;
    /* never more than the inner chunk's codecs can have made of it */
    vv_status s = zr_store_get(a, key, off, len, zr3_encoded_max(&a->chain[a->nshard], n), &src, &m,
                               NULL, NULL);
    if (s != VV_OK)
        return s;
    if (file_bytes)
        *file_bytes += m;
    char what[2300];
    snprintf(what, sizeof what, "%s: inner chunk at bytes %llu..%llu", key, (unsigned long long)off,
             (unsigned long long)(off + len));
    s = vv_zr_decode_unit(a, idx, src, m, out, n, what);
    free(src);
    return s;
}

/* One read unit whose shard index is not cached: its shard, its entry. */
typedef struct zr_need {
    uint64_t id, p, i;
} zr_need;

static int
cmp_need(const void *x, const void *y) {
    const zr_need *a = x, *b = y;
    if (a->id != b->id)
        return a->id < b->id ? -1 : 1;
    return a->i < b->i ? -1 : a->i > b->i;
}

vv_status
zr3_locate_many(const zr_array *a, uint64_t n, const uint64_t *idx, uint64_t *off, uint64_t *len,
                unsigned char *missing, int window, uint64_t *file_bytes) {
    if (a->nshard != 1)
        return vv_error_set(VV_ERR_INVALID, "zr3_locate_many: %d sharding levels", a->nshard);
    zr_need *need = malloc((size_t)(n ? n : 1) * sizeof *need);
    if (!need)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %llu chunk reads",
                            (unsigned long long)n);
    uint64_t nn = 0, count = 1;
    for (int d = 0; d < a->ndim; d++)
        count *= a->cshape[0][d] / a->cshape[1][d];
    for (uint64_t i = 0; i < n; i++) {
        const uint64_t *x = idx + i * ZR_MAX_DIM;
        uint64_t p = 0, id = 0;
        for (int d = 0; d < a->ndim; d++) {
            const uint64_t e0 = x[d] * a->chunks[d];
            const uint64_t per = a->cshape[0][d] / a->cshape[1][d];
            const uint64_t grid = (a->shape[d] + a->cshape[0][d] - 1) / a->cshape[0][d];
            p = p * per + (e0 % a->cshape[0][d]) / a->cshape[1][d];
            id = id * grid + e0 / a->cshape[0][d];
        }
        uint64_t o[2], size = 0;
        missing[i] = 0;
        if (zr_index_cache_find(a->cache, 0, id, p, o, &size)) {
            missing[i] = o[0] == UINT64_MAX && o[1] == UINT64_MAX;
            off[i] = o[0];
            len[i] = o[1];
        } else {
            need[nn++] = (zr_need){id, p, i};
        }
    }
    qsort(need, (size_t)nn, sizeof *need, cmp_need);
    /* the shards' indexes, each fetched once, a window of them in flight
     * together: at most a quarter of the memory budget of index bytes */
    uint64_t ib;
    int big;
    index_size(a, 0, count, &ib, &big);
    const uint64_t quarter = vv_memory_budget_get() / 4;
    if (window < 1)
        window = 1;
    if ((uint64_t)window * ib > quarter)
        window = quarter / ib > 1 ? (int)(quarter / ib) : 1;
    bs_get *g = calloc((size_t)window, sizeof *g);
    char *keys = malloc((size_t)window * 2200);
    uint64_t *first = malloc((size_t)(window + 1) * sizeof *first);
    vv_status s =
        g && keys && first ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory for shard indexes");
    for (uint64_t k = 0; s == VV_OK && k < nn;) {
        int w = 0; /* the window's shards: need[first[u] .. first[u + 1]) each */
        uint64_t j = k;
        while (j < nn && w < window) {
            first[w] = j;
            uint64_t top[ZR_MAX_DIM];
            const uint64_t *x = idx + need[j].i * ZR_MAX_DIM;
            for (int d = 0; d < a->ndim; d++)
                top[d] = x[d] * a->chunks[d] / a->cshape[0][d];
            zr_chunk_key(a, top, keys + (size_t)w * 2200, 2200);
            index_get(a, keys + (size_t)w * 2200, count, &g[w]);
            w++;
            const uint64_t id = need[j].id;
            while (j < nn && need[j].id == id)
                j++;
        }
        first[w] = j;
        s = zr_store_get_many(a, g, w);
        for (int u = 0; u < w; u++) {
            uint64_t *ent = NULL;
            if (s == VV_OK && !g[u].missing) {
                if (file_bytes)
                    *file_bytes += g[u].n;
                const uint64_t ioff = a->index_start[0] ? 0 : g[u].size - ib;
                s = parse_index(a, 0, g[u].key, g[u].out, g[u].n, g[u].size, ioff, count, &ent);
            }
            for (uint64_t q = first[u]; s == VV_OK && q < first[u + 1]; q++) {
                const uint64_t i = need[q].i, p = need[q].p;
                /* no shard, or an empty inner chunk: the fill value */
                missing[i] = !ent || (ent[2 * p] == UINT64_MAX && ent[2 * p + 1] == UINT64_MAX);
                off[i] = ent ? ent[2 * p] : 0;
                len[i] = ent ? ent[2 * p + 1] : 0;
            }
            if (ent)
                zr_index_cache_put(a->cache, 0, need[first[u]].id, ent, count, g[u].size, 2);
            free(g[u].out);
            g[u].out = NULL;
        }
        k = j;
    }
    free(first);
    free(keys);
    free(g);
    free(need);
    return s;
}
