/*
 * Tests of the `volvis` command-line tool, run as a separate process
 * (posix_spawn) with stdout and stderr captured to files. The executable is
 * $VV_CLI (set by CTest), output goes under $VV_TEST_OUT/cli.
 */
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

typedef vt_run_result run_result;

/* Captured output and files of these tests go to build/.../test-out/cli. */
#define outdir() vt_outdir("cli")
#define out_file(name) vt_path(outdir(), name)
#define free_result vt_run_result_free
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})

static int
file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static int
count_char(const char *s, char c) {
    int n = 0;
    for (; *s; s++)
        n += *s == c;
    return n;
}

/* Exactly one line on stderr, starting "volvis:". */
static void
assert_one_error_line(const run_result *r) {
    if (strncmp(r->err, "volvis:", 7) != 0 || count_char(r->err, '\n') != 1 ||
        r->err[strlen(r->err) - 1] != '\n')
        fail_msg("expected one 'volvis:' line on stderr, got: [%s]", r->err);
}

#define assert_contains(hay, needle)                                                               \
    do {                                                                                           \
        if (!strstr((hay), (needle)))                                                              \
            fail_msg("expected \"%s\" in output:\n%s", (needle), (hay));                           \
    } while (0)

/* ---- help and version ----------------------------------------------------- */

static void
test_help(void **state) {
    (void)state;
    static const struct {
        const char *cmd;
        const char *mentions[8];
    } cases[] = {
        {"info", {"usage: volvis info", "--raw", "--bins", NULL}},
        {"render",
         {"usage: volvis render", "--mode", "--iso", "--tf", "--size", "--azimuth", "--renderer",
          NULL}},
        {"convert", {"usage: volvis convert", "--format", "--strict", "--raw", NULL}},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        run_result r = run_cli(cases[i].cmd, "--help");
        assert_int_equal(r.status, 0);
        assert_string_equal(r.err, "");
        for (int k = 0; cases[i].mentions[k]; k++)
            assert_contains(r.out, cases[i].mentions[k]);
        run_result h = run_cli("help", cases[i].cmd);
        assert_int_equal(h.status, 0);
        assert_string_equal(h.out, r.out);
        free_result(&h);
        /* --help wins over other problems on the line */
        h = run_cli(cases[i].cmd, "--bogus", "-h");
        assert_int_equal(h.status, 0);
        assert_string_equal(h.out, r.out);
        free_result(&h);
        free_result(&r);
    }
    {
        run_result r = run_cli("render", "--help");
        assert_contains(r.out, "--step");
        assert_contains(r.out, "--gamma");
        assert_contains(r.out, "--quiet");
        assert_contains(r.out, "--threads");
        assert_contains(r.out, "--zoom");
        assert_contains(r.out, "--elevation");
        /* the renderer registry is listed, with every option of every
         * renderer's table and its default */
        assert_true(vv_renderer_count() > 0);
        for (int i = 0; i < vv_renderer_count(); i++) {
            const vv_renderer_info *in = vv_renderer_info_at(i);
            assert_contains(r.out, in->name);
            for (int k = 0; k < in->n_options; k++) {
                char opt[160];
                snprintf(opt, sizeof opt, "--set %s=", in->options[k].key);
                assert_contains(r.out, opt);
            }
        }
        free_result(&r);
    }
    const char *globals[] = {"--help", "help", "-h"};
    for (int i = 0; i < 3; i++) {
        run_result r = run_cli(globals[i]);
        assert_int_equal(r.status, 0);
        assert_string_equal(r.err, "");
        assert_contains(r.out, "info");
        assert_contains(r.out, "render");
        assert_contains(r.out, "convert");
        free_result(&r);
    }
    run_result r = run_cli("--version");
    assert_int_equal(r.status, 0);
    assert_true(strncmp(r.out, "volvis ", 7) == 0);
    assert_contains(r.out, vv_version());
    free_result(&r);
}

/* ---- usage errors ---------------------------------------------------------- */

