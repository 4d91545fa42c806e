/*
 * The .vvc file: the header, the tables (quantisation and Huffman), the
 * subcube index and the data section, each with its CRC-32; writing,
 * parsing and checking, loading and saving (docs/file-formats.md).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

#include "compress/rangecoder.h"
#include "compress/vvc_internal.h"
#include "core/internal.h"

void
vv_vvc_free(vv_vvc *c) {
    if (!c)
        return;
    if (c->c2r) {
        vv_fftw_lock();
        fftwf_destroy_plan(c->c2r);
        vv_fftw_unlock();
    }
    free(c->bytes);
    vvc_scan_free(&c->scan);
    free(c->qtab);
    free(c->step_abs);
    free(c->offsets);
    free(c->p0);
    free(c->recon);
    free(c);
}

/* ---- little-endian writing and reading ------------------------------------ */

typedef struct bytebuf {
    unsigned char *p;
    size_t len, cap;
    int failed;
} bytebuf;

static void
bb_put(bytebuf *b, const void *data, size_t n) {
    if (b->failed)
        return;
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + n)
            cap *= 2;
        unsigned char *np = realloc(b->p, cap);
        if (!np) {
            b->failed = 1;
            return;
        }
        b->p = np;
        b->cap = cap;
    }
    memcpy(b->p + b->len, data, n);
    b->len += n;
}

static void
bb_u8(bytebuf *b, unsigned v) {
    unsigned char c = (unsigned char)v;
    bb_put(b, &c, 1);
}

static void
bb_u16(bytebuf *b, unsigned v) {
    unsigned char c[2] = {(unsigned char)v, (unsigned char)(v >> 8)};
    bb_put(b, c, 2);
}

static void
bb_u32(bytebuf *b, uint32_t v) {
    unsigned char c[4];
    for (int i = 0; i < 4; i++)
        c[i] = (unsigned char)(v >> (8 * i));
    bb_put(b, c, 4);
}

static void
bb_u64(bytebuf *b, uint64_t v) {
    unsigned char c[8];
    for (int i = 0; i < 8; i++)
        c[i] = (unsigned char)(v >> (8 * i));
    bb_put(b, c, 8);
}

static void
bb_f64(bytebuf *b, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    bb_u64(b, v);
}

static void
bb_f32(bytebuf *b, float f) {
    uint32_t v;
    memcpy(&v, &f, 4);
    bb_u32(b, v);
}

static void
bb_crc(bytebuf *b, size_t from) {
    if (b->failed)
        return;
    uLong crc = crc32(0L, Z_NULL, 0);
    size_t n = b->len - from;
    const unsigned char *p = b->p + from;
    while (n > 0) {
        uInt chunk = n > (1u << 30) ? (1u << 30) : (uInt)n;
        crc = crc32(crc, p, chunk);
        p += chunk;
        n -= chunk;
    }
    bb_u32(b, (uint32_t)crc);
}

uint32_t
vvc_crc(const unsigned char *p, uint64_t n) {
    uLong crc = crc32(0L, Z_NULL, 0);
    while (n > 0) {
        uInt chunk = n > (1u << 30) ? (1u << 30) : (uInt)n;
        crc = crc32(crc, p, chunk);
        p += chunk;
        n -= chunk;
    }
    return (uint32_t)crc;
}

static uint32_t
rd_u32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t
rd_u64(const unsigned char *p) {
    return (uint64_t)rd_u32(p) | (uint64_t)rd_u32(p + 4) << 32;
}

static double
rd_f64(const unsigned char *p) {
    uint64_t v = rd_u64(p);
    double d;
    memcpy(&d, &v, 8);
    return d;
}

static float
rd_f32(const unsigned char *p) {
    uint32_t v = rd_u32(p);
    float f;
    memcpy(&f, &v, 4);
    return f;
}

size_t
vvc_tables_bytes(int M, const vv_huff_table *dc, const vv_huff_table *ac) {
    const size_t H = (size_t)M / 2 + 1;
    return 4 + 4 * H * H * H + 16 + 2 * (size_t)dc->nvals + 16 + 2 * (size_t)ac->nvals + 4;
}

