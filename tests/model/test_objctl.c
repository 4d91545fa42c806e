/* Object control in the model: 2-D transfer functions, presets, textures,
 * their scene-file form (round trips and errors) and snapshots. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static char g_dir[1024];

static int
setup(void **state) {
    (void)state;
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("model_objctl"));
    int dims[3] = {6, 5, 4};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_I16) != VV_OK)
        return -1;
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 5; j++)
            for (int i = 0; i < 6; i++)
                vv_volume_set(v, i, j, k, -1000 + 100 * (i + j + k));
    vv_volume_update_range(v);
    char path[1200];
    snprintf(path, sizeof path, "%s/vol.nrrd", g_dir);
    vv_status st = vt_save(v, path, VV_FORMAT_NRRD, 0, 0);
    vv_volume_free(v);
    vv_image *im = NULL;
    if (st != VV_OK || vv_image_new(&im, 2, 2) != VV_OK)
        return -1;
    for (int i = 0; i < 4; i++) {
        im->rgba[4 * i] = (float)(i & 1);
        im->rgba[4 * i + 1] = 0.5f;
        im->rgba[4 * i + 2] = 1;
        im->rgba[4 * i + 3] = 1;
    }
    snprintf(path, sizeof path, "%s/tex.png", g_dir);
    st = vv_image_write_png(im, path, 1.0, 0);
    vv_image_free(im);
    return st == VV_OK ? 0 : -1;
}

static const char *
write_scene(const char *name, const char *text) {
    static char path[1200];
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    vt_write_file(path, text, strlen(text));
    return path;
}

static void
expect_error(const char *name, const char *text, int line, int col, const char *needle) {
    const char *path = write_scene(name, text);
    vv_world *w = (vv_world *)1;
    vv_error_clear();
    vv_status st = vv_scene_load(&w, path);
    if (st == VV_OK)
        fail_msg("%s: loaded, expected an error containing \"%s\"", name, needle);
    assert_null(w);
    const char *msg = vv_error_message();
    char where[1400];
    snprintf(where, sizeof where, "%s:%d:%d: ", path, line, col);
    if (!strstr(msg, where) || !strstr(msg, needle))
        fail_msg("%s: message \"%s\" lacks \"%s\" or \"%s\"", name, msg, where, needle);
    assert_null(strchr(msg, '\n'));
}

static void
test_tf2d_eval(void **state) {
    (void)state;
    vv_tf2d tf;
    vv_tf2d_init(&tf);
    vv_tf2d_widget r;
    vv_tf2d_widget_init_rectangle(&r, 100, 200, 10, 50, vv_vec3_make(1, 0, 0), 0.8);
    r.ramp = 20;
    vt_ok(vv_tf2d_add_widget(&tf, &r));
    double a;
    vv_vec3 c;
    vv_tf2d_eval(&tf, 150, 30, &a, &c);
    assert_near(a, 0.8, 1e-12);
    assert_near(c.x, 1, 0);
    vv_tf2d_eval(&tf, 110, 30, &a, NULL); /* half way up the ramp */
    assert_near(a, 0.4, 1e-12);
    vv_tf2d_eval(&tf, 150, 60, &a, &c);
    assert_near(a, 0, 0);
    assert_near(c.y, 1, 0); /* white where transparent */
    /* a triangle: apex 500 at gradient 0, 200 wide at gradient 100 */
    vv_tf2d_widget t;
    vv_tf2d_widget_init_triangle(&t, 500, 200, 100, vv_vec3_make(0, 0, 1), 1.0);
    assert_near(vv_tf2d_widget_opacity(&t, 500, 50), 1.0, 1e-12);
    assert_near(vv_tf2d_widget_opacity(&t, 525, 50), 0.5, 1e-12); /* half width 50 */
    assert_near(vv_tf2d_widget_opacity(&t, 560, 50), 0.0, 0);
    assert_near(vv_tf2d_widget_opacity(&t, 500, 101), 0.0, 0);
    /* overlapping widgets: independent absorbers, opacity-weighted colour */
    vv_tf2d two;
    vv_tf2d_init(&two);
    vv_tf2d_widget a1, a2;
    vv_tf2d_widget_init_rectangle(&a1, 0, 10, 0, 10, vv_vec3_make(1, 0, 0), 0.5);
    vv_tf2d_widget_init_rectangle(&a2, 0, 10, 0, 10, vv_vec3_make(0, 0, 1), 0.5);
    vt_ok(vv_tf2d_add_widget(&two, &a1));
    vt_ok(vv_tf2d_add_widget(&two, &a2));
    vv_tf2d_eval(&two, 5, 5, &a, &c);
    assert_near(a, 0.75, 1e-12);
    assert_near(c.x, 0.5, 1e-12);
    assert_near(c.z, 0.5, 1e-12);
    assert_near(vv_tf2d_gradient_max(&tf), 50, 0);
    /* bad widgets */
    vv_tf2d_widget bad = r;
    bad.value[0] = NAN;
    vt_err(vv_tf2d_add_widget(&tf, &bad));
    bad = r;
    bad.gradient[0] = 60;
    vt_err(vv_tf2d_add_widget(&tf, &bad));
    bad = t;
    bad.width = 0;
    vt_err(vv_tf2d_add_widget(&tf, &bad));
    bad = r;
    bad.opacity = 1.5;
    vt_err(vv_tf2d_add_widget(&tf, &bad));
    for (int i = tf.n_widgets; i < VV_TF2D_MAX_WIDGETS; i++)
        vt_ok(vv_tf2d_add_widget(&tf, &r));
    assert_int_equal(vv_tf2d_add_widget(&tf, &r), VV_ERR_LIMIT);
}

