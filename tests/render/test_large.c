/*
 * A volume of several hundred MB renders: 640 x 640 x 384 u16 (300 MiB),
 * anisotropic spacing, an ellipsoid with a known silhouette. Rendered with
 * cached gradients and again with gradients computed on the fly (the path
 * taken when memory is short); the two must agree, and the silhouette must
 * have the analytic size. Not built under the sanitizers (tests/CMakeLists.txt:
 * ASan's shadow memory would triple the footprint of a test meant for real
 * sizes); the release suite runs it.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

enum { NX = 640, NY = 640, NZ = 384, IMG = 96 };

static vv_volume *
make_ellipsoid(void) {
    const int dims[3] = {NX, NY, NZ};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U16));
    v->spacing[0] = 0.5;
    v->spacing[1] = 0.5;
    v->spacing[2] = 0.8;
    uint16_t *d = v->data;
    /* semi-axes in world units: 140 x 140 x 130 (mm) */
#pragma omp parallel for schedule(static)
    for (int k = 0; k < NZ; k++)
        for (int j = 0; j < NY; j++)
            for (int i = 0; i < NX; i++) {
                double x = (i - (NX - 1) / 2.0) * 0.5 / 140.0;
                double y = (j - (NY - 1) / 2.0) * 0.5 / 140.0;
                double z = (k - (NZ - 1) / 2.0) * 0.8 / 130.0;
                double r = sqrt(x * x + y * y + z * z);
                double val = 2000.0 * (1.2 - r);
                d[((size_t)k * NY + (size_t)j) * NX + (size_t)i] = (uint16_t)(val < 0      ? 0
                                                                              : val > 2000 ? 2000
                                                                                           : val);
            }
    vv_volume_update_range(v);
    return v;
}

static void
test_large_volume(void **state) {
    (void)state;
    vv_volume *v = make_ellipsoid();
    assert_true(vv_volume_voxel_count(v) * 2 >= 300u * 1048576u);
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = IMG;
    o.mode = VV_MODE_ISO;
    o.has_isovalue = 1;
    o.isovalue = 400; /* r = 1: the ellipsoid surface */
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    /* orthographic along z: the silhouette is the 140 x 140 mm ellipse */
    w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    w->view.eye = vv_vec3_make(0, 0, 1000);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.up = vv_vec3_make(0, 1, 0);
    w->view.ortho_height = 320;

    vv_renderer *cached = NULL, *fly = NULL;
    vt_ok(vv_renderer_new(&cached, "raycast"));
    vt_ok(vv_renderer_new(&fly, "raycast"));
    vt_ok(vv_renderer_set_option(fly, "gradient_budget_mb", "0"));
    vv_image *a = NULL, *b = NULL;
    vt_ok(vv_image_new(&a, IMG, IMG));
    vt_ok(vv_image_new(&b, IMG, IMG));
    vt_ok(vv_renderer_render(cached, w, &w->view, NULL, a));
    vt_ok(vv_renderer_render(fly, w, &w->view, NULL, b));

    int hits = 0;
    for (int p = 0; p < IMG * IMG; p++)
        hits += a->rgba[4 * p + 3] > 0.5f;
    const double pix = 320.0 / IMG; /* world units per pixel */
    const double expect = VV_PI * 140.0 * 140.0 / (pix * pix);
    double psnr = vv_image_psnr(a, b);
    print_message("300 MiB volume: silhouette %d pixels (expected %.1f), cached vs on-the-fly "
                  "gradients %.1f dB\n",
                  hits, expect, psnr);
    assert_true(fabs(hits - expect) / expect < 0.03);
    assert_true(psnr >= 30);
    char path[1200];
    snprintf(path, sizeof path, "%s/large_ellipsoid.png", vt_outdir("render"));
    vt_ok(vv_image_write_png(a, path, 1.0, 0));
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(cached);
    vv_renderer_free(fly);
    vv_world_free(w);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_large_volume),
    };
    return vt_run_tests(tests, NULL, NULL);
}
