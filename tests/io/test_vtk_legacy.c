/* VTK legacy STRUCTURED_POINTS reader: real files, synthetic and bad input. */
#include "testutil.h"

#include "io/io_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *
tmp_write(const char *name, const void *data, size_t n) {
    static char path[1200];
    snprintf(path, sizeof path, "%s/%s", vt_outdir("io_vtk"), name);
    vt_write_file(path, data, n);
    return path;
}

static double
sum_all(const vv_volume *v) {
    double s = 0;
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int i = 0; i < v->dims[0]; i++)
                s += vv_volume_get(v, i, j, k);
    return s;
}

/* Sums and voxels computed once with a Python script reading the files. */
static void
test_real_files(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_vtk_read(&v, vt_data("volumes/ironProt.vtk")));
    assert_int_equal(v->type, VV_U8);
    for (int a = 0; a < 3; a++) {
        assert_int_equal(v->dims[a], 68);
        assert_true(v->spacing[a] == 1.0);
        assert_true(v->origin[a] == 0.0);
    }
    assert_true(sum_all(v) == 4131089.0);
    assert_true(vv_volume_get(v, 34, 34, 34) == 131);
    assert_true(v->range[0] == 0 && v->range[1] == 255);
    vv_volume_free(v);

    vt_ok(vv_vtk_read(&v, vt_data("volumes/heart.vtk")));
    assert_int_equal(v->type, VV_F32);
    assert_int_equal(v->dims[0], 32);
    assert_int_equal(v->dims[1], 32);
    assert_int_equal(v->dims[2], 12);
    assert_true(v->spacing[0] == 1.0 && v->spacing[1] == 1.0 && v->spacing[2] == 4.0);
    assert_true(sum_all(v) == 832283.0);
    assert_true(vv_volume_get(v, 16, 16, 6) == 85);
    assert_true(vv_volume_get(v, 10, 20, 5) == 215);
    assert_true(vv_volume_get(v, 0, 0, 0) == 16);
    assert_true(v->range[0] == 0 && v->range[1] == 255);
    vv_volume_free(v);
}

/* Binary big-endian i16 with spacing, origin, a component count, CRLF. */
static void
test_synthetic_binary(void **state) {
    (void)state;
    static const char hdr[] = "# vtk DataFile Version 3.0\r\nsynthetic\r\nBINARY\r\n"
                              "DATASET STRUCTURED_POINTS\r\nDIMENSIONS 3 2 2\r\n"
                              "SPACING 0.5 2 3.25\r\nORIGIN -1 2.5 100\r\nPOINT_DATA 12\r\n"
                              "SCALARS density short 1\r\nLOOKUP_TABLE default\r\n";
    unsigned char buf[sizeof hdr - 1 + 24 + 1];
    memcpy(buf, hdr, sizeof hdr - 1);
    for (int i = 0; i < 12; i++) {
        int16_t x = (int16_t)(i * 1000 - 6000);
        uint16_t u = (uint16_t)x;
        buf[sizeof hdr - 1 + 2 * i] = (unsigned char)(u >> 8);
        buf[sizeof hdr - 1 + 2 * i + 1] = (unsigned char)(u & 0xFF);
    }
    buf[sizeof buf - 1] = '\n';
    vv_volume *v = NULL;
    vt_ok(vv_vtk_read(&v, tmp_write("i16.vtk", buf, sizeof buf)));
    assert_int_equal(v->type, VV_I16);
    for (int i = 0; i < 12; i++)
        assert_int_equal(((int16_t *)v->data)[i], i * 1000 - 6000);
    assert_true(v->spacing[0] == 0.5 && v->spacing[1] == 2 && v->spacing[2] == 3.25);
    assert_true(v->origin[0] == -1 && v->origin[1] == 2.5 && v->origin[2] == 100);
    assert_true(v->range[0] == -6000 && v->range[1] == 5000);
    vv_volume_free(v);

    /* Binary data whose first byte is whitespace and no LOOKUP_TABLE line. */
    static const char hdr2[] = "# vtk DataFile Version 2.0\nx\nBINARY\nDATASET STRUCTURED_POINTS\n"
                               "DIMENSIONS 2 2 1\nPOINT_DATA 4\nSCALARS s unsigned_char\n";
    unsigned char b2[sizeof hdr2 - 1 + 4];
    memcpy(b2, hdr2, sizeof hdr2 - 1);
    memcpy(b2 + sizeof hdr2 - 1, "\n\x20\x09L", 4);
    vt_ok(vv_vtk_read(&v, tmp_write("nolut.vtk", b2, sizeof b2)));
    assert_memory_equal(v->data, "\n\x20\x09L", 4);
    vv_volume_free(v);
}

