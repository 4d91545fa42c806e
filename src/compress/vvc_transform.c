/*
 * The .vvc subcube transform: the forward real-to-complex 3-D DFT (FFTW) of
 * every M^3 subcube of a volume in coded values, and the lock that
 * serialises FFTW's planner. The inverse transform is in vvc_decode.c.
 */
#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "compress/vvc_internal.h"
#include "core/internal.h"

static pthread_mutex_t fftw_lock = PTHREAD_MUTEX_INITIALIZER;

void
vv_fftw_lock(void) {
    pthread_mutex_lock(&fftw_lock);
}

void
vv_fftw_unlock(void) {
    pthread_mutex_unlock(&fftw_lock);
}

/* ---------------------------------------------------------------------- */
/* Forward transform of every subcube                                       */

vv_status
vv_vvc_spectra(const vv_volume *v, int M, int threads, float **spectra, double *offset,
               double *unit, const vv_progress *progress) {
    *spectra = NULL;
    const int H = M / 2 + 1;
    const int nb[3] = {(v->dims[0] + M - 1) / M, (v->dims[1] + M - 1) / M,
                       (v->dims[2] + M - 1) / M};
    const size_t nsub = (size_t)nb[0] * nb[1] * nb[2];
    const size_t per = 2 * (size_t)M * M * H;
    const uint64_t bytes = (uint64_t)nsub * per * sizeof(float);
    if (bytes > (((uint64_t)48) << 30))
        return vv_error_set(VV_ERR_LIMIT, "spectra of %zu subcubes would take %llu bytes", nsub,
                            (unsigned long long)bytes);
    vv_vvc_value_scale(v, offset, unit);
    float *out = fftwf_malloc(bytes ? (size_t)bytes : 1);
    float *tmp_in = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
    float *tmp_out = fftwf_malloc(sizeof(float) * per);
    if (!out || !tmp_in || !tmp_out) {
        fftwf_free(out);
        fftwf_free(tmp_in);
        fftwf_free(tmp_out);
        return vv_error_set(VV_ERR_NOMEM, "out of memory (%llu bytes of spectra)",
                            (unsigned long long)bytes);
    }
    vv_fftw_lock();
    fftwf_plan plan =
        fftwf_plan_dft_r2c_3d(M, M, M, tmp_in, (fftwf_complex *)tmp_out, FFTW_ESTIMATE);
    vv_fftw_unlock();
    if (!plan) {
        fftwf_free(out);
        fftwf_free(tmp_in);
        fftwf_free(tmp_out);
        return vv_error_set(VV_ERR_NOMEM, "FFTW could not make a %d^3 plan", M);
    }
    const double off = *offset, inv = 1.0 / *unit;
    int nthreads = threads > 0 ? threads : vv_threads_get();
    int cancelled = 0;
    long done = 0;
#pragma omp parallel num_threads(nthreads)
    {
        float *in = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
        float *sp = fftwf_malloc(sizeof(float) * per);
#pragma omp for schedule(dynamic, 4)
        for (long s = 0; s < (long)nsub; s++) {
            if (cancelled || !in || !sp)
                continue;
            const int bx = (int)(s % nb[0]), by = (int)((s / nb[0]) % nb[1]),
                      bz = (int)(s / ((long)nb[0] * nb[1]));
            for (int z = 0; z < M; z++)
                for (int y = 0; y < M; y++) {
                    const int j = by * M + y, k = bz * M + z;
                    float *row = in + (z * M + y) * M;
                    int x = 0;
                    if (j < v->dims[1] && k < v->dims[2]) {
                        const size_t base =
                            ((size_t)k * v->dims[1] + (size_t)j) * v->dims[0] + (size_t)bx * M;
                        const int nx = v->dims[0] - bx * M < M ? v->dims[0] - bx * M : M;
                        for (; x < nx; x++) {
                            const double d = vv_voxel_at(v, base + (size_t)x);
                            row[x] = d == d ? (float)((d - off) * inv) : 0.0f;
                        }
                    }
                    for (; x < M; x++)
                        row[x] = 0; /* padding: the minimum */
                }
            fftwf_execute_dft_r2c(plan, in, (fftwf_complex *)sp);
            memcpy(out + (size_t)s * per, sp, sizeof(float) * per);
            if (progress && progress->fn) {
#pragma omp critical(vvc_progress)
                {
                    done++;
                    if (vv_progress_report(progress, 0.3 * (double)done / (double)nsub))
                        cancelled = 1;
                }
            }
        }
        if (!in || !sp)
            cancelled = 2;
        fftwf_free(in);
        fftwf_free(sp);
    }
    vv_fftw_lock();
    fftwf_destroy_plan(plan);
    vv_fftw_unlock();
    fftwf_free(tmp_in);
    fftwf_free(tmp_out);
    if (cancelled) {
        fftwf_free(out);
        return cancelled == 2 ? vv_error_set(VV_ERR_NOMEM, "out of memory")
                              : vv_error_set(VV_ERR_CANCELLED, "cancelled");
    }
    *spectra = out;
    return VV_OK;
}
