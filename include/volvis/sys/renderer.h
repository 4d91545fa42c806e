/*
 * VolVis rendering, the implementor's side (include/volvis/render.h is the
 * user's): the versioned table a rendering method fills in, the region
 * contract that out-of-core and distributed rendering use, the frame runner
 * that owns the tile loop, and the camera-ray helper every ray-casting
 * method starts from. libgit2's include/git2/sys/ split; OSPRay's renderers
 * likewise supply the work of a tile while a load balancer owns the loop,
 * and distribution is a named contract (renderRegion), not a back channel.
 *
 * Adding a method: fill a vv_renderer_ops (version VV_RENDERER_OPS_VERSION,
 * a vv_renderer_info with its capabilities and option table, the size of
 * its state, render; init, release and render_region optional), and either
 * declare it in src/render/registry.h and list it in src/render/registry.c
 * (built in) or pass it to vv_renderer_register (a plug-in). Nothing else
 * names it: the CLI, the GUI, scene files and Python read the
 * registry. Options are data: each row of the option table binds to its
 * field of the state (VV_OPTION_BIND and its kin below), and the registry
 * allocates the state, sets every option to its default from the table's
 * text and stores each value set later, the same way for every method; a
 * method writes no default and no setter of its own, only a hook for an
 * option whose change has a side effect (a cache to drop, a file to read).
 *
 * A volume source (sys/source.h) feeds region renders brick by brick and
 * by levels of detail; a tile's work gets its rectangle and a per-thread scratch,
 * so a kernel may trace a packet of rays (8 with AVX2) per call instead of
 * one; channels are a property of the object, not of this interface.
 *
 * Thread-safety: the tables are immutable and the registry only grows
 * (vv_renderer_register). A method's
 * state serves one render (or region render) at a time (render.h); within
 * it, vv_frame_run calls the tile function on several threads at once, so
 * a tile writes only its own pixels and reads what the frame prepared.
 * Errors follow the library's convention (vv_status and the thread-local
 * trace; a tile's message is carried back to the caller's thread).
 */
#ifndef VOLVIS_SYS_RENDERER_H
#define VOLVIS_SYS_RENDERER_H

#include <math.h>
#include <stddef.h>

#include "../render.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The version of vv_renderer_ops this header describes. */
#define VV_RENDERER_OPS_VERSION 3

/* ---- regions ---------------------------------------------------------------- */

/**
 * How partial images of regions combine (front over back, in visibility
 * order). Exactness: every sample of a whole render is taken by exactly
 * one region, at the same point, with the same classification and shading,
 * so MAX and MIN give the whole render's image bit for bit and OVER up to
 * the rounding of re-associating the over operator (≥ 50 dB; tests).
 * NEAREST (isosurfaces): a crossing between samples k - 1 and k belongs to
 * the region that owns sample k, which reads sample k - 1 from its ghost
 * voxels, so each region finds the crossings of the whole render; the
 * nearest wins (shading and the refinement's start may differ in the last
 * bits at region faces: ≥ 50 dB; tests). SUM (X-ray): each region sums
 * the values of its samples and counts them; the sums add up, and the mean
 * is classified once at the end (vv_region_image_finish, through the
 * image's classify), so the image is the whole render's up to the
 * rounding of adding the sums in another order. ATTENUATED_MAX (napari's
 * attenuated MIP): the operator is associative. With E the running sum of
 * the per-sample exponents k n (n a sample's value normalised by the
 * contrast limits, k the attenuation per step), the whole render's pixel
 * value is the maximum over samples of (v + qoff) exp(k - E), E including
 * the sample. A region starts its E at 0 and gives its local maximum m and
 * its total E; front F over back B is m = max(m_F, m_B exp(-E_F)), E =
 * E_F + E_B, since exp(k - E_F - E_B) = exp(-E_F) exp(k - E_B). The final m
 * is classified once at the end as SUM's mean is, so the image is the whole
 * render's up to the rounding of the products (>= 50 dB; tests).
 */
typedef enum vv_region_op {
    VV_REGION_OVER = 0,    /**< composite: premultiplied colour and opacity, Porter-Duff over;
                                depth: the front region's unless it saw nothing */
    VV_REGION_MAX = 1,     /**< maximum intensity projection: the pixel of the larger key;
                                equal keys keep the front one */
    VV_REGION_MIN = 2,     /**< minimum intensity projection: the pixel of the smaller key */
    VV_REGION_NEAREST = 3, /**< isosurface: the pixel of the smaller depth (its surface's
                                crossing); equal depths keep the front one; no key (NAN) */
    VV_REGION_SUM = 4,     /**< X-ray: the sums of the sample values add up (a partial pixel
                                holds no colour until vv_region_image_finish; see
                                vv_region_image.key) */
    VV_REGION_ATTENUATED_MAX = 5, /**< attenuated MIP: the maximum of the back's values scaled
                                       by exp(-E) of the front, the exponents E add up (a
                                       partial pixel holds no colour until
                                       vv_region_image_finish; see vv_region_image.key) */
} vv_region_op;

