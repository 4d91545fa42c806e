/*
 * libFuzzer harness: Zarr v3 arrays, structure-aware (issue 78): the
 * zarr.json of src/io/store/zarr3.c (shape, data_type, chunk_grid,
 * chunk_key_encoding, fill_value, codecs, dimension_names), its codec
 * chains (transpose, bytes either endian, gzip, zstd, blosc, crc32c,
 * sharding_indexed nested up to three deep, the index at either end, with
 * or without its crc32c) and the shard indexes' checks (entries past the
 * end, overlapping, empty, damaged checksums), then the inner chunks
 * decoded, fill values and edge chunks, read by zarr_read.c and
 * zarr_pyramid.c.
 *
 * The input is not the store: it describes one, and the harness writes a
 * store that is valid unless the input says where not, so that mutations
 * reach past the metadata's checks into the shard indexes and the chunks.
 *
 *   [48-byte header][tweaks...]["\n--JSON--\n" JSON object]
 *
 * The header (a byte each, taken modulo its field's range; every value is
 * a valid choice):
 *
 *   0 ndim (2..5)          1 data_type (table dtypes[], the last refused)
 *   2 endian (little, big, absent)   3..7 shape (ndim sizes, small)
 *   8..12 chunk_shape (1 to the shape + 1: edge chunks)
 *   13 sharding levels (0..3)
 *   14 + 6 l, l = 0..2: level l's inner chunk shape (a divisor of the
 *      outer one, by axis), then its flags: 1 index at the start, 2 the
 *      index's crc32c, 4 the index big-endian, 8 the checksum wrong,
 *      16 the index's bytes codec without an endian
 *   32 transpose (bit 0), 33 its permutation (Lehmer code)
 *   34 bytes-to-bytes codecs (0..3), 35..37 each one: gzip, zstd, blosc,
 *      crc32c; 38 blosc's cname and shuffle
 *   39 chunk_key_encoding (default "/", default ".", v2 ".", v2 "/")
 *   40 fill_value's form (a number, "NaN", "Infinity", "-Infinity", hex
 *      bits, a boolean, 0.5, null), 41 its number
 *   42 bit 0 dimension_names; bits 1-2: a plain array at the root, or an
 *      OME-NGFF 0.5 group of one or two levels ("0", "1": halved);
 *      bit 3: vv_open whole too
 *   43 the voxels' pattern, 44 the level asked (NGFF; 7 modulo 8: one past
 *      the last)
 *   45 channels asked out of core at once (modulo 5; 2..4: vv_open's
 *      n_channels, issue 89), 46 which: two bits each (0..3, past the
 *      store's channels refused)
 *
 * Then the tweaks, a byte each, taken as the store is written (chunk files
 * in C order of the chunk grid, each shard's inner chunks depth first in
 * C order); an exhausted input reads as zeros (nothing changed):
 *
 *   a shard (before its inner chunks): 0..10 as encoded; 11 its file
 *     absent (the top level); 12 entry [b] offset += [b]; 13 entries [b]
 *     and [b] swapped; 14 entry [b] length = [b]; 15 entry [b] = ([u16],
 *     [u16]) (the arguments read after its inner chunks)
 *   an inner chunk (or a chunk, unsharded): 0..10 as encoded; 11, 12
 *     absent (an empty index entry; unsharded: 11 no file, 12 an empty
 *     file); 13 raw: [u16 LE length] bytes of the input instead (the
 *     seeds carry real encoders' chunks so); 14 cut by [b] + 1 bytes;
 *     15 byte [b] xor [b]
 *
 * The optional JSON object after a line "--JSON--" is merged into the
 * generated zarr.json of level 0 (a key whose value is null is removed):
 * what the header cannot say (a real store's exact metadata, a wrong key).
 * A second object after a line "--GROUP--" is merged so into the NGFF
 * group's "ome" attributes: "omero" channels and their windows (NaN,
 * inverted, absurd), other multiscales.
 *
 * Each store is read as the library reads one: vv_ome_zarr_read whole,
 * then vv_open out of core (a small box of every level and the proxy) and,
 * when the header says, whole, in a cache of the harness's own with a small budget; it lies in
 * the harness's private folder (/dev/shm) and is removed after each input.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
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
#include "fuzz_util.h"
#include "io/store/zarr.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define Z3_BUDGET ((uint64_t)8 << 20)
#define Z3_HEADER 48
#define Z3_MAX_TOP 32    /* chunk files of one level */
#define Z3_MAX_INNER 256 /* innermost chunks of one level */

