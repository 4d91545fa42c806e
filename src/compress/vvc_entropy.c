/*
 * The .vvc entropy coding (format version 1), as in baseline JPEG: the DC
 * term by its size category, the rest as (zero run, size) symbols with EOB
 * and ZRL, canonical Huffman codes (huffman.c) followed by the amplitude
 * bits; one byte-aligned bit stream per subcube.
 */
#include <string.h>

#include "compress/vvc_internal.h"

static inline int
size_of(int64_t v) {
    uint64_t a = v < 0 ? (uint64_t)(-v) : (uint64_t)v;
    int n = 0;
    while (a) {
        n++;
        a >>= 1;
    }
    return n;
}

/* Amplitude bits of v in `size` bits (JPEG: negative values as v - 1 in two's complement). */
static inline uint64_t
amp_bits(int64_t v, int size) {
    return (uint64_t)(v < 0 ? v - 1 : v) & ((size >= 64 ? 0 : (1ull << size)) - 1);
}

static inline void
emit(sym_counter *c, int is_dc, int sym, int64_t v, int size) {
    if (c->w) {
        const vv_huff_enc *e = is_dc ? c->dce : c->ace;
        vv_bw_put(c->w, e->code[sym], e->len[sym]);
        if (size > 32) {
            uint64_t b = amp_bits(v, size);
            vv_bw_put(c->w, (uint32_t)(b >> 32), size - 32);
            vv_bw_put(c->w, (uint32_t)b, 32);
        } else if (size > 0) {
            vv_bw_put(c->w, (uint32_t)amp_bits(v, size), size);
        }
        return;
    }
    (is_dc ? c->dcf : c->acf)[sym]++;
    c->amp += (uint64_t)size;
}

void
vvc_symbolise(const int64_t *q, int N, sym_counter *c) {
    int s = size_of(q[0]);
    emit(c, 1, s, q[0], s);
    int run = 0;
    for (int k = 1; k < N; k++) {
        if (q[k] == 0) {
            run++;
            continue;
        }
        while (run > 15) {
            emit(c, 0, VVC_ZRL, 0, 0);
            run -= 16;
        }
        s = size_of(q[k]);
        emit(c, 0, run * 64 + s, q[k], s);
        run = 0;
    }
    if (run > 0)
        emit(c, 0, VVC_EOB, 0, 0);
}

/* ---------------------------------------------------------------------- */
/* Decoding                                                                 */

/* Entropy decoding of one subcube into N integers in scan order. */
vv_status
vvc_decode_ints(const vv_vvc *c, int index, int64_t *q) {
    const int N = c->scan.N;
    vv_bitreader r = {c->bytes + c->data_start + c->offsets[index],
                      c->bytes + c->data_start + c->offsets[index + 1], 0, 0, 0};
    memset(q, 0, sizeof *q * (size_t)N);
    int sym = vv_huff_decode(&r, &c->dc);
    if (sym < 0 || sym > VVC_MAX_SIZE)
        goto bad;
    int64_t v = 0;
    if (sym > 0) {
        uint64_t bits = sym > 32 ? ((uint64_t)vv_br_get(&r, sym - 32) << 32) | vv_br_get(&r, 32)
                                 : vv_br_get(&r, sym);
        v = (bits >> (sym - 1)) ? (int64_t)bits : (int64_t)bits - (int64_t)((1ull << sym) - 1);
    }
    q[0] = v;
    for (int k = 1; k < N;) {
        sym = vv_huff_decode(&r, &c->ac);
        if (sym < 0)
            goto bad;
        if (sym == VVC_EOB)
            break;
        const int run = sym >> 6, size = sym & 63;
        if (size == 0) {
            if (sym != VVC_ZRL)
                goto bad;
            k += 16;
            if (k >= N) /* a ZRL must be followed by a coefficient */
                goto bad;
            continue;
        }
        k += run;
        if (k >= N || size > VVC_MAX_SIZE)
            goto bad;
        uint64_t bits = size > 32 ? ((uint64_t)vv_br_get(&r, size - 32) << 32) | vv_br_get(&r, 32)
                                  : vv_br_get(&r, size);
        q[k] = (bits >> (size - 1)) ? (int64_t)bits : (int64_t)bits - (int64_t)((1ull << size) - 1);
        k++;
        if (vv_br_overrun(&r))
            goto bad;
    }
    if (vv_br_overrun(&r))
        goto bad;
    return VV_OK;
bad:
    return vv_error_set(VV_ERR_FORMAT, "subcube %d: bit stream does not decode", index);
}
