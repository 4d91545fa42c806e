/*
 * The .vvc entropy coding of format version 2: context-modelled binary
 * arithmetic coding (rangecoder.h) of a subcube's quantised coefficients in
 * scan order, with one fixed probability per context stored in the file
 * (estimated from the whole volume's statistics by the encoder, so every
 * subcube still decodes alone).
 *
 * Per subcube: the last band holding a nonzero coefficient plus one, L in
 * 0 .. nb (0: every coefficient zero), as a 6-bit binary tree; then, for
 * every scan position of a band below L, "nonzero?" in the context (band,
 * activity), activity being the summed magnitudes of the three coefficients
 * one step lower in frequency (already coded) in six classes; for a
 * nonzero: "|q| > 1?" and "|q| > 2?" in the same contexts, |q| - 3 as an
 * order-0 Exp-Golomb code whose prefix bits have contexts per (band group,
 * bit) and whose suffix bits are raw, then the sign as a raw bit. With an
 * error bound, the voxel corrections follow (vvc_corr_*). The layout is in
 * docs/file-formats.md.
 */
#include <math.h>
#include <string.h>

#include "compress/rangecoder.h"
#include "compress/vvc_internal.h"

void
vvc2_model_init(vvc2_model *m, int nb) {
    m->nb = nb;
    m->o_last = 0;
    m->o_sig = m->o_last + 64;
    m->o_g1 = m->o_sig + nb * VVC2_ACT * VVC2_LC;
    m->o_g2 = m->o_g1 + nb * VVC2_ACT;
    m->o_eg = m->o_g2 + nb * VVC2_ACT;
    m->o_corr = m->o_eg + VVC2_EG_GROUPS * VVC2_EG_CTX;
    m->nctx = m->o_corr + 3 * VVC2_EG_CTX;
}

static inline uint64_t
mag(int64_t v) {
    return v < 0 ? (uint64_t)-v : (uint64_t)v;
}

/* q holds N + 1 numbers, q[N] = 0 (the neighbour that is not there) */
static inline int
activity(const vvc_scan *sc, const int64_t *q, int e) {
    static const uint8_t cls[9] = {0, 1, 2, 3, 3, 4, 4, 4, 4};
    const int32_t *n = sc->nbr + VVC_NBR * e;
    const uint64_t s = mag(q[n[0]]) + mag(q[n[1]]) + mag(q[n[2]]) + mag(q[n[3]]);
    return s <= 8 ? cls[s] : 5;
}

/* Position classes 4 b / L of the bands b < L, and Exp-Golomb groups 4 b / nb. */
static inline void
band_classes(const vvc2_model *m, int L, uint8_t *lc, uint8_t *eg) {
    for (int b = 0; b < L; b++) {
        lc[b] = (uint8_t)(b * VVC2_LC / L);
        eg[b] = (uint8_t)(b * VVC2_EG_GROUPS / m->nb);
    }
}

/* Where bits go: counted per context, or coded. */
typedef struct sink {
    uint64_t *counts; /* 2 per context, or NULL */
    uint64_t bypass;
    const uint16_t *p0;
    vv_rc_enc *e;
} sink;

static inline void
put_bit(sink *s, int ctx, int bit) {
    if (s->counts)
        s->counts[2 * ctx + bit]++;
    else
        vv_rc_bit(s->e, s->p0[ctx], bit);
}

static inline void
put_raw(sink *s, uint64_t v, int n) {
    if (s->counts) {
        s->bypass += (uint64_t)n;
        return;
    }
    if (n > 32) {
        vv_rc_bits(s->e, (uint32_t)(v >> 32), n - 32);
        n = 32;
    }
    vv_rc_bits(s->e, (uint32_t)v, n);
}

