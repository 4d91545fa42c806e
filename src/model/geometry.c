/*
 * The geometry-type table (include/volvis/sys/geometry.h): one row per geometric
 * object type, and the helpers its record files share.
 */
#include "volvis/sys/geometry.h"

#include <math.h>
#include <stddef.h>

#include "core/geom.h"
#include "model/model_internal.h"

extern const vv_geom_type vv_geom_plane;
extern const vv_geom_type vv_geom_polygon;
extern const vv_geom_type vv_geom_sphere;
extern const vv_geom_type vv_geom_box;
extern const vv_geom_type vv_geom_cylinder;
extern const vv_geom_type vv_geom_mesh;

/* One row per primitive, in vv_object_type order (volumes and grids are not
 * geometry). */
static const vv_geom_type *const table[] = {
    &vv_geom_plane, &vv_geom_polygon,  &vv_geom_sphere,
    &vv_geom_box,   &vv_geom_cylinder, &vv_geom_mesh,
};

const vv_geom_type *
vv_geom_type_get(vv_object_type type) {
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (table[i]->type == type)
            return table[i];
    return NULL;
}

vv_status
vv_geom_object_type(const vv_object *obj, const vv_geom_type **out) {
    *out = NULL;
    const vv_geom_type *gt = vv_geom_type_get(obj->type);
    if (!gt)
        return vv_error_set(VV_ERR_INVALID, "object '%s': a %s is not a geometric shape", obj->name,
                            vv_object_type_name(obj->type));
    vv_status s = gt->check(&obj->geometry);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    *out = gt;
    return VV_OK;
}

const vv_geom_type *const *
vv_geom_types(int *n) {
    if (n)
        *n = (int)(sizeof table / sizeof table[0]);
    return table;
}

int
vv_geom_tess_segments(const vv_geom_tess *opt, double radius) {
    long n = opt->segments;
    if (n <= 0) {
        /* a chord of the angle 2 pi / n stands off the arc by r (1 - cos(pi / n)) */
        const double c = 1 - opt->tolerance / radius;
        n = !(opt->tolerance > 0) || !(radius > 0) ? 64 : c <= 0 ? 3 : (long)ceil(VV_PI / acos(c));
    }
    n = n < 3 ? 3 : n > 4096 ? 4096 : n;
    return (int)n;
}

vv_status
vv_geom_mesh_new(vv_mesh **out, size_t nv, size_t nt) {
    vv_status s = vv_mesh_new(out);
    if (s == VV_OK)
        s = vv_mesh_enable_attributes(*out, 1, 0);
    if (s == VV_OK)
        s = vv_mesh_reserve(*out, nv, nt);
    if (s != VV_OK) {
        vv_mesh_free(*out);
        *out = NULL;
    }
    return s;
}

vv_status
vv_geom_mesh_vertex(vv_mesh *m, vv_vec3 p, vv_vec3 n) {
    uint32_t i;
    vv_status s = vv_mesh_add_vertex(m, p, &i);
    if (s != VV_OK)
        return s;
    m->normals[3 * (size_t)i] = (float)n.x;
    m->normals[3 * (size_t)i + 1] = (float)n.y;
    m->normals[3 * (size_t)i + 2] = (float)n.z;
    return VV_OK;
}

void
vv_geom_perpendicular(vv_vec3 e, vv_vec3 *p1, vv_vec3 *p2) {
    vv_vec3 a = fabs(e.x) < 0.9 ? vv_v3(1, 0, 0) : vv_v3(0, 1, 0);
    *p1 = vv_vec3_normalize(vv_vec3_cross(a, e));
    *p2 = vv_vec3_cross(e, *p1);
}

vv_vec3
vv_geom_newell(const vv_vec3 *v, int n) {
    vv_vec3 nn = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        vv_vec3 a = v[i], b = v[(i + 1) % n];
        nn.x += (a.y - b.y) * (a.z + b.z);
        nn.y += (a.z - b.z) * (a.x + b.x);
        nn.z += (a.x - b.x) * (a.y + b.y);
    }
    return nn;
}

double
vv_geom_prism_distance(double a, double b) {
    double oa = a > 0 ? a : 0, ob = b > 0 ? b : 0;
    double in = a > b ? a : b;
    return (in < 0 ? in : 0) + sqrt(oa * oa + ob * ob);
}

double
vv_geom_box_distance(vv_vec3 q, vv_vec3 half, double rounding) {
    const double r = rounding;
    const double qx = fabs(q.x) - half.x + r, qy = fabs(q.y) - half.y + r,
                 qz = fabs(q.z) - half.z + r;
    const double ox = qx > 0 ? qx : 0, oy = qy > 0 ? qy : 0, oz = qz > 0 ? qz : 0;
    const double in = fmax(qx, fmax(qy, qz));
    return sqrt(ox * ox + oy * oy + oz * oz) + (in < 0 ? in : 0) - r;
}

double
vv_geom_sphere_distance(vv_vec3 q, double r) {
    return vv_v3_len(q) - r;
}
