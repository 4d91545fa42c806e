/*
 * The CLI out of core: `volvis convert IN OUT.vvb` (by bricks from an
 * uncompressed NRRD, whole from other formats; zstd bricks unless
 * --no-compress), `volvis render OUT.vvb`
 * and `volvis render --memory-limit` (the same image as in memory with the
 * same transfer function; the `wrote` line counts the bricks read), with
 * raycast and raytrace (region renders trace one ray a pixel: the ray
 * tracer's quality 1; MIP byte for byte; composite with its shadows:
 * >= 50 dB where the proxy is the whole volume, the nut;
 * on the CT head, a 4x coarser proxy (the .vvb's coarse level), exact
 * without shadows and with them (their light volumes swept through the
 * bricks); X-ray bit for bit by both), quality 2 by regions, and
 * its errors: a memory limit smaller than one brick, a bad size, a
 * renderer without the region contract; the pyramid levels convert
 * writes (render --level and --lod read them: OME-Zarr's images bit for
 * bit); a scene of three heads side by side out of core (by bricks, from
 * the levels, one read whole): the in-memory image >= 50 dB, and its
 * refusals; `volvis measure --memory-limit` (box by box) against the whole
 * volume's measurements; a file too big to render in memory read out of
 * core without being asked.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define outdir() vt_outdir("cli_bricks")
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})
/* a run that must exit with @p status (and, with @p msg, say it on
 * stderr); cli_ok: exit 0, cli_fails: exit 1 saying @p msg
 * (vt_run_cli_expect) */
#define cli_expect(status, msg, ...)                                                               \
    vt_run_cli_expect(outdir(), status, msg, (const char *const[]){__VA_ARGS__, NULL})
#define cli_ok(...) cli_expect(0, NULL, __VA_ARGS__)
#define cli_fails(msg, ...) cli_expect(1, msg, __VA_ARGS__)

static void
test_convert_render(void **state) {
    (void)state;
    struct stat st;
    const char *nut = vt_data("volumes/nut.slc");
    if (stat(nut, &st) != 0)
        vt_skip("../shared/data/volumes/nut.slc is missing");
    char vvb[1200], nrrd[1200], vvb2[1200], mem[1200], ooc[1200], ooc2[1200];
    snprintf(vvb, sizeof vvb, "%s/nut.vvb", outdir());
    snprintf(nrrd, sizeof nrrd, "%s/nut_raw.nrrd", outdir());
    snprintf(vvb2, sizeof vvb2, "%s/nut2.vvb", outdir());
    snprintf(mem, sizeof mem, "%s/mem.png", outdir());
    snprintf(ooc, sizeof ooc, "%s/ooc.png", outdir());
    snprintf(ooc2, sizeof ooc2, "%s/ooc2.png", outdir());
    /* SLC: read whole, written by bricks */
    vt_run_result r = run_cli("convert", nut, vvb);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "(vvb, "));
    assert_non_null(strstr(r.out, ", zstd, 2 pyramid levels)")); /* by default */
    vt_run_result_free(&r);
    /* --no-compress: raw bricks, a larger file; --no-coarse alone keeps the
     * coarse levels of zstd bricks, with a note */
    char raw_vvb[1200];
    snprintf(raw_vvb, sizeof raw_vvb, "%s/nut_raw.vvb", outdir());
    r = run_cli("convert", "--no-compress", nut, raw_vvb);
    assert_int_equal(r.status, 0);
    assert_null(strstr(r.out, "zstd"));
    vt_run_result_free(&r);
    struct stat sz, sr;
    assert_int_equal(stat(vvb, &sz), 0);
    assert_int_equal(stat(raw_vvb, &sr), 0);
    printf("nut.vvb: %lld bytes with zstd bricks, %lld raw\n", (long long)sz.st_size,
           (long long)sr.st_size);
    assert_true(sz.st_size < sr.st_size);
    r = run_cli("convert", "--no-coarse", nut, raw_vvb);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.err, "keep their coarse levels"));
    vt_run_result_free(&r);
    /* an uncompressed NRRD: converted brick by brick */
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, nut, NULL));
    vt_ok(vt_save(v, nrrd, VV_FORMAT_NRRD, 0, 0));
    vv_volume_free(v);
    cli_ok("convert", nrrd, vvb2);
    cli_ok("render", nut, "--tf", "40:200", "--size", "96x80", "--mode", "mip", "-o", mem);
    r = run_cli("render", vvb, "--tf", "40:200", "--size", "96x80", "--mode", "mip", "-o", ooc);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "out of core: "));
    vt_run_result_free(&r);
    cli_ok("render", nrrd, "--memory-limit", "8M", "--tf", "40:200", "--size", "96x80", "--mode",
           "mip", "-o", ooc2);
    /* MIP out of core is the in-memory image, bit for bit */
    size_t n1, n2, n3;
    unsigned char *a = vt_read_file(mem, &n1), *b = vt_read_file(ooc, &n2),
                  *c = vt_read_file(ooc2, &n3);
    assert_int_equal(n1, n2);
    assert_memory_equal(a, b, n1);
    assert_int_equal(n1, n3);
    assert_memory_equal(a, c, n1);
    free(a);
    free(b);
    free(c);
}

