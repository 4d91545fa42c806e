/*
 * Out-of-core volumes (the reader src/io/store/bricked.c, the render driver
 * src/render/driver_region.c over the region contract):
 * - the CT head written as .vvb (with coarse levels), raw and raw-encoded
 *   NRRD, opened as bricked volumes with a 4 MB memory budget and rendered
 *   brick by brick by every renderer with the region contract (raycast;
 *   raytrace at quality 1, one ray a pixel, with its shadows traced through
 *   the World's whole volume): composite >= 50 dB against the in-memory
 *   render, MIP and MinIP bit for bit; each brick read at most once a frame
 *   (counted), bricks outside the transfer function skipped unread, the
 *   cache within its budget; a renderer without the contract is refused;
 *   an isosurface by raycast >= 60 dB against memory (bricks below the
 *   isovalue skipped unread), raytrace's too (refused with a coarse proxy
 *   as the World's volume); X-ray bit for bit;
 * - the proxy (coarse whole volume) spans the same world box;
 * - a small synthetic volume: .vvb round trip voxel for voxel;
 * - bad input: a .vvb whose index sends a brick past the end of the file,
 *   a wrong brick count, a truncated file, a memory limit smaller than one
 *   brick: clear errors.
 */
#include "testutil.h"

#include "io/store/bricked.h"
#include "render/drivers.h"

#include "volvis/sys/renderer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define outdir() vt_outdir("bricks")

/* The head's World at azimuth @p az: the transfer function 100..1500, or
 * (X-ray) the default ramp over the range. */
static vv_world *
head_world(vv_volume *v, vv_render_mode mode, double az) {
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.mode = mode;
    o.width = 96;
    o.height = 88;
    o.azimuth = az;
    o.elevation = 0.3;
    o.has_tf_range = mode != VV_MODE_XRAY;
    o.tf_lo = 100;
    o.tf_hi = 1500;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    return w;
}

