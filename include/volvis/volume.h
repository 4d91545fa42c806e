/*
 * VolVis volume: a rectilinear scalar volume in its native voxel type.
 *
 * Layout: voxel (i, j, k) with i fastest, data[k][j][i], i.e. byte offset
 * ((k * dims[1] + j) * dims[0] + i) * voxel_size. Node-centred:
 *   world = origin + direction * (spacing ∘ (i, j, k)).
 * direction is a row-major 3x3 matrix whose COLUMNS are the unit axis
 * directions of i, j and k in world space (identity unless the file gave one).
 * Spacing and origin are in world units (usually millimetres).
 *
 * Ownership: a volume is reference-counted. vv_volume_new() returns a count
 * of 1; vv_volume_ref() adds one; vv_volume_free() drops one and frees the
 * volume at zero. The fields are public for speed; change data only before
 * sharing the volume, and call vv_volume_update_range() (and bump
 * `modified`) after changing voxels so caches notice.
 *
 * Thread-safety: reading and sampling are thread-safe; ref/free are atomic.
 */
#ifndef VOLVIS_VOLUME_H
#define VOLVIS_VOLUME_H

#include <stddef.h>
#include <stdint.h>

#include "core.h"
#include "math.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Native voxel types. */
typedef enum vv_voxel_type {
    VV_U8 = 0,
    VV_I8,
    VV_U16,
    VV_I16,
    VV_U32,
    VV_I32,
    VV_F32,
    VV_F64
} vv_voxel_type;

/**
 * Length unit of the spacing: SLC's enumeration (0 .. 5), then nanometres,
 * which SLC cannot name (electron microscopy: Neuroglancer precomputed's
 * resolution, OME-Zarr's "nanometer"). The values are stored in .vvb and
 * .vvc headers; SLC and NIfTI, which hold no nanometres, are written in
 * microns.
 */
typedef enum vv_unit {
    VV_UNIT_METER = 0,
    VV_UNIT_MM = 1,
    VV_UNIT_MICRON = 2,
    VV_UNIT_FOOT = 3,
    VV_UNIT_INCH = 4,
    VV_UNIT_UNKNOWN = 5,
    VV_UNIT_NM = 6 /**< nanometres (not in SLC's enumeration) */
} vv_unit;

/** The largest vv_unit value: header checks accept 0 .. VV_UNIT_LAST. */
#define VV_UNIT_LAST VV_UNIT_NM

/** Where the data came from (SLC's "data origin" enumeration). */
typedef enum vv_data_origin {
    VV_ORIGIN_BIORAD_CONFOCAL = 0,
    VV_ORIGIN_MRI = 1,
    VV_ORIGIN_CT = 2,
    VV_ORIGIN_SIMULATION = 3,
    VV_ORIGIN_BINARY_VOXELIZED = 4,
    VV_ORIGIN_FUZZY_VOXELIZED = 5,
    VV_ORIGIN_FUNCTION_VOXELIZED = 6,
    VV_ORIGIN_OTHER = 7
} vv_data_origin;

/** What was done to the data (SLC's "modification" enumeration). */
typedef enum vv_modification {
    VV_MOD_ORIGINAL = 0,
    VV_MOD_RESAMPLED = 1,
    VV_MOD_RESAMPLED_FILTERED = 2,
    VV_MOD_FILTERED = 3,
    VV_MOD_OTHER = 4
} vv_modification;

/**
 * The anatomical frame world coordinates are given in, when the file says:
 * RAS (+x right, +y anterior, +z superior; NIfTI) or LPS (+x left, +y
 * posterior, +z superior; DICOM, many NRRD files). Used to put default views
 * in front of a patient.
 */
typedef enum vv_space { VV_SPACE_UNKNOWN = 0, VV_SPACE_RAS = 1, VV_SPACE_LPS = 2 } vv_space;

/** Largest accepted size along one axis. */
#define VV_VOLUME_MAX_DIM 65536
/** Largest accepted voxel count (2^33, i.e. 8 G voxels). */
#define VV_VOLUME_MAX_VOXELS (((uint64_t)1) << 33)
/** Largest accepted data size in bytes (32 GiB). */
#define VV_VOLUME_MAX_BYTES (((uint64_t)32) << 30)

typedef struct vv_volume {
    int dims[3];         /**< voxels along i, j, k; each >= 1 */
    double spacing[3];   /**< world units between voxel centres, > 0 */
    double origin[3];    /**< world position of voxel (0, 0, 0) */
    double direction[9]; /**< row-major 3x3; columns are the i, j, k axes */
    vv_voxel_type type;  /**< native voxel type of data */
    double range[2];     /**< min and max voxel value (vv_volume_update_range) */
    void *data;          /**< dims[0]*dims[1]*dims[2] voxels; owned */
    vv_unit unit;        /**< length unit of spacing and origin */
    vv_data_origin data_origin;
    vv_modification modification;
    vv_space space;    /**< anatomical frame of world coordinates, if known */
    uint64_t modified; /**< bumped on each change, for caches */
    int refcount;      /**< use vv_volume_ref / vv_volume_free */
    /** Who releases data at the last vv_volume_free: NULL (the library's own
        allocation, free()), else a callback (vv_volume_wrap). */
    void (*release)(void *user, void *data);
    void *release_user; /**< passed to release */
} vv_volume;