/* Order-0 Exp-Golomb code of v >= 0 with prefix contexts ctx0 + min(j, VVC2_EG_CTX - 1). */
static inline void
put_eg(sink *s, int ctx0, uint64_t v) {
    const uint64_t x = v + 1;
    int nbits = 63 - __builtin_clzll(x);
    for (int j = 0; j < nbits; j++)
        put_bit(s, ctx0 + (j < VVC2_EG_CTX - 1 ? j : VVC2_EG_CTX - 1), 1);
    put_bit(s, ctx0 + (nbits < VVC2_EG_CTX - 1 ? nbits : VVC2_EG_CTX - 1), 0);
    put_raw(s, x, nbits);
}

static void
code_block(const vvc_scan *sc, const vvc2_model *m, const int64_t *q, sink *s) {
    int last = -1;
    for (int e = sc->N - 1; e >= 0; e--)
        if (q[e]) {
            last = sc->band[e];
            break;
        }
    const int L = last + 1;
    for (int i = 5, node = 1; i >= 0; i--) {
        const int bit = (L >> i) & 1;
        put_bit(s, m->o_last + node, bit);
        node = 2 * node + bit;
    }
    const int end = L > 0 ? sc->band_end[L - 1] : 0;
    uint8_t lc[64], eg[64];
    band_classes(m, L, lc, eg);
    for (int e = 0; e < end; e++) {
        const int b = sc->band[e], ctx = b * VVC2_ACT + activity(sc, q, e);
        const int64_t v = q[e];
        put_bit(s, m->o_sig + ctx * VVC2_LC + lc[b], v != 0);
        if (!v)
            continue;
        const uint64_t a = mag(v);
        put_bit(s, m->o_g1 + ctx, a > 1);
        if (a > 1) {
            put_bit(s, m->o_g2 + ctx, a > 2);
            if (a > 2)
                put_eg(s, m->o_eg + eg[b] * VVC2_EG_CTX, a - 3);
        }
        put_raw(s, v < 0, 1);
    }
}

void
vvc2_count_block(const vvc_scan *sc, const vvc2_model *m, const int64_t *q, uint64_t *counts,
                 uint64_t *bypass) {
    sink s = {counts, 0, NULL, NULL};
    code_block(sc, m, q, &s);
    *bypass += s.bypass;
}

void
vvc2_encode_block(const vvc_scan *sc, const vvc2_model *m, const int64_t *q, const uint16_t *p0,
                  vv_rc_enc *e) {
    sink s = {NULL, 0, p0, e};
    code_block(sc, m, q, &s);
}

/* ---- voxel corrections of the error-bound mode --------------------------- */

void
vvc2_code_corrections(const vvc2_model *m, const vvc_corr *cr, int n, uint64_t *counts,
                      uint64_t *bypass, const uint16_t *p0, vv_rc_enc *e) {
    sink s = {counts, 0, p0, e};
    put_eg(&s, m->o_corr, (uint64_t)n);
    int prev = -1;
    for (int i = 0; i < n; i++) {
        put_eg(&s, m->o_corr + VVC2_EG_CTX, (uint64_t)(cr[i].pos - prev - 1));
        prev = cr[i].pos;
        const int64_t k = cr[i].k;
        put_eg(&s, m->o_corr + 2 * VVC2_EG_CTX, (uint64_t)(k < 0 ? -k : k) - 1);
        put_raw(&s, k < 0, 1);
    }
    if (bypass)
        *bypass += s.bypass;
}

/* ---- decoding ---------------------------------------------------------- */

static inline int
get_eg(vv_rc_dec *d, const uint16_t *p0, int ctx0, uint64_t *v) {
    int nbits = 0;
    while (vv_rc_dec_bit(d, p0[ctx0 + (nbits < VVC2_EG_CTX - 1 ? nbits : VVC2_EG_CTX - 1)])) {
        if (++nbits > VVC2_EG_MAX || d->overrun)
            return -1;
    }
    uint64_t x = 1;
    if (nbits > 32) {
        x = (x << (nbits - 32)) | vv_rc_dec_bits(d, nbits - 32);
        x = (x << 32) | vv_rc_dec_bits(d, 32);
    } else if (nbits > 0) {
        x = (x << nbits) | vv_rc_dec_bits(d, nbits);
    }
    *v = x - 1;
    return 0;
}

