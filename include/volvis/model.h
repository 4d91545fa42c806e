/*
 * VolVis abstract model: the World of the VolVis paper (Avila et al., IEEE
 * Visualization '94, section 3 "Abstract model"): lights, objects, views,
 * global cut planes and global shading (ambient light, background colour).
 * Plus scene files (JSON, read with Jansson; schema in docs/scene-format.md).
 *
 * Units: positions and distances in world units; angles in radians (scene
 * files use degrees and are converted on load).
 *
 * Ownership: a World owns its objects; an object holds one reference to its
 * volume. Thread-safety: a World may be read by many threads at once (a
 * render); changing it while a render reads it is the caller's to prevent.
 */
#ifndef VOLVIS_MODEL_H
#define VOLVIS_MODEL_H

#include "core.h"
#include "math.h"
#include "mesh.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

#define VV_TF_MAX_POINTS 256
#define VV_MAX_CUT_PLANES 8
#define VV_MAX_LIGHTS 16
#define VV_NAME_MAX 64
#define VV_MAX_RENDER_OPTIONS 32
#define VV_RENDER_NAME_MAX 32          /**< bytes of a renderer name, with its NUL */
#define VV_RENDER_OPTION_KEY_MAX 32    /**< bytes of an option key, with its NUL */
#define VV_RENDER_OPTION_VALUE_MAX 256 /**< bytes of an option value, with its NUL */

/* ---- transfer function ---------------------------------------------- */

typedef struct vv_tf_opacity_point {
    double value;   /**< data value */
    double opacity; /**< in [0, 1], per opacity_unit_distance of ray length */
} vv_tf_opacity_point;

typedef struct vv_tf_color_point {
    double value;
    vv_vec3 color; /**< RGB in [0, 1] */
} vv_tf_color_point;

/**
 * Piecewise-linear opacity and colour transfer functions of the data value.
 * Points are kept sorted by value; outside the first and last point the end
 * values hold; two points at the same value make a step (the one added later
 * holds from that value up). With no colour points the colour is white; with
 * no opacity points the opacity is 0. A NaN value has opacity 0 and the
 * first colour. Opacity is per opacity_unit_distance (world units)
 * of ray length; a renderer that steps by s uses 1 - (1 - a)^(s / unit).
 */
typedef struct vv_tf {
    int n_opacity;
    vv_tf_opacity_point opacity[VV_TF_MAX_POINTS];
    int n_color;
    vv_tf_color_point color[VV_TF_MAX_POINTS];
    double opacity_unit_distance; /**< world units, > 0 */
} vv_tf;

/** Empty TF (opacity 0, white) with unit distance 1. */
void vv_tf_init(vv_tf *tf);
/**
 * Adds an opacity point, keeping the points sorted by value. Errors:
 * VV_ERR_LIMIT when full, VV_ERR_INVALID for NaN values or opacity outside
 * [0, 1].
 */
vv_status vv_tf_add_opacity(vv_tf *tf, double value, double opacity);
/** Adds a colour point (sorted). Errors as vv_tf_add_opacity, colour in [0,1]. */
vv_status vv_tf_add_color(vv_tf *tf, double value, vv_vec3 color);
/** Opacity per unit distance at @p value (piecewise-linear). */
double vv_tf_eval_opacity(const vv_tf *tf, double value);
/** Colour at @p value (piecewise-linear; white when there are no points). */
vv_vec3 vv_tf_eval_color(const vv_tf *tf, double value);
/**
 * Replaces the TF with a ramp: opacity 0 at lo rising linearly to
 * @p max_opacity at hi, colour @p color throughout.
 */
void vv_tf_set_ramp(vv_tf *tf, double lo, double hi, double max_opacity, vv_vec3 color,
                    double unit_distance);

/* ---- lights, cut planes, material, view -------------------------------- */

typedef enum vv_light_type { VV_LIGHT_DIRECTIONAL = 0, VV_LIGHT_POINT = 1 } vv_light_type;

