/*
 * Volume objects of the World: data, transform, material, segmentation,
 * local shading and cut planes (the paper's "object", section 3).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "model/model_internal.h"
#include "volvis/model.h"
#include "volvis/sys/geometry.h"

double
vv_tf_default_unit_distance(const vv_volume *v) {
    double s = v->spacing[0];
    if (v->spacing[1] < s)
        s = v->spacing[1];
    if (v->spacing[2] < s)
        s = v->spacing[2];
    if (!(s > 0.0) || !isfinite(s))
        s = 1.0;
    return s;
}

void
vv_model_copy_name(char dst[VV_NAME_MAX], const char *src) {
    if (!src)
        src = "";
    size_t n = strlen(src);
    if (n >= VV_NAME_MAX)
        n = VV_NAME_MAX - 1;
    memcpy(dst, src, n);
    dst[n] = '\0';
}

/* Defaults shared by volume and geometric objects. */
static void
object_defaults(vv_object *o) {
    o->position = vv_vec3_make(0, 0, 0);
    o->orientation = vv_quat_identity();
    o->scale = vv_vec3_make(1, 1, 1);
    o->material.ambient = 0.1;
    o->material.diffuse = 0.6;
    o->material.specular = 0.3;
    o->material.shininess = 30.0;
    o->material.color = vv_vec3_make(1, 1, 1);
    o->material.reflectance = 0.0;
    o->material.transparency = 0.0;
    o->material.ior = 1.0;
    o->material.emission = vv_vec3_make(0, 0, 0);
    o->segmentation = VV_SEG_TRANSFER_FUNCTION;
    o->mode = VV_MODE_COMPOSITE;
    o->step = 0.5;
    o->attenuation = 0.05;
    o->shading = 1;
    o->visible = 1;
    o->casts_shadows = 1;
    o->receives_shadows = 1;
    o->visible_in_reflections = 1;
    o->reflects = 1;
    o->n_cut_planes = 0;
    vv_tf2d_init(&o->tf2d);
    vv_texture_map_init(&o->texture);
    vv_solid_texture_init(&o->solid_texture);
}

const char *
vv_object_type_name(vv_object_type t) {
    if (t == VV_OBJECT_VOLUME)
        return "volume";
    if (t == VV_OBJECT_GRID)
        return "grid";
    const vv_geom_type *gt = vv_geom_type_get(t);
    return gt ? gt->name : "unknown";
}

vv_status
vv_object_new_volume(vv_object **out, vv_volume *volume, const char *name) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "object: NULL output");
    *out = NULL;
    if (!volume)
        return vv_error_set(VV_ERR_INVALID, "object: NULL volume");
    if (volume->dims[0] < 1 || volume->dims[1] < 1 || volume->dims[2] < 1)
        return vv_error_set(VV_ERR_INVALID, "object: volume has dimensions %dx%dx%d",
                            volume->dims[0], volume->dims[1], volume->dims[2]);
    vv_object *o = calloc(1, sizeof *o);
    if (!o)
        return vv_error_set(VV_ERR_NOMEM, "object: out of memory");
    vv_model_copy_name(o->name, name ? name : "volume");
    o->type = VV_OBJECT_VOLUME;
    o->volume = vv_volume_ref(volume);
    object_defaults(o);
    double lo = volume->range[0], hi = volume->range[1];
    if (!isfinite(lo) || !isfinite(hi)) {
        lo = 0.0;
        hi = 1.0;
    }
    if (!(hi > lo))
        hi = lo + 1.0;
    o->threshold = 0.5 * (lo + hi);
    vv_tf_set_ramp(&o->tf, lo, hi, 1.0, vv_vec3_make(1, 1, 1), vv_tf_default_unit_distance(volume));
    o->tf2d.opacity_unit_distance = vv_tf_default_unit_distance(volume);
    o->isovalue = 0.5 * (lo + hi);
    *out = o;
    return VV_OK;
}

vv_status
vv_object_attach_source(vv_object *obj, vv_source *source, int level) {
    if (!obj || !source || obj->type != VV_OBJECT_VOLUME || !obj->volume || obj->n_channels > 0)
        return vv_error_set(VV_ERR_INVALID, "object: %s: not a volume object of one channel",
                            obj ? obj->name : "(null)");
    if (vv_source_volume(source)) /* in memory: the object's own volume */
        return VV_OK;
    const vv_volume *h = vv_source_level(source, level);
    if (!h)
        return vv_error_set(VV_ERR_INVALID, "object: %s has no level %d (it has %d)",
                            vv_path_basename(vv_source_path(source)), level,
                            vv_source_levels(source));
    /* opacity per the level's smallest voxel edge where it was the proxy's
     * (a default transfer function): an image does not change with the
     * proxy */
    const double pu = vv_tf_default_unit_distance(obj->volume), lu = vv_tf_default_unit_distance(h);
    if (fabs(obj->tf.opacity_unit_distance - pu) <= 1e-12 * pu)
        obj->tf.opacity_unit_distance = lu;
    if (fabs(obj->tf2d.opacity_unit_distance - pu) <= 1e-12 * pu)
        obj->tf2d.opacity_unit_distance = lu;
    vv_source_ref(source);
    vv_source_free(obj->source);
    obj->source = source;
    return VV_OK;
}

