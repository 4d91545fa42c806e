/*
 * Several volume objects in one World out of core
 * (vv_renderer_render_sources, src/render/sources_render.c; issue 29:
 * "several bricked volumes (and in-memory ones) in one World"):
 * - two CT heads side by side, the left read by bricks from a .vvb (4 MiB
 *   budget), the right from the levels of a .vvb pyramid at level 0, and
 *   the same two with the right one in memory: against the in-memory
 *   render of the World (the ray caster, every pixel cast), MIP, MinIP and
 *   X-ray bit for bit, composite and iso >= 50 dB, a composite object
 *   beside a MIP one >= 50 dB; every brick read at most once a frame;
 * - overlapping MIP objects combine by the maximum (bit for bit), while
 *   overlapping composite objects are refused, naming both;
 * - one object alone gives vv_renderer_render_bricks's image bit for bit;
 * - refusals: the ray tracer with two objects (its shadows fall between
 *   them), a geometric object, an object named twice, bad arguments.
 * The images are written under the test's folder (`sources_*.png`).
 */
#include "testutil.h"

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

static void
save(const vv_image *img, const char *name) {
    char path[1200];
    snprintf(path, sizeof path, "%s/sources_%s.png", outdir(), name);
    vt_ok(vv_image_write_png(img, path, 1.0, 0));
}

/* The in-memory render of @p w, every pixel cast. */
static vv_image *
reference(vv_world *w) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vt_ok(vv_renderer_set_option(r, "refinement", "off"));
    vv_render_options ro;
    vv_render_options_init(&ro);
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vt_ok(vv_renderer_render(r, w, &w->view, &ro, img));
    vv_renderer_free(r);
    return img;
}

