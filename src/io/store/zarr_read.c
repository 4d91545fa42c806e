/*
 * OME-Zarr / Zarr v2 reader: one channel at one time step of the full
 * resolution level as a volume (vv_volume_load's contract).
 *
 * A store is a folder. Its root .zattrs holds the OME-NGFF multiscales
 * metadata (0.4: "axes" objects with name, type and unit; 0.3: axis names;
 * older: none, the axes then t, c, z, y, x of a 5-D array), the first
 * dataset's path is level 0 and its coordinateTransformations (scale, then
 * an optional translation; multiplied by the multiscale's own) give the
 * spacing and origin of the spatial axes and the time between steps. The
 * omero block names and colours the channels. A folder with a .zarray and
 * no multiscales is a plain 3-D array (z, y, x).
 *
 * The array's .zarray (Zarr v2 spec): shape, chunks, dtype ("<u2", ">f4",
 * "|u1": u1 u2 u4 i1 i2 i4 f4 f8, either byte order), compressor (null,
 * zlib, gzip, zstd, blosc with any of its inner codecs and shuffles), C
 * order, no filters, fill_value, dimension_separator "." or "/". Chunks
 * are files named by their indices; a missing chunk is the fill value. Only
 * the chunks holding the asked channel and step are read, each checked to
 * decode to exactly the chunk's size.
 *
 * Axes: two or three spatial ones (type "space", or named x, y, z), at most
 * one "channel" (or c) and one "time" (or t) axis, in any order. Every size
 * is checked against the limits before anything is allocated; JSON files
 * over 16 MiB and chunks over 1 GiB are refused.
 *
 * Zarr v3 (OME-NGFF 0.5: the root's zarr.json, a group with
 * attributes.ome, or an array) is parsed and decoded by zarr3.c through
 * the same zr_array: the read unit of a sharded array is its inner chunk.
 * Every byte read of the store goes through zr_store_get (a key beneath
 * the root, an offset and a length), the one place a remote byte source
 * will take.
 */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <blosc.h>
#include <jansson.h>
#include <omp.h>
#include <zlib.h>
#include <zstd.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/zarr.h"

/* 1 when the real path @p real lies in or beneath the real folder @p dir. */
static int
zr_beneath(const char *real, const char *dir) {
    const size_t n = strlen(dir);
    return !strncmp(real, dir, n) &&
           (real[n] == '/' || real[n] == '\0' || (n == 1 && dir[0] == '/'));
}

vv_status
zr_store_get(const zr_array *a, const char *key, uint64_t off, uint64_t len, uint64_t max,
             unsigned char **out, size_t *n, uint64_t *size, int *missing) {
    bs_get g = {.key = key, .off = off, .len = len, .max = max};
    const vv_status s = zr_store_get_many(a, &g, 1);
    *out = g.out;
    *n = g.n;
    if (size)
        *size = g.size;
    if (missing)
        *missing = g.missing;
    if (s == VV_OK && g.missing && !missing)
        return vv_error_set(VV_ERR_FORMAT, "no %s", key);
    return s;
}

vv_status
zr_store_get_many(const zr_array *a, bs_get *g, int n) {
    if (bs_is_url(a->root)) {
        vv_bytesrc *src = bs_remote(a->root);
        return src ? src->ops->get_many(src, g, n) : VV_ERR_INVALID;
    }
    bs_local loc;
    bs_local_init(&loc, a->root, a->real);
    return loc.base.ops->get_many(&loc.base, g, n);
}

/* ---- a remote store's metadata, kept a moment ------------------------------------------ */

/* The JSON documents of remote stores (zarr.json, .zattrs, .zarray) fetched
 * in the last ZR_MEMO_SECONDS, absent ones too, keyed by the store's URL
 * and the key: opening a pyramid parses the root's document once for every
 * level, and the levels' own documents are fetched together
 * (prefetch_levels), so that an open is a few round trips, not two a
 * level. Older entries are fetched again (a store that changes is seen as
 * it is 10 s later). At most ZR_MEMO_N documents of up to ZR_MEMO_MAX
 * bytes; the oldest replaced. One mutex. */
#define ZR_MEMO_N 64
#define ZR_MEMO_MAX ((size_t)1 << 20)
#define ZR_MEMO_SECONDS 10.0

typedef struct zr_memo {
    char *url;
    unsigned char *b;
    size_t n;
    int missing;
    double t;
} zr_memo;

static zr_memo memo[ZR_MEMO_N];
static pthread_mutex_t memo_lock = PTHREAD_MUTEX_INITIALIZER;

static double
memo_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static char *
memo_url(const zr_array *a, const char *key) {
    const size_t n = strlen(a->root) + strlen(key) + 2;
    char *u = malloc(n);
    if (u)
        snprintf(u, n, "%s/%s", a->root, key);
    return u;
}

/* 1 and a copy of the document (*b, *n; free it) or its absence when
 * @p key of @p a's store was fetched lately; @p b NULL: only whether it
 * was (nothing copied). */
static int
memo_get(const zr_array *a, const char *key, unsigned char **b, size_t *n, int *missing) {
    char *u = memo_url(a, key);
    int hit = 0;
    pthread_mutex_lock(&memo_lock);
    const double now = memo_now();
    for (int i = 0; u && i < ZR_MEMO_N && !hit; i++) {
        const zr_memo *m = &memo[i];
        if (!m->url || strcmp(m->url, u) || now - m->t > ZR_MEMO_SECONDS)
            continue;
        if (b) {
            *b = m->missing ? NULL : malloc(m->n ? m->n : 1);
            if (!m->missing && !*b)
                break;
            if (*b)
                memcpy(*b, m->b, m->n);
            *n = m->missing ? 0 : m->n;
            *missing = m->missing;
        }
        hit = 1;
    }
    pthread_mutex_unlock(&memo_lock);
    free(u);
    return hit;
}

/* Keeps document @p key of @p a's store (@p b, @p n; copied) or its
 * absence. */
static void
memo_put(const zr_array *a, const char *key, const unsigned char *b, size_t n, int missing) {
    if (n > ZR_MEMO_MAX)
        return;
    char *u = memo_url(a, key);
    unsigned char *c = missing ? NULL : malloc(n ? n : 1);
    if (!u || (!missing && !c)) {
        free(u);
        free(c);
        return;
    }
    if (c)
        memcpy(c, b, n);
    pthread_mutex_lock(&memo_lock);
    int k = 0; /* the same URL's entry, else a free one, else the oldest */
    for (int i = 0; i < ZR_MEMO_N; i++) {
        if (memo[i].url && !strcmp(memo[i].url, u)) {
            k = i;
            break;
        }
        if (!memo[i].url ? memo[k].url != NULL : memo[k].url && memo[i].t < memo[k].t)
            k = i;
    }
    free(memo[k].url);
    free(memo[k].b);
    memo[k] = (zr_memo){u, c, n, missing, memo_now()};
    pthread_mutex_unlock(&memo_lock);
}

/* The documents of @p count levels (the datasets @p dsl of the store's
 * multiscales) fetched together into the memo when the store is remote:
 * each level's zarr.json, and its .zarray for a Zarr v2 store. What fails
 * is left out: the level's own read reports it. */