static void
test_usage_errors(void **state) {
    (void)state;
    const char *nut = vt_data("volumes/nut.slc");
    const char *neghip = vt_data("volumes/neghip.slc");
    const char *png = out_file("usage.png");
    unlink(png);
    const char *const cases[][12] = {
        {"frobnicate", NULL},
        {"--frobnicate", NULL},
        {"info", NULL},
        {"info", "--bogus", nut, NULL},
        {"info", nut, nut, NULL},
        {"info", "--bins", "0", nut, NULL},
        {"info", "--raw", "4x4:u8", nut, NULL},
        {"info", "--raw", "4x4x4:q12", nut, NULL},
        {"info", "--raw", "4x4x4:u8:sideways", nut, NULL},
        {"info", "--raw", "4x4x4:u8:1x0x1", nut, NULL},
        {"render", neghip, NULL},
        {"render", "-o", png, NULL},
        {"render", neghip, "-o", png, "--size", "5x", NULL},
        {"render", neghip, "-o", png, "--size", "0x10", NULL},
        {"render", neghip, "-o", png, "--size", "40000x10", NULL},
        {"render", neghip, "-o", png, "--size", "64x48x", NULL},
        {"render", neghip, "-o", png, "--size=", NULL},
        {"render", neghip, "-o", png, "--zoom", "nan", NULL},
        {"render", neghip, "-o", png, "--zoom", "0", NULL},
        {"render", neghip, "-o", png, "--azimuth", "inf", NULL},
        {"render", neghip, "-o", png, "--azimuth", "", NULL},
        {"render", neghip, "-o", png, "--threads", "2.5", NULL},
        {"render", neghip, "-o", png, "--mode", "foo", NULL},
        {"render", neghip, "-o", png, "--tf", "5:1", NULL},
        {"render", neghip, "-o", png, "--tf", "5", NULL},
        {"render", neghip, "-o", png, "--iso", "1e999", NULL},
        {"render", neghip, "-o", png, "--renderer", "nosuch", NULL},
        {"render", neghip, "-o", png, "--quality=7", NULL},
        {"render", neghip, "-o", png, "--quiet=1", NULL},
        {"render", neghip, "-o", png, "--set", "novalue", NULL},
        {"render", neghip, "-o", png, "--size", NULL},
        {"convert", nut, NULL},
        {"convert", nut, out_file("x.foo"), NULL},
        {"convert", "--format", "dicom", nut, out_file("x.dcm"), NULL},
        {"convert", "--codec", "lzw", nut, out_file("x.nrrd"), NULL},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        run_result r = vt_run_cli_v(outdir(), cases[i]);
        if (r.status != 2)
            fail_msg("case %zu (%s %s ...): exit %d, want 2; stderr: %s", i, cases[i][0],
                     cases[i][1] ? cases[i][1] : "", r.status, r.err);
        assert_one_error_line(&r);
        assert_string_equal(r.out, "");
        free_result(&r);
    }
    assert_false(file_exists(png));

    /* no command at all */
    run_result r = vt_run_cli_v(outdir(), (const char *const[]){NULL});
    assert_int_equal(r.status, 2);
    assert_one_error_line(&r);
    free_result(&r);

    /* the message says what was wrong */
    r = run_cli("render", neghip, "-o", png, "--size", "5x");
    assert_contains(r.err, "5x");
    free_result(&r);
    r = run_cli("render", neghip, "-o", png, "--mode", "foo");
    assert_contains(r.err, "foo");
    free_result(&r);
    r = run_cli("info", "--bogus", nut);
    assert_contains(r.err, "--bogus");
    free_result(&r);
}

/* ---- missing and bad files --------------------------------------------------- */

static void
test_missing_file(void **state) {
    (void)state;
    const char *missing = out_file("no-such-volume.slc");
    const char *png = out_file("missing.png");
    unlink(missing);
    unlink(png);
    const char *const cases[][8] = {
        {"info", missing, NULL},
        {"render", missing, "-o", png, NULL},
        {"convert", missing, out_file("missing.nrrd"), NULL},
        {"info", "--raw", "4x4x4:u8", missing, NULL},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        run_result r = vt_run_cli_v(outdir(), cases[i]);
        assert_int_equal(r.status, 1);
        assert_one_error_line(&r);
        assert_contains(r.err, "no-such-volume.slc");
        assert_string_equal(r.out, "");
        free_result(&r);
    }
    assert_false(file_exists(png));
    assert_false(file_exists(out_file("missing.nrrd")));

    /* a file that is no volume */
    const char *bad = out_file("garbage.slc");
    static const char bad_text[] = "this is not a volume\n";
    vt_write_file(bad, bad_text, strlen(bad_text));
    run_result r = run_cli("info", bad);
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_contains(r.err, "garbage.slc");
    free_result(&r);
}

/* ---- info ---------------------------------------------------------------------- */

static void
test_info_nut(void **state) {
    (void)state;
    run_result r = run_cli("info", vt_data("volumes/nut.slc"));
    assert_int_equal(r.status, 0);
    assert_string_equal(r.err, "");
    assert_contains(r.out, "format:       slc");
    assert_contains(r.out, "dimensions:   68 x 41 x 59 (164492 voxels)");
    assert_contains(r.out, "voxel type:   u8");
    assert_contains(r.out, "spacing:      1 x 1 x 1");
    assert_contains(r.out, "data origin:  fuzzy voxelized");
    assert_contains(r.out, "range:");
    assert_contains(r.out, "mean:");
    assert_contains(r.out, "percentiles:  1%:");
    assert_contains(r.out, "99%:");
    assert_contains(r.out, "histogram:");

    /* the range agrees with the library's own */
    vv_volume *v;
    vt_ok(vv_volume_load(&v, vt_data("volumes/nut.slc"), NULL));
    char want[128];
    snprintf(want, sizeof want, "range:        %g .. %g\n", v->range[0], v->range[1]);
    assert_contains(r.out, want);
    vv_volume_free(v);
    free_result(&r);

    /* a CT with negative values and anisotropic voxel spacing */
    r = run_cli("info", "--bins", "8", vt_data("volumes/ct_head.nrrd"));
    assert_int_equal(r.status, 0);
    assert_contains(r.out, "256 x 256 x 108");
    assert_contains(r.out, "i16");
    assert_contains(r.out, "8 bins");
    free_result(&r);
}

/* Writes a 4x3x2 u16 volume, value 100 * linear index, big-endian, after @p skip junk bytes. */
static void
write_raw_u16(const char *path, int skip) {
    unsigned char buf[64 + 48];
    memset(buf, 0xAB, sizeof buf);
    for (int i = 0; i < 24; i++) {
        unsigned v = 100u * (unsigned)i;
        buf[skip + 2 * i] = (unsigned char)(v >> 8);
        buf[skip + 2 * i + 1] = (unsigned char)(v & 0xff);
    }
    vt_write_file(path, buf, (size_t)skip + 48);
}

