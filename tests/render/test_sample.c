/*
 * Tests of the renderers' voxel cache (src/render/sample.h): the cached
 * gradients in 16-bit octahedral code. Against float central differences,
 * each voxel's decoded direction is within the code's angular error; the
 * interpolated gradient of a distance field points along the analytic
 * gradient within a degree and within twice the error of the 3 x int8
 * code it replaced (computed here from the same differences); the vectorised interpolation agrees
 * with a double-precision one of the decoded corners; a flat volume has
 * no gradient; and on the real CT head the decoded directions stay within
 * the bound.
 */
#include "testutil.h"

#include "render/kernels_avx2.h"
#include "render/sample.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double
angle_deg(const double a[3], const double b[3]) {
    const double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    const double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
    d = d > 1 ? 1 : d < -1 ? -1 : d;
    return acos(d) * 57.29577951308232;
}

/* Central differences (one-sided at the faces) of the cache's values at
 * voxel (i, j, k): fill_gradients's definition, in double. */
static void
central_difference(const vv_vcache *c, int i, int j, int k, double g[3]) {
    const int idx[3] = {i, j, k}, n[3] = {c->nx, c->ny, c->nz};
    const size_t st[3] = {1, c->sy, c->sz};
    const size_t at = (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
    for (int a = 0; a < 3; a++) {
        const int lo = idx[a] > 0 ? idx[a] - 1 : idx[a];
        const int hi = idx[a] < n[a] - 1 ? idx[a] + 1 : idx[a];
        const size_t base = at - (size_t)idx[a] * st[a];
        g[a] = ((double)vv_vcache_value(c, base + (size_t)hi * st[a]) -
                vv_vcache_value(c, base + (size_t)lo * st[a])) /
               (hi - lo);
    }
}

static void snorm8x3(const double g[3], double q[3]);

/* Every voxel with a gradient: the decoded unit vector's angle to the
 * float gradient. Returns the largest; *mean the mean; s8[2]: the largest
 * and the mean of the 3 x int8 code's; *flat the voxels with a zero
 * gradient, which must hold the zero code. */
static double
voxel_errors(const vv_vcache *c, double *mean, double s8[2], size_t *flat) {
    double worst = 0, sum = 0;
    s8[0] = s8[1] = 0;
    size_t n = 0;
    *flat = 0;
    for (int k = 0; k < c->nz; k++)
        for (int j = 0; j < c->ny; j++)
            for (int i = 0; i < c->nx; i++) {
                double g[3];
                central_difference(c, i, j, k, g);
                const size_t at = (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
                const vv_v4f d = vv_vcache_normal(c, at);
                if (g[0] == 0 && g[1] == 0 && g[2] == 0) {
                    assert_int_equal(c->nrm[2 * at], VV_OCT_ZERO);
                    assert_true(d[0] == 0 && d[1] == 0 && d[2] == 0);
                    (*flat)++;
                    continue;
                }
                const double dd[3] = {d[0], d[1], d[2]};
                assert_float_equal(sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]), 1.0, 1e-5);
                const double e = angle_deg(dd, g);
                worst = e > worst ? e : worst;
                sum += e;
                double q[3];
                snorm8x3(g, q);
                const double es = angle_deg(q, g);
                s8[0] = es > s8[0] ? es : s8[0];
                s8[1] += es;
                n++;
            }
    *mean = sum / (double)n;
    s8[1] /= (double)n;
    return worst;
}

static vv_volume *
distance_field(int n, double cx, double cy, double cz) {
    vv_volume *v = NULL;
    const int dims[3] = {n, n, n};
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    float *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                d[((size_t)k * n + (size_t)j) * n + (size_t)i] =
                    (float)sqrt((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz));
    vv_volume_update_range(v);
    return v;
}

/* The 3 x int8 code the octahedral one replaced: the unit gradient times
 * 127, rounded; zero where the gradient is. */
static void
snorm8x3(const double g[3], double q[3]) {
    const double l = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    for (int a = 0; a < 3; a++)
        q[a] = l > 0 ? (double)lrint(g[a] / l * 127) : 0;
}

/* A cache set holding @p v's cache (*c) with its normals built. */
static vv_vcache_set *
cache_with_normals(vv_volume *v, vv_vcache **c) {
    vv_vcache_set *s = malloc(sizeof *s);
    assert_non_null(s);
    vv_vcache_set_init(s);
    vt_ok(vv_vcache_get(s, v, c));
    vv_vcache_need_normals(s, *c);
    assert_non_null((*c)->nrm);
    return s;
}

static void
cache_set_free(vv_vcache_set *s) {
    vv_vcache_set_clear(s);
    free(s);
}

