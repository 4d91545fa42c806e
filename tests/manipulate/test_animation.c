/*
 * The Animator's model: interpolation (keys hit exactly, Catmull–Rom through
 * its keys, slerp on the unit sphere at constant angular speed, a closed path
 * C1 at its seam, easing, TF blending), property paths, evaluation into World
 * snapshots, sequences, the flight recorder, and animation files (round trip
 * and one-line errors with file, line and key).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static vv_anim_track *
track_with(vv_animation *a, const char *prop, int n, const double *times, const double (*vals)[4]) {
    int ti;
    vt_ok(vv_animation_add_track(a, prop, &ti));
    for (int i = 0; i < n; i++) {
        vv_anim_key k;
        vv_anim_key_init(&k, times[i]);
        memcpy(k.value, vals[i], sizeof k.value);
        vt_ok(vv_anim_track_add_key(&a->tracks[ti], &k));
    }
    return &a->tracks[ti];
}

static void
test_keys_hit_and_catmull_rom(void **state) {
    (void)state;
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    const double t[5] = {0, 1, 2.5, 3, 5};
    const double v[5][4] = {{0, 0, 0}, {1, 2, 0}, {3, -1, 2}, {4, 0, 1}, {2, 2, 2}};
    vv_anim_track *tr = track_with(a, "view.eye", 5, t, v);
    double out[4];
    for (int i = 0; i < 5; i++) {
        vt_ok(vv_anim_track_eval(tr, t[i], out, NULL));
        for (int c = 0; c < 3; c++)
            assert_true(out[c] == v[i][c]); /* exactly */
    }
    /* Catmull–Rom with uneven times: velocity at key i is (P[i+1] - P[i-1]) /
     * (t[i+1] - t[i-1]); measure it by finite differences from both sides */
    for (int i = 1; i < 4; i++) {
        double h = 1e-6, lo[4], hi[4];
        vt_ok(vv_anim_track_eval(tr, t[i] - h, lo, NULL));
        vt_ok(vv_anim_track_eval(tr, t[i] + h, hi, NULL));
        for (int c = 0; c < 3; c++) {
            double want = (v[i + 1][c] - v[i - 1][c]) / (t[i + 1] - t[i - 1]);
            assert_near((v[i][c] - lo[c]) / h, want, 1e-4);
            assert_near((hi[c] - v[i][c]) / h, want, 1e-4);
        }
    }
    /* clamped outside the keys */
    vt_ok(vv_anim_track_eval(tr, -3, out, NULL));
    assert_true(out[0] == 0);
    vt_ok(vv_anim_track_eval(tr, 99, out, NULL));
    assert_true(out[0] == 2);
    /* two keys: a straight line at constant speed */
    vv_animation_free(a);
    vt_ok(vv_animation_new(&a));
    const double t2[2] = {0, 2};
    const double v2[2][4] = {{0, 0, 0}, {4, 2, -2}};
    tr = track_with(a, "objects[0].position", 2, t2, v2);
    vt_ok(vv_anim_track_eval(tr, 0.5, out, NULL));
    assert_near(out[0], 1, 1e-12);
    assert_near(out[1], 0.5, 1e-12);
    assert_near(out[2], -0.5, 1e-12);
    vv_animation_free(a);
}

static void
test_kb_parameters_and_easing(void **state) {
    (void)state;
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    const double t[3] = {0, 1, 2};
    const double v[3][4] = {{0}, {1}, {0}};
    vv_anim_track *tr = track_with(a, "lights[0].intensity", 3, t, v);
    /* tension 1 at the middle key: zero tangent there (a flat top) */
    tr->keys[1].tension = 1;
    double lo[4], hi[4];
    vt_ok(vv_anim_track_eval(tr, 1 - 1e-5, lo, NULL));
    vt_ok(vv_anim_track_eval(tr, 1 + 1e-5, hi, NULL));
    assert_near((1 - lo[0]) / 1e-5, 0, 1e-3);
    assert_near((1 - hi[0]) / 1e-5, 0, 1e-3);
    /* linear interpolation with ease-in-out: halfway in time is halfway in
     * value, a quarter of the way is 3u^2 - 2u^3 */
    tr->interp = VV_INTERP_LINEAR;
    tr->keys[0].easing = VV_EASE_IN_OUT;
    double o[4];
    vt_ok(vv_anim_track_eval(tr, 0.5, o, NULL));
    assert_near(o[0], 0.5, 1e-12);
    vt_ok(vv_anim_track_eval(tr, 0.25, o, NULL));
    assert_near(o[0], 3 * 0.0625 - 2 * 0.015625, 1e-12);
    tr->keys[0].easing = VV_EASE_IN;
    vt_ok(vv_anim_track_eval(tr, 0.25, o, NULL));
    assert_near(o[0], 0.0625, 1e-12);
    tr->interp = VV_INTERP_STEP;
    vt_ok(vv_anim_track_eval(tr, 0.99, o, NULL));
    assert_true(o[0] == 0);
    vv_animation_free(a);
}

