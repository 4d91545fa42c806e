/*
 * Tests of the software rasterizer (include/volvis/raster.h) and the
 * `surface` renderer (src/render/raster).
 *
 * Analytic checks: the pixels a triangle covers (pixel centres inside it,
 * exactly) and its depth; perspective-correct interpolation (the depth of
 * every pixel of a slanted quad equals the ray-plane distance, which an
 * affine interpolation would miss); back-face culling; clipping at the near
 * plane (a triangle reaching behind the eye) and at cut planes; sphere
 * silhouettes against the analytic disc and flat / Gouraud / Phong shading
 * against the analytic Phong-lit sphere. Then: determinism across thread
 * counts, wireframe, depth merging, every geometric object type, options
 * and bad input, and the cross-check of the issue: the ray-cast isosurface
 * of neghip.slc against its rasterized Marching Cubes surface.
 *
 * The orthographic test view looks down -z from z = E with +y up and is
 * 1 world unit per pixel: pixel (px, py) of a W x H view centred on the
 * origin sees x = px + 0.5 - W/2, y = H/2 - py - 0.5.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------- */
/* Helpers                                                                  */

static vv_view
ortho_view(int w, int h, double eye_z) {
    vv_view v;
    memset(&v, 0, sizeof v);
    v.eye = vv_vec3_make(0, 0, eye_z);
    v.at = vv_vec3_make(0, 0, eye_z - 1);
    v.up = vv_vec3_make(0, 1, 0);
    v.fov = vv_deg_to_rad(30);
    v.ortho_height = h;
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    v.width = w;
    v.height = h;
    return v;
}

static vv_view
persp_view(int w, int h, vv_vec3 eye, vv_vec3 at, vv_vec3 up, double fov_deg) {
    vv_view v;
    memset(&v, 0, sizeof v);
    v.eye = eye;
    v.at = at;
    v.up = up;
    v.fov = vv_deg_to_rad(fov_deg);
    v.ortho_height = 1;
    v.projection = VV_PROJECTION_PERSPECTIVE;
    v.width = w;
    v.height = h;
    return v;
}

static vv_mesh *
mesh_from(const double *p, int nv, const uint32_t *tri, int nt) {
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_new(&m));
    for (int i = 0; i < nv; i++)
        vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(p[3 * i], p[3 * i + 1], p[3 * i + 2]), NULL));
    for (int i = 0; i < nt; i++)
        vt_ok(vv_mesh_add_triangle(m, tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]));
    return m;
}

static vv_image *
new_image(int w, int h) {
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w, h));
    return img;
}

static const float *
px(const vv_image *img, int x, int y) {
    return img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
}

static void
write_png(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.png", vt_outdir("raster"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* Twice the signed area of (a, b, p) in 2-D. */
static double
orient(double ax, double ay, double bx, double by, double x, double y) {
    return (bx - ax) * (y - ay) - (by - ay) * (x - ax);
}

static vv_world *
new_world(void) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    vv_light l;
    memset(&l, 0, sizeof l);
    l.type = VV_LIGHT_DIRECTIONAL;
    l.headlight = 1;
    l.color = vv_vec3_make(1, 1, 1);
    l.intensity = 1;
    vt_ok(vv_world_add_light(w, &l));
    w->ambient = vv_vec3_make(1, 1, 1);
    w->background = vv_vec3_make(0, 0, 0);
    return w;
}

static vv_object *
add_geometry(vv_world *w, vv_object_type t) {
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, t, NULL));
    vt_ok(vv_world_add_object(w, o));
    return o;
}

static vv_renderer *
new_surface(void) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raster"));
    return r;
}

static vv_image *
render_t(vv_renderer *r, const vv_world *w, const vv_view *view, int threads) {
    vv_image *img = new_image(view->width, view->height);
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    vt_ok(vv_renderer_render(r, w, view, &opt, img));
    return img;
}

static long
count_covered(const vv_image *img) {
    long n = 0;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++)
            n += px(img, x, y)[3] > 0.5f;
    return n;
}

/* ---------------------------------------------------------------------- */
/* Coverage and depth of single triangles                                   */

/* A triangle parallel to the image: the covered pixels are exactly those
 * whose centres lie inside it (no vertex or edge passes through a pixel
 * centre), and the depth is the eye height above it. */
static void
test_triangle_coverage_depth(void **state) {
    (void)state;
    const int W = 64, H = 48;
    const double tri2[2][6] = {{-20.3, -15.1, 25.7, -3.3, -2.2, 19.9},
                               {-28.6, 20.45, 30.15, 21.3, 0.7, -22.85}};
    for (int t = 0; t < 2; t++) {
        const double *q = tri2[t];
        const double p[9] = {q[0], q[1], 2, q[2], q[3], 2, q[4], q[5], 2};
        const uint32_t idx[3] = {0, 1, 2};
        vv_mesh *m = mesh_from(p, 3, idx, 1);
        vv_raster *r = NULL;
        vt_ok(vv_raster_new(&r, W, H));
        vv_view view = ortho_view(W, H, 10);
        vt_ok(vv_raster_set_view(r, &view, 0, 100));
        vv_raster_begin(r, vv_vec3_make(0, 0, 0));
        vv_material mat;
        memset(&mat, 0, sizeof mat);
        mat.color = vv_vec3_make(0.25, 0.5, 0.75);
        vv_raster_set_material(r, &mat, 0);
        vt_ok(vv_raster_draw_mesh(r, m, vv_mat4_identity()));
        vv_image *img = new_image(W, H);
        vt_ok(vv_raster_finish(r, img, 0));
        long mismatch = 0, covered = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const double wx = x + 0.5 - W / 2.0, wy = H / 2.0 - y - 0.5;
                double s = orient(q[0], q[1], q[2], q[3], q[4], q[5]);
                double e0 = orient(q[0], q[1], q[2], q[3], wx, wy) * s;
                double e1 = orient(q[2], q[3], q[4], q[5], wx, wy) * s;
                double e2 = orient(q[4], q[5], q[0], q[1], wx, wy) * s;
                int in = e0 > 0 && e1 > 0 && e2 > 0;
                int got = px(img, x, y)[3] > 0.5f;
                mismatch += in != got;
                covered += got;
                if (got) {
                    assert_near(img->depth[y * W + x], 8.0, 1e-5);
                    assert_near(px(img, x, y)[0], 0.25, 1e-6);
                    assert_near(px(img, x, y)[2], 0.75, 1e-6);
                } else {
                    assert_true(isinf(img->depth[y * W + x]));
                }
            }
        print_message("triangle %d (%s winding): %ld pixels covered, %ld differ from the "
                      "analytic set\n",
                      t, t ? "clockwise" : "counter-clockwise", covered, mismatch);
        assert_int_equal(mismatch, 0);
        assert_true(covered > 300);
        vv_image_free(img);
        vv_raster_free(r);
        vv_mesh_free(m);
    }
}

/* Two triangles sharing an edge through pixel centres: every pixel centre
 * of the square is drawn exactly once (top-left rule, no cracks). */
