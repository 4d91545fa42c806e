/* Multiplanar reconstruction (include/volvis/slice.h): planes in the
 * anatomical frame, exact samples of a linear field, the probe, a rotated
 * and placed volume against vv_volume_sample_world, a real CT slice against
 * Teem's own `unu slice`, window and level, `volvis slice`, and an object
 * out of core (an OME-Zarr pyramid) sliced and probed from its file. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* A volume whose value is linear in the index, so trilinear samples are exact:
 * v = 1 + i + 10 j + 100 k. */
static vv_volume *
linear_volume(int nx, int ny, int nz, vv_space space) {
    vv_volume *v = NULL;
    int dims[3] = {nx, ny, nz};
    vt_ok(vv_volume_new(&v, dims, VV_F32));
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++)
                vv_volume_set(v, i, j, k, 1 + i + 10 * j + 100 * k);
    v->spacing[0] = 0.5;
    v->spacing[1] = 2;
    v->spacing[2] = 3;
    v->origin[0] = -4;
    v->origin[1] = 1;
    v->origin[2] = 7;
    v->space = space;
    vv_volume_update_range(v);
    return v;
}

static vv_object *
object_of(vv_volume *v) {
    vv_object *o = NULL;
    vt_ok(vv_object_new_volume(&o, v, "v"));
    vv_volume_free(v);
    return o;
}

/* value of linear_volume at world point p (identity direction, no transform) */
static double
linear_at(vv_vec3 p) {
    double i = (p.x + 4) / 0.5, j = (p.y - 1) / 2, k = (p.z - 7) / 3;
    return 1 + i + 10 * j + 100 * k;
}

/* Radiological orientation in RAS and LPS, the World's axes otherwise. */
static void
test_orientation(void **state) {
    (void)state;
    vv_slice_plane p;
    vv_vec3 o = vv_vec3_make(0, 0, 0);
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_AXIAL, VV_SPACE_RAS, o, 10, 10, 1));
    assert_string_equal(p.edge[0], "L"); /* patient's left on the image's right */
    assert_string_equal(p.edge[1], "R");
    assert_string_equal(p.edge[2], "A");
    assert_string_equal(p.edge[3], "P");
    vv_vec3 n = vv_slice_plane_normal(&p);
    assert_near(n.z, -1, 1e-12); /* seen from the feet */
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_CORONAL, VV_SPACE_LPS, o, 10, 10, 1));
    assert_near(p.right.x, 1, 1e-12); /* LPS: +x is the patient's left */
    assert_string_equal(p.edge[0], "L");
    assert_string_equal(p.edge[2], "S");
    assert_string_equal(p.edge[3], "I");
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_SAGITTAL, VV_SPACE_RAS, o, 10, 10, 1));
    assert_string_equal(p.edge[0], "P"); /* anterior on the left */
    assert_string_equal(p.edge[1], "A");
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_SAGITTAL, VV_SPACE_UNKNOWN, o, 10, 10, 1));
    assert_string_equal(p.edge[0], "+y");
    assert_string_equal(p.edge[2], "+z");
    /* an oblique plane: unit axes, right x up = the normal, up towards superior */
    vt_ok(vv_slice_plane_oblique(&p, VV_SPACE_RAS, o, vv_vec3_make(0, 1, 1), 10, 10, 1));
    n = vv_slice_plane_normal(&p);
    assert_near(n.y, sqrt(0.5), 1e-12);
    assert_near(n.z, sqrt(0.5), 1e-12);
    assert_near(vv_vec3_dot(p.right, p.up), 0, 1e-12);
    assert_true(p.up.z > 0);
    vt_ok(vv_slice_plane_oblique(&p, VV_SPACE_RAS, o, vv_vec3_make(0, 0, 5), 10, 10, 1));
    assert_near(p.up.y, 1, 1e-12); /* along z: anterior up */
    vt_err(vv_slice_plane_oblique(&p, VV_SPACE_RAS, o, vv_vec3_make(0, 0, 0), 10, 10, 1));
    vt_err(vv_slice_plane_standard(&p, VV_SLICE_OBLIQUE, VV_SPACE_RAS, o, 10, 10, 1));
    vt_err(vv_slice_plane_standard(&p, VV_SLICE_AXIAL, VV_SPACE_RAS, o, 0, 10, 1));
    vt_err(vv_slice_plane_standard(&p, VV_SLICE_AXIAL, VV_SPACE_RAS, o, 10, 10, -1));
    /* pixel <-> world round trip */
    vt_ok(vv_slice_plane_oblique(&p, VV_SPACE_RAS, vv_vec3_make(1, 2, 3), vv_vec3_make(1, 2, 2), 64,
                                 48, 0.25));
    vv_vec3 w = vv_slice_plane_to_world(&p, 10.25, 40.5);
    double x, y, d;
    vv_slice_plane_from_world(&p, vv_vec3_add(w, vv_vec3_scale(vv_slice_plane_normal(&p), 2)), &x,
                              &y, &d);
    assert_near(x, 10.25, 1e-9);
    assert_near(y, 40.5, 1e-9);
    assert_near(d, 2, 1e-9);
}