static void
test_slerp_unit_constant_speed(void **state) {
    (void)state;
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    vv_quat q0 = vv_quat_from_axis_angle(vv_vec3_make(0, 0, 1), 0.2);
    vv_quat q1 = vv_quat_from_axis_angle(vv_vec3_make(1, 1, 0), 2.0);
    const double t[2] = {0, 1};
    const double v[2][4] = {{q0.w, q0.x, q0.y, q0.z}, {q1.w, q1.x, q1.y, q1.z}};
    vv_anim_track *tr = track_with(a, "objects.head.orientation", 2, t, v);
    tr->interp = VV_INTERP_LINEAR;
    double total = 2 * acos(fabs(q0.w * q1.w + q0.x * q1.x + q0.y * q1.y + q0.z * q1.z));
    double prev[4];
    vt_ok(vv_anim_track_eval(tr, 0, prev, NULL));
    const int n = 20;
    for (int i = 1; i <= n; i++) {
        double q[4];
        vt_ok(vv_anim_track_eval(tr, (double)i / n, q, NULL));
        assert_near(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1, 1e-12);
        double d = fabs(q[0] * prev[0] + q[1] * prev[1] + q[2] * prev[2] + q[3] * prev[3]);
        double step = 2 * acos(d > 1 ? 1 : d);
        assert_near(step, total / n, 1e-9);
        memcpy(prev, q, sizeof q);
    }
    /* squad through three keys: unit quaternions, keys hit */
    vv_anim_key k;
    vv_anim_key_init(&k, 2);
    vv_quat q2 = vv_quat_from_axis_angle(vv_vec3_make(0, 1, 0), -1.0);
    k.value[0] = q2.w, k.value[1] = q2.x, k.value[2] = q2.y, k.value[3] = q2.z;
    vt_ok(vv_anim_track_add_key(tr, &k));
    tr->interp = VV_INTERP_SPLINE;
    for (int i = 0; i <= 40; i++) {
        double q[4];
        vt_ok(vv_anim_track_eval(tr, i / 20.0, q, NULL));
        assert_near(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1, 1e-12);
    }
    double q[4];
    vt_ok(vv_anim_track_eval(tr, 1, q, NULL));
    assert_near(q[0], q1.w, 1e-12);
    assert_near(q[1], q1.x, 1e-12);
    vv_animation_free(a);
}

static void
test_closed_path_c1_at_seam(void **state) {
    (void)state;
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    /* a loop through four points, uneven times, back to the start */
    const double t[5] = {0, 1, 2.5, 3, 4};
    const double v[5][4] = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0.5}, {0, -1, 0}, {1, 0, 0}};
    vv_anim_track *tr = track_with(a, "view.eye", 5, t, v);
    tr->closed = 1;
    vt_ok(vv_animation_validate(a));
    double h = 1e-6, s0[4], s1[4], e0[4], e1[4];
    vt_ok(vv_anim_track_eval(tr, 0, s0, NULL));
    vt_ok(vv_anim_track_eval(tr, h, s1, NULL));
    vt_ok(vv_anim_track_eval(tr, 4 - h, e0, NULL));
    vt_ok(vv_anim_track_eval(tr, 4, e1, NULL));
    for (int c = 0; c < 3; c++) {
        assert_true(s0[c] == e1[c]);                                 /* C0 */
        assert_near((s1[c] - s0[c]) / h, (e1[c] - e0[c]) / h, 1e-4); /* C1 */
    }
    /* the velocity at the seam is the wrapped Catmull–Rom one */
    assert_near((s1[1] - s0[1]) / h, (v[1][1] - v[3][1]) / (1.0 + 1.0), 1e-4);
    /* not closed: the end velocities differ */
    tr->closed = 0;
    vt_ok(vv_anim_track_eval(tr, h, s1, NULL));
    vt_ok(vv_anim_track_eval(tr, 4 - h, e0, NULL));
    assert_true(fabs((s1[0] - s0[0]) / h - (e1[0] - e0[0]) / h) > 0.1);
    /* a closed track must end where it starts */
    tr->closed = 1;
    tr->keys[4].value[0] = 2;
    vt_err(vv_animation_validate(a));
    assert_non_null(strstr(vv_error_message(), "keys[4]"));
    vv_animation_free(a);
}