static void
prefetch_levels(const zr_array *a, json_t *dsl, int count) {
    if (!bs_is_url(a->root) || count < 2 || a->zarr_format == ZR_PRECOMPUTED)
        return; /* (a precomputed volume's levels are all in its info) */
    const int per = a->zarr_format == 2 ? 2 : 1;
    bs_get *g = calloc((size_t)(count * per), sizeof *g);
    char *keys = malloc((size_t)(count * per) * 1100);
    int n = 0;
    for (int i = 0; g && keys && i < count; i++) {
        const char *p = json_string_value(json_object_get(json_array_get(dsl, (size_t)i), "path"));
        for (int f = 0; p && f < per; f++) {
            char *k = keys + (size_t)n * 1100;
            snprintf(k, 1100, "%s/%s", p,
                     a->zarr_format == ZR_N5 ? "attributes.json"
                     : f                     ? ".zarray"
                                             : "zarr.json");
            if (memo_get(a, k, NULL, NULL, NULL))
                continue; /* fetched lately */
            g[n++] = (bs_get){.key = k, .off = 0, .len = ZR_ALL, .max = ZR_JSON_MAX};
        }
    }
    if (n > 0 && zr_store_get_many(a, g, n) == VV_OK)
        for (int i = 0; i < n; i++) {
            memo_put(a, g[i].key, g[i].out, g[i].n, g[i].missing);
            free(g[i].out);
        }
    vv_error_clear();
    free(g);
    free(keys);
}

/* Python's json (zarr-python, ome-zarr-py) writes a NaN or an infinity in
 * user attributes (an omero window) as the bare words NaN, Infinity and
 * -Infinity, which are not JSON and which Jansson refuses: each such word
 * outside a string becomes "[]" and spaces (the same length, so that
 * Jansson's line and column still point at the file's text), a value that
 * is no number, which the readers then ignore or refuse by name. */
static void
zr_json_nonfinite(char *b, size_t n) {
    int in_string = 0;
    for (size_t i = 0; i < n; i++) {
        if (in_string) {
            if (b[i] == '\\')
                i++;
            else if (b[i] == '"')
                in_string = 0;
            continue;
        }
        if (b[i] == '"') {
            in_string = 1;
            continue;
        }
        size_t len = 0;
        if (n - i >= 3 && !memcmp(b + i, "NaN", 3))
            len = 3;
        else if (n - i >= 8 && !memcmp(b + i, "Infinity", 8))
            len = 8;
        else if (n - i >= 9 && !memcmp(b + i, "-Infinity", 9))
            len = 9;
        /* a bare word: not the tail of a longer one */
        if (!len || (i > 0 && (isalnum((unsigned char)b[i - 1]) || b[i - 1] == '_')) ||
            (i + len < n && (isalnum((unsigned char)b[i + len]) || b[i + len] == '_')))
            continue;
        b[i] = '[';
        b[i + 1] = ']';
        memset(b + i + 2, ' ', len - 2);
        i += len - 1;
    }
}

/* The object @p key of the store loaded as JSON (at most ZR_JSON_MAX
 * bytes); NULL with the error set (naming @p name), or NULL without an
 * error when the object is absent and @p optional. */
static json_t *load_json(const zr_array *a, const char *key, const char *name, int optional,
                         vv_status *s);

void *
zr_load_json(const zr_array *a, const char *key, const char *name, int optional, vv_status *s) {
    return load_json(a, key, name, optional, s);
}

static json_t *
load_json(const zr_array *a, const char *key, const char *name, int optional, vv_status *s) {
    unsigned char *b = NULL;
    size_t n = 0;
    int missing = 0;
    const int remote = bs_is_url(a->root);
    if (remote && memo_get(a, key, &b, &n, &missing))
        *s = VV_OK;
    else {
        *s = zr_store_get(a, key, 0, ZR_ALL, ZR_JSON_MAX, &b, &n, NULL, &missing);
        if (*s == VV_OK && remote)
            memo_put(a, key, b, n, missing);
    }
    if (*s == VV_OK && missing && !optional)
        *s = vv_error_set(VV_ERR_FORMAT, "no %s (not a Zarr array)", name);
    if (*s != VV_OK || missing)
        return NULL;
    json_error_t e;
    zr_json_nonfinite((char *)b, n);
    json_t *j = json_loadb((const char *)b, n, JSON_REJECT_DUPLICATES, &e);
    free(b);
    if (!j)
        *s = vv_error_set(VV_ERR_FORMAT, "%s: line %d: %s", name, e.line, e.text);
    return j;
}

/* The key of @p name in the array's folder. */
static void
array_key(const zr_array *a, const char *name, char *k, size_t cap) {
    snprintf(k, cap, "%s%s%s", a->prefix, a->prefix[0] ? "/" : "", name);
}

static vv_status
parse_dtype(const char *d, zr_array *a) {
    if (!d || strlen(d) != 3 || !strchr("<>|", d[0]))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            ".zarray: dtype \"%s\" (supported: u1 u2 u4 i1 i2 "
                            "i4 f4 f8, either byte order)",
                            d ? d : "(none)");
    static const struct {
        const char *k;
        vv_voxel_type t;
    } map[] = {{"u1", VV_U8},  {"i1", VV_I8},  {"u2", VV_U16}, {"i2", VV_I16},
               {"u4", VV_U32}, {"i4", VV_I32}, {"f4", VV_F32}, {"f8", VV_F64}};
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcmp(d + 1, map[i].k)) {
            a->type = map[i].t;
            a->esize = vv_voxel_type_size(a->type);
            a->swap = a->esize > 1 && (d[0] == '>') == vv_host_is_little_endian();
            return VV_OK;
        }
    return vv_error_set(VV_ERR_UNSUPPORTED,
                        ".zarray: dtype \"%s\" (supported: u1 u2 u4 i1 i2 i4 f4 f8)", d);
}

/* The array metadata of @p a's folder into @p a: its zarr.json (Zarr v3)
 * or else its .zarray. */
