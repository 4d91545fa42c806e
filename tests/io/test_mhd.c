/* MetaImage reader: the real file, .mha, compression, lists, bad input. */
#include "testutil.h"

#include "io/io_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static const char *
tmp_path(const char *name) {
    static char path[8][1200];
    static int slot;
    slot = (slot + 1) % 8;
    snprintf(path[slot], sizeof path[slot], "%s/%s", vt_outdir("io_mhd"), name);
    return path[slot];
}

/* Writes a header followed by @p n data bytes. */
static const char *
write_mha(const char *name, const char *hdr, const void *data, size_t n) {
    size_t h = strlen(hdr);
    unsigned char *buf = malloc(h + n + 1);
    assert_non_null(buf);
    memcpy(buf, hdr, h);
    if (n)
        memcpy(buf + h, data, n);
    const char *p = tmp_path(name);
    vt_write_file(p, buf, h + n);
    free(buf);
    return p;
}

/* Sum and voxels of HeadMRVolume.raw computed once with Python. */
static void
test_real_file(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_mhd_read(&v, vt_data("volumes/HeadMRVolume.mhd")));
    assert_int_equal(v->type, VV_U8);
    assert_int_equal(v->dims[0], 48);
    assert_int_equal(v->dims[1], 62);
    assert_int_equal(v->dims[2], 42);
    uint64_t sum = 0;
    for (uint64_t i = 0; i < vv_volume_voxel_count(v); i++)
        sum += ((unsigned char *)v->data)[i];
    assert_true(sum == 3058332);
    assert_true(vv_volume_get(v, 24, 31, 21) == 79);
    assert_true(vv_volume_get(v, 10, 20, 30) == 32);
    for (int a = 0; a < 3; a++) {
        assert_true(v->spacing[a] == 4.0);
        assert_true(v->origin[a] == 0.0);
        for (int b = 0; b < 3; b++)
            assert_true(v->direction[a * 3 + b] == (a == b ? 1.0 : 0.0));
    }
    assert_true(v->range[0] == 0 && v->range[1] == 255);
    vv_volume_free(v);
}

/* .mha with big-endian u16, a rotation, offset, and ElementSize overridden
   by ElementSpacing given later. */
