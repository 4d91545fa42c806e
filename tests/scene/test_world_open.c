/*
 * The door (vv_world_open, include/volvis/scene.h): the slice views'
 * automatic window of a real MRI spans its brain, not its background;
 * the out-of-core choices; options checked by their version; misfits
 * named; an object's time steps.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "volvis/volvis.h"

#define CH2 "/usr/share/mricron/templates/ch2better.nii.gz"

/* mricron-data's MNI template (values 0..130; 63 % background at 0; its
 * brain between 62 and 119): the window's lower end at 50 or above, and
 * under 5 % of the voxels above 8 above its upper end -- through the door
 * (what the browser shows) and vv_slice_auto_window (what the GUI calls). */
static void
test_foreground_window(void **state) {
    (void)state;
    FILE *f = fopen(CH2, "rb");
    if (!f)
        vt_skip("%s is missing (Debian's mricron-data)", CH2);
    fclose(f);
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.slice_window = 1;
    vv_world *w = NULL;
    vv_world_open_info info;
    vt_ok(vv_world_open(&w, CH2, &o, &info));
    assert_int_equal(info.input, VV_INPUT_VOLUME);
    assert_int_equal(info.out_of_core, 0);
    const vv_volume *v = w->objects[0]->volume;
    double lo = info.level - 0.5 * info.window, hi = info.level + 0.5 * info.window;
    uint64_t above8 = 0, over = 0;
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int i = 0; i < v->dims[0]; i++) {
                double x = vv_volume_get(v, i, j, k);
                above8 += x > 8;
                over += x > 8 && x > hi;
            }
    printf("ch2better: window %.1f .. %.1f; %.2f %% of the voxels above 8 lie above it\n", lo, hi,
           100.0 * (double)over / (double)above8);
    assert_true(lo >= 50);
    assert_true(hi <= 131);
    assert_true((double)over < 0.05 * (double)above8);
    double w2, l2;
    vv_slice_auto_window(v, &w2, &l2);
    assert_true(w2 == info.window && l2 == info.level);
    vv_world_free(w);
}

/* A volume without a background (a ramp) keeps its 1st to 99.5th percentiles. */
static void
test_window_without_background(void **state) {
    (void)state;
    vv_volume *v = NULL;
    const int dims[3] = {64, 64, 16};
    vt_ok(vv_volume_new(&v, dims, VV_U16));
    uint16_t *d = v->data;
    for (size_t i = 0; i < 64 * 64 * 16; i++)
        d[i] = (uint16_t)(i % 1000);
    vv_volume_update_range(v);
    double win, lev;
    vv_slice_auto_window(v, &win, &lev);
    double lo = lev - 0.5 * win, hi = lev + 0.5 * win;
    printf("ramp 0..999: window %.1f .. %.1f\n", lo, hi);
    assert_true(fabs(lo - 10) < 3 && fabs(hi - 995) < 3);
    vv_volume_free(v);
}

/* Out of core as asked: a gzip NIfTI cannot be read so (one line naming it);
 * where able it is read whole; a .vvb opens out of core by its bricks. */
static void
test_out_of_core_choices(void **state) {
    (void)state;
    const char *nii = vt_data("volumes/avg152T1_RL_nifti.nii.gz");
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.memory = VV_WORLD_OUT_OF_CORE;
    vv_world *w = NULL;
    vv_world_open_info info;
    vv_error_clear();
    vt_expect_refusal("gzip NIfTI out of core", vv_world_open(&w, nii, &o, &info),
                      VV_ERR_UNSUPPORTED, "cannot be read out of core", "avg152T1");
    assert_null(w);
    o.memory = VV_WORLD_OUT_OF_CORE_IF_ABLE;
    vt_ok(vv_world_open(&w, nii, &o, &info));
    assert_int_equal(info.out_of_core, 0);
    assert_non_null(w->objects[0]->volume);
    vv_world_free(w);

    const char *dir = vt_outdir("scene_world_open");
    const char *vvb = vt_path(dir, "ct.vvb");
    vv_volume *ct = NULL;
    vt_ok(vv_volume_load(&ct, vt_data("volumes/ct_head.nrrd"), NULL));
    vt_ok(vt_save(ct, vvb, VV_FORMAT_VVB, -1, 0));
    vv_volume_free(ct);
    vv_world_open_options_init(&o);
    vt_ok(vv_world_open(&w, vvb, &o, &info));
    assert_int_equal(info.out_of_core, 1);
    assert_non_null(w->objects[0]->source);
    vv_world_free(w);
}

/* A store's default appearance is the same read whole and out of core: the
 * transfer function from its coarsest level's histogram, the opacity unit
 * of the level shown (it was level 0's histogram in memory, the coarsest
 * level's out of core: 34 dB apart on the CT head's default view). */