static void
test_shared_edge_watertight(void **state) {
    (void)state;
    const int W = 32, H = 32;
    /* square [-8, 8]^2 with a diagonal through pixel centres (x = y + ...) */
    const double p[12] = {-7.5, -7.5, 0, 8.5, -7.5, 0, 8.5, 8.5, 0, -7.5, 8.5, 0};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    vv_mesh *m = mesh_from(p, 4, idx, 2);
    vv_raster *r = NULL;
    vt_ok(vv_raster_new(&r, W, H));
    vv_view view = ortho_view(W, H, 10);
    vt_ok(vv_raster_set_view(r, &view, 0, 100));
    vv_raster_begin(r, vv_vec3_make(0, 0, 0));
    vt_ok(vv_raster_draw_mesh(r, m, vv_mat4_identity()));
    vv_image *img = new_image(W, H);
    vt_ok(vv_raster_finish(r, img, 0));
    /* pixel centres strictly inside plus the top-left edges: x in [-7.5, 8.5), y in (-7.5, 8.5] */
    long expect = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const double wx = x + 0.5 - W / 2.0, wy = H / 2.0 - y - 0.5;
            int in = wx >= -7.5 && wx < 8.5 && wy > -7.5 && wy <= 8.5;
            expect += in;
            assert_int_equal(in, px(img, x, y)[3] > 0.5f);
        }
    /* each pixel's triangle: the diagonal pixels go to exactly one triangle */
    assert_int_equal(count_covered(img), expect);
    assert_int_equal(expect, 16 * 16);
    vv_image_free(img);
    vv_raster_free(r);
    vv_mesh_free(m);
}

/* ---------------------------------------------------------------------- */
/* Perspective-correct interpolation and near-plane clipping                */

/* Ray-triangle intersection (Moller-Trumbore); returns t or -1. */
static double
ray_triangle(vv_ray ray, vv_vec3 a, vv_vec3 b, vv_vec3 c) {
    vv_vec3 e1 = vv_vec3_sub(b, a), e2 = vv_vec3_sub(c, a);
    vv_vec3 pv = vv_vec3_cross(ray.dir, e2);
    double det = vv_vec3_dot(e1, pv);
    if (fabs(det) < 1e-12)
        return -1;
    vv_vec3 tv = vv_vec3_sub(ray.origin, a);
    double u = vv_vec3_dot(tv, pv) / det;
    vv_vec3 qv = vv_vec3_cross(tv, e1);
    double v = vv_vec3_dot(ray.dir, qv) / det;
    if (u < 0 || v < 0 || u + v > 1)
        return -1;
    return vv_vec3_dot(e2, qv) / det;
}

/* Renders the triangles of @p m under @p view and compares every pixel with
 * ray casting the same triangles: coverage may differ only on edge pixels,
 * and the depth must match. Returns the number of covered pixels. */
static long
compare_with_rays(const vv_mesh *m, const vv_view *view, double znear, const char *name,
                  double *max_depth_err) {
    vv_raster *r = NULL;
    vt_ok(vv_raster_new(&r, view->width, view->height));
    vt_ok(vv_raster_set_view(r, view, znear, INFINITY));
    vv_raster_begin(r, vv_vec3_make(0, 0, 0));
    vt_ok(vv_raster_draw_mesh(r, m, vv_mat4_identity()));
    vv_image *img = new_image(view->width, view->height);
    vt_ok(vv_raster_finish(r, img, 0));
    write_png(img, name);
    long mismatch = 0, covered = 0;
    double worst = 0;
    vv_vec3 fwd = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    for (int y = 0; y < view->height; y++)
        for (int x = 0; x < view->width; x++) {
            vv_ray ray = vv_view_ray(view, x, y);
            double best = INFINITY;
            int edge = 0;
            for (size_t t = 0; t < m->n_triangles; t++) {
                vv_vec3 a = vv_mesh_vertex(m, m->triangles[3 * t]);
                vv_vec3 b = vv_mesh_vertex(m, m->triangles[3 * t + 1]);
                vv_vec3 c = vv_mesh_vertex(m, m->triangles[3 * t + 2]);
                double th = ray_triangle(ray, a, b, c);
                /* the near plane is at distance znear along the view direction */
                if (th > 0 && th * vv_vec3_dot(ray.dir, fwd) > znear && th < best)
                    best = th;
                /* pixels whose neighbours disagree are edge pixels */
                for (int k = 0; k < 4; k++) {
                    vv_ray rk =
                        vv_view_ray(view, x + 0.6 * (k & 1 ? 1 : -1), y + 0.6 * (k & 2 ? 1 : -1));
                    double tk = ray_triangle(rk, a, b, c);
                    edge |= (tk > 0) != (th > 0);
                }
            }
            const int got = px(img, x, y)[3] > 0.5f;
            covered += got;
            if (got != (best < INFINITY)) {
                if (!edge)
                    fail_msg("%s: pixel (%d, %d) %s but the ray %s", name, x, y,
                             got ? "drawn" : "empty", got ? "misses" : "hits");
                mismatch++;
            } else if (got) {
                double e = fabs(img->depth[y * view->width + x] - best) / best;
                worst = e > worst ? e : worst;
            }
        }
    print_message("%s: %ld pixels, %ld edge pixels differ, depth relative error %.2e\n", name,
                  covered, mismatch, worst);
    *max_depth_err = worst;
    vv_image_free(img);
    vv_raster_free(r);
    return covered;
}

static void
test_perspective_correct(void **state) {
    (void)state;
    /* a slanted quad receding from the eye: affine interpolation of the
     * barycentric coordinates would put interior pixels at wrong depths */
    const double p[12] = {-40, 0, -10, 40, 0, -10, 40, 300, 60, -40, 300, 60};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    vv_mesh *m = mesh_from(p, 4, idx, 2);
    vv_view view = persp_view(96, 80, vv_vec3_make(5, -60, 20), vv_vec3_make(0, 100, 10),
                              vv_vec3_make(0, 0, 1), 50);
    double err = 0;
    long n = compare_with_rays(m, &view, 0.1, "perspective_quad", &err);
    assert_true(n > 2000);
    assert_true(err < 1e-4);
    vv_mesh_free(m);
}

static void
test_near_plane_clipping(void **state) {
    (void)state;
    /* a floor reaching from far in front of the eye to far behind it */
    const double p[9] = {-200, -300, -5, 200, -300, -5, 0, 400, -5};
    const uint32_t idx[3] = {0, 1, 2};
    vv_mesh *m = mesh_from(p, 3, idx, 1);
    vv_view view = persp_view(80, 60, vv_vec3_make(0, 0, 0), vv_vec3_make(0, 1, -0.3),
                              vv_vec3_make(0, 0, 1), 60);
    double err = 0;
    long n = compare_with_rays(m, &view, 0.5, "near_clip_floor", &err);
    assert_true(n > 1000);
    /* vertices snap to 1/256 pixel: near the horizon, where the depth grows
     * fast across the image, that moves the depth by a few 1e-4 of itself */
    assert_true(err < 1e-3);
    /* a near plane far enough to cut the visible floor: pixels below the
     * near line disappear, the rest keep their depth */
    long n2 = compare_with_rays(m, &view, 12, "near_clip_floor_far", &err);
    assert_true(n2 < n - 100);
    assert_true(err < 1e-3);
    vv_mesh_free(m);
}

