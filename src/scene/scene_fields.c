/*
 * Scene files, the pieces every section reads with: errors placed at their
 * line and column (vv_json_locate, src/core/json_text.c), the closest key
 * suggested for an unknown one, and typed fields with their ranges.
 */
#include <float.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "scene/scene_internal.h"
#include "volvis/io.h"
#include "volvis/model.h"
#include "volvis/modeling.h"

/* Line and column of @p path in the scene text (its nearest ancestor's when
 * the path itself cannot be found). */
void
vv_scene_locate(const sctx *c, const char *path, int *line, int *col) {
    vv_json_locate(c->text, c->len, path, line, col);
}

vv_vec3
vv_scene_unit(vv_vec3 v) {
    double n2 = vv_vec3_dot(v, v);
    if (fabs(n2 - 1.0) <= 8 * DBL_EPSILON)
        return v;
    return vv_vec3_normalize(v);
}

/* ---- error reporting ---------------------------------------------------- */

vv_status
vv_scene_serr(const sctx *c, const char *path, const char *fmt, ...) {
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    int line, col;
    vv_scene_locate(c, path, &line, &col);
    if (path && path[0])
        return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s: %s", c->path, line, col, path, msg);
    return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s", c->path, line, col, msg);
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

void
vv_scene_path_key(char *dst, const char *parent, const char *key) {
    if (parent && parent[0])
        path_cat(dst, parent, ".", key);
    else
        path_cat(dst, "", "", key);
}

void
vv_scene_path_index(char *dst, const char *parent, size_t i) {
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
vv_status
vv_scene_check_keys(const sctx *c, json_t *obj, const char *path, const char *const *allowed) {
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
        vv_scene_path_key(kp, path, key);
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
            return vv_scene_serr(c, kp, "unknown key (did you mean %s?)", best);
        char list[512];
        size_t off = 0;
        list[0] = '\0';
        for (int i = 0; allowed[i] && off < sizeof list; i++)
            off +=
                (size_t)snprintf(list + off, sizeof list - off, "%s%s", i ? ", " : "", allowed[i]);
        return vv_scene_serr(c, kp, "unknown key; expected one of: %s", list);
    }
    return VV_OK;
}

/* ---- typed fields -------------------------------------------------------- */

vv_status
vv_scene_value_number(const sctx *c, json_t *v, const char *path, double *out) {
    if (!json_is_number(v))
        return vv_scene_serr(c, path, "expected a number, got %s", vv_json_kind(v));
    double d = json_number_value(v);
    if (!isfinite(d))
        return vv_scene_serr(c, path, "number is not finite");
    *out = d;
    return VV_OK;
}

vv_status
vv_scene_value_vec3(const sctx *c, json_t *v, const char *path, vv_vec3 *out) {
    if (!json_is_array(v) || json_array_size(v) != 3)
        return vv_scene_serr(c, path, "expected an array of 3 numbers, got %s%s", vv_json_kind(v),
                             json_is_array(v) ? " of another length" : "");
    double d[3];
    for (size_t i = 0; i < 3; i++) {
        json_t *e = json_array_get(v, i);
        if (!json_is_number(e)) {
            char ep[PATH_MAX_LEN];
            vv_scene_path_index(ep, path, i);
            return vv_scene_serr(c, ep, "expected a number, got %s", vv_json_kind(e));
        }
        d[i] = json_number_value(e);
    }
    *out = vv_vec3_make(d[0], d[1], d[2]);
    return VV_OK;
}

vv_status
vv_scene_value_color(const sctx *c, json_t *v, const char *path, vv_vec3 *out) {
    vv_status st = vv_scene_value_vec3(c, v, path, out);
    if (st != VV_OK)
        return st;
    double d[3] = {out->x, out->y, out->z};
    for (int i = 0; i < 3; i++)
        if (!(d[i] >= 0.0 && d[i] <= 1.0))
            return vv_scene_serr(c, path, "colour component %g is outside [0, 1]", d[i]);
    return VV_OK;
}

/* Field getters: *present (may be NULL) says whether the key was there; a
 * missing key leaves *out unchanged and is not an error. */
json_t *
vv_scene_field(json_t *obj, const char *key, char *kp, const char *path, int *present) {
    json_t *v = json_object_get(obj, key);
    vv_scene_path_key(kp, path, key);
    if (present)
        *present = v != NULL;
    return v;
}

vv_status
vv_scene_get_number(const sctx *c, json_t *obj, const char *path, const char *key, double *out,
                    int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, present);
    return v ? vv_scene_value_number(c, v, kp, out) : VV_OK;
}