static vv_status
parse_zarray(zr_array *a) {
    vv_status s;
    char key[1100];
    if (a->zarr_format == ZR_PRECOMPUTED) { /* a scale of the root's info */
        json_t *j = load_json(a, "info", "info", 0, &s);
        if (!j)
            return s;
        s = zr_pc_parse_array(a, j);
        json_decref(j);
        return s;
    }
    if (a->zarr_format == ZR_N5) { /* an N5 level or dataset: n5.c */
        array_key(a, "attributes.json", key, sizeof key);
        json_t *j = load_json(a, key, "attributes.json", 0, &s);
        if (!j)
            return s;
        s = zr_n5_parse_array(a, j);
        json_decref(j);
        return s;
    }
    array_key(a, "zarr.json", key, sizeof key);
    json_t *j = load_json(a, key, "zarr.json", 1, &s);
    if (s != VV_OK)
        return s;
    if (j) {
        s = zr3_parse_array(a, j);
        json_decref(j);
        return s;
    }
    if (a->zarr_format == 3) /* an OME-Zarr 0.5 group's level */
        return vv_error_set(VV_ERR_FORMAT, "no %s (not a Zarr v3 array)", key);
    a->zarr_format = 2;
    array_key(a, ".zarray", key, sizeof key);
    j = load_json(a, key, ".zarray", 0, &s);
    if (!j)
        return s;
    json_t *shape = json_object_get(j, "shape"), *chunks = json_object_get(j, "chunks");
    json_t *comp = json_object_get(j, "compressor"), *filt = json_object_get(j, "filters");
    json_t *fmt = json_object_get(j, "zarr_format"), *order = json_object_get(j, "order");
    json_t *fill = json_object_get(j, "fill_value"),
           *sep = json_object_get(j, "dimension_separator");
    s = VV_OK;
    if (!json_is_integer(fmt) || json_integer_value(fmt) != 2)
        s = vv_error_set(VV_ERR_UNSUPPORTED, ".zarray: zarr_format is not 2");
    else if (!json_is_array(shape) || !json_is_array(chunks) ||
             json_array_size(shape) != json_array_size(chunks) || json_array_size(shape) < 2 ||
             json_array_size(shape) > ZR_MAX_DIM)
        s = vv_error_set(VV_ERR_FORMAT,
                         ".zarray: shape and chunks must be arrays of 2 to %d sizes, alike",
                         ZR_MAX_DIM);
    else if (order && (!json_is_string(order) || strcmp(json_string_value(order), "C")))
        s = vv_error_set(VV_ERR_UNSUPPORTED, ".zarray: order \"%s\" (only C order is read)",
                         json_is_string(order) ? json_string_value(order) : "?");
    else if (filt && !json_is_null(filt) && !(json_is_array(filt) && json_array_size(filt) == 0))
        s = vv_error_set(VV_ERR_UNSUPPORTED, ".zarray: filters are not supported");
    if (s == VV_OK) {
        a->ndim = (int)json_array_size(shape);
        for (int i = 0; i < a->ndim && s == VV_OK; i++) {
            json_t *x = json_array_get(shape, (size_t)i), *c = json_array_get(chunks, (size_t)i);
            if (!json_is_integer(x) || !json_is_integer(c) || json_integer_value(x) < 1 ||
                json_integer_value(c) < 1 || json_integer_value(x) > (1LL << 40) ||
                json_integer_value(c) > (1LL << 40))
                s = vv_error_set(VV_ERR_FORMAT, ".zarray: axis %d: shape or chunk size not a size",
                                 i);
            else {
                a->shape[i] = (uint64_t)json_integer_value(x);
                a->chunks[i] = (uint64_t)json_integer_value(c);
            }
        }
    }
    if (s == VV_OK)
        s = parse_dtype(json_string_value(json_object_get(j, "dtype")), a);
    if (s == VV_OK) {
        a->codec[0] = '\0';
        if (comp && !json_is_null(comp)) {
            const char *id = json_string_value(json_object_get(comp, "id"));
            if (!id || (strcmp(id, "zlib") && strcmp(id, "gzip") && strcmp(id, "zstd") &&
                        strcmp(id, "blosc")))
                s = vv_error_set(VV_ERR_UNSUPPORTED,
                                 ".zarray: compressor \"%s\" (supported: zlib, gzip, zstd, blosc)",
                                 id ? id : "?");
            else
                snprintf(a->codec, sizeof a->codec, "%s", id);
        }
        a->sep = '.';
        if (sep && json_is_string(sep) && !strcmp(json_string_value(sep), "/"))
            a->sep = '/';
        else if (sep && !(json_is_string(sep) && !strcmp(json_string_value(sep), ".")))
            s = vv_error_set(VV_ERR_FORMAT, ".zarray: dimension_separator is not \".\" or \"/\"");
        a->fill = 0;
        const char *fs = json_string_value(fill);
        if (json_is_number(fill))
            a->fill = json_number_value(fill);
        else if (fs && !strcmp(fs, "NaN"))
            a->fill = NAN;
        else if (fs && !strcmp(fs, "Infinity"))
            a->fill = INFINITY;
        else if (fs && !strcmp(fs, "-Infinity"))
            a->fill = -INFINITY;
        else if (s == VV_OK && fill && !json_is_null(fill))
            s = vv_error_set(VV_ERR_FORMAT, ".zarray: fill_value is not a number, null, \"NaN\" or "
                                            "\"Infinity\"");
    }
    json_decref(j);
    return s;
}

static int
axis_kind(const char *name, const char *type) {
    if (type && !strcmp(type, "channel"))
        return 1;
    if (type && !strcmp(type, "time"))
        return 2;
    if (type && !strcmp(type, "space"))
        return 0;
    if (!strcmp(name, "c"))
        return 1;
    if (!strcmp(name, "t"))
        return 2;
    if (!strcmp(name, "x") || !strcmp(name, "y") || !strcmp(name, "z"))
        return 0;
    return -1;
}

/* scale (and translation) of one coordinateTransformations list into
 * sc/tr (multiplied, added: nested levels compose). A scale or translation
 * that is not @p ndim numbers, a scale that is not positive and finite:
 * VV_ERR_FORMAT naming @p where (a zero or non-finite spacing is never
 * taken). Other transform types are ignored. */
static vv_status
apply_transforms(json_t *list, int ndim, double *sc, double *tr, const char *md,
                 const char *where) {
    size_t i;
    json_t *t;
    json_array_foreach(list, i, t) {
        const char *type = json_string_value(json_object_get(t, "type"));
        if (!type || (strcmp(type, "scale") && strcmp(type, "translation")))
            continue;
        const int scale = !strcmp(type, "scale");
        json_t *v = json_object_get(t, type);
        if (!json_is_array(v) || (int)json_array_size(v) != ndim)
            return vv_error_set(VV_ERR_FORMAT, "%s: %s: the %s is not %d numbers", md, where, type,
                                ndim);
        for (int k = 0; k < ndim; k++) {
            json_t *n = json_array_get(v, (size_t)k);
            const double x = json_number_value(n);
            if (!json_is_number(n) || !isfinite(x) || (scale && !(x > 0)))
                return vv_error_set(VV_ERR_FORMAT, "%s: %s: %s %d is not a %s number", md, where,
                                    type, k, scale ? "positive finite" : "finite");
            /* x' = s x (the translation so far scaled too), x' = x + t */
            if (scale) {
                sc[k] *= x;
                tr[k] *= x;
            } else {
                tr[k] += x;
            }
            if (!isfinite(sc[k]) || !(sc[k] > 0) || !isfinite(tr[k]))
                return vv_error_set(VV_ERR_FORMAT,
                                    "%s: %s: the composed %s along axis %d is not finite "
                                    "and positive",
                                    md, where,
                                    isfinite(sc[k]) && sc[k] > 0 ? "translation" : "scale", k);
        }
    }
    return VV_OK;
}

/* The store's OME metadata into *za (a new reference; NULL: a plain
 * array): the root's zarr.json (Zarr v3: a group's attributes.ome, or an
 * array) or else its .zattrs, or else an N5 store's attributes.json (a
 * dataset, or a multiscale group as the multiscales it amounts to); *md
 * names the file. */
static vv_status
root_metadata(const zr_array *a, json_t **za, const char **md) {
    vv_status s = VV_OK;
    *za = NULL;
    *md = ".zattrs";
    /* Neuroglancer's precomputed:// and n5:// name the format: its
     * metadata alone is asked for */
    const char *only = bs_url_format(a->root);
    const int pc_only = only && !strcmp(only, "precomputed");
    const int n5_only = only && !strcmp(only, "n5");
    json_t *z3 = pc_only || n5_only ? NULL : load_json(a, "zarr.json", "zarr.json", 1, &s);
    if (s != VV_OK)
        return s;
    if (!z3) {
        *za = pc_only || n5_only ? NULL : load_json(a, ".zattrs", ".zattrs", 1, &s);
        if (s != VV_OK || *za)
            return s;
        /* N5: a dataset, or a multiscale group read as OME-NGFF (n5.c) */
        json_t *n5 = pc_only ? NULL : load_json(a, "attributes.json", "attributes.json", 1, &s);
        if (s != VV_OK)
            return s;
        json_t *info = n5 || n5_only ? NULL : load_json(a, "info", "info", 1, &s);
        if (s != VV_OK)
            return s;
        if (info) { /* Neuroglancer precomputed: its info (precomputed.c) */
            *md = "info";
            void *ms = NULL;
            s = zr_pc_root(a, info, &ms);
            *za = ms;
            json_decref(info);
            return s;
        }
        if (!n5 && !pc_only) {
            /* an N5 multiscale group without attributes (BigDataViewer's
             * timepoint groups): its dataset s0 says */
            json_t *s0 = load_json(a, "s0/attributes.json", "s0/attributes.json", 1, &s);
            if (s != VV_OK || !s0)
                return s;
            json_decref(s0);
            n5 = json_object();
        }
        if (!n5)
            return s;
        *md = "attributes.json";
        void *ms = NULL;
        s = zr_n5_root(a, n5, &ms);
        *za = ms;
        json_decref(n5);
        return s;
    }
    *md = "zarr.json";
    const char *nt = json_string_value(json_object_get(z3, "node_type"));
    json_t *fmt = json_object_get(z3, "zarr_format");
    if (!json_is_integer(fmt) || json_integer_value(fmt) != 3)
        s = vv_error_set(VV_ERR_UNSUPPORTED, "zarr.json: zarr_format is not 3");
    else if (nt && !strcmp(nt, "array"))
        s = VV_OK; /* a plain array */
    else if (!nt || strcmp(nt, "group"))
        s = vv_error_set(VV_ERR_FORMAT, "zarr.json: node_type is not \"array\" or \"group\"");
    else {
        json_t *at = json_object_get(z3, "attributes");
        json_t *ome = json_object_get(at, "ome");
        /* NGFF 0.5 keeps its metadata under "ome"; drafts put it beside */
        json_t *m = json_object_get(ome, "multiscales") ? ome : at;
        json_t *g = json_is_object(ome) ? ome : at;
        if (!json_object_get(m, "multiscales") &&
            (s = zr_refuse_group(a->root, g, "zarr.json")) != VV_OK)
            ; /* a plate, a well, a labels group: the path to open instead */
        else if (!json_object_get(m, "multiscales"))
            s = vv_error_set(VV_ERR_FORMAT, "zarr.json: a group without attributes.ome.multiscales "
                                            "(not an OME-Zarr image)");
        else
            *za = json_incref(m);
    }
    json_decref(z3);
    return s;
}

