/*
 * Tests of the splatting renderer (src/render/splat/splat.c).
 *
 * Agreement with the ray caster on a transformed, cut volume (the real
 * and analytic volumes are in test_splat_agree.c); energy conservation of X-ray footprints; no
 * popping under 1-degree rotations (and the axis-aligned sheet buffer
 * failing that test); EWA antialiasing of a far checkerboard; threads and
 * determinism; voxel-list reuse and culling; progress and cancel; bad
 * input. Images go to build/test-out/render_splat/.
 */
#include "splat_common.h"

/* Neghip turned and scaled by an object transform, with a cut plane. */
static void
test_agree_transform_cut(void **state) {
    (void)state;
    if (!vt_have_data("volumes/neghip.slc"))
        vt_skip("../shared/data/volumes/neghip.slc is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    v->spacing[2] = 1.7; /* anisotropic */
    vv_world *w = scene_for(v, 128, 10, 35);
    vv_object *o = w->objects[0];
    o->orientation = vv_quat_from_axis_angle(vv_vec3_make(1, 2, 0.5), vv_deg_to_rad(40));
    o->scale = vv_vec3_make(1.2, 0.8, 1.0);
    w->n_cut_planes = 1;
    w->cut_planes[0].point = vv_vec3_make(0, 0, 0);
    w->cut_planes[0].normal = vv_vec3_normalize(vv_vec3_make(0.3, 1, 0.2));
    const double pc = agreement(w, VV_MODE_COMPOSITE, "neghip_transform_cut");
    const double pm = agreement(w, VV_MODE_MIP, "neghip_transform_cut_mip");
    vv_world_free(w);
    vv_volume_free(v);
    if (!(pc >= 28) || !(pm >= 35))
        fail_msg("transformed, cut neghip: composite %.2f dB (>= 28), MIP %.2f dB (>= 35)", pc, pm);
}

/* Two volumes overlapping on screen and in depth: their samples are
 * composited together, sheet by sheet, like the ray caster's. */
static void
test_agree_two_objects(void **state) {
    (void)state;
    vv_volume *v = marschner_lobb(40);
    vv_world *w = scene_for(v, 96, 25, 15);
    vv_object *a = w->objects[0];
    vv_tf_init(&a->tf);
    vv_tf_add_opacity(&a->tf, 0.45, 0.0);
    vv_tf_add_opacity(&a->tf, 0.7, 0.6);
    vv_tf_add_color(&a->tf, 0, vv_vec3_make(1, 0.5, 0.2));
    vv_tf_add_color(&a->tf, 1, vv_vec3_make(1, 0.9, 0.6));
    a->shading = 1;
    vv_object *b = NULL;
    vt_ok(vv_object_new_volume(&b, v, "second"));
    b->mode = VV_MODE_COMPOSITE;
    b->shading = 1;
    b->material = a->material;
    b->tf = a->tf;
    vv_tf_init(&b->tf);
    vv_tf_add_opacity(&b->tf, 0.3, 0.0);
    vv_tf_add_opacity(&b->tf, 0.6, 0.5);
    vv_tf_add_color(&b->tf, 0, vv_vec3_make(0.2, 0.5, 1));
    vv_tf_add_color(&b->tf, 1, vv_vec3_make(0.6, 0.9, 1));
    b->position = vv_vec3_add(a->position, vv_vec3_make(0.9, 0.4, 0.5));
    b->orientation = vv_quat_from_axis_angle(vv_vec3_make(0, 0, 1), vv_deg_to_rad(30));
    vt_ok(vv_world_add_object(w, b));
    const double p = agreement(w, VV_MODE_COMPOSITE, "two_objects");
    vv_world_free(w);
    vv_volume_free(v);
    if (!(p >= 28))
        fail_msg("two overlapping objects: composite PSNR %.2f dB < 28", p);
}

/* ---------------------------------------------------------------------- */
/* Energy: X-ray footprints integrate to the voxels' sum                    */

static void
test_xray_energy(void **state) {
    (void)state;
    const int nx = 24, ny = 20, nz = 16;
    vv_volume *v = new_volume(nx, ny, nz, VV_F32, 1.0, 1.5, 0.7);
    uint64_t seed = 12345;
    double sum = 0;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
                const double x = 1.0 + (double)(seed >> 40) / (double)(1ULL << 24) * 9.0;
                vv_volume_set(v, i, j, k, x);
                sum += x;
            }
    vv_volume_update_range(v);
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "noise"));
    o->mode = VV_MODE_XRAY;
    o->position = vv_vec3_make(-11.5, -14.25, -5.25);
    vt_ok(vv_world_add_object(w, o));
    vv_renderer *sp = new_r("splat");
    static const double dirs[][3] = {{0, 0, 1}, {1, 0, 0}, {0.3, -0.5, 0.8}, {-0.7, 0.6, 0.4}};
    for (int rot = 0; rot < 2; rot++) {
        /* also with an object rotation and scale */
        if (rot) {
            o->orientation = vv_quat_from_axis_angle(vv_vec3_make(1, 1, 0), vv_deg_to_rad(33));
            o->scale = vv_vec3_make(1.3, 1, 0.9);
        }
        const double det = 1.0 * 1.5 * 0.7 * (rot ? 1.3 * 0.9 : 1.0);
        for (size_t d = 0; d < sizeof dirs / sizeof dirs[0]; d++) {
            vv_view view;
            memset(&view, 0, sizeof view);
            const vv_vec3 dir = vv_vec3_normalize(vv_vec3_make(dirs[d][0], dirs[d][1], dirs[d][2]));
            view.eye = vv_vec3_scale(dir, 100);
            view.at = vv_vec3_make(0, 0, 0);
            view.up = fabs(dir.z) > 0.9 ? vv_vec3_make(0, 1, 0) : vv_vec3_make(0, 0, 1);
            view.projection = VV_PROJECTION_ORTHOGRAPHIC;
            view.ortho_height = 64;
            view.width = view.height = 96;
            vv_image *img = render_q(sp, w, &view, 0, 2);
            const float *xi = vv_splat_xray_integral(sp);
            assert_non_null(xi);
            double e = 0;
            for (int i = 0; i < 96 * 96; i++)
                e += xi[i];
            const double pa = (64.0 / 96) * (64.0 / 96);
            const double rel = e * pa / (sum * det) - 1;
            print_message("energy, view %zu%s: relative error %.2e\n", d, rot ? ", rotated" : "",
                          rel);
            if (!(fabs(rel) <= 1e-3))
                fail_msg("X-ray energy off by %.3g (view %zu, rotated %d)", rel, d, rot);
            vv_image_free(img);
        }
    }
    vv_renderer_free(sp);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* No popping                                                               */

