/*
 * VolVis scene files: a World as JSON (schema in docs/scene-format.md), read
 * and written with Jansson.
 *
 * The scene layer sits above io, Modeling and Filtering (DESIGN.md's map:
 * apps -> scene -> manipulate, parallel -> render, modeling, filter, io, ...
 * -> model -> core): loading a scene loads the volume, grid, mesh and
 * texture files it names (io), volume-samples its "geometry" objects
 * (Modeling) and applies its "filters" chains (Filtering); saving writes the
 * World back so that loading the file reproduces it.
 *
 * Units: world units for positions and distances; angles in degrees in the
 * file, radians in the World.
 *
 * Thread-safety: loading and saving are reentrant (no shared state besides
 * an optional filter cache, which is thread-safe); a World must not change
 * while it is being saved.
 */
#ifndef VOLVIS_SCENE_H
#define VOLVIS_SCENE_H

#include "core.h"
#include "filter.h"
#include "io.h"
#include "model.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

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
 * vv_scene_load_progress keeping the volumes of objects with a "filters"
 * chain in @p cache (include/volvis/filter.h; may be NULL: filtered again at
 * every load), so loading the scene again does not filter again. Those
 * volumes are shared with the cache: the World treats them as read-only
 * (objects copy a volume before editing it).
 */
vv_status vv_scene_load_cached(vv_world **out, const char *path, const vv_progress *progress,
                               vv_filter_cache *cache);

/**
 * vv_scene_load_cached opening each volume file of a volume object without
 * "filters" as @p open says (vv_open, io.h; NULL: read whole, into memory):
 * out of core (a bricked file, a pyramid) with VV_OPEN_OUT_OF_CORE or
 * VV_OPEN_AUTO, every file's pieces in open->cache under one budget (the
 * CLI's --memory-limit, the GUI's). The object then shows the file's source
 * (vv_object_new_source; its level open->load.level frames it), and its
 * file places it: a scene's "origin" and "spacing" for such a file must be
 * the file's own (as vv_scene_save writes them), else VV_ERR_FORMAT ("object
 * 'NAME': out of core its file's own origin and spacing place it"); its
 * "time" a pyramid's time step (a bricked file has step 0 only: another
 * step is read whole). open->load's format, channel and time are the
 * scene's; its level and raw parameters are not used but for the level
 * that frames. Errors as vv_scene_load, and vv_open's.
 */
vv_status vv_scene_load_open(vv_world **out, const char *path, const vv_progress *progress,
                             vv_filter_cache *cache, const vv_open_options *open);

/**
 * Writes a World as a scene file, atomically. An object showing a file out
 * of core (its source) is written with the file's own origin and spacing
 * (level 0's), so that loading the scene out of core again accepts them.
 * Volumes are referred to by
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

/* ---- the door: what a user names, opened into a World ready to draw ---- */

/** The version of vv_world_open_options this header describes. */
#define VV_WORLD_OPEN_VERSION 1

/** Where the volume of a file lives once opened (vv_world_open_options.memory). */
typedef enum vv_world_memory {
    /**
     * Read whole into memory, unless rendering it in memory would take more
     * than the memory budget (vv_memory_budget_get; its voxels, the
     * renderers' copy and, shaded, the cached gradients): then, for a file
     * that can be read out of core, drawn by a renderer with the region
     * contract, of one channel and no time step asked for, out of core in a
     * cache of a quarter of the budget (and of the memory available, at
     * most 1 GiB), said in vv_world_open_info.switched. The format's way for
     * a file made for out of core (a .vvb).
     */
    VV_WORLD_MEMORY_AUTO = 0,
    /** Out of core (bricks, or a pyramid's chunks); a file that cannot be read so is
     *  VV_ERR_UNSUPPORTED, nothing read. */
    VV_WORLD_OUT_OF_CORE = 1,
    /** Out of core where the file can be read so, whole otherwise (a browser's session). */
    VV_WORLD_OUT_OF_CORE_IF_ABLE = 2,
    /**
     * Out of core when the file's level 0 holds more than a quarter of the
     * process cache's budget (vv_open's VV_OPEN_AUTO), a pyramid by its
     * levels, whole otherwise; a scene's files each so (a desktop session,
     * whose budget the user sets).
     */
    VV_WORLD_OUT_OF_CORE_IF_LARGE = 3,
    /** Read whole into memory whatever its size (a .vvb too; a scene's files too): for
     *  front ends that want every voxel at hand (`volvis slice`). */
    VV_WORLD_IN_MEMORY = 4,
} vv_world_memory;

