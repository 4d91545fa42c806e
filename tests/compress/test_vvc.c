/*
 * Tests of the .vvc codec (src/compress/vvc_*.c).
 *
 * Round trips at the finest quantisation (integer data decode exactly, float
 * data within half a grey level), every header field kept, PSNR rising with
 * quality, the rate target met, every subcube decoding alone to the values
 * of a full decode, and a corrupt or truncated file refused: every single
 * byte flipped, every truncation length, and bit streams scrambled behind
 * valid CRCs (which must decode or fail, never crash; run under the asan
 * preset too).
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static double
rnd(uint64_t *s) {
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

/* A smooth field plus noise, dims not multiples of the block size. */
static vv_volume *
synthetic(int nx, int ny, int nz, vv_voxel_type t, double amp) {
    vv_volume *v = NULL;
    const int dims[3] = {nx, ny, nz};
    vt_ok(vv_volume_new(&v, dims, t));
    uint64_t seed = 42;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                double x = amp * (0.5 + 0.3 * sin(i * 0.3) * cos(j * 0.2) + 0.1 * sin(k * 0.5)) +
                           0.05 * amp * rnd(&seed);
                vv_volume_set(v, i, j, k, x);
            }
    vv_volume_update_range(v);
    return v;
}

static vv_vvc *
compress_q(const vv_volume *v, int block, double q) {
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.block = block;
    p.quality = q;
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    return c;
}

static void
test_lossless_integer(void **state) {
    (void)state;
    const char *files[] = {"volumes/neghip.slc", "volumes/ct_head.nrrd"};
    for (int f = 0; f < 2; f++) {
        vv_volume *v = NULL;
        vt_ok(vv_volume_load(&v, vt_data(files[f]), NULL));
        vv_vvc *c = compress_q(v, 16, 100);
        vv_volume *d = NULL;
        vt_ok(vv_vvc_decompress(&d, c, 0, NULL));
        double psnr, rmse, maxe;
        vt_ok(vv_volume_compare(v, d, &psnr, &rmse, &maxe));
        /* within 0.5 of a grey level, so rounding restores every voxel */
        assert_true(maxe == 0);
        assert_true(isinf(psnr));
        assert_int_equal(d->type, v->type);
        vv_volume_free(d);
        vv_vvc_free(c);
        vv_volume_free(v);
    }
}

