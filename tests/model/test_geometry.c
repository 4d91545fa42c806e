/*
 * The geometry-type table (include/volvis/sys/geometry.h), every record against its
 * own tessellation: the bounds contain it; the signed distance is 0 on it
 * (within the tessellation tolerance), positive outside and negative inside
 * (behind a surface); intersect finds the hit the triangles give, within the
 * tolerance, with an outward normal; checks refuse broken shapes; the
 * polygon's ear clipping covers exactly the polygon.
 */
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "volvis/sys/geometry.h"

/* An L-shaped (non-convex) hexagon in a tilted plane, and a convex quad. */
static const vv_vec3 L_SHAPE[6] = {{0, 0, 0},   {2, 0, 0.4}, {2, 1, 0.9},
                                   {1, 1, 0.7}, {1, 2, 1.2}, {0, 2, 1.0}};
static const vv_vec3 QUAD[4] = {{-1, -1, 0.5}, {1, -1, 0.5}, {1.2, 1, 0.5}, {-0.8, 1, 0.5}};

typedef struct sample {
    const char *what;
    vv_object_type type;
    vv_geometry g;
    double size; /* a length scale of the shape */
} sample;

static int
samples(sample *s) {
    int n = 0;
    memset(s, 0, 8 * sizeof *s);
    s[n] = (sample){"sphere", VV_OBJECT_SPHERE, {.center = {0.3, -0.2, 0.1}, .radius = 1.3}, 1.3};
    n++;
    s[n] = (sample){"box", VV_OBJECT_BOX, {.box = {{-1, -0.5, 0}, {2, 1, 0.7}}}, 1};
    n++;
    s[n] = (sample){"capped cylinder",
                    VV_OBJECT_CYLINDER,
                    {.base = {0, 0, 0}, .top = {0.5, 1, 2}, .radius = 0.4, .capped = 1},
                    1};
    n++;
    s[n] = (sample){"open cylinder",
                    VV_OBJECT_CYLINDER,
                    {.base = {0, 0, -1}, .top = {0, 0, 1}, .radius = 0.7, .capped = 0},
                    1};
    n++;
    s[n] = (sample){
        "L polygon", VV_OBJECT_POLYGON, {.n_vertices = 6, .vertices = (vv_vec3 *)L_SHAPE}, 1};
    n++;
    s[n] = (sample){"quad", VV_OBJECT_POLYGON, {.n_vertices = 4, .vertices = (vv_vec3 *)QUAD}, 1};
    n++;
    s[n] = (sample){"plane",
                    VV_OBJECT_PLANE,
                    {.point = {1, 2, 3}, .normal = vv_vec3_normalize(vv_vec3_make(0.2, 0.3, 0.9))},
                    1};
    n++;
    s[n] = (sample){"mesh", VV_OBJECT_MESH, {.mesh = vt_sphere_mesh(0.9, 3)}, 0.9};
    n++;
    return n;
}

static void
samples_free(sample *s, int n) {
    for (int i = 0; i < n; i++)
        vv_mesh_free(s[i].g.mesh);
}

static vv_mesh *
tessellate(const vv_geom_type *gt, const sample *s, double tol) {
    vv_geom_tess opt = {.tolerance = tol * s->size};
    /* the plane: a square of half side 3 around its point nearest (0, 0, 0) */
    opt.center = vv_v3(0, 0, 0);
    opt.half = 3;
    vv_mesh *m = NULL;
    vt_ok(gt->tessellate(&s->g, &opt, &m));
    assert_non_null(m);
    assert_true(m->n_triangles > 0);
    return m;
}

static vv_vec3
corner(const vv_mesh *m, size_t t, int k) {
    return vv_mesh_vertex(m, m->triangles[3 * t + (size_t)k]);
}

