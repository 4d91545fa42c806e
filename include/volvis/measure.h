/*
 * VolVis Measurement (VolVis paper, Avila et al., IEEE Visualization '94,
 * section "Measurement"): histograms of a volume or a region, the volume
 * and surface area of an isosurface (whole volume or a surface-tracked
 * section) by voxel counting and by Marching Cubes, distances between
 * points, and area, enclosed volume and distance of geometric surface
 * models (meshes).
 *
 * Every length, area and volume is in world units (the volume's unit,
 * vv_unit_name(v->unit); the spacing and direction matrix are applied) and
 * accumulated in double. Inside means value >= isovalue, as in
 * vv_isosurface_extract.
 *
 * Thread-safety: all functions read their inputs only and are reentrant.
 */
#ifndef VOLVIS_MEASURE_H
#define VOLVIS_MEASURE_H

#include <stddef.h>
#include <stdint.h>

#include "core.h"
#include "mesh.h"
#include "model.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A region of interest (ROI) of a volume, what Measurement measures within: a voxel
 *  box and cut planes (not a render region: docs/architecture.md, "Glossary"). */
typedef struct vv_roi {
    int roi_min[3], roi_max[3]; /**< voxel index box, inclusive; roi_max[0] < 0: whole volume */
    int n_cut_planes;           /**< world-space cut planes; a voxel counts when n·(x−p) >= 0 */
    vv_cut_plane cut_planes[VV_MAX_CUT_PLANES];
} vv_roi;

/** The whole volume, no cut planes. */
void vv_roi_init(vv_roi *r);

/* ---- histogram ------------------------------------------------------------ */

/** A histogram of voxel values, from vv_measure_histogram. Owned by the caller. */
typedef struct vv_histogram {
    int nbins;        /**< bins over [lo, hi], each (hi - lo) / nbins wide */
    double lo, hi;    /**< value range of the bins */
    uint64_t *counts; /**< nbins counts; values outside [lo, hi] are not counted */
    uint64_t total;   /**< voxels in the region (NaN excluded) */
    uint64_t outside; /**< of those, values below lo or above hi */
    uint64_t nan;     /**< NaN voxels in the region */
    double min, max;  /**< of the voxels in the region (NaN when empty) */
    double mean, sd;  /**< of the voxels in the region */
} vv_histogram;

/**
 * Histogram of the voxels of @p v in @p region (NULL: whole volume) into
 * @p nbins equal bins over [lo, hi]; lo >= hi (e.g. 0, 0) takes the
 * region's own value range. A value equal to hi goes into the last bin.
 * Parallel (OpenMP), deterministic. Errors: VV_ERR_INVALID (NULL, nbins
 * outside 1..1048576, region outside the volume, non-finite lo/hi, zero
 * cut-plane normal, empty region), VV_ERR_NOMEM.
 */
vv_status vv_measure_histogram(vv_histogram **out, const vv_volume *v, int nbins, double lo,
                               double hi, const vv_roi *region);
/**
 * vv_measure_histogram of the whole volume @p hdr describes (dims, type; its
 * voxels are not read), read box by box through @p read (boxes of at most
 * 128 x 128 x 64 voxels, x fastest, each read twice: the statistics, then
 * the bins), so that a volume larger than memory is measured at full
 * resolution: a pyramid's level 0 (vv_pyramid_read_box), a bricked file
 * (vv_bricked_read_box), slabs of a stack (vv_slabs_read_box). The counts,
 * min and max are vv_measure_histogram's of the whole volume exactly; the
 * mean and standard deviation may differ in the last bits (sums in another
 * order). @p progress (may be NULL) reports 0 to 1 and can cancel. Errors:
 * VV_ERR_INVALID (as vv_measure_histogram; a box of another shape from
 * @p read), VV_ERR_NOMEM, VV_ERR_CANCELLED, the reader's.
 */
