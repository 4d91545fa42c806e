/*
 * The .vvb pyramid (issue 29: ".vvb gains a full pyramid"): levels after
 * the bricks, written by VV_VVB_LEVELS and read by vv_pyramid_open.
 *
 * - The CT head (256 x 256 x 108, int16) with zstd bricks: every level's
 *   geometry and voxels equal those of the OME-Zarr writer's pyramid of
 *   the same volume, read through the same vv_pyramid; level 1 checked
 *   against 2x2x2 means computed here; each chunk read once (counted).
 * - Odd shapes, raw bricks: a float volume of 129 x 65 x 3 (the last voxel
 *   of an axis lies in the last brick's shared face, past the chunk grid
 *   of the bricks) and an axis of one voxel; level 0 read through the
 *   pyramid is the volume voxel for voxel, each level the means of the one
 *   before.
 * - Empty space skipped unread: a ball in a corner of a volume of zeros,
 *   rendered at level 0, reads only the chunks near the ball (the others'
 *   ranges from the index: 27 of 125 chunks read), and the image is the
 *   one drawn with every chunk read.
 * - A .vvb without levels is no pyramid (vv_open by its levels reads it by bricks, one level),
 *   with levels it is; the box writer gives the in-memory writer's bytes.
 * - Bad input: a level table past the end of the file, a wrong level
 *   count, a chunk of the wrong size, a scribbled zstd frame: one-line
 *   errors naming the file and the level or chunk, never a crash.
 */
#include "testutil.h"

#include "io/store/bricked.h"
#include "io/store/pyramid.h"
#include "render/drivers.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define outdir() vt_outdir("vvb_pyramid")

/* 1 when @p path opens by its levels as a pyramid (vv_open out of core,
 * levels asked for); a .vvb without levels opens by bricks. */
static int
opens_as_pyramid(const char *path) {
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE;
    oo.levels = 1;
    vv_opened od;
    vt_ok(vv_open(&od, path, &oo));
    const int p = vv_source_get_kind(od.source) == VV_SOURCE_PYRAMID;
    vv_opened_clear(&od);
    return p;
}

static vv_volume *
read_level(vv_pyramid *p, int level) {
    const vv_volume *h = vv_pyramid_level(p, level);
    assert_non_null(h);
    const int lo[3] = {0, 0, 0}, hi[3] = {h->dims[0] - 1, h->dims[1] - 1, h->dims[2] - 1};
    vv_volume *v = NULL;
    vt_ok(vv_pyramid_read_box(p, level, lo, hi, &v));
    return v;
}

/* The mean of the 2x2x2 voxels of @p a under voxel (i, j, k) of the next
 * level (axes of one voxel not halved), rounded as integers are. */
static double
block_mean(const vv_volume *a, int i, int j, int k) {
    int st[3];
    for (int q = 0; q < 3; q++)
        st[q] = a->dims[q] > 1 ? 2 : 1;
    double sum = 0;
    int n = 0;
    for (int z = k * st[2]; z < k * st[2] + st[2] && z < a->dims[2]; z++)
        for (int y = j * st[1]; y < j * st[1] + st[1] && y < a->dims[1]; y++)
            for (int x = i * st[0]; x < i * st[0] + st[0] && x < a->dims[0]; x++, n++)
                sum += vv_volume_get(a, x, y, z);
    const double m = sum / n;
    return a->type == VV_F32 || a->type == VV_F64 ? m : floor(m + 0.5);
}

static void
assert_means(const vv_volume *fine, const vv_volume *coarse) {
    for (int q = 0; q < 3; q++)
        assert_int_equal(coarse->dims[q], fine->dims[q] > 1 ? (fine->dims[q] + 1) / 2 : 1);
    for (int k = 0; k < coarse->dims[2]; k++)
        for (int j = 0; j < coarse->dims[1]; j++)
            for (int i = 0; i < coarse->dims[0]; i++) {
                const double want = block_mean(fine, i, j, k), got = vv_volume_get(coarse, i, j, k);
                if (fine->type == VV_F32 ? fabs(got - want) > 1e-6 * (1 + fabs(want)) : got != want)
                    fail_msg("voxel %d,%d,%d: %g, the mean is %g", i, j, k, got, want);
            }
}

