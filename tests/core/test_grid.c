/*
 * The grid data model (src/core/grid.c, grid_tets.c) and Marching
 * Tetrahedra (src/surface/marching_tets.c): validation, fields and fill
 * values, time steps, blocks, spherical lattices, the split into
 * tetrahedra with adjacency and boundary faces, degenerate and missing
 * cells, isosurface area against the analytic sphere.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/grid_internal.h"
#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Two tetrahedra sharing the face (1, 2, 3). */
static vv_grid *
two_tets(void) {
    vv_grid *g = NULL;
    vt_ok(vv_grid_new(&g, VV_GRID_UNSTRUCTURED));
    vt_ok(vv_grid_alloc(g, 5, 2, 8));
    const double P[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    memcpy(g->points, P, sizeof P);
    const uint32_t c[8] = {0, 1, 2, 3, 4, 1, 2, 3};
    memcpy(g->connectivity, c, sizeof c);
    for (int i = 0; i < 2; i++) {
        g->cell_types[i] = VV_CELL_TETRA;
        g->cell_offsets[i + 1] = 4 * (size_t)(i + 1);
    }
    return g;
}

static void
test_validate_and_bounds(void **state) {
    (void)state;
    vv_grid *g = two_tets();
    vt_ok(vv_grid_validate(g));
    vv_box b = vv_grid_bounds(g);
    assert_near(b.max.x, 1, 0);
    assert_near(b.min.z, 0, 0);
    g->connectivity[5] = 7; /* a missing point */
    vt_err(vv_grid_validate(g));
    assert_non_null(strstr(vv_error_message(), "point 7"));
    g->connectivity[5] = 1;
    g->cell_types[1] = VV_CELL_HEXAHEDRON; /* 4 points for a hexahedron */
    vt_err(vv_grid_validate(g));
    vv_grid_free(g);
    /* limits are checked before allocating */
    vt_ok(vv_grid_new(&g, VV_GRID_UNSTRUCTURED));
    vv_error_clear();
    assert_int_equal(vv_grid_alloc(g, (size_t)VV_GRID_MAX_POINTS + 1, 0, 0), VV_ERR_LIMIT);
    vv_grid_free(g);
}

static void
test_fields(void **state) {
    (void)state;
    vv_grid *g = two_tets();
    vv_grid_field *f = NULL;
    vt_ok(vv_grid_add_field(g, "v", 0, 3, &f));
    for (int i = 0; i < 5; i++) {
        f->values[3 * i] = 3;
        f->values[3 * i + 1] = 4;
        f->values[3 * i + 2] = (float)i;
    }
    f->values[3 * 4 + 2] = -999;
    f->has_fill = 1;
    f->fill = -999; /* point 4 is missing */
    vv_grid_field_update_range(f);
    assert_near(f->range[0], 5, 1e-6);            /* |(3, 4, 0)| */
    assert_near(f->range[1], sqrt(25 + 9), 1e-5); /* point 3 */
    float *sc = NULL;
    vt_ok(vv_grid_field_scalars(g, 0, 2, &sc));
    assert_near(sc[3], 3, 0);
    assert_true(isnan(sc[4]));
    free(sc);
    vt_err(vv_grid_field_scalars(g, 0, 3, &sc));
    vv_grid_field *t1 = NULL;
    vt_ok(vv_grid_add_field(g, "thickness1", 1, 1, &t1));
    assert_int_equal(t1->n_tuples, 2);
    assert_int_equal(vv_grid_find_field(g, "thickness", 1), 1);
    assert_int_equal(vv_grid_find_field(g, "thickness", 2), -1);
    assert_int_equal(vv_grid_find_field(g, "v", 0), 0);
    assert_int_equal(vv_grid_find_field(g, NULL, 0), 0);
    vv_grid_free(g);
}

static void
test_tetmesh_adjacency(void **state) {
    (void)state;
    vv_grid *g = two_tets();
    float v[5] = {0, 1, 2, 3, 4};
    vv_tetmesh m;
    vt_ok(vv_tetmesh_build(&m, g, v, 0, 1, 1));
    assert_int_equal(m.n_tets, 2);
    {
        size_t *off = NULL, nbound = 0;
        int64_t *nbr = NULL;
        vt_ok(vv_grid_face_adjacency(g, &off, &nbr, &nbound));
        assert_int_equal(nbound, 6);
        assert_int_equal(nbr[0], 1);     /* tetra 0's face 0 is (1, 2, 3) */
        assert_int_equal(nbr[4 + 0], 0); /* tetra 1 = (4, 1, 2, 3): face 0 is the same */
        assert_int_equal(nbr[1], -1);
        free(off);
        free(nbr);
    }
    size_t boundary = 0;
    for (size_t f = 0; f < 8; f++)
        boundary += m.nb[f] < 0;
    assert_int_equal(boundary, 6);
    /* neighbours point back at each other */
    for (size_t f = 0; f < 8; f++)
        if (m.nb[f] >= 0)
            assert_int_equal(m.nb[m.nb[f]], (int32_t)f);
    /* positive orientation after the split */
    for (size_t t = 0; t < 2; t++) {
        const double *a = m.p + 3 * m.tet[4 * t], *b = m.p + 3 * m.tet[4 * t + 1],
                     *c = m.p + 3 * m.tet[4 * t + 2], *d = m.p + 3 * m.tet[4 * t + 3];
        double u[3], w[3], z[3];
        for (int k = 0; k < 3; k++) {
            u[k] = b[k] - a[k];
            w[k] = c[k] - a[k];
            z[k] = d[k] - a[k];
        }
        const double det = u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) +
                           u[2] * (w[0] * z[1] - w[1] * z[0]);
        assert_true(det > 0);
    }
    /* f = x + 2y + 3z on the first tetrahedron, the only one at point 0 */
    assert_near(m.grad[0], 1, 1e-6);
    assert_near(m.grad[1], 2, 1e-6);
    assert_near(m.grad[2], 3, 1e-6);
    vv_tetmesh_clear(&m);
    /* a missing value drops the tetrahedra that touch it */
    v[4] = NAN;
    vt_ok(vv_tetmesh_build(&m, g, v, 0, 1, 0));
    assert_int_equal(m.n_tets, 1);
    assert_int_equal(m.n_missing, 1);
    vv_tetmesh_clear(&m);
    /* a degenerate (flat) tetrahedron is left out */
    g->points[3 * 4 + 0] = 0.25;
    g->points[3 * 4 + 1] = 0.25;
    g->points[3 * 4 + 2] = 0.5; /* on the plane x + y + z = 1 */
    v[4] = 1;
    vt_ok(vv_tetmesh_build(&m, g, v, 0, 1, 0));
    assert_int_equal(m.n_tets, 1);
    assert_int_equal(m.n_degenerate, 1);
    vv_tetmesh_clear(&m);
    vv_grid_free(g);
}

