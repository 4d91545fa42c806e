/*
 * Internal interface of the .vvc codec (include/volvis/compress.h), shared
 * by its files and with the `fourier` renderer:
 *   vvc_quant.c      the scan (3-D zig-zag), quantisation table, quantiser
 *   vvc_transform.c  the forward subcube DFT (FFTW) and FFTW's planner lock
 *   vvc_entropy.c    JPEG-style run-length + Huffman coding of a subcube
 *   vvc_encode.c     statistics, rate search, vv_vvc_compress
 *   vvc_format.c     header, tables, index, CRCs: writing, parsing, I/O
 *   vvc_decode.c     one subcube's spectrum or values, the whole volume
 *   huffman.c        canonical Huffman codes, bit reader and writer
 */
#ifndef VV_COMPRESS_VVC_INTERNAL_H
#define VV_COMPRESS_VVC_INTERNAL_H

#include <fftw3.h>

#include "compress/huffman.h"
#include "volvis/compress.h"

#define VVC_MAGIC "\x89VVC\r\n\x1a\n"
#define VVC_HEADER_BYTES 244    /* version 1 */
#define VVC_HEADER_BYTES_V2 264 /* version 2: + max error, correction step, CRC */
#define VVC_MAX_SIZE 40         /* largest amplitude size category accepted */
#define VVC_DC_SYMS 64
#define VVC_AC_SYMS 1024
#define VVC_EOB 0
#define VVC_ZRL (15 * 64)
#define VVC_MAX_FILE (((uint64_t)64) << 30)

/** The coded-value offset and unit of @p v (see compress.h). */
void vv_vvc_value_scale(const vv_volume *v, double *offset, double *unit);

/* ---- the scan and the quantiser (vvc_quant.c) ---------------------------- */

#define VVC_NBR 4 /* context neighbours: three lower in frequency, the real part */

/** The M^3 independent real numbers of the r2c spectrum, by increasing frequency. */
typedef struct vvc_scan {
    int M, H, N;     /* side, M/2 + 1, M^3 */
    int32_t *entry;  /* N: 2 * complex index + part (0 re, 1 im) */
    int32_t *fold;   /* N: folded-frequency table index (fz * H + fy) * H + fx */
    int32_t *mirror; /* nmirror pairs (from, to): Hermitian duplicates to fill */
    int nmirror;
    int nb;            /* frequency bands: fx + fy + fz in 0 .. 3 M/2 */
    uint8_t *band;     /* N: band of each scan position (non-decreasing) */
    int32_t *nbr;      /* VVC_NBR N: scan positions of the context neighbours (none: N, so
                          arrays of quantised numbers hold N + 1 entries, the last 0) */
    int32_t *band_end; /* nb + 1: first scan position past band b */
} vvc_scan;

/** Builds the scan of side @p M. Errors: VV_ERR_NOMEM. */
vv_status vvc_scan_init(vvc_scan *s, int M);
void vvc_scan_free(vvc_scan *s);

/** Steps of the unitary coefficients per folded frequency, (M/2+1)^3 entries. */
void vvc_make_table(float *tab, int M, double quality, double slope);

/** Steps of the unnormalised coefficients in scan order (N entries) from the table. */
void vvc_make_step_abs(const vvc_scan *sc, const float *qtab, float *step_abs);

/** Rounds one subcube's spectrum (N numbers in scan order) divided by its steps to integers. */
void vvc_quantise(const vvc_scan *sc, const float *sp, const double *inv_step, int64_t *q);

/* ---- version 2 context modelling (vvc_context.c, rangecoder.h) ------------ */

#define VVC2_ACT 6        /* activity classes of a coefficient's lower neighbours */
#define VVC2_LC 4         /* classes of a band's position below the subcube's last band */
#define VVC2_EG_GROUPS 4  /* band groups of the Exp-Golomb prefix contexts */
#define VVC2_EG_CTX 24    /* prefix contexts per group */
#define VVC2_EG_MAX 44    /* longest Exp-Golomb prefix accepted */
#define VVC2_MAX_CTX 4096 /* more contexts than any block side needs */

