/*
 * Tests of volumetric radiosity (src/render/radiosity).
 *
 * Analytic: the form factor between two parallel unit squares against the
 * closed form; a closed box that emits and reflects uniformly (the
 * "furnace") against B = E / (1 - rho); power conservation in a closed box
 * with no absorption, and power in = absorbed + escaped + unshot with it.
 * Independent method: Monte Carlo path tracers written here render a
 * small scene of two polygons under a point light, and a cube of uniform
 * fog beside one; the radiosity images agree within their noise. Hierarchy: the paper's Figure 6
 * scene (a voxelized sphere above a red polygon) at a small scale, hierarchical against
 * element-to-element (levels 1): the images within 30 dB with fewer interactions (the 10^4
 * reduction at 128^3 is measured by bench/bench_radiosity). Colour bleeding: a green polygon turns
 * the sphere's lower half green and its upper half far less. Bad input, the renderer's cache,
 * progress and cancel. Images go to build/test-out/radiosity.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RT_PI 3.14159265358979323846

static double t0_test;

/* ---------------------------------------------------------------------- */
/* scene helpers                                                            */

static vv_world *
new_world(void) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    w->background = vv_vec3_make(0, 0, 0);
    return w;
}

static vv_object *
add_polygon(vv_world *w, int n, const vv_vec3 *v, vv_vec3 color, double kd, double emission) {
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_POLYGON, "polygon"));
    vt_ok(vv_object_set_polygon(o, n, v));
    o->material.color = color;
    o->material.diffuse = kd;
    o->material.emission = vv_vec3_make(emission, emission, emission);
    vt_ok(vv_world_add_object(w, o));
    return o;
}

static vv_object *
add_box(vv_world *w, double kd, double emission) {
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_BOX, "box"));
    o->geometry.box.min = vv_vec3_make(0, 0, 0);
    o->geometry.box.max = vv_vec3_make(1, 1, 1);
    o->material.color = vv_vec3_make(1, 1, 1);
    o->material.diffuse = kd;
    o->material.emission = vv_vec3_make(emission, emission, emission);
    vt_ok(vv_world_add_object(w, o));
    return o;
}

static void
add_point_light(vv_world *w, vv_vec3 p, double intensity) {
    vv_light l;
    memset(&l, 0, sizeof l);
    l.type = VV_LIGHT_POINT;
    l.position = p;
    l.color = vv_vec3_make(1, 1, 1);
    l.intensity = intensity;
    vt_ok(vv_world_add_light(w, &l));
}

/* A voxelized sphere (u8 densities with a smooth edge, like the Modeling
 * component's) of n^3 voxels, centred at c, opaque inside, white. */
static vv_object *
add_sphere_volume(vv_world *w, int n, double radius, vv_vec3 c, double kd) {
    vv_volume *v = NULL;
    const int dims[3] = {n, n, n};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    double sp = 2.5 * radius / (n - 1);
    for (int a = 0; a < 3; a++)
        v->spacing[a] = sp;
    v->origin[0] = c.x - 0.5 * (n - 1) * sp;
    v->origin[1] = c.y - 0.5 * (n - 1) * sp;
    v->origin[2] = c.z - 0.5 * (n - 1) * sp;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double x = (i - 0.5 * (n - 1)) * sp, y = (j - 0.5 * (n - 1)) * sp,
                       z = (k - 0.5 * (n - 1)) * sp;
                double d = (radius - sqrt(x * x + y * y + z * z)) / (1.5 * sp);
                double f = 0.5 + d;
                f = f < 0 ? 0 : f > 1 ? 1 : f;
                vv_volume_set(v, i, j, k, 255 * f);
            }
    vv_volume_update_range(v);
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "sphere"));
    vv_volume_free(v);
    vv_tf_init(&o->tf);
    vt_ok(vv_tf_add_opacity(&o->tf, 76, 0));
    vt_ok(vv_tf_add_opacity(&o->tf, 153, 1));
    o->tf.opacity_unit_distance = sp;
    o->material.diffuse = kd;
    vt_ok(vv_world_add_object(w, o));
    return o;
}

static vv_view
make_view(vv_vec3 eye, vv_vec3 at, double fov_deg, int size) {
    vv_view v;
    memset(&v, 0, sizeof v);
    v.eye = eye;
    v.at = at;
    v.up = vv_vec3_make(0, 0, 1);
    v.fov = vv_deg_to_rad(fov_deg);
    v.projection = VV_PROJECTION_PERSPECTIVE;
    v.ortho_height = 1;
    v.width = v.height = size;
    return v;
}

static void
save(const vv_image *img, const char *name) {
    vt_ok(vv_image_write_png(img, vt_path(vt_outdir("radiosity"), name), 1, 0));
}

static double
sum3(const double *v) {
    return v[0] + v[1] + v[2];
}

