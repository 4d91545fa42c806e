/* Views: primary rays, framing a box, orbiting. */
#include <math.h>

#include "testutil.h"

static vv_view
make_view(void) {
    vv_view v;
    v.eye = vv_vec3_make(0, -10, 0);
    v.at = vv_vec3_make(0, 0, 0);
    v.up = vv_vec3_make(0, 0, 1);
    v.fov = vv_deg_to_rad(60.0);
    v.ortho_height = 4.0;
    v.projection = VV_PROJECTION_PERSPECTIVE;
    v.width = 200;
    v.height = 100;
    return v;
}

static double
angle_between(vv_vec3 a, vv_vec3 b) {
    double c = vv_vec3_dot(vv_vec3_normalize(a), vv_vec3_normalize(b));
    if (c > 1)
        c = 1;
    if (c < -1)
        c = -1;
    return acos(c);
}

static void
test_centre_ray(void **state) {
    (void)state;
    vv_view v = make_view();
    /* the image centre is the corner shared by pixels (99, 49) and (100, 50):
     * pixel px covers [px, px + 1), its centre is px + 0.5 */
    vv_ray r = vv_view_ray(&v, 99.5, 49.5);
    assert_near(r.origin.y, -10, 1e-12);
    assert_near(r.dir.x, 0, 1e-12);
    assert_near(r.dir.y, 1, 1e-12);
    assert_near(r.dir.z, 0, 1e-12);
    assert_near(vv_vec3_length(r.dir), 1.0, 1e-12);
}

static void
test_corner_rays(void **state) {
    (void)state;
    vv_view v = make_view();
    double t = tan(0.5 * v.fov);
    /* top edge, centre column: the angle to the axis is fov/2 */
    vv_ray r = vv_view_ray(&v, 99.5, -0.5);
    assert_near(angle_between(r.dir, vv_vec3_make(0, 1, 0)), 0.5 * v.fov, 1e-12);
    assert_true(r.dir.z > 0); /* row 0 is at the top */
    /* right edge, centre row: horizontal half-angle atan(aspect * tan(fov/2)) */
    r = vv_view_ray(&v, 199.5, 49.5);
    assert_near(angle_between(r.dir, vv_vec3_make(0, 1, 0)), atan(2.0 * t), 1e-12);
    assert_true(r.dir.x > 0); /* column 0 at the left, +x to the right seen from -y */
    /* centre of pixel (0, 0) */
    r = vv_view_ray(&v, 0, 0);
    double x = (2.0 * 0.5 / 200 - 1) * t * 2.0, y = (1 - 2.0 * 0.5 / 100) * t;
    vv_vec3 want = vv_vec3_normalize(vv_vec3_make(x, 1, y));
    assert_near(r.dir.x, want.x, 1e-12);
    assert_near(r.dir.y, want.y, 1e-12);
    assert_near(r.dir.z, want.z, 1e-12);
}

static void
test_orthographic(void **state) {
    (void)state;
    vv_view v = make_view();
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    vv_ray a = vv_view_ray(&v, 0, 0);
    vv_ray b = vv_view_ray(&v, 199, 99);
    assert_near(a.dir.y, 1, 1e-12);
    assert_near(b.dir.y, 1, 1e-12);
    assert_near(a.dir.x, b.dir.x, 1e-12);
    /* origins on the eye plane, spanning ortho_height x ortho_height*aspect */
    assert_near(a.origin.y, -10, 1e-12);
    vv_ray top = vv_view_ray(&v, 99.5, -0.5);
    vv_ray right = vv_view_ray(&v, 199.5, 49.5);
    assert_near(top.origin.z, 2.0, 1e-12);
    assert_near(right.origin.x, 4.0, 1e-12);
    assert_near(a.origin.x, -4.0 + 8.0 * 0.5 / 200, 1e-12);
}

