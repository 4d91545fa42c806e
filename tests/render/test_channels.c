/*
 * Multi-channel volume objects (vv_object_set_channels) and the ray
 * caster's one-pass rendering of them under the three blend rules
 * (include/volvis/model.h, vv_channel_blend).
 *
 * - Analytic: three balls, each in its own channel at a known place: every
 *   rule shows each channel's colour at its ball and only there.
 * - Additive: the image equals the sum of the channels' one-channel images
 *   (the one-object kernel, a separate code path) within 8-bit rounding.
 * - Maximum: the image equals the sum of the channels' one-channel MIPs
 *   (exactly, on noisy data seen obliquely: the one traversal that all
 *   channels share gives each its one-channel projection's value).
 * - Composite: on a slab where two channels overlap completely, the colour
 *   is the opacity-weighted mix (red : green = a_red : a_green per sample)
 *   and the pixel is at least as opaque and as bright as either channel
 *   alone (no dark seam where channels overlap), against the per-sample
 *   formula evaluated here.
 * - The ray tracer draws the channels by the same rules: with its global
 *   effects off its images are the ray caster's (PSNR >= 40 dB, and the
 *   balls' colours at their places); with shadows on, each channel's ball
 *   shadows a floor, and hiding the channel takes its shadow away.
 * - Thread counts and empty-space skipping do not change a bit; clones
 *   hold their own references; bad input gets one-line errors; renderers
 *   without VV_RENDERER_CHANNELS and region renders refuse such objects.
 * - A label volume as a channel shows each label in its colour under every
 *   rule in both renderers, and alone equals the one-channel labels object.
 * - Scene files: the channels of an ImageJ hyperstack (written here with
 *   libtiff) load with their indices, names, visibility, transfer functions
 *   and blend rule, render, save and load again to the same bits; bad
 *   "channels" and "blend" entries are errors naming their place.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <tiffio.h>

#define N 40

/* u8 volume N^3, value 200 inside a ball of radius r around (cx, cy, cz), else 0. */
static vv_volume *
ball(double cx, double cy, double cz, double r) {
    vv_volume *v = NULL;
    const int dims[3] = {N, N, N};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int k = 0; k < N; k++)
        for (int j = 0; j < N; j++)
            for (int i = 0; i < N; i++) {
                double d = sqrt((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz));
                vv_volume_set(v, i, j, k, d <= r ? 200 : 0);
            }
    vv_volume_update_range(v);
    return v;
}

static vv_volume *
constant(double value) {
    vv_volume *v = NULL;
    const int dims[3] = {16, 16, 16};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int k = 0; k < 16; k++)
        for (int j = 0; j < 16; j++)
            for (int i = 0; i < 16; i++)
                vv_volume_set(v, i, j, k, value);
    vv_volume_update_range(v);
    return v;
}

/* Orthographic view down -z onto the box [0, n-1]^2, 2 pixels a voxel. */
static vv_view
view_z(int n) {
    vv_view v;
    memset(&v, 0, sizeof v);
    double c = 0.5 * (n - 1);
    v.eye = vv_vec3_make(c, c, 3.0 * n + 0.25);
    v.at = vv_vec3_make(c, c, 0);
    v.up = vv_vec3_make(0, 1, 0);
    v.fov = vv_deg_to_rad(30);
    v.ortho_height = n;
    v.projection = VV_PROJECTION_ORTHOGRAPHIC;
    v.width = v.height = 2 * n;
    return v;
}

static vv_world *
world(void) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    w->background = vv_vec3_make(0, 0, 0);
    w->n_lights = 1;
    memset(&w->lights[0], 0, sizeof w->lights[0]);
    w->lights[0].type = VV_LIGHT_DIRECTIONAL;
    w->lights[0].direction = vv_vec3_make(-0.3, -0.4, -0.866);
    w->lights[0].color = vv_vec3_make(1, 1, 1);
    w->lights[0].intensity = 1;
    return w;
}

static const vv_vec3 RGB[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

/* A World holding one object of the channels @p vols (colours RGB[c],
 * contrast 50..150, opacity @p op), blend @p b, shading @p shading. */
static vv_world *
channel_world(vv_volume **vols, int n, vv_channel_blend b, int shading, double op) {
    vv_world *w = world();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, vols[0], "cells"));
    vt_ok(vv_object_set_channels(o, n, vols, NULL));
    for (int c = 0; c < n; c++)
        vt_ok(vv_tf_set_contrast(&o->channels[c].tf, 50, 150, 1.0, op, RGB[c % 3], 1.0));
    o->blend = b;
    o->shading = shading;
    o->step = 0.5;
    vt_ok(vv_world_add_object(w, o));
    return w;
}

/* The World of channel @p c alone, as a one-channel object in @p mode. */
static vv_world *
single_world(const vv_world *multi, int c, vv_render_mode mode) {
    const vv_object *m = multi->objects[0];
    vv_world *w = world();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, m->channels[c].volume, "one"));
    o->tf = m->channels[c].tf;
    o->mode = mode;
    o->shading = m->shading;
    o->material = m->material;
    o->step = m->step;
    vt_ok(vv_world_add_object(w, o));
    return w;
}

static vv_image *
render_opt(const vv_world *w, const vv_view *view, int threads, int skipping) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    if (!skipping)
        vt_ok(vv_renderer_set_option(r, "empty_space_skipping", "0"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, view->width, view->height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    vt_ok(vv_renderer_render(r, w, view, &opt, img));
    vv_renderer_free(r);
    return img;
}

static vv_image *
render(const vv_world *w, const vv_view *view) {
    return render_opt(w, view, 0, 1);
}

/* render without adaptive refinement (option refinement=off): every pixel
 * cast, as the maximum rule's region renders cast them. */
static vv_image *
render_unrefined(const vv_world *w, const vv_view *view) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vt_ok(vv_renderer_set_option(r, "refinement", "off"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, view->width, view->height));
    vt_ok(vv_renderer_render(r, w, view, NULL, img));
    vv_renderer_free(r);
    return img;
}

