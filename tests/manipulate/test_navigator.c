/* Navigator maths (trackball, pan, zoom, flight simulator, objects, lights)
 * and the preview representations, without a display. */
#include <math.h>
#include <string.h>

#include "testutil.h"

static vv_view
front_view(void) {
    vv_view v;
    memset(&v, 0, sizeof v);
    v.eye = vv_vec3_make(0, -100, 0);
    v.at = vv_vec3_make(0, 0, 0);
    v.up = vv_vec3_make(0, 0, 1);
    v.fov = vv_deg_to_rad(30);
    v.ortho_height = 50;
    v.width = 400;
    v.height = 400;
    return v;
}

/* A drag to the left turns the object's front to the viewer's left: the
 * eye orbits towards +x (the viewer's right); a drag across the height is
 * half a turn; the distance is kept. */
static void
test_trackball(void **state) {
    (void)state;
    vv_view v = front_view();
    vv_nav_view_rotate(&v, -200, 0); /* half the height: a quarter turn */
    assert_near(v.eye.x, 100, 1e-9);
    assert_near(v.eye.y, 0, 1e-9);
    assert_near(vv_vec3_length(vv_vec3_sub(v.eye, v.at)), 100, 1e-9);
    v = front_view();
    vv_nav_view_rotate(&v, 0, 200); /* a drag down lifts the eye over the top */
    assert_near(v.eye.z, 100, 1e-9);
    assert_true(vv_nav_view_valid(&v));
    /* rotations compose back to the start */
    vv_nav_view_rotate(&v, 0, -200);
    assert_near(v.eye.y, -100, 1e-9);
    assert_near(v.up.z, 1, 1e-9);
}

static void
test_pan_zoom(void **state) {
    (void)state;
    vv_view v = front_view();
    double wpp = 2 * 100 * tan(vv_deg_to_rad(15)) / 400;
    vv_nav_view_pan(&v, 10, 0); /* scene follows the mouse to the right: camera goes left */
    assert_near(v.eye.x, -10 * wpp, 1e-9);
    assert_near(v.at.x, -10 * wpp, 1e-9);
    vv_nav_view_pan(&v, 0, 10); /* mouse down: camera goes up */
    assert_near(v.at.z, 10 * wpp, 1e-9);
    v = front_view();
    vv_nav_view_zoom(&v, 2);
    assert_near(v.eye.y, -50, 1e-9);
    vv_nav_view_zoom(&v, 1e9); /* clamped to 16 */
    assert_near(v.eye.y, -50.0 / 16, 1e-9);
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    vv_nav_view_zoom(&v, 0.5);
    assert_near(v.ortho_height, 100, 1e-9);
}

/* Yaw at a constant rate turns the direction of flight by rate * t; the
 * throttle moves the eye along it. */
static void
test_flight(void **state) {
    (void)state;
    vv_view v = front_view();
    for (int i = 0; i < 90; i++)
        vv_nav_view_fly(&v, vv_deg_to_rad(30), 0, 0, 0, 1.0 / 30); /* 3 s at 30 deg/s */
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(v.at, v.eye));
    assert_near(vv_vec3_dot(f, vv_vec3_make(0, 1, 0)), 0, 1e-9); /* turned 90 degrees */
    assert_near(fabs(f.x), 1, 1e-9);
    assert_near(vv_vec3_length(vv_vec3_sub(v.eye, vv_vec3_make(0, -100, 0))), 0, 1e-9);
    vv_vec3 e0 = v.eye;
    vv_nav_view_fly(&v, 0, 0, 0, 20, 0.5);
    assert_near(vv_vec3_length(vv_vec3_sub(v.eye, e0)), 10, 1e-9);
    /* roll turns up about the viewing direction */
    v = front_view();
    for (int i = 0; i < 30; i++)
        vv_nav_view_fly(&v, 0, 0, vv_deg_to_rad(90), 0, 1.0 / 30);
    assert_near(fabs(v.up.x), 1, 1e-9);
    assert_near(v.up.z, 0, 1e-9);
}

/* Absurd and NaN input never makes the camera invalid. */
static void
test_bad_input(void **state) {
    (void)state;
    vv_view v = front_view();
    vv_nav_view_rotate(&v, NAN, 1e6);
    assert_true(vv_nav_view_valid(&v));
    vv_nav_view_rotate(&v, INFINITY, -INFINITY);
    vv_nav_view_pan(&v, 1e300, NAN);
    vv_nav_view_zoom(&v, NAN);
    vv_nav_view_zoom(&v, -3);
    vv_nav_view_zoom(&v, 0);
    vv_nav_view_zoom(&v, INFINITY);
    for (int i = 0; i < 2000; i++)
        vv_nav_view_zoom(&v, 16);
    vv_nav_view_fly(&v, NAN, INFINITY, -1e300, NAN, 1e9);
    for (int i = 0; i < 1000; i++)
        vv_nav_view_fly(&v, 0, 0, 0, 1e9, 1);
    assert_true(vv_nav_view_valid(&v));
    vv_view bad = front_view();
    bad.eye.x = NAN;
    assert_false(vv_nav_view_valid(&bad));
    vv_nav_view_rotate(&bad, 10, 10); /* left alone, no crash */
    assert_true(isnan(bad.eye.x));

    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "s"));
    vv_nav_object_rotate(o, &v, NAN, 1e30);
    vv_nav_object_translate(o, &v, INFINITY, NAN);
    vv_nav_object_scale(o, NAN);
    vv_nav_object_scale(o, 0);
    assert_true(isfinite(o->position.x) && isfinite(o->orientation.w) && o->scale.x > 0);
    vv_object_free(o);
    vv_light l = {VV_LIGHT_DIRECTIONAL, 1, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1};
    vv_nav_light_drag(&l, &v, NAN, 1e300);
    assert_true(isfinite(l.direction.x) && isfinite(l.direction.y) && isfinite(l.direction.z));
}

