/*
 * Model trees in scene files (docs/scene-format.md, "Geometry objects"):
 * primitives {"type": "sphere", "radius": 10, ...} and operations
 * {"op": "difference", "children": [...]}, each with an optional transform
 * ("translate", "rotate", "scale"). Also vv_shape_load, which reads a mesh
 * file or the geometry objects of a scene file into one model.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "modeling/modeling_internal.h"

#define JPATH 256

typedef struct jctx {
    const char *scene_path;
    char *err_path;
    size_t cap;
} jctx;

/* dst = a + b + c, truncated to JPATH - 1 bytes (a truncated path only makes
 * an error position less precise) */
static void
pcat(char *dst, const char *a, const char *b, const char *c) {
    size_t k = 0;
    const char *parts[3] = {a, b, c};
    for (int p = 0; p < 3; p++)
        for (const char *q = parts[p]; q && *q && k + 1 < JPATH; q++)
            dst[k++] = *q;
    dst[k] = '\0';
}

static void
kpath(char *dst, const char *parent, const char *key) {
    pcat(dst, parent, parent && parent[0] ? "." : "", key);
}

static void
ipath(char *dst, const char *parent, size_t i) {
    char idx[32];
    snprintf(idx, sizeof idx, "[%zu]", i);
    pcat(dst, parent, idx, "");
}

static vv_status jfail(const jctx *c, const char *path, vv_status st, const char *fmt, ...)
    VV_PRINTF(4, 5);

static vv_status
jfail(const jctx *c, const char *path, vv_status st, const char *fmt, ...) {
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (c->err_path && c->cap) {
        snprintf(c->err_path, c->cap, "%s", path);
    }
    return vv_error_set(st, "%s", msg);
}

static vv_status
check_keys(const jctx *c, json_t *o, const char *path, const char *const *allowed) {
    const char *key;
    json_t *v;
    json_object_foreach(o, key, v) {
        int ok = 0;
        for (const char *const *a = allowed; *a; a++)
            ok |= strcmp(*a, key) == 0;
        if (!ok) {
            char kp[JPATH], list[400] = "";
            kpath(kp, path, key);
            for (const char *const *a = allowed; *a; a++) {
                strncat(list, *a, sizeof list - strlen(list) - 1);
                if (a[1])
                    strncat(list, ", ", sizeof list - strlen(list) - 1);
            }
            return jfail(c, kp, VV_ERR_FORMAT, "unknown key \"%s\"; expected one of %s", key, list);
        }
    }
    return VV_OK;
}

/* number at key; *has (may be NULL) says whether present; required if !has */
static vv_status
num(const jctx *c, json_t *o, const char *path, const char *key, double *out, int *has) {
    json_t *v = json_object_get(o, key);
    char kp[JPATH];
    kpath(kp, path, key);
    if (has)
        *has = v != NULL;
    if (!v) {
        if (has)
            return VV_OK;
        return jfail(c, path, VV_ERR_FORMAT, "missing \"%s\"", key);
    }
    if (!json_is_number(v))
        return jfail(c, kp, VV_ERR_FORMAT, "expected a number, got %s", vv_json_kind(v));
    *out = json_number_value(v);
    if (!isfinite(*out))
        return jfail(c, kp, VV_ERR_FORMAT, "expected a finite number");
    return VV_OK;
}

static vv_status
vec_at(const jctx *c, json_t *v, const char *kp, double *out, size_t n) {
    if (!json_is_array(v) || json_array_size(v) != n)
        return jfail(c, kp, VV_ERR_FORMAT, "expected an array of %zu numbers, got %s", n,
                     vv_json_kind(v));
    for (size_t i = 0; i < n; i++) {
        json_t *e = json_array_get(v, i);
        if (!json_is_number(e)) {
            char ip[JPATH];
            ipath(ip, kp, i);
            return jfail(c, ip, VV_ERR_FORMAT, "expected a number, got %s", vv_json_kind(e));
        }
        out[i] = json_number_value(e);
    }
    return VV_OK;
}