/* ---------------------------------------------------------------------- */
/* form factor of two parallel unit squares                                 */

/* Closed form for two directly opposed parallel a x b rectangles at distance c. */
static double
ff_parallel(double a, double b, double c) {
    double X = a / c, Y = b / c;
    double x1 = sqrt(1 + X * X), y1 = sqrt(1 + Y * Y);
    return 2 / (RT_PI * X * Y) *
           (log(sqrt((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y))) + X * y1 * atan(X / y1) +
            Y * x1 * atan(Y / x1) - X * atan(X) - Y * atan(Y));
}

static double
solve_ff(double d, double error) {
    vv_world *w = new_world();
    const vv_vec3 a[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const vv_vec3 b[4] = {{0, 0, d}, {1, 0, d}, {1, 1, d}, {0, 1, d}};
    add_polygon(w, 4, a, vv_vec3_make(1, 1, 1), 0, 1); /* emits 1 from each side */
    add_polygon(w, 4, b, vv_vec3_make(1, 1, 1), 0, 0); /* black: absorbs all it gets */
    vv_radiosity_options o;
    vv_radiosity_options_init(&o);
    o.error = error;
    o.patch_size = 1.0 / 6;
    vv_radiosity *r = NULL;
    vt_ok(vv_radiosity_solve(&r, w, &o, NULL));
    double absorbed[3];
    vt_ok(vv_radiosity_object_power(r, 1, absorbed, NULL));
    vv_radiosity_free(r);
    vv_world_free(w);
    return absorbed[0]; /* the emitter's side facing B sends power 1 */
}

static void
test_form_factor(void **state) {
    (void)state;
    const double ds[3] = {0.5, 1, 2};
    for (int i = 0; i < 3; i++) {
        double exact = ff_parallel(1, 1, ds[i]);
        double finest = solve_ff(ds[i], 0);
        double hier = solve_ff(ds[i], 1e-4);
        printf("# d %g: F exact %.5f, element to element %.5f (%.3f %%), hierarchical %.5f "
               "(%.3f %%)\n",
               ds[i], exact, finest, 100 * (finest / exact - 1), hier, 100 * (hier / exact - 1));
        assert_near(finest / exact, 1, 0.01);
        assert_near(hier / exact, 1, 0.01);
    }
}

/* ---------------------------------------------------------------------- */
/* furnace and energy                                                       */

static void
test_furnace(void **state) {
    (void)state;
    vv_world *w = new_world();
    const double E = 1, rho = 0.5;
    add_box(w, rho, E);
    vv_radiosity_options o;
    vv_radiosity_options_init(&o);
    o.tolerance = 1e-3;
    o.patch_size = 0.25;
    vv_radiosity *r = NULL;
    vt_ok(vv_radiosity_solve(&r, w, &o, NULL));
    vv_radiosity_stats st;
    vv_radiosity_get_stats(r, &st);
    assert_true(st.converged);
    const vv_vec3 c = vv_vec3_make(0.5, 0.5, 0.5);
    const vv_vec3 pts[5] = {
        {0.5, 0.5, 0}, {0.05, 0.05, 0}, {1, 0.5, 0.9}, {0.3, 1, 0.7}, {0.9, 0.1, 1}};
    double worst = 0;
    for (int i = 0; i < 5; i++) {
        double b_in[3], b_out[3];
        vt_ok(vv_radiosity_patch_at(r, 0, pts[i], vv_vec3_sub(c, pts[i]), b_in));
        vt_ok(vv_radiosity_patch_at(r, 0, pts[i], vv_vec3_sub(pts[i], c), b_out));
        double err = fabs(b_in[0] / (E / (1 - rho)) - 1);
        printf("# furnace point %d: inside %.4f outside %.4f\n", i, b_in[0], b_out[0]);
        worst = err > worst ? err : worst;
        assert_near(b_out[0], E, 1e-6); /* outside: emission only */
    }
    printf("# furnace: %d patches, %d shots, worst inside radiosity error %.4f %%\n", st.n_patches,
           st.n_shots, 100 * worst);
    assert_true(worst < 0.01);
    vv_radiosity_free(r);
    vv_world_free(w);
}

static void
test_energy(void **state) {
    (void)state;
    /* closed, nothing absorbed: a white box with reflectance 1, a light inside */
    vv_world *w = new_world();
    add_box(w, 1, 0);
    add_point_light(w, vv_vec3_make(0.4, 0.5, 0.6), 1);
    vv_radiosity_options o;
    vv_radiosity_options_init(&o);
    o.patch_size = 0.25;
    o.max_shots = 300; /* it never converges: the cap stops it */
    vv_radiosity *r = NULL;
    vt_ok(vv_radiosity_solve(&r, w, &o, NULL));
    vv_radiosity_stats st;
    vv_radiosity_get_stats(r, &st);
    double pin = sum3(st.power_in);
    printf("# closed box, rho 1: power in %.6g, unshot %.6g, escaped %.3g, absorbed %.3g after "
           "%d shots\n",
           pin, sum3(st.power_unshot), sum3(st.power_escaped), sum3(st.power_absorbed), st.n_shots);
    assert_false(st.converged);
    assert_int_equal(st.n_shots, 300);
    assert_near(sum3(st.power_absorbed), 0, 1e-9 * pin);
    assert_near(sum3(st.power_unshot) / pin, 1, 1e-3);
    vv_radiosity_free(r);
    vv_world_free(w);

    /* with absorption: a floor, a voxelized sphere, a light */
    w = new_world();
    const vv_vec3 f[4] = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
    add_polygon(w, 4, f, vv_vec3_make(0.9, 0.5, 0.2), 0.8, 0);
    add_sphere_volume(w, 20, 0.8, vv_vec3_make(0, 0, 1), 0.7);
    add_point_light(w, vv_vec3_make(1, -1, 4), 10);
    vv_radiosity_options_init(&o);
    vt_ok(vv_radiosity_solve(&r, w, &o, NULL));
    vv_radiosity_get_stats(r, &st);
    pin = sum3(st.power_in);
    double out = sum3(st.power_absorbed) + sum3(st.power_escaped) + sum3(st.power_unshot);
    printf("# floor and sphere: in %.6g = absorbed %.6g + escaped %.6g + unshot %.6g (%.2g)\n", pin,
           sum3(st.power_absorbed), sum3(st.power_escaped), sum3(st.power_unshot), out / pin - 1);
    assert_true(st.converged);
    assert_true(sum3(st.power_absorbed) > 0);
    for (int c = 0; c < 3; c++)
        assert_near(st.power_absorbed[c] + st.power_escaped[c] + st.power_unshot[c], st.power_in[c],
                    1e-6 * st.power_in[c]);
    vv_radiosity_free(r);
    /* the same on a coarser radiosity grid than the volume (10 for 20) */
    o.grid = 10;
    vt_ok(vv_radiosity_solve(&r, w, &o, NULL));
    vv_radiosity_stats sc;
    vv_radiosity_get_stats(r, &sc);
    printf("# grid 10: %d voxel elements (%d at 20), absorbed %.6g\n", sc.n_voxels, st.n_voxels,
           sum3(sc.power_absorbed));
    assert_true(sc.converged);
    assert_true(sc.n_voxels > 0 && 3 * sc.n_voxels < st.n_voxels);
    assert_near(sum3(sc.power_absorbed) / sum3(st.power_absorbed), 1, 0.1);
    for (int c = 0; c < 3; c++)
        assert_near(sc.power_absorbed[c] + sc.power_escaped[c] + sc.power_unshot[c], sc.power_in[c],
                    1e-6 * sc.power_in[c]);
    vv_radiosity_free(r);
    vv_world_free(w);
}

/* ---------------------------------------------------------------------- */
/* an independent Monte Carlo path tracer                                    */

typedef struct mc_quad {
    vv_vec3 o, u, v, n; /* corner, edges, unit normal */
    vv_vec3 rho;
} mc_quad;

static uint64_t
mc_next(uint64_t *s) {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static double
mc_rand(uint64_t *s) {
    return (double)(mc_next(s) >> 11) / 9007199254740992.0;
}

static int
mc_hit(const mc_quad *q, int nq, vv_vec3 o, vv_vec3 d, double tmax, double *th) {
    int best = -1;
    *th = tmax;
    for (int i = 0; i < nq; i++) {
        double dn = vv_vec3_dot(d, q[i].n);
        if (fabs(dn) < 1e-12)
            continue;
        double t = vv_vec3_dot(vv_vec3_sub(q[i].o, o), q[i].n) / dn;
        if (!(t > 1e-7 && t < *th))
            continue;
        vv_vec3 p = vv_vec3_sub(vv_vec3_add(o, vv_vec3_scale(d, t)), q[i].o);
        double a = vv_vec3_dot(p, q[i].u) / vv_vec3_dot(q[i].u, q[i].u);
        double b = vv_vec3_dot(p, q[i].v) / vv_vec3_dot(q[i].v, q[i].v);
        if (a < 0 || a > 1 || b < 0 || b > 1)
            continue;
        *th = t;
        best = i;
    }
    return best;
}

/* Radiosity (display value) leaving point x of quad qi towards the side
 * the ray came from (direction d arriving), one path. */
static void
mc_radiosity(const mc_quad *q, int nq, int qi, vv_vec3 x, vv_vec3 d, vv_vec3 light, double I,
             int depth, uint64_t *rng, double out[3]) {
    vv_vec3 n = q[qi].n;
    if (vv_vec3_dot(n, d) > 0)
        n = vv_vec3_scale(n, -1); /* the side facing the incoming ray */
    double e = 0;
    vv_vec3 l = vv_vec3_sub(light, x);
    double ll = vv_vec3_length(l);
    l = vv_vec3_scale(l, 1 / ll);
    double cl = vv_vec3_dot(n, l), th;
    if (cl > 0 && mc_hit(q, nq, x, l, ll, &th) < 0)
        e = I * cl / (ll * ll);
    double ind[3] = {0, 0, 0};
    if (depth > 0) {
        /* cosine-weighted: E_indirect = pi * mean L = mean B */
        double u1 = mc_rand(rng), u2 = mc_rand(rng);
        double rr = sqrt(u1), ph = 2 * RT_PI * u2;
        vv_vec3 t = fabs(n.x) < 0.9 ? vv_vec3_make(1, 0, 0) : vv_vec3_make(0, 1, 0);
        t = vv_vec3_normalize(vv_vec3_cross(n, t));
        vv_vec3 b = vv_vec3_cross(n, t);
        vv_vec3 dir = vv_vec3_add(
            vv_vec3_scale(n, sqrt(1 - u1)),
            vv_vec3_add(vv_vec3_scale(t, rr * cos(ph)), vv_vec3_scale(b, rr * sin(ph))));
        int h = mc_hit(q, nq, x, dir, INFINITY, &th);
        if (h >= 0)
            mc_radiosity(q, nq, h, vv_vec3_add(x, vv_vec3_scale(dir, th)), dir, light, I, depth - 1,
                         rng, ind);
    }
    const double *rho = &q[qi].rho.x;
    for (int c = 0; c < 3; c++)
        out[c] = rho[c] * (e + ind[c]);
}

static void
test_monte_carlo(void **state) {
    (void)state;
    const vv_vec3 floor_v[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const vv_vec3 wall_v[4] = {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}};
    const vv_vec3 floor_c = {1, 1, 1}, wall_c = {0.9, 0.15, 0.1};
    const double kd_floor = 0.75, kd_wall = 0.9;
    const vv_vec3 light = {0.5, 0.25, 0.9};
    const double I = 0.45;
    vv_world *w = new_world();
    add_polygon(w, 4, floor_v, floor_c, kd_floor, 0);
    add_polygon(w, 4, wall_v, wall_c, kd_wall, 0);
    add_point_light(w, light, I);
    vv_radiosity_options o;
    vv_radiosity_options_init(&o);
    o.patch_size = 1.0 / 40;
    o.tolerance = 1e-4;
    vv_radiosity *r = NULL;
    vt_ok(vv_radiosity_solve(&r, w, &o, NULL));
    const int S = 40;
    vv_view v = make_view(vv_vec3_make(0.5, -1.3, 0.75), vv_vec3_make(0.5, 0.5, 0.35), 40, S);
    vv_image *ra = NULL, *mc = NULL;
    vt_ok(vv_image_new(&ra, S, S));
    vt_ok(vv_image_new(&mc, S, S));
    vt_ok(vv_radiosity_view_frame(r, w, &v, 0, ra));

    mc_quad q[2];
    q[0].o = floor_v[0];
    q[0].u = vv_vec3_sub(floor_v[1], floor_v[0]);
    q[0].v = vv_vec3_sub(floor_v[3], floor_v[0]);
    q[0].rho = vv_vec3_scale(floor_c, kd_floor);
    q[1].o = wall_v[0];
    q[1].u = vv_vec3_sub(wall_v[1], wall_v[0]);
    q[1].v = vv_vec3_sub(wall_v[3], wall_v[0]);
    q[1].rho = vv_vec3_scale(wall_c, kd_wall);
    for (int i = 0; i < 2; i++)
        q[i].n = vv_vec3_normalize(vv_vec3_cross(q[i].u, q[i].v));
    const int paths = 200;
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++) {
            uint64_t rng = 0x9E3779B97F4A7C15ull ^ (uint64_t)(y * S + x + 1) * 2654435761ull;
            vv_ray ray = vv_view_ray(&v, x, y);
            double th;
            int h = mc_hit(q, 2, ray.origin, ray.dir, INFINITY, &th);
            double acc[3] = {0, 0, 0};
            if (h >= 0) {
                vv_vec3 p = vv_vec3_add(ray.origin, vv_vec3_scale(ray.dir, th));
                for (int k = 0; k < paths; k++) {
                    double b[3];
                    mc_radiosity(q, 2, h, p, ray.dir, light, I, 4, &rng, b);
                    for (int c = 0; c < 3; c++)
                        acc[c] += b[c] / paths;
                }
            }
            float *px = &mc->rgba[4 * (y * S + x)];
            for (int c = 0; c < 3; c++)
                px[c] = (float)acc[c];
            px[3] = h >= 0;
        }
    save(ra, "mc_radiosity.png");
    save(mc, "mc_path_traced.png");
    double psnr = vv_image_psnr(ra, mc);
    double peak = 0;
    for (int i = 0; i < S * S; i++)
        peak = fmax(peak, mc->rgba[4 * i]);
    printf("# Monte Carlo (%d paths a pixel) vs radiosity: PSNR %.2f dB (peak red %.2f)\n", paths,
           psnr, peak);
    assert_true(peak > 0.5); /* the comparison is not of two black images */
    assert_true(psnr >= 30);
    vv_image_free(ra);
    vv_image_free(mc);
    vv_radiosity_free(r);
    vv_world_free(w);
}

/* The same for a participating medium: a cube of uniform fog (isotropic
 * scattering, albedo 0.8, optical depth 2 across) beside a point light,
 * path traced with free flights and next-event estimation. */
static double
fog_tau(vv_vec3 o, vv_vec3 d, double tmax, vv_box b, double sigma) {
    vv_ray r = {o, d};
    double a, e;
    if (!vv_box_intersect_ray(b, r, &a, &e))
        return 0;
    a = a > 0 ? a : 0;
    e = e < tmax ? e : tmax;
    return e > a ? sigma * (e - a) : 0;
}

static void
test_monte_carlo_fog(void **state) {
    (void)state;
    const int n = 12;
    const double sigma = 2, albedo = 0.8, I = 6;
    const vv_vec3 light = {1.6, -0.6, 1.5};
    vv_world *w = new_world();
    vv_volume *v = NULL;
    const int dims[3] = {n, n, n};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    const double sp = 1.0 / n;
    for (int a = 0; a < 3; a++) {
        v->spacing[a] = sp;
        v->origin[a] = 0.5 * sp; /* cells fill [0, 1]^3 */
    }
    memset(v->data, 200, (size_t)n * n * n);
    vv_volume_update_range(v);
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "fog"));
    vv_volume_free(v);
    vv_tf_init(&o->tf);
    o->tf.opacity_unit_distance = 1;
    vt_ok(vv_tf_add_opacity(&o->tf, 0, 1 - exp(-sigma)));
    o->material.diffuse = albedo;
    vt_ok(vv_world_add_object(w, o));
    add_point_light(w, light, I);
    vv_radiosity_options ro;
    vv_radiosity_options_init(&ro);
    ro.diffuse_voxels = 0;
    ro.tolerance = 1e-4;
    vv_radiosity *r = NULL;
    vt_ok(vv_radiosity_solve(&r, w, &ro, NULL));
    const int S = 40;
    vv_view view = make_view(vv_vec3_make(0.5, -2.6, 1.4), vv_vec3_make(0.5, 0.5, 0.5), 35, S);
    vv_image *ra = NULL, *mc = NULL;
    vt_ok(vv_image_new(&ra, S, S));
    vt_ok(vv_image_new(&mc, S, S));
    vt_ok(vv_radiosity_view_frame(r, w, &view, 0, ra));
    const vv_box box = {{0, 0, 0}, {1, 1, 1}};
    const int paths = 300;
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++) {
            uint64_t rng = 0x2545F4914F6CDD1Dull ^ (uint64_t)(y * S + x + 1) * 2654435761ull;
            vv_ray ray = vv_view_ray(&view, x, y);
            double acc = 0, hit = 0;
            for (int k = 0; k < paths; k++) {
                vv_vec3 p = ray.origin, d = ray.dir;
                double wgt = 1;
                for (int depth = 0; depth < 40; depth++) {
                    vv_ray rr = {p, d};
                    double a, e;
                    if (!vv_box_intersect_ray(box, rr, &a, &e) || e <= 0)
                        break;
                    a = a > 0 ? a : 0;
                    double t = a - log(1 - mc_rand(&rng)) / sigma;
                    if (t >= e)
                        break; /* flew through */
                    if (depth == 0)
                        hit = 1;
                    p = vv_vec3_add(p, vv_vec3_scale(d, t));
                    wgt *= albedo;
                    /* next event: the light, attenuated to the box's edge */
                    vv_vec3 l = vv_vec3_sub(light, p);
                    double ll = vv_vec3_length(l);
                    l = vv_vec3_scale(l, 1 / ll);
                    acc += wgt * I / (ll * ll) * exp(-fog_tau(p, l, ll, box, sigma)) / (4 * RT_PI);
                    /* isotropic scattering */
                    double cz = 1 - 2 * mc_rand(&rng), ph = 2 * RT_PI * mc_rand(&rng);
                    double sz = sqrt(1 - cz * cz);
                    d = vv_vec3_make(sz * cos(ph), sz * sin(ph), cz);
                }
            }
            float *px = &mc->rgba[4 * (y * S + x)];
            for (int c = 0; c < 3; c++)
                px[c] = (float)(RT_PI * acc / paths); /* display units: pi x radiance */
            px[3] = (float)hit;
        }
    save(ra, "fog_radiosity.png");
    save(mc, "fog_path_traced.png");
    double psnr = vv_image_psnr(ra, mc), peak = 0, mr = 0, mm = 0;
    for (int i = 0; i < S * S; i++) {
        peak = fmax(peak, mc->rgba[4 * i]);
        mr += ra->rgba[4 * i];
        mm += mc->rgba[4 * i];
    }
    printf("# fog cube: Monte Carlo (%d paths a pixel) vs radiosity: PSNR %.2f dB, peak %.2f, "
           "mean radiosity / path traced %.4f\n",
           paths, psnr, peak, mr / mm);
    assert_true(peak > 0.3);
    assert_true(psnr >= 30);
    vv_image_free(ra);
    vv_image_free(mc);
    vv_radiosity_free(r);
    vv_world_free(w);
}

