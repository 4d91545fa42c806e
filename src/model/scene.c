/*
 * Scene files: the World as JSON (schema in docs/scene-format.md), read with
 * Jansson. Scene loading is the one place where the model calls io
 * (vv_volume_load): a scene file names its volume files.
 *
 * Error positions: Jansson reports line:column for syntax errors but keeps
 * no positions for values, so a schema error is located by a second, lazy
 * pass over the raw text (scan_locate) that walks to the offending path
 * ("objects[0].transfer_function") and reports where its key (or, for an
 * array element, its value) starts. This pass runs only when there is an
 * error to report.
 */
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "filter/filter_scene.h"
#include "model/model_internal.h"
#include "modeling/modeling_internal.h"
#include "volvis/io.h"
#include "volvis/model.h"
#include "volvis/modeling.h"

#define SCENE_MAX_BYTES (16u << 20)
#define PATH_MAX_LEN 256
#define IMAGE_MAX_SIDE 32768

typedef struct sctx {
    const char *path; /* scene file as given */
    const char *text;
    size_t len;
    const vv_progress *progress; /* voxelization of geometry objects; may be NULL */
} sctx;

/* ---- locating a path in the raw text ---------------------------------- */

typedef struct scan {
    const char *s;
    size_t n, i;
    int line, col;
    const char *target;
    int found, fline, fcol;
} scan;

static int
sc_peek(const scan *sc) {
    return sc->i < sc->n ? (unsigned char)sc->s[sc->i] : -1;
}

static void
sc_adv(scan *sc) {
    if (sc->i >= sc->n)
        return;
    unsigned char ch = (unsigned char)sc->s[sc->i++];
    if (ch == '\n') {
        sc->line++;
        sc->col = 1;
    } else if ((ch & 0xC0) != 0x80) {
        /* columns count characters: UTF-8 continuation bytes add nothing */
        sc->col++;
    }
}

static void
sc_ws(scan *sc) {
    for (;;) {
        int ch = sc_peek(sc);
        if (ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r')
            sc_adv(sc);
        else
            return;
    }
}

/* Consumes a string at the cursor, copying its (roughly decoded) text. */
static void
sc_string(scan *sc, char *buf, size_t cap) {
    size_t k = 0;
    sc_adv(sc); /* opening quote */
    while (sc->i < sc->n) {
        int ch = sc_peek(sc);
        if (ch == '"') {
            sc_adv(sc);
            break;
        }
        if (ch == '\\') {
            sc_adv(sc);
            ch = sc_peek(sc);
            if (ch < 0)
                break;
        }
        if (buf && k + 1 < cap)
            buf[k++] = (char)ch;
        sc_adv(sc);
    }
    if (buf && cap)
        buf[k] = '\0';
}

/* Skips one value without recursion. */
static void
sc_skip(scan *sc) {
    int depth = 0;
    do {
        sc_ws(sc);
        int ch = sc_peek(sc);
        if (ch < 0)
            return;
        if (ch == '"') {
            sc_string(sc, NULL, 0);
        } else if (ch == '{' || ch == '[') {
            depth++;
            sc_adv(sc);
        } else if (ch == '}' || ch == ']') {
            depth--;
            sc_adv(sc);
        } else if (ch == ',' || ch == ':') {
            sc_adv(sc);
        } else {
            while (sc->i < sc->n) {
                ch = sc_peek(sc);
                if (ch == ',' || ch == ']' || ch == '}' || ch == ' ' || ch == '\n' || ch == '\t' ||
                    ch == '\r')
                    break;
                sc_adv(sc);
            }
        }
    } while (depth > 0 && sc->i < sc->n);
}

static int
path_is_prefix(const char *path, const char *target) {
    size_t l = strlen(path);
    if (l == 0)
        return 1;
    return strncmp(path, target, l) == 0 && (target[l] == '.' || target[l] == '[');
}

static void
sc_found(scan *sc) {
    sc->found = 1;
    sc->fline = sc->line;
    sc->fcol = sc->col;
}

/* Walks the value at the cursor whose path is @p path, descending only
 * towards the target; the recursion depth is the target's depth. */
static void
sc_value(scan *sc, const char *path) {
    sc_ws(sc);
    if (strcmp(path, sc->target) == 0) {
        sc_found(sc);
        return;
    }
    int ch = sc_peek(sc);
    if (!path_is_prefix(path, sc->target) || (ch != '{' && ch != '[')) {
        sc_skip(sc);
        return;
    }
    char child[2 * PATH_MAX_LEN + 32];
    if (ch == '{') {
        sc_adv(sc);
        for (;;) {
            sc_ws(sc);
            ch = sc_peek(sc);
            if (ch != '"') {
                if (ch == '}')
                    sc_adv(sc);
                return;
            }
            int kl = sc->line, kc = sc->col;
            char key[PATH_MAX_LEN];
            sc_string(sc, key, sizeof key);
            if (path[0])
                snprintf(child, sizeof child, "%s.%s", path, key);
            else
                snprintf(child, sizeof child, "%s", key);
            sc_ws(sc);
            if (sc_peek(sc) == ':')
                sc_adv(sc);
            if (strcmp(child, sc->target) == 0) {
                sc->found = 1;
                sc->fline = kl;
                sc->fcol = kc;
                return;
            }
            sc_value(sc, child);
            if (sc->found)
                return;
            sc_ws(sc);
            if (sc_peek(sc) == ',')
                sc_adv(sc);
            else {
                if (sc_peek(sc) == '}')
                    sc_adv(sc);
                return;
            }
        }
    } else {
        sc_adv(sc);
        for (int idx = 0;; idx++) {
            sc_ws(sc);
            ch = sc_peek(sc);
            if (ch < 0 || ch == ']') {
                sc_adv(sc);
                return;
            }
            snprintf(child, sizeof child, "%s[%d]", path, idx);
            sc_value(sc, child);
            if (sc->found)
                return;
            sc_ws(sc);
            if (sc_peek(sc) == ',')
                sc_adv(sc);
            else {
                if (sc_peek(sc) == ']')
                    sc_adv(sc);
                return;
            }
        }
    }
}

/* Strips the last ".key" or "[i]" of a path in place; 0 when nothing is left. */
static int
path_parent(char *p) {
    size_t l = strlen(p);
    if (l == 0)
        return 0;
    while (l > 0 && p[l - 1] != '.' && p[l - 1] != '[')
        l--;
    if (l == 0) {
        p[0] = '\0';
        return 1;
    }
    p[l - 1] = '\0';
    return 1;
}

/* Line and column of @p path in the scene text (its nearest ancestor's when
 * the path itself cannot be found). */
static void
scene_locate(const sctx *c, const char *path, int *line, int *col) {
    char p[PATH_MAX_LEN];
    snprintf(p, sizeof p, "%s", path ? path : "");
    for (;;) {
        scan sc = {c->text, c->len, 0, 1, 1, p, 0, 1, 1};
        sc_value(&sc, "");
        if (sc.found) {
            *line = sc.fline;
            *col = sc.fcol;
            return;
        }
        if (!path_parent(p))
            break;
    }
    *line = 1;
    *col = 1;
}

void
vv_model_json_locate(const char *text, size_t len, const char *path, int *line, int *col) {
    sctx c = {NULL, text, len, NULL};
    scene_locate(&c, path, line, col);
}

/* ---- error reporting ---------------------------------------------------- */

static vv_status serr(const sctx *c, const char *path, const char *fmt, ...) VV_PRINTF(3, 4);

static vv_status
serr(const sctx *c, const char *path, const char *fmt, ...) {
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    int line, col;
    scene_locate(c, path, &line, &col);
    if (path && path[0])
        return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s: %s", c->path, line, col, path, msg);
    return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s", c->path, line, col, msg);
}

const char *
vv_model_json_kind(const json_t *v) {
    switch (json_typeof(v)) {
    case JSON_OBJECT:
        return "an object";
    case JSON_ARRAY:
        return "an array";
    case JSON_STRING:
        return "a string";
    case JSON_INTEGER:
    case JSON_REAL:
        return "a number";
    case JSON_TRUE:
    case JSON_FALSE:
        return "a boolean";
    case JSON_NULL:
        break;
    }
    return "null";
}

/* dst = a + sep + b, truncated to PATH_MAX_LEN - 1 bytes (a truncated path
 * only makes an error position less precise). */
static void
path_cat(char *dst, const char *a, const char *sep, const char *b) {
    size_t k = 0;
    const char *parts[3] = {a, sep, b};
    for (int p = 0; p < 3; p++)
        for (const char *q = parts[p]; q && *q && k + 1 < PATH_MAX_LEN; q++)
            dst[k++] = *q;
    dst[k] = '\0';
}

static void
path_key(char *dst, const char *parent, const char *key) {
    if (parent && parent[0])
        path_cat(dst, parent, ".", key);
    else
        path_cat(dst, "", "", key);
}

static void
path_index(char *dst, const char *parent, size_t i) {
    char idx[32];
    snprintf(idx, sizeof idx, "[%zu]", i);
    path_cat(dst, parent, "", idx);
}

/* Optimal string alignment distance (edits incl. transpositions), capped. */
static int
edit_distance(const char *a, const char *b) {
    size_t la = strlen(a), lb = strlen(b);
    if (la > 40 || lb > 40)
        return 99;
    int d[41][41];
    for (size_t i = 0; i <= la; i++)
        d[i][0] = (int)i;
    for (size_t j = 0; j <= lb; j++)
        d[0][j] = (int)j;
    for (size_t i = 1; i <= la; i++) {
        for (size_t j = 1; j <= lb; j++) {
            int cost = a[i - 1] == b[j - 1] ? 0 : 1;
            int best = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < best)
                best = d[i][j - 1] + 1;
            if (d[i - 1][j - 1] + cost < best)
                best = d[i - 1][j - 1] + cost;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                d[i - 2][j - 2] + 1 < best)
                best = d[i - 2][j - 2] + 1;
            d[i][j] = best;
        }
    }
    return d[la][lb];
}

/* Every key of @p obj must be in the NULL-terminated @p allowed list. */
static vv_status
check_keys(const sctx *c, json_t *obj, const char *path, const char *const *allowed) {
    const char *key;
    json_t *val;
    json_object_foreach(obj, key, val) {
        int ok = 0;
        for (int i = 0; allowed[i]; i++)
            if (strcmp(key, allowed[i]) == 0)
                ok = 1;
        if (ok)
            continue;
        char kp[PATH_MAX_LEN];
        path_key(kp, path, key);
        const char *best = NULL;
        int bd = 99;
        for (int i = 0; allowed[i]; i++) {
            int d = edit_distance(key, allowed[i]);
            if (d < bd) {
                bd = d;
                best = allowed[i];
            }
        }
        size_t kl = strlen(key);
        int limit = kl <= 4 ? 1 : (kl <= 8 ? 2 : 3);
        if (best && bd <= limit)
            return serr(c, kp, "unknown key (did you mean %s?)", best);
        char list[512];
        size_t off = 0;
        list[0] = '\0';
        for (int i = 0; allowed[i] && off < sizeof list; i++)
            off +=
                (size_t)snprintf(list + off, sizeof list - off, "%s%s", i ? ", " : "", allowed[i]);
        return serr(c, kp, "unknown key; expected one of: %s", list);
    }
    return VV_OK;
}

/* ---- typed fields -------------------------------------------------------- */

static vv_status
value_number(const sctx *c, json_t *v, const char *path, double *out) {
    if (!json_is_number(v))
        return serr(c, path, "expected a number, got %s", vv_model_json_kind(v));
    double d = json_number_value(v);
    if (!isfinite(d))
        return serr(c, path, "number is not finite");
    *out = d;
    return VV_OK;
}

static vv_status
value_vec3(const sctx *c, json_t *v, const char *path, vv_vec3 *out) {
    if (!json_is_array(v) || json_array_size(v) != 3)
        return serr(c, path, "expected an array of 3 numbers, got %s%s", vv_model_json_kind(v),
                    json_is_array(v) ? " of another length" : "");
    double d[3];
    for (size_t i = 0; i < 3; i++) {
        json_t *e = json_array_get(v, i);
        if (!json_is_number(e)) {
            char ep[PATH_MAX_LEN];
            path_index(ep, path, i);
            return serr(c, ep, "expected a number, got %s", vv_model_json_kind(e));
        }
        d[i] = json_number_value(e);
    }
    *out = vv_vec3_make(d[0], d[1], d[2]);
    return VV_OK;
}

