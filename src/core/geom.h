/*
 * Geometry kernels shared by the renderers, measurement and modeling (not
 * installed): inline vector helpers on vv_vec3, the ray/box slab test in its
 * two forms, and ray/triangle intersection. Everything is static inline: these
 * sit on the hot path of every ray, and the public vv_vec3_* functions of
 * volvis/math.h live in another translation unit.
 *
 * Numbers: all arithmetic is in double, in the order written here, so every
 * caller gets the same bits for the same inputs (the renderers' images do not
 * depend on which of them tested a box or a triangle).
 *
 * Thread-safety: pure functions, reentrant.
 */
#ifndef VOLVIS_CORE_GEOM_H
#define VOLVIS_CORE_GEOM_H

#include <math.h>

#include "volvis/math.h"

/* ---- vectors ----------------------------------------------------------- */

static inline vv_vec3
vv_v3(double x, double y, double z) {
    vv_vec3 r = {x, y, z};
    return r;
}
/** The vector of three floats p[0..2]. */
static inline vv_vec3
vv_v3_f(const float *p) {
    return vv_v3(p[0], p[1], p[2]);
}
/** The vector of three doubles p[0..2]. */
static inline vv_vec3
vv_v3_d(const double *p) {
    return vv_v3(p[0], p[1], p[2]);
}
static inline vv_vec3
vv_v3_add(vv_vec3 a, vv_vec3 b) {
    return vv_v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline vv_vec3
vv_v3_sub(vv_vec3 a, vv_vec3 b) {
    return vv_v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline vv_vec3
vv_v3_scale(vv_vec3 a, double k) {
    return vv_v3(a.x * k, a.y * k, a.z * k);
}
static inline double
vv_v3_dot(vv_vec3 a, vv_vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline vv_vec3
vv_v3_cross(vv_vec3 a, vv_vec3 b) {
    return vv_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double
vv_v3_len(vv_vec3 a) {
    return sqrt(vv_v3_dot(a, a));
}
/** a / |a|; the zero vector is returned unchanged (as vv_vec3_normalize). */
static inline vv_vec3
vv_v3_norm(vv_vec3 a) {
    double l = vv_v3_len(a);
    return l > 0 ? vv_v3_scale(a, 1.0 / l) : a;
}
/** Component @p axis (0 x, 1 y, 2 z). */
static inline double
vv_v3_axis(vv_vec3 v, int axis) {
    return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}
/** Component-wise minimum and maximum. */
static inline vv_vec3
vv_v3_min(vv_vec3 a, vv_vec3 b) {
    return vv_v3(a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z);
}
static inline vv_vec3
vv_v3_max(vv_vec3 a, vv_vec3 b) {
    return vv_v3(a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z);
}

/* ---- ray / box: the slab test (Kay and Kajiya, SIGGRAPH 1986) -------------- */

/** vv_slab_span's answers. */
enum {
    VV_SLAB_OUTSIDE = 0, /**< parallel to the slab and outside it */
    VV_SLAB_INSIDE = 1,  /**< parallel and inside: all of the line (ta, tb untouched) */
    VV_SLAB_UP = 2,      /**< crosses it from lo to hi (ta at lo) */
    VV_SLAB_DOWN = 3     /**< crosses it from hi to lo (ta at hi) */
};

/**
 * One axis of the slab test in the division form: the line o + t d (one
 * coordinate) is inside [lo, hi] for t in [*ta, *tb] (set, *ta <= *tb, on
 * VV_SLAB_UP and VV_SLAB_DOWN). A direction below 1e-300 in magnitude is
 * parallel to the slab.
 */
static inline int
vv_slab_span(double lo, double hi, double o, double d, double *ta, double *tb) {
    if (fabs(d) < 1e-300)
        return o < lo || o > hi ? VV_SLAB_OUTSIDE : VV_SLAB_INSIDE;
    double a = (lo - o) / d, b = (hi - o) / d;
    if (a > b) {
        *ta = b;
        *tb = a;
        return VV_SLAB_DOWN;
    }
    *ta = a;
    *tb = b;
    return VV_SLAB_UP;
}

/**
 * One axis of the slab test in the division form: clips [*t0, *t1] to the
 * part of the line inside [lo, hi]; returns 0 when the line is parallel to
 * the slab and outside it. Does not test *t0 <= *t1 (the caller does, after
 * one axis or all three).
 */
static inline int
vv_slab_axis(double lo, double hi, double o, double d, double *t0, double *t1) {
    double ta, tb;
    const int k = vv_slab_span(lo, hi, o, d, &ta, &tb);
    if (k < VV_SLAB_UP)
        return k;
    *t0 = ta > *t0 ? ta : *t0;
    *t1 = tb < *t1 ? tb : *t1;
    return 1;
}

/**
 * Slab test of one box, division form: exact on axis-parallel rays, for a box
 * tested once per ray (a volume's grid, a geometric box). Clips [*t0, *t1] (the
 * caller's ray interval, e.g. -INFINITY..INFINITY or 0..tmax) to the box
 * [lo, hi] and returns 1 when something is left (*t0 <= *t1), else 0 (the
 * interval is then meaningless). Boxes and points in the same units as o, d.
 */
static inline int
vv_slab(const double lo[3], const double hi[3], const double o[3], const double d[3], double *t0,
        double *t1) {
    for (int a = 0; a < 3; a++)
        if (!vv_slab_axis(lo[a], hi[a], o[a], d[a], t0, t1) || *t0 > *t1)
            return 0;
    return 1;
}

/**
 * Slab test with the reciprocal direction inv = 1 / d (IEEE: +-INFINITY for a
 * zero component), for a traversal that tests many boxes with one ray.
 * Clips [*t0, *t1] to the box and returns 1 when something is left. A zero
 * direction component whose origin lies on the slab's plane gives 0 * inf =
 * NaN, which leaves the interval unchanged (the ray is then in the slab's
 * plane: inside). The same bits as the division form only where 1 / d is
 * exact; callers choose one form and keep it.
 */
static inline int
vv_slab_inv(const double lo[3], const double hi[3], const double o[3], const double inv[3],
            double *t0, double *t1) {
    double a0 = *t0, a1 = *t1;
    for (int a = 0; a < 3; a++) {
        double ta = (lo[a] - o[a]) * inv[a], tb = (hi[a] - o[a]) * inv[a];
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        a0 = ta > a0 ? ta : a0;
        a1 = tb < a1 ? tb : a1;
        if (a0 > a1)
            return 0;
    }
    *t0 = a0;
    *t1 = a1;
    return 1;
}

/** vv_slab_inv on a box of floats (a BVH node); the conversion to double is exact. */
static inline int
vv_slab_inv_f(const float lo[3], const float hi[3], const double o[3], const double inv[3],
              double *t0, double *t1) {
    const double l[3] = {lo[0], lo[1], lo[2]}, h[3] = {hi[0], hi[1], hi[2]};
    return vv_slab_inv(l, h, o, inv, t0, t1);
}

/* ---- ray / triangle (Moeller and Trumbore, JGT 2(1), 1997) ----------------- */

/**
 * Where the line o + t d crosses the triangle with vertex @p a and edges
 * e1 = b - a, e2 = c - a: returns 1 with the line parameter *t and the
 * barycentric weights *u (of b) and *v (of c) when u >= 0, v >= 0 and
 * u + v <= 1 (edges and vertices included), 0 when it misses or the line
 * is parallel to the plane (|det| < 1e-300). The caller tests t against its
 * interval; *t, *u, *v are set only on a hit. Not watertight (Woop, Benthin
 * and Wald, JCGT 2013): rays aimed exactly at an edge shared by two
 * triangles hit at least one of them in every trial of
 * tests/core/test_geom.c, but one aimed exactly at a vertex where four meet
 * misses all of them about once in 150 (u + v rounds above 1 in each),
 * which the renderers tolerate (a pixel's ray passes exactly through a
 * vertex with probability 0). The edges are the caller's so that a mesh
 * can keep them.
 */
static inline int
vv_ray_triangle(vv_vec3 o, vv_vec3 d, vv_vec3 a, vv_vec3 e1, vv_vec3 e2, double *t, double *u,
                double *v) {
    const vv_vec3 p = vv_v3_cross(d, e2);
    const double det = vv_v3_dot(e1, p);
    if (fabs(det) < 1e-300)
        return 0;
    const double id = 1.0 / det;
    const vv_vec3 s = vv_v3_sub(o, a);
    const double uu = vv_v3_dot(s, p) * id;
    if (uu < 0 || uu > 1)
        return 0;
    const vv_vec3 q = vv_v3_cross(s, e1);
    const double vv = vv_v3_dot(d, q) * id;
    if (vv < 0 || uu + vv > 1)
        return 0;
    *t = vv_v3_dot(e2, q) * id;
    *u = uu;
    *v = vv;
    return 1;
}

/** vv_ray_triangle of the triangle with vertices a, b, c (edges from a, in double). */
static inline int
vv_ray_triangle3(vv_vec3 o, vv_vec3 d, vv_vec3 a, vv_vec3 b, vv_vec3 c, double *t, double *u,
                 double *v) {
    return vv_ray_triangle(o, d, a, vv_v3_sub(b, a), vv_v3_sub(c, a), t, u, v);
}

/* ---- closest points (Ericson, Real-Time Collision Detection, 2005, 5.1) ---- */

/** The point of the triangle a b c nearest @p p (a degenerate triangle gives a). */
static inline vv_vec3
vv_closest_point_triangle(vv_vec3 p, vv_vec3 a, vv_vec3 b, vv_vec3 c) {
    const vv_vec3 ab = vv_v3_sub(b, a), ac = vv_v3_sub(c, a), ap = vv_v3_sub(p, a);
    const double d1 = vv_v3_dot(ab, ap), d2 = vv_v3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return a;
    const vv_vec3 bp = vv_v3_sub(p, b);
    const double d3 = vv_v3_dot(ab, bp), d4 = vv_v3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return vv_v3_add(a, vv_v3_scale(ab, d1 / (d1 - d3)));
    const vv_vec3 cp = vv_v3_sub(p, c);
    const double d5 = vv_v3_dot(ab, cp), d6 = vv_v3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return vv_v3_add(a, vv_v3_scale(ac, d2 / (d2 - d6)));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return vv_v3_add(b, vv_v3_scale(vv_v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    const double den = va + vb + vc;
    if (!(den > 0))
        return a;
    const double v = vb / den, w = vc / den;
    return vv_v3_add(a, vv_v3_add(vv_v3_scale(ab, v), vv_v3_scale(ac, w)));
}

/** Squared distance from @p p to the box [lo, hi] (0 inside). */
static inline double
vv_box_distance2_f(const float lo[3], const float hi[3], vv_vec3 p) {
    const double q[3] = {p.x, p.y, p.z};
    double s = 0;
    for (int a = 0; a < 3; a++) {
        const double g = q[a] < lo[a] ? lo[a] - q[a] : q[a] > hi[a] ? q[a] - hi[a] : 0;
        s += g * g;
    }
    return s;
}

#endif
