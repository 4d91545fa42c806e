/*
 * A TIFF stack out of core: the TIFF row's store (vv_store,
 * include/volvis/sys/source.h), so that a stack larger than memory is drawn
 * by the pyramid (src/io/store/pyramid.h) like an OME-Zarr.
 *
 * Level 0 is the stack (tiff_stack.h): slice z of the channel and time step
 * asked is page refs[z], of one file or of a folder's files. A chunk is read
 * by decoding only the tiles (or strips) its box touches of each of its
 * slices' pages.
 *
 * Coarser levels are the pyramid an OME-TIFF keeps in SubIFDs (what
 * bfconvert, raw2ometiff, QuPath and tifffile's subifds= write): SubIFD
 * l - 1 of every page is level l in x and y. Those levels are reduced in x
 * and y only; z is reduced here as the chunks are read, so that level of
 * detail works in 3-D: level l's slice k is the mean of slices k f .. k f +
 * f - 1 of SubIFD level l - 1, f the power of two nearest the level's
 * reduction in x and y (vv_pyr_reduce, the same mean as our own pyramids).
 * Every level's pages must have the format (type, samples) of level 0's and
 * the size of page 0's at that level; the first page that differs is an
 * error naming it when it is read.
 *
 * Opening walks the IFD chain once, noting each slice's IFD offset and its
 * SubIFDs' offsets; reads seek to them directly (TIFFSetSubDirectory).
 * libtiff's handles are not thread-safe: the store keeps a few open handles
 * and gives each chunk read one of its own (parallel reads of different
 * chunks). In the reader sandbox (the row is a third-party format) the
 * store runs in volvis-reader, its chunks sent back decoded.
 *
 * Errors name the file, the page and the tile or strip.
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <tiffio.h>

#include "core/internal.h"
#include "io/store/pyramid.h"
#include "io/volume/tiff_stack.h"
#include "volvis/sys/source.h"

/* Handles open at once (reads past that many wait for one). */
#define TS_HANDLES 16
/* A chunk's voxels at most (x y z), aimed at when choosing its z extent. */
#define TS_CHUNK_VOXELS (1u << 18)

typedef struct ts_level {
    int dims[3];
    int zf;        /* level 0's slices under one of this level's */
    page_fmt f;    /* page 0's format at this level */
    uint64_t *ifd; /* level 0's nz slices: the IFD offset of each at this level */
} ts_level;

typedef struct ts_handle {
    TIFF *t;
    int file; /* the file open in t, -1: none */
    int busy;
    tiff_msg msg;
} ts_handle;

typedef struct ts_store {
    char **files;
    int n_files;
    tiff_stack k;
    int n_levels;
    ts_level lv[VV_STORE_MAX_LEVELS];
    pthread_mutex_t lock;
    pthread_cond_t freed;
    ts_handle h[TS_HANDLES];
} ts_store;

/* "NAME: " of file @p file when the stack is a folder's files, else "" (the
 * caller's prefix names the one file). */
static const char *
ts_where(const ts_store *s, int file, char *buf, size_t cap) {
    if (s->n_files <= 1)
        return "";
    snprintf(buf, cap, "%s: ", vv_path_basename(s->files[file]));
    return buf;
}

static void
ts_close(void *ctx) {
    ts_store *s = ctx;
    if (!s)
        return;
    for (int i = 0; i < TS_HANDLES; i++)
        if (s->h[i].t)
            TIFFClose(s->h[i].t);
    for (int l = 0; l < VV_STORE_MAX_LEVELS; l++) /* ts_index allocates every level's */
        free(s->lv[l].ifd);
    tiff_stack_clear(&s->k);
    tiff_free_files(s->files, s->n_files);
    pthread_mutex_destroy(&s->lock);
    pthread_cond_destroy(&s->freed);
    free(s);
}

/* Handle @p h back to @p s's free ones. */
static void
ts_give(ts_store *s, ts_handle *h) {
    pthread_mutex_lock(&s->lock);
    h->busy = 0;
    pthread_cond_signal(&s->freed);
    pthread_mutex_unlock(&s->lock);
}

/* A handle of @p s with file @p file open (waiting for one while all are
 * busy); NULL when the file does not open (the error set). */
