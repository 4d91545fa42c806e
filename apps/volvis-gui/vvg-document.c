/* VvgDocument: the edited World, undo, sources and selection (vvg-document.h). */
#define _GNU_SOURCE /* renameat2 */
#include "vvg-document.h"

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "volvis/filter.h"
#include "vvg-models.h"

struct _VvgDocument {
    GObject parent;
    vv_world *world;
    vv_world *kept; /* the World while a transient one is shown, else NULL */
    vvg_undo *undo;
    char *path;
    gboolean dirty_untracked; /* changed in a way the undo stack cannot return from (restored
                                 from an autosave): unsaved until saved or opened */
    int selected;
    vv_filter_cache *filtered; /* filtered volumes of scene objects, kept across reopenings */
    GPtrArray *autosaved;      /* autosaved_volume: what the last autosave wrote */
    int edited_channel;        /* the channel the Transfer function page edits */
    char *merge_label;         /* vvg_document_begin_edit_merging: the last merged edit */
    gint64 merge_time;
    GHashTable *time_steps; /* source path -> the file's time steps (GINT_TO_POINTER) */
    GHashTable *series;     /* "channel\npath" -> vv_time_series* */
    /* vvg_document_request_time: a read in flight, the step asked for since */
    gboolean time_busy;
    int time_want; /* -1: none */
    VvgTimeFailed time_failed;
    gpointer time_failed_user;
};

/* A volume the last autosave wrote, by identity (a reference of its own) and
 * its modification count: an autosave links the file instead of writing it
 * again while both are the same. */
typedef struct autosaved_volume {
    vv_volume *volume;
    uint64_t modified;
    char *file; /* base name in the autosave folder */
} autosaved_volume;

static void
autosaved_volume_free(gpointer p) {
    autosaved_volume *a = p;
    vv_volume_free(a->volume);
    g_free(a->file);
    g_free(a);
}

G_DEFINE_TYPE(VvgDocument, vvg_document, G_TYPE_OBJECT)

enum { SIGNAL_CHANGED, SIGNAL_SELECTION_CHANGED, N_SIGNALS };
static guint signals[N_SIGNALS];

G_DEFINE_QUARK(vvg - error - quark, vvg_error)

static void
set_error(GError **error, const char *fallback) {
    const char *m = vv_error_message();
    g_set_error_literal(error, VVG_ERROR, 1, m && *m ? m : fallback);
}

static void
vvg_document_finalize(GObject *o) {
    VvgDocument *doc = VVG_DOCUMENT(o);
    vv_world_free(doc->world);
    vv_world_free(doc->kept);
    vvg_undo_free(doc->undo);
    vv_filter_cache_free(doc->filtered);
    g_free(doc->path);
    g_ptr_array_unref(doc->autosaved);
    g_free(doc->merge_label);
    g_hash_table_unref(doc->time_steps);
    g_hash_table_unref(doc->series);
    G_OBJECT_CLASS(vvg_document_parent_class)->finalize(o);
}

static void
vvg_document_class_init(VvgDocumentClass *klass) {
    G_OBJECT_CLASS(klass)->finalize = vvg_document_finalize;
    signals[SIGNAL_CHANGED] = g_signal_new("changed", G_TYPE_FROM_CLASS(klass), G_SIGNAL_RUN_LAST,
                                           0, NULL, NULL, NULL, G_TYPE_NONE, 0);
    signals[SIGNAL_SELECTION_CHANGED] =
        g_signal_new("selection-changed", G_TYPE_FROM_CLASS(klass), G_SIGNAL_RUN_LAST, 0, NULL,
                     NULL, NULL, G_TYPE_NONE, 0);
}

static void
vvg_document_init(VvgDocument *doc) {
    if (vv_world_new(&doc->world) != VV_OK || vvg_undo_new(&doc->undo, 200) != VV_OK ||
        vv_filter_cache_new(&doc->filtered, 8) != VV_OK)
        g_error("volvis-gui: out of memory");
    doc->selected = -1;
    doc->autosaved = g_ptr_array_new_with_free_func(autosaved_volume_free);
    doc->time_steps = g_hash_table_new_full(g_str_hash, g_str_equal, g_free, NULL);
    doc->series = vvg_time_cache_new();
    doc->time_want = -1;
}

VvgDocument *
vvg_document_new(void) {
    return g_object_new(VVG_TYPE_DOCUMENT, NULL);
}

vv_world *
vvg_document_world(VvgDocument *doc) {
    return doc->world;
}

vv_world *
vvg_document_snapshot(VvgDocument *doc) {
    vv_world *w = NULL;
    if (vv_world_clone(&w, doc->world) != VV_OK)
        return NULL;
    return w;
}

static void
clamp_selection(VvgDocument *doc) {
    if (doc->selected >= doc->world->n_objects)
        doc->selected = doc->world->n_objects - 1;
    if (doc->selected < 0 && doc->world->n_objects > 0)
        doc->selected = 0;
}

/* Drops the World kept aside: the transient World shown becomes the World. */
static void
keep_transient(VvgDocument *doc) {
    vv_world_free(doc->kept);
    doc->kept = NULL;
}

/* Puts the World kept aside back, without a signal. */
static void
restore_kept(VvgDocument *doc) {
    if (!doc->kept)
        return;
    vv_world_free(doc->world);
    doc->world = doc->kept;
    doc->kept = NULL;
    clamp_selection(doc);
}

/* The state now is the one opened or saved: the undo stack's clean state. */
static void
mark_clean(VvgDocument *doc) {
    vvg_undo_mark_clean(doc->undo);
    doc->dirty_untracked = FALSE;
    g_clear_pointer(&doc->merge_label, g_free); /* the next edit is a step of its own */
}

