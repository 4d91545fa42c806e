/* Scene files: the documented schema, errors with file:line:column, round trips. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static char g_dir[1024];

/* A 6x5x4 i16 volume with spacing (0.957, 0.957, 1.5) and origin (1, 2, 3). */
static int
setup(void **state) {
    (void)state;
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("scene_files"));
    int dims[3] = {6, 5, 4};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_I16) != VV_OK)
        return -1;
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 5; j++)
            for (int i = 0; i < 6; i++)
                vv_volume_set(v, i, j, k, -1000 + 100 * (i + j + k));
    vv_volume_update_range(v);
    v->spacing[0] = v->spacing[1] = 0.957;
    v->spacing[2] = 1.5;
    v->origin[0] = 1;
    v->origin[1] = 2;
    v->origin[2] = 3;
    char path[1200];
    snprintf(path, sizeof path, "%s/ct_head.nrrd", g_dir);
    vv_status st = vt_save(v, path, VV_FORMAT_NRRD, 0, 0);
    vv_volume_free(v);
    return st == VV_OK ? 0 : -1;
}

static const char *
write_scene(const char *name, const char *text) {
    static char path[1200];
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    vt_write_file(path, text, strlen(text));
    return path;
}

/* Loading must fail with a message containing "<path>:<line>:<col>:" and @p needle. */
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
}

static const char *example =
    "{\n"
    "  \"view\": {\"eye\": [0, -600, 0], \"at\": [0, 0, 0], \"up\": [0, 0, 1],\n"
    "           \"fov\": 20, \"projection\": \"perspective\",\n"
    "           \"width\": 512, \"height\": 512, \"background\": [0, 0, 0]},\n"
    "  \"lights\": [{\"type\": \"directional\", \"direction\": [0, 1, 0],\n"
    "              \"color\": [1, 1, 1], \"intensity\": 1.0}],\n"
    "  \"shading\": {\"ambient\": [1, 1, 1]},\n"
    "  \"objects\": [{\n"
    "    \"name\": \"head\", \"type\": \"volume\", \"file\": \"ct_head.nrrd\",\n"
    "    \"origin\": [-122.0, -122.0, -80.25],\n"
    "    \"mode\": \"composite\",\n"
    "    \"step\": 0.5,\n"
    "    \"transfer_function\": {\n"
    "      \"opacity\": [[100, 0.0], [1500, 0.5]],\n"
    "      \"color\": [[100, [1, 1, 1]], [1500, [1, 1, 1]]],\n"
    "      \"opacity_unit_distance\": 0.957\n"
    "    },\n"
    "    \"material\": {\"ambient\": 0.1, \"diffuse\": 0.6, \"specular\": 0.3, \"shininess\": "
    "30},\n"
    "    \"cut_planes\": [{\"point\": [0, 0, 0], \"normal\": [1, 0, 0]}]\n"
    "  }]\n"
    "}\n";

static void
test_example(void **state) {
    (void)state;
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, write_scene("example.json", example)));
    assert_near(w->view.eye.y, -600, 0);
    assert_near(w->view.up.z, 1, 0);
    assert_near(w->view.fov, vv_deg_to_rad(20), 1e-15);
    assert_int_equal(w->view.projection, VV_PROJECTION_PERSPECTIVE);
    assert_int_equal(w->view.width, 512);
    assert_int_equal(w->n_lights, 1);
    assert_int_equal(w->lights[0].type, VV_LIGHT_DIRECTIONAL);
    assert_int_equal(w->lights[0].headlight, 0);
    assert_near(w->lights[0].direction.y, 1, 0);
    assert_near(w->ambient.x, 1, 0);
    assert_int_equal(w->n_objects, 1);
    const vv_object *o = w->objects[0];
    assert_string_equal(o->name, "head");
    assert_int_equal(o->volume->dims[0], 6);
    /* origin overrides the file's; spacing is the file's */
    assert_near(o->volume->origin[0], -122, 0);
    assert_near(o->volume->origin[2], -80.25, 0);
    assert_near(o->volume->spacing[2], 1.5, 1e-12);
    assert_int_equal(o->mode, VV_MODE_COMPOSITE);
    assert_near(o->step, 0.5, 0);
    assert_int_equal(o->segmentation, VV_SEG_TRANSFER_FUNCTION);
    assert_int_equal(o->tf.n_opacity, 2);
    assert_near(vv_tf_eval_opacity(&o->tf, 800), 0.25, 1e-12);
    assert_int_equal(o->tf.n_color, 2);
    assert_near(o->tf.opacity_unit_distance, 0.957, 0);
    assert_near(o->material.diffuse, 0.6, 0);
    assert_near(o->material.shininess, 30, 0);
    assert_int_equal(o->n_cut_planes, 1);
    assert_near(o->cut_planes[0].normal.x, 1, 0);
    assert_int_equal(w->n_cut_planes, 0);
    vv_world_free(w);
}