static void
test_objects_lights(void **state) {
    (void)state;
    vv_view v = front_view();
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "s"));
    o->position = vv_vec3_make(5, 0, 0);
    /* rotating about its own centre keeps it in place */
    vv_nav_object_rotate(o, &v, 123, 45);
    assert_near(o->position.x, 5, 1e-9);
    assert_near(
        vv_vec3_length(vv_vec3_make(o->orientation.x, o->orientation.y, o->orientation.z)) *
                vv_vec3_length(vv_vec3_make(o->orientation.x, o->orientation.y, o->orientation.z)) +
            o->orientation.w * o->orientation.w,
        1, 1e-12);
    double wpp = 2 * 100 * tan(vv_deg_to_rad(15)) / 400;
    vv_nav_object_translate(o, &v, 10, -10);
    assert_near(o->position.x, 5 + 10 * wpp, 1e-9);
    assert_near(o->position.z, 10 * wpp, 1e-9);
    vv_nav_object_scale(o, 2);
    assert_near(o->scale.x, 2, 1e-12);
    vv_object_free(o);

    vv_light pl = {VV_LIGHT_POINT, 0, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1};
    vv_nav_light_drag(&pl, &v, 20, 0);
    assert_near(pl.position.x, 20 * wpp, 1e-9);
    vv_light hl = {VV_LIGHT_DIRECTIONAL, 1, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1};
    vv_nav_light_drag(&hl, &v, 200, 0); /* a quarter turn about up */
    assert_int_equal(hl.headlight, 0);
    assert_near(fabs(hl.direction.x), 1, 1e-9);
}

/* The policy casts rays whenever a reduced cast fits: 1/8 first, finer
 * ones as they are measured to fit; surfaces only when even 1/8 is too slow. */
static void
test_policy(void **state) {
    (void)state;
    vv_preview_policy pol;
    vv_preview_policy_init(&pol);
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_RAYCAST_8);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_8, 0.001);
    /* 1/4 expected at 4 ms, 1/2 at 16 ms: both fit, the finer wins */
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_RAYCAST_2);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_2, 0.2);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_2, 0.2);
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_RAYCAST_4);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_4, 0.1);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_4, 0.1);
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_RAYCAST_8);
    /* 1/8 a little too slow (a passing load): still the data, not boxes */
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_8, 0.05);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_8, 0.05);
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_RAYCAST_8);
    /* a surface that fits and is much quicker than the slow cast */
    vv_preview_policy_record(&pol, VV_PREVIEW_BOXES, 0.002);
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_BOXES);
    vv_preview_policy_record(&pol, VV_PREVIEW_COARSE_MC, 0.01);
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_COARSE_MC);
    /* data too large to cast (1/8 at 5 times the budget): bounding boxes
     * before anything else is measured */
    vv_preview_policy_init(&pol);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_8, 0.15);
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_BBOX);
    pol.forced = VV_PREVIEW_BBOX;
    assert_int_equal(vv_preview_policy_choose(&pol, 0.03), VV_PREVIEW_BBOX);
    /* a machine that became quick again: every 24th choice probes a finer cast */
    vv_preview_policy_init(&pol);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_8, 0.002);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_4, 0.02);
    vv_preview_policy_record(&pol, VV_PREVIEW_RAYCAST_2, 0.04);
    int probes = 0;
    for (int i = 0; i < 48; i++)
        probes += vv_preview_policy_choose(&pol, 0.03) == VV_PREVIEW_RAYCAST_2;
    assert_int_equal(probes, 2);
    vv_preview_kind k;
    vt_ok(vv_preview_kind_parse("raycast_1/2", &k));
    assert_int_equal(k, VV_PREVIEW_RAYCAST_2);
    vt_ok(vv_preview_kind_parse("raycast_1/8", &k));
    assert_int_equal(k, VV_PREVIEW_RAYCAST_8);
    vt_err(vv_preview_kind_parse("fast", &k));
    int w, h;
    vv_preview_size(VV_PREVIEW_RAYCAST_4, 513, 7, &w, &h);
    assert_int_equal(w, 129);
    assert_int_equal(h, 2);
    vv_preview_size(VV_PREVIEW_RAYCAST_8, 1000, 801, &w, &h);
    assert_int_equal(w, 125);
    assert_int_equal(h, 101);
}

