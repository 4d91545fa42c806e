/*
 * Animation files: JSON read and written with Jansson (schema in
 * docs/animation-format.md). Schema errors are placed at the line and column
 * of the offending key with the scene loader's locator
 * (vv_json_locate), so every message reads
 * "FILE:LINE:COL: tracks[0].keys[2].time: ...".
 */
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "manipulate/anim_internal.h"
#include "volvis/animate.h"

#define ANIM_MAX_BYTES (16u << 20)
#define JP_MAX 256

typedef struct actx {
    const char *path;
    const char *text;
    size_t len;
} actx;

static void jpf(char *dst, const char *fmt, ...) VV_PRINTF(2, 3);

/* A JSON path into a JP_MAX buffer (a truncated path only makes an error
 * position less precise). */
static void
jpf(char *dst, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(dst, JP_MAX, fmt, ap);
    va_end(ap);
}

static vv_status aerr(const actx *c, const char *jpath, const char *fmt, ...) VV_PRINTF(3, 4);

static vv_status
aerr(const actx *c, const char *jpath, const char *fmt, ...) {
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    int line = 1, col = 1;
    vv_json_locate(c->text, c->len, jpath, &line, &col);
    if (jpath && jpath[0])
        return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s: %s", c->path, line, col, jpath, msg);
    return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s", c->path, line, col, msg);
}

static vv_status
check_keys(const actx *c, json_t *obj, const char *jpath, const char *const *allowed) {
    const char *key;
    json_t *val;
    json_object_foreach(obj, key, val) {
        int ok = 0;
        for (int i = 0; allowed[i]; i++)
            ok |= strcmp(key, allowed[i]) == 0;
        if (ok)
            continue;
        char kp[JP_MAX], list[512] = "";
        jpf(kp, "%s%s%s", jpath, jpath[0] ? "." : "", key);
        size_t off = 0;
        for (int i = 0; allowed[i] && off < sizeof list; i++)
            off +=
                (size_t)snprintf(list + off, sizeof list - off, "%s%s", i ? ", " : "", allowed[i]);
        return aerr(c, kp, "unknown key; expected one of: %s", list);
    }
    return VV_OK;
}

static vv_status
get_num(const actx *c, json_t *v, const char *jp, double *out) {
    if (!json_is_number(v))
        return aerr(c, jp, "expected a number, got %s", vv_json_kind(v));
    double d = json_number_value(v);
    if (!isfinite(d))
        return aerr(c, jp, "number is not finite");
    *out = d;
    return VV_OK;
}

static vv_status
get_vec(const actx *c, json_t *v, const char *jp, int n, double *out) {
    if (!json_is_array(v) || json_array_size(v) != (size_t)n)
        return aerr(c, jp, "expected an array of %d numbers, got %s%s", n, vv_json_kind(v),
                    json_is_array(v) ? " of another length" : "");
    for (int i = 0; i < n; i++) {
        char ep[JP_MAX];
        jpf(ep, "%s[%d]", jp, i);
        vv_status s = get_num(c, json_array_get(v, (size_t)i), ep, &out[i]);
        if (s != VV_OK)
            return s;
    }
    return VV_OK;
}

static vv_status
get_vec3(const actx *c, json_t *v, const char *jp, vv_vec3 *out) {
    double d[3];
    vv_status s = get_vec(c, v, jp, 3, d);
    if (s == VV_OK)
        *out = vv_vec3_make(d[0], d[1], d[2]);
    return s;
}

/* Optional number field @p key of @p obj. */
static vv_status
opt_num(const actx *c, json_t *obj, const char *jp, const char *key, double *out) {
    json_t *v = json_object_get(obj, key);
    if (!v)
        return VV_OK;
    char kp[JP_MAX];
    jpf(kp, "%s.%s", jp, key);
    return get_num(c, v, kp, out);
}

