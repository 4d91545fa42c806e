/*
 * The out-of-core readers as volume sources (include/volvis/sys/source.h):
 * a bricked volume (src/io/store/bricked.c) as a source of kind
 * VV_SOURCE_BRICKS, a pyramid (src/io/store/pyramid.c) as one of kind
 * VV_SOURCE_PYRAMID. What vv_open returns for a file read out of core.
 */
#include <string.h>

#include "core/internal.h"
#include "io/store/bricked.h"
#include "io/store/pyramid.h"

/* ---- bricks ------------------------------------------------------------------------ */

static int
bk_levels(void *user) {
    (void)user;
    return 1;
}

static const vv_volume *
bk_level(void *user, int level) {
    (void)level;
    return vv_bricked_header(user);
}

static vv_status
bk_read_box(void *user, int level, const int lo[3], const int hi[3], vv_volume **out) {
    (void)level;
    return vv_bricked_read_box(user, lo, hi, out);
}

/* The proxy's largest side, voxels (vv_bricked_proxy). */
#define BK_PROXY_SIDE 128

static vv_status
bk_proxy(void *user, int level, vv_volume **out) {
    (void)level;
    return vv_bricked_proxy(user, BK_PROXY_SIDE, out);
}

static void
bk_bricks(void *user, vv_brick_source *out) {
    vv_bricked_source(user, out);
}

static void
bk_stats(void *user, vv_source_stats *out) {
    vv_bricked_stats st;
    vv_bricked_stats_get(user, &st);
    out->loads = st.loads;
    out->hits = st.hits;
    out->evictions = st.evictions;
    out->skipped = st.skipped;
    out->bytes_read = st.bytes_read;
    out->peak_bytes = st.peak_bytes;
    out->held_bytes = st.held_bytes;
    out->max_loads = st.max_loads;
    out->n_bricks = vv_bricked_count(user);
    vv_bricked_grid(user, out->bricks_grid);
}

static void
bk_close(void *user) {
    vv_bricked_free(user);
}

static const vv_source_ops bricks_ops = {
    .version = VV_SOURCE_OPS_VERSION,
    .kind = VV_SOURCE_BRICKS,
    .format = "bricks",
    .levels = bk_levels,
    .level = bk_level,
    .read_box = bk_read_box,
    .proxy = bk_proxy,
    .bricks = bk_bricks,
    .stats = bk_stats,
    .close = bk_close,
};

/* ---- pyramids ------------------------------------------------------------------------ */

static int
py_levels(void *user) {
    return vv_pyramid_levels(user);
}

static const vv_volume *
py_level(void *user, int level) {
    return vv_pyramid_level(user, level);
}

static vv_status
py_read_box(void *user, int level, const int lo[3], const int hi[3], vv_volume **out) {
    return vv_pyramid_read_box(user, level, lo, hi, out);
}

static vv_status
py_proxy(void *user, int level, vv_volume **out) {
    return vv_pyramid_proxy(user, level, out);
}

static void
py_multires(void *user, vv_multires_source *out) {
    vv_pyramid_source(user, out);
}

static void
py_stats(void *user, vv_source_stats *out) {
    vv_pyramid_stats st;
    vv_pyramid_stats_get(user, &st);
    memcpy(out->chunk_reads, st.chunk_reads, sizeof out->chunk_reads);
    out->chunk_hits = st.chunk_hits;
    out->hits = st.chunk_hits;
    out->missing = st.missing;
    out->evictions = st.evictions;
    out->bytes_read = st.bytes_read;
    out->peak_bytes = st.peak_bytes;
    out->frames = st.frames;
    out->max_reads_per_frame = st.max_reads_per_frame;
    out->loaded = st.loaded;
    out->cancelled = st.cancelled;
    out->cancelled_in_flight = st.cancelled_in_flight;
    out->load_stopped = st.load_stopped;
    out->load_errors = st.load_errors;
    out->loading = st.loading;
    out->stalled = st.stalled;
    out->held_bytes = st.held_bytes;
    out->resident = st.resident;
}

static int
py_loading(void *user) {
    return vv_pyramid_loading(user);
}

static int
py_wait(void *user, double seconds) {
    return vv_pyramid_wait(user, seconds);
}

static void
py_cancel(void *user) {
    vv_pyramid_request(user, 0, NULL, NULL, NULL);
}

static void
py_close(void *user) {
    vv_pyramid_free(user);
}

static vv_status
py_read_ahead(void *user, void *like_user) {
    return vv_pyramid_request_like(user, like_user);
}

static int
py_channels(void *user) {
    return vv_pyramid_channels(user);
}

static const vv_volume *
py_channel_level(void *user, int channel, int level) {
    return vv_pyramid_channel_level(user, channel, level);
}

static vv_status
py_channel_read_box(void *user, int channel, int level, const int lo[3], const int hi[3],
                    vv_volume **out) {
    return vv_pyramid_channel_read_box(user, channel, level, lo, hi, out);
}

static vv_status
py_channel_proxy(void *user, int channel, int level, vv_volume **out) {
    return vv_pyramid_channel_proxy(user, channel, level, out);
}

static const vv_source_ops pyramid_ops = {
    .version = VV_SOURCE_OPS_VERSION,
    .kind = VV_SOURCE_PYRAMID,
    .format = "pyramid",
    .levels = py_levels,
    .level = py_level,
    .read_box = py_read_box,
    .proxy = py_proxy,
    .multires = py_multires,
    .stats = py_stats,
    .loading = py_loading,
    .wait = py_wait,
    .cancel = py_cancel,
    .close = py_close,
    .channels = py_channels,
    .channel_level = py_channel_level,
    .channel_read_box = py_channel_read_box,
    .channel_proxy = py_channel_proxy,
    .read_ahead = py_read_ahead,
};

vv_status
vv_bricked_source_new(vv_source **out, vv_bricked *b, const char *format) {
    return vv_source_new(out, &bricks_ops, b, vv_bricked_path(b), format, vv_bricked_cache(b));
}

vv_status
vv_pyramid_source_new(vv_source **out, vv_pyramid *p, const char *format) {
    return vv_source_new(out, &pyramid_ops, p, vv_pyramid_path(p), format, vv_pyramid_cache(p));
}
