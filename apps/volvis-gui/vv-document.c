/* VvDocument: the edited World, undo, sources and selection (vv-document.h). */
#include "vv-document.h"

#include <stdlib.h>
#include <string.h>

#include "volvis/filter.h"
#include "vvg-models.h"

struct _VvDocument {
    GObject parent;
    vv_world *world;
    vv_world *kept; /* the World while a transient one is shown, else NULL */
    vvg_undo *undo;
    char *path;
    gboolean dirty;
    int selected;
    vv_filter_cache *filtered; /* filtered volumes of scene objects, kept across reopenings */
};

G_DEFINE_TYPE(VvDocument, vv_document, G_TYPE_OBJECT)

enum { SIGNAL_CHANGED, SIGNAL_SELECTION_CHANGED, N_SIGNALS };
static guint signals[N_SIGNALS];

G_DEFINE_QUARK(vv - gui - error - quark, vv_gui_error)

static void
set_error(GError **error, const char *fallback) {
    const char *m = vv_error_message();
    g_set_error_literal(error, VV_GUI_ERROR, 1, m && *m ? m : fallback);
}

static void
vv_document_finalize(GObject *o) {
    VvDocument *doc = VV_DOCUMENT(o);
    vv_world_free(doc->world);
    vv_world_free(doc->kept);
    vvg_undo_free(doc->undo);
    vv_filter_cache_free(doc->filtered);
    g_free(doc->path);
    G_OBJECT_CLASS(vv_document_parent_class)->finalize(o);
}

static void
vv_document_class_init(VvDocumentClass *klass) {
    G_OBJECT_CLASS(klass)->finalize = vv_document_finalize;
    signals[SIGNAL_CHANGED] = g_signal_new("changed", G_TYPE_FROM_CLASS(klass), G_SIGNAL_RUN_LAST,
                                           0, NULL, NULL, NULL, G_TYPE_NONE, 0);
    signals[SIGNAL_SELECTION_CHANGED] =
        g_signal_new("selection-changed", G_TYPE_FROM_CLASS(klass), G_SIGNAL_RUN_LAST, 0, NULL,
                     NULL, NULL, G_TYPE_NONE, 0);
}

static void
vv_document_init(VvDocument *doc) {
    if (vv_world_new(&doc->world) != VV_OK || vvg_undo_new(&doc->undo, 200) != VV_OK ||
        vv_filter_cache_new(&doc->filtered, 8) != VV_OK)
        g_error("volvis-gui: out of memory");
    doc->selected = -1;
}

VvDocument *
vv_document_new(void) {
    return g_object_new(VV_TYPE_DOCUMENT, NULL);
}

vv_world *
vv_document_world(VvDocument *doc) {
    return doc->world;
}

vv_world *
vv_document_snapshot(VvDocument *doc) {
    vv_world *w = NULL;
    if (vv_world_clone(&w, doc->world) != VV_OK)
        return NULL;
    return w;
}

static void
clamp_selection(VvDocument *doc) {
    if (doc->selected >= doc->world->n_objects)
        doc->selected = doc->world->n_objects - 1;
    if (doc->selected < 0 && doc->world->n_objects > 0)
        doc->selected = 0;
}

/* Drops the World kept aside: the transient World shown becomes the World. */
static void
keep_transient(VvDocument *doc) {
    vv_world_free(doc->kept);
    doc->kept = NULL;
}

/* Puts the World kept aside back, without a signal. */
static void
restore_kept(VvDocument *doc) {
    if (!doc->kept)
        return;
    vv_world_free(doc->world);
    doc->world = doc->kept;
    doc->kept = NULL;
    clamp_selection(doc);
}

void
vv_document_begin_edit(VvDocument *doc, const char *label) {
    /* callers may hold pointers into the World shown: the edit changes it */
    keep_transient(doc);
    if (vvg_undo_push(doc->undo, doc->world, label) != VV_OK)
        g_warning("volvis-gui: no undo step for '%s': %s", label, vv_error_message());
    doc->dirty = TRUE;
}

void
vv_document_changed(VvDocument *doc) {
    g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
}

static void
world_replaced(VvDocument *doc) {
    clamp_selection(doc);
    g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
    g_signal_emit(doc, signals[SIGNAL_SELECTION_CHANGED], 0);
}

gboolean
vv_document_undo(VvDocument *doc) {
    gboolean restored = doc->kept != NULL;
    restore_kept(doc);
    if (vvg_undo_undo(doc->undo, &doc->world) != VV_OK) {
        if (restored)
            g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
        return FALSE;
    }
    doc->dirty = TRUE;
    world_replaced(doc);
    return TRUE;
}