vv_status
vv_object_new_source(vv_object **out, vv_source *source, int level, const char *name) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "object: NULL output");
    *out = NULL;
    if (!source)
        return vv_error_set(VV_ERR_INVALID, "object: NULL source");
    vv_volume *whole = vv_source_volume(source);
    if (whole)
        return vv_object_new_volume(out, whole, name);
    vv_volume *proxy = NULL;
    vv_status s = vv_source_proxy(source, level, &proxy);
    if (s != VV_OK)
        return s;
    s = vv_object_new_volume(out, proxy, name);
    vv_volume_free(proxy);
    if (s == VV_OK && (s = vv_object_attach_source(*out, source, level)) != VV_OK) {
        vv_object_free(*out);
        *out = NULL;
    }
    return s;
}

vv_status
vv_object_set_volume(vv_object *obj, vv_volume *volume) {
    if (!obj || !volume || obj->type != VV_OBJECT_VOLUME || obj->n_channels > 0)
        return vv_error_set(VV_ERR_INVALID, "object: %s: not a volume object of one channel",
                            obj ? obj->name : "(null)");
    vv_volume_ref(volume);
    vv_volume_free(obj->volume);
    obj->volume = volume;
    vv_source_free(obj->source);
    obj->source = NULL;
    return VV_OK;
}

vv_status
vv_object_new_grid(vv_object **out, vv_grid *grid, const char *field, const char *name) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "object: NULL output");
    *out = NULL;
    if (!grid)
        return vv_error_set(VV_ERR_INVALID, "object: NULL grid");
    vv_object *o = calloc(1, sizeof *o);
    if (!o)
        return vv_error_set(VV_ERR_NOMEM, "object: out of memory");
    vv_model_copy_name(o->name, name ? name : "grid");
    o->type = VV_OBJECT_GRID;
    o->grid = vv_grid_ref(grid);
    object_defaults(o);
    o->component = -1;
    if (field)
        snprintf(o->field, sizeof o->field, "%s", field);
    int f = vv_object_grid_field(o);
    if (f < 0 && grid->n_fields > 0) {
        vv_object_free(o);
        return VV_ERR_INVALID;
    }
    double lo = f >= 0 ? grid->fields[f].range[0] : 0, hi = f >= 0 ? grid->fields[f].range[1] : 1;
    if (!isfinite(lo) || !isfinite(hi)) {
        lo = 0.0;
        hi = 1.0;
    }
    if (!(hi > lo))
        hi = lo + 1.0;
    vv_box b = vv_grid_bounds(grid);
    double ext = fmax(b.max.x - b.min.x, fmax(b.max.y - b.min.y, b.max.z - b.min.z));
    if (!(ext > 0))
        ext = 1;
    o->threshold = 0.5 * (lo + hi);
    vv_tf_set_ramp(&o->tf, lo, hi, 1.0, vv_vec3_make(1, 1, 1), ext / 100);
    o->tf2d.opacity_unit_distance = ext / 100;
    o->isovalue = 0.5 * (lo + hi);
    *out = o;
    return VV_OK;
}

int
vv_object_grid_field(const vv_object *obj) {
    if (!obj || !obj->grid) {
        vv_error_set(VV_ERR_INVALID, "object: not a grid object");
        return -1;
    }
    int f = vv_grid_find_field(obj->grid, obj->field[0] ? obj->field : NULL, obj->time);
    if (f < 0) {
        char known[256] = "";
        size_t len = 0;
        for (int i = 0; i < obj->grid->n_fields && len < 200; i++) {
            int w = snprintf(known + len, sizeof known - len, "%s%s", i ? ", " : "",
                             obj->grid->fields[i].name);
            len += w > 0 ? (size_t)w : 0;
        }
        vv_error_set(VV_ERR_INVALID, "grid object '%s': no field '%s' at time %d (fields: %s)",
                     obj->name, obj->field[0] ? obj->field : "(first)", obj->time,
                     known[0] ? known : "none");
    }
    return f;
}