static const float *
px(const vv_image *img, int x, int y) {
    return img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
}

static void
save(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.png", vt_outdir("render"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* Pixel of voxel column (i, j) in view_z(n), n = the image's width / 2. */
static const float *
at_voxel(const vv_image *img, double i, double j) {
    int n = img->width / 2;
    int x = (int)(2 * i + 1), y = (int)(2 * (n - 1 - j) + 1);
    return px(img, x, y);
}

static void
three_balls(vv_volume *v[3]) {
    v[0] = ball(10, 20, 20, 6);
    v[1] = ball(20, 20, 20, 6);
    v[2] = ball(30, 20, 20, 6);
}

static void
test_three_balls(void **state) {
    (void)state;
    vv_volume *v[3];
    three_balls(v);
    vv_view view = view_z(N);
    const vv_channel_blend rules[3] = {VV_BLEND_COMPOSITE, VV_BLEND_ADDITIVE, VV_BLEND_MAXIMUM};
    for (int r = 0; r < 3; r++) {
        /* unshaded: a white highlight would show in every colour */
        vv_world *w = channel_world(v, 3, rules[r], 0, 0.8);
        vv_image *img = render(w, &view);
        char name[64];
        snprintf(name, sizeof name, "channels_balls_%s", vv_channel_blend_name(rules[r]));
        save(img, name);
        for (int c = 0; c < 3; c++) {
            const float *p = at_voxel(img, 10 + 10 * c, 20);
            for (int k = 0; k < 3; k++) {
                if (k == c && !(p[k] > 0.2f))
                    fail_msg("%s: ball %d shows %.3f of its own colour", name, c, p[k]);
                if (k != c && !(p[k] < 1e-6f))
                    fail_msg("%s: ball %d shows %.3g of channel %d's colour", name, c, p[k], k);
            }
        }
        /* outside every ball: the black background */
        const float *o = at_voxel(img, 20, 35);
        assert_true(o[0] == 0 && o[1] == 0 && o[2] == 0 && o[3] == 0);
        /* hiding channel 1 removes its ball and nothing else */
        w->objects[0]->channels[1].visible = 0;
        vv_image *hid = render(w, &view);
        const float *h = at_voxel(hid, 20, 20);
        assert_true(h[0] == 0 && h[1] == 0 && h[2] == 0);
        assert_true(at_voxel(hid, 10, 20)[0] == at_voxel(img, 10, 20)[0]);
        vv_image_free(hid);
        vv_image_free(img);
        vv_world_free(w);
    }
    for (int c = 0; c < 3; c++)
        vv_volume_free(v[c]);
}

/* |a - b| over the RGB of every pixel. */
static double
max_rgb_diff(const vv_image *a, const vv_image *b) {
    double m = 0;
    for (size_t i = 0; i < (size_t)a->width * (size_t)a->height; i++)
        for (int k = 0; k < 3; k++) {
            double d = fabs((double)a->rgba[4 * i + k] - (double)b->rgba[4 * i + k]);
            m = d > m ? d : m;
        }
    return m;
}

/* The blend rule's image against the sum of one-channel images in @p mode. */
static void
check_sum(vv_channel_blend rule, vv_render_mode mode, int shading, const char *name) {
    vv_volume *v[2] = {ball(16, 20, 20, 9), ball(24, 20, 20, 9)}; /* overlapping */
    vv_view view = view_z(N);
    vv_world *w = channel_world(v, 2, rule, shading, 0.6);
    vv_image *img = render(w, &view);
    save(img, name);
    vv_image *sum = NULL;
    vt_ok(vv_image_new(&sum, view.width, view.height));
    for (int c = 0; c < 2; c++) {
        vv_world *one = single_world(w, c, mode);
        vv_image *i1 = render(one, &view);
        for (size_t p = 0; p < 4 * (size_t)view.width * (size_t)view.height; p++)
            sum->rgba[p] += i1->rgba[p];
        vv_image_free(i1);
        vv_world_free(one);
    }
    double d = max_rgb_diff(img, sum);
    print_message("%s: largest difference from the sum of one-channel images %.3g\n", name, d);
    if (!(d <= 1.0 / 255))
        fail_msg("%s: differs from the sum of the one-channel images by %.4f (> 1/255)", name, d);
    /* where the balls overlap both channels show */
    const float *p = at_voxel(img, 20, 20);
    assert_true(p[0] > 0.05f && p[1] > 0.05f);
    vv_image_free(sum);
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
}

static void
test_additive_is_sum(void **state) {
    (void)state;
    check_sum(VV_BLEND_ADDITIVE, VV_MODE_COMPOSITE, 1, "channels_additive_shaded");
    check_sum(VV_BLEND_ADDITIVE, VV_MODE_COMPOSITE, 0, "channels_additive");
}

static void
test_maximum_is_sum_of_mips(void **state) {
    (void)state;
    check_sum(VV_BLEND_MAXIMUM, VV_MODE_MIP, 0, "channels_maximum");
}

/* u16 N^3: noise 100..163 from @p seed and 12 bright Gaussian spots at
 * places of the seed's own. */
static vv_volume *
noisy_spots(uint32_t seed) {
    vv_volume *v = NULL;
    const int dims[3] = {N, N, N};
    vt_ok(vv_volume_new(&v, dims, VV_U16));
    uint32_t x = seed * 2654435761u + 1;
    uint16_t *d = v->data;
    for (size_t i = 0; i < (size_t)N * N * N; i++) {
        x = x * 1664525u + 1013904223u;
        d[i] = (uint16_t)(100 + (x >> 26));
    }
    for (int s = 0; s < 12; s++) {
        x = x * 1664525u + 1013904223u;
        const double cx = 4 + (x >> 8) % (N - 8), cy = 4 + (x >> 14) % (N - 8),
                     cz = 4 + (x >> 20) % (N - 8), peak = 800 + (x >> 24) * 8;
        for (int k = 0; k < N; k++)
            for (int j = 0; j < N; j++)
                for (int i = 0; i < N; i++) {
                    const double r2 =
                        (i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz);
                    if (r2 < 25)
                        d[((size_t)k * N + j) * N + i] += (uint16_t)(peak * exp(-r2 / 4.5));
                }
    }
    vv_volume_update_range(v);
    return v;
}

/* The maximum rule's one traversal for all channels gives exactly the
 * one-channel MIPs' values: on noisy data with spots in different places,
 * seen obliquely in perspective (leaps, group and subvolume skips, chunks
 * cut at every place), the image equals the sum of the one-channel MIP
 * images (unrefined: every pixel cast, as the rule casts them) to float
 * rounding, and skipping off changes no bit. */
static void
test_maximum_one_pass_exact(void **state) {
    (void)state;
    vv_volume *v[3] = {noisy_spots(1), noisy_spots(2), noisy_spots(3)};
    vv_world *w = channel_world(v, 3, VV_BLEND_MAXIMUM, 0, 0.8);
    for (int c = 0; c < 3; c++)
        vt_ok(vv_tf_set_contrast(&w->objects[0]->channels[c].tf, 200 + 50 * c, 900, 1.0, 0.8,
                                 RGB[c], 1.0));
    vv_view view = view_z(N);
    view.projection = VV_PROJECTION_PERSPECTIVE;
    view.eye = vv_vec3_make(19.5 + 47, 19.5 + 31, 19.5 + 83);
    view.at = vv_vec3_make(19.5, 19.5, 19.5);
    view.fov = vv_deg_to_rad(35);
    vv_image *img = render(w, &view), *flat = render_opt(w, &view, 1, 0);
    save(img, "channels_maximum_noisy");
    assert_memory_equal(img->rgba, flat->rgba,
                        4 * sizeof(float) * (size_t)view.width * (size_t)view.height);
    vv_image *sum = NULL;
    vt_ok(vv_image_new(&sum, view.width, view.height));
    for (int c = 0; c < 3; c++) {
        vv_world *one = single_world(w, c, VV_MODE_MIP);
        vv_image *i1 = render_unrefined(one, &view);
        for (size_t p = 0; p < 4 * (size_t)view.width * (size_t)view.height; p++)
            sum->rgba[p] += i1->rgba[p];
        vv_image_free(i1);
        vv_world_free(one);
    }
    const double d = max_rgb_diff(img, sum);
    if (!(d <= 1e-6))
        fail_msg("the one-pass maximum differs from the one-channel MIPs by %g", d);
    int lit = 0;
    for (size_t p = 0; p < (size_t)view.width * (size_t)view.height; p++)
        lit += img->rgba[4 * p] > 0.05f && img->rgba[4 * p + 1] > 0.05f;
    assert_true(lit > 20); /* the spots of different channels overlap on screen */
    vv_image_free(sum);
    vv_image_free(img);
    vv_image_free(flat);
    vv_world_free(w);
    for (int c = 0; c < 3; c++)
        vv_volume_free(v[c]);
}

/* Composite rule on a slab both channels fill: per sample the opacities
 * a_r, a_g (the step-corrected table values) combine as 1 - (1-a_r)(1-a_g)
 * and the colour is red a_r + green a_g over their sum, so at every pixel
 * red / green = a_r / a_g exactly and red + green = alpha; the pixel is at
 * least as opaque and bright as either channel alone. */
static void
test_composite_mix(void **state) {
    (void)state;
    vv_volume *v[2] = {constant(100), constant(100)};
    vv_view view = view_z(16);
    vv_world *w = world();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v[0], "slab"));
    vt_ok(vv_object_set_channels(o, 2, v, (const char *const[]){"red", "green"}));
    /* constant opacity per unit distance: 0.1 (red) and 0.03 (green), so
     * that no ray ends early */
    vv_tf_set_ramp(&o->channels[0].tf, 0, 200, 0.2, RGB[0], 1.0);
    vv_tf_set_ramp(&o->channels[1].tf, 0, 200, 0.06, RGB[1], 1.0);
    o->shading = 0;
    o->step = 0.5;
    vt_ok(vv_world_add_object(w, o));
    vv_image *img = render(w, &view);
    save(img, "channels_composite_slab");
    const float *p = at_voxel(img, 8, 8);
    const double ar = 1 - pow(1 - 0.1, 0.5), ag = 1 - pow(1 - 0.03, 0.5);
    /* samples inside the slab: from alpha = 1 - ((1-ar)(1-ag))^n */
    double n = log(1 - p[3]) / log((1 - ar) * (1 - ag));
    print_message("composite: alpha %.5f (%.3f samples), red %.5f green %.5f\n", p[3], n, p[0],
                  p[1]);
    assert_near(n, round(n), 1e-3);
    assert_near(p[0] / p[1], ar / ag, 1e-4);
    assert_near(p[0] + p[1], p[3], 1e-5);
    for (int c = 0; c < 2; c++) {
        vv_world *one = single_world(w, c, VV_MODE_COMPOSITE);
        vv_image *i1 = render(one, &view);
        const float *q = at_voxel(i1, 8, 8);
        assert_true(p[3] >= q[3]);
        assert_true(p[0] + p[1] + p[2] >= q[0] + q[1] + q[2]);
        vv_image_free(i1);
        vv_world_free(one);
    }
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
}

