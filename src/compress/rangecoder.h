/*
 * A binary range coder (internal to the .vvc codec, format version 2): the
 * carry-propagating coder of LZMA (Pavlov; Martin 1979, "Range encoding"),
 * 32-bit range, 12-bit probabilities of a 0 bit, and raw (bypass) bits. The
 * probabilities are fixed per call (the .vvc stores one per context), so
 * the cost of a bit is known in advance: -log2(p) (vv_rc_cost).
 *
 * The encoder appends to a growing buffer; vv_rc_enc_flush writes the last
 * 5 bytes. The decoder reads [p, end); reading past the end feeds zeros and
 * sets `overrun`, which a caller must treat as a corrupt stream. Neither
 * allocates for the decoder; both are plain values (one per thread).
 */
#ifndef VV_COMPRESS_RANGECODER_H
#define VV_COMPRESS_RANGECODER_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define VV_RC_PROB_BITS 12
#define VV_RC_ONE (1u << VV_RC_PROB_BITS) /* probability 1 */
#define VV_RC_TOP (1u << 24)

typedef struct vv_rc_enc {
    uint8_t *buf;
    size_t len, cap;
    uint64_t low;
    uint32_t range;
    uint8_t cache;
    uint64_t cache_size;
    int failed; /* an allocation failed */
} vv_rc_enc;

static inline void
vv_rc_enc_init(vv_rc_enc *e) {
    memset(e, 0, sizeof *e);
    e->range = 0xFFFFFFFFu;
    e->cache_size = 1;
}

static inline void
vv_rc_put_byte(vv_rc_enc *e, uint8_t b) {
    if (e->len == e->cap) {
        size_t cap = e->cap ? 2 * e->cap : 256;
        uint8_t *p = realloc(e->buf, cap);
        if (!p) {
            e->failed = 1;
            return;
        }
        e->buf = p;
        e->cap = cap;
    }
    e->buf[e->len++] = b;
}

static inline void
vv_rc_shift_low(vv_rc_enc *e) {
    if ((uint32_t)e->low < 0xFF000000u || (e->low >> 32) != 0) {
        uint8_t temp = e->cache;
        do {
            vv_rc_put_byte(e, (uint8_t)(temp + (uint8_t)(e->low >> 32)));
            temp = 0xFF;
        } while (--e->cache_size != 0);
        e->cache = (uint8_t)(e->low >> 24);
    }
    e->cache_size++;
    e->low = (e->low & 0x00FFFFFFu) << 8;
}

/** Codes @p bit with probability p0 / 4096 of a 0 (1 <= p0 <= 4095). */
static inline void
vv_rc_bit(vv_rc_enc *e, unsigned p0, int bit) {
    const uint32_t bound = (e->range >> VV_RC_PROB_BITS) * p0;
    if (!bit) {
        e->range = bound;
    } else {
        e->low += bound;
        e->range -= bound;
    }
    while (e->range < VV_RC_TOP) {
        e->range <<= 8;
        vv_rc_shift_low(e);
    }
}

/** Codes the @p n low bits of @p v (n <= 32), most significant first, each with probability 1/2. */
static inline void
vv_rc_bits(vv_rc_enc *e, uint32_t v, int n) {
    for (int i = n - 1; i >= 0; i--) {
        e->range >>= 1;
        if ((v >> i) & 1)
            e->low += e->range;
        while (e->range < VV_RC_TOP) {
            e->range <<= 8;
            vv_rc_shift_low(e);
        }
    }
}

static inline void
vv_rc_enc_flush(vv_rc_enc *e) {
    for (int i = 0; i < 5; i++)
        vv_rc_shift_low(e);
}

typedef struct vv_rc_dec {
    const uint8_t *p, *end;
    uint32_t range, code;
    int overrun;
} vv_rc_dec;

static inline uint8_t
vv_rc_next(vv_rc_dec *d) {
    if (d->p < d->end)
        return *d->p++;
    d->overrun = 1;
    return 0;
}

static inline void
vv_rc_dec_init(vv_rc_dec *d, const uint8_t *p, const uint8_t *end) {
    d->p = p;
    d->end = end;
    d->overrun = 0;
    d->range = 0xFFFFFFFFu;
    d->code = 0;
    if (vv_rc_next(d) != 0) /* the encoder's first byte is always 0 */
        d->overrun = 1;
    for (int i = 0; i < 4; i++)
        d->code = (d->code << 8) | vv_rc_next(d);
}

static inline int
vv_rc_dec_bit(vv_rc_dec *d, unsigned p0) {
    const uint32_t bound = (d->range >> VV_RC_PROB_BITS) * p0;
    int bit;
    if (d->code < bound) {
        d->range = bound;
        bit = 0;
    } else {
        d->code -= bound;
        d->range -= bound;
        bit = 1;
    }
    while (d->range < VV_RC_TOP) {
        d->range <<= 8;
        d->code = (d->code << 8) | vv_rc_next(d);
    }
    return bit;
}

static inline uint32_t
vv_rc_dec_bits(vv_rc_dec *d, int n) {
    uint32_t v = 0;
    for (int i = 0; i < n; i++) {
        d->range >>= 1;
        uint32_t b = d->code >= d->range;
        if (b)
            d->code -= d->range;
        v = (v << 1) | b;
        while (d->range < VV_RC_TOP) {
            d->range <<= 8;
            d->code = (d->code << 8) | vv_rc_next(d);
        }
    }
    return v;
}

#endif
