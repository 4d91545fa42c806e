/* VvgWindow: the main window, its layout and its actions (vvg-window.h). */
#include "vvg-window.h"
#include "vvg-widgets.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include <glib/gstdio.h>

#include "volvis/io.h"
#include "volvis/sys/format.h"
#include "vvg-animator-page.h"
#include "vvg-channel-panel.h"
#include "vvg-cut-panel.h"
#include "vvg-devices-page.h"
#include "vvg-dicom-dialog.h"
#include "vvg-filter-page.h"
#include "vvg-image-window.h"
#include "vvg-lights-panel.h"
#include "vvg-marks.h"
#include "vvg-measurement-page.h"
#include "vvg-modeling-page.h"
#include "vvg-navigator-panel.h"
#include "vvg-object-list.h"
#include "vvg-object-panel.h"
#include "vvg-raw-dialog.h"
#include "vvg-rendering-page.h"
#include "vvg-scene-view.h"
#include "vvg-start-page.h"
#include "vvg-tf-panel.h"
#include "vvg-view-area.h"
#include "vvg-view-panel.h"

struct _VvgWindow {
    GtkApplicationWindow parent;
    VvgDocument *doc;
    VvgSceneView *scene;
    VvgMarks *marks;
    GtkWidget *navigator; /* VvgNavigatorPanel */
    GtkWidget *area;      /* VvgViewArea */
    GtkWidget *pages;     /* the side bar's GtkStack */
    GtkWidget *chooser;   /* the side bar's page chooser (GtkDropDown of the titles) */
    GtkWidget *side;      /* the side bar: hidden by the Controls toggle (F9) */
    GtkWidget *remote;    /* "N chunks, X MB pending" over the views while remote reads wait */
    guint remote_tick;
    /* File > Open URL… runs on a worker thread (open_async): at most one at a
     * time; the open pending is opening (NULL: none), shown over the views
     * by opening_bar (a spinner, "Opening URL…" and Cancel) */
    GCancellable *opening;
    GtkWidget *opening_bar, *opening_label, *opening_spinner;
    /* a close or quit waiting for Save (As) to finish */
    void (*after_save)(void *user);
    void *after_save_user;
    gboolean closing;         /* the close was confirmed: let the window go */
    const void *marks_volume; /* the volume the slice cursor belongs to (compared only) */
    /* autosave: this window's folder, its timers, and the folder of
     * a restored session, removed once this window's own autosave stands */
    char *autosave_dir;
    char *restore_from;
    guint autosave_tick, autosave_delay;
    gboolean autosave_pending;
    /* an autosave written on a worker thread: at most one at a time; the
     * window waits for it before it goes (autosave_lock, autosave_done);
     * autosave_gen moves on when the folder must go (saved, closed), so
     * that a run that ends after that removes what it wrote */
    GMutex autosave_lock;
    GCond autosave_done;
    gboolean autosave_writing; /* the worker's, under the lock */
    gboolean autosave_running; /* the main thread's: until autosave_finished */
    guint autosave_gen;
};

G_DEFINE_TYPE(VvgWindow, vvg_window, GTK_TYPE_APPLICATION_WINDOW)

static void
show_error(VvgWindow *win, const char *what, const char *message) {
    vvg_show_error(GTK_WIDGET(win), what, message);
}

static void
update_title(VvgWindow *win) {
    const char *p = vvg_document_path(win->doc);
    g_autofree char *base = p ? g_path_get_basename(p) : g_strdup("untitled");
    char *t = g_strdup_printf("VolVis — %s%s", base, vvg_document_dirty(win->doc) ? " *" : "");
    /* called for every change, also during drags: the X server is told only of new titles */
    if (g_strcmp0(t, gtk_window_get_title(GTK_WINDOW(win))) != 0)
        gtk_window_set_title(GTK_WINDOW(win), t);
    g_free(t);
    GAction *a = g_action_map_lookup_action(G_ACTION_MAP(win), "undo");
    g_simple_action_set_enabled(G_SIMPLE_ACTION(a), vvg_document_can_undo(win->doc));
    a = g_action_map_lookup_action(G_ACTION_MAP(win), "redo");
    g_simple_action_set_enabled(G_SIMPLE_ACTION(a), vvg_document_can_redo(win->doc));
}

/* ---- autosave -----------------------------------------------------------------
 * After an edit (a few seconds after the last one) and every 60 s while
 * there are unsaved changes, the session goes to
 * $XDG_STATE_HOME/volvis/session-<pid>-<n> as one unit
 * (vvg_document_autosave). A saved or closed session removes its folder; a
 * folder whose process is gone is a crash, offered for restoring at the
 * next start. VOLVIS_AUTOSAVE_DELAY and VOLVIS_AUTOSAVE_SECONDS set the two
 * times (tests). */

static char *
autosave_root(void) {
    return g_build_filename(g_get_user_state_dir(), "volvis", NULL);
}

static guint
env_seconds(const char *name, guint fallback) {
    const char *v = g_getenv(name);
    guint64 n = v ? g_ascii_strtoull(v, NULL, 10) : 0;
    return n >= 1 && n <= 86400 ? (guint)n : fallback;
}

typedef struct autosave_task {
    vvg_autosave_job *job;
    guint gen;
    gboolean ok;
    char *error;
} autosave_task;

static void
autosave_task_free(gpointer p) {
    autosave_task *t = p;
    vvg_autosave_job_free(t->job);
    g_free(t->error);
    g_free(t);
}

/* The worker: writes the snapshot, then lets a closing window go on. */
static void
autosave_thread(GTask *task, gpointer source, gpointer data, GCancellable *cancel) {
    (void)cancel;
    VvgWindow *win = source;
    autosave_task *t = data;
    GError *err = NULL;
    t->ok = vvg_autosave_job_run(t->job, &err);
    if (err) {
        t->error = g_strdup(err->message);
        g_error_free(err);
    }
    g_mutex_lock(&win->autosave_lock);
    win->autosave_writing = FALSE;
    g_cond_broadcast(&win->autosave_done);
    g_mutex_unlock(&win->autosave_lock);
    g_task_return_boolean(task, TRUE);
}

static void do_autosave(VvgWindow *win);

/* Back on the main thread: the document remembers what was written; a
 * folder that should be gone by now (the session was saved or the window
 * closed while it was written) is removed. */
static void
autosave_finished(GObject *source, GAsyncResult *res, gpointer user) {
    (void)user;
    VvgWindow *win = VVG_WINDOW(source);
    autosave_task *t = g_task_get_task_data(G_TASK(res));
    const char *dir = vvg_autosave_job_folder(t->job);
    win->autosave_running = FALSE;
    if (t->gen != win->autosave_gen || !win->doc) {
        vvg_document_remove_folder(dir);
        if (win->doc && win->autosave_pending) /* edited again since the save */
            do_autosave(win);
        return;
    }
    vvg_document_autosave_end(win->doc, t->job, t->ok);
    if (!t->ok) {
        g_printerr("volvis-gui: autosave failed: %s\n", t->error ? t->error : "unknown error");
        win->autosave_pending = TRUE; /* again at the next tick */
        return;
    }
    g_printerr("volvis-gui: autosaved %s\n", dir);
    if (win->restore_from) {
        vvg_document_remove_folder(win->restore_from);
        g_clear_pointer(&win->restore_from, g_free);
    }
    if (win->autosave_pending) /* edits while it was written */
        do_autosave(win);
}

/* Waits for an autosave being written (the window is going). */
static void
autosave_wait(VvgWindow *win) {
    g_mutex_lock(&win->autosave_lock);
    while (win->autosave_writing)
        g_cond_wait(&win->autosave_done, &win->autosave_lock);
    g_mutex_unlock(&win->autosave_lock);
}

/* The session is saved, or a file was opened that left it with nothing
 * unsaved (what the next autosave would find too, do_autosave, only at
 * once): its autosave folder goes (a run still writing removes it when
 * done), and so does a crashed session it was restored from. Kept, either
 * would be offered after a later crash as a session newer than the file,
 * and it is older. */
