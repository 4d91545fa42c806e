/*
 * The gpu renderer's brick cache on the device (src/render/gpu/gpu.c,
 * issue 81 part 4), on the Vulkan device there is (in CI Mesa's lavapipe):
 * the CT head as a .vvb read out of core within 4 MiB (`volvis render
 * --memory-limit 4M`), drawn brick by brick through the region contract.
 *
 *  - `--repeat 3 --stats`: the first frame uploads its bricks (upload_bytes
 *    > 0, every brick a miss), the next two upload 0 bytes and only hit,
 *    as many bricks as the first drew; the image (the third frame's) is
 *    the one the cache turned off draws (option brick_cache=0, which
 *    uploads every brick every frame: the path before the cache), >= 60 dB;
 *  - an orbit (a second view, close up so that each view leaves bricks off
 *    screen; same renderer): only bricks not yet on the device go up
 *    (fewer bytes than the first frame; hits + misses are the bricks the
 *    view draws, as a fresh renderer counts them; the two views' bytes add
 *    up to the same in either order); the image is that of every brick
 *    uploaded;
 *  - a pyramid by level of detail (`--lod`, two threads): its nodes hit
 *    the cache on the second frame (the multiresolution driver draws them
 *    in turn on the renderer, not on clones whose caches last a frame);
 *  - eviction: a cache budget (device_memory_mb) smaller than the volume's
 *    bricks misses on every frame, and the image stays right;
 *  - `--repeat 3 --orbit 45`: the camera turns between frames, frames 2 and
 *    3 hit the bricks seen before and send no more than the first, and the
 *    last image is `--azimuth 120`'s drawn afresh.
 *
 * Where no Vulkan device exists the tests skip, saying why.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/gpu/vk.h"
#include "testutil.h"

#define SIZE 48 /* pixels a side: lavapipe casts each brick's rays over the whole view */

static int have_device;
static const char *no_device;
static char vvb[512];

/* Mesa 22.3's lavapipe keeps allocations of its JIT-compiled shaders past
 * vkDestroyDevice (as tests/render/test_gpu.c; tests/lsan.supp). */
const char *__lsan_default_suppressions(void);
const char *
__lsan_default_suppressions(void) {
    return "leak:libvulkan_lvp.so\nleak:libLLVM-15.so\n";
}

#define run_cli(...)                                                                               \
    vt_run_cli_v(vt_outdir("render_gpu_cache"), (const char *const[]){__VA_ARGS__, NULL})

static int
setup(void **state) {
    (void)state;
    setenv("LSAN_OPTIONS", "suppressions=" VV_SOURCE_DIR "/tests/lsan.supp:print_suppressions=0",
           0);
    vv_gpu_device d[4];
    have_device = vv_gpu_devices(d, 4, &no_device) > 0;
    if (!have_device)
        return 0;
    printf("# gpu device 0: %s (%s)\n", d[0].name, d[0].kind);
    snprintf(vvb, sizeof vvb, "%s/ct_head.vvb", vt_outdir("render_gpu_cache"));
    vt_run_result r = run_cli("convert", "-q", vt_data("volumes/ct_head.nrrd"), vvb);
    const int ok = r.status == 0;
    if (!ok)
        fprintf(stderr, "convert: %s\n", r.err);
    vt_run_result_free(&r);
    return ok ? 0 : -1;
}

#define NEED_DEVICE()                                                                              \
    do {                                                                                           \
        if (!have_device)                                                                          \
            vt_skip("no Vulkan device: %s", no_device);                                            \
    } while (0)

/* One frame's `--stats` line. */
typedef struct frame_stats {
    int frame;
    double ms;
    unsigned long long upload_bytes;
    unsigned hits, misses;
} frame_stats;

/* The `--stats` lines of @p out into @p f (at most @p max): how many. */
static int
parse_stats(const char *out, frame_stats *f, int max) {
    int n = 0;
    for (const char *p = strstr(out, "frame="); p && n < max; p = strstr(p + 1, "frame=")) {
        if (p != out && p[-1] != '\n')
            continue;
        double dev;
        unsigned long long samples;
        if (sscanf(p,
                   "frame=%d ms=%lf device_ms=%lf upload_bytes=%llu cache_hits=%u "
                   "cache_misses=%u samples=%llu",
                   &f[n].frame, &f[n].ms, &dev, &f[n].upload_bytes, &f[n].hits, &f[n].misses,
                   &samples) == 7)
            n++;
    }
    return n;
}