/* Mean 8-bit differences of consecutive frames of an orbit in 1-degree
 * steps from azimuth a0 (elevation 0), for n frames. */
static void
orbit_diffs(vv_renderer *r, vv_world *w, double a0, int n, double *d) {
    vv_view v0 = w->view;
    vv_image *prev = NULL;
    for (int f = 0; f < n; f++) {
        vv_view view = v0;
        vv_view_orbit(&view, vv_deg_to_rad(a0 + f), 0);
        vv_image *img = render_q(r, w, &view, 0, 2);
        if (prev)
            d[f - 1] = mean_abs_diff8(prev, img);
        vv_image_free(prev);
        prev = img;
    }
    vv_image_free(prev);
}

static void
test_no_popping(void **state) {
    (void)state;
    if (!vt_have_data("volumes/neghip.slc"))
        vt_skip("../shared/data/volumes/neghip.slc is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    /* ortho, looking along +x rotated about z: the axis-aligned method
     * switches from x to y slices at 45 degrees */
    vv_world *w = scene_for(v, 96, 0, 0);
    w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    w->view.eye = vv_vec3_make(-200, 0, 0);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.up = vv_vec3_make(0, 0, 1);
    w->view.ortho_height = 80;
    vv_object *o = w->objects[0];
    o->shading = 1;
    vv_tf_init(&o->tf);
    /* a semi-transparent band: which samples a ray takes shows */
    vv_tf_add_opacity(&o->tf, 30, 0.0);
    vv_tf_add_opacity(&o->tf, 40, 0.3);
    vv_tf_add_opacity(&o->tf, 50, 0.0);
    vv_tf_add_color(&o->tf, 40, vv_vec3_make(1, 0.6, 0.3));
    vv_tf_add_color(&o->tf, 255, vv_vec3_make(1, 1, 1));
    enum { N = 9 };
    const double a0 = 41;
    double dr[N - 1], ds[N - 1], da[N - 1];
    vv_renderer *rc = new_r("raycast"), *sp = new_r("splat"), *ax = new_r("splat");
    vt_ok(vv_renderer_set_option(ax, "sheets", "axis"));
    orbit_diffs(rc, w, a0, N, dr);
    orbit_diffs(sp, w, a0, N, ds);
    orbit_diffs(ax, w, a0, N, da);
    int splat_ok = 1, axis_pops = 0;
    for (int i = 0; i < N - 1; i++) {
        print_message("%g -> %g deg: raycast %.3f, splat %.3f, axis-aligned %.3f\n", a0 + i,
                      a0 + i + 1, dr[i], ds[i], da[i]);
        splat_ok &= ds[i] <= 2 * dr[i];
        axis_pops |= da[i] > 2 * dr[i];
    }
    vv_renderer_free(rc);
    vv_renderer_free(sp);
    vv_renderer_free(ax);
    vv_world_free(w);
    vv_volume_free(v);
    if (!splat_ok)
        fail_msg("image-aligned splatting: a 1-degree step changed the image more than twice "
                 "as much as the ray caster's");
    if (!axis_pops)
        fail_msg("the axis-aligned sheet buffer did not pop: the test cannot tell the methods "
                 "apart");
}

/* ---------------------------------------------------------------------- */
/* EWA: a far checkerboard averages to grey                                 */

static void
test_ewa_checkerboard(void **state) {
    (void)state;
    const int n = 128, nz = 4;
    vv_volume *v = new_volume(n, n, nz, VV_U8, 1, 1, 1);
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                vv_volume_set(v, i, j, k, ((i + j) & 1) ? 255 : 0);
    vv_volume_update_range(v);
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    w->background = vv_vec3_make(0, 0, 0);
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "checker"));
    o->mode = VV_MODE_COMPOSITE;
    o->shading = 0;
    o->position = vv_vec3_make(-63.5, -63.5, -1.5);
    vv_tf_init(&o->tf);
    vv_tf_add_opacity(&o->tf, 0, 1.0);
    vv_tf_add_opacity(&o->tf, 255, 1.0);
    vv_tf_add_color(&o->tf, 0, vv_vec3_make(0, 0, 0));
    vv_tf_add_color(&o->tf, 255, vv_vec3_make(1, 1, 1));
    vt_ok(vv_world_add_object(w, o));
    vv_view view;
    memset(&view, 0, sizeof view);
    /* far away: the 128-voxel face spans about 30 pixels, turned 7 degrees */
    view.eye = vv_vec3_make(0, 0, 100);
    view.at = vv_vec3_make(0, 0, 0);
    view.up = vv_vec3_make(sin(vv_deg_to_rad(7)), cos(vv_deg_to_rad(7)), 0);
    view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    view.ortho_height = 256;
    view.width = view.height = 64;
    vv_renderer *rc = new_r("raycast"), *sp = new_r("splat");
    vv_image *a = render_q(rc, w, &view, 0, 2), *b = render_q(sp, w, &view, 0, 2);
    write_png(a, "checker_raycast");
    write_png(b, "checker_splat");
    /* the grey of the interior pixels (the face's central 20 x 20) */
    double m[2] = {0, 0}, sd[2] = {0, 0};
    const vv_image *im[2] = {a, b};
    for (int t = 0; t < 2; t++) {
        double s1 = 0, s2 = 0;
        int cnt = 0;
        for (int y = 22; y < 42; y++)
            for (int x = 22; x < 42; x++) {
                const float *p = im[t]->rgba + 4 * ((size_t)y * 64 + (size_t)x);
                const double g = p[0] / (p[3] > 0 ? p[3] : 1);
                s1 += g;
                s2 += g * g;
                cnt++;
            }
        m[t] = s1 / cnt;
        sd[t] = sqrt(fmax(0, s2 / cnt - m[t] * m[t]));
    }
    print_message("checkerboard: ray caster mean %.3f sd %.3f; splat mean %.3f sd %.3f\n", m[0],
                  sd[0], m[1], sd[1]);
    /* the splat is grey; the point-sampling ray caster shows moire */
    assert_true(fabs(m[1] - 0.5) < 0.05);
    assert_true(sd[1] < 0.03);
    assert_true(sd[0] > 0.1);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(rc);
    vv_renderer_free(sp);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Threads, voxel lists, occlusion culling, pre-classification, quality    */

