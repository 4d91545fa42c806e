/*
 * Opening and freeing a pyramid (src/io/store/pyramid.h: vv_pyramid_open_store,
 * vv_pyramid_free; the state in pyramid_internal.h). Opening takes a
 * store whole and reads its metadata only (each level's geometry and
 * chunk grid, the chunks' ranges its index gives) and the coarsest level,
 * whose voxels give the proxy and, without a window in the metadata, the
 * value range; it chooses the node size and the boxes held at once that
 * the memory limit allows, and joins the process's cache as a client
 * (its eviction from pyramid.c, its planned next use from pyramid_load.c).
 * Freeing stops the loader, drops the plan and every chunk, and closes
 * the store. The top of the pyramid's three files: it calls the chunks'
 * (pyramid.c) and the loader's (pyramid_load.c).
 */
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/cache.h"
#include "core/internal.h"
#include "io/store/pyramid.h"
#include "io/store/pyramid_internal.h"

#define PY_MAX_LEVEL_CHUNKS ((uint64_t)1 << 26)

void
vv_pyramid_free(vv_pyramid *p) {
    if (!p)
        return;
    py_stop_loaders(p);
    free(p->queue);
    free(p->last_box);
    pthread_mutex_lock(p->lock);
    py_clear_plan(p);
    py_each_chunk(p, py_drop_chunk);
    pthread_mutex_unlock(p->lock);
    vv_cache_client_remove(&p->cl);
    vv_cache_free(p->cache);
    for (int i = 0; i < p->n_levels; i++) {
        py_level *l = &p->lv[i];
        vv_volume_free(l->hdr);
        for (int k = 0; k < VV_STORE_MAX_CHANNELS; k++)
            vv_volume_free(l->chdr[k]);
        free(l->cmin);
        free(l->cmax);
        free(l->known);
        free(l->read_frame);
        free(l->frame_reads);
    }
    vv_store_close(&p->store);
    pthread_mutex_destroy(&p->store_lock);
    pthread_cond_destroy(&p->work);
    pthread_cond_destroy(&p->arrived);
    free(p);
}

/* Chunks of under PY_SMALL_CHUNK_VOXELS voxels: at most PY_SMALL_CHUNKS_MAX
 * of them a level (real stores chunk by 32^3 to 256^3). */
#define PY_SMALL_CHUNK_VOXELS 4096
#define PY_SMALL_CHUNKS_MAX 65536

/* Level @p i's layout, header and chunk tables from the store's level;
 * each level must have level 0's type and no more voxels. */
