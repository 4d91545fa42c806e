/*
 * The .vvb format's row and its pyramid store (docs/file-formats.md; the
 * layout and its reading in vvb_layout.h, vvb_read.c): a .vvb as a
 * pyramid's store (vv_vvb_pyramid_store, read in this process on every
 * core) and as a row of the volume format table (vv_format_vvb: read whole
 * at any level through its store, written by vvb_write.c, opened by bricks
 * through bricked.c or as a pyramid). The top of the .vvb's files: it
 * calls the others.
 *
 * Thread-safety: a store's chunks are read with pread only, in parallel.
 */
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/bricked.h"
#include "io/store/pyramid.h"
#include "io/store/vvb_layout.h"
#include "volvis/sys/format.h"

/* ---- a .vvb as a pyramid's store ------------------------------------------- */

static vv_status
vvb_store_read(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
               const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    (void)c;
    *missing = 0;
    uint64_t got = 0;
    const vv_status s = vvb_read_level_box(ctx, level, org, dims, dst, scratch, &got);
    *file_bytes = got;
    return s;
}

/* A chunk's range from the index: level 0's from the brick holding it (its
 * stored box: a superset), the others' their own. */
static int
vvb_store_range(void *ctx, int level, const int c[3], double *lo, double *hi) {
    const vvb_file *vf = ctx;
    if (level > 0) {
        const vvb_level *L = &vf->lv[level];
        const vvb_chunk *e = &L->c[(c[2] * L->nc[1] + c[1]) * L->nc[0] + c[0]];
        *lo = e->vmin;
        *hi = e->vmax;
        return 1;
    }
    int bc[3];
    for (int a = 0; a < 3; a++)
        bc[a] = c[a] < vf->nb[a] - 1 ? c[a] : vf->nb[a] - 1;
    const vvb_brick *e = &vf->e[(bc[2] * vf->nb[1] + bc[1]) * vf->nb[0] + bc[0]];
    *lo = e->vmin;
    *hi = e->vmax;
    return 1;
}

static void
vvb_store_close(void *ctx) {
    vvb_file_close(ctx);
    free(ctx);
}

vv_status
vv_vvb_pyramid_store(vv_store *st, const char *path, int channel, int time) {
    memset(st, 0, sizeof *st);
    st->name = "vvb";
    if (channel > 0 || time > 0)
        return vv_error_set(VV_ERR_INVALID,
                            "a .vvb holds one channel at one time step (asked "
                            "for channel %d, time step %d)",
                            channel, time);
    vvb_file *vf = calloc(1, sizeof *vf);
    if (!vf)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vf->fd = -1;
    vf->data_path = strdup(path);
    st->ctx = vf;
    st->close = vvb_store_close;
    st->read_chunk = vvb_store_read;
    st->chunk_range = vvb_store_range;
    st->parallel = 1; /* pread and zstd into the caller's buffers */
    vv_status s = vf->data_path ? vvb_open_file(vf) : vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s != VV_OK)
        return s;
    st->scratch = (size_t)vvb_piece_bytes(vf);
    st->n_levels = vf->n_levels;
    const vv_volume *h = vf->header;
    int f[3] = {1, 1, 1}; /* level-0 voxels per voxel of level l */
    for (int l = 0; l < vf->n_levels && s == VV_OK; l++) {
        const int *d = l ? vf->lv[l].dims : h->dims;
        int cd[3];
        for (int a = 0; a < 3; a++) {
            cd[a] = d[a] < VVB_CHUNK ? d[a] : VVB_CHUNK;
            if (l > 0 && (l > 1 ? vf->lv[l - 1].dims[a] : h->dims[a]) > 1)
                f[a] *= 2;
        }
        if ((s = vv_store_set_level(st, l, h->type, d, cd)) != VV_OK)
            break;
        /* each voxel's centre at the centre of the level-0 voxels it
         * summarises, along the volume's axes */
        vv_volume *v = st->lv[l].hdr;
        memcpy(v->direction, h->direction, sizeof v->direction);
        memcpy(v->origin, h->origin, sizeof v->origin);
        for (int a = 0; a < 3; a++) {
            v->spacing[a] = h->spacing[a] * f[a];
            const double t = 0.5 * (f[a] - 1) * h->spacing[a];
            for (int r = 0; r < 3; r++)
                v->origin[r] += h->direction[3 * r + a] * t;
        }
        v->unit = h->unit;
        v->space = h->space;
        v->range[0] = h->range[0];
        v->range[1] = h->range[1];
        v->modification = VV_MOD_ORIGINAL;
    }
    st->n_channels = st->n_times = 1;
    st->has_range = 1;
    st->range[0] = h->range[0];
    st->range[1] = h->range[1];
    return s;
}