/* Samples of a linear field are exact; outside the box they are NaN; the
 * probe agrees; the slice step is one voxel along the normal. */
static void
test_linear(void **state) {
    (void)state;
    vv_object *o = object_of(linear_volume(17, 9, 6, VV_SPACE_RAS));
    vv_slice_plane p;
    vv_vec3 at = vv_vec3_make(0, 5, 13.5); /* k = 2.17: between slices */
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_AXIAL, VV_SPACE_RAS, at, 40, 30, 0.37));
    float *v = malloc(sizeof(float) * 40 * 30);
    vt_ok(vv_slice_sample(o, &p, v));
    int inside = 0, outside = 0;
    vv_box box = vv_object_world_box(o);
    for (int y = 0; y < 30; y++)
        for (int x = 0; x < 40; x++) {
            vv_vec3 w = vv_slice_plane_to_world(&p, x + 0.5, y + 0.5);
            int in = w.x >= box.min.x && w.x <= box.max.x && w.y >= box.min.y && w.y <= box.max.y;
            float s = v[y * 40 + x];
            if (in) {
                assert_near(s, linear_at(w), 2e-4);
                assert_near(vv_slice_probe(o, w, NULL), linear_at(w), 2e-4);
                inside++;
            } else {
                assert_true(isnan(s));
                outside++;
            }
        }
    assert_true(inside > 300 && outside > 100);
    /* the image's right is the patient's left (-x in RAS): values fall to the right */
    assert_true(v[15 * 40 + 10] > v[15 * 40 + 11]);
    double ijk[3];
    assert_near(vv_slice_probe(o, vv_vec3_make(-4 + 0.5 * 3, 1 + 2 * 4, 7 + 3 * 5), ijk),
                1 + 3 + 40 + 500, 1e-4);
    assert_near(ijk[0], 3, 1e-9);
    assert_near(ijk[2], 5, 1e-9);
    assert_true(isnan(vv_slice_probe(o, vv_vec3_make(100, 0, 0), NULL)));
    assert_near(vv_slice_step(o, vv_vec3_make(0, 0, 1)), 3, 1e-12);
    assert_near(vv_slice_step(o, vv_vec3_make(1, 0, 0)), 0.5, 1e-12);
    /* along (0, 1, 1): one voxel along j (2) takes sqrt(2) * 2 ... the larger index step is k's */
    assert_near(vv_slice_step(o, vv_vec3_make(0, 1, 1)), 2 * sqrt(2), 1e-12);
    free(v);
    vv_object_free(o);
}

/* A turned volume (direction matrix) placed by an object transform: the
 * slice equals vv_volume_sample_world at the point the transform brings back. */
