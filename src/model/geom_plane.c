/*
 * The plane record of the geometry-type table: the infinite plane through
 * geometry.point with unit normal geometry.normal (its front side). It has
 * no bounds; it is tessellated as a large square around a point of interest.
 */
#include <math.h>

#include "core/geom.h"
#include "model/model_internal.h"
#include "volvis/sys/geometry.h"

static vv_status
plane_check(const vv_geometry *g) {
    if (!(vv_v3_len(g->normal) > 0))
        return vv_error_set(VV_ERR_INVALID, "plane with a zero normal");
    return VV_OK;
}

static int
plane_solid(const vv_geometry *g) {
    (void)g;
    return 0;
}

static int
plane_bounds(const vv_geometry *g, vv_box *b) {
    (void)g;
    (void)b;
    return 0;
}

/* A 16 x 16 grid of quads, opt->half on each side of the point of the plane
 * nearest opt->center. */
static vv_status
plane_tessellate(const vv_geometry *g, const vv_geom_tess *opt, vv_mesh **out) {
    enum { G = 16 };
    vv_status s = plane_check(g);
    if (s != VV_OK)
        return s;
    const vv_vec3 n = g->normal;
    const vv_vec3 c = vv_vec3_sub(
        opt->center, vv_vec3_scale(n, vv_vec3_dot(n, vv_vec3_sub(opt->center, g->point))));
    const double half = opt->half;
    vv_vec3 p1, p2;
    vv_geom_perpendicular(n, &p1, &p2);
    s = vv_geom_mesh_new(out, (G + 1) * (G + 1), 2 * G * G);
    vv_mesh *m = *out;
    for (int j = 0; j <= G && s == VV_OK; j++)
        for (int i = 0; i <= G && s == VV_OK; i++) {
            const double u = half * (2.0 * i / G - 1), v = half * (2.0 * j / G - 1);
            s = vv_geom_mesh_vertex(
                m, vv_vec3_add(c, vv_vec3_add(vv_vec3_scale(p1, u), vv_vec3_scale(p2, v))), n);
        }
    for (int j = 0; j < G && s == VV_OK; j++)
        for (int i = 0; i < G && s == VV_OK; i++) {
            const uint32_t a = (uint32_t)(j * (G + 1) + i);
            s = vv_mesh_add_triangle(m, a, a + 1, a + G + 2);
            if (s == VV_OK)
                s = vv_mesh_add_triangle(m, a, a + G + 2, a + G + 1);
        }
    if (s != VV_OK) {
        vv_mesh_free(*out);
        *out = NULL;
    }
    return s;
}

static int
plane_intersect(const vv_geometry *g, const void *prep, vv_vec3 o, vv_vec3 d, double tmin,
                double tmax, double *t, vv_vec3 *n) {
    (void)prep;
    const double dn = vv_v3_dot(g->normal, d);
    if (fabs(dn) < 1e-300)
        return 0;
    const double tp = vv_v3_dot(g->normal, vv_v3_sub(g->point, o)) / dn;
    if (!(tp > tmin && tp < tmax))
        return 0;
    *t = tp;
    *n = g->normal;
    return 1;
}

static double
plane_distance(const vv_geometry *g, const void *prep, vv_vec3 q) {
    (void)prep;
    return vv_v3_dot(g->normal, vv_v3_sub(q, g->point)) / vv_v3_len(g->normal);
}

const vv_geom_type vv_geom_plane = {
    .version = VV_GEOM_TYPE_VERSION,
    .type = VV_OBJECT_PLANE,
    .name = "plane",
    .check = plane_check,
    .solid = plane_solid,
    .bounds = plane_bounds,
    .tessellate = plane_tessellate,
    .intersect = plane_intersect,
    .distance = plane_distance,
};
