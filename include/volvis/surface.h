/*
 * VolVis surface extraction: Marching Cubes isosurfaces and the Navigator's
 * two reduced-resolution previews of an isosurface, PARC subvolumes and
 * coarse Marching Cubes (VolVis paper, Avila et al., IEEE Visualization '94,
 * sections "Surface extraction" and "Navigator").
 *
 * Marching Cubes (Lorensen and Cline, SIGGRAPH '87) with the asymptotic
 * decider (Nielson and Hamann, Visualization '91) on every ambiguous face:
 * the two cells that share a face always join its contour segments the same
 * way, so the surface has no cracks or holes, and a surface that does not
 * leave the region comes out closed and 2-manifold. Ambiguities inside a
 * cell (the "tunnel" configurations of Marching Cubes 33) are not resolved:
 * the topology inside a cell can differ from the trilinear interpolant's,
 * which never opens the surface. See docs/surface.md.
 *
 * Conventions: a voxel is INSIDE when its value is >= the isovalue (NaN is
 * outside). Vertices lie on grid edges at the linearly interpolated crossing
 * and are shared by every triangle that uses the edge. Positions are world
 * coordinates (vv_volume_index_to_world: origin, direction, spacing).
 * Triangles are counter-clockwise seen from outside, the outside being the
 * side of LOWER values, so the mesh's signed volume (vv_mesh_signed_volume)
 * is the positive volume of the inside region and normals point towards
 * decreasing value (for CT bone at 300 HU: out of the bone).
 *
 * Thread-safety: every function here reads the volume only and is
 * reentrant; one vv_parc or vv_coarse_surface must not be changed by two
 * threads at once.
 */
#ifndef VOLVIS_SURFACE_H
#define VOLVIS_SURFACE_H

#include <stddef.h>
#include <stdint.h>

#include "core.h"
#include "mesh.h"
#include "model.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Options of vv_isosurface_extract; initialise with vv_isosurface_options_init. */
typedef struct vv_isosurface_options {
    int threads; /**< <= 0: vv_threads_get(), but at most one per 2^18 voxels of the region */
    int compute_normals;        /**< 1 (default): per-vertex normals from the volume gradient */
    int roi_min[3], roi_max[3]; /**< voxel index region, inclusive; roi_max[0] < 0: whole volume */
    int n_cut_planes;           /**< world-space cut planes; keeps n·(x−p) >= 0 */
    vv_cut_plane cut_planes[VV_MAX_CUT_PLANES];
    vv_progress progress;
    /**
     * Optional, borrowed: the min/max subvolume grid of this same volume
     * (vv_minmax_grid_build, any block size; the ray caster's and PARC's
     * grid). Subvolumes whose range excludes the isovalue are classified
     * without reading their voxels. NULL (default): every voxel is read.
     */
    const vv_minmax_grid *minmax;
    /**
     * Optional, borrowed: a volume with the same dimensions whose value,
     * interpolated along the edge like the vertex, becomes the per-vertex
     * scalar (mesh->scalars), e.g. to colour a surface by another field.
     * NULL (default): no scalars.
     */
    const vv_volume *scalar_volume;
} vv_isosurface_options;

/** Defaults: threads 0, compute_normals 1, whole volume, no cut planes, no progress. */
void vv_isosurface_options_init(vv_isosurface_options *o);

/**
 * Extracts the isosurface value == @p isovalue of @p v into a new indexed
 * triangle mesh (*out, refcount 1, caller frees with vv_mesh_free).
 *
 * All voxel types; anisotropic spacing and the direction matrix are applied
 * (world coordinates). Normals (when asked) are the normalised negative
 * trilinear-interpolated central-difference gradient, i.e. pointing towards
 * decreasing value; where the gradient vanishes the area-weighted face
 * normal is used. Vertex order: grid rows (k, then j), per row the crossings
 * on x, y and z edges in i order, then the row's cell-centre vertices (the
 * few tunnel configurations that need one); the output is identical for
 * every thread count. The mesh is closed where the surface does not leave the region of
 * interest, the volume or a cut plane; cut planes clip the triangles
 * exactly (new vertices where mesh edges cross a plane, shared). An
 * isovalue outside the value range gives an empty mesh (not an error).
 *
 * Errors: VV_ERR_INVALID (NULL arguments, non-finite isovalue, ROI outside
 * the volume or empty, zero cut-plane normal, scalar_volume of other
 * dimensions), VV_ERR_LIMIT (more than VV_MESH_MAX_ELEMENTS vertices or
 * triangles), VV_ERR_NOMEM, VV_ERR_CANCELLED.
 */
