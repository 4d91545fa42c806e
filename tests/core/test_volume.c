/* Volumes: size limits, reference counting, voxel access, geometry, sampling,
 * gradients, histograms and quantiles. */
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static void
assert_vec_near(vv_vec3 got, vv_vec3 want, double tol) {
    if (!(fabs(got.x - want.x) <= tol && fabs(got.y - want.y) <= tol &&
          fabs(got.z - want.z) <= tol))
        fail_msg("got (%.17g, %.17g, %.17g), want (%.17g, %.17g, %.17g) (tolerance %g)", got.x,
                 got.y, got.z, want.x, want.y, want.z, tol);
}

static double
rnd(uint64_t *s, double lo, double hi) {
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) / 9007199254740992.0;
}

static vv_volume *
make_volume(int nx, int ny, int nz, vv_voxel_type t) {
    const int dims[3] = {nx, ny, nz};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, t));
    assert_non_null(v);
    return v;
}

/* ---- sizes ---- */

static void
expect_limit(int a, int b, int c, vv_voxel_type t, const char *needle) {
    const int dims[3] = {a, b, c};
    uint64_t bytes = 12345;
    vv_error_clear();
    vv_status s = vv_volume_check_size(dims, t, &bytes);
    if (s != VV_ERR_LIMIT)
        fail_msg("%d x %d x %d %s: got %s, want VV_ERR_LIMIT", a, b, c, vv_voxel_type_name(t),
                 vv_status_name(s));
    const char *msg = vv_error_message();
    if (!strstr(msg, needle))
        fail_msg("message '%s' does not mention '%s'", msg, needle);
}

static void
expect_size(int a, int b, int c, vv_voxel_type t, uint64_t want) {
    const int dims[3] = {a, b, c};
    uint64_t bytes = 0;
    vt_ok(vv_volume_check_size(dims, t, &bytes));
    if (bytes != want)
        fail_msg("%d x %d x %d %s: %llu bytes, want %llu", a, b, c, vv_voxel_type_name(t),
                 (unsigned long long)bytes, (unsigned long long)want);
}

static void
test_check_size(void **state) {
    (void)state;
    /* the fixed limits alone: no memory budget (it is tested in
     * tests/io/test_hardening.c) */
    vv_memory_budget_set(UINT64_MAX);
    expect_limit(0, 1, 1, VV_U8, "0 x 1 x 1");
    expect_limit(1, 0, 1, VV_U8, "1 x 0 x 1");
    expect_limit(1, 1, 0, VV_U8, "1 x 1 x 0");
    expect_limit(-5, 10, 10, VV_U8, "-5 x 10 x 10");
    expect_limit(10, 10, -2147483647 - 1, VV_F32, "10 x 10 x -2147483648");
    expect_limit(65537, 1, 1, VV_U8, "65537");
    expect_limit(1, 1, 2147483647, VV_U8, "2147483647");
    /* products that overflow 32 bits, or 64 bits when multiplied carelessly */
    expect_limit(65536, 65536, 65536, VV_F64, "65536 x 65536 x 65536");
    expect_limit(65536, 65536, 65536, VV_U8, "65536 x 65536 x 65536");
    expect_limit(65536, 65536, 3, VV_U8, "65536 x 65536 x 3");  /* > 2^33 voxels */
    expect_limit(65536, 65536, 2, VV_F64, "65536 x 65536 x 2"); /* 64 GiB */
    expect_limit(65536, 32768, 3, VV_F64, "65536 x 32768 x 3"); /* 48 GiB */
    /* exactly at the limits */
    expect_size(65536, 65536, 2, VV_U8, (uint64_t)1 << 33);   /* 2^33 voxels */
    expect_size(65536, 65536, 2, VV_U32, (uint64_t)32 << 30); /* 32 GiB */
    expect_size(65536, 65536, 1, VV_F64, (uint64_t)32 << 30); /* 32 GiB */
    expect_size(1, 1, 1, VV_U8, 1);
    expect_size(65536, 1, 1, VV_I16, 131072);
    expect_size(100, 200, 300, VV_F32, 24000000);
    expect_size(3, 5, 7, VV_F64, 840);
    /* bytes may be NULL */
    const int ok_dims[3] = {4, 4, 4};
    vt_ok(vv_volume_check_size(ok_dims, VV_U16, NULL));
    /* an invalid voxel type */
    vv_error_clear();
    assert_int_equal(vv_volume_check_size(ok_dims, (vv_voxel_type)42, NULL), VV_ERR_INVALID);
    assert_true(vv_error_message()[0] != '\0');
    /* vv_volume_new refuses the same sizes and leaves *out NULL */
    const int bad[3] = {65536, 65536, 65536};
    vv_volume *v = (vv_volume *)&v; /* garbage that must be overwritten */
    vv_error_clear();
    assert_int_equal(vv_volume_new(&v, bad, VV_F64), VV_ERR_LIMIT);
    assert_null(v);
    assert_true(vv_error_message()[0] != '\0');
    vv_memory_budget_set(0);
}