static void
test_finest_float_and_header(void **state) {
    (void)state;
    for (int bi = 0; bi < 3; bi++) {
        const int block = 8 << bi;
        vv_volume *v = synthetic(21, 13, 10, VV_F32, 3.0);
        v->spacing[0] = 0.7;
        v->spacing[1] = 1.3;
        v->spacing[2] = 2.5;
        v->origin[0] = -12.5;
        v->origin[1] = 3.25;
        v->origin[2] = 1e-3;
        const double d[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
        memcpy(v->direction, d, sizeof d);
        v->unit = VV_UNIT_MICRON;
        v->data_origin = VV_ORIGIN_SIMULATION;
        v->modification = VV_MOD_FILTERED;
        v->space = VV_SPACE_LPS;
        vv_vvc *c = compress_q(v, block, 100);
        vv_volume *r = NULL;
        vt_ok(vv_vvc_decompress(&r, c, 1, NULL));
        double maxe;
        vt_ok(vv_volume_compare(v, r, NULL, NULL, &maxe));
        vv_vvc_info info;
        vv_vvc_get_info(c, &info);
        /* a grey level of float data is range / 65535 */
        assert_true(maxe <= 0.5 * info.value_unit);
        assert_near(info.value_unit, (v->range[1] - v->range[0]) / 65535, 1e-12);
        for (int i = 0; i < 3; i++) {
            assert_int_equal(r->dims[i], v->dims[i]);
            assert_true(r->spacing[i] == v->spacing[i]);
            assert_true(r->origin[i] == v->origin[i]);
            assert_int_equal(info.subcubes[i], (v->dims[i] + block - 1) / block);
        }
        for (int i = 0; i < 9; i++)
            assert_true(r->direction[i] == v->direction[i]);
        assert_int_equal(r->type, VV_F32);
        assert_int_equal(r->unit, VV_UNIT_MICRON);
        assert_int_equal(r->data_origin, VV_ORIGIN_SIMULATION);
        assert_int_equal(r->modification, VV_MOD_FILTERED);
        assert_int_equal(r->space, VV_SPACE_LPS);
        assert_int_equal(info.block, block);
        assert_int_equal(info.version, VV_VVC_VERSION);
        assert_true(info.range[0] == v->range[0] && info.range[1] == v->range[1]);
        vv_volume_free(r);
        vv_vvc_free(c);
        vv_volume_free(v);
    }
}

static void
test_psnr_rises_with_quality(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    double last_psnr = 0;
    uint64_t last_bytes = 0;
    for (int q = 0; q <= 100; q += 10) {
        vv_vvc *c = compress_q(v, 16, q);
        vv_volume *d = NULL;
        vt_ok(vv_vvc_decompress(&d, c, 0, NULL));
        double psnr;
        vt_ok(vv_volume_compare(v, d, &psnr, NULL, NULL));
        vv_vvc_info info;
        vv_vvc_get_info(c, &info);
        printf("quality %3d: %.3f bits per voxel, PSNR %.2f dB\n", q, info.bits_per_voxel, psnr);
        assert_true(psnr > last_psnr);
        assert_true(info.file_bytes > last_bytes);
        last_psnr = psnr;
        last_bytes = info.file_bytes;
        vv_volume_free(d);
        vv_vvc_free(c);
    }
    vv_volume_free(v);
}

static void
test_rate_target(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    const double rates[] = {0.5, 1, 2, 4};
    for (int i = 0; i < 4; i++) {
        vv_vvc_params p;
        vv_vvc_params_init(&p);
        p.target = VV_VVC_RATE;
        p.rate = rates[i];
        vv_vvc *c = NULL;
        vt_ok(vv_vvc_compress(&c, v, &p));
        vv_vvc_info info;
        vv_vvc_get_info(c, &info);
        printf("rate %.1f: %.4f bits per voxel at quality %.2f\n", rates[i], info.bits_per_voxel,
               info.quality);
        assert_true(info.bits_per_voxel <= rates[i]);
        assert_true(info.bits_per_voxel >= 0.9 * rates[i]);
        vv_vvc_free(c);
    }
    vv_volume_free(v);
}

static void
test_subcubes_decode_alone(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_vvc *c = compress_q(v, 16, 60);
    vv_volume *d = NULL;
    vt_ok(vv_vvc_decompress(&d, c, 0, NULL));
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    const int M = info.block, n = vv_vvc_subcube_count(c);
    assert_int_equal(n, info.subcubes[0] * info.subcubes[1] * info.subcubes[2]);
    float *vals = malloc(sizeof(float) * (size_t)M * M * M);
    assert_non_null(vals);
    for (int s = n - 1; s >= 0; s--) { /* backwards: no decoder state carries over */
        vt_ok(vv_vvc_decode_subcube(c, s, vals));
        const int bx = s % info.subcubes[0], by = (s / info.subcubes[0]) % info.subcubes[1],
                  bz = s / (info.subcubes[0] * info.subcubes[1]);
        for (int z = 0; z < M; z++)
            for (int y = 0; y < M; y++)
                for (int x = 0; x < M; x++) {
                    const int i = bx * M + x, j = by * M + y, k = bz * M + z;
                    if (i >= v->dims[0] || j >= v->dims[1] || k >= v->dims[2])
                        continue;
                    /* the full decode rounds and clamps to u8 */
                    double e = nearbyint(vals[(z * M + y) * M + x]);
                    e = e < 0 ? 0 : e > 255 ? 255 : e;
                    if (e != vv_volume_get(d, i, j, k))
                        fail_msg("subcube %d voxel (%d,%d,%d): alone %g, full %g", s, i, j, k, e,
                                 vv_volume_get(d, i, j, k));
                }
    }
    vt_err(vv_vvc_decode_subcube(c, n, vals));
    vt_err(vv_vvc_decode_subcube(c, -1, vals));
    free(vals);
    vv_volume_free(d);
    vv_vvc_free(c);
    vv_volume_free(v);
}

static void
test_file_round_trip(void **state) {
    (void)state;
    vv_volume *v = synthetic(30, 20, 17, VV_U16, 4000);
    vv_vvc *c = compress_q(v, 8, 70);
    char path[1200];
    snprintf(path, sizeof path, "%s/s.vvc", vt_outdir("compress"));
    vt_ok(vv_vvc_save(c, path));
    assert_true(vv_vvc_detect(path));
    vv_vvc *c2 = NULL;
    vt_ok(vv_vvc_load(&c2, path));
    size_t n1, n2;
    const unsigned char *b1 = vv_vvc_bytes(c, &n1), *b2 = vv_vvc_bytes(c2, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(b1, b2, n1);
    vv_volume *d1 = NULL, *d2 = NULL;
    vt_ok(vv_vvc_decompress(&d1, c, 1, NULL));
    vt_ok(vv_vvc_decompress(&d2, c2, 2, NULL));
    double maxe;
    vt_ok(vv_volume_compare(d1, d2, NULL, NULL, &maxe));
    assert_true(maxe == 0);
    vv_vvc_info info;
    vv_vvc_get_info(c2, &info);
    assert_near(info.bits_per_voxel, 8.0 * (double)n1 / (30 * 20 * 17), 1e-12);
    assert_near(info.ratio, 2.0 * 30 * 20 * 17 / (double)n1, 1e-12);
    /* not a .vvc, missing file */
    assert_false(vv_vvc_detect(vt_data("volumes/neghip.slc")));
    vv_vvc *bad = NULL;
    vt_err(vv_vvc_load(&bad, vt_data("volumes/neghip.slc")));
    assert_null(bad);
    vt_err(vv_vvc_load(&bad, "/nonexistent/x.vvc"));
    vv_volume_free(d1);
    vv_volume_free(d2);
    vv_vvc_free(c);
    vv_vvc_free(c2);
    vv_volume_free(v);
}

static void
test_bad_parameters(void **state) {
    (void)state;
    vv_volume *v = synthetic(9, 9, 9, VV_U8, 200);
    vv_vvc_params p;
    vv_vvc *c = NULL;
    vv_vvc_params_init(&p);
    p.block = 12;
    vt_err(vv_vvc_compress(&c, v, &p));
    vv_vvc_params_init(&p);
    p.quality = 100.5;
    vt_err(vv_vvc_compress(&c, v, &p));
    vv_vvc_params_init(&p);
    p.target = VV_VVC_RATE;
    p.rate = 0;
    vt_err(vv_vvc_compress(&c, v, &p));
    vv_vvc_params_init(&p);
    p.slope = -1;
    vt_err(vv_vvc_compress(&c, v, &p));
    assert_null(c);
    /* an unreachable rate gives the smallest file, above the rate */
    vv_vvc_params_init(&p);
    p.target = VV_VVC_RATE;
    p.rate = 1e-4;
    vt_ok(vv_vvc_compress(&c, v, &p));
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    assert_true(info.quality == 0);
    vv_vvc_free(c);
    vv_volume_free(v);
}

/* Checks that a buffer is refused by the parser or, when it parses, that
 * every subcube decodes or fails cleanly. Returns 1 when it was refused. */
static int
refused(const unsigned char *buf, size_t n) {
    vv_vvc *c = NULL;
    vv_error_clear();
    vv_status s = vv_vvc_from_memory(&c, buf, n, "fuzz.vvc");
    if (s != VV_OK) {
        assert_null(c);
        assert_true(s == VV_ERR_FORMAT || s == VV_ERR_LIMIT);
        assert_true(vv_error_message()[0] != '\0');
        return 1;
    }
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    float *sp = malloc(sizeof(float) * 2 * (size_t)info.block * info.block * (info.block / 2 + 1));
    assert_non_null(sp);
    for (int k = 0; k < vv_vvc_subcube_count(c); k++)
        (void)vv_vvc_decode_spectrum(c, k, sp);
    free(sp);
    vv_volume *d = NULL;
    if (vv_vvc_decompress(&d, c, 1, NULL) == VV_OK)
        vv_volume_free(d);
    vv_vvc_free(c);
    return 0;
}

static uint32_t
rd32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void
wr32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void
test_corruption(void **state) {
    (void)state;
    vv_volume *v = synthetic(19, 11, 9, VV_I16, 3000);
    vv_vvc *c = compress_q(v, 8, 50);
    size_t n;
    const unsigned char *orig = vv_vvc_bytes(c, &n);
    unsigned char *buf = malloc(n);
    assert_non_null(buf);
    printf("fuzzing a %zu-byte file\n", n);
    /* every byte flipped: the CRCs catch each one */
    for (size_t i = 0; i < n; i++) {
        memcpy(buf, orig, n);
        buf[i] ^= (unsigned char)(1u << (i % 8));
        if (!refused(buf, n))
            fail_msg("a flipped bit in byte %zu was not detected", i);
        buf[i] = (unsigned char)~orig[i];
        if (!refused(buf, n))
            fail_msg("an inverted byte %zu was not detected", i);
    }
    /* every truncation, and one extra byte */
    for (size_t len = 0; len < n; len++)
        if (!refused(orig, len))
            fail_msg("a file truncated to %zu bytes was accepted", len);
    memcpy(buf, orig, n);
    unsigned char *longer = malloc(n + 1);
    assert_non_null(longer);
    memcpy(longer, orig, n);
    longer[n] = 0;
    assert_true(refused(longer, n + 1));
    free(longer);
    /* hostile: scrambled bit streams behind valid CRCs decode or fail, never crash */
    const uint64_t tables = (uint64_t)rd32(orig + 216) | (uint64_t)rd32(orig + 220) << 32;
    const uint64_t index = (uint64_t)rd32(orig + 224) | (uint64_t)rd32(orig + 228) << 32;
    const size_t d0 = 244 + (size_t)tables + (size_t)index;
    uint64_t seed = 7;
    int failures = 0;
    for (int trial = 0; trial < 300; trial++) {
        memcpy(buf, orig, n);
        const int flips = 1 + trial % 8;
        for (int f = 0; f < flips; f++) {
            size_t pos = d0 + (size_t)(rnd(&seed) * (double)(n - 4 - d0));
            buf[pos] ^= (unsigned char)(1 + rnd(&seed) * 255);
        }
        wr32(buf + n - 4, (uint32_t)crc32(0, buf + d0, (uInt)(n - 4 - d0)));
        vv_vvc *cc = NULL;
        vt_ok(vv_vvc_from_memory(&cc, buf, n, "scrambled.vvc"));
        vv_volume *d = NULL;
        vv_error_clear();
        if (vv_vvc_decompress(&d, cc, 1, NULL) == VV_OK)
            vv_volume_free(d);
        else
            failures++;
        vv_vvc_free(cc);
    }
    printf("scrambled streams: %d of 300 refused\n", failures);
    assert_true(failures > 0);
    /* hostile tables behind a valid CRC: a Huffman table that over-fills the code space */
    memcpy(buf, orig, n);
    const size_t h0 = 244 + 4 + 4 * 5 * 5 * 5; /* DC table bits[1..16] */
    buf[h0] = 2;                               /* 2 codes of length 1 ... */
    buf[h0 + 1] = 3;                           /* ... and 3 of length 2: 2*2 + 3 > 4 */
    wr32(buf + 244 + tables - 4, (uint32_t)crc32(0, buf + 244, (uInt)(tables - 4)));
    assert_true(refused(buf, n));
    free(buf);
    vv_vvc_free(c);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lossless_integer),
        cmocka_unit_test(test_finest_float_and_header),
        cmocka_unit_test(test_psnr_rises_with_quality),
        cmocka_unit_test(test_rate_target),
        cmocka_unit_test(test_subcubes_decode_alone),
        cmocka_unit_test(test_file_round_trip),
        cmocka_unit_test(test_bad_parameters),
        cmocka_unit_test(test_corruption),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
