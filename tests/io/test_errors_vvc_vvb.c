/*
 * Every refusal of the .vvc and .vvb readers ("our own parsers under
 * attack"): hand-made hostile files, each checked for its status, a phrase
 * naming the field or the problem, the file's name where the reader's outer
 * layer adds it, and a message of one printable line.
 *
 * - .vvc (src/compress/vvc_format.c): a valid file of each version taken
 *   apart into its sections, one field or section changed, put together
 *   again with every CRC-32 right (so the check under test, not a CRC,
 *   refuses it), or broken after its CRCs were made (the CRC checks).
 * - .vvb (src/io/store/vvb_read.c, vvb.c, bricked.c): a valid file of each kind
 *   (raw, coarse, zstd, with levels) with one header field, index record,
 *   level record or zstd frame changed, read whole (vv_volume_load) and by
 *   bricks (vv_bricked_open); raw layouts past their file's end, a brick
 *   source over its budget, a file cut short while open.
 */
#include "testutil.h"

#define expect_refusal(got, want, needle, name, what)                                              \
    vt_expect_refusal(what, got, want, needle, name)

#include "compress/vvc_internal.h"
#include "io/store/bricked.h"
#include "io/store/vvb_layout.h"
#include "volvis/bricks.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#define outdir() vt_outdir("errors_vvc_vvb")

static void
put32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void
put64(unsigned char *p, uint64_t v) {
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void
putf64(unsigned char *p, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    put64(p, v);
}

static uint32_t
get32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t
get64(const unsigned char *p) {
    return (uint64_t)get32(p) | (uint64_t)get32(p + 4) << 32;
}

/* ======================================================================== */
/* .vvc                                                                      */

/* A .vvc taken apart: the header (with its CRCs) and the payloads of the
 * tables, the index and the data, without their CRCs. */
typedef struct vvc_parts {
    unsigned char h[VVC_HEADER_BYTES_V2];
    size_t hb;
    unsigned char *t, *x, *d;
    size_t tn, xn, dn;
    int keep_sizes; /* leave the header's section sizes as the mutation set them */
} vvc_parts;

static vv_volume *
ramp_volume(int nx, int ny, int nz, vv_voxel_type t) {
    const int dims[3] = {nx, ny, nz};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, t));
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++)
                vv_volume_set(v, i, j, k, (double)((i * 7 + j * 13 + k * 29) % 251));
    vv_volume_update_range(v);
    return v;
}

static unsigned char *
dup_bytes(const unsigned char *p, size_t n) {
    unsigned char *q = malloc(n ? n : 1);
    assert_non_null(q);
    memcpy(q, p, n);
    return q;
}

static void
vvc_split(int version, vvc_parts *vp) {
    vv_volume *v = ramp_volume(19, 11, 9, VV_I16);
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.block = 8;
    p.quality = 50;
    p.version = version;
    vv_vvc *c = NULL;
    vt_ok(vv_vvc_compress(&c, v, &p));
    vv_volume_free(v);
    size_t n;
    const unsigned char *b = vv_vvc_bytes(c, &n);
    memset(vp, 0, sizeof *vp);
    vp->hb = version == 1 ? VVC_HEADER_BYTES : VVC_HEADER_BYTES_V2;
    assert_int_equal(get32(b + 12), vp->hb);
    memcpy(vp->h, b, vp->hb);
    const uint64_t T = get64(b + 216), I = get64(b + 224), D = get64(b + 232);
    assert_int_equal(vp->hb + T + I + D, n);
    vp->t = dup_bytes(b + vp->hb, (size_t)T - 4);
    vp->tn = (size_t)T - 4;
    vp->x = dup_bytes(b + vp->hb + T, (size_t)I - 4);
    vp->xn = (size_t)I - 4;
    vp->d = dup_bytes(b + vp->hb + T + I, (size_t)D - 4);
    vp->dn = (size_t)D - 4;
    vv_vvc_free(c);
}

static void
vvc_parts_free(vvc_parts *vp) {
    free(vp->t);
    free(vp->x);
    free(vp->d);
}

static void
crc_at(unsigned char *p, size_t n) {
    put32(p + n, (uint32_t)crc32(0L, p, (uInt)n));
}

/* The header's CRCs made right (after a change to its fields). */
static void
vvc_fix_header(unsigned char *b, size_t hb) {
    crc_at(b, VVC_HEADER_BYTES - 4);
    if (hb > VVC_HEADER_BYTES)
        crc_at(b + VVC_HEADER_BYTES, hb - VVC_HEADER_BYTES - 4);
}

/* The parts put together, every CRC right. */
static unsigned char *
vvc_join(vvc_parts *vp, size_t *n) {
    if (!vp->keep_sizes) {
        put64(vp->h + 216, vp->tn + 4);
        put64(vp->h + 224, vp->xn + 4);
        put64(vp->h + 232, vp->dn + 4);
    }
    *n = vp->hb + vp->tn + vp->xn + vp->dn + 12;
    unsigned char *b = malloc(*n);
    assert_non_null(b);
    memcpy(b, vp->h, vp->hb);
    vvc_fix_header(b, vp->hb);
    size_t o = vp->hb;
    memcpy(b + o, vp->t, vp->tn);
    crc_at(b + o, vp->tn);
    o += vp->tn + 4;
    memcpy(b + o, vp->x, vp->xn);
    crc_at(b + o, vp->xn);
    o += vp->xn + 4;
    memcpy(b + o, vp->d, vp->dn);
    crc_at(b + o, vp->dn);
    return b;
}