/* ---------------------------------------------------------------------- */
/* Figure 6 at a small scale (20^3): hierarchy and colour bleeding                   */

static vv_world *
figure6(int n, vv_vec3 floor_color) {
    vv_world *w = new_world();
    const vv_vec3 f[4] = {{-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}};
    add_polygon(w, 4, f, floor_color, 0.9, 0);
    add_sphere_volume(w, n, 1, vv_vec3_make(0, 0, 1.35), 0.8);
    add_point_light(w, vv_vec3_make(2.5, -2.5, 6), 60);
    return w;
}

/* Mean colour of the sphere's upper and lower halves (rows above and below
 * its centre) in a horizontal orthographic view. */
static void
halves(const vv_image *img, double up[3], double lo[3]) {
    const int S = img->width;
    int nu = 0, nl = 0;
    for (int c = 0; c < 3; c++)
        up[c] = lo[c] = 0;
    for (int y = 0; y < S; y++)
        for (int x = S / 2 - S / 8; x < S / 2 + S / 8; x++) {
            const float *p = &img->rgba[4 * (y * S + x)];
            double dy = (y + 0.5 - S / 2.0) / (S / 2.0); /* sphere radius = half the view */
            if (p[3] < 0.99)
                continue;
            if (dy < -0.3 && dy > -0.9) {
                for (int c = 0; c < 3; c++)
                    up[c] += p[c];
                nu++;
            } else if (dy > 0.3 && dy < 0.9) {
                for (int c = 0; c < 3; c++)
                    lo[c] += p[c];
                nl++;
            }
        }
    assert_true(nu > 10 && nl > 10);
    for (int c = 0; c < 3; c++) {
        up[c] /= nu;
        lo[c] /= nl;
    }
}

