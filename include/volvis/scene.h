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

#ifdef __cplusplus
}
#endif
#endif
