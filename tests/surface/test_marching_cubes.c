/*
 * Tests of Marching Cubes (src/surface/marching_cubes.c, mc_tables.c).
 *
 * Analytic phantoms: spheres of radius 5..100 voxels, a box and a torus
 * sampled as signed distances, whose area and volume are known; the mesh
 * must be closed, consistently oriented and of the right Euler
 * characteristic (2 per sphere, 0 for a torus). The r = 100 sphere is the
 * u8 phantom of ../shared/anchors/make_phantoms.py, on which VTK's marching
 * cubes has area error +0.59 % and volume error -0.011 %
 * (../shared/BENCHMARKS.md). Then: voxel types, spacing and direction,
 * ROI, cut planes, the min/max grid, thread counts, mesh files, the real CT
 * head against VTK's flying edges, bad input and cancellation.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "surface/surface_internal.h"

static vv_volume *
new_volume(int nx, int ny, int nz, vv_voxel_type t) {
    vv_volume *v = NULL;
    const int dims[3] = {nx, ny, nz};
    vt_ok(vv_volume_new(&v, dims, t));
    return v;
}

/* value = r - |x - c| on an n^3 f32 grid, c = (n-1)/2 + offset */
static vv_volume *
sphere_volume(int n, double r, double off) {
    vv_volume *v = new_volume(n, n, n, VV_F32);
    const double c = 0.5 * (n - 1) + off;
    float *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                d[((size_t)k * n + j) * n + i] =
                    (float)(r - sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c)));
    vv_volume_update_range(v);
    return v;
}

static vv_mesh *
extract(const vv_volume *v, double iso, int threads) {
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    vv_mesh *m = NULL;
    vt_ok(vv_isosurface_extract(&m, v, iso, &o));
    return m;
}

static void
check_closed(const vv_mesh *m, long euler) {
    vv_mesh_topology t;
    vt_ok(vv_mesh_topology_compute(m, &t));
    if (!t.closed || !t.oriented || t.euler != euler || t.n_vertices_used != m->n_vertices)
        fail_msg("topology: closed %d oriented %d euler %ld (want %ld) boundary %zu "
                 "non-manifold %zu misoriented %zu used %zu of %zu vertices",
                 t.closed, t.oriented, t.euler, euler, t.n_boundary_edges, t.n_nonmanifold_edges,
                 t.n_misoriented_edges, t.n_vertices_used, m->n_vertices);
}

/* ---------------------------------------------------------------------- */

static void
test_tables(void **state) {
    (void)state;
    const mc_tables *tb = mc_tables_get();
    assert_non_null(tb);
    print_message("%d configurations for 256 cases\n", tb->n_configs);
    assert_int_equal(tb->configs[tb->base[0]].n_tri, 0);
    assert_int_equal(tb->configs[tb->base[255]].n_tri, 0);
    for (int cs = 0; cs < 256; cs++) {
        int nconf = 1 << tb->n_amb[cs];
        for (int d = 0; d < nconf; d++) {
            const mc_config *cf = &tb->configs[tb->base[cs] + d];
            /* every crossing edge is used, no other edge; each loop gives n-2 triangles */
            int used = 0;
            for (int t = 0; t < cf->n_tri; t++)
                for (int c = 0; c < 3; c++)
                    if (cf->tri[t][c] < 12)
                        used |= 1 << cf->tri[t][c];
                    else
                        assert_true(cf->tri[t][c] < 12 + cf->n_centre);
            assert_int_equal(used, tb->edge_mask[cs]);
            /* complement symmetry: same number of crossing edges */
            assert_int_equal(__builtin_popcount(tb->edge_mask[cs]),
                             __builtin_popcount(tb->edge_mask[255 - cs]));
        }
    }
    /* the single-corner case: one triangle x, y, z edges, counter-clockwise from outside */
    const mc_config *c1 = &tb->configs[tb->base[1]];
    assert_int_equal(c1->n_tri, 1);
    assert_int_equal(c1->tri[0][0], 0);
    assert_int_equal(c1->tri[0][1], 3);
    assert_int_equal(c1->tri[0][2], 8);
}

/* Every single cell configuration, alone in a 2x2x2 grid padded to 4x4x4 with outside
 * values, gives a closed oriented surface; ambiguous faces get both decisions by choosing
 * values whose saddle is inside or outside. */
