/*
 * Tests of the Measurement component (src/measure): histograms (counts by
 * hand, regions, cut planes, the PNG plot), isosurface area and volume by
 * Marching Cubes and by voxel counting on analytic spheres (whole, cut by
 * the volume boundary and by a region), surface tracking of two disjoint
 * spheres, the real CT head against VTK, distances, mesh volume and the
 * distance between meshes, and bad input.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static vv_volume *
new_volume(int nx, int ny, int nz, vv_voxel_type t) {
    vv_volume *v = NULL;
    const int dims[3] = {nx, ny, nz};
    vt_ok(vv_volume_new(&v, dims, t));
    return v;
}

/* value = max over spheres (r_s - |x - c_s|), f32, spacing sp */
static vv_volume *
spheres(int n, const double (*c)[3], const double *r, int ns, const double sp[3]) {
    vv_volume *v = new_volume(n, n, n, VV_F32);
    memcpy(v->spacing, sp, 3 * sizeof(double));
    float *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double best = -1e9, p[3] = {i * sp[0], j * sp[1], k * sp[2]};
                for (int s = 0; s < ns; s++) {
                    double dx = p[0] - c[s][0], dy = p[1] - c[s][1], dz = p[2] - c[s][2];
                    double x = r[s] - sqrt(dx * dx + dy * dy + dz * dz);
                    best = x > best ? x : best;
                }
                d[((size_t)k * n + j) * n + i] = (float)best;
            }
    vv_volume_update_range(v);
    return v;
}

static void
test_histogram(void **state) {
    (void)state;
    vv_volume *v = new_volume(10, 4, 3, VV_U8);
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 10; i++)
                vv_volume_set(v, i, j, k, i * 10); /* 0..90, 12 voxels each */
    vv_volume_update_range(v);
    vv_histogram *h = NULL;
    vt_ok(vv_measure_histogram(&h, v, 10, 0, 100, NULL));
    for (int b = 0; b < 10; b++)
        assert_int_equal(h->counts[b], 12);
    assert_int_equal(h->total, 120);
    assert_near(h->mean, 45, 1e-12);
    assert_near(h->sd, sqrt(825.0), 1e-9);
    vv_histogram_free(h);
    /* own range: 0..90, the value 90 in the last bin */
    vt_ok(vv_measure_histogram(&h, v, 3, 0, 0, NULL));
    assert_near(h->lo, 0, 0);
    assert_near(h->hi, 90, 0);
    assert_int_equal(h->counts[0], 36); /* 0,10,20 */
    assert_int_equal(h->counts[1], 36); /* 30,40,50 */
    assert_int_equal(h->counts[2], 48); /* 60,70,80,90 */
    vv_histogram_free(h);
    /* a region and a cut plane keeping x >= 4.5 */
    vv_region r;
    vv_region_init(&r);
    r.roi_min[0] = 2;
    r.roi_min[1] = 0;
    r.roi_min[2] = 1;
    r.roi_max[0] = 9;
    r.roi_max[1] = 3;
    r.roi_max[2] = 2;
    vt_ok(vv_measure_histogram(&h, v, 10, 0, 100, &r));
    assert_int_equal(h->total, 8 * 4 * 2);
    assert_int_equal(h->counts[1], 0);
    assert_int_equal(h->counts[2], 8);
    vv_histogram_free(h);
    r.n_cut_planes = 1;
    r.cut_planes[0].point = vv_vec3_make(4.5, 0, 0);
    r.cut_planes[0].normal = vv_vec3_make(1, 0, 0);
    vt_ok(vv_measure_histogram(&h, v, 10, 0, 50, &r));
    assert_int_equal(h->total, 5 * 4 * 2);
    assert_int_equal(h->counts[4], 0);
    assert_int_equal(h->counts[9], 8);   /* 50 = hi: the last bin */
    assert_int_equal(h->outside, 4 * 8); /* 60..90 */
    vv_histogram_free(h);
    /* bad input */
    vt_err(vv_measure_histogram(&h, v, 0, 0, 1, NULL));
    vt_err(vv_measure_histogram(&h, v, 10, NAN, 1, NULL));
    r.roi_max[0] = 10;
    vt_err(vv_measure_histogram(&h, v, 10, 0, 1, &r));
    vv_volume_free(v);
}

