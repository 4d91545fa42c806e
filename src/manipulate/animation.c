/*
 * The Animator's model: keyframe tracks addressed by property paths,
 * Kochanek–Bartels splines, slerp and squad, transfer-function blending, the
 * keyless transformation sequences, and evaluation into World snapshots
 * (include/volvis/animate.h; VolVis paper, section 4).
 *
 * Splines: a Hermite segment between keys i and i+1 whose tangents are the
 * Kochanek–Bartels tangents (Kochanek and Bartels, "Interpolating splines with
 * local tension, continuity, and bias control", SIGGRAPH '84), scaled for
 * unevenly spaced key times so that with tension = continuity = bias = 0 (the
 * Catmull–Rom spline) the velocity is continuous in time across every key.
 * Quaternions: slerp, or squad (Shoemake, "Animating rotation with
 * quaternion curves", SIGGRAPH '85) for a smooth orientation spline.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "manipulate/anim_internal.h"
#include "volvis/animate.h"

/* ---- property paths -------------------------------------------------------- */

enum { SC_VIEW = 1, SC_GLOBAL, SC_LIGHT, SC_CUT, SC_OBJECT };

enum {
    F_EYE = 1,
    F_AT,
    F_UP,
    F_FOV,
    F_ORTHO,
    F_BACKGROUND,
    F_AMBIENT,
    F_L_POSITION,
    F_L_DIRECTION,
    F_L_COLOR,
    F_L_INTENSITY,
    F_C_POINT,
    F_C_NORMAL,
    F_O_POSITION,
    F_O_ORIENTATION,
    F_O_SCALE,
    F_O_TF,
    F_O_ISOVALUE,
    F_O_THRESHOLD,
    F_O_STEP,
    F_O_TIME,
    F_M_COLOR,
    F_M_AMBIENT,
    F_M_DIFFUSE,
    F_M_SPECULAR,
    F_M_SHININESS,
    F_M_REFLECTANCE,
    F_M_TRANSPARENCY,
    F_OC_POINT,
    F_OC_NORMAL
};

typedef struct leaf {
    const char *name;
    int field;
    vv_anim_kind kind;
} leaf;

static const leaf view_leaves[] = {{"eye", F_EYE, VV_ANIM_VEC3},
                                   {"at", F_AT, VV_ANIM_VEC3},
                                   {"up", F_UP, VV_ANIM_VEC3},
                                   {"fov", F_FOV, VV_ANIM_SCALAR},
                                   {"ortho_height", F_ORTHO, VV_ANIM_SCALAR},
                                   {NULL, 0, 0}};
static const leaf light_leaves[] = {{"position", F_L_POSITION, VV_ANIM_VEC3},
                                    {"direction", F_L_DIRECTION, VV_ANIM_VEC3},
                                    {"color", F_L_COLOR, VV_ANIM_VEC3},
                                    {"intensity", F_L_INTENSITY, VV_ANIM_SCALAR},
                                    {NULL, 0, 0}};
static const leaf cut_leaves[] = {
    {"point", F_C_POINT, VV_ANIM_VEC3}, {"normal", F_C_NORMAL, VV_ANIM_VEC3}, {NULL, 0, 0}};
static const leaf object_leaves[] = {{"position", F_O_POSITION, VV_ANIM_VEC3},
                                     {"orientation", F_O_ORIENTATION, VV_ANIM_QUAT},
                                     {"scale", F_O_SCALE, VV_ANIM_VEC3},
                                     {"tf", F_O_TF, VV_ANIM_TF},
                                     {"isovalue", F_O_ISOVALUE, VV_ANIM_SCALAR},
                                     {"threshold", F_O_THRESHOLD, VV_ANIM_SCALAR},
                                     {"step", F_O_STEP, VV_ANIM_SCALAR},
                                     {"time", F_O_TIME, VV_ANIM_SCALAR},
                                     {"material.color", F_M_COLOR, VV_ANIM_VEC3},
                                     {"material.ambient", F_M_AMBIENT, VV_ANIM_SCALAR},
                                     {"material.diffuse", F_M_DIFFUSE, VV_ANIM_SCALAR},
                                     {"material.specular", F_M_SPECULAR, VV_ANIM_SCALAR},
                                     {"material.shininess", F_M_SHININESS, VV_ANIM_SCALAR},
                                     {"material.reflectance", F_M_REFLECTANCE, VV_ANIM_SCALAR},
                                     {"material.transparency", F_M_TRANSPARENCY, VV_ANIM_SCALAR},
                                     {NULL, 0, 0}};

static int
find_leaf(const leaf *table, const char *name, int *field, vv_anim_kind *kind) {
    for (int i = 0; table[i].name; i++)
        if (strcmp(table[i].name, name) == 0) {
            *field = table[i].field;
            *kind = table[i].kind;
            return 1;
        }
    return 0;
}

/* Reads "[N]" at *p; advances past it. */
static int
read_index(const char **p, int *out) {
    const char *s = *p;
    if (*s != '[')
        return 0;
    s++;
    if (*s < '0' || *s > '9')
        return 0;
    long v = 0;
    while (*s >= '0' && *s <= '9') {
        v = v * 10 + (*s - '0');
        if (v > 1000000)
            return 0;
        s++;
    }
    if (*s != ']')
        return 0;
    *p = s + 1;
    *out = (int)v;
    return 1;
}