static void
test_table(void **state) {
    (void)state;
    int n = 0;
    const vv_geom_type *const *all = vv_geom_types(&n);
    assert_int_equal(n, 6);
    for (int i = 0; i < n; i++) {
        const vv_geom_type *gt = all[i];
        assert_int_equal(gt->version, VV_GEOM_TYPE_VERSION);
        assert_ptr_equal(vv_geom_type_get(gt->type), gt);
        assert_string_equal(gt->name, vv_object_type_name(gt->type));
        assert_true(gt->check && gt->solid && gt->bounds && gt->tessellate && gt->intersect &&
                    gt->distance);
        assert_true(!gt->prepare == !gt->release);
    }
    assert_null(vv_geom_type_get(VV_OBJECT_VOLUME));
    assert_null(vv_geom_type_get(VV_OBJECT_GRID));
}

static void
test_checks(void **state) {
    (void)state;
    vv_geometry g;
    memset(&g, 0, sizeof g);
    const vv_geom_type *sp = vv_geom_type_get(VV_OBJECT_SPHERE);
    g.radius = 0;
    vt_err(sp->check(&g));
    g.radius = NAN;
    vt_err(sp->check(&g));
    g.radius = 1;
    vt_ok(sp->check(&g));
    const vv_geom_type *bx = vv_geom_type_get(VV_OBJECT_BOX);
    g.box = (vv_box){{0, 0, 1}, {1, 1, 0}};
    vt_err(bx->check(&g));
    vv_mesh *m = NULL;
    vt_err(bx->tessellate(&g, &(vv_geom_tess){.segments = 8}, &m));
    assert_null(m);
    const vv_geom_type *cy = vv_geom_type_get(VV_OBJECT_CYLINDER);
    g.base = g.top = vv_v3(1, 1, 1);
    g.radius = 1;
    vt_err(cy->check(&g));
    const vv_geom_type *pg = vv_geom_type_get(VV_OBJECT_POLYGON);
    const vv_vec3 line[3] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
    g.vertices = (vv_vec3 *)line;
    g.n_vertices = 2;
    vt_err(pg->check(&g));
    g.n_vertices = 3;
    vt_err(pg->check(&g)); /* collinear: no area */
    void *prep = NULL;
    vt_err(pg->prepare(&g, &prep));
    assert_null(prep);
    const vv_geom_type *pl = vv_geom_type_get(VV_OBJECT_PLANE);
    g.normal = vv_v3(0, 0, 0);
    vt_err(pl->check(&g));
    const vv_geom_type *me = vv_geom_type_get(VV_OBJECT_MESH);
    g.mesh = NULL;
    vt_err(me->check(&g));
    vt_err(me->prepare(&g, &prep));
}

/* Bounds hold the tessellation (tightly for flat shapes); the distance is
 * ~0 at the vertices, within the tolerance at the triangle centroids, and
 * has the right sign just off the surface. */