static void
autosave_drop(VvgWindow *win) {
    win->autosave_pending = FALSE;
    win->autosave_gen++;
    if (win->autosave_dir && !win->autosave_running)
        vvg_document_remove_folder(win->autosave_dir);
    if (win->restore_from) {
        vvg_document_remove_folder(win->restore_from);
        g_clear_pointer(&win->restore_from, g_free);
    }
}

static void
do_autosave(VvgWindow *win) {
    if (!win->doc || !win->autosave_dir)
        return;
    if (!vvg_document_dirty(win->doc)) { /* nothing unsaved: nothing to restore */
        autosave_drop(win);
        return;
    }
    if (win->autosave_running) { /* one at a time: this one once that ends */
        win->autosave_pending = TRUE;
        return;
    }
    win->autosave_pending = FALSE;
    GError *err = NULL;
    vvg_autosave_job *job = vvg_document_autosave_begin(win->doc, win->autosave_dir, &err);
    if (!job) {
        g_printerr("volvis-gui: autosave failed: %s\n", err->message);
        g_error_free(err);
        win->autosave_pending = TRUE;
        return;
    }
    autosave_task *t = g_new0(autosave_task, 1);
    t->job = job;
    t->gen = win->autosave_gen;
    win->autosave_running = TRUE;
    g_mutex_lock(&win->autosave_lock);
    win->autosave_writing = TRUE;
    g_mutex_unlock(&win->autosave_lock);
    GTask *task = g_task_new(win, NULL, autosave_finished, NULL);
    g_task_set_task_data(task, t, autosave_task_free);
    g_task_run_in_thread(task, autosave_thread);
    g_object_unref(task);
}

static gboolean
autosave_delay_cb(gpointer user) {
    VvgWindow *win = user;
    win->autosave_delay = 0;
    do_autosave(win);
    return G_SOURCE_REMOVE;
}

static gboolean
autosave_tick_cb(gpointer user) {
    VvgWindow *win = user;
    if (win->autosave_pending)
        do_autosave(win);
    return G_SOURCE_CONTINUE;
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgWindow *win = user;
    update_title(win);
    win->autosave_pending = TRUE;
    if (win->autosave_delay)
        g_source_remove(win->autosave_delay);
    win->autosave_delay =
        g_timeout_add_seconds(env_seconds("VOLVIS_AUTOSAVE_DELAY", 5), autosave_delay_cb, win);
}

/* 1 when process @p pid is a running volvis-gui. */
static gboolean
gui_alive(long pid) {
    if (pid <= 0 || (kill((pid_t)pid, 0) != 0 && errno != EPERM))
        return FALSE;
    g_autofree char *path = g_strdup_printf("/proc/%ld/comm", pid);
    g_autofree char *comm = NULL;
    return g_file_get_contents(path, &comm, NULL, NULL) && strstr(comm, "volvis-gui") != NULL;
}

/* The folders of autosaves whose process is gone, newest first. */
static GPtrArray *
stale_autosaves(void) {
    GPtrArray *out = g_ptr_array_new_with_free_func(g_free);
    g_autofree char *root = autosave_root();
    GDir *d = g_dir_open(root, 0, NULL);
    const char *name;
    while (d && (name = g_dir_read_name(d))) {
        long pid = 0;
        if (!g_str_has_prefix(name, "session-") || sscanf(name + 8, "%ld", &pid) != 1 ||
            pid == (long)getpid() || gui_alive(pid))
            continue;
        char *dir = g_build_filename(root, name, NULL);
        if (g_str_has_suffix(name, ".tmp")) { /* a stage the crash interrupted */
            vvg_document_remove_folder(dir);
            g_free(dir);
            continue;
        }
        g_ptr_array_add(out, dir);
    }
    if (d)
        g_dir_close(d);
    return out;
}

static gint64
session_mtime(const char *dir) {
    g_autofree char *p = g_build_filename(dir, "session.json", NULL);
    GStatBuf st;
    return g_stat(p, &st) == 0 ? (gint64)st.st_mtime : 0;
}

static void
restore_response(GtkDialog *d, int response, gpointer user) {
    VvgWindow *win = user;
    GPtrArray *stale = g_object_get_data(G_OBJECT(d), "stale");
    const char *newest = g_ptr_array_index(stale, 0);
    if (response == GTK_RESPONSE_ACCEPT) {
        GError *err = NULL;
        if (vvg_document_restore(win->doc, newest, &err)) {
            win->restore_from = g_strdup(newest);
            do_autosave(win); /* the restored volumes into this window's own folder */
        } else {
            show_error(win, "Cannot restore the session", err->message);
            g_error_free(err);
        }
    } else {
        for (guint i = 0; i < stale->len; i++)
            vvg_document_remove_folder(g_ptr_array_index(stale, i));
    }
    gtk_window_destroy(GTK_WINDOW(d));
}

void
vvg_window_offer_restore(VvgWindow *win) {
    GPtrArray *stale = stale_autosaves();
    guint best = 0;
    for (guint i = 0; i < stale->len; i++)
        if (session_mtime(g_ptr_array_index(stale, i)) >
            session_mtime(g_ptr_array_index(stale, best)))
            best = i;
    if (stale->len == 0 || session_mtime(g_ptr_array_index(stale, best)) == 0) {
        for (guint i = 0; i < stale->len; i++) /* no session in it: nothing to offer */
            vvg_document_remove_folder(g_ptr_array_index(stale, i));
        g_ptr_array_unref(stale);
        return;
    }
    char *first = g_ptr_array_steal_index(stale, best);
    g_ptr_array_insert(stale, 0, first);
    g_autoptr(GDateTime) t = g_date_time_new_from_unix_local(session_mtime(first));
    g_autofree char *when = g_date_time_format(t, "%Y-%m-%d %H:%M:%S");
    GtkWidget *d = gtk_message_dialog_new(GTK_WINDOW(win), GTK_DIALOG_MODAL, GTK_MESSAGE_QUESTION,
                                          GTK_BUTTONS_NONE, "Restore the last session?");
    gtk_message_dialog_format_secondary_text(
        GTK_MESSAGE_DIALOG(d),
        "VolVis did not close properly. The session autosaved at %s, with its unsaved "
        "changes, can be restored; Discard removes it.",
        when);
    gtk_window_set_title(GTK_WINDOW(d), "VolVis — restore");
    gtk_dialog_add_button(GTK_DIALOG(d), "_Discard", GTK_RESPONSE_REJECT);
    gtk_dialog_add_button(GTK_DIALOG(d), "_Restore", GTK_RESPONSE_ACCEPT);
    g_object_set_data_full(G_OBJECT(d), "stale", stale, (GDestroyNotify)g_ptr_array_unref);
    g_signal_connect(d, "response", G_CALLBACK(restore_response), win);
    gtk_widget_show(d);
}

/* A new volume selected: the slice views start again from its centre. */
static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgWindow *win = user;
    vv_object *o = vvg_document_selected_object(win->doc);
    if (o && o->volume && o->volume != win->marks_volume) {
        win->marks_volume = o->volume;
        vvg_marks_reset(win->marks);
    }
}

/* ---- opening ------------------------------------------------------------------ */

static void
raw_error_response(GtkDialog *d, int response, gpointer user) {
    char *path = g_object_get_data(G_OBJECT(d), "path");
    if (response == GTK_RESPONSE_ACCEPT && path)
        vvg_raw_dialog_present(GTK_WINDOW(user), vvg_window_document(user), path);
    gtk_window_destroy(GTK_WINDOW(d));
}

/* A file of no known format: the error, and the raw-import dialog on offer
 * (the library's hint names the CLI's --raw, which means nothing here). */
