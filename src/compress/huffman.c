/* Canonical Huffman coding as in baseline JPEG (ITU T.81: code lengths by
 * Annex K.2, codes by Annex C, decoding by Annex F.2.2.3), and the bit
 * reader and writer of the .vvc codec. */
#include <stdlib.h>
#include <string.h>

#include "compress/huffman.h"

void
vv_huff_build(const uint64_t *freq, int nsym, vv_huff_table *t) {
    /* Annex K.2 with nsym + 1 symbols: the extra one (frequency 1) reserves
     * the all-ones code point and guarantees at least two symbols. */
    const int n = nsym + 1;
    uint64_t *f = malloc(sizeof *f * (size_t)n);
    int *codesize = calloc((size_t)n, sizeof *codesize);
    int *others = malloc(sizeof *others * (size_t)n);
    memset(t, 0, sizeof *t);
    if (!f || !codesize || !others) {
        free(f);
        free(codesize);
        free(others);
        return;
    }
    for (int i = 0; i < nsym; i++)
        f[i] = freq[i];
    f[nsym] = 1;
    for (int i = 0; i < n; i++)
        others[i] = -1;
    for (;;) {
        int c1 = -1, c2 = -1;
        uint64_t v = UINT64_MAX;
        /* smallest non-zero frequency; on ties the largest symbol (as K.2) */
        for (int i = 0; i < n; i++)
            if (f[i] && f[i] <= v) {
                v = f[i];
                c1 = i;
            }
        v = UINT64_MAX;
        for (int i = 0; i < n; i++)
            if (f[i] && f[i] <= v && i != c1) {
                v = f[i];
                c2 = i;
            }
        if (c2 < 0)
            break;
        f[c1] += f[c2];
        f[c2] = 0;
        codesize[c1]++;
        while (others[c1] >= 0) {
            c1 = others[c1];
            codesize[c1]++;
        }
        others[c1] = c2;
        codesize[c2]++;
        while (others[c2] >= 0) {
            c2 = others[c2];
            codesize[c2]++;
        }
    }
    int count[64] = {0};
    for (int i = 0; i < n; i++)
        if (codesize[i])
            count[codesize[i] < 63 ? codesize[i] : 63]++;
    /* limit the lengths to 16 (Annex K.2, Figure K.3) */
    for (int i = 63; i > VV_HUFF_MAX_LEN; i--) {
        while (count[i] > 0) {
            int j = i - 2;
            while (count[j] == 0)
                j--;
            count[i] -= 2;
            count[i - 1]++;
            count[j + 1] += 2;
            count[j]--;
        }
    }
    /* drop the reserved code point (the longest code) */
    int i = VV_HUFF_MAX_LEN;
    while (i > 0 && count[i] == 0)
        i--;
    if (i > 0)
        count[i]--;
    for (int l = 1; l <= VV_HUFF_MAX_LEN; l++)
        t->bits[l] = (uint8_t)count[l];
    /* symbols by code length, then by value */
    int k = 0;
    for (int l = 1; l <= 62; l++)
        for (int s = 0; s < nsym; s++)
            if (codesize[s] == l && k < VV_HUFF_MAX_SYMS)
                t->vals[k++] = (uint16_t)s;
    /* after length limiting the symbols keep the order of their original
     * lengths, so the shortest codes still go to the most frequent symbols */
    int total = 0;
    for (int l = 1; l <= VV_HUFF_MAX_LEN; l++)
        total += t->bits[l];
    t->nvals = total < k ? total : k;
    free(f);
    free(codesize);
    free(others);
}

/* Walks the canonical codes of t; calls back per symbol. 0, or -1 when the table over-fills. */
static int
canonical(const vv_huff_table *t, vv_huff_enc *e, vv_huff_dec *d) {
    uint32_t code = 0;
    int k = 0;
    for (int l = 1; l <= VV_HUFF_MAX_LEN; l++) {
        if (d) {
            d->valptr[l] = k;
            d->mincode[l] = (int32_t)code;
            d->maxcode[l] = -1;
        }
        for (int c = 0; c < t->bits[l]; c++) {
            if (k >= t->nvals || code >= (1u << l))
                return -1;
            if (e)
                e->code[t->vals[k]] = code, e->len[t->vals[k]] = (uint8_t)l;
            if (d)
                d->maxcode[l] = (int32_t)code;
            code++;
            k++;
        }
        code <<= 1;
    }
    if (d)
        d->maxcode[VV_HUFF_MAX_LEN + 1] = INT32_MAX; /* sentinel */
    return k == t->nvals ? 0 : -1;
}