static void
test_store_same_defaults(void **state) {
    (void)state;
    const char *dir = vt_outdir("scene_world_open");
    const char *store = vt_path(dir, "ct.ome.zarr");
    const char *args[] = {"convert", "-q", vt_data("volumes/ct_head.nrrd"), store, NULL};
    vt_run_cli_expect(dir, 0, NULL, args);
    for (int mode = 0; mode < 2; mode++) {
        vv_world_open_options o;
        vv_world_open_options_init(&o);
        o.has_mode = 1;
        o.view.mode = mode ? VV_MODE_MIP : VV_MODE_COMPOSITE;
        vv_world *mem = NULL, *ooc = NULL;
        vv_world_open_info im, io;
        vt_ok(vv_world_open(&mem, store, &o, &im));
        o.memory = VV_WORLD_OUT_OF_CORE;
        o.levels = 1;
        vt_ok(vv_world_open(&ooc, store, &o, &io));
        assert_int_equal(im.out_of_core, 0);
        assert_int_equal(io.out_of_core, 1);
        const vv_object *a = mem->objects[0], *b = ooc->objects[0];
        assert_int_equal(a->tf.n_opacity, b->tf.n_opacity);
        assert_int_equal(a->tf.n_color, b->tf.n_color);
        for (int i = 0; i < a->tf.n_opacity; i++) {
            assert_true(a->tf.opacity[i].value == b->tf.opacity[i].value);
            assert_true(a->tf.opacity[i].opacity == b->tf.opacity[i].opacity);
        }
        for (int i = 0; i < a->tf.n_color; i++)
            assert_true(a->tf.color[i].value == b->tf.color[i].value);
        assert_true(a->tf.opacity_unit_distance == b->tf.opacity_unit_distance);
        assert_true(a->tf.opacity_unit_distance == 0.957031 ||
                    fabs(a->tf.opacity_unit_distance - 0.957031) < 1e-6);
        assert_true(a->isovalue == b->isovalue);
        vv_world_free(mem);
        vv_world_free(ooc);
    }
}

/* The renderer, not the front end, falls back to the proxies: a .vvb out of
 * core drawn by splat (no region contract) is VV_ERR_UNSUPPORTED unless the
 * options allow the fallback; then it is the image of the proxies in
 * memory, bit for bit, and the lod says why. */
static void
test_proxy_fallback(void **state) {
    (void)state;
    const char *dir = vt_outdir("scene_world_open");
    const char *vvb = vt_path(dir, "fallback.vvb");
    vv_volume *ct = NULL;
    vt_ok(vv_volume_load(&ct, vt_data("volumes/ct_head.nrrd"), NULL));
    vt_ok(vt_save(ct, vvb, VV_FORMAT_VVB, -1, 0));
    vv_volume_free(ct);
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.has_size = 1;
    o.view.width = 64;
    o.view.height = 48;
    vv_world *w = NULL;
    vt_ok(vv_world_open(&w, vvb, &o, NULL));
    assert_non_null(w->objects[0]->source);
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "splat"));
    vv_image *a = NULL, *b = NULL;
    vt_ok(vv_image_new(&a, 64, 48));
    vt_ok(vv_image_new(&b, 64, 48));
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = 1;
    vv_lod lod;
    vv_lod_init(&lod);
    ro.lod = &lod;
    vt_expect_refusal("splat out of core", vv_renderer_render(r, w, &w->view, &ro, a),
                      VV_ERR_UNSUPPORTED, "region", NULL);
    ro.proxy_fallback = 1;
    vt_ok(vv_renderer_render(r, w, &w->view, &ro, a));
    printf("the fallback's note: %s\n", lod.note);
    assert_true(strstr(lod.note, "region") != NULL);
    /* the proxies in memory, as a front end made them before */
    vv_world *m = NULL;
    vt_ok(vv_world_clone(&m, w));
    vt_ok(vv_object_set_volume(m->objects[0], m->objects[0]->volume));
    assert_null(m->objects[0]->source);
    ro.lod = NULL;
    vt_ok(vv_renderer_render(r, m, &m->view, &ro, b));
    int identical = 0;
    vt_image_psnr(a, b, &identical);
    assert_true(identical);
    vv_world_free(m);
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(r);
    vv_world_free(w);
}

/* The version guards the layout; channels are for volume files; a missing
 * input is one line naming it. */
static void
test_refusals(void **state) {
    (void)state;
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    vv_world *w = NULL;
    vv_world_open_info info;
    o.version = VV_WORLD_OPEN_VERSION + 1;
    vt_expect_refusal("another version", vv_world_open(&w, "examples/ct_head.json", &o, &info),
                      VV_ERR_INVALID, "version", "ct_head.json");
    vv_world_open_options_init(&o);
    o.n_channels = 2;
    o.channels[1] = 1;
    vt_expect_refusal("channels of a scene", vv_world_open(&w, "examples/ct_head.json", &o, &info),
                      VV_ERR_INVALID, "not a scene", "ct_head.json");
    vt_expect_refusal("missing", vv_world_open(&w, "no/such.nii", NULL, &info), VV_ERR_IO,
                      "No such file", "no/such.nii");
    assert_null(w);
}

/* A scene is opened as one; its overrides apply to every volume object. */
static void
test_scene_overrides(void **state) {
    (void)state;
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.has_mode = 1;
    o.view.mode = VV_MODE_MIP;
    o.step = 0.75;
    o.has_size = 1;
    o.view.width = 64;
    o.view.height = 48;
    vv_world *w = NULL;
    vv_world_open_info info;
    vt_ok(vv_world_open(&w, "examples/ct_head.json", &o, &info));
    assert_int_equal(info.input, VV_INPUT_SCENE);
    assert_int_equal(w->view.width, 64);
    assert_int_equal(w->view.height, 48);
    int volumes = 0;
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->type == VV_OBJECT_VOLUME) {
            volumes++;
            assert_int_equal(w->objects[i]->mode, VV_MODE_MIP);
            assert_true(w->objects[i]->step == 0.75);
        }
    assert_true(volumes > 0);
    vv_world_free(w);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_foreground_window),
        cmocka_unit_test(test_window_without_background),
        cmocka_unit_test(test_out_of_core_choices),
        cmocka_unit_test(test_store_same_defaults),
        cmocka_unit_test(test_proxy_fallback),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_scene_overrides),
    };
    return vt_run_tests(tests, NULL, NULL);
}
