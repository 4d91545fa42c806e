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
                    double e = floor(vals[(z * M + y) * M + x] + 0.5); /* as the decoder */
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
corruption_run(int version) {
    vv_volume *v = synthetic(19, 11, 9, VV_I16, 3000);
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.block = 8;
    p.quality = 50;
    p.version = version;
    if (version == 2) { /* with voxel corrections too */
        p.target = VV_VVC_MAX_ERROR;
        p.max_error = 40;
    }
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    size_t n;
    const unsigned char *orig = vv_vvc_bytes(c, &n);
    unsigned char *buf = malloc(n);
    assert_non_null(buf);
    printf("fuzzing a %zu-byte version %d file\n", n, version);
    const size_t hb = rd32(orig + 12); /* header bytes: 244 (version 1) or 264 */
    assert_int_equal(hb, version == 1 ? 244 : 264);
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
    const size_t d0 = hb + (size_t)tables + (size_t)index;
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
    memcpy(buf, orig, n);
    const size_t h0 = hb + 4 + 4 * 5 * 5 * 5; /* after the quantisation table */
    if (version == 1) {
        /* hostile tables behind a valid CRC: a Huffman table that over-fills the code space */
        buf[h0] = 2;     /* 2 codes of length 1 ... */
        buf[h0 + 1] = 3; /* ... and 3 of length 2: 2*2 + 3 > 4 */
    } else {
        /* a context probability of 0 (a certain 1 bit) */
        buf[h0 + 4 + 10] = 0;
        buf[h0 + 4 + 11] = 0;
    }
    wr32(buf + hb + tables - 4, (uint32_t)crc32(0, buf + hb, (uInt)(tables - 4)));
    assert_true(refused(buf, n));
    free(buf);
    vv_vvc_free(c);
    vv_volume_free(v);
}

static void
test_corruption(void **state) {
    (void)state;
    corruption_run(1);
    corruption_run(2);
}

/* The legacy format: a version 1 file written by the encoder of the
 * previous release (tests/data, 5.4 KB) decodes to the same voxels, and the
 * legacy encoder (params.version = 1) still writes the same bytes. */
static vv_volume *
legacy_volume(void) {
    vv_volume *v = NULL;
    const int dims[3] = {21, 18, 13};
    vt_ok(vv_volume_new(&v, dims, VV_U16));
    uint64_t seed = 7;
    for (int k = 0; k < 13; k++)
        for (int j = 0; j < 18; j++)
            for (int i = 0; i < 21; i++)
                vv_volume_set(
                    v, i, j, k,
                    floor(1000 * (0.5 + 0.3 * sin(i * 0.3) * cos(j * 0.2) + 0.1 * sin(k * 0.5)) +
                          50 * rnd(&seed)));
    vv_volume_update_range(v);
    return v;
}

static void
test_legacy_version(void **state) {
    (void)state;
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_load(&c, VV_SOURCE_DIR "/tests/data/vvc_v1_u16_21x18x13.vvc"));
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    assert_int_equal(info.version, 1);
    vv_volume *d = NULL;
    vt_ok(vv_vvc_decompress(&d, c, 2, NULL));
    /* CRC-32 of the voxels the previous release decoded from this file */
    assert_int_equal(crc32(0, d->data, 21 * 18 * 13 * 2), 0xe5794c72u);
    vv_volume_free(d);
    vv_vvc_free(c);
    vv_volume *v = legacy_volume();
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.block = 8;
    p.quality = 60;
    p.threads = 1;
    p.version = 1;
    vt_ok(vv_vvc_compress(&c, v, &p));
    size_t n;
    const unsigned char *b = vv_vvc_bytes(c, &n);
    assert_int_equal(n, 5386);
    assert_int_equal(crc32(0, b, (uInt)n), 0x261c4413u);
    vv_vvc_free(c);
    vv_volume_free(v);
}

/* The version check: a version 2 file keeps the version 1 header CRC in
 * place, so a version 1 reader (which checks the CRC of bytes 0..239, then
 * the version) says "format version 2"; a version 3 file is refused here. */
static void
test_version_check(void **state) {
    (void)state;
    vv_volume *v = synthetic(12, 10, 9, VV_U8, 200);
    vv_vvc *c = compress_q(v, 8, 60);
    size_t n;
    const unsigned char *b = vv_vvc_bytes(c, &n);
    assert_int_equal(rd32(b + 8), 2);
    assert_int_equal(rd32(b + 240), (uint32_t)crc32(0, b, 240));
    unsigned char *buf = malloc(n);
    assert_non_null(buf);
    memcpy(buf, b, n);
    wr32(buf + 8, 3);
    wr32(buf + 240, (uint32_t)crc32(0, buf, 240));
    vv_vvc *c3 = NULL;
    assert_int_equal(vv_vvc_from_memory(&c3, buf, n, "v3.vvc"), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "format version 3"));
    free(buf);
    vv_vvc_free(c);
    vv_volume_free(v);
}

