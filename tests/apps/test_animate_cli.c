/*
 * volvis animate: an orbit of the real CT head equals still renders at the
 * interpolated azimuth (PNG frames bit for bit; decoded H.264 frames within
 * 35 dB PSNR), frame counts and rates of MP4 and WebM by ffprobe, help, and
 * one-line errors for bad animation files and outputs.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#define N 4
#define DEG 60.0

static const char *
outdir(void) {
    return vt_outdir("animate_cli");
}

#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})

static int
have_ffmpeg(void) {
    return system("command -v ffprobe >/dev/null 2>&1 && command -v ffmpeg >/dev/null 2>&1") == 0;
}

static void
expect_ok(vt_run_result *r) {
    if (r->status != 0)
        fail_msg("volvis failed (%d): %s", r->status, r->err);
}

/* The still `volvis render HEAD --azimuth DEG*k/N` at 96x96. */
static const char *
still(int k) {
    char az[64], name[64];
    snprintf(az, sizeof az, "%.17g", DEG * k / N);
    snprintf(name, sizeof name, "still_%d.png", k);
    const char *png = vt_path(outdir(), name);
    vt_run_result r = run_cli("render", vt_data("volumes/ct_head.nrrd"), "--size", "96x96", "--tf",
                              "100:1500", "--azimuth", az, "-q", "-o", png);
    expect_ok(&r);
    vt_run_result_free(&r);
    return png;
}

static void
test_orbit_png_equals_render(void **state) {
    (void)state;
    char pattern[1024];
    snprintf(pattern, sizeof pattern, "%s/orbit_%%02d.png", outdir());
    for (int k = 0; k < N; k++) {
        char name[64];
        snprintf(name, sizeof name, "orbit_%02d.png", k);
        unlink(vt_path(outdir(), name));
    }
    vt_run_result r = run_cli("animate", vt_data("volumes/ct_head.nrrd"), "--size", "96x96", "--tf",
                              "100:1500", "--orbit", "60", "--frames", "4", "-o", pattern);
    expect_ok(&r);
    assert_non_null(strstr(r.out, "4 frames"));
    vt_run_result_free(&r);
    for (int k = 0; k < N; k++) {
        char name[64];
        snprintf(name, sizeof name, "orbit_%02d.png", k);
        size_t s1, s2;
        unsigned char *a = vt_read_file(vt_path(outdir(), name), &s1);
        unsigned char *b = vt_read_file(still(k), &s2);
        if (s1 != s2 || memcmp(a, b, s1) != 0)
            fail_msg("frame %d differs from the still at azimuth %g", k, DEG * k / N);
        free(a);
        free(b);
    }
    /* run again: every frame is complete, nothing is rendered */
    r = run_cli("animate", vt_data("volumes/ct_head.nrrd"), "--size", "96x96", "--tf", "100:1500",
                "--orbit", "60", "--frames", "4", "-o", pattern);
    expect_ok(&r);
    assert_non_null(strstr(r.out, "0 rendered, 4 reused"));
    vt_run_result_free(&r);
}

static void
probe(const char *path, int *frames, double *fps) {
    char cmd[2048];
    snprintf(cmd, sizeof cmd,
             "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
             "stream=nb_read_frames,avg_frame_rate -of default=nw=1 '%s'",
             path);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char line[256];
    *frames = -1;
    *fps = -1;
    while (fgets(line, sizeof line, p)) {
        int a, b;
        if (sscanf(line, "nb_read_frames=%d", &a) == 1)
            *frames = a;
        if (sscanf(line, "avg_frame_rate=%d/%d", &a, &b) == 2 && b > 0)
            *fps = (double)a / b;
    }
    assert_int_equal(pclose(p), 0);
}