static void
offer_raw_import(VvgWindow *win, const char *path, const char *message) {
    g_autofree char *base = g_path_get_basename(path);
    g_autofree char *msg = g_strdup(message);
    char *hint = strstr(msg, "; use --raw for raw data");
    if (hint)
        strcpy(hint, ")");
    g_printerr("volvis-gui: Cannot open %s: %s\n", base, msg);
    GtkWidget *d = gtk_message_dialog_new(GTK_WINDOW(win), GTK_DIALOG_MODAL, GTK_MESSAGE_ERROR,
                                          GTK_BUTTONS_NONE, "Cannot open %s", base);
    gtk_message_dialog_format_secondary_text(
        GTK_MESSAGE_DIALOG(d), "%s\n\nIf it holds raw voxels, import it and describe them.", msg);
    gtk_window_set_title(GTK_WINDOW(d), "VolVis: error");
    gtk_dialog_add_button(GTK_DIALOG(d), "_Close", GTK_RESPONSE_CLOSE);
    gtk_dialog_add_button(GTK_DIALOG(d), "_Import as raw…", GTK_RESPONSE_ACCEPT);
    g_object_set_data_full(G_OBJECT(d), "path", g_strdup(path), g_free);
    g_signal_connect(d, "response", G_CALLBACK(raw_error_response), win);
    gtk_widget_show(d);
}

/* What an open of @p path ended with (@p err: NULL on success; taken):
 * the error dialog, else the recent list; the title either way. */
static void
open_ended(VvgWindow *win, const char *path, GError *err) {
    if (err) {
        if (strstr(err->message, "use --raw for raw data")) {
            offer_raw_import(win, path, err->message);
        } else {
            g_autofree char *base = g_path_get_basename(path);
            char *what = g_strdup_printf("Cannot open %s", base);
            show_error(win, what, err->message);
            g_free(what);
        }
        g_error_free(err);
    } else {
        vvg_start_page_add_recent(path);
        if (!vvg_document_dirty(win->doc))
            autosave_drop(win);
    }
    update_title(win);
}

void
vvg_window_open(VvgWindow *win, const char *path) {
    GError *err = NULL;
    vvg_document_open(win->doc, path, &err);
    open_ended(win, path, err);
}

/* ---- opening on a worker thread ------------------------------------------------
 * A URL (File > Open URL…) is opened off the UI thread: the door fetches
 * the store's metadata and its coarsest level over the network, seconds on
 * a slow server, up to the transport's timeouts on one that does not answer.
 * vvg_open_job_run runs on a GTask thread; the window shows the open pending
 * over the views with Cancel, and installs the result on the UI thread
 * (open_async_done: vvg_document_open_finish, then open_ended, as
 * vvg_window_open does). One at a time: Open URL… is disabled while one is
 * pending. Cancel (or the window going) forgets the open at once; the
 * worker runs until the door returns and its result is then dropped, the
 * document as it was. Local files stay on the UI thread (vvg_window_open):
 * a scene's voxelizing and the raw-import offer are dialogs of their own,
 * and the start-up, drop and recent-file opens, and the tests and
 * autosave restore built on them, expect the file open when the call
 * returns. */

static void
opening_shown(VvgWindow *win, const char *url) {
    GAction *a = g_action_map_lookup_action(G_ACTION_MAP(win), "open-url");
    g_simple_action_set_enabled(G_SIMPLE_ACTION(a), url == NULL);
    if (url) {
        g_autofree char *text = g_strdup_printf("Opening %s…", url);
        gtk_label_set_text(GTK_LABEL(win->opening_label), text);
        gtk_spinner_start(GTK_SPINNER(win->opening_spinner));
    } else {
        gtk_spinner_stop(GTK_SPINNER(win->opening_spinner));
    }
    gtk_widget_set_visible(win->opening_bar, url != NULL);
}

static void
open_async_thread(GTask *task, gpointer source, gpointer data, GCancellable *cancel) {
    (void)source;
    (void)cancel; /* the door cannot be interrupted: its result is dropped instead */
    vvg_open_job_run(data);
    g_task_return_boolean(task, TRUE);
}

static void
open_async_done(GObject *source, GAsyncResult *res, gpointer user) {
    (void)user;
    VvgWindow *win = VVG_WINDOW(source);
    GTask *task = G_TASK(res);
    vvg_open_job *job = g_task_get_task_data(task);
    GCancellable *cancel = g_task_get_cancellable(task);
    if (g_cancellable_is_cancelled(cancel) || cancel != win->opening) {
        g_printerr("volvis-gui: the open of %s was cancelled; its result is dropped\n",
                   vvg_open_job_path(job));
        return;
    }
    g_clear_object(&win->opening);
    opening_shown(win, NULL);
    GError *err = NULL;
    vvg_document_open_finish(job, &err);
    open_ended(win, vvg_open_job_path(job), err);
}

/* Opens @p url on a worker thread; refused (FALSE) while an open is pending. */
static gboolean
open_async(VvgWindow *win, const char *url) {
    if (win->opening)
        return FALSE;
    win->opening = g_cancellable_new();
    GTask *task = g_task_new(win, win->opening, open_async_done, NULL);
    g_task_set_task_data(task, vvg_document_open_job_new(win->doc, url),
                         (GDestroyNotify)vvg_open_job_free);
    opening_shown(win, url);
    g_task_run_in_thread(task, open_async_thread);
    g_object_unref(task);
    return TRUE;
}

/* Cancel (the button over the views): the open is forgotten now. */
static void
opening_cancel(VvgWindow *win) {
    if (!win->opening)
        return;
    g_cancellable_cancel(win->opening);
    g_clear_object(&win->opening);
    g_printerr("volvis-gui: opening cancelled\n");
    opening_shown(win, NULL);
}

/* The open pending, over the top of the views: a spinner, "Opening URL…"
 * (a label: its text is its accessible name) and Cancel. */
static GtkWidget *
opening_bar(VvgWindow *win) {
    GtkWidget *bar = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 8);
    gtk_widget_add_css_class(bar, "osd");
    gtk_widget_set_halign(bar, GTK_ALIGN_CENTER);
    gtk_widget_set_valign(bar, GTK_ALIGN_START);
    gtk_widget_set_margin_top(bar, 8);
    win->opening_spinner = gtk_spinner_new();
    gtk_accessible_update_property(GTK_ACCESSIBLE(win->opening_spinner),
                                   GTK_ACCESSIBLE_PROPERTY_LABEL, "Opening", -1);
    win->opening_label = gtk_label_new("");
    gtk_label_set_ellipsize(GTK_LABEL(win->opening_label), PANGO_ELLIPSIZE_MIDDLE);
    gtk_label_set_max_width_chars(GTK_LABEL(win->opening_label), 60);
    gtk_accessible_update_property(GTK_ACCESSIBLE(win->opening_label),
                                   GTK_ACCESSIBLE_PROPERTY_DESCRIPTION,
                                   "a remote store being opened", -1);
    GtkWidget *cancel = gtk_button_new_with_label("Cancel");
    gtk_accessible_update_property(GTK_ACCESSIBLE(cancel), GTK_ACCESSIBLE_PROPERTY_LABEL,
                                   "Cancel opening", -1);
    g_signal_connect_swapped(cancel, "clicked", G_CALLBACK(opening_cancel), win);
    gtk_box_append(GTK_BOX(bar), win->opening_spinner);
    gtk_box_append(GTK_BOX(bar), win->opening_label);
    gtk_box_append(GTK_BOX(bar), cancel);
    gtk_widget_set_visible(bar, FALSE);
    win->opening_bar = bar;
    return bar;
}

static void
act_open_file(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    vvg_window_open(user, g_variant_get_string(p, NULL));
}

/* "Open URL…": a remote OME-Zarr store (http, https, s3), opened through
 * the same door as a file (docs/formats.md, "Remote data"). */