static vv_status
vec3(const jctx *c, json_t *o, const char *path, const char *key, vv_vec3 *out, int *has) {
    json_t *v = json_object_get(o, key);
    char kp[JPATH];
    kpath(kp, path, key);
    if (has)
        *has = v != NULL;
    if (!v)
        return has ? VV_OK : jfail(c, path, VV_ERR_FORMAT, "missing \"%s\" ([x, y, z])", key);
    double d[3];
    vv_status st = vec_at(c, v, kp, d, 3);
    if (st == VV_OK)
        *out = vv_vec3_make(d[0], d[1], d[2]);
    return st;
}

/* An array of [a, b] (dim 2) or [x, y, z] (dim 3) points into a malloc'ed array. */
static vv_status
points(const jctx *c, json_t *o, const char *path, const char *key, int dim, double **out, int *n) {
    json_t *v = json_object_get(o, key);
    char kp[JPATH];
    kpath(kp, path, key);
    *out = NULL;
    if (!v)
        return jfail(c, path, VV_ERR_FORMAT, "missing \"%s\" (an array of %d-D points)", key, dim);
    if (!json_is_array(v) || json_array_size(v) < 3)
        return jfail(c, kp, VV_ERR_FORMAT, "expected an array of at least 3 points, got %s",
                     json_is_array(v) ? "fewer" : vv_json_kind(v));
    size_t m = json_array_size(v);
    if (m > (1u << 20))
        return jfail(c, kp, VV_ERR_LIMIT, "%zu points is over the limit of 2^20", m);
    double *p = malloc(m * (size_t)dim * sizeof *p);
    if (!p)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < m; i++) {
        char ip[JPATH];
        ipath(ip, kp, i);
        vv_status st = vec_at(c, json_array_get(v, i), ip, p + (size_t)dim * i, (size_t)dim);
        if (st != VV_OK) {
            free(p);
            return st;
        }
    }
    *out = p;
    *n = (int)m;
    return VV_OK;
}

/* translate, rotate (an {axis, angle} or an array of them, applied in
 * order), scale (number or [sx, sy, sz]) -> T * R * S; "center" adds to T. */
static vv_status
transform(const jctx *c, json_t *o, const char *path, vv_mat4 *M) {
    vv_status st;
    vv_vec3 t = {0, 0, 0}, ctr = {0, 0, 0};
    int has_c;
    if ((st = vec3(c, o, path, "translate", &t, &has_c)) != VV_OK ||
        (st = vec3(c, o, path, "center", &ctr, &has_c)) != VV_OK)
        return st;
    vv_mat4 R = vv_mat4_identity();
    json_t *rot = json_object_get(o, "rotate");
    if (rot) {
        char rp[JPATH];
        kpath(rp, path, "rotate");
        size_t nr = json_is_array(rot) ? json_array_size(rot) : 1;
        for (size_t i = 0; i < nr; i++) {
            json_t *r = json_is_array(rot) ? json_array_get(rot, i) : rot;
            char ep[JPATH];
            if (json_is_array(rot))
                ipath(ep, rp, i);
            else
                pcat(ep, rp, "", "");
            if (!json_is_object(r))
                return jfail(c, ep, VV_ERR_FORMAT,
                             "expected {\"axis\": [x, y, z], \"angle\": degrees}, got %s",
                             vv_json_kind(r));
            static const char *const rk[] = {"axis", "angle", NULL};
            vv_vec3 axis;
            double ang;
            if ((st = check_keys(c, r, ep, rk)) != VV_OK ||
                (st = vec3(c, r, ep, "axis", &axis, NULL)) != VV_OK ||
                (st = num(c, r, ep, "angle", &ang, NULL)) != VV_OK)
                return st;
            if (!(vv_vec3_length(axis) > 0)) {
                char ap[JPATH];
                kpath(ap, ep, "axis");
                return jfail(c, ap, VV_ERR_FORMAT, "the rotation axis is the zero vector");
            }
            R = vv_mat4_mul(vv_mat4_rotate(axis, vv_deg_to_rad(ang)), R);
        }
    }
    vv_vec3 s = {1, 1, 1};
    json_t *sc = json_object_get(o, "scale");
    if (sc) {
        char sp[JPATH];
        kpath(sp, path, "scale");
        if (json_is_number(sc)) {
            double u = json_number_value(sc);
            s = vv_vec3_make(u, u, u);
        } else {
            double d[3];
            if ((st = vec_at(c, sc, sp, d, 3)) != VV_OK)
                return st;
            s = vv_vec3_make(d[0], d[1], d[2]);
        }
        if (!(s.x > 0 && s.y > 0 && s.z > 0 && isfinite(s.x + s.y + s.z)))
            return jfail(c, sp, VV_ERR_FORMAT, "scale factors must be finite and > 0");
    }
    *M = vv_mat4_mul(vv_mat4_translate(vv_vec3_add(t, ctr)), vv_mat4_mul(R, vv_mat4_scale(s)));
    return VV_OK;
}