static void
test_info_raw(void **state) {
    (void)state;
    const char *raw = out_file("ramp.raw");
    write_raw_u16(raw, 0);
    run_result r = run_cli("info", "--raw", "4x3x2:u16:be:0.5x1x2", raw);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_contains(r.out, "format:       raw");
    assert_contains(r.out, "dimensions:   4 x 3 x 2 (24 voxels)");
    assert_contains(r.out, "voxel type:   u16");
    assert_contains(r.out, "spacing:      0.5 x 1 x 2");
    assert_contains(r.out, "range:        0 .. 2300\n");
    assert_contains(r.out, "mean:         1150 ");
    /* exact percentiles of the 24 values 0, 100, ..., 2300 */
    assert_contains(r.out, "percentiles:  1%: 0  5%: 100  50%: 1100  95%: 2200  99%: 2300\n");
    free_result(&r);

    /* four histogram bins of six values each */
    r = run_cli("info", "--bins", "4", "--raw", "4x3x2:u16:be", raw);
    assert_int_equal(r.status, 0);
    int quarters = 0;
    for (const char *p = r.out; (p = strstr(p, " 6  25.00% ")); p++)
        quarters++;
    if (quarters != 4)
        fail_msg("expected 4 bins of 6 voxels:\n%s", r.out);
    free_result(&r);

    /* --raw=... form, a header to skip, the options in another order */
    const char *skipped = out_file("ramp-skip.raw");
    write_raw_u16(skipped, 16);
    r = run_cli("info", skipped, "--raw=4x3x2:u16:skip=16:be");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_contains(r.out, "range:        0 .. 2300\n");
    free_result(&r);

    /* little-endian reading of the same bytes gives other values */
    r = run_cli("info", "--raw", "4x3x2:u16:le", raw);
    assert_int_equal(r.status, 0);
    assert_true(strstr(r.out, "range:        0 .. 2300\n") == NULL);
    free_result(&r);

    /* a file too small for the dimensions */
    r = run_cli("info", "--raw", "4x3x3:u16", raw);
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_contains(r.err, "ramp.raw");
    free_result(&r);
}

/* ---- render ---------------------------------------------------------------------- */

static unsigned
be32(const unsigned char *p) {
    return (unsigned)p[0] << 24 | (unsigned)p[1] << 16 | (unsigned)p[2] << 8 | p[3];
}

/* Checks the PNG signature and IHDR size, and that the image is not blank. */
static void
check_png(const char *path, int w, int h) {
    size_t n;
    unsigned char *b = vt_read_file(path, &n);
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    assert_true(n > 33);
    assert_memory_equal(b, sig, 8);
    assert_memory_equal(b + 12, "IHDR", 4);
    assert_int_equal(be32(b + 16), (unsigned)w);
    assert_int_equal(be32(b + 20), (unsigned)h);
    free(b);

    vv_image *img;
    vt_ok(vv_image_read_png(&img, path));
    assert_int_equal(img->width, w);
    assert_int_equal(img->height, h);
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < w * h; i++)
        for (int c = 0; c < 3; c++) {
            float v = img->rgba[4 * i + c];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    vv_image_free(img);
    if (!(hi - lo > 0.05f))
        fail_msg("%s looks blank: values %g..%g", path, lo, hi);
}

/* ---- options that must take effect ------------------------------------------------ */

#define BLOB_N 32

/* A 32^3 u8 raw volume: a ball of radius 7 voxels centred off the middle
 * in x, y and z, bright at its centre and falling off linearly (255 - 25 r). */
static const char *
write_blob(void) {
    static unsigned char v[BLOB_N * BLOB_N * BLOB_N];
    const double c[3] = {22, 20, 19};
    for (int k = 0; k < BLOB_N; k++)
        for (int j = 0; j < BLOB_N; j++)
            for (int i = 0; i < BLOB_N; i++) {
                double r = sqrt((i - c[0]) * (i - c[0]) + (j - c[1]) * (j - c[1]) +
                                (k - c[2]) * (k - c[2]));
                v[(k * BLOB_N + j) * BLOB_N + i] = (unsigned char)(r < 7 ? 255 - 25 * r : 0);
            }
    const char *path = out_file("blob.raw");
    vt_write_file(path, v, sizeof v);
    return path;
}

/* Renders @p in (raw blob when @p raw) at 64x64 with the extra arguments
 * (NULL-terminated) and returns the image read back from the PNG. */
static vv_image *
render_with(const char *in, int raw, const char *name, const char *const *extra) {
    const char *args[32];
    int n = 0;
    const char *png = out_file(name);
    args[n++] = "render";
    if (raw) {
        args[n++] = "--raw";
        args[n++] = "32x32x32:u8";
    }
    args[n++] = in;
    args[n++] = "-o";
    args[n++] = png;
    args[n++] = "--size";
    args[n++] = "64x64";
    for (int i = 0; extra[i] && n < 31; i++)
        args[n++] = extra[i];
    args[n] = NULL;
    run_result r = vt_run_cli_v(outdir(), args);
    if (r.status != 0)
        fail_msg("render %s: exit %d: %s", name, r.status, r.err);
    free_result(&r);
    vv_image *img = NULL;
    vt_ok(vv_image_read_png(&img, png));
    return img;
}

static double
luminance(const vv_image *im, int i) {
    return (im->rgba[4 * i] + im->rgba[4 * i + 1] + im->rgba[4 * i + 2]) / 3.0;
}

