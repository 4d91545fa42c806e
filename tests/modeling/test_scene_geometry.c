/*
 * Geometry objects in scene files (voxelized at load), vv_shape_load, the
 * `volvis voxelize` command, and the example scenes (paper Figures 2 and 3)
 * rendered to PNG. Bad scene input gives file:line:col and the key path.
 */
#include "testutil.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#define VT_PI 3.14159265358979323846

static const char *
write_scene(const char *name, const char *text) {
    static char path[1024];
    snprintf(path, sizeof path, "%s/%s", vt_outdir("modeling_scene"), name);
    vt_write_file(path, text, strlen(text));
    return path;
}

/* Volume above the 0.5 level of a u8 density volume by voxel count. */
static double
count_volume(const vv_volume *v) {
    const unsigned char *d = v->data;
    size_t n = vv_volume_voxel_count(v), c = 0;
    for (size_t i = 0; i < n; i++)
        c += d[i] > 127;
    return (double)c * v->spacing[0] * v->spacing[1] * v->spacing[2];
}

static void
test_geometry_object(void **state) {
    (void)state;
    const char *p = write_scene(
        "sphere.json",
        "{\"objects\": [{\"type\": \"geometry\", \"name\": \"ball\", \"resolution\": 80,\n"
        "  \"primitive\": {\"type\": \"sphere\", \"radius\": 10, \"center\": [1, 2, 3]},\n"
        "  \"position\": [5, 0, 0], \"material\": {\"color\": [1, 0, 0]}}]}\n");
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, p));
    assert_int_equal(w->n_objects, 1);
    vv_object *o = w->objects[0];
    assert_int_equal(o->type, VV_OBJECT_VOLUME);
    assert_string_equal(o->name, "ball");
    assert_int_equal(o->volume->type, VV_U8);
    assert_int_equal(o->volume->data_origin, VV_ORIGIN_FUZZY_VOXELIZED);
    int dmax = o->volume->dims[0];
    assert_int_equal(dmax, 80);
    assert_near(count_volume(o->volume), 4.0 / 3 * VT_PI * 1000, 0.03 * 4.0 / 3 * VT_PI * 1000);
    assert_near(o->position.x, 5, 0);
    /* shape coordinates are the volume's world coordinates: centre at (1,2,3) */
    float c;
    assert_true(vv_volume_sample_world(o->volume, vv_vec3_make(1, 2, 3), &c));
    assert_true(c == 255.0f);
    assert_true(vv_volume_sample_world(o->volume, vv_vec3_make(1, 2, 13.0), &c));
    assert_near(c, 127.5, 3.0);
    /* default TF: opaque above the surface level */
    assert_true(vv_tf_eval_opacity(&o->tf, 250) > 0.9);
    assert_true(vv_tf_eval_opacity(&o->tf, 10) == 0.0);
    vv_world_free(w);

    /* vv_shape_load: the same scene as a model, with the object transform */
    vv_shape *s = NULL;
    vv_voxelize_options vo;
    vv_voxelize_options_init(&vo);
    vt_ok(vv_shape_load(&s, p, &vo));
    assert_int_equal(vo.size, 80);
    vv_box b = vv_shape_bounds(s);
    assert_near(b.min.x, 1 + 5 - 10, 1e-9);
    assert_near(b.max.z, 13, 1e-9);
    vv_shape_free(s);
}

static int
seen_progress(void *user, double f) {
    *(double *)user = f;
    return 0;
}

