/*
 * Writing .vvb files (docs/file-formats.md; the layout in vvb_layout.h):
 * from a bricked volume opened from any source (vv_bricked_write_vvb), a
 * box reader such as a pyramid's level 0 (vv_boxes_write_vvb) or a volume
 * in memory (vv_volume_write_vvb). One brick at a time: its voxels with
 * their ghosts, its min/max, raw or one zstd frame (level 3, its content
 * size and checksum in the frame), and its coarse level; then with
 * VV_VVB_LEVELS the pyramid levels, each chunk reduced from the level
 * before as read back from the file (vv_pyr_reduce: OME-Zarr's levels,
 * voxel for voxel); the header and index last. Memory is bounded by a
 * brick (and a level's 2x2x2 chunks), not the volume. The file is written
 * beside the target (named by vv_tmp_name) and renamed over it; the
 * temporaries of writers of the same target that were killed are removed
 * first (vv_tmp_sweep).
 *
 * Thread-safety: one file a call; calls on different files may run at
 * once (a bricked source is read through its own reader, src/io/store/bricked.h).
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <zstd.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/bricked.h"
#include "io/store/pyramid.h"
#include "io/store/vvb_layout.h"

#define VVB_ZSTD_LEVEL 3

/* One zstd frame of @p n bytes at @p src into @p dst (@p cap bytes): level 3,
 * its content size and a checksum in the frame (a scribbled frame fails to
 * decode rather than giving other voxels). The size, or a zstd error code. */
static size_t
zstd_frame(void *dst, size_t cap, const void *src, size_t n) {
    ZSTD_CCtx *c = ZSTD_createCCtx();
    if (!c)
        return (size_t)-1; /* ZSTD_isError: a generic error */
    size_t r = ZSTD_CCtx_setParameter(c, ZSTD_c_compressionLevel, VVB_ZSTD_LEVEL);
    if (!ZSTD_isError(r))
        r = ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 1);
    if (!ZSTD_isError(r))
        r = ZSTD_compress2(c, dst, cap, src, n);
    ZSTD_freeCCtx(c);
    return r;
}

/* The pyramid levels after level 0's bricks (written to @p f, their
 * records in @p index): each level's chunks from the level before read
 * back from @p f and reduced (vv_pyr_reduce: OME-Zarr's levels, voxel for
 * voxel), each followed by its index; then the level table. *pos is the
 * file's end; *n_levels and *table_off get what the header says. Memory: a
 * chunk's 2x2x2 blocks (128^3 voxels) and one piece. */
