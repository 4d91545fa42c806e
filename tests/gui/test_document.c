/* VvgDocument's transient Worlds (the Animator's Play), without a display:
 * no undo steps and nothing unsaved; ending one puts back the very World
 * kept aside; an edit keeps the World shown; undo restores first; saving
 * writes the kept World. Autosave and restore. */
#include "testutil.h"
#include "vvg-document.h"

#include <sys/stat.h>
#include <unistd.h>

static int changed;

static void
on_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    (void)user;
    changed++;
}

/* A document with one sphere at x = 0 (one undo step: adding it). */
static VvgDocument *
doc_with_sphere(void) {
    VvgDocument *doc = vvg_document_new();
    vv_object *o = NULL;
    vt_ok(vv_object_new_geometry(&o, VV_OBJECT_SPHERE, "s"));
    vvg_document_add_object(doc, o, NULL);
    g_signal_connect(doc, "changed", G_CALLBACK(on_changed), NULL);
    changed = 0;
    return doc;
}

/* A frame of an animation: the World with the eye and the sphere moved. */
static vv_world *
frame(VvgDocument *doc, double x) {
    vv_world *w = vvg_document_snapshot(doc);
    assert_non_null(w);
    w->view.eye.x = x;
    w->objects[0]->position.x = x;
    return w;
}

static void
test_restore(void **state) {
    (void)state;
    VvgDocument *doc = doc_with_sphere();
    vv_world *kept = vvg_document_world(doc);
    vv_vec3 eye = kept->view.eye;
    vv_world *f1 = frame(doc, 11);
    vvg_document_show_transient(doc, f1);
    assert_ptr_equal(vvg_document_world(doc), f1);
    assert_true(vvg_document_transient(doc));
    vv_world *f2 = frame(doc, 22);
    vvg_document_show_transient(doc, f2); /* frees f1 */
    assert_ptr_equal(vvg_document_world(doc), f2);
    assert_int_equal(changed, 2);
    vvg_document_end_transient(doc, TRUE);
    /* the very World kept aside, unchanged */
    assert_ptr_equal(vvg_document_world(doc), kept);
    assert_false(vvg_document_transient(doc));
    assert_near(kept->view.eye.x, eye.x, 0);
    assert_near(kept->objects[0]->position.x, 0, 0);
    assert_int_equal(changed, 3);
    vvg_document_end_transient(doc, TRUE); /* nothing shown: nothing happens */
    assert_int_equal(changed, 3);
    /* no undo step was added: one undo empties the World */
    assert_true(vvg_document_undo(doc));
    assert_int_equal(vvg_document_world(doc)->n_objects, 0);
    assert_false(vvg_document_can_undo(doc));
    g_object_unref(doc);
}

static void
test_edit_keeps_the_frame(void **state) {
    (void)state;
    VvgDocument *doc = doc_with_sphere();
    vv_world *f = frame(doc, 7);
    vvg_document_show_transient(doc, f);
    /* an edit during Play: the World shown is the one it changes */
    vvg_document_begin_edit(doc, "move");
    assert_false(vvg_document_transient(doc));
    assert_ptr_equal(vvg_document_world(doc), f);
    f->objects[0]->position.x = 8;
    vvg_document_changed(doc);
    vvg_document_end_transient(doc, TRUE); /* too late: nothing to restore */
    assert_ptr_equal(vvg_document_world(doc), f);
    /* undo goes back to the frame that was shown, then to before it */
    assert_true(vvg_document_undo(doc));
    assert_near(vvg_document_world(doc)->objects[0]->position.x, 7, 0);
    assert_true(vvg_document_undo(doc));
    assert_int_equal(vvg_document_world(doc)->n_objects, 0);
    g_object_unref(doc);
}

static void
test_undo_restores_first(void **state) {
    (void)state;
    VvgDocument *doc = doc_with_sphere();
    vvg_document_begin_edit(doc, "move");
    vvg_document_world(doc)->objects[0]->position.x = 1;
    vvg_document_changed(doc);
    vvg_document_show_transient(doc, frame(doc, 5));
    /* undo is of the kept World's last edit: x 1 -> 0 */
    assert_true(vvg_document_undo(doc));
    assert_false(vvg_document_transient(doc));
    assert_near(vvg_document_world(doc)->objects[0]->position.x, 0, 0);
    assert_near(vvg_document_world(doc)->view.eye.x, 0, 0);
    /* redo brings x = 1 back, not the frame */
    assert_true(vvg_document_redo(doc));
    assert_near(vvg_document_world(doc)->objects[0]->position.x, 1, 0);
    g_object_unref(doc);
}

