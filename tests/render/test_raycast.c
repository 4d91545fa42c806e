/*
 * Tests of the direct volume ray caster (src/render/raycast/raycast.c).
 *
 * The checks are analytic where possible: the transmittance of a constant
 * slab, projections of axis-aligned views against voxel columns, the
 * silhouette area and depth of a sampled sphere, and how object transforms
 * and cut planes move or cut that silhouette. Then agreement checks (step
 * halving, on-the-fly gradients, skipping on/off, thread counts), progress
 * and cancellation, bad input, and every shared real volume.
 *
 * Geometry used throughout: an orthographic view looking down -z from an
 * eye at z = E, right = +x, up = +y, so pixel (px, py) of a W x H view of
 * height h centred on (cx, cy) has its ray through
 *   x = cx + (px + 0.5 - W/2) * h/H,  y = cy - (py + 0.5 - H/2) * h/H,
 * and samples lie at z = E - k * dt.
 */
#include "testutil.h"

#include "render/frame.h"
#include "render/kernels_avx2.h"
#include "render/project.h"
#include "render/shade.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------- */
/* Helpers                                                                  */

static vv_volume *
new_volume(int nx, int ny, int nz, vv_voxel_type t, double sx, double sy, double sz) {
    vv_volume *v = NULL;
    const int dims[3] = {nx, ny, nz};
    vt_ok(vv_volume_new(&v, dims, t));
    v->spacing[0] = sx;
    v->spacing[1] = sy;
    v->spacing[2] = sz;
    return v;
}

static vv_volume *
constant_volume(int nx, int ny, int nz, vv_voxel_type t, double sx, double sy, double sz,
                double value) {
    vv_volume *v = new_volume(nx, ny, nz, t, sx, sy, sz);
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++)
                vv_volume_set(v, i, j, k, value);
    vv_volume_update_range(v);
    return v;
}

/* value = r - distance from the grid centre (f32, spacing 1): the isosurface
 * 0 is a sphere of radius r around ((n-1)/2, (n-1)/2, (n-1)/2). */
static vv_volume *
sphere_volume(int n, double r) {
    vv_volume *v = new_volume(n, n, n, VV_F32, 1, 1, 1);
    const double c = 0.5 * (n - 1);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                vv_volume_set(v, i, j, k,
                              r - sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c)));
    vv_volume_update_range(v);
    return v;
}

/* xorshift64*: deterministic pseudo-random numbers in [0, 1). */
static double
rnd(uint64_t *s) {
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static vv_world *
new_world(void) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    w->background = vv_vec3_make(0, 0, 0);
    return w;
}

/* Adds a volume object (the World owns it) and returns it. */
static vv_object *
add_object(vv_world *w, vv_volume *v, vv_render_mode mode) {
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, NULL));
    o->mode = mode;
    o->shading = 0;
    vt_ok(vv_world_add_object(w, o));
    return o;
}

/* Orthographic view looking down -z (right +x, up +y) from z = eye_z. */
static vv_view
ortho_z(double cx, double cy, double eye_z, double height, int width_px, int height_px) {
    vv_view v;
    memset(&v, 0, sizeof v);
    v.eye = vv_vec3_make(cx, cy, eye_z);
    v.at = vv_vec3_make(cx, cy, eye_z - 1);
    v.up = vv_vec3_make(0, 1, 0);
    v.fov = vv_deg_to_rad(30);
    v.ortho_height = height;
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    v.width = width_px;
    v.height = height_px;
    return v;
}

static vv_renderer *
new_raycaster(void) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    return r;
}

static vv_image *
render_t(vv_renderer *r, const vv_world *w, const vv_view *view, int threads) {
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, view->width, view->height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    vt_ok(vv_renderer_render(r, w, view, &opt, img));
    return img;
}

static vv_image *
render(vv_renderer *r, const vv_world *w, const vv_view *view) {
    return render_t(r, w, view, 0);
}

static const float *
px(const vv_image *img, int x, int y) {
    return img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
}

/* Pixels with alpha > 0.5 (hit), their count and centroid (pixel units). */
typedef struct hits {
    long n;
    double cx, cy;
    int x0, x1, y0, y1; /* bounding box, inclusive */
} hits;

static hits
count_hits(const vv_image *img, int xa, int xb) {
    hits h = {0, 0, 0, img->width, -1, img->height, -1};
    for (int y = 0; y < img->height; y++)
        for (int x = xa; x < xb; x++)
            if (px(img, x, y)[3] > 0.5f) {
                h.n++;
                h.cx += x;
                h.cy += y;
                h.x0 = x < h.x0 ? x : h.x0;
                h.x1 = x > h.x1 ? x : h.x1;
                h.y0 = y < h.y0 ? y : h.y0;
                h.y1 = y > h.y1 ? y : h.y1;
            }
    if (h.n) {
        h.cx /= (double)h.n;
        h.cy /= (double)h.n;
    }
    return h;
}

static int
images_identical(const vv_image *a, const vv_image *b) {
    size_t n = (size_t)a->width * (size_t)a->height;
    if (a->width != b->width || a->height != b->height)
        return 0;
    return memcmp(a->rgba, b->rgba, 4 * n * sizeof(float)) == 0 &&
           memcmp(a->depth, b->depth, n * sizeof(float)) == 0;
}

static double
max_abs_diff(const vv_image *a, const vv_image *b) {
    return vt_image_diff(a, b, NULL);
}

static void
write_png(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.png", vt_outdir("render"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* The default scene of the shared volume volumes/@p file (vt_volume_scene). */
static vv_world *
real_scene(const char *file, int size, vv_volume **vol) {
    char rel[256];
    snprintf(rel, sizeof rel, "volumes/%s", file);
    return vt_volume_scene(rel, size, vol);
}

/* ---------------------------------------------------------------------- */
/* Analytic: transmittance of a constant slab                               */

/* One slab: nx x ny x nz voxels of constant value, spacing s, TF opacity a
 * per unit distance u, white, unshaded, seen straight down z. The eye sits
 * half a step off the sample grid relative to both faces, so that exactly
 * L / dt samples fall inside the slab (the midpoint rule): then 1 - alpha
 * must equal (1 - a)^(L / u) = exp(-tau L), tau = -ln(1 - a) / u. */
static double
slab_error(vv_voxel_type type, double value, const double s[3], int nz, double step, double a,
           double u) {
    vv_volume *v = constant_volume(6, 6, nz, type, s[0], s[1], s[2], value);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_COMPOSITE);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, value, a));
    o->tf.opacity_unit_distance = u;
    o->step = step;
    double smin = s[0] < s[1] ? s[0] : s[1];
    smin = s[2] < smin ? s[2] : smin;
    const double dt = step * smin;
    const double L = (nz - 1) * s[2];
    /* L must be a whole number of steps for the midpoint placement */
    assert_true(fabs(L / dt - floor(L / dt + 0.5)) < 1e-9);
    const double eye_z = L + (floor(50.0 / dt) + 0.5) * dt;
    vv_view view = ortho_z(2.5 * s[0], 2.5 * s[1], eye_z, 2.0 * s[1], 4, 4);
    vv_renderer *r = new_raycaster();
    vt_ok(vv_renderer_set_option(r, "early_termination", "1"));
    vv_image *img = render(r, w, &view);
    const double expect = exp(log(1.0 - a) / u * L); /* exp(-tau L) */
    double worst = 0;
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            const float *p = px(img, x, y);
            double trans = 1.0 - p[3];
            double err = fabs(trans / expect - 1.0);
            worst = err > worst ? err : worst;
            /* white emission over black: colour equals coverage */
            assert_float_equal(p[0], p[3], 1e-5);
            assert_float_equal(p[2], p[3], 1e-5);
            /* depth: the first sample, half a step inside the front face */
            assert_float_equal(img->depth[y * 4 + x], eye_z - L + 0.5 * dt, 1e-3);
        }
    print_message("slab type %s L=%.2f dt=%.3f a=%.2f u=%.2f: exp(-tau L)=%.5f, rel err %.2e\n",
                  vv_voxel_type_name(type), L, dt, a, u, expect, worst);
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
    return worst;
}

static void
test_slab_transmittance(void **state) {
    (void)state;
    const double iso[3] = {1, 1, 1};
    const double aniso[3] = {2.0, 3.0, 0.7};
    const double aniso2[3] = {0.5, 0.8, 2.5};
    assert_true(slab_error(VV_F32, 3.0, iso, 5, 0.5, 0.5, 1.0) < 0.01);
    assert_true(slab_error(VV_U8, 100, iso, 21, 0.5, 0.2, 2.5) < 0.01);
    assert_true(slab_error(VV_I16, -7, iso, 5, 0.25, 0.9, 2.0) < 0.01);
    assert_true(slab_error(VV_F32, 1.0, iso, 31, 1.0, 0.05, 0.3) < 0.01);
    /* anisotropic: dt follows the smallest spacing */
    assert_true(slab_error(VV_F32, 2.0, aniso, 9, 0.5, 0.4, 1.0) < 0.01);
    assert_true(slab_error(VV_U16, 500, aniso2, 7, 0.5, 0.3, 4.0) < 0.01);
}

/* With both faces on the sample grid, L / dt + 1 samples fall inside: the
 * documented sampling (t = k dt, faces included) gives (1 - a)^((L + dt)/u). */
static void
test_slab_sample_count(void **state) {
    (void)state;
    vv_volume *v = constant_volume(4, 4, 9, VV_F32, 1, 1, 1, 5.0);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_COMPOSITE);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, 5.0, 0.3));
    o->tf.opacity_unit_distance = 1.0;
    o->step = 0.5;
    vv_view view = ortho_z(1.5, 1.5, 8.0 + 40.0, 2.0, 2, 2);
    vv_renderer *r = new_raycaster();
    vt_ok(vv_renderer_set_option(r, "early_termination", "1"));
    vv_image *img = render(r, w, &view);
    double expect = 1.0 - pow(0.7, (8.0 + 0.5) / 1.0);
    assert_float_equal(px(img, 0, 0)[3], expect, 1e-4);
    assert_float_equal(img->depth[0], 40.0, 1e-4);
    vv_image_free(img);
    /* the work counted (vv_render_options.stats): 17 samples on each of
     * the 4 rays, all shaded; added to what the counts held, from any
     * thread count; a transparent object takes none (skipped) */
    for (int threads = 1; threads <= 2; threads++) {
        vv_render_stats st = {.samples = 1, .shaded = 1};
        vv_render_options opt;
        vv_render_options_init(&opt);
        opt.threads = threads;
        opt.stats = &st;
        vt_ok(vv_image_new(&img, view.width, view.height));
        vt_ok(vv_renderer_render(r, w, &view, &opt, img));
        assert_int_equal(st.samples, 1 + 4 * 17);
        assert_int_equal(st.shaded, 1 + 4 * 17);
        o->tf.opacity[0].opacity = 0;
        st.samples = st.shaded = 0;
        vt_ok(vv_renderer_render(r, w, &view, &opt, img));
        assert_int_equal(st.samples, 0);
        assert_int_equal(st.shaded, 0);
        o->tf.opacity[0].opacity = 0.3;
        vv_image_free(img);
    }
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* Early termination at the default 0.99 stops a thick opaque slab's ray,
 * which is visible as coverage just above 0.99 instead of 1 - 0.5^20. */