static const struct {
    const char *name;
    int size, flt, sgn;
} dtypes[] = {{"bool", 1, 0, 0},    {"uint8", 1, 0, 0},  {"int8", 1, 0, 1},   {"uint16", 2, 0, 0},
              {"int16", 2, 0, 1},   {"uint32", 4, 0, 0}, {"int32", 4, 0, 1},  {"float32", 4, 1, 1},
              {"float64", 8, 1, 1}, {"int64", 8, 0, 1},  {"uint64", 8, 0, 0}, {"float16", 2, 1, 1}};
#define N_DTYPES (int)(sizeof dtypes / sizeof dtypes[0])

/* The input, read a byte at a time (zeros once exhausted). */
typedef struct {
    const uint8_t *p;
    size_t n, at;
} reader;

static unsigned
rd(reader *r) {
    return r->at < r->n ? r->p[r->at++] : 0;
}

static unsigned
rd16(reader *r) {
    const unsigned lo = rd(r);
    return lo | rd(r) << 8;
}

/* The array the header describes. */
typedef struct {
    int ndim, dtype, endian, nshard, transpose, order[ZR_MAX_DIM], nb2b, b2b[3], cname, key;
    int fill_kind, fill_num, dimnames, ngff, whole, seed, ask, n_ch, ch[4];
    int index_start[3], index_crc[3], index_big[3], crc_bad[3], index_noendian[3];
    uint64_t shape[ZR_MAX_DIM], cs[4][ZR_MAX_DIM];
} spec;

/* A growing byte buffer (aborts when out of memory: the machine's fault). */
typedef struct {
    unsigned char *b;
    size_t n, cap;
} buf;

static void
buf_put(buf *o, const void *p, size_t n) {
    if (o->n + n > o->cap) {
        o->cap = (o->n + n) * 2 + 64;
        o->b = realloc(o->b, o->cap);
        if (!o->b)
            abort();
    }
    if (n)
        memcpy(o->b + o->n, p, n);
    o->n += n;
}

static uint64_t
prod(const uint64_t *x, int n) {
    uint64_t p = 1;
    for (int i = 0; i < n; i++)
        p *= x[i];
    return p;
}

static uint64_t
grid_count(const uint64_t *shape, const uint64_t *cs, int n) {
    uint64_t p = 1;
    for (int i = 0; i < n; i++)
        p *= (shape[i] + cs[i] - 1) / cs[i];
    return p;
}

/* The header's spec; sizes kept small (at most 48^2, 16^3, 8^4 or 6^5
 * voxels, 32 chunk files, 256 innermost chunks of a level). */