/* A file too big to render in memory under the memory budget is read out
 * of core without --memory-limit (issue 65), said in one line, and gives
 * the image --memory-limit gives; within the budget it is read whole and
 * nothing is said; -q silences the note; a renderer without the region
 * contract reads it whole. A 192^3 u8 ball (7 MiB) needs 35 MiB in memory
 * (the voxels, the 16-bit copy, the gradients): over a budget of 24M. */
static void
test_too_big_for_memory(void **state) {
    (void)state;
    enum { N = 192 };
    vv_volume *v = NULL;
    const int dims[3] = {N, N, N};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    uint8_t *d = v->data;
    const double c = (N - 1) / 2.0;
    for (int k = 0; k < N; k++)
        for (int j = 0; j < N; j++)
            for (int i = 0; i < N; i++) {
                const double r = sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c));
                const double x = 255 - 3 * r;
                d[((size_t)k * N + (size_t)j) * N + (size_t)i] = (uint8_t)(x < 0     ? 0
                                                                           : x > 255 ? 255
                                                                                     : x);
            }
    vv_volume_update_range(v);
    char nrrd[1200], a[1200], b[1200], m[1200];
    snprintf(nrrd, sizeof nrrd, "%s/ball.nrrd", outdir());
    snprintf(a, sizeof a, "%s/ball_auto.png", outdir());
    snprintf(b, sizeof b, "%s/ball_limit.png", outdir());
    snprintf(m, sizeof m, "%s/ball_mem.png", outdir());
    vt_ok(vt_save(v, nrrd, VV_FORMAT_NRRD, 0, 0));
    vv_volume_free(v);
    vt_run_result r = run_cli("--max-memory", "24M", "render", nrrd, "--size", "64x64", "-o", a);
    if (r.status != 0)
        fail_msg("%s", r.err);
    assert_non_null(strstr(r.out, "out of core: "));
    char want[1400];
    snprintf(want, sizeof want,
             "volvis: note: %s: rendering it in memory would take 33 MiB, more than the memory "
             "budget of 24 MiB (--max-memory): read out of core (--memory-limit 6M)\n",
             nrrd);
    assert_string_equal(r.err, want);
    vt_run_result_free(&r);
    cli_ok("render", nrrd, "--size", "64x64", "--memory-limit", "6M", "-o", b);
    assert_true(isinf(vt_png_psnr(a, b)));
    /* within the default budget: in memory, nothing said */
    r = run_cli("render", nrrd, "--size", "64x64", "-o", m);
    assert_int_equal(r.status, 0);
    assert_null(strstr(r.out, "out of core"));
    assert_string_equal(r.err, "");
    vt_run_result_free(&r);
    r = run_cli("--max-memory", "24M", "render", nrrd, "--size", "64x64", "-q", "-o", a);
    assert_int_equal(r.status, 0);
    assert_string_equal(r.err, "");
    vt_run_result_free(&r);
    /* splat has no region contract: read whole (the volume alone fits) */
    r = run_cli("--max-memory", "24M", "render", nrrd, "--renderer", "splat", "--size", "32x32",
                "-o", m);
    assert_int_equal(r.status, 0);
    assert_null(strstr(r.out, "out of core"));
    vt_run_result_free(&r);
}

/* In memory and out of core (--memory-limit) with @p renderer at quality 1
 * and the extra options; returns the PSNR of the two PNGs. Out of core,
 * bricks are region renders, which cast every pixel: the in-memory render
 * does too (refinement=off). */
