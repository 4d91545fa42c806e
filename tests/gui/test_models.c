/* The GUI's display-free models: the undo stack, transfer-function editing
 * and the renderer the GUI picks on its own (gpu only on a real GPU). */
#include <stdio.h>
#include <stdlib.h>

#include "testutil.h"
#include "vvg-models.h"

static vv_world *
world_with_sphere(void) {
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "s"));
    vt_ok(vv_world_add_object(w, o));
    return w;
}

/* Undo restores each earlier World exactly; redo re-applies; a new edit clears redo. */
static void
test_undo(void **state) {
    (void)state;
    vvg_undo *u = NULL;
    vt_ok(vvg_undo_new(&u, 3));
    vv_world *w = world_with_sphere();
    assert_false(vvg_undo_can_undo(u));
    for (int i = 1; i <= 4; i++) {
        vt_ok(vvg_undo_push(u, w, "move"));
        w->objects[0]->position.x = i;
    }
    assert_string_equal(vvg_undo_label(u, 0), "move");
    /* the limit of 3 keeps the last three steps */
    for (int i = 3; i >= 1; i--) {
        vt_ok(vvg_undo_undo(u, &w));
        assert_near(w->objects[0]->position.x, i, 0);
    }
    assert_false(vvg_undo_can_undo(u));
    vt_err(vvg_undo_undo(u, &w));
    vt_ok(vvg_undo_redo(u, &w));
    assert_near(w->objects[0]->position.x, 2, 0);
    vt_ok(vvg_undo_push(u, w, "colour"));
    w->objects[0]->material.color.x = 0.5;
    assert_false(vvg_undo_can_redo(u));
    vt_ok(vvg_undo_undo(u, &w));
    assert_near(w->objects[0]->material.color.x, 1, 0);
    assert_near(w->objects[0]->position.x, 2, 0);
    vv_world_free(w);
    vvg_undo_free(u);
}

static void
test_tf_editing(void **state) {
    (void)state;
    vv_tf tf;
    vv_tf_init(&tf);
    vvg_tf_axes a = {0, 1000, 500, 100};
    assert_near(vvg_tf_x(&a, 500), 250, 1e-12);
    assert_near(vvg_tf_opacity(&a, 25), 0.75, 1e-12);
    int i = vvg_tf_add_point(&tf, &a, 100, 100); /* value 200, opacity 0 */
    int j = vvg_tf_add_point(&tf, &a, 400, 0);   /* value 800, opacity 1 */
    assert_int_equal(i, 0);
    assert_int_equal(j, 1);
    assert_near(vv_tf_eval_opacity(&tf, 500), 0.5, 1e-12);
    assert_int_equal(vvg_tf_hit(&tf, &a, 402, 3, 6), 1);
    assert_int_equal(vvg_tf_hit(&tf, &a, 250, 50, 6), -1);
    /* a point cannot pass its neighbour: order and indices stay valid */
    vvg_tf_move_point(&tf, 1, &a, 10, 50);
    assert_near(tf.opacity[1].value, 200, 1e-12);
    assert_near(tf.opacity[1].opacity, 0.5, 1e-12);
    vvg_tf_move_point(&tf, 1, &a, 1e9, -1e9); /* clamped into the area */
    assert_near(tf.opacity[1].value, 1000, 1e-12);
    assert_near(tf.opacity[1].opacity, 1, 1e-12);
    vvg_tf_move_point(&tf, 1, &a, NAN, 3); /* ignored */
    assert_near(tf.opacity[1].value, 1000, 1e-12);
    vvg_tf_delete_point(&tf, 0);
    vvg_tf_delete_point(&tf, 7);
    assert_int_equal(tf.n_opacity, 1);
    int c = vvg_tf_add_color(&tf, &a, 250, vv_vec3_make(1, 0, 0));
    assert_int_equal(vvg_tf_hit_color(&tf, &a, 252, 4), c);
    vvg_tf_move_color(&tf, c, &a, 0);
    assert_near(tf.color[0].value, 0, 1e-12);
    vvg_tf_delete_color(&tf, c);
    assert_int_equal(tf.n_color, 0);
}

/* Clean-state tracking (issue 66): undo and redo back to the marked state
 * are clean; an edit after undoing past it, or its step dropped off the
 * bottom, make it unreachable; an edit merged into the last step is not clean. */
