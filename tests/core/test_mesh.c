/* Triangle meshes: building, area and divergence-theorem volume against
 * analytic values, topology (closed, oriented, Euler characteristic),
 * transforms, and file round trips through Assimp (PLY, OBJ, STL) plus the
 * shared real meshes. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VT_PI 3.14159265358979323846

static void
test_sphere_measures(void **state) {
    (void)state;
    vv_mesh *m = vt_sphere_mesh(10.0, 5);
    assert_int_equal(m->n_triangles, 8 * 1024);
    double a = vv_mesh_area(m), v = vv_mesh_signed_volume(m);
    /* inscribed polyhedron: a little below the sphere, converging as 4^-levels */
    assert_true(a < 4 * VT_PI * 100 && a > 0.995 * 4 * VT_PI * 100);
    assert_true(v < 4.0 / 3.0 * VT_PI * 1000 && v > 0.99 * 4.0 / 3.0 * VT_PI * 1000);
    vv_mesh_topology t;
    vt_ok(vv_mesh_topology_compute(m, &t));
    assert_true(t.closed);
    assert_true(t.oriented);
    assert_int_equal(t.euler, 2);
    assert_int_equal(t.n_boundary_edges, 0);

    /* translation keeps the volume; a mirror keeps it positive (winding flipped) */
    vv_mat4 M = vv_mat4_mul(vv_mat4_translate(vv_vec3_make(1000, -500, 3)),
                            vv_mat4_scale(vv_vec3_make(-1, 2, 1)));
    vv_mesh_transform(m, M);
    assert_near(vv_mesh_signed_volume(m), 2 * v, 1e-3 * v);
    /* prolate spheroid, semi-axes 10, 20, 10: 2 pi a^2 (1 + b asin(e) / (a e)) */
    double e = sqrt(1.0 - 0.25);
    double spheroid = 2 * VT_PI * 100 * (1 + 20 * asin(e) / (10 * e));
    assert_true(vv_mesh_area(m) < spheroid && vv_mesh_area(m) > 0.995 * spheroid);
    vt_ok(vv_mesh_topology_compute(m, &t));
    assert_true(t.oriented && t.closed);
    vt_ok(vv_mesh_compute_normals(m));
    vv_box b = vv_mesh_bounds(m);
    assert_near(b.min.x, 990, 1e-3);
    assert_near(b.max.y, -480, 1e-3);
    vv_mesh_free(m);
}

static void
test_open_and_bad(void **state) {
    (void)state;
    vv_mesh *m = vt_sphere_mesh(1.0, 1);
    m->n_triangles--; /* punch a hole */
    vv_mesh_topology t;
    vt_ok(vv_mesh_topology_compute(m, &t));
    assert_false(t.closed);
    assert_int_equal(t.n_boundary_edges, 3);
    vt_err(vv_mesh_add_triangle(m, 0, 1, 999));
    vt_err(vv_mesh_save(m, "/tmp/x.xyz"));
    vv_mesh_free(m);
    vv_mesh *none = NULL;
    vt_err(vv_mesh_load(&none, "/nonexistent/mesh.ply"));
    assert_null(none);

    char path[512];
    snprintf(path, sizeof path, "%s/garbage.ply", vt_outdir("mesh"));
    vt_write_file(path, "ply\nformat nonsense\n", 20);
    vv_mesh *g = NULL;
    vt_err(vv_mesh_load(&g, path));
    assert_null(g);
    assert_non_null(strstr(vv_error_message(), "garbage.ply"));
}

static void
test_round_trip(void **state) {
    (void)state;
    vv_mesh *m = vt_sphere_mesh(5.0, 3);
    vt_ok(vv_mesh_compute_normals(m));
    const char *ext[] = {"ply", "obj", "stl"};
    for (int i = 0; i < 3; i++) {
        char path[512];
        snprintf(path, sizeof path, "%s/sphere.%s", vt_outdir("mesh"), ext[i]);
        vt_ok(vv_mesh_save(m, path));
        vv_mesh *r = NULL;
        vt_ok(vv_mesh_load(&r, path));
        assert_int_equal(r->n_triangles, m->n_triangles);
        assert_int_equal(r->n_vertices, m->n_vertices); /* STL too: vertices rejoined */
        assert_near(vv_mesh_area(r), vv_mesh_area(m), 1e-4 * vv_mesh_area(m));
        assert_near(vv_mesh_signed_volume(r), vv_mesh_signed_volume(m),
                    1e-4 * vv_mesh_signed_volume(m));
        vv_mesh_topology t;
        vt_ok(vv_mesh_topology_compute(r, &t));
        assert_true(t.closed && t.oriented);
        assert_int_equal(t.euler, 2);
        assert_non_null(r->normals);
        vv_mesh_free(r);
    }
    vv_mesh_free(m);
}

static void
test_shared_meshes(void **state) {
    (void)state;
    const char *files[] = {"meshes/bunny.ply", "meshes/knot1.off", "meshes/cow.obj",
                           "meshes/propeller.stl", "meshes/42400-IDGH.stl"};
    for (int i = 0; i < 5; i++) {
        vv_mesh *m = NULL;
        vt_ok(vv_mesh_load(&m, vt_data(files[i])));
        assert_true(m->n_triangles > 100);
        assert_true(vv_mesh_area(m) > 0);
        vv_mesh_topology t;
        vt_ok(vv_mesh_topology_compute(m, &t));
        printf("%s: %zu vertices, %zu triangles, area %g, volume %g, closed %d, boundary %zu, "
               "euler %ld\n",
               files[i], m->n_vertices, m->n_triangles, vv_mesh_area(m), vv_mesh_signed_volume(m),
               t.closed, t.n_boundary_edges, t.euler);
        vv_mesh_free(m);
    }
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_measures),
        cmocka_unit_test(test_open_and_bad),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_shared_meshes),
    };
    return vt_run_tests(tests, NULL, NULL);
}