gboolean
vv_document_redo(VvDocument *doc) {
    gboolean restored = doc->kept != NULL;
    restore_kept(doc);
    if (vvg_undo_redo(doc->undo, &doc->world) != VV_OK) {
        if (restored)
            g_signal_emit(doc, signals[SIGNAL_CHANGED], 0);
        return FALSE;
    }
    doc->dirty = TRUE;
    world_replaced(doc);
    return TRUE;
}

gboolean
vv_document_can_undo(VvDocument *doc) {
    return vvg_undo_can_undo(doc->undo);
}

gboolean
vv_document_can_redo(VvDocument *doc) {
    return vvg_undo_can_redo(doc->undo);
}

/* The file an object's volume came from, kept in geometry.source as scene
 * loading does, so saving refers to it. */
static void
remember_source(vv_object *o, const char *path) {
    if (!o || !path)
        return;
    free(o->geometry.source);
    /* malloc'ed: the library frees it with free() */
    char *abs = g_canonicalize_filename(path, NULL);
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

/* A scene replaces the World; its volumes' files are the scene's. */
static gboolean
open_scene(VvDocument *doc, const char *path, GError **error) {
    vv_world *w = NULL;
    vv_error_clear();
    if (vv_scene_load_cached(&w, path, NULL, doc->filtered) != VV_OK) {
        set_error(error, "cannot read the scene");
        return FALSE;
    }
    vv_document_begin_edit(doc, "open scene");
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
    world_replaced(doc);
    doc->dirty = FALSE;
    return TRUE;
}

/* The renderer that draws every object of @p w: a renderer the user chose
 * that draws them is kept, else the World's default (vv_world_renderer:
 * the first renderer whose capabilities cover every object), named in the
 * settings so the saved scene renders the same through the CLI. */
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
    g_strlcpy(w->render.renderer, vv_world_renderer(w), sizeof w->render.renderer);
}

gboolean
vv_document_mesh_is_y_up(const char *path) {
    /* the exporters' conventions: OBJ, PLY, glTF, COLLADA and FBX are
     * usually Y-up; STL, OFF and 3DS (CAD, printing) Z-up */
    static const char *const y_up[] = {".obj", ".ply", ".gltf", ".glb", ".dae", ".fbx", NULL};
    return has_suffix(path, y_up);
}

/* The object added beside others: the view frames the whole World (same
 * undo step), and the renderer is one that draws everything. */
static void
added_beside(VvDocument *doc) {
    vv_world *w = doc->world;
    choose_renderer(w);
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    vv_document_changed(doc);
}

static gboolean
open_mesh(VvDocument *doc, const char *path, GError **error) {
    vv_mesh *m = NULL;
    vv_object *o = NULL;
    if (vv_mesh_load(&m, path) != VV_OK) {
        set_error(error, "cannot read the mesh");
        return FALSE;
    }
    g_autofree char *base = g_path_get_basename(path);
    vv_status s = vv_object_new_geometry(&o, VV_OBJECT_MESH, base);
    g_autofree char *abs = g_canonicalize_filename(path, NULL);
    if (s == VV_OK)
        s = vv_object_set_mesh(o, m, abs);
    vv_mesh_free(m);
    if (s != VV_OK) {
        vv_object_free(o);
        set_error(error, "cannot use the mesh");
        return FALSE;
    }
    if (vv_document_mesh_is_y_up(path)) /* its Y turned to the World's Z (up) */
        o->orientation = vv_quat_from_axis_angle(vv_vec3_make(1, 0, 0), VV_PI / 2);
    gboolean fresh = doc->world->n_objects == 0 && !doc->dirty;
    if (doc->world->n_objects == 0 && doc->world->n_lights == 0) {
        vv_light l = {VV_LIGHT_DIRECTIONAL, 1, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1.0};
        vv_world_add_light(doc->world, &l);
    }
    vv_document_add_object(doc, o, NULL);
    added_beside(doc);
    doc->dirty = !fresh;
    return TRUE;
}

