/*
 * Measures of the World's geometric objects: area, enclosed volume and the
 * distance between two objects, over their tessellations by the
 * geometry-type table (include/volvis/sys/geometry.h) in world coordinates.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "measure_internal.h"
#include "volvis/sys/geometry.h"

/* The object's triangles in world coordinates within @p tolerance world
 * units (a new mesh the caller frees), and whether they enclose a volume. */
static vv_status
world_triangles(const vv_object *obj, double tolerance, vv_mesh **out, int *solid) {
    *out = NULL;
    if (!obj)
        return vv_error_set(VV_ERR_INVALID, "NULL object");
    const vv_geom_type *gt = vv_geom_type_get(obj->type);
    if (!gt)
        return vv_error_set(VV_ERR_INVALID, "object '%s': a %s is not a geometric shape", obj->name,
                            vv_object_type_name(obj->type));
    vv_status s = gt->check(&obj->geometry);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    vv_box b;
    if (!gt->bounds(&obj->geometry, &b))
        return vv_error_set(VV_ERR_INVALID, "object '%s': a %s is unbounded", obj->name, gt->name);
    /* object units: the world tolerance over the largest scale */
    const double scale = fmax(fabs(obj->scale.x), fmax(fabs(obj->scale.y), fabs(obj->scale.z)));
    if (!(scale > 0) || !isfinite(scale))
        return vv_error_set(VV_ERR_INVALID, "object '%s': scale %g %g %g", obj->name, obj->scale.x,
                            obj->scale.y, obj->scale.z);
    const double size = vv_vec3_length(vv_vec3_sub(b.max, b.min));
    const vv_geom_tess opt = {.tolerance = tolerance > 0 ? tolerance / scale : 1e-3 * size};
    vv_mesh *m = NULL;
    if ((s = gt->tessellate(&obj->geometry, &opt, &m)) != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    /* a copy of the positions and triangles (a mesh object's tessellation is
     * the object's own mesh), moved to the world */
    vv_mesh *w = NULL;
    s = vv_mesh_new(&w);
    if (s == VV_OK)
        s = vv_mesh_reserve(w, m->n_vertices, m->n_triangles);
    if (s == VV_OK) {
        memcpy(w->positions, m->positions, 3 * m->n_vertices * sizeof *w->positions);
        memcpy(w->triangles, m->triangles, 3 * m->n_triangles * sizeof *w->triangles);
        w->n_vertices = m->n_vertices;
        w->n_triangles = m->n_triangles;
        vv_mesh_transform(w, vv_object_matrix(obj));
    }
    vv_mesh_free(m);
    if (s != VV_OK) {
        vv_mesh_free(w);
        return vv_error_prefix(s, "object '%s'", obj->name);
    }
    *out = w;
    *solid = gt->solid(&obj->geometry);
    return VV_OK;
}

vv_status
vv_measure_object(const vv_object *obj, double tolerance, vv_object_measure *out) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "measure object: NULL argument");
    memset(out, 0, sizeof *out);
    vv_mesh *m = NULL;
    int solid = 0;
    vv_status s = world_triangles(obj, tolerance, &m, &solid);
    if (s != VV_OK)
        return vv_error_prefix(s, "measure object");
    out->area = vv_mesh_area(m);
    out->volume = solid ? fabs(vv_mesh_signed_volume(m)) : 0;
    out->solid = solid;
    out->n_triangles = m->n_triangles;
    vv_mesh_free(m);
    return VV_OK;
}

vv_status
vv_measure_object_distance(const vv_object *a, const vv_object *b, double tolerance, int threads,
                           double *dist, vv_vec3 *pa, vv_vec3 *pb) {
    if (!dist)
        return vv_error_set(VV_ERR_INVALID, "object distance: NULL argument");
    vv_mesh *ma = NULL, *mb = NULL;
    int solid;
    vv_status s = world_triangles(a, tolerance, &ma, &solid);
    if (s == VV_OK)
        s = world_triangles(b, tolerance, &mb, &solid);
    if (s == VV_OK)
        s = vv_measure_mesh_distance(ma, mb, threads, dist, pa, pb);
    vv_mesh_free(ma);
    vv_mesh_free(mb);
    return s == VV_OK ? VV_OK : vv_error_prefix(s, "object distance");
}