static double
coverage(const vv_image *img) {
    size_t n = (size_t)img->width * img->height, lit = 0;
    for (size_t i = 0; i < n; i++)
        lit += img->rgba[4 * i + 3] > 0.5f;
    return (double)lit / n;
}

/* Every representation of a ball shows a disc of about the right size; the
 * full one is exactly the final renderer's image. */
static void
test_preview_render(void **state) {
    (void)state;
    int dims[3] = {48, 48, 48};
    vv_volume *vol = NULL;
    vt_ok(vv_volume_new(&vol, dims, VV_U8));
    for (int k = 0; k < 48; k++)
        for (int j = 0; j < 48; j++)
            for (int i = 0; i < 48; i++) {
                double r = sqrt((i - 23.5) * (i - 23.5) + (j - 23.5) * (j - 23.5) +
                                (k - 23.5) * (k - 23.5));
                vv_volume_set(vol, i, j, k, r < 16 ? 200 : 0);
            }
    vv_volume_update_range(vol);
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = 96;
    o.mode = VV_MODE_ISO;
    o.has_isovalue = 1;
    o.isovalue = 100;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, vol, &o));
    vv_volume_free(vol);
    vv_preview *p = NULL;
    vt_ok(vv_preview_new(&p, "raycast"));
    double cov[VV_PREVIEW_COUNT];
    for (int k = 0; k < VV_PREVIEW_COUNT; k++) {
        int iw, ih;
        vv_preview_size((vv_preview_kind)k, 96, 96, &iw, &ih);
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, iw, ih));
        vt_ok(vv_preview_render(p, w, &w->view, (vv_preview_kind)k, NULL, img));
        cov[k] = coverage(img);
        if (k == VV_PREVIEW_FULL) {
            vv_renderer *r = NULL;
            vt_ok(vv_renderer_new(&r, "raycast"));
            vv_image *ref = NULL;
            vt_ok(vv_image_new(&ref, 96, 96));
            vt_ok(vv_renderer_render(r, w, &w->view, NULL, ref));
            assert_memory_equal(ref->rgba, img->rgba, sizeof(float) * 4 * 96 * 96);
            vv_image_free(ref);
            vv_renderer_free(r);
        }
        vv_image_free(img);
    }
    for (int k = 0; k < VV_PREVIEW_COUNT; k++)
        print_message("%s coverage %.3f\n", vv_preview_kind_name((vv_preview_kind)k), cov[k]);
    /* the ball's disc: the full image covers pi r^2 of the framed view */
    for (int k = VV_PREVIEW_COARSE_MC; k < VV_PREVIEW_COUNT; k++)
        assert_near(cov[k], cov[VV_PREVIEW_FULL], 0.1 * cov[VV_PREVIEW_FULL]);
    /* the boxes enclose the surface: a superset of the disc, not twice it */
    assert_true(cov[VV_PREVIEW_BOXES] >= cov[VV_PREVIEW_FULL]);
    assert_true(cov[VV_PREVIEW_BOXES] < 2 * cov[VV_PREVIEW_FULL]);
    assert_true(cov[VV_PREVIEW_FULL] > 0.05);
    assert_true(cov[VV_PREVIEW_BBOX] > 0.0); /* edges of the box */
    /* cache-building frames are flagged: the 1/4 ray cast was drawn first
     * unshaded, its second (shaded) frame built the gradients; now warm */
    {
        int iw, ih;
        vv_preview_size(VV_PREVIEW_RAYCAST_4, 96, 96, &iw, &ih);
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, iw, ih));
        vt_ok(vv_preview_render(p, w, &w->view, VV_PREVIEW_RAYCAST_4, NULL, img));
        assert_int_equal(vv_preview_last_warmup(p), 0);
        vv_image_free(img);
        vv_preview *q = NULL;
        vt_ok(vv_preview_new(&q, "raycast"));
        vt_ok(vv_image_new(&img, iw, ih));
        for (int r = 0; r < 3; r++) {
            vt_ok(vv_preview_render(q, w, &w->view, VV_PREVIEW_RAYCAST_4, NULL, img));
            assert_int_equal(vv_preview_last_warmup(q), r < 2);
        }
        vv_image_free(img);
        vv_preview_free(q);
    }
    vv_image *wrong = NULL;
    vt_ok(vv_image_new(&wrong, 96, 96));
    vt_err(vv_preview_render(p, w, &w->view, VV_PREVIEW_RAYCAST_2, NULL, wrong));
    vv_image_free(wrong);
    vv_preview_free(p);
    vv_world_free(w);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trackball),      cmocka_unit_test(test_pan_zoom),
        cmocka_unit_test(test_flight),         cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_objects_lights), cmocka_unit_test(test_policy),
        cmocka_unit_test(test_preview_render),
    };
    return vt_run_tests(tests, NULL, NULL);
}
