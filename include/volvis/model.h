/*
 * VolVis abstract model: the World of the VolVis paper (Avila et al., IEEE
 * Visualization '94, section 3 "Abstract model"): lights, objects, views,
 * global cut planes and global shading (ambient light, background colour).
 * Scene files (JSON) are read and written by the scene layer above
 * (include/volvis/scene.h), which loads the files they name.
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
#include "grid.h"
#include "image.h"
#include "math.h"
#include "mesh.h"
#include "source.h"
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
#define VV_TF2D_MAX_WIDGETS 16

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
 * The colour of label @p label in a label volume (a categorical transfer
 * function): hues a golden-ratio turn apart (neighbouring labels far apart
 * on the colour wheel), saturation 0.65, value 0.95; label 0 is black.
 * RGB in [0, 1]. Thread-safe.
 */
vv_vec3 vv_label_color(uint32_t label);
/**
 * The key vv_label_color colours label id @p id (a voxel of a label volume:
 * uint8 .. uint32, or uint64 read as a double): 0 for ids below 1/2 (the
 * background), the id rounded below 2^32, else its two 32-bit halves
 * xor-ed (1 where that is 0), so that the 64-bit ids of connectomics
 * segmentations (MICrONS, H01: ids past 2^50) keep colours of their own.
 * Thread-safe.
 */
uint32_t vv_label_key(double id);
/**
 * Replaces the TF with a ramp: opacity 0 at lo rising linearly to
 * @p max_opacity at hi, colour @p color throughout.
 */
void vv_tf_set_ramp(vv_tf *tf, double lo, double hi, double max_opacity, vv_vec3 color,
                    double unit_distance);

/**
 * Transfer-function presets. @p name is one of vv_tf_preset_names(), in
 * three families:
 *  - CT, in Hounsfield units: "ct-bone" (bone opaque and ivory, below about
 *    150 HU transparent), "ct-soft-tissue" (skin and soft tissue faint and
 *    reddish, bone opaque), "ct-lung", "ct-vessels" (contrast 150..500 HU),
 *    "ct-muscle", "ct-skin", "ct-fat". They are placed on the volume's
 *    values thus: a volume whose minimum is below -200 is taken as HU; one
 *    whose values lie in [-200, 65535] with a maximum of at least 1200 (CT
 *    stored unsigned, e.g. 0..4095) as HU + 1024; any other range (8-bit
 *    CT) as [-1024, 3071] HU stretched linearly over the volume's range.
 *  - MR, without absolute units, from the 50th to the 99th percentile of
 *    the volume's values: "mr" (a grey ramp), "mr-t1-brain", "mr-t2-brain",
 *    "mr-angio".
 *  - Any data, from the 1st to the 99.5th percentile: "mip" (black to
 *    white, for maximum intensity projection), "grey", "fire",
 *    "microscopy-green", "microscopy-magenta", "microscopy-cyan",
 *    "hot-iron", "viridis", "inferno", "cool-warm" (diverging),
 *    "top-5-percent".
 * vv_tf_preset_description gives each a one-line description.
 * @p v may be NULL only for the CT presets (then HU). The TF's
 * opacity_unit_distance is the smallest voxel spacing of @p v (1 without
 * a volume). Errors: VV_ERR_INVALID (unknown name, with the list; NULL
 * tf; an MR or data preset without a volume).
 */
vv_status vv_tf_preset(vv_tf *tf, const char *name, const vv_volume *v);
/** The names vv_tf_preset accepts, NULL-terminated; static storage. */
const char *const *vv_tf_preset_names(void);
/** The one-line description of preset @p name (static storage), or NULL for an unknown name. */
const char *vv_tf_preset_description(const char *name);

/**
 * The opacity unit distance a transfer function of @p v starts with: the
 * smallest voxel spacing of @p v (world units), or 1 when that is not
 * positive and finite. Thread-safe.
 */
double vv_tf_default_unit_distance(const vv_volume *v);

/* ---- 2-D transfer function (value x gradient magnitude) ------------------ */

/**
 * Widget shapes of a 2-D transfer function (Kniss, Kindlmann and Hansen,
 * "Multidimensional transfer functions for interactive volume rendering",
 * IEEE TVCG 2002).
 */
typedef enum vv_tf2d_shape {
    /** value[0..1] x gradient[0..1], with soft edges `ramp` (value) and
     * `gradient_ramp` (gradient magnitude) inside the box */
    VV_TF2D_RECTANGLE = 0,
    /** Kniss's triangle: apex at (center, gradient magnitude 0), widening
     * linearly to `width` (the full base width, data units) at gradient
     * magnitude gradient[1]; cut below gradient[0]. Opacity falls linearly
     * from the centre line (value = center) to 0 at the slanted edges. */
    VV_TF2D_TRIANGLE = 1
} vv_tf2d_shape;