vv_status vv_measure_histogram_boxes(vv_histogram **out, const vv_volume *hdr, vv_box_reader read,
                                     void *ctx, int nbins, double lo, double hi,
                                     const vv_progress *progress);
/** Releases a histogram. Accepts NULL. */
void vv_histogram_free(vv_histogram *h);
/**
 * Draws @p h as a bar chart into a PNG (cairo) of width x height pixels
 * (each 200..8192): axes with ticks, tick labels, axis titles ("value"
 * and "voxels", or @p xlabel), the title @p title (may be NULL) and the
 * voxel count; log_scale draws log10(1 + count). Written atomically.
 * Errors: VV_ERR_INVALID, VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_histogram_plot_png(const vv_histogram *h, const char *path, int width, int height,
                                const char *title, const char *xlabel, int log_scale);

/* ---- joint histogram of value x gradient magnitude ------------------------ */

/**
 * A joint histogram of data value and gradient magnitude, for editing 2-D
 * transfer functions (Kniss, Kindlmann and Hansen 2002; vv_tf2d). Owned by
 * the caller. Gradient magnitudes are in data units per world unit of the
 * volume's own coordinates (spacing and direction applied): central
 * differences in index space (one-sided at the faces) mapped by the
 * inverse transpose of the volume's index-to-world matrix, as the ray
 * caster and ray tracer compute them for vv_tf2d. Counts are linear; a log
 * scale is the caller's (the GUI's) choice.
 */
typedef struct vv_histogram2d {
    int nbins_value;                 /**< bins along the value axis */
    int nbins_gradient;              /**< bins along the gradient-magnitude axis */
    double value_lo, value_hi;       /**< value range of the bins */
    double gradient_lo, gradient_hi; /**< gradient-magnitude range (gradient_lo is 0) */
    /** nbins_gradient rows of nbins_value counts: counts[g * nbins_value + v],
     * row 0 the smallest gradient magnitudes */
    uint64_t *counts;
    uint64_t total;      /**< voxels counted (NaN values and gradients excluded) */
    uint64_t outside;    /**< of all non-NaN voxels, those outside both ranges' box */
    double gradient_max; /**< largest gradient magnitude of the volume */
} vv_histogram2d;

/**
 * Joint histogram of the voxels of @p v: @p nbins_value x @p nbins_gradient
 * equal bins over [value_lo, value_hi] x [0, gradient_hi]. value_lo >=
 * value_hi takes the volume's range; gradient_hi <= 0 takes the largest
 * gradient magnitude. A value equal to a range's upper end goes into the
 * last bin. Deterministic; parallel (OpenMP). Errors: VV_ERR_INVALID (NULL,
 * bins outside 1..65536, non-finite ranges), VV_ERR_NOMEM.
 */
vv_status vv_histogram2d_compute(vv_histogram2d **out, const vv_volume *v, int nbins_value,
                                 int nbins_gradient, double value_lo, double value_hi,
                                 double gradient_hi);
/** Releases a joint histogram. Accepts NULL. */
void vv_histogram2d_free(vv_histogram2d *h);

/* ---- isosurface volume and area ------------------------------------------- */

typedef enum vv_measure_method {
    /** Marching Cubes: area of the triangles (clipped to the cut planes); volume by the
     * divergence theorem over the triangles plus the caps where the inside region meets the
     * region's boundary: the box faces and the cut planes (exact for the piecewise-linear
     * surface, also when the volume boundary or a cut plane cuts it). */
    VV_MEASURE_MC = 0,
    /** Voxel counting: volume = voxels inside x voxel volume; area = exposed voxel faces,
     * which overestimates a smooth surface (by 3/2 averaged over orientations). */
    VV_MEASURE_VOXEL = 1
} vv_measure_method;

typedef struct vv_isosurface_measure_options {
    vv_measure_method method; /**< default VV_MEASURE_MC */
    /** 1: measure only the surface-tracked section: the 6-connected component of inside
     * voxels (flood fill) containing the inside voxel nearest to seed. */
    int has_seed;
    double seed[3]; /**< voxel index coordinates (fractional allowed) */
    vv_roi region;  /**< default whole volume; both methods take cut planes */
    int threads;    /**< <= 0: vv_threads_get() */
    vv_progress progress;
} vv_isosurface_measure_options;

