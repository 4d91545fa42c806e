/*
 * The .vvc encoder: the subcube spectra in scan order; version 1 (symbol
 * statistics and Huffman tables) and version 2 (context statistics and
 * probabilities, range coding, the voxel corrections of the error-bound
 * mode); the search of the quality for a target rate (vv_vvc_compress).
 */
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "compress/rangecoder.h"
#include "compress/vvc_internal.h"
#include "core/internal.h"

/* ---------------------------------------------------------------------- */
/* Encoding                                                                 */

typedef struct enc {
    const vvc_scan *sc;
    const float *spectra; /* per subcube: its M^3 numbers in scan order */
    size_t per;           /* floats per subcube (M^3) */
    int nsub;
    int threads;
    const vv_volume *v;  /* the volume (error-bound mode) */
    double offset, unit; /* coded value = (value - offset) / unit */
    double theta;        /* version 2: rounding threshold of the AC magnitudes */
    double lambda;       /* version 2: Lagrange multiplier of the RDO quantiser (0: off) */
} enc;

/* Unitary step of the flat table in the error-bound mode, in units of the
 * correction step (measured: the smallest files on ct_head, neghip, noise) */
#define VVC_ERR_STEP 1.5

/* Version 2's quantiser, measured on ct_head at 0.5 / 1 / 2 bits per voxel
 * (PSNR, dB): plain rounding 45.88 / 52.31 / 60.16; dead zone (theta 0.4)
 * 46.24 / 52.60 / 60.39; RDO with lambda 0.12, 0.18, 0.25, 0.35, 0.5 (in
 * squared steps per bit): 52.81, 52.89, 52.93, 52.91, 52.79 at 1 bit. The
 * dead zone makes the statistics the RDO pass starts from. */
#define VVC_THETA 0.4
#define VVC_LAMBDA 0.25

/* Symbol statistics of all subcubes at the given steps. */
static vv_status
gather_stats(const enc *en, const float *step_abs, uint64_t *dcf, uint64_t *acf, uint64_t *amp) {
    memset(dcf, 0, sizeof(uint64_t) * VVC_DC_SYMS);
    memset(acf, 0, sizeof(uint64_t) * VVC_AC_SYMS);
    *amp = 0;
    double *inv = malloc(sizeof(double) * (size_t)en->sc->N);
    if (!inv)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int e = 0; e < en->sc->N; e++)
        inv[e] = 1.0 / (double)step_abs[e];
    int failed = 0;
#pragma omp parallel num_threads(en->threads)
    {
        uint64_t ldc[VVC_DC_SYMS] = {0};
        uint64_t *lac = calloc(VVC_AC_SYMS, sizeof *lac);
        int64_t *q = calloc((size_t)en->sc->N + 1, sizeof *q);
        sym_counter c = {ldc, lac, 0, NULL, NULL, NULL};
#pragma omp for schedule(dynamic, 8)
        for (int s = 0; s < en->nsub; s++) {
            if (!lac || !q)
                continue;
            vvc_quantise(en->sc, en->spectra + (size_t)s * en->per, inv, q);
            vvc_symbolise(q, en->sc->N, &c);
        }
#pragma omp critical(vvc_stats)
        {
            if (!lac || !q) {
                failed = 1;
            } else {
                for (int i = 0; i < VVC_DC_SYMS; i++)
                    dcf[i] += ldc[i];
                for (int i = 0; i < VVC_AC_SYMS; i++)
                    acf[i] += lac[i];
                *amp += c.amp;
            }
        }
        free(lac);
        free(q);
    }
    free(inv);
    return failed ? vv_error_set(VV_ERR_NOMEM, "out of memory") : VV_OK;
}

/* File size for the given steps (tables built from the statistics): exact
 * but for the byte padding of each subcube, counted as 7 bits (an upper bound). */
static vv_status
count_file_bytes(const enc *en, const float *step_abs, int M, uint64_t *file_bytes) {
    uint64_t *dcf = malloc(sizeof *dcf * VVC_DC_SYMS), *acf = malloc(sizeof *acf * VVC_AC_SYMS);
    vv_huff_table *t = malloc(2 * sizeof *t);
    vv_huff_enc *e = malloc(2 * sizeof *e);
    vv_status s = VV_ERR_NOMEM;
    if (!dcf || !acf || !t || !e) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    uint64_t amp;
    if ((s = gather_stats(en, step_abs, dcf, acf, &amp)) != VV_OK)
        goto done;
    vv_huff_build(dcf, VVC_DC_SYMS, &t[0]);
    vv_huff_build(acf, VVC_AC_SYMS, &t[1]);
    if ((s = vv_huff_make_enc(&t[0], &e[0])) != VV_OK || (s = vv_huff_make_enc(&t[1], &e[1])))
        goto done;
    /* the code bits follow from the statistics; each subcube's stream is
     * padded to a byte, at most 7 bits, counted in full so that the
     * estimate is an upper bound */
    uint64_t bits = amp + 7 * (uint64_t)en->nsub;
    for (int i = 0; i < VVC_DC_SYMS; i++)
        bits += dcf[i] * e[0].len[i];
    for (int i = 0; i < VVC_AC_SYMS; i++)
        bits += acf[i] * e[1].len[i];
    const uint64_t data = bits / 8;
    const uint64_t total_data = data + 4;
    const uint64_t index = (uint64_t)en->nsub * (total_data - 4 < (1ull << 32) ? 4 : 8) + 4;
    *file_bytes = VVC_HEADER_BYTES + vvc_tables_bytes(M, &t[0], &t[1]) + index + total_data;
    s = VV_OK;
done:
    free(dcf);
    free(acf);
    free(t);
    free(e);
    return s;
}