void
vvg_document_begin_edit(VvgDocument *doc, const char *label) {
    /* callers may hold pointers into the World shown: the edit changes it */
    keep_transient(doc);
    if (vvg_undo_push(doc->undo, doc->world, label) != VV_OK) {
        g_warning("volvis-gui: no undo step for '%s': %s", label, vv_error_message());
        vvg_undo_mark_unclean(doc->undo); /* changed, and no step returns to the clean state */
    }
    g_clear_pointer(&doc->merge_label, g_free);
}

void
vvg_document_begin_edit_merging(VvgDocument *doc, const char *label) {
    gint64 now = g_get_monotonic_time();
    if (doc->merge_label && !strcmp(doc->merge_label, label) && now - doc->merge_time < 1000000 &&
        !doc->kept && vvg_undo_can_undo(doc->undo)) {
        doc->merge_time = now;
        vvg_undo_mark_unclean(doc->undo); /* merged into the last step: the state moved on */
        return;
    }
    vvg_document_begin_edit(doc, label);
    doc->merge_label = g_strdup(label);
    doc->merge_time = now;
}

void
vvg_document_changed(VvgDocument *doc) {
    g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
}

static void
world_replaced(VvgDocument *doc) {
    clamp_selection(doc);
    g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
    g_signal_emit(doc, signals[SIGNAL_SELECTION_CHANGED], 0);
}

gboolean
vvg_document_undo(VvgDocument *doc) {
    g_clear_pointer(&doc->merge_label, g_free);
    gboolean restored = doc->kept != NULL;
    restore_kept(doc);
    if (vvg_undo_undo(doc->undo, &doc->world) != VV_OK) {
        if (restored)
            g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
        return FALSE;
    }
    world_replaced(doc); /* back at the opened or saved state: clean (vvg_undo_is_clean) */
    return TRUE;
}

gboolean
vvg_document_redo(VvgDocument *doc) {
    g_clear_pointer(&doc->merge_label, g_free);
    gboolean restored = doc->kept != NULL;
    restore_kept(doc);
    if (vvg_undo_redo(doc->undo, &doc->world) != VV_OK) {
        if (restored)
            g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
        return FALSE;
    }
    world_replaced(doc);
    return TRUE;
}

gboolean
vvg_document_can_undo(VvgDocument *doc) {
    return vvg_undo_can_undo(doc->undo);
}

gboolean
vvg_document_can_redo(VvgDocument *doc) {
    return vvg_undo_can_redo(doc->undo);
}

/* @p path made absolute (a new string); a URL as it is: no folder of the
 * working directory is put before "http://". */
static char *
canonical(const char *path) {
    return vv_path_is_url(path) ? g_strdup(path) : g_canonicalize_filename(path, NULL);
}

/* The file an object's volume came from, kept in geometry.source as scene
 * loading does, so saving refers to it. */
static void
remember_source(vv_object *o, const char *path) {
    if (!o || !path)
        return;
    free(o->geometry.source);
    /* malloc'ed: the library frees it with free() */
    char *abs = canonical(path);
    size_t n = strlen(abs) + 1;
    o->geometry.source = malloc(n);
    if (o->geometry.source)
        memcpy(o->geometry.source, abs, n);
    g_free(abs);
}

static gboolean
has_suffix(const char *path, const char *const *suffixes) {
    g_autofree char *lower = g_ascii_strdown(path, -1);
    for (int i = 0; suffixes[i]; i++)
        if (g_str_has_suffix(lower, suffixes[i]))
            return TRUE;
    return FALSE;
}

static const char *const mesh_suffixes[] = {".obj", ".ply", ".stl",  ".off", ".dae",
                                            ".3ds", ".fbx", ".gltf", ".glb", NULL};

/* How the GUI opens files: through the door (vv_world_open), out of core
 * when level 0 holds more than a quarter of the process's cache budget
 * (vvg_document_memory_limit, set at start-up), a .vvb always, a file with
 * pyramid levels by its levels (level of detail), not by bricks; a volume
 * file's every channel as one object, in memory or out of core (a
 * pyramid's nodes holding every channel: the channel panel's toggles,
 * colours and contrast redraw from the cache). */
static void
open_options(VvgDocument *doc, vv_world_open_options *o) {
    vv_world_open_options_init(o);
    o->memory = VV_WORLD_OUT_OF_CORE_IF_LARGE;
    o->memory_limit = vvg_document_memory_limit();
    o->all_channels = 1;
    o->filter_cache = doc->filtered;
}

/* Scene file @p path's World @p w (the door's; taken) replaces the World;
 * its volumes' files are the scene's, each opened as open_options says
 * (the objects out of core own their files' sources, all in the process's
 * one cache). */
static gboolean
show_scene(VvgDocument *doc, const char *path, vv_world *w) {
    vvg_document_begin_edit(doc, "open scene");
    /* the view fills the window: the scene's camera at the window's size */
    if (doc->world->view.width > 0 && doc->world->view.height > 0) {
        w->view.width = doc->world->view.width;
        w->view.height = doc->world->view.height;
    }
    vv_world_free(doc->world);
    doc->world = w;
    /* the scene names its volumes relative to itself; without the names at
     * hand, saving writes them beside the new scene unless found below */
    g_free(doc->path);
    doc->path = g_canonicalize_filename(path, NULL);
    doc->selected = w->n_objects > 0 ? 0 : -1;
    mark_clean(doc);
    world_replaced(doc);
    return TRUE;
}

/* The renderer that draws every object of @p w: a renderer the user chose
 * that draws them is kept, else the World's default (vv_world_renderer:
 * the first renderer whose capabilities cover every object, or gpu in its
 * place: vvg_gui_renderer), named in the settings so the saved scene
 * renders the same through the CLI. */