static vv_volume *
ramp_volume(vv_voxel_type t, double lo, double hi) {
    int dims[3] = {16, 2, 2};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, t));
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 16; i++)
                vv_volume_set(v, i, j, k, lo + (hi - lo) * i / 15.0);
    vv_volume_update_range(v);
    return v;
}

static void
test_presets(void **state) {
    (void)state;
    const char *const *names = vv_tf_preset_names();
    int n = 0;
    while (names[n])
        n++;
    assert_true(n >= 20);
    vv_tf tf;
    /* Hounsfield units */
    vv_volume *hu = ramp_volume(VV_I16, -1024, 2986);
    for (int i = 0; i < n; i++) {
        vt_ok(vv_tf_preset(&tf, names[i], hu));
        assert_non_null(vv_tf_preset_description(names[i]));
        assert_true(tf.n_opacity >= 2 && tf.n_color >= 2);
        for (int k = 1; k < tf.n_opacity; k++) /* sorted, within the data's range or HU */
            assert_true(tf.opacity[k].value >= tf.opacity[k - 1].value);
        for (int j = 0; j < i; j++) /* distinct names */
            assert_string_not_equal(names[i], names[j]);
    }
    assert_null(vv_tf_preset_description("nonsense"));
    /* the CT presets by their tissues: lung parenchyma, contrast, muscle, fat */
    vt_ok(vv_tf_preset(&tf, "ct-lung", hu));
    assert_true(vv_tf_eval_opacity(&tf, -700) > 0.03);
    assert_near(vv_tf_eval_opacity(&tf, 0), 0, 0.05);
    vt_ok(vv_tf_preset(&tf, "ct-vessels", hu));
    assert_true(vv_tf_eval_opacity(&tf, 300) > 0.4);
    assert_near(vv_tf_eval_opacity(&tf, 40), 0, 0);
    vt_ok(vv_tf_preset(&tf, "ct-fat", hu));
    assert_true(vv_tf_eval_opacity(&tf, -110) > vv_tf_eval_opacity(&tf, 40));
    /* data presets over the 1st..99.5th percentile: mip is black to white */
    vt_ok(vv_tf_preset(&tf, "mip", hu));
    assert_near(vv_tf_eval_opacity(&tf, -1024), 0, 0.01);
    assert_true(vv_tf_eval_color(&tf, 2986).x > 0.99);
    vt_err(vv_tf_preset(&tf, "viridis", NULL));
    vt_ok(vv_tf_preset(&tf, "ct-bone", hu));
    assert_near(vv_tf_eval_opacity(&tf, 0), 0, 0);     /* water */
    assert_near(vv_tf_eval_opacity(&tf, -1000), 0, 0); /* air */
    assert_near(vv_tf_eval_opacity(&tf, 1500), 1, 0);  /* cortical bone */
    vt_ok(vv_tf_preset(&tf, "ct-soft-tissue", hu));
    assert_true(vv_tf_eval_opacity(&tf, 40) > 0.05); /* soft tissue */
    assert_near(vv_tf_eval_opacity(&tf, -1000), 0, 0);
    /* CT stored unsigned: HU + 1024 */
    vv_volume *u = ramp_volume(VV_U16, 0, 4095);
    vt_ok(vv_tf_preset(&tf, "ct-bone", u));
    assert_near(vv_tf_eval_opacity(&tf, 1024), 0, 0);
    assert_near(vv_tf_eval_opacity(&tf, 1500 + 1024), 1, 0);
    /* 8-bit: [-1024, 3071] HU over [0, 255]; 1500 HU at 157.4 */
    vv_volume *b = ramp_volume(VV_U8, 0, 255);
    vt_ok(vv_tf_preset(&tf, "ct-bone", b));
    assert_near(vv_tf_eval_opacity(&tf, 255), 1, 0);
    assert_near(vv_tf_eval_opacity(&tf, 60), 0, 0);
    /* MR: from the median up */
    vt_ok(vv_tf_preset(&tf, "mr", b));
    assert_near(vv_tf_eval_opacity(&tf, 0), 0, 0);
    assert_true(vv_tf_eval_opacity(&tf, 255) > 0.5);
    vt_err(vv_tf_preset(&tf, "mr", NULL));
    vt_err(vv_tf_preset(&tf, "ct-liver", hu));
    assert_non_null(strstr(vv_error_message(), "ct-bone"));
    assert_non_null(strstr(vv_error_message(), "top-5-percent"));
    vv_volume_free(hu);
    vv_volume_free(u);
    vv_volume_free(b);
}