vv_status
vv_object_new_geometry(vv_object **out, vv_object_type type, const char *name) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "object: NULL output");
    *out = NULL;
    if (type <= VV_OBJECT_VOLUME || type > VV_OBJECT_MESH)
        return vv_error_set(VV_ERR_INVALID, "object: %d is not a geometric object type", (int)type);
    vv_object *o = calloc(1, sizeof *o);
    if (!o)
        return vv_error_set(VV_ERR_NOMEM, "object: out of memory");
    vv_model_copy_name(o->name, name ? name : vv_object_type_name(type));
    o->type = type;
    object_defaults(o);
    vv_tf_init(&o->tf);
    o->threshold = 0.5;
    o->isovalue = 0.5;
    vv_geometry *g = &o->geometry;
    g->center = vv_vec3_make(0, 0, 0);
    g->radius = 1.0;
    g->point = vv_vec3_make(0, 0, 0);
    g->normal = vv_vec3_make(0, 0, 1);
    g->box.min = vv_vec3_make(-1, -1, -1);
    g->box.max = vv_vec3_make(1, 1, 1);
    g->base = vv_vec3_make(0, 0, -1);
    g->top = vv_vec3_make(0, 0, 1);
    g->capped = 1;
    *out = o;
    return VV_OK;
}

vv_status
vv_object_set_polygon(vv_object *obj, int n, const vv_vec3 *vertices) {
    if (!obj || obj->type != VV_OBJECT_POLYGON)
        return vv_error_set(VV_ERR_INVALID, "polygon: not a polygon object");
    if (n < 3 || !vertices)
        return vv_error_set(VV_ERR_INVALID, "polygon: needs at least 3 vertices, got %d", n);
    if (n > 1000000)
        return vv_error_set(VV_ERR_LIMIT, "polygon: %d vertices (at most 1000000)", n);
    /* Newell's normal: robust for any simple planar polygon, either winding. */
    vv_vec3 nrm = {0, 0, 0};
    double size = 0.0;
    for (int i = 0; i < n; i++) {
        vv_vec3 a = vertices[i], b = vertices[(i + 1) % n];
        if (!isfinite(a.x) || !isfinite(a.y) || !isfinite(a.z))
            return vv_error_set(VV_ERR_INVALID, "polygon: vertex %d is not finite", i);
        nrm.x += (a.y - b.y) * (a.z + b.z);
        nrm.y += (a.z - b.z) * (a.x + b.x);
        nrm.z += (a.x - b.x) * (a.y + b.y);
        size = fmax(size, vv_vec3_length(vv_vec3_sub(a, vertices[0])));
    }
    double len = vv_vec3_length(nrm);
    if (!(len > 1e-12 * size * size) || !(size > 0))
        return vv_error_set(VV_ERR_INVALID, "polygon: zero area");
    nrm = vv_vec3_scale(nrm, 1.0 / len);
    for (int i = 0; i < n; i++) {
        double d = vv_vec3_dot(nrm, vv_vec3_sub(vertices[i], vertices[0]));
        if (fabs(d) > 1e-6 * size)
            return vv_error_set(VV_ERR_INVALID,
                                "polygon: vertex %d is %g off the plane of the others", i, d);
    }
    vv_vec3 *v = malloc((size_t)n * sizeof *v);
    if (!v)
        return vv_error_set(VV_ERR_NOMEM, "polygon: out of memory");
    memcpy(v, vertices, (size_t)n * sizeof *v);
    free(obj->geometry.vertices);
    obj->geometry.vertices = v;
    obj->geometry.n_vertices = n;
    obj->geometry.point = vertices[0];
    obj->geometry.normal = nrm;
    return VV_OK;
}

vv_status
vv_object_set_mesh(vv_object *obj, vv_mesh *mesh, const char *source) {
    if (!obj || obj->type != VV_OBJECT_MESH)
        return vv_error_set(VV_ERR_INVALID, "mesh object: not a mesh object");
    if (!mesh || mesh->n_triangles == 0)
        return vv_error_set(VV_ERR_INVALID, "mesh object: the mesh has no triangles");
    char *src = NULL;
    if (source) {
        src = vv_strdup(source);
        if (!src)
            return vv_error_set(VV_ERR_NOMEM, "mesh object: out of memory");
    }
    free(obj->geometry.source);
    obj->geometry.source = src;
    vv_mesh_free(obj->geometry.mesh);
    obj->geometry.mesh = vv_mesh_ref(mesh);
    return VV_OK;
}

void
vv_object_free(vv_object *obj) {
    if (!obj)
        return;
    vv_volume_free(obj->volume);
    vv_grid_free(obj->grid);
    free(obj->geometry.vertices);
    vv_mesh_free(obj->geometry.mesh);
    free(obj->geometry.source);
    free(obj->geometry.filters);
    vv_texture_image_free(obj->texture.image);
    vv_volume_free(obj->solid_texture.volume);
    free(obj->solid_texture.source);
    for (int c = 0; c < obj->n_channels; c++)
        vv_volume_free(obj->channels[c].volume);
    free(obj->channels);
    vv_source_free(obj->source);
    free(obj);
}