typedef struct vv_light {
    vv_light_type type;
    int headlight;     /**< 1: directional light from the eye along the view direction */
    vv_vec3 direction; /**< directional: the direction the light travels (unit) */
    vv_vec3 position;  /**< point light position, world units */
    vv_vec3 color;     /**< RGB in [0, 1] */
    double intensity;  /**< scales color */
} vv_light;

/** A cut plane keeps the half-space the normal points into: n·(x − point) >= 0. */
typedef struct vv_cut_plane {
    vv_vec3 point;
    vv_vec3 normal; /**< unit */
} vv_cut_plane;

/**
 * Phong material coefficients (the paper's object "material"), plus the
 * global-illumination terms of volumetric ray tracing (Sobierajski and
 * Kaufman 1994): a mirror reflectance and a transparency with an index of
 * refraction. Renderers without global effects ignore the last three.
 */
typedef struct vv_material {
    double ambient;      /**< ka */
    double diffuse;      /**< kd */
    double specular;     /**< ks */
    double shininess;    /**< Phong exponent */
    vv_vec3 color;       /**< base colour (threshold segmentation, isosurfaces, geometry) */
    double reflectance;  /**< fraction of light mirrored, [0, 1]; 0 by default */
    double transparency; /**< fraction of light transmitted, [0, 1]; 0 by default */
    double ior;          /**< index of refraction of a transparent object, > 0; 1 by default */
} vv_material;

typedef enum vv_projection {
    VV_PROJECTION_PERSPECTIVE = 0,
    VV_PROJECTION_ORTHOGRAPHIC = 1
} vv_projection;

/** A camera. */
typedef struct vv_view {
    vv_vec3 eye;
    vv_vec3 at;
    vv_vec3 up;
    double fov;          /**< vertical field of view, radians (perspective) */
    double ortho_height; /**< world height of the view (orthographic) */
    vv_projection projection;
    int width; /**< image size in pixels */
    int height;
} vv_view;

/**
 * The primary ray through image position (px + 0.5, py + 0.5): pixel (px,
 * py) covers [px, px + 1) x [py, py + 1), so integer px, py give the ray
 * through the centre of that pixel. Column 0 is at the left, row 0 at the
 * top. Fractional coordinates are allowed (supersampling).
 *
 * Camera basis: forward = normalize(at - eye), right = normalize(forward x
 * up), true up = right x forward (a degenerate up falls back to +z or +x).
 * Perspective: origin at the eye, dir through the image plane spanning
 * vertical angle fov and aspect width/height. Orthographic: dir = forward,
 * origin on the plane through the eye, the view ortho_height tall and
 * ortho_height * width / height wide. dir is unit.
 */
vv_ray vv_view_ray(const vv_view *view, double px, double py);

/**
 * Sets `at` to the centre of @p box and moves the eye along the current
 * viewing direction so that the bounding sphere of the box fits the view
 * (the narrower of the two image axes). Perspective: distance r / sin(half
 * the narrower field of view). Orthographic: ortho_height is set to hold the
 * sphere in both axes and the eye is put 2r from the centre. `up` is kept.
 */
void vv_view_frame_box(vv_view *view, vv_box box);

/**
 * Places the eye on a sphere around `at` by azimuth (about `up`) and
 * elevation (towards `up`), both radians, relative to the current eye
 * direction, keeping the distance. The up vector turns with the elevation
 * (a trackball), so orbiting over a pole never degenerates.
 */
void vv_view_orbit(vv_view *view, double azimuth, double elevation);

/* ---- objects --------------------------------------------------------- */

/**
 * What an object is. Geometric objects are defined in object coordinates by
 * vv_geometry and placed in the World by the object transform like volumes.
 */