/* Appends @p what to @p info's warning (one line, "; " between). */
static void
add_warning(vv_load_info *info, const char *what) {
    if (!info)
        return;
    const size_t n = strlen(info->warning);
    snprintf(info->warning + n, sizeof info->warning - n, "%s%s", n ? "; " : "", what);
}

/* The least and greatest value voxels of @p a's type hold (floats: +-1e38). */
static void
type_limits(const zr_array *a, double *lo, double *hi) {
    switch (a->type) {
    case VV_U8:
        *lo = 0, *hi = 255;
        break;
    case VV_I8:
        *lo = -128, *hi = 127;
        break;
    case VV_U16:
        *lo = 0, *hi = 65535;
        break;
    case VV_I16:
        *lo = -32768, *hi = 32767;
        break;
    case VV_U32:
        *lo = 0, *hi = 4294967295.0;
        break;
    case VV_I32:
        *lo = -2147483648.0, *hi = 2147483647.0;
        break;
    default:
        *lo = -1e38, *hi = 1e38;
    }
    if (a->conv64 == 1)
        *lo = -9.3e18, *hi = 9.3e18;
    else if (a->conv64 == 2)
        *lo = 0, *hi = 1.85e19;
}

/* Channel @p channel's omero window @p w (may be NULL): min and max into
 * a->has_window, a->window (the data range); start and end into
 * info->has_window, info->window (the contrast). A pair that is not two
 * finite numbers, inverted, or beyond what the voxel type holds (by more
 * than its own span) is ignored, said in info->warning. */
static void
zr_omero_window(zr_array *a, json_t *w, int channel, const char *md, vv_load_info *info) {
    a->has_window = 0;
    if (!json_is_object(w))
        return;
    double tlo, thi;
    type_limits(a, &tlo, &thi);
    static const char *const keys[2][2] = {{"min", "max"}, {"start", "end"}};
    for (int pair = 0; pair < 2; pair++) {
        json_t *x = json_object_get(w, keys[pair][0]), *y = json_object_get(w, keys[pair][1]);
        if (!x && !y)
            continue;
        const double lo = json_number_value(x), hi = json_number_value(y);
        const double slack = thi - tlo;
        const char *why = !json_is_number(x) || !json_is_number(y) || !isfinite(lo) || !isfinite(hi)
                              ? "not two finite numbers"
                          : hi < lo || (pair == 1 && hi == lo) ? "inverted"
                          : lo < tlo - slack || hi > thi + slack
                              ? "beyond what the voxel type holds"
                              : NULL;
        if (why) {
            char msg[200];
            snprintf(msg, sizeof msg, "%s: omero channel %d's window %s/%s is %s: ignored", md,
                     channel, keys[pair][0], keys[pair][1], why);
            add_warning(info, msg);
            continue;
        }
        if (pair == 0) {
            a->has_window = 1;
            a->window[0] = lo;
            a->window[1] = hi;
        } else if (info) {
            info->has_window = 1;
            info->window[0] = lo;
            info->window[1] = hi;
        }
    }
}

/* The OME metadata of the store at @p root (its .zattrs, or zarr.json):
 * level @p level's folder, axes, transforms; the channel's name, colour
 * and window into @p info and @p a. Every dataset's path is checked, not
 * only the asked level's. */
