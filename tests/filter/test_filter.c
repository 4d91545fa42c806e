/*
 * The Filtering component against analytic answers, bad input, thread
 * counts, cancellation and the geometry it must keep: the Gaussian of a
 * delta on anisotropic voxels, the gradient of a linear ramp, the Laplacian
 * of a parabola, Otsu on two levels, region growing on two touching
 * spheres, world positions through crop/pad/flip/permute/resample, label
 * overflow and NaN voxels.
 */
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static vv_filter_options
threads(int n) {
    vv_filter_options o;
    vv_filter_options_init(&o);
    o.threads = n;
    return o;
}

static vv_volume *
vol(int nx, int ny, int nz, vv_voxel_type t, double sx, double sy, double sz) {
    vv_volume *v;
    vt_ok(vv_volume_new(&v, (int[]){nx, ny, nz}, t));
    v->spacing[0] = sx;
    v->spacing[1] = sy;
    v->spacing[2] = sz;
    return v;
}

static vv_vec3
world(const vv_volume *v, double i, double j, double k) {
    vv_mat4 m = vv_volume_index_to_world(v);
    return vv_mat4_mul_point(m, vv_vec3_make(i, j, k));
}

/* The Gaussian of a delta is a sampled Gaussian with sigma in world units. */
static void
test_gaussian_delta(void **state) {
    (void)state;
    vv_volume *v = vol(61, 31, 21, VV_F32, 0.5, 1.0, 2.0);
    const int c[3] = {30, 15, 10};
    vv_volume_set(v, c[0], c[1], c[2], 1.0);
    const double sigma = 3.0; /* world: 6, 3 and 1.5 voxels */
    vv_volume *g;
    vt_ok(vv_filter_gaussian(v, (double[]){sigma, sigma, sigma}, NULL, &g));
    assert_int_equal(g->type, VV_F32);
    double sum = 0, m2[3] = {0, 0, 0}, peak = vv_volume_get(g, c[0], c[1], c[2]), worst = 0;
    for (int k = 0; k < 21; k++)
        for (int j = 0; j < 31; j++)
            for (int i = 0; i < 61; i++) {
                double x = (i - c[0]) * 0.5, y = (j - c[1]) * 1.0, z = (k - c[2]) * 2.0;
                double f = vv_volume_get(g, i, j, k);
                sum += f;
                m2[0] += f * x * x;
                m2[1] += f * y * y;
                m2[2] += f * z * z;
                double r2 = x * x + y * y + z * z;
                if (r2 <= 4 * sigma * sigma) {
                    double expect = peak * exp(-0.5 * r2 / (sigma * sigma));
                    worst = fmax(worst, fabs(f - expect) / expect);
                }
            }
    assert_near(sum, 1.0, 1e-5);
    /* isotropic in the world: the same variance along x, y and z */
    for (int a = 0; a < 3; a++)
        assert_near(m2[a], sigma * sigma, 0.01 * sigma * sigma);
    assert_true(worst < 1e-4);
    vv_volume_free(g);
    vv_volume_free(v);
}

/* A linear ramp f = 2x + 3y - z (world) on anisotropic, rotated voxels. */
static void
test_gradient_ramp(void **state) {
    (void)state;
    vv_volume *v = vol(12, 10, 9, VV_F32, 0.7, 1.3, 2.1);
    /* a rotation about z by 30 degrees, and an origin */
    double cs = cos(M_PI / 6), sn = sin(M_PI / 6);
    double R[9] = {cs, -sn, 0, sn, cs, 0, 0, 0, 1};
    memcpy(v->direction, R, sizeof R);
    v->origin[0] = 5;
    v->origin[1] = -3;
    v->origin[2] = 2;
    for (int k = 0; k < 9; k++)
        for (int j = 0; j < 10; j++)
            for (int i = 0; i < 12; i++) {
                vv_vec3 p = world(v, i, j, k);
                vv_volume_set(v, i, j, k, 2 * p.x + 3 * p.y - p.z);
            }
    vv_volume *g[3];
    vt_ok(vv_filter_gradient(v, 0, NULL, g));
    const double expect[3] = {2, 3, -1};
    for (int a = 0; a < 3; a++) {
        const float *d = g[a]->data;
        for (size_t q = 0; q < 12 * 10 * 9; q++)
            assert_near(d[q], expect[a], 2e-4);
        vv_volume_free(g[a]);
    }
    /* derivative of Gaussian: exact away from the faces */
    vt_ok(vv_filter_gradient(v, 1.0, NULL, g));
    for (int a = 0; a < 3; a++) {
        assert_near(vv_volume_get(g[a], 6, 5, 4), expect[a], 2e-3);
        vv_volume_free(g[a]);
    }
    vv_volume *m;
    vt_ok(vv_filter_gradient_magnitude(v, 0, NULL, &m));
    assert_near(vv_volume_get(m, 0, 0, 0), sqrt(14.0), 2e-4);
    vv_volume_free(m);
    vv_volume_free(v);
}