typedef enum vv_object_type {
    VV_OBJECT_VOLUME = 0,   /**< a vv_volume */
    VV_OBJECT_PLANE = 1,    /**< infinite plane: geometry.point, geometry.normal */
    VV_OBJECT_POLYGON = 2,  /**< planar polygon: geometry.vertices (n >= 3) */
    VV_OBJECT_SPHERE = 3,   /**< geometry.center, geometry.radius */
    VV_OBJECT_BOX = 4,      /**< axis-aligned in object space: geometry.box */
    VV_OBJECT_CYLINDER = 5, /**< axis geometry.base to geometry.top, radius; capped */
    VV_OBJECT_MESH = 6      /**< geometry.mesh (a triangle mesh) */
} vv_object_type;

/** Name of an object type as in scene files ("volume", "sphere", ...). Never NULL. */
const char *vv_object_type_name(vv_object_type t);

/**
 * Shape of a geometric object, in object coordinates (world units before the
 * object transform). Only the fields of the object's type are meaningful.
 */
typedef struct vv_geometry {
    vv_vec3 center;    /**< sphere centre */
    double radius;     /**< sphere, cylinder radius, > 0 */
    vv_vec3 point;     /**< plane: a point on it */
    vv_vec3 normal;    /**< plane: unit normal (its front side) */
    vv_box box;        /**< box: [min, max] corners */
    vv_vec3 base, top; /**< cylinder: centres of the two cap discs */
    int capped;        /**< cylinder: 1 closed with discs, 0 an open tube */
    int n_vertices;    /**< polygon: number of vertices, >= 3 */
    vv_vec3 *vertices; /**< polygon: owned, planar, in order (either winding) */
    vv_mesh *mesh;     /**< mesh: one reference held */
    char *source;      /**< mesh or volume: file it came from (owned, may be NULL), for scene
                            saving (vv_scene_load sets it for volumes; vv_scene_save uses it
                            when no file name is given) */
} vv_geometry;

typedef enum vv_render_mode {
    VV_MODE_COMPOSITE = 0, /**< front-to-back compositing through the TF */
    VV_MODE_MIP = 1,       /**< maximum intensity projection */
    VV_MODE_MINIP = 2,     /**< minimum intensity projection */
    VV_MODE_XRAY = 3,      /**< average value along the ray */
    VV_MODE_ISO = 4        /**< first isosurface hit, shaded */
} vv_render_mode;

typedef enum vv_segmentation {
    VV_SEG_TRANSFER_FUNCTION = 0, /**< opacity and colour from tf */
    VV_SEG_THRESHOLD = 1          /**< opaque in material.color where value >= threshold */
} vv_segmentation;

/**
 * An object of the World: a volume or a geometric shape. World position of
 * an object point q (the volume's own world coordinates, or the geometry's
 * coordinates) is  position + orientation ⊗ (scale ∘ q).
 *
 * The shading-effect flags are the per-object control of global effects of
 * volumetric ray tracing (VolVis paper, section 5, Figure 5); renderers
 * without global effects ignore them.
 */
typedef struct vv_object {
    char name[VV_NAME_MAX];
    vv_object_type type;
    vv_volume *volume;    /**< VV_OBJECT_VOLUME: one reference held (released by vv_object_free) */
    vv_geometry geometry; /**< geometric types; owned */
    vv_vec3 position;
    vv_quat orientation;
    vv_vec3 scale;
    vv_material material;
    vv_segmentation segmentation;
    double threshold; /**< VV_SEG_THRESHOLD */
    vv_tf tf;         /**< VV_SEG_TRANSFER_FUNCTION; also the grey ramp of mip/minip/xray */
    vv_render_mode mode;
    double isovalue; /**< VV_MODE_ISO */
    double step;     /**< sample step in units of the smallest voxel spacing, > 0 */
    int shading;     /**< 1: Phong shading from gradients; 0: emission only */
    int visible;
    int casts_shadows;          /**< 1: blocks light on its way to other points */
    int receives_shadows;       /**< 1: its points are shaded with shadow rays */
    int visible_in_reflections; /**< 1: seen by reflected and transmitted rays */
    int reflects;               /**< 1: spawns reflected rays when material.reflectance > 0 */
    int n_cut_planes;
    vv_cut_plane cut_planes[VV_MAX_CUT_PLANES]; /**< local, in world coordinates */
} vv_object;