/* ---- lifetime ---- */

static void
test_new_ref_free(void **state) {
    (void)state;
    vv_volume *v = make_volume(3, 4, 5, VV_I16);
    assert_int_equal(v->dims[0], 3);
    assert_int_equal(v->dims[1], 4);
    assert_int_equal(v->dims[2], 5);
    assert_int_equal(v->type, VV_I16);
    assert_int_equal(v->refcount, 1);
    assert_true(vv_volume_voxel_count(v) == 60);
    for (int a = 0; a < 3; a++) {
        assert_true(v->spacing[a] == 1.0);
        assert_true(v->origin[a] == 0.0);
        for (int b = 0; b < 3; b++)
            assert_true(v->direction[3 * a + b] == (a == b ? 1.0 : 0.0));
    }
    assert_true(v->range[0] == 0 && v->range[1] == 0);
    for (int k = 0; k < 5; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 3; i++)
                assert_true(vv_volume_get(v, i, j, k) == 0.0); /* zero-filled */
    assert_ptr_equal(vv_volume_ref(v), v);
    assert_int_equal(v->refcount, 2);
    vv_volume_free(v);
    /* still alive: ASan reports a use after free here if the first free released it */
    assert_int_equal(v->refcount, 1);
    vv_volume_set(v, 2, 3, 4, 17);
    assert_true(vv_volume_get(v, 2, 3, 4) == 17);
    vv_volume_free(v); /* released now; LeakSanitizer reports it otherwise */
    vv_volume_free(NULL);
    assert_null(vv_volume_ref(NULL));
}

/* Many threads taking and dropping references leave the count unchanged. */
static void
test_ref_threads(void **state) {
    (void)state;
    vv_volume *v = make_volume(2, 2, 2, VV_U8);
#pragma omp parallel num_threads(4)
    {
        for (int n = 0; n < 20000; n++) {
            vv_volume_ref(v);
            vv_volume_free(v);
        }
    }
    assert_int_equal(v->refcount, 1);
    vv_volume_free(v);
}

/* ---- voxel access ---- */

static void
test_layout(void **state) {
    (void)state;
    for (int t = VV_U8; t <= VV_F64; t++) {
        vv_volume *v = make_volume(5, 3, 4, (vv_voxel_type)t);
        size_t vs = vv_voxel_type_size((vv_voxel_type)t);
        vv_volume_set(v, 4, 1, 2, 7);
        /* data[k][j][i]: byte offset ((k * ny + j) * nx + i) * size */
        size_t idx = ((size_t)2 * 3 + 1) * 5 + 4;
        const unsigned char *bytes = v->data;
        int nonzero = 0;
        for (size_t b = 0; b < 60 * vs; b++)
            if (bytes[b])
                nonzero |= !(b >= idx * vs && b < (idx + 1) * vs);
        assert_false(nonzero);
        switch ((vv_voxel_type)t) {
        case VV_U8:
            assert_int_equal(((uint8_t *)v->data)[idx], 7);
            break;
        case VV_I8:
            assert_int_equal(((int8_t *)v->data)[idx], 7);
            break;
        case VV_U16:
            assert_int_equal(((uint16_t *)v->data)[idx], 7);
            break;
        case VV_I16:
            assert_int_equal(((int16_t *)v->data)[idx], 7);
            break;
        case VV_U32:
            assert_int_equal(((uint32_t *)v->data)[idx], 7);
            break;
        case VV_I32:
            assert_int_equal(((int32_t *)v->data)[idx], 7);
            break;
        case VV_F32:
            assert_true(((float *)v->data)[idx] == 7.0f);
            break;
        case VV_F64:
            assert_true(((double *)v->data)[idx] == 7.0);
            break;
        }
        assert_true(vv_volume_get(v, 4, 1, 2) == 7);
        assert_true(vv_volume_get(v, 1, 2, 2) == 0);
        vv_volume_free(v);
    }
}

typedef struct set_case {
    vv_voxel_type type;
    double in;
    double want;
} set_case;