/* Writes the whole file for the given quality into b. */
static vv_status
encode_file(const enc *en, const vv_volume *v, int M, double quality, double slope, double offset,
            double unit, unsigned char **bytes, size_t *size, const vv_progress *progress) {
    const vvc_scan *sc = en->sc;
    const int H = M / 2 + 1;
    float *qtab = malloc(sizeof(float) * (size_t)H * H * H);
    float *step_abs = malloc(sizeof(float) * (size_t)sc->N);
    uint64_t *dcf = malloc(sizeof *dcf * VVC_DC_SYMS), *acf = malloc(sizeof *acf * VVC_AC_SYMS);
    vv_huff_table *t = malloc(2 * sizeof *t);
    vv_huff_enc *e = malloc(2 * sizeof *e);
    vv_bitwriter *streams = calloc((size_t)en->nsub, sizeof *streams);
    vv_status s;
    if (!qtab || !step_abs || !dcf || !acf || !t || !e || !streams) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    vvc_make_table(qtab, M, quality, slope);
    vvc_make_step_abs(sc, qtab, step_abs);
    uint64_t amp;
    if ((s = gather_stats(en, step_abs, dcf, acf, &amp)) != VV_OK)
        goto done;
    vv_huff_build(dcf, VVC_DC_SYMS, &t[0]);
    vv_huff_build(acf, VVC_AC_SYMS, &t[1]);
    if ((s = vv_huff_make_enc(&t[0], &e[0])) != VV_OK || (s = vv_huff_make_enc(&t[1], &e[1])))
        goto done;
    double *inv = malloc(sizeof(double) * (size_t)sc->N);
    if (!inv) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < sc->N; i++)
        inv[i] = 1.0 / (double)step_abs[i];
    int failed = 0;
    int cancelled = 0;
    long done_n = 0;
#pragma omp parallel num_threads(en->threads)
    {
        int64_t *q = calloc((size_t)sc->N + 1, sizeof *q); /* q[N] = 0: see vvc_scan.nbr */
#pragma omp for schedule(dynamic, 8)
        for (int k = 0; k < en->nsub; k++) {
            if (!q || cancelled) {
                failed |= !q;
                continue;
            }
            sym_counter c = {NULL, NULL, 0, &e[0], &e[1], &streams[k]};
            vvc_quantise(sc, en->spectra + (size_t)k * en->per, inv, q);
            vvc_symbolise(q, sc->N, &c);
            vv_bw_flush(&streams[k]);
            if (streams[k].failed)
                failed = 1;
            if (progress && progress->fn) {
#pragma omp critical(vvc_progress)
                {
                    done_n++;
                    if (vv_progress_report(progress, 0.7 + 0.3 * (double)done_n / en->nsub))
                        cancelled = 1;
                }
            }
        }
        free(q);
    }
    free(inv);
    if (failed) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (cancelled) {
        s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
        goto done;
    }
    {
        uint8_t **bufs = malloc(sizeof *bufs * (size_t)en->nsub);
        size_t *lens = malloc(sizeof *lens * (size_t)en->nsub);
        if (!bufs || !lens) {
            free(bufs);
            free(lens);
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            goto done;
        }
        for (int k = 0; k < en->nsub; k++) {
            bufs[k] = streams[k].buf;
            lens[k] = streams[k].len;
        }
        const vvc_file_desc fd = {1, M,    quality, slope, offset, unit, 0,
                                  0, qtab, t,       NULL,  NULL,   0,    NULL};
        const vvc_streams st = {en->nsub, bufs, lens};
        s = vvc_write_file(v, &fd, &st, bytes, size);
        free(bufs);
        free(lens);
    }
done:
    if (streams)
        for (int k = 0; k < en->nsub; k++)
            free(streams[k].buf);
    free(streams);
    free(qtab);
    free(step_abs);
    free(dcf);
    free(acf);
    free(t);
    free(e);
    return s;
}

/* ---------------------------------------------------------------------- */
/* Version 2: context-modelled arithmetic coding                            */

/* Context bit counts of all subcubes at the given steps (2 per context) and raw bits. */
/* One subcube quantised: rate-distortion optimised with the bit costs @p cost, or
 * (cost NULL) with the dead zone. */