static void
test_save_writes_the_kept_world(void **state) {
    (void)state;
    VvgDocument *doc = doc_with_sphere();
    const char *path = vt_path(vt_outdir("gui_document"), "transient.json");
    double eye_x = vvg_document_world(doc)->view.eye.x;
    vv_world *f = frame(doc, 99);
    vvg_document_show_transient(doc, f);
    GError *err = NULL;
    assert_true(vvg_document_save(doc, path, &err));
    assert_false(vvg_document_dirty(doc));
    assert_ptr_equal(vvg_document_world(doc), f); /* still shown */
    vv_world *saved = NULL;
    vt_ok(vv_scene_load(&saved, path));
    assert_near(saved->view.eye.x, eye_x, 1e-9);
    assert_near(saved->objects[0]->position.x, 0, 1e-9);
    vv_world_free(saved);
    /* showing frames leaves the session saved */
    vvg_document_end_transient(doc, TRUE);
    assert_false(vvg_document_dirty(doc));
    g_object_unref(doc);
}

/* Issue 66: open the CT head, move the view, undo: the document is the
 * opened one again and not "changed" (Ctrl+Q does not ask); a save marks
 * the saved state, and undo and redo back to it are clean too. */
static void
test_undo_to_clean(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    VvgDocument *doc = vvg_document_new();
    GError *err = NULL;
    assert_true(vvg_document_open(doc, vt_data("volumes/ct_head.nrrd"), &err));
    assert_false(vvg_document_dirty(doc));
    vvg_document_begin_edit_merging(doc, "rotate the view");
    vvg_document_world(doc)->view.eye.x += 10;
    vvg_document_begin_edit_merging(doc, "rotate the view"); /* merged into one step */
    vvg_document_world(doc)->view.eye.x += 10;
    assert_true(vvg_document_dirty(doc));
    assert_true(vvg_document_undo(doc));
    assert_false(vvg_document_dirty(doc));
    assert_true(vvg_document_redo(doc));
    assert_true(vvg_document_dirty(doc));
    const char *path = vt_path(vt_outdir("gui_document"), "clean.json");
    assert_true(vvg_document_save(doc, path, &err));
    assert_false(vvg_document_dirty(doc));
    /* a drag right after the save is a step of its own, not merged into the saved one */
    vvg_document_begin_edit_merging(doc, "rotate the view");
    vvg_document_world(doc)->view.eye.x += 5;
    assert_true(vvg_document_dirty(doc));
    assert_true(vvg_document_undo(doc));
    assert_false(vvg_document_dirty(doc));
    assert_true(vvg_document_undo(doc)); /* before the drag that was saved */
    assert_true(vvg_document_dirty(doc));
    assert_true(vvg_document_redo(doc));
    assert_false(vvg_document_dirty(doc));
    g_object_unref(doc);
}

static ino_t
inode_of(const char *path) {
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    return st.st_ino;
}

static gpointer
autosave_job_thread(gpointer job) {
    return GINT_TO_POINTER(vvg_autosave_job_run(job, NULL));
}

/* Autosave (issue 33) of a volume made in the session: session.json and
 * volume_1.nrrd in the folder; a second autosave links the unchanged volume
 * (the same inode) and leaves no stage; a changed volume is written anew;
 * the document's path and unsaved flag are untouched. Restoring gives an
 * untitled, unsaved document whose volume has no source (it is the
 * session's again) and the same voxels. A folder that cannot be made is an
 * error and the previous autosave stays. */