static void
choose_renderer(vv_world *w) {
    const vv_renderer_info *info = vv_renderer_info_find(vv_render_settings_renderer(&w->render));
    gboolean all = info != NULL;
    for (int i = 0; all && i < w->n_objects; i++)
        all = !w->objects[i]->visible || (info->draws & VV_DRAWS(w->objects[i]->type));
    if (all)
        return;
    w->render.renderer[0] = '\0';
    w->render.n_options = 0; /* the options belong to the other renderer */
    /* on a machine with a real GPU the gpu renderer where it draws the World
     * (vvg_gui_renderer; never on a CPU device such as lavapipe) */
    g_strlcpy(w->render.renderer, vvg_gui_renderer(w, vv_world_renderer(w)),
              sizeof w->render.renderer);
}

gboolean
vvg_document_mesh_is_y_up(const char *path) {
    /* the exporters' conventions: OBJ, PLY, glTF, COLLADA and FBX are
     * usually Y-up; STL, OFF and 3DS (CAD, printing) Z-up */
    static const char *const y_up[] = {".obj", ".ply", ".gltf", ".glb", ".dae", ".fbx", NULL};
    return has_suffix(path, y_up);
}

/* The object added beside others: the view frames the whole World (same
 * undo step), and the renderer is one that draws everything. */
static void
added_beside(VvgDocument *doc) {
    vv_world *w = doc->world;
    choose_renderer(w);
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    vvg_document_changed(doc);
}

/* Adds mesh @p m (borrowed) read from @p path as an object. */
static gboolean
add_mesh(VvgDocument *doc, const char *path, vv_mesh *m, GError **error) {
    vv_object *o = NULL;
    g_autofree char *base = g_path_get_basename(path);
    vv_status s = vv_object_new_geometry(&o, VV_OBJECT_MESH, base);
    g_autofree char *abs = g_canonicalize_filename(path, NULL);
    if (s == VV_OK)
        s = vv_object_set_mesh(o, m, abs);
    if (s != VV_OK) {
        vv_object_free(o);
        set_error(error, "cannot use the mesh");
        return FALSE;
    }
    if (vvg_document_mesh_is_y_up(path)) /* its Y turned to the World's Z (up) */
        o->orientation = vv_quat_from_axis_angle(vv_vec3_make(1, 0, 0), VV_PI / 2);
    gboolean fresh = doc->world->n_objects == 0 && !vvg_document_dirty(doc);
    if (doc->world->n_objects == 0 && doc->world->n_lights == 0) {
        vv_light l = {VV_LIGHT_DIRECTIONAL, 1, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1.0};
        vv_world_add_light(doc->world, &l);
    }
    vvg_document_add_object(doc, o, NULL);
    added_beside(doc);
    if (fresh) /* a file just opened is not "unsaved" */
        mark_clean(doc);
    return TRUE;
}

static gboolean
open_mesh(VvgDocument *doc, const char *path, GError **error) {
    vv_mesh *m = NULL;
    if (vv_mesh_load(&m, path) != VV_OK) {
        set_error(error, "cannot read the mesh");
        return FALSE;
    }
    const gboolean ok = add_mesh(doc, path, m, error);
    vv_mesh_free(m);
    return ok;
}

/* Shows the first object of @p w (a default World: the door's, or one of a
 * volume in memory), named @p name, read from @p source (may be NULL): in
 * an empty document @p w becomes the World (its view, lights and shading;
 * the session's render settings and view size stay), else the object is
 * added beside the others. Takes @p w. */
static gboolean
show_default_world(VvgDocument *doc, vv_world *w, const char *name, const char *source) {
    /* the object as `volvis render FILE` shows it */
    vv_object *obj = NULL;
    vv_world_take_object(w, 0, &obj);
    g_strlcpy(obj->name, name, sizeof obj->name);
    if (source)
        remember_source(obj, source);
    if (doc->world->n_objects == 0) {
        gboolean fresh = !vvg_document_dirty(doc);
        vvg_document_begin_edit(doc, "open volume");
        /* the default scene's view, lights and shading; the session's
         * render settings and view size stay */
        w->render = doc->world->render;
        gboolean resized = FALSE;
        if (doc->world->view.width > 0 && doc->world->view.height > 0) {
            resized = w->view.width != doc->world->view.width ||
                      w->view.height != doc->world->view.height;
            w->view.width = doc->world->view.width;
            w->view.height = doc->world->view.height;
        }
        vv_world_free(doc->world);
        doc->world = w;
        vv_world_add_object(doc->world, obj);
        if (!w->render.renderer[0]) {
            /* no renderer named: the gpu renderer where the GUI picks it on
             * its own (a real GPU: vvg_gui_renderer), else none (the default) */
            const char *dflt = vv_world_renderer(w), *pick = vvg_gui_renderer(w, dflt);
            if (strcmp(pick, dflt) != 0)
                g_strlcpy(w->render.renderer, pick, sizeof w->render.renderer);
        }
        if (resized) /* framed for the window's shape */
            vv_view_frame_box(&w->view, vv_world_bounds(w));
        doc->selected = 0;
        if (fresh) /* a file just opened is not "unsaved" */
            mark_clean(doc);
        world_replaced(doc);
        return TRUE;
    }
    vv_world_free(w);
    vvg_document_add_object(doc, obj, NULL);
    added_beside(doc);
    return TRUE;
}

gboolean
vvg_document_add_volume(VvgDocument *doc, vv_volume *v, const char *name, const char *source,
                        GError **error) {
    vv_world *w = NULL;
    vv_error_clear();
    if (vv_world_new_for_volume(&w, v, NULL) != VV_OK) {
        set_error(error, "cannot show the volume");
        return FALSE;
    }
    return show_default_world(doc, w, name, source);
}

/* ---- files out of core -------------------------------------------------------- */