vv_status vv_isosurface_extract(vv_mesh **out, const vv_volume *v, double isovalue,
                                const vv_isosurface_options *opt);

/* ---- PARC subvolumes ------------------------------------------------------ */

/**
 * PARC (polygon-assisted ray casting) subvolumes: the volume divided into
 * uniform cubic boxes of `block` cells a side; the boxes that contain part
 * of the isosurface (some voxel >= the isovalue and some voxel below it) are
 * kept as a sorted list of box indices. The Navigator draws the outer faces
 * of the kept boxes as a preview (vv_parc_mesh); the ray caster and ray
 * tracer use the same list to know where the surface can be. Box
 * (bi, bj, bk) is the subvolume of the same index in `grid` (its voxels
 * include the shared boundary layer). Owned by the caller; fields read-only.
 */
typedef struct vv_parc {
    int level;              /**< subdivision level: the longest axis is split into 2^level boxes */
    int block;              /**< cells per box side */
    int dims[3];            /**< boxes per axis (grid->dims) */
    double isovalue;        /**< of the current list (NaN before vv_parc_set_isovalue) */
    size_t n_boxes;         /**< kept boxes */
    uint32_t *boxes;        /**< n_boxes indices bi + dims[0] * (bj + dims[1] * bk), ascending */
    vv_minmax_grid *grid;   /**< per-box min/max, owned */
    int volume_dims[3];     /**< voxels of the volume */
    vv_mat4 index_to_world; /**< of the volume */
    uint8_t *kept;          /**< one byte per box: 1 when in the list (owned) */
} vv_parc;

/**
 * Builds the PARC subdivision of @p v at @p level (0..16; block =
 * ceil((longest axis voxels - 1) / 2^level), at least 1): the min/max of
 * every box, once. The box list is empty until vv_parc_set_isovalue.
 * Errors: VV_ERR_INVALID (NULL, level out of range), VV_ERR_LIMIT (more
 * than 2^32 boxes), VV_ERR_NOMEM.
 */
vv_status vv_parc_new(vv_parc **out, const vv_volume *v, int level);
/**
 * Rebuilds the box list for @p isovalue from the stored min/max (no voxel
 * is read: fast enough for an isovalue slider). The min/max are floats, so
 * for u32, i32 and f64 data a box whose extreme lies within float rounding
 * of the isovalue can be misjudged. Errors: VV_ERR_INVALID
 * (NULL, non-finite isovalue), VV_ERR_NOMEM.
 */
vv_status vv_parc_set_isovalue(vv_parc *p, double isovalue);
/** 1 when box (bi, bj, bk) is in the current list (binary search), else 0. */
int vv_parc_box_kept(const vv_parc *p, int bi, int bj, int bk);
/**
 * The preview: a quad (two triangles) for every face of a kept box whose
 * neighbour is not kept, in world coordinates, counter-clockwise seen from
 * outside the boxes. Box corners are shared vertices, so the surface of
 * each group of boxes is closed (edge-connected groups may share an edge);
 * no normals: draw it flat-shaded. Errors: VV_ERR_INVALID, VV_ERR_LIMIT,
 * VV_ERR_NOMEM.
 */
vv_status vv_parc_mesh(const vv_parc *p, vv_mesh **out);
/** Releases a PARC structure. Accepts NULL. */
void vv_parc_free(vv_parc *p);

/* ---- coarse Marching Cubes ------------------------------------------------ */

/**
 * Coarse Marching Cubes: Marching Cubes on a reduced grid (every
 * stride = 2^level-th voxel of a tent-filtered copy of the volume) where
 * each edge intersection is snapped to one of four positions along the edge,
 * (code + 0.5) / 4 for code 0..3, so a vertex is its edge plus 2 bits
 * instead of three floats. The compact form is `edges` + `codes` +
 * `triangles`; vv_coarse_mesh decodes it. The reduced grid is built once
 * (vv_coarse_new); vv_coarse_set_isovalue rebuilds the surface quickly.
 */