static void
test_synthetic_ascii(void **state) {
    (void)state;
    static const char f[] = "# vtk DataFile Version 2.0\ndoubles\nascii\n"
                            "dataset structured_points\ndimensions 2 1 2\naspect_ratio 1 1 2\n"
                            "origin 0 0 0\npoint_data 4\nscalars d double\n"
                            "1.25 -3e2\n\t0.1   1e-300\n";
    vv_volume *v = NULL;
    vt_ok(vv_vtk_read(&v, tmp_write("double.vtk", f, sizeof f - 1)));
    assert_int_equal(v->type, VV_F64);
    const double *d = v->data;
    assert_true(d[0] == 1.25 && d[1] == -300 && d[2] == 0.1 && d[3] == 1e-300);
    assert_true(v->spacing[2] == 2.0);
    vv_volume_free(v);

    static const char u[] = "# vtk DataFile Version 2.0\nints\nASCII\nDATASET STRUCTURED_POINTS\n"
                            "DIMENSIONS 3 1 1\nPOINT_DATA 3\nSCALARS i unsigned_int 1\n"
                            "LOOKUP_TABLE default\n0 4294967295 17\n";
    vt_ok(vv_vtk_read(&v, tmp_write("u32.vtk", u, sizeof u - 1)));
    assert_int_equal(v->type, VV_U32);
    assert_true(((uint32_t *)v->data)[1] == 4294967295u);
    assert_true(((uint32_t *)v->data)[2] == 17);
    vv_volume_free(v);
}

static void
expect_error(const char *name, const void *data, size_t n, vv_status want, const char *needle) {
    vv_volume *v = (vv_volume *)1;
    vv_error_clear();
    vv_status s = vv_vtk_read(&v, tmp_write(name, data, n));
    if (s != want)
        fail_msg("%s: got %s (%s), want %s", name, vv_status_name(s), vv_error_message(),
                 vv_status_name(want));
    assert_null(v);
    const char *msg = vv_error_message();
    assert_non_null(strstr(msg, "vtk: "));
    assert_non_null(strstr(msg, name));
    if (needle && !strstr(msg, needle))
        fail_msg("%s: message \"%s\" lacks \"%s\"", name, msg, needle);
}

#define HDR(fmt, dims, n, type)                                                                    \
    "# vtk DataFile Version 2.0\nt\n" fmt "\nDATASET STRUCTURED_POINTS\nDIMENSIONS " dims          \
    "\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA " n "\nSCALARS s " type "\nLOOKUP_TABLE default\n"

