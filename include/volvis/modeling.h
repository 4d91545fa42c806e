/*
 * VolVis Modeling: geometric models turned into volumes by volume sampling,
 * with constructive solid geometry evaluated on voxel densities (VolVis
 * paper, Avila et al., IEEE Visualization '94, section 3 "Modeling";
 * method of Wang and Kaufman, "Volume Sampled Voxelization of Geometric
 * Primitives", IEEE Visualization '93). docs/modeling.md explains the method.
 *
 * A model is a tree of vv_shape nodes: primitives (analytic solids, 2-D
 * profiles revolved, extruded or swept along a helix, triangle meshes) at
 * the leaves and CSG operations (union, intersection, difference) inside.
 * Every node has a transform from its own coordinates to its parent's (the
 * root's parent is world space). vv_voxelize samples the tree onto a grid:
 * the density of a voxel is a sampling-kernel weight looked up by the signed distance
 * d from the voxel centre to the surface (negative inside), so the density
 * is 1 deep inside, 0 far outside and exactly 0.5 on the surface.
 *
 * Ownership: shapes are created by vv_shape_* constructors and released
 * with vv_shape_free (which frees the whole subtree); vv_shape_csg takes
 * ownership of its children (also on failure). A mesh shape holds its own
 * reference to the mesh.
 * Thread-safety: building and changing a tree is not thread-safe; a finished
 * tree may be voxelized by several threads at once (it is only read).
 */
#ifndef VOLVIS_MODELING_H
#define VOLVIS_MODELING_H

#include "core.h"
#include "math.h"
#include "mesh.h"
#include "model.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- sampling kernels ---------------------------------------------------- */

/**
 * The sampling kernels of volume sampling: spherically symmetric 3-D
 * reconstruction kernels of radius R (in voxels):
 *   box:   h(r) = 1                      for r <= R
 *   tent:  h(r) = 1 - r / R              (a cone; Wang and Kaufman's choice)
 *   gauss: h(r) = exp(-r^2 / (2 s^2)) - exp(-R^2 / (2 s^2)), s = R / 2
 *          (a Gaussian truncated smoothly to zero at R)
 * each normalised to unit integral. (Not Filtering's filters, filter.h: scene
 * files and `volvis voxelize` still choose a kernel by the key "filter" and
 * the option --filter.)
 */
typedef enum vv_sampling_kernel_kind {
    VV_SAMPLING_KERNEL_BOX = 0,
    VV_SAMPLING_KERNEL_TENT = 1,
    VV_SAMPLING_KERNEL_GAUSS = 2
} vv_sampling_kernel_kind;

/** "box", "tent", "gauss"; "unknown" out of range. Never NULL. */
const char *vv_sampling_kernel_name(vv_sampling_kernel_kind k);
/** Parses a kernel name ("box", "tent" or "linear", "gauss" or "gaussian").
 * Errors: VV_ERR_INVALID with the accepted names. */
vv_status vv_sampling_kernel_parse(const char *name, vv_sampling_kernel_kind *out);

/**
 * A precomputed density table of a kernel: entry i holds the integral of the
 * kernel over the half-space lying beyond a plane at signed distance
 *   d_i = -radius + 2 radius i / (n - 1)   (voxels; negative inside)
 * from the kernel centre, i.e. the density of a voxel whose centre is at
 * signed distance d from a locally flat surface. The table is computed by
 * numerical integration of the 3-D kernel (not from the closed forms), so
 * vv_sampling_kernel_integral checks it. density[0] = 1, density[n-1] = 0 and
 * density(-d) = 1 - density(d); the 0.5 entry is at d = 0.
 */
typedef struct vv_sampling_kernel_table {
    vv_sampling_kernel_kind kind;
    double radius; /**< voxels, > 0 */
    int n;         /**< entries, >= 2 */
    float *density;
} vv_sampling_kernel_table;

/** Default number of table entries. */
#define VV_SAMPLING_KERNEL_TABLE_SIZE 2048

/**
 * Builds the table of @p kind with @p radius voxels (0.25 to 16) and @p n
 * entries (2 to 1<<20; n <= 0 means VV_SAMPLING_KERNEL_TABLE_SIZE). Errors:
 * VV_ERR_INVALID, VV_ERR_NOMEM.
 */
vv_status vv_sampling_kernel_table_new(vv_sampling_kernel_table **out, vv_sampling_kernel_kind kind,
                                       double radius, int n);