static vv_status node(const jctx *c, json_t *o, const char *path, vv_shape **out, int depth);

static vv_status
primitive(const jctx *c, json_t *o, const char *path, const char *type, vv_shape **out) {
#define TKEYS "translate", "rotate", "scale", "center", "type"
    static const char *const k_sphere[] = {TKEYS, "radius", NULL};
    static const char *const k_ell[] = {TKEYS, "radii", NULL};
    static const char *const k_box[] = {TKEYS, "size", "rounding", NULL};
    static const char *const k_cyl[] = {TKEYS, "radius", "height", NULL};
    static const char *const k_cone[] = {TKEYS, "radius_bottom", "radius_top", "height", NULL};
    static const char *const k_torus[] = {TKEYS, "major_radius", "minor_radius", NULL};
    static const char *const k_poly[] = {TKEYS, "vertices", "thickness", NULL};
    static const char *const k_rev[] = {TKEYS, "profile", NULL};
    static const char *const k_ext[] = {TKEYS, "polygon", "height", NULL};
    static const char *const k_hel[] = {TKEYS, "profile", "pitch", "z0", "z1", NULL};
    static const char *const k_mesh[] = {TKEYS, "file", "mode", "thickness", NULL};
#undef TKEYS
    vv_status st;
    double a = 0, b = 0, d = 0, e = 0;
    int has;
    double *pts = NULL;
    int n = 0;
    *out = NULL;
    if (strcmp(type, "sphere") == 0) {
        if ((st = check_keys(c, o, path, k_sphere)) != VV_OK ||
            (st = num(c, o, path, "radius", &a, NULL)) != VV_OK)
            return st;
        st = vv_shape_sphere(out, a);
    } else if (strcmp(type, "ellipsoid") == 0) {
        vv_vec3 r;
        if ((st = check_keys(c, o, path, k_ell)) != VV_OK ||
            (st = vec3(c, o, path, "radii", &r, NULL)) != VV_OK)
            return st;
        st = vv_shape_ellipsoid(out, r);
    } else if (strcmp(type, "box") == 0) {
        vv_vec3 sz;
        if ((st = check_keys(c, o, path, k_box)) != VV_OK ||
            (st = vec3(c, o, path, "size", &sz, NULL)) != VV_OK ||
            (st = num(c, o, path, "rounding", &a, &has)) != VV_OK)
            return st;
        st = vv_shape_box(out, sz, a);
    } else if (strcmp(type, "cylinder") == 0) {
        if ((st = check_keys(c, o, path, k_cyl)) != VV_OK ||
            (st = num(c, o, path, "radius", &a, NULL)) != VV_OK ||
            (st = num(c, o, path, "height", &b, NULL)) != VV_OK)
            return st;
        st = vv_shape_cylinder(out, a, b);
    } else if (strcmp(type, "cone") == 0) {
        if ((st = check_keys(c, o, path, k_cone)) != VV_OK ||
            (st = num(c, o, path, "radius_bottom", &a, NULL)) != VV_OK ||
            (st = num(c, o, path, "radius_top", &b, &has)) != VV_OK ||
            (st = num(c, o, path, "height", &d, NULL)) != VV_OK)
            return st;
        st = vv_shape_cone(out, a, b, d);
    } else if (strcmp(type, "torus") == 0) {
        if ((st = check_keys(c, o, path, k_torus)) != VV_OK ||
            (st = num(c, o, path, "major_radius", &a, NULL)) != VV_OK ||
            (st = num(c, o, path, "minor_radius", &b, NULL)) != VV_OK)
            return st;
        st = vv_shape_torus(out, a, b);
    } else if (strcmp(type, "polygon") == 0) {
        if ((st = check_keys(c, o, path, k_poly)) != VV_OK ||
            (st = num(c, o, path, "thickness", &a, NULL)) != VV_OK ||
            (st = points(c, o, path, "vertices", 3, &pts, &n)) != VV_OK)
            return st;
        st = vv_shape_polygon(out, n, (const vv_vec3 *)(void *)pts, a);
    } else if (strcmp(type, "revolution") == 0) {
        if ((st = check_keys(c, o, path, k_rev)) != VV_OK ||
            (st = points(c, o, path, "profile", 2, &pts, &n)) != VV_OK)
            return st;
        st = vv_shape_revolution(out, n, pts);
    } else if (strcmp(type, "extrusion") == 0) {
        if ((st = check_keys(c, o, path, k_ext)) != VV_OK ||
            (st = num(c, o, path, "height", &a, NULL)) != VV_OK ||
            (st = points(c, o, path, "polygon", 2, &pts, &n)) != VV_OK)
            return st;
        st = vv_shape_extrusion(out, n, pts, a);
    } else if (strcmp(type, "helix") == 0) {
        if ((st = check_keys(c, o, path, k_hel)) != VV_OK ||
            (st = num(c, o, path, "pitch", &a, NULL)) != VV_OK ||
            (st = num(c, o, path, "z0", &d, NULL)) != VV_OK ||
            (st = num(c, o, path, "z1", &e, NULL)) != VV_OK ||
            (st = points(c, o, path, "profile", 2, &pts, &n)) != VV_OK)
            return st;
        st = vv_shape_helix(out, n, pts, a, d, e);
    } else if (strcmp(type, "mesh") == 0) {
        json_t *f = json_object_get(o, "file"), *m = json_object_get(o, "mode");
        char fp[JPATH];
        kpath(fp, path, "file");
        if ((st = check_keys(c, o, path, k_mesh)) != VV_OK ||
            (st = num(c, o, path, "thickness", &a, &has)) != VV_OK)
            return st;
        if (!f)
            return jfail(c, path, VV_ERR_FORMAT, "missing \"file\" (the mesh file)");
        if (!json_is_string(f) || !json_string_value(f)[0])
            return jfail(c, fp, VV_ERR_FORMAT, "expected a file name, got %s", vv_json_kind(f));
        vv_mesh_mode mode = VV_MESH_AUTO;
        if (m) {
            const char *ms = json_is_string(m) ? json_string_value(m) : "";
            char mp[JPATH];
            kpath(mp, path, "mode");
            if (strcmp(ms, "auto") == 0)
                mode = VV_MESH_AUTO;
            else if (strcmp(ms, "solid") == 0)
                mode = VV_MESH_SOLID;
            else if (strcmp(ms, "shell") == 0)
                mode = VV_MESH_SHELL;
            else
                return jfail(c, mp, VV_ERR_FORMAT, "expected \"auto\", \"solid\" or \"shell\"");
        }
        char *full = c->scene_path ? vv_path_join_dir(c->scene_path, json_string_value(f))
                                   : vv_strdup(json_string_value(f));
        if (!full)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        st = vv_shape_mesh_load(out, full, mode, has ? a : 0.0);
        free(full);
        if (st != VV_OK && c->err_path)
            snprintf(c->err_path, c->cap, "%s", fp);
        return st;
    } else {
        char tp[JPATH];
        kpath(tp, path, "type");
        return jfail(c, tp, VV_ERR_FORMAT,
                     "unknown primitive \"%s\"; expected sphere, ellipsoid, box, cylinder, "
                     "cone, torus, polygon, revolution, extrusion, helix or mesh",
                     type);
    }
    free(pts);
    if (st != VV_OK) {
        if (c->err_path)
            snprintf(c->err_path, c->cap, "%s", path);
        return st;
    }
    return VV_OK;
}

