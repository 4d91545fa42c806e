/*
 * Internals of the Modeling component shared by its files (not installed):
 * the shape node, the per-primitive distance functions, mesh scan
 * conversion, and the JSON reader of models used by scene files.
 */
#ifndef VV_MODELING_INTERNAL_H
#define VV_MODELING_INTERNAL_H

#include <jansson.h>

#include "volvis/modeling.h"

typedef enum shape_kind {
    SHAPE_SPHERE,
    SHAPE_ELLIPSOID,
    SHAPE_BOX,
    SHAPE_TORUS,
    SHAPE_REVOLUTION, /* also cylinder and cone */
    SHAPE_EXTRUSION,  /* also the thick planar polygon (with a frame) */
    SHAPE_HELIX,
    SHAPE_MESH,
    SHAPE_CSG
} shape_kind;

struct vv_shape {
    shape_kind kind;
    const char *name; /* primitive name for messages */
    vv_mat4 M;        /* node -> parent */
    vv_mat4 frame;    /* shape coordinates -> node coordinates (the polygon's plane) */
    double p[6];      /* sizes: see each constructor */
    int n;            /* 2-D polygon points */
    double *pts;      /* 2n doubles */
    double pbox[4];   /* bounding box of pts: min x, min y, max x, max y */
    vv_mesh *mesh;
    vv_mesh_mode mesh_mode;
    double thickness;
    vv_csg_op op;
    int n_children;
    vv_shape **children;
};

/**
 * Signed distance (negative inside) from @p q, in shape coordinates, to the
 * primitive's surface, in the same units; exact where the docs say so.
 */
double vv_shape_sdf(const vv_shape *s, vv_vec3 q);
/**
 * A lower bound of the distance usable for classifying a region: b > 0
 * means the distance is at least b outside, b < 0 at least -b inside, 0
 * tells nothing.
 */
double vv_shape_sdf_bound(const vv_shape *s, vv_vec3 q);
/** Bounding box of the primitive in shape coordinates. */
vv_box vv_shape_local_box(const vv_shape *s);

/**
 * Scan converts a mesh (transformed by @p to_world) onto the grid of @p ref
 * (dims, spacing, origin; identity direction): sd gets the signed world
 * distance per voxel (negative inside for solids; |d| - thickness/2 for
 * shells), accurate within @p band world units of the surface and clamped
 * to +-band beyond. sd has dims[0]*dims[1]*dims[2] floats. Solids: inside by
 * the majority of the ray parities along the x, y and z rows through the
 * voxel, distance to the planes of the triangles crossed along those rows.
 * Shells: exact point-triangle distances.
 */
vv_status vv_mesh_scan(const vv_mesh *mesh, vv_mat4 to_world, int solid, double thickness,
                       const int dims[3], const double spacing[3], const double origin[3],
                       double band, float *sd, int threads);

/**
 * Reads a model node of a scene file: a primitive ({"type": "sphere", ...})
 * or an operation ({"op": "union", "children": [...]}), with an optional
 * transform. Mesh files are resolved relative to @p scene_path. On a JSON
 * error, the message is the problem without position and @p err_path (cap
 * bytes) receives the key path of the offending value, starting from
 * @p path, so the caller can add the line and column; on other errors
 * (a mesh file) err_path names the key too.
 */
vv_status vv_shape_from_json(vv_shape **out, json_t *node, const char *path, const char *scene_path,
                             char *err_path, size_t cap);

/**
 * Reads the voxelization keys of a geometry object ("resolution",
 * "voxel_spacing", "filter", "filter_radius", "margin", "voxel_type") into
 * @p opt. Errors as vv_shape_from_json.
 */
vv_status vv_voxelize_options_from_json(vv_voxelize_options *opt, json_t *obj, const char *path,
                                        char *err_path, size_t cap);

#endif
