/*
 * VolVis Filtering (VolVis paper, Avila et al., IEEE Visualization '94,
 * Figure 1: input data passes through "Modeling and Filtering" before it
 * reaches the World): smoothing and denoising, resampling and reshaping,
 * derivatives, and segmentation into masks and label volumes.
 *
 * Every filter reads a volume of any voxel type (borrowed, never changed)
 * and creates a new volume (*out, refcount 1, caller frees with
 * vv_volume_free) of the type the function documents. Spacing, origin,
 * direction, unit and anatomical frame are copied, or updated where the
 * filter changes the grid (resampling, crop, pad, flip, permute). The output's
 * range[] is up to date and its `modification` is VV_MOD_FILTERED (or
 * VV_MOD_RESAMPLED).
 *
 * Units: sigmas and other lengths named "world" are in the volume's world
 * units (its spacing's unit, usually mm) and are divided by each axis's
 * spacing, so anisotropic voxels are smoothed by the same physical amount
 * along every axis. Radii "in voxels" count voxels along each axis.
 *
 * Boundaries: neighbourhood filters (Gaussian, median, bilateral, the
 * derivative-of-Gaussian kernels) extend the volume by mirror reflection
 * about the edge of the outermost voxel (d c b a | a b c d | d c b a,
 * SciPy ndimage's "reflect"), repeated as often as a large kernel needs, so
 * a radius larger than the volume is well defined. Binary morphology treats
 * outside voxels as background (SciPy's border_value=0). Resampling clamps
 * to the edge voxel (Teem's "bleed").
 *
 * NaN voxels (float data): smoothing, resampling and derivatives propagate
 * them (an output voxel whose neighbourhood holds a NaN is NaN); the median
 * and bilateral filters ignore NaN neighbours (NaN only when all are);
 * thresholds, region growing and Otsu treat NaN as outside every range;
 * casting to an integer type writes 0 for NaN.
 *
 * Threads: each filter runs on vv_filter_options.threads threads (0: the
 * library default, vv_threads_get()), OpenMP threads taking rows from a
 * shared counter (vv_parallel_for, src/core/parallel_for.h, as Marching
 * Cubes). Every output voxel is computed by the same operations in the same
 * order whatever the thread count, so results are bit-identical for every
 * thread count.
 * Progress is reported through options.progress; a callback returning
 * non-zero stops the filter, which returns VV_ERR_CANCELLED and no volume.
 *
 * Thread-safety: all functions are reentrant; inputs are only read.
 * Errors: VV_ERR_INVALID (NULL arguments, parameters out of their domain,
 * with the parameter and value in the message), VV_ERR_LIMIT (sizes over the
 * volume limits, label counts over the label type), VV_ERR_NOMEM,
 * VV_ERR_CANCELLED.
 */
#ifndef VOLVIS_FILTER_H
#define VOLVIS_FILTER_H

#include <stdint.h>

#include "core.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Per-call options of every filter. */
typedef struct vv_filter_options {
    int threads;          /**< threads to use; 0: vv_threads_get() */
    vv_progress progress; /**< fraction in [0, 1]; non-zero return cancels */
} vv_filter_options;

/** Default options: library thread count, no progress. */
void vv_filter_options_init(vv_filter_options *o);

/** Largest accepted neighbourhood radius, in voxels (median, morphology, kernels). */
#define VV_FILTER_MAX_RADIUS 64

/* ---- smoothing and denoising ---------------------------------------------- */

/**
 * Gaussian smoothing, separable (three 1-D passes, i then j then k). @p sigma
 * holds the standard deviation along x, y, z in world units (each > 0); it
 * becomes sigma[a] / spacing[a] voxels along axis a. The kernel is the
 * sampled Gaussian truncated at 4 sigma (radius floor(4 sigma + 0.5) voxels)
 * and normalised to sum 1, SciPy's gaussian_filter. Output: f32.
 */
vv_status vv_filter_gaussian(const vv_volume *in, const double sigma[3], const vv_filter_options *o,
                             vv_volume **out);