static void
test_transformed(void **state) {
    (void)state;
    vv_volume *vol = linear_volume(20, 16, 12, VV_SPACE_LPS);
    double c = cos(0.4), s = sin(0.4);
    double dir[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
    memcpy(vol->direction, dir, sizeof dir);
    vv_object *o = object_of(vol);
    o->position = vv_vec3_make(3, -2, 1);
    o->orientation = vv_quat_from_axis_angle(vv_vec3_normalize(vv_vec3_make(1, 1, 0)), 0.3);
    o->scale = vv_vec3_make(1.5, 1.5, 1.5);
    vv_box box = vv_object_world_box(o);
    vv_vec3 mid = vv_vec3_scale(vv_vec3_add(box.min, box.max), 0.5);
    vv_slice_plane p;
    vt_ok(vv_slice_plane_oblique(&p, VV_SPACE_LPS, mid, vv_vec3_make(0.2, -0.5, 1), 50, 50, 1));
    vv_slice_plane_fit(&p, box, 0.05);
    float *v = malloc(sizeof(float) * 50 * 50);
    vt_ok(vv_slice_sample(o, &p, v));
    int ok = 0;
    vv_mat4 inv_obj;
    int inv = 0;
    inv_obj = vv_mat4_inverse(vv_object_matrix(o), &inv);
    assert_true(inv);
    for (int y = 0; y < 50; y++)
        for (int x = 0; x < 50; x++) {
            vv_vec3 w = vv_slice_plane_to_world(&p, x + 0.5, y + 0.5);
            float ref = 0;
            if (vv_volume_sample_world(o->volume, vv_mat4_mul_point(inv_obj, w), &ref) &&
                !isnan(v[y * 50 + x])) {
                assert_near(v[y * 50 + x], ref, 1e-3 * fabs(ref) + 1e-3);
                ok++;
            }
        }
    assert_true(ok > 100);
    free(v);
    vv_object_free(o);
}

/* The CT head's axial slice 54 at one pixel a voxel equals Teem's `unu slice`. */
static void
test_ct_against_teem(void **state) {
    (void)state;
    const char *in = vt_data("volumes/ct_head.nrrd");
    const char *ref = vt_path(vt_outdir("render_slice"), "unu_slice54.nrrd");
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "teem-unu slice -a 2 -p 54 -i '%s' -o '%s' 2>/dev/null", in, ref);
    if (system(cmd) != 0) {
        vt_skip("teem-unu is not installed (Debian teem-apps)");
    }
    vv_volume *v = NULL, *r = NULL;
    vt_ok(vv_volume_load(&v, in, NULL));
    vt_ok(vv_volume_load(&r, ref, NULL));
    assert_int_equal(r->dims[0], 256);
    assert_int_equal(r->dims[1], 256);
    vv_object *o = object_of(v);
    vv_vec3 at = vv_vec3_make(0, 0, 54 * 1.5);
    vv_slice_plane p;
    vt_ok(vv_slice_plane_standard(&p, VV_SLICE_AXIAL, v->space, at, 256, 256, v->spacing[0]));
    /* centre of the image on the centre of voxel row/column 127.5 */
    p.center.x = p.center.y = 127.5 * v->spacing[0];
    float *s = malloc(sizeof(float) * 256 * 256);
    vt_ok(vv_slice_sample(o, &p, s));
    int mirror = p.right.x < 0;
    for (int y = 0; y < 256; y += 3)
        for (int x = 0; x < 256; x += 3) {
            int i = mirror ? 255 - x : x, j = 255 - y; /* image rows go down, j goes up */
            assert_near(s[y * 256 + x], vv_volume_get(r, i, j, 0), 1e-3);
        }
    free(s);
    vv_volume_free(r);
    vv_object_free(o);
}

static void
test_window_level(void **state) {
    (void)state;
    float v[5] = {-10, 0, 40, 100, NAN};
    uint8_t px[20];
    vv_slice_window_level(v, 5, 100, 50, vv_vec3_make(0, 0, 1), px);
    assert_int_equal(px[0], 0);
    assert_int_equal(px[4], 0);
    assert_int_equal(px[8], 102); /* 255 * 40 / 100 */
    assert_int_equal(px[12], 255);
    assert_int_equal(px[16], 0);
    assert_int_equal(px[18], 255); /* outside: blue */
    assert_int_equal(px[19], 255);
    vv_volume *lin = linear_volume(8, 8, 8, VV_SPACE_UNKNOWN);
    double w, l;
    vv_slice_auto_window(lin, &w, &l);
    assert_true(w > 0 && l > lin->range[0] && l < lin->range[1]);
    vv_volume_free(lin);
}

/* `volvis slice`: the PNG's size and the probe's value, as the library gives them. */
static void
test_cli(void **state) {
    (void)state;
    const char *in = vt_data("volumes/ct_head.nrrd");
    const char *out = vt_path(vt_outdir("render_slice"), "cor.png");
    const char *args[] = {"slice", in, "--axis", "coronal", "-o", out, NULL};
    vt_run_result r = vt_run_cli_v(vt_outdir("render_slice"), args);
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    vv_image *img = NULL;
    vt_ok(vv_image_read_png(&img, out));
    assert_int_equal(img->width, 256);
    assert_int_equal(img->height, (int)ceil(107 * 1.5 / 0.95703119999999997 + 1));
    vv_image_free(img);
    const char *probe[] = {"slice", in, "--probe", "voxel:100.5,120,50", NULL};
    r = vt_run_cli_v(vt_outdir("render_slice"), probe);
    assert_int_equal(r.status, 0);
    double value = 0;
    assert_int_equal(sscanf(r.out, "value %lf", &value), 1);
    vt_run_result_free(&r);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, in, NULL));
    assert_near(value, 0.5 * (vv_volume_get(v, 100, 120, 50) + vv_volume_get(v, 101, 120, 50)),
                1e-6);
    vv_volume_free(v);
    const char *bad[] = {"slice", in, "--axis", "diagonal", "-o", out, NULL};
    r = vt_run_cli_v(vt_outdir("render_slice"), bad);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "diagonal"));
    vt_run_result_free(&r);
    const char *outside[] = {"slice", in, "--probe", "1e4,0,0", NULL};
    r = vt_run_cli_v(vt_outdir("render_slice"), outside);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "outside"));
    vt_run_result_free(&r);
}

