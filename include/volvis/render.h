/*
 * VolVis rendering, the user's side: pick a rendering method by name, read
 * what it draws and which options it takes, set them, render a World.
 *
 * A renderer turns a World plus a View into an image (RGBA float + depth,
 * see image.h). Every method is listed in one registry
 * (src/render/registry.c) with a vv_renderer_info: its capabilities (the
 * object kinds and modes it draws, whether it renders regions for
 * out-of-core and distributed rendering) and a declarative table of typed
 * options. The CLI's --set and --help, `volvis renderers`, scene files'
 * "render.options", the GUI's Rendering page and Python all read that one
 * table; values are validated from it. Implementing a method is the other
 * side (include/volvis/sys/renderer.h, libgit2's include/git2/sys/ split).
 *
 * Thread-safety: one vv_renderer must not render from two threads at once;
 * distinct renderers are independent. The registry and the info records are
 * immutable and may be read from any thread. A renderer may cache
 * per-volume data (gradients, subvolume min/max) between renders; the cache
 * is keyed on the volume and its `modified` counter and holds a reference
 * to the volume.
 */
#ifndef VOLVIS_RENDER_H
#define VOLVIS_RENDER_H

#include "core.h"
#include "image.h"
#include "model.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * The work of a render, counted for measurements (bench/bench_raycast's
 * shaded samples per second against the machine's peak). Counts are added
 * to what the struct holds; a render that counts nothing leaves it.
 * Fields are only ever added at the end: initialise with `{0}` or by
 * designated fields.
 */
typedef struct vv_render_stats {
    uint64_t samples; /**< samples taken along rays (value and transfer-function entry) */
    uint64_t shaded;  /**< of those, the samples that contributed: shaded and composited */
    /** shaded volumes (objects or channels) whose gradients were computed
     * at the samples, slower, because their cached gradients (2 bytes a
     * voxel) fit neither the renderer's gradient_budget_mb nor half the
     * memory left (the ray caster counts them; others add nothing) */
    uint32_t gradients_at_samples;
    /** milliseconds the device spent on the frame's commands, between two
     * timestamps around them (the gpu renderer: uploads, the ray casting
     * dispatch and the copy back; others add nothing) */
    double device_ms;
    /** shading tables the frame built (the ray caster's shading=table: a
     * diffuse and a specular term per normal code, rebuilt when a light,
     * the view direction, the material or the object's orientation
     * changed; 0 when the previous frame's served) */
    uint32_t shading_tables_built;
    /** bytes of volume data the frame copied to the device: voxel values,
     * gradient codes and gradient magnitudes of a volume or of its bricks
     * (the gpu renderer; the frame's uniforms, transfer-function tables and
     * subvolume min/max, a few KiB a brick, are not counted; others add
     * nothing) */
    uint64_t upload_bytes;
    /** bricks (the regions of a volume drawn out of core, by the drivers or
     * over the device's memory) the frame found on the device, in the gpu
     * renderer's brick cache (option device_memory_mb); others add nothing */
    uint32_t cache_hits;
    /** bricks the frame uploaded to the device because the brick cache did
     * not hold them (first seen, evicted, or the cache is off); others add
     * nothing */
    uint32_t cache_misses;
} vv_render_stats;

#define VV_LOD_MAX_LEVELS 16 /**< levels a level-of-detail frame draws from */

/**
 * Level of detail of a frame that draws objects from pyramids
 * (vv_render_options.lod), and what the frame used (summed over the
 * objects).
 */
