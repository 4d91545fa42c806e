/* Joint value x gradient-magnitude histograms (vv_histogram2d_compute). */
#include <math.h>
#include <stdlib.h>

#include "testutil.h"

/* value = 3 i on a grid of spacing 0.5: the gradient magnitude is 3 / 0.5
 * = 6 data units per world unit at every voxel (one-sided differences at
 * the faces of a linear ramp are exact too). */
static void
test_ramp_constant_gradient(void **state) {
    (void)state;
    int dims[3] = {10, 6, 5};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    v->spacing[0] = v->spacing[1] = v->spacing[2] = 0.5;
    for (int k = 0; k < 5; k++)
        for (int j = 0; j < 6; j++)
            for (int i = 0; i < 10; i++)
                vv_volume_set(v, i, j, k, 3.0 * i);
    vv_volume_update_range(v);
    vv_histogram2d *h = NULL;
    vt_ok(vv_histogram2d_compute(&h, v, 10, 4, 0, 0, 12));
    assert_near(h->gradient_max, 6.0, 1e-12);
    assert_int_equal(h->total, 300);
    assert_int_equal(h->outside, 0);
    assert_near(h->value_lo, 0, 0);
    assert_near(h->value_hi, 27, 0);
    for (int g = 0; g < 4; g++)
        for (int b = 0; b < 10; b++)
            assert_int_equal(h->counts[g * 10 + b], g == 2 ? 30 : 0); /* 6 of [0, 12] in 4 */
    vv_histogram2d_free(h);
    /* automatic gradient range: the maximum falls into the last bin */
    vt_ok(vv_histogram2d_compute(&h, v, 3, 8, 0, 0, 0));
    assert_near(h->gradient_hi, 6.0, 1e-12);
    uint64_t last = 0;
    for (int b = 0; b < 3; b++)
        last += h->counts[7 * 3 + b];
    assert_int_equal(last, 300);
    vv_histogram2d_free(h);
    vt_err(vv_histogram2d_compute(&h, v, 0, 8, 0, 0, 0));
    vt_err(vv_histogram2d_compute(&h, v, 4, 8, NAN, 1, 0));
    assert_null(h);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ramp_constant_gradient),
    };
    return vt_run_tests(tests, NULL, NULL);
}
