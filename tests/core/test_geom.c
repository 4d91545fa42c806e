/*
 * core/geom.h: the slab test in both forms, Moeller-Trumbore ray/triangle
 * and the closest point on a triangle, against analytic answers and
 * against independent brute-force checks.
 */
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdint.h>

#include "core/geom.h"

static vv_vec3
rnd_vec(uint64_t *s, double lo, double hi) {
    double x = vt_rnd(s, lo, hi), y = vt_rnd(s, lo, hi), z = vt_rnd(s, lo, hi);
    return vv_v3(x, y, z);
}

static int
inside_box(const double lo[3], const double hi[3], vv_vec3 p, double tol) {
    const double q[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; a++)
        if (q[a] < lo[a] - tol || q[a] > hi[a] + tol)
            return 0;
    return 1;
}

/* Entry and exit of axis-aligned rays and of a diagonal through the unit box. */
static void
test_slab_analytic(void **state) {
    (void)state;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 4};
    const double o[3] = {-1, 0.5, 1}, d[3] = {1, 0, 0};
    double t0 = -INFINITY, t1 = INFINITY;
    assert_true(vv_slab(lo, hi, o, d, &t0, &t1));
    assert_true(t0 == 1 && t1 == 2);
    /* the caller's interval clips: starting at 1.5 */
    t0 = 1.5;
    t1 = INFINITY;
    assert_true(vv_slab(lo, hi, o, d, &t0, &t1));
    assert_true(t0 == 1.5 && t1 == 2);
    /* ending before the box: a miss */
    t0 = 0;
    t1 = 0.5;
    assert_false(vv_slab(lo, hi, o, d, &t0, &t1));
    /* parallel to y and z: outside on y is a miss whatever x does */
    const double o2[3] = {-1, 3, 1};
    t0 = -INFINITY;
    t1 = INFINITY;
    assert_false(vv_slab(lo, hi, o2, d, &t0, &t1));
    /* origin inside: t0 negative */
    const double o3[3] = {0.25, 1, 2}, d3[3] = {0, 0, -2};
    t0 = -INFINITY;
    t1 = INFINITY;
    assert_true(vv_slab(lo, hi, o3, d3, &t0, &t1));
    assert_true(t0 == -1 && t1 == 1);
    /* on a face's plane, parallel to it: inside (closed box) */
    const double o4[3] = {0, 1, -1}, d4[3] = {0, 0, 1};
    t0 = -INFINITY;
    t1 = INFINITY;
    assert_true(vv_slab(lo, hi, o4, d4, &t0, &t1));
    assert_true(t0 == 1 && t1 == 5);
    /* the reciprocal form: the same intervals where 1 / d is exact */
    const double inv[3] = {1 / d[0], 1 / d[1], 1 / d[2]};
    t0 = -INFINITY;
    t1 = INFINITY;
    assert_true(vv_slab_inv(lo, hi, o, inv, &t0, &t1));
    assert_true(t0 == 1 && t1 == 2);
    const double inv4[3] = {1 / d4[0], 1 / d4[1], 1 / d4[2]}; /* 0 * inf = NaN: inside */
    t0 = -INFINITY;
    t1 = INFINITY;
    assert_true(vv_slab_inv(lo, hi, o4, inv4, &t0, &t1));
    assert_true(t0 == 1 && t1 == 5);
    t0 = -INFINITY;
    t1 = INFINITY;
    assert_false(vv_slab_inv(lo, hi, o2, inv, &t0, &t1));
    /* one axis: vv_slab_span tells which face is entered */
    double ta, tb;
    assert_int_equal(vv_slab_span(0, 1, 2, -1, &ta, &tb), VV_SLAB_DOWN);
    assert_true(ta == 1 && tb == 2);
    assert_int_equal(vv_slab_span(0, 1, -2, 0.5, &ta, &tb), VV_SLAB_UP);
    assert_true(ta == 4 && tb == 6);
    assert_int_equal(vv_slab_span(0, 1, 0.5, 0, &ta, &tb), VV_SLAB_INSIDE);
    assert_int_equal(vv_slab_span(0, 1, 1.5, 1e-301, &ta, &tb), VV_SLAB_OUTSIDE);
    /* the library's public slab test is the same */
    vv_box b = {{0, 0, 0}, {1, 2, 4}};
    vv_ray r = {{-1, 0.5, 1}, {1, 0, 0}};
    assert_true(vv_box_intersect_ray(b, r, &t0, &t1));
    assert_true(t0 == 1 && t1 == 2);
}

