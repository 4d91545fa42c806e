/*
 * The filters against an independent implementation on the same input:
 * SciPy's ndimage (Debian's python3-scipy through /usr/bin/python3, see
 * tests/filter/scipy_ref.py). Gaussian to within 1e-4 relative; median,
 * morphology, hole filling and connected-component labels exactly. Skipped
 * with a message where SciPy is missing.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "testutil.h"

#define PY "/usr/bin/python3"

static int have_scipy = -1;

static int
scipy_available(void) {
    if (have_scipy < 0) {
        int rc = system(PY " -c 'import scipy.ndimage' >/dev/null 2>&1");
        have_scipy = rc == 0;
    }
    return have_scipy;
}

static const char *
numpy_dtype(vv_voxel_type t) {
    static const char *n[] = {"uint8",  "int8",  "uint16",  "int16",
                              "uint32", "int32", "float32", "float64"};
    return n[t];
}

/* Runs scipy_ref.py OP on @p v; returns the malloc'ed raw result of @p bytes. */
static void *
scipy_ref(const char *op, const vv_volume *v, const char *params, size_t bytes) {
    const char *dir = vt_outdir("filter_scipy");
    char in[512], out[512], cmd[2048];
    snprintf(in, sizeof in, "%s/in_%s.raw", dir, op);
    snprintf(out, sizeof out, "%s/out_%s.raw", dir, op);
    vt_write_file(in, v->data, (size_t)vv_volume_voxel_count(v) * vv_voxel_type_size(v->type));
    snprintf(cmd, sizeof cmd, PY " %s/tests/filter/scipy_ref.py %s %s %d %d %d %s %s %s",
             VV_SOURCE_DIR, op, in, v->dims[0], v->dims[1], v->dims[2], numpy_dtype(v->type), out,
             params);
    int rc = system(cmd);
    if (rc != 0)
        fail_msg("%s failed (status %d)", cmd, rc);
    size_t n;
    unsigned char *r = vt_read_file(out, &n);
    assert_int_equal(n, bytes);
    return r;
}

