/*
 * A new format is one file and one row; a new renderer one file and one
 * table (issue 62). The toy format (toy_format.c) and the toy renderer
 * (toy_renderer.c) are registered at run time (vv_format_register,
 * vv_renderer_register) and used through the library's own calls only:
 * - the row: refusals (a name taken, another record version, the
 *   third-party flag); a ball (40 x 48 x 36 voxels, anisotropic spacing)
 *   saved by extension and loaded back voxel for voxel; found by its
 *   signature under another name; vv_format_parse takes its name;
 *   vv_open reads it whole by default and, through its raw layout, out of
 *   core by bricks;
 * - the renderer: refusals; "toymip" of the ball draws its maximum (200)
 *   at the centre and covers the ray caster's MIP footprint (where its
 *   trilinear maximum passes half the centre's; to 5 % of the disc's
 *   pixels: the rim, where nearest and trilinear samples part); its option "gain" doubles the grey
 * and refuses 0; the World out of core is refused (it renders no regions);
 * - the toy file out of core by bricks drawn by the ray caster equals the
 *   in-memory render bit for bit (MIP).
 * The images are written under the test's folder (toy_*.png).
 */
#include "testutil.h"

#include "toy.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define outdir() vt_outdir("plugins_toy")

static vv_format toy_id;

/* The ball: 200 within 10 voxels of (20, 24, 18), 0 elsewhere. */
static vv_volume *
ball(void) {
    const int dims[3] = {40, 48, 36};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    unsigned char *p = v->data;
    for (int k = 0; k < dims[2]; k++)
        for (int j = 0; j < dims[1]; j++)
            for (int i = 0; i < dims[0]; i++) {
                const double r2 =
                    (i - 20.0) * (i - 20.0) + (j - 24.0) * (j - 24.0) + (k - 18.0) * (k - 18.0);
                *p++ = r2 <= 100.0 ? 200 : 0;
            }
    v->spacing[0] = 0.8;
    v->spacing[1] = 1.0;
    v->spacing[2] = 1.25;
    v->unit = VV_UNIT_MM;
    vv_volume_update_range(v);
    return v;
}

static int
setup(void **state) {
    (void)state;
    if (vv_format_register(&toy_format, &toy_id) != VV_OK ||
        vv_renderer_register(&toy_renderer) != VV_OK) {
        fprintf(stderr, "register: %s\n", vv_error_message());
        return -1;
    }
    return 0;
}

