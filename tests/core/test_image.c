/* Images: allocation limits, 8-bit conversion with gamma, PSNR, PNG round
 * trips (ours and other libpng layouts), bad PNG input, atomic output. */
#include "testutil.h"

#include <dirent.h>
#include <math.h>
#include <png.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

static char outdir[1024];

static const char *
out_path(const char *name) {
    static char path[8][1200];
    static int slot;
    slot = (slot + 1) % 8;
    if (!outdir[0])
        snprintf(outdir, sizeof outdir, "%s", vt_outdir("core_image"));
    snprintf(path[slot], sizeof path[slot], "%s/%s", outdir, name);
    return path[slot];
}

/* Number of entries in @p dir whose name contains @p needle. */
static int
count_entries(const char *dir, const char *needle) {
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, needle))
            n++;
    closedir(d);
    return n;
}

static int
exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

/* An image whose every channel is an exact multiple of 1/255. */
static vv_image *
pattern_image(int w, int h, int with_alpha) {
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w, h));
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 4; c++) {
                int v = (x * 7 + y * 13 + c * 71 + x * y) % 256;
                if (c == 3 && !with_alpha)
                    v = 255;
                img->rgba[4 * ((size_t)y * w + x) + c] = (float)(v / 255.0);
            }
    return img;
}

static void
test_new_limits(void **state) {
    (void)state;
    const int bad[][2] = {
        {0, 1}, {1, 0}, {-1, 5}, {5, -1}, {32769, 1}, {1, 32769}, {-2147483647 - 1, 1}};
    for (size_t n = 0; n < sizeof bad / sizeof bad[0]; n++) {
        vv_image *img = (vv_image *)&img;
        vv_error_clear();
        vv_status s = vv_image_new(&img, bad[n][0], bad[n][1]);
        if (s != VV_ERR_INVALID)
            fail_msg("%d x %d: got %s, want VV_ERR_INVALID", bad[n][0], bad[n][1],
                     vv_status_name(s));
        assert_null(img);
        assert_true(vv_error_message()[0] != '\0');
    }
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 1, 1));
    vv_image_free(img);
    vt_ok(vv_image_new(&img, 32768, 1)); /* the largest side is accepted */
    assert_int_equal(img->width, 32768);
    vv_image_free(img);
    vt_ok(vv_image_new(&img, 3, 2));
    assert_int_equal(img->width, 3);
    assert_int_equal(img->height, 2);
    for (int i = 0; i < 6; i++) {
        for (int c = 0; c < 4; c++)
            assert_true(img->rgba[4 * i + c] == 0.0f);
        assert_true(isinf(img->depth[i]) && img->depth[i] > 0);
    }
    vv_image_free(img);
    vv_image_free(NULL);
}

static void
test_clear(void **state) {
    (void)state;
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, 5, 4));
    for (int i = 0; i < 20; i++)
        img->depth[i] = (float)i;
    vv_image_clear(img, 0.25f, 0.5f, 0.75f, 1.0f);
    for (int i = 0; i < 20; i++) {
        assert_true(img->rgba[4 * i + 0] == 0.25f);
        assert_true(img->rgba[4 * i + 1] == 0.5f);
        assert_true(img->rgba[4 * i + 2] == 0.75f);
        assert_true(img->rgba[4 * i + 3] == 1.0f);
        assert_true(isinf(img->depth[i]) && img->depth[i] > 0);
    }
    vv_image_free(img);
}

