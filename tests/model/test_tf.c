/* Transfer functions: evaluation, sorting, end holds, limits; label colour keys. */
#include <math.h>

#include "testutil.h"

static void
test_empty(void **state) {
    (void)state;
    vv_tf tf;
    vv_tf_init(&tf);
    assert_int_equal(tf.n_opacity, 0);
    assert_int_equal(tf.n_color, 0);
    assert_near(tf.opacity_unit_distance, 1.0, 0);
    assert_near(vv_tf_eval_opacity(&tf, 12.0), 0.0, 0);
    vv_vec3 c = vv_tf_eval_color(&tf, 12.0);
    assert_near(c.x, 1.0, 0);
    assert_near(c.y, 1.0, 0);
    assert_near(c.z, 1.0, 0);
}

static void
test_eval_and_sorting(void **state) {
    (void)state;
    vv_tf tf;
    vv_tf_init(&tf);
    /* added out of order */
    vt_ok(vv_tf_add_opacity(&tf, 100.0, 0.8));
    vt_ok(vv_tf_add_opacity(&tf, 0.0, 0.2));
    vt_ok(vv_tf_add_opacity(&tf, 50.0, 0.0));
    assert_int_equal(tf.n_opacity, 3);
    assert_near(tf.opacity[0].value, 0.0, 0);
    assert_near(tf.opacity[1].value, 50.0, 0);
    assert_near(tf.opacity[2].value, 100.0, 0);
    /* interpolation inside each segment */
    assert_near(vv_tf_eval_opacity(&tf, 25.0), 0.1, 1e-12);
    assert_near(vv_tf_eval_opacity(&tf, 50.0), 0.0, 1e-12);
    assert_near(vv_tf_eval_opacity(&tf, 75.0), 0.4, 1e-12);
    assert_near(vv_tf_eval_opacity(&tf, 90.0), 0.64, 1e-12);
    /* end values hold */
    assert_near(vv_tf_eval_opacity(&tf, -1e9), 0.2, 0);
    assert_near(vv_tf_eval_opacity(&tf, 1e9), 0.8, 0);
    assert_near(vv_tf_eval_opacity(&tf, NAN), 0.0, 0);

    vt_ok(vv_tf_add_color(&tf, 10.0, vv_vec3_make(0, 0, 1)));
    vt_ok(vv_tf_add_color(&tf, 0.0, vv_vec3_make(1, 0, 0)));
    vv_vec3 c = vv_tf_eval_color(&tf, 2.5);
    assert_near(c.x, 0.75, 1e-12);
    assert_near(c.y, 0.0, 1e-12);
    assert_near(c.z, 0.25, 1e-12);
    c = vv_tf_eval_color(&tf, -5);
    assert_near(c.x, 1.0, 0);
    c = vv_tf_eval_color(&tf, 50);
    assert_near(c.z, 1.0, 0);
}

static void
test_step(void **state) {
    (void)state;
    /* two points at one value make a step: the later one holds above it */
    vv_tf tf;
    vv_tf_init(&tf);
    vt_ok(vv_tf_add_opacity(&tf, 10.0, 0.0));
    vt_ok(vv_tf_add_opacity(&tf, 10.0, 1.0));
    assert_near(vv_tf_eval_opacity(&tf, 9.999), 0.0, 0);
    assert_near(vv_tf_eval_opacity(&tf, 10.0), 1.0, 0);
    assert_near(vv_tf_eval_opacity(&tf, 10.001), 1.0, 0);
    assert_true(isfinite(vv_tf_eval_opacity(&tf, 10.0)));
}