/* `volvis render` of the .vvb out of core (4 MiB) with the gpu renderer,
 * @p n frames with --stats into @p f, the last written to @p png; @p set
 * an option (NULL: none). Fails the test when it fails. */
static void
render_cli(const char *png, int n, const char *set, frame_stats *f) {
    char reps[16];
    snprintf(reps, sizeof reps, "%d", n);
    vt_run_result r =
        set ? run_cli("render", vvb, "--renderer", "gpu", "--memory-limit", "4M", "--tf",
                      "100:1500", "--azimuth", "30", "--elevation", "20", "--size", "48x48",
                      "--repeat", reps, "--stats", "--set", set, "-o", png)
            : run_cli("render", vvb, "--renderer", "gpu", "--memory-limit", "4M", "--tf",
                      "100:1500", "--azimuth", "30", "--elevation", "20", "--size", "48x48",
                      "--repeat", reps, "--stats", "-o", png);
    if (r.status != 0) {
        char why[600];
        snprintf(why, sizeof why, "%s", r.err);
        vt_run_result_free(&r);
        fail_msg("render %s: %s", set ? set : "", why);
    }
    printf("%s", r.out);
    const int got = parse_stats(r.out, f, n);
    const int said = strstr(r.out, "out of core") != NULL;
    vt_run_result_free(&r);
    assert_int_equal(got, n);
    assert_true(said);
    for (int i = 0; i < n; i++)
        assert_int_equal(f[i].frame, i + 1);
}

/* The uncached frame of test_repeat_uploads_once (its PNG: uncached.png),
 * which test_eviction compares with (it runs after it). */
static frame_stats uncached;

/* The must-hold of issue 81: --repeat 3 --stats uploads on the first frame
 * only; the image equals the uncached path's. */
static void
test_repeat_uploads_once(void **state) {
    (void)state;
    NEED_DEVICE();
    const char *dir = vt_outdir("render_gpu_cache");
    char cached[600], plain[600];
    snprintf(cached, sizeof cached, "%s/cached.png", dir);
    snprintf(plain, sizeof plain, "%s/uncached.png", dir);
    frame_stats f[3], u[1];
    render_cli(cached, 3, NULL, f);
    assert_true(f[0].upload_bytes > 0);
    assert_true(f[0].misses > 0);
    assert_int_equal(f[0].hits, 0);
    for (int i = 1; i < 3; i++) {
        assert_true(f[i].upload_bytes == 0);
        assert_int_equal(f[i].misses, 0);
        assert_int_equal(f[i].hits, f[0].misses);
    }
    /* the cache off: every brick uploaded, the same bytes (every frame:
     * test_eviction's second frame) */
    render_cli(plain, 1, "brick_cache=0", u);
    uncached = u[0];
    assert_true(u[0].upload_bytes == f[0].upload_bytes);
    assert_int_equal(u[0].misses, f[0].misses);
    assert_int_equal(u[0].hits, 0);
    const double db = vt_png_psnr(cached, plain);
    printf("# frame 1 %.1f ms, frames 2-3 %.1f, %.1f ms (uncached %.1f ms); cached against "
           "uncached %.1f dB\n",
           f[0].ms, f[1].ms, f[2].ms, u[0].ms, db);
    assert_true(db >= 60);
}

/* A frame of @p w by @p r with its counts into *@p st. */
static vv_image *
frame(vv_renderer *r, const vv_world *w, vv_render_stats *st) {
    vv_render_options o;
    vv_render_options_init(&o);
    *st = (vv_render_stats){0};
    o.stats = st;
    vv_image *img;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vt_ok(vv_renderer_render(r, w, &w->view, &o, img));
    return img;
}

/* The .vvb opened out of core (its bricks through the process cache). */
static vv_world *
open_vvb(void) {
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.memory = VV_WORLD_OUT_OF_CORE;
    o.view = vt_scene_options(SIZE);
    o.view.has_tf_range = 1;
    o.view.tf_lo = 100;
    o.view.tf_hi = 1500;
    o.has_size = 1;
    vv_world *w = NULL;
    vv_world_open_info info;
    vt_ok(vv_world_open(&w, vvb, &o, &info));
    assert_int_equal(info.out_of_core, 1);
    return w;
}