vv_status
vv_anim_parse_property(const char *prop, vv_anim_target *t, vv_anim_kind *kind) {
    memset(t, 0, sizeof *t);
    t->index = 0;
    const char *p = prop;
    if (!prop || !*prop)
        return vv_error_set(VV_ERR_INVALID, "empty property");
    if (strlen(prop) >= VV_ANIM_PATH_MAX)
        return vv_error_set(VV_ERR_INVALID, "property '%.40s...' is too long", prop);
    if (strncmp(p, "view.", 5) == 0) {
        t->scope = SC_VIEW;
        if (find_leaf(view_leaves, p + 5, &t->field, kind))
            return VV_OK;
        return vv_error_set(VV_ERR_INVALID,
                            "unknown property '%s' (view has eye, at, up, fov, ortho_height)",
                            prop);
    }
    if (strcmp(p, "background") == 0 || strcmp(p, "ambient") == 0) {
        t->scope = SC_GLOBAL;
        t->field = p[0] == 'b' ? F_BACKGROUND : F_AMBIENT;
        *kind = VV_ANIM_VEC3;
        return VV_OK;
    }
    if (strncmp(p, "lights", 6) == 0 || strncmp(p, "cut_planes", 10) == 0) {
        int light = p[0] == 'l';
        p += light ? 6 : 10;
        if (!read_index(&p, &t->index) || *p != '.')
            return vv_error_set(VV_ERR_INVALID, "property '%s': expected %s[INDEX].NAME", prop,
                                light ? "lights" : "cut_planes");
        t->scope = light ? SC_LIGHT : SC_CUT;
        if (find_leaf(light ? light_leaves : cut_leaves, p + 1, &t->field, kind))
            return VV_OK;
        return vv_error_set(VV_ERR_INVALID, "unknown property '%s' (%s)", prop,
                            light ? "a light has position, direction, color, intensity"
                                  : "a cut plane has point, normal");
    }
    if (strncmp(p, "objects", 7) == 0) {
        p += 7;
        t->scope = SC_OBJECT;
        if (*p == '[') {
            if (!read_index(&p, &t->index))
                return vv_error_set(VV_ERR_INVALID, "property '%s': bad object index", prop);
        } else if (*p == '.') {
            p++;
            const char *dot = strchr(p, '.');
            size_t n = dot ? (size_t)(dot - p) : 0;
            if (!dot || n == 0 || n >= VV_NAME_MAX)
                return vv_error_set(VV_ERR_INVALID,
                                    "property '%s': expected objects.NAME.PROPERTY or "
                                    "objects[INDEX].PROPERTY",
                                    prop);
            memcpy(t->object, p, n);
            t->object[n] = '\0';
            t->index = -1;
            p = dot;
        } else {
            return vv_error_set(VV_ERR_INVALID, "unknown property '%s'", prop);
        }
        if (*p != '.')
            return vv_error_set(VV_ERR_INVALID, "property '%s': expected '.' after the object",
                                prop);
        p++;
        if (strncmp(p, "cut_planes", 10) == 0) {
            p += 10;
            if (!read_index(&p, &t->sub) || *p != '.')
                return vv_error_set(VV_ERR_INVALID,
                                    "property '%s': expected cut_planes[INDEX].NAME", prop);
            if (find_leaf(cut_leaves, p + 1, &t->field, kind)) {
                t->field = t->field == F_C_POINT ? F_OC_POINT : F_OC_NORMAL;
                return VV_OK;
            }
            return vv_error_set(VV_ERR_INVALID,
                                "unknown property '%s' (a cut plane has point, normal)", prop);
        }
        if (find_leaf(object_leaves, p, &t->field, kind))
            return VV_OK;
        return vv_error_set(VV_ERR_INVALID,
                            "unknown property '%s' (an object has position, orientation, scale, "
                            "tf, isovalue, threshold, step, time, material.color|ambient|diffuse|"
                            "specular|shininess|reflectance|transparency, cut_planes[j].point|"
                            "normal)",
                            prop);
    }
    return vv_error_set(VV_ERR_INVALID,
                        "unknown property '%s' (view.*, background, ambient, lights[i].*, "
                        "cut_planes[i].*, objects[i].* or objects.NAME.*)",
                        prop);
}

int
vv_anim_kind_components(vv_anim_kind k) {
    switch (k) {
    case VV_ANIM_SCALAR:
        return 1;
    case VV_ANIM_VEC3:
        return 3;
    case VV_ANIM_QUAT:
        return 4;
    case VV_ANIM_TF:
        break;
    }
    return 0;
}

int
vv_anim_property_is_angle(const vv_anim_track *t) {
    return t->target.scope == SC_VIEW && t->target.field == F_FOV;
}

/* ---- animation objects ----------------------------------------------------- */

vv_status
vv_animation_new(vv_animation **out) {
    *out = calloc(1, sizeof **out);
    if (!*out)
        return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
    (*out)->fps = 30;
    (*out)->duration = 1;
    return VV_OK;
}

static void
track_clear(vv_anim_track *t) {
    for (int k = 0; k < t->n_keys; k++)
        free(t->keys[k].tf);
    free(t->keys);
    t->keys = NULL;
    t->n_keys = t->cap_keys = 0;
}

void
vv_animation_free(vv_animation *a) {
    if (!a)
        return;
    for (int i = 0; i < a->n_tracks; i++)
        track_clear(&a->tracks[i]);
    free(a->tracks);
    free(a->sequences);
    free(a->scene);
    free(a);
}

vv_status
vv_animation_clone(vv_animation **out, const vv_animation *a) {
    *out = NULL;
    if (!a)
        return vv_error_set(VV_ERR_INVALID, "animation: NULL");
    vv_animation *c;
    vv_status s = vv_animation_new(&c);
    if (s != VV_OK)
        return s;
    c->fps = a->fps;
    c->duration = a->duration;
    if (a->scene && !(c->scene = vv_strdup(a->scene)))
        goto nomem;
    for (int i = 0; i < a->n_tracks; i++) {
        const vv_anim_track *t = &a->tracks[i];
        int idx;
        if ((s = vv_animation_add_track(c, t->property, &idx)) != VV_OK) {
            vv_animation_free(c);
            return s;
        }
        c->tracks[idx].interp = t->interp;
        c->tracks[idx].closed = t->closed;
        for (int k = 0; k < t->n_keys; k++)
            if ((s = vv_anim_track_add_key(&c->tracks[idx], &t->keys[k])) != VV_OK) {
                vv_animation_free(c);
                return s;
            }
    }
    for (int i = 0; i < a->n_sequences; i++)
        if ((s = vv_animation_add_sequence(c, &a->sequences[i])) != VV_OK) {
            vv_animation_free(c);
            return s;
        }
    *out = c;
    return VV_OK;
nomem:
    vv_animation_free(c);
    return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
}

int
vv_animation_frame_count(const vv_animation *a) {
    double n = floor(a->duration * a->fps + 0.5);
    if (!(n >= 1))
        return 1;
    if (n > 1e7)
        return 10000000;
    return (int)n;
}

