/*
 * Internals of the Modeling component shared by its files (not installed):
 * the shape node, the per-primitive distance functions, mesh scan
 * conversion.
 */
#ifndef VV_MODELING_INTERNAL_H
#define VV_MODELING_INTERNAL_H

#include "volvis/model.h"
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
    SHAPE_OBJECT, /* a World object's geometry, through its geometry-type record */
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
    vv_object *obj;                  /* SHAPE_OBJECT: a copy of the object (owned) */
    const struct vv_geom_type *geom; /* its record (include/volvis/sys/geometry.h) */
    void *prep;                      /* what geom->prepare built, or NULL */
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
 * to +-band beyond. sd has dims[0]*dims[1]*dims[2] floats. Solids: inside
 * where the generalized winding number |w| > 1/2 (mesh_holes.c: the signed
 * crossings of the mesh closed by caps over its holes, along the x, y and z
 * rows through the voxel, median of the three, less the caps' solid angles
 * near the holes), distance to the planes of the triangles crossed along
 * those rows. Shells: exact point-triangle distances. Errors: VV_ERR_NOMEM;
 * VV_ERR_INVALID (a vertex index out of range; holes too many and too large
 * to evaluate).
 */
vv_status vv_mesh_scan(const vv_mesh *mesh, vv_mat4 to_world, int solid, double thickness,
                       const int dims[3], const double spacing[3], const double origin[3],
                       double band, float *sd, int threads);

/**
 * The closed completion of a mesh (mesh_holes.c): @p tri is a copy of the
 * triangles (3 per triangle, the mesh's vertex indices) with each connected
 * component oriented consistently across its two-triangle edges (vertices
 * welded by exact position; the majority orientation of a component is
 * kept); the boundary left is split into n_loops closed loops, loop l being
 * loop_v[loop_start[l] .. loop_start[l + 1]) in the direction the mesh
 * traverses them (a cap fans them backwards from vv_mesh_loop_centroid).
 * cap_area: the fans' area; mesh_area: the non-degenerate triangles' area
 * (world units squared). Owned by the caller: vv_mesh_holes_free.
 */
typedef struct vv_mesh_holes {
    uint32_t *tri;
    size_t n_tri;
    size_t n_flipped; /**< triangles turned to agree with their component */
    size_t n_loops;
    size_t *loop_start; /**< n_loops + 1 offsets into loop_v */
    uint32_t *loop_v;
    double cap_area, mesh_area;
} vv_mesh_holes;

/** Fills @p out for @p m (indices must be checked by the caller). Errors: VV_ERR_NOMEM. */
vv_status vv_mesh_holes_find(const vv_mesh *m, vv_mesh_holes *out);
void vv_mesh_holes_free(vv_mesh_holes *h);
/** Mean of loop @p l's vertices, mesh coordinates. */
void vv_mesh_loop_centroid(const vv_mesh *m, const vv_mesh_holes *h, size_t l, double c[3]);
/**
 * Signed solid angle (steradians) of the triangle a, b, c seen from the
 * origin, positive when the triangle turns counter-clockwise seen from the
 * origin's side opposite its normal (Van Oosterom and Strackee 1983).
 */
double vv_solid_angle(const double a[3], const double b[3], const double c[3]);

/** The node's transform to its parent's coordinates. */
vv_mat4 vv_shape_get_transform(const vv_shape *s);

#endif