/** Releases a table. Accepts NULL. */
void vv_sampling_kernel_table_free(vv_sampling_kernel_table *t);
/** Density at signed distance @p d voxels, linearly interpolated; 1 below -radius, 0 above. */
double vv_sampling_kernel_table_eval(const vv_sampling_kernel_table *t, double d);
/**
 * The same density from the closed-form integral (spherical-cap volumes for
 * the box, their analogues for the tent and the truncated Gaussian), for
 * checking the tables.
 */
double vv_sampling_kernel_integral(vv_sampling_kernel_kind kind, double radius, double d);

/* ---- shapes -------------------------------------------------------------- */

/** A node of a model tree: a primitive or a CSG operation. Opaque. */
typedef struct vv_shape vv_shape;

typedef enum vv_csg_op {
    VV_CSG_UNION = 0,        /**< density max(a, b, ...) */
    VV_CSG_INTERSECTION = 1, /**< density min(a, b, ...) */
    VV_CSG_DIFFERENCE = 2    /**< first child minus the others: min(a, 1 - b, 1 - c, ...) */
} vv_csg_op;

/** "union", "intersection", "difference". Never NULL. */
const char *vv_csg_op_name(vv_csg_op op);

/*
 * Primitive constructors. Sizes are in the shape's own coordinates (world
 * units before the transforms above it); every size must be finite and > 0
 * (errors: VV_ERR_INVALID naming the primitive and the value, VV_ERR_NOMEM).
 * Each primitive is centred on its own origin unless said otherwise; axes of
 * revolution are the z axis.
 */
/** Sphere of @p radius. */
vv_status vv_shape_sphere(vv_shape **out, double radius);
/** Ellipsoid with semi-axes @p radii along x, y, z. */
vv_status vv_shape_ellipsoid(vv_shape **out, vv_vec3 radii);
/** Box of edge lengths @p size, edges rounded with radius @p rounding (0 = sharp;
 * at most half the smallest edge). */
vv_status vv_shape_box(vv_shape **out, vv_vec3 size, double rounding);
/** Capped cylinder of @p radius, z from -height/2 to height/2. */
vv_status vv_shape_cylinder(vv_shape **out, double radius, double height);
/** Capped (truncated) cone: radius @p r_bottom at z = -height/2, @p r_top at
 * z = height/2; one of the radii may be 0 (a pointed cone). */
vv_status vv_shape_cone(vv_shape **out, double r_bottom, double r_top, double height);
/** Torus around the z axis: tube centre circle of radius @p major, tube radius
 * @p minor < major. */
vv_status vv_shape_torus(vv_shape **out, double major, double minor);
/** Planar polygon of @p n >= 3 vertices (x, y, z each, either winding, simple,
 * planar within 1e-6 of its size) thickened by @p thickness (half on each side). */
vv_status vv_shape_polygon(vv_shape **out, int n, const vv_vec3 *vertices, double thickness);
/**
 * Solid of revolution: the simple polygon of @p n >= 3 points (r, z)
 * (@p profile holds 2n doubles, r >= 0) revolved about the z axis. A wine
 * glass or a bottle is one profile.
 */
vv_status vv_shape_revolution(vv_shape **out, int n, const double *profile);
/** Extrusion of the simple polygon of @p n >= 3 points (x, y) (@p polygon holds
 * 2n doubles) along z from -height/2 to height/2 (a hexagonal nut blank). */
vv_status vv_shape_extrusion(vv_shape **out, int n, const double *polygon, double height);
/**
 * Helix sweep (a screw thread): the simple polygon of @p n >= 3 points (r, z)
 * in the half-plane y = 0, x = r > 0 (@p profile holds 2n doubles), swept
 * about the z axis so that it rises by @p pitch per turn (right-handed;
 * a negative pitch gives a left-handed thread), kept between z0 and z1.
 * The profile should be shorter than |pitch| along z. The distance is
 * measured in the meridian half-plane after undoing the rise, exact up to
 * the helix slope pitch / (2 pi r).
 */
vv_status vv_shape_helix(vv_shape **out, int n, const double *profile, double pitch, double z0,
                         double z1);

/**
 * VV_MESH_AUTO fills an open mesh as a solid when the caps closing its holes
 * (fans over its boundary loops) have at most this fraction of its area: a
 * scanned solid with a few holes; above it, the mesh is a surface meant as a
 * shell.
 */