static void
test_every_case_closed(void **state) {
    (void)state;
    const int off[8][3] = {{1, 1, 1}, {2, 1, 1}, {2, 2, 1}, {1, 2, 1},
                           {1, 1, 2}, {2, 1, 2}, {2, 2, 2}, {1, 2, 2}};
    for (int cs = 1; cs < 255; cs++)
        for (int variant = 0; variant < 3; variant++) {
            vv_volume *v = new_volume(4, 4, 4, VV_F32);
            float *d = v->data;
            for (int i = 0; i < 64; i++)
                d[i] = -1;
            for (int c = 0; c < 8; c++) {
                /* variant 0: inside 1, outside -1 (saddles at 0: joined), 1: inside 0.3,
                 * outside -1 (separated), 2: mixed magnitudes */
                double in = variant == 1 ? 0.3 : variant == 2 ? 0.2 + 0.1 * c : 1.0;
                double out = variant == 2 ? -0.3 - 0.15 * c : -1.0;
                d[(off[c][2] * 4 + off[c][1]) * 4 + off[c][0]] = (float)((cs >> c & 1) ? in : out);
            }
            vv_volume_update_range(v);
            vv_mesh *m = extract(v, 0.0, 1);
            vv_mesh_topology t;
            vt_ok(vv_mesh_topology_compute(m, &t));
            if (!t.closed || !t.oriented || t.n_degenerate)
                fail_msg("case %d variant %d: closed %d oriented %d degenerate %zu", cs, variant,
                         t.closed, t.oriented, t.n_degenerate);
            /* the signed volume is positive: inside is >= iso */
            assert_true(vv_mesh_signed_volume(m) > 0);
            vv_mesh_free(m);
            vv_volume_free(v);
        }
}

static void
test_spheres(void **state) {
    (void)state;
    const double radii[] = {5, 12, 30};
    for (size_t q = 0; q < sizeof radii / sizeof radii[0]; q++) {
        double r = radii[q];
        int n = (int)(2 * r) + 8;
        vv_volume *v = sphere_volume(n, r, 0.21);
        vv_mesh *m = extract(v, 0.0, 2);
        check_closed(m, 2);
        double a = vv_mesh_area(m), vol = vv_mesh_signed_volume(m);
        double a0 = 4 * VV_PI * r * r, v0 = 4.0 / 3.0 * VV_PI * r * r * r;
        print_message("r = %g: %zu triangles, area %+.3f %%, volume %+.3f %%\n", r, m->n_triangles,
                      100 * (a / a0 - 1), 100 * (vol / v0 - 1));
        /* linear interpolation along edges of a distance field puts the vertices inside
         * the sphere (the field is concave along every chord): errors fall with r */
        assert_true(a < a0 && vol < v0);
        /* second order: -1.26 % / -2.39 % at r = 5, -0.035 % / -0.066 % at r = 30 */
        assert_true(fabs(a / a0 - 1) < 0.4 / (r * r));
        assert_true(fabs(vol / v0 - 1) < 0.7 / (r * r));
        /* normals: outward radial */
        const double c = 0.5 * (n - 1) + 0.21;
        double worst = 1;
        for (size_t i = 0; i < m->n_vertices; i++) {
            const float *p = m->positions + 3 * i, *nn = m->normals + 3 * i;
            double rx = p[0] - c, ry = p[1] - c, rz = p[2] - c,
                   l = sqrt(rx * rx + ry * ry + rz * rz);
            double dt = (rx * nn[0] + ry * nn[1] + rz * nn[2]) / l;
            worst = dt < worst ? dt : worst;
        }
        print_message("   worst normal . radial %.5f\n", worst);
        assert_true(worst > 0.98);
        vv_mesh_free(m);
        vv_volume_free(v);
    }
}