/* ---------------------------------------------------------------------- */
/* Culling                                                                  */

static void
test_culling(void **state) {
    (void)state;
    const int W = 32, H = 32;
    /* front: counter-clockwise seen from +z (the eye); back: clockwise */
    const double p[18] = {-12, -12, 0, -2, -12, 0, -7, 10, 0, 2, -12, 0, 7, 10, 0, 12, -12, 0};
    const uint32_t idx[6] = {0, 1, 2, 3, 4, 5};
    vv_mesh *m = mesh_from(p, 6, idx, 2);
    vv_view view = ortho_view(W, H, 10);
    const vv_raster_cull modes[3] = {VV_RASTER_CULL_NONE, VV_RASTER_CULL_BACK,
                                     VV_RASTER_CULL_FRONT};
    for (int mirror = 0; mirror < 2; mirror++)
        for (int c = 0; c < 3; c++) {
            vv_raster *r = NULL;
            vt_ok(vv_raster_new(&r, W, H));
            vt_ok(vv_raster_set_view(r, &view, 0, 100));
            vv_raster_begin(r, vv_vec3_make(0, 0, 0));
            vv_raster_set_cull(r, modes[c]);
            /* a mirror about x = 0 swaps which triangle is where, and their
             * winding, but a front face stays a front face */
            vv_mat4 M = mirror ? vv_mat4_scale(vv_vec3_make(-1, 1, 1)) : vv_mat4_identity();
            vt_ok(vv_raster_draw_mesh(r, m, M));
            vv_image *img = new_image(W, H);
            vt_ok(vv_raster_finish(r, img, 0));
            long left = 0, right = 0;
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    left += x < W / 2 && px(img, x, y)[3] > 0.5f;
                    right += x >= W / 2 && px(img, x, y)[3] > 0.5f;
                }
            long front = mirror ? right : left, back = mirror ? left : right;
            assert_true(front > 50 || c == 2);
            assert_true(back > 50 || c == 1);
            if (c == 1)
                assert_int_equal(back, 0);
            if (c == 2)
                assert_int_equal(front, 0);
            vv_image_free(img);
            vv_raster_free(r);
        }
    vv_mesh_free(m);
}

/* ---------------------------------------------------------------------- */
/* Spheres: silhouette and shading against the analytic sphere              */

static void
test_sphere_shading(void **state) {
    (void)state;
    const int W = 128, H = 128;
    const double R = 50;
    vv_world *w = new_world();
    vv_object *o = add_geometry(w, VV_OBJECT_SPHERE);
    o->geometry.radius = R;
    o->material.color = vv_vec3_make(1, 0.8, 0.6);
    vv_view view = ortho_view(W, H, 200);
    const char *names[3] = {"flat", "gouraud", "phong"};
    double err[3];
    vv_image *imgs[3];
    vv_renderer *r = new_surface();
    vt_ok(vv_renderer_set_option(r, "segments", "24"));
    for (int s = 0; s < 3; s++) {
        vt_ok(vv_renderer_set_option(r, "shading", names[s]));
        imgs[s] = render_t(r, w, &view, 0);
        char name[64];
        snprintf(name, sizeof name, "sphere_%s", names[s]);
        write_png(imgs[s], name);
        double sum = 0;
        long n = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const double wx = x + 0.5 - W / 2.0, wy = H / 2.0 - y - 0.5;
                const double rr = sqrt(wx * wx + wy * wy);
                if (rr > 0.95 * R * cos(VV_PI / 24))
                    continue;
                /* analytic: headlight and eye along +z, ka 0.1 kd 0.6 ks 0.3 n 30 */
                const double nz = sqrt(R * R - rr * rr) / R;
                const double spec = 0.3 * pow(2 * nz * nz - 1 > 0 ? 2 * nz * nz - 1 : 0, 30);
                const double base[3] = {1, 0.8, 0.6};
                for (int c = 0; c < 3; c++) {
                    double a = (0.1 + 0.6 * nz) * base[c] + spec;
                    sum += fabs(px(imgs[s], x, y)[c] - a);
                }
                n++;
                /* depth of the tessellated sphere: within its flattening */
                assert_true(imgs[s]->depth[y * W + x] >= 200 - sqrt(R * R - rr * rr) - 1e-3);
                assert_true(imgs[s]->depth[y * W + x] <=
                            200 - sqrt(R * R - rr * rr) + R * (1 - cos(VV_PI / 12)) / nz + 1e-3);
            }
        err[s] = sum / (3.0 * (double)n);
    }
    print_message("mean colour error against the analytic sphere: flat %.4f, gouraud %.4f, "
                  "phong %.4f\n",
                  err[0], err[1], err[2]);
    assert_true(err[2] < err[1]);
    assert_true(err[1] < err[0]);
    assert_true(err[2] < 0.01);
    /* the silhouette does not depend on the shading */
    for (int s = 1; s < 3; s++)
        for (int i = 0; i < W * H; i++)
            assert_true(imgs[s]->rgba[4 * i + 3] == imgs[0]->rgba[4 * i + 3]);
    /* silhouette against the analytic disc: the inscribed 24-gon rings of
     * latitude (area factor of a regular n-gon: n/(2 pi) sin(2 pi/n)) */
    const long n = count_covered(imgs[0]);
    const double disc = VV_PI * R * R, poly = disc * 24 / (2 * VV_PI) * sin(2 * VV_PI / 24);
    print_message("silhouette: %ld pixels, disc %.0f, 24-gon %.0f\n", n, disc, poly);
    assert_true(fabs(n - poly) < 2 * VV_PI * R * 0.5);
    assert_true(n < disc);
    for (int s = 0; s < 3; s++)
        vv_image_free(imgs[s]);

    /* finer tessellation: the silhouette converges to the disc */
    vt_ok(vv_renderer_set_option(r, "segments", "256"));
    vv_image *fine = render_t(r, w, &view, 0);
    long nf = count_covered(fine);
    print_message("256 segments: %ld pixels, disc %.0f\n", nf, disc);
    assert_true(fabs(nf - disc) < 0.25 * 2 * VV_PI * R);
    vv_image_free(fine);
    vv_renderer_free(r);
    vv_world_free(w);
}

/* Back faces of closed objects are culled by default (cull=auto): half the
 * sphere's triangles, same image as with culling off. */
static void
test_auto_cull_same_image(void **state) {
    (void)state;
    vv_world *w = new_world();
    vv_object *o = add_geometry(w, VV_OBJECT_SPHERE);
    o->geometry.radius = 20;
    o->position = vv_vec3_make(3, -2, 1);
    vv_view view = persp_view(64, 64, vv_vec3_make(40, -90, 30), vv_vec3_make(0, 0, 0),
                              vv_vec3_make(0, 0, 1), 40);
    vv_renderer *r = new_surface();
    vv_image *a = render_t(r, w, &view, 0);
    vt_ok(vv_renderer_set_option(r, "cull", "none"));
    vv_image *b = render_t(r, w, &view, 0);
    assert_memory_equal(a->rgba, b->rgba, 4 * 64 * 64 * sizeof(float));
    assert_memory_equal(a->depth, b->depth, 64 * 64 * sizeof(float));
    assert_true(count_covered(a) > 400);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(r);
    vv_world_free(w);
}