/* Random rays and boxes: both forms agree, and the interval they give is
 * the part of the line inside the box, checked by sampling points. */
static void
test_slab_random(void **state) {
    (void)state;
    uint64_t seed = 7;
    int hits = 0, misses = 0;
    for (int i = 0; i < 20000; i++) {
        vv_vec3 a = rnd_vec(&seed, -2, 2), b = rnd_vec(&seed, -2, 2);
        const double lo[3] = {fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)};
        const double hi[3] = {fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)};
        vv_vec3 o = rnd_vec(&seed, -4, 4), dv = rnd_vec(&seed, -1, 1);
        if (i % 7 == 0)
            dv.y = 0; /* some rays parallel to a slab */
        const double oo[3] = {o.x, o.y, o.z}, d[3] = {dv.x, dv.y, dv.z};
        const double inv[3] = {1 / d[0], 1 / d[1], 1 / d[2]};
        double t0 = -INFINITY, t1 = INFINITY, u0 = -INFINITY, u1 = INFINITY;
        const int h = vv_slab(lo, hi, oo, d, &t0, &t1);
        const int hv = vv_slab_inv(lo, hi, oo, inv, &u0, &u1);
        if (h != hv) {
            /* only a grazing ray may differ: an interval of rounding size */
            assert_true(!h || fabs(t1 - t0) < 1e-12 * (1 + fabs(t0)));
            assert_true(!hv || fabs(u1 - u0) < 1e-12 * (1 + fabs(u0)));
            continue;
        }
        if (!h) {
            misses++;
            /* no sampled point of the line lies in the box */
            for (double t = -20; t <= 20; t += 0.01)
                assert_false(inside_box(lo, hi, vv_v3_add(o, vv_v3_scale(dv, t)), -1e-9));
            continue;
        }
        hits++;
        assert_near(t0, u0, 1e-12 * (1 + fabs(t0)));
        assert_near(t1, u1, 1e-12 * (1 + fabs(t1)));
        /* inside between the ends, outside just beyond them */
        const double len = vv_v3_len(dv);
        const double eps = 1e-6 / len;
        for (int k = 1; k < 8; k++)
            assert_true(
                inside_box(lo, hi, vv_v3_add(o, vv_v3_scale(dv, t0 + (t1 - t0) * k / 8)), 1e-9));
        if (t1 - t0 > 1e-5) {
            assert_false(inside_box(lo, hi, vv_v3_add(o, vv_v3_scale(dv, t0 - eps)), 0));
            assert_false(inside_box(lo, hi, vv_v3_add(o, vv_v3_scale(dv, t1 + eps)), 0));
        }
    }
    assert_true(hits > 1000 && misses > 1000);
}

/* A triangle in the plane z = 1: the hit, its barycentric weights; edges,
 * vertices, parallel rays and misses. */