static void
test_histogram_plot(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    vv_histogram *h = NULL;
    vt_ok(vv_measure_histogram(&h, v, 128, 0, 0, NULL));
    assert_int_equal(h->total, vv_volume_voxel_count(v));
    char path[512];
    snprintf(path, sizeof path, "%s/ct_head_histogram.png", vt_outdir("measure"));
    vt_ok(vv_histogram_plot_png(h, path, 800, 500, "ct_head.nrrd", "value (HU)", 1));
    vv_image *img = NULL;
    vt_ok(vv_image_read_png(&img, path));
    assert_int_equal(img->width, 800);
    assert_int_equal(img->height, 500);
    vv_image_free(img);
    vt_err(vv_histogram_plot_png(h, path, 10, 500, NULL, NULL, 0));
    vt_err(vv_histogram_plot_png(h, "/nonexistent-dir/x.png", 800, 500, NULL, NULL, 0));
    vv_histogram_free(h);
    vv_volume_free(v);
}

static void
test_sphere_mc_and_voxels(void **state) {
    (void)state;
    const double c[1][3] = {{20.3, 19.8, 20.1}}, r[1] = {14}, sp[3] = {1, 1, 1};
    vv_volume *v = spheres(41, c, r, 1, sp);
    vv_isosurface_measure m;
    vv_isosurface_measure_options o;
    vv_isosurface_measure_options_init(&o);
    vt_ok(vv_measure_isosurface(&m, v, 0.0, &o));
    double a0 = 4 * VV_PI * r[0] * r[0], v0 = 4.0 / 3 * VV_PI * r[0] * r[0] * r[0];
    print_message("MC: area %+.3f %%, volume %+.3f %%, cut %g\n", 100 * (m.area / a0 - 1),
                  100 * (m.volume / v0 - 1), m.cut_area);
    assert_true(fabs(m.area / a0 - 1) < 0.004);
    assert_true(fabs(m.volume / v0 - 1) < 0.006);
    assert_near(m.cut_area, 0, 0);
    /* the closed-surface volume is the mesh's signed volume */
    vv_mesh *mesh = NULL;
    vt_ok(vv_isosurface_extract(&mesh, v, 0.0, NULL));
    assert_near(m.volume, vv_mesh_signed_volume(mesh), 1e-6 * v0);
    vv_mesh_free(mesh);
    o.method = VV_MEASURE_VOXEL;
    vt_ok(vv_measure_isosurface(&m, v, 0.0, &o));
    print_message("voxels: %llu, volume %+.3f %%, face area / true %.3f (bias %.2f)\n",
                  (unsigned long long)m.voxels, 100 * (m.volume / v0 - 1), m.area / a0,
                  m.area_bias);
    assert_true(fabs(m.volume / v0 - 1) < 0.01);
    assert_true(fabs(m.area / a0 / 1.5 - 1) < 0.08);
    vv_volume_free(v);
}

/* Volume of the part of the ball (c, r) with x >= x0 and y <= y1, by integrating chords
 * along z over a fine x-y grid. */
static double
part_volume(const double c[3], double r, double x0, double y1) {
    double ref = 0, step = 0.02;
    for (double x = x0; x < c[0] + r; x += step)
        for (double y = c[1] - r; y < y1; y += step) {
            double xm = x + step / 2, ym = y + step / 2;
            double q = r * r - (xm - c[0]) * (xm - c[0]) - (ym - c[1]) * (ym - c[1]);
            if (q > 0 && ym <= y1)
                ref += 2 * sqrt(q) * step * step;
        }
    return ref;
}

/* A sphere cut by the volume boundary at x = 0 (and by a region): the capped divergence
 * volume is the volume of the part inside, a sphere minus a cap. */
