/*
 * The polygon record of the geometry-type table: geometry.vertices (n >= 3,
 * planar, simple, either winding). Its front is the side of its Newell
 * normal, the one its vertices turn counter-clockwise around.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "model/model_internal.h"
#include "volvis/sys/geometry.h"

/* What intersect and distance need: the plane, and the axis dropped to test
 * inside the polygon in 2-D (the normal's largest component). */
typedef struct polygon_prep {
    vv_plane plane;
    int drop;
} polygon_prep;

static vv_status
polygon_check(const vv_geometry *g) {
    if (g->n_vertices < 3 || !g->vertices)
        return vv_error_set(VV_ERR_INVALID, "polygon with %d vertices",
                            g->vertices ? g->n_vertices : 0);
    if (!(vv_v3_len(vv_geom_newell(g->vertices, g->n_vertices)) > 0))
        return vv_error_set(VV_ERR_INVALID, "degenerate polygon");
    return VV_OK;
}

static int
polygon_solid(const vv_geometry *g) {
    (void)g;
    return 0;
}

static int
polygon_bounds(const vv_geometry *g, vv_box *b) {
    if (g->n_vertices < 1 || !g->vertices)
        return 0;
    b->min = b->max = g->vertices[0];
    for (int i = 1; i < g->n_vertices; i++) {
        b->min = vv_v3_min(b->min, g->vertices[i]);
        b->max = vv_v3_max(b->max, g->vertices[i]);
    }
    return 1;
}

/* 1 when no other remaining vertex lies in the triangle a b c (2-D, q). */
static int
ear_empty(const double (*q)[2], const int *idx, int k, int a, int b, int c) {
    for (int j = 0; j < k; j++) {
        const int p = idx[j];
        if (p == a || p == b || p == c)
            continue;
        const double d1 =
            (q[b][0] - q[a][0]) * (q[p][1] - q[a][1]) - (q[b][1] - q[a][1]) * (q[p][0] - q[a][0]);
        const double d2 =
            (q[c][0] - q[b][0]) * (q[p][1] - q[b][1]) - (q[c][1] - q[b][1]) * (q[p][0] - q[b][0]);
        const double d3 =
            (q[a][0] - q[c][0]) * (q[p][1] - q[c][1]) - (q[a][1] - q[c][1]) * (q[p][0] - q[c][0]);
        if (d1 >= 0 && d2 >= 0 && d3 >= 0)
            return 0;
    }
    return 1;
}

/* Ear clipping in the plane of the Newell normal; triangles keep the
 * polygon's own winding. The search for an ear starts at the second
 * remaining vertex, so a convex polygon becomes the fan from its first
 * vertex (0, i, i + 1). */
static vv_status
polygon_tessellate(const vv_geometry *g, const vv_geom_tess *opt, vv_mesh **out) {
    (void)opt;
    vv_status s = polygon_check(g);
    if (s != VV_OK)
        return s;
    const vv_vec3 *v = g->vertices;
    const int n = g->n_vertices;
    vv_vec3 nn = vv_vec3_normalize(vv_geom_newell(v, n)), p1, p2;
    vv_geom_perpendicular(nn, &p1, &p2);
    s = vv_geom_mesh_new(out, (size_t)n, (size_t)n);
    vv_mesh *m = *out;
    for (int i = 0; i < n && s == VV_OK; i++)
        s = vv_geom_mesh_vertex(m, v[i], nn);
    int *idx = malloc((size_t)n * sizeof *idx);
    double(*q)[2] = malloc((size_t)n * sizeof *q);
    if (s == VV_OK && (!idx || !q))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < n && s == VV_OK; i++) {
        idx[i] = i;
        q[i][0] = vv_vec3_dot(v[i], p1);
        q[i][1] = vv_vec3_dot(v[i], p2);
    }
    /* counter-clockwise in (p1, p2) because p1 x p2 = the Newell normal */
    int k = n;
    while (k > 3 && s == VV_OK) {
        int found = -1;
        for (int ii = 0; ii < k && found < 0; ii++) {
            const int i = (ii + 1) % k;
            const int a = idx[(i + k - 1) % k], b = idx[i], c = idx[(i + 1) % k];
            const double cr = (q[b][0] - q[a][0]) * (q[c][1] - q[a][1]) -
                              (q[b][1] - q[a][1]) * (q[c][0] - q[a][0]);
            if (cr > 0 && ear_empty((const double(*)[2])q, idx, k, a, b, c))
                found = i;
        }
        if (found < 0)
            found = 1; /* self-intersecting input: clip anyway */
        const int a = idx[(found + k - 1) % k], b = idx[found], c = idx[(found + 1) % k];
        s = vv_mesh_add_triangle(m, (uint32_t)a, (uint32_t)b, (uint32_t)c);
        memmove(idx + found, idx + found + 1, (size_t)(k - found - 1) * sizeof *idx);
        k--;
    }
    if (s == VV_OK)
        s = vv_mesh_add_triangle(m, (uint32_t)idx[0], (uint32_t)idx[1], (uint32_t)idx[2]);
    free(idx);
    free(q);
    if (s != VV_OK) {
        vv_mesh_free(*out);
        *out = NULL;
    }
    return s;
}