static vv_status
write_levels(FILE *f, const char *path, const vv_volume *hdr, const int nb[3], int n, int zstd,
             const unsigned char *index, uint64_t *pos, int *n_levels, uint64_t *table_off,
             const vv_progress *progress) {
    int dims[VV_PYRAMID_MAX_LEVELS][3];
    const int nl = vvb_level_dims(hdr->dims, dims);
    *n_levels = 1;
    if (nl < 2)
        return VV_OK;
    vvb_file *rd = NULL; /* level 0 and the levels written so far, read back */
    vv_status s = vvb_readback_new(&rd, fileno(f), path, hdr, nb, n, zstd, index);
    if (s != VV_OK)
        return s;
    const int swap = !vv_host_is_little_endian();
    const size_t vs = vv_voxel_type_size(hdr->type);
    const size_t work_n = (size_t)8 * VVB_CHUNK * VVB_CHUNK * VVB_CHUNK * vs,
                 chunk_n = (size_t)VVB_CHUNK * VVB_CHUNK * VVB_CHUNK * vs,
                 zcap = ZSTD_compressBound(chunk_n);
    unsigned char *piece = malloc((size_t)vvb_piece_bytes(rd)), *work = malloc(work_n),
                  *chunk = malloc(chunk_n), *z = zstd ? malloc(zcap) : NULL;
    unsigned char table[VV_PYRAMID_MAX_LEVELS * VVB_LEVEL_RECORD];
    memset(table, 0, sizeof table);
    if (!piece || !work || !chunk || (!z && zstd))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    uint64_t total = 0, done = 0;
    for (int l = 1; l < nl; l++) {
        vvb_level t;
        vvb_level_grid(&t, dims[l]);
        total += (uint64_t)t.n;
    }
    for (int l = 1; l < nl && s == VV_OK; l++) {
        if (fflush(f) != 0) {
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
            break;
        }
        vvb_level *L = vvb_readback_level(rd, l, dims[l]);
        if (!L) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            break;
        }
        const int *sd = dims[l - 1];
        for (int i = 0; i < L->n && s == VV_OK; i++) {
            vv_pyr_reduce_box rb;
            memset(&rb, 0, sizeof rb);
            rb.src = work;
            rb.type = hdr->type;
            vvb_chunk_box(L, i, rb.lo, rb.n);
            for (int a = 0; a < 3; a++) {
                rb.src_dims[a] = sd[a];
                rb.step[a] = sd[a] > 1 ? 2 : 1;
                rb.src_lo[a] = rb.lo[a] * rb.step[a];
                rb.src_n[a] = (rb.lo[a] + rb.n[a]) * rb.step[a] < sd[a] ? rb.n[a] * rb.step[a]
                                                                        : sd[a] - rb.src_lo[a];
            }
            rb.dst_dims[0] = rb.n[0];
            rb.dst_dims[1] = rb.n[1];
            uint64_t got = 0;
            if ((s = vvb_read_level_box(rd, l - 1, rb.src_lo, rb.src_n, work, piece, &got)) !=
                VV_OK)
                break;
            vv_pyr_reduce(&rb, chunk);
            const size_t nv = (size_t)rb.n[0] * rb.n[1] * rb.n[2];
            vv_volume cv; /* the chunk, for its range (NaN left out) */
            memset(&cv, 0, sizeof cv);
            cv.type = hdr->type;
            cv.data = chunk;
            memcpy(cv.dims, rb.n, sizeof cv.dims);
            vv_volume_update_range(&cv);
            const double mn = cv.range[0], mx = cv.range[1];
            if (swap)
                vvb_swap_bytes(chunk, nv, vs);
            const unsigned char *out = chunk;
            size_t out_n = nv * vs;
            if (zstd) {
                const size_t zn = zstd_frame(z, zcap, chunk, out_n);
                if (ZSTD_isError(zn)) {
                    s = vv_error_set(VV_ERR_IO, "%s: level %d chunk %d: zstd: %s", path, l, i,
                                     ZSTD_getErrorName(zn));
                    break;
                }
                out = z;
                out_n = zn;
            }
            if (fwrite(out, 1, out_n, f) != out_n) {
                s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
                break;
            }
            L->c[i] = (vvb_chunk){*pos, out_n, mn, mx};
            *pos += out_n;
            if (progress && vv_progress_report(progress, 0.875 + 0.125 * (double)++done / total))
                s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
        }
        /* the level's index, and its record in the table */
        unsigned char *idx = s == VV_OK ? malloc((size_t)L->n * VVB_CHUNK_RECORD) : NULL;
        if (s == VV_OK && !idx)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        for (int i = 0; i < L->n && s == VV_OK; i++) {
            unsigned char *e = idx + (size_t)i * VVB_CHUNK_RECORD;
            vvb_put_u64(e, L->c[i].offset);
            vvb_put_u64(e + 8, L->c[i].bytes);
            vvb_put_f64(e + 16, L->c[i].vmin);
            vvb_put_f64(e + 24, L->c[i].vmax);
        }
        if (s == VV_OK && fwrite(idx, VVB_CHUNK_RECORD, (size_t)L->n, f) != (size_t)L->n)
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
        free(idx);
        unsigned char *r = table + (size_t)(l - 1) * VVB_LEVEL_RECORD;
        for (int a = 0; a < 3; a++)
            vvb_put_u32(r + 4 * a, (uint32_t)L->dims[a]);
        vvb_put_u32(r + 12, VVB_CHUNK);
        vvb_put_u64(r + 16, *pos);
        vvb_put_u64(r + 24, (uint64_t)L->n);
        *pos += (uint64_t)L->n * VVB_CHUNK_RECORD;
    }
    const size_t tbytes = (size_t)(nl - 1) * VVB_LEVEL_RECORD;
    if (s == VV_OK && fwrite(table, 1, tbytes, f) != tbytes)
        s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
    if (s == VV_OK) {
        *table_off = *pos;
        *pos += tbytes;
        *n_levels = nl;
    }
    vvb_readback_free(rd);
    free(piece);
    free(work);
    free(chunk);
    free(z);
    return s;
}

/* Where a brick's voxels come from while writing. */
typedef vv_status (*brick_source)(void *ctx, int index, const vv_brick_info *in, void *buf);