/* The intensity centroid (pixels) and the silhouette (pixels brighter
 * than 0.02): its area and its bounding box's width and height. */
static void
image_shape(const vv_image *im, double c[2], int *area, int *w, int *h) {
    double s = 0, sx = 0, sy = 0;
    int x0 = im->width, x1 = -1, y0 = im->height, y1 = -1;
    *area = 0;
    for (int y = 0; y < im->height; y++)
        for (int x = 0; x < im->width; x++) {
            double l = luminance(im, y * im->width + x);
            s += l;
            sx += l * x;
            sy += l * y;
            if (l > 0.02) {
                (*area)++;
                x0 = x < x0 ? x : x0;
                x1 = x > x1 ? x : x1;
                y0 = y < y0 ? y : y0;
                y1 = y > y1 ? y : y1;
            }
        }
    assert_true(s > 0);
    c[0] = sx / s;
    c[1] = sy / s;
    *w = x1 - x0 + 1;
    *h = y1 - y0 + 1;
}

/* --mode mip: a maximum along each ray does not depend on the ray's
 * direction, so (orthographic) the view from behind is the mirror image;
 * its grey transfer function gives R = G = B; and it is not the composite
 * image. */
static void
test_option_mode_mip(void **state) {
    (void)state;
    const char *blob = write_blob();
    vv_image *front = render_with(blob, 1, "opt-mip0.png",
                                  (const char *const[]){"--mode", "mip", "--ortho", NULL});
    vv_image *back =
        render_with(blob, 1, "opt-mip180.png",
                    (const char *const[]){"--mode", "mip", "--ortho", "--azimuth", "180", NULL});
    vv_image *comp = render_with(blob, 1, "opt-comp0.png", (const char *const[]){"--ortho", NULL});
    const int W = front->width, H = front->height;
    double diff = 0, grey = 0, vs_comp = 0, hi = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const int i = y * W + x, m = y * W + (W - 1 - x);
            diff += fabs(luminance(front, i) - luminance(back, m));
            vs_comp += fabs(luminance(front, i) - luminance(comp, i));
            const float *p = &front->rgba[4 * i];
            grey = fmax(grey, fmax(fabs(p[0] - p[1]), fabs(p[1] - p[2])));
            hi = fmax(hi, luminance(front, i));
        }
    diff /= W * H;
    vs_comp /= W * H;
    print_message("mip: front vs mirrored back %.4f, vs composite %.4f, max channel gap %.4f, "
                  "brightest %.3f\n",
                  diff, vs_comp, grey, hi);
    assert_true(hi > 0.5);          /* the ball is there */
    assert_true(diff < 0.01);       /* order-independent: the mirror image */
    assert_true(grey <= 1.0 / 255); /* the grey ramp */
    assert_true(vs_comp > 5 * diff + 0.005);
    vv_image_free(front);
    vv_image_free(back);
    vv_image_free(comp);
}

/* --azimuth turns the camera about the up axis: the off-centre ball's
 * centroid moves to the mirrored side at 180 degrees, and 360 is 0. */
static void
test_option_azimuth(void **state) {
    (void)state;
    const char *blob = write_blob();
    double c0[2], c90[2], c180[2], c360[2];
    int a, w, h;
    const char *names[4] = {"opt-az0.png", "opt-az90.png", "opt-az180.png", "opt-az360.png"};
    const char *deg[4] = {"0", "90", "180", "360"};
    double *cs[4] = {c0, c90, c180, c360};
    for (int i = 0; i < 4; i++) {
        vv_image *im = render_with(blob, 1, names[i],
                                   (const char *const[]){"--ortho", "--azimuth", deg[i], NULL});
        image_shape(im, cs[i], &a, &w, &h);
        vv_image_free(im);
    }
    const double mid = 31.5;
    print_message("azimuth: centroid x %.2f (0), %.2f (90), %.2f (180), %.2f (360)\n", c0[0],
                  c90[0], c180[0], c360[0]);
    assert_true(fabs(c0[0] - mid) > 3);                     /* off centre to begin with */
    assert_true(fabs((c0[0] - mid) + (c180[0] - mid)) < 1); /* mirrored at 180 */
    assert_true(fabs(c0[1] - c180[1]) < 1);                 /* about the vertical axis */
    assert_true(fabs(c90[0] - c0[0]) > 2);                  /* 90 degrees: elsewhere */
    assert_true(fabs(c360[0] - c0[0]) < 0.05 && fabs(c360[1] - c0[1]) < 0.05);
}

/* --zoom 2 (orthographic: the framed height halves) doubles the
 * silhouette's width and height and quadruples its area, about the
 * image centre. */
static void
test_option_zoom(void **state) {
    (void)state;
    const char *blob = write_blob();
    vv_image *one = render_with(blob, 1, "opt-zoom1.png", (const char *const[]){"--ortho", NULL});
    vv_image *two = render_with(blob, 1, "opt-zoom2.png",
                                (const char *const[]){"--ortho", "--zoom", "2", NULL});
    double c1[2], c2[2];
    int a1, w1, h1, a2, w2, h2;
    image_shape(one, c1, &a1, &w1, &h1);
    image_shape(two, c2, &a2, &w2, &h2);
    print_message("zoom: silhouette %dx%d (%d px) -> %dx%d (%d px), centroid (%.2f, %.2f) -> "
                  "(%.2f, %.2f)\n",
                  w1, h1, a1, w2, h2, a2, c1[0], c1[1], c2[0], c2[1]);
    assert_true(w1 >= 8 && h1 >= 8);
    assert_true(fabs((double)w2 / w1 - 2) < 0.25 && fabs((double)h2 / h1 - 2) < 0.25);
    assert_true(fabs((double)a2 / a1 - 4) < 0.6);
    /* distances from the image centre double too */
    for (int k = 0; k < 2; k++)
        assert_true(fabs((c2[k] - 31.5) - 2 * (c1[k] - 31.5)) < 1.0);
    vv_image_free(one);
    vv_image_free(two);
}