typedef struct vv_lod {
    /**
     * In: >= 0: every node at this level (the coarsest when past it); -1:
     * each node at the coarsest level whose voxel projects to at most
     * voxel_pixels pixels at the node's point nearest the eye (screen-space
     * error).
     */
    int level;
    double voxel_pixels; /**< in: > 0 (default 1; larger is coarser and faster) */
    /**
     * In: 1: a progressive frame -- a node is drawn at its level when the
     * source holds its chunks, or when they fit in what is left of
     * load_budget chunks (nodes nearest the eye first); otherwise at the
     * finest coarser level the source holds (the coarsest at worst), and
     * counted in pending. Needs the source's missing_chunks. 0: every node
     * at its level, read as needed.
     */
    int progressive;
    int load_budget; /**< in: chunks a progressive frame may read (>= 0) */
    /**
     * In: 1 (with progressive, when the source loads in the background, as
     * pyramids do): the frame then asks the source for
     * its pending nodes' chunks -- at their own level and every coarser one
     * short of the coarsest, coarse levels first, then front to back --
     * and for those of the nodes drawn at their level (held: so that the
     * loader keeps them while it makes room for the others),
     * replacing the previous frame's request (none pending: cancelled), so
     * that a later frame draws them finer: draw, wait (vv_source_wait),
     * draw again until pending is 0 (what the GUI and Python do while the
     * view stands still). 0: no request (the frames depend on the budget
     * alone).
     */
    int background;
    int nodes[VV_LOD_MAX_LEVELS]; /**< out: nodes rendered at each level */
    int skipped;   /**< out: nodes skipped unread (their known min/max is transparent) */
    int pending;   /**< out: nodes drawn coarser than their level (0: the converged image) */
    int requested; /**< out: boxes a progressive frame asked the source to load */
    /**
     * Out: 1 when a background frame found the previous request stalled
     * (the source's cache is full of the chunks the view wants, and nodes
     * are still pending): waiting will not sharpen it further; a frame with
     * progressive 0 streams the converged image through the cache.
     */
    int stalled;
    /** Out: why the frame drew the objects' proxies in memory
     *  (vv_render_options.proxy_fallback); "" when it drew them out of core. */
    char note[160];
} vv_lod;

/** level -1 (screen-space error), voxel_pixels 1, counts 0. */
void vv_lod_init(vv_lod *lod);

#define VV_SOURCES_MAX 16 /**< visible volume objects out of core one frame draws */

/** vv_pixels8.format: the layout of a render's 8-bit frame. */
typedef enum vv_pixels8_format {
    VV_PIXELS8_RGBX = 0,   /**< 4 bytes a pixel, R G B and alpha */
    VV_PIXELS8_YUV420 = 1, /**< JPEG's Y, Cb and Cr planes, chroma 2 x 2 subsampled */
} vv_pixels8_format;

/**
 * Where a render also writes its frame as 8-bit pixels (`volvis serve`'s
 * JPEG input), rows top to bottom, each component of the float image as
 * (uint8)(clamp(v * 255 + 0.5, 0, 255)) (gamma 1), in one of two layouts:
 *
 * - VV_PIXELS8_RGBX (0, the default): `rgbx`, 4 bytes a pixel, width * 4
 *   bytes a row; X is the alpha.
 * - VV_PIXELS8_YUV420: `yuv`, the planes TurboJPEG's
 *   tjCompressFromYUVPlanes takes for TJSAMP_420 with NULL strides, one
 *   after the other (vv_pixels8_bytes): Y of pw x ph bytes, then Cb, then
 *   Cr, each pw/2 x ph/2, where pw and ph are width and height rounded up
 *   to even (the odd last column or row repeated, as libjpeg pads). The
 *   8-bit R, G, B go through JPEG/JFIF's full-range BT.601 transform in
 *   libjpeg's 16-bit fixed point (Y = 0.299 R + 0.587 G + 0.114 B, Cb =
 *   128 - 0.16874 R - 0.33126 G + 0.5 B, Cr = 128 + 0.5 R - 0.41869 G -
 *   0.08131 B) and Cb, Cr are averaged over 2 x 2 pixels with libjpeg's
 *   alternating bias: the planes are the bytes tjEncodeYUVPlanes makes of
 *   the RGBX frame, so the JPEG is the one tjCompress2 makes of it, without
 *   the encoder's colour pass. Alpha is dropped.
 *
 * The buffer is the caller's, of the view's width and height. A renderer
 * whose tiles write final pixels converts each tile on the worker thread
 * that drew it, while the tile is in that core's cache (the frame runner's
 * `image`; YUV needs tiles of even sides); for the others
 * vv_renderer_render converts the finished image. Either way, after a
 * successful render the buffer holds the frame and `converted_in_tiles`
 * says which way it went. Zero-initialised fields mean RGBX.
 */
typedef struct vv_pixels8 {
    uint8_t *rgbx;          /**< RGBX: 4 * width * height bytes, the caller's */
    int width, height;      /**< its size, pixels: the view's */
    int converted_in_tiles; /**< out: 1 by the tiles that drew them, 0 after the frame */
    int format;             /**< vv_pixels8_format */
    uint8_t *yuv;           /**< YUV420: vv_pixels8_bytes bytes, the caller's */
} vv_pixels8;