static vv_renderer *
gpu(const char *key, const char *value) {
    vv_renderer *r;
    vt_ok(vv_renderer_new(&r, "gpu"));
    if (key)
        vt_ok(vv_renderer_set_option(r, key, value));
    return r;
}

/* An orbit uploads only the bricks not yet on the device. */
static void
test_orbit_uploads_new_bricks(void **state) {
    (void)state;
    NEED_DEVICE();
    vv_world *w = open_vvb();
    /* close up (zoom 6): each view leaves some bricks off screen, so the
     * orbit's view draws bricks the first did not */
    vv_anim_view_turn(&w->view, 0, 0, 6);
    const vv_view v1 = w->view;
    vv_view v2 = v1;
    vv_anim_view_turn(&v2, vv_deg_to_rad(90), 0, 1);
    vv_renderer *r = gpu(NULL, NULL);
    vv_render_stats s1, s2, fresh;
    vv_image *a = frame(r, w, &s1);
    w->view = v2;
    vv_image *b = frame(r, w, &s2);
    /* the second view by a renderer of its own (every brick uploaded) */
    w->view = v2;
    vv_renderer *r2 = gpu(NULL, NULL);
    vv_image *b_fresh = frame(r2, w, &fresh);
    printf("# first view: %llu bytes, %u misses; orbit: %llu bytes, %u hits, %u misses (alone: "
           "%u bricks)\n",
           (unsigned long long)s1.upload_bytes, s1.cache_misses,
           (unsigned long long)s2.upload_bytes, s2.cache_hits, s2.cache_misses, fresh.cache_misses);
    assert_true(s1.upload_bytes > 0 && s1.cache_misses > 0 && s1.cache_hits == 0);
    /* the orbit draws what a fresh renderer draws, some of it already there */
    assert_int_equal(s2.cache_hits + s2.cache_misses, fresh.cache_misses);
    assert_true(s2.cache_hits > 0 && s2.cache_misses > 0);
    assert_true(s2.upload_bytes > 0);
    assert_true(s2.upload_bytes < s1.upload_bytes);
    assert_true(s2.upload_bytes < fresh.upload_bytes);
    /* what went up is what was missing: the fresh renderer then turned to
     * the first view sends the same bytes in all (the two views' bricks) */
    w->view = v1;
    vv_render_stats s4;
    vv_image_free(frame(r2, w, &s4));
    printf("# the views the other way round: %llu then %llu bytes\n",
           (unsigned long long)fresh.upload_bytes, (unsigned long long)s4.upload_bytes);
    assert_true(s1.upload_bytes + s2.upload_bytes == fresh.upload_bytes + s4.upload_bytes);
    assert_int_equal(s1.cache_misses + s2.cache_misses, fresh.cache_misses + s4.cache_misses);
    const double db_b = vt_image_psnr(b_fresh, b, NULL);
    printf("# orbit against its bricks all uploaded %.1f dB\n", db_b);
    assert_true(db_b >= 60);
    vv_image_write_png(b, vt_path(vt_outdir("render_gpu_cache"), "orbit.png"), 1, 0);
    vv_image_free(a);
    vv_image_free(b);
    vv_image_free(b_fresh);
    vv_renderer_free(r);
    vv_renderer_free(r2);
    vv_world_free(w);
}

/* A cache smaller than the volume's bricks: misses every frame, the right
 * image. */
static void
test_eviction(void **state) {
    (void)state;
    NEED_DEVICE();
    const char *dir = vt_outdir("render_gpu_cache");
    char small[600], plain[600];
    snprintf(small, sizeof small, "%s/evicting.png", dir);
    snprintf(plain, sizeof plain, "%s/uncached.png", dir); /* test_repeat_uploads_once's */
    if (!uncached.upload_bytes)
        fail_msg("test_repeat_uploads_once did not draw the uncached frame");
    frame_stats f[2];
    render_cli(small, 2, "device_memory_mb=2", f);
    assert_int_equal(f[0].misses, uncached.misses);
    for (int i = 0; i < 2; i++) {
        assert_true(f[i].misses > 0);
        assert_true(f[i].upload_bytes > 0);
    }
    /* 2 MiB hold one or two of the bricks the frame draws: nearly all go up again */
    assert_true(f[1].upload_bytes > uncached.upload_bytes / 2);
    const double db = vt_png_psnr(small, plain);
    printf("# a cache of 2 MiB: frame 2 uploads %llu of %llu bytes, %u misses; against uncached "
           "%.1f dB\n",
           f[1].upload_bytes, uncached.upload_bytes, f[1].misses, db);
    assert_true(db >= 60);
}

