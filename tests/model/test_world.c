/* Objects and the World: transforms, bounds, lights, cut planes. */
#include <math.h>

#include "testutil.h"

static vv_volume *
small_volume(void) {
    int dims[3] = {5, 4, 3};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 5; i++)
                vv_volume_set(v, i, j, k, i + j + k);
    vv_volume_update_range(v);
    v->spacing[0] = 2.0;
    v->spacing[1] = 0.5;
    v->spacing[2] = 1.0;
    v->origin[0] = 10;
    return v;
}

static void
test_object_defaults(void **state) {
    (void)state;
    vv_volume *v = small_volume();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "thing"));
    assert_int_equal(v->refcount, 2);
    assert_string_equal(o->name, "thing");
    assert_int_equal(o->mode, VV_MODE_COMPOSITE);
    assert_near(o->step, 0.5, 0);
    assert_int_equal(o->shading, 1);
    assert_int_equal(o->visible, 1);
    assert_near(o->material.ambient, 0.1, 0);
    assert_near(o->material.diffuse, 0.6, 0);
    assert_near(o->material.specular, 0.3, 0);
    assert_near(o->material.shininess, 30, 0);
    assert_near(o->tf.opacity_unit_distance, 0.5, 0);
    assert_near(vv_tf_eval_opacity(&o->tf, v->range[0]), 0.0, 0);
    assert_true(vv_tf_eval_opacity(&o->tf, v->range[1]) > 0.0);
    vv_object_free(o);
    assert_int_equal(v->refcount, 1);
    vt_err(vv_object_new_volume(&o, NULL, "x"));
    assert_null(o);
    vv_volume_free(v);
}

static void
test_object_matrix(void **state) {
    (void)state;
    vv_volume *v = small_volume();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, NULL));
    o->position = vv_vec3_make(1, 2, 3);
    o->orientation = vv_quat_from_axis_angle(vv_vec3_make(0, 0, 1), VV_PI / 2);
    o->scale = vv_vec3_make(2, 2, 2);
    /* position + orientation (scale q) */
    vv_vec3 q = vv_vec3_make(1, 0, 0);
    vv_vec3 p = vv_mat4_mul_point(vv_object_matrix(o), q);
    assert_near(p.x, 1, 1e-12);
    assert_near(p.y, 4, 1e-12);
    assert_near(p.z, 3, 1e-12);
    /* index (1, 0, 0): volume world (12, 0, 0) -> object: rotate (24, 0, 0) -> (0, 24, 0) */
    p = vv_mat4_mul_point(vv_object_index_to_world(o), vv_vec3_make(1, 0, 0));
    assert_near(p.x, 1, 1e-9);
    assert_near(p.y, 26, 1e-9);
    assert_near(p.z, 3, 1e-9);
    vv_box b = vv_object_world_box(o);
    /* i spans 10..18 in volume world, j 0..1.5, k 0..2; x2, rotated 90° about z */
    assert_near(b.min.y, 2 + 20, 1e-9);
    assert_near(b.max.y, 2 + 36, 1e-9);
    assert_near(b.min.x, 1 - 3, 1e-9);
    assert_near(b.max.x, 1, 1e-9);
    assert_near(b.max.z, 3 + 4, 1e-9);
    vv_object_free(o);
    vv_volume_free(v);
}

