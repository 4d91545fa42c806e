/*
 * The .vvb format's own reading (docs/file-formats.md; the layout in
 * vvb_layout.h): its header, brick index and pyramid levels, each piece
 * checked against the file's size before anything is read; a piece read
 * raw or as one zstd frame (libzstd, its size checked before and after
 * decoding); boxes of any level assembled from the bricks or chunks they
 * overlap. On that: a .vvb as a pyramid's store (vv_vvb_pyramid_store,
 * read in this process on every core) and as a row of the volume format
 * table (vv_format_vvb: read whole at any level, written by vvb_write.c,
 * opened by bricks or as a pyramid). The bricked reader (bricked.c) opens
 * a .vvb through vvb_open_file; the writer reads its levels back through
 * vvb_readback_new.
 *
 * Thread-safety: pieces and level boxes are read with pread only, from
 * any thread; a store's chunks are read in parallel.
 */
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <zstd.h>

#include "core/internal.h"
#include "io/bricked.h"
#include "io/pyramid.h"
#include "io/vvb_layout.h"
#include "volvis/sys/format.h"

/* ---- pyramid levels -------------------------------------------------------- */

/* The dims of each level of a volume of @p d voxels: level 0 is the volume,
 * each next level halves every axis longer than 1 (rounding up) until every
 * axis fits one chunk, as the OME-Zarr writer's levels; at most
 * VV_PYRAMID_MAX_LEVELS. Returns the count. */
int
vvb_level_dims(const int d[3], int dims[VV_PYRAMID_MAX_LEVELS][3]) {
    memcpy(dims[0], d, sizeof dims[0]);
    int n = 1;
    while (n < VV_PYRAMID_MAX_LEVELS && (dims[n - 1][0] > VVB_CHUNK || dims[n - 1][1] > VVB_CHUNK ||
                                         dims[n - 1][2] > VVB_CHUNK)) {
        for (int a = 0; a < 3; a++)
            dims[n][a] = dims[n - 1][a] > 1 ? (dims[n - 1][a] + 1) / 2 : 1;
        n++;
    }
    return n;
}

/* Level @p L's geometry (levels >= 1) from its dims, with its chunk grid. */
void
vvb_level_grid(vvb_level *L, const int dims[3]) {
    L->n = 1;
    for (int a = 0; a < 3; a++) {
        L->dims[a] = dims[a];
        L->nc[a] = (dims[a] + VVB_CHUNK - 1) / VVB_CHUNK;
        L->n *= L->nc[a];
    }
}

/* Chunk @p i of level @p L: its first voxel and voxel counts. */
void
vvb_chunk_box(const vvb_level *L, int i, int org[3], int n[3]) {
    const int c[3] = {i % L->nc[0], (i / L->nc[0]) % L->nc[1], i / (L->nc[0] * L->nc[1])};
    for (int a = 0; a < 3; a++) {
        org[a] = c[a] * VVB_CHUNK;
        n[a] = L->dims[a] - org[a] < VVB_CHUNK ? L->dims[a] - org[a] : VVB_CHUNK;
    }
}

/* The bytes of the largest piece of a level (a brick's stored box at level
 * 0, a chunk above): what vvb_read_level_box's @p piece holds. */
uint64_t
vvb_piece_bytes(const vv_bricked *b) {
    uint64_t n = 1;
    for (int a = 0; a < 3; a++) {
        const int d = b->header->dims[a], side = VV_BRICK_CELLS + 3;
        n *= (uint64_t)(d < side ? d : side);
    }
    return n * vv_voxel_type_size(b->header->type);
}

/* ---- reading pieces ---------------------------------------------------------- */

/* The @p bytes at @p off of a .vvb -- a brick's stored box or a level's
 * chunk, of @p want bytes -- into @p dst (as stored: little-endian): one
 * pread, then with zstd one frame decoded into exactly @p want bytes.
 * Uncounted: any thread. */
