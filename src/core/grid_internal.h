/*
 * Irregular grids as tetrahedra (internal): the one representation the
 * irregular renderer and Marching Tetrahedra work on.
 */
#ifndef VOLVIS_GRID_INTERNAL_H
#define VOLVIS_GRID_INTERNAL_H

#include <stdint.h>

#include "volvis/grid.h"

/**
 * A grid's 3-D cells split into positively oriented tetrahedra.
 * Tetrahedra of lattice hexahedra (curvilinear and spherical grids) follow
 * the Kuhn split (6 per cube, face diagonals agree between neighbours);
 * unstructured hexahedra, wedges and pyramids get a centre point (the mean
 * of their corners and values) and a tetrahedron per face triangle, each
 * quadrilateral face split on the diagonal through its lowest-numbered
 * point, so neighbours split a shared face alike and no crack opens.
 * Tetrahedra of zero volume (a singular axis, a pole) and those touching a
 * missing value are left out: rays leave the mesh there and re-enter.
 * Face i of a tetrahedron is the one opposite its vertex i.
 */
typedef struct vv_tetmesh {
    size_t n_points;
    double *p;   /**< 3 * n_points: the grid's points, then the cell centres */
    float *val;  /**< n_points values (point data), NULL for cell data */
    float *grad; /**< 3 * n_points: volume-weighted mean gradient of the tetrahedra at each
                      point (point data, when asked for), else NULL */
    size_t n_tets;
    uint32_t *tet;       /**< 4 * n_tets point indices, positively oriented */
    float *tval;         /**< n_tets values (cell data), NULL for point data */
    int32_t *nb;         /**< 4 * n_tets: the neighbour across face i as 4 * tet + its face, or -1
                              (a boundary face); NULL without adjacency */
    size_t n_degenerate; /**< tetrahedra left out for zero volume */
    size_t n_missing;    /**< left out for a missing value */
    double range[2];     /**< of the values kept */
} vv_tetmesh;

/**
 * Builds @p m from the 3-D cells of @p g with @p scalars (n_points values,
 * or n_cells with @p cell_data; NaN = missing). With @p adjacency the
 * neighbours are found (a face shared by three tetrahedra is an error:
 * overlapping or inverted cells); with @p gradients the point gradients.
 * Errors: VV_ERR_INVALID (no 3-D cells), VV_ERR_FORMAT, VV_ERR_LIMIT,
 * VV_ERR_NOMEM.
 */
vv_status vv_tetmesh_build(vv_tetmesh *m, const vv_grid *g, const float *scalars, int cell_data,
                           int adjacency, int gradients);
/** Releases what vv_tetmesh_build allocated; safe on a zeroed struct. */
void vv_tetmesh_clear(vv_tetmesh *m);

/** Outward vertex order of face i (opposite vertex i) of a positive tetrahedron. */
extern const int vv_tet_face[4][3];

#endif