/* voxel_errors of @p c, printed under @p label and checked: 255 x 255
 * codes over the sphere lie about 0.8 degrees apart, the nearest of four
 * within about 0.65 (3 x int8, 24 bits, does better, at 3 bytes instead
 * of 2). */
static void
check_voxel_errors(const vv_vcache *c, const char *label) {
    double mean = 0, s8[2];
    size_t flat = 0;
    const double worst = voxel_errors(c, &mean, s8, &flat);
    print_message("%s: decoded against float gradients: octahedral 16-bit max %.3f mean %.3f deg; "
                  "3 x int8 max %.3f mean %.3f deg; %zu flat voxels\n",
                  label, worst, mean, s8[0], s8[1], flat);
    assert_true(worst < 0.7);
    assert_true(mean < 0.35);
}

static void
test_distance_field(void **state) {
    (void)state;
    const int n = 40;
    const double cx = 19.3, cy = 20.6, cz = 18.8;
    vv_volume *v = distance_field(n, cx, cy, cz);
    vv_vcache *c = NULL;
    vv_vcache_set *s = cache_with_normals(v, &c);
    check_voxel_errors(c, "distance field 40^3");

    /* interpolated gradients at random points of the shell 4..16 voxels
     * from the centre (away from the kink at the centre and the one-sided
     * faces) against the analytic direction p - centre */
    uint64_t seed = 7;
    double e_oct = 0, e_s8 = 0, m_oct = 0, m_s8 = 0, max_simd = 0;
    int samples = 0;
    while (samples < 20000) {
        const float p[3] = {(float)vt_rnd(&seed, 2, n - 3), (float)vt_rnd(&seed, 2, n - 3),
                            (float)vt_rnd(&seed, 2, n - 3)};
        const double r[3] = {p[0] - cx, p[1] - cy, p[2] - cz};
        const double dist = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (dist < 4 || dist > 16)
            continue;
        samples++;
        float f[3], g[3];
        const size_t o = vv_vcache_cell_of(c, p, f);
        vv_vcache_gradient_at(c, o, f, g);
        /* the same trilinear interpolation in double, of the decoded
         * corners, and of the 3 x int8 corners */
        double gd[3] = {0, 0, 0}, gs[3] = {0, 0, 0};
        const int ci = (int)(o % c->sy), cj = (int)(o / c->sy % (size_t)c->ny),
                  ck = (int)(o / c->sz);
        for (int corner = 0; corner < 8; corner++) {
            const int di = corner & 1, dj = (corner >> 1) & 1, dk = corner >> 2;
            const double w =
                (di ? f[0] : 1 - f[0]) * (dj ? f[1] : 1 - f[1]) * (dk ? f[2] : 1 - f[2]);
            const size_t at = o + (size_t)di + (size_t)dj * c->sy + (size_t)dk * c->sz;
            const vv_v4f d = vv_vcache_normal(c, at);
            double cd[3], q[3];
            central_difference(c, ci + di, cj + dj, ck + dk, cd);
            snorm8x3(cd, q);
            for (int a = 0; a < 3; a++) {
                gd[a] += w * d[a];
                gs[a] += w * q[a];
            }
        }
        for (int a = 0; a < 3; a++) {
            const double diff = fabs(g[a] - gd[a]);
            max_simd = diff > max_simd ? diff : max_simd;
        }
        const double gg[3] = {g[0], g[1], g[2]};
        const double eo = angle_deg(gg, r), es = angle_deg(gs, r);
        e_oct = eo > e_oct ? eo : e_oct;
        e_s8 = es > e_s8 ? es : e_s8;
        m_oct += eo;
        m_s8 += es;
    }
    m_oct /= samples;
    m_s8 /= samples;
    print_message("interpolated against the analytic gradient (%d points): octahedral 16-bit max "
                  "%.3f mean %.4f deg; 3 x int8 max %.3f mean %.4f deg; vectorised against "
                  "double %.2e\n",
                  samples, e_oct, m_oct, e_s8, m_s8, max_simd);
    /* the vectorised decode (rsqrt: 12 bits) against the double one */
    assert_true(max_simd < 2e-3);
    /* within a degree, and within twice the error of the code it replaced
     * (measured: 1.7 times the mean, 1.3 times the largest) */
    assert_true(e_oct < 1.0);
    assert_true(m_oct <= 2 * m_s8);
    cache_set_free(s);
    vv_volume_free(v);
}