/* Three tetrahedra on one face: overlapping cells are an error. */
static void
test_nonmanifold(void **state) {
    (void)state;
    vv_grid *g = NULL;
    vt_ok(vv_grid_new(&g, VV_GRID_UNSTRUCTURED));
    vt_ok(vv_grid_alloc(g, 6, 3, 12));
    const double P[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {0.2, 0.2, 0.2}};
    memcpy(g->points, P, sizeof P);
    const uint32_t c[12] = {0, 1, 2, 3, 4, 1, 2, 3, 5, 1, 2, 3};
    memcpy(g->connectivity, c, sizeof c);
    for (int i = 0; i < 3; i++) {
        g->cell_types[i] = VV_CELL_TETRA;
        g->cell_offsets[i + 1] = 4 * (size_t)(i + 1);
    }
    float v[6] = {0, 0, 0, 0, 0, 0};
    vv_tetmesh m;
    vt_err(vv_tetmesh_build(&m, g, v, 0, 1, 0));
    assert_non_null(strstr(vv_error_message(), "three"));
    size_t *off = NULL;
    int64_t *nbr = NULL;
    vt_err(vv_grid_face_adjacency(g, &off, &nbr, NULL));
    assert_null(off);
    vv_grid_free(g);
}

/* Hexahedra, wedges and pyramids: split into tetrahedra of the same total
 * volume, with every interior face matched (no cracks). */
