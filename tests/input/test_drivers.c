/*
 * The input drivers without hardware: libspnav against a fake spacenavd on
 * a socket named by $SPNAV_SOCKET (protocol v0: eight 32-bit integers per
 * event), SDL2 through a virtual joystick that looks like a game
 * controller, and the network driver's line protocol. Each also loses its
 * device mid-stream and the manager keeps going.
 */
#include "testutil.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#ifdef VV_HAVE_SDL2
#include <SDL2/SDL.h>
#endif

#include "input_collect.h"

static int
listen_at(const char *path) {
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_un a;
    memset(&a, 0, sizeof a);
    a.sun_family = AF_UNIX;
    snprintf(a.sun_path, sizeof a.sun_path, "%s", path);
    unlink(path);
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    assert_int_equal(listen(fd, 4), 0);
    return fd;
}

static int
connect_to(const char *path) {
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_un a;
    memset(&a, 0, sizeof a);
    a.sun_family = AF_UNIX;
    snprintf(a.sun_path, sizeof a.sun_path, "%s", path);
    assert_int_equal(connect(fd, (struct sockaddr *)&a, sizeof a), 0);
    return fd;
}

/* Waits (poll, no spinning) until the manager's descriptor is readable, then dispatches. */
static int
wait_dispatch(vv_input_manager *m, double now) {
    struct pollfd p = {vv_input_manager_fd(m), POLLIN, 0};
    poll(&p, 1, 2000);
    return vv_input_manager_dispatch(m, now);
}

/* ---- 3-D mouse: libspnav against a fake spacenavd ----------------------------- */

#ifdef VV_HAVE_SPNAV
static void
send_ev(int fd, int32_t a, int32_t b, int32_t c, int32_t d, int32_t e, int32_t f, int32_t g,
        int32_t h) {
    int32_t ev[8] = {a, b, c, d, e, f, g, h};
    assert_int_equal(write(fd, ev, sizeof ev), (ssize_t)sizeof ev);
}

static void
test_spnav(void **state) {
    (void)state;
    const char *path = temp_socket("spnav.sock");
    int lfd = listen_at(path);
    setenv("SPNAV_SOCKET", path, 1);
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, &c, NULL));
    int id = 0;
    /* the fake daemon speaks v0: libspnav's protocol request goes unanswered */
    vt_ok(vv_input_manager_open_spacenav(m, &id));
    vt_err(vv_input_manager_open_spacenav(m, NULL)); /* one connection per process */
    int dfd = accept(lfd, NULL, NULL);
    assert_true(dfd >= 0);
    char junk[64];
    fcntl(dfd, F_SETFL, O_NONBLOCK);
    (void)!read(dfd, junk, sizeof junk); /* the request and the sensitivity: ignored */

    /* motion with the default method: dominant axis (rz), dead zone 0.05, quadratic */
    send_ev(dfd, 0, 100, -50, 20, 0, 0, 175, 16);
    wait_dispatch(m, 1.0);
    int i = collect_find(&c, VV_ACTION_MOTION, 0);
    assert_true(i >= 0);
    double expect = vv_input_response(175.0 / 350, 0.05, 2);
    for (int k = 0; k < 5; k++)
        assert_true(c.a[i].motion[k] == 0);
    assert_true(c.a[i].motion[5] == expect);
    assert_near(c.a[i].dt, 0.016, 1e-15); /* the first motion uses the daemon's period */

    /* linear, all axes: the swap of method does not touch the application */
    vv_input_method mt = vv_input_method_default();
    vt_ok(vv_input_manager_set_method(m, id, &mt));
    send_ev(dfd, 0, 100, -50, 20, 0, 0, 175, 16);
    /* buttons: press, release (a click) and the binding's command */
    send_ev(dfd, 1, 0, 0, 0, 0, 0, 0, 0);
    send_ev(dfd, 2, 0, 0, 0, 0, 0, 0, 0);
    wait_dispatch(m, 1.1);
    i = collect_find(&c, VV_ACTION_MOTION, i + 1);
    assert_true(i >= 0);
    assert_true(c.a[i].motion[0] == 100.0 / 350 && c.a[i].motion[1] == -50.0 / 350 &&
                c.a[i].motion[2] == 20.0 / 350 && c.a[i].motion[5] == 0.5);
    assert_true(collect_find(&c, VV_ACTION_BUTTON_PRESS, i) > i);
    assert_true(collect_find(&c, VV_ACTION_BUTTON_CLICK, i) > i);
    int k = collect_find(&c, VV_ACTION_COMMAND, i);
    assert_true(k > i);
    assert_string_equal(c.a[k].command, "view.reset");

    /* garbage: an unknown type is dropped with a warning; huge values are clamped */
    uint64_t w = vv_input_manager_warning_count(m);
    send_ev(dfd, 99, 1, 2, 3, 4, 5, 6, 7);
    send_ev(dfd, 0, INT_MAX, INT_MIN, 0, 0, 0, 0, 0);
    send_ev(dfd, 1, 1000, 0, 0, 0, 0, 0, 0);
    wait_dispatch(m, 1.2);
    assert_true(vv_input_manager_warning_count(m) >= w + 3);
    vv_input_state st;
    vt_ok(vv_input_manager_state(m, id, &st));
    assert_true(st.axes[0] == 1 && st.axes[1] == -1);
    for (int a = 0; a < 6; a++)
        assert_true(isfinite(st.axes[a]));

    /* the daemon goes away: a removed action, the application goes on */
    close(dfd);
    wait_dispatch(m, 1.3);
    assert_int_equal(c.a[c.n - 1].kind, VV_ACTION_DEVICE_REMOVED);
    assert_int_equal(c.a[c.n - 1].device, id);
    vt_ok(vv_input_manager_state(m, id, &st));
    assert_int_equal(st.present, 0);
    vv_input_raw_event e = raw(VV_INPUT_KEYBOARD_ID, 2, VV_RAW_KEY, 0xff50, 1, 0);
    vt_ok(vv_input_manager_feed(m, &e));
    assert_int_equal(c.a[c.n - 1].kind, VV_ACTION_COMMAND);
    vv_input_manager_free(m);
    close(lfd);
    unlink(path);

    /* no daemon: a clear error */
    setenv("SPNAV_SOCKET", temp_socket("nobody.sock"), 1);
    vt_ok(vv_input_manager_new(&m, NULL));
    vt_err(vv_input_manager_open_spacenav(m, NULL));
    assert_non_null(strstr(vv_error_message(), "spacenavd"));
    vv_input_manager_free(m);
    unsetenv("SPNAV_SOCKET");
    collect_free(&c);
}
#endif

