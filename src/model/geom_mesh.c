/*
 * The mesh record of the geometry-type table: geometry.mesh, a triangle mesh
 * taken as a solid whose triangles turn counter-clockwise seen from outside
 * (volvis/mesh.h). Its queries go through one bounding volume hierarchy over
 * the triangles (core/bvh.h), built by prepare.
 */
#include <math.h>
#include <stdlib.h>

#include "core/bvh.h"
#include "core/geom.h"
#include "volvis/sys/geometry.h"

static vv_status
mesh_check(const vv_geometry *g) {
    if (!g->mesh)
        return vv_error_set(VV_ERR_INVALID, "mesh object without a mesh");
    return VV_OK;
}

static int
mesh_solid(const vv_geometry *g) {
    (void)g;
    return 1;
}

static int
mesh_bounds(const vv_geometry *g, vv_box *b) {
    if (!g->mesh || g->mesh->n_vertices == 0)
        return 0;
    *b = vv_mesh_bounds(g->mesh);
    return 1;
}

static vv_status
mesh_tessellate(const vv_geometry *g, const vv_geom_tess *opt, vv_mesh **out) {
    (void)opt;
    vv_status s = mesh_check(g);
    if (s != VV_OK)
        return s;
    *out = vv_mesh_ref(g->mesh);
    return VV_OK;
}

static vv_status
mesh_prepare(const vv_geometry *g, void **prep) {
    vv_status s = mesh_check(g);
    if (s != VV_OK)
        return s;
    vv_bvh *b = malloc(sizeof *b);
    if (!b)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    s = vv_bvh_build_triangles(b, g->mesh->positions, g->mesh->triangles, g->mesh->n_triangles);
    if (s != VV_OK) {
        free(b);
        return s;
    }
    *prep = b;
    return VV_OK;
}

static void
mesh_release(void *prep) {
    vv_bvh_clear(prep);
    free(prep);
}

static inline void
tri_corners(const vv_mesh *m, uint32_t t, vv_vec3 *a, vv_vec3 *e1, vv_vec3 *e2) {
    const uint32_t *tr = m->triangles + 3 * (size_t)t;
    *a = vv_v3_f(m->positions + 3 * (size_t)tr[0]);
    *e1 = vv_v3_sub(vv_v3_f(m->positions + 3 * (size_t)tr[1]), *a);
    *e2 = vv_v3_sub(vv_v3_f(m->positions + 3 * (size_t)tr[2]), *a);
}

typedef struct mesh_ray {
    const vv_mesh *m;
    vv_vec3 o, d;
    double tmin;
    double t;    /* nearest hit so far */
    vv_vec3 n;   /* its triangle's normal */
    int hit;     /* a hit was found */
    int winding; /* all crossings beyond 0: their signed count (mesh_winding) */
} mesh_ray;

/* Nearest hit in the leaf: of equal t, the first triangle tested keeps it. */
static int
leaf_nearest(void *ctx, const uint32_t *items, int count, double *t1) {
    mesh_ray *r = ctx;
    for (int i = 0; i < count; i++) {
        vv_vec3 a, e1, e2;
        double t, u, v;
        tri_corners(r->m, items[i], &a, &e1, &e2);
        if (vv_ray_triangle(r->o, r->d, a, e1, e2, &t, &u, &v) && t > r->tmin && t < *t1) {
            *t1 = r->t = t;
            r->n = vv_v3_cross(e1, e2);
            r->hit = 1;
        }
    }
    return 0;
}

