/*
 * Several volume objects in one World out of core, each holding its source
 * (vv_object_attach_source), drawn by the one render call
 * (vv_renderer_render, which chooses the sources driver:
 * src/render/driver_sources.c; issue 29: "several bricked volumes (and
 * in-memory ones) in one World"; issue 62: one cache, one render call):
 * - two CT heads side by side, the left read by bricks from a .vvb, the
 *   right from the levels of a .vvb pyramid at level 0 (one cache of
 *   12 MiB for both), and
 *   the same two with the right one in memory: against the in-memory
 *   render of the World (the ray caster, every pixel cast), MIP, MinIP and
 *   X-ray bit for bit, composite and iso >= 50 dB, a composite object
 *   beside a MIP one >= 50 dB; every brick read at most once a frame;
 * - overlapping MIP objects combine by the maximum (bit for bit), while
 *   overlapping composite objects are refused, naming both;
 * - one object alone gives the region driver's image bit for bit;
 * - refusals: the ray tracer with two objects (its shadows fall between
 *   them), a geometric object.
 * The images are written under the test's folder (`sources_*.png`).
 */
#include "testutil.h"

#include "render/drivers.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define outdir() vt_outdir("render_sources")

/* Two heads in mode @p m0 and @p m1, the second moved along x by @p dx
 * times the head's width (1.1: apart; 0.5: overlapping), the view framing
 * both. */
static vv_world *
two_heads(vv_volume *head, vv_render_mode m0, vv_render_mode m1, double dx) {
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.mode = m0;
    o.width = 120;
    o.height = 72;
    o.azimuth = 0.5;
    o.elevation = 0.35;
    o.has_tf_range = m0 != VV_MODE_XRAY;
    o.tf_lo = 100;
    o.tf_hi = 1500;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, head, &o));
    w->background = (vv_vec3){0.1, 0.2, 0.3};
    vv_object *b = NULL;
    vt_ok(vv_object_clone(&b, w->objects[0]));
    snprintf(b->name, sizeof b->name, "right");
    snprintf(w->objects[0]->name, sizeof w->objects[0]->name, "left");
    b->mode = m1;
    b->isovalue = w->objects[0]->isovalue = 800;
    b->position.x += dx * head->dims[0] * head->spacing[0];
    vt_ok(vv_world_add_object(w, b));
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    return w;
}

/* @p w drawn by the one render call with level 0 everywhere; the objects
 * hold their sources (attach). */
static vv_status
render_sources(vv_world *w, vv_image **out) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vv_render_options ro;
    vv_render_options_init(&ro);
    vv_lod lod;
    vv_lod_init(&lod);
    lod.level = 0;
    ro.lod = &lod;
    vt_ok(vv_image_new(out, w->view.width, w->view.height));
    vv_status s = vv_renderer_render(r, w, &w->view, &ro, *out);
    vv_renderer_free(r);
    return s;
}

/* Object @p i of @p w shows @p src (its volume the in-memory head, the
 * proxy of the same box: the region renders read the source). */
static void
attach(vv_world *w, int i, vv_source *src) {
    if (src)
        vt_ok(vv_object_attach_source(w->objects[i], src, 0));
}

static const char *
mode_name(vv_render_mode m) {
    static const char *const names[] = {"composite", "mip", "minip", "xray", "iso"};
    return names[m];
}

