/*
 * Scene files, the objects that are not volume files: geometric objects for
 * the ray tracer (plane, polygon, sphere, box, cylinder, mesh), "geometry"
 * objects volume-sampled by Modeling at load, and irregular grids.
 */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "scene/scene_internal.h"
#include "volvis/grid.h"
#include "volvis/mesh.h"
#include "volvis/model.h"
#include "volvis/modeling.h"

/* ---- geometric objects (volumetric ray tracing) ---------------------------- */

/* VV_OBJECT_VOLUME for "volume" and for names that are not geometric types. */
vv_object_type
vv_scene_geometry_type(const char *name) {
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
        g->normal = vv_scene_unit(g->normal);
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

/* A geometric object: its shape (in object coordinates), transform,
 * material, visibility and shading-effect flags. */
vv_status
vv_scene_parse_geometry_object(const sctx *c, json_t *e, const char *op, vv_world *w) {
    static const char *const shape_keys[][5] = {
        [VV_OBJECT_PLANE] = {"point", "normal", NULL},
        [VV_OBJECT_POLYGON] = {"vertices", NULL},
        [VV_OBJECT_SPHERE] = {"center", "radius", NULL},
        [VV_OBJECT_BOX] = {"min", "max", NULL},
        [VV_OBJECT_CYLINDER] = {"base", "top", "radius", "capped", NULL},
        [VV_OBJECT_MESH] = {"file", NULL},
    };
    const vv_object_type type =
        vv_scene_geometry_type(json_string_value(json_object_get(e, "type")));
    const char *name = NULL;
    vv_status st = vv_scene_check_object_keys(c, e, op, shape_keys[type], 0);
    if (st != VV_OK || (st = vv_scene_get_object_name(c, e, op, &name)) != VV_OK)
        return st;
    vv_object *o = NULL;
    if ((st = vv_object_new_geometry(&o, type, name)) != VV_OK)
        return vv_error_prefix(st, "%s: %s", c->path, op);
    if ((st = parse_shape(c, e, op, o)) != VV_OK ||
        (st = vv_scene_parse_object_fields(c, e, op, o, NULL)) != VV_OK ||
        (st = vv_scene_parse_effect_flags(c, e, op, o)) != VV_OK) {
        vv_object_free(o);
        return st;
    }
    return vv_world_add_object(w, o);
}

/* ---- geometry objects (Modeling) ------------------------------------------
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

vv_status
vv_scene_parse_voxelized_geometry(const sctx *c, json_t *e, const char *op, vv_world *w) {
    static const char *const own[] = {"primitive",     "csg",        "resolution",
                                      "voxel_spacing", "filter",     "filter_radius",
                                      "margin",        "voxel_type", NULL};
    char kp[PATH_MAX_LEN], ep[PATH_MAX_LEN];
    const char *name = NULL;
    vv_status st = vv_scene_check_object_keys(c, e, op, own, 1);
    if (st != VV_OK || (st = vv_scene_get_object_name(c, e, op, &name)) != VV_OK)
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
    /* Modeling reads its keys from JSON text: hand it the values as text
     * (Jansson writes numbers with 17 digits, so they read back exactly) */
    char *text = json_dumps(e, JSON_COMPACT | JSON_ENCODE_ANY);
    if (!text)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    st = vv_voxelize_options_parse_json(&vo, text, strlen(text), op, ep, sizeof ep);
    free(text);
    if (st != VV_OK)
        return geometry_err(c, st, ep);
    if (!(text = json_dumps(prim ? prim : csg, JSON_COMPACT | JSON_ENCODE_ANY)))
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    vv_shape *shape = NULL;
    st = vv_shape_parse_json(&shape, text, strlen(text), kp, c->path, ep, sizeof ep);
    free(text);
    if (st != VV_OK)
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
    if ((st = vv_scene_parse_object_fields(c, e, op, o, NULL)) != VV_OK ||
        (st = vv_scene_parse_effect_flags(c, e, op, o)) != VV_OK) {
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
vv_status
vv_scene_parse_grid_object(const sctx *c, json_t *e, const char *op, vv_world *w) {
    static const char *const own[] = {"file", "field", "component", "time", NULL};
    char kp[PATH_MAX_LEN];
    vv_status st = vv_scene_check_object_keys(c, e, op, own, 1);
    const char *name = NULL, *file = NULL, *field = NULL;
    int component = -1, time = 0;
    if (st != VV_OK || (st = vv_scene_get_object_name(c, e, op, &name)) != VV_OK ||
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
        vv_scene_name_from_file(defname, file);
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
    if ((st = vv_scene_parse_object_fields(c, e, op, o, NULL)) != VV_OK ||
        (st = vv_scene_parse_effect_flags(c, e, op, o)) != VV_OK) {
        vv_object_free(o);
        return st;
    }
    return vv_world_add_object(w, o);
}