static void
test_early_termination(void **state) {
    (void)state;
    vv_volume *v = constant_volume(4, 4, 21, VV_F32, 1, 1, 1, 1.0);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_COMPOSITE);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, 1.0, 0.5));
    o->step = 0.5;
    vv_view view = ortho_z(1.5, 1.5, 20.0 + 30.25, 2.0, 2, 2);
    vv_renderer *r = new_raycaster();
    vv_image *img = render(r, w, &view);
    float a = px(img, 0, 0)[3];
    assert_true(a >= 0.99f && a < 0.995f);
    vt_ok(vv_renderer_set_option(r, "early_termination", "1.0"));
    vv_image *img2 = render(r, w, &view);
    assert_float_equal(px(img2, 0, 0)[3], 1.0 - pow(0.5, 20.0), 1e-5);
    vv_image_free(img);
    vv_image_free(img2);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Projections against voxel columns                                        */

/* A seeded random n x n x d volume rendered with @p mode through a view whose
 * pixel centres sit exactly on the voxel columns (power-of-two n keeps the
 * arithmetic exact); every pixel must show the column's reduction (max, min
 * or mean) through a grey ramp from range[0] (black) to range[1] (white),
 * opacity 1, within one step of the 4096-entry table. */
static vv_image *
check_projection_ramp(vv_render_mode mode, vv_voxel_type type, int skipping, double step, double r0,
                      double r1) {
    const int n = 32, d = 24;
    vv_volume *v = new_volume(n, n, d, type, 1, 1, 1);
    uint64_t seed = 0x9e3779b97f4a7c15ULL + (uint64_t)mode;
    for (int k = 0; k < d; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double x = rnd(&seed);
                /* some structure so that whole subvolumes can be skipped */
                if (k > 8 && k < 16 && i > 16)
                    x = x * 0.3;
                vv_volume_set(v, i, j, k, type == VV_F32 ? 1000.0 * x - 200.0 : floor(4000 * x));
            }
    vv_volume_update_range(v);
    const double lo = v->range[0], hi = v->range[1];
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, mode);
    o->step = step;
    /* the grey ramp over [a, b], flat outside it when r0 > 0 or r1 < 1 */
    const double a = lo + r0 * (hi - lo), b = lo + r1 * (hi - lo);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, lo, 1.0));
    vt_ok(vv_tf_add_color(&o->tf, a, vv_vec3_make(0, 0, 0)));
    vt_ok(vv_tf_add_color(&o->tf, b, vv_vec3_make(1, 1, 1)));
    vv_view view = ortho_z(0.5 * (n - 1), 0.5 * (n - 1), 64.0, n, n, n);
    vv_renderer *r = new_raycaster();
    vt_ok(vv_renderer_set_option(r, "empty_space_skipping", skipping ? "1" : "0"));
    vv_image *img = render(r, w, &view);
    double worst = 0;
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++) {
            const int j = n - 1 - y; /* row 0 is the top, +y */
            double acc = mode == VV_MODE_MIP ? -INFINITY : mode == VV_MODE_MINIP ? INFINITY : 0;
            for (int k = 0; k < d; k++) {
                double val = vv_volume_get(v, x, j, k);
                if (mode == VV_MODE_MIP)
                    acc = val > acc ? val : acc;
                else if (mode == VV_MODE_MINIP)
                    acc = val < acc ? val : acc;
                else
                    acc += val / d;
            }
            double grey = (acc - a) / (b - a);
            grey = grey < 0 ? 0 : grey > 1 ? 1 : grey;
            const float *p = px(img, x, y);
            /* the table index is floor((v - lo) * 4095 / (hi - lo)) */
            double err = grey - p[0];
            const double tol = (hi - lo) / (b - a) / 4095;
            if (!(err > -1e-5 && err < tol + 1e-5))
                fail_msg("mode %d skipping %d pixel (%d, %d): expected %.6f (value %.3f), got "
                         "%.6f",
                         (int)mode, skipping, x, y, grey, acc, (double)p[0]);
            assert_float_equal(p[1], p[0], 0);
            assert_float_equal(p[3], 1.0, 0);
            worst = fabs(err) > worst ? fabs(err) : worst;
        }
    print_message("projection mode %d type %s skipping %d step %.2f ramp [%.1f, %.1f]: worst "
                  "grey error %.2e\n",
                  (int)mode, vv_voxel_type_name(type), skipping, step, r0, r1, worst);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
    return img;
}

static vv_image *
check_projection(vv_render_mode mode, vv_voxel_type type, int skipping, double step) {
    return check_projection_ramp(mode, type, skipping, step, 0, 1);
}

/* Renders with skipping on and off; both must be right and identical. */
static void
check_projection_both(vv_render_mode mode, vv_voxel_type type, double step) {
    vv_image *on = check_projection(mode, type, 1, step);
    vv_image *off = check_projection(mode, type, 0, step);
    if (!images_identical(on, off))
        fail_msg("mode %d: skipping on/off differ by up to %.3g", (int)mode, max_abs_diff(on, off));
    vv_image_free(on);
    vv_image_free(off);
}

/* Transfer functions flat below and above a ramp (MIP: 30 % to 97 % of the
 * range, where the column maxima of the random volume lie; MinIP: 3 % to
 * 70 %): MIP and MinIP start at one flat end and stop at the other
 * (vv_vray_project's bounds); the colours must still be those of the true
 * extremes. */
static void
test_projection_flat_ends(void **state) {
    (void)state;
    const vv_render_mode modes[2] = {VV_MODE_MIP, VV_MODE_MINIP};
    const vv_voxel_type types[2] = {VV_F32, VV_U16};
    for (int m = 0; m < 2; m++)
        for (int t = 0; t < 2; t++) {
            const double r0 = m == 0 ? 0.3 : 0.03, r1 = m == 0 ? 0.97 : 0.7;
            vv_image *on = check_projection_ramp(modes[m], types[t], 1, 0.5, r0, r1);
            vv_image *off = check_projection_ramp(modes[m], types[t], 0, 0.5, r0, r1);
            if (!images_identical(on, off))
                fail_msg("mode %d: skipping on/off differ", (int)modes[m]);
            vv_image_free(on);
            vv_image_free(off);
        }
}

/* ---------------------------------------------------------------------- */
/* Attenuated MIP (napari's)                                                */

/* A bright voxel (1.0, at z = 5) behind a dimmer slab (0.6, z = 14..21) in
 * every column of a 16 x 16 x 24 volume, seen down -z: every pixel shows
 * napari's value through a grey ramp over the contrast limits [0.1, 1]
 * (the transfer function's first and last opacity points). A small
 * attenuation lets the bright voxel win, napari's default and a large one
 * hide it behind the slab. */
static void
test_attenuated_mip_analytic(void **state) {
    (void)state;
    const int n = 16, d = 24;
    double col[24];
    for (int k = 0; k < d; k++)
        col[k] = k == 5 ? 1.0 : k >= 14 && k <= 21 ? 0.6 : 0.0;
    vv_volume *v = new_volume(n, n, d, VV_F32, 1, 1, 1);
    for (int k = 0; k < d; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                vv_volume_set(v, i, j, k, col[k]);
    vv_volume_update_range(v);
    const double lo = 0.1, hi = 1.0, step = 0.5;
    /* the samples along a column: z = d - 1 down to 0 by half a voxel
     * (t = k dt from the eye at z = 64), linear between the voxels */
    double samples[2 * 24];
    int ns = 0;
    for (int h = 2 * (d - 1); h >= 0; h--)
        samples[ns++] = h % 2 ? 0.5 * (col[h / 2] + col[h / 2 + 1]) : col[h / 2];
    const double atts[3] = {0.01, 0.05, 0.5};
    vv_renderer *r = new_raycaster();
    vv_view view = ortho_z(0.5 * (n - 1), 0.5 * (n - 1), 64.0, n, n, n);
    for (int a = 0; a < 3; a++) {
        vv_world *w = new_world();
        vv_object *o = add_object(w, v, VV_MODE_ATTENUATED_MIP);
        o->step = step;
        o->attenuation = atts[a];
        vt_tf_grey(&o->tf, lo, hi);
        int at = -1;
        const double want = vt_napari_attenuated_mip(samples, ns, lo, hi, atts[a], step, &at);
        double grey = (want - lo) / (hi - lo);
        grey = grey < 0 ? 0 : grey > 1 ? 1 : grey;
        /* the bright voxel's sample is number 2 (d - 1 - 5) */
        const int bright = at == 2 * (d - 1 - 5);
        if (a == 0)
            assert_true(bright);
        else
            assert_false(bright);
        vv_image *img = render(r, w, &view);
        const double tol = 1.0 / (hi - lo) / 4095 + 1e-5; /* one entry of the 4096 table */
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                const float *p = px(img, x, y);
                if (!(fabs(p[0] - grey) <= tol))
                    fail_msg("attenuation %.2f pixel (%d, %d): napari's value %.6f (grey %.6f, "
                             "sample %d), got grey %.6f",
                             atts[a], x, y, want, grey, at, (double)p[0]);
                assert_float_equal(p[3], 1.0, 0);
            }
        print_message("attenuated MIP, attenuation %.2f: napari's value %.5f at sample %d (%s), "
                      "pixel grey %.5f\n",
                      atts[a], want, at, bright ? "the bright voxel" : "the slab",
                      (double)px(img, 3, 3)[0]);
        vv_image_free(img);
        vv_world_free(w);
    }
    vv_renderer_free(r);
    vv_volume_free(v);
}

/* Attenuation 0 scales every sample by exactly 1: the image of MIP bit for
 * bit (colours; MIP's depth may name an earlier sample of the same colour),
 * for 16-bit and float volumes and a ramp with flat ends (MIP then starts
 * at one end and stops at the other). */
static void
test_attenuated_mip_zero_is_mip(void **state) {
    (void)state;
    const vv_voxel_type types[2] = {VV_U16, VV_F32};
    for (int t = 0; t < 2; t++) {
        const int n = 32, d = 24;
        vv_volume *v = new_volume(n, n, d, types[t], 1, 1, 1);
        uint64_t seed = 0x243f6a8885a308d3ULL + (uint64_t)t;
        for (int k = 0; k < d; k++)
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    double x = rnd(&seed);
                    if (k > 8 && k < 16 && i > 16)
                        x *= 0.3;
                    vv_volume_set(v, i, j, k,
                                  types[t] == VV_F32 ? 1000 * x - 200 : floor(4000 * x));
                }
        vv_volume_update_range(v);
        const double lo = v->range[0], hi = v->range[1];
        vv_image *img[2];
        for (int m = 0; m < 2; m++) {
            vv_world *w = new_world();
            vv_object *o = add_object(w, v, m ? VV_MODE_ATTENUATED_MIP : VV_MODE_MIP);
            o->attenuation = 0;
            vt_tf_flat_ends(&o->tf, lo, hi);
            /* a turned view: rays not along the grid */
            vv_view view = ortho_z(0.5 * (n - 1), 0.5 * (n - 1), 64.0, 1.5 * n, 48, 40);
            view.at = vv_vec3_make(0.5 * (n - 1), 0.5 * (n - 1), 0.5 * (d - 1));
            view.eye = vv_vec3_make(0.5 * (n - 1) + 30, 0.5 * (n - 1) + 17, 60);
            vv_renderer *r = new_raycaster();
            img[m] = render(r, w, &view);
            vv_renderer_free(r);
            vv_world_free(w);
        }
        const size_t np = (size_t)img[0]->width * (size_t)img[0]->height;
        if (memcmp(img[0]->rgba, img[1]->rgba, 4 * np * sizeof(float)) != 0)
            fail_msg("%s: attenuation 0 differs from MIP by up to %.3g",
                     vv_voxel_type_name(types[t]), max_abs_diff(img[0], img[1]));
        double lit = 0;
        for (size_t i = 0; i < np; i++)
            lit += img[0]->rgba[4 * i + 3] > 0;
        assert_true(lit > 0.2 * (double)np); /* not an empty image */
        vv_image_free(img[0]);
        vv_image_free(img[1]);
        vv_volume_free(v);
    }
}

