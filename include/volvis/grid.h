/*
 * VolVis irregular grids: unstructured, curvilinear (multi-block) and
 * spherical grids carrying point and cell fields (VolVis paper, section 5.4:
 * data not on a rectilinear grid is rendered directly, cell by cell, after
 * Garrity, "Raytracing irregular volume data", 1990).
 *
 * Every grid keeps an explicit list of points (world units, double) and of
 * cells (VTK cell-type numbers and point indices), whatever its kind: a
 * curvilinear block is stored as its hexahedra (i fastest) with its
 * dimensions kept beside them, a spherical grid as the hexahedra of its
 * (r, theta, phi) lattice converted to Cartesian points. Renderers and
 * Marching Tetrahedra work on that one representation.
 *
 * Fields hold float values, one tuple of n_components per point (point
 * data) or per cell (cell data). A field's fill value (missing data, land in
 * an ocean model) marks values that are transparent: they are never
 * averaged into their neighbours.
 *
 * Ownership: vv_grid is reference-counted like vv_volume (vv_grid_ref,
 * vv_grid_free). Thread-safety: reading is thread-safe; building is not.
 */
#ifndef VOLVIS_GRID_H
#define VOLVIS_GRID_H

#include <stddef.h>
#include <stdint.h>

#include "core.h"
#include "math.h"
#include "mesh.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Upper limits checked against file headers before anything is allocated. */
#define VV_GRID_MAX_POINTS 200000000u /**< points of one grid */
#define VV_GRID_MAX_CELLS 200000000u  /**< cells of one grid */
#define VV_GRID_MAX_FIELDS 256        /**< fields of one grid */
#define VV_GRID_MAX_BLOCKS 4096       /**< curvilinear blocks */
#define VV_GRID_FIELD_NAME_MAX 64     /**< bytes of a field name with its NUL */

typedef enum vv_grid_kind {
    VV_GRID_UNSTRUCTURED = 0, /**< arbitrary cells (tetrahedra, hexahedra, wedges, pyramids) */
    VV_GRID_CURVILINEAR = 1,  /**< structured blocks, a point per node (PLOT3D) */
    VV_GRID_SPHERICAL = 2     /**< (r, theta, phi) lattice, each axis even or uneven */
} vv_grid_kind;

/** Cell types, numbered as VTK numbers them. */
typedef enum vv_cell_type {
    VV_CELL_VERTEX = 1,
    VV_CELL_LINE = 3,
    VV_CELL_TRIANGLE = 5,
    VV_CELL_POLYGON = 7,
    VV_CELL_QUAD = 9,
    VV_CELL_TETRA = 10,
    VV_CELL_HEXAHEDRON = 12,
    VV_CELL_WEDGE = 13,
    VV_CELL_PYRAMID = 14
} vv_cell_type;

/** Name of a cell type ("tetra", "hexahedron", ...); "unknown" otherwise. */
const char *vv_cell_type_name(int type);

/** A field on a grid. */
typedef struct vv_grid_field {
    char name[VV_GRID_FIELD_NAME_MAX];
    int cell_data;    /**< 1: one tuple per cell; 0: one per point */
    int n_components; /**< 1 (scalar) .. 9 */
    float *values;    /**< n_tuples * n_components, tuple-major; owned */
    size_t n_tuples;  /**< n_points or n_cells */
    int has_fill;     /**< 1: values equal to fill (or NaN) are missing */
    double fill;
    double range[2]; /**< min and max of the scalar (component 0, or the magnitude of
                          vectors) over the non-missing values; vv_grid_field_update_range */
} vv_grid_field;

/** An irregular grid. Fields are public for speed; change them only while building. */
typedef struct vv_grid {
    vv_grid_kind kind;
    size_t n_points;
    double *points; /**< 3 * n_points, world units; owned */
    size_t n_cells;
    uint8_t *cell_types;    /**< n_cells vv_cell_type values; owned */
    size_t *cell_offsets;   /**< n_cells + 1: the points of cell c are
                                 connectivity[cell_offsets[c] .. cell_offsets[c + 1]) */
    uint32_t *connectivity; /**< point indices in VTK's order per type; owned */
    int n_blocks;           /**< curvilinear: blocks; else 0 */
    int (*block_dims)[3];   /**< curvilinear: n_blocks x (ni, nj, nk) points; owned */
    /** spherical: axis lengths (points) and coordinates: r (world units), theta (polar
     * angle from +z, radians), phi (longitude, radians), each increasing; owned */
    int sph_dims[3];
    double *sph_axes[3];
    int n_fields;
    vv_grid_field *fields; /**< owned */
    int refcount;          /**< use vv_grid_ref / vv_grid_free */
} vv_grid;