/* --gamma G writes v^(1/G): every pixel of the default render, mapped by
 * the power law, is the pixel of the gamma render (within 8-bit rounding). */
static void
test_option_gamma(void **state) {
    (void)state;
    const char *neghip = vt_data("volumes/neghip.slc");
    vv_image *lin = render_with(neghip, 0, "opt-gamma1.png", (const char *const[]){NULL});
    vv_image *g =
        render_with(neghip, 0, "opt-gamma22.png", (const char *const[]){"--gamma", "2.2", NULL});
    int checked = 0, changed = 0;
    double worst = 0;
    for (int i = 0; i < 4 * lin->width * lin->height; i++) {
        if (i % 4 == 3)
            continue; /* alpha */
        const double x = lin->rgba[i], y = g->rgba[i];
        if (x < 16.0 / 255)
            continue; /* the power law's slope is steep near 0: rounding dominates */
        const double want = pow(x, 1 / 2.2);
        /* the linear value was rounded to 1/255: allow that through the slope */
        const double tol = (1.0 + 0.5 * (1 / 2.2) * pow(x, 1 / 2.2 - 1)) / 255;
        worst = fmax(worst, fabs(y - want) / tol);
        if (!(fabs(y - want) <= tol))
            fail_msg("channel %d: %.4f with gamma 2.2, expected %.4f = %.4f^(1/2.2)", i, y, want,
                     x);
        checked++;
        changed += fabs(y - x) > 2.0 / 255;
    }
    print_message("gamma: %d values checked, %d changed, worst error %.2f of the tolerance\n",
                  checked, changed, worst);
    assert_true(checked > 500 && changed > checked / 2);
    vv_image_free(lin);
    vv_image_free(g);
}

static void
test_render_png(void **state) {
    (void)state;
    const char *png = out_file("neghip.png");
    unlink(png);
    run_result r = run_cli("render", vt_data("volumes/neghip.slc"), "-o", png, "--size", "64x48");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    /* not a terminal: no progress bar, nothing on stderr */
    assert_string_equal(r.err, "");
    char want[1400];
    snprintf(want, sizeof want, "wrote %s (64x48, ", png);
    assert_true(strncmp(r.out, want, strlen(want)) == 0);
    assert_contains(r.out, " s)\n");
    assert_int_equal(count_char(r.out, '\n'), 1);
    free_result(&r);
    check_png(png, 64, 48);

    /* --opt=VALUE forms, another mode and view, quiet */
    const char *mip = out_file("neghip-mip.png");
    unlink(mip);
    r = run_cli("render", "--size=40x30", "--mode=mip", "--azimuth", "-30", "--elevation=20",
                "--zoom", "1.5", "--threads", "2", "--step", "0.5", "--gamma", "2.2", "-q",
                vt_data("volumes/neghip.slc"), "-o", mip);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_string_equal(r.out, "");
    assert_string_equal(r.err, "");
    free_result(&r);
    check_png(mip, 40, 30);

    /* a transfer function range and an isosurface */
    const char *iso = out_file("neghip-iso.png");
    r = run_cli("render", vt_data("volumes/neghip.slc"), "-o", iso, "--size", "32x32", "--iso",
                "60");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    free_result(&r);
    check_png(iso, 32, 32);

    /* cached gradients over the budget: computed at the samples, said in
     * one line (the default above fits and says nothing); -q silences it */
    const char *otf = out_file("neghip-otf.png");
    r = run_cli("render", vt_data("volumes/neghip.slc"), "-o", otf, "--size", "32x32", "--set",
                "gradient_budget_mb=0");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_string_equal(r.err,
                        "volvis: note: 1 volume shaded with gradients computed at the samples "
                        "(slower): cached gradients (2 bytes a voxel) fit neither the gradient "
                        "budget (--set gradient_budget_mb) nor half the memory left\n");
    free_result(&r);
    r = run_cli("render", vt_data("volumes/neghip.slc"), "-o", otf, "--size", "32x32", "--set",
                "gradient_budget_mb=0", "-q");
    assert_int_equal(r.status, 0);
    assert_string_equal(r.err, "");
    free_result(&r);
    check_png(otf, 32, 32);

    /* --iso alone implies --mode iso; it differs from composite */
    const char *iso2 = out_file("neghip-iso2.png");
    const char *comp = out_file("neghip-comp.png");
    r = run_cli("render", vt_data("volumes/neghip.slc"), "-o", iso2, "--size", "32x32", "--mode",
                "iso", "--iso", "60");
    assert_int_equal(r.status, 0);
    free_result(&r);
    r = run_cli("render", vt_data("volumes/neghip.slc"), "-o", comp, "--size", "32x32");
    assert_int_equal(r.status, 0);
    free_result(&r);
    vv_image *i1, *i2, *i3;
    vt_ok(vv_image_read_png(&i1, iso));
    vt_ok(vv_image_read_png(&i2, iso2));
    vt_ok(vv_image_read_png(&i3, comp));
    assert_true(isinf(vv_image_psnr(i1, i2)));
    assert_true(isfinite(vv_image_psnr(i1, i3)));
    vv_image_free(i1);
    vv_image_free(i2);
    vv_image_free(i3);

    /* the real CT head with the documented transfer function */
    const char *ct = out_file("ct_head.png");
    r = run_cli("render", vt_data("volumes/ct_head.nrrd"), "--tf", "100:1500", "--size", "48x40",
                "-o", ct);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    free_result(&r);
    check_png(ct, 48, 40);
}