static void
test_flat_volume(void **state) {
    (void)state;
    vv_volume *v = NULL;
    const int dims[3] = {9, 7, 5};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    memset(v->data, 42, 9 * 7 * 5);
    vv_volume_update_range(v);
    vv_vcache *c = NULL;
    vv_vcache_set *s = cache_with_normals(v, &c);
    for (size_t i = 0; i < 9 * 7 * 5; i++)
        assert_int_equal(c->nrm[2 * i], VV_OCT_ZERO);
    const float p[3] = {3.3f, 2.7f, 1.5f};
    float f[3], g[3] = {1, 1, 1};
    vv_vcache_gradient_at(c, vv_vcache_cell_of(c, p, f), f, g);
    assert_true(g[0] == 0 && g[1] == 0 && g[2] == 0);
    cache_set_free(s);
    vv_volume_free(v);
}

static void
test_real_volume(void **state) {
    (void)state;
    if (!vt_have_data("volumes/headsq/quarter.nhdr"))
        vt_skip("../shared/data/volumes/headsq/quarter.nhdr is missing");
    vv_volume *v = NULL;
    vv_world *w = vt_volume_scene("volumes/headsq/quarter.nhdr", 16, &v);
    vv_vcache *c = NULL;
    vv_vcache_set *s = cache_with_normals(v, &c);
    check_voxel_errors(c, "headsq/quarter");
    cache_set_free(s);
    vv_world_free(w);
    vv_volume_free(v);
}

/* The encoders agree code for code: four at a time (SSE2), one at a time
 * (the portable tail) and eight at a time (AVX2, where the processor has
 * it), on random directions and the special ones (axes, diagonals, zero,
 * the fold's edges, denormals, and the gradients that are not finite: no
 * direction, as zero; the portable one cast a NaN to int before). */
static void
test_encoders_agree(void **state) {
    (void)state;
    enum { N = 4099 };
    float *g[3];
    for (int a = 0; a < 3; a++)
        g[a] = malloc(N * sizeof(float));
    uint64_t seed = 11;
    const float special[][3] = {
        {0, 0, 0},        {1, 0, 0},        {0, 1, 0},         {0, 0, 1},        {-1, 0, 0},
        {0, -1, 0},       {0, 0, -1},       {1, 1, 1},         {-1, -1, -1},     {1, -1, 0},
        {0.5f, 0.5f, -1}, {1e-40f, 0, 0},   {3, -4, 1e-30f},   {-2, 7, -1e-7f},  {NAN, 0, 0},
        {1, NAN, -1},     {INFINITY, 1, 0}, {0, 0, -INFINITY}, {3e38f, 3e38f, 0}};
    const int ns = (int)(sizeof special / sizeof special[0]);
    for (int i = 0; i < N; i++)
        for (int a = 0; a < 3; a++)
            g[a][i] = i < ns ? special[i][a] : (float)vt_rnd(&seed, -1000, 1000);
    int8_t *four = malloc(2 * N), *one = malloc(2 * N), *eight = malloc(2 * N);
    vv_oct_encode_n(g[0], g[1], g[2], N, four);
    for (int i = 0; i < N; i++)
        vv_oct_encode_n(g[0] + i, g[1] + i, g[2] + i, 1, one + 2 * i);
    assert_memory_equal(four, one, 2 * N);
    for (int i = 0; i < N; i++) {
        /* no direction: zero, or not finite (a NaN, an infinity, an l1 norm
         * past FLT_MAX: differences of a range wider than a float) */
        const float l1 = fabsf(g[0][i]) + fabsf(g[1][i]) + fabsf(g[2][i]);
        const int zero = !(l1 > 0 && l1 <= FLT_MAX);
        assert_int_equal(four[2 * i] == VV_OCT_ZERO, zero);
        if (!zero) {
            const vv_v4f d = vv_oct_decode(four[2 * i], four[2 * i + 1]);
            const double dd[3] = {d[0], d[1], d[2]}, gg[3] = {g[0][i], g[1][i], g[2][i]};
            assert_true(angle_deg(dd, gg) < 0.7);
        }
    }
#if VV_VC_HAVE_AVX2
    if (vv_vc_have_avx2()) {
        vv_oct_encode_n_avx2(g[0], g[1], g[2], N, eight);
        assert_memory_equal(four, eight, 2 * N);
        print_message("%d directions: the SSE2, portable and AVX2 encoders agree\n", N);
    } else {
        print_message("%d directions: the SSE2 and portable encoders agree (no AVX2 here)\n", N);
    }
#endif
    for (int a = 0; a < 3; a++)
        free(g[a]);
    free(four);
    free(one);
    free(eight);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_distance_field),
        cmocka_unit_test(test_flat_volume),
        cmocka_unit_test(test_encoders_agree),
        cmocka_unit_test(test_real_volume),
    };
    return vt_run_tests(tests, NULL, NULL);
}