/** An empty grid of @p kind with refcount 1. Errors: VV_ERR_NOMEM. */
vv_status vv_grid_new(vv_grid **out, vv_grid_kind kind);
/** Adds a reference; returns @p g. Atomic. */
vv_grid *vv_grid_ref(vv_grid *g);
/** Drops a reference, freeing at zero. Accepts NULL. Atomic. */
void vv_grid_free(vv_grid *g);
/** Name of a kind ("unstructured", "curvilinear", "spherical"). */
const char *vv_grid_kind_name(vv_grid_kind k);

/**
 * Allocates @p n_points points and @p n_cells cells with @p n_conn point
 * indices in all (contents zero), after checking them against the limits.
 * Errors: VV_ERR_LIMIT, VV_ERR_NOMEM. Replaces what the grid had.
 */
vv_status vv_grid_alloc(vv_grid *g, size_t n_points, size_t n_cells, size_t n_conn);

/**
 * Adds a field (values zero) and returns it in @p out (owned by the grid;
 * valid until the next field is added, which may move the array).
 * @p name is truncated to VV_GRID_FIELD_NAME_MAX - 1 bytes. Errors:
 * VV_ERR_LIMIT (too many fields), VV_ERR_INVALID (components outside 1..9),
 * VV_ERR_NOMEM.
 */
vv_status vv_grid_add_field(vv_grid *g, const char *name, int cell_data, int n_components,
                            vv_grid_field **out);

/** Recomputes f->range over the non-missing tuples (component 0, or |v| for vectors). */
void vv_grid_field_update_range(vv_grid_field *f);

/** 1 when tuple @p i of @p f is missing (fill value or NaN). */
int vv_grid_field_missing(const vv_grid_field *f, size_t i);

/**
 * The field called @p name at time step @p time: "name<time>" when it
 * exists and @p time > 0 (blow.vtk's thickness0, thickness1, ...), else
 * the field named exactly "name" (a field without time steps), else, for
 * time 0, "name0". NULL @p name: the first field. Returns its index or -1.
 */
int vv_grid_find_field(const vv_grid *g, const char *name, int time);

/**
 * Scalars of field @p field: component @p component, or the magnitude with
 * component -1 (the default for vectors; scalars ignore it). @p out gets
 * n_tuples floats (malloc'ed, the caller frees) with NaN for missing values.
 * Errors: VV_ERR_INVALID (bad field or component), VV_ERR_NOMEM.
 */
vv_status vv_grid_field_scalars(const vv_grid *g, int field, int component, float **out);

/**
 * Checks the grid: every point's coordinates finite, every cell's type known and its point count
 * right, every index below n_points, cell offsets increasing, fields sized to their points or
 * cells. Errors: VV_ERR_FORMAT with the first bad cell.
 */
vv_status vv_grid_validate(const vv_grid *g);

/**
 * Face adjacency of the grid's 3-D cells. The faces of a cell are numbered
 * in VTK's order (tetra 4: opposite points 0..3; hexahedron 6: -z, +z, -y,
 * +x, +y, -x of its corner numbering; wedge 5: the two triangles, then the
 * three quadrilaterals; pyramid 5: the base, then the four triangles).
 * @p offsets (n_cells + 1, malloc'ed) indexes @p neighbours (malloc'ed): the
 * faces of cell c are neighbours[offsets[c] .. offsets[c + 1]), each the
 * index of the cell across that face, or -1 on the boundary (cells that are
 * not 3-D have no faces). Faces match by their set of points.
 * @p n_boundary (may be NULL) gets the number of boundary faces. Errors:
 * VV_ERR_FORMAT (a face shared by three or more cells: overlapping cells),
 * VV_ERR_NOMEM. O(F log F) for F faces.
 */
vv_status vv_grid_face_adjacency(const vv_grid *g, size_t **offsets, int64_t **neighbours,
                                 size_t *n_boundary);

/** Bounding box of the points (an empty box at the origin with no points). */
vv_box vv_grid_bounds(const vv_grid *g);

/** Cells of the 3-D types and of the surface types (triangles, quads, polygons). */
void vv_grid_count_cells(const vv_grid *g, size_t *n3d, size_t *n_surface);

/**
 * A curvilinear block of ni x nj x nk points (i fastest) added to the grid:
 * its points are appended from @p xyz (3 * ni * nj * nk doubles), its
 * (ni-1)(nj-1)(nk-1) hexahedra appended to the cells, its dims to
 * block_dims. Errors: VV_ERR_LIMIT, VV_ERR_INVALID (a dimension < 2),
 * VV_ERR_NOMEM.
 */
