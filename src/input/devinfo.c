/*
 * The device information base (VolVis sec. 6): one JSON file per device
 * kind (share/devices/<kind>.json), read with Jansson over built-in
 * defaults, so that a missing file still leaves a usable entry.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <jansson.h>
#include <link.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "input_internal.h"

static void
set_dof(vv_input_devinfo *e, int i, const char *name, double lo, double hi, const char *unit) {
    snprintf(e->dof[i].name, sizeof e->dof[i].name, "%s", name);
    e->dof[i].min = lo;
    e->dof[i].max = hi;
    snprintf(e->dof[i].unit, sizeof e->dof[i].unit, "%s", unit);
}

static void
add_binding(vv_input_devinfo *e, int kind, int code, const char *cmd) {
    if (e->n_bindings >= VV_INPUT_MAX_BINDINGS)
        return;
    vv_input_binding *b = &e->bindings[e->n_bindings++];
    b->kind = kind;
    b->code = code;
    snprintf(b->command, sizeof b->command, "%s", cmd);
}

/* Built-in defaults: what the shipped JSON files say, in case none is found. */
static void
builtin(vv_input_devinfo *e, vv_input_kind k) {
    static const char *const six[6] = {"tx", "ty", "tz", "rx", "ry", "rz"};
    memset(e, 0, sizeof *e);
    e->kind = k;
    e->method = vv_input_method_default();
    e->click_time = 0.3;
    e->pixels_per_unit = 200;
    switch (k) {
    case VV_INPUT_KEYBOARD:
        snprintf(e->name, sizeof e->name, "Keyboard");
        snprintf(e->good_for, sizeof e->good_for, "commands,discrete navigation");
        add_binding(e, VV_RAW_KEY, 0xff51, "axis:-tx");    /* Left */
        add_binding(e, VV_RAW_KEY, 0xff53, "axis:+tx");    /* Right */
        add_binding(e, VV_RAW_KEY, 0xff52, "axis:+ty");    /* Up */
        add_binding(e, VV_RAW_KEY, 0xff54, "axis:-ty");    /* Down */
        add_binding(e, VV_RAW_KEY, 0xff55, "axis:-tz");    /* Page Up */
        add_binding(e, VV_RAW_KEY, 0xff56, "axis:+tz");    /* Page Down */
        add_binding(e, VV_RAW_KEY, 0xff50, "view.reset");  /* Home */
        add_binding(e, VV_RAW_KEY, 0xff09, "select.next"); /* Tab */
        break;
    case VV_INPUT_MOUSE:
        snprintf(e->name, sizeof e->name, "Mouse");
        e->n_dof = 2;
        set_dof(e, 0, "pointer-x", 0, 32768, "px");
        set_dof(e, 1, "pointer-y", 0, 32768, "px");
        e->n_buttons = 3;
        snprintf(e->good_for, sizeof e->good_for, "picking,2-D dragging,trackball rotation");
        break;
    case VV_INPUT_SPACEBALL:
        snprintf(e->name, sizeof e->name, "3-D mouse (spacenavd)");
        e->n_dof = 6;
        for (int i = 0; i < 6; i++)
            set_dof(e, i, six[i], -350, 350, "counts");
        e->coupled = 1;
        e->n_buttons = 2;
        e->method.dead_zone = 0.05;
        e->method.exponent = 2;
        e->method.dominant_axis = 1;
        snprintf(e->good_for, sizeof e->good_for, "6-DOF navigation,object rotation,flight paths");
        add_binding(e, VV_RAW_BUTTON, 0, "view.reset");
        add_binding(e, VV_RAW_BUTTON, 1, "select.next");
        break;
    case VV_INPUT_GAMECONTROLLER:
        snprintf(e->name, sizeof e->name, "Game controller (SDL2)");
        e->n_dof = 6;
        for (int i = 0; i < 6; i++)
            set_dof(e, i, six[i], -1, 1, "normalized");
        e->n_buttons = 21;
        e->method.dead_zone = 0.1;
        e->method.exponent = 2;
        snprintf(e->good_for, sizeof e->good_for, "navigation,fly-through");
        add_binding(e, VV_RAW_BUTTON, 0, "select.next");     /* A */
        add_binding(e, VV_RAW_BUTTON, 1, "select.previous"); /* B */
        add_binding(e, VV_RAW_BUTTON, 4, "view.reset");      /* Back */
        break;
    case VV_INPUT_DATAGLOVE:
        snprintf(e->name, sizeof e->name, "DataGlove (replay / network only)");
        e->n_dof = 6;
        for (int i = 0; i < 3; i++)
            set_dof(e, i, six[i], -1000, 1000, "mm");
        for (int i = 3; i < 6; i++)
            set_dof(e, i, six[i], -VV_PI, VV_PI, "rad");
        e->n_buttons = 1;
        snprintf(e->good_for, sizeof e->good_for, "grabbing,two-hand gestures,pointing");
        break;
    case VV_INPUT_NETWORK:
    default:
        snprintf(e->name, sizeof e->name, "Network device");
        e->n_dof = 6;
        for (int i = 0; i < 6; i++)
            set_dof(e, i, six[i], -1, 1, "normalized");
        snprintf(e->good_for, sizeof e->good_for, "remote navigation,scripts");
        break;
    }
}