gboolean
vv_document_add_volume(VvDocument *doc, vv_volume *v, const char *name, const char *source,
                       GError **error) {
    vv_world *w = NULL;
    vv_error_clear();
    if (vv_world_new_for_volume(&w, v, NULL) != VV_OK) {
        set_error(error, "cannot show the volume");
        return FALSE;
    }
    /* the object as `volvis render FILE` shows it */
    vv_object *obj = NULL;
    vv_world_take_object(w, 0, &obj);
    g_strlcpy(obj->name, name, sizeof obj->name);
    if (source)
        remember_source(obj, source);
    if (doc->world->n_objects == 0) {
        gboolean fresh = !doc->dirty;
        vv_document_begin_edit(doc, "open volume");
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
        if (resized) /* framed for the window's shape */
            vv_view_frame_box(&w->view, vv_world_bounds(w));
        doc->selected = 0;
        doc->dirty = !fresh; /* a file just opened is not "unsaved" */
        world_replaced(doc);
        return TRUE;
    }
    vv_world_free(w);
    vv_document_add_object(doc, obj, NULL);
    added_beside(doc);
    return TRUE;
}

gboolean
vv_document_open(VvDocument *doc, const char *path, GError **error) {
    static const char *const scene_suffixes[] = {".json", NULL};
    if (has_suffix(path, scene_suffixes))
        return open_scene(doc, path, error);
    vv_error_clear();
    if (has_suffix(path, mesh_suffixes))
        return open_mesh(doc, path, error);
    vv_volume *v = NULL;
    if (vv_volume_load(&v, path, NULL) != VV_OK) {
        set_error(error, "cannot read the volume");
        return FALSE;
    }
    g_autofree char *base = g_path_get_basename(path);
    char *dot = strchr(base, '.');
    if (dot && dot != base)
        *dot = '\0';
    gboolean ok = vv_document_add_volume(doc, v, base, path, error);
    vv_volume_free(v);
    return ok;
}

void
vv_document_set_view_size(VvDocument *doc, int width, int height) {
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
vv_document_path(VvDocument *doc) {
    return doc->path;
}

gboolean
vv_document_dirty(VvDocument *doc) {
    return doc->dirty;
}

gboolean
vv_document_save(VvDocument *doc, const char *path, GError **error) {
    vv_world *w = doc->kept ? doc->kept : doc->world; /* never a transient World */
    g_autofree char *dir = g_path_get_dirname(path);
    g_autofree char *stem = g_path_get_basename(path);
    char *dot = strrchr(stem, '.');
    if (dot && dot != stem)
        *dot = '\0';
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->type != VV_OBJECT_VOLUME || !o->volume || o->geometry.source)
            continue; /* vv_scene_save refers to the file it came from */
        /* made in this session: written beside the scene */
        g_autofree char *name = g_strdup_printf("%s_%d_%s.nrrd", stem, i, o->name);
        for (char *c = name; *c; c++)
            if (!g_ascii_isalnum(*c) && *c != '.' && *c != '_' && *c != '-')
                *c = '_';
        g_autofree char *full = g_build_filename(dir, name, NULL);
        vv_error_clear();
        if (vv_volume_save(o->volume, full, VV_FORMAT_NRRD, 0) != VV_OK) {
            set_error(error, "cannot write a volume");
            return FALSE;
        }
        remember_source(o, full);
    }
    vv_error_clear();
    if (vv_scene_save(w, path, NULL) != VV_OK) {
        set_error(error, "cannot write the scene");
        return FALSE;
    }
    /* @p path may be doc->path itself (Save): canonicalize before freeing */
    char *saved = g_canonicalize_filename(path, NULL);
    g_free(doc->path);
    doc->path = saved;
    doc->dirty = FALSE;
    return TRUE;
}

void
vv_document_add_object(VvDocument *doc, vv_object *obj, const char *source) {
    vv_document_begin_edit(doc, "add object");
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
vv_document_delete_object(VvDocument *doc, int index) {
    if (index < 0 || index >= doc->world->n_objects)
        return;
    vv_document_begin_edit(doc, "delete object");
    vv_object *o = NULL;
    if (vv_world_take_object(doc->world, index, &o) == VV_OK)
        vv_object_free(o);
    if (doc->selected >= doc->world->n_objects)
        doc->selected = doc->world->n_objects - 1;
    world_replaced(doc);
}

int
vv_document_selected(VvDocument *doc) {
    return doc->selected;
}

vv_object *
vv_document_selected_object(VvDocument *doc) {
    if (doc->selected < 0 || doc->selected >= doc->world->n_objects)
        return NULL;
    return doc->world->objects[doc->selected];
}

void
vv_document_select(VvDocument *doc, int index) {
    if (index < -1 || index >= doc->world->n_objects)
        index = -1;
    doc->selected = index;
    g_signal_emit(doc, signals[SIGNAL_SELECTION_CHANGED], 0);
}

void
vv_document_show_transient(VvDocument *doc, vv_world *world) {
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
vv_document_end_transient(VvDocument *doc, gboolean restore) {
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
vv_document_transient(VvDocument *doc) {
    return doc->kept != NULL;
}