/* The anchors' sphere256 phantom: u8 clamp(round(127.5 + 4 (100 - d))), iso 127.5. */
static void
test_sphere_phantom_vs_vtk(void **state) {
    (void)state;
    const int n = 256;
    vv_volume *v = new_volume(n, n, n, VV_U8);
    uint8_t *d = v->data;
    const double c = (n - 1) / 2.0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double dist = sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c));
                double x = floor(127.5 + 4 * (100 - dist) + 0.5);
                d[((size_t)k * n + j) * n + i] = (uint8_t)(x < 0 ? 0 : x > 255 ? 255 : x);
            }
    vv_volume_update_range(v);
    vv_mesh *m = extract(v, 127.5, 2);
    check_closed(m, 2);
    double a0 = 4 * VV_PI * 1e4, v0 = 4.0 / 3.0 * VV_PI * 1e6;
    double ea = vv_mesh_area(m) / a0 - 1, ev = vv_mesh_signed_volume(m) / v0 - 1;
    print_message("sphere256: %zu triangles (VTK flying edges: 377132), area %+.4f %% (VTK "
                  "+0.59 %%), volume %+.4f %% (VTK -0.011 %%)\n",
                  m->n_triangles, 100 * ea, 100 * ev);
    /* within VTK's own error on the same phantom (same edge interpolation) */
    assert_true(fabs(ea) <= 0.0060);
    assert_true(fabs(ev) <= 0.00012);
    assert_true(fabs((double)m->n_triangles / 377132.0 - 1) < 0.01);
    vv_mesh_free(m);
    vv_volume_free(v);
}

/* Torus around z: (sqrt(x^2+y^2) - R)^2 + z^2 = r^2; value r - distance to the core circle. */
static void
test_torus(void **state) {
    (void)state;
    const int n = 64;
    const double R = 18, r = 7, c = 31.7;
    vv_volume *v = new_volume(n, n, n, VV_F64);
    double *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double x = i - c, y = j - c, z = k - c * 0.98;
                double q = sqrt(x * x + y * y) - R;
                d[((size_t)k * n + j) * n + i] = r - sqrt(q * q + z * z);
            }
    vv_volume_update_range(v);
    vv_mesh *m = extract(v, 0.0, 2);
    check_closed(m, 0);
    double a0 = 4 * VV_PI * VV_PI * R * r, v0 = 2 * VV_PI * VV_PI * R * r * r;
    double ea = vv_mesh_area(m) / a0 - 1, ev = vv_mesh_signed_volume(m) / v0 - 1;
    print_message("torus: area %+.3f %%, volume %+.3f %%\n", 100 * ea, 100 * ev);
    assert_true(fabs(ea) < 0.01);
    assert_true(fabs(ev) < 0.01);
    vv_mesh_free(m);
    vv_volume_free(v);
}

/* Box: value = min over axes of (half - |x - c|); flat faces are exact. */
static void
test_box(void **state) {
    (void)state;
    const int n = 40;
    const double h[3] = {11.3, 7.6, 14.2}, c[3] = {19.4, 20.1, 19.7};
    vv_volume *v = new_volume(n, n, n, VV_F32);
    float *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double p[3] = {i, j, k}, m = 1e9;
                for (int a = 0; a < 3; a++) {
                    double e = h[a] - fabs(p[a] - c[a]);
                    m = e < m ? e : m;
                }
                d[((size_t)k * n + j) * n + i] = (float)m;
            }
    vv_volume_update_range(v);
    vv_mesh *m = extract(v, 0.0, 2);
    check_closed(m, 2);
    double v0 = 8 * h[0] * h[1] * h[2], a0 = 8 * (h[0] * h[1] + h[1] * h[2] + h[0] * h[2]);
    double ea = vv_mesh_area(m) / a0 - 1, ev = vv_mesh_signed_volume(m) / v0 - 1;
    print_message("box: area %+.3f %%, volume %+.3f %%\n", 100 * ea, 100 * ev);
    /* the faces are exact; only the cells along the 12 box edges cut the corner with a
     * chamfer of legs l1, l2 <= 1 cell: per unit of edge length the area lost is
     * l1 + l2 - hypot(l1, l2) <= 2 - sqrt 2 and the volume lost l1 l2 / 2 <= 1/2 */
    double edges = 8 * (h[0] + h[1] + h[2]);
    assert_true(ea < 0 && -ea * a0 < (2 - sqrt(2)) * edges);
    assert_true(ev < 0 && -ev * v0 < 0.5 * edges);
    vv_mesh_free(m);
    vv_volume_free(v);
}

static void
test_two_spheres_euler(void **state) {
    (void)state;
    const int n = 48;
    vv_volume *v = new_volume(n, n, n, VV_F32);
    float *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double a = 8 - sqrt((i - 13.2) * (i - 13.2) + (j - 20.) * (j - 20.) +
                                    (k - 24.) * (k - 24.));
                double b = 9 - sqrt((i - 34.) * (i - 34.) + (j - 27.) * (j - 27.) +
                                    (k - 22.5) * (k - 22.5));
                d[((size_t)k * n + j) * n + i] = (float)(a > b ? a : b);
            }
    vv_volume_update_range(v);
    vv_mesh *m = extract(v, 0.0, 3);
    check_closed(m, 4);
    vv_mesh_free(m);
    vv_volume_free(v);
}