/**
 * A new volume object holding a reference to @p volume (borrowed; the object
 * takes its own reference): identity transform, composite mode, step 0.5,
 * shading on, visible, material ka 0.1 kd 0.6 ks 0.3 shininess 30 colour
 * white, TF a white ramp from opacity 0 at range[0] to 1 at range[1] with
 * opacity_unit_distance the smallest voxel spacing; threshold and isovalue
 * the middle of the range. @p name may be NULL ("volume"); it is truncated
 * to VV_NAME_MAX - 1 bytes. Errors: VV_ERR_NOMEM, VV_ERR_INVALID.
 */
vv_status vv_object_new_volume(vv_object **out, vv_volume *volume, const char *name);
/**
 * A new geometric object of @p type (not VV_OBJECT_VOLUME) with the same
 * defaults as vv_object_new_volume (material, flags) and a unit shape: sphere
 * at the origin with radius 1, plane z = 0 facing +z, box [-1, 1]^3, capped
 * cylinder from (0,0,-1) to (0,0,1) radius 1; polygon and mesh start empty
 * (vv_object_set_polygon, vv_object_set_mesh). @p name may be NULL (the
 * type name). Errors: VV_ERR_INVALID, VV_ERR_NOMEM.
 */
vv_status vv_object_new_geometry(vv_object **out, vv_object_type type, const char *name);
/**
 * Sets a polygon object's vertices (copied). Errors: VV_ERR_INVALID (not a
 * polygon, fewer than 3 vertices, not planar within 1e-6 of its size, zero
 * area), VV_ERR_NOMEM.
 */
vv_status vv_object_set_polygon(vv_object *obj, int n, const vv_vec3 *vertices);
/**
 * Sets a mesh object's mesh (the object takes its own reference; @p source
 * is the file name kept for scene saving, may be NULL). Errors:
 * VV_ERR_INVALID (not a mesh object, empty mesh), VV_ERR_NOMEM.
 */
vv_status vv_object_set_mesh(vv_object *obj, vv_mesh *mesh, const char *source);
/** Releases an object, its reference to the volume and its geometry. Accepts NULL. */
void vv_object_free(vv_object *obj);
/**
 * A copy of @p obj: every field copied, the polygon vertices and mesh source
 * duplicated, one more reference taken on the volume and the mesh (voxels
 * and triangles are shared, not copied: they are never changed in place by
 * the World's editors, so a copy is cheap). Thread-safe for concurrent
 * readers of @p obj. Errors: VV_ERR_INVALID (NULL), VV_ERR_NOMEM.
 */
vv_status vv_object_clone(vv_object **out, const vv_object *obj);
/** Object-to-world matrix T(position) * R(orientation) * S(scale). */
vv_mat4 vv_object_matrix(const vv_object *obj);
/** Index-to-world matrix of the object's volume: object matrix * volume index-to-world. */
vv_mat4 vv_object_index_to_world(const vv_object *obj);
/**
 * World bounding box of the object: a volume's 8 index-box corners
 * transformed, a shape's object-space bounds transformed. A plane is
 * unbounded: its box is empty (min > max) and vv_world_bounds skips it.
 */
vv_box vv_object_world_box(const vv_object *obj);

/* ---- render settings ------------------------------------------------- */

/**
 * How a World wants to be rendered: the renderer, its quality level and its
 * --set options, kept with the World so that a saved scene renders as it
 * was shown (scene file section "render", docs/scene-format.md). Plain data:
 * copying the struct copies the settings. The model layer does not know the
 * renderers, so names, keys and values are not checked against them here;
 * the CLI and the GUI pass them to vv_renderer_new and
 * vv_renderer_set_option, which do.
 */