/**
 * The whole volume of a region's object at full resolution, read by boxes,
 * for a region render's global effects: the ray tracer sweeps its light
 * volumes through it, so that out of core its shadows are those of the
 * in-memory render rather than of the World's coarse proxy. A driver that
 * renders from a proxy and can read the whole volume offers it (out of
 * core by bricks, or from a pyramid's level 0); NULL elsewhere (the World
 * holds the whole volume, or nothing beyond the rank's own box can be
 * read: distributed rendering). Borrowed for the region render; used from
 * one thread at a time.
 */
typedef struct vv_region_volume {
    void *user; /**< the reader's state */
    /** Its geometry as a volume whose voxels must not be read: dims, type,
     *  spacing, origin, direction, value range. */
    const vv_volume *header;
    /**
     * Voxels lo .. hi (inclusive, within the volume) as a new volume
     * reference whose voxel (0, 0, 0) is voxel lo, with the header's
     * spacing, origin, direction and value range. Errors: VV_ERR_IO,
     * VV_ERR_FORMAT, VV_ERR_LIMIT, VV_ERR_NOMEM.
     */
    vv_status (*read_box)(void *user, const int lo[3], const int hi[3], vv_volume **out);
    /** Cells a side of the boxes worth reading at a time (the source's bricks or the nodes its
     *  memory limit holds), > 0. */
    int tile;
    /**
     * Optional (NULL): the least and greatest value (data units) of voxels
     * lo .. hi when known without reading them (the bricks' min and max):
     * 1 and *vmin, *vmax set (bounds: the box's voxels lie within them);
     * 0 when unknown. A box the transfer function shows as empty need not
     * be read.
     */
    int (*box_range)(void *user, const int lo[3], const int hi[3], float *vmin, float *vmax);
} vv_region_volume;

/**
 * Rays a frame drawn by regions traces again: the image-plane points of a
 * renderer's supersampling (vv_region_image.supersample), per_pixel of them
 * for each of n_pixels pixels, in the order the renderer averages them.
 */
typedef struct vv_region_rays {
    int per_pixel;   /**< points a pixel, >= 1 */
    size_t n_pixels; /**< pixels listed */
    size_t *pixel;   /**< n_pixels pixel indices y width + x, ascending; malloc'd */
    double *xy;      /**< n_pixels * per_pixel points (x, y), in the units of vv_camera_ray
                          (pixel x's centre at x); malloc'd */
} vv_region_rays;

/**
 * One region of a volume object: the samples inside an axis-aligned box of
 * the object's index space (voxel units of its whole volume; the box is an
 * oriented box of the World when the object is turned). A region render
 * draws only the samples p with lo <= p < hi on each axis (an infinite
 * bound leaves that side open), as the whole render takes them (rays, step
 * and sample points t = k dt of the whole volume), from the voxels given.
 */