/* Projects p into pixel coordinates of a perspective view. */
static int
project(const vv_view *v, vv_vec3 p, double *px, double *py) {
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(v->at, v->eye));
    vv_vec3 r = vv_vec3_normalize(vv_vec3_cross(f, v->up));
    vv_vec3 u = vv_vec3_cross(r, f);
    vv_vec3 d = vv_vec3_sub(p, v->eye);
    double z = vv_vec3_dot(d, f);
    if (z <= 0)
        return 0;
    double t = tan(0.5 * v->fov), aspect = (double)v->width / v->height;
    double x = vv_vec3_dot(d, r) / z / (t * aspect), y = vv_vec3_dot(d, u) / z / t;
    *px = (x + 1) * 0.5 * v->width;
    *py = (1 - y) * 0.5 * v->height;
    return 1;
}

static void
check_box_in_view(const vv_view *v, vv_box b) {
    for (int i = 0; i < 8; i++) {
        vv_vec3 p = vv_vec3_make(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                 i & 4 ? b.max.z : b.min.z);
        double px = -1, py = -1;
        assert_true(project(v, p, &px, &py));
        assert_true(px >= 0 && px <= v->width);
        assert_true(py >= 0 && py <= v->height);
    }
}

static void
test_frame_box(void **state) {
    (void)state;
    vv_box b = {{10, 20, -5}, {110, 60, 45}};
    vv_view v = make_view();
    vv_view_frame_box(&v, b);
    assert_near(v.at.x, 60, 1e-9);
    assert_near(v.at.y, 40, 1e-9);
    assert_near(v.at.z, 20, 1e-9);
    /* same viewing direction as before */
    vv_vec3 d = vv_vec3_normalize(vv_vec3_sub(v.at, v.eye));
    assert_near(d.y, 1, 1e-12);
    check_box_in_view(&v, b);
    /* tall image: the width limits */
    v.width = 50;
    v.height = 300;
    vv_view_frame_box(&v, b);
    check_box_in_view(&v, b);
    /* the view is tight: the sphere touches the narrower image edge */
    double r = 0.5 * vv_vec3_length(vv_vec3_sub(b.max, b.min));
    double half = atan(tan(0.5 * v.fov) * 50.0 / 300.0);
    assert_near(vv_vec3_length(vv_vec3_sub(v.eye, v.at)), r / sin(half), 1e-9);
    /* orbiting around keeps the box in view from any side */
    for (int k = 0; k < 12; k++) {
        vv_view_orbit(&v, vv_deg_to_rad(37), vv_deg_to_rad(23));
        check_box_in_view(&v, b);
    }
    /* orthographic: ortho_height covers the sphere in both directions */
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    vv_view_frame_box(&v, b);
    assert_true(v.ortho_height * 50.0 / 300.0 >= 2 * r - 1e-9);
}

static void
test_orbit(void **state) {
    (void)state;
    vv_view v = make_view();
    v.at = vv_vec3_make(1, 2, 3);
    v.eye = vv_vec3_make(1, -8, 3);
    vv_view_orbit(&v, vv_deg_to_rad(90), 0);
    assert_near(vv_vec3_length(vv_vec3_sub(v.eye, v.at)), 10, 1e-9);
    /* azimuth +90 about +z takes the eye from -y to +x */
    assert_near(v.eye.x, 11, 1e-9);
    assert_near(v.eye.y, 2, 1e-9);
    assert_near(v.eye.z, 3, 1e-9);
    /* elevation moves the eye towards up */
    vv_view_orbit(&v, 0, vv_deg_to_rad(30));
    assert_near(vv_vec3_length(vv_vec3_sub(v.eye, v.at)), 10, 1e-9);
    assert_near(v.eye.z - 3, 10 * sin(vv_deg_to_rad(30)), 1e-9);
    /* over the pole: the view stays defined */
    vv_view_orbit(&v, 0, vv_deg_to_rad(60));
    assert_near(v.eye.z - 3, 10, 1e-9);
    vv_ray r = vv_view_ray(&v, 99.5, 49.5);
    assert_near(r.dir.z, -1, 1e-9);
    assert_false(isnan(r.dir.x) || isnan(r.dir.y));
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_centre_ray),   cmocka_unit_test(test_corner_rays),
        cmocka_unit_test(test_orthographic), cmocka_unit_test(test_frame_box),
        cmocka_unit_test(test_orbit),
    };
    return vt_run_tests(tests, NULL, NULL);
}