static void
test_mha_local(void **state) {
    (void)state;
    uint16_t vals[24];
    unsigned char be[48];
    for (int i = 0; i < 24; i++) {
        vals[i] = (uint16_t)(i * 2711 + 3);
        be[2 * i] = (unsigned char)(vals[i] >> 8);
        be[2 * i + 1] = (unsigned char)(vals[i] & 0xFF);
    }
    const char *hdr = "ObjectType = Image\r\nNDims = 3\r\nDimSize = 4 3 2\r\n"
                      "ElementSize = 9 9 9\r\n"
                      "Offset = 10 -20 30.5\r\n"
                      "TransformMatrix = 0 1 0 -1 0 0 0 0 1\r\n"
                      "ElementSpacing = 0.5 0.75 2\r\n"
                      "AnatomicalOrientation = RAI\r\n"
                      "BinaryData = True\r\nBinaryDataByteOrderMSB = True\r\n"
                      "ElementType = MET_USHORT\r\nElementDataFile = LOCAL\r\n";
    vv_volume *v = NULL;
    vt_ok(vv_mhd_read(&v, write_mha("u16.mha", hdr, be, sizeof be)));
    assert_int_equal(v->type, VV_U16);
    assert_memory_equal(v->data, vals, sizeof vals);
    assert_true(v->spacing[0] == 0.5 && v->spacing[1] == 0.75 && v->spacing[2] == 2);
    assert_true(v->origin[0] == 10 && v->origin[1] == -20 && v->origin[2] == 30.5);
    /* The listed matrix gives the i axis first: i -> +y, j -> -x, k -> +z.
       Ours keeps axes in columns (row-major storage). */
    static const double want[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    for (int e = 0; e < 9; e++)
        assert_true(v->direction[e] == want[e]);
    /* Independent check: voxel (1, 0, 0) lies at origin + 0.5 * (0, 1, 0). */
    vv_mat4 m = vv_volume_index_to_world(v);
    vv_vec3 p = vv_mat4_mul_point(m, vv_vec3_make(1, 0, 0));
    assert_true(p.x == 10 && p.y == -19.5 && p.z == 30.5);
    p = vv_mat4_mul_point(m, vv_vec3_make(0, 2, 0));
    assert_true(p.x == 8.5 && p.y == -20 && p.z == 30.5);
    vv_volume_free(v);

    /* 2-D image as one slice, float little-endian, Position and Orientation. */
    float f[6] = {1.5f, -2, 3, 4, 5, 6e10f};
    const char *h2 = "NDims = 2\nDimSize = 3 2\nElementSpacing = 2 3\nPosition = 1 2\n"
                     "Orientation = 1 0 0 1\nElementByteOrderMSB = False\n"
                     "ElementType = MET_FLOAT\nElementDataFile = LOCAL\n";
    unsigned char fl[24];
    for (int i = 0; i < 6; i++) {
        uint32_t u;
        memcpy(&u, &f[i], 4);
        for (int b = 0; b < 4; b++)
            fl[4 * i + b] = (unsigned char)(u >> (8 * b));
    }
    vt_ok(vv_mhd_read(&v, write_mha("f32.mha", h2, fl, sizeof fl)));
    assert_int_equal(v->type, VV_F32);
    assert_int_equal(v->dims[2], 1);
    assert_memory_equal(v->data, f, sizeof f);
    assert_true(v->spacing[0] == 2 && v->spacing[1] == 3 && v->spacing[2] == 1);
    assert_true(v->origin[0] == 1 && v->origin[1] == 2 && v->origin[2] == 0);
    vv_volume_free(v);
}

static void
test_compressed(void **state) {
    (void)state;
    int16_t vals[5 * 4 * 3];
    for (int i = 0; i < 60; i++)
        vals[i] = (int16_t)((i % 7) * 1000 - 3000);
    unsigned char le[120];
    for (int i = 0; i < 60; i++) {
        le[2 * i] = (unsigned char)((uint16_t)vals[i] & 0xFF);
        le[2 * i + 1] = (unsigned char)((uint16_t)vals[i] >> 8);
    }
    unsigned char z[512];
    uLongf zn = sizeof z;
    assert_int_equal(compress2(z, &zn, le, sizeof le, 9), Z_OK);
    char hdr[512];
    snprintf(hdr, sizeof hdr,
             "ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\nElementType = MET_SHORT\n"
             "CompressedData = True\nCompressedDataSize = %lu\nElementDataFile = LOCAL\n",
             (unsigned long)zn);
    vv_volume *v = NULL;
    vt_ok(vv_mhd_read(&v, write_mha("z.mha", hdr, z, zn)));
    assert_int_equal(v->type, VV_I16);
    assert_memory_equal(v->data, vals, sizeof vals);
    assert_true(v->range[0] == -3000 && v->range[1] == 3000);
    vv_volume_free(v);

    /* Without CompressedDataSize, in a detached file. */
    vt_write_file(tmp_path("z.zraw"), z, zn);
    const char *h2 = "NDims = 3\nDimSize = 5 4 3\nElementType = MET_SHORT\n"
                     "CompressedData = True\nElementDataFile = z.zraw\n";
    vt_ok(vv_mhd_read(&v, write_mha("z.mhd", h2, NULL, 0)));
    assert_memory_equal(v->data, vals, sizeof vals);
    vv_volume_free(v);

    /* Corrupt and truncated streams. */
    vv_status s;
    unsigned char bad[512];
    memcpy(bad, z, zn);
    bad[zn / 2] ^= 0x55;
    bad[zn / 2 + 1] ^= 0xAA;
    vt_err(vv_mhd_read(&v, write_mha("zbad.mha", hdr, bad, zn)));
    assert_null(v);
    const char *h4 = "NDims = 3\nDimSize = 5 4 3\nElementType = MET_SHORT\n"
                     "CompressedData = True\nElementDataFile = LOCAL\n";
    s = vv_mhd_read(&v, write_mha("zshort.mha", h4, z, zn / 2));
    assert_int_equal(s, VV_ERR_FORMAT);
    assert_null(v);
    vt_write_file(tmp_path("z.zraw"), z, zn / 2);
    s = vv_mhd_read(&v, tmp_path("z.mhd"));
    assert_int_equal(s, VV_ERR_FORMAT);
    assert_null(v);
    /* CompressedDataSize past the end of the file. */
    snprintf(hdr, sizeof hdr,
             "NDims = 3\nDimSize = 5 4 3\nElementType = MET_SHORT\n"
             "CompressedData = True\nCompressedDataSize = %lu\nElementDataFile = LOCAL\n",
             (unsigned long)zn + 10);
    assert_int_equal(vv_mhd_read(&v, write_mha("zsize.mha", hdr, z, zn)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "CompressedDataSize"));
    /* A huge volume from a few compressed bytes: refused before allocating. */
    const char *h3 = "NDims = 3\nDimSize = 2000 2000 2000\nElementType = MET_UCHAR\n"
                     "CompressedData = True\nElementDataFile = LOCAL\n";
    assert_int_equal(vv_mhd_read(&v, write_mha("zbig.mha", h3, z, zn)), VV_ERR_FORMAT);
    assert_null(v);
}

/* HeaderSize -1, HeaderSize n, a LIST of slices and a file-name pattern. */
static void
test_data_files(void **state) {
    (void)state;
    unsigned char d[2 * 2 * 3], junk[40];
    for (int i = 0; i < 12; i++)
        d[i] = (unsigned char)(i * 20 + 1);
    memset(junk, 0x5A, sizeof junk);
    unsigned char f[52];
    memcpy(f, junk, 40);
    memcpy(f + 40, d, 12);
    vt_write_file(tmp_path("skip.raw"), f, sizeof f);
    vv_volume *v = NULL;
    vt_ok(vv_mhd_read(&v, write_mha("tail.mhd",
                                    "NDims = 3\nDimSize = 2 2 3\nElementType = MET_CHAR\n"
                                    "HeaderSize = -1\nElementDataFile = skip.raw\n",
                                    NULL, 0)));
    assert_int_equal(v->type, VV_I8);
    assert_memory_equal(v->data, d, 12);
    vv_volume_free(v);
    vt_ok(vv_mhd_read(&v, write_mha("skip.mhd",
                                    "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                                    "HeaderSize = 40\nElementDataFile = skip.raw\n",
                                    NULL, 0)));
    assert_memory_equal(v->data, d, 12);
    vv_volume_free(v);
    assert_int_equal(vv_mhd_read(&v, write_mha("skip2.mhd",
                                               "NDims = 3\nDimSize = 2 2 3\nElementType = "
                                               "MET_UCHAR\nHeaderSize = 41\n"
                                               "ElementDataFile = skip.raw\n",
                                               NULL, 0)),
                     VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "skip.raw"));

    for (int k = 0; k < 3; k++) {
        char name[32];
        snprintf(name, sizeof name, "slice%03d.raw", k + 1);
        vt_write_file(tmp_path(name), d + 4 * k, 4);
    }
    vt_ok(vv_mhd_read(&v, write_mha("list.mhd",
                                    "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                                    "ElementDataFile = LIST 2D\nslice001.raw\nslice002.raw\n"
                                    "slice003.raw\n",
                                    NULL, 0)));
    assert_memory_equal(v->data, d, 12);
    vv_volume_free(v);
    vt_ok(vv_mhd_read(&v, write_mha("pattern.mhd",
                                    "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                                    "ElementDataFile = slice%03d.raw 1 3 1\n",
                                    NULL, 0)));
    assert_memory_equal(v->data, d, 12);
    vv_volume_free(v);
    /* Patterns with a bad range or conversion. */
    vt_err(vv_mhd_read(&v, write_mha("pattern2.mhd",
                                     "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                                     "ElementDataFile = s%d.raw -9223372036854775807 "
                                     "9223372036854775807 1\n",
                                     NULL, 0)));
    vt_err(vv_mhd_read(&v, write_mha("pattern3.mhd",
                                     "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                                     "ElementDataFile = s%s.raw 1 3 1\n",
                                     NULL, 0)));
    assert_null(v);
    /* a field width of half a billion: refused at once (fuzz_mhd found
     * snprintf padding it for seconds) */
    vt_err(vv_mhd_read(&v, write_mha("pattern4.mhd",
                                     "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                                     "ElementDataFile = s%0581530138d.raw 1 3 1\n",
                                     NULL, 0)));
    assert_non_null(strstr(vv_error_message(), "field width"));
    assert_null(v);
    /* A list naming a missing file. */
    vt_err(vv_mhd_read(&v, write_mha("list2.mhd",
                                     "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                                     "ElementDataFile = LIST\nslice001.raw\nnope.raw\n"
                                     "slice003.raw\n",
                                     NULL, 0)));
    assert_non_null(strstr(vv_error_message(), "nope.raw"));
    assert_null(v);
}

