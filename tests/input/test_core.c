/*
 * The Device Unified Interface without hardware: simulation methods
 * (analytic), the information base, keyboard and mouse feeds, record and
 * replay (bit-for-bit), snap-dragging and two-hand gestures from replayed
 * gloves, malformed replay files, NaN and huge values.
 */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "input_collect.h"

#define outdir() vt_outdir("input")

static void
write_text(const char *path, const char *text) {
    vt_write_file(path, text, strlen(text));
}

/* ---- pure simulation functions ------------------------------------------- */

static void
test_response(void **state) {
    (void)state;
    assert_true(vv_input_response(0.05, 0.1, 1) == 0);
    assert_near(vv_input_response(0.55, 0.1, 1), 0.5, 1e-15);
    assert_near(vv_input_response(-0.55, 0.1, 2), -0.25, 1e-15);
    assert_near(vv_input_response(0.5, 0, 3), 0.125, 1e-15);
    assert_true(vv_input_response(7, 0.1, 2) == 1);
    assert_true(vv_input_response(NAN, 0, 1) == 0);
    double v[6] = {0.1, -0.2, 0.05, 0.3, -0.9, 0.4};
    vv_input_dominant_axis(v);
    for (int i = 0; i < 6; i++)
        assert_true(v[i] == (i == 4 ? -0.9 : 0));
}

static void
test_snap(void **state) {
    (void)state;
    vv_vec3 feats[2] = {{10, 10, 0}, {50, 0, 0}};
    vv_input_snap_params p = {1, 15 * VV_PI / 180, 5, 3, feats, 2};
    int s, f;
    /* nearly along x: axis snap, then the grid along x */
    vv_vec3 r = vv_input_snap(&p, vv_vec3_make(0, 0, 0), vv_vec3_make(21, 2, 0), &s, &f);
    assert_int_equal(s, VV_SNAP_AXIS | VV_SNAP_GRID);
    assert_int_equal(f, -1);
    assert_true(r.x == 20 && r.y == 0 && r.z == 0);
    /* 45 degrees: no axis, grid on every coordinate */
    r = vv_input_snap(&p, vv_vec3_make(0, 0, 0), vv_vec3_make(21, 22, 0), &s, &f);
    assert_int_equal(s, VV_SNAP_GRID);
    assert_true(r.x == 20 && r.y == 20);
    /* near a feature point: the point wins */
    r = vv_input_snap(&p, vv_vec3_make(0, 0, 0), vv_vec3_make(11, 9, 1), &s, &f);
    assert_int_equal(s, VV_SNAP_FEATURE);
    assert_int_equal(f, 0);
    assert_true(r.x == 10 && r.y == 10 && r.z == 0);
}

static void
test_two_hand_solve(void **state) {
    (void)state;
    /* hands 2 apart along x move to 4 apart along y, midpoint up by 3 */
    vv_input_two_hand r = vv_input_two_hand_solve(vv_vec3_make(0, 0, 0), vv_vec3_make(2, 0, 0),
                                                  vv_vec3_make(1, 1, 0), vv_vec3_make(1, 5, 0));
    assert_near(r.translation.x, 0, 1e-15);
    assert_near(r.translation.y, 3, 1e-15);
    assert_near(r.scale, 2, 1e-15);
    vv_vec3 x = vv_quat_rotate(r.rotation, vv_vec3_make(1, 0, 0));
    assert_near(x.x, 0, 1e-12);
    assert_near(x.y, 1, 1e-12);
    /* 90 degrees about +z */
    assert_near(r.rotation.w, cos(VV_PI / 4), 1e-12);
    assert_near(r.rotation.z, sin(VV_PI / 4), 1e-12);
    /* opposite directions: a half turn; degenerate pair: identity */
    r = vv_input_two_hand_solve(vv_vec3_make(0, 0, 0), vv_vec3_make(1, 0, 0), vv_vec3_make(0, 0, 0),
                                vv_vec3_make(-1, 0, 0));
    x = vv_quat_rotate(r.rotation, vv_vec3_make(1, 0, 0));
    assert_near(x.x, -1, 1e-12);
    r = vv_input_two_hand_solve(vv_vec3_make(1, 1, 1), vv_vec3_make(1, 1, 1), vv_vec3_make(0, 0, 0),
                                vv_vec3_make(1, 0, 0));
    assert_true(r.scale == 1 && r.rotation.w == 1);
}