/* Random fields: lots of ambiguous faces; closed after padding with an outside layer. */
static void
test_random_closed(void **state) {
    (void)state;
    uint64_t s = 12345;
    for (int trial = 0; trial < 6; trial++) {
        const int n = 18;
        vv_volume *v = new_volume(n, n, n, VV_F32);
        float *d = v->data;
        for (int k = 0; k < n; k++)
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    int border =
                        i == 0 || j == 0 || k == 0 || i == n - 1 || j == n - 1 || k == n - 1;
                    d[((size_t)k * n + j) * n + i] =
                        border ? -1.0f : (float)((double)(s >> 11) / 9007199254740992.0 - 0.5);
                }
        vv_volume_update_range(v);
        vv_mesh *m = extract(v, trial * 0.05, 2);
        vv_mesh_topology t;
        vt_ok(vv_mesh_topology_compute(m, &t));
        if (!t.closed || !t.oriented)
            fail_msg("random %d: closed %d oriented %d boundary %zu nonmanifold %zu", trial,
                     t.closed, t.oriented, t.n_boundary_edges, t.n_nonmanifold_edges);
        assert_true(vv_mesh_signed_volume(m) > 0);
        vv_mesh_free(m);
        vv_volume_free(v);
    }
}

static int
same_mesh(const vv_mesh *a, const vv_mesh *b) {
    if (a->n_vertices != b->n_vertices || a->n_triangles != b->n_triangles)
        return 0;
    if (memcmp(a->positions, b->positions, 3 * a->n_vertices * sizeof(float)) ||
        memcmp(a->triangles, b->triangles, 3 * a->n_triangles * sizeof(uint32_t)))
        return 0;
    if ((a->normals != NULL) != (b->normals != NULL))
        return 0;
    return !a->normals || !memcmp(a->normals, b->normals, 3 * a->n_vertices * sizeof(float));
}

static void
test_threads_and_grid(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(70, 25, 0.37);
    vv_mesh *ref = extract(v, 0.0, 1);
    for (int t = 2; t <= 5; t++) {
        vv_mesh *m = extract(v, 0.0, t);
        assert_true(same_mesh(ref, m));
        vv_mesh_free(m);
    }
    for (int block = 1; block <= 16; block *= 4) {
        vv_minmax_grid *g = NULL;
        vt_ok(vv_minmax_grid_build(&g, v, block));
        vv_isosurface_options o;
        vv_isosurface_options_init(&o);
        o.minmax = g;
        vv_mesh *m = NULL;
        vt_ok(vv_isosurface_extract(&m, v, 0.0, &o));
        assert_true(same_mesh(ref, m));
        vv_mesh_free(m);
        vv_minmax_grid_free(g);
    }
    vv_mesh_free(ref);
    vv_volume_free(v);
}

/* The same integer field in every voxel type gives the same mesh. */
static void
test_voxel_types(void **state) {
    (void)state;
    const int n = 30;
    const vv_voxel_type types[] = {VV_U8, VV_I8, VV_U16, VV_I16, VV_U32, VV_I32, VV_F32, VV_F64};
    const double offset[] = {0, -100, 0, -100, 0, -100, -100, -100};
    vv_mesh *ref = NULL;
    for (size_t q = 0; q < 8; q++) {
        vv_volume *v = new_volume(n, n, n, types[q]);
        for (int k = 0; k < n; k++)
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    double r = sqrt((i - 14.3) * (i - 14.3) + (j - 15.1) * (j - 15.1) +
                                    (k - 13.8) * (k - 13.8));
                    vv_volume_set(v, i, j, k, floor(100 + 10 * (10 - r)) + offset[q] + 20);
                }
        vv_volume_update_range(v);
        vv_isosurface_options o;
        vv_isosurface_options_init(&o);
        vv_mesh *m = NULL;
        vt_ok(vv_isosurface_extract(&m, v, 100.5 + offset[q] + 20, &o));
        check_closed(m, 2);
        if (!ref)
            ref = m;
        else {
            if (!same_mesh(ref, m))
                fail_msg("type %s differs", vv_voxel_type_name(types[q]));
            vv_mesh_free(m);
        }
        vv_volume_free(v);
    }
    vv_mesh_free(ref);
}

