/* Canonical Huffman codes as in baseline JPEG (ITU T.81, Annex C and K.2),
 * and a bit reader and writer for the .vvc codec (internal). */
#ifndef VV_COMPRESS_HUFFMAN_H
#define VV_COMPRESS_HUFFMAN_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/core.h"

#define VV_HUFF_MAX_LEN 16    /* longest code, as in JPEG */
#define VV_HUFF_MAX_SYMS 1024 /* symbols are < 1024 */

/** A table as stored: counts of codes of each length 1..16 and the symbols in code order. */
typedef struct vv_huff_table {
    uint8_t bits[VV_HUFF_MAX_LEN + 1]; /* bits[l] codes of length l (bits[0] unused) */
    uint16_t vals[VV_HUFF_MAX_SYMS];
    int nvals;
} vv_huff_table;

/** Encoder view: code and length of every symbol (length 0: symbol absent). */
typedef struct vv_huff_enc {
    uint32_t code[VV_HUFF_MAX_SYMS];
    uint8_t len[VV_HUFF_MAX_SYMS];
} vv_huff_enc;

#define VV_HUFF_LOOK 9 /* bits decoded by one table lookup */

/** Decoder view (Annex F.2.2.3), with a lookup table for codes of up to 9 bits. */
typedef struct vv_huff_dec {
    uint16_t look[1 << VV_HUFF_LOOK]; /* symbol + 1024 * length, or 0: longer code */
    int32_t mincode[VV_HUFF_MAX_LEN + 1];
    int32_t maxcode[VV_HUFF_MAX_LEN + 2]; /* -1: no code of that length */
    int valptr[VV_HUFF_MAX_LEN + 1];
    uint16_t vals[VV_HUFF_MAX_SYMS];
} vv_huff_dec;

/**
 * Optimal code lengths limited to 16 bits for @p nsym symbols with the given
 * frequencies (Annex K.2, with one reserved code point so that no code is
 * all ones). Symbols with frequency 0 get no code.
 */
void vv_huff_build(const uint64_t *freq, int nsym, vv_huff_table *t);

/** Canonical codes of a table. Returns VV_ERR_FORMAT if the table over-fills the code space. */
vv_status vv_huff_make_enc(const vv_huff_table *t, vv_huff_enc *e);

/** Decoder tables. Returns VV_ERR_FORMAT if the table over-fills the code space. */
vv_status vv_huff_make_dec(const vv_huff_table *t, vv_huff_dec *d);

/** Appends bits to a growing buffer. */
typedef struct vv_bitwriter {
    uint8_t *buf;
    size_t len, cap;
    uint64_t acc;
    int nacc;
    int failed; /* an allocation failed */
} vv_bitwriter;

void vv_bw_put(vv_bitwriter *w, uint32_t bits, int n); /* n <= 32 */
/** Pads the last byte with 1 bits (as JPEG). */
void vv_bw_flush(vv_bitwriter *w);

/** Reads bits from [p, end); reading past the end sets `overrun`. */
typedef struct vv_bitreader {
    const uint8_t *p, *end;
    uint64_t acc;
    int nacc;
    int overrun; /* zero bytes fed past the end */
} vv_bitreader;

/** Next @p n bits (n <= 32), MSB first. Past the end, zeros and overrun = 1. */
uint32_t vv_br_get(vv_bitreader *r, int n);

/** 1 when bits past the end were consumed. */
int vv_br_overrun(const vv_bitreader *r);

/** Decodes one symbol; -1 for an invalid code or an overrun. */
int vv_huff_decode(vv_bitreader *r, const vv_huff_dec *d);

#endif