static void
open_url_go(GtkWidget *w, gpointer dialog) {
    (void)w;
    GtkWidget *entry = g_object_get_data(G_OBJECT(dialog), "entry");
    VvgWindow *win = g_object_get_data(G_OBJECT(dialog), "win");
    g_autofree char *url = g_strstrip(g_strdup(gtk_editable_get_text(GTK_EDITABLE(entry))));
    gtk_window_destroy(GTK_WINDOW(dialog));
    if (url[0] && !open_async(win, url))
        show_error(win, "Cannot open the URL", "another URL is being opened; cancel it first");
}

static void
act_open_url(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    GtkWidget *d = gtk_window_new();
    gtk_window_set_title(GTK_WINDOW(d), "VolVis — open URL");
    gtk_window_set_transient_for(GTK_WINDOW(d), GTK_WINDOW(user));
    gtk_window_set_modal(GTK_WINDOW(d), TRUE);
    gtk_window_set_default_size(GTK_WINDOW(d), 520, -1);
    GtkWidget *box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 8);
    gtk_widget_set_margin_start(box, 12);
    gtk_widget_set_margin_end(box, 12);
    gtk_widget_set_margin_top(box, 12);
    gtk_widget_set_margin_bottom(box, 12);
    GtkWidget *label = gtk_label_new("An OME-Zarr store over HTTP(S) or S3:");
    gtk_label_set_xalign(GTK_LABEL(label), 0);
    GtkWidget *entry = gtk_entry_new();
    gtk_entry_set_placeholder_text(
        GTK_ENTRY(entry), "https://host/path/image.ome.zarr or s3://bucket/image.ome.zarr");
    GtkWidget *row = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 8);
    gtk_widget_set_halign(row, GTK_ALIGN_END);
    GtkWidget *cancel = gtk_button_new_with_label("Cancel");
    GtkWidget *open = gtk_button_new_with_label("Open");
    gtk_box_append(GTK_BOX(row), cancel);
    gtk_box_append(GTK_BOX(row), open);
    gtk_box_append(GTK_BOX(box), label);
    gtk_box_append(GTK_BOX(box), entry);
    gtk_box_append(GTK_BOX(box), row);
    gtk_window_set_child(GTK_WINDOW(d), box);
    g_object_set_data(G_OBJECT(d), "entry", entry);
    g_object_set_data(G_OBJECT(d), "win", user);
    g_signal_connect(open, "clicked", G_CALLBACK(open_url_go), d);
    g_signal_connect(entry, "activate", G_CALLBACK(open_url_go), d);
    g_signal_connect_swapped(cancel, "clicked", G_CALLBACK(gtk_window_destroy), d);
    GtkEventController *esc = gtk_shortcut_controller_new();
    gtk_shortcut_controller_add_shortcut(GTK_SHORTCUT_CONTROLLER(esc),
                                         gtk_shortcut_new(gtk_keyval_trigger_new(GDK_KEY_Escape, 0),
                                                          gtk_named_action_new("window.close")));
    gtk_widget_add_controller(d, esc);
    gtk_accessible_update_property(GTK_ACCESSIBLE(entry), GTK_ACCESSIBLE_PROPERTY_LABEL,
                                   "URL of the store", -1);
    gtk_window_present(GTK_WINDOW(d));
}

static void
act_import_raw(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vvg_raw_dialog_present(GTK_WINDOW(user), VVG_WINDOW(user)->doc, NULL);
}

static void
act_browse_dicom(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vvg_dicom_dialog_present(GTK_WINDOW(user), VVG_WINDOW(user)->doc);
}

static void
open_response(GtkNativeDialog *d, int response, gpointer user) {
    VvgWindow *win = user;
    if (response == GTK_RESPONSE_ACCEPT) {
        GListModel *files = gtk_file_chooser_get_files(GTK_FILE_CHOOSER(d));
        for (guint i = 0; i < g_list_model_get_n_items(files); i++) {
            GFile *f = g_list_model_get_item(files, i);
            char *p = g_file_get_path(f);
            if (p)
                vvg_window_open(win, p);
            g_free(p);
            g_object_unref(f);
        }
        g_object_unref(files);
    }
    g_object_unref(d);
}

static void
act_open(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    GtkFileChooserNative *d = gtk_file_chooser_native_new(
        "Open volume, mesh or scene", user, GTK_FILE_CHOOSER_ACTION_OPEN, "_Open", "_Cancel");
    gtk_file_chooser_set_select_multiple(GTK_FILE_CHOOSER(d), TRUE);
    g_signal_connect(d, "response", G_CALLBACK(open_response), user);
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

static gboolean
save_to(VvgWindow *win, const char *path) {
    GError *err = NULL;
    gboolean ok = vvg_document_save(win->doc, path, &err);
    if (!ok) {
        show_error(win, "Cannot save the session", err->message);
        g_error_free(err);
    } else {
        vvg_start_page_add_recent(path);
        if (!vvg_document_dirty(win->doc))
            autosave_drop(win);
    }
    update_title(win);
    /* a close or quit waiting for this save goes on now, or not at all */
    if (win->after_save) {
        void (*done)(void *) = win->after_save;
        void *u = win->after_save_user;
        win->after_save = NULL;
        if (ok)
            done(u);
    }
    return ok;
}

static void
save_response(GtkNativeDialog *d, int response, gpointer user) {
    if (response == GTK_RESPONSE_ACCEPT) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(d));
        char *p = g_file_get_path(f);
        if (p) {
            if (!g_str_has_suffix(p, ".json")) {
                char *q = g_strconcat(p, ".json", NULL);
                g_free(p);
                p = q;
            }
            save_to(user, p);
        }
        g_free(p);
        g_object_unref(f);
    } else {
        VVG_WINDOW(user)->after_save = NULL; /* a close waiting for the save is cancelled */
    }
    g_object_unref(d);
}

static void
act_save_as(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    GtkFileChooserNative *d = gtk_file_chooser_native_new(
        "Save session as scene file", user, GTK_FILE_CHOOSER_ACTION_SAVE, "_Save", "_Cancel");
    gtk_file_chooser_set_current_name(GTK_FILE_CHOOSER(d), "session.json");
    g_signal_connect(d, "response", G_CALLBACK(save_response), user);
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

static void
act_save(GSimpleAction *a, GVariant *p, gpointer user) {
    VvgWindow *win = user;
    const char *path = vvg_document_path(win->doc);
    if (path)
        save_to(win, path);
    else
        act_save_as(a, p, user);
}

/* ---- Save volume as… --------------------------------------------------------
 * The selected volume object (else the first one) written to any format
 * that writes, chosen by the name's extension (the format table, as
 * `volvis convert`). The write runs on a worker thread with its own
 * reference to the volume, so a large file does not stop the window; what
 * the format cannot hold (its record's fits) is said after the save. */

typedef struct save_volume_job {
    vv_volume *volume; /* a reference of its own */
    char *path;
    char *warning; /* what the format dropped, or NULL */
} save_volume_job;

static void
save_volume_job_free(gpointer p) {
    save_volume_job *j = p;
    vv_volume_free(j->volume);
    g_free(j->path);
    g_free(j->warning);
    g_free(j);
}

static void
save_volume_thread(GTask *task, gpointer source, gpointer data, GCancellable *cancel) {
    (void)source;
    (void)cancel;
    save_volume_job *j = data;
    if (vv_volume_save_with(j->volume, j->path, NULL) != VV_OK)
        g_task_return_new_error(task, G_IO_ERROR, G_IO_ERROR_FAILED, "%s", vv_error_message());
    else
        g_task_return_boolean(task, TRUE);
}

static void
save_volume_done(GObject *source, GAsyncResult *res, gpointer user) {
    (void)user;
    VvgWindow *win = VVG_WINDOW(source);
    save_volume_job *j = g_task_get_task_data(G_TASK(res));
    g_autofree char *base = g_path_get_basename(j->path);
    GError *err = NULL;
    if (!g_task_propagate_boolean(G_TASK(res), &err)) {
        g_autofree char *what = g_strdup_printf("Cannot save %s", base);
        show_error(win, what, err->message);
        g_error_free(err);
        return;
    }
    if (j->warning) {
        g_printerr("volvis-gui: saved %s: %s\n", base, j->warning);
        GtkWidget *d =
            gtk_message_dialog_new(GTK_WINDOW(win), GTK_DIALOG_MODAL, GTK_MESSAGE_WARNING,
                                   GTK_BUTTONS_CLOSE, "Saved %s", base);
        gtk_message_dialog_format_secondary_text(GTK_MESSAGE_DIALOG(d), "%s", j->warning);
        gtk_window_set_title(GTK_WINDOW(d), "VolVis: saved with a warning");
        g_signal_connect(d, "response", G_CALLBACK(gtk_window_destroy), NULL);
        gtk_widget_show(d);
    }
}

/* The volume Save volume as… writes: the selected object's, else the first. */
static vv_object *
volume_to_save(VvgWindow *win) {
    vv_object *o = vvg_document_selected_object(win->doc);
    if (o && o->type == VV_OBJECT_VOLUME && o->volume)
        return o;
    vv_world *w = vvg_document_world(win->doc);
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->type == VV_OBJECT_VOLUME && w->objects[i]->volume)
            return w->objects[i];
    return NULL;
}