static const char *scene_text =
    "{\n"
    "  \"objects\": [\n"
    "    {\"type\": \"volume\", \"file\": \"vol.nrrd\", \"segmentation\": \"tf2d\",\n"
    "     \"tf2d\": {\"widgets\": [\n"
    "        {\"shape\": \"rectangle\", \"value\": [-500, 300], \"gradient\": [10, 400],\n"
    "         \"ramp\": 50, \"gradient_ramp\": 5, \"color\": [1, 0.5, 0.25], \"opacity\": 0.7},\n"
    "        {\"shape\": \"triangle\", \"center\": 200, \"width\": 300, \"gradient\": [0, 250],\n"
    "         \"color\": [0, 1, 0], \"opacity\": 0.4}],\n"
    "        \"opacity_unit_distance\": 2},\n"
    "     \"solid_texture\": {\"procedural\": \"wood\", \"period\": 3, \"center\": [1, 2, 3],\n"
    "        \"axis\": [0, 1, 0], \"turbulence\": 0.5, \"seed\": 7,\n"
    "        \"color0\": [0.8, 0.6, 0.3], \"color1\": [0.4, 0.2, 0.1]},\n"
    "     \"mode\": \"iso\", \"isovalue\": 0,\n"
    "     \"texture\": {\"image\": \"tex.png\", \"projection\": \"cylindrical\",\n"
    "        \"center\": [2, 2, 1], \"axis\": [0, 0, 2], \"scale\": [2, 0.5]}},\n"
    "    {\"type\": \"volume\", \"file\": \"vol.nrrd\",\n"
    "     \"solid_texture\": {\"volume\": \"vol.nrrd\", \"color0\": [0, 0, 0]}},\n"
    "    {\"type\": \"sphere\", \"radius\": 2,\n"
    "     \"texture\": {\"image\": \"tex.png\", \"projection\": \"spherical\"}}\n"
    "  ]\n"
    "}\n";

static void
compare_objects(const vv_object *a, const vv_object *b) {
    assert_int_equal(a->segmentation, b->segmentation);
    assert_int_equal(a->tf2d.n_widgets, b->tf2d.n_widgets);
    assert_memory_equal(a->tf2d.widgets, b->tf2d.widgets,
                        (size_t)a->tf2d.n_widgets * sizeof a->tf2d.widgets[0]);
    assert_near(a->tf2d.opacity_unit_distance, b->tf2d.opacity_unit_distance, 0);
    assert_int_equal(a->texture.image != NULL, b->texture.image != NULL);
    if (a->texture.image) {
        assert_string_equal(a->texture.image->source, b->texture.image->source);
        assert_int_equal(a->texture.projection, b->texture.projection);
        assert_memory_equal(&a->texture.center, &b->texture.center, sizeof(vv_vec3));
        assert_memory_equal(&a->texture.axis, &b->texture.axis, sizeof(vv_vec3));
        assert_memory_equal(a->texture.scale, b->texture.scale, sizeof a->texture.scale);
    }
    const vv_solid_texture *s = &a->solid_texture, *t = &b->solid_texture;
    assert_int_equal(s->kind, t->kind);
    assert_near(s->period, t->period, 0);
    assert_near(s->turbulence, t->turbulence, 0);
    assert_int_equal(s->seed, t->seed);
    assert_memory_equal(&s->center, &t->center, sizeof(vv_vec3));
    assert_memory_equal(&s->axis, &t->axis, sizeof(vv_vec3));
    assert_memory_equal(&s->color0, &t->color0, sizeof(vv_vec3));
    assert_memory_equal(&s->color1, &t->color1, sizeof(vv_vec3));
    assert_int_equal(s->volume != NULL, t->volume != NULL);
    if (s->source || t->source)
        assert_string_equal(s->source, t->source);
}

