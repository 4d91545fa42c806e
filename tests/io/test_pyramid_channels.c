/*
 * Channels of a pyramid out of core (include/volvis/source.h, the channel_
 * functions; include/volvis/sys/source.h, vv_store_stack and
 * vv_multires_source's channels): three stores of one channel each, held
 * in memory by this test (a store of the implementor's interface, as a
 * format row fills one), stacked into one store of three channels and
 * opened as a pyramid whose chunks hold every channel:
 *
 * - each channel read back by boxes and as its proxy voxel for voxel, its
 *   level headers with its own value range;
 * - a frame of a 3-channel object over the source (vv_object_set_channels_
 *   source) equals the same channels in memory (vv_object_set_channels,
 *   the same transfer functions) under the composite, additive and maximum
 *   rules (>= 50, 50 and 60 dB: the rounding of compositing by nodes), and
 *   reads each chunk once for all channels (one chunk read a chunk: not
 *   three);
 * - a channel hidden or recoloured redraws from the cache: no chunk read;
 * - vv_object_drop_source leaves the proxies in memory;
 * - stores that are not one grid, or of several channels, are refused by
 *   vv_store_stack, naming the channel.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/store/pyramid.h"
#include "testutil.h"
#include "volvis/volvis.h"

#define NX 40
#define NY 36
#define NZ 28
#define CHUNK 8
#define NCH 3

/* One channel in memory: level 0 (NX x NY x NZ) and level 1 (halved), u16. */
typedef struct mem_store {
    uint16_t *lv[2];
    int dims[2][3];
    int reads;
} mem_store;

static vv_status
ms_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
              const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    (void)scratch;
    (void)c;
    mem_store *m = ctx;
    const int *d = m->dims[level];
    uint16_t *out = (uint16_t *)dst;
    for (int z = 0; z < dims[2]; z++)
        for (int y = 0; y < dims[1]; y++)
            for (int x = 0; x < dims[0]; x++)
                out[((size_t)z * (size_t)dims[1] + (size_t)y) * (size_t)dims[0] + (size_t)x] =
                    m->lv[level][((size_t)(org[2] + z) * (size_t)d[1] + (size_t)(org[1] + y)) *
                                     (size_t)d[0] +
                                 (size_t)(org[0] + x)];
    __atomic_add_fetch(&m->reads, 1, __ATOMIC_RELAXED);
    *missing = 0;
    *file_bytes = (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2] * 2;
    return VV_OK;
}

static void
ms_close(void *ctx) {
    mem_store *m = ctx;
    free(m->lv[0]);
    free(m->lv[1]);
    free(m);
}

/* Channel @p ch's voxel (x, y, z) of level 0: a blob of its own and noise. */
static uint16_t
value(int ch, int x, int y, int z) {
    const double cx = 10 + 9 * ch, cy = 12 + 5 * ch, cz = 9 + 4 * ch, r2 = 30 + 20 * ch;
    const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz);
    const unsigned h = (unsigned)(x * 73856093u ^ y * 19349663u ^ z * 83492791u ^ ch * 2654435u);
    return (uint16_t)(2000.0 * exp(-d2 / r2) + 100 + (h % 40));
}

/* A store of channel @p ch (levels 0 and 1), @p nx voxels along x at level 0. */
static mem_store *
store_of(vv_store *st, int ch, int nx) {
    mem_store *m = calloc(1, sizeof *m);
    assert_non_null(m);
    memset(st, 0, sizeof *st);
    const int d0[3] = {nx, NY, NZ}, d1[3] = {nx / 2, NY / 2, NZ / 2};
    memcpy(m->dims[0], d0, sizeof d0);
    memcpy(m->dims[1], d1, sizeof d1);
    m->lv[0] = malloc(sizeof(uint16_t) * (size_t)nx * NY * NZ);
    m->lv[1] = malloc(sizeof(uint16_t) * (size_t)d1[0] * d1[1] * d1[2]);
    assert_true(m->lv[0] && m->lv[1]);
    for (int z = 0; z < NZ; z++)
        for (int y = 0; y < NY; y++)
            for (int x = 0; x < nx; x++)
                m->lv[0][((size_t)z * NY + (size_t)y) * (size_t)nx + (size_t)x] =
                    value(ch, x, y, z);
    for (int z = 0; z < d1[2]; z++)
        for (int y = 0; y < d1[1]; y++)
            for (int x = 0; x < d1[0]; x++) {
                double s = 0;
                for (int k = 0; k < 8; k++)
                    s += m->lv[0][((size_t)(2 * z + (k >> 2)) * NY +
                                   (size_t)(2 * y + ((k >> 1) & 1))) *
                                      (size_t)nx +
                                  (size_t)(2 * x + (k & 1))];
                m->lv[1][((size_t)z * (size_t)d1[1] + (size_t)y) * (size_t)d1[0] + (size_t)x] =
                    (uint16_t)lround(s / 8);
            }
    st->name = "memory";
    st->ctx = m;
    st->n_levels = 2;
    st->n_channels = NCH;
    st->n_times = 1;
    st->parallel = 1;
    st->read_chunk = ms_read_chunk;
    st->close = ms_close;
    const int cd[3] = {CHUNK, CHUNK, CHUNK};
    for (int l = 0; l < 2; l++) {
        vt_ok(vv_store_set_level(st, l, VV_U16, m->dims[l], cd));
        for (int k = 0; k < 3; k++) {
            st->lv[l].hdr->spacing[k] = l ? 2.0 : 1.0;
            st->lv[l].hdr->origin[k] = l ? 0.5 : 0.0;
        }
    }
    return m;
}