static const char *every_key =
    "{\n"
    "  \"view\": {\"eye\": [10, 0, 0], \"at\": [0, 0, 0], \"up\": [0, 0, 1],\n"
    "           \"projection\": \"orthographic\", \"ortho_height\": 123.5,\n"
    "           \"fov\": 45, \"width\": 320, \"height\": 200},\n"
    "  \"lights\": [{\"color\": [1, 0.5, 0.25], \"intensity\": 0.75},\n"
    "             {\"type\": \"point\", \"position\": [1, 2, 3]}],\n"
    "  \"shading\": {\"ambient\": [0.2, 0.3, 0.4], \"background\": [0.1, 0.2, 0.3]},\n"
    "  \"cut_planes\": [{\"point\": [1, 1, 1], \"normal\": [0, 0, -2]}],\n"
    "  \"objects\": [\n"
    "    {\"file\": \"ct_head.nrrd\", \"spacing\": [2, 2, 2], \"position\": [5, 6, 7],\n"
    "     \"rotation\": {\"axis\": [0, 0, 1], \"angle\": 90}, \"scale\": 2,\n"
    "     \"shading\": false, \"visible\": false, \"mode\": \"iso\", \"isovalue\": -250,\n"
    "     \"segmentation\": {\"threshold\": -300},\n"
    "     \"material\": {\"color\": [0.9, 0.8, 0.7], \"shininess\": 5}},\n"
    "    {\"name\": \"second\", \"file\": \"ct_head.nrrd\", \"orientation\": [0, 1, 0, 0],\n"
    "     \"scale\": [1, 2, 3], \"mode\": \"mip\", \"step\": 0.25, \"attenuation\": 0.2},\n"
    "    {\"file\": \"ct_head.nrrd\", \"mode\": \"minip\"},\n"
    "    {\"file\": \"ct_head.nrrd\", \"mode\": \"xray\", \"transfer_function\": {\"opacity\": "
    "[]}}\n"
    "  ]\n"
    "}\n";

static void
test_every_key(void **state) {
    (void)state;
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, write_scene("every.json", every_key)));
    assert_int_equal(w->view.projection, VV_PROJECTION_ORTHOGRAPHIC);
    assert_near(w->view.ortho_height, 123.5, 0);
    assert_int_equal(w->view.width, 320);
    assert_int_equal(w->view.height, 200);
    /* a light without direction is a headlight along the view direction */
    assert_int_equal(w->n_lights, 2);
    assert_int_equal(w->lights[0].headlight, 1);
    assert_near(w->lights[0].direction.x, -1, 1e-12);
    assert_near(w->lights[0].color.z, 0.25, 0);
    assert_near(w->lights[0].intensity, 0.75, 0);
    assert_int_equal(w->lights[1].type, VV_LIGHT_POINT);
    assert_near(w->lights[1].position.z, 3, 0);
    assert_near(w->lights[1].intensity, 1, 0);
    assert_near(w->ambient.z, 0.4, 0);
    assert_near(w->background.y, 0.2, 0);
    assert_int_equal(w->n_cut_planes, 1);
    assert_near(w->cut_planes[0].normal.z, -1, 0);
    assert_int_equal(w->n_objects, 4);

    const vv_object *o = w->objects[0];
    assert_string_equal(o->name, "ct_head");
    assert_near(o->volume->spacing[1], 2, 0);
    assert_near(o->volume->origin[1], 2, 1e-12); /* the file's origin */
    assert_near(o->position.y, 6, 0);
    vv_vec3 r = vv_quat_rotate(o->orientation, vv_vec3_make(1, 0, 0));
    assert_near(r.y, 1, 1e-12);
    assert_near(o->scale.z, 2, 0);
    assert_int_equal(o->shading, 0);
    assert_int_equal(o->visible, 0);
    assert_int_equal(o->mode, VV_MODE_ISO);
    assert_near(o->isovalue, -250, 0);
    assert_int_equal(o->segmentation, VV_SEG_THRESHOLD);
    assert_near(o->threshold, -300, 0);
    assert_near(o->material.color.x, 0.9, 0);
    assert_near(o->material.shininess, 5, 0);
    assert_near(o->material.diffuse, 0.6, 0); /* default kept */

    o = w->objects[1];
    assert_string_equal(o->name, "second");
    r = vv_quat_rotate(o->orientation, vv_vec3_make(0, 1, 0));
    assert_near(r.y, -1, 1e-12);
    assert_near(o->scale.y, 2, 0);
    assert_int_equal(o->mode, VV_MODE_MIP);
    assert_near(o->step, 0.25, 0);
    assert_near(o->attenuation, 0.2, 0);
    assert_near(w->objects[2]->attenuation, 0.05, 0); /* the default */
    assert_true(o->tf.n_opacity >= 2);                /* the default grey ramp */
    assert_int_equal(w->objects[2]->mode, VV_MODE_MINIP);
    assert_int_equal(w->objects[3]->mode, VV_MODE_XRAY);
    assert_int_equal(w->objects[3]->tf.n_opacity, 0);
    vv_world_free(w);
}