static void
test_cut_sphere_volume(void **state) {
    (void)state;
    const double sp[3] = {0.7, 1.1, 0.9};
    const double c[1][3] = {{5.2, 22.1, 21.7}}, r[1] = {14.5};
    vv_volume *v = spheres(48, c, r, 1, sp);
    const double h = r[0] - c[0][0]; /* cap height beyond x = 0 */
    const double vin = 4.0 / 3 * VV_PI * pow(r[0], 3) - VV_PI * h * h * (3 * r[0] - h) / 3;
    const double disc = VV_PI * (r[0] * r[0] - c[0][0] * c[0][0]);
    vv_isosurface_measure m;
    vv_isosurface_measure_options o;
    vv_isosurface_measure_options_init(&o);
    vt_ok(vv_measure_isosurface(&m, v, 0.0, &o));
    print_message("cut by x = 0: volume %+.3f %%, cap %+.3f %%\n", 100 * (m.volume / vin - 1),
                  100 * (m.cut_area / disc - 1));
    assert_true(fabs(m.volume / vin - 1) < 0.01);
    assert_true(fabs(m.cut_area / disc - 1) < 0.02);
    /* the uncapped mesh volume is far off (depends on the origin): the caps matter */
    vv_mesh *mesh = NULL;
    vt_ok(vv_isosurface_extract(&mesh, v, 0.0, NULL));
    assert_true(fabs(vv_mesh_signed_volume(mesh) / vin - 1) > 0.05 || fabs(m.cut_area) > 0);
    vv_mesh_free(mesh);
    /* a region cutting at y <= 22.1 / 1.1 = voxel 20 (the sphere's centre plane): half */
    o.region.roi_min[0] = o.region.roi_min[1] = o.region.roi_min[2] = 0;
    o.region.roi_max[0] = 47;
    o.region.roi_max[1] = 20;
    o.region.roi_max[2] = 47;
    vt_ok(vv_measure_isosurface(&m, v, 0.0, &o));
    double yc = 20 * 1.1; /* the region's face, world y */
    /* volume of the part with x >= x0 and y <= y1: numerical reference by fine sampling */
    double ref = part_volume(c[0], r[0], 0, yc);
    print_message("region y <= %g: volume %.1f, reference %.1f (%+.3f %%)\n", yc, m.volume, ref,
                  100 * (m.volume / ref - 1));
    assert_true(fabs(m.volume / ref - 1) < 0.01);
    /* voxel counting counts whole voxel boxes, which reach half a voxel past the boundary
     * voxels: compare with that region */
    o.method = VV_MEASURE_VOXEL;
    vt_ok(vv_measure_isosurface(&m, v, 0.0, &o));
    double refv = part_volume(c[0], r[0], -0.5 * sp[0], yc + 0.5 * sp[1]);
    print_message("voxels: volume %.1f, reference %.1f (%+.3f %%)\n", m.volume, refv,
                  100 * (m.volume / refv - 1));
    assert_true(fabs(m.volume / refv - 1) < 0.01);
    assert_true(m.cut_area > 0);
    vv_volume_free(v);
}

static void
test_surface_tracking(void **state) {
    (void)state;
    const double c[2][3] = {{13.2, 14.1, 15.3}, {33.4, 31.2, 30.6}}, r[2] = {8.5, 11.2},
                 sp[3] = {1, 1, 1};
    vv_volume *v = spheres(46, c, r, 2, sp);
    vv_isosurface_measure whole, m[2], vx[2];
    vv_isosurface_measure_options o;
    vv_isosurface_measure_options_init(&o);
    vt_ok(vv_measure_isosurface(&whole, v, 0.0, &o));
    for (int s = 0; s < 2; s++) {
        o.method = VV_MEASURE_MC;
        o.has_seed = 1;
        /* a seed on the surface, not on a voxel: the top of the sphere */
        o.seed[0] = c[s][0];
        o.seed[1] = c[s][1];
        o.seed[2] = c[s][2] + r[s];
        vt_ok(vv_measure_isosurface(&m[s], v, 0.0, &o));
        o.method = VV_MEASURE_VOXEL;
        vt_ok(vv_measure_isosurface(&vx[s], v, 0.0, &o));
        double a0 = 4 * VV_PI * r[s] * r[s], v0 = 4.0 / 3 * VV_PI * pow(r[s], 3);
        print_message("sphere %d (seed voxel %d %d %d): MC area %+.3f %% volume %+.3f %%, "
                      "voxels volume %+.3f %%\n",
                      s, m[s].seed_voxel[0], m[s].seed_voxel[1], m[s].seed_voxel[2],
                      100 * (m[s].area / a0 - 1), 100 * (m[s].volume / v0 - 1),
                      100 * (vx[s].volume / v0 - 1));
        assert_true(fabs(m[s].area / a0 - 1) < 0.01);
        assert_true(fabs(m[s].volume / v0 - 1) < 0.01);
        assert_true(fabs(vx[s].volume / v0 - 1) < 0.02);
        assert_int_equal(m[s].voxels, vx[s].voxels);
    }
    /* the sections add up to the whole */
    assert_near(m[0].area + m[1].area, whole.area, 1e-6 * whole.area);
    assert_near(m[0].volume + m[1].volume, whole.volume, 1e-6 * whole.volume);
    assert_int_equal(m[0].voxels + m[1].voxels, whole.voxels);
    /* bad seeds */
    o.seed[0] = -3;
    vt_err(vv_measure_isosurface(&m[0], v, 0.0, &o));
    o.seed[0] = 2;
    o.seed[1] = 2;
    o.seed[2] = 40; /* far from both */
    vt_err(vv_measure_isosurface(&m[0], v, 0.0, &o));
    vv_volume_free(v);
}