static inline void
v2_quantise(const enc *en, const vvc2_model *m, int k, const double *inv, const float *cost,
            const float *weight, int64_t *q) {
    const float *sp = en->spectra + (size_t)k * en->per;
    if (cost)
        vvc2_rdoq_block(en->sc, m, cost, sp, inv, weight, en->lambda, q);
    else
        vvc_quantise_dz(en->sc, sp, inv, en->theta, q);
}

/* Adds one subcube's rounding residuals |x| - |q| (in steps) per band and
 * magnitude class (|q| = 1, > 1) to sum and n. */
static inline void
recon_add(const enc *en, int k, const double *inv, const int64_t *q, double *sum, uint64_t *n) {
    const float *sp = en->spectra + (size_t)k * en->per;
    for (int e = 1; e < en->sc->N; e++) {
        const int64_t v = q[e];
        if (!v)
            continue;
        const int i = 2 * en->sc->band[e] + (v > 1 || v < -1);
        sum[i] += fabs((double)sp[e] * inv[e]) - (double)(v < 0 ? -v : v);
        n[i]++;
    }
}

/* The reconstruction offsets: the mean residual of each class (the
 * least-squares offset), clamped to [-0.5, 0.5], in f32 as stored. */
static void
recon_finish(int nb, const double *sum, const uint64_t *n, float *recon) {
    for (int i = 0; i < 2 * nb; i++) {
        double d = n[i] ? sum[i] / (double)n[i] : 0;
        d = d < -0.5 ? -0.5 : d > 0.5 ? 0.5 : d;
        recon[i] = (float)d;
    }
}

/* Context counts (and, with rsum, the sums for the reconstruction offsets) of
 * every stride-th subcube. */
static vv_status
count_v2(const enc *en, const vvc2_model *m, const float *step_abs, const float *cost,
         const float *weight, int stride, uint64_t *counts, uint64_t *bypass, double *rsum,
         uint64_t *rn) {
    memset(counts, 0, sizeof(uint64_t) * 2 * (size_t)m->nctx);
    *bypass = 0;
    double *inv = malloc(sizeof(double) * (size_t)en->sc->N);
    if (!inv)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int e = 0; e < en->sc->N; e++)
        inv[e] = 1.0 / (double)step_abs[e];
    int failed = 0;
    const int nr = 2 * en->sc->nb;
    if (rsum) {
        memset(rsum, 0, sizeof *rsum * (size_t)nr);
        memset(rn, 0, sizeof *rn * (size_t)nr);
    }
#pragma omp parallel num_threads(en->threads)
    {
        uint64_t *lc = calloc(2 * (size_t)m->nctx, sizeof *lc);
        int64_t *q = calloc((size_t)en->sc->N + 1, sizeof *q);
        double *ls = calloc((size_t)nr, sizeof *ls);
        uint64_t *ln = calloc((size_t)nr, sizeof *ln);
        uint64_t lb = 0;
#pragma omp for schedule(dynamic, 8)
        for (int s = 0; s < en->nsub; s += stride) {
            if (!lc || !q || !ls || !ln)
                continue;
            v2_quantise(en, m, s, inv, cost, weight, q);
            vvc2_count_block(en->sc, m, q, lc, &lb);
            if (rsum)
                recon_add(en, s, inv, q, ls, ln);
        }
#pragma omp critical(vvc_stats)
        {
            if (!lc || !q || !ls || !ln) {
                failed = 1;
            } else {
                for (int i = 0; i < 2 * m->nctx; i++)
                    counts[i] += lc[i];
                *bypass += lb;
                for (int i = 0; rsum && i < nr; i++) {
                    rsum[i] += ls[i];
                    rn[i] += ln[i];
                }
            }
        }
        free(lc);
        free(q);
        free(ls);
        free(ln);
    }
    free(inv);
    return failed ? vv_error_set(VV_ERR_NOMEM, "out of memory") : VV_OK;
}

/* The context statistics and probabilities at the given steps: a first pass
 * with the dead-zone quantiser; with the RDO quantiser, a second pass whose
 * decisions use the bit costs of the first (left in @p cost; @p weight
 * filled) and whose counts give the final probabilities. */
static vv_status
v2_statistics(const enc *en, const vvc2_model *m, const float *step_abs, uint64_t *counts,
              uint64_t *bypass, uint8_t *code, uint16_t *p0, float *cost, float *weight,
              double *rsum, uint64_t *rn) {
    /* the first pass only steers the RDO decisions: every 4th subcube is enough */
    const int rdo = en->lambda > 0;
    vv_status s =
        count_v2(en, m, step_abs, NULL, NULL, rdo ? 4 : 1, counts, bypass, rdo ? NULL : rsum, rn);
    vvc2_probabilities(m, counts, code, p0);
    if (s != VV_OK || !(en->lambda > 0))
        return s;
    vvc2_costs(m, p0, cost);
    float smin = step_abs[0];
    for (int e = 0; e < en->sc->N; e++)
        smin = step_abs[e] < smin ? step_abs[e] : smin;
    for (int e = 0; e < en->sc->N; e++)
        weight[e] = (step_abs[e] / smin) * (step_abs[e] / smin);
    s = count_v2(en, m, step_abs, cost, weight, 1, counts, bypass, rsum, rn);
    vvc2_probabilities(m, counts, code, p0);
    return s;
}

