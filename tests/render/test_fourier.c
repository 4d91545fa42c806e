/*
 * Tests of the compression-domain `fourier` renderer
 * (src/render/fourier/fourier.c).
 *
 * The Fourier projection of an uncompressed volume must equal the spatial
 * X-ray projection of the ray caster (mode xray: the mean value along the
 * ray through the same transfer function) on real volumes at several
 * angles; a block phantom has the analytic mean; attenuation per subcube
 * makes the front of a volume count more, in both viewing directions;
 * images from compressed data approach the exact one as the rate grows,
 * and a .vvc file renders like the same data compressed in memory;
 * modes other than xray go to the ray caster on the decoded volume; X-ray
 * in perspective views, cut planes and bad options are refused.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static vv_world *
world_for(vv_volume *v, double az_deg, double el_deg, int size) {
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.mode = VV_MODE_XRAY;
    o.width = o.height = size;
    o.has_tf_range = 1;
    o.tf_lo = v->range[0];
    o.tf_hi = v->range[1];
    o.azimuth = vv_deg_to_rad(az_deg);
    o.elevation = vv_deg_to_rad(el_deg);
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    return w;
}

static vv_image *
render_with(vv_renderer *r, const vv_world *w, int threads) {
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    vt_ok(vv_renderer_render(r, w, &w->view, &opt, img));
    return img;
}

static vv_image *
render_named(const char *name, const vv_world *w, const char *const *options) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, name));
    for (int i = 0; options && options[i]; i += 2)
        vt_ok(vv_renderer_set_option(r, options[i], options[i + 1]));
    vv_image *img = render_with(r, w, 0);
    vv_renderer_free(r);
    return img;
}

static void
save(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", vt_outdir("fourier"), name);
    vt_ok(vv_image_write_png(img, path, 1, 0));
}

/* The largest grey value of an image (the mean along the brightest ray). */
static float
max_grey(const vv_image *img) {
    float m = 0;
    for (int i = 0; i < img->width * img->height; i++)
        m = img->rgba[4 * i] > m ? img->rgba[4 * i] : m;
    return m;
}

static void
check_equals_xray(const char *file, const char *tag) {
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data(file), NULL));
    const double angles[3][2] = {{0, 0}, {30, 20}, {-130, 65}};
    for (int a = 0; a < 3; a++) {
        vv_world *w = world_for(v, angles[a][0], angles[a][1], 256);
        vv_image *ref = render_named("raycast", w, NULL);
        /* means are far below the maximum value: stretch a linear grey ramp
         * onto the brightest mean so that the comparison sees every grey
         * level (the default grey ramp also ramps the colour: grey = t^2) */
        const float m = sqrtf(max_grey(ref));
        assert_true(m > 0.01f);
        vv_object *obj = w->objects[0];
        vv_tf_set_ramp(&obj->tf, v->range[0], v->range[0] + (v->range[1] - v->range[0]) * m, 1.0,
                       vv_vec3_make(1, 1, 1), obj->tf.opacity_unit_distance);
        vv_image_free(ref);
        ref = render_named("raycast", w, NULL);
        vv_image *f = render_named("fourier", w, NULL);
        const double psnr = vv_image_psnr(ref, f);
        printf("%s azimuth %g elevation %g: PSNR %.2f dB against the spatial X-ray\n", file,
               angles[a][0], angles[a][1], psnr);
        char name[64];
        snprintf(name, sizeof name, "%s_%d_xray.png", tag, a);
        save(ref, name);
        snprintf(name, sizeof name, "%s_%d_fourier.png", tag, a);
        save(f, name);
        assert_true(psnr >= 35);
        /* coverage: the same pixels hit */
        long differ = 0;
        for (int i = 0; i < 256 * 256; i++)
            differ += (ref->depth[i] < INFINITY) != (f->depth[i] < INFINITY);
        assert_true(differ == 0);
        vv_image_free(ref);
        vv_image_free(f);
        vv_world_free(w);
    }
    vv_volume_free(v);
}