/* The Laplacian of x^2 + y^2 + z^2 is 6 (per world unit squared). */
static void
test_laplacian(void **state) {
    (void)state;
    vv_volume *v = vol(24, 22, 20, VV_F64, 0.5, 0.8, 1.1);
    for (int k = 0; k < 20; k++)
        for (int j = 0; j < 22; j++)
            for (int i = 0; i < 24; i++) {
                vv_vec3 p = world(v, i, j, k);
                vv_volume_set(v, i, j, k, p.x * p.x + p.y * p.y + p.z * p.z);
            }
    vv_volume *l;
    vt_ok(vv_filter_laplacian(v, 0, NULL, &l));
    assert_near(vv_volume_get(l, 10, 11, 9), 6.0, 1e-3);
    vv_volume_free(l);
    vt_ok(vv_filter_laplacian(v, 1.0, NULL, &l));
    assert_near(vv_volume_get(l, 12, 11, 10), 6.0, 5e-3);
    vv_volume_free(l);
    vv_volume_free(v);
}

/* Otsu on two levels finds the gap; the threshold separates them. */
static void
test_otsu(void **state) {
    (void)state;
    vv_volume *v = vol(20, 20, 20, VV_I16, 1, 1, 1);
    for (int k = 0; k < 20; k++)
        for (int j = 0; j < 20; j++)
            for (int i = 0; i < 20; i++)
                vv_volume_set(v, i, j, k, (i - 8) * (i - 8) + (j - 9) * (j - 9) < 30 ? 900 : -200);
    double t;
    vt_ok(vv_filter_otsu(v, &t));
    print_message("otsu: %g\n", t);
    assert_true(t > -200 && t <= 900);
    assert_near(t, 350, 2); /* the middle of the gap */
    vv_volume *m;
    vt_ok(vv_filter_threshold(v, t, INFINITY, NULL, &m));
    for (size_t q = 0; q < 8000; q++)
        assert_int_equal(((uint8_t *)m->data)[q], vv_voxel_value(VV_I16, v->data, q) == 900);
    vv_volume_free(m);
    vv_volume_free(v);
    /* a constant volume has no threshold */
    v = vol(4, 4, 4, VV_U8, 1, 1, 1);
    vt_err(vv_filter_otsu(v, &t));
    vv_volume_free(v);
}

/* Two touching spheres of different values: growing from a seed in one
 * with its value range takes exactly that sphere. */
