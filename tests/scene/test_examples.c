/*
 * Every example scene (the .json files of examples/) saved and loaded back
 * equal: every field the writer writes is bit for bit the same in the
 * reloaded World (docs/scene-format.md lists them), every volume object has
 * the same voxels, and saving the reloaded World gives the same file byte
 * for byte (no drift over repeated saves). Volumes made at load ("geometry"
 * objects, volume-sampled by Modeling) are written as NRRD beside the saved
 * scene, as the GUI does; the other files are referred to by absolute paths
 * because the saved scene lives in another folder than the example.
 */
#define _DEFAULT_SOURCE /* realpath */
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "testutil.h"

#define MAX_OBJECTS 64

/* The files of @p w's objects for vv_scene_save, malloc'ed strings in
 * @p files (NULL where vv_scene_save needs none). */
static void
object_files(const vv_world *w, const char *scene, const char *dir, const char *stem,
             char *files[MAX_OBJECTS]) {
    assert_true(w->n_objects <= MAX_OBJECTS);
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        files[i] = NULL;
        if (o->type == VV_OBJECT_VOLUME && !o->geometry.source) {
            char name[300];
            snprintf(name, sizeof name, "%.200s_%d.nrrd", stem, i);
            const char *p = vt_path(dir, name);
            vt_ok(vt_save(o->volume, p, VV_FORMAT_NRRD, 0, 0));
            files[i] = realpath(p, NULL);
        } else if (o->type == VV_OBJECT_MESH || o->type == VV_OBJECT_VOLUME ||
                   o->type == VV_OBJECT_GRID) {
            assert_non_null(o->geometry.source);
            /* volumes and grids keep the path as opened, meshes as the scene names them */
            char *joined = o->type == VV_OBJECT_MESH ? vv_path_join_dir(scene, o->geometry.source)
                                                     : strdup(o->geometry.source);
            assert_non_null(joined);
            files[i] = realpath(joined, NULL);
            if (!files[i])
                fail_msg("%s: object %d: %s does not resolve", scene, i, joined);
            free(joined);
        }
    }
}