/*
 * The CT head at 300 HU against VTK 9.1 (bench_vtk.py ct_head.nrrd --iso 300 on the project
 * machine, 2026-11-21, and vtkMassProperties on its vtkFlyingEdges3D surface): area
 * 291104.7 mm^2. The surface is open (cut by the first and last slices), so
 * vtkMassProperties' Volume (512704.9, an average of three projections) is not a volume;
 * its x projection GetVolumeX() = 607822.4 mm^3 is, because the caps lie in z planes and
 * add nothing to the x flux. Voxel counting, as numpy computes it from the same file:
 * count(arr >= 300) * 0.9570312^2 * 1.5 = 606030.2 mm^3.
 */
static void
test_ct_head(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    vv_isosurface_measure m;
    vv_isosurface_measure_options o;
    vv_isosurface_measure_options_init(&o);
    vt_ok(vv_measure_isosurface(&m, v, 300, &o));
    print_message("MC: area %.1f mm^2 (VTK 291104.7), volume %.1f mm^3 (VTK x-projection "
                  "607822.4), caps %.1f mm^2, %zu triangles\n",
                  m.area, m.volume, m.cut_area, m.n_triangles);
    assert_true(fabs(m.area / 291104.7 - 1) < 0.01);
    assert_true(fabs(m.volume / 607822.4 - 1) < 0.01);
    assert_true(m.cut_area > 0);
    o.method = VV_MEASURE_VOXEL;
    vt_ok(vv_measure_isosurface(&m, v, 300, &o));
    print_message("voxels: %llu, volume %.1f mm^3 (numpy 606030.2)\n", (unsigned long long)m.voxels,
                  m.volume);
    assert_near(m.volume, 606030.2371978697, 0.01);
    /* isovalue outside the range */
    o.method = VV_MEASURE_MC;
    vt_err(vv_measure_isosurface(&m, v, 5000, &o));
    vt_err(vv_measure_isosurface(&m, v, -1024, &o));
    /* cut planes need voxel counting */
    o.region.n_cut_planes = 1;
    o.region.cut_planes[0].normal = vv_vec3_make(0, 0, 1);
    assert_int_equal(vv_measure_isosurface(&m, v, 300, &o), VV_ERR_UNSUPPORTED);
    vv_volume_free(v);
}

static void
test_distance(void **state) {
    (void)state;
    vv_volume *v = new_volume(4, 4, 4, VV_U8);
    v->spacing[0] = 2;
    v->spacing[2] = 3;
    v->origin[0] = 100;
    double d;
    vt_ok(vv_measure_distance(v, vv_vec3_make(0, 0, 0), 1, vv_vec3_make(1, 0, 1), 1, &d));
    assert_near(d, sqrt(13.0), 1e-12);
    vt_ok(vv_measure_distance(v, vv_vec3_make(0, 0, 0), 1, vv_vec3_make(100, 4, 0), 0, &d));
    assert_near(d, 4, 1e-12);
    vt_ok(vv_measure_distance(NULL, vv_vec3_make(0, 0, 0), 0, vv_vec3_make(3, 4, 0), 0, &d));
    assert_near(d, 5, 1e-12);
    vt_err(vv_measure_distance(NULL, vv_vec3_make(0, 0, 0), 1, vv_vec3_make(3, 4, 0), 0, &d));
    vt_err(vv_measure_distance(v, vv_vec3_make(NAN, 0, 0), 0, vv_vec3_make(3, 4, 0), 0, &d));
    vv_volume_free(v);
}

