/*
 * Volume-sampled voxelization (src/modeling): sampling-kernel tables against their
 * closed-form integrals; the 0.5-level volume and the surface area of
 * voxelized solids against analytic values (sphere r = 5..100, boxes with
 * and without rounded edges, torus, cylinder, cone, ellipsoid, extrusion,
 * thick polygon, revolution, helix sweep, transforms); CSG identities;
 * closed and open meshes; bad input.
 *
 * Measures: measure_volume_k from the closed-form kernel integrals,
 * independently of the library's tables, and Marching Cubes
 * (vv_measure_isosurface at the 0.5 level).
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VT_PI 3.14159265358979323846

typedef struct measure {
    double volume, area;
} measure;

static double
invert_density(vv_sampling_kernel_kind k, double R, double rho) {
    double lo = -R, hi = R;
    for (int it = 0; it < 50; it++) {
        double mid = 0.5 * (lo + hi);
        if (vv_sampling_kernel_integral(k, R, mid) > rho)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

/*
 * Volume inside the 0.5 level and area of an f32 density volume made with
 * kernel k of radius R (isotropic spacing h), from the closed-form kernel
 * integral, not the library's tables:
 *  - each voxel's signed distance d (voxels) is recovered by inverting the
 *    integral; the sum of the inside fractions clamp(1/2 - d, 0, 1) is the
 *    volume up to a bias of A'(0) / 24 (A(s): area of the level set at
 *    distance s), which is removed with A'(0) = integral of the mean
 *    curvature sum over the surface = sum of laplacian(d) |grad rho|;
 *  - the area is the coarea formula: the integral of |grad rho| (central
 *    differences), the density falling from 1 to 0 across the surface.
 */
static measure
measure_volume_k(const vv_volume *v, vv_sampling_kernel_kind k, double R) {
    const float *rho = v->data;
    int nx = v->dims[0], ny = v->dims[1], nz = v->dims[2];
    size_t n = vv_volume_voxel_count(v), sy = (size_t)nx, sz = (size_t)nx * ny;
    double h = v->spacing[0], vol = 0, area = 0, curv = 0;
    enum { NL = 1 << 16 };
    static double inv[NL + 1];
    static vv_sampling_kernel_kind inv_k = (vv_sampling_kernel_kind)-1;
    static double inv_r = 0;
    double *d = malloc(n * sizeof *d);
    assert_non_null(d);
    if (inv_k != k || inv_r != R) {
        for (int i = 0; i <= NL; i++)
            inv[i] = invert_density(k, R, (double)i / NL);
        inv_k = k;
        inv_r = R;
    }
    for (size_t i = 0; i < n; i++) {
        double r = rho[i];
        if (r >= 1.0) {
            d[i] = -INFINITY;
            vol += 1;
        } else if (r <= 0.0) {
            d[i] = INFINITY;
        } else {
            double t = r * NL;
            int a = (int)t;
            d[i] = a >= NL ? inv[NL] : inv[a] + (t - a) * (inv[a + 1] - inv[a]);
            double f = 0.5 - d[i];
            vol += f < 0 ? 0 : (f > 1 ? 1 : f);
        }
    }
    for (int z = 1; z < nz - 1; z++)
        for (int y = 1; y < ny - 1; y++)
            for (int x = 1; x < nx - 1; x++) {
                size_t i = (size_t)z * sz + (size_t)y * sy + (size_t)x;
                double gx = 0.5 * (rho[i + 1] - rho[i - 1]);
                double gy = 0.5 * (rho[i + sy] - rho[i - sy]);
                double gz = 0.5 * (rho[i + sz] - rho[i - sz]);
                double g = sqrt(gx * gx + gy * gy + gz * gz);
                area += g;
                double lap =
                    d[i + 1] + d[i - 1] + d[i + sy] + d[i - sy] + d[i + sz] + d[i - sz] - 6 * d[i];
                if (isfinite(lap))
                    curv += lap * g;
            }
    free(d);
    return (measure){(vol - curv / 24.0) * h * h * h, area * h * h};
}

static measure
measure_volume(const vv_volume *v) {
    return measure_volume_k(v, VV_SAMPLING_KERNEL_TENT, 1.5);
}

/* The 0.5-level volume and area by Marching Cubes (vv_measure_isosurface,
 * the surface-extraction component: an independent measure). */
static measure
measure_mc(const vv_volume *v) {
    vv_isosurface_measure_options mo;
    vv_isosurface_measure_options_init(&mo);
    vv_isosurface_measure r;
    double iso = v->type == VV_U8 ? 127.5 : 0.5;
    vt_ok(vv_measure_isosurface(&r, v, iso, &mo));
    return (measure){r.volume, r.area};
}

static void
opts_f32(vv_voxelize_options *o, vv_sampling_kernel_kind k, double R) {
    vv_voxelize_options_init(o);
    o->type = VV_F32;
    o->kernel = k;
    o->radius = R;
}

static vv_volume *
vox(const vv_shape *s, const vv_voxelize_options *o) {
    vv_volume *v = NULL;
    vt_ok(vv_voxelize(&v, s, o));
    return v;
}

static void
check_rel(const char *what, double got, double want, double tol) {
    double rel = fabs(got - want) / want;
    if (!(rel <= tol))
        fail_msg("%s: %.6g, expected %.6g (rel. error %.4f > %.4f)", what, got, want, rel, tol);
}

/* ---------------------------------------------------------------------- */