/* ---- information base ------------------------------------------------------ */

static void
test_devinfo(void **state) {
    (void)state;
    const char *dirs[] = {DEVDIR};
    vv_input_devinfo_db *db = NULL;
    vt_ok(vv_input_devinfo_db_load(&db, dirs, 1));
    const vv_input_devinfo *sb = vv_input_devinfo_db_get(db, VV_INPUT_SPACEBALL);
    assert_int_equal(sb->n_dof, 6);
    assert_true(sb->coupled);
    assert_true(sb->method.dominant_axis);
    assert_true(sb->dof[0].max == 350);
    assert_non_null(strstr(sb->source, "spaceball.json"));
    const vv_input_devinfo *kb = vv_input_devinfo_db_get(db, VV_INPUT_KEYBOARD);
    assert_int_equal(kb->n_bindings, 8);
    vv_input_devinfo_db_free(db);

    /* a user directory overrides one kind; a broken file is a clear error */
    const char *dir = outdir();
    char sub[512];
    snprintf(sub, sizeof sub, "%s/devices-user", dir);
    vt_ok(mkdir(sub, 0755) == 0 || errno == EEXIST ? VV_OK : VV_ERR_IO);
    write_text(vt_path(sub, "mouse.json"),
               "{\"kind\": \"mouse\", \"name\": \"Trackball\", \"pixels_per_unit\": 50}\n");
    const char *dirs2[] = {DEVDIR, sub};
    vt_ok(vv_input_devinfo_db_load(&db, dirs2, 2));
    assert_string_equal(vv_input_devinfo_db_get(db, VV_INPUT_MOUSE)->name, "Trackball");
    assert_true(vv_input_devinfo_db_get(db, VV_INPUT_MOUSE)->pixels_per_unit == 50);
    vv_input_devinfo_db_free(db);
    write_text(vt_path(sub, "mouse.json"), "{\"kind\": \"mouse\",\n \"method\": {\"name\": 3}\n");
    vt_err(vv_input_devinfo_db_load(&db, dirs2, 2));
    assert_non_null(strstr(vv_error_message(), "mouse.json"));
    assert_non_null(strstr(vv_error_message(), "line"));
    write_text(vt_path(sub, "mouse.json"),
               "{\"kind\": \"mouse\", \"method\": {\"name\": \"direct\", \"exponent\": 0}}");
    vt_err(vv_input_devinfo_db_load(&db, dirs2, 2));
    assert_non_null(strstr(vv_error_message(), "exponent"));
    remove(vt_path(sub, "mouse.json"));
}

/* ---- keyboard and mouse ---------------------------------------------------- */

static void
test_keyboard(void **state) {
    (void)state;
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, &c, NULL));
    vv_input_raw_event e = raw(VV_INPUT_KEYBOARD_ID, 1.0, VV_RAW_KEY, 0xff50, 1, 0); /* Home */
    vt_ok(vv_input_manager_feed(m, &e));
    assert_int_equal(c.n, 1);
    assert_int_equal(c.a[0].kind, VV_ACTION_COMMAND);
    assert_string_equal(c.a[0].command, "view.reset");
    e = raw(VV_INPUT_KEYBOARD_ID, 1.1, VV_RAW_KEY, 0xff53, 1, 0); /* Right held */
    vt_ok(vv_input_manager_feed(m, &e));
    assert_int_equal(c.a[1].kind, VV_ACTION_MOTION);
    assert_true(c.a[1].motion[0] == 1);
    e.v[0] = 0;
    e.time = 1.2;
    vt_ok(vv_input_manager_feed(m, &e));
    assert_true(c.a[2].motion[0] == 0);
    /* a binding set by the application replaces the information base's */
    vt_ok(vv_input_manager_bind(m, VV_INPUT_KEYBOARD_ID, VV_RAW_KEY, 'r', "view.reset"));
    e = raw(VV_INPUT_KEYBOARD_ID, 1.3, VV_RAW_KEY, 'r', 1, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    assert_string_equal(c.a[3].command, "view.reset");
    vv_input_manager_free(m);
    collect_free(&c);
}