static void
test_get_set_round(void **state) {
    (void)state;
    /* Conversion rounds to nearest with nearbyint (ties to even in the default
     * rounding mode) and clamps to the type's range; NaN becomes 0. */
    const set_case cases[] = {
        {VV_U8, 0, 0},
        {VV_U8, 255, 255},
        {VV_U8, 300.7, 255},
        {VV_U8, -3.4, 0},
        {VV_U8, 12.4, 12},
        {VV_U8, 12.6, 13},
        {VV_U8, 2.5, 2},
        {VV_U8, 3.5, 4},
        {VV_U8, 254.5, 254},
        {VV_U8, 255.49, 255},
        {VV_U8, INFINITY, 255},
        {VV_U8, -INFINITY, 0},
        {VV_U8, NAN, 0},
        {VV_I8, -128, -128},
        {VV_I8, 127, 127},
        {VV_I8, -200, -128},
        {VV_I8, 200, 127},
        {VV_I8, -2.6, -3},
        {VV_I8, -2.5, -2},
        {VV_I8, NAN, 0},
        {VV_U16, 65535, 65535},
        {VV_U16, 70000, 65535},
        {VV_U16, -1, 0},
        {VV_U16, 1000.5, 1000},
        {VV_U16, 1001.5, 1002},
        {VV_I16, -32768, -32768},
        {VV_I16, 32767, 32767},
        {VV_I16, 40000, 32767},
        {VV_I16, -40000, -32768},
        {VV_I16, 2.5, 2},
        {VV_I16, -2.5, -2},
        {VV_I16, -7.3, -7},
        {VV_U32, 4294967295.0, 4294967295.0},
        {VV_U32, 5e9, 4294967295.0},
        {VV_U32, -1, 0},
        {VV_U32, 123456789.4, 123456789},
        {VV_U32, 1e300, 4294967295.0},
        {VV_I32, 2147483647.0, 2147483647.0},
        {VV_I32, -2147483648.0, -2147483648.0},
        {VV_I32, 3e9, 2147483647.0},
        {VV_I32, -3e9, -2147483648.0},
        {VV_I32, -1e300, -2147483648.0},
        {VV_I32, -123456.5, -123456},
        {VV_I32, NAN, 0},
        {VV_F32, 0.1, (double)0.1f},
        {VV_F32, -1234.5678, (double)-1234.5678f},
        {VV_F32, 1e30, (double)1e30f},
        {VV_F64, 0.1, 0.1},
        {VV_F64, -1e300, -1e300},
        {VV_F64, 2.5, 2.5},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        vv_volume *v = make_volume(2, 2, 2, cases[c].type);
        vv_volume_set(v, 1, 0, 1, cases[c].in);
        double got = vv_volume_get(v, 1, 0, 1);
        if (got != cases[c].want)
            fail_msg("%s: set %.17g, got %.17g, want %.17g", vv_voxel_type_name(cases[c].type),
                     cases[c].in, got, cases[c].want);
        assert_true(vv_volume_get(v, 0, 0, 1) == 0); /* neighbours untouched */
        assert_true(vv_volume_get(v, 1, 1, 1) == 0);
        vv_volume_free(v);
    }
    /* f32 and f64 keep NaN */
    vv_volume *f = make_volume(1, 1, 1, VV_F32);
    vv_volume_set(f, 0, 0, 0, NAN);
    assert_true(isnan(vv_volume_get(f, 0, 0, 0)));
    vv_volume_free(f);
}

static void
test_update_range(void **state) {
    (void)state;
    const struct {
        vv_voxel_type t;
        double lo, hi;
    } cases[] = {
        {VV_U8, 3, 250},          {VV_I8, -128, 127},        {VV_U16, 1, 65535},
        {VV_I16, -32768, -5},     {VV_U32, 7, 4294967295.0}, {VV_I32, -2147483648.0, 2147483647.0},
        {VV_F32, -1.5e-3, 2.5e7}, {VV_F64, -1e300, 1e-300},
    };
    /* small, and large enough to be measured in pieces on several threads
     * (the extremes in different pieces, the last piece partial) */
    const size_t n_cases = sizeof cases / sizeof cases[0];
    for (size_t run = 0; run < 2 * n_cases; run++) {
        const int big = run >= n_cases;
        const int nx = big ? 301 : 9, ny = big ? 300 : 8, nz = 7;
        const size_t c = run % n_cases;
        vv_volume *v = make_volume(nx, ny, nz, cases[c].t);
        /* fill with a middle value, then place the extremes far apart */
        double mid = cases[c].lo + (cases[c].hi - cases[c].lo) / 3;
        for (int k = 0; k < nz; k++)
            for (int j = 0; j < ny; j++)
                for (int i = 0; i < nx; i++)
                    vv_volume_set(v, i, j, k, mid);
        vv_volume_set(v, nx - 1, 0, nz - 1, cases[c].lo);
        vv_volume_set(v, 0, ny - 1, 0, cases[c].hi);
        uint64_t mod = v->modified;
        vv_volume_update_range(v);
        assert_true(v->modified > mod);
        if (v->range[0] != cases[c].lo &&
            !(cases[c].t == VV_F32 && v->range[0] == (double)(float)cases[c].lo))
            fail_msg("%s: min %.17g, want %.17g", vv_voxel_type_name(cases[c].t), v->range[0],
                     cases[c].lo);
        if (v->range[1] != cases[c].hi &&
            !(cases[c].t == VV_F32 && v->range[1] == (double)(float)cases[c].hi))
            fail_msg("%s: max %.17g, want %.17g", vv_voxel_type_name(cases[c].t), v->range[1],
                     cases[c].hi);
        vv_volume_free(v);
    }
    /* NaNs are ignored, wherever they are (first, last, everywhere between) */
    vv_volume *f = make_volume(4, 1, 1, VV_F32);
    vv_volume_set(f, 0, 0, 0, NAN);
    vv_volume_set(f, 1, 0, 0, -2.5);
    vv_volume_set(f, 2, 0, 0, 3);
    vv_volume_set(f, 3, 0, 0, NAN);
    vv_volume_update_range(f);
    assert_true(f->range[0] == -2.5 && f->range[1] == 3);
    /* all NaN: the range is still finite */
    vv_volume_set(f, 1, 0, 0, NAN);
    vv_volume_set(f, 2, 0, 0, NAN);
    vv_volume_update_range(f);
    assert_true(isfinite(f->range[0]) && isfinite(f->range[1]));
    assert_true(f->range[0] <= f->range[1]);
    vv_volume_free(f);
    vv_volume *d = make_volume(3, 1, 1, VV_F64);
    vv_volume_set(d, 0, 0, 0, 5);
    vv_volume_set(d, 1, 0, 0, NAN);
    vv_volume_set(d, 2, 0, 0, 6);
    vv_volume_update_range(d);
    assert_true(d->range[0] == 5 && d->range[1] == 6);
    vv_volume_free(d);
}