/* Renders the head out of core from @p path and compares with memory. */
static void
check_source(vv_volume *head, const char *path, const vv_raw_params *raw, const char *what,
             int full) {
    vv_bricked *b = NULL;
    vt_ok(vv_bricked_open(&b, path, raw, vt_cache(4 << 20)));
    const vv_volume *h = vv_bricked_header(b);
    for (int a = 0; a < 3; a++)
        assert_int_equal(h->dims[a], head->dims[a]);
    assert_true(h->range[0] == head->range[0] && h->range[1] == head->range[1]);
    int nb[3];
    vv_bricked_grid(b, nb);
    const int nbricks = nb[0] * nb[1] * nb[2];
    const vv_render_mode modes[3] = {VV_MODE_COMPOSITE, VV_MODE_MIP, VV_MODE_MINIP};
    const char *const renderers[2] = {"raycast", "raytrace"};
    int frames = 0;
    vv_brick_source src;
    vv_bricked_source(b, &src);
    /* full: every mode from two views; else composite and mip from one */
    for (int ri = 0; ri < 2; ri++)
        for (int m = 0; m < (full ? 3 : 2); m++)
            for (int view = 0; view < (full ? 2 : 1); view++) {
                if (ri == 1 && view == 1)
                    continue; /* the ray tracer from one view */
                vv_world *w = head_world(head, modes[m], view ? 2.5 : 0.6);
                vv_renderer *mem = NULL, *ooc = NULL;
                vt_ok(vv_renderer_new(&mem, renderers[ri]));
                vt_ok(vv_renderer_new(&ooc, renderers[ri]));
                /* region renders cast every pixel (no adaptive refinement) */
                vt_ok(vv_renderer_set_option(mem, "refinement", "off"));
                vv_render_options ro;
                vv_render_options_init(&ro);
                /* region renders trace one ray a pixel: the ray tracer's quality 1 */
                ro.quality = ri == 1 ? 1 : 2;
                vv_image *ref = NULL, *img = NULL;
                vt_ok(vv_image_new(&ref, w->view.width, w->view.height));
                vt_ok(vv_image_new(&img, w->view.width, w->view.height));
                vt_ok(vv_renderer_render(mem, w, &w->view, &ro, ref));
                vv_bricked_stats before;
                vv_bricked_stats_get(b, &before);
                vt_ok(drv_render_bricks(drv_renderer_of(ooc, &(drv_renderer){0}), w, 0, &src,
                                        &w->view, &ro, img));
                frames++;
                vv_bricked_stats after;
                vv_bricked_stats_get(b, &after);
                int same = 0;
                const double db = vt_image_psnr(ref, img, &same);
                printf("%s %s %s view %d: %s %.1f dB; read %llu bricks, %llu from the cache, "
                       "%llu skipped (of %d)\n",
                       what, renderers[ri],
                       m == 0   ? "composite"
                       : m == 1 ? "mip"
                                : "minip",
                       view, same ? "bit-identical" : "differs", db,
                       (unsigned long long)(after.loads - before.loads),
                       (unsigned long long)(after.hits - before.hits),
                       (unsigned long long)(after.skipped - before.skipped), nbricks);
                if (m == 0) {
                    /* the ray caster takes the whole render's samples: its
                     * early ray termination carried across the bricks
                     * (vv_render_region.front; without it, 58 dB); the ray
                     * tracer's regions end their rays on their own */
                    assert_true(db >= (ri == 0 ? 100 : 50));
                    /* the air around the head is transparent under 100..1500 */
                    assert_true(after.skipped > before.skipped);
                } else {
                    assert_true(same);
                }
                /* every brick at most once a frame */
                assert_true(after.loads - before.loads + after.hits - before.hits <=
                            (uint64_t)nbricks);
                vv_image_free(ref);
                vv_image_free(img);
                vv_renderer_free(mem);
                vv_renderer_free(ooc);
                vv_world_free(w);
            }
    {
        /* an isosurface: each brick finds the crossings between its samples
         * and the one before them (read from its ghost voxels), the nearest
         * wins; a brick's one ghost voxel leaves the gradient of a crossing
         * just before its box one-sided, so shading may differ in the last
         * bits there; bricks wholly below the isovalue are skipped unread */
        vv_world *w = head_world(head, VV_MODE_ISO, 0.6);
        w->objects[0]->isovalue = 600;
        vv_renderer *mem = NULL, *ooc = NULL, *rt = NULL;
        vt_ok(vv_renderer_new(&mem, "raycast"));
        vt_ok(vv_renderer_new(&ooc, "raycast"));
        vt_ok(vv_renderer_new(&rt, "raytrace"));
        vt_ok(vv_renderer_set_option(mem, "refinement", "off"));
        vv_image *ref = NULL, *img = NULL;
        vt_ok(vv_image_new(&ref, w->view.width, w->view.height));
        vt_ok(vv_image_new(&img, w->view.width, w->view.height));
        vt_ok(vv_renderer_render(mem, w, &w->view, NULL, ref));
        vv_bricked_stats before, after;
        vv_bricked_stats_get(b, &before);
        vt_ok(drv_render_bricks(drv_renderer_of(ooc, &(drv_renderer){0}), w, 0, &src, &w->view,
                                NULL, img));
        frames++;
        vv_bricked_stats_get(b, &after);
        int same = 0, lit = 0;
        const double db = vt_image_psnr(ref, img, &same);
        for (size_t i = 0; i < (size_t)img->width * img->height; i++)
            lit += img->rgba[4 * i + 3] > 0.5f;
        printf("%s raycast iso 600: %s %.1f dB, %d pixels of surface; %llu bricks skipped\n", what,
               same ? "bit-identical" : "differs", db, lit,
               (unsigned long long)(after.skipped - before.skipped));
        assert_true(db >= 60);
        assert_true(lit > 1000);
        assert_true(after.skipped > before.skipped);
        /* the ray tracer's isosurface by bricks (its shadows through the
         * World's whole volume) against its in-memory render at quality 1
         * (one ray a pixel, as its regions trace) */
        vv_render_options ro;
        vv_render_options_init(&ro);
        ro.quality = 1;
        vv_renderer *rtm = NULL;
        vt_ok(vv_renderer_new(&rtm, "raytrace"));
        vt_ok(vv_renderer_set_option(rtm, "refinement", "off"));
        vt_ok(vv_renderer_render(rtm, w, &w->view, &ro, ref));
        vt_ok(drv_render_bricks(drv_renderer_of(rt, &(drv_renderer){0}), w, 0, &src, &w->view, &ro,
                                img));
        frames++;
        const double dbr = vt_image_psnr(ref, img, &same);
        printf("%s raytrace iso 600: %s %.1f dB\n", what, same ? "bit-identical" : "differs", dbr);
        assert_true(dbr >= 60);
        vv_renderer_free(rtm);
        /* with a coarse proxy as the World's volume (out of core from a
         * file) its shadows would band the surface: refused (after the first
         * brick is read) */
        vv_volume *pv = NULL;
        vt_ok(vv_bricked_proxy(b, 64, &pv));
        vv_world *wp = head_world(pv, VV_MODE_ISO, 0.6);
        wp->objects[0]->isovalue = 600;
        assert_int_equal(drv_render_bricks(drv_renderer_of(rt, &(drv_renderer){0}), wp, 0, &src,
                                           &wp->view, &ro, img),
                         VV_ERR_UNSUPPORTED);
        frames++;
        assert_non_null(strstr(vv_error_message(), "iso regions need the whole volume"));
        vv_world_free(wp);
        vv_volume_free(pv);
        /* X-ray: each brick's sums and counts add up, the mean classified at
         * the end as the whole render classifies it */
        vv_world *wx = head_world(head, VV_MODE_XRAY, 0.6);
        vt_ok(vv_renderer_render(mem, wx, &wx->view, NULL, ref));
        vt_ok(drv_render_bricks(drv_renderer_of(ooc, &(drv_renderer){0}), wx, 0, &src, &wx->view,
                                NULL, img));
        vv_world_free(wx);
        frames++;
        const double dbx = vt_image_psnr(ref, img, &same);
        int depths = 1;
        for (size_t i = 0; i < (size_t)img->width * img->height; i++)
            depths &= ref->depth[i] == img->depth[i];
        int shown = 0; /* pixels of the head, not a black image */
        for (size_t i = 0; i < (size_t)img->width * img->height; i++)
            shown += img->rgba[4 * i] > 0.01f;
        printf("%s raycast xray: %s %.1f dB, depths %s, %d pixels of the head\n", what,
               same ? "bit-identical" : "differs", dbx, depths ? "the same" : "differ", shown);
        assert_true(same && depths);
        assert_true(shown > 1000);
        vv_image_free(ref);
        vv_image_free(img);
        vv_renderer_free(mem);
        vv_renderer_free(ooc);
        vv_renderer_free(rt);
        vv_world_free(w);
    }
    {
        /* a renderer without the region contract is refused, naming it */
        vv_world *w = head_world(head, VV_MODE_COMPOSITE, 0.6);
        vv_renderer *sp = NULL;
        vv_image *img = NULL;
        vt_ok(vv_renderer_new(&sp, "splat"));
        vt_ok(vv_image_new(&img, w->view.width, w->view.height));
        assert_int_equal(drv_render_bricks(drv_renderer_of(sp, &(drv_renderer){0}), w, 0, &src,
                                           &w->view, NULL, img),
                         VV_ERR_UNSUPPORTED);
        assert_non_null(strstr(vv_error_message(), "splat renders no regions"));
        vv_image_free(img);
        vv_renderer_free(sp);
        vv_world_free(w);
    }
    vv_bricked_stats st;
    vv_bricked_stats_get(b, &st);
    assert_true(st.max_loads <= frames);
    assert_true(st.evictions > 0); /* 4 MB does not hold the head's 14 MB */
    assert_true(st.peak_bytes <= (uint64_t)4 << 20);
    /* the proxy spans the same world box */
    vv_volume *p = NULL;
    vt_ok(vv_bricked_proxy(b, 64, &p));
    for (int a = 0; a < 3; a++) {
        assert_true(p->dims[a] <= 64);
        assert_near((p->dims[a] - 1) * p->spacing[a], (head->dims[a] - 1) * head->spacing[a], 1e-9);
    }
    vv_volume_free(p);
    vv_bricked_free(b);
}