static void
test_tf_blend(void **state) {
    (void)state;
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    int ti;
    vt_ok(vv_animation_add_track(a, "objects[0].tf", &ti));
    vv_tf tf0, tf1;
    vv_tf_set_ramp(&tf0, 0, 100, 1, vv_vec3_make(1, 0, 0), 1);
    vv_tf_init(&tf1);
    vt_ok(vv_tf_add_opacity(&tf1, 0, 0));
    vt_ok(vv_tf_add_opacity(&tf1, 50, 1));
    vt_ok(vv_tf_add_opacity(&tf1, 200, 0));
    vt_ok(vv_tf_add_color(&tf1, 0, vv_vec3_make(0, 0, 1)));
    vv_anim_key k;
    vv_anim_key_init(&k, 0);
    k.tf = &tf0;
    vt_ok(vv_anim_track_add_key(&a->tracks[ti], &k));
    vv_anim_key_init(&k, 1);
    k.tf = &tf1;
    vt_ok(vv_anim_track_add_key(&a->tracks[ti], &k));
    vv_tf out;
    double v[4];
    vt_ok(vv_anim_track_eval(&a->tracks[ti], 0, v, &out));
    assert_memory_equal(&out, &tf0, sizeof out);
    vt_ok(vv_anim_track_eval(&a->tracks[ti], 0.5, v, &out));
    /* different point counts: resampled on the union of values, blended */
    for (double x = 0; x <= 200; x += 25) {
        double want = 0.5 * vv_tf_eval_opacity(&tf0, x) + 0.5 * vv_tf_eval_opacity(&tf1, x);
        assert_near(vv_tf_eval_opacity(&out, x), want, 1e-12);
    }
    vv_vec3 c = vv_tf_eval_color(&out, 10);
    assert_near(c.x, 0.5, 1e-12);
    assert_near(c.z, 0.5, 1e-12);
    vv_animation_free(a);
}

static void
test_properties(void **state) {
    (void)state;
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    const char *good[] = {"view.eye",
                          "view.fov",
                          "background",
                          "lights[2].direction",
                          "cut_planes[0].point",
                          "objects[3].material.color",
                          "objects.head.tf",
                          "objects.head.cut_planes[1].normal",
                          "objects[0].orientation"};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++)
        vt_ok(vv_animation_add_track(a, good[i], NULL));
    assert_int_equal(a->tracks[4].kind, VV_ANIM_VEC3);
    assert_int_equal(a->tracks[6].kind, VV_ANIM_TF);
    assert_int_equal(a->tracks[8].kind, VV_ANIM_QUAT);
    const char *bad[] = {"view.eyes",        "objects.head",      "objects[x].position",
                         "lights.intensity", "objects[0].colour", "",
                         "camera.eye"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        vt_err(vv_animation_add_track(a, bad[i], NULL));
    vv_animation_free(a);
}

/* A small World: one volume object named "volume" with the default view. */
static vv_world *
small_world(void) {
    vv_volume *v;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = 32;
    vv_world *w;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    vv_volume_free(v);
    return w;
}