typedef struct vv_render_region {
    int object;   /**< index of the volume object in the World */
    int dims[3];  /**< the whole volume's dims */
    double lo[3]; /**< owned samples: lo <= p (index units; -INFINITY: open) */
    double hi[3]; /**< owned samples: p < hi (+INFINITY: open) */
    /**
     * The region's voxels: the box plus at least one voxel beyond each
     * owned face (within the volume), so that trilinear samples and
     * central-difference gradients are the whole volume's (iso mode: two,
     * since a crossing may lie up to a step before the box; with one its
     * gradient there is one-sided); with the whole
     * volume's spacing, origin, direction and value range; its voxel
     * (0, 0, 0) is the whole volume's voxel `offset`. Borrowed.
     */
    const vv_volume *voxels;
    int offset[3];
    int x0, y0, x1, y1; /**< pixels x0 <= x < x1, y0 <= y < y1 that can see the region
                             (vv_region_rect); x1 <= x0: the whole image */
    /** The whole volume, for global effects, when the World's own volume of the object is a
     *  coarse proxy and the driver can read it (vv_region_volume); NULL: none. */
    const vv_region_volume *whole;
    /**
     * NULL: one ray through each pixel centre into the view-sized image.
     * Else these points only: point i of rays->xy into entry i (row-major)
     * of an image of at least per_pixel * n_pixels entries (and its keys),
     * each as a pixel is (colour, depth, key); points whose pixel lies
     * outside the rectangle, and entries past the last point, stay clear.
     * Borrowed.
     */
    const vv_region_rays *rays;
    /**
     * Where the voxels come from, for a renderer that keeps them between
     * frames (the gpu renderer's brick cache on the device), or NULL (an
     * initializer's default): nothing to key on, the voxels are drawn and
     * forgotten. The volume the voxels are a box of, made by vv_volume_new
     * (a bricked file's header, a pyramid level's, or the volume itself in
     * memory): the same object while the source is open, its `modified`
     * bumped when its voxels change. A renderer that keys on it holds a
     * reference (vv_volume_ref), so that the address stays unique; the
     * voxels are then known by (from, from->modified, level, offset, the
     * voxels' dims). Borrowed.
     */
    const vv_volume *from;
    int level; /**< the pyramid level of `from` (0: the finest, or a volume of one level) */
    /**
     * The world length of a sample step in this region's voxels over its
     * length at the finest level the frame's regions come from (a pyramid
     * level L against level 0: level L's smallest voxel size over level
     * 0's, about 2^L), > 0; 0 (an initializer's default): 1. What sums a
     * quantity per sample along the ray weighs each sample by it, so that
     * nodes of different levels in one frame sum it per world length
     * alike (attenuated MIP's exponents, VV_REGION_ATTENUATED_MAX).
     */
    double step_scale;
    /**
     * A multi-channel object (vv_object.n_channels > 1, drawn by its
     * channels under the composite rule): channel_voxels[c] the voxels of
     * the object's channel c over the same box as `voxels` (which is the
     * first drawn channel's), each with that channel's value range; NULL
     * for a channel not drawn here (hidden, or transparent throughout the
     * region: its samples are not taken). NULL (an initializer's default): an object
     * of one channel. The additive and maximum rules combine the channels
     * only after each is composited or projected along the whole ray, so a
     * driver draws such an object a channel at a time, each channel an
     * object of its own. Borrowed.
     */
    const vv_volume *const *channel_voxels;
    /**
     * With channel_voxels: the whole volume of each channel (object channel
     * order, as `whole` is for one channel), for the global effects of a
     * frame drawn at level 0 from coarse proxies (the ray tracer's shadows
     * through every channel); NULL: none. Borrowed.
     */
    const vv_region_volume *channel_whole;
    /**
     * 0 (an initializer's default): the object as it is. c + 1: channel c
     * of a multi-channel object alone, as an object of one channel (its
     * volume `voxels`, its transfer function; composite mode, MIP under the
     * maximum rule, its label colours): one pass of the additive or
     * maximum rule, whose passes a caller combines over its regions (over,
     * or max) and then adds (what the renderers do along a whole ray).
     */
    int pass_channel;
    /**
     * What lies in front of this region along every ray, or NULL (an
     * initializer's default): nothing known. The image the caller has
     * composited so far, front to back (view->width x view->height,
     * premultiplied RGBA; only its opacity is read), when its regions come
     * in front-to-back order under the composite rule (VV_REGION_OVER) and
     * rays is NULL. A renderer with early ray termination may then stop a
     * ray once the opacity in front and its own together reach its
     * threshold, 1 - (1 - front) (1 - own) >= threshold, and leave a pixel
     * already that opaque clear: the samples it does not take are those the
     * whole render would not have taken (Levoy 1990's early ray
     * termination, carried across the bricks of sort-last compositing).
     * Borrowed; not written during the render. A front of another size,
     * or with rays, is refused (VV_ERR_INVALID).
     */
    const vv_image *front;
} vv_render_region;