static void
test_ct_head(void **state) {
    (void)state;
    vv_volume *head = NULL;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vt_ok(vv_volume_load(&head, vt_data("volumes/ct_head.nrrd"), NULL));
    const char *dir = outdir();
    char vvb[1200], raw[1200], nrrd[1200];
    snprintf(vvb, sizeof vvb, "%s/head.vvb", dir);
    snprintf(raw, sizeof raw, "%s/head.raw", dir);
    snprintf(nrrd, sizeof nrrd, "%s/head_raw.nrrd", dir);
    vt_ok(vt_save(head, vvb, VV_FORMAT_VVB, -1, 1));
    vt_ok(vt_save(head, nrrd, VV_FORMAT_NRRD, 0, 0));
    FILE *f = fopen(raw, "wb");
    assert_non_null(f);
    const size_t n = (size_t)head->dims[0] * head->dims[1] * head->dims[2];
    assert_int_equal(fwrite(head->data, 2, n, f), n);
    fclose(f);
    check_source(head, vvb, NULL, "vvb", 1);
    /* zstd bricks: the same voxels and images, a smaller file */
    char vvbz[1200];
    snprintf(vvbz, sizeof vvbz, "%s/head_zstd.vvb", dir);
    vt_ok(vt_save(head, vvbz, VV_FORMAT_VVB, -1, VV_VVB_ZSTD));
    struct stat sr, sz;
    assert_int_equal(stat(vvb, &sr), 0);
    assert_int_equal(stat(vvbz, &sz), 0);
    printf("head.vvb %lld bytes raw, %lld with zstd bricks\n", (long long)sr.st_size,
           (long long)sz.st_size);
    assert_true(sz.st_size < sr.st_size * 3 / 4);
    check_source(head, vvbz, NULL, "vvb zstd", 0);
    vv_raw_params rp;
    vv_raw_params_init(&rp);
    memcpy(rp.dims, head->dims, sizeof rp.dims);
    memcpy(rp.spacing, head->spacing, sizeof rp.spacing);
    memcpy(rp.origin, head->origin, sizeof rp.origin);
    rp.type = head->type;
    check_source(head, raw, &rp, "raw", 0);
    check_source(head, nrrd, NULL, "nrrd", 0);

    /* a memory limit smaller than one brick */
    vv_bricked *b = NULL;
    assert_int_equal(vv_bricked_open(&b, vvb, NULL, vt_cache(100000)), VV_ERR_LIMIT);
    assert_null(b);
    assert_non_null(strstr(vv_error_message(), "smaller than one brick"));
    /* a gzip NRRD cannot be read by bricks */
    assert_int_equal(vv_bricked_open(&b, vt_data("volumes/ct_head.nrrd"), NULL, vt_cache(0)),
                     VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "convert it to .vvb first"));
    vv_volume_free(head);
}