static void
test_examples(void **state) {
    (void)state;
    const char *ex[3] = {VV_SOURCE_DIR "/examples/nut_bolt.json",
                         VV_SOURCE_DIR "/examples/wine_glasses.json",
                         VV_SOURCE_DIR "/examples/wine_glasses_table.json"};
    const char *png[3] = {"nut_bolt.png", "wine_glasses.png", "wine_glasses_table.png"};
    const char *renderer[3] = {"raycast", "raycast", "raytrace"};
    for (int e = 0; e < 3; e++) {
        vv_world *w = NULL;
        double last = -1;
        vv_progress pr = {seen_progress, &last};
        vt_ok(vv_scene_load_progress(&w, ex[e], &pr));
        assert_float_equal(last, 1.0, 0);
        assert_true(w->n_objects >= 2);
        for (int i = 0; i < w->n_objects; i++) {
            if (w->objects[i]->type != VV_OBJECT_VOLUME)
                continue; /* the table of the ray-traced scene */
            assert_int_equal(w->objects[i]->volume->range[0], 0);
            assert_int_equal(w->objects[i]->volume->range[1], 255);
        }
        vv_renderer *r = NULL;
        vt_ok(vv_renderer_new(&r, renderer[e]));
        vv_image *img = NULL;
        vt_ok(vv_image_new(&img, w->view.width, w->view.height));
        vv_render_options ro;
        vv_render_options_init(&ro);
        vt_ok(vv_renderer_render(r, w, &w->view, &ro, img));
        char out[1024];
        snprintf(out, sizeof out, "%s/%s", vt_outdir("modeling_scene"), png[e]);
        vt_ok(vv_image_write_png(img, out, 1.0, 0));
        /* something was drawn: a good share of the pixels are lit */
        size_t lit = 0, n = (size_t)img->width * img->height;
        for (size_t i = 0; i < n; i++)
            lit += img->rgba[4 * i + 3] > 0.5f;
        assert_true(lit > n / 20);
        vv_image_free(img);
        vv_renderer_free(r);
        vv_world_free(w);
    }
    /* the nut is a difference: its bore is empty at the centre */
    vv_shape *s = NULL;
    vt_ok(vv_shape_load(&s, ex[0], NULL));
    vv_shape_free(s);
}

static void
expect_scene_error(const char *name, const char *text, const char *needle) {
    const char *p = write_scene(name, text);
    vv_world *w = NULL;
    vt_err(vv_scene_load(&w, p));
    assert_null(w);
    if (!strstr(vv_error_message(), needle))
        fail_msg("%s: message \"%s\" lacks \"%s\"", name, vv_error_message(), needle);
}

static void
test_bad_scenes(void **state) {
    (void)state;
    expect_scene_error("missing_child.json",
                       "{\"objects\": [{\"type\": \"geometry\", \"csg\": {\"op\": \"union\",\n"
                       "  \"children\": [{\"type\": \"sphere\", \"radius\": 1},\n"
                       "                null]}}]}\n",
                       ":3:17: objects[0].csg.children[1]: child 2 of the union is missing");
    expect_scene_error(
        "no_children.json",
        "{\"objects\": [{\"type\": \"geometry\", \"csg\": {\"op\": \"difference\"}}]}",
        "objects[0].csg: missing \"children\"");
    expect_scene_error("zero_radius.json",
                       "{\"objects\": [{\"type\": \"geometry\",\n"
                       "  \"primitive\": {\"type\": \"sphere\", \"radius\": 0}}]}",
                       ":2:3: objects[0].primitive: sphere: radius must be finite and > 0, got 0");
    expect_scene_error("absurd.json",
                       "{\"objects\": [{\"type\": \"geometry\", \"resolution\": 100000,\n"
                       "  \"primitive\": {\"type\": \"sphere\", \"radius\": 1}}]}",
                       "objects[0].resolution: 100000 voxels per axis is over the limit");
    expect_scene_error("unknown_prim.json",
                       "{\"objects\": [{\"type\": \"geometry\",\n"
                       "  \"primitive\": {\"type\": \"dodecahedron\"}}]}",
                       "objects[0].primitive.type: unknown primitive \"dodecahedron\"");
    expect_scene_error("bad_mesh.json",
                       "{\"objects\": [{\"type\": \"geometry\",\n"
                       "  \"primitive\": {\"type\": \"mesh\", \"file\": \"no_such_mesh.ply\"}}]}",
                       "objects[0].primitive.file");
    expect_scene_error("both.json",
                       "{\"objects\": [{\"type\": \"geometry\", \"csg\": {}, \"primitive\": {}}]}",
                       "give either \"primitive\" or \"csg\"");
    expect_scene_error("bad_key.json",
                       "{\"objects\": [{\"type\": \"geometry\", \"primitive\": {\"type\": "
                       "\"sphere\", \"radius\": 1, \"radiuss\": 2}}]}",
                       "objects[0].primitive.radiuss: unknown key");
    vv_shape *s = NULL;
    vt_err(vv_shape_load(&s, write_scene("none.json", "{\"objects\": []}"), NULL));
    vt_err(vv_shape_load(&s, "no/such/model.obj", NULL));
}

