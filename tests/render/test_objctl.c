/* Object control in the renderers: 2-D transfer functions, image textures
 * and solid textures (raycast and raytrace). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static vv_volume *
new_volume(int n, vv_voxel_type t) {
    vv_volume *v = NULL;
    int dims[3] = {n, n, n};
    vt_ok(vv_volume_new(&v, dims, t));
    return v;
}

/* value = r - distance from the grid centre: the isosurface 0 is a sphere. */
static vv_volume *
sphere_volume(int n, double r) {
    vv_volume *v = new_volume(n, VV_F32);
    const double c = 0.5 * (n - 1);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                vv_volume_set(v, i, j, k,
                              r - sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c)));
    vv_volume_update_range(v);
    return v;
}

/* 100 inside a ball of radius r, 0 outside: homogeneous interior, a sharp
 * boundary. */
static vv_volume *
ball_volume(int n, double r) {
    vv_volume *v = new_volume(n, VV_U8);
    const double c = 0.5 * (n - 1);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double d = sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c));
                vv_volume_set(v, i, j, k, d <= r ? 100 : 0);
            }
    vv_volume_update_range(v);
    return v;
}

static vv_view
ortho(vv_vec3 eye, vv_vec3 at, vv_vec3 up, double height, int w, int h) {
    vv_view v;
    memset(&v, 0, sizeof v);
    v.eye = eye;
    v.at = at;
    v.up = up;
    v.fov = vv_deg_to_rad(30);
    v.ortho_height = height;
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    v.width = w;
    v.height = h;
    return v;
}

static vv_image *
render(const char *method, const vv_world *w, const vv_view *view) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, method));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, view->width, view->height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    vt_ok(vv_renderer_render(r, w, view, &opt, img));
    vv_renderer_free(r);
    return img;
}

static const float *
px(const vv_image *img, int x, int y) {
    return img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
}

static void
save(const vv_image *img, const char *name) {
    vt_ok(vv_image_write_png(img, vt_path(vt_outdir("render_objctl"), name), 1.0, 0));
}

static vv_world *
world_with(vv_volume *v, vv_object **obj) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    w->background = vv_vec3_make(0, 0, 0);
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, NULL));
    o->shading = 0;
    vt_ok(vv_world_add_object(w, o));
    *obj = o;
    return w;
}

/* A rectangle over every gradient magnitude is the 1-D TF of its value
 * profile. Not bit-identical: the 2-D table has 1024 value bins (nearest)
 * where the 1-D one has 4096 (floor), and the general kernel, not the
 * single-volume fast one, composites it; both see the same samples. */