static vv_status
fmt_err(const char *path, const char *what) {
    return vv_error_set(VV_ERR_FORMAT, "devices: %s: %s", path, what);
}

static int
get_number(json_t *o, const char *key, double *out) {
    json_t *v = json_object_get(o, key);
    if (!v)
        return 0;
    if (!json_is_number(v) && !json_is_boolean(v))
        return -1;
    *out = json_is_boolean(v) ? (json_is_true(v) ? 1 : 0) : json_number_value(v);
    return isfinite(*out) ? 1 : -1;
}

static vv_status
parse_binding_key(const char *key, int *kind, int *code) {
    const char *colon = strchr(key, ':');
    if (!colon)
        return VV_ERR_FORMAT;
    size_t n = (size_t)(colon - key);
    if (n == 3 && strncmp(key, "key", 3) == 0)
        *kind = VV_RAW_KEY;
    else if (n == 6 && strncmp(key, "button", 6) == 0)
        *kind = VV_RAW_BUTTON;
    else
        return VV_ERR_FORMAT;
    char *end;
    long v = strtol(colon + 1, &end, 0);
    if (end == colon + 1 || *end || v < 0 || v > 0x7fffffff)
        return VV_ERR_FORMAT;
    *code = (int)v;
    return VV_OK;
}

vv_status
vv_input_devinfo_load(const char *path, vv_input_devinfo *out) {
    json_error_t jerr;
    json_t *root = json_load_file(path, JSON_REJECT_DUPLICATES, &jerr);
    if (!root) {
        vv_status s = jerr.line < 0 ? VV_ERR_IO : VV_ERR_FORMAT;
        return vv_error_set(s, "devices: %s: line %d, column %d: %s", path, jerr.line, jerr.column,
                            jerr.text);
    }
    vv_status st = VV_OK;
    char msg[256];
    vv_input_kind kind;
    const char *ks = json_string_value(json_object_get(root, "kind"));
    if (!json_is_object(root)) {
        st = fmt_err(path, "not a JSON object");
        goto done;
    }
    if (!ks || vv_input_kind_parse(ks, &kind) != VV_OK) {
        st = fmt_err(path, "\"kind\" missing or not a known device kind");
        goto done;
    }
    builtin(out, kind);
    const char *name = json_string_value(json_object_get(root, "name"));
    if (name)
        snprintf(out->name, sizeof out->name, "%s", name);
    json_t *dofs = json_object_get(root, "degrees_of_freedom");
    if (dofs) {
        if (!json_is_array(dofs) || json_array_size(dofs) > VV_INPUT_MAX_DOF) {
            st = fmt_err(path, "\"degrees_of_freedom\" must be an array of at most 8 objects");
            goto done;
        }
        out->n_dof = (int)json_array_size(dofs);
        for (int i = 0; i < out->n_dof; i++) {
            json_t *d = json_array_get(dofs, (size_t)i);
            const char *dn = json_string_value(json_object_get(d, "name"));
            const char *du = json_string_value(json_object_get(d, "unit"));
            double lo, hi;
            if (!dn || get_number(d, "min", &lo) != 1 || get_number(d, "max", &hi) != 1 ||
                !(lo < hi)) {
                snprintf(msg, sizeof msg,
                         "degree of freedom %d: needs \"name\", \"min\" < \"max\" (numbers)", i);
                st = fmt_err(path, msg);
                goto done;
            }
            set_dof(out, i, dn, lo, hi, du ? du : "");
        }
    }
    double v;
    if (get_number(root, "coupled", &v) == 1)
        out->coupled = v != 0;
    if (get_number(root, "buttons", &v) == 1 && v >= 0 && v <= 64)
        out->n_buttons = (int)v;
    if (get_number(root, "click_time", &v) == 1 && v > 0)
        out->click_time = v;
    if (get_number(root, "pixels_per_unit", &v) == 1 && v > 0)
        out->pixels_per_unit = v;
    json_t *gf = json_object_get(root, "good_for");
    if (json_is_array(gf)) {
        out->good_for[0] = '\0';
        size_t i;
        json_t *g;
        json_array_foreach(gf, i, g) {
            const char *gs = json_string_value(g);
            if (!gs)
                continue;
            size_t len = strlen(out->good_for);
            snprintf(out->good_for + len, sizeof out->good_for - len, "%s%s", len ? "," : "", gs);
        }
    }
    json_t *meth = json_object_get(root, "method");
    if (meth) {
        const char *mn = json_string_value(json_object_get(meth, "name"));
        if (!json_is_object(meth) || !mn) {
            st = fmt_err(path, "\"method\" must be an object with a \"name\"");
            goto done;
        }
        if (strcmp(mn, "direct") == 0)
            out->method.kind = VV_METHOD_DIRECT;
        else if (strcmp(mn, "snap-drag") == 0)
            out->method.kind = VV_METHOD_SNAP_DRAG;
        else if (strcmp(mn, "two-hand") == 0)
            out->method.kind = VV_METHOD_TWO_HAND;
        else {
            st = fmt_err(path, "\"method\": unknown name (direct, snap-drag, two-hand)");
            goto done;
        }
        if (get_number(meth, "dead_zone", &v) == 1) {
            if (!(v >= 0 && v < 1)) {
                st = fmt_err(path, "\"method\": dead_zone must be in [0, 1)");
                goto done;
            }
            out->method.dead_zone = v;
        }
        if (get_number(meth, "exponent", &v) == 1) {
            if (!(v >= 1 && v <= 10)) {
                st = fmt_err(path, "\"method\": exponent must be in [1, 10]");
                goto done;
            }
            out->method.exponent = v;
        }
        if (get_number(meth, "dominant_axis", &v) == 1)
            out->method.dominant_axis = v != 0;
        if (get_number(meth, "gain", &v) == 1 && v > 0)
            out->method.gain = v;
        if (get_number(meth, "snap_axes", &v) == 1)
            out->method.snap_axes = v != 0;
        if (get_number(meth, "snap_angle_degrees", &v) == 1 && v >= 0 && v <= 90)
            out->method.snap_angle = v * VV_PI / 180;
        if (get_number(meth, "grid", &v) == 1 && v >= 0)
            out->method.grid = v;
        if (get_number(meth, "feature_radius", &v) == 1 && v >= 0)
            out->method.feature_radius = v;
    }
    json_t *binds = json_object_get(root, "bindings");
    if (binds) {
        if (!json_is_object(binds)) {
            st = fmt_err(path, "\"bindings\" must be an object");
            goto done;
        }
        out->n_bindings = 0;
        const char *key;
        json_t *val;
        json_object_foreach(binds, key, val) {
            int bk, bc;
            const char *cmd = json_string_value(val);
            if (!cmd || parse_binding_key(key, &bk, &bc) != VV_OK ||
                strlen(cmd) >= sizeof out->bindings[0].command) {
                snprintf(msg, sizeof msg,
                         "binding \"%.64s\": keys are \"key:CODE\" or \"button:N\", values command "
                         "names of at most 47 characters",
                         key);
                st = fmt_err(path, msg);
                goto done;
            }
            if (out->n_bindings >= VV_INPUT_MAX_BINDINGS) {
                st = fmt_err(path, "more than 24 bindings");
                goto done;
            }
            add_binding(out, bk, bc, cmd);
        }
    }
    snprintf(out->source, sizeof out->source, "%s", path);
done:
    json_decref(root);
    return st;
}