typedef struct vv_render_settings {
    char renderer[VV_RENDER_NAME_MAX]; /**< "" = not set (the default, raycast) */
    int quality;                       /**< 0..2; -1 = not set (the renderer's default) */
    int n_options;                     /**< 0..VV_MAX_RENDER_OPTIONS */
    /** Option keys, distinct, in the order first set; for the renderer named above. */
    char option_keys[VV_MAX_RENDER_OPTIONS][VV_RENDER_OPTION_KEY_MAX];
    /** Option values as text ("1"/"0" for booleans, numbers as %.17g). */
    char option_values[VV_MAX_RENDER_OPTIONS][VV_RENDER_OPTION_VALUE_MAX];
} vv_render_settings;

/** Sets @p rs to "nothing set": renderer "", quality -1, no options. */
void vv_render_settings_init(vv_render_settings *rs);
/**
 * Sets option @p key to @p value (both copied): replaces the value of an
 * existing key, else appends the key. Errors: VV_ERR_INVALID (NULL
 * argument, empty key, key of VV_RENDER_OPTION_KEY_MAX bytes or more, value
 * of VV_RENDER_OPTION_VALUE_MAX bytes or more), VV_ERR_LIMIT (a new key
 * beyond VV_MAX_RENDER_OPTIONS). On error @p rs is unchanged. Not
 * thread-safe for concurrent writers of @p rs.
 */
vv_status vv_render_settings_set_option(vv_render_settings *rs, const char *key, const char *value);
/** The value of option @p key, or NULL when it is not set (borrowed from @p rs). */
const char *vv_render_settings_get_option(const vv_render_settings *rs, const char *key);

/* ---- world ------------------------------------------------------------ */

typedef struct vv_world {
    vv_view view; /**< the current view */
    int n_lights;
    vv_light lights[VV_MAX_LIGHTS];
    int n_objects;
    int cap_objects;
    vv_object **objects; /**< owned */
    int n_cut_planes;
    vv_cut_plane cut_planes[VV_MAX_CUT_PLANES]; /**< global */
    vv_vec3 ambient;                            /**< global ambient light colour */
    vv_vec3 background;                         /**< background colour */
    vv_render_settings render;                  /**< how to render it; may be not set */
} vv_world;

/**
 * An empty World: a 512x512 perspective view with fov 30° from eye
 * (0, -1000, 0) looking at the origin with up +z (ortho_height 500), no
 * objects, no lights, no cut planes, ambient (1,1,1), black background,
 * render settings not set (vv_render_settings_init).
 */
vv_status vv_world_new(vv_world **out);
/** Releases a World and every object it owns. Accepts NULL. */
void vv_world_free(vv_world *w);
/** Appends @p obj; the World takes ownership (also on failure it frees obj). */
vv_status vv_world_add_object(vv_world *w, vv_object *obj);
/** Appends a copy of @p light. Errors: VV_ERR_LIMIT beyond VV_MAX_LIGHTS. */
vv_status vv_world_add_light(vv_world *w, const vv_light *light);
/** Appends a global cut plane. Errors: VV_ERR_LIMIT, VV_ERR_INVALID (zero normal). */
vv_status vv_world_add_cut_plane(vv_world *w, vv_vec3 point, vv_vec3 normal);
/**
 * A snapshot of @p w: the view, lights, cut planes, global shading, render
 * settings (copied by value) and a vv_object_clone of every object.
 * Renderers may read the snapshot on other threads while @p w goes on being
 * edited (the Navigator and the GUI render snapshots, DESIGN.md
 * "Interaction"). Errors: VV_ERR_INVALID, VV_ERR_NOMEM.
 */
vv_status vv_world_clone(vv_world **out, const vv_world *w);
/**
 * Removes object @p index and returns it (the caller owns it), keeping the
 * order of the others. Errors: VV_ERR_INVALID (index out of range).
 */