static double
mem_vs_ooc(const char *input, const char *vvb, const char *renderer, const char *mode,
           const char *set, const char *tf) {
    char mem[1200], ooc[1200];
    snprintf(mem, sizeof mem, "%s/%s_%s_mem.png", outdir(), renderer, mode);
    snprintf(ooc, sizeof ooc, "%s/%s_%s_ooc.png", outdir(), renderer, mode);
    vt_run_result r =
        run_cli("render", input, "--renderer", renderer, "--quality", "1", "--mode", mode, "--set",
                set, "--set", "refinement=off", "--tf", tf, "--size", "96x80", "-q", "-o", mem);
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
    r = run_cli("render", vvb, "--memory-limit", "4M", "--renderer", renderer, "--quality", "1",
                "--mode", mode, "--set", set, "--tf", tf, "--size", "96x80", "-o", ooc);
    if (r.status != 0)
        fail_msg("%s", r.err);
    assert_non_null(strstr(r.out, "out of core: "));
    vt_run_result_free(&r);
    const double db = vt_png_psnr(mem, ooc);
    printf("%s %s %s (%s): %.1f dB out of core against in memory\n", input, renderer, mode, set,
           db);
    return db;
}

static void
test_renderers(void **state) {
    (void)state;
    struct stat st;
    const char *nut = vt_data("volumes/nut.slc"), *head = vt_data("volumes/ct_head.nrrd");
    if (stat(nut, &st) != 0 || stat(head, &st) != 0)
        vt_skip("../shared/data/volumes/nut.slc or ct_head.nrrd is missing");
    char nvvb[1200], hvvb[1200];
    snprintf(nvvb, sizeof nvvb, "%s/nut_r.vvb", outdir());
    snprintf(hvvb, sizeof hvvb, "%s/head_r.vvb", outdir());
    cli_ok("convert", "-q", nut, nvvb);
    cli_ok("convert", "-q", head, hvvb);
    /* the nut (68 x 41 x 59) is its own proxy: shadows exact */
    assert_true(isinf(mem_vs_ooc(nut, nvvb, "raytrace", "mip", "shadows=1", "40:200")));
    assert_true(mem_vs_ooc(nut, nvvb, "raytrace", "composite", "shadows=1", "40:200") >= 50);
    assert_true(isinf(mem_vs_ooc(nut, nvvb, "raycast", "mip", "simd=1", "40:200")));
    /* the CT head: MIP exact; composite exact without shadows, and with
     * them: its light volume swept brick by brick through the whole volume,
     * not through the 4x coarser proxy (test_exact_shadows) */
    assert_true(isinf(mem_vs_ooc(head, hvvb, "raytrace", "mip", "shadows=1", "100:1500")));
    assert_true(mem_vs_ooc(head, hvvb, "raytrace", "composite", "shadows=0", "100:1500") >= 50);
    assert_true(mem_vs_ooc(head, hvvb, "raytrace", "composite", "shadows=1", "100:1500") >= 55);
    assert_true(mem_vs_ooc(head, hvvb, "raycast", "composite", "simd=1", "100:1500") >= 50);
    /* X-ray: the regions' sums add up and their mean is classified once, by
     * either renderer (the ray tracer's regions sum as the ray caster's) */
    assert_true(isinf(mem_vs_ooc(head, hvvb, "raytrace", "xray", "shadows=1", "100:1500")));
    assert_true(isinf(mem_vs_ooc(head, hvvb, "raycast", "xray", "simd=1", "100:1500")));
}

/* The CT head @p head converted to @p tag.vvb and @p tag.ome.zarr (each
 * path 1200 bytes), and the paths of the images in memory and out of
 * core. */
static void
head_stores(const char *head, const char *tag, char *vvb, char *zarr, char *mem, char *ooc) {
    snprintf(vvb, 1200, "%s/head_%s.vvb", outdir(), tag);
    snprintf(zarr, 1200, "%s/head_%s.ome.zarr", outdir(), tag);
    snprintf(mem, 1200, "%s/%s_mem.png", outdir(), tag);
    snprintf(ooc, 1200, "%s/%s_ooc.png", outdir(), tag);
    cli_ok("convert", "-q", head, vvb);
    cli_ok("convert", "-q", head, zarr);
}

/* Exact ray-traced shadows out of core: the CT head seen (and lit by the
 * headlight) from an oblique direction, read by bricks from a .vvb whose
 * proxy is 4x coarser and by boxes of level 0 from an OME-Zarr pyramid
 * (--level 0), against the in-memory render (quality 1, refinement off:
 * one ray a pixel, as region renders cast). Through the proxy the shadows
 * were 35-43 dB off; swept through the whole volume they are the in-memory
 * light volume's (65 dB here). An OME-Zarr frame at coarser levels keeps
 * the proxy's shadows (the sweep would read level 0 whole), and so does
 * shadow_grid=2, whose swept shadow grids march the context itself. Point
 * lights from scene files, one outside the head and one inside it: at
 * least the agreement of the bricks without shadows (what splitting the
 * composite costs by itself), far above shadows marched through the proxy.
 * And a sparse shell, most of whose bricks the sweep does not read. */