static void
test_eval_world_and_sequences(void **state) {
    (void)state;
    vv_world *w = small_world();
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    a->duration = 2;
    a->fps = 10;
    assert_int_equal(vv_animation_frame_count(a), 20);
    const double t[2] = {0, 1};
    const double fov[2][4] = {{0.3}, {0.6}};
    track_with(a, "view.fov", 2, t, fov);
    const double iso[2][4] = {{10}, {90}};
    track_with(a, "objects.volume.isovalue", 2, t, iso);
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.type = VV_SEQ_ORBIT;
    q.degrees = 90;
    q.zoom = 1;
    vt_ok(vv_animation_add_sequence(a, &q));
    memset(&q, 0, sizeof q);
    q.type = VV_SEQ_SWEEP_CUT;
    q.normal = vv_vec3_make(1, 0, 0);
    q.point = vv_vec3_make(-10, 0, 0);
    q.distance = 20;
    vt_ok(vv_animation_add_sequence(a, &q));
    vt_ok(vv_animation_check_world(a, w));
    vv_world *s;
    vt_ok(vv_animation_eval_frame(a, w, 10, &s)); /* t = 1, halfway */
    assert_near(s->view.fov, 0.6, 1e-12);
    assert_near(s->objects[0]->isovalue, 90, 1e-12);
    assert_int_equal(s->n_cut_planes, w->n_cut_planes + 1);
    assert_near(s->cut_planes[s->n_cut_planes - 1].point.x, 0, 1e-12);
    /* the orbit turned the eye by 45 degrees about up, at the same distance */
    vv_vec3 d0 = vv_vec3_sub(w->view.eye, w->view.at), d1 = vv_vec3_sub(s->view.eye, s->view.at);
    assert_near(vv_vec3_length(d0), vv_vec3_length(d1), 1e-9 * vv_vec3_length(d0));
    assert_near(acos(vv_vec3_dot(d0, d1) / vv_vec3_dot(d0, d0)), VV_PI / 4, 1e-9);
    /* the base is untouched */
    assert_near(w->objects[0]->isovalue, w->objects[0]->isovalue, 0);
    assert_true(w->objects[0]->isovalue != 90);
    vv_world_free(s);
    /* the time form agrees with the frame form */
    vt_ok(vv_animation_eval(a, w, 1.0, &s));
    assert_near(s->view.fov, 0.6, 1e-12);
    vv_world_free(s);
    /* a missing target is an error naming the track */
    vt_ok(vv_animation_add_track(a, "objects.nobody.position", NULL));
    vt_err(vv_animation_check_world(a, w));
    assert_non_null(strstr(vv_error_message(), "nobody"));
    vt_err(vv_animation_eval(a, w, 0, &s));
    assert_null(s);
    vv_animation_free(a);
    vv_world_free(w);
}

static void
test_rotate_object(void **state) {
    (void)state;
    vv_world *w = small_world();
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.type = VV_SEQ_ROTATE_OBJECT;
    snprintf(q.object, sizeof q.object, "%s", w->objects[0]->name);
    q.axis = vv_vec3_make(0, 0, 1);
    q.degrees = 180;
    vt_ok(vv_animation_add_sequence(a, &q));
    vv_box b0 = vv_object_world_box(w->objects[0]);
    vv_world *s;
    vt_ok(vv_animation_eval(a, w, 0.5, &s)); /* half of 180 */
    vv_box b1 = vv_object_world_box(s->objects[0]);
    /* turned in place: the box centre stays */
    assert_near(b1.min.x + b1.max.x, b0.min.x + b0.max.x, 1e-9);
    assert_near(b1.min.y + b1.max.y, b0.min.y + b0.max.y, 1e-9);
    vv_quat o = s->objects[0]->orientation;
    assert_near(2 * acos(fabs(o.w)), VV_PI / 2, 1e-9);
    vv_world_free(s);
    vv_animation_free(a);
    vv_world_free(w);
}