static vv_status
value_color(const sctx *c, json_t *v, const char *path, vv_vec3 *out) {
    vv_status st = value_vec3(c, v, path, out);
    if (st != VV_OK)
        return st;
    double d[3] = {out->x, out->y, out->z};
    for (int i = 0; i < 3; i++)
        if (!(d[i] >= 0.0 && d[i] <= 1.0))
            return serr(c, path, "colour component %g is outside [0, 1]", d[i]);
    return VV_OK;
}

/* Field getters: *present (may be NULL) says whether the key was there; a
 * missing key leaves *out unchanged and is not an error. */
static json_t *
field(json_t *obj, const char *key, char *kp, const char *path, int *present) {
    json_t *v = json_object_get(obj, key);
    path_key(kp, path, key);
    if (present)
        *present = v != NULL;
    return v;
}

static vv_status
get_number(const sctx *c, json_t *obj, const char *path, const char *key, double *out,
           int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, present);
    return v ? value_number(c, v, kp, out) : VV_OK;
}

/* A number in a range; open ends when lo_open / hi_open. */
static vv_status
get_number_in(const sctx *c, json_t *obj, const char *path, const char *key, double *out,
              int *present, double lo, int lo_open, double hi, int hi_open) {
    char kp[PATH_MAX_LEN];
    int here;
    json_t *v = field(obj, key, kp, path, &here);
    if (present)
        *present = here;
    if (!v)
        return VV_OK;
    double d = 0.0;
    vv_status st = value_number(c, v, kp, &d);
    if (st != VV_OK)
        return st;
    int ok = (lo_open ? d > lo : d >= lo) && (hi_open ? d < hi : d <= hi);
    if (!ok) {
        char hs[64];
        if (isinf(hi))
            snprintf(hs, sizeof hs, "inf");
        else
            snprintf(hs, sizeof hs, "%g", hi);
        return serr(c, kp, "%g is outside %c%g, %s%c", d, lo_open ? '(' : '[', lo, hs,
                    hi_open ? ')' : ']');
    }
    *out = d;
    return VV_OK;
}

static vv_status
get_int_in(const sctx *c, json_t *obj, const char *path, const char *key, int *out, int lo,
           int hi) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, NULL);
    if (!v)
        return VV_OK;
    double d = 0.0;
    vv_status st = value_number(c, v, kp, &d);
    if (st != VV_OK)
        return st;
    if (d != floor(d))
        return serr(c, kp, "expected an integer, got %g", d);
    if (d < lo || d > hi)
        return serr(c, kp, "%g is outside %d..%d", d, lo, hi);
    *out = (int)d;
    return VV_OK;
}

static vv_status
get_vec3(const sctx *c, json_t *obj, const char *path, const char *key, vv_vec3 *out,
         int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, present);
    return v ? value_vec3(c, v, kp, out) : VV_OK;
}

static vv_status
get_nonzero_vec3(const sctx *c, json_t *obj, const char *path, const char *key, vv_vec3 *out,
                 int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, present);
    if (!v)
        return VV_OK;
    vv_status st = value_vec3(c, v, kp, out);
    if (st != VV_OK)
        return st;
    if (!(vv_vec3_length(*out) > 0.0))
        return serr(c, kp, "must not be the zero vector");
    return VV_OK;
}

static vv_status
get_color(const sctx *c, json_t *obj, const char *path, const char *key, vv_vec3 *out,
          int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, present);
    return v ? value_color(c, v, kp, out) : VV_OK;
}

static vv_status
get_bool(const sctx *c, json_t *obj, const char *path, const char *key, int *out) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, NULL);
    if (!v)
        return VV_OK;
    if (!json_is_boolean(v))
        return serr(c, kp, "expected true or false, got %s", vv_model_json_kind(v));
    *out = json_is_true(v) ? 1 : 0;
    return VV_OK;
}

static vv_status
get_string(const sctx *c, json_t *obj, const char *path, const char *key, const char **out) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, NULL);
    if (!v)
        return VV_OK;
    if (!json_is_string(v))
        return serr(c, kp, "expected a string, got %s", vv_model_json_kind(v));
    *out = json_string_value(v);
    return VV_OK;
}

/* An optional object or array (@p want, named @p what in the error); *out is
 * NULL when absent. */
static vv_status
get_container(const sctx *c, json_t *obj, const char *path, const char *key, json_type want,
              const char *what, json_t **out) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, NULL);
    *out = NULL;
    if (!v)
        return VV_OK;
    if (json_typeof(v) != want)
        return serr(c, kp, "expected %s, got %s", what, vv_model_json_kind(v));
    *out = v;
    return VV_OK;
}

static vv_status
get_object(const sctx *c, json_t *obj, const char *path, const char *key, json_t **out) {
    return get_container(c, obj, path, key, JSON_OBJECT, "an object", out);
}

static vv_status
get_array(const sctx *c, json_t *obj, const char *path, const char *key, json_t **out) {
    return get_container(c, obj, path, key, JSON_ARRAY, "an array", out);
}

static vv_status
missing(const sctx *c, const char *path, const char *key, const char *what) {
    return serr(c, path, "missing required key \"%s\" (%s)", key, what);
}

/* ---- sections ------------------------------------------------------------ */

static vv_status
parse_cut_planes(const sctx *c, json_t *arr, const char *path, vv_cut_plane *planes, int *n) {
    static const char *const keys[] = {"point", "normal", NULL};
    size_t i;
    json_t *e;
    *n = 0;
    json_array_foreach(arr, i, e) {
        char ep[PATH_MAX_LEN];
        path_index(ep, path, i);
        if (!json_is_object(e))
            return serr(c, ep, "expected an object {\"point\", \"normal\"}, got %s",
                        vv_model_json_kind(e));
        if (i >= VV_MAX_CUT_PLANES)
            return serr(c, ep, "more than %d cut planes", VV_MAX_CUT_PLANES);
        vv_status st = check_keys(c, e, ep, keys);
        if (st != VV_OK)
            return st;
        int hp, hn;
        vv_vec3 p = {0, 0, 0}, nrm = {0, 0, 0};
        if ((st = get_vec3(c, e, ep, "point", &p, &hp)) != VV_OK ||
            (st = get_nonzero_vec3(c, e, ep, "normal", &nrm, &hn)) != VV_OK)
            return st;
        if (!hp)
            return missing(c, ep, "point", "a point on the plane");
        if (!hn)
            return missing(c, ep, "normal", "the normal of the kept half-space");
        planes[i].point = p;
        planes[i].normal = vv_vec3_normalize(nrm);
        (*n)++;
    }
    return VV_OK;
}

static vv_status
parse_view(const sctx *c, json_t *v, vv_world *w, int *has_background) {
    static const char *const keys[] = {
        "eye",          "at",    "up",     "fov",        "projection",
        "ortho_height", "width", "height", "background", NULL};
    const char *path = "view";
    vv_status st = check_keys(c, v, path, keys);
    if (st != VV_OK)
        return st;
    vv_view *vw = &w->view;
    double fov = vv_rad_to_deg(vw->fov);
    const char *proj = NULL;
    if ((st = get_vec3(c, v, path, "eye", &vw->eye, NULL)) != VV_OK ||
        (st = get_vec3(c, v, path, "at", &vw->at, NULL)) != VV_OK ||
        (st = get_nonzero_vec3(c, v, path, "up", &vw->up, NULL)) != VV_OK ||
        (st = get_number_in(c, v, path, "fov", &fov, NULL, 0, 1, 180, 1)) != VV_OK ||
        (st = get_string(c, v, path, "projection", &proj)) != VV_OK ||
        (st = get_number_in(c, v, path, "ortho_height", &vw->ortho_height, NULL, 0, 1, INFINITY,
                            1)) != VV_OK ||
        (st = get_int_in(c, v, path, "width", &vw->width, 1, IMAGE_MAX_SIDE)) != VV_OK ||
        (st = get_int_in(c, v, path, "height", &vw->height, 1, IMAGE_MAX_SIDE)) != VV_OK ||
        (st = get_color(c, v, path, "background", &w->background, has_background)) != VV_OK)
        return st;
    vw->fov = vv_deg_to_rad(fov);
    if (proj) {
        if (strcmp(proj, "perspective") == 0)
            vw->projection = VV_PROJECTION_PERSPECTIVE;
        else if (strcmp(proj, "orthographic") == 0)
            vw->projection = VV_PROJECTION_ORTHOGRAPHIC;
        else
            return serr(c, "view.projection",
                        "unknown projection \"%s\"; expected perspective or orthographic", proj);
    }
    vv_vec3 dir = vv_vec3_sub(vw->at, vw->eye);
    if (!(vv_vec3_length(dir) > 0.0))
        return serr(c, "view.at", "the eye and the point looked at are the same");
    vv_vec3 cr = vv_vec3_cross(vv_vec3_normalize(dir), vv_vec3_normalize(vw->up));
    if (!(vv_vec3_length(cr) > 1e-9))
        return serr(c, "view.up", "up is parallel to the viewing direction");
    return VV_OK;
}

static vv_status
parse_lights(const sctx *c, json_t *arr, vv_world *w) {
    static const char *const keys[] = {"type", "direction", "position", "color", "intensity", NULL};
    size_t i;
    json_t *e;
    vv_vec3 view_dir = vv_vec3_normalize(vv_vec3_sub(w->view.at, w->view.eye));
    json_array_foreach(arr, i, e) {
        char ep[PATH_MAX_LEN];
        path_index(ep, "lights", i);
        if (!json_is_object(e))
            return serr(c, ep, "expected an object, got %s", vv_model_json_kind(e));
        if (i >= VV_MAX_LIGHTS)
            return serr(c, ep, "more than %d lights", VV_MAX_LIGHTS);
        vv_status st = check_keys(c, e, ep, keys);
        if (st != VV_OK)
            return st;
        vv_light l;
        memset(&l, 0, sizeof l);
        l.color = vv_vec3_make(1, 1, 1);
        l.intensity = 1.0;
        const char *type = "directional";
        int hd, hp;
        if ((st = get_string(c, e, ep, "type", &type)) != VV_OK ||
            (st = get_nonzero_vec3(c, e, ep, "direction", &l.direction, &hd)) != VV_OK ||
            (st = get_vec3(c, e, ep, "position", &l.position, &hp)) != VV_OK ||
            (st = get_color(c, e, ep, "color", &l.color, NULL)) != VV_OK ||
            (st = get_number_in(c, e, ep, "intensity", &l.intensity, NULL, 0, 0, INFINITY, 1)) !=
                VV_OK)
            return st;
        char kp[PATH_MAX_LEN];
        if (strcmp(type, "directional") == 0) {
            l.type = VV_LIGHT_DIRECTIONAL;
            if (hp) {
                path_key(kp, ep, "position");
                return serr(c, kp,
                            "a directional light has no position (use \"type\": "
                            "\"point\")");
            }
            if (hd) {
                l.direction = vv_vec3_normalize(l.direction);
            } else {
                l.headlight = 1;
                l.direction = view_dir;
            }
        } else if (strcmp(type, "point") == 0) {
            l.type = VV_LIGHT_POINT;
            if (hd) {
                path_key(kp, ep, "direction");
                return serr(c, kp, "a point light has no direction");
            }
            if (!hp)
                return missing(c, ep, "position", "where the point light is");
        } else {
            path_key(kp, ep, "type");
            return serr(c, kp, "unknown light type \"%s\"; expected directional or point", type);
        }
        w->lights[w->n_lights++] = l;
    }
    return VV_OK;
}