/**
 * The bytes of an 8-bit frame of @p width x @p height pixels in @p format
 * (vv_pixels8_format): 4 w h for RGBX; pw ph + 2 (pw/2)(ph/2) for YUV420,
 * pw and ph the sides rounded up to even. 0 for an unknown format or a
 * side < 1. Thread-safe.
 */
size_t vv_pixels8_bytes(int format, int width, int height);

/** Options of one render call. */
typedef struct vv_render_options {
    int threads;          /**< <= 0: vv_threads_get() */
    int quality;          /**< 0 draft .. 2 final; what it means: vv_renderer_info.quality */
    vv_progress progress; /**< reports the fraction of image tiles done; may cancel */
    /** NULL, or where the render adds the work it did. Counted by the ray
     * caster's march of one composite volume (the common case and the
     * speed anchor), and by the gpu renderer (its device time, uploads and
     * brick cache); other renderers and paths add nothing. Counting
     * neither changes the image nor costs measurable time. */
    vv_render_stats *stats;
    /**
     * NULL (vv_lod_init's), or the level of detail of the objects drawn
     * from pyramids, and where the frame writes what it used: its level
     * (`--level`), its screen-space error (`--lod`), progressive frames.
     * Ignored by a World held in memory.
     */
    vv_lod *lod;
    /**
     * 1: objects out of core that the renderer cannot draw by regions (it
     * has no region contract, or the World is not one that layers draw:
     * overlapping composite objects, geometry beside them) are drawn from
     * their proxies in memory (vv_source_proxy: coarse) by the renderer's
     * whole-frame method, and lod->note says why; 0: that is
     * VV_ERR_UNSUPPORTED (what the CLI reports).
     */
    int proxy_fallback;
    /**
     * 1: a renderer that offers a cheaper shading uses it for this frame
     * whatever its options say (the ray caster: shading=table, Phong's
     * terms per normal code blended at the samples, >= 40 dB from Phong);
     * the Navigator's reduced previews set it. 0: the renderer's options
     * decide.
     */
    int fast_shading;
    /** NULL, or where a successful vv_renderer_render also leaves the frame
     *  in 8 bits (vv_pixels8); its size must be the view's. */
    vv_pixels8 *pixels8;
} vv_render_options;

/** threads 0, quality 2, no progress callback, no stats, no lod, no proxy fallback, the
 *  renderer's own shading, no 8-bit pixels. */
void vv_render_options_init(vv_render_options *o);

/* ---- typed option tables ------------------------------------------------ */

/** The type of a renderer option's value. */
typedef enum vv_option_type {
    VV_OPTION_BOOL = 0,   /**< "1" or "0" */
    VV_OPTION_INT = 1,    /**< a decimal integer within [min, max] */
    VV_OPTION_REAL = 2,   /**< a decimal number within [min, max] (ends open when flagged) */
    VV_OPTION_ENUM = 3,   /**< one of `words` */
    VV_OPTION_STRING = 4, /**< any text (a file name) shorter than VV_RENDER_OPTION_VALUE_MAX */
} vv_option_type;

/** vv_option_spec.flags */
#define VV_OPTION_MIN_OPEN 1u /**< the value must be > min (not >=) */
#define VV_OPTION_MAX_OPEN 2u /**< the value must be < max (not <=) */

/** Where a renderer keeps an option's value: the implementor's side (sys/renderer.h). */
typedef struct vv_option_binding vv_option_binding;

/**
 * One option of a renderer: what `--set KEY=VALUE` accepts. For INT and
 * REAL, `words` (may be NULL) lists words accepted besides numbers (e.g.
 * "auto", "exact"); for ENUM it lists every value. `def` is the default as
 * the text --set would take, and it passes the option's own validator
 * (tests/render/test_registry.c checks every table). A new renderer starts
 * with every option at its `def`, set as vv_renderer_set_option sets it.
 */
typedef struct vv_option_spec {
    const char *key;          /**< [a-z0-9_]+ */
    vv_option_type type;      /**< value type */
    const char *def;          /**< default, as text; never NULL ("" for an empty string) */
    double min, max;          /**< INT, REAL: the inclusive range (flags make ends open) */
    unsigned flags;           /**< VV_OPTION_MIN_OPEN, VV_OPTION_MAX_OPEN */
    const char *const *words; /**< NULL-terminated (see above), or NULL */
    const char *doc;          /**< one line: meaning and unit */
    /** The field of the renderer's state that holds the value, and how
     * (sys/renderer.h); readers of the table leave it alone. */
    const vv_option_binding *bind;
} vv_option_spec;