static void
parse_header(reader *r, spec *s) {
    uint8_t h[Z3_HEADER];
    for (int i = 0; i < Z3_HEADER; i++)
        h[i] = (uint8_t)rd(r);
    memset(s, 0, sizeof *s);
    s->ndim = 2 + h[0] % 4;
    s->dtype = h[1] % N_DTYPES;
    s->endian = h[2] % 3;
    static const unsigned maxside[] = {0, 0, 48, 16, 8, 6};
    for (int i = 0; i < s->ndim; i++)
        s->shape[i] = 1 + h[3 + i] % maxside[s->ndim];
    for (int i = 0; i < s->ndim; i++)
        s->cs[0][i] = 1 + h[8 + i] % (s->shape[i] + 1);
    for (int i = 0; i < s->ndim && grid_count(s->shape, s->cs[0], s->ndim) > Z3_MAX_TOP; i++)
        s->cs[0][i] = s->shape[i];
    s->nshard = h[13] % 4;
    for (int l = 0; l < s->nshard; l++) {
        for (int i = 0; i < s->ndim; i++) {
            /* the (h % number of divisors)-th divisor of the outer size */
            const uint64_t outer = s->cs[l][i];
            uint64_t divs[64];
            int nd = 0;
            for (uint64_t d = 1; d <= outer && nd < 64; d++)
                if (outer % d == 0)
                    divs[nd++] = d;
            s->cs[l + 1][i] = divs[h[14 + 6 * l + i % 5] % nd];
        }
        const int f = h[14 + 6 * l + 5];
        s->index_start[l] = f & 1;
        s->index_crc[l] = (f >> 1) & 1;
        s->index_big[l] = (f >> 2) & 1;
        s->crc_bad[l] = (f >> 3) & 1;
        s->index_noendian[l] = (f >> 4) & 1;
    }
    /* at most Z3_MAX_INNER innermost chunks: axes left unsharded */
    for (int i = 0;
         i < s->ndim && grid_count(s->shape, s->cs[0], s->ndim) *
                                (prod(s->cs[0], s->ndim) / prod(s->cs[s->nshard], s->ndim)) >
                            Z3_MAX_INNER;
         i++)
        for (int l = 1; l <= s->nshard; l++)
            s->cs[l][i] = s->cs[0][i];
    s->transpose = h[32] & 1;
    unsigned sel = h[33];
    int left[ZR_MAX_DIM];
    for (int i = 0; i < s->ndim; i++)
        left[i] = i;
    for (int i = 0; i < s->ndim; i++) { /* a permutation by its Lehmer code */
        const int k = (int)(sel % (unsigned)(s->ndim - i));
        sel /= (unsigned)(s->ndim - i);
        s->order[i] = left[k];
        memmove(left + k, left + k + 1, sizeof(int) * (size_t)(s->ndim - i - 1 - k));
    }
    s->nb2b = h[34] % 4;
    for (int i = 0; i < 3; i++)
        s->b2b[i] = h[35 + i] % 4;
    s->cname = h[38];
    s->key = h[39] % 4;
    s->fill_kind = h[40] % 8;
    s->fill_num = h[41];
    s->dimnames = h[42] & 1;
    s->whole = (h[42] >> 3) & 1;
    s->ngff = (h[42] >> 1) % 3;
    s->seed = h[43];
    s->ask = h[44];
    s->n_ch = h[45] % 5 >= 2 ? h[45] % 5 : 0;
    for (int k = 0; k < 4; k++)
        s->ch[k] = (h[46] >> (2 * k)) & 3;
}

static const char *cnames[] = {"lz4", "zstd", "blosclz", "zlib", "lz4hc"};
static const char *shuffles[] = {"noshuffle", "shuffle", "bitshuffle"};

static json_t *chain_json(const spec *s, int level);

static json_t *
codec(const char *name, json_t *cfg) {
    json_t *c = json_pack("{s:s}", "name", name);
    if (cfg)
        json_object_set_new(c, "configuration", cfg);
    return c;
}

static json_t *
sharding_json(const spec *s, int l) {
    json_t *cs = json_array();
    for (int i = 0; i < s->ndim; i++)
        json_array_append_new(cs, json_integer((json_int_t)s->cs[l + 1][i]));
    json_t *ic = json_array();
    json_array_append_new(
        ic, codec("bytes", s->index_noendian[l]
                               ? NULL
                               : json_pack("{s:s}", "endian", s->index_big[l] ? "big" : "little")));
    if (s->index_crc[l])
        json_array_append_new(ic, codec("crc32c", NULL));
    return codec("sharding_indexed",
                 json_pack("{s:o,s:o,s:o,s:s}", "chunk_shape", cs, "codecs", chain_json(s, l + 1),
                           "index_codecs", ic, "index_location",
                           s->index_start[l] ? "start" : "end"));
}

/* The codecs of level @p level (the innermost: transpose, bytes, b2b). */
static json_t *
chain_json(const spec *s, int level) {
    json_t *c = json_array();
    if (level < s->nshard) {
        json_array_append_new(c, sharding_json(s, level));
        return c;
    }
    if (s->transpose) {
        json_t *o = json_array();
        for (int i = 0; i < s->ndim; i++)
            json_array_append_new(o, json_integer(s->order[i]));
        json_array_append_new(c, codec("transpose", json_pack("{s:o}", "order", o)));
    }
    json_array_append_new(
        c,
        codec("bytes",
              s->endian == 2 ? NULL : json_pack("{s:s}", "endian", s->endian ? "big" : "little")));
    for (int i = 0; i < s->nb2b; i++) {
        switch (s->b2b[i]) {
        case 0:
            json_array_append_new(c, codec("gzip", json_pack("{s:i}", "level", 1)));
            break;
        case 1:
            json_array_append_new(c,
                                  codec("zstd", json_pack("{s:i,s:b}", "level", 1, "checksum", 0)));
            break;
        case 2:
            json_array_append_new(
                c, codec("blosc", json_pack("{s:s,s:i,s:s,s:i,s:i}", "cname", cnames[s->cname % 5],
                                            "clevel", 1, "shuffle", shuffles[(s->cname / 5) % 3],
                                            "typesize", dtypes[s->dtype].size, "blocksize", 0)));
            break;
        default:
            json_array_append_new(c, codec("crc32c", NULL));
        }
    }
    return c;
}