static uint32_t
lcg(uint32_t *s) {
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static void
test_bad_input(void **state) {
    (void)state;
    expect_error("empty.vtk", "", 0, VV_ERR_FORMAT, "empty");
    expect_error("magic.vtk", "# vtk DataFiel\nx\nASCII\n", 23, VV_ERR_FORMAT, "not a VTK");
    static const char th[] = "# vtk DataFile Version 2.0\nt\nBINARY\nDATASET STRUCTURED_POINTS\n"
                             "DIMENSIONS 4 4";
    expect_error("trunc_hdr.vtk", th, sizeof th - 1, VV_ERR_FORMAT, "truncated");
    static const char enc[] = "# vtk DataFile Version 2.0\nt\nXML\nDATASET STRUCTURED_POINTS\n";
    expect_error("enc.vtk", enc, sizeof enc - 1, VV_ERR_FORMAT, "ASCII or BINARY");
    static const char td[] = HDR("BINARY", "4 4 4", "64", "unsigned_char") "0123456789";
    expect_error("trunc_bin.vtk", td, sizeof td - 1, VV_ERR_FORMAT, "truncated");
    static const char ta[] = HDR("ASCII", "4 4 4", "64", "float") "1 2 3 4 5 6 7 8 9 10 11 12 "
                                                                  "13 14 15 16 17 18 19 20 21 22 "
                                                                  "23 24 25 26 27 28 29 30 31 32";
    expect_error("trunc_ascii.vtk", ta, sizeof ta - 1, VV_ERR_FORMAT, "truncated");
    static const char ab[] =
        HDR("BINARY", "100000 100000 100000", "1000000000000000", "unsigned_char") "xx";
    expect_error("absurd.vtk", ab, sizeof ab - 1, VV_ERR_LIMIT, NULL);
    /* Within the limits, far bigger than the file: refused before allocating. */
    static const char big[] = HDR("BINARY", "2000 2000 2000", "8000000000", "unsigned_char") "xx";
    expect_error("big.vtk", big, sizeof big - 1, VV_ERR_FORMAT, "truncated");
    static const char neg[] = HDR("BINARY", "-4 4 4", "-64", "unsigned_char") "xx";
    expect_error("neg.vtk", neg, sizeof neg - 1, VV_ERR_FORMAT, "DIMENSIONS");
    static const char pd[] = HDR("ASCII", "2 2 2", "7", "unsigned_char") "1 2 3 4 5 6 7 8";
    expect_error("pointdata.vtk", pd, sizeof pd - 1, VV_ERR_FORMAT, "POINT_DATA 7");
    /* 1..4 components are channels; more is not VTK legacy */
    static const char nc[] = HDR("ASCII", "1 1 1", "1", "float 5") "1 2 3 4 5";
    expect_error("ncomp.vtk", nc, sizeof nc - 1, VV_ERR_FORMAT, "5 components");
    static const char nt[] = HDR("ASCII", "1 1 1", "1", "float 3") "1 2";
    expect_error("ncomp_short.vtk", nt, sizeof nt - 1, VV_ERR_FORMAT, "truncated");
    static const char ty[] = HDR("ASCII", "1 1 1", "1", "bit") "1";
    expect_error("type.vtk", ty, sizeof ty - 1, VV_ERR_UNSUPPORTED, "bit");
    static const char ds[] = "# vtk DataFile Version 2.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n";
    expect_error("grid.vtk", ds, sizeof ds - 1, VV_ERR_UNSUPPORTED, "UNSTRUCTURED_GRID");
    static const char range[] = HDR("ASCII", "2 1 1", "2", "unsigned_char") "1 300";
    expect_error("range.vtk", range, sizeof range - 1, VV_ERR_FORMAT, "value 1");
    static const char junk[] = HDR("ASCII", "2 1 1", "2", "short") "1 abc";
    expect_error("junk.vtk", junk, sizeof junk - 1, VV_ERR_FORMAT, "value 1");
    static const char sp[] = "# vtk DataFile Version 2.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n"
                             "DIMENSIONS 1 1 1\nSPACING 1 -1 1\nPOINT_DATA 1\nSCALARS s float\n1";
    expect_error("spacing.vtk", sp, sizeof sp - 1, VV_ERR_FORMAT, "SPACING");

    vv_volume *v = (vv_volume *)1;
    assert_int_equal(vv_vtk_read(&v, "/nonexistent/x.vtk"), VV_ERR_IO);
    assert_null(v);

    /* Random bytes, and every prefix of a small binary file. */
    uint32_t seed = 7;
    unsigned char r[3000];
    for (int t = 0; t < 100; t++) {
        size_t len = 1 + lcg(&seed) % sizeof r;
        for (size_t i = 0; i < len; i++)
            r[i] = (unsigned char)lcg(&seed);
        if (t % 2)
            memcpy(r, "# vtk DataFile Version 2.0\n", len < 27 ? len : 27);
        vv_status s = vv_vtk_read(&v, tmp_write("random.vtk", r, len));
        assert_true(s < 0);
        assert_null(v);
    }
    static const char full[] = HDR("BINARY", "2 2 2", "8", "unsigned_short") "0123456789abcdef";
    for (size_t cut = 0; cut < sizeof full - 1; cut++) {
        vv_status s = vv_vtk_read(&v, tmp_write("cut.vtk", full, cut));
        assert_true(s < 0);
        assert_null(v);
    }
    vt_ok(vv_vtk_read(&v, tmp_write("cut.vtk", full, sizeof full - 1)));
    assert_int_equal(((uint16_t *)v->data)[0], ('0' << 8) | '1');
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_real_files),
        cmocka_unit_test(test_synthetic_binary),
        cmocka_unit_test(test_synthetic_ascii),
        cmocka_unit_test(test_bad_input),
    };
    return vt_run_tests(tests, NULL, NULL);
}