/**
 * One widget. Data values in the volume's units; gradient magnitudes in
 * data units per world unit of the volume's own coordinates (voxel spacing
 * and direction applied, the object transform not), by central differences
 * (vv_histogram2d_compute uses the same definition).
 */
typedef struct vv_tf2d_widget {
    vv_tf2d_shape shape;
    double value[2];      /**< rectangle: value range, value[0] <= value[1] */
    double gradient[2];   /**< gradient-magnitude range, 0 <= gradient[0] <= gradient[1] */
    double ramp;          /**< rectangle: soft edge (data units) inside each value edge, >= 0 */
    double gradient_ramp; /**< rectangle: soft edge inside each gradient edge, >= 0 */
    double center;        /**< triangle: apex value */
    double width;         /**< triangle: base width at gradient[1], data units, > 0 */
    vv_vec3 color;        /**< RGB in [0, 1] */
    double opacity;       /**< peak opacity in [0, 1], per opacity_unit_distance */
} vv_tf2d_widget;

/**
 * A 2-D transfer function: up to VV_TF2D_MAX_WIDGETS widgets. Where widgets
 * overlap they combine as independent absorbers: opacity = 1 - prod(1 -
 * a_i), colour = sum(a_i c_i) / sum(a_i) (opacity-weighted mean), so the
 * order of widgets does not matter. Outside every widget the opacity is 0.
 * Opacity is per opacity_unit_distance of ray length, as in vv_tf.
 */
typedef struct vv_tf2d {
    int n_widgets;
    vv_tf2d_widget widgets[VV_TF2D_MAX_WIDGETS];
    double opacity_unit_distance; /**< world units, > 0 */
} vv_tf2d;

/** No widgets (transparent everywhere), unit distance 1. */
void vv_tf2d_init(vv_tf2d *tf);
/** A rectangle widget value [v0, v1] x gradient [g0, g1], hard edges. */
void vv_tf2d_widget_init_rectangle(vv_tf2d_widget *w, double v0, double v1, double g0, double g1,
                                   vv_vec3 color, double opacity);
/** A triangle widget: apex value @p center, base @p width at gradient magnitude @p g1. */
void vv_tf2d_widget_init_triangle(vv_tf2d_widget *w, double center, double width, double g1,
                                  vv_vec3 color, double opacity);
/**
 * Checks a widget: finite parameters, ordered ranges, ramps >= 0, triangle
 * width > 0 and gradient[1] > 0, colour and opacity in [0, 1]. Errors:
 * VV_ERR_INVALID naming the bad parameter.
 */
vv_status vv_tf2d_widget_check(const vv_tf2d_widget *w);
/** Appends a copy of @p w after vv_tf2d_widget_check. Errors: VV_ERR_INVALID, VV_ERR_LIMIT. */
vv_status vv_tf2d_add_widget(vv_tf2d *tf, const vv_tf2d_widget *w);
/** Opacity in [0, 1] of one widget at (value, gradient magnitude), its colour aside. */
double vv_tf2d_widget_opacity(const vv_tf2d_widget *w, double value, double gradient);
/**
 * Opacity (per unit distance) and colour at (value, gradient magnitude)
 * under the combination rule above; colour white where the opacity is 0.
 * NaN inputs give opacity 0. Either output may be NULL.
 */
void vv_tf2d_eval(const vv_tf2d *tf, double value, double gradient, double *opacity,
                  vv_vec3 *color);
/** The largest gradient[1] of the widgets (0 without widgets). */
double vv_tf2d_gradient_max(const vv_tf2d *tf);

/* ---- textures (object colour and texture, VolVis paper section 4) -------- */

/**
 * A 2-D image used as a texture, shared by reference between objects and
 * World snapshots (vv_object_clone). Immutable once made; ref and free are
 * atomic, so snapshots on other threads may hold it.
 */
typedef struct vv_texture_image {
    vv_image *image; /**< owned; colour = rgb, alpha ignored */
    char *source;    /**< file name for scene saving (owned, may be NULL) */
    int refcount;    /**< internal; use vv_texture_image_ref / _free */
} vv_texture_image;

/** Wraps @p image (ownership taken, also on failure) with refcount 1. */
vv_status vv_texture_image_new(vv_texture_image **out, vv_image *image, const char *source);
/** Takes one more reference; returns @p t. */
vv_texture_image *vv_texture_image_ref(vv_texture_image *t);
/** Drops one reference, freeing on the last. Accepts NULL. */
void vv_texture_image_free(vv_texture_image *t);