static void
test_region_grow(void **state) {
    (void)state;
    vv_volume *v = vol(40, 24, 24, VV_U8, 1, 1, 1);
    const double r = 9;
    int na = 0;
    for (int k = 0; k < 24; k++)
        for (int j = 0; j < 24; j++)
            for (int i = 0; i < 40; i++) {
                double a = (i - 10.5) * (i - 10.5) + (j - 12) * (j - 12) + (k - 12) * (k - 12);
                double b = (i - 28.5) * (i - 28.5) + (j - 12) * (j - 12) + (k - 12) * (k - 12);
                if (a <= r * r) {
                    vv_volume_set(v, i, j, k, 100);
                    na++;
                } else if (b <= r * r) {
                    vv_volume_set(v, i, j, k, 200);
                }
            }
    /* they touch: voxels 19 and 20 along the centre line */
    assert_int_equal(vv_volume_get(v, 19, 12, 12), 100);
    assert_int_equal(vv_volume_get(v, 20, 12, 12), 200);
    vv_volume *m;
    const int seed[1][3] = {{10, 12, 12}};
    vt_ok(vv_filter_region_grow(v, seed, 1, 50, 150, 26, NULL, &m));
    int got = 0;
    for (int k = 0; k < 24; k++)
        for (int j = 0; j < 24; j++)
            for (int i = 0; i < 40; i++) {
                int in = vv_volume_get(m, i, j, k) != 0;
                assert_int_equal(in, vv_volume_get(v, i, j, k) == 100);
                got += in;
            }
    assert_int_equal(got, na);
    vv_volume_free(m);
    /* a range holding both takes both; seeds outside or out of range fail */
    vt_ok(vv_filter_region_grow(v, seed, 1, 50, 250, 6, NULL, &m));
    assert_int_equal(vv_volume_get(m, 28, 12, 12), 1);
    vv_volume_free(m);
    const int outside[1][3] = {{40, 0, 0}};
    vt_err(vv_filter_region_grow(v, outside, 1, 50, 150, 6, NULL, &m));
    assert_non_null(strstr(vv_error_message(), "outside the volume"));
    const int negative[1][3] = {{-1, 3, 3}};
    vt_err(vv_filter_region_grow(v, negative, 1, 50, 150, 6, NULL, &m));
    const int bg[1][3] = {{0, 0, 0}};
    vt_err(vv_filter_region_grow(v, bg, 1, 50, 150, 6, NULL, &m));
    assert_non_null(strstr(vv_error_message(), "outside the range"));
    vv_volume_free(v);
}

/* Frangi vesselness: high on the axis of a bright tube, low on a bright
 * plate and a blob of the same profile, zero for a dark tube unless asked. */
