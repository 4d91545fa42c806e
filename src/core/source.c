/*
 * Volume sources (include/volvis/source.h, the user's side;
 * include/volvis/sys/source.h, the implementor's): a reference-counted
 * handle over a table of methods, and the source of a volume held whole in
 * memory (one level, one brick).
 */
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/sys/source.h"

struct vv_source {
    atomic_int refs;
    const vv_source_ops *ops;
    void *user;
    char *path;
    char format[32];
    vv_cache *cache;
};

vv_status
vv_source_new(vv_source **out, const vv_source_ops *ops, void *user, const char *path,
              const char *format, vv_cache *cache) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "source: NULL output");
    *out = NULL;
    const char *bad =
        !ops                                                         ? "no table"
        : ops->version != 1 && ops->version != VV_SOURCE_OPS_VERSION ? "a table of another version"
        : !ops->levels || !ops->level || !ops->read_box || !ops->proxy || !ops->stats || !ops->close
            ? "a required method missing"
        : ops->kind == VV_SOURCE_BRICKS && !ops->bricks    ? "bricks without a brick view"
        : ops->kind == VV_SOURCE_PYRAMID && !ops->multires ? "a pyramid without levels"
                                                           : NULL;
    if (bad) {
        if (ops && ops->close && user)
            ops->close(user);
        return vv_error_set(VV_ERR_INVALID, "source: %s", bad);
    }
    vv_source *s = calloc(1, sizeof *s);
    char *p = vv_strdup(path ? path : "");
    if (!s || !p) {
        free(s);
        free(p);
        ops->close(user);
        return vv_error_set(VV_ERR_NOMEM, "source: out of memory");
    }
    atomic_store(&s->refs, 1);
    s->ops = ops;
    s->user = user;
    s->path = p;
    snprintf(s->format, sizeof s->format, "%s",
             format        ? format
             : ops->format ? ops->format
                           : "memory");
    s->cache = vv_cache_ref(cache);
    *out = s;
    return VV_OK;
}

vv_source *
vv_source_ref(vv_source *s) {
    if (s)
        atomic_fetch_add(&s->refs, 1);
    return s;
}

void
vv_source_free(vv_source *s) {
    if (!s || atomic_fetch_sub(&s->refs, 1) != 1)
        return;
    s->ops->close(s->user);
    vv_cache_free(s->cache);
    free(s->path);
    free(s);
}

vv_source_kind
vv_source_get_kind(const vv_source *s) {
    return s ? s->ops->kind : VV_SOURCE_MEMORY;
}

const char *
vv_source_kind_name(vv_source_kind k) {
    return k == VV_SOURCE_BRICKS ? "bricks" : k == VV_SOURCE_PYRAMID ? "pyramid" : "memory";
}

const char *
vv_source_path(const vv_source *s) {
    return s ? s->path : "";
}

const char *
vv_source_format(const vv_source *s) {
    return s ? s->format : "memory";
}

vv_cache *
vv_source_cache(const vv_source *s) {
    return s ? s->cache : NULL;
}

int
vv_source_levels(const vv_source *s) {
    return s ? s->ops->levels(s->user) : 0;
}

const vv_volume *
vv_source_level(const vv_source *s, int level) {
    return s && level >= 0 && level < s->ops->levels(s->user) ? s->ops->level(s->user, level)
                                                              : NULL;
}

/* VV_ERR_INVALID unless @p level is one of @p s's and voxels @p lo ..
 * @p hi (inclusive) lie in it. */
static vv_status
check_box(const vv_source *s, int level, const int lo[3], const int hi[3]) {
    const vv_volume *h = vv_source_level(s, level);
    if (!h)
        return vv_error_set(VV_ERR_INVALID, "source: %s: no level %d (it has %d)",
                            vv_path_basename(s->path), level, s->ops->levels(s->user));
    for (int k = 0; k < 3; k++)
        if (lo[k] < 0 || hi[k] < lo[k] || hi[k] >= h->dims[k])
            return vv_error_set(VV_ERR_INVALID,
                                "source: %s: box %d..%d outside level %d's %d voxels along axis %d",
                                vv_path_basename(s->path), lo[k], hi[k], level, h->dims[k], k);
    return VV_OK;
}

vv_status
vv_source_read_box(vv_source *s, int level, const int lo[3], const int hi[3], vv_volume **out) {
    if (!s || !lo || !hi || !out)
        return vv_error_set(VV_ERR_INVALID, "source: NULL argument");
    *out = NULL;
    const vv_status st = check_box(s, level, lo, hi);
    return st != VV_OK ? st : s->ops->read_box(s->user, level, lo, hi, out);
}

/* The channel methods of @p s's table (a version 1 table has none). */
static int
has_channels(const vv_source *s) {
    return s->ops->version >= 2 && s->ops->channels && s->ops->channel_level &&
           s->ops->channel_read_box && s->ops->channel_proxy;
}

int
vv_source_channels(const vv_source *s) {
    if (!s || !has_channels(s))
        return 1;
    const int n = s->ops->channels(s->user);
    return n > 1 ? n : 1;
}