/* Index and data bytes of a version 2 file from its coded bits (each
 * subcube's range coder adds at most 5 bytes when flushed). */
static uint64_t
v2_file_bytes(const enc *en, size_t zlen, double bits) {
    const uint64_t data = (uint64_t)ceil(bits / 8.0) + 5 * (uint64_t)en->nsub + 4;
    const uint64_t index = (uint64_t)en->nsub * (data - 4 < (1ull << 32) ? 4 : 8) + 4;
    return VVC_HEADER_BYTES_V2 + vvc2_tables_bytes(zlen, en->sc->nb) + index + data;
}

/* Estimated size of a version 2 file at @p quality. */
static vv_status
size_v2(const enc *en, double quality, double slope, uint64_t *file_bytes) {
    const int M = en->sc->M, H = M / 2 + 1;
    vvc2_model m;
    vvc2_model_init(&m, en->sc->nb);
    float *qtab = malloc(sizeof(float) * (size_t)H * H * H);
    float *step_abs = malloc(sizeof(float) * (size_t)en->sc->N);
    uint64_t *counts = malloc(sizeof(uint64_t) * 2 * (size_t)m.nctx);
    uint16_t *p0 = malloc(sizeof(uint16_t) * (size_t)m.nctx);
    uint8_t *code = malloc((size_t)m.nctx), *z = NULL;
    float *cost = malloc(sizeof(float) * 2 * (size_t)m.nctx);
    float *weight = malloc(sizeof(float) * (size_t)en->sc->N);
    vv_status s = VV_OK;
    uint64_t bypass = 0;
    size_t zlen = 0;
    if (!qtab || !step_abs || !counts || !p0 || !code || !cost || !weight)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s == VV_OK) {
        vvc_make_table(qtab, M, quality, slope);
        vvc_make_step_abs(en->sc, qtab, step_abs);
        s = v2_statistics(en, &m, step_abs, counts, &bypass, code, p0, cost, weight, NULL, NULL);
    }
    if (s == VV_OK)
        s = vvc2_pack_codes(&m, code, &z, &zlen);
    if (s == VV_OK)
        *file_bytes = v2_file_bytes(en, zlen, vvc2_cost_bits(&m, counts, p0, bypass));
    free(code);
    free(z);
    free(qtab);
    free(step_abs);
    free(counts);
    free(p0);
    free(cost);
    free(weight);
    return s;
}

/* Final value of a decoded voxel in the native type (as store_row in vvc_decode.c). */
static inline double
native_value(vv_voxel_type t, float y) {
    double x = y;
    switch (t) {
    case VV_F32:
    case VV_F64:
        return x;
    default:
        break;
    }
    x = x == x ? floor(x + 0.5) : 0;
    const double lo[] = {0, -128, 0, -32768, 0, -2147483648.0};
    const double hi[] = {255, 127, 65535, 32767, 4294967295.0, 2147483647.0};
    const int i = t == VV_U8    ? 0
                  : t == VV_I8  ? 1
                  : t == VV_U16 ? 2
                  : t == VV_I16 ? 3
                  : t == VV_U32 ? 4
                                : 5;
    return x < lo[i] ? lo[i] : x > hi[i] ? hi[i] : x;
}

/* The voxel corrections of subcube k: every voxel of the volume whose decoded
 * value is off by more than max_error gets value += k * corr_step, k chosen
 * so that it is within the bound (checked with the decoder's arithmetic). */
static int
find_corrections(const enc *en, int k, const float *vals, double max_error, double corr_step,
                 vvc_corr *cr) {
    const vv_volume *v = en->v;
    const int M = en->sc->M;
    const int nb0 = (v->dims[0] + M - 1) / M, nb1 = (v->dims[1] + M - 1) / M;
    const int bx = k % nb0, by = (k / nb0) % nb1, bz = k / (nb0 * nb1);
    int n = 0;
    for (int z = 0; z < M && bz * M + z < v->dims[2]; z++)
        for (int y = 0; y < M && by * M + y < v->dims[1]; y++) {
            const size_t base =
                ((size_t)(bz * M + z) * v->dims[1] + (size_t)(by * M + y)) * v->dims[0] +
                (size_t)bx * M;
            for (int x = 0; x < M && bx * M + x < v->dims[0]; x++) {
                const double orig = vv_voxel_at(v, base + (size_t)x);
                if (orig != orig)
                    continue; /* NaN: coded as the minimum, no bound */
                const int pos = (z * M + y) * M + x;
                const float dec = vals[pos];
                if (fabs(orig - native_value(v->type, dec)) <= max_error)
                    continue; /* (float data: max_error has a margin, see the caller) */
                const int64_t k0 = llround((orig - (double)dec) / corr_step);
                int64_t best = k0;
                for (int d = 0; d <= 2; d++) {
                    const int64_t kk = d == 0 ? k0 : d == 1 ? k0 - 1 : k0 + 1;
                    const float y2 = (float)((double)dec + (double)kk * corr_step);
                    if (kk != 0 && fabs(orig - native_value(v->type, y2)) <= max_error) {
                        best = kk;
                        break;
                    }
                }
                cr[n].pos = pos;
                cr[n].k = best == 0 ? 1 : best;
                n++;
            }
        }
    return n;
}