static void
grow(unsigned char **p, size_t *n, size_t to) {
    unsigned char *q = realloc(*p, to);
    assert_non_null(q);
    if (to > *n)
        memset(q + *n, 0, to - *n);
    *p = q;
    *n = to;
}

/* ---- the mutations: one field or section each ---- */

#define VVC_QTAB_END (4 + 4 * 5 * 5 * 5) /* version 1, M = 8: the table's count and steps */

static void
m_version(vvc_parts *p) {
    put32(p->h + 8, 3);
}
static void
m_header_size(vvc_parts *p) {
    put32(p->h + 12, 250);
}
static void
m_error_bound(vvc_parts *p) {
    putf64(p->h + 244, -1.0);
}
static void
m_dim0(vvc_parts *p) {
    put32(p->h + 16, 0);
}
static void
m_enum(vvc_parts *p) {
    p->h[28] = 200;
}
static void
m_side(vvc_parts *p) {
    p->h[33] = 12;
}
static void
m_huge(vvc_parts *p) {
    for (int a = 0; a < 3; a++)
        put32(p->h + 16 + 4 * a, 65536);
}
static void
m_spacing0(vvc_parts *p) {
    putf64(p->h + 36 + 8, 0.0);
}
static void
m_spacing_nan(vvc_parts *p) {
    putf64(p->h + 36 + 16, NAN);
}
static void
m_spacing_neg(vvc_parts *p) {
    putf64(p->h + 36, -1.0);
}
static void
m_origin_inf(vvc_parts *p) {
    putf64(p->h + 60 + 8, INFINITY);
}
static void
m_direction_nan(vvc_parts *p) {
    putf64(p->h + 84 + 8 * 4, NAN);
}
static void
m_value_unit(vvc_parts *p) {
    putf64(p->h + 180, 0.0);
}
static void
m_subcubes(vvc_parts *p) {
    put32(p->h + 204 + 4, 7);
}
static void
m_section_sizes(vvc_parts *p) {
    p->keep_sizes = 1;
    put64(p->h + 216, (uint64_t)1 << 40);
}
static void
m_tables_tiny(vvc_parts *p) {
    p->tn = 3;
}
static void
m_qtab_count(vvc_parts *p) {
    put32(p->t, 7);
}
static void
m_qtab_zero(vvc_parts *p) {
    memset(p->t + 4 + 4 * 3, 0, 4);
}
static void
m_quality(vvc_parts *p) {
    putf64(p->h + 188, 2000.0);
}
static void
m_dc_short(vvc_parts *p) {
    p->tn = VVC_QTAB_END + 5;
}
static void
m_dc_codes(vvc_parts *p) {
    p->t[VVC_QTAB_END] = 65;
}
static void
m_dc_symbols_short(vvc_parts *p) {
    p->tn = VVC_QTAB_END + VV_HUFF_MAX_LEN + 1;
}
static void
m_dc_symbol_range(vvc_parts *p) {
    p->t[VVC_QTAB_END + VV_HUFF_MAX_LEN] = 64;
    p->t[VVC_QTAB_END + VV_HUFF_MAX_LEN + 1] = 0;
}
static void
m_dc_symbol_invalid(vvc_parts *p) {
    p->t[VVC_QTAB_END + VV_HUFF_MAX_LEN] = VVC_MAX_SIZE + 1;
    p->t[VVC_QTAB_END + VV_HUFF_MAX_LEN + 1] = 0;
}
static void
m_stray(vvc_parts *p) {
    grow(&p->t, &p->tn, p->tn + 2);
}
static void
m_ctx_size(vvc_parts *p) {
    grow(&p->t, &p->tn, p->tn + 4);
}
static void
m_recon_count(vvc_parts *p) {
    const size_t rp = 8 + get32(p->t + 4);
    put32(p->t + rp, get32(p->t + rp) + 1);
}
static void
m_recon_value(vvc_parts *p) {
    const size_t rp = 8 + get32(p->t + 4);
    const float f = 0.75f;
    uint32_t u;
    memcpy(&u, &f, 4);
    put32(p->t + rp + 4, u);
}
static void
m_inflate(vvc_parts *p) {
    p->t[8] ^= 0xff; /* the zlib stream's header */
}
static void
m_index_size(vvc_parts *p) {
    grow(&p->x, &p->xn, p->xn + 4);
}
static void
m_offset_order(vvc_parts *p) {
    put32(p->x, 1);
}

/* ---- and what is done after the CRCs are made ---- */