/* Names in the output directory that start with @p prefix. */
static int
count_entries(const char *prefix) {
    DIR *d = opendir(outdir());
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += strncmp(e->d_name, prefix, strlen(prefix)) == 0;
    closedir(d);
    return n;
}

static void
test_render_failure_keeps_output(void **state) {
    (void)state;
    const char *bad = out_file("keep-bad.slc");
    static const char bad_text[] = "11111\n this is not really an SLC file\n";
    vt_write_file(bad, bad_text, strlen(bad_text));
    const char *fresh = out_file("keep-fresh.png");
    unlink(fresh);
    run_result r = run_cli("render", bad, "-o", fresh, "--size", "64x48");
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_string_equal(r.out, "");
    free_result(&r);
    assert_false(file_exists(fresh));

    const char *existing = out_file("keep-existing.png");
    static const char content[] = "previous image, must survive";
    vt_write_file(existing, content, sizeof content);
    r = run_cli("render", bad, "-o", existing, "--size", "64x48");
    assert_int_equal(r.status, 1);
    free_result(&r);
    r = run_cli("render", out_file("keep-missing.slc"), "-o", existing);
    assert_int_equal(r.status, 1);
    free_result(&r);
    size_t n;
    unsigned char *got = vt_read_file(existing, &n);
    assert_int_equal(n, sizeof content);
    assert_memory_equal(got, content, sizeof content);
    free(got);
    /* no temporary files left beside the target */
    assert_int_equal(count_entries("keep-"), 2);

    /* an output directory that does not exist: exit 1, the message names the path */
    r = run_cli("render", vt_data("volumes/neghip.slc"), "-o", out_file("no-dir/x.png"), "--size",
                "8x8");
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_contains(r.err, "no-dir/x.png");
    free_result(&r);
}

/* Writes a scene file showing neghip.slc (66^3, grid 0..65) from -y, @p w x @p h. */
/* The neghip scene; @p extra (may be "") is inserted as top-level keys after the view. */
static void
write_scene_with(const char *path, const char *leading, int w, int h, const char *extra) {
    char text[4096];
    int n =
        snprintf(text, sizeof text,
                 "%s{\n"
                 "  \"view\": {\"eye\": [32.5, -180, 32.5], \"at\": [32.5, 32.5, 32.5],\n"
                 "           \"up\": [0, 0, 1], \"fov\": 30, \"width\": %d, \"height\": %d},\n"
                 "%s"
                 "  \"lights\": [{\"type\": \"directional\", \"direction\": [0, 1, 0]}],\n"
                 "  \"objects\": [{\"file\": \"%s\", \"mode\": \"composite\",\n"
                 "    \"transfer_function\": {\"opacity\": [[20, 0], [120, 0.8]],\n"
                 "                          \"color\": [[20, [1, 0.5, 0.2]], [120, [1, 1, 1]]]}}]\n"
                 "}\n",
                 leading, w, h, extra, vt_data("volumes/neghip.slc"));
    assert_true(n > 0 && (size_t)n < sizeof text);
    vt_write_file(path, text, (size_t)n);
}

static void
write_scene(const char *path, const char *leading, int w, int h) {
    write_scene_with(path, leading, w, h, "");
}

static void
test_render_scene(void **state) {
    (void)state;
    const char *scene = out_file("scene.json");
    write_scene(scene, "", 40, 30);
    const char *png = out_file("scene.png");
    unlink(png);
    run_result r = run_cli("render", scene, "-o", png);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_contains(r.out, "(40x30, ");
    free_result(&r);
    check_png(png, 40, 30); /* the scene's own size */

    /* overrides: size, view and mode; content-detected scene without .json */
    const char *txt = out_file("scene.txt");
    write_scene(txt, "  \n\t", 40, 30);
    const char *png2 = out_file("scene-override.png");
    r = run_cli("render", txt, "-o", png2, "--size", "24x20", "--azimuth", "40", "--zoom", "2",
                "--mode", "mip", "--tf", "0:200");
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_contains(r.out, "(24x20, ");
    free_result(&r);
    check_png(png2, 24, 20);

    /* --zoom changes the picture */
    const char *a = out_file("scene-a.png"), *b = out_file("scene-b.png");
    r = run_cli("render", scene, "-o", a, "--size", "32x32");
    assert_int_equal(r.status, 0);
    free_result(&r);
    r = run_cli("render", scene, "-o", b, "--size", "32x32", "--zoom", "2");
    assert_int_equal(r.status, 0);
    free_result(&r);
    vv_image *ia, *ib;
    vt_ok(vv_image_read_png(&ia, a));
    vt_ok(vv_image_read_png(&ib, b));
    assert_true(isfinite(vv_image_psnr(ia, ib))); /* --zoom changed the picture */
    vv_image_free(ia);
    vv_image_free(ib);

    /* a broken scene: exit 1, one line naming the file */
    const char *broken = out_file("broken.json");
    static const char broken_text[] = "{\"view\": {\"fov\": \"wide\"}}\n";
    vt_write_file(broken, broken_text, strlen(broken_text));
    r = run_cli("render", broken, "-o", out_file("broken.png"));
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_contains(r.err, "broken.json");
    free_result(&r);
    assert_false(file_exists(out_file("broken.png")));
}