static json_t *
fill_json(const spec *s) {
    char hex[24];
    switch (s->fill_kind) {
    case 0:
        return json_integer(s->fill_num);
    case 1:
        return json_string("NaN");
    case 2:
        return json_string("Infinity");
    case 3:
        return json_string("-Infinity");
    case 4:
        snprintf(hex, sizeof hex, "0x%0*x", dtypes[s->dtype].size * 2, s->fill_num);
        return json_string(hex);
    case 5:
        return json_boolean(s->fill_num & 1);
    case 6:
        return json_real(0.5);
    default:
        return json_null();
    }
}

static json_t *
array_json(const spec *s, const uint64_t *shape) {
    json_t *sh = json_array(), *cs = json_array();
    for (int i = 0; i < s->ndim; i++) {
        json_array_append_new(sh, json_integer((json_int_t)shape[i]));
        json_array_append_new(cs, json_integer((json_int_t)s->cs[0][i]));
    }
    json_t *j =
        json_pack("{s:i,s:s,s:o,s:s,s:{s:s,s:{s:o}},s:{s:s,s:{s:s}},s:o,s:o,s:{}}", "zarr_format",
                  3, "node_type", "array", "shape", sh, "data_type", dtypes[s->dtype].name,
                  "chunk_grid", "name", "regular", "configuration", "chunk_shape", cs,
                  "chunk_key_encoding", "name", s->key < 2 ? "default" : "v2", "configuration",
                  "separator", s->key == 0 || s->key == 3 ? "/" : ".", "fill_value", fill_json(s),
                  "codecs", chain_json(s, 0), "attributes");
    if (s->dimnames) {
        static const char *names[] = {"t", "c", "z", "y", "x"};
        json_t *dn = json_array();
        for (int i = 0; i < s->ndim; i++)
            json_array_append_new(dn, json_string(names[5 - s->ndim + i]));
        json_object_set_new(j, "dimension_names", dn);
    }
    return j;
}

static json_t *
group_json(const spec *s, int levels) {
    static const char *names[] = {"t", "c", "z", "y", "x"};
    static const char *types[] = {"time", "channel", "space", "space", "space"};
    json_t *axes = json_array(), *ds = json_array();
    for (int i = 0; i < s->ndim; i++) {
        const int k = 5 - s->ndim + i;
        json_array_append_new(axes, json_pack("{s:s,s:s}", "name", names[k], "type", types[k]));
    }
    for (int l = 0; l < levels; l++) {
        json_t *sc = json_array();
        for (int i = 0; i < s->ndim; i++)
            json_array_append_new(sc, json_real(5 - s->ndim + i >= 2 ? (double)(1 << l) : 1.0));
        char p[8];
        snprintf(p, sizeof p, "%d", l);
        json_array_append_new(ds,
                              json_pack("{s:s,s:[{s:s,s:o}]}", "path", p,
                                        "coordinateTransformations", "type", "scale", "scale", sc));
    }
    return json_pack("{s:i,s:s,s:{s:{s:s,s:[{s:s,s:o,s:o}]}}}", "zarr_format", 3, "node_type",
                     "group", "attributes", "ome", "version", "0.5", "multiscales", "name", "fuzz",
                     "axes", axes, "datasets", ds);
}

/* One element of value @p v in the data type's native (little-endian)
 * form into @p o. */
static void
put_elem(const spec *s, unsigned v, unsigned char *o) {
    const int es = dtypes[s->dtype].size;
    switch (s->dtype) {
    case 0:
        o[0] = v & 1;
        return;
    case 7: {
        const float f = (float)(v & 0xff) * 0.5f;
        memcpy(o, &f, 4);
        return;
    }
    case 8: {
        const double d = (double)(v & 0xff) * 0.25;
        memcpy(o, &d, 8);
        return;
    }
    case 11: {
        const uint16_t hb = (uint16_t)(0x3c00 + (v & 0xff)); /* float16 */
        memcpy(o, &hb, 2);
        return;
    }
    default: {
        const uint64_t x = v & 0x7f;
        memcpy(o, &x, (size_t)es); /* little-endian host (checked at start) */
    }
    }
}

