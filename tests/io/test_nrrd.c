/*
 * NRRD reading and writing: the shared files, hand-written headers for each
 * encoding and layout, a bit-exact round trip for every voxel type, and bad
 * input.
 */
#include "testutil.h"

#include "io/io_internal.h"

#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include <teem/nrrd.h>

/*
 * Teem 1.12 leaks its gzip stream when a gzip-encoded file is truncated
 * (_nrrdEncodingGzip_read returns without _nrrdGzClose). Suppress exactly
 * that for LeakSanitizer; full stacks are needed to see the Teem frames
 * inside zlib's allocations. Same list as tests/lsan.supp.
 */
const char *__lsan_default_suppressions(void);
const char *__asan_default_options(void);
const char *
__lsan_default_suppressions(void) {
    return "leak:_nrrdGzOpen\nleak:_nrrdEncodingGzip_read\n";
}
const char *
__asan_default_options(void) {
    return "fast_unwind_on_malloc=0";
}

/* cmocka 1.1.5 has no assert_double_equal */

static char *
out_path(const char *name) {
    static char buf[4][1024];
    static int slot;
    slot = (slot + 1) % 4;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", vt_outdir("io_nrrd"), name);
    return buf[slot];
}

static void
write_text(const char *path, const char *text) {
    vt_write_file(path, text, strlen(text));
}

static void
test_headsq_detached_multifile(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_nrrd_read(&v, vt_data("volumes/headsq/quarter.nhdr")));
    assert_int_equal(v->dims[0], 64);
    assert_int_equal(v->dims[1], 64);
    assert_int_equal(v->dims[2], 93);
    assert_int_equal(v->type, VV_I16);
    assert_near(v->spacing[0], 3.2, 1e-12);
    assert_near(v->spacing[1], 3.2, 1e-12);
    assert_near(v->spacing[2], 1.5, 1e-12);
    /* slice k = 49 is the file quarter.50, little-endian shorts */
    size_t n = 0;
    unsigned char *raw = vt_read_file(vt_data("volumes/headsq/quarter.50"), &n);
    assert_int_equal(n, 64 * 64 * 2);
    for (int j = 0; j < 64; j += 7)
        for (int i = 0; i < 64; i += 5) {
            size_t o = ((size_t)j * 64 + (size_t)i) * 2;
            int16_t x = (int16_t)(raw[o] | raw[o + 1] << 8);
            assert_int_equal((int)vv_volume_get(v, i, j, 49), x);
        }
    free(raw);
    assert_true(v->range[1] > v->range[0]);
    vv_volume_free(v);
}

static void
test_ct_head(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_nrrd_read(&v, vt_data("volumes/ct_head.nrrd")));
    assert_int_equal(v->dims[0], 256);
    assert_int_equal(v->dims[1], 256);
    assert_int_equal(v->dims[2], 108);
    assert_int_equal(v->type, VV_I16);
    assert_near(v->spacing[0], 0.9570312, 1e-9);
    assert_near(v->spacing[1], 0.9570312, 1e-9);
    assert_near(v->spacing[2], 1.5, 1e-12);
    assert_near(v->range[0], -1024, 0);
    assert_near(v->range[1], 2986, 0);
    vv_volume_free(v);
}

/* A volume of type t whose values span the type's range, with a rotated frame. */
static vv_volume *
make_volume(vv_voxel_type t) {
    int dims[3] = {7, 5, 3};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, t));
    size_t sz = vv_voxel_type_size(t);
    unsigned char *p = v->data;
    uint32_t x = 0x12345678u + (uint32_t)t;
    for (size_t i = 0; i < 7 * 5 * 3 * sz; i++) {
        x = x * 1664525u + 1013904223u;
        p[i] = (unsigned char)(x >> 24);
    }
    if (t == VV_F32) { /* keep the floats finite but odd */
        float *f = v->data;
        for (int i = 0; i < 7 * 5 * 3; i++)
            f[i] = (float)(i * 0.37 - 11.0) / 3.0f;
        f[3] = -0.0f;
        f[4] = 3.4e38f;
    } else if (t == VV_F64) {
        double *d = v->data;
        for (int i = 0; i < 7 * 5 * 3; i++)
            d[i] = (i * 0.37 - 11.0) / 3.0;
        d[3] = 1e-300;
        d[4] = -1.7e308;
    }
    v->spacing[0] = 0.5;
    v->spacing[1] = 1.25;
    v->spacing[2] = 2.75;
    v->origin[0] = -10.125;
    v->origin[1] = 20.5;
    v->origin[2] = 3.0 / 7.0;
    double c = cos(0.5), s = sin(0.5);
    double rot[9] = {c, -s, 0, s, c, 0, 0, 0, 1}; /* columns are the rotated axes */
    memcpy(v->direction, rot, sizeof rot);
    v->unit = VV_UNIT_MM;
    vv_volume_update_range(v);
    return v;
}