vv_source *
vvg_object_source(const vv_object *o) {
    if (!o || o->type != VV_OBJECT_VOLUME || !o->source)
        return NULL;
    return vv_source_get_kind(o->source) == VV_SOURCE_MEMORY ? NULL : o->source;
}

uint64_t
vvg_document_memory_limit(void) {
    const char *e = g_getenv("VOLVIS_MEMORY_LIMIT");
    if (!e || !*e)
        return VV_CACHE_DEFAULT_LIMIT;
    char *end = NULL;
    double v = g_ascii_strtod(e, &end);
    const char u = end ? g_ascii_toupper(*end) : '\0';
    v *= u == 'K' ? 1024.0 : u == 'M' ? 1048576.0 : u == 'G' ? 1073741824.0 : 1.0;
    if (!(v >= 1048576.0) || v > 1e15) {
        g_warning("volvis-gui: VOLVIS_MEMORY_LIMIT=%s is not a size of at least 1M; 1G is used", e);
        return VV_CACHE_DEFAULT_LIMIT;
    }
    return (uint64_t)v;
}

/* A volume object's name from its file: the file name up to its first dot
 * ("brain.nii.gz" is "brain"). Free with g_free. */
static char *
volume_name(const char *path) {
    char *base = g_path_get_basename(path);
    char *dot = strchr(base, '.');
    if (dot && dot != base)
        *dot = '\0';
    return base;
}

struct vvg_open_job {
    VvgDocument *doc; /* a reference: its filter cache is used by the run */
    char *path;
    vv_world_open_options options;
    vv_world *world; /* the run's result (NULL: failed, or not run) */
    vv_world_open_info info;
    char *error; /* the run's error message (the worker's trace, copied) */
};

vvg_open_job *
vvg_document_open_job_new(VvgDocument *doc, const char *path) {
    vvg_open_job *job = g_new0(vvg_open_job, 1);
    job->doc = g_object_ref(doc);
    job->path = g_strdup(path);
    open_options(doc, &job->options);
    return job;
}

const char *
vvg_open_job_path(const vvg_open_job *job) {
    return job->path;
}

void
vvg_open_job_run(vvg_open_job *job) {
    vv_error_clear();
    if (vv_world_open(&job->world, job->path, &job->options, &job->info) != VV_OK) {
        const char *m = vv_error_message();
        job->error = g_strdup(m && *m ? m : NULL);
        job->world = NULL;
    }
}

void
vvg_open_job_free(vvg_open_job *job) {
    if (!job)
        return;
    vv_world_free(job->world);
    g_free(job->error);
    g_free(job->path);
    g_object_unref(job->doc);
    g_free(job);
}

/* A volume file, a folder (a DICOM series, a TIFF stack, a store) or a
 * scene through the door (open_options, vvg_open_job_run): a volume read
 * whole shows every channel (the first VV_MAX_CHANNELS) at time step 0, out
 * of core channel 0 alone (the drivers out of core draw objects of one
 * channel), the object owning the source; a mesh that the door names so is
 * added as a mesh; a grid is refused. */
gboolean
vvg_document_open_finish(vvg_open_job *job, GError **error) {
    VvgDocument *doc = job->doc;
    const char *path = job->path;
    const vv_world_open_info info = job->info;
    if (!job->world) {
        if (info.input == VV_INPUT_MESH) { /* the format table's mesh, by its content */
            vv_error_clear();
            return open_mesh(doc, path, error);
        }
        const char *fallback =
            info.input == VV_INPUT_SCENE ? "cannot read the scene" : "cannot read the volume";
        g_set_error_literal(error, VVG_ERROR, 1, job->error ? job->error : fallback);
        return FALSE;
    }
    vv_world *w = g_steal_pointer(&job->world);
    if (info.input == VV_INPUT_SCENE)
        return show_scene(doc, path, w);
    if (info.input == VV_INPUT_GRID) {
        vv_world_free(w);
        g_autofree char *base = g_path_get_basename(path);
        g_set_error(error, VVG_ERROR, 1,
                    "%s: an irregular grid; the GUI shows volumes and meshes (volvis render "
                    "draws grids)",
                    base);
        return FALSE;
    }
    if (info.n_channels > VV_MAX_CHANNELS)
        g_message("volvis-gui: %s has %d channels; the first %d are shown", path, info.n_channels,
                  VV_MAX_CHANNELS);
    g_autofree char *base = volume_name(path);
    /* before the object, whose "changed" the pages fill from; keyed as
     * remember_source names the file; a file out of core shows its step 0 */
    g_hash_table_replace(doc->time_steps, canonical(path),
                         GINT_TO_POINTER(!info.out_of_core && info.n_times > 1 ? info.n_times : 1));
    return show_default_world(doc, w, base, path);
}

static gboolean
open_input(VvgDocument *doc, const char *path, GError **error) {
    vvg_open_job *job = vvg_document_open_job_new(doc, path);
    vvg_open_job_run(job);
    const gboolean ok = vvg_document_open_finish(job, error);
    vvg_open_job_free(job);
    return ok;
}

gboolean
vvg_document_open(VvgDocument *doc, const char *path, GError **error) {
    vv_error_clear();
    if (has_suffix(path, mesh_suffixes))
        return open_mesh(doc, path, error);
    /* a Zarr store chosen by its metadata file (a file chooser picks no folder) */
    g_autofree char *leaf = g_path_get_basename(path);
    g_autofree char *store =
        !strcmp(leaf, ".zattrs") || !strcmp(leaf, ".zgroup") || !strcmp(leaf, ".zarray")
            ? g_path_get_dirname(path)
            : NULL;
    if (store) /* the folder is the store; the door says what it holds */
        path = store;
    return open_input(doc, path, error);
}

int
vvg_document_edited_channel(VvgDocument *doc) {
    vv_object *o = vvg_document_selected_object(doc);
    if (!o || o->n_channels < 1)
        return -1;
    return doc->edited_channel < o->n_channels ? doc->edited_channel : 0;
}