static void
test_flight_recorder(void **state) {
    (void)state;
    vv_flight_recorder *r;
    vt_ok(vv_flight_recorder_new(&r));
    vv_view v;
    memset(&v, 0, sizeof v);
    v.up = vv_vec3_make(0, 0, 1);
    v.fov = 0.5;
    v.width = v.height = 64;
    /* 3 s at 30 Hz: a straight line, then a quarter circle */
    for (int i = 0; i <= 90; i++) {
        double t = i / 30.0;
        if (t <= 1.5)
            v.eye = vv_vec3_make(0, -100 + 40 * t, 0);
        else {
            double ang = (t - 1.5) / 1.5 * VV_PI / 2;
            v.eye = vv_vec3_make(40 * sin(ang), -40 * cos(ang), 0);
        }
        v.at = vv_vec3_make(0, 0, 0);
        vt_ok(vv_flight_recorder_add(r, 10 + t, &v));
    }
    vt_err(vv_flight_recorder_add(r, 10, &v)); /* time goes back */
    assert_int_equal(vv_flight_recorder_count(r), 91);
    vv_animation *a;
    vt_ok(vv_flight_recorder_finish(r, 0.5, vv_deg_to_rad(1), 30, &a));
    assert_int_equal(a->n_tracks, 3); /* eye, at, up: the fov did not change */
    int keys = a->tracks[0].n_keys;
    assert_true(keys >= 3 && keys < 40); /* the straight part is one segment */
    assert_near(a->tracks[0].keys[0].time, 0, 1e-12);
    assert_near(a->duration, 3 + 1 / 30.0, 1e-9);
    /* the thinned path stays near every sample */
    vv_world *w;
    vt_ok(vv_world_new(&w));
    for (int i = 0; i <= 90; i += 7) {
        double t = i / 30.0, e[4];
        vt_ok(vv_anim_track_eval(&a->tracks[0], t, e, NULL));
        vv_vec3 want = t <= 1.5 ? vv_vec3_make(0, -100 + 40 * t, 0)
                                : vv_vec3_make(40 * sin((t - 1.5) / 1.5 * VV_PI / 2),
                                               -40 * cos((t - 1.5) / 1.5 * VV_PI / 2), 0);
        assert_true(vv_vec3_length(vv_vec3_sub(vv_vec3_make(e[0], e[1], e[2]), want)) < 2.0);
    }
    vv_world_free(w);
    /* saved as an animation file and read back */
    const char *path = vt_path(vt_outdir("manipulate"), "flight.json");
    vt_ok(vv_animation_save(a, path));
    vv_animation *b;
    vt_ok(vv_animation_load(&b, path));
    assert_int_equal(b->n_tracks, 3);
    assert_int_equal(b->tracks[0].n_keys, keys);
    for (int k = 0; k < keys; k++)
        assert_true(b->tracks[0].keys[k].value[1] == a->tracks[0].keys[k].value[1]);
    vv_animation_free(b);
    vv_animation_free(a);
    vv_flight_recorder_free(r);
}

static const char *
write_text(const char *name, const char *text) {
    const char *p = vt_path(vt_outdir("manipulate"), name);
    vt_write_file(p, text, strlen(text));
    return p;
}

static void
test_file_roundtrip(void **state) {
    (void)state;
    const char *path = write_text(
        "good.json", "{\n"
                     "  \"volvis_animation\": 1,\n"
                     "  \"scene\": \"head.json\",\n"
                     "  \"fps\": 24,\n"
                     "  \"tracks\": [\n"
                     "    {\"property\": \"view.fov\", \"keys\": [\n"
                     "      {\"time\": 0, \"value\": 30},\n"
                     "      {\"time\": 2, \"value\": 20, \"easing\": \"ease-out\"}]},\n"
                     "    {\"property\": \"objects.head.orientation\",\n"
                     "     \"interpolation\": \"slerp\", \"keys\": [\n"
                     "      {\"time\": 0, \"value\": {\"axis\": [0, 0, 1], \"angle\": 0}},\n"
                     "      {\"time\": 1, \"value\": {\"axis\": [0, 0, 1], \"angle\": 90},\n"
                     "       \"tension\": 0.5}]},\n"
                     "    {\"property\": \"objects[0].tf\", \"keys\": [\n"
                     "      {\"time\": 0, \"value\": {\"opacity\": [[0, 0], [100, 1]]}},\n"
                     "      {\"time\": 1, \"value\": {\"opacity\": [[50, 0], [90, 0.5]],\n"
                     "        \"color\": [[0, [1, 0, 0]]]}}]}\n"
                     "  ],\n"
                     "  \"sequences\": [{\"type\": \"orbit\", \"degrees\": 360}]\n"
                     "}\n");
    vv_animation *a;
    vt_ok(vv_animation_load(&a, path));
    assert_string_equal(a->scene, "head.json");
    assert_near(a->fps, 24, 0);
    assert_near(a->duration, 2 + 1 / 24.0, 1e-12); /* the last key is the last frame */
    assert_near(a->tracks[0].keys[1].value[0], vv_deg_to_rad(20), 1e-15);
    assert_int_equal(a->tracks[0].keys[1].easing, VV_EASE_OUT);
    assert_int_equal(a->tracks[1].interp, VV_INTERP_LINEAR);
    assert_near(a->tracks[1].keys[1].tension, 0.5, 0);
    assert_int_equal(a->tracks[2].keys[1].tf->n_color, 1);
    assert_int_equal(a->n_sequences, 1);
    const char *out = vt_path(vt_outdir("manipulate"), "good_saved.json");
    vt_ok(vv_animation_save(a, out));
    vv_animation *b;
    vt_ok(vv_animation_load(&b, out));
    assert_int_equal(b->n_tracks, 3);
    assert_near(b->tracks[0].keys[1].value[0], a->tracks[0].keys[1].value[0], 1e-15);
    assert_memory_equal(b->tracks[2].keys[1].tf, a->tracks[2].keys[1].tf, sizeof(vv_tf));
    assert_near(b->duration, a->duration, 1e-15);
    vv_animation *c;
    vt_ok(vv_animation_clone(&c, b));
    assert_int_equal(c->tracks[2].n_keys, 2);
    vv_animation_free(c);
    vv_animation_free(b);
    vv_animation_free(a);
}