static void
test_autosave_and_restore(void **state) {
    (void)state;
    VvgDocument *doc = doc_with_sphere();
    int dims[3] = {20, 16, 12};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U16));
    for (int i = 0; i < 20 * 16 * 12; i++)
        ((uint16_t *)v->data)[i] = (uint16_t)(i * 7);
    vv_volume_update_range(v);
    GError *err = NULL;
    assert_true(vvg_document_add_volume(doc, v, "made", NULL, &err));
    char dir[512];
    snprintf(dir, sizeof dir, "%s/autosave", vt_outdir("gui_document"));
    vvg_document_remove_folder(dir);
    assert_true(vvg_document_autosave(doc, dir, &err));
    assert_true(vvg_document_dirty(doc));
    assert_null(vvg_document_path(doc));
    char vol[700], stage[600];
    snprintf(vol, sizeof vol, "%s/volume_1.nrrd", dir);
    snprintf(stage, sizeof stage, "%s.tmp", dir);
    ino_t first = inode_of(vol);
    assert_true(vvg_document_autosave(doc, dir, &err));
    assert_int_equal(inode_of(vol), first);
    assert_int_not_equal(access(stage, F_OK), 0);
    vv_object *o = vvg_document_world(doc)->objects[1];
    o->volume->modified++;
    assert_true(vvg_document_autosave(doc, dir, &err));
    assert_int_not_equal(inode_of(vol), first);
    /* a folder that cannot be made: an error, the autosave as it was */
    char bad[600];
    snprintf(bad, sizeof bad, "%s/session.json/x", dir);
    assert_false(vvg_document_autosave(doc, bad, &err));
    assert_non_null(err);
    g_clear_error(&err);
    assert_int_equal(access(vol, F_OK), 0);

    /* in three steps (the GUI runs the middle one on a worker thread): the
     * snapshot is what gets written, whatever the document does meanwhile */
    vvg_autosave_job *job = vvg_document_autosave_begin(doc, dir, &err);
    assert_non_null(job);
    vvg_document_delete_object(doc, 1);
    assert_int_equal(vvg_document_world(doc)->n_objects, 1);
    GThread *worker = g_thread_new("autosave", autosave_job_thread, job);
    assert_true(GPOINTER_TO_INT(g_thread_join(worker)));
    vvg_document_autosave_end(doc, job, TRUE);
    vvg_autosave_job_free(job);
    assert_int_equal(access(vol, F_OK), 0);
    vvg_document_undo(doc); /* the volume back, for what follows */
    assert_int_equal(vvg_document_world(doc)->n_objects, 2);

    VvgDocument *back = vvg_document_new();
    assert_true(vvg_document_restore(back, dir, &err));
    assert_null(vvg_document_path(back));
    assert_true(vvg_document_dirty(back));
    vv_world *w = vvg_document_world(back);
    assert_int_equal(w->n_objects, 2);
    assert_null(w->objects[1]->geometry.source);
    assert_memory_equal(w->objects[1]->volume->data, v->data, (size_t)20 * 16 * 12 * 2);
    /* its own autosave writes the volume again: the old folder can go */
    char dir2[600];
    snprintf(dir2, sizeof dir2, "%s2", dir);
    vvg_document_remove_folder(dir2);
    assert_true(vvg_document_autosave(back, dir2, &err));
    vvg_document_remove_folder(dir);
    snprintf(vol, sizeof vol, "%s/volume_1.nrrd", dir2);
    assert_int_equal(access(vol, F_OK), 0);
    vvg_document_remove_folder(dir2);
    g_object_unref(back);
    vv_volume_free(v);
    g_object_unref(doc);
}

/* Saving is all or nothing: a scene that cannot be written (its name is a
 * folder) leaves no volume file of that save behind, and the volume stays
 * the session's (no source); then a good save writes both, the volume
 * named relative to the scene; a second save under the same name keeps
 * the first save's file (a new name for the new one). */
