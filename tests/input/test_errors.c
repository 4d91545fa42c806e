/*
 * Hostile input to the input drivers ("our own parsers under attack"):
 *
 * - replay files (src/input/replay.c): every refusal, each one line naming
 *   the file and the line; devices and drivers past the manager's limits.
 * - the network protocol (src/input/net.c): what a remote device sends --
 *   malformed, oversized, partial, binary lines, too many devices and
 *   clients -- is answered "error line N: why" and counted as a warning,
 *   never a crash; the listener's own refusals.
 */
#include "testutil.h"

#define check_message(st, want, needle, file, what) vt_expect_refusal(what, st, want, needle, file)

#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "input_collect.h"

#define outdir() vt_outdir("input_errors")

/* ---- replay files ------------------------------------------------------------ */

static void
test_replay_refusals(void **state) {
    (void)state;
    static const struct {
        const char *text, *needle;
    } cases[] = {
        {"volvis-input 1\na b c d e f g h i j k l m n o p\n", "line 2: too many fields"},
        {"volvis-input 1\ndevice 1 mouse\n", "line 2: 'device' takes an id, a kind and a name"},
        {"volvis-input 1\ndevice x mouse m\n", "line 2: device id is not an integer in 1..1000000"},
        {"volvis-input 1\ndevice 0 mouse m\n", "line 2: device id is not an integer"},
        {"volvis-input 1\ndevice 1 mouse m\n12\n", "line 3: expected 'device ...' or 'TIME KIND"},
        {"volvis-input 1\ndevice 1 mouse m\n0 axis 1 9 0.5\n", "line 3: axis code 9 out of range"},
        {"volvis-input 1\ndevice 1 mouse m\n0 axis x 0 0.5\n",
         "line 3: device 'x' is not an integer"},
        {"volvis-input 1\ndevice 1 \x1b[2Jmouse m\n",
         "line 2: unknown device kind '\\x1b[2Jmouse'"},
        {"\xff\xfe volvis\n", "line 1: expected the header"},
        {"volvis-input 1\0\n", "contains NUL bytes"},
    };
    vv_input_manager *m = new_manager();
    const int devices = vv_input_manager_device_count(m); /* the keyboard and the mouse */
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *path = vt_path(outdir(), "bad.vvin");
        size_t n = strlen(cases[i].text);
        if (strstr(cases[i].needle, "NUL"))
            n = 16;
        vt_write_file(path, cases[i].text, n);
        vv_error_clear();
        check_message(vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL), VV_ERR_FORMAT,
                      cases[i].needle, "bad.vvin", cases[i].needle);
    }
    /* 17 devices */
    char text[2048] = "volvis-input 1\n";
    for (int d = 1; d <= 17; d++)
        snprintf(text + strlen(text), sizeof text - strlen(text), "device %d mouse m%d\n", d, d);
    const char *path = vt_path(outdir(), "many.vvin");
    vt_write_file(path, text, strlen(text));
    check_message(vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL), VV_ERR_FORMAT,
                  "line 18: more than 16 devices", "many.vvin", "17 devices");
    /* the arguments, a missing file */
    check_message(vv_input_manager_open_replay(m, path, 0, 0, NULL, NULL), VV_ERR_INVALID,
                  "replay: needs a file, a finite start and speed > 0", NULL, "speed 0");
    check_message(vv_input_manager_open_replay(NULL, path, 0, 1, NULL, NULL), VV_ERR_INVALID,
                  "replay: needs a file", NULL, "no manager");
    check_message(
        vv_input_manager_open_replay(m, vt_path(outdir(), "absent.vvin"), 0, 1, NULL, NULL),
        VV_ERR_IO, "replay", "absent.vvin", "missing");
    assert_int_equal(vv_input_manager_device_count(m), devices); /* nothing half-added */
    vv_input_manager_free(m);
}

/* Past the manager's devices (64) and drivers (8): refused naming the file. */
static void
test_replay_limits(void **state) {
    (void)state;
    char text[2048] = "volvis-input 1\n";
    for (int d = 1; d <= 16; d++)
        snprintf(text + strlen(text), sizeof text - strlen(text), "device %d mouse m%d\n", d, d);
    const char *path = vt_path(outdir(), "sixteen.vvin");
    vt_write_file(path, text, strlen(text));
    vv_input_manager *m = new_manager();
    vv_status st = VV_OK;
    int opened = 0;
    while (opened < 10 && (st = vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL)) == VV_OK)
        opened++;
    assert_int_equal(opened, 3); /* 2 + 3 * 16 devices, and 16 more are too many */
    check_message(st, VV_ERR_LIMIT, "too many devices for the manager", "sixteen.vvin", "devices");
    vv_input_manager_free(m);

    path = vt_path(outdir(), "one.vvin");
    const char *one = "volvis-input 1\ndevice 1 mouse m\n0 button 1 0 1\n";
    vt_write_file(path, one, strlen(one));
    m = new_manager();
    opened = 0;
    while (opened < 20 && (st = vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL)) == VV_OK)
        opened++;
    assert_true(opened < 20);
    check_message(st, VV_ERR_LIMIT, "drivers", "one.vvin", "drivers");
    vv_input_manager_free(m);
}