vv_status
vv_huff_make_enc(const vv_huff_table *t, vv_huff_enc *e) {
    memset(e, 0, sizeof *e);
    if (canonical(t, e, NULL))
        return vv_error_set(VV_ERR_FORMAT, "Huffman table over-fills the code space");
    return VV_OK;
}

vv_status
vv_huff_make_dec(const vv_huff_table *t, vv_huff_dec *d) {
    memset(d, 0, sizeof *d);
    if (canonical(t, NULL, d))
        return vv_error_set(VV_ERR_FORMAT, "Huffman table over-fills the code space");
    memcpy(d->vals, t->vals, sizeof(uint16_t) * (size_t)t->nvals);
    /* every code of up to VV_HUFF_LOOK bits fills the entries it prefixes */
    uint32_t code = 0;
    int k = 0;
    for (int l = 1; l <= VV_HUFF_MAX_LEN; l++) {
        for (int c = 0; c < t->bits[l]; c++, k++, code++) {
            if (l > VV_HUFF_LOOK)
                continue;
            const uint32_t first = code << (VV_HUFF_LOOK - l), n = 1u << (VV_HUFF_LOOK - l);
            for (uint32_t e = 0; e < n; e++)
                d->look[first + e] = (uint16_t)(t->vals[k] + 1024 * l);
        }
        code <<= 1;
    }
    return VV_OK;
}

static void
bw_reserve(vv_bitwriter *w, size_t extra) {
    if (w->failed || w->len + extra <= w->cap)
        return;
    size_t cap = w->cap ? w->cap * 2 : 1024;
    while (cap < w->len + extra)
        cap *= 2;
    uint8_t *nb = realloc(w->buf, cap);
    if (!nb) {
        w->failed = 1;
        return;
    }
    w->buf = nb;
    w->cap = cap;
}

void
vv_bw_put(vv_bitwriter *w, uint32_t bits, int n) {
    if (n <= 0)
        return;
    w->acc = (w->acc << n) | (bits & (uint32_t)((1ull << n) - 1));
    w->nacc += n;
    if (w->nacc >= 32) {
        bw_reserve(w, 8);
        if (w->failed) {
            w->nacc = 0;
            return;
        }
        while (w->nacc >= 8) {
            w->nacc -= 8;
            w->buf[w->len++] = (uint8_t)(w->acc >> w->nacc);
        }
    }
}

void
vv_bw_flush(vv_bitwriter *w) {
    if (w->nacc % 8)
        vv_bw_put(w, 0xff, 8 - w->nacc % 8);
    bw_reserve(w, 8);
    if (w->failed)
        return;
    while (w->nacc >= 8) {
        w->nacc -= 8;
        w->buf[w->len++] = (uint8_t)(w->acc >> w->nacc);
    }
    w->acc = 0;
}

uint32_t
vv_br_get(vv_bitreader *r, int n) {
    if (n <= 0)
        return 0;
    while (r->nacc < n) {
        uint64_t byte = 0;
        if (r->p < r->end)
            byte = *r->p++;
        else
            r->overrun++;
        r->acc = (r->acc << 8) | byte;
        r->nacc += 8;
    }
    r->nacc -= n;
    return (uint32_t)((r->acc >> r->nacc) & ((1ull << n) - 1));
}

int
vv_br_overrun(const vv_bitreader *r) {
    /* the zero bytes fed past the end are the newest in acc: some were consumed
     * when fewer unread bits remain than were fed */
    return r->overrun > 0 && 8 * r->overrun > r->nacc;
}

int
vv_huff_decode(vv_bitreader *r, const vv_huff_dec *d) {
    /* peek VV_HUFF_LOOK bits (zeros past the end, counted as overrun) */
    while (r->nacc < VV_HUFF_LOOK) {
        uint64_t byte = 0;
        if (r->p < r->end)
            byte = *r->p++;
        else
            r->overrun++;
        r->acc = (r->acc << 8) | byte;
        r->nacc += 8;
    }
    const uint32_t peek =
        (uint32_t)(r->acc >> (r->nacc - VV_HUFF_LOOK)) & ((1u << VV_HUFF_LOOK) - 1);
    const uint16_t e = d->look[peek];
    if (e) {
        r->nacc -= e >> 10;
        return e & 1023;
    }
    /* a longer code: its first VV_HUFF_LOOK bits, then bit by bit */
    int32_t code = (int32_t)vv_br_get(r, VV_HUFF_LOOK);
    for (int l = VV_HUFF_LOOK + 1; l <= VV_HUFF_MAX_LEN; l++) {
        code = (code << 1) | (int32_t)vv_br_get(r, 1);
        if (d->maxcode[l] >= 0 && code <= d->maxcode[l] && code >= d->mincode[l])
            return d->vals[d->valptr[l] + code - d->mincode[l]];
    }
    return -1;
}
