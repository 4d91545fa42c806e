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

/** What a scene's volume loader gives for a file (vv_scene_load_with). */
typedef struct vv_scene_volume {
    /** a new reference, owned by the scene then: the file's voxels, or a
     * volume that stands for them over the same world box (a pyramid's proxy) */
    vv_volume *volume;
    /** its voxel size over the file's, per axis (1: the file's own voxels):
     * a "spacing" the scene gives is multiplied by it */
    double scale[3];
} vv_scene_volume;

/**
 * Loads the volume file @p path (time step @p time, -1 or 0: the first) of
 * a scene into *@p out; VV_ERR_UNSUPPORTED (nothing set): the scene reads
 * it with vv_volume_load instead. Other errors fail the load, prefixed
 * with the position of the object's "file" key.
 */
typedef vv_status (*vv_scene_volume_loader)(void *user, const char *path, int time,
                                            vv_scene_volume *out);

/**
 * vv_scene_load_cached with @p loader (may be NULL) asked first for the
 * volume file of each volume object without "filters" -- so that a program
 * can stand a proxy in for a file larger than memory, as the GUI does for
 * pyramids (docs/gui.md). The scene's "origin" applies to what it gives,
 * its "spacing" times the loader's scale. Called on the loading thread, in
 * the scene's order. Errors as vv_scene_load, and the loader's.
 */
vv_status vv_scene_load_with(vv_world **out, const char *path, const vv_progress *progress,
                             vv_filter_cache *cache, vv_scene_volume_loader loader, void *user);

/**
 * How many times vv_scene_load_with of scene @p path would call its loader:
 * its volume objects read from a file without "filters" (so that a program
 * can share a memory budget among them before loading). 0 for a file that
 * cannot be read or parsed (vv_scene_load_with then says why). Thread-safe.
 */
int vv_scene_loader_files(const char *path);

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