static void
test_undo_clean(void **state) {
    (void)state;
    vvg_undo *u = NULL;
    vt_ok(vvg_undo_new(&u, 3));
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    assert_true(vvg_undo_is_clean(u)); /* a new stack: nothing changed */
    vt_ok(vvg_undo_push(u, w, "a"));
    assert_false(vvg_undo_is_clean(u));
    vt_ok(vvg_undo_undo(u, &w));
    assert_true(vvg_undo_is_clean(u)); /* undone back to the start */
    vt_ok(vvg_undo_redo(u, &w));
    assert_false(vvg_undo_is_clean(u));
    vvg_undo_mark_clean(u); /* saved after "a" */
    assert_true(vvg_undo_is_clean(u));
    vt_ok(vvg_undo_push(u, w, "b"));
    vt_ok(vvg_undo_undo(u, &w));
    assert_true(vvg_undo_is_clean(u));
    vt_ok(vvg_undo_undo(u, &w)); /* before "a": not the saved state */
    assert_false(vvg_undo_is_clean(u));
    vt_ok(vvg_undo_push(u, w, "c")); /* the saved state's redo steps are gone */
    assert_false(vvg_undo_is_clean(u));
    vt_ok(vvg_undo_undo(u, &w));
    assert_false(vvg_undo_is_clean(u));
    assert_int_equal(vvg_undo_clean_index(u), -1);
    /* the clean state's step dropped off the bottom of a 3-step stack */
    vvg_undo_mark_clean(u); /* at 0 steps */
    for (int i = 0; i < 4; i++)
        vt_ok(vvg_undo_push(u, w, "d"));
    while (vvg_undo_can_undo(u)) {
        vt_ok(vvg_undo_undo(u, &w));
        assert_false(vvg_undo_is_clean(u));
    }
    /* a merged edit: the state moved without a step */
    vvg_undo_clear(u);
    assert_true(vvg_undo_is_clean(u));
    vvg_undo_mark_unclean(u);
    assert_false(vvg_undo_is_clean(u));
    vvg_undo_set_clean_index(u, 0);
    assert_true(vvg_undo_is_clean(u));
    vv_world_free(w);
    vvg_undo_free(u);
}

/* The GUI picks gpu on its own only on a real GPU: never on a CPU device
 * such as lavapipe (VOLVIS_GUI_GPU=any lets it, for this test), never for a
 * World it does not draw, never when VOLVIS_GUI_GPU=0. */
static void
test_gui_renderer(void **state) {
    (void)state;
    vv_gpu_device d[16];
    const int n = vv_gpu_devices(d, 16, NULL);
    int real = 0;
    for (int i = 0; i < n && i < 16; i++)
        real |= !d[i].cpu;
    const int dims[3] = {8, 8, 8};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "v"));
    vt_ok(vv_world_add_object(w, o));
    unsetenv("VOLVIS_GUI_GPU");
    assert_string_equal(vvg_gui_renderer(w, "raycast"), real ? "gpu" : "raycast");
    assert_string_equal(vvg_gui_renderer(w, "raytrace"), "raytrace");
    setenv("VOLVIS_GUI_GPU", "0", 1);
    assert_string_equal(vvg_gui_renderer(w, "raycast"), "raycast");
    setenv("VOLVIS_GUI_GPU", "any", 1);
    assert_string_equal(vvg_gui_renderer(w, "raycast"), n > 0 ? "gpu" : "raycast");
    /* two volume objects: raycast draws them, gpu does not */
    vv_object *o2 = NULL;
    vt_ok(vv_object_new_volume(&o2, v, "v2"));
    vt_ok(vv_world_add_object(w, o2));
    assert_string_equal(vvg_gui_renderer(w, "raycast"), "raycast");
    o2->visible = 0;
    /* label colours: raycast's */
    o->segmentation = VV_SEG_LABELS;
    assert_string_equal(vvg_gui_renderer(w, "raycast"), "raycast");
    unsetenv("VOLVIS_GUI_GPU");
    printf("# %d Vulkan device(s), %s: the GUI picks %s\n", n, real ? "a real GPU" : "no real GPU",
           real ? "gpu" : "raycast");
    vv_world_free(w);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_undo),
        cmocka_unit_test(test_undo_clean),
        cmocka_unit_test(test_tf_editing),
        cmocka_unit_test(test_gui_renderer),
    };
    return vt_run_tests(tests, NULL, NULL);
}
