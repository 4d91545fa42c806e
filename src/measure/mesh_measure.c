/*
 * Measures of geometric surface models (meshes): enclosed volume of a
 * closed mesh and the minimum distance between two meshes (exact
 * triangle-triangle distances; a bounding-volume hierarchy over the second
 * mesh prunes the pairs, parallel over the first mesh's triangles).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/bvh.h"
#include "core/geom.h"
#include "measure/measure_internal.h"

vv_status
vv_measure_mesh_volume(const vv_mesh *m, double *volume) {
    if (!m || !volume)
        return vv_error_set(VV_ERR_INVALID, "mesh volume: NULL argument");
    if (m->n_triangles == 0)
        return vv_error_set(VV_ERR_INVALID, "mesh volume: the mesh has no triangles");
    vv_mesh_topology t;
    vv_status s = vv_mesh_topology_compute(m, &t);
    if (s != VV_OK)
        return vv_error_prefix(s, "mesh volume");
    if (!t.closed || !t.oriented)
        return vv_error_set(VV_ERR_INVALID,
                            "mesh volume: the mesh is not a closed, consistently oriented surface "
                            "(%zu boundary edges, %zu non-manifold edges, %zu misoriented edges): "
                            "it encloses no volume",
                            t.n_boundary_edges, t.n_nonmanifold_edges, t.n_misoriented_edges);
    *volume = vv_mesh_signed_volume(m);
    return VV_OK;
}

/* ---- geometry (Ericson, Real-Time Collision Detection, 5.1; core/geom.h) ------ */

static double
clamp01(double x) {
    return x < 0 ? 0 : x > 1 ? 1 : x;
}

/* Squared distance between segments p1q1 and p2q2, closest points c1, c2. */
static double
seg_seg(vv_vec3 p1, vv_vec3 q1, vv_vec3 p2, vv_vec3 q2, vv_vec3 *c1, vv_vec3 *c2) {
    vv_vec3 d1 = vv_v3_sub(q1, p1), d2 = vv_v3_sub(q2, p2), r = vv_v3_sub(p1, p2);
    double a = vv_v3_dot(d1, d1), e = vv_v3_dot(d2, d2), f = vv_v3_dot(d2, r), s, t;
    const double eps = 1e-300;
    if (a <= eps && e <= eps) {
        s = t = 0;
    } else if (a <= eps) {
        s = 0;
        t = clamp01(f / e);
    } else {
        double c = vv_v3_dot(d1, r);
        if (e <= eps) {
            t = 0;
            s = clamp01(-c / a);
        } else {
            double b = vv_v3_dot(d1, d2), den = a * e - b * b;
            s = den > 0 ? clamp01((b * f - c * e) / den) : 0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = clamp01(-c / a);
            } else if (t > 1) {
                t = 1;
                s = clamp01((b - c) / a);
            }
        }
    }
    *c1 = vv_v3_add(p1, vv_v3_scale(d1, s));
    *c2 = vv_v3_add(p2, vv_v3_scale(d2, t));
    vv_vec3 d = vv_v3_sub(*c1, *c2);
    return vv_v3_dot(d, d);
}

/* Whether segment pq crosses triangle abc; the crossing point in *x. */
static int
seg_tri_hit(vv_vec3 p, vv_vec3 q, vv_vec3 a, vv_vec3 b, vv_vec3 c, vv_vec3 *x) {
    const vv_vec3 d = vv_v3_sub(q, p);
    double t, u, v;
    if (!vv_ray_triangle3(p, d, a, b, c, &t, &u, &v) || t < 0 || t > 1)
        return 0;
    *x = vv_v3_add(p, vv_v3_scale(d, t));
    return 1;
}

/* Squared distance between triangles A and B, closest points pa, pb. */
static double
tri_tri(const vv_vec3 A[3], const vv_vec3 B[3], vv_vec3 *pa, vv_vec3 *pb) {
    double best = INFINITY;
    vv_vec3 x, y;
    for (int side = 0; side < 2; side++) {
        const vv_vec3 *P = side ? B : A, *Q = side ? A : B;
        for (int e = 0; e < 3; e++) {
            vv_vec3 p = P[e], q = P[(e + 1) % 3];
            if (seg_tri_hit(p, q, Q[0], Q[1], Q[2], &x)) {
                *pa = *pb = x;
                return 0;
            }
            /* endpoint to triangle */
            vv_vec3 c = vv_closest_point_triangle(p, Q[0], Q[1], Q[2]);
            double d = vv_v3_dot(vv_v3_sub(p, c), vv_v3_sub(p, c));
            if (d < best) {
                best = d;
                *pa = side ? c : p;
                *pb = side ? p : c;
            }
            /* edge to edges */
            for (int f = 0; f < 3; f++) {
                d = seg_seg(p, q, Q[f], Q[(f + 1) % 3], &x, &y);
                if (d < best) {
                    best = d;
                    *pa = side ? y : x;
                    *pb = side ? x : y;
                }
            }
        }
    }
    return best;
}