/* Quality 2 by regions: raytrace's region render names its supersampling
 * (vv_region_image.supersample, not at quality 1; raycast never), traces
 * the points it is given (vv_render_region.rays: a point at a pixel's
 * centre is that pixel of the plain region render, bit for bit), refuses
 * an image with fewer entries than points; and drv_render_bricks at
 * quality 2 gives the in-memory supersampled image (MIP bit for bit,
 * composite >= 50 dB), reading the bricks a second time. */
static void
test_quality2_regions(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vv_volume *head = NULL;
    vt_ok(vv_volume_load(&head, vt_data("volumes/ct_head.nrrd"), NULL));
    char vvb[1200];
    snprintf(vvb, sizeof vvb, "%s/head_q2.vvb", outdir());
    vt_ok(vt_save(head, vvb, VV_FORMAT_VVB, -1, VV_VVB_ZSTD));
    vv_bricked *b = NULL;
    vt_ok(vv_bricked_open(&b, vvb, NULL, vt_cache(4 << 20)));
    vv_brick_source src;
    vv_bricked_source(b, &src);
    int nb[3];
    vv_bricked_grid(b, nb);
    const int nbricks = nb[0] * nb[1] * nb[2];
    vv_render_options ro;
    vv_render_options_init(&ro); /* quality 2 */

    /* the contract, on one region: the whole volume */
    vv_world *w = head_world(head, VV_MODE_MIP, 0.6);
    const int W = w->view.width, H = w->view.height;
    vv_renderer *rt = NULL, *rc = NULL;
    vt_ok(vv_renderer_new(&rt, "raytrace"));
    vt_ok(vv_renderer_new(&rc, "raycast"));
    vv_render_region rg;
    memset(&rg, 0, sizeof rg);
    rg.voxels = head;
    for (int a = 0; a < 3; a++) {
        rg.dims[a] = head->dims[a];
        rg.lo[a] = -INFINITY;
        rg.hi[a] = INFINITY;
    }
    float *keys = malloc(sizeof(float) * (size_t)W * (size_t)H);
    assert_non_null(keys);
    vv_region_image pix = {.key = keys};
    vt_ok(vv_image_new(&pix.image, W, H));
    vt_ok(vv_renderer_render_region(rc, w, &w->view, &rg, &ro, &pix));
    assert_null(pix.supersample);
    ro.quality = 1;
    vt_ok(vv_renderer_render_region(rt, w, &w->view, &rg, &ro, &pix));
    assert_null(pix.supersample);
    ro.quality = 2;
    vt_ok(vv_renderer_render_region(rt, w, &w->view, &rg, &ro, &pix));
    assert_non_null(pix.supersample);
    /* 12 pixel centres down the middle column, 3 points each */
    size_t pxl[12];
    double xy[2 * 36];
    for (int i = 0; i < 12; i++) {
        const int x = W / 2, y = H / 6 + i * (H * 2 / 3) / 12;
        pxl[i] = (size_t)y * (size_t)W + (size_t)x;
        for (int k = 0; k < 3; k++) {
            xy[2 * (3 * i + k)] = x;
            xy[2 * (3 * i + k) + 1] = y;
        }
    }
    const vv_region_rays rays = {.per_pixel = 3, .n_pixels = 12, .pixel = pxl, .xy = xy};
    float rkeys[40];
    vv_region_image pts = {.key = rkeys};
    vt_ok(vv_image_new(&pts.image, 8, 5)); /* 40 entries for 36 points */
    rg.rays = &rays;
    vt_ok(vv_renderer_render_region(rt, w, &w->view, &rg, &ro, &pts));
    assert_null(pts.supersample);
    for (int i = 0; i < 36; i++) {
        const size_t at = pxl[i / 3];
        assert_memory_equal(pts.image->rgba + 4 * i, pix.image->rgba + 4 * at, 4 * sizeof(float));
        assert_memory_equal(pts.key + i, pix.key + at, sizeof(float));
    }
    for (int i = 36; i < 40; i++) /* past the last point: clear */
        assert_true(pts.image->rgba[4 * i + 3] == 0 && isnan(pts.key[i]));
    vv_image_free(pts.image);
    vt_ok(vv_image_new(&pts.image, 5, 7)); /* 35 entries: too few */
    assert_int_equal(vv_renderer_render_region(rt, w, &w->view, &rg, &ro, &pts), VV_ERR_INVALID);
    assert_non_null(strstr(vv_error_message(), "rays"));
    vv_image_free(pts.image);
    vv_image_free(pix.image);
    free(keys);
    vv_renderer_free(rc);
    vv_renderer_free(rt);
    vv_world_free(w);

    /* whole frames by bricks at quality 2 against memory */
    for (int m = 0; m < 2; m++) {
        w = head_world(head, m ? VV_MODE_COMPOSITE : VV_MODE_MIP, 0.6);
        vv_renderer *mem = NULL, *ooc = NULL;
        vt_ok(vv_renderer_new(&mem, "raytrace"));
        vt_ok(vv_renderer_new(&ooc, "raytrace"));
        vv_image *ref = NULL, *img = NULL;
        vt_ok(vv_image_new(&ref, w->view.width, w->view.height));
        vt_ok(vv_image_new(&img, w->view.width, w->view.height));
        vt_ok(vv_renderer_render(mem, w, &w->view, &ro, ref));
        vv_bricked_stats before, after;
        vv_bricked_stats_get(b, &before);
        vt_ok(drv_render_bricks(drv_renderer_of(ooc, &(drv_renderer){0}), w, 0, &src, &w->view, &ro,
                                img));
        vv_bricked_stats_get(b, &after);
        int same = 0;
        const double db = vt_image_psnr(ref, img, &same);
        const unsigned long long reads =
            (unsigned long long)(after.loads - before.loads + after.hits - before.hits);
        printf("quality 2 by bricks, %s: %s %.1f dB, %llu brick reads (of %d bricks)\n",
               m ? "composite" : "mip", same ? "bit-identical" : "differs", db, reads, nbricks);
        if (m == 0)
            assert_true(same);
        else
            assert_true(db >= 50);
        assert_true(reads > (unsigned long long)nbricks / 2 && reads <= 2ull * nbricks);
        vv_image_free(ref);
        vv_image_free(img);
        vv_renderer_free(mem);
        vv_renderer_free(ooc);
        vv_world_free(w);
    }
    vv_bricked_free(b);
    vv_volume_free(head);
}