const vv_volume *
vv_source_channel_level(const vv_source *s, int channel, int level) {
    if (!s || channel < 0 || channel >= vv_source_channels(s))
        return NULL;
    if (channel == 0 && !has_channels(s))
        return vv_source_level(s, level);
    return level >= 0 && level < s->ops->levels(s->user)
               ? s->ops->channel_level(s->user, channel, level)
               : NULL;
}

/* VV_ERR_INVALID unless @p channel is one of @p s's. */
static vv_status
check_channel(const vv_source *s, int channel) {
    const int n = vv_source_channels(s);
    if (channel < 0 || channel >= n)
        return vv_error_set(VV_ERR_INVALID, "source: %s: no channel %d (it carries %d)",
                            vv_path_basename(s->path), channel, n);
    return VV_OK;
}

vv_status
vv_source_channel_read_box(vv_source *s, int channel, int level, const int lo[3], const int hi[3],
                           vv_volume **out) {
    if (!s || !lo || !hi || !out)
        return vv_error_set(VV_ERR_INVALID, "source: NULL argument");
    *out = NULL;
    vv_status st = check_channel(s, channel);
    if (st != VV_OK || !has_channels(s))
        return st != VV_OK ? st : vv_source_read_box(s, level, lo, hi, out);
    if ((st = check_box(s, level, lo, hi)) != VV_OK)
        return st;
    return s->ops->channel_read_box(s->user, channel, level, lo, hi, out);
}

vv_status
vv_source_channel_proxy(vv_source *s, int channel, int level, vv_volume **out) {
    if (!s || !out)
        return vv_error_set(VV_ERR_INVALID, "source: NULL argument");
    *out = NULL;
    vv_status st = check_channel(s, channel);
    if (st != VV_OK || !has_channels(s))
        return st != VV_OK ? st : vv_source_proxy(s, level, out);
    if (!vv_source_level(s, level))
        return vv_error_set(VV_ERR_INVALID, "source: %s: no level %d for a proxy (it has %d)",
                            vv_path_basename(s->path), level, s->ops->levels(s->user));
    return s->ops->channel_proxy(s->user, channel, level, out);
}

vv_status
vv_source_box(void *source, const int lo[3], const int hi[3], vv_volume **out) {
    return vv_source_read_box(source, 0, lo, hi, out);
}

vv_status
vv_source_proxy(vv_source *s, int level, vv_volume **out) {
    if (!s || !out)
        return vv_error_set(VV_ERR_INVALID, "source: NULL argument");
    *out = NULL;
    if (!vv_source_level(s, level))
        return vv_error_set(VV_ERR_INVALID, "source: %s: no level %d for a proxy (it has %d)",
                            vv_path_basename(s->path), level, s->ops->levels(s->user));
    return s->ops->proxy(s->user, level, out);
}

void
vv_source_stats_get(const vv_source *s, vv_source_stats *st) {
    if (!st)
        return;
    memset(st, 0, sizeof *st);
    if (!s)
        return;
    st->kind = s->ops->kind;
    s->ops->stats(s->user, st);
    st->kind = s->ops->kind;
    if (s->cache)
        st->limit_bytes = vv_cache_limit(s->cache);
}

int
vv_source_loading(vv_source *s) {
    return s && s->ops->loading ? s->ops->loading(s->user) : 0;
}

int
vv_source_wait(vv_source *s, double seconds) {
    return s && s->ops->wait ? s->ops->wait(s->user, seconds) : 0;
}

vv_status
vv_source_read_ahead(vv_source *s, const vv_source *like) {
    if (!s || !like)
        return vv_error_set(VV_ERR_INVALID, "source: NULL argument");
    if (s->ops != like->ops || s->ops->version < 2 || !s->ops->read_ahead)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "source: %s: read-ahead is between two pyramids of one kind",
                            vv_path_basename(s->path));
    return s->ops->read_ahead(s->user, like->user);
}

void
vv_source_cancel(vv_source *s) {
    if (s && s->ops->cancel)
        s->ops->cancel(s->user);
}

int
vv_source_brick_view(vv_source *s, vv_brick_source *out) {
    if (!s || !s->ops->bricks)
        return 0;
    s->ops->bricks(s->user, out);
    return 1;
}

int
vv_source_multires_view(vv_source *s, vv_multires_source *out) {
    if (!s || s->ops->kind != VV_SOURCE_PYRAMID || !s->ops->multires)
        return 0;
    s->ops->multires(s->user, out);
    return 1;
}

/* ---- stores ------------------------------------------------------------------------- */

vv_status
vv_store_set_level(vv_store *st, int level, vv_voxel_type type, const int dims[3],
                   const int cdims[3]) {
    if (!st || level < 0 || level >= VV_STORE_MAX_LEVELS)
        return vv_error_set(VV_ERR_INVALID, "store: no level %d", level);
    const int one[3] = {1, 1, 1};
    const vv_status s = vv_volume_new(&st->lv[level].hdr, one, type);
    if (s != VV_OK)
        return s;
    memcpy(st->lv[level].hdr->dims, dims, sizeof st->lv[level].hdr->dims); /* geometry only */
    memcpy(st->lv[level].cdims, cdims, sizeof st->lv[level].cdims);
    return VV_OK;
}