static void
compare_worlds(const vv_world *a, const vv_world *b) {
    const double e = 1e-12;
    assert_near(vv_vec3_length(vv_vec3_sub(a->view.eye, b->view.eye)), 0, e);
    assert_near(vv_vec3_length(vv_vec3_sub(a->view.at, b->view.at)), 0, e);
    assert_near(vv_vec3_length(vv_vec3_sub(a->view.up, b->view.up)), 0, e);
    assert_near(a->view.fov, b->view.fov, e);
    assert_near(a->view.ortho_height, b->view.ortho_height, 0);
    assert_int_equal(a->view.projection, b->view.projection);
    assert_int_equal(a->view.width, b->view.width);
    assert_int_equal(a->view.height, b->view.height);
    assert_int_equal(a->n_lights, b->n_lights);
    for (int i = 0; i < a->n_lights; i++) {
        assert_int_equal(a->lights[i].type, b->lights[i].type);
        assert_int_equal(a->lights[i].headlight, b->lights[i].headlight);
        assert_near(vv_vec3_length(vv_vec3_sub(a->lights[i].direction, b->lights[i].direction)), 0,
                    e);
        assert_near(vv_vec3_length(vv_vec3_sub(a->lights[i].position, b->lights[i].position)), 0,
                    e);
        assert_near(vv_vec3_length(vv_vec3_sub(a->lights[i].color, b->lights[i].color)), 0, 0);
        assert_near(a->lights[i].intensity, b->lights[i].intensity, 0);
    }
    assert_near(vv_vec3_length(vv_vec3_sub(a->ambient, b->ambient)), 0, 0);
    assert_near(vv_vec3_length(vv_vec3_sub(a->background, b->background)), 0, 0);
    assert_int_equal(a->n_cut_planes, b->n_cut_planes);
    for (int i = 0; i < a->n_cut_planes; i++)
        assert_near(vv_vec3_length(vv_vec3_sub(a->cut_planes[i].normal, b->cut_planes[i].normal)),
                    0, e);
    assert_int_equal(a->n_objects, b->n_objects);
    for (int i = 0; i < a->n_objects; i++) {
        const vv_object *p = a->objects[i], *q = b->objects[i];
        assert_string_equal(p->name, q->name);
        for (int k = 0; k < 3; k++) {
            assert_near(p->volume->origin[k], q->volume->origin[k], 0);
            assert_near(p->volume->spacing[k], q->volume->spacing[k], 0);
        }
        assert_near(vv_vec3_length(vv_vec3_sub(p->position, q->position)), 0, 0);
        assert_near(fabs(vv_quat_mul(p->orientation, vv_quat_conjugate(q->orientation)).w), 1, e);
        assert_near(vv_vec3_length(vv_vec3_sub(p->scale, q->scale)), 0, 0);
        assert_int_equal(p->mode, q->mode);
        assert_near(p->isovalue, q->isovalue, 0);
        assert_near(p->step, q->step, 0);
        assert_near(p->attenuation, q->attenuation, 0);
        assert_int_equal(p->shading, q->shading);
        assert_int_equal(p->visible, q->visible);
        assert_int_equal(p->segmentation, q->segmentation);
        if (p->segmentation == VV_SEG_THRESHOLD) {
            assert_near(p->threshold, q->threshold, 0);
        } else {
            assert_int_equal(p->tf.n_opacity, q->tf.n_opacity);
            assert_int_equal(p->tf.n_color, q->tf.n_color);
            assert_memory_equal(p->tf.opacity, q->tf.opacity,
                                (size_t)p->tf.n_opacity * sizeof p->tf.opacity[0]);
            assert_memory_equal(p->tf.color, q->tf.color,
                                (size_t)p->tf.n_color * sizeof p->tf.color[0]);
            assert_near(p->tf.opacity_unit_distance, q->tf.opacity_unit_distance, 0);
        }
        assert_memory_equal(&p->material, &q->material, sizeof p->material);
        assert_int_equal(p->n_cut_planes, q->n_cut_planes);
    }
    assert_string_equal(a->render.renderer, b->render.renderer);
    assert_int_equal(a->render.quality, b->render.quality);
    assert_int_equal(a->render.n_options, b->render.n_options);
    for (int i = 0; i < a->render.n_options; i++) {
        assert_string_equal(a->render.option_keys[i], b->render.option_keys[i]);
        assert_string_equal(a->render.option_values[i], b->render.option_values[i]);
    }
}

static void
test_round_trip(void **state) {
    (void)state;
    const char *sources[] = {example, every_key};
    for (int s = 0; s < 2; s++) {
        vv_world *a = NULL, *b = NULL;
        vt_ok(vv_scene_load(&a, write_scene("rt_in.json", sources[s])));
        /* awkward values survive too */
        a->objects[0]->position = vv_vec3_make(0.1, 1.0 / 3.0, -1e-300);
        snprintf(a->objects[0]->name, VV_NAME_MAX, "we\"ird\\name\t");
        const char *files[4] = {"ct_head.nrrd", "ct_head.nrrd", "ct_head.nrrd", "ct_head.nrrd"};
        char out[1200];
        snprintf(out, sizeof out, "%s/rt_out.json", g_dir);
        vt_ok(vv_scene_save(a, out, files));
        vt_ok(vv_scene_load(&b, out));
        compare_worlds(a, b);
        vv_world_free(a);
        vv_world_free(b);
    }
    /* an empty world */
    vv_world *a = NULL, *b = NULL;
    vt_ok(vv_world_new(&a));
    char out[1200];
    snprintf(out, sizeof out, "%s/rt_empty.json", g_dir);
    vt_ok(vv_scene_save(a, out, NULL));
    vt_ok(vv_scene_load(&b, out));
    compare_worlds(a, b);
    /* a world of the default scene (headlight, histogram TF) */
    vv_world_free(b);
    vv_world_free(a);
    vv_volume *v = NULL;
    snprintf(out, sizeof out, "%s/ct_head.nrrd", g_dir);
    vt_ok(vv_volume_load(&v, out, NULL));
    vt_ok(vv_world_new_for_volume(&a, v, NULL));
    vv_volume_free(v);
    const char *files[1] = {"ct_head.nrrd"};
    snprintf(out, sizeof out, "%s/rt_default.json", g_dir);
    vt_ok(vv_scene_save(a, out, files));
    vt_ok(vv_scene_load(&b, out));
    compare_worlds(a, b);
    /* save errors: no file names, and a failed save leaves the old file */
    vt_err(vv_scene_save(a, out, NULL));
    vt_err(vv_scene_save(a, "/nonexistent-dir/x/scene.json", files));
    vv_world *c = NULL;
    vt_ok(vv_scene_load(&c, out));
    vv_world_free(c);
    vv_world_free(a);
    vv_world_free(b);
}

