/*
 * Every refusal of the OME-Zarr reader (src/io/store/zarr_read.c) and of its
 * pyramid (src/io/store/zarr_pyramid.c, src/io/store/pyramid_open.c,
 * src/io/store/pyramid_load.c) on hostile stores written here: each row a store
 * (.zattrs, .zarray, a chunk), the status and a piece of the message that
 * names the field; every message one line naming the store, no volume
 * left behind, nothing for the sanitizers to report.
 *
 * - A multiscales dataset path "../../../../etc" is refused with the path
 *   quoted (it was formatted from freed JSON: a heap use-after-free), here
 *   and through `volvis info` (VOLVIS_SANDBOX=0).
 * - A dataset path that is a symbolic link to a folder outside the store.
 * - Zero, negative, non-number or overflowing scales in the
 *   coordinateTransformations (a zero or non-finite spacing is never taken).
 * - Short and corrupt zlib, gzip, zstd and blosc chunks; a chunk file over
 *   1 GiB (sparse), one that is a folder, one below a file; a chunk, or a
 *   folder of chunks, that is a link out of the store; FIFOs for .zarray,
 *   .zattrs and a chunk (an open would block).
 */
#include "testutil.h"

#define expect(got, want, needle, file) vt_expect_refusal(NULL, got, want, needle, file)

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "core/crc32c.h"
#include "io/store/pyramid.h"
#include "io/store/zarr.h"
#include "volvis/volvis.h"

static char g_dir[4096];

/* Removes @p path and, when a folder (not a link), what it holds. */
static void
rm_rf(const char *path) {
    struct stat st;
    if (lstat(path, &st) != 0)
        return;
    if (S_ISDIR(st.st_mode)) {
        DIR *d = opendir(path);
        for (struct dirent *e = d ? readdir(d) : NULL; e; e = readdir(d)) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char p[8400];
            snprintf(p, sizeof p, "%s/%s", path, e->d_name);
            rm_rf(p);
        }
        if (d)
            closedir(d);
    }
    remove(path);
}

