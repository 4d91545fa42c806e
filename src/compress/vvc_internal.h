/* Internal helpers of the .vvc codec shared with the `fourier` renderer. */
#ifndef VV_COMPRESS_VVC_INTERNAL_H
#define VV_COMPRESS_VVC_INTERNAL_H

#include <fftw3.h>

#include "volvis/compress.h"

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

#endif