/* What the passes of encode_v2 over the subcubes share. */
typedef struct v2_pass {
    const enc *en;
    vvc2_model *m;
    const double *inv;
    const float *rdo, *weight, *step_abs, *recon;
    fftwf_plan c2r; /* the decoder's inverse plan (corrections only) */
    double bound, corr_step;
    uint64_t *counts; /* 2 * m->nctx context statistics, added to */
    uint16_t *p0;
    vv_rc_enc *rc;   /* per subcube */
    vvc_corr **corr; /* per subcube, corrections only */
    int *ncorr;
} v2_pass;

/* The voxel corrections of every subcube, found on the values the decoder
 * will decode, and their context statistics added to P->counts. */
static vv_status
v2_corrections(const v2_pass *P) {
    const enc *en = P->en;
    const vvc_scan *sc = en->sc;
    const int M = sc->M, H = M / 2 + 1, N = sc->N;
    const vvc2_model *mm = P->m;
    int failed = 0;
#pragma omp parallel num_threads(en->threads)
    {
        int64_t *q = calloc((size_t)N + 1, sizeof *q);
        float *sp = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * H);
        float *vals = fftwf_malloc(sizeof(float) * (size_t)N);
        vvc_corr *tmp = malloc(sizeof *tmp * (size_t)N);
        uint64_t *lc = calloc(2 * (size_t)mm->nctx, sizeof *lc);
        uint64_t lb = 0;
#pragma omp for schedule(dynamic, 8)
        for (int k = 0; k < en->nsub; k++) {
            if (!q || !sp || !vals || !tmp || !lc) {
                failed = 1;
                continue;
            }
            v2_quantise(en, mm, k, P->inv, P->rdo, P->weight, q);
            vvc_dequantise(sc, P->step_abs, P->recon, q, sp);
            vvc_values(P->c2r, N, en->unit, en->offset, sp, vals);
            const int n = find_corrections(en, k, vals, P->bound, P->corr_step, tmp);
            P->ncorr[k] = n;
            if (n > 0) {
                if (!(P->corr[k] = malloc(sizeof *tmp * (size_t)n))) {
                    failed = 1;
                    continue;
                }
                memcpy(P->corr[k], tmp, sizeof *tmp * (size_t)n);
            }
            vvc2_code_corrections(mm, P->corr[k], n, lc, &lb, NULL, NULL);
        }
#pragma omp critical(vvc_stats)
        if (lc) {
            for (int i = 0; i < 2 * mm->nctx; i++)
                P->counts[i] += lc[i];
        }
        free(q);
        fftwf_free(sp);
        fftwf_free(vals);
        free(tmp);
        free(lc);
    }
    return failed ? vv_error_set(VV_ERR_NOMEM, "out of memory") : VV_OK;
}

/* Every subcube coded into its range coder (with its corrections when
 * @p with_corrections), progress from 0.7 to 1. */
static vv_status
v2_encode_blocks(const v2_pass *P, int with_corrections, const vv_progress *progress) {
    const enc *en = P->en;
    const vvc_scan *sc = en->sc;
    const int N = sc->N;
    int failed = 0, cancelled = 0;
    long done_n = 0;
#pragma omp parallel num_threads(en->threads)
    {
        int64_t *q = calloc((size_t)N + 1, sizeof *q);
#pragma omp for schedule(dynamic, 8)
        for (int k = 0; k < en->nsub; k++) {
            if (!q || cancelled) {
                failed |= !q;
                continue;
            }
            vv_rc_enc_init(&P->rc[k]);
            v2_quantise(en, P->m, k, P->inv, P->rdo, P->weight, q);
            vvc2_encode_block(sc, P->m, q, P->p0, &P->rc[k]);
            if (with_corrections)
                vvc2_code_corrections(P->m, P->corr[k], P->ncorr[k], NULL, NULL, P->p0, &P->rc[k]);
            vv_rc_enc_flush(&P->rc[k]);
            if (P->rc[k].failed)
                failed = 1;
            if (progress && progress->fn) {
#pragma omp critical(vvc_progress)
                {
                    done_n++;
                    if (vv_progress_report(progress, 0.7 + 0.3 * (double)done_n / en->nsub))
                        cancelled = 1;
                }
            }
        }
        free(q);
    }
    if (failed)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (cancelled)
        return vv_error_set(VV_ERR_CANCELLED, "cancelled");
    return VV_OK;
}

/* Writes a version 2 file at @p quality; with max_error > 0 the voxel
 * corrections too. */