/* A number in a range; open ends when lo_open / hi_open. */
vv_status
vv_scene_get_number_in(const sctx *c, json_t *obj, const char *path, const char *key, double *out,
                       int *present, double lo, int lo_open, double hi, int hi_open) {
    char kp[PATH_MAX_LEN];
    int here;
    json_t *v = vv_scene_field(obj, key, kp, path, &here);
    if (present)
        *present = here;
    if (!v)
        return VV_OK;
    double d = 0.0;
    vv_status st = vv_scene_value_number(c, v, kp, &d);
    if (st != VV_OK)
        return st;
    int ok = (lo_open ? d > lo : d >= lo) && (hi_open ? d < hi : d <= hi);
    if (!ok) {
        char hs[64];
        if (isinf(hi))
            snprintf(hs, sizeof hs, "inf");
        else
            snprintf(hs, sizeof hs, "%g", hi);
        return vv_scene_serr(c, kp, "%g is outside %c%g, %s%c", d, lo_open ? '(' : '[', lo, hs,
                             hi_open ? ')' : ']');
    }
    *out = d;
    return VV_OK;
}

vv_status
vv_scene_get_int_in(const sctx *c, json_t *obj, const char *path, const char *key, int *out, int lo,
                    int hi) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, NULL);
    if (!v)
        return VV_OK;
    double d = 0.0;
    vv_status st = vv_scene_value_number(c, v, kp, &d);
    if (st != VV_OK)
        return st;
    if (d != floor(d))
        return vv_scene_serr(c, kp, "expected an integer, got %g", d);
    if (d < lo || d > hi)
        return vv_scene_serr(c, kp, "%g is outside %d..%d", d, lo, hi);
    *out = (int)d;
    return VV_OK;
}

vv_status
vv_scene_get_vec3(const sctx *c, json_t *obj, const char *path, const char *key, vv_vec3 *out,
                  int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, present);
    return v ? vv_scene_value_vec3(c, v, kp, out) : VV_OK;
}

vv_status
vv_scene_get_nonzero_vec3(const sctx *c, json_t *obj, const char *path, const char *key,
                          vv_vec3 *out, int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, present);
    if (!v)
        return VV_OK;
    vv_status st = vv_scene_value_vec3(c, v, kp, out);
    if (st != VV_OK)
        return st;
    if (!(vv_vec3_length(*out) > 0.0))
        return vv_scene_serr(c, kp, "must not be the zero vector");
    return VV_OK;
}

vv_status
vv_scene_get_color(const sctx *c, json_t *obj, const char *path, const char *key, vv_vec3 *out,
                   int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, present);
    return v ? vv_scene_value_color(c, v, kp, out) : VV_OK;
}

vv_status
vv_scene_get_bool(const sctx *c, json_t *obj, const char *path, const char *key, int *out) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, NULL);
    if (!v)
        return VV_OK;
    if (!json_is_boolean(v))
        return vv_scene_serr(c, kp, "expected true or false, got %s", vv_json_kind(v));
    *out = json_is_true(v) ? 1 : 0;
    return VV_OK;
}

vv_status
vv_scene_get_string(const sctx *c, json_t *obj, const char *path, const char *key,
                    const char **out) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, NULL);
    if (!v)
        return VV_OK;
    if (!json_is_string(v))
        return vv_scene_serr(c, kp, "expected a string, got %s", vv_json_kind(v));
    *out = json_string_value(v);
    return VV_OK;
}

/* An optional object or array (@p want, named @p what in the error); *out is
 * NULL when absent. */
static vv_status
get_container(const sctx *c, json_t *obj, const char *path, const char *key, json_type want,
              const char *what, json_t **out) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, NULL);
    *out = NULL;
    if (!v)
        return VV_OK;
    if (json_typeof(v) != want)
        return vv_scene_serr(c, kp, "expected %s, got %s", what, vv_json_kind(v));
    *out = v;
    return VV_OK;
}

vv_status
vv_scene_get_object(const sctx *c, json_t *obj, const char *path, const char *key, json_t **out) {
    return get_container(c, obj, path, key, JSON_OBJECT, "an object", out);
}

vv_status
vv_scene_get_array(const sctx *c, json_t *obj, const char *path, const char *key, json_t **out) {
    return get_container(c, obj, path, key, JSON_ARRAY, "an array", out);
}

vv_status
vv_scene_missing(const sctx *c, const char *path, const char *key, const char *what) {
    return vv_scene_serr(c, path, "missing required key \"%s\" (%s)", key, what);
}
