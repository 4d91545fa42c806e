/*
 * The .vvc decoder: one subcube's spectrum (entropy decoding and
 * dequantisation: random access through the subcube index), its inverse
 * 3-D DFT, the whole volume in parallel, and the voxel-by-voxel comparison
 * of two volumes.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "compress/rangecoder.h"
#include "compress/vvc_internal.h"
#include "core/internal.h"

/* Writes n values (rounded and clamped to the native type; NaN as 0) at element idx. */
static void
store_row(vv_volume *v, size_t idx, const float *vals, int n) {
#define VVC_STORE(T, LO, HI)                                                                       \
    do {                                                                                           \
        T *d = (T *)v->data + idx;                                                                 \
        for (int i = 0; i < n; i++) {                                                              \
            double x = vals[i];                                                                    \
            x = x == x ? floor(x + 0.5) : 0;                                                       \
            d[i] = (T)(x < (LO) ? (LO) : x > (HI) ? (HI) : x);                                     \
        }                                                                                          \
    } while (0)
    switch (v->type) {
    case VV_U8:
        VVC_STORE(uint8_t, 0, 255);
        break;
    case VV_I8:
        VVC_STORE(int8_t, -128, 127);
        break;
    case VV_U16:
        VVC_STORE(uint16_t, 0, 65535);
        break;
    case VV_I16:
        VVC_STORE(int16_t, -32768, 32767);
        break;
    case VV_U32:
        VVC_STORE(uint32_t, 0, 4294967295.0);
        break;
    case VV_I32:
        VVC_STORE(int32_t, -2147483648.0, 2147483647.0);
        break;
    case VV_F32:
        for (int i = 0; i < n; i++)
            ((float *)v->data)[idx + (size_t)i] = vals[i];
        break;
    case VV_F64:
        for (int i = 0; i < n; i++)
            ((double *)v->data)[idx + (size_t)i] = vals[i];
        break;
    }
#undef VVC_STORE
}

void
vvc_dequantise(const vvc_scan *sc, const float *step_abs, const float *recon, const int64_t *q,
               float *spectrum) {
    memset(spectrum, 0, sizeof(float) * 2 * (size_t)sc->M * sc->M * sc->H);
    if (!recon) {
        for (int e = 0; e < sc->N; e++)
            spectrum[sc->entry[e]] = (float)((double)q[e] * (double)step_abs[e]);
    } else {
        for (int e = 0; e < sc->N; e++) {
            const int64_t v = q[e];
            if (!v)
                continue;
            const double d = recon[2 * sc->band[e] + (v > 1 || v < -1)];
            spectrum[sc->entry[e]] = (float)(((double)v + (v > 0 ? d : -d)) * (double)step_abs[e]);
        }
    }
    for (int m = 0; m < sc->nmirror; m++) {
        const int from = sc->mirror[2 * m], to = sc->mirror[2 * m + 1];
        spectrum[2 * to] = spectrum[2 * from];
        spectrum[2 * to + 1] = -spectrum[2 * from + 1];
    }
}

vv_status
vvc_decode_q(const vv_vvc *c, int index, int64_t *q, vvc_corr **cr, int *ncr) {
    if (cr) {
        *cr = NULL;
        *ncr = 0;
    }
    if (c->info.version == 1)
        return vvc_decode_ints(c, index, q);
    vv_rc_dec d;
    vv_rc_dec_init(&d, c->bytes + c->data_start + c->offsets[index],
                   c->bytes + c->data_start + c->offsets[index + 1]);
    int r = vvc2_decode_block(&c->scan, &c->model, c->p0, &d, q);
    if (r == 0 && cr && c->info.corr_step > 0)
        r = vvc2_decode_corrections(&c->model, c->p0, &d, c->scan.N, cr, ncr);
    if (r == -2)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (r != 0)
        return vv_error_set(VV_ERR_FORMAT, "subcube %d: bit stream does not decode", index);
    return VV_OK;
}