/* ---------------------------------------------------------------------- */
/* Cut planes                                                               */

static void
test_cut_planes(void **state) {
    (void)state;
    const int W = 96, H = 96;
    vv_world *w = new_world();
    vv_object *a = add_geometry(w, VV_OBJECT_SPHERE);
    a->geometry.radius = 20;
    a->position = vv_vec3_make(-22, 0, 0);
    vv_object *b = add_geometry(w, VV_OBJECT_SPHERE);
    b->geometry.radius = 20;
    b->position = vv_vec3_make(22, 0, 0);
    vv_view view = ortho_view(W, H, 100);
    vv_renderer *r = new_surface();
    vv_image *full = render_t(r, w, &view, 0);
    /* local: sphere b keeps z <= 5 (its cap towards the eye is cut away);
     * sphere a is unchanged */
    b->n_cut_planes = 1;
    b->cut_planes[0].point = vv_vec3_make(0, 0, 5);
    b->cut_planes[0].normal = vv_vec3_make(0, 0, -1);
    vv_image *loc = render_t(r, w, &view, 0);
    write_png(loc, "cut_local");
    long changed_a = 0, cap_b = 0, covered_b = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const size_t i = (size_t)y * W + (size_t)x;
            if (x < W / 2) {
                changed_a += memcmp(px(full, x, y), px(loc, x, y), 4 * sizeof(float)) != 0;
                continue;
            }
            if (px(loc, x, y)[3] > 0.5f) {
                covered_b++;
                /* visible points lie in the kept half-space z <= 5 */
                assert_true(100 - loc->depth[i] <= 5 + 1e-3);
                /* the solid cut face z = 5, lit head on (ka 0.1 + kd 0.6 + ks 0.3) */
                const double wx = x + 0.5 - W / 2.0 - 22, wy = H / 2.0 - y - 0.5;
                if (wx * wx + wy * wy < 18.5 * 18.5) {
                    cap_b++;
                    assert_near(loc->depth[i], 95, 1e-3);
                    assert_near(px(loc, x, y)[0], 1.0, 1e-3);
                }
            }
        }
    print_message("local cut: %ld pixels of b (%ld on the cut face), %ld pixels of a changed\n",
                  covered_b, cap_b, changed_a);
    assert_int_equal(changed_a, 0);
    assert_true(labs(covered_b - (long)(VV_PI * 400)) < 60);
    assert_true(cap_b > 1000);
    /* caps=0: the cut surface is open and its inside shows, deeper than the face */
    vt_ok(vv_renderer_set_option(r, "caps", "0"));
    vv_image *open = render_t(r, w, &view, 0);
    write_png(open, "cut_local_open");
    long deeper = 0;
    for (int y = 0; y < H; y++)
        for (int x = W / 2; x < W; x++)
            deeper += px(open, x, y)[3] > 0.5f && open->depth[(size_t)y * W + (size_t)x] > 95.01f;
    assert_true(deeper > 1000);
    vv_image_free(open);
    vt_ok(vv_renderer_set_option(r, "caps", "1"));
    /* global: x >= 0 removes sphere a and leaves sphere b's silhouette */
    b->n_cut_planes = 0;
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 0), vv_vec3_make(1, 0, 0)));
    vv_image *glob = render_t(r, w, &view, 0);
    write_png(glob, "cut_global");
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            if (x < W / 2)
                assert_true(px(glob, x, y)[3] == 0);
            else
                assert_memory_equal(px(glob, x, y), px(full, x, y), 4 * sizeof(float));
        }
    vv_image_free(full);
    vv_image_free(loc);
    vv_image_free(glob);
    vv_renderer_free(r);
    vv_world_free(w);
}

/* ---------------------------------------------------------------------- */
/* Determinism, wireframe, merge                                            */

static vv_world *
busy_world(vv_mesh **keep) {
    vv_world *w = new_world();
    uint64_t seed = 12345;
    for (int i = 0; i < 40; i++) {
        vv_object *o = add_geometry(w, i % 3 == 0 ? VV_OBJECT_BOX : VV_OBJECT_SPHERE);
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        double a = (double)(seed >> 11) / 9007199254740992.0;
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        double b = (double)(seed >> 11) / 9007199254740992.0;
        o->position = vv_vec3_make(80 * (a - 0.5), 80 * (b - 0.5), 40 * (a * b - 0.25));
        o->scale = vv_vec3_make(8 + 6 * a, 8 + 6 * b, 8);
        o->orientation = vv_quat_from_axis_angle(vv_vec3_make(a, b, 1), 3 * a);
        o->material.color = vv_vec3_make(a, b, 1 - a);
    }
    vv_light pl;
    memset(&pl, 0, sizeof pl);
    pl.type = VV_LIGHT_POINT;
    pl.position = vv_vec3_make(50, -80, 90);
    pl.color = vv_vec3_make(1, 0.9, 0.8);
    pl.intensity = 0.7;
    vt_ok(vv_world_add_light(w, &pl));
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_load(&m, vt_data("meshes/bunny.ply")));
    vv_object *o = add_geometry(w, VV_OBJECT_MESH);
    vt_ok(vv_object_set_mesh(o, m, NULL));
    o->scale = vv_vec3_make(300, 300, 300);
    o->orientation = vv_quat_from_axis_angle(vv_vec3_make(1, 0, 0), VV_PI / 2);
    *keep = m;
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 20), vv_vec3_make(0.2, 0.1, -1)));
    return w;
}

static void
test_determinism(void **state) {
    (void)state;
    vv_mesh *m = NULL;
    vv_world *w = busy_world(&m);
    vv_view view = persp_view(160, 120, vv_vec3_make(60, -140, 90), vv_vec3_make(0, 0, 0),
                              vv_vec3_make(0, 0, 1), 45);
    const char *shadings[3] = {"flat", "gouraud", "phong"};
    for (int s = 0; s < 3; s++)
        for (int wire = 0; wire < 2; wire++) {
            vv_renderer *r = new_surface();
            vt_ok(vv_renderer_set_option(r, "shading", shadings[s]));
            vt_ok(vv_renderer_set_option(r, "wireframe", wire ? "1" : "0"));
            vv_image *ref = render_t(r, w, &view, 1);
            if (s == 2) {
                char name[64];
                snprintf(name, sizeof name, "busy_%s%s", shadings[s], wire ? "_wire" : "");
                write_png(ref, name);
            }
            assert_true(count_covered(ref) > 3000);
            const int threads[3] = {2, 3, 8};
            for (int t = 0; t < 3; t++) {
                vv_image *img = render_t(r, w, &view, threads[t]);
                assert_memory_equal(ref->rgba, img->rgba, 4 * 160 * 120 * sizeof(float));
                assert_memory_equal(ref->depth, img->depth, 160 * 120 * sizeof(float));
                vv_image_free(img);
            }
            vv_image_free(ref);
            vv_renderer_free(r);
        }
    vv_world_free(w);
    vv_mesh_free(m);
}