static void
test_to_8bit(void **state) {
    (void)state;
    /* input, expected at gamma 1, expected at gamma 2.2; computed independently
     * as round(255 * v^(1/gamma)) for the float value of v */
    const struct {
        float v;
        uint8_t g1, g22;
    } cases[] = {
        {0.0f, 0, 0},         {1.0f, 255, 255},  {0.5f, 128, 186},    {0.25f, 64, 136},
        {0.1f, 26, 90},       {0.01f, 3, 31},    {0.9f, 229, 243},    {0.75f, 191, 224},
        {0.002f, 1, 15},      {0.0019f, 0, 15},  {-0.5f, 0, 0},       {1.5f, 255, 255},
        {-1e30f, 0, 0},       {1e30f, 255, 255}, {NAN, 0, 0},         {-NAN, 0, 0},
        {INFINITY, 255, 255}, {-INFINITY, 0, 0}, {1.0f / 255, 1, 21}, {254.0f / 255, 254, 255},
    };
    const int n = (int)(sizeof cases / sizeof cases[0]);
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, n, 1));
    for (int i = 0; i < n; i++) {
        img->rgba[4 * i + 0] = cases[i].v;
        img->rgba[4 * i + 1] = 0.5f;
        img->rgba[4 * i + 2] = cases[(i + 1) % n].v;
        img->rgba[4 * i + 3] = cases[i].v;
    }
    uint8_t *rgb = malloc((size_t)n * 3), *rgba = malloc((size_t)n * 4);
    assert_non_null(rgb);
    assert_non_null(rgba);
    const double gammas[] = {1.0, 2.2};
    for (int g = 0; g < 2; g++) {
        vv_image_to_8bit(img, 3, gammas[g], rgb);
        vv_image_to_8bit(img, 4, gammas[g], rgba);
        for (int i = 0; i < n; i++) {
            uint8_t want = g ? cases[i].g22 : cases[i].g1;
            uint8_t want_b = g ? cases[(i + 1) % n].g22 : cases[(i + 1) % n].g1;
            uint8_t want_g = g ? 186 : 128;
            if (rgb[3 * i] != want)
                fail_msg("gamma %g: %.9g -> %d, want %d", gammas[g], (double)cases[i].v, rgb[3 * i],
                         want);
            assert_int_equal(rgb[3 * i + 1], want_g);
            assert_int_equal(rgb[3 * i + 2], want_b);
            assert_int_equal(rgba[4 * i], want);
            assert_int_equal(rgba[4 * i + 1], want_g);
            assert_int_equal(rgba[4 * i + 2], want_b);
            /* alpha is coverage, not colour: never gamma-encoded */
            assert_int_equal(rgba[4 * i + 3], cases[i].g1);
        }
    }
    /* gamma <= 0 is taken as 1 */
    uint8_t *ref = malloc((size_t)n * 3);
    assert_non_null(ref);
    vv_image_to_8bit(img, 3, 1.0, ref);
    vv_image_to_8bit(img, 3, 0.0, rgb);
    assert_memory_equal(rgb, ref, (size_t)n * 3);
    vv_image_to_8bit(img, 3, -2.2, rgb);
    assert_memory_equal(rgb, ref, (size_t)n * 3);
    free(ref);
    free(rgb);
    free(rgba);
    vv_image_free(img);
    /* rows top to bottom, x fastest */
    vt_ok(vv_image_new(&img, 2, 2));
    for (int i = 0; i < 4; i++)
        img->rgba[4 * i] = (float)((i + 1) * 10 / 255.0);
    uint8_t out[12];
    vv_image_to_8bit(img, 3, 1.0, out);
    assert_int_equal(out[0], 10);
    assert_int_equal(out[3], 20);
    assert_int_equal(out[6], 30);
    assert_int_equal(out[9], 40);
    vv_image_free(img);
}

static void
test_psnr(void **state) {
    (void)state;
    vv_image *a = NULL, *b = NULL, *c = NULL;
    vt_ok(vv_image_new(&a, 4, 2));
    vt_ok(vv_image_new(&b, 4, 2));
    vt_ok(vv_image_new(&c, 2, 4));
    double p = vv_image_psnr(a, b);
    assert_true(isinf(p) && p > 0);
    /* alpha and depth do not count */
    b->rgba[3] = 1.0f;
    b->depth[0] = 1.0f;
    p = vv_image_psnr(a, b);
    assert_true(isinf(p) && p > 0);
    /* one channel off by 10 in 8 bits over 4 x 2 x 3 samples: MSE = 100 / 24 */
    b->rgba[4 * 5 + 1] = (float)(10 / 255.0);
    double want = 10 * log10(255.0 * 255.0 / (100.0 / 24.0));
    assert_true(fabs(vv_image_psnr(a, b) - want) < 1e-9);
    assert_true(fabs(vv_image_psnr(b, a) - want) < 1e-9);
    /* worst case: black against white, MSE = 255^2, 0 dB */
    vv_image_clear(b, 1, 1, 1, 1);
    assert_true(fabs(vv_image_psnr(a, b)) < 1e-12);
    /* compared after clamping to 8 bits: out-of-range values equal their clamp */
    vv_image_clear(a, 2, 1, -1, 0);
    vv_image_clear(b, 1, 1, 0, 0);
    p = vv_image_psnr(a, b);
    assert_true(isinf(p) && p > 0);
    /* different sizes: NaN (same pixel count, different shape) */
    assert_true(isnan(vv_image_psnr(a, c)));
    assert_true(isnan(vv_image_psnr(c, a)));
    vv_image_free(a);
    vv_image_free(b);
    vv_image_free(c);
}