vv_status
vv_vvc_decode_spectrum(const vv_vvc *c, int index, float *spectrum) {
    if (index < 0 || index >= c->nsub)
        return vv_error_set(VV_ERR_INVALID, "vvc: subcube %d out of range (0..%d)", index,
                            c->nsub - 1);
    const vvc_scan *sc = &c->scan;
    int64_t *q = calloc((size_t)sc->N + 1, sizeof *q); /* q[N] = 0: see vvc_scan.nbr */
    if (!q)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = vvc_decode_q(c, index, q, NULL, NULL);
    if (s != VV_OK) {
        free(q);
        return vv_error_prefix(s, "vvc");
    }
    vvc_dequantise(sc, c->step_abs, c->recon, q, spectrum);
    free(q);
    return VV_OK;
}

static vv_status
ensure_plan(const vv_vvc *cc) {
    vv_vvc *c = (vv_vvc *)cc;
    vv_status s = VV_OK;
    vv_fftw_lock();
    if (!c->c2r) {
        const int M = c->M;
        float *in = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * (M / 2 + 1));
        float *out = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
        if (in && out)
            c->c2r = fftwf_plan_dft_c2r_3d(M, M, M, (fftwf_complex *)in, out, FFTW_ESTIMATE);
        if (!c->c2r)
            s = vv_error_set(VV_ERR_NOMEM, "FFTW could not make a %d^3 plan", M);
        fftwf_free(in);
        fftwf_free(out);
    }
    vv_fftw_unlock();
    return s;
}

void
vvc_values(fftwf_plan c2r, int N, double unit, double offset, float *spectrum, float *values) {
    fftwf_execute_dft_c2r(c2r, (fftwf_complex *)spectrum, values);
    const float scale = (float)(unit / N);
    const float off = (float)offset;
    for (int i = 0; i < N; i++)
        values[i] = off + scale * values[i];
}

void
vvc_apply_corrections(float *values, const vvc_corr *cr, int n, double corr_step) {
    for (int i = 0; i < n; i++)
        values[cr[i].pos] = (float)((double)values[cr[i].pos] + (double)cr[i].k * corr_step);
}

/* One subcube decoded to values, corrections included (spectrum is scratch). */
static vv_status
subcube_decode(const vv_vvc *c, int index, int64_t *q, float *spectrum, float *values) {
    vvc_corr *cr = NULL;
    int ncr = 0;
    vv_status s = vvc_decode_q(c, index, q, &cr, &ncr);
    if (s != VV_OK)
        return vv_error_prefix(s, "vvc");
    vvc_dequantise(&c->scan, c->step_abs, c->recon, q, spectrum);
    vvc_values(c->c2r, c->scan.N, c->info.value_unit, c->info.value_offset, spectrum, values);
    vvc_apply_corrections(values, cr, ncr, c->info.corr_step);
    free(cr);
    return VV_OK;
}

vv_status
vv_vvc_decode_subcube(const vv_vvc *c, int index, float *values) {
    vv_status s = ensure_plan(c);
    if (s != VV_OK)
        return s;
    const int M = c->M;
    if (index < 0 || index >= c->nsub)
        return vv_error_set(VV_ERR_INVALID, "vvc: subcube %d out of range (0..%d)", index,
                            c->nsub - 1);
    float *sp = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * (M / 2 + 1));
    float *vals = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
    int64_t *q = calloc((size_t)c->scan.N + 1, sizeof *q);
    if (!sp || !vals || !q) {
        fftwf_free(sp);
        fftwf_free(vals);
        free(q);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    if ((s = subcube_decode(c, index, q, sp, vals)) == VV_OK)
        memcpy(values, vals, sizeof(float) * (size_t)M * M * M);
    fftwf_free(sp);
    fftwf_free(vals);
    free(q);
    return s;
}