static void
test_bounds_and_distance(void **state) {
    (void)state;
    sample s[8];
    const int ns = samples(s);
    const double tol = 1e-3;
    for (int i = 0; i < ns; i++) {
        const vv_geom_type *gt = vv_geom_type_get(s[i].type);
        vt_ok(gt->check(&s[i].g));
        void *prep = NULL;
        if (gt->prepare)
            vt_ok(gt->prepare(&s[i].g, &prep));
        vv_mesh *m = tessellate(gt, &s[i], tol);
        vv_box b;
        const int bounded = gt->bounds(&s[i].g, &b);
        assert_int_equal(bounded, s[i].type != VV_OBJECT_PLANE);
        const double eps = 1e-3 * s[i].size, vtol = 2e-6 * s[i].size;
        for (size_t v = 0; v < m->n_vertices; v++) {
            const vv_vec3 p = vv_mesh_vertex(m, v);
            if (bounded) {
                const double bt = 1e-6 * s[i].size;
                if (p.x < b.min.x - bt || p.y < b.min.y - bt || p.z < b.min.z - bt ||
                    p.x > b.max.x + bt || p.y > b.max.y + bt || p.z > b.max.z + bt)
                    fail_msg("%s: vertex %zu (%g %g %g) outside its bounds", s[i].what, v, p.x, p.y,
                             p.z);
            }
            const double d = gt->distance(&s[i].g, prep, p);
            if (!(fabs(d) <= vtol))
                fail_msg("%s: distance %g at vertex %zu", s[i].what, d, v);
            if (m->normals) {
                /* outward along the vertex normal: +eps */
                const vv_vec3 n = vv_v3_f(m->normals + 3 * v);
                assert_near(vv_v3_len(n), 1, 1e-6);
                const double dout = gt->distance(&s[i].g, prep, vv_v3_add(p, vv_v3_scale(n, eps)));
                if (!(fabs(dout - eps) <= 0.05 * eps + vtol))
                    fail_msg("%s: distance %g a step %g outside vertex %zu", s[i].what, dout, eps,
                             v);
            }
        }
        for (size_t t = 0; t < m->n_triangles; t++) {
            const vv_vec3 a = corner(m, t, 0), bb = corner(m, t, 1), c = corner(m, t, 2);
            const vv_vec3 cen = vv_v3_scale(vv_v3_add(a, vv_v3_add(bb, c)), 1.0 / 3);
            const vv_vec3 fn = vv_v3_norm(vv_v3_cross(vv_v3_sub(bb, a), vv_v3_sub(c, a)));
            const double d = gt->distance(&s[i].g, prep, cen);
            /* chords of convex surfaces lie inside: <= 0 and within the tolerance */
            if (!(fabs(d) <= 2 * tol * s[i].size + vtol))
                fail_msg("%s: distance %g at the centroid of triangle %zu", s[i].what, d, t);
            const double ec = 0.02 * s[i].size; /* well past the chord error */
            const double din = gt->distance(&s[i].g, prep, vv_v3_sub(cen, vv_v3_scale(fn, ec)));
            const double dout = gt->distance(&s[i].g, prep, vv_v3_add(cen, vv_v3_scale(fn, ec)));
            if (!(din < 0 && dout > 0))
                fail_msg("%s: triangle %zu: distance %g behind and %g in front (step %g)",
                         s[i].what, t, din, dout, ec);
            /* the triangles face outwards: the vertex normals agree */
            if (m->normals) {
                vv_vec3 vn = {0, 0, 0};
                for (int k = 0; k < 3; k++)
                    vn = vv_v3_add(vn, vv_v3_f(m->normals + 3 * m->triangles[3 * t + (size_t)k]));
                assert_true(vv_v3_dot(vn, fn) > 0);
            }
        }
        /* points far outside are positive; the box centre of a solid is inside */
        if (bounded) {
            const vv_vec3 far = vv_v3_add(b.max, vv_v3(s[i].size, s[i].size, s[i].size));
            assert_true(gt->distance(&s[i].g, prep, far) > 0);
            if (gt->solid(&s[i].g))
                assert_true(gt->distance(&s[i].g, prep, vv_v3_scale(vv_v3_add(b.min, b.max), 0.5)) <
                            0);
        }
        vv_mesh_free(m);
        if (prep)
            gt->release(prep);
    }
    samples_free(s, ns);
}