/** Defaults: Marching Cubes, no seed, whole volume, default threads. */
void vv_isosurface_measure_options_init(vv_isosurface_measure_options *o);

typedef struct vv_isosurface_measure {
    vv_measure_method method;
    double isovalue;
    double area;        /**< isosurface area, world units^2 (caps not included) */
    double volume;      /**< volume of the inside region, world units^3 */
    double cut_area;    /**< where the inside region meets the region's boundary
                             (MC: the caps; voxel: boundary voxel faces), world units^2 */
    uint64_t voxels;    /**< inside voxels counted (in the section when seeded) */
    size_t n_triangles; /**< Marching Cubes triangles (0 for voxel counting) */
    double area_bias;   /**< expected area ratio measured/true: 1.5 for voxel faces, 1 for MC */
    int seed_voxel[3];  /**< the voxel the section grew from (when seeded) */
    vv_unit unit;       /**< the volume's length unit */
} vv_isosurface_measure;

/**
 * Measures the isosurface value == @p isovalue of @p v (see
 * vv_measure_method). Errors: VV_ERR_INVALID (NULL, isovalue outside
 * (range[0], range[1]] so that there is no surface, seed outside the volume
 * or with no inside voxel within 2 voxels, bad region, fewer than 2 voxels
 * on an axis for MC), VV_ERR_NOMEM, VV_ERR_CANCELLED. With cut planes and
 * a seed, the section is grown from the voxels the planes keep; voxels the
 * planes remove keep their values for Marching Cubes, so the section's
 * surface reaches the plane unchanged and is clipped there.
 */
vv_status vv_measure_isosurface(vv_isosurface_measure *out, const vv_volume *v, double isovalue,
                                const vv_isosurface_measure_options *opt);

/**
 * vv_measure_isosurface by @p method of the whole volume @p hdr describes
 * (dims, spacing, direction, value range; its voxels are not read), read
 * box by box through @p read (boxes of 128 x 128 x 64 voxels; voxel
 * counting reads a ghost voxel beyond each inner face, Marching Cubes one
 * beyond each upper inner face, so that the boxes' cells tile the
 * volume's), so that a volume larger than memory is measured at full
 * resolution. Voxel counting: the voxels counted, the volume, the faces
 * between inside and outside voxels and those on the volume's boundary
 * (cut_area) of the whole volume. Marching Cubes: the triangles' area and
 * count; each box's inside volume by the divergence theorem closed by caps
 * on its six faces (the caps of a face two boxes share cancel), summed;
 * cut_area the caps on the volume's own faces; the voxels inside. Equal to
 * vv_measure_isosurface of the whole volume up to the rounding of sums in
 * another order. No region or seed: a surface-tracked section needs the
 * whole volume. @p progress (may be NULL) reports and can cancel. Errors:
 * VV_ERR_INVALID (an isovalue outside the range, an unknown method, fewer
 * than 2 voxels along an axis for Marching Cubes, a box of another shape),
 * VV_ERR_CANCELLED, VV_ERR_NOMEM, the reader's.
 */
vv_status vv_measure_isosurface_boxes(vv_isosurface_measure *out, const vv_volume *hdr,
                                      vv_box_reader read, void *ctx, double isovalue,
                                      vv_measure_method method, const vv_progress *progress);

/**
 * The Marching Cubes surface that vv_measure_isosurface measures with
 * VV_MEASURE_MC (method ignored): the whole surface in the region, or the
 * surface-tracked section when seeded, with normals; cut planes clip it.
 * *out is new (caller frees). Errors: as vv_measure_isosurface.
 */
vv_status vv_measure_isosurface_mesh(vv_mesh **out, const vv_volume *v, double isovalue,
                                     const vv_isosurface_measure_options *opt);