static void
test_sampling_kernel_tables(void **state) {
    (void)state;
    const vv_sampling_kernel_kind kinds[3] = {VV_SAMPLING_KERNEL_BOX, VV_SAMPLING_KERNEL_TENT,
                                              VV_SAMPLING_KERNEL_GAUSS};
    const double radii[5] = {0.5, 1.0, 1.5, 2.0, 3.5};
    for (int k = 0; k < 3; k++)
        for (int r = 0; r < 5; r++) {
            vv_sampling_kernel_table *t = NULL;
            vt_ok(vv_sampling_kernel_table_new(&t, kinds[k], radii[r], 0));
            assert_float_equal(vv_sampling_kernel_table_eval(t, 0.0), 0.5, 1e-6);
            assert_float_equal(vv_sampling_kernel_table_eval(t, -radii[r] - 1), 1.0, 0.0);
            assert_float_equal(vv_sampling_kernel_table_eval(t, radii[r] + 1), 0.0, 0.0);
            double worst = 0, prev = 2;
            for (int i = 0; i <= 1000; i++) {
                double d = -1.2 * radii[r] + 2.4 * radii[r] * i / 1000.0;
                double a = vv_sampling_kernel_table_eval(t, d),
                       b = vv_sampling_kernel_integral(kinds[k], radii[r], d);
                worst = fmax(worst, fabs(a - b));
                assert_true(a <= prev + 1e-7); /* monotone */
                prev = a;
            }
            if (!(worst < 2e-5))
                fail_msg("%s R=%g: table differs from the integral by %g",
                         vv_sampling_kernel_name(kinds[k]), radii[r], worst);
            vv_sampling_kernel_table_free(t);
        }
    /* the closed forms themselves: the box is the spherical cap volume */
    double R = 2.0, d = 0.7, hcap = R - d;
    assert_float_equal(vv_sampling_kernel_integral(VV_SAMPLING_KERNEL_BOX, R, d),
                       VT_PI * hcap * hcap * (3 * R - hcap) / 3 / (4.0 / 3 * VT_PI * R * R * R),
                       1e-12);
    vv_sampling_kernel_table *t = NULL;
    vt_err(vv_sampling_kernel_table_new(&t, VV_SAMPLING_KERNEL_TENT, 0.0, 0));
    vt_err(vv_sampling_kernel_table_new(&t, (vv_sampling_kernel_kind)7, 1.0, 0));
    vv_sampling_kernel_kind fk;
    vt_ok(vv_sampling_kernel_parse("gauss", &fk));
    assert_int_equal(fk, VV_SAMPLING_KERNEL_GAUSS);
    vt_err(vv_sampling_kernel_parse("sinc", &fk));
}

static void
test_sphere_radii(void **state) {
    (void)state;
    const double radii[] = {5, 7.5, 10, 20, 50, 100};
    for (size_t i = 0; i < sizeof radii / sizeof *radii; i++) {
        double r = radii[i];
        vv_shape *s = NULL;
        vt_ok(vv_shape_sphere(&s, r));
        /* off the lattice symmetry */
        vv_shape_transform(s, vv_mat4_translate(vv_vec3_make(0.31, -0.17, 0.43)));
        vv_voxelize_options o;
        opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
        o.voxel_spacing = 1.0;
        vv_volume *v = vox(s, &o);
        measure m = measure_volume(v);
        char what[64];
        snprintf(what, sizeof what, "sphere r=%g volume", r);
        check_rel(what, m.volume, 4.0 / 3 * VT_PI * r * r * r, 0.01);
        snprintf(what, sizeof what, "sphere r=%g area", r);
        check_rel(what, m.area, 4 * VT_PI * r * r, 0.02);
        measure mc = measure_mc(v);
        print_message("sphere r=%g: volume %+.3f %%, area %+.3f %%; Marching Cubes volume "
                      "%+.3f %%, area %+.3f %%\n",
                      r, 100 * (m.volume / (4.0 / 3 * VT_PI * r * r * r) - 1),
                      100 * (m.area / (4 * VT_PI * r * r) - 1),
                      100 * (mc.volume / (4.0 / 3 * VT_PI * r * r * r) - 1),
                      100 * (mc.area / (4 * VT_PI * r * r) - 1));
        snprintf(what, sizeof what, "sphere r=%g Marching Cubes volume", r);
        if (r >= 10) /* below, the chords of Marching Cubes cut off over 1 % */
            check_rel(what, mc.volume, 4.0 / 3 * VT_PI * r * r * r, 0.01);
        snprintf(what, sizeof what, "sphere r=%g Marching Cubes area", r);
        check_rel(what, mc.area, 4 * VT_PI * r * r, 0.02);
        vv_volume_free(v);
        vv_shape_free(s);
    }
    /* every kernel, u8 output: the u8 volume scaled back agrees */
    const vv_sampling_kernel_kind kinds[3] = {VV_SAMPLING_KERNEL_BOX, VV_SAMPLING_KERNEL_TENT,
                                              VV_SAMPLING_KERNEL_GAUSS};
    for (int k = 0; k < 3; k++) {
        vv_shape *s = NULL;
        vt_ok(vv_shape_sphere(&s, 12.0));
        vv_voxelize_options o;
        opts_f32(&o, kinds[k], 2.0);
        o.voxel_spacing = 1.0;
        vv_volume *v = vox(s, &o);
        measure m = measure_volume_k(v, kinds[k], 2.0);
        check_rel(vv_sampling_kernel_name(kinds[k]), m.volume, 4.0 / 3 * VT_PI * 12 * 12 * 12,
                  0.01);
        o.type = VV_U8;
        vv_volume *u = vox(s, &o);
        assert_int_equal(u->dims[0], v->dims[0]);
        const unsigned char *ud = u->data;
        const float *fd = v->data;
        for (uint64_t j = 0; j < vv_volume_voxel_count(v); j++)
            assert_true(fabs(ud[j] / 255.0 - fd[j]) <= 0.5 / 255 + 1e-6);
        assert_int_equal(u->data_origin, VV_ORIGIN_FUZZY_VOXELIZED);
        vv_volume_free(u);
        vv_volume_free(v);
        vv_shape_free(s);
    }
}

static void
check_shape(vv_shape *s, double want_vol, double want_area, double h, const char *what) {
    vv_voxelize_options o;
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.voxel_spacing = h;
    vv_volume *v = vox(s, &o);
    measure m = measure_volume(v);
    char w[96];
    snprintf(w, sizeof w, "%s volume", what);
    check_rel(w, m.volume, want_vol, 0.01);
    if (want_area > 0) {
        snprintf(w, sizeof w, "%s area", what);
        check_rel(w, m.area, want_area, 0.02);
        measure mc = measure_mc(v);
        snprintf(w, sizeof w, "%s Marching Cubes volume", what);
        check_rel(w, mc.volume, want_vol, 0.01);
        snprintf(w, sizeof w, "%s Marching Cubes area", what);
        check_rel(w, mc.area, want_area, 0.02);
    }
    vv_volume_free(v);
    vv_shape_free(s);
}