static const char *
base(const char *path) {
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

/* A fresh empty folder @p name under the test's output folder. */
static const char *
fresh(const char *name) {
    static char p[4400];
    snprintf(p, sizeof p, "%s/%s", g_dir, name);
    rm_rf(p);
    assert_int_equal(mkdir(p, 0755), 0);
    return p;
}

static void
put(const char *dir, const char *name, const void *data, size_t n) {
    char p[8400];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    for (char *slash = p + strlen(dir) + 1; (slash = strchr(slash, '/')) != NULL; slash++) {
        *slash = '\0'; /* the sub-folders first */
        mkdir(p, 0755);
        *slash = '/';
    }
    vt_write_file(p, data, n);
}

static void
put_text(const char *dir, const char *name, const char *text) {
    put(dir, name, text, strlen(text));
}

/* Loads the store @p dir (as detected) at @p level / @p channel / @p time;
 * asserts it is refused as expected, with no volume. */
static void
load_expect(const char *dir, int level, int channel, int time, vv_status want, const char *needle) {
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_OME_ZARR;
    o.level = level;
    o.channel = channel;
    o.time = time;
    vv_volume *v = (vv_volume *)(uintptr_t)1;
    vv_status s = vv_volume_load(&v, dir, &o);
    assert_null(v);
    expect(s, want, needle, base(dir));
}

/* ---- the metadata ----------------------------------------------------------------- */

#define ZA_(shape, chunks, dtype, more)                                                            \
    "{\"zarr_format\": 2, \"shape\": " shape ", \"chunks\": " chunks ", \"dtype\": \"" dtype       \
    "\", \"compressor\": null, \"fill_value\": 0, \"order\": \"C\"" more "}"
#define ZA ZA_("[4, 4, 4]", "[4, 4, 4]", "|u1", "")
#define AX3                                                                                        \
    "[{\"name\": \"z\", \"type\": \"space\"}, {\"name\": \"y\", \"type\": \"space\"}, "            \
    "{\"name\": \"x\", \"type\": \"space\", \"unit\": \"micrometer\"}]"
#define SC3 "[{\"type\": \"scale\", \"scale\": [1, 1, 1]}]"
#define MS_(axes, datasets, more)                                                                  \
    "{\"multiscales\": [{\"version\": \"0.4\", \"axes\": " axes ", \"datasets\": " datasets more   \
    "}]}"
#define DS_(path, tr) "[{\"path\": \"" path "\", \"coordinateTransformations\": " tr "}]"
#define MS(path, tr) MS_(AX3, DS_(path, tr), "")

typedef struct zcase {
    const char *name;
    const char *zattrs; /* NULL: none (a plain array at the root) */
    const char *zarray; /* at "0/" with .zattrs, else at the root; NULL: none */
    int level, channel, time;
    vv_status want;
    const char *needle;
} zcase;

static const zcase g_meta[] = {
    {"no_zarray", MS("0", SC3), NULL, 0, -1, -1, VV_ERR_FORMAT, "no .zarray"},
    {"zattrs_json", "{\"multiscales\": [", ZA, 0, -1, -1, VV_ERR_FORMAT, ".zattrs: line"},
    {"zarray_json", MS("0", SC3), "{\"zarr_format\": 2,,}", 0, -1, -1, VV_ERR_FORMAT,
     ".zarray: line"},
    {"zarray_dup_key", NULL, "{\"zarr_format\": 2, \"zarr_format\": 2}", 0, -1, -1, VV_ERR_FORMAT,
     "duplicate"},
    {"no_datasets", MS_(AX3, "[]", ""), ZA, 0, -1, -1, VV_ERR_FORMAT,
     "multiscales without datasets"},
    {"level_past", MS("0", SC3), ZA, 3, -1, -1, VV_ERR_INVALID, "level 3 asked, the store has 1"},
    {"level_plain", NULL, ZA, 1, -1, -1, VV_ERR_INVALID, "level 1 asked"},
    {"path_none", MS_(AX3, "[{\"coordinateTransformations\": " SC3 "}]", ""), ZA, 0, -1, -1,
     VV_ERR_FORMAT, "dataset 0 has no path"},
    {"path_empty", MS("", SC3), ZA, 0, -1, -1, VV_ERR_FORMAT, "dataset 0 has no path"},
    {"path_number", MS_(AX3, "[{\"path\": 7}]", ""), ZA, 0, -1, -1, VV_ERR_FORMAT, "no path"},
    {"path_dotdot", MS("../../../../etc", SC3), ZA, 0, -1, -1, VV_ERR_FORMAT,
     "path \"../../../../etc\" leaves the store"},
    {"path_absolute", MS("/etc", SC3), ZA, 0, -1, -1, VV_ERR_FORMAT,
     "path \"/etc\" leaves the store"},
    {"path_inner_dotdot", MS("0/../../x", SC3), ZA, 0, -1, -1, VV_ERR_FORMAT, "leaves the store"},
    {"path_control", MS("\\u001b[31m/..", SC3), ZA, 0, -1, -1, VV_ERR_FORMAT, "\\x1b[31m"},
    {"zarr_format", NULL, "{\"zarr_format\": 3, \"shape\": [4, 4, 4]}", 0, -1, -1,
     VV_ERR_UNSUPPORTED, "zarr_format is not 2"},
    {"zarr_format_string", NULL, "{\"zarr_format\": \"2\"}", 0, -1, -1, VV_ERR_UNSUPPORTED,
     "zarr_format"},
    {"shape_missing", NULL, "{\"zarr_format\": 2, \"chunks\": [4, 4, 4]}", 0, -1, -1, VV_ERR_FORMAT,
     "shape and chunks must be arrays"},
    {"shape_chunks_differ", NULL, ZA_("[4, 4, 4]", "[4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_FORMAT,
     "shape and chunks"},
    {"shape_1d", NULL, ZA_("[4]", "[4]", "|u1", ""), 0, -1, -1, VV_ERR_FORMAT, "2 to 5 sizes"},
    {"shape_6d", NULL, ZA_("[1, 1, 1, 1, 1, 1]", "[1, 1, 1, 1, 1, 1]", "|u1", ""), 0, -1, -1,
     VV_ERR_FORMAT, "2 to 5 sizes"},
    {"shape_zero", NULL, ZA_("[4, 0, 4]", "[4, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_FORMAT,
     "axis 1: shape or chunk size not a size"},
    {"chunk_zero", NULL, ZA_("[4, 4, 4]", "[4, 4, 0]", "|u1", ""), 0, -1, -1, VV_ERR_FORMAT,
     "axis 2: shape or chunk"},
    {"chunk_negative", NULL, ZA_("[4, 4, 4]", "[-4, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_FORMAT,
     "axis 0: shape or chunk"},
    {"shape_huge", NULL, ZA_("[4, 4, 2000000000000]", "[4, 4, 4]", "|u1", ""), 0, -1, -1,
     VV_ERR_FORMAT, "axis 2: shape or chunk"},
    {"shape_float", NULL, ZA_("[4, 4.5, 4]", "[4, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_FORMAT,
     "axis 1"},
    {"order_f", NULL,
     "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], "
     "\"order\": \"F\"}",
     0, -1, -1, VV_ERR_UNSUPPORTED, "order \"F\""},
    {"order_number", NULL,
     "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], "
     "\"order\": 1}",
     0, -1, -1, VV_ERR_UNSUPPORTED, "order \"?\""},
    {"filters", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "|u1", ", \"filters\": [{\"id\": \"delta\"}]"),
     0, -1, -1, VV_ERR_UNSUPPORTED, "filters are not supported"},
    {"dtype_f16", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "<f16", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "dtype \"<f16\""},
    {"dtype_object", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "|O", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "dtype \"|O\""},
    {"dtype_unicode", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "<U8", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "dtype \"<U8\""},
    {"dtype_f2", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "<f2", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "dtype \"<f2\""},
    {"dtype_order", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "=u2", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "dtype \"=u2\""},
    {"dtype_none", NULL, "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4]}", 0, -1,
     -1, VV_ERR_UNSUPPORTED, "dtype \"(none)\""},
    {"dtype_structured", NULL,
     "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], "
     "\"dtype\": [[\"a\", \"<u1\"]]}",
     0, -1, -1, VV_ERR_UNSUPPORTED, "dtype \"(none)\""},
    {"compressor_lz4", NULL,
     "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], \"dtype\": \"|u1\", "
     "\"compressor\": {\"id\": \"lz4\"}}",
     0, -1, -1, VV_ERR_UNSUPPORTED, "compressor \"lz4\""},
    {"compressor_no_id", NULL,
     "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], \"dtype\": \"|u1\", "
     "\"compressor\": 5}",
     0, -1, -1, VV_ERR_UNSUPPORTED, "compressor \"?\""},
    {"separator", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "|u1", ", \"dimension_separator\": \"\\\\\""),
     0, -1, -1, VV_ERR_FORMAT, "dimension_separator"},
    {"separator_number", NULL, ZA_("[4, 4, 4]", "[4, 4, 4]", "|u1", ", \"dimension_separator\": 0"),
     0, -1, -1, VV_ERR_FORMAT, "dimension_separator"},
    {"fill_junk", NULL,
     "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], \"dtype\": \"|u1\", "
     "\"fill_value\": \"junk\"}",
     0, -1, -1, VV_ERR_FORMAT, "fill_value"},
    {"fill_object", NULL,
     "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], \"dtype\": \"|u1\", "
     "\"fill_value\": {\"a\": 1}}",
     0, -1, -1, VV_ERR_FORMAT, "fill_value"},
    {"level_prefix", MS("0", SC3), ZA_("[4, 4, 4]", "[4, 4, 4]", "<f16", ""), 0, -1, -1,
     VV_ERR_UNSUPPORTED, "level 0: .zarray: dtype"},
    {"axes_count", MS_("[\"y\", \"x\"]", DS_("0", SC3), ""), ZA, 0, -1, -1, VV_ERR_FORMAT,
     "2 axes for an array of 3 dimensions"},
    {"plain_2d", NULL, ZA_("[4, 4]", "[4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_FORMAT,
     "a 2-D array without OME axes"},
    {"axis_kind",
     MS_("[{\"name\": \"z\", \"type\": \"space\"}, {\"name\": \"q\", \"type\": \"angle\"}, "
         "{\"name\": \"x\", \"type\": \"space\"}]",
         DS_("0", SC3), ""),
     ZA, 0, -1, -1, VV_ERR_UNSUPPORTED, "axis \"q\" of type \"angle\""},
    {"axis_name_number", MS_("[\"z\", 5, \"x\"]", DS_("0", SC3), ""), ZA, 0, -1, -1,
     VV_ERR_UNSUPPORTED, "axis \"?\""},
    {"scale_zero", MS("0", "[{\"type\": \"scale\", \"scale\": [1, 0, 1]}]"), ZA, 0, -1, -1,
     VV_ERR_FORMAT, "dataset 0: scale 1 is not a positive finite number"},
    {"scale_negative", MS("0", "[{\"type\": \"scale\", \"scale\": [-1, 1, 1]}]"), ZA, 0, -1, -1,
     VV_ERR_FORMAT, "scale 0 is not a positive"},
    {"scale_string", MS("0", "[{\"type\": \"scale\", \"scale\": [1, 1, \"NaN\"]}]"), ZA, 0, -1, -1,
     VV_ERR_FORMAT, "scale 2 is not"},
    {"scale_short", MS("0", "[{\"type\": \"scale\", \"scale\": [1, 1]}]"), ZA, 0, -1, -1,
     VV_ERR_FORMAT, "the scale is not 3 numbers"},
    {"scale_not_array", MS("0", "[{\"type\": \"scale\", \"scale\": 2}]"), ZA, 0, -1, -1,
     VV_ERR_FORMAT, "the scale is not 3 numbers"},
    {"translation_null", MS("0", "[{\"type\": \"translation\", \"translation\": [0, null, 0]}]"),
     ZA, 0, -1, -1, VV_ERR_FORMAT, "translation 1 is not a finite number"},
    {"scale_overflow",
     MS_(AX3, DS_("0", "[{\"type\": \"scale\", \"scale\": [1e300, 1, 1]}]"),
         ", \"coordinateTransformations\": [{\"type\": \"scale\", \"scale\": [1e300, 1, 1]}]"),
     ZA, 0, -1, -1, VV_ERR_FORMAT, "multiscales: the composed scale along axis 0"},
    {"scale_underflow",
     MS_(AX3, DS_("0", "[{\"type\": \"scale\", \"scale\": [1, 1e-300, 1]}]"),
         ", \"coordinateTransformations\": [{\"type\": \"scale\", \"scale\": [1, 1e-300, 1]}]"),
     ZA, 0, -1, -1, VV_ERR_FORMAT, "the composed scale along axis 1"},
    {"translation_overflow",
     MS("0", "[{\"type\": \"translation\", \"translation\": [1e308, 0, 0]}, "
             "{\"type\": \"scale\", \"scale\": [1e10, 1, 1]}]"),
     ZA, 0, -1, -1, VV_ERR_FORMAT, "the composed translation along axis 0"},
    /* the layout */
    {"two_channels",
     MS_("[{\"name\": \"c\", \"type\": \"channel\"}, {\"name\": \"d\", \"type\": \"channel\"}, "
         "{\"name\": \"y\", \"type\": \"space\"}, {\"name\": \"x\", \"type\": \"space\"}]",
         DS_("0", "[{\"type\": \"scale\", \"scale\": [1, 1, 1, 1]}]"), ""),
     ZA_("[2, 2, 4, 4]", "[1, 1, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "two channel axes"},
    {"two_times", MS_("[\"t\", \"t\", \"y\", \"x\"]", DS_("0", "[]"), ""),
     ZA_("[2, 2, 4, 4]", "[1, 1, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "two time axes"},
    {"four_space", MS_("[\"x\", \"z\", \"y\", \"x\"]", DS_("0", "[]"), ""),
     ZA_("[2, 2, 4, 4]", "[1, 1, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_UNSUPPORTED,
     "more than three spatial axes"},
    {"one_space", MS_("[\"c\", \"x\"]", DS_("0", "[]"), ""), ZA_("[2, 4]", "[1, 4]", "|u1", ""), 0,
     -1, -1, VV_ERR_UNSUPPORTED, "1 spatial axes"},
    {"axis_too_long", NULL, ZA_("[4, 4, 100000]", "[4, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_LIMIT,
     "axis x has 100000 samples"},
    {"channel_past", MS_("[\"c\", \"z\", \"y\", \"x\"]", DS_("0", "[]"), ""),
     ZA_("[2, 4, 4, 4]", "[1, 4, 4, 4]", "|u1", ""), 0, 2, -1, VV_ERR_INVALID,
     "channel 2 asked, the store has 2"},
    {"time_past", MS_("[\"t\", \"z\", \"y\", \"x\"]", DS_("0", "[]"), ""),
     ZA_("[3, 4, 4, 4]", "[1, 4, 4, 4]", "|u1", ""), 0, -1, 3, VV_ERR_INVALID,
     "time step 3 asked, the store has 3"},
    {"channels_over_int", MS_("[\"c\", \"z\", \"y\", \"x\"]", DS_("0", "[]"), ""),
     ZA_("[4294967296, 4, 4, 4]", "[1, 4, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_LIMIT,
     "4294967296 channels"},
    {"times_over_int", MS_("[\"t\", \"z\", \"y\", \"x\"]", DS_("0", "[]"), ""),
     ZA_("[4294967296, 4, 4, 4]", "[1, 4, 4, 4]", "|u1", ""), 0, -1, -1, VV_ERR_LIMIT,
     "4294967296 time steps"},
    {"chunk_over_limit", NULL, ZA_("[4, 4, 4]", "[1024, 1024, 2048]", "<f8", ""), 0, -1, -1,
     VV_ERR_LIMIT, "chunks of over 1073741824 bytes"},
    {"chunk_product_overflow", MS_("[\"t\", \"c\", \"z\", \"y\", \"x\"]", DS_("0", "[]"), ""),
     ZA_("[1, 1, 4, 4, 4]", "[1099511627776, 1099511627776, 1099511627776, 4, 4]", "<f8", ""), 0,
     -1, -1, VV_ERR_LIMIT, "chunks of over"},
};

static void
test_metadata(void **state) {
    (void)state;
    for (size_t i = 0; i < sizeof g_meta / sizeof g_meta[0]; i++) {
        const zcase *c = &g_meta[i];
        char name[128];
        snprintf(name, sizeof name, "%s.zarr", c->name);
        const char *dir = fresh(name);
        if (c->zattrs)
            put_text(dir, ".zattrs", c->zattrs);
        if (c->zarray)
            put_text(dir, c->zattrs ? "0/.zarray" : ".zarray", c->zarray);
        print_message("%s\n", c->name);
        load_expect(dir, c->level, c->channel, c->time, c->want, c->needle);
    }
}

/* The use-after-free: the path quoted in the message was freed JSON. */
static void
test_path_leaves_store(void **state) {
    (void)state;
    const char *dir = fresh("escape.zarr");
    put_text(dir, ".zattrs", MS("../../../../etc", SC3));
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "\"../../../../etc\" leaves the store");
    zr_array a;
    memset(&a, 0, sizeof a);
    expect(vv_zr_parse_store(dir, 0, &a, 0, NULL, NULL), VV_ERR_FORMAT,
           ".zattrs: dataset 0: path \"../../../../etc\" leaves the store", NULL);
    vv_pyramid *p = NULL;
    expect(vv_pyramid_open(&p, dir, 0, -1, vt_cache(64u << 20), NULL), VV_ERR_FORMAT,
           "leaves the store", "escape.zarr");
    assert_null(p);
    /* the command line prints that one line, nothing of /etc */
    const char *args[] = {"info", dir, NULL};
    vt_run_result r = vt_run_cli_v(g_dir, args);
    assert_int_not_equal(r.status, 0);
    if (!strstr(r.err, "\"../../../../etc\" leaves the store") || !strstr(r.err, "escape.zarr"))
        fail_msg("volvis info printed '%s'", r.err);
    const char *nl = strchr(r.err, '\n');
    assert_true(nl == NULL || nl[1] == '\0');
    assert_null(strstr(r.out, "root:"));
    vt_run_result_free(&r);
}

/* A dataset path that is a link to a folder outside the store (holding a
 * valid array) is refused like "..". */
static void
test_path_symlink(void **state) {
    (void)state;
    const char *out = fresh("outside");
    put_text(out, ".zarray", ZA);
    char outside[4400];
    snprintf(outside, sizeof outside, "%s", out);
    const char *dir = fresh("link.zarr");
    put_text(dir, ".zattrs", MS("0", SC3));
    char link[8400];
    snprintf(link, sizeof link, "%s/0", dir);
    assert_int_equal(symlink(outside, link), 0);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "path \"0\" leaves the store");
    /* a link inside the store is read */
    const char *ok = fresh("inner_link.zarr");
    put_text(ok, ".zattrs", MS("0", SC3));
    put_text(ok, "real/.zarray", ZA);
    snprintf(link, sizeof link, "%s/0", ok);
    assert_int_equal(symlink("real", link), 0);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, ok, NULL));
    assert_int_equal(v->dims[0], 4);
    vv_volume_free(v);
    /* a .zarray or a .zattrs that is itself a link to a file outside */
    char target[8400];
    snprintf(target, sizeof target, "%s/.zarray", outside);
    char meta[4400], attrs[4400]; /* fresh() answers in one buffer */
    snprintf(meta, sizeof meta, "%s", fresh("meta_link.zarr"));
    put_text(meta, ".zattrs", MS("0", SC3));
    snprintf(link, sizeof link, "%s/0", meta);
    assert_int_equal(mkdir(link, 0755), 0);
    snprintf(link, sizeof link, "%s/0/.zarray", meta);
    assert_int_equal(symlink(target, link), 0);
    load_expect(meta, 0, -1, -1, VV_ERR_FORMAT, ".zarray leaves the store");
    snprintf(attrs, sizeof attrs, "%s", fresh("attrs_link.zarr"));
    put_text(outside, ".zattrs", MS("0", SC3));
    snprintf(target, sizeof target, "%s/.zattrs", outside);
    snprintf(link, sizeof link, "%s/.zattrs", attrs);
    assert_int_equal(symlink(target, link), 0);
    load_expect(attrs, 0, -1, -1, VV_ERR_FORMAT, ".zattrs leaves the store");
}

/* A .zattrs or .zarray over 16 MiB (sparse) is refused unread. */
static void
test_json_too_large(void **state) {
    (void)state;
    const char *dir = fresh("big.zarr");
    put_text(dir, ".zarray", ZA);
    char p[8400];
    snprintf(p, sizeof p, "%s/.zattrs", dir);
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (off_t)ZR_JSON_MAX + 1), 0);
    close(fd);
    load_expect(dir, 0, -1, -1, VV_ERR_LIMIT, ".zattrs is 16777217 bytes (limit 16777216)");
}

/* ---- chunks --------------------------------------------------------------------------- */

#define ZAC(codec)                                                                                 \
    "{\"zarr_format\": 2, \"shape\": [4, 4, 4], \"chunks\": [4, 4, 4], \"dtype\": \"|u1\", "       \
    "\"fill_value\": 0, \"compressor\": " codec "}"

static void
chunk_expect(const char *name, const char *zarray, const void *chunk, size_t n, vv_status want,
             const char *needle) {
    print_message("%s\n", name);
    const char *dir = fresh(name);
    put_text(dir, ".zarray", zarray);
    put(dir, "0.0.0", chunk, n);
    load_expect(dir, 0, -1, -1, want, needle);
}

static void
test_chunks(void **state) {
    (void)state;
    unsigned char junk[64], z[256];
    for (int i = 0; i < 64; i++)
        junk[i] = (unsigned char)(i * 37 + 11);
    /* uncompressed: one byte short */
    chunk_expect("raw_short.zarr", ZA, junk, 63, VV_ERR_FORMAT,
                 "0.0.0: 63 bytes, an uncompressed chunk has 64");
    /* zlib: a valid stream of 10 bytes, a stream cut short, junk */
    uLongf zn = sizeof z;
    assert_int_equal(compress(z, &zn, junk, 10), Z_OK);
    chunk_expect("zlib_small.zarr", ZAC("{\"id\": \"zlib\"}"), z, zn, VV_ERR_FORMAT,
                 "the zlib stream does not decode to 64 bytes");
    zn = sizeof z;
    assert_int_equal(compress(z, &zn, junk, 64), Z_OK);
    chunk_expect("zlib_cut.zarr", ZAC("{\"id\": \"zlib\"}"), z, zn / 2, VV_ERR_FORMAT,
                 "the zlib stream does not decode");
    chunk_expect("zlib_junk.zarr", ZAC("{\"id\": \"zlib\"}"), junk, 64, VV_ERR_FORMAT,
                 "the zlib stream");
    chunk_expect("gzip_junk.zarr", ZAC("{\"id\": \"gzip\"}"), junk, 64, VV_ERR_FORMAT,
                 "the gzip stream does not decode to 64 bytes");
    chunk_expect("zlib_empty.zarr", ZAC("{\"id\": \"zlib\"}"), junk, 0, VV_ERR_FORMAT,
                 "the zlib stream");
    /* zstd: junk, a frame that says 64 bytes and a broken block, another size */
    chunk_expect("zstd_junk.zarr", ZAC("{\"id\": \"zstd\"}"), junk, 64, VV_ERR_FORMAT,
                 "the zstd frame does not decode to 64 bytes");
    const unsigned char zf[] = {0x28, 0xb5, 0x2f, 0xfd, 0x20, 64, 0xff, 0xff, 0xff, 1, 2, 3};
    chunk_expect("zstd_block.zarr", ZAC("{\"id\": \"zstd\"}"), zf, sizeof zf, VV_ERR_FORMAT,
                 "the zstd frame");
    const unsigned char zs[] = {0x28, 0xb5, 0x2f, 0xfd, 0x20, 63, 0x01, 0x00, 0x00};
    chunk_expect("zstd_size.zarr", ZAC("{\"id\": \"zstd\"}"), zs, sizeof zs, VV_ERR_FORMAT,
                 "the zstd frame");
    /* blosc: junk, a header of another size, a header whose lz4 stream is junk */
    chunk_expect("blosc_junk.zarr", ZAC("{\"id\": \"blosc\", \"cname\": \"lz4\"}"), junk, 10,
                 VV_ERR_FORMAT, "the blosc buffer does not decode to 64 bytes");
    unsigned char bh[48] = {2, 1, 0x01 | (1 << 5), 1};
    const uint32_t nbytes = 32, block = 32, cbytes = sizeof bh, start = 20, csize = 40;
    memcpy(bh + 4, &nbytes, 4);
    memcpy(bh + 8, &block, 4);
    memcpy(bh + 12, &cbytes, 4);
    memcpy(bh + 16, &start, 4);
    memcpy(bh + 20, &csize, 4);
    chunk_expect("blosc_size.zarr", ZAC("{\"id\": \"blosc\"}"), bh, sizeof bh, VV_ERR_FORMAT,
                 "the blosc buffer");
    const uint32_t n64 = 64, b64 = 64;
    memcpy(bh + 4, &n64, 4);
    memcpy(bh + 8, &b64, 4);
    memset(bh + 24, 0xee, sizeof bh - 24);
    chunk_expect("blosc_body.zarr", ZAC("{\"id\": \"blosc\"}"), bh, sizeof bh, VV_ERR_FORMAT,
                 "the blosc buffer");
}

/* Chunk files that are no files: over 1 GiB (sparse), a folder, one below
 * a file (ENOTDIR). */
static void
test_chunk_files(void **state) {
    (void)state;
    const char *dir = fresh("chunk_big.zarr");
    put_text(dir, ".zarray", ZA);
    char p[8400];
    snprintf(p, sizeof p, "%s/0.0.0", dir);
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (off_t)ZR_CHUNK_MAX + 1), 0);
    close(fd);
    load_expect(dir, 0, -1, -1, VV_ERR_LIMIT, "0.0.0 is 1073741825 bytes (limit 1073741824)");

    dir = fresh("chunk_dir.zarr");
    put_text(dir, ".zarray", ZA);
    snprintf(p, sizeof p, "%s/0.0.0", dir);
    assert_int_equal(mkdir(p, 0755), 0);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "0.0.0 is not a regular file");

    dir = fresh("chunk_notdir.zarr");
    put_text(dir, ".zarray",
             ZA_("[4, 4, 4]", "[4, 4, 4]", "|u1", ", \"dimension_separator\": \"/\""));
    put_text(dir, "0", "not a folder");
    load_expect(dir, 0, -1, -1, VV_ERR_IO, "0/0/0: Not a directory");

    /* a chunk that is a link to a file of its size outside the store, and
     * a folder of chunks that is a link out of it ("/" separator) */
    char out[4400]; /* fresh() returns its own buffer */
    snprintf(out, sizeof out, "%s", fresh("chunk_outside"));
    unsigned char secret[64];
    memset(secret, 's', sizeof secret);
    vt_write_file(vt_path(out, "secret"), secret, sizeof secret);
    char sub[8400];
    snprintf(sub, sizeof sub, "%s/0", out);
    assert_int_equal(mkdir(sub, 0755), 0);
    snprintf(sub, sizeof sub, "%s/0/0", out);
    assert_int_equal(mkdir(sub, 0755), 0);
    vt_write_file(vt_path(out, "0/0/0"), secret, sizeof secret);
    char target[8400];
    snprintf(target, sizeof target, "%s/secret", out);
    dir = fresh("chunk_link.zarr");
    put_text(dir, ".zarray", ZA);
    snprintf(p, sizeof p, "%s/0.0.0", dir);
    assert_int_equal(symlink(target, p), 0);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT,
                "0.0.0 leaves the store (a link to a file outside it)");
    snprintf(target, sizeof target, "%s/0", out);
    dir = fresh("chunk_dir_link.zarr");
    put_text(dir, ".zarray",
             ZA_("[4, 4, 4]", "[4, 4, 4]", "|u1", ", \"dimension_separator\": \"/\""));
    snprintf(p, sizeof p, "%s/0", dir);
    assert_int_equal(symlink(target, p), 0);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT,
                "0/0/0 leaves the store (a link to a file outside it)");
    /* the pyramid reads its chunks in this process: refused there too */
    vv_pyramid *py = NULL;
    expect(vv_pyramid_open(&py, dir, 0, -1, vt_cache(64u << 20), NULL), VV_ERR_FORMAT,
           "leaves the store", "chunk_dir_link.zarr");
    assert_null(py);
    /* a chunk linked inside the store is read */
    dir = fresh("chunk_inner_link.zarr");
    put_text(dir, ".zarray", ZA);
    vt_write_file(vt_path(dir, "data"), secret, sizeof secret);
    snprintf(p, sizeof p, "%s/0.0.0", dir);
    assert_int_equal(symlink("data", p), 0);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, dir, NULL));
    assert_int_equal(((unsigned char *)v->data)[0], 's');
    vv_volume_free(v);
}