/** A region render's output: the partial image and how it combines. */
typedef struct vv_region_image {
    /**
     * view->width x view->height; RGBA premultiplied colour and opacity
     * without the background, depth of the first visible sample (OVER) or of
     * the key's sample (MAX, MIN), INFINITY where none; pixels outside the
     * region's rectangle are {0, 0, 0, 0}, INFINITY.
     */
    vv_image *image;
    /**
     * width * height floats (MAX, MIN): the projected sample value of the
     * pixel, in units that order like the data and are the same in every
     * region of one render; NAN where the region took no sample. The colour
     * of the pixel is the classification of this value, so the pixel of the
     * winning key is the whole render's pixel. SUM: the sum s of the
     * pixel's sample values (in such units) as key = (float)s and the
     * remainder s - key in the pixel's red, the number of samples in its
     * green (blue and opacity 0), depth the whole ray's entry in the region
     * holding its first sample (else INFINITY); NAN where none.
     * ATTENUATED_MAX: the region's largest attenuated value m (real data
     * units, value + qoff, not stored units: the scale multiplies the real
     * value) as key, the sum E of its samples' exponents (dimensionless,
     * >= 0) in the pixel's red (green, blue and opacity 0), depth that of
     * the sample of m (the first of equals); NAN where none.
     */
    float *key;
    vv_region_op op; /**< set by the renderer */
    /**
     * 1: the caller keeps the image clear outside the rectangle of the
     * region it asks for (a driver that clears each rectangle after using
     * it), so vv_renderer_render_region clears only the rectangle; 0 (an
     * initializer's default): the whole image is cleared.
     */
    int clear_outside;
    /**
     * SUM and ATTENUATED_MAX: set by the renderer's region render: the
     * colour {opacity, r, g, b} (not premultiplied) that its whole render
     * gives the mean value (SUM) or the attenuated maximum (ATTENUATED_MAX)
     * @p v (key units), for vv_region_image_finish; @p ctx is
     * classify_ctx, owned by the renderer and valid until its next render
     * or its destruction. NULL otherwise (an initializer's default).
     */
    void (*classify)(const void *ctx, float v, float entry[4]);
    const void *classify_ctx;
    /**
     * Set by a region render whose whole render traces more rays than one
     * a pixel at this quality (the ray tracer's supersampling at quality
     * 2), else NULL (an initializer's default): given @p first, the frame's
     * regions combined and finished (one ray a pixel), fills @p rays with
     * the points to trace again (none: the frame is done). The driver then
     * renders every region again on those points (vv_render_region.rays),
     * combines and finishes each point as a pixel, and sets each listed
     * pixel to its points' mean (their colours summed in order, divided by
     * their count) and their nearest depth: the whole render's pixel.
     * @p ctx is supersample_ctx, valid as classify_ctx is. Errors:
     * VV_ERR_NOMEM.
     */
    vv_status (*supersample)(const void *ctx, const vv_image *first, vv_region_rays *rays);
    const void *supersample_ctx;
} vv_region_image;

/** How the region renders of an object in @p mode combine. */
static inline vv_region_op
vv_region_op_for(vv_render_mode mode) {
    return mode == VV_MODE_MIP              ? VV_REGION_MAX
           : mode == VV_MODE_MINIP          ? VV_REGION_MIN
           : mode == VV_MODE_ISO            ? VV_REGION_NEAREST
           : mode == VV_MODE_XRAY           ? VV_REGION_SUM
           : mode == VV_MODE_ATTENUATED_MIP ? VV_REGION_ATTENUATED_MAX
                                            : VV_REGION_OVER;
}

/** Combines one pixel: @p f (front, updated) and @p b (behind), colour, depth and key as
 *  vv_region_image holds them for @p op. */
static inline void
vv_region_pixel_combine(vv_region_op op, float f[4], float *fdepth, float *fkey, const float b[4],
                        float bdepth, float bkey) {
    if (op == VV_REGION_OVER) {
        const float w = 1 - f[3];
        f[0] += w * b[0];
        f[1] += w * b[1];
        f[2] += w * b[2];
        f[3] += w * b[3];
        if (*fdepth == INFINITY)
            *fdepth = bdepth;
        return;
    }
    if (op == VV_REGION_NEAREST) {
        if (bdepth < *fdepth) {
            f[0] = b[0];
            f[1] = b[1];
            f[2] = b[2];
            f[3] = b[3];
            *fdepth = bdepth;
        }
        return;
    }
    if (bkey != bkey) /* behind took no sample */
        return;
    if (op == VV_REGION_ATTENUATED_MAX && *fkey == *fkey) {
        /* the back's values seen through the front's exponents */
        const float m = (float)((double)bkey * exp(-(double)f[0]));
        if (m > *fkey) {
            *fkey = m;
            *fdepth = bdepth;
        }
        f[0] += b[0];
        return;
    }
    if (op == VV_REGION_SUM && *fkey == *fkey) {
        /* the sums, each kept as a float and its remainder */
        const double sum = ((double)*fkey + (double)f[0]) + ((double)bkey + (double)b[0]);
        *fkey = (float)sum;
        f[0] = (float)(sum - (double)*fkey);
        f[1] += b[1];
        if (*fdepth == INFINITY)
            *fdepth = bdepth;
        return;
    }
    if (*fkey != *fkey || (op == VV_REGION_MAX ? bkey > *fkey : bkey < *fkey)) {
        f[0] = b[0];
        f[1] = b[1];
        f[2] = b[2];
        f[3] = b[3];
        *fdepth = bdepth;
        *fkey = bkey;
    }
}

/**
 * Turns a combined partial image into the final one: colour + (1 -
 * opacity) × @p background, opacity clamped to 1 (exactly as the whole
 * render writes a pixel). SUM: each pixel's colour is first its mean
 * (key + red) / green, classified by img->classify (opacity times colour,
 * and the opacity; a pixel without samples or an image without classify
 * is transparent). ATTENUATED_MAX: each pixel's colour is its key
 * classified the same way.
 */
