/*
 * The ray caster's shading=table (src/render/shade_table.h): a diffuse and
 * a specular term per 16-bit normal code, blended over a cell's corners.
 * Checked against the ray caster's own Phong (the default) on real volumes
 * (the CT head and neghip of ../shared/data): its image is at least 40 dB
 * from Phong's at the same settings, and not Phong's (the table path ran);
 * the table is built on the first frame and not again for the same one;
 * the portable path (float table) agrees with the AVX2 one (>= 60 dB);
 * it is rebuilt when the light moves, and the image follows the light (the
 * table image under the new light is >= 40 dB from Phong's under it, and
 * far from its own image under the old one); an orthographic camera
 * moved parallel to itself (a pan: view direction and headlight unchanged)
 * reuses it, a turned one rebuilds it; vv_render_options.fast_shading
 * gives the table image with shading=phong set, and the Navigator's reduced
 * previews shade by table while its final frame keeps Phong.
 * The PNGs go to build/.../test-out/render/ to look at.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "volvis/navigator.h"
#include "volvis/render.h"

static vv_image *
render(vv_renderer *r, const vv_world *w, int fast, vv_render_stats *st) {
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = 2;
    opt.stats = st;
    opt.fast_shading = fast;
    vt_ok(vv_renderer_render(r, w, &w->view, &opt, img));
    return img;
}

static void
write_png(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.png", vt_outdir("render"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* Renders with a fresh shading=table renderer and returns the frame and
 * the tables it built. */
static vv_image *
render_table(vv_renderer *t, const vv_world *w, uint32_t *built) {
    vv_render_stats st = {0};
    vv_image *img = render(t, w, 0, &st);
    *built = st.shading_tables_built;
    return img;
}

static void
check_volume(const char *file, const char *tag, double lo, double hi) {
    if (!vt_have_data(file)) {
        vt_skip("%s is missing (../shared/data)", file);
        return;
    }
    vv_volume *vol = NULL;
    vv_world *w = vt_volume_scene(file, 256, &vol);
    vv_object *o = w->objects[0];
    assert_int_equal(o->mode, VV_MODE_COMPOSITE);
    assert_true(o->shading);
    vv_tf_set_ramp(&o->tf, lo, hi, 0.5, vv_vec3_make(1, 0.9, 0.8), o->tf.opacity_unit_distance);
    vv_renderer *phong = NULL, *table = NULL;
    vt_ok(vv_renderer_new(&phong, "raycast"));
    vt_ok(vv_renderer_new(&table, "raycast"));
    vt_ok(vv_renderer_set_option(table, "shading", "table"));
    vt_err(vv_renderer_set_option(table, "shading", "gouraud"));

    /* the same settings: >= 40 dB, and not the Phong image itself */
    uint32_t built = 0;
    vv_image *p = render(phong, w, 0, NULL), *t = render_table(table, w, &built);
    assert_int_equal(built, 1);
    int same = 0;
    const double db = vt_image_psnr(p, t, &same);
    char name[256];
    snprintf(name, sizeof name, "shade_table_%s_phong", tag);
    write_png(p, name);
    snprintf(name, sizeof name, "shade_table_%s_table", tag);
    write_png(t, name);
    print_message("%s: shading=table %.2f dB from Phong\n", tag, db);
    assert_false(same);
    assert_true(db >= 40.0);
    /* the next frame of the same view reuses the table: the same image */
    vv_image *t2 = render_table(table, w, &built);
    assert_int_equal(built, 0);
    assert_true(vt_image_psnr(t, t2, &same) == INFINITY && same);
    /* the portable path (float table, corners kept while the ray stays in
     * a cell) against the AVX2 one (16-bit packed table) */
    vt_ok(vv_renderer_set_option(table, "simd", "0"));
    vv_image *tp = render_table(table, w, &built);
    vt_ok(vv_renderer_set_option(table, "simd", "1"));
    const double db_portable = vt_image_psnr(t, tp, NULL);
    print_message("%s: portable table path %.2f dB from the AVX2 one\n", tag, db_portable);
    assert_true(db_portable >= 60.0);
    vv_image_free(tp);
    /* fast_shading (previews) on a Phong renderer: the table image */
    vv_render_stats st = {0};
    vv_image *f = render(phong, w, 1, &st);
    assert_int_equal(st.shading_tables_built, 1);
    vt_image_psnr(t, f, &same);
    assert_true(same);

    /* a light from the side instead of the headlight: rebuilt, and the
     * image follows the light */
    w->lights[0].headlight = 0;
    w->lights[0].type = VV_LIGHT_DIRECTIONAL;
    const vv_vec3 f3 = vv_vec3_sub(w->view.at, w->view.eye);
    const vv_vec3 side = vv_vec3_normalize(vv_vec3_cross(f3, w->view.up));
    w->lights[0].direction = vv_vec3_normalize(vv_vec3_add(vv_vec3_normalize(f3), side));
    vv_image *pl = render(phong, w, 0, NULL), *tl = render_table(table, w, &built);
    assert_int_equal(built, 1);
    const double db_light = vt_image_psnr(pl, tl, NULL), db_old = vt_image_psnr(t, tl, NULL);
    snprintf(name, sizeof name, "shade_table_%s_side_light_table", tag);
    write_png(tl, name);
    print_message("%s, side light: table %.2f dB from Phong; %.2f dB from the headlight's "
                  "table image\n",
                  tag, db_light, db_old);
    assert_true(db_light >= 40.0);
    assert_true(db_old < db_light - 10);

    /* orthographic, headlight: a pan keeps the view direction and the
     * light, so the table stays; turning the camera rebuilds it */
    w->lights[0].headlight = 1;
    w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    w->view.ortho_height = 1.2 * vv_vec3_length(f3) * tan(w->view.fov / 2) * 2;
    vv_image *o1 = render_table(table, w, &built);
    assert_int_equal(built, 1);
    const vv_vec3 pan = vv_vec3_scale(side, 0.05 * w->view.ortho_height);
    w->view.eye = vv_vec3_add(w->view.eye, pan);
    w->view.at = vv_vec3_add(w->view.at, pan);
    vv_image *o2 = render_table(table, w, &built);
    assert_int_equal(built, 0);
    assert_false(vt_image_psnr(o1, o2, &same) == INFINITY); /* the image did move */
    vv_image *po2 = render(phong, w, 0, NULL);
    const double db_ortho = vt_image_psnr(po2, o2, NULL);
    print_message("%s, orthographic, panned: table %.2f dB from Phong\n", tag, db_ortho);
    assert_true(db_ortho >= 40.0);
    w->view.eye = vv_vec3_add(w->view.eye, vv_vec3_scale(w->view.up, 0.3 * vv_vec3_length(f3)));
    vv_image *o3 = render_table(table, w, &built);
    assert_int_equal(built, 1);

    vv_image *all[] = {p, t, t2, f, pl, tl, o1, o2, po2, o3};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        vv_image_free(all[i]);
    vv_renderer_free(phong);
    vv_renderer_free(table);
    vv_world_free(w);
    vv_volume_free(vol);
}