static vv_status
polygon_prepare(const vv_geometry *g, void **prep) {
    vv_status s = polygon_check(g);
    if (s != VV_OK)
        return s;
    polygon_prep *p = malloc(sizeof *p);
    if (!p)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    const vv_vec3 nn = vv_geom_newell(g->vertices, g->n_vertices);
    p->plane = vv_plane_from_point_normal(g->vertices[0], nn);
    const double ax = fabs(nn.x), ay = fabs(nn.y), az = fabs(nn.z);
    p->drop = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
    *prep = p;
    return VV_OK;
}

static void
polygon_release(void *prep) {
    free(prep);
}

/* Even-odd test of the point p of the polygon's plane, in 2-D without the
 * dropped axis. */
static int
polygon_inside(const vv_geometry *g, const polygon_prep *pp, vv_vec3 p) {
    const int u = pp->drop == 0 ? 1 : 0, v = pp->drop == 2 ? 1 : 2;
    const double pu = vv_v3_axis(p, u), pv = vv_v3_axis(p, v);
    int inside = 0;
    for (int i = 0, j = g->n_vertices - 1; i < g->n_vertices; j = i++) {
        const double ui = vv_v3_axis(g->vertices[i], u), vi = vv_v3_axis(g->vertices[i], v);
        const double uj = vv_v3_axis(g->vertices[j], u), vj = vv_v3_axis(g->vertices[j], v);
        if ((vi > pv) != (vj > pv) && pu < (uj - ui) * (pv - vi) / (vj - vi) + ui)
            inside = !inside;
    }
    return inside;
}

static int
polygon_intersect(const vv_geometry *g, const void *prep, vv_vec3 o, vv_vec3 d, double tmin,
                  double tmax, double *t, vv_vec3 *n) {
    const polygon_prep *pp = prep;
    const double dn = vv_v3_dot(pp->plane.n, d);
    if (fabs(dn) < 1e-300)
        return 0;
    const double th = -vv_plane_distance(pp->plane, o) / dn;
    if (!(th > tmin && th < tmax))
        return 0;
    if (!polygon_inside(g, pp, vv_v3_add(o, vv_v3_scale(d, th))))
        return 0;
    *t = th;
    *n = pp->plane.n;
    return 1;
}

/* Distance to the polygon's region: to its plane where q projects inside,
 * else to its nearest edge; negative behind the front. */
static double
polygon_distance(const vv_geometry *g, const void *prep, vv_vec3 q) {
    const polygon_prep *pp = prep;
    const double h = vv_plane_distance(pp->plane, q);
    double dist;
    if (polygon_inside(g, pp, vv_v3_sub(q, vv_v3_scale(pp->plane.n, h)))) {
        dist = fabs(h);
    } else {
        double best = INFINITY;
        for (int i = 0, j = g->n_vertices - 1; i < g->n_vertices; j = i++) {
            const vv_vec3 a = g->vertices[j], e = vv_v3_sub(g->vertices[i], a);
            const vv_vec3 w = vv_v3_sub(q, a);
            const double ee = vv_v3_dot(e, e);
            double s = ee > 0 ? vv_v3_dot(w, e) / ee : 0;
            s = s < 0 ? 0 : s > 1 ? 1 : s;
            const vv_vec3 r = vv_v3_sub(w, vv_v3_scale(e, s));
            const double d2 = vv_v3_dot(r, r);
            best = d2 < best ? d2 : best;
        }
        dist = sqrt(best);
    }
    return h < 0 ? -dist : dist;
}

const vv_geom_type vv_geom_polygon = {
    .version = VV_GEOM_TYPE_VERSION,
    .type = VV_OBJECT_POLYGON,
    .name = "polygon",
    .check = polygon_check,
    .solid = polygon_solid,
    .bounds = polygon_bounds,
    .tessellate = polygon_tessellate,
    .prepare = polygon_prepare,
    .release = polygon_release,
    .intersect = polygon_intersect,
    .distance = polygon_distance,
};