static vv_status
encode_v2(const enc *en, double quality, double slope, double max_error, double bound,
          double corr_step, unsigned char **bytes, size_t *size, const vv_progress *progress) {
    const vvc_scan *sc = en->sc;
    const int M = sc->M, H = M / 2 + 1, N = sc->N;
    vvc2_model m;
    vvc2_model_init(&m, sc->nb);
    float *qtab = malloc(sizeof(float) * (size_t)H * H * H);
    float *step_abs = malloc(sizeof(float) * (size_t)N);
    uint64_t *counts = malloc(sizeof(uint64_t) * 2 * (size_t)m.nctx);
    uint16_t *p0 = malloc(sizeof(uint16_t) * (size_t)m.nctx);
    double *inv = malloc(sizeof(double) * (size_t)N);
    float *cost = malloc(sizeof(float) * 2 * (size_t)m.nctx);
    float *weight = malloc(sizeof(float) * (size_t)N);
    uint8_t *code = malloc((size_t)m.nctx), *pz = NULL;
    size_t pzlen = 0;
    double *rsum = calloc(2 * (size_t)sc->nb, sizeof *rsum);
    uint64_t *rn = calloc(2 * (size_t)sc->nb, sizeof *rn);
    float *recon = malloc(sizeof *recon * 2 * (size_t)sc->nb);
    vv_rc_enc *rc = calloc((size_t)en->nsub, sizeof *rc);
    vvc_corr **corr = max_error > 0 ? calloc((size_t)en->nsub, sizeof *corr) : NULL;
    int *ncorr = max_error > 0 ? calloc((size_t)en->nsub, sizeof *ncorr) : NULL;
    uint8_t **bufs = malloc(sizeof *bufs * (size_t)en->nsub);
    size_t *lens = malloc(sizeof *lens * (size_t)en->nsub);
    fftwf_plan c2r = NULL;
    vv_status s = VV_OK;
    if (!qtab || !step_abs || !counts || !p0 || !inv || !cost || !weight || !code || !rsum || !rn ||
        !recon || !rc || !bufs || !lens || (max_error > 0 && (!corr || !ncorr))) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    vvc_make_table(qtab, M, quality, slope);
    vvc_make_step_abs(sc, qtab, step_abs);
    for (int i = 0; i < N; i++)
        inv[i] = 1.0 / (double)step_abs[i];
    uint64_t bypass;
    if ((s = v2_statistics(en, &m, step_abs, counts, &bypass, code, p0, cost, weight, rsum, rn)) !=
        VV_OK)
        goto done;
    recon_finish(sc->nb, rsum, rn, recon);
    const float *rdo = en->lambda > 0 ? cost : NULL;
    if (max_error > 0) {
        /* the plan the decoder makes (vvc_decode.c), so that the values match bit for bit */
        vv_fftw_lock();
        float *in = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * H);
        float *out = fftwf_malloc(sizeof(float) * (size_t)N);
        if (in && out)
            c2r = fftwf_plan_dft_c2r_3d(M, M, M, (fftwf_complex *)in, out, FFTW_ESTIMATE);
        fftwf_free(in);
        fftwf_free(out);
        vv_fftw_unlock();
        if (!c2r) {
            s = vv_error_set(VV_ERR_NOMEM, "FFTW could not make a %d^3 plan", M);
            goto done;
        }
    }
    const v2_pass P = {en,    &m,        inv,    rdo, weight, step_abs, recon, c2r,
                       bound, corr_step, counts, p0,  rc,     corr,     ncorr};
    if (max_error > 0 && (s = v2_corrections(&P)) != VV_OK)
        goto done;
    vvc2_probabilities(&m, counts, code, p0);
    if ((s = vvc2_pack_codes(&m, code, &pz, &pzlen)) != VV_OK ||
        (s = v2_encode_blocks(&P, max_error > 0, progress)) != VV_OK)
        goto done;
    for (int k = 0; k < en->nsub; k++) {
        bufs[k] = rc[k].buf;
        lens[k] = rc[k].len;
    }
    {
        const vvc_file_desc fd = {2,         M,    quality, slope, en->offset, en->unit, max_error,
                                  corr_step, qtab, NULL,    &m,    pz,         pzlen,    recon};
        const vvc_streams st = {en->nsub, bufs, lens};
        s = vvc_write_file(en->v, &fd, &st, bytes, size);
    }
done:
    if (c2r) {
        vv_fftw_lock();
        fftwf_destroy_plan(c2r);
        vv_fftw_unlock();
    }
    if (rc)
        for (int k = 0; k < en->nsub; k++)
            free(rc[k].buf);
    if (corr)
        for (int k = 0; k < en->nsub; k++)
            free(corr[k]);
    free(corr);
    free(ncorr);
    free(rc);
    free(bufs);
    free(lens);
    free(qtab);
    free(step_abs);
    free(counts);
    free(p0);
    free(inv);
    free(cost);
    free(weight);
    free(code);
    free(pz);
    free(rsum);
    free(rn);
    free(recon);
    return s;
}

/* ---------------------------------------------------------------------- */
/* The codec's entry point                                                  */