void
vvg_document_set_edited_channel(VvgDocument *doc, int channel) {
    doc->edited_channel = channel > 0 ? channel : 0;
    g_signal_emit(doc, signals[SIGNAL_SELECTION_CHANGED], 0);
}

int
vvg_document_time_steps(VvgDocument *doc, const vv_object *o) {
    if (!o || o->type != VV_OBJECT_VOLUME || !o->geometry.source)
        return 0;
    return GPOINTER_TO_INT(g_hash_table_lookup(doc->time_steps, o->geometry.source));
}

GHashTable *
vvg_time_cache_new(void) {
    return g_hash_table_new_full(g_str_hash, g_str_equal, g_free,
                                 (GDestroyNotify)vv_time_series_free);
}

/* The time series of channel @p index of @p path in @p cache, opened once. */
static vv_time_series *
series_for(GHashTable *cache, const char *path, int index) {
    g_autofree char *key = g_strdup_printf("%d\n%s", index, path);
    vv_time_series *ts = g_hash_table_lookup(cache, key);
    if (ts)
        return ts;
    vv_load_options opt;
    vv_load_options_init(&opt);
    opt.channel = index;
    vv_error_clear();
    if (vv_time_series_open(&ts, path, &opt, 0) != VV_OK)
        return NULL;
    g_hash_table_replace(cache, g_steal_pointer(&key), ts);
    return ts;
}

/* Step @p t of every channel of @p o's file into @p v (new references), the
 * step after read ahead. */
static vv_status
read_step(GHashTable *cache, const vv_object *o, int t, vv_volume **v) {
    const int n = o->n_channels > 0 ? o->n_channels : 1;
    vv_status s = VV_OK;
    for (int c = 0; c < n && s == VV_OK; c++) {
        vv_time_series *ts =
            series_for(cache, o->geometry.source, o->n_channels > 0 ? o->channels[c].index : -1);
        s = ts ? vv_time_series_get(ts, t, &v[c]) : vv_error_prefix(VV_ERR_IO, "%s", o->name);
        if (ts && s == VV_OK && t + 1 < vv_time_series_count(ts))
            vv_time_series_prefetch(ts, t + 1); /* the next step while this one draws */
    }
    if (s != VV_OK)
        for (int c = 0; c < n; c++)
            g_clear_pointer(&v[c], vv_volume_free);
    return s;
}

gboolean
vvg_world_apply_time(GHashTable *cache, vv_world *w, const vv_world *base, GError **error) {
    for (int i = 0; i < w->n_objects && i < base->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->type != VV_OBJECT_VOLUME || !o->volume || o->time == base->objects[i]->time)
            continue;
        if (!o->geometry.source) {
            g_set_error(error, VVG_ERROR, 1,
                        "%s: time step %d: the volume was not read from a file", o->name, o->time);
            return FALSE;
        }
        vv_volume *v[VV_MAX_CHANNELS] = {NULL};
        vv_error_clear();
        vv_status s = read_step(cache, o, o->time, v);
        if (s == VV_OK)
            s = vv_object_replace_volumes(o, o->n_channels > 0 ? o->n_channels : 1, v);
        for (int c = 0; c < VV_MAX_CHANNELS; c++)
            vv_volume_free(v[c]);
        if (s != VV_OK) {
            set_error(error, "cannot read the time step");
            return FALSE;
        }
    }
    return TRUE;
}

/* Step @p t of the selected object @p o exists; else @p error says not. */
static gboolean
check_step(VvgDocument *doc, const vv_object *o, int t, GError **error) {
    const int steps = vvg_document_time_steps(doc, o);
    if (steps >= 2 && t >= 0 && t < steps)
        return TRUE;
    g_set_error(error, VVG_ERROR, 1, "%s: no time step %d (%d steps)", o ? o->name : "no object", t,
                steps);
    return FALSE;
}

gboolean
vvg_document_set_time(VvgDocument *doc, int t, GError **error) {
    vv_object *o = vvg_document_selected_object(doc);
    if (!check_step(doc, o, t, error))
        return FALSE;
    if (o->time == t)
        return TRUE;
    const int n = o->n_channels > 0 ? o->n_channels : 1;
    vv_volume *v[VV_MAX_CHANNELS] = {NULL};
    vv_error_clear();
    vv_status s = read_step(doc->series, o, t, v);
    if (s == VV_OK) {
        vvg_document_begin_edit_merging(doc, "time step");
        o = vvg_document_selected_object(doc);
        vv_error_clear();
        if ((s = vv_object_replace_volumes(o, n, v)) == VV_OK)
            o->time = t;
    }
    for (int c = 0; c < n; c++)
        vv_volume_free(v[c]);
    if (s != VV_OK) {
        set_error(error, "cannot read the time step");
        return FALSE;
    }
    vvg_document_changed(doc);
    return TRUE;
}

/* One asynchronous step read (vvg_document_request_time): the series are
 * resolved on the main thread, read on a worker. */
typedef struct time_job {
    int t, n;
    char *source; /* the object's file: the result goes to an object of it */
    vv_time_series *ts[VV_MAX_CHANNELS];
    vv_volume *v[VV_MAX_CHANNELS];
    char *message; /* the read's error, or NULL */
} time_job;

static void
time_job_free(gpointer p) {
    time_job *j = p;
    for (int c = 0; c < j->n; c++)
        vv_volume_free(j->v[c]);
    g_free(j->source);
    g_free(j->message);
    g_free(j);
}

