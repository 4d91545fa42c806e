/*
 * The cylinder record of the geometry-type table: the axis from
 * geometry.base to geometry.top, geometry.radius, closed with discs when
 * geometry.capped (a solid), else an open tube (a surface facing outwards).
 */
#include <math.h>

#include "core/geom.h"
#include "model/model_internal.h"
#include "volvis/sys/geometry.h"

static vv_status
cylinder_check(const vv_geometry *g) {
    if (!(g->radius > 0) || !(vv_v3_len(vv_v3_sub(g->top, g->base)) > 0))
        return vv_error_set(VV_ERR_INVALID, "cylinder needs radius > 0 and base != top");
    return VV_OK;
}

static int
cylinder_solid(const vv_geometry *g) {
    return g->capped != 0;
}

/* Exact bounds of the two cap discs. */
static int
cylinder_bounds(const vv_geometry *g, vv_box *b) {
    vv_vec3 a = vv_vec3_sub(g->top, g->base);
    double l2 = vv_vec3_dot(a, a);
    if (!(l2 > 0))
        return 0;
    vv_vec3 ev = {g->radius * sqrt(fmax(0.0, 1.0 - a.x * a.x / l2)),
                  g->radius * sqrt(fmax(0.0, 1.0 - a.y * a.y / l2)),
                  g->radius * sqrt(fmax(0.0, 1.0 - a.z * a.z / l2))};
    vv_vec3 lo = {fmin(g->base.x, g->top.x), fmin(g->base.y, g->top.y), fmin(g->base.z, g->top.z)};
    vv_vec3 hi = {fmax(g->base.x, g->top.x), fmax(g->base.y, g->top.y), fmax(g->base.z, g->top.z)};
    b->min = vv_vec3_sub(lo, ev);
    b->max = vv_vec3_add(hi, ev);
    return 1;
}

/* Side: a bottom and a top ring of `seg` vertices; caps: a centre and a ring each. */
static vv_status
cylinder_tessellate(const vv_geometry *g, const vv_geom_tess *opt, vv_mesh **out) {
    vv_status s = cylinder_check(g);
    if (s != VV_OK)
        return s;
    const vv_vec3 base = g->base, top = g->top;
    const double r = g->radius;
    const int seg = vv_geom_tess_segments(opt, r);
    vv_vec3 e = vv_vec3_normalize(vv_vec3_sub(top, base)), p1, p2;
    vv_geom_perpendicular(e, &p1, &p2);
    s = vv_geom_mesh_new(out, 4 * (size_t)seg + 2, 4 * (size_t)seg);
    vv_mesh *m = *out;
    for (int ring = 0; ring < 2 && s == VV_OK; ring++)
        for (int j = 0; j < seg && s == VV_OK; j++) {
            const double ph = 2 * VV_PI * j / seg;
            vv_vec3 n = vv_vec3_add(vv_vec3_scale(p1, cos(ph)), vv_vec3_scale(p2, sin(ph)));
            s = vv_geom_mesh_vertex(m, vv_vec3_add(ring ? top : base, vv_vec3_scale(n, r)), n);
        }
    for (int j = 0; j < seg && s == VV_OK; j++) {
        const uint32_t bl = (uint32_t)j, br = (uint32_t)((j + 1) % seg);
        s = vv_mesh_add_triangle(m, bl, br, br + (uint32_t)seg);
        if (s == VV_OK)
            s = vv_mesh_add_triangle(m, bl, br + (uint32_t)seg, bl + (uint32_t)seg);
    }
    for (int cap = 0; cap < 2 && g->capped && s == VV_OK; cap++) {
        vv_vec3 n = cap ? e : vv_vec3_scale(e, -1), c = cap ? top : base;
        const uint32_t centre = (uint32_t)m->n_vertices;
        s = vv_geom_mesh_vertex(m, c, n);
        for (int j = 0; j < seg && s == VV_OK; j++) {
            const double ph = 2 * VV_PI * j / seg;
            vv_vec3 q = vv_vec3_add(vv_vec3_scale(p1, cos(ph)), vv_vec3_scale(p2, sin(ph)));
            s = vv_geom_mesh_vertex(m, vv_vec3_add(c, vv_vec3_scale(q, r)), n);
        }
        for (int j = 0; j < seg && s == VV_OK; j++) {
            const uint32_t a = centre + 1 + (uint32_t)j, b = centre + 1 + (uint32_t)((j + 1) % seg);
            s = cap ? vv_mesh_add_triangle(m, centre, a, b) : vv_mesh_add_triangle(m, centre, b, a);
        }
    }
    if (s != VV_OK) {
        vv_mesh_free(*out);
        *out = NULL;
    }
    return s;
}