/* FIFOs where files belong: refused at once, never opened for reading
 * (which would block until a writer came). */
static void
test_fifos(void **state) {
    (void)state;
    char p[8400];
    const char *dir = fresh("fifo_zarray.zarr");
    snprintf(p, sizeof p, "%s/.zarray", dir);
    assert_int_equal(mkfifo(p, 0644), 0);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, ".zarray is not a regular file");
    dir = fresh("fifo_zattrs.zarr");
    snprintf(p, sizeof p, "%s/.zattrs", dir);
    assert_int_equal(mkfifo(p, 0644), 0);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, ".zattrs is not a regular file");
    /* detection does not open it either: not a store */
    vv_volume *v = NULL;
    assert_int_not_equal(vv_volume_load(&v, dir, NULL), VV_OK);
    assert_null(v);
    dir = fresh("fifo_chunk.zarr");
    put_text(dir, ".zarray", ZA);
    snprintf(p, sizeof p, "%s/0.0.0", dir);
    assert_int_equal(mkfifo(p, 0644), 0);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "0.0.0 is not a regular file");
}

/* The reader's own arguments. */
static void
test_arguments(void **state) {
    (void)state;
    vv_load_options o;
    vv_load_options_init(&o);
    vv_volume *v = NULL;
    expect(vv_ome_zarr_read(NULL, "x", &o), VV_ERR_INVALID, "zarr: NULL argument", NULL);
    expect(vv_ome_zarr_read(&v, NULL, &o), VV_ERR_INVALID, "zarr: NULL argument", NULL);
    expect(vv_ome_zarr_read(&v, "x", NULL), VV_ERR_INVALID, "zarr: NULL argument", NULL);
}