static void
test_primitives(void **state) {
    (void)state;
    vv_shape *s = NULL;
    /* box, rotated: V = abc, A = 2(ab + bc + ca) */
    vt_ok(vv_shape_box(&s, vv_vec3_make(30, 20, 14), 0.0));
    vv_shape_transform(s, vv_mat4_rotate(vv_vec3_make(1, 2, 3), 0.6));
    check_shape(s, 30 * 20 * 14, 2 * (30 * 20 + 20 * 14 + 14 * 30), 0.5, "box");
    /* rounded box: inner box Minkowski-summed with a ball of radius q */
    double q = 4, a = 30 - 2 * q, b = 20 - 2 * q, c = 14 - 2 * q;
    vt_ok(vv_shape_box(&s, vv_vec3_make(30, 20, 14), q));
    check_shape(s,
                a * b * c + 2 * q * (a * b + b * c + a * c) + VT_PI * q * q * (a + b + c) +
                    4.0 / 3 * VT_PI * q * q * q,
                2 * (a * b + b * c + a * c) + 2 * VT_PI * q * (a + b + c) + 4 * VT_PI * q * q, 1.0,
                "rounded box");
    /* torus: V = 2 pi^2 R r^2, A = 4 pi^2 R r */
    vt_ok(vv_shape_torus(&s, 25, 8));
    vv_shape_transform(s, vv_mat4_rotate(vv_vec3_make(1, 0, 0), 0.4));
    check_shape(s, 2 * VT_PI * VT_PI * 25 * 64, 4 * VT_PI * VT_PI * 25 * 8, 1.0, "torus");
    vt_ok(vv_shape_torus(&s, 12, 6));
    check_shape(s, 2 * VT_PI * VT_PI * 12 * 36, 4 * VT_PI * VT_PI * 12 * 6, 0.5, "small torus");
    /* cylinder and cone */
    vt_ok(vv_shape_cylinder(&s, 10, 30));
    check_shape(s, VT_PI * 100 * 30, 2 * VT_PI * 10 * 30 + 2 * VT_PI * 100, 1.0, "cylinder");
    vt_ok(vv_shape_cone(&s, 12, 5, 20));
    check_shape(s, VT_PI * 20 * (144 + 60 + 25) / 3, 0, 1.0, "truncated cone");
    vt_ok(vv_shape_cone(&s, 10, 0, 25));
    check_shape(s, VT_PI * 25 * 100 / 3, 0, 0.5, "pointed cone");
    /* ellipsoid, and a sphere scaled non-uniformly */
    vt_ok(vv_shape_ellipsoid(&s, vv_vec3_make(20, 12, 8)));
    check_shape(s, 4.0 / 3 * VT_PI * 20 * 12 * 8, 0, 1.0, "ellipsoid");
    vt_ok(vv_shape_sphere(&s, 10));
    vv_shape_transform(s, vv_mat4_scale(vv_vec3_make(2.0, 1.2, 0.8)));
    check_shape(s, 4.0 / 3 * VT_PI * 20 * 12 * 8, 0, 1.0, "scaled sphere");
    /* hexagonal extrusion: area 3 sqrt(3)/2 s^2 */
    double hex[12];
    for (int i = 0; i < 6; i++) {
        hex[2 * i] = 15 * cos(i * VT_PI / 3);
        hex[2 * i + 1] = 15 * sin(i * VT_PI / 3);
    }
    vt_ok(vv_shape_extrusion(&s, 6, hex, 12));
    check_shape(s, 1.5 * sqrt(3.0) * 225 * 12, 2 * 1.5 * sqrt(3.0) * 225 + 6 * 15 * 12, 0.5,
                "hexagonal prism");
    /* a thick triangle in a tilted plane */
    vv_vec3 tri[3] = {{0, 0, 0}, {30, 0, 10}, {0, 25, 5}};
    vt_ok(vv_shape_polygon(&s, 3, tri, 6));
    double tri_area = 0.5 * vv_vec3_length(vv_vec3_cross(vv_vec3_sub(tri[1], tri[0]),
                                                         vv_vec3_sub(tri[2], tri[0])));
    check_shape(s, tri_area * 6, 0, 0.5, "thick triangle");
    /* revolution of a rectangle r in [5, 15], z in [0, 10]: an annulus,
     * Pappus: V = A * 2 pi rc */
    double ring[8] = {5, 0, 15, 0, 15, 10, 5, 10};
    vt_ok(vv_shape_revolution(&s, 4, ring));
    check_shape(s, 100 * 2 * VT_PI * 10, 0, 1.0, "revolved rectangle");
    /* helix sweep of a triangle: the helical shear keeps volume, so per unit
     * height V = A * 2 pi rc / pitch */
    double thread[6] = {10, -2, 14, 0, 10, 2};
    vt_ok(vv_shape_helix(&s, 3, thread, 5.0, -20, 20));
    check_shape(s, 8.0 * 2 * VT_PI * (34.0 / 3) * 40 / 5.0, 0, 0.5, "helix thread");
}

/* World objects as model primitives (vv_shape_object: the geometry-type
 * table's distances): analytic volumes and areas, the same voxels as
 * Modeling's own sphere and box, CSG with them, and the refusals. */