static void
assert_same_volume(const vv_volume *a, const vv_volume *b) {
    for (int i = 0; i < 3; i++) {
        assert_int_equal(a->dims[i], b->dims[i]);
        assert_near(a->spacing[i], b->spacing[i], 1e-12);
        assert_near(a->origin[i], b->origin[i], 1e-12);
    }
    for (int i = 0; i < 9; i++)
        assert_near(a->direction[i], b->direction[i], 1e-12);
    assert_int_equal(a->type, b->type);
    assert_int_equal(a->unit, b->unit);
    assert_memory_equal(a->data, b->data, vv_volume_voxel_count(a) * vv_voxel_type_size(a->type));
}

static void
test_round_trip_all_types(void **state) {
    (void)state;
    for (int t = VV_U8; t <= VV_F64; t++) {
        for (int gz = 0; gz < 2; gz++) {
            vv_volume *v = make_volume((vv_voxel_type)t);
            char name[64];
            snprintf(name, sizeof name, "rt_%s_%d.nrrd", vv_voxel_type_name((vv_voxel_type)t), gz);
            const char *path = out_path(name);
            vt_ok(vv_nrrd_write(v, path, gz));
            vv_volume *r = NULL;
            vt_ok(vv_nrrd_read(&r, path));
            assert_same_volume(v, r);
            assert_near(v->range[0], r->range[0], 0);
            assert_near(v->range[1], r->range[1], 0);
            /* the header says what it is */
            size_t n = 0;
            unsigned char *text = vt_read_file(path, &n);
            assert_non_null(strstr((char *)text, gz ? "encoding: gzip" : "encoding: raw"));
            assert_non_null(strstr((char *)text, "space origin:"));
            free(text);
            vv_volume_free(r);
            vv_volume_free(v);
        }
    }
}

static void
test_ascii_encoding(void **state) {
    (void)state;
    const char *path = out_path("ascii.nrrd");
    write_text(path, "NRRD0004\n"
                     "type: float\n"
                     "dimension: 3\n"
                     "sizes: 2 2 2\n"
                     "spacings: 0.5 0.25 4\n"
                     "axis mins: 1 2 3\n"
                     "encoding: ascii\n"
                     "\n"
                     "1.5 -2 3 4\n5 6 7 8.25\n");
    vv_volume *v = NULL;
    vt_ok(vv_nrrd_read(&v, path));
    assert_int_equal(v->type, VV_F32);
    assert_near(vv_volume_get(v, 0, 0, 0), 1.5, 0);
    assert_near(vv_volume_get(v, 1, 0, 0), -2, 0);
    assert_near(vv_volume_get(v, 1, 1, 1), 8.25, 0);
    assert_near(v->spacing[1], 0.25, 0);
    assert_near(v->spacing[2], 4, 0);
    assert_near(v->origin[0], 1, 0);
    assert_near(v->origin[2], 3, 0);
    assert_near(v->range[0], -2, 0);
    assert_near(v->range[1], 8.25, 0);
    vv_volume_free(v);
}