/* ---- geometry ---- */

/* A rotation about (1, 2, 3) by 0.7 rad as a row-major 3x3 direction matrix. */
static void
set_rotation(vv_volume *v) {
    vv_mat4 r = vv_mat4_rotate(vv_vec3_make(1, 2, 3), 0.7);
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            v->direction[3 * a + b] = r.m[a][b];
}

/* world = origin + D (spacing ∘ index), computed here by hand. */
static vv_vec3
by_hand(const vv_volume *v, double i, double j, double k) {
    double s[3] = {i * v->spacing[0], j * v->spacing[1], k * v->spacing[2]};
    double w[3];
    for (int r = 0; r < 3; r++)
        w[r] = v->origin[r] + v->direction[3 * r] * s[0] + v->direction[3 * r + 1] * s[1] +
               v->direction[3 * r + 2] * s[2];
    return vv_vec3_make(w[0], w[1], w[2]);
}

static void
test_index_world(void **state) {
    (void)state;
    vv_volume *v = make_volume(6, 7, 8, VV_U8);
    v->spacing[0] = 0.5;
    v->spacing[1] = 2.0;
    v->spacing[2] = 1.25;
    v->origin[0] = 10;
    v->origin[1] = -5;
    v->origin[2] = 3;
    /* axis-aligned first */
    vv_mat4 m = vv_volume_index_to_world(v);
    assert_vec_near(vv_mat4_mul_point(m, vv_vec3_make(0, 0, 0)), vv_vec3_make(10, -5, 3), 0);
    assert_vec_near(vv_mat4_mul_point(m, vv_vec3_make(2, 3, 4)), vv_vec3_make(11, 1, 8), 1e-12);
    vv_box b = vv_volume_world_box(v);
    assert_vec_near(b.min, vv_vec3_make(10, -5, 3), 1e-12);
    assert_vec_near(b.max, vv_vec3_make(12.5, 7, 11.75), 1e-12);
    /* a 90-degree turn about z: i runs along +y, j along -x */
    const double rz[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    memcpy(v->direction, rz, sizeof rz);
    m = vv_volume_index_to_world(v);
    assert_vec_near(vv_mat4_mul_point(m, vv_vec3_make(1, 0, 0)), vv_vec3_make(10, -4.5, 3), 1e-12);
    assert_vec_near(vv_mat4_mul_point(m, vv_vec3_make(0, 1, 0)), vv_vec3_make(8, -5, 3), 1e-12);
    b = vv_volume_world_box(v);
    assert_vec_near(b.min, vv_vec3_make(10 - 12, -5, 3), 1e-12);
    assert_vec_near(b.max, vv_vec3_make(10, -5 + 2.5, 11.75), 1e-12);
    /* a general rotation */
    set_rotation(v);
    m = vv_volume_index_to_world(v);
    vv_mat4 inv = vv_volume_world_to_index(v);
    uint64_t seed = 11;
    for (int trial = 0; trial < 100; trial++) {
        double i = rnd(&seed, -1, 6), j = rnd(&seed, -1, 7), k = rnd(&seed, -1, 8);
        vv_vec3 w = vv_mat4_mul_point(m, vv_vec3_make(i, j, k));
        assert_vec_near(w, by_hand(v, i, j, k), 1e-12);
        assert_vec_near(vv_mat4_mul_point(inv, w), vv_vec3_make(i, j, k), 1e-12);
    }
    /* the world box is the bounding box of the 8 corner voxel centres */
    b = vv_volume_world_box(v);
    vv_vec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; c++) {
        vv_vec3 p = by_hand(v, (c & 1) ? 5 : 0, (c & 2) ? 6 : 0, (c & 4) ? 7 : 0);
        lo = vv_vec3_make(fmin(lo.x, p.x), fmin(lo.y, p.y), fmin(lo.z, p.z));
        hi = vv_vec3_make(fmax(hi.x, p.x), fmax(hi.y, p.y), fmax(hi.z, p.z));
    }
    assert_vec_near(b.min, lo, 1e-12);
    assert_vec_near(b.max, hi, 1e-12);
    vv_volume_free(v);
}