static void
test_two_heads(void **state) {
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
    vt_ok(vv_cache_new(&cache, 12 << 20));
    vv_source *bricks = vt_open_ooc(bricks_path, 0, cache);
    vv_source *levels = vt_open_ooc(levels_path, 1, cache);
    vv_brick_source bs;
    assert_true(vv_source_brick_view(bricks, &bs));
    vv_source_stats st0;
    vv_source_stats_get(bricks, &st0);
    const int n_bricks = st0.n_bricks;

    const vv_render_mode pairs[][2] = {
        {VV_MODE_COMPOSITE, VV_MODE_COMPOSITE},
        {VV_MODE_MIP, VV_MODE_MIP},
        {VV_MODE_MINIP, VV_MODE_MINIP},
        {VV_MODE_XRAY, VV_MODE_XRAY},
        {VV_MODE_ISO, VV_MODE_ISO},
        {VV_MODE_COMPOSITE, VV_MODE_MIP},
    };
    for (size_t pi = 0; pi < sizeof pairs / sizeof pairs[0]; pi++)
        for (int right_in_memory = 0; right_in_memory < 2; right_in_memory++) {
            vv_world *w = two_heads(head, pairs[pi][0], pairs[pi][1], 1.1);
            vv_image *ref = vt_render_reference(w);
            attach(w, 0, bricks);
            attach(w, 1, right_in_memory ? NULL : levels);
            vv_source_stats before, after;
            vv_source_stats_get(bricks, &before);
            vv_image *img = NULL;
            vt_ok(render_sources(w, &img));
            vv_source_stats_get(bricks, &after);
            int same = 0;
            const double db = vt_image_psnr(ref, img, &same);
            const int proj = pairs[pi][0] != VV_MODE_COMPOSITE && pairs[pi][0] != VV_MODE_ISO &&
                             pairs[pi][1] != VV_MODE_COMPOSITE && pairs[pi][1] != VV_MODE_ISO;
            printf("%s + %s, right %s: %s %.1f dB; %llu bricks read, %llu skipped (of %d)\n",
                   mode_name(pairs[pi][0]), mode_name(pairs[pi][1]),
                   right_in_memory ? "in memory" : "from the pyramid",
                   same ? "bit-identical" : "differs", db,
                   (unsigned long long)(after.loads - before.loads + after.hits - before.hits),
                   (unsigned long long)(after.skipped - before.skipped), n_bricks);
            if (proj)
                assert_true(same);
            else
                assert_true(db >= 50);
            assert_true(after.loads - before.loads + after.hits - before.hits <=
                        (uint64_t)n_bricks);
            if (!right_in_memory) {
                char name[64];
                snprintf(name, sizeof name, "%s_%s", mode_name(pairs[pi][0]),
                         mode_name(pairs[pi][1]));
                vt_save_png(img, outdir(), "sources_", name);
                snprintf(name, sizeof name, "%s_%s_memory", mode_name(pairs[pi][0]),
                         mode_name(pairs[pi][1]));
                vt_save_png(ref, outdir(), "sources_", name);
            }
            vv_image_free(img);
            vv_image_free(ref);
            vv_world_free(w);
        }

    /* overlapping projections combine by the maximum: bit for bit */
    {
        vv_world *w = two_heads(head, VV_MODE_MIP, VV_MODE_MIP, 0.5);
        vv_image *ref = vt_render_reference(w);
        attach(w, 0, bricks);
        attach(w, 1, levels);
        vv_image *img = NULL;
        vt_ok(render_sources(w, &img));
        int same = 0;
        vt_image_psnr(ref, img, &same);
        assert_true(same);
        vt_save_png(img, outdir(), "sources_", "mip_overlapping");
        vv_image_free(img);
        vv_image_free(ref);
        vv_world_free(w);
    }
    /* overlapping composite objects: refused, both named */
    {
        vv_world *w = two_heads(head, VV_MODE_COMPOSITE, VV_MODE_COMPOSITE, 0.5);
        attach(w, 0, bricks);
        vv_image *img = NULL;
        assert_int_equal(render_sources(w, &img), VV_ERR_UNSUPPORTED);
        assert_non_null(strstr(vv_error_message(), "'left' and 'right' overlap"));
        vv_image_free(img);
        vv_world_free(w);
    }
    /* one object: the region driver's image, bit for bit */
    {
        vv_world *w = two_heads(head, VV_MODE_COMPOSITE, VV_MODE_COMPOSITE, 1.1);
        w->objects[1]->visible = 0;
        attach(w, 0, bricks);
        vv_image *img = NULL, *one = NULL;
        vt_ok(render_sources(w, &img));
        vv_renderer *r = NULL;
        vt_ok(vv_renderer_new(&r, "raycast"));
        vv_render_options ro;
        vv_render_options_init(&ro);
        vt_ok(vv_image_new(&one, w->view.width, w->view.height));
        vt_ok(drv_render_bricks(drv_renderer_of(r, &(drv_renderer){0}), w, 0, &bs, &w->view, &ro,
                                one));
        int same = 0;
        vt_image_psnr(one, img, &same);
        assert_true(same);
        /* nothing visible: the background, transparent, at no depth */
        w->objects[0]->visible = 0;
        vt_ok(drv_render_sources(drv_renderer_of(r, &(drv_renderer){0}), w, &w->view, &ro, NULL,
                                 one));
        for (size_t i = 0; i < (size_t)one->width * (size_t)one->height; i++) {
            assert_float_equal(one->rgba[4 * i + 2], 0.3f, 1e-7);
            assert_float_equal(one->rgba[4 * i + 3], 0.0f, 0);
            assert_true(isinf(one->depth[i]));
        }
        w->objects[0]->visible = 1;
        /* refusals: the ray tracer with two objects */
        w->objects[1]->visible = 1;
        vv_renderer *rt = NULL;
        vt_ok(vv_renderer_new(&rt, "raytrace"));
        assert_int_equal(vv_renderer_render(rt, w, &w->view, &ro, one), VV_ERR_UNSUPPORTED);
        assert_non_null(strstr(vv_error_message(), "raytrace"));
        /* a geometric object */
        vv_object *ball = NULL;
        vt_ok(vv_object_new_geometry(&ball, VV_OBJECT_SPHERE, "ball"));
        vt_ok(vv_world_add_object(w, ball));
        assert_int_equal(vv_renderer_render(r, w, &w->view, &ro, one), VV_ERR_UNSUPPORTED);
        assert_non_null(strstr(vv_error_message(), "'ball'"));
        vv_renderer_free(rt);
        vv_renderer_free(r);
        vv_image_free(one);
        vv_image_free(img);
        vv_world_free(w);
    }
    /* one cache for both files: its peak within its budget */
    vv_cache_stats cs;
    vv_cache_stats_get(cache, &cs);
    printf("one cache for both: peak %.1f MiB of %.1f MiB, %d sources\n", cs.peak / 1048576.0,
           cs.limit / 1048576.0, cs.sources);
    assert_int_equal(cs.sources, 2);
    assert_true(cs.peak <= cs.limit);
    vv_source_free(levels);
    vv_source_free(bricks);
    vv_cache_free(cache);
    vv_volume_free(head);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_heads),
    };
    return vt_run_tests(tests, NULL, NULL);
}