static void
test_wireframe(void **state) {
    (void)state;
    const int W = 64, H = 64;
    const double p[12] = {-20.2, -20.3, 0, 20.1, -20.3, 0, 20.1, 20.4, 0, -20.2, 20.4, 0};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    vv_mesh *m = mesh_from(p, 4, idx, 2);
    vv_raster *r = NULL;
    vt_ok(vv_raster_new(&r, W, H));
    vv_view view = ortho_view(W, H, 10);
    vt_ok(vv_raster_set_view(r, &view, 0, 100));
    vv_raster_begin(r, vv_vec3_make(0, 0, 0));
    vv_raster_set_wireframe(r, 1);
    vt_ok(vv_raster_draw_mesh(r, m, vv_mat4_identity()));
    vv_image *img = new_image(W, H);
    vt_ok(vv_raster_finish(r, img, 0));
    write_png(img, "wireframe_quad");
    /* drawn pixels are within half a pixel (plus rounding) of an edge; every
     * pixel centre within 0.45 of an edge is drawn */
    long drawn = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const double wx = x + 0.5 - W / 2.0, wy = H / 2.0 - y - 0.5;
            double dmin = INFINITY;
            const int edges[5][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}};
            for (int e = 0; e < 5; e++) {
                const double *a = p + 3 * edges[e][0], *b = p + 3 * edges[e][1];
                double dx = b[0] - a[0], dy = b[1] - a[1];
                double s = ((wx - a[0]) * dx + (wy - a[1]) * dy) / (dx * dx + dy * dy);
                s = s < 0 ? 0 : s > 1 ? 1 : s;
                double ex = wx - a[0] - s * dx, ey = wy - a[1] - s * dy;
                double d = sqrt(ex * ex + ey * ey);
                dmin = d < dmin ? d : dmin;
            }
            const int got = px(img, x, y)[3] > 0.5f;
            drawn += got;
            if (got)
                assert_true(dmin <= 0.5 + 0.01);
            if (dmin < 0.45)
                assert_true(got);
        }
    print_message("wireframe quad: %ld pixels drawn\n", drawn);
    /* perimeter 4 x 40.5 plus the diagonal 57: one pixel wide */
    assert_true(drawn > 200 && drawn < 330);
    vv_image_free(img);
    vv_raster_free(r);
    vv_mesh_free(m);
}

/* Clipped triangles do not draw the edges that clipping created. */
static void
test_wireframe_clip_edges(void **state) {
    (void)state;
    const int W = 64, H = 64;
    const double p[9] = {-25.2, -20.3, 0, 25.1, -20.3, 0, 0.3, 25.4, 0};
    const uint32_t idx[3] = {0, 1, 2};
    vv_mesh *m = mesh_from(p, 3, idx, 1);
    vv_raster *r = NULL;
    vt_ok(vv_raster_new(&r, W, H));
    vv_view view = ortho_view(W, H, 10);
    vt_ok(vv_raster_set_view(r, &view, 0, 100));
    vv_raster_begin(r, vv_vec3_make(0, 0, 0));
    vv_raster_set_wireframe(r, 1);
    vv_cut_plane cp = {{0, 0.2, 0}, {0, -1, 0}}; /* keeps y <= 0.2 */
    vt_ok(vv_raster_set_cut_planes(r, &cp, 1));
    vt_ok(vv_raster_draw_mesh(r, m, vv_mat4_identity()));
    vv_image *img = new_image(W, H);
    vt_ok(vv_raster_finish(r, img, 0));
    write_png(img, "wireframe_clipped");
    /* along y = 0.2 (rows whose centres are within half a pixel) only the two
     * slanted edges are drawn, not the cut */
    int row = H / 2 - 1; /* centre y = 0.5 */
    long n = 0;
    for (int x = 0; x < W; x++)
        n += px(img, x, row)[3] > 0.5f;
    assert_true(n <= 6);
    long above = 0;
    for (int y = 0; y < row; y++)
        for (int x = 0; x < W; x++)
            above += px(img, x, y)[3] > 0.5f;
    assert_int_equal(above, 0);
    vv_image_free(img);
    vv_raster_free(r);
    vv_mesh_free(m);
}

static void
test_merge(void **state) {
    (void)state;
    const int W = 32, H = 32;
    const double p[9] = {-14, -14, 0, 14, -14, 0, 0, 14, 0};
    const uint32_t idx[3] = {0, 1, 2};
    vv_mesh *m = mesh_from(p, 3, idx, 1);
    vv_raster *r = NULL;
    vt_ok(vv_raster_new(&r, W, H));
    vv_view view = ortho_view(W, H, 10);
    vt_ok(vv_raster_set_view(r, &view, 0, 100));
    vv_raster_begin(r, vv_vec3_make(0, 0, 0));
    vv_material mat;
    memset(&mat, 0, sizeof mat);
    mat.color = vv_vec3_make(0, 1, 0);
    vv_raster_set_material(r, &mat, 0);
    vt_ok(vv_raster_draw_mesh(r, m, vv_mat4_identity()));
    /* another renderer's image: red at depth 5 on the left, 20 on the right */
    vv_image *img = new_image(W, H);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *q = img->rgba + 4 * (y * W + x);
            q[0] = 1;
            q[1] = q[2] = 0;
            q[3] = 1;
            img->depth[y * W + x] = x < W / 2 ? 5.0f : 20.0f;
        }
    vt_ok(vv_raster_finish(r, img, 1));
    long green_left = 0, green_right = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float *q = px(img, x, y);
            if (q[1] > 0.5f) {
                if (x < W / 2)
                    green_left++;
                else
                    green_right++;
                assert_near(img->depth[y * W + x], 10, 1e-5);
            }
        }
    assert_int_equal(green_left, 0);
    assert_true(green_right > 100);
    vv_image_free(img);
    vv_raster_free(r);
    vv_mesh_free(m);
}

/* ---------------------------------------------------------------------- */
/* Geometric object types                                                   */