static void
test_exact_shadows(void **state) {
    (void)state;
    const char *head = vt_data("volumes/ct_head.nrrd");
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    char vvb[1200], zarr[1200], mem[1200], ooc[1200];
    head_stores(head, "shadows", vvb, zarr, mem, ooc);
#define SHADOW_VIEW                                                                                \
    "--renderer", "raytrace", "--quality", "1", "--tf", "100:1500", "--azimuth", "35",             \
        "--elevation", "25", "--size", "96x80", "-q"
    cli_ok("render", head, SHADOW_VIEW, "--set", "refinement=off", "-o", mem);
    cli_ok("render", vvb, "--memory-limit", "4M", SHADOW_VIEW, "-o", ooc);
    double db = vt_png_psnr(mem, ooc);
    printf("CT head composite with shadows, .vvb by bricks: %.1f dB against in memory\n", db);
    assert_true(db >= 55);
    cli_ok("render", zarr, "--level", "0", "--memory-limit", "64M", SHADOW_VIEW, "-o", ooc);
    db = vt_png_psnr(mem, ooc);
    printf("CT head composite with shadows, OME-Zarr level 0: %.1f dB against in memory\n", db);
    assert_true(db >= 55);
    /* without the light volumes' sweep (shadow_grid=2 sweeps its own grids
     * through the context): the proxy's shadows, measurably worse */
    cli_ok("render", vvb, "--memory-limit", "4M", SHADOW_VIEW, "--set", "shadow_grid=2", "-o", ooc);
    cli_ok("render", head, SHADOW_VIEW, "--set", "refinement=off", "--set", "shadow_grid=2", "-o",
           mem);
    db = vt_png_psnr(mem, ooc);
    printf("CT head composite, shadow_grid=2 through the proxy: %.1f dB\n", db);
    assert_true(db < 50);
#undef SHADOW_VIEW
    /* a point light outside the head and one inside it (its light volume
     * swept in order of distance to the light, the tiles centred on it):
     * scenes of the file in memory and of the .vvb */
    const char *lights[2] = {"[200, 500, 250]", "[128, 60, 80]"};
    for (int l = 0; l < 2; l++) {
        char scm[1200], sco[1200];
        snprintf(scm, sizeof scm, "%s/point_mem.json", outdir());
        snprintf(sco, sizeof sco, "%s/point_ooc.json", outdir());
        for (int k = 0; k < 2; k++) {
            char text[2400];
            const int n = snprintf(
                text, sizeof text,
                "{\"view\": {\"eye\": [128, 700, 60], \"at\": [128, 128, 60], \"up\": [0, 0, "
                "1], \"fov\": 30, \"width\": 96, \"height\": 96},\n"
                " \"lights\": [{\"type\": \"point\", \"position\": %s, \"intensity\": 2}],\n"
                " \"shading\": {\"ambient\": [0.2, 0.2, 0.2]},\n"
                " \"objects\": [{\"name\": \"head\", \"type\": \"volume\", \"file\": \"%s\",\n"
                "   \"mode\": \"composite\", \"step\": 0.5, \"transfer_function\": {\"opacity\": "
                "[[-600, 0], [-300, 0.015], [-150, 0], [250, 0], [500, 0.3], [1500, 0.8]],\n"
                "   \"color\": [[-600, [0.9, 0.6, 0.5]], [1500, [1, 1, 1]]]}}]}\n",
                lights[l], k ? vvb : head);
            vt_write_file(k ? sco : scm, text, (size_t)n);
        }
        /* with the light volume swept through the bricks; without shadows
         * (what splitting the composite into bricks costs by itself, low
         * with a light this near: its highlights); marched through the
         * proxy (light_volumes=0) */
        const char *sets[3] = {"shadows=1", "shadows=0", "light_volumes=0"};
        double got[3];
        for (int k = 0; k < 3; k++) {
            cli_ok("render", scm, "--renderer", "raytrace", "--quality", "1", "--set",
                   "refinement=off", "--set", sets[k], "-q", "-o", mem);
            cli_ok("render", sco, "--memory-limit", "4M", "--renderer", "raytrace", "--quality",
                   "1", "--set", sets[k], "-q", "-o", ooc);
            got[k] = vt_png_psnr(mem, ooc);
        }
        printf("CT head composite, a point light at %s, .vvb by bricks: %.1f dB (without "
               "shadows %.1f dB, shadows marched through the proxy %.1f dB)\n",
               lights[l], got[0], got[1], got[2]);
        assert_true(got[0] >= 48 && got[0] >= got[1] - 1);
        assert_true(got[2] < got[0] - 5);
    }
    /* a sparse volume: a shell in one corner of a 160^3 box (27 bricks,
     * most of them empty under the transfer function, whose tiles the
     * sweep does not read); a u8 volume, lit from an oblique view */
    enum { N = 160 };
    vv_volume *v = NULL;
    const int dims[3] = {N, N, N};
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    uint8_t *d = v->data;
    for (int k = 0; k < N; k++)
        for (int j = 0; j < N; j++)
            for (int i = 0; i < N; i++) {
                const double r = sqrt((i - 50.0) * (i - 50.0) + (j - 56.0) * (j - 56.0) +
                                      (k - 48.0) * (k - 48.0));
                const double x = 200 - 4 * fabs(r - 26);
                d[((size_t)k * N + (size_t)j) * N + (size_t)i] = (uint8_t)(x < 0 ? 0 : x);
            }
    vv_volume_update_range(v);
    char nrrd[1200], svvb[1200];
    snprintf(nrrd, sizeof nrrd, "%s/shell.nrrd", outdir());
    snprintf(svvb, sizeof svvb, "%s/shell.vvb", outdir());
    vt_ok(vt_save(v, nrrd, VV_FORMAT_NRRD, 0, 0));
    vv_volume_free(v);
    cli_ok("convert", "-q", nrrd, svvb);
#define SHELL_VIEW                                                                                 \
    "--renderer", "raytrace", "--quality", "1", "--tf", "50:200", "--azimuth", "30",               \
        "--elevation", "20", "--size", "96x96", "-q"
    cli_ok("render", nrrd, SHELL_VIEW, "--set", "refinement=off", "-o", mem);
    cli_ok("render", svvb, "--memory-limit", "8M", SHELL_VIEW, "-o", ooc);
    db = vt_png_psnr(mem, ooc);
    printf("a sparse shell, composite with shadows, .vvb by bricks: %.1f dB\n", db);
    assert_true(db >= 55);
#undef SHELL_VIEW
}