void vv_region_image_finish(vv_region_image *img, vv_vec3 background);

/**
 * The World a region method renders: @p w's settings (view, lights, cut
 * planes, shading) with the region's object alone, its volume replaced by
 * the region's voxels. Points into itself: filled in place by the region
 * helpers of src/render (frame.h) and not copied; nothing in it is
 * released; it lives as long as @p w and the region.
 */
typedef struct vv_region_world {
    vv_object part;     /**< the object, its volume the region's voxels */
    vv_object *slot[1]; /**< world's object array: &part */
    vv_world world;     /**< the World to render */
    /** a multi-channel part's channels (their volumes the region's channel voxels), or
     *  NULL; owned: vv_region_world_release frees them */
    vv_channel *chan;
} vv_region_world;

/** Clears @p img to "nothing seen": colour 0, depth INFINITY, key NAN. */
void vv_region_image_clear(vv_region_image *img);

/**
 * The pixel rectangle of @p view that can see the index box lo .. hi of a
 * volume placed by @p index_to_world, two pixels wider on each side; the
 * whole image (x1 <= x0) when the box reaches behind the eye; an empty
 * rectangle (x1 > x0, y1 <= y0) when it is off screen. Fills rg->x0 .. y1.
 */
void vv_region_rect(vv_render_region *rg, vv_mat4 index_to_world, const vv_view *view,
                    const int lo[3], const int hi[3]);

/* ---- option rows: where a method keeps each option ----------------------------- */

/**
 * How a bound option's value is stored in its field of the method's state
 * (vv_option_binding.store). A number is the parsed value (BOOL: 0 or 1)
 * times the binding's scale, or the value of the word given
 * (vv_option_binding.word_values).
 */
typedef enum vv_option_store {
    VV_OPTION_STORE_NONE = 0,   /**< nothing: the row's hook applies the value */
    VV_OPTION_STORE_DOUBLE = 1, /**< double: BOOL, INT, REAL */
    VV_OPTION_STORE_FLOAT = 2,  /**< float: BOOL, INT, REAL, rounded to float */
    VV_OPTION_STORE_INT = 3,    /**< int: BOOL 0 or 1, INT, ENUM (the word's index, or its
                                     value where word_values are given); never scaled */
    VV_OPTION_STORE_UINT64 = 4, /**< uint64_t: INT, REAL >= 0, times scale, truncated */
    VV_OPTION_STORE_CHARS = 5,  /**< char[size]: STRING's text, NUL-padded (size >=
                                     VV_RENDER_OPTION_VALUE_MAX holds any value) */
} vv_option_store;

/**
 * An option's side effect, called after its value is stored (also when a
 * new renderer takes the default): drop a cache the value invalidates,
 * read the file it names, reset an option it overrides. @p v is the
 * validated value (v->word >= 0: one of the row's words). An error undoes
 * the store (the field gets its previous bytes back) and is what
 * vv_renderer_set_option returns; the hook itself leaves things as they
 * were where it can.
 */
typedef vv_status (*vv_option_hook)(void *state, const vv_option_spec *spec,
                                    const vv_option_value *v);

/**
 * An option row's binding (vv_option_spec.bind): the field of the method's
 * state that holds its value, how it is stored and its side effect. The
 * registry's one setter parses the text (vv_option_parse), stores it here
 * and calls the hook, for the defaults of a new renderer and for every
 * vv_renderer_set_option alike. A word (v->word >= 0) stores
 * word_values[v->word] as if that number had been given (sentinels such
 * as -1 for "auto"); without word_values an INT store takes the word's
 * index (ENUM), and any other store keeps its value and leaves the word
 * to the hook (e.g. gradient_budget_mb=auto). tests/render/test_registry.c
 * checks every binding against its row and the state's size.
 */
struct vv_option_binding {
    vv_option_store store;
    size_t offset;             /**< offsetof(state type, field) */
    size_t size;               /**< sizeof the field */
    double scale;              /**< numbers (not INT stores) are stored times this (1: as given) */
    const double *word_values; /**< one per entry of the row's words, or NULL (above) */
    vv_option_hook hook;       /**< or NULL */
};

/** The binding of the field @p field of state type @p type (as
 * offsetof takes it: `refine.mode` reaches into a member), stored as
 * VV_OPTION_STORE_##kind (DOUBLE, FLOAT, INT, UINT64, CHARS), with
 * @p scale, @p word_values (VV_OPTION_WORD_VALUES, or NULL) and @p hook
 * (or NULL). The shorter forms below fill the rest. */