static void
test_save_all_or_nothing(void **state) {
    (void)state;
    VvgDocument *doc = doc_with_sphere();
    int dims[3] = {8, 8, 8};
    vv_volume *v = NULL;
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    GError *err = NULL;
    assert_true(vvg_document_add_volume(doc, v, "made", NULL, &err));
    char dir[512];
    snprintf(dir, sizeof dir, "%s/all_or_nothing", vt_outdir("gui_document"));
    vvg_document_remove_folder(dir);
    g_mkdir_with_parents(dir, 0755);
    char scene[600];
    snprintf(scene, sizeof scene, "%s/s.json", dir);
    g_mkdir_with_parents(scene, 0755); /* a folder where the scene goes */
    assert_false(vvg_document_save(doc, scene, &err));
    g_clear_error(&err);
    GDir *d = g_dir_open(dir, 0, NULL);
    const char *name;
    int n = 0;
    while ((name = g_dir_read_name(d)))
        n++;
    g_dir_close(d);
    assert_int_equal(n, 1); /* the folder named s.json only */
    assert_null(vvg_document_world(doc)->objects[1]->geometry.source);
    assert_true(vvg_document_dirty(doc));
    rmdir(scene);
    assert_true(vvg_document_save(doc, scene, &err));
    char vol[700];
    snprintf(vol, sizeof vol, "%s/s_1_made.nrrd", dir);
    assert_int_equal(access(vol, F_OK), 0);
    vv_world *back = NULL;
    vt_ok(vv_scene_load(&back, scene));
    assert_int_equal(back->n_objects, 2);
    vv_world_free(back);
    gchar *text = NULL;
    assert_true(g_file_get_contents(scene, &text, NULL, NULL));
    assert_non_null(strstr(text, "\"s_1_made.nrrd\""));
    g_free(text);
    /* the volume is now the file's: a new volume object saved again under the
     * same scene name gets a name of its own */
    vv_volume_free(v);
    vt_ok(vv_volume_new(&v, dims, VV_U8));
    vvg_document_delete_object(doc, 1);
    assert_true(vvg_document_add_volume(doc, v, "made", NULL, &err));
    assert_true(vvg_document_save(doc, scene, &err));
    snprintf(vol, sizeof vol, "%s/s_1_made-2.nrrd", dir);
    assert_int_equal(access(vol, F_OK), 0);
    vvg_document_remove_folder(dir);
    vv_volume_free(v);
    g_object_unref(doc);
}

/* A NIfTI-1 file of X x Y x Z voxels (u8), T time steps and C channels
 * (dim[4], dim[5]), written here byte by byte: voxel (i, j, k) of step t,
 * channel c is value(i, t, c). */
#define NX 6
#define NY 5
#define NZ 4
static int
value(int i, int t, int c) {
    return 10 * t + 100 * c + i;
}

static void
write_nifti(const char *path, int T, int C) {
    size_t n = (size_t)NX * NY * NZ * T * C;
    unsigned char *buf = calloc(352 + n, 1);
    assert_non_null(buf);
    int32_t i32 = 348;
    memcpy(buf, &i32, 4);
    int16_t dim[8] = {C > 1 ? 5 : 4, NX, NY, NZ, (int16_t)T, (int16_t)C, 1, 1};
    memcpy(buf + 40, dim, sizeof dim);
    int16_t datatype = 2, bitpix = 8; /* DT_UINT8 */
    memcpy(buf + 70, &datatype, 2);
    memcpy(buf + 72, &bitpix, 2);
    float pixdim[8] = {1, 1, 1, 1, 0.5f, 1, 1, 1};
    memcpy(buf + 76, pixdim, sizeof pixdim);
    float vox_offset = 352;
    memcpy(buf + 108, &vox_offset, 4);
    memcpy(buf + 344, "n+1", 4);
    unsigned char *d = buf + 352;
    for (int c = 0; c < C; c++)
        for (int t = 0; t < T; t++)
            for (int k = 0; k < NZ; k++)
                for (int j = 0; j < NY; j++)
                    for (int i = 0; i < NX; i++)
                        *d++ = (unsigned char)value(i, t, c);
    vt_write_file(path, buf, 352 + n);
    free(buf);
}

/* Every voxel of @p v is value(i, t, c). */
static void
assert_step(const vv_volume *v, int t, int c) {
    for (int k = 0; k < NZ; k++)
        for (int j = 0; j < NY; j++)
            for (int i = 0; i < NX; i++)
                assert_int_equal((int)vv_volume_get(v, i, j, k), value(i, t, c));
}

static void
time_failed(VvgDocument *doc, const char *message, gpointer user) {
    (void)doc;
    snprintf(user, 256, "%s", message);
}

/* A 4-D NIfTI of two channels opens as one object of two channels with its
 * time steps known; vvg_document_set_time puts step 2 of both channels in,
 * steps shown within a second make one undo step, which undo takes back;
 * vvg_document_request_time reads off the main thread and shows the last
 * step asked;
 * vvg_world_apply_time puts a frame's step into a World evaluated from the
 * document's (an Animator's objects[i].time track) and names what it
 * cannot read. */
/* What main() does at start-up: the process's one cache set to
 * VOLVIS_MEMORY_LIMIT before any file opens. */
static void
set_memory_limit(const char *limit) {
    g_setenv("VOLVIS_MEMORY_LIMIT", limit, TRUE);
    vv_cache_set_limit(vv_cache_process(), vvg_document_memory_limit());
}