/** A validated option value (vv_option_parse). */
typedef struct vv_option_value {
    vv_option_type type; /**< the spec's type */
    int word;            /**< index into spec->words when the text was one of them, else -1 */
    int b;               /**< BOOL: 0 or 1 */
    long long i;         /**< INT (and BOOL as 0/1) */
    double r;            /**< INT, REAL: the number (NAN for a word) */
    const char *text;    /**< the text as given (borrowed from the caller) */
} vv_option_value;

/**
 * Parses and validates @p text as a value of option @p spec: type, range,
 * enumerated values. Errors: VV_ERR_INVALID with a one-line message naming
 * the key, the text and what is accepted ("early_termination: '2' is not in
 * (0, 1]"). Thread-safe.
 */
vv_status vv_option_parse(const vv_option_spec *spec, const char *text, vv_option_value *out);

/**
 * Writes what @p spec accepts into @p buf (e.g. "real in (0, 1]",
 * "post|pre", "integer in 1..16 or auto"); returns @p buf.
 */
const char *vv_option_describe(const vv_option_spec *spec, char *buf, size_t cap);

/** "bool", "int", "real", "enum" or "string". */
const char *vv_option_type_name(vv_option_type t);

/* ---- capabilities -------------------------------------------------------- */

/** vv_renderer_info.draws: the object kinds a renderer draws (1u << vv_object_type). */
#define VV_DRAWS(type) (1u << (unsigned)(type))
/** Every geometric primitive (plane, polygon, sphere, box, cylinder) and meshes. */
#define VV_DRAWS_GEOMETRY                                                                          \
    (VV_DRAWS(VV_OBJECT_PLANE) | VV_DRAWS(VV_OBJECT_POLYGON) | VV_DRAWS(VV_OBJECT_SPHERE) |        \
     VV_DRAWS(VV_OBJECT_BOX) | VV_DRAWS(VV_OBJECT_CYLINDER) | VV_DRAWS(VV_OBJECT_MESH))

/** vv_renderer_info.modes: the modes of volume and grid objects it draws (1u << vv_render_mode). */
#define VV_MODE_BIT(mode) (1u << (unsigned)(mode))
/** The five classic modes (composite, MIP, MinIP, X-ray, iso); VV_MODE_ATTENUATED_MIP is
 * drawn only by renderers that add its bit (raycast). */
#define VV_MODES_ALL                                                                               \
    (VV_MODE_BIT(VV_MODE_COMPOSITE) | VV_MODE_BIT(VV_MODE_MIP) | VV_MODE_BIT(VV_MODE_MINIP) |      \
     VV_MODE_BIT(VV_MODE_XRAY) | VV_MODE_BIT(VV_MODE_ISO))

/** vv_renderer_info.caps */
#define VV_RENDERER_REGION 1u      /**< renders regions (sys/renderer.h): out of core, MPI */
#define VV_RENDERER_QUALITY 2u     /**< the quality level changes the image */
#define VV_RENDERER_PREVIEW 4u     /**< draws the Navigator's reduced-resolution previews */
#define VV_RENDERER_PROGRESSIVE 8u /**< reserved: draws from resident data and refines */
#define VV_RENDERER_GLOBAL                                                                         \
    16u /**< pixels depend on objects off their primary ray                                        \
             (shadows, reflections, interreflection) */
/** draws every visible channel of a multi-channel volume object
 * (vv_object.channels) combined by its blend rule; a renderer without it
 * refuses such an object (vv_renderer_check_world) */
#define VV_RENDERER_CHANNELS 32u
/** draws on a device whose memory belongs to the renderer (the gpu
 * renderer's brick cache): the drivers draw its regions in turn with it,
 * never on clones of it for other threads (a clone's device and cache
 * would last one frame) */
#define VV_RENDERER_DEVICE 64u

/**
 * What a rendering method is, draws and takes. Immutable, owned by the
 * library. A renderer draws the visible objects of the kinds in `draws`
 * (volume and grid objects only in the `modes` listed) and leaves the other
 * kinds out; a World of which it draws nothing, or an object of a drawn
 * kind in a mode it does not draw, or a visible volume object of several
 * channels for a renderer without VV_RENDERER_CHANNELS, is an error
 * (vv_renderer_check_world).
 */
