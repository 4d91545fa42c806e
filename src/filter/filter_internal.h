/*
 * Internal pieces shared by the files of src/filter (not installed): the
 * row-parallel loop, row conversion from any voxel type, output volumes
 * that copy an input's geometry, mirror indexing and 1-D kernels.
 */
#ifndef VV_FILTER_INTERNAL_H
#define VV_FILTER_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "core/parallel_for.h"
#include "volvis/filter.h"

/** Most threads a filter uses. */
#define VF_MAX_THREADS 64
#if VF_MAX_THREADS > VV_PARALLEL_MAX_THREADS
#error "a filter cannot use more threads than vv_parallel_for"
#endif

/** Threads a filter with options @p o uses (1..VF_MAX_THREADS). */
int vf_threads(const vv_filter_options *o);

/**
 * Body of a parallel loop: items [i0, i1) on worker @p w (0..threads-1).
 * Items are handed out in chunks from a shared counter; a body must compute
 * each item independently of which worker runs it (determinism).
 */
typedef vv_parallel_fn vf_body;

/**
 * vv_parallel_for over items 0..n-1 in chunks of @p chunk on vf_threads(o)
 * threads (the caller is worker 0): worker 0 reports progress p0..p1 after
 * each of its chunks and p1 at the end; a cancel stops every worker.
 * Returns VV_OK or VV_ERR_CANCELLED ("filter: cancelled").
 */
vv_status vf_parallel(const vv_filter_options *o, long n, long chunk, vf_body body, void *ctx,
                      double p0, double p1);

/** Reports @p f to o's progress; VV_ERR_CANCELLED (with a message) on cancel, else VV_OK. */
vv_status vf_report(const vv_filter_options *o, double f);

/**
 * A new zero-filled volume of @p dims and @p type with @p in's spacing,
 * origin, direction, unit, space and data origin; modification FILTERED.
 */
vv_status vf_new_like(const vv_volume *in, const int dims[3], vv_voxel_type type, vv_volume **out);

/** Converts @p n voxels of type @p t from @p src (element offset @p off) to float. */
void vf_load_f(vv_voxel_type t, const void *src, size_t off, size_t n, float *dst);
/** Converts to double. */
void vf_load_d(vv_voxel_type t, const void *src, size_t off, size_t n, double *dst);
/** Stores @p n doubles into type @p t (rounded and clamped for integers, NaN -> 0). */
void vf_store_d(vv_voxel_type t, void *dst, size_t off, size_t n, const double *src);

/** Mirror index into 0..n-1 (d c b a | a b c d | d c b a), any integer i. */
static inline int
vf_reflect(long i, int n) {
    if (n == 1)
        return 0;
    long p = 2L * n;
    long m = i % p;
    if (m < 0)
        m += p;
    return (int)(m < n ? m : p - 1 - m);
}

/** A 1-D convolution kernel: w[0..2r], centred on w[r]; out[i] = sum_t w[t] f[i + t - r]. */
typedef struct vf_kernel {
    int r;
    float *w;
} vf_kernel;

/**
 * Sampled Gaussian derivative kernel of @p order (0, 1, 2), @p sigma in
 * voxels (> 0), truncated at 4 sigma. Order 0 sums to 1; order 1 is exact
 * for a ramp (sum t w = 1 with f[i + t]), order 2 has sum 0 and sum t^2 w = 2.
 */
vv_status vf_kernel_gauss(vf_kernel *k, double sigma, int order);
void vf_kernel_free(vf_kernel *k);

/**
 * Separable convolution of the voxels of @p data (type @p t, @p dims) with
 * k[0] along i, k[1] along j, k[2] along k (mirror boundary); a NULL kernel
 * skips that axis. @p out (dims voxels, f32) receives the result; @p tmp is
 * scratch of the same size. Progress p0..p1.
 */
vv_status vf_separable(const void *data, vv_voxel_type t, const int dims[3],
                       const vf_kernel *const k[3], float *out, float *tmp,
                       const vv_filter_options *o, double p0, double p1);

/** Rejects NULL volume and output arguments with a message naming @p what. */
vv_status vf_check_io(const vv_volume *in, const void *out, const char *what);

/** f32 mask test: non-zero and not NaN. */
static inline int
vf_nonzero(double v) {
    return v != 0.0 && v == v;
}

/** A u8 mask (0/1) of the non-zero voxels of @p in (parallel). Caller frees. */
vv_status vf_mask_u8(const vv_volume *in, const vv_filter_options *o, uint8_t **mask);

/**
 * Connected components of a u8 mask (non-zero = foreground). Labels 1..count
 * in raster order of first voxels; @p labels (dims voxels of u32, zeroed by
 * the caller) receives them; sizes (count + 1, malloc'ed) as in vv_filter_components.
 */
vv_status vf_label_mask(const uint8_t *mask, const int dims[3], int connectivity,
                        const vv_filter_options *o, double p0, double p1, uint32_t *labels,
                        uint64_t **sizes, uint64_t *count);

/** Parses "nearest", "linear", "bspline" (or "cubic"), "sinc"; VV_ERR_INVALID otherwise. */
vv_status vv_filter_kernel_parse(const char *name, vv_filter_kernel *out);

#endif