/* The ray tracer's image of @p w at quality 1 (one ray a pixel: no
 * adaptive refinement), its shadows on or off, no reflected rays. */
static vv_image *
render_rt(const vv_world *w, const vv_view *view, int shadows) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raytrace"));
    vt_ok(vv_renderer_set_option(r, "shadows", shadows ? "1" : "0"));
    vt_ok(vv_renderer_set_option(r, "max_depth", "0"));
    vt_ok(vv_renderer_set_option(r, "refinement", "off"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, view->width, view->height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.quality = 1;
    vt_ok(vv_renderer_render(r, w, view, &opt, img));
    vv_renderer_free(r);
    return img;
}

/* With its effects off the ray tracer draws the channels as the ray caster
 * does, under every rule: three overlapping shaded balls, and the three
 * apart unshaded (each channel's colour at its ball and only there). */
static void
test_raytrace_agrees(void **state) {
    (void)state;
    vv_volume *v[3] = {ball(13, 20, 20, 8), ball(20, 22, 20, 8), ball(27, 20, 20, 8)};
    vv_volume *apart[3];
    three_balls(apart);
    vv_view view = view_z(N);
    const vv_channel_blend rules[3] = {VV_BLEND_COMPOSITE, VV_BLEND_ADDITIVE, VV_BLEND_MAXIMUM};
    for (int r = 0; r < 3; r++) {
        vv_world *w = channel_world(v, 3, rules[r], 1, 0.5);
        vv_image *a = render(w, &view), *b = render_rt(w, &view, 0);
        char name[64];
        snprintf(name, sizeof name, "channels_raytrace_%s", vv_channel_blend_name(rules[r]));
        save(b, name);
        const double psnr = vv_image_psnr(a, b);
        print_message("%s: raytrace vs raycast PSNR %.2f dB, largest difference %.4f\n", name, psnr,
                      max_rgb_diff(a, b));
        if (!(psnr >= 40.0))
            fail_msg("%s: the ray tracer's image differs from the ray caster's (PSNR %.2f dB)",
                     name, psnr);
        /* where the three overlap, every channel shows (under the
         * composite rule the middle ball's front hides the others') */
        const float *p = at_voxel(b, 20, 21);
        if (rules[r] != VV_BLEND_COMPOSITE)
            assert_true(p[0] > 0.02f && p[1] > 0.02f && p[2] > 0.02f);
        else
            assert_true(p[1] > 0.05f);
        vv_image_free(a);
        vv_image_free(b);
        vv_world_free(w);
        w = channel_world(apart, 3, rules[r], 0, 0.8);
        b = render_rt(w, &view, 0);
        for (int c = 0; c < 3; c++) {
            const float *q = at_voxel(b, 10 + 10 * c, 20);
            for (int k = 0; k < 3; k++)
                if (k == c ? !(q[k] > 0.2f) : !(q[k] < 1e-6f))
                    fail_msg("%s: ball %d shows %.3g of channel %d's colour", name, c, q[k], k);
        }
        vv_image_free(b);
        vv_world_free(w);
    }
    for (int c = 0; c < 3; c++) {
        vv_volume_free(v[c]);
        vv_volume_free(apart[c]);
    }
}

/* Shadows of the channels on a floor: two balls in two channels over a
 * grey plane at z = -10, the light travelling along (-0.3, -0.4, -0.866),
 * so that a ball centred at (cx, cy, 20) shadows the floor around
 * (cx - 10.4, cy - 13.9). Under every rule each ball's shadow is dark
 * against the floor with both channels hidden, and hiding channel 1 lights
 * the floor under its ball again and leaves channel 0's shadow as it was. */
static void
test_raytrace_shadows(void **state) {
    (void)state;
    vv_volume *v[2] = {ball(12, 30, 20, 6), ball(30, 30, 20, 6)};
    vv_view view = view_z(N);
    const vv_channel_blend rules[3] = {VV_BLEND_COMPOSITE, VV_BLEND_ADDITIVE, VV_BLEND_MAXIMUM};
    for (int r = 0; r < 3; r++) {
        vv_world *w = channel_world(v, 2, rules[r], 1, 1.0);
        vv_object *pl = NULL;
        vt_ok(vv_object_new_geometry(&pl, VV_OBJECT_PLANE, "floor"));
        pl->position = vv_vec3_make(0, 0, -10);
        pl->material.color = vv_vec3_make(0.5, 0.5, 0.5);
        vt_ok(vv_world_add_object(w, pl));
        vv_image *img = render_rt(w, &view, 1);
        char name[64];
        snprintf(name, sizeof name, "channels_raytrace_shadows_%s",
                 vv_channel_blend_name(rules[r]));
        save(img, name);
        const float s0 = at_voxel(img, 12 - 10.4, 30 - 13.9)[0];
        const float s1 = at_voxel(img, 30 - 10.4, 30 - 13.9)[0];
        w->objects[0]->channels[0].visible = w->objects[0]->channels[1].visible = 0;
        vv_image *none = render_rt(w, &view, 1);
        const float lit = at_voxel(none, 30 - 10.4, 30 - 13.9)[0];
        assert_true(fabsf(at_voxel(none, 12 - 10.4, 30 - 13.9)[0] - lit) < 1e-6f);
        vv_image_free(none);
        w->objects[0]->channels[0].visible = 1;
        print_message("%s: floor %.3f lit, %.3f and %.3f in the balls' shadows\n", name, lit, s0,
                      s1);
        if (!(lit > 0.1f && s0 < 0.6f * lit && s1 < 0.6f * lit))
            fail_msg("%s: no shadow of the channels' balls (floor %.3f, shadows %.3f %.3f)", name,
                     lit, s0, s1);
        w->objects[0]->channels[1].visible = 0;
        vv_image *hid = render_rt(w, &view, 1);
        const float h1 = at_voxel(hid, 30 - 10.4, 30 - 13.9)[0];
        const float h0 = at_voxel(hid, 12 - 10.4, 30 - 13.9)[0];
        if (!(fabsf(h1 - lit) < 0.02f && fabsf(h0 - s0) < 0.005f))
            fail_msg("%s: hiding channel 1 leaves its shadow (%.3f, lit %.3f) or moves the "
                     "other's (%.5f, was %.5f)",
                     name, h1, lit, h0, s0);
        vv_image_free(hid);
        vv_image_free(img);
        vv_world_free(w);
    }
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
}

/* Thread counts and empty-space skipping change no bit; clones hold their
 * own references (the original freed first). */
static void
test_deterministic_and_clone(void **state) {
    (void)state;
    vv_volume *v[3];
    three_balls(v);
    vv_view view = view_z(N);
    const vv_channel_blend rules[3] = {VV_BLEND_COMPOSITE, VV_BLEND_ADDITIVE, VV_BLEND_MAXIMUM};
    for (int r = 0; r < 3; r++) {
        vv_world *w = channel_world(v, 3, rules[r], 1, 0.5);
        vv_image *a = render_opt(w, &view, 1, 1), *b = render_opt(w, &view, 2, 1),
                 *c = render_opt(w, &view, 2, 0);
        size_t n = 4 * (size_t)view.width * (size_t)view.height * sizeof(float);
        assert_memory_equal(a->rgba, b->rgba, n);
        assert_memory_equal(a->rgba, c->rgba, n);
        /* beside another composited object, off to the side, the
         * multi-channel object goes through the general loop: the same image
         * where the other one does not reach */
        if (rules[r] == VV_BLEND_COMPOSITE) {
            vv_volume *far = ball(20, 20, 20, 4);
            vv_object *o = NULL;
            vt_ok(vv_object_new_volume(&o, far, "far"));
            vv_volume_free(far);
            o->position = vv_vec3_make(500, 0, 0);
            o->shading = 0;
            vt_ok(vv_world_add_object(w, o));
            vv_image *g = render_opt(w, &view, 2, 1);
            assert_memory_equal(a->rgba, g->rgba, n);
            vv_image_free(g);
            vv_object *taken = NULL;
            vt_ok(vv_world_take_object(w, 1, &taken));
            vv_object_free(taken);
        }
        vv_world *snap = NULL;
        vt_ok(vv_world_clone(&snap, w));
        vv_world_free(w);
        vv_image *d = render_opt(snap, &view, 2, 1);
        assert_memory_equal(a->rgba, d->rgba, n);
        vv_world_free(snap);
        vv_image_free(a);
        vv_image_free(b);
        vv_image_free(c);
        vv_image_free(d);
    }
    for (int c = 0; c < 3; c++)
        vv_volume_free(v[c]);
}

static void
test_bad_input(void **state) {
    (void)state;
    vv_volume *v[2] = {ball(20, 20, 20, 5), constant(1)};
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v[0], "x"));
    vt_err(vv_object_set_channels(o, 2, v, NULL)); /* 40^3 and 16^3 */
    assert_non_null(strstr(vv_error_message(), "channel 1 is 16x16x16"));
    assert_int_equal(o->n_channels, 0);
    vv_volume *one[1] = {v[0]};
    vt_err(vv_object_set_channels(o, 1, one, NULL));
    vv_volume *many[VV_MAX_CHANNELS + 1];
    for (int c = 0; c <= VV_MAX_CHANNELS; c++)
        many[c] = v[0];
    vt_err(vv_object_set_channels(o, VV_MAX_CHANNELS + 1, many, NULL));
    vt_ok(vv_object_set_channels(o, VV_MAX_CHANNELS, many, NULL));
    assert_string_equal(o->channels[3].name, "channel 3");
    vv_channel_blend b;
    vt_err(vv_channel_blend_parse("sum", &b));
    assert_non_null(strstr(vv_error_message(), "composite, additive or maximum"));
    vt_ok(vv_channel_blend_parse("maximum", &b));
    assert_int_equal(b, VV_BLEND_MAXIMUM);
    vv_tf tf;
    vt_err(vv_tf_set_contrast(&tf, 5, 5, 1, 1, RGB[0], 1));
    vt_err(vv_tf_set_contrast(&tf, 0, 5, 0, 1, RGB[0], 1));
    vt_err(vv_tf_set_contrast(&tf, 0, 5, 1, 2, RGB[0], 1));
    /* a renderer without VV_RENDERER_CHANNELS refuses the object and names the one that draws it */
    vv_world *w = world();
    vt_ok(vv_world_add_object(w, o));
    vv_view view = view_z(N);
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "splat"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, view.width, view.height));
    vt_err(vv_renderer_render(r, w, &view, NULL, img));
    assert_non_null(strstr(vv_error_message(), "16 channels"));
    assert_non_null(strstr(vv_error_message(), "raycast"));
    assert_string_equal(vv_world_renderer(w), "raycast");
    vv_renderer_free(r);
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
}