static void
test_neghip_equals_xray(void **state) {
    (void)state;
    check_equals_xray("volumes/neghip.slc", "neghip");
}

static void
test_ct_head_equals_xray(void **state) {
    (void)state;
    check_equals_xray("volumes/ct_head.nrrd", "ct_head");
}

static void
test_object_transform(void **state) {
    (void)state;
    /* a rotated, anisotropically scaled object with a direction matrix: the
     * view direction in index space has no zero component */
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    const double d[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    memcpy(v->direction, d, sizeof d);
    v->spacing[2] = 1.7;
    vv_world *w = world_for(v, 25, -35, 200);
    vv_object *obj = w->objects[0];
    obj->orientation = vv_quat_from_axis_angle(vv_vec3_make(1, 2, 0.5), vv_deg_to_rad(40));
    obj->scale = vv_vec3_make(1.3, 0.8, 1.1);
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    vv_tf_set_ramp(&obj->tf, 0, 60, 1, vv_vec3_make(1, 1, 1), 1);
    vv_image *ref = render_named("raycast", w, NULL), *f = render_named("fourier", w, NULL);
    const double psnr = vv_image_psnr(ref, f);
    printf("transformed object: PSNR %.2f dB against the spatial X-ray\n", psnr);
    save(ref, "transformed_xray.png");
    save(f, "transformed_fourier.png");
    assert_true(psnr >= 35);
    vv_image_free(ref);
    vv_image_free(f);
    vv_world_free(w);
    vv_volume_free(v);
}

/* 32 x 32 x nz u8 volume: value `va` in the box [8, 23]^2 x [za, za + 15], `vb` in [8, 23]^2 x
 * [zb, zb + 15] (when zb >= 0), 0 elsewhere. */
static vv_volume *
blocks(int nz, int za, double va, int zb, double vb) {
    vv_volume *v = NULL;
    const int dims[3] = {32, 32, nz};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int k = 0; k < nz; k++)
        for (int j = 8; j < 24; j++)
            for (int i = 8; i < 24; i++) {
                if (k >= za && k < za + 16)
                    vv_volume_set(v, i, j, k, va);
                if (zb >= 0 && k >= zb && k < zb + 16)
                    vv_volume_set(v, i, j, k, vb);
            }
    vv_volume_update_range(v);
    return v;
}

/* An orthographic world looking along -z (from +z) or +z, grey ramp 0..255 -> 0..1. */
static vv_world *
block_world(vv_volume *v, int from_plus_z) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, NULL));
    o->mode = VV_MODE_XRAY;
    vv_tf_set_ramp(&o->tf, 0, 255, 1, vv_vec3_make(1, 1, 1), 1);
    vt_ok(vv_world_add_object(w, o));
    vv_view *vw = &w->view;
    const double cz = 0.5 * (v->dims[2] - 1);
    vw->at = vv_vec3_make(15.5, 15.5, cz);
    vw->eye = vv_vec3_make(15.5, 15.5, from_plus_z ? cz + 100 : cz - 100);
    vw->up = vv_vec3_make(0, 1, 0);
    vw->projection = VV_PROJECTION_ORTHOGRAPHIC;
    vw->ortho_height = 40;
    vw->width = vw->height = 80;
    return w;
}

static double
centre_grey(const vv_image *img) {
    return img->rgba[4 * (40 * 80 + 40)];
}

