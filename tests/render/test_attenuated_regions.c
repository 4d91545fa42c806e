/*
 * napari's attenuated MIP rendered by regions (VV_REGION_ATTENUATED_MAX,
 * include/volvis/sys/renderer.h): each region keeps its own running sum of
 * exponents from 0 and gives its largest attenuated value and that sum;
 * front over back the back's values are scaled by exp(-E) of the front,
 * and the final value is classified once. On the CT head (real data):
 * - by bricks from a .vvb and by the levels of a .vvb pyramid at level 0
 *   (the one render call of vv_renderer_render with the object holding its
 *   source) against the in-memory render of the ray caster, at attenuation
 *   0 (equal to plain MIP, which it must be), napari's default 0.05 and a
 *   strong 1.0 (far from MIP: attenuation visibly matters): >= 50 dB;
 * - by coarser levels of the pyramid: the nodes of level L weigh their
 *   samples about 2^L times (vv_render_region.step_scale), so that the
 *   attenuation per world length is level 0's: against level L's voxels
 *   rendered in memory at level 0's step and attenuation per sample,
 *   >= 35 dB (without the weights 29 and 26 dB);
 * - the CLI: `volvis render --memory-limit` of the .vvb (by bricks) and
 *   `--lod` of the pyramid succeed and match `volvis render` in memory.
 * The images are written under the test's folder (`att_*.png`) to look at.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "volvis/sys/renderer.h"

#define outdir() vt_outdir("attenuated_regions")
#define run_cli(...) vt_run_cli_v(outdir(), (const char *const[]){__VA_ARGS__, NULL})

/* The head in @p mode with attenuation @p att, transfer function 100..1500. */
static vv_world *
head_world(vv_volume *head, vv_render_mode mode, double att) {
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.mode = mode;
    o.width = 120;
    o.height = 100;
    o.azimuth = 0.6;
    o.elevation = 0.3;
    o.has_tf_range = 1;
    o.tf_lo = 100;
    o.tf_hi = 1500;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, head, &o));
    w->objects[0]->attenuation = att;
    w->background = (vv_vec3){0.1, 0.1, 0.2};
    return w;
}

/* head_world(@p head, attenuated MIP, @p att), its object holding @p src,
 * by the one render call, at level @p level (-1: chosen per node, a voxel
 * at most @p voxel_pixels pixels); lod->nodes counts the nodes of each
 * level. */
static vv_image *
render_source(vv_volume *head, double att, vv_source *src, int level, double voxel_pixels,
              vv_lod *lod) {
    vv_world *w = head_world(head, VV_MODE_ATTENUATED_MIP, att);
    vt_ok(vv_object_attach_source(w->objects[0], src, 0));
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vv_render_options ro;
    vv_render_options_init(&ro);
    vv_lod_init(lod);
    lod->level = level;
    lod->voxel_pixels = voxel_pixels;
    ro.lod = lod;
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vt_ok(vv_renderer_render(r, w, &w->view, &ro, img));
    vv_renderer_free(r);
    vv_world_free(w);
    return img;
}

/* Pixels of @p img brighter than the background (not an empty image). */
static int
lit_pixels(const vv_image *img) {
    int n = 0;
    for (size_t i = 0; i < (size_t)img->width * (size_t)img->height; i++)
        n += img->rgba[4 * i] + img->rgba[4 * i + 1] + img->rgba[4 * i + 2] > 0.6f;
    return n;
}