static void
test_tf2d_rectangle_equals_1d(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(32, 10);
    vv_object *o = NULL;
    vv_world *w = world_with(v, &o);
    vv_vec3 col = vv_vec3_make(1.0, 0.8, 0.5);
    vv_tf_init(&o->tf);
    o->tf.opacity_unit_distance = 1;
    vt_ok(vv_tf_add_opacity(&o->tf, 0, 0));
    vt_ok(vv_tf_add_opacity(&o->tf, 2, 0.3));
    vt_ok(vv_tf_add_opacity(&o->tf, 8, 0.3));
    vt_ok(vv_tf_add_opacity(&o->tf, 10, 0));
    vt_ok(vv_tf_add_color(&o->tf, 0, col));
    vv_view view = ortho(vv_vec3_make(15.5, 15.5, 100), vv_vec3_make(15.5, 15.5, 0),
                         vv_vec3_make(0, 1, 0), 32, 48, 48);
    vv_image *a = render("raycast", w, &view);
    vv_tf2d_widget wd;
    vv_tf2d_widget_init_rectangle(&wd, 0, 10, 0, 1e6, col, 0.3);
    wd.ramp = 2;
    vv_tf2d_init(&o->tf2d);
    o->tf2d.opacity_unit_distance = 1;
    vt_ok(vv_tf2d_add_widget(&o->tf2d, &wd));
    o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
    vv_image *b = render("raycast", w, &view);
    double maxd = 0, sum_a = 0;
    for (size_t i = 0; i < 4 * (size_t)48 * 48; i++) {
        maxd = fmax(maxd, fabs(a->rgba[i] - b->rgba[i]));
        sum_a += a->rgba[i];
    }
    assert_true(sum_a > 100); /* the sphere is there */
    assert_true(maxd < 0.02);
    /* the same in the ray tracer */
    vv_image *c = render("raytrace", w, &view);
    o->segmentation = VV_SEG_TRANSFER_FUNCTION;
    vv_image *c1 = render("raytrace", w, &view);
    o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
    double maxr = 0;
    for (size_t i = 0; i < 4 * (size_t)48 * 48; i++)
        maxr = fmax(maxr, fabs(c->rgba[i] - c1->rgba[i]));
    assert_true(maxr < 0.02);
    vv_image_free(c1);
    /* and a rectangle above every gradient magnitude (|grad| = 1) shows nothing */
    o->tf2d.widgets[0].gradient[0] = 5;
    vv_image *d = render("raycast", w, &view);
    for (size_t i = 0; i < (size_t)48 * 48; i++)
        assert_true(d->rgba[4 * i + 3] == 0);
    vv_image_free(a);
    vv_image_free(b);
    vv_image_free(c);
    vv_image_free(d);
    vv_world_free(w);
    vv_volume_free(v);
}

/* Selecting high gradient magnitudes keeps the boundary of a homogeneous
 * ball and drops its interior: the central ray crosses the shell twice
 * (partly transparent) where the 1-D TF makes it opaque. */
static void
test_tf2d_boundary_only(void **state) {
    (void)state;
    vv_volume *v = ball_volume(40, 14);
    vv_object *o = NULL;
    vv_world *w = world_with(v, &o);
    vv_tf_set_ramp(&o->tf, 0, 0, 1, vv_vec3_make(1, 1, 1), 1);
    vv_tf_init(&o->tf);
    o->tf.opacity_unit_distance = 1;
    vt_ok(vv_tf_add_opacity(&o->tf, 49, 0));
    vt_ok(vv_tf_add_opacity(&o->tf, 50, 0.3));
    vv_view view = ortho(vv_vec3_make(19.5, 19.5, 100), vv_vec3_make(19.5, 19.5, 0),
                         vv_vec3_make(0, 1, 0), 40, 40, 40);
    vv_image *a = render("raycast", w, &view);
    vv_tf2d_widget wd;
    vv_tf2d_widget_init_rectangle(&wd, 50, 100, 10, 1000, vv_vec3_make(1, 1, 1), 0.3);
    vv_tf2d_init(&o->tf2d);
    o->tf2d.opacity_unit_distance = 1;
    vt_ok(vv_tf2d_add_widget(&o->tf2d, &wd));
    o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
    vv_image *b = render("raycast", w, &view);
    save(b, "tf2d_boundary.png");
    const float a1 = px(a, 20, 20)[3], a2 = px(b, 20, 20)[3];
    assert_true(a1 > 0.98);
    /* two crossings of a shell about two voxels thick at most */
    assert_true(a2 > 0.05 && a2 < 1 - pow(0.7, 6));
    /* the rim, seen tangentially through the shell, is more opaque */
    assert_true(px(b, 20, 7)[3] > a2);
    /* outside the ball nothing */
    assert_true(px(b, 1, 1)[3] == 0);
    vv_image_free(a);
    vv_image_free(b);
    vv_world_free(w);
    vv_volume_free(v);
}

/* 4x4 PNG: quadrants red (top left), green (top right), blue (bottom
 * left), white (bottom right), so that bilinear lookups inside a quadrant
 * are pure. */
