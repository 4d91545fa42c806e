/* The sphere record of the geometry-type table: geometry.center, geometry.radius. */
#include <math.h>

#include "core/geom.h"
#include "model/model_internal.h"
#include "volvis/sys/geometry.h"

static vv_status
sphere_check(const vv_geometry *g) {
    if (!(g->radius > 0) || !isfinite(g->radius))
        return vv_error_set(VV_ERR_INVALID, "sphere radius must be > 0");
    return VV_OK;
}

static int
sphere_solid(const vv_geometry *g) {
    (void)g;
    return 1;
}

static int
sphere_bounds(const vv_geometry *g, vv_box *b) {
    vv_vec3 r = {g->radius, g->radius, g->radius};
    b->min = vv_vec3_sub(g->center, r);
    b->max = vv_vec3_add(g->center, r);
    return 1;
}

/* UV sphere: `seg` meridians, seg / 2 bands of parallels, one vertex per pole. */
static vv_status
sphere_tessellate(const vv_geometry *g, const vv_geom_tess *opt, vv_mesh **out) {
    vv_status s = sphere_check(g);
    if (s != VV_OK)
        return s;
    const vv_vec3 c = g->center;
    const double r = g->radius;
    int seg = vv_geom_tess_segments(opt, r);
    const int nlat = seg / 2 < 2 ? 2 : seg / 2;
    s = vv_geom_mesh_new(out, (size_t)(nlat - 1) * (size_t)seg + 2, 2 * (size_t)nlat * seg);
    vv_mesh *m = *out;
    s = s == VV_OK ? vv_geom_mesh_vertex(m, vv_vec3_add(c, vv_v3(0, 0, r)), vv_v3(0, 0, 1)) : s;
    for (int i = 1; i < nlat && s == VV_OK; i++) {
        const double th = VV_PI * i / nlat;
        for (int j = 0; j < seg && s == VV_OK; j++) {
            const double ph = 2 * VV_PI * j / seg;
            vv_vec3 n = vv_v3(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
            s = vv_geom_mesh_vertex(m, vv_vec3_add(c, vv_vec3_scale(n, r)), n);
        }
    }
    if (s == VV_OK)
        s = vv_geom_mesh_vertex(m, vv_vec3_add(c, vv_v3(0, 0, -r)), vv_v3(0, 0, -1));
    const uint32_t south = (uint32_t)((nlat - 1) * seg + 1);
    for (int j = 0; j < seg && s == VV_OK; j++) {
        const uint32_t j1 = (uint32_t)((j + 1) % seg);
        s = vv_mesh_add_triangle(m, 0, 1 + (uint32_t)j, 1 + j1);
        for (int i = 1; i + 1 < nlat && s == VV_OK; i++) {
            const uint32_t a = 1 + (uint32_t)((i - 1) * seg + j),
                           d = 1 + (uint32_t)((i - 1) * seg) + j1;
            const uint32_t b = a + (uint32_t)seg, cc = d + (uint32_t)seg;
            s = vv_mesh_add_triangle(m, a, b, cc);
            if (s == VV_OK)
                s = vv_mesh_add_triangle(m, a, cc, d);
        }
        if (s == VV_OK) {
            const uint32_t base = 1 + (uint32_t)((nlat - 2) * seg);
            s = vv_mesh_add_triangle(m, base + (uint32_t)j, south, base + j1);
        }
    }
    if (s != VV_OK) {
        vv_mesh_free(*out);
        *out = NULL;
    }
    return s;
}

static int
sphere_intersect(const vv_geometry *g, const void *prep, vv_vec3 o, vv_vec3 d, double tmin,
                 double tmax, double *t, vv_vec3 *n) {
    (void)prep;
    const vv_vec3 oc = vv_v3_sub(o, g->center);
    const double a = vv_v3_dot(d, d), b = vv_v3_dot(oc, d),
                 c = vv_v3_dot(oc, oc) - g->radius * g->radius;
    const double disc = b * b - a * c;
    if (disc < 0)
        return 0;
    const double sq = sqrt(disc);
    const double t0 = (-b - sq) / a, t1 = (-b + sq) / a;
    const double th = t0 > tmin ? t0 : t1;
    if (!(th > tmin && th < tmax))
        return 0;
    *t = th;
    *n = vv_v3_sub(vv_v3_add(o, vv_v3_scale(d, th)), g->center);
    return 1;
}

static double
sphere_distance(const vv_geometry *g, const void *prep, vv_vec3 q) {
    (void)prep;
    return vv_geom_sphere_distance(vv_v3_sub(q, g->center), g->radius);
}

const vv_geom_type vv_geom_sphere = {
    .version = VV_GEOM_TYPE_VERSION,
    .type = VV_OBJECT_SPHERE,
    .name = "sphere",
    .check = sphere_check,
    .solid = sphere_solid,
    .bounds = sphere_bounds,
    .tessellate = sphere_tessellate,
    .intersect = sphere_intersect,
    .distance = sphere_distance,
};