static void
test_vesselness(void **state) {
    (void)state;
    vv_volume *v = vol(48, 40, 40, VV_F32, 1, 1, 1);
    for (int k = 0; k < 40; k++)
        for (int j = 0; j < 40; j++)
            for (int i = 0; i < 48; i++) {
                double tube = exp(-((j - 10) * (j - 10) + (k - 10) * (k - 10)) / 8.0);
                double plate = exp(-(k - 30) * (k - 30) / 8.0) * (j >= 20);
                double blob =
                    exp(-((i - 36) * (i - 36) + (j - 10) * (j - 10) + (k - 22) * (k - 22)) / 8.0);
                vv_volume_set(v, i, j, k, 100 * (tube * (i < 28) + plate + blob));
            }
    vv_volume *o;
    vt_ok(vv_filter_vesselness(v, (double[]){1.5, 2.0, 3.0}, 3, 0.5, 0.5, 0, 1, NULL, &o));
    double on_tube = vv_volume_get(o, 14, 10, 10), plate = vv_volume_get(o, 24, 30, 30),
           blob = vv_volume_get(o, 36, 10, 22), bg = vv_volume_get(o, 24, 30, 12);
    print_message("vesselness: tube %.3f plate %.3f blob %.3f background %.3f\n", on_tube, plate,
                  blob, bg);
    assert_true(on_tube > 0.3);
    /* a blob: Ra = Rb = 1, exp(-1 / 2 beta^2) = 0.135 of the tube at most */
    assert_true(plate < 0.05 * on_tube && blob < 0.2 * on_tube && bg < 0.01);
    vv_volume_free(o);
    /* dark vessels: the bright tube gives nothing */
    vt_ok(vv_filter_vesselness(v, (double[]){2.0}, 1, 0.5, 0.5, 0, 0, NULL, &o));
    assert_true(vv_volume_get(o, 14, 10, 10) < 0.01);
    vv_volume_free(o);
    vv_volume_free(v);
}

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double
rnd(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* Every filter gives bit-identical output on 1, 2 and 5 threads. */
static void
test_thread_counts(void **state) {
    (void)state;
    vv_volume *v = vol(37, 29, 23, VV_I16, 0.9, 1.1, 1.7);
    for (size_t q = 0; q < 37 * 29 * 23; q++)
        ((int16_t *)v->data)[q] = (int16_t)(rnd() < 0.4 ? 1000 * rnd() : -500 * rnd());
    vv_volume_update_range(v);
    static const char *chains[][2] = {
        {"gaussian", "1.3"},
        {"median", "1"},
        {"median", "2"},
        {"bilateral", "1.5:200"},
        {"diffusion", "5:100"},
        {"resize", "20x41x17:sinc"},
        {"resample", "0.5x0.5x0.5:bspline"},
        {"resize", "50x13x30:nearest"},
        {"cast", "u8:rescale"},
        {"crop", "3,2,1:30,20,19"},
        {"pad", "2,3,1:-7"},
        {"flip", "x"},
        {"flip", "z"},
        {"permute", "zxy"},
        {"gradient", "0"},
        {"gradient", "1.2"},
        {"laplacian", "1.0"},
        {"vesselness", "1,2"},
        {"threshold", "otsu"},
        {"window", "-100:500"},
        {"grow", "0,0,0:-1000:2000:26"},
        {"components", "26"},
        {"largest", "2:18"},
        {"close", "1"},
        {"fill-holes", ""},
    };
    for (size_t c = 0; c < sizeof chains / sizeof chains[0]; c++) {
        vv_filter_chain *ch;
        vt_ok(vv_filter_chain_new(&ch));
        if (strcmp(chains[c][0], "largest") == 0 || strcmp(chains[c][0], "components") == 0 ||
            strcmp(chains[c][0], "close") == 0 || strcmp(chains[c][0], "fill-holes") == 0)
            vt_ok(vv_filter_chain_add(ch, "threshold", "200:"));
        vt_ok(vv_filter_chain_add(ch, chains[c][0], chains[c][1]));
        vv_volume *ref = NULL;
        for (int nt = 1; nt <= 5; nt += nt == 1 ? 1 : 3) {
            vv_filter_options o = threads(nt);
            vv_volume *out;
            vt_ok(vv_filter_chain_apply(ch, v, &o, &out));
            if (!ref) {
                ref = out;
                continue;
            }
            assert_int_equal(out->type, ref->type);
            assert_memory_equal(out->dims, ref->dims, sizeof out->dims);
            if (memcmp(out->data, ref->data,
                       (size_t)vv_volume_voxel_count(out) * vv_voxel_type_size(out->type)) != 0)
                fail_msg("%s: %d threads differ from 1", vv_filter_chain_text(ch), nt);
            vv_volume_free(out);
        }
        vv_volume_free(ref);
        vv_filter_chain_free(ch);
    }
    vv_volume_free(v);
}

static int
cancel_at_half(void *u, double f) {
    (void)u;
    return f >= 0.5;
}

static void
test_cancel(void **state) {
    (void)state;
    vv_volume *v = vol(40, 40, 40, VV_U8, 1, 1, 1);
    vv_filter_options o = threads(2);
    o.progress.fn = cancel_at_half;
    vv_volume *out = NULL;
    assert_int_equal(vv_filter_gaussian(v, (double[]){2, 2, 2}, &o, &out), VV_ERR_CANCELLED);
    assert_null(out);
    assert_int_equal(vv_filter_median(v, 1, &o, &out), VV_ERR_CANCELLED);
    assert_int_equal(vv_filter_resample(v, (int[]){50, 50, 50}, VV_KERNEL_LINEAR, &o, &out),
                     VV_ERR_CANCELLED);
    assert_null(out);
    vv_volume_free(v);
}

/* Voxels keep their world positions through the reshaping filters. */
static void
test_geometry(void **state) {
    (void)state;
    vv_volume *v = vol(7, 6, 5, VV_U16, 0.5, 1.5, 2.5);
    double cs = cos(0.3), sn = sin(0.3);
    double R[9] = {1, 0, 0, 0, cs, -sn, 0, sn, cs};
    memcpy(v->direction, R, sizeof R);
    v->origin[0] = 10;
    v->origin[1] = 20;
    v->origin[2] = -5;
    for (int k = 0; k < 5; k++)
        for (int j = 0; j < 6; j++)
            for (int i = 0; i < 7; i++)
                vv_volume_set(v, i, j, k, i + 10 * j + 100 * k);
    vv_volume_update_range(v);
    vv_volume *c, *p, *f, *m;
    vt_ok(vv_filter_crop(v, (int[]){2, 1, 3}, (int[]){5, 4, 4}, NULL, &c));
    assert_int_equal(c->dims[0], 4);
    assert_int_equal(vv_volume_get(c, 0, 0, 0), vv_volume_get(v, 2, 1, 3));
    vv_vec3 a = world(c, 1, 2, 1), b = world(v, 3, 3, 4);
    assert_near(a.x, b.x, 1e-9);
    assert_near(a.y, b.y, 1e-9);
    assert_near(a.z, b.z, 1e-9);
    vt_ok(vv_filter_pad(v, (int[]){2, 1, 0}, (int[]){2, 1, 0}, 7, NULL, &p));
    assert_int_equal(p->dims[0], 11);
    assert_int_equal(vv_volume_get(p, 0, 0, 0), 7);
    assert_int_equal(vv_volume_get(p, 2, 1, 0), 0);
    a = world(p, 2, 1, 0);
    b = world(v, 0, 0, 0);
    assert_near(a.y, b.y, 1e-9);
    assert_near(a.z, b.z, 1e-9);
    for (int axis = 0; axis < 3; axis++) {
        vt_ok(vv_filter_flip(v, axis, NULL, &f));
        int idx[3] = {1, 2, 3}, fi[3] = {1, 2, 3};
        fi[axis] = v->dims[axis] - 1 - idx[axis];
        assert_int_equal(vv_volume_get(f, fi[0], fi[1], fi[2]),
                         vv_volume_get(v, idx[0], idx[1], idx[2]));
        a = world(f, fi[0], fi[1], fi[2]);
        b = world(v, idx[0], idx[1], idx[2]);
        assert_near(a.x, b.x, 1e-9);
        assert_near(a.y, b.y, 1e-9);
        assert_near(a.z, b.z, 1e-9);
        vv_volume_free(f);
    }
    vt_ok(vv_filter_permute(v, (int[]){2, 0, 1}, NULL, &m));
    assert_int_equal(m->dims[0], 5);
    assert_int_equal(m->dims[1], 7);
    assert_int_equal(vv_volume_get(m, 3, 1, 2), vv_volume_get(v, 1, 2, 3));
    a = world(m, 3, 1, 2);
    b = world(v, 1, 2, 3);
    assert_near(a.x, b.x, 1e-9);
    assert_near(a.y, b.y, 1e-9);
    assert_near(a.z, b.z, 1e-9);
    vv_volume_free(m);
    /* resampling keeps the extent: the last voxel stays where it was */
    vt_ok(vv_filter_resample_spacing(v, (double[]){0.25, 0.75, 1.25}, VV_KERNEL_LINEAR, NULL, &m));
    assert_int_equal(m->dims[0], 13);
    assert_int_equal(m->dims[2], 9);
    a = world(m, 12, 10, 8);
    b = world(v, 6, 5, 4);
    assert_near(a.x, b.x, 1e-9);
    assert_near(a.y, b.y, 1e-9);
    assert_near(a.z, b.z, 1e-9);
    assert_near(vv_volume_get(m, 3, 4, 1), 1.5 + 10 * 2 + 100 * 0.5, 1e-3); /* trilinear */
    vv_volume_free(m);
    /* cast: clamp and rescale */
    vt_ok(vv_filter_cast(v, VV_U8, 0, NULL, &m));
    assert_int_equal(vv_volume_get(m, 6, 5, 4), 255);
    assert_int_equal(vv_volume_get(m, 6, 5, 0), 56);
    vv_volume_free(m);
    vt_ok(vv_filter_cast(v, VV_U8, 1, NULL, &m));
    assert_int_equal(vv_volume_get(m, 6, 5, 4), 255);
    assert_int_equal(vv_volume_get(m, 0, 0, 0), 0);
    vv_volume_free(m);
    vv_volume_free(c);
    vv_volume_free(p);
    vv_volume_free(v);
}

static void
test_bad_input(void **state) {
    (void)state;
    vv_volume *v = vol(6, 5, 4, VV_F32, 1, 1, 1), *o = NULL;
    vt_err(vv_filter_gaussian(v, (double[]){0, 1, 1}, NULL, &o));
    assert_non_null(strstr(vv_error_message(), "sigma"));
    vt_err(vv_filter_gaussian(v, (double[]){-1, -1, -1}, NULL, &o));
    vt_err(vv_filter_gaussian(v, (double[]){NAN, 1, 1}, NULL, &o));
    vt_err(vv_filter_gaussian(NULL, (double[]){1, 1, 1}, NULL, &o));
    vt_err(vv_filter_median(v, -1, NULL, &o));
    vt_err(vv_filter_median(v, VV_FILTER_MAX_RADIUS + 1, NULL, &o));
    vt_err(vv_filter_morphology(v, VV_MORPH_ERODE, 0, NULL, &o));
    vt_err(vv_filter_bilateral(v, 0, 10, NULL, &o));
    vt_err(vv_filter_bilateral(v, 1, -1, NULL, &o));
    vt_err(vv_filter_bilateral(v, 1000, 1, NULL, &o));
    vt_err(vv_filter_diffusion(v, 3, 1, 0.5, NULL, &o));
    vt_err(vv_filter_diffusion(v, 0, 1, 0.1, NULL, &o));
    vt_err(vv_filter_gradient(v, -1, NULL, (vv_volume *[3]){0}));
    vt_err(vv_filter_laplacian(v, -0.5, NULL, &o));
    vt_err(vv_filter_vesselness(v, (double[]){0}, 1, 0.5, 0.5, 0, 1, NULL, &o));
    vt_err(vv_filter_threshold(v, 5, 1, NULL, &o));
    vt_err(vv_filter_window(v, 1, 1, NULL, &o));
    vt_err(vv_filter_components(v, 5, VV_U32, NULL, &o, NULL, NULL));
    vt_err(vv_filter_components(v, 6, VV_F32, NULL, &o, NULL, NULL));
    vt_err(vv_filter_largest(v, 0, 6, NULL, &o));
    vt_err(vv_filter_crop(v, (int[]){0, 0, 0}, (int[]){6, 4, 3}, NULL, &o));
    vt_err(vv_filter_crop(v, (int[]){3, 0, 0}, (int[]){2, 4, 3}, NULL, &o));
    vt_err(vv_filter_pad(v, (int[]){-1, 0, 0}, (int[]){0, 0, 0}, 0, NULL, &o));
    vt_err(vv_filter_flip(v, 3, NULL, &o));
    vt_err(vv_filter_permute(v, (int[]){0, 0, 1}, NULL, &o));
    vt_err(vv_filter_resample(v, (int[]){0, 4, 4}, VV_KERNEL_LINEAR, NULL, &o));
    vt_err(vv_filter_resample_spacing(v, (double[]){1e-9, 1, 1}, VV_KERNEL_LINEAR, NULL, &o));
    assert_null(o);
    /* the chain checks arguments before any data is read */
    vv_filter_chain *c;
    vt_ok(vv_filter_chain_new(&c));
    vt_err(vv_filter_chain_add(c, "gaussian", "0"));
    vt_err(vv_filter_chain_add(c, "gaussian", "-2"));
    vt_err(vv_filter_chain_add(c, "median", "1.5"));
    vt_err(vv_filter_chain_add(c, "threshold", "abc:"));
    vt_err(vv_filter_chain_add(c, "resample", "1x1:linear"));
    vt_err(vv_filter_chain_add(c, "resample", "1x1x1:cubicle"));
    vt_err(vv_filter_chain_add(c, "grow", "1,2:0:5"));
    vt_err(vv_filter_chain_add(c, "components", "7"));
    vt_err(vv_filter_chain_add(c, "sharpen", "1"));
    assert_non_null(strstr(vv_error_message(), "unknown filter"));
    assert_int_equal(vv_filter_chain_length(c), 0);
    vt_ok(vv_filter_chain_add(c, "gaussian", "1,2,3v"));
    vt_ok(vv_filter_chain_add(c, "threshold", ":0.5"));
    assert_string_equal(vv_filter_chain_text(c), "--gaussian 1,2,3v --threshold :0.5");
    vv_filter_chain_free(c);
    vv_volume_free(v);
}

/* A checkerboard has a component per foreground voxel when 6-connected:
 * 256 of them overflow u8 labels, fit u16. */
static void
test_label_overflow(void **state) {
    (void)state;
    vv_volume *v = vol(8, 8, 8, VV_U8, 1, 1, 1), *l = NULL;
    for (int k = 0; k < 8; k++)
        for (int j = 0; j < 8; j++)
            for (int i = 0; i < 8; i++)
                vv_volume_set(v, i, j, k, (i + j + k) & 1);
    vt_err(vv_filter_components(v, 6, VV_U8, NULL, &l, NULL, NULL));
    assert_non_null(strstr(vv_error_message(), "256 components"));
    assert_null(l);
    uint64_t n, *sizes;
    vt_ok(vv_filter_components(v, 6, VV_U16, NULL, &l, &sizes, &n));
    assert_int_equal(n, 256);
    assert_int_equal(vv_volume_get(l, 7, 7, 7), 256);
    assert_int_equal(sizes[0], 256);
    assert_int_equal(sizes[17], 1);
    free(sizes);
    vv_volume_free(l);
    /* 18-connected, the checkerboard is one component */
    vt_ok(vv_filter_components(v, 18, VV_U8, NULL, &l, NULL, &n));
    assert_int_equal(n, 1);
    vv_volume_free(l);
    vv_volume_free(v);
}

/* NaN voxels: documented results, no crash. */
static void
test_nan(void **state) {
    (void)state;
    vv_volume *v = vol(9, 8, 7, VV_F32, 1, 1, 1), *o;
    float *d = v->data;
    for (int q = 0; q < 9 * 8 * 7; q++)
        d[q] = (float)(q % 13);
    d[4 + 9 * (4 + 8 * 3)] = NAN;
    vv_volume_update_range(v);
    vt_ok(vv_filter_gaussian(v, (double[]){0.5, 0.5, 0.5}, NULL, &o)); /* radius 2 */
    assert_true(isnan(vv_volume_get(o, 4, 4, 3)));
    assert_true(isnan(vv_volume_get(o, 5, 4, 3)));
    assert_false(isnan(vv_volume_get(o, 0, 0, 0)));
    vv_volume_free(o);
    /* the median leaves NaN neighbours out */
    vt_ok(vv_filter_median(v, 1, NULL, &o));
    for (int q = 0; q < 9 * 8 * 7; q++)
        assert_false(isnan(((float *)o->data)[q]));
    vv_volume_free(o);
    vt_ok(vv_filter_threshold(v, -INFINITY, INFINITY, NULL, &o));
    assert_int_equal(vv_volume_get(o, 4, 4, 3), 0);
    assert_int_equal(vv_volume_get(o, 3, 4, 3), 1);
    vv_volume_free(o);
    vt_ok(vv_filter_cast(v, VV_I16, 0, NULL, &o));
    assert_int_equal(vv_volume_get(o, 4, 4, 3), 0);
    vv_volume_free(o);
    double t;
    vt_ok(vv_filter_otsu(v, &t));
    assert_true(isfinite(t));
    vt_ok(vv_filter_components(v, 26, VV_U32, NULL, &o, NULL, NULL));
    assert_int_equal(vv_volume_get(o, 4, 4, 3), 0);
    vv_volume_free(o);
    vv_volume_free(v);
}

/* Morphology on a known shape: a 3x3x3 cube eroded by the cross is its centre. */
static void
test_morphology_shapes(void **state) {
    (void)state;
    vv_volume *v = vol(9, 9, 9, VV_U8, 1, 1, 1), *o;
    for (int k = 3; k < 6; k++)
        for (int j = 3; j < 6; j++)
            for (int i = 3; i < 6; i++)
                vv_volume_set(v, i, j, k, 1);
    vt_ok(vv_filter_morphology(v, VV_MORPH_ERODE, 1, NULL, &o));
    assert_int_equal(o->range[1], 1);
    int n = 0;
    for (int q = 0; q < 729; q++)
        n += ((uint8_t *)o->data)[q];
    assert_int_equal(n, 1);
    assert_int_equal(vv_volume_get(o, 4, 4, 4), 1);
    vv_volume_free(o);
    vt_ok(vv_filter_morphology(v, VV_MORPH_DILATE, 1, NULL, &o));
    n = 0;
    for (int q = 0; q < 729; q++)
        n += ((uint8_t *)o->data)[q];
    assert_int_equal(n, 27 + 6 * 9);
    vv_volume_free(o);
    /* a hollow cube is filled */
    vv_volume_set(v, 4, 4, 4, 0);
    vt_ok(vv_filter_fill_holes(v, NULL, &o));
    assert_int_equal(vv_volume_get(o, 4, 4, 4), 1);
    vv_volume_free(o);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gaussian_delta),
        cmocka_unit_test(test_gradient_ramp),
        cmocka_unit_test(test_laplacian),
        cmocka_unit_test(test_otsu),
        cmocka_unit_test(test_region_grow),
        cmocka_unit_test(test_thread_counts),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_geometry),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_label_overflow),
        cmocka_unit_test(test_nan),
        cmocka_unit_test(test_morphology_shapes),
        cmocka_unit_test(test_vesselness),
    };
    return vt_run_tests(tests, NULL, NULL);
}