/**
 * Median over the (2r+1)^3 voxel cube around each voxel, @p radius r in
 * voxels (0..VV_FILTER_MAX_RADIUS; 0 copies). For an odd count the middle
 * value; NaN neighbours are left out and an even count takes the upper
 * median. Output: the input's type (values are exact: a median is one of
 * the inputs).
 */
vv_status vv_filter_median(const vv_volume *in, int radius, const vv_filter_options *o,
                           vv_volume **out);

/**
 * Bilateral filter (Tomasi and Manduchi 1998): a Gaussian-weighted mean over
 * neighbours, the weight also a Gaussian of the value difference.
 * @p sigma_spatial in world units (> 0; window radius ceil(2 sigma) voxels
 * per axis), @p sigma_range in value units (> 0). Output: f32.
 */
vv_status vv_filter_bilateral(const vv_volume *in, double sigma_spatial, double sigma_range,
                              const vv_filter_options *o, vv_volume **out);

/**
 * Perona-Malik anisotropic diffusion (Perona and Malik 1990), explicit
 * 6-neighbour scheme: each of @p iterations steps adds @p dt times the sum
 * over the six neighbours of g(|d| / kappa) * d * (h_min / h_a)^2, where d
 * is the neighbour's difference, h_a the spacing along its axis and
 * g(x) = exp(-x^2) (edges with |d|/h_a >> kappa, in value units per world
 * unit, diffuse little). No flux through the volume's faces.
 * @p iterations in 1..10000, @p kappa > 0, @p dt in (0, 1/6] (stability).
 * Output: f32.
 */
vv_status vv_filter_diffusion(const vv_volume *in, int iterations, double kappa, double dt,
                              const vv_filter_options *o, vv_volume **out);

/* ---- resampling and reshaping --------------------------------------------- */

/** Resampling kernels (Teem's names in brackets). */
typedef enum vv_filter_kernel {
    VV_KERNEL_NEAREST = 0, /**< nearest voxel ["cheap"]; keeps the voxel type */
    VV_KERNEL_LINEAR,      /**< trilinear ["tent"] */
    VV_KERNEL_BSPLINE3,    /**< uniform cubic B-spline, approximating ["bspln3"] */
    VV_KERNEL_SINC         /**< Hann-windowed sinc, 3 lobes each side ["hann:1,3"] */
} vv_filter_kernel;

/**
 * Resamples to @p dims voxels (each 1..VV_VOLUME_MAX_DIM) over the same
 * extent: node-centred, output voxel 0 at input voxel 0 and the last at the
 * last, so the new spacing is (n - 1) h / (n' - 1) and the origin is kept.
 * Separable: i, then j, then k. When an axis is downsampled the kernel is
 * widened by the ratio (anti-aliasing, as Teem does); weights are
 * renormalised to sum 1 and samples outside clamp to the edge voxel.
 * Agrees with `unu resample -c node -k <kernel>`. Output: f32, or the input
 * type for VV_KERNEL_NEAREST.
 */
vv_status vv_filter_resample(const vv_volume *in, const int dims[3], vv_filter_kernel kernel,
                             const vv_filter_options *o, vv_volume **out);

/**
 * Resamples to the voxel @p spacing (world units, each > 0): n' = round((n -
 * 1) h / h') + 1 voxels along each axis, then as vv_filter_resample (the
 * spacing obtained is the nearest that fits the extent exactly).
 */
vv_status vv_filter_resample_spacing(const vv_volume *in, const double spacing[3],
                                     vv_filter_kernel kernel, const vv_filter_options *o,
                                     vv_volume **out);

/**
 * Crops to the voxel box lo..hi (inclusive, inside the volume, lo <= hi).
 * The origin moves to voxel lo's world position. Output: the input's type.
 */
vv_status vv_filter_crop(const vv_volume *in, const int lo[3], const int hi[3],
                         const vv_filter_options *o, vv_volume **out);