static vv_status
parse_tf_points(const sctx *c, json_t *tfj, const char *tp, vv_tf *tf, int opacity) {
    const char *key = opacity ? "opacity" : "color";
    json_t *arr;
    vv_status st = get_array(c, tfj, tp, key, &arr);
    if (st != VV_OK || !arr)
        return st;
    char ap[PATH_MAX_LEN];
    path_key(ap, tp, key);
    if (json_array_size(arr) > VV_TF_MAX_POINTS)
        return serr(c, ap, "more than %d points", VV_TF_MAX_POINTS);
    size_t i;
    json_t *e;
    json_array_foreach(arr, i, e) {
        char ep[PATH_MAX_LEN];
        path_index(ep, ap, i);
        if (!json_is_array(e) || json_array_size(e) != 2)
            return serr(c, ep, "expected a pair [value, %s], got %s",
                        opacity ? "opacity" : "[r, g, b]", vv_model_json_kind(e));
        char vp[PATH_MAX_LEN], op[PATH_MAX_LEN];
        path_index(vp, ep, 0);
        path_index(op, ep, 1);
        double value = 0.0;
        if ((st = value_number(c, json_array_get(e, 0), vp, &value)) != VV_OK)
            return st;
        if (opacity) {
            double a = 0.0;
            if ((st = value_number(c, json_array_get(e, 1), op, &a)) != VV_OK)
                return st;
            if (!(a >= 0.0 && a <= 1.0))
                return serr(c, op, "opacity %g is outside [0, 1]", a);
            if (vv_tf_add_opacity(tf, value, a) != VV_OK)
                return serr(c, ep, "%s", vv_error_message());
        } else {
            vv_vec3 col;
            if ((st = value_color(c, json_array_get(e, 1), op, &col)) != VV_OK)
                return st;
            if (vv_tf_add_color(tf, value, col) != VV_OK)
                return serr(c, ep, "%s", vv_error_message());
        }
    }
    return VV_OK;
}

static vv_status
parse_tf(const sctx *c, json_t *tfj, const char *tp, vv_object *o) {
    static const char *const keys[] = {"opacity", "color", "opacity_unit_distance", NULL};
    vv_status st = check_keys(c, tfj, tp, keys);
    if (st != VV_OK)
        return st;
    if (!json_object_get(tfj, "opacity"))
        return missing(c, tp, "opacity", "[[value, opacity], ...]");
    vv_tf tf;
    vv_tf_init(&tf);
    tf.opacity_unit_distance =
        o->volume ? vv_model_min_spacing(o->volume) : o->tf.opacity_unit_distance;
    if ((st = parse_tf_points(c, tfj, tp, &tf, 1)) != VV_OK ||
        (st = parse_tf_points(c, tfj, tp, &tf, 0)) != VV_OK ||
        (st = get_number_in(c, tfj, tp, "opacity_unit_distance", &tf.opacity_unit_distance, NULL, 0,
                            1, INFINITY, 1)) != VV_OK)
        return st;
    o->tf = tf;
    return VV_OK;
}

/* An optional [a, b] pair of numbers. */
static vv_status
get_pair(const sctx *c, json_t *obj, const char *path, const char *key, double out[2],
         int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = field(obj, key, kp, path, present);
    if (!v)
        return VV_OK;
    if (!json_is_array(v) || json_array_size(v) != 2)
        return serr(c, kp, "expected an array of 2 numbers, got %s%s", vv_model_json_kind(v),
                    json_is_array(v) ? " of another length" : "");
    for (size_t i = 0; i < 2; i++) {
        char ip[PATH_MAX_LEN];
        path_index(ip, kp, i);
        vv_status st = value_number(c, json_array_get(v, i), ip, &out[i]);
        if (st != VV_OK)
            return st;
    }
    return VV_OK;
}

static vv_status
parse_tf2d_widget(const sctx *c, json_t *e, const char *wp, vv_tf2d_widget *w) {
    static const char *const rkeys[] = {"shape",         "value", "gradient", "ramp",
                                        "gradient_ramp", "color", "opacity",  NULL};
    static const char *const tkeys[] = {"shape", "center",  "width", "gradient",
                                        "color", "opacity", NULL};
    if (!json_is_object(e))
        return serr(c, wp, "expected a widget object, got %s", vv_model_json_kind(e));
    const char *shape = NULL;
    vv_status st = get_string(c, e, wp, "shape", &shape);
    if (st != VV_OK)
        return st;
    if (!shape)
        return missing(c, wp, "shape", "\"rectangle\" or \"triangle\"");
    char kp[PATH_MAX_LEN];
    int has_a, has_b, has_c;
    if (strcmp(shape, "rectangle") == 0) {
        vv_tf2d_widget_init_rectangle(w, 0, 0, 0, 0, vv_vec3_make(1, 1, 1), 1.0);
        if ((st = check_keys(c, e, wp, rkeys)) != VV_OK ||
            (st = get_pair(c, e, wp, "value", w->value, &has_a)) != VV_OK ||
            (st = get_pair(c, e, wp, "gradient", w->gradient, &has_b)) != VV_OK ||
            (st = get_number(c, e, wp, "ramp", &w->ramp, NULL)) != VV_OK ||
            (st = get_number(c, e, wp, "gradient_ramp", &w->gradient_ramp, NULL)) != VV_OK)
            return st;
        if (!has_a)
            return missing(c, wp, "value", "[lo, hi] data values");
        if (!has_b)
            return missing(c, wp, "gradient", "[lo, hi] gradient magnitudes");
        w->center = 0.5 * (w->value[0] + w->value[1]);
        w->width = w->value[1] - w->value[0];
    } else if (strcmp(shape, "triangle") == 0) {
        vv_tf2d_widget_init_triangle(w, 0, 1, 1, vv_vec3_make(1, 1, 1), 1.0);
        if ((st = check_keys(c, e, wp, tkeys)) != VV_OK ||
            (st = get_number(c, e, wp, "center", &w->center, &has_a)) != VV_OK ||
            (st = get_number(c, e, wp, "width", &w->width, &has_b)) != VV_OK ||
            (st = get_pair(c, e, wp, "gradient", w->gradient, &has_c)) != VV_OK)
            return st;
        if (!has_a)
            return missing(c, wp, "center", "the apex data value");
        if (!has_b)
            return missing(c, wp, "width", "the base width at gradient[1], data units");
        if (!has_c)
            return missing(c, wp, "gradient", "[lo, hi] gradient magnitudes");
        w->value[0] = w->center - 0.5 * w->width;
        w->value[1] = w->center + 0.5 * w->width;
    } else {
        path_key(kp, wp, "shape");
        return serr(c, kp, "unknown widget shape \"%s\"; expected rectangle or triangle", shape);
    }
    if ((st = get_color(c, e, wp, "color", &w->color, NULL)) != VV_OK ||
        (st = get_number(c, e, wp, "opacity", &w->opacity, NULL)) != VV_OK)
        return st;
    vv_error_clear();
    if (vv_tf2d_widget_check(w) != VV_OK)
        return serr(c, wp, "%s", vv_error_message());
    return VV_OK;
}

static vv_status
parse_tf2d(const sctx *c, json_t *tj, const char *tp, vv_object *o) {
    static const char *const keys[] = {"widgets", "opacity_unit_distance", NULL};
    vv_status st = check_keys(c, tj, tp, keys);
    if (st != VV_OK)
        return st;
    json_t *arr;
    if ((st = get_array(c, tj, tp, "widgets", &arr)) != VV_OK)
        return st;
    if (!arr)
        return missing(c, tp, "widgets", "[{\"shape\": ...}, ...]");
    char ap[PATH_MAX_LEN];
    path_key(ap, tp, "widgets");
    if (json_array_size(arr) > VV_TF2D_MAX_WIDGETS)
        return serr(c, ap, "more than %d widgets", VV_TF2D_MAX_WIDGETS);
    vv_tf2d tf;
    vv_tf2d_init(&tf);
    tf.opacity_unit_distance = o->volume ? vv_model_min_spacing(o->volume) : 1.0;
    size_t i;
    json_t *e;
    json_array_foreach(arr, i, e) {
        char wp[PATH_MAX_LEN];
        path_index(wp, ap, i);
        if ((st = parse_tf2d_widget(c, e, wp, &tf.widgets[tf.n_widgets])) != VV_OK)
            return st;
        tf.n_widgets++;
    }
    if ((st = get_number_in(c, tj, tp, "opacity_unit_distance", &tf.opacity_unit_distance, NULL, 0,
                            1, INFINITY, 1)) != VV_OK)
        return st;
    o->tf2d = tf;
    return VV_OK;
}

/* A file named relative to the scene file, for error messages at its key. */
static vv_status
file_err(const sctx *c, vv_status st, const char *kp) {
    int line, col;
    scene_locate(c, kp, &line, &col);
    return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
}

static vv_status
parse_texture(const sctx *c, json_t *tj, const char *tp, vv_object *o) {
    static const char *const keys[] = {"image", "projection", "center", "axis", "scale", NULL};
    vv_status st = check_keys(c, tj, tp, keys);
    if (st != VV_OK)
        return st;
    const char *file = NULL, *proj = NULL;
    vv_texture_map m;
    vv_texture_map_init(&m);
    double sc[2] = {1, 1};
    char kp[PATH_MAX_LEN];
    if ((st = get_string(c, tj, tp, "image", &file)) != VV_OK ||
        (st = get_string(c, tj, tp, "projection", &proj)) != VV_OK ||
        (st = get_vec3(c, tj, tp, "center", &m.center, NULL)) != VV_OK ||
        (st = get_nonzero_vec3(c, tj, tp, "axis", &m.axis, NULL)) != VV_OK ||
        (st = get_pair(c, tj, tp, "scale", sc, NULL)) != VV_OK)
        return st;
    if (!file)
        return missing(c, tp, "image", "a PNG file, relative to the scene file");
    if (proj && vv_texture_projection_parse(proj, &m.projection) != VV_OK) {
        path_key(kp, tp, "projection");
        return serr(c, kp, "unknown projection \"%s\"; expected planar, cylindrical or spherical",
                    proj);
    }
    if (!(sc[0] != 0 && sc[1] != 0)) {
        path_key(kp, tp, "scale");
        return serr(c, kp, "scale factors must not be 0");
    }
    m.axis = vv_vec3_normalize(m.axis);
    m.scale[0] = sc[0];
    m.scale[1] = sc[1];
    path_key(kp, tp, "image");
    if (!file[0])
        return serr(c, kp, "empty file name");
    char *full = vv_path_join_dir(c->path, file);
    if (!full)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    vv_texture_image *img = NULL;
    st = vv_texture_image_load(&img, full, file);
    free(full);
    if (st != VV_OK)
        return file_err(c, st, kp);
    m.image = img; /* the reference from loading moves into the object */
    vv_texture_image_free(o->texture.image);
    o->texture = m;
    return VV_OK;
}