static void
tri_points(const vv_mesh *m, size_t t, vv_vec3 P[3]) {
    const uint32_t *tr = m->triangles + 3 * t;
    for (int c = 0; c < 3; c++) {
        const float *p = m->positions + 3 * (size_t)tr[c];
        P[c] = (vv_vec3){p[0], p[1], p[2]};
    }
}

/* The search for the closest pair: triangle A (index q) of the first mesh
 * against the second mesh's hierarchy; of equal distances the pair with the
 * lowest (q, k) wins, so the result does not depend on the traversal. */
typedef struct pair_search {
    const vv_mesh *b;
    vv_vec3 A[3];
    double lo[3], hi[3]; /* A's box */
    double best;         /* squared distance of the best pair so far */
    vv_vec3 pa, pb;
    size_t bt, bk; /* its triangles */
    size_t q;
} pair_search;

static int
pair_box(void *ctx, const float lo[3], const float hi[3]) {
    const pair_search *ps = ctx;
    double d = 0;
    for (int a = 0; a < 3; a++) {
        const double g =
            lo[a] - ps->hi[a] > ps->lo[a] - hi[a] ? lo[a] - ps->hi[a] : ps->lo[a] - hi[a];
        if (g > 0)
            d += g * g;
    }
    return !(d > ps->best);
}

static int
pair_leaf(void *ctx, const uint32_t *items, int count) {
    pair_search *ps = ctx;
    for (int i = 0; i < count; i++) {
        vv_vec3 B[3], x = {0, 0, 0}, y = {0, 0, 0};
        tri_points(ps->b, items[i], B);
        const double d = tri_tri(ps->A, B, &x, &y);
        if (d < ps->best ||
            (d == ps->best && (ps->q < ps->bt || (ps->q == ps->bt && items[i] < ps->bk)))) {
            ps->best = d;
            ps->pa = x;
            ps->pb = y;
            ps->bt = ps->q;
            ps->bk = items[i];
        }
    }
    return 0;
}

vv_status
vv_measure_mesh_distance(const vv_mesh *a, const vv_mesh *b, int threads, double *dist, vv_vec3 *pa,
                         vv_vec3 *pb) {
    if (!a || !b || !dist)
        return vv_error_set(VV_ERR_INVALID, "mesh distance: NULL argument");
    if (a->n_triangles == 0 || b->n_triangles == 0)
        return vv_error_set(VV_ERR_INVALID, "mesh distance: a mesh has no triangles");
    if (b->n_triangles > (size_t)INT32_MAX / 2)
        return vv_error_set(VV_ERR_LIMIT, "mesh distance: %zu triangles", b->n_triangles);
    vv_bvh t;
    vv_status s = vv_bvh_build_triangles(&t, b->positions, b->triangles, b->n_triangles);
    if (s != VV_OK)
        return vv_error_prefix(s, "mesh distance");
    const int nt = threads > 0 ? threads : vv_threads_get();
    double best = INFINITY;
    vv_vec3 best_a = {0, 0, 0}, best_b = {0, 0, 0};
    size_t best_t = SIZE_MAX, best_k = SIZE_MAX;
#pragma omp parallel num_threads(nt)
    {
        pair_search ps = {.b = b, .best = INFINITY, .bt = SIZE_MAX, .bk = SIZE_MAX};
#pragma omp for schedule(dynamic, 64)
        for (long q = 0; q < (long)a->n_triangles; q++) {
            tri_points(a, (size_t)q, ps.A);
            for (int k = 0; k < 3; k++) {
                ps.lo[k] = fmin(vv_v3_axis(ps.A[0], k),
                                fmin(vv_v3_axis(ps.A[1], k), vv_v3_axis(ps.A[2], k)));
                ps.hi[k] = fmax(vv_v3_axis(ps.A[0], k),
                                fmax(vv_v3_axis(ps.A[1], k), vv_v3_axis(ps.A[2], k)));
            }
            ps.q = (size_t)q;
            vv_bvh_query(&t, pair_box, pair_leaf, &ps);
        }
#pragma omp critical
        {
            if (ps.best < best ||
                (ps.best == best && (ps.bt < best_t || (ps.bt == best_t && ps.bk < best_k)))) {
                best = ps.best;
                best_a = ps.pa;
                best_b = ps.pb;
                best_t = ps.bt;
                best_k = ps.bk;
            }
        }
    }
    vv_bvh_clear(&t);
    *dist = sqrt(best);
    if (pa)
        *pa = vv_vec3_make(best_a.x, best_a.y, best_a.z);
    if (pb)
        *pb = vv_vec3_make(best_b.x, best_b.y, best_b.z);
    return VV_OK;
}