static vv_status
node(const jctx *c, json_t *o, const char *path, vv_shape **out, int depth) {
    *out = NULL;
    if (depth > 1000)
        return jfail(c, path, VV_ERR_LIMIT, "the model tree is deeper than 1000 levels");
    if (!json_is_object(o))
        return jfail(c, path, VV_ERR_FORMAT,
                     "expected a primitive {\"type\": ...} or an operation {\"op\": ...}, got %s",
                     vv_json_kind(o));
    json_t *type = json_object_get(o, "type"), *op = json_object_get(o, "op");
    vv_status st;
    vv_mat4 M;
    if (type && op)
        return jfail(c, path, VV_ERR_FORMAT,
                     "give either \"type\" (a primitive) or \"op\" (a "
                     "CSG operation), not both");
    if (type) {
        char tp[JPATH];
        kpath(tp, path, "type");
        if (!json_is_string(type))
            return jfail(c, tp, VV_ERR_FORMAT, "expected a primitive name, got %s",
                         vv_json_kind(type));
        if ((st = transform(c, o, path, &M)) != VV_OK ||
            (st = primitive(c, o, path, json_string_value(type), out)) != VV_OK)
            return st;
        vv_shape_transform(*out, M);
        return VV_OK;
    }
    if (!op)
        return jfail(c, path, VV_ERR_FORMAT,
                     "missing \"type\" (a primitive) or \"op\" (union, intersection, difference)");
    static const char *const k_op[] = {"op",    "children", "translate", "rotate",
                                       "scale", "center",   NULL};
    char opp[JPATH], cp[JPATH];
    kpath(opp, path, "op");
    kpath(cp, path, "children");
    if ((st = check_keys(c, o, path, k_op)) != VV_OK)
        return st;
    const char *ops = json_is_string(op) ? json_string_value(op) : "";
    vv_csg_op cop;
    if (strcmp(ops, "union") == 0)
        cop = VV_CSG_UNION;
    else if (strcmp(ops, "intersection") == 0)
        cop = VV_CSG_INTERSECTION;
    else if (strcmp(ops, "difference") == 0)
        cop = VV_CSG_DIFFERENCE;
    else
        return jfail(c, opp, VV_ERR_FORMAT,
                     "expected \"union\", \"intersection\" or "
                     "\"difference\"");
    json_t *ch = json_object_get(o, "children");
    if (!ch)
        return jfail(c, path, VV_ERR_FORMAT, "missing \"children\" of the %s", ops);
    if (!json_is_array(ch) || json_array_size(ch) == 0)
        return jfail(c, cp, VV_ERR_FORMAT, "expected a non-empty array of children, got %s",
                     json_is_array(ch) ? "an empty array" : vv_json_kind(ch));
    if (cop == VV_CSG_DIFFERENCE && json_array_size(ch) < 2)
        return jfail(c, cp, VV_ERR_FORMAT,
                     "a difference needs two or more children (the first minus the others)");
    if ((st = transform(c, o, path, &M)) != VV_OK)
        return st;
    size_t n = json_array_size(ch);
    vv_shape **kids = calloc(n, sizeof *kids);
    if (!kids)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n; i++) {
        char ip[JPATH];
        ipath(ip, cp, i);
        json_t *e = json_array_get(ch, i);
        if (json_is_null(e)) {
            st = jfail(c, ip, VV_ERR_FORMAT, "child %zu of the %s is missing (null)", i + 1, ops);
            break;
        }
        if ((st = node(c, e, ip, &kids[i], depth + 1)) != VV_OK)
            break;
    }
    if (st != VV_OK) {
        for (size_t i = 0; i < n; i++)
            vv_shape_free(kids[i]);
        free(kids);
        return st;
    }
    st = vv_shape_csg(out, cop, (int)n, kids);
    free(kids);
    if (st != VV_OK)
        return st;
    vv_shape_transform(*out, M);
    return VV_OK;
}