static ts_handle *
ts_take(ts_store *s, int file) {
    pthread_mutex_lock(&s->lock);
    ts_handle *h = NULL;
    for (;;) {
        for (int i = 0; i < TS_HANDLES && !h; i++)
            if (!s->h[i].busy && s->h[i].file == file)
                h = &s->h[i];
        for (int i = 0; i < TS_HANDLES && !h; i++)
            if (!s->h[i].busy && !s->h[i].t)
                h = &s->h[i];
        for (int i = 0; i < TS_HANDLES && !h; i++)
            if (!s->h[i].busy)
                h = &s->h[i];
        if (h)
            break;
        pthread_cond_wait(&s->freed, &s->lock);
    }
    h->busy = 1;
    pthread_mutex_unlock(&s->lock);
    if (h->t && h->file == file)
        return h;
    if (h->t)
        TIFFClose(h->t);
    h->file = file;
    h->t = tiff_open_file(s->files[file], &h->msg);
    if (h->t)
        return h;
    char w[300];
    vv_error_set(VV_ERR_FORMAT, "%s%s", ts_where(s, file, w, sizeof w),
                 tiff_msg_or(&h->msg, "not a TIFF file"));
    h->file = -1;
    ts_give(s, h);
    return NULL;
}

/* Box x0, y0, cols x rows of slice @p z (level 0's numbering) of level
 * @p level into @p dst; *bytes grows by the stored bytes decoded. */
static vv_status
ts_read_slice(ts_store *s, int level, int z, uint32_t x0, uint32_t y0, uint32_t cols, uint32_t rows,
              unsigned char *dst, uint64_t *bytes) {
    const ts_level *L = &s->lv[level];
    const page_ref *r = &s->k.refs[z];
    ts_handle *h = ts_take(s, r->file);
    if (!h)
        return VV_ERR_FORMAT;
    vv_status st = VV_OK;
    h->msg.text[0] = '\0';
    page_fmt f;
    if (!TIFFSetSubDirectory(h->t, L->ifd[z]))
        st = vv_error_set(VV_ERR_FORMAT, "%s", tiff_msg_or(&h->msg, "cannot read its directory"));
    else if ((st = tiff_page_format(h->t, &f)) == VV_OK &&
             (f.w != L->f.w || f.h != L->f.h || f.type != L->f.type || f.spp != L->f.spp))
        st = vv_error_set(VV_ERR_FORMAT,
                          "%u x %u %s x %u samples, the level's first page is %u x %u %s x %u", f.w,
                          f.h, vv_voxel_type_name(f.type), f.spp, L->f.w, L->f.h,
                          vv_voxel_type_name(L->f.type), L->f.spp);
    if (st == VV_OK)
        st = tiff_read_region(h->t, &f, s->k.sample, x0, y0, cols, rows, dst, &h->msg, bytes);
    ts_give(s, h);
    if (st == VV_OK)
        return VV_OK;
    char w[300];
    if (level > 0)
        return vv_error_prefix(st, "%spage %ld, SubIFD %d", ts_where(s, r->file, w, sizeof w),
                               r->page, level - 1);
    return vv_error_prefix(st, "%spage %ld", ts_where(s, r->file, w, sizeof w), r->page);
}

static vv_status
ts_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
              const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    (void)c;
    (void)scratch;
    ts_store *s = ctx;
    const ts_level *L = &s->lv[level];
    const size_t vs = vv_voxel_type_size(L->f.type);
    const size_t plane = (size_t)dims[0] * (size_t)dims[1] * vs;
    uint64_t bytes = 0;
    vv_status st = VV_OK;
    *missing = 0;
    /* the slices under the chunk: its own (zf 1, read into dst), or zf a
     * voxel, reduced here to their means */
    const int z0 = org[2] * L->zf;
    int z1 = (org[2] + dims[2]) * L->zf;
    if (z1 > s->k.nz)
        z1 = s->k.nz;
    unsigned char *src = L->zf == 1 ? dst : malloc((size_t)(z1 - z0) * plane);
    if (!src)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for level %d's slices", level);
    for (int z = z0; z < z1 && st == VV_OK; z++)
        st = ts_read_slice(s, level, z, (uint32_t)org[0], (uint32_t)org[1], (uint32_t)dims[0],
                           (uint32_t)dims[1], src + (size_t)(z - z0) * plane, &bytes);
    if (st == VV_OK && src != dst) {
        const vv_pyr_reduce_box b = {.src = src,
                                     .type = L->f.type,
                                     .src_dims = {L->dims[0], L->dims[1], s->k.nz},
                                     .src_lo = {org[0], org[1], z0},
                                     .src_n = {dims[0], dims[1], z1 - z0},
                                     .step = {1, 1, L->zf},
                                     .lo = {org[0], org[1], org[2]},
                                     .n = {dims[0], dims[1], dims[2]},
                                     .dst_dims = {dims[0], dims[1]}};
        vv_pyr_reduce(&b, dst);
    }
    if (src != dst)
        free(src);
    *file_bytes = bytes;
    return st;
}

