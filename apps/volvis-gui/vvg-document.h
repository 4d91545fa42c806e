/*
 * VvgDocument: the World a VolVis window edits, with its undo stack, the file
 * each volume came from, the selection and the session's file name.
 *
 * Every edit of the World goes through vvg_document_begin_edit (an undo step)
 * and vvg_document_changed (the "changed" signal, so views re-render). The
 * World is read by the UI thread; renderers read snapshots of it
 * (vvg_document_snapshot), never the World itself. UI thread only.
 */
#ifndef VVG_DOCUMENT_H
#define VVG_DOCUMENT_H

#include <gtk/gtk.h>
#include <volvis/volvis.h>

G_BEGIN_DECLS

#define VVG_TYPE_DOCUMENT (vvg_document_get_type())
G_DECLARE_FINAL_TYPE(VvgDocument, vvg_document, VVG, DOCUMENT, GObject)

/** The error domain of the GUI: messages are the library's error trace. */
#define VVG_ERROR (vvg_error_quark())
GQuark vvg_error_quark(void);

/** An empty World (vv_world_new). */
VvgDocument *vvg_document_new(void);
/** The World being edited (owned by the document; valid until the next undo, redo or open). */
vv_world *vvg_document_world(VvgDocument *doc);
/** A snapshot of the World for a renderer (caller frees with vv_world_free), or NULL. */
vv_world *vvg_document_snapshot(VvgDocument *doc);

/** Records an undo step called @p label before the World is changed, and marks it unsaved. */
void vvg_document_begin_edit(VvgDocument *doc, const char *label);
/**
 * As vvg_document_begin_edit, but edits of the same @p label less than a
 * second apart (a slider dragged, time played) make one undo step; any other
 * edit, undo or redo ends the run.
 */
void vvg_document_begin_edit_merging(VvgDocument *doc, const char *label);
/** Emits "changed": the World was changed (live, during a drag too). */
void vvg_document_changed(VvgDocument *doc);
gboolean vvg_document_undo(VvgDocument *doc);
gboolean vvg_document_redo(VvgDocument *doc);
gboolean vvg_document_can_undo(VvgDocument *doc);
gboolean vvg_document_can_redo(VvgDocument *doc);

/**
 * Opens a volume (any format vv_open reads), a mesh (any format Assimp
 * reads: .obj .ply .stl .off ...) or a scene file (.json). Volumes, and the
 * volumes of a scene, open with VV_OPEN_AUTO: out of core (by bricks, or a
 * pyramid by its levels) when level 0 holds more than a quarter of the
 * process's cache budget (vvg_document_memory_limit), a .vvb always; the
 * object then owns the file's source (vv_object_attach_source) and shows
 * its proxy, and every file shares the one cache. The
 * volume into an empty World gets the default scene of `volvis render FILE`;
 * later objects are added beside it and the view frames them all; a mesh
 * whose format is usually Y-up (vvg_document_mesh_is_y_up) is turned so that
 * its Y is the World's up (Z); a renderer that would not draw a mesh (the
 * ray caster) is replaced by one that does (raytrace beside volumes, else
 * surface); a scene replaces the World (keeping the view's size: the view
 * fills the window). A file opened into a fresh session leaves it saved.
 * One undo step.
 * On failure the World is unchanged and @p error holds the library's message
 * naming the file.
 */
gboolean vvg_document_open(VvgDocument *doc, const char *path, GError **error);

/**
 * vvg_document_open of what the door opens (a volume file, a folder, a
 * store, a URL, a scene; not a mesh named by its suffix) in two halves, so
 * that the slow half can run on a worker thread while the main loop goes on
 * (File > Open URL…: the network): vvg_document_open_job_new (UI thread)
 * takes @p path (copied) and the document's open options and a reference to
 * the document; vvg_open_job_run (any one thread, once, nothing else
 * touching the job meanwhile) calls the door (vv_world_open, thread-safe but
 * for the process cache's limit, which is set to the same value by every
 * open) and keeps the World it built or the library's one-line error (the
 * error trace is per thread: the message is copied into the job);
 * vvg_document_open_finish (UI thread) installs the result exactly as
 * vvg_document_open does (same World, selection, undo step and saved
 * state) or fills @p error with the kept message. A job finished or not is
 * freed with vvg_open_job_free (UI thread; NULL: nothing), which drops a
 * World never installed: a cancelled open leaves the document as it was.
 * The door cannot be interrupted: a job runs until vv_world_open returns
 * (for a URL, at the latest the transport's timeouts, docs/formats.md).
 */