/* Renderers that do not draw attenuated MIP refuse it in one line, naming
 * the one that does; a region render (out of core, MPI) takes it, combined
 * by VV_REGION_ATTENUATED_MAX (test_attenuated_regions). */
static void
test_attenuated_mip_refused(void **state) {
    (void)state;
    vv_volume *v = constant_volume(8, 8, 8, VV_U8, 1, 1, 1, 100);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_ATTENUATED_MIP);
    vv_volume_free(v);
    (void)o;
    vv_view view = ortho_z(3.5, 3.5, 64, 10, 8, 8);
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "splat"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 8, 8));
    assert_int_equal(vv_renderer_render(r, w, &view, NULL, img), VV_ERR_UNSUPPORTED);
    const char *msg = vv_error_message();
    assert_non_null(strstr(msg, "attenuated-mip mode is not drawn by splat (drawn by raycast"));
    assert_null(strchr(msg, '\n'));
    vv_renderer_free(r);
    vv_region_op op;
    vv_render_region rg;
    memset(&rg, 0, sizeof rg);
    vt_ok(vv_render_region_check(w, &rg, &op));
    assert_int_equal(op, VV_REGION_ATTENUATED_MAX);
    vv_image_free(img);
    vv_world_free(w);
}

static void
test_mip_columns(void **state) {
    (void)state;
    check_projection_both(VV_MODE_MIP, VV_F32, 0.5);
    check_projection_both(VV_MODE_MIP, VV_U16, 0.5);
}

static void
test_minip_columns(void **state) {
    (void)state;
    check_projection_both(VV_MODE_MINIP, VV_F32, 0.5);
    check_projection_both(VV_MODE_MINIP, VV_U16, 0.5);
}

/* X-ray is the mean of the samples; with step 1 they are the voxels. */
static void
test_xray_columns(void **state) {
    (void)state;
    check_projection_both(VV_MODE_XRAY, VV_F32, 1.0);
    check_projection_both(VV_MODE_XRAY, VV_U16, 1.0);
}

/* ---------------------------------------------------------------------- */
/* Isosurface of a sampled sphere                                           */

static void
test_iso_sphere_silhouette(void **state) {
    (void)state;
    const int n = 64;
    const double R = 24, c = 31.5;
    vv_volume *v = sphere_volume(n, R);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_ISO);
    o->isovalue = 0;
    /* pixel size 0.5 */
    vv_view view = ortho_z(c, c, 200, 64, 128, 128);
    vv_renderer *r = new_raycaster();
    vv_image *img = render(r, w, &view);
    write_png(img, "iso_sphere_ortho");
    hits h = count_hits(img, 0, 128);
    double area = h.n * 0.25, expect = VV_PI * R * R;
    double err = area / expect - 1;
    print_message("iso sphere R=%g: silhouette area %.2f, pi R^2 %.2f, rel err %.2e\n", R, area,
                  expect, err);
    assert_true(fabs(err) < 0.01);
    /* centred: centroid on the middle of the image */
    assert_float_equal(h.cx, 63.5, 0.05);
    assert_float_equal(h.cy, 63.5, 0.05);
    /* depth of the centre pixels: eye distance to the front of the sphere */
    assert_float_equal(img->depth[64 * 128 + 64], 200 - (c + R), 0.05);
    vv_image_free(img);

    /* perspective: odd size puts the centre pixel's ray on the axis */
    vv_view pv;
    memset(&pv, 0, sizeof pv);
    pv.eye = vv_vec3_make(c, c, c + 100);
    pv.at = vv_vec3_make(c, c, c);
    pv.up = vv_vec3_make(0, 1, 0);
    pv.fov = vv_deg_to_rad(30);
    pv.projection = VV_PROJECTION_PERSPECTIVE;
    pv.width = pv.height = 65;
    img = render(r, w, &pv);
    double dep = img->depth[32 * 65 + 32];
    print_message("iso sphere perspective: centre depth %.4f, expected %.4f\n", dep, 100 - R);
    assert_float_equal(dep, 100 - R, 0.05);
    /* silhouette of a sphere seen in perspective: a disc of angular radius
     * asin(R / D); in image-plane units tan(asin(R/D)) / tan(fov/2) * 32.5 px */
    hits hp = count_hits(img, 0, 65);
    double rp = tan(asin(R / 100.0)) / tan(pv.fov / 2) * 32.5;
    double perr = hp.n / (VV_PI * rp * rp) - 1;
    print_message("iso sphere perspective: %ld pixels, expected %.1f, rel err %.2e\n", hp.n,
                  VV_PI * rp * rp, perr);
    assert_true(fabs(perr) < 0.02);
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Several objects; object transforms                                       */

/* Renders the World with only object @p only visible (-1: all). */
static vv_image *
render_only(vv_renderer *r, vv_world *w, const vv_view *view, int only) {
    for (int i = 0; i < w->n_objects; i++)
        w->objects[i]->visible = only < 0 || i == only;
    vv_image *img = render(r, w, view);
    for (int i = 0; i < w->n_objects; i++)
        w->objects[i]->visible = 1;
    return img;
}

static void
test_two_slabs_order(void **state) {
    (void)state;
    vv_volume *v = constant_volume(8, 8, 5, VV_U8, 1, 1, 1, 10);
    vv_world *w = new_world();
    vv_object *red = add_object(w, v, VV_MODE_COMPOSITE);
    vv_object *green = add_object(w, v, VV_MODE_COMPOSITE);
    const vv_vec3 colors[2] = {vv_vec3_make(1, 0, 0), vv_vec3_make(0, 1, 0)};
    vv_object *objs[2] = {red, green};
    for (int i = 0; i < 2; i++) {
        vv_tf_init(&objs[i]->tf);
        vt_ok(vv_tf_add_opacity(&objs[i]->tf, 10, 0.3));
        vt_ok(vv_tf_add_color(&objs[i]->tf, 10, colors[i]));
    }
    vv_view view = ortho_z(3.5, 3.5, 100.25, 4, 8, 8);
    vv_renderer *r = new_raycaster();
    for (int swap = 0; swap < 2; swap++) {
        vv_object *front = swap ? green : red, *back = swap ? red : green;
        front->position = vv_vec3_make(0, 0, 20);
        back->position = vv_vec3_make(0, 0, 0);
        vv_image *both = render_only(r, w, &view, -1);
        vv_image *a0 = render_only(r, w, &view, swap ? 1 : 0);
        vv_image *a1 = render_only(r, w, &view, swap ? 0 : 1);
        for (int y = 0; y < 8; y++)
            for (int x = 0; x < 8; x++) {
                const float *p = px(both, x, y), *f = px(a0, x, y), *b = px(a1, x, y);
                /* the one-object renders (single-volume kernel) composited front to
                 * back must give the two-object render (general kernel) */
                for (int ch = 0; ch < 4; ch++)
                    assert_float_equal(p[ch], f[ch] + (1 - f[3]) * b[ch], 1e-4);
                const int fc = swap ? 1 : 0, bc = swap ? 0 : 1;
                /* front alpha 1 - 0.7^4 = 0.76; the back shows through 0.24 of it */
                assert_true(p[fc] > 0.7f && p[bc] < 0.25f && p[bc] > 0.1f && p[fc] > 3 * p[bc]);
                assert_float_equal(both->depth[y * 8 + x], 100.25 - 24 + 0.25, 1e-3);
            }
        if (swap == 0)
            print_message("two slabs: front red (%.4f, %.4f, %.4f, %.4f)\n", px(both, 3, 3)[0],
                          px(both, 3, 3)[1], px(both, 3, 3)[2], px(both, 3, 3)[3]);
        vv_image_free(both);
        vv_image_free(a0);
        vv_image_free(a1);
    }
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_object_translate_scale(void **state) {
    (void)state;
    const double R = 10;
    vv_volume *v = sphere_volume(32, R);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_ISO);
    o->isovalue = 0;
    /* pixel size 0.5, view centre (20, 20) */
    vv_view view = ortho_z(20, 20, 200, 64, 128, 128);
    vv_renderer *r = new_raycaster();
    vv_image *img0 = render(r, w, &view);
    hits h0 = count_hits(img0, 0, 128);
    /* sphere centre (15.5, 15.5) -> pixel centre x = 64 + (15.5 - 20) / 0.5 - 0.5 */
    assert_float_equal(h0.cx, 54.5, 0.05);
    assert_float_equal(h0.cy, 72.5, 0.05);

    o->position = vv_vec3_make(6, -3, 0);
    vv_image *img1 = render(r, w, &view);
    hits h1 = count_hits(img1, 0, 128);
    print_message("translate (6, -3): centroid moved by (%.3f, %.3f) px, expected (12, 6)\n",
                  h1.cx - h0.cx, h1.cy - h0.cy);
    assert_int_equal(h1.n, h0.n);
    assert_float_equal(h1.cx - h0.cx, 12, 0.01);
    assert_float_equal(h1.cy - h0.cy, 6, 0.01);

    o->position = vv_vec3_make(0, 0, 0);
    o->scale = vv_vec3_make(1.5, 1.5, 1.5);
    vv_image *img2 = render(r, w, &view);
    hits h2 = count_hits(img2, 0, 128);
    double ratio = (double)h2.n / (double)h0.n;
    print_message("scale 1.5: area ratio %.4f (expected 2.25)\n", ratio);
    assert_float_equal(ratio, 2.25, 0.02);
    /* the centre scales about the object origin: 15.5 * 1.5 = 23.25 */
    assert_float_equal(h2.cx, 64 + (23.25 - 20) / 0.5 - 0.5, 0.05);
    assert_float_equal(h2.cy, 64 - (23.25 - 20) / 0.5 - 0.5, 0.05);
    vv_image_free(img0);
    vv_image_free(img1);
    vv_image_free(img2);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* A 20 x 6 x 5 box (voxels of 1 inside a border of 0, isovalue 0.5) turned
 * +90 degrees about z (x -> y): its silhouette turns from wide to tall and
 * its centre goes from (10.5, 3.5) to (-3.5, 10.5). */
static void
test_object_orientation(void **state) {
    (void)state;
    vv_volume *v = new_volume(22, 8, 7, VV_U8, 1, 1, 1);
    for (int k = 1; k <= 5; k++)
        for (int j = 1; j <= 6; j++)
            for (int i = 1; i <= 20; i++)
                vv_volume_set(v, i, j, k, 1);
    vv_volume_update_range(v);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_ISO);
    o->isovalue = 0.5;
    const double cx = 5, cy = 8, ps = 0.5;
    vv_view view = ortho_z(cx, cy, 100, 64, 128, 128);
    vv_renderer *r = new_raycaster();
    for (int rot = 0; rot < 2; rot++) {
        o->orientation =
            rot ? vv_quat_from_axis_angle(vv_vec3_make(0, 0, 1), 0.5 * VV_PI) : vv_quat_identity();
        vv_image *img = render(r, w, &view);
        hits h = count_hits(img, 0, 128);
        double wx = (h.x1 - h.x0 + 1) * ps, wy = (h.y1 - h.y0 + 1) * ps;
        double mx = cx + (h.cx + 0.5 - 64) * ps, my = cy - (h.cy + 0.5 - 64) * ps;
        print_message("box rot %d: extent %.1f x %.1f, centre (%.2f, %.2f)\n", rot * 90, wx, wy, mx,
                      my);
        assert_float_equal(wx, rot ? 6 : 20, 0.6);
        assert_float_equal(wy, rot ? 20 : 6, 0.6);
        assert_float_equal(mx, rot ? -3.5 : 10.5, 0.3);
        assert_float_equal(my, rot ? 10.5 : 3.5, 0.3);
        vv_image_free(img);
    }
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* Iso mode where the ray enters the volume already inside the surface (a
 * constant volume above the isovalue: the box face is a cut face, which the
 * ray caster shades at the first sample). Empty-space skipping must not
 * change that: every pixel over the box is hit, at the box's front face. */
static void
test_iso_enter_inside(void **state) {
    (void)state;
    vv_volume *v = constant_volume(9, 9, 9, VV_F32, 1, 1, 1, 1.0);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_ISO);
    o->isovalue = 0.5;
    vv_view view = ortho_z(4, 4, 50, 4, 8, 8);
    int ok[2] = {0, 0};
    for (int skipping = 0; skipping < 2; skipping++) {
        vv_renderer *r = new_raycaster();
        vt_ok(vv_renderer_set_option(r, "empty_space_skipping", skipping ? "1" : "0"));
        vv_image *img = render(r, w, &view);
        long n = count_hits(img, 0, 8).n;
        print_message("iso, constant volume above the isovalue, skipping %d: %ld of 64 pixels "
                      "hit, centre depth %g (front face at 42)\n",
                      skipping, n, (double)img->depth[4 * 8 + 4]);
        ok[skipping] = n == 64 && fabs(img->depth[4 * 8 + 4] - 42) < 0.51;
        vv_image_free(img);
        vv_renderer_free(r);
    }
    vv_world_free(w);
    vv_volume_free(v);
    assert_true(ok[0]);
    assert_true(ok[1]);
}