/**
 * Pads with @p before[a] and @p after[a] voxels (each >= 0) of @p value
 * (converted to the voxel type, clamped) along each axis; the origin moves
 * so the old voxels stay where they were in the world. Output: input type.
 */
vv_status vv_filter_pad(const vv_volume *in, const int before[3], const int after[3], double value,
                        const vv_filter_options *o, vv_volume **out);

/**
 * Mirrors the voxel order along @p axis (0, 1, 2) without moving the data in
 * the world: the origin becomes the old last voxel's position and the
 * axis's direction column is negated. Output: input type.
 */
vv_status vv_filter_flip(const vv_volume *in, int axis, const vv_filter_options *o,
                         vv_volume **out);

/**
 * Reorders the axes: output axis a is input axis perm[a] (a permutation of
 * 0, 1, 2); dims, spacing and direction columns follow, so voxels keep
 * their world positions. Output: input type.
 */
vv_status vv_filter_permute(const vv_volume *in, const int perm[3], const vv_filter_options *o,
                            vv_volume **out);

/**
 * Converts to voxel type @p type. @p rescale 0: values are rounded (integer
 * types) and clamped to the type's range, NaN becomes 0. @p rescale 1: the
 * input range [min, max] is mapped linearly onto the type's full range
 * (integer types) or onto [0, 1] (f32, f64) first. Output: @p type.
 */
vv_status vv_filter_cast(const vv_volume *in, vv_voxel_type type, int rescale,
                         const vv_filter_options *o, vv_volume **out);

/* ---- derivatives ---------------------------------------------------------- */

/**
 * Gradient in world coordinates (value units per world unit), through the
 * spacing and the direction matrix. @p sigma 0: central differences (one-sided
 * at the faces, so a linear ramp is exact everywhere); sigma > 0:
 * derivative-of-Gaussian with that standard deviation in world units
 * (kernels truncated at 4 sigma, normalised so a linear ramp is exact away
 * from the faces). @p out receives three f32 volumes: the x, y and z
 * components (each freed by the caller).
 */
vv_status vv_filter_gradient(const vv_volume *in, double sigma, const vv_filter_options *o,
                             vv_volume *out[3]);

/** Gradient magnitude |grad f| (see vv_filter_gradient). Output: f32. */
vv_status vv_filter_gradient_magnitude(const vv_volume *in, double sigma,
                                       const vv_filter_options *o, vv_volume **out);

/**
 * Laplacian, the sum of the second derivatives along the three axes in
 * world units (value units per world unit squared; the direction matrix is
 * taken as orthonormal, which leaves the Laplacian unchanged). @p sigma 0:
 * the 3-point second difference (mirror boundary); sigma > 0: second
 * derivative of a Gaussian, sigma in world units. Output: f32.
 */
vv_status vv_filter_laplacian(const vv_volume *in, double sigma, const vv_filter_options *o,
                              vv_volume **out);

/**
 * Frangi vesselness (Frangi, Niessen, Vincken and Viergever, MICCAI 1998):
 * at each scale sigma (world units) the scale-normalised Hessian (sigma^2
 * times second derivatives of a Gaussian) has eigenvalues
 * |l1| <= |l2| <= |l3|; V = 0 unless l2, l3 < 0 (bright tubes on a dark
 * background; @p bright 0 flips the signs for dark tubes), else
 * (1 - exp(-Ra^2 / 2 alpha^2)) exp(-Rb^2 / 2 beta^2) (1 - exp(-S^2 / 2 c^2))
 * with Ra = |l2|/|l3|, Rb = |l1|/sqrt|l2 l3|, S the Frobenius norm. The
 * output is the maximum over the @p n_scales scales (1..16). @p alpha,
 * @p beta > 0 (Frangi: 0.5); @p c > 0, or 0 for half the largest S of each
 * scale. Output: f32 in [0, 1].
 */
vv_status vv_filter_vesselness(const vv_volume *in, const double *sigmas, int n_scales,
                               double alpha, double beta, double c, int bright,
                               const vv_filter_options *o, vv_volume **out);