vv_status vv_grid_add_block(vv_grid *g, const int dims[3], const double *xyz);

/**
 * A spherical grid: points r[i], theta[j], phi[k] (radians; theta from +z;
 * each axis increasing, at least 2 values) converted to
 * x = r sin(theta) cos(phi), y = r sin(theta) sin(phi), z = r cos(theta),
 * and the hexahedra of the lattice (i fastest). With @p wrap_phi the last
 * phi cell joins phi[n-1] back to phi[0] (a full circle of longitudes).
 * Errors: VV_ERR_INVALID (an axis too short or not increasing),
 * VV_ERR_LIMIT, VV_ERR_NOMEM.
 */
vv_status vv_grid_new_spherical(vv_grid **out, const double *r, int nr, const double *theta,
                                int ntheta, const double *phi, int nphi, int wrap_phi);

/**
 * The volume's voxel lattice as an unstructured grid (@p tetrahedra: each
 * cube split into 6 tetrahedra along its main diagonal, the Kuhn split,
 * whose face diagonals agree between neighbours; else hexahedra), with the
 * voxel values as point field "scalars". World positions as
 * vv_volume_index_to_world. For tests and benchmarks of the irregular
 * renderer against the ray caster. Errors: VV_ERR_INVALID (a dimension
 * < 2), VV_ERR_LIMIT, VV_ERR_NOMEM.
 */
vv_status vv_grid_new_from_volume(vv_grid **out, const vv_volume *v, int tetrahedra);

/** Grid file formats. */
typedef enum vv_grid_format {
    VV_GRID_FORMAT_AUTO = 0,
    VV_GRID_FORMAT_VTK,    /**< VTK legacy UNSTRUCTURED_GRID (.vtk), ASCII or binary */
    VV_GRID_FORMAT_VTU,    /**< VTK XML UnstructuredGrid (.vtu) */
    VV_GRID_FORMAT_DX,     /**< OpenDX native (.dx) */
    VV_GRID_FORMAT_PLOT3D, /**< PLOT3D grid (.xyz, .bin) with its solution (.q) */
    VV_GRID_FORMAT_NETCDF  /**< NetCDF with CF conventions (.nc, .cdf) */
} vv_grid_format;

/**
 * 1 when @p path looks like a grid file the build reads (by content: a VTK
 * legacy UNSTRUCTURED_GRID, a VTK XML UnstructuredGrid, an OpenDX file; by
 * name: .xyz / *xyz.bin PLOT3D, .cdf / .nc NetCDF), writing its format to
 * @p fmt (may be NULL). 0 for volume files and anything else.
 */
int vv_grid_file_detect(const char *path, vv_grid_format *fmt);

/**
 * Loads a grid file (format detected with vv_grid_file_detect). For
 * PLOT3D the solution file is found beside the grid (bluntfinxyz.bin ->
 * bluntfinq.bin, x.xyz -> x.q) when present. Errors: VV_ERR_IO,
 * VV_ERR_FORMAT (one line naming the file and the problem), VV_ERR_LIMIT,
 * VV_ERR_UNSUPPORTED (a format this build cannot read), VV_ERR_NOMEM.
 */
vv_status vv_grid_load(vv_grid **out, const char *path);

/**
 * Marching Tetrahedra: the isosurface f = @p isovalue of scalar field
 * @p field (component as vv_grid_field_scalars) through the grid's 3-D
 * cells (hexahedra, wedges and pyramids split into tetrahedra), as a
 * triangle mesh with the field value at every vertex (mesh->scalars) and
 * normals from the tetrahedra's gradients. Cell data is averaged to the
 * points first (missing values excluded); tetrahedra touching a missing
 * value are skipped. Errors: VV_ERR_INVALID, VV_ERR_NOMEM.
 */
vv_status vv_grid_isosurface(const vv_grid *g, int field, int component, double isovalue,
                             vv_mesh **out);

/**
 * The grid's surface cells (triangles, quads and polygons, fanned into
 * triangles) as a mesh, the scalars of @p field (may be -1: none) at the
 * vertices, each point moved by vector field @p displacement when it is
 * >= 0. For grids of surface cells only (blow.vtk). Errors:
 * VV_ERR_INVALID (no surface cells, bad field), VV_ERR_NOMEM.
 */
vv_status vv_grid_surface_mesh(const vv_grid *g, int field, int displacement, vv_mesh **out);

#ifdef __cplusplus
}
#endif
#endif