/* ---- convert ----------------------------------------------------------------------- */

static void
assert_same_voxels(const vv_volume *a, const vv_volume *b) {
    assert_int_equal(a->dims[0], b->dims[0]);
    assert_int_equal(a->dims[1], b->dims[1]);
    assert_int_equal(a->dims[2], b->dims[2]);
    assert_int_equal(a->type, b->type);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(a->spacing[i] - b->spacing[i]) < 1e-9);
    size_t bytes = (size_t)vv_volume_voxel_count(a) * vv_voxel_type_size(a->type);
    assert_memory_equal(a->data, b->data, bytes);
}

static void
test_convert_roundtrip(void **state) {
    (void)state;
    const char *nut = vt_data("volumes/nut.slc");
    const char *nrrd = out_file("nut-rt.nrrd");
    const char *slc = out_file("nut-rt.slc");
    unlink(nrrd);
    unlink(slc);
    run_result r = run_cli("convert", nut, nrrd);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_string_equal(r.err, "");
    assert_contains(r.out, "wrote ");
    assert_contains(r.out, "nut-rt.nrrd");
    free_result(&r);
    r = run_cli("convert", nrrd, slc);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_string_equal(r.err, ""); /* u8 data: no rescaling note */
    free_result(&r);

    vv_volume *orig, *via_nrrd, *back;
    vt_ok(vv_volume_load(&orig, nut, NULL));
    vt_ok(vv_volume_load(&via_nrrd, nrrd, NULL));
    vt_ok(vv_volume_load(&back, slc, NULL));
    assert_int_equal(vv_format_detect(nrrd), VV_FORMAT_NRRD);
    assert_int_equal(vv_format_detect(slc), VV_FORMAT_SLC);
    assert_same_voxels(orig, via_nrrd);
    assert_same_voxels(orig, back);
    vv_volume_free(orig);
    vv_volume_free(via_nrrd);
    vv_volume_free(back);

    /* --format overrides the extension */
    const char *odd = out_file("nut-rt.vol");
    r = run_cli("convert", "--format", "nrrd", nut, odd);
    assert_int_equal(r.status, 0);
    free_result(&r);
    assert_int_equal(vv_format_detect(odd), VV_FORMAT_NRRD);
}

static void
test_convert_rescale_and_strict(void **state) {
    (void)state;
    const char *raw = out_file("conv-ramp.raw");
    write_raw_u16(raw, 0);
    const char *slc = out_file("conv-ramp.slc");
    unlink(slc);
    run_result r = run_cli("convert", "--strict", "--raw", "4x3x2:u16:be", raw, slc);
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_contains(r.err, "conv-ramp.slc");
    free_result(&r);
    assert_false(file_exists(slc));

    r = run_cli("convert", "--raw", "4x3x2:u16:be", raw, slc);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_one_error_line(&r); /* the rescaling note */
    assert_contains(r.err, "rescaled");
    free_result(&r);
    vv_volume *v;
    vt_ok(vv_volume_load(&v, slc, NULL));
    assert_int_equal(v->type, VV_U8);
    assert_int_equal(v->dims[0], 4);
    assert_int_equal(v->dims[2], 2);
    assert_true(v->range[0] == 0 && v->range[1] == 255);
    /* monotone ramp stays monotone */
    for (int i = 1; i < 4; i++)
        assert_true(vv_volume_get(v, i, 0, 0) > vv_volume_get(v, i - 1, 0, 0));
    vv_volume_free(v);

    /* raw u16 to NRRD keeps the values */
    const char *nrrd = out_file("conv-ramp.nrrd");
    r = run_cli("convert", "-q", "--raw", "4x3x2:u16:be", raw, nrrd);
    assert_int_equal(r.status, 0);
    assert_string_equal(r.out, "");
    free_result(&r);
    vt_ok(vv_volume_load(&v, nrrd, NULL));
    assert_int_equal(v->type, VV_U16);
    assert_true(vv_volume_get(v, 3, 2, 1) == 2300.0);
    vv_volume_free(v);
}

/* Renders with the CLI (exit 0 expected) and reads the PNG back. */
static vv_image *
render_image(const char *const *args) {
    run_result r = vt_run_cli_v(outdir(), args);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    free_result(&r);
    const char *png = NULL;
    for (int i = 0; args[i]; i++)
        if (strcmp(args[i], "-o") == 0)
            png = args[i + 1];
    assert_non_null(png);
    vv_image *img = NULL;
    vt_ok(vv_image_read_png(&img, png));
    return img;
}

static int
same_pixels(const vv_image *a, const vv_image *b) {
    return a->width == b->width && a->height == b->height &&
           memcmp(a->rgba, b->rgba, (size_t)a->width * (size_t)a->height * 4 * sizeof(float)) == 0;
}

/* A scene's "render" section gives the renderer, quality and options: the
 * same pixels as the plain scene with them on the command line; --renderer
 * naming another renderer drops the scene's options, --set overrides them,
 * and an option the renderer refuses is an error naming the scene. */