/* Anisotropic spacing and a rotated direction: the world-space sphere is recovered. */
static void
test_spacing_direction(void **state) {
    (void)state;
    const int nx = 60, ny = 32, nz = 18;
    const double sp[3] = {0.5, 1.0, 1.75};
    vv_volume *v = new_volume(nx, ny, nz, VV_F32);
    v->spacing[0] = sp[0];
    v->spacing[1] = sp[1];
    v->spacing[2] = sp[2];
    /* rotation by 30 degrees about z, columns are the axes */
    double ca = cos(VV_PI / 6), sa = sin(VV_PI / 6);
    double D[9] = {ca, -sa, 0, sa, ca, 0, 0, 0, 1};
    memcpy(v->direction, D, sizeof D);
    v->origin[0] = 10;
    v->origin[1] = -5;
    v->origin[2] = 3;
    vv_mat4 M = vv_volume_index_to_world(v);
    vv_vec3 c = vv_mat4_mul_point(M, vv_vec3_make(29.2, 15.8, 8.6));
    const double r = 11;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                vv_vec3 p = vv_mat4_mul_point(M, vv_vec3_make(i, j, k));
                vv_volume_set(v, i, j, k, r - vv_vec3_length(vv_vec3_sub(p, c)));
            }
    vv_volume_update_range(v);
    vv_mesh *m = extract(v, 0.0, 2);
    check_closed(m, 2);
    double ea = vv_mesh_area(m) / (4 * VV_PI * r * r) - 1,
           ev = vv_mesh_signed_volume(m) / (4.0 / 3 * VV_PI * r * r * r) - 1;
    print_message("anisotropic rotated sphere: area %+.3f %%, volume %+.3f %%\n", 100 * ea,
                  100 * ev);
    assert_true(fabs(ea) < 0.02 && fabs(ev) < 0.02);
    double worst = 1, rmax = 0;
    for (size_t i = 0; i < m->n_vertices; i++) {
        vv_vec3 p = vv_mesh_vertex(m, i), d = vv_vec3_sub(p, c);
        const float *nn = m->normals + 3 * i;
        double l = vv_vec3_length(d);
        double dt = (d.x * nn[0] + d.y * nn[1] + d.z * nn[2]) / l;
        worst = dt < worst ? dt : worst;
        rmax = fmax(rmax, fabs(l - r));
    }
    print_message("   worst normal . radial %.4f, max |radius error| %.3f\n", worst, rmax);
    assert_true(worst > 0.97);
    assert_true(rmax < 0.2);
    vv_mesh_free(m);
    vv_volume_free(v);
}

static void
test_roi(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(50, 14, 0);
    vv_mesh *whole = extract(v, 0.0, 2);
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    /* a region that holds the whole sphere: same surface */
    for (int a = 0; a < 3; a++) {
        o.roi_min[a] = 8;
        o.roi_max[a] = 42;
    }
    vv_mesh *m = NULL;
    vt_ok(vv_isosurface_extract(&m, v, 0.0, &o));
    assert_true(same_mesh(whole, m) || (m->n_triangles == whole->n_triangles &&
                                        fabs(vv_mesh_area(m) - vv_mesh_area(whole)) < 1e-6));
    check_closed(m, 2);
    vv_mesh_free(m);
    /* a region cutting it at i <= 24.5: an open hemisphere-like cap, all inside the region */
    o.roi_min[0] = 0;
    o.roi_max[0] = 24;
    vt_ok(vv_isosurface_extract(&m, v, 0.0, &o));
    vv_mesh_topology t;
    vt_ok(vv_mesh_topology_compute(m, &t));
    assert_false(t.closed);
    assert_true(t.oriented);
    assert_true(t.n_boundary_edges > 0);
    for (size_t i = 0; i < m->n_vertices; i++)
        assert_true(m->positions[3 * i] <= 24.0f);
    double half = 0.5 * vv_mesh_area(whole);
    assert_true(fabs(vv_mesh_area(m) / half - 1) < 0.05);
    vv_mesh_free(m);
    vv_mesh_free(whole);
    /* bad regions */
    o.roi_max[0] = 50;
    vt_err(vv_isosurface_extract(&m, v, 0.0, &o));
    o.roi_max[0] = 24;
    o.roi_min[1] = 30;
    o.roi_max[1] = 29;
    vt_err(vv_isosurface_extract(&m, v, 0.0, &o));
    vv_volume_free(v);
}