static void
test_ct_head(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    char vvb[1200], zarr[1200];
    snprintf(vvb, sizeof vvb, "%s/head.vvb", outdir());
    snprintf(zarr, sizeof zarr, "%s/head.ome.zarr", outdir());
    vt_ok(vt_save(v, vvb, VV_FORMAT_VVB, -1, VV_VVB_ZSTD | VV_VVB_LEVELS));
    vt_ok(vt_save(v, zarr, VV_FORMAT_OME_ZARR, -1, 0));
    assert_true(opens_as_pyramid(vvb));
    vv_pyramid *a = NULL, *b = NULL;
    vv_load_info info;
    vt_ok(vv_pyramid_open(&a, vvb, -1, -1, vt_cache(0), &info));
    vt_ok(vv_pyramid_open(&b, zarr, -1, -1, vt_cache(0), NULL));
    assert_int_equal(vv_pyramid_levels(a), 3);
    assert_int_equal(vv_pyramid_levels(a), vv_pyramid_levels(b));
    assert_int_equal(info.n_levels, 3);
    vv_volume *prev = NULL;
    for (int l = 0; l < 3; l++) {
        const vv_volume *ha = vv_pyramid_level(a, l), *hb = vv_pyramid_level(b, l);
        for (int q = 0; q < 3; q++) {
            assert_int_equal(ha->dims[q], hb->dims[q]);
            assert_true(fabs(ha->spacing[q] - hb->spacing[q]) < 1e-12);
            assert_true(fabs(ha->origin[q] - hb->origin[q]) < 1e-9);
        }
        vv_volume *va = read_level(a, l), *vb = read_level(b, l);
        assert_int_equal(va->type, VV_I16);
        assert_memory_equal(va->data, vb->data,
                            (size_t)va->dims[0] * va->dims[1] * va->dims[2] * 2);
        if (l == 0)
            assert_memory_equal(va->data, v->data, (size_t)256 * 256 * 108 * 2);
        else
            assert_means(prev, va);
        printf("level %d: %d x %d x %d, the OME-Zarr writer's voxels\n", l, va->dims[0],
               va->dims[1], va->dims[2]);
        vv_volume_free(prev);
        vv_volume_free(vb);
        prev = va;
    }
    vv_volume_free(prev);
    vv_pyramid_stats st;
    vv_pyramid_stats_get(a, &st);
    /* 4 x 4 x 2, 2 x 2 x 1 and 1 chunk of 64^3, each read once */
    assert_int_equal(st.chunk_reads[0], 32);
    assert_int_equal(st.chunk_reads[1], 4);
    assert_int_equal(st.chunk_reads[2], 1);
    assert_true(st.bytes_read > 0);
    vv_pyramid_free(a);
    vv_pyramid_free(b);
    vv_volume_free(v);
}

/* A float volume of @p d voxels, values from the position. */
static vv_volume *
odd_volume(const int d[3]) {
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, d, VV_F32));
    float *f = v->data;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++)
                f[((size_t)k * d[1] + j) * d[0] + i] =
                    (float)(sin(0.37 * i) * cos(0.21 * j) + 0.01 * k * i);
    v->spacing[2] = 2.5;
    v->origin[0] = -3;
    vv_volume_update_range(v);
    return v;
}