vv_status
vvb_read_piece(const vv_bricked *b, uint64_t off, uint64_t bytes, void *dst, uint64_t want,
               const char *what) {
    if (!b->zstd)
        return vvb_pread(b, dst, (size_t)want, off, what);
    void *z = malloc((size_t)bytes);
    if (!z)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = vvb_pread(b, z, (size_t)bytes, off, what);
    if (s == VV_OK) {
        const unsigned long long fs = ZSTD_getFrameContentSize(z, (size_t)bytes);
        const unsigned long long zb = bytes, zo = off;
        if (fs == ZSTD_CONTENTSIZE_ERROR)
            s = vv_error_set(VV_ERR_FORMAT, "%s: %llu bytes at offset %llu are not a zstd frame",
                             what, zb, zo);
        else if (fs == ZSTD_CONTENTSIZE_UNKNOWN)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: the zstd frame at offset %llu does not give its size", what, zo);
        else if (fs != (unsigned long long)want)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: the zstd frame at offset %llu holds %llu bytes; its box needs "
                             "%llu",
                             what, zo, fs, (unsigned long long)want);
        else {
            const size_t r = ZSTD_decompress(dst, (size_t)want, z, (size_t)bytes);
            if (ZSTD_isError(r) || r != (size_t)want)
                s = vv_error_set(VV_ERR_FORMAT,
                                 "%s: the zstd frame of %llu bytes at offset %llu: %s", what, zb,
                                 zo, ZSTD_isError(r) ? ZSTD_getErrorName(r) : "short");
        }
    }
    free(z);
    return s;
}

/* Voxels lo .. lo + n - 1 of level @p level into @p dst (x fastest, host
 * byte order), from the bricks (level 0: each brick's own voxels lo .. hi)
 * or the level's chunks that the box overlaps, each read once into
 * @p piece (vvb_piece_bytes); *bytes adds the bytes read. Uncounted in the
 * statistics: any thread. */
vv_status
vvb_read_level_box(const vv_bricked *b, int level, const int lo[3], const int n[3],
                   unsigned char *dst, unsigned char *piece, uint64_t *bytes) {
    const size_t vs = vv_voxel_type_size(b->header->type);
    const vvb_level *L = level > 0 ? &b->lv[level] : NULL;
    const int *grid = L ? L->nc : b->nb;
    int c0[3], c1[3];
    for (int a = 0; a < 3; a++) {
        const int side = L ? VVB_CHUNK : VV_BRICK_CELLS;
        c0[a] = lo[a] / side < grid[a] - 1 ? lo[a] / side : grid[a] - 1;
        c1[a] = (lo[a] + n[a] - 1) / side < grid[a] - 1 ? (lo[a] + n[a] - 1) / side : grid[a] - 1;
    }
    for (int ck = c0[2]; ck <= c1[2]; ck++)
        for (int cj = c0[1]; cj <= c1[1]; cj++)
            for (int ci = c0[0]; ci <= c1[0]; ci++) {
                const int i = (ck * grid[1] + cj) * grid[0] + ci;
                int own0[3], own1[3], st0[3], sn[3]; /* its own voxels; what is stored */
                uint64_t off, zbytes;
                char what[64];
                if (L) {
                    vvb_chunk_box(L, i, st0, sn);
                    for (int a = 0; a < 3; a++) {
                        own0[a] = st0[a];
                        own1[a] = st0[a] + sn[a] - 1;
                    }
                    off = L->c[i].offset;
                    zbytes = L->c[i].bytes;
                    snprintf(what, sizeof what, "level %d chunk %d", level, i);
                } else {
                    vv_brick_info in;
                    vvb_brick_boxes(b->header->dims, b->nb, i, &in);
                    for (int a = 0; a < 3; a++) {
                        own0[a] = in.lo[a];
                        own1[a] = in.hi[a];
                        st0[a] = in.slo[a];
                        sn[a] = in.shi[a] - in.slo[a] + 1;
                    }
                    off = b->e[i].offset;
                    zbytes = b->e[i].bytes;
                    snprintf(what, sizeof what, "brick %d", i);
                }
                const uint64_t nv = (uint64_t)sn[0] * sn[1] * sn[2];
                vv_status s = vvb_read_piece(b, off, zbytes, piece, nv * vs, what);
                if (s != VV_OK)
                    return s;
                *bytes += zbytes;
                if (b->swap && vs > 1)
                    vvb_swap_bytes(piece, (size_t)nv, vs);
                int g0[3], g1[3]; /* the overlap, inclusive */
                for (int a = 0; a < 3; a++) {
                    g0[a] = lo[a] > own0[a] ? lo[a] : own0[a];
                    g1[a] = lo[a] + n[a] - 1 < own1[a] ? lo[a] + n[a] - 1 : own1[a];
                }
                for (int k = g0[2]; k <= g1[2]; k++)
                    for (int j = g0[1]; j <= g1[1]; j++)
                        memcpy(dst + (((size_t)(k - lo[2]) * n[1] + (j - lo[1])) * n[0] +
                                      (g0[0] - lo[0])) *
                                         vs,
                               piece + (((size_t)(k - st0[2]) * sn[1] + (j - st0[1])) * sn[0] +
                                        (g0[0] - st0[0])) *
                                           vs,
                               (size_t)(g1[0] - g0[0] + 1) * vs);
            }
    return VV_OK;
}