/* A multiresolution file larger than a quarter of VOLVIS_MEMORY_LIMIT opens
 * out of core: the object shows the proxy (the coarsest level over level
 * 0's box) and owns the file's source, a pyramid in the process's cache; a
 * larger limit's quarter holds an OME-Zarr store whole (a .vvb opens out
 * of core at any size: its format is made for it); a session saves level
 * 0's geometry, and opened again shows the proxy over the same box with
 * level 0 unread; a file deleted and opened again gets a source of its own
 * in the same cache. The same for an OME-Zarr store and a .vvb with
 * pyramid levels. */
static void
pyramid_out_of_core(const char *dir, const char *store, const vv_volume *v, int always) {
    GError *err = NULL;
    /* 64 MiB: level 0 (13.5 MiB) fits a quarter: read whole (not a .vvb) */
    set_memory_limit("64M");
    assert_int_equal(vv_cache_limit(vv_cache_process()), 64u << 20);
    VvgDocument *doc = vvg_document_new();
    assert_true(vvg_document_open(doc, store, &err));
    vv_object *o = vvg_document_selected_object(doc);
    assert_non_null(o);
    if (always) {
        assert_non_null(vvg_object_source(o));
        assert_int_equal(o->volume->dims[0], 64);
    } else {
        assert_null(vvg_object_source(o));
        assert_null(o->source);
        assert_int_equal(o->volume->dims[0], 256);
    }
    g_object_unref(doc);
    /* 16 MiB: out of core */
    set_memory_limit("16M");
    doc = vvg_document_new();
    assert_true(vvg_document_open(doc, store, &err));
    o = vvg_document_selected_object(doc);
    vv_source *src = vvg_object_source(o);
    assert_non_null(src);
    assert_ptr_equal(src, o->source);
    assert_int_equal(vv_source_get_kind(src), VV_SOURCE_PYRAMID);
    assert_int_equal(vv_source_levels(src), 3);
    assert_ptr_equal(vv_source_cache(src), vv_cache_process()); /* the one cache */
    assert_int_equal(vv_cache_limit(vv_source_cache(src)), 16u << 20);
    assert_int_equal(o->volume->dims[0], 64); /* the coarsest level */
    assert_int_equal(vv_source_level(src, 0)->dims[0], 256);
    const vv_box b = vv_object_world_box(o);
    assert_near(b.max.x - b.min.x, 255 * v->spacing[0], 1e-6);
    /* a session names the store with level 0's spacing (the library's
     * scene writer: no geometry patched by the GUI) */
    const char *scene = vt_path(dir, "pyramid_session.json");
    assert_true(vvg_document_save(doc, scene, &err));
    assert_ptr_equal(vvg_object_source(vvg_document_selected_object(doc)), src);
    vv_world *w = NULL;
    vt_ok(vv_scene_load(&w, scene));
    assert_int_equal(w->objects[0]->volume->dims[0], 256);
    assert_near(w->objects[0]->volume->spacing[0], v->spacing[0], 1e-9);
    vv_world_free(w);
    /* the session opened again: the store out of core again, never read
     * whole, over the same world box */
    VvgDocument *again = vvg_document_new();
    assert_true(vvg_document_open(again, scene, &err));
    vv_object *o2 = vvg_document_selected_object(again);
    assert_non_null(o2);
    vv_source *src2 = vvg_object_source(o2);
    assert_non_null(src2);
    assert_ptr_equal(vv_source_cache(src2), vv_cache_process());
    assert_int_equal(o2->volume->dims[0], 64);
    const vv_box b2 = vv_object_world_box(o2);
    assert_near(b2.max.x - b2.min.x, b.max.x - b.min.x, 1e-6);
    assert_near(b2.max.z - b2.min.z, b.max.z - b.min.z, 1e-6);
    vv_source_stats ps;
    vv_source_stats_get(src2, &ps);
    assert_int_equal(ps.chunk_reads[0], 0); /* level 0 unread */
    g_object_unref(again);
    /* deleted, then opened again: a source of its own, in the same cache */
    vvg_document_delete_object(doc, 0);
    assert_true(vvg_document_open(doc, store, &err));
    o = vvg_document_selected_object(doc);
    assert_non_null(vvg_object_source(o));
    assert_ptr_not_equal(vvg_object_source(o), src);
    assert_ptr_equal(vv_source_cache(vvg_object_source(o)), vv_cache_process());
    /* a filter's result replaces the proxy and drops the source: in memory */
    vv_volume *proxy = vv_volume_ref(o->volume);
    vvg_document_begin_edit(doc, "filter");
    o = vvg_document_selected_object(doc);
    vt_ok(vv_object_set_volume(o, proxy));
    assert_null(vvg_object_source(o));
    assert_true(vvg_document_undo(doc)); /* and undo gives the file back */
    assert_non_null(vvg_object_source(vvg_document_selected_object(doc)));
    vv_volume_free(proxy);
    g_object_unref(doc);
    set_memory_limit("1G");
    g_unsetenv("VOLVIS_MEMORY_LIMIT");
}

