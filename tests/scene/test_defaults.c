/*
 * A scene that names a file without a transfer function or without a view
 * gets what the file opened alone gets (vv_world_open, the door): the
 * default transfer function and isovalue for the object's mode (a
 * pyramid's from its coarsest level, the opacity unit of the level drawn),
 * and the door's view (for several objects, framing them all) with its
 * headlight when the scene gives no lights. A scene naming only the MNI
 * template renders like the file opened directly (>= 40 dB, issue 89; it
 * rendered almost black before); so do scenes giving only a view, only a
 * transfer function, or another mode, and the scene drawn at another size
 * or mode by the door. The defaults survive a save and a load; a scene
 * that gives its view and lights keeps them.
 */
#define _DEFAULT_SOURCE /* realpath */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "volvis/volvis.h"

#define MNI "volumes/avg152T1_RL_nifti.nii.gz"
#define SIZE "256x256"

static char g_dir[1024];
static char g_mni[4096]; /* the template's absolute path, for scene files elsewhere */

static int
setup(void **state) {
    (void)state;
    snprintf(g_dir, sizeof g_dir, "%s", vt_outdir("scene_defaults"));
    if (!vt_have_data(MNI) || !realpath(vt_data(MNI), g_mni))
        g_mni[0] = '\0';
    return 0;
}

static void
need_mni(void) {
    if (!g_mni[0])
        vt_skip("%s is missing (../shared/data)", MNI);
}

static const char *
write_scene(const char *name, const char *text) {
    static char path[1200];
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    vt_write_file(path, text, strlen(text));
    return path;
}

/* @p what (a file or a scene) through the door. */
static vv_world *
door(const char *what, vv_render_mode mode) {
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    if (mode != VV_MODE_COMPOSITE) {
        o.has_mode = 1;
        o.view.mode = mode;
    }
    vv_world *w = NULL;
    vt_ok(vv_world_open(&w, what, &o, NULL));
    return w;
}

/* The same transfer function, isovalue, threshold (a scene file keeps it
 * only for a threshold segmentation: not with @p no_threshold) and mode,
 * bit for bit. */
static void
same_look(const vv_object *a, const vv_object *b, int no_threshold) {
    assert_int_equal(a->mode, b->mode);
    assert_int_equal(a->segmentation, b->segmentation);
    assert_int_equal(a->tf.n_opacity, b->tf.n_opacity);
    assert_int_equal(a->tf.n_color, b->tf.n_color);
    for (int i = 0; i < a->tf.n_opacity; i++) {
        assert_true(a->tf.opacity[i].value == b->tf.opacity[i].value);
        assert_true(a->tf.opacity[i].opacity == b->tf.opacity[i].opacity);
    }
    for (int i = 0; i < a->tf.n_color; i++) {
        assert_true(a->tf.color[i].value == b->tf.color[i].value);
        assert_true(a->tf.color[i].color.x == b->tf.color[i].color.x);
        assert_true(a->tf.color[i].color.y == b->tf.color[i].color.y);
        assert_true(a->tf.color[i].color.z == b->tf.color[i].color.z);
    }
    assert_true(a->tf.opacity_unit_distance == b->tf.opacity_unit_distance);
    assert_true(a->isovalue == b->isovalue);
    assert_true(no_threshold || a->threshold == b->threshold);
}

static void
same_appearance(const vv_object *a, const vv_object *b) {
    same_look(a, b, 0);
}

static vv_vec3
box_centre(vv_box b) {
    return vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
}

/* @p s's view is @p d's (the door's, whose volume is centred on the
 * origin) moved to where the scene's objects are: the same direction,
 * distance, up, field of view and size, looking at the centre of the
 * scene's World; one headlight each, the same ambient and background. */