static void
test_errors(void **state) {
    (void)state;
    expect_error("syntax.json", "{\n  \"view\": {\n    \"fov\": 20,\n  }\n}\n", 4, 3, "");
    expect_error("empty.json", "", 1, 1, "");
    expect_error("wrong_type.json",
                 "{\n  \"view\": {\n    \"width\": 10,\n    \"fov\": \"wide\"\n  }\n}\n", 4, 5,
                 "view.fov: expected a number, got a string");
    expect_error(
        "unknown.json",
        "{\"objects\": [\n  {\"file\": \"ct_head.nrrd\",\n   \"trasnfer_function\": {}}]}\n", 3, 4,
        "objects[0].trasnfer_function: unknown key (did you mean transfer_function?)");
    expect_error("unknown_top.json", "{\"view\": {},\n \"zebra\": 1}", 2, 2,
                 "zebra: unknown key; expected one of");
    expect_error("missing.json", "{\"objects\": [\n  {\"name\": \"x\"}\n]}", 2, 3,
                 "objects[0]: missing required key \"file\"");
    expect_error("bad_mode.json",
                 "{\"objects\": [{\"file\": \"ct_head.nrrd\",\n \"mode\": \"mipp\"}]}", 2, 2,
                 "objects[0].mode: unknown mode \"mipp\"");
    /* (without a transfer function of its own the file's default isovalue serves) */
    expect_error("iso.json",
                 "{\"objects\": [{\"file\": \"ct_head.nrrd\",\n  \"mode\": \"iso\", "
                 "\"transfer_function\": {\"opacity\": []}}]}",
                 2, 3, "needs an \"isovalue\"");
    expect_error("no_volume.json", "{\"objects\": [{\n  \"file\": \"nothere.nrrd\"}]}", 2, 3,
                 "objects[0].file");
    expect_error("width.json", "{\"view\": {\"width\": 0}}", 1, 11, "view.width: 0 is outside");
    expect_error("width2.json", "{\"view\": {\"width\": 10.5}}", 1, 11, "expected an integer");
    expect_error("fov.json", "{\"view\": {\"fov\": 180}}", 1, 11, "view.fov");
    expect_error("opacity.json",
                 "{\"objects\": [{\"file\": \"ct_head.nrrd\", \"transfer_function\":\n"
                 "  {\"opacity\": [[0, 0], [1, 1.5]]}}]}",
                 2, 28, "objects[0].transfer_function.opacity[1][1]: opacity 1.5 is outside");
    expect_error("color.json", "{\"view\": {\"background\": [0, 2, 0]}}", 1, 11, "outside [0, 1]");
    expect_error("step.json", "{\"objects\": [{\"file\": \"ct_head.nrrd\", \"step\": 0}]}", 1, 39,
                 "objects[0].step");
    expect_error("attenuation.json",
                 "{\"objects\": [{\"file\": \"ct_head.nrrd\", \"attenuation\": -1}]}", 1, 39,
                 "objects[0].attenuation: -1 is outside");
    expect_error("mode_am.json",
                 "{\"objects\": [{\"file\": \"ct_head.nrrd\",\n \"mode\": \"attenuated_mip\"}]}", 2,
                 2, "expected composite, mip, minip, xray, iso or attenuated-mip");
    expect_error("normal.json",
                 "{\"cut_planes\": [{\"point\": [0, 0, 0],\n \"normal\": [0, 0, 0]}]}", 2, 2,
                 "cut_planes[0].normal: must not be the zero vector");
    expect_error("vec.json", "{\"view\": {\"eye\": [1, 2]}}", 1, 11,
                 "view.eye: expected an array of 3");
    expect_error("elem.json", "{\"view\": {\"eye\": [1, \"2\", 3]}}", 1, 22, "view.eye[1]");
    expect_error("top.json", "[1, 2]", 1, 1, "expected a JSON object at the top level");
    expect_error("dup.json", "{\"view\": {}, \"view\": {}}", 1, 19, "duplicate");
    expect_error("tf_noopacity.json",
                 "{\"objects\": [{\"file\": \"ct_head.nrrd\", \"transfer_function\": {}}]}", 1, 39,
                 "missing required key \"opacity\"");
    expect_error(
        "both.json",
        "{\"objects\": [{\"file\": \"ct_head.nrrd\", \"transfer_function\": {\"opacity\": []},\n"
        "  \"segmentation\": {\"threshold\": 1}}]}",
        2, 3, "not both");
    expect_error("light.json", "{\"lights\": [{\"type\": \"spot\"}]}", 1, 14, "unknown light type");
    expect_error("point.json", "{\"lights\": [{\"type\": \"point\"}]}", 1, 13,
                 "missing required key \"position\"");
    expect_error("up.json", "{\"view\": {\"eye\": [0, 0, -5], \"up\": [0, 0, 1]}}", 1, 30,
                 "parallel");
    expect_error("utf8.json", "{\"objects\": [{\"name\": \"\xc3\xa9\xc3\xa9\", \"file\": 5}]}", 1,
                 29, "objects[0].file: expected a string, got a number");

    /* a missing scene file, and a file over the size limit */
    vv_world *w = NULL;
    char path[1200];
    snprintf(path, sizeof path, "%s/absent.json", g_dir);
    vt_err(vv_scene_load(&w, path));
    assert_null(w);
    assert_non_null(strstr(vv_error_message(), "absent.json"));
    size_t big = (16u << 20) + 10;
    char *text = malloc(big);
    assert_non_null(text);
    memset(text, ' ', big);
    text[0] = '{';
    text[big - 1] = '}';
    snprintf(path, sizeof path, "%s/big.json", g_dir);
    vt_write_file(path, text, big);
    free(text);
    vt_err(vv_scene_load(&w, path));
    assert_null(w);
    vt_err(vv_scene_load(NULL, path));
}