static vv_status
parse_solid_texture(const sctx *c, json_t *tj, const char *tp, vv_object *o) {
    static const char *const keys[] = {"procedural", "volume", "period", "center", "axis",
                                       "turbulence", "seed",   "color0", "color1", NULL};
    vv_status st = check_keys(c, tj, tp, keys);
    if (st != VV_OK)
        return st;
    const char *proc = NULL, *file = NULL;
    char kp[PATH_MAX_LEN];
    vv_solid_texture s;
    vv_solid_texture_init(&s);
    double seed = 1;
    if ((st = get_string(c, tj, tp, "procedural", &proc)) != VV_OK ||
        (st = get_string(c, tj, tp, "volume", &file)) != VV_OK ||
        (st = get_number_in(c, tj, tp, "period", &s.period, NULL, 0, 1, INFINITY, 1)) != VV_OK ||
        (st = get_vec3(c, tj, tp, "center", &s.center, NULL)) != VV_OK ||
        (st = get_nonzero_vec3(c, tj, tp, "axis", &s.axis, NULL)) != VV_OK ||
        (st = get_number_in(c, tj, tp, "turbulence", &s.turbulence, NULL, 0, 0, INFINITY, 1)) !=
            VV_OK ||
        (st = get_number_in(c, tj, tp, "seed", &seed, NULL, 0, 0, 4294967295.0, 0)) != VV_OK ||
        (st = get_color(c, tj, tp, "color0", &s.color0, NULL)) != VV_OK ||
        (st = get_color(c, tj, tp, "color1", &s.color1, NULL)) != VV_OK)
        return st;
    if (seed != floor(seed)) {
        path_key(kp, tp, "seed");
        return serr(c, kp, "expected an integer, got %g", seed);
    }
    s.seed = (unsigned)seed;
    s.axis = vv_vec3_normalize(s.axis);
    if ((proc != NULL) == (file != NULL))
        return serr(c, tp,
                    "give exactly one of \"procedural\" (checker3d, wood, marble) and "
                    "\"volume\" (a volume file)");
    if (proc) {
        path_key(kp, tp, "procedural");
        if (strcmp(proc, "checker3d") == 0)
            s.kind = VV_SOLID_TEXTURE_CHECKER;
        else if (strcmp(proc, "wood") == 0)
            s.kind = VV_SOLID_TEXTURE_WOOD;
        else if (strcmp(proc, "marble") == 0)
            s.kind = VV_SOLID_TEXTURE_MARBLE;
        else
            return serr(c, kp,
                        "unknown procedural texture \"%s\"; expected checker3d, wood or "
                        "marble",
                        proc);
    } else {
        path_key(kp, tp, "volume");
        if (!file[0])
            return serr(c, kp, "empty file name");
        char *full = vv_path_join_dir(c->path, file);
        if (!full)
            return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
        vv_volume *vol = NULL;
        st = vv_volume_load(&vol, full, NULL);
        free(full);
        if (st != VV_OK)
            return file_err(c, st, kp);
        st = vv_solid_texture_set_volume(&s, vol, file);
        vv_volume_free(vol);
        if (st != VV_OK)
            return st;
    }
    vv_solid_texture_clear(&o->solid_texture);
    o->solid_texture = s;
    return VV_OK;
}

/* The global-illumination terms of a material (volumetric ray tracing). */
static vv_status
parse_material_global(const sctx *c, json_t *m, const char *mp, vv_material *mat) {
    vv_status st;
    if ((st = get_number_in(c, m, mp, "reflectance", &mat->reflectance, NULL, 0, 0, 1, 0)) !=
            VV_OK ||
        (st = get_number_in(c, m, mp, "transparency", &mat->transparency, NULL, 0, 0, 1, 0)) !=
            VV_OK ||
        (st = get_number_in(c, m, mp, "ior", &mat->ior, NULL, 0, 1, INFINITY, 1)) != VV_OK)
        return st;
    /* radiosity: light emitted, each component >= 0 (may exceed 1) */
    int here = 0;
    vv_vec3 em = mat->emission;
    if ((st = get_vec3(c, m, mp, "emission", &em, &here)) != VV_OK)
        return st;
    if (here) {
        if (!(isfinite(em.x) && isfinite(em.y) && isfinite(em.z) && em.x >= 0 && em.y >= 0 &&
              em.z >= 0)) {
            char kp[PATH_MAX_LEN];
            path_key(kp, mp, "emission");
            return serr(c, kp, "expected three finite numbers >= 0");
        }
        mat->emission = em;
    }
    return VV_OK;
}

/* The per-object shading-effect flags (every object type). */
static vv_status
parse_effect_flags(const sctx *c, json_t *e, const char *op, vv_object *o) {
    vv_status st;
    if ((st = get_bool(c, e, op, "casts_shadows", &o->casts_shadows)) != VV_OK ||
        (st = get_bool(c, e, op, "receives_shadows", &o->receives_shadows)) != VV_OK ||
        (st = get_bool(c, e, op, "visible_in_reflections", &o->visible_in_reflections)) != VV_OK ||
        (st = get_bool(c, e, op, "reflects", &o->reflects)) != VV_OK)
        return st;
    return VV_OK;
}

static vv_status
parse_material(const sctx *c, json_t *m, const char *mp, vv_material *mat) {
    static const char *const keys[] = {"ambient",  "diffuse",     "specular",     "shininess",
                                       "color",    "reflectance", "transparency", "ior",
                                       "emission", NULL};
    vv_status st = check_keys(c, m, mp, keys);
    if (st != VV_OK)
        return st;
    if ((st = get_number_in(c, m, mp, "ambient", &mat->ambient, NULL, 0, 0, INFINITY, 1)) !=
            VV_OK ||
        (st = get_number_in(c, m, mp, "diffuse", &mat->diffuse, NULL, 0, 0, INFINITY, 1)) !=
            VV_OK ||
        (st = get_number_in(c, m, mp, "specular", &mat->specular, NULL, 0, 0, INFINITY, 1)) !=
            VV_OK ||
        (st = get_number_in(c, m, mp, "shininess", &mat->shininess, NULL, 0, 0, INFINITY, 1)) !=
            VV_OK ||
        (st = get_color(c, m, mp, "color", &mat->color, NULL)) != VV_OK)
        return st;
    return parse_material_global(c, m, mp, mat);
}

static const char *const mode_names[] = {"composite", "mip", "minip", "xray", "iso"};

static vv_status
parse_mode(const sctx *c, const char *op, const char *s, vv_render_mode *out) {
    for (int i = 0; i < 5; i++) {
        if (strcmp(s, mode_names[i]) == 0) {
            *out = (vv_render_mode)i;
            return VV_OK;
        }
    }
    char kp[PATH_MAX_LEN];
    path_key(kp, op, "mode");
    return serr(c, kp, "unknown mode \"%s\"; expected composite, mip, minip, xray or iso", s);
}

/* Object fields other than the volume source (file, origin, spacing). */
static vv_status
parse_object_fields(const sctx *c, json_t *e, const char *op, vv_object *o) {
    vv_status st;
    char kp[PATH_MAX_LEN];
    const char *mode = NULL;
    int has_iso, has_rot, has_ori;
    if ((st = get_string(c, e, op, "mode", &mode)) != VV_OK)
        return st;
    if (mode && (st = parse_mode(c, op, mode, &o->mode)) != VV_OK)
        return st;
    if ((st = get_number(c, e, op, "isovalue", &o->isovalue, &has_iso)) != VV_OK ||
        (st = get_number_in(c, e, op, "step", &o->step, NULL, 0, 1, INFINITY, 1)) != VV_OK ||
        (st = get_bool(c, e, op, "shading", &o->shading)) != VV_OK ||
        (st = get_bool(c, e, op, "visible", &o->visible)) != VV_OK ||
        (st = get_vec3(c, e, op, "position", &o->position, NULL)) != VV_OK)
        return st;
    if (o->mode == VV_MODE_ISO && !has_iso) {
        path_key(kp, op, "mode");
        return serr(c, kp, "mode \"iso\" needs an \"isovalue\"");
    }

    /* rotation (axis-angle, degrees) or orientation (quaternion) */
    json_t *rot;
    if ((st = get_object(c, e, op, "rotation", &rot)) != VV_OK)
        return st;
    has_rot = rot != NULL;
    has_ori = json_object_get(e, "orientation") != NULL;
    if (has_rot && has_ori) {
        path_key(kp, op, "orientation");
        return serr(c, kp, "give either \"rotation\" or \"orientation\", not both");
    }
    if (rot) {
        static const char *const rkeys[] = {"axis", "angle", NULL};
        char rp[PATH_MAX_LEN];
        path_key(rp, op, "rotation");
        vv_vec3 axis = {0, 0, 1};
        double angle = 0.0;
        int ha, hg;
        if ((st = check_keys(c, rot, rp, rkeys)) != VV_OK ||
            (st = get_nonzero_vec3(c, rot, rp, "axis", &axis, &ha)) != VV_OK ||
            (st = get_number(c, rot, rp, "angle", &angle, &hg)) != VV_OK)
            return st;
        if (!ha)
            return missing(c, rp, "axis", "the rotation axis [x, y, z]");
        if (!hg)
            return missing(c, rp, "angle", "degrees");
        o->orientation = vv_quat_from_axis_angle(axis, vv_deg_to_rad(angle));
    }
    if (has_ori) {
        json_t *q = json_object_get(e, "orientation");
        path_key(kp, op, "orientation");
        if (!json_is_array(q) || json_array_size(q) != 4)
            return serr(c, kp, "expected a quaternion [w, x, y, z], got %s", vv_model_json_kind(q));
        double d[4];
        for (size_t i = 0; i < 4; i++) {
            char ip[PATH_MAX_LEN];
            path_index(ip, kp, i);
            if ((st = value_number(c, json_array_get(q, i), ip, &d[i])) != VV_OK)
                return st;
        }
        double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
        if (!(n > 0.0))
            return serr(c, kp, "the zero quaternion is not a rotation");
        o->orientation = (vv_quat){d[0] / n, d[1] / n, d[2] / n, d[3] / n};
    }

    /* scale: a number (uniform) or [sx, sy, sz], all > 0 */
    json_t *sc = json_object_get(e, "scale");
    if (sc) {
        path_key(kp, op, "scale");
        vv_vec3 s;
        if (json_is_number(sc)) {
            double u = json_number_value(sc);
            s = vv_vec3_make(u, u, u);
        } else if ((st = value_vec3(c, sc, kp, &s)) != VV_OK) {
            return st;
        }
        if (!(s.x > 0.0 && s.y > 0.0 && s.z > 0.0))
            return serr(c, kp, "scale factors must be > 0");
        o->scale = s;
    }

    /* segmentation: a transfer function (1-D or 2-D) or a threshold */
    json_t *tfj, *seg = NULL, *mat, *cuts, *tf2j, *texj, *soj;
    const char *seg_name = NULL;
    json_t *segv = json_object_get(e, "segmentation");
    if (segv && json_is_string(segv)) {
        seg_name = json_string_value(segv);
    } else if ((st = get_object(c, e, op, "segmentation", &seg)) != VV_OK) {
        path_key(kp, op, "segmentation");
        return serr(c, kp,
                    "expected {\"threshold\": value}, \"transfer_function\" or \"tf2d\", got %s",
                    vv_model_json_kind(segv));
    }
    if ((st = get_object(c, e, op, "transfer_function", &tfj)) != VV_OK ||
        (st = get_object(c, e, op, "tf2d", &tf2j)) != VV_OK ||
        (st = get_object(c, e, op, "texture", &texj)) != VV_OK ||
        (st = get_object(c, e, op, "solid_texture", &soj)) != VV_OK ||
        (st = get_object(c, e, op, "material", &mat)) != VV_OK ||
        (st = get_array(c, e, op, "cut_planes", &cuts)) != VV_OK)
        return st;
    if (seg_name) {
        path_key(kp, op, "segmentation");
        if (strcmp(seg_name, "tf2d") == 0) {
            if (!tf2j)
                return serr(c, kp, "segmentation \"tf2d\" needs a \"tf2d\" object");
            o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
        } else if (strcmp(seg_name, "transfer_function") == 0) {
            o->segmentation = VV_SEG_TRANSFER_FUNCTION;
        } else if (strcmp(seg_name, "labels") == 0) {
            o->segmentation = VV_SEG_LABELS;
        } else {
            return serr(c, kp,
                        "unknown segmentation \"%s\"; expected \"transfer_function\", \"tf2d\", "
                        "\"labels\" or {\"threshold\": value}",
                        seg_name);
        }
    }
    if (tf2j) {
        path_key(kp, op, "tf2d");
        if ((st = parse_tf2d(c, tf2j, kp, o)) != VV_OK)
            return st;
    }
    if (texj) {
        path_key(kp, op, "texture");
        if ((st = parse_texture(c, texj, kp, o)) != VV_OK)
            return st;
    }
    if (soj) {
        path_key(kp, op, "solid_texture");
        if ((st = parse_solid_texture(c, soj, kp, o)) != VV_OK)
            return st;
    }
    if (tfj && seg) {
        path_key(kp, op, "segmentation");
        return serr(c, kp, "give either \"transfer_function\" or \"segmentation\", not both");
    }
    if (tfj) {
        path_key(kp, op, "transfer_function");
        if ((st = parse_tf(c, tfj, kp, o)) != VV_OK)
            return st;
    } else if (o->volume) {
        /* the default TF depends on the mode, known only now */
        double iso_lo;
        vv_model_default_tf(o->volume, o->mode, &o->tf, &iso_lo);
    }
    if (seg) {
        static const char *const skeys[] = {"threshold", NULL};
        path_key(kp, op, "segmentation");
        int ht;
        if ((st = check_keys(c, seg, kp, skeys)) != VV_OK ||
            (st = get_number(c, seg, kp, "threshold", &o->threshold, &ht)) != VV_OK)
            return st;
        if (!ht)
            return missing(c, kp, "threshold", "the data value from which voxels are opaque");
        o->segmentation = VV_SEG_THRESHOLD;
    }
    if (mat) {
        path_key(kp, op, "material");
        if ((st = parse_material(c, mat, kp, &o->material)) != VV_OK)
            return st;
    }
    if (cuts) {
        path_key(kp, op, "cut_planes");
        if ((st = parse_cut_planes(c, cuts, kp, o->cut_planes, &o->n_cut_planes)) != VV_OK)
            return st;
    }
    return VV_OK;
}