/* Level of detail from the .vvb's pyramid: the second frame only hits. */
static void
test_pyramid_nodes_hit(void **state) {
    (void)state;
    NEED_DEVICE();
    vt_run_result r =
        run_cli("render", vvb, "--renderer", "gpu", "--lod", "0.3", "--threads", "2", "--tf",
                "100:1500", "--azimuth", "30", "--elevation", "20", "--size", "48x48", "--repeat",
                "2", "--stats", "-o", vt_path(vt_outdir("render_gpu_cache"), "lod.png"));
    if (r.status != 0) {
        char why[600];
        snprintf(why, sizeof why, "%s", r.err);
        vt_run_result_free(&r);
        fail_msg("render --lod: %s", why);
    }
    printf("%s", r.out);
    frame_stats f[2];
    const int n = parse_stats(r.out, f, 2), levels = strstr(r.out, "levels") != NULL;
    vt_run_result_free(&r);
    assert_int_equal(n, 2);
    assert_true(levels);
    assert_true(f[0].misses > 1 && f[0].upload_bytes > 0 && f[0].hits == 0);
    assert_true(f[1].upload_bytes == 0);
    assert_int_equal(f[1].misses, 0);
    assert_int_equal(f[1].hits, f[0].misses);
}

/* `volvis render --repeat 3 --orbit 45` (close up, so that each view leaves
 * bricks off screen): the camera turns between frames on one renderer, the
 * bricks seen before stay on the device (hits on frames 2 and 3, none
 * uploaded twice: each frame sends no more than the first), and the last
 * frame is the one `--azimuth 120` draws afresh (30 + 45 + 45 degrees). */
static void
test_cli_orbit(void **state) {
    (void)state;
    NEED_DEVICE();
    const char *dir = vt_outdir("render_gpu_cache");
    char orbit[512], fresh[512];
    snprintf(orbit, sizeof orbit, "%s/orbit.png", dir);
    snprintf(fresh, sizeof fresh, "%s/orbit_fresh.png", dir);
    vt_run_result r = run_cli("render", vvb, "--renderer", "gpu", "--memory-limit", "4M", "--tf",
                              "100:1500", "--azimuth", "30", "--zoom", "3", "--size", "48x48",
                              "--repeat", "3", "--orbit", "45", "--stats", "-o", orbit);
    if (r.status != 0) {
        char why[600];
        snprintf(why, sizeof why, "%s", r.err);
        vt_run_result_free(&r);
        fail_msg("render --orbit: %s", why);
    }
    printf("%s", r.out);
    frame_stats f[3];
    const int n = parse_stats(r.out, f, 3);
    vt_run_result_free(&r);
    assert_int_equal(n, 3);
    assert_true(f[0].misses > 0 && f[0].hits == 0 && f[0].upload_bytes > 0);
    for (int i = 1; i < 3; i++) {
        assert_true(f[i].hits > 0);
        assert_true(f[i].upload_bytes <= f[0].upload_bytes);
    }
    r = run_cli("render", vvb, "--renderer", "gpu", "--memory-limit", "4M", "--tf", "100:1500",
                "--azimuth", "120", "--zoom", "3", "--size", "48x48", "-q", "-o", fresh);
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    const double db = vt_png_psnr(orbit, fresh);
    printf("# --orbit 45 twice from 30 against --azimuth 120: %.1f dB\n", db);
    assert_true(db >= 60);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_repeat_uploads_once),
        cmocka_unit_test(test_orbit_uploads_new_bricks),
        cmocka_unit_test(test_eviction),
        cmocka_unit_test(test_pyramid_nodes_hit),
        cmocka_unit_test(test_cli_orbit),
    };
    return vt_run_tests(tests, setup, NULL);
}