/* Quality 2 out of core: the ray tracer's adaptive supersampling by
 * regions (vv_region_image.supersample: the pixels it picks in the
 * combined first image traced again, point by point in every brick). The
 * CT head at the default quality, in memory and out of core (by bricks,
 * and from OME-Zarr's level 0): MIP bit for bit, composite with its
 * shadows >= 55 dB (64.8 at 512 x 512; 49.3 and 42.0 dB when regions cast
 * one ray a pixel); the second pass reads the bricks again. */
static void
test_quality2(void **state) {
    (void)state;
    const char *head = vt_data("volumes/ct_head.nrrd");
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    char vvb[1200], zarr[1200], mem[1200], ooc[1200];
    head_stores(head, "q2", vvb, zarr, mem, ooc);
    const char *modes[] = {"mip", "composite"};
    for (int m = 0; m < 2; m++) {
#define Q2_VIEW                                                                                    \
    "--renderer", "raytrace", "--mode", modes[m], "--tf", "100:1500", "--elevation", "20",         \
        "--size", "128x112"
        cli_ok("render", head, Q2_VIEW, "-q", "-o", mem);
        vt_run_result r = run_cli("render", vvb, "--memory-limit", "4M", Q2_VIEW, "-o", ooc);
        assert_int_equal(r.status, 0);
        /* 29 (composite: 3 skipped) or 32 bricks, then again for the rays */
        int nread = 0, nb = 0;
        const char *at = strstr(r.out, "out of core: ");
        assert_non_null(at);
        assert_int_equal(sscanf(at, "out of core: %d of %d bricks read", &nread, &nb), 2);
        vt_run_result_free(&r);
        double db = vt_png_psnr(mem, ooc);
        printf("CT head %s at quality 2, .vvb by bricks: %.1f dB against in memory (%d brick "
               "reads)\n",
               modes[m], db, nread);
        assert_true(m == 0 ? isinf(db) : db >= 55);
        assert_true(nread > nb);
        cli_ok("render", zarr, "--level", "0", "--memory-limit", "64M", Q2_VIEW, "-q", "-o", ooc);
        db = vt_png_psnr(mem, ooc);
        printf("CT head %s at quality 2, OME-Zarr level 0: %.1f dB against in memory\n", modes[m],
               db);
        assert_true(m == 0 ? isinf(db) : db >= 55);
#undef Q2_VIEW
    }
}