static vv_status
opt_vec3(const actx *c, json_t *obj, const char *jp, const char *key, vv_vec3 *out, int required) {
    json_t *v = json_object_get(obj, key);
    char kp[JP_MAX];
    jpf(kp, "%s.%s", jp, key);
    if (!v)
        return required ? aerr(c, jp, "missing key '%s' ([x, y, z])", key) : VV_OK;
    return get_vec3(c, v, kp, out);
}

static vv_status
parse_tf(const actx *c, json_t *v, const char *jp, vv_tf *tf) {
    static const char *const keys[] = {"opacity", "color", "opacity_unit_distance", NULL};
    if (!json_is_object(v))
        return aerr(c, jp,
                    "expected a transfer function {\"opacity\": [[value, opacity], ...], "
                    "\"color\": [[value, [r, g, b]], ...]}, got %s",
                    vv_json_kind(v));
    vv_status s = check_keys(c, v, jp, keys);
    if (s != VV_OK)
        return s;
    vv_tf_init(tf);
    for (int pass = 0; pass < 2; pass++) {
        const char *key = pass == 0 ? "opacity" : "color";
        json_t *arr = json_object_get(v, key);
        char ap[JP_MAX];
        jpf(ap, "%s.%s", jp, key);
        if (!arr) {
            if (pass == 0)
                return aerr(c, jp, "missing key 'opacity' ([[value, opacity], ...])");
            continue;
        }
        if (!json_is_array(arr))
            return aerr(c, ap, "expected an array, got %s", vv_json_kind(arr));
        if (json_array_size(arr) > VV_TF_MAX_POINTS)
            return aerr(c, ap, "more than %d points", VV_TF_MAX_POINTS);
        size_t i;
        json_t *e;
        json_array_foreach(arr, i, e) {
            char ep[JP_MAX], vp[JP_MAX], op[JP_MAX];
            jpf(ep, "%s[%zu]", ap, i);
            jpf(vp, "%s[0]", ep);
            jpf(op, "%s[1]", ep);
            if (!json_is_array(e) || json_array_size(e) != 2)
                return aerr(c, ep, "expected a pair [value, %s]",
                            pass == 0 ? "opacity" : "[r, g, b]");
            double value = 0;
            if ((s = get_num(c, json_array_get(e, 0), vp, &value)) != VV_OK)
                return s;
            if (pass == 0) {
                double a = 0;
                if ((s = get_num(c, json_array_get(e, 1), op, &a)) != VV_OK)
                    return s;
                if (!(a >= 0 && a <= 1))
                    return aerr(c, op, "opacity %g is outside [0, 1]", a);
                if (vv_tf_add_opacity(tf, value, a) != VV_OK)
                    return aerr(c, ep, "%s", vv_error_message());
            } else {
                vv_vec3 col;
                if ((s = get_vec3(c, json_array_get(e, 1), op, &col)) != VV_OK)
                    return s;
                if (vv_tf_add_color(tf, value, col) != VV_OK)
                    return aerr(c, ep, "colour outside [0, 1]");
            }
        }
    }
    double u = 1;
    if ((s = opt_num(c, v, jp, "opacity_unit_distance", &u)) != VV_OK)
        return s;
    if (!(u > 0))
        return aerr(c, jp, "opacity_unit_distance %g must be > 0", u);
    tf->opacity_unit_distance = u;
    return VV_OK;
}

