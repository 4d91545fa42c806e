/*
 * Scene files, the objects: volume objects (transfer functions, textures,
 * materials, modes, cut planes), geometric objects for the ray tracer,
 * geometry objects volume-sampled by Modeling, and grid objects.
 */
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "filter/filter_scene.h"
#include "model/model_internal.h"
#include "model/scene_internal.h"
#include "modeling/modeling_internal.h"
#include "volvis/io.h"
#include "volvis/model.h"
#include "volvis/modeling.h"

static vv_status
parse_tf_points(const sctx *c, json_t *tfj, const char *tp, vv_tf *tf, int opacity) {
    const char *key = opacity ? "opacity" : "color";
    json_t *arr;
    vv_status st = vv_scene_get_array(c, tfj, tp, key, &arr);
    if (st != VV_OK || !arr)
        return st;
    char ap[PATH_MAX_LEN];
    vv_scene_path_key(ap, tp, key);
    if (json_array_size(arr) > VV_TF_MAX_POINTS)
        return vv_scene_serr(c, ap, "more than %d points", VV_TF_MAX_POINTS);
    size_t i;
    json_t *e;
    json_array_foreach(arr, i, e) {
        char ep[PATH_MAX_LEN];
        vv_scene_path_index(ep, ap, i);
        if (!json_is_array(e) || json_array_size(e) != 2)
            return vv_scene_serr(c, ep, "expected a pair [value, %s], got %s",
                                 opacity ? "opacity" : "[r, g, b]", vv_json_kind(e));
        char vp[PATH_MAX_LEN], op[PATH_MAX_LEN];
        vv_scene_path_index(vp, ep, 0);
        vv_scene_path_index(op, ep, 1);
        double value = 0.0;
        if ((st = vv_scene_value_number(c, json_array_get(e, 0), vp, &value)) != VV_OK)
            return st;
        if (opacity) {
            double a = 0.0;
            if ((st = vv_scene_value_number(c, json_array_get(e, 1), op, &a)) != VV_OK)
                return st;
            if (!(a >= 0.0 && a <= 1.0))
                return vv_scene_serr(c, op, "opacity %g is outside [0, 1]", a);
            if (vv_tf_add_opacity(tf, value, a) != VV_OK)
                return vv_scene_serr(c, ep, "%s", vv_error_message());
        } else {
            vv_vec3 col;
            if ((st = vv_scene_value_color(c, json_array_get(e, 1), op, &col)) != VV_OK)
                return st;
            if (vv_tf_add_color(tf, value, col) != VV_OK)
                return vv_scene_serr(c, ep, "%s", vv_error_message());
        }
    }
    return VV_OK;
}

static vv_status
parse_tf(const sctx *c, json_t *tfj, const char *tp, vv_object *o) {
    static const char *const keys[] = {"opacity", "color", "opacity_unit_distance", NULL};
    vv_status st = vv_scene_check_keys(c, tfj, tp, keys);
    if (st != VV_OK)
        return st;
    if (!json_object_get(tfj, "opacity"))
        return vv_scene_missing(c, tp, "opacity", "[[value, opacity], ...]");
    vv_tf tf;
    vv_tf_init(&tf);
    tf.opacity_unit_distance =
        o->volume ? vv_model_min_spacing(o->volume) : o->tf.opacity_unit_distance;
    if ((st = parse_tf_points(c, tfj, tp, &tf, 1)) != VV_OK ||
        (st = parse_tf_points(c, tfj, tp, &tf, 0)) != VV_OK ||
        (st = vv_scene_get_number_in(c, tfj, tp, "opacity_unit_distance", &tf.opacity_unit_distance,
                                     NULL, 0, 1, INFINITY, 1)) != VV_OK)
        return st;
    o->tf = tf;
    return VV_OK;
}