/** What the user named, as vv_world_open found it (vv_world_open_info.input). */
typedef enum vv_world_input {
    VV_INPUT_VOLUME = 0, /**< a volume file, folder (DICOM series, TIFF stack) or store */
    VV_INPUT_GRID = 1,   /**< an irregular grid file */
    VV_INPUT_SCENE = 2,  /**< a scene file (docs/scene-format.md) */
    VV_INPUT_MESH = 3,   /**< a triangle mesh: no World (VV_ERR_UNSUPPORTED; vv_mesh_load) */
} vv_world_input;

/**
 * How vv_world_open opens an input and what it overrides in the World it
 * builds. Initialise with vv_world_open_options_init, then set fields; the
 * version field guards a caller built against another layout.
 */
typedef struct vv_world_open_options {
    int version; /**< VV_WORLD_OPEN_VERSION (set by vv_world_open_options_init) */
    /** A volume file's format (VV_FORMAT_AUTO: detected once) and raw description, DICOM
     *  series, channel (-1: 0) and time step (-1: 0); also a grid's step (time >= 0). */
    vv_load_options load;
    int level; /**< a multiresolution file's level (0 the finest; -1: none given): in
                    memory that level read whole, out of core every node at it */
    vv_world_memory memory;
    uint64_t memory_limit; /**< the process cache's budget in bytes (0: its default, 1 GiB) */
    int levels;            /**< 1: a pyramid by its levels (level of detail, progressive frames);
                                with VV_WORLD_OUT_OF_CORE a file without levels is VV_ERR_INVALID */
    int distributed;       /**< 1: every MPI rank opens the same input and reads its own box (a
                                file by bricks without the pass over its values) */
    const char *renderer;  /**< the method that will draw it (the switch of
                                VV_WORLD_MEMORY_AUTO needs its region contract); NULL: raycast */
    /* a volume file's channels as one object (vv_object_set_channels) */
    int n_channels;                /**< > 0: these channels of the file */
    int channels[VV_MAX_CHANNELS]; /**< their indices in the file */
    /** 1: every channel of the file, in order: with colours, contrast or a blend rule
     *  given always (more of them than channels is a misfit), else when the file has
     *  more than one and is read whole */
    int all_channels;
    int n_colors;                        /**< colours given for the first n_colors channels */
    vv_vec3 colors[VV_MAX_CHANNELS];     /**< RGB in [0, 1] (else the file's, else defaults) */
    int n_contrast;                      /**< contrast limits given for the first n_contrast */
    double contrast[VV_MAX_CHANNELS][2]; /**< lower and upper limits in data values */
    int has_blend;                       /**< 1: blend given (else composite) */
    vv_channel_blend blend;
    int label_channel[VV_MAX_CHANNELS]; /**< 1 where channels[i] holds labels */
    /* the appearance, overriding the defaults guessed from the data (or a scene's) */
    int has_mode;
    vv_default_scene_options view; /**< mode (has_mode), transfer function range (stretched
                                        onto a scene's), isovalue, size (has_size) */
    int has_size;
    const char *field;   /**< a grid's field (NULL: its first scalar field) */
    double step;         /**< > 0: every object's sample step (units of the smallest spacing) */
    int has_attenuation; /**< 1: every volume and grid object's attenuation is `attenuation` */
    double attenuation;  /**< >= 0: VV_MODE_ATTENUATED_MIP's attenuation (vv_object) */
    int labels;          /**< 1: every volume object a label volume (VV_SEG_LABELS) */
    int slice_window;    /**< 1: guess the slice views' window and level (info->window) */
    /* long work */
    const vv_progress *progress;   /**< voxelizing a scene's geometry; may be NULL */
    vv_filter_cache *filter_cache; /**< a scene's filtered volumes (NULL: none kept) */
} vv_world_open_options;

/** Defaults: detected format, channel and step 0, no level, VV_WORLD_MEMORY_AUTO, the
 *  default cache, raycast, one channel, the defaults guessed from the data. */
void vv_world_open_options_init(vv_world_open_options *o);