static vv_status
parse_value(const actx *c, const vv_anim_track *t, json_t *v, const char *jp, vv_anim_key *k,
            vv_tf *tf) {
    vv_status s;
    switch (t->kind) {
    case VV_ANIM_SCALAR:
        if ((s = get_num(c, v, jp, &k->value[0])) != VV_OK)
            return s;
        if (vv_anim_property_is_angle(t))
            k->value[0] = vv_deg_to_rad(k->value[0]);
        return VV_OK;
    case VV_ANIM_VEC3:
        return get_vec(c, v, jp, 3, k->value);
    case VV_ANIM_QUAT:
        if (json_is_object(v)) {
            static const char *const keys[] = {"axis", "angle", NULL};
            if ((s = check_keys(c, v, jp, keys)) != VV_OK)
                return s;
            vv_vec3 axis = vv_vec3_make(0, 0, 1);
            double angle = 0;
            if ((s = opt_vec3(c, v, jp, "axis", &axis, 1)) != VV_OK ||
                (s = opt_num(c, v, jp, "angle", &angle)) != VV_OK)
                return s;
            if (!(vv_vec3_length(axis) > 0))
                return aerr(c, jp, "the rotation axis must be non-zero");
            vv_quat q = vv_quat_from_axis_angle(axis, vv_deg_to_rad(angle));
            k->value[0] = q.w, k->value[1] = q.x, k->value[2] = q.y, k->value[3] = q.z;
            return VV_OK;
        }
        if ((s = get_vec(c, v, jp, 4, k->value)) != VV_OK)
            return s;
        {
            double l = sqrt(k->value[0] * k->value[0] + k->value[1] * k->value[1] +
                            k->value[2] * k->value[2] + k->value[3] * k->value[3]);
            if (!(l > 1e-12))
                return aerr(c, jp, "the zero quaternion is not a rotation");
            for (int i = 0; i < 4; i++)
                k->value[i] /= l;
        }
        return VV_OK;
    case VV_ANIM_TF:
        if ((s = parse_tf(c, v, jp, tf)) != VV_OK)
            return s;
        k->tf = tf;
        return VV_OK;
    }
    return aerr(c, jp, "internal: unknown kind");
}

static const char *const easing_names[] = {"linear", "ease-in", "ease-out", "ease-in-out"};