/**
 * Short name of a length unit: "m", "mm", "um", "ft", "in", "nm"; "unknown" for
 * VV_UNIT_UNKNOWN and out-of-range values. Never NULL.
 */
const char *vv_unit_name(vv_unit u);

/**
 * The word to print after a length of @p v: its unit's short name when
 * known, "voxel units" for a volume of unknown unit and unit spacing,
 * else "units" (also for NULL). Static storage; reentrant.
 */
const char *vv_volume_length_unit(const vv_volume *v);

/**
 * Parses a unit name: the short names of vv_unit_name and the usual long
 * forms ("millimeter(s)", "micron(s)", "micrometer(s)", "µm" with the micro
 * sign or the Greek mu, "nanometer(s)", "inch(es)", "foot", "feet",
 * "meter(s)"; also the British "-metre" spellings). Anything else gives
 * VV_UNIT_UNKNOWN.
 */
vv_unit vv_unit_parse(const char *name);

/** Bytes per voxel of a type (1, 2, 4 or 8). */
size_t vv_voxel_type_size(vv_voxel_type t);
/** Lower-case name: "u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64". */
const char *vv_voxel_type_name(vv_voxel_type t);
/** Parses a name as printed by vv_voxel_type_name (also "uchar", "short", "float", ...). */
vv_status vv_voxel_type_parse(const char *name, vv_voxel_type *out);

/**
 * Checks that a volume of @p dims voxels of type @p t is within the limits
 * above (each dimension in [1, VV_VOLUME_MAX_DIM], no overflow, total voxels
 * and bytes within VV_VOLUME_MAX_*, bytes within the memory budget of
 * vv_memory_budget_get()). On success stores the byte count in
 * *bytes (may be NULL). Errors: VV_ERR_LIMIT with a message giving the size.
 * Readers call this on header values before allocating anything.
 */
vv_status vv_volume_check_size(const int dims[3], vv_voxel_type t, uint64_t *bytes);

/**
 * Allocates a zero-filled volume with unit spacing, zero origin, identity
 * direction, range [0, 0], refcount 1. Errors: VV_ERR_LIMIT (see
 * vv_volume_check_size), VV_ERR_NOMEM.
 */
vv_status vv_volume_new(vv_volume **out, const int dims[3], vv_voxel_type t);

/**
 * A volume over voxels the caller owns (no copy): @p data holds
 * dims[0]*dims[1]*dims[2] voxels of type @p t, i fastest, and must stay valid
 * and unmoved until the volume's last reference is dropped, when
 * @p release(@p user, @p data) is called (release may be NULL: the caller
 * frees the memory some other way after the last vv_volume_free). Geometry
 * and metadata are the defaults of vv_volume_new; range[] is computed
 * (vv_volume_update_range). The library only reads the voxels; whoever
 * changes them calls vv_volume_update_range afterwards so that caches see
 * the change. Used by the Python package to share a numpy array's memory.
 * The release callback may run on any thread that drops the last reference
 * (a renderer's cache, a World). Errors: VV_ERR_INVALID (NULL data),
 * VV_ERR_LIMIT (see vv_volume_check_size), VV_ERR_NOMEM; on failure release
 * is not called.
 */
vv_status vv_volume_wrap(vv_volume **out, const int dims[3], vv_voxel_type t, void *data,
                         void (*release)(void *user, void *data), void *user);

/** Adds a reference; returns @p v. */
vv_volume *vv_volume_ref(vv_volume *v);

/**
 * Drops a reference; frees at zero (the voxels by free(), or by the release
 * callback of a vv_volume_wrap volume). Accepts NULL.
 */
void vv_volume_free(vv_volume *v);

/** Number of voxels. */
uint64_t vv_volume_voxel_count(const vv_volume *v);

/** Recomputes range[] from the data and bumps `modified`. NaNs are ignored. */
void vv_volume_update_range(vv_volume *v);

/**
 * Element @p i of voxel data of type @p t as double (for loops over
 * vv_volume.data; no bounds check). Thread-safe.
 */
static inline double
vv_voxel_value(vv_voxel_type t, const void *data, size_t i) {
    switch (t) {
    case VV_U8:
        return ((const uint8_t *)data)[i];
    case VV_I8:
        return ((const int8_t *)data)[i];
    case VV_U16:
        return ((const uint16_t *)data)[i];
    case VV_I16:
        return ((const int16_t *)data)[i];
    case VV_U32:
        return ((const uint32_t *)data)[i];
    case VV_I32:
        return ((const int32_t *)data)[i];
    case VV_F32:
        return ((const float *)data)[i];
    case VV_F64:
        return ((const double *)data)[i];
    }
    return 0;
}