static void
expect_error(const char *name, const char *hdr, size_t ndata, vv_status want, const char *needle) {
    unsigned char data[256];
    memset(data, 3, sizeof data);
    assert_true(ndata <= sizeof data);
    vv_volume *v = (vv_volume *)1;
    vv_error_clear();
    vv_status s = vv_mhd_read(&v, write_mha(name, hdr, data, ndata));
    if (s != want)
        fail_msg("%s: got %s (%s), want %s", name, vv_status_name(s), vv_error_message(),
                 vv_status_name(want));
    assert_null(v);
    const char *msg = vv_error_message();
    assert_non_null(strstr(msg, "mhd: "));
    assert_non_null(strstr(msg, name));
    if (needle && !strstr(msg, needle))
        fail_msg("%s: message \"%s\" lacks \"%s\"", name, msg, needle);
}

static uint32_t
lcg(uint32_t *s) {
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static void
test_bad_input(void **state) {
    (void)state;
    expect_error("empty.mha", "", 0, VV_ERR_FORMAT, "empty");
    expect_error("trunc_hdr.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_U", 0,
                 VV_ERR_UNSUPPORTED, "MET_U");
    expect_error("nodata.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n", 0,
                 VV_ERR_FORMAT, "ElementDataFile");
    expect_error("trunc_data.mha",
                 "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                 63, VV_ERR_FORMAT, "truncated");
    expect_error("absurd.mha",
                 "NDims = 3\nDimSize = 100000 100000 100000\nElementType = MET_UCHAR\n"
                 "ElementDataFile = LOCAL\n",
                 8, VV_ERR_LIMIT, NULL);
    expect_error("big.mha",
                 "NDims = 3\nDimSize = 2000 2000 2000\nElementType = MET_UCHAR\n"
                 "ElementDataFile = LOCAL\n",
                 8, VV_ERR_FORMAT, "truncated");
    expect_error("neg.mha",
                 "NDims = 3\nDimSize = -4 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                 64, VV_ERR_FORMAT, "DimSize");
    expect_error("ndims.mha",
                 "NDims = 4\nDimSize = 4 4 4 4\nElementType = MET_UCHAR\n"
                 "ElementDataFile = LOCAL\n",
                 256, VV_ERR_UNSUPPORTED, "NDims");
    expect_error("mismatch.mha",
                 "NDims = 3\nDimSize = 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", 16,
                 VV_ERR_FORMAT, "DimSize");
    expect_error("type.mha",
                 "NDims = 3\nDimSize = 4 4 4\nElementType = MET_LONG_LONG\n"
                 "ElementDataFile = LOCAL\n",
                 64, VV_ERR_UNSUPPORTED, "MET_LONG_LONG");
    expect_error("notype.mha", "NDims = 3\nDimSize = 4 4 4\nElementDataFile = LOCAL\n", 64,
                 VV_ERR_FORMAT, "ElementType");
    expect_error("channels.mha",
                 "NDims = 3\nDimSize = 4 4 1\nElementNumberOfChannels = 3\n"
                 "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                 48, VV_ERR_UNSUPPORTED, "Channels");
    expect_error("spacing.mha",
                 "NDims = 3\nDimSize = 4 4 4\nElementSpacing = 1 0 1\nElementType = MET_UCHAR\n"
                 "ElementDataFile = LOCAL\n",
                 64, VV_ERR_FORMAT, "ElementSpacing");
    expect_error("matrix.mha",
                 "NDims = 3\nDimSize = 4 4 4\nTransformMatrix = 1 0 0 1 0\n"
                 "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                 64, VV_ERR_FORMAT, "TransformMatrix");
    expect_error("object.mha",
                 "ObjectType = Mesh\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n"
                 "ElementDataFile = LOCAL\n",
                 64, VV_ERR_UNSUPPORTED, "Mesh");
    expect_error("nokey.mha", "NDims 3\n", 0, VV_ERR_FORMAT, "Key = Value");
    expect_error("missing.mhd",
                 "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n"
                 "ElementDataFile = does-not-exist.raw\n",
                 0, VV_ERR_IO, "does-not-exist.raw");

    vv_volume *v = (vv_volume *)1;
    assert_int_equal(vv_mhd_read(&v, "/nonexistent/x.mhd"), VV_ERR_IO);
    assert_null(v);

    /* Random bytes, with and without a plausible first line; every prefix
       of a small .mha. */
    uint32_t seed = 5;
    char r[3001];
    for (int t = 0; t < 100; t++) {
        size_t len = 1 + lcg(&seed) % 3000;
        for (size_t i = 0; i < len; i++)
            r[i] = (char)lcg(&seed);
        if (t % 2)
            memcpy(r, "NDims = 3\n", len < 10 ? len : 10);
        const char *p = tmp_path("random.mha");
        vt_write_file(p, r, len);
        vv_status s = vv_mhd_read(&v, p);
        assert_true(s < 0);
        assert_null(v);
    }
    static const char full[] = "NDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\n"
                               "ElementDataFile = LOCAL\n0123456789abcdef";
    for (size_t cut = 0; cut < sizeof full - 1; cut++) {
        const char *p = tmp_path("cut.mha");
        vt_write_file(p, full, cut);
        assert_true(vv_mhd_read(&v, p) < 0);
        assert_null(v);
    }
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_real_file),  cmocka_unit_test(test_mha_local),
        cmocka_unit_test(test_compressed), cmocka_unit_test(test_data_files),
        cmocka_unit_test(test_bad_input),
    };
    return vt_run_tests(tests, NULL, NULL);
}