/* ---- the network protocol ---------------------------------------------------- */

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

/* Dispatches until the manager has nothing more to read (poll, no spinning). */
static void
pump(vv_input_manager *m) {
    struct pollfd p = {vv_input_manager_fd(m), POLLIN, 0};
    while (poll(&p, 1, 200) == 1)
        vv_input_manager_dispatch(m, 1.0);
}

/* Sends @p n bytes of @p text on @p fd, lets the manager read them, and
 * returns what the server answered (empty when nothing). */
static const char *
exchange(vv_input_manager *m, int fd, const char *text, size_t n) {
    static char reply[4096];
    assert_int_equal(write(fd, text, n), (ssize_t)n);
    pump(m);
    size_t got = 0;
    struct pollfd p = {fd, POLLIN, 0};
    while (got + 1 < sizeof reply && poll(&p, 1, 100) == 1) {
        ssize_t r = read(fd, reply + got, sizeof reply - 1 - got);
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    reply[got] = '\0';
    return reply;
}

static void
expect_reply(vv_input_manager *m, int fd, const char *line, const char *want) {
    uint64_t w0 = vv_input_manager_warning_count(m);
    const char *r = exchange(m, fd, line, strlen(line));
    if (!strstr(r, want))
        fail_msg("'%s': the reply '%s' lacks '%s'", line, r, want);
    assert_int_equal(vv_input_manager_warning_count(m), w0 + 1);
    if (!strstr(vv_input_manager_last_warning(m), "network: line "))
        fail_msg("'%s': warning '%s'", line, vv_input_manager_last_warning(m));
    /* one printable line, whatever the client sent */
    for (const char *c = vv_input_manager_last_warning(m); *c; c++)
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            fail_msg("'%s': warning '%s' holds byte 0x%02x", line, vv_input_manager_last_warning(m),
                     (unsigned char)*c);
}

static void
test_network_protocol(void **state) {
    (void)state;
    const char *path = temp_socket("p.sock");
    vv_input_manager *m = new_manager();
    vt_ok(vv_input_manager_listen(m, path));
    /* a name with terminal escapes (and a tab) is kept printable */
    int fd = connect_to(path);
    pump(m);
    assert_string_equal(exchange(m, fd, "device 2 mouse a\x1b[2J\tb\x07\n", 24), "");
    vv_input_device_desc dd;
    vt_ok(vv_input_manager_device_get(m, vv_input_manager_device_count(m) - 1, &dd));
    assert_string_equal(dd.name, "a [2J b ");
    close(fd);
    pump(m);
    fd = connect_to(path);
    pump(m);
    assert_string_equal(exchange(m, fd, "device 1 mouse m\n", 17), "");
    expect_reply(m, fd, "a b c d e f g h i j k l m n o p\n", "error line 2: too many fields");
    expect_reply(m, fd, "device 2\n", "error line 3: 'device' takes an id (1..1000000)");
    expect_reply(m, fd, "device x mouse m\n", "error line 4: 'device' takes an id");
    expect_reply(m, fd, "device 2 toaster t\n", "error line 5: unknown device kind 'toaster'");
    expect_reply(m, fd, "device 1 mouse again\n", "error line 6: device 1 declared twice");
    expect_reply(m, fd, "pointer 5 0 1 1\n",
                 "error line 7: device 5 was not declared on this connection");
    expect_reply(m, fd, "jump 1 0\n", "error line 8: unknown event kind 'jump'");
    expect_reply(m, fd, "pointer 1 0 1e999 1\n", "error line 9: value 1 '1e999' is not finite");
    /* an over-long line and binary garbage: dropped whole, the next line read */
    char *big = malloc(3000);
    assert_non_null(big);
    memset(big, 'x', 2999);
    big[2999] = '\n';
    uint64_t w0 = vv_input_manager_warning_count(m);
    const char *r = exchange(m, fd, big, 3000);
    free(big);
    assert_non_null(strstr(r, "error line 10: line too long"));
    assert_non_null(strstr(vv_input_manager_last_warning(m), "longer than 1024 characters"));
    assert_int_equal(vv_input_manager_warning_count(m), w0 + 1);
    r = exchange(m, fd, "button 1\0\x01\x02 3 1\n", 16);
    assert_non_null(strstr(r, "error line 11: line too long"));
    /* a line in pieces is read once it is whole */
    assert_string_equal(exchange(m, fd, "button 1 ", 9), "");
    assert_string_equal(exchange(m, fd, "3 1\n", 4), "");
    expect_reply(m, fd, "button 1 99 1\n", "error line 13: button code 99 out of range");
    /* up to 8 devices on one connection */
    for (int d = 2; d <= 8; d++) {
        char line[64];
        snprintf(line, sizeof line, "device %d mouse m%d\n", d, d);
        assert_string_equal(exchange(m, fd, line, strlen(line)), "");
    }
    expect_reply(m, fd, "device 9 mouse m9\n", "error line 21: more than 8 devices on one");
    /* an escape sequence in what the client names: the warning holds '?' */
    expect_reply(m, fd, "jump\x1b[2J 1 0\n", "error line 22: unknown event kind");
    /* the manager's 64 devices (the keyboard and the mouse among them): more
     * connections of 8 until one is refused */
    int more[8], nmore = 0, refused = 0;
    while (!refused && nmore < 8) {
        const int c = nmore++;
        more[c] = connect_to(path);
        pump(m);
        for (int d = 1; d <= 8 && !refused; d++) {
            char line[64];
            snprintf(line, sizeof line, "device %d mouse c%dm%d\n", d, c, d);
            uint64_t w = vv_input_manager_warning_count(m);
            r = exchange(m, more[c], line, strlen(line));
            if (r[0]) {
                if (!strstr(r, "input: more than 64 devices"))
                    fail_msg("device %d of connection %d: reply '%s'", d, c, r);
                assert_int_equal(vv_input_manager_warning_count(m), w + 1);
                refused = 1;
            }
        }
    }
    assert_true(refused);
    assert_int_equal(vv_input_manager_device_count(m), 64);
    /* a partial line, then the client goes: nothing is fed */
    assert_string_equal(exchange(m, more[nmore - 1], "button 1 0", 10), "");
    for (int c = 0; c < nmore; c++)
        close(more[c]);
    pump(m);
    /* more than 16 clients: the 17th is refused with a warning */
    int cl[17];
    cl[0] = fd;
    for (int c = 1; c < 17; c++) {
        cl[c] = connect_to(path);
        pump(m);
    }
    assert_non_null(strstr(vv_input_manager_last_warning(m), "more than 16 clients"));
    char b;
    struct pollfd p = {cl[16], POLLIN, 0};
    assert_int_equal(poll(&p, 1, 2000), 1);
    assert_int_equal(read(cl[16], &b, 1), 0); /* closed by the server */
    for (int c = 0; c < 17; c++)
        close(cl[c]);
    pump(m);
    vv_input_manager_free(m);
}

static void
test_network_listen(void **state) {
    (void)state;
    vv_input_manager *m = new_manager();
    check_message(vv_input_manager_listen(m, ""), VV_ERR_INVALID, "network: needs a socket path",
                  NULL, "empty");
    check_message(vv_input_manager_listen(NULL, "x"), VV_ERR_INVALID, "needs a socket path", NULL,
                  "no manager");
    char lng[200];
    memset(lng, 'a', sizeof lng - 1);
    lng[sizeof lng - 1] = '\0';
    lng[0] = '/';
    check_message(vv_input_manager_listen(m, lng), VV_ERR_INVALID,
                  "socket path longer than 107 bytes", NULL, "long");
    check_message(vv_input_manager_listen(m, "/nonexistent/dir/x.sock"), VV_ERR_IO, NULL, "x.sock",
                  "bind");
    const char *path = temp_socket("l.sock");
    vt_ok(vv_input_manager_listen(m, path));
    check_message(vv_input_manager_listen(m, path), VV_ERR_INVALID, "network: already listening",
                  NULL, "twice");
    vv_input_manager_free(m);
    /* no driver left for the listener: refused naming the socket */
    m = new_manager();
    const char *one = "volvis-input 1\ndevice 1 mouse m\n";
    const char *rp = vt_path(outdir(), "one.vvin");
    vt_write_file(rp, one, strlen(one));
    while (vv_input_manager_open_replay(m, rp, 0, 1, NULL, NULL) == VV_OK)
        ;
    check_message(vv_input_manager_listen(m, temp_socket("full.sock")), VV_ERR_LIMIT, "drivers",
                  "full.sock", "drivers");
    vv_input_manager_free(m);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_replay_refusals),
        cmocka_unit_test(test_replay_limits),
        cmocka_unit_test(test_network_protocol),
        cmocka_unit_test(test_network_listen),
    };
    int r = vt_run_tests(tests, NULL, NULL);
    if (socket_dir()[0]) {
        unlink(temp_socket("p.sock"));
        unlink(temp_socket("l.sock"));
        unlink(temp_socket("full.sock"));
        rmdir(socket_dir());
    }
    return r;
}