static vv_volume *
synthetic(void) {
    const int dims[3] = {70, 131, 9};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    uint8_t *d = v->data;
    for (size_t i = 0; i < (size_t)dims[0] * dims[1] * dims[2]; i++)
        d[i] = (uint8_t)(i * 2654435761u >> 24);
    vv_volume_update_range(v);
    return v;
}

static void round_trip(unsigned flags);

/* Raw bricks without coarse levels, then zstd bricks (which keep theirs):
 * every brick, a box across bricks and the proxies read the volume's
 * voxels. */
static void
test_round_trip(void **state) {
    (void)state;
    for (int z = 0; z < 2; z++)
        round_trip(z ? VV_VVB_ZSTD : 0);
}

static void
round_trip(unsigned flags) {
    vv_volume *v = synthetic();
    char path[1200];
    snprintf(path, sizeof path, "%s/syn%u.vvb", outdir(), flags);
    vt_ok(vt_save(v, path, VV_FORMAT_VVB, -1, flags));
    vv_bricked *b = NULL;
    vt_ok(vv_bricked_open(&b, path, NULL, vt_cache(0)));
    int nb[3];
    vv_bricked_grid(b, nb);
    assert_int_equal(nb[0], 2);
    assert_int_equal(nb[1], 3);
    assert_int_equal(nb[2], 1);
    /* every brick holds the voxels of its box with the ghosts */
    for (int i = 0; i < nb[0] * nb[1] * nb[2]; i++) {
        vv_volume *bv = NULL;
        vt_ok(vv_bricked_load(b, i, &bv));
        const int bi = i % nb[0], bj = (i / nb[0]) % nb[1];
        const int x0 = bi ? bi * 64 - 1 : 0, y0 = bj ? bj * 64 - 1 : 0;
        for (int k = 0; k < bv->dims[2]; k++)
            for (int j = 0; j < bv->dims[1]; j++)
                for (int x = 0; x < bv->dims[0]; x++)
                    assert_true(vv_volume_get(bv, x, j, k) == vv_volume_get(v, x0 + x, y0 + j, k));
        vv_volume_free(bv);
    }
    /* the proxy: from the voxels of the bricks (no coarse levels) or from
     * the coarse levels, every 4th voxel either way */
    vv_volume *p = NULL;
    vt_ok(vv_bricked_proxy(b, 40, &p));
    assert_int_equal(p->dims[1], 33); /* every 4th of 131 */
    assert_true(vv_volume_get(p, 5, 7, 2) == vv_volume_get(v, 20, 28, 8));
    vv_volume_free(p);
    /* a proxy of every voxel (zstd: the bricks read whole) */
    vt_ok(vv_bricked_proxy(b, 200, &p));
    assert_int_equal(p->dims[1], 131);
    assert_memory_equal(p->data, v->data, (size_t)70 * 131 * 9);
    vv_volume_free(p);
    /* a box across four bricks */
    const int lo[3] = {50, 60, 2}, hi[3] = {69, 70, 8};
    vt_ok(vv_bricked_read_box(b, lo, hi, &p));
    for (int k = lo[2]; k <= hi[2]; k++)
        for (int j = lo[1]; j <= hi[1]; j++)
            for (int i = lo[0]; i <= hi[0]; i++)
                assert_true(vv_volume_get(p, i - lo[0], j - lo[1], k - lo[2]) ==
                            vv_volume_get(v, i, j, k));
    vv_volume_free(p);
    vv_bricked_free(b);
    vv_volume_free(v);
}