void
vvg_window_save_volume(VvgWindow *win, const char *path) {
    vv_object *o = volume_to_save(win);
    g_autofree char *base = g_path_get_basename(path);
    g_autofree char *what = g_strdup_printf("Cannot save %s", base);
    if (!o) {
        show_error(win, what, "there is no volume in the scene");
        return;
    }
    vv_format f = vv_format_from_extension(path);
    int n = 0;
    const vv_format_record *const *table = vv_format_table(&n);
    const vv_format_record *r = vv_format_record_of(f);
    if (!r || !r->write || r->holds != VV_DATA_VOLUME) {
        GString *exts = g_string_new(NULL);
        for (int i = 0; i < n; i++)
            for (const char *const *e = vv_format_record_write_extensions(table[i]);
                 table[i]->holds == VV_DATA_VOLUME && table[i]->write && e && *e; e++)
                g_string_append_printf(exts, "%s.%s", exts->len ? ", " : "", *e);
        g_autofree char *m =
            g_strdup_printf("no format that writes has this extension (use %s)", exts->str);
        g_string_free(exts, TRUE);
        show_error(win, what, m);
        return;
    }
    save_volume_job *j = g_new0(save_volume_job, 1);
    j->volume = vv_volume_ref(o->volume);
    j->path = g_strdup(path);
    char why[256];
    if (r->fits && !r->fits(o->volume, why, sizeof why))
        j->warning = g_strdup(why);
    GTask *task = g_task_new(win, NULL, save_volume_done, NULL);
    g_task_set_task_data(task, j, save_volume_job_free);
    g_task_run_in_thread(task, save_volume_thread);
    g_object_unref(task);
}

static void
save_volume_response(GtkNativeDialog *d, int response, gpointer user) {
    if (response == GTK_RESPONSE_ACCEPT) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(d));
        char *p = g_file_get_path(f);
        if (p)
            vvg_window_save_volume(user, p);
        g_free(p);
        g_object_unref(f);
    }
    g_object_unref(d);
}