static vv_status
parse_track(const actx *c, json_t *tj, const char *jp, vv_animation *a) {
    static const char *const keys[] = {"property", "interpolation", "closed", "keys", NULL};
    if (!json_is_object(tj))
        return aerr(c, jp, "expected a track object, got %s", vv_json_kind(tj));
    vv_status s = check_keys(c, tj, jp, keys);
    if (s != VV_OK)
        return s;
    json_t *pj = json_object_get(tj, "property");
    char kp[JP_MAX];
    jpf(kp, "%s.property", jp);
    if (!pj)
        return aerr(c, jp, "missing key 'property' (e.g. \"view.eye\")");
    if (!json_is_string(pj))
        return aerr(c, kp, "expected a string, got %s", vv_json_kind(pj));
    int idx;
    vv_error_clear();
    if ((s = vv_animation_add_track(a, json_string_value(pj), &idx)) != VV_OK) {
        const char *m = vv_error_message();
        if (strncmp(m, "animation: ", 11) == 0)
            m += 11;
        return aerr(c, kp, "%s", m);
    }
    vv_anim_track *t = &a->tracks[idx];
    json_t *ij = json_object_get(tj, "interpolation");
    if (ij) {
        jpf(kp, "%s.interpolation", jp);
        const char *n = json_is_string(ij) ? json_string_value(ij) : "";
        int quat = t->kind == VV_ANIM_QUAT;
        if (strcmp(n, "spline") == 0 || (quat && strcmp(n, "squad") == 0))
            t->interp = VV_INTERP_SPLINE;
        else if (strcmp(n, "linear") == 0 || (quat && strcmp(n, "slerp") == 0))
            t->interp = VV_INTERP_LINEAR;
        else if (strcmp(n, "step") == 0)
            t->interp = VV_INTERP_STEP;
        else
            return aerr(c, kp, "expected \"spline\", \"linear\" or \"step\"%s",
                        quat ? " (or \"squad\", \"slerp\")" : "");
    }
    json_t *cj = json_object_get(tj, "closed");
    if (cj) {
        jpf(kp, "%s.closed", jp);
        if (!json_is_boolean(cj))
            return aerr(c, kp, "expected true or false, got %s", vv_json_kind(cj));
        t->closed = json_is_true(cj);
    }
    json_t *kj = json_object_get(tj, "keys");
    jpf(kp, "%s.keys", jp);
    if (!kj)
        return aerr(c, jp, "missing key 'keys' (track %s)", t->property);
    if (!json_is_array(kj))
        return aerr(c, kp, "expected an array of keys, got %s", vv_json_kind(kj));
    if (json_array_size(kj) == 0)
        return aerr(c, kp, "no keys: track %s needs at least one", t->property);
    size_t i;
    json_t *e;
    vv_tf *tf = malloc(sizeof *tf);
    if (!tf)
        return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
    json_array_foreach(kj, i, e) {
        static const char *const kkeys[] = {"time", "value",  "tension", "continuity",
                                            "bias", "easing", NULL};
        char ep[JP_MAX], xp[JP_MAX];
        jpf(ep, "%s[%zu]", kp, i);
        if (!json_is_object(e)) {
            s = aerr(c, ep, "expected a key {\"time\": ..., \"value\": ...}, got %s",
                     vv_json_kind(e));
            break;
        }
        if ((s = check_keys(c, e, ep, kkeys)) != VV_OK)
            break;
        vv_anim_key k;
        vv_anim_key_init(&k, 0);
        json_t *tv = json_object_get(e, "time"), *vv = json_object_get(e, "value");
        if (!tv || !vv) {
            s = aerr(c, ep, "missing key '%s' (track %s)", tv ? "value" : "time", t->property);
            break;
        }
        jpf(xp, "%s.time", ep);
        if ((s = get_num(c, tv, xp, &k.time)) != VV_OK)
            break;
        if (t->n_keys > 0 && !(k.time > t->keys[t->n_keys - 1].time)) {
            s = aerr(c, xp, "time %g is not after %g: keys out of order (track %s)", k.time,
                     t->keys[t->n_keys - 1].time, t->property);
            break;
        }
        jpf(xp, "%s.value", ep);
        if ((s = parse_value(c, t, vv, xp, &k, tf)) != VV_OK)
            break;
        double *p[3] = {&k.tension, &k.continuity, &k.bias};
        const char *pn[3] = {"tension", "continuity", "bias"};
        for (int q = 0; q < 3 && s == VV_OK; q++) {
            if ((s = opt_num(c, e, ep, pn[q], p[q])) != VV_OK)
                break;
            if (!(*p[q] >= -1 && *p[q] <= 1)) {
                jpf(xp, "%s.%s", ep, pn[q]);
                s = aerr(c, xp, "%g is outside [-1, 1]", *p[q]);
            }
        }
        if (s != VV_OK)
            break;
        json_t *ej = json_object_get(e, "easing");
        if (ej) {
            jpf(xp, "%s.easing", ep);
            int found = -1;
            for (int q = 0; q < 4; q++)
                if (json_is_string(ej) && strcmp(json_string_value(ej), easing_names[q]) == 0)
                    found = q;
            if (found < 0) {
                s = aerr(c, xp,
                         "expected \"linear\", \"ease-in\", \"ease-out\" or "
                         "\"ease-in-out\"");
                break;
            }
            k.easing = (vv_anim_easing)found;
        }
        if ((s = vv_anim_track_add_key(t, &k)) != VV_OK) {
            s = aerr(c, ep, "%s", vv_error_message());
            break;
        }
    }
    free(tf);
    if (s != VV_OK)
        return s;
    int bad;
    if ((s = vv_anim_track_validate(t, &bad)) != VV_OK) {
        char m[512];
        snprintf(m, sizeof m, "%s", vv_error_message());
        char ep[JP_MAX];
        if (bad >= 0)
            jpf(ep, "%s[%d]", kp, bad);
        else
            jpf(ep, "%s", jp);
        return aerr(c, ep, "%s (track %s)", m, t->property);
    }
    return VV_OK;
}

static const char *const seq_names[] = {"orbit", "rotate_object", "fly", "sweep_cut"};