vv_status
vvc2_pack_codes(const vvc2_model *m, const uint8_t *code, uint8_t **z, size_t *zlen) {
    uLongf n = compressBound((uLong)m->nctx);
    *z = malloc(n);
    if (!*z || compress2(*z, &n, code, (uLong)m->nctx, 9) != Z_OK) {
        free(*z);
        *z = NULL;
        return vv_error_set(VV_ERR_NOMEM, "out of memory (deflating the context table)");
    }
    *zlen = n;
    return VV_OK;
}

size_t
vvc2_tables_bytes(size_t zlen, int nb) {
    return 4 + 4 + zlen + 4 + 8 * (size_t)nb + 4;
}

/* ---------------------------------------------------------------------- */
/* Writing                                                                  */

vv_status
vvc_write_file(const vv_volume *v, const vvc_file_desc *fd, const vvc_streams *st,
               unsigned char **bytes, size_t *size) {
    const int M = fd->M, H = M / 2 + 1, nsub = st->n;
    bytebuf bb = {0}, *b = &bb;
    uint64_t data_len = 0;
    for (int k = 0; k < nsub; k++)
        data_len += st->len[k];
    const int off_bytes = data_len < (1ull << 32) ? 4 : 8;
    const uint64_t tables_size = fd->version == 1 ? vvc_tables_bytes(M, &fd->huff[0], &fd->huff[1])
                                                  : vvc2_tables_bytes(fd->pzlen, fd->model->nb);
    const uint64_t index_size = (uint64_t)nsub * (uint64_t)off_bytes + 4;
    const uint64_t data_size = data_len + 4;

    /* header */
    bb_put(b, VVC_MAGIC, 8);
    bb_u32(b, (uint32_t)fd->version);
    bb_u32(b, fd->version == 1 ? VVC_HEADER_BYTES : VVC_HEADER_BYTES_V2);
    for (int i = 0; i < 3; i++)
        bb_u32(b, (uint32_t)v->dims[i]);
    bb_u8(b, (unsigned)v->type);
    bb_u8(b, (unsigned)v->unit);
    bb_u8(b, (unsigned)v->data_origin);
    bb_u8(b, (unsigned)v->modification);
    bb_u8(b, (unsigned)v->space);
    bb_u8(b, (unsigned)M);
    bb_u8(b, 0);
    bb_u8(b, 0);
    for (int i = 0; i < 3; i++)
        bb_f64(b, v->spacing[i]);
    for (int i = 0; i < 3; i++)
        bb_f64(b, v->origin[i]);
    for (int i = 0; i < 9; i++)
        bb_f64(b, v->direction[i]);
    bb_f64(b, v->range[0]);
    bb_f64(b, v->range[1]);
    bb_f64(b, fd->offset);
    bb_f64(b, fd->unit);
    bb_f64(b, fd->quality);
    bb_f64(b, fd->slope);
    for (int i = 0; i < 3; i++)
        bb_u32(b, (uint32_t)((v->dims[i] + M - 1) / M));
    bb_u64(b, tables_size);
    bb_u64(b, index_size);
    bb_u64(b, data_size);
    bb_crc(b, 0);
    if (fd->version >= 2) {
        /* the extension of version 2, after the CRC of the version 1 layout so
         * that a version 1 reader gets as far as the version number */
        bb_f64(b, fd->max_error);
        bb_f64(b, fd->corr_step);
        bb_crc(b, VVC_HEADER_BYTES);
    }
    /* tables */
    size_t from = b->len;
    if (fd->version == 1) {
        bb_u32(b, (uint32_t)(H * H * H));
        for (int i = 0; i < H * H * H; i++)
            bb_f32(b, fd->qtab[i]);
        for (int k = 0; k < 2; k++) {
            for (int l = 1; l <= VV_HUFF_MAX_LEN; l++)
                bb_u8(b, fd->huff[k].bits[l]);
            for (int i = 0; i < fd->huff[k].nvals; i++)
                bb_u16(b, fd->huff[k].vals[i]);
        }
    } else {
        /* version 2: the quantisation table follows from the quality and slope */
        bb_u32(b, (uint32_t)fd->model->nctx);
        bb_u32(b, (uint32_t)fd->pzlen);
        bb_put(b, fd->pz, fd->pzlen);
        bb_u32(b, (uint32_t)(2 * fd->model->nb));
        for (int i = 0; i < 2 * fd->model->nb; i++)
            bb_f32(b, fd->recon[i]);
    }
    bb_crc(b, from);
    /* index */
    from = b->len;
    uint64_t off = 0;
    for (int k = 0; k < nsub; k++) {
        if (off_bytes == 4)
            bb_u32(b, (uint32_t)off);
        else
            bb_u64(b, off);
        off += st->len[k];
    }
    bb_crc(b, from);
    /* data */
    from = b->len;
    for (int k = 0; k < nsub; k++)
        bb_put(b, st->buf[k], st->len[k]);
    bb_crc(b, from);
    if (b->failed) {
        free(b->p);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    *bytes = b->p;
    *size = b->len;
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* Parsing                                                                  */

static vv_status
parse_huff(const unsigned char **pp, const unsigned char *end, vv_huff_table *t, int nsym,
           const char *what) {
    const unsigned char *p = *pp;
    if (end - p < VV_HUFF_MAX_LEN)
        return vv_error_set(VV_ERR_FORMAT, "%s Huffman table truncated", what);
    memset(t, 0, sizeof *t);
    int total = 0;
    for (int l = 1; l <= VV_HUFF_MAX_LEN; l++) {
        t->bits[l] = *p++;
        total += t->bits[l];
    }
    if (total > nsym)
        return vv_error_set(VV_ERR_FORMAT, "%s Huffman table has %d codes (at most %d)", what,
                            total, nsym);
    if (end - p < 2 * total)
        return vv_error_set(VV_ERR_FORMAT, "%s Huffman table truncated", what);
    for (int i = 0; i < total; i++) {
        unsigned v = (unsigned)p[0] | (unsigned)p[1] << 8;
        p += 2;
        if ((int)v >= nsym)
            return vv_error_set(VV_ERR_FORMAT, "%s Huffman symbol %u out of range", what, v);
        if (nsym == VVC_DC_SYMS ? v > VVC_MAX_SIZE : (v & 63) > VVC_MAX_SIZE || v >> 6 > 15)
            return vv_error_set(VV_ERR_FORMAT, "%s Huffman symbol %u is not valid", what, v);
        t->vals[i] = (uint16_t)v;
    }
    t->nvals = total;
    *pp = p;
    return VV_OK;
}

/* Where the sections are, from the header. */
typedef struct vvc_sections {
    uint32_t hbytes;
    uint64_t tables_size, index_size, data_size;
} vvc_sections;

/* The header (and version 2's extension): c->info, c->M, c->nsub and the
 * section sizes, every field checked. */
static vv_status
vvc_parse_header(vv_vvc *c, vvc_sections *sec) {
    const unsigned char *b = c->bytes;
    const uint64_t size = c->size;
    if (size < 8 || memcmp(b, VVC_MAGIC, 8) != 0)
        return vv_error_set(VV_ERR_FORMAT, "not a .vvc file (bad magic number)");
    if (size < VVC_HEADER_BYTES)
        return vv_error_set(VV_ERR_FORMAT, "truncated header (%llu of %d bytes)",
                            (unsigned long long)size, VVC_HEADER_BYTES);
    const uint32_t version = rd_u32(b + 8);
    if (rd_u32(b + VVC_HEADER_BYTES - 4) != vvc_crc(b, VVC_HEADER_BYTES - 4))
        return vv_error_set(VV_ERR_FORMAT, "header CRC-32 mismatch (corrupt file)");
    if (version < 1 || version > VV_VVC_VERSION)
        return vv_error_set(VV_ERR_FORMAT, "format version %u (this build reads versions 1 to %d)",
                            version, VV_VVC_VERSION);
    const uint32_t hbytes = version == 1 ? VVC_HEADER_BYTES : VVC_HEADER_BYTES_V2;
    sec->hbytes = hbytes;
    if (rd_u32(b + 12) != hbytes)
        return vv_error_set(VV_ERR_FORMAT, "header size %u (expected %u for version %u)",
                            rd_u32(b + 12), hbytes, version);
    if (size < hbytes)
        return vv_error_set(VV_ERR_FORMAT, "truncated header (%llu of %u bytes)",
                            (unsigned long long)size, hbytes);
    if (hbytes > VVC_HEADER_BYTES &&
        rd_u32(b + hbytes - 4) != vvc_crc(b + VVC_HEADER_BYTES, hbytes - VVC_HEADER_BYTES - 4))
        return vv_error_set(VV_ERR_FORMAT, "header extension CRC-32 mismatch (corrupt file)");
    vv_vvc_info *in = &c->info;
    memset(in, 0, sizeof *in);
    in->version = (int)version;
    if (version >= 2) {
        in->max_error = rd_f64(b + VVC_HEADER_BYTES);
        in->corr_step = rd_f64(b + VVC_HEADER_BYTES + 8);
        if (!(in->max_error >= 0) || !(in->corr_step >= 0) || !isfinite(in->max_error) ||
            !isfinite(in->corr_step) || (in->corr_step > 0) != (in->max_error > 0))
            return vv_error_set(VV_ERR_FORMAT, "bad error bound %g or correction step %g",
                                in->max_error, in->corr_step);
    }
    for (int i = 0; i < 3; i++) {
        uint32_t d = rd_u32(b + 16 + 4 * i);
        if (d < 1 || d > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_FORMAT, "dimension %d is %u", i, d);
        in->dims[i] = (int)d;
    }
    if (b[28] > VV_F64 || b[29] > VV_UNIT_LAST || b[30] > VV_ORIGIN_OTHER ||
        b[31] > VV_MOD_OTHER || b[32] > VV_SPACE_LPS)
        return vv_error_set(VV_ERR_FORMAT, "bad enumeration in the header");
    in->type = (vv_voxel_type)b[28];
    in->unit = (vv_unit)b[29];
    in->data_origin = (vv_data_origin)b[30];
    in->modification = (vv_modification)b[31];
    in->space = (vv_space)b[32];
    const int M = b[33];
    if (M != 8 && M != 16 && M != 32)
        return vv_error_set(VV_ERR_FORMAT, "subcube side %d (expected 8, 16 or 32)", M);
    vv_status s = vv_volume_check_size(in->dims, in->type, &in->raw_bytes);
    if (s != VV_OK)
        return s;
    const unsigned char *p = b + 36;
    for (int i = 0; i < 3; i++)
        in->spacing[i] = rd_f64(p + 8 * i);
    for (int i = 0; i < 3; i++)
        in->origin[i] = rd_f64(p + 24 + 8 * i);
    for (int i = 0; i < 9; i++)
        in->direction[i] = rd_f64(p + 48 + 8 * i);
    /* a zero or non-finite spacing would place every voxel at one point
     * (or nowhere) for the renderers and measurements downstream */
    for (int i = 0; i < 3; i++) {
        if (!(in->spacing[i] > 0) || !isfinite(in->spacing[i]))
            return vv_error_set(VV_ERR_FORMAT, "voxel spacing %g on axis %d (must be finite, > 0)",
                                in->spacing[i], i);
        if (!isfinite(in->origin[i]))
            return vv_error_set(VV_ERR_FORMAT, "origin %g on axis %d is not finite", in->origin[i],
                                i);
    }
    for (int i = 0; i < 9; i++)
        if (!isfinite(in->direction[i]))
            return vv_error_set(VV_ERR_FORMAT, "direction matrix entry %d is %g (not finite)", i,
                                in->direction[i]);
    p += 120;
    in->range[0] = rd_f64(p);
    in->range[1] = rd_f64(p + 8);
    in->value_offset = rd_f64(p + 16);
    in->value_unit = rd_f64(p + 24);
    in->quality = rd_f64(p + 32);
    in->slope = rd_f64(p + 40);
    p += 48;
    if (!isfinite(in->value_offset) || !(in->value_unit > 0) || !isfinite(in->value_unit))
        return vv_error_set(VV_ERR_FORMAT, "bad value offset or unit");
    for (int i = 0; i < 3; i++) {
        in->subcubes[i] = (int)rd_u32(p + 4 * i);
        if (in->subcubes[i] != (in->dims[i] + M - 1) / M)
            return vv_error_set(VV_ERR_FORMAT, "%d subcubes along axis %d for %d voxels of %d",
                                in->subcubes[i], i, in->dims[i], M);
    }
    p += 12;
    const uint64_t tables_size = rd_u64(p), index_size = rd_u64(p + 8), data_size = rd_u64(p + 16);
    sec->tables_size = tables_size;
    sec->index_size = index_size;
    sec->data_size = data_size;
    const uint64_t rest = size - hbytes;
    if (tables_size > rest || index_size > rest - tables_size ||
        data_size != rest - tables_size - index_size)
        return vv_error_set(VV_ERR_FORMAT,
                            "section sizes %llu + %llu + %llu do not match the %llu bytes after "
                            "the header (truncated or corrupt file)",
                            (unsigned long long)tables_size, (unsigned long long)index_size,
                            (unsigned long long)data_size, (unsigned long long)rest);
    c->M = M;
    in->block = M;
    c->nsub = in->subcubes[0] * in->subcubes[1] * in->subcubes[2];
    in->file_bytes = size;
    in->data_bytes = data_size >= 4 ? data_size - 4 : 0;
    in->ratio = (double)in->raw_bytes / (double)size;
    in->bits_per_voxel =
        8.0 * (double)size / ((double)in->dims[0] * (double)in->dims[1] * (double)in->dims[2]);
    return VV_OK;
}

/* Version 2's context tables (the adaptive binary model's initial
 * probabilities, zlib-compressed) and reconstruction offsets, from @p hp
 * to @p hend. */
static vv_status
vvc_parse_contexts(vv_vvc *c, const unsigned char *hp, const unsigned char *hend) {
    vvc2_model_init(&c->model, c->scan.nb);
    const int nr = 2 * c->model.nb;
    if (hend - hp < 8 || rd_u32(hp) != (uint32_t)c->model.nctx ||
        (uint64_t)(hend - hp) != 8 + (uint64_t)rd_u32(hp + 4) + 4 + 4 * (uint64_t)nr)
        return vv_error_set(VV_ERR_FORMAT, "context table of %lld bytes (expected %d contexts)",
                            (long long)(hend - hp), c->model.nctx);
    const unsigned char *rp = hp + 8 + rd_u32(hp + 4);
    if (rd_u32(rp) != (uint32_t)nr)
        return vv_error_set(VV_ERR_FORMAT, "%u reconstruction offsets (expected %d)", rd_u32(rp),
                            nr);
    if (!(c->recon = malloc(sizeof *c->recon * (size_t)nr)))
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < nr; i++) {
        c->recon[i] = rd_f32(rp + 4 + 4 * (size_t)i);
        if (!(c->recon[i] >= -0.5f && c->recon[i] <= 0.5f))
            return vv_error_set(VV_ERR_FORMAT, "reconstruction offset %d is %g", i,
                                (double)c->recon[i]);
    }
    uint8_t *code = malloc((size_t)c->model.nctx);
    if (!code || !(c->p0 = malloc(sizeof *c->p0 * (size_t)c->model.nctx))) {
        free(code);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    uLongf n = (uLongf)c->model.nctx;
    const int zr = uncompress(code, &n, hp + 8, (uLong)rd_u32(hp + 4));
    if (zr != Z_OK || n != (uLongf)c->model.nctx) {
        free(code);
        return vv_error_set(VV_ERR_FORMAT, "context table does not inflate to %d bytes",
                            c->model.nctx);
    }
    for (int i = 0; i < c->model.nctx; i++)
        c->p0[i] = (uint16_t)vvc2_prob_of_code(code[i]);
    free(code);
    return VV_OK;
}

/* The tables: the quantisation table (stored, or from the quality and
 * slope), then version 1's Huffman tables or version 2's contexts. */
static vv_status
vvc_parse_tables(vv_vvc *c, const vvc_sections *sec) {
    const unsigned char *b = c->bytes;
    const vv_vvc_info *in = &c->info;
    const int version = in->version, M = c->M;
    const uint64_t tables_size = sec->tables_size;
    vv_status s;
    const unsigned char *t0 = b + sec->hbytes;
    if (tables_size < 8 || rd_u32(t0 + tables_size - 4) != vvc_crc(t0, tables_size - 4))
        return vv_error_set(VV_ERR_FORMAT, "tables CRC-32 mismatch (corrupt file)");
    const int H = M / 2 + 1;
    if ((s = vvc_scan_init(&c->scan, M)) != VV_OK)
        return s;
    c->qtab = malloc(sizeof(float) * (size_t)H * H * H);
    c->step_abs = malloc(sizeof(float) * (size_t)c->scan.N);
    if (!c->qtab || !c->step_abs)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    const unsigned char *hp = t0, *hend = t0 + tables_size - 4;
    if (version == 1) {
        if (rd_u32(t0) != (uint32_t)(H * H * H) || tables_size < 4 + 4ull * H * H * H + 4)
            return vv_error_set(VV_ERR_FORMAT, "quantisation table size %u (expected %d)",
                                rd_u32(t0), H * H * H);
        for (int i = 0; i < H * H * H; i++)
            c->qtab[i] = rd_f32(t0 + 4 + 4 * (size_t)i);
        hp = t0 + 4 + 4 * (size_t)H * H * H;
    } else {
        /* the table follows from the quality and the slope */
        if (!(in->quality > -1000 && in->quality <= 1000) || !(in->slope >= 0 && in->slope <= 100))
            return vv_error_set(VV_ERR_FORMAT, "quality %g or slope %g out of range", in->quality,
                                in->slope);
        vvc_make_table(c->qtab, M, in->quality, in->slope);
    }
    for (int i = 0; i < H * H * H; i++)
        if (!(c->qtab[i] > 0) || !(c->qtab[i] < 1e30f))
            return vv_error_set(VV_ERR_FORMAT, "quantisation step %d is %g", i, (double)c->qtab[i]);
    vvc_make_step_abs(&c->scan, c->qtab, c->step_abs);
    if (version == 1) {
        if ((s = parse_huff(&hp, hend, &c->dct, VVC_DC_SYMS, "DC")) != VV_OK ||
            (s = parse_huff(&hp, hend, &c->act, VVC_AC_SYMS, "AC")) != VV_OK)
            return s;
        if (hp != hend)
            return vv_error_set(VV_ERR_FORMAT, "%lld stray bytes after the Huffman tables",
                                (long long)(hend - hp));
        if ((s = vv_huff_make_dec(&c->dct, &c->dc)) != VV_OK ||
            (s = vv_huff_make_dec(&c->act, &c->ac)) != VV_OK)
            return s;
    } else if ((s = vvc_parse_contexts(c, hp, hend)) != VV_OK) {
        return s;
    }
    return VV_OK;
}

/* The subcube index (offsets in order, within the data) and the data's CRC. */
static vv_status
vvc_parse_index(vv_vvc *c, const vvc_sections *sec) {
    const unsigned char *b = c->bytes;
    const uint64_t index_size = sec->index_size, data_size = sec->data_size;
    const unsigned char *i0 = b + sec->hbytes + sec->tables_size;
    if (data_size < 4)
        return vv_error_set(VV_ERR_FORMAT, "data section of %llu bytes",
                            (unsigned long long)data_size);
    const uint64_t data_len = data_size - 4;
    const int ob = data_len < (1ull << 32) ? 4 : 8;
    if (index_size != (uint64_t)c->nsub * (uint64_t)ob + 4)
        return vv_error_set(VV_ERR_FORMAT, "subcube index of %llu bytes (expected %llu)",
                            (unsigned long long)index_size,
                            (unsigned long long)((uint64_t)c->nsub * (uint64_t)ob + 4));
    if (rd_u32(i0 + index_size - 4) != vvc_crc(i0, index_size - 4))
        return vv_error_set(VV_ERR_FORMAT, "subcube index CRC-32 mismatch (corrupt file)");
    c->offsets = malloc(sizeof(uint64_t) * ((size_t)c->nsub + 1));
    if (!c->offsets)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int k = 0; k < c->nsub; k++) {
        uint64_t o = ob == 4 ? rd_u32(i0 + 4 * (size_t)k) : rd_u64(i0 + 8 * (size_t)k);
        if ((k == 0 && o != 0) || (k > 0 && o < c->offsets[k - 1]) || o > data_len)
            return vv_error_set(VV_ERR_FORMAT, "subcube %d: offset %llu out of order", k,
                                (unsigned long long)o);
        c->offsets[k] = o;
    }
    c->offsets[c->nsub] = data_len;
    const unsigned char *d0 = i0 + index_size;
    if (rd_u32(d0 + data_len) != vvc_crc(d0, data_len))
        return vv_error_set(VV_ERR_FORMAT, "data CRC-32 mismatch (corrupt file)");
    c->data_start = (uint64_t)(d0 - b);
    c->data_len = data_len;
    return VV_OK;
}

vv_status
vvc_parse(vv_vvc *c, const char *name) {
    (void)name;
    vvc_sections sec = {0, 0, 0, 0};
    vv_status s;
    if ((s = vvc_parse_header(c, &sec)) != VV_OK || (s = vvc_parse_tables(c, &sec)) != VV_OK)
        return s;
    return vvc_parse_index(c, &sec);
}

vv_status
vv_vvc_from_memory(vv_vvc **out, const void *data, size_t size, const char *name) {
    *out = NULL;
    if (!name)
        name = "(memory)";
    if ((uint64_t)size > VVC_MAX_FILE)
        return vv_error_set(VV_ERR_LIMIT, "vvc: %s: %zu bytes is over the limit", name, size);
    vv_status s = vv_memory_budget_check((uint64_t)size, "a copy of a .vvc");
    if (s != VV_OK)
        return vv_error_prefix(s, "vvc: %s", name);
    vv_vvc *c = calloc(1, sizeof *c);
    if (!c || !(c->bytes = malloc(size ? size : 1))) {
        free(c);
        return vv_error_set(VV_ERR_NOMEM, "vvc: %s: out of memory", name);
    }
    memcpy(c->bytes, data, size);
    c->size = size;
    s = vvc_parse(c, name);
    if (s != VV_OK) {
        vv_vvc_free(c);
        return vv_error_prefix(s, "vvc: %s", name);
    }
    *out = c;
    return VV_OK;
}

vv_status
vv_vvc_load(vv_vvc **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status s = VV_OK;
    /* the whole file is read into memory: first its magic (a large file that
     * is no .vvc is not read at all) and its size against the budget */
    struct stat st;
    if (stat(path, &st) == 0 && S_ISREG(st.st_mode)) {
        if (st.st_size >= 8 && !vv_vvc_detect(path))
            s = vv_error_set(VV_ERR_FORMAT, "not a .vvc file (bad magic number)");
        else
            s = vv_memory_budget_check((uint64_t)st.st_size, "a .vvc file read whole");
    }
    if (s == VV_OK)
        s = vv_read_file(path, VVC_MAX_FILE, &data, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "vvc: %s", path);
    vv_vvc *c = calloc(1, sizeof *c);
    if (!c) {
        free(data);
        return vv_error_set(VV_ERR_NOMEM, "vvc: %s: out of memory", path);
    }
    c->bytes = data;
    c->size = (size_t)size;
    if ((s = vvc_parse(c, path)) != VV_OK) {
        vv_vvc_free(c);
        return vv_error_prefix(s, "vvc: %s", path);
    }
    *out = c;
    return VV_OK;
}

vv_status
vv_vvc_save(const vv_vvc *c, const char *path) {
    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, path);
    if (s != VV_OK)
        return vv_error_prefix(s, "vvc");
    if (fwrite(c->bytes, 1, c->size, af.fp) != c->size) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "vvc: %s: write failed", path);
    }
    if ((s = vv_atomic_file_commit(&af)) != VV_OK)
        return vv_error_prefix(s, "vvc");
    return VV_OK;
}

const unsigned char *
vv_vvc_bytes(const vv_vvc *c, size_t *size) {
    if (size)
        *size = c->size;
    return c->bytes;
}

void
vv_vvc_get_info(const vv_vvc *c, vv_vvc_info *info) {
    *info = c->info;
}

int
vv_vvc_detect(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    unsigned char m[8];
    int ok = fread(m, 1, 8, f) == 8 && memcmp(m, VVC_MAGIC, 8) == 0;
    fclose(f);
    return ok;
}

int
vv_vvc_subcube_count(const vv_vvc *c) {
    return c->nsub;
}