static void
test_block_phantom(void **state) {
    (void)state;
    /* one block of 200, 16 voxels deep in a 32-voxel column: the mean over
     * the band-limited footprint [-0.5, 31.5] of the column is 100 */
    vv_volume *v = blocks(32, 8, 200, -1, 0);
    vv_world *w = block_world(v, 1);
    vv_image *f = render_named("fourier", w, NULL);
    save(f, "block.png");
    assert_near(centre_grey(f) * 255, 100, 2.0);
    /* a ray beside the block sees zeros; the corner of the image misses the volume */
    assert_near(f->rgba[4 * (40 * 80 + 4)] * 255, 0, 2.0);
    assert_true(f->rgba[3] == 0 && isinf(f->depth[0]));
    /* the ray caster's mean over its sample grid [0, 31] agrees to a few grey levels */
    vv_image *r = render_named("raycast", w, NULL);
    assert_near(centre_grey(r) * 255, 100, 5.0);
    assert_near(f->depth[40 * 80 + 40], r->depth[40 * 80 + 40], 0.6);
    vv_image_free(r);
    vv_image_free(f);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_attenuation_front_counts_more(void **state) {
    (void)state;
    /* 200 deep down, 50 near the top (z large): mean without attenuation
     * (200 * 16 + 50 * 16) / 64 = 62.5 */
    vv_volume *v = blocks(64, 8, 200, 40, 50);
    const char *none[] = {"attenuation", "0", NULL};
    const char *strong[] = {"attenuation", "20", NULL};
    vv_world *top = block_world(v, 1), *bottom = block_world(v, 0);
    vv_image *t0 = render_named("fourier", top, none), *b0 = render_named("fourier", bottom, none);
    vv_image *t1 = render_named("fourier", top, strong),
             *b1 = render_named("fourier", bottom, strong);
    save(t1, "attenuation_top.png");
    save(b1, "attenuation_bottom.png");
    const double m_t0 = centre_grey(t0) * 255, m_b0 = centre_grey(b0) * 255;
    const double m_t1 = centre_grey(t1) * 255, m_b1 = centre_grey(b1) * 255;
    printf("means: no attenuation %.2f / %.2f, attenuation 20: from the top %.2f, from the "
           "bottom %.2f\n",
           m_t0, m_b0, m_t1, m_b1);
    assert_near(m_t0, 62.5, 2.0);
    assert_near(m_b0, 62.5, 2.0);
    assert_true(m_t1 < m_t0 - 5); /* the 50 block is in front */
    assert_true(m_b1 > m_b0 + 5); /* the 200 block is in front */
    vv_image_free(t0);
    vv_image_free(b0);
    vv_image_free(t1);
    vv_image_free(b1);
    vv_world_free(top);
    vv_world_free(bottom);
    vv_volume_free(v);
}

static void
test_compressed_degrades_gracefully(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_world *w = world_for(v, 40, 25, 200);
    vv_object *obj = w->objects[0];
    vv_tf_set_ramp(&obj->tf, 0, 60, 1, vv_vec3_make(1, 1, 1), 1);
    vv_image *exact = render_named("fourier", w, NULL);
    const char *rates[] = {"0.25", "0.5", "1", "2", "4"};
    double last = 0;
    for (int i = 0; i < 5; i++) {
        const char *o[] = {"rate", rates[i], NULL};
        vv_image *f = render_named("fourier", w, o);
        const double psnr = vv_image_psnr(exact, f);
        printf("rate %s bits per voxel: PSNR %.2f dB against the uncompressed projection\n",
               rates[i], psnr);
        char name[64];
        snprintf(name, sizeof name, "neghip_rate%s.png", rates[i]);
        save(f, name);
        assert_true(psnr > last - 0.5);
        last = psnr > last ? psnr : last;
        vv_image_free(f);
    }
    assert_true(last >= 40);
    /* the same data from a .vvc file render exactly as compressed in memory */
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.quality = 45;
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    char path[1200];
    snprintf(path, sizeof path, "%s/neghip_q45.vvc", vt_outdir("fourier"));
    vt_ok(vv_vvc_save(c, path));
    vv_vvc_free(c);
    const char *fo[] = {"vvc", path, NULL};
    const char *mo[] = {"quality", "45", NULL};
    vv_image *ff = render_named("fourier", w, fo), *fm = render_named("fourier", w, mo);
    assert_memory_equal(ff->rgba, fm->rgba, sizeof(float) * 4 * 200 * 200);
    assert_true(vv_image_psnr(exact, ff) > 30);
    vv_image_free(ff);
    vv_image_free(fm);
    vv_image_free(exact);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_threads_and_blocks(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_world *w = world_for(v, -20, 10, 160);
    vv_tf_set_ramp(&w->objects[0]->tf, 0, 60, 1, vv_vec3_make(1, 1, 1), 1);
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "fourier"));
    vv_image *a = render_with(r, w, 1), *b = render_with(r, w, 2);
    assert_true(vv_image_psnr(a, b) > 60); /* sums in another order */
    /* deterministic for a thread count: the same bits again, from a new renderer too */
    vv_renderer *r2 = NULL;
    vt_ok(vv_renderer_new(&r2, "fourier"));
    vv_image *b2 = render_with(r, w, 2), *b3 = render_with(r2, w, 2);
    assert_memory_equal(b->rgba, b2->rgba, sizeof(float) * 4 * 160 * 160);
    assert_memory_equal(b->rgba, b3->rgba, sizeof(float) * 4 * 160 * 160);
    vv_image_free(b2);
    vv_image_free(b3);
    vv_renderer_free(r2);
    vv_image_free(b);
    for (int m = 8; m <= 32; m *= 2) {
        char val[16];
        snprintf(val, sizeof val, "%d", m);
        vt_ok(vv_renderer_set_option(r, "block", val));
        b = render_with(r, w, 0);
        printf("block %d: PSNR %.2f dB against block 16\n", m, vv_image_psnr(a, b));
        assert_true(vv_image_psnr(a, b) > 40);
        vv_image_free(b);
    }
    vv_image_free(a);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

static int
cancel_at_half(void *user, double fraction) {
    int *calls = user;
    (*calls)++;
    return fraction >= 0.5;
}

static void
test_options_and_cancel(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_world *w = world_for(v, 10, 10, 96);
    vv_tf_set_ramp(&w->objects[0]->tf, 0, 60, 1, vv_vec3_make(1, 1, 1), 1);
    vv_image *exact = render_named("fourier", w, NULL);
    /* one renderer, its source changed between frames: no stale spectra */
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "fourier"));
    vt_ok(vv_renderer_set_option(r, "rate", "0.25"));
    vv_image *lo = render_with(r, w, 0);
    vt_ok(vv_renderer_set_option(r, "rate", "4"));
    vv_image *hi = render_with(r, w, 0);
    vt_ok(vv_renderer_set_option(r, "quality", "exact"));
    vv_image *ex = render_with(r, w, 0);
    assert_true(vv_image_psnr(exact, hi) > vv_image_psnr(exact, lo) + 10);
    assert_memory_equal(exact->rgba, ex->rgba, sizeof(float) * 4 * 96 * 96);
    /* progress is reported and a cancel stops the render */
    int calls = 0;
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.progress.fn = cancel_at_half;
    opt.progress.user = &calls;
    vv_error_clear();
    assert_int_equal(vv_renderer_render(r, w, &w->view, &opt, ex), VV_ERR_CANCELLED);
    assert_true(calls > 1);
    vv_image_free(lo);
    vv_image_free(hi);
    vv_image_free(ex);
    vv_image_free(exact);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