void
vv_store_close(vv_store *st) {
    if (!st)
        return;
    for (int i = 0; i < VV_STORE_MAX_LEVELS; i++)
        vv_volume_free(st->lv[i].hdr);
    if (st->close && st->ctx)
        st->close(st->ctx);
    memset(st, 0, sizeof *st);
}

/* ---- a volume in memory ------------------------------------------------------------ */

static int
mem_levels(void *user) {
    (void)user;
    return 1;
}

static const vv_volume *
mem_level(void *user, int level) {
    (void)level;
    return user;
}

static vv_status
mem_read_box(void *user, int level, const int lo[3], const int hi[3], vv_volume **out) {
    (void)level;
    const vv_volume *v = user;
    int dims[3];
    for (int k = 0; k < 3; k++)
        dims[k] = hi[k] - lo[k] + 1;
    if (dims[0] == v->dims[0] && dims[1] == v->dims[1] && dims[2] == v->dims[2]) {
        *out = vv_volume_ref((vv_volume *)v);
        return VV_OK;
    }
    vv_volume *b = NULL;
    vv_status s = vv_volume_new(&b, dims, v->type);
    if (s != VV_OK)
        return s;
    const size_t vs = vv_voxel_type_size(v->type), row = (size_t)dims[0] * vs;
    const unsigned char *src = v->data;
    unsigned char *dst = b->data;
    for (int z = 0; z < dims[2]; z++)
        for (int y = 0; y < dims[1]; y++)
            memcpy(dst + ((size_t)z * (size_t)dims[1] + (size_t)y) * row,
                   src + (((size_t)(z + lo[2]) * (size_t)v->dims[1] + (size_t)(y + lo[1])) *
                              (size_t)v->dims[0] +
                          (size_t)lo[0]) *
                             vs,
                   row);
    memcpy(b->spacing, v->spacing, sizeof b->spacing);
    memcpy(b->origin, v->origin, sizeof b->origin);
    memcpy(b->direction, v->direction, sizeof b->direction);
    memcpy(b->range, v->range, sizeof b->range);
    b->unit = v->unit;
    b->space = v->space;
    *out = b;
    return VV_OK;
}

static vv_status
mem_proxy(void *user, int level, vv_volume **out) {
    (void)level;
    *out = vv_volume_ref(user);
    return VV_OK;
}

static const vv_volume *
mem_header(void *user) {
    return user;
}

static void
mem_grid(void *user, int nb[3]) {
    (void)user;
    nb[0] = nb[1] = nb[2] = 1;
}

static void
mem_info(void *user, int index, vv_brick_info *out) {
    const vv_volume *v = user;
    (void)index;
    memset(out, 0, sizeof *out);
    for (int a = 0; a < 3; a++) {
        out->lo[a] = out->slo[a] = 0;
        out->hi[a] = out->shi[a] = v->dims[a] - 1;
    }
    out->vmin = (float)v->range[0];
    out->vmax = (float)v->range[1];
}

static vv_status
mem_load(void *user, int index, vv_volume **out) {
    (void)index;
    *out = vv_volume_ref(user);
    return VV_OK;
}

void
vv_volume_brick_view(vv_volume *v, vv_brick_source *out) {
    memset(out, 0, sizeof *out);
    out->version = VV_BRICK_SOURCE_VERSION;
    out->user = v;
    out->header = mem_header;
    out->grid = mem_grid;
    out->info = mem_info;
    out->load = mem_load;
}

static void
mem_bricks(void *user, vv_brick_source *out) {
    vv_volume_brick_view(user, out);
}

static void
mem_stats(void *user, vv_source_stats *out) {
    (void)user;
    out->n_bricks = 1;
    out->bricks_grid[0] = out->bricks_grid[1] = out->bricks_grid[2] = 1;
}

static void
mem_close(void *user) {
    vv_volume_free(user);
}

static const vv_source_ops memory_ops = {
    .version = VV_SOURCE_OPS_VERSION,
    .kind = VV_SOURCE_MEMORY,
    .format = "memory",
    .levels = mem_levels,
    .level = mem_level,
    .read_box = mem_read_box,
    .proxy = mem_proxy,
    .bricks = mem_bricks,
    .stats = mem_stats,
    .close = mem_close,
};

vv_status
vv_source_new_memory(vv_source **out, vv_volume *volume) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "source: NULL output");
    *out = NULL;
    if (!volume)
        return vv_error_set(VV_ERR_INVALID, "source: NULL volume");
    return vv_source_new(out, &memory_ops, vv_volume_ref(volume), NULL, NULL, NULL);
}

vv_volume *
vv_source_volume(const vv_source *s) {
    return s && s->ops == &memory_ops ? s->user : NULL;
}