static void
test_geometry_objects(void **state) {
    (void)state;
    const int W = 80, H = 80;
    vv_view view = ortho_view(W, H, 100);
    vv_renderer *r = new_surface();
    /* box seen face on: exactly the square's pixel centres */
    {
        vv_world *w = new_world();
        vv_object *o = add_geometry(w, VV_OBJECT_BOX);
        o->geometry.box.min = vv_vec3_make(-10.3, -5.2, -3);
        o->geometry.box.max = vv_vec3_make(20.2, 15.4, 7);
        vv_image *img = render_t(r, w, &view, 0);
        long bad = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const double wx = x + 0.5 - W / 2.0, wy = H / 2.0 - y - 0.5;
                int in = wx > -10.3 && wx < 20.2 && wy > -5.2 && wy < 15.4;
                bad += in != (px(img, x, y)[3] > 0.5f);
                if (in)
                    assert_near(img->depth[y * W + x], 93, 1e-4);
            }
        assert_int_equal(bad, 0);
        vv_image_free(img);
        vv_world_free(w);
    }
    /* cylinder along the view: a disc at the top cap's depth; across: a rectangle */
    {
        vv_world *w = new_world();
        vv_object *o = add_geometry(w, VV_OBJECT_CYLINDER);
        o->geometry.base = vv_vec3_make(0, 0, -10);
        o->geometry.top = vv_vec3_make(0, 0, 10);
        o->geometry.radius = 25;
        vt_ok(vv_renderer_set_option(r, "segments", "128"));
        vv_image *img = render_t(r, w, &view, 0);
        long n = count_covered(img);
        assert_true(fabs(n - VV_PI * 625) < 2 * VV_PI * 25 * 0.5);
        assert_near(img->depth[(H / 2) * W + W / 2], 90, 1e-4);
        vv_image_free(img);
        o->orientation = vv_quat_from_axis_angle(vv_vec3_make(0, 1, 0), VV_PI / 2);
        img = render_t(r, w, &view, 0);
        write_png(img, "cylinder_side");
        n = count_covered(img);
        assert_true(labs(n - 20 * 50) <= 2 * (20 + 50));
        vv_image_free(img);
        vv_world_free(w);
    }
    /* concave L-shaped polygon: its area */
    {
        vv_world *w = new_world();
        vv_object *o = add_geometry(w, VV_OBJECT_POLYGON);
        const vv_vec3 v[6] = {{-20.1, -20.2, 0}, {20.3, -20.2, 0}, {20.3, 0.1, 0},
                              {0.2, 0.1, 0},     {0.2, 20.4, 0},   {-20.1, 20.4, 0}};
        vt_ok(vv_object_set_polygon(o, 6, v));
        vv_image *img = render_t(r, w, &view, 0);
        write_png(img, "polygon_L");
        long bad = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const double wx = x + 0.5 - W / 2.0, wy = H / 2.0 - y - 0.5;
                int in =
                    wx > -20.1 && wx < 20.3 && wy > -20.2 && wy < 20.4 && !(wx > 0.2 && wy > 0.1);
                bad += in != (px(img, x, y)[3] > 0.5f);
            }
        assert_int_equal(bad, 0);
        vv_image_free(img);
        vv_world_free(w);
    }
    /* a plane seen in perspective: the horizon, and ray-plane depths */
    {
        vv_world *w = new_world();
        vv_object *o = add_geometry(w, VV_OBJECT_PLANE);
        o->position = vv_vec3_make(0, 0, -10);
        vv_view pv = persp_view(W, H, vv_vec3_make(0, 0, 0), vv_vec3_make(0, 1, 0),
                                vv_vec3_make(0, 0, 1), 60);
        vv_image *img = render_t(r, w, &pv, 0);
        write_png(img, "plane_horizon");
        long bad = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                vv_ray ray = vv_view_ray(&pv, x, y);
                /* pixels far below the horizon: hit at t = -10 / dir.z */
                if (ray.dir.z < -0.05) {
                    bad += !(px(img, x, y)[3] > 0.5f);
                    assert_near(img->depth[y * W + x] / (-10 / ray.dir.z), 1, 1e-3);
                } else if (ray.dir.z > 0) {
                    bad += px(img, x, y)[3] > 0.5f;
                }
            }
        assert_int_equal(bad, 0);
        vv_image_free(img);
        vv_world_free(w);
    }
    /* a mesh object with a transform; invisible objects are skipped */
    {
        vv_world *w = new_world();
        vv_mesh *m = NULL;
        vt_ok(vv_mesh_load(&m, vt_data("meshes/bunny.ply")));
        vv_object *o = add_geometry(w, VV_OBJECT_MESH);
        vt_ok(vv_object_set_mesh(o, m, NULL));
        vv_box bb = vv_mesh_bounds(m);
        vv_vec3 c = vv_vec3_scale(vv_vec3_add(bb.min, bb.max), 0.5);
        o->scale = vv_vec3_make(300, 300, 300);
        o->position = vv_vec3_scale(c, -300);
        vv_image *img = render_t(r, w, &view, 0);
        write_png(img, "bunny");
        long n = count_covered(img);
        print_message("bunny: %ld pixels\n", n);
        assert_true(n > 1000);
        o->visible = 0;
        vv_image *none = render_t(r, w, &view, 0);
        assert_int_equal(count_covered(none), 0);
        vv_image_free(img);
        vv_image_free(none);
        vv_world_free(w);
        vv_mesh_free(m);
    }
    vv_renderer_free(r);
}

/* ---------------------------------------------------------------------- */
/* The camera matches vv_view_ray                                            */

static void
test_camera_matches_rays(void **state) {
    (void)state;
    /* small sphere objects placed on the rays of chosen pixels must cover
     * exactly those pixels' centres */
    for (int proj = 0; proj < 2; proj++) {
        vv_view view = persp_view(90, 60, vv_vec3_make(10, -70, 25), vv_vec3_make(2, 3, 1),
                                  vv_vec3_make(0.1, 0, 1), 35);
        if (proj) {
            view.projection = VV_PROJECTION_ORTHOGRAPHIC;
            view.ortho_height = 40;
        }
        vv_world *w = new_world();
        const int pts[4][2] = {{5, 7}, {80, 12}, {44, 30}, {17, 55}};
        for (int i = 0; i < 4; i++) {
            vv_ray ray = vv_view_ray(&view, pts[i][0], pts[i][1]);
            vv_object *o = add_geometry(w, VV_OBJECT_SPHERE);
            o->geometry.radius = proj ? 0.2 : 0.2 * (50 + 10 * i) / 70.0 * 0.8;
            o->position = vv_ray_at(ray, 50 + 10 * i);
        }
        vv_renderer *r = new_surface();
        vv_image *img = render_t(r, w, &view, 0);
        for (int i = 0; i < 4; i++) {
            const int x = pts[i][0], y = pts[i][1];
            assert_true(px(img, x, y)[3] > 0.5f);
            /* depth at the centre: the sphere's front at 50 + 10 i - radius */
            double rad = w->objects[i]->geometry.radius;
            assert_near(img->depth[y * 90 + x], 50 + 10 * i - rad, 0.02 * rad + 1e-4);
            assert_true(px(img, x + 1, y)[3] == 0 && px(img, x - 1, y)[3] == 0);
            assert_true(px(img, x, y + 1)[3] == 0 && px(img, x, y - 1)[3] == 0);
        }
        assert_int_equal(count_covered(img), 4);
        vv_image_free(img);
        vv_renderer_free(r);
        vv_world_free(w);
    }
}

/* ---------------------------------------------------------------------- */
/* Options and bad input                                                    */