static size_t
a_magic(unsigned char *b, size_t n) {
    b[0] ^= 1;
    return n;
}
static size_t
a_short(unsigned char *b, size_t n) {
    (void)b;
    (void)n;
    return 100;
}
static size_t
a_short_v2(unsigned char *b, size_t n) {
    (void)b;
    (void)n;
    return 250;
}
static size_t
a_header_crc(unsigned char *b, size_t n) {
    b[20] ^= 1;
    return n;
}
static size_t
a_ext_crc(unsigned char *b, size_t n) {
    b[250] ^= 1;
    return n;
}
static size_t
a_tables_crc(unsigned char *b, size_t n) {
    b[get32(b + 12) + 10] ^= 1;
    return n;
}
static size_t
a_index_crc(unsigned char *b, size_t n) {
    b[get32(b + 12) + get64(b + 216)] ^= 1;
    return n;
}
static size_t
a_data_crc(unsigned char *b, size_t n) {
    b[n - 5] ^= 1;
    return n;
}
/* A data section of 2 bytes (the file cut, the header saying so). */
static size_t
a_data_short(unsigned char *b, size_t n) {
    const size_t hb = get32(b + 12);
    const uint64_t d = get64(b + 232);
    put64(b + 232, 2);
    vvc_fix_header(b, hb);
    return n - (size_t)d + 2;
}

typedef struct vvc_case {
    const char *what;
    int version;
    void (*mutate)(vvc_parts *);
    size_t (*after)(unsigned char *, size_t);
    vv_status status;
    const char *needle;
} vvc_case;

static const vvc_case vvc_cases[] = {
    {"magic", 1, NULL, a_magic, VV_ERR_FORMAT, "bad magic number"},
    {"header cut", 1, NULL, a_short, VV_ERR_FORMAT, "truncated header (100 of 244"},
    {"header CRC", 2, NULL, a_header_crc, VV_ERR_FORMAT, "header CRC-32 mismatch"},
    {"version", 1, m_version, NULL, VV_ERR_FORMAT, "format version 3"},
    {"header size", 1, m_header_size, NULL, VV_ERR_FORMAT, "header size 250 (expected 244"},
    {"v2 header cut", 2, NULL, a_short_v2, VV_ERR_FORMAT, "truncated header (250 of 264"},
    {"extension CRC", 2, NULL, a_ext_crc, VV_ERR_FORMAT, "header extension CRC-32"},
    {"error bound", 2, m_error_bound, NULL, VV_ERR_FORMAT, "bad error bound -1"},
    {"dimension", 1, m_dim0, NULL, VV_ERR_FORMAT, "dimension 0 is 0"},
    {"enumeration", 2, m_enum, NULL, VV_ERR_FORMAT, "bad enumeration"},
    {"subcube side", 1, m_side, NULL, VV_ERR_FORMAT, "subcube side 12"},
    {"size limit", 2, m_huge, NULL, VV_ERR_LIMIT, "65536 x 65536 x 65536"},
    {"spacing 0", 1, m_spacing0, NULL, VV_ERR_FORMAT, "voxel spacing 0 on axis 1"},
    {"spacing NaN", 2, m_spacing_nan, NULL, VV_ERR_FORMAT, "voxel spacing nan on axis 2"},
    {"spacing < 0", 2, m_spacing_neg, NULL, VV_ERR_FORMAT, "voxel spacing -1 on axis 0"},
    {"origin inf", 1, m_origin_inf, NULL, VV_ERR_FORMAT, "origin inf on axis 1"},
    {"direction NaN", 2, m_direction_nan, NULL, VV_ERR_FORMAT, "direction"},
    {"value unit", 1, m_value_unit, NULL, VV_ERR_FORMAT, "bad value offset or unit"},
    {"subcubes", 2, m_subcubes, NULL, VV_ERR_FORMAT, "7 subcubes along axis 1"},
    {"section sizes", 1, m_section_sizes, NULL, VV_ERR_FORMAT, "section sizes 1099511627776"},
    {"tables CRC", 1, NULL, a_tables_crc, VV_ERR_FORMAT, "tables CRC-32 mismatch"},
    {"tables of 7 bytes", 2, m_tables_tiny, NULL, VV_ERR_FORMAT, "tables CRC-32 mismatch"},
    {"quantisation count", 1, m_qtab_count, NULL, VV_ERR_FORMAT, "quantisation table size 7"},
    {"quantisation step", 1, m_qtab_zero, NULL, VV_ERR_FORMAT, "quantisation step 3 is 0"},
    {"quality", 2, m_quality, NULL, VV_ERR_FORMAT, "quality 2000"},
    {"DC cut", 1, m_dc_short, NULL, VV_ERR_FORMAT, "DC Huffman table truncated"},
    {"DC codes", 1, m_dc_codes, NULL, VV_ERR_FORMAT, "DC Huffman table has"},
    {"DC symbols cut", 1, m_dc_symbols_short, NULL, VV_ERR_FORMAT, "DC Huffman table truncated"},
    {"DC symbol range", 1, m_dc_symbol_range, NULL, VV_ERR_FORMAT,
     "DC Huffman symbol 64 out of range"},
    {"DC symbol", 1, m_dc_symbol_invalid, NULL, VV_ERR_FORMAT, "DC Huffman symbol 41 is not valid"},
    {"stray bytes", 1, m_stray, NULL, VV_ERR_FORMAT, "2 stray bytes after the Huffman tables"},
    {"context table", 2, m_ctx_size, NULL, VV_ERR_FORMAT, "context table of"},
    {"reconstruction count", 2, m_recon_count, NULL, VV_ERR_FORMAT, "reconstruction offsets"},
    {"reconstruction value", 2, m_recon_value, NULL, VV_ERR_FORMAT,
     "reconstruction offset 0 is 0.75"},
    {"contexts inflate", 2, m_inflate, NULL, VV_ERR_FORMAT, "does not inflate"},
    {"data section", 1, NULL, a_data_short, VV_ERR_FORMAT, "data section of 2 bytes"},
    {"index size", 2, m_index_size, NULL, VV_ERR_FORMAT, "subcube index of"},
    {"index CRC", 1, NULL, a_index_crc, VV_ERR_FORMAT, "subcube index CRC-32"},
    {"offset order", 2, m_offset_order, NULL, VV_ERR_FORMAT, "subcube 0: offset 1 out of order"},
    {"data CRC", 2, NULL, a_data_crc, VV_ERR_FORMAT, "data CRC-32 mismatch"},
};