static void
test_world_objects(void **state) {
    (void)state;
    vv_object *o = NULL;
    vv_shape *s = NULL;
    /* a sphere placed and rotated by the object transform */
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "ball"));
    o->geometry.radius = 12;
    o->position = vv_vec3_make(5, -3, 2);
    vt_ok(vv_shape_object(&s, o));
    check_shape(s, 4.0 / 3 * VT_PI * 12 * 12 * 12, 4 * VT_PI * 144, 0.5, "object sphere");
    /* voxel for voxel the same as Modeling's sphere there */
    vv_voxelize_options opt;
    opts_f32(&opt, VV_SAMPLING_KERNEL_TENT, 1.5);
    opt.voxel_spacing = 1.0;
    vt_ok(vv_shape_object(&s, o));
    vv_volume *a = vox(s, &opt);
    vv_shape_free(s);
    vt_ok(vv_shape_sphere(&s, 12));
    vv_shape_transform(s, vv_mat4_translate(o->position));
    vv_volume *b = vox(s, &opt);
    vv_shape_free(s);
    assert_memory_equal(a->dims, b->dims, sizeof a->dims);
    assert_memory_equal(a->data, b->data, vv_volume_voxel_count(a) * sizeof(float));
    vv_volume_free(a);
    vv_volume_free(b);
    vv_object_free(o);
    /* a box off the origin, rotated: V = abc, A = 2(ab + bc + ca) */
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_BOX, "crate"));
    o->geometry.box = (vv_box){{-5, 0, 2}, {25, 20, 16}};
    o->orientation = vv_quat_from_axis_angle(vv_vec3_make(1, 2, 3), 0.6);
    vt_ok(vv_shape_object(&s, o));
    check_shape(s, 30 * 20 * 14, 2 * (30 * 20 + 20 * 14 + 14 * 30), 0.5, "object box");
    /* the same voxels as Modeling's box of the same size and centre */
    o->orientation = vv_quat_identity();
    vt_ok(vv_shape_object(&s, o));
    a = vox(s, &opt);
    vv_shape_free(s);
    vt_ok(vv_shape_box(&s, vv_vec3_make(30, 20, 14), 0));
    vv_shape_transform(s, vv_mat4_translate(vv_vec3_make(10, 10, 9)));
    b = vox(s, &opt);
    vv_shape_free(s);
    assert_memory_equal(a->data, b->data, vv_volume_voxel_count(a) * sizeof(float));
    vv_volume_free(a);
    vv_volume_free(b);
    vv_object_free(o);
    /* a capped cylinder along a slanted axis: V = pi r^2 h, A = 2 pi r (r + h) */
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_CYLINDER, "can"));
    o->geometry.base = vv_vec3_make(0, 0, 0);
    o->geometry.top = vv_vec3_make(12, 16, 0); /* h = 20 */
    o->geometry.radius = 6;
    vt_ok(vv_shape_object(&s, o));
    check_shape(s, VT_PI * 36 * 20, 2 * VT_PI * 6 * 26, 0.5, "object cylinder");
    /* minus a sphere on its axis: CSG works on object shapes */
    vv_shape *kids[2] = {NULL, NULL};
    vt_ok(vv_shape_object(&kids[0], o));
    vt_ok(vv_shape_sphere(&kids[1], 4));
    vv_shape_transform(kids[1], vv_mat4_translate(vv_vec3_make(6, 8, 0)));
    vt_ok(vv_shape_csg(&s, VV_CSG_DIFFERENCE, 2, kids));
    check_shape(s, VT_PI * 36 * 20 - 4.0 / 3 * VT_PI * 64, 0, 0.5, "cylinder minus sphere");
    /* an open tube, a polygon, a plane and a volume are refused */
    o->geometry.capped = 0;
    vt_err(vv_shape_object(&s, o));
    assert_null(s);
    vv_object_free(o);
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_PLANE, NULL));
    vt_err(vv_shape_object(&s, o));
    vv_object_free(o);
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_POLYGON, NULL));
    const vv_vec3 quad[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    vt_ok(vv_object_set_polygon(o, 4, quad));
    vt_err(vv_shape_object(&s, o));
    vv_object_free(o);
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, NULL));
    o->geometry.radius = -1;
    vt_err(vv_shape_object(&s, o));
    vv_object_free(o);
    /* a mesh object: Modeling's scan conversion of the mesh */
    vv_mesh *m = vt_sphere_mesh(10, 4);
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_MESH, NULL));
    vt_ok(vv_object_set_mesh(o, m, NULL));
    vv_mesh_free(m);
    vt_ok(vv_shape_object(&s, o));
    double mv = 0;
    vt_ok(vv_measure_mesh_volume(o->geometry.mesh, &mv));
    check_shape(s, mv, 0, 0.5, "object mesh");
    vv_object_free(o);
}

static void
test_csg(void **state) {
    (void)state;
    vv_voxelize_options o;
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.dims[0] = o.dims[1] = o.dims[2] = 72;
    o.spacing[0] = o.spacing[1] = o.spacing[2] = 1.0;
    o.origin[0] = o.origin[1] = o.origin[2] = -35.5;
    vv_shape *a, *b, *kids[2];
#define MAKE_AB()                                                                                  \
    do {                                                                                           \
        vt_ok(vv_shape_sphere(&a, 20));                                                            \
        vv_shape_transform(a, vv_mat4_translate(vv_vec3_make(-6, 1, 0)));                          \
        vt_ok(vv_shape_box(&b, vv_vec3_make(30, 24, 36), 3));                                      \
        vv_shape_transform(b, vv_mat4_translate(vv_vec3_make(9, 0, 2)));                           \
    } while (0)
    MAKE_AB();
    vv_volume *va = vox(a, &o), *vb = vox(b, &o);
    kids[0] = a;
    kids[1] = b;
    vv_shape *u, *x, *u2;
    vt_ok(vv_shape_csg(&u, VV_CSG_UNION, 2, kids));
    vv_volume *vu = vox(u, &o);
    vv_shape_free(u);
    MAKE_AB();
    kids[0] = a;
    kids[1] = b;
    vt_ok(vv_shape_csg(&x, VV_CSG_INTERSECTION, 2, kids));
    vv_volume *vx = vox(x, &o);
    vv_shape_free(x);
    MAKE_AB();
    kids[0] = b;
    kids[1] = a;
    vt_ok(vv_shape_csg(&u2, VV_CSG_UNION, 2, kids));
    vv_volume *vu2 = vox(u2, &o);
    vv_shape_free(u2);
    /* union is commutative voxel for voxel, and is max(A, B) per voxel */
    size_t n = vv_volume_voxel_count(vu);
    assert_memory_equal(vu->data, vu2->data, n * sizeof(float));
    const float *fa = va->data, *fb = vb->data, *fu = vu->data, *fx = vx->data;
    for (size_t i = 0; i < n; i++) {
        assert_true(fu[i] == fmaxf(fa[i], fb[i]));
        assert_true(fx[i] == fminf(fa[i], fb[i]));
    }
    measure ma = measure_volume(va), mb = measure_volume(vb);
    measure mu = measure_volume(vu), mx = measure_volume(vx);
    check_rel("vol(A u B) + vol(A n B)", mu.volume + mx.volume, ma.volume + mb.volume, 0.01);
    assert_true(mx.volume > 0.1 * ma.volume && mx.volume < 0.9 * ma.volume); /* overlap */
    /* A - B + A n B = A */
    MAKE_AB();
    kids[0] = a;
    kids[1] = b;
    vt_ok(vv_shape_csg(&x, VV_CSG_DIFFERENCE, 2, kids));
    vv_volume *vd = vox(x, &o);
    vv_shape_free(x);
    measure md = measure_volume(vd);
    check_rel("vol(A - B) + vol(A n B)", md.volume + mx.volume, ma.volume, 0.01);
    /* A - A is empty: no voxel above the 0.5 level */
    MAKE_AB();
    vv_shape_free(b);
    vt_ok(vv_shape_sphere(&b, 20));
    vv_shape_transform(b, vv_mat4_translate(vv_vec3_make(-6, 1, 0)));
    kids[0] = a;
    kids[1] = b;
    vt_ok(vv_shape_csg(&x, VV_CSG_DIFFERENCE, 2, kids));
    vv_volume *ve = vox(x, &o);
    vv_shape_free(x);
    assert_true(ve->range[1] <= 0.5);
    const float *fe = ve->data;
    for (size_t i = 0; i < n; i++)
        assert_true(fe[i] <= 0.5f);
    /* the analytic volume of the intersection of a sphere and a half-space
     * through its centre: a deep tree (depth 12 of nested unions with one
     * real child) of an intersection is still half a sphere */
    vv_shape *h = NULL, *sp = NULL;
    vt_ok(vv_shape_box(&h, vv_vec3_make(60, 60, 30), 0));
    vv_shape_transform(h, vv_mat4_translate(vv_vec3_make(0, 0, 15)));
    vt_ok(vv_shape_sphere(&sp, 25));
    kids[0] = sp;
    kids[1] = h;
    vt_ok(vv_shape_csg(&x, VV_CSG_INTERSECTION, 2, kids));
    for (int d = 0; d < 12; d++)
        vt_ok(vv_shape_csg(&x, d & 1 ? VV_CSG_INTERSECTION : VV_CSG_UNION, 1, &x));
    vv_volume *vh = vox(x, &o);
    vv_shape_free(x);
    check_rel("half sphere", measure_volume(vh).volume, 2.0 / 3 * VT_PI * 25 * 25 * 25, 0.01);
    vv_volume *vols[] = {va, vb, vu, vu2, vx, vd, ve, vh};
    for (size_t i = 0; i < sizeof vols / sizeof *vols; i++)
        vv_volume_free(vols[i]);
#undef MAKE_AB
}