static vv_status
shape_from_json(vv_shape **out, json_t *n, const char *path, const char *scene_path, char *err_path,
                size_t cap) {
    jctx c = {scene_path, err_path, cap};
    if (err_path && cap)
        err_path[0] = '\0';
    return node(&c, n, path, out, 0);
}

static vv_status
voxelize_options_from_json(vv_voxelize_options *opt, json_t *o, const char *path, char *err_path,
                           size_t cap) {
    jctx c = {NULL, err_path, cap};
    vv_status st;
    double v;
    int has;
    char kp[JPATH];
    if ((st = num(&c, o, path, "resolution", &v, &has)) != VV_OK)
        return st;
    if (has) {
        kpath(kp, path, "resolution");
        if (!(v >= 2 && v == floor(v)))
            return jfail(&c, kp, VV_ERR_FORMAT, "expected a whole number of voxels >= 2");
        if (v > VV_VOLUME_MAX_DIM)
            return jfail(&c, kp, VV_ERR_LIMIT, "%.0f voxels per axis is over the limit of %d", v,
                         VV_VOLUME_MAX_DIM);
        opt->size = (int)v;
    }
    if ((st = num(&c, o, path, "voxel_spacing", &v, &has)) != VV_OK)
        return st;
    if (has) {
        kpath(kp, path, "voxel_spacing");
        if (!(v > 0))
            return jfail(&c, kp, VV_ERR_FORMAT, "voxel spacing must be > 0");
        opt->voxel_spacing = v;
    }
    if ((st = num(&c, o, path, "filter_radius", &v, &has)) != VV_OK)
        return st;
    if (has) {
        kpath(kp, path, "filter_radius");
        if (!(v >= 0.25 && v <= 16))
            return jfail(&c, kp, VV_ERR_FORMAT, "filter radius must be in [0.25, 16] voxels");
        opt->radius = v;
    }
    if ((st = num(&c, o, path, "margin", &v, &has)) != VV_OK)
        return st;
    if (has) {
        kpath(kp, path, "margin");
        if (!(v >= 0 && v <= 1e4))
            return jfail(&c, kp, VV_ERR_FORMAT, "margin must be in [0, 10000] voxels");
        opt->margin = v;
    }
    json_t *f = json_object_get(o, "filter");
    if (f) {
        kpath(kp, path, "filter");
        if (!json_is_string(f) ||
            vv_sampling_kernel_parse(json_string_value(f), &opt->kernel) != VV_OK)
            return jfail(&c, kp, VV_ERR_FORMAT, "expected \"box\", \"tent\" or \"gauss\"");
    }
    json_t *t = json_object_get(o, "voxel_type");
    if (t) {
        kpath(kp, path, "voxel_type");
        const char *ts = json_is_string(t) ? json_string_value(t) : "";
        if (strcmp(ts, "u8") == 0)
            opt->type = VV_U8;
        else if (strcmp(ts, "f32") == 0)
            opt->type = VV_F32;
        else
            return jfail(&c, kp, VV_ERR_FORMAT, "expected \"u8\" or \"f32\"");
    }
    return VV_OK;
}

