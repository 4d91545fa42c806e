/* VvgImageWindow: a final render with progress, Cancel and Save (vvg-image-window.h). */
#include "vvg-image-window.h"
#include "vvg-widgets.h"

#include <stdio.h>
#include <string.h>

struct _VvgImageWindow {
    GtkWindow parent;
    vv_world *world;
    vv_image *image;
    GThread *thread;
    int cancel;      /* atomic */
    double fraction; /* atomic-ish: written by the worker, read by a timer */
    gint64 start_us;
    guint timer;
    vv_status status;
    gboolean disposed;
    char error[512];
    GtkWidget *picture, *progress, *cancel_button, *save_button, *status_label;
    GtkWidget *width, *height, *rerender;
    guint gen; /* of the render under way: a restarted one's end is ignored */
};

typedef struct done_msg {
    VvgImageWindow *win; /* a reference */
    guint gen;
} done_msg;

G_DEFINE_TYPE(VvgImageWindow, vvg_image_window, GTK_TYPE_WINDOW)

static int
progress_cb(void *user, double fraction) {
    VvgImageWindow *win = user;
    __atomic_store(&win->fraction, &fraction, __ATOMIC_RELAXED);
    return __atomic_load_n(&win->cancel, __ATOMIC_RELAXED);
}

static gboolean render_done(gpointer data);

static gpointer
render_main(gpointer data) {
    VvgImageWindow *win = data;
    guint gen = win->gen; /* set before this thread started */
    const vv_world *w = win->world;
    vv_renderer *r = NULL;
    vv_error_clear();
    vv_status s = vv_renderer_new_for_world(&r, w);
    if (s == VV_OK)
        s = vv_image_new(&win->image, w->view.width, w->view.height);
    if (s == VV_OK) {
        vv_render_options ro;
        vv_render_options_init(&ro);
        ro.quality = vv_render_settings_quality(&w->render);
        ro.progress.fn = progress_cb;
        ro.progress.user = win;
        s = vv_renderer_render(r, w, &w->view, &ro, win->image);
    }
    win->status = s;
    if (s != VV_OK)
        g_strlcpy(win->error, vv_error_message(), sizeof win->error);
    vv_renderer_free(r);
    done_msg *m = g_new(done_msg, 1);
    m->win = g_object_ref(win);
    m->gen = gen;
    g_idle_add(render_done, m);
    return NULL;
}

static gboolean
tick(gpointer data) {
    VvgImageWindow *win = data;
    double f;
    __atomic_load(&win->fraction, &f, __ATOMIC_RELAXED);
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(win->progress), f);
    double el = (g_get_monotonic_time() - win->start_us) * 1e-6;
    char text[96];
    if (f > 0.02)
        snprintf(text, sizeof text, "%.0f %% — %.1f s left", 100 * f, el * (1 - f) / f);
    else
        snprintf(text, sizeof text, "%.0f %%", 100 * f);
    gtk_progress_bar_set_text(GTK_PROGRESS_BAR(win->progress), text);
    return G_SOURCE_CONTINUE;
}

static gboolean
render_done(gpointer data) {
    done_msg *m = data;
    VvgImageWindow *win = m->win;
    gboolean stale = m->gen != win->gen;
    g_free(m);
    if (win->disposed || stale) {
        g_object_unref(win);
        return G_SOURCE_REMOVE;
    }
    if (win->thread) {
        g_thread_join(win->thread);
        win->thread = NULL;
    }
    if (win->timer) {
        g_source_remove(win->timer);
        win->timer = 0;
    }
    gtk_widget_set_sensitive(win->cancel_button, FALSE);
    double el = (g_get_monotonic_time() - win->start_us) * 1e-6;
    if (win->status == VV_OK) {
        int w = win->image->width, h = win->image->height;
        size_t n = (size_t)w * h * 4;
        guint8 *px = g_malloc(n);
        vv_image_to_8bit(win->image, 4, 1.0, px);
        for (size_t i = 3; i < n; i += 4)
            px[i] = 255;
        GBytes *b = g_bytes_new_take(px, n);
        GdkTexture *t = gdk_memory_texture_new(w, h, GDK_MEMORY_R8G8B8A8, b, 4 * w);
        g_bytes_unref(b);
        gtk_picture_set_paintable(GTK_PICTURE(win->picture), GDK_PAINTABLE(t));
        g_object_unref(t);
        gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(win->progress), 1);
        char text[64];
        snprintf(text, sizeof text, "done in %.2f s", el);
        gtk_progress_bar_set_text(GTK_PROGRESS_BAR(win->progress), text);
        gtk_widget_set_sensitive(win->save_button, TRUE);
    } else {
        gtk_progress_bar_set_text(GTK_PROGRESS_BAR(win->progress),
                                  win->status == VV_ERR_CANCELLED ? "cancelled" : "failed");
        gtk_label_set_text(GTK_LABEL(win->status_label), win->error);
    }
    g_object_unref(win);
    return G_SOURCE_REMOVE;
}