static void
test_meshes(void **state) {
    (void)state;
    /* a closed sphere mesh: solid, volume of the polyhedron */
    vv_mesh *m = vt_sphere_mesh(20, 5);
    vv_shape *s = NULL;
    vt_ok(vv_shape_mesh(&s, m, VV_MESH_AUTO, 0));
    vv_voxelize_options o;
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.voxel_spacing = 0.5;
    vv_volume *v = vox(s, &o);
    measure ms = measure_volume(v);
    check_rel("sphere mesh volume", ms.volume, vv_mesh_signed_volume(m), 0.01);
    check_rel("sphere mesh area", ms.area, vv_mesh_area(m), 0.02);
    vv_volume_free(v);
    vv_shape_free(s);

    /* the same mesh, open (the triangles with a vertex above z = 15
     * removed): a shell, not a flood */
    size_t keep = 0;
    for (size_t t = 0; t < m->n_triangles; t++) {
        int top = 0;
        for (int k = 0; k < 3; k++)
            top |= vv_mesh_vertex(m, m->triangles[3 * t + k]).z > 15;
        if (!top) {
            memmove(m->triangles + 3 * keep, m->triangles + 3 * t, 3 * sizeof *m->triangles);
            keep++;
        }
    }
    m->n_triangles = keep;
    vv_mesh_topology topo;
    vt_ok(vv_mesh_topology_compute(m, &topo));
    assert_false(topo.closed);
    vt_ok(vv_shape_mesh(&s, m, VV_MESH_AUTO, 1.0));
    o.voxel_spacing = 0.5;
    v = vox(s, &o);
    float centre;
    assert_true(vv_volume_sample_world(v, vv_vec3_make(0, 0, 0), &centre));
    assert_true(centre == 0.0f);
    measure mo = measure_volume(v);
    /* a shell of thickness 1 around the open surface */
    check_rel("open mesh shell volume", mo.volume, vv_mesh_area(m) * 1.0, 0.05);
    assert_true(vv_volume_sample_world(v, vv_vec3_make(20, 0, 0), &centre));
    assert_true(centre > 0.5f);
    vv_volume_free(v);
    vv_shape_free(s);
    vv_mesh_free(m);

    /* a cube mesh without its top face, voxelized as a solid: the z rows
     * through the hole abstain, the x and y rows still fill it; as AUTO it
     * is an open mesh, so a shell */
    vv_mesh *cube = NULL;
    vt_ok(vv_mesh_new(&cube));
    for (int i = 0; i < 8; i++)
        vt_ok(vv_mesh_add_vertex(
            cube, vv_vec3_make(i & 1 ? 10 : -10, i & 2 ? 10 : -10, i & 4 ? 10 : -10), NULL));
    const uint32_t faces[5][4] = {
        {0, 2, 3, 1}, {0, 1, 5, 4}, {1, 3, 7, 5}, {3, 2, 6, 7}, {2, 0, 4, 6}}; /* no top */
    for (int f = 0; f < 5; f++) {
        vt_ok(vv_mesh_add_triangle(cube, faces[f][0], faces[f][1], faces[f][2]));
        vt_ok(vv_mesh_add_triangle(cube, faces[f][0], faces[f][2], faces[f][3]));
    }
    vt_ok(vv_shape_mesh(&s, cube, VV_MESH_SOLID, 0));
    /* turned about z only: the hole stays across the z rows (a tilted hole
     * would make the solid itself ambiguous) */
    vv_shape_transform(s, vv_mat4_rotate(vv_vec3_make(0, 0, 1), 0.3));
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.voxel_spacing = 0.5;
    v = vox(s, &o);
    /* the missing face has no distance band (no triangles): its level is
     * only voxel-accurate, up to half a layer of 0.5 x 20 x 20 */
    check_rel("open-topped cube as a solid", measure_volume(v).volume, 8000, 0.02);
    vv_volume_free(v);
    vv_shape_free(s);
    vt_ok(vv_shape_mesh(&s, cube, VV_MESH_AUTO, 1.0));
    v = vox(s, &o);
    assert_true(vv_volume_sample_world(v, vv_vec3_make(0, 0, 0), &centre));
    assert_true(centre == 0.0f);
    vv_volume_free(v);
    vv_shape_free(s);
    vv_mesh_free(cube);

    /* the shared knot: closed; volume within 2 % of the divergence volume */
    vv_mesh *knot = NULL;
    vt_ok(vv_mesh_load(&knot, vt_data("meshes/knot1.off")));
    vt_ok(vv_mesh_topology_compute(knot, &topo));
    assert_true(topo.closed);
    vt_ok(vv_shape_mesh(&s, knot, VV_MESH_AUTO, 0));
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.size = 160;
    v = vox(s, &o);
    measure mk = measure_volume(v);
    check_rel("knot1.off volume", mk.volume, fabs(vv_mesh_signed_volume(knot)), 0.02);
    check_rel("knot1.off area", mk.area, vv_mesh_area(knot), 0.05);
    vv_volume_free(v);
    /* the same voxels whatever the thread count */
    vv_volume *k1 = NULL, *k3 = NULL;
    vv_voxelize_options_init(&o);
    o.size = 96;
    o.threads = 1;
    vt_ok(vv_voxelize(&k1, s, &o));
    o.threads = 3;
    vt_ok(vv_voxelize(&k3, s, &o));
    assert_memory_equal(k1->data, k3->data, vv_volume_voxel_count(k1));
    vv_volume_free(k1);
    vv_volume_free(k3);
    vv_shape_free(s);
    vv_mesh_free(knot);
}

/* A copy of @p m without the triangles whose index is 0 mod @p stride (from
 * @p first), @p n of them: small holes spread over the surface. */