static void
same_view(const vv_world *s, const vv_world *d) {
    const vv_vec3 c = box_centre(vv_world_bounds(s));
    const vv_vec3 cd = box_centre(vv_world_bounds(d));
    const double r = vv_vec3_length(vv_vec3_sub(d->view.eye, d->view.at));
    assert_true(vv_vec3_length(vv_vec3_sub(s->view.at, c)) < 1e-9 * r);
    assert_true(vv_vec3_length(vv_vec3_sub(d->view.at, cd)) < 1e-9 * r);
    const vv_vec3 os = vv_vec3_sub(s->view.eye, s->view.at);
    const vv_vec3 od = vv_vec3_sub(d->view.eye, d->view.at);
    assert_true(vv_vec3_length(vv_vec3_sub(os, od)) < 1e-9 * r);
    assert_true(vv_vec3_length(vv_vec3_sub(s->view.up, d->view.up)) < 1e-12);
    assert_true(s->view.fov == d->view.fov);
    assert_int_equal(s->view.projection, d->view.projection);
    assert_true(fabs(s->view.ortho_height - d->view.ortho_height) < 1e-9 * r);
    assert_int_equal(s->view.width, d->view.width);
    assert_int_equal(s->view.height, d->view.height);
    assert_int_equal(s->n_lights, 1);
    assert_int_equal(d->n_lights, 1);
    assert_true(s->lights[0].headlight && d->lights[0].headlight);
    assert_true(s->lights[0].intensity == d->lights[0].intensity);
    assert_true(vv_vec3_length(vv_vec3_sub(s->lights[0].direction, d->lights[0].direction)) <
                1e-12);
    assert_true(s->ambient.x == d->ambient.x && s->background.x == d->background.x);
}

/* `volvis render WHAT --size SIZE [--mode MODE]` into test-out/NAME.png. */
static const char *
render(const char *what, const char *mode, const char *name) {
    static char out[8][1400];
    static int next;
    char *o = out[next++ % 8];
    snprintf(o, sizeof out[0], "%s/%s.png", g_dir, name);
    const char *args[] = {"render", what, "--size", SIZE, "-o", o, "-q", NULL, NULL, NULL};
    if (mode) {
        args[7] = "--mode";
        args[8] = mode;
    }
    vt_run_cli_expect(g_dir, 0, NULL, args);
    return o;
}

/* The scene and the file opened directly, drawn by the CLI: >= 40 dB. */
static void
renders_like_door(const char *scene, const char *mode, const char *name) {
    char a[1400], b[1400], na[256];
    snprintf(na, sizeof na, "%s_door", name);
    snprintf(a, sizeof a, "%s", render(g_mni, mode, na));
    snprintf(b, sizeof b, "%s", render(scene, NULL, name));
    const double psnr = vt_png_psnr(a, b);
    printf("%s: %.1f dB against `volvis render %s%s%s`\n", name, psnr, MNI, mode ? " --mode " : "",
           mode ? mode : "");
    if (!(psnr >= 40.0))
        fail_msg("%s renders %.1f dB from the file opened directly (< 40 dB)", name, psnr);
}

/* Issue 89: the scene naming only the template, the World and the image. */
static void
test_only_the_file(void **state) {
    (void)state;
    need_mni();
    char text[4400];
    snprintf(text, sizeof text, "{\"objects\": [{\"file\": \"%s\"}]}\n", g_mni);
    const char *scene = write_scene("mni.json", text);
    vv_world *s = NULL, *d = door(g_mni, VV_MODE_COMPOSITE);
    vt_ok(vv_scene_load(&s, scene));
    assert_int_equal(s->n_objects, 1);
    same_appearance(s->objects[0], d->objects[0]);
    same_view(s, d);
    /* through the door too (what volvis render does with a scene) */
    vv_world *sd = door(scene, VV_MODE_COMPOSITE);
    same_appearance(sd->objects[0], d->objects[0]);
    same_view(sd, d);
    vv_world_free(sd);
    vv_world_free(s);
    vv_world_free(d);
    renders_like_door(scene, NULL, "mni");
}