static vv_status
parse_sequence(const actx *c, json_t *sj, const char *jp, vv_animation *a) {
    static const char *const keys[] = {"type",  "degrees", "azimuth",  "elevation",
                                       "zoom",  "object",  "axis",     "offset",
                                       "point", "normal",  "distance", NULL};
    if (!json_is_object(sj))
        return aerr(c, jp, "expected a sequence object, got %s", vv_json_kind(sj));
    vv_status s = check_keys(c, sj, jp, keys);
    if (s != VV_OK)
        return s;
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.zoom = 1;
    json_t *tj = json_object_get(sj, "type");
    int type = -1;
    for (int i = 0; i < 4; i++)
        if (json_is_string(tj) && strcmp(json_string_value(tj), seq_names[i]) == 0)
            type = i;
    if (type < 0)
        return aerr(c, jp, "'type' must be \"orbit\", \"rotate_object\", \"fly\" or \"sweep_cut\"");
    q.type = (vv_anim_sequence_type)type;
    json_t *oj = json_object_get(sj, "object");
    if (oj) {
        if (!json_is_string(oj) || strlen(json_string_value(oj)) >= VV_NAME_MAX)
            return aerr(c, jp, "'object' must be an object name (a string)");
        snprintf(q.object, sizeof q.object, "%s", json_string_value(oj));
    }
    if ((s = opt_num(c, sj, jp, "degrees", &q.degrees)) != VV_OK ||
        (s = opt_num(c, sj, jp, "azimuth", &q.azimuth)) != VV_OK ||
        (s = opt_num(c, sj, jp, "elevation", &q.elevation)) != VV_OK ||
        (s = opt_num(c, sj, jp, "zoom", &q.zoom)) != VV_OK ||
        (s = opt_num(c, sj, jp, "distance", &q.distance)) != VV_OK ||
        (s = opt_vec3(c, sj, jp, "axis", &q.axis, q.type == VV_SEQ_ROTATE_OBJECT)) != VV_OK ||
        (s = opt_vec3(c, sj, jp, "offset", &q.offset, q.type == VV_SEQ_FLY)) != VV_OK ||
        (s = opt_vec3(c, sj, jp, "point", &q.point, q.type == VV_SEQ_SWEEP_CUT)) != VV_OK ||
        (s = opt_vec3(c, sj, jp, "normal", &q.normal, q.type == VV_SEQ_SWEEP_CUT)) != VV_OK)
        return s;
    vv_error_clear();
    if ((s = vv_animation_add_sequence(a, &q)) != VV_OK) {
        const char *m = vv_error_message();
        if (strncmp(m, "animation: ", 11) == 0)
            m += 11;
        return aerr(c, jp, "%s", m);
    }
    return VV_OK;
}

static vv_status
parse_root(const actx *c, json_t *root, vv_animation *a) {
    static const char *const keys[] = {"volvis_animation", "scene",     "fps", "duration",
                                       "tracks",           "sequences", NULL};
    if (!json_is_object(root))
        return aerr(c, "", "expected an object at the top, got %s", vv_json_kind(root));
    vv_status s = check_keys(c, root, "", keys);
    if (s != VV_OK)
        return s;
    json_t *ver = json_object_get(root, "volvis_animation");
    if (ver && (!json_is_integer(ver) || json_integer_value(ver) != 1))
        return aerr(c, "volvis_animation", "unsupported version (this build reads 1)");
    json_t *sc = json_object_get(root, "scene");
    if (sc) {
        if (!json_is_string(sc))
            return aerr(c, "scene", "expected a file name, got %s", vv_json_kind(sc));
        if (!(a->scene = vv_strdup(json_string_value(sc))))
            return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
    }
    json_t *fj = json_object_get(root, "fps");
    if (fj) {
        if ((s = get_num(c, fj, "fps", &a->fps)) != VV_OK)
            return s;
        if (!(a->fps > 0 && a->fps <= 1000))
            return aerr(c, "fps", "%g is outside (0, 1000]", a->fps);
    }
    json_t *tracks = json_object_get(root, "tracks"), *seqs = json_object_get(root, "sequences");
    if (tracks && !json_is_array(tracks))
        return aerr(c, "tracks", "expected an array, got %s", vv_json_kind(tracks));
    if (seqs && !json_is_array(seqs))
        return aerr(c, "sequences", "expected an array, got %s", vv_json_kind(seqs));
    size_t i;
    json_t *e;
    if (tracks)
        json_array_foreach(tracks, i, e) {
            char jp[JP_MAX];
            jpf(jp, "tracks[%zu]", i);
            if ((s = parse_track(c, e, jp, a)) != VV_OK)
                return s;
        }
    if (seqs)
        json_array_foreach(seqs, i, e) {
            char jp[JP_MAX];
            jpf(jp, "sequences[%zu]", i);
            if ((s = parse_sequence(c, e, jp, a)) != VV_OK)
                return s;
        }
    if (a->n_tracks == 0 && a->n_sequences == 0)
        return aerr(c, "", "nothing to animate: no tracks and no sequences");
    json_t *dj = json_object_get(root, "duration");
    if (dj) {
        if ((s = get_num(c, dj, "duration", &a->duration)) != VV_OK)
            return s;
        if (!(a->duration > 0) || a->duration * a->fps > 1e7)
            return aerr(c, "duration", "%g s must be > 0 and under 10^7 frames", a->duration);
    } else {
        double end = 0;
        for (int t = 0; t < a->n_tracks; t++)
            if (a->tracks[t].keys[a->tracks[t].n_keys - 1].time > end)
                end = a->tracks[t].keys[a->tracks[t].n_keys - 1].time;
        if (!(end > 0))
            return aerr(c, "", "missing key 'duration' (seconds): the keys do not give one");
        a->duration = end + 1 / a->fps; /* the last key is the last frame */
    }
    return VV_OK;
}