/* Patches @p n bytes at @p off of a copy of @p src written to @p dst. */
static void
patched(const char *src, const char *dst, long off, const void *bytes, size_t n, long truncate) {
    size_t len;
    unsigned char *d = vt_read_file(src, &len);
    if (off >= 0)
        memcpy(d + off, bytes, n);
    vt_write_file(dst, d, truncate >= 0 ? (size_t)truncate : len);
    free(d);
}

static void
test_bad_vvb(void **state) {
    (void)state;
    vv_volume *v = synthetic();
    char good[1200], bad[1200];
    snprintf(good, sizeof good, "%s/good.vvb", outdir());
    snprintf(bad, sizeof bad, "%s/bad.vvb", outdir());
    vt_ok(vt_save(v, good, VV_FORMAT_VVB, -1, 1));
    vv_bricked *b = NULL;
    /* brick 3's offset past the end of the file (index at 256, 48 bytes a brick) */
    const unsigned char far[8] = {0, 0, 0, 0, 0, 1, 0, 0};
    patched(good, bad, 256 + 3 * 48, far, 8, -1);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_null(b);
    printf("%s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "brick 3"));
    assert_non_null(strstr(vv_error_message(), "past the end of the file"));
    /* a brick size that does not match its box */
    const unsigned char size[8] = {5, 0, 0, 0, 0, 0, 0, 0};
    patched(good, bad, 256 + 1 * 48 + 8, size, 8, -1);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "brick 1"));
    /* a brick count that does not match the dims */
    const unsigned char count[8] = {7, 0, 0, 0, 0, 0, 0, 0};
    patched(good, bad, 192, count, 8, -1);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "index of 7 bricks"));
    /* truncated: the last bricks are gone */
    patched(good, bad, -1, NULL, 0, 2000);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "past the end of the file"));
    /* not a .vvb at all */
    patched(good, bad, 0, "NOTAVVB!", 8, -1);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "magic"));
    /* a raw file shorter than its dims */
    vv_raw_params rp;
    vv_raw_params_init(&rp);
    rp.dims[0] = rp.dims[1] = rp.dims[2] = 100;
    rp.type = VV_U8;
    assert_int_equal(vv_bricked_open(&b, good, &rp, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "past the end of the file"));
    /* zstd bricks */
    char goodz[1200];
    snprintf(goodz, sizeof goodz, "%s/goodz.vvb", outdir());
    vt_ok(vt_save(v, goodz, VV_FORMAT_VVB, -1, VV_VVB_ZSTD));
    vt_ok(vv_bricked_open(&b, goodz, NULL, vt_cache(0)));
    vv_brick_info bi;
    vv_bricked_info(b, 2, &bi);
    vv_bricked_free(b);
    size_t zlen;
    unsigned char *zf = vt_read_file(goodz, &zlen);
    uint64_t off2 = 0, bytes2 = 0;
    for (int q = 0; q < 8; q++) {
        off2 |= (uint64_t)zf[256 + 2 * 48 + q] << (8 * q);
        bytes2 |= (uint64_t)zf[256 + 2 * 48 + 8 + q] << (8 * q);
    }
    free(zf);
    /* brick 2's frame scribbled over in its middle: opens, fails to load */
    const unsigned char junk[16] = {0xde, 0xad, 0xbe, 0xef, 0xde, 0xad, 0xbe, 0xef,
                                    0xde, 0xad, 0xbe, 0xef, 0xde, 0xad, 0xbe, 0xef};
    patched(goodz, bad, (long)(off2 + bytes2 / 2), junk, 16, -1);
    vt_ok(vv_bricked_open(&b, bad, NULL, vt_cache(0)));
    vv_volume *bv = NULL;
    assert_int_equal(vv_bricked_load(b, 2, &bv), VV_ERR_FORMAT);
    assert_null(bv);
    printf("%s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "brick 2"));
    assert_non_null(strstr(vv_error_message(), "zstd"));
    vv_bricked_free(b);
    /* brick 1's frame cut to 5 bytes: not a frame */
    patched(goodz, bad, 256 + 1 * 48 + 8, size, 8, -1);
    vt_ok(vv_bricked_open(&b, bad, NULL, vt_cache(0)));
    assert_int_equal(vv_bricked_load(b, 1, &bv), VV_ERR_FORMAT);
    printf("%s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "brick 1"));
    vv_bricked_free(b);
    /* brick 0 pointing at brick 2's frame: a frame of another size */
    unsigned char rec[16];
    for (int q = 0; q < 8; q++) {
        rec[q] = (unsigned char)(off2 >> (8 * q));
        rec[8 + q] = (unsigned char)(bytes2 >> (8 * q));
    }
    patched(goodz, bad, 256, rec, 16, -1);
    vt_ok(vv_bricked_open(&b, bad, NULL, vt_cache(0)));
    assert_int_equal(vv_bricked_load(b, 0, &bv), VV_ERR_FORMAT);
    printf("%s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "its box needs"));
    vv_bricked_free(b);
    /* an empty frame, an unknown codec, zstd without coarse levels */
    const unsigned char zero8[8] = {0};
    patched(goodz, bad, 256 + 3 * 48 + 8, zero8, 8, -1);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "brick 3"));
    const unsigned char codec[4] = {7, 0, 0, 0};
    patched(goodz, bad, 200, codec, 4, -1);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "unknown brick codec 7"));
    patched(goodz, bad, 32, zero8, 4, -1);
    assert_int_equal(vv_bricked_open(&b, bad, NULL, vt_cache(0)), VV_ERR_FORMAT);
    assert_non_null(strstr(vv_error_message(), "without coarse levels"));
    assert_null(b);
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ct_head),
        cmocka_unit_test(test_quality2_regions),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_bad_vvb),
    };
    return vt_run_tests(tests, NULL, NULL);
}
