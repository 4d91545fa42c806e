/*
 * VolVis triangle meshes: the geometric surface models of the VolVis paper
 * (Avila et al., IEEE Visualization '94): what Marching Cubes produces, what
 * the Modeling component voxelizes and what the geometry renderer draws.
 *
 * Layout: an indexed triangle mesh with shared vertices. positions holds
 * 3 * n_vertices floats (x, y, z per vertex, world units), normals (optional)
 * 3 * n_vertices floats (unit, pointing outwards), scalars (optional)
 * n_vertices floats, triangles 3 * n_triangles vertex indices. A closed
 * mesh's triangles are counter-clockwise seen from outside, so the signed
 * volume is positive.
 *
 * Ownership: a mesh is reference-counted like vv_volume: vv_mesh_new gives a
 * count of 1, vv_mesh_ref adds one, vv_mesh_free drops one and frees at zero.
 * Thread-safety: reading is thread-safe; building and changing are not.
 */
#ifndef VOLVIS_MESH_H
#define VOLVIS_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "core.h"
#include "math.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Limits checked before allocating (vertices and triangles each). */
#define VV_MESH_MAX_ELEMENTS ((size_t)1 << 31)

typedef struct vv_mesh {
    size_t n_vertices;
    size_t cap_vertices;
    float *positions; /**< 3 * n_vertices, world units */
    float *normals;   /**< 3 * n_vertices unit vectors, or NULL */
    float *scalars;   /**< n_vertices, or NULL */
    size_t n_triangles;
    size_t cap_triangles;
    uint32_t *triangles; /**< 3 * n_triangles vertex indices */
    int refcount;        /**< use vv_mesh_ref / vv_mesh_free */
} vv_mesh;

/** An empty mesh without normals or scalars. Errors: VV_ERR_NOMEM. */
vv_status vv_mesh_new(vv_mesh **out);
/** Adds a reference; returns @p m. Atomic. */
vv_mesh *vv_mesh_ref(vv_mesh *m);
/** Drops a reference; frees at zero. Accepts NULL. Atomic. */
void vv_mesh_free(vv_mesh *m);

/**
 * Makes room for at least @p n_vertices vertices and @p n_triangles triangles
 * in total (normals and scalars too where present). Errors: VV_ERR_LIMIT
 * over VV_MESH_MAX_ELEMENTS, VV_ERR_NOMEM.
 */
vv_status vv_mesh_reserve(vv_mesh *m, size_t n_vertices, size_t n_triangles);
/**
 * Gives the mesh per-vertex normals (with_normals) and/or scalars
 * (with_scalars), zero-filled for existing vertices. Errors: VV_ERR_NOMEM.
 */
vv_status vv_mesh_enable_attributes(vv_mesh *m, int with_normals, int with_scalars);
/**
 * Appends a vertex (normal and scalar 0 where the mesh has them); its index
 * goes to @p index (may be NULL). Errors: VV_ERR_LIMIT, VV_ERR_NOMEM.
 */
vv_status vv_mesh_add_vertex(vv_mesh *m, vv_vec3 p, uint32_t *index);
/** Appends a triangle. Errors: VV_ERR_INVALID (an index out of range), VV_ERR_LIMIT, VV_ERR_NOMEM.
 */
vv_status vv_mesh_add_triangle(vv_mesh *m, uint32_t a, uint32_t b, uint32_t c);
/** Position of vertex @p i. */
vv_vec3 vv_mesh_vertex(const vv_mesh *m, size_t i);

/**
 * Sets per-vertex normals to the area-weighted sum of the adjacent face
 * normals, normalised (enabling normals if absent). Errors: VV_ERR_NOMEM.
 */
vv_status vv_mesh_compute_normals(vv_mesh *m);
/** Bounding box of the vertices (an empty box at the origin if none). */
vv_box vv_mesh_bounds(const vv_mesh *m);
/**
 * Transforms positions by @p M and normals by its inverse transpose
 * (renormalised). A reflection (negative determinant) also reverses every
 * triangle's winding so outward stays outward.
 */
void vv_mesh_transform(vv_mesh *m, vv_mat4 M);

/** Total triangle area, world units squared (accumulated in double). */
double vv_mesh_area(const vv_mesh *m);
/**
 * Signed enclosed volume by the divergence theorem, sum over triangles of
 * p0 · (p1 × p2) / 6, world units cubed. Meaningful for closed meshes;
 * positive when triangles are counter-clockwise seen from outside.
 */
double vv_mesh_signed_volume(const vv_mesh *m);

/** Edge topology of a mesh, from vv_mesh_topology_compute. */
typedef struct vv_mesh_topology {
    size_t n_vertices_used;     /**< vertices referenced by a triangle */
    size_t n_edges;             /**< distinct undirected edges */
    size_t n_boundary_edges;    /**< edges with one triangle */
    size_t n_nonmanifold_edges; /**< edges with three or more triangles */
    size_t n_misoriented_edges; /**< two-triangle edges traversed the same way by both */
    size_t n_degenerate;        /**< triangles with a repeated vertex index */
    long euler;                 /**< V - E + F over used vertices */
    int closed;                 /**< no boundary and no non-manifold edges */
    int oriented;               /**< every two-triangle edge is traversed both ways */
} vv_mesh_topology;

/**
 * Counts edges by how many triangles share them (vertex indices, not
 * positions, so a mesh must share its vertices to come out closed).
 * Errors: VV_ERR_NOMEM.
 */
vv_status vv_mesh_topology_compute(const vv_mesh *m, vv_mesh_topology *out);

/**
 * Loads a triangle mesh through Assimp (OBJ, PLY, STL, OFF and every other
 * format Assimp reads), triangulated, with identical vertices joined and all
 * meshes of the file merged in their node transforms. Normals are kept when
 * the file has them. Errors: VV_ERR_IO (unreadable), VV_ERR_FORMAT (Assimp's
 * message, or no triangles), VV_ERR_LIMIT, VV_ERR_NOMEM; the message names
 * the file.
 */
vv_status vv_mesh_load(vv_mesh **out, const char *path);

/**
 * Writes @p m atomically in the format its extension names: .ply (binary
 * little-endian), .obj, .stl (binary), .glb (glTF 2.0 binary, for Blender
 * and the web; Assimp's exporter), .vtp (VTK XML PolyData with the
 * per-vertex scalars as a point field); normals are written
 * where the format holds them. Errors: VV_ERR_INVALID (unknown extension,
 * empty mesh), VV_ERR_IO.
 */
vv_status vv_mesh_save(const vv_mesh *m, const char *path);

#ifdef __cplusplus
}
#endif
#endif