static void
test_mixed_cells(void **state) {
    (void)state;
    vv_grid *g = NULL;
    vt_ok(vv_grid_new(&g, VV_GRID_UNSTRUCTURED));
    /* a unit cube hexahedron [0,1]^3, a wedge on its top face x-y ... and a
     * pyramid on its +x face */
    vt_ok(vv_grid_alloc(g, 11, 3, 8 + 6 + 5));
    const double P[11][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1},    {1, 0, 1},
                             {1, 1, 1}, {0, 1, 1}, {0, 0, 2}, {1, 0, 2}, {2, 0.5, 0.5}};
    memcpy(g->points, P, sizeof P);
    const uint32_t hex[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    /* wedge: triangle (4, 5, 8) over... a prism with triangles (4,7,8)
     * and (5,6,9) sharing the top face quad (4,5,6,7) */
    const uint32_t wedge[6] = {4, 7, 8, 5, 6, 9};
    const uint32_t pyr[5] = {1, 2, 6, 5, 10};
    memcpy(g->connectivity, hex, sizeof hex);
    memcpy(g->connectivity + 8, wedge, sizeof wedge);
    memcpy(g->connectivity + 14, pyr, sizeof pyr);
    g->cell_types[0] = VV_CELL_HEXAHEDRON;
    g->cell_types[1] = VV_CELL_WEDGE;
    g->cell_types[2] = VV_CELL_PYRAMID;
    g->cell_offsets[1] = 8;
    g->cell_offsets[2] = 14;
    g->cell_offsets[3] = 19;
    vt_ok(vv_grid_validate(g));
    float v[11];
    for (int i = 0; i < 11; i++)
        v[i] = (float)i;
    vv_tetmesh m;
    vt_ok(vv_tetmesh_build(&m, g, v, 0, 1, 0));
    assert_int_equal(m.n_tets, 12 + 8 + 6);
    double vol = 0;
    for (size_t t = 0; t < m.n_tets; t++) {
        const double *a = m.p + 3 * m.tet[4 * t], *b = m.p + 3 * m.tet[4 * t + 1],
                     *c = m.p + 3 * m.tet[4 * t + 2], *d = m.p + 3 * m.tet[4 * t + 3];
        double u[3], w[3], z[3];
        for (int k = 0; k < 3; k++) {
            u[k] = b[k] - a[k];
            w[k] = c[k] - a[k];
            z[k] = d[k] - a[k];
        }
        vol += (u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) +
                u[2] * (w[0] * z[1] - w[1] * z[0])) /
               6;
    }
    /* cube 1 + prism (triangle area 1/2 x length 1) + pyramid (1 x 1 base, height 1) / 3 */
    assert_near(vol, 1 + 0.5 + 1.0 / 3, 1e-12);
    /* the boundary: 6 cube faces - 2 covered = 4 quads (8 triangles), the
     * prism's 2 triangles + 2 outer quads (4), the pyramid's 4 triangles */
    size_t boundary = 0;
    for (size_t f = 0; f < 4 * m.n_tets; f++)
        boundary += m.nb[f] < 0;
    assert_int_equal(boundary, 8 + 2 + 4 + 4);
    vv_tetmesh_clear(&m);
    /* cell adjacency: the hexahedron's +z face meets the wedge, its +x face the pyramid */
    size_t *off = NULL, nbound = 0;
    int64_t *nbr = NULL;
    vt_ok(vv_grid_face_adjacency(g, &off, &nbr, &nbound));
    assert_int_equal(off[3], 6 + 5 + 5);
    assert_int_equal(nbound, 6 + 5 + 5 - 4);
    assert_int_equal(nbr[1], 1);      /* hexahedron face 1 (+z) */
    assert_int_equal(nbr[3], 2);      /* hexahedron face 3 (+x) */
    assert_int_equal(nbr[off[2]], 0); /* the pyramid's base */
    assert_int_equal(nbr[0], -1);
    free(off);
    free(nbr);
    vv_grid_free(g);
}