/** How object points map to texture coordinates. */
typedef enum vv_texture_projection {
    VV_TEXTURE_PLANAR = 0,      /**< (s, t) = (d.U, d.V), world units */
    VV_TEXTURE_CYLINDRICAL = 1, /**< s = angle about the axis / 2pi, t = d.W (world units) */
    VV_TEXTURE_SPHERICAL = 2    /**< s = angle about the axis / 2pi, t = polar angle from +W / pi */
} vv_texture_projection;

/**
 * An image texture on an object. In object coordinates (a geometric
 * object's shape coordinates; a volume's own world coordinates, before the
 * object transform), d = point - center and the frame is W = axis, U =
 * the unit part of X (or Y when W is within 25 degrees of X) perpendicular to W,
 * V = W x U; the angle is atan2(d.V, d.U) in [0, 2pi). Texture
 * coordinates (u, v) = (scale[0] s, scale[1] t), looked up with
 * bilinear filtering, repeating; the texture colour multiplies the material
 * colour.
 */
typedef struct vv_texture_map {
    vv_texture_image *image; /**< one reference held; NULL: no texture */
    vv_texture_projection projection;
    vv_vec3 center;  /**< object coordinates */
    vv_vec3 axis;    /**< unit */
    double scale[2]; /**< repeats per unit of s and t (planar: per world unit), != 0 */
} vv_texture_map;

/** No image, planar, centre 0, axis +z, scale (1, 1). */
void vv_texture_map_init(vv_texture_map *m);
/** Texture colour at object point @p q; white when there is no image. */
vv_vec3 vv_texture_map_eval(const vv_texture_map *m, vv_vec3 q);
/** Name of a projection ("planar", ...); never NULL. */
const char *vv_texture_projection_name(vv_texture_projection p);
/** Projection from its name. Errors: VV_ERR_INVALID. */
vv_status vv_texture_projection_parse(const char *name, vv_texture_projection *out);

/** What a solid (3-D) texture is. */
typedef enum vv_solid_texture_kind {
    VV_SOLID_TEXTURE_NONE = 0,
    VV_SOLID_TEXTURE_CHECKER = 1, /**< cubes of side `period`: color0 where floor(x/p) + floor(y/p)
                                       + floor(z/p) (d = point - center) is even, else color1 */
    VV_SOLID_TEXTURE_WOOD = 2,    /**< rings about the axis through center, `period` apart,
                                       distorted by `turbulence` times seeded noise */
    VV_SOLID_TEXTURE_MARBLE = 3,  /**< veins: sin along the axis plus turbulence, `period` apart */
    VV_SOLID_TEXTURE_VOLUME = 4   /**< a second volume sampled at the point (its own world
                                       coordinates), normalised through its range to f in [0, 1]:
                                       colour = color0 + f (color1 - color0); 0 outside it */
} vv_solid_texture_kind;

/**
 * A solid texture: a colour at every object point (a volume's own world
 * coordinates) that multiplies the colour of composited volume samples
 * (the transfer function's colour). Procedural patterns mix color0 and
 * color1 by a weight f in [0, 1]; noise is a deterministic value noise of
 * @p seed (the same image on every run and thread count).
 */
typedef struct vv_solid_texture {
    vv_solid_texture_kind kind;
    vv_vec3 color0, color1; /**< RGB in [0, 1] */
    double period;          /**< world units, > 0 */
    vv_vec3 center;         /**< object coordinates */
    vv_vec3 axis;           /**< unit: wood's trunk axis, marble's vein direction */
    double turbulence;      /**< noise amplitude, in periods, >= 0 */
    unsigned seed;
    vv_volume *volume; /**< VV_SOLID_TEXTURE_VOLUME: one reference held */
    char *source;      /**< the volume's file name for scene saving (owned, may be NULL) */
} vv_solid_texture;

/** Kind none, colours black and white, period 1, centre 0, axis +z, turbulence 0, seed 1. */
void vv_solid_texture_init(vv_solid_texture *s);
/** Colour at object point @p q (white for kind none). Thread-safe. */
vv_vec3 vv_solid_texture_eval(const vv_solid_texture *s, vv_vec3 q);
/** Name of a kind ("none", "checker3d", "wood", "marble", "volume"); never NULL. */
const char *vv_solid_texture_kind_name(vv_solid_texture_kind k);
/**
 * Sets @p s to sample @p volume (the texture takes its own reference;
 * @p source may be NULL). Errors: VV_ERR_INVALID, VV_ERR_NOMEM.
 */