/* ---- sampling ---- */

/* A trilinear function: trilinear interpolation reproduces it exactly. */
static double
trilin(double i, double j, double k) {
    return 1.5 + 2 * i - 3 * j + 0.75 * k + 0.125 * i * j - 0.25 * j * k + 0.0625 * i * k +
           0.03125 * i * j * k;
}

/* A linear function f = a + b i + c j + d k. */
#define LA 1.5
#define LB 2.0
#define LC (-3.0)
#define LD 0.75

static double
linear(double i, double j, double k) {
    return LA + LB * i + LC * j + LD * k;
}

static vv_volume *
fill(int nx, int ny, int nz, double (*f)(double, double, double)) {
    vv_volume *v = make_volume(nx, ny, nz, VV_F64);
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++)
                vv_volume_set(v, i, j, k, f(i, j, k));
    vv_volume_update_range(v);
    return v;
}

static void
test_sample_index(void **state) {
    (void)state;
    vv_volume *v = fill(7, 5, 6, trilin);
    uint64_t seed = 17;
    for (int trial = 0; trial < 500; trial++) {
        double x = rnd(&seed, 0, 6), y = rnd(&seed, 0, 4), z = rnd(&seed, 0, 5);
        double want = trilin(x, y, z);
        assert_near(vv_volume_sample_index(v, x, y, z), want, 1e-5 * (1 + fabs(want)));
    }
    /* grid points are exact (up to float) and the far corner is reachable */
    assert_near(vv_volume_sample_index(v, 6, 4, 5), (float)trilin(6, 4, 5), 0);
    assert_near(vv_volume_sample_index(v, 0, 0, 0), (float)trilin(0, 0, 0), 0);
    /* outside the grid, coordinates clamp to it */
    assert_near(vv_volume_sample_index(v, -3, 2.5, 1.5), vv_volume_sample_index(v, 0, 2.5, 1.5), 0);
    assert_near(vv_volume_sample_index(v, 100, 2.5, 1.5), vv_volume_sample_index(v, 6, 2.5, 1.5),
                0);
    assert_near(vv_volume_sample_index(v, 1.5, -0.5, 99), vv_volume_sample_index(v, 1.5, 0, 5), 0);
    assert_near(vv_volume_sample_index(v, -1e300, 1e300, -INFINITY),
                vv_volume_sample_index(v, 0, 4, 0), 0);
    vv_volume_free(v);
    /* a volume one voxel thick along an axis */
    vv_volume *t = fill(4, 1, 3, linear);
    assert_near(vv_volume_sample_index(t, 1.5, 0, 0.5), linear(1.5, 0, 0.5), 1e-5);
    assert_near(vv_volume_sample_index(t, 1.5, 0.7, 0.5), linear(1.5, 0, 0.5), 1e-5);
    vv_volume_free(t);
    /* integer types sample as float too */
    vv_volume *u = make_volume(2, 1, 1, VV_U8);
    vv_volume_set(u, 0, 0, 0, 10);
    vv_volume_set(u, 1, 0, 0, 255);
    assert_near(vv_volume_sample_index(u, 0.25, 0, 0), 10 + 0.25 * 245, 1e-4);
    vv_volume_free(u);
}

static vv_volume *
linear_world_volume(int rotated) {
    vv_volume *v = fill(9, 7, 8, linear);
    v->spacing[0] = 0.5;
    v->spacing[1] = 2.0;
    v->spacing[2] = 1.25;
    v->origin[0] = 10;
    v->origin[1] = -5;
    v->origin[2] = 3;
    if (rotated)
        set_rotation(v);
    return v;
}