/* ---- the pyramid ------------------------------------------------------------------------ */

/* A two-level store: level 0 of @p dims0, level 1 of @p dims1 (|u1 or
 * @p dtype1, chunks of 4), no chunk files (the fill value). */
static const char *
pyramid_store(const char *name, const char *za0, const char *za1) {
    const char *dir = fresh(name);
    put_text(dir, ".zattrs",
             MS_(AX3,
                 "[{\"path\": \"0\", \"coordinateTransformations\": " SC3 "}, {\"path\": "
                 "\"1\", \"coordinateTransformations\": "
                 "[{\"type\": \"scale\", \"scale\": [2, 2, 2]}]}]",
                 ""));
    put_text(dir, "0/.zarray", za0);
    put_text(dir, "1/.zarray", za1);
    return dir;
}

static void
pyramid_expect(const char *dir, vv_cache *cache, vv_status want, const char *needle) {
    vv_pyramid *p = (vv_pyramid *)(uintptr_t)1;
    vv_status s = vv_pyramid_open(&p, dir, 0, -1, cache ? cache : vt_cache(64u << 20), NULL);
    assert_null(p);
    expect(s, want, needle, base(dir));
}

static void
test_pyramid(void **state) {
    (void)state;
    /* level 1 of another type, with a channel axis, bigger than level 0 */
    pyramid_expect(pyramid_store("py_type.zarr", ZA, ZA_("[2, 2, 2]", "[4, 4, 4]", "<u2", "")),
                   NULL, VV_ERR_FORMAT, "level 1: its axes, channels, steps or type differ");
    pyramid_expect(pyramid_store("py_big.zarr", ZA, ZA_("[8, 8, 8]", "[4, 4, 4]", "|u1", "")), NULL,
                   VV_ERR_FORMAT, "level 1: 8 voxels along axis 0, more than level 0's 4");
    /* a broken level 1: the level is named */
    pyramid_expect(pyramid_store("py_broken.zarr", ZA, ZA_("[2, 2, 2]", "[4, 4, 4]", "<f16", "")),
                   NULL, VV_ERR_UNSUPPORTED, "level 1: level 1: .zarray: dtype \"<f16\"");
    /* 17 levels */
    const char *dir = fresh("py_levels.zarr");
    char za[8192];
    int n = snprintf(za, sizeof za, "{\"multiscales\": [{\"axes\": " AX3 ", \"datasets\": [");
    for (int i = 0; i <= VV_PYRAMID_MAX_LEVELS; i++)
        n += snprintf(za + n, sizeof za - (size_t)n, "%s{\"path\": \"0\"}", i ? ", " : "");
    snprintf(za + n, sizeof za - (size_t)n, "]}]}");
    put_text(dir, ".zattrs", za);
    put_text(dir, "0/.zarray", ZA);
    pyramid_expect(dir, NULL, VV_ERR_LIMIT, "17 levels (at most 16 are read)");
    /* a cache too small for one box */
    pyramid_expect(pyramid_store("py_small.zarr", ZA_("[512, 512, 512]", "[64, 64, 64]", "<f8", ""),
                                 ZA_("[256, 256, 256]", "[64, 64, 64]", "<f8", "")),
                   vt_cache(1u << 20), VV_ERR_LIMIT, "is smaller than a box of 8 cells");
    /* the coarsest level's chunk does not decode: opening reads it */
    dir = pyramid_store("py_chunk.zarr", ZA, ZA_("[2, 2, 2]", "[2, 2, 2]", "|u1", ""));
    put_text(dir, "1/0.0.0", "short");
    pyramid_expect(dir, NULL, VV_ERR_FORMAT, "5 bytes, an uncompressed chunk has 8");
}

