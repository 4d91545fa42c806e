/*
 * volvis devices: the input devices found (keyboard and mouse always, a
 * 3-D mouse when spacenavd answers, the game controllers SDL sees), their
 * information-base entries and the application each is assigned to; also
 * --assign DEVICE APP (kept in a small JSON file), --replay FILE (prints the
 * actions of a recording) and --record FILE (records a device for a while).
 */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <jansson.h>

#include "cli.h"

static const cli_opt_spec dev_opts[] = {
    {"device-dir", 0, "DIR"},   {"config", 0, "FILE"}, {"assign", 0, "DEVICE"},
    {"replay", 0, "FILE"},      {"record", 0, "FILE"}, {"device", 0, "SOURCE"},
    {"duration", 0, "SECONDS"}, {"no-probe", 0, NULL},
};
#define N_DEV_OPTS ((int)(sizeof dev_opts / sizeof dev_opts[0]))

void
cli_devices_usage(FILE *out) {
    fprintf(
        out,
        "usage: volvis devices [OPTIONS]\n"
        "       volvis devices --assign DEVICE APP\n"
        "       volvis devices --replay FILE\n"
        "       volvis devices --record FILE --device SOURCE [--duration SECONDS]\n"
        "\n"
        "Lists the input devices found (keyboard and mouse always, a 3-D mouse when\n"
        "spacenavd answers, the game controllers SDL sees), what the device information\n"
        "base says of each (degrees of freedom, coupled or independent, good for,\n"
        "default simulation method) and the application each is assigned to.\n"
        "\n"
        "Options:\n"
        "  --device-dir DIR  read the information base from DIR (default: the installed\n"
        "                    share/volvis/devices, ~/.config/volvis/devices,\n"
        "                    $VOLVIS_DEVICE_DIR)\n"
        "  --config FILE     the assignments file (default\n"
        "                    $XDG_CONFIG_HOME/volvis/input.json or ~/.config/volvis/input.json)\n"
        "  --assign DEVICE APP  assign a device kind (keyboard, mouse, spaceball,\n"
        "                    gamecontroller, dataglove, network) to an application\n"
        "                    (navigator, animator, gui...; 'all' removes the assignment)\n"
        "  --replay FILE     validate a recording and print its actions, one per line\n"
        "  --record FILE     record raw events to FILE from --device: spacenav,\n"
        "                    controllers, or network:SOCKET, for --duration seconds\n"
        "                    (default 10)\n"
        "  --no-probe        do not look for a 3-D mouse or controllers\n"
        "  -h, --help        show this help\n"
        "\n"
        "Examples:\n"
        "  volvis devices\n"
        "  volvis devices --assign spaceball navigator\n"
        "  volvis devices --replay drag.vvin\n");
}

static void
config_path(const cli_args *a, char *buf, size_t n) {
    const char *c = cli_get(a, "config");
    const char *xdg = getenv("XDG_CONFIG_HOME");
    const char *home = getenv("HOME");
    if (c)
        snprintf(buf, n, "%s", c);
    else if (xdg && *xdg)
        snprintf(buf, n, "%s/volvis/input.json", xdg);
    else
        snprintf(buf, n, "%s/.config/volvis/input.json", home ? home : ".");
}

/* The assignments: {"assignments": {"spaceball": "navigator", ...}}; NULL when absent. */
static json_t *
load_config(const char *path, int *bad) {
    *bad = 0;
    struct stat sb;
    if (stat(path, &sb) != 0)
        return json_object();
    json_error_t e;
    json_t *root = json_load_file(path, 0, &e);
    if (!root || !json_is_object(json_object_get(root, "assignments"))) {
        cli_error("%s: line %d: %s", path, root ? 1 : e.line,
                  root ? "needs an \"assignments\" object" : e.text);
        json_decref(root);
        *bad = 1;
        return NULL;
    }
    return root;
}

static int
mkdir_parent(const char *path) {
    char dir[1024];
    snprintf(dir, sizeof dir, "%s", path);
    for (char *p = dir + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(dir, 0755) != 0 && errno != EEXIST)
                return -1;
            *p = '/';
        }
    return 0;
}