/* The Navigator's previews (vv_preview_render): a reduced ray cast of a
 * warm volume builds a shading table, the final frame builds none and is
 * the Phong renderer's image. */
static void
test_previews_use_table(void **state) {
    (void)state;
    if (!vt_have_data("volumes/neghip.slc")) {
        vt_skip("volumes/neghip.slc is missing (../shared/data)");
        return;
    }
    vv_volume *vol = NULL;
    vv_world *w = vt_volume_scene("volumes/neghip.slc", 128, &vol);
    vv_preview *pv = NULL;
    vt_ok(vv_preview_new(&pv, "raycast"));
    int pw, ph;
    vv_preview_size(VV_PREVIEW_RAYCAST_2, 128, 128, &pw, &ph);
    vv_image *small = NULL, *full = NULL;
    vt_ok(vv_image_new(&small, pw, ph));
    vt_ok(vv_image_new(&full, 128, 128));
    vv_render_stats st = {0};
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.stats = &st;
    /* the first reduced cast is unshaded (no gradients yet), the next shade */
    for (int i = 0; i < 3; i++)
        vt_ok(vv_preview_render(pv, w, &w->view, VV_PREVIEW_RAYCAST_2, &opt, small));
    assert_int_equal(st.shading_tables_built, 1);
    st.shading_tables_built = 0;
    vt_ok(vv_preview_render(pv, w, &w->view, VV_PREVIEW_FULL, &opt, full));
    assert_int_equal(st.shading_tables_built, 0);
    vv_renderer *phong = NULL;
    vt_ok(vv_renderer_new(&phong, "raycast"));
    vv_image *ref = render(phong, w, 0, NULL);
    int same = 0;
    vt_image_psnr(ref, full, &same);
    assert_true(same);
    vv_image_free(ref);
    vv_renderer_free(phong);
    vv_image_free(small);
    vv_image_free(full);
    vv_preview_free(pv);
    vv_world_free(w);
    vv_volume_free(vol);
}

static void
test_table_ct_head(void **state) {
    (void)state;
    check_volume("volumes/ct_head.nrrd", "ct_head", 100, 1500);
}

static void
test_table_neghip(void **state) {
    (void)state;
    check_volume("volumes/neghip.slc", "neghip", 40, 200);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table_ct_head),
        cmocka_unit_test(test_table_neghip),
        cmocka_unit_test(test_previews_use_table),
    };
    return vt_run_tests(tests, NULL, NULL);
}