static int
is_dir(const char *p) {
    struct stat sb;
    return p && stat(p, &sb) == 0 && S_ISDIR(sb.st_mode);
}

static vv_status
load_dir(vv_input_devinfo_db *db, const char *dir) {
    if (!is_dir(dir))
        return VV_OK;
    for (int k = 0; k < VV_INPUT_KIND_COUNT; k++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s.json", dir, vv_input_kind_name((vv_input_kind)k));
        struct stat sb;
        if (stat(path, &sb) != 0)
            continue;
        vv_input_devinfo e;
        vv_status s = vv_input_devinfo_load(path, &e);
        if (s != VV_OK)
            return s;
        if (e.kind != (vv_input_kind)k)
            return vv_error_set(VV_ERR_FORMAT, "devices: %s: \"kind\" is \"%s\", not \"%s\"", path,
                                vv_input_kind_name(e.kind), vv_input_kind_name((vv_input_kind)k));
        db->e[k] = e;
    }
    return VV_OK;
}

/* An object of the library's own code's file: dladdr names the file it was
 * loaded from (libvolvis.so, or the program the library is linked into). */
static const char devinfo_anchor = 0;

/* The file this code was loaded from: a shared object's path, or for the
 * main program (whose link map has the name "", and whose dladdr name is
 * argv[0], not a path when found through PATH) the program itself. */