/* Loads @p text and checks that the one-line error names the file, the
 * line and @p key. */
static void
expect_error(const char *name, const char *text, int line, const char *key) {
    const char *path = write_text(name, text);
    vv_animation *a = (vv_animation *)1;
    vt_err(vv_animation_load(&a, path));
    assert_null(a);
    const char *m = vv_error_message();
    char want[256];
    snprintf(want, sizeof want, "%s:%d:", path, line);
    if (!strstr(m, want) || (key && !strstr(m, key)) || strchr(m, '\n'))
        fail_msg("error '%s' lacks '%s' or '%s'", m, want, key ? key : "");
}

static void
test_file_errors(void **state) {
    (void)state;
    expect_error(
        "unknown_prop.json",
        "{\"tracks\": [\n"
        "  {\"property\": \"view.eye\", \"keys\": [{\"time\": 0, \"value\": [0, 0, 0]}]},\n"
        "  {\"property\": \"view.colour\", \"keys\": [{\"time\": 0, \"value\": 1}]}]}\n",
        3, "tracks[1].property");
    expect_error("unknown_key.json",
                 "{\"tracks\": [\n"
                 "  {\"property\": \"view.fov\",\n"
                 "   \"keys\": [{\"time\": 0, \"value\": 30, \"tensoin\": 1}]}]}\n",
                 3, "tracks[0].keys[0].tensoin");
    expect_error("order.json",
                 "{\"tracks\": [{\"property\": \"view.fov\", \"keys\": [\n"
                 "  {\"time\": 0, \"value\": 30},\n"
                 "  {\"time\": 2, \"value\": 30},\n"
                 "  {\"time\": 1, \"value\": 20}]}]}\n",
                 4, "tracks[0].keys[2].time");
    expect_error("nan.json",
                 "{\"tracks\": [{\"property\": \"view.fov\", \"keys\": [\n"
                 "  {\"time\": 0, \"value\": NaN}]}]}\n",
                 2, NULL);
    expect_error("empty.json",
                 "{\"tracks\": [{\"property\": \"view.fov\",\n"
                 "  \"keys\": []}]}\n",
                 2, "tracks[0].keys");
    expect_error("badvalue.json",
                 "{\"tracks\": [{\"property\": \"view.eye\", \"keys\": [\n"
                 "  {\"time\": 0, \"value\": [0, 0]}]}]}\n",
                 2, "tracks[0].keys[0].value");
    expect_error("closed.json",
                 "{\"tracks\": [{\"property\": \"view.fov\", \"closed\": true, \"keys\": [\n"
                 "  {\"time\": 0, \"value\": 30},\n"
                 "  {\"time\": 1, \"value\": 20}]}]}\n",
                 3, "keys[1]");
    expect_error("nothing.json", "{\"fps\": 30}\n", 1, "nothing to animate");
    expect_error("syntax.json", "{\"tracks\": [\n  {\"property\": }]}\n", 2, NULL);
    vv_animation *a;
    vt_err(vv_animation_load(&a, vt_path(vt_outdir("manipulate"), "does_not_exist.json")));
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_keys_hit_and_catmull_rom),
        cmocka_unit_test(test_kb_parameters_and_easing),
        cmocka_unit_test(test_slerp_unit_constant_speed),
        cmocka_unit_test(test_closed_path_c1_at_seam),
        cmocka_unit_test(test_tf_blend),
        cmocka_unit_test(test_properties),
        cmocka_unit_test(test_eval_world_and_sequences),
        cmocka_unit_test(test_rotate_object),
        cmocka_unit_test(test_flight_recorder),
        cmocka_unit_test(test_file_roundtrip),
        cmocka_unit_test(test_file_errors),
    };
    return vt_run_tests(tests, NULL, NULL);
}