/* Name from a file path: its base name without the extension(s). */
static void
name_from_file(char dst[VV_NAME_MAX], const char *file) {
    vv_model_copy_name(dst, vv_path_basename(file));
    char *dot = strchr(dst, '.');
    if (dot && dot != dst)
        *dot = '\0';
}

/* ---- geometric objects (volumetric ray tracing) ---------------------------- */

/* VV_OBJECT_VOLUME for "volume" and for names that are not geometric types. */
static vv_object_type
geometry_type(const char *name) {
    static const vv_object_type types[] = {VV_OBJECT_PLANE, VV_OBJECT_POLYGON,  VV_OBJECT_SPHERE,
                                           VV_OBJECT_BOX,   VV_OBJECT_CYLINDER, VV_OBJECT_MESH};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        if (strcmp(name, vv_object_type_name(types[i])) == 0)
            return types[i];
    return VV_OBJECT_VOLUME;
}

/* The shape keys of one geometric type. */
static vv_status
parse_shape(const sctx *c, json_t *e, const char *op, vv_object *o) {
    vv_geometry *g = &o->geometry;
    vv_status st;
    char kp[PATH_MAX_LEN];
    int has_a, has_b;
    switch (o->type) {
    case VV_OBJECT_PLANE:
        if ((st = get_vec3(c, e, op, "point", &g->point, NULL)) != VV_OK ||
            (st = get_nonzero_vec3(c, e, op, "normal", &g->normal, NULL)) != VV_OK)
            return st;
        g->normal = vv_vec3_normalize(g->normal);
        return VV_OK;
    case VV_OBJECT_SPHERE:
        return (st = get_vec3(c, e, op, "center", &g->center, NULL)) != VV_OK
                   ? st
                   : get_number_in(c, e, op, "radius", &g->radius, NULL, 0, 1, INFINITY, 1);
    case VV_OBJECT_BOX: {
        vv_box b = g->box;
        if ((st = get_vec3(c, e, op, "min", &b.min, &has_a)) != VV_OK ||
            (st = get_vec3(c, e, op, "max", &b.max, &has_b)) != VV_OK)
            return st;
        if (!(b.min.x < b.max.x && b.min.y < b.max.y && b.min.z < b.max.z)) {
            path_key(kp, op, "max");
            return serr(c, kp, "each coordinate must be greater than in \"min\"");
        }
        g->box = b;
        return VV_OK;
    }
    case VV_OBJECT_CYLINDER:
        if ((st = get_vec3(c, e, op, "base", &g->base, NULL)) != VV_OK ||
            (st = get_vec3(c, e, op, "top", &g->top, NULL)) != VV_OK ||
            (st = get_number_in(c, e, op, "radius", &g->radius, NULL, 0, 1, INFINITY, 1)) !=
                VV_OK ||
            (st = get_bool(c, e, op, "capped", &g->capped)) != VV_OK)
            return st;
        if (!(vv_vec3_length(vv_vec3_sub(g->top, g->base)) > 0)) {
            path_key(kp, op, "top");
            return serr(c, kp, "the cylinder's top must differ from its base");
        }
        return VV_OK;
    case VV_OBJECT_POLYGON: {
        json_t *arr;
        if ((st = get_array(c, e, op, "vertices", &arr)) != VV_OK)
            return st;
        if (!arr)
            return missing(c, op, "vertices", "[[x, y, z], ...], at least 3, in one plane");
        path_key(kp, op, "vertices");
        size_t n = json_array_size(arr);
        if (n < 3 || n > 100000)
            return serr(c, kp, "expected 3 to 100000 vertices, got %zu", n);
        vv_vec3 *v = malloc(n * sizeof *v);
        if (!v)
            return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
        for (size_t i = 0; i < n; i++) {
            char ip[PATH_MAX_LEN];
            path_index(ip, kp, i);
            if ((st = value_vec3(c, json_array_get(arr, i), ip, &v[i])) != VV_OK) {
                free(v);
                return st;
            }
        }
        vv_error_clear();
        st = vv_object_set_polygon(o, (int)n, v);
        free(v);
        if (st != VV_OK) {
            int line, col;
            scene_locate(c, kp, &line, &col);
            return vv_error_prefix(VV_ERR_FORMAT, "%s:%d:%d: %s", c->path, line, col, kp);
        }
        return VV_OK;
    }
    case VV_OBJECT_MESH: {
        const char *file = NULL;
        if ((st = get_string(c, e, op, "file", &file)) != VV_OK)
            return st;
        if (!file)
            return missing(c, op, "file",
                           "the mesh file (OBJ, PLY, STL, ...), relative to the "
                           "scene file");
        path_key(kp, op, "file");
        if (!file[0])
            return serr(c, kp, "empty file name");
        char *full = vv_path_join_dir(c->path, file);
        if (!full)
            return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
        vv_mesh *m = NULL;
        st = vv_mesh_load(&m, full);
        free(full);
        if (st == VV_OK) {
            st = vv_object_set_mesh(o, m, file);
            vv_mesh_free(m);
        }
        if (st != VV_OK) {
            int line, col;
            scene_locate(c, kp, &line, &col);
            return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
        }
        return VV_OK;
    }
    default:
        return serr(c, op, "not a geometric object");
    }
}

/* Checks the keys of object @p e: "name" and "type", the kind's own keys
 * @p own (NULL-terminated), the keys of volume-like objects (mode,
 * segmentation, cut planes) when @p volume_like, and the transform,
 * material, visibility and shading-effect keys every object takes. */
static vv_status
check_object_keys(const sctx *c, json_t *e, const char *op, const char *const *own,
                  int volume_like) {
    static const char *const head[] = {"name", "type", NULL};
    static const char *const volume_head[] = {"mode", "isovalue", "step", "shading", NULL};
    static const char *const place[] = {"visible",     "position", "rotation",
                                        "orientation", "scale",    NULL};
    static const char *const volume_mid[] = {"transfer_function", "segmentation", "tf2d",
                                             "solid_texture", NULL};
    static const char *const mat[] = {"material", "texture", NULL};
    static const char *const volume_tail[] = {"cut_planes", NULL};
    static const char *const flags[] = {"casts_shadows", "receives_shadows",
                                        "visible_in_reflections", "reflects", NULL};
    const char *const *parts[] = {head,
                                  own,
                                  volume_like ? volume_head : NULL,
                                  place,
                                  volume_like ? volume_mid : NULL,
                                  mat,
                                  volume_like ? volume_tail : NULL,
                                  flags};
    const char *keys[64];
    size_t n = 0;
    for (size_t p = 0; p < sizeof parts / sizeof parts[0]; p++)
        for (size_t i = 0; parts[p] && parts[p][i] && n + 1 < sizeof keys / sizeof keys[0]; i++)
            keys[n++] = parts[p][i];
    keys[n] = NULL;
    return check_keys(c, e, op, keys);
}

/* The optional "name" of object @p e, at most VV_NAME_MAX - 1 bytes. */
static vv_status
get_object_name(const sctx *c, json_t *e, const char *op, const char **name) {
    vv_status st = get_string(c, e, op, "name", name);
    if (st == VV_OK && *name && strlen(*name) >= VV_NAME_MAX) {
        char kp[PATH_MAX_LEN];
        path_key(kp, op, "name");
        return serr(c, kp, "longer than %d bytes", VV_NAME_MAX - 1);
    }
    return st;
}

/* A geometric object: its shape (in object coordinates), transform,
 * material, visibility and shading-effect flags. */
static vv_status
parse_geometry_object(const sctx *c, json_t *e, const char *op, vv_world *w) {
    static const char *const shape_keys[][5] = {
        [VV_OBJECT_PLANE] = {"point", "normal", NULL},
        [VV_OBJECT_POLYGON] = {"vertices", NULL},
        [VV_OBJECT_SPHERE] = {"center", "radius", NULL},
        [VV_OBJECT_BOX] = {"min", "max", NULL},
        [VV_OBJECT_CYLINDER] = {"base", "top", "radius", "capped", NULL},
        [VV_OBJECT_MESH] = {"file", NULL},
    };
    const vv_object_type type = geometry_type(json_string_value(json_object_get(e, "type")));
    const char *name = NULL;
    vv_status st = check_object_keys(c, e, op, shape_keys[type], 0);
    if (st != VV_OK || (st = get_object_name(c, e, op, &name)) != VV_OK)
        return st;
    vv_object *o = NULL;
    if ((st = vv_object_new_geometry(&o, type, name)) != VV_OK)
        return vv_error_prefix(st, "%s: %s", c->path, op);
    if ((st = parse_shape(c, e, op, o)) != VV_OK ||
        (st = parse_object_fields(c, e, op, o)) != VV_OK ||
        (st = parse_effect_flags(c, e, op, o)) != VV_OK) {
        vv_object_free(o);
        return st;
    }
    return vv_world_add_object(w, o);
}

/* ---- geometry objects (issue 3, Modeling) ---------------------------------
 * A "geometry" object holds a primitive or a CSG tree, read by the Modeling
 * component (src/modeling/shape_json.c) and volume-sampled here at load, so
 * it becomes a volume object that every volume renderer draws. */

/* Adds "file:line:col: key.path" in front of a message set by Modeling. */
static vv_status
geometry_err(const sctx *c, vv_status st, const char *path) {
    int line, col;
    scene_locate(c, path, &line, &col);
    return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, path);
}

static vv_status
parse_voxelized_geometry(const sctx *c, json_t *e, const char *op, vv_world *w) {
    static const char *const own[] = {"primitive",     "csg",        "resolution",
                                      "voxel_spacing", "filter",     "filter_radius",
                                      "margin",        "voxel_type", NULL};
    char kp[PATH_MAX_LEN], ep[PATH_MAX_LEN];
    const char *name = NULL;
    vv_status st = check_object_keys(c, e, op, own, 1);
    if (st != VV_OK || (st = get_object_name(c, e, op, &name)) != VV_OK)
        return st;
    json_t *prim = json_object_get(e, "primitive"), *csg = json_object_get(e, "csg");
    if (prim && csg) {
        path_key(kp, op, "csg");
        return serr(c, kp, "give either \"primitive\" or \"csg\", not both");
    }
    if (!prim && !csg)
        return missing(c, op, "primitive",
                       "a primitive {\"type\": ...} or a \"csg\" tree {\"op\": ...}");
    path_key(kp, op, prim ? "primitive" : "csg");
    if (csg && !json_object_get(csg, "op"))
        return serr(c, kp, "expected a CSG operation {\"op\": ..., \"children\": [...]}");
    vv_voxelize_options vo;
    vv_voxelize_options_init(&vo);
    if (c->progress)
        vo.progress = *c->progress;
    if ((st = vv_voxelize_options_from_json(&vo, e, op, ep, sizeof ep)) != VV_OK)
        return geometry_err(c, st, ep);
    vv_shape *shape = NULL;
    if ((st = vv_shape_from_json(&shape, prim ? prim : csg, kp, c->path, ep, sizeof ep)) != VV_OK)
        return geometry_err(c, st, ep[0] ? ep : kp);
    vv_volume *vol = NULL;
    st = vv_voxelize(&vol, shape, &vo);
    vv_shape_free(shape);
    if (st != VV_OK)
        return geometry_err(c, st, kp);
    vv_object *o = NULL;
    st = vv_object_new_volume(&o, vol, name ? name : "geometry");
    vv_volume_free(vol);
    if (st != VV_OK)
        return vv_error_prefix(st, "%s: %s", c->path, op);
    if ((st = parse_object_fields(c, e, op, o)) != VV_OK ||
        (st = parse_effect_flags(c, e, op, o)) != VV_OK) {
        vv_object_free(o);
        return st;
    }
    if (!json_object_get(e, "transfer_function") && !json_object_get(e, "segmentation")) {
        /* densities: opaque from just below the surface level (half scale) */
        double top = vo.type == VV_U8 ? 255.0 : 1.0;
        vv_tf_set_ramp(&o->tf, 0.3 * top, 0.6 * top, 1.0, o->material.color,
                       o->tf.opacity_unit_distance);
    }
    return vv_world_add_object(w, o);
}