/* A level's reduction along an axis of @p n0 pixels that it holds in @p n:
 * 2^k when n is n0 / 2^k rounded either way (a pyramid of halvings, as
 * OME-Zarr's: the level's pixel spacing exactly 2^k times level 0's), else
 * the ratio n0 / n (the level covering level 0's extent). */
static double
level_factor(uint32_t n0, uint32_t n) {
    for (uint32_t f = 1; f <= n0 && f <= (1u << 30); f *= 2)
        if (n == n0 / f || n == (n0 + f - 1) / f)
            return f;
    return (double)n0 / n;
}

/* The power of two nearest @p r (>= 1). */
static int
pow2_near(double r) {
    int f = 1;
    while (f < (1 << 20) && f * 1.5 < r)
        f *= 2;
    return f;
}

/* Level @p l's chunk box: whole tiles (or strips: whole rows) about 256
 * voxels a side in x and y, and slices up to TS_CHUNK_VOXELS. */
static void
ts_chunk_dims(TIFF *t, const ts_level *L, int cd[3]) {
    uint32_t tw = 0, th = 0;
    if (TIFFIsTiled(t)) {
        TIFFGetField(t, TIFFTAG_TILEWIDTH, &tw);
        TIFFGetField(t, TIFFTAG_TILELENGTH, &th);
    } else {
        TIFFGetFieldDefaulted(t, TIFFTAG_ROWSPERSTRIP, &th);
        tw = L->f.w <= 4096 ? L->f.w : 256;
    }
    if (tw < 1 || tw > L->f.w)
        tw = L->f.w;
    if (th < 1 || th > L->f.h)
        th = L->f.h;
    uint32_t cx = tw, cy = th;
    while (cx < 128 && cx * 2 <= L->f.w)
        cx += tw;
    while (cy < 128 && cy + th <= L->f.h)
        cy += th;
    cd[0] = (int)(cx < L->f.w ? cx : L->f.w);
    cd[1] = (int)(cy < L->f.h ? cy : L->f.h);
    uint64_t cz = TS_CHUNK_VOXELS / ((uint64_t)cd[0] * (uint64_t)cd[1]);
    cd[2] = (int)(cz < 1 ? 1 : cz > (uint64_t)L->dims[2] ? (uint64_t)L->dims[2] : cz);
}

/* The IFD offsets of every slice at every level, the levels' formats: one
 * walk of each file's IFD chain. */