/* Modes the frequency domain cannot do (MIP, composite, iso) are rendered by
 * the ray caster from the decoded volume: from the volume itself without
 * compression, from the decoded .vvc with it (also in perspective). */
static void
test_other_modes_decode(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.target = VV_VVC_MAX_ERROR;
    p.max_error = 2;
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    char path[1200];
    snprintf(path, sizeof path, "%s/neghip_e2.vvc", vt_outdir("fourier"));
    vt_ok(vv_vvc_save(c, path));
    vv_volume *dec = NULL;
    vt_ok(vv_vvc_decompress(&dec, c, 0, NULL));
    vv_vvc_free(c);
    const vv_render_mode modes[] = {VV_MODE_MIP, VV_MODE_COMPOSITE, VV_MODE_ISO};
    for (int m = 0; m < 3; m++) {
        vv_world *w = world_for(v, 30, 20, 96);
        w->objects[0]->mode = modes[m];
        w->objects[0]->isovalue = 60;
        vv_image *ref = render_named("raycast", w, NULL);
        vv_image *f = render_named("fourier", w, NULL);
        assert_memory_equal(ref->rgba, f->rgba, sizeof(float) * 4 * 96 * 96);
        const char *fo[] = {"vvc", path, NULL};
        vv_image *fc = render_named("fourier", w, fo);
        /* the ray caster on the decoded volume */
        vv_world *wd = world_for(dec, 30, 20, 96);
        wd->objects[0]->mode = modes[m];
        wd->objects[0]->isovalue = 60;
        wd->objects[0]->tf = w->objects[0]->tf;
        vv_image *rd = render_named("raycast", wd, NULL);
        assert_memory_equal(rd->rgba, fc->rgba, sizeof(float) * 4 * 96 * 96);
        printf("mode %d: decoded .vvc (max error 2) against the original: %.2f dB\n", (int)modes[m],
               vv_image_psnr(ref, fc));
        if (m == 0)
            save(fc, "neghip_mip_from_vvc.png");
        vv_image_free(ref);
        vv_image_free(f);
        vv_image_free(fc);
        vv_image_free(rd);
        vv_world_free(wd);
        vv_world_free(w);
    }
    /* perspective is fine for these modes */
    vv_world *w = world_for(v, 30, 20, 64);
    w->objects[0]->mode = VV_MODE_MIP;
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    vv_image *f = render_named("fourier", w, NULL);
    vv_image_free(f);
    vv_world_free(w);
    vv_volume_free(dec);
    vv_volume_free(v);
}