static void
test_world(void **state) {
    (void)state;
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    assert_int_equal(w->view.width, 512);
    assert_int_equal(w->view.height, 512);
    assert_near(w->view.fov, vv_deg_to_rad(30), 1e-12);
    assert_near(w->view.eye.y, -1000, 0);
    assert_near(w->ambient.x, 1, 0);
    assert_near(w->background.x, 0, 0);
    vv_box b = vv_world_bounds(w);
    assert_near(b.max.x - b.min.x, 0, 0);

    vv_volume *v = small_volume();
    for (int i = 0; i < 9; i++) {
        vv_object *o = NULL;
        vt_ok(vv_object_new_volume(&o, v, "o"));
        o->position = vv_vec3_make(100.0 * i, 0, 0);
        o->visible = i < 8;
        vt_ok(vv_world_add_object(w, o));
    }
    assert_int_equal(w->n_objects, 9);
    b = vv_world_bounds(w);
    assert_near(b.min.x, 10, 1e-9);
    assert_near(b.max.x, 718, 1e-9); /* the 9th is hidden */
    assert_int_equal(v->refcount, 10);
    vt_err(vv_world_add_object(w, NULL));

    vv_light l = {VV_LIGHT_DIRECTIONAL, 1, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1.0};
    for (int i = 0; i < VV_MAX_LIGHTS; i++)
        vt_ok(vv_world_add_light(w, &l));
    assert_int_equal(vv_world_add_light(w, &l), VV_ERR_LIMIT);

    vt_err(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 0), vv_vec3_make(0, 0, 0)));
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(1, 0, 0), vv_vec3_make(0, 0, 5)));
    assert_near(w->cut_planes[0].normal.z, 1, 0);
    for (int i = 1; i < VV_MAX_CUT_PLANES; i++)
        vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(1, 0, 0), vv_vec3_make(0, 0, 5)));
    assert_int_equal(vv_world_add_cut_plane(w, vv_vec3_make(0, 0, 0), vv_vec3_make(1, 0, 0)),
                     VV_ERR_LIMIT);
    vv_world_free(w);
    assert_int_equal(v->refcount, 1);
    vv_volume_free(v);
    vv_world_free(NULL);
    vv_object_free(NULL);
}

/* A clone is independent of its source (edits do not leak either way) and shares the voxels. */
static void
test_world_clone(void **state) {
    (void)state;
    vv_world *w = NULL;
    vt_ok(vv_world_new(&w));
    vv_volume *v = small_volume();
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "head"));
    vt_ok(vv_world_add_object(w, o));
    vv_object *p = NULL;
    vt_ok(vv_object_new_geometry(&p, VV_OBJECT_POLYGON, "tri"));
    vv_vec3 tri[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    vt_ok(vv_object_set_polygon(p, 3, tri));
    vt_ok(vv_world_add_object(w, p));
    vt_ok(vv_world_add_cut_plane(w, vv_vec3_make(1, 2, 3), vv_vec3_make(0, 0, 1)));

    vv_world *c = NULL;
    vt_ok(vv_world_clone(&c, w));
    assert_int_equal(c->n_objects, 2);
    assert_ptr_not_equal(c->objects[0], w->objects[0]);
    assert_ptr_equal(c->objects[0]->volume, v);
    assert_int_equal(v->refcount, 3);
    assert_ptr_not_equal(c->objects[1]->geometry.vertices, w->objects[1]->geometry.vertices);
    assert_near(c->objects[1]->geometry.vertices[1].x, 1, 0);
    assert_int_equal(c->n_cut_planes, 1);
    assert_string_equal(c->objects[0]->name, "head");

    w->objects[0]->tf.opacity[0].opacity = 0.25;
    w->objects[1]->geometry.vertices[1].x = 7;
    w->view.fov = 1.0;
    assert_true(c->objects[0]->tf.opacity[0].opacity != 0.25);
    assert_near(c->objects[1]->geometry.vertices[1].x, 1, 0);
    assert_true(c->view.fov != 1.0);

    /* take and insert keep the order */
    vv_object *t = NULL;
    vt_ok(vv_world_take_object(c, 0, &t));
    assert_int_equal(c->n_objects, 1);
    assert_string_equal(c->objects[0]->name, "tri");
    vt_ok(vv_world_insert_object(c, 0, t));
    assert_string_equal(c->objects[0]->name, "head");
    assert_string_equal(c->objects[1]->name, "tri");
    vt_err(vv_world_take_object(c, 2, &t));
    vt_err(vv_world_insert_object(c, 5, NULL));

    vv_world_free(c);
    assert_int_equal(v->refcount, 2);
    vv_world_free(w);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_object_defaults),
        cmocka_unit_test(test_object_matrix),
        cmocka_unit_test(test_world),
        cmocka_unit_test(test_world_clone),
    };
    return vt_run_tests(tests, NULL, NULL);
}