/* An ImageJ hyperstack of two u8 channels (pages z-major, channel-minor). */
static void
write_hyperstack(const char *path, vv_volume *const v[2]) {
    TIFF *t = TIFFOpen(path, "w");
    assert_non_null(t);
    char desc[128];
    snprintf(desc, sizeof desc, "ImageJ=1.53t\nimages=%d\nchannels=2\nslices=%d\nhyperstack=true\n",
             2 * N, N);
    unsigned char row[N];
    for (int p = 0; p < 2 * N; p++) {
        const int z = p / 2, c = p % 2;
        TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)N);
        TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)N);
        TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)8);
        TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1);
        TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
        TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
        TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)N);
        if (p == 0)
            TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, desc);
        for (int y = 0; y < N; y++) {
            for (int x = 0; x < N; x++)
                row[x] = (unsigned char)vv_volume_get(v[c], x, y, z);
            assert_true(TIFFWriteScanline(t, row, (uint32_t)y, 0) >= 0);
        }
        assert_true(TIFFWriteDirectory(t));
    }
    TIFFClose(t);
}

static vv_status
load_text(const char *dir, const char *name, const char *json, vv_world **w) {
    const char *path = vt_path(dir, name);
    vt_write_file(path, json, strlen(json));
    vv_error_clear();
    return vv_scene_load(w, path);
}

