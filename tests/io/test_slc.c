/* SLC reader and writer: real files, round trips, hand-built and bad input. */
#include "testutil.h"

#include "io/io_internal.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Sums, extremes and a few voxels of the shared SLC files, computed once
   with an independent Python decoder (RLE per the format description). */
typedef struct slc_expect {
    const char *file;
    int dims[3];
    int unit, origin, mod;
    uint64_t sum;
    int probe[3][4]; /* i, j, k, value */
} slc_expect;

static const slc_expect expected[] = {
    {"volumes/nut.slc",
     {68, 41, 59},
     2,
     5,
     0,
     5807640,
     {{34, 20, 29, 2}, {10, 20, 30, 255}, {67, 40, 58, 0}}},
    {"volumes/bolt.slc",
     {70, 123, 66},
     2,
     5,
     0,
     19004049,
     {{35, 61, 33, 253}, {10, 20, 30, 0}, {69, 122, 65, 0}}},
    {"volumes/neghip.slc",
     {66, 66, 66},
     1,
     6,
     0,
     4824177,
     {{33, 33, 33, 0}, {10, 20, 30, 211}, {65, 65, 65, 0}}},
    {"volumes/sphere.slc",
     {50, 50, 50},
     1,
     7,
     0,
     6746931,
     {{25, 25, 25, 255}, {10, 20, 30, 143}, {49, 49, 49, 0}}},
};

static uint64_t
sum_u8(const vv_volume *v) {
    uint64_t s = 0, n = vv_volume_voxel_count(v);
    const unsigned char *d = v->data;
    for (uint64_t i = 0; i < n; i++)
        s += d[i];
    return s;
}

static void
test_real_files(void **state) {
    (void)state;
    for (size_t f = 0; f < sizeof expected / sizeof expected[0]; f++) {
        const slc_expect *e = &expected[f];
        vv_volume *v = NULL;
        vt_ok(vv_slc_read(&v, vt_data(e->file)));
        assert_int_equal(v->type, VV_U8);
        for (int a = 0; a < 3; a++) {
            assert_int_equal(v->dims[a], e->dims[a]);
            assert_true(v->spacing[a] == 1.0);
            assert_true(v->origin[a] == 0.0);
        }
        assert_int_equal(v->unit, e->unit);
        assert_int_equal(v->data_origin, e->origin);
        assert_int_equal(v->modification, e->mod);
        assert_true(sum_u8(v) == e->sum);
        assert_true(v->range[0] == 0.0);
        assert_true(v->range[1] == 255.0);
        for (int p = 0; p < 3; p++)
            assert_true(vv_volume_get(v, e->probe[p][0], e->probe[p][1], e->probe[p][2]) ==
                        e->probe[p][3]);
        vv_volume_free(v);
    }
}

static void
assert_same_volume(const vv_volume *a, const vv_volume *b) {
    for (int i = 0; i < 3; i++) {
        assert_int_equal(a->dims[i], b->dims[i]);
        assert_true(a->spacing[i] == b->spacing[i]);
    }
    assert_int_equal(a->type, b->type);
    assert_int_equal(a->unit, b->unit);
    assert_int_equal(a->data_origin, b->data_origin);
    assert_int_equal(a->modification, b->modification);
    assert_memory_equal(a->data, b->data, (size_t)vv_volume_voxel_count(a));
}

/* Checks the written icon: at most 64x64, R = G = B, max = the volume max. */
static void
check_icon(const char *path, const vv_volume *v) {
    size_t n;
    unsigned char *d = vt_read_file(path, &n);
    int iw = 0, ih = 0, pos = 0, lines = 0;
    /* Skip the four header lines, then "IW IH X". */
    while ((size_t)pos < n && lines < 4)
        if (d[pos++] == '\n')
            lines++;
    assert_int_equal(sscanf((const char *)d + pos, "%d %d X", &iw, &ih), 2);
    assert_true(iw >= 1 && iw <= 64 && ih >= 1 && ih <= 64);
    const unsigned char *x = memchr(d + pos, 'X', n - (size_t)pos);
    assert_non_null(x);
    const unsigned char *icon = x + 1;
    size_t plane = (size_t)iw * (size_t)ih;
    assert_true((size_t)(icon - d) + 3 * plane <= n);
    assert_memory_equal(icon, icon + plane, plane);
    assert_memory_equal(icon, icon + 2 * plane, plane);
    unsigned char m = 0;
    for (size_t i = 0; i < plane; i++)
        if (icon[i] > m)
            m = icon[i];
    assert_true(m == v->range[1]);
    free(d);
}