#define VV_OPTION_BIND_FULL(type, field, kind, scale_, word_values_, hook_)                        \
    (&(const vv_option_binding){.store = VV_OPTION_STORE_##kind,                                   \
                                .offset = offsetof(type, field),                                   \
                                .size = sizeof(((type *)0)->field),                                \
                                .scale = (scale_),                                                 \
                                .word_values = (word_values_),                                     \
                                .hook = (hook_)})
/** A plain binding: the value as given, no side effect. */
#define VV_OPTION_BIND(type, field, kind) VV_OPTION_BIND_FULL(type, field, kind, 1, NULL, NULL)
/** A binding with a side effect. */
#define VV_OPTION_BIND_HOOK(type, field, kind, hook_)                                              \
    VV_OPTION_BIND_FULL(type, field, kind, 1, NULL, hook_)
/** A binding whose words stand for numbers (VV_OPTION_WORD_VALUES(...)), and a hook or NULL. */
#define VV_OPTION_BIND_WORDS(type, field, kind, word_values_, hook_)                               \
    VV_OPTION_BIND_FULL(type, field, kind, 1, word_values_, hook_)
/** Nothing stored: @p hook_ applies the value. */
#define VV_OPTION_BIND_NONE(hook_)                                                                 \
    (&(const vv_option_binding){.store = VV_OPTION_STORE_NONE, .scale = 1, .hook = (hook_)})
/** The numbers the words of a row stand for, in the order of its words. */
#define VV_OPTION_WORD_VALUES(...) ((const double[]){__VA_ARGS__})

/* ---- the table a method fills in ---------------------------------------------- */

/**
 * One rendering method. Methods may be NULL where marked optional; callers
 * go through render.h, which checks the version, validates options against
 * info.options and checks the World against info.draws and info.modes
 * before a method sees them.
 *
 * A new renderer: the registry allocates state_size bytes, zeroed; calls
 * init; then sets every option of info.options, in table order, to its
 * default (the row's text, through the same setter as
 * vv_renderer_set_option: stored in the bound field, then the row's hook).
 * Freeing it: release, then the registry frees the state.
 */
typedef struct vv_renderer_ops {
    int version;           /**< VV_RENDERER_OPS_VERSION */
    vv_renderer_info info; /**< name, capabilities, option table (every row bound) */
    size_t state_size;     /**< sizeof the method's state */
    /**
     * Optional: sets up what is not an option (caches, structs), before the
     * options' defaults are set. Errors: VV_ERR_NOMEM (release is called
     * all the same).
     */
    vv_status (*init)(void *state);
    /** Optional: releases what the state holds (never the state itself); also after a
     * failed init, so it takes zeroed members. */
    void (*release)(void *state);
    /** Renders the whole image (render.h: vv_renderer_render). */
    vv_status (*render)(void *state, const vv_world *world, const vv_view *view,
                        const vv_render_options *opt, vv_image *out);
    /**
     * Optional (VV_RENDERER_REGION): renders only @p region of the World's
     * object region->object into @p out (vv_region_image), on one ray
     * through each pixel centre, or on the points of region->rays (then it
     * must not set out->supersample). The World has that one visible object
     * (checked by the frame runner before the call); its own volume spans the same world box
     * and holds real voxels: the whole volume (distributed rendering of an
     * in-memory volume) or a coarse proxy (out of core): a method with
     * global effects traces them through it, so they are exact only with
     * the whole volume, or where it reads region->whole (the ray tracer's
     * light volumes of directional lights). Errors: VV_ERR_UNSUPPORTED (a mode or option it
     * cannot split), VV_ERR_NOMEM, VV_ERR_CANCELLED.
     */
    vv_status (*render_region)(void *state, const vv_world *world, const vv_view *view,
                               const vv_render_region *region, const vv_render_options *opt,
                               vv_region_image *out);
    /**
     * Optional: a frame this method draws as another method would, from a
     * World of its own making (the Fourier method's modes other than X-ray:
     * the ray caster on the decoded volumes). vv_renderer_render calls it
     * before render; it sets *stand_in to the name of a method of the
     * registry and *draw to the World that method draws (owned by the
     * state, valid until the next call or release), and the registry draws
     * the frame with that method (one instance kept with @p state's
     * renderer, with no option set); or it leaves *stand_in NULL, and
     * render draws the frame. So a method never reaches into the registry
     * itself. Errors: those of preparing *draw (VV_ERR_NOMEM, ...).
     */
    vv_status (*stand_in)(void *state, const vv_world *world, const vv_render_options *opt,
                          const char **stand_in, const vv_world **draw);
} vv_renderer_ops;

/** The registry: a NULL-terminated array of every method (built in, then
 *  registered), in registry order. */
const vv_renderer_ops *const *vv_renderer_registry(void);

/** The most methods vv_renderer_register adds to a process's registry. */
#define VV_RENDERERS_REGISTERED_MAX 16