/* An optional [a, b] pair of numbers. */
static vv_status
get_pair(const sctx *c, json_t *obj, const char *path, const char *key, double out[2],
         int *present) {
    char kp[PATH_MAX_LEN];
    json_t *v = vv_scene_field(obj, key, kp, path, present);
    if (!v)
        return VV_OK;
    if (!json_is_array(v) || json_array_size(v) != 2)
        return vv_scene_serr(c, kp, "expected an array of 2 numbers, got %s%s", vv_json_kind(v),
                             json_is_array(v) ? " of another length" : "");
    for (size_t i = 0; i < 2; i++) {
        char ip[PATH_MAX_LEN];
        vv_scene_path_index(ip, kp, i);
        vv_status st = vv_scene_value_number(c, json_array_get(v, i), ip, &out[i]);
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
        return vv_scene_serr(c, wp, "expected a widget object, got %s", vv_json_kind(e));
    const char *shape = NULL;
    vv_status st = vv_scene_get_string(c, e, wp, "shape", &shape);
    if (st != VV_OK)
        return st;
    if (!shape)
        return vv_scene_missing(c, wp, "shape", "\"rectangle\" or \"triangle\"");
    char kp[PATH_MAX_LEN];
    int has_a, has_b, has_c;
    if (strcmp(shape, "rectangle") == 0) {
        vv_tf2d_widget_init_rectangle(w, 0, 0, 0, 0, vv_vec3_make(1, 1, 1), 1.0);
        if ((st = vv_scene_check_keys(c, e, wp, rkeys)) != VV_OK ||
            (st = get_pair(c, e, wp, "value", w->value, &has_a)) != VV_OK ||
            (st = get_pair(c, e, wp, "gradient", w->gradient, &has_b)) != VV_OK ||
            (st = vv_scene_get_number(c, e, wp, "ramp", &w->ramp, NULL)) != VV_OK ||
            (st = vv_scene_get_number(c, e, wp, "gradient_ramp", &w->gradient_ramp, NULL)) != VV_OK)
            return st;
        if (!has_a)
            return vv_scene_missing(c, wp, "value", "[lo, hi] data values");
        if (!has_b)
            return vv_scene_missing(c, wp, "gradient", "[lo, hi] gradient magnitudes");
        w->center = 0.5 * (w->value[0] + w->value[1]);
        w->width = w->value[1] - w->value[0];
    } else if (strcmp(shape, "triangle") == 0) {
        vv_tf2d_widget_init_triangle(w, 0, 1, 1, vv_vec3_make(1, 1, 1), 1.0);
        if ((st = vv_scene_check_keys(c, e, wp, tkeys)) != VV_OK ||
            (st = vv_scene_get_number(c, e, wp, "center", &w->center, &has_a)) != VV_OK ||
            (st = vv_scene_get_number(c, e, wp, "width", &w->width, &has_b)) != VV_OK ||
            (st = get_pair(c, e, wp, "gradient", w->gradient, &has_c)) != VV_OK)
            return st;
        if (!has_a)
            return vv_scene_missing(c, wp, "center", "the apex data value");
        if (!has_b)
            return vv_scene_missing(c, wp, "width", "the base width at gradient[1], data units");
        if (!has_c)
            return vv_scene_missing(c, wp, "gradient", "[lo, hi] gradient magnitudes");
        w->value[0] = w->center - 0.5 * w->width;
        w->value[1] = w->center + 0.5 * w->width;
    } else {
        vv_scene_path_key(kp, wp, "shape");
        return vv_scene_serr(c, kp, "unknown widget shape \"%s\"; expected rectangle or triangle",
                             shape);
    }
    if ((st = vv_scene_get_color(c, e, wp, "color", &w->color, NULL)) != VV_OK ||
        (st = vv_scene_get_number(c, e, wp, "opacity", &w->opacity, NULL)) != VV_OK)
        return st;
    vv_error_clear();
    if (vv_tf2d_widget_check(w) != VV_OK)
        return vv_scene_serr(c, wp, "%s", vv_error_message());
    return VV_OK;
}

static vv_status
parse_tf2d(const sctx *c, json_t *tj, const char *tp, vv_object *o) {
    static const char *const keys[] = {"widgets", "opacity_unit_distance", NULL};
    vv_status st = vv_scene_check_keys(c, tj, tp, keys);
    if (st != VV_OK)
        return st;
    json_t *arr;
    if ((st = vv_scene_get_array(c, tj, tp, "widgets", &arr)) != VV_OK)
        return st;
    if (!arr)
        return vv_scene_missing(c, tp, "widgets", "[{\"shape\": ...}, ...]");
    char ap[PATH_MAX_LEN];
    vv_scene_path_key(ap, tp, "widgets");
    if (json_array_size(arr) > VV_TF2D_MAX_WIDGETS)
        return vv_scene_serr(c, ap, "more than %d widgets", VV_TF2D_MAX_WIDGETS);
    vv_tf2d tf;
    vv_tf2d_init(&tf);
    tf.opacity_unit_distance = o->volume ? vv_model_min_spacing(o->volume) : 1.0;
    size_t i;
    json_t *e;
    json_array_foreach(arr, i, e) {
        char wp[PATH_MAX_LEN];
        vv_scene_path_index(wp, ap, i);
        if ((st = parse_tf2d_widget(c, e, wp, &tf.widgets[tf.n_widgets])) != VV_OK)
            return st;
        tf.n_widgets++;
    }
    if ((st = vv_scene_get_number_in(c, tj, tp, "opacity_unit_distance", &tf.opacity_unit_distance,
                                     NULL, 0, 1, INFINITY, 1)) != VV_OK)
        return st;
    o->tf2d = tf;
    return VV_OK;
}

/* A file named relative to the scene file, for error messages at its key. */
static vv_status
file_err(const sctx *c, vv_status st, const char *kp) {
    int line, col;
    vv_scene_locate(c, kp, &line, &col);
    return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
}

static vv_status
parse_texture(const sctx *c, json_t *tj, const char *tp, vv_object *o) {
    static const char *const keys[] = {"image", "projection", "center", "axis", "scale", NULL};
    vv_status st = vv_scene_check_keys(c, tj, tp, keys);
    if (st != VV_OK)
        return st;
    const char *file = NULL, *proj = NULL;
    vv_texture_map m;
    vv_texture_map_init(&m);
    double sc[2] = {1, 1};
    char kp[PATH_MAX_LEN];
    if ((st = vv_scene_get_string(c, tj, tp, "image", &file)) != VV_OK ||
        (st = vv_scene_get_string(c, tj, tp, "projection", &proj)) != VV_OK ||
        (st = vv_scene_get_vec3(c, tj, tp, "center", &m.center, NULL)) != VV_OK ||
        (st = vv_scene_get_nonzero_vec3(c, tj, tp, "axis", &m.axis, NULL)) != VV_OK ||
        (st = get_pair(c, tj, tp, "scale", sc, NULL)) != VV_OK)
        return st;
    if (!file)
        return vv_scene_missing(c, tp, "image", "a PNG file, relative to the scene file");
    if (proj && vv_texture_projection_parse(proj, &m.projection) != VV_OK) {
        vv_scene_path_key(kp, tp, "projection");
        return vv_scene_serr(
            c, kp, "unknown projection \"%s\"; expected planar, cylindrical or spherical", proj);
    }
    if (!(sc[0] != 0 && sc[1] != 0)) {
        vv_scene_path_key(kp, tp, "scale");
        return vv_scene_serr(c, kp, "scale factors must not be 0");
    }
    m.axis = vv_vec3_normalize(m.axis);
    m.scale[0] = sc[0];
    m.scale[1] = sc[1];
    vv_scene_path_key(kp, tp, "image");
    if (!file[0])
        return vv_scene_serr(c, kp, "empty file name");
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
    vv_status st = vv_scene_check_keys(c, tj, tp, keys);
    if (st != VV_OK)
        return st;
    const char *proc = NULL, *file = NULL;
    char kp[PATH_MAX_LEN];
    vv_solid_texture s;
    vv_solid_texture_init(&s);
    double seed = 1;
    if ((st = vv_scene_get_string(c, tj, tp, "procedural", &proc)) != VV_OK ||
        (st = vv_scene_get_string(c, tj, tp, "volume", &file)) != VV_OK ||
        (st = vv_scene_get_number_in(c, tj, tp, "period", &s.period, NULL, 0, 1, INFINITY, 1)) !=
            VV_OK ||
        (st = vv_scene_get_vec3(c, tj, tp, "center", &s.center, NULL)) != VV_OK ||
        (st = vv_scene_get_nonzero_vec3(c, tj, tp, "axis", &s.axis, NULL)) != VV_OK ||
        (st = vv_scene_get_number_in(c, tj, tp, "turbulence", &s.turbulence, NULL, 0, 0, INFINITY,
                                     1)) != VV_OK ||
        (st = vv_scene_get_number_in(c, tj, tp, "seed", &seed, NULL, 0, 0, 4294967295.0, 0)) !=
            VV_OK ||
        (st = vv_scene_get_color(c, tj, tp, "color0", &s.color0, NULL)) != VV_OK ||
        (st = vv_scene_get_color(c, tj, tp, "color1", &s.color1, NULL)) != VV_OK)
        return st;
    if (seed != floor(seed)) {
        vv_scene_path_key(kp, tp, "seed");
        return vv_scene_serr(c, kp, "expected an integer, got %g", seed);
    }
    s.seed = (unsigned)seed;
    s.axis = vv_vec3_normalize(s.axis);
    if ((proc != NULL) == (file != NULL))
        return vv_scene_serr(c, tp,
                             "give exactly one of \"procedural\" (checker3d, wood, marble) and "
                             "\"volume\" (a volume file)");
    if (proc) {
        vv_scene_path_key(kp, tp, "procedural");
        if (strcmp(proc, "checker3d") == 0)
            s.kind = VV_SOLID_TEXTURE_CHECKER;
        else if (strcmp(proc, "wood") == 0)
            s.kind = VV_SOLID_TEXTURE_WOOD;
        else if (strcmp(proc, "marble") == 0)
            s.kind = VV_SOLID_TEXTURE_MARBLE;
        else
            return vv_scene_serr(c, kp,
                                 "unknown procedural texture \"%s\"; expected checker3d, wood or "
                                 "marble",
                                 proc);
    } else {
        vv_scene_path_key(kp, tp, "volume");
        if (!file[0])
            return vv_scene_serr(c, kp, "empty file name");
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
    if ((st = vv_scene_get_number_in(c, m, mp, "reflectance", &mat->reflectance, NULL, 0, 0, 1,
                                     0)) != VV_OK ||
        (st = vv_scene_get_number_in(c, m, mp, "transparency", &mat->transparency, NULL, 0, 0, 1,
                                     0)) != VV_OK ||
        (st = vv_scene_get_number_in(c, m, mp, "ior", &mat->ior, NULL, 0, 1, INFINITY, 1)) != VV_OK)
        return st;
    /* radiosity: light emitted, each component >= 0 (may exceed 1) */
    int here = 0;
    vv_vec3 em = mat->emission;
    if ((st = vv_scene_get_vec3(c, m, mp, "emission", &em, &here)) != VV_OK)
        return st;
    if (here) {
        if (!(isfinite(em.x) && isfinite(em.y) && isfinite(em.z) && em.x >= 0 && em.y >= 0 &&
              em.z >= 0)) {
            char kp[PATH_MAX_LEN];
            vv_scene_path_key(kp, mp, "emission");
            return vv_scene_serr(c, kp, "expected three finite numbers >= 0");
        }
        mat->emission = em;
    }
    return VV_OK;
}

/* The per-object shading-effect flags (every object type). */
static vv_status
parse_effect_flags(const sctx *c, json_t *e, const char *op, vv_object *o) {
    vv_status st;
    if ((st = vv_scene_get_bool(c, e, op, "casts_shadows", &o->casts_shadows)) != VV_OK ||
        (st = vv_scene_get_bool(c, e, op, "receives_shadows", &o->receives_shadows)) != VV_OK ||
        (st = vv_scene_get_bool(c, e, op, "visible_in_reflections", &o->visible_in_reflections)) !=
            VV_OK ||
        (st = vv_scene_get_bool(c, e, op, "reflects", &o->reflects)) != VV_OK)
        return st;
    return VV_OK;
}

static vv_status
parse_material(const sctx *c, json_t *m, const char *mp, vv_material *mat) {
    static const char *const keys[] = {"ambient",  "diffuse",     "specular",     "shininess",
                                       "color",    "reflectance", "transparency", "ior",
                                       "emission", NULL};
    vv_status st = vv_scene_check_keys(c, m, mp, keys);
    if (st != VV_OK)
        return st;
    if ((st = vv_scene_get_number_in(c, m, mp, "ambient", &mat->ambient, NULL, 0, 0, INFINITY,
                                     1)) != VV_OK ||
        (st = vv_scene_get_number_in(c, m, mp, "diffuse", &mat->diffuse, NULL, 0, 0, INFINITY,
                                     1)) != VV_OK ||
        (st = vv_scene_get_number_in(c, m, mp, "specular", &mat->specular, NULL, 0, 0, INFINITY,
                                     1)) != VV_OK ||
        (st = vv_scene_get_number_in(c, m, mp, "shininess", &mat->shininess, NULL, 0, 0, INFINITY,
                                     1)) != VV_OK ||
        (st = vv_scene_get_color(c, m, mp, "color", &mat->color, NULL)) != VV_OK)
        return st;
    return parse_material_global(c, m, mp, mat);
}

const char *const vv_scene_mode_names[5] = {"composite", "mip", "minip", "xray", "iso"};

static vv_status
parse_mode(const sctx *c, const char *op, const char *s, vv_render_mode *out) {
    for (int i = 0; i < 5; i++) {
        if (strcmp(s, vv_scene_mode_names[i]) == 0) {
            *out = (vv_render_mode)i;
            return VV_OK;
        }
    }
    char kp[PATH_MAX_LEN];
    vv_scene_path_key(kp, op, "mode");
    return vv_scene_serr(c, kp, "unknown mode \"%s\"; expected composite, mip, minip, xray or iso",
                         s);
}

/* Object fields other than the volume source (file, origin, spacing). */
static vv_status
parse_object_fields(const sctx *c, json_t *e, const char *op, vv_object *o) {
    vv_status st;
    char kp[PATH_MAX_LEN];
    const char *mode = NULL;
    int has_iso, has_rot, has_ori;
    if ((st = vv_scene_get_string(c, e, op, "mode", &mode)) != VV_OK)
        return st;
    if (mode && (st = parse_mode(c, op, mode, &o->mode)) != VV_OK)
        return st;
    if ((st = vv_scene_get_number(c, e, op, "isovalue", &o->isovalue, &has_iso)) != VV_OK ||
        (st = vv_scene_get_number_in(c, e, op, "step", &o->step, NULL, 0, 1, INFINITY, 1)) !=
            VV_OK ||
        (st = vv_scene_get_bool(c, e, op, "shading", &o->shading)) != VV_OK ||
        (st = vv_scene_get_bool(c, e, op, "visible", &o->visible)) != VV_OK ||
        (st = vv_scene_get_vec3(c, e, op, "position", &o->position, NULL)) != VV_OK)
        return st;
    if (o->mode == VV_MODE_ISO && !has_iso) {
        vv_scene_path_key(kp, op, "mode");
        return vv_scene_serr(c, kp, "mode \"iso\" needs an \"isovalue\"");
    }

    /* rotation (axis-angle, degrees) or orientation (quaternion) */
    json_t *rot;
    if ((st = vv_scene_get_object(c, e, op, "rotation", &rot)) != VV_OK)
        return st;
    has_rot = rot != NULL;
    has_ori = json_object_get(e, "orientation") != NULL;
    if (has_rot && has_ori) {
        vv_scene_path_key(kp, op, "orientation");
        return vv_scene_serr(c, kp, "give either \"rotation\" or \"orientation\", not both");
    }
    if (rot) {
        static const char *const rkeys[] = {"axis", "angle", NULL};
        char rp[PATH_MAX_LEN];
        vv_scene_path_key(rp, op, "rotation");
        vv_vec3 axis = {0, 0, 1};
        double angle = 0.0;
        int ha, hg;
        if ((st = vv_scene_check_keys(c, rot, rp, rkeys)) != VV_OK ||
            (st = vv_scene_get_nonzero_vec3(c, rot, rp, "axis", &axis, &ha)) != VV_OK ||
            (st = vv_scene_get_number(c, rot, rp, "angle", &angle, &hg)) != VV_OK)
            return st;
        if (!ha)
            return vv_scene_missing(c, rp, "axis", "the rotation axis [x, y, z]");
        if (!hg)
            return vv_scene_missing(c, rp, "angle", "degrees");
        o->orientation = vv_quat_from_axis_angle(axis, vv_deg_to_rad(angle));
    }
    if (has_ori) {
        json_t *q = json_object_get(e, "orientation");
        vv_scene_path_key(kp, op, "orientation");
        if (!json_is_array(q) || json_array_size(q) != 4)
            return vv_scene_serr(c, kp, "expected a quaternion [w, x, y, z], got %s",
                                 vv_json_kind(q));
        double d[4];
        for (size_t i = 0; i < 4; i++) {
            char ip[PATH_MAX_LEN];
            vv_scene_path_index(ip, kp, i);
            if ((st = vv_scene_value_number(c, json_array_get(q, i), ip, &d[i])) != VV_OK)
                return st;
        }
        double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
        if (!(n > 0.0))
            return vv_scene_serr(c, kp, "the zero quaternion is not a rotation");
        o->orientation = (vv_quat){d[0] / n, d[1] / n, d[2] / n, d[3] / n};
    }

    /* scale: a number (uniform) or [sx, sy, sz], all > 0 */
    json_t *sc = json_object_get(e, "scale");
    if (sc) {
        vv_scene_path_key(kp, op, "scale");
        vv_vec3 s;
        if (json_is_number(sc)) {
            double u = json_number_value(sc);
            s = vv_vec3_make(u, u, u);
        } else if ((st = vv_scene_value_vec3(c, sc, kp, &s)) != VV_OK) {
            return st;
        }
        if (!(s.x > 0.0 && s.y > 0.0 && s.z > 0.0))
            return vv_scene_serr(c, kp, "scale factors must be > 0");
        o->scale = s;
    }

    /* segmentation: a transfer function (1-D or 2-D) or a threshold */
    json_t *tfj, *seg = NULL, *mat, *cuts, *tf2j, *texj, *soj;
    const char *seg_name = NULL;
    json_t *segv = json_object_get(e, "segmentation");
    if (segv && json_is_string(segv)) {
        seg_name = json_string_value(segv);
    } else if ((st = vv_scene_get_object(c, e, op, "segmentation", &seg)) != VV_OK) {
        vv_scene_path_key(kp, op, "segmentation");
        return vv_scene_serr(
            c, kp, "expected {\"threshold\": value}, \"transfer_function\" or \"tf2d\", got %s",
            vv_json_kind(segv));
    }
    if ((st = vv_scene_get_object(c, e, op, "transfer_function", &tfj)) != VV_OK ||
        (st = vv_scene_get_object(c, e, op, "tf2d", &tf2j)) != VV_OK ||
        (st = vv_scene_get_object(c, e, op, "texture", &texj)) != VV_OK ||
        (st = vv_scene_get_object(c, e, op, "solid_texture", &soj)) != VV_OK ||
        (st = vv_scene_get_object(c, e, op, "material", &mat)) != VV_OK ||
        (st = vv_scene_get_array(c, e, op, "cut_planes", &cuts)) != VV_OK)
        return st;
    if (seg_name) {
        vv_scene_path_key(kp, op, "segmentation");
        if (strcmp(seg_name, "tf2d") == 0) {
            if (!tf2j)
                return vv_scene_serr(c, kp, "segmentation \"tf2d\" needs a \"tf2d\" object");
            o->segmentation = VV_SEG_TRANSFER_FUNCTION_2D;
        } else if (strcmp(seg_name, "transfer_function") == 0) {
            o->segmentation = VV_SEG_TRANSFER_FUNCTION;
        } else if (strcmp(seg_name, "labels") == 0) {
            o->segmentation = VV_SEG_LABELS;
        } else {
            return vv_scene_serr(c, kp,
                                 "unknown segmentation \"%s\"; expected \"transfer_function\", "
                                 "\"tf2d\", \"labels\" or {\"threshold\": value}",
                                 seg_name);
        }
    }
    if (tf2j) {
        vv_scene_path_key(kp, op, "tf2d");
        if ((st = parse_tf2d(c, tf2j, kp, o)) != VV_OK)
            return st;
    }
    if (texj) {
        vv_scene_path_key(kp, op, "texture");
        if ((st = parse_texture(c, texj, kp, o)) != VV_OK)
            return st;
    }
    if (soj) {
        vv_scene_path_key(kp, op, "solid_texture");
        if ((st = parse_solid_texture(c, soj, kp, o)) != VV_OK)
            return st;
    }
    if (tfj && seg) {
        vv_scene_path_key(kp, op, "segmentation");
        return vv_scene_serr(c, kp,
                             "give either \"transfer_function\" or \"segmentation\", not both");
    }
    if (tfj) {
        vv_scene_path_key(kp, op, "transfer_function");
        if ((st = parse_tf(c, tfj, kp, o)) != VV_OK)
            return st;
    } else if (o->volume) {
        /* the default TF depends on the mode, known only now */
        double iso_lo;
        vv_model_default_tf(o->volume, o->mode, &o->tf, &iso_lo);
    }
    if (seg) {
        static const char *const skeys[] = {"threshold", NULL};
        vv_scene_path_key(kp, op, "segmentation");
        int ht;
        if ((st = vv_scene_check_keys(c, seg, kp, skeys)) != VV_OK ||
            (st = vv_scene_get_number(c, seg, kp, "threshold", &o->threshold, &ht)) != VV_OK)
            return st;
        if (!ht)
            return vv_scene_missing(c, kp, "threshold",
                                    "the data value from which voxels are opaque");
        o->segmentation = VV_SEG_THRESHOLD;
    }
    if (mat) {
        vv_scene_path_key(kp, op, "material");
        if ((st = parse_material(c, mat, kp, &o->material)) != VV_OK)
            return st;
    }
    if (cuts) {
        vv_scene_path_key(kp, op, "cut_planes");
        if ((st = vv_scene_parse_cut_planes(c, cuts, kp, o->cut_planes, &o->n_cut_planes)) != VV_OK)
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
        if ((st = vv_scene_get_vec3(c, e, op, "point", &g->point, NULL)) != VV_OK ||
            (st = vv_scene_get_nonzero_vec3(c, e, op, "normal", &g->normal, NULL)) != VV_OK)
            return st;
        g->normal = vv_vec3_normalize(g->normal);
        return VV_OK;
    case VV_OBJECT_SPHERE:
        return (st = vv_scene_get_vec3(c, e, op, "center", &g->center, NULL)) != VV_OK
                   ? st
                   : vv_scene_get_number_in(c, e, op, "radius", &g->radius, NULL, 0, 1, INFINITY,
                                            1);
    case VV_OBJECT_BOX: {
        vv_box b = g->box;
        if ((st = vv_scene_get_vec3(c, e, op, "min", &b.min, &has_a)) != VV_OK ||
            (st = vv_scene_get_vec3(c, e, op, "max", &b.max, &has_b)) != VV_OK)
            return st;
        if (!(b.min.x < b.max.x && b.min.y < b.max.y && b.min.z < b.max.z)) {
            vv_scene_path_key(kp, op, "max");
            return vv_scene_serr(c, kp, "each coordinate must be greater than in \"min\"");
        }
        g->box = b;
        return VV_OK;
    }
    case VV_OBJECT_CYLINDER:
        if ((st = vv_scene_get_vec3(c, e, op, "base", &g->base, NULL)) != VV_OK ||
            (st = vv_scene_get_vec3(c, e, op, "top", &g->top, NULL)) != VV_OK ||
            (st = vv_scene_get_number_in(c, e, op, "radius", &g->radius, NULL, 0, 1, INFINITY,
                                         1)) != VV_OK ||
            (st = vv_scene_get_bool(c, e, op, "capped", &g->capped)) != VV_OK)
            return st;
        if (!(vv_vec3_length(vv_vec3_sub(g->top, g->base)) > 0)) {
            vv_scene_path_key(kp, op, "top");
            return vv_scene_serr(c, kp, "the cylinder's top must differ from its base");
        }
        return VV_OK;
    case VV_OBJECT_POLYGON: {
        json_t *arr;
        if ((st = vv_scene_get_array(c, e, op, "vertices", &arr)) != VV_OK)
            return st;
        if (!arr)
            return vv_scene_missing(c, op, "vertices",
                                    "[[x, y, z], ...], at least 3, in one plane");
        vv_scene_path_key(kp, op, "vertices");
        size_t n = json_array_size(arr);
        if (n < 3 || n > 100000)
            return vv_scene_serr(c, kp, "expected 3 to 100000 vertices, got %zu", n);
        vv_vec3 *v = malloc(n * sizeof *v);
        if (!v)
            return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
        for (size_t i = 0; i < n; i++) {
            char ip[PATH_MAX_LEN];
            vv_scene_path_index(ip, kp, i);
            if ((st = vv_scene_value_vec3(c, json_array_get(arr, i), ip, &v[i])) != VV_OK) {
                free(v);
                return st;
            }
        }
        vv_error_clear();
        st = vv_object_set_polygon(o, (int)n, v);
        free(v);
        if (st != VV_OK) {
            int line, col;
            vv_scene_locate(c, kp, &line, &col);
            return vv_error_prefix(VV_ERR_FORMAT, "%s:%d:%d: %s", c->path, line, col, kp);
        }
        return VV_OK;
    }
    case VV_OBJECT_MESH: {
        const char *file = NULL;
        if ((st = vv_scene_get_string(c, e, op, "file", &file)) != VV_OK)
            return st;
        if (!file)
            return vv_scene_missing(c, op, "file",
                                    "the mesh file (OBJ, PLY, STL, ...), relative to the "
                                    "scene file");
        vv_scene_path_key(kp, op, "file");
        if (!file[0])
            return vv_scene_serr(c, kp, "empty file name");
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
            vv_scene_locate(c, kp, &line, &col);
            return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
        }
        return VV_OK;
    }
    default:
        return vv_scene_serr(c, op, "not a geometric object");
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
    return vv_scene_check_keys(c, e, op, keys);
}

/* The optional "name" of object @p e, at most VV_NAME_MAX - 1 bytes. */
static vv_status
get_object_name(const sctx *c, json_t *e, const char *op, const char **name) {
    vv_status st = vv_scene_get_string(c, e, op, "name", name);
    if (st == VV_OK && *name && strlen(*name) >= VV_NAME_MAX) {
        char kp[PATH_MAX_LEN];
        vv_scene_path_key(kp, op, "name");
        return vv_scene_serr(c, kp, "longer than %d bytes", VV_NAME_MAX - 1);
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
    vv_scene_locate(c, path, &line, &col);
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
        vv_scene_path_key(kp, op, "csg");
        return vv_scene_serr(c, kp, "give either \"primitive\" or \"csg\", not both");
    }
    if (!prim && !csg)
        return vv_scene_missing(c, op, "primitive",
                                "a primitive {\"type\": ...} or a \"csg\" tree {\"op\": ...}");
    vv_scene_path_key(kp, op, prim ? "primitive" : "csg");
    if (csg && !json_object_get(csg, "op"))
        return vv_scene_serr(c, kp, "expected a CSG operation {\"op\": ..., \"children\": [...]}");
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
        (st = vv_scene_get_string(c, e, op, "file", &file)) != VV_OK ||
        (st = vv_scene_get_string(c, e, op, "field", &field)) != VV_OK ||
        (st = vv_scene_get_int_in(c, e, op, "component", &component, -1, 8)) != VV_OK ||
        (st = vv_scene_get_int_in(c, e, op, "time", &time, 0, 1000000)) != VV_OK)
        return st;
    if (!file)
        return vv_scene_missing(
            c, op, "file",
            "the grid file (VTK, .vtu, OpenDX, PLOT3D, NetCDF), relative to the "
            "scene file");
    vv_scene_path_key(kp, op, "file");
    if (!file[0])
        return vv_scene_serr(c, kp, "empty file name");
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
        vv_scene_locate(c, kp, &line, &col);
        return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
    }
    o->geometry.source = full;
    o->component = component;
    o->time = time;
    if (field)
        snprintf(o->field, sizeof o->field, "%s", field);
    if (vv_object_grid_field(o) < 0 && o->grid->n_fields > 0) {
        vv_scene_path_key(kp, op, field ? "field" : "time");
        char msg[512];
        snprintf(msg, sizeof msg, "%s", vv_error_message());
        vv_object_free(o);
        return vv_scene_serr(c, kp, "%s", msg);
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

vv_status
vv_scene_parse_object(const sctx *c, json_t *e, size_t idx, vv_world *w) {
    static const char *const own[] = {"file", "origin", "spacing", "filters", NULL};
    char op[PATH_MAX_LEN], kp[PATH_MAX_LEN];
    vv_scene_path_index(op, "objects", idx);
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
        return vv_scene_serr(c, op, "expected an object, got %s", vv_json_kind(e));
    vv_status st = check_object_keys(c, e, op, own, 1);
    if (st != VV_OK)
        return st;
    const char *type = "volume", *name = NULL, *file = NULL;
    if ((st = vv_scene_get_string(c, e, op, "type", &type)) != VV_OK ||
        (st = get_object_name(c, e, op, &name)) != VV_OK ||
        (st = vv_scene_get_string(c, e, op, "file", &file)) != VV_OK)
        return st;
    if (strcmp(type, "volume") != 0) {
        vv_scene_path_key(kp, op, "type");
        return vv_scene_serr(
            c, kp,
            "unsupported object type \"%s\"; expected volume, grid, geometry, plane, "
            "polygon, sphere, box, cylinder or mesh",
            type);
    }
    if (!file)
        return vv_scene_missing(c, op, "file", "the volume file, relative to the scene file");
    vv_scene_path_key(kp, op, "file");
    if (!file[0])
        return vv_scene_serr(c, kp, "empty file name");
    vv_vec3 origin, spacing;
    int has_origin, has_spacing;
    if ((st = vv_scene_get_vec3(c, e, op, "origin", &origin, &has_origin)) != VV_OK ||
        (st = vv_scene_get_vec3(c, e, op, "spacing", &spacing, &has_spacing)) != VV_OK)
        return st;
    if (has_spacing && !(spacing.x > 0.0 && spacing.y > 0.0 && spacing.z > 0.0)) {
        vv_scene_path_key(kp, op, "spacing");
        return vv_scene_serr(c, kp, "voxel spacing must be > 0");
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
        vv_scene_path_key(kp, op, "filters");
        if ((st = vf_chain_from_json(fj, &chain, &bad)) != VV_OK) {
            char msg[512], ip[PATH_MAX_LEN];
            snprintf(msg, sizeof msg, "%s", vv_error_message());
            free(full);
            if (bad >= 0)
                vv_scene_path_index(ip, kp, (size_t)bad);
            return vv_scene_serr(c, bad >= 0 ? ip : kp, "%s", msg);
        }
        double o3[3] = {origin.x, origin.y, origin.z}, s3[3] = {spacing.x, spacing.y, spacing.z};
        vv_filter_options fo;
        vv_filter_options_init(&fo);
        if (c->progress)
            fo.progress = *c->progress; /* and its cancel */
        st = vv_filter_load_cached(c->fcache, full, has_origin ? o3 : NULL, has_spacing ? s3 : NULL,
                                   chain, &fo, &vol);
    } else {
        st = vv_volume_load(&vol, full, NULL);
    }
    if (st != VV_OK) {
        vv_filter_chain_free(chain);
        free(full);
        int line, col;
        vv_scene_path_key(kp, op, fj ? "filters" : "file");
        vv_scene_locate(c, kp, &line, &col);
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