/* Exact distances: a sphere, a box, a capped cylinder, a plane. */
static void
test_distance_analytic(void **state) {
    (void)state;
    vv_geometry g;
    memset(&g, 0, sizeof g);
    g.center = vv_v3(1, 1, 1);
    g.radius = 2;
    const vv_geom_type *sp = vv_geom_type_get(VV_OBJECT_SPHERE);
    assert_near(sp->distance(&g, NULL, vv_v3(1, 1, 5)), 2, 1e-15);
    assert_near(sp->distance(&g, NULL, vv_v3(1, 1, 1)), -2, 1e-15);
    const vv_geom_type *bx = vv_geom_type_get(VV_OBJECT_BOX);
    g.box = (vv_box){{0, 0, 0}, {2, 4, 6}};
    assert_near(bx->distance(&g, NULL, vv_v3(1, 2, 3)), -1, 1e-15);   /* nearest face x */
    assert_near(bx->distance(&g, NULL, vv_v3(5, 2, 3)), 3, 1e-15);    /* off a face */
    assert_near(bx->distance(&g, NULL, vv_v3(5, 8, 3)), 5, 1e-15);    /* off an edge: 3-4-5 */
    assert_near(bx->distance(&g, NULL, vv_v3(-1, -2, -2)), 3, 1e-15); /* off a corner */
    const vv_geom_type *cy = vv_geom_type_get(VV_OBJECT_CYLINDER);
    g.base = vv_v3(0, 0, 0);
    g.top = vv_v3(0, 0, 4);
    g.radius = 1;
    g.capped = 1;
    assert_near(cy->distance(&g, NULL, vv_v3(0, 0, 2)), -1, 1e-15);
    assert_near(cy->distance(&g, NULL, vv_v3(0.5, 0, 3.8)), -0.2, 1e-12);
    assert_near(cy->distance(&g, NULL, vv_v3(4, 0, 2)), 3, 1e-15);
    assert_near(cy->distance(&g, NULL, vv_v3(4, 0, 8)), 5, 1e-15);
    g.capped = 0; /* the open tube: to the wall, the rim beyond the ends */
    assert_near(cy->distance(&g, NULL, vv_v3(0.5, 0, 3.8)), -0.5, 1e-12);
    assert_near(cy->distance(&g, NULL, vv_v3(0, 0, 7)), -sqrt(10), 1e-12);
    const vv_geom_type *pl = vv_geom_type_get(VV_OBJECT_PLANE);
    g.point = vv_v3(0, 0, 1);
    g.normal = vv_v3(0, 0, 2); /* not unit: the distance is still in lengths */
    assert_near(pl->distance(&g, NULL, vv_v3(5, 5, -2)), -3, 1e-15);
}

/* Random rays from outside at points in the bounds: the record's nearest
 * hit against the nearest hit among its tessellation's triangles. */