/* Through the door with a size and a mode (volvis render SCENE --size
 * --mode): a scene without a view is framed for that size (a portrait
 * image too, where the framing depends on it), an object without a
 * transfer function gets the default of that mode, as the file does. */
static void
test_door_size_and_mode(void **state) {
    (void)state;
    need_mni();
    char text[4400];
    snprintf(text, sizeof text, "{\"objects\": [{\"file\": \"%s\"}]}\n", g_mni);
    const char *scene = write_scene("mni_door.json", text);
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.has_size = 1;
    o.view.width = 200;
    o.view.height = 300;
    o.has_mode = 1;
    o.view.mode = VV_MODE_MIP;
    vv_world *s = NULL, *d = NULL;
    vt_ok(vv_world_open(&s, scene, &o, NULL));
    vt_ok(vv_world_open(&d, g_mni, &o, NULL));
    assert_int_equal(s->view.width, 200);
    same_appearance(s->objects[0], d->objects[0]);
    same_view(s, d);
    vv_world_free(s);
    vv_world_free(d);
    const char *args[] = {"render", scene, "--size", "200x300",
                          "--mode", "mip", "-o",     vt_path(g_dir, "mni_portrait.png"),
                          "-q",     NULL};
    vt_run_cli_expect(g_dir, 0, NULL, args);
    const char *argd[] = {"render", g_mni, "--size", "200x300",
                          "--mode", "mip", "-o",     vt_path(g_dir, "mni_portrait_door.png"),
                          "-q",     NULL};
    vt_run_cli_expect(g_dir, 0, NULL, argd);
    const double psnr =
        vt_png_psnr(vt_path(g_dir, "mni_portrait.png"), vt_path(g_dir, "mni_portrait_door.png"));
    printf("mni_portrait: %.1f dB against the file at 200x300 --mode mip\n", psnr);
    assert_true(psnr >= 40.0);
}

/* The model's two functions on their own: an object of the template gets
 * vv_world_new_for_volume's appearance, a World of it the same view. */
static void
test_model_functions(void **state) {
    (void)state;
    need_mni();
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, g_mni, NULL));
    vv_world *d = NULL, *w = NULL;
    vt_ok(vv_world_new_for_volume(&d, v, NULL));
    vt_ok(vv_world_new(&w));
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "mni"));
    vv_object_default_appearance(o, NULL, NULL);
    same_appearance(o, d->objects[0]);
    vt_ok(vv_world_add_object(w, o));
    vt_ok(vv_world_fit_default_view(w, NULL, 1));
    same_view(w, d);
    /* no second headlight unless asked; a bad zoom is refused */
    vt_ok(vv_world_fit_default_view(w, NULL, 0));
    assert_int_equal(w->n_lights, 1);
    vv_default_scene_options opt;
    vv_default_scene_options_init(&opt);
    opt.zoom = 0;
    vt_expect_refusal("zoom 0", vv_world_fit_default_view(w, &opt, 0), VV_ERR_INVALID, "zoom",
                      NULL);
    vv_object_default_appearance(NULL, NULL, NULL); /* nothing to do */
    vv_world_free(w);
    vv_world_free(d);
    vv_volume_free(v);
}

/* A view (and a headlight) but no transfer function: the file's default
 * transfer function under the scene's view. */
