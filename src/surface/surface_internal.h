/*
 * Internal pieces of the surface component shared with src/measure: the
 * Marching Cubes case tables, the extraction with coarse-mode extras, exact
 * mesh clipping by a plane, and the marching-squares area of the inside
 * region on a grid face (the caps that close a surface cut by the volume
 * boundary, built with the same interpolation and asymptotic decider as the
 * mesh, so mesh + caps is a closed polyhedron).
 */
#ifndef VOLVIS_SURFACE_INTERNAL_H
#define VOLVIS_SURFACE_INTERNAL_H

#include <stdint.h>

#include "volvis/mesh.h"
#include "volvis/surface.h"
#include "volvis/volume.h"

/** Most triangles and centre vertices one cell configuration produces. */
#define MC_MAX_TRI 16
#define MC_MAX_CENTRE 4

/** One cell configuration: a case plus the decisions of its ambiguous faces. */
typedef struct mc_config {
    uint8_t n_tri;
    uint8_t n_centre;                     /**< extra vertices inside the cell */
    uint16_t centre_edges[MC_MAX_CENTRE]; /**< edges whose crossings centre c averages */
    /** vertices: cell edge numbers 0..11, or 12 + c for centre vertex c; counter-clockwise
     * seen from outside */
    uint8_t tri[MC_MAX_TRI][3];
} mc_config;

/** The case tables, built once (thread-safe) by mc_tables_get. */
typedef struct mc_tables {
    uint16_t base[256];       /**< first configuration of each case */
    uint8_t n_amb[256];       /**< ambiguous faces of the case */
    uint8_t amb_face[256][6]; /**< their face numbers, in the bit order of the decision index */
    uint16_t edge_mask[256];  /**< bit e set when edge e crosses the surface */
    int n_configs;
    mc_config *configs;
} mc_tables;

/* Cube numbering: corner c at (c&1 ^ (c>>1&1), c>>1&1, c>>2&1): 0 (0,0,0), 1 (1,0,0),
 * 2 (1,1,0), 3 (0,1,0), 4..7 the same at z = 1. Edge e joins mc_edge_corner[e]. */
extern const int mc_edge_corner[12][2];
/** Face f's corners in cyclic order: 0 z=0, 1 z=1, 2 y=0, 3 y=1, 4 x=0, 5 x=1. */
extern const int mc_face_corner[6][4];

const mc_tables *mc_tables_get(void);

/**
 * Asymptotic decider on a face with corner values (minus the isovalue) in
 * cyclic order w0..w3, ambiguous (w0, w2 on one side, w1, w3 on the other):
 * returns 1 when the two INSIDE corners are joined (the face's saddle is
 * inside). Symmetric in the face's orientation, so both cells agree.
 */
static inline int
mc_face_joined(double w0, double w1, double w2, double w3) {
    if (w0 >= 0) /* w0, w2 inside */
        return w0 * w2 >= w1 * w3;
    return w1 * w3 >= w0 * w2;
}

/** Extras of the extraction used by coarse Marching Cubes. */
typedef struct mc_extra {
    int quantize;       /**< snap each crossing to (code + 0.5) / 4 along its edge */
    uint32_t *edge_ids; /**< out (malloc'ed): per vertex 3 * voxel index + axis (whole grid) */
    uint8_t *codes;     /**< out (malloc'ed): per vertex the 2-bit code (one byte each) */
    /** 1 (with quantize): the edge vertices get no positions, the mesh has no vertices
     * (n_vertices 0) and only its triangles are valid; the cell-centre vertices' positions
     * go to centres, in vertex order. No normals, scalars or cut planes. */
    int edges_only;
    size_t n_vertices; /**< out with edges_only: the vertices the triangles index */
    size_t n_centres;  /**< out with edges_only */
    float *centres;    /**< out with edges_only (malloc'ed): 3 floats per centre vertex */
} mc_extra;

/** vv_isosurface_extract with extras (x may be NULL). */
vv_status vv_isosurface_extract_ex(vv_mesh **out, const vv_volume *v, double isovalue,
                                   const vv_isosurface_options *opt, mc_extra *x);

/**
 * Clips @p m in place to the half-space n·x + d >= 0: triangles wholly
 * outside go, triangles across are cut exactly with one new vertex per cut
 * mesh edge (shared by both triangles of the edge; normals and scalars
 * interpolated); unused vertices are dropped. Errors: VV_ERR_NOMEM,
 * VV_ERR_LIMIT.
 */
vv_status vv_mesh_clip_plane(vv_mesh *m, vv_vec3 n, double d);

#endif
