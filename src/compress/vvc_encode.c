/*
 * The .vvc encoder: the subcube spectra in scan order, symbol statistics and
 * Huffman tables, the search of the quality for a target rate and the
 * coding of every subcube (vv_vvc_compress).
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

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
} enc;

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
        int64_t *q = malloc(sizeof *q * (size_t)en->sc->N);
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
        int64_t *q = malloc(sizeof *q * (size_t)sc->N);
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
    s = vvc_write_file(v, M, quality, slope, offset, unit, qtab, t, streams, en->nsub, bytes, size);
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
    if (p->target == VV_VVC_QUALITY && !(p->quality >= 0 && p->quality <= 100))
        return vv_error_set(VV_ERR_INVALID, "vvc: quality %g outside [0, 100]", p->quality);
    if (p->target == VV_VVC_RATE && !(p->rate > 0 && isfinite(p->rate)))
        return vv_error_set(VV_ERR_INVALID, "vvc: rate %g bits per voxel (must be > 0)", p->rate);
    if (!(p->slope >= 0 && p->slope <= 100))
        return vv_error_set(VV_ERR_INVALID, "vvc: slope %g outside [0, 100]", p->slope);
    if (!(v->range[1] >= v->range[0]) || !isfinite(v->range[0]) || !isfinite(v->range[1]))
        return vv_error_set(VV_ERR_INVALID, "vvc: the volume's value range [%g, %g] is not valid",
                            v->range[0], v->range[1]);
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
    enc en = {&sc, NULL, (size_t)sc.N, 0, threads};
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
    double quality = p->quality;
    if (p->target == VV_VVC_RATE) {
        const int H = M / 2 + 1;
        float *qtab = malloc(sizeof(float) * (size_t)H * H * H);
        float *step_abs = malloc(sizeof(float) * (size_t)sc.N);
        if (!qtab || !step_abs) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        } else {
            const double target_bytes = p->rate * (double)vv_volume_voxel_count(v) / 8.0;
            /* The file grows with quality and log(size) is nearly linear in
             * it: regula falsi on log(size / target) (Illinois variant), keeping
             * the bracket [lo (fits), hi (too big)]; stops within 0.3 % of the
             * target or after 16 sizes. */
            double lo = 0, hi = 100, flo = 0, fhi = 0;
            uint64_t bytes = 0;
            int side = 0;
            vvc_make_table(qtab, M, hi, p->slope);
            vvc_make_step_abs(&sc, qtab, step_abs);
            s = count_file_bytes(&en, step_abs, M, &bytes);
            fhi = log((double)bytes / target_bytes);
            if (s == VV_OK && fhi <= 0) {
                lo = hi;
            } else if (s == VV_OK) {
                vvc_make_table(qtab, M, lo, p->slope);
                vvc_make_step_abs(&sc, qtab, step_abs);
                s = count_file_bytes(&en, step_abs, M, &bytes);
                flo = log((double)bytes / target_bytes);
                for (int it = 0; it < 14 && s == VV_OK && flo < 0 && flo < -0.003; it++) {
                    double mid = lo - flo * (hi - lo) / (fhi - flo);
                    if (!(mid > lo && mid < hi))
                        mid = 0.5 * (lo + hi);
                    vvc_make_table(qtab, M, mid, p->slope);
                    vvc_make_step_abs(&sc, qtab, step_abs);
                    if ((s = count_file_bytes(&en, step_abs, M, &bytes)) != VV_OK)
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
                    if (vv_progress_report(&p->progress, 0.3 + 0.4 * (it + 1) / 14.0)) {
                        s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
                        break;
                    }
                }
            }
            quality = lo;
        }
        free(qtab);
        free(step_abs);
    }
    unsigned char *fbytes = NULL;
    size_t fsize = 0;
    if (s == VV_OK)
        s = encode_file(&en, v, M, quality, p->slope, offset, unit, &fbytes, &fsize, &p->progress);
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
