/*
 * Label volumes from the Filtering component, carried on: the ray caster
 * colours them by label (segmentation "labels", a categorical transfer
 * function with each sample coloured by its nearest label, so two touching
 * labels do not blend into a third colour) and Measurement measures each
 * label (vv_measure_labels, `volvis measure --labels`).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define outdir() vt_outdir("filter_labels")
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})

/* Two touching spheres of values 100 and 200 (u8), anisotropic voxels. */
static vv_volume *
spheres(void) {
    vv_volume *v;
    vt_ok(vv_volume_new(&v, (int[]){48, 24, 24}, VV_U8));
    v->spacing[0] = 0.5;
    v->spacing[1] = 1;
    v->spacing[2] = 1;
    for (int k = 0; k < 24; k++)
        for (int j = 0; j < 24; j++)
            for (int i = 0; i < 48; i++) {
                double x = i * 0.5;
                double a = (x - 7) * (x - 7) + (j - 12) * (j - 12) + (k - 12) * (k - 12);
                double b = (x - 16) * (x - 16) + (j - 12) * (j - 12) + (k - 12) * (k - 12);
                vv_volume_set(v, i, j, k, a <= 20.25 ? 100 : b <= 20.25 ? 200 : 0);
            }
    vv_volume_update_range(v);
    return v;
}

static void
test_measure_labels(void **state) {
    (void)state;
    vv_volume *v = spheres(), *lab;
    /* the two values as two labels: components of each range, added */
    vv_volume *m1, *m2, *l1, *l2;
    vt_ok(vv_filter_region_grow(v, (const int[][3]){{14, 12, 12}}, 1, 50, 150, 6, NULL, &m1));
    vt_ok(vv_filter_region_grow(v, (const int[][3]){{32, 12, 12}}, 1, 150, 250, 6, NULL, &m2));
    vt_ok(vv_filter_components(m1, 6, VV_U8, NULL, &l1, NULL, NULL));
    vt_ok(vv_filter_components(m2, 6, VV_U8, NULL, &l2, NULL, NULL));
    lab = l1;
    uint64_t n1 = 0, n2 = 0;
    for (size_t q = 0; q < 48 * 24 * 24; q++) {
        uint8_t *d = lab->data;
        n1 += d[q] == 1;
        if (((uint8_t *)l2->data)[q]) {
            d[q] = 2;
            n2++;
        }
    }
    vv_label_stats *s;
    int n;
    vt_ok(vv_measure_labels(lab, &s, &n));
    assert_int_equal(n, 2);
    assert_int_equal(s[0].label, 1);
    assert_int_equal(s[0].voxels, n1);
    assert_int_equal(s[1].voxels, n2);
    assert_near(s[0].volume, n1 * 0.5, 1e-9);
    assert_near(s[0].centroid.x, 7, 0.05);
    assert_near(s[1].centroid.x, 16, 0.05);
    assert_near(s[1].centroid.y, 12, 0.05);
    assert_int_equal(s[0].box_min[1], 8);
    assert_int_equal(s[0].box_max[1], 16);
    free(s);
    /* not a label volume */
    vv_volume *f;
    vt_ok(vv_filter_gaussian(v, (double[]){1, 1, 1}, NULL, &f));
    vt_err(vv_measure_labels(f, &s, &n));
    assert_non_null(strstr(vv_error_message(), "not a whole number"));
    vv_volume_free(f);

    /* the CLI: the same numbers */
    const char *path = vt_path(outdir(), "labels.nrrd");
    vt_ok(vv_volume_save(lab, path, VV_FORMAT_NRRD, 0));
    vt_run_result r = run_cli("measure", path, "--labels");
    assert_int_equal(r.status, 0);
    char line[128];
    snprintf(line, sizeof line, "       1 %10llu", (unsigned long long)n1);
    if (!strstr(r.out, line))
        fail_msg("expected \"%s\" in:\n%s", line, r.out);
    vt_run_result_free(&r);

    /* the ray caster, the ray tracer, splatting and the surface renderer:
     * both label colours, and no third one where they touch */
    const char *const renderers[] = {"raycast", "raytrace", "splat", "raster"};
    for (int ri = 0; ri < 4; ri++) {
        const char *png = vt_path(outdir(), "labels.png");
        r = run_cli("render", path, "-o", png, "--labels", "--size", "160x160", "--renderer",
                    renderers[ri], "-q");
        if (r.status != 0)
            fail_msg("render (%s): %s", renderers[ri], r.err);
        vt_run_result_free(&r);
        vv_image *im;
        vt_ok(vv_image_read_png(&im, png));
        vv_vec3 c1 = vv_label_color(1), c2 = vv_label_color(2);
        int lit = 0, near1 = 0, near2 = 0;
        for (int p = 0; p < im->width * im->height; p++) {
            const float *px = im->rgba + 4 * p;
            double sum = px[0] + px[1] + px[2];
            if (sum < 0.15)
                continue;
            lit++;
            /* chromaticity against each label's */
            double d1 = 0, d2 = 0, s1 = c1.x + c1.y + c1.z, s2 = c2.x + c2.y + c2.z;
            double pc[3] = {px[0] / sum, px[1] / sum, px[2] / sum};
            double l1c[3] = {c1.x / s1, c1.y / s1, c1.z / s1},
                   l2c[3] = {c2.x / s2, c2.y / s2, c2.z / s2};
            for (int k = 0; k < 3; k++) {
                d1 += (pc[k] - l1c[k]) * (pc[k] - l1c[k]);
                d2 += (pc[k] - l2c[k]) * (pc[k] - l2c[k]);
            }
            near1 += d1 < 0.01;
            near2 += d2 < 0.01;
        }
        print_message("labels render (%s): %d lit pixels, %d of label 1's colour, %d of label "
                      "2's\n",
                      renderers[ri], lit, near1, near2);
        assert_true(lit > 1000);
        assert_true(near1 > lit / 5 && near2 > lit / 5);
        assert_true(near1 + near2 > lit * 9 / 10);
        vv_image_free(im);
    }
    vv_volume_free(l2);
    vv_volume_free(m1);
    vv_volume_free(m2);
    vv_volume_free(lab);
    vv_volume_free(v);
}

/* "segmentation": "labels" in a scene, kept when saved. */
static void
test_scene_labels(void **state) {
    (void)state;
    vv_volume *v = spheres();
    const char *vol = vt_path(outdir(), "s.nrrd"), *scene = vt_path(outdir(), "s.json"),
               *saved = vt_path(outdir(), "saved.json");
    vt_ok(vv_volume_save(v, vol, VV_FORMAT_NRRD, 0));
    const char *text = "{\"objects\": [{\"file\": \"s.nrrd\", \"filters\": \"--threshold 50: "
                       "--components 6:u8\", \"segmentation\": \"labels\"}]}";
    vt_write_file(scene, text, strlen(text));
    vv_world *w, *w2;
    vt_ok(vv_scene_load(&w, scene));
    assert_int_equal(w->objects[0]->segmentation, VV_SEG_LABELS);
    assert_int_equal(w->objects[0]->volume->range[1], 1); /* touching: one component */
    vt_ok(vv_scene_save(w, saved, NULL));
    vt_ok(vv_scene_load(&w2, saved));
    assert_int_equal(w2->objects[0]->segmentation, VV_SEG_LABELS);
    vv_world_free(w);
    vv_world_free(w2);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_measure_labels),
        cmocka_unit_test(test_scene_labels),
    };
    return vt_run_tests(tests, NULL, NULL);
}