vv_status
vv_animation_load(vv_animation **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, ANIM_MAX_BYTES, &data, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "animation: %s", path);
    json_error_t je;
    json_t *root = json_loadb((const char *)data, (size_t)size, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        free(data);
        return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s", path, je.line, je.column, je.text);
    }
    actx c = {path, (const char *)data, (size_t)size};
    vv_animation *a;
    if ((s = vv_animation_new(&a)) == VV_OK) {
        if ((s = parse_root(&c, root, a)) != VV_OK) {
            vv_animation_free(a);
            a = NULL;
        }
    }
    json_decref(root);
    free(data);
    *out = a;
    return s;
}

/* ---- saving ------------------------------------------------------------------- */

static json_t *
jvec(const double *v, int n) {
    json_t *a = json_array();
    for (int i = 0; i < n; i++)
        json_array_append_new(a, json_real(v[i]));
    return a;
}

static json_t *
jvec3(vv_vec3 v) {
    double d[3] = {v.x, v.y, v.z};
    return jvec(d, 3);
}

static json_t *
tf_json(const vv_tf *tf) {
    json_t *o = json_object(), *op = json_array(), *co = json_array();
    for (int i = 0; i < tf->n_opacity; i++) {
        double d[2] = {tf->opacity[i].value, tf->opacity[i].opacity};
        json_array_append_new(op, jvec(d, 2));
    }
    for (int i = 0; i < tf->n_color; i++) {
        json_t *p = json_array();
        json_array_append_new(p, json_real(tf->color[i].value));
        json_array_append_new(p, jvec3(tf->color[i].color));
        json_array_append_new(co, p);
    }
    json_object_set_new(o, "opacity", op);
    json_object_set_new(o, "color", co);
    json_object_set_new(o, "opacity_unit_distance", json_real(tf->opacity_unit_distance));
    return o;
}