static vv_mesh *
sphere_mesh(double cx, double cy, double cz, double r) {
    const double c[1][3] = {{cx - 0, cy, cz}}, rr[1] = {r}, sp[3] = {1, 1, 1};
    (void)c;
    int n = (int)(2 * r) + 6;
    const double cc[1][3] = {{0.5 * (n - 1) + 0.13, 0.5 * (n - 1) - 0.21, 0.5 * (n - 1)}};
    vv_volume *v = spheres(n, cc, rr, 1, sp);
    vv_mesh *m = NULL;
    vt_ok(vv_isosurface_extract(&m, v, 0.0, NULL));
    vv_mesh_transform(m,
                      vv_mat4_translate(vv_vec3_make(cx - cc[0][0], cy - cc[0][1], cz - cc[0][2])));
    vv_volume_free(v);
    return m;
}

static double
brute_distance(const vv_mesh *a, const vv_mesh *b) {
    double best = INFINITY; /* vertex-vertex: an upper bound for the exact distance */
    for (size_t i = 0; i < a->n_vertices; i++)
        for (size_t j = 0; j < b->n_vertices; j++) {
            vv_vec3 d = vv_vec3_sub(vv_mesh_vertex(a, i), vv_mesh_vertex(b, j));
            best = fmin(best, vv_vec3_length(d));
        }
    return best;
}

static void
test_mesh_measures(void **state) {
    (void)state;
    vv_mesh *a = sphere_mesh(0, 0, 0, 6), *b = sphere_mesh(15, 3, -2, 5);
    double vol;
    vt_ok(vv_measure_mesh_volume(a, &vol));
    assert_true(fabs(vol / (4.0 / 3 * VV_PI * 216) - 1) < 0.05);
    double d;
    vv_vec3 pa, pb;
    vt_ok(vv_measure_mesh_distance(a, b, 2, &d, &pa, &pb));
    double expect = sqrt(15 * 15 + 9 + 4) - 11;
    double bf = brute_distance(a, b);
    print_message("mesh distance %.4f (spheres %.4f, vertex pairs %.4f)\n", d, expect, bf);
    assert_true(d <= bf + 1e-9);
    assert_true(fabs(d - expect) < 0.15);
    assert_near(vv_vec3_length(vv_vec3_sub(pa, pb)), d, 1e-6);
    /* same answer with one thread and swapped */
    double d1, d2;
    vt_ok(vv_measure_mesh_distance(a, b, 1, &d1, NULL, NULL));
    vt_ok(vv_measure_mesh_distance(b, a, 3, &d2, NULL, NULL));
    assert_near(d1, d, 1e-12);
    assert_near(d2, d, 1e-9);
    /* overlapping meshes: 0 */
    vv_mesh *c = sphere_mesh(7, 0, 0, 5);
    vt_ok(vv_measure_mesh_distance(a, c, 2, &d, NULL, NULL));
    assert_near(d, 0, 0);
    /* an open mesh has no volume */
    vv_mesh *open = NULL;
    vt_ok(vv_mesh_new(&open));
    uint32_t i0, i1, i2;
    vt_ok(vv_mesh_add_vertex(open, vv_vec3_make(0, 0, 0), &i0));
    vt_ok(vv_mesh_add_vertex(open, vv_vec3_make(1, 0, 0), &i1));
    vt_ok(vv_mesh_add_vertex(open, vv_vec3_make(0, 1, 0), &i2));
    vt_ok(vv_mesh_add_triangle(open, i0, i1, i2));
    vt_err(vv_measure_mesh_volume(open, &vol));
    /* the real bunny (open: holes in the base) */
    vv_mesh *bunny = NULL;
    vt_ok(vv_mesh_load(&bunny, vt_data("meshes/bunny.ply")));
    vt_err(vv_measure_mesh_volume(bunny, &vol));
    print_message("bunny: %s\n", vv_error_message());
    vt_ok(vv_measure_mesh_distance(bunny, open, 2, &d, NULL, NULL));
    assert_true(d >= 0);
    vv_mesh_free(bunny);
    vv_mesh_free(open);
    vv_mesh_free(c);
    vv_mesh_free(a);
    vv_mesh_free(b);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_histogram),
        cmocka_unit_test(test_histogram_plot),
        cmocka_unit_test(test_sphere_mc_and_voxels),
        cmocka_unit_test(test_cut_sphere_volume),
        cmocka_unit_test(test_surface_tracking),
        cmocka_unit_test(test_ct_head),
        cmocka_unit_test(test_distance),
        cmocka_unit_test(test_mesh_measures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