/* ---------------------------------------------------------------------- */
/* Cut planes                                                               */

static void
test_global_cut_plane(void **state) {
    (void)state;
    const double R = 10, c = 15.5;
    vv_volume *v = sphere_volume(32, R);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_ISO);
    o->isovalue = 0;
    vv_view view = ortho_z(c, c, 100, 32, 64, 64); /* pixel 0.5, sphere centred */
    vv_renderer *r = new_raycaster();
    vv_image *full = render(r, w, &view);
    hits hf = count_hits(full, 0, 64);
    assert_true(hf.n > 1000);

    /* normal +x keeps x >= 15.5: the right half of the image (columns 32..) */
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(c, c, c), vv_vec3_make(1, 0, 0)));
    vv_image *img = render(r, w, &view);
    hits h = count_hits(img, 0, 64);
    print_message("global cut +x: %ld of %ld pixels kept (%.4f)\n", h.n, hf.n,
                  (double)h.n / (double)hf.n);
    assert_int_equal(count_hits(img, 0, 32).n, 0);
    assert_int_equal(h.n, count_hits(full, 32, 64).n);
    assert_float_equal((double)h.n / (double)hf.n, 0.5, 0.01);
    vv_image_free(img);

    /* normal -x keeps the left half */
    w->cut_planes[0].normal = vv_vec3_make(-1, 0, 0);
    img = render(r, w, &view);
    assert_int_equal(count_hits(img, 32, 64).n, 0);
    assert_int_equal(count_hits(img, 0, 32).n, count_hits(full, 0, 32).n);
    vv_image_free(img);

    /* normal -z (away from the eye) keeps the back half: the silhouette stays
     * and the depth is the eye's distance to the cut face */
    w->cut_planes[0].normal = vv_vec3_make(0, 0, -1);
    img = render(r, w, &view);
    assert_int_equal(count_hits(img, 0, 64).n, hf.n);
    const double dt = 0.5;
    int bad = 0;
    for (int y = 28; y < 36; y++)
        for (int x = 28; x < 36; x++) {
            float d = img->depth[y * 64 + x];
            if (!(d >= 100 - c - 1e-3 && d < 100 - c + dt + 1e-3) && !bad++)
                print_error("cut plane normal -z through the centre: pixel (%d, %d) depth %g, "
                            "expected the cut face at %g (+ < one step %g)\n",
                            x, y, (double)d, 100 - c, dt);
        }
    vv_image_free(img);
    vv_image_free(full);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
    assert_int_equal(bad, 0);
}

/* Two spheres side by side; a local cut plane on the left one (normal +y)
 * halves it and leaves the right one whole. */
static void
test_local_cut_plane(void **state) {
    (void)state;
    const double R = 10, c = 15.5;
    vv_volume *v = sphere_volume(32, R);
    vv_world *w = new_world();
    vv_object *a = add_object(w, v, VV_MODE_ISO);
    vv_object *b = add_object(w, v, VV_MODE_ISO);
    a->isovalue = b->isovalue = 0;
    b->position = vv_vec3_make(24, 0, 0);
    vv_view view = ortho_z(27.5, c, 100, 32, 128, 64); /* pixel 0.5 */
    vv_renderer *r = new_raycaster();
    vv_image *full = render(r, w, &view);
    hits fa = count_hits(full, 0, 64), fb = count_hits(full, 64, 128);
    assert_true(fa.n > 1000);
    assert_int_equal(fa.n, fb.n);

    a->n_cut_planes = 1;
    a->cut_planes[0].point = vv_vec3_make(c, c, c);
    a->cut_planes[0].normal = vv_vec3_make(0, 1, 0);
    vv_image *img = render(r, w, &view);
    hits ha = count_hits(img, 0, 64), hb = count_hits(img, 64, 128);
    print_message("local cut +y on the left sphere: left %ld of %ld, right %ld of %ld\n", ha.n,
                  fa.n, hb.n, fb.n);
    assert_int_equal(hb.n, fb.n);
    assert_float_equal((double)ha.n / (double)fa.n, 0.5, 0.01);
    /* +y is up: only the upper rows (y < 32) remain */
    assert_true(ha.y1 < 32);
    vv_image_free(img);
    vv_image_free(full);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Agreement checks on a real CT                                            */

static vv_world *
headsq_world(int size, vv_volume **vol) {
    vv_world *w = real_scene("headsq/quarter.nhdr", size, vol);
    assert_int_equal(w->n_objects, 1);
    assert_int_equal(w->objects[0]->mode, VV_MODE_COMPOSITE);
    assert_true(w->objects[0]->shading);
    return w;
}

static void
test_step_halving(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vv_world *w = headsq_world(128, &v);
    vv_renderer *r = new_raycaster();
    w->objects[0]->step = 0.5;
    vv_image *a = render(r, w, &w->view);
    w->objects[0]->step = 0.25;
    vv_image *b = render(r, w, &w->view);
    write_png(a, "headsq_step050");
    write_png(b, "headsq_step025");
    double psnr = vv_image_psnr(a, b);
    print_message("headsq composite, step 0.5 vs 0.25: PSNR %.2f dB\n", psnr);
    long lit = count_hits(a, 0, 128).n;
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
    assert_true(lit > 1000);
    assert_true(psnr >= 40.0);
}

static void
test_gradients_on_the_fly(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vv_world *w = headsq_world(128, &v);
    vv_renderer *r = new_raycaster();
    vv_image *a = render(r, w, &w->view);
    vt_ok(vv_renderer_set_option(r, "gradient_budget_mb", "0"));
    vv_image *b = render(r, w, &w->view);
    double psnr = vv_image_psnr(a, b);
    print_message("headsq: cached vs on-the-fly gradients: PSNR %.2f dB\n", psnr);
    /* they must differ at all (otherwise the option did nothing) */
    int same = images_identical(a, b);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
    assert_false(same);
    assert_true(psnr >= 30.0);
}

static void
test_determinism(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vv_world *w = headsq_world(96, &v);
    vv_renderer *r = new_raycaster();
    vv_image *t1 = render_t(r, w, &w->view, 1);
    vv_image *t2 = render_t(r, w, &w->view, 2);
    vv_image *t2b = render_t(r, w, &w->view, 2); /* cache reused */
    assert_true(count_hits(t1, 0, 96).n > 500);
    assert_true(images_identical(t1, t2));
    assert_true(images_identical(t2, t2b));
    /* a fresh renderer (fresh cache) gives the same image too */
    vv_renderer *r2 = new_raycaster();
    vv_image *f = render_t(r2, w, &w->view, 2);
    assert_true(images_identical(t1, f));

    vv_image_free(f);
    vv_image_free(t1);
    vv_image_free(t2);
    vv_image_free(t2b);
    vv_renderer_free(r2);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* Empty-space skipping must not change a composite image, with one object
 * (the single-volume kernel) or two overlapping ones (the general kernel). */
static void
test_skipping_exact(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vv_world *w = headsq_world(96, &v);
    vv_renderer *on = new_raycaster(), *off = new_raycaster();
    vt_ok(vv_renderer_set_option(off, "empty_space_skipping", "0"));
    vv_image *a = render(on, w, &w->view), *b = render(off, w, &w->view);
    int same1 = images_identical(a, b);
    print_message("one object, skipping on vs off: %s (max |diff| %.3g, PSNR %.2f dB)\n",
                  same1 ? "identical" : "DIFFERENT", max_abs_diff(a, b), vv_image_psnr(a, b));
    vv_image_free(a);
    vv_image_free(b);

    vv_object *o2 = NULL;
    vt_ok(vv_object_new_volume(&o2, v, "second"));
    o2->tf = w->objects[0]->tf;
    o2->position = vv_vec3_add(w->objects[0]->position, vv_vec3_make(60, 0, 0));
    vt_ok(vv_world_add_object(w, o2));
    a = render(on, w, &w->view);
    b = render(off, w, &w->view);
    int same2 = images_identical(a, b);
    print_message("two objects, skipping on vs off: %s (max |diff| %.3g)\n",
                  same2 ? "identical" : "DIFFERENT", max_abs_diff(a, b));
    assert_true(count_hits(a, 0, 96).n > 500);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(on);
    vv_renderer_free(off);
    vv_world_free(w);
    vv_volume_free(v);
    assert_true(same1);
    assert_true(same2);
}

/* The runs of visible samples (vv_vray_visible_run_avx2) take whole cubes
 * of visible subvolumes where their distance to a hidden one (vdist) is 2
 * or more, and scan sample by sample elsewhere; the samples they leave out
 * must be transparent. Boxes of noise of every size in an empty 72^3
 * volume (cubes of every vdist, edges everywhere), shaded, seen in
 * perspective from six oblique directions: skipping on and off give the
 * same image bit for bit, and the portable path the same to rounding. */
static void
test_runs_exact(void **state) {
    (void)state;
    const int n = 72;
    vv_volume *v = new_volume(n, n, n, VV_U8, 1, 1, 1);
    uint64_t seed = 0x9E3779B97F4A7C15ULL;
    for (int b = 0; b < 40; b++) {
        int lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            const int size = 1 + (int)(rnd(&seed) * 24);
            lo[a] = (int)(rnd(&seed) * (n - size));
            hi[a] = lo[a] + size;
        }
        for (int k = lo[2]; k < hi[2]; k++)
            for (int j = lo[1]; j < hi[1]; j++)
                for (int i = lo[0]; i < hi[0]; i++)
                    vv_volume_set(v, i, j, k, 40 + 200 * rnd(&seed));
    }
    vv_volume_update_range(v);
    vv_world *w = new_world();
    w->n_lights = 1; /* one directional light: the eight-lane shading pass */
    memset(&w->lights[0], 0, sizeof w->lights[0]);
    w->lights[0].type = VV_LIGHT_DIRECTIONAL;
    w->lights[0].direction = vv_vec3_make(-0.3, -0.4, -0.866);
    w->lights[0].color = vv_vec3_make(1, 1, 1);
    w->lights[0].intensity = 1;
    vv_object *o = add_object(w, v, VV_MODE_COMPOSITE);
    o->shading = 1;
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, 20, 0.0));
    vt_ok(vv_tf_add_opacity(&o->tf, 240, 0.6));
    vt_ok(vv_tf_add_color(&o->tf, 20, vv_vec3_make(0.9, 0.6, 0.3)));
    vt_ok(vv_tf_add_color(&o->tf, 240, vv_vec3_make(1, 1, 1)));
    vv_renderer *on = new_raycaster(), *off = new_raycaster(), *plain = new_raycaster();
    vt_ok(vv_renderer_set_option(off, "empty_space_skipping", "0"));
    vt_ok(vv_renderer_set_option(plain, "simd", "0"));
    const double eyes[6][3] = {{1, 0.3, 0.2}, {-0.4, 1, 0.7}, {0.2, -0.5, -1},
                               {-1, -1, 0.9}, {0.7, 0.1, -1}, {0.05, 1, 0.02}};
    const double c = 0.5 * (n - 1);
    for (int e = 0; e < 6; e++) {
        vv_view view;
        memset(&view, 0, sizeof view);
        const vv_vec3 d = vv_vec3_normalize(vv_vec3_make(eyes[e][0], eyes[e][1], eyes[e][2]));
        view.eye = vv_vec3_make(c + 2.2 * n * d.x, c + 2.2 * n * d.y, c + 2.2 * n * d.z);
        view.at = vv_vec3_make(c, c, c);
        view.up = fabs(d.z) < 0.9 ? vv_vec3_make(0, 0, 1) : vv_vec3_make(0, 1, 0);
        view.fov = vv_deg_to_rad(30);
        view.projection = VV_PROJECTION_PERSPECTIVE;
        view.width = view.height = 96;
        vv_image *a = render(on, w, &view), *b = render(off, w, &view),
                 *p = render(plain, w, &view);
        const long lit = count_hits(a, 0, 96).n;
        const double psnr = vv_image_psnr(a, p);
        print_message("runs, view %d: %ld pixels lit; skipping on vs off %s; AVX2 vs portable "
                      "%.1f dB\n",
                      e, lit, images_identical(a, b) ? "identical" : "DIFFERENT", psnr);
        if (e == 0)
            write_png(a, "runs_boxes");
        assert_true(lit > 1500);
        assert_true(images_identical(a, b));
        assert_true(psnr >= 60);
        vv_image_free(a);
        vv_image_free(b);
        vv_image_free(p);
    }
    vv_renderer_free(on);
    vv_renderer_free(off);
    vv_renderer_free(plain);
    vv_world_free(w);
    vv_volume_free(v);
}