typedef struct vv_renderer_info {
    const char *name;              /**< registry key, e.g. "raycast" */
    const char *description;       /**< one line */
    unsigned draws;                /**< VV_DRAWS(...) bits */
    unsigned modes;                /**< VV_MODE_BIT(...) bits */
    unsigned caps;                 /**< VV_RENDERER_* bits */
    const char *quality;           /**< one line: what quality 0, 1, 2 mean to it */
    const vv_option_spec *options; /**< its options, n_options of them (may be NULL) */
    int n_options;
} vv_renderer_info;

/** Renderers in the registry (built in, then vv_renderer_register's). */
int vv_renderer_count(void);
/** Renderer @p i (0 .. vv_renderer_count() - 1) in registry order; NULL out of range. */
const vv_renderer_info *vv_renderer_info_at(int i);
/** The renderer called @p name, or NULL. */
const vv_renderer_info *vv_renderer_info_find(const char *name);
/** Option @p key of @p info, or NULL. */
const vv_option_spec *vv_renderer_info_option(const vv_renderer_info *info, const char *key);
/**
 * Validates `key=value` for the renderer @p info without creating one (the
 * GUI checks a field with it). Errors: VV_ERR_INVALID: unknown key (the
 * message lists the keys) or a bad value (vv_option_parse).
 */
vv_status vv_renderer_info_check_option(const vv_renderer_info *info, const char *key,
                                        const char *value);

/**
 * Checks that @p info can draw @p w: it must draw at least one visible
 * object (volume objects without a volume and grid objects without a grid
 * do not count), and every visible object of a kind it draws must be in a
 * mode it draws. Objects of other kinds are left out (not an error: the
 * CLI notes them). A World without visible objects passes (the background).
 * Errors: VV_ERR_UNSUPPORTED, one line naming the object, its kind or mode,
 * the renderer and the renderers that draw it.
 */
vv_status vv_renderer_check_world(const vv_renderer_info *info, const vv_world *w);

/**
 * The renderer for @p w: the one its render settings name, else the default
 * chosen from the capabilities: the first renderer in registry order
 * (raycast, raytrace, irregular, splat, surface, radiosity, fourier, gpu) that
 * draws every visible object of the World, else the first that draws the
 * most of them. A World of volumes gets raycast, volumes with geometry
 * raytrace, grids irregular, grids with volumes or geometry surface; an
 * empty World raycast. Never NULL; the pointer is into @p w or static.
 */
const char *vv_world_renderer(const vv_world *w);

/* ---- GPU devices ----------------------------------------------------------- */

/** A Vulkan device the gpu renderer can run on (vv_gpu_devices). */
typedef struct vv_gpu_device {
    char name[256];   /**< the driver's name, e.g. "NVIDIA H100 80GB HBM3", "llvmpipe (...)" */
    const char *kind; /**< "discrete GPU", "integrated GPU", "virtual GPU", "CPU", "other" */
    int cpu;          /**< 1: a CPU device (Mesa's lavapipe): never chosen on its own by the GUI */
    uint32_t api_version;  /**< VK_MAKE_API_VERSION form */
    uint64_t memory_bytes; /**< its largest device-local memory heap */
} vv_gpu_device;

/**
 * The Vulkan devices there are, in the driver's order (the numbers of the
 * gpu renderer's option `device`): up to @p max into @p out (may be NULL
 * with @p max 0); returns how many there are, 0 where there is no Vulkan
 * loader (libvulkan.so.1, opened at run time), no driver or the library
 * was built without Vulkan, and *why (may be NULL) then gets the reason
 * (a static string). The list is read once a process. Thread-safe.
 */
int vv_gpu_devices(vv_gpu_device *out, int max, const char **why);

/* ---- renderer objects ------------------------------------------------------ */

typedef struct vv_renderer vv_renderer;

/** Creates the method called @p name. Errors: VV_ERR_INVALID (unknown name), VV_ERR_NOMEM. */
vv_status vv_renderer_new(vv_renderer **out, const char *name);
/** Releases a renderer and its caches (and their volume references). Accepts NULL. */
void vv_renderer_free(vv_renderer *r);
/**
 * A new renderer of @p r's method with the options set on @p r so far
 * (vv_renderer_set_option, in the order first set, the last value of each),
 * without its caches: one for another thread. On failure *out is NULL.
 * Errors: those of vv_renderer_new and of setting the options.
 */