/* Chunks of 512 MiB for an array of 64 voxels, under a budget of 64 MiB:
 * refused before a chunk buffer is allocated (each was filled whole). */
static void
test_chunk_budget(void **state) {
    (void)state;
    const char *dir = fresh("chunk_budget.zarr");
    put_text(dir, ".zarray", ZA_("[4, 4, 4]", "[512, 1024, 1024]", "|u1", ""));
    vv_memory_budget_set((uint64_t)64 << 20);
    load_expect(dir, 0, -1, -1, VV_ERR_LIMIT,
                "a Zarr chunk's buffer: 536870912 bytes is over the memory budget");
    /* the pyramid's scratch buffers alike */
    dir = pyramid_store("py_budget.zarr", ZA_("[4, 4, 4]", "[512, 1024, 1024]", "|u1", ""),
                        ZA_("[2, 2, 2]", "[2, 2, 2]", "|u1", ""));
    pyramid_expect(dir, NULL, VV_ERR_LIMIT, "level 0: a Zarr chunk's buffer: 536870912 bytes");
    vv_memory_budget_set(0);
    /* chunks of one voxel: 4 million files to look for, refused unread */
    dir = fresh("tiny_chunks.zarr");
    put_text(dir, ".zarray", ZA_("[4, 1024, 1024]", "[1, 1, 1]", "|u1", ""));
    load_expect(dir, 0, -1, -1, VV_ERR_LIMIT,
                "4194304 chunks of 1 x 1 x 1 voxels to read whole (at most 1048576");
    /* and out of core (each chunk a piece of the cache: gigabytes of
       bookkeeping for a 4 MiB level) */
    vv_pyramid *p = NULL;
    expect(vv_pyramid_open(&p, dir, 0, -1, vt_cache(64u << 20), NULL), VV_ERR_LIMIT,
           "level 0: 4194304 chunks of 1 x 1 x 1 voxels", NULL);
    assert_null(p);
}

/* Requests outside the pyramid: refused, one line. */
static void
test_pyramid_requests(void **state) {
    (void)state;
    const char *dir = pyramid_store("py_ok.zarr", ZA_("[64, 64, 64]", "[16, 16, 16]", "|u1", ""),
                                    ZA_("[32, 32, 32]", "[16, 16, 16]", "|u1", ""));
    vv_pyramid *p = NULL;
    vt_ok(vv_pyramid_open(&p, dir, 0, -1, vt_cache(64u << 20), NULL));
    const int lv[1] = {0}, lv2[1] = {2}, lo[3] = {0, 0, 0}, hi[3] = {3, 3, 3};
    const int blo[3] = {0, 0, 9}, bhi[3] = {0, 0, 4};
    expect(vv_pyramid_request(p, 1, lv, NULL, hi), VV_ERR_INVALID, "bad request arguments", NULL);
    expect(vv_pyramid_request(p, -1, lv, lo, hi), VV_ERR_INVALID, "bad request arguments", NULL);
    expect(vv_pyramid_request(p, 1, lv2, lo, hi), VV_ERR_INVALID, "request of level 2 (0 .. 1)",
           NULL);
    expect(vv_pyramid_request(p, 1, lv, blo, bhi), VV_ERR_INVALID, "pyramid:", NULL);
    vv_volume *v = NULL;
    expect(vv_pyramid_read_box(p, 0, lo, (const int[3]){64, 0, 0}, &v), VV_ERR_INVALID, NULL, NULL);
    assert_null(v);
    /* over 2^24 chunks in one request: 262145 boxes of 64 chunks */
    const int nb = (1 << 18) + 1;
    int *blv = calloc((size_t)nb, sizeof(int)), *bl = calloc((size_t)nb * 3, sizeof(int)),
        *bh = malloc(sizeof(int) * (size_t)nb * 3);
    assert_true(blv && bl && bh);
    for (int i = 0; i < 3 * nb; i++)
        bh[i] = 63;
    expect(vv_pyramid_request(p, nb, blv, bl, bh), VV_ERR_LIMIT,
           "a request of 16777280 chunks (at most 16777216)", NULL);
    free(blv);
    free(bl);
    free(bh);
    vt_ok(vv_pyramid_request(p, 1, lv, lo, hi));
    vv_pyramid_free(p);
}

/* ---- Zarr v3: sharded stores built byte by byte ------------------------------------ */

#define V3_(shape, grid, dtype, codecs)                                                            \
    "{\"zarr_format\": 3, \"node_type\": \"array\", \"shape\": " shape ", \"data_type\": \"" dtype \
    "\", \"chunk_grid\": {\"name\": \"regular\", \"configuration\": {\"chunk_shape\": " grid       \
    "}}, \"chunk_key_encoding\": {\"name\": \"default\"}, \"fill_value\": 7, \"codecs\": " codecs  \
    "}"
#define V3IDX                                                                                      \
    "\"index_codecs\": [{\"name\": \"bytes\", \"configuration\": {\"endian\": \"little\"}}, "      \
    "{\"name\": \"crc32c\"}]"
#define V3SHARD(inner, codecs)                                                                     \
    "[{\"name\": \"sharding_indexed\", \"configuration\": {\"chunk_shape\": " inner                \
    ", \"codecs\": " codecs ", " V3IDX "}}]"
#define V3RAW "[{\"name\": \"bytes\"}]"

/* One shard of n^3 u8 voxels in inner chunks of m^3, raw, written in
 * order, inner chunk i filled with i + 1 (inner chunk @p empty, when
 * >= 0, left empty), its index at the end with its crc32c: the file
 * c/0/0/0 of folder @p dir. @p edit (may be NULL) changes the index
 * entries (offset, length pairs) before the checksum is taken. Returns the
 * shard's size. */
static size_t
put_shard(const char *dir, int n, int m, int empty, void (*edit)(uint64_t *e)) {
    const int per = n / m, count = per * per * per, cb = m * m * m;
    const size_t size = (size_t)count * (size_t)cb + (size_t)count * 16 + 4;
    unsigned char *b = calloc(1, size);
    assert_non_null(b);
    uint64_t *e = calloc((size_t)count * 2, sizeof *e);
    assert_non_null(e);
    size_t off = 0;
    for (int i = 0; i < count; i++) {
        if (i == empty) {
            e[2 * i] = e[2 * i + 1] = UINT64_MAX;
            continue;
        }
        memset(b + off, i + 1, (size_t)cb);
        e[2 * i] = off;
        e[2 * i + 1] = (uint64_t)cb;
        off += (size_t)cb;
    }
    if (edit)
        edit(e);
    unsigned char *ix = b + (size_t)count * (size_t)cb;
    for (int i = 0; i < 2 * count; i++)
        for (int k = 0; k < 8; k++)
            ix[8 * i + k] = (unsigned char)(e[i] >> (8 * k));
    const uint32_t c = vv_crc32c(0, ix, (size_t)count * 16);
    for (int k = 0; k < 4; k++)
        ix[(size_t)count * 16 + (size_t)k] = (unsigned char)(c >> (8 * k));
    put(dir, "c/0/0/0", b, size);
    free(b);
    free(e);
    return size;
}

static void
edit_past(uint64_t *e) {
    e[2 * 3] = 1u << 20; /* inner chunk 3 past the shard's end */
}

static void
edit_overlap(uint64_t *e) {
    e[2 * 5] = e[2 * 4] + 1; /* inner chunk 5 inside chunk 4 */
}

static void
edit_huge(uint64_t *e) {
    e[2 * 2] = 16;
    e[2 * 2 + 1] = UINT64_MAX - 8; /* wraps around when added */
}

/* Builds the store @p name: zarr.json @p meta and, when @p n > 0, one
 * shard (put_shard). */
static const char *
v3_store(const char *name, const char *meta, int n, int m, int empty, void (*edit)(uint64_t *e)) {
    const char *dir = fresh(name);
    put_text(dir, "zarr.json", meta);
    if (n > 0)
        put_shard(dir, n, m, empty, edit);
    return dir;
}

#define V3OK V3_("[8, 8, 8]", "[8, 8, 8]", "uint8", V3SHARD("[4, 4, 4]", V3RAW))

/* The reference values of CRC-32C, and a good shard read voxel for voxel:
 * the empty inner chunk is the fill value. */