/**
 * Adds the method @p ops to the registry, after those built in: from then
 * on vv_renderer_new, vv_world_renderer, `volvis renderers`, the CLI's
 * --renderer, the GUI's list and Python find it by its name as they find
 * any method. A new method is its table in one file and this call.
 * @p ops is borrowed for the life of the process (a static table).
 * Thread-safe; methods are never removed.
 *
 * Errors: VV_ERR_INVALID (no name, a name taken, no render call, an option
 * row not bound inside state_size bytes), VV_ERR_UNSUPPORTED (another
 * VV_RENDERER_OPS_VERSION), VV_ERR_LIMIT (over
 * VV_RENDERERS_REGISTERED_MAX methods).
 */
vv_status vv_renderer_register(const vv_renderer_ops *ops);

/** The table behind @p r; owned by the library. */
const vv_renderer_ops *vv_renderer_ops_of(const vv_renderer *r);

/**
 * Renders a region with renderer @p r (which must declare
 * VV_RENDERER_REGION): checks the arguments and clears @p out, then calls
 * its render_region. Errors: VV_ERR_UNSUPPORTED (no region method),
 * VV_ERR_INVALID (sizes, object), those of the method.
 */
vv_status vv_renderer_render_region(vv_renderer *r, const vv_world *world, const vv_view *view,
                                    const vv_render_region *region, const vv_render_options *opt,
                                    vv_region_image *out);

/* ---- the frame runner (src/render/frame.c) ------------------------------------ */

#define VV_FRAME_TILE 16 /**< default tile side, pixels */

/** The piece of work a tile callback gets. */
typedef struct vv_frame_tile {
    int x0, y0, x1, y1; /**< pixels x0 <= x < x1, y0 <= y < y1 (never empty) */
    int index;          /**< tile number, row-major over the whole image */
    int thread;         /**< 0 .. threads - 1 */
    void *scratch;      /**< this thread's scratch (vv_frame_job.scratch_bytes, 64-byte
                             aligned, zeroed once per run), or NULL */
    const void *run;    /**< the run (vv_frame_cancelled) */
} vv_frame_tile;

/**
 * 1 once the run of tile @p t is cancelled or another tile failed: a long
 * tile may stop early (its pixels are discarded with the frame).
 */
int vv_frame_cancelled(const vv_frame_tile *t);

/**
 * The work of a tile: fill the pixels of @p t (only those). Runs on worker
 * threads, several tiles at once; a tile's pixels depend on the tile
 * alone, so the image is the same for any thread count. Return VV_OK, or
 * an error (with vv_error_set on the worker's thread: its message is
 * carried back) to stop the run.
 */
typedef vv_status (*vv_frame_tile_fn)(void *user, const vv_frame_tile *t);

/** One pass over the image's tiles. */
typedef struct vv_frame_job {
    int width, height;    /**< image size */
    int tile;             /**< tile width (side), pixels; <= 0: VV_FRAME_TILE */
    int tile_h;           /**< tile height; <= 0: square tiles (bands of rows: tile = width) */
    int x0, y0, x1, y1;   /**< only these pixels (tiles clipped to them); x1 <= x0: all */
    size_t scratch_bytes; /**< per-thread scratch, 0: none */
    vv_frame_tile_fn fn;  /**< the tile's work */
    void *user;           /**< its payload */
    double progress_from; /**< the run reports progress from here ... */
    double progress_to;   /**< ... to here (0 and 0: 0 to 1) */
    /** NULL, or the image whose pixels a tile leaves final when it returns
     *  (the frame's last pass over the caller's image, whole renders
     *  only): with vv_render_options.pixels8 the runner converts each
     *  finished tile to 8 bits on its thread (vv_image_rect_to_rgbx8, or
     *  vv_image_rect_to_yuv420 when tiles have even sides) and,
     *  once every tile of the whole image is done, sets
     *  pixels8->converted_in_tiles. */
    const vv_image *image;
} vv_frame_job;

/** A whole image, 16-pixel tiles, progress 0 to 1. */
void vv_frame_job_init(vv_frame_job *job, int width, int height, vv_frame_tile_fn fn, void *user);

/**
 * Runs @p job: tiles row-major, taken dynamically by opt->threads OpenMP
 * threads (<= 0: vv_threads_get()); after each tile the fraction of tiles
 * done is reported through opt->progress (tiles outside the job's
 * rectangle count as done), and a non-zero answer cancels: tiles not begun
 * are skipped. Errors: VV_ERR_CANCELLED, VV_ERR_NOMEM (scratch), the first
 * error a tile returned (its message).
 */
vv_status vv_frame_run(const vv_frame_job *job, const vv_render_options *opt);

/* ---- adaptive image-space refinement (src/render/frame.c) ------------------------- */