vv_status
vv_zr_parse_store(const char *root, int level, zr_array *a, int channel, vv_load_info *info,
                  int *n_levels) {
    vv_status s;
    a->cache = NULL;
    /* the store's real path: every file, folder and chunk read must lie
     * beneath it (a symbolic link may lead out) */
    char *rroot = realpath(root, NULL);
    snprintf(a->real, sizeof a->real, "%s", rroot ? rroot : "");
    free(rroot);
    snprintf(a->root, sizeof a->root, "%s", root);
    a->prefix[0] = '\0';
    json_t *za = NULL;
    const char *md = ".zattrs";
    if ((s = root_metadata(a, &za, &md)) != VV_OK)
        return s;
    /* the levels' format */
    a->zarr_format = !strcmp(md, "zarr.json")         ? 3
                     : !strcmp(md, "attributes.json") ? ZR_N5
                     : !strcmp(md, "info")            ? ZR_PRECOMPUTED
                                                      : 2;
    json_t *ms = za ? json_array_get(json_object_get(za, "multiscales"), 0) : NULL;
    if (za && !json_object_get(za, "multiscales") &&
        (s = zr_refuse_group(root, za, md)) != VV_OK) { /* a v2 plate, well, labels group */
        json_decref(za);
        return s;
    }
    if (info && za && json_is_object(json_object_get(za, "image-label")))
        info->is_label = 1;
    snprintf(a->dir, sizeof a->dir, "%s", root);
    json_t *axes = ms ? json_object_get(ms, "axes") : NULL;
    json_t *dsl = ms ? json_object_get(ms, "datasets") : NULL;
    json_t *ds0 = ms ? json_array_get(dsl, (size_t)level) : NULL;
    if (ms && !json_array_get(dsl, 0)) {
        json_decref(za);
        return vv_error_set(VV_ERR_FORMAT, "%s: multiscales without datasets", md);
    }
    const int count = ms ? (int)json_array_size(dsl) : 1;
    if (n_levels)
        *n_levels = count;
    /* every level's path, so that `info` refuses a store whose level 2 is
     * "/etc/passwd" as a read of that level would */
    for (int i = 0; ms && i < count; i++) {
        const char *p = json_string_value(json_object_get(json_array_get(dsl, (size_t)i), "path"));
        if (!p || !*p || strstr(p, "..") || p[0] == '/' || strlen(p) >= sizeof a->prefix) {
            /* the message quotes the path: format it before the JSON that
             * holds it is freed */
            s = !p || !*p
                    ? vv_error_set(VV_ERR_FORMAT, "%s: dataset %d has no path", md, i)
                    : vv_error_set(VV_ERR_FORMAT,
                                   "%s: dataset %d: path \"%.200s\" leaves the store", md, i, p);
            json_decref(za);
            return s;
        }
    }
    if (level < 0 || (ms ? !ds0 : level > 0)) {
        json_decref(za);
        return vv_error_set(VV_ERR_INVALID, "level %d asked, the store has %d", level, count);
    }
    if (ms)
        prefetch_levels(a, dsl, count); /* a remote store's: one round trip for every level */
    if (ds0) {
        const char *p = json_string_value(json_object_get(ds0, "path"));
        snprintf(a->dir, sizeof a->dir, "%s/%s", root, p);
        snprintf(a->prefix, sizeof a->prefix, "%s", p);
        /* a symbolic link may still lead out of the store: compare the
         * real paths (a folder that does not exist has no .zarray) */
        char *rdir = realpath(a->dir, NULL);
        const int inside = !rdir || !a->real[0] || zr_beneath(rdir, a->real);
        free(rdir);
        if (!inside) {
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: dataset %d: path \"%s\" leaves the store (a link to a "
                             "folder outside it)",
                             md, level, p);
            json_decref(za);
            return s;
        }
    }
    s = parse_zarray(a);
    if (s != VV_OK) {
        char lname[256];
        snprintf(lname, sizeof lname, "%s",
                 ds0 ? json_string_value(json_object_get(ds0, "path")) : ".");
        json_decref(za);
        vv_zr_array_release(a);
        return vv_error_prefix(s, "level %s", lname);
    }
    /* Zarr v3 dimension_names name the axes when the OME metadata does not
     * (each one x, y, z, c or t) */
    int dimnames = (a->zarr_format == 3 || a->zarr_format == ZR_N5) && !axes;
    for (int i = 0; dimnames && i < a->ndim; i++)
        dimnames = axis_kind(a->axes[i].name, NULL) >= 0;
    /* the axes: from the metadata, else (no OME axes) the last three are z,
     * y, x after t and c */
    static const char *const tczyx[5] = {"t", "c", "z", "y", "x"};
    for (int i = 0; i < a->ndim; i++) {
        json_t *ax = axes ? json_array_get(axes, (size_t)i) : NULL;
        char dname[32];
        snprintf(dname, sizeof dname, "%s", a->axes[i].name);
        const char *name = json_is_string(ax) ? json_string_value(ax)
                           : ax               ? json_string_value(json_object_get(ax, "name"))
                           : dimnames         ? dname
                                              : tczyx[5 - a->ndim + i];
        const char *type =
            ax && json_is_object(ax) ? json_string_value(json_object_get(ax, "type")) : NULL;
        const char *unit =
            ax && json_is_object(ax) ? json_string_value(json_object_get(ax, "unit")) : NULL;
        if (axes && (int)json_array_size(axes) != a->ndim) {
            s = vv_error_set(VV_ERR_FORMAT, "%s: %zu axes for an array of %d dimensions", md,
                             json_array_size(axes), a->ndim);
            break;
        }
        if (!axes && !dimnames && a->ndim < 3) {
            s = vv_error_set(VV_ERR_FORMAT, "a %d-D array without OME axes", a->ndim);
            break;
        }
        snprintf(a->axes[i].name, sizeof a->axes[i].name, "%s", name ? name : "?");
        snprintf(a->axes[i].unit, sizeof a->axes[i].unit, "%s", unit ? unit : "");
        a->axes[i].kind = axis_kind(a->axes[i].name, type);
        if (a->axes[i].kind < 0) {
            s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: axis \"%s\" of type \"%s\"", md,
                             a->axes[i].name, type ? type : "?");
            break;
        }
        a->scale[i] = 1;
        a->trans[i] = 0;
    }
    if (s == VV_OK && ds0) {
        char where[64];
        snprintf(where, sizeof where, "dataset %d", level);
        s = apply_transforms(json_object_get(ds0, "coordinateTransformations"), a->ndim, a->scale,
                             a->trans, md, where);
        if (s == VV_OK)
            s = apply_transforms(json_object_get(ms, "coordinateTransformations"), a->ndim,
                                 a->scale, a->trans, md, "multiscales");
    }
    /* an N5 dataset opened alone: its own resolution and unit */
    for (int i = 0; s == VV_OK && !ds0 && a->zarr_format == ZR_N5 && a->n5_has_res && i < a->ndim;
         i++)
        if (a->axes[i].kind == 0) {
            a->scale[i] = a->n5_res[i];
            snprintf(a->axes[i].unit, sizeof a->axes[i].unit, "%s", a->n5_unit);
        }
    /* omero: the channel's label and colour (RRGGBB) */
    json_t *chs = za ? json_object_get(json_object_get(za, "omero"), "channels") : NULL;
    json_t *ch = json_array_get(chs, (size_t)(channel < 0 ? 0 : channel));
    if (s == VV_OK && ch && info) {
        const char *label = json_string_value(json_object_get(ch, "label"));
        if (label)
            snprintf(info->channel_name, sizeof info->channel_name, "%s", label);
        const char *col = json_string_value(json_object_get(ch, "color"));
        char *end = NULL;
        unsigned long rgb = col && strlen(col) == 6 ? strtoul(col, &end, 16) : 0;
        info->inactive = json_is_false(json_object_get(ch, "active"));
        if (end && *end == '\0' && rgb != 0) {
            for (int k = 0; k < 3; k++)
                info->color[k] = (float)((rgb >> (16 - 8 * k)) & 0xffu) / 255.0f;
            info->has_color = 1;
        }
    }
    /* the omero window: its min and max (the data's range), its start and
     * end (the contrast limits); either pair NaN, inverted or absurd is
     * ignored with a warning */
    if (s == VV_OK)
        zr_omero_window(a, json_object_get(ch, "window"), channel < 0 ? 0 : channel, md, info);
    json_decref(za);
    if (s != VV_OK)
        vv_zr_array_release(a);
    return s;
}

void
zr_chunk_key(const zr_array *a, const uint64_t *idx, char *key, size_t cap) {
    if (a->zarr_format == ZR_N5) {
        zr_n5_key(a, idx, key, cap);
        return;
    }
    if (a->zarr_format == ZR_PRECOMPUTED) {
        zr_pc_key(a, idx, key, cap);
        return;
    }
    int len = snprintf(key, cap, "%s%s", a->prefix, a->prefix[0] ? "/" : "");
    const int c = a->zarr_format == 3 && a->key_default;
    if (c && len < (int)cap)
        len += snprintf(key + len, cap - (size_t)len, "c");
    for (int i = 0; i < a->ndim && len < (int)cap; i++)
        len += snprintf(key + len, cap - (size_t)len, "%s%llu", i || c ? (char[2]){a->sep, 0} : "",
                        (unsigned long long)idx[i]);
}

/* Decodes a Zarr v2 chunk of @p m bytes at @p src with the array's
 * compressor into exactly @p n bytes at @p out. */
static vv_status
decode_v2(const zr_array *a, const unsigned char *src, size_t m, unsigned char *out, size_t n,
          const char *path) {
    vv_status s = VV_OK;
    if (!a->codec[0]) {
        if (m != n)
            s = vv_error_set(VV_ERR_FORMAT, "%s: %zu bytes, an uncompressed chunk has %zu", path, m,
                             n);
        else
            memcpy(out, src, n);
    } else if (!strcmp(a->codec, "zlib") || !strcmp(a->codec, "gzip")) {
        z_stream z;
        memset(&z, 0, sizeof z);
        int ok = inflateInit2(&z, !strcmp(a->codec, "gzip") ? 16 + MAX_WBITS : MAX_WBITS) == Z_OK;
        size_t done = 0;
        int r = Z_DATA_ERROR;
        if (ok) {
            z.next_in = (unsigned char *)src;
            z.avail_in = (uInt)m;
            z.next_out = out;
            z.avail_out = (uInt)n;
            r = inflate(&z, Z_FINISH);
            done = n - z.avail_out;
            inflateEnd(&z);
        }
        if (r != Z_STREAM_END || done != n)
            s = vv_error_set(VV_ERR_FORMAT, "%s: the %s stream does not decode to %zu bytes", path,
                             a->codec, n);
    } else if (!strcmp(a->codec, "zstd")) {
        unsigned long long fs = ZSTD_getFrameContentSize(src, m);
        size_t r = fs == (unsigned long long)n ? ZSTD_decompress(out, n, src, m) : 0;
        if (fs != (unsigned long long)n || ZSTD_isError(r) || r != n)
            s = vv_error_set(VV_ERR_FORMAT, "%s: the zstd frame does not decode to %zu bytes", path,
                             n);
    } else { /* blosc */
        size_t nb = 0;
        if (blosc_cbuffer_validate(src, m, &nb) != 0 || nb != n ||
            blosc_decompress_ctx(src, out, n, 1) != (int)n)
            s = vv_error_set(VV_ERR_FORMAT, "%s: the blosc buffer does not decode to %zu bytes",
                             path, n);
    }
    return s;
}