/* The .vvb's pyramid levels from the CLI: `convert` writes them (3 for the
 * CT head) unless --no-levels; `render --level L` and `--lod` read them
 * (the image of OME-Zarr's level L, bit for bit), without them those
 * options are refused; a .vvb from an OME-Zarr pyramid (read by boxes of
 * its level 0), or from a .vvb without levels (brick by brick), is the bytes
 * of the one from the NRRD. */
static void
test_levels(void **state) {
    (void)state;
    const char *head = vt_data("volumes/ct_head.nrrd");
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    char vvb[1200], flat[1200], zarr[1200], back[1200], a[1200], b[1200];
    snprintf(vvb, sizeof vvb, "%s/head_l.vvb", outdir());
    snprintf(flat, sizeof flat, "%s/head_flat.vvb", outdir());
    snprintf(zarr, sizeof zarr, "%s/head_l.ome.zarr", outdir());
    snprintf(back, sizeof back, "%s/head_z.vvb", outdir());
    snprintf(a, sizeof a, "%s/level_vvb.png", outdir());
    snprintf(b, sizeof b, "%s/level_zarr.png", outdir());
    vt_run_result r = run_cli("convert", head, vvb);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, ", zstd, 3 pyramid levels"));
    vt_run_result_free(&r);
    cli_ok("convert", "-q", head, zarr);
    cli_ok("convert", "-q", zarr, back);
    size_t n1, n2;
    unsigned char *x = vt_read_file(vvb, &n1), *y = vt_read_file(back, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(x, y, n1);
    free(x);
    free(y);
    for (int level = 1; level <= 2; level++) {
        char ls[16];
        snprintf(ls, sizeof ls, "%d", level);
        r = run_cli("render", vvb, "--level", ls, "--mode", "mip", "--size", "96x80", "-o", a);
        assert_int_equal(r.status, 0);
        assert_non_null(strstr(r.out, "out of core from 3 levels"));
        vt_run_result_free(&r);
        cli_ok("render", zarr, "--level", ls, "--memory-limit", "64M", "--mode", "mip", "--size",
               "96x80", "-q", "-o", b);
        assert_true(isinf(vt_png_psnr(a, b)));
    }
    r = run_cli("render", vvb, "--lod", "1", "--size", "96x80", "-o", a);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "out of core from 3 levels"));
    vt_run_result_free(&r);
    r = run_cli("convert", "--no-levels", head, flat);
    assert_int_equal(r.status, 0);
    assert_null(strstr(r.out, "pyramid levels"));
    vt_run_result_free(&r);
    cli_expect(2, "a .vvb with pyramid levels", "render", flat, "--lod", "1", "-o", a);
    /* a .vvb read brick by brick into another: levels added back, the same bytes */
    cli_ok("convert", "-q", flat, back);
    x = vt_read_file(vvb, &n1);
    y = vt_read_file(back, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(x, y, n1);
    free(x);
    free(y);
}

/* Writes @p text to @p path. */
static void
write_text(const char *path, const char *text) {
    vt_write_file(path, text, strlen(text));
}

/* A scene of three CT heads side by side out of core: the left and right
 * by bricks from a .vvb (or from its levels with --lod), the middle from
 * the gzip NRRD read whole; the same image as in memory. Overlapping
 * composite objects, a scene's "origin" for a file read out of core and
 * the ray tracer with several objects: one-line errors, nothing written. */