/* The innermost chunk at @p origin encoded as the chain says into @p o. */
static void
encode_chunk(const spec *s, const uint64_t *origin, buf *o) {
    const int nd = s->ndim, es = dtypes[s->dtype].size;
    const uint64_t *cs = s->cs[s->nshard];
    const size_t n = (size_t)prod(cs, nd), nb = n * (size_t)es;
    unsigned char *a = malloc(nb ? nb : 1), *t = malloc(nb ? nb : 1);
    if (!a || !t)
        abort();
    uint64_t pos[ZR_MAX_DIM] = {0};
    for (size_t q = 0; q < n; q++) {
        uint64_t lin = 0;
        int inside = 1;
        for (int d = 0; d < nd; d++) {
            const uint64_t g = origin[d] + pos[d];
            inside &= g < s->shape[d];
            lin = lin * s->shape[d] + g;
        }
        put_elem(s, inside ? (unsigned)(lin * 7 + (unsigned)s->seed) : 0, a + q * (size_t)es);
        for (int d = nd - 1; d >= 0 && ++pos[d] == cs[d]; d--)
            pos[d] = 0;
    }
    if (s->transpose) { /* encoded axis d is input axis order[d] */
        uint64_t enc[ZR_MAX_DIM], st[ZR_MAX_DIM], e[ZR_MAX_DIM] = {0};
        for (int d = 0; d < nd; d++)
            enc[d] = cs[s->order[d]];
        st[nd - 1] = 1;
        for (int d = nd - 2; d >= 0; d--)
            st[d] = st[d + 1] * cs[d + 1];
        for (size_t q = 0; q < n; q++) {
            uint64_t src = 0;
            for (int d = 0; d < nd; d++)
                src += e[d] * st[s->order[d]];
            memcpy(t + q * (size_t)es, a + src * (size_t)es, (size_t)es);
            for (int d = nd - 1; d >= 0 && ++e[d] == enc[d]; d--)
                e[d] = 0;
        }
        memcpy(a, t, nb);
    }
    if (s->endian == 1 && es > 1)
        for (size_t q = 0; q < n; q++)
            for (int k = 0; k < es / 2; k++) {
                unsigned char *p = a + q * (size_t)es;
                const unsigned char x = p[k];
                p[k] = p[es - 1 - k];
                p[es - 1 - k] = x;
            }
    size_t m = nb;
    for (int i = 0; i < s->nb2b; i++) {
        const size_t cap = m + m / 2 + 1024;
        unsigned char *d = malloc(cap);
        if (!d)
            abort();
        size_t r = 0;
        switch (s->b2b[i]) {
        case 0: {
            z_stream z;
            memset(&z, 0, sizeof z);
            /* a small window and state: tiny chunks, and a cheap init under ASan */
            if (deflateInit2(&z, 1, Z_DEFLATED, 16 + 10, 2, Z_DEFAULT_STRATEGY) != Z_OK)
                abort();
            z.next_in = a;
            z.avail_in = (uInt)m;
            z.next_out = d;
            z.avail_out = (uInt)cap;
            if (deflate(&z, Z_FINISH) != Z_STREAM_END)
                abort();
            r = cap - z.avail_out;
            deflateEnd(&z);
            break;
        }
        case 1: {
            static ZSTD_CCtx *zc; /* one context for every input */
            if (!zc && !(zc = ZSTD_createCCtx()))
                abort();
            r = ZSTD_compressCCtx(zc, d, cap, a, m, 1);
            if (ZSTD_isError(r))
                abort();
            break;
        }
        case 2: {
            const int c = blosc_compress_ctx(1, (int)((s->cname / 5) % 3), (size_t)es, m, a, d, cap,
                                             cnames[s->cname % 5], 0, 1);
            r = c > 0 ? (size_t)c : 0;
            break;
        }
        default: {
            memcpy(d, a, m);
            const uint32_t c = vv_crc32c(0, a, m);
            for (int k = 0; k < 4; k++)
                d[m + (size_t)k] = (unsigned char)(c >> (8 * k));
            r = m + 4;
        }
        }
        free(a);
        a = d;
        m = r;
    }
    buf_put(o, a, m);
    free(a);
    free(t);
}