static void
test_bricks_and_levels(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vv_volume *head = NULL;
    vt_ok(vv_volume_load(&head, vt_data("volumes/ct_head.nrrd"), NULL));
    char bricks_path[1200], levels_path[1200];
    snprintf(bricks_path, sizeof bricks_path, "%s/head.vvb", outdir());
    snprintf(levels_path, sizeof levels_path, "%s/head_levels.vvb", outdir());
    vt_ok(vt_save(head, bricks_path, VV_FORMAT_VVB, -1, VV_VVB_ZSTD));
    vt_ok(vt_save(head, levels_path, VV_FORMAT_VVB, -1, VV_VVB_ZSTD | VV_VVB_LEVELS));
    vv_cache *cache = NULL;
    vt_ok(vv_cache_new(&cache, 8 << 20)); /* less than the head's 14 MB */
    vv_source *bricks = vt_open_ooc(bricks_path, 0, cache);
    vv_source *levels = vt_open_ooc(levels_path, 1, cache);
    vv_source_stats st;
    vv_source_stats_get(bricks, &st);
    assert_true(st.n_bricks > 4); /* several regions along each ray */

    /* plain MIP, for attenuation 0 and to show the strong one differs */
    vv_world *wm = head_world(head, VV_MODE_MIP, 0);
    vv_image *mip = vt_render_reference(wm);
    vv_world_free(wm);
    vt_save_png(mip, outdir(), "att_", "mip_memory");
    const double atts[3] = {0, 0.05, 1.0};
    for (int a = 0; a < 3; a++) {
        vv_world *w = head_world(head, VV_MODE_ATTENUATED_MIP, atts[a]);
        vv_image *ref = vt_render_reference(w);
        vv_lod lod;
        vv_image *ib = render_source(head, atts[a], bricks, 0, 1, &lod);
        vv_image *il = render_source(head, atts[a], levels, 0, 1, &lod);
        assert_true(lod.nodes[0] > 4 && lod.nodes[1] == 0);
        int same = 0;
        const double db_b = vt_image_psnr(ref, ib, &same);
        const double db_l = vt_image_psnr(ref, il, &same);
        const double db_mip = vt_image_psnr(ref, mip, &same);
        const double db_bmip = vt_image_psnr(ib, mip, &same);
        printf("attenuation %.2f: by bricks %.1f dB, from the levels (level 0, %d nodes) %.1f dB "
               "against memory; memory %.1f dB and bricks %.1f dB from plain MIP; %d lit pixels\n",
               atts[a], db_b, lod.nodes[0], db_l, db_mip, db_bmip, lit_pixels(ib));
        char name[64];
        snprintf(name, sizeof name, "%.2f_memory", atts[a]);
        vt_save_png(ref, outdir(), "att_", name);
        snprintf(name, sizeof name, "%.2f_bricks", atts[a]);
        vt_save_png(ib, outdir(), "att_", name);
        snprintf(name, sizeof name, "%.2f_levels", atts[a]);
        vt_save_png(il, outdir(), "att_", name);
        assert_true(db_b >= 50 && db_l >= 50);
        assert_true(lit_pixels(ib) > 1000);
        if (atts[a] == 0) {
            assert_true(db_mip >= 60 && db_bmip >= 50); /* plain MIP */
        } else if (atts[a] >= 1) {
            assert_true(db_bmip < 30); /* attenuation visibly matters */
        }
        vv_image_free(ref);
        vv_image_free(ib);
        vv_image_free(il);
        vv_world_free(w);
    }
    /* coarser levels (lod.level 1 and 2 everywhere): a node of level L
     * weighs its samples by its step over level 0's (about 2^L), so the
     * attenuation per world length is level 0's: the image is that of the
     * level's voxels in memory sampled at level 0's step (object step
     * 0.5 / 2^L) with the attenuation per sample of level 0 (attenuation
     * 0.2 / 2^L at that step). Without the weights: 28.7 and 25.9 dB. */
    for (int L = 1; L <= 2; L++) {
        const vv_volume *h = vv_source_level(levels, L);
        const int lo[3] = {0, 0, 0}, hi[3] = {h->dims[0] - 1, h->dims[1] - 1, h->dims[2] - 1};
        vv_volume *vl = NULL;
        vt_ok(vv_source_read_box(levels, L, lo, hi, &vl));
        vv_world *w0 = head_world(head, VV_MODE_ATTENUATED_MIP, 0.2);
        vv_world *wl = head_world(vl, VV_MODE_ATTENUATED_MIP, 0.2 / (1 << L));
        wl->objects[0]->step = 0.5 / (1 << L);
        wl->view = w0->view;
        vv_image *ref0 = vt_render_reference(w0), *refl = vt_render_reference(wl);
        vv_lod lod;
        vv_image *il = render_source(head, 0.2, levels, L, 1, &lod);
        assert_true(lod.nodes[L] > 0 && lod.nodes[0] == 0);
        int same = 0;
        const double db = vt_image_psnr(refl, il, &same);
        const double db0 = vt_image_psnr(ref0, il, &same), dbl0 = vt_image_psnr(ref0, refl, &same);
        printf("attenuation 0.20 at level %d (%d nodes): %.1f dB against level %d's voxels in "
               "memory at level 0's step; %.1f dB against level 0 (level %d's voxels in memory: "
               "%.1f dB)\n",
               L, lod.nodes[L], db, L, db0, L, dbl0);
        char name[64];
        snprintf(name, sizeof name, "0.20_level%d", L);
        vt_save_png(il, outdir(), "att_", name);
        snprintf(name, sizeof name, "0.20_level%d_memory", L);
        vt_save_png(refl, outdir(), "att_", name);
        assert_true(db >= 35);
        vv_image_free(ref0);
        vv_image_free(refl);
        vv_image_free(il);
        vv_world_free(w0);
        vv_world_free(wl);
        vv_volume_free(vl);
    }
    vv_image_free(mip);
    vv_source_free(levels);
    vv_source_free(bricks);
    vv_cache_free(cache);
    vv_volume_free(head);
}