int
vvc2_decode_block(const vvc_scan *sc, const vvc2_model *m, const uint16_t *p0, vv_rc_dec *d,
                  int64_t *q) {
    memset(q, 0, sizeof *q * (size_t)sc->N);
    int L = 0;
    for (int i = 5, node = 1; i >= 0; i--) {
        const int bit = vv_rc_dec_bit(d, p0[m->o_last + node]);
        node = 2 * node + bit;
        L = 2 * L + bit;
    }
    if (L > m->nb)
        return -1;
    const int end = L > 0 ? sc->band_end[L - 1] : 0;
    uint8_t lc[64], eg[64];
    band_classes(m, L, lc, eg);
    for (int e = 0; e < end; e++) {
        const int b = sc->band[e], ctx = b * VVC2_ACT + activity(sc, q, e);
        if (!vv_rc_dec_bit(d, p0[m->o_sig + ctx * VVC2_LC + lc[b]]))
            continue;
        uint64_t a = 1;
        if (vv_rc_dec_bit(d, p0[m->o_g1 + ctx])) {
            a = 2;
            if (vv_rc_dec_bit(d, p0[m->o_g2 + ctx])) {
                uint64_t r;
                if (get_eg(d, p0, m->o_eg + eg[b] * VVC2_EG_CTX, &r))
                    return -1;
                a = 3 + r;
            }
        }
        q[e] = vv_rc_dec_bits(d, 1) ? -(int64_t)a : (int64_t)a;
        if (d->overrun)
            return -1;
    }
    return d->overrun ? -1 : 0;
}

int
vvc2_decode_corrections(const vvc2_model *m, const uint16_t *p0, vv_rc_dec *d, int nvox,
                        vvc_corr **out, int *n) {
    *out = NULL;
    *n = 0;
    uint64_t cnt;
    if (get_eg(d, p0, m->o_corr, &cnt) || cnt > (uint64_t)nvox)
        return -1;
    if (cnt == 0)
        return d->overrun ? -1 : 0;
    vvc_corr *cr = malloc(sizeof *cr * (size_t)cnt);
    if (!cr)
        return -2;
    int prev = -1;
    for (uint64_t i = 0; i < cnt; i++) {
        uint64_t gap, a;
        if (get_eg(d, p0, m->o_corr + VVC2_EG_CTX, &gap) || gap >= (uint64_t)(nvox - prev - 1) ||
            get_eg(d, p0, m->o_corr + 2 * VVC2_EG_CTX, &a) || a > (1ull << 40)) {
            free(cr);
            return -1;
        }
        prev += (int)gap + 1;
        cr[i].pos = prev;
        cr[i].k = vv_rc_dec_bits(d, 1) ? -(int64_t)(a + 1) : (int64_t)(a + 1);
    }
    if (d->overrun) {
        free(cr);
        return -1;
    }
    *out = cr;
    *n = (int)cnt;
    return 0;
}

/* ---- probabilities from counts ------------------------------------------- */

unsigned
vvc2_prob_of_code(unsigned code) {
    if (code == 0)
        return VV_RC_ONE / 2;
    const long v = lround(VV_RC_ONE / (1.0 + exp(-((double)code - 128.0) / 18.0)));
    return (unsigned)(v < 1 ? 1 : v > (long)VV_RC_ONE - 1 ? (long)VV_RC_ONE - 1 : v);
}

void
vvc2_probabilities(const vvc2_model *m, const uint64_t *counts, uint8_t *code, uint16_t *p0) {
    for (int c = 0; c < m->nctx; c++) {
        const double n0 = (double)counts[2 * c], n1 = (double)counts[2 * c + 1];
        unsigned v = 0;
        if (n0 + n1 > 0) {
            /* the byte whose logistic probability is nearest in the logit domain */
            const double p = (n0 + 0.4) / (n0 + n1 + 0.8);
            const long k = lround(128.0 + 18.0 * log(p / (1.0 - p)));
            v = (unsigned)(k < 1 ? 1 : k > 255 ? 255 : k);
        }
        code[c] = (uint8_t)v;
        p0[c] = (uint16_t)vvc2_prob_of_code(v);
    }
}