static const char *
checker_png(void) {
    vv_image *im = NULL;
    vt_ok(vv_image_new(&im, 4, 4));
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            float *p = im->rgba + 4 * (y * 4 + x);
            int q = (y >= 2) * 2 + (x >= 2);
            static const float c[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
            p[0] = c[q][0];
            p[1] = c[q][1];
            p[2] = c[q][2];
            p[3] = 1;
        }
    const char *path = vt_path(vt_outdir("render_objctl"), "checker.png");
    vt_ok(vv_image_write_png(im, path, 1.0, 0));
    vv_image_free(im);
    return path;
}

static void
assert_rgb(const float *p, double r, double g, double b) {
    if (!(fabs(p[0] - r) < 0.03 && fabs(p[1] - g) < 0.03 && fabs(p[2] - b) < 0.03))
        fail_msg("pixel (%g, %g, %g), expected (%g, %g, %g)", p[0], p[1], p[2], r, g, b);
}

/* Spherical projection about +z: the direction +y (u = 1/4) shows the left
 * half of the image, -y (u = 3/4) the right; the upper hemisphere the top.
 * Seen from +y and -y, orthographic, unlit (ka = 1, no lights). */
static void
test_texture_sphere_spherical(void **state) {
    (void)state;
    vv_texture_image *tex = NULL;
    vt_ok(vv_texture_image_load(&tex, checker_png(), "checker.png"));
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "ball"));
    o->material.ambient = 1;
    o->material.diffuse = 0;
    o->material.specular = 0;
    vv_object_set_texture_image(o, tex);
    o->texture.projection = VV_TEXTURE_SPHERICAL;
    vt_ok(vv_world_add_object(w, o));
    /* pixel row 24 is z = 0.71, row 95 z = -0.71 (120 px over 2.4) */
    for (int side = 0; side < 2; side++) {
        double s = side ? -1 : 1;
        vv_view view = ortho(vv_vec3_make(0, 5 * s, 0), vv_vec3_make(0, 0, 0),
                             vv_vec3_make(0, 0, 1), 2.4, 120, 120);
        vv_image *img = render("raytrace", w, &view);
        if (!side)
            save(img, "texture_sphere.png");
        if (!side) {
            assert_rgb(px(img, 60, 24), 1, 0, 0);
            assert_rgb(px(img, 60, 95), 0, 0, 1);
        } else {
            assert_rgb(px(img, 60, 24), 0, 1, 0);
            assert_rgb(px(img, 60, 95), 1, 1, 1);
        }
        vv_image_free(img);
    }
    /* the isosurface of a volume, iso mode, ray caster and ray tracer */
    vv_volume *v = sphere_volume(33, 12);
    vv_object *vo = NULL;
    vt_ok(vv_object_new_volume(&vo, v, NULL));
    vo->mode = VV_MODE_ISO;
    vo->isovalue = 0;
    vo->shading = 0;
    vo->step = 0.25;
    vv_object_set_texture_image(vo, tex);
    vo->texture.projection = VV_TEXTURE_SPHERICAL;
    vo->texture.center = vv_vec3_make(16, 16, 16);
    vv_world *wv = NULL;
    vt_ok(vv_world_new(&wv));
    vt_ok(vv_world_add_object(wv, vo));
    vv_view view = ortho(vv_vec3_make(16, 60, 16), vv_vec3_make(16, 16, 16), vv_vec3_make(0, 0, 1),
                         28.8, 120, 120);
    for (int m = 0; m < 2; m++) {
        vv_image *img = render(m ? "raytrace" : "raycast", wv, &view);
        assert_rgb(px(img, 60, 24), 1, 0, 0);
        assert_rgb(px(img, 60, 95), 0, 0, 1);
        vv_image_free(img);
    }
    vv_world_free(wv);
    vv_volume_free(v);
    vv_world_free(w);
    vv_texture_image_free(tex);
}

/* A checker3d solid texture on an opaque cube volume seen from above: the
 * first sample (just under the top face, z in [16, 20)) takes color0 where
 * floor(x/4) + floor(y/4) is even. */