/* ---- segmentation --------------------------------------------------------- */

/**
 * Binary threshold: 1 where lo <= value <= hi, else 0 (NaN gives 0). Either
 * bound may be infinite (-INFINITY, INFINITY) for a one-sided threshold;
 * lo <= hi. Output: u8 mask.
 */
vv_status vv_filter_threshold(const vv_volume *in, double lo, double hi, const vv_filter_options *o,
                              vv_volume **out);

/**
 * Intensity window: (clamp(value, lo, hi) - lo) / (hi - lo), lo < hi, NaN
 * stays NaN. Output: f32 in [0, 1].
 */
vv_status vv_filter_window(const vv_volume *in, double lo, double hi, const vv_filter_options *o,
                           vv_volume **out);

/**
 * Otsu's threshold (Otsu 1979): the value t that maximises the
 * between-class variance of {v < t} and {v >= t}, from a 1024-bin histogram
 * over the volume's finite value range; where a range of splits ties (an
 * empty gap between two levels), the middle of that range. NaNs ignored.
 * Errors: VV_ERR_INVALID for a constant (or all-NaN) volume.
 */
vv_status vv_filter_otsu(const vv_volume *in, double *threshold);

/**
 * Region growing: the voxels with lo <= value <= hi connected (6, 18 or 26
 * @p connectivity) to one of the @p n_seeds seeds (voxel indices, i, j, k).
 * Every seed must lie inside the volume and in the range. Output: u8 mask.
 */
vv_status vv_filter_region_grow(const vv_volume *in, const int (*seeds)[3], int n_seeds, double lo,
                                double hi, int connectivity, const vv_filter_options *o,
                                vv_volume **out);

/**
 * Connected components of the non-zero voxels (6, 18 or 26 connectivity;
 * NaN counts as zero). Labels 1..count are given in raster order of each
 * component's first voxel (i fastest), as SciPy's ndimage.label; 0 is the
 * background. @p label_type is VV_U8, VV_U16 or VV_U32 (VV_ERR_LIMIT when
 * count exceeds its maximum). *@p sizes (may be NULL) receives a malloc'ed
 * array of count + 1 voxel counts (sizes[0]: background); *@p count (may be
 * NULL) the number of components. Output: a label volume of @p label_type.
 */
vv_status vv_filter_components(const vv_volume *in, int connectivity, vv_voxel_type label_type,
                               const vv_filter_options *o, vv_volume **labels, uint64_t **sizes,
                               uint64_t *count);

/**
 * The @p k (>= 1) largest connected components of the non-zero voxels (ties
 * go to the lower label); all of them when there are fewer. Output: u8 mask.
 */
vv_status vv_filter_largest(const vv_volume *in, int k, int connectivity,
                            const vv_filter_options *o, vv_volume **out);

/** Binary morphology operations. */
typedef enum vv_morphology {
    VV_MORPH_ERODE = 0,
    VV_MORPH_DILATE,
    VV_MORPH_OPEN, /**< erode, then dilate */
    VV_MORPH_CLOSE /**< dilate, then erode */
} vv_morphology;

/**
 * Binary morphology of the non-zero voxels with a ball of @p radius voxels
 * (1..VV_FILTER_MAX_RADIUS; the voxel offsets d with |d|^2 <= r^2, so 1 is
 * the 6-neighbour cross). Outside the volume is background. Output: u8 mask.
 */
vv_status vv_filter_morphology(const vv_volume *in, vv_morphology op, int radius,
                               const vv_filter_options *o, vv_volume **out);

/**
 * Fills holes: background voxels not 6-connected to the volume's faces
 * through background become foreground (SciPy's binary_fill_holes). Output:
 * u8 mask.
 */
vv_status vv_filter_fill_holes(const vv_volume *in, const vv_filter_options *o, vv_volume **out);

/* ---- filter chains (CLI, scene files, GUI) -------------------------------- */