static void
check_odd(const int d[3], int want_levels) {
    vv_volume *v = odd_volume(d);
    char path[1200];
    snprintf(path, sizeof path, "%s/odd_%d_%d_%d.vvb", outdir(), d[0], d[1], d[2]);
    vt_ok(vt_save(v, path, VV_FORMAT_VVB, -1, VV_VVB_LEVELS)); /* raw bricks, no coarse levels */
    vv_bricked *bk = NULL;
    vt_ok(vv_bricked_open(&bk, path, NULL, vt_cache(0)));
    assert_int_equal(vv_bricked_levels(bk), want_levels);
    vv_bricked_free(bk);
    vv_pyramid *p = NULL;
    vt_ok(vv_pyramid_open(&p, path, 0, 0, vt_cache(0), NULL));
    assert_int_equal(vv_pyramid_levels(p), want_levels);
    vv_volume *prev = read_level(p, 0);
    assert_memory_equal(prev->data, v->data, (size_t)d[0] * d[1] * d[2] * 4);
    for (int l = 1; l < want_levels; l++) {
        vv_volume *c = read_level(p, l);
        assert_means(prev, c);
        /* each voxel's centre at the centre of the voxels under it */
        const vv_volume *h = vv_pyramid_level(p, l), *h0 = vv_pyramid_level(p, 0);
        for (int q = 0; q < 3; q++) {
            const double f = h->spacing[q] / h0->spacing[q];
            assert_true(fabs(h->origin[q] - (h0->origin[q] + 0.5 * (f - 1) * h0->spacing[q])) <
                        1e-9);
        }
        vv_volume_free(prev);
        prev = c;
    }
    vv_volume_free(prev);
    vv_pyramid_free(p);
    vv_volume_free(v);
}

static void
test_odd_shapes(void **state) {
    (void)state;
    check_odd((const int[3]){129, 65, 3}, 3);
    check_odd((const int[3]){200, 1, 70}, 3);
    check_odd((const int[3]){40, 30, 20}, 1); /* fits one chunk: no levels */
}

/* Empty space skipped before a voxel is read: a 320^3 volume of zeros but
 * for a ball in one corner, rendered at level 0 (composite, a transfer
 * function that hides 0): the chunks' ranges come from the .vvb's index,
 * so the empty nodes are skipped unread and only the ball's chunks are
 * read; the image is the one from a cache that read every chunk. */
static vv_image *
render_level0(vv_pyramid *p, int *skipped) {
    vv_volume *proxy = NULL;
    vt_ok(vv_pyramid_proxy(p, 0, &proxy));
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = 64;
    o.has_tf_range = 1;
    o.tf_lo = 50;
    o.tf_hi = 255;
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, proxy, &o));
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    vt_ok(vv_renderer_new(&ren, "raycast"));
    vt_ok(vv_image_new(&img, 64, 64));
    vv_multires_source src;
    vv_pyramid_source(p, &src);
    vv_lod lod;
    vv_lod_init(&lod);
    lod.level = 0;
    vt_ok(drv_render_multires(drv_renderer_of(ren, &(drv_renderer){0}), w, 0, &src, &w->view, NULL,
                              &lod, img));
    *skipped = lod.skipped;
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_volume_free(proxy);
    return img;
}