static vv_mesh *
mesh_with_holes(const vv_mesh *m, size_t first, size_t stride, int n) {
    vv_mesh *h = NULL;
    vt_ok(vv_mesh_new(&h));
    for (size_t i = 0; i < m->n_vertices; i++)
        vt_ok(vv_mesh_add_vertex(h, vv_mesh_vertex(m, i), NULL));
    int removed = 0;
    for (size_t t = 0; t < m->n_triangles; t++) {
        if (removed < n && t >= first && (t - first) % stride == 0) {
            removed++;
            continue;
        }
        const uint32_t *v = m->triangles + 3 * t;
        vt_ok(vv_mesh_add_triangle(h, v[0], v[1], v[2]));
    }
    assert_int_equal(removed, n);
    return h;
}

/* Appends @p b to @p a, its vertices moved by @p d; @p inward reverses its triangles. */
static void
mesh_append(vv_mesh *a, const vv_mesh *b, vv_vec3 d, int inward) {
    uint32_t base = (uint32_t)a->n_vertices;
    for (size_t i = 0; i < b->n_vertices; i++)
        vt_ok(vv_mesh_add_vertex(a, vv_vec3_add(vv_mesh_vertex(b, i), d), NULL));
    for (size_t t = 0; t < b->n_triangles; t++) {
        const uint32_t *v = b->triangles + 3 * t;
        if (inward)
            vt_ok(vv_mesh_add_triangle(a, base + v[0], base + v[2], base + v[1]));
        else
            vt_ok(vv_mesh_add_triangle(a, base + v[0], base + v[1], base + v[2]));
    }
}

static double
mesh_volume_voxelized(vv_mesh *m, vv_mesh_mode mode, float *centre) {
    vv_shape *s = NULL;
    vt_ok(vv_shape_mesh(&s, m, mode, 0));
    vv_voxelize_options o;
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.voxel_spacing = 0.5;
    vv_volume *v = vox(s, &o);
    if (centre)
        assert_true(vv_volume_sample_world(v, vv_vec3_make(0, 0, 0), centre));
    double vol = measure_volume(v).volume;
    vv_volume_free(v);
    vv_shape_free(s);
    return vol;
}

/* Imperfect meshes fill as the solids they obviously are (the generalized
 * winding number): holes, a flipped patch, overlapping and inward parts. */
static void
test_imperfect_meshes(void **state) {
    (void)state;
    vv_mesh *sphere = vt_sphere_mesh(20, 5);
    float centre = 0;
    double closed = mesh_volume_voxelized(sphere, VV_MESH_AUTO, &centre);
    assert_true(centre == 1.0f);
    check_rel("closed sphere", closed, vv_mesh_signed_volume(sphere), 0.01);
    /* 1, 10 and 100 small holes (one triangle each, spread out) */
    const int holes[3] = {1, 10, 100};
    for (int k = 0; k < 3; k++) {
        vv_mesh *h =
            mesh_with_holes(sphere, 37, sphere->n_triangles / (size_t)holes[k] - 1, holes[k]);
        vv_mesh_topology topo;
        vt_ok(vv_mesh_topology_compute(h, &topo));
        assert_int_equal(topo.n_boundary_edges, 3 * (size_t)holes[k]);
        char what[64];
        snprintf(what, sizeof what, "sphere with %d holes (auto)", holes[k]);
        check_rel(what, mesh_volume_voxelized(h, VV_MESH_AUTO, &centre), closed, 0.01);
        assert_true(centre == 1.0f);
        snprintf(what, sizeof what, "sphere with %d holes (solid)", holes[k]);
        check_rel(what, mesh_volume_voxelized(h, VV_MESH_SOLID, NULL), closed, 0.01);
        vv_mesh_free(h);
    }
    /* a large hole and a flat sheet are surfaces: auto makes shells */
    {
        vv_mesh *disc = NULL;
        vt_ok(vv_mesh_new(&disc));
        vt_ok(vv_mesh_add_vertex(disc, vv_vec3_make(0, 0, 0), NULL));
        for (int i = 0; i < 32; i++)
            vt_ok(vv_mesh_add_vertex(
                disc, vv_vec3_make(10 * cos(i * VT_PI / 16), 10 * sin(i * VT_PI / 16), 0), NULL));
        for (uint32_t i = 0; i < 32; i++)
            vt_ok(vv_mesh_add_triangle(disc, 0, 1 + i, 1 + (i + 1) % 32));
        double shell = mesh_volume_voxelized(disc, VV_MESH_AUTO, NULL);
        /* a shell two voxels (1 world unit) thick around the disc */
        check_rel("a disc as a shell", shell, vv_mesh_area(disc) * 1.0, 0.1);
        vv_mesh_free(disc);
    }
    /* a flipped patch (every triangle with a vertex beyond x = 12): turned
     * back, the same solid */
    {
        vv_mesh *f = mesh_with_holes(sphere, 0, 1, 0);
        size_t nflip = 0;
        for (size_t t = 0; t < f->n_triangles; t++) {
            uint32_t *v = f->triangles + 3 * t;
            int far = 0;
            for (int k = 0; k < 3; k++)
                far |= vv_mesh_vertex(f, v[k]).x > 12;
            if (far) {
                uint32_t x = v[1];
                v[1] = v[2];
                v[2] = x;
                nflip++;
            }
        }
        assert_true(nflip > 100 && nflip < f->n_triangles / 4);
        vv_mesh_topology topo;
        vt_ok(vv_mesh_topology_compute(f, &topo));
        assert_false(topo.oriented);
        check_rel("sphere with a flipped patch", mesh_volume_voxelized(f, VV_MESH_AUTO, &centre),
                  closed, 0.01);
        assert_true(centre == 1.0f);
        /* ... and with holes as well: the orientation is fixed first */
        vv_mesh *fh = mesh_with_holes(f, 11, f->n_triangles / 10 - 1, 10);
        check_rel("flipped patch and 10 holes", mesh_volume_voxelized(fh, VV_MESH_AUTO, NULL),
                  closed, 0.01);
        vv_mesh_free(fh);
        vv_mesh_free(f);
    }
    /* self-intersecting parts: two spheres 20 apart in one mesh (their
     * overlap counts once, parity would hollow it out), and a third sphere,
     * apart from them, facing inwards (still a solid) */
    {
        vv_mesh *u = NULL;
        vt_ok(vv_mesh_new(&u));
        mesh_append(u, sphere, vv_vec3_make(0, 0, 0), 0);
        mesh_append(u, sphere, vv_vec3_make(20, 0, 0), 0);
        double r = 20, d = 20;
        double lens = VT_PI * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
        double sv = vv_mesh_signed_volume(sphere);
        /* the polyhedron's lens is smaller than the ball's by its volume ratio */
        double expect = 2 * sv - lens * sv / (4.0 / 3.0 * VT_PI * r * r * r);
        check_rel("two overlapping spheres", mesh_volume_voxelized(u, VV_MESH_AUTO, &centre),
                  expect, 0.01);
        mesh_append(u, sphere, vv_vec3_make(-45, 0, 0), 1);
        check_rel("... and an inward-facing one", mesh_volume_voxelized(u, VV_MESH_SOLID, NULL),
                  expect + sv, 0.01);
        vv_mesh_free(u);
    }
    vv_mesh_free(sphere);

    /* the Stanford bunny: five holes in its base (223 boundary edges); auto
     * fills it as a solid, within 1 % of the volume the rows through its
     * closed parts give when it is turned so no x row meets a hole */
    vv_mesh *bunny = NULL;
    vt_ok(vv_mesh_load(&bunny, vt_data("meshes/bunny.ply")));
    vv_mesh_topology topo;
    vt_ok(vv_mesh_topology_compute(bunny, &topo));
    assert_false(topo.closed);
    vv_shape *s = NULL;
    vt_ok(vv_shape_mesh(&s, bunny, VV_MESH_AUTO, 0));
    vv_voxelize_options o;
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.size = 128;
    vv_volume *v = vox(s, &o);
    double vb = measure_volume(v).volume;
    float inside = 0;
    /* a point in the body, just above the holes of the base */
    assert_true(vv_volume_sample_world(v, vv_vec3_make(-0.02, 0.06, 0.0), &inside));
    assert_true(inside == 1.0f);
    vv_volume_free(v);
    vv_shape_free(s);
    printf("bunny solid volume %.6g, divergence volume of the open mesh %.6g\n", vb,
           fabs(vv_mesh_signed_volume(bunny)));
    check_rel("bunny.ply as a solid", vb, fabs(vv_mesh_signed_volume(bunny)), 0.05);
    vv_mesh_free(bunny);
}