static void
test_vvc_refusals(void **state) {
    (void)state;
    vvc_parts ref[2];
    vvc_split(1, &ref[0]);
    vvc_split(2, &ref[1]);
    /* the parts put together again are the file (the harness is sound) */
    for (int k = 0; k < 2; k++) {
        vvc_parts p = ref[k];
        size_t n;
        unsigned char *b = vvc_join(&p, &n);
        vv_vvc *c = NULL;
        vt_ok(vv_vvc_from_memory(&c, b, n, "good.vvc"));
        vv_vvc_free(c);
        free(b);
    }
    for (size_t i = 0; i < sizeof vvc_cases / sizeof vvc_cases[0]; i++) {
        const vvc_case *tc = &vvc_cases[i];
        const vvc_parts *r = &ref[tc->version - 1];
        vvc_parts p = *r;
        p.t = dup_bytes(r->t, r->tn);
        p.x = dup_bytes(r->x, r->xn);
        p.d = dup_bytes(r->d, r->dn);
        if (tc->mutate)
            tc->mutate(&p);
        size_t n;
        unsigned char *b = vvc_join(&p, &n);
        if (tc->after)
            n = tc->after(b, n);
        char name[96];
        snprintf(name, sizeof name, "case%02zu.vvc", i);
        vv_vvc *c = NULL;
        vv_error_clear();
        expect_refusal(vv_vvc_from_memory(&c, b, n, name), tc->status, tc->needle, name, tc->what);
        assert_null(c);
        /* the same bytes from a file: the path named */
        if (i % 5 == 0) {
            const char *path = vt_path(outdir(), name);
            vt_write_file(path, b, n);
            vv_error_clear();
            expect_refusal(vv_vvc_load(&c, path), tc->status, tc->needle, name, tc->what);
            assert_null(c);
        }
        free(b);
        vvc_parts_free(&p);
    }
    vvc_parts_free(&ref[0]);
    vvc_parts_free(&ref[1]);
}

static void
test_vvc_io(void **state) {
    (void)state;
    vv_vvc *c = NULL;
    /* a size over the limit is refused before the bytes are touched */
    const unsigned char one = 0;
    expect_refusal(vv_vvc_from_memory(&c, &one, (size_t)VVC_MAX_FILE + 1, "big.vvc"), VV_ERR_LIMIT,
                   "is over the limit", "big.vvc", "size limit");
    assert_null(c);
    expect_refusal(vv_vvc_from_memory(&c, &one, 1, NULL), VV_ERR_FORMAT, "bad magic", "(memory)",
                   "no name");
    /* a missing file */
    expect_refusal(vv_vvc_load(&c, vt_path(outdir(), "missing.vvc")), VV_ERR_IO, NULL,
                   "missing.vvc", "missing file");
    assert_null(c);
    /* a file larger than the memory budget is not read (a sparse file of
     * 16 MiB under a budget of 1 MiB), a large file without the magic neither */
    const char *big = vt_path(outdir(), "big.vvc");
    vt_write_file(big, VVC_MAGIC, 8);
    assert_int_equal(truncate(big, 16 << 20), 0);
    vv_memory_budget_set(1 << 20);
    expect_refusal(vv_vvc_load(&c, big), VV_ERR_LIMIT, "memory budget", "big.vvc", "budget");
    assert_null(c);
    unsigned char *bytes = calloc(1, 2 << 20);
    assert_non_null(bytes);
    memcpy(bytes, VVC_MAGIC, 8);
    expect_refusal(vv_vvc_from_memory(&c, bytes, 2 << 20, "copy.vvc"), VV_ERR_LIMIT,
                   "memory budget", "copy.vvc", "budget copy");
    free(bytes);
    vv_memory_budget_set(0);
    vt_write_file(big, "NOTAVVC!", 8);
    assert_int_equal(truncate(big, 16 << 20), 0);
    expect_refusal(vv_vvc_load(&c, big), VV_ERR_FORMAT, "bad magic number", "big.vvc", "magic");
    assert_null(c);
    unlink(big);
    /* saving into a folder that is not there */
    vv_volume *v = ramp_volume(9, 9, 9, VV_U8);
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    vt_ok(vv_vvc_compress(&c, v, &p));
    vv_volume_free(v);
    expect_refusal(vv_vvc_save(c, vt_path(outdir(), "no/such/folder/x.vvc")), VV_ERR_IO, "vvc",
                   "x.vvc", "save");
    vv_vvc_free(c);
}