/* ---- opening ---------------------------------------------------------------- */

/* What is wrong with a piece of a .vvb -- a brick's voxels or a level's
 * chunk -- of @p bytes at @p off, whose box (@p box names it) holds @p want
 * bytes: 0 when nothing, else 1 and the phrase in @p why: its size against
 * the box's (raw: equal; zstd: 1 to the compression bound), or where it
 * runs past the end of the file. */
static int
piece_problem(const vv_bricked *b, uint64_t off, uint64_t bytes, uint64_t want, const char *box,
              char *why, size_t cap) {
    const uint64_t bound = b->zstd ? ZSTD_compressBound((size_t)want) : want;
    if (b->zstd ? bytes == 0 || bytes > bound : bytes != want)
        snprintf(why, cap, " has %llu bytes; its box %s needs %s%llu", (unsigned long long)bytes,
                 box, b->zstd ? "compressed 1 to " : "", (unsigned long long)bound);
    else if (off < VVB_HEADER || off > b->file_size || b->file_size - off < bytes)
        snprintf(why, cap, ": %llu bytes at offset %llu run past the end of the file (%llu bytes)",
                 (unsigned long long)bytes, (unsigned long long)off,
                 (unsigned long long)b->file_size);
    else
        return 0;
    return 1;
}

/* The pyramid levels of a .vvb: @p n levels in all (0 and 1: the bricks
 * only), the table at @p table_off; each level's dims must be the halving
 * rule's (vvb_level_dims), its index and chunks inside the file. */
static vv_status
open_levels(vv_bricked *b, uint32_t n, uint64_t table_off) {
    b->n_levels = 1;
    if (n <= 1)
        return VV_OK;
    int dims[VV_PYRAMID_MAX_LEVELS][3];
    const int want = vvb_level_dims(b->header->dims, dims);
    if (n != (uint32_t)want)
        return vv_error_set(VV_ERR_FORMAT, "%u pyramid levels; %dx%dx%d voxels make %d", n,
                            dims[0][0], dims[0][1], dims[0][2], want);
    const uint64_t tbytes = (uint64_t)(n - 1) * VVB_LEVEL_RECORD;
    if (table_off < VVB_HEADER || table_off > b->file_size || b->file_size - table_off < tbytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "level table of %llu bytes at offset %llu runs past the end of the "
                            "file (%llu bytes)",
                            (unsigned long long)tbytes, (unsigned long long)table_off,
                            (unsigned long long)b->file_size);
    unsigned char t[VV_PYRAMID_MAX_LEVELS * VVB_LEVEL_RECORD];
    vv_status s = vvb_read_at(b, t, (size_t)tbytes, table_off, "level table");
    const size_t vs = vv_voxel_type_size(b->header->type);
    for (int l = 1; l < want && s == VV_OK; l++) {
        const unsigned char *r = t + (size_t)(l - 1) * VVB_LEVEL_RECORD;
        vvb_level *L = &b->lv[l];
        vvb_level_grid(L, dims[l]);
        const uint64_t ioff = vvb_get_u64(r + 16), count = vvb_get_u64(r + 24);
        if (vvb_get_u32(r) != (uint32_t)dims[l][0] || vvb_get_u32(r + 4) != (uint32_t)dims[l][1] ||
            vvb_get_u32(r + 8) != (uint32_t)dims[l][2] || vvb_get_u32(r + 12) != VVB_CHUNK ||
            count != (uint64_t)L->n)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: %ux%ux%u voxels in %llu chunks of %u (expected "
                                "%dx%dx%d in %d of %d)",
                                l, vvb_get_u32(r), vvb_get_u32(r + 4), vvb_get_u32(r + 8),
                                (unsigned long long)count, vvb_get_u32(r + 12), dims[l][0],
                                dims[l][1], dims[l][2], L->n, VVB_CHUNK);
        const uint64_t ibytes = count * VVB_CHUNK_RECORD;
        if (ioff < VVB_HEADER || ioff > b->file_size || b->file_size - ioff < ibytes)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: index of %llu bytes at offset %llu runs past the end "
                                "of the file (%llu bytes)",
                                l, (unsigned long long)ibytes, (unsigned long long)ioff,
                                (unsigned long long)b->file_size);
        unsigned char *idx = malloc((size_t)ibytes);
        L->c = calloc((size_t)L->n, sizeof *L->c);
        if (!idx || !L->c) {
            free(idx);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        s = vvb_read_at(b, idx, (size_t)ibytes, ioff, "level index");
        for (int i = 0; i < L->n && s == VV_OK; i++) {
            const unsigned char *e = idx + (size_t)i * VVB_CHUNK_RECORD;
            vvb_chunk *c = &L->c[i];
            c->offset = vvb_get_u64(e);
            c->bytes = vvb_get_u64(e + 8);
            c->vmin = vvb_get_f64(e + 16);
            c->vmax = vvb_get_f64(e + 24);
            int o[3], cn[3];
            vvb_chunk_box(L, i, o, cn);
            const uint64_t cw = (uint64_t)cn[0] * cn[1] * cn[2] * vs;
            char box[64], why[256];
            snprintf(box, sizeof box, "of %dx%dx%d voxels", cn[0], cn[1], cn[2]);
            if (piece_problem(b, c->offset, c->bytes, cw, box, why, sizeof why))
                s = vv_error_set(VV_ERR_FORMAT, "level %d: chunk %d%s", l, i, why);
            else if (!(c->vmin <= c->vmax))
                s = vv_error_set(VV_ERR_FORMAT, "level %d: chunk %d: min %g > max %g", l, i,
                                 c->vmin, c->vmax);
        }
        free(idx);
    }
    if (s == VV_OK)
        b->n_levels = want;
    return s;
}