static void
act_save_volume(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgWindow *win = user;
    vv_object *o = volume_to_save(win);
    if (!o) {
        show_error(win, "Cannot save a volume", "there is no volume in the scene");
        return;
    }
    GtkFileChooserNative *d = gtk_file_chooser_native_new(
        "Save volume as", user, GTK_FILE_CHOOSER_ACTION_SAVE, "_Save", "_Cancel");
    g_autofree char *name = g_strdup_printf("%s.nii.gz", o->name[0] ? o->name : "volume");
    gtk_file_chooser_set_current_name(GTK_FILE_CHOOSER(d), name);
    g_signal_connect(d, "response", G_CALLBACK(save_volume_response), user);
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

static void
act_undo(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgWindow *win = user;
    vvg_document_undo(win->doc);
    update_title(win);
}

static void
act_redo(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgWindow *win = user;
    vvg_document_redo(win->doc);
    update_title(win);
}

static void
act_delete(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgWindow *win = user;
    vvg_document_delete_object(win->doc, vvg_document_selected(win->doc));
}

static void
act_render(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgWindow *win = user;
    vv_world *snap = vvg_document_snapshot(win->doc);
    if (!snap)
        return;
    VvgImageWindow *iw = vvg_image_window_new(GTK_WINDOW(win), snap);
    gtk_window_present(GTK_WINDOW(iw));
}

/* Camera presets: the view direction set, the scene framed again. */
static void
camera_preset(VvgWindow *win, vv_vec3 dir, vv_vec3 up, const char *label) {
    vvg_document_begin_edit(win->doc, label);
    vv_world *w = vvg_document_world(win->doc);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.eye = vv_vec3_scale(dir, -1);
    w->view.up = up;
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    vvg_document_changed(win->doc);
}

static void
act_view_front(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    camera_preset(user, vv_vec3_make(0, 1, 0), vv_vec3_make(0, 0, 1), "front view");
}

static void
act_view_side(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    camera_preset(user, vv_vec3_make(-1, 0, 0), vv_vec3_make(0, 0, 1), "side view");
}

static void
act_view_top(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    camera_preset(user, vv_vec3_make(0, 0, -1), vv_vec3_make(0, 1, 0), "top view");
}

static void
act_view_reset(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgWindow *win = user;
    vv_world *w = vvg_document_world(win->doc);
    vvg_document_begin_edit(win->doc, "frame all");
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    vvg_document_changed(win->doc);
}

static void
act_frame_all(GSimpleAction *a, GVariant *p, gpointer user) {
    act_view_reset(a, p, user);
}

/* What a drag in the view moves (Alt+1..4): the dropdown follows. */
static void
act_drag_target(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    VvgWindow *win = user;
    const char *t = g_variant_get_string(p, NULL);
    guint k = !strcmp(t, "object") ? 1u : !strcmp(t, "light") ? 2u : !strcmp(t, "cut") ? 3u : 0u;
    vvg_navigator_panel_set_target(VVG_NAVIGATOR_PANEL(win->navigator), (VvgNavTarget)k);
}

/* 1-up or 4-up (a stateful action: the header bar's toggles and the menu follow). */
static void
act_layout(GSimpleAction *a, GVariant *p, gpointer user) {
    VvgWindow *win = user;
    const char *s = g_variant_get_string(p, NULL);
    vvg_view_area_set_layout(VVG_VIEW_AREA(win->area), !strcmp(s, "4") ? 4 : 1);
    g_simple_action_set_state(a, p);
}

/* ---- closing ------------------------------------------------------------------- */

typedef struct close_ctx {
    VvgWindow *win;
    void (*done)(void *user);
    void *user;
} close_ctx;

static void
close_response(GtkDialog *d, int response, gpointer data) {
    close_ctx *c = data;
    gtk_window_destroy(GTK_WINDOW(d));
    if (response == GTK_RESPONSE_REJECT) { /* close without saving */
        c->done(c->user);
    } else if (response == GTK_RESPONSE_ACCEPT) { /* save first, then close */
        c->win->after_save = c->done;
        c->win->after_save_user = c->user;
        g_action_group_activate_action(G_ACTION_GROUP(c->win), "save", NULL);
    }
    g_free(c);
}

void
vvg_window_confirm_close(VvgWindow *win, void (*done)(void *user), void *user) {
    if (!vvg_document_dirty(win->doc)) {
        done(user);
        return;
    }
    const char *p = vvg_document_path(win->doc);
    g_autofree char *base = p ? g_path_get_basename(p) : g_strdup("the session");
    GtkWidget *d = gtk_message_dialog_new(GTK_WINDOW(win), GTK_DIALOG_MODAL, GTK_MESSAGE_QUESTION,
                                          GTK_BUTTONS_NONE, "Save the changes to %s?", base);
    gtk_message_dialog_format_secondary_text(GTK_MESSAGE_DIALOG(d),
                                             "Your changes are lost if you close without saving.");
    gtk_window_set_title(GTK_WINDOW(d), "VolVis: unsaved changes");
    gtk_dialog_add_button(GTK_DIALOG(d), "_Cancel", GTK_RESPONSE_CANCEL);
    gtk_dialog_add_button(GTK_DIALOG(d), "Close _without saving", GTK_RESPONSE_REJECT);
    gtk_dialog_add_button(GTK_DIALOG(d), "_Save", GTK_RESPONSE_ACCEPT);
    gtk_dialog_set_default_response(GTK_DIALOG(d), GTK_RESPONSE_ACCEPT);
    close_ctx *c = g_new(close_ctx, 1);
    c->win = win;
    c->done = done;
    c->user = user;
    g_signal_connect(d, "response", G_CALLBACK(close_response), c);
    gtk_widget_show(d);
}

static void
close_now(void *user) {
    VvgWindow *win = user;
    win->closing = TRUE;
    gtk_window_close(GTK_WINDOW(win));
}

static gboolean
close_request(GtkWindow *w, gpointer user) {
    (void)user;
    VvgWindow *win = VVG_WINDOW(w);
    if (win->closing || !vvg_document_dirty(win->doc))
        return FALSE;
    vvg_window_confirm_close(win, close_now, win);
    return TRUE; /* the dialog decides */
}

static void
act_close(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    gtk_window_close(GTK_WINDOW(user));
}

/* ---- drag and drop -------------------------------------------------------------- */

static gboolean
drop_cb(GtkDropTarget *t, const GValue *value, double x, double y, gpointer user) {
    (void)t;
    (void)x;
    (void)y;
    VvgWindow *win = user;
    if (!G_VALUE_HOLDS(value, GDK_TYPE_FILE_LIST))
        return FALSE;
    for (GSList *l = g_value_get_boxed(value); l; l = l->next) {
        char *p = g_file_get_path(l->data);
        if (p)
            vvg_window_open(win, p);
        g_free(p);
    }
    return TRUE;
}

/* ---- layout ------------------------------------------------------------------------ */

/* The application menu: the same named actions as the shortcuts, pages and devices. */
static GMenuModel *
main_menu(void) {
    static const struct {
        const char *section, *label, *action;
    } items[] = {
        {"File", "Open…", "win.open"},
        {"File", "Open URL…", "win.open-url"},
        {"File", "Import raw…", "win.import-raw"},
        {"File", "Browse DICOM…", "win.browse-dicom"},
        {"File", "Save session", "win.save"},
        {"File", "Save session as…", "win.save-as"},
        {"File", "Save volume as…", "win.save-volume"},
        {"File", "Close window", "win.close"},
        {"File", "Quit", "app.quit"},
        {"Edit", "Undo", "win.undo"},
        {"Edit", "Redo", "win.redo"},
        {"Edit", "Delete object", "win.delete-object"},
        {"View", "Frame all", "win.frame-all"},
        {"View", "Front", "win.view-front"},
        {"View", "Side", "win.view-side"},
        {"View", "Top", "win.view-top"},
        {"View", "One view", "win.layout::1"},
        {"View", "Four views (3-D and slices)", "win.layout::4"},
        {"Render", "Render…", "win.render"},
    };
    GMenu *menu = g_menu_new();
    GMenu *sec = NULL;
    const char *cur = NULL;
    for (size_t i = 0; i < G_N_ELEMENTS(items); i++) {
        if (!cur || strcmp(cur, items[i].section)) {
            if (sec) {
                g_menu_append_section(menu, cur, G_MENU_MODEL(sec));
                g_object_unref(sec);
            }
            sec = g_menu_new();
            cur = items[i].section;
        }
        g_menu_append(sec, items[i].label, items[i].action);
    }
    g_menu_append_section(menu, cur, G_MENU_MODEL(sec));
    g_object_unref(sec);
    return G_MENU_MODEL(menu);
}

static GtkWidget *
header_button(const char *label, const char *action, const char *tip) {
    /* no mnemonic: GTK 4.8 would name the button "_Save Save" for screen readers */
    GtkWidget *b = gtk_button_new_with_label(label);
    gtk_actionable_set_action_name(GTK_ACTIONABLE(b), action);
    gtk_widget_set_tooltip_text(b, tip);
    return b;
}

/* The header bar: Open, Save, Undo, Redo; the layout; the application menu. */
static GtkWidget *
header_bar(void) {
    GtkWidget *hb = gtk_header_bar_new();
    gtk_header_bar_pack_start(GTK_HEADER_BAR(hb), header_button("Open…", "win.open", "Ctrl+O"));
    gtk_header_bar_pack_start(GTK_HEADER_BAR(hb), header_button("Save", "win.save", "Ctrl+S"));
    gtk_header_bar_pack_start(GTK_HEADER_BAR(hb), header_button("Undo", "win.undo", "Ctrl+Z"));
    gtk_header_bar_pack_start(GTK_HEADER_BAR(hb),
                              header_button("Redo", "win.redo", "Ctrl+Shift+Z"));
    GtkWidget *menu = gtk_menu_button_new();
    gtk_menu_button_set_label(GTK_MENU_BUTTON(menu), "Menu");
    GMenuModel *m = main_menu();
    gtk_menu_button_set_menu_model(GTK_MENU_BUTTON(menu), m);
    g_object_unref(m);
    gtk_menu_button_set_primary(GTK_MENU_BUTTON(menu), TRUE);
    vvg_name(menu, "Menu");

    gtk_header_bar_pack_end(GTK_HEADER_BAR(hb), menu);
    GtkWidget *layout = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 0);
    gtk_widget_add_css_class(layout, "linked");
    GtkWidget *one = gtk_toggle_button_new_with_label("1 view");
    GtkWidget *four = gtk_toggle_button_new_with_label("4 views");
    gtk_actionable_set_detailed_action_name(GTK_ACTIONABLE(one), "win.layout::1");
    gtk_actionable_set_detailed_action_name(GTK_ACTIONABLE(four), "win.layout::4");
    gtk_widget_set_tooltip_text(four, "the 3-D view with axial, coronal and sagittal slices");
    gtk_box_append(GTK_BOX(layout), one);
    gtk_box_append(GTK_BOX(layout), four);
    gtk_header_bar_pack_end(GTK_HEADER_BAR(hb), layout);
    GtkWidget *controls = gtk_toggle_button_new_with_label("Controls");
    gtk_actionable_set_action_name(GTK_ACTIONABLE(controls), "win.controls");
    gtk_widget_set_tooltip_text(controls, "show or hide the side bar of pages (F9)");
    gtk_header_bar_pack_end(GTK_HEADER_BAR(hb), controls);
    return hb;
}

static void
add_page(VvgWindow *win, GtkWidget *content, const char *name, const char *title) {
    gtk_stack_add_titled(GTK_STACK(win->pages), content, name, title);
    /* "Objects page": tests and screen readers find a page's widgets under it */
    g_autofree char *a11y = g_strdup_printf("%s page", title);
    vvg_name(content, a11y);
}

static GtkWidget *
two(GtkWidget *a, GtkWidget *b) {
    GtkWidget *box = vvg_page_box();
    gtk_box_append(GTK_BOX(box), a);
    gtk_box_append(GTK_BOX(box), b);
    return vvg_scrolled(box);
}

static GtkWidget *
one(GtkWidget *a) {
    GtkWidget *box = vvg_page_box();
    gtk_box_append(GTK_BOX(box), a);
    return vvg_scrolled(box);
}