vv_status
vv_animation_add_track(vv_animation *a, const char *property, int *index) {
    vv_anim_track t;
    memset(&t, 0, sizeof t);
    vv_status s = vv_anim_parse_property(property, &t.target, &t.kind);
    if (s != VV_OK)
        return vv_error_prefix(s, "animation");
    snprintf(t.property, sizeof t.property, "%s", property);
    t.interp = VV_INTERP_SPLINE;
    if (a->n_tracks == a->cap_tracks) {
        int cap = a->cap_tracks ? 2 * a->cap_tracks : 8;
        vv_anim_track *nt = realloc(a->tracks, sizeof *nt * (size_t)cap);
        if (!nt)
            return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
        a->tracks = nt;
        a->cap_tracks = cap;
    }
    a->tracks[a->n_tracks] = t;
    if (index)
        *index = a->n_tracks;
    a->n_tracks++;
    return VV_OK;
}

void
vv_anim_key_init(vv_anim_key *key, double time) {
    memset(key, 0, sizeof *key);
    key->time = time;
    key->easing = VV_EASE_LINEAR;
}

vv_status
vv_anim_track_add_key(vv_anim_track *track, const vv_anim_key *key) {
    if (!isfinite(key->time))
        return vv_error_set(VV_ERR_INVALID, "%s: key time is not finite", track->property);
    if (track->kind == VV_ANIM_TF) {
        if (!key->tf)
            return vv_error_set(VV_ERR_INVALID, "%s: a transfer-function key needs a tf",
                                track->property);
    } else {
        for (int c = 0; c < vv_anim_kind_components(track->kind); c++)
            if (!isfinite(key->value[c]))
                return vv_error_set(VV_ERR_INVALID, "%s: key at %g: value is not finite",
                                    track->property, key->time);
    }
    int pos = track->n_keys;
    while (pos > 0 && track->keys[pos - 1].time > key->time)
        pos--;
    if (pos > 0 && track->keys[pos - 1].time == key->time)
        return vv_error_set(VV_ERR_INVALID, "%s: there is a key at time %g already",
                            track->property, key->time);
    if (track->n_keys == track->cap_keys) {
        int cap = track->cap_keys ? 2 * track->cap_keys : 8;
        vv_anim_key *nk = realloc(track->keys, sizeof *nk * (size_t)cap);
        if (!nk)
            return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
        track->keys = nk;
        track->cap_keys = cap;
    }
    vv_anim_key k = *key;
    k.tf = NULL;
    if (track->kind == VV_ANIM_TF) {
        k.tf = malloc(sizeof *k.tf);
        if (!k.tf)
            return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
        *k.tf = *key->tf;
    }
    memmove(track->keys + pos + 1, track->keys + pos,
            sizeof *track->keys * (size_t)(track->n_keys - pos));
    track->keys[pos] = k;
    track->n_keys++;
    return VV_OK;
}

vv_status
vv_anim_sequence_check(const vv_anim_sequence *q) {
    switch (q->type) {
    case VV_SEQ_ORBIT:
        if (!isfinite(q->degrees) || !isfinite(q->azimuth) || !isfinite(q->elevation))
            return vv_error_set(VV_ERR_INVALID, "orbit: angles must be finite");
        if (!(q->zoom > 0) || !isfinite(q->zoom))
            return vv_error_set(VV_ERR_INVALID, "orbit: zoom %g must be > 0", q->zoom);
        return VV_OK;
    case VV_SEQ_ROTATE_OBJECT:
        if (!q->object[0])
            return vv_error_set(VV_ERR_INVALID, "rotate_object: no object name");
        if (!isfinite(q->degrees) || !(vv_vec3_length(q->axis) > 0) ||
            !isfinite(vv_vec3_length(q->axis)))
            return vv_error_set(VV_ERR_INVALID,
                                "rotate_object: the axis must be non-zero and the angle finite");
        return VV_OK;
    case VV_SEQ_FLY:
        if (!isfinite(vv_vec3_length(q->offset)))
            return vv_error_set(VV_ERR_INVALID, "fly: offset must be finite");
        return VV_OK;
    case VV_SEQ_SWEEP_CUT:
        if (!isfinite(vv_vec3_length(q->point)) || !isfinite(q->distance) ||
            !(vv_vec3_length(q->normal) > 0) || !isfinite(vv_vec3_length(q->normal)))
            return vv_error_set(VV_ERR_INVALID,
                                "sweep_cut: point and distance must be finite, normal non-zero");
        return VV_OK;
    }
    return vv_error_set(VV_ERR_INVALID, "unknown sequence type %d", (int)q->type);
}

vv_status
vv_animation_add_sequence(vv_animation *a, const vv_anim_sequence *seq) {
    vv_status s = vv_anim_sequence_check(seq);
    if (s != VV_OK)
        return vv_error_prefix(s, "animation");
    if (a->n_sequences == a->cap_sequences) {
        int cap = a->cap_sequences ? 2 * a->cap_sequences : 4;
        vv_anim_sequence *ns = realloc(a->sequences, sizeof *ns * (size_t)cap);
        if (!ns)
            return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
        a->sequences = ns;
        a->cap_sequences = cap;
    }
    a->sequences[a->n_sequences++] = *seq;
    return VV_OK;
}

/* ---- validation -------------------------------------------------------------- */

static int
tf_finite(const vv_tf *tf) {
    if (tf->n_opacity < 0 || tf->n_opacity > VV_TF_MAX_POINTS || tf->n_color < 0 ||
        tf->n_color > VV_TF_MAX_POINTS || !(tf->opacity_unit_distance > 0) ||
        !isfinite(tf->opacity_unit_distance))
        return 0;
    for (int i = 0; i < tf->n_opacity; i++)
        if (!isfinite(tf->opacity[i].value) || !(tf->opacity[i].opacity >= 0) ||
            !(tf->opacity[i].opacity <= 1))
            return 0;
    for (int i = 0; i < tf->n_color; i++)
        if (!isfinite(tf->color[i].value) || !isfinite(vv_vec3_length(tf->color[i].color)))
            return 0;
    return 1;
}