static void
test_scene_round_trip(void **state) {
    (void)state;
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, write_scene("objctl.json", scene_text)));
    assert_int_equal(w->n_objects, 3);
    const vv_object *o = w->objects[0];
    assert_int_equal(o->segmentation, VV_SEG_TRANSFER_FUNCTION_2D);
    assert_int_equal(o->tf2d.n_widgets, 2);
    assert_int_equal(o->tf2d.widgets[1].shape, VV_TF2D_TRIANGLE);
    assert_near(o->tf2d.widgets[0].ramp, 50, 0);
    assert_near(o->tf2d.widgets[1].width, 300, 0);
    assert_near(o->tf2d.opacity_unit_distance, 2, 0);
    assert_int_equal(o->texture.projection, VV_TEXTURE_CYLINDRICAL);
    assert_near(o->texture.axis.z, 1, 1e-15); /* normalised */
    assert_int_equal(o->texture.image->image->width, 2);
    assert_int_equal(o->solid_texture.kind, VV_SOLID_TEXTURE_WOOD);
    assert_int_equal(w->objects[1]->solid_texture.kind, VV_SOLID_TEXTURE_VOLUME);
    assert_non_null(w->objects[1]->solid_texture.volume);
    assert_int_equal(w->objects[2]->texture.projection, VV_TEXTURE_SPHERICAL);
    /* save, load, compare */
    const char *files[] = {"vol.nrrd", "vol.nrrd", NULL};
    char path[1200];
    snprintf(path, sizeof path, "%s/objctl_saved.json", g_dir);
    vt_ok(vv_scene_save(w, path, files));
    vv_world *w2 = NULL;
    vt_ok(vv_scene_load(&w2, path));
    assert_int_equal(w2->n_objects, 3);
    for (int i = 0; i < 3; i++)
        compare_objects(w->objects[i], w2->objects[i]);
    /* snapshots share texture images and solid-texture volumes */
    vv_world *snap = NULL;
    vt_ok(vv_world_clone(&snap, w2));
    vv_world_free(w2);
    compare_objects(w->objects[0], snap->objects[0]);
    compare_objects(w->objects[1], snap->objects[1]);
    vv_vec3 c = vv_texture_map_eval(&snap->objects[0]->texture, vv_vec3_make(3, 2, 0));
    assert_true(c.z > 0.99);
    vv_world_free(snap);
    vv_world_free(w);
}

static void
test_scene_errors(void **state) {
    (void)state;
    expect_error("missing_tex.json",
                 "{\"objects\": [{\"type\": \"sphere\",\n"
                 "  \"texture\": {\"image\": \"nope.png\"}}]}",
                 2, 15, "texture");
    expect_error("bad_shape.json",
                 "{\"objects\": [{\"type\": \"volume\", \"file\": \"vol.nrrd\",\n"
                 "  \"tf2d\": {\"widgets\": [{\"shape\": \"circle\"}]}}]}",
                 2, 25, "unknown widget shape \"circle\"");
    expect_error("bad_proj.json",
                 "{\"objects\": [{\"type\": \"sphere\",\n"
                 "  \"texture\": {\"image\": \"tex.png\", \"projection\": \"conical\"}}]}",
                 2, 35, "unknown projection \"conical\"");
    expect_error("nan.json",
                 "{\"objects\": [{\"type\": \"volume\", \"file\": \"vol.nrrd\",\n"
                 "  \"tf2d\": {\"widgets\": [{\"shape\": \"triangle\", \"center\": NaN}]}}]}",
                 2, 58, "invalid token");
    expect_error("reversed.json",
                 "{\"objects\": [{\"type\": \"volume\", \"file\": \"vol.nrrd\",\n"
                 "  \"tf2d\": {\"widgets\": [{\"shape\": \"rectangle\", \"value\": [5, 1],\n"
                 "                          \"gradient\": [0, 1]}]}}]}",
                 2, 24, "reversed");
    expect_error("seg.json",
                 "{\"objects\": [{\"type\": \"volume\", \"file\": \"vol.nrrd\",\n"
                 "  \"segmentation\": \"tf2d\"}]}",
                 2, 3, "needs a \"tf2d\"");
    expect_error("solid.json",
                 "{\"objects\": [{\"type\": \"volume\", \"file\": \"vol.nrrd\",\n"
                 "  \"solid_texture\": {\"procedural\": \"plaid\"}}]}",
                 2, 21, "unknown procedural texture");
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tf2d_eval),
        cmocka_unit_test(test_presets),
        cmocka_unit_test(test_scene_round_trip),
        cmocka_unit_test(test_scene_errors),
    };
    return vt_run_tests(tests, setup, NULL);
}