/* Channel @p ch of level @p level as a volume (the test's own copy of the store's). */
static vv_volume *
channel_volume(const mem_store *m, int level) {
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, m->dims[level], VV_U16));
    memcpy(v->data, m->lv[level],
           sizeof(uint16_t) * (size_t)m->dims[level][0] * m->dims[level][1] * m->dims[level][2]);
    for (int k = 0; k < 3; k++) {
        v->spacing[k] = level ? 2.0 : 1.0;
        v->origin[k] = level ? 0.5 : 0.0;
    }
    vv_volume_update_range(v);
    return v;
}

typedef struct fixture {
    mem_store *m[NCH];
    vv_volume *full[NCH]; /* level 0 of each channel */
    vv_source *src;
    vv_cache *cache;
} fixture;

static void
fixture_init(fixture *f, uint64_t limit) {
    memset(f, 0, sizeof *f);
    vv_store parts[NCH], st;
    for (int c = 0; c < NCH; c++) {
        f->m[c] = store_of(&parts[c], c, NX);
        f->full[c] = channel_volume(f->m[c], 0);
    }
    vt_ok(vv_store_stack(&st, parts, NCH));
    assert_int_equal(st.n_ch, NCH);
    f->cache = vt_cache(limit);
    vv_pyramid *p = NULL;
    vt_ok(vv_pyramid_open_store(&p, &st, "memory-channels", f->cache, NULL));
    vt_ok(vv_pyramid_source_new(&f->src, p, "memory"));
}

static void
fixture_free(fixture *f) {
    vv_source_free(f->src);
    for (int c = 0; c < NCH; c++)
        vv_volume_free(f->full[c]);
    /* f->cache belongs to testutil (vt_cache), which frees it at exit. */
}

static int
reads(const fixture *f) {
    int n = 0;
    for (int c = 0; c < NCH; c++)
        n += __atomic_load_n(&f->m[c]->reads, __ATOMIC_RELAXED);
    return n;
}

static void
test_read_back(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 64 << 20);
    assert_int_equal(vv_source_channels(f.src), NCH);
    assert_null(vv_source_channel_level(f.src, NCH, 0));
    for (int c = 0; c < NCH; c++) {
        /* the range: the coarsest level's of that channel (no window in the store) */
        vv_volume *coarse = channel_volume(f.m[c], 1);
        const vv_volume *h = vv_source_channel_level(f.src, c, 0);
        assert_non_null(h);
        assert_int_equal(h->dims[0], NX);
        assert_true(h->range[0] == coarse->range[0] && h->range[1] == coarse->range[1]);
        const int lo[3] = {3, 5, 7}, hi[3] = {NX - 2, NY - 3, NZ - 1};
        vv_volume *box = NULL;
        vt_ok(vv_source_channel_read_box(f.src, c, 0, lo, hi, &box));
        int same = 1;
        for (int z = lo[2]; z <= hi[2]; z++)
            for (int y = lo[1]; y <= hi[1]; y++)
                for (int x = lo[0]; x <= hi[0]; x++)
                    same &= vv_volume_get(box, x - lo[0], y - lo[1], z - lo[2]) ==
                            (double)value(c, x, y, z);
        assert_true(same);
        assert_true(box->range[0] == h->range[0] && box->range[1] == h->range[1]);
        vv_volume *proxy = NULL;
        vt_ok(vv_source_channel_proxy(f.src, c, 0, &proxy));
        assert_int_equal(proxy->dims[0], NX / 2);
        assert_memory_equal(proxy->data, coarse->data,
                            sizeof(uint16_t) * (NX / 2) * (NY / 2) * (NZ / 2));
        vv_volume_free(proxy);
        vv_volume_free(box);
        vv_volume_free(coarse);
    }
    vv_volume *none = NULL;
    const int lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    vt_err(vv_source_channel_read_box(f.src, NCH, 0, lo, hi, &none));
    assert_null(none);
    fixture_free(&f);
}

/* A World of one 3-channel object at @p size x @p size pixels, blend @p b: over the
 * source out of core (@p src), or the volumes @p full in memory. */
static vv_world *
world_of(fixture *f, int ooc, vv_channel_blend b) {
    vv_volume *proxy = NULL;
    vt_ok(vv_source_channel_proxy(f->src, 0, 0, &proxy));
    vv_default_scene_options o = vt_scene_options(160);
    vv_world *w = NULL;
    vt_ok(vv_world_new_for_volume(&w, ooc ? proxy : f->full[0], &o));
    vv_volume_free(proxy);
    vv_object *obj = w->objects[0];
    if (ooc)
        vt_ok(vv_object_set_channels_source(obj, f->src, 0, NULL));
    else
        vt_ok(vv_object_set_channels(obj, NCH, f->full, NULL));
    obj->blend = b;
    for (int c = 0; c < NCH; c++) /* the same transfer functions both ways */
        vt_ok(vv_tf_set_contrast(&obj->channels[c].tf, 300, 2200, 1.0, 0.5,
                                 vv_channel_default_color(c), 1.0));
    return w;
}