/* MIP and MinIP march a ray one subvolume at a time (the portable path)
 * or in chunks of samples whose subvolumes are tested eight at a time
 * (AVX2, 16-bit values): both are exact, so on real data, where
 * subvolumes are skipped, they must give the same colours, with one
 * thread or several. MIP keeps the default transfer function, flat above
 * a ramp: a ray stops once it reaches the flat top, at a point that
 * depends on the path, so only its depth may differ (an earlier sample of
 * the same colour, vv_vray_project). MinIP and X-ray (whose AVX2 path adds
 * the same values in the same order) get a ramp with no flat end: every
 * ray is marched to its end and the depths must agree too. On a processor
 * without AVX2 both take the portable path. */
static void
test_projection_paths_identical(void **state) {
    (void)state;
    const char *files[2] = {"neghip.slc", "headsq/quarter.nhdr"};
    const vv_render_mode modes[3] = {VV_MODE_MIP, VV_MODE_MINIP, VV_MODE_XRAY};
    const char *names[3] = {"mip", "minip", "xray"};
    for (int f = 0; f < 2; f++)
        for (int m = 0; m < 3; m++) {
            vv_volume *v = NULL;
            vv_world *w = real_scene(files[f], 160, &v);
            vv_object *o = w->objects[0];
            o->mode = modes[m];
            if (modes[m] != VV_MODE_MIP) {
                /* opaque, a grey ramp that starts below the data: no
                 * flat end to stop at, every ray marched to its end */
                const double lo = v->range[0], hi = v->range[1];
                vv_tf_init(&o->tf);
                vt_ok(vv_tf_add_opacity(&o->tf, lo, 1.0));
                vt_ok(vv_tf_add_color(&o->tf, lo - (hi - lo), vv_vec3_make(0, 0, 0)));
                vt_ok(vv_tf_add_color(&o->tf, hi, vv_vec3_make(1, 1, 1)));
            }
            vv_image *img[3]; /* portable; AVX2; AVX2 on one thread */
            for (int path = 0; path < 3; path++) {
                vv_renderer *r = new_raycaster();
                vt_ok(vv_renderer_set_option(r, "simd", path ? "1" : "0"));
                img[path] = render_t(r, w, &w->view, path == 2 ? 1 : 0);
                vv_renderer_free(r);
            }
            long lit = 0;
            for (size_t i = 0; i < 160 * 160; i++)
                lit += img[0]->rgba[4 * i + 3] > 0.02f;
            long depths = 0; /* pixels whose depths differ, any two paths */
            for (size_t i = 0; i < 160 * 160; i++)
                for (int path = 1; path < 3; path++)
                    if (memcmp(&img[0]->depth[i], &img[path]->depth[i], sizeof(float))) {
                        depths++;
                        break;
                    }
            const double diff = fmax(max_abs_diff(img[0], img[1]), max_abs_diff(img[0], img[2]));
            print_message("%s %s: %ld pixels lit; portable and AVX2: colours differ by %g, %ld "
                          "depths differ\n",
                          files[f], names[m], lit, diff, depths);
            assert_true(lit > 2000);
            assert_true(diff == 0);
            assert_true(images_identical(img[1], img[2])); /* any thread count */
            if (modes[m] != VV_MODE_MIP)
                assert_int_equal(depths, 0);
            for (int path = 0; path < 3; path++)
                vv_image_free(img[path]);
            vv_world_free(w);
            vv_volume_free(v);
        }
}

/* One volume in iso mode takes its own kernel (vv_vray_iso_first: runs of
 * visible subvolumes, values eight at a time); with a second object in the
 * World (here out of sight, so that it adds nothing) the per-sample march
 * of several objects draws it instead. Both search the same samples for
 * the first crossing and refine it the same way, so on real data, with a
 * cut plane through the surface, they must agree to rounding, with and
 * without skipping, and on the portable path at a step of 1/10 voxel
 * (its runs then exceed a chunk: the case 2 of @p skipping). After hidden
 * subvolumes the search restarts at the sample before the visible ones,
 * so skipping leaves the image bit for bit as it is without (the region
 * renders of out-of-core isosurfaces rely on it). */
static void
test_iso_kernels_agree(void **state) {
    (void)state;
    const char *files[2] = {"neghip.slc", "headsq/quarter.nhdr"};
    for (int f = 0; f < 2; f++) {
        vv_image *noskip[2] = {NULL, NULL}; /* one object, several */
        for (int skipping = 0; skipping < 3; skipping++) {
            vv_volume *v = NULL;
            vv_world *w = real_scene(files[f], 128, &v);
            vv_object *o = w->objects[0];
            o->mode = VV_MODE_ISO;
            o->isovalue = v->range[0] + 0.4 * (v->range[1] - v->range[0]);
            o->n_cut_planes = 1;
            o->cut_planes[0].point = vv_vec3_make(0, 0, 0);
            o->cut_planes[0].normal = vv_vec3_normalize(vv_vec3_make(0.3, 0.2, 1));
            vv_renderer *r = new_raycaster();
            vt_ok(vv_renderer_set_option(r, "empty_space_skipping", skipping ? "1" : "0"));
            if (skipping == 2) {
                vt_ok(vv_renderer_set_option(r, "simd", "0"));
                o->step = 0.1;
            }
            vv_image *one = render(r, w, &w->view);
            vv_object *far = NULL;
            vt_ok(vv_object_new_volume(&far, v, "far"));
            far->mode = VV_MODE_ISO;
            far->isovalue = o->isovalue;
            far->step = o->step;
            far->position = vv_vec3_make(0, 0, -1e6);
            vt_ok(vv_world_add_object(w, far));
            vv_image *two = render(r, w, &w->view);
            long lit = 0, depths = 0;
            double dmax = 0;
            for (size_t i = 0; i < 128 * 128; i++) {
                lit += one->rgba[4 * i + 3] > 0.5f;
                if (one->depth[i] != two->depth[i]) {
                    depths++;
                    dmax = fmax(dmax, fabs((double)one->depth[i] - (double)two->depth[i]));
                }
            }
            const double diff = max_abs_diff(one, two);
            print_message("%s iso %.1f, skipping %d: %ld pixels hit; one object's kernel against "
                          "the march of several: colours differ by %.3g, %ld depths by up to "
                          "%.3g\n",
                          files[f], o->isovalue, skipping, lit, diff, depths, dmax);
            if (skipping == 1)
                write_png(one, f ? "iso_kernel_headsq" : "iso_kernel_neghip");
            assert_true(lit > 300);
            assert_true(diff < 1e-3);
            assert_true(dmax < 1e-3);
            if (skipping == 0) {
                noskip[0] = one;
                noskip[1] = two;
                one = two = NULL;
            } else if (skipping == 1) {
                for (int k = 0; k < 2; k++) {
                    const vv_image *a = noskip[k], *b = k ? two : one;
                    assert_memory_equal(a->rgba, b->rgba, sizeof(float) * 4 * 128 * 128);
                    assert_memory_equal(a->depth, b->depth, sizeof(float) * 128 * 128);
                }
            }
            vv_image_free(one);
            vv_image_free(two);
            vv_renderer_free(r);
            vv_world_free(w);
            vv_volume_free(v);
        }
        vv_image_free(noskip[0]);
        vv_image_free(noskip[1]);
    }
}