static void
test_v3_good(void **state) {
    (void)state;
    static const unsigned char digits[] = "123456789";
    assert_int_equal(vv_crc32c(0, digits, 9), 0xe3069283u);
    assert_int_equal(vv_crc32c(0, NULL, 0), 0);
    const char *dir = v3_store("v3_ok.zarr", V3OK, 8, 4, 6, NULL);
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_OME_ZARR;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, dir, &o));
    assert_int_equal(v->dims[0], 8);
    const unsigned char *d = v->data;
    for (int k = 0; k < 8; k++)
        for (int j = 0; j < 8; j++)
            for (int i = 0; i < 8; i++) {
                const int c = (k / 4) * 4 + (j / 4) * 2 + i / 4;
                assert_int_equal(d[(k * 8 + j) * 8 + i], c == 6 ? 7 : c + 1);
            }
    /* the range measured chunk by chunk as they were copied is the
     * volume's (a pass over it gives the same) */
    assert_true(v->range[0] == 1 && v->range[1] == 8);
    vv_volume_update_range(v);
    assert_true(v->range[0] == 1 && v->range[1] == 8);
    vv_volume_free(v);
}

/* A box of a sharded level reads the shard's index and the inner chunks
 * it needs, never the whole shard. */
static void
test_v3_box_bytes(void **state) {
    (void)state;
    const char *dir = fresh("v3_box.zarr");
    put_text(dir, "zarr.json",
             "{\"zarr_format\": 3, \"node_type\": \"group\", \"attributes\": {\"ome\": "
             "{\"version\": \"0.5\", \"multiscales\": [{\"axes\": " AX3 ", \"datasets\": "
             "[{\"path\": \"0\", \"coordinateTransformations\": " SC3 "}, {\"path\": \"1\", "
             "\"coordinateTransformations\": [{\"type\": \"scale\", \"scale\": [2, 2, 2]}]}]}]}}}");
    char sub[4400];
    snprintf(sub, sizeof sub, "%s/0", dir);
    mkdir(sub, 0755);
    put_text(sub, "zarr.json",
             V3_("[64, 64, 64]", "[64, 64, 64]", "uint8", V3SHARD("[16, 16, 16]", V3RAW)));
    const size_t shard = put_shard(sub, 64, 16, -1, NULL);
    put_text(dir, "1/zarr.json", V3_("[32, 32, 32]", "[32, 32, 32]", "uint8", V3RAW));
    vv_pyramid *p = NULL;
    vt_ok(vv_pyramid_open(&p, dir, 0, -1, vt_cache(64u << 20), NULL));
    vv_pyramid_stats a, b;
    vv_pyramid_stats_get(p, &a);
    vv_volume *v = NULL;
    vt_ok(vv_pyramid_read_box(p, 0, (const int[3]){20, 20, 20}, (const int[3]){30, 30, 30}, &v));
    /* voxel (20, 20, 20) is in inner chunk (1, 1, 1): number 21 + 1 */
    assert_int_equal(((const unsigned char *)v->data)[0], 22);
    vv_volume_free(v);
    vv_pyramid_stats_get(p, &b);
    const uint64_t want = 64 * 16 + 4 + 16 * 16 * 16; /* the index and one inner chunk */
    if (b.bytes_read - a.bytes_read != want)
        fail_msg("a box in one inner chunk read %llu bytes (want %llu; the shard is %zu)",
                 (unsigned long long)(b.bytes_read - a.bytes_read), (unsigned long long)want,
                 shard);
    /* a second box in the same shard: the index is cached */
    vt_ok(vv_pyramid_read_box(p, 0, (const int[3]){40, 0, 0}, (const int[3]){47, 7, 7}, &v));
    vv_volume_free(v);
    vv_pyramid_stats_get(p, &a);
    assert_int_equal(a.bytes_read - b.bytes_read, 16 * 16 * 16);
    vv_pyramid_free(p);
}

/* Hostile sharded stores: one line naming the file and the field. */
static void
test_v3_hostile(void **state) {
    (void)state;
    load_expect(v3_store("v3_past.zarr", V3OK, 8, 4, -1, edit_past), 0, -1, -1, VV_ERR_FORMAT,
                "c/0/0/0: shard index entry 3: bytes 1048576..1048640 past the shard's end");
    load_expect(v3_store("v3_wrap.zarr", V3OK, 8, 4, -1, edit_huge), 0, -1, -1, VV_ERR_FORMAT,
                "c/0/0/0: shard index entry 2: bytes 16..");
    load_expect(v3_store("v3_overlap.zarr", V3OK, 8, 4, -1, edit_overlap), 0, -1, -1, VV_ERR_FORMAT,
                "c/0/0/0: shard index: inner chunks (or the index) overlap");
    /* a damaged index: the checksum */
    const char *dir = v3_store("v3_crc.zarr", V3OK, 8, 4, -1, NULL);
    char f[4400];
    snprintf(f, sizeof f, "%s/c/0/0/0", dir);
    FILE *fp = fopen(f, "r+b");
    assert_non_null(fp);
    fseek(fp, 8 * 64 + 3, SEEK_SET);
    fputc(0x55, fp);
    fclose(fp);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT,
                "c/0/0/0: shard index: crc32c checksum mismatch (damaged bytes)");
    /* a shard shorter than its index */
    dir = v3_store("v3_short.zarr", V3OK, 0, 0, -1, NULL);
    put_text(dir, "c/0/0/0", "short");
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "c/0/0/0: 5 bytes, fewer than the 132 asked");
    /* an inner chunk that decompresses past its size (a bomb): gzip of
     * 64 KiB where 64 bytes are expected */
    dir = v3_store("v3_bomb.zarr",
                   V3_("[8, 8, 8]", "[8, 8, 8]", "uint8",
                       V3SHARD("[4, 4, 4]", "[{\"name\": \"bytes\"}, {\"name\": \"gzip\"}]")),
                   0, 0, -1, NULL);
    {
        static unsigned char zero[65536], gz[2048];
        z_stream z;
        memset(&z, 0, sizeof z);
        assert_int_equal(deflateInit2(&z, 9, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY),
                         Z_OK);
        z.next_in = zero;
        z.avail_in = sizeof zero;
        z.next_out = gz;
        z.avail_out = sizeof gz;
        assert_int_equal(deflate(&z, Z_FINISH), Z_STREAM_END);
        const size_t gn = sizeof gz - z.avail_out;
        deflateEnd(&z);
        unsigned char buf[4096];
        memcpy(buf, gz, gn);
        uint64_t e[16];
        for (int i = 0; i < 8; i++) {
            e[2 * i] = 0;
            e[2 * i + 1] = gn; /* every inner chunk the same bytes (overlapping) */
        }
        e[2] = e[4] = e[6] = e[8] = e[10] = e[12] = e[14] = UINT64_MAX;
        e[3] = e[5] = e[7] = e[9] = e[11] = e[13] = e[15] = UINT64_MAX;
        for (int i = 0; i < 16; i++)
            for (int k = 0; k < 8; k++)
                buf[gn + 8 * (size_t)i + (size_t)k] = (unsigned char)(e[i] >> (8 * k));
        const uint32_t c = vv_crc32c(0, buf + gn, 128);
        for (int k = 0; k < 4; k++)
            buf[gn + 128 + (size_t)k] = (unsigned char)(c >> (8 * k));
        put(dir, "c/0/0/0", buf, gn + 132);
    }
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "the gzip stream does not decode to 64 bytes");
    /* an NGFF 0.5 group's level without its zarr.json */
    dir = fresh("v3_nolevel.zarr");
    put_text(dir, "zarr.json",
             "{\"zarr_format\": 3, \"node_type\": \"group\", \"attributes\": {\"ome\": "
             "{\"version\": \"0.5\", \"multiscales\": [{\"axes\": " AX3 ", \"datasets\": "
             "[{\"path\": \"0\"}]}]}}}");
    put_text(dir, "0/.zarray", ZA);
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "level 0: no 0/zarr.json (not a Zarr v3 array)");
    /* a raw chunk longer than its voxels: refused before it is read */
    dir = v3_store("v3_long.zarr", V3_("[8, 8, 8]", "[4, 4, 4]", "uint8", V3RAW), 0, 0, -1, NULL);
    {
        static const unsigned char big[100];
        put(dir, "c/0/0/0", big, sizeof big);
    }
    load_expect(dir, 0, -1, -1, VV_ERR_LIMIT, "c/0/0/0 is 100 bytes (limit 64)");
    /* codec chains */
    static const struct {
        const char *name, *codecs, *needle;
        vv_status want;
    } chains[] = {
        {"v3_nobytes", "[{\"name\": \"gzip\"}]",
         "zarr.json: codecs: codec \"gzip\" before the array-to-bytes codec", VV_ERR_FORMAT},
        {"v3_empty", "[]", "zarr.json: codecs: not a list of codecs", VV_ERR_FORMAT},
        {"v3_twice", "[{\"name\": \"bytes\"}, {\"name\": \"bytes\"}]",
         "zarr.json: codecs: two array-to-bytes codecs", VV_ERR_FORMAT},
        {"v3_order",
         "[{\"name\": \"bytes\"}, {\"name\": \"transpose\", \"configuration\": "
         "{\"order\": [2, 1, 0]}}]",
         "zarr.json: codecs: transpose after the array-to-bytes codec", VV_ERR_FORMAT},
        {"v3_perm",
         "[{\"name\": \"transpose\", \"configuration\": {\"order\": [0, 0, 1]}}, "
         "{\"name\": \"bytes\"}]",
         "zarr.json: codecs: transpose order is not a permutation", VV_ERR_FORMAT},
        {"v3_unknown", "[{\"name\": \"bytes\"}, {\"name\": \"lzma\"}]",
         "zarr.json: codecs: codec \"lzma\" (supported:", VV_ERR_UNSUPPORTED},
        {"v3_inner_nobytes", V3SHARD("[4, 4, 4]", "[{\"name\": \"crc32c\"}]"),
         "zarr.json: sharding_indexed codecs: codec \"crc32c\" before the array-to-bytes codec",
         VV_ERR_FORMAT},
        {"v3_divide", V3SHARD("[3, 4, 4]", V3RAW),
         "zarr.json: sharding_indexed: sharding_indexed chunk_shape 0 does not divide the "
         "shard's 8",
         VV_ERR_FORMAT},
        {"v3_nest",
         V3SHARD("[8, 8, 8]",
                 V3SHARD("[8, 8, 8]",
                         V3SHARD("[8, 8, 8]", V3SHARD("[8, 8, 8]", V3SHARD("[8, 8, 8]", V3RAW))))),
         "shards nested over 4 deep", VV_ERR_LIMIT},
    };
    for (size_t i = 0; i < sizeof chains / sizeof chains[0]; i++) {
        char meta[4096], name[64];
        snprintf(meta, sizeof meta, V3_("[8, 8, 8]", "[8, 8, 8]", "uint8", "%s"), chains[i].codecs);
        snprintf(name, sizeof name, "%s.zarr", chains[i].name);
        print_message("%s\n", chains[i].name);
        load_expect(v3_store(name, meta, 0, 0, -1, NULL), 0, -1, -1, chains[i].want,
                    chains[i].needle);
    }
    /* 2^30 inner chunks in one shard: refused before its index is read */
    load_expect(v3_store("v3_many.zarr",
                         V3_("[1024, 1024, 1024]", "[1024, 1024, 1024]", "uint8",
                             V3SHARD("[1, 1, 1]", V3RAW)),
                         0, 0, -1, NULL),
                0, -1, -1, VV_ERR_LIMIT, "over 262144 inner chunks in one shard");
    /* data types and fill values */
    load_expect(v3_store("v3_complex.zarr", V3_("[8, 8, 8]", "[8, 8, 8]", "complex64", V3RAW), 0, 0,
                         -1, NULL),
                0, -1, -1, VV_ERR_UNSUPPORTED, "zarr.json: data_type \"complex64\" (supported:");
    load_expect(
        v3_store("v3_f16.zarr", V3_("[8, 8, 8]", "[8, 8, 8]", "float16", V3RAW), 0, 0, -1, NULL), 0,
        -1, -1, VV_ERR_UNSUPPORTED, "zarr.json: data_type \"float16\"");
    /* deep JSON: jansson's depth limit, one line */
    dir = fresh("v3_deep.zarr");
    {
        const int depth = 100000;
        char *deep = malloc((size_t)depth * 2 + 1);
        assert_non_null(deep);
        memset(deep, '[', (size_t)depth);
        memset(deep + depth, ']', (size_t)depth);
        deep[2 * depth] = '\0';
        put_text(dir, "zarr.json", deep);
        free(deep);
    }
    load_expect(dir, 0, -1, -1, VV_ERR_FORMAT, "zarr.json: line 1:");
}