static void
test_skip_unread(void **state) {
    (void)state;
    const int d[3] = {320, 320, 320};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, d, VV_U8));
    unsigned char *u = v->data;
    for (int k = 0; k < 40; k++)
        for (int j = 0; j < 40; j++)
            for (int i = 0; i < 40; i++)
                if ((i - 20) * (i - 20) + (j - 20) * (j - 20) + (k - 20) * (k - 20) < 18 * 18)
                    u[((size_t)k * d[1] + j) * d[0] + i] = 200;
    vv_volume_update_range(v);
    char path[1200];
    snprintf(path, sizeof path, "%s/ball.vvb", outdir());
    vt_ok(vt_save(v, path, VV_FORMAT_VVB, -1, VV_VVB_ZSTD | VV_VVB_LEVELS));
    vv_pyramid *p = NULL;
    vt_ok(vv_pyramid_open(&p, path, -1, -1, vt_cache(0), NULL));
    vv_pyramid_stats st0, st1;
    vv_pyramid_stats_get(p, &st0);
    int skipped = 0;
    vv_image *a = render_level0(p, &skipped);
    vv_pyramid_stats_get(p, &st1);
    const uint64_t read0 = st1.chunk_reads[0] - st0.chunk_reads[0];
    printf("level 0: %llu of 125 chunks read, %d of 125 nodes skipped unread\n",
           (unsigned long long)read0, skipped);
    /* the 8 nodes next to the ball are drawn: their boxes and ghosts lie
     * in the 27 chunks nearest the corner; nothing else is read */
    assert_int_equal(skipped, 125 - 8);
    assert_true(read0 <= 27);
    /* every chunk read into the cache first: the same image */
    const int lo[3] = {0, 0, 0}, hi[3] = {319, 319, 319};
    vv_volume *all = NULL;
    vt_ok(vv_pyramid_read_box(p, 0, lo, hi, &all));
    vv_volume_free(all);
    vv_image *b = render_level0(p, &skipped);
    assert_memory_equal(a->rgba, b->rgba, sizeof(float) * 4 * 64 * 64);
    vv_image_free(a);
    vv_image_free(b);
    vv_pyramid_free(p);
    vv_volume_free(v);
}

/* A .vvb without levels is no pyramid; the box writer writes the same bytes. */
static vv_status
read_mem_box(void *ctx, const int lo[3], const int hi[3], vv_volume **out) {
    return vv_filter_crop(ctx, lo, hi, NULL, out);
}