static void
test_sample_world(void **state) {
    (void)state;
    for (int rotated = 0; rotated < 2; rotated++) {
        vv_volume *v = linear_world_volume(rotated);
        uint64_t seed = 23;
        float val = -1;
        for (int trial = 0; trial < 200; trial++) {
            double i = rnd(&seed, 0, 8), j = rnd(&seed, 0, 6), k = rnd(&seed, 0, 7);
            vv_vec3 w = by_hand(v, i, j, k);
            assert_int_equal(vv_volume_sample_world(v, w, &val), 1);
            assert_near(val, linear(i, j, k), 1e-4);
        }
        /* voxel centres on the box faces are inside, including the corners */
        assert_int_equal(vv_volume_sample_world(v, by_hand(v, 8, 6, 7), &val), 1);
        assert_near(val, linear(8, 6, 7), 1e-4);
        assert_int_equal(vv_volume_sample_world(v, by_hand(v, 0, 0, 0), &val), 1);
        assert_near(val, linear(0, 0, 0), 1e-4);
        /* just outside: 0 and value 0 */
        const double out[][3] = {{-0.01, 3, 3}, {8.01, 3, 3},  {4, -0.01, 3},
                                 {4, 6.01, 3},  {4, 3, -0.01}, {4, 3, 7.01}};
        for (size_t n = 0; n < sizeof out / sizeof out[0]; n++) {
            val = 99;
            assert_int_equal(
                vv_volume_sample_world(v, by_hand(v, out[n][0], out[n][1], out[n][2]), &val), 0);
            assert_true(val == 0);
        }
        vv_volume_free(v);
    }
}

static void
test_gradient_world(void **state) {
    (void)state;
    for (int rotated = 0; rotated < 2; rotated++) {
        vv_volume *v = linear_world_volume(rotated);
        /* index-space gradient (b, c, d) divided by the spacing, then turned by D */
        double gi[3] = {LB / 0.5, LC / 2.0, LD / 1.25};
        vv_vec3 want = vv_vec3_make(
            v->direction[0] * gi[0] + v->direction[1] * gi[1] + v->direction[2] * gi[2],
            v->direction[3] * gi[0] + v->direction[4] * gi[1] + v->direction[5] * gi[2],
            v->direction[6] * gi[0] + v->direction[7] * gi[1] + v->direction[8] * gi[2]);
        if (!rotated)
            assert_vec_near(want, vv_vec3_make(4, -1.5, 0.6), 1e-15);
        uint64_t seed = 29;
        for (int trial = 0; trial < 200; trial++) {
            /* everywhere in the box, including within half a voxel of the faces */
            double i = rnd(&seed, 0, 8), j = rnd(&seed, 0, 6), k = rnd(&seed, 0, 7);
            if (trial == 0)
                i = j = k = 0;
            if (trial == 1) {
                i = 8;
                j = 6;
                k = 7;
            }
            vv_vec3 g;
            vv_vec3 p = by_hand(v, i, j, k);
            assert_int_equal(vv_volume_gradient_world(v, p, &g), 1);
            assert_vec_near(g, want, 1e-4);
            /* independent check: world-space central differences of samples */
            if (i > 1 && i < 7 && j > 1 && j < 5 && k > 1 && k < 6) {
                const double h = 0.05;
                double fd[3];
                for (int a = 0; a < 3; a++) {
                    vv_vec3 e = vv_vec3_make(a == 0 ? h : 0, a == 1 ? h : 0, a == 2 ? h : 0);
                    float f1, f0;
                    assert_int_equal(vv_volume_sample_world(v, vv_vec3_add(p, e), &f1), 1);
                    assert_int_equal(vv_volume_sample_world(v, vv_vec3_sub(p, e), &f0), 1);
                    fd[a] = ((double)f1 - (double)f0) / (2 * h);
                }
                assert_vec_near(g, vv_vec3_make(fd[0], fd[1], fd[2]), 2e-3);
            }
        }
        /* outside: 0 and a zero gradient */
        vv_vec3 g = {9, 9, 9};
        assert_int_equal(vv_volume_gradient_world(v, by_hand(v, -0.5, 3, 3), &g), 0);
        assert_true(g.x == 0 && g.y == 0 && g.z == 0);
        vv_volume_free(v);
    }
}

/* ---- histogram and quantile ---- */