static int
keys_equal(const vv_anim_track *t, const vv_anim_key *a, const vv_anim_key *b) {
    if (t->kind == VV_ANIM_TF)
        return a->tf && b->tf && memcmp(a->tf, b->tf, sizeof *a->tf) == 0;
    int n = vv_anim_kind_components(t->kind);
    double d = 0, s = 1;
    for (int c = 0; c < n; c++) {
        d += fabs(a->value[c] - b->value[c]);
        s += fabs(a->value[c]);
    }
    if (t->kind == VV_ANIM_QUAT && d > 1e-9 * s) { /* q and -q are one rotation */
        d = 0;
        for (int c = 0; c < n; c++)
            d += fabs(a->value[c] + b->value[c]);
    }
    return d <= 1e-9 * s;
}

vv_status
vv_anim_track_validate(const vv_anim_track *t, int *bad_key) {
    *bad_key = -1;
    if (t->n_keys < 1)
        return vv_error_set(VV_ERR_INVALID, "no keys (a track needs at least one)");
    int n = vv_anim_kind_components(t->kind);
    for (int k = 0; k < t->n_keys; k++) {
        const vv_anim_key *key = &t->keys[k];
        *bad_key = k;
        if (!isfinite(key->time))
            return vv_error_set(VV_ERR_INVALID, "time is not finite");
        if (k > 0 && !(key->time > t->keys[k - 1].time))
            return vv_error_set(VV_ERR_INVALID, "time %g is not after %g (keys out of order)",
                                key->time, t->keys[k - 1].time);
        for (int c = 0; c < n; c++)
            if (!isfinite(key->value[c]))
                return vv_error_set(VV_ERR_INVALID, "value is not finite");
        if (t->kind == VV_ANIM_QUAT) {
            double l = sqrt(key->value[0] * key->value[0] + key->value[1] * key->value[1] +
                            key->value[2] * key->value[2] + key->value[3] * key->value[3]);
            if (!(l > 1e-12))
                return vv_error_set(VV_ERR_INVALID, "the zero quaternion is not a rotation");
        }
        if (t->kind == VV_ANIM_TF && (!key->tf || !tf_finite(key->tf)))
            return vv_error_set(VV_ERR_INVALID, "transfer function missing or not finite");
        const double p[3] = {key->tension, key->continuity, key->bias};
        for (int i = 0; i < 3; i++)
            if (!(p[i] >= -1 && p[i] <= 1))
                return vv_error_set(VV_ERR_INVALID,
                                    "tension, continuity and bias must be in [-1, 1], got %g",
                                    p[i]);
        if ((int)key->easing < 0 || (int)key->easing > VV_EASE_IN_OUT)
            return vv_error_set(VV_ERR_INVALID, "unknown easing %d", (int)key->easing);
    }
    *bad_key = -1;
    if ((int)t->interp < 0 || (int)t->interp > VV_INTERP_STEP)
        return vv_error_set(VV_ERR_INVALID, "unknown interpolation %d", (int)t->interp);
    if (t->closed) {
        if (t->n_keys < 2)
            return vv_error_set(VV_ERR_INVALID, "a closed track needs at least 2 keys");
        if (!keys_equal(t, &t->keys[0], &t->keys[t->n_keys - 1])) {
            *bad_key = t->n_keys - 1;
            return vv_error_set(VV_ERR_INVALID,
                                "a closed track must end with the value of its first key");
        }
    }
    return VV_OK;
}

vv_status
vv_animation_validate(const vv_animation *a) {
    if (!a)
        return vv_error_set(VV_ERR_INVALID, "animation: NULL");
    if (!(a->fps > 0 && a->fps <= 1000))
        return vv_error_set(VV_ERR_INVALID, "animation: fps %g is outside (0, 1000]", a->fps);
    if (!(a->duration > 0) || !isfinite(a->duration) || a->duration * a->fps > 1e7)
        return vv_error_set(VV_ERR_INVALID,
                            "animation: duration %g s must be > 0 and under 10^7 frames",
                            a->duration);
    for (int i = 0; i < a->n_tracks; i++) {
        int k;
        vv_status s = vv_anim_track_validate(&a->tracks[i], &k);
        if (s != VV_OK) {
            if (k >= 0)
                return vv_error_prefix(s, "animation: tracks[%d] %s: keys[%d]", i,
                                       a->tracks[i].property, k);
            return vv_error_prefix(s, "animation: tracks[%d] %s", i, a->tracks[i].property);
        }
    }
    for (int i = 0; i < a->n_sequences; i++) {
        vv_status s = vv_anim_sequence_check(&a->sequences[i]);
        if (s != VV_OK)
            return vv_error_prefix(s, "animation: sequences[%d]", i);
    }
    return VV_OK;
}

/* ---- interpolation ------------------------------------------------------------ */

static double
ease(vv_anim_easing e, double u) {
    switch (e) {
    case VV_EASE_IN:
        return u * u;
    case VV_EASE_OUT:
        return 1 - (1 - u) * (1 - u);
    case VV_EASE_IN_OUT:
        return u * u * (3 - 2 * u);
    case VV_EASE_LINEAR:
        break;
    }
    return u;
}

/* Neighbour of key i in direction dir (-1, +1) for the tangent: its value
 * and the time between them. Open ends mirror the segment next to them;
 * closed tracks wrap round the seam (key n-1 is key 0). */
static void
neighbour(const vv_anim_track *t, int i, int dir, int nc, double out[4], double *dt) {
    int n = t->n_keys;
    int j = i + dir;
    if (j >= 0 && j < n) {
        for (int c = 0; c < nc; c++)
            out[c] = t->keys[j].value[c];
        *dt = fabs(t->keys[j].time - t->keys[i].time);
        return;
    }
    if (t->closed && n >= 3) {
        int w = dir < 0 ? n - 2 : 1;    /* across the seam */
        int base = dir < 0 ? n - 1 : 0; /* w's neighbour on its own side */
        for (int c = 0; c < nc; c++)
            out[c] = t->keys[w].value[c];
        *dt = fabs(t->keys[w].time - t->keys[base].time);
        return;
    }
    int m = i - dir; /* mirror the other neighbour through key i */
    for (int c = 0; c < nc; c++)
        out[c] = 2 * t->keys[i].value[c] - t->keys[m].value[c];
    *dt = fabs(t->keys[i].time - t->keys[m].time);
}