static vv_view
figure6_view(int S) {
    vv_view v = make_view(vv_vec3_make(0, -10, 1.35), vv_vec3_make(0, 0, 1.35), 30, S);
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    v.ortho_height = 2.0;
    return v;
}

static void
test_hierarchy(void **state) {
    (void)state;
    vv_world *w = figure6(20, vv_vec3_make(0.95, 0.1, 0.1));
    vv_radiosity_options o;
    vv_radiosity_options_init(&o);
    o.patch_size = 0.6;
    vv_radiosity *hier = NULL, *fine = NULL;
    vt_ok(vv_radiosity_solve(&hier, w, &o, NULL));
    o.levels = 1; /* every interaction between single elements */
    vt_ok(vv_radiosity_solve(&fine, w, &o, NULL));
    vv_radiosity_stats sh, sf;
    vv_radiosity_get_stats(hier, &sh);
    vv_radiosity_get_stats(fine, &sf);
    const int S = 96;
    vv_view v = make_view(vv_vec3_make(0, -8, 3.5), vv_vec3_make(0, 0, 1), 35, S);
    vv_image *a = NULL, *b = NULL;
    vt_ok(vv_image_new(&a, S, S));
    vt_ok(vv_image_new(&b, S, S));
    vt_ok(vv_radiosity_view_frame(hier, w, &v, 0, a));
    vt_ok(vv_radiosity_view_frame(fine, w, &v, 0, b));
    save(a, "figure6_hierarchical.png");
    save(b, "figure6_finest.png");
    double psnr = vv_image_psnr(a, b);
    printf("# Figure 6 at 20^3: %d voxels + %d patches; interactions hierarchical %.4g, finest "
           "%.4g (%.1fx fewer), pairwise %.4g (%.0fx); PSNR %.2f dB\n",
           sh.n_voxels, sh.n_patches, sh.interactions, sf.interactions,
           sf.interactions / sh.interactions, sh.pairwise, sh.pairwise / sh.interactions, psnr);
    assert_true(psnr >= 30);
    assert_true(sf.interactions >= 10 * sh.interactions);
    assert_true(sh.pairwise >= 100 * sh.interactions);
    vv_image_free(a);
    vv_image_free(b);
    vv_radiosity_free(hier);
    vv_radiosity_free(fine);
    vv_world_free(w);
}

