/*
 * Helpers shared by the splatting renderer's tests (test_splat.c,
 * test_splat_agree.c): rendering, images, volumes, the default scene, and
 * agreement with the ray caster. Static, for inclusion by one test file.
 */
#ifndef VV_TEST_SPLAT_COMMON_H
#define VV_TEST_SPLAT_COMMON_H

#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/splat/splat.h"

#define VT_UNUSED __attribute__((unused))

/* ---------------------------------------------------------------------- */
/* Helpers                                                                  */

VT_UNUSED static vv_renderer *
new_r(const char *name) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, name));
    return r;
}

VT_UNUSED static vv_image *
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

VT_UNUSED static vv_image *
render(vv_renderer *r, const vv_world *w) {
    return render_q(r, w, &w->view, 0, 2);
}

VT_UNUSED static void
write_png(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.png", vt_outdir("render_splat"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* Mean absolute difference of the 8-bit RGB conversions (0..255). */
VT_UNUSED static double
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

VT_UNUSED static vv_volume *
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
VT_UNUSED static vv_volume *
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
VT_UNUSED static vv_world *
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

/* Renders w with both methods in @p mode, writes both images, returns the
 * PSNR. Projections get a grey ramp over the volume's range, opaque. */
VT_UNUSED static double
agreement_with(vv_renderer *rc, vv_renderer *sp, vv_world *w, vv_render_mode mode,
               const char *name) {
    vv_object *o = w->objects[0];
    o->mode = mode;
    if (mode != VV_MODE_COMPOSITE) {
        vv_tf_init(&o->tf);
        vv_tf_add_opacity(&o->tf, o->volume->range[0], 1.0);
        vv_tf_add_opacity(&o->tf, o->volume->range[1], 1.0);
        vv_tf_add_color(&o->tf, o->volume->range[0], vv_vec3_make(0, 0, 0));
        vv_tf_add_color(&o->tf, o->volume->range[1], vv_vec3_make(1, 1, 1));
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
    return psnr;
}

/* agreement_with new renderers. */
VT_UNUSED static double
agreement(vv_world *w, vv_render_mode mode, const char *name) {
    vv_renderer *rc = new_r("raycast"), *sp = new_r("splat");
    const double p = agreement_with(rc, sp, w, mode, name);
    vv_renderer_free(rc);
    vv_renderer_free(sp);
    return p;
}

#endif