static void
test_orbit_mp4_psnr_and_webm(void **state) {
    (void)state;
    if (!have_ffmpeg()) {
        print_message("skipped: ffprobe/ffmpeg not found (scripts/install-deps.sh test)\n");
        return;
    }
    const char *mp4 = vt_path(outdir(), "orbit.mp4");
    vt_run_result r =
        run_cli("animate", vt_data("volumes/ct_head.nrrd"), "--size", "96x96", "--tf", "100:1500",
                "--orbit", "60", "--frames", "4", "--fps", "24", "--no-resume", "-o", mp4);
    expect_ok(&r);
    vt_run_result_free(&r);
    int n;
    double fps;
    probe(mp4, &n, &fps);
    assert_int_equal(n, N);
    assert_near(fps, 24, 1e-9);
    /* decode every frame with ffmpeg to PNG and compare with the stills */
    char cmd[2048], pattern[1024];
    snprintf(pattern, sizeof pattern, "%s/decoded_%%d.png", outdir());
    snprintf(cmd, sizeof cmd, "ffmpeg -v error -y -i '%s' -start_number 0 '%s'", mp4, pattern);
    assert_int_equal(system(cmd), 0);
    for (int k = 0; k < N; k++) {
        char name[64];
        snprintf(name, sizeof name, "decoded_%d.png", k);
        vv_image *a, *b;
        vt_ok(vv_image_read_png(&a, vt_path(outdir(), name)));
        vt_ok(vv_image_read_png(&b, still(k)));
        double psnr = vv_image_psnr(a, b);
        print_message("frame %d: %.1f dB\n", k, psnr);
        assert_true(psnr >= 35);
        vv_image_free(a);
        vv_image_free(b);
    }
    const char *webm = vt_path(outdir(), "orbit.webm");
    r = run_cli("animate", vt_data("volumes/ct_head.nrrd"), "--size", "64x64", "--orbit", "90",
                "--frames", "5", "--fps", "10", "--no-resume", "-q", "-o", webm);
    expect_ok(&r);
    vt_run_result_free(&r);
    probe(webm, &n, &fps);
    assert_int_equal(n, 5);
    assert_near(fps, 10, 1e-9);
}

static void
expect_fail(vt_run_result *r, int status, const char *needle) {
    if (r->status != status || !strstr(r->err, needle))
        fail_msg("expected status %d and '%s', got %d: %s", status, needle, r->status, r->err);
    /* one line */
    const char *nl = strchr(r->err, '\n');
    assert_true(nl && nl[1] == '\0');
}

static void
test_errors_and_help(void **state) {
    (void)state;
    vt_run_result r = run_cli("animate", "--help");
    expect_ok(&r);
    assert_non_null(strstr(r.out, "--orbit DEG"));
    assert_non_null(strstr(r.out, "--azimuth"));
    vt_run_result_free(&r);
    r = run_cli("animate", vt_data("volumes/neghip.slc"), "-o", "x.mp4");
    expect_fail(&r, 2, "nothing to animate");
    vt_run_result_free(&r);
    const char *bad = vt_path(outdir(), "bad.json");
    const char *text = "{\"tracks\": [{\"property\": \"view.eye\", \"keys\": [\n"
                       "  {\"time\": 1, \"value\": [0, 0, 0]},\n"
                       "  {\"time\": 0.5, \"value\": [0, 1, 0]}]}]}\n";
    vt_write_file(bad, text, strlen(text));
    r = run_cli("animate", vt_data("volumes/neghip.slc"), "--animation", bad, "-o", "x.mp4");
    expect_fail(&r, 1, ":3:");
    assert_non_null(strstr(r.err, "tracks[0].keys[1].time"));
    vt_run_result_free(&r);
    r = run_cli("animate", vt_data("volumes/neghip.slc"), "--orbit", "90", "--frames", "2", "-o",
                "/nonexistent-dir/movie.mp4");
    expect_fail(&r, 1, "nonexistent-dir");
    vt_run_result_free(&r);
    r = run_cli("animate", vt_data("volumes/neghip.slc"), "--rotate-object", "nobody:z:90", "-o",
                outdir());
    expect_fail(&r, 1, "nobody");
    vt_run_result_free(&r);
    /* a keyframed animation file with its scene beside it */
    const char *anim = vt_path(outdir(), "zoom.json");
    const char *atext = "{\"fps\": 10, \"tracks\": [{\"property\": \"view.fov\", \"keys\": [\n"
                        "  {\"time\": 0, \"value\": 30}, {\"time\": 0.2, \"value\": 20}]}]}\n";
    vt_write_file(anim, atext, strlen(atext));
    const char *dir = vt_path(outdir(), "zoom_frames");
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
    assert_int_equal(system(cmd), 0);
    r = run_cli("animate", vt_data("volumes/neghip.slc"), "--animation", anim, "--size", "32x32",
                "-o", dir);
    expect_ok(&r);
    assert_non_null(strstr(r.out, "3 frames"));
    vt_run_result_free(&r);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orbit_png_equals_render),
        cmocka_unit_test(test_orbit_mp4_psnr_and_webm),
        cmocka_unit_test(test_errors_and_help),
    };
    return vt_run_tests(tests, NULL, NULL);
}