static void
test_view_without_tf(void **state) {
    (void)state;
    need_mni();
    vv_world *d = door(g_mni, VV_MODE_COMPOSITE);
    const vv_view *v = &d->view;
    const vv_vec3 p = d->objects[0]->position;
    char text[8192];
    snprintf(text, sizeof text,
             "{\"view\": {\"eye\": [%.17g, %.17g, %.17g], \"at\": [%.17g, %.17g, %.17g],\n"
             "           \"up\": [%.17g, %.17g, %.17g], \"fov\": %.17g},\n"
             " \"lights\": [{\"type\": \"directional\"}],\n"
             " \"objects\": [{\"file\": \"%s\", \"position\": [%.17g, %.17g, %.17g]}]}\n",
             v->eye.x, v->eye.y, v->eye.z, v->at.x, v->at.y, v->at.z, v->up.x, v->up.y, v->up.z,
             vv_rad_to_deg(v->fov), g_mni, p.x, p.y, p.z);
    const char *scene = write_scene("mni_view.json", text);
    vv_world *s = NULL;
    vt_ok(vv_scene_load(&s, scene));
    same_appearance(s->objects[0], d->objects[0]);
    /* the view is the scene's, as given */
    assert_true(vv_vec3_length(vv_vec3_sub(s->view.eye, v->eye)) < 1e-9);
    assert_int_equal(s->n_lights, 1);
    vv_world_free(s);
    vv_world_free(d);
    renders_like_door(scene, NULL, "mni_view");
}

/* A transfer function but no view: the door's view of the file, with a
 * headlight; the transfer function is the scene's. */
static void
test_tf_without_view(void **state) {
    (void)state;
    need_mni();
    vv_world *d = door(g_mni, VV_MODE_COMPOSITE);
    const vv_tf *tf = &d->objects[0]->tf;
    char text[16384];
    int n = snprintf(text, sizeof text,
                     "{\"objects\": [{\"file\": \"%s\",\n \"transfer_function\": {", g_mni);
    n += snprintf(text + n, sizeof text - (size_t)n,
                  "\"opacity_unit_distance\": %.17g,\n \"opacity\": [", tf->opacity_unit_distance);
    for (int i = 0; i < tf->n_opacity; i++)
        n += snprintf(text + n, sizeof text - (size_t)n, "%s[%.17g, %.17g]", i ? ", " : "",
                      tf->opacity[i].value, tf->opacity[i].opacity);
    n += snprintf(text + n, sizeof text - (size_t)n, "],\n \"color\": [");
    for (int i = 0; i < tf->n_color; i++)
        n += snprintf(text + n, sizeof text - (size_t)n, "%s[%.17g, [%.17g, %.17g, %.17g]]",
                      i ? ", " : "", tf->color[i].value, tf->color[i].color.x, tf->color[i].color.y,
                      tf->color[i].color.z);
    snprintf(text + n, sizeof text - (size_t)n, "]}}]}\n");
    const char *scene = write_scene("mni_tf.json", text);
    vv_world *s = NULL;
    vt_ok(vv_scene_load(&s, scene));
    same_view(s, d);
    assert_int_equal(s->objects[0]->tf.n_opacity, tf->n_opacity);
    for (int i = 0; i < tf->n_opacity; i++)
        assert_true(s->objects[0]->tf.opacity[i].value == tf->opacity[i].value);
    vv_world_free(s);
    vv_world_free(d);
    renders_like_door(scene, NULL, "mni_tf");
}

/* The object's mode chooses the default as --mode does for the file: a
 * grey ramp for MIP; for "iso" the default isovalue (no error). */
static void
test_modes(void **state) {
    (void)state;
    need_mni();
    static const struct {
        const char *name;
        vv_render_mode mode;
    } modes[] = {{"mip", VV_MODE_MIP}, {"iso", VV_MODE_ISO}};
    for (size_t m = 0; m < sizeof modes / sizeof modes[0]; m++) {
        char text[4400], name[64];
        snprintf(text, sizeof text, "{\"objects\": [{\"file\": \"%s\", \"mode\": \"%s\"}]}\n",
                 g_mni, modes[m].name);
        char scene[1200];
        snprintf(name, sizeof name, "mni_%s.json", modes[m].name);
        snprintf(scene, sizeof scene, "%s", write_scene(name, text));
        vv_world *s = NULL, *d = door(g_mni, modes[m].mode);
        vt_ok(vv_scene_load(&s, scene));
        same_appearance(s->objects[0], d->objects[0]);
        same_view(s, d);
        vv_world_free(s);
        vv_world_free(d);
        snprintf(name, sizeof name, "mni_%s", modes[m].name);
        renders_like_door(scene, modes[m].name, name);
    }
}