static void
test_format_row(void **state) {
    (void)state;
    /* refusals */
    vt_err(vv_format_register(&toy_format, NULL));
    assert_non_null(strstr(vv_error_message(), "the name is format toy's"));
    vv_format_record other = toy_format;
    other.name = "toy2";
    other.version = VV_FORMAT_RECORD_VERSION + 1;
    assert_int_equal(vv_format_register(&other, NULL), VV_ERR_UNSUPPORTED);
    other.version = VV_FORMAT_RECORD_VERSION;
    other.flags = VV_FORMAT_FLAG_THIRD_PARTY;
    assert_int_equal(vv_format_register(&other, NULL), VV_ERR_UNSUPPORTED);
    assert_non_null(strstr(vv_error_message(), "reader sandbox"));
    vv_format f = VV_FORMAT_UNKNOWN;
    vt_ok(vv_format_parse("toy", &f));
    assert_int_equal(f, toy_id);
    assert_ptr_equal(vv_format_record_of(toy_id), &toy_format);

    /* saved by extension, loaded back */
    vv_volume *v = ball(), *back = NULL;
    const char *path = vt_path(outdir(), "ball.toy");
    vt_ok(vv_volume_save(v, path, VV_FORMAT_AUTO, 1));
    vt_ok(vv_volume_load(&back, path, NULL));
    assert_memory_equal(back->dims, v->dims, sizeof v->dims);
    assert_memory_equal(back->spacing, v->spacing, sizeof v->spacing);
    assert_memory_equal(back->data, v->data, (size_t)40 * 48 * 36);
    vv_volume_free(back);
    /* by its signature under another name */
    size_t n = 0;
    unsigned char *bytes = vt_read_file(path, &n);
    const char *bin = vt_path(outdir(), "ball.bin");
    vt_write_file(bin, bytes, n);
    free(bytes);
    assert_int_equal(vv_format_detect(bin), toy_id);
    vt_ok(vv_volume_load(&back, bin, NULL));
    assert_memory_equal(back->data, v->data, (size_t)40 * 48 * 36);
    vv_volume_free(back);

    /* vv_open: whole by default, by bricks out of core */
    vv_open_options oo;
    vv_open_options_init(&oo);
    vv_opened od = {0};
    vt_ok(vv_open(&od, path, &oo));
    assert_int_equal(od.format, toy_id);
    assert_int_equal(vv_source_get_kind(od.source), VV_SOURCE_MEMORY);
    vv_opened_clear(&od);
    oo.mode = VV_OPEN_OUT_OF_CORE;
    vt_ok(vv_open(&od, path, &oo));
    assert_int_equal(vv_source_get_kind(od.source), VV_SOURCE_BRICKS);
    vv_volume *box = NULL;
    const int lo[3] = {0, 0, 0}, hi[3] = {39, 47, 35};
    vt_ok(vv_source_read_box(od.source, 0, lo, hi, &box));
    assert_memory_equal(box->data, v->data, (size_t)40 * 48 * 36);
    vv_volume_free(box);
    vv_opened_clear(&od);
    vv_volume_free(v);

    /* the backstop behind every reader (issue 67): the toy row lets an
     * infinite spacing through ("inf" > 0); the library refuses it, whole
     * and out of core, in one line naming the file and the field */
    const char *inf = vt_path(outdir(), "inf.toy");
    FILE *fp = fopen(inf, "wb");
    assert_non_null(fp);
    fputs("TOYVOL\n2 2 2\n1 1 inf\n", fp);
    fwrite("\0\0\0\0\0\0\0\0", 1, 8, fp);
    assert_int_equal(fclose(fp), 0);
    assert_int_equal(vv_volume_load(&back, inf, NULL), VV_ERR_FORMAT);
    assert_null(back);
    assert_non_null(strstr(vv_error_message(), "toy: inf.toy: the spacing along z is inf"));
    oo.mode = VV_OPEN_OUT_OF_CORE;
    assert_int_equal(vv_open(&od, inf, &oo), VV_ERR_FORMAT);
    assert_null(od.source);
    printf("# %s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "inf.toy"));
    assert_non_null(strstr(vv_error_message(), "spacing"));
}

/* The image of @p w by renderer @p name (options "key=value", NULL-ended). */
static vv_image *
render(const char *name, const vv_world *w, const char *const *options) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, name));
    for (const char *const *o = options; o && *o; o += 2)
        vt_ok(vv_renderer_set_option(r, o[0], o[1]));
    vv_render_options ro;
    vv_render_options_init(&ro);
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vt_ok(vv_renderer_render(r, w, &w->view, &ro, img));
    vv_renderer_free(r);
    return img;
}

static vv_default_scene_options
mip_view(void) {
    vv_default_scene_options o = vt_scene_options(96);
    o.mode = VV_MODE_MIP;
    o.has_tf_range = 1;
    o.tf_lo = 0;
    o.tf_hi = 255;
    return o;
}