static vv_status
render_sources(vv_world *w, const vv_object_source *src, int n, vv_image **out) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    vv_render_options ro;
    vv_render_options_init(&ro);
    vv_lod lod;
    vv_lod_init(&lod);
    lod.level = 0;
    vt_ok(vv_image_new(out, w->view.width, w->view.height));
    vv_status s = vv_renderer_render_sources(r, w, src, n, &w->view, &ro, &lod, *out);
    vv_renderer_free(r);
    return s;
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
    vt_ok(vv_volume_write_vvb(head, bricks_path, VV_VVB_ZSTD));
    vt_ok(vv_volume_write_vvb(head, levels_path, VV_VVB_ZSTD | VV_VVB_LEVELS));
    vv_bricked *b = NULL;
    vt_ok(vv_bricked_open(&b, bricks_path, NULL, 4 << 20));
    vv_pyramid *p = NULL;
    vt_ok(vv_pyramid_open(&p, levels_path, 0, -1, 8 << 20, NULL));
    vv_brick_source bs;
    vv_bricked_source(b, &bs);
    vv_multires_source ms;
    vv_pyramid_source(p, &ms);
    int nb[3];
    vv_bricked_grid(b, nb);

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
            vv_image *ref = reference(w);
            vv_object_source src[2];
            vv_object_source_init(&src[0], 0);
            src[0].bricks = &bs;
            vv_object_source_init(&src[1], 1);
            src[1].multires = right_in_memory ? NULL : &ms;
            vv_bricked_stats before, after;
            vv_bricked_stats_get(b, &before);
            vv_image *img = NULL;
            vt_ok(render_sources(w, src, 2, &img));
            vv_bricked_stats_get(b, &after);
            int same = 0;
            const double db = vt_image_psnr(ref, img, &same);
            const int proj = pairs[pi][0] != VV_MODE_COMPOSITE && pairs[pi][0] != VV_MODE_ISO &&
                             pairs[pi][1] != VV_MODE_COMPOSITE && pairs[pi][1] != VV_MODE_ISO;
            printf("%s + %s, right %s: %s %.1f dB; %llu bricks read, %llu skipped (of %d)\n",
                   mode_name(pairs[pi][0]), mode_name(pairs[pi][1]),
                   right_in_memory ? "in memory" : "from the pyramid",
                   same ? "bit-identical" : "differs", db,
                   (unsigned long long)(after.loads - before.loads + after.hits - before.hits),
                   (unsigned long long)(after.skipped - before.skipped), nb[0] * nb[1] * nb[2]);
            if (proj)
                assert_true(same);
            else
                assert_true(db >= 50);
            assert_true(after.loads - before.loads + after.hits - before.hits <=
                        (uint64_t)(nb[0] * nb[1] * nb[2]));
            if (!right_in_memory) {
                char name[64];
                snprintf(name, sizeof name, "%s_%s", mode_name(pairs[pi][0]),
                         mode_name(pairs[pi][1]));
                save(img, name);
                snprintf(name, sizeof name, "%s_%s_memory", mode_name(pairs[pi][0]),
                         mode_name(pairs[pi][1]));
                save(ref, name);
            }
            vv_image_free(img);
            vv_image_free(ref);
            vv_world_free(w);
        }

    /* overlapping projections combine by the maximum: bit for bit */
    {
        vv_world *w = two_heads(head, VV_MODE_MIP, VV_MODE_MIP, 0.5);
        vv_image *ref = reference(w);
        vv_object_source src[2];
        vv_object_source_init(&src[0], 0);
        src[0].bricks = &bs;
        vv_object_source_init(&src[1], 1);
        src[1].multires = &ms;
        vv_image *img = NULL;
        vt_ok(render_sources(w, src, 2, &img));
        int same = 0;
        vt_image_psnr(ref, img, &same);
        assert_true(same);
        save(img, "mip_overlapping");
        vv_image_free(img);
        vv_image_free(ref);
        vv_world_free(w);
    }
    /* overlapping composite objects: refused, both named */
    {
        vv_world *w = two_heads(head, VV_MODE_COMPOSITE, VV_MODE_COMPOSITE, 0.5);
        vv_object_source src[1];
        vv_object_source_init(&src[0], 0);
        src[0].bricks = &bs;
        vv_image *img = NULL;
        assert_int_equal(render_sources(w, src, 1, &img), VV_ERR_UNSUPPORTED);
        assert_non_null(strstr(vv_error_message(), "'left' and 'right' overlap"));
        vv_image_free(img);
        vv_world_free(w);
    }
    /* one object: vv_renderer_render_bricks's image, bit for bit */
    {
        vv_world *w = two_heads(head, VV_MODE_COMPOSITE, VV_MODE_COMPOSITE, 1.1);
        w->objects[1]->visible = 0;
        vv_object_source src[1];
        vv_object_source_init(&src[0], 0);
        src[0].bricks = &bs;
        vv_image *img = NULL, *one = NULL;
        vt_ok(render_sources(w, src, 1, &img));
        vv_renderer *r = NULL;
        vt_ok(vv_renderer_new(&r, "raycast"));
        vv_render_options ro;
        vv_render_options_init(&ro);
        vt_ok(vv_image_new(&one, w->view.width, w->view.height));
        vt_ok(vv_renderer_render_bricks(r, w, 0, &bs, &w->view, &ro, one));
        int same = 0;
        vt_image_psnr(one, img, &same);
        assert_true(same);
        /* nothing visible: the background, transparent, at no depth */
        w->objects[0]->visible = 0;
        vt_ok(vv_renderer_render_sources(r, w, src, 1, &w->view, &ro, NULL, one));
        for (size_t i = 0; i < (size_t)one->width * (size_t)one->height; i++) {
            assert_float_equal(one->rgba[4 * i + 2], 0.3f, 1e-7);
            assert_float_equal(one->rgba[4 * i + 3], 0.0f, 0);
            assert_true(isinf(one->depth[i]));
        }
        w->objects[0]->visible = 1;
        /* refusals: the ray tracer with two objects; an object named twice */
        w->objects[1]->visible = 1;
        vv_renderer *rt = NULL;
        vt_ok(vv_renderer_new(&rt, "raytrace"));
        assert_int_equal(vv_renderer_render_sources(rt, w, src, 1, &w->view, &ro, NULL, one),
                         VV_ERR_UNSUPPORTED);
        assert_non_null(strstr(vv_error_message(), "raytrace"));
        vv_object_source twice[2] = {src[0], src[0]};
        assert_int_equal(vv_renderer_render_sources(r, w, twice, 2, &w->view, &ro, NULL, one),
                         VV_ERR_INVALID);
        assert_int_equal(vv_renderer_render_sources(r, w, NULL, 1, &w->view, &ro, NULL, one),
                         VV_ERR_INVALID);
        /* a geometric object */
        vv_object *ball = NULL;
        vt_ok(vv_object_new_geometry(&ball, VV_OBJECT_SPHERE, "ball"));
        vt_ok(vv_world_add_object(w, ball));
        assert_int_equal(vv_renderer_render_sources(r, w, src, 1, &w->view, &ro, NULL, one),
                         VV_ERR_UNSUPPORTED);
        assert_non_null(strstr(vv_error_message(), "'ball'"));
        vv_renderer_free(rt);
        vv_renderer_free(r);
        vv_image_free(one);
        vv_image_free(img);
        vv_world_free(w);
    }
    vv_pyramid_free(p);
    vv_bricked_free(b);
    vv_volume_free(head);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_heads),
    };
    return vt_run_tests(tests, NULL, NULL);
}