vv_status vv_solid_texture_set_volume(vv_solid_texture *s, vv_volume *volume, const char *source);
/** Releases what @p s holds (volume reference, source) and re-initialises it. */
void vv_solid_texture_clear(vv_solid_texture *s);

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
    /** Light emitted (radiosity): a surface's radiant exitance from each side, display
        units (a patch of emission e shows as e); a volume's opaque regions show it. RGB,
        each >= 0; 0 by default. Only the radiosity renderer uses it. */
    vv_vec3 emission;
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
    VV_OBJECT_MESH = 6,     /**< geometry.mesh (a triangle mesh) */
    VV_OBJECT_GRID = 7      /**< an irregular grid (grid.h): grid, field, component, time */
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
    char *filters;     /**< volume: the filter chain applied at load, as command-line text
                            ("--gaussian 1 --median 1"; owned, may be NULL), for scene saving */
} vv_geometry;

typedef enum vv_render_mode {
    VV_MODE_COMPOSITE = 0, /**< front-to-back compositing through the TF */
    VV_MODE_MIP = 1,       /**< maximum intensity projection */
    VV_MODE_MINIP = 2,     /**< minimum intensity projection */
    VV_MODE_XRAY = 3,      /**< average value along the ray */
    VV_MODE_ISO = 4,       /**< first isosurface hit, shaded */
    /** napari's attenuated maximum intensity projection (VisPy's volume
     * shader): the maximum along the ray of each sample value v_i scaled by
     * exp(-attenuation (S_i - 1) / step), S_i the sum of the samples'
     * contrast-normalised values clamp((v - lo) / (hi - lo), 0, 1) up to and
     * including sample i, [lo, hi] the contrast limits: the values of the
     * transfer function's first and last opacity points (the volume's range
     * when they do not span one), step vv_object.step; the scaled maximum is
     * coloured through the transfer function like MIP. Far structures behind
     * bright ones fade. */
    VV_MODE_ATTENUATED_MIP = 5
} vv_render_mode;

/** The number of render modes (vv_render_mode values 0..VV_MODE_COUNT - 1). */
#define VV_MODE_COUNT 6

typedef enum vv_segmentation {
    VV_SEG_TRANSFER_FUNCTION = 0, /**< opacity and colour from tf */
    VV_SEG_THRESHOLD = 1,         /**< opaque in material.color where value >= threshold */
    VV_SEG_TRANSFER_FUNCTION_2D =
        2 /**< opacity and colour from tf2d (value x gradient magnitude) */,
    VV_SEG_LABELS = 3 /**< a label volume (vv_filter_components): label 0 transparent, every
                           other label opaque in vv_label_color(label) */
} vv_segmentation;

/** Channels of one volume object at most (vv_object.channels). */
#define VV_MAX_CHANNELS 16

/**
 * How the channels of a multi-channel volume object combine along a ray
 * (vv_object.blend; the ray caster and the ray tracer draw them).
 */
typedef enum vv_channel_blend {
    /** Per sample, the visible channels' opacities combine as independent
     * absorbers, alpha = 1 - prod(1 - alpha_c), and their shaded colours mix
     * weighted by opacity, colour = sum(alpha_c colour_c) / sum(alpha_c);
     * the mixed sample is composited front to back (Kniss, Premoze, Ikits,
     * Lefohn, Hansen, Praun, "Gaussian Transfer Functions for Multi-Field
     * Volume Visualization", IEEE Visualization 2003: the multi-field mix).
     * Symmetric in the channels: no channel hides another where they
     * overlap, and no dark seams. */
    VV_BLEND_COMPOSITE = 0,
    /** Each visible channel is composited along the ray on its own (its own
     * accumulated opacity) and the channels' colours are added (napari's
     * blending='additive'): the image is the sum of the single-channel
     * images over a black background. */
    VV_BLEND_ADDITIVE = 1,
    /** A maximum intensity projection per channel, each maximum coloured by
     * its channel's transfer function (colour times opacity at that value),
     * the channels added: the fluorescence microscopist's standard view. */
    VV_BLEND_MAXIMUM = 2
} vv_channel_blend;

/** "composite", "additive", "maximum"; NULL for an unknown value. */
const char *vv_channel_blend_name(vv_channel_blend b);
/** Parses a vv_channel_blend_name(). Errors: VV_ERR_INVALID (names the choices). */
vv_status vv_channel_blend_parse(const char *name, vv_channel_blend *out);

/**
 * One channel of a multi-channel volume object: its voxels, its transfer
 * function, whether it is drawn, its name (e.g. the OME channel name).
 */