/* The page chooser shows a page: the stack's page at the chosen position. */
static void
page_chosen(GObject *dd, GParamSpec *pspec, gpointer user) {
    (void)pspec;
    VvgWindow *win = user;
    guint i = gtk_drop_down_get_selected(GTK_DROP_DOWN(dd));
    GtkSelectionModel *pages = gtk_stack_get_pages(GTK_STACK(win->pages));
    if (i < g_list_model_get_n_items(G_LIST_MODEL(pages))) {
        GtkStackPage *pg = g_list_model_get_item(G_LIST_MODEL(pages), i);
        gtk_stack_set_visible_child(GTK_STACK(win->pages), gtk_stack_page_get_child(pg));
        g_object_unref(pg);
    }
    g_object_unref(pages);
}

/* The chooser follows the stack when code shows a page. */
static void
page_shown(GObject *stack, GParamSpec *pspec, gpointer user) {
    (void)pspec;
    VvgWindow *win = user;
    GtkWidget *shown = gtk_stack_get_visible_child(GTK_STACK(stack));
    GtkSelectionModel *pages = gtk_stack_get_pages(GTK_STACK(stack));
    guint n = g_list_model_get_n_items(G_LIST_MODEL(pages));
    for (guint i = 0; i < n; i++) {
        GtkStackPage *pg = g_list_model_get_item(G_LIST_MODEL(pages), i);
        if (gtk_stack_page_get_child(pg) == shown &&
            gtk_drop_down_get_selected(GTK_DROP_DOWN(win->chooser)) != i)
            gtk_drop_down_set_selected(GTK_DROP_DOWN(win->chooser), i);
        g_object_unref(pg);
    }
    g_object_unref(pages);
}

/* Long labels of the side bar wrap (a check button's text, a hint, a
 * description): their width, not the window's, would set the side bar's. */
static void
wrap_long_labels(GtkWidget *w) {
    if (GTK_IS_LABEL(w)) {
        const char *t = gtk_label_get_text(GTK_LABEL(w));
        if (t && g_utf8_strlen(t, -1) > 36 && !gtk_label_get_wrap(GTK_LABEL(w)) &&
            gtk_label_get_ellipsize(GTK_LABEL(w)) == PANGO_ELLIPSIZE_NONE) {
            gtk_label_set_wrap(GTK_LABEL(w), TRUE);
            gtk_label_set_wrap_mode(GTK_LABEL(w), PANGO_WRAP_WORD_CHAR);
        }
        if (gtk_label_get_wrap(GTK_LABEL(w)) && gtk_label_get_max_width_chars(GTK_LABEL(w)) < 0)
            gtk_label_set_max_width_chars(GTK_LABEL(w), 40);
        return;
    }
    for (GtkWidget *c = gtk_widget_get_first_child(w); c; c = gtk_widget_get_next_sibling(c))
        wrap_long_labels(c);
}

/* The side bar (the views get most of the window): a drop-down
 * of the pages above the page, one page per component, each scrolling on
 * its own, 340 pixels wide; hidden altogether by Controls. */
static GtkWidget *
side_bar(VvgWindow *win) {
    GActionMap *am = G_ACTION_MAP(win);
    win->pages = gtk_stack_new();
    add_page(win, two(vvg_object_list_new(win->doc), vvg_object_panel_new(win->doc)), "objects",
             "Objects");
    add_page(win, one(vvg_tf_panel_new(win->doc, win->marks)), "transfer", "Transfer function");
    add_page(win, one(vvg_channel_panel_new(win->doc)), "channels", "Channels and time");
    win->navigator = vvg_navigator_panel_new(win->scene);
    add_page(win, two(win->navigator, vvg_view_panel_new(win->doc)), "view", "View");
    add_page(win, one(vvg_lights_panel_new(win->doc, win->scene, am)), "lights", "Lights");
    add_page(win, one(vvg_cut_panel_new(win->doc, win->scene, am)), "cut", "Cut planes");
    add_page(win, vvg_scrolled(vvg_rendering_page_new(win->doc)), "rendering", "Rendering");
    add_page(win, vvg_scrolled(vvg_measurement_page_new(win->doc, win->scene, win->marks, am)),
             "measurement", "Measurement");
    add_page(win, vvg_scrolled(vvg_modeling_page_new(win->doc, am)), "modeling", "Modeling");
    add_page(win, vvg_filter_page_new(win->doc), "filtering", "Filtering");
    add_page(win, vvg_animator_page_new(win->doc), "animator", "Animator");
    add_page(win, vvg_devices_page_new(win), "devices", "Input devices");
    /* the chooser: a drop-down of the pages' titles, one row (3D Slicer's
     * module selector), so that the page keeps the side bar's height */
    GtkSelectionModel *pages = gtk_stack_get_pages(GTK_STACK(win->pages));
    guint n = g_list_model_get_n_items(G_LIST_MODEL(pages));
    GtkStringList *titles = gtk_string_list_new(NULL);
    for (guint i = 0; i < n; i++) {
        GtkStackPage *pg = g_list_model_get_item(G_LIST_MODEL(pages), i);
        gtk_string_list_append(titles, gtk_stack_page_get_title(pg));
        g_object_unref(pg);
    }
    g_object_unref(pages);
    win->chooser = gtk_drop_down_new(G_LIST_MODEL(titles), NULL);
    vvg_name(win->chooser, "Pages");
    GtkWidget *inner = gtk_widget_get_first_child(win->chooser);
    if (inner) /* the button inside takes the focus: it carries the name too */
        vvg_name(inner, "Pages");
    gtk_widget_set_tooltip_text(win->chooser, "the side bar's page");
    gtk_widget_set_margin_start(win->chooser, 6);
    gtk_widget_set_margin_end(win->chooser, 6);
    gtk_widget_set_margin_top(win->chooser, 6);
    gtk_widget_set_margin_bottom(win->chooser, 4);
    g_signal_connect(win->chooser, "notify::selected", G_CALLBACK(page_chosen), win);
    g_signal_connect(win->pages, "notify::visible-child", G_CALLBACK(page_shown), win);
    page_shown(G_OBJECT(win->pages), NULL, win);
    GtkWidget *side = gtk_box_new(GTK_ORIENTATION_VERTICAL, 0);
    gtk_box_append(GTK_BOX(side), win->chooser);
    gtk_widget_set_size_request(win->pages, 340, -1);
    gtk_widget_set_hexpand(win->pages, FALSE);
    gtk_widget_set_vexpand(win->pages, TRUE);
    gtk_box_append(GTK_BOX(side), win->pages);
    wrap_long_labels(win->pages);
    win->side = side;
    return side;
}

/* Controls (F9): the side bar shown or hidden; hidden, the views take the window. */
static void
act_controls(GSimpleAction *a, GVariant *value, gpointer user) {
    VvgWindow *win = user;
    g_simple_action_set_state(a, value);
    gtk_widget_set_visible(win->side, g_variant_get_boolean(value));
}

/* ---- remote data ------------------------------------------------------------------- */

/* The reads of remote stores (HTTP, HTTPS, S3) not yet answered, four
 * times a second, over the bottom of the views: "12 chunks, 3.4 MB
 * pending" (kB under a megabyte) while a render or the loader waits for the
 * network, hidden when nothing is pending (vv_remote_stats_get: the
 * process's, lock-free). */
static gboolean
remote_tick(gpointer user) {
    VvgWindow *win = user;
    vv_remote_stats st;
    vv_remote_stats_get(&st);
    if (st.pending == 0) {
        gtk_widget_set_visible(win->remote, FALSE);
        return G_SOURCE_CONTINUE;
    }
    char text[128];
    const char *what = st.pending == 1 ? "chunk" : "chunks";
    if (st.pending_bytes >= 1000000)
        snprintf(text, sizeof text, "%" G_GUINT64_FORMAT " %s, %.1f MB pending", st.pending, what,
                 (double)st.pending_bytes / 1e6);
    else if (st.pending_bytes > 0)
        snprintf(text, sizeof text, "%" G_GUINT64_FORMAT " %s, %.0f kB pending", st.pending, what,
                 ceil((double)st.pending_bytes / 1e3));
    else
        snprintf(text, sizeof text, "%" G_GUINT64_FORMAT " %s pending", st.pending, what);
    if (strcmp(gtk_label_get_text(GTK_LABEL(win->remote)), text) != 0)
        gtk_label_set_text(GTK_LABEL(win->remote), text);
    gtk_widget_set_visible(win->remote, TRUE);
    return G_SOURCE_CONTINUE;
}