/** Offsets of the context groups in the probability table. */
typedef struct vvc2_model {
    int nb, nctx;
    int o_last, o_sig, o_g1, o_g2, o_eg, o_corr;
} vvc2_model;

/** One voxel correction of the error-bound mode: value += k * corr_step at pos (in the subcube). */
typedef struct vvc_corr {
    int pos;
    int64_t k;
} vvc_corr;

struct vv_rc_enc;
struct vv_rc_dec;

void vvc2_model_init(vvc2_model *m, int nb);
/** Adds one subcube's context bits to counts (2 per context) and its raw bits to *bypass. */
void vvc2_count_block(const vvc_scan *sc, const vvc2_model *m, const int64_t *q, uint64_t *counts,
                      uint64_t *bypass);
void vvc2_encode_block(const vvc_scan *sc, const vvc2_model *m, const int64_t *q,
                       const uint16_t *p0, struct vv_rc_enc *e);
/** Decodes one subcube's N integers; -1: the stream does not decode. */
int vvc2_decode_block(const vvc_scan *sc, const vvc2_model *m, const uint16_t *p0,
                      struct vv_rc_dec *d, int64_t *q);
/** Counts (counts != NULL) or codes (with p0, e) n corrections, positions increasing. */
void vvc2_code_corrections(const vvc2_model *m, const vvc_corr *cr, int n, uint64_t *counts,
                           uint64_t *bypass, const uint16_t *p0, struct vv_rc_enc *e);
/** Decodes the corrections of a subcube of nvox voxels (malloc'ed list); -1 bad, -2 no memory. */
int vvc2_decode_corrections(const vvc2_model *m, const uint16_t *p0, struct vv_rc_dec *d, int nvox,
                            vvc_corr **out, int *n);
/** cost[2 c + bit]: bits of coding bit in context c with these probabilities. */
void vvc2_costs(const vvc2_model *m, const uint16_t *p0, float *cost);
/**
 * Rate-distortion optimised quantisation of one subcube (N numbers in scan
 * order): each AC magnitude of the plain rounding is kept, lowered by one or
 * zeroed, whichever costs least in weight * (error / step)^2 + lambda * bits.
 */
void vvc2_rdoq_block(const vvc_scan *sc, const vvc2_model *m, const float *cost, const float *sp,
                     const double *inv_step, const float *weight, double lambda, int64_t *q);
/**
 * The probability of a 0 per context from the counts, as stored: one byte
 * per context (0: never used, probability 1/2; 1..255: the logistic
 * 4096 / (1 + exp(-(code - 128) / 18)), clamped to 1..4095), and the 12-bit
 * probability it stands for.
 */
void vvc2_probabilities(const vvc2_model *m, const uint64_t *counts, uint8_t *code, uint16_t *p0);
/** The 12-bit probability of a stored context byte. */
unsigned vvc2_prob_of_code(unsigned code);
/** Bits of coding the counted bits with these probabilities (raw bits included). */
double vvc2_cost_bits(const vvc2_model *m, const uint64_t *counts, const uint16_t *p0,
                      uint64_t bypass);

/** As vvc_quantise, AC magnitudes rounded up from fraction 1 - theta (version 2's dead zone). */
void vvc_quantise_dz(const vvc_scan *sc, const float *sp, const double *inv_step, double theta,
                     int64_t *q);

/* ---- the object ------------------------------------------------------------ */

struct vv_vvc {
    unsigned char *bytes;
    size_t size;
    vv_vvc_info info;
    int M, nsub;
    vvc_scan scan;
    float *qtab;            /* (M/2+1)^3 unitary steps, as stored */
    float *step_abs;        /* N: steps of the unnormalised coefficients in scan order */
    vv_huff_table dct, act; /* version 1 */
    vv_huff_dec dc, ac;
    vvc2_model model; /* version 2 */
    uint16_t *p0;     /* model.nctx probabilities */
    float *recon;     /* 2 nb reconstruction offsets (steps) by band and |q| = 1, > 1 */
    uint64_t data_start, data_len; /* bit streams (without the CRC) */
    uint64_t *offsets;             /* nsub + 1 */
    fftwf_plan c2r;                /* for vv_vvc_decode_subcube */
};