static void
test_scene(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    const char *head = vt_data("volumes/ct_head.nrrd");
    char vvb[1200], scene[1200], bad[1200], a[1200], b[1200], c[8192];
    snprintf(vvb, sizeof vvb, "%s/head_s.vvb", outdir());
    snprintf(scene, sizeof scene, "%s/three.json", outdir());
    snprintf(bad, sizeof bad, "%s/bad.json", outdir());
    snprintf(a, sizeof a, "%s/scene_ooc.png", outdir());
    snprintf(b, sizeof b, "%s/scene_mem.png", outdir());
    cli_ok("convert", "-q", head, vvb);
    const char *tf = "\"transfer_function\": {\"opacity\": [[100, 0], [1500, 0.8]]}";
    snprintf(c, sizeof c,
             "{\"view\": {\"width\": 240, \"height\": 100, \"eye\": [392, -1300, 400],\n"
             "  \"at\": [392, 122, 80], \"up\": [0, 0, 1], \"fov\": 30},\n"
             " \"objects\": [\n"
             "  {\"name\": \"left\", \"file\": \"%s\", %s},\n"
             "  {\"name\": \"middle\", \"file\": \"%s\", \"position\": [270, 0, 0], %s},\n"
             "  {\"name\": \"right\", \"file\": \"%s\", \"mode\": \"mip\", "
             "\"position\": [540, 0, 0], %s}]}\n",
             vvb, tf, head, tf, vvb, tf);
    write_text(scene, c);
    vt_run_result r = run_cli("render", scene, "--memory-limit", "16M", "-o", a);
    assert_int_equal(r.status, 0);
    printf("%s", r.out);
    assert_non_null(strstr(r.out, "2 objects out of core"));
    /* left and right name one file: one source, its reads counted once
     * (each object read the file on its own before: 29 and 32 of 32) */
    const char *left = strstr(r.out, "left: ");
    assert_non_null(left);
    int reads = 0, bricks = 0;
    assert_int_equal(sscanf(left, "left: %d of %d bricks read", &reads, &bricks), 2);
    assert_int_equal(bricks, 32);
    assert_true(reads >= 32 && reads < 29 + 32);
    assert_non_null(strstr(r.out, "middle: in memory"));
    assert_non_null(strstr(r.out, "right: the file of left, one source (counted there)"));
    vt_run_result_free(&r);
    cli_ok("render", scene, "-q", "-o", b);
    const double db = vt_png_psnr(a, b);
    printf("three heads out of core against in memory: %.1f dB\n", db);
    /* 83.6 dB: only compositing's rounding differs; a transfer function
     * whose opacity unit came from the coarse proxy rather than the file's
     * voxels (the scene gives none) gave 51 dB */
    assert_true(db >= 75);
    /* the .vvb's levels, level 0 everywhere: the same image */
    r = run_cli("render", scene, "--level", "0", "--memory-limit", "16M", "-o", a);
    assert_int_equal(r.status, 0);
    printf("%s", r.out);
    assert_non_null(strstr(r.out, "left: "));
    assert_non_null(strstr(r.out, " chunks read from 3 levels"));
    vt_run_result_free(&r);
    printf("from the levels against in memory: %.1f dB\n", vt_png_psnr(a, b));
    assert_true(vt_png_psnr(a, b) >= 75);

    remove(a);
    struct stat st;
    /* composite objects overlapping */
    snprintf(c, sizeof c,
             "{\"objects\": [{\"name\": \"one\", \"file\": \"%s\"},\n"
             "  {\"name\": \"two\", \"file\": \"%s\", \"position\": [100, 0, 0]}]}\n",
             vvb, vvb);
    write_text(bad, c);
    cli_fails("objects 'one' and 'two' overlap", "render", bad, "--memory-limit", "16M", "-o", a);
    /* several objects by the ray tracer */
    cli_fails("raytrace draws light between objects", "render", scene, "--memory-limit", "16M",
              "--renderer", "raytrace", "-o", a);
    /* a file read out of core keeps its own origin */
    snprintf(c, sizeof c,
             "{\"objects\": [{\"name\": \"moved\", \"file\": \"%s\", "
             "\"origin\": [5, 0, 0]}]}\n",
             vvb);
    write_text(bad, c);
    cli_fails("object 'moved': out of core its file's own origin", "render", bad, "--memory-limit",
              "16M", "-o", a);
    assert_int_not_equal(stat(a, &st), 0);
}

/* The text between @p key and the next ']' or '}' of @p json (a JSON
 * field's value, for comparing two outputs), in @p buf. */
static const char *
json_field(const char *json, const char *key, char *buf, size_t cap) {
    const char *p = strstr(json, key);
    assert_non_null(p);
    size_t n = strcspn(p, "]}");
    n = n < cap - 1 ? n : cap - 1;
    memcpy(buf, p, n);
    buf[n] = '\0';
    return buf;
}

/* `volvis measure --memory-limit`: the CT head's isosurface (both methods)
 * and histogram, read box by box from a .vvb's pyramid level 0 and from an
 * uncompressed NRRD by bricks, are those of the whole volume in memory:
 * voxel counting and the histogram's counts digit for digit, Marching
 * Cubes' voxels and triangles exactly and its area and volume to 1e-7
 * (the triangles' float32 vertices); what needs the whole volume is
 * refused. */