static vv_image *
frame(vv_world *w, int refine_off) {
    vv_renderer *r = NULL;
    vt_ok(vv_renderer_new(&r, "raycast"));
    if (refine_off)
        vt_ok(vv_renderer_set_option(r, "refinement", "off"));
    vv_image *img = NULL;
    vt_ok(vv_image_new(&img, w->view.width, w->view.height));
    vv_lod lod;
    vv_lod_init(&lod);
    lod.level = 0;
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.lod = &lod;
    vt_ok(vv_renderer_render(r, w, &w->view, &opt, img));
    vv_renderer_free(r);
    return img;
}

static void
test_frames_match_memory(void **state) {
    (void)state;
    fixture f;
    fixture_init(&f, 64 << 20);
    const vv_channel_blend rules[3] = {VV_BLEND_COMPOSITE, VV_BLEND_ADDITIVE, VV_BLEND_MAXIMUM};
    const double want[3] = {50, 50, 60};
    for (int i = 0; i < 3; i++) {
        vv_world *wm = world_of(&f, 0, rules[i]), *wo = world_of(&f, 1, rules[i]);
        assert_non_null(wo->objects[0]->source);
        const int before = reads(&f);
        vv_image *a = frame(wm, 1), *b = frame(wo, 0);
        const int n = reads(&f) - before;
        int same = 0;
        const double db = vt_image_psnr(a, b, &same);
        vv_source_stats st;
        vv_source_stats_get(f.src, &st);
        printf("%s: out of core %.1f dB from in memory; %d chunk reads of the stores (%llu chunks "
               "read at level 0)\n",
               vv_channel_blend_name(rules[i]), db, n, (unsigned long long)st.chunk_reads[0]);
        assert_true(db >= want[i]);
        /* every chunk of level 0 read once for all its channels: a read of each
         * channel's store a chunk, the chunks read once (64 MiB holds them) */
        const int chunks =
            ((NX + CHUNK - 1) / CHUNK) * ((NY + CHUNK - 1) / CHUNK) * ((NZ + CHUNK - 1) / CHUNK);
        if (i == 0) {
            assert_int_equal(st.chunk_reads[0], chunks);
            assert_int_equal(n, NCH * chunks);
            assert_int_equal(st.max_reads_per_frame, 1);
        } else {
            assert_int_equal(n, 0); /* in the cache: drawn again without a read */
        }
        if (i == 1) {
            /* a channel hidden and another recoloured: redrawn from the cache */
            wo->objects[0]->channels[1].visible = 0;
            vt_ok(vv_tf_set_contrast(&wo->objects[0]->channels[2].tf, 300, 2200, 1.0, 0.5,
                                     vv_vec3_make(1, 1, 0), 1.0));
            const int r0 = reads(&f);
            vv_image *c = frame(wo, 0);
            assert_int_equal(reads(&f) - r0, 0);
            assert_true(vt_image_psnr(b, c, &same) < 40); /* and the image changed */
            vv_image_free(c);
        }
        vt_save_png(b, vt_outdir("pyramid_channels"), "ooc", vv_channel_blend_name(rules[i]));
        vv_image_free(a);
        vv_image_free(b);
        vv_world_free(wm);
        vv_world_free(wo);
    }
    /* without its source the object draws its proxies in memory */
    vv_world *wo = world_of(&f, 1, VV_BLEND_COMPOSITE);
    vv_object_drop_source(wo->objects[0]);
    assert_null(wo->objects[0]->source);
    assert_int_equal(wo->objects[0]->channels[0].volume->dims[0], NX / 2);
    const int r0 = reads(&f);
    vv_image *p = frame(wo, 0);
    assert_int_equal(reads(&f) - r0, 0);
    vv_image_free(p);
    vv_world_free(wo);
    fixture_free(&f);
}

static void
test_stack_refuses(void **state) {
    (void)state;
    vv_store parts[2], st;
    store_of(&parts[0], 0, NX);
    store_of(&parts[1], 1, NX - 8); /* another grid */
    vt_err(vv_store_stack(&st, parts, 2));
    assert_non_null(strstr(vv_error_message(), "channel 1"));
    assert_null(parts[0].ctx); /* taken (closed) on error too */
    store_of(&parts[0], 0, NX);
    parts[0].n_ch = 2; /* a store of several channels */
    store_of(&parts[1], 1, NX);
    vt_err(vv_store_stack(&st, parts, 2));
    assert_non_null(strstr(vv_error_message(), "channel 0"));
    vt_err(vv_store_stack(&st, parts, 0));
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_back),
        cmocka_unit_test(test_frames_match_memory),
        cmocka_unit_test(test_stack_refuses),
    };
    return vt_run_tests(tests, NULL, NULL);
}