/* File size at a quality, by the format's own estimate (an upper bound). */
static vv_status
size_at(const enc *en, int version, double quality, double slope, uint64_t *bytes) {
    if (version >= 2)
        return size_v2(en, quality, slope, bytes);
    const int M = en->sc->M, H = M / 2 + 1;
    float *qtab = malloc(sizeof(float) * (size_t)H * H * H);
    float *step_abs = malloc(sizeof(float) * (size_t)en->sc->N);
    vv_status s;
    if (!qtab || !step_abs) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    } else {
        vvc_make_table(qtab, M, quality, slope);
        vvc_make_step_abs(en->sc, qtab, step_abs);
        s = count_file_bytes(en, step_abs, M, bytes);
    }
    free(qtab);
    free(step_abs);
    return s;
}

/* The quality whose file is at most target_bytes (the closest reachable). */
static vv_status
search_quality(const enc *en, int version, double slope, double target_bytes,
               const vv_progress *progress, double *quality) {
    /* The file grows with quality and log(size) is nearly linear in it:
     * regula falsi on log(size / target) (Illinois variant), keeping the
     * bracket [lo (fits), hi (too big)]; stops within 0.3 % of the target
     * or after 16 sizes. */
    double lo = 0, hi = 100, flo = 0, fhi = 0;
    uint64_t bytes = 0;
    int side = 0;
    vv_status s = size_at(en, version, hi, slope, &bytes);
    fhi = log((double)bytes / target_bytes);
    if (s == VV_OK && fhi <= 0) {
        lo = hi;
    } else if (s == VV_OK) {
        s = size_at(en, version, lo, slope, &bytes);
        flo = log((double)bytes / target_bytes);
        for (int it = 0; it < 14 && s == VV_OK && flo < 0 && flo < -0.003; it++) {
            double mid = lo - flo * (hi - lo) / (fhi - flo);
            if (!(mid > lo && mid < hi))
                mid = 0.5 * (lo + hi);
            if ((s = size_at(en, version, mid, slope, &bytes)) != VV_OK)
                break;
            const double f = log((double)bytes / target_bytes);
            if (f <= 0) {
                lo = mid;
                flo = f;
                if (side == -1)
                    fhi *= 0.5;
                side = -1;
            } else {
                hi = mid;
                fhi = f;
                if (side == 1)
                    flo *= 0.5;
                side = 1;
            }
            if (vv_progress_report(progress, 0.3 + 0.4 * (it + 1) / 14.0)) {
                s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
                break;
            }
        }
    }
    *quality = lo;
    return s;
}

/* The smallest error bound the decoded values can honour: integer types
 * any bound > 0 (below 1 the data decode exactly); float types at least 4
 * units in the last place of a float at the largest magnitude (the decoder
 * computes in single precision). */
static double
min_error_bound(const vv_volume *v) {
    if (v->type != VV_F32 && v->type != VV_F64)
        return 0;
    const double a = fmax(fabs(v->range[0]), fabs(v->range[1]));
    return a > 0 ? 4.0 * ldexp(1.0, ilogb(a) - 23) : 4.0 * FLT_MIN;
}