static void
test_solid_checker_cube(void **state) {
    (void)state;
    vv_volume *v = new_volume(20, VV_U8);
    for (int k = 0; k < 20; k++)
        for (int j = 0; j < 20; j++)
            for (int i = 0; i < 20; i++)
                vv_volume_set(v, i, j, k, 200);
    vv_volume_update_range(v);
    vv_object *o = NULL;
    vv_world *w = world_with(v, &o);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, 0, 1));
    o->solid_texture.kind = VV_SOLID_TEXTURE_CHECKER;
    o->solid_texture.period = 4;
    o->solid_texture.color0 = vv_vec3_make(1, 0, 0);
    o->solid_texture.color1 = vv_vec3_make(0, 0, 1);
    /* pixel (i, j) is at x = i, y = 19 - j */
    vv_view view = ortho(vv_vec3_make(9.5, 9.5, 50), vv_vec3_make(9.5, 9.5, 0),
                         vv_vec3_make(0, 1, 0), 20, 20, 20);
    for (int m = 0; m < 2; m++) {
        vv_image *img = render(m ? "raytrace" : "raycast", w, &view);
        if (!m)
            save(img, "solid_checker.png");
        assert_rgb(px(img, 2, 17), 1, 0, 0);  /* x 2, y 2 */
        assert_rgb(px(img, 6, 17), 0, 0, 1);  /* x 6, y 2 */
        assert_rgb(px(img, 6, 13), 1, 0, 0);  /* x 6, y 6 */
        assert_rgb(px(img, 10, 13), 0, 0, 1); /* x 10, y 6 */
        vv_image_free(img);
    }
    vv_world_free(w);
    vv_volume_free(v);
}

/* The CT head with a triangle widget on the soft-tissue/bone boundary and a
 * wood texture on a volume: images to look at (build/test-out). */
static void
test_ct_head_images(void **state) {
    (void)state;
    vv_volume *v = NULL;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    vv_world *w = NULL;
    vv_default_scene_options so;
    vv_default_scene_options_init(&so);
    so.width = so.height = 160;
    vt_ok(vv_world_new_for_volume(&w, v, &so));
    vv_object *o = w->objects[0];
    vv_tf2d_widget wd;
    vv_tf2d_widget_init_triangle(&wd, 700, 1400, 1500, vv_vec3_make(1, 0.95, 0.85), 0.9);
    wd.gradient[0] = 150;
    vv_tf2d_init(&o->tf2d);
    o->tf2d.opacity_unit_distance = 1;
    vt_ok(vv_tf2d_add_widget(&o->tf2d, &wd));
    o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
    vv_image *img = render("raycast", w, &w->view);
    save(img, "ct_head_tf2d.png");
    long opaque = 0;
    for (size_t i = 0; i < (size_t)160 * 160; i++)
        opaque += img->rgba[4 * i + 3] > 0.5;
    assert_true(opaque > 1000);
    vv_image_free(img);
    o->segmentation = VV_SEG_TRANSFER_FUNCTION;
    vt_ok(vv_tf_preset(&o->tf, "ct-bone", v));
    o->solid_texture.kind = VV_SOLID_TEXTURE_WOOD;
    o->solid_texture.period = 12;
    o->solid_texture.turbulence = 0.4;
    o->solid_texture.axis = vv_vec3_make(0, 0, 1);
    o->solid_texture.center = vv_vec3_make(0, 0, 0);
    o->solid_texture.color0 = vv_vec3_make(0.85, 0.6, 0.35);
    o->solid_texture.color1 = vv_vec3_make(0.45, 0.25, 0.1);
    img = render("raycast", w, &w->view);
    save(img, "ct_head_wood.png");
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tf2d_rectangle_equals_1d), cmocka_unit_test(test_tf2d_boundary_only),
        cmocka_unit_test(test_texture_sphere_spherical), cmocka_unit_test(test_solid_checker_cube),
        cmocka_unit_test(test_ct_head_images),
    };
    return vt_run_tests(tests, NULL, NULL);
}