static vv_status
write_vvb(const char *path, const vv_volume *hdr, const int nb[3], int n, unsigned flags,
          brick_source src, void *ctx, const vv_progress *progress) {
    const size_t vs = vv_voxel_type_size(hdr->type);
    /* zstd bricks always come with coarse levels (previews read those) */
    const int zstd = (flags & VV_VVB_ZSTD) != 0;
    const int coarse = zstd || (flags & VV_VVB_COARSE);
    const int levels = (flags & VV_VVB_LEVELS) != 0;
    const size_t cap = strlen(path) + 64;
    char *tmp = malloc(cap);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    /* beside the target, named by this process (vv_tmp_name); the
     * temporaries of writers of this path that were killed go first */
    (void)vv_tmp_sweep(path);
    int fd = -1, err = EEXIST;
    for (unsigned attempt = 0; fd < 0 && err == EEXIST && attempt < 100; attempt++) {
        if (vv_tmp_name(tmp, cap, path, (long)getpid(), attempt) != 0)
            err = ENAMETOOLONG;
        else if ((fd = open(tmp, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666)) < 0)
            err = errno;
    }
    FILE *f = fd >= 0 ? fdopen(fd, "w+b") : NULL; /* the levels read the bricks back */
    if (!f) {
        if (fd >= 0) {
            err = errno;
            close(fd);
            remove(tmp);
        }
        vv_status s = vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(err));
        free(tmp);
        return s;
    }
    unsigned char *index = calloc((size_t)n, VVB_RECORD);
    vv_status s = index ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    uint64_t pos = VVB_HEADER + (uint64_t)n * VVB_RECORD;
    double lo = INFINITY, hi = -INFINITY;
    void *buf = NULL, *cbuf = NULL, *zbuf = NULL;
    if (s == VV_OK && fseeko(f, (off_t)pos, SEEK_SET) != 0)
        s = vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
    for (int i = 0; i < n && s == VV_OK; i++) {
        vv_brick_info in;
        vvb_brick_boxes(hdr->dims, nb, i, &in);
        const uint64_t nv = vvb_box_voxels(in.slo, in.shi);
        free(buf);
        buf = malloc((size_t)(nv * vs));
        if (!buf) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            break;
        }
        if ((s = src(ctx, i, &in, buf)) != VV_OK)
            break;
        vv_volume tmpv;
        memset(&tmpv, 0, sizeof tmpv);
        tmpv.type = hdr->type;
        tmpv.data = buf;
        tmpv.dims[0] = in.shi[0] - in.slo[0] + 1;
        tmpv.dims[1] = in.shi[1] - in.slo[1] + 1;
        tmpv.dims[2] = in.shi[2] - in.slo[2] + 1;
        vv_volume_update_range(&tmpv); /* NaN left out; 0 and 0 when nothing else */
        const double mn = tmpv.range[0], mx = tmpv.range[1];
        lo = mn < lo ? mn : lo;
        hi = mx > hi ? mx : hi;
        unsigned char *r = index + (size_t)i * VVB_RECORD;
        vvb_put_f64(r + 16, mn);
        vvb_put_f64(r + 24, mx);
        if (!vv_host_is_little_endian())
            vvb_swap_bytes(buf, (size_t)nv, vs);
        const void *out = buf;
        size_t out_bytes = (size_t)(nv * vs);
        if (zstd) {
            const size_t bound = ZSTD_compressBound(out_bytes);
            free(zbuf);
            zbuf = malloc(bound);
            if (!zbuf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            const size_t zn = zstd_frame(zbuf, bound, buf, out_bytes);
            if (ZSTD_isError(zn)) {
                s = vv_error_set(VV_ERR_IO, "%s: brick %d: zstd: %s", path, i,
                                 ZSTD_getErrorName(zn));
                break;
            }
            out = zbuf;
            out_bytes = zn;
        }
        vvb_put_u64(r, pos);
        vvb_put_u64(r + 8, out_bytes);
        if (fwrite(out, 1, out_bytes, f) != out_bytes) {
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
            break;
        }
        pos += out_bytes;
        if (coarse) {
            int cd[3];
            vvb_coarse_dims(&in, cd);
            const size_t cn = (size_t)cd[0] * cd[1] * cd[2];
            free(cbuf);
            cbuf = malloc(cn * vs);
            if (!cbuf) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
                break;
            }
            for (int k = 0; k < cd[2]; k++)
                for (int j = 0; j < cd[1]; j++)
                    for (int ii = 0; ii < cd[0]; ii++) {
                        const size_t sx = (size_t)(in.lo[0] + VVB_COARSE * ii - in.slo[0]);
                        const size_t sy = (size_t)(in.lo[1] + VVB_COARSE * j - in.slo[1]);
                        const size_t sz = (size_t)(in.lo[2] + VVB_COARSE * k - in.slo[2]);
                        memcpy((char *)cbuf + (((size_t)k * cd[1] + j) * cd[0] + ii) * vs,
                               (char *)buf + ((sz * tmpv.dims[1] + sy) * tmpv.dims[0] + sx) * vs,
                               vs);
                    }
            vvb_put_u64(r + 32, pos);
            vvb_put_u64(r + 40, cn * vs);
            if (fwrite(cbuf, vs, cn, f) != cn) {
                s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
                break;
            }
            pos += cn * vs;
        }
        if (progress && vv_progress_report(progress, (levels ? 0.875 : 1.0) * (double)(i + 1) / n))
            s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
    }
    free(buf);
    free(cbuf);
    free(zbuf);
    int n_levels = 1;
    uint64_t table_off = 0;
    if (s == VV_OK && levels)
        s = write_levels(f, path, hdr, nb, n, zstd, index, &pos, &n_levels, &table_off, progress);
    if (s == VV_OK) {
        unsigned char h[VVB_HEADER];
        memset(h, 0, sizeof h);
        memcpy(h, VVB_MAGIC, 8);
        vvb_put_u32(h + 8, VVB_HEADER);
        vvb_put_u32(h + 12, VV_BRICK_CELLS);
        for (int a = 0; a < 3; a++)
            vvb_put_u32(h + 16 + 4 * a, (uint32_t)hdr->dims[a]);
        vvb_put_u32(h + 28, (uint32_t)hdr->type);
        vvb_put_u32(h + 32, coarse ? 1 : 0);
        vvb_put_u32(h + 36, (uint32_t)hdr->unit);
        vvb_put_u32(h + 40, (uint32_t)hdr->space);
        for (int a = 0; a < 3; a++) {
            vvb_put_f64(h + 48 + 8 * a, hdr->spacing[a]);
            vvb_put_f64(h + 72 + 8 * a, hdr->origin[a]);
        }
        for (int a = 0; a < 9; a++)
            vvb_put_f64(h + 96 + 8 * a, hdr->direction[a]);
        if (!(lo <= hi))
            lo = hi = 0;
        vvb_put_f64(h + 168, lo);
        vvb_put_f64(h + 176, hi);
        vvb_put_u64(h + 184, VVB_HEADER);
        vvb_put_u64(h + 192, (uint64_t)n);
        vvb_put_u32(h + 200, zstd ? VVB_CODEC_ZSTD : 0);
        if (n_levels > 1) {
            vvb_put_u32(h + 204, (uint32_t)n_levels);
            vvb_put_u64(h + 208, table_off);
        }
        if (fseeko(f, 0, SEEK_SET) != 0 || fwrite(h, 1, sizeof h, f) != sizeof h ||
            fwrite(index, VVB_RECORD, (size_t)n, f) != (size_t)n)
            s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
    }
    free(index);
    if (fclose(f) != 0 && s == VV_OK)
        s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", path, strerror(errno));
    if (s == VV_OK && rename(tmp, path) != 0)
        s = vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
    if (s != VV_OK)
        remove(tmp);
    free(tmp);
    return s;
}