typedef struct vv_channel {
    char name[VV_NAME_MAX];
    vv_volume *volume; /**< one reference held; the same dims as every channel of the object */
    vv_tf tf;          /**< its classification (opacity and colour) */
    int visible;       /**< 0: left out of the image */
    int index;         /**< its channel in the object's file (a scene file's "channel"), from 0 */
    int labels;        /**< 1: a label volume (segment ids; vv_object_set_channel_labels): label 0
                            transparent, every other label opaque in vv_label_color(label), as
                            VV_SEG_LABELS; tf is kept but not used */
} vv_channel;

/**
 * Colour @p index of the default channel colours: magenta, green, cyan,
 * yellow (the colour-blind-safe additive set of fluorescence microscopy,
 * where magenta and green replace red and green), then Okabe and Ito's
 * palette (orange, sky blue, bluish green, vermillion, blue, reddish
 * purple); repeats after 10.
 */
vv_vec3 vv_channel_default_color(int index);

/**
 * Default contrast limits of a channel, for a fluorescence stack where most
 * voxels are background: lo is the background's level plus three standard
 * deviations of its noise, estimated from the quartiles (q50 + 4.5 (q75 -
 * q50), q50 itself when that reaches hi), hi the 99.99 % quantile
 * (vv_volume_quantile: a 4096-bin histogram), so that sparse bright
 * structures show and the background stays clear; the value range where
 * those coincide (lo + 1 above a constant volume).
 */
void vv_channel_default_contrast(const vv_volume *v, double *lo, double *hi);

/**
 * The microscopy shorthand for a channel's transfer function: colour
 * @p color throughout, opacity 0 up to @p lo (the lower contrast limit),
 * rising as ((v - lo) / (hi - lo))^gamma to @p max_opacity at @p hi and
 * staying there (sampled at 9 points when gamma is not 1). Errors:
 * VV_ERR_INVALID for hi <= lo, a gamma outside [0.05, 20], an opacity
 * outside [0, 1] or a unit distance <= 0.
 */
vv_status vv_tf_set_contrast(vv_tf *tf, double lo, double hi, double gamma, double max_opacity,
                             vv_vec3 color, double unit_distance);

/**
 * The contrast limits, gamma, opacity and colour of @p tf read back as
 * vv_tf_set_contrast's parameters (the GUI's contrast sliders): lo the
 * first opacity point's value, hi the first point at the highest opacity
 * (lo + 1 when that is not above lo), gamma the least-squares fit of
 * log(opacity / max) = gamma log((v - lo) / (hi - lo)) over the points
 * between (1 for a straight ramp; clamped to [0.05, 20]), the colour at hi.
 * Any output may be NULL. Returns 1 when vv_tf_set_contrast with those
 * makes @p tf again (a contrast function), 0 for any other function (the
 * values are then the nearest contrast function's) or a function of fewer
 * than two opacity points. Reads @p tf only; reentrant.
 */
int vv_tf_get_contrast(const vv_tf *tf, double *lo, double *hi, double *gamma, double *max_opacity,
                       vv_vec3 *color);

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
    double threshold;       /**< VV_SEG_THRESHOLD */
    vv_tf tf;               /**< VV_SEG_TRANSFER_FUNCTION; also the grey ramp of mip/minip/xray */
    vv_tf2d tf2d;           /**< VV_SEG_TRANSFER_FUNCTION_2D (composite mode; other modes use tf) */
    vv_texture_map texture; /**< image texture: geometry and isosurfaces (iso mode) */
    vv_solid_texture solid_texture; /**< solid texture: composited volume samples */
    vv_render_mode mode;
    double isovalue;    /**< VV_MODE_ISO */
    double attenuation; /**< VV_MODE_ATTENUATED_MIP: napari's attenuation, >= 0 (default 0.05;
                             napari's slider spans 0..0.5); 0 gives MIP */
    double step;        /**< sample step in units of the smallest voxel spacing, > 0 */
    int shading;        /**< 1: Phong shading from gradients; 0: emission only */
    int visible;
    int casts_shadows;          /**< 1: blocks light on its way to other points */
    int receives_shadows;       /**< 1: its points are shaded with shadow rays */
    int visible_in_reflections; /**< 1: seen by reflected and transmitted rays */
    int reflects;               /**< 1: spawns reflected rays when material.reflectance > 0 */
    int n_cut_planes;
    vv_cut_plane cut_planes[VV_MAX_CUT_PLANES]; /**< local, in world coordinates */
    vv_grid *grid;                              /**< VV_OBJECT_GRID: one reference held */
    char field[VV_GRID_FIELD_NAME_MAX];         /**< grid: field shown ("" = the first) */
    int component;                              /**< grid: vector component, -1 = magnitude */
    int time; /**< grid: time step (vv_grid_find_field); volume: the time step of its file
                   its voxels are (scene files' "time", vv_time_series users set it) */
    /** Volume objects with several channels (vv_object_set_channels): 0 for
     * an object of one channel (volume and tf), else 2..VV_MAX_CHANNELS;
     * channels[0].volume is also `volume`. */
    int n_channels;
    vv_channel *channels;   /**< n_channels entries, owned (freed and cloned with the object) */
    vv_channel_blend blend; /**< how the channels combine */
    /**
     * Where the voxels come from when they are not all in memory: a
     * bricked file or a pyramid read out of core (include/volvis/source.h;
     * one reference held); `volume` is then its proxy (a coarse volume over
     * the same world box: the defaults, previews and global effects are
     * drawn from it) and vv_renderer_render reads the voxels from here.
     * NULL: `volume` holds them all (in memory). An object of several
     * channels holds a source of as many (vv_object_set_channels_source),
     * each channel's volume its proxy.
     */
    vv_source *source;
} vv_object;