/* An irregular grid object: {"type": "grid", "file": ..., "field": ...,
 * "component": -1, "time": 0} with the volume objects' keys. */
static vv_status
parse_grid_object(const sctx *c, json_t *e, const char *op, vv_world *w) {
    static const char *const own[] = {"file", "field", "component", "time", NULL};
    char kp[PATH_MAX_LEN];
    vv_status st = check_object_keys(c, e, op, own, 1);
    const char *name = NULL, *file = NULL, *field = NULL;
    int component = -1, time = 0;
    if (st != VV_OK || (st = get_object_name(c, e, op, &name)) != VV_OK ||
        (st = get_string(c, e, op, "file", &file)) != VV_OK ||
        (st = get_string(c, e, op, "field", &field)) != VV_OK ||
        (st = get_int_in(c, e, op, "component", &component, -1, 8)) != VV_OK ||
        (st = get_int_in(c, e, op, "time", &time, 0, 1000000)) != VV_OK)
        return st;
    if (!file)
        return missing(c, op, "file",
                       "the grid file (VTK, .vtu, OpenDX, PLOT3D, NetCDF), relative to the "
                       "scene file");
    path_key(kp, op, "file");
    if (!file[0])
        return serr(c, kp, "empty file name");
    char *full = vv_path_join_dir(c->path, file);
    if (!full)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    vv_grid *g = NULL;
    st = vv_grid_load(&g, full);
    vv_object *o = NULL;
    if (st == VV_OK) {
        char defname[VV_NAME_MAX];
        name_from_file(defname, file);
        st = vv_object_new_grid(&o, g, NULL, name ? name : defname);
        vv_grid_free(g);
    }
    if (st != VV_OK) {
        free(full);
        int line, col;
        scene_locate(c, kp, &line, &col);
        return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
    }
    o->geometry.source = full;
    o->component = component;
    o->time = time;
    if (field)
        snprintf(o->field, sizeof o->field, "%s", field);
    if (vv_object_grid_field(o) < 0 && o->grid->n_fields > 0) {
        path_key(kp, op, field ? "field" : "time");
        char msg[512];
        snprintf(msg, sizeof msg, "%s", vv_error_message());
        vv_object_free(o);
        return serr(c, kp, "%s", msg);
    }
    /* the TF default follows the chosen field */
    const int f = vv_object_grid_field(o);
    if (f >= 0 && o->grid->fields[f].range[1] > o->grid->fields[f].range[0])
        vv_tf_set_ramp(&o->tf, o->grid->fields[f].range[0], o->grid->fields[f].range[1], 1.0,
                       vv_vec3_make(1, 1, 1), o->tf.opacity_unit_distance);
    if ((st = parse_object_fields(c, e, op, o)) != VV_OK ||
        (st = parse_effect_flags(c, e, op, o)) != VV_OK) {
        vv_object_free(o);
        return st;
    }
    return vv_world_add_object(w, o);
}

static vv_status
parse_object(const sctx *c, json_t *e, size_t idx, vv_world *w) {
    static const char *const own[] = {"file", "origin", "spacing", "filters", NULL};
    char op[PATH_MAX_LEN], kp[PATH_MAX_LEN];
    path_index(op, "objects", idx);
    if (json_is_object(e)) {
        json_t *tj = json_object_get(e, "type");
        if (json_is_string(tj) && strcmp(json_string_value(tj), "geometry") == 0)
            return parse_voxelized_geometry(c, e, op, w);
        if (json_is_string(tj) && strcmp(json_string_value(tj), "grid") == 0)
            return parse_grid_object(c, e, op, w);
        if (json_is_string(tj) && geometry_type(json_string_value(tj)) != VV_OBJECT_VOLUME)
            return parse_geometry_object(c, e, op, w);
    }
    if (!json_is_object(e))
        return serr(c, op, "expected an object, got %s", vv_model_json_kind(e));
    vv_status st = check_object_keys(c, e, op, own, 1);
    if (st != VV_OK)
        return st;
    const char *type = "volume", *name = NULL, *file = NULL;
    if ((st = get_string(c, e, op, "type", &type)) != VV_OK ||
        (st = get_object_name(c, e, op, &name)) != VV_OK ||
        (st = get_string(c, e, op, "file", &file)) != VV_OK)
        return st;
    if (strcmp(type, "volume") != 0) {
        path_key(kp, op, "type");
        return serr(c, kp,
                    "unsupported object type \"%s\"; expected volume, grid, geometry, plane, "
                    "polygon, sphere, box, cylinder or mesh",
                    type);
    }
    if (!file)
        return missing(c, op, "file", "the volume file, relative to the scene file");
    path_key(kp, op, "file");
    if (!file[0])
        return serr(c, kp, "empty file name");
    vv_vec3 origin, spacing;
    int has_origin, has_spacing;
    if ((st = get_vec3(c, e, op, "origin", &origin, &has_origin)) != VV_OK ||
        (st = get_vec3(c, e, op, "spacing", &spacing, &has_spacing)) != VV_OK)
        return st;
    if (has_spacing && !(spacing.x > 0.0 && spacing.y > 0.0 && spacing.z > 0.0)) {
        path_key(kp, op, "spacing");
        return serr(c, kp, "voxel spacing must be > 0");
    }

    char *full = vv_path_join_dir(c->path, file);
    if (!full)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    vv_volume *vol = NULL;
    /* "filters": a filter chain applied at load (src/filter), the result cached */
    json_t *fj = json_object_get(e, "filters");
    vv_filter_chain *chain = NULL;
    if (fj) {
        int bad;
        path_key(kp, op, "filters");
        if ((st = vf_chain_from_json(fj, &chain, &bad)) != VV_OK) {
            char msg[512], ip[PATH_MAX_LEN];
            snprintf(msg, sizeof msg, "%s", vv_error_message());
            free(full);
            if (bad >= 0)
                path_index(ip, kp, (size_t)bad);
            return serr(c, bad >= 0 ? ip : kp, "%s", msg);
        }
        double o3[3] = {origin.x, origin.y, origin.z}, s3[3] = {spacing.x, spacing.y, spacing.z};
        vv_filter_options fo;
        vv_filter_options_init(&fo);
        if (c->progress)
            fo.progress = *c->progress; /* and its cancel */
        st = vv_filter_load_cached(full, has_origin ? o3 : NULL, has_spacing ? s3 : NULL, chain,
                                   &fo, &vol);
    } else {
        st = vv_volume_load(&vol, full, NULL);
    }
    if (st != VV_OK) {
        vv_filter_chain_free(chain);
        free(full);
        int line, col;
        path_key(kp, op, fj ? "filters" : "file");
        scene_locate(c, kp, &line, &col);
        return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
    }
    /* the volume is freshly loaded and ours alone, so overriding is safe (a
     * filtered one is shared with the cache and already has them) */
    if (has_origin && !fj) {
        vol->origin[0] = origin.x;
        vol->origin[1] = origin.y;
        vol->origin[2] = origin.z;
    }
    if (has_spacing && !fj) {
        vol->spacing[0] = spacing.x;
        vol->spacing[1] = spacing.y;
        vol->spacing[2] = spacing.z;
    }
    char defname[VV_NAME_MAX];
    name_from_file(defname, file);
    vv_object *o = NULL;
    st = vv_object_new_volume(&o, vol, name ? name : defname);
    vv_volume_free(vol);
    if (st != VV_OK) {
        vv_filter_chain_free(chain);
        free(full);
        return vv_error_prefix(st, "%s: %s", c->path, op);
    }
    o->geometry.source = full; /* kept for saving the scene again */
    if (chain && vv_filter_chain_length(chain) > 0 &&
        !(o->geometry.filters = vv_strdup(vv_filter_chain_text(chain)))) {
        vv_filter_chain_free(chain);
        vv_object_free(o);
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    }
    vv_filter_chain_free(chain);
    st = parse_object_fields(c, e, op, o);
    if (st == VV_OK)
        st = parse_effect_flags(c, e, op, o);
    if (st != VV_OK) {
        vv_object_free(o);
        return st;
    }
    return vv_world_add_object(w, o);
}

/* An option value as the text a renderer's set-option reads: strings as they
 * are, booleans "1"/"0", numbers with as few digits as read back the same
 * double (%.15g, else %.17g). */
static vv_status
render_option_text(const sctx *c, json_t *v, const char *kp, char *buf, size_t cap) {
    switch (json_typeof(v)) {
    case JSON_STRING: {
        size_t n = json_string_length(v);
        if (n >= cap)
            return serr(c, kp, "value is %zu bytes; at most %zu", n, cap - 1);
        if (strlen(json_string_value(v)) != n)
            return serr(c, kp, "value contains a NUL character");
        memcpy(buf, json_string_value(v), n + 1);
        return VV_OK;
    }
    case JSON_TRUE:
    case JSON_FALSE:
        snprintf(buf, cap, "%s", json_is_true(v) ? "1" : "0");
        return VV_OK;
    case JSON_INTEGER:
    case JSON_REAL: {
        double d = 0.0;
        vv_status st = value_number(c, v, kp, &d);
        if (st != VV_OK)
            return st;
        snprintf(buf, cap, "%.15g", d);
        if (strtod(buf, NULL) != d)
            snprintf(buf, cap, "%.17g", d);
        return VV_OK;
    }
    default:
        break;
    }
    return serr(c, kp, "expected a string, a number or a boolean, got %s", vv_model_json_kind(v));
}

/* The optional "render" section: renderer, quality and renderer options.
 * Renderer names and option keys are not checked here (the model does not
 * know the renderers); vv_renderer_new and vv_renderer_set_option do. */
static vv_status
parse_render(const sctx *c, json_t *r, vv_render_settings *rs) {
    static const char *const keys[] = {"renderer", "quality", "options", NULL};
    const char *path = "render";
    const char *name = NULL;
    json_t *opts = NULL;
    int quality = rs->quality;
    vv_status st;
    if ((st = check_keys(c, r, path, keys)) != VV_OK ||
        (st = get_string(c, r, path, "renderer", &name)) != VV_OK ||
        (st = get_int_in(c, r, path, "quality", &quality, 0, 2)) != VV_OK ||
        (st = get_object(c, r, path, "options", &opts)) != VV_OK)
        return st;
    if (name) {
        size_t n = strlen(name);
        if (n == 0)
            return serr(c, "render.renderer", "the renderer name is empty");
        if (n >= sizeof rs->renderer)
            return serr(c, "render.renderer", "renderer name \"%.40s\" is %zu bytes; at most %zu",
                        name, n, sizeof rs->renderer - 1);
        memcpy(rs->renderer, name, n + 1);
    }
    rs->quality = quality;
    if (!opts)
        return VV_OK;
    const char *key;
    json_t *v;
    json_object_foreach(opts, key, v) {
        char kp[PATH_MAX_LEN];
        path_key(kp, "render.options", key);
        size_t kl = strlen(key);
        if (kl == 0)
            return serr(c, kp, "the option name is empty");
        if (kl >= VV_RENDER_OPTION_KEY_MAX)
            return serr(c, kp, "option name is %zu bytes; at most %d", kl,
                        VV_RENDER_OPTION_KEY_MAX - 1);
        if (rs->n_options >= VV_MAX_RENDER_OPTIONS)
            return serr(c, kp, "more than %d options", VV_MAX_RENDER_OPTIONS);
        char text[VV_RENDER_OPTION_VALUE_MAX];
        if ((st = render_option_text(c, v, kp, text, sizeof text)) != VV_OK)
            return st;
        if ((st = vv_render_settings_set_option(rs, key, text)) != VV_OK)
            return serr(c, kp, "%s", vv_error_message());
    }
    return VV_OK;
}

