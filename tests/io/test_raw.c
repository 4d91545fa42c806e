/* Raw reader: parameters, byte order, header skip, size checks. */
#include "testutil.h"

#include "io/io_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *
tmp_path(const char *name) {
    static char path[1200];
    snprintf(path, sizeof path, "%s/%s", vt_outdir("io_raw"), name);
    return path;
}

static void
test_params_init(void **state) {
    (void)state;
    vv_raw_params p;
    memset(&p, 0xAB, sizeof p);
    vv_raw_params_init(&p);
    for (int a = 0; a < 3; a++) {
        assert_int_equal(p.dims[a], 0);
        assert_true(p.spacing[a] == 1.0);
        assert_true(p.origin[a] == 0.0);
    }
    assert_int_equal(p.type, VV_U8);
    assert_int_equal(p.big_endian, 0);
    assert_true(p.header_skip == 0);
}

/* HeadMRVolume.raw is plain 48 x 62 x 42 u8; sum and voxels computed with Python. */
static void
test_real_file(void **state) {
    (void)state;
    vv_raw_params p;
    vv_raw_params_init(&p);
    p.dims[0] = 48;
    p.dims[1] = 62;
    p.dims[2] = 42;
    p.spacing[0] = p.spacing[1] = p.spacing[2] = 4.0;
    p.origin[2] = -10.5;
    vv_volume *v = NULL;
    vt_ok(vv_raw_read(&v, vt_data("volumes/HeadMRVolume.raw"), &p));
    assert_int_equal(v->type, VV_U8);
    uint64_t sum = 0;
    for (uint64_t i = 0; i < vv_volume_voxel_count(v); i++)
        sum += ((unsigned char *)v->data)[i];
    assert_true(sum == 3058332);
    assert_true(vv_volume_get(v, 24, 31, 21) == 79);
    assert_true(vv_volume_get(v, 10, 20, 30) == 32);
    assert_true(v->range[0] == 0 && v->range[1] == 255);
    assert_true(v->spacing[1] == 4.0);
    assert_true(v->origin[2] == -10.5);
    vv_volume_free(v);
}

/* A 16-byte header, then 3 x 2 x 2 u16 written in a chosen byte order. */
static void
test_byte_order_and_skip(void **state) {
    (void)state;
    unsigned char buf[16 + 24];
    memset(buf, 0xEE, 16);
    for (int be = 0; be <= 1; be++) {
        for (int i = 0; i < 12; i++) {
            unsigned v = (unsigned)(i * 5000 + 7);
            buf[16 + 2 * i + (be ? 1 : 0)] = (unsigned char)(v & 0xFF);
            buf[16 + 2 * i + (be ? 0 : 1)] = (unsigned char)(v >> 8);
        }
        const char *path = tmp_path(be ? "u16be.raw" : "u16le.raw");
        vt_write_file(path, buf, sizeof buf);
        vv_raw_params p;
        vv_raw_params_init(&p);
        p.dims[0] = 3;
        p.dims[1] = 2;
        p.dims[2] = 2;
        p.type = VV_U16;
        p.big_endian = be;
        p.header_skip = 16;
        vv_volume *v = NULL;
        vt_ok(vv_raw_read(&v, path, &p));
        assert_int_equal(v->type, VV_U16);
        for (int i = 0; i < 12; i++)
            assert_int_equal(((uint16_t *)v->data)[i], i * 5000 + 7);
        assert_true(v->range[1] == 11 * 5000 + 7);
        vv_volume_free(v);

        /* The wrong byte order gives different values: the flag matters. */
        p.big_endian = !be;
        vt_ok(vv_raw_read(&v, path, &p));
        assert_int_not_equal(((uint16_t *)v->data)[1], 5007);
        vv_volume_free(v);
    }

    /* f32 big-endian: 1.5 is 3F C0 00 00. */
    unsigned char f[8] = {0x3F, 0xC0, 0, 0, 0xC1, 0x20, 0, 0}; /* 1.5, -10 */
    const char *path = tmp_path("f32be.raw");
    vt_write_file(path, f, sizeof f);
    vv_raw_params p;
    vv_raw_params_init(&p);
    p.dims[0] = 2;
    p.dims[1] = p.dims[2] = 1;
    p.type = VV_F32;
    p.big_endian = 1;
    vv_volume *v = NULL;
    vt_ok(vv_raw_read(&v, path, &p));
    assert_true(((float *)v->data)[0] == 1.5f);
    assert_true(((float *)v->data)[1] == -10.0f);
    assert_true(v->range[0] == -10.0 && v->range[1] == 1.5);
    vv_volume_free(v);
}

static void
test_bad_input(void **state) {
    (void)state;
    vv_raw_params p;
    vv_raw_params_init(&p);
    p.dims[0] = 10;
    p.dims[1] = 10;
    p.dims[2] = 10;
    p.type = VV_I16;
    vv_volume *v = (vv_volume *)1;

    /* Empty and too-small files: the message names both sizes. */
    const char *empty = tmp_path("empty.raw");
    vt_write_file(empty, "", 0);
    vv_error_clear();
    assert_int_equal(vv_raw_read(&v, empty, &p), VV_ERR_FORMAT);
    assert_null(v);
    assert_non_null(strstr(vv_error_message(), "raw: empty.raw"));
    assert_non_null(strstr(vv_error_message(), "2000"));

    unsigned char data[2100];
    memset(data, 1, sizeof data);
    const char *small = tmp_path("small.raw");
    vt_write_file(small, data, 1999);
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "needs 2000 bytes"));
    assert_non_null(strstr(vv_error_message(), "has 1999"));

    /* Exactly enough works; with a header skip it no longer fits. */
    vt_write_file(small, data, 2000);
    vt_ok(vv_raw_read(&v, small, &p));
    vv_volume_free(v);
    p.header_skip = 1;
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "needs 2001 bytes"));
    p.header_skip = UINT64_MAX;
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_FORMAT);
    p.header_skip = 0;

    /* Absurd, negative and zero sizes, bad spacing and type. */
    p.dims[0] = p.dims[1] = p.dims[2] = 100000;
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_LIMIT);
    assert_null(v);
    p.dims[0] = 2000;
    p.dims[1] = 2000;
    p.dims[2] = 1000; /* within the limits, far bigger than the file */
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_FORMAT);
    p.dims[0] = -10;
    p.dims[1] = p.dims[2] = 10;
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_INVALID);
    p.dims[0] = 0;
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_INVALID);
    p.dims[0] = 10;
    p.spacing[1] = 0;
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_INVALID);
    p.spacing[1] = 1;
    p.type = (vv_voxel_type)42;
    assert_int_equal(vv_raw_read(&v, small, &p), VV_ERR_INVALID);
    p.type = VV_I16;

    vt_err(vv_raw_read(&v, "/nonexistent/x.raw", &p));
    assert_int_equal(vv_raw_read(&v, "/nonexistent/x.raw", &p), VV_ERR_IO);
    assert_int_equal(vv_raw_read(&v, small, NULL), VV_ERR_INVALID);
    assert_null(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_params_init),
        cmocka_unit_test(test_real_file),
        cmocka_unit_test(test_byte_order_and_skip),
        cmocka_unit_test(test_bad_input),
    };
    return vt_run_tests(tests, NULL, NULL);
}