/* ---- the CLI ------------------------------------------------------------- */

static int
run_cli(const char *const *args, char **err) {
    vt_run_result r = vt_run_cli_v(vt_outdir("modeling_scene"), args);
    free(r.out);
    *err = r.err;
    return r.status;
}

static void
test_cli(void **state) {
    (void)state;
    char out[1024], *err;
    snprintf(out, sizeof out, "%s/knot.nrrd", vt_outdir("modeling_scene"));
    const char *a1[] = {"voxelize", VV_DATA_DIR "/meshes/knot1.off",
                        "-o",       out,
                        "--size",   "64",
                        "--filter", "gauss",
                        "--radius", "2",
                        "-q",       NULL};
    assert_int_equal(run_cli(a1, &err), 0);
    free(err);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, out, NULL));
    int mx = v->dims[0] > v->dims[1] ? v->dims[0] : v->dims[1];
    assert_int_equal(mx > v->dims[2] ? mx : v->dims[2], 64);
    assert_int_equal(v->type, VV_U8);
    vv_volume_free(v);
    snprintf(out, sizeof out, "%s/nut_bolt.slc", vt_outdir("modeling_scene"));
    const char *a2[] = {
        "voxelize", VV_SOURCE_DIR "/examples/nut_bolt.json", "-o", out, "--spacing", "2", "-q",
        NULL};
    assert_int_equal(run_cli(a2, &err), 0);
    free(err);
    vt_ok(vv_volume_load(&v, out, NULL));
    assert_near(v->spacing[0], 2.0, 1e-6);
    vv_volume_free(v);
    /* usage errors and bad input */
    const char *a3[] = {
        "voxelize", VV_DATA_DIR "/meshes/knot1.off", "-o", out, "--size", "64", "--spacing", "1",
        NULL};
    assert_int_equal(run_cli(a3, &err), 2);
    assert_non_null(strstr(err, "either --size or --spacing"));
    free(err);
    const char *a4[] = {"voxelize", VV_DATA_DIR "/meshes/knot1.off", "-o", out, "--filter", "sinc",
                        NULL};
    assert_int_equal(run_cli(a4, &err), 2);
    free(err);
    const char *a5[] = {"voxelize", "no/such.ply", "-o", out, NULL};
    assert_int_equal(run_cli(a5, &err), 1);
    free(err);
    const char *a6[] = {"voxelize", VV_DATA_DIR "/meshes/knot1.off", "-o", out, "--size", "100000",
                        NULL};
    assert_int_equal(run_cli(a6, &err), 1);
    assert_non_null(strstr(err, "over the limit"));
    free(err);
    const char *a7[] = {"voxelize", VV_DATA_DIR "/meshes/knot1.off", "-o", out, "--type", "f32",
                        NULL};
    assert_int_equal(run_cli(a7, &err), 2);
    free(err);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_geometry_object),
        cmocka_unit_test(test_examples),
        cmocka_unit_test(test_bad_scenes),
        cmocka_unit_test(test_cli),
    };
    return vt_run_tests(tests, NULL, NULL);
}