/* ======================================================================== */
/* .vvb                                                                      */

/* Field offsets of the header (vvb_layout.h). */
#define H_HSIZE 8
#define H_DIMS 16
#define H_TYPE 28
#define H_COARSE 32
#define H_SPACING 48
#define H_ORIGIN 72
#define H_UNIT 36
#define H_SPACE 40
#define H_DIRECTION 96
#define H_RANGE 168
#define H_INDEX 184
#define H_COUNT 192
#define H_CODEC 200
#define H_LEVELS 204
#define H_TABLE 208

enum { K_RAW, K_COARSE, K_ZSTD, K_LEVELS, K_KINDS };
static const unsigned kind_flags[K_KINDS] = {0, VV_VVB_COARSE, VV_VVB_ZSTD,
                                             VV_VVB_ZSTD | VV_VVB_LEVELS};
static const char *const kind_names[K_KINDS] = {"raw", "coarse", "zstd", "levels"};

/* A noisy volume of 70 x 20 x 10 u16 (two bricks along x, a level 1 of
 * 35 x 10 x 5), written as kind @p k; the file's bytes in *@p n. */
static unsigned char *
vvb_bytes(int k, size_t *n) {
    const char *path = vt_path(outdir(), kind_names[k]);
    char full[512];
    snprintf(full, sizeof full, "%s.vvb", path);
    const int dims[3] = {70, 20, 10};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U16));
    uint64_t s = 99;
    uint16_t *d = v->data;
    for (size_t i = 0; i < 70 * 20 * 10; i++)
        d[i] = (uint16_t)vt_rnd(&s, 0, 60000);
    vv_volume_update_range(v);
    vt_ok(vt_save(v, full, VV_FORMAT_VVB, -1, kind_flags[k]));
    vv_volume_free(v);
    return vt_read_file(full, n);
}

/* A zstd frame of @p content bytes declared (@p declare: 0 none, else 4
 * bytes of size @p declared) holding one raw block of @p content bytes;
 * its length. */
static size_t
zstd_frame(unsigned char *f, int declare, uint32_t declared, uint32_t content) {
    size_t o = 0;
    put32(f, 0xFD2FB528u);
    o = 4;
    if (declare) {
        f[o++] = 0xA0; /* single segment, 4-byte content size */
        put32(f + o, declared);
        o += 4;
    } else {
        f[o++] = 0x00; /* no content size: a window descriptor follows */
        f[o++] = 0x00;
    }
    const uint32_t bh = content << 3 | 1; /* last block, raw */
    f[o++] = (unsigned char)bh;
    f[o++] = (unsigned char)(bh >> 8);
    f[o++] = (unsigned char)(bh >> 16);
    memset(f + o, 7, content);
    return o + content;
}

typedef struct vvb_case {
    const char *what;
    int kind;
    void (*mutate)(unsigned char *b, size_t *n);
    vv_status status;
    const char *needle;
    int bricks_only; /* refused when read, not when opened: vv_volume_load only */
} vvb_case;

static unsigned char *
rec(unsigned char *b, int brick) {
    return b + get64(b + H_INDEX) + (uint64_t)brick * VVB_RECORD;
}
static unsigned char *
level_rec(unsigned char *b) {
    return b + get64(b + H_TABLE);
}
static unsigned char *
chunk_rec(unsigned char *b) {
    return b + get64(level_rec(b) + 16);
}