static void
test_colour_bleeding(void **state) {
    (void)state;
    double up[2][3], lo[2][3];
    const vv_vec3 colors[2] = {{0.95, 0.1, 0.1}, {0.1, 0.95, 0.1}};
    const int S = 64;
    for (int i = 0; i < 2; i++) {
        vv_world *w = figure6(32, colors[i]);
        vv_radiosity *r = NULL;
        vt_ok(vv_radiosity_solve(&r, w, NULL, NULL));
        vv_view v = figure6_view(S);
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, S, S));
        vt_ok(vv_radiosity_view_frame(r, w, &v, 0, img));
        save(img, i ? "bleeding_green.png" : "bleeding_red.png");
        halves(img, up[i], lo[i]);
        vv_image_free(img);
        vv_radiosity_free(r);
        vv_world_free(w);
    }
    printf("# lower half red floor (%.3f %.3f %.3f) green floor (%.3f %.3f %.3f); upper half "
           "(%.3f %.3f %.3f) -> (%.3f %.3f %.3f)\n",
           lo[0][0], lo[0][1], lo[0][2], lo[1][0], lo[1][1], lo[1][2], up[0][0], up[0][1], up[0][2],
           up[1][0], up[1][1], up[1][2]);
    /* the lower half turns from red to green */
    assert_true(lo[0][0] > 1.5 * lo[0][1]);
    assert_true(lo[1][1] > 1.5 * lo[1][0]);
    double dlo = fabs(lo[1][1] - lo[0][1]) + fabs(lo[1][0] - lo[0][0]);
    double dup = fabs(up[1][1] - up[0][1]) + fabs(up[1][0] - up[0][0]);
    assert_true(dlo > 0.05);
    assert_true(dup < 0.25 * dlo);
}