double
vvc2_cost_bits(const vvc2_model *m, const uint64_t *counts, const uint16_t *p0, uint64_t bypass) {
    double bits = (double)bypass;
    for (int c = 0; c < m->nctx; c++) {
        const double p = p0[c] / (double)VV_RC_ONE;
        if (counts[2 * c])
            bits -= (double)counts[2 * c] * log2(p);
        if (counts[2 * c + 1])
            bits -= (double)counts[2 * c + 1] * log2(1.0 - p);
    }
    return bits;
}

/* ---- rate-distortion optimised quantisation ------------------------------ */

void
vvc2_costs(const vvc2_model *m, const uint16_t *p0, float *cost) {
    for (int c = 0; c < m->nctx; c++) {
        cost[2 * c] = (float)-log2(p0[c] / (double)VV_RC_ONE);
        cost[2 * c + 1] = (float)-log2(1.0 - p0[c] / (double)VV_RC_ONE);
    }
}

/* Bits of a nonzero magnitude a in context ctx, Exp-Golomb group g (sign included). */
static inline float
mag_bits(const vvc2_model *m, const float *cost, int ctx, int g, uint64_t a) {
    float bits = cost[2 * (m->o_g1 + ctx) + (a > 1)] + 1.0f;
    if (a > 1) {
        bits += cost[2 * (m->o_g2 + ctx) + (a > 2)];
        if (a > 2) {
            const int c0 = m->o_eg + g * VVC2_EG_CTX;
            const int nbits = 63 - __builtin_clzll(a - 2);
            for (int j = 0; j < nbits; j++)
                bits += cost[2 * (c0 + (j < VVC2_EG_CTX - 1 ? j : VVC2_EG_CTX - 1)) + 1];
            bits +=
                cost[2 * (c0 + (nbits < VVC2_EG_CTX - 1 ? nbits : VVC2_EG_CTX - 1))] + (float)nbits;
        }
    }
    return bits;
}

void
vvc2_rdoq_block(const vvc_scan *sc, const vvc2_model *m, const float *cost, const float *sp,
                const double *inv_step, const float *weight, double lambda, int64_t *q) {
    /* the plain rounding first: its last band fixes the position classes */
    int last = -1;
    for (int e = 0; e < sc->N; e++) {
        const double x = (double)sp[e] * inv_step[e];
        q[e] = (int64_t)(x + copysign(0.5, x));
        if (q[e])
            last = sc->band[e];
    }
    const int L = last + 1;
    const int end = L > 0 ? sc->band_end[L - 1] : 0;
    uint8_t lc[64], eg[64];
    band_classes(m, L, lc, eg);
    for (int e = 1; e < end; e++) {
        if (!q[e])
            continue;
        const double x = fabs((double)sp[e] * inv_step[e]);
        const uint64_t a0 = mag(q[e]);
        const int b = sc->band[e], ctx = b * VVC2_ACT + activity(sc, q, e);
        const int sctx = m->o_sig + ctx * VVC2_LC + lc[b];
        const double w = weight[e];
        /* candidates a0, a0 - 1 and 0 */
        double best = w * (x - (double)a0) * (x - (double)a0) +
                      lambda * (cost[2 * sctx + 1] + mag_bits(m, cost, ctx, eg[b], a0));
        uint64_t ba = a0;
        if (a0 > 1) {
            const double d = x - (double)(a0 - 1);
            const double j =
                w * d * d + lambda * (cost[2 * sctx + 1] + mag_bits(m, cost, ctx, eg[b], a0 - 1));
            if (j < best) {
                best = j;
                ba = a0 - 1;
            }
        }
        const double j0 = w * x * x + lambda * cost[2 * sctx];
        if (j0 < best)
            ba = 0;
        q[e] = q[e] < 0 ? -(int64_t)ba : (int64_t)ba;
    }
}