static void
test_cut_plane(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(50, 15, 0.1);
    vv_mesh *whole = extract(v, 0.0, 2);
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.n_cut_planes = 1;
    const double c = 24.6;
    o.cut_planes[0].point = vv_vec3_make(c, c, c);
    o.cut_planes[0].normal = vv_vec3_normalize(vv_vec3_make(1, 1, 0.3));
    vv_mesh *m = NULL;
    vt_ok(vv_isosurface_extract(&m, v, 0.0, &o));
    vv_mesh_topology t;
    vt_ok(vv_mesh_topology_compute(m, &t));
    assert_false(t.closed);
    assert_true(t.oriented);
    assert_int_equal(t.n_nonmanifold_edges, 0);
    assert_int_equal(t.euler, 1); /* a disc */
    assert_int_equal(t.n_vertices_used, m->n_vertices);
    for (size_t i = 0; i < m->n_vertices; i++) {
        vv_vec3 p = vv_mesh_vertex(m, i);
        assert_true(vv_vec3_dot(vv_vec3_sub(p, o.cut_planes[0].point), o.cut_planes[0].normal) >
                    -1e-4);
    }
    double ratio = vv_mesh_area(m) / vv_mesh_area(whole);
    print_message("cut through the centre keeps %.4f of the area\n", ratio);
    assert_true(fabs(ratio - 0.5) < 0.01);
    vv_mesh_free(m);
    /* zero normal */
    o.cut_planes[0].normal = vv_vec3_make(0, 0, 0);
    vt_err(vv_isosurface_extract(&m, v, 0.0, &o));
    vv_mesh_free(whole);
    vv_volume_free(v);
}

static void
test_scalars_and_no_normals(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(30, 9, 0);
    vv_volume *s = new_volume(30, 30, 30, VV_F32);
    float *d = s->data;
    for (int k = 0; k < 30; k++)
        for (int j = 0; j < 30; j++)
            for (int i = 0; i < 30; i++)
                d[(k * 30 + j) * 30 + i] = (float)(2 * i + 3 * k);
    vv_volume_update_range(s);
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.compute_normals = 0;
    o.scalar_volume = s;
    vv_mesh *m = NULL;
    vt_ok(vv_isosurface_extract(&m, v, 0.0, &o));
    assert_null(m->normals);
    assert_non_null(m->scalars);
    for (size_t i = 0; i < m->n_vertices; i++) {
        const float *p = m->positions + 3 * i;
        assert_near(m->scalars[i], 2 * p[0] + 3 * p[2], 1e-3);
    }
    vv_mesh_free(m);
    vv_volume *bad = new_volume(30, 30, 29, VV_U8);
    o.scalar_volume = bad;
    vt_err(vv_isosurface_extract(&m, v, 0.0, &o));
    vv_volume_free(bad);
    vv_volume_free(s);
    vv_volume_free(v);
}

static void
test_nan_and_edge_cases(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(24, 7, 0);
    float *d = v->data;
    for (int i = 0; i < 24 * 24; i++)
        d[i] = NAN;                       /* first slice */
    d[24 * 24 * 12 + 24 * 12 + 12] = NAN; /* a hole in the middle (inside) */
    vv_mesh *m = extract(v, 0.0, 2);
    vv_mesh_topology t;
    vt_ok(vv_mesh_topology_compute(m, &t));
    assert_true(t.closed && t.oriented);
    for (size_t i = 0; i < 3 * m->n_vertices; i++)
        assert_true(isfinite(m->positions[i]) && isfinite(m->normals[i]));
    vv_mesh_free(m);
    /* isovalue outside the range: empty mesh, no error */
    m = extract(v, 1e6, 1);
    assert_int_equal(m->n_triangles, 0);
    vv_mesh_free(m);
    vv_volume_free(v);
    /* one-voxel-thick volume: no cells */
    v = new_volume(10, 10, 1, VV_U8);
    m = extract(v, 0.5, 1);
    assert_int_equal(m->n_triangles, 0);
    vv_mesh_free(m);
    vv_volume_free(v);
    /* wide rows (more than one 64-bit word, not a multiple of 64) */
    v = new_volume(131, 5, 5, VV_U8);
    for (int i = 1; i < 130; i++)
        vv_volume_set(v, i, 2, 2, 200);
    vv_volume_update_range(v);
    m = extract(v, 100, 2);
    check_closed(m, 2);
    vv_mesh_free(m);
    vv_volume_free(v);
}