/* ---------------------------------------------------------------------- */
/* bad input, the renderer, progress                                          */

static void
test_bad_input(void **state) {
    (void)state;
    const vv_vec3 f[4] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    vv_radiosity *r = NULL;
    /* reflectance above 1 and below 0 */
    vv_world *w = new_world();
    vv_object *p = add_polygon(w, 4, f, vv_vec3_make(1, 1, 1), 1.5, 0);
    add_point_light(w, vv_vec3_make(0, 0, 2), 1);
    vt_err(vv_radiosity_solve(&r, w, NULL, NULL));
    assert_non_null(strstr(vv_error_message(), "reflectance"));
    assert_null(r);
    p->material.diffuse = -0.2;
    vt_err(vv_radiosity_solve(&r, w, NULL, NULL));
    p->material.diffuse = 0.5;
    p->material.emission.y = NAN;
    vt_err(vv_radiosity_solve(&r, w, NULL, NULL));
    p->material.emission.y = 0;
    /* an emitter with NaN power */
    w->lights[0].intensity = NAN;
    vt_err(vv_radiosity_solve(&r, w, NULL, NULL));
    assert_non_null(strstr(vv_error_message(), "light 0"));
    /* no emitter: only a headlight */
    w->lights[0].intensity = 1;
    w->lights[0].headlight = 1;
    vt_err(vv_radiosity_solve(&r, w, NULL, NULL));
    assert_non_null(strstr(vv_error_message(), "no emitter"));
    /* the renderer says the same */
    vv_renderer *rr = NULL;
    vt_ok(vv_renderer_new(&rr, "radiosity"));
    vv_image *img = NULL;
    vv_view v = make_view(vv_vec3_make(0, -4, 2), vv_vec3_make(0, 0, 0), 40, 16);
    vt_ok(vv_image_new(&img, 16, 16));
    vt_err(vv_renderer_render(rr, w, &v, NULL, img));
    vt_err(vv_renderer_set_option(rr, "tolerance", "2"));
    vt_err(vv_renderer_set_option(rr, "grid", "1"));
    vt_err(vv_renderer_set_option(rr, "bogus", "1"));
    vt_err(vv_renderer_set_option(rr, "error", "nan"));
    /* a hierarchy deeper than the volume */
    w->lights[0].headlight = 0;
    add_sphere_volume(w, 16, 0.5, vv_vec3_make(0, 0, 1), 0.5);
    vv_radiosity_options o;
    vv_radiosity_options_init(&o);
    o.levels = 12;
    vt_err(vv_radiosity_solve(&r, w, &o, NULL));
    assert_non_null(strstr(vv_error_message(), "levels"));
    o.levels = 5; /* 16 voxels: 5 levels */
    vt_ok(vv_radiosity_solve(&r, w, &o, NULL));
    vv_radiosity_free(r);
    vv_image_free(img);
    vv_renderer_free(rr);
    vv_world_free(w);
}