/* A pyramid written from the template (OME-Zarr, .vvb with levels): the
 * scene's object has the door's appearance read whole and out of core
 * alike -- the coarsest level's histogram, the opacity unit of the level
 * drawn. */
/* The scene naming pyramid @p name (written by convert with
 * @p convert_args) in memory and out of core, against the file through
 * the door (with its levels asked for when @p door_levels). */
static void
pyramid_like_door(const char *name, const char *const *convert_args, int door_levels) {
    char store[1200], text[4400], scene[1200], sname[64];
    snprintf(store, sizeof store, "%s/%s", g_dir, name);
    const char *args[] = {"convert", "-q", g_mni, store, convert_args[0], convert_args[1], NULL};
    vt_run_cli_expect(g_dir, 0, NULL, args);
    snprintf(text, sizeof text, "{\"objects\": [{\"file\": \"%s\"}]}\n", name);
    snprintf(sname, sizeof sname, "%s.json", name);
    snprintf(scene, sizeof scene, "%s", write_scene(sname, text));
    for (int ooc = 0; ooc < 2; ooc++) {
        vv_world_open_options o;
        vv_world_open_options_init(&o);
        if (ooc) {
            o.memory = VV_WORLD_OUT_OF_CORE;
            o.levels = 1;
        }
        vv_world *s = NULL, *d = NULL;
        vv_world_open_info si, di;
        vt_ok(vv_world_open(&s, scene, &o, &si));
        o.levels |= door_levels;
        vt_ok(vv_world_open(&d, store, &o, &di));
        /* (the door opens a .vvb out of core in any case: it is made for that) */
        assert_int_equal(si.out_of_core, ooc);
        printf("%s, the scene %s, the file %s: isovalue %g, unit %g\n", name,
               ooc ? "out of core" : "in memory", di.out_of_core ? "out of core" : "in memory",
               d->objects[0]->isovalue, d->objects[0]->tf.opacity_unit_distance);
        same_appearance(s->objects[0], d->objects[0]);
        same_view(s, d);
        vv_world_free(s);
        vv_world_free(d);
    }
}

static void
test_pyramid(void **state) {
    (void)state;
    need_mni();
    const char *zarr[] = {"--chunk", "32"}, *vvb[] = {NULL, NULL};
    pyramid_like_door("mni.ome.zarr", zarr, 0);
    /* a .vvb with its pyramid levels: the door takes them for the coarsest
     * level's histogram when it opens them (--lod; opened by bricks without,
     * it takes the proxy's) */
    pyramid_like_door("mni.vvb", vvb, 1);
}

/* Several objects and no view: the door's direction for the first volume,
 * framing the bounds of them all. */
static void
test_several_objects(void **state) {
    (void)state;
    need_mni();
    char text[9000];
    snprintf(text, sizeof text,
             "{\"objects\": [{\"file\": \"%s\"},\n"
             "  {\"file\": \"%s\", \"position\": [300, 0, 40], \"mode\": \"mip\"}]}\n",
             g_mni, g_mni);
    vv_world *s = NULL;
    vt_ok(vv_scene_load(&s, write_scene("two.json", text)));
    vv_world *d = door(g_mni, VV_MODE_COMPOSITE);
    same_appearance(s->objects[0], d->objects[0]);
    vv_world *dm = door(g_mni, VV_MODE_MIP);
    same_appearance(s->objects[1], dm->objects[0]);
    const vv_box b = vv_world_bounds(s);
    const double radius = 0.5 * vv_vec3_length(vv_vec3_sub(b.max, b.min));
    const vv_vec3 off = vv_vec3_sub(s->view.eye, s->view.at);
    assert_true(vv_vec3_length(vv_vec3_sub(s->view.at, box_centre(b))) < 1e-9 * radius);
    /* NIfTI is RAS: from +y, at the distance where the bounding sphere fits */
    assert_true(fabs(off.x) < 1e-9 * radius && off.y > 0 && fabs(off.z) < 1e-9 * radius);
    assert_true(fabs(vv_vec3_length(off) - radius / sin(0.5 * s->view.fov)) < 1e-9 * radius);
    assert_int_equal(s->n_lights, 1);
    vv_world_free(s);
    vv_world_free(d);
    vv_world_free(dm);
}