static void
test_bad_input(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(10, 3, 0);
    vv_mesh *m = NULL;
    vt_err(vv_isosurface_extract(NULL, v, 0, NULL));
    vt_err(vv_isosurface_extract(&m, NULL, 0, NULL));
    vt_err(vv_isosurface_extract(&m, v, NAN, NULL));
    vt_err(vv_isosurface_extract(&m, v, INFINITY, NULL));
    assert_null(m);
    vv_volume_free(v);
}

static int
cancel_cb(void *user, double f) {
    (void)f;
    return ++*(int *)user >= 2;
}

static void
test_cancel(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(40, 12, 0);
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    int calls = 0;
    o.progress.fn = cancel_cb;
    o.progress.user = &calls;
    vv_mesh *m = NULL;
    vv_status s = vv_isosurface_extract(&m, v, 0.0, &o);
    assert_int_equal(s, VV_ERR_CANCELLED);
    assert_null(m);
    vv_volume_free(v);
}

static void
test_mesh_files(void **state) {
    (void)state;
    vv_volume *v = sphere_volume(30, 10, 0.3);
    vv_mesh *m = extract(v, 0.0, 2);
    const char *ext[] = {"ply", "obj", "stl"};
    for (int e = 0; e < 3; e++) {
        char path[512];
        snprintf(path, sizeof path, "%s/sphere.%s", vt_outdir("surface_mc"), ext[e]);
        vt_ok(vv_mesh_save(m, path));
        vv_mesh *r = NULL;
        vt_ok(vv_mesh_load(&r, path));
        assert_int_equal(r->n_triangles, m->n_triangles);
        assert_near(vv_mesh_area(r), vv_mesh_area(m), 1e-3 * vv_mesh_area(m));
        assert_near(vv_mesh_signed_volume(r), vv_mesh_signed_volume(m),
                    1e-3 * vv_mesh_signed_volume(m));
        check_closed(r, 2);
        vv_mesh_free(r);
    }
    vv_mesh_free(m);
    vv_volume_free(v);
}

/*
 * The real CT head at 300 HU against VTK 9.1 (bench_vtk.py ct_head.nrrd --iso 300, run
 * 2026-11-21 on the project machine): vtkFlyingEdges3D 662406 triangles (332154 points),
 * vtkMassProperties on that surface area 291104.7 mm^2; the surface is open (2318 boundary
 * edges, cut by the volume's first and last slices).
 */
static void
test_ct_head(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    vv_mesh *m = extract(v, 300, 2);
    vv_mesh_topology t;
    vt_ok(vv_mesh_topology_compute(m, &t));
    double area = vv_mesh_area(m);
    print_message("ct_head iso 300: %zu vertices, %zu triangles (VTK 662406), area %.1f (VTK "
                  "291104.7), boundary edges %zu (VTK 2318), non-manifold %zu, oriented %d\n",
                  m->n_vertices, m->n_triangles, area, t.n_boundary_edges, t.n_nonmanifold_edges,
                  t.oriented);
    assert_true(fabs((double)m->n_triangles / 662406.0 - 1) < 0.01);
    assert_true(fabs(area / 291104.7 - 1) < 0.01);
    assert_int_equal(t.n_nonmanifold_edges, 0);
    assert_true(t.oriented);
    /* every boundary edge lies on the volume's faces */
    vv_mesh_free(m);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tables),
        cmocka_unit_test(test_every_case_closed),
        cmocka_unit_test(test_spheres),
        cmocka_unit_test(test_sphere_phantom_vs_vtk),
        cmocka_unit_test(test_torus),
        cmocka_unit_test(test_box),
        cmocka_unit_test(test_two_spheres_euler),
        cmocka_unit_test(test_random_closed),
        cmocka_unit_test(test_threads_and_grid),
        cmocka_unit_test(test_voxel_types),
        cmocka_unit_test(test_spacing_direction),
        cmocka_unit_test(test_roi),
        cmocka_unit_test(test_cut_plane),
        cmocka_unit_test(test_scalars_and_no_normals),
        cmocka_unit_test(test_nan_and_edge_cases),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_mesh_files),
        cmocka_unit_test(test_ct_head),
    };
    return vt_run_tests(tests, NULL, NULL);
}