static int
cancel_at(void *user, double f) {
    int *calls = user;
    (*calls)++;
    return f >= 0 && *calls > 2;
}

static void
test_renderer_cache_and_cancel(void **state) {
    (void)state;
    vv_world *w = figure6(20, vv_vec3_make(0.95, 0.1, 0.1));
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "radiosity"));
    const int S = 48;
    vv_view v1 = make_view(vv_vec3_make(0, -8, 3.5), vv_vec3_make(0, 0, 1), 35, S);
    vv_view v2 = v1;
    vv_view_orbit(&v2, vv_deg_to_rad(40), 0);
    vv_image *a = NULL, *b = NULL, *c = NULL;
    vt_ok(vv_image_new(&a, S, S));
    vt_ok(vv_image_new(&b, S, S));
    vt_ok(vv_image_new(&c, S, S));
    vt_ok(vv_renderer_render(r, w, &v1, NULL, a));
    vt_ok(vv_renderer_render(r, w, &v2, NULL, b)); /* reuses the solution */
    vt_ok(vv_renderer_render(r, w, &v1, NULL, c));
    assert_memory_equal(a->rgba, c->rgba, sizeof(float) * 4 * S * S);
    /* the same as a fresh solution of that view */
    vv_radiosity *sol = NULL;
    vt_ok(vv_radiosity_solve(&sol, w, NULL, NULL));
    vt_ok(vv_radiosity_view_frame(sol, w, &v2, 0, c));
    assert_memory_equal(b->rgba, c->rgba, sizeof(float) * 4 * S * S);
    vv_radiosity_free(sol);
    /* a changed colour is a new solution */
    w->objects[0]->material.color = vv_vec3_make(0.1, 0.95, 0.1);
    vt_ok(vv_renderer_render(r, w, &v1, NULL, c));
    assert_true(vv_image_psnr(a, c) < 40);
    /* cancel */
    int calls = 0;
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.progress.fn = cancel_at;
    opt.progress.user = &calls;
    w->objects[0]->material.color = vv_vec3_make(0.5, 0.5, 0.9);
    vv_error_clear();
    assert_int_equal(vv_renderer_render(r, w, &v1, &opt, c), VV_ERR_CANCELLED);
    assert_non_null(strstr(vv_error_message(), "unshot"));
    vv_image_free(a);
    vv_image_free(b);
    vv_image_free(c);
    vv_renderer_free(r);
    vv_world_free(w);
}