/**
 * A new volume object holding a reference to @p volume (borrowed; the object
 * takes its own reference): identity transform, composite mode, step 0.5, attenuation 0.05,
 * shading on, visible, material ka 0.1 kd 0.6 ks 0.3 shininess 30 colour
 * white, TF a white ramp from opacity 0 at range[0] to 1 at range[1] with
 * opacity_unit_distance the smallest voxel spacing; threshold and isovalue
 * the middle of the range. @p name may be NULL ("volume"); it is truncated
 * to VV_NAME_MAX - 1 bytes. Errors: VV_ERR_NOMEM, VV_ERR_INVALID.
 */
vv_status vv_object_new_volume(vv_object **out, vv_volume *volume, const char *name);
/**
 * A new volume object showing @p source (a reference is taken), framed by
 * the box of its level @p level (0: the finest): a memory source's volume
 * becomes the object's own (no source kept); any other source is kept in
 * `source` and its proxy (vv_source_proxy of @p level) becomes `volume`,
 * with the defaults of vv_object_new_volume taken from the proxy except
 * the transfer function's opacity_unit_distance, which is the smallest
 * voxel spacing of the level (so an image does not change with the level
 * drawn). @p name as vv_object_new_volume. Errors: VV_ERR_INVALID (NULL, no
 * such level), those of reading the proxy, VV_ERR_NOMEM.
 */
vv_status vv_object_new_source(vv_object **out, vv_source *source, int level, const char *name);

/**
 * Makes volume object @p obj (of one channel), whose `volume` is
 * @p source's proxy over level @p level (vv_source_proxy), show @p source
 * (a reference is taken; a memory source: nothing changes): its transfer
 * functions' opacity_unit_distance, where it is the proxy's default (its
 * smallest voxel spacing), becomes the level's. What vv_object_new_source
 * does after making the object from the proxy; for a World made from the
 * proxy (vv_world_new_for_volume). Errors: VV_ERR_INVALID (not such an
 * object, no such level). Not thread-safe on the same object.
 */
vv_status vv_object_attach_source(vv_object *obj, vv_source *source, int level);

/**
 * Replaces the voxels of volume object @p obj by @p volume (a reference is
 * taken) and drops its source: the object is then in memory (a filter's
 * result, a proxy edited). Errors: VV_ERR_INVALID (not a volume object of
 * one channel, NULL). Not thread-safe on the same object.
 */
vv_status vv_object_set_volume(vv_object *obj, vv_volume *volume);

/**
 * Makes @p obj (a volume object) an object of @p n channels (2..16): channel
 * c holds a reference to @p volumes[c] (borrowed), is named @p names[c]
 * (@p names or an entry may be NULL: "channel c"), visible, coloured
 * vv_channel_default_color(c) with contrast limits
 * vv_channel_default_contrast and opacity 0.5 per smallest voxel spacing
 * (vv_tf_set_contrast, gamma 1), index c. The object's `volume` becomes
 * volumes[0]; blend stays as it was. Replaces channels set before; drops
 * the object's source (the channels are in memory). Errors:
 * VV_ERR_INVALID (not a volume object, n out of range, a NULL volume, dims
 * differing from channel 0's: named), VV_ERR_NOMEM; on error @p obj is
 * unchanged. Not thread-safe on the same object.
 */
vv_status vv_object_set_channels(vv_object *obj, int n, vv_volume *const *volumes,
                                 const char *const *names);

