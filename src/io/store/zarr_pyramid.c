/*
 * The OME-Zarr store of a pyramid (src/io/store/pyramid.h): the multiscales
 * levels of one channel, or of several at once, at one time step, each
 * level's .zarray parsed once, and its chunks read and decoded in this
 * process (reentrant: the pyramid decodes a box's chunks on every core, a
 * scratch buffer of the largest chunk each). The level's chunk box is the
 * store's own. With several channels a read fills each channel's block in
 * turn (vv_store.n_ch); channels that one chunk of the array holds (chunked
 * by more than one along c) are decoded once and copied apart.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/pyramid.h"
#include "io/store/zarr.h"

/* One level's parsed array and its layouts (which point into it): J of
 * the first channel, Jc[k] of channel k (Jc[0] is J). */
typedef struct zp_level {
    zr_array a;
    zr_layout J;
    zr_layout Jc[VV_STORE_MAX_CHANNELS];
} zp_level;

typedef struct zp_store {
    int n_levels;
    int n_ch; /* channels a read fills (1: J's alone) */
    zp_level lv[VV_PYRAMID_MAX_LEVELS];
} zp_store;

static vv_status
zp_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
              const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    const zp_store *z = ctx;
    const zp_level *l = &z->lv[level];
    if (z->n_ch <= 1)
        return vv_zr_copy_chunk(&l->J, vv_zr_chunk_linear(&l->J, c), scratch, dst, org, dims,
                                missing, file_bytes, NULL);
    /* each channel's unit, a unit read once for the channels after it that it holds */
    const uint64_t L = vv_zr_chunk_linear(&l->J, c);
    const size_t bb = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2] * l->a.esize;
    uint64_t have[ZR_MAX_DIM], bytes = 0;
    int held = 0, unit_missing = 0, all_missing = 1;
    for (int k = 0; k < z->n_ch; k++) {
        uint64_t idx[ZR_MAX_DIM];
        vv_zr_unit_index(&l->Jc[k], L, idx);
        if (!held || memcmp(idx, have, sizeof idx)) {
            uint64_t fb = 0;
            vv_status s = vv_zr_read_chunk(&l->a, idx, scratch, l->J.cbytes, &unit_missing, &fb);
            if (s != VV_OK)
                return s;
            vv_zr_unit_host(&l->J, scratch, unit_missing);
            memcpy(have, idx, sizeof have);
            held = 1;
            bytes += fb;
        }
        vv_zr_unit_copy(&l->Jc[k], idx, scratch, dst + (size_t)k * bb, org, dims, NULL);
        all_missing &= unit_missing;
    }
    if (missing)
        *missing = all_missing;
    if (file_bytes)
        *file_bytes = bytes;
    return VV_OK;
}

/* A remote store's chunks of one level in batches (vv_zr_copy_chunks). */
/* A remote store's chunks of one level in batches (vv_zr_copy_chunks):
 * with several channels (each its own chunks: the array chunked by one
 * along c), one batch a channel, in the channels' order, a chunk cancelled
 * in any batch left out of the later ones. */