/* Reads and decodes the chunk at grid position @p idx into @p out
 * (exactly @p n bytes); 0 with *missing = 1 when it is absent. */
vv_status
vv_zr_read_chunk(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], unsigned char *out, size_t n,
                 int *missing, uint64_t *file_bytes) {
    *missing = 0;
    if (file_bytes)
        *file_bytes = 0;
    if (a->zarr_format == 3 && a->nshard > 0)
        return zr3_read_sharded(a, idx, out, n, missing, file_bytes);
    if (a->zarr_format == ZR_PRECOMPUTED && a->pc_shard)
        return zr_pc_read_sharded(a, idx, out, n, missing, file_bytes);
    char key[2200];
    zr_chunk_key(a, idx, key, sizeof key);
    unsigned char *src = NULL;
    size_t m = 0;
    /* a v3 chunk is never more than its codecs can have made of it */
    const uint64_t max = a->zarr_format == 3 ? zr3_encoded_max(&a->chain[0], n) : ZR_CHUNK_MAX;
    vv_status s = zr_store_get(a, key, 0, ZR_ALL, max, &src, &m, NULL, missing);
    if (s != VV_OK || *missing)
        return s;
    if (file_bytes)
        *file_bytes = m;
    s = vv_zr_decode_unit(a, idx, src, m, out, n, key);
    free(src);
    return s;
}

vv_status
vv_zr_decode_unit(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], const unsigned char *src,
                  size_t m, unsigned char *out, size_t n, const char *what) {
    if (a->zarr_format == ZR_PRECOMPUTED)
        return zr_pc_decode(a, idx, src, m, out, n, what);
    if (a->zarr_format == ZR_N5)
        return zr_n5_decode(a, src, m, out, n, what);
    if (a->zarr_format != 3)
        return decode_v2(a, src, m, out, n, what);
    const zr_chain *c = &a->chain[a->nshard];
    vv_status s = zr3_decode_bytes(c, src, m, out, n, what);
    unsigned char *tmp = NULL;
    for (int i = 0; s == VV_OK && i < c->n && !tmp; i++)
        if (c->c[i].kind == ZC_TRANSPOSE && !(tmp = malloc(n)))
            s = vv_error_set(VV_ERR_NOMEM, "out of memory for a chunk of %zu bytes", n);
    if (s == VV_OK && tmp)
        zr3_untranspose(c, a->ndim, a->chunks, a->esize, out, tmp);
    free(tmp);
    return s;
}

uint64_t
vv_zr_read_held(const zr_array *a, size_t n) {
    if (a->zarr_format == ZR_PRECOMPUTED && a->pc_shard && a->pc_data_gzip)
        return 2 * (uint64_t)n; /* and the chunk's gzip data_encoding inflated */
    if (a->zarr_format == ZR_N5 || a->zarr_format == ZR_PRECOMPUTED)
        return n; /* a block cut at the array's end, decoded before it is placed */
    if (a->zarr_format != 3)
        return 0; /* the v2 reader's count as it was: the decoded chunk */
    const zr_chain *c = &a->chain[a->nshard];
    uint64_t held = zr3_encoded_max(c, n) + n; /* the bytes read, one step decoded */
    for (int i = 0; i < c->n; i++)
        if (c->c[i].kind == ZC_TRANSPOSE)
            return held + n; /* and the transposed copy */
    return held;
}

void
vv_zr_array_release(zr_array *a) {
    if (a)
        zr3_cache_free(a);
}

/* Fills @p n voxels of type @p t at @p dst with @p x (the fill value, cast). */
void
vv_zr_fill(void *dst, size_t n, vv_voxel_type t, double x) {
#define ZR_FILL(T)                                                                                 \
    for (size_t i = 0; i < n; i++)                                                                 \
        ((T *)dst)[i] = (T)x;
    static const double lo[] = {0, -128, 0, -32768, 0, -2147483648.0},
                        hi[] = {255, 127, 65535, 32767, 4294967295.0, 2147483647.0};
    if (t <= VV_I32 && !(x >= lo[t] && x <= hi[t]))
        x = 0; /* a fill value the type cannot hold (never cast out of range) */
    if (t == VV_F32 && isfinite(x) && fabs(x) > 3.4e38)
        x = 0;
    switch (t) {
    case VV_U8:
        ZR_FILL(uint8_t) break;
    case VV_I8:
        ZR_FILL(int8_t) break;
    case VV_U16:
        ZR_FILL(uint16_t) break;
    case VV_I16:
        ZR_FILL(int16_t) break;
    case VV_U32:
        ZR_FILL(uint32_t) break;
    case VV_I32:
        ZR_FILL(int32_t) break;
    case VV_F32:
        ZR_FILL(float) break;
    case VV_F64:
        ZR_FILL(double) break;
    }
#undef ZR_FILL
}

vv_status
vv_zr_layout(const zr_array *a, int channel, int time, zr_layout *J) {
    memset(J, 0, sizeof *J);
    J->a = a;
    int sp[3], ns = 0;
    J->cax = J->tax = -1;
    for (int i = 0; i < a->ndim; i++) {
        int *slot = a->axes[i].kind == 1 ? &J->cax : a->axes[i].kind == 2 ? &J->tax : NULL;
        if (slot && *slot >= 0)
            return vv_error_set(VV_ERR_UNSUPPORTED, "two %s axes",
                                a->axes[i].kind == 1 ? "channel" : "time");
        if (slot)
            *slot = i;
        else if (ns < 3)
            sp[ns++] = i;
        else
            return vv_error_set(VV_ERR_UNSUPPORTED, "more than three spatial axes");
    }
    if (ns < 2)
        return vv_error_set(VV_ERR_UNSUPPORTED, "%d spatial axes (2 or 3 are read)", ns);
    /* volume axes i, j, k = the last, the middle, the first spatial axis */
    J->vax[0] = sp[ns - 1];
    J->vax[1] = sp[ns - 2];
    J->vax[2] = ns == 3 ? sp[0] : -1;
    for (int k = 0; k < 3; k++) {
        uint64_t n = J->vax[k] >= 0 ? a->shape[J->vax[k]] : 1;
        if (n > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT, "axis %s has %llu samples (limit %d)",
                                a->axes[J->vax[k]].name, (unsigned long long)n, VV_VOLUME_MAX_DIM);
        J->dims[k] = (int)n;
    }
    J->nc = J->cax >= 0 ? a->shape[J->cax] : 1;
    J->nt = J->tax >= 0 ? a->shape[J->tax] : 1;
    if (J->nc > INT_MAX || J->nt > INT_MAX) /* counted in ints (vv_load_info) */
        return vv_error_set(VV_ERR_LIMIT, "%llu %s (limit %d)",
                            (unsigned long long)(J->nc > INT_MAX ? J->nc : J->nt),
                            J->nc > INT_MAX ? "channels" : "time steps", INT_MAX);
    const int ch = channel < 0 ? 0 : channel, tp = time < 0 ? 0 : time;
    if ((uint64_t)ch >= J->nc)
        return vv_error_set(VV_ERR_INVALID, "channel %d asked, the store has %llu", ch,
                            (unsigned long long)J->nc);
    if ((uint64_t)tp >= J->nt)
        return vv_error_set(VV_ERR_INVALID, "time step %d asked, the store has %llu", tp,
                            (unsigned long long)J->nt);
    J->ch = (uint64_t)ch;
    J->tp = (uint64_t)tp;
    uint64_t cbytes = a->esize;
    for (int i = 0; i < a->ndim; i++) {
        if (a->chunks[i] > ZR_CHUNK_MAX || cbytes > ZR_CHUNK_MAX / a->chunks[i])
            return vv_error_set(VV_ERR_LIMIT, "chunks of over %llu bytes",
                                (unsigned long long)ZR_CHUNK_MAX);
        cbytes *= a->chunks[i];
    }
    J->cbytes = (size_t)cbytes;
    /* element strides of a chunk (C order), chunks per axis */
    J->cstride[a->ndim - 1] = 1;
    for (int i = a->ndim - 2; i >= 0; i--)
        J->cstride[i] = J->cstride[i + 1] * a->chunks[i + 1];
    for (int i = 0; i < a->ndim; i++)
        J->nchunk[i] = (a->shape[i] + a->chunks[i] - 1) / a->chunks[i];
    for (int k = 0; k < 3; k++) {
        J->cdims[k] = J->vax[k] >= 0 ? (int)a->chunks[J->vax[k]] : 1;
        J->nchunks[k] = J->vax[k] >= 0 ? (int)J->nchunk[J->vax[k]] : 1;
    }
    return VV_OK;
}