static const char *
self_file(Dl_info *di) {
    struct link_map *map = NULL;
    if (!dladdr1(&devinfo_anchor, di, (void **)&map, RTLD_DL_LINKMAP))
        return NULL;
    if (!map || !map->l_name || !map->l_name[0])
        return "/proc/self/exe";
    return di->dli_fname;
}

/* share/volvis/devices beside the library's prefix: <dir of the object this
 * code was loaded from>/../share/volvis/devices, so that a relocated install
 * (the pip wheel) finds its own files. 1 when it fits @p buf. */
static int
relative_datadir(char *buf, size_t cap) {
    Dl_info di;
    const char *f;
    char *obj = NULL;
    if (!(f = self_file(&di)) || !(obj = realpath(f, NULL)))
        return 0;
    char *slash = strrchr(obj, '/');
    int ok = 0;
    if (slash) {
        *slash = '\0';
        ok = (size_t)snprintf(buf, cap, "%s/../share/volvis/devices", obj) < cap;
    }
    free(obj);
    return ok;
}

vv_status
vv_input_devinfo_db_load(vv_input_devinfo_db **out, const char *const *dirs, int n_dirs) {
    *out = NULL;
    vv_input_devinfo_db *db = calloc(1, sizeof *db);
    if (!db)
        return vv_error_set(VV_ERR_NOMEM, "devices: out of memory");
    for (int k = 0; k < VV_INPUT_KIND_COUNT; k++)
        builtin(&db->e[k], (vv_input_kind)k);
    vv_status s = VV_OK;
    if (n_dirs > 0) {
        for (int i = 0; i < n_dirs && s == VV_OK; i++)
            if (dirs[i])
                s = load_dir(db, dirs[i]);
    } else {
#ifdef VV_DEVICE_DATADIR
        /* the configured install folder (absent from relocatable builds) */
        s = load_dir(db, VV_DEVICE_DATADIR);
#endif
        /* then the one relative to the library, where it was moved to */
        char rel[4096];
        if (s == VV_OK && relative_datadir(rel, sizeof rel))
            s = load_dir(db, rel);
        const char *home = getenv("HOME");
        if (s == VV_OK && home) {
            char p[1024];
            snprintf(p, sizeof p, "%s/.config/volvis/devices", home);
            s = load_dir(db, p);
        }
        if (s == VV_OK)
            s = load_dir(db, getenv("VOLVIS_DEVICE_DIR"));
    }
    if (s != VV_OK) {
        free(db);
        return s;
    }
    *out = db;
    return VV_OK;
}

void
vv_input_devinfo_db_free(vv_input_devinfo_db *db) {
    free(db);
}

const vv_input_devinfo *
vv_input_devinfo_db_get(const vv_input_devinfo_db *db, vv_input_kind kind) {
    if (!db || (unsigned)kind >= VV_INPUT_KIND_COUNT)
        return NULL;
    return &db->e[kind];
}