/* A chunk as the tweak byte says (1: absent). */
static int
chunk_bytes(const spec *s, reader *r, const uint64_t *origin, buf *o, int *empty_file) {
    const unsigned t = rd(r) % 16;
    *empty_file = 0;
    if (t == 11 || t == 12) {
        *empty_file = t == 12;
        return 1;
    }
    if (t == 13) { /* raw bytes of the input */
        size_t n = rd16(r);
        if (n > r->n - r->at)
            n = r->n - r->at;
        buf_put(o, r->p + r->at, n);
        r->at += n;
        return 0;
    }
    const size_t start = o->n;
    encode_chunk(s, origin, o);
    const size_t len = o->n - start;
    if (t == 14) {
        const size_t cut = rd(r) + 1u;
        o->n = start + (cut < len ? len - cut : 0);
    } else if (t == 15 && len) {
        const size_t at = rd(r) % len;
        o->b[start + at] ^= (unsigned char)(rd(r) | 1);
    }
    return 0;
}

static void
put64(unsigned char *p, uint64_t v, int big) {
    for (int k = 0; k < 8; k++)
        p[big ? 7 - k : k] = (unsigned char)(v >> (8 * k));
}

/* The shard of level @p l at @p origin (its inner chunks, its index) into
 * @p o; 1 when its file is to be absent (level 0). */
static int
encode_shard(const spec *s, reader *r, int l, const uint64_t *origin, buf *o) {
    const int nd = s->ndim;
    const unsigned t = rd(r) % 16;
    if (t == 11 && l == 0)
        return 1;
    uint64_t per[ZR_MAX_DIM], pos[ZR_MAX_DIM] = {0};
    for (int d = 0; d < nd; d++)
        per[d] = s->cs[l][d] / s->cs[l + 1][d];
    const uint64_t count = prod(per, nd);
    uint64_t *ent = calloc((size_t)count * 2, 8);
    if (!ent)
        abort();
    buf body = {0};
    for (uint64_t q = 0; q < count; q++) {
        uint64_t org[ZR_MAX_DIM];
        for (int d = 0; d < nd; d++)
            org[d] = origin[d] + pos[d] * s->cs[l + 1][d];
        const size_t start = body.n;
        int absent = 0, empty_file;
        if (l + 1 < s->nshard)
            absent = encode_shard(s, r, l + 1, org, &body);
        else
            absent = chunk_bytes(s, r, org, &body, &empty_file);
        ent[2 * q] = absent ? UINT64_MAX : start;
        ent[2 * q + 1] = absent ? UINT64_MAX : body.n - start;
        for (int d = nd - 1; d >= 0 && ++pos[d] == per[d]; d--)
            pos[d] = 0;
    }
    const size_t ib = (size_t)count * 16 + (s->index_crc[l] ? 4 : 0);
    if (s->index_start[l])
        for (uint64_t q = 0; q < count; q++)
            if (ent[2 * q] != UINT64_MAX)
                ent[2 * q] += ib;
    switch (t) {
    case 12:
        ent[2 * (rd(r) % count)] += rd(r);
        break;
    case 13: {
        const uint64_t a = rd(r) % count, b = rd(r) % count;
        const uint64_t x0 = ent[2 * a], x1 = ent[2 * a + 1];
        ent[2 * a] = ent[2 * b];
        ent[2 * a + 1] = ent[2 * b + 1];
        ent[2 * b] = x0;
        ent[2 * b + 1] = x1;
        break;
    }
    case 14:
        ent[2 * (rd(r) % count) + 1] = rd(r);
        break;
    case 15: {
        const uint64_t k = rd(r) % count;
        ent[2 * k] = rd16(r);
        ent[2 * k + 1] = rd16(r);
        break;
    }
    default:
        break;
    }
    unsigned char *ix = malloc(ib);
    if (!ix)
        abort();
    const int big = s->index_big[l] && !s->index_noendian[l];
    for (uint64_t q = 0; q < 2 * count; q++)
        put64(ix + 8 * q, ent[q], big);
    if (s->index_crc[l]) {
        uint32_t c = vv_crc32c(0, ix, (size_t)count * 16);
        if (s->crc_bad[l])
            c ^= 1u << (s->seed % 32);
        for (int k = 0; k < 4; k++)
            ix[count * 16 + (uint64_t)k] = (unsigned char)(c >> (8 * k));
    }
    if (s->index_start[l])
        buf_put(o, ix, ib);
    buf_put(o, body.b, body.n);
    if (!s->index_start[l])
        buf_put(o, ix, ib);
    free(ix);
    free(body.b);
    free(ent);
    return 0;
}

