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
#define VVC_HEADER_BYTES 244
#define VVC_MAX_SIZE 40 /* largest amplitude size category accepted */
#define VVC_DC_SYMS 64
#define VVC_AC_SYMS 1024
#define VVC_EOB 0
#define VVC_ZRL (15 * 64)
#define VVC_MAX_FILE (((uint64_t)64) << 30)

/* FFTW's planner is not thread-safe: every plan is made and destroyed under this lock. */
void vv_fftw_lock(void);
void vv_fftw_unlock(void);

/**
 * The r2c spectrum of every M^3 subcube of @p v, coded values
 * (value - offset) / unit with the padding at 0 (i.e. the minimum), in
 * FFTW's layout (see vv_vvc_decode_spectrum), subcubes in index order:
 * n * 2 * M * M * (M/2 + 1) floats (fftwf_malloc'ed; free with fftwf_free).
 * No quantisation: this is what a .vvc codes before its quantiser.
 */
vv_status vv_vvc_spectra(const vv_volume *v, int M, int threads, float **spectra, double *offset,
                         double *unit, const vv_progress *progress);

/** The coded-value offset and unit of @p v (see compress.h). */
void vv_vvc_value_scale(const vv_volume *v, double *offset, double *unit);

/* ---- the scan and the quantiser (vvc_quant.c) ---------------------------- */

/** The M^3 independent real numbers of the r2c spectrum, by increasing frequency. */
typedef struct vvc_scan {
    int M, H, N;     /* side, M/2 + 1, M^3 */
    int32_t *entry;  /* N: 2 * complex index + part (0 re, 1 im) */
    int32_t *fold;   /* N: folded-frequency table index (fz * H + fy) * H + fx */
    int32_t *mirror; /* nmirror pairs (from, to): Hermitian duplicates to fill */
    int nmirror;
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

/* ---- the object ------------------------------------------------------------ */

struct vv_vvc {
    unsigned char *bytes;
    size_t size;
    vv_vvc_info info;
    int M, nsub;
    vvc_scan scan;
    float *qtab;     /* (M/2+1)^3 unitary steps, as stored */
    float *step_abs; /* N: steps of the unnormalised coefficients in scan order */
    vv_huff_table dct, act;
    vv_huff_dec dc, ac;
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

/* ---- the file (vvc_format.c) ---------------------------------------------- */

/** CRC-32 of n bytes (zlib). */
uint32_t vvc_crc(const unsigned char *p, uint64_t n);

/** Bytes of the tables section for these Huffman tables. */
size_t vvc_tables_bytes(int M, const vv_huff_table *dc, const vv_huff_table *ac);

/**
 * Writes a whole file (header, tables, index, data, CRCs) into a new
 * malloc'ed buffer: @p t holds the DC and AC tables, @p streams the nsub
 * flushed subcube bit streams. Errors: VV_ERR_NOMEM.
 */
vv_status vvc_write_file(const vv_volume *v, int M, double quality, double slope, double offset,
                         double unit, const float *qtab, const vv_huff_table *t,
                         const vv_bitwriter *streams, int nsub, unsigned char **bytes,
                         size_t *size);

/** Parses and checks c->bytes (c->size) into the rest of @p c. Errors: VV_ERR_FORMAT, ... */
vv_status vvc_parse(vv_vvc *c, const char *name);

#endif