/* ---- game controllers: SDL2 with a virtual joystick ------------------------------- */

#ifdef VV_HAVE_SDL2
static void
test_sdl(void **state) {
    (void)state;
    setenv("SDL_VIDEODRIVER", "dummy", 1);
    setenv("SDL_AUDIODRIVER", "dummy", 1);
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, &c, NULL));
    vt_ok(vv_input_manager_open_controllers(m));
    assert_near(vv_input_manager_timeout(m, 0), 0.5, 1e-12); /* hot-plug poll only */

    SDL_VirtualJoystickDesc d;
    SDL_zero(d);
    d.version = SDL_VIRTUAL_JOYSTICK_DESC_VERSION;
    d.type = SDL_JOYSTICK_TYPE_GAMECONTROLLER;
    d.naxes = SDL_CONTROLLER_AXIS_MAX;
    d.nbuttons = SDL_CONTROLLER_BUTTON_MAX;
    d.name = "VolVis virtual pad";
    int idx = SDL_JoystickAttachVirtualEx(&d);
    assert_true(idx >= 0);
    SDL_Joystick *js = SDL_JoystickOpen(idx);
    assert_non_null(js);
    vv_input_manager_dispatch(m, 1.0);
    int i = collect_find(&c, VV_ACTION_DEVICE_ADDED, 0);
    assert_true(i >= 0);
    int id = c.a[i].device;
    vv_input_device_desc desc;
    vt_ok(vv_input_manager_device_get(m, id - 1, &desc));
    assert_int_equal(desc.kind, VV_INPUT_GAMECONTROLLER);
    assert_string_equal(desc.driver, "sdl");
    assert_near(vv_input_manager_timeout(m, 0), 1.0 / 60, 1e-12);

    SDL_JoystickSetVirtualAxis(js, SDL_CONTROLLER_AXIS_LEFTX, 16384);
    SDL_JoystickSetVirtualAxis(js, SDL_CONTROLLER_AXIS_TRIGGERRIGHT, 32767);
    SDL_JoystickSetVirtualButton(js, SDL_CONTROLLER_BUTTON_A, 1);
    vv_input_manager_dispatch(m, 1.1);
    SDL_JoystickSetVirtualButton(js, SDL_CONTROLLER_BUTTON_A, 0);
    vv_input_manager_dispatch(m, 1.2);
    vv_input_state st;
    vt_ok(vv_input_manager_state(m, id, &st));
    assert_true(st.axes[0] == vv_input_response(16384 / 32767.0, 0.1, 2));
    assert_true(st.axes[1] == 1); /* right trigger: up */
    assert_true(collect_find(&c, VV_ACTION_MOTION, i) > i);
    int k = collect_find(&c, VV_ACTION_COMMAND, i);
    assert_true(k > i);
    assert_string_equal(c.a[k].command, "select.next");
    assert_int_equal(c.a[k].button, SDL_CONTROLLER_BUTTON_A);
    assert_true(collect_find(&c, VV_ACTION_BUTTON_CLICK, i) > i);

    /* unplugged mid-stream */
    SDL_JoystickClose(js);
    SDL_JoystickDetachVirtual(idx);
    vv_input_manager_dispatch(m, 1.3);
    assert_int_equal(c.a[c.n - 1].kind, VV_ACTION_DEVICE_REMOVED);
    assert_int_equal(c.a[c.n - 1].device, id);
    assert_near(vv_input_manager_timeout(m, 0), 0.5, 1e-12);
    vv_input_manager_free(m);
    collect_free(&c);
}
#endif