/* Two files out of core share the process's one cache under the one
 * memory limit: every voxel of level 0 of both (13.5 MiB each, 27 MiB
 * together) read box by box (the Measurement page's histograms) through a
 * 16 MiB budget, the cache never holds more than the limit, it evicts to
 * stay within it, and both histograms count every voxel. */
static void
two_files_share_the_cache(const char *store, const char *vvb, const vv_volume *v) {
    GError *err = NULL;
    set_memory_limit("16M");
    vv_cache_stats before;
    vv_cache_stats_get(vv_cache_process(), &before);
    VvgDocument *doc = vvg_document_new();
    assert_true(vvg_document_open(doc, store, &err));
    assert_true(vvg_document_open(doc, vvb, &err));
    vv_world *w = vvg_document_world(doc);
    assert_int_equal(w->n_objects, 2);
    vv_source *a = vvg_object_source(w->objects[0]), *b = vvg_object_source(w->objects[1]);
    assert_non_null(a);
    assert_non_null(b);
    assert_ptr_not_equal(a, b);
    assert_ptr_equal(vv_source_cache(a), vv_cache_process());
    assert_ptr_equal(vv_source_cache(b), vv_cache_process());
    const uint64_t limit = 16u << 20;
    vv_source *both[2] = {a, b};
    for (int r = 0; r < 2; r++)
        for (int i = 0; i < 2; i++) {
            vv_histogram *h = NULL;
            vt_ok(vv_measure_histogram_boxes(&h, vv_source_level(both[i], 0), vv_source_box,
                                             both[i], 64, 0, 0, NULL));
            assert_int_equal(h->total, (uint64_t)v->dims[0] * v->dims[1] * v->dims[2]);
            vv_histogram_free(h);
            vv_cache_stats cs;
            vv_cache_stats_get(vv_cache_process(), &cs);
            assert_int_equal(cs.limit, limit);
            assert_true(cs.held <= limit);
            assert_true(cs.held + cs.reserved <= limit);
            assert_true(cs.sources >= 2);
        }
    vv_cache_stats cs;
    vv_cache_stats_get(vv_cache_process(), &cs);
    assert_true(cs.evictions > before.evictions); /* 27 MiB through 16: one budget, shared */
    vv_source_stats sa, sb;
    vv_source_stats_get(a, &sa);
    vv_source_stats_get(b, &sb);
    assert_true(sa.chunk_reads[0] > 0 && sb.chunk_reads[0] > 0);
    assert_true(sa.held_bytes + sb.held_bytes <= limit);
    assert_int_equal(sa.limit_bytes, limit);
    assert_int_equal(sb.limit_bytes, limit);
    g_object_unref(doc);
    set_memory_limit("1G");
    g_unsetenv("VOLVIS_MEMORY_LIMIT");
}

static void
test_pyramid_out_of_core(void **state) {
    (void)state;
    if (!vt_have_data("volumes/ct_head.nrrd"))
        vt_skip("../shared/data/volumes/ct_head.nrrd is missing");
    const char *dir = vt_outdir("gui_document");
    const char *store = vt_path(dir, "head.ome.zarr");
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, vt_data("volumes/ct_head.nrrd"), NULL));
    vt_ok(vt_save(v, store, VV_FORMAT_OME_ZARR, -1, 0));
    pyramid_out_of_core(dir, store, v, 0);
    const char *vvb = vt_path(dir, "head.vvb");
    vt_ok(vt_save(v, vvb, VV_FORMAT_VVB, -1, VV_VVB_ZSTD | VV_VVB_LEVELS));
    pyramid_out_of_core(dir, vvb, v, 1);
    two_files_share_the_cache(store, vvb, v);
    vv_volume_free(v);
}