/* Saved (every field written: the transfer function, the view, the light)
 * and loaded back, the defaulted World is the same; saved again, the same
 * file. */
static void
test_round_trip(void **state) {
    (void)state;
    need_mni();
    char text[4400];
    snprintf(text, sizeof text, "{\"objects\": [{\"file\": \"%s\", \"mode\": \"iso\"}]}\n", g_mni);
    vv_world *a = NULL, *b = NULL;
    vt_ok(vv_scene_load(&a, write_scene("rt.json", text)));
    const char *files[] = {g_mni, NULL};
    char p1[1200], p2[1200];
    snprintf(p1, sizeof p1, "%s/rt_saved.json", g_dir);
    snprintf(p2, sizeof p2, "%s/rt_saved_again.json", g_dir);
    vt_ok(vv_scene_save(a, p1, files));
    vt_ok(vv_scene_load(&b, p1));
    same_look(b->objects[0], a->objects[0], 1);
    assert_true(vv_vec3_length(vv_vec3_sub(a->view.eye, b->view.eye)) == 0);
    assert_true(vv_vec3_length(vv_vec3_sub(a->view.at, b->view.at)) == 0);
    assert_true(a->view.ortho_height == b->view.ortho_height);
    assert_int_equal(b->n_lights, 1);
    assert_true(b->lights[0].headlight);
    vt_ok(vv_scene_save(b, p2, files));
    size_t n1 = 0, n2 = 0;
    unsigned char *t1 = vt_read_file(p1, &n1), *t2 = vt_read_file(p2, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(t1, t2, n1);
    free(t1);
    free(t2);
    vv_world_free(a);
    vv_world_free(b);
}

/* What a scene gives stays: its view without lights gets no headlight, its
 * lights without a view no other light. */
static void
test_given_parts_kept(void **state) {
    (void)state;
    need_mni();
    char text[4400];
    snprintf(text, sizeof text,
             "{\"view\": {\"eye\": [0, 500, 0], \"at\": [0, 0, 0]},\n"
             " \"objects\": [{\"file\": \"%s\"}]}\n",
             g_mni);
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, write_scene("view_only.json", text)));
    assert_int_equal(w->n_lights, 0);
    assert_true(w->view.eye.y == 500 && w->view.at.y == 0);
    vv_world_free(w);
    snprintf(text, sizeof text,
             "{\"lights\": [{\"type\": \"directional\", \"direction\": [1, 0, 0]},\n"
             "             {\"type\": \"directional\"}],\n"
             " \"objects\": [{\"file\": \"%s\"}]}\n",
             g_mni);
    vt_ok(vv_scene_load(&w, write_scene("lights_only.json", text)));
    assert_int_equal(w->n_lights, 2);
    assert_false(w->lights[0].headlight);
    assert_true(w->lights[0].direction.x == 1);
    /* the headlight points along the fitted view */
    const vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(w->view.at, w->view.eye));
    assert_true(w->lights[1].headlight);
    assert_true(vv_vec3_length(vv_vec3_sub(w->lights[1].direction, f)) < 1e-12);
    vv_world_free(w);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_only_the_file),
        cmocka_unit_test(test_view_without_tf),
        cmocka_unit_test(test_tf_without_view),
        cmocka_unit_test(test_modes),
        cmocka_unit_test(test_pyramid),
        cmocka_unit_test(test_several_objects),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_given_parts_kept),
        cmocka_unit_test(test_door_size_and_mode),
        cmocka_unit_test(test_model_functions),
    };
    return vt_run_tests(tests, setup, NULL);
}