static void
test_refusals(void **state) {
    (void)state;
    vv_volume *v = blocks(32, 8, 200, -1, 0);
    vv_world *w = block_world(v, 1);
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "fourier"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 80, 80));
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    vv_error_clear();
    assert_int_equal(vv_renderer_render(r, w, &w->view, NULL, img), VV_ERR_UNSUPPORTED);
    assert_non_null(strstr(vv_error_message(), "perspective"));
    w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 16), vv_vec3_make(0, 0, 1)));
    vt_err(vv_renderer_render(r, w, &w->view, NULL, img));
    vt_err(vv_renderer_set_option(r, "block", "12"));
    vt_err(vv_renderer_set_option(r, "quality", "101"));
    vt_err(vv_renderer_set_option(r, "rate", "-1"));
    vt_err(vv_renderer_set_option(r, "attenuation", "x"));
    vt_err(vv_renderer_set_option(r, "nonsense", "1"));
    vt_err(vv_renderer_set_option(r, "vvc", "/nonexistent.vvc"));
    /* a .vvc of other dimensions than the object's volume */
    vv_volume *other = blocks(16, 0, 10, -1, 0);
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, other, NULL));
    char path[1200];
    snprintf(path, sizeof path, "%s/other.vvc", vt_outdir("fourier"));
    vt_ok(vv_vvc_save(c, path));
    vv_vvc_free(c);
    vt_ok(vv_renderer_set_option(r, "vvc", path));
    w->n_cut_planes = 0;
    vt_err(vv_renderer_render(r, w, &w->view, NULL, img));
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(other);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_neghip_equals_xray),
        cmocka_unit_test(test_ct_head_equals_xray),
        cmocka_unit_test(test_object_transform),
        cmocka_unit_test(test_block_phantom),
        cmocka_unit_test(test_attenuation_front_counts_more),
        cmocka_unit_test(test_compressed_degrades_gracefully),
        cmocka_unit_test(test_threads_and_blocks),
        cmocka_unit_test(test_options_and_cancel),
        cmocka_unit_test(test_other_modes_decode),
        cmocka_unit_test(test_refusals),
    };
    return vt_run_tests(tests, NULL, NULL);
}