vv_status
vv_object_clone(vv_object **out, const vv_object *obj) {
    if (!out || !obj)
        return vv_error_set(VV_ERR_INVALID, "object clone: NULL %s", out ? "object" : "output");
    *out = NULL;
    vv_object *c = malloc(sizeof *c);
    if (!c)
        return vv_error_set(VV_ERR_NOMEM, "object clone: out of memory");
    *c = *obj;
    c->geometry.vertices = NULL;
    c->geometry.source = NULL;
    c->geometry.filters = NULL;
    c->solid_texture.source = NULL;
    c->channels = NULL;
    if (obj->n_channels > 0) {
        c->channels = malloc((size_t)obj->n_channels * sizeof *c->channels);
        if (!c->channels)
            goto nomem;
        memcpy(c->channels, obj->channels, (size_t)obj->n_channels * sizeof *c->channels);
    }
    if (obj->geometry.vertices && obj->geometry.n_vertices > 0) {
        size_t n = (size_t)obj->geometry.n_vertices * sizeof *c->geometry.vertices;
        c->geometry.vertices = malloc(n);
        if (!c->geometry.vertices)
            goto nomem;
        memcpy(c->geometry.vertices, obj->geometry.vertices, n);
    }
    if (obj->geometry.source) {
        c->geometry.source = vv_strdup(obj->geometry.source);
        if (!c->geometry.source)
            goto nomem;
    }
    if (obj->solid_texture.source) {
        c->solid_texture.source = vv_strdup(obj->solid_texture.source);
        if (!c->solid_texture.source)
            goto nomem;
    }
    if (obj->geometry.filters) {
        c->geometry.filters = vv_strdup(obj->geometry.filters);
        if (!c->geometry.filters)
            goto nomem;
    }
    if (c->volume)
        vv_volume_ref(c->volume);
    if (c->grid)
        vv_grid_ref(c->grid);
    if (c->geometry.mesh)
        vv_mesh_ref(c->geometry.mesh);
    vv_texture_image_ref(c->texture.image);
    if (c->solid_texture.volume)
        vv_volume_ref(c->solid_texture.volume);
    for (int k = 0; k < c->n_channels; k++)
        vv_volume_ref(c->channels[k].volume);
    vv_source_ref(c->source);
    *out = c;
    return VV_OK;
nomem:
    free(c->channels);
    free(c->geometry.vertices);
    free(c->geometry.source);
    free(c->solid_texture.source);
    free(c->geometry.filters);
    free(c);
    return vv_error_set(VV_ERR_NOMEM, "object clone: out of memory");
}

vv_mat4
vv_object_matrix(const vv_object *obj) {
    if (!obj)
        return vv_mat4_identity();
    vv_mat4 t = vv_mat4_translate(obj->position);
    vv_mat4 r = vv_quat_to_mat4(vv_quat_normalize(obj->orientation));
    vv_mat4 s = vv_mat4_scale(obj->scale);
    return vv_mat4_mul(t, vv_mat4_mul(r, s));
}

vv_mat4
vv_object_index_to_world(const vv_object *obj) {
    if (!obj || !obj->volume)
        return vv_object_matrix(obj);
    return vv_mat4_mul(vv_object_matrix(obj), vv_volume_index_to_world(obj->volume));
}

/* Object-space bounds of a shape (its geometry-type record's, or the
 * grid's); 0 for an unbounded or empty one. */
static int
geometry_bounds(const vv_object *obj, vv_box *b) {
    if (obj->type == VV_OBJECT_GRID) {
        if (!obj->grid || obj->grid->n_points == 0)
            return 0;
        *b = vv_grid_bounds(obj->grid);
        return 1;
    }
    const vv_geom_type *gt = vv_geom_type_get(obj->type);
    return gt ? gt->bounds(&obj->geometry, b) : 0;
}

vv_box
vv_object_world_box(const vv_object *obj) {
    vv_box b = {{0, 0, 0}, {0, 0, 0}};
    if (!obj)
        return b;
    if (obj->type != VV_OBJECT_VOLUME) {
        vv_box ob;
        if (!geometry_bounds(obj, &ob)) {
            b.min = vv_vec3_make(1, 1, 1);
            b.max = vv_vec3_make(-1, -1, -1);
            return b;
        }
        return vv_box_transform(ob, vv_object_matrix(obj));
    }
    if (!obj->volume)
        return b;
    vv_box idx = {
        {0, 0, 0},
        {obj->volume->dims[0] - 1.0, obj->volume->dims[1] - 1.0, obj->volume->dims[2] - 1.0}};
    return vv_box_transform(idx, vv_object_index_to_world(obj));
}