/* @p merge's keys set into @p j (a null value removes the key). */
static void
merge_into(json_t *j, json_t *merge) {
    const char *k;
    json_t *v;
    json_object_foreach(merge, k, v) {
        if (json_is_null(v))
            json_object_del(j, k);
        else
            json_object_set(j, k, v);
    }
}

static void
mkdirs_write(const char *path, const void *b, size_t n) {
    char p[1024];
    snprintf(p, sizeof p, "%s", path);
    for (char *c = p + 1; (c = strchr(c, '/')) != NULL; c++) {
        *c = '\0';
        if (mkdir(p, 0700) != 0 && errno != EEXIST) {
            perror("fuzz: mkdir");
            abort();
        }
        *c = '/';
    }
    const int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd < 0) {
        perror("fuzz: writing a store's file");
        abort();
    }
    size_t done = 0;
    while (done < n) {
        const ssize_t w = write(fd, (const char *)b + done, n - done);
        if (w <= 0) {
            perror("fuzz: writing a store's file");
            abort();
        }
        done += (size_t)w;
    }
    close(fd);
}

static void
write_json(const char *path, json_t *j) {
    char *txt = json_dumps(j, JSON_COMPACT);
    if (!txt)
        abort();
    mkdirs_write(path, txt, strlen(txt));
    free(txt);
}

/* One array (level folder @p dir, of shape @p shape) written. */
static void
write_array(const spec *s, reader *r, const char *dir, const uint64_t *shape, json_t *merge) {
    spec a = *s;
    memcpy(a.shape, shape, sizeof a.shape);
    json_t *j = array_json(&a, shape);
    if (merge)
        merge_into(j, merge);
    char p[1024];
    snprintf(p, sizeof p, "%s/zarr.json", dir);
    write_json(p, j);
    json_decref(j);
    const int nd = a.ndim;
    uint64_t grid[ZR_MAX_DIM], pos[ZR_MAX_DIM] = {0};
    for (int d = 0; d < nd; d++)
        grid[d] = (a.shape[d] + a.cs[0][d] - 1) / a.cs[0][d];
    const uint64_t n = prod(grid, nd);
    for (uint64_t q = 0; q < n; q++) {
        uint64_t origin[ZR_MAX_DIM];
        for (int d = 0; d < nd; d++)
            origin[d] = pos[d] * a.cs[0][d];
        buf o = {0};
        int absent, empty_file = 0;
        if (a.nshard)
            absent = encode_shard(&a, r, 0, origin, &o);
        else
            absent = chunk_bytes(&a, r, origin, &o, &empty_file);
        if (!absent || empty_file) {
            const char *sep = a.key == 0 || a.key == 3 ? "/" : ".";
            int len = snprintf(p, sizeof p, "%s/%s", dir, a.key < 2 ? "c" : "");
            for (int d = 0; d < nd; d++)
                len += snprintf(p + len, sizeof p - (size_t)len, "%s%llu",
                                d || a.key < 2 ? sep : "", (unsigned long long)pos[d]);
            mkdirs_write(p, o.b, o.n);
        }
        free(o.b);
        for (int d = nd - 1; d >= 0 && ++pos[d] == grid[d]; d--)
            pos[d] = 0;
    }
}

static void
open_store(const char *root, vv_open_mode mode, int level, vv_cache *cache, const spec *s) {
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = mode;
    oo.load.format = VV_FORMAT_OME_ZARR;
    oo.load.level = level;
    oo.cache = cache;
    if (s) { /* several channels at once, out of core */
        oo.n_channels = s->n_ch;
        for (int k = 0; k < s->n_ch; k++)
            oo.channels[k] = s->ch[k];
    }
    vv_opened o;
    memset(&o, 0, sizeof o);
    const vv_status st = vv_open(&o, root, &oo);
    fuzz_check_status(st);
    if (st != VV_OK)
        return;
    if (o.kind != VV_DATA_VOLUME || !o.source)
        __builtin_trap(); /* a store holds a volume */
    fuzz_read_source(o.source);
    const int nc = vv_source_channels(o.source);
    /* a source has 1 .. VV_MAX_CHANNELS channels */
    if (s && (nc < 1 || nc > VV_MAX_CHANNELS))
        __builtin_trap();
    /* the other channels: a box of the coarsest level, its proxy */
    for (int c = 1; s && c < nc; c++) {
        const int l = vv_source_levels(o.source) - 1;
        const vv_volume *h = vv_source_channel_level(o.source, c, l);
        if (!h)
            __builtin_trap(); /* a channel the source counts has its levels */
        const int lo[3] = {0, 0, 0};
        const int hi[3] = {h->dims[0] - 1, h->dims[1] - 1, h->dims[2] - 1};
        vv_volume *v = NULL;
        vv_status cst = vv_source_channel_read_box(o.source, c, l, lo, hi, &v);
        fuzz_check_status(cst);
        if (cst == VV_OK)
            fuzz_check_volume(v);
        v = NULL;
        cst = vv_source_channel_proxy(o.source, c, l, &v);
        fuzz_check_status(cst);
        if (cst == VV_OK)
            fuzz_check_volume(v);
    }
    vv_opened_clear(&o);
}