/** What vv_world_open found and decided (filled on success). */
typedef struct vv_world_open_info {
    vv_world_input input;
    int n_channels;  /**< channels of the volume file (1 for a scene or a grid) */
    int n_times;     /**< time steps of the volume file (1 for a scene or a grid) */
    int out_of_core; /**< 1: a visible volume object shows a file out of core */
    /** 1: VV_WORLD_MEMORY_AUTO read it out of core because rendering it in memory would take
     *  need_bytes, more than budget_bytes; the cache was set to cache_bytes */
    int switched;
    uint64_t need_bytes, budget_bytes, cache_bytes;
    /** The slice views' automatic window and level (vv_slice_auto_window: the foreground's
     *  1st to 99.5th percentile) of the first volume object, in data values, with
     *  vv_world_open_options.slice_window; else, or without a volume, 1 and 0.5. */
    double window, level;
    /** 1 on failure when the options do not fit the input (a usage error: channels for a
     *  scene, more colours than the file has channels, levels of a file without them) */
    int options_misfit;
    /** Metadata of the file that was ignored, one line for the user ("" none): an omero
     *  window that is NaN, inverted or absurd (vv_load_info.warning) */
    char warning[512];
} vv_world_open_info;

/**
 * The one door from what a user names to a World ready to draw: a volume
 * file, a folder (a DICOM series, a TIFF stack, an OME-Zarr store), a scene
 * file (a ".json" name or a JSON object inside), a BigDataViewer XML, or an
 * irregular grid. The input is opened once through the format table
 * (vv_open: third-party parsers in the reader sandbox); a volume becomes
 * the default World of vv_world_new_for_source (in memory, or out of core
 * as @p opt->memory decides, under the process cache), its channels one
 * object of several (vv_object_set_channels) when asked; a grid the World
 * of vv_world_new_for_grid; a scene vv_scene_load_open's World. The
 * appearance is guessed from the data once (transfer function, channel
 * contrast and colours, the slice views' window and level), then @p opt's
 * overrides apply. The view is fitted but not turned.
 *
 * @p opt may be NULL (the defaults); @p info may be NULL. On failure *out
 * is NULL and the error is one line naming @p what and the reason.
 * Errors: VV_ERR_IO (missing, unreadable), VV_ERR_FORMAT (cannot tell the
 * format, a malformed file), VV_ERR_UNSUPPORTED (VV_WORLD_OUT_OF_CORE of a
 * file that cannot be read so), VV_ERR_INVALID (options that do not fit
 * the input: info->options_misfit; a channel, time step or level past the
 * file's), VV_ERR_LIMIT, VV_ERR_NOMEM, VV_ERR_CANCELLED, and the readers'.
 * Sets the process cache's limit (memory_limit). Thread-safe but for that
 * limit, which is the process's.
 */
vv_status vv_world_open(vv_world **out, const char *what, const vv_world_open_options *opt,
                        vv_world_open_info *info);

/**
 * A volume object's time steps: the steps of the file it shows
 * (vv_world_open_info.n_times), one vv_time_series (io.h) for each of its
 * channels, read step by step with the next one read ahead.
 * Not thread-safe: one user at a time.
 */
typedef struct vv_time_steps vv_time_steps;

/**
 * Opens the time steps of file @p what for object @p o (borrowed): its
 * channels' file indices (vv_object.channels[c].index), else @p load's
 * channel; @p load's DICOM series and raw description (@p load may be
 * NULL). An object out of core (a pyramid's source) has each step opened
 * out of core in the process cache, every channel at once, the next step's
 * chunks read ahead in the background (vv_source_read_ahead: those the
 * step before read, the view being the same); others read each step whole.
 * Errors: those of vv_time_series_open, or of opening the file out of
 * core; *out is NULL then.
 */
vv_status vv_time_steps_open(vv_time_steps **out, const char *what, const vv_load_options *load,
                             const vv_object *o);
/** The file's time steps (>= 1); 0 for NULL. */
int vv_time_steps_count(const vv_time_steps *t);
/**
 * Puts step @p step into @p o (vv_object_replace_volumes; o->time = step)
 * and reads step @p next (>= 0; -1: none) ahead in the background. Errors:
 * those of reading the step (VV_ERR_INVALID past the file's steps).
 */
vv_status vv_time_steps_show(vv_time_steps *t, vv_object *o, int step, int next);
/** Frees @p t (NULL accepted). */
void vv_time_steps_free(vv_time_steps *t);

#ifdef __cplusplus
}
#endif
#endif