/**
 * vv_object_set_channels over a source of several channels, out of core:
 * @p obj (a volume object) becomes an object of the @p source's channels
 * (vv_source_channels, 2..VV_MAX_CHANNELS; channel c of the object is the
 * source's channel c), each channel's volume its proxy over level
 * @p level (vv_source_channel_proxy: the coarsest level, for defaults,
 * previews and global effects) and its transfer function's opacity unit
 * the level's smallest voxel spacing; the renderers read the voxels from
 * the source (vv_renderer_render's level-of-detail driver, every channel
 * of a node at once). Names, colours and contrast as vv_object_set_channels
 * (contrast from the proxies). A reference to @p source is taken. Errors:
 * VV_ERR_INVALID (not a volume object, a source of one channel, no such
 * level), those of reading the proxies, VV_ERR_NOMEM; on error @p obj is
 * unchanged. Not thread-safe on the same object.
 */
vv_status vv_object_set_channels_source(vv_object *obj, vv_source *source, int level,
                                        const char *const *names);

/**
 * Replaces the source of volume object @p obj (out of core, one channel or
 * several) by @p source of the same geometry and as many channels (another
 * time step of the same file: vv_time_steps): its volumes become the new
 * source's proxies over level @p level, and everything else (transfer
 * functions, names, colours, visibility) stays. A reference to @p source
 * is taken. Errors: VV_ERR_INVALID (not an object with a source, another
 * channel count, proxies of another size: named), those of reading the
 * proxies; on error @p obj is unchanged. Not thread-safe on the same
 * object.
 */
vv_status vv_object_replace_source(vv_object *obj, vv_source *source, int level);

/**
 * Drops the source of volume object @p obj (one channel or several): its
 * volumes (the proxies out of core) become what it shows, in memory.
 * Nothing when it has none. What a renderer without the region contract
 * falls back to (vv_render_options.proxy_fallback). Not thread-safe on the
 * same object.
 */
void vv_object_drop_source(vv_object *obj);

/**
 * Marks channel @p c of multi-channel object @p obj as a label volume
 * (@p labels 1: segment ids, coloured by label as VV_SEG_LABELS colours a
 * one-channel object; label 0 transparent) or back to a transfer-function
 * channel (0). Every renderer that draws channels honours it under every
 * blend rule: composite and additive show each label's region opaque in
 * vv_label_color (the nearest non-zero label of a sample's cell, so colours
 * do not blend across labels); maximum projects the largest label. Errors:
 * VV_ERR_INVALID (not a multi-channel object, @p c out of range, a float
 * channel: labels are integers, @p labels not 0 or 1: named); on error
 * @p obj is unchanged. Not thread-safe on the same object.
 */
vv_status vv_object_set_channel_labels(vv_object *obj, int c, int labels);

/**
 * Replaces the voxels of volume object @p obj by another time step of the
 * same data (vv_time_series_get): @p volumes[0] for an object of one
 * channel, else one volume per channel in the object's channel order
 * (@p n is max(1, n_channels)); each borrowed, the object takes its own
 * reference. Transfer functions, names and everything else stay; the
 * object's source is dropped (the step is in memory). Errors:
 * VV_ERR_INVALID (not a volume object, @p n not the channel count, a NULL
 * volume, dims differing from the volume it replaces: named); on error
 * @p obj is unchanged. Not thread-safe on the same object (edit a copy,
 * as snapshots do).
 */
vv_status vv_object_replace_volumes(vv_object *obj, int n, vv_volume *const *volumes);

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
/**
 * A new grid object showing field @p field (NULL: the first; time step 0,
 * magnitude of vectors) of @p grid (the object takes its own reference),
 * with the defaults of vv_object_new_volume: TF a white ramp over the
 * field's range with opacity_unit_distance 1/100 of the largest bounding-box
 * extent. Errors: VV_ERR_INVALID (NULL grid, unknown field), VV_ERR_NOMEM.
 */
vv_status vv_object_new_grid(vv_object **out, vv_grid *grid, const char *field, const char *name);
/**
 * The index of the field a grid object shows (its field at its time step),
 * or -1 with an error message naming the field.
 */
int vv_object_grid_field(const vv_object *obj);
/** Releases an object, its references (volume, mesh, textures) and its geometry. Accepts NULL. */
void vv_object_free(vv_object *obj);
/**
 * A copy of @p obj: every field copied, the polygon vertices and mesh source
 * duplicated, one more reference taken on the volume, the mesh, the texture
 * image and the solid texture's volume (its source duplicated) (voxels,
 * triangles and texels are shared, not copied: they are never changed in place by
 * the World's editors, so a copy is cheap). Thread-safe for concurrent
 * readers of @p obj. Errors: VV_ERR_INVALID (NULL), VV_ERR_NOMEM.
 */
vv_status vv_object_clone(vv_object **out, const vv_object *obj);
/**
 * Sets an object's image texture: @p image (may be NULL: none) gets a
 * reference; the old one is released. Projection parameters are kept.
 */