static int
identical(const vv_image *a, const vv_image *b) {
    const size_t n = (size_t)a->width * (size_t)a->height;
    return memcmp(a->rgba, b->rgba, 4 * n * sizeof(float)) == 0 &&
           memcmp(a->depth, b->depth, n * sizeof(float)) == 0;
}

static void
test_threads_lists_culling(void **state) {
    (void)state;
    if (!vt_have_data("volumes/neghip.slc"))
        vt_skip("../shared/data/volumes/neghip.slc is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_world *w = scene_for(v, 96, 30, 20);
    /* opaque enough that the occlusion map has work */
    vv_tf_init(&w->objects[0]->tf);
    vv_tf_add_opacity(&w->objects[0]->tf, 30, 0.0);
    vv_tf_add_opacity(&w->objects[0]->tf, 60, 1.0);
    vv_renderer *sp = new_r("splat");
    vv_image *a = render_q(sp, w, &w->view, 1, 2);
    const vv_splat_stats st1 = *vv_splat_stats_get(sp);
    assert_int_equal(st1.lists_built, 1);
    assert_true(st1.listed < st1.voxels); /* empty voxels skipped */
    vv_image *b = render_q(sp, w, &w->view, 2, 2);
    assert_int_equal(vv_splat_stats_get(sp)->lists_built, 0); /* reused */
    vv_image *c = render_q(sp, w, &w->view, 3, 2);
    assert_true(identical(a, b));
    assert_true(identical(a, c));
    /* a small turn stays in the octant: the list is reused */
    vv_view turned = w->view;
    vv_view_orbit(&turned, vv_deg_to_rad(3), 0);
    vv_image *d = render_q(sp, w, &turned, 0, 2);
    assert_int_equal(vv_splat_stats_get(sp)->lists_built, 0);
    assert_false(identical(a, d));
    /* occlusion culling changes nothing in the image */
    assert_true(st1.culled > 0);
    vt_ok(vv_renderer_set_option(sp, "occlusion_culling", "0"));
    vv_image *e = render_q(sp, w, &w->view, 2, 2);
    assert_int_equal(vv_splat_stats_get(sp)->culled, 0);
    assert_true(vv_splat_stats_get(sp)->footprints > st1.footprints);
    assert_true(identical(a, e));
    /* nor does empty-voxel skipping, beyond rounding */
    vt_ok(vv_renderer_set_option(sp, "empty_space_skipping", "0"));
    vv_image *f = render_q(sp, w, &w->view, 2, 2);
    assert_int_equal(vv_splat_stats_get(sp)->listed, vv_splat_stats_get(sp)->voxels);
    const double pskip = vv_image_psnr(a, f);
    print_message("skipping on/off: PSNR %.2f dB\n", pskip);
    assert_true(pskip >= 50);
    /* a new transfer function builds a new list */
    vt_ok(vv_renderer_set_option(sp, "empty_space_skipping", "1"));
    vv_tf_init(&w->objects[0]->tf);
    vv_tf_add_opacity(&w->objects[0]->tf, 200, 0.0);
    vv_tf_add_opacity(&w->objects[0]->tf, 255, 0.9);
    vv_image *g = render_q(sp, w, &w->view, 2, 2);
    assert_int_equal(vv_splat_stats_get(sp)->lists_built, 1);
    vv_image *imgs[] = {a, b, c, d, e, f, g};
    for (size_t i = 0; i < sizeof imgs / sizeof imgs[0]; i++)
        vv_image_free(imgs[i]);
    vv_renderer_free(sp);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_preclassified_and_quality(void **state) {
    (void)state;
    if (!vt_have_data("volumes/neghip.slc"))
        vt_skip("../shared/data/volumes/neghip.slc is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_world *w = scene_for(v, 128, 30, 20);
    vv_renderer *rc = new_r("raycast"), *sp = new_r("splat"), *pre = new_r("splat");
    vt_ok(vv_renderer_set_option(pre, "classification", "pre"));
    vv_image *a = render(rc, w), *b = render(sp, w), *c = render(pre, w);
    const vv_splat_stats *sb = vv_splat_stats_get(sp);
    const uint64_t listed_post = sb->listed;
    const vv_splat_stats *sc = vv_splat_stats_get(pre);
    write_png(c, "neghip_preclassified");
    const double p_post = vv_image_psnr(a, b), p_pre = vv_image_psnr(a, c);
    print_message("neghip composite: post-classified %.2f dB, pre-classified %.2f dB "
                  "(%llu and %llu voxels listed)\n",
                  p_post, p_pre, (unsigned long long)listed_post, (unsigned long long)sc->listed);
    assert_true(sc->listed < listed_post); /* only voxels visible by themselves */
    assert_true(p_pre >= 20);
    assert_true(p_post > p_pre); /* post-classification is the sharper, closer one */
    /* quality: fewer footprints, still the same picture */
    double prev_fp = INFINITY;
    for (int q = 2; q >= 0; q--) {
        vv_image *d = render_q(sp, w, &w->view, 0, q);
        const double fp = (double)vv_splat_stats_get(sp)->footprints;
        const double p = vv_image_psnr(a, d);
        print_message("quality %d: %.0f footprints, %.2f dB\n", q, fp, p);
        assert_true(fp < prev_fp);
        assert_true(p >= 28);
        prev_fp = fp;
        vv_image_free(d);
    }
    vv_image_free(a);
    vv_image_free(b);
    vv_image_free(c);
    vv_renderer_free(rc);
    vv_renderer_free(sp);
    vv_renderer_free(pre);
    vv_world_free(w);
    vv_volume_free(v);
}

/* ---------------------------------------------------------------------- */
/* Progress, cancel, bad input                                              */

typedef struct progress_log {
    int n, cancel_at;
    double last;
    int monotone;
} progress_log;

static int
on_progress(void *user, double fraction) {
    progress_log *l = user;
    l->monotone &= fraction >= l->last;
    l->last = fraction;
    l->n++;
    return l->cancel_at > 0 && l->n >= l->cancel_at;
}

static void
test_progress_and_cancel(void **state) {
    (void)state;
    vv_volume *v = marschner_lobb(32);
    vv_world *w = scene_for(v, 64, 30, 20);
    vv_renderer *sp = new_r("splat");
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 64, 64));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = 2;
    progress_log log = {0, 0, 0, 1};
    opt.progress.fn = on_progress;
    opt.progress.user = &log;
    vt_ok(vv_renderer_render(sp, w, &w->view, &opt, img));
    assert_true(log.n >= 2);
    assert_true(log.monotone);
    assert_near(log.last, 1.0, 1e-12);
    progress_log l2 = {0, 1, 0, 1};
    opt.progress.user = &l2;
    vv_error_clear();
    assert_int_equal(vv_renderer_render(sp, w, &w->view, &opt, img), VV_ERR_CANCELLED);
    assert_non_null(strstr(vv_error_message(), "cancel"));
    vv_image_free(img);
    vv_renderer_free(sp);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_bad_input(void **state) {
    (void)state;
    vv_renderer *sp = new_r("splat");
    vt_err(vv_renderer_set_option(sp, "radius", "0"));
    assert_non_null(strstr(vv_error_message(), "radius"));
    vt_err(vv_renderer_set_option(sp, "radius", "1e9"));
    vt_err(vv_renderer_set_option(sp, "radius", "nan"));
    vt_err(vv_renderer_set_option(sp, "sigma", "0"));
    vt_err(vv_renderer_set_option(sp, "sigma", "-1"));
    assert_non_null(strstr(vv_error_message(), "sigma"));
    vt_err(vv_renderer_set_option(sp, "classification", "mid"));
    vt_err(vv_renderer_set_option(sp, "no_such_option", "1"));
    vt_err(vv_renderer_set_option(sp, "sheet_spacing", "0.01"));

    /* an empty volume (every voxel transparent): the background, nothing listed */
    vv_volume *v = new_volume(16, 16, 16, VV_U8, 1, 1, 1);
    vv_volume_update_range(v);
    vv_world *w = scene_for(v, 32, 0, 0);
    w->background = vv_vec3_make(0.2, 0.3, 0.4);
    vv_object *o = w->objects[0];
    vv_tf_init(&o->tf);
    vv_tf_add_opacity(&o->tf, 0, 0.0);
    vv_tf_add_opacity(&o->tf, 255, 0.0);
    vv_image *img = render(sp, w);
    for (int i = 0; i < 32 * 32; i++) {
        assert_near(img->rgba[4 * i], 0.2, 1e-6);
        assert_near(img->rgba[4 * i + 2], 0.4, 1e-6);
        assert_near(img->rgba[4 * i + 3], 0, 0);
    }
    assert_int_equal(vv_splat_stats_get(sp)->listed, 0);
    vv_image_free(img);
    /* one voxel: renders */
    vv_volume *one = new_volume(1, 1, 1, VV_F32, 1, 1, 1);
    vv_volume_set(one, 0, 0, 0, 5);
    vv_volume_update_range(one);
    vv_world *w1 = scene_for(one, 16, 0, 0);
    img = render(sp, w1);
    vv_image_free(img);
    vv_world_free(w1);
    vv_volume_free(one);
    /* iso mode is the ray caster's and the surface renderer's */
    o->mode = VV_MODE_ISO;
    vv_image *out = NULL;
    vt_ok(vv_image_new(&out, 32, 32));
    vt_err(vv_renderer_render(sp, w, &w->view, NULL, out));
    assert_non_null(strstr(vv_error_message(), "iso"));
    o->mode = VV_MODE_COMPOSITE;
    o->step = 0;
    vt_err(vv_renderer_render(sp, w, &w->view, NULL, out));
    o->step = 0.5;
    /* a huge kernel renders (slowly, but correctly) */
    vt_ok(vv_renderer_set_option(sp, "radius", "8"));
    vt_ok(vv_renderer_set_option(sp, "sigma", "4"));
    vv_tf_add_opacity(&o->tf, 0, 0.5);
    vt_ok(vv_renderer_render(sp, w, &w->view, NULL, out));
    vv_image_free(out);
    vv_world_free(w);
    vv_volume_free(v);
    vv_renderer_free(sp);
}

/* The eye inside the volume (perspective): an image like the ray caster's. */
/* Issue 32's accuracy check: the quality-2 image, and quality 1's, against
 * the converged reference, the same renderer with sheets at 1/16 of the
 * step and 4 x 4 pixels a pixel (vt_converged_reference); neghip's default
 * scene. The floors sit about 1 dB under the values measured when the test
 * was written, to guard the speed work. */
static void
test_converged_reference(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_world *w = scene_for(v, 64, 30, 20);
    vv_renderer *r = new_r("splat");
    vv_image *ref = vt_converged_reference(r, w, 16, 4);
    vv_image *q2 = vt_render_q(r, w, 2, 0, NULL), *q1 = vt_render_q(r, w, 1, 0, NULL);
    const double p2 = vv_image_psnr(q2, ref), p1 = vv_image_psnr(q1, ref);
    print_message("splat, neghip against the converged reference: quality 2 %.2f dB, quality 1 "
                  "%.2f dB\n",
                  p2, p1);
    write_png(q2, "converged_q2");
    write_png(ref, "converged_ref");
    assert_true(p2 >= 46);   /* measured 46.91 dB */
    assert_true(p1 >= 45.5); /* 46.76 */
    vv_image *imgs[] = {ref, q2, q1};
    for (size_t i = 0; i < 3; i++)
        vv_image_free(imgs[i]);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_view_inside(void **state) {
    (void)state;
    vv_volume *v = marschner_lobb(48);
    vv_world *w = scene_for(v, 64, 20, 10);
    vv_object *o = w->objects[0];
    vv_tf_init(&o->tf);
    vv_tf_add_opacity(&o->tf, 0.5, 0.0);
    vv_tf_add_opacity(&o->tf, 1.0, 0.3);
    vv_tf_add_color(&o->tf, 0, vv_vec3_make(1, 0.8, 0.6));
    vv_tf_add_color(&o->tf, 1, vv_vec3_make(1, 1, 1));
    /* the eye a quarter of the way in from the centre */
    vv_vec3 c = vv_vec3_make(0, 0, 0);
    vv_vec3 dir = vv_vec3_normalize(vv_vec3_sub(w->view.eye, w->view.at));
    w->view.at = c;
    w->view.eye = vv_vec3_add(c, vv_vec3_scale(dir, 0.4));
    vv_renderer *rc = new_r("raycast"), *sp = new_r("splat");
    vv_image *a = render(rc, w), *b = render(sp, w);
    write_png(a, "inside_raycast");
    write_png(b, "inside_splat");
    const double p = vv_image_psnr(a, b);
    print_message("view inside the volume: PSNR %.2f dB\n", p);
    assert_true(p >= 25);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(rc);
    vv_renderer_free(sp);
    vv_world_free(w);
    vv_volume_free(v);
}

int
main(int argc, char **argv) {
    /* an optional test name pattern, e.g. test_render_splat 'test_agree_*' */
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_agree_transform_cut),
        cmocka_unit_test(test_agree_two_objects),
        cmocka_unit_test(test_xray_energy),
        cmocka_unit_test(test_no_popping),
        cmocka_unit_test(test_ewa_checkerboard),
        cmocka_unit_test(test_threads_lists_culling),
        cmocka_unit_test(test_preclassified_and_quality),
        cmocka_unit_test(test_progress_and_cancel),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_view_inside),
        cmocka_unit_test(test_converged_reference),
    };
    return vt_run_tests(tests, NULL, NULL);
}