vv_status
vvb_open_file(vv_bricked *b) {
    vv_status s = vvb_open_data(b, b->data_path);
    if (s != VV_OK)
        return s;
    unsigned char h[VVB_HEADER];
    if (b->file_size < VVB_HEADER)
        return vv_error_set(VV_ERR_FORMAT, "file of %llu bytes is shorter than the header",
                            (unsigned long long)b->file_size);
    if ((s = vvb_read_at(b, h, VVB_HEADER, 0, "header")) != VV_OK)
        return s;
    if (memcmp(h, VVB_MAGIC, 8) != 0)
        return vv_error_set(VV_ERR_FORMAT, "not a .vvb file (no \"%s\" magic)", VVB_MAGIC);
    const uint32_t hsize = vvb_get_u32(h + 8), cells = vvb_get_u32(h + 12);
    int dims[3];
    for (int a = 0; a < 3; a++)
        dims[a] = (int)vvb_get_u32(h + 16 + 4 * a);
    const uint32_t type = vvb_get_u32(h + 28);
    if (hsize != VVB_HEADER || cells != VV_BRICK_CELLS)
        return vv_error_set(VV_ERR_FORMAT, "header size %u, brick side %u (expected %d, %d)", hsize,
                            cells, VVB_HEADER, VV_BRICK_CELLS);
    if (type > VV_F64)
        return vv_error_set(VV_ERR_FORMAT, "voxel type %u", type);
    uint64_t vbytes;
    if ((s = vv_volume_check_limits(dims, (vv_voxel_type)type, &vbytes)) != VV_OK)
        return s;
    const int one[3] = {1, 1, 1};
    if ((s = vv_volume_new(&b->header, one, (vv_voxel_type)type)) != VV_OK)
        return s;
    vv_volume *v = b->header;
    memcpy(v->dims, dims, sizeof dims);
    b->has_coarse = vvb_get_u32(h + 32) != 0;
    const uint32_t codec = vvb_get_u32(h + 200);
    if (codec > VVB_CODEC_ZSTD)
        return vv_error_set(VV_ERR_FORMAT, "unknown brick codec %u (0 raw, 1 zstd)", codec);
    b->zstd = codec == VVB_CODEC_ZSTD;
    if (b->zstd && !b->has_coarse)
        return vv_error_set(VV_ERR_FORMAT, "zstd bricks without coarse levels");
    v->unit = (vv_unit)vvb_get_u32(h + 36);
    v->space = (vv_space)vvb_get_u32(h + 40);
    for (int a = 0; a < 3; a++) {
        v->spacing[a] = vvb_get_f64(h + 48 + 8 * a);
        v->origin[a] = vvb_get_f64(h + 72 + 8 * a);
    }
    for (int a = 0; a < 9; a++)
        v->direction[a] = vvb_get_f64(h + 96 + 8 * a);
    v->range[0] = vvb_get_f64(h + 168);
    v->range[1] = vvb_get_f64(h + 176);
    for (int a = 0; a < 3; a++)
        if (!(v->spacing[a] > 0) || !isfinite(v->spacing[a]) || !isfinite(v->origin[a]))
            return vv_error_set(VV_ERR_FORMAT, "bad spacing or origin on axis %d", a);
    if (!(v->range[0] <= v->range[1]))
        return vv_error_set(VV_ERR_FORMAT, "bad value range %g..%g", v->range[0], v->range[1]);
    const uint64_t index_off = vvb_get_u64(h + 184), count = vvb_get_u64(h + 192);
    /* the entries are allocated once the file is known to hold the index */
    if ((s = vvb_brick_grid(b->header->dims, b->nb, &b->n)) != VV_OK)
        return s;
    if (count != (uint64_t)b->n)
        return vv_error_set(VV_ERR_FORMAT, "index of %llu bricks; %dx%dx%d voxels need %d",
                            (unsigned long long)count, dims[0], dims[1], dims[2], b->n);
    const uint64_t ibytes = count * VVB_RECORD;
    if (index_off < VVB_HEADER || index_off > b->file_size || b->file_size - index_off < ibytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "index of %llu bytes at offset %llu runs past the end of the file "
                            "(%llu bytes)",
                            (unsigned long long)ibytes, (unsigned long long)index_off,
                            (unsigned long long)b->file_size);
    if (!(b->e = calloc((size_t)b->n, sizeof *b->e)))
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    unsigned char *idx = malloc((size_t)ibytes);
    if (!idx)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    s = vvb_read_at(b, idx, (size_t)ibytes, index_off, "index");
    const size_t vs = vv_voxel_type_size(v->type);
    for (int i = 0; i < b->n && s == VV_OK; i++) {
        const unsigned char *r = idx + (size_t)i * VVB_RECORD;
        vvb_brick *e = &b->e[i];
        e->offset = vvb_get_u64(r);
        e->bytes = vvb_get_u64(r + 8);
        e->vmin = vvb_get_f64(r + 16);
        e->vmax = vvb_get_f64(r + 24);
        e->coarse_offset = vvb_get_u64(r + 32);
        e->coarse_bytes = vvb_get_u64(r + 40);
        vv_brick_info in;
        vvb_brick_boxes(b->header->dims, b->nb, i, &in);
        const uint64_t want = vvb_box_voxels(in.slo, in.shi) * vs;
        int cd[3];
        vvb_coarse_dims(&in, cd);
        const uint64_t cwant = b->has_coarse ? (uint64_t)cd[0] * cd[1] * cd[2] * vs : 0;
        char box[96], why[256];
        snprintf(box, sizeof box, "%d..%d x %d..%d x %d..%d", in.slo[0], in.shi[0], in.slo[1],
                 in.shi[1], in.slo[2], in.shi[2]);
        if (piece_problem(b, e->offset, e->bytes, want, box, why, sizeof why))
            s = vv_error_set(VV_ERR_FORMAT, "index: brick %d (%d,%d,%d)%s", i,
                             in.lo[0] / VV_BRICK_CELLS, in.lo[1] / VV_BRICK_CELLS,
                             in.lo[2] / VV_BRICK_CELLS, why);
        else if (e->coarse_bytes != cwant ||
                 (cwant && (e->coarse_offset > b->file_size ||
                            b->file_size - e->coarse_offset < e->coarse_bytes)))
            s = vv_error_set(VV_ERR_FORMAT,
                             "index: brick %d: coarse level of %llu bytes at offset %llu (expected "
                             "%llu bytes within the file)",
                             i, (unsigned long long)e->coarse_bytes,
                             (unsigned long long)e->coarse_offset, (unsigned long long)cwant);
        else if (!(e->vmin <= e->vmax))
            s = vv_error_set(VV_ERR_FORMAT, "index: brick %d: min %g > max %g", i, e->vmin,
                             e->vmax);
    }
    free(idx);
    if (s == VV_OK)
        s = open_levels(b, vvb_get_u32(h + 204), vvb_get_u64(h + 208));
    return s;
}