static void
test_channels_and_time(void **state) {
    (void)state;
    const char *path = vt_path(vt_outdir("gui_document"), "cells.nii");
    write_nifti(path, 4, 2);
    VvgDocument *doc = vvg_document_new();
    GError *err = NULL;
    assert_true(vvg_document_open(doc, path, &err));
    vv_object *o = vvg_document_selected_object(doc);
    assert_non_null(o);
    assert_int_equal(o->n_channels, 2);
    assert_int_equal(vvg_document_time_steps(doc, o), 4);
    assert_int_equal(vvg_document_edited_channel(doc), 0);
    vvg_document_set_edited_channel(doc, 1);
    assert_int_equal(vvg_document_edited_channel(doc), 1);
    assert_step(o->channels[1].volume, 0, 1);
    assert_true(vvg_document_set_time(doc, 1, &err));
    assert_true(vvg_document_set_time(doc, 2, &err));
    o = vvg_document_selected_object(doc);
    assert_int_equal(o->time, 2);
    assert_step(o->channels[0].volume, 2, 0);
    assert_step(o->channels[1].volume, 2, 1);
    assert_true(o->volume == o->channels[0].volume);
    assert_false(vvg_document_set_time(doc, 4, &err));
    assert_non_null(strstr(err->message, "no time step 4 (4 steps)"));
    g_clear_error(&err);
    assert_true(vvg_document_undo(doc)); /* both steps at once: back to step 0 */
    o = vvg_document_selected_object(doc);
    assert_int_equal(o->time, 0);
    assert_step(o->channels[1].volume, 0, 1);

    /* asked without blocking: asks while a read is in flight replace the
     * step to show next, and the last one asked ends shown; a step out of
     * range is heard of, the World unchanged */
    char heard[256] = "";
    vvg_document_request_time(doc, 1, time_failed, heard);
    vvg_document_request_time(doc, 3, time_failed, heard);
    vvg_document_request_time(doc, 2, time_failed, heard);
    while (vvg_document_time_pending(doc))
        g_main_context_iteration(NULL, TRUE);
    o = vvg_document_selected_object(doc);
    assert_int_equal(o->time, 2);
    assert_step(o->channels[0].volume, 2, 0);
    assert_step(o->channels[1].volume, 2, 1);
    assert_string_equal(heard, "");
    vvg_document_request_time(doc, 9, time_failed, heard);
    assert_false(vvg_document_time_pending(doc));
    assert_non_null(strstr(heard, "no time step 9"));
    assert_int_equal(vvg_document_selected_object(doc)->time, 2);
    assert_true(vvg_document_undo(doc)); /* back to step 0 */
    assert_int_equal(vvg_document_selected_object(doc)->time, 0);

    /* an Animator frame: the object at step 3, the base World's at step 0 */
    GHashTable *cache = vvg_time_cache_new();
    vv_world *base = vvg_document_snapshot(doc), *w = vvg_document_snapshot(doc);
    w->objects[0]->time = 3;
    assert_true(vvg_world_apply_time(cache, w, base, &err));
    assert_step(w->objects[0]->channels[0].volume, 3, 0);
    assert_step(w->objects[0]->channels[1].volume, 3, 1);
    assert_step(base->objects[0]->channels[1].volume, 0, 1);
    w->objects[0]->time = 7;
    assert_false(vvg_world_apply_time(cache, w, base, &err));
    assert_non_null(strstr(err->message, "time step 7"));
    g_clear_error(&err);
    free(w->objects[0]->geometry.source);
    w->objects[0]->geometry.source = NULL;
    assert_false(vvg_world_apply_time(cache, w, base, &err));
    assert_non_null(strstr(err->message, "not read from a file"));
    g_clear_error(&err);
    vv_world_free(w);
    vv_world_free(base);
    g_hash_table_unref(cache);
    g_object_unref(doc);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_restore),
        cmocka_unit_test(test_edit_keeps_the_frame),
        cmocka_unit_test(test_undo_restores_first),
        cmocka_unit_test(test_save_writes_the_kept_world),
        cmocka_unit_test(test_undo_to_clean),
        cmocka_unit_test(test_autosave_and_restore),
        cmocka_unit_test(test_save_all_or_nothing),
        cmocka_unit_test(test_channels_and_time),
        cmocka_unit_test(test_pyramid_out_of_core),
    };
    return vt_run_tests(tests, NULL, NULL);
}