static void
time_job_run(GTask *task, gpointer src, gpointer data, GCancellable *cancel) {
    (void)src;
    (void)cancel;
    time_job *j = data;
    for (int c = 0; c < j->n && !j->message; c++) {
        vv_error_clear();
        if (vv_time_series_get(j->ts[c], j->t, &j->v[c]) != VV_OK)
            j->message = g_strdup(vv_error_message());
        else if (j->t + 1 < vv_time_series_count(j->ts[c]))
            vv_time_series_prefetch(j->ts[c], j->t + 1); /* the next step while this one draws */
    }
    g_task_return_boolean(task, TRUE);
}

static void time_job_start(VvgDocument *doc);

static void
time_job_done(GObject *src, GAsyncResult *res, gpointer data) {
    (void)data;
    VvgDocument *doc = VVG_DOCUMENT(src);
    time_job *j = g_task_get_task_data(G_TASK(res));
    doc->time_busy = FALSE;
    vv_object *o = vvg_document_selected_object(doc);
    const int n = o && o->n_channels > 0 ? o->n_channels : 1;
    if (j->message) {
        doc->time_want = -1;
        if (doc->time_failed)
            doc->time_failed(doc, j->message, doc->time_failed_user);
    } else if (o && o->geometry.source && !strcmp(o->geometry.source, j->source) && n == j->n &&
               o->time != j->t) {
        vvg_document_begin_edit_merging(doc, "time step");
        o = vvg_document_selected_object(doc);
        vv_error_clear();
        if (vv_object_replace_volumes(o, n, j->v) == VV_OK) {
            o->time = j->t;
            vvg_document_changed(doc);
        } else if (doc->time_failed) {
            doc->time_failed(doc, vv_error_message(), doc->time_failed_user);
        }
    }
    if (doc->time_want >= 0)
        time_job_start(doc);
}

/* Starts reading doc->time_want of the selected object, unless it is shown. */
static void
time_job_start(VvgDocument *doc) {
    vv_object *o = vvg_document_selected_object(doc);
    const int t = doc->time_want;
    doc->time_want = -1;
    if (!o || !o->geometry.source || o->time == t)
        return;
    time_job *j = g_new0(time_job, 1);
    j->t = t;
    j->n = o->n_channels > 0 ? o->n_channels : 1;
    j->source = g_strdup(o->geometry.source);
    for (int c = 0; c < j->n; c++) {
        j->ts[c] = series_for(doc->series, o->geometry.source,
                              o->n_channels > 0 ? o->channels[c].index : -1);
        if (!j->ts[c]) {
            if (doc->time_failed)
                doc->time_failed(doc, vv_error_message(), doc->time_failed_user);
            time_job_free(j);
            return;
        }
    }
    doc->time_busy = TRUE;
    GTask *task = g_task_new(doc, NULL, time_job_done, NULL);
    g_task_set_task_data(task, j, time_job_free);
    g_task_run_in_thread(task, time_job_run);
    g_object_unref(task);
}

void
vvg_document_request_time(VvgDocument *doc, int t, VvgTimeFailed failed, gpointer user) {
    g_autoptr(GError) err = NULL;
    doc->time_failed = failed;
    doc->time_failed_user = user;
    if (!check_step(doc, vvg_document_selected_object(doc), t, &err)) {
        if (failed)
            failed(doc, err->message, user);
        return;
    }
    doc->time_want = t;
    if (!doc->time_busy)
        time_job_start(doc);
}

gboolean
vvg_document_time_pending(VvgDocument *doc) {
    return doc->time_busy || doc->time_want >= 0;
}

void
vvg_document_forget_time_listener(VvgDocument *doc, gpointer user) {
    if (doc->time_failed_user == user) {
        doc->time_failed = NULL;
        doc->time_failed_user = NULL;
    }
}

void
vvg_document_set_view_size(VvgDocument *doc, int width, int height) {
    if (width < 1 || height < 1)
        return;
    doc->world->view.width = width;
    doc->world->view.height = height;
    if (doc->kept) {
        doc->kept->view.width = width;
        doc->kept->view.height = height;
    }
}

const char *
vvg_document_path(VvgDocument *doc) {
    return doc->path;
}

gboolean
vvg_document_dirty(VvgDocument *doc) {
    return doc->dirty_untracked || !vvg_undo_is_clean(doc->undo);
}

gboolean
vvg_document_save(VvgDocument *doc, const char *path, GError **error) {
    vv_world *w = doc->kept ? doc->kept : doc->world; /* never a transient World */
    g_autofree char *dir = g_path_get_dirname(path);
    g_autofree char *stem = g_path_get_basename(path);
    char *dot = strrchr(stem, '.');
    if (dot && dot != stem)
        *dot = '\0';
    /* All or nothing: the volumes made in the session are written under
     * names no file has yet (an older save's files stay as its scene needs
     * them), then the scene; when the scene cannot be written, the volumes
     * of this save are removed again and no object takes their names. */
    const char **files = g_new0(const char *, w->n_objects > 0 ? w->n_objects : 1);
    GPtrArray *written = g_ptr_array_new_with_free_func(g_free);
    gboolean ok = TRUE;
    for (int i = 0; ok && i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->type != VV_OBJECT_VOLUME || !o->volume || o->geometry.source)
            continue; /* vv_scene_save refers to the file it came from */
        g_autofree char *base = g_strdup_printf("%s_%d_%s", stem, i, o->name);
        for (char *c = base; *c; c++)
            if (!g_ascii_isalnum(*c) && *c != '.' && *c != '_' && *c != '-')
                *c = '_';
        char *full = NULL;
        for (int k = 1; !full || g_file_test(full, G_FILE_TEST_EXISTS); k++) {
            g_free(full);
            g_autofree char *name =
                k == 1 ? g_strdup_printf("%s.nrrd", base) : g_strdup_printf("%s-%d.nrrd", base, k);
            full = g_build_filename(dir, name, NULL);
        }
        vv_error_clear();
        if (vv_volume_save(o->volume, full, VV_FORMAT_NRRD, 0) != VV_OK) {
            set_error(error, "cannot write a volume");
            g_free(full);
            ok = FALSE;
            break;
        }
        g_ptr_array_add(written, full);
        const char *slash = strrchr(full, '/');
        files[i] = slash ? slash + 1 : full; /* beside the scene: relative to it */
    }
    vv_error_clear();
    /* objects out of core are written with their files' level-0 geometry */
    if (ok && vv_scene_save(w, path, files) != VV_OK) {
        set_error(error, "cannot write the scene");
        ok = FALSE;
    }
    if (ok) {
        for (int i = 0, k = 0; i < w->n_objects; i++)
            if (files[i])
                remember_source(w->objects[i], g_ptr_array_index(written, k++));
    } else {
        for (guint i = 0; i < written->len; i++)
            unlink(g_ptr_array_index(written, i));
    }
    g_free(files);
    g_ptr_array_unref(written);
    if (!ok)
        return FALSE;
    /* @p path may be doc->path itself (Save): canonicalize before freeing */
    char *saved = g_canonicalize_filename(path, NULL);
    g_free(doc->path);
    doc->path = saved;
    mark_clean(doc);
    return TRUE;
}