static void
test_bad_input(void **state) {
    (void)state;
    vv_raster *r = NULL;
    vt_err(vv_raster_new(&r, 0, 10));
    vt_err(vv_raster_new(&r, 10, VV_IMAGE_MAX_SIDE + 1));
    vt_ok(vv_raster_new(&r, 16, 16));
    vv_mat4 bad = vv_mat4_identity();
    bad.m[3][0] = 1;
    vt_err(vv_raster_set_camera(r, vv_mat4_identity(), bad));
    vt_err(vv_raster_set_camera(r, vv_mat4_scale(vv_vec3_make(0, 1, 1)), vv_mat4_identity()));
    vv_view v = ortho_view(16, 16, 10);
    vt_err(vv_raster_set_view(r, &v, 0, INFINITY));
    vt_err(vv_raster_set_view(r, &v, 5, 2));
    v.projection = VV_PROJECTION_PERSPECTIVE;
    vt_err(vv_raster_set_view(r, &v, 0, 100));
    v.fov = 0;
    vt_err(vv_raster_set_view(r, &v, 1, 100));
    vv_cut_plane cp = {{0, 0, 0}, {0, 0, 0}};
    vt_err(vv_raster_set_cut_planes(r, &cp, 1));
    vv_light many[VV_MAX_LIGHTS + 1];
    memset(many, 0, sizeof many);
    vt_err(vv_raster_set_lights(r, many, VV_MAX_LIGHTS + 1, vv_vec3_make(1, 1, 1)));
    /* a triangle index out of range; a singular model matrix */
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_new(&m));
    vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(0, 0, 0), NULL));
    vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(1, 0, 0), NULL));
    vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(0, 1, 0), NULL));
    vt_ok(vv_mesh_add_triangle(m, 0, 1, 2));
    vt_err(vv_raster_draw_mesh(r, m, vv_mat4_scale(vv_vec3_make(1, 0, 1))));
    /* a vertex that is not a point: its triangles are skipped, others drawn */
    {
        vv_view ov = ortho_view(16, 16, 10);
        vt_ok(vv_raster_set_view(r, &ov, 0, 100));
        vv_mesh *q = NULL;
        const double pq[12] = {-6, -6, 0, 6, -6, 0, 0, 6, 0, 0, 0, 0};
        const uint32_t iq[6] = {0, 1, 2, 0, 1, 3};
        q = mesh_from(pq, 4, iq, 2);
        q->positions[9] = NAN;
        q->positions[10] = INFINITY;
        vv_raster_begin(r, vv_vec3_make(0, 0, 0));
        vt_ok(vv_raster_draw_mesh(r, q, vv_mat4_identity()));
        vv_image *qi = new_image(16, 16);
        vt_ok(vv_raster_finish(r, qi, 0));
        assert_true(count_covered(qi) > 30);
        vv_image_free(qi);
        vv_mesh_free(q);
    }
    m->triangles[2] = 7;
    vt_err(vv_raster_draw_mesh(r, m, vv_mat4_identity()));
    vt_err(vv_raster_draw_mesh(r, NULL, vv_mat4_identity()));
    vv_image *img = new_image(8, 8);
    vt_err(vv_raster_finish(r, img, 0));
    vv_image_free(img);
    vv_mesh_free(m);
    vv_raster_free(r);
    vv_raster_free(NULL);

    vv_renderer *s = new_surface();
    vt_err(vv_renderer_set_option(s, "shading", "toon"));
    vt_err(vv_renderer_set_option(s, "wireframe", "maybe"));
    vt_err(vv_renderer_set_option(s, "cull", "sideways"));
    vt_err(vv_renderer_set_option(s, "segments", "2"));
    vt_err(vv_renderer_set_option(s, "colour", "1"));
    vt_ok(vv_renderer_set_option(s, "cull", "back"));
    /* booleans are 0 or 1, as the option table says (render.h) */
    vt_err(vv_renderer_set_option(s, "wireframe", "off"));
    vt_ok(vv_renderer_set_option(s, "wireframe", "0"));
    vv_renderer_free(s);
}

static int
cancel_at_half(void *user, double fraction) {
    int *calls = user;
    ++*calls;
    return fraction >= 0.5;
}

static int
count_calls(void *user, double fraction) {
    (void)fraction;
    ++*(int *)user;
    return 0;
}

/* Progress is reported per object and at the end; the callback cancels. */
static void
test_progress_and_cancel(void **state) {
    (void)state;
    vv_world *w = new_world();
    for (int i = 0; i < 4; i++) {
        vv_object *o = add_geometry(w, VV_OBJECT_SPHERE);
        o->geometry.radius = 3;
        o->position = vv_vec3_make(7 * i - 10, 0, 0);
    }
    vv_view view = ortho_view(32, 32, 50);
    vv_renderer *r = new_surface();
    vv_image *img = new_image(32, 32);
    vv_render_options opt;
    vv_render_options_init(&opt);
    int calls = 0;
    opt.progress.fn = count_calls;
    opt.progress.user = &calls;
    vt_ok(vv_renderer_render(r, w, &view, &opt, img));
    assert_int_equal(calls, 5);
    calls = 0;
    opt.progress.fn = cancel_at_half;
    vv_status s = vv_renderer_render(r, w, &view, &opt, img);
    assert_int_equal(s, VV_ERR_CANCELLED);
    assert_int_equal(calls, 3);
    /* the renderer still works afterwards */
    opt.progress.fn = NULL;
    vt_ok(vv_renderer_render(r, w, &view, &opt, img));
    assert_true(count_covered(img) > 20);
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
}

/* ---------------------------------------------------------------------- */
/* Volumes: isosurfaces against the ray caster                              */

/* value = r - distance from the centre: the isosurface 0 is a sphere */
static vv_volume *
sphere_volume(int n, double r) {
    vv_volume *v = NULL;
    const int dims[3] = {n, n, n};
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    const double c = 0.5 * (n - 1);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                vv_volume_set(v, i, j, k,
                              r - sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c)));
    vv_volume_update_range(v);
    return v;
}

/* Renders @p w with the ray caster and the surface renderer; returns the
 * PSNR, the largest depth difference where both hit, the pixels hit by one
 * only and the pixels hit by both whose depths differ by more than one
 * voxel (1 world unit here). */
static long cross_far;

static double
cross_check(vv_world *w, const vv_view *view, const char *name, double *depth_diff,
            long *coverage_diff) {
    vv_renderer *rc = NULL, *sf = new_surface();
    vt_ok(vv_renderer_new(&rc, "raycast"));
    vv_image *a = render_t(rc, w, view, 0);
    vv_image *b = render_t(sf, w, view, 0);
    char n1[128], n2[128];
    snprintf(n1, sizeof n1, "%s_raycast", name);
    snprintf(n2, sizeof n2, "%s_surface", name);
    write_png(a, n1);
    write_png(b, n2);
    double worst = 0;
    long cov = 0;
    cross_far = 0;
    for (int i = 0; i < view->width * view->height; i++) {
        int ha = a->rgba[4 * i + 3] > 0.5f, hb = b->rgba[4 * i + 3] > 0.5f;
        cov += ha != hb;
        if (ha && hb) {
            double d = fabs(a->depth[i] - b->depth[i]);
            worst = d > worst ? d : worst;
            cross_far += d > 1;
        }
    }
    double psnr = vv_image_psnr(a, b);
    *depth_diff = worst;
    *coverage_diff = cov;
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(rc);
    vv_renderer_free(sf);
    return psnr;
}