/* A mouse drag: press left at (100,100), move right by 10 px per step, release. */
static void
feed_drag(vv_input_manager *m, int dev) {
    vv_input_raw_event e = raw(dev, 10.0, VV_RAW_POINTER, 0, 100, 100);
    vt_ok(vv_input_manager_feed(m, &e));
    e = raw(dev, 10.01, VV_RAW_BUTTON, 1, 1, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    for (int i = 1; i <= 20; i++) {
        e = raw(dev, 10.01 + 0.016 * i, VV_RAW_POINTER, 0, 100 + 10 * i, 100 + 0.3 * i);
        vt_ok(vv_input_manager_feed(m, &e));
    }
    e = raw(dev, 10.5, VV_RAW_BUTTON, 1, 0, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    e = raw(dev, 10.6, VV_RAW_SCROLL, 0, 0, -2);
    vt_ok(vv_input_manager_feed(m, &e));
}

static void
run_replay(const char *path, collect *c, vv_input_state *st) {
    vv_input_manager *m = new_manager();
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, c, NULL));
    int first = 0, n = 0;
    vt_ok(vv_input_manager_open_replay(m, path, 100.0, 1.0, &first, &n));
    assert_int_equal(n, 2);
    assert_true(vv_input_manager_replay_pending(m));
    /* the virtual clock: nothing is due before the start, everything after */
    assert_int_equal(vv_input_manager_dispatch(m, 99.0), 0);
    assert_near(vv_input_manager_timeout(m, 99.0), 1.0, 1e-12);
    double now = 100.0;
    while (vv_input_manager_replay_pending(m)) {
        vv_input_manager_dispatch(m, now);
        now += 0.05;
    }
    assert_true(vv_input_manager_timeout(m, now) < 0);
    vt_ok(vv_input_manager_state(m, first + 1, st)); /* the mouse is the file's second device */
    vv_input_manager_free(m);
}

static void
test_mouse_record_replay(void **state) {
    (void)state;
    const char *path = vt_path(outdir(), "drag.vvin");
    vv_input_manager *m = new_manager();
    collect live = {0};
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, &live, NULL));
    vt_ok(vv_input_manager_record_start(m, path));
    feed_drag(m, VV_INPUT_MOUSE_ID);
    vt_ok(vv_input_manager_record_stop(m));
    vv_input_state live_st;
    vt_ok(vv_input_manager_state(m, VV_INPUT_MOUSE_ID, &live_st));
    vv_input_manager_free(m);

    /* the drag: 20 motions rotating about y by 10/200 each, a click, a dolly */
    assert_int_equal(collect_count(&live, VV_ACTION_MOTION), 21);
    int i = collect_find(&live, VV_ACTION_MOTION, 0);
    assert_true(live.a[i].motion[4] == 10.0 / 200);
    assert_near(live.a[i].motion[3], 0.3 / 200, 1e-15);
    assert_int_equal(collect_count(&live, VV_ACTION_BUTTON_CLICK), 0); /* 0.49 s > 0.3 s */
    assert_true(live_st.position.x == 300 && live_st.buttons == 0);

    collect a = {0}, b = {0};
    vv_input_state sa, sb;
    run_replay(path, &a, &sa);
    run_replay(path, &b, &sb);
    assert_int_equal(a.n, live.n);
    for (int k = 0; k < live.n; k++) {
        a.a[k].device = b.a[k].device = live.a[k].device; /* ids differ between managers */
        if (memcmp(&a.a[k], &live.a[k], sizeof live.a[k]) != 0)
            fail_msg("action %d (%s) differs between the live feed and the replay", k,
                     vv_input_action_kind_name(live.a[k].kind));
    }
    assert_memory_equal(a.a, b.a, (size_t)a.n * sizeof *a.a);
    assert_memory_equal(&sa, &live_st, sizeof sa);
    assert_memory_equal(&sa, &sb, sizeof sa);
    collect_free(&live);
    collect_free(&a);
    collect_free(&b);
}