/* ---- model files ------------------------------------------------------------ */

static int
is_json(const char *path) {
    size_t n = strlen(path);
    return n >= 5 && strcmp(path + n - 5, ".json") == 0;
}

/* The object transform of a scene object: position, rotation {axis, angle}
 * or orientation [w, x, y, z], scale. */
static vv_status
object_matrix(const jctx *c, json_t *o, const char *path, vv_mat4 *M) {
    vv_status st;
    vv_vec3 pos = {0, 0, 0};
    int has;
    if ((st = vec3(c, o, path, "position", &pos, &has)) != VV_OK)
        return st;
    vv_mat4 R = vv_mat4_identity();
    json_t *rot = json_object_get(o, "rotation"), *ori = json_object_get(o, "orientation");
    char kp[JPATH];
    if (rot) {
        kpath(kp, path, "rotation");
        vv_vec3 axis;
        double ang;
        if (!json_is_object(rot))
            return jfail(c, kp, VV_ERR_FORMAT, "expected {\"axis\", \"angle\"}, got %s",
                         vv_json_kind(rot));
        if ((st = vec3(c, rot, kp, "axis", &axis, NULL)) != VV_OK ||
            (st = num(c, rot, kp, "angle", &ang, NULL)) != VV_OK)
            return st;
        R = vv_mat4_rotate(axis, vv_deg_to_rad(ang));
    } else if (ori) {
        kpath(kp, path, "orientation");
        double q[4];
        if ((st = vec_at(c, ori, kp, q, 4)) != VV_OK)
            return st;
        R = vv_quat_to_mat4(vv_quat_normalize((vv_quat){q[0], q[1], q[2], q[3]}));
    }
    vv_vec3 s = {1, 1, 1};
    json_t *sc = json_object_get(o, "scale");
    if (sc) {
        kpath(kp, path, "scale");
        if (json_is_number(sc)) {
            double u = json_number_value(sc);
            s = vv_vec3_make(u, u, u);
        } else {
            double d[3];
            if ((st = vec_at(c, sc, kp, d, 3)) != VV_OK)
                return st;
            s = vv_vec3_make(d[0], d[1], d[2]);
        }
    }
    *M = vv_mat4_mul(vv_mat4_translate(pos), vv_mat4_mul(R, vv_mat4_scale(s)));
    return VV_OK;
}