static void
test_intersect_vs_tessellation(void **state) {
    (void)state;
    sample s[8];
    const int ns = samples(s);
    const double tol = 2e-4;
    uint64_t seed = 99;
    for (int i = 0; i < ns; i++) {
        const vv_geom_type *gt = vv_geom_type_get(s[i].type);
        void *prep = NULL;
        if (gt->prepare)
            vt_ok(gt->prepare(&s[i].g, &prep));
        vv_mesh *m = tessellate(gt, &s[i], tol);
        vv_box b;
        if (!gt->bounds(&s[i].g, &b)) /* the plane: around its nearest point to the origin */
            b = (vv_box){{-2, -2, -2}, {2, 2, 4}};
        const vv_vec3 c = vv_v3_scale(vv_v3_add(b.min, b.max), 0.5);
        const double R = vv_v3_len(vv_v3_sub(b.max, b.min));
        int hits = 0, grazing = 0, mismatch = 0;
        for (int r = 0; r < 1500; r++) {
            vv_vec3 target = vv_v3(vt_rnd(&seed, b.min.x, b.max.x), vt_rnd(&seed, b.min.y, b.max.y),
                                   vt_rnd(&seed, b.min.z, b.max.z));
            if (s[i].type == VV_OBJECT_PLANE) {
                /* on the plane, within 2 of the square's centre (half side 3) */
                const vv_vec3 n = s[i].g.normal;
                vv_vec3 p1, p2;
                vv_geom_perpendicular(n, &p1, &p2);
                const vv_vec3 q = vv_v3_scale(n, vv_v3_dot(n, s[i].g.point));
                target = vv_v3_add(q, vv_v3_add(vv_v3_scale(p1, vt_rnd(&seed, -2, 2)),
                                                vv_v3_scale(p2, vt_rnd(&seed, -2, 2))));
            }
            vv_vec3 dir =
                vv_v3_norm(vv_v3(vt_rnd(&seed, -1, 1), vt_rnd(&seed, -1, 1), vt_rnd(&seed, -1, 1)));
            const vv_vec3 o = vv_v3_add(c, vv_v3_scale(dir, 2 * R));
            const vv_vec3 d = vv_v3_sub(target, o);
            double th = INFINITY;
            for (size_t t = 0; t < m->n_triangles; t++) {
                double tt, u, v;
                if (vv_ray_triangle3(o, d, corner(m, t, 0), corner(m, t, 1), corner(m, t, 2), &tt,
                                     &u, &v) &&
                    tt > 0 && tt < th)
                    th = tt;
            }
            double tr;
            vv_vec3 n;
            const int hit = gt->intersect(&s[i].g, prep, o, d, 0, INFINITY, &tr, &n);
            const double L = vv_v3_len(d);
            if (hit != (th < INFINITY)) {
                /* only by a grazing ray, within the tolerance of both */
                mismatch++;
                const vv_vec3 p = vv_v3_add(o, vv_v3_scale(d, hit ? tr : th));
                if (!hit) {
                    assert_true(fabs(gt->distance(&s[i].g, prep, p)) <= 3 * tol * s[i].size);
                } else if (s[i].type != VV_OBJECT_PLANE) { /* the plane: beyond the square */
                    double best = INFINITY;
                    for (size_t t = 0; t < m->n_triangles; t++)
                        best = fmin(best,
                                    vv_v3_len(vv_v3_sub(p, vv_closest_point_triangle(
                                                               p, corner(m, t, 0), corner(m, t, 1),
                                                               corner(m, t, 2)))));
                    assert_true(best <= 3 * tol * s[i].size + 1e-9);
                }
                continue;
            }
            if (!hit)
                continue;
            hits++;
            const vv_vec3 pr = vv_v3_add(o, vv_v3_scale(d, tr)),
                          pt = vv_v3_add(o, vv_v3_scale(d, th));
            const vv_vec3 nn = vv_v3_norm(n);
            const double cosang = fabs(vv_v3_dot(nn, vv_v3_scale(d, 1 / L)));
            if (cosang < 0.1) {
                grazing++;
                continue;
            }
            if (!(vv_v3_len(vv_v3_sub(pr, pt)) <= 4 * tol * s[i].size / cosang + 1e-9))
                fail_msg("%s: ray %d: record hit (%g %g %g), triangles (%g %g %g)", s[i].what, r,
                         pr.x, pr.y, pr.z, pt.x, pt.y, pt.z);
            /* the normal faces out: a step along it leaves a solid, or goes to
             * a surface's front */
            const double h = 1e-4 * s[i].size;
            if (!(gt->distance(&s[i].g, prep, vv_v3_add(pr, vv_v3_scale(nn, h))) > 0))
                fail_msg("%s: ray %d: the normal does not face out", s[i].what, r);
            /* from just past the hit, a solid is left again further on */
            double t2;
            vv_vec3 n2;
            if (gt->solid(&s[i].g)) {
                assert_true(
                    gt->intersect(&s[i].g, prep, o, d, tr * (1 + 1e-9), INFINITY, &t2, &n2));
                assert_true(t2 > tr && vv_v3_dot(n2, d) > 0);
                /* and nothing lies in (0, tr) */
                assert_false(gt->intersect(&s[i].g, prep, o, d, 0, tr * (1 - 1e-9), &t2, &n2));
            }
        }
        if (!(hits > 300 && mismatch < 40 && grazing < 200))
            fail_msg("%s: %d hits, %d mismatches, %d grazing", s[i].what, hits, mismatch, grazing);
        vv_mesh_free(m);
        if (prep)
            gt->release(prep);
    }
    samples_free(s, ns);
}

/* Ear clipping: the triangles cover the polygon exactly (their areas add up
 * to its area and their centroids lie inside it), all facing the Newell
 * normal; a convex polygon gives the fan from its first vertex. */