/** A sequence of filter steps applied in order. Opaque; see vv_filter_chain_add. */
typedef struct vv_filter_chain vv_filter_chain;

/** One filter as the CLI and scene files name it. */
typedef struct vv_filter_info {
    const char *name;    /**< "gaussian", "median", ... (CLI: --NAME) */
    const char *metavar; /**< argument syntax, e.g. "SIGMA[,SY,SZ][v]"; never NULL */
    const char *help;    /**< one line: what it does, units, output type */
} vv_filter_info;

/** Number of filters a chain knows. */
int vv_filter_info_count(void);
/** Filter @p i (0..count-1), or NULL. */
const vv_filter_info *vv_filter_info_get(int i);
/** The filter called @p name, or NULL. */
const vv_filter_info *vv_filter_info_find(const char *name);

/** An empty chain. Errors: VV_ERR_NOMEM. */
vv_status vv_filter_chain_new(vv_filter_chain **out);
/** Frees a chain; accepts NULL. */
void vv_filter_chain_free(vv_filter_chain *c);

/**
 * Appends the filter @p name with its argument text @p arg (as on the
 * command line: "1.5", "300:", "1x1x1:linear"), checking both now so a
 * bad chain fails before any data is read. Errors: VV_ERR_INVALID with a
 * message naming the filter and the argument.
 */
vv_status vv_filter_chain_add(vv_filter_chain *c, const char *name, const char *arg);

/**
 * A chain from command-line text: "--gaussian 1.5 --median 1 --fill-holes"
 * (words separated by white space; a word starting with "--" names a
 * filter, the next word is its argument unless the filter takes none). An
 * empty text gives an empty chain. Errors: VV_ERR_INVALID naming the word.
 */
vv_status vv_filter_chain_parse(const char *text, vv_filter_chain **out);

/** Number of steps. */
int vv_filter_chain_length(const vv_filter_chain *c);

/**
 * The chain as command-line text ("--gaussian 1.5 --median 1"), owned by the
 * chain, valid until it changes. Equal texts mean equal chains (a cache key).
 */
const char *vv_filter_chain_text(const vv_filter_chain *c);

/**
 * Applies the steps in order to @p in; *@p out is a new volume (a new
 * reference to @p in for an empty chain). Progress is split evenly between
 * the steps. Errors: those of the steps, prefixed with the step ("step 2
 * (--median 1): ...").
 */
vv_status vv_filter_chain_apply(const vv_filter_chain *c, const vv_volume *in,
                                const vv_filter_options *o, vv_volume **out);

/**
 * A cache of loaded, filtered volumes (vv_filter_load_cached), owned by its
 * creator (the GUI's document holds one, so reopening a scene does not
 * filter again). Thread-safe: locked inside.
 */
typedef struct vv_filter_cache vv_filter_cache;

/** A cache of @p capacity volumes (1..64; least recently used dropped). Errors: VV_ERR_INVALID,
 * VV_ERR_NOMEM. */
vv_status vv_filter_cache_new(vv_filter_cache **out, int capacity);
/** Frees the cache and its references to the volumes (NULL: nothing). */
void vv_filter_cache_free(vv_filter_cache *cache);

/**
 * Loads the volume file @p path, applies @p chain (NULL or empty: none),
 * then sets the result's origin and voxel spacing to @p origin and
 * @p spacing where given (NULL: as loaded and filtered). With a @p cache
 * (may be NULL), the result is kept there keyed by the path, the file's
 * size and modification time, the overrides and the chain text, and found
 * again instead of filtering again; *@p out is then a new reference to a
 * volume the cache shares: treat it as read-only. Thread-safe (two threads
 * missing at once both filter, the first result is kept). Errors: those of
 * vv_volume_load and vv_filter_chain_apply.
 */
vv_status vv_filter_load_cached(vv_filter_cache *cache, const char *path, const double *origin,
                                const double *spacing, const vv_filter_chain *chain,
                                const vv_filter_options *o, vv_volume **out);

#ifdef __cplusplus
}
#endif
#endif