/* ---- geometric objects, global-illumination material terms, effect flags ---- */

static const char *geometry_scene =
    "{\n"
    "  \"objects\": [\n"
    "    {\"type\": \"volume\", \"file\": \"ct_head.nrrd\", \"casts_shadows\": false,\n"
    "     \"receives_shadows\": false, \"visible_in_reflections\": false, \"reflects\": false,\n"
    "     \"material\": {\"reflectance\": 0.25, \"transparency\": 0.5, \"ior\": 1.33}},\n"
    "    {\"name\": \"floor\", \"type\": \"plane\", \"point\": [0, 0, -100],\n"
    "     \"normal\": [0, 0, 2], \"material\": {\"reflectance\": 0.3}},\n"
    "    {\"type\": \"polygon\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],\n"
    "     \"receives_shadows\": false},\n"
    "    {\"type\": \"sphere\", \"center\": [1, 2, 3], \"radius\": 4.5,\n"
    "     \"material\": {\"transparency\": 0.9, \"ior\": 1.5, \"color\": [1, 0, 0]}},\n"
    "    {\"type\": \"box\", \"min\": [-1, -2, -3], \"max\": [1, 2, 3], \"position\": [5, 0, 0],\n"
    "     \"rotation\": {\"axis\": [0, 0, 1], \"angle\": 30}, \"scale\": 2},\n"
    "    {\"type\": \"cylinder\", \"base\": [0, 0, 0], \"top\": [0, 0, 10], \"radius\": 2,\n"
    "     \"capped\": false, \"visible\": false},\n"
    "    {\"name\": \"tet\", \"type\": \"mesh\", \"file\": \"tet.obj\", \"casts_shadows\": false}\n"
    "  ]\n"
    "}\n";

static void
write_tetrahedron(void) {
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_new(&m));
    uint32_t v[4];
    const double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 4; i++)
        vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(p[i][0], p[i][1], p[i][2]), &v[i]));
    vt_ok(vv_mesh_add_triangle(m, v[0], v[2], v[1]));
    vt_ok(vv_mesh_add_triangle(m, v[0], v[1], v[3]));
    vt_ok(vv_mesh_add_triangle(m, v[1], v[2], v[3]));
    vt_ok(vv_mesh_add_triangle(m, v[2], v[0], v[3]));
    char path[1200];
    snprintf(path, sizeof path, "%s/tet.obj", g_dir);
    vt_ok(vv_mesh_save(m, path));
    vv_mesh_free(m);
}

static void
compare_geometry(const vv_object *p, const vv_object *q) {
    assert_string_equal(p->name, q->name);
    assert_int_equal(p->type, q->type);
    assert_memory_equal(&p->material, &q->material, sizeof p->material);
    assert_int_equal(p->casts_shadows, q->casts_shadows);
    assert_int_equal(p->receives_shadows, q->receives_shadows);
    assert_int_equal(p->visible_in_reflections, q->visible_in_reflections);
    assert_int_equal(p->reflects, q->reflects);
    assert_int_equal(p->visible, q->visible);
    if (p->type == VV_OBJECT_VOLUME)
        return;
    assert_near(vv_vec3_length(vv_vec3_sub(p->position, q->position)), 0, 0);
    assert_near(fabs(vv_quat_mul(p->orientation, vv_quat_conjugate(q->orientation)).w), 1, 1e-12);
    assert_near(vv_vec3_length(vv_vec3_sub(p->scale, q->scale)), 0, 0);
    const vv_geometry *a = &p->geometry, *b = &q->geometry;
    assert_near(vv_vec3_length(vv_vec3_sub(a->center, b->center)), 0, 0);
    assert_near(a->radius, b->radius, 0);
    assert_near(vv_vec3_length(vv_vec3_sub(a->point, b->point)), 0, 0);
    assert_near(vv_vec3_length(vv_vec3_sub(a->normal, b->normal)), 0, 1e-15);
    assert_near(vv_vec3_length(vv_vec3_sub(a->box.min, b->box.min)), 0, 0);
    assert_near(vv_vec3_length(vv_vec3_sub(a->box.max, b->box.max)), 0, 0);
    assert_near(vv_vec3_length(vv_vec3_sub(a->base, b->base)), 0, 0);
    assert_near(vv_vec3_length(vv_vec3_sub(a->top, b->top)), 0, 0);
    assert_int_equal(a->capped, b->capped);
    assert_int_equal(a->n_vertices, b->n_vertices);
    for (int i = 0; i < a->n_vertices; i++)
        assert_near(vv_vec3_length(vv_vec3_sub(a->vertices[i], b->vertices[i])), 0, 0);
    if (p->type == VV_OBJECT_MESH) {
        assert_int_equal(a->mesh->n_triangles, b->mesh->n_triangles);
        assert_int_equal(a->mesh->n_vertices, b->mesh->n_vertices);
    }
}