static void
v_short(unsigned char *b, size_t *n) {
    (void)b;
    *n = 100;
}
static void
v_hsize(unsigned char *b, size_t *n) {
    (void)n;
    put32(b + H_HSIZE, 100);
}
static void
v_type(unsigned char *b, size_t *n) {
    (void)n;
    put32(b + H_TYPE, 99);
}
static void
v_dims(unsigned char *b, size_t *n) {
    (void)n;
    put32(b + H_DIMS + 4, 0);
}
static void
v_codec(unsigned char *b, size_t *n) {
    (void)n;
    put32(b + H_CODEC, 5);
}
static void
v_zstd_no_coarse(unsigned char *b, size_t *n) {
    (void)n;
    put32(b + H_COARSE, 0);
}
static void
v_spacing0(unsigned char *b, size_t *n) {
    (void)n;
    putf64(b + H_SPACING + 8, 0.0);
}
static void
v_spacing_nan(unsigned char *b, size_t *n) {
    (void)n;
    putf64(b + H_SPACING + 16, NAN);
}
static void
v_origin_inf(unsigned char *b, size_t *n) {
    (void)n;
    putf64(b + H_ORIGIN, -INFINITY);
}
static void
v_direction(unsigned char *b, size_t *n) {
    (void)n;
    putf64(b + H_DIRECTION + 8 * 4, INFINITY);
}
static void
v_range(unsigned char *b, size_t *n) {
    (void)n;
    putf64(b + H_RANGE, 10.0);
    putf64(b + H_RANGE + 8, 1.0);
}
static void
v_count(unsigned char *b, size_t *n) {
    (void)n;
    put64(b + H_COUNT, 3);
}
static void
v_index_off(unsigned char *b, size_t *n) {
    put64(b + H_INDEX, (uint64_t)*n - 10);
}
static void
v_brick_bytes(unsigned char *b, size_t *n) {
    (void)n;
    put64(rec(b, 1) + 8, get64(rec(b, 1) + 8) - 2);
}
static void
v_brick_offset(unsigned char *b, size_t *n) {
    put64(rec(b, 0), (uint64_t)*n - 8);
}
static void
v_brick_zero(unsigned char *b, size_t *n) {
    (void)n;
    put64(rec(b, 0) + 8, 0);
}
static void
v_coarse_bytes(unsigned char *b, size_t *n) {
    (void)n;
    put64(rec(b, 0) + 40, 3);
}
static void
v_coarse_offset(unsigned char *b, size_t *n) {
    put64(rec(b, 1) + 32, (uint64_t)*n - 4);
}
static void
v_brick_minmax(unsigned char *b, size_t *n) {
    (void)n;
    putf64(rec(b, 0) + 16, 5.0);
    putf64(rec(b, 0) + 24, 1.0);
}
static void
v_levels(unsigned char *b, size_t *n) {
    (void)n;
    put32(b + H_LEVELS, 5);
}
static void
v_table_off(unsigned char *b, size_t *n) {
    put64(b + H_TABLE, (uint64_t)*n - 16);
}
static void
v_level_dims(unsigned char *b, size_t *n) {
    (void)n;
    put32(level_rec(b), 99);
}
static void
v_level_index(unsigned char *b, size_t *n) {
    put64(level_rec(b) + 16, (uint64_t)*n);
}
static void
v_chunk_bytes(unsigned char *b, size_t *n) {
    (void)n;
    put64(chunk_rec(b) + 8, 0);
}
static void
v_chunk_minmax(unsigned char *b, size_t *n) {
    (void)n;
    putf64(chunk_rec(b) + 16, NAN);
}
static void
v_frame_magic(unsigned char *b, size_t *n) {
    (void)n;
    memset(b + get64(rec(b, 0)), 0, 4);
}
static void
v_frame_unknown(unsigned char *b, size_t *n) {
    (void)n;
    zstd_frame(b + get64(rec(b, 0)), 0, 0, 10);
}
static void
v_frame_size(unsigned char *b, size_t *n) {
    (void)n;
    zstd_frame(b + get64(rec(b, 0)), 1, 10, 10);
}
static void
v_frame_short(unsigned char *b, size_t *n) {
    (void)n;
    /* the size its box needs declared, 10 bytes held */
    const uint32_t want = 66 * 20 * 10 * 2;
    zstd_frame(b + get64(rec(b, 0)), 1, want, 10);
}

static const vvb_case vvb_cases[] = {
    {"file cut", K_RAW, v_short, VV_ERR_FORMAT, "shorter than the header", 0},
    {"header size", K_RAW, v_hsize, VV_ERR_FORMAT, "header size 100, brick side 64", 0},
    {"voxel type", K_COARSE, v_type, VV_ERR_FORMAT, "voxel type 99", 0},
    {"dims", K_RAW, v_dims, VV_ERR_LIMIT, "axis 1 is outside", 0},
    {"codec", K_RAW, v_codec, VV_ERR_FORMAT, "unknown brick codec 5", 0},
    {"zstd without coarse", K_ZSTD, v_zstd_no_coarse, VV_ERR_FORMAT, "without coarse levels", 0},
    {"spacing 0", K_RAW, v_spacing0, VV_ERR_FORMAT, "bad spacing or origin on axis 1", 0},
    {"spacing NaN", K_ZSTD, v_spacing_nan, VV_ERR_FORMAT, "bad spacing or origin on axis 2", 0},
    {"origin inf", K_RAW, v_origin_inf, VV_ERR_FORMAT, "bad spacing or origin on axis 0", 0},
    {"direction", K_COARSE, v_direction, VV_ERR_FORMAT, "direction matrix entry 4 is inf", 0},
    {"range", K_RAW, v_range, VV_ERR_FORMAT, "bad value range 10..1", 0},
    {"brick count", K_RAW, v_count, VV_ERR_FORMAT, "index of 3 bricks", 0},
    {"index offset", K_COARSE, v_index_off, VV_ERR_FORMAT, "runs past the end of the file", 0},
    {"brick bytes", K_RAW, v_brick_bytes, VV_ERR_FORMAT, "index: brick 1 (1,0,0) has", 0},
    {"brick offset", K_RAW, v_brick_offset, VV_ERR_FORMAT, "run past the end of the file", 0},
    {"zstd brick of 0 bytes", K_ZSTD, v_brick_zero, VV_ERR_FORMAT, "needs compressed 1 to", 0},
    {"coarse bytes", K_COARSE, v_coarse_bytes, VV_ERR_FORMAT, "brick 0: coarse level of 3 bytes",
     0},
    {"coarse offset", K_ZSTD, v_coarse_offset, VV_ERR_FORMAT, "brick 1: coarse level of", 0},
    {"brick min > max", K_RAW, v_brick_minmax, VV_ERR_FORMAT, "brick 0: min 5 > max 1", 0},
    {"level count", K_LEVELS, v_levels, VV_ERR_FORMAT, "5 pyramid levels; 70x20x10 voxels make 2",
     0},
    {"level table", K_LEVELS, v_table_off, VV_ERR_FORMAT, "level table of 32 bytes", 0},
    {"level dims", K_LEVELS, v_level_dims, VV_ERR_FORMAT, "level 1: 99x10x5 voxels", 0},
    {"level index", K_LEVELS, v_level_index, VV_ERR_FORMAT, "level 1: index of 32 bytes", 0},
    {"chunk bytes", K_LEVELS, v_chunk_bytes, VV_ERR_FORMAT, "level 1: chunk 0 has 0 bytes", 0},
    {"chunk range", K_LEVELS, v_chunk_minmax, VV_ERR_FORMAT, "level 1: chunk 0: min nan", 0},
    {"zstd magic", K_ZSTD, v_frame_magic, VV_ERR_FORMAT, "are not a zstd frame", 1},
    {"zstd no size", K_ZSTD, v_frame_unknown, VV_ERR_FORMAT, "does not give its size", 1},
    {"zstd size", K_ZSTD, v_frame_size, VV_ERR_FORMAT, "holds 10 bytes; its box needs 26400", 1},
    {"zstd short", K_ZSTD, v_frame_short, VV_ERR_FORMAT, "the zstd frame of", 1},
};

