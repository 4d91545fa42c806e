/*
 * The OME-Zarr store of a pyramid (src/io/store/pyramid.h): the multiscales
 * levels of one channel at one time step, each level's .zarray parsed
 * once, and its chunks read and decoded in this process (reentrant: the
 * pyramid decodes a box's chunks on every core, a scratch buffer of the
 * largest chunk each). The level's chunk box is the store's own.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/store/pyramid.h"
#include "io/store/zarr.h"

/* One level's parsed array and its layout (which points into it). */
typedef struct zp_level {
    zr_array a;
    zr_layout J;
} zp_level;

typedef struct zp_store {
    int n_levels;
    zp_level lv[VV_PYRAMID_MAX_LEVELS];
} zp_store;

static vv_status
zp_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
              const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    const zp_level *l = &((const zp_store *)ctx)->lv[level];
    return vv_zr_copy_chunk(&l->J, vv_zr_chunk_linear(&l->J, c), scratch, dst, org, dims, missing,
                            file_bytes, NULL);
}

/* A remote store's chunks of one level in batches (vv_zr_copy_chunks). */
static vv_status
zp_read_many(void *ctx, int level, int n, const int *c, unsigned char *const *dst, const int *org,
             const int *dims, int nthreads, int *missing, uint64_t *file_bytes, double *range,
             int (*stale)(void *stale_user, int i), void *stale_user, int *cancelled) {
    const zp_level *l = &((const zp_store *)ctx)->lv[level];
    uint64_t *L = calloc((size_t)(n > 0 ? n : 1), sizeof *L);
    zr_dest *d = calloc((size_t)(n > 0 ? n : 1), sizeof *d);
    vv_status s = L && d ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory for %d chunks", n);
    for (int i = 0; s == VV_OK && i < n; i++) {
        L[i] = vv_zr_chunk_linear(&l->J, c + 3 * i);
        d[i].dst = dst[i];
        memcpy(d[i].org, org + 3 * i, sizeof d[i].org);
        memcpy(d[i].dims, dims + 3 * i, sizeof d[i].dims);
        d[i].range[0] = INFINITY;
        d[i].range[1] = -INFINITY;
        d[i].stale = stale;
        d[i].stale_u = stale_user;
        d[i].stale_i = i;
    }
    if (s == VV_OK)
        s = vv_zr_copy_chunks(&l->J, L, (uint64_t)n, NULL, NULL, NULL, d, nthreads, NULL);
    for (int i = 0; s == VV_OK && i < n; i++) {
        if (cancelled)
            cancelled[i] = d[i].cancelled;
        if (d[i].cancelled)
            continue;
        missing[i] = d[i].missing;
        file_bytes[i] = d[i].file_bytes;
        range[2 * i] = d[i].range[0];
        range[2 * i + 1] = d[i].range[1];
    }
    free(L);
    free(d);
    return s;
}

static void
zp_close(void *ctx) {
    zp_store *z = ctx;
    for (int i = 0; z && i < VV_PYRAMID_MAX_LEVELS; i++)
        vv_zr_array_release(&z->lv[i].a);
    free(ctx);
}

/* Level @p i's metadata and layout; each level must have level 0's axes,
 * channels, steps and type. */
static vv_status
zp_open_level(zp_store *z, const char *path, int i, int channel, int time, vv_load_info *info) {
    zp_level *l = &z->lv[i];
    vv_status s = vv_zr_parse_store(path, i, &l->a, channel, i == 0 ? info : NULL, NULL);
    if (s == VV_OK)
        s = vv_zr_layout(&l->a, channel, time, &l->J);
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
    }
    return VV_OK;
}

vv_status
vv_zr_pyramid_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    memset(st, 0, sizeof *st);
    st->name = "zarr";
    int n_levels = 1;
    zr_array *probe = calloc(1, sizeof *probe);
    if (!probe)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = vv_zr_parse_store(path, 0, probe, channel, NULL, &n_levels);
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
        if ((s = zp_open_level(z, path, i, channel, time, info)) != VV_OK)
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
    st->n_channels = (int)z->lv[0].J.nc;
    st->n_times = (int)z->lv[0].J.nt;
    st->has_range = z->lv[0].a.has_window;
    st->range[0] = z->lv[0].a.window[0];
    st->range[1] = z->lv[0].a.window[1];
    return VV_OK;
}