/* A bricked source being written as .vvb: a .vvb's bricks read one by one;
 * a raw layout's read a row of bricks at a time (every brick of one j and
 * k: one pread a row of the volume instead of one a row of each brick),
 * when that row is under 64 MiB. */
typedef struct bricked_feed {
    vv_bricked *b;
    vv_volume row; /* the row of bricks held: data NULL, or voxels 0 .. N-1 x slo .. shi */
    int rj, rk;    /* its brick j and k */
} bricked_feed;

static vv_status
source_bricked(void *ctx, int index, const vv_brick_info *in, void *buf) {
    bricked_feed *f = ctx;
    vv_bricked *b = f->b;
    const vv_volume *h = vv_bricked_header(b);
    const size_t vs = vv_voxel_type_size(h->type);
    const int *d = h->dims;
    const uint64_t row_bytes =
        (uint64_t)d[0] * (uint64_t)(VV_BRICK_CELLS + 3) * (uint64_t)(VV_BRICK_CELLS + 3) * vs;
    if (vvb_is_vvb(b) || row_bytes > ((uint64_t)64 << 20))
        return vvb_read_stored(b, index, in, buf);
    int nb[3];
    vv_bricked_grid(b, nb);
    const int bj = (index / nb[0]) % nb[1], bk = index / (nb[0] * nb[1]);
    if (!f->row.data || f->rj != bj || f->rk != bk) {
        free(f->row.data);
        f->row.data = malloc((size_t)row_bytes);
        if (!f->row.data)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        vv_brick_info r = *in;
        r.slo[0] = 0;
        r.shi[0] = d[0] - 1;
        f->row.type = h->type;
        for (int a = 0; a < 3; a++)
            f->row.dims[a] = r.shi[a] - r.slo[a] + 1;
        f->rj = bj;
        f->rk = bk;
        const vv_status s = vvb_read_stored(b, -1, &r, f->row.data);
        if (s != VV_OK) {
            free(f->row.data);
            f->row.data = NULL;
            return s;
        }
    }
    const size_t n = (size_t)(in->shi[0] - in->slo[0] + 1) * vs;
    char *dst = buf;
    for (int k = 0; k < f->row.dims[2]; k++)
        for (int j = 0; j < f->row.dims[1]; j++, dst += n)
            memcpy(dst,
                   (const char *)f->row.data +
                       (((size_t)k * f->row.dims[1] + j) * f->row.dims[0] + in->slo[0]) * vs,
                   n);
    return VV_OK;
}