static int
mesh_intersect(const vv_geometry *g, const void *prep, vv_vec3 o, vv_vec3 d, double tmin,
               double tmax, double *t, vv_vec3 *n) {
    mesh_ray r = {g->mesh, o, d, tmin, tmax, {0, 0, 1}, 0, 0};
    const double oo[3] = {o.x, o.y, o.z}, inv[3] = {1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
    /* boxes from 0 (the triangles test tmin) */
    vv_bvh_ray(prep, oo, inv, 0, tmax, leaf_nearest, &r);
    if (!r.hit)
        return 0;
    *t = r.t;
    *n = r.n;
    return 1;
}

/* Every crossing beyond the origin, counted +1 leaving (along the outward
 * normal) and -1 entering. */
static int
leaf_crossings(void *ctx, const uint32_t *items, int count, double *t1) {
    mesh_ray *r = ctx;
    (void)t1;
    for (int i = 0; i < count; i++) {
        vv_vec3 a, e1, e2;
        double t, u, v;
        tri_corners(r->m, items[i], &a, &e1, &e2);
        if (vv_ray_triangle(r->o, r->d, a, e1, e2, &t, &u, &v) && t > 0) {
            const double dn = vv_v3_dot(r->d, vv_v3_cross(e1, e2));
            r->winding += dn > 0 ? 1 : dn < 0 ? -1 : 0;
        }
    }
    return 0;
}

/* Whether q is inside: the winding number along three rays in directions
 * that no axis-aligned or diagonal edge is parallel to; two of three decide
 * (a ray through an edge or a vertex may count a crossing twice or never). */
static int
mesh_inside(const vv_mesh *m, const vv_bvh *b, vv_vec3 q) {
    static const double dir[3][3] = {
        {0.9270, 0.3174, 0.1998}, {-0.2893, 0.8712, 0.3965}, {0.1537, -0.4286, 0.8904}};
    int votes = 0;
    for (int k = 0; k < 3; k++) {
        const vv_vec3 d = vv_v3(dir[k][0], dir[k][1], dir[k][2]);
        mesh_ray r = {m, q, d, 0, INFINITY, {0, 0, 1}, 0, 0};
        const double oo[3] = {q.x, q.y, q.z}, inv[3] = {1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
        vv_bvh_ray(b, oo, inv, 0, INFINITY, leaf_crossings, &r);
        votes += r.winding != 0;
    }
    return votes >= 2;
}

typedef struct mesh_near {
    const vv_mesh *m;
    vv_vec3 q;
    double best; /* squared distance */
} mesh_near;

static int
box_near(void *ctx, const float lo[3], const float hi[3]) {
    const mesh_near *c = ctx;
    return vv_box_distance2_f(lo, hi, c->q) <= c->best;
}

static int
leaf_near(void *ctx, const uint32_t *items, int count) {
    mesh_near *c = ctx;
    for (int i = 0; i < count; i++) {
        const uint32_t *tr = c->m->triangles + 3 * (size_t)items[i];
        const vv_vec3 p = vv_closest_point_triangle(c->q, vv_v3_f(c->m->positions + 3 * tr[0]),
                                                    vv_v3_f(c->m->positions + 3 * tr[1]),
                                                    vv_v3_f(c->m->positions + 3 * tr[2]));
        const vv_vec3 w = vv_v3_sub(p, c->q);
        const double d2 = vv_v3_dot(w, w);
        c->best = d2 < c->best ? d2 : c->best;
    }
    return 0;
}

static double
mesh_distance(const vv_geometry *g, const void *prep, vv_vec3 q) {
    const vv_bvh *b = prep;
    mesh_near c = {g->mesh, q, INFINITY};
    vv_bvh_query(b, box_near, leaf_near, &c);
    const double d = sqrt(c.best);
    return mesh_inside(g->mesh, b, q) ? -d : d;
}

const vv_geom_type vv_geom_mesh = {
    .version = VV_GEOM_TYPE_VERSION,
    .type = VV_OBJECT_MESH,
    .name = "mesh",
    .check = mesh_check,
    .solid = mesh_solid,
    .bounds = mesh_bounds,
    .tessellate = mesh_tessellate,
    .prepare = mesh_prepare,
    .release = mesh_release,
    .intersect = mesh_intersect,
    .distance = mesh_distance,
};