typedef struct vv_coarse_surface {
    int level;           /**< reduction level */
    int stride;          /**< 2^level voxels per reduced cell */
    int dims[3];         /**< reduced grid voxels: (volume dims - 1) / stride + 1 */
    double isovalue;     /**< of the current surface (NaN before the first set) */
    size_t n_vertices;   /**< vertices of the current surface */
    uint32_t *edges;     /**< n_vertices edge ids 3 * (i + dims0 * (j + dims1 * k)) + axis */
    uint8_t *codes;      /**< ceil(n_vertices / 4) bytes: 2 bits per vertex, vertex v in
                              bits 2 * (v % 4) of byte v / 4 */
    size_t n_triangles;  /**< triangles of the current surface */
    uint32_t *triangles; /**< 3 * n_triangles vertex indices */
    size_t n_centres;    /**< vertices with edge id UINT32_MAX (a cell-centre vertex of a
                              tunnel configuration), stored as positions */
    float *centres;      /**< 3 * n_centres world coordinates, in vertex order */
    vv_volume *reduced;  /**< the reduced grid (f32), owned; world placement of the volume */
} vv_coarse_surface;

/**
 * Builds the reduced grid of @p v at @p level (0..8; level 0 keeps every
 * voxel and only quantizes the vertices). Errors: VV_ERR_INVALID,
 * VV_ERR_LIMIT, VV_ERR_NOMEM.
 */
vv_status vv_coarse_new(vv_coarse_surface **out, const vv_volume *v, int level);
/**
 * Extracts the coarse surface at @p isovalue with at most @p threads threads
 * (<= 0: vv_threads_get()) and at most one per 2^18 voxels of the reduced
 * grid. Errors: VV_ERR_INVALID, VV_ERR_LIMIT, VV_ERR_NOMEM.
 */
vv_status vv_coarse_set_isovalue(vv_coarse_surface *c, double isovalue, int threads);
/**
 * Decodes the compact surface into a mesh in world coordinates with
 * normals from the reduced grid's gradient. Errors: VV_ERR_INVALID,
 * VV_ERR_NOMEM.
 */
vv_status vv_coarse_mesh(const vv_coarse_surface *c, vv_mesh **out);
/** Bytes of the compact form (edges, codes, triangles). */
size_t vv_coarse_bytes(const vv_coarse_surface *c);
/** Releases a coarse surface. Accepts NULL. */
void vv_coarse_free(vv_coarse_surface *c);

/* ---- Marching Cubes on one grid face (capping isosurfaces) ---------------- */

/**
 * Area, in index units (cells of size 1 x 1), of the part of the grid face
 * axis == @p pos (0 <= pos < dims[axis]; axis 0, 1 or 2) of the region
 * @p lo .. @p hi (inclusive voxel box, within the volume) where the
 * piecewise-linear Marching Cubes field of @p v is inside (>= @p isovalue):
 * marching squares with the same edge interpolation and face decider as the
 * 3-D extraction (vv_isosurface_extract), so the caps close its surface exactly.
 * Used by the measurement of isosurface-bounded volumes and areas where a
 * surface is cut by the region's box. Never fails; thread-safe.
 */
double vv_mc_face_inside_area(const vv_volume *v, double isovalue, int axis, int pos,
                              const int lo[3], const int hi[3]);

/** Receives one polygon of @p n (3..6) points in index coordinates (see
 *  below): @p pts holds 3 * @p n doubles, x, y, z of each point in turn. */
typedef void (*vv_mc_face_polygon_fn)(void *ctx, int n, const double *pts);

/**
 * vv_mc_face_inside_area, and when @p emit is not NULL also the inside part
 * of every face cell as polygons (one per cell, two for an ambiguous face
 * whose inside corners are not joined), in index coordinates, counter-
 * clockwise in the (u, w) plane of the face, u < w the two other axes (so
 * their vector area is along e_u x e_w). @p emit is called serially, cell by
 * cell, with @p ctx. Returns the area as vv_mc_face_inside_area.
 */
double vv_mc_face_inside_polygons(const vv_volume *v, double isovalue, int axis, int pos,
                                  const int lo[3], const int hi[3], vv_mc_face_polygon_fn emit,
                                  void *ctx);

#ifdef __cplusplus
}
#endif
#endif
