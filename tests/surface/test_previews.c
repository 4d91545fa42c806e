/*
 * Tests of the Navigator's reduced-resolution previews (src/surface/parc.c,
 * coarse.c): PARC keeps exactly the boxes a brute-force scan finds crossing
 * the isovalue and its outer faces enclose exactly their volume; coarse
 * Marching Cubes matches full-precision Marching Cubes on the reduced grid
 * triangle for triangle, with every vertex within 1/8 of an edge of the
 * exact crossing, and stays closed.
 */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static vv_volume *
sphere_volume(int n, double r, double c) {
    vv_volume *v = NULL;
    const int dims[3] = {n, n + 3, n - 2};
    vt_ok(vv_volume_new(&v, dims, VV_I16));
    v->spacing[0] = 0.8;
    v->spacing[1] = 1.0;
    v->spacing[2] = 1.3;
    for (int k = 0; k < dims[2]; k++)
        for (int j = 0; j < dims[1]; j++)
            for (int i = 0; i < dims[0]; i++) {
                double x = (i - c) * 0.8, y = (j - c) * 1.0, z = (k - c) * 1.3;
                vv_volume_set(v, i, j, k, 1000 * (r - sqrt(x * x + y * y + z * z)));
            }
    vv_volume_update_range(v);
    return v;
}

static void
test_parc(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(50, 17, 24.3);
    for (int level = 1; level <= 4; level++) {
        vv_parc *p = NULL;
        vt_ok(vv_parc_new(&p, v, level));
        assert_int_equal(p->n_boxes, 0);
        vt_ok(vv_parc_set_isovalue(p, 0.5));
        const int B = p->block;
        size_t kept = 0;
        double boxvol = 0;
        for (int bk = 0; bk < p->dims[2]; bk++)
            for (int bj = 0; bj < p->dims[1]; bj++)
                for (int bi = 0; bi < p->dims[0]; bi++) {
                    int lo[3] = {bi * B, bj * B, bk * B}, hi[3], in = 0, out = 0;
                    for (int a = 0; a < 3; a++)
                        hi[a] = lo[a] + B < v->dims[a] - 1 ? lo[a] + B : v->dims[a] - 1;
                    for (int k = lo[2]; k <= hi[2]; k++)
                        for (int j = lo[1]; j <= hi[1]; j++)
                            for (int i = lo[0]; i <= hi[0]; i++) {
                                double x = vv_volume_get(v, i, j, k);
                                in += x >= 0.5;
                                out += x < 0.5;
                            }
                    int want = in && out;
                    assert_int_equal(vv_parc_box_kept(p, bi, bj, bk), want);
                    if (want) {
                        kept++;
                        boxvol +=
                            (hi[0] - lo[0]) * 0.8 * (hi[1] - lo[1]) * 1.0 * (hi[2] - lo[2]) * 1.3;
                    }
                }
        assert_int_equal(p->n_boxes, kept);
        for (size_t q = 1; q < p->n_boxes; q++)
            assert_true(p->boxes[q] > p->boxes[q - 1]);
        vv_mesh *m = NULL;
        vt_ok(vv_parc_mesh(p, &m));
        vv_mesh_topology t;
        vt_ok(vv_mesh_topology_compute(m, &t));
        print_message(
            "level %d: block %d, %zu of %d boxes, %zu faces, enclosed %.1f (boxes %.1f)\n", level,
            B, p->n_boxes, p->dims[0] * p->dims[1] * p->dims[2], m->n_triangles / 2,
            vv_mesh_signed_volume(m), boxvol);
        assert_int_equal(t.n_boundary_edges, 0);
        assert_near(vv_mesh_signed_volume(m), boxvol, 1e-6 * boxvol);
        vv_mesh_free(m);
        /* an isovalue outside the range keeps nothing */
        vt_ok(vv_parc_set_isovalue(p, 1e9));
        assert_int_equal(p->n_boxes, 0);
        vt_err(vv_parc_set_isovalue(p, NAN));
        vv_parc_free(p);
    }
    vv_parc *p = NULL;
    vt_err(vv_parc_new(&p, v, 17));
    vt_err(vv_parc_new(&p, NULL, 2));
    vv_volume_free(v);
}

static void
test_coarse(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(64, 22, 31.1);
    for (int level = 0; level <= 2; level++) {
        vv_coarse_surface *c = NULL;
        vt_ok(vv_coarse_new(&c, v, level));
        assert_int_equal(c->stride, 1 << level);
        assert_int_equal(c->dims[0], 63 / c->stride + 1);
        vt_ok(vv_coarse_set_isovalue(c, 0.0, 2));
        vv_mesh *m = NULL, *exact = NULL;
        vt_ok(vv_coarse_mesh(c, &m));
        vv_isosurface_options o;
        vv_isosurface_options_init(&o);
        vt_ok(vv_isosurface_extract(&exact, c->reduced, 0.0, &o));
        assert_int_equal(m->n_triangles, exact->n_triangles);
        assert_int_equal(m->n_vertices, exact->n_vertices);
        assert_memory_equal(m->triangles, exact->triangles, 3 * m->n_triangles * sizeof(uint32_t));
        /* each vertex within 1/8 of its edge from the exact crossing (longest edge 1.3 s) */
        double worst = 0, lim = 0.125 * 1.3 * c->stride + 1e-4;
        for (size_t i = 0; i < m->n_vertices; i++) {
            vv_vec3 d = vv_vec3_sub(vv_mesh_vertex(m, i), vv_mesh_vertex(exact, i));
            worst = fmax(worst, vv_vec3_length(d));
        }
        vv_mesh_topology t;
        vt_ok(vv_mesh_topology_compute(m, &t));
        double r = 22, a0 = 4 * VV_PI * r * r;
        size_t full = m->n_vertices * 3 * sizeof(float) + m->n_triangles * 3 * sizeof(uint32_t);
        print_message("level %d: %zu triangles, worst vertex shift %.3f (limit %.3f), area %+.2f "
                      "%%, %zu bytes compact vs %zu float\n",
                      level, m->n_triangles, worst, lim, 100 * (vv_mesh_area(m) / a0 - 1),
                      vv_coarse_bytes(c), full);
        assert_true(worst <= lim);
        assert_true(t.closed && t.oriented && t.euler == 2);
        assert_true(fabs(vv_mesh_area(m) / a0 - 1) < 0.05 * (1 << level));
        assert_true(vv_coarse_bytes(c) < full);
        /* normals outward */
        for (size_t i = 0; i < m->n_vertices; i++) {
            vv_vec3 p = vv_mesh_vertex(m, i);
            vv_vec3 rad = vv_vec3_make(p.x - 31.1 * 0.8, p.y - 31.1, p.z - 31.1 * 1.3);
            const float *n = m->normals + 3 * i;
            assert_true(rad.x * n[0] + rad.y * n[1] + rad.z * n[2] > 0);
        }
        vv_mesh_free(m);
        vv_mesh_free(exact);
        /* a new isovalue replaces the surface */
        size_t before = c->n_triangles;
        vt_ok(vv_coarse_set_isovalue(c, -3000.0, 1));
        assert_true(c->n_triangles > before);
        vv_coarse_free(c);
    }
    vv_coarse_surface *c = NULL;
    vt_err(vv_coarse_new(&c, v, 9));
    vt_err(vv_coarse_new(&c, NULL, 1));
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parc),
        cmocka_unit_test(test_coarse),
    };
    return vt_run_tests(tests, NULL, NULL);
}