vv_status
vv_vvc_decompress(vv_volume **out, const vv_vvc *c, int threads, const vv_progress *progress) {
    *out = NULL;
    vv_status s = ensure_plan(c);
    if (s != VV_OK)
        return s;
    vv_volume *v;
    if ((s = vv_volume_new(&v, c->info.dims, c->info.type)) != VV_OK)
        return vv_error_prefix(s, "vvc");
    for (int i = 0; i < 3; i++) {
        v->spacing[i] = c->info.spacing[i];
        v->origin[i] = c->info.origin[i];
    }
    memcpy(v->direction, c->info.direction, sizeof v->direction);
    v->unit = c->info.unit;
    v->data_origin = c->info.data_origin;
    v->modification = c->info.modification;
    v->space = c->info.space;
    const int M = c->M;
    const int *nb = c->info.subcubes;
    const int nthreads = threads > 0 ? threads : vv_threads_get();
    int failed = 0, cancelled = 0;
    long done = 0;
    char msg[256] = "";
#pragma omp parallel num_threads(nthreads)
    {
        float *sp = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * (M / 2 + 1));
        float *vals = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
        int64_t *q = calloc((size_t)c->scan.N + 1, sizeof *q);
#pragma omp for schedule(dynamic, 4)
        for (int k = 0; k < c->nsub; k++) {
            if (failed || cancelled)
                continue;
            if (!sp || !vals || !q) {
                failed = 1;
                continue;
            }
            if (subcube_decode(c, k, q, sp, vals) != VV_OK) {
#pragma omp critical(vvc_err)
                {
                    if (!failed)
                        snprintf(msg, sizeof msg, "%s", vv_error_message());
                    failed = 2;
                }
                continue;
            }
            const int bx = k % nb[0], by = (k / nb[0]) % nb[1], bz = k / (nb[0] * nb[1]);
            const int nx = v->dims[0] - bx * M < M ? v->dims[0] - bx * M : M;
            for (int z = 0; z < M; z++) {
                const int kk = bz * M + z;
                if (kk >= v->dims[2])
                    break;
                for (int y = 0; y < M; y++) {
                    const int jj = by * M + y;
                    if (jj >= v->dims[1])
                        break;
                    store_row(v,
                              ((size_t)kk * v->dims[1] + (size_t)jj) * v->dims[0] + (size_t)bx * M,
                              vals + (z * M + y) * M, nx);
                }
            }
            if (progress && progress->fn) {
#pragma omp critical(vvc_progress)
                {
                    done++;
                    if (vv_progress_report(progress, (double)done / c->nsub))
                        cancelled = 1;
                }
            }
        }
        fftwf_free(sp);
        fftwf_free(vals);
        free(q);
    }
    if (failed || cancelled) {
        vv_volume_free(v);
        if (cancelled && !failed)
            return vv_error_set(VV_ERR_CANCELLED, "cancelled");
        if (failed == 2)
            return vv_error_set(VV_ERR_FORMAT, "%s", msg);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

vv_status
vv_volume_compare(const vv_volume *a, const vv_volume *b, double *psnr, double *rmse,
                  double *max_error) {
    for (int i = 0; i < 3; i++)
        if (a->dims[i] != b->dims[i])
            return vv_error_set(VV_ERR_INVALID, "compare: dimensions %dx%dx%d and %dx%dx%d differ",
                                a->dims[0], a->dims[1], a->dims[2], b->dims[0], b->dims[1],
                                b->dims[2]);
    double se = 0, mx = 0, lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < a->dims[2]; k++)
        for (int j = 0; j < a->dims[1]; j++)
            for (int i = 0; i < a->dims[0]; i++) {
                const double x = vv_volume_get(a, i, j, k), y = vv_volume_get(b, i, j, k);
                const double d = fabs(x - y);
                se += d * d;
                mx = d > mx ? d : mx;
                lo = x < lo ? x : lo;
                hi = x > hi ? x : hi;
            }
    const double mse = se / (double)vv_volume_voxel_count(a);
    const double peak = hi - lo;
    if (psnr)
        *psnr = mse == 0 ? INFINITY : 10.0 * log10(peak * peak / mse);
    if (rmse)
        *rmse = sqrt(mse);
    if (max_error)
        *max_error = mx;
    return VV_OK;
}