static void
test_big_endian_and_byte_skip(void **state) {
    (void)state;
    /* attached, big-endian u16 */
    const char *hdr = "NRRD0004\ntype: unsigned short\ndimension: 3\nsizes: 2 1 2\n"
                      "endian: big\nencoding: raw\n\n";
    unsigned char buf[256];
    size_t h = strlen(hdr);
    memcpy(buf, hdr, h);
    const unsigned char be[8] = {0x01, 0x02, 0xff, 0x00, 0x00, 0x07, 0x80, 0x01};
    memcpy(buf + h, be, 8);
    const char *path = out_path("be.nrrd");
    vt_write_file(path, buf, h + 8);
    vv_volume *v = NULL;
    vt_ok(vv_nrrd_read(&v, path));
    assert_int_equal(v->type, VV_U16);
    assert_int_equal(v->dims[1], 1);
    assert_near(vv_volume_get(v, 0, 0, 0), 0x0102, 0);
    assert_near(vv_volume_get(v, 1, 0, 0), 0xff00, 0);
    assert_near(vv_volume_get(v, 0, 0, 1), 0x0007, 0);
    assert_near(vv_volume_get(v, 1, 0, 1), 0x8001, 0);
    vv_volume_free(v);

    /* detached, little-endian i32 after 13 bytes of junk ("byte skip") */
    unsigned char data[13 + 16];
    memset(data, 0xAB, 13);
    const int32_t vals[4] = {-5, 100000, 7, -2000000000};
    for (int i = 0; i < 4; i++)
        for (int b = 0; b < 4; b++)
            data[13 + i * 4 + b] = (unsigned char)((uint32_t)vals[i] >> (8 * b));
    vt_write_file(out_path("skip.bin"), data, sizeof data);
    write_text(out_path("skip.nhdr"), "NRRD0004\ntype: int\ndimension: 3\nsizes: 1 2 2\n"
                                      "endian: little\nencoding: raw\nbyte skip: 13\n"
                                      "data file: skip.bin\n");
    vt_ok(vv_nrrd_read(&v, out_path("skip.nhdr")));
    assert_int_equal(v->type, VV_I32);
    assert_near(vv_volume_get(v, 0, 0, 0), -5, 0);
    assert_near(vv_volume_get(v, 0, 1, 0), 100000, 0);
    assert_near(vv_volume_get(v, 0, 0, 1), 7, 0);
    assert_near(vv_volume_get(v, 0, 1, 1), -2000000000, 0);
    vv_volume_free(v);
}