/**
 * One pixel of a refined tile: @p px gets the colour and opacity of pixel
 * centre (x, y) over the background (px[0..3], the image's layout) and its
 * depth (px[4]); @p work is the tile's own accumulator, passed through
 * (the frame runner's refinement, src/render/frame.c). Called on the tile's thread; a pure function
 * of (x, y) for the frame, so that the image is the same for any thread count.
 */
typedef void (*vv_frame_pixel_fn)(void *user, int x, int y, float px[5], void *work);

/** The lattice of the refinement: every 4th pixel in x and y. */
#define VV_FRAME_REFINE_LATTICE 4

/** The words of the refinement options (VV_FRAME_REFINE_OPTIONS):
 * {"auto", "on", "off"} (the option's values 0, 1, 2) and {"auto"}. */
extern const char *const vv_frame_refine_modes[];
extern const char *const vv_frame_refine_auto[];

/**
 * A renderer's refinement settings, the values of its
 * VV_FRAME_REFINE_OPTIONS: mode 0 auto (at quality 0 and 1, and where the
 * renderer says), 1 on, 2 off;
 * tolerance < 0 by quality (1/16, 1/64, 1/1024 at quality 0, 1, 2). A member of the
 * renderer's state that the two option rows bind to, read when a frame
 * starts.
 */
typedef struct vv_frame_refine_settings {
    int mode;
    double tolerance;
} vv_frame_refine_settings;

/**
 * The two option rows of a renderer that refines (its option table's
 * rows), bound to the vv_frame_refine_settings member @p field of its
 * state type @p type: `refinement` (enum auto/on/off: mode 0 auto, when
 * the string literal @p when says, at least at quality 0 and 1; 1 on; 2
 * off) and `refinement_tolerance` (real in [0, 1], or auto: tolerance -1,
 * the tolerance of the quality).
 */
/* clang-format off */
#define VV_FRAME_REFINE_OPTIONS(type, field, when)                                                 \
    {"refinement", VV_OPTION_ENUM, "auto", 0, 0, 0, vv_frame_refine_modes,                         \
     "adaptive image-space refinement from a lattice of every 4th pixel (auto: " when ")",        \
     VV_OPTION_BIND(type, field.mode, INT)},                                                      \
    {"refinement_tolerance", VV_OPTION_REAL, "auto", 0, 1, 0, vv_frame_refine_auto,                \
     "colour or opacity error of a lattice cell's interpolation that casts its inner rays "       \
     "(auto: 1/16, 1/64, 1/1024 at quality 0, 1, 2)",                                              \
     VV_OPTION_BIND_WORDS(type, field.tolerance, DOUBLE, VV_OPTION_WORD_VALUES(-1), NULL)}
/* clang-format on */

/* ---- camera rays ------------------------------------------------------------------ */

/**
 * The primary rays of a view in affine form: vv_view_ray's origin and
 * (before normalisation) direction are affine in the pixel position, so
 * ray (px, py) = origin o00 + px ox + py oy, direction d00 + px dx + py dy,
 * normalised. Perspective directions are scaled to unit depth along the
 * view axis first. Every ray-casting renderer starts from this form (a
 * packet kernel evaluates it for 8 pixels at once); its rays agree with
 * vv_view_ray to rounding.
 */
typedef struct vv_camera_rays {
    vv_vec3 o00, ox, oy; /**< origin at pixel (0, 0) and its change per pixel in x, y */
    vv_vec3 d00, dx, dy; /**< unnormalised direction likewise */
    vv_vec3 forward;     /**< unit view direction */
    int ortho;           /**< orthographic (parallel rays) */
} vv_camera_rays;

/** The affine form of @p view's rays (three vv_view_ray calls). */
void vv_camera_rays_init(vv_camera_rays *c, const vv_view *view);

/** The unit ray through image position (px, py) (integers: pixel centres). */
static inline vv_ray
vv_camera_ray(const vv_camera_rays *c, double px, double py) {
    vv_ray r;
    r.origin.x = c->o00.x + px * c->ox.x + py * c->oy.x;
    r.origin.y = c->o00.y + px * c->ox.y + py * c->oy.y;
    r.origin.z = c->o00.z + px * c->ox.z + py * c->oy.z;
    const double dx = c->d00.x + px * c->dx.x + py * c->dy.x;
    const double dy = c->d00.y + px * c->dx.y + py * c->dy.y;
    const double dz = c->d00.z + px * c->dx.z + py * c->dy.z;
    const double inv = 1.0 / sqrt(dx * dx + dy * dy + dz * dz);
    r.dir.x = dx * inv;
    r.dir.y = dy * inv;
    r.dir.z = dz * inv;
    return r;
}

#ifdef __cplusplus
}
#endif
#endif