static vv_status
ts_index(ts_store *s, int *chunk_dims) {
    const tiff_stack *k = &s->k;
    int n_sub = VV_STORE_MAX_LEVELS - 1;
    for (int l = 0; l < VV_STORE_MAX_LEVELS; l++) {
        s->lv[l].ifd = calloc((size_t)k->nz, sizeof *s->lv[l].ifd);
        if (!s->lv[l].ifd)
            return vv_error_set(VV_ERR_NOMEM, "out of memory for the pages' index");
    }
    s->n_levels = VV_STORE_MAX_LEVELS;
    vv_status st = VV_OK;
    int z = 0;
    for (int file = 0; file < s->n_files && z < k->nz && st == VV_OK; file++) {
        if (k->refs[z].file != file)
            continue;
        ts_handle *h = ts_take(s, file);
        if (!h)
            return VV_ERR_FORMAT;
        long page = 0;
        h->msg.text[0] = '\0';
        while (z < k->nz && k->refs[z].file == file && st == VV_OK) {
            while (page < k->refs[z].page && TIFFReadDirectory(h->t))
                page++;
            if (page != k->refs[z].page) {
                char w[300];
                st = vv_error_set(VV_ERR_FORMAT, "%spage %ld: %s", ts_where(s, file, w, sizeof w),
                                  k->refs[z].page,
                                  tiff_msg_or(&h->msg, "missing (the file ends before it)"));
                break;
            }
            s->lv[0].ifd[z] = TIFFCurrentDirOffset(h->t);
            uint16_t n = 0;
            uint64_t *sub = NULL;
            if (!TIFFGetField(h->t, TIFFTAG_SUBIFD, &n, &sub) || !sub)
                n = 0;
            if (n < n_sub)
                n_sub = n;
            for (int l = 1; l <= n_sub; l++)
                s->lv[l].ifd[z] = sub[l - 1];
            z++;
        }
        ts_give(s, h);
    }
    if (st != VV_OK)
        return st;
    /* each level's format from page 0's (SubIFD) directory */
    ts_handle *h = ts_take(s, k->refs[0].file);
    if (!h)
        return VV_ERR_FORMAT;
    s->n_levels = 1 + n_sub;
    for (int l = 0; l < s->n_levels && st == VV_OK; l++) {
        ts_level *L = &s->lv[l];
        h->msg.text[0] = '\0';
        char w[300];
        ts_where(s, k->refs[0].file, w, sizeof w);
        if (!TIFFSetSubDirectory(h->t, L->ifd[0])) {
            st = vv_error_set(VV_ERR_FORMAT, "%spage %ld, SubIFD %d: %s", s->n_files > 1 ? w : "",
                              k->refs[0].page, l - 1,
                              tiff_msg_or(&h->msg, "cannot read its directory"));
            break;
        }
        if ((st = tiff_page_format(h->t, &L->f)) != VV_OK) {
            st = vv_error_prefix(st, "%spage %ld, SubIFD %d", s->n_files > 1 ? w : "",
                                 k->refs[0].page, l - 1);
            break;
        }
        const ts_level *P = l ? &s->lv[l - 1] : NULL;
        if (P && (L->f.type != P->f.type || L->f.spp != P->f.spp || L->f.w > P->f.w ||
                  L->f.h > P->f.h)) {
            /* not a reduced copy of the level before (a thumbnail, a mask):
             * the levels end there */
            s->n_levels = l;
            break;
        }
        L->dims[0] = (int)L->f.w;
        L->dims[1] = (int)L->f.h;
        L->zf = l ? pow2_near(0.5 * (level_factor(k->f0.w, L->f.w) + level_factor(k->f0.h, L->f.h)))
                  : 1;
        L->dims[2] = (k->nz + L->zf - 1) / L->zf;
        ts_chunk_dims(h->t, L, chunk_dims + 3 * l);
    }
    ts_give(s, h);
    return st;
}

/* Slices whose values give a stack without levels its range. */
#define TS_RANGE_SLICES 16
/* Bytes of a band of a slice read at once for the range. */
#define TS_RANGE_BAND ((size_t)16 << 20)

/*
 * The value range of a stack without SubIFD levels, from TS_RANGE_SLICES of
 * its slices evenly spaced (the first and the last among them), each read
 * in bands of rows: what the pyramid would otherwise take from its coarsest
 * level, here level 0, read whole at open. An estimate where the other
 * slices reach further (the transfer function's default range only).
 */
static vv_status
ts_sample_range(ts_store *s, double range[2]) {
    const ts_level *L = &s->lv[0];
    const size_t vs = vv_voxel_type_size(L->f.type), row = (size_t)L->f.w * vs;
    uint32_t band = (uint32_t)(TS_RANGE_BAND / row);
    if (band < 1)
        band = 1;
    if (band > L->f.h)
        band = L->f.h;
    unsigned char *buf = malloc((size_t)band * row);
    if (!buf)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for the stack's range");
    const int n = s->k.nz < TS_RANGE_SLICES ? s->k.nz : TS_RANGE_SLICES;
    double lo = INFINITY, hi = -INFINITY;
    vv_status st = VV_OK;
    uint64_t bytes = 0;
    for (int i = 0; i < n && st == VV_OK; i++) {
        const int z = n > 1 ? (int)((int64_t)i * (s->k.nz - 1) / (n - 1)) : 0;
        for (uint32_t y = 0; y < L->f.h && st == VV_OK; y += band) {
            const uint32_t rows = y + band > L->f.h ? L->f.h - y : band;
            st = ts_read_slice(s, 0, z, 0, y, L->f.w, rows, buf, &bytes);
            for (size_t j = 0; st == VV_OK && j < (size_t)rows * L->f.w; j++) {
                const double x = vv_pyr_voxel(buf, L->f.type, j);
                if (x < lo)
                    lo = x;
                if (x > hi)
                    hi = x;
            }
        }
    }
    free(buf);
    if (st == VV_OK && !(lo <= hi))
        lo = hi = 0; /* every value NaN */
    range[0] = lo;
    range[1] = hi;
    return st;
}