static void
round_trip(int w, int h, int with_alpha) {
    vv_image *img = pattern_image(w, h, with_alpha);
    const char *path = out_path(with_alpha ? "rt_rgba.png" : "rt_rgb.png");
    vt_ok(vv_image_write_png(img, path, 1.0, with_alpha));
    vv_image *back = NULL;
    vt_ok(vv_image_read_png(&back, path));
    assert_int_equal(back->width, w);
    assert_int_equal(back->height, h);
    /* every channel is the exact float of v/255 */
    for (size_t i = 0; i < (size_t)w * h * 4; i++) {
        float want = img->rgba[i];
        if (!with_alpha && i % 4 == 3)
            want = 1.0f;
        if (back->rgba[i] != want)
            fail_msg("sample %zu: got %.9g, want %.9g", i, (double)back->rgba[i], (double)want);
    }
    uint8_t *b1 = malloc((size_t)w * h * 4), *b2 = malloc((size_t)w * h * 4);
    assert_non_null(b1);
    assert_non_null(b2);
    vv_image_to_8bit(img, 4, 1.0, b1);
    vv_image_to_8bit(back, 4, 1.0, b2);
    if (with_alpha)
        assert_memory_equal(b1, b2, (size_t)w * h * 4);
    assert_true(isinf(vv_image_psnr(img, back)));
    free(b1);
    free(b2);
    vv_image_free(back);
    vv_image_free(img);
    assert_int_equal(count_entries(outdir, ".tmp-"), 0);
}

static void
test_png_round_trip(void **state) {
    (void)state;
    round_trip(37, 23, 0);
    round_trip(37, 23, 1);
    round_trip(1, 1, 1);
    round_trip(300, 2, 0);
    /* gamma is applied on writing, to colour only */
    vv_image *img = pattern_image(16, 16, 1);
    const char *path = out_path("gamma.png");
    vt_ok(vv_image_write_png(img, path, 2.2, 1));
    vv_image *back = NULL;
    vt_ok(vv_image_read_png(&back, path));
    uint8_t want[16 * 16 * 4], got[16 * 16 * 4];
    vv_image_to_8bit(img, 4, 2.2, want);
    vv_image_to_8bit(back, 4, 1.0, got);
    assert_memory_equal(want, got, sizeof want);
    vv_image_free(back);
    vv_image_free(img);
}

/* Other layouts written with libpng's simplified API. */
static void
write_simplified(const char *path, int w, int h, png_uint_32 format, const void *pixels,
                 const void *colormap, int ncolors) {
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    pi.width = (png_uint_32)w;
    pi.height = (png_uint_32)h;
    pi.format = format;
    pi.colormap_entries = (png_uint_32)ncolors;
    if (!png_image_write_to_file(&pi, path, 0, pixels, 0, colormap))
        fail_msg("libpng could not write %s: %s", path, pi.message);
}