/* Bit-equal values: a saved World must load back exactly, not nearly. */
#define SAME(x)                                                                                    \
    do {                                                                                           \
        if (memcmp(&a->x, &b->x, sizeof a->x) != 0)                                                \
            fail_msg("%s: %s differs after saving and loading", where, #x);                        \
    } while (0)

static void
same_tf(const vv_tf *a, const vv_tf *b, const char *where) {
    SAME(n_opacity);
    SAME(n_color);
    for (int i = 0; i < a->n_opacity; i++) {
        SAME(opacity[i].value);
        SAME(opacity[i].opacity);
    }
    for (int i = 0; i < a->n_color; i++) {
        SAME(color[i].value);
        SAME(color[i].color);
    }
    SAME(opacity_unit_distance);
}

static void
same_tf2d(const vv_tf2d *a, const vv_tf2d *b, const char *where) {
    SAME(n_widgets);
    for (int i = 0; i < a->n_widgets; i++) {
        SAME(widgets[i].shape);
        SAME(widgets[i].value);
        SAME(widgets[i].gradient);
        SAME(widgets[i].color);
        SAME(widgets[i].opacity);
        if (a->widgets[i].shape == VV_TF2D_TRIANGLE) {
            SAME(widgets[i].center);
            SAME(widgets[i].width);
        } else {
            SAME(widgets[i].ramp);
            SAME(widgets[i].gradient_ramp);
        }
    }
    SAME(opacity_unit_distance);
}

/* The fields of a geometric object's shape (vv_geometry). */
static void
same_shape(const vv_object *a, const vv_object *b, const char *where) {
    switch (a->type) {
    case VV_OBJECT_PLANE:
        SAME(geometry.point);
        SAME(geometry.normal);
        break;
    case VV_OBJECT_POLYGON:
        SAME(geometry.n_vertices);
        for (int i = 0; i < a->geometry.n_vertices; i++)
            SAME(geometry.vertices[i]);
        break;
    case VV_OBJECT_SPHERE:
        SAME(geometry.center);
        SAME(geometry.radius);
        break;
    case VV_OBJECT_BOX:
        SAME(geometry.box);
        break;
    case VV_OBJECT_CYLINDER:
        SAME(geometry.base);
        SAME(geometry.top);
        SAME(geometry.radius);
        SAME(geometry.capped);
        break;
    case VV_OBJECT_MESH:
        SAME(geometry.mesh->n_vertices);
        SAME(geometry.mesh->n_triangles);
        break;
    default:
        break;
    }
}

/* Everything vv_scene_save writes of one object (docs/scene-format.md). */
static void
same_object(const vv_object *a, const vv_object *b, const char *where) {
    SAME(name);
    SAME(type);
    same_shape(a, b, where);
    SAME(position);
    SAME(orientation);
    SAME(scale);
    SAME(visible);
    SAME(material);
    SAME(casts_shadows);
    SAME(receives_shadows);
    SAME(visible_in_reflections);
    SAME(reflects);
    SAME(texture.projection);
    if (a->texture.image) {
        SAME(texture.center);
        SAME(texture.axis);
        SAME(texture.scale);
    }
    SAME(solid_texture.kind);
    if (a->solid_texture.kind != VV_SOLID_TEXTURE_NONE) {
        SAME(solid_texture.color0);
        SAME(solid_texture.color1);
        SAME(solid_texture.period);
        SAME(solid_texture.center);
        SAME(solid_texture.axis);
        SAME(solid_texture.turbulence);
        SAME(solid_texture.seed);
    }
    if (a->type != VV_OBJECT_VOLUME && a->type != VV_OBJECT_GRID)
        return;
    SAME(mode);
    SAME(isovalue);
    SAME(step);
    SAME(shading);
    SAME(segmentation);
    if (a->segmentation == VV_SEG_THRESHOLD)
        SAME(threshold);
    else
        same_tf(&a->tf, &b->tf, where);
    same_tf2d(&a->tf2d, &b->tf2d, where);
    SAME(n_cut_planes);
    for (int i = 0; i < a->n_cut_planes; i++) {
        SAME(cut_planes[i].point);
        SAME(cut_planes[i].normal);
    }
    if (a->type == VV_OBJECT_GRID) {
        SAME(field);
        SAME(component);
        SAME(time);
    } else {
        SAME(volume->origin);
        SAME(volume->spacing);
        SAME(volume->dims);
        SAME(volume->type);
        if (memcmp(a->volume->data, b->volume->data,
                   vv_volume_voxel_count(a->volume) * vv_voxel_type_size(a->volume->type)) != 0)
            fail_msg("%s: the reloaded voxels differ", where);
    }
}

static void
same_world(const vv_world *a, const vv_world *b, const char *where) {
    SAME(view.eye);
    SAME(view.at);
    SAME(view.up);
    SAME(view.fov);
    SAME(view.ortho_height);
    SAME(view.projection);
    SAME(view.width);
    SAME(view.height);
    SAME(background);
    SAME(ambient);
    SAME(n_lights);
    for (int i = 0; i < a->n_lights; i++) {
        SAME(lights[i].type);
        SAME(lights[i].headlight);
        SAME(lights[i].color);
        SAME(lights[i].intensity);
        if (a->lights[i].type == VV_LIGHT_POINT)
            SAME(lights[i].position);
        else if (!a->lights[i].headlight)
            SAME(lights[i].direction);
    }
    SAME(n_cut_planes);
    for (int i = 0; i < a->n_cut_planes; i++) {
        SAME(cut_planes[i].point);
        SAME(cut_planes[i].normal);
    }
    SAME(render.renderer);
    SAME(render.quality);
    SAME(render.n_options);
    for (int i = 0; i < a->render.n_options; i++) {
        assert_string_equal(a->render.option_keys[i], b->render.option_keys[i]);
        assert_string_equal(a->render.option_values[i], b->render.option_values[i]);
    }
    SAME(n_objects);
    for (int i = 0; i < a->n_objects; i++) {
        char w[512];
        snprintf(w, sizeof w, "%.480s: object %d", where, i);
        same_object(a->objects[i], b->objects[i], w);
    }
}

static void
round_trip(const char *scene, const char *dir, const char *stem) {
    vv_world *w1 = NULL, *w2 = NULL;
    vt_ok(vv_scene_load(&w1, scene));
    char *files[MAX_OBJECTS] = {0};
    object_files(w1, scene, dir, stem, files);
    char name[300];
    snprintf(name, sizeof name, "%.200s_a.json", stem);
    char *a = strdup(vt_path(dir, name));
    snprintf(name, sizeof name, "%.200s_b.json", stem);
    char *b = strdup(vt_path(dir, name));
    vt_ok(vv_scene_save(w1, a, (const char *const *)files));
    vt_ok(vv_scene_load(&w2, a));
    same_world(w1, w2, scene);
    vt_ok(vv_scene_save(w2, b, (const char *const *)files));
    size_t na, nb;
    unsigned char *ta = vt_read_file(a, &na), *tb = vt_read_file(b, &nb);
    if (na != nb || memcmp(ta, tb, na) != 0)
        fail_msg("%s: saving the reloaded World gives another file (%s, %s)", scene, a, b);
    free(ta);
    free(tb);
    for (int i = 0; i < MAX_OBJECTS; i++)
        free(files[i]);
    free(a);
    free(b);
    vv_world_free(w1);
    vv_world_free(w2);
}

static int
by_name(const void *a, const void *b) {
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void
test_every_example(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("the shared data (../shared/data) is not there");
    const char *dir = vt_outdir("scene_examples");
    DIR *d = opendir(VV_SOURCE_DIR "/examples");
    assert_non_null(d);
    char *names[256];
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < 256) {
        size_t len = strlen(e->d_name);
        if (len > 5 && strcmp(e->d_name + len - 5, ".json") == 0)
            names[n++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(names, (size_t)n, sizeof names[0], by_name);
    assert_true(n >= 10); /* the examples of the paper's figures */
    for (int i = 0; i < n; i++) {
        char scene[PATH_MAX], stem[256];
        snprintf(scene, sizeof scene, "%s/examples/%s", VV_SOURCE_DIR, names[i]);
        snprintf(stem, sizeof stem, "%.*s", (int)(strlen(names[i]) - 5), names[i]);
        print_message("%s\n", names[i]);
        round_trip(scene, dir, stem);
        free(names[i]);
    }
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_example),
    };
    return vt_run_tests(tests, NULL, NULL);
}
