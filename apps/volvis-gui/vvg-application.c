/* VvgApplication: start-up, files from the command line, quit (vvg-application.h). */
#include "vvg-application.h"

#include <epoxy/gl.h>
#include <string.h>

#include "vvg-window.h"

struct _VvgApplication {
    GtkApplication parent;
};

G_DEFINE_TYPE(VvgApplication, vvg_application, GTK_TYPE_APPLICATION)

/* Quit: each window with unsaved changes asks in turn (Cancel stops the
 * quit), then every window goes as a closed one does: its render thread
 * ends and its autosave folder is removed. GtkApplication's quit alone
 * leaves the windows undisposed, and an autosave folder left behind would
 * be offered as a crashed session at the next start. A quit's serial marks
 * the windows whose question it has had answered. */
static guint quit_serial;

static gboolean quit_next(gpointer user);

static void
quit_answered(void *user) {
    GtkWindow *w = user;
    g_object_set_data(G_OBJECT(w), "vvg-quit-answered", GUINT_TO_POINTER(quit_serial));
    /* not from inside the dialog's or the save's own handlers */
    g_idle_add(quit_next, g_object_ref(gtk_window_get_application(w)));
}

static gpointer
ref_window(gconstpointer w, gpointer unused) {
    (void)unused;
    return g_object_ref((gpointer)w);
}

static gboolean
quit_next(gpointer user) {
    GtkApplication *app = user;
    for (GList *l = gtk_application_get_windows(app); l; l = l->next) {
        if (!VVG_IS_WINDOW(l->data) ||
            GPOINTER_TO_UINT(g_object_get_data(G_OBJECT(l->data), "vvg-quit-answered")) ==
                quit_serial ||
            !vvg_document_dirty(vvg_window_document(l->data)))
            continue;
        gtk_window_present(GTK_WINDOW(l->data));
        vvg_window_confirm_close(VVG_WINDOW(l->data), quit_answered, l->data);
        g_object_unref(app);
        return G_SOURCE_REMOVE;
    }
    GList *all = g_list_copy_deep(gtk_application_get_windows(app), ref_window, NULL);
    for (GList *l = all; l; l = l->next)
        gtk_window_destroy(GTK_WINDOW(l->data));
    g_list_free_full(all, g_object_unref);
    g_application_quit(G_APPLICATION(app));
    g_object_unref(app);
    return G_SOURCE_REMOVE;
}

static void
act_quit(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    quit_serial++;
    quit_next(g_object_ref(user));
}

/* GTK 4 draws its windows through OpenGL by default. Where OpenGL is Mesa's
 * software rasterizer (no GPU: a virtual machine, a remote or virtual X
 * display), that drawing takes most of the CPU a frame: on 2 cores under
 * Xvfb, llvmpipe held a four-view window to 23 redraws a second while a
 * scroll of the 512^3 slice view asked for more, where GTK's cairo renderer,
 * which redraws only what changed, gave 61 (bench/bench_gui.py). So unless
 * the user chose a renderer (GSK_RENDERER), a software GL display gets the
 * cairo renderer; a GPU keeps GTK's default. */
static void
prefer_cairo_on_software_gl(void) {
    if (g_getenv("GSK_RENDERER"))
        return;
    GdkDisplay *d = gdk_display_get_default();
    if (!d)
        return;
    GError *e = NULL;
    GdkGLContext *c = gdk_display_create_gl_context(d, &e);
    if (!c || !gdk_gl_context_realize(c, &e)) {
        /* no OpenGL at all: GTK falls back to cairo by itself */
        g_clear_error(&e);
        g_clear_object(&c);
        return;
    }
    gdk_gl_context_make_current(c);
    const char *r = (const char *)glGetString(GL_RENDERER);
    gboolean soft = r && (strstr(r, "llvmpipe") || strstr(r, "softpipe") || strstr(r, "swrast"));
    gdk_gl_context_clear_current();
    g_object_unref(c);
    if (soft)
        g_setenv("GSK_RENDERER", "cairo", FALSE);
}

static void
vvg_application_startup(GApplication *app) {
    G_APPLICATION_CLASS(vvg_application_parent_class)->startup(app);
    prefer_cairo_on_software_gl();
    static const GActionEntry entries[] = {{"quit", act_quit, NULL, NULL, NULL, {0}}};
    g_action_map_add_action_entries(G_ACTION_MAP(app), entries, 1, app);
    static const struct {
        const char *action;
        const char *accels[3];
    } keys[] = {
        {"app.quit", {"<Control>q", NULL}},
        {"win.open", {"<Control>o", NULL}},
        {"win.open-url", {"<Control><Shift>o", NULL}},
        {"win.import-raw", {"<Control>i", NULL}},
        {"win.browse-dicom", {"<Control>d", NULL}},
        {"win.close", {"<Control>w", NULL}},
        {"win.layout::1", {"<Control>1", NULL}},
        {"win.layout::4", {"<Control>4", NULL}},
        {"win.controls", {"F9", NULL}},
        {"win.save", {"<Control>s", NULL}},
        {"win.save-as", {"<Control><Shift>s", NULL}},
        {"win.save-volume", {"<Control><Shift>e", NULL}},
        {"win.undo", {"<Control>z", NULL}},
        {"win.redo", {"<Control><Shift>z", "<Control>y", NULL}},
        {"win.render", {"<Control>r", NULL}},
        {"win.delete-object", {"Delete", NULL}},
        {"win.view-reset", {"<Control>0", NULL}},
        {"win.drag-target::view", {"<Alt>1", NULL}},
        {"win.drag-target::object", {"<Alt>2", NULL}},
        {"win.drag-target::light", {"<Alt>3", NULL}},
        {"win.drag-target::cut", {"<Alt>4", NULL}},
    };
    for (size_t i = 0; i < G_N_ELEMENTS(keys); i++)
        gtk_application_set_accels_for_action(GTK_APPLICATION(app), keys[i].action, keys[i].accels);
}

static VvgWindow *
new_window(GApplication *app) {
    VvgWindow *w = vvg_window_new(GTK_APPLICATION(app));
    gtk_window_set_default_size(GTK_WINDOW(w), 1100, 720);
    gtk_window_present(GTK_WINDOW(w));
    return w;
}

static void
vvg_application_activate(GApplication *app) {
    vvg_window_offer_restore(new_window(app));
}

static void
vvg_application_open(GApplication *app, GFile **files, int n, const char *hint) {
    (void)hint;
    VvgWindow *w = new_window(app);
    for (int i = 0; i < n; i++) {
        char *p = g_file_get_path(files[i]);
        if (p)
            vvg_window_open(w, p);
        g_free(p);
    }
    vvg_window_offer_restore(w);
}

static void
vvg_application_class_init(VvgApplicationClass *klass) {
    G_APPLICATION_CLASS(klass)->startup = vvg_application_startup;
    G_APPLICATION_CLASS(klass)->activate = vvg_application_activate;
    G_APPLICATION_CLASS(klass)->open = vvg_application_open;
}

static void
vvg_application_init(VvgApplication *app) {
    (void)app;
}

VvgApplication *
vvg_application_new(void) {
    /* NON_UNIQUE: every start is its own process (tests run several at once) */
    return g_object_new(VVG_TYPE_APPLICATION, "application-id", "org.volvis.VolVis", "flags",
                        G_APPLICATION_HANDLES_OPEN | G_APPLICATION_NON_UNIQUE, NULL);
}