static void
test_render_scene_settings(void **state) {
    (void)state;
    const char *with = out_file("settings.json"), *plain = out_file("settings-plain.json");
    write_scene_with(
        with, "", 64, 64,
        /* "surface": the raster renderer's old name, still taken */
        "  \"render\": {\"renderer\": \"surface\", \"options\": {\"wireframe\": 1}},\n");
    write_scene(plain, "", 64, 64);
    const char *p1 = out_file("settings-scene.png"), *p2 = out_file("settings-cli.png");
    const char *p3 = out_file("settings-solid.png"), *p4 = out_file("settings-override.png");
    const char *p5 = out_file("settings-raycast.png"), *p6 = out_file("settings-raycast-plain.png");
    unlink(p1);
    vv_image *a = render_image((const char *const[]){"render", with, "-q", "-o", p1, NULL});
    vv_image *b = render_image((const char *const[]){"render", plain, "-q", "--renderer", "raster",
                                                     "--set", "wireframe=1", "-o", p2, NULL});
    vv_image *c = render_image(
        (const char *const[]){"render", plain, "-q", "--renderer", "raster", "-o", p3, NULL});
    vv_image *d = render_image(
        (const char *const[]){"render", with, "-q", "--set", "wireframe=0", "-o", p4, NULL});
    /* raycast does not know "wireframe": the scene's options are dropped */
    vv_image *e = render_image(
        (const char *const[]){"render", with, "-q", "--renderer", "raycast", "-o", p5, NULL});
    vv_image *f = render_image((const char *const[]){"render", plain, "-q", "-o", p6, NULL});
    assert_int_equal(a->width, 64);
    assert_int_equal(a->height, 64);
    if (!same_pixels(a, b))
        fail_msg("the scene's render section and the command line give different images");
    if (same_pixels(a, c)) /* the option matters, so the test above can fail */
        fail_msg("wireframe=1 draws the same image as wireframe=0");
    if (!same_pixels(c, d))
        fail_msg("--set wireframe=0 did not override the scene's wireframe");
    if (!same_pixels(e, f))
        fail_msg("--renderer raycast on the scene differs from the plain scene");
    if (same_pixels(a, f))
        fail_msg("the scene's renderer was not used");
    vv_image_free(a);
    vv_image_free(b);
    vv_image_free(c);
    vv_image_free(d);
    vv_image_free(e);
    vv_image_free(f);

    /* an option the scene's renderer refuses: exit 1, one line naming the scene and the key */
    const char *bad = out_file("settings-bad.json"), *pb = out_file("settings-bad.png");
    write_scene_with(
        bad, "", 16, 16,
        "  \"render\": {\"renderer\": \"surface\", \"options\": {\"wirefrmae\": 1}},\n");
    unlink(pb);
    run_result r = run_cli("render", bad, "-q", "-o", pb);
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_contains(r.err, "settings-bad.json");
    assert_contains(r.err, "render.options.wirefrmae");
    free_result(&r);
    assert_false(file_exists(pb));
    /* an unknown renderer in the scene */
    write_scene_with(bad, "", 16, 16, "  \"render\": {\"renderer\": \"nosuch\"},\n");
    r = run_cli("render", bad, "-q", "-o", pb);
    assert_int_equal(r.status, 1);
    assert_one_error_line(&r);
    assert_contains(r.err, "render.renderer: unknown renderer 'nosuch'");
    free_result(&r);
    assert_false(file_exists(pb));
}

/* Scenes of volumes and geometric objects: the ray tracer renders them,
 * --set passes its options, a bad option value is a usage error, and the
 * ray caster renders the same scene (skipping the geometry). */
static void
test_render_raytrace_scene(void **state) {
    (void)state;
    const char *scene = VV_SOURCE_DIR "/examples/mip_floor_shadow.json";
    const char *png = out_file("mip_floor.png");
    unlink(png);
    run_result r = run_cli("render", scene, "--renderer", "raytrace", "--size", "48x40", "--set",
                           "samples=3", "--set", "jitter=1", "--quality", "2", "-o", png);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    assert_string_equal(r.err, "");
    free_result(&r);
    check_png(png, 48, 40);
    const char *png2 = out_file("mip_floor_raycast.png");
    unlink(png2);
    r = run_cli("render", scene, "--size", "48x40", "-q", "-o", png2);
    if (r.status != 0)
        fail_msg("exit %d: %s", r.status, r.err);
    free_result(&r);
    check_png(png2, 48, 40);
    const char *png3 = out_file("mip_floor_bad.png");
    unlink(png3);
    r = run_cli("render", scene, "--renderer", "raytrace", "--set", "max_depth=100", "-o", png3);
    assert_int_equal(r.status, 2);
    assert_contains(r.err, "max_depth");
    free_result(&r);
    assert_false(file_exists(png3));
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_help),
        cmocka_unit_test(test_usage_errors),
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_info_nut),
        cmocka_unit_test(test_info_raw),
        cmocka_unit_test(test_render_png),
        cmocka_unit_test(test_option_mode_mip),
        cmocka_unit_test(test_option_azimuth),
        cmocka_unit_test(test_option_zoom),
        cmocka_unit_test(test_option_gamma),
        cmocka_unit_test(test_render_failure_keeps_output),
        cmocka_unit_test(test_render_scene),
        cmocka_unit_test(test_render_raytrace_scene),
        cmocka_unit_test(test_render_scene_settings),
        cmocka_unit_test(test_convert_roundtrip),
        cmocka_unit_test(test_convert_rescale_and_strict),
    };
    return vt_run_tests(tests, NULL, NULL);
}