static void
test_iso_sphere_vs_raycast(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(48, 18);
    vv_world *w = new_world();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, NULL));
    o->mode = VV_MODE_ISO;
    o->isovalue = 0;
    o->step = 0.25;
    vt_ok(vv_world_add_object(w, o));
    vv_view view = persp_view(128, 128, vv_vec3_make(30, -100, 60), vv_vec3_make(23.5, 23.5, 23.5),
                              vv_vec3_make(0, 0, 1), 30);
    double dd;
    long cov;
    double psnr = cross_check(w, &view, "iso_sphere", &dd, &cov);
    print_message("sphere r=18: PSNR %.1f dB, depth difference <= %.3f, %ld pixels differ in "
                  "coverage\n",
                  psnr, dd, cov);
    assert_true(psnr > 35);
    assert_true(dd < 0.2);
    assert_true(cov < 30);
    /* cut by a plane: both show a solid cut face at the same place (shaded
     * with the plane's normal here, with the volume's gradient by the ray
     * caster, so only the shapes are compared) */
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(26, 23.5, 23.5), vv_vec3_make(-1, 0.3, -0.2)));
    psnr = cross_check(w, &view, "iso_sphere_cut", &dd, &cov);
    print_message("sphere r=18, cut: PSNR %.1f dB, depth difference <= %.3f, %ld pixels differ in "
                  "coverage\n",
                  psnr, dd, cov);
    assert_true(dd < 0.3);
    assert_true(cov < 40);
    vv_world_free(w);
    vv_volume_free(v);
}

/* The cross-check: ray-cast isosurface and rasterized Marching
 * Cubes surface of neghip.slc, same World and view, agree to >= 30 dB. */
static void
test_neghip_cross_check(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    const double isos[2] = {40, 120};
    for (int k = 0; k < 2; k++) {
        vv_default_scene_options so;
        vv_default_scene_options_init(&so);
        so.mode = VV_MODE_ISO;
        so.has_isovalue = 1;
        so.isovalue = isos[k];
        so.width = so.height = 256;
        so.azimuth = vv_deg_to_rad(30);
        so.elevation = vv_deg_to_rad(20);
        vv_world *w = NULL;
        vt_ok(vv_world_new_for_volume(&w, v, &so));
        w->objects[0]->step = 0.25;
        double dd;
        long cov;
        char name[64];
        snprintf(name, sizeof name, "neghip_iso%.0f", isos[k]);
        double psnr = cross_check(w, &w->view, name, &dd, &cov);
        print_message("neghip iso %.0f: PSNR %.1f dB, %ld pixels differ in coverage, %ld in depth "
                      "by more than a voxel\n",
                      isos[k], psnr, cov, cross_far);
        assert_true(psnr >= 30);
        assert_true(cross_far < 100);
        assert_true(cov < 100);
        /* cut through the middle: solid cut faces in both, in the same place
         * (shaded differently: plane normal here, gradient in the ray caster) */
        vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 0), vv_vec3_make(0.3, -1, 0.2)));
        snprintf(name, sizeof name, "neghip_iso%.0f_cut", isos[k]);
        psnr = cross_check(w, &w->view, name, &dd, &cov);
        print_message("neghip iso %.0f, cut: PSNR %.1f dB, %ld pixels differ in coverage, %ld in "
                      "depth by more than a voxel\n",
                      isos[k], psnr, cov, cross_far);
        assert_true(cross_far < 100);
        assert_true(cov < 100);
        vv_world_free(w);
    }
    vv_volume_free(v);
}

/* The isosurface cache: same mesh while nothing changes, new one when the
 * isovalue or the data change; composite mode takes the TF's half-maximum. */
static void
test_iso_cache_and_tf(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(40, 12);
    vv_world *w = new_world();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, NULL));
    o->mode = VV_MODE_ISO;
    o->isovalue = 0;
    vt_ok(vv_world_add_object(w, o));
    vv_view view = ortho_view(64, 64, 100);
    view.at = vv_vec3_make(0, 0, 0);
    view.eye = vv_vec3_make(0, 0, 100);
    o->position = vv_vec3_make(-19.5, -19.5, -19.5);
    vv_renderer *r = new_surface();
    vv_image *a = render_t(r, w, &view, 0);
    long na = count_covered(a);
    vv_image *a2 = render_t(r, w, &view, 0);
    assert_memory_equal(a->rgba, a2->rgba, 64 * 64 * 4 * sizeof(float));
    /* radius 12 -> 8 by the isovalue */
    o->isovalue = 4;
    vv_image *b = render_t(r, w, &view, 0);
    long nb = count_covered(b);
    /* radius 12 -> 6 by the data: seen only once `modified` says so (the
     * cached surface is kept until then) */
    for (int k = 0; k < 40; k++)
        for (int j = 0; j < 40; j++)
            for (int i = 0; i < 40; i++)
                vv_volume_set(v, i, j, k, vv_volume_get(v, i, j, k) - 2);
    vv_image *stale = render_t(r, w, &view, 0);
    assert_memory_equal(stale->rgba, b->rgba, 64 * 64 * 4 * sizeof(float));
    vv_image_free(stale);
    vv_volume_update_range(v);
    vv_image *c = render_t(r, w, &view, 0);
    long nc = count_covered(c);
    /* composite: ramp 0 at -6 to 1 at 2 -> isovalue -2: value 10 - d = -2 at radius 12 */
    o->mode = VV_MODE_COMPOSITE;
    vv_tf_set_ramp(&o->tf, -6, 2, 1, vv_vec3_make(0, 1, 0), 1);
    vv_image *d = render_t(r, w, &view, 0);
    long nd = count_covered(d);
    print_message("iso sphere pixels: r12 %ld, r8 %ld, r6 %ld, tf r12 %ld\n", na, nb, nc, nd);
    assert_true(fabs(na - VV_PI * 144) < 40);
    assert_true(fabs(nb - VV_PI * 64) < 30);
    assert_true(fabs(nc - VV_PI * 36) < 25);
    assert_int_equal(nd, na);
    /* the TF colour at the isovalue: green */
    const float *q = px(d, 32, 32);
    assert_true(q[1] - q[0] > 0.5f && q[0] == q[2]); /* green plus the white highlight */
    vv_image_free(a);
    vv_image_free(a2);
    vv_image_free(b);
    vv_image_free(c);
    vv_image_free(d);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle_coverage_depth),
        cmocka_unit_test(test_shared_edge_watertight),
        cmocka_unit_test(test_perspective_correct),
        cmocka_unit_test(test_near_plane_clipping),
        cmocka_unit_test(test_culling),
        cmocka_unit_test(test_sphere_shading),
        cmocka_unit_test(test_auto_cull_same_image),
        cmocka_unit_test(test_cut_planes),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_wireframe),
        cmocka_unit_test(test_wireframe_clip_edges),
        cmocka_unit_test(test_merge),
        cmocka_unit_test(test_geometry_objects),
        cmocka_unit_test(test_camera_matches_rays),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_progress_and_cancel),
        cmocka_unit_test(test_iso_sphere_vs_raycast),
        cmocka_unit_test(test_neghip_cross_check),
        cmocka_unit_test(test_iso_cache_and_tf),
    };
    return vt_run_tests(tests, NULL, NULL);
}