/* Marschner-Lobb test signal on [-1, 1]^3 (f_M = 6, alpha = 0.25), float. */
static vv_volume *
marschner_lobb(int n) {
    vv_volume *v = NULL;
    const int dims[3] = {n, n, n};
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double x = 2.0 * i / (n - 1) - 1, y = 2.0 * j / (n - 1) - 1,
                             z = 2.0 * k / (n - 1) - 1;
                const double r = sqrt(x * x + y * y);
                const double pr = cos(2 * VV_PI * 6 * cos(VV_PI * r / 2));
                vv_volume_set(v, i, j, k, (1 - sin(VV_PI * z / 2) + 0.25 * (1 + pr)) / 2.5);
            }
    vv_volume_update_range(v);
    return v;
}

static vv_volume *
noise_volume(vv_voxel_type t, double amp, uint64_t seed) {
    vv_volume *v = NULL;
    const int dims[3] = {23, 17, 11};
    vt_ok(vv_volume_new(&v, dims, t));
    for (size_t i = 0; i < vv_volume_voxel_count(v); i++)
        vv_volume_set(v, (int)(i % 23), (int)(i / 23 % 17), (int)(i / (23 * 17)),
                      t == VV_F32 ? amp * rnd(&seed)
                                  : floor(amp * rnd(&seed)) - (t == VV_I16 ? amp / 2 : 0));
    vv_volume_update_range(v);
    return v;
}

static vv_volume *
constant_volume(vv_voxel_type t, double value) {
    vv_volume *v = NULL;
    const int dims[3] = {19, 9, 20};
    vt_ok(vv_volume_new(&v, dims, t));
    for (size_t i = 0; i < vv_volume_voxel_count(v); i++)
        vv_volume_set(v, (int)(i % 19), (int)(i / 19 % 9), (int)(i / (19 * 9)), value);
    vv_volume_update_range(v);
    return v;
}

/* The error bound on every voxel, full decode and subcube by subcube. */
static void
check_bound(const vv_volume *v, double e, int block, const char *what) {
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.target = VV_VVC_MAX_ERROR;
    p.max_error = e;
    p.block = block;
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    vv_volume *d = NULL;
    vt_ok(vv_vvc_decompress(&d, c, 0, NULL));
    double maxe, psnr;
    vt_ok(vv_volume_compare(v, d, &psnr, NULL, &maxe));
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    printf("%-22s E %-8g block %2d: max error %-10.4g %.3f bits per voxel, PSNR %.2f\n", what, e,
           block, maxe, info.bits_per_voxel, psnr);
    if (!(maxe <= e))
        fail_msg("%s: max error %g over the bound %g", what, maxe, e);
    assert_true(info.max_error > 0 && info.max_error <= e);
    /* decoded alone, each subcube carries its corrections */
    const int M = info.block;
    float *vals = malloc(sizeof(float) * (size_t)M * M * M);
    assert_non_null(vals);
    for (int s = 0; s < vv_vvc_subcube_count(c); s += 3) {
        vt_ok(vv_vvc_decode_subcube(c, s, vals));
        const int bx = s % info.subcubes[0], by = (s / info.subcubes[0]) % info.subcubes[1],
                  bz = s / (info.subcubes[0] * info.subcubes[1]);
        for (int z = 0; z < M && bz * M + z < v->dims[2]; z++)
            for (int y = 0; y < M && by * M + y < v->dims[1]; y++)
                for (int x = 0; x < M && bx * M + x < v->dims[0]; x++) {
                    double a = vals[(z * M + y) * M + x];
                    if (v->type == VV_U8)
                        a = fmin(255, fmax(0, floor(a + 0.5)));
                    else if (v->type == VV_U16)
                        a = fmin(65535, fmax(0, floor(a + 0.5)));
                    else if (v->type == VV_I16)
                        a = fmin(32767, fmax(-32768, floor(a + 0.5)));
                    if (fabs(a - vv_volume_get(v, bx * M + x, by * M + y, bz * M + z)) > e)
                        fail_msg("%s: subcube %d voxel off by more than %g", what, s, e);
                }
    }
    free(vals);
    vv_volume_free(d);
    vv_vvc_free(c);
}