#define VV_MESH_AUTO_HOLE_AREA 0.05

/**
 * How a mesh is voxelized. Solids are classified by the generalized winding
 * number w (Jacobson, Kavan and Sorkine-Hornung, SIGGRAPH 2013): a voxel is
 * inside where |w| > 1/2. Before that, each connected component is oriented
 * consistently (its majority orientation kept, so a flipped patch is turned
 * back); holes are closed smoothly by the w = 1/2 level; self-intersecting
 * and overlapping parts count once; a component facing inwards still counts.
 * On a closed, consistently oriented mesh without self-intersections this is
 * Jordan's parity, voxel for voxel.
 */
typedef enum vv_mesh_mode {
    VV_MESH_AUTO = 0,  /**< solid when closed or when its holes are small (VV_MESH_AUTO_HOLE_AREA),
                            else shell */
    VV_MESH_SOLID = 1, /**< solid by the winding number, whatever the topology */
    VV_MESH_SHELL = 2  /**< a shell of the given thickness around the triangles */
} vv_mesh_mode;
/**
 * A triangle mesh (borrowed; the shape takes its own reference). @p thickness
 * is the shell thickness in world units (<= 0: two voxels of the largest voxel
 * spacing of the output grid; thinner shells alias in renderings). Errors: VV_ERR_INVALID (no
 * triangles), VV_ERR_NOMEM.
 */
vv_status vv_shape_mesh(vv_shape **out, vv_mesh *mesh, vv_mesh_mode mode, double thickness);
/** A mesh loaded with vv_mesh_load (any format Assimp reads). Errors as vv_mesh_load. */
vv_status vv_shape_mesh_load(vv_shape **out, const char *path, vv_mesh_mode mode, double thickness);
/**
 * A World object's geometry as a model primitive, placed by the object's
 * transform: spheres, boxes and capped cylinders through their exact signed
 * distances (the geometry-type table, src/model/geometry.h), meshes as mesh
 * shapes (VV_MESH_AUTO). The shape keeps its own copy of the object.
 * Errors: VV_ERR_INVALID (NULL, a volume or grid, a broken shape, a plane
 * (no bounds), a polygon or an open cylinder (no inside)), VV_ERR_NOMEM.
 */
vv_status vv_shape_object(vv_shape **out, const vv_object *obj);
/**
 * A CSG operation on @p n >= 1 children (n >= 2 for a difference is not
 * required: a difference of one child is that child). Takes ownership of
 * every non-NULL child, also on failure. Errors: VV_ERR_INVALID when a child
 * is NULL ("csg union: child 2 of 3 is missing"), VV_ERR_NOMEM.
 */
vv_status vv_shape_csg(vv_shape **out, vv_csg_op op, int n, vv_shape **children);
/** Releases a shape and its subtree. Accepts NULL. */
void vv_shape_free(vv_shape *s);
/** Applies @p M after the node's current transform (node -> parent: M * old). */
void vv_shape_transform(vv_shape *s, vv_mat4 M);
/**
 * Conservative bounding box of the solid in the coordinates above the node
 * (its transform applied): for a union the union of the children's boxes,
 * an intersection their intersection, a difference the first child's box.
 * An empty model gives min > max.
 */
vv_box vv_shape_bounds(const vv_shape *s);

/* ---- voxelization -------------------------------------------------------- */

typedef struct vv_voxelize_options {
    vv_sampling_kernel_kind kernel; /**< scene key "filter"; default VV_SAMPLING_KERNEL_TENT */
    double radius;      /**< kernel radius in voxels (of the largest spacing); default 1.5 */
    vv_voxel_type type; /**< VV_U8 (density * 255) or VV_F32 (density); default VV_U8 */
    /** Explicit grid when dims[0] > 0: dims, spacing (> 0), origin; axis-aligned. */
    int dims[3];
    double spacing[3];
    double origin[3];
    /** Otherwise the grid covers the model's bounding box plus a margin: */
    double voxel_spacing; /**< > 0: isotropic spacing in world units */
    int size;             /**< else voxels along the longest axis (default 128) */
    double margin;        /**< voxels around the box on each side; < 0: default radius + 1 */
    int threads;          /**< <= 0: vv_threads_get() */
    vv_progress progress;
} vv_voxelize_options;

/** Fills @p o with the defaults above. */
void vv_voxelize_options_init(vv_voxelize_options *o);