static void
test_geometry_objects(void **state) {
    (void)state;
    write_tetrahedron();
    vv_world *a = NULL, *b = NULL;
    vt_ok(vv_scene_load(&a, write_scene("geometry.json", geometry_scene)));
    assert_int_equal(a->n_objects, 7);
    const vv_object *v = a->objects[0];
    assert_int_equal(v->type, VV_OBJECT_VOLUME);
    assert_false(v->casts_shadows || v->receives_shadows || v->visible_in_reflections ||
                 v->reflects);
    assert_near(v->material.reflectance, 0.25, 0);
    assert_near(v->material.transparency, 0.5, 0);
    assert_near(v->material.ior, 1.33, 0);
    const vv_object *pl = a->objects[1];
    assert_int_equal(pl->type, VV_OBJECT_PLANE);
    assert_string_equal(pl->name, "floor");
    assert_near(pl->geometry.normal.z, 1, 1e-15); /* normalised */
    assert_near(pl->geometry.point.z, -100, 0);
    assert_near(pl->material.reflectance, 0.3, 0);
    assert_near(pl->material.ior, 1, 0); /* defaults kept */
    assert_true(pl->casts_shadows && pl->receives_shadows && pl->reflects);
    const vv_object *po = a->objects[2];
    assert_int_equal(po->type, VV_OBJECT_POLYGON);
    assert_int_equal(po->geometry.n_vertices, 4);
    assert_false(po->receives_shadows);
    const vv_object *sp = a->objects[3];
    assert_int_equal(sp->type, VV_OBJECT_SPHERE);
    assert_near(sp->geometry.radius, 4.5, 0);
    assert_near(sp->geometry.center.y, 2, 0);
    assert_near(sp->material.ior, 1.5, 0);
    const vv_object *bx = a->objects[4];
    assert_int_equal(bx->type, VV_OBJECT_BOX);
    assert_near(bx->geometry.box.max.z, 3, 0);
    assert_near(bx->scale.x, 2, 0);
    const vv_object *cy = a->objects[5];
    assert_int_equal(cy->type, VV_OBJECT_CYLINDER);
    assert_false(cy->geometry.capped);
    assert_false(cy->visible);
    const vv_object *me = a->objects[6];
    assert_int_equal(me->type, VV_OBJECT_MESH);
    assert_int_equal(me->geometry.mesh->n_triangles, 4);
    assert_string_equal(me->geometry.source, "tet.obj");
    /* round trip: volume files named, the mesh by its source */
    const char *files[7] = {"ct_head.nrrd", NULL, NULL, NULL, NULL, NULL, NULL};
    char out[1200];
    snprintf(out, sizeof out, "%s/geometry_out.json", g_dir);
    vt_ok(vv_scene_save(a, out, files));
    vt_ok(vv_scene_load(&b, out));
    assert_int_equal(b->n_objects, 7);
    for (int i = 0; i < 7; i++)
        compare_geometry(a->objects[i], b->objects[i]);
    vv_world_free(b);
    /* a world of geometry only needs no file names */
    vv_world *g = NULL;
    vt_ok(vv_world_new(&g));
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "ball"));
    o->material.reflectance = 0.5;
    o->reflects = 0;
    vt_ok(vv_world_add_object(g, o));
    vt_ok(vv_scene_save(g, out, NULL));
    vt_ok(vv_scene_load(&b, out));
    compare_geometry(g->objects[0], b->objects[0]);
    vv_world_free(b);
    /* a mesh without a source file cannot be saved */
    vv_mesh *m = NULL;
    vt_ok(vv_mesh_new(&m));
    uint32_t i0, i1, i2;
    vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(0, 0, 0), &i0));
    vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(1, 0, 0), &i1));
    vt_ok(vv_mesh_add_vertex(m, vv_vec3_make(0, 1, 0), &i2));
    vt_ok(vv_mesh_add_triangle(m, i0, i1, i2));
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_MESH, NULL));
    vt_ok(vv_object_set_mesh(o, m, NULL));
    vv_mesh_free(m);
    vt_ok(vv_world_add_object(g, o));
    vt_err(vv_scene_save(g, out, NULL));
    vv_world_free(g);
    vv_world_free(a);

    /* errors name the position and the key */
    expect_error("geo_type.json", "{\"objects\": [\n  {\"type\": \"cone\"}]}", 2, 4,
                 "unsupported object type \"cone\"");
    expect_error("geo_key.json",
                 "{\"objects\": [\n  {\"type\": \"sphere\", \"normal\": [0, 0, 1]}]}", 2, 22,
                 "normal: unknown key");
    expect_error("geo_mat.json",
                 "{\"objects\": [\n  {\"type\": \"box\", \"material\": {\"shine\": 3}}]}", 2, 32,
                 "shine");
    expect_error("geo_refl.json",
                 "{\"objects\": [\n  {\"type\": \"box\", \"material\": {\"transparency\": -1}}]}",
                 2, 32, "transparency");
    expect_error("geo_flag.json",
                 "{\"objects\": [\n  {\"type\": \"plane\", \"reflects\": \"yes\"}]}", 2, 21,
                 "expected true or false");
    expect_error(
        "geo_poly.json",
        "{\"objects\": [\n  {\"type\": \"polygon\", \"vertices\": [[0,0,0],[1,0,0],[0,1,0],"
        "[0,0,1]]}]}",
        2, 23, "vertices");
    expect_error("geo_mesh.json",
                 "{\"objects\": [\n  {\"type\": \"mesh\", \"file\": \"none.ply\"}]}", 2, 20,
                 "none.ply");
}