/* Renders the snapshot again at the size typed (the same camera: the
 * vertical field of view is kept), after stopping a render under way. */
static void
start_render(VvgImageWindow *win) {
    if (win->thread) {
        __atomic_store_n(&win->cancel, 1, __ATOMIC_RELAXED);
        g_thread_join(win->thread);
        win->thread = NULL;
    }
    __atomic_store_n(&win->cancel, 0, __ATOMIC_RELAXED);
    vv_image_free(win->image);
    win->image = NULL;
    win->world->view.width = (int)vvg_spin_value(win->width);
    win->world->view.height = (int)vvg_spin_value(win->height);
    double zero = 0;
    __atomic_store(&win->fraction, &zero, __ATOMIC_RELAXED);
    gtk_widget_set_sensitive(win->save_button, FALSE);
    gtk_widget_set_sensitive(win->cancel_button, TRUE);
    gtk_label_set_text(GTK_LABEL(win->status_label), "");
    win->start_us = g_get_monotonic_time();
    win->gen++;
    if (!win->timer)
        win->timer = g_timeout_add(100, tick, win);
    win->thread = g_thread_new("volvis-final", render_main, win);
}

static void
rerender_clicked(GtkButton *b, gpointer user) {
    (void)b;
    start_render(user);
}

static void
cancel_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgImageWindow *win = user;
    __atomic_store_n(&win->cancel, 1, __ATOMIC_RELAXED);
}

gboolean
vvg_image_window_save(VvgImageWindow *win, const char *path, GError **error) {
    if (!win->image || win->status != VV_OK) {
        g_set_error_literal(error, VVG_ERROR, 1, "no finished image to save");
        return FALSE;
    }
    vv_error_clear();
    if (vv_image_write_png(win->image, path, 1.0, 0) != VV_OK) {
        g_set_error(error, VVG_ERROR, 1, "%s", vv_error_message());
        return FALSE;
    }
    return TRUE;
}

static void
save_response(GtkNativeDialog *d, int response, gpointer user) {
    VvgImageWindow *win = user;
    if (response == GTK_RESPONSE_ACCEPT) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(d));
        char *path = g_file_get_path(f);
        GError *err = NULL;
        if (!vvg_image_window_save(win, path, &err)) {
            gtk_label_set_text(GTK_LABEL(win->status_label), err->message);
            g_error_free(err);
        } else {
            char *m = g_strdup_printf("saved %s", path);
            gtk_label_set_text(GTK_LABEL(win->status_label), m);
            g_free(m);
        }
        g_free(path);
        g_object_unref(f);
    }
    g_object_unref(d);
}

static void
save_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgImageWindow *win = user;
    GtkFileChooserNative *d = gtk_file_chooser_native_new(
        "Save image as PNG", GTK_WINDOW(win), GTK_FILE_CHOOSER_ACTION_SAVE, "_Save", "_Cancel");
    gtk_file_chooser_set_current_name(GTK_FILE_CHOOSER(d), "render.png");
    g_signal_connect(d, "response", G_CALLBACK(save_response), win);
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

static void
vvg_image_window_dispose(GObject *o) {
    VvgImageWindow *win = VVG_IMAGE_WINDOW(o);
    win->disposed = TRUE;
    if (win->thread) {
        /* closing cancels the render cleanly */
        __atomic_store_n(&win->cancel, 1, __ATOMIC_RELAXED);
        g_thread_join(win->thread);
        win->thread = NULL;
    }
    if (win->timer) {
        g_source_remove(win->timer);
        win->timer = 0;
    }
    G_OBJECT_CLASS(vvg_image_window_parent_class)->dispose(o);
}