/* `volvis render` of the .vvb out of core (--memory-limit: by bricks) and
 * by level of detail (--lod) against the in-memory render of the NRRD. */
static void
test_cli(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    const char *head = vt_data("volumes/ct_head.nrrd");
    char vvb[1200], mem[1200], ooc[1200], lod[1200];
    snprintf(vvb, sizeof vvb, "%s/head_cli.vvb", outdir());
    snprintf(mem, sizeof mem, "%s/att_cli_memory.png", outdir());
    snprintf(ooc, sizeof ooc, "%s/att_cli_bricks.png", outdir());
    snprintf(lod, sizeof lod, "%s/att_cli_lod.png", outdir());
    vt_run_result r = run_cli("convert", "-q", head, vvb);
    assert_int_equal(r.status, 0);
    vt_run_result_free(&r);
#define ATT_ARGS                                                                                   \
    "--mode", "attenuated-mip", "--attenuation", "0.5", "--tf", "100:1500", "--size", "160x128"
    r = run_cli("render", head, ATT_ARGS, "--set", "refinement=off", "-q", "-o", mem);
    if (r.status != 0)
        fail_msg("%s", r.err);
    vt_run_result_free(&r);
    r = run_cli("render", vvb, "--memory-limit", "4M", ATT_ARGS, "-o", ooc);
    if (r.status != 0)
        fail_msg("%s", r.err);
    assert_non_null(strstr(r.out, "out of core: "));
    vt_run_result_free(&r);
    /* a voxel of level 0 covers under a pixel here: level 0 where it shows */
    r = run_cli("render", vvb, "--lod", "0.5", ATT_ARGS, "-o", lod);
    if (r.status != 0)
        fail_msg("%s", r.err);
    assert_non_null(strstr(r.out, "out of core from 3 levels"));
    vt_run_result_free(&r);
#undef ATT_ARGS
    const double db_ooc = vt_png_psnr(mem, ooc), db_lod = vt_png_psnr(mem, lod);
    printf("volvis render attenuated-mip 0.5: --memory-limit 4M %.1f dB, --lod 0.5 %.1f dB "
           "against memory\n",
           db_ooc, db_lod);
    assert_true(db_ooc >= 50);
    assert_true(db_lod >= 50);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bricks_and_levels),
        cmocka_unit_test(test_cli),
    };
    return vt_run_tests(tests, NULL, NULL);
}