/** Value of voxel (i, j, k) as double; indices must be inside. */
double vv_volume_get(const vv_volume *v, int i, int j, int k);

/** Sets voxel (i, j, k), converting (rounding, clamping) to the native type. */
void vv_volume_set(vv_volume *v, int i, int j, int k, double value);

/**
 * Index-to-world matrix: world = M (i, j, k, 1). Includes direction, spacing
 * and origin.
 */
vv_mat4 vv_volume_index_to_world(const vv_volume *v);

/** World-to-index matrix (inverse of vv_volume_index_to_world). */
vv_mat4 vv_volume_world_to_index(const vv_volume *v);

/** World-space bounding box of the node-centred grid (all 8 corners). */
vv_box vv_volume_world_box(const vv_volume *v);

/**
 * Trilinear sample at continuous index coordinates (x, y, z), clamped to the
 * grid. Returns the interpolated value as float.
 */
float vv_volume_sample_index(const vv_volume *v, double x, double y, double z);

/**
 * Trilinear sample at world position @p p. Returns 1 and stores the value
 * when p is inside the grid box, 0 (and *value = 0) outside.
 */
int vv_volume_sample_world(const vv_volume *v, vv_vec3 p, float *value);

/**
 * Gradient at world position @p p, in value units per world unit: central
 * differences of trilinear samples half a voxel apart along each index axis,
 * mapped to world axes through the direction matrix. Returns 1 inside the
 * grid box, 0 outside (gradient zero).
 */
int vv_volume_gradient_world(const vv_volume *v, vv_vec3 p, vv_vec3 *gradient);

/**
 * Histogram of all voxels into @p nbins equal bins over [lo, hi] (values
 * outside are clamped into the end bins; NaNs are skipped). @p bins has
 * nbins entries and is overwritten. Errors: VV_ERR_INVALID if nbins < 1 or
 * hi <= lo.
 */
vv_status vv_volume_histogram(const vv_volume *v, int nbins, double lo, double hi, uint64_t *bins);

/**
 * The value below which a fraction @p q of the voxels lies (q in [0, 1]),
 * estimated from a 4096-bin histogram over range[]. Used to build default
 * transfer functions.
 */
double vv_volume_quantile(const vv_volume *v, double q);

/**
 * The @p n quantiles @p q[0..n-1] (each in [0, 1]) of the voxels into
 * @p out[0..n-1], from one 4096-bin histogram over range[] (one pass over
 * the voxels: vv_volume_quantile n times makes n). A volume of one value
 * gives that value; where the histogram cannot be allocated, the linear
 * interpolation of range[]. Thread-safe for distinct @p out.
 */
void vv_volume_quantiles(const vv_volume *v, int n, const double *q, double *out);

/**
 * Minimum and maximum of the voxel values over uniform subvolumes: the
 * subvolume grid behind PARC (polygon-assisted ray casting; VolVis paper,
 * section 4, Navigator) and empty-space skipping. Subvolume (bi, bj, bk)
 * covers the cells with index i in [bi*block, (bi+1)*block] (its voxels
 * include the shared boundary layer, so a cell never straddles two
 * subvolumes unseen), likewise j and k, clamped to the grid. An axis of one
 * voxel has one subvolume. min and max hold dims[0]*dims[1]*dims[2] floats,
 * bi fastest; NaN voxels are ignored (an all-NaN subvolume has min +inf,
 * max -inf). Owned by the grid.
 */
typedef struct vv_minmax_grid {
    int block;   /**< cells per subvolume side, >= 1 */
    int dims[3]; /**< subvolumes per axis: max(1, ceil((volume dims - 1) / block)) */
    float *min;
    float *max;
} vv_minmax_grid;

/**
 * Builds the min/max grid of @p v with subvolumes of @p block cells a side
 * (OpenMP-parallel). Errors: VV_ERR_INVALID (block < 1), VV_ERR_NOMEM.
 * Thread-safe with respect to @p v (reads only).
 */
vv_status vv_minmax_grid_build(vv_minmax_grid **out, const vv_volume *v, int block);
/** Releases a grid. Accepts NULL. */
void vv_minmax_grid_free(vv_minmax_grid *g);

/**
 * A volume read box by box: voxels lo .. hi (inclusive, x, y, z) as a new
 * volume of hi - lo + 1 voxels a side and the volume's type (voxel
 * (0, 0, 0) is voxel lo), which the caller frees. vv_bricked_read_box and
 * vv_pyramid_read_box (level 0) fit it with a one-line adapter; the writers
 * of OME-Zarr and .vvb (io.h, bricks.h) and vv_measure_histogram_boxes
 * (measure.h) take one.
 */
typedef vv_status (*vv_box_reader)(void *ctx, const int lo[3], const int hi[3], vv_volume **out);

#ifdef __cplusplus
}
#endif
#endif
