/*
 * The .vvb file's reading (docs/file-formats.md; the layout and the
 * vvb_file in vvb_layout.h): its header, brick index and pyramid levels,
 * each piece checked against the file's size before anything is read; a
 * piece read raw or as one zstd frame (libzstd, its size checked before
 * and after decoding); boxes of any level assembled from the bricks or
 * chunks they overlap; the geometry of bricks, levels and chunks; pread
 * of exactly so many bytes, which the bricked reader (bricked.c) also
 * reads raw layouts with. It knows no bricked volume: the bricked reader,
 * the writer (vvb_write.c, which reads its levels back through
 * vvb_readback_new) and the .vvb's pyramid store and format row (vvb.c)
 * all stand on it.
 *
 * Thread-safety: the geometry functions are pure; pieces and level boxes
 * are read with pread only, from any thread; vvb_read_at and
 * vvb_read_brick count the bytes read atomically.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <zstd.h>

#include "core/internal.h"
#include "io/store/pyramid.h"
#include "io/store/vvb_layout.h"

void
vvb_swap_bytes(void *data, size_t count, size_t vs) {
    unsigned char *b = data;
    for (size_t i = 0; i < count; i++, b += vs)
        for (size_t k = 0; k < vs / 2; k++) {
            unsigned char t = b[k];
            b[k] = b[vs - 1 - k];
            b[vs - 1 - k] = t;
        }
}

/* pread of exactly n bytes at off (uncounted: any thread). */
vv_status
vvb_pread(const vvb_file *f, void *buf, size_t n, uint64_t off, const char *what) {
    size_t done = 0;
    while (done < n) {
        ssize_t r = pread(f->fd, (char *)buf + done, n - done, (off_t)(off + done));
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return vv_error_set(VV_ERR_IO, "%s: %s: %s", vv_path_basename(f->data_path), what,
                                strerror(errno));
        if (r == 0)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: %s: the file ends at byte %llu (reading %zu bytes at %llu)",
                                vv_path_basename(f->data_path), what,
                                (unsigned long long)(off + done), n, (unsigned long long)off);
        done += (size_t)r;
    }
    return VV_OK;
}

/* vvb_pread, counted in f->bytes_read. */
vv_status
vvb_read_at(vvb_file *f, void *buf, size_t n, uint64_t off, const char *what) {
    const vv_status s = vvb_pread(f, buf, n, off, what);
    if (s == VV_OK)
        __atomic_fetch_add(&f->bytes_read, (uint64_t)n, __ATOMIC_RELAXED);
    return s;
}

/* ---- geometry ------------------------------------------------------------- */

void
vvb_brick_boxes(const int dims[3], const int nb[3], int index, vv_brick_info *in) {
    int c[3] = {index % nb[0], (index / nb[0]) % nb[1], index / (nb[0] * nb[1])};
    for (int a = 0; a < 3; a++) {
        const int last = dims[a] - 1;
        in->lo[a] = c[a] * VV_BRICK_CELLS;
        in->hi[a] = in->lo[a] + VV_BRICK_CELLS < last ? in->lo[a] + VV_BRICK_CELLS : last;
        in->slo[a] = in->lo[a] > 0 ? in->lo[a] - 1 : 0;
        in->shi[a] = in->hi[a] < last ? in->hi[a] + 1 : last;
    }
}

/* The brick grid of @p dims into @p nb and *@p n_out (no entries yet);
 * VV_ERR_LIMIT over 2^26 bricks. */
vv_status
vvb_brick_grid(const int dims[3], int nb[3], int *n_out) {
    for (int a = 0; a < 3; a++) {
        const int cells = dims[a] > 1 ? dims[a] - 1 : 1;
        nb[a] = (cells + VV_BRICK_CELLS - 1) / VV_BRICK_CELLS;
    }
    const uint64_t n = (uint64_t)nb[0] * (uint64_t)nb[1] * (uint64_t)nb[2];
    if (n > (uint64_t)1 << 26)
        return vv_error_set(VV_ERR_LIMIT, "bricks: %llu bricks", (unsigned long long)n);
    *n_out = (int)n;
    return VV_OK;
}

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
vvb_piece_bytes(const vvb_file *f) {
    uint64_t n = 1;
    for (int a = 0; a < 3; a++) {
        const int d = f->header->dims[a], side = VV_BRICK_CELLS + 3;
        n *= (uint64_t)(d < side ? d : side);
    }
    return n * vv_voxel_type_size(f->header->type);
}

/* ---- reading pieces ------------------------------------------------------- */

