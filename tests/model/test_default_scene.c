/* The default scene of one volume: centring, framing, histogram transfer function. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "testutil.h"

static int
project(const vv_view *v, vv_vec3 p, double *px, double *py) {
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(v->at, v->eye));
    vv_vec3 r = vv_vec3_normalize(vv_vec3_cross(f, v->up));
    vv_vec3 u = vv_vec3_cross(r, f);
    vv_vec3 d = vv_vec3_sub(p, v->eye);
    double z = vv_vec3_dot(d, f);
    if (z <= 0)
        return 0;
    double t = tan(0.5 * v->fov), aspect = (double)v->width / v->height;
    *px = (vv_vec3_dot(d, r) / z / (t * aspect) + 1) * 0.5 * v->width;
    *py = (1 - vv_vec3_dot(d, u) / z / t) * 0.5 * v->height;
    return 1;
}

static void
check_box_in_view(const vv_view *v, vv_box b) {
    for (int i = 0; i < 8; i++) {
        vv_vec3 p = vv_vec3_make(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                 i & 4 ? b.max.z : b.min.z);
        double px = -1, py = -1;
        assert_true(project(v, p, &px, &py));
        assert_true(px >= 0 && px <= v->width);
        assert_true(py >= 0 && py <= v->height);
    }
}

/* Fraction of voxels with value >= x. */
static double
fraction_above(const vv_volume *v, double x) {
    uint64_t n = vv_volume_voxel_count(v), above = 0;
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int i = 0; i < v->dims[0]; i++)
                above += vv_volume_get(v, i, j, k) >= x;
    return (double)above / (double)n;
}

static double
tf_lo(const vv_object *o) {
    return o->tf.opacity[0].value;
}

static double
tf_hi(const vv_object *o) {
    return o->tf.opacity[o->tf.n_opacity - 1].value;
}

static void
test_ct_head(void **state) {
    (void)state;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, NULL));
    assert_int_equal(w->n_objects, 1);
    const vv_object *o = w->objects[0];
    assert_ptr_equal(o->volume, v);
    assert_int_equal(v->refcount, 2);

    /* centred on the origin */
    vv_box b = vv_world_bounds(w);
    assert_near(0.5 * (b.min.x + b.max.x), 0, 1e-6);
    assert_near(0.5 * (b.min.y + b.max.y), 0, 1e-6);
    assert_near(0.5 * (b.min.z + b.max.z), 0, 1e-6);
    /* from the front (+y: no declared space, RAS-like), up +z, the whole box in view */
    assert_true(w->view.eye.y > 0);
    assert_near(w->view.eye.x, 0, 1e-9);
    assert_near(w->view.up.z, 1, 1e-9);
    assert_near(w->view.fov, vv_deg_to_rad(30), 1e-12);
    assert_int_equal(w->view.width, 512);
    check_box_in_view(&w->view, b);
    /* a white headlight, ambient 1, black background */
    assert_int_equal(w->n_lights, 1);
    assert_int_equal(w->lights[0].headlight, 1);
    assert_near(w->lights[0].intensity, 1, 0);
    assert_near(w->ambient.y, 1, 0);
    assert_near(w->background.z, 0, 0);
    assert_near(o->step, 0.5, 0);
    assert_near(o->material.shininess, 30, 0);

    /* TF: above air, below the top of the range */
    double lo = tf_lo(o), hi = tf_hi(o);
    assert_true(lo > -500);
    assert_true(hi < 3000);
    assert_true(hi > lo + 500); /* reaches into bone */
    assert_near(vv_tf_eval_opacity(&o->tf, -1000), 0, 0);
    assert_true(vv_tf_eval_opacity(&o->tf, 1500) > 0.3);
    assert_near(o->tf.opacity_unit_distance,
                v->spacing[0] < v->spacing[2] ? v->spacing[0] : v->spacing[2], 1e-9);
    double fa = fraction_above(v, lo);
    assert_true(fa > 0.05 && fa < 0.5);
    vv_world_free(w);

    /* data declared LPS (DICOM-style): anterior is -y, so the eye is on -y */
    v->space = VV_SPACE_LPS;
    vt_ok(vv_world_new_for_volume(&w, v, NULL));
    assert_true(w->view.eye.y < 0);
    vv_world_free(w);
    v->space = VV_SPACE_UNKNOWN;

    /* MIP: grey ramp over the 1st..99.9th percentile; iso: a value above air */
    vv_default_scene_options opt;
    vv_default_scene_options_init(&opt);
    opt.mode = VV_MODE_MIP;
    vt_ok(vv_world_new_for_volume(&w, v, &opt));
    o = w->objects[0];
    assert_int_equal(o->mode, VV_MODE_MIP);
    assert_true(tf_lo(o) < -900);
    assert_true(tf_hi(o) > 1000 && tf_hi(o) < 3000);
    vv_vec3 c = vv_tf_eval_color(&o->tf, tf_lo(o));
    assert_near(c.x, 0, 1e-12);
    vv_world_free(w);

    opt.mode = VV_MODE_ISO;
    vt_ok(vv_world_new_for_volume(&w, v, &opt));
    assert_true(w->objects[0]->isovalue > -500 && w->objects[0]->isovalue < 500);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_mri(void **state) {
    (void)state;
    const char *files[] = {"volumes/HeadMRVolume.mhd", "volumes/avg152T1_RL_nifti.nii.gz",
                           "/usr/share/mricron/templates/ch2.nii.gz"};
    for (int f = 0; f < 3; f++) {
        const char *path = f < 2 ? vt_data(files[f]) : files[f];
        vv_volume *v = NULL;
        if (f == 2) {
            FILE *fp = fopen(path, "rb");
            if (!fp)
                continue; /* optional Debian package mricron-data */
            fclose(fp);
        }
        vt_ok(vv_volume_load(&v, path, NULL));
        vv_world *w = NULL;
        vt_ok(vv_world_new_for_volume(&w, v, NULL));
        double lo = tf_lo(w->objects[0]), hi = tf_hi(w->objects[0]);
        /* the background (about half the voxels, near 0) is transparent */
        double fa = fraction_above(v, lo);
        if (!(fa > 0.02 && fa < 0.75) || !(lo > v->range[0] + 5) || !(hi > lo))
            fail_msg("%s: lo %g hi %g, %.3f of the voxels above lo", path, lo, hi, fa);
        assert_near(vv_tf_eval_opacity(&w->objects[0]->tf, v->range[0]), 0, 0);
        vv_world_free(w);
        vv_volume_free(v);
    }
}