/* ---- distances -------------------------------------------------------------- */

/**
 * Euclidean distance in world units between points @p a and @p b, each in
 * world coordinates or, when its *_voxel flag is 1, in voxel index
 * coordinates of @p v (mapped by vv_volume_index_to_world; fractional
 * allowed). Errors: VV_ERR_INVALID (voxel coordinates without a volume,
 * non-finite coordinates).
 */
vv_status vv_measure_distance(const vv_volume *v, vv_vec3 a, int a_voxel, vv_vec3 b, int b_voxel,
                              double *out);

/**
 * Geodesic distance along the surface of mesh @p m between the points of
 * the mesh closest to @p a and @p b (stored in a_on, b_on; may be NULL):
 * the shortest path in the Steiner graph of the mesh (Lanthier, Maheshwari
 * and Sack 2001) with @p steiner points per edge (0..64; 8 is a good
 * default): within every triangle each pair of its boundary points (vertices
 * and Steiner points) is joined by a straight segment. The result is the
 * length of a real path on the surface (never below the true geodesic of
 * the mesh) and approaches it roughly as 1/steiner^2: on a Marching Cubes
 * plane +4.3 % with no Steiner points, +0.25 % with 6, +0.18 % with 8
 * (tested). Serial;
 * memory O(triangles x steiner). Errors: VV_ERR_INVALID (NULL, empty mesh,
 * steiner out of range, points on different connected parts),
 * VV_ERR_NOMEM.
 */
vv_status vv_measure_geodesic(const vv_mesh *m, vv_vec3 a, vv_vec3 b, int steiner, double *out,
                              vv_vec3 *a_on, vv_vec3 *b_on);

/* ---- meshes ------------------------------------------------------------------- */

/**
 * Enclosed volume of a closed mesh (divergence theorem, positive for
 * outward winding). Errors: VV_ERR_INVALID when the mesh is open or
 * non-manifold (the message gives the boundary and non-manifold edge
 * counts) or has no triangles, VV_ERR_NOMEM.
 */
vv_status vv_measure_mesh_volume(const vv_mesh *m, double *volume);

/**
 * Minimum distance between the surfaces of meshes @p a and @p b (0 when
 * they intersect), with the closest points (pa, pb may be NULL): exact
 * triangle-triangle distances with a bounding-volume hierarchy over b,
 * parallel over a's triangles. Errors: VV_ERR_INVALID (NULL, empty mesh),
 * VV_ERR_NOMEM.
 */
vv_status vv_measure_mesh_distance(const vv_mesh *a, const vv_mesh *b, int threads, double *dist,
                                   vv_vec3 *pa, vv_vec3 *pb);

/* ---- geometric objects --------------------------------------------------------- */

/** What vv_measure_object reports, world units. */
typedef struct vv_object_measure {
    double area;        /**< surface area of the tessellation */
    double volume;      /**< enclosed volume (solids: sphere, box, capped cylinder, mesh), else 0 */
    int solid;          /**< the shape encloses a volume */
    size_t n_triangles; /**< of the tessellation measured */
} vv_object_measure;

/**
 * Area and enclosed volume of a geometric object of the World (sphere, box,
 * cylinder, polygon, mesh) in world units, placed by its transform: sums
 * over its tessellation within @p tolerance world units of the surface (the
 * geometry-type table's, src/model/geometry.h; <= 0: 1/1000 of the object's
 * size). Exact for flat shapes; a curved one comes out smaller by about
 * 2 tolerance / radius relative (inscribed facets). Errors: VV_ERR_INVALID
 * (NULL, not geometry, a plane (unbounded), a broken shape), VV_ERR_NOMEM.
 */
vv_status vv_measure_object(const vv_object *obj, double tolerance, vv_object_measure *out);