static vv_status
model_from_scene(vv_shape **out, const char *path, vv_voxelize_options *opt) {
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status st = vv_read_file(path, (uint64_t)16 << 20, &data, &size);
    if (st != VV_OK)
        return vv_error_prefix(st, "model");
    json_error_t jerr;
    json_t *root = json_loadb((const char *)data, (size_t)size,
                              JSON_REJECT_DUPLICATES | JSON_DECODE_INT_AS_REAL, &jerr);
    free(data);
    if (!root)
        return vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s", path, jerr.line, jerr.column, jerr.text);
    char ep[JPATH] = "";
    jctx c = {path, ep, sizeof ep};
    json_t *objs = json_is_object(root) ? json_object_get(root, "objects") : NULL;
    size_t n = json_is_array(objs) ? json_array_size(objs) : 0;
    vv_shape **parts = calloc(n ? n : 1, sizeof *parts);
    int np = 0;
    if (!parts)
        st = vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n && st == VV_OK; i++) {
        json_t *o = json_array_get(objs, i);
        json_t *t = json_is_object(o) ? json_object_get(o, "type") : NULL;
        if (!json_is_string(t) || strcmp(json_string_value(t), "geometry") != 0)
            continue;
        char op[JPATH], kp[JPATH];
        ipath(op, "objects", i);
        json_t *prim = json_object_get(o, "primitive"), *csg = json_object_get(o, "csg");
        if (!prim && !csg) {
            st = jfail(&c, op, VV_ERR_FORMAT, "a geometry object needs \"primitive\" or \"csg\"");
            break;
        }
        kpath(kp, op, prim ? "primitive" : "csg");
        vv_mat4 M;
        if ((st = node(&c, prim ? prim : csg, kp, &parts[np], 0)) != VV_OK ||
            (st = object_matrix(&c, o, op, &M)) != VV_OK)
            break;
        vv_shape_transform(parts[np++], M);
        if (np == 1 && opt)
            st = voxelize_options_from_json(opt, o, op, ep, sizeof ep);
    }
    json_decref(root);
    if (st == VV_OK && np == 0)
        st = vv_error_set(VV_ERR_INVALID, "%s: no objects of type \"geometry\"", path);
    else if (st == VV_OK && np > 1) {
        st = vv_shape_csg(out, VV_CSG_UNION, np, parts); /* owns the parts, also on failure */
        np = st == VV_OK ? -1 : 0;
    } else if (ep[0])
        vv_error_prefix(st, "%s: %s", path, ep);
    else
        vv_error_prefix(st, "%s", path);
    if (st == VV_OK && np == 1)
        *out = parts[0];
    if (np < 0)
        np = 0;
    if (st != VV_OK)
        for (int i = 0; i < np; i++)
            vv_shape_free(parts[i]);
    free(parts);
    return st;
}