vv_status
vv_bricked_write_vvb(vv_bricked *src, const char *path, unsigned flags,
                     const vv_progress *progress) {
    bricked_feed f;
    memset(&f, 0, sizeof f);
    f.b = src;
    int nb[3];
    vv_bricked_grid(src, nb);
    const vv_status s = write_vvb(path, vv_bricked_header(src), nb, vv_bricked_count(src), flags,
                                  source_bricked, &f, progress);
    free(f.row.data);
    return s;
}

static vv_status
source_memory(void *ctx, int index, const vv_brick_info *in, void *buf) {
    (void)index;
    const vv_volume *v = ctx;
    const size_t vs = vv_voxel_type_size(v->type);
    const size_t row = (size_t)(in->shi[0] - in->slo[0] + 1) * vs;
    char *dst = buf;
    for (int k = in->slo[2]; k <= in->shi[2]; k++)
        for (int j = in->slo[1]; j <= in->shi[1]; j++) {
            memcpy(dst,
                   (const char *)v->data +
                       (((size_t)k * v->dims[1] + j) * v->dims[0] + in->slo[0]) * vs,
                   row);
            dst += row;
        }
    return VV_OK;
}

/* A box reader's box of a brick (ghosts included) copied into @p buf. */
typedef struct box_source {
    vv_box_reader read;
    void *ctx;
    vv_voxel_type type;
} box_source;

static vv_status
source_boxes(void *ctx, int index, const vv_brick_info *in, void *buf) {
    (void)index;
    const box_source *bs = ctx;
    vv_volume *v = NULL;
    vv_status s = bs->read(bs->ctx, in->slo, in->shi, &v);
    if (s == VV_OK &&
        (!v || v->type != bs->type || v->dims[0] != in->shi[0] - in->slo[0] + 1 ||
         v->dims[1] != in->shi[1] - in->slo[1] + 1 || v->dims[2] != in->shi[2] - in->slo[2] + 1))
        s = vv_error_set(VV_ERR_INVALID, "the reader gave a box of another shape or type");
    if (s == VV_OK)
        memcpy(buf, v->data, vvb_box_voxels(in->slo, in->shi) * vv_voxel_type_size(v->type));
    vv_volume_free(v);
    return s;
}

/* write_vvb of the volume @p hdr describes, its brick grid made here (the
 * grid only: no entries). */
static vv_status
write_vvb_of(const vv_volume *hdr, const char *path, unsigned flags, brick_source src, void *ctx,
             const vv_progress *progress) {
    int nb[3], n = 0;
    vv_status s = vvb_brick_grid(hdr->dims, nb, &n);
    if (s != VV_OK)
        return s;
    return write_vvb(path, hdr, nb, n, flags, src, ctx, progress);
}

vv_status
vv_boxes_write_vvb(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                   unsigned flags, const vv_progress *progress) {
    if (!hdr || !read || !path)
        return vv_error_set(VV_ERR_INVALID, "vvb: NULL argument");
    box_source bs = {read, ctx, hdr->type};
    return write_vvb_of(hdr, path, flags, source_boxes, &bs, progress);
}

vv_status
vv_volume_write_vvb(const vv_volume *v, const char *path, unsigned flags) {
    return write_vvb_of(v, path, flags, source_memory, (void *)v, NULL);
}