/* Kochanek–Bartels tangent at key i, per unit time; outgoing (for the
 * segment after i) or incoming (before i). */
static void
kb_tangent(const vv_anim_track *t, int i, int outgoing, int nc, double m[4]) {
    double prev[4], next[4], dp, dn;
    neighbour(t, i, -1, nc, prev, &dp);
    neighbour(t, i, +1, nc, next, &dn);
    /* at the seam of a closed track both sides use key 0's parameters */
    const vv_anim_key *k = (t->closed && i == t->n_keys - 1) ? &t->keys[0] : &t->keys[i];
    double T = k->tension, C = k->continuity, B = k->bias;
    double a, b;
    if (outgoing) {
        a = (1 - T) * (1 + B) * (1 + C) / 2;
        b = (1 - T) * (1 - B) * (1 - C) / 2;
    } else {
        a = (1 - T) * (1 + B) * (1 - C) / 2;
        b = (1 - T) * (1 - B) * (1 + C) / 2;
    }
    /* the tangents a dP_prev + b dP_next are per segment; 2 / (dp + dn) makes
     * them per unit time (for Catmull–Rom, (P_next - P_prev) / (dp + dn)) */
    double s = (dp + dn) > 0 ? 2 / (dp + dn) : 0;
    for (int c = 0; c < nc; c++) {
        double p = t->keys[i].value[c];
        m[c] = s * (a * (p - prev[c]) + b * (next[c] - p));
    }
}

static vv_quat
key_quat(const vv_anim_key *k) {
    vv_quat q = {k->value[0], k->value[1], k->value[2], k->value[3]};
    return vv_quat_normalize(q);
}

static double
quat_dot(vv_quat a, vv_quat b) {
    return a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
}

static vv_quat
quat_neg(vv_quat q) {
    vv_quat r = {-q.w, -q.x, -q.y, -q.z};
    return r;
}

/* slerp without choosing the shorter arc (squad's inner interpolations). */
static vv_quat
slerp_long(vv_quat a, vv_quat b, double t) {
    double d = quat_dot(a, b);
    if (d > 1)
        d = 1;
    if (d < -1)
        d = -1;
    double wa, wb;
    double th = acos(d), s = sin(th);
    if (fabs(s) < 1e-9) {
        wa = 1 - t;
        wb = t;
    } else {
        wa = sin((1 - t) * th) / s;
        wb = sin(t * th) / s;
    }
    vv_quat r = {wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y,
                 wa * a.z + wb * b.z};
    return vv_quat_normalize(r);
}

static vv_quat
quat_log(vv_quat q) { /* unit q -> (0, v θ) */
    double vl = sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
    double th = atan2(vl, q.w);
    double k = vl > 1e-12 ? th / vl : 1;
    vv_quat r = {0, q.x * k, q.y * k, q.z * k};
    return r;
}

static vv_quat
quat_exp(vv_quat q) { /* (0, v) -> unit */
    double th = sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
    double k = th > 1e-12 ? sin(th) / th : 1;
    vv_quat r = {cos(th), q.x * k, q.y * k, q.z * k};
    return r;
}

/* Key i's orientation sign-aligned with @p ref. */
static vv_quat
aligned(const vv_anim_track *t, int i, vv_quat ref) {
    vv_quat q = key_quat(&t->keys[i]);
    return quat_dot(q, ref) < 0 ? quat_neg(q) : q;
}

/* Squad's inner control point at key i (qi is key i, already aligned). */
static vv_quat
squad_control(const vv_anim_track *t, int i, vv_quat qi) {
    int n = t->n_keys;
    int ip = i - 1, in = i + 1;
    if (t->closed && n >= 3) {
        if (ip < 0)
            ip = n - 2;
        if (in >= n)
            in = 1;
    }
    if (ip < 0 || in >= n)
        return qi;
    vv_quat inv = vv_quat_conjugate(qi);
    vv_quat qp = aligned(t, ip, qi), qn = aligned(t, in, qi);
    vv_quat ln = quat_log(vv_quat_mul(inv, qn)), lp = quat_log(vv_quat_mul(inv, qp));
    vv_quat e = {0, -(ln.x + lp.x) / 4, -(ln.y + lp.y) / 4, -(ln.z + lp.z) / 4};
    return vv_quat_normalize(vv_quat_mul(qi, quat_exp(e)));
}

/* Linear blend of two transfer functions: point by point when they have the
 * same numbers of points, else both resampled onto the union of their point
 * values. */
static void
tf_blend(const vv_tf *a, const vv_tf *b, double u, vv_tf *out) {
    vv_tf r;
    vv_tf_init(&r);
    r.opacity_unit_distance =
        a->opacity_unit_distance + u * (b->opacity_unit_distance - a->opacity_unit_distance);
    if (a->n_opacity == b->n_opacity) {
        r.n_opacity = a->n_opacity;
        for (int i = 0; i < a->n_opacity; i++) {
            r.opacity[i].value =
                a->opacity[i].value + u * (b->opacity[i].value - a->opacity[i].value);
            r.opacity[i].opacity =
                a->opacity[i].opacity + u * (b->opacity[i].opacity - a->opacity[i].opacity);
        }
    } else {
        double vals[2 * VV_TF_MAX_POINTS];
        int n = 0;
        for (int i = 0, j = 0; i < a->n_opacity || j < b->n_opacity;) {
            double v;
            if (j >= b->n_opacity ||
                (i < a->n_opacity && a->opacity[i].value <= b->opacity[j].value))
                v = a->opacity[i++].value;
            else
                v = b->opacity[j++].value;
            if (n == 0 || v > vals[n - 1])
                vals[n++] = v;
        }
        int m = n <= VV_TF_MAX_POINTS ? n : VV_TF_MAX_POINTS;
        for (int i = 0; i < m; i++) {
            double v = vals[m == n ? i : (int)((double)i * (n - 1) / (m - 1) + 0.5)];
            double oa = vv_tf_eval_opacity(a, v), ob = vv_tf_eval_opacity(b, v);
            r.opacity[i].value = v;
            r.opacity[i].opacity = oa + u * (ob - oa);
        }
        r.n_opacity = m;
    }
    if (a->n_color == b->n_color) {
        r.n_color = a->n_color;
        for (int i = 0; i < a->n_color; i++) {
            r.color[i].value = a->color[i].value + u * (b->color[i].value - a->color[i].value);
            r.color[i].color = vv_vec3_lerp(a->color[i].color, b->color[i].color, u);
        }
    } else {
        double vals[2 * VV_TF_MAX_POINTS];
        int n = 0;
        for (int i = 0, j = 0; i < a->n_color || j < b->n_color;) {
            double v;
            if (j >= b->n_color || (i < a->n_color && a->color[i].value <= b->color[j].value))
                v = a->color[i++].value;
            else
                v = b->color[j++].value;
            if (n == 0 || v > vals[n - 1])
                vals[n++] = v;
        }
        int m = n <= VV_TF_MAX_POINTS ? n : VV_TF_MAX_POINTS;
        for (int i = 0; i < m; i++) {
            double v = vals[m == n ? i : (int)((double)i * (n - 1) / (m - 1) + 0.5)];
            r.color[i].value = v;
            r.color[i].color = vv_vec3_lerp(vv_tf_eval_color(a, v), vv_tf_eval_color(b, v), u);
        }
        r.n_color = m;
    }
    *out = r;
}