/* A stalled caller: the replay is delayed by the stall, not compressed. */
static void
test_replay_stall(void **state) {
    (void)state;
    const char *path = vt_path(outdir(), "stall.vvin");
    write_text(path, "volvis-input 1\n"
                     "device 1 spaceball puck\n"
                     "0 motion6 1 0 0 0 0 0 0 0 16\n"
                     "1.0 motion6 1 0 0 0 0 0 350 0 16\n"
                     "1.25 motion6 1 0 0 0 0 0 300 0 16\n"
                     "1.5 motion6 1 0 0 0 0 0 0 0 16\n");
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, "navigator", collect_fn, &c, NULL));
    vt_ok(vv_input_manager_open_replay(m, path, 10.0, 1.0, NULL, NULL));
    vv_input_manager_dispatch(m, 10.05); /* 0.05 s late: on time enough */
    int n0 = collect_count(&c, VV_ACTION_MOTION);
    assert_near(vv_input_manager_timeout(m, 10.05), 0.95, 1e-9);
    /* the caller stalls 3 s: the first motion now, the rest at its spacing */
    vv_input_manager_dispatch(m, 14.0);
    assert_int_equal(collect_count(&c, VV_ACTION_MOTION), n0 + 1);
    assert_near(vv_input_manager_timeout(m, 14.0), 0.25, 1e-9);
    vv_input_manager_dispatch(m, 14.2);
    assert_int_equal(collect_count(&c, VV_ACTION_MOTION), n0 + 1);
    vv_input_manager_dispatch(m, 14.25);
    assert_int_equal(collect_count(&c, VV_ACTION_MOTION), n0 + 2);
    assert_true(vv_input_manager_replay_pending(m));
    vv_input_manager_dispatch(m, 14.5);
    assert_false(vv_input_manager_replay_pending(m));
    /* recorded times are kept */
    int i = collect_find(&c, VV_ACTION_MOTION, n0);
    assert_true(i >= 0 && c.a[i].time == 1.0 && c.a[i].motion[4] > 0);
    vv_input_manager_free(m);
    collect_free(&c);
}

/* ---- gloves: snap-dragging and two hands ----------------------------------- */