static vv_status
parse_scene(const sctx *c, json_t *root, vv_world *w) {
    static const char *const keys[] = {"view",       "lights", "shading", "objects",
                                       "cut_planes", "render", NULL};
    if (!json_is_object(root))
        return serr(c, "", "expected a JSON object at the top level, got %s",
                    vv_model_json_kind(root));
    vv_status st = check_keys(c, root, "", keys);
    if (st != VV_OK)
        return st;
    json_t *view, *lights, *shading, *objects, *cuts, *render;
    if ((st = get_object(c, root, "", "view", &view)) != VV_OK ||
        (st = get_object(c, root, "", "render", &render)) != VV_OK ||
        (st = get_array(c, root, "", "lights", &lights)) != VV_OK ||
        (st = get_object(c, root, "", "shading", &shading)) != VV_OK ||
        (st = get_array(c, root, "", "objects", &objects)) != VV_OK ||
        (st = get_array(c, root, "", "cut_planes", &cuts)) != VV_OK)
        return st;
    int view_bg = 0;
    if (view && (st = parse_view(c, view, w, &view_bg)) != VV_OK)
        return st;
    if (shading) {
        static const char *const skeys[] = {"ambient", "background", NULL};
        vv_vec3 bg;
        int has_bg;
        if ((st = check_keys(c, shading, "shading", skeys)) != VV_OK ||
            (st = get_color(c, shading, "shading", "ambient", &w->ambient, NULL)) != VV_OK ||
            (st = get_color(c, shading, "shading", "background", &bg, &has_bg)) != VV_OK)
            return st;
        if (has_bg && view_bg)
            return serr(c, "shading.background",
                        "the background is also given in view.background; give it once");
        if (has_bg)
            w->background = bg;
    }
    if (render && (st = parse_render(c, render, &w->render)) != VV_OK)
        return st;
    if (lights && (st = parse_lights(c, lights, w)) != VV_OK)
        return st;
    if (cuts &&
        (st = parse_cut_planes(c, cuts, "cut_planes", w->cut_planes, &w->n_cut_planes)) != VV_OK)
        return st;
    if (objects) {
        size_t i;
        json_t *e;
        json_array_foreach(objects, i, e) {
            if ((st = parse_object(c, e, i, w)) != VV_OK)
                return st;
        }
    }
    return VV_OK;
}

vv_status
vv_scene_load(vv_world **out, const char *path) {
    return vv_scene_load_progress(out, path, NULL);
}

vv_status
vv_scene_load_progress(vv_world **out, const char *path, const vv_progress *progress) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "scene: NULL output");
    *out = NULL;
    if (!path)
        return vv_error_set(VV_ERR_INVALID, "scene: NULL path");
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status st = vv_read_file(path, SCENE_MAX_BYTES, &data, &size);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene");
    sctx c = {path, (const char *)data, (size_t)size, progress};
    json_error_t jerr;
    json_t *root = json_loadb((const char *)data, (size_t)size,
                              JSON_REJECT_DUPLICATES | JSON_DECODE_INT_AS_REAL, &jerr);
    if (!root) {
        st = vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s", path, jerr.line > 0 ? jerr.line : 1,
                          jerr.column > 0 ? jerr.column : 1, jerr.text);
        free(data);
        return st;
    }
    vv_world *w = NULL;
    st = vv_world_new(&w);
    if (st == VV_OK)
        st = parse_scene(&c, root, w);
    json_decref(root);
    free(data);
    if (st != VV_OK) {
        vv_world_free(w);
        return st;
    }
    *out = w;
    return VV_OK;
}

/* ---- writing ------------------------------------------------------------- */

static void
put_num(FILE *f, double v) {
    char buf[64];
    if (!isfinite(v))
        v = 0.0; /* never produced by a valid World; keep the file parseable */
    snprintf(buf, sizeof buf, "%.15g", v);
    if (strtod(buf, NULL) != v)
        snprintf(buf, sizeof buf, "%.17g", v);
    fputs(buf, f);
}

/* An angle in degrees, written with as few digits as read back to the same radians. */
static void
put_degrees(FILE *f, double rad) {
    double deg = vv_rad_to_deg(rad);
    for (int prec = 6; prec <= 17; prec++) {
        char buf[64];
        snprintf(buf, sizeof buf, "%.*g", prec, deg);
        if (vv_deg_to_rad(strtod(buf, NULL)) == rad || prec == 17) {
            fputs(buf, f);
            return;
        }
    }
}

static void
put_vec3(FILE *f, vv_vec3 v) {
    fputc('[', f);
    put_num(f, v.x);
    fputs(", ", f);
    put_num(f, v.y);
    fputs(", ", f);
    put_num(f, v.z);
    fputc(']', f);
}

