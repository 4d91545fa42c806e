/* vv_nav_apply: every motion on every kind of target, checked against the
 * geometry it must produce (the GUI's mouse and the input devices both go
 * through it). */
#include <math.h>
#include <string.h>

#include "testutil.h"

/* A 400 x 400 view from -y at distance 100, z up, 30 degrees. */
static vv_world *
front_world(void) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    w->view.eye = vv_vec3_make(0, -100, 0);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.up = vv_vec3_make(0, 0, 1);
    w->view.fov = vv_deg_to_rad(30);
    w->view.ortho_height = 50;
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    w->view.width = 400;
    w->view.height = 400;
    return w;
}

/* World units per pixel at the look-at distance of front_world. */
static double
wpp(void) {
    return 2 * 100 * tan(vv_deg_to_rad(15)) / 400;
}

static vv_nav_motion
motion(vv_nav_motion_kind kind, double dx, double dy) {
    vv_nav_motion m;
    memset(&m, 0, sizeof m);
    m.kind = kind;
    m.dx = dx;
    m.dy = dy;
    m.factor = 1;
    m.rotation = vv_quat_identity();
    return m;
}

static const vv_nav_target view_target = {VV_NAV_TARGET_VIEW, 0, 0};

static void
assert_vec(vv_vec3 a, double x, double y, double z, double tol) {
    assert_near(a.x, x, tol);
    assert_near(a.y, y, tol);
    assert_near(a.z, z, tol);
}

/* The view: a drag across half the height is a quarter turn about the
 * look-at point, the scene following the mouse; pan, zoom, fly and a
 * two-hand turn. */
static void
test_view(void **state) {
    (void)state;
    vv_world *w = front_world();
    vv_nav_motion m = motion(VV_NAV_ROTATE, -200, 0);
    vt_ok(vv_nav_apply(w, &view_target, &m));
    assert_vec(w->view.eye, 100, 0, 0, 1e-9);
    assert_vec(w->view.at, 0, 0, 0, 1e-12);

    vv_world_free(w);
    w = front_world();
    m = motion(VV_NAV_PAN, 10, 20);
    vt_ok(vv_nav_apply(w, &view_target, &m));
    /* the scene follows the mouse right and down: the camera goes left and up */
    assert_vec(w->view.at, -10 * wpp(), 0, 20 * wpp(), 1e-9);
    assert_vec(w->view.eye, -10 * wpp(), -100, 20 * wpp(), 1e-9);

    m = motion(VV_NAV_ZOOM, 0, 0);
    m.factor = 4;
    vt_ok(vv_nav_apply(w, &view_target, &m));
    assert_near(vv_vec3_length(vv_vec3_sub(w->view.eye, w->view.at)), 25, 1e-9);

    vv_world_free(w);
    w = front_world();
    m = motion(VV_NAV_FLY, 0, 0);
    m.yaw = vv_deg_to_rad(90); /* a quarter turn to the left in one second */
    m.speed = 0;
    m.dt = 1;
    vt_ok(vv_nav_apply(w, &view_target, &m));
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(w->view.at, w->view.eye));
    assert_vec(f, -1, 0, 0, 1e-9);
    assert_vec(w->view.eye, 0, -100, 0, 1e-9);

    /* two hands turn the scene 90 degrees about the view's up axis (+x of
     * the scene goes away from the viewer): the camera goes round to -x */
    vv_world_free(w);
    w = front_world();
    m = motion(VV_NAV_TURN, 0, 0);
    m.rotation = vv_quat_from_axis_angle(vv_vec3_make(0, 1, 0), VV_PI / 2);
    vt_ok(vv_nav_apply(w, &view_target, &m));
    assert_vec(w->view.eye, -100, 0, 0, 1e-9);
    assert_vec(w->view.up, 0, 0, 1, 1e-9);
    vv_world_free(w);
}

/* An object turns about its box centre, follows the mouse, and scales
 * about its box centre (which therefore stays put); flight does not move it. */