static void
vvg_image_window_finalize(GObject *o) {
    VvgImageWindow *win = VVG_IMAGE_WINDOW(o);
    vv_world_free(win->world);
    vv_image_free(win->image);
    G_OBJECT_CLASS(vvg_image_window_parent_class)->finalize(o);
}

static void
vvg_image_window_class_init(VvgImageWindowClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_image_window_dispose;
    G_OBJECT_CLASS(klass)->finalize = vvg_image_window_finalize;
}

static void
vvg_image_window_init(VvgImageWindow *win) {
    gtk_window_set_title(GTK_WINDOW(win), "VolVis — render");
    GtkWidget *box = gtk_box_new(GTK_ORIENTATION_VERTICAL, 6);
    win->picture = gtk_picture_new();
    gtk_widget_set_vexpand(win->picture, TRUE);
    vvg_name(win->picture, "rendered image");
    GtkWidget *size = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 6);
    GtkWidget *wl = gtk_label_new("width"), *hl = gtk_label_new("height");
    win->width = vvg_spin(16, VV_IMAGE_MAX_SIDE, 16, 0, 512);
    win->height = vvg_spin(16, VV_IMAGE_MAX_SIDE, 16, 0, 512);
    vvg_label_for(win->width, wl);
    vvg_label_for(win->height, hl);
    win->rerender = gtk_button_new_with_label("Render at this size");
    g_signal_connect(win->rerender, "clicked", G_CALLBACK(rerender_clicked), win);
    gtk_box_append(GTK_BOX(size), wl);
    gtk_box_append(GTK_BOX(size), win->width);
    gtk_box_append(GTK_BOX(size), hl);
    gtk_box_append(GTK_BOX(size), win->height);
    gtk_box_append(GTK_BOX(size), win->rerender);
    win->progress = gtk_progress_bar_new();
    gtk_progress_bar_set_show_text(GTK_PROGRESS_BAR(win->progress), TRUE);
    GtkWidget *row = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 6);
    win->cancel_button = gtk_button_new_with_label("Cancel");
    win->save_button = gtk_button_new_with_label("Save as PNG…");
    gtk_widget_set_sensitive(win->save_button, FALSE);
    g_signal_connect(win->cancel_button, "clicked", G_CALLBACK(cancel_clicked), win);
    g_signal_connect(win->save_button, "clicked", G_CALLBACK(save_clicked), win);
    win->status_label = gtk_label_new("");
    gtk_label_set_selectable(GTK_LABEL(win->status_label), TRUE);
    gtk_label_set_wrap(GTK_LABEL(win->status_label), TRUE);
    gtk_box_append(GTK_BOX(row), win->progress);
    gtk_widget_set_hexpand(win->progress, TRUE);
    gtk_box_append(GTK_BOX(row), win->cancel_button);
    gtk_box_append(GTK_BOX(row), win->save_button);
    GtkWidget *close = gtk_button_new_with_label("Close");
    g_signal_connect_swapped(close, "clicked", G_CALLBACK(gtk_window_close), win);
    gtk_box_append(GTK_BOX(row), close);
    gtk_box_append(GTK_BOX(box), size);
    gtk_box_append(GTK_BOX(box), win->picture);
    gtk_box_append(GTK_BOX(box), row);
    gtk_box_append(GTK_BOX(box), win->status_label);
    gtk_window_set_child(GTK_WINDOW(win), box);
    vvg_close_on_escape(GTK_WINDOW(win));
}

VvgImageWindow *
vvg_image_window_new(GtkWindow *parent, vv_world *world) {
    VvgImageWindow *win = g_object_new(VVG_TYPE_IMAGE_WINDOW, NULL);
    if (parent) {
        gtk_window_set_transient_for(GTK_WINDOW(win), parent);
        /* one of the application's windows: its shortcuts (Ctrl+Q) work here too */
        GtkApplication *app = gtk_window_get_application(parent);
        if (app)
            gtk_window_set_application(GTK_WINDOW(win), app);
    }
    win->world = world;
    vvg_set_spin(win->width, world->view.width);
    vvg_set_spin(win->height, world->view.height);
    gtk_window_set_default_size(GTK_WINDOW(win), MIN(world->view.width, 1200),
                                MIN(world->view.height, 900) + 100);
    start_render(win);
    return win;
}