/* ---- autosave ---------------------------------------------------------------- */

static int
remove_entry(const char *p, const struct stat *st, int flag, struct FTW *ftw) {
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(p) != 0 && errno != ENOENT ? -1 : 0;
}

void
vvg_document_remove_folder(const char *dir) {
    if (dir)
        nftw(dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* The file the autosave @p prev lists for @p v as it is now, or NULL. */
static const char *
autosaved_file(const GPtrArray *prev, const vv_volume *v) {
    for (guint i = 0; i < prev->len; i++) {
        const autosaved_volume *a = g_ptr_array_index(prev, i);
        if (a->volume == v && a->modified == v->modified)
            return a->file;
    }
    return NULL;
}

/* An autosave in the making: a snapshot of the World (the objects share
 * their volumes, referenced) and what the last autosave wrote, so that it
 * can be written on another thread while the session goes on. */
struct vvg_autosave_job {
    vv_world *world;
    char *dir;
    GPtrArray *prev; /* autosaved_volume: the last autosave's, references of their own */
    GPtrArray *done; /* autosaved_volume: what this one wrote */
};

/* Writes the staged session into @p stage: volume_<i>.nrrd for each volume
 * made in the session (linked from the job's folder when unchanged), then
 * session.json. */
static gboolean
autosave_stage(vvg_autosave_job *job, const char *stage, GError **error) {
    const vv_world *w = job->world;
    const char **files = g_new0(const char *, w->n_objects > 0 ? w->n_objects : 1);
    GPtrArray *names = g_ptr_array_new_with_free_func(g_free);
    gboolean ok = TRUE;
    for (int i = 0; ok && i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->type != VV_OBJECT_VOLUME || !o->volume || o->geometry.source)
            continue;
        char *name = g_strdup_printf("volume_%d.nrrd", i);
        g_ptr_array_add(names, name);
        files[i] = name;
        g_autofree char *to = g_build_filename(stage, name, NULL);
        const char *old = autosaved_file(job->prev, o->volume);
        g_autofree char *from = old ? g_build_filename(job->dir, old, NULL) : NULL;
        if (!from || link(from, to) != 0) {
            vv_error_clear();
            if (vv_volume_save(o->volume, to, VV_FORMAT_NRRD, 0) != VV_OK) {
                set_error(error, "cannot write a volume");
                ok = FALSE;
                break;
            }
        }
        autosaved_volume *a = g_new0(autosaved_volume, 1);
        a->volume = vv_volume_ref(o->volume);
        a->modified = o->volume->modified;
        a->file = g_strdup(name);
        g_ptr_array_add(job->done, a);
    }
    g_autofree char *scene = g_build_filename(stage, "session.json", NULL);
    vv_error_clear();
    if (ok && vv_scene_save(w, scene, files) != VV_OK) {
        set_error(error, "cannot write the scene");
        ok = FALSE;
    }
    g_free(files);
    g_ptr_array_unref(names);
    return ok;
}

vvg_autosave_job *
vvg_document_autosave_begin(VvgDocument *doc, const char *dir, GError **error) {
    const vv_world *w = doc->kept ? doc->kept : doc->world; /* never a transient World */
    vvg_autosave_job *job = g_new0(vvg_autosave_job, 1);
    vv_error_clear();
    if (vv_world_clone(&job->world, w) != VV_OK) {
        set_error(error, "cannot take a snapshot of the World");
        g_free(job);
        return NULL;
    }
    job->dir = g_strdup(dir);
    job->prev = g_ptr_array_new_with_free_func(autosaved_volume_free);
    for (guint i = 0; i < doc->autosaved->len; i++) {
        const autosaved_volume *a = g_ptr_array_index(doc->autosaved, i);
        autosaved_volume *c = g_new0(autosaved_volume, 1);
        c->volume = vv_volume_ref(a->volume);
        c->modified = a->modified;
        c->file = g_strdup(a->file);
        g_ptr_array_add(job->prev, c);
    }
    job->done = g_ptr_array_new_with_free_func(autosaved_volume_free);
    return job;
}

gboolean
vvg_autosave_job_run(vvg_autosave_job *job, GError **error) {
    const char *dir = job->dir;
    g_autofree char *stage = g_strconcat(dir, ".tmp", NULL);
    vvg_document_remove_folder(stage); /* a stage an earlier crash left */
    if (g_mkdir_with_parents(stage, 0700) != 0) {
        g_set_error(error, VVG_ERROR, 1, "%s: %s", stage, g_strerror(errno));
        return FALSE;
    }
    gboolean ok = autosave_stage(job, stage, error);
    /* one unit: the stage takes the folder's place in one step */
    if (ok && g_file_test(dir, G_FILE_TEST_IS_DIR)) {
        if (renameat2(AT_FDCWD, stage, AT_FDCWD, dir, RENAME_EXCHANGE) != 0) {
            g_set_error(error, VVG_ERROR, 1, "%s: %s", dir, g_strerror(errno));
            ok = FALSE;
        }
    } else if (ok && rename(stage, dir) != 0) {
        g_set_error(error, VVG_ERROR, 1, "%s: %s", dir, g_strerror(errno));
        ok = FALSE;
    }
    vvg_document_remove_folder(stage); /* the old autosave, or what failed */
    if (!ok)
        g_ptr_array_set_size(job->done, 0);
    return ok;
}

const char *
vvg_autosave_job_folder(const vvg_autosave_job *job) {
    return job->dir;
}

void
vvg_document_autosave_end(VvgDocument *doc, vvg_autosave_job *job, gboolean ok) {
    if (!ok)
        return;
    g_ptr_array_unref(doc->autosaved);
    doc->autosaved = job->done;
    job->done = g_ptr_array_new_with_free_func(autosaved_volume_free);
}

void
vvg_autosave_job_free(vvg_autosave_job *job) {
    if (!job)
        return;
    vv_world_free(job->world);
    g_free(job->dir);
    g_ptr_array_unref(job->prev);
    g_ptr_array_unref(job->done);
    g_free(job);
}

gboolean
vvg_document_autosave(VvgDocument *doc, const char *dir, GError **error) {
    vvg_autosave_job *job = vvg_document_autosave_begin(doc, dir, error);
    if (!job)
        return FALSE;
    gboolean ok = vvg_autosave_job_run(job, error);
    vvg_document_autosave_end(doc, job, ok);
    vvg_autosave_job_free(job);
    return ok;
}

gboolean
vvg_document_restore(VvgDocument *doc, const char *dir, GError **error) {
    g_autofree char *scene = g_build_filename(dir, "session.json", NULL);
    g_autofree char *was_path = g_strdup(doc->path);
    const gboolean was_untracked = doc->dirty_untracked;
    const int was_clean = vvg_undo_clean_index(doc->undo);
    if (!open_input(doc, scene, error))
        return FALSE;
    /* the autosave's own volumes are volumes of the session again: saving
     * writes them (the folder goes away once the new autosave stands), so
     * one opened out of core (larger than a quarter of the budget) is read
     * whole, as the session that wrote it held it */
    g_autofree char *prefix = g_canonicalize_filename(dir, NULL);
    for (int i = 0; i < doc->world->n_objects; i++) {
        vv_object *o = doc->world->objects[i];
        if (!o->geometry.source || !g_str_has_prefix(o->geometry.source, prefix) ||
            o->geometry.source[strlen(prefix)] != '/')
            continue;
        if (vvg_object_source(o)) {
            vv_volume *v = NULL;
            vv_error_clear();
            vv_status s = vv_volume_load(&v, o->geometry.source, NULL);
            if (s == VV_OK)
                s = vv_object_set_volume(o, v);
            vv_volume_free(v);
            if (s != VV_OK) { /* the session as it was before */
                set_error(error, "cannot read the autosaved volume");
                vvg_document_undo(doc);
                g_free(doc->path);
                doc->path = g_steal_pointer(&was_path);
                doc->dirty_untracked = was_untracked;
                vvg_undo_set_clean_index(doc->undo, was_clean);
                return FALSE;
            }
        }
        free(o->geometry.source);
        o->geometry.source = NULL;
    }
    g_free(doc->path);
    doc->path = NULL;
    doc->dirty_untracked = TRUE; /* a restored session is unsaved, whatever is undone */
    g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
    return TRUE;
}

void
vvg_document_add_object(VvgDocument *doc, vv_object *obj, const char *source) {
    vvg_document_begin_edit(doc, "add object");
    if (source && obj->type == VV_OBJECT_VOLUME)
        remember_source(obj, source);
    if (vv_world_add_object(doc->world, obj) != VV_OK) {
        g_warning("volvis-gui: %s", vv_error_message());
        return;
    }
    doc->selected = doc->world->n_objects - 1;
    world_replaced(doc);
}

void
vvg_document_delete_object(VvgDocument *doc, int index) {
    if (index < 0 || index >= doc->world->n_objects)
        return;
    vvg_document_begin_edit(doc, "delete object");
    vv_object *o = NULL;
    if (vv_world_take_object(doc->world, index, &o) == VV_OK)
        vv_object_free(o);
    if (doc->selected >= doc->world->n_objects)
        doc->selected = doc->world->n_objects - 1;
    world_replaced(doc);
}

int
vvg_document_selected(VvgDocument *doc) {
    return doc->selected;
}

vv_object *
vvg_document_selected_object(VvgDocument *doc) {
    if (doc->selected < 0 || doc->selected >= doc->world->n_objects)
        return NULL;
    return doc->world->objects[doc->selected];
}

void
vvg_document_select(VvgDocument *doc, int index) {
    if (index < -1 || index >= doc->world->n_objects)
        index = -1;
    doc->selected = index;
    g_signal_emit(doc, signals[SIGNAL_SELECTION_CHANGED], 0);
}

void
vvg_document_show_transient(VvgDocument *doc, vv_world *world) {
    if (!world)
        return;
    if (doc->kept)
        vv_world_free(doc->world);
    else
        doc->kept = doc->world;
    doc->world = world;
    clamp_selection(doc);
    g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
}

void
vvg_document_end_transient(VvgDocument *doc, gboolean restore) {
    if (!doc->kept)
        return;
    if (!restore) {
        keep_transient(doc);
        return;
    }
    restore_kept(doc);
    g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
}

gboolean
vvg_document_transient(VvgDocument *doc) {
    return doc->kept != NULL;
}