/* The AVX2 classification pass (chosen at run time) and the portable one
 * differ only in fused multiply-add rounding: the images must agree to far
 * better than any visible difference, with and without skipping. On a
 * processor without AVX2 both renders take the portable path. */
static void
test_simd_matches_portable(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vv_world *w = headsq_world(96, &v);
    vv_renderer *simd = new_raycaster(), *plain = new_raycaster();
    vt_ok(vv_renderer_set_option(plain, "simd", "0"));
    vv_image *a = render(simd, w, &w->view), *b = render(plain, w, &w->view);
    double psnr = vv_image_psnr(a, b);
    print_message("simd vs portable: PSNR %.2f dB, max |diff| %.3g\n", psnr, max_abs_diff(a, b));
    assert_true(psnr >= 60);
    assert_true(count_hits(a, 0, 96).n > 500);
    vv_image_free(a);
    vv_image_free(b);
    vt_ok(vv_renderer_set_option(simd, "empty_space_skipping", "0"));
    vt_ok(vv_renderer_set_option(plain, "empty_space_skipping", "0"));
    a = render(simd, w, &w->view);
    b = render(plain, w, &w->view);
    assert_true(vv_image_psnr(a, b) >= 60);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(simd);
    vv_renderer_free(plain);
    vv_world_free(w);
    vv_volume_free(v);
}

/* Adaptive image-space refinement (Levoy 1990; option refinement, on by
 * default at quality 0 and 1, and at quality 2 in frames of composite
 * objects). Against a converged reference (step 1/16 of the
 * object's, 4 x 4 rays a pixel, box-filtered), the default quality-2 image
 * (refined at 1/1024) is as accurate as without refinement (within 0.01 dB: issue
 * 65's rule allows 0.05) and is refinement=on's; quality 1 is within a few
 * dB with far fewer samples; any thread count gives the same image;
 * refinement=off at quality 1 is refinement=off's quality-2 image. */
/* The ray caster's converged reference: step 1/16 of the objects', k x k
 * rays a pixel, box-filtered, no refinement (vt_converged_reference). */
static vv_image *
converged_reference(const vv_world *world, int k) {
    vv_renderer *r = new_raycaster();
    vt_ok(vv_renderer_set_option(r, "refinement", "off"));
    vv_image *img = vt_converged_reference(r, world, 16, k);
    vv_renderer_free(r);
    return img;
}

static void
test_adaptive_refinement(void **state) {
    (void)state;
    static const char *files[] = {"neghip.slc", "headsq/quarter.nhdr"};
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        vv_volume *v = NULL;
        vv_world *w = real_scene(files[f], 128, &v);
        vv_image *ref = converged_reference(w, 4);
        vv_renderer *r = new_raycaster(), *on = new_raycaster(), *off = new_raycaster();
        vt_ok(vv_renderer_set_option(on, "refinement", "on"));
        vt_ok(vv_renderer_set_option(off, "refinement", "off"));
        vv_render_stats s2 = {0}, s2a = {0}, s1 = {0}, s2off = {0};
        vv_image *q2 = vt_render_q(r, w, 2, 0, &s2);
        vv_image *q2a = vt_render_q(on, w, 2, 0, &s2a);
        vv_image *q2off = vt_render_q(off, w, 2, 0, &s2off);
        vv_image *q1 = vt_render_q(r, w, 1, 1, &s1);
        vv_image *q1t = vt_render_q(r, w, 1, 2, NULL);
        vv_image *q1off = vt_render_q(off, w, 1, 2, NULL);
        const double p2 = vv_image_psnr(q2, ref), p2a = vv_image_psnr(q2a, ref),
                     p1 = vv_image_psnr(q1, ref), p2off = vv_image_psnr(q2off, ref);
        print_message("%s against the converged reference: quality 2 (default, refined) %.3f dB "
                      "(%llu samples), refinement=off %.3f dB (%llu), quality 1 adaptive %.2f dB "
                      "(%llu)\n",
                      files[f], p2, (unsigned long long)s2.samples, p2off,
                      (unsigned long long)s2off.samples, p1, (unsigned long long)s1.samples);
        write_png(q1, f ? "adaptive_q1_headsq" : "adaptive_q1_neghip");
        assert_true(count_hits(q2, 0, 128).n > 500);
        assert_true(images_identical(q2, q2a));
        (void)p2a;
        assert_true(p2 >= p2off - 0.01);
        assert_true(p2 >= (f ? 45.2 : 51.5)); /* measured 46.26 and 52.58 dB */
        assert_true(p1 >= p2 - 6);
        assert_true(p1 >= 30);
        /* at about two pixels a voxel most tiles refine whole: the lattice
         * costs at most the next tiles' first rows and columns */
        assert_true(s1.samples > 0 && (double)s1.samples < 1.15 * (double)s2.samples);
        assert_true(images_identical(q1, q1t));
        assert_true(images_identical(q1off, q2off));
        vv_image *q[] = {ref, q2, q2a, q2off, q1, q1t, q1off};
        for (size_t i = 0; i < sizeof q / sizeof q[0]; i++)
            vv_image_free(q[i]);
        /* MIP and MinIP at quality 2: refined by default (region renders,
         * out of core and the multi-channel maximum, cast every pixel: the
         * refinement=off image), within issue 65's 0.05 dB of the
         * unrefined image against the converged reference */
        const vv_tf tf0 = w->objects[0]->tf;
        for (int m = 0; m < 2; m++) {
            w->objects[0]->mode = m ? VV_MODE_MINIP : VV_MODE_MIP;
            if (m) {
                /* opaque, a grey ramp that starts below the data (the
                 * minimum of most rays is the background, shown dark
                 * grey rather than transparent) */
                const double lo = v->range[0], hi = v->range[1];
                vv_tf *tf = &w->objects[0]->tf;
                vv_tf_init(tf);
                vt_ok(vv_tf_add_opacity(tf, lo, 1.0));
                vt_ok(vv_tf_add_color(tf, lo - (hi - lo), vv_vec3_make(0, 0, 0)));
                vt_ok(vv_tf_add_color(tf, hi, vv_vec3_make(1, 1, 1)));
            }
            vv_image *mref = converged_reference(w, 4), *mq2 = vt_render_q(on, w, 2, 0, NULL);
            vv_image *moff = vt_render_q(off, w, 2, 0, NULL);
            vv_image *mdef = vt_render_q(r, w, 2, 0, NULL);
            const double pm = vv_image_psnr(mq2, mref), pmoff = vv_image_psnr(moff, mref);
            print_message("%s %s against the converged reference: quality 2 refined (the "
                          "default) %.3f dB, unrefined %.3f dB\n",
                          files[f], m ? "MinIP" : "MIP", pm, pmoff);
            assert_true(images_identical(mdef, mq2));
            assert_false(images_identical(mq2, moff)); /* refined: some pixels interpolated */
            assert_true(pm >= pmoff - 0.05);
            vv_image_free(mdef);
            vv_image_free(mref);
            vv_image_free(mq2);
            vv_image_free(moff);
        }
        w->objects[0]->tf = tf0;
        w->objects[0]->mode = VV_MODE_COMPOSITE;
        /* magnified four times (about eight pixels a voxel on neghip, the
         * benchmark's view): far fewer samples for nearly the same image */
        w->view.fov *= 0.25;
        s1 = s2 = (vv_render_stats){0};
        q2 = vt_render_q(r, w, 2, 0, &s2);
        q1 = vt_render_q(r, w, 1, 0, &s1);
        const double pz = vv_image_psnr(q1, q2);
        print_message("%s magnified: quality 1 adaptive against quality 2: %.2f dB, %llu of %llu "
                      "samples\n",
                      files[f], pz, (unsigned long long)s1.samples, (unsigned long long)s2.samples);
        assert_true(pz >= 40);
        assert_true((double)s1.samples < 0.75 * (double)s2.samples);
        vv_image_free(q1);
        vv_image_free(q2);
        vv_renderer_free(r);
        vv_renderer_free(on);
        vv_renderer_free(off);
        vv_world_free(w);
        vv_volume_free(v);
    }
}

/* Pre-integrated classification (option preintegration): the segments
 * between samples cover a ray's whole path through the volume, entry and
 * exit included, and integrate the transfer function exactly along the
 * linear value ramp between two samples. Seen straight down z at any
 * offset of the sample grid: (1) a constant slab of length L gives
 * 1 - alpha = exp(-tau L); (2) a ramp (value = z) under a transfer
 * function stepping from 0 to opacity a at value 10.5 gives
 * exp(-tau (L - 10.5)), where point sampling's count of samples above the
 * step, and so its result, varies with the offset. White, unshaded: the
 * colour equals the opacity. */
static double
preint_transmittance(vv_world *w, vv_renderer *r, double top, double dt, double phase) {
    const double eye_z = top + (floor(40.0 / dt) + phase) * dt;
    vv_view view = ortho_z(1.5, 1.5, eye_z, 2.0, 2, 2);
    vv_image *img = render(r, w, &view);
    const float *p = px(img, 1, 1);
    assert_float_equal(p[0], p[3], 1e-5);
    const double trans = 1.0 - p[3];
    vv_image_free(img);
    return trans;
}

static void
test_preintegration_analytic(void **state) {
    (void)state;
    vv_renderer *pre = new_raycaster(), *point = new_raycaster();
    vt_ok(vv_renderer_set_option(pre, "preintegration", "1"));
    vt_ok(vv_renderer_set_option(pre, "early_termination", "1"));
    vt_ok(vv_renderer_set_option(point, "early_termination", "1"));
    static const double phases[] = {0.0, 0.13, 0.37, 0.5, 0.71, 0.96};
    /* (1) a constant slab, 8 voxels long */
    vv_volume *v = constant_volume(4, 4, 9, VV_F32, 1, 1, 1, 5.0);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_COMPOSITE);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, 5.0, 0.3));
    o->tf.opacity_unit_distance = 1.0;
    o->step = 0.7;
    double worst = 0;
    for (size_t i = 0; i < sizeof phases / sizeof phases[0]; i++) {
        const double t = preint_transmittance(w, pre, 8.0, 0.7, phases[i]);
        const double e = fabs(t / pow(0.7, 8.0) - 1);
        worst = e > worst ? e : worst;
    }
    print_message("pre-integrated slab: worst relative error %.2e over %zu offsets\n", worst,
                  sizeof phases / sizeof phases[0]);
    assert_true(worst < 1e-5);
    vv_world_free(w);
    vv_volume_free(v);
    /* (2) a ramp along z, 31 voxels long */
    v = new_volume(4, 4, 32, VV_F32, 1, 1, 1);
    for (int k = 0; k < 32; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++)
                vv_volume_set(v, i, j, k, k);
    vv_volume_update_range(v);
    w = new_world();
    o = add_object(w, v, VV_MODE_COMPOSITE);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, 0, 0));
    vt_ok(vv_tf_add_opacity(&o->tf, 10.49, 0));
    vt_ok(vv_tf_add_opacity(&o->tf, 10.51, 0.1));
    vt_ok(vv_tf_add_opacity(&o->tf, 31, 0.1));
    o->tf.opacity_unit_distance = 1.0;
    const double expect = pow(0.9, 31 - 10.5);
    for (int st = 0; st < 2; st++) {
        const double step = st ? 1.0 : 0.5;
        o->step = step;
        double wp = 0, wq = 0;
        for (size_t i = 0; i < sizeof phases / sizeof phases[0]; i++) {
            const double tp = preint_transmittance(w, pre, 31.0, step, phases[i]);
            const double tq = preint_transmittance(w, point, 31.0, step, phases[i]);
            wp = fabs(tp / expect - 1) > wp ? fabs(tp / expect - 1) : wp;
            wq = fabs(tq / expect - 1) > wq ? fabs(tq / expect - 1) : wq;
        }
        print_message("ramp under a step transfer function, step %.1f: worst relative error "
                      "pre-integrated %.2e, point-sampled %.2e\n",
                      step, wp, wq);
        assert_true(wp < 1e-3);
        assert_true(wq > 10 * wp);
    }
    vv_world_free(w);
    vv_volume_free(v);
    vv_renderer_free(pre);
    vv_renderer_free(point);
}