static void
test_renderer(void **state) {
    (void)state;
    vt_err(vv_renderer_register(&toy_renderer));
    assert_non_null(strstr(vv_error_message(), "a method of that name exists"));
    vv_renderer_ops bad = toy_renderer;
    bad.info.name = "toy_unbound";
    bad.state_size = 4; /* gain, a double, does not fit */
    vt_err(vv_renderer_register(&bad));
    assert_non_null(strstr(vv_error_message(), "option gain is not bound"));
    assert_non_null(vv_renderer_info_find("toymip"));
    assert_null(vv_renderer_info_find("toy_unbound"));

    vv_volume *v = ball();
    const vv_default_scene_options o = mip_view();
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    vv_image *toy = render("toymip", w, NULL);
    static const char *const twice[] = {"gain", "2", NULL};
    vv_image *toy2 = render("toymip", w, twice);
    vv_image *ray = render("raycast", w, NULL);
    vt_ok(vv_image_write_png(toy, vt_path(outdir(), "toy_mip.png"), 1.0, 1));
    vt_ok(vv_image_write_png(ray, vt_path(outdir(), "toy_raycast_mip.png"), 1.0, 1));
    /* the centre ray meets the ball's 200; the footprints agree */
    const int c = 4 * (48 * 96 + 48);
    assert_float_equal(toy->rgba[c], 200.0f / 255.0f, 1e-6);
    assert_float_equal(toy2->rgba[c], 1.0f, 0);
    /* the ray caster interpolates: its footprint is where its maximum
     * passes half the centre's (100 of 200, where nearest voxels switch) */
    const float half = 0.5f * ray->rgba[c + 3];
    int disc = 0, differ = 0;
    for (int i = 0; i < 96 * 96; i++) {
        const int a = toy->rgba[4 * i + 3] > 0.5f, b = ray->rgba[4 * i + 3] > half;
        disc += a;
        differ += a != b;
        if (a)
            assert_float_equal(toy2->rgba[4 * i], fminf(1.0f, 2 * toy->rgba[4 * i]), 1e-6);
    }
    printf("toymip: %d pixels of the disc, %d differ from the ray caster's MIP footprint\n", disc,
           differ);
    assert_true(disc > 400);
    assert_true(differ <= disc / 20);
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "toymip"));
    vt_err(vv_renderer_set_option(r, "gain", "0"));
    vv_renderer_free(r);
    vv_image_free(toy);
    vv_image_free(toy2);
    vv_image_free(ray);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_out_of_core(void **state) {
    (void)state;
    vv_volume *v = ball();
    const char *path = vt_path(outdir(), "ball_ooc.toy");
    vt_ok(vv_volume_save(v, path, VV_FORMAT_AUTO, 1));
    const vv_default_scene_options o = mip_view();
    vv_world *mem = NULL, *ooc = NULL;
    vt_ok(vv_world_new_for_volume(&mem, v, &o));
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE;
    vv_opened od = {0};
    vt_ok(vv_open(&od, path, &oo));
    vt_ok(vv_world_new_for_source(&ooc, od.source, 0, &o));
    ooc->view = mem->view;
    ooc->objects[0]->tf = mem->objects[0]->tf;
    static const char *const every_pixel[] = {"refinement", "off", NULL};
    vv_image *a = render("raycast", mem, every_pixel);
    vv_image *b = render("raycast", ooc, every_pixel);
    vt_ok(vv_image_write_png(b, vt_path(outdir(), "toy_ooc_raycast_mip.png"), 1.0, 1));
    int identical = 0;
    vt_image_psnr(a, b, &identical);
    assert_true(identical);
    /* the toy renderer has no region contract: out of core it is refused */
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "toymip"));
    vv_render_options ro;
    vv_render_options_init(&ro);
    assert_int_equal(vv_renderer_render(r, ooc, &ooc->view, &ro, b), VV_ERR_UNSUPPORTED);
    printf("toymip out of core: %s\n", vv_error_message());
    vv_renderer_free(r);
    vv_image_free(a);
    vv_image_free(b);
    vv_world_free(ooc);
    vv_world_free(mem);
    vv_opened_clear(&od);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format_row),
        cmocka_unit_test(test_renderer),
        cmocka_unit_test(test_out_of_core),
    };
    return vt_run_tests(tests, setup, NULL);
}