static vv_status
zp_read_many(void *ctx, int level, int n, const int *c, unsigned char *const *dst, const int *org,
             const int *dims, int nthreads, int *missing, uint64_t *file_bytes, double *range,
             int (*stale)(void *stale_user, int i), void *stale_user, int *cancelled) {
    const zp_store *z = ctx;
    const zp_level *l = &z->lv[level];
    const int nch = z->n_ch > 1 ? z->n_ch : 1;
    uint64_t *L = calloc((size_t)(n > 0 ? n : 1), sizeof *L);
    zr_dest *d = calloc((size_t)(n > 0 ? n : 1), sizeof *d);
    int *gone = calloc((size_t)(n > 0 ? n : 1), sizeof *gone);
    vv_status s =
        L && d && gone ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory for %d chunks", n);
    for (int k = 0; k < nch && s == VV_OK; k++) {
        int m = 0; /* the chunks still wanted, in order */
        for (int i = 0; i < n; i++) {
            if (gone[i])
                continue;
            const size_t bb = (size_t)dims[3 * i] * (size_t)dims[3 * i + 1] *
                              (size_t)dims[3 * i + 2] * l->a.esize;
            L[m] = vv_zr_chunk_linear(&l->J, c + 3 * i);
            memset(&d[m], 0, sizeof d[m]);
            d[m].dst = dst[i] + (size_t)k * bb;
            memcpy(d[m].org, org + 3 * i, sizeof d[m].org);
            memcpy(d[m].dims, dims + 3 * i, sizeof d[m].dims);
            d[m].range[0] = INFINITY;
            d[m].range[1] = -INFINITY;
            d[m].stale = stale;
            d[m].stale_u = stale_user;
            d[m].stale_i = i;
            m++;
        }
        if (m > 0)
            s = vv_zr_copy_chunks(&l->Jc[k], L, (uint64_t)m, NULL, NULL, NULL, d, nthreads, NULL);
        for (int j = 0; s == VV_OK && j < m; j++) {
            const int i = d[j].stale_i;
            if (d[j].cancelled) {
                gone[i] = 1;
                continue;
            }
            missing[i] = k == 0 ? d[j].missing : missing[i] && d[j].missing;
            file_bytes[i] = (k == 0 ? 0 : file_bytes[i]) + d[j].file_bytes;
            range[2 * ((size_t)i * (size_t)nch + (size_t)k)] = d[j].range[0];
            range[2 * ((size_t)i * (size_t)nch + (size_t)k) + 1] = d[j].range[1];
        }
    }
    for (int i = 0; s == VV_OK && cancelled && i < n; i++)
        cancelled[i] = gone[i];
    free(L);
    free(d);
    free(gone);
    return s;
}

static void
zp_close(void *ctx) {
    zp_store *z = ctx;
    for (int i = 0; z && i < VV_PYRAMID_MAX_LEVELS; i++)
        vv_zr_array_release(&z->lv[i].a);
    free(ctx);
}

/* Level @p i's metadata and layouts (channels @p channels[0 .. z->n_ch),
 * or @p channel alone); each level must have level 0's axes, channels,
 * steps, type and channel chunking. */
static vv_status
zp_open_level(zp_store *z, const char *path, int i, int channel, const int *channels, int time,
              vv_load_info *info) {
    zp_level *l = &z->lv[i];
    if (channels)
        channel = channels[0];
    vv_status s = vv_zr_parse_store(path, i, &l->a, channel, i == 0 ? info : NULL, NULL);
    if (s == VV_OK)
        s = vv_zr_layout(&l->a, channel, time, &l->J);
    for (int k = 0; channels && k < z->n_ch && s == VV_OK; k++)
        if ((s = vv_zr_layout(&l->a, channels[k], time, &l->Jc[k])) == VV_OK)
            l->Jc[k].a = &l->a;
    if (!channels && s == VV_OK)
        l->Jc[0] = l->J; /* zp_read_many reads channel k by Jc[k] */
    /* each reading thread holds a scratch buffer of the largest chunk (an
     * inner chunk of a shard), and what it reads and decodes it from */
    if (s == VV_OK)
        s = vv_memory_budget_check((uint64_t)l->J.cbytes + vv_zr_read_held(&l->a, l->J.cbytes),
                                   "a Zarr chunk's buffer");
    if (s != VV_OK)
        return vv_error_prefix(s, "level %d", i);
    l->J.a = &l->a; /* the layout points into the level it describes */
    if (i > 0) {
        const zp_level *l0 = &z->lv[0];
        if (l->a.ndim != l0->a.ndim || l->a.type != l0->a.type || l->J.cax != l0->J.cax ||
            l->J.tax != l0->J.tax || l->J.nc != l0->J.nc || l->J.nt != l0->J.nt)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: its axes, channels, steps or type differ from level 0's "
                                "(inconsistent multiscales)",
                                i);
        if (l->J.cax >= 0 && l->a.chunks[l->J.cax] != l0->a.chunks[l0->J.cax])
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: chunks of %llu along the channel axis, level 0's of "
                                "%llu (inconsistent multiscales)",
                                i, (unsigned long long)l->a.chunks[l->J.cax],
                                (unsigned long long)l0->a.chunks[l0->J.cax]);
    }
    return VV_OK;
}

