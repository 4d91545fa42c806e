/*
 * Scene files, what every object carries: transfer functions (1-D and 2-D),
 * textures (images and solid textures), materials, the rendering mode,
 * the transform, the segmentation, local cut planes and the shading-effect
 * flags.
 */
#include <float.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "scene/scene_internal.h"
#include "volvis/io.h"
#include "volvis/model.h"

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

vv_status
vv_scene_parse_tf(const sctx *c, json_t *tfj, const char *tp, double unit, vv_tf *out) {
    static const char *const keys[] = {"opacity", "color", "opacity_unit_distance", NULL};
    vv_status st = vv_scene_check_keys(c, tfj, tp, keys);
    if (st != VV_OK)
        return st;
    if (!json_object_get(tfj, "opacity"))
        return vv_scene_missing(c, tp, "opacity", "[[value, opacity], ...]");
    vv_tf tf;
    vv_tf_init(&tf);
    tf.opacity_unit_distance = unit;
    if ((st = parse_tf_points(c, tfj, tp, &tf, 1)) != VV_OK ||
        (st = parse_tf_points(c, tfj, tp, &tf, 0)) != VV_OK ||
        (st = vv_scene_get_number_in(c, tfj, tp, "opacity_unit_distance", &tf.opacity_unit_distance,
                                     NULL, 0, 1, INFINITY, 1)) != VV_OK)
        return st;
    *out = tf;
    return VV_OK;
}

/* The opacity unit a transfer function without one takes: the object's
 * smallest voxel edge -- for an object out of core its level's, which
 * vv_object_attach_source set, not its proxy's. */
static double
default_unit(const vv_object *o, double set) {
    return o->source || !o->volume ? set : vv_tf_default_unit_distance(o->volume);
}

static vv_status
parse_tf(const sctx *c, json_t *tfj, const char *tp, vv_object *o) {
    return vv_scene_parse_tf(c, tfj, tp, default_unit(o, o->tf.opacity_unit_distance), &o->tf);
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
    tf.opacity_unit_distance = o->volume ? default_unit(o, o->tf2d.opacity_unit_distance) : 1.0;
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
vv_status
vv_scene_file_err(const sctx *c, vv_status st, const char *kp) {
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
    m.axis = vv_scene_unit(m.axis);
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
        return vv_scene_file_err(c, st, kp);
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
    s.axis = vv_scene_unit(s.axis);
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
            return vv_scene_file_err(c, st, kp);
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
vv_status
vv_scene_parse_effect_flags(const sctx *c, json_t *e, const char *op, vv_object *o) {
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

const char *const vv_scene_mode_names[VV_MODE_COUNT] = {"composite", "mip", "minip",
                                                        "xray",      "iso", "attenuated-mip"};

static vv_status
parse_mode(const sctx *c, const char *op, const char *s, vv_render_mode *out) {
    for (int i = 0; i < VV_MODE_COUNT; i++) {
        if (strcmp(s, vv_scene_mode_names[i]) == 0) {
            *out = (vv_render_mode)i;
            return VV_OK;
        }
    }
    char kp[PATH_MAX_LEN];
    vv_scene_path_key(kp, op, "mode");
    return vv_scene_serr(c, kp,
                         "unknown mode \"%s\"; expected composite, mip, minip, xray, iso or "
                         "attenuated-mip",
                         s);
}

/* "rotation" (axis-angle, degrees) or "orientation" (a quaternion), not both. */
static vv_status
parse_orientation(const sctx *c, json_t *e, const char *op, vv_object *o) {
    vv_status st;
    char kp[PATH_MAX_LEN];
    int has_rot, has_ori;
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
        double n2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3];
        if (!(n2 > 0.0))
            return vv_scene_serr(c, kp, "the zero quaternion is not a rotation");
        /* as vv_scene_unit: a unit quaternion (a saved one) is kept bit for bit */
        double n = fabs(n2 - 1.0) <= 8 * DBL_EPSILON ? 1.0 : sqrt(n2);
        o->orientation = (vv_quat){d[0] / n, d[1] / n, d[2] / n, d[3] / n};
    }

    return VV_OK;
}

/* "scale": a number (uniform) or [sx, sy, sz], all > 0. */
static vv_status
parse_scale(const sctx *c, json_t *e, const char *op, vv_object *o) {
    vv_status st;
    char kp[PATH_MAX_LEN];
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

    return VV_OK;
}

/* The segmentation (a 1-D or 2-D transfer function, a threshold, labels),
 * the textures, the material and the local cut planes. @p fd: the
 * defaults of an object of a file without an appearance of its own
 * (NULL: none); @p has_iso: an "isovalue" was given. */
static vv_status
parse_segmentation(const sctx *c, json_t *e, const char *op, vv_object *o,
                   const scene_file_defaults *fd, int has_iso) {
    vv_status st;
    char kp[PATH_MAX_LEN];
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
    } else if (o->volume && fd) {
        /* what the file opened alone shows, for the object's mode (known
         * only now; the door's when it sets every object's), its isovalue
         * unless one is given */
        const double iso = o->isovalue;
        const vv_render_mode mode = o->mode;
        if (c->over && c->over->has_mode)
            o->mode = c->over->mode;
        vv_object_default_appearance(o, fd->histogram, fd->shown);
        o->mode = mode; /* the door sets its own after loading */
        if (has_iso)
            o->isovalue = o->threshold = iso;
    } else if (o->volume) {
        /* the default TF depends on the mode, known only now */
        double iso_lo;
        vv_tf_default(&o->tf, o->volume, o->mode, &iso_lo);
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

/* Object fields other than the volume source (file, origin, spacing). */
vv_status
vv_scene_parse_object_fields(const sctx *c, json_t *e, const char *op, vv_object *o,
                             const scene_file_defaults *fd) {
    vv_status st;
    char kp[PATH_MAX_LEN];
    const char *mode = NULL;
    int has_iso;
    if ((st = vv_scene_get_string(c, e, op, "mode", &mode)) != VV_OK)
        return st;
    if (mode && (st = parse_mode(c, op, mode, &o->mode)) != VV_OK)
        return st;
    if ((st = vv_scene_get_number(c, e, op, "isovalue", &o->isovalue, &has_iso)) != VV_OK ||
        (st = vv_scene_get_number_in(c, e, op, "step", &o->step, NULL, 0, 1, INFINITY, 1)) !=
            VV_OK ||
        (st = vv_scene_get_number_in(c, e, op, "attenuation", &o->attenuation, NULL, 0, 0, INFINITY,
                                     1)) != VV_OK ||
        (st = vv_scene_get_bool(c, e, op, "shading", &o->shading)) != VV_OK ||
        (st = vv_scene_get_bool(c, e, op, "visible", &o->visible)) != VV_OK ||
        (st = vv_scene_get_vec3(c, e, op, "position", &o->position, NULL)) != VV_OK)
        return st;
    /* an object of a file without an appearance of its own takes the
     * file's defaults, a default isovalue among them */
    if (json_object_get(e, "transfer_function") || json_object_get(e, "segmentation") ||
        json_object_get(e, "tf2d") || !o->volume)
        fd = NULL;
    if (o->mode == VV_MODE_ISO && !has_iso && !fd) {
        vv_scene_path_key(kp, op, "mode");
        return vv_scene_serr(c, kp, "mode \"iso\" needs an \"isovalue\"");
    }
    if ((st = parse_orientation(c, e, op, o)) != VV_OK || (st = parse_scale(c, e, op, o)) != VV_OK)
        return st;
    return parse_segmentation(c, e, op, o, fd, has_iso);
}