static vv_status
open_level(vv_pyramid *p, int i) {
    py_level *l = &p->lv[i];
    vv_store_level *sl = &p->store.lv[i];
    if (!sl->hdr)
        return vv_error_set(VV_ERR_FORMAT, "level %d: no geometry", i);
    l->type = sl->hdr->type;
    l->esize = vv_voxel_type_size(l->type);
    for (int k = 0; k < 3; k++) {
        l->dims[k] = sl->hdr->dims[k];
        l->cdims[k] = sl->cdims[k];
        if (l->dims[k] < 1 || l->cdims[k] < 1)
            return vv_error_set(VV_ERR_FORMAT, "level %d: %d voxels in chunks of %d along axis %d",
                                i, l->dims[k], l->cdims[k], k);
        l->nchunks[k] = (l->dims[k] + l->cdims[k] - 1) / l->cdims[k];
    }
    /* each chunk is a piece the cache keeps apart, with its bookkeeping:
     * many chunks of a few voxels held gigabytes of it for a 4 MiB level
     * (fuzz_zarr: chunks of one voxel) */
    const uint64_t nch = (uint64_t)l->nchunks[0] * (uint64_t)l->nchunks[1] * l->nchunks[2];
    const uint64_t cvox = (uint64_t)l->cdims[0] * (uint64_t)l->cdims[1] * l->cdims[2];
    if (nch > PY_SMALL_CHUNKS_MAX && cvox < PY_SMALL_CHUNK_VOXELS)
        return vv_error_set(VV_ERR_LIMIT,
                            "level %d: %llu chunks of %d x %d x %d voxels (chunks of under %d "
                            "voxels are read only when there are at most %d: rechunk the store)",
                            i, (unsigned long long)nch, l->cdims[0], l->cdims[1], l->cdims[2],
                            PY_SMALL_CHUNK_VOXELS, PY_SMALL_CHUNKS_MAX);
    if (i > 0) {
        const py_level *l0 = &p->lv[0];
        if (l->type != l0->type)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: its type differs from level 0's (inconsistent "
                                "multiscales)",
                                i);
        for (int k = 0; k < 3; k++)
            if (l->dims[k] > l0->dims[k])
                return vv_error_set(VV_ERR_FORMAT,
                                    "level %d: %d voxels along axis %d, more than level 0's %d "
                                    "(inconsistent multiscales)",
                                    i, l->dims[k], k, l0->dims[k]);
    }
    uint64_t n = 1;
    for (int k = 0; k < 3; k++)
        n *= (uint64_t)l->nchunks[k];
    l->n_chunks = n;
    const uint64_t nchan = (uint64_t)p->n_ch;
    if (n <= PY_MAX_LEVEL_CHUNKS) {
        l->cmin = malloc(sizeof(float) * n * nchan);
        l->cmax = malloc(sizeof(float) * n * nchan);
        l->known = calloc(n, 1);
        l->read_frame = calloc(n, sizeof(uint32_t));
        l->frame_reads = calloc(n, sizeof(uint16_t));
        if (!l->cmin || !l->cmax || !l->known || !l->read_frame || !l->frame_reads)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        /* ranges the store's index gives before any chunk is read */
        for (uint64_t L = 0; p->store.chunk_range && p->n_ch == 1 && L < n; L++) {
            const int c[3] = {(int)(L % (uint64_t)l->nchunks[0]),
                              (int)(L / (uint64_t)l->nchunks[0] % (uint64_t)l->nchunks[1]),
                              (int)(L / ((uint64_t)l->nchunks[0] * (uint64_t)l->nchunks[1]))};
            double lo, hi;
            if (p->store.chunk_range(p->store.ctx, i, c, &lo, &hi) && lo <= hi) {
                l->cmin[L] = (float)lo;
                l->cmax[L] = (float)hi;
                l->known[L] = 1;
            }
        }
    }
    l->hdr = sl->hdr; /* taken */
    sl->hdr = NULL;
    /* the other channels' headers (their ranges are set once known) */
    for (int k = 1; k < p->n_ch; k++) {
        const int one[3] = {1, 1, 1};
        vv_status s = vv_volume_new(&l->chdr[k], one, l->type);
        if (s != VV_OK)
            return s;
        memcpy(l->chdr[k]->dims, l->hdr->dims, sizeof l->chdr[k]->dims); /* geometry only */
        vv_volume_take_geometry(l->chdr[k], l->hdr);
        l->chdr[k]->modification = l->hdr->modification;
    }
    return VV_OK;
}

/* The bytes a node of @p cells cells a side holds while rendered (its box:
 * the cells, a ghost voxel beyond each face and the half-voxel shifts of
 * coarser levels): the box, the ray caster's 16-bit or float copy and
 * cached gradients (src/render/sample.h); and in *chunks the bytes of
 * the decoded chunks such a box overlaps at most (any level). */
static uint64_t
working_set(const vv_pyramid *p, int cells, uint64_t *chunks) {
    uint64_t v = (uint64_t)p->n_ch, worst = 0; /* every channel's box and copies */
    for (int k = 0; k < 3; k++) {
        const int d = p->lv[0].dims[k], box = cells + 5;
        v *= (uint64_t)(d < box ? d : box);
    }
    for (int i = 0; i < p->n_levels; i++) {
        const py_level *l = &p->lv[i];
        uint64_t c = l->esize * (uint64_t)p->n_ch;
        for (int k = 0; k < 3; k++) {
            const int box = cells + 5, cd = l->cdims[k];
            int n = (box + cd - 1) / cd + 1;
            n = n < l->nchunks[k] ? n : l->nchunks[k];
            c *= (uint64_t)n * (uint64_t)(cd < l->dims[k] ? cd : l->dims[k]);
        }
        worst = c > worst ? c : worst;
    }
    *chunks = worst;
    return v * (p->lv[0].esize + 4 + 4 + p->lv[0].esize);
}