/* A single slice (a 2-D image) is viewed face on, along its one-voxel axis. */
static void
test_single_slice(void **state) {
    (void)state;
    const int dims[3] = {40, 30, 1};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    for (int j = 0; j < 30; j++)
        for (int i = 0; i < 40; i++)
            vv_volume_set(v, i, j, 0, (i * 7 + j * 3) % 200);
    vv_volume_update_range(v);
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, NULL));
    vv_vec3 dir = vv_vec3_normalize(vv_vec3_sub(w->view.eye, w->view.at));
    assert_near(fabs(dir.z), 1, 1e-9);
    assert_near(w->view.up.y, 1, 1e-9);
    vv_world_free(w);
    vv_volume_free(v);
}

static void
test_synthetic(void **state) {
    (void)state;
    /* a noisy ball of value ~200 in a background of ~10 */
    int dims[3] = {40, 40, 40};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    unsigned seed = 1;
    for (int k = 0; k < 40; k++)
        for (int j = 0; j < 40; j++)
            for (int i = 0; i < 40; i++) {
                seed = seed * 1103515245u + 12345u;
                double noise = (double)((seed >> 16) % 9) - 4.0;
                double r = sqrt((i - 20.0) * (i - 20.0) + (j - 20.0) * (j - 20.0) +
                                (k - 20.0) * (k - 20.0));
                vv_volume_set(v, i, j, k, (r < 12 ? 200 : 10) + noise);
            }
    vv_volume_update_range(v);
    v->origin[0] = 100;
    v->spacing[2] = 2;
    vv_default_scene_options opt;
    vv_default_scene_options_init(&opt);
    opt.azimuth = vv_deg_to_rad(90);
    opt.zoom = 2;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &opt));
    double lo = tf_lo(w->objects[0]), hi = tf_hi(w->objects[0]);
    if (!(lo > 14 && lo < 196 && hi <= 204 && hi > lo))
        fail_msg("lo %g hi %g", lo, hi);
    vv_box b = vv_world_bounds(w);
    assert_near(b.min.x + b.max.x, 0, 1e-9);
    assert_near(b.max.z - b.min.z, 78, 1e-9);
    /* azimuth 90° about +z: the eye moves from +y to -x */
    assert_true(w->view.eye.x < 0);
    assert_near(w->view.eye.y, 0, 1e-6);
    vv_world_free(w);

    /* the given range and isovalue win */
    opt.has_tf_range = 1;
    opt.tf_lo = 50;
    opt.tf_hi = 60;
    opt.mode = VV_MODE_ISO;
    opt.has_isovalue = 1;
    opt.isovalue = 77;
    vt_ok(vv_world_new_for_volume(&w, v, &opt));
    assert_near(tf_lo(w->objects[0]), 50, 0);
    assert_near(tf_hi(w->objects[0]), 60, 0);
    assert_near(w->objects[0]->isovalue, 77, 0);
    vv_world_free(w);

    /* bad options */
    opt.zoom = 0;
    vt_err(vv_world_new_for_volume(&w, v, &opt));
    assert_null(w);
    opt.zoom = 1;
    opt.tf_hi = 40;
    vt_err(vv_world_new_for_volume(&w, v, &opt));
    vt_err(vv_world_new_for_volume(&w, NULL, NULL));
    vv_volume_free(v);

    /* a constant volume does not break anything */
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    vv_volume_update_range(v);
    vt_ok(vv_world_new_for_volume(&w, v, NULL));
    assert_true(tf_hi(w->objects[0]) > tf_lo(w->objects[0]));
    vv_world_free(w);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ct_head),
        cmocka_unit_test(test_mri),
        cmocka_unit_test(test_synthetic),
        cmocka_unit_test(test_single_slice),
    };
    return vt_run_tests(tests, NULL, NULL);
}