/* ---- the network driver ---------------------------------------------------------------- */

static void
test_network(void **state) {
    (void)state;
    const char *path = temp_socket("net.sock");
    vv_input_manager *m = new_manager();
    collect c = {0};
    vt_ok(vv_input_manager_subscribe(m, NULL, collect_fn, &c, NULL));
    vt_ok(vv_input_manager_listen(m, path));
    int fd = connect_to(path);
    wait_dispatch(m, 5.0); /* the connection */
    const char *msg = "# a script drives the navigator\n"
                      "device 1 network script\n"
                      "axis 1 0 0.5\n"
                      "button 1 3 1\n"
                      "axis 1 9 0.5\n"
                      "pointer 1 0 nan 1\n"
                      "frobnicate\n";
    assert_int_equal(write(fd, msg, strlen(msg)), (ssize_t)strlen(msg));
    wait_dispatch(m, 5.5);
    int i = collect_find(&c, VV_ACTION_DEVICE_ADDED, 0);
    assert_true(i >= 0);
    int id = c.a[i].device;
    i = collect_find(&c, VV_ACTION_MOTION, i);
    assert_true(i >= 0);
    assert_true(c.a[i].motion[0] == 0.5 && c.a[i].time == 5.5 && c.a[i].device == id);
    assert_true(collect_find(&c, VV_ACTION_BUTTON_PRESS, i) > i);
    assert_true(vv_input_manager_warning_count(m) >= 3);
    /* the client is told what was wrong, line by line */
    char reply[512] = "";
    struct pollfd p = {fd, POLLIN, 0};
    assert_int_equal(poll(&p, 1, 2000), 1);
    ssize_t n = read(fd, reply, sizeof reply - 1);
    assert_true(n > 0);
    reply[n] = '\0';
    assert_non_null(strstr(reply, "error line 5: axis code 9 out of range"));
    assert_non_null(strstr(reply, "error line 6: value 1 'nan' is not finite"));
    assert_non_null(strstr(reply, "error line 7: unknown event kind 'frobnicate'"));
    /* a second client on its own device ids; then the first disconnects */
    int fd2 = connect_to(path);
    wait_dispatch(m, 6.0);
    const char *msg2 = "device 1 dataglove glove\npose 1 0 1 2 3 1 0 0 0\n";
    assert_int_equal(write(fd2, msg2, strlen(msg2)), (ssize_t)strlen(msg2));
    wait_dispatch(m, 6.1);
    i = collect_find(&c, VV_ACTION_POSE, 0);
    assert_true(i >= 0 && c.a[i].device != id && c.a[i].position.z == 3);
    close(fd);
    wait_dispatch(m, 7.0);
    assert_int_equal(c.a[c.n - 1].kind, VV_ACTION_DEVICE_REMOVED);
    assert_int_equal(c.a[c.n - 1].device, id);
    close(fd2);
    wait_dispatch(m, 7.1);
    vv_input_manager_free(m);
    collect_free(&c);
    vt_err(vv_input_manager_new(&m, NULL) == VV_OK ? vv_input_manager_listen(m, "/nonexistent/x/y")
                                                   : VV_ERR_IO);
    vv_input_manager_free(m);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
#ifdef VV_HAVE_SPNAV
        cmocka_unit_test(test_spnav),
#endif
#ifdef VV_HAVE_SDL2
        cmocka_unit_test(test_sdl),
#endif
        cmocka_unit_test(test_network),
    };
    int r = vt_run_tests(tests, NULL, NULL);
    if (socket_dir()[0])
        rmdir(socket_dir());
    return r;
}