/* ---- a .vvb as a volume format (vv_volume_load) ------------------------------ */

/* Level opt->level of the .vvb at @p path, whole, through its pyramid store. */
static vv_status
vvb_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    *out = NULL;
    vv_store st;
    vv_status s = vv_vvb_pyramid_store(&st, path, opt->channel, opt->time);
    const int level = opt->level > 0 ? opt->level : 0;
    if (s == VV_OK && level >= st.n_levels)
        s = vv_error_set(VV_ERR_INVALID, "level %d asked, the file has %d", level, st.n_levels);
    vv_volume *v = NULL;
    if (s == VV_OK)
        s = vv_volume_new(&v, st.lv[level].hdr->dims, st.lv[level].hdr->type);
    unsigned char *piece = s == VV_OK ? malloc(st.scratch) : NULL;
    if (s == VV_OK && !piece)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    const int zero[3] = {0, 0, 0};
    uint64_t bytes = 0;
    if (s == VV_OK)
        s = vvb_read_level_box(st.ctx, level, zero, v->dims, v->data, piece, &bytes);
    free(piece);
    if (s == VV_OK) {
        const vv_volume *h = st.lv[level].hdr;
        vv_volume_take_geometry(v, h);
        v->modification = VV_MOD_ORIGINAL;
        vv_volume_update_range(v);
        if (opt->info) {
            opt->info->n_channels = opt->info->n_times = 1;
            opt->info->n_levels = st.n_levels;
        }
    }
    vv_store_close(&st);
    if (s != VV_OK) {
        vv_volume_free(v);
        return vv_error_prefix(s, "vvb: %s", vv_path_basename(path));
    }
    *out = v;
    return VV_OK;
}

/* The .vvb row's open_bricks. */
static vv_status
vvb_open_bricks(vv_source **out, const char *path, int header_only, vv_cache *cache) {
    (void)header_only; /* its index has the ranges */
    vv_bricked *b = NULL;
    vv_status s = vvb_open_bricked(&b, path, cache);
    return s == VV_OK ? vv_bricked_source_new(out, b, "vvb") : s;
}

/* The .vvb row's store (its levels). */
static vv_status
vvb_open_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    (void)info;
    return vv_vvb_pyramid_store(st, path, channel, time);
}

static vv_status
vvb_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_volume_write_vvb(v, path, opt->vvb_flags);
}

static vv_status
vvb_write_boxes_record(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                       const vv_save_options *opt) {
    return vv_boxes_write_vvb(hdr, read, ctx, path, opt->vvb_flags,
                              opt->progress.fn ? &opt->progress : NULL);
}

static int
vvb_looks_like(const vv_format_probe *p, int deep) {
    (void)deep;
    return !p->is_dir && p->n >= 8 && !memcmp(p->head, VVB_MAGIC, 8);
}

static const char *const vvb_extensions[] = {"vvb", NULL};

const vv_format_record vv_format_vvb = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "vvb",
    .title = ".vvb",
    .extensions = vvb_extensions,
    .doc = "VolVis's bricked volumes (volvis convert IN OUT.vvb): read whole, any pyramid level "
           "(--level); rendered out of core by bricks (volvis render) or by level of detail "
           "(--lod)",
    .flags = VV_FORMAT_FLAG_OUT_OF_CORE,
    .looks_like = vvb_looks_like,
    .read = vvb_read,
    .write = vvb_write_record,
    .write_boxes = vvb_write_boxes_record,
    .open_store = vvb_open_store,
    .open_bricks = vvb_open_bricks,
};