/* ---- reading back the file being written ------------------------------------- */

vv_status
vvb_readback_new(vv_bricked **out, int fd, const char *path, const vv_volume *hdr, const int nb[3],
                 int n, int zstd, const unsigned char *index) {
    *out = NULL;
    vv_bricked *rd = calloc(1, sizeof *rd);
    if (!rd || !(rd->e = calloc((size_t)n, sizeof *rd->e))) {
        free(rd);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    rd->fd = fd;
    rd->data_path = (char *)path;
    rd->header = (vv_volume *)hdr;
    memcpy(rd->nb, nb, sizeof rd->nb);
    rd->n = n;
    rd->zstd = zstd;
    rd->swap = !vv_host_is_little_endian();
    for (int i = 0; i < n; i++) {
        rd->e[i].offset = vvb_get_u64(index + (size_t)i * VVB_RECORD);
        rd->e[i].bytes = vvb_get_u64(index + (size_t)i * VVB_RECORD + 8);
    }
    *out = rd;
    return VV_OK;
}

vvb_level *
vvb_readback_level(vv_bricked *rd, int l, const int dims[3]) {
    vvb_level *L = &rd->lv[l];
    vvb_level_grid(L, dims);
    L->c = calloc((size_t)L->n, sizeof *L->c);
    return L->c ? L : NULL;
}

void
vvb_readback_free(vv_bricked *rd) {
    if (!rd)
        return;
    for (int l = 1; l < VV_PYRAMID_MAX_LEVELS; l++)
        free(rd->lv[l].c);
    free(rd->e);
    free(rd);
}

/* ---- a .vvb as a pyramid's store ------------------------------------------- */

int
vv_vvb_probe(const char *path) {
    unsigned char h[VVB_HEADER];
    const int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return 0;
    const ssize_t r = pread(fd, h, sizeof h, 0);
    close(fd);
    if (r != (ssize_t)sizeof h || memcmp(h, VVB_MAGIC, 8) != 0)
        return 0;
    const uint32_t n = vvb_get_u32(h + 204);
    return n > 1 && n <= VV_PYRAMID_MAX_LEVELS ? (int)n : 1;
}

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
    const vv_bricked *b = ctx;
    if (level > 0) {
        const vvb_level *L = &b->lv[level];
        const vvb_chunk *e = &L->c[(c[2] * L->nc[1] + c[1]) * L->nc[0] + c[0]];
        *lo = e->vmin;
        *hi = e->vmax;
        return 1;
    }
    int bc[3];
    for (int a = 0; a < 3; a++)
        bc[a] = c[a] < b->nb[a] - 1 ? c[a] : b->nb[a] - 1;
    const vvb_brick *e = &b->e[(bc[2] * b->nb[1] + bc[1]) * b->nb[0] + bc[0]];
    *lo = e->vmin;
    *hi = e->vmax;
    return 1;
}