static void
test_vvb_refusals(void **state) {
    (void)state;
    unsigned char *ref[K_KINDS];
    size_t refn[K_KINDS];
    for (int k = 0; k < K_KINDS; k++)
        ref[k] = vvb_bytes(k, &refn[k]);
    for (size_t i = 0; i < sizeof vvb_cases / sizeof vvb_cases[0]; i++) {
        const vvb_case *tc = &vvb_cases[i];
        size_t n = refn[tc->kind];
        unsigned char *b = dup_bytes(ref[tc->kind], n);
        tc->mutate(b, &n);
        char name[64];
        snprintf(name, sizeof name, "bad%02zu.vvb", i);
        const char *path = vt_path(outdir(), name);
        vt_write_file(path, b, n);
        free(b);
        /* read whole */
        vv_volume *v = NULL;
        vv_error_clear();
        expect_refusal(vv_volume_load(&v, path, NULL), tc->status, tc->needle, name, tc->what);
        assert_null(v);
        /* by bricks: refused when opened, or when the brick is read */
        vv_bricked *bk = NULL;
        vv_error_clear();
        vv_status s = vv_bricked_open(&bk, path, NULL, vt_cache(0));
        if (tc->bricks_only) {
            vt_ok(s);
            vv_volume *brick = NULL;
            vv_error_clear();
            expect_refusal(vv_bricked_load(bk, 0, &brick), tc->status, tc->needle, name, tc->what);
            assert_null(brick);
            const int lo[3] = {0, 0, 0}, hi[3] = {3, 3, 3};
            vv_error_clear();
            expect_refusal(vv_bricked_read_box(bk, lo, hi, &brick), tc->status, tc->needle, name,
                           tc->what);
            assert_null(brick);
            vv_bricked_free(bk);
        } else {
            expect_refusal(s, tc->status, tc->needle, name, tc->what);
            assert_null(bk);
        }
    }
    for (int k = 0; k < K_KINDS; k++)
        free(ref[k]);
}

/* Not a .vvb though named one; missing; a folder; the store's channel and
 * level; bricks over the budget, a box outside, a brick that is not there,
 * a file cut while open; raw layouts. */