static void
test_png_read_layouts(void **state) {
    (void)state;
    vv_image *img = NULL;
    /* 8-bit grey */
    uint8_t grey[6] = {0, 1, 127, 128, 254, 255};
    const char *p = out_path("grey8.png");
    write_simplified(p, 3, 2, PNG_FORMAT_GRAY, grey, NULL, 0);
    vt_ok(vv_image_read_png(&img, p));
    assert_int_equal(img->width, 3);
    assert_int_equal(img->height, 2);
    for (int i = 0; i < 6; i++) {
        for (int c = 0; c < 3; c++)
            assert_true(img->rgba[4 * i + c] == (float)(grey[i] / 255.0));
        assert_true(img->rgba[4 * i + 3] == 1.0f);
    }
    vv_image_free(img);
    /* 8-bit grey + alpha */
    uint8_t ga[8] = {10, 20, 30, 40, 50, 60, 70, 255};
    p = out_path("ga8.png");
    write_simplified(p, 2, 2, PNG_FORMAT_GA, ga, NULL, 0);
    vt_ok(vv_image_read_png(&img, p));
    for (int i = 0; i < 4; i++) {
        assert_true(img->rgba[4 * i + 1] == (float)(ga[2 * i] / 255.0));
        assert_true(img->rgba[4 * i + 3] == (float)(ga[2 * i + 1] / 255.0));
    }
    vv_image_free(img);
    /* 16-bit grey: values v / 65535 */
    uint16_t g16[4] = {0, 1, 32768, 65535};
    p = out_path("grey16.png");
    write_simplified(p, 4, 1, PNG_FORMAT_LINEAR_Y, g16, NULL, 0);
    vt_ok(vv_image_read_png(&img, p));
    for (int i = 0; i < 4; i++) {
        assert_true(img->rgba[4 * i + 2] == (float)(g16[i] / 65535.0));
        assert_true(img->rgba[4 * i + 3] == 1.0f);
    }
    vv_image_free(img);
    /* palette */
    uint8_t cmap[3 * 3] = {255, 0, 0, 0, 128, 0, 1, 2, 3};
    uint8_t idx[4] = {0, 1, 2, 1};
    p = out_path("palette.png");
    write_simplified(p, 2, 2, PNG_FORMAT_RGB_COLORMAP, idx, cmap, 3);
    vt_ok(vv_image_read_png(&img, p));
    for (int i = 0; i < 4; i++) {
        for (int c = 0; c < 3; c++)
            assert_true(img->rgba[4 * i + c] == (float)(cmap[3 * idx[i] + c] / 255.0));
        assert_true(img->rgba[4 * i + 3] == 1.0f);
    }
    vv_image_free(img);
}

static void
expect_read_error(const char *path, const char *what) {
    vv_image *img = (vv_image *)&img;
    vv_error_clear();
    vv_status s = vv_image_read_png(&img, path);
    if (s >= 0)
        fail_msg("%s: read succeeded", what);
    if (img != NULL)
        fail_msg("%s: *out not NULL after an error", what);
    if (vv_error_message()[0] == '\0')
        fail_msg("%s: %s with an empty message", what, vv_status_name(s));
}

static unsigned char *
good_png(size_t *n) {
    vv_image *img = pattern_image(9, 7, 1);
    const char *path = out_path("good.png");
    vt_ok(vv_image_write_png(img, path, 1.0, 1));
    vv_image_free(img);
    return vt_read_file(path, n);
}

static void
test_png_bad_input(void **state) {
    (void)state;
    expect_read_error(out_path("does-not-exist.png"), "missing file");
    vv_image *img = NULL;
    assert_int_equal(vv_image_read_png(&img, out_path("does-not-exist.png")), VV_ERR_IO);
    assert_non_null(strstr(vv_error_message(), "does-not-exist.png"));
    const char *p = out_path("empty.png");
    vt_write_file(p, "", 0);
    expect_read_error(p, "empty file");
    assert_int_equal(vv_image_read_png(&img, p), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "empty.png"));
    /* a directory */
    expect_read_error(outdir, "directory");
    /* random bytes, with and without a PNG signature in front */
    unsigned char junk[4096];
    uint32_t r = 12345;
    for (size_t i = 0; i < sizeof junk; i++) {
        r = r * 1103515245u + 12345u;
        junk[i] = (unsigned char)(r >> 16);
    }
    p = out_path("junk.png");
    vt_write_file(p, junk, sizeof junk);
    expect_read_error(p, "random bytes");
    assert_int_equal(vv_image_read_png(&img, p), VV_ERR_FORMAT);
    memcpy(junk, "\x89PNG\r\n\x1a\n", 8);
    vt_write_file(p, junk, sizeof junk);
    expect_read_error(p, "signature then random bytes");
    /* a good PNG truncated at every length */
    size_t n = 0;
    unsigned char *good = good_png(&n);
    p = out_path("truncated.png");
    for (size_t len = 0; len < n; len++) {
        vt_write_file(p, good, len);
        char what[64];
        snprintf(what, sizeof what, "truncated to %zu of %zu bytes", len, n);
        expect_read_error(p, what);
    }
    free(good);
}