static void
test_polygon_tessellation(void **state) {
    (void)state;
    const vv_geom_type *pg = vv_geom_type_get(VV_OBJECT_POLYGON);
    vv_geometry g;
    memset(&g, 0, sizeof g);
    g.vertices = (vv_vec3 *)L_SHAPE;
    g.n_vertices = 6;
    vv_mesh *m = NULL;
    vt_ok(pg->tessellate(&g, &(vv_geom_tess){0}, &m));
    assert_int_equal(m->n_triangles, 4);
    const vv_vec3 nn = vv_geom_newell(L_SHAPE, 6);
    double area = 0;
    void *prep = NULL;
    vt_ok(pg->prepare(&g, &prep));
    for (size_t t = 0; t < m->n_triangles; t++) {
        const vv_vec3 a = corner(m, t, 0), b = corner(m, t, 1), c = corner(m, t, 2);
        const vv_vec3 cr = vv_v3_cross(vv_v3_sub(b, a), vv_v3_sub(c, a));
        assert_true(vv_v3_dot(cr, nn) > 0);
        area += 0.5 * vv_v3_len(cr);
        /* the centroid is on the polygon: distance 0 */
        const vv_vec3 cen = vv_v3_scale(vv_v3_add(a, vv_v3_add(b, c)), 1.0 / 3);
        assert_true(fabs(pg->distance(&g, prep, cen)) < 1e-6);
    }
    assert_near(area, 0.5 * vv_v3_len(nn), 1e-6);
    pg->release(prep);
    vv_mesh_free(m);
    g.vertices = (vv_vec3 *)QUAD;
    g.n_vertices = 4;
    vt_ok(pg->tessellate(&g, &(vv_geom_tess){0}, &m));
    const uint32_t fan[6] = {0, 1, 2, 0, 2, 3};
    assert_int_equal(m->n_triangles, 2);
    assert_memory_equal(m->triangles, fan, sizeof fan);
    vv_mesh_free(m);
}

/* The tolerance sets the segments: a finer tolerance gives more triangles and
 * a closer fit. */
static void
test_tolerance(void **state) {
    (void)state;
    const vv_geom_type *sp = vv_geom_type_get(VV_OBJECT_SPHERE);
    vv_geometry g;
    memset(&g, 0, sizeof g);
    g.radius = 10;
    double prev = INFINITY;
    size_t prev_n = 0;
    for (int k = 0; k < 4; k++) {
        const double tol = 0.5 / pow(4, k);
        vv_mesh *m = NULL;
        vt_ok(sp->tessellate(&g, &(vv_geom_tess){.tolerance = tol}, &m));
        double worst = 0;
        for (size_t t = 0; t < m->n_triangles; t++) {
            const vv_vec3 cen = vv_v3_scale(
                vv_v3_add(corner(m, t, 0), vv_v3_add(corner(m, t, 1), corner(m, t, 2))), 1.0 / 3);
            worst = fmax(worst, -sp->distance(&g, NULL, cen));
        }
        assert_true(worst <= 2 * tol);
        assert_true(worst < prev && m->n_triangles > prev_n);
        prev = worst;
        prev_n = m->n_triangles;
        vv_mesh_free(m);
    }
    /* segments given: exactly that many meridians */
    vv_mesh *m = NULL;
    vt_ok(sp->tessellate(&g, &(vv_geom_tess){.segments = 12}, &m));
    assert_int_equal(m->n_triangles, 2 * 6 * 12 - 2 * 12);
    vv_mesh_free(m);
}

/* Objects use the table for their world boxes: a plane has none. */
static void
test_object_bounds(void **state) {
    (void)state;
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, NULL));
    o->geometry.radius = 2;
    o->position = vv_v3(1, 0, 0);
    vv_box b = vv_object_world_box(o);
    assert_true(b.min.x == -1 && b.max.x == 3 && b.min.z == -2 && b.max.z == 2);
    vv_object_free(o);
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_PLANE, NULL));
    b = vv_object_world_box(o);
    assert_true(b.min.x > b.max.x);
    vv_object_free(o);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_checks),
        cmocka_unit_test(test_bounds_and_distance),
        cmocka_unit_test(test_distance_analytic),
        cmocka_unit_test(test_intersect_vs_tessellation),
        cmocka_unit_test(test_polygon_tessellation),
        cmocka_unit_test(test_tolerance),
        cmocka_unit_test(test_object_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