static void
test_vvb_open(void **state) {
    (void)state;
    vv_bricked *bk = NULL;
    unsigned char junk[300];
    memset(junk, 'x', sizeof junk);
    const char *path = vt_path(outdir(), "junk.vvb");
    vt_write_file(path, junk, sizeof junk);
    expect_refusal(vv_bricked_open(&bk, path, NULL, vt_cache(0)), VV_ERR_FORMAT,
                   "not a .vvb file (no \"VOLVISB1\" magic)", "junk.vvb", "magic");
    assert_null(bk);
    expect_refusal(vv_bricked_open(&bk, vt_path(outdir(), "none.vvb"), NULL, vt_cache(0)),
                   VV_ERR_IO, "No such file", "none.vvb", "missing");
    /* a folder: pread fails (EISDIR) or it is shorter than a header */
    const char *dir = vt_path(outdir(), "folder.vvb");
    mkdir(dir, 0755);
    vv_error_clear();
    vv_status s = vv_bricked_open(&bk, dir, NULL, vt_cache(0));
    assert_true(s == VV_ERR_IO || s == VV_ERR_FORMAT);
    expect_refusal(s, s, s == VV_ERR_IO ? "Is a directory" : "shorter than the header",
                   "folder.vvb", "folder");

    size_t n;
    unsigned char *good = vvb_bytes(K_RAW, &n);
    path = vt_path(outdir(), "good.vvb");
    vt_write_file(path, good, n);
    vv_load_options lo;
    vv_load_options_init(&lo);
    lo.channel = 1;
    vv_volume *v = NULL;
    expect_refusal(vv_volume_load(&v, path, &lo), VV_ERR_INVALID, "holds one channel", NULL,
                   "channel");
    vv_load_options_init(&lo);
    lo.level = 3;
    expect_refusal(vv_volume_load(&v, path, &lo), VV_ERR_INVALID, "level 3 asked, the file has 1",
                   "good.vvb", "level");
    assert_null(v);
    /* a budget smaller than one brick */
    expect_refusal(vv_bricked_open(&bk, path, NULL, vt_cache(4096)), VV_ERR_LIMIT,
                   "memory limit of 4096 bytes is smaller than one brick", "good.vvb", "budget");
    assert_null(bk);
    vt_ok(vv_bricked_open(&bk, path, NULL, vt_cache(0)));
    vv_volume *brick = NULL;
    expect_refusal(vv_bricked_load(bk, 2, &brick), VV_ERR_INVALID, "no brick 2", NULL, "index");
    expect_refusal(vv_bricked_load(bk, -1, &brick), VV_ERR_INVALID, "no brick -1", NULL, "index");
    const int lo3[3] = {0, 0, 0}, hi3[3] = {70, 1, 1};
    expect_refusal(vv_bricked_read_box(bk, lo3, hi3, &brick), VV_ERR_INVALID,
                   "box 0..70 outside 0..69 on axis 0", NULL, "box");
    assert_null(brick);
    /* the file cut short while open: the brick's read says where it ends */
    assert_int_equal(truncate(path, 400), 0);
    expect_refusal(vv_bricked_load(bk, 0, &brick), VV_ERR_FORMAT, "the file ends at byte 400",
                   "good.vvb", "cut while open");
    assert_null(brick);
    vv_bricked_free(bk);
    free(good);

    /* a unit and a space past their enumerations are unknown (optional metadata) */
    good = vvb_bytes(K_RAW, &n);
    put32(good + H_UNIT, 999);
    put32(good + H_SPACE, 7);
    path = vt_path(outdir(), "unit.vvb");
    vt_write_file(path, good, n);
    free(good);
    vt_ok(vv_volume_load(&v, path, NULL));
    assert_int_equal(v->unit, VV_UNIT_UNKNOWN);
    assert_int_equal(v->space, VV_SPACE_UNKNOWN);
    vv_volume_free(v);
    vt_ok(vv_bricked_open(&bk, path, NULL, vt_cache(0)));
    assert_int_equal(vv_bricked_header(bk)->unit, VV_UNIT_UNKNOWN);
    vv_bricked_free(bk);

    /* a raw layout past its file's end; a file no brick reader reads */
    unsigned char raw[1000];
    memset(raw, 1, sizeof raw);
    path = vt_path(outdir(), "short.raw");
    vt_write_file(path, raw, sizeof raw);
    vv_raw_params rp;
    vv_raw_params_init(&rp);
    rp.dims[0] = rp.dims[1] = rp.dims[2] = 10;
    rp.type = VV_U8;
    rp.header_skip = 24;
    expect_refusal(vv_bricked_open(&bk, path, &rp, vt_cache(0)), VV_ERR_FORMAT,
                   "1000 bytes of voxels from offset 24 run past the end of the file (1000 bytes)",
                   "short.raw", "raw layout");
    assert_null(bk);
    /* the scan of a raw layout reads a slice at a time: a slice over the
     * memory budget is refused, not allocated (a sparse file of 32 MiB) */
    path = vt_path(outdir(), "wide.raw");
    vt_write_file(path, raw, 1);
    assert_int_equal(truncate(path, 4096 * 4096 * 2), 0);
    rp.dims[0] = rp.dims[1] = 4096;
    rp.dims[2] = 2;
    rp.header_skip = 0;
    vv_memory_budget_set(1 << 20);
    expect_refusal(vv_bricked_open(&bk, path, &rp, vt_cache(0)), VV_ERR_LIMIT, "memory budget",
                   "wide.raw", "slice");
    vv_memory_budget_set(0);
    assert_null(bk);
    unlink(path);
    path = vt_path(outdir(), "notes.txt");
    vt_write_file(path, "hello\n", 6);
    vv_error_clear();
    s = vv_bricked_open(&bk, path, NULL, vt_cache(0));
    assert_int_not_equal(s, VV_OK);
    expect_refusal(s, s, "bricks: notes.txt", "notes.txt", "not bricks");
    assert_null(bk);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vvc_refusals),
        cmocka_unit_test(test_vvc_io),
        cmocka_unit_test(test_vvb_refusals),
        cmocka_unit_test(test_vvb_open),
    };
    return vt_run_tests(tests, NULL, NULL);
}