/* Every single-byte corruption of a good PNG either fails with a message or
 * reads an image of the stated size; none crashes (run under ASan). */
static void
test_png_corrupt_bytes(void **state) {
    (void)state;
    size_t n = 0;
    unsigned char *good = good_png(&n);
    unsigned char *bad = malloc(n);
    assert_non_null(bad);
    const char *p = out_path("corrupt.png");
    int failures = 0;
    for (size_t pos = 8; pos < n; pos++) {
        for (int flip = 0; flip < 2; flip++) {
            memcpy(bad, good, n);
            bad[pos] ^= flip ? 0xFF : 0x01;
            vt_write_file(p, bad, n);
            vv_image *img = NULL;
            vv_error_clear();
            vv_status s = vv_image_read_png(&img, p);
            if (s == VV_OK) {
                assert_non_null(img);
                assert_true(img->width >= 1 && img->height >= 1);
                vv_image_free(img);
            } else {
                failures++;
                assert_null(img);
                assert_true(vv_error_message()[0] != '\0');
            }
        }
    }
    assert_true(failures > 0); /* CRCs catch most of them */
    free(bad);
    free(good);
}

static void
put32(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

/* A PNG whose header (with a valid CRC) claims an absurd size. */
static void
test_png_oversized_header(void **state) {
    (void)state;
    const uint32_t sizes[][2] = {{40000, 1}, {1, 40000}, {0x7FFFFFFF, 0x7FFFFFFF}, {0, 5}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        unsigned char f[8 + 25 + 12];
        memcpy(f, "\x89PNG\r\n\x1a\n", 8);
        put32(f + 8, 13);
        memcpy(f + 12, "IHDR", 4);
        put32(f + 16, sizes[s][0]);
        put32(f + 20, sizes[s][1]);
        f[24] = 8; /* depth */
        f[25] = 6; /* RGBA */
        f[26] = f[27] = f[28] = 0;
        put32(f + 29, (uint32_t)crc32(0, f + 12, 17));
        put32(f + 33, 0);
        memcpy(f + 37, "IEND", 4);
        put32(f + 41, (uint32_t)crc32(0, f + 37, 4));
        const char *p = out_path("huge.png");
        vt_write_file(p, f, sizeof f);
        char what[80];
        snprintf(what, sizeof what, "IHDR %u x %u", sizes[s][0], sizes[s][1]);
        expect_read_error(p, what);
    }
}

static void
test_write_errors(void **state) {
    (void)state;
    vv_image *img = pattern_image(8, 8, 1);
    /* a directory that does not exist: VV_ERR_IO, nothing created */
    char path[1300];
    snprintf(path, sizeof path, "%s/no-such-dir/x.png", out_path(""));
    vv_error_clear();
    assert_int_equal(vv_image_write_png(img, path, 1.0, 1), VV_ERR_IO);
    assert_non_null(strstr(vv_error_message(), "no-such-dir/x.png"));
    assert_false(exists(path));
    char dir[1300];
    snprintf(dir, sizeof dir, "%s/no-such-dir", outdir);
    assert_false(exists(dir));
    /* the target is a directory: the temporary is written, the rename fails,
     * and the temporary is removed */
    const char *target = out_path("a-directory.png");
    mkdir(target, 0755);
    vv_error_clear();
    assert_int_equal(vv_image_write_png(img, target, 1.0, 1), VV_ERR_IO);
    assert_true(vv_error_message()[0] != '\0');
    assert_int_equal(count_entries(outdir, ".tmp-"), 0);
    struct stat st;
    assert_int_equal(stat(target, &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    vv_image_free(img);
}

/* A write that runs out of space part way (RLIMIT_FSIZE) fails with
 * VV_ERR_IO, leaves no temporary and leaves an existing target untouched. */
static void
test_write_out_of_space(void **state) {
    (void)state;
    vv_image *small = pattern_image(4, 4, 0);
    const char *target = out_path("fsize.png");
    vt_ok(vv_image_write_png(small, target, 1.0, 0));
    size_t n0 = 0;
    unsigned char *before = vt_read_file(target, &n0);
    /* noise does not compress: about 3 * 256 * 256 bytes */
    vv_image *big = NULL;
    vt_ok(vv_image_new(&big, 256, 256));
    uint32_t r = 1;
    for (size_t i = 0; i < 256 * 256 * 4; i++) {
        r = r * 1664525u + 1013904223u;
        big->rgba[i] = (float)((r >> 24) / 255.0);
    }
    struct rlimit old;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    struct rlimit lim = old;
    lim.rlim_cur = 20000;
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    vv_error_clear();
    vv_status s = vv_image_write_png(big, target, 1.0, 0);
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, old_handler);
    assert_int_equal(s, VV_ERR_IO);
    assert_true(vv_error_message()[0] != '\0');
    assert_int_equal(count_entries(outdir, ".tmp-"), 0);
    size_t n1 = 0;
    unsigned char *after = vt_read_file(target, &n1);
    assert_true(n0 == n1);
    assert_memory_equal(before, after, n0);
    free(before);
    free(after);
    vv_image_free(big);
    vv_image_free(small);
}

/* Writing over an existing file replaces it by rename: a hard link to the old
 * file still holds the old bytes (an in-place rewrite would change them). */
static void
test_write_replaces_atomically(void **state) {
    (void)state;
    const char *target = out_path("replace.png");
    char old_link[1300];
    snprintf(old_link, sizeof old_link, "%s/replace-old.png", outdir);
    unlink(old_link);
    vv_image *a = pattern_image(5, 5, 1);
    vv_image *b = NULL;
    vt_ok(vv_image_new(&b, 7, 3));
    vv_image_clear(b, 1, 0, 0, 1);
    vt_ok(vv_image_write_png(a, target, 1.0, 1));
    size_t na = 0;
    unsigned char *bytes_a = vt_read_file(target, &na);
    assert_int_equal(link(target, old_link), 0);
    vt_ok(vv_image_write_png(b, target, 1.0, 1));
    size_t nl = 0;
    unsigned char *bytes_old = vt_read_file(old_link, &nl);
    assert_true(nl == na);
    assert_memory_equal(bytes_old, bytes_a, na);
    vv_image *back = NULL;
    vt_ok(vv_image_read_png(&back, target));
    assert_int_equal(back->width, 7);
    assert_int_equal(back->height, 3);
    assert_true(isinf(vv_image_psnr(back, b)));
    vv_image_free(back);
    assert_int_equal(count_entries(outdir, ".tmp-"), 0);
    /* the new file gets the usual permissions (0666 less the umask), not
     * mkstemp's 0600 */
    mode_t old_mask = umask(022);
    vt_ok(vv_image_write_png(a, target, 1.0, 1));
    umask(old_mask);
    struct stat st;
    assert_int_equal(stat(target, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0644);
    free(bytes_a);
    free(bytes_old);
    vv_image_free(a);
    vv_image_free(b);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_new_limits),
        cmocka_unit_test(test_clear),
        cmocka_unit_test(test_to_8bit),
        cmocka_unit_test(test_psnr),
        cmocka_unit_test(test_png_round_trip),
        cmocka_unit_test(test_png_read_layouts),
        cmocka_unit_test(test_png_bad_input),
        cmocka_unit_test(test_png_corrupt_bytes),
        cmocka_unit_test(test_png_oversized_header),
        cmocka_unit_test(test_write_errors),
        cmocka_unit_test(test_write_out_of_space),
        cmocka_unit_test(test_write_replaces_atomically),
    };
    return vt_run_tests(tests, NULL, NULL);
}