static void
test_measure(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    const char *head = vt_data("volumes/ct_head.nrrd");
    char vvb[1200], nrrd[1200];
    snprintf(vvb, sizeof vvb, "%s/head_m.vvb", outdir());
    snprintf(nrrd, sizeof nrrd, "%s/head_m.nrrd", outdir());
    cli_ok("convert", "-q", head, vvb);
    cli_ok("convert", "-q", "--no-compress", head, nrrd);
    const char *methods[2] = {"voxel", "mc"};
    for (int m = 0; m < 2; m++) {
        vt_run_result mem = run_cli("measure", head, "--iso", "300", "--method", methods[m],
                                    "--histogram", "--bins", "16", "--json");
        assert_int_equal(mem.status, 0);
        const char *files[2] = {vvb, nrrd};
        for (int f = 0; f < 2; f++) {
            vt_run_result r =
                run_cli("measure", files[f], "--iso", "300", "--method", methods[m], "--histogram",
                        "--bins", "16", "--memory-limit", "16M", "--json");
            printf("%s", r.out);
            assert_int_equal(r.status, 0);
            char a[4096], b[4096];
            assert_string_equal(json_field(r.out, "\"counts\"", a, sizeof a),
                                json_field(mem.out, "\"counts\"", b, sizeof b));
            assert_string_equal(json_field(r.out, "\"voxels\"", a, sizeof a),
                                json_field(mem.out, "\"voxels\"", b, sizeof b));
            if (m == 0) {
                assert_string_equal(json_field(r.out, "\"isosurface\"", a, sizeof a),
                                    json_field(mem.out, "\"isosurface\"", b, sizeof b));
            } else {
                const char *keys[2] = {"\"area\": ", "\"volume\": "};
                for (int k = 0; k < 2; k++) {
                    const double x = atof(strstr(r.out, keys[k]) + strlen(keys[k]));
                    const double y = atof(strstr(mem.out, keys[k]) + strlen(keys[k]));
                    assert_true(x > 0 && fabs(x - y) <= 1e-7 * y);
                }
            }
            vt_run_result_free(&r);
        }
        vt_run_result_free(&mem);
    }
    vt_run_result r = run_cli("measure", vvb, "--iso", "300", "--memory-limit", "16M");
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "out of core, box by box"));
    vt_run_result_free(&r);
    cli_expect(2, "not with --seed", "measure", vvb, "--iso", "300", "--seed", "voxel:128,128,50",
               "--memory-limit", "16M");
    cli_expect(2, NULL, "measure", vvb, "--iso", "300", "--memory-limit", "lots");
    /* a gzip NRRD cannot be read by bricks */
    cli_fails("convert it to .vvb first", "measure", head, "--iso", "300", "--memory-limit", "16M");
}

static void
test_errors(void **state) {
    (void)state;
    struct stat st;
    const char *nut = vt_data("volumes/nut.slc");
    if (stat(nut, &st) != 0)
        vt_skip("../shared/data/volumes/nut.slc is missing");
    char vvb[1200], png[1200];
    snprintf(vvb, sizeof vvb, "%s/nut_e.vvb", outdir());
    snprintf(png, sizeof png, "%s/never.png", outdir());
    cli_ok("convert", "-q", nut, vvb);
    remove(png);
    cli_fails("smaller than one brick", "render", vvb, "--memory-limit", "64K", "-o", png);
    cli_expect(2, "--memory-limit", "render", vvb, "--memory-limit", "lots", "-o", png);
    /* a gzip NRRD cannot be read by bricks */
    cli_fails("convert it to .vvb first", "render", vt_data("volumes/ct_head.nrrd"),
              "--memory-limit", "8M", "-o", png);
    /* a renderer without the region contract */
    cli_fails("splat renders no regions", "render", vvb, "--renderer", "splat", "-o", png);
    assert_int_not_equal(stat(png, &st), 0);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_convert_render),
        cmocka_unit_test(test_renderers),
        cmocka_unit_test(test_exact_shadows),
        cmocka_unit_test(test_quality2),
        cmocka_unit_test(test_levels),
        cmocka_unit_test(test_scene),
        cmocka_unit_test(test_measure),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_too_big_for_memory),
    };
    return vt_run_tests(tests, NULL, NULL);
}