void
vv_zr_geometry(const zr_layout *J, vv_volume *v) {
    for (int k = 0; k < 3; k++) {
        v->spacing[k] = J->vax[k] >= 0 ? J->a->scale[J->vax[k]] : 1;
        v->origin[k] = J->vax[k] >= 0 ? J->a->trans[J->vax[k]] : 0;
    }
    v->unit = vv_unit_parse(J->a->axes[J->vax[0]].unit);
    v->modification = VV_MOD_ORIGINAL;
}

uint64_t
vv_zr_chunk_linear(const zr_layout *J, const int c[3]) {
    uint64_t L = 0;
    for (int i = 0; i < J->a->ndim; i++) {
        if (i == J->cax || i == J->tax)
            continue;
        const int k = i == J->vax[0] ? 0 : i == J->vax[1] ? 1 : 2;
        L = L * J->nchunk[i] + (uint64_t)c[k];
    }
    return L;
}

void
vv_zr_unit_index(const zr_layout *J, uint64_t L, uint64_t idx[ZR_MAX_DIM]) {
    const zr_array *a = J->a;
    for (int i = a->ndim - 1; i >= 0; i--) {
        if (i == J->cax)
            idx[i] = J->ch / a->chunks[i];
        else if (i == J->tax)
            idx[i] = J->tp / a->chunks[i];
        else {
            idx[i] = L % J->nchunk[i];
            L /= J->nchunk[i];
        }
    }
}

vv_status
vv_zr_copy_chunk(const zr_layout *J, uint64_t L, unsigned char *buf, unsigned char *dst,
                 const int dorg[3], const int ddims[3], int *missing_out, uint64_t *file_bytes,
                 double *range) {
    uint64_t idx[ZR_MAX_DIM];
    vv_zr_unit_index(J, L, idx);
    int missing = 0;
    vv_status s = vv_zr_read_chunk(J->a, idx, buf, J->cbytes, &missing, file_bytes);
    if (s != VV_OK)
        return s;
    if (missing_out)
        *missing_out = missing;
    vv_zr_place_unit(J, idx, buf, missing, dst, dorg, ddims, range);
    return VV_OK;
}

void
vv_zr_place_unit(const zr_layout *J, const uint64_t idx[ZR_MAX_DIM], unsigned char *buf,
                 int missing, unsigned char *dst, const int dorg[3], const int ddims[3],
                 double *range) {
    vv_zr_unit_host(J, buf, missing);
    vv_zr_unit_copy(J, idx, buf, dst, dorg, ddims, range);
}

void
vv_zr_unit_host(const zr_layout *J, unsigned char *buf, int missing) {
    const zr_array *a = J->a;
    const size_t vs = a->esize;
    if (missing)
        vv_zr_fill(buf, J->cbytes / vs, a->type, a->fill);
    else if (a->swap)
        vv_byteswap(buf, J->cbytes / vs, vs);
    if (!missing && a->conv64) /* 64-bit integers read as doubles, in place */
        for (size_t i = 0; i < J->cbytes / 8; i++) {
            uint64_t u;
            memcpy(&u, buf + 8 * i, 8);
            const double x = a->conv64 == 1 ? (double)(int64_t)u : (double)u;
            memcpy(buf + 8 * i, &x, 8);
        }
}

void
vv_zr_unit_copy(const zr_layout *J, const uint64_t idx[ZR_MAX_DIM], const unsigned char *buf,
                unsigned char *dst, const int dorg[3], const int ddims[3], double *range) {
    const zr_array *a = J->a;
    const size_t vs = a->esize;
    /* the part inside the array, at the asked channel and step */
    uint64_t base = 0;
    if (J->cax >= 0)
        base += (J->ch - idx[J->cax] * a->chunks[J->cax]) * J->cstride[J->cax];
    if (J->tax >= 0)
        base += (J->tp - idx[J->tax] * a->chunks[J->tax]) * J->cstride[J->tax];
    uint64_t o[3], n[3];
    for (int k = 0; k < 3; k++) {
        const int ax = J->vax[k];
        if (ax < 0) {
            o[k] = 0;
            n[k] = 1;
            continue;
        }
        o[k] = idx[ax] * a->chunks[ax];
        uint64_t e = o[k] + a->chunks[ax];
        n[k] = (e > a->shape[ax] ? a->shape[ax] : e) - o[k];
    }
    const uint64_t si = J->cstride[J->vax[0]], sj = J->cstride[J->vax[1]],
                   sk = J->vax[2] >= 0 ? J->cstride[J->vax[2]] : 0;
    for (uint64_t kk = 0; kk < n[2]; kk++)
        for (uint64_t jj = 0; jj < n[1]; jj++) {
            unsigned char *d = dst + (((o[2] - (uint64_t)dorg[2] + kk) * (uint64_t)ddims[1] + o[1] -
                                       (uint64_t)dorg[1] + jj) *
                                          (uint64_t)ddims[0] +
                                      o[0] - (uint64_t)dorg[0]) *
                                         vs;
            const unsigned char *src = buf + (base + kk * sk + jj * sj) * vs;
            if (si == 1)
                memcpy(d, src, (size_t)(n[0] * vs));
            else
                for (uint64_t ii = 0; ii < n[0]; ii++)
                    memcpy(d + ii * vs, src + ii * si * vs, vs);
            if (range) /* the row just written, in this core's cache */
                vv_range_accumulate(a->type, d, (size_t)n[0], range);
        }
}