/* The generalized winding number of @p m at @p p, by brute force: the sum
 * of its triangles' solid angles (the l'Huilier-free Van Oosterom-Strackee
 * formula, written here independently of the library) over 4 pi. */
static double
winding_brute(const vv_mesh *m, vv_vec3 p) {
    double sum = 0;
    for (size_t t = 0; t < m->n_triangles; t++) {
        vv_vec3 a = vv_vec3_sub(vv_mesh_vertex(m, m->triangles[3 * t]), p);
        vv_vec3 b = vv_vec3_sub(vv_mesh_vertex(m, m->triangles[3 * t + 1]), p);
        vv_vec3 c = vv_vec3_sub(vv_mesh_vertex(m, m->triangles[3 * t + 2]), p);
        double la = vv_vec3_length(a), lb = vv_vec3_length(b), lc = vv_vec3_length(c);
        double num = vv_vec3_dot(a, vv_vec3_cross(b, c));
        double den =
            la * lb * lc + vv_vec3_dot(a, b) * lc + vv_vec3_dot(a, c) * lb + vv_vec3_dot(b, c) * la;
        sum += 2.0 * atan2(num, den);
    }
    return sum / (4.0 * VT_PI);
}

/* A large, non-planar hole filled as a solid: the voxels away from the
 * surface are inside exactly where the brute-force winding number is above
 * 1/2 (the hole's fill is the w = 1/2 level, not the flat cap). */
static void
test_winding_number(void **state) {
    (void)state;
    vv_mesh *sphere = vt_sphere_mesh(20, 4);
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_new(&m));
    for (size_t i = 0; i < sphere->n_vertices; i++)
        vt_ok(vv_mesh_add_vertex(m, vv_mesh_vertex(sphere, i), NULL));
    for (size_t t = 0; t < sphere->n_triangles; t++) {
        const uint32_t *v = sphere->triangles + 3 * t;
        vv_vec3 c =
            vv_vec3_scale(vv_vec3_add(vv_vec3_add(vv_mesh_vertex(m, v[0]), vv_mesh_vertex(m, v[1])),
                                      vv_mesh_vertex(m, v[2])),
                          1.0 / 3);
        if (c.x > 8 && c.y > -4) /* a saddle-shaped loop: not planar */
            continue;
        vt_ok(vv_mesh_add_triangle(m, v[0], v[1], v[2]));
    }
    vv_shape *s = NULL;
    vt_ok(vv_shape_mesh(&s, m, VV_MESH_SOLID, 0));
    vv_voxelize_options o;
    opts_f32(&o, VV_SAMPLING_KERNEL_TENT, 1.5);
    o.voxel_spacing = 1.0;
    vv_volume *v = vox(s, &o);
    const float *rho = v->data;
    size_t checked = 0, hole_fill = 0;
    for (size_t i = 0; i < vv_volume_voxel_count(v); i += 9) {
        if (rho[i] != 0.0f && rho[i] != 1.0f)
            continue; /* near a triangle */
        int x = (int)(i % (size_t)v->dims[0]),
            y = (int)(i / (size_t)v->dims[0] % (size_t)v->dims[1]),
            z = (int)(i / ((size_t)v->dims[0] * (size_t)v->dims[1]));
        vv_vec3 p = vv_vec3_make(v->origin[0] + x * v->spacing[0], v->origin[1] + y * v->spacing[1],
                                 v->origin[2] + z * v->spacing[2]);
        double w = winding_brute(m, p);
        if (fabs(fabs(w) - 0.5) < 0.02)
            continue; /* on the fill's level, up to the far field's error */
        checked++;
        hole_fill += p.x > 12 && fabs(w) > 0.5 && fabs(w) < 0.95;
        if ((rho[i] == 1.0f) != (fabs(w) > 0.5))
            fail_msg("voxel (%d %d %d) at (%g %g %g): density %g, winding number %g", x, y, z, p.x,
                     p.y, p.z, rho[i], w);
    }
    printf("winding number: %zu voxels checked, %zu of them inside near the hole\n", checked,
           hole_fill);
    assert_true(checked > 1000 && hole_fill > 20);
    vv_volume_free(v);
    vv_shape_free(s);
    vv_mesh_free(m);
    vv_mesh_free(sphere);
}