static void
test_snap_drag_replay(void **state) {
    (void)state;
    const char *path = vt_path(outdir(), "glove-snap.vvin");
    write_text(path, "volvis-input 1\n"
                     "device 7 dataglove right hand\n"
                     "0.0 pose 7 0 0 0 0 1 0 0 0\n"
                     "0.1 button 7 0 1           # pinch: the drag starts at the origin\n"
                     "0.2 pose 7 0 23 2 0 1 0 0 0   # nearly along x\n"
                     "0.3 pose 7 0 47 3 20 1 0 0 0  # off-axis: grid\n"
                     "0.4 pose 7 0 58 41 0 1 0 0 0  # near the feature (60,40,0)\n"
                     "0.5 button 7 0 0\n");
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, "navigator", collect_fn, &c, NULL));
    int id = 0;
    vt_ok(vv_input_manager_open_replay(m, path, 0, INFINITY, &id, NULL));
    vv_input_method mt;
    vt_ok(vv_input_manager_get_method(m, id, &mt));
    assert_true(mt.grid == 10 && mt.feature_radius == 20); /* from dataglove.json */
    mt.kind = VV_METHOD_SNAP_DRAG;
    mt.feature_radius = 5;
    vt_ok(vv_input_manager_set_method(m, id, &mt));
    vv_vec3 feat = {60, 40, 0};
    vt_ok(vv_input_manager_set_features(m, id, &feat, 1));
    vt_ok(vv_input_manager_assign(m, id, "navigator"));
    vv_input_manager_dispatch(m, 0);
    assert_int_equal(collect_count(&c, VV_ACTION_SNAP_DRAG), 3);
    int i = collect_find(&c, VV_ACTION_SNAP_DRAG, 0);
    assert_int_equal(c.a[i].snap, VV_SNAP_AXIS | VV_SNAP_GRID);
    assert_true(c.a[i].position.x == 20 && c.a[i].position.y == 0 && c.a[i].position.z == 0);
    i = collect_find(&c, VV_ACTION_SNAP_DRAG, i + 1);
    assert_int_equal(c.a[i].snap, VV_SNAP_GRID);
    assert_true(c.a[i].position.x == 50 && c.a[i].position.y == 0 && c.a[i].position.z == 20);
    i = collect_find(&c, VV_ACTION_SNAP_DRAG, i + 1);
    assert_int_equal(c.a[i].snap, VV_SNAP_FEATURE);
    assert_int_equal(c.a[i].feature, 0);
    assert_true(c.a[i].position.x == 60 && c.a[i].position.y == 40);
    /* a subscriber of another application does not see the navigator's device */
    collect other = {0};
    vt_ok(vv_input_manager_subscribe(m, "animator", collect_fn, &other, NULL));
    vv_input_raw_event e = raw(id, 1.0, VV_RAW_BUTTON, 0, 1, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    assert_int_equal(other.n, 0);
    vv_input_manager_free(m);
    collect_free(&c);
    collect_free(&other);
}

static void
test_two_hand_replay(void **state) {
    (void)state;
    const char *path = vt_path(outdir(), "gloves-two-hand.vvin");
    /* left hand at -1, right at +1 on x; they spread and turn to the y axis */
    write_text(path, "volvis-input 1\n"
                     "device 1 dataglove left\n"
                     "device 2 dataglove right\n"
                     "0.00 pose 1 0 -1 0 0 1 0 0 0\n"
                     "0.00 pose 2 0 1 0 0 1 0 0 0\n"
                     "0.10 pose 1 0 -0.5 -1 0 1 0 0 0\n"
                     "0.10 pose 2 0 0.8 1.5 0 1 0 0 0\n"
                     "0.20 pose 1 0 0 -2 1 1 0 0 0\n"
                     "0.20 pose 2 0 0 2 1 1 0 0 0\n");
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, &c, NULL));
    int id = 0;
    vt_ok(vv_input_manager_open_replay(m, path, 0, INFINITY, &id, NULL));
    vt_ok(vv_input_manager_pair(m, id, id + 1));
    vv_input_manager_dispatch(m, 0);
    assert_int_equal(collect_count(&c, VV_ACTION_TWO_HAND), 4);
    vv_vec3 t = {0, 0, 0};
    double s = 1;
    vv_quat q = vv_quat_identity();
    for (int i = 0; i < c.n; i++)
        if (c.a[i].kind == VV_ACTION_TWO_HAND) {
            assert_int_equal(c.a[i].device, id);
            t = vv_vec3_add(t, c.a[i].translation);
            s *= c.a[i].scale;
            q = vv_quat_mul(c.a[i].rotation, q);
        }
    /* analytic: midpoint (0,0,0) -> (0,0,1), distance 2 -> 4, x axis -> y axis */
    assert_near(t.x, 0, 1e-12);
    assert_near(t.y, 0, 1e-12);
    assert_near(t.z, 1, 1e-12);
    assert_near(s, 2, 1e-12);
    vv_vec3 d = vv_quat_rotate(q, vv_vec3_make(1, 0, 0));
    assert_near(d.x, 0, 1e-12);
    assert_near(d.y, 1, 1e-12);
    assert_near(d.z, 0, 1e-12);
    vv_input_manager_free(m);
    collect_free(&c);
}