static void
test_scene_round_trip(void **state) {
    (void)state;
    vv_volume *v[2] = {ball(14, 20, 20, 7), ball(26, 20, 20, 7)};
    char dir[1024]; /* vt_outdir's buffer is reused by save() */
    snprintf(dir, sizeof dir, "%s", vt_outdir("channels_scene"));
    write_hyperstack(vt_path(dir, "hyper.tif"), v);
    const char *scene =
        "{\"view\": {\"eye\": [19.5, 19.5, 200], \"at\": [19.5, 19.5, 0], \"up\": [0, 1, 0],\n"
        "  \"projection\": \"orthographic\", \"ortho_height\": 40, \"width\": 80, \"height\": "
        "80},\n"
        " \"objects\": [{\"file\": \"hyper.tif\", \"name\": \"cells\", \"shading\": false,\n"
        "   \"blend\": \"additive\",\n"
        "   \"channels\": [{\"channel\": 1, \"name\": \"membrane\"},\n"
        "                {\"channel\": 0, \"name\": \"nuclei\", \"visible\": true,\n"
        "                 \"transfer_function\": {\"opacity\": [[50, 0], [150, 0.4]],\n"
        "                                       \"color\": [[0, [0, 1, 0]]]}}]}]}\n";
    vv_world *w = NULL;
    vt_ok(load_text(dir, "cells.json", scene, &w));
    const vv_object *o = w->objects[0];
    assert_int_equal(o->n_channels, 2);
    assert_int_equal(o->blend, VV_BLEND_ADDITIVE);
    assert_int_equal(o->channels[0].index, 1);
    assert_int_equal(o->channels[1].index, 0);
    assert_string_equal(o->channels[0].name, "membrane");
    assert_string_equal(o->channels[1].name, "nuclei");
    assert_int_equal(o->channels[1].tf.n_opacity, 2);
    assert_near(o->channels[1].tf.opacity[1].opacity, 0.4, 1e-12);
    for (int c = 0; c < 2; c++) /* the voxels of the file's channel */
        for (int i = 0; i < N; i += 3)
            assert_true(vv_volume_get(o->channels[c].volume, i, 20, 20) ==
                        vv_volume_get(v[1 - c], i, 20, 20));
    vv_image *a = render(w, &w->view);
    save(a, "channels_scene");
    /* nuclei (file channel 0, green by its TF) at x = 14, membrane (the
     * object's channel 0: magenta by default) at 26 */
    assert_true(at_voxel(a, 14, 20)[1] > 0.1f && at_voxel(a, 14, 20)[0] == 0);
    assert_true(at_voxel(a, 26, 20)[0] > 0.1f && at_voxel(a, 26, 20)[2] > 0.1f &&
                at_voxel(a, 26, 20)[1] == 0);
    const char *saved = vt_path(dir, "saved.json");
    vt_ok(vv_scene_save(w, saved, NULL));
    vv_world *w2 = NULL;
    vt_ok(vv_scene_load(&w2, saved));
    const vv_object *o2 = w2->objects[0];
    assert_int_equal(o2->n_channels, 2);
    assert_int_equal(o2->blend, VV_BLEND_ADDITIVE);
    assert_int_equal(o2->channels[0].index, 1);
    assert_string_equal(o2->channels[1].name, "nuclei");
    vv_image *b = render(w2, &w2->view);
    assert_memory_equal(a->rgba, b->rgba, 4 * sizeof(float) * (size_t)a->width * a->height);
    vv_image_free(a);
    vv_image_free(b);
    vv_world_free(w);
    vv_world_free(w2);
    /* a label channel: "labels" loads, saves and loads again */
    const char *lscene =
        "{\"objects\": [{\"file\": \"hyper.tif\", \"channels\": [{\"channel\": 0}, "
        "{\"channel\": 1, \"labels\": true}]}]}";
    vt_ok(load_text(dir, "labels.json", lscene, &w));
    assert_int_equal(w->objects[0]->channels[0].labels, 0);
    assert_int_equal(w->objects[0]->channels[1].labels, 1);
    vt_ok(vv_scene_save(w, saved, NULL));
    vt_ok(vv_scene_load(&w2, saved));
    assert_int_equal(w2->objects[0]->channels[0].labels, 0);
    assert_int_equal(w2->objects[0]->channels[1].labels, 1);
    vv_world_free(w);
    vv_world_free(w2);
    /* bad entries: an error naming the place, no World */
    static const struct {
        const char *objects, *needle;
    } bad[] = {
        {"[{\"file\": \"hyper.tif\", \"channels\": [{\"channel\": 0}]}]", "1 channels"},
        {"[{\"file\": \"hyper.tif\", \"blend\": \"sum\", \"channels\": [{\"channel\": 0}, "
         "{\"channel\": 1}]}]",
         "unknown blend"},
        {"[{\"file\": \"hyper.tif\", \"blend\": \"maximum\"}]", "needs \"channels\""},
        {"[{\"file\": \"hyper.tif\", \"channels\": [{\"channel\": 0}, {\"name\": \"x\"}]}]",
         "channels[1]"},
        {"[{\"file\": \"hyper.tif\", \"channels\": [{\"channel\": 0}, {\"channel\": 5}]}]",
         "channels[1].channel"},
        {"[{\"file\": \"hyper.tif\", \"channels\": [{\"channel\": 0}, {\"channel\": 1, "
         "\"colour\": 1}]}]",
         "colour"},
        {"[{\"file\": \"hyper.tif\", \"channels\": [{\"channel\": 0}, {\"channel\": 1, "
         "\"labels\": 1}]}]",
         "channels[1].labels"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char text[512];
        snprintf(text, sizeof text, "{\"objects\": %s}", bad[i].objects);
        vv_world *x = NULL;
        assert_true(load_text(dir, "bad.json", text, &x) != VV_OK);
        assert_null(x);
        if (!strstr(vv_error_message(), bad[i].needle))
            fail_msg("%s: '%s' not in: %s", bad[i].objects, bad[i].needle, vv_error_message());
    }
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
}

/* vv_tf_get_contrast reads vv_tf_set_contrast's parameters back exactly,
 * for gamma 1 (a ramp) and another gamma; an edited function is not one. */
static void
test_contrast_read_back(void **state) {
    (void)state;
    const double gammas[] = {1.0, 0.5, 2.2};
    for (int i = 0; i < 3; i++) {
        vv_tf tf;
        vt_ok(vv_tf_set_contrast(&tf, 12, 180, gammas[i], 0.7, vv_vec3_make(1, 0, 1), 2));
        double lo, hi, g, op;
        vv_vec3 col;
        assert_int_equal(vv_tf_get_contrast(&tf, &lo, &hi, &g, &op, &col), 1);
        assert_true(fabs(lo - 12) < 1e-12 && fabs(hi - 180) < 1e-12);
        assert_true(fabs(g - gammas[i]) < 1e-9);
        assert_true(fabs(op - 0.7) < 1e-12);
        assert_true(col.x == 1 && col.y == 0 && col.z == 1);
        vt_ok(vv_tf_add_opacity(&tf, 100, 0.05)); /* a point added in the editor */
        assert_int_equal(vv_tf_get_contrast(&tf, NULL, NULL, NULL, NULL, NULL), 0);
    }
    vv_tf empty;
    vv_tf_init(&empty);
    assert_int_equal(vv_tf_get_contrast(&empty, NULL, NULL, NULL, NULL, NULL), 0);
}

/* Slices of two channels blend additively by their contrast functions:
 * each ball shows its channel's colour scaled by ((v - lo)/(hi - lo))^gamma,
 * the background black, a hidden channel nothing; per-channel samples equal
 * the one-channel object's. */
static void
test_slice_blend(void **state) {
    (void)state;
    vv_volume *v[2] = {ball(12, 20, 20, 6), ball(28, 20, 20, 6)};
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v[0], "two"));
    vt_ok(vv_object_set_channels(o, 2, v, NULL));
    vt_ok(vv_tf_set_contrast(&o->channels[0].tf, 0, 400, 1.0, 0.5, vv_vec3_make(1, 0, 1), 1));
    vt_ok(vv_tf_set_contrast(&o->channels[1].tf, 0, 200, 2.0, 0.3, vv_vec3_make(0, 1, 0), 1));
    vv_slice_plane p;
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_AXIAL, VV_SPACE_UNKNOWN, vv_vec3_make(20, 20, 20), N,
                                  N, 1));
    size_t n = (size_t)N * N;
    float *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *ref = malloc(n * sizeof *ref);
    uint8_t *rgba = malloc(4 * n);
    vt_ok(vv_slice_sample_channel(o, 0, &p, a));
    vt_ok(vv_slice_sample_channel(o, 1, &p, b));
    vv_object *one = NULL;
    vt_ok(vv_object_new_volume(&one, v[1], "one"));
    vt_ok(vv_slice_sample(one, &p, ref));
    assert_memory_equal(b, ref, n * sizeof *b);
    const float *vals[2] = {a, b};
    vv_slice_blend_channels(o, vals, n, vv_vec3_make(0, 0, 1), rgba);
    double x, y;
    vv_slice_plane_from_world(&p, vv_vec3_make(12, 20, 20), &x, &y, NULL);
    const uint8_t *px = rgba + 4 * ((size_t)y * N + (size_t)x);
    /* channel 0 at 200 of 0..400, gamma 1: half magenta */
    assert_int_equal(px[0], 128);
    assert_int_equal(px[1], 0);
    assert_int_equal(px[2], 128);
    vv_slice_plane_from_world(&p, vv_vec3_make(28, 20, 20), &x, &y, NULL);
    px = rgba + 4 * ((size_t)y * N + (size_t)x);
    assert_int_equal(px[0], 0);
    assert_int_equal(px[1], 255); /* 200 of 0..200: full green */
    assert_int_equal(px[2], 0);
    vv_slice_plane_from_world(&p, vv_vec3_make(20, 35, 20), &x, &y, NULL);
    px = rgba + 4 * ((size_t)y * N + (size_t)x);
    assert_true(px[0] == 0 && px[1] == 0 && px[2] == 0 && px[3] == 255);
    o->channels[1].visible = 0;
    vv_slice_blend_channels(o, vals, n, vv_vec3_make(0, 0, 1), rgba);
    vv_slice_plane_from_world(&p, vv_vec3_make(28, 20, 20), &x, &y, NULL);
    px = rgba + 4 * ((size_t)y * N + (size_t)x);
    assert_true(px[0] == 0 && px[1] == 0 && px[2] == 0);
    assert_int_equal(vv_slice_sample_channel(o, 2, &p, a), VV_ERR_INVALID);
    assert_non_null(strstr(vv_error_message(), "no channel 2"));
    assert_int_equal(vv_slice_sample_channel(one, 0, &p, a), VV_ERR_INVALID);
    free(a);
    free(b);
    free(ref);
    free(rgba);
    vv_object_free(one);
    vv_object_free(o);
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
}