/* The @p bytes at @p off of a .vvb -- a brick's stored box or a level's
 * chunk, of @p want bytes -- into @p dst (as stored: little-endian): one
 * pread, then with zstd one frame decoded into exactly @p want bytes.
 * Uncounted: any thread. */
vv_status
vvb_read_piece(const vvb_file *f, uint64_t off, uint64_t bytes, void *dst, uint64_t want,
               const char *what) {
    if (!f->zstd)
        return vvb_pread(f, dst, (size_t)want, off, what);
    void *z = malloc((size_t)bytes);
    if (!z)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = vvb_pread(f, z, (size_t)bytes, off, what);
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

/* Brick @p index of a .vvb, its stored box of @p want bytes, into @p dst
 * (as stored), counted. */
vv_status
vvb_read_brick(vvb_file *f, int index, void *dst, uint64_t want, const char *what) {
    const vvb_brick *e = &f->e[index];
    const vv_status s = vvb_read_piece(f, e->offset, e->bytes, dst, want, what);
    if (s == VV_OK)
        __atomic_fetch_add(&f->bytes_read, e->bytes, __ATOMIC_RELAXED);
    return s;
}

/* Voxels lo .. lo + n - 1 of level @p level into @p dst (x fastest, host
 * byte order), from the bricks (level 0: each brick's own voxels lo .. hi)
 * or the level's chunks that the box overlaps, each read once into
 * @p piece (vvb_piece_bytes); *bytes adds the bytes read. Uncounted in the
 * statistics: any thread. */
vv_status
vvb_read_level_box(const vvb_file *f, int level, const int lo[3], const int n[3],
                   unsigned char *dst, unsigned char *piece, uint64_t *bytes) {
    const size_t vs = vv_voxel_type_size(f->header->type);
    const vvb_level *L = level > 0 ? &f->lv[level] : NULL;
    const int *grid = L ? L->nc : f->nb;
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
                    vvb_brick_boxes(f->header->dims, f->nb, i, &in);
                    for (int a = 0; a < 3; a++) {
                        own0[a] = in.lo[a];
                        own1[a] = in.hi[a];
                        st0[a] = in.slo[a];
                        sn[a] = in.shi[a] - in.slo[a] + 1;
                    }
                    off = f->e[i].offset;
                    zbytes = f->e[i].bytes;
                    snprintf(what, sizeof what, "brick %d", i);
                }
                const uint64_t nv = (uint64_t)sn[0] * sn[1] * sn[2];
                vv_status s = vvb_read_piece(f, off, zbytes, piece, nv * vs, what);
                if (s != VV_OK)
                    return s;
                *bytes += zbytes;
                if (f->swap && vs > 1)
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

/* ---- opening -------------------------------------------------------------- */

vv_status
vvb_open_data(vvb_file *f, const char *path) {
    f->fd = open(path, O_RDONLY);
    if (f->fd < 0)
        return vv_error_set(VV_ERR_IO, "%s: %s", vv_path_basename(path), strerror(errno));
    struct stat st;
    if (fstat(f->fd, &st) != 0)
        return vv_error_set(VV_ERR_IO, "%s: %s", vv_path_basename(path), strerror(errno));
    f->file_size = (uint64_t)st.st_size;
    return VV_OK;
}

/* What is wrong with a piece of a .vvb -- a brick's voxels or a level's
 * chunk -- of @p bytes at @p off, whose box (@p box names it) holds @p want
 * bytes: 0 when nothing, else 1 and the phrase in @p why: its size against
 * the box's (raw: equal; zstd: 1 to the compression bound), or where it
 * runs past the end of the file. */
static int
piece_problem(const vvb_file *f, uint64_t off, uint64_t bytes, uint64_t want, const char *box,
              char *why, size_t cap) {
    const uint64_t bound = f->zstd ? ZSTD_compressBound((size_t)want) : want;
    if (f->zstd ? bytes == 0 || bytes > bound : bytes != want)
        snprintf(why, cap, " has %llu bytes; its box %s needs %s%llu", (unsigned long long)bytes,
                 box, f->zstd ? "compressed 1 to " : "", (unsigned long long)bound);
    else if (off < VVB_HEADER || off > f->file_size || f->file_size - off < bytes)
        snprintf(why, cap, ": %llu bytes at offset %llu run past the end of the file (%llu bytes)",
                 (unsigned long long)bytes, (unsigned long long)off,
                 (unsigned long long)f->file_size);
    else
        return 0;
    return 1;
}

/* The pyramid levels of a .vvb: @p n levels in all (0 and 1: the bricks
 * only), the table at @p table_off; each level's dims must be the halving
 * rule's (vvb_level_dims), its index and chunks inside the file. */
static vv_status
open_levels(vvb_file *f, uint32_t n, uint64_t table_off) {
    f->n_levels = 1;
    if (n <= 1)
        return VV_OK;
    int dims[VV_PYRAMID_MAX_LEVELS][3];
    const int want = vvb_level_dims(f->header->dims, dims);
    if (n != (uint32_t)want)
        return vv_error_set(VV_ERR_FORMAT, "%u pyramid levels; %dx%dx%d voxels make %d", n,
                            dims[0][0], dims[0][1], dims[0][2], want);
    const uint64_t tbytes = (uint64_t)(n - 1) * VVB_LEVEL_RECORD;
    if (table_off < VVB_HEADER || table_off > f->file_size || f->file_size - table_off < tbytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "level table of %llu bytes at offset %llu runs past the end of the "
                            "file (%llu bytes)",
                            (unsigned long long)tbytes, (unsigned long long)table_off,
                            (unsigned long long)f->file_size);
    unsigned char t[VV_PYRAMID_MAX_LEVELS * VVB_LEVEL_RECORD];
    vv_status s = vvb_read_at(f, t, (size_t)tbytes, table_off, "level table");
    const size_t vs = vv_voxel_type_size(f->header->type);
    for (int l = 1; l < want && s == VV_OK; l++) {
        const unsigned char *r = t + (size_t)(l - 1) * VVB_LEVEL_RECORD;
        vvb_level *L = &f->lv[l];
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
        if (ioff < VVB_HEADER || ioff > f->file_size || f->file_size - ioff < ibytes)
            return vv_error_set(VV_ERR_FORMAT,
                                "level %d: index of %llu bytes at offset %llu runs past the end "
                                "of the file (%llu bytes)",
                                l, (unsigned long long)ibytes, (unsigned long long)ioff,
                                (unsigned long long)f->file_size);
        unsigned char *idx = malloc((size_t)ibytes);
        L->c = calloc((size_t)L->n, sizeof *L->c);
        if (!idx || !L->c) {
            free(idx);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        s = vvb_read_at(f, idx, (size_t)ibytes, ioff, "level index");
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
            if (piece_problem(f, c->offset, c->bytes, cw, box, why, sizeof why))
                s = vv_error_set(VV_ERR_FORMAT, "level %d: chunk %d%s", l, i, why);
            else if (!(c->vmin <= c->vmax))
                s = vv_error_set(VV_ERR_FORMAT, "level %d: chunk %d: min %g > max %g", l, i,
                                 c->vmin, c->vmax);
        }
        free(idx);
    }
    if (s == VV_OK)
        f->n_levels = want;
    return s;
}

vv_status
vvb_open_file(vvb_file *f) {
    f->swap = !vv_host_is_little_endian(); /* a .vvb is little-endian */
    vv_status s = vvb_open_data(f, f->data_path);
    if (s != VV_OK)
        return s;
    unsigned char h[VVB_HEADER];
    if (f->file_size < VVB_HEADER)
        return vv_error_set(VV_ERR_FORMAT, "file of %llu bytes is shorter than the header",
                            (unsigned long long)f->file_size);
    if ((s = vvb_read_at(f, h, VVB_HEADER, 0, "header")) != VV_OK)
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
    if ((s = vv_volume_new(&f->header, one, (vv_voxel_type)type)) != VV_OK)
        return s;
    vv_volume *v = f->header;
    memcpy(v->dims, dims, sizeof dims);
    f->has_coarse = vvb_get_u32(h + 32) != 0;
    const uint32_t codec = vvb_get_u32(h + 200);
    if (codec > VVB_CODEC_ZSTD)
        return vv_error_set(VV_ERR_FORMAT, "unknown brick codec %u (0 raw, 1 zstd)", codec);
    f->zstd = codec == VVB_CODEC_ZSTD;
    if (f->zstd && !f->has_coarse)
        return vv_error_set(VV_ERR_FORMAT, "zstd bricks without coarse levels");
    /* optional metadata: a unit or space this build does not know is unknown,
     * not a value past the enumeration passed on to writers */
    const uint32_t unit = vvb_get_u32(h + 36), space = vvb_get_u32(h + 40);
    v->unit = unit <= VV_UNIT_LAST ? (vv_unit)unit : VV_UNIT_UNKNOWN;
    v->space = space <= VV_SPACE_LPS ? (vv_space)space : VV_SPACE_UNKNOWN;
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
    for (int a = 0; a < 9; a++)
        if (!isfinite(v->direction[a]))
            return vv_error_set(VV_ERR_FORMAT, "direction matrix entry %d is %g (not finite)", a,
                                v->direction[a]);
    if (!(v->range[0] <= v->range[1]))
        return vv_error_set(VV_ERR_FORMAT, "bad value range %g..%g", v->range[0], v->range[1]);
    const uint64_t index_off = vvb_get_u64(h + 184), count = vvb_get_u64(h + 192);
    /* the entries are allocated once the file is known to hold the index */
    if ((s = vvb_brick_grid(f->header->dims, f->nb, &f->n)) != VV_OK)
        return s;
    if (count != (uint64_t)f->n)
        return vv_error_set(VV_ERR_FORMAT, "index of %llu bricks; %dx%dx%d voxels need %d",
                            (unsigned long long)count, dims[0], dims[1], dims[2], f->n);
    const uint64_t ibytes = count * VVB_RECORD;
    if (index_off < VVB_HEADER || index_off > f->file_size || f->file_size - index_off < ibytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "index of %llu bytes at offset %llu runs past the end of the file "
                            "(%llu bytes)",
                            (unsigned long long)ibytes, (unsigned long long)index_off,
                            (unsigned long long)f->file_size);
    if (!(f->e = calloc((size_t)f->n, sizeof *f->e)))
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    unsigned char *idx = malloc((size_t)ibytes);
    if (!idx)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    s = vvb_read_at(f, idx, (size_t)ibytes, index_off, "index");
    const size_t vs = vv_voxel_type_size(v->type);
    for (int i = 0; i < f->n && s == VV_OK; i++) {
        const unsigned char *r = idx + (size_t)i * VVB_RECORD;
        vvb_brick *e = &f->e[i];
        e->offset = vvb_get_u64(r);
        e->bytes = vvb_get_u64(r + 8);
        e->vmin = vvb_get_f64(r + 16);
        e->vmax = vvb_get_f64(r + 24);
        e->coarse_offset = vvb_get_u64(r + 32);
        e->coarse_bytes = vvb_get_u64(r + 40);
        vv_brick_info in;
        vvb_brick_boxes(f->header->dims, f->nb, i, &in);
        const uint64_t want = vvb_box_voxels(in.slo, in.shi) * vs;
        int cd[3];
        vvb_coarse_dims(&in, cd);
        const uint64_t cwant = f->has_coarse ? (uint64_t)cd[0] * cd[1] * cd[2] * vs : 0;
        char box[96], why[256];
        snprintf(box, sizeof box, "%d..%d x %d..%d x %d..%d", in.slo[0], in.shi[0], in.slo[1],
                 in.shi[1], in.slo[2], in.shi[2]);
        if (piece_problem(f, e->offset, e->bytes, want, box, why, sizeof why))
            s = vv_error_set(VV_ERR_FORMAT, "index: brick %d (%d,%d,%d)%s", i,
                             in.lo[0] / VV_BRICK_CELLS, in.lo[1] / VV_BRICK_CELLS,
                             in.lo[2] / VV_BRICK_CELLS, why);
        else if (e->coarse_bytes != cwant ||
                 (cwant && (e->coarse_offset > f->file_size ||
                            f->file_size - e->coarse_offset < e->coarse_bytes)))
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
        s = open_levels(f, vvb_get_u32(h + 204), vvb_get_u64(h + 208));
    return s;
}

/* Releases what @p f holds (not @p f itself): its index, its levels' chunk
 * tables, its header, its name and the file. */
void
vvb_file_close(vvb_file *f) {
    free(f->e);
    for (int l = 1; l < VV_PYRAMID_MAX_LEVELS; l++)
        free(f->lv[l].c);
    if (f->fd >= 0)
        close(f->fd);
    vv_volume_free(f->header);
    free(f->data_path);
}

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

/* ---- reading back the file being written ---------------------------------- */

vv_status
vvb_readback_new(vvb_file **out, int fd, const char *path, const vv_volume *hdr, const int nb[3],
                 int n, int zstd, const unsigned char *index) {
    *out = NULL;
    vvb_file *rd = calloc(1, sizeof *rd);
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
vvb_readback_level(vvb_file *rd, int l, const int dims[3]) {
    vvb_level *L = &rd->lv[l];
    vvb_level_grid(L, dims);
    L->c = calloc((size_t)L->n, sizeof *L->c);
    return L->c ? L : NULL;
}

void
vvb_readback_free(vvb_file *rd) {
    if (!rd)
        return;
    for (int l = 1; l < VV_PYRAMID_MAX_LEVELS; l++)
        free(rd->lv[l].c);
    free(rd->e);
    free(rd);
}