/* ---- bad input -------------------------------------------------------------- */

static void
test_bad_replay_files(void **state) {
    (void)state;
    static const struct {
        const char *text, *expect;
    } cases[] = {
        {"", "empty file"},
        {"hello 1\n", "line 1: expected the header"},
        {"volvis-input 2\n", "line 1: unsupported version"},
        {"volvis-input 1\n", "declares no device"},
        {"volvis-input 1\ndevice 1 toaster t\n", "line 2: unknown device kind 'toaster'"},
        {"volvis-input 1\ndevice 1 mouse m\ndevice 1 mouse n\n", "line 3: device id declared"},
        {"volvis-input 1\ndevice 1 mouse m\n0 pointer 2 0 1 1\n", "line 3: device 2 was not"},
        {"volvis-input 1\ndevice 1 mouse m\n0 pointer 1 0 1\n", "line 3: 'pointer' takes"},
        {"volvis-input 1\ndevice 1 mouse m\n0 pointer 1 0 nan 1\n", "line 3: value 1 'nan' is not "
                                                                    "finite"},
        {"volvis-input 1\ndevice 1 mouse m\n0 pointer 1 0 1x 1\n", "line 3: value 1 '1x' is not a"},
        {"volvis-input 1\ndevice 1 mouse m\n1 pointer 1 0 1 1\n0.5 pointer 1 0 1 1\n",
         "line 4: time 0.5 goes backwards"},
        {"volvis-input 1\ndevice 1 mouse m\ninf pointer 1 0 1 1\n", "line 3: time 'inf'"},
        {"volvis-input 1\ndevice 1 mouse m\n0 button 1 64 1\n", "line 3: button code 64"},
        {"volvis-input 1\ndevice 1 mouse m\n0 jump 1 0 1\n", "line 3: unknown event kind"},
        {"volvis-input 1\ndevice 1 mouse m\n0 axis 1 -1 0.5\n", "line 3: code '-1'"},
    };
    vv_input_manager *m = new_manager();
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *path = vt_path(outdir(), "bad.vvin");
        write_text(path, cases[i].text);
        vt_err(vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL));
        if (!strstr(vv_error_message(), cases[i].expect) ||
            !strstr(vv_error_message(), "bad.vvin") || strchr(vv_error_message(), '\n'))
            fail_msg("case %zu: expected '%s' in one line, got '%s'", i, cases[i].expect,
                     vv_error_message());
    }
    /* binary garbage and an over-long line */
    const char *path = vt_path(outdir(), "bad.vvin");
    vt_write_file(path, "volvis-input 1\n\0\1\2", 18);
    vt_err(vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL));
    char *big = malloc(5000);
    memset(big, 'x', 4999);
    big[4999] = '\0';
    memcpy(big, "volvis-input 1\n", 15);
    write_text(path, big);
    free(big);
    vt_err(vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL));
    assert_non_null(strstr(vv_error_message(), "line 2: line longer"));
    vt_err(vv_input_manager_open_replay(m, vt_path(outdir(), "missing.vvin"), 0, 1, NULL, NULL));
    assert_int_equal(vv_input_manager_device_count(m), 2); /* nothing half-added */
    vv_input_manager_free(m);
}

static void
state_finite(const vv_input_state *s) {
    const double *d = (const double *)s;
    for (size_t i = 0; i < offsetof(vv_input_state, buttons) / sizeof(double); i++)
        assert_true(isfinite(d[i]));
}