static int
do_assign(const cli_args *a, const char *dev, const char *app) {
    vv_input_kind k;
    if (vv_input_kind_parse(dev, &k) != VV_OK)
        return cli_usage_error(a, "%s", vv_error_message());
    char path[1024];
    config_path(a, path, sizeof path);
    int bad;
    json_t *root = load_config(path, &bad);
    if (!root)
        return CLI_EXIT_FAIL;
    json_t *as = json_object_get(root, "assignments");
    if (!as) {
        as = json_object();
        json_object_set_new(root, "assignments", as);
    }
    if (strcmp(app, "all") == 0)
        json_object_del(as, dev);
    else
        json_object_set_new(as, dev, json_string(app));
    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    if (mkdir_parent(path) != 0 || json_dump_file(root, tmp, JSON_INDENT(2)) != 0 ||
        rename(tmp, path) != 0) {
        remove(tmp);
        json_decref(root);
        cli_error("%s: cannot write: %s", path, strerror(errno));
        return CLI_EXIT_FAIL;
    }
    json_decref(root);
    printf("%s -> %s (%s)\n", dev, app, path);
    return CLI_EXIT_OK;
}

static vv_status
load_db(const cli_args *a, vv_input_devinfo_db **db) {
    const char *dir = cli_get(a, "device-dir");
    return vv_input_devinfo_db_load(db, dir ? &dir : NULL, dir ? 1 : 0);
}

static void
print_action(const vv_input_action *x) {
    printf("%.6f %-9s dev=%d", x->time, vv_input_action_kind_name(x->kind), x->device);
    switch (x->kind) {
    case VV_ACTION_MOTION:
        printf(" t=(%.4g %.4g %.4g) r=(%.4g %.4g %.4g) dt=%.4g", x->motion[0], x->motion[1],
               x->motion[2], x->motion[3], x->motion[4], x->motion[5], x->dt);
        break;
    case VV_ACTION_BUTTON_PRESS:
    case VV_ACTION_BUTTON_RELEASE:
    case VV_ACTION_BUTTON_CLICK:
        printf(" button=%d", x->button);
        break;
    case VV_ACTION_COMMAND:
        printf(" command=%s", x->command);
        break;
    case VV_ACTION_POSE:
    case VV_ACTION_SNAP_DRAG:
        printf(" position=(%.6g %.6g %.6g)", x->position.x, x->position.y, x->position.z);
        if (x->kind == VV_ACTION_SNAP_DRAG)
            printf(" snap=%d", x->snap);
        break;
    case VV_ACTION_TWO_HAND:
        printf(" translation=(%.6g %.6g %.6g) rotation=(%.6g %.6g %.6g %.6g) scale=%.6g",
               x->translation.x, x->translation.y, x->translation.z, x->rotation.w, x->rotation.x,
               x->rotation.y, x->rotation.z, x->scale);
        break;
    default:
        break;
    }
    putchar('\n');
}

static void
on_print(void *user, const vv_input_action *x) {
    (void)user;
    print_action(x);
}

static int
do_replay(const char *path, vv_input_devinfo_db *db) {
    vv_input_manager *m;
    vv_status s = vv_input_manager_new(&m, db);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    vv_input_manager_subscribe(m, NULL, on_print, NULL, NULL);
    s = vv_input_manager_open_replay(m, path, 0, INFINITY, NULL, NULL);
    if (s != VV_OK) {
        vv_input_manager_free(m);
        return cli_fail(s, path);
    }
    vv_input_manager_dispatch(m, 0);
    if (vv_input_manager_warning_count(m))
        fprintf(stderr, "volvis: %s: %llu event(s) dropped or clamped; last: %s\n", path,
                (unsigned long long)vv_input_manager_warning_count(m),
                vv_input_manager_last_warning(m));
    vv_input_manager_free(m);
    return CLI_EXIT_OK;
}

static int
do_record(const cli_args *a, const char *path, vv_input_devinfo_db *db) {
    const char *src = cli_get(a, "device");
    double dur = 10;
    if (!src)
        return cli_usage_error(a,
                               "--record needs --device (spacenav, controllers, network:SOCKET)");
    if (cli_get(a, "duration") &&
        cli_parse_double(a, "duration", cli_get(a, "duration"), 0.001, 86400, &dur) != 0)
        return CLI_EXIT_USAGE;
    vv_input_manager *m;
    vv_status s = vv_input_manager_new(&m, db);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    if (strcmp(src, "spacenav") == 0)
        s = vv_input_manager_open_spacenav(m, NULL);
    else if (strcmp(src, "controllers") == 0)
        s = vv_input_manager_open_controllers(m);
    else if (strncmp(src, "network:", 8) == 0)
        s = vv_input_manager_listen(m, src + 8);
    else {
        vv_input_manager_free(m);
        return cli_usage_error(a, "unknown --device '%s' (spacenav, controllers, network:SOCKET)",
                               src);
    }
    if (s == VV_OK)
        s = vv_input_manager_record_start(m, path);
    if (s != VV_OK) {
        vv_input_manager_free(m);
        return cli_fail(s, NULL);
    }
    cli_progress pr;
    cli_progress_begin(&pr, 1); /* Ctrl-C stops the recording early, keeping it */
    double end = vv_input_now() + dur;
    struct pollfd p = {vv_input_manager_fd(m), POLLIN, 0};
    for (double now = vv_input_now(); now < end && !cli_interrupted(); now = vv_input_now()) {
        double to = vv_input_manager_timeout(m, now);
        double left = end - now;
        if (to < 0 || to > left)
            to = left;
        poll(&p, 1, (int)ceil(to * 1000));
        vv_input_manager_dispatch(m, vv_input_now());
    }
    cli_progress_end(&pr);
    s = vv_input_manager_record_stop(m);
    vv_input_manager_free(m);
    if (s != VV_OK)
        return cli_fail(s, path);
    printf("wrote %s\n", path);
    return CLI_EXIT_OK;
}

