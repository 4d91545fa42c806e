/*
 * The geometry-type table, part of the implementor's API (like
 * sys/renderer.h): one record per kind of geometric object of the World
 * (plane, polygon, sphere, box, cylinder, mesh), with everything the
 * components need to know about that kind of shape --
 *
 *   check        is the shape valid (a sphere's radius > 0, ...)
 *   bounds       its object-space bounding box
 *   tessellate   its triangles within a tolerance (the rasterizer draws them,
 *                radiosity subdivides them into patches, measurement sums them)
 *   prepare      per-object data for the queries below (a polygon's plane,
 *                a mesh's bounding volume hierarchy), built once per frame
 *   intersect    the nearest ray hit and its normal (the ray tracer)
 *   distance     the signed distance from a point (Modeling's volume
 *                sampling voxelizes any record through it)
 *
 * in the spirit of Embree's user geometry (bounds / intersect callbacks)
 * and Teem's format records. Everything is in the object's coordinates
 * (vv_geometry's), before the object transform; callers transform rays and
 * points. Adding a primitive is one file src/model/geom_<name>.c defining
 * its record plus one row in the table of src/model/geometry.c (and the
 * vv_object_type value and scene keys it is read from):
 * docs/architecture.md, "Adding a geometric primitive".
 *
 * Voxelization: a record does not voxelize itself. Volume sampling needs
 * Modeling's filter tables, which sit above the model, so Modeling
 * voxelizes a World object through the record's distance
 * (vv_shape_object in src/modeling), except meshes, which Modeling scan
 * converts (its mesh shapes); the arrows point down (DESIGN.md).
 *
 * Thread-safety: records are constant; every function is reentrant, and a
 * prepared object may be queried by any number of threads at once.
 */
#ifndef VOLVIS_SYS_GEOMETRY_H
#define VOLVIS_SYS_GEOMETRY_H

#include "volvis/mesh.h"
#include "volvis/model.h"

/** The record layout's version; a record sets it so a table can check. */
#define VV_GEOM_TYPE_VERSION 1

/** How finely to tessellate (vv_geom_type.tessellate). */
typedef struct vv_geom_tess {
    /** > 0: segments around a circle (sphere meridians, with segments / 2
     * parallels; cylinder sides and caps). 0: from @p tolerance. */
    int segments;
    /** With segments 0: the largest distance between a triangle and the curved
     * surface it stands for, in object units (> 0). */
    double tolerance;
    /** Unbounded primitives (the plane): the square of half side @p half drawn
     * around the point of the plane nearest @p center. */
    vv_vec3 center;
    double half;
} vv_geom_tess;

typedef struct vv_geom_type {
    int version; /**< VV_GEOM_TYPE_VERSION */
    vv_object_type type;
    const char *name; /**< the scene files' type name ("sphere") */
    /**
     * VV_OK when @p g is a shape of this kind, else VV_ERR_INVALID with a
     * message naming the problem ("sphere radius must be > 0"); the caller
     * prefixes the object's name.
     */
    vv_status (*check)(const vv_geometry *g);
    /** 1 when the shape encloses a volume (intersect normals and distance
     * signs then tell inside from outside), 0 for a surface. */
    int (*solid)(const vv_geometry *g);
    /** Object-space bounding box in *out; 0 for an unbounded shape (the plane)
     * or an empty one. */
    int (*bounds)(const vv_geometry *g, vv_box *out);
    /**
     * The shape's triangles in object coordinates, counter-clockwise seen from
     * outside (a surface: from its front, the side its normal points to), with
     * unit per-vertex normals; a mesh returns a new reference to itself.
     * The caller frees *out with vv_mesh_free. Errors: VV_ERR_INVALID (as
     * check), VV_ERR_NOMEM.
     */
    vv_status (*tessellate)(const vv_geometry *g, const vv_geom_tess *opt, vv_mesh **out);
    /**
     * Optional (NULL: the queries need nothing): what intersect and distance
     * need of @p g, in *prep (NULL allowed), released with release. @p g must
     * outlive it. Errors: VV_ERR_INVALID, VV_ERR_NOMEM, VV_ERR_LIMIT.
     */
    vv_status (*prepare)(const vv_geometry *g, void **prep);
    void (*release)(void *prep);
    /**
     * The nearest hit of the ray o + t d with tmin < t < tmax: returns 1 with
     * *t and the object-space normal *n there (not normalised; outward for
     * solids, the front normal for surfaces, whichever side was hit), else 0.
     */
    int (*intersect)(const vv_geometry *g, const void *prep, vv_vec3 o, vv_vec3 d, double tmin,
                     double tmax, double *t, vv_vec3 *n);
    /**
     * Signed distance from @p q to the surface, object units: negative inside
     * a solid; for a surface, negative behind it (against its normal).
     * Exact for the analytic shapes; a mesh's sign comes from the winding
     * number along three rays (inside where two of them see the mesh wind
     * around q), exact for closed, consistently oriented meshes.
     */
    double (*distance)(const vv_geometry *g, const void *prep, vv_vec3 q);
} vv_geom_type;

/** The record of a geometric object type; NULL for volumes and grids. */
const vv_geom_type *vv_geom_type_get(vv_object_type type);

/**
 * The record of a geometric object whose shape passes the record's check:
 * *out. Errors: VV_ERR_INVALID "object 'NAME': a TYPE is not a geometric
 * shape" (a volume or grid), or the check's message prefixed with
 * "object 'NAME'".
 */
vv_status vv_geom_object_type(const vv_object *obj, const vv_geom_type **out);

/** The records, in vv_object_type order (for tests and listings); *n their number. */
const vv_geom_type *const *vv_geom_types(int *n);

/* ---- helpers of the record files (src/model/geom_*.c) --------------------- */

/** A unit vector perpendicular to unit @p e, and a second one with p1 x p2 = e. */
void vv_geom_perpendicular(vv_vec3 e, vv_vec3 *p1, vv_vec3 *p2);
/** Newell's normal of a closed polygon (not normalised; its length is twice the area). */
vv_vec3 vv_geom_newell(const vv_vec3 *v, int n);
/* Exact signed distances shared by the records and Modeling's primitives. */
/** Distance combining a 2-D signed distance a and a slab's signed distance b,
 * exact for a prism (capped cylinder, extrusion). */
double vv_geom_prism_distance(double a, double b);
/** From @p q (relative to the centre) to the sphere of radius @p r. */
double vv_geom_sphere_distance(vv_vec3 q, double r);
/** From @p q (relative to the centre) to the box of half sizes @p half with
 * edges rounded by @p rounding (0: sharp; at most the smallest half size). */
double vv_geom_box_distance(vv_vec3 q, vv_vec3 half, double rounding);

#endif