/* vv_zr_pyramid_store of @p channel, or of channels[0 .. n) when @p channels. */
static vv_status
zp_store_open(vv_store *st, const char *path, int channel, int n, const int *channels, int time,
              vv_load_info *info) {
    memset(st, 0, sizeof *st);
    st->name = "zarr";
    int n_levels = 1;
    zr_array *probe = calloc(1, sizeof *probe);
    if (!probe)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = vv_zr_parse_store(path, 0, probe, channel, NULL, &n_levels);
    if (s == VV_OK && probe->zarr_format == ZR_N5)
        st->name = "n5";
    vv_zr_array_release(probe);
    free(probe);
    if (s != VV_OK)
        return s;
    if (n_levels > VV_PYRAMID_MAX_LEVELS)
        return vv_error_set(VV_ERR_LIMIT, "%d levels (at most %d are read)", n_levels,
                            VV_PYRAMID_MAX_LEVELS);
    zp_store *z = calloc(1, sizeof *z);
    if (!z)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    st->ctx = z;
    z->n_ch = channels ? n : 1;
    st->close = zp_close;
    st->read_chunk = zp_read_chunk;
    /* a remote store's reads wait on the network: as many at once as the
     * transport keeps in flight */
    st->parallel = bs_is_url(path) ? bs_http_in_flight() : 1;
    /* and they are asked together, many in flight (a local store's are
     * read chunk by chunk on the cores) */
    if (bs_is_url(path))
        st->read_many = zp_read_many;
    for (int i = 0; i < n_levels; i++) {
        if ((s = zp_open_level(z, path, i, channel, channels, time, info)) != VV_OK)
            return s;
        z->n_levels = st->n_levels = i + 1;
        const zp_level *l = &z->lv[i];
        if ((s = vv_store_set_level(st, i, l->a.type, l->J.dims, l->J.cdims)) != VV_OK)
            return s;
        vv_zr_geometry(&l->J, st->lv[i].hdr);
        st->scratch = l->J.cbytes > st->scratch ? l->J.cbytes : st->scratch;
    }
    for (int i = 0; i < z->n_levels; i++)
        if (z->lv[i].a.zarr_format == 3 && z->lv[i].a.nshard > 1)
            st->read_many = NULL; /* nested shards: a thread a request, read_chunk */
    /* channels chunked together: decoded once a chunk by read_chunk (the
     * batches of read_many are a channel's each) */
    if (z->n_ch > 1 && z->lv[0].J.cax >= 0 && z->lv[0].a.chunks[z->lv[0].J.cax] > 1)
        st->read_many = NULL;
    st->n_channels = (int)z->lv[0].J.nc;
    st->n_times = (int)z->lv[0].J.nt;
    st->has_range = z->lv[0].a.has_window;
    st->range[0] = z->lv[0].a.window[0];
    st->range[1] = z->lv[0].a.window[1];
    return VV_OK;
}

vv_status
vv_zr_pyramid_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    return zp_store_open(st, path, channel, 1, NULL, time, info);
}

vv_status
vv_zr_pyramid_store_channels(vv_store *st, const char *path, int n, const int *channels, int time,
                             vv_load_info *info) {
    if (!st || !channels || n < 1 || n > VV_STORE_MAX_CHANNELS)
        return vv_error_set(VV_ERR_INVALID, "%d channels asked (1 .. %d)", n,
                            VV_STORE_MAX_CHANNELS);
    vv_status s = zp_store_open(st, path, channels[0], n, channels, time, info);
    if (s != VV_OK || n == 1)
        return s;
    st->n_ch = n;
    /* each channel's omero name, colour, window and range (level 0's metadata) */
    zr_array *a = calloc(1, sizeof *a);
    if (!a)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int k = 0; k < n && s == VV_OK; k++) {
        vv_load_info one;
        memset(&one, 0, sizeof one);
        vv_load_info *ik = info ? &info[k] : &one;
        if (k > 0 && info) {
            memset(ik, 0, sizeof *ik);
            ik->n_channels = info[0].n_channels;
            ik->n_times = info[0].n_times;
            ik->n_levels = info[0].n_levels;
            ik->is_label = info[0].is_label;
        }
        if (k == 0) {
            st->ch_has_range[0] = st->has_range;
            memcpy(st->ch_range[0], st->range, sizeof st->ch_range[0]);
            continue;
        }
        memset(a, 0, sizeof *a);
        s = vv_zr_parse_store(path, 0, a, channels[k], ik, NULL);
        st->ch_has_range[k] = s == VV_OK && a->has_window;
        st->ch_range[k][0] = a->window[0];
        st->ch_range[k][1] = a->window[1];
        vv_zr_array_release(a);
    }
    free(a);
    return s;
}