vv_status
vv_anim_track_eval(const vv_anim_track *t, double time, double value[4], vv_tf *tf) {
    if (!t || t->n_keys < 1)
        return vv_error_set(VV_ERR_INVALID, "animation: %s: no keys", t ? t->property : "track");
    if (!isfinite(time))
        return vv_error_set(VV_ERR_INVALID, "animation: %s: time is not finite", t->property);
    int n = t->n_keys, nc = vv_anim_kind_components(t->kind);
    if (t->kind == VV_ANIM_TF && !tf)
        return vv_error_set(VV_ERR_INVALID, "animation: %s: no tf to evaluate into", t->property);
    /* the segment [i, i+1] holding the time; keys are returned exactly */
    int i;
    if (!(time > t->keys[0].time) || n == 1) {
        i = 0;
    } else if (time >= t->keys[n - 1].time) {
        i = n - 1;
    } else {
        int lo = 0, hi = n - 1; /* keys[lo].time <= time < keys[hi].time */
        while (hi - lo > 1) {
            int mid = (lo + hi) / 2;
            if (t->keys[mid].time <= time)
                lo = mid;
            else
                hi = mid;
        }
        i = lo;
    }
    const vv_anim_key *k0 = &t->keys[i];
    if (i == n - 1 || time <= k0->time || t->interp == VV_INTERP_STEP) {
        if (t->kind == VV_ANIM_TF)
            *tf = *k0->tf;
        else
            for (int c = 0; c < 4; c++)
                value[c] = c < nc ? k0->value[c] : 0;
        if (t->kind == VV_ANIM_QUAT) {
            vv_quat q = key_quat(k0);
            value[0] = q.w, value[1] = q.x, value[2] = q.y, value[3] = q.z;
        }
        return VV_OK;
    }
    const vv_anim_key *k1 = &t->keys[i + 1];
    double dt = k1->time - k0->time;
    double u = ease(k0->easing, (time - k0->time) / dt);
    if (t->kind == VV_ANIM_TF) {
        tf_blend(k0->tf, k1->tf, u, tf);
        return VV_OK;
    }
    if (t->kind == VV_ANIM_QUAT) {
        vv_quat q0 = key_quat(k0), q1 = aligned(t, i + 1, q0), q;
        if (t->interp == VV_INTERP_LINEAR) {
            q = slerp_long(q0, q1, u);
        } else {
            vv_quat s0 = squad_control(t, i, q0), s1 = squad_control(t, i + 1, q1);
            if (quat_dot(s0, q0) < 0)
                s0 = quat_neg(s0);
            if (quat_dot(s1, q1) < 0)
                s1 = quat_neg(s1);
            q = slerp_long(slerp_long(q0, q1, u), slerp_long(s0, s1, u), 2 * u * (1 - u));
        }
        value[0] = q.w, value[1] = q.x, value[2] = q.y, value[3] = q.z;
        return VV_OK;
    }
    if (t->interp == VV_INTERP_LINEAR) {
        for (int c = 0; c < 4; c++)
            value[c] = c < nc ? k0->value[c] + u * (k1->value[c] - k0->value[c]) : 0;
        return VV_OK;
    }
    double m0[4], m1[4];
    kb_tangent(t, i, 1, nc, m0);
    kb_tangent(t, i + 1, 0, nc, m1);
    double u2 = u * u, u3 = u2 * u;
    double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
    for (int c = 0; c < 4; c++)
        value[c] =
            c < nc ? h00 * k0->value[c] + h10 * dt * m0[c] + h01 * k1->value[c] + h11 * dt * m1[c]
                   : 0;
    return VV_OK;
}

/* ---- applying to a World ------------------------------------------------------ */

static vv_object *
find_object(const vv_world *w, const vv_anim_target *tg) {
    if (tg->index >= 0)
        return tg->index < w->n_objects ? w->objects[tg->index] : NULL;
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i] && strcmp(w->objects[i]->name, tg->object) == 0)
            return w->objects[i];
    return NULL;
}

static vv_object *
find_named(const vv_world *w, const char *name) {
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i] && strcmp(w->objects[i]->name, name) == 0)
            return w->objects[i];
    return NULL;
}

