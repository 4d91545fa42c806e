/*
 * `volvis filter` (apps/volvis/cmd_filter.c) as a user runs it, and the
 * real-data check of the issue: the CT head's largest bone component
 * excludes the head holder ("table") under it, by its bounding box; a PNG
 * of it is rendered into build/.../test-out/filter_cli to look at.
 */
#include "testutil.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define outdir() vt_outdir("filter_cli")
#define out_file(name) vt_path(outdir(), name)
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})

#define assert_contains(hay, needle)                                                               \
    do {                                                                                           \
        if (!strstr((hay), (needle)))                                                              \
            fail_msg("expected \"%s\" in output:\n%s", (needle), (hay));                           \
    } while (0)

static const char *
small_volume(void) {
    const char *p = out_file("small.nrrd");
    vv_volume *v;
    vt_ok(vv_volume_new(&v, (int[]){20, 18, 16}, VV_I16));
    v->spacing[2] = 2;
    for (int k = 0; k < 16; k++)
        for (int j = 0; j < 18; j++)
            for (int i = 0; i < 20; i++) {
                double a = (i - 6) * (i - 6) + (j - 9) * (j - 9) + (k - 8) * (k - 8);
                double b = (i - 15) * (i - 15) + (j - 9) * (j - 9) + (k - 8) * (k - 8);
                vv_volume_set(v, i, j, k, a < 16 ? 500 : b < 4 ? 400 : (i * 7 + j * 3) % 50);
            }
    vv_volume_update_range(v);
    vt_ok(vv_volume_save(v, p, VV_FORMAT_NRRD, 0));
    vv_volume_free(v);
    return p;
}

static void
test_help_lists_every_filter(void **state) {
    (void)state;
    vt_run_result r = run_cli("filter", "--help");
    assert_int_equal(r.status, 0);
    for (int i = 0; i < vv_filter_info_count(); i++) {
        char opt[64];
        snprintf(opt, sizeof opt, "--%s %s", vv_filter_info_get(i)->name,
                 vv_filter_info_get(i)->metavar);
        assert_contains(r.out, opt);
    }
    assert_contains(r.out, "world units");
    vt_run_result_free(&r);
    r = run_cli("--help");
    assert_contains(r.out, "filter");
    vt_run_result_free(&r);
}

static void
test_order_and_output(void **state) {
    (void)state;
    const char *in = small_volume(), *out = out_file("f.nrrd");
    /* threshold, then the largest component: the big sphere alone */
    vt_run_result r =
        run_cli("filter", in, out, "--threshold", "300:", "--largest", "1", "--threads", "2");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_contains(r.out, "--threshold 300: --largest 1");
    vt_run_result_free(&r);
    vv_volume *v;
    vt_ok(vv_volume_load(&v, out, NULL));
    assert_int_equal(v->type, VV_U8);
    assert_int_equal(vv_volume_get(v, 6, 9, 8), 1);
    assert_int_equal(vv_volume_get(v, 15, 9, 8), 0);
    assert_near(v->spacing[2], 2, 1e-12);
    vv_volume_free(v);
    /* the other order gives something else: smoothing after the mask is f32 */
    r = run_cli("filter", in, out, "--threshold", "300:", "--gaussian", "1v", "-q");
    assert_int_equal(r.status, 0);
    assert_string_equal(r.out, "");
    vt_run_result_free(&r);
    vt_ok(vv_volume_load(&v, out, NULL));
    assert_int_equal(v->type, VV_F32);
    assert_true(v->range[1] < 1.0 && v->range[1] > 0.5);
    vv_volume_free(v);
    /* labels: two spheres in raster order of their first voxel */
    r = run_cli("filter", in, out, "--threshold", "300:", "--components", "26:u8", "-q");
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    vt_ok(vv_volume_load(&v, out, NULL));
    assert_int_equal(v->type, VV_U8);
    assert_int_equal(vv_volume_get(v, 6, 9, 8), 1);
    assert_int_equal(vv_volume_get(v, 15, 9, 8), 2);
    vv_volume_free(v);
}

static int
count_tmp(void) {
    DIR *d = opendir(outdir());
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        n += strstr(e->d_name, ".tmp-") != NULL;
    if (d)
        closedir(d);
    return n;
}