vv_status
vv_animation_save(const vv_animation *a, const char *path) {
    vv_status s = vv_animation_validate(a);
    if (s != VV_OK)
        return s;
    json_t *root = json_object();
    json_object_set_new(root, "volvis_animation", json_integer(1));
    if (a->scene)
        json_object_set_new(root, "scene", json_string(a->scene));
    json_object_set_new(root, "fps", json_real(a->fps));
    json_object_set_new(root, "duration", json_real(a->duration));
    json_t *tracks = json_array();
    for (int i = 0; i < a->n_tracks; i++) {
        const vv_anim_track *t = &a->tracks[i];
        json_t *tj = json_object();
        json_object_set_new(tj, "property", json_string(t->property));
        const char *interp =
            t->interp == VV_INTERP_LINEAR
                ? (t->kind == VV_ANIM_QUAT ? "slerp" : "linear")
                : (t->interp == VV_INTERP_STEP ? "step"
                                               : (t->kind == VV_ANIM_QUAT ? "squad" : "spline"));
        json_object_set_new(tj, "interpolation", json_string(interp));
        if (t->closed)
            json_object_set_new(tj, "closed", json_true());
        json_t *keys = json_array();
        for (int k = 0; k < t->n_keys; k++) {
            const vv_anim_key *key = &t->keys[k];
            json_t *kj = json_object();
            json_object_set_new(kj, "time", json_real(key->time));
            if (t->kind == VV_ANIM_TF)
                json_object_set_new(kj, "value", tf_json(key->tf));
            else if (t->kind == VV_ANIM_SCALAR)
                json_object_set_new(kj, "value",
                                    json_real(vv_anim_property_is_angle(t)
                                                  ? vv_rad_to_deg(key->value[0])
                                                  : key->value[0]));
            else
                json_object_set_new(kj, "value",
                                    jvec(key->value, vv_anim_kind_components(t->kind)));
            if (key->tension != 0)
                json_object_set_new(kj, "tension", json_real(key->tension));
            if (key->continuity != 0)
                json_object_set_new(kj, "continuity", json_real(key->continuity));
            if (key->bias != 0)
                json_object_set_new(kj, "bias", json_real(key->bias));
            if (key->easing != VV_EASE_LINEAR)
                json_object_set_new(kj, "easing", json_string(easing_names[key->easing]));
            json_array_append_new(keys, kj);
        }
        json_object_set_new(tj, "keys", keys);
        json_array_append_new(tracks, tj);
    }
    json_object_set_new(root, "tracks", tracks);
    if (a->n_sequences) {
        json_t *seqs = json_array();
        for (int i = 0; i < a->n_sequences; i++) {
            const vv_anim_sequence *q = &a->sequences[i];
            json_t *sj = json_object();
            json_object_set_new(sj, "type", json_string(seq_names[q->type]));
            switch (q->type) {
            case VV_SEQ_ORBIT:
                json_object_set_new(sj, "degrees", json_real(q->degrees));
                json_object_set_new(sj, "azimuth", json_real(q->azimuth));
                json_object_set_new(sj, "elevation", json_real(q->elevation));
                json_object_set_new(sj, "zoom", json_real(q->zoom));
                break;
            case VV_SEQ_ROTATE_OBJECT:
                json_object_set_new(sj, "object", json_string(q->object));
                json_object_set_new(sj, "axis", jvec3(q->axis));
                json_object_set_new(sj, "degrees", json_real(q->degrees));
                break;
            case VV_SEQ_FLY:
                json_object_set_new(sj, "offset", jvec3(q->offset));
                break;
            case VV_SEQ_SWEEP_CUT:
                json_object_set_new(sj, "point", jvec3(q->point));
                json_object_set_new(sj, "normal", jvec3(q->normal));
                json_object_set_new(sj, "distance", json_real(q->distance));
                break;
            }
            json_array_append_new(seqs, sj);
        }
        json_object_set_new(root, "sequences", seqs);
    }
    char *text = json_dumps(root, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
    json_decref(root);
    if (!text)
        return vv_error_set(VV_ERR_NOMEM, "animation: %s: out of memory", path);
    vv_atomic_file af;
    if ((s = vv_atomic_file_open(&af, path)) != VV_OK) {
        free(text);
        return vv_error_prefix(s, "animation");
    }
    size_t n = strlen(text);
    int ok = fwrite(text, 1, n, af.fp) == n && fputc('\n', af.fp) != EOF;
    free(text);
    if (!ok) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "animation: %s: write failed", path);
    }
    if ((s = vv_atomic_file_commit(&af)) != VV_OK)
        return vv_error_prefix(s, "animation");
    return VV_OK;
}