static uint64_t rng = 88172645463325252ull;
static double
rnd(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static vv_volume *
noise(const int dims[3], vv_voxel_type t, double lo, double hi) {
    vv_volume *v;
    vt_ok(vv_volume_new(&v, dims, t));
    for (int k = 0; k < dims[2]; k++)
        for (int j = 0; j < dims[1]; j++)
            for (int i = 0; i < dims[0]; i++)
                vv_volume_set(v, i, j, k, lo + (hi - lo) * rnd());
    vv_volume_update_range(v);
    return v;
}

/* A mask of blobs: smoothed noise thresholded (so components, holes and
 * thin bridges all occur). */
static vv_volume *
blobs(const int dims[3], double frac) {
    vv_volume *n = noise(dims, VV_F32, 0, 1), *g, *m;
    double s[3] = {1.2, 1.2, 1.2};
    vt_ok(vv_filter_gaussian(n, s, NULL, &g));
    vt_ok(vv_filter_threshold(g, vv_volume_quantile(g, 1 - frac), INFINITY, NULL, &m));
    vv_volume_free(n);
    vv_volume_free(g);
    return m;
}

static void
test_gaussian(void **state) {
    (void)state;
    if (!scipy_available())
        vt_skip("SciPy (python3-scipy for " PY ") is missing: no comparison with scipy.ndimage");
    const int dims[3] = {23, 19, 17};
    vv_volume *v = noise(dims, VV_I16, -1000, 2000);
    v->spacing[0] = 0.8;
    v->spacing[1] = 1.1;
    v->spacing[2] = 2.5;
    const double sigma[3] = {1.6, 1.6, 3.0}; /* world: 2, 1.45, 1.2 voxels */
    vv_volume *g;
    vt_ok(vv_filter_gaussian(v, sigma, NULL, &g));
    char p[128];
    snprintf(p, sizeof p, "%.17g %.17g %.17g", sigma[0] / 0.8, sigma[1] / 1.1, sigma[2] / 2.5);
    size_t n = (size_t)vv_volume_voxel_count(v);
    float *ref = scipy_ref("gaussian", v, p, n * sizeof(float));
    const float *out = g->data;
    double worst = 0, scale = 3000;
    for (size_t q = 0; q < n; q++) {
        double e = fabs(out[q] - ref[q]) / fmax(fabs(ref[q]), 1e-3 * scale);
        worst = fmax(worst, e);
    }
    print_message("gaussian vs scipy: worst relative difference %.3g\n", worst);
    assert_true(worst <= 1e-4);
    free(ref);
    vv_volume_free(g);
    vv_volume_free(v);
}

static void
check_median(const int dims[3], vv_voxel_type t, int r) {
    vv_volume *v = noise(dims, t, t == VV_U8 ? 0 : -3000, t == VV_U8 ? 255 : 3000), *m;
    vt_ok(vv_filter_median(v, r, NULL, &m));
    char p[16];
    snprintf(p, sizeof p, "%d", r);
    size_t bytes = (size_t)vv_volume_voxel_count(v) * vv_voxel_type_size(t);
    void *ref = scipy_ref("median", v, p, bytes);
    assert_memory_equal(m->data, ref, bytes);
    free(ref);
    vv_volume_free(m);
    vv_volume_free(v);
}

static void
test_median(void **state) {
    (void)state;
    if (!scipy_available())
        vt_skip("SciPy (python3-scipy for " PY ") is missing: no comparison with scipy.ndimage");
    check_median((int[]){21, 17, 13}, VV_U8, 1);
    check_median((int[]){21, 17, 13}, VV_I16, 1);
    check_median((int[]){15, 12, 11}, VV_F32, 2);
    check_median((int[]){9, 8, 7}, VV_I32, 1);
    /* a radius larger than the volume: mirror-extended, as documented */
    check_median((int[]){3, 4, 2}, VV_U16, 5);
}

static void
test_morphology(void **state) {
    (void)state;
    if (!scipy_available())
        vt_skip("SciPy (python3-scipy for " PY ") is missing: no comparison with scipy.ndimage");
    const int dims[3] = {26, 22, 19};
    vv_volume *m = blobs(dims, 0.45);
    size_t n = (size_t)vv_volume_voxel_count(m);
    static const char *names[] = {"erode", "dilate", "open", "close"};
    for (int r = 1; r <= 2; r++)
        for (int op = 0; op < 4; op++) {
            vv_volume *o;
            vt_ok(vv_filter_morphology(m, (vv_morphology)op, r, NULL, &o));
            char p[16];
            snprintf(p, sizeof p, "%d", r);
            void *ref = scipy_ref(names[op], m, p, n);
            assert_memory_equal(o->data, ref, n);
            free(ref);
            vv_volume_free(o);
        }
    vv_volume_free(m);
    /* mostly foreground, so that background pockets are enclosed */
    m = blobs(dims, 0.8);
    vv_volume *f;
    vt_ok(vv_filter_fill_holes(m, NULL, &f));
    void *ref = scipy_ref("fill", m, "", n);
    assert_memory_equal(f->data, ref, n);
    /* the blobs do have holes, so the test can fail */
    assert_memory_not_equal(f->data, m->data, n);
    free(ref);
    vv_volume_free(f);
    vv_volume_free(m);
}

static void
test_labels(void **state) {
    (void)state;
    if (!scipy_available())
        vt_skip("SciPy (python3-scipy for " PY ") is missing: no comparison with scipy.ndimage");
    const int dims[3] = {40, 33, 29};
    vv_volume *m = blobs(dims, 0.3);
    size_t n = (size_t)vv_volume_voxel_count(m);
    static const int conns[3] = {6, 18, 26};
    for (int c = 0; c < 3; c++) {
        vv_volume *l;
        uint64_t *sizes, count;
        vv_filter_options o;
        vv_filter_options_init(&o);
        o.threads = 3;
        vt_ok(vv_filter_components(m, conns[c], VV_U32, &o, &l, &sizes, &count));
        char p[16];
        snprintf(p, sizeof p, "%d", conns[c]);
        uint32_t *ref = scipy_ref("label", m, p, n * 4);
        assert_memory_equal(l->data, ref, n * 4);
        uint64_t total = 0;
        for (uint64_t q = 0; q <= count; q++)
            total += sizes[q];
        assert_int_equal(total, n);
        uint64_t c1 = 0;
        for (size_t q = 0; q < n; q++)
            c1 += ref[q] == 1;
        assert_int_equal(c1, sizes[1]);
        print_message("%d-connected: %llu components, as scipy\n", conns[c],
                      (unsigned long long)count);
        assert_true(count > 3);
        free(ref);
        free(sizes);
        vv_volume_free(l);
    }
    vv_volume_free(m);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gaussian),
        cmocka_unit_test(test_median),
        cmocka_unit_test(test_morphology),
        cmocka_unit_test(test_labels),
    };
    return vt_run_tests(tests, NULL, NULL);
}