static void
test_bad_usage(void **state) {
    (void)state;
    const char *in = small_volume(), *out = out_file("keep.nrrd");
    vt_write_file(out, "previous", 8);
    static const char *const bad[][3] = {
        {"--gaussian", "0", NULL},      {"--gaussian", "-1", NULL},  {"--median", "x", NULL},
        {"--threshold", "1:2:3", NULL}, {"--resample", "1x1", NULL}, {"--components", "5", NULL},
        {"--grow", "1,2,3:5", NULL},    {"--cast", "u7", NULL},      {"--flip", "w", NULL},
        {"--permute", "xxy", NULL},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        vt_run_result r = run_cli("filter", in, out, bad[i][0], bad[i][1]);
        if (r.status != 2)
            fail_msg("%s %s: exit %d, expected 2: %s", bad[i][0], bad[i][1], r.status, r.err);
        assert_contains(r.err, bad[i][0]);
        /* one line */
        assert_ptr_equal(strchr(r.err, '\n'), r.err + strlen(r.err) - 1);
        vt_run_result_free(&r);
    }
    vt_run_result r = run_cli("filter", in, out);
    assert_int_equal(r.status, 2);
    assert_contains(r.err, "no filter");
    vt_run_result_free(&r);
    /* failures after loading: a seed outside, a crop box outside; OUT is untouched */
    r = run_cli("filter", in, out, "--grow", "30,0,0:0:100");
    assert_int_equal(r.status, 1);
    assert_contains(r.err, "outside the volume");
    vt_run_result_free(&r);
    r = run_cli("filter", in, out, "--median", "1", "--crop", "0,0,0:20,5,5");
    assert_int_equal(r.status, 1);
    assert_contains(r.err, "step 2 (--crop 0,0,0:20,5,5)");
    vt_run_result_free(&r);
    size_t n;
    unsigned char *keep = vt_read_file(out, &n);
    assert_int_equal(n, 8);
    assert_memory_equal(keep, "previous", 8);
    free(keep);
    assert_int_equal(count_tmp(), 0);
}

/* The CT head: thresholded at 300 HU, the bone and the two halves of the
 * head holder under it are separate components; the largest is the skull. */
static void
test_ct_head_largest_bone(void **state) {
    (void)state;
    const char *ct = vt_data("volumes/ct_head.nrrd");
    if (access(ct, R_OK) != 0)
        vt_skip("%s is missing", ct);
    vv_volume *v;
    vt_ok(vv_volume_load(&v, ct, NULL));
    vv_filter_options o;
    vv_filter_options_init(&o);
    o.threads = 2;
    vv_volume *mask, *bone;
    vt_ok(vv_filter_threshold(v, 300, INFINITY, &o, &mask));
    vt_ok(vv_filter_largest(mask, 1, 26, &o, &bone));
    int lo[2][3], hi[2][3];
    const vv_volume *m[2] = {mask, bone};
    uint64_t count[2] = {0, 0};
    for (int q = 0; q < 2; q++) {
        for (int a = 0; a < 3; a++) {
            lo[q][a] = 1 << 30;
            hi[q][a] = -1;
        }
        const uint8_t *d = m[q]->data;
        for (int k = 0; k < v->dims[2]; k++)
            for (int j = 0; j < v->dims[1]; j++)
                for (int i = 0; i < v->dims[0]; i++)
                    if (d[((size_t)k * v->dims[1] + j) * v->dims[0] + i]) {
                        int p[3] = {i, j, k};
                        count[q]++;
                        for (int a = 0; a < 3; a++) {
                            lo[q][a] = p[a] < lo[q][a] ? p[a] : lo[q][a];
                            hi[q][a] = p[a] > hi[q][a] ? p[a] : hi[q][a];
                        }
                    }
        print_message("%s: %llu voxels, box x %d..%d y %d..%d z %d..%d\n",
                      q ? "largest" : "threshold", (unsigned long long)count[q], lo[q][0], hi[q][0],
                      lo[q][1], hi[q][1], lo[q][2], hi[q][2]);
    }
    /* the holder reaches the first rows (y = 0) and wide in x; the skull does not */
    assert_int_equal(lo[0][1], 0);
    assert_true(lo[0][0] < 30 && hi[0][0] > 225);
    assert_true(lo[1][1] >= 12);
    assert_true(lo[1][0] >= 45 && hi[1][0] <= 215);
    assert_true(count[1] > 300000 && count[1] < count[0] - 30000);
    /* the same through the CLI, rendered to look at */
    vt_run_result r = run_cli("filter", ct, out_file("bone.nrrd"), "--threshold",
                              "300:", "--largest", "1:26", "-q");
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    vv_volume *cli;
    vt_ok(vv_volume_load(&cli, out_file("bone.nrrd"), NULL));
    assert_memory_equal(cli->data, bone->data, (size_t)vv_volume_voxel_count(v));
    vv_volume_free(cli);
    r = run_cli("render", out_file("bone.nrrd"), "-o", out_file("bone.png"), "--mode", "iso",
                "--iso", "0.5", "--size", "256x256", "--azimuth", "90", "-q");
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    vv_volume_free(mask);
    vv_volume_free(bone);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_help_lists_every_filter),
        cmocka_unit_test(test_order_and_output),
        cmocka_unit_test(test_bad_usage),
        cmocka_unit_test(test_ct_head_largest_bone),
    };
    return vt_run_tests(tests, NULL, NULL);
}