/* The "render" section: values of every JSON kind read as text, a round
 * trip, the clone, the option helper, and bad values with line:column. */
static void
test_render_settings(void **state) {
    (void)state;
    static const char *text =
        "{\n"
        "  \"view\": {\"width\": 64, \"height\": 48},\n"
        "  \"render\": {\n"
        "    \"renderer\": \"raytrace\",\n"
        "    \"quality\": 1,\n"
        "    \"options\": {\"shadows\": true, \"soft\": false, \"max_depth\": 4,\n"
        "                \"eps\": 0.1, \"third\": 0.33333333333333331, \"shading\": "
        "\"gou\\\"raud\"}\n"
        "  }\n"
        "}\n";
    vv_world *a = NULL, *b = NULL, *c = NULL;
    vt_ok(vv_scene_load(&a, write_scene("render.json", text)));
    assert_string_equal(a->render.renderer, "raytrace");
    assert_int_equal(a->render.quality, 1);
    assert_int_equal(a->render.n_options, 6);
    assert_string_equal(vv_render_settings_get_option(&a->render, "shadows"), "1");
    assert_string_equal(vv_render_settings_get_option(&a->render, "soft"), "0");
    assert_string_equal(vv_render_settings_get_option(&a->render, "max_depth"), "4");
    assert_string_equal(vv_render_settings_get_option(&a->render, "eps"), "0.1");
    /* a number is kept exactly: strtod of its text is the same double */
    const char *third = vv_render_settings_get_option(&a->render, "third");
    assert_non_null(third);
    assert_true(strtod(third, NULL) == 1.0 / 3.0);
    assert_string_equal(vv_render_settings_get_option(&a->render, "shading"), "gou\"raud");
    assert_null(vv_render_settings_get_option(&a->render, "nope"));

    /* save then load gives the same settings; a clone copies them */
    char out[1200];
    snprintf(out, sizeof out, "%s/render_out.json", g_dir);
    vt_ok(vv_scene_save(a, out, NULL));
    vt_ok(vv_scene_load(&b, out));
    compare_worlds(a, b);
    vt_ok(vv_world_clone(&c, a));
    compare_worlds(a, c);
    vv_world_free(b);
    vv_world_free(c);

    /* only the quality set: the section has just that */
    vv_render_settings_init(&a->render);
    a->render.quality = 0;
    vt_ok(vv_scene_save(a, out, NULL));
    vt_ok(vv_scene_load(&b, out));
    assert_string_equal(b->render.renderer, "");
    assert_int_equal(b->render.quality, 0);
    assert_int_equal(b->render.n_options, 0);
    vv_world_free(b);
    vv_world_free(a);

    /* a new World has nothing set, and saving it writes no "render" section */
    vt_ok(vv_world_new(&a));
    assert_string_equal(a->render.renderer, "");
    assert_int_equal(a->render.quality, -1);
    assert_int_equal(a->render.n_options, 0);
    vt_ok(vv_scene_save(a, out, NULL));
    size_t n = 0;
    char *saved = (char *)vt_read_file(out, &n);
    assert_non_null(saved);
    assert_null(strstr(saved, "render"));
    free(saved);
    /* settings that would not read back are refused */
    a->render.quality = 3;
    vt_err(vv_scene_save(a, out, NULL));
    vv_world_free(a);

    /* the helper: replace, append, limits; a failure changes nothing */
    vv_render_settings rs;
    vv_render_settings_init(&rs);
    vt_ok(vv_render_settings_set_option(&rs, "k", "1"));
    vt_ok(vv_render_settings_set_option(&rs, "k", "2"));
    assert_int_equal(rs.n_options, 1);
    assert_string_equal(vv_render_settings_get_option(&rs, "k"), "2");
    char longkey[VV_RENDER_OPTION_KEY_MAX + 1], longval[VV_RENDER_OPTION_VALUE_MAX + 1];
    /* VV_RENDER_OPTION_KEY_MAX (VALUE_MAX) characters: no room for the NUL */
    memset(longkey, 'k', VV_RENDER_OPTION_KEY_MAX);
    longkey[VV_RENDER_OPTION_KEY_MAX] = '\0';
    memset(longval, 'v', VV_RENDER_OPTION_VALUE_MAX);
    longval[VV_RENDER_OPTION_VALUE_MAX] = '\0';
    assert_int_equal(vv_render_settings_set_option(&rs, longkey, "1"), VV_ERR_INVALID);
    longkey[VV_RENDER_OPTION_KEY_MAX - 1] = '\0'; /* the longest allowed */
    vt_ok(vv_render_settings_set_option(&rs, longkey, "1"));
    assert_int_equal(vv_render_settings_set_option(&rs, "k", longval), VV_ERR_INVALID);
    assert_string_equal(vv_render_settings_get_option(&rs, "k"), "2");
    assert_int_equal(vv_render_settings_set_option(&rs, "", "1"), VV_ERR_INVALID);
    for (int i = rs.n_options; i < VV_MAX_RENDER_OPTIONS; i++) {
        char key[16];
        snprintf(key, sizeof key, "o%d", i);
        vt_ok(vv_render_settings_set_option(&rs, key, "x"));
    }
    assert_int_equal(vv_render_settings_set_option(&rs, "one_more", "x"), VV_ERR_LIMIT);
    vt_ok(vv_render_settings_set_option(&rs, "k", "3")); /* replacing still works when full */
    assert_int_equal(rs.n_options, VV_MAX_RENDER_OPTIONS);

    /* bad values: clear errors at the offending key */
    expect_error("r_key.json", "{\n  \"render\": {\"renderer\": \"splat\",\n    \"option\": {}}}",
                 3, 5, "render.option: unknown key (did you mean options?)");
    expect_error("r_quality.json", "{\"render\": {\n  \"quality\": 3}}", 2, 3,
                 "render.quality: 3 is outside 0..2");
    expect_error("r_quality2.json", "{\"render\": {\n  \"quality\": 1.5}}", 2, 3,
                 "render.quality: expected an integer");
    expect_error("r_empty.json", "{\"render\": {\n  \"renderer\": \"\"}}", 2, 3,
                 "render.renderer: the renderer name is empty");
    expect_error("r_long.json",
                 "{\"render\": {\n  \"renderer\": \"a_renderer_name_of_32_bytes_long\"}}", 2, 3,
                 "render.renderer: renderer name \"a_renderer_name_of_32_bytes_long\" is 32 bytes");
    expect_error("r_name_type.json", "{\"render\": {\n  \"renderer\": 7}}", 2, 3,
                 "render.renderer: expected a string, got a number");
    expect_error("r_opts.json", "{\"render\": {\n  \"options\": [1]}}", 2, 3,
                 "render.options: expected an object, got an array");
    expect_error("r_null.json", "{\"render\": {\"options\": {\n  \"a\": 1,\n  \"b\": null}}}", 3, 3,
                 "render.options.b: expected a string, a number or a boolean, got null");
    expect_error("r_arr.json", "{\"render\": {\"options\": {\n  \"a\": [1]}}}", 2, 3,
                 "render.options.a: expected a string, a number or a boolean, got an array");
    expect_error("r_section.json", "{\"view\": {},\n \"render\": \"raytrace\"}", 2, 2,
                 "render: expected an object, got a string");
    char big[2048];
    int k = snprintf(big, sizeof big, "{\"render\": {\"options\": {\n  \"v\": \"");
    memset(big + k, 'x', VV_RENDER_OPTION_VALUE_MAX);
    snprintf(big + k + VV_RENDER_OPTION_VALUE_MAX,
             sizeof big - (size_t)k - VV_RENDER_OPTION_VALUE_MAX, "\"}}}");
    expect_error("r_value.json", big, 2, 3, "render.options.v: value is 256 bytes; at most 255");
    k = snprintf(big, sizeof big, "{\"render\": {\"options\": {");
    for (int i = 0; i <= VV_MAX_RENDER_OPTIONS; i++)
        k += snprintf(big + k, sizeof big - (size_t)k, "%s\n  \"o%d\": %d", i ? "," : "", i, i);
    snprintf(big + k, sizeof big - (size_t)k, "}}}");
    expect_error("r_many.json", big, VV_MAX_RENDER_OPTIONS + 2, 3,
                 "render.options.o32: more than 32 options");
}