void vv_object_set_texture_image(vv_object *obj, vv_texture_image *image);
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
 * vv_world_new_for_volume of @p source: a memory source's volume, or
 * another source's proxy over level @p level (vv_source_proxy: the
 * transfer function from its histogram, the view framing level @p level's
 * box) with the object showing the source (vv_object_attach_source).
 * Errors: those of both, of reading the proxy.
 */
vv_status vv_world_new_for_source(vv_world **out, vv_source *source, int level,
                                  const vv_default_scene_options *opt);

/**
 * Gives volume object @p obj the appearance the default scene gives a file
 * opened alone (docs/scene-format.md, "Default scene"), for the object's
 * own mode: the transfer function of vv_tf_default from the histogram of
 * @p histogram (NULL: the object's volume; a pyramid's coarsest level, so
 * that a store looks the same read whole or out of core), its
 * opacity_unit_distance the smallest voxel spacing of @p shown (NULL: the
 * object's volume; out of core the level drawn, vv_source_level, not the
 * proxy's), and the isovalue and threshold at the ramp's low end. What
 * vv_world_new_for_volume, vv_world_open and scene files whose objects
 * give no transfer function use. Does nothing to other objects (NULL, not
 * a volume). Not thread-safe on the same object.
 */
void vv_object_default_appearance(vv_object *obj, const vv_volume *histogram,
                                  const vv_volume *shown);

/**
 * Points and frames @p w's view as vv_world_new_for_volume does, on the
 * World as it is: perspective, fov 30°, up +z, from the front of the first
 * visible volume object's volume (-y for VV_SPACE_LPS, else +y; a single
 * slice face on), or from -y when there is none (grids, geometry); framed
 * on vv_world_bounds (vv_view_frame_box) at the view's own image size,
 * orbited by @p opt's azimuth and elevation, the eye distance divided by
 * its zoom, ortho_height the height of the view at its centre. For a World
 * of one volume object this is the default scene's view of its file. With
 * @p headlight, also adds the default scene's white headlight of intensity 1.
 * Objects, ambient and background are left as they are. @p opt may be
 * NULL (no rotation, zoom 1; its mode, size and ranges are not used).
 * Errors: VV_ERR_INVALID (NULL, bad zoom or angles), VV_ERR_LIMIT (no room
 * for a light).
 */
vv_status vv_world_fit_default_view(vv_world *w, const vv_default_scene_options *opt,
                                    int headlight);

/**
 * A World showing one irregular grid, the grid counterpart of
 * vv_world_new_for_volume: a grid object (vv_object_new_grid) showing
 * @p field (NULL: the first scalar field, else the first field) at time
 * step @p time, centred on the origin, the same view, headlight and
 * background; mode, size, angles and zoom from @p opt (may be NULL). Its
 * transfer function is a white ramp from opacity 0 at 10% of the field's
 * range to 0.5 at its top (or opt's range) per 1/20 of the grid's largest
 * extent; the isovalue is the middle of the range. The World's render
 * settings name the "irregular" renderer for a grid with 3-D cells and the
 * "raster" renderer for a grid of surface cells only (blow.vtk), which
 * shows the surface coloured by the field. Errors: VV_ERR_INVALID (bad
 * options, unknown field), VV_ERR_NOMEM.
 */
vv_status vv_world_new_for_grid(vv_world **out, vv_grid *grid, const char *field, int time,
                                const vv_default_scene_options *opt);

/**
 * The default transfer function of @p v for @p mode (docs/scene-format.md,
 * "Default scene"): for the projection modes (MIP, MinIP, X-ray,
 * attenuated MIP) a grey
 * ramp from the 1st to the 99.9th percentile of the values; for the others
 * an opacity ramp with a warm colour map over the foreground (the
 * histogram's background peak left out: 2 % to 99.5 % of the remaining
 * count); unit distance vv_tf_default_unit_distance.
 * Fills @p tf and stores the composite ramp's lower end in *@p iso_lo (may
 * be NULL), a default isovalue. What vv_object_default_appearance uses.
 * Never fails; thread-safe.
 */
void vv_tf_default(vv_tf *tf, const vv_volume *v, vv_render_mode mode, double *iso_lo);

/**
 * The values of @p v's foreground between its quantiles @p q_lo and @p q_hi
 * (fractions in [0, 1], q_lo < q_hi) into *@p lo < *@p hi: the voxels left
 * when the histogram's background peak (air in CT, the dark surround of an
 * MRI; vv_tf_default's rule) is set aside; every voxel when (almost) all
 * are background. The value range when the quantiles coincide. Data
 * values; never fails; thread-safe.
 */
void vv_volume_foreground_range(const vv_volume *v, double q_lo, double q_hi, double *lo,
                                double *hi);

#ifdef __cplusplus
}
#endif
#endif