/* A store whose level 1 is "/etc/passwd": `volvis info` refuses it as a
 * read of that level would (v2 and v3), one line. */
static void
test_info_level_paths(void **state) {
    (void)state;
    char dir[4400]; /* fresh() returns its own buffer */
    snprintf(dir, sizeof dir, "%s", fresh("info_v2.zarr"));
    put_text(dir, ".zattrs", MS_(AX3, "[{\"path\": \"0\"}, {\"path\": \"/etc/passwd\"}]", ""));
    put_text(dir, "0/.zarray", ZA);
    const char *d3 = fresh("info_v3.zarr");
    put_text(d3, "zarr.json",
             "{\"zarr_format\": 3, \"node_type\": \"group\", \"attributes\": {\"ome\": "
             "{\"version\": \"0.5\", \"multiscales\": [{\"axes\": " AX3 ", \"datasets\": "
             "[{\"path\": \"0\"}, {\"path\": \"a/../../x\"}]}]}}}");
    put_text(d3, "0/zarr.json", V3_("[4, 4, 4]", "[4, 4, 4]", "uint8", V3RAW));
    const char *dirs[2] = {dir, d3};
    const char *needles[2] = {".zattrs: dataset 1: path \"/etc/passwd\" leaves the store",
                              "zarr.json: dataset 1: path \"a/../../x\" leaves the store"};
    for (int i = 0; i < 2; i++) {
        const char *args[] = {"info", dirs[i], NULL};
        vt_run_result r = vt_run_cli_v(g_dir, args);
        assert_int_not_equal(r.status, 0);
        if (!strstr(r.err, needles[i]) || !strstr(r.err, base(dirs[i])))
            fail_msg("volvis info printed '%s'", r.err);
        const char *nl = strchr(r.err, '\n');
        assert_true(nl == NULL || nl[1] == '\0');
        vt_run_result_free(&r);
    }
}

/* A scene naming one OME-Zarr store in three objects, out of core: the
 * objects share one source (one client of the cache: its chunks, shard
 * indexes and loader threads held once), not three that each hold and
 * count the same chunks; another step of the store is a source of its own. */
static void
test_scene_shares_store(void **state) {
    (void)state;
    const char *dir = fresh("scene_share");
    char store[4600], scene[4600], other[4600];
    snprintf(store, sizeof store, "%s/img.ome.zarr", dir);
    snprintf(other, sizeof other, "%s/two.ome.zarr", dir);
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, (const int[3]){64, 48, 40}, VV_U16));
    for (uint64_t i = 0; i < vv_volume_voxel_count(v); i++)
        ((uint16_t *)v->data)[i] = (uint16_t)(i * 7 % 4000);
    vv_save_options so;
    vv_save_options_init(&so);
    so.format = VV_FORMAT_OME_ZARR;
    vt_ok(vv_volume_save_with(v, store, &so));
    vt_ok(vv_volume_save_with(v, other, &so));
    vv_volume_free(v);
    snprintf(scene, sizeof scene, "%s/scene.json", dir);
    put_text(dir, "scene.json",
             "{\"objects\": [{\"name\": \"a\", \"file\": \"img.ome.zarr\"}, "
             "{\"name\": \"b\", \"file\": \"img.ome.zarr\", \"position\": [80, 0, 0]}, "
             "{\"name\": \"c\", \"file\": \"./img.ome.zarr\"}, "
             "{\"name\": \"d\", \"file\": \"two.ome.zarr\"}]}");
    vv_cache *cache = vt_cache(64u << 20);
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE;
    oo.cache = cache;
    vv_world *w = NULL;
    vt_ok(vv_scene_load_open(&w, scene, NULL, NULL, &oo));
    assert_int_equal(w->n_objects, 4);
    for (int i = 0; i < 4; i++)
        assert_non_null(w->objects[i]->source);
    assert_ptr_equal(w->objects[0]->source, w->objects[1]->source);
    assert_ptr_equal(w->objects[0]->source, w->objects[2]->source);
    assert_ptr_not_equal(w->objects[0]->source, w->objects[3]->source);
    vv_cache_stats st;
    vv_cache_stats_get(cache, &st);
    assert_int_equal(st.sources, 2); /* img.ome.zarr once, two.ome.zarr once */
    vv_world_free(w);
    vv_cache_stats_get(cache, &st);
    assert_int_equal(st.sources, 0); /* the last object's reference closed it */
}

/* An HCS plate (v2) and an image with labels listed by
 * vv_ome_zarr_contents_get; hostile plates and label groups refused in one
 * line naming the file and the field, by the listing and by a read. */
#define PLATE_(wells, more)                                                                        \
    "{\"plate\": {\"rows\": [{\"name\": \"A\"}, {\"name\": \"B\"}], \"columns\": [{\"name\": "     \
    "\"1\"}], \"wells\": " wells more "}}"
#define WELL_A1 "{\"path\": \"A/1\", \"rowIndex\": 0, \"columnIndex\": 0}"

static const char *
plate_store(const char *name, const char *plate, const char *well) {
    const char *dir = fresh(name);
    put_text(dir, ".zattrs", plate);
    put_text(dir, "A/1/.zattrs", well);
    put_text(dir, "A/1/0/.zattrs", MS("0", SC3));
    put_text(dir, "A/1/0/0/.zarray", ZA);
    return dir;
}

static void
contents_expect(const char *dir, vv_status want, const char *needle) {
    vv_ome_zarr_contents c;
    vv_status s = vv_ome_zarr_contents_get(dir, &c);
    assert_null(c.wells);
    assert_null(c.labels);
    expect(s, want, needle, base(dir));
    load_expect(dir, 0, 0, 0, want, needle); /* a read refuses it alike */
}