static void
test_object(void **state) {
    (void)state;
    vv_world *w = front_world();
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_BOX, "b"));
    o->geometry.box = (vv_box){{0, 0, 0}, {10, 10, 10}};
    o->position = vv_vec3_make(5, 0, 0);
    vt_ok(vv_world_add_object(w, o));
    vv_nav_target t = {VV_NAV_TARGET_OBJECT, 0, 0};
    vv_box b0 = vv_object_world_box(w->objects[0]);
    vv_vec3 c0 = vv_vec3_scale(vv_vec3_add(b0.min, b0.max), 0.5);

    vv_nav_motion m = motion(VV_NAV_ZOOM, 0, 0);
    m.factor = 2;
    vt_ok(vv_nav_apply(w, &t, &m));
    vv_box b1 = vv_object_world_box(w->objects[0]);
    vv_vec3 c1 = vv_vec3_scale(vv_vec3_add(b1.min, b1.max), 0.5);
    assert_vec(c1, c0.x, c0.y, c0.z, 1e-9);
    assert_near(b1.max.x - b1.min.x, 20, 1e-9);
    assert_near(w->objects[0]->scale.x, 2, 1e-12);

    vv_vec3 p0 = w->objects[0]->position;
    m = motion(VV_NAV_PAN, 10, 0);
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->objects[0]->position, p0.x + 10 * wpp(), p0.y, p0.z, 1e-9);

    /* a quarter turn about the view's up (world z): x turns to -y, the
     * box centre stays */
    b1 = vv_object_world_box(w->objects[0]);
    c1 = vv_vec3_scale(vv_vec3_add(b1.min, b1.max), 0.5);
    m = motion(VV_NAV_ROTATE, -200, 0);
    vt_ok(vv_nav_apply(w, &t, &m));
    vv_vec3 x = vv_quat_rotate(w->objects[0]->orientation, vv_vec3_make(1, 0, 0));
    assert_vec(x, 0, -1, 0, 1e-9);
    vv_box b2 = vv_object_world_box(w->objects[0]);
    vv_vec3 c2 = vv_vec3_scale(vv_vec3_add(b2.min, b2.max), 0.5);
    assert_vec(c2, c1.x, c1.y, c1.z, 1e-9);

    vv_vec3 p1 = w->objects[0]->position;
    m = motion(VV_NAV_FLY, 0, 0);
    m.speed = 100;
    m.dt = 1;
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->objects[0]->position, p1.x, p1.y, p1.z, 0);
    assert_vec(w->view.eye, 0, -100, 0, 0); /* nor the view */
    vv_world_free(w);
}

/* A point light follows the mouse in the view plane; a directional light
 * turns with the trackball. */
static void
test_light(void **state) {
    (void)state;
    vv_world *w = front_world();
    vv_light p = {VV_LIGHT_POINT, 0, {0, 1, 0}, {1, 2, 3}, {1, 1, 1}, 1};
    vv_light d = {VV_LIGHT_DIRECTIONAL, 0, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1};
    vt_ok(vv_world_add_light(w, &p));
    vt_ok(vv_world_add_light(w, &d));
    vv_nav_target t = {VV_NAV_TARGET_LIGHT, 0, 0};
    vv_nav_motion m = motion(VV_NAV_PAN, 10, -20);
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->lights[0].position, 1 + 10 * wpp(), 2, 3 + 20 * wpp(), 1e-9);
    t.index = 1;
    m = motion(VV_NAV_ROTATE, 200, 0); /* a quarter turn about z: +y turns to -x */
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->lights[1].direction, -1, 0, 0, 1e-9);
    vv_world_free(w);
}

/* A cut plane facing +z seen from the front: a drag up the length of its
 * drawn handle (0.15 of the eye distance, 15 units) moves it 15 units along
 * its normal; a sideways drag does not move it; a drag down a quarter
 * turn tilts the normal towards the viewer. Local planes are addressed
 * through their object. */