static void
test_ray_triangle_analytic(void **state) {
    (void)state;
    const vv_vec3 a = vv_v3(0, 0, 1), b = vv_v3(2, 0, 1), c = vv_v3(0, 2, 1);
    double t, u, v;
    assert_true(vv_ray_triangle3(vv_v3(0.5, 0.25, -1), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    assert_true(t == 2 && u == 0.25 && v == 0.125);
    /* from the other side, a direction of another length: t scales */
    assert_true(vv_ray_triangle3(vv_v3(0.5, 0.25, 5), vv_v3(0, 0, -4), a, b, c, &t, &u, &v));
    assert_true(t == 1);
    /* on an edge (v = 0), on the hypotenuse (u + v = 1), on a vertex: hits */
    assert_true(vv_ray_triangle3(vv_v3(1, 0, 0), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    assert_true(v == 0 && u == 0.5);
    assert_true(vv_ray_triangle3(vv_v3(1, 1, 0), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    assert_true(u + v == 1);
    assert_true(vv_ray_triangle3(vv_v3(2, 0, 0), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    assert_true(u == 1 && v == 0);
    /* outside each edge: misses */
    assert_false(vv_ray_triangle3(vv_v3(1, -0.01, 0), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    assert_false(vv_ray_triangle3(vv_v3(-0.01, 1, 0), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    assert_false(vv_ray_triangle3(vv_v3(1.01, 1, 0), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    /* parallel to the plane, in it or off it: no hit */
    assert_false(vv_ray_triangle3(vv_v3(-1, 0.5, 1), vv_v3(1, 0, 0), a, b, c, &t, &u, &v));
    assert_false(vv_ray_triangle3(vv_v3(-1, 0.5, 2), vv_v3(1, 0, 0), a, b, c, &t, &u, &v));
    /* the line is what is tested: a triangle behind the origin gives t < 0 */
    assert_true(vv_ray_triangle3(vv_v3(0.5, 0.5, 3), vv_v3(0, 0, 1), a, b, c, &t, &u, &v));
    assert_true(t == -2);
    /* a degenerate (zero-area) triangle is never hit */
    assert_false(
        vv_ray_triangle3(vv_v3(0.5, 0, 0), vv_v3(0, 0, 1), a, b, vv_v3(1, 0, 1), &t, &u, &v));
}

/* Random triangles and rays: the hit point is on the triangle's plane and
 * equals the barycentric combination; a hit agrees with an independent
 * inside test by signed areas (away from the edges). */
static void
test_ray_triangle_random(void **state) {
    (void)state;
    uint64_t seed = 11;
    int hits = 0, misses = 0;
    for (int i = 0; i < 50000; i++) {
        const vv_vec3 a = rnd_vec(&seed, -1, 1), b = rnd_vec(&seed, -1, 1),
                      c = rnd_vec(&seed, -1, 1);
        const vv_vec3 o = rnd_vec(&seed, -3, 3), target = rnd_vec(&seed, -1, 1);
        const vv_vec3 d = vv_v3_sub(target, o);
        const vv_vec3 n = vv_v3_cross(vv_v3_sub(b, a), vv_v3_sub(c, a));
        const double dn = vv_v3_dot(n, d);
        if (fabs(dn) < 1e-3 * vv_v3_len(n) * vv_v3_len(d))
            continue; /* nearly parallel: the independent test below is ill-conditioned */
        /* independent: the line's point on the plane, then the signs of the
         * three sub-triangle areas */
        const double tp = vv_v3_dot(n, vv_v3_sub(a, o)) / dn;
        const vv_vec3 p = vv_v3_add(o, vv_v3_scale(d, tp));
        const double s0 = vv_v3_dot(n, vv_v3_cross(vv_v3_sub(b, a), vv_v3_sub(p, a)));
        const double s1 = vv_v3_dot(n, vv_v3_cross(vv_v3_sub(c, b), vv_v3_sub(p, b)));
        const double s2 = vv_v3_dot(n, vv_v3_cross(vv_v3_sub(a, c), vv_v3_sub(p, c)));
        const double margin = 1e-9 * vv_v3_dot(n, n);
        const int in = s0 > margin && s1 > margin && s2 > margin;
        const int out = s0 < -margin || s1 < -margin || s2 < -margin;
        double t = 0, u = 0, v = 0;
        const int h = vv_ray_triangle3(o, d, a, b, c, &t, &u, &v);
        if (in) {
            assert_true(h);
            hits++;
            assert_near(t, tp, 1e-9 * (1 + fabs(tp)));
            const vv_vec3 q = vv_v3_add(vv_v3_scale(a, 1 - u - v),
                                        vv_v3_add(vv_v3_scale(b, u), vv_v3_scale(c, v)));
            assert_true(vv_v3_len(vv_v3_sub(q, vv_v3_add(o, vv_v3_scale(d, t)))) < 1e-9);
        } else if (out) {
            assert_false(h);
            misses++;
        }
    }
    assert_true(hits > 2000 && misses > 2000);
}

/* A closed octahedron: rays from inside aimed exactly at points of its
 * edges and faces hit at least one face, never none (no leak through a
 * shared edge), at the analytic distance; rays aimed exactly at a vertex
 * leak rarely (the method is not watertight). */
static void
test_ray_triangle_shared_edges(void **state) {
    (void)state;
    const vv_vec3 P[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    int F[8][3], nf = 0;
    for (int sx = 0; sx < 2; sx++)
        for (int sy = 0; sy < 2; sy++)
            for (int sz = 0; sz < 2; sz++) {
                F[nf][0] = sx;
                F[nf][1] = 2 + sy;
                F[nf][2] = 4 + sz;
                nf++;
            }
    uint64_t seed = 3;
    int tested = 0, leaks = 0;
    for (int i = 0; i < 3000; i++) {
        /* a target on an edge (i % 3 == 0), at a vertex (== 1), inside a face */
        const int f = (int)vt_rnd(&seed, 0, 8);
        const vv_vec3 a = P[F[f][0]], b = P[F[f][1]], c = P[F[f][2]];
        double s = vt_rnd(&seed, 0, 1), w = vt_rnd(&seed, 0, 1 - s);
        vv_vec3 target = i % 3 == 0   ? vv_v3_add(vv_v3_scale(a, 1 - s), vv_v3_scale(b, s))
                         : i % 3 == 1 ? c
                                      : vv_v3_add(vv_v3_scale(a, 1 - s - w),
                                                  vv_v3_add(vv_v3_scale(b, s), vv_v3_scale(c, w)));
        const vv_vec3 o = vv_v3_scale(rnd_vec(&seed, -1, 1), 0.2);
        const vv_vec3 d = vv_v3_sub(target, o);
        int n_hit = 0;
        for (int g = 0; g < nf; g++) {
            double t, u, v;
            if (vv_ray_triangle3(o, d, P[F[g][0]], P[F[g][1]], P[F[g][2]], &t, &u, &v) && t > 0) {
                n_hit++;
                assert_near(t, 1.0, 1e-12);
            }
        }
        if (n_hit == 0) {
            /* Moeller-Trumbore is not watertight: a ray aimed exactly at a
             * vertex where four faces meet can miss all of them (u + v
             * rounds above 1 in each); at an edge or inside a face never */
            assert_int_equal(i % 3, 1);
            leaks++;
        }
        tested++;
    }
    assert_int_equal(tested, 3000);
    /* measured: 7 of the 1000 rays at vertices */
    assert_true(leaks <= 20);
}

/* The closest point beats every point of a fine barycentric sampling of the
 * triangle, and no sample comes closer than it. */
static void
test_closest_point(void **state) {
    (void)state;
    uint64_t seed = 5;
    for (int i = 0; i < 300; i++) {
        const vv_vec3 a = rnd_vec(&seed, -1, 1), b = rnd_vec(&seed, -1, 1),
                      c = rnd_vec(&seed, -1, 1), p = rnd_vec(&seed, -2, 2);
        const vv_vec3 q = vv_closest_point_triangle(p, a, b, c);
        const double dq = vv_v3_len(vv_v3_sub(q, p));
        double best = INFINITY;
        const int N = 60;
        for (int u = 0; u <= N; u++)
            for (int v = 0; u + v <= N; v++) {
                const vv_vec3 s = vv_v3_add(
                    vv_v3_scale(a, (double)(N - u - v) / N),
                    vv_v3_add(vv_v3_scale(b, (double)u / N), vv_v3_scale(c, (double)v / N)));
                best = fmin(best, vv_v3_len(vv_v3_sub(s, p)));
            }
        assert_true(dq <= best + 1e-12);
        /* the sampling is at most a cell's diameter away from q */
        const double cell = fmax(vv_v3_len(vv_v3_sub(b, a)),
                                 fmax(vv_v3_len(vv_v3_sub(c, a)), vv_v3_len(vv_v3_sub(c, b)))) /
                            N;
        assert_true(best <= dq + cell);
    }
    /* a point above the interior projects onto the plane */
    const vv_vec3 q = vv_closest_point_triangle(vv_v3(0.25, 0.25, 3), vv_v3(0, 0, 0),
                                                vv_v3(1, 0, 0), vv_v3(0, 1, 0));
    assert_true(q.x == 0.25 && q.y == 0.25 && q.z == 0);
    /* box distance: 0 inside, per-axis gaps outside */
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    assert_true(vv_box_distance2_f(lo, hi, vv_v3(0.5, 0.5, 0.5)) == 0);
    assert_true(vv_box_distance2_f(lo, hi, vv_v3(2, -1, 0.5)) == 2);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slab_analytic),
        cmocka_unit_test(test_slab_random),
        cmocka_unit_test(test_ray_triangle_analytic),
        cmocka_unit_test(test_ray_triangle_random),
        cmocka_unit_test(test_ray_triangle_shared_edges),
        cmocka_unit_test(test_closest_point),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