vv_status vv_world_take_object(vv_world *w, int index, vv_object **out);
/**
 * Inserts @p obj at @p index (0..n_objects), shifting the rest; the World
 * takes ownership (also on failure it frees obj). Errors: VV_ERR_INVALID,
 * VV_ERR_NOMEM, VV_ERR_LIMIT.
 */
vv_status vv_world_insert_object(vv_world *w, int index, vv_object *obj);
/** Bounding box of all visible bounded objects (an empty box at the origin if none). */
vv_box vv_world_bounds(const vv_world *w);

/** Options for vv_world_new_for_volume. */
typedef struct vv_default_scene_options {
    vv_render_mode mode;
    int has_tf_range; /**< 1: use tf_lo/tf_hi, else derived from the histogram */
    double tf_lo, tf_hi;
    int has_isovalue;
    double isovalue;
    int width, height;
    double azimuth, elevation; /**< radians, applied to the default view */
    double zoom;               /**< > 1 moves closer */
} vv_default_scene_options;

/** Defaults: composite, histogram TF, 512x512, no rotation, zoom 1. */
void vv_default_scene_options_init(vv_default_scene_options *o);

/**
 * A World showing one volume the way a user expects from `volvis render
 * FILE`: the volume centred on the origin (object position = minus the
 * centre of its world box), a perspective view (fov 30°) from the front
 * (eye on the anterior side: -y when volume->space is VV_SPACE_LPS, else +y;
 * up +z; a single slice, one voxel along an axis, is seen face on along it) framed with
 * vv_view_frame_box, orbited by azimuth and elevation, then the eye distance divided by zoom; one
 * white headlight of intensity 1, ambient (1,1,1), black background; material and step as
 * vv_object_new_volume; and a transfer function from the histogram (or the
 * given range). The rule is in docs/scene-format.md, "Default scene". @p opt
 * may be NULL (defaults). Takes its own reference to @p volume. Errors:
 * VV_ERR_INVALID (bad options), VV_ERR_NOMEM.
 */
vv_status vv_world_new_for_volume(vv_world **out, vv_volume *volume,
                                  const vv_default_scene_options *opt);

/**
 * Loads a scene file (JSON, docs/scene-format.md; at most 16 MiB). Volume
 * files are resolved relative to the scene file and loaded with
 * vv_volume_load. Unknown keys are errors. On failure *out is NULL. Errors:
 * VV_ERR_IO, VV_ERR_LIMIT (file too large), VV_ERR_FORMAT with the file,
 * line and column (1-based) and the path of the offending value
 * ("scene.json:12:7: view.fov: expected a number, got a string"), or
 * whatever loading a volume returned, prefixed with the position of its
 * "file" key.
 */
vv_status vv_scene_load(vv_world **out, const char *path);

/**
 * vv_scene_load reporting the progress of voxelizing the "geometry" objects
 * (each voxelization reports 0 to 1 in turn) to @p progress (may be NULL),
 * which can cancel (VV_ERR_CANCELLED). Geometry objects are volume-sampled
 * by the Modeling component (include/volvis/modeling.h) into volume objects.
 */
vv_status vv_scene_load_progress(vv_world **out, const char *path, const vv_progress *progress);

/**
 * Writes a World as a scene file, atomically. Volumes are referred to by
 * @p volume_files[i] for object i (relative to the scene file); a mesh
 * object by volume_files[i] when given, else by its geometry.source; the
 * entries of other geometric objects are not read, and @p volume_files may
 * be NULL when there are no volume objects. Every field is written (the volume's current
 * origin and spacing too; the "render" section when any render setting is
 * set), so vv_scene_load of the file reproduces the World; the TF of a
 * threshold-segmented object is not kept. A volume object with no entry in
 * @p volume_files is referred to by its geometry.source. Errors:
 * VV_ERR_IO, VV_ERR_INVALID.
 */
vv_status vv_scene_save(const vv_world *w, const char *path, const char *const *volume_files);

#ifdef __cplusplus
}
#endif
#endif