static void
test_scene_emission(void **state) {
    (void)state;
    const char *dir = vt_outdir("radiosity");
    const char *path = vt_path(dir, "emission.json");
    const char *json =
        "{\"objects\": [{\"name\": \"lamp\", \"type\": \"polygon\", \"vertices\": [[0,0,0],[1,0,0],"
        "[1,1,0]], \"material\": {\"diffuse\": 0, \"emission\": [2, 1, 0.5]}}]}";
    vt_write_file(path, json, strlen(json));
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, path));
    assert_near(w->objects[0]->material.emission.x, 2, 0);
    assert_near(w->objects[0]->material.emission.z, 0.5, 0);
    const char *saved = vt_path(dir, "emission_saved.json");
    vt_ok(vv_scene_save(w, saved, NULL));
    vv_world *w2 = NULL;
    vt_ok(vv_scene_load(&w2, saved));
    assert_near(w2->objects[0]->material.emission.y, 1, 0);
    /* the emitting triangle alone: radiated power = 2 sides x area x emission */
    vv_radiosity *r = NULL;
    vt_ok(vv_radiosity_solve(&r, w2, NULL, NULL));
    double rad[3];
    vt_ok(vv_radiosity_object_power(r, 0, NULL, rad));
    assert_near(rad[0], 2 * 0.5 * 2, 1e-5);
    vv_radiosity_free(r);
    vv_world_free(w);
    vv_world_free(w2);
    const char *bad = "{\"objects\": [{\"type\": \"polygon\", \"vertices\": [[0,0,0],[1,0,0],"
                      "[1,1,0]], \"material\": {\"emission\": [1, -1, 0]}}]}";
    vt_write_file(path, bad, strlen(bad));
    vt_err(vv_scene_load(&w, path));
    assert_non_null(strstr(vv_error_message(), "emission"));
}

static int
setup_timer(void **state) {
    (void)state;
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    t0_test = t.tv_sec + 1e-9 * t.tv_nsec;
    return 0;
}

static int
teardown_timer(void **state) {
    (void)state;
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    printf("# (%.2f s)\n", t.tv_sec + 1e-9 * t.tv_nsec - t0_test);
    return 0;
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_form_factor, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_furnace, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_energy, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_monte_carlo, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_monte_carlo_fog, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_hierarchy, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_colour_bleeding, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_bad_input, setup_timer, teardown_timer),
        cmocka_unit_test_setup_teardown(test_renderer_cache_and_cancel, setup_timer,
                                        teardown_timer),
        cmocka_unit_test_setup_teardown(test_scene_emission, setup_timer, teardown_timer),
    };
    return vt_run_tests(tests, NULL, NULL);
}