static void
vvb_store_close(void *ctx) {
    vv_bricked_free(ctx);
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
    vv_bricked *b = calloc(1, sizeof *b);
    if (!b)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    b->fd = -1;
    b->vvb = 1;
    b->swap = !vv_host_is_little_endian();
    b->path = strdup(path);
    b->data_path = strdup(path);
    st->ctx = b;
    st->close = vvb_store_close;
    st->read_chunk = vvb_store_read;
    st->chunk_range = vvb_store_range;
    st->parallel = 1; /* pread and zstd into the caller's buffers */
    vv_status s =
        b->path && b->data_path ? vvb_open_file(b) : vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s != VV_OK)
        return s;
    st->scratch = (size_t)vvb_piece_bytes(b);
    st->n_levels = b->n_levels;
    const vv_volume *h = b->header;
    int f[3] = {1, 1, 1}; /* level-0 voxels per voxel of level l */
    for (int l = 0; l < b->n_levels && s == VV_OK; l++) {
        const int *d = l ? b->lv[l].dims : h->dims;
        int cd[3];
        for (int a = 0; a < 3; a++) {
            cd[a] = d[a] < VVB_CHUNK ? d[a] : VVB_CHUNK;
            if (l > 0 && (l > 1 ? b->lv[l - 1].dims[a] : h->dims[a]) > 1)
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