/* Checks that the target of @p t exists in @p w; sets the error otherwise. */
static vv_status
check_target(const vv_anim_track *t, const vv_world *w) {
    const vv_anim_target *tg = &t->target;
    switch (tg->scope) {
    case SC_LIGHT:
        if (tg->index >= w->n_lights)
            return vv_error_set(VV_ERR_INVALID, "the World has %d light%s", w->n_lights,
                                w->n_lights == 1 ? "" : "s");
        return VV_OK;
    case SC_CUT:
        if (tg->index >= w->n_cut_planes)
            return vv_error_set(VV_ERR_INVALID, "the World has %d global cut plane%s",
                                w->n_cut_planes, w->n_cut_planes == 1 ? "" : "s");
        return VV_OK;
    case SC_OBJECT: {
        vv_object *o = find_object(w, tg);
        if (!o) {
            if (tg->index < 0)
                return vv_error_set(VV_ERR_INVALID, "no object named '%s' in the World",
                                    tg->object);
            return vv_error_set(VV_ERR_INVALID, "the World has %d object%s", w->n_objects,
                                w->n_objects == 1 ? "" : "s");
        }
        if ((tg->field == F_O_TF || tg->field == F_O_ISOVALUE || tg->field == F_O_THRESHOLD ||
             tg->field == F_O_STEP) &&
            o->type != VV_OBJECT_VOLUME)
            return vv_error_set(VV_ERR_INVALID, "object '%s' is not a volume", o->name);
        if ((tg->field == F_OC_POINT || tg->field == F_OC_NORMAL) && tg->sub >= o->n_cut_planes)
            return vv_error_set(VV_ERR_INVALID, "object '%s' has %d cut plane%s", o->name,
                                o->n_cut_planes, o->n_cut_planes == 1 ? "" : "s");
        return VV_OK;
    }
    default:
        return VV_OK;
    }
}

vv_status
vv_animation_check_world(const vv_animation *a, const vv_world *world) {
    if (!a || !world)
        return vv_error_set(VV_ERR_INVALID, "animation: no animation or no World");
    for (int i = 0; i < a->n_tracks; i++) {
        vv_status s = check_target(&a->tracks[i], world);
        if (s != VV_OK)
            return vv_error_prefix(s, "animation: tracks[%d] %s", i, a->tracks[i].property);
    }
    for (int i = 0; i < a->n_sequences; i++) {
        const vv_anim_sequence *q = &a->sequences[i];
        if (q->type == VV_SEQ_ROTATE_OBJECT && !find_named(world, q->object))
            return vv_error_set(VV_ERR_INVALID,
                                "animation: sequences[%d] rotate_object: no object named '%s' in "
                                "the World",
                                i, q->object);
        if (q->type == VV_SEQ_SWEEP_CUT && world->n_cut_planes >= VV_MAX_CUT_PLANES)
            return vv_error_set(VV_ERR_INVALID,
                                "animation: sequences[%d] sweep_cut: the World has %d cut planes "
                                "already (at most %d)",
                                i, world->n_cut_planes, VV_MAX_CUT_PLANES);
    }
    return VV_OK;
}

static double
clampd(double v, double lo, double hi) {
    return v < lo ? lo : (v > hi ? hi : v);
}

static vv_vec3
clamp_color(vv_vec3 c) {
    return vv_vec3_make(clampd(c.x, 0, 1), clampd(c.y, 0, 1), clampd(c.z, 0, 1));
}

/* A direction from an interpolated value; the old one when it degenerates. */
static vv_vec3
unit_or(vv_vec3 v, vv_vec3 old) {
    double l = vv_vec3_length(v);
    return l > 1e-12 ? vv_vec3_scale(v, 1 / l) : old;
}

static void
tf_clamp(vv_tf *tf) {
    for (int i = 0; i < tf->n_opacity; i++)
        tf->opacity[i].opacity = clampd(tf->opacity[i].opacity, 0, 1);
    for (int i = 0; i < tf->n_color; i++)
        tf->color[i].color = clamp_color(tf->color[i].color);
}

static vv_status
apply_track(const vv_anim_track *t, vv_world *w, double time, vv_tf *tfbuf) {
    vv_status s = check_target(t, w);
    if (s != VV_OK)
        return s;
    double v[4];
    if ((s = vv_anim_track_eval(t, time, v, tfbuf)) != VV_OK)
        return s;
    vv_vec3 x = vv_vec3_make(v[0], v[1], v[2]);
    const vv_anim_target *tg = &t->target;
    vv_light *l = tg->scope == SC_LIGHT ? &w->lights[tg->index] : NULL;
    vv_cut_plane *cp = tg->scope == SC_CUT ? &w->cut_planes[tg->index] : NULL;
    vv_object *o = tg->scope == SC_OBJECT ? find_object(w, tg) : NULL;
    vv_cut_plane *ocp =
        o && (tg->field == F_OC_POINT || tg->field == F_OC_NORMAL) ? &o->cut_planes[tg->sub] : NULL;
    switch (tg->field) {
    case F_EYE:
        w->view.eye = x;
        break;
    case F_AT:
        w->view.at = x;
        break;
    case F_UP:
        w->view.up = unit_or(x, w->view.up);
        break;
    case F_FOV:
        w->view.fov = clampd(v[0], 1e-4, VV_PI - 1e-4);
        break;
    case F_ORTHO:
        w->view.ortho_height = v[0] > 1e-12 ? v[0] : 1e-12;
        break;
    case F_BACKGROUND:
        w->background = clamp_color(x);
        break;
    case F_AMBIENT:
        w->ambient = vv_vec3_make(fmax(x.x, 0), fmax(x.y, 0), fmax(x.z, 0));
        break;
    case F_L_POSITION:
        l->position = x;
        break;
    case F_L_DIRECTION:
        l->direction = unit_or(x, l->direction);
        break;
    case F_L_COLOR:
        l->color = clamp_color(x);
        break;
    case F_L_INTENSITY:
        l->intensity = fmax(v[0], 0);
        break;
    case F_C_POINT:
        cp->point = x;
        break;
    case F_C_NORMAL:
        cp->normal = unit_or(x, cp->normal);
        break;
    case F_OC_POINT:
        ocp->point = x;
        break;
    case F_OC_NORMAL:
        ocp->normal = unit_or(x, ocp->normal);
        break;
    case F_O_POSITION:
        o->position = x;
        break;
    case F_O_ORIENTATION: {
        vv_quat q = {v[0], v[1], v[2], v[3]};
        o->orientation = vv_quat_normalize(q);
        break;
    }
    case F_O_SCALE:
        o->scale = x;
        break;
    case F_O_TF:
        tf_clamp(tfbuf);
        o->tf = *tfbuf;
        break;
    case F_O_ISOVALUE:
        o->isovalue = v[0];
        break;
    case F_O_THRESHOLD:
        o->threshold = v[0];
        break;
    case F_O_STEP:
        o->step = v[0] > 1e-3 ? v[0] : 1e-3;
        break;
    case F_O_TIME: /* the nearest step; the caller reads it (prepare_frame) */
        o->time = v[0] > 0 && v[0] < 1e6 ? (int)lround(v[0]) : v[0] >= 1e6 ? 1000000 : 0;
        break;
    case F_M_COLOR:
        o->material.color = clamp_color(x);
        break;
    case F_M_AMBIENT:
        o->material.ambient = fmax(v[0], 0);
        break;
    case F_M_DIFFUSE:
        o->material.diffuse = fmax(v[0], 0);
        break;
    case F_M_SPECULAR:
        o->material.specular = fmax(v[0], 0);
        break;
    case F_M_SHININESS:
        o->material.shininess = fmax(v[0], 0);
        break;
    case F_M_REFLECTANCE:
        o->material.reflectance = clampd(v[0], 0, 1);
        break;
    case F_M_TRANSPARENCY:
        o->material.transparency = clampd(v[0], 0, 1);
        break;
    default:
        return vv_error_set(VV_ERR_INVALID, "internal: unknown field %d", tg->field);
    }
    return VV_OK;
}