/* An object showing an OME-Zarr pyramid out of core is sliced from the
 * file, not from its coarse proxy: at a pixel finer than a voxel, level 0's
 * values (those of the same volume in memory; the field is not linear, so a
 * coarser level would differ); at a pixel of several voxels, a coarser
 * level's box; the probe reads level 0. */
static void
test_out_of_core(void **state) {
    (void)state;
    /* not linear, so that a coarser level (2x2x2 means) differs from level 0 */
    vv_volume *v = linear_volume(96, 80, 72, VV_SPACE_UNKNOWN);
    for (int k = 0; k < 72; k++)
        for (int j = 0; j < 80; j++)
            for (int i = 0; i < 96; i++)
                vv_volume_set(v, i, j, k, (double)((i * j + 7 * k) % 23) + 0.1 * i);
    vv_volume_update_range(v);
    char path[4096];
    snprintf(path, sizeof path, "%s/linear.ome.zarr", vt_outdir("slice"));
    vt_ok(vv_volume_save(v, path, VV_FORMAT_OME_ZARR, 0));
    vv_object *mem = object_of(v);
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE;
    oo.levels = 1;
    vv_opened od;
    vt_ok(vv_open(&od, path, &oo));
    assert_int_equal(vv_source_get_kind(od.source), VV_SOURCE_PYRAMID);
    assert_true(vv_source_levels(od.source) >= 2);
    vv_object *ooc = NULL;
    vt_ok(vv_object_new_source(&ooc, od.source, 0, "file"));
    vv_opened_clear(&od);
    assert_non_null(ooc->source);
    /* the proxy is coarser than level 0: what the file gives must not be it */
    assert_true(ooc->volume->dims[0] < 96);

    vv_box box = vv_object_world_box(mem);
    vv_vec3 c = vv_vec3_scale(vv_vec3_add(box.min, box.max), 0.5);
    vv_slice_plane pl;
    vt_ok(vv_slice_plane_standard(&pl, VV_SLICE_AXIAL, VV_SPACE_UNKNOWN,
                                  vv_vec3_add(c, vv_vec3_make(0.3, -0.7, 1.1)), 64, 48, 0.25));
    size_t n = (size_t)pl.width * pl.height;
    float *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
    assert_non_null(a);
    assert_non_null(b);
    vt_ok(vv_slice_sample(mem, &pl, a));
    vt_ok(vv_slice_sample(ooc, &pl, b));
    int inside = 0;
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(isnan(a[i]), isnan(b[i]));
        if (!isnan(a[i])) {
            inside++;
            if (fabsf(a[i] - b[i]) > 1e-3f * fabsf(a[i]))
                fail_msg("pixel %zu: %g in memory, %g from the file", i, a[i], b[i]);
        }
    }
    assert_true(inside > (int)n / 2);
    /* a pixel of several voxels: a coarser level, values within the data's range */
    vt_ok(vv_slice_plane_standard(&pl, VV_SLICE_CORONAL, VV_SPACE_UNKNOWN, c, 40, 30, 2.5));
    n = (size_t)pl.width * pl.height;
    vt_ok(vv_slice_sample(ooc, &pl, b));
    inside = 0;
    for (size_t i = 0; i < n; i++)
        if (!isnan(b[i])) {
            inside++;
            assert_true(b[i] >= mem->volume->range[0] - 1e-3 &&
                        b[i] <= mem->volume->range[1] + 1e-3);
        }
    assert_true(inside > (int)n / 4);
    /* the probe: level 0, its index */
    double ia[3], ib[3];
    vv_vec3 q = vv_vec3_add(c, vv_vec3_make(1.3, 2.9, -4.4));
    double va = vv_slice_probe(mem, q, ia), vb = vv_slice_probe(ooc, q, ib);
    assert_true(fabs(va - vb) < 1e-3 * fabs(va));
    for (int k = 0; k < 3; k++)
        assert_true(fabs(ia[k] - ib[k]) < 1e-6);
    assert_true(isnan(vv_slice_probe(ooc, vv_vec3_make(1e4, 0, 0), NULL)));
    free(a);
    free(b);
    vv_object_free(mem);
    vv_object_free(ooc);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orientation),  cmocka_unit_test(test_linear),
        cmocka_unit_test(test_transformed),  cmocka_unit_test(test_ct_against_teem),
        cmocka_unit_test(test_window_level), cmocka_unit_test(test_cli),
        cmocka_unit_test(test_out_of_core),
    };
    return vt_run_tests(tests, NULL, NULL);
}
