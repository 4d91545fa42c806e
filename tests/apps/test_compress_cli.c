/*
 * Tests of `volvis compress`, `volvis decompress`, `volvis info` on a .vvc
 * and `volvis render --renderer fourier --ortho` (apps/volvis/cmd_compress.c,
 * cmd_info.c, cmd_render.c), run as a separate process like a user would.
 */
#include "testutil.h"

#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

typedef vt_run_result run_result;

/* Captured output and files of these tests go to build/.../test-out/compress_cli. */
#define outdir() vt_outdir("compress_cli")
#define out_file(name) vt_path(outdir(), name)
#define free_result vt_run_result_free
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})

#define assert_contains(hay, needle)                                                               \
    do {                                                                                           \
        if (!strstr((hay), (needle)))                                                              \
            fail_msg("expected \"%s\" in output:\n%s", (needle), (hay));                           \
    } while (0)

static void
test_compress_decompress_info(void **state) {
    (void)state;
    const char *in = vt_data("volumes/neghip.slc");
    const char *vvc = out_file("neghip.vvc"), *nrrd = out_file("neghip.nrrd");
    unlink(vvc);
    run_result r = run_cli("compress", in, vvc, "--quality", "100", "--check");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_contains(r.out, "wrote ");
    assert_contains(r.out, "PSNR inf dB");
    assert_contains(r.out, "maximum error 0");
    free_result(&r);

    r = run_cli("info", vvc);
    assert_int_equal(r.status, 0);
    assert_contains(r.out, "format:       vvc");
    assert_contains(r.out, "compressed:");
    assert_contains(r.out, "bits per voxel");
    assert_contains(r.out, "ratio");
    assert_contains(r.out, "dimensions:   66 x 66 x 66");
    free_result(&r);

    r = run_cli("decompress", vvc, nrrd);
    assert_int_equal(r.status, 0);
    free_result(&r);
    vv_volume *a = NULL, *b = NULL;
    vt_ok(vv_volume_load(&a, in, NULL));
    vt_ok(vv_volume_load(&b, nrrd, NULL));
    assert_memory_equal(a->data, b->data, (size_t)vv_volume_voxel_count(a));
    vv_volume_free(a);
    vv_volume_free(b);

    /* a rate target */
    r = run_cli("compress", in, vvc, "--rate", "1", "--block", "8", "-q");
    assert_int_equal(r.status, 0);
    assert_true(r.out[0] == '\0');
    free_result(&r);
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_load(&c, vvc));
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    assert_true(info.bits_per_voxel <= 1 && info.block == 8);
    vv_vvc_free(c);

    /* an error bound, shown by info; the legacy format on request */
    r = run_cli("compress", in, vvc, "--max-error", "3", "--check");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_contains(r.out, "error bound 3 on every voxel");
    assert_contains(r.out, "maximum error 3");
    free_result(&r);
    r = run_cli("info", vvc);
    assert_int_equal(r.status, 0);
    assert_contains(r.out, "version 2");
    assert_contains(r.out, "error bound:  3 on every voxel");
    free_result(&r);
    const char *v1 = out_file("neghip_v1.vvc");
    r = run_cli("compress", in, v1, "--quality", "60", "--format", "1", "-q");
    assert_int_equal(r.status, 0);
    free_result(&r);
    r = run_cli("info", v1);
    assert_int_equal(r.status, 0);
    assert_contains(r.out, "version 1");
    free_result(&r);

    /* render straight from it, parallel view */
    const char *png = out_file("fourier.png");
    char set[1300];
    snprintf(set, sizeof set, "vvc=%s", vvc);
    r = run_cli("render", in, "--renderer", "fourier", "--ortho", "--set", set, "--size", "64x64",
                "--mode", "xray", "-o", png);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    free_result(&r);
    vv_image *img = NULL;
    vt_ok(vv_image_read_png(&img, png));
    assert_int_equal(img->width, 64);
    vv_image_free(img);
    /* an X-ray in a perspective view is refused with one line */
    r = run_cli("render", in, "--renderer", "fourier", "--mode", "xray", "-o", out_file("no.png"));
    assert_int_equal(r.status, 1);
    assert_contains(r.err, "perspective");
    free_result(&r);
    /* other modes (here the default, composite) go to the ray caster on the decoded volume */
    r = run_cli("render", in, "--renderer", "fourier", "--set", set, "--size", "48x48", "-o",
                out_file("composite_from_vvc.png"));
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    free_result(&r);
}

static void
test_errors(void **state) {
    (void)state;
    const char *in = vt_data("volumes/neghip.slc");
    run_result r = run_cli("compress", in, out_file("x.vvc"));
    assert_int_equal(r.status, 2); /* neither --quality nor --rate */
    free_result(&r);
    r = run_cli("compress", in, out_file("x.vvc"), "--quality", "50", "--rate", "1");
    assert_int_equal(r.status, 2);
    free_result(&r);
    r = run_cli("compress", in, out_file("x.vvc"), "--quality", "50", "--block", "12");
    assert_int_equal(r.status, 2);
    free_result(&r);
    /* bad rates and bounds: one line, usage exit */
    const char *bad_values[][2] = {
        {"--rate", "0"},       {"--rate", "-1"},       {"--rate", "nan"},      {"--max-error", "0"},
        {"--max-error", "-2"}, {"--max-error", "nan"}, {"--max-error", "inf"}, {"--format", "3"}};
    for (int i = 0; i < 8; i++) {
        r = run_cli("compress", in, out_file("x.vvc"), bad_values[i][0], bad_values[i][1]);
        if (r.status != 2)
            fail_msg("%s %s: exit %d", bad_values[i][0], bad_values[i][1], r.status);
        assert_true(r.err[0] != '\0');
        free_result(&r);
    }
    r = run_cli("compress", in, out_file("x.vvc"), "--max-error", "1", "--format", "1");
    assert_int_equal(r.status, 2);
    free_result(&r);
    /* a corrupt file: exit 1, one line, nothing written */
    const char *vvc = out_file("c.vvc"), *bad = out_file("bad.vvc"), *o = out_file("bad.nrrd");
    r = run_cli("compress", in, vvc, "--quality", "60", "-q");
    assert_int_equal(r.status, 0);
    free_result(&r);
    size_t n;
    unsigned char *bytes = vt_read_file(vvc, &n);
    bytes[n / 2] ^= 0x10;
    vt_write_file(bad, bytes, n);
    free(bytes);
    unlink(o);
    r = run_cli("decompress", bad, o);
    assert_int_equal(r.status, 1);
    assert_contains(r.err, "CRC-32");
    assert_true(strchr(r.err, '\n') == r.err + strlen(r.err) - 1);
    free_result(&r);
    struct stat st;
    assert_true(stat(o, &st) != 0);
    r = run_cli("info", bad);
    assert_int_equal(r.status, 1);
    free_result(&r);
    r = run_cli("decompress", vvc, out_file("x.unknown"));
    assert_int_equal(r.status, 2);
    free_result(&r);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compress_decompress_info),
        cmocka_unit_test(test_errors),
    };
    return vt_run_tests(tests, NULL, NULL);
}