void
vv_anim_view_turn(vv_view *view, double azimuth, double elevation, double zoom) {
    if (azimuth != 0 || elevation != 0)
        vv_view_orbit(view, azimuth, elevation);
    if (zoom != 1) {
        vv_vec3 d = vv_vec3_sub(view->eye, view->at);
        view->eye = vv_vec3_add(view->at, vv_vec3_scale(d, 1.0 / zoom));
        view->ortho_height /= zoom;
    }
}

/* Sequence @p q at fraction num / den of the way (computed as a product
 * first, so frame k of N gives exactly DEG * k / N). */
static vv_status
apply_sequence(const vv_anim_sequence *q, vv_world *w, double num, double den) {
    switch (q->type) {
    case VV_SEQ_ORBIT: {
        double az = q->azimuth + q->degrees * num / den;
        vv_anim_view_turn(&w->view, vv_deg_to_rad(az), vv_deg_to_rad(q->elevation), q->zoom);
        return VV_OK;
    }
    case VV_SEQ_ROTATE_OBJECT: {
        vv_object *o = find_named(w, q->object);
        if (!o)
            return vv_error_set(VV_ERR_INVALID, "rotate_object: no object named '%s' in the World",
                                q->object);
        vv_box b = vv_object_world_box(o);
        vv_vec3 c = o->position;
        if (b.min.x <= b.max.x)
            c = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
        vv_quat r = vv_quat_from_axis_angle(q->axis, vv_deg_to_rad(q->degrees * num / den));
        o->orientation = vv_quat_normalize(vv_quat_mul(r, o->orientation));
        o->position = vv_vec3_add(c, vv_quat_rotate(r, vv_vec3_sub(o->position, c)));
        return VV_OK;
    }
    case VV_SEQ_FLY: {
        vv_vec3 d = vv_vec3_scale(q->offset, num / den);
        w->view.eye = vv_vec3_add(w->view.eye, d);
        w->view.at = vv_vec3_add(w->view.at, d);
        return VV_OK;
    }
    case VV_SEQ_SWEEP_CUT: {
        vv_vec3 n = vv_vec3_normalize(q->normal);
        vv_vec3 p = vv_vec3_add(q->point, vv_vec3_scale(n, q->distance * num / den));
        return vv_world_add_cut_plane(w, p, n);
    }
    }
    return vv_error_set(VV_ERR_INVALID, "unknown sequence type %d", (int)q->type);
}

static vv_status
apply_all(const vv_animation *a, vv_world *w, double time, double num, double den) {
    vv_tf *tfbuf = NULL;
    vv_status s = VV_OK;
    for (int i = 0; i < a->n_tracks && s == VV_OK; i++) {
        if (a->tracks[i].kind == VV_ANIM_TF && !tfbuf && !(tfbuf = malloc(sizeof *tfbuf)))
            return vv_error_set(VV_ERR_NOMEM, "animation: out of memory");
        s = apply_track(&a->tracks[i], w, time, tfbuf);
        if (s != VV_OK)
            s = vv_error_prefix(s, "animation: tracks[%d] %s", i, a->tracks[i].property);
    }
    free(tfbuf);
    for (int i = 0; i < a->n_sequences && s == VV_OK; i++) {
        s = apply_sequence(&a->sequences[i], w, num, den);
        if (s != VV_OK)
            s = vv_error_prefix(s, "animation: sequences[%d]", i);
    }
    return s;
}

vv_status
vv_animation_apply(const vv_animation *a, vv_world *world, double time) {
    if (!a || !world || !isfinite(time))
        return vv_error_set(VV_ERR_INVALID, "animation: no animation, no World or bad time");
    return apply_all(a, world, time, time, a->duration);
}

vv_status
vv_animation_eval(const vv_animation *a, const vv_world *base, double time, vv_world **out) {
    *out = NULL;
    if (!a || !base || !isfinite(time))
        return vv_error_set(VV_ERR_INVALID, "animation: no animation, no World or bad time");
    vv_world *w;
    vv_status s = vv_world_clone(&w, base);
    if (s != VV_OK)
        return s;
    if ((s = apply_all(a, w, time, time, a->duration)) != VV_OK) {
        vv_world_free(w);
        return s;
    }
    *out = w;
    return VV_OK;
}

vv_status
vv_animation_eval_frame(const vv_animation *a, const vv_world *base, int frame, vv_world **out) {
    *out = NULL;
    if (!a || !base)
        return vv_error_set(VV_ERR_INVALID, "animation: no animation or no World");
    int n = vv_animation_frame_count(a);
    if (frame < 0 || frame >= n)
        return vv_error_set(VV_ERR_INVALID, "animation: frame %d is outside 0..%d", frame, n - 1);
    vv_world *w;
    vv_status s = vv_world_clone(&w, base);
    if (s != VV_OK)
        return s;
    if ((s = apply_all(a, w, frame / a->fps, frame, n)) != VV_OK) {
        vv_world_free(w);
        return s;
    }
    *out = w;
    return VV_OK;
}