/* The side (a quadric in the plane across the axis), then the cap discs. */
static int
cylinder_intersect(const vv_geometry *g, const void *prep, vv_vec3 o, vv_vec3 d, double tmin,
                   double tmax, double *t, vv_vec3 *nrm) {
    (void)prep;
    const vv_vec3 axis = vv_v3_sub(g->top, g->base);
    const double h = vv_v3_len(axis);
    if (!(h > 0))
        return 0;
    const vv_vec3 a = vv_v3_scale(axis, 1.0 / h);
    const vv_vec3 oc = vv_v3_sub(o, g->base);
    const double da = vv_v3_dot(d, a), oa = vv_v3_dot(oc, a);
    const vv_vec3 dp = vv_v3_sub(d, vv_v3_scale(a, da)), op = vv_v3_sub(oc, vv_v3_scale(a, oa));
    const double A = vv_v3_dot(dp, dp), B = vv_v3_dot(op, dp),
                 C = vv_v3_dot(op, op) - g->radius * g->radius;
    double th = INFINITY;
    vv_vec3 n = {0, 0, 1};
    if (A > 1e-300) {
        const double disc = B * B - A * C;
        if (disc >= 0) {
            const double sq = sqrt(disc);
            const double ts[2] = {(-B - sq) / A, (-B + sq) / A};
            for (int i = 0; i < 2; i++) {
                const double z = oa + ts[i] * da;
                if (ts[i] > tmin && ts[i] < th && z >= 0 && z <= h) {
                    th = ts[i];
                    n = vv_v3_add(op, vv_v3_scale(dp, ts[i]));
                }
            }
        }
    }
    if (g->capped && fabs(da) > 1e-300) {
        for (int i = 0; i < 2; i++) {
            const double tc = ((i ? h : 0) - oa) / da;
            if (!(tc > tmin && tc < th))
                continue;
            const vv_vec3 q = vv_v3_add(op, vv_v3_scale(dp, tc));
            if (vv_v3_dot(q, q) <= g->radius * g->radius) {
                th = tc;
                n = i ? a : vv_v3_scale(a, -1);
            }
        }
    }
    if (!(th > tmin && th < tmax))
        return 0;
    *t = th;
    *nrm = n;
    return 1;
}

/* Capped: the prism distance of the radial and axial distances. Open: the
 * distance to the tube, negative inside its radius. */
static double
cylinder_distance(const vv_geometry *g, const void *prep, vv_vec3 q) {
    (void)prep;
    const vv_vec3 axis = vv_v3_sub(g->top, g->base);
    const double h = vv_v3_len(axis);
    const vv_vec3 a = vv_v3_scale(axis, h > 0 ? 1.0 / h : 0);
    const vv_vec3 qc = vv_v3_sub(q, g->base);
    const double z = vv_v3_dot(qc, a);
    const double radial = vv_v3_len(vv_v3_sub(qc, vv_v3_scale(a, z))) - g->radius;
    const double axial = fabs(z - 0.5 * h) - 0.5 * h;
    if (g->capped)
        return vv_geom_prism_distance(radial, axial);
    const double d = axial > 0 ? sqrt(axial * axial + radial * radial) : fabs(radial);
    return radial < 0 ? -d : d;
}

const vv_geom_type vv_geom_cylinder = {
    .version = VV_GEOM_TYPE_VERSION,
    .type = VV_OBJECT_CYLINDER,
    .name = "cylinder",
    .check = cylinder_check,
    .solid = cylinder_solid,
    .bounds = cylinder_bounds,
    .tessellate = cylinder_tessellate,
    .intersect = cylinder_intersect,
    .distance = cylinder_distance,
};
