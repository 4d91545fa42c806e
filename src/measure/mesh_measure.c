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

/* ---- geometry (Ericson, Real-Time Collision Detection, 5.1) ------------------- */

typedef struct v3 {
    double x, y, z;
} v3;

static inline v3
sub(v3 a, v3 b) {
    return (v3){a.x - b.x, a.y - b.y, a.z - b.z};
}
static inline v3
add(v3 a, v3 b) {
    return (v3){a.x + b.x, a.y + b.y, a.z + b.z};
}
static inline v3
scl(v3 a, double s) {
    return (v3){a.x * s, a.y * s, a.z * s};
}
static inline double
dot(v3 a, v3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline v3
cross(v3 a, v3 b) {
    return (v3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

static v3
closest_pt_triangle(v3 p, v3 a, v3 b, v3 c) {
    v3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
    double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return a;
    v3 bp = sub(p, b);
    double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return b;
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return add(a, scl(ab, d1 / (d1 - d3)));
    v3 cp = sub(p, c);
    double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return c;
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return add(a, scl(ac, d2 / (d2 - d6)));
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return add(b, scl(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    double den = va + vb + vc;
    if (!(den > 0))
        return a; /* degenerate triangle */
    double v = vb / den, w = vc / den;
    return add(a, add(scl(ab, v), scl(ac, w)));
}

static double
clamp01(double x) {
    return x < 0 ? 0 : x > 1 ? 1 : x;
}

/* Squared distance between segments p1q1 and p2q2, closest points c1, c2. */
static double
seg_seg(v3 p1, v3 q1, v3 p2, v3 q2, v3 *c1, v3 *c2) {
    v3 d1 = sub(q1, p1), d2 = sub(q2, p2), r = sub(p1, p2);
    double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r), s, t;
    const double eps = 1e-300;
    if (a <= eps && e <= eps) {
        s = t = 0;
    } else if (a <= eps) {
        s = 0;
        t = clamp01(f / e);
    } else {
        double c = dot(d1, r);
        if (e <= eps) {
            t = 0;
            s = clamp01(-c / a);
        } else {
            double b = dot(d1, d2), den = a * e - b * b;
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
    *c1 = add(p1, scl(d1, s));
    *c2 = add(p2, scl(d2, t));
    v3 d = sub(*c1, *c2);
    return dot(d, d);
}

/* Whether segment pq crosses triangle abc; the crossing point in *x. */
static int
seg_tri_hit(v3 p, v3 q, v3 a, v3 b, v3 c, v3 *x) {
    v3 d = sub(q, p), e1 = sub(b, a), e2 = sub(c, a), h = cross(d, e2);
    double det = dot(e1, h);
    if (fabs(det) < 1e-300)
        return 0;
    double inv = 1 / det;
    v3 s = sub(p, a);
    double u = dot(s, h) * inv;
    if (u < 0 || u > 1)
        return 0;
    v3 qq = cross(s, e1);
    double v = dot(d, qq) * inv;
    if (v < 0 || u + v > 1)
        return 0;
    double t = dot(e2, qq) * inv;
    if (t < 0 || t > 1)
        return 0;
    *x = add(p, scl(d, t));
    return 1;
}

/* Squared distance between triangles A and B, closest points pa, pb. */
static double
tri_tri(const v3 A[3], const v3 B[3], v3 *pa, v3 *pb) {
    double best = INFINITY;
    v3 x, y;
    for (int side = 0; side < 2; side++) {
        const v3 *P = side ? B : A, *Q = side ? A : B;
        for (int e = 0; e < 3; e++) {
            v3 p = P[e], q = P[(e + 1) % 3];
            if (seg_tri_hit(p, q, Q[0], Q[1], Q[2], &x)) {
                *pa = *pb = x;
                return 0;
            }
            /* endpoint to triangle */
            v3 c = closest_pt_triangle(p, Q[0], Q[1], Q[2]);
            double d = dot(sub(p, c), sub(p, c));
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

/* ---- bounding-volume hierarchy ---------------------------------------------- */

typedef struct bvh_node {
    double lo[3], hi[3];
    int left, right; /* children, or -1 for a leaf */
    int first, count;
} bvh_node;

typedef struct bvh {
    bvh_node *nodes;
    int n_nodes;
    uint32_t *order; /* triangle indices */
    const vv_mesh *m;
    double *centroid;
} bvh;

static int
cmp_axis_key(const void *a, const void *b) {
    double x = ((const double *)a)[0], y = ((const double *)b)[0];
    return x < y ? -1 : x > y;
}

static int
bvh_build_node(bvh *t, int first, int count, double *scratch) {
    int id = t->n_nodes++;
    bvh_node *n = &t->nodes[id];
    for (int a = 0; a < 3; a++) {
        n->lo[a] = INFINITY;
        n->hi[a] = -INFINITY;
    }
    for (int q = first; q < first + count; q++) {
        const uint32_t *tr = t->m->triangles + 3 * (size_t)t->order[q];
        for (int c = 0; c < 3; c++)
            for (int a = 0; a < 3; a++) {
                double x = t->m->positions[3 * (size_t)tr[c] + (size_t)a];
                n->lo[a] = x < n->lo[a] ? x : n->lo[a];
                n->hi[a] = x > n->hi[a] ? x : n->hi[a];
            }
    }
    n->first = first;
    n->count = count;
    n->left = n->right = -1;
    if (count <= 4)
        return id;
    int axis = 0;
    double ext = -1;
    for (int a = 0; a < 3; a++)
        if (n->hi[a] - n->lo[a] > ext) {
            ext = n->hi[a] - n->lo[a];
            axis = a;
        }
    /* sort by centroid along the axis (key, index pairs) and split at the median */
    for (int q = 0; q < count; q++) {
        scratch[2 * q] = t->centroid[3 * (size_t)t->order[first + q] + (size_t)axis];
        scratch[2 * q + 1] = (double)t->order[first + q];
    }
    qsort(scratch, (size_t)count, 2 * sizeof(double), cmp_axis_key);
    for (int q = 0; q < count; q++)
        t->order[first + q] = (uint32_t)scratch[2 * q + 1];
    int half = count / 2;
    int l = bvh_build_node(t, first, half, scratch);
    int r = bvh_build_node(t, first + half, count - half, scratch);
    t->nodes[id].left = l;
    t->nodes[id].right = r;
    return id;
}

static double
box_box_dist2(const double alo[3], const double ahi[3], const double blo[3], const double bhi[3]) {
    double d = 0;
    for (int a = 0; a < 3; a++) {
        double g = blo[a] - ahi[a] > alo[a] - bhi[a] ? blo[a] - ahi[a] : alo[a] - bhi[a];
        if (g > 0)
            d += g * g;
    }
    return d;
}

static void
tri_points(const vv_mesh *m, size_t t, v3 P[3]) {
    const uint32_t *tr = m->triangles + 3 * t;
    for (int c = 0; c < 3; c++) {
        const float *p = m->positions + 3 * (size_t)tr[c];
        P[c] = (v3){p[0], p[1], p[2]};
    }
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
    bvh t = {0};
    t.m = b;
    t.nodes = malloc(2 * b->n_triangles * sizeof *t.nodes);
    t.order = malloc(b->n_triangles * sizeof *t.order);
    t.centroid = malloc(3 * b->n_triangles * sizeof *t.centroid);
    double *scratch = malloc(2 * b->n_triangles * sizeof *scratch);
    if (!t.nodes || !t.order || !t.centroid || !scratch) {
        free(t.nodes);
        free(t.order);
        free(t.centroid);
        free(scratch);
        return vv_error_set(VV_ERR_NOMEM, "mesh distance: out of memory");
    }
    for (size_t q = 0; q < b->n_triangles; q++) {
        t.order[q] = (uint32_t)q;
        v3 P[3];
        tri_points(b, q, P);
        t.centroid[3 * q] = (P[0].x + P[1].x + P[2].x) / 3;
        t.centroid[3 * q + 1] = (P[0].y + P[1].y + P[2].y) / 3;
        t.centroid[3 * q + 2] = (P[0].z + P[1].z + P[2].z) / 3;
    }
    bvh_build_node(&t, 0, (int)b->n_triangles, scratch);
    free(scratch);
    const int nt = threads > 0 ? threads : vv_threads_get();
    double best = INFINITY;
    v3 best_a = {0, 0, 0}, best_b = {0, 0, 0};
    size_t best_t = SIZE_MAX;
#pragma omp parallel num_threads(nt)
    {
        double mine = INFINITY;
        v3 ma = {0, 0, 0}, mb = {0, 0, 0};
        size_t mt = SIZE_MAX;
        int stack[128];
#pragma omp for schedule(dynamic, 64)
        for (long q = 0; q < (long)a->n_triangles; q++) {
            v3 A[3];
            tri_points(a, (size_t)q, A);
            double lo[3] = {fmin(A[0].x, fmin(A[1].x, A[2].x)), fmin(A[0].y, fmin(A[1].y, A[2].y)),
                            fmin(A[0].z, fmin(A[1].z, A[2].z))};
            double hi[3] = {fmax(A[0].x, fmax(A[1].x, A[2].x)), fmax(A[0].y, fmax(A[1].y, A[2].y)),
                            fmax(A[0].z, fmax(A[1].z, A[2].z))};
            int sp = 0;
            stack[sp++] = 0;
            while (sp) {
                const bvh_node *n = &t.nodes[stack[--sp]];
                if (box_box_dist2(lo, hi, n->lo, n->hi) > mine)
                    continue;
                if (n->left < 0) {
                    for (int k = n->first; k < n->first + n->count; k++) {
                        v3 B[3], x = {0, 0, 0}, y = {0, 0, 0};
                        tri_points(b, t.order[k], B);
                        double d = tri_tri(A, B, &x, &y);
                        if (d < mine || (d == mine && (size_t)q < mt)) {
                            mine = d;
                            ma = x;
                            mb = y;
                            mt = (size_t)q;
                        }
                    }
                } else if (sp + 2 <= 128) {
                    stack[sp++] = n->left;
                    stack[sp++] = n->right;
                }
            }
        }
#pragma omp critical
        {
            if (mine < best || (mine == best && mt < best_t)) {
                best = mine;
                best_a = ma;
                best_b = mb;
                best_t = mt;
            }
        }
    }
    free(t.nodes);
    free(t.order);
    free(t.centroid);
    *dist = sqrt(best);
    if (pa)
        *pa = vv_vec3_make(best_a.x, best_a.y, best_a.z);
    if (pb)
        *pb = vv_vec3_make(best_b.x, best_b.y, best_b.z);
    return VV_OK;
}