/* The row's store: @p path's stack of channel @p channel at time step
 * @p time, its OME-TIFF SubIFD levels as the pyramid's. */
vv_status
vv_tiff_open_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    memset(st, 0, sizeof *st);
    st->name = "tiff";
    ts_store *s = calloc(1, sizeof *s);
    if (!s)
        return vv_error_set(VV_ERR_NOMEM, "tiff: out of memory");
    pthread_mutex_init(&s->lock, NULL);
    pthread_cond_init(&s->freed, NULL);
    for (int i = 0; i < TS_HANDLES; i++)
        s->h[i].file = -1;
    int is_dir = 0;
    vv_status r = tiff_files(path, &s->files, &s->n_files, &is_dir);
    const char *bad = path;
    if (r == VV_OK)
        r = tiff_stack_plan(&s->k, s->files, s->n_files, channel, time, &bad);
    if (r != VV_OK) {
        if (is_dir && bad != path) /* a folder's file */
            r = vv_error_prefix(r, "%s", vv_path_basename(bad));
        ts_close(s);
        return r;
    }
    int cd[3 * VV_STORE_MAX_LEVELS];
    r = ts_index(s, cd);
    const tiff_stack *k = &s->k;
    for (int l = 0; l < s->n_levels && r == VV_OK; l++) {
        const ts_level *L = &s->lv[l];
        if ((r = vv_store_set_level(st, l, L->f.type, L->dims, cd + 3 * l)) != VV_OK)
            break;
        /* each voxel's centre at the centre of the level-0 voxels it
         * summarises */
        vv_volume *v = st->lv[l].hdr;
        const double f[3] = {level_factor(k->f0.w, L->f.w), level_factor(k->f0.h, L->f.h), L->zf};
        for (int a = 0; a < 3; a++) {
            v->spacing[a] = k->spacing[a] * f[a];
            v->origin[a] = k->origin[a] + 0.5 * (f[a] - 1) * k->spacing[a];
        }
        v->unit = k->unit;
        v->modification = VV_MOD_ORIGINAL;
    }
    /* no levels: the range from a few slices, not from level 0 read whole */
    if (r == VV_OK && s->n_levels == 1 && (r = ts_sample_range(s, st->range)) == VV_OK)
        st->has_range = 1;
    if (r != VV_OK) {
        ts_close(s);
        vv_store_close(st);
        return r;
    }
    st->ctx = s;
    st->close = ts_close;
    st->read_chunk = ts_read_chunk;
    st->parallel = 1;
    st->n_levels = s->n_levels;
    st->n_channels = k->nc;
    st->n_times = k->nt;
    if (info) {
        const int n_ch = k->nc, n_t = k->nt;
        *info = k->meta;
        info->n_channels = n_ch;
        info->n_times = n_t;
        info->time_step = k->time_step;
        info->n_slices = k->nz;
    }
    return VV_OK;
}

vv_status
vv_tiff_read_level(vv_volume **out, const char *path, int channel, int time, int level,
                   vv_load_info *info) {
    *out = NULL;
    vv_store st;
    vv_status r = vv_tiff_open_store(&st, path, channel, time, info);
    if (r == VV_OK && level >= st.n_levels)
        r = vv_error_set(VV_ERR_INVALID, "level %d asked, the file has %d", level, st.n_levels);
    if (r == VV_OK) /* chunk by chunk: slices of one chunk's depth held at once */
        r = vv_store_read_level(&st, level, out);
    if (r == VV_OK && info)
        info->n_levels = st.n_levels;
    vv_store_close(&st);
    return r == VV_OK ? VV_OK : vv_error_prefix(r, "tiff: %s", path);
}