static int
do_list(const cli_args *a, vv_input_devinfo_db *db) {
    char cpath[1024];
    config_path(a, cpath, sizeof cpath);
    int bad;
    json_t *cfg = load_config(cpath, &bad);
    if (!cfg)
        return CLI_EXIT_FAIL;
    vv_input_manager *m;
    vv_status s = vv_input_manager_new(&m, db);
    if (s != VV_OK) {
        json_decref(cfg);
        return cli_fail(s, NULL);
    }
    const char *spnav = "not probed", *sdl = "not probed";
    if (!cli_count(a, "no-probe")) {
        spnav = vv_input_manager_open_spacenav(m, NULL) == VV_OK ? "connected" : vv_error_message();
        char spbuf[256];
        snprintf(spbuf, sizeof spbuf, "%s", spnav);
        if (vv_input_manager_open_controllers(m) == VV_OK) {
            sdl = "SDL2 game-controller API";
            vv_input_manager_dispatch(m, vv_input_now()); /* controllers attached now */
        } else {
            sdl = vv_error_message();
        }
        printf("3-D mouse:   %s\ncontrollers: %s\n\n", spbuf, sdl);
    }
    json_t *as = json_object_get(cfg, "assignments");
    for (int i = 0; i < vv_input_manager_device_count(m); i++) {
        vv_input_device_desc d;
        vv_input_manager_device_get(m, i, &d);
        const char *app = json_string_value(json_object_get(as, vv_input_kind_name(d.kind)));
        const vv_input_devinfo *in = d.info;
        printf("device %d: %s (%s, driver %s)%s\n", d.id, d.name, vv_input_kind_name(d.kind),
               d.driver, d.present ? "" : " [removed]");
        printf("  assigned to: %s\n", app ? app : "all applications");
        printf("  information: %s%s%s\n", in->name, in->source[0] ? " from " : " (built-in)",
               in->source);
        printf("  degrees of freedom: %d (%s)", in->n_dof, in->coupled ? "coupled" : "independent");
        for (int k = 0; k < in->n_dof; k++)
            printf("%s %s [%g, %g] %s", k ? "," : ":", in->dof[k].name, in->dof[k].min,
                   in->dof[k].max, in->dof[k].unit);
        printf("\n  buttons: %d\n  good for: %s\n", in->n_buttons, in->good_for);
        printf("  method: %s, dead zone %g, exponent %g%s\n", vv_input_method_name(in->method.kind),
               in->method.dead_zone, in->method.exponent,
               in->method.dominant_axis ? ", dominant axis" : "");
    }
    vv_input_manager_free(m);
    json_decref(cfg);
    return CLI_EXIT_OK;
}

int
cli_devices_main(int argc, char **argv) {
    cli_args a;
    int r = cli_parse(&a, "devices", dev_opts, N_DEV_OPTS, argc, argv);
    if (r == CLI_HELP) {
        cli_devices_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (r != 0)
        return r;
    if (cli_get(&a, "assign")) {
        if (a.n_pos != 1)
            return cli_usage_error(&a, "--assign DEVICE APP takes one application name");
        return do_assign(&a, cli_get(&a, "assign"), a.pos[0]);
    }
    if (a.n_pos != 0)
        return cli_usage_error(&a, "unexpected argument '%s'", a.pos[0]);
    vv_input_devinfo_db *db = NULL;
    vv_status s = load_db(&a, &db);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    if (cli_get(&a, "replay"))
        r = do_replay(cli_get(&a, "replay"), db);
    else if (cli_get(&a, "record"))
        r = do_record(&a, cli_get(&a, "record"), db);
    else
        r = do_list(&a, db);
    vv_input_devinfo_db_free(db);
    return r;
}