/**
 * Minimum distance between the surfaces of two geometric objects of the
 * World (world units, 0 when they touch or cross), with the closest points
 * (pa, pb may be NULL): vv_measure_mesh_distance between their
 * tessellations within @p tolerance (as vv_measure_object), so within
 * tolerance of the exact distance. Errors: as vv_measure_object.
 */
vv_status vv_measure_object_distance(const vv_object *a, const vv_object *b, double tolerance,
                                     int threads, double *dist, vv_vec3 *pa, vv_vec3 *pb);

/* ---- label volumes -------------------------------------------------------- */

/** What vv_measure_labels reports for one label. */
typedef struct vv_label_stats {
    uint32_t label;             /**< 1.. */
    uint64_t voxels;            /**< voxels with this label */
    double volume;              /**< voxels times the voxel volume, world units cubed */
    vv_vec3 centroid;           /**< mean world position of its voxels */
    int box_min[3], box_max[3]; /**< voxel index bounding box, inclusive */
} vv_label_stats;

/**
 * Per-label measurement of a label volume (vv_filter_components; Filtering
 * component): for every label >= 1 present, its voxel count, volume,
 * centroid and bounding box. *@p out receives a malloc'ed array of *@p n
 * entries in ascending label order (NULL when there are none); the caller
 * frees it. Voxel values must be whole numbers (any type); 0 and negative
 * values are background. Errors: VV_ERR_INVALID (NULL, a non-integer or NaN
 * value, with its voxel), VV_ERR_LIMIT (a label above 2^24), VV_ERR_NOMEM.
 * Reentrant.
 */
vv_status vv_measure_labels(const vv_volume *labels, vv_label_stats **out, int *n);

/* ---- colocalisation of two channels --------------------------------------- */

/** What vv_measure_colocalisation reports (Measurement, per channel pair). */
typedef struct vv_colocalisation {
    uint64_t voxels;     /**< voxels measured: inside the mask, both values finite */
    double pearson;      /**< Pearson's correlation coefficient r of the two channels' values
                              over those voxels, in [-1, 1]; NaN when either is constant */
    double manders_m1;   /**< Manders' M1: the fraction of channel A's intensity above its
                              threshold that lies where B is above its threshold, in [0, 1];
                              NaN when no A value is above its threshold */
    double manders_m2;   /**< Manders' M2: the same for B against A */
    double threshold[2]; /**< the thresholds used, in data values (A, B) */
    double mean[2];      /**< the channels' mean values over the voxels measured */
} vv_colocalisation;

/**
 * Colocalisation of two channels @p a and @p b of one image (the same
 * dims; voxel (i, j, k) of each is the same place): Pearson's correlation
 * coefficient and Manders' overlap coefficients M1 and M2, over the voxels
 * where @p mask (NULL: every voxel; else the same dims) is non-zero and both
 * values are finite. With thresholds tA, tB (data values; voxels above them
 * count as signal, as Costes et al. threshold them),
 *   M1 = Σ A_i [A_i > tA ∧ B_i > tB] / Σ A_i [A_i > tA],
 *   M2 = Σ B_i [B_i > tB ∧ A_i > tA] / Σ B_i [B_i > tB];
 * tA = tB = 0 gives Manders' original coefficients for non-negative data.
 * Pearson's r is computed in two passes (the means first) in double.
 * Sources: Manders, Verbeek and Aten, "Measurement of co-localization of
 * objects in dual-colour confocal images", J. Microscopy 169 (1993);
 * Costes et al., "Automatic and quantitative measurement of protein-protein
 * colocalization in live cells", Biophysical Journal 86 (2004), for the
 * thresholds. Deterministic for any thread count (sums per slice, then in
 * slice order). Errors: VV_ERR_INVALID (NULL, dims that differ, named; a
 * threshold that is not finite), VV_ERR_NOMEM. Reentrant.
 */
vv_status vv_measure_colocalisation(const vv_volume *a, const vv_volume *b, const vv_volume *mask,
                                    double threshold_a, double threshold_b, vv_colocalisation *out);

#ifdef __cplusplus
}
#endif
#endif