/* The writer writes JSON that Jansson reads: short members on one line,
 * numbers with as few digits as read back, strings escaped, and a name that
 * is not UTF-8 (which the reader would refuse) is an error naming the
 * object, with the old file left as it was. */
static void
test_writer_text(void **state) {
    (void)state;
    vv_world *a = NULL, *b = NULL;
    vt_ok(vv_world_new(&a));
    a->view.eye = vv_vec3_make(0.1, 1.0 / 3.0, 250);
    a->view.fov = vv_deg_to_rad(30);
    char out[1200];
    snprintf(out, sizeof out, "%s/text_out.json", g_dir);
    vt_ok(vv_scene_save(a, out, NULL));
    size_t n = 0;
    char *text = (char *)vt_read_file(out, &n);
    /* 0.1 as written by a person, 1/3 with the 17 digits it needs, 30 degrees */
    assert_non_null(strstr(text, "\"eye\": [0.1, 0.33333333333333331, 250],\n"));
    assert_non_null(strstr(text, "\"fov\": 30,\n"));
    assert_non_null(strstr(text, "\"cut_planes\": [],\n"));
    assert_true(n > 0 && text[n - 1] == '\n');
    vt_ok(vv_scene_load(&b, out));
    compare_worlds(a, b);
    vv_world_free(b);

    vv_volume *v = NULL;
    snprintf(out, sizeof out, "%s/ct_head.nrrd", g_dir);
    vt_ok(vv_volume_load(&v, out, NULL));
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "bad\xff name"));
    vv_volume_free(v);
    vt_ok(vv_world_add_object(a, o));
    const char *files[1] = {"ct_head.nrrd"};
    snprintf(out, sizeof out, "%s/text_out.json", g_dir);
    vv_error_clear();
    assert_int_equal(vv_scene_save(a, out, files), VV_ERR_INVALID);
    assert_non_null(strstr(vv_error_message(), "object 0"));
    assert_non_null(strstr(vv_error_message(), "UTF-8"));
    char *again = (char *)vt_read_file(out, &n);
    assert_string_equal(again, text);
    free(again);
    free(text);
    vv_world_free(a);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_example),          cmocka_unit_test(test_every_key),
        cmocka_unit_test(test_round_trip),       cmocka_unit_test(test_errors),
        cmocka_unit_test(test_geometry_objects), cmocka_unit_test(test_render_settings),
        cmocka_unit_test(test_writer_text),
    };
    return vt_run_tests(tests, setup, NULL);
}