static vv_status
read_array(vv_volume **out, const zr_array *ap, const vv_load_options *opt, int n_levels) {
    vv_load_info *info = opt->info;
    vv_status s;
    zr_layout J;
    if ((s = vv_zr_layout(ap, opt->channel, opt->time, &J)) != VV_OK)
        return s;
    const int *dims = J.dims;
    const int cax = J.cax, tax = J.tax;
    const uint64_t nc = J.nc, nt = J.nt;
    if ((s = vv_volume_check_size(dims, ap->type, NULL)) != VV_OK)
        return s;
    /* each thread decodes into a buffer of a whole chunk (one thread for
     * chunks over 64 MiB): a store of a few bytes may declare chunks of
     * 1 GiB, so the buffers count against the budget too (fewer threads
     * when they would not fit) */
    /* a thread holds its chunk buffer and, for Zarr v3, what it reads and
     * decodes it from (an inner chunk of a shard) */
    const uint64_t per = (uint64_t)J.cbytes + vv_zr_read_held(ap, J.cbytes);
    int nthreads = J.cbytes > ((size_t)64 << 20) ? 1 : omp_get_max_threads();
    /* a remote store's reads are batched (vv_zr_copy_chunks), but those of
     * nested shards wait on the network one at a time a thread: as many
     * threads as the transport keeps requests in flight */
    if (bs_is_url(ap->root) && ap->zarr_format == 3 && ap->nshard > 1 && nthreads > 1 &&
        bs_http_in_flight() > nthreads)
        nthreads = bs_http_in_flight();
    const uint64_t budget = vv_memory_budget_get();
    if (per * (uint64_t)nthreads > budget)
        nthreads = budget / per > 1 ? (int)(budget / per) : 1;
    if ((s = vv_memory_budget_check(per, "a Zarr chunk's buffer")) != VV_OK)
        return s;
    uint64_t n_spatial = 1;
    for (int i = 0; i < ap->ndim; i++)
        if (i != cax && i != tax)
            n_spatial *= J.nchunk[i]; /* at most 2^48: each axis is at most 65536 */
    /* each chunk is a file to look for: chunks of a few voxels made a 4 MiB
     * volume 4 million opens (a read of minutes; fuzz_zarr) */
    if (n_spatial > ZR_READ_CHUNKS_MAX)
        return vv_error_set(VV_ERR_LIMIT,
                            ".zarray: %llu chunks of %d x %d x %d voxels to read whole (at most "
                            "%d: rechunk the store, or open it out of core)",
                            (unsigned long long)n_spatial, J.cdims[0], J.cdims[1], J.cdims[2],
                            ZR_READ_CHUNKS_MAX);
    vv_volume *v = NULL;
    if ((s = vv_volume_new(&v, dims, ap->type)) != VV_OK)
        return s;
    /* the chunks on nthreads threads, each its own buffer (a remote store's
     * fetched in batches meanwhile); the value range measured as the chunks
     * are copied (no pass after); not at all in the reader sandbox
     * (one_shot), whose parent trusts no range it is sent and measures the
     * voxels again */
    double range[2] = {INFINITY, -INFINITY};
    const int want_range = !opt->one_shot;
    const int zero[3] = {0, 0, 0};
    s = vv_zr_copy_chunks(&J, NULL, n_spatial, v->data, zero, dims, NULL, nthreads,
                          want_range ? range : NULL);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_zr_geometry(&J, v);
    if (want_range)
        vv_volume_set_range(v, range);
    if (info) {
        info->n_channels = (int)nc;
        info->n_levels = n_levels;
        info->n_times = (int)nt;
        if (tax >= 0 && ap->scale[tax] > 0) {
            const char *u = ap->axes[tax].unit;
            double f = !strcmp(u, "second")        ? 1
                       : !strcmp(u, "millisecond") ? 1e-3
                       : !strcmp(u, "microsecond") ? 1e-6
                       : !strcmp(u, "minute")      ? 60
                       : !strcmp(u, "hour")        ? 3600
                                                   : 0;
            info->time_step = ap->scale[tax] * f;
        }
    }
    *out = v;
    return VV_OK;
}

/* Every level of the store at @p path but @p level (whose array is @p a)
 * chunked along its channel axis as @p a is: a pyramid read out of core
 * holds every channel of a node in one piece, so a store that chunks its
 * channels differently at two levels is inconsistent multiscales, refused
 * in memory as out of core (zarr_pyramid.c). */
static vv_status
check_channel_chunks(const char *path, int level, const zr_array *a, int n_levels) {
    int cax = -1;
    for (int i = 0; i < a->ndim; i++)
        if (a->axes[i].kind == 1)
            cax = i;
    if (cax < 0 || n_levels < 2)
        return VV_OK;
    zr_array *b = calloc(1, sizeof *b);
    if (!b)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = VV_OK;
    for (int i = 0; i < n_levels && s == VV_OK; i++) {
        if (i == level)
            continue;
        memset(b, 0, sizeof *b);
        if ((s = vv_zr_parse_store(path, i, b, -1, NULL, NULL)) != VV_OK)
            break;
        if (b->ndim == a->ndim && b->axes[cax].kind == 1 && b->chunks[cax] != a->chunks[cax])
            s = vv_error_set(VV_ERR_FORMAT,
                             "level %d: chunks of %llu along the channel axis, level %d's of %llu "
                             "(inconsistent multiscales)",
                             i, (unsigned long long)b->chunks[cax], level,
                             (unsigned long long)a->chunks[cax]);
        vv_zr_array_release(b);
    }
    free(b);
    return s;
}

static vv_status
read_store(vv_volume **out, const char *path, const vv_load_options *opt) {
    zr_array *a = calloc(1, sizeof *a); /* 14 KiB: not on a reader thread's stack */
    if (!a)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    int n_levels = 1;
    vv_status s = vv_zr_parse_store(path, opt->level, a, opt->channel, opt->info, &n_levels);
    if (s == VV_OK)
        s = check_channel_chunks(path, opt->level, a, n_levels);
    if (s == VV_OK)
        s = read_array(out, a, opt, n_levels);
    vv_zr_array_release(a);
    free(a);
    return s;
}

/* read_store behind the row named @p row: its arguments checked, its
 * errors prefixed "ROW: NAME". */
static vv_status
read_as(const char *row, vv_volume **out, const char *path, const vv_load_options *opt) {
    if (!out || !path || !opt)
        return vv_error_set(VV_ERR_INVALID, "%s: NULL argument", row);
    *out = NULL;
    vv_status s = read_store(out, path, opt);
    if (s != VV_OK)
        return vv_error_prefix(s, "%s: %s", row, bs_name(path));
    return VV_OK;
}

vv_status
vv_ome_zarr_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    return read_as("zarr", out, path, opt);
}

vv_status
vv_pc_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    return read_as("precomputed", out, path, opt);
}

vv_status
vv_n5_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    return read_as("n5", out, path, opt);
}

int
zr_file_head(const char *dir, const char *name, char *head, size_t cap) {
    char f[4200];
    struct stat st;
    snprintf(f, sizeof f, "%s/%s", dir, name);
    if (stat(f, &st) != 0 || !S_ISREG(st.st_mode)) /* a FIFO would block the open */
        return 0;
    FILE *fp = fopen(f, "rb");
    if (!fp)
        return 0;
    size_t n = fread(head, 1, cap - 1, fp);
    fclose(fp);
    head[n] = '\0';
    return 1;
}

/* 1 when the metadata @p buf names an HCS plate, a well or a labels
 * group (opened to say which path to open instead; zarr_meta.c). */
static int
ome_group_key(const char *buf) {
    return strstr(buf, "\"plate\"") || strstr(buf, "\"well\"") || strstr(buf, "\"labels\"");
}

/* A folder with a .zarray, or a .zattrs naming multiscales (or a plate, a
 * well, labels), or a Zarr v3 zarr.json of an array or of a group naming
 * them. */
int
vv_ome_zarr_looks_like(const vv_format_probe *p, int deep) {
    if (!p->is_dir || deep)
        return 0;
    char f[4200];
    struct stat st;
    snprintf(f, sizeof f, "%s/.zarray", p->path);
    if (stat(f, &st) == 0)
        return 1;
    const size_t cap = 65536; /* an NGFF group's zarr.json names multiscales early */
    char *buf = malloc(cap);
    if (!buf)
        return 0;
    int yes = 0;
    if (zr_file_head(p->path, "zarr.json", buf, cap)) {
        /* "node_type": "array", or a group naming multiscales */
        const char *nt = strstr(buf, "\"node_type\"");
        if (nt) {
            nt += strlen("\"node_type\"");
            while (*nt == ' ' || *nt == '\t' || *nt == '\n' || *nt == '\r' || *nt == ':')
                nt++;
        }
        /* a long plate's wells may push node_type past the head */
        yes = nt ? !strncmp(nt, "\"array\"", 7) || strstr(buf, "\"multiscales\"") ||
                       ome_group_key(buf)
                 : strstr(buf, "\"zarr_format\"") == NULL && strstr(buf, "\"ome\"") &&
                       ome_group_key(buf);
    } else if (zr_file_head(p->path, ".zattrs", buf, 4096))
        yes = strstr(buf, "\"multiscales\"") != NULL || ome_group_key(buf);
    free(buf);
    return yes;
}