static vv_status
pyramid_open(vv_pyramid *p, vv_load_info *info) {
    vv_status s = VV_OK;
    if (p->store.n_levels < 1 || p->store.n_levels > VV_PYRAMID_MAX_LEVELS)
        return vv_error_set(VV_ERR_LIMIT, "%d levels (1 .. %d are read)", p->store.n_levels,
                            VV_PYRAMID_MAX_LEVELS);
    if (p->store.n_ch < 0 || p->store.n_ch > VV_STORE_MAX_CHANNELS)
        return vv_error_set(VV_ERR_LIMIT, "%d channels a read (at most %d)", p->store.n_ch,
                            VV_STORE_MAX_CHANNELS);
    p->n_ch = p->store.n_ch > 1 ? p->store.n_ch : 1;
    for (int i = 0; i < p->store.n_levels; i++) {
        s = open_level(p, i);
        p->n_levels = i + 1;
        if (s != VV_OK)
            return s;
    }
    p->limit = vv_cache_limit(p->cache);
    /* the largest node (64, 32, 16 or 8 cells) whose box, working set and
     * chunks fit the limit */
    uint64_t ws = 0, chunks = 0;
    int cells = VV_BRICK_CELLS;
    for (; cells >= 8; cells /= 2) {
        ws = working_set(p, cells, &chunks);
        if (ws + chunks <= p->limit)
            break;
    }
    if (cells < 8)
        return vv_error_set(VV_ERR_LIMIT,
                            "memory limit of %llu bytes is smaller than a box of 8 cells, its "
                            "working set and its chunks (%llu bytes)",
                            (unsigned long long)p->limit, (unsigned long long)(ws + chunks));
    p->node_cells = cells;
    /* boxes held at once (the driver renders that many nodes at a time, one
     * a thread): as many working sets as an eighth of the limit holds, at
     * most 8; the cache gets the rest */
    uint64_t boxes = ws > 0 ? p->limit / 8 / ws : 1;
    boxes = boxes < 1 ? 1 : boxes > 8 ? 8 : boxes;
    if (ws * boxes + chunks > p->limit)
        boxes = 1;
    p->boxes = (int)boxes;
    /* the cache holds the rest, with every other source's pieces */
    p->cl.reserve = ws * boxes;
    p->cl.next_use = py_client_next_use;
    p->cl.drop = py_client_drop;
    vv_cache_client_add(p->cache, &p->cl);
    /* each channel's range: the store's (an omero window), else the
     * coarsest level's (its chunks read for all channels at once) */
    int known = 1;
    for (int k = 0; k < p->n_ch; k++) {
        const int has = p->n_ch > 1 ? p->store.ch_has_range[k] : p->store.has_range;
        const double *r = p->n_ch > 1 ? p->store.ch_range[k] : p->store.range;
        p->crange[k][0] = has ? r[0] : 0;
        p->crange[k][1] = has ? r[1] : 1;
        known &= has;
    }
    if (!known) {
        const py_level *c = &p->lv[p->n_levels - 1];
        const int lo[3] = {0, 0, 0}, hi[3] = {c->dims[0] - 1, c->dims[1] - 1, c->dims[2] - 1};
        vv_volume *v[VV_STORE_MAX_CHANNELS] = {NULL};
        if ((s = py_box_read(p, p->n_levels - 1, -1, lo, hi, v, NULL)) != VV_OK)
            return s;
        for (int k = 0; k < p->n_ch; k++) {
            const int has = p->n_ch > 1 ? p->store.ch_has_range[k] : p->store.has_range;
            vv_volume_update_range(v[k]);
            if (!has) {
                p->crange[k][0] = v[k]->range[0];
                p->crange[k][1] = v[k]->range[1];
            }
            vv_volume_free(v[k]);
        }
    }
    p->range[0] = p->crange[0][0];
    p->range[1] = p->crange[0][1];
    for (int i = 0; i < p->n_levels; i++)
        for (int k = 0; k < p->n_ch; k++) {
            vv_volume *h = k ? p->lv[i].chdr[k] : p->lv[i].hdr;
            h->range[0] = p->crange[k][0];
            h->range[1] = p->crange[k][1];
        }
    if (info) {
        info->n_channels = p->store.n_channels;
        info->n_times = p->store.n_times;
        info->n_levels = p->n_levels;
    }
    return VV_OK;
}

vv_status
vv_pyramid_open_store(vv_pyramid **out, vv_store *st, const char *path, vv_cache *cache,
                      vv_load_info *info) {
    *out = NULL;
    char name[64]; /* st->name is the store's, closed on failure */
    snprintf(name, sizeof name, "%s", st->name ? st->name : "pyramid");
    vv_pyramid *p = strlen(path) < sizeof(((vv_pyramid *)0)->path) ? calloc(1, sizeof *p) : NULL;
    if (!p) {
        vv_store_close(st);
        return vv_error_set(VV_ERR_NOMEM, "%s: %s: out of memory", name, vv_path_basename(path));
    }
    snprintf(p->path, sizeof p->path, "%s", path);
    p->cache = vv_cache_ref(cache ? cache : vv_cache_process());
    p->lock = vv_cache_mutex(p->cache);
    pthread_mutex_init(&p->store_lock, NULL);
    pthread_cond_init(&p->work, NULL);
    pthread_cond_init(&p->arrived, NULL);
    p->store = *st; /* taken */
    memset(st, 0, sizeof *st);
    vv_status s = pyramid_open(p, info);
    if (s != VV_OK) {
        vv_pyramid_free(p);
        return vv_pyramid_prefix(s, name, path);
    }
    *out = p;
    return VV_OK;
}