static void
test_bad_input(void **state) {
    (void)state;
    vv_shape *s = NULL, *kids[3] = {NULL, NULL, NULL};
    vv_volume *v = NULL;
    vt_err(vv_shape_mesh_load(&s, "no/such/mesh.ply", VV_MESH_AUTO, 0));
    assert_null(s);
    char junk[256];
    snprintf(junk, sizeof junk, "%s/junk.ply", vt_outdir("modeling"));
    vt_write_file(junk, "ply\nformat garbage\n\x01\x02", 22);
    vt_err(vv_shape_mesh_load(&s, junk, VV_MESH_AUTO, 0));
    vt_err(vv_shape_sphere(&s, 0.0));
    assert_non_null(strstr(vv_error_message(), "radius"));
    vt_err(vv_shape_sphere(&s, NAN));
    vt_err(vv_shape_torus(&s, 5, 6));
    vt_err(vv_shape_box(&s, vv_vec3_make(1, 0, 1), 0));
    vt_err(vv_shape_box(&s, vv_vec3_make(1, 1, 1), 0.8));
    vt_err(vv_shape_cylinder(&s, 1, -2));
    double line[6] = {0, 0, 1, 1, 2, 2};
    vt_err(vv_shape_extrusion(&s, 3, line, 1));
    vt_err(vv_shape_revolution(&s, 2, line));
    double neg[6] = {-1, 0, 1, 0, 1, 1};
    vt_err(vv_shape_revolution(&s, 3, neg));
    vv_vec3 bent[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 1}};
    vt_err(vv_shape_polygon(&s, 4, bent, 0.1));
    /* a CSG tree with a missing child; the others are freed (ASan checks) */
    vt_ok(vv_shape_sphere(&kids[0], 1));
    vt_ok(vv_shape_sphere(&kids[2], 1));
    vt_err(vv_shape_csg(&s, VV_CSG_UNION, 3, kids));
    assert_non_null(strstr(vv_error_message(), "child 2 of 3 is missing"));
    assert_null(s);
    /* an absurd resolution */
    vt_ok(vv_shape_sphere(&s, 1));
    vv_voxelize_options o;
    vv_voxelize_options_init(&o);
    o.size = 100000;
    vt_err(vv_voxelize(&v, s, &o));
    assert_null(v);
    vv_voxelize_options_init(&o);
    o.voxel_spacing = 1e-5;
    vt_err(vv_voxelize(&v, s, &o));
    vv_voxelize_options_init(&o);
    o.dims[0] = o.dims[1] = o.dims[2] = 100000;
    o.spacing[0] = o.spacing[1] = o.spacing[2] = 1;
    vt_err(vv_voxelize(&v, s, &o));
    vv_voxelize_options_init(&o);
    o.size = 4; /* no room inside the margin */
    vt_err(vv_voxelize(&v, s, &o));
    vv_voxelize_options_init(&o);
    o.radius = 100;
    vt_err(vv_voxelize(&v, s, &o));
    vv_voxelize_options_init(&o);
    o.type = VV_I16;
    vt_err(vv_voxelize(&v, s, &o));
    /* a singular transform */
    vv_shape_transform(s, vv_mat4_scale(vv_vec3_make(1, 0, 1)));
    vv_voxelize_options_init(&o);
    o.dims[0] = o.dims[1] = o.dims[2] = 8;
    o.spacing[0] = o.spacing[1] = o.spacing[2] = 1;
    vt_err(vv_voxelize(&v, s, &o));
    vv_shape_free(s);
    /* a tree too deep to evaluate */
    vt_ok(vv_shape_sphere(&s, 1));
    for (int d = 0; d < 100000; d++) /* freed without recursion too */
        vt_ok(vv_shape_csg(&s, VV_CSG_UNION, 1, &s));
    vt_err(vv_voxelize(&v, s, NULL));
    assert_non_null(strstr(vv_error_message(), "deeper"));
    vv_shape_free(s);
    /* a mesh with a vertex at NaN: no crash, the rest voxelizes */
    vv_mesh *bad = NULL;
    vt_ok(vv_mesh_new(&bad));
    vt_ok(vv_mesh_add_vertex(bad, vv_vec3_make(0, 0, 0), NULL));
    vt_ok(vv_mesh_add_vertex(bad, vv_vec3_make(10, 0, 0), NULL));
    vt_ok(vv_mesh_add_vertex(bad, vv_vec3_make(0, 10, 0), NULL));
    vt_ok(vv_mesh_add_vertex(bad, vv_vec3_make(NAN, 0, 5), NULL));
    vt_ok(vv_mesh_add_triangle(bad, 0, 1, 2));
    vt_ok(vv_mesh_add_triangle(bad, 0, 1, 3));
    vt_ok(vv_shape_mesh(&s, bad, VV_MESH_SOLID, 0));
    vv_voxelize_options_init(&o);
    o.dims[0] = o.dims[1] = o.dims[2] = 16;
    o.spacing[0] = o.spacing[1] = o.spacing[2] = 1;
    o.origin[0] = o.origin[1] = o.origin[2] = -3;
    vt_ok(vv_voxelize(&v, s, &o));
    vv_volume_free(v);
    v = NULL;
    vv_shape_free(s);
    vv_mesh_free(bad);
    /* an empty intersection */
    vt_ok(vv_shape_sphere(&kids[0], 1));
    vt_ok(vv_shape_sphere(&kids[1], 1));
    vv_shape_transform(kids[1], vv_mat4_translate(vv_vec3_make(10, 0, 0)));
    vt_ok(vv_shape_csg(&s, VV_CSG_INTERSECTION, 2, kids));
    vt_err(vv_voxelize(&v, s, NULL));
    vv_shape_free(s);
}

static int
count_progress(void *user, double f) {
    double *last = user;
    assert_true(f >= *last - 1e-12 && f <= 1.0);
    *last = f;
    return 0;
}

static int
cancel_now(void *user, double f) {
    (void)user;
    (void)f;
    return 1;
}

static void
test_threads_progress(void **state) {
    (void)state;
    vv_shape *s = NULL;
    vt_ok(vv_shape_torus(&s, 30, 10));
    vv_voxelize_options o;
    vv_voxelize_options_init(&o);
    o.size = 96;
    o.threads = 1;
    vv_volume *a = vox(s, &o);
    o.threads = 4;
    double last = 0;
    o.progress = (vv_progress){count_progress, &last};
    vv_volume *b = vox(s, &o);
    assert_float_equal(last, 1.0, 0);
    assert_memory_equal(a->data, b->data, vv_volume_voxel_count(a));
    o.progress = (vv_progress){cancel_now, NULL};
    vv_volume *c = NULL;
    vv_status st = vv_voxelize(&c, s, &o);
    assert_int_equal(st, VV_ERR_CANCELLED);
    assert_null(c);
    vv_volume_free(a);
    vv_volume_free(b);
    vv_shape_free(s);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sampling_kernel_tables),
        cmocka_unit_test(test_sphere_radii),
        cmocka_unit_test(test_primitives),
        cmocka_unit_test(test_csg),
        cmocka_unit_test(test_meshes),
        cmocka_unit_test(test_imperfect_meshes),
        cmocka_unit_test(test_winding_number),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_threads_progress),
        cmocka_unit_test(test_world_objects),
    };
    return vt_run_tests(tests, NULL, NULL);
}