static void
put_str(FILE *f, const char *s) {
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

static void
put_cut_planes(FILE *f, const vv_cut_plane *p, int n, const char *indent) {
    fputc('[', f);
    for (int i = 0; i < n; i++) {
        fprintf(f, "%s\n%s  {\"point\": ", i ? "," : "", indent);
        put_vec3(f, p[i].point);
        fputs(", \"normal\": ", f);
        put_vec3(f, p[i].normal);
        fputc('}', f);
    }
    if (n)
        fprintf(f, "\n%s", indent);
    fputc(']', f);
}

static void
put_material_global(FILE *f, const vv_material *m) {
    fputs(", \"reflectance\": ", f);
    put_num(f, m->reflectance);
    fputs(", \"transparency\": ", f);
    put_num(f, m->transparency);
    fputs(", \"ior\": ", f);
    put_num(f, m->ior);
    if (m->emission.x != 0 || m->emission.y != 0 || m->emission.z != 0) {
        fputs(", \"emission\": ", f);
        put_vec3(f, m->emission);
    }
}

static void
put_effect_flags(FILE *f, const vv_object *o) {
    fprintf(f,
            ",\n      \"casts_shadows\": %s, \"receives_shadows\": %s,"
            "\n      \"visible_in_reflections\": %s, \"reflects\": %s",
            o->casts_shadows ? "true" : "false", o->receives_shadows ? "true" : "false",
            o->visible_in_reflections ? "true" : "false", o->reflects ? "true" : "false");
}

static void
put_pair(FILE *f, const double p[2]) {
    fputc('[', f);
    put_num(f, p[0]);
    fputs(", ", f);
    put_num(f, p[1]);
    fputc(']', f);
}

static void
put_tf2d(FILE *f, const vv_tf2d *tf) {
    fputs(",\n      \"tf2d\": {\n        \"widgets\": [", f);
    for (int i = 0; i < tf->n_widgets; i++) {
        const vv_tf2d_widget *w = &tf->widgets[i];
        fputs(i ? ",\n          {" : "\n          {", f);
        if (w->shape == VV_TF2D_TRIANGLE) {
            fputs("\"shape\": \"triangle\", \"center\": ", f);
            put_num(f, w->center);
            fputs(", \"width\": ", f);
            put_num(f, w->width);
        } else {
            fputs("\"shape\": \"rectangle\", \"value\": ", f);
            put_pair(f, w->value);
            fputs(", \"ramp\": ", f);
            put_num(f, w->ramp);
            fputs(", \"gradient_ramp\": ", f);
            put_num(f, w->gradient_ramp);
        }
        fputs(", \"gradient\": ", f);
        put_pair(f, w->gradient);
        fputs(", \"color\": ", f);
        put_vec3(f, w->color);
        fputs(", \"opacity\": ", f);
        put_num(f, w->opacity);
        fputc('}', f);
    }
    fputs(tf->n_widgets ? "\n        ],\n" : "],\n", f);
    fputs("        \"opacity_unit_distance\": ", f);
    put_num(f, tf->opacity_unit_distance);
    fputs("\n      }", f);
}

static void
put_textures(FILE *f, const vv_object *o) {
    const vv_texture_map *m = &o->texture;
    if (m->image) {
        fputs(",\n      \"texture\": {\"image\": ", f);
        put_str(f, m->image->source ? m->image->source : "");
        fprintf(
            f, ", \"projection\": \"%s\", \"center\": ", vv_texture_projection_name(m->projection));
        put_vec3(f, m->center);
        fputs(", \"axis\": ", f);
        put_vec3(f, m->axis);
        fputs(", \"scale\": ", f);
        put_pair(f, m->scale);
        fputc('}', f);
    }
    const vv_solid_texture *s = &o->solid_texture;
    if (s->kind == VV_SOLID_TEXTURE_NONE)
        return;
    fputs(",\n      \"solid_texture\": {", f);
    if (s->kind == VV_SOLID_TEXTURE_VOLUME) {
        fputs("\"volume\": ", f);
        put_str(f, s->source ? s->source : "");
    } else {
        fprintf(f, "\"procedural\": \"%s\"", vv_solid_texture_kind_name(s->kind));
    }
    fputs(", \"period\": ", f);
    put_num(f, s->period);
    fputs(", \"center\": ", f);
    put_vec3(f, s->center);
    fputs(", \"axis\": ", f);
    put_vec3(f, s->axis);
    fputs(", \"turbulence\": ", f);
    put_num(f, s->turbulence);
    fprintf(f, ", \"seed\": %u, \"color0\": ", s->seed);
    put_vec3(f, s->color0);
    fputs(", \"color1\": ", f);
    put_vec3(f, s->color1);
    fputc('}', f);
}

/* A geometric object; @p file names a mesh's file (else geometry.source). */
static void
put_geometry_object(FILE *f, const vv_object *o, const char *file) {
    const vv_geometry *g = &o->geometry;
    fputs("    {\n      \"name\": ", f);
    put_str(f, o->name);
    fprintf(f, ",\n      \"type\": \"%s\"", vv_object_type_name(o->type));
    switch (o->type) {
    case VV_OBJECT_PLANE:
        fputs(",\n      \"point\": ", f);
        put_vec3(f, g->point);
        fputs(", \"normal\": ", f);
        put_vec3(f, g->normal);
        break;
    case VV_OBJECT_POLYGON:
        fputs(",\n      \"vertices\": [", f);
        for (int i = 0; i < g->n_vertices; i++) {
            fputs(i ? ", " : "", f);
            put_vec3(f, g->vertices[i]);
        }
        fputc(']', f);
        break;
    case VV_OBJECT_SPHERE:
        fputs(",\n      \"center\": ", f);
        put_vec3(f, g->center);
        fputs(", \"radius\": ", f);
        put_num(f, g->radius);
        break;
    case VV_OBJECT_BOX:
        fputs(",\n      \"min\": ", f);
        put_vec3(f, g->box.min);
        fputs(", \"max\": ", f);
        put_vec3(f, g->box.max);
        break;
    case VV_OBJECT_CYLINDER:
        fputs(",\n      \"base\": ", f);
        put_vec3(f, g->base);
        fputs(", \"top\": ", f);
        put_vec3(f, g->top);
        fputs(", \"radius\": ", f);
        put_num(f, g->radius);
        fprintf(f, ", \"capped\": %s", g->capped ? "true" : "false");
        break;
    case VV_OBJECT_MESH:
        fputs(",\n      \"file\": ", f);
        put_str(f, file && file[0] ? file : g->source ? g->source : "");
        break;
    default:
        break;
    }
    fputs(",\n      \"position\": ", f);
    put_vec3(f, o->position);
    vv_quat q = vv_quat_normalize(o->orientation);
    fputs(",\n      \"orientation\": [", f);
    put_num(f, q.w);
    fputs(", ", f);
    put_num(f, q.x);
    fputs(", ", f);
    put_num(f, q.y);
    fputs(", ", f);
    put_num(f, q.z);
    fputs("],\n      \"scale\": ", f);
    put_vec3(f, o->scale);
    fprintf(f, ",\n      \"visible\": %s", o->visible ? "true" : "false");
    fputs(",\n      \"material\": {\"ambient\": ", f);
    put_num(f, o->material.ambient);
    fputs(", \"diffuse\": ", f);
    put_num(f, o->material.diffuse);
    fputs(", \"specular\": ", f);
    put_num(f, o->material.specular);
    fputs(", \"shininess\": ", f);
    put_num(f, o->material.shininess);
    fputs(", \"color\": ", f);
    put_vec3(f, o->material.color);
    put_material_global(f, &o->material);
    fputc('}', f);
    put_textures(f, o);
    put_effect_flags(f, o);
    fputs("\n    }", f);
}

static void
put_object(FILE *f, const vv_object *o, const char *file) {
    if (o->type != VV_OBJECT_VOLUME && o->type != VV_OBJECT_GRID) {
        put_geometry_object(f, o, file);
        return;
    }
    fputs("    {\n      \"name\": ", f);
    put_str(f, o->name);
    if (o->type == VV_OBJECT_GRID) {
        fputs(",\n      \"type\": \"grid\",\n      \"file\": ", f);
        put_str(f, file && file[0] ? file : o->geometry.source ? o->geometry.source : "");
        if (o->field[0]) {
            fputs(",\n      \"field\": ", f);
            put_str(f, o->field);
        }
        fprintf(f, ",\n      \"component\": %d,\n      \"time\": %d", o->component, o->time);
    } else {
        const vv_volume *v = o->volume;
        fputs(",\n      \"type\": \"volume\",\n      \"file\": ", f);
        put_str(f, file && file[0] ? file : o->geometry.source ? o->geometry.source : "");
        fputs(",\n      \"origin\": ", f);
        put_vec3(f, vv_vec3_make(v->origin[0], v->origin[1], v->origin[2]));
        fputs(",\n      \"spacing\": ", f);
        put_vec3(f, vv_vec3_make(v->spacing[0], v->spacing[1], v->spacing[2]));
        if (o->geometry.filters) {
            fputs(",\n      \"filters\": ", f);
            put_str(f, o->geometry.filters);
        }
    }
    fputs(",\n      \"position\": ", f);
    put_vec3(f, o->position);
    vv_quat q = vv_quat_normalize(o->orientation);
    fputs(",\n      \"orientation\": [", f);
    put_num(f, q.w);
    fputs(", ", f);
    put_num(f, q.x);
    fputs(", ", f);
    put_num(f, q.y);
    fputs(", ", f);
    put_num(f, q.z);
    fputs("],\n      \"scale\": ", f);
    put_vec3(f, o->scale);
    int mode = (int)o->mode;
    fprintf(f, ",\n      \"mode\": \"%s\"", mode_names[mode >= 0 && mode < 5 ? mode : 0]);
    fputs(",\n      \"isovalue\": ", f);
    put_num(f, o->isovalue);
    fputs(",\n      \"step\": ", f);
    put_num(f, o->step);
    fprintf(f, ",\n      \"shading\": %s,\n      \"visible\": %s", o->shading ? "true" : "false",
            o->visible ? "true" : "false");
    if (o->segmentation == VV_SEG_THRESHOLD) {
        fputs(",\n      \"segmentation\": {\"threshold\": ", f);
        put_num(f, o->threshold);
        fputc('}', f);
    } else {
        fputs(",\n      \"transfer_function\": {\n        \"opacity\": [", f);
        for (int i = 0; i < o->tf.n_opacity; i++) {
            fputs(i ? ", [" : "[", f);
            put_num(f, o->tf.opacity[i].value);
            fputs(", ", f);
            put_num(f, o->tf.opacity[i].opacity);
            fputc(']', f);
        }
        fputs("],\n        \"color\": [", f);
        for (int i = 0; i < o->tf.n_color; i++) {
            fputs(i ? ", [" : "[", f);
            put_num(f, o->tf.color[i].value);
            fputs(", ", f);
            put_vec3(f, o->tf.color[i].color);
            fputc(']', f);
        }
        fputs("],\n        \"opacity_unit_distance\": ", f);
        put_num(f, o->tf.opacity_unit_distance);
        fputs("\n      }", f);
        if (o->segmentation == VV_SEG_TRANSFER_FUNCTION_2D)
            fputs(",\n      \"segmentation\": \"tf2d\"", f);
        if (o->segmentation == VV_SEG_LABELS)
            fputs(",\n      \"segmentation\": \"labels\"", f);
    }
    if (o->segmentation == VV_SEG_TRANSFER_FUNCTION_2D || o->tf2d.n_widgets > 0)
        put_tf2d(f, &o->tf2d);
    fputs(",\n      \"material\": {\"ambient\": ", f);
    put_num(f, o->material.ambient);
    fputs(", \"diffuse\": ", f);
    put_num(f, o->material.diffuse);
    fputs(", \"specular\": ", f);
    put_num(f, o->material.specular);
    fputs(", \"shininess\": ", f);
    put_num(f, o->material.shininess);
    fputs(", \"color\": ", f);
    put_vec3(f, o->material.color);
    put_material_global(f, &o->material);
    fputc('}', f);
    put_textures(f, o);
    fputs(",\n      \"cut_planes\": ", f);
    put_cut_planes(f, o->cut_planes, o->n_cut_planes, "      ");
    put_effect_flags(f, o);
    fputs("\n    }", f);
}

static int
render_settings_any(const vv_render_settings *rs) {
    return rs->renderer[0] || rs->quality >= 0 || rs->n_options > 0;
}

static void
put_render(FILE *f, const vv_render_settings *rs) {
    const char *sep = "";
    fputs(",\n  \"render\": {", f);
    if (rs->renderer[0]) {
        fputs("\"renderer\": ", f);
        put_str(f, rs->renderer);
        sep = ", ";
    }
    if (rs->quality >= 0) {
        fprintf(f, "%s\"quality\": %d", sep, rs->quality);
        sep = ", ";
    }
    if (rs->n_options > 0) {
        fprintf(f, "%s\"options\": {", sep);
        for (int i = 0; i < rs->n_options; i++) {
            fputs(i ? ",\n    " : "\n    ", f);
            put_str(f, rs->option_keys[i]);
            fputs(": ", f);
            put_str(f, rs->option_values[i]);
        }
        fputs("\n  }", f);
    }
    fputc('}', f);
}

/* The render settings must read back as they are: terminated strings,
 * distinct non-empty keys, a quality the loader accepts. */
static vv_status
check_render_settings(const vv_render_settings *rs) {
    if (!memchr(rs->renderer, '\0', sizeof rs->renderer))
        return vv_error_set(VV_ERR_INVALID, "render settings: renderer name not terminated");
    if (rs->quality < -1 || rs->quality > 2)
        return vv_error_set(VV_ERR_INVALID, "render settings: quality %d outside -1..2",
                            rs->quality);
    if (rs->n_options < 0 || rs->n_options > VV_MAX_RENDER_OPTIONS)
        return vv_error_set(VV_ERR_INVALID, "render settings: %d options outside 0..%d",
                            rs->n_options, VV_MAX_RENDER_OPTIONS);
    for (int i = 0; i < rs->n_options; i++) {
        if (!memchr(rs->option_keys[i], '\0', sizeof rs->option_keys[i]) ||
            !memchr(rs->option_values[i], '\0', sizeof rs->option_values[i]))
            return vv_error_set(VV_ERR_INVALID, "render settings: option %d not terminated", i);
        if (!rs->option_keys[i][0])
            return vv_error_set(VV_ERR_INVALID, "render settings: option %d has an empty key", i);
        for (int j = 0; j < i; j++)
            if (strcmp(rs->option_keys[i], rs->option_keys[j]) == 0)
                return vv_error_set(VV_ERR_INVALID, "render settings: option %s given twice",
                                    rs->option_keys[i]);
    }
    return VV_OK;
}

static vv_status
check_saveable(const vv_world *w, const char *const *volume_files) {
    const vv_view *v = &w->view;
    vv_status st = check_render_settings(&w->render);
    if (st != VV_OK)
        return st;
    if (v->width < 1 || v->width > IMAGE_MAX_SIDE || v->height < 1 || v->height > IMAGE_MAX_SIDE)
        return vv_error_set(VV_ERR_INVALID, "view size %dx%d outside 1..%d", v->width, v->height,
                            IMAGE_MAX_SIDE);
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o)
            return vv_error_set(VV_ERR_INVALID, "object %d is NULL", i);
        if (o->type == VV_OBJECT_MESH && !o->geometry.source && !(volume_files && volume_files[i]))
            return vv_error_set(VV_ERR_INVALID, "object %d: a mesh without a file name", i);
        if (o->texture.image && !o->texture.image->source)
            return vv_error_set(VV_ERR_INVALID, "object %d: a texture image without a file name",
                                i);
        if (o->solid_texture.kind == VV_SOLID_TEXTURE_VOLUME && !o->solid_texture.source)
            return vv_error_set(VV_ERR_INVALID,
                                "object %d: a solid-texture volume without a file name", i);
    }
    for (int i = 0; i < w->n_objects; i++) {
        if (w->objects[i]->type != VV_OBJECT_VOLUME)
            continue;
        if (!w->objects[i]->volume)
            return vv_error_set(VV_ERR_INVALID, "object %d has no volume", i);
        const char *file =
            volume_files && volume_files[i] ? volume_files[i] : w->objects[i]->geometry.source;
        if (!file || !file[0])
            return vv_error_set(VV_ERR_INVALID, "object %d: no volume file name", i);
    }
    return VV_OK;
}

vv_status
vv_scene_save(const vv_world *w, const char *path, const char *const *volume_files) {
    if (!w || !path)
        return vv_error_set(VV_ERR_INVALID, "scene: NULL %s", w ? "path" : "world");
    vv_status st = check_saveable(w, volume_files);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene: %s", path);
    vv_atomic_file af;
    st = vv_atomic_file_open(&af, path);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene");
    FILE *f = af.fp;
    const vv_view *v = &w->view;
    fputs("{\n  \"view\": {\n    \"eye\": ", f);
    put_vec3(f, v->eye);
    fputs(",\n    \"at\": ", f);
    put_vec3(f, v->at);
    fputs(",\n    \"up\": ", f);
    put_vec3(f, v->up);
    fputs(",\n    \"fov\": ", f);
    put_degrees(f, v->fov);
    fprintf(f, ",\n    \"projection\": \"%s\"",
            v->projection == VV_PROJECTION_ORTHOGRAPHIC ? "orthographic" : "perspective");
    fputs(",\n    \"ortho_height\": ", f);
    put_num(f, v->ortho_height);
    fprintf(f, ",\n    \"width\": %d,\n    \"height\": %d", v->width, v->height);
    fputs(",\n    \"background\": ", f);
    put_vec3(f, w->background);
    fputs("\n  },\n  \"lights\": [", f);
    for (int i = 0; i < w->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        fprintf(f, "%s\n    {\"type\": \"%s\"", i ? "," : "",
                l->type == VV_LIGHT_POINT ? "point" : "directional");
        if (l->type == VV_LIGHT_POINT) {
            fputs(", \"position\": ", f);
            put_vec3(f, l->position);
        } else if (!l->headlight) {
            fputs(", \"direction\": ", f);
            put_vec3(f, l->direction);
        }
        fputs(", \"color\": ", f);
        put_vec3(f, l->color);
        fputs(", \"intensity\": ", f);
        put_num(f, l->intensity);
        fputc('}', f);
    }
    fputs(w->n_lights ? "\n  ],\n" : "],\n", f);
    fputs("  \"shading\": {\"ambient\": ", f);
    put_vec3(f, w->ambient);
    fputc('}', f);
    if (render_settings_any(&w->render))
        put_render(f, &w->render);
    fputs(",\n  \"cut_planes\": ", f);
    put_cut_planes(f, w->cut_planes, w->n_cut_planes, "  ");
    fputs(",\n  \"objects\": [", f);
    for (int i = 0; i < w->n_objects; i++) {
        fputs(i ? ",\n" : "\n", f);
        put_object(f, w->objects[i], volume_files ? volume_files[i] : NULL);
    }
    fputs(w->n_objects ? "\n  ]\n}\n" : "]\n}\n", f);
    if (ferror(f)) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "scene: %s: write failed", path);
    }
    st = vv_atomic_file_commit(&af);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene");
    return VV_OK;
}