typedef struct vvg_open_job vvg_open_job;
vvg_open_job *vvg_document_open_job_new(VvgDocument *doc, const char *path);
/** The path or URL the job opens (owned by the job). */
const char *vvg_open_job_path(const vvg_open_job *job);
void vvg_open_job_run(vvg_open_job *job);
gboolean vvg_document_open_finish(vvg_open_job *job, GError **error);
void vvg_open_job_free(vvg_open_job *job);
/**
 * Saves the World as a scene file that `volvis render` renders to the same
 * image (vv_scene_save: an object out of core is written with its file's
 * own level-0 origin and spacing, not its proxy's). Volumes that came from
 * files are referred to by path; volumes made in the session (Modeling, raw import) are written as
 * NRRD beside the scene, under names no file has yet ("<scene>_<i>_<name>.nrrd", else with
 * "-2", "-3", ...), referred to relative to it. All or nothing: the scene
 * is written atomically after the volumes, and when it cannot be, the
 * volumes of this save are removed and the objects keep no reference to
 * them. On failure @p error holds the message.
 */
gboolean vvg_document_save(VvgDocument *doc, const char *path, GError **error);
/**
 * Adds volume @p v (borrowed; the World takes a reference) as an object
 * named @p name, read from @p source (NULL: made in the session, written
 * beside the scene when saved). Into an empty World it gets the default
 * scene of `volvis render FILE` (and the session stays unsaved only if it
 * was); beside other objects the view frames them all. One undo step.
 */
gboolean vvg_document_add_volume(VvgDocument *doc, vv_volume *v, const char *name,
                                 const char *source, GError **error);
/** TRUE for mesh files whose exporters usually write Y up (OBJ, PLY, glTF, COLLADA, FBX). */
gboolean vvg_document_mesh_is_y_up(const char *path);
/**
 * Sets the view's image size (pixels) without an undo step and without
 * marking the session unsaved: the scene view renders at its own size, and
 * a saved session renders through the CLI at that size. No signal.
 */
void vvg_document_set_view_size(VvgDocument *doc, int width, int height);
/**
 * Autosave: writes the World (the kept one while a transient
 * World is shown) into the folder @p dir as one unit: session.json and
 * volume_<i>.nrrd for each volume made in the session, staged in
 * "<dir>.tmp" and exchanged with @p dir in one rename (renameat2
 * RENAME_EXCHANGE), so @p dir always holds one whole autosave. A volume the
 * previous autosave wrote and that has not changed since is hard-linked, not
 * written again. The document's path, unsaved flag and sources are left as
 * they are. On failure @p dir keeps the previous autosave and @p error the
 * message.
 */
gboolean vvg_document_autosave(VvgDocument *doc, const char *dir, GError **error);
/**
 * The same in three steps, so that the writing runs on a worker thread:
 * vvg_document_autosave_begin takes a snapshot of the World (a clone whose
 * objects share the volumes) and of what the last autosave wrote, on the
 * main thread (NULL with @p error when the snapshot fails);
 * vvg_autosave_job_run writes it into the folder on any thread, touching
 * nothing of the document; vvg_document_autosave_end, on the main thread,
 * makes the document remember what a successful run wrote (for the links
 * of the next one). vvg_autosave_job_free releases the job (NULL is fine).
 */
typedef struct vvg_autosave_job vvg_autosave_job;
vvg_autosave_job *vvg_document_autosave_begin(VvgDocument *doc, const char *dir, GError **error);
gboolean vvg_autosave_job_run(vvg_autosave_job *job, GError **error);
/** The folder the job writes (owned by the job). */
const char *vvg_autosave_job_folder(const vvg_autosave_job *job);
void vvg_document_autosave_end(VvgDocument *doc, vvg_autosave_job *job, gboolean ok);
void vvg_autosave_job_free(vvg_autosave_job *job);
/**
 * Opens the autosave in @p dir as an untitled session with unsaved
 * changes; its volumes become volumes of the session again (written by the
 * next save or autosave, so the folder can go). Emits "changed".
 */
gboolean vvg_document_restore(VvgDocument *doc, const char *dir, GError **error);
/** Removes the folder @p dir and all in it (an autosave); NULL is ignored. */
void vvg_document_remove_folder(const char *dir);
/** The scene file the session was opened from or saved to, or NULL. */
const char *vvg_document_path(VvgDocument *doc);
/** TRUE when the World has changed since it was opened or saved. */
gboolean vvg_document_dirty(VvgDocument *doc);

/**
 * The channel of the selected object that the Transfer function page edits
 * (0..n_channels-1), or -1 for an object of one channel (its own tf).
 */
int vvg_document_edited_channel(VvgDocument *doc);
/** Picks the channel the Transfer function page edits; emits "selection-changed". */
void vvg_document_set_edited_channel(VvgDocument *doc, int channel);
/**
 * The time steps of the file volume object @p o came from, as its read in
 * this session said (vvg_document_open): 0 when unknown (a scene's object,
 * a volume made in the session), else >= 1.
 */
int vvg_document_time_steps(VvgDocument *doc, const vv_object *o);