static void
test_cut_plane(void **state) {
    (void)state;
    vv_world *w = front_world();
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 0), vv_vec3_make(0, 0, 1)));
    vv_nav_target t = {VV_NAV_TARGET_CUT, -1, -1};
    double handle_px = 15 / wpp(); /* the handle's length on screen */
    vv_nav_motion m = motion(VV_NAV_PAN, 0, -handle_px);
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->cut_planes[0].point, 0, 0, 15, 1e-9);
    m = motion(VV_NAV_PAN, 50, 0);
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->cut_planes[0].point, 0, 0, 15, 1e-9);
    m = motion(VV_NAV_ROTATE, 0, 200);
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->cut_planes[0].normal, 0, -1, 0, 1e-9);

    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "s"));
    o->cut_planes[0] = (vv_cut_plane){{0, 0, 0}, {1, 0, 0}};
    o->cut_planes[1] = (vv_cut_plane){{0, 0, 0}, {0, 0, 1}};
    o->n_cut_planes = 2;
    vt_ok(vv_world_add_object(w, o));
    t = (vv_nav_target){VV_NAV_TARGET_CUT, 0, 0};
    m = motion(VV_NAV_PAN, handle_px, 0); /* +x is to the right */
    vt_ok(vv_nav_apply(w, &t, &m));
    assert_vec(w->objects[0]->cut_planes[0].point, 15, 0, 0, 1e-9);
    assert_vec(w->objects[0]->cut_planes[1].point, 0, 0, 0, 0);
    vv_world_free(w);
}

/* Bad targets are errors that leave the World alone; no input makes the
 * view invalid. */
static void
test_errors(void **state) {
    (void)state;
    vv_world *w = front_world();
    vv_nav_motion m = motion(VV_NAV_ROTATE, 10, 10);
    vv_nav_target t = {VV_NAV_TARGET_OBJECT, 0, 0};
    assert_int_equal(vv_nav_apply(w, &t, &m), VV_ERR_INVALID);
    assert_non_null(strstr(vv_error_message(), "no object 0"));
    t = (vv_nav_target){VV_NAV_TARGET_LIGHT, 3, 0};
    assert_int_equal(vv_nav_apply(w, &t, &m), VV_ERR_INVALID);
    t = (vv_nav_target){VV_NAV_TARGET_CUT, -1, -1};
    assert_int_equal(vv_nav_apply(w, &t, &m), VV_ERR_INVALID);
    assert_int_equal(vv_nav_apply(NULL, &t, &m), VV_ERR_INVALID);
    assert_int_equal(vv_nav_apply(w, NULL, &m), VV_ERR_INVALID);
    assert_int_equal(vv_nav_apply(w, &t, NULL), VV_ERR_INVALID);
    assert_vec(w->view.eye, 0, -100, 0, 0);
    m = motion(VV_NAV_ROTATE, NAN, INFINITY);
    vt_ok(vv_nav_apply(w, &view_target, &m));
    m = motion(VV_NAV_TURN, 0, 0);
    m.rotation = (vv_quat){NAN, 0, 0, 0};
    vt_ok(vv_nav_apply(w, &view_target, &m));
    assert_true(vv_nav_view_valid(&w->view));
    w->view.eye = w->view.at;
    m = motion(VV_NAV_PAN, 1, 1);
    assert_int_equal(vv_nav_apply(w, &view_target, &m), VV_ERR_INVALID);
    vv_world_free(w);
}

/* vv_nav_view_project is the inverse of vv_view_ray, in both projections. */
static void
test_project(void **state) {
    (void)state;
    vv_world *w = front_world();
    for (int proj = 0; proj < 2; proj++) {
        w->view.projection = (vv_projection)proj;
        w->view.width = 300; /* not square */
        double pts[][2] = {{0, 0}, {299.5, 10.25}, {150, 200}, {17.75, 399}};
        for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
            vv_ray r = vv_view_ray(&w->view, pts[i][0], pts[i][1]);
            vv_vec3 p = vv_ray_at(r, 37.5);
            double px, py;
            assert_int_equal(vv_nav_view_project(&w->view, p, &px, &py), 1);
            assert_near(px, pts[i][0] + 0.5, 1e-9);
            assert_near(py, pts[i][1] + 0.5, 1e-9);
        }
    }
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    double px = -1, py = -1;
    assert_int_equal(vv_nav_view_project(&w->view, vv_vec3_make(0, -150, 0), &px, &py), 0);
    assert_near(px, -1, 0);
    vv_world_free(w);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_view),   cmocka_unit_test(test_object),
        cmocka_unit_test(test_light),  cmocka_unit_test(test_cut_plane),
        cmocka_unit_test(test_errors), cmocka_unit_test(test_project),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