vv_status vv_renderer_clone(vv_renderer **out, const vv_renderer *r);
/** The method's registry name ("raycast"); owned by the library. */
const char *vv_renderer_name(const vv_renderer *r);
/** The method's info record; owned by the library. */
const vv_renderer_info *vv_renderer_get_info(const vv_renderer *r);
/**
 * Sets option @p key of the renderer from text, validated against its
 * option table (vv_renderer_info_check_option) before the renderer sees it;
 * docs/rendering.md and `volvis renderers` list every table. Errors:
 * VV_ERR_INVALID for an unknown key or a bad value, with a one-line message;
 * those of applying it (fourier's vvc=FILE: reading the file).
 */
vv_status vv_renderer_set_option(vv_renderer *r, const char *key, const char *value);

/**
 * Renders @p world seen through @p view into @p out, which must be
 * view->width x view->height. @p opt may be NULL (defaults). The World is
 * checked first (vv_renderer_check_world). This call alone chooses how
 * (src/render/drivers.h): a World whose visible objects hold their voxels
 * in memory is drawn whole by the renderer; one where a volume object
 * shows a file out of core (its `source`, vv_object_new_source) is drawn
 * object by object, each into a layer of its own -- a bricked file brick
 * by brick in front-to-back order, a pyramid by level of detail
 * (opt->lod), an object in memory as one region -- with the renderer's
 * region contract (VV_RENDERER_REGION), and the layers combined as the ray
 * caster combines objects along a ray: the composite and iso objects
 * composited front to back by depth, the MIP, MinIP and X-ray ones by the
 * largest classified colour behind them, the background last. Out of core
 * the image equals the in-memory render up to the rounding of compositing
 * (bit for bit for MIP, MinIP and X-ray) and to each object being sampled
 * at its own step; bricks and nodes whose known min/max the transfer
 * function makes transparent are skipped unread. Out of core needs: volume
 * objects only, each of one channel, at most VV_SOURCES_MAX visible; the
 * boxes of composite and iso objects apart; with several visible objects a
 * renderer without VV_RENDERER_GLOBAL. Errors: VV_ERR_INVALID (size
 * mismatch, bad World), VV_ERR_UNSUPPORTED (nothing it draws, a mode it
 * does not draw, what out of core needs: naming the objects), VV_ERR_LIMIT,
 * VV_ERR_NOMEM, VV_ERR_CANCELLED, those of reading the sources.
 */
vv_status vv_renderer_render(vv_renderer *r, const vv_world *world, const vv_view *view,
                             const vv_render_options *opt, vv_image *out);

/**
 * The renderer a World's render settings name (vv_render_settings, in
 * model.h), or "raycast" when none is set. Never NULL. Callers that have
 * the World use vv_world_renderer, which chooses by its objects.
 */
const char *vv_render_settings_renderer(const vv_render_settings *rs);
/** Their quality level, or 2 (final) when none is set. */
int vv_render_settings_quality(const vv_render_settings *rs);
/**
 * Passes every option of @p rs to @p r in order (vv_renderer_set_option),
 * so a renderer draws what `volvis render` of the saved scene draws.
 * Errors: VV_ERR_INVALID for an option the renderer refuses, with its key.
 */
vv_status vv_renderer_apply_settings(vv_renderer *r, const vv_render_settings *rs);
/**
 * A new renderer for @p w: vv_renderer_new of vv_world_renderer(w), then
 * the options of its render settings (vv_renderer_apply_settings; they
 * belong to the World's renderer). Errors: those of both.
 */
vv_status vv_renderer_new_for_world(vv_renderer **out, const vv_world *w);

/**
 * The surface a surface-drawing method shows for a volume object: in iso
 * mode its isovalue (colour material.color); threshold-segmented, its
 * threshold; else the lowest value at which the transfer function's opacity
 * reaches half its maximum over the volume's range, coloured by the transfer
 * function there. Returns 0 (and leaves @p iso unset) when the transfer
 * function is transparent over the whole range. Used by the `surface`
 * renderer and the Navigator's previews so they show the same surface.
 */
int vv_object_surface_value(const vv_object *obj, double *iso, vv_vec3 *color);

#ifdef __cplusplus
}
#endif
#endif