static void
test_blocks_and_spherical(void **state) {
    (void)state;
    vv_grid *g = NULL;
    vt_ok(vv_grid_new(&g, VV_GRID_CURVILINEAR));
    const int d[3] = {3, 2, 2};
    double xyz[36];
    for (int k = 0, p = 0; k < 2; k++)
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 3; i++, p++) {
                xyz[3 * p] = i;
                xyz[3 * p + 1] = j;
                xyz[3 * p + 2] = k;
            }
    vt_ok(vv_grid_add_block(g, d, xyz));
    vt_ok(vv_grid_add_block(g, d, xyz));
    assert_int_equal(g->n_blocks, 2);
    assert_int_equal(g->n_cells, 4);
    assert_int_equal(g->connectivity[8 * 2], 12); /* second block's first point */
    vt_ok(vv_grid_validate(g));
    vv_grid_free(g);
    const double r[3] = {1, 2, 4}, th[3] = {0, M_PI / 2, M_PI}, ph[4] = {0, 1, 2, 3};
    vt_ok(vv_grid_new_spherical(&g, r, 3, th, 3, ph, 4, 1));
    assert_int_equal(g->n_points, 36);
    assert_int_equal(g->n_cells, 2 * 2 * 4); /* the phi cells wrap */
    vt_ok(vv_grid_validate(g));
    const double th_bad[3] = {0, 2, 1};
    vv_grid *g2 = NULL;
    vt_err(vv_grid_new_spherical(&g2, r, 3, th_bad, 3, ph, 4, 0));
    vv_grid_free(g);
}

/* Marching Tetrahedra of f = |x| on a lattice: the isosurface f = r is a
 * sphere of area 4 pi r^2, closed. */
static void
test_marching_tetrahedra_sphere(void **state) {
    (void)state;
    vv_volume *v = NULL;
    const int dims[3] = {33, 33, 33};
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    float *d = v->data;
    for (int k = 0, i = 0; k < 33; k++)
        for (int j = 0; j < 33; j++)
            for (int x = 0; x < 33; x++, i++)
                d[i] = (float)sqrt((x - 16.0) * (x - 16.0) + (j - 16.0) * (j - 16.0) +
                                   (k - 16.0) * (k - 16.0));
    vv_volume_update_range(v);
    vv_grid *g = NULL;
    vt_ok(vv_grid_new_from_volume(&g, v, 0)); /* hexahedra: centre split */
    vv_mesh *m = NULL;
    vt_ok(vv_grid_isosurface(g, 0, -1, 10.0, &m)); /* through lattice points */
    assert_true(fabs(vv_mesh_area(m) / (4 * M_PI * 100) - 1) < 0.02);
    vv_mesh_free(m);
    vt_ok(vv_grid_isosurface(g, 0, -1, 10.3, &m));
    const double area = vv_mesh_area(m);
    printf("Marching Tetrahedra sphere r = 10.3: area %.2f (exact %.2f), %zu triangles\n", area,
           4 * M_PI * 10.3 * 10.3, m->n_triangles);
    assert_true(fabs(area / (4 * M_PI * 10.3 * 10.3) - 1) < 0.02);
    vv_mesh_topology top;
    vt_ok(vv_mesh_topology_compute(m, &top));
    assert_true(top.closed);
    assert_true(top.oriented);
    /* triangles face away from the higher values: here the distance grows
     * outwards, so they face the centre and the signed volume is negative */
    assert_near(vv_mesh_signed_volume(m), -4.0 / 3 * M_PI * pow(10.3, 3), 0.03 * 4577);
    vv_mesh_free(m);
    vv_grid_free(g);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validate_and_bounds),
        cmocka_unit_test(test_fields),
        cmocka_unit_test(test_tetmesh_adjacency),
        cmocka_unit_test(test_nonmanifold),
        cmocka_unit_test(test_mixed_cells),
        cmocka_unit_test(test_blocks_and_spherical),
        cmocka_unit_test(test_marching_tetrahedra_sphere),
    };
    return vt_run_tests(tests, NULL, NULL);
}