static void
test_histogram(void **state) {
    (void)state;
    vv_volume *v = make_volume(16, 8, 2, VV_U8);
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 8; j++)
            for (int i = 0; i < 16; i++)
                vv_volume_set(v, i, j, k, i + 16 * j + 128 * k); /* 0..255 once each */
    uint64_t bins[10];
    vt_ok(vv_volume_histogram(v, 4, 0, 256, bins));
    for (int b = 0; b < 4; b++)
        assert_true(bins[b] == 64);
    /* values outside [lo, hi] go to the end bins; hi itself is in the last */
    vt_ok(vv_volume_histogram(v, 10, 100, 200, bins));
    assert_true(bins[0] == 110); /* 0..109 */
    for (int b = 1; b < 9; b++)
        if (bins[b] != 10)
            fail_msg("bin %d has %llu, want 10", b, (unsigned long long)bins[b]);
    assert_true(bins[9] == 66); /* 190..255 */
    /* one bin takes everything */
    vt_ok(vv_volume_histogram(v, 1, -1e9, -1e8, bins));
    assert_true(bins[0] == 256);
    /* the result does not depend on the thread count */
    uint64_t one[7], many[7];
    vv_threads_set(1);
    vt_ok(vv_volume_histogram(v, 7, 3, 251, one));
    vv_threads_set(5);
    vt_ok(vv_volume_histogram(v, 7, 3, 251, many));
    vv_threads_set(0);
    assert_memory_equal(one, many, sizeof one);
    /* bad arguments */
    vt_err(vv_volume_histogram(v, 0, 0, 1, bins));
    vt_err(vv_volume_histogram(v, -3, 0, 1, bins));
    vt_err(vv_volume_histogram(v, 4, 1, 1, bins));
    vt_err(vv_volume_histogram(v, 4, 2, 1, bins));
    vt_err(vv_volume_histogram(v, 4, 0, NAN, bins));
    assert_int_equal(vv_volume_histogram(v, 4, 2, 1, bins), VV_ERR_INVALID);
    vv_volume_free(v);
    /* NaNs are skipped; infinities clamp into the end bins */
    vv_volume *f = make_volume(5, 1, 1, VV_F32);
    vv_volume_set(f, 0, 0, 0, NAN);
    vv_volume_set(f, 1, 0, 0, -INFINITY);
    vv_volume_set(f, 2, 0, 0, INFINITY);
    vv_volume_set(f, 3, 0, 0, 0.5);
    vv_volume_set(f, 4, 0, 0, NAN);
    vt_ok(vv_volume_histogram(f, 2, 0, 1, bins));
    assert_true(bins[0] == 1 && bins[1] == 2);
    vv_volume_free(f);
}

static void
test_quantile(void **state) {
    (void)state;
    /* 0..999 once each, in a scrambled order */
    vv_volume *v = make_volume(10, 10, 10, VV_F32);
    for (int n = 0; n < 1000; n++) {
        int m = (n * 367) % 1000; /* 367 is prime to 1000: a permutation */
        vv_volume_set(v, m % 10, (m / 10) % 10, m / 100, n);
    }
    vv_volume_update_range(v);
    assert_true(v->range[0] == 0 && v->range[1] == 999);
    assert_near(vv_volume_quantile(v, 0), 0, 1e-9);
    assert_near(vv_volume_quantile(v, 1), 999, 1e-9);
    const double qs[] = {0.1, 0.25, 0.5, 0.9, 0.99};
    for (size_t n = 0; n < sizeof qs / sizeof qs[0]; n++)
        assert_near(vv_volume_quantile(v, qs[n]), qs[n] * 1000, 1.0);
    /* several in one pass: each the one-at-a-time quantile */
    double many[5];
    vv_volume_quantiles(v, 5, qs, many);
    for (size_t n = 0; n < 5; n++)
        assert_true(many[n] == vv_volume_quantile(v, qs[n]));
    /* monotone in q */
    double prev = -1;
    for (double q = 0; q <= 1.0; q += 0.01) {
        double x = vv_volume_quantile(v, q);
        assert_true(x >= prev);
        prev = x;
    }
    vv_volume_free(v);
    /* a skewed distribution: 90 % zeros, 10 % tens */
    vv_volume *s = make_volume(100, 1, 1, VV_U8);
    for (int i = 90; i < 100; i++)
        vv_volume_set(s, i, 0, 0, 10);
    vv_volume_update_range(s);
    assert_true(vv_volume_quantile(s, 0.5) <= 10.0 / 4096 + 1e-12);
    assert_true(vv_volume_quantile(s, 0.85) <= 10.0 / 4096 + 1e-12);
    assert_true(vv_volume_quantile(s, 0.95) >= 10 - 10.0 / 4096 - 1e-12);
    vv_volume_free(s);
    /* a constant volume: every quantile is that value */
    vv_volume *c = make_volume(3, 3, 3, VV_I16);
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 3; i++)
                vv_volume_set(c, i, j, k, -42);
    vv_volume_update_range(c);
    assert_near(vv_volume_quantile(c, 0.3), -42, 0);
    vv_volume_free(c);
}

/* ---- a large volume ---- */