static void
test_nan_and_huge(void **state) {
    (void)state;
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, &c, NULL));
    int sb;
    vt_ok(vv_input_manager_device_add(m, VV_INPUT_SPACEBALL, "fake", &sb));
    uint64_t w0 = vv_input_manager_warning_count(m);
    vv_input_raw_event e = raw(VV_INPUT_MOUSE_ID, 1, VV_RAW_POINTER, 0, NAN, 3);
    vt_ok(vv_input_manager_feed(m, &e));
    assert_int_equal(c.n, 0);
    assert_int_equal(vv_input_manager_warning_count(m), w0 + 1);
    assert_non_null(strstr(vv_input_manager_last_warning(m), "non-finite"));
    e = raw(VV_INPUT_MOUSE_ID, INFINITY, VV_RAW_POINTER, 0, 1, 3);
    vt_ok(vv_input_manager_feed(m, &e));
    e = raw(VV_INPUT_MOUSE_ID, 2, VV_RAW_POINTER, 0, 1e300, -1e300);
    vt_ok(vv_input_manager_feed(m, &e));
    vv_input_state st;
    vt_ok(vv_input_manager_state(m, VV_INPUT_MOUSE_ID, &st));
    assert_true(st.position.x == 1e6 && st.position.y == -1e6);
    state_finite(&st);
    e = raw(sb, 3, VV_RAW_MOTION6, 0, 1e308, -1e308);
    e.v[2] = 5;
    e.v[6] = 1e9;
    vt_ok(vv_input_manager_feed(m, &e));
    vt_ok(vv_input_manager_state(m, sb, &st));
    state_finite(&st);
    assert_true(fabs(st.axes[0]) <= 1);
    e = raw(sb, 4, VV_RAW_POSE, 0, 0, 0); /* zero quaternion -> identity */
    vt_ok(vv_input_manager_feed(m, &e));
    vt_ok(vv_input_manager_state(m, sb, &st));
    assert_true(st.orientation.w == 1);
    state_finite(&st);
    /* unknown device or kind: an error and a warning, no crash */
    e = raw(99, 1, VV_RAW_KEY, 1, 1, 0);
    vt_err(vv_input_manager_feed(m, &e));
    e = raw(VV_INPUT_KEYBOARD_ID, 1, (vv_input_raw_kind)77, 1, 1, 0);
    vt_err(vv_input_manager_feed(m, &e));
    e = raw(VV_INPUT_MOUSE_ID, 5, VV_RAW_BUTTON, 64, 1, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    assert_true(vv_input_manager_warning_count(m) >= w0 + 6);
    /* removed: further events are dropped, the manager keeps working */
    e = raw(sb, 6, VV_RAW_REMOVED, 0, 0, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    assert_int_equal(c.a[c.n - 1].kind, VV_ACTION_DEVICE_REMOVED);
    int n = c.n;
    e = raw(sb, 7, VV_RAW_AXIS, 0, 0.5, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    assert_int_equal(c.n, n);
    vv_input_method bad = vv_input_method_default();
    bad.exponent = NAN;
    vt_err(vv_input_manager_set_method(m, sb, &bad));
    vv_input_manager_free(m);
    collect_free(&c);
}

static void
test_idle(void **state) {
    (void)state;
    vv_input_manager *m = new_manager();
    assert_true(vv_input_manager_fd(m) >= 0);
    assert_true(vv_input_manager_timeout(m, vv_input_now()) < 0);
    struct pollfd p = {vv_input_manager_fd(m), POLLIN, 0};
    assert_int_equal(poll(&p, 1, 50), 0);
    assert_int_equal(vv_input_manager_dispatch(m, vv_input_now()), 0);
    vv_input_manager_free(m);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_response),        cmocka_unit_test(test_snap),
        cmocka_unit_test(test_two_hand_solve),  cmocka_unit_test(test_devinfo),
        cmocka_unit_test(test_keyboard),        cmocka_unit_test(test_mouse_record_replay),
        cmocka_unit_test(test_replay_stall),    cmocka_unit_test(test_snap_drag_replay),
        cmocka_unit_test(test_two_hand_replay), cmocka_unit_test(test_bad_replay_files),
        cmocka_unit_test(test_nan_and_huge),    cmocka_unit_test(test_idle),
    };
    return vt_run_tests(tests, NULL, NULL);
}