/* ---- entropy coding (vvc_entropy.c) ---------------------------------------- */

/* Where the JPEG symbol sequence of a subcube goes: symbol statistics
 * (dcf, acf, amp) or, with w, Huffman codes and amplitude bits. */
typedef struct sym_counter {
    uint64_t *dcf, *acf;
    uint64_t amp;                 /* amplitude bits */
    const vv_huff_enc *dce, *ace; /* codes, for writing */
    vv_bitwriter *w;              /* for writing, or NULL */
} sym_counter;

/** Turns one subcube's N integers (scan order) into symbols, counted or written by @p c. */
void vvc_symbolise(const int64_t *q, int N, sym_counter *c);

/** Entropy decoding of subcube @p index into N integers in scan order. Errors: VV_ERR_FORMAT. */
vv_status vvc_decode_ints(const vv_vvc *c, int index, int64_t *q);

/* ---- decoding (vvc_decode.c) -------------------------------------------- */

/** The r2c spectrum (FFTW layout, duplicates filled) of N integers in scan order. */
/** With @p recon (version 2; NULL: version 1) a nonzero q stands for (q + sign(q) * recon[2 band +
 * (|q| > 1)]) steps. */
void vvc_dequantise(const vvc_scan *sc, const float *step_abs, const float *recon, const int64_t *q,
                    float *spectrum);
/** Inverse DFT (c2r plan of side M, N = M^3) and value scaling; @p spectrum is destroyed. */
void vvc_values(fftwf_plan c2r, int N, double unit, double offset, float *spectrum, float *values);
/** values[pos] += k * corr_step for each correction. */
void vvc_apply_corrections(float *values, const vvc_corr *cr, int n, double corr_step);
/** Entropy decoding of subcube @p index (with its corrections when cr != NULL; free *cr). */
vv_status vvc_decode_q(const vv_vvc *c, int index, int64_t *q, vvc_corr **cr, int *ncr);

/* ---- the file (vvc_format.c) ---------------------------------------------- */

/** CRC-32 of n bytes (zlib). */
uint32_t vvc_crc(const unsigned char *p, uint64_t n);

/** Bytes of the tables section for these Huffman tables. */
size_t vvc_tables_bytes(int M, const vv_huff_table *dc, const vv_huff_table *ac);

/** Deflates the context bytes (malloc'ed *z, *zlen bytes). Errors: VV_ERR_NOMEM. */
vv_status vvc2_pack_codes(const vvc2_model *m, const uint8_t *code, uint8_t **z, size_t *zlen);
/** Bytes of the version 2 tables section with zlen bytes of deflated context bytes. */
size_t vvc2_tables_bytes(size_t zlen, int nb);

/** What the header and tables of a file hold. */
typedef struct vvc_file_desc {
    int version, M;
    double quality, slope, offset, unit;
    double max_error, corr_step; /* version 2 */
    const float *qtab;           /* (M/2+1)^3 unitary steps */
    const vv_huff_table *huff;   /* version 1: DC and AC tables */
    const vvc2_model *model;     /* version 2: the contexts, ... */
    const uint8_t *pz;           /* ... their deflated probability bytes */
    size_t pzlen;
    const float *recon; /* ... and 2 nb reconstruction offsets */
} vvc_file_desc;

/** The subcube bit streams of a file. */
typedef struct vvc_streams {
    int n;
    uint8_t **buf;
    size_t *len;
} vvc_streams;

/** Writes a whole file (header, tables, index, data, CRCs) into a new malloc'ed buffer. Errors:
 * VV_ERR_NOMEM. */
vv_status vvc_write_file(const vv_volume *v, const vvc_file_desc *fd, const vvc_streams *st,
                         unsigned char **bytes, size_t *size);

/** Parses and checks c->bytes (c->size) into the rest of @p c. Errors: VV_ERR_FORMAT, ... */
vv_status vvc_parse(vv_vvc *c, const char *name);

#endif