vv_status
vv_vvc_compress(vv_vvc **out, const vv_volume *v, const vv_vvc_params *p) {
    *out = NULL;
    vv_vvc_params def;
    if (!p) {
        vv_vvc_params_init(&def);
        p = &def;
    }
    if (!v || !v->data)
        return vv_error_set(VV_ERR_INVALID, "vvc: no volume");
    if (p->block != 8 && p->block != 16 && p->block != 32)
        return vv_error_set(VV_ERR_INVALID, "vvc: block size %d (expected 8, 16 or 32)", p->block);
    if (p->target != VV_VVC_QUALITY && p->target != VV_VVC_RATE && p->target != VV_VVC_MAX_ERROR)
        return vv_error_set(VV_ERR_INVALID, "vvc: unknown target %d", (int)p->target);
    if (p->target == VV_VVC_QUALITY && !(p->quality >= 0 && p->quality <= 100))
        return vv_error_set(VV_ERR_INVALID, "vvc: quality %g outside [0, 100]", p->quality);
    if (p->target == VV_VVC_RATE && !(p->rate > 0 && isfinite(p->rate)))
        return vv_error_set(VV_ERR_INVALID, "vvc: rate %g bits per voxel (must be > 0)", p->rate);
    if (!(p->slope >= 0 && p->slope <= 100))
        return vv_error_set(VV_ERR_INVALID, "vvc: slope %g outside [0, 100]", p->slope);
    const int version = p->version == 0 ? VV_VVC_VERSION : p->version;
    if (version != 1 && version != 2)
        return vv_error_set(VV_ERR_INVALID, "vvc: format version %d (writes 1 or 2)", p->version);
    if (!(v->range[1] >= v->range[0]) || !isfinite(v->range[0]) || !isfinite(v->range[1]))
        return vv_error_set(VV_ERR_INVALID, "vvc: the volume's value range [%g, %g] is not valid",
                            v->range[0], v->range[1]);
    if (p->target == VV_VVC_MAX_ERROR) {
        if (!(p->max_error > 0) || !isfinite(p->max_error))
            return vv_error_set(VV_ERR_INVALID, "vvc: max error %g (must be a finite number > 0)",
                                p->max_error);
        if (version == 1)
            return vv_error_set(VV_ERR_INVALID, "vvc: format version 1 has no error bound mode");
        const double lo = min_error_bound(v);
        if (p->max_error < lo)
            return vv_error_set(VV_ERR_INVALID,
                                "vvc: max error %g is below what %s values of magnitude up to %g "
                                "can hold after decoding in single precision (at least %g)",
                                p->max_error, vv_voxel_type_name(v->type),
                                fmax(fabs(v->range[0]), fabs(v->range[1])), lo);
    }
    const int M = p->block;
    vvc_scan sc;
    vv_status s = vvc_scan_init(&sc, M);
    if (s != VV_OK)
        return s;
    float *spectra = NULL;
    double offset, unit;
    const int threads = p->threads > 0 ? p->threads : vv_threads_get();
    if ((s = vv_vvc_spectra(v, M, threads, &spectra, &offset, &unit, &p->progress)) != VV_OK) {
        vvc_scan_free(&sc);
        return s;
    }
    enc en = {&sc, NULL, (size_t)sc.N, 0, threads, v, offset, unit, VVC_THETA, VVC_LAMBDA};
    en.nsub = (int)(((v->dims[0] + M - 1) / M) * (size_t)((v->dims[1] + M - 1) / M) *
                    (size_t)((v->dims[2] + M - 1) / M));
    {
        /* the M^3 independent numbers of each spectrum in scan order, so that
         * every quantisation pass reads them contiguously */
        const size_t per = 2 * (size_t)M * M * (M / 2 + 1);
        float *scanned = malloc(sizeof(float) * (size_t)sc.N * (size_t)en.nsub);
        if (!scanned) {
            fftwf_free(spectra);
            vvc_scan_free(&sc);
            return vv_error_set(VV_ERR_NOMEM, "vvc: out of memory");
        }
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int k = 0; k < en.nsub; k++) {
            const float *src = spectra + per * (size_t)k;
            float *dst = scanned + (size_t)sc.N * (size_t)k;
            for (int e = 0; e < sc.N; e++)
                dst[e] = src[sc.entry[e]];
        }
        fftwf_free(spectra);
        spectra = NULL;
        en.spectra = scanned;
    }
    double quality = p->quality, slope = p->slope, max_error = 0, bound = 0, corr_step = 0;
    if (p->target == VV_VVC_RATE) {
        const double target_bytes = p->rate * (double)vv_volume_voxel_count(v) / 8.0;
        s = search_quality(&en, version, slope, target_bytes, &p->progress, &quality);
    } else if (p->target == VV_VVC_MAX_ERROR) {
        /* A flat table whose unitary step is VVC_ERR_STEP times the bound:
         * the decoded error then exceeds the bound on few voxels, which
         * get corrections. */
        const int integer = v->type != VV_F32 && v->type != VV_F64;
        max_error = p->max_error;
        bound = integer ? floor(max_error) : max_error; /* integer data: below 1 is exact */
        corr_step = integer ? bound + 0.5 : bound;
        /* float data: a margin of 1e-5 of the bound for decoders whose FFT
         * rounds differently (integer data have the margin of the rounding) */
        if (!integer)
            bound *= 1.0 - 1e-5;
        double du = VVC_ERR_STEP * corr_step / unit;
        const double dmax = fmax(1.0, (v->range[1] - v->range[0]) / unit) * sc.N;
        du = du < dmax ? du : dmax;
        quality = 100.0 - 5.0 * log2(2.0 * du * sqrt((double)sc.N));
        slope = 0;
    }
    unsigned char *fbytes = NULL;
    size_t fsize = 0;
    if (s == VV_OK && version == 1) {
        s = encode_file(&en, v, M, quality, slope, offset, unit, &fbytes, &fsize, &p->progress);
    } else if (s == VV_OK) {
        s = encode_v2(&en, quality, slope, max_error, bound, corr_step, &fbytes, &fsize,
                      &p->progress);
        if (s == VV_OK && p->target == VV_VVC_RATE) {
            /* the estimate ignores the range coders' exact flush: step the
             * quality down until the file fits */
            const double target_bytes = p->rate * (double)vv_volume_voxel_count(v) / 8.0;
            for (int it = 0; it < 20 && s == VV_OK && (double)fsize > target_bytes && quality > 0;
                 it++) {
                free(fbytes);
                fbytes = NULL;
                quality = fmax(0, quality - 0.1);
                s = encode_v2(&en, quality, slope, 0, 0, 0, &fbytes, &fsize, &p->progress);
            }
        }
    }
    free((void *)en.spectra);
    vvc_scan_free(&sc);
    if (s != VV_OK) {
        free(fbytes);
        return vv_error_prefix(s, "vvc");
    }
    vv_vvc *c = calloc(1, sizeof *c);
    if (!c) {
        free(fbytes);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    c->bytes = fbytes;
    c->size = fsize;
    if ((s = vvc_parse(c, "(compressed)")) != VV_OK) {
        vv_vvc_free(c);
        return s;
    }
    *out = c;
    return VV_OK;
}