/* The views with the remote-data line laid over their bottom left corner
 * (over, not below: the views keep their size when it comes and goes). */
static GtkWidget *
views_with_remote_line(VvgWindow *win) {
    GtkWidget *overlay = gtk_overlay_new();
    gtk_overlay_set_child(GTK_OVERLAY(overlay), win->area);
    win->remote = gtk_label_new("");
    gtk_widget_add_css_class(win->remote, "osd");
    gtk_widget_set_halign(win->remote, GTK_ALIGN_START);
    gtk_widget_set_valign(win->remote, GTK_ALIGN_END);
    gtk_widget_set_margin_start(win->remote, 8);
    gtk_widget_set_margin_bottom(win->remote, 8);
    gtk_widget_set_can_target(win->remote, FALSE); /* the view under it keeps its input */
    /* a label's accessible name is its text (GTK sets it): what it says is
     * found by that, and what it is by its description */
    gtk_accessible_update_property(
        GTK_ACCESSIBLE(win->remote), GTK_ACCESSIBLE_PROPERTY_DESCRIPTION,
        "reads of remote stores (HTTP, S3) asked for and not yet answered", -1);
    gtk_widget_set_visible(win->remote, FALSE);
    gtk_overlay_add_overlay(GTK_OVERLAY(overlay), win->remote);
    gtk_overlay_add_overlay(GTK_OVERLAY(overlay), opening_bar(win));
    win->remote_tick = g_timeout_add(250, remote_tick, win);
    return overlay;
}

/* ---- life cycle --------------------------------------------------------------------- */

static void
vvg_window_dispose(GObject *o) {
    VvgWindow *win = VVG_WINDOW(o);
    /* the render thread ends with the window, not with the last frame
     * that holds the view (vvg_scene_view_stop) */
    if (win->scene)
        vvg_scene_view_stop(win->scene);
    g_clear_handle_id(&win->autosave_delay, g_source_remove);
    g_clear_handle_id(&win->autosave_tick, g_source_remove);
    g_clear_handle_id(&win->remote_tick, g_source_remove);
    if (win->opening) { /* an open pending is dropped when it ends */
        g_cancellable_cancel(win->opening);
        g_clear_object(&win->opening);
    }
    autosave_wait(win); /* an autosave being written ends first */
    win->autosave_gen++;
    if (win->autosave_dir) { /* closed as the user chose: no crash to restore */
        vvg_document_remove_folder(win->autosave_dir);
        g_clear_pointer(&win->autosave_dir, g_free);
    }
    g_clear_pointer(&win->restore_from, g_free);
    if (win->doc) {
        g_signal_handlers_disconnect_by_data(win->doc, win);
        g_clear_object(&win->doc);
    }
    g_clear_object(&win->marks);
    G_OBJECT_CLASS(vvg_window_parent_class)->dispose(o);
}

static void
vvg_window_finalize(GObject *o) {
    VvgWindow *win = VVG_WINDOW(o);
    g_mutex_clear(&win->autosave_lock);
    g_cond_clear(&win->autosave_done);
    G_OBJECT_CLASS(vvg_window_parent_class)->finalize(o);
}

static void
vvg_window_class_init(VvgWindowClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_window_dispose;
    G_OBJECT_CLASS(klass)->finalize = vvg_window_finalize;
}

static const GActionEntry win_actions[] = {
    {"open", act_open, NULL, NULL, NULL, {0}},
    {"open-url", act_open_url, NULL, NULL, NULL, {0}},
    {"open-file", act_open_file, "s", NULL, NULL, {0}},
    {"import-raw", act_import_raw, NULL, NULL, NULL, {0}},
    {"browse-dicom", act_browse_dicom, NULL, NULL, NULL, {0}},
    {"save", act_save, NULL, NULL, NULL, {0}},
    {"save-as", act_save_as, NULL, NULL, NULL, {0}},
    {"save-volume", act_save_volume, NULL, NULL, NULL, {0}},
    {"close", act_close, NULL, NULL, NULL, {0}},
    {"undo", act_undo, NULL, NULL, NULL, {0}},
    {"redo", act_redo, NULL, NULL, NULL, {0}},
    {"delete-object", act_delete, NULL, NULL, NULL, {0}},
    {"render", act_render, NULL, NULL, NULL, {0}},
    {"view-front", act_view_front, NULL, NULL, NULL, {0}},
    {"view-side", act_view_side, NULL, NULL, NULL, {0}},
    {"view-top", act_view_top, NULL, NULL, NULL, {0}},
    {"view-reset", act_view_reset, NULL, NULL, NULL, {0}},
    {"frame-all", act_frame_all, NULL, NULL, NULL, {0}},
    {"drag-target", act_drag_target, "s", NULL, NULL, {0}},
    {"layout", NULL, "s", "'1'", act_layout, {0}},
    {"controls", NULL, NULL, "true", act_controls, {0}},
};

static void
vvg_window_init(VvgWindow *win) {
    g_mutex_init(&win->autosave_lock);
    g_cond_init(&win->autosave_done);
    win->doc = vvg_document_new();
    win->marks = vvg_marks_new();
    g_action_map_add_action_entries(G_ACTION_MAP(win), win_actions, G_N_ELEMENTS(win_actions), win);
    win->scene = vvg_scene_view_new(win->doc, win->marks);
    win->area = vvg_view_area_new(win->doc, win->scene, win->marks);
    gtk_window_set_titlebar(GTK_WINDOW(win), header_bar());

    GtkWidget *paned = gtk_paned_new(GTK_ORIENTATION_HORIZONTAL);
    gtk_paned_set_start_child(GTK_PANED(paned), views_with_remote_line(win));
    gtk_paned_set_end_child(GTK_PANED(paned), side_bar(win));
    gtk_paned_set_resize_end_child(GTK_PANED(paned), FALSE);
    gtk_paned_set_shrink_end_child(GTK_PANED(paned), FALSE);
    gtk_paned_set_shrink_start_child(GTK_PANED(paned), FALSE);
    gtk_window_set_child(GTK_WINDOW(win), paned);

    GtkDropTarget *drop = gtk_drop_target_new(GDK_TYPE_FILE_LIST, GDK_ACTION_COPY);
    g_signal_connect(drop, "drop", G_CALLBACK(drop_cb), win);
    gtk_widget_add_controller(GTK_WIDGET(win), GTK_EVENT_CONTROLLER(drop));
    /* the values of every page take the wheel only when focused */
    vvg_wheel_when_focused_all(paned);
    g_signal_connect(win, "close-request", G_CALLBACK(close_request), NULL);

    g_signal_connect(win->doc, "changed", G_CALLBACK(doc_changed), win);
    g_signal_connect(win->doc, "selection-changed", G_CALLBACK(selection_changed), win);
    update_title(win);
    static int serial;
    g_autofree char *root = autosave_root();
    g_autofree char *name = g_strdup_printf("session-%ld-%d", (long)getpid(), ++serial);
    win->autosave_dir = g_build_filename(root, name, NULL);
    win->autosave_tick =
        g_timeout_add_seconds(env_seconds("VOLVIS_AUTOSAVE_SECONDS", 60), autosave_tick_cb, win);
}

VvgWindow *
vvg_window_new(GtkApplication *app) {
    return g_object_new(VVG_TYPE_WINDOW, "application", app, NULL);
}

VvgDocument *
vvg_window_document(VvgWindow *win) {
    return win->doc;
}

VvgSceneView *
vvg_window_scene_view(VvgWindow *win) {
    return win->scene;
}