/**
 * Volume-samples the model @p shape (world coordinates = the root's parent
 * space) onto a grid: each voxel gets the kernel-table density of its signed
 * distance to each primitive, combined through the tree per voxel (union =
 * max, intersection = min, difference = min(a, 1 - b)). Only voxels within
 * the kernel radius of a primitive's surface are evaluated one by one:
 * the grid is walked in 4^3 subvolumes classified as inside, outside or
 * near the surface from a lower bound of the distance at the subvolume
 * centre; inside ones are filled, outside ones skipped, and a mesh is scan
 * converted along grid rows instead: inside by the majority of the ray
 * parities of the x, y and z rows through a voxel, a row abstaining when its
 * signed crossings do not balance (it passes through a hole of an open
 * mesh); the distance near the surface from the planes of the crossed
 * triangles.
 *
 * Output: u8 (255 * density, surface at 127.5) or f32 (density, surface at
 * 0.5), data_origin VV_ORIGIN_FUZZY_VOXELIZED, range updated. OpenMP-parallel
 * and deterministic. @p opt may be NULL (defaults).
 *
 * Errors: VV_ERR_INVALID (bad options, an empty model, a non-invertible
 * transform), VV_ERR_LIMIT (a grid over the volume limits, e.g. 10^5 voxels
 * along an axis; a tree deeper than 1000 levels), VV_ERR_NOMEM,
 * VV_ERR_CANCELLED.
 */
vv_status vv_voxelize(vv_volume **out, const vv_shape *shape, const vv_voxelize_options *opt);

/**
 * Loads a geometric model file as one shape (a "model" alone is the World,
 * model.h): a triangle mesh (any format vv_mesh_load reads) or a
 * scene file (JSON, docs/scene-format.md), of which every object of type
 * "geometry" is taken, its shape placed by the object's position, rotation
 * and scale, and all of them united. For a scene, the voxelization keys of
 * the first geometry object ("resolution", "voxel_spacing", "filter",
 * "filter_radius", "margin", "voxel_type") are stored in @p opt when it is
 * not NULL (other fields are left as they are). Errors: those of
 * vv_mesh_load, VV_ERR_FORMAT with the file and the key path of the
 * offending value, VV_ERR_INVALID (a scene without geometry objects).
 */
vv_status vv_shape_load(vv_shape **out, const char *path, vv_voxelize_options *opt);

/**
 * Reads a model tree given as JSON text (docs/scene-format.md, "Geometry
 * objects"): a primitive ({"type": "sphere", "radius": 10, ...}) or an
 * operation ({"op": "union", "children": [...]}), each with an optional
 * transform. This is how the scene layer hands the "primitive" or "csg"
 * value of a scene file's geometry object to Modeling. @p json is @p len
 * bytes of UTF-8 (not NUL-terminated necessarily); @p key_path is where the
 * value sits in the enclosing document ("objects[2].csg", may be ""), used
 * to name the offending value; mesh files named in the tree are resolved
 * relative to the folder of @p base_path (the scene file; may be NULL: the
 * current folder).
 *
 * On error the message is the problem without a file position, and
 * @p err_path (@p cap bytes, may be NULL) receives the key path of the
 * offending value (starting with @p key_path), so that the caller can add
 * the line and column in its own text. Errors: VV_ERR_FORMAT (malformed JSON,
 * a bad key or value), VV_ERR_LIMIT (a tree deeper than 1000 levels), those
 * of vv_mesh_load for mesh nodes, VV_ERR_NOMEM. Reentrant.
 */
vv_status vv_shape_parse_json(vv_shape **out, const char *json, size_t len, const char *key_path,
                              const char *base_path, char *err_path, size_t cap);

/**
 * Reads the voxelization keys ("resolution", "voxel_spacing", "filter",
 * "filter_radius", "margin", "voxel_type") of the JSON object in @p json
 * (@p len bytes; other keys are ignored) into @p opt, leaving the fields of
 * absent keys as they are. @p key_path and @p err_path as in
 * vv_shape_parse_json. Errors: VV_ERR_FORMAT (malformed JSON, a value out
 * of range), VV_ERR_LIMIT (a resolution over VV_VOLUME_MAX_DIM). Reentrant.
 */
vv_status vv_voxelize_options_parse_json(vv_voxelize_options *opt, const char *json, size_t len,
                                         const char *key_path, char *err_path, size_t cap);

#ifdef __cplusplus
}
#endif

#endif
