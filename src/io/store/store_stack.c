/*
 * Stores of one channel each, stacked into one store of several
 * (vv_store_stack, include/volvis/sys/source.h): how a format whose store
 * reads one channel (the HDF5 pyramids of BigDataViewer and Imaris, in the
 * reader sandbox or here; a BigDataViewer XML's setups) gives a pyramid
 * whose chunks hold every channel its object draws. A chunk read reads
 * each part's chunk into its channel's block, one after another; the
 * parts read in turn keep their own ways (a sandboxed part fetches ahead).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/sys/source.h"

typedef struct stk_store {
    int n;
    size_t esize[VV_STORE_MAX_LEVELS]; /* bytes a voxel of each level */
    vv_store part[VV_STORE_MAX_CHANNELS];
} stk_store;

/* Bytes of one channel's block of @p dims voxels of level @p level. */
static size_t
block_bytes(const stk_store *k, int level, const int dims[3]) {
    return (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2] * k->esize[level];
}

static vv_status
stk_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
               const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    const stk_store *k = ctx;
    const size_t bb = block_bytes(k, level, dims);
    int all_missing = 1;
    uint64_t bytes = 0;
    for (int i = 0; i < k->n; i++) {
        const vv_store *p = &k->part[i];
        int m = 0;
        uint64_t fb = 0;
        vv_status s =
            p->read_chunk(p->ctx, level, c, scratch, dst + (size_t)i * bb, org, dims, &m, &fb);
        if (s != VV_OK)
            return vv_error_prefix(s, "channel %d", i);
        all_missing &= m != 0;
        bytes += fb;
    }
    if (missing)
        *missing = all_missing;
    if (file_bytes)
        *file_bytes = bytes;
    return VV_OK;
}

static int
stk_prefetch(void *ctx, int level, const int c[3]) {
    const stk_store *k = ctx;
    int asked = 1;
    for (int i = 0; i < k->n && asked; i++)
        asked = k->part[i].prefetch ? k->part[i].prefetch(k->part[i].ctx, level, c) : 0;
    return asked;
}

static void
stk_close(void *ctx) {
    stk_store *k = ctx;
    for (int i = 0; k && i < k->n; i++)
        vv_store_close(&k->part[i]);
    free(k);
}

/* VV_ERR_FORMAT unless part @p i has part 0's levels, dims, chunks, type and geometry. */
static vv_status
same_as_first(const vv_store *parts, int i) {
    const vv_store *a = &parts[0], *b = &parts[i];
    if (b->n_levels != a->n_levels)
        return vv_error_set(VV_ERR_FORMAT, "channel %d has %d levels, channel 0 %d", i, b->n_levels,
                            a->n_levels);
    for (int l = 0; l < a->n_levels; l++) {
        const vv_volume *ha = a->lv[l].hdr, *hb = b->lv[l].hdr;
        if (!ha || !hb)
            return vv_error_set(VV_ERR_FORMAT, "channel %d: level %d has no geometry", i, l);
        int same = ha->type == hb->type;
        for (int k = 0; k < 3; k++)
            same &= ha->dims[k] == hb->dims[k] && a->lv[l].cdims[k] == b->lv[l].cdims[k] &&
                    fabs(ha->spacing[k] - hb->spacing[k]) <= 1e-9 * fabs(ha->spacing[k]) &&
                    fabs(ha->origin[k] - hb->origin[k]) <=
                        1e-9 * (fabs(ha->origin[k]) + ha->spacing[k]);
        if (!same)
            return vv_error_set(VV_ERR_FORMAT,
                                "channel %d: level %d differs from channel 0's (its dims, chunks, "
                                "type or placement): the channels are not one grid",
                                i, l);
    }
    return VV_OK;
}

vv_status
vv_store_stack(vv_store *out, vv_store *parts, int n) {
    vv_status s = VV_OK;
    if (!out || !parts || n < 1 || n > VV_STORE_MAX_CHANNELS)
        s = vv_error_set(VV_ERR_INVALID, "store: %d channels to stack (1 .. %d)", n,
                         VV_STORE_MAX_CHANNELS);
    for (int i = 0; s == VV_OK && i < n; i++)
        if (parts[i].n_ch > 1 || !parts[i].read_chunk)
            s = vv_error_set(VV_ERR_INVALID, "store: channel %d is not a store of one channel", i);
    for (int i = 1; s == VV_OK && i < n; i++)
        s = same_as_first(parts, i);
    stk_store *k = s == VV_OK ? calloc(1, sizeof *k) : NULL;
    if (s == VV_OK && !k)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s != VV_OK) {
        for (int i = 0; parts && i < n && i < VV_STORE_MAX_CHANNELS; i++)
            vv_store_close(&parts[i]);
        return s;
    }
    memset(out, 0, sizeof *out);
    out->name = parts[0].name;
    out->n_levels = parts[0].n_levels;
    out->n_channels = parts[0].n_channels;
    out->n_times = parts[0].n_times;
    out->parallel = 1;
    for (int i = 0; i < n; i++) {
        const vv_store *p = &parts[i];
        out->scratch = p->scratch > out->scratch ? p->scratch : out->scratch;
        /* a part read one at a time makes the stack so; network waits: the least */
        out->parallel = p->parallel < out->parallel ? p->parallel : out->parallel;
        out->ch_has_range[i] = p->has_range;
        out->ch_range[i][0] = p->range[0];
        out->ch_range[i][1] = p->range[1];
    }
    /* the levels' headers are channel 0's (taken); the others' go with their parts */
    for (int l = 0; l < out->n_levels; l++) {
        k->esize[l] = vv_voxel_type_size(parts[0].lv[l].hdr->type);
        out->lv[l] = parts[0].lv[l];
        parts[0].lv[l].hdr = NULL;
    }
    k->n = n;
    for (int i = 0; i < n; i++) {
        k->part[i] = parts[i];
        memset(&parts[i], 0, sizeof parts[i]);
    }
    int prefetch = 1;
    for (int i = 0; i < n; i++)
        prefetch &= k->part[i].prefetch != NULL;
    out->ctx = k;
    out->n_ch = n;
    out->has_range = out->ch_has_range[0];
    out->range[0] = out->ch_range[0][0];
    out->range[1] = out->ch_range[0][1];
    out->read_chunk = stk_read_chunk;
    out->prefetch = prefetch ? stk_prefetch : NULL;
    out->close = stk_close;
    return VV_OK;
}