/**
 * The file out of core that volume object @p o shows (vv_object.source: a
 * bricked file or a multiresolution pyramid, opened by vvg_document_open or
 * a scene), whose proxy is the object's volume; NULL when its voxels are in
 * memory (a file read whole, a volume made or filtered in the session).
 * Borrowed (vv_source_ref to keep it).
 */
vv_source *vvg_object_source(const vv_object *o);
/**
 * The memory limit of the process's cache (vv_cache_process, one budget
 * for the bricks and chunks of every file out of core):
 * VOLVIS_MEMORY_LIMIT (bytes, or a number with K, M or G; at least 1M),
 * default 1 GiB. main() sets the cache to it at start-up, before any file
 * is opened; a volume whose level 0 holds more than a quarter of it opens
 * out of core (vv_open's VV_OPEN_AUTO).
 */
uint64_t vvg_document_memory_limit(void);
/**
 * Shows time step @p t of the selected object's file: every channel's
 * voxels replaced by that step's (vv_time_series, opened once a session and
 * reading the next step ahead; only the steps in use are resident), the
 * object's time set. Steps shown within a second of each other are one undo
 * step. Emits "changed". On failure the World is unchanged and @p error
 * holds the message naming the file.
 */
gboolean vvg_document_set_time(VvgDocument *doc, int t, GError **error);

/** Called on the main thread when a requested step could not be shown. */
typedef void (*VvgTimeFailed)(VvgDocument *doc, const char *message, gpointer user);
/**
 * vvg_document_set_time without blocking the interface: the step's voxels
 * are read on a worker thread (the time series are thread-safe; the main
 * thread only opens them) and put in when they arrive, as set_time puts
 * them, if the selected object is still the one asked for and not at that
 * step already. One read is in flight at a time: asks while it reads
 * replace the step to show next (the latest wins), so dragging the slider
 * shows the steps it can keep up with and ends on the last. @p failed
 * (may be NULL) hears of a read that failed. vvg_document_time_pending says
 * whether a read or a next step is outstanding (tests wait on it).
 */
void vvg_document_request_time(VvgDocument *doc, int t, VvgTimeFailed failed, gpointer user);
/** 1 while vvg_document_request_time has a read in flight or a step waiting. */
gboolean vvg_document_time_pending(VvgDocument *doc);
/** Drops @p user as the listener of vvg_document_request_time's failures
 *  (call it when @p user goes away with a read in flight). */
void vvg_document_forget_time_listener(VvgDocument *doc, gpointer user);

/** A cache of time series by (file, channel) for vvg_world_apply_time (g_hash_table_unref it). */
GHashTable *vvg_time_cache_new(void);
/**
 * Puts into every volume object of @p w whose time step differs from the
 * same object's of @p base (the World @p w was evaluated from: the same
 * objects, their voxels those of base's steps) the voxels of its step, read
 * from the file it came from (geometry.source; each channel's own) through
 * the series of @p cache, the step after read ahead: an Animator's
 * objects[i].time track. Any one thread a cache (vv_time_series are
 * thread-safe, the cache is not). FALSE with @p error naming the object or
 * file: a volume made in the session, a step the file does not have, a
 * read error.
 */
gboolean vvg_world_apply_time(GHashTable *cache, vv_world *w, const vv_world *base, GError **error);

/** Adds @p obj (the World takes it), remembering @p source (may be NULL); one undo step. */
void vvg_document_add_object(VvgDocument *doc, vv_object *obj, const char *source);
/** Deletes object @p index; one undo step. */
void vvg_document_delete_object(VvgDocument *doc, int index);
/** Index of the selected object, or -1. */
int vvg_document_selected(VvgDocument *doc);
/** The selected object, or NULL. */
vv_object *vvg_document_selected_object(VvgDocument *doc);
/** Selects object @p index (-1: none) and emits "selection-changed". */
void vvg_document_select(VvgDocument *doc, int index);

/**
 * Shows @p world (taken) in place of the World for a while, with no undo step
 * and without marking the session unsaved, and emits "changed": the
 * Animator's Play puts each evaluated frame here so that the views draw it.
 * The first call keeps the World aside; later calls replace the previous
 * transient World. Meanwhile vvg_document_world returns the transient World
 * (a pointer valid until the next call, as after an undo). Any edit
 * (vvg_document_begin_edit) ends it keeping the World shown, which the edit
 * then changes; undo and redo end it putting the kept World back first;
 * saving writes the kept World. The selection index is kept.
 */
void vvg_document_show_transient(VvgDocument *doc, vv_world *world);
/**
 * Ends a transient World: @p restore puts the World kept aside back exactly
 * as it was and emits "changed"; otherwise the transient World becomes the
 * World. Does nothing when no transient World is shown.
 */
void vvg_document_end_transient(VvgDocument *doc, gboolean restore);
/** TRUE while a transient World is shown (vvg_document_show_transient). */
gboolean vvg_document_transient(VvgDocument *doc);

G_END_DECLS
#endif