static void
test_probe_and_writers(void **state) {
    (void)state;
    vv_volume *v = odd_volume((const int[3]){150, 90, 70});
    char plain[1200], lv[1200], boxes[1200];
    snprintf(plain, sizeof plain, "%s/plain.vvb", outdir());
    snprintf(lv, sizeof lv, "%s/levels.vvb", outdir());
    snprintf(boxes, sizeof boxes, "%s/boxes.vvb", outdir());
    vt_ok(vt_save(v, plain, VV_FORMAT_VVB, -1, VV_VVB_ZSTD));
    vt_ok(vt_save(v, lv, VV_FORMAT_VVB, -1, VV_VVB_ZSTD | VV_VVB_LEVELS));
    vv_save_options so;
    vv_save_options_init(&so);
    so.format = VV_FORMAT_VVB;
    so.vvb_flags = VV_VVB_ZSTD | VV_VVB_LEVELS;
    vt_ok(vv_volume_save_boxes(v, read_mem_box, v, boxes, &so));
    assert_false(opens_as_pyramid(plain));
    assert_true(opens_as_pyramid(lv));
    size_t n1, n2;
    unsigned char *a = vt_read_file(lv, &n1), *b = vt_read_file(boxes, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(a, b, n1);
    free(a);
    free(b);
    /* the bricked reader still reads a file with levels, brick for brick */
    vv_bricked *bk = NULL;
    vt_ok(vv_bricked_open(&bk, lv, NULL, vt_cache(0)));
    assert_int_equal(vv_bricked_levels(bk), 3);
    const int lo[3] = {60, 10, 30}, hi[3] = {140, 80, 69};
    vv_volume *box = NULL, *want = NULL;
    vt_ok(vv_bricked_read_box(bk, lo, hi, &box));
    vt_ok(vv_filter_crop(v, lo, hi, NULL, &want));
    assert_memory_equal(box->data, want->data, (size_t)81 * 71 * 40 * 4);
    vv_volume_free(box);
    vv_volume_free(want);
    vv_bricked_free(bk);
    vv_volume_free(v);
}

static uint64_t
get_u64(const unsigned char *p) {
    uint64_t x = 0;
    for (int q = 0; q < 8; q++)
        x |= (uint64_t)p[q] << (8 * q);
    return x;
}

/* A copy of @p src at @p dst with @p n bytes at @p off replaced. */
static void
patched(const char *src, const char *dst, uint64_t off, const void *bytes, size_t n) {
    size_t len;
    unsigned char *d = vt_read_file(src, &len);
    assert_true(off + n <= len);
    memcpy(d + off, bytes, n);
    vt_write_file(dst, d, len);
    free(d);
}

/* vv_pyramid_open of @p path fails with @p code and a message holding @p what. */
static void
refused(const char *path, vv_status code, const char *what) {
    vv_pyramid *p = NULL;
    assert_int_equal(vv_pyramid_open(&p, path, -1, -1, vt_cache(0), NULL), code);
    assert_null(p);
    printf("%s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), what));
    assert_non_null(strstr(vv_error_message(), "bad.vvb"));
    assert_null(strchr(vv_error_message(), '\n'));
}

static void
test_bad_levels(void **state) {
    (void)state;
    vv_volume *v = odd_volume((const int[3]){150, 90, 70});
    char good[1200], bad[1200];
    snprintf(good, sizeof good, "%s/good.vvb", outdir());
    snprintf(bad, sizeof bad, "%s/bad.vvb", outdir());
    vt_ok(vt_save(v, good, VV_FORMAT_VVB, -1, VV_VVB_ZSTD | VV_VVB_LEVELS));
    size_t len;
    unsigned char *f = vt_read_file(good, &len);
    const uint64_t table = get_u64(f + 208);
    const uint64_t idx1 = get_u64(f + table + 16); /* level 1's index */
    const uint64_t c0off = get_u64(f + idx1), c0bytes = get_u64(f + idx1 + 8);
    free(f);
    /* the table past the end of the file */
    const unsigned char far[8] = {0, 0, 0, 0, 0, 1, 0, 0};
    patched(good, bad, 208, far, 8);
    refused(bad, VV_ERR_FORMAT, "level table");
    /* a level count the dims do not make */
    const unsigned char five[4] = {5, 0, 0, 0};
    patched(good, bad, 204, five, 4);
    refused(bad, VV_ERR_FORMAT, "5 pyramid levels");
    /* level 1's dims changed */
    const unsigned char dims[4] = {9, 0, 0, 0};
    patched(good, bad, table, dims, 4);
    refused(bad, VV_ERR_FORMAT, "level 1:");
    /* level 1's chunk 0 of size 0 */
    const unsigned char zero[8] = {0};
    patched(good, bad, idx1 + 8, zero, 8);
    refused(bad, VV_ERR_FORMAT, "level 1: chunk 0");
    /* level 1's chunk 0 scribbled over: opens, its read fails naming it */
    const unsigned char junk[8] = {0xde, 0xad, 0xbe, 0xef, 0xde, 0xad, 0xbe, 0xef};
    patched(good, bad, c0off + c0bytes / 2, junk, 8);
    vv_pyramid *p = NULL;
    if (vv_pyramid_open(&p, bad, -1, -1, vt_cache(0), NULL) != VV_OK)
        fail_msg("%s", vv_error_message());
    const int lo[3] = {0, 0, 0}, hi[3] = {10, 10, 10};
    vv_volume *box = NULL;
    assert_int_equal(vv_pyramid_read_box(p, 1, lo, hi, &box), VV_ERR_FORMAT);
    assert_null(box);
    printf("%s\n", vv_error_message());
    assert_non_null(strstr(vv_error_message(), "level 1 chunk 0"));
    assert_non_null(strstr(vv_error_message(), "bad.vvb"));
    vv_pyramid_free(p);
    /* a channel or time step a .vvb does not have */
    vv_pyramid *q = NULL;
    assert_int_equal(vv_pyramid_open(&q, good, 1, -1, vt_cache(0), NULL), VV_ERR_INVALID);
    printf("%s\n", vv_error_message());
    vv_volume_free(v);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ct_head),     cmocka_unit_test(test_odd_shapes),
        cmocka_unit_test(test_skip_unread), cmocka_unit_test(test_probe_and_writers),
        cmocka_unit_test(test_bad_levels),
    };
    return vt_run_tests(tests, NULL, NULL);
}