/* A JSON object of @p n bytes, or NULL (none, not an object). */
static json_t *
load_object(const uint8_t *p, size_t n) {
    json_t *j = n ? json_loadb((const char *)p, n, JSON_DECODE_ANY, NULL) : NULL;
    if (j && !json_is_object(j)) {
        json_decref(j);
        j = NULL;
    }
    return j;
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static vv_cache *cache;
    if (!cache) {
        const uint16_t one = 1;
        if (*(const uint8_t *)&one != 1)
            __builtin_trap(); /* the encoder writes the host's order as little-endian */
        vv_memory_budget_set(Z3_BUDGET);
        if (vv_cache_new(&cache, Z3_BUDGET) != VV_OK)
            __builtin_trap();
    }
    const uint8_t *desc, *js, *gjs;
    size_t ndesc, njs, ngjs;
    fuzz_split(data, size, "\n--JSON--\n", &desc, &ndesc, &js, &njs);
    fuzz_split(js, njs, "\n--GROUP--\n", &js, &njs, &gjs, &ngjs);
    json_t *merge = load_object(js, njs), *gmerge = load_object(gjs, ngjs);
    reader r = {desc, ndesc, 0};
    spec s;
    parse_header(&r, &s);
    char root[512], dir[600];
    snprintf(root, sizeof root, "%s/in.zarr", fuzz_dir());
    fuzz_rm_tree(root);
    if (mkdir(root, 0700) != 0) {
        perror("fuzz: mkdir store");
        abort();
    }
    if (!s.ngff) {
        write_array(&s, &r, root, s.shape, merge);
    } else {
        const int levels = s.ngff;
        json_t *g = group_json(&s, levels);
        if (gmerge)
            merge_into(json_object_get(json_object_get(g, "attributes"), "ome"), gmerge);
        snprintf(dir, sizeof dir, "%s/zarr.json", root);
        write_json(dir, g);
        json_decref(g);
        uint64_t shape[ZR_MAX_DIM];
        memcpy(shape, s.shape, sizeof shape);
        for (int l = 0; l < levels; l++) {
            snprintf(dir, sizeof dir, "%s/%d", root, l);
            write_array(&s, &r, dir, shape, l ? NULL : merge);
            for (int d = 0; d < s.ndim; d++) /* the spatial axes halved */
                if (5 - s.ndim + d >= 2)
                    shape[d] = (shape[d] + 1) / 2;
        }
    }
    json_decref(merge);
    json_decref(gmerge);
    /* the level asked: one past the last (refused) once in eight */
    const int level = !s.ngff ? 0 : s.ask % 8 == 7 ? s.ngff : s.ask % s.ngff;
    vv_load_options lo;
    vv_load_options_init(&lo);
    vv_load_info info;
    memset(&info, 0, sizeof info);
    lo.level = level;
    lo.info = &info;
    vv_volume *v = NULL;
    const vv_status st = vv_ome_zarr_read(&v, root, &lo);
    fuzz_check_status(st);
    if (st == VV_OK)
        fuzz_check_volume(v);
    if (s.whole) /* mostly vv_ome_zarr_read's path again: not every input */
        open_store(root, VV_OPEN_WHOLE, level, cache, NULL);
    open_store(root, VV_OPEN_OUT_OF_CORE, level, cache, NULL);
    if (s.n_ch)
        open_store(root, VV_OPEN_OUT_OF_CORE, level, cache, &s);
    fuzz_rm_tree(root);
    return 0;
}