/* Pre-integration on a real volume under a sharp transfer function (neghip,
 * opacity rising over 4 of its 256 values): against the converged ray
 * integral (point sampling at 1/16 of the step, one ray a pixel) it is
 * several dB more accurate than point sampling at the same step (measured
 * +7.7 dB at step 0.5, +4.8 at step 1), and still ahead against the
 * converged image (4 x 4 rays a pixel, where the pixel sampling dominates);
 * any thread count and skipping on or off give the same image; the
 * portable classification agrees with AVX2's. */
static void
test_preintegration_real(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vv_world *w = real_scene("neghip.slc", 128, &v);
    vv_object *o = w->objects[0];
    vv_tf_set_ramp(&o->tf, 60, 64, 0.5, vv_vec3_make(1, 0.85, 0.7), o->tf.opacity_unit_distance);
    vv_renderer *pre = new_raycaster(), *point = new_raycaster();
    vt_ok(vv_renderer_set_option(pre, "preintegration", "1"));
    for (int st = 0; st < 2; st++) {
        o->step = st ? 1.0 : 0.5;
        vv_image *ref = converged_reference(w, 1), *ref4 = converged_reference(w, 4);
        vv_image *a = vt_render_q(pre, w, 2, 0, NULL), *b = vt_render_q(point, w, 2, 0, NULL);
        const double pa = vv_image_psnr(a, ref), pb = vv_image_psnr(b, ref);
        const double pa4 = vv_image_psnr(a, ref4), pb4 = vv_image_psnr(b, ref4);
        print_message("neghip, sharp transfer function, step %.1f, against the converged ray "
                      "integral: pre-integrated %.2f dB, point-sampled %.2f dB; against 4 x 4 "
                      "rays a pixel: %.2f and %.2f dB\n",
                      o->step, pa, pb, pa4, pb4);
        write_png(a, st ? "preint_neghip_step1" : "preint_neghip_step05");
        assert_true(count_hits(a, 0, 128).n > 300);
        assert_true(pa >= pb + 3);
        assert_true(pa4 >= pb4 + 0.3);
        vv_image_free(ref4);
        if (st == 0) {
            vv_image *t1 = vt_render_q(pre, w, 2, 1, NULL), *t2 = vt_render_q(pre, w, 2, 2, NULL);
            assert_true(images_identical(a, t1));
            assert_true(images_identical(a, t2));
            vt_ok(vv_renderer_set_option(pre, "empty_space_skipping", "0"));
            vv_image *ns = vt_render_q(pre, w, 2, 0, NULL);
            assert_true(images_identical(a, ns));
            vt_ok(vv_renderer_set_option(pre, "empty_space_skipping", "1"));
            vt_ok(vv_renderer_set_option(pre, "simd", "0"));
            vv_image *portable = vt_render_q(pre, w, 2, 0, NULL);
            assert_true(vv_image_psnr(a, portable) >= 60);
            vt_ok(vv_renderer_set_option(pre, "simd", "1"));
            vv_image *q[] = {t1, t2, ns, portable};
            for (size_t i = 0; i < sizeof q / sizeof q[0]; i++)
                vv_image_free(q[i]);
        }
        vv_image_free(a);
        vv_image_free(b);
        vv_image_free(ref);
    }
    vv_renderer_free(pre);
    vv_renderer_free(point);
    vv_world_free(w);
    vv_volume_free(v);
}

/* The composite kernel shades eight samples at a time with AVX2
 * (vv_vshade8); its results must be vv_vshade's bit for bit (the images of
 * both paths are compared bit for bit elsewhere: raytrace against raycast):
 * random normal matrices, gradients (a quarter of length 0, so unlit),
 * one to three directional lights, shadows (every other round), colours
 * and opacities, and every lane. */
typedef struct shade8_lane {
    const float *shadow; /* light l of lane q at shadow[8 l + q] */
    int q;
} shade8_lane;

static float
lane_shadow(const void *ctx, int light) {
    const shade8_lane *s = ctx;
    return s->shadow[8 * light + s->q];
}

static void
test_shade8_matches_scalar(void **state) {
    (void)state;
    if (!vv_vc_have_avx2())
        vt_skip("this processor has no AVX2: the kernel shades with vv_vshade only");
    uint64_t seed = 0x243f6a8885a308d3ULL;
    vv_vshading sh;
    memset(&sh, 0, sizeof sh);
    for (int i = 0; i <= VV_VC_SPEC; i++)
        sh.spec[i] = powf((float)i / VV_VC_SPEC, 30.0f);
    long lanes = 0, unlit = 0;
    for (int round = 0; round < 200; round++) {
        for (int i = 0; i < 3; i++) {
            sh.amb[i] = (float)rnd(&seed) * 0.3f;
            for (int j = 0; j < 3; j++)
                sh.nrm[i][j] = (float)(rnd(&seed) * 4 - 2);
        }
        vv_vlight lights[3];
        memset(lights, 0, sizeof lights);
        const int nl = 1 + round % 3;
        for (int l = 0; l < nl; l++) {
            double d[3], n = 0;
            for (int a = 0; a < 3; a++) {
                d[a] = rnd(&seed) * 2 - 1;
                n += d[a] * d[a];
            }
            for (int a = 0; a < 3; a++) {
                lights[l].dir[a] = (float)(d[a] / sqrt(n));
                sh.kd_col[l][a] = (float)rnd(&seed) * 0.7f;
                sh.ks_col[l][a] = (float)rnd(&seed) * 0.3f;
            }
        }
        float v[3];
        double vn = 0, vd[3];
        for (int a = 0; a < 3; a++) {
            vd[a] = rnd(&seed) * 2 - 1;
            vn += vd[a] * vd[a];
        }
        for (int a = 0; a < 3; a++)
            v[a] = (float)(vd[a] / sqrt(vn));
        float gx[8], gy[8], gz[8], al[8], cr[8], cg[8], cb[8], orr[8], org[8], orb[8];
        for (int q = 0; q < 8; q++) {
            const int zero = rnd(&seed) < 0.25;
            gx[q] = zero ? 0 : (float)(rnd(&seed) * 254 - 127);
            gy[q] = zero ? 0 : (float)(rnd(&seed) * 254 - 127);
            gz[q] = zero ? 0 : (float)(rnd(&seed) * 254 - 127);
            al[q] = (float)rnd(&seed);
            cr[q] = al[q] * (float)rnd(&seed);
            cg[q] = al[q] * (float)rnd(&seed);
            cb[q] = al[q] * (float)rnd(&seed);
            unlit += zero;
        }
        /* every other round with shadows: transmittances in [0, 1], some
         * exactly 0 or 1 */
        float shadow[3 * 8];
        const int with_shadow = round % 2;
        for (int i = 0; i < 3 * 8; i++) {
            const double x = rnd(&seed);
            shadow[i] = x < 0.1 ? 0.0f : x > 0.9 ? 1.0f : (float)rnd(&seed);
        }
        vv_vshade8(&sh, lights, nl, v, with_shadow ? shadow : NULL, gx, gy, gz, al, cr, cg, cb, orr,
                   org, orb);
        for (int q = 0; q < 8; q++) {
            const float g[3] = {gx[q], gy[q], gz[q]}, col[3] = {cr[q], cg[q], cb[q]};
            const float pw[3] = {0, 0, 0};
            float out[3];
            const shade8_lane lane = {shadow, q};
            vv_vshade(&sh, lights, nl, g, pw, v, col, al[q], with_shadow ? lane_shadow : NULL,
                      &lane, out);
            const float got[3] = {orr[q], org[q], orb[q]};
            if (memcmp(out, got, sizeof out) != 0)
                fail_msg("round %d lane %d: vv_vshade (%.9g, %.9g, %.9g), vv_vshade8 (%.9g, "
                         "%.9g, %.9g)",
                         round, q, (double)out[0], (double)out[1], (double)out[2], (double)got[0],
                         (double)got[1], (double)got[2]);
            lanes++;
        }
    }
    print_message("vv_vshade8 against vv_vshade: %ld lanes (%ld unlit) bit for bit\n", lanes,
                  unlit);
}

/* A 2-D image (one voxel along z) renders as a slab one voxel thick, face
 * on through the default scene, in composite and MIP modes. */
static void
test_single_slice(void **state) {
    (void)state;
    const int dims[3] = {48, 48, 1};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int j = 0; j < 48; j++)
        for (int i = 0; i < 48; i++)
            vv_volume_set(v, i, j, 0, 40 + (i + j) * 2);
    vv_volume_update_range(v);
    for (int mode = 0; mode < 2; mode++) {
        vv_default_scene_options o;
        vv_default_scene_options_init(&o);
        o.width = o.height = 64;
        o.mode = mode ? VV_MODE_MIP : VV_MODE_COMPOSITE;
        vv_world *w = NULL;
        vt_ok(vv_world_new_for_volume(&w, v, &o));
        vv_renderer *r = new_raycaster();
        vv_image *img = render(r, w, &w->view);
        int lit = 0;
        for (int p = 0; p < 64 * 64; p++)
            lit += img->rgba[4 * p + 0] > 0.02f;
        print_message("single slice, %s: %d of 4096 pixels lit\n", mode ? "mip" : "composite", lit);
        assert_true(lit > 1000); /* face on: a large square, not an edge */
        vv_image_free(img);
        vv_renderer_free(r);
        vv_world_free(w);
    }
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Progress and cancellation                                                */

typedef struct progress_log {
    int n;
    double f[1024];
    int cancel_at; /* call number at which to cancel; 0: never */
} progress_log;

static int
on_progress(void *user, double fraction) {
    progress_log *l = user;
    if (l->n < 1024)
        l->f[l->n] = fraction;
    l->n++;
    return l->cancel_at > 0 && l->n >= l->cancel_at;
}

static void
test_progress_and_cancel(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(32, 10);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_COMPOSITE);
    (void)o;
    vv_view view = ortho_z(15.5, 15.5, 100, 32, 64, 64);
    vv_renderer *r = new_raycaster();
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 64, 64));
    progress_log log;
    memset(&log, 0, sizeof log);
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = 2;
    opt.progress.fn = on_progress;
    opt.progress.user = &log;
    vt_ok(vv_renderer_render(r, w, &view, &opt, img));
    assert_true(log.n >= 2);
    for (int i = 1; i < log.n; i++)
        assert_true(log.f[i] > log.f[i - 1]);
    assert_true(log.f[0] > 0);
    assert_float_equal(log.f[log.n - 1], 1.0, 1e-12);

    memset(&log, 0, sizeof log);
    log.cancel_at = 1;
    vv_error_clear();
    assert_int_equal(vv_renderer_render(r, w, &view, &opt, img), VV_ERR_CANCELLED);
    assert_true(vv_error_message()[0] != '\0');
    assert_true(log.n >= 1 && log.n < 16); /* stopped well before the 16 tiles */
    /* the renderer still works afterwards */
    vt_ok(vv_renderer_render(r, w, &view, NULL, img));
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Bad input                                                                */