static void
test_error_bound(void **state) {
    (void)state;
    vv_volume *v = synthetic(29, 21, 18, VV_U16, 4000);
    const double es[] = {0.4, 3, 400, 1e9};
    for (int i = 0; i < 4; i++)
        check_bound(v, es[i], 8, "smooth u16");
    vv_volume_free(v);
    v = synthetic(20, 19, 17, VV_F32, 3.0);
    check_bound(v, 1e-4, 16, "smooth f32");
    check_bound(v, 0.05, 8, "smooth f32");
    vv_volume_free(v);
    v = marschner_lobb(41);
    check_bound(v, 1e-3, 16, "Marschner-Lobb f32");
    check_bound(v, 0.02, 16, "Marschner-Lobb f32");
    vv_volume_free(v);
    v = noise_volume(VV_U8, 256, 3);
    check_bound(v, 1, 8, "noise u8");
    check_bound(v, 10, 16, "noise u8");
    vv_volume_free(v);
    v = noise_volume(VV_I16, 60000, 5);
    check_bound(v, 2, 8, "noise i16");
    vv_volume_free(v);
    v = noise_volume(VV_F32, 1.0, 9);
    check_bound(v, 1e-5, 8, "noise f32");
    vv_volume_free(v);
    v = constant_volume(VV_U16, 1234);
    check_bound(v, 0.5, 8, "constant u16");
    vv_volume_free(v);
    v = constant_volume(VV_F32, -7.25);
    check_bound(v, 1e-5, 16, "constant f32");
    vv_volume_free(v);
    v = constant_volume(VV_F64, 0);
    check_bound(v, 1e-30, 8, "constant zero f64");
    vv_volume_free(v);
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    check_bound(v, 3, 16, "neghip u8");
    vv_volume_free(v);
}

static void
test_bad_error_bounds(void **state) {
    (void)state;
    vv_volume *v = synthetic(9, 9, 9, VV_F32, 1000);
    vv_vvc_params p;
    vv_vvc *c = NULL;
    const double bad[] = {0, -1, NAN, INFINITY, 1e-9};
    for (int i = 0; i < 5; i++) {
        vv_vvc_params_init(&p);
        p.target = VV_VVC_MAX_ERROR;
        p.max_error = bad[i];
        assert_int_equal(vv_vvc_compress(&c, v, &p), VV_ERR_INVALID);
        assert_null(c);
        printf("max error %g: %s\n", bad[i], vv_error_message());
    }
    /* 1e-9 on values up to 1000 is below single precision */
    assert_non_null(strstr(vv_error_message(), "single precision"));
    vv_vvc_params_init(&p);
    p.target = VV_VVC_MAX_ERROR;
    p.max_error = 1;
    p.version = 1;
    assert_int_equal(vv_vvc_compress(&c, v, &p), VV_ERR_INVALID);
    const double bad_rates[] = {0, -2, NAN, INFINITY};
    for (int i = 0; i < 4; i++) {
        vv_vvc_params_init(&p);
        p.target = VV_VVC_RATE;
        p.rate = bad_rates[i];
        assert_int_equal(vv_vvc_compress(&c, v, &p), VV_ERR_INVALID);
    }
    vv_vvc_params_init(&p);
    p.version = 3;
    assert_int_equal(vv_vvc_compress(&c, v, &p), VV_ERR_INVALID);
    vv_volume_free(v);
}

/* Round trips at every rate of both versions: the file within the rate,
 * every subcube decoding, the PSNR rising with the rate. */
static void
test_rates_both_versions(void **state) {
    (void)state;
    vv_volume *v = marschner_lobb(40);
    for (int ver = 1; ver <= 2; ver++) {
        double last = 0;
        const double rates[] = {1, 2, 4, 8};
        for (int i = 0; i < 4; i++) {
            vv_vvc_params p;
            vv_vvc_params_init(&p);
            p.target = VV_VVC_RATE;
            p.rate = rates[i];
            p.version = ver;
            vv_vvc *c = NULL;
            vt_ok(vv_vvc_compress(&c, v, &p));
            vv_vvc_info info;
            vv_vvc_get_info(c, &info);
            vv_volume *d = NULL;
            vt_ok(vv_vvc_decompress(&d, c, 0, NULL));
            double psnr;
            vt_ok(vv_volume_compare(v, d, &psnr, NULL, NULL));
            printf("Marschner-Lobb 40^3 f32, version %d, rate %g: %.4f bits per voxel, PSNR "
                   "%.2f dB\n",
                   ver, rates[i], info.bits_per_voxel, psnr);
            assert_int_equal(info.version, ver);
            assert_true(info.bits_per_voxel <= rates[i]);
            assert_true(psnr > last);
            last = psnr;
            vv_volume_free(d);
            vv_vvc_free(c);
        }
    }
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
        cmocka_unit_test(test_legacy_version),
        cmocka_unit_test(test_version_check),
        cmocka_unit_test(test_error_bound),
        cmocka_unit_test(test_bad_error_bounds),
        cmocka_unit_test(test_rates_both_versions),
    };
    return vt_run_tests(tests, NULL, NULL);
}