static void
test_limits(void **state) {
    (void)state;
    vv_tf tf;
    vv_tf_init(&tf);
    vt_err(vv_tf_add_opacity(&tf, NAN, 0.5));
    vt_err(vv_tf_add_opacity(&tf, INFINITY, 0.5));
    vt_err(vv_tf_add_opacity(&tf, 1.0, -0.01));
    vt_err(vv_tf_add_opacity(&tf, 1.0, 1.01));
    vt_err(vv_tf_add_opacity(&tf, 1.0, NAN));
    vt_err(vv_tf_add_color(&tf, 1.0, vv_vec3_make(0, 2, 0)));
    vt_err(vv_tf_add_color(&tf, NAN, vv_vec3_make(0, 0, 0)));
    assert_int_equal(tf.n_opacity, 0);
    assert_int_equal(tf.n_color, 0);
    for (int i = 0; i < VV_TF_MAX_POINTS; i++)
        vt_ok(vv_tf_add_opacity(&tf, VV_TF_MAX_POINTS - i, 0.5));
    assert_int_equal(vv_tf_add_opacity(&tf, 0, 0.5), VV_ERR_LIMIT);
    for (int i = 1; i < VV_TF_MAX_POINTS; i++)
        assert_true(tf.opacity[i - 1].value <= tf.opacity[i].value);
    for (int i = 0; i < VV_TF_MAX_POINTS; i++)
        vt_ok(vv_tf_add_color(&tf, i, vv_vec3_make(0, 0, 0)));
    assert_int_equal(vv_tf_add_color(&tf, 0, vv_vec3_make(0, 0, 0)), VV_ERR_LIMIT);
}

static void
test_ramp(void **state) {
    (void)state;
    vv_tf tf;
    vv_tf_set_ramp(&tf, 100, 300, 0.6, vv_vec3_make(1, 0.5, 0), 0.25);
    assert_near(tf.opacity_unit_distance, 0.25, 0);
    assert_near(vv_tf_eval_opacity(&tf, 50), 0.0, 0);
    assert_near(vv_tf_eval_opacity(&tf, 200), 0.3, 1e-12);
    assert_near(vv_tf_eval_opacity(&tf, 1000), 0.6, 0);
    vv_vec3 c = vv_tf_eval_color(&tf, 150);
    assert_near(c.y, 0.5, 0);
    /* reversed ends are swapped; bad unit distance falls back to 1 */
    vv_tf_set_ramp(&tf, 300, 100, 2.0, vv_vec3_make(1, 1, 1), -1);
    assert_near(tf.opacity_unit_distance, 1.0, 0);
    assert_near(vv_tf_eval_opacity(&tf, 300), 1.0, 0);
    assert_near(vv_tf_eval_opacity(&tf, 100), 0.0, 0);
}

/* Label ids to colour keys: the background 0, ids below 2^32 themselves,
 * 64-bit ids (connectomics segmentations) folded to non-zero keys that
 * still tell neighbouring ids apart. */
static void
test_label_key(void **state) {
    (void)state;
    assert_int_equal(vv_label_key(0), 0);
    assert_int_equal(vv_label_key(0.4), 0);
    assert_int_equal(vv_label_key(-3), 0);
    assert_int_equal(vv_label_key(NAN), 0);
    assert_int_equal(vv_label_key(1), 1);
    assert_int_equal(vv_label_key(4294967295.0), 4294967295u);
    assert_int_equal(vv_label_key(4294967296.0), 1); /* halves 1 and 0 */
    const double big = 1099511627776.0;              /* 2^40 */
    assert_int_equal(vv_label_key(big), 256);
    assert_int_not_equal(vv_label_key(big + 3), vv_label_key(big + 4));
    assert_int_not_equal(vv_label_key(big + 3), 0);
    assert_int_not_equal(vv_label_key(864691135561333258.0), 0); /* a MICrONS-sized id */
    assert_int_equal(vv_label_key(1e30), 1); /* past 2^64: all ones, halves xor-ed to 0, so 1 */
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_empty), cmocka_unit_test(test_eval_and_sorting),
        cmocka_unit_test(test_step),  cmocka_unit_test(test_limits),
        cmocka_unit_test(test_ramp),  cmocka_unit_test(test_label_key),
    };
    return vt_run_tests(tests, NULL, NULL);
}