static void
round_trip(const vv_volume *v, const char *name) {
    char path[1200];
    const char *dir = vt_outdir("io_slc_roundtrip");
    for (int rle = 0; rle <= 1; rle++) {
        snprintf(path, sizeof path, "%s/%s-%d.slc", dir, name, rle);
        vt_ok(vv_slc_write(v, path, rle));
        vv_volume *r = NULL;
        vt_ok(vv_slc_read(&r, path));
        assert_same_volume(v, r);
        check_icon(path, r);
        vv_volume_free(r);
    }
}

static void
test_round_trip_real(void **state) {
    (void)state;
    const char *files[] = {"volumes/nut.slc", "volumes/bolt.slc"};
    for (int f = 0; f < 2; f++) {
        vv_volume *v = NULL;
        vt_ok(vv_slc_read(&v, vt_data(files[f])));
        round_trip(v, f ? "bolt" : "nut");
        vv_volume_free(v);
    }
}

static uint32_t
lcg(uint32_t *s) {
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

/* Long runs (past 127), runs of 1-3, literal stretches of random bytes. */
static void
test_round_trip_synthetic(void **state) {
    (void)state;
    int dims[3] = {67, 53, 11};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    unsigned char *d = v->data;
    uint64_t n = vv_volume_voxel_count(v), i = 0;
    uint32_t seed = 12345;
    while (i < n) {
        uint32_t kind = lcg(&seed) % 4, len;
        if (kind == 0)
            len = 100 + lcg(&seed) % 400; /* long run */
        else if (kind == 1)
            len = 1 + lcg(&seed) % 3; /* short run */
        else
            len = 1 + lcg(&seed) % 300; /* literal stretch */
        unsigned char c = (unsigned char)lcg(&seed);
        for (uint32_t k = 0; k < len && i < n; k++, i++)
            d[i] = kind >= 2 ? (unsigned char)lcg(&seed) : c;
    }
    v->spacing[0] = 0.5;
    v->spacing[1] = 1.25;
    v->spacing[2] = 3.1;
    v->unit = VV_UNIT_MICRON;
    v->data_origin = VV_ORIGIN_CT;
    v->modification = VV_MOD_FILTERED;
    vv_volume_update_range(v);
    round_trip(v, "synthetic");

    /* Constant and all-literal volumes, and a 1x1x1 volume. */
    memset(d, 7, (size_t)n);
    vv_volume_update_range(v);
    round_trip(v, "constant");
    for (i = 0; i < n; i++)
        d[i] = (unsigned char)(i * 7 + (i >> 3));
    vv_volume_update_range(v);
    round_trip(v, "ramp");
    vv_volume_free(v);

    int one[3] = {1, 1, 1};
    vt_ok(vv_volume_new(&v, one, VV_U8));
    v->unit = VV_UNIT_MM; /* SLC has no "unknown" unit */
    ((unsigned char *)v->data)[0] = 200;
    vv_volume_update_range(v);
    round_trip(v, "one");
    vv_volume_free(v);

    /* A run-heavy volume compresses. */
    int big[3] = {128, 128, 4};
    vt_ok(vv_volume_new(&v, big, VV_U8));
    vv_volume_update_range(v);
    char path[1200];
    snprintf(path, sizeof path, "%s/zeros.slc", vt_outdir("io_slc_roundtrip"));
    vt_ok(vv_slc_write(v, path, 1));
    size_t fsize;
    free(vt_read_file(path, &fsize));
    assert_true(fsize < 128 * 128 * 4 / 20 + 3 * 64 * 64 + 100);
    vv_volume_free(v);
}

static const char *
write_tmp(const char *name, const void *data, size_t n) {
    static char path[1200];
    snprintf(path, sizeof path, "%s/%s", vt_outdir("io_slc_bad"), name);
    vt_write_file(path, data, n);
    return path;
}

/* Header of a 4 x 2 x ZSIZE RLE volume with a 1 x 1 icon. */
#define HDR4x2(z) "11111\n4 2 " #z " 8\n1 1 2.5\n1 1 0 1\n1 1 X\x01\x02\x03"

static void
test_hand_built_short_slice(void **state) {
    (void)state;
    /* Slice 0: 7 voxels of 5 then the terminator: one voxel short.
       Slice 1: literal 1 2 3, repeat 4 x 9, no terminator (n ends first).
       Slice 2: empty (terminator only). */
    static const char file[] = HDR4x2(3) "3 X\x07\x05\x00"
                                         "6 X\x83\x01\x02\x03\x04\x09"
                                         "1 X\x00";
    vv_volume *v = NULL;
    vt_ok(vv_slc_read(&v, write_tmp("short.slc", file, sizeof file - 1)));
    static const unsigned char want[24] = {5, 5, 5, 5, 5, 5, 5, 0, 1, 2, 3, 9,
                                           9, 9, 9, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    assert_memory_equal(v->data, want, 24);
    assert_true(v->spacing[2] == 2.5);
    assert_true(v->range[1] == 9.0);
    vv_volume_free(v);

    /* Whitespace between the header fields is free-form. */
    static const char loose[] = "11111 4\t2\n\n1   8 1.0 1.0\r\n1.0 0 0 0 1 0 0 X"
                                "2 X\x08\x06";
    vt_ok(vv_slc_read(&v, write_tmp("loose.slc", loose, sizeof loose - 1)));
    for (int i = 0; i < 8; i++)
        assert_int_equal(((unsigned char *)v->data)[i], 6);
    vv_volume_free(v);
}

static void
expect_error(const char *name, const void *data, size_t n, vv_status want, const char *needle) {
    vv_volume *v = (vv_volume *)1;
    vv_error_clear();
    vv_status s = vv_slc_read(&v, write_tmp(name, data, n));
    if (s != want)
        fail_msg("%s: got %s (%s), want %s", name, vv_status_name(s), vv_error_message(),
                 vv_status_name(want));
    assert_null(v);
    const char *msg = vv_error_message();
    assert_non_null(strstr(msg, "slc: "));
    assert_non_null(strstr(msg, name));
    if (needle && !strstr(msg, needle))
        fail_msg("%s: message \"%s\" lacks \"%s\"", name, msg, needle);
}

static void
test_bad_input(void **state) {
    (void)state;
    expect_error("empty.slc", "", 0, VV_ERR_FORMAT, NULL);
    expect_error("magic.slc", "11112\n4 2 1 8\n", 14, VV_ERR_FORMAT, "magic");
    static const char trunc_hdr[] = "11111\n68 41";
    expect_error("trunc_hdr.slc", trunc_hdr, sizeof trunc_hdr - 1, VV_ERR_FORMAT, "truncated");
    static const char absurd[] = "11111\n100000 100000 100000 8\n1 1 1\n1 1 0 1\n0 0 X";
    expect_error("absurd.slc", absurd, sizeof absurd - 1, VV_ERR_LIMIT, NULL);
    /* Within the limits but far more than the file could hold: no 7 GB allocation. */
    static const char big[] = "11111\n60000 60000 2 8\n1 1 1\n1 1 0 1\n0 0 X1 X\x00";
    expect_error("big.slc", big, sizeof big - 1, VV_ERR_FORMAT, "truncated");
    static const char bigraw[] = "11111\n60000 60000 2 8\n1 1 1\n1 1 0 0\n0 0 X\x00\x00";
    expect_error("bigraw.slc", bigraw, sizeof bigraw - 1, VV_ERR_FORMAT, "truncated");
    static const char neg[] = "11111\n-4 2 1 8\n1 1 1\n1 1 0 1\n0 0 X";
    expect_error("neg.slc", neg, sizeof neg - 1, VV_ERR_FORMAT, "size");
    static const char bits[] = "11111\n4 2 1 16\n1 1 1\n1 1 0 1\n0 0 X";
    expect_error("bits.slc", bits, sizeof bits - 1, VV_ERR_UNSUPPORTED, "16 bits");
    static const char spacing[] = "11111\n4 2 1 8\n1 0 1\n1 1 0 1\n0 0 X";
    expect_error("spacing.slc", spacing, sizeof spacing - 1, VV_ERR_FORMAT, "spacing");
    static const char comp[] = "11111\n4 2 1 8\n1 1 1\n1 1 0 2\n0 0 X";
    expect_error("comp.slc", comp, sizeof comp - 1, VV_ERR_FORMAT, "compression");
    static const char icon[] = "11111\n4 2 1 8\n1 1 1\n1 1 0 1\n100 100 X\x01\x02";
    expect_error("icon.slc", icon, sizeof icon - 1, VV_ERR_FORMAT, "icon");
    /* A run that overflows the slice (8 voxels). */
    static const char over[] = HDR4x2(2) "3 X\x07\x05\x00"
                                         "5 X\x05\x01\x04\x02\x00";
    expect_error("over.slc", over, sizeof over - 1, VV_ERR_FORMAT,
                 "slice 1: run of 4 bytes overflows the slice (9 > 8)");
    /* A literal run longer than the slice data. */
    static const char lit[] = HDR4x2(1) "3 X\x85\x01\x02";
    expect_error("lit.slc", lit, sizeof lit - 1, VV_ERR_FORMAT, "slice 0: literal run");
    static const char lit2[] = HDR4x2(1) "3 X\x83\x01\x02"
                                         "\x00\x00\x00";
    expect_error("lit2.slc", lit2, sizeof lit2 - 1, VV_ERR_FORMAT, "slice 0: literal run");
    /* A repeat run whose value byte is missing. */
    static const char rep[] = HDR4x2(1) "1 X\x05";
    expect_error("rep.slc", rep, sizeof rep - 1, VV_ERR_FORMAT, "slice 0: repeat run");
    /* A slice size past the end of the file, and a negative one. */
    static const char past[] = HDR4x2(1) "300 X\x08\x01\x00";
    expect_error("past.slc", past, sizeof past - 1, VV_ERR_FORMAT, "slice 0: compressed size");
    static const char negn[] = HDR4x2(1) "-3 X\x08\x01\x00";
    expect_error("negn.slc", negn, sizeof negn - 1, VV_ERR_FORMAT, "slice 0: compressed size");
    /* Missing slices. */
    static const char missing[] = HDR4x2(2) "3 X\x08\x01\x00";
    expect_error("missing.slc", missing, sizeof missing - 1, VV_ERR_FORMAT, "slice 1");
    /* Uncompressed data one slice short. */
    static const char raw[] = "11111\n4 2 2 8\n1 1 1\n1 1 0 0\n0 0 X\x01\x02\x03\x04\x05\x06\x07"
                              "\x08\x09";
    expect_error("raw.slc", raw, sizeof raw - 1, VV_ERR_FORMAT, "truncated");

    vv_volume *v = (vv_volume *)1;
    assert_int_equal(vv_slc_read(&v, vt_outdir("io_slc_bad")), VV_ERR_IO); /* a directory */
    vt_err(vv_slc_read(&v, "/nonexistent/dir/x.slc"));
    assert_null(v);
    assert_int_equal(vv_slc_read(&v, "/nonexistent/dir/x.slc"), VV_ERR_IO);
}

/* Every prefix and many corruptions of a real file: an error or a volume,
   never a crash (the ASan build checks the memory accesses). */
static void
test_truncations_and_noise(void **state) {
    (void)state;
    size_t n;
    unsigned char *d = vt_read_file(vt_data("volumes/nut.slc"), &n);
    int ok = 0;
    for (size_t cut = 0; cut < n; cut += (cut < 26200 ? 37 : 997)) {
        vv_volume *v = NULL;
        vv_status s = vv_slc_read(&v, write_tmp("cut.slc", d, cut));
        assert_true(s < 0);
        assert_null(v);
        assert_true(vv_error_message()[0] != '\0');
    }
    uint32_t seed = 99;
    unsigned char *c = malloc(n);
    assert_non_null(c);
    for (int trial = 0; trial < 200; trial++) {
        memcpy(c, d, n);
        int flips = 1 + (int)(lcg(&seed) % 8);
        for (int f = 0; f < flips; f++)
            c[26100 + lcg(&seed) % (n - 26100)] = (unsigned char)lcg(&seed);
        vv_volume *v = NULL;
        vv_status s = vv_slc_read(&v, write_tmp("noise.slc", c, n));
        if (s == VV_OK) {
            ok++;
            vv_volume_free(v);
        } else {
            assert_null(v);
        }
    }
    (void)ok;
    /* Random bytes, with and without the magic number in front. */
    for (int trial = 0; trial < 100; trial++) {
        size_t len = 1 + lcg(&seed) % 4000;
        for (size_t i = 0; i < len; i++)
            c[i] = (unsigned char)lcg(&seed);
        if (trial % 2)
            memcpy(c, "11111 ", len < 6 ? len : 6);
        vv_volume *v = NULL;
        vv_status s = vv_slc_read(&v, write_tmp("random.slc", c, len));
        assert_true(s < 0);
        assert_null(v);
    }
    free(c);
    free(d);
}

static int
count_entries(const char *dir) {
    DIR *dp = opendir(dir);
    assert_non_null(dp);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(dp)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            n++;
    closedir(dp);
    return n;
}

static void
test_write_errors(void **state) {
    (void)state;
    const char *dir = vt_outdir("io_slc_write");
    char base[1024], path[1200];
    snprintf(base, sizeof base, "%s", dir);
    int dims[3] = {5, 4, 3};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));

    /* A nonexistent directory: an error and nothing written. */
    int before = count_entries(base);
    snprintf(path, sizeof path, "%s/no/such/dir/x.slc", base);
    vt_err(vv_slc_write(v, path, 1));
    assert_int_equal(count_entries(base), before);

    /* A failing write over an existing file leaves it as it was. */
    snprintf(path, sizeof path, "%s/keep.slc", base);
    remove(path);
    before = count_entries(base);
    vt_write_file(path, "old contents", 12);
    vv_volume *w = NULL;
    vt_ok(vv_volume_new(&w, dims, VV_U16));
    vv_error_clear();
    assert_int_equal(vv_slc_write(w, path, 1), VV_ERR_UNSUPPORTED);
    assert_non_null(strstr(vv_error_message(), "keep.slc"));
    size_t n;
    unsigned char *d = vt_read_file(path, &n);
    assert_int_equal(n, 12);
    assert_memory_equal(d, "old contents", 12);
    free(d);
    assert_int_equal(count_entries(base), before + 1);

    /* A successful write replaces it. */
    vt_ok(vv_slc_write(v, path, 0));
    d = vt_read_file(path, &n);
    assert_memory_equal(d, "11111", 5);
    free(d);
    assert_int_equal(count_entries(base), before + 1);

    vv_volume_free(w);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_real_files),
        cmocka_unit_test(test_round_trip_real),
        cmocka_unit_test(test_round_trip_synthetic),
        cmocka_unit_test(test_hand_built_short_slice),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_truncations_and_noise),
        cmocka_unit_test(test_write_errors),
    };
    return vt_run_tests(tests, NULL, NULL);
}