/* u8 label volume N^3: label 1 in the box x 22..28, y 12..18, label 2 in
 * x 22..28, y 22..28 (z 14..26 both), 0 elsewhere. */
static vv_volume *
two_labels(void) {
    vv_volume *v = NULL;
    const int dims[3] = {N, N, N};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int k = 14; k <= 26; k++)
        for (int j = 12; j <= 28; j++)
            for (int i = 22; i <= 28; i++)
                vv_volume_set(v, i, j, k, j <= 18 ? 1 : j >= 22 ? 2 : 0);
    vv_volume_update_range(v);
    return v;
}

static int
near_rgb(const float *p, vv_vec3 c, double tol) {
    return fabs(p[0] - c.x) <= tol && fabs(p[1] - c.y) <= tol && fabs(p[2] - c.z) <= tol;
}

/* A label volume as one channel (vv_object_set_channel_labels): under
 * every rule, in the ray caster and the ray tracer, each label's region
 * shows vv_label_color(label) (unshaded, opaque) and the other channel its
 * own colour; the label channel alone draws as the one-channel object with
 * VV_SEG_LABELS (the general kernel, another code path); slices take the
 * nearest label and add half its colour; a float channel or a missing one
 * is refused, and the flag survives a clone. */
static void
test_label_channel(void **state) {
    (void)state;
    vv_volume *v[2] = {ball(10, 20, 20, 6), two_labels()};
    const vv_vec3 l1 = vv_label_color(1), l2 = vv_label_color(2);
    vv_view view = view_z(N);
    for (int rule = 0; rule < 3; rule++) {
        vv_world *w = channel_world(v, 2, (vv_channel_blend)rule, 0, 1.0);
        vt_ok(vv_object_set_channel_labels(w->objects[0], 1, 1));
        for (int rt = 0; rt < 2; rt++) {
            vv_image *img = rt ? render_rt(w, &view, 0) : render(w, &view);
            if (rule == 0 && rt == 0)
                save(img, "channels_labels");
            const double tol = rule == VV_BLEND_MAXIMUM ? 0.02 : 0.002;
            if (!near_rgb(at_voxel(img, 25, 15), l1, tol) ||
                !near_rgb(at_voxel(img, 25, 25), l2, tol))
                fail_msg("%s, %s: label colours (%g %g %g), (%g %g %g)",
                         rt ? "raytrace" : "raycast", vv_channel_blend_name(rule),
                         at_voxel(img, 25, 15)[0], at_voxel(img, 25, 15)[1],
                         at_voxel(img, 25, 15)[2], at_voxel(img, 25, 25)[0],
                         at_voxel(img, 25, 25)[1], at_voxel(img, 25, 25)[2]);
            const float *b = at_voxel(img, 10, 20); /* the ball: red only */
            assert_true(b[0] > 0.5f && b[1] < 0.01f && b[2] < 0.01f);
            const float *gap = at_voxel(img, 25, 20); /* label 0 between the boxes */
            assert_true(gap[0] < 0.01f && gap[1] < 0.01f && gap[2] < 0.01f);
            vv_image_free(img);
        }
        vv_world_free(w);
    }
    /* the label channel alone against the one-channel labels object */
    vv_world *w = channel_world(v, 2, VV_BLEND_COMPOSITE, 1, 1.0);
    vt_ok(vv_object_set_channel_labels(w->objects[0], 1, 1));
    w->objects[0]->channels[0].visible = 0;
    vv_world *one = single_world(w, 1, VV_MODE_COMPOSITE);
    one->objects[0]->segmentation = VV_SEG_LABELS;
    vv_image *a = render(w, &view), *b = render(one, &view);
    assert_true(max_rgb_diff(a, b) < 1e-4);
    vv_image_free(a);
    vv_image_free(b);
    /* clones keep the flag */
    vv_object *c = NULL;
    vt_ok(vv_object_clone(&c, w->objects[0]));
    assert_int_equal(c->channels[1].labels, 1);
    assert_int_equal(c->channels[0].labels, 0);
    vv_object_free(c);
    /* slices: nearest labels, half their colour */
    vv_slice_plane p;
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_AXIAL, VV_SPACE_UNKNOWN, vv_vec3_make(20, 20, 20), N,
                                  N, 1));
    const size_t n = (size_t)N * N;
    float *s0 = malloc(n * sizeof *s0), *s1 = malloc(n * sizeof *s1);
    uint8_t *rgba = malloc(4 * n);
    vt_ok(vv_slice_sample_channel(w->objects[0], 0, &p, s0));
    vt_ok(vv_slice_sample_channel(w->objects[0], 1, &p, s1));
    for (size_t i = 0; i < n; i++)
        assert_true(s1[i] != s1[i] || s1[i] == 0 || s1[i] == 1 || s1[i] == 2);
    w->objects[0]->channels[0].visible = 1;
    const float *vals[2] = {s0, s1};
    vv_slice_blend_channels(w->objects[0], vals, n, vv_vec3_make(0, 0, 0), rgba);
    double x, y;
    vv_slice_plane_from_world(&p, vv_vec3_make(25, 25, 20), &x, &y, NULL);
    const uint8_t *q = rgba + 4 * ((size_t)y * N + (size_t)x);
    assert_true(abs(q[0] - (int)lrint(0.5 * l2.x * 255)) <= 1 &&
                abs(q[1] - (int)lrint(0.5 * l2.y * 255)) <= 1 &&
                abs(q[2] - (int)lrint(0.5 * l2.z * 255)) <= 1);
    free(s0);
    free(s1);
    free(rgba);
    /* bad input */
    vt_err(vv_object_set_channel_labels(w->objects[0], 2, 1));
    assert_non_null(strstr(vv_error_message(), "channels 0..1, not 2"));
    vt_err(vv_object_set_channel_labels(one->objects[0], 0, 1));
    vv_volume *f[2] = {NULL, NULL};
    const int dims[3] = {N, N, N};
    vt_ok(vv_volume_new(&f[0], dims, VV_U8));
    vt_ok(vv_volume_new(&f[1], dims, VV_F32));
    vv_object *fo = NULL;
    vt_ok(vv_object_new_volume(&fo, f[0], "mixed"));
    vt_ok(vv_object_set_channels(fo, 2, f, NULL));
    vt_err(vv_object_set_channel_labels(fo, 1, 1));
    assert_non_null(strstr(vv_error_message(), "labels are integers"));
    assert_int_equal(fo->channels[1].labels, 0);
    vv_object_free(fo);
    vv_volume_free(f[0]);
    vv_volume_free(f[1]);
    vv_world_free(w);
    vv_world_free(one);
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_three_balls),
        cmocka_unit_test(test_additive_is_sum),
        cmocka_unit_test(test_maximum_is_sum_of_mips),
        cmocka_unit_test(test_maximum_one_pass_exact),
        cmocka_unit_test(test_composite_mix),
        cmocka_unit_test(test_raytrace_agrees),
        cmocka_unit_test(test_raytrace_shadows),
        cmocka_unit_test(test_deterministic_and_clone),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_scene_round_trip),
        cmocka_unit_test(test_contrast_read_back),
        cmocka_unit_test(test_slice_blend),
        cmocka_unit_test(test_label_channel),
    };
    return vt_run_tests(tests, NULL, NULL);
}