static void
test_bad_input(void **state) {
    (void)state;
    vv_renderer *bad = NULL;
    vv_error_clear();
    assert_int_equal(vv_renderer_new(&bad, "no-such-method"), VV_ERR_INVALID);
    assert_null(bad);
    assert_non_null(strstr(vv_error_message(), "no-such-method"));

    vv_renderer *r = new_raycaster();
    assert_string_equal(vv_renderer_name(r), "raycast");
    const char *bad_opts[][2] = {
        {"early_termination", "0"},   {"early_termination", "1.5"},
        {"early_termination", "abc"}, {"early_termination", ""},
        {"early_termination", "nan"}, {"early_termination", "0.5x"},
        {"gradient_budget_mb", "-1"}, {"empty_space_skipping", "yes"},
        {"no_such_option", "1"},
    };
    for (size_t i = 0; i < sizeof bad_opts / sizeof bad_opts[0]; i++) {
        vv_error_clear();
        vv_status s = vv_renderer_set_option(r, bad_opts[i][0], bad_opts[i][1]);
        if (s != VV_ERR_INVALID)
            fail_msg("option %s=%s: got %s", bad_opts[i][0], bad_opts[i][1], vv_status_name(s));
        assert_true(vv_error_message()[0] != '\0');
    }
    vt_ok(vv_renderer_set_option(r, "early_termination", "0.95"));
    vt_ok(vv_renderer_set_option(r, "gradient_budget_mb", "16"));
    vt_ok(vv_renderer_set_option(r, "empty_space_skipping", "0"));

    vv_volume *v = sphere_volume(8, 3);
    vv_world *w = new_world();
    vv_object *o = add_object(w, v, VV_MODE_COMPOSITE);
    vv_view view = ortho_z(3.5, 3.5, 50, 8, 16, 16);
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 16, 8));
    vv_error_clear();
    assert_int_equal(vv_renderer_render(r, w, &view, NULL, img), VV_ERR_INVALID);
    assert_true(vv_error_message()[0] != '\0');
    vv_image_free(img);
    vt_ok(vv_image_new(&img, 16, 16));
    vt_ok(vv_renderer_render(r, w, &view, NULL, img));
    o->step = 0;
    vt_err(vv_renderer_render(r, w, &view, NULL, img));
    o->step = -1;
    vt_err(vv_renderer_render(r, w, &view, NULL, img));
    o->step = NAN;
    vt_err(vv_renderer_render(r, w, &view, NULL, img));
    o->step = 0.5;
    vt_ok(vv_renderer_render(r, w, &view, NULL, img));
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Every shared real volume renders through the default scene               */

static void
test_real_files(void **state) {
    (void)state;
    static const char *files[] = {
        "nut.slc",          "bolt.slc",
        "neghip.slc",       "sphere.slc",
        "ct_head.nrrd",     "headsq/quarter.nhdr",
        "ironProt.vtk",     "heart.vtk",
        "HeadMRVolume.mhd", "avg152T1_RL_nifti.nii.gz",
    };
    vv_renderer *r = new_raycaster();
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        vv_volume *v = NULL;
        vv_world *w = real_scene(files[f], 64, &v);
        vv_image *img = render(r, w, &w->view);
        long lit = 0;
        for (int y = 0; y < 64; y++)
            for (int x = 0; x < 64; x++) {
                const float *p = px(img, x, y);
                double d = fabs(p[0] - w->background.x) + fabs(p[1] - w->background.y) +
                           fabs(p[2] - w->background.z);
                lit += d > 0.1;
            }
        print_message("%s: %d x %d x %d %s, %ld of 4096 pixels differ from the background\n",
                      files[f], v->dims[0], v->dims[1], v->dims[2], vv_voxel_type_name(v->type),
                      lit);
        if (lit < 40)
            fail_msg("%s renders (almost) blank: %ld lit pixels", files[f], lit);
        char name[256];
        snprintf(name, sizeof name, "real_%s", files[f]);
        for (char *c = name; *c; c++)
            if (*c == '/' || *c == '.')
                *c = '_';
        write_png(img, name);
        vv_image_free(img);
        vv_world_free(w);
        vv_volume_free(v);
    }
    vv_renderer_free(r);
}

/* A float volume whose values span a denormal width (1e-38): its table's
 * scale overflowed float and NaN indices crashed the ray caster; now every
 * mode draws it (the values fall in one bin) with finite pixels. */
static void
test_denormal_range(void **state) {
    (void)state;
    const int d[3] = {12, 10, 8};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, d, VV_F32));
    float *f = v->data;
    for (size_t i = 0; i < vv_volume_voxel_count(v); i++)
        f[i] = (float)(1e-38 * (double)(i % 7) / 6.0);
    vv_volume_update_range(v);
    vv_render_mode modes[] = {VV_MODE_COMPOSITE, VV_MODE_MIP, VV_MODE_ISO, VV_MODE_XRAY};
    for (size_t m = 0; m < sizeof modes / sizeof modes[0]; m++) {
        vv_default_scene_options o;
        vv_default_scene_options_init(&o);
        o.width = o.height = 32;
        o.mode = modes[m];
        vv_world *w = NULL;
        vt_ok(vv_world_new_for_volume(&w, v, &o));
        vv_renderer *r = new_raycaster();
        vv_image *img = render(r, w, &w->view);
        for (size_t i = 0; i < (size_t)img->width * img->height * 4; i++)
            assert_true(isfinite(img->rgba[i]));
        vv_image_free(img);
        vv_renderer_free(r);
        vv_world_free(w);
    }
    vv_volume_free(v);
}

/* A float volume whose values span more than a float holds (-2.5e38 and
 * 3.2e38): the cache stores some of them as infinite, a sample between
 * them is NaN, and its table index was a NaN cast to int, and so was the
 * octahedral code of a NaN gradient (undefined; found by fuzz_render,
 * tests/fuzz/corpus/render/crash-*); now every mode draws it with finite
 * pixels. */
static void
test_range_past_float(void **state) {
    (void)state;
    const int d[3] = {9, 7, 6};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, d, VV_F32));
    float *f = v->data;
    /* two columns at the extremes (the last one reaches the scalar encoder
     * of the gradients: 9 = 8 + 1), a NaN, a ramp elsewhere */
    for (int z = 0, i = 0; z < d[2]; z++)
        for (int y = 0; y < d[1]; y++)
            for (int x = 0; x < d[0]; x++, i++)
                f[i] = x == 7 ? -2.5e38f : x == 8 ? 3.2e38f : 0.1f * (float)(x + y + z);
    f[40] = NAN;
    vv_volume_update_range(v);
    vv_render_mode modes[] = {VV_MODE_COMPOSITE, VV_MODE_MIP, VV_MODE_ISO, VV_MODE_XRAY,
                              VV_MODE_MINIP};
    for (size_t m = 0; m < sizeof modes / sizeof modes[0]; m++) {
        vv_default_scene_options o;
        vv_default_scene_options_init(&o);
        o.width = o.height = 24;
        o.mode = modes[m];
        vv_world *w = NULL;
        vt_ok(vv_world_new_for_volume(&w, v, &o));
        vv_renderer *r = new_raycaster();
        vv_image *img = render(r, w, &w->view);
        for (size_t i = 0; i < (size_t)img->width * img->height * 4; i++)
            assert_true(isfinite(img->rgba[i]));
        vv_image_free(img);
        vv_renderer_free(r);
        vv_world_free(w);
    }
    vv_volume_free(v);
}

/* A volume whose range does not hold its voxels (a region of a .vvb
 * carries the range its header states: found by fuzz_render,
 * tests/fuzz/corpus/render/crash-1826d8a1...): the 16-bit copy's cast of a
 * value below or past the range was undefined; now such values are clamped
 * to the range, and every mode draws finite pixels. */
static void
test_range_narrower_than_voxels(void **state) {
    (void)state;
    const int d[3] = {10, 8, 6};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, d, VV_I32));
    int32_t *f = v->data;
    for (size_t i = 0; i < vv_volume_voxel_count(v); i++)
        f[i] = (int32_t)(i % 11) * 20000 - 50000;
    v->range[0] = 0;
    v->range[1] = 100;
    vv_render_mode modes[] = {VV_MODE_COMPOSITE, VV_MODE_MIP, VV_MODE_ISO};
    for (size_t m = 0; m < sizeof modes / sizeof modes[0]; m++) {
        vv_default_scene_options o;
        vv_default_scene_options_init(&o);
        o.width = o.height = 24;
        o.mode = modes[m];
        vv_world *w = NULL;
        vt_ok(vv_world_new_for_volume(&w, v, &o));
        vv_renderer *r = new_raycaster();
        vv_image *img = render(r, w, &w->view);
        for (size_t i = 0; i < (size_t)img->width * img->height * 4; i++)
            assert_true(isfinite(img->rgba[i]));
        vv_image_free(img);
        vv_renderer_free(r);
        vv_world_free(w);
    }
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_range_narrower_than_voxels),
        cmocka_unit_test(test_denormal_range),
        cmocka_unit_test(test_range_past_float),
        cmocka_unit_test(test_adaptive_refinement),
        cmocka_unit_test(test_preintegration_analytic),
        cmocka_unit_test(test_preintegration_real),
        cmocka_unit_test(test_shade8_matches_scalar),
        cmocka_unit_test(test_slab_transmittance),
        cmocka_unit_test(test_slab_sample_count),
        cmocka_unit_test(test_early_termination),
        cmocka_unit_test(test_mip_columns),
        cmocka_unit_test(test_attenuated_mip_analytic),
        cmocka_unit_test(test_attenuated_mip_zero_is_mip),
        cmocka_unit_test(test_attenuated_mip_refused),
        cmocka_unit_test(test_projection_flat_ends),
        cmocka_unit_test(test_minip_columns),
        cmocka_unit_test(test_xray_columns),
        cmocka_unit_test(test_iso_sphere_silhouette),
        cmocka_unit_test(test_two_slabs_order),
        cmocka_unit_test(test_object_translate_scale),
        cmocka_unit_test(test_object_orientation),
        cmocka_unit_test(test_iso_enter_inside),
        cmocka_unit_test(test_iso_kernels_agree),
        cmocka_unit_test(test_global_cut_plane),
        cmocka_unit_test(test_local_cut_plane),
        cmocka_unit_test(test_step_halving),
        cmocka_unit_test(test_gradients_on_the_fly),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_skipping_exact),
        cmocka_unit_test(test_runs_exact),
        cmocka_unit_test(test_simd_matches_portable),
        cmocka_unit_test(test_projection_paths_identical),
        cmocka_unit_test(test_single_slice),
        cmocka_unit_test(test_progress_and_cancel),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_real_files),
    };
    return vt_run_tests(tests, NULL, NULL);
}