vv_status
vv_shape_load(vv_shape **out, const char *path, vv_voxelize_options *opt) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "model: NULL output");
    *out = NULL;
    if (!path)
        return vv_error_set(VV_ERR_INVALID, "model: NULL path");
    if (is_json(path))
        return model_from_scene(out, path, opt);
    return vv_shape_mesh_load(out, path, VV_MESH_AUTO, 0.0);
}

/* Parses @p len bytes of JSON text as the scene reader does (duplicate keys
 * refused, integers as reals); on failure the error names the position in
 * that text and err_path gets @p key_path. */
static vv_status
parse_text(json_t **out, const char *json, size_t len, const char *key_path, char *err_path,
           size_t cap) {
    if (err_path && cap)
        snprintf(err_path, cap, "%s", key_path ? key_path : "");
    if (!json)
        return vv_error_set(VV_ERR_INVALID, "model: NULL JSON text");
    json_error_t jerr;
    *out = json_loadb(json, len, JSON_REJECT_DUPLICATES | JSON_DECODE_INT_AS_REAL | JSON_DECODE_ANY,
                      &jerr);
    if (!*out)
        return vv_error_set(VV_ERR_FORMAT, "%d:%d: %s", jerr.line, jerr.column, jerr.text);
    if (err_path && cap)
        err_path[0] = '\0';
    return VV_OK;
}

vv_status
vv_shape_parse_json(vv_shape **out, const char *json, size_t len, const char *key_path,
                    const char *base_path, char *err_path, size_t cap) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "model: NULL output");
    *out = NULL;
    json_t *root = NULL;
    vv_status st = parse_text(&root, json, len, key_path, err_path, cap);
    if (st != VV_OK)
        return st;
    st = shape_from_json(out, root, key_path ? key_path : "", base_path, err_path, cap);
    json_decref(root);
    return st;
}

vv_status
vv_voxelize_options_parse_json(vv_voxelize_options *opt, const char *json, size_t len,
                               const char *key_path, char *err_path, size_t cap) {
    if (!opt)
        return vv_error_set(VV_ERR_INVALID, "model: NULL options");
    json_t *root = NULL;
    vv_status st = parse_text(&root, json, len, key_path, err_path, cap);
    if (st != VV_OK)
        return st;
    if (!json_is_object(root)) {
        if (err_path && cap)
            snprintf(err_path, cap, "%s", key_path ? key_path : "");
        st = vv_error_set(VV_ERR_FORMAT, "expected an object, got %s", vv_json_kind(root));
        json_decref(root);
        return st;
    }
    st = voxelize_options_from_json(opt, root, key_path ? key_path : "", err_path, cap);
    json_decref(root);
    return st;
}