static void
test_space_lps_and_4d(void **state) {
    (void)state;
    /* 4-D with a first axis of size 1, LPS space, oblique directions */
    const char *hdr = "NRRD0005\ntype: uchar\ndimension: 4\nsizes: 1 2 2 2\n"
                      "space: left-posterior-superior\n"
                      "space directions: none (0,2,0) (-3,0,0) (0,0,1.5)\n"
                      "kinds: list domain domain domain\n"
                      "space origin: (10,-20,30.5)\nencoding: raw\n\n";
    unsigned char buf[512];
    size_t h = strlen(hdr);
    memcpy(buf, hdr, h);
    for (int i = 0; i < 8; i++)
        buf[h + (size_t)i] = (unsigned char)(10 * i);
    const char *path = out_path("lps4d.nrrd");
    vt_write_file(path, buf, h + 8);
    vv_volume *v = NULL;
    vt_ok(vv_nrrd_read(&v, path));
    assert_int_equal(v->space, VV_SPACE_LPS);
    assert_int_equal(v->dims[0], 2);
    assert_int_equal(v->dims[2], 2);
    assert_near(v->spacing[0], 2, 1e-12);
    assert_near(v->spacing[1], 3, 1e-12);
    assert_near(v->spacing[2], 1.5, 1e-12);
    /* columns kept in the file's (LPS) space */
    const double dir[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    for (int i = 0; i < 9; i++)
        assert_near(v->direction[i], dir[i], 1e-12);
    assert_near(v->origin[0], 10, 0);
    assert_near(v->origin[1], -20, 0);
    assert_near(v->origin[2], 30.5, 0);
    assert_near(vv_volume_get(v, 1, 1, 1), 70, 0);
    /* the anatomical space survives a write and a read */
    vt_ok(vv_nrrd_write(v, out_path("lps_again.nrrd"), 1));
    vv_volume *back = NULL;
    vt_ok(vv_nrrd_read(&back, out_path("lps_again.nrrd")));
    assert_int_equal(back->space, VV_SPACE_LPS);
    assert_near(back->origin[1], -20, 0);
    vv_volume_free(back);
    vv_volume_free(v);

    /* a 64-bit integer type in range becomes f64; out of range is refused */
    const char *h64 = "NRRD0004\ntype: long long\ndimension: 1\nsizes: 2\nencoding: ascii\n\n"
                      "-3 9007199254740992\n";
    write_text(out_path("ll.nrrd"), h64);
    vt_ok(vv_nrrd_read(&v, out_path("ll.nrrd")));
    assert_int_equal(v->type, VV_F64);
    assert_near(vv_volume_get(v, 1, 0, 0), 9007199254740992.0, 0);
    vv_volume_free(v);
    write_text(out_path("ll2.nrrd"), "NRRD0004\ntype: long long\ndimension: 1\nsizes: 2\n"
                                     "encoding: ascii\n\n-3 9007199254740993\n");
    assert_int_equal(vv_nrrd_read(&v, out_path("ll2.nrrd")), VV_ERR_UNSUPPORTED);
    assert_null(v);
}

static void
test_bzip2_and_gzip_from_teem(void **state) {
    (void)state;
    if (!nrrdEncodingBzip2->available())
        vt_skip("this Teem has no bzip2 encoding");
    /* Teem writes a bzip2 file; we read it back through vv_nrrd_read */
    unsigned short data[24];
    for (int i = 0; i < 24; i++)
        data[i] = (unsigned short)(i * 2731);
    Nrrd *n = nrrdNew();
    assert_int_equal(nrrdWrap_va(n, data, nrrdTypeUShort, 3, (size_t)4, (size_t)3, (size_t)2), 0);
    NrrdIoState *nio = nrrdIoStateNew();
    nio->encoding = nrrdEncodingBzip2;
    const char *path = out_path("bz.nrrd");
    assert_int_equal(nrrdSave(path, n, nio), 0);
    nrrdIoStateNix(nio);
    nrrdNix(n);
    vv_volume *v = NULL;
    vt_ok(vv_nrrd_read(&v, path));
    assert_int_equal(v->type, VV_U16);
    assert_memory_equal(v->data, data, sizeof data);
    vv_volume_free(v);
}

static void
expect_error(const char *path, vv_status want) {
    vv_volume *v = (vv_volume *)1;
    vv_error_clear();
    vv_status s = vv_nrrd_read(&v, path);
    if (s != want)
        fail_msg("%s: got %s (%s), want %s", path, vv_status_name(s), vv_error_message(),
                 vv_status_name(want));
    assert_null(v);
    const char *msg = vv_error_message();
    assert_true(strncmp(msg, "nrrd: ", 6) == 0);
}

static void
test_bad_input(void **state) {
    (void)state;
    expect_error(out_path("does-not-exist.nrrd"), VV_ERR_IO);

    vt_write_file(out_path("empty.nrrd"), "", 0);
    expect_error(out_path("empty.nrrd"), VV_ERR_FORMAT);

    unsigned char junk[300];
    uint32_t x = 99;
    for (size_t i = 0; i < sizeof junk; i++) {
        x = x * 1103515245u + 12345u;
        junk[i] = (unsigned char)(x >> 16);
    }
    vt_write_file(out_path("junk.nrrd"), junk, sizeof junk);
    expect_error(out_path("junk.nrrd"), VV_ERR_FORMAT);

    /* NRRD magic, garbage header */
    write_text(out_path("badhdr.nrrd"), "NRRD0004\ntype: bogus\nsizes: x\n\n");
    expect_error(out_path("badhdr.nrrd"), VV_ERR_FORMAT);

    /* truncated raw and gzip data */
    vv_volume *v = make_volume(VV_I16);
    for (int gz = 0; gz < 2; gz++) {
        const char *p = out_path(gz ? "trunc_gz.nrrd" : "trunc_raw.nrrd");
        vt_ok(vv_nrrd_write(v, p, gz));
        size_t n = 0;
        unsigned char *bytes = vt_read_file(p, &n);
        vt_write_file(p, bytes, n - 20);
        free(bytes);
        expect_error(p, VV_ERR_FORMAT);
    }
    vv_volume_free(v);

    /* absurd sizes: refused before anything is allocated */
    write_text(out_path("huge.nrrd"), "NRRD0004\ntype: float\ndimension: 3\nendian: little\n"
                                      "sizes: 100000 100000 100000\nencoding: raw\n\n");
    expect_error(out_path("huge.nrrd"), VV_ERR_LIMIT);
    write_text(out_path("huge2.nrrd"), "NRRD0004\ntype: double\ndimension: 3\nendian: big\n"
                                       "sizes: 60000 60000 60000\nencoding: raw\n\n");
    expect_error(out_path("huge2.nrrd"), VV_ERR_LIMIT);

    /* missing detached data file, and a missing file of a pattern */
    write_text(out_path("nodata.nhdr"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\n"
                                        "encoding: raw\ndata file: nowhere.raw\n");
    expect_error(out_path("nodata.nhdr"), VV_ERR_IO);
    write_text(out_path("nopat.nhdr"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\n"
                                       "encoding: raw\ndata file: nopat.%d 1 2 1\n");
    write_text(out_path("nopat.1"), "abcd");
    expect_error(out_path("nopat.nhdr"), VV_ERR_IO);
    /* a pattern's field width of hundreds of millions (fuzz_nrrd: snprintf
       padded for seconds): refused in one line */
    write_text(out_path("wide.nhdr"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\n"
                                      "encoding: raw\ndata file: te%777777775d 3 884 5\n");
    expect_error(out_path("wide.nhdr"), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "field width over 64"));

    /* 4-D data that is not a volume, and an unsupported type */
    write_text(out_path("vec.nrrd"), "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 3 2 2 2\n"
                                     "encoding: ascii\n\n1 2 3 4 5 6 7 8 9 10 11 12 "
                                     "1 2 3 4 5 6 7 8 9 10 11 12\n");
    expect_error(out_path("vec.nrrd"), VV_ERR_UNSUPPORTED);
}

static int
count_temporaries(const char *dir) {
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp"))
            n++;
    closedir(d);
    return n;
}

static void
test_failed_write_keeps_existing_file(void **state) {
    (void)state;
    const char *dir = vt_outdir("io_nrrd_fail");
    char path[1100];
    snprintf(path, sizeof path, "%s/existing.nrrd", dir);
    const char *old = "the previous contents\n";
    write_text(path, old);

    int dims[3] = {64, 64, 64};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    memset(v->data, 7, 64 * 64 * 64);

    /* a file size limit makes the write fail half-way */
    struct rlimit old_lim, lim;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old_lim), 0);
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    lim = old_lim;
    lim.rlim_cur = 4096;
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    vv_error_clear();
    vv_status s = vv_nrrd_write(v, path, 0);
    setrlimit(RLIMIT_FSIZE, &old_lim);
    signal(SIGXFSZ, old_handler);
    assert_true(s < 0);
    assert_true(vv_error_message()[0] != '\0');

    size_t n = 0;
    unsigned char *now = vt_read_file(path, &n);
    assert_int_equal(n, strlen(old));
    assert_memory_equal(now, old, n);
    free(now);
    assert_int_equal(count_temporaries(dir), 0);

    /* a directory that does not exist */
    snprintf(path, sizeof path, "%s/no/such/dir/x.nrrd", dir);
    vt_err(vv_nrrd_write(v, path, 1));
    vv_volume_free(v);
}

static void *
reader_thread(void *arg) {
    long bad = 0;
    for (int i = 0; i < 3; i++) {
        vv_volume *v = NULL;
        if (vv_nrrd_read(&v, vt_data("volumes/headsq/quarter.nhdr")) != VV_OK || v->dims[2] != 93)
            bad++;
        vv_volume_free(v);
        /* a failing read in parallel must not disturb the others' biff state */
        if (vv_nrrd_read(&v, (const char *)arg) == VV_OK)
            bad++;
    }
    return (void *)bad;
}

static void
test_threads(void **state) {
    (void)state;
    const char *bad = out_path("threads_bad.nrrd");
    write_text(bad, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\nab");
    pthread_t th[4];
    for (int i = 0; i < 4; i++)
        assert_int_equal(pthread_create(&th[i], NULL, reader_thread, (void *)bad), 0);
    for (int i = 0; i < 4; i++) {
        void *r = NULL;
        pthread_join(th[i], &r);
        assert_int_equal((long)r, 0);
    }
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_headsq_detached_multifile),
        cmocka_unit_test(test_ct_head),
        cmocka_unit_test(test_round_trip_all_types),
        cmocka_unit_test(test_ascii_encoding),
        cmocka_unit_test(test_big_endian_and_byte_skip),
        cmocka_unit_test(test_space_lps_and_4d),
        cmocka_unit_test(test_bzip2_and_gzip_from_teem),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_failed_write_keeps_existing_file),
        cmocka_unit_test(test_threads),
    };
    return vt_run_tests(tests, NULL, NULL);
}