static void
test_large(void **state) {
    (void)state;
    const int dims[3] = {512, 512, 512};
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, VV_U8);
    if (s == VV_ERR_NOMEM)
        vt_skip("512^3 u8 (128 MiB) could not be allocated: %s", vv_error_message());
    vt_ok(s);
    assert_true(vv_volume_voxel_count(v) == (uint64_t)1 << 27);
    vv_volume_set(v, 511, 511, 511, 7);
    vv_volume_set(v, 0, 0, 0, 3);
    vv_volume_set(v, 1, 300, 400, 200);
    assert_int_equal(((uint8_t *)v->data)[((size_t)511 * 512 + 511) * 512 + 511], 7);
    assert_int_equal(((uint8_t *)v->data)[((size_t)400 * 512 + 300) * 512 + 1], 200);
    assert_true(vv_volume_get(v, 0, 0, 0) == 3);
    vv_volume_update_range(v);
    assert_true(v->range[0] == 0 && v->range[1] == 200);
    vv_volume_free(v);
}

/* ---- voxel type names ---- */

static void
test_type_names(void **state) {
    (void)state;
    const char *names[] = {"u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64"};
    const size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
    for (int t = VV_U8; t <= VV_F64; t++) {
        assert_string_equal(vv_voxel_type_name((vv_voxel_type)t), names[t]);
        assert_int_equal(vv_voxel_type_size((vv_voxel_type)t), sizes[t]);
        vv_voxel_type back = (vv_voxel_type)99;
        vt_ok(vv_voxel_type_parse(vv_voxel_type_name((vv_voxel_type)t), &back));
        assert_int_equal(back, t);
    }
    const struct {
        const char *name;
        vv_voxel_type t;
    } alias[] = {{"uchar", VV_U8},   {"uint8", VV_U8},    {"char", VV_I8},    {"short", VV_I16},
                 {"ushort", VV_U16}, {"int", VV_I32},     {"uint", VV_U32},   {"float", VV_F32},
                 {"double", VV_F64}, {"float32", VV_F32}, {"float64", VV_F64}};
    for (size_t n = 0; n < sizeof alias / sizeof alias[0]; n++) {
        vv_voxel_type t = (vv_voxel_type)99;
        vt_ok(vv_voxel_type_parse(alias[n].name, &t));
        assert_int_equal(t, alias[n].t);
    }
    vv_voxel_type t = VV_F64;
    vt_err(vv_voxel_type_parse("u9", &t));
    assert_non_null(strstr(vv_error_message(), "u9"));
    vt_err(vv_voxel_type_parse("", &t));
    vt_err(vv_voxel_type_parse("u8 ", &t));
    assert_int_equal(vv_voxel_type_parse("bogus", &t), VV_ERR_INVALID);
    /* out-of-range values do not crash */
    assert_non_null(vv_voxel_type_name((vv_voxel_type)42));
    assert_int_equal(vv_voxel_type_size((vv_voxel_type)42), 0);
}

/* The min/max grid against a brute-force scan of each subvolume's voxels. */
static void
test_minmax_grid(void **state) {
    (void)state;
    vv_volume *v = make_volume(13, 9, 1, VV_I16);
    uint64_t seed = 7;
    for (int j = 0; j < 9; j++)
        for (int i = 0; i < 13; i++)
            vv_volume_set(v, i, j, 0, rnd(&seed, -1000, 1000));
    vv_minmax_grid *g = NULL;
    vt_err(vv_minmax_grid_build(&g, v, 0));
    vt_ok(vv_minmax_grid_build(&g, v, 4));
    assert_int_equal(g->dims[0], 3);
    assert_int_equal(g->dims[1], 2);
    assert_int_equal(g->dims[2], 1);
    for (int bj = 0; bj < 2; bj++)
        for (int bi = 0; bi < 3; bi++) {
            double mn = INFINITY, mx = -INFINITY;
            for (int j = 4 * bj; j <= 4 * bj + 4 && j < 9; j++)
                for (int i = 4 * bi; i <= 4 * bi + 4 && i < 13; i++) {
                    mn = fmin(mn, vv_volume_get(v, i, j, 0));
                    mx = fmax(mx, vv_volume_get(v, i, j, 0));
                }
            assert_near(g->min[bj * 3 + bi], mn, 0);
            assert_near(g->max[bj * 3 + bi], mx, 0);
        }
    vv_minmax_grid_free(g);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_minmax_grid),    cmocka_unit_test(test_check_size),
        cmocka_unit_test(test_new_ref_free),   cmocka_unit_test(test_ref_threads),
        cmocka_unit_test(test_layout),         cmocka_unit_test(test_get_set_round),
        cmocka_unit_test(test_update_range),   cmocka_unit_test(test_index_world),
        cmocka_unit_test(test_sample_index),   cmocka_unit_test(test_sample_world),
        cmocka_unit_test(test_gradient_world), cmocka_unit_test(test_histogram),
        cmocka_unit_test(test_quantile),       cmocka_unit_test(test_large),
        cmocka_unit_test(test_type_names),
    };
    return vt_run_tests(tests, NULL, NULL);
}