static void
test_plate_labels(void **state) {
    (void)state;
    const char *wimg = "{\"well\": {\"images\": [{\"path\": \"0\"}, {\"path\": \"1\"}]}}";
    const char *dir =
        plate_store("plate.zarr", PLATE_("[" WELL_A1 "]", ", \"field_count\": 2"), wimg);
    vv_ome_zarr_contents c;
    vt_ok(vv_ome_zarr_contents_get(dir, &c));
    assert_int_equal(c.kind, VV_OME_ZARR_PLATE);
    assert_int_equal(c.n_rows, 2);
    assert_int_equal(c.n_columns, 1);
    assert_int_equal(c.field_count, 2);
    assert_int_equal(c.n_wells, 1);
    assert_string_equal(c.wells[0].path, "A/1");
    assert_int_equal(c.wells[0].n_fields, 2);
    assert_string_equal(c.wells[0].first_field, "0");
    vv_ome_zarr_contents_clear(&c);
    load_expect(dir, 0, 0, 0, VV_ERR_FORMAT, "plate.zarr/A/1/0)");
    /* the field reads as an image */
    char field[4700];
    snprintf(field, sizeof field, "%s/A/1/0", dir);
    vv_load_options o;
    vv_load_options_init(&o);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, field, &o));
    assert_int_equal(v->dims[0], 4);
    vv_volume_free(v);
    /* hostile plates */
    contents_expect(
        plate_store("p_dotdot.zarr",
                    PLATE_("[{\"path\": \"A/..\", \"rowIndex\": 0, \"columnIndex\": 0}]", ""),
                    wimg),
        VV_ERR_FORMAT, ".zattrs: plate.wells 0: path \"A/..\" leaves the store");
    contents_expect(plate_store("p_abs.zarr",
                                PLATE_("[{\"path\": \"/etc/x\", \"rowIndex\": 0, \"columnIndex\": "
                                       "0}]",
                                       ""),
                                wimg),
                    VV_ERR_FORMAT, "plate.wells 0: path \"/etc/x\" leaves the store");
    contents_expect(plate_store("p_nopath.zarr", PLATE_("[{\"rowIndex\": 0}]", ""), wimg),
                    VV_ERR_FORMAT, "plate.wells 0: no path");
    contents_expect(
        plate_store("p_col.zarr",
                    PLATE_("[{\"path\": \"A/1\", \"rowIndex\": 0, \"columnIndex\": 1}]", ""), wimg),
        VV_ERR_FORMAT, "plate.wells 0: rowIndex or columnIndex");
    contents_expect(
        plate_store("p_fc.zarr", PLATE_("[" WELL_A1 "]", ", \"field_count\": -1"), wimg),
        VV_ERR_FORMAT, "plate.field_count is not a count");
    contents_expect(plate_store("p_rows.zarr", "{\"plate\": {\"rows\": 3}}", wimg), VV_ERR_FORMAT,
                    "plate.rows is not a list");
    contents_expect(plate_store("p_field.zarr", PLATE_("[" WELL_A1 "]", ""),
                                "{\"well\": {\"images\": [{\"path\": \"0/../../..\"}]}}"),
                    VV_ERR_FORMAT, "A/1/.zattrs: well.images 0: path \"0/../../..\"");
    contents_expect(plate_store("p_ctl.zarr", PLATE_("[" WELL_A1 "]", ""),
                                "{\"well\": {\"images\": [{\"path\": \"0\\n1\"}]}}"),
                    VV_ERR_FORMAT, "A/1/.zattrs: well.images 0: path");
    /* 4097 wells */
    char *big = malloc(4097 * 64 + 256);
    assert_non_null(big);
    int n = sprintf(big, "{\"plate\": {\"rows\": [], \"columns\": [], \"wells\": [");
    for (int i = 0; i < 4097; i++)
        n += sprintf(big + n, "%s" WELL_A1, i ? ", " : "");
    sprintf(big + n, "]}}");
    contents_expect(plate_store("p_many.zarr", big, wimg), VV_ERR_LIMIT,
                    "plate.wells: 4097 entries (at most 4096 are read)");
    free(big);
    /* an image with labels; a label named out of the store */
    char img[4600]; /* fresh's buffer is reused below */
    snprintf(img, sizeof img, "%s", fresh("img_labels.zarr"));
    dir = img;
    put_text(dir, ".zattrs", MS("0", SC3));
    put_text(dir, "0/.zarray", ZA);
    put_text(dir, "labels/.zattrs", "{\"labels\": [\"cells\"]}");
    put_text(dir, "labels/cells/.zattrs",
             "{\"multiscales\": [{\"axes\": " AX3 ", \"datasets\": [{\"path\": \"0\"}]}], "
             "\"image-label\": {\"colors\": [{\"label-value\": 1, \"rgba\": [1, 2, 3, 4]}]}}");
    put_text(dir, "labels/cells/0/.zarray", ZA_("[4, 4, 4]", "[2, 2, 2]", "<u2", ""));
    vt_ok(vv_ome_zarr_contents_get(dir, &c));
    assert_int_equal(c.kind, VV_OME_ZARR_IMAGE);
    assert_int_equal(c.n_labels, 1);
    assert_string_equal(c.labels[0].name, "cells");
    assert_int_equal(c.labels[0].type, VV_U16);
    assert_int_equal(c.labels[0].n_colors, 1);
    vv_ome_zarr_contents_clear(&c);
    vv_load_info info;
    memset(&info, 0, sizeof info);
    vv_load_options_init(&o);
    o.info = &info;
    snprintf(field, sizeof field, "%s/labels/cells", dir);
    vt_ok(vv_volume_load(&v, field, &o));
    assert_int_equal(info.is_label, 1);
    vv_volume_free(v);
    /* a scene object naming the label image, read whole and out of core:
     * a label volume unless the object says otherwise */
    put_text(dir, "scene.json",
             "{\"objects\": [{\"file\": \"labels/cells\"}, {\"file\": \"labels/cells\", "
             "\"position\": [9, 0, 0], \"segmentation\": \"transfer_function\"}]}");
    char scene[4700];
    snprintf(scene, sizeof scene, "%s/scene.json", dir);
    for (int ooc = 0; ooc < 2; ooc++) {
        vv_open_options oo;
        vv_open_options_init(&oo);
        oo.mode = VV_OPEN_OUT_OF_CORE;
        oo.cache = vt_cache(64u << 20);
        vv_world *w = NULL;
        vt_ok(vv_scene_load_open(&w, scene, NULL, NULL, ooc ? &oo : NULL));
        assert_int_equal(w->n_objects, 2);
        assert_int_equal(w->objects[0]->segmentation, VV_SEG_LABELS);
        assert_int_equal(w->objects[1]->segmentation, VV_SEG_TRANSFER_FUNCTION);
        vv_world_free(w);
    }
    put_text(dir, "labels/.zattrs", "{\"labels\": [\"../0\"]}");
    vv_status s = vv_ome_zarr_contents_get(dir, &c);
    expect(s, VV_ERR_FORMAT, "labels/.zattrs: labels 0: path \"../0\" leaves the store",
           "img_labels.zarr");
    put_text(dir, "labels/.zattrs", "{\"labels\": [\"0\"]}"); /* not a multiscales image */
    s = vv_ome_zarr_contents_get(dir, &c);
    expect(s, VV_ERR_FORMAT, "labels 0: \"0\" is not a multiscales image", "img_labels.zarr");
    /* a label folder that is a link out of the store */
    const char *out = fresh("outside_labels");
    put_text(out, ".zattrs",
             "{\"multiscales\": [{\"axes\": " AX3 ", \"datasets\": [{\"path\": "
             "\"0\"}]}]}");
    put_text(dir, "labels/.zattrs", "{\"labels\": [\"ext\"]}");
    char link[4700];
    snprintf(link, sizeof link, "%s/labels/ext", dir);
    assert_int_equal(symlink(out, link), 0);
    s = vv_ome_zarr_contents_get(dir, &c);
    expect(s, VV_ERR_FORMAT, "labels/ext/.zattrs leaves the store", "img_labels.zarr");
}

int
main(void) {
    setenv("VOLVIS_SANDBOX", "0", 1);
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("errors_zarr"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_metadata),         cmocka_unit_test(test_path_leaves_store),
        cmocka_unit_test(test_path_symlink),     cmocka_unit_test(test_json_too_large),
        cmocka_unit_test(test_chunks),           cmocka_unit_test(test_chunk_files),
        cmocka_unit_test(test_chunk_budget),     cmocka_unit_test(test_fifos),
        cmocka_unit_test(test_arguments),        cmocka_unit_test(test_pyramid),
        cmocka_unit_test(test_pyramid_requests), cmocka_unit_test(test_v3_good),
        cmocka_unit_test(test_v3_box_bytes),     cmocka_unit_test(test_v3_hostile),
        cmocka_unit_test(test_info_level_paths), cmocka_unit_test(test_scene_shares_store),
        cmocka_unit_test(test_plate_labels),
    };
    return vt_run_tests(tests, NULL, NULL);
}
