/* VvWindow: the main window, its layout and its actions (vv-window.h). */
#include "vv-window.h"
#include "vvg-widgets.h"

#include <string.h>

#include "vv-animator-page.h"
#include "vv-cut-panel.h"
#include "vv-devices-page.h"
#include "vv-filter-page.h"
#include "vv-image-window.h"
#include "vv-lights-panel.h"
#include "vv-measurement-page.h"
#include "vv-modeling-page.h"
#include "vv-navigator-panel.h"
#include "vv-object-list.h"
#include "vv-object-panel.h"
#include "vv-rendering-page.h"
#include "vv-scene-view.h"
#include "vv-tf-panel.h"
#include "vv-view-panel.h"

struct _VvWindow {
    GtkApplicationWindow parent;
    VvDocument *doc;
    VvSceneView *scene;
    GtkWidget *navigator; /* VvNavigatorPanel */
};

G_DEFINE_TYPE(VvWindow, vv_window, GTK_TYPE_APPLICATION_WINDOW)

static void
show_error(VvWindow *win, const char *what, const char *message) {
    vvg_show_error(GTK_WIDGET(win), what, message);
}

static void
update_title(VvWindow *win) {
    const char *p = vv_document_path(win->doc);
    g_autofree char *base = p ? g_path_get_basename(p) : g_strdup("untitled");
    char *t = g_strdup_printf("VolVis — %s%s", base, vv_document_dirty(win->doc) ? " *" : "");
    /* called for every change, also during drags: the X server is told only of new titles */
    if (g_strcmp0(t, gtk_window_get_title(GTK_WINDOW(win))) != 0)
        gtk_window_set_title(GTK_WINDOW(win), t);
    g_free(t);
    GAction *a = g_action_map_lookup_action(G_ACTION_MAP(win), "undo");
    g_simple_action_set_enabled(G_SIMPLE_ACTION(a), vv_document_can_undo(win->doc));
    a = g_action_map_lookup_action(G_ACTION_MAP(win), "redo");
    g_simple_action_set_enabled(G_SIMPLE_ACTION(a), vv_document_can_redo(win->doc));
}

static void
doc_changed(VvDocument *doc, gpointer user) {
    (void)doc;
    update_title(user);
}

/* ---- actions ---------------------------------------------------------------- */

void
vv_window_open(VvWindow *win, const char *path) {
    GError *err = NULL;
    if (!vv_document_open(win->doc, path, &err)) {
        g_autofree char *base = g_path_get_basename(path);
        char *what = g_strdup_printf("Cannot open %s", base);
        show_error(win, what, err->message);
        g_free(what);
        g_error_free(err);
    }
    update_title(win);
}

static void
open_response(GtkNativeDialog *d, int response, gpointer user) {
    VvWindow *win = user;
    if (response == GTK_RESPONSE_ACCEPT) {
        GListModel *files = gtk_file_chooser_get_files(GTK_FILE_CHOOSER(d));
        for (guint i = 0; i < g_list_model_get_n_items(files); i++) {
            GFile *f = g_list_model_get_item(files, i);
            char *p = g_file_get_path(f);
            if (p)
                vv_window_open(win, p);
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

static void
save_to(VvWindow *win, const char *path) {
    GError *err = NULL;
    if (!vv_document_save(win->doc, path, &err)) {
        show_error(win, "Cannot save the session", err->message);
        g_error_free(err);
    }
    update_title(win);
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
    VvWindow *win = user;
    const char *path = vv_document_path(win->doc);
    if (path)
        save_to(win, path);
    else
        act_save_as(a, p, user);
}

static void
act_undo(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_document_undo(win->doc);
    update_title(win);
}

static void
act_redo(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_document_redo(win->doc);
    update_title(win);
}

static void
act_delete(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_document_delete_object(win->doc, vv_document_selected(win->doc));
}

static void
act_render(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_world *snap = vv_document_snapshot(win->doc);
    if (!snap)
        return;
    VvImageWindow *iw = vv_image_window_new(GTK_WINDOW(win), snap);
    gtk_window_present(GTK_WINDOW(iw));
}

/* Camera presets: the view direction set, the scene framed again. */
static void
camera_preset(VvWindow *win, vv_vec3 dir, vv_vec3 up, const char *label) {
    vv_document_begin_edit(win->doc, label);
    vv_world *w = vv_document_world(win->doc);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.eye = vv_vec3_scale(dir, -1);
    w->view.up = up;
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    vv_document_changed(win->doc);
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
    VvWindow *win = user;
    vv_world *w = vv_document_world(win->doc);
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(w->view.at, w->view.eye));
    vv_document_begin_edit(win->doc, "reset view");
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    (void)f;
    vv_document_changed(win->doc);
}

/* The menu: the same named actions as the shortcuts, pages and devices. */
static GtkWidget *
main_menu_button(void) {
    static const struct {
        const char *section, *label, *action;
    } items[] = {
        {"File", "Open…", "win.open"},
        {"File", "Save session", "win.save"},
        {"File", "Save session as…", "win.save-as"},
        {"File", "Quit", "app.quit"},
        {"Edit", "Undo", "win.undo"},
        {"Edit", "Redo", "win.redo"},
        {"Edit", "Delete object", "win.delete-object"},
        {"View", "Front", "win.view-front"},
        {"View", "Side", "win.view-side"},
        {"View", "Top", "win.view-top"},
        {"View", "Reset", "win.view-reset"},
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
    GtkWidget *b = gtk_menu_button_new();
    gtk_menu_button_set_label(GTK_MENU_BUTTON(b), "Menu");
    gtk_menu_button_set_menu_model(GTK_MENU_BUTTON(b), G_MENU_MODEL(menu));
    g_object_unref(menu);
    return b;
}

/* The Manipulation page: the object list, the Navigator, Object Control
 * (segmentation and transfer functions; placement, material, textures and
 * shading), cut planes, lights and the view. */
static GtkWidget *
manipulation_page(VvWindow *win) {
    GtkWidget *box = vvg_page_box();
    GtkWidget *list = vv_object_list_new(win->doc);
    vv_object_list_add_button(VV_OBJECT_LIST(list), main_menu_button());
    gtk_box_append(GTK_BOX(box), list);
    win->navigator = vv_navigator_panel_new(win->scene);
    gtk_box_append(GTK_BOX(box), win->navigator);
    gtk_box_append(GTK_BOX(box), vv_tf_panel_new(win->doc));
    gtk_box_append(GTK_BOX(box), vv_object_panel_new(win->doc));
    gtk_box_append(GTK_BOX(box), vv_cut_panel_new(win->doc, G_ACTION_MAP(win)));
    gtk_box_append(GTK_BOX(box), vv_lights_panel_new(win->doc, win->scene, G_ACTION_MAP(win)));
    gtk_box_append(GTK_BOX(box), vv_view_panel_new(win->doc));
    return vvg_scrolled(box);
}

/* ---- drag and drop -------------------------------------------------------------- */

static gboolean
drop_cb(GtkDropTarget *t, const GValue *value, double x, double y, gpointer user) {
    (void)t;
    (void)x;
    (void)y;
    VvWindow *win = user;
    if (!G_VALUE_HOLDS(value, GDK_TYPE_FILE_LIST))
        return FALSE;
    for (GSList *l = g_value_get_boxed(value); l; l = l->next) {
        char *p = g_file_get_path(l->data);
        if (p)
            vv_window_open(win, p);
        g_free(p);
    }
    return TRUE;
}

/* ---- life cycle --------------------------------------------------------------------- */

static void
vv_window_dispose(GObject *o) {
    VvWindow *win = VV_WINDOW(o);
    if (win->doc) {
        g_signal_handlers_disconnect_by_data(win->doc, win);
        g_clear_object(&win->doc);
    }
    G_OBJECT_CLASS(vv_window_parent_class)->dispose(o);
}

static void
vv_window_class_init(VvWindowClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vv_window_dispose;
}

/* What a drag in the view moves (Alt+1..4): the dropdown follows. */
static void
act_drag_target(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    VvWindow *win = user;
    const char *t = g_variant_get_string(p, NULL);
    guint k = !strcmp(t, "object") ? 1u : !strcmp(t, "light") ? 2u : !strcmp(t, "cut") ? 3u : 0u;
    vv_navigator_panel_set_target(VV_NAVIGATOR_PANEL(win->navigator), (VvNavTarget)k);
}

static const GActionEntry win_actions[] = {
    {"open", act_open, NULL, NULL, NULL, {0}},
    {"save", act_save, NULL, NULL, NULL, {0}},
    {"save-as", act_save_as, NULL, NULL, NULL, {0}},
    {"undo", act_undo, NULL, NULL, NULL, {0}},
    {"redo", act_redo, NULL, NULL, NULL, {0}},
    {"delete-object", act_delete, NULL, NULL, NULL, {0}},
    {"render", act_render, NULL, NULL, NULL, {0}},
    {"view-front", act_view_front, NULL, NULL, NULL, {0}},
    {"view-side", act_view_side, NULL, NULL, NULL, {0}},
    {"view-top", act_view_top, NULL, NULL, NULL, {0}},
    {"view-reset", act_view_reset, NULL, NULL, NULL, {0}},
    {"drag-target", act_drag_target, "s", NULL, NULL, {0}},
};

static void
vv_window_init(VvWindow *win) {
    win->doc = vv_document_new();
    g_action_map_add_action_entries(G_ACTION_MAP(win), win_actions, G_N_ELEMENTS(win_actions), win);
    win->scene = vv_scene_view_new(win->doc);

    GtkWidget *stack = gtk_stack_new();
    GActionMap *am = G_ACTION_MAP(win);
    gtk_stack_add_titled(GTK_STACK(stack), manipulation_page(win), "manipulation", "Manipulation");
    gtk_stack_add_titled(GTK_STACK(stack), vvg_scrolled(vv_rendering_page_new(win->doc)),
                         "rendering", "Rendering");
    gtk_stack_add_titled(GTK_STACK(stack),
                         vvg_scrolled(vv_measurement_page_new(win->doc, win->scene, am)),
                         "measurement", "Measurement");
    gtk_stack_add_titled(GTK_STACK(stack), vvg_scrolled(vv_modeling_page_new(win->doc, am)),
                         "modeling", "Modeling");
    gtk_stack_add_titled(GTK_STACK(stack), vv_devices_page_new(win), "devices", "Input devices");
    gtk_stack_add_titled(GTK_STACK(stack), vv_animator_page_new(win->doc), "animator", "Animator");
    gtk_stack_add_titled(GTK_STACK(stack), vv_filter_page_new(win->doc), "filtering", "Filtering");
    GtkWidget *switcher = gtk_stack_sidebar_new();
    gtk_stack_sidebar_set_stack(GTK_STACK_SIDEBAR(switcher), GTK_STACK(stack));
    GtkWidget *side = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 0);
    gtk_box_append(GTK_BOX(side), switcher);
    gtk_widget_set_size_request(stack, 340, -1);
    gtk_box_append(GTK_BOX(side), stack);

    GtkWidget *paned = gtk_paned_new(GTK_ORIENTATION_HORIZONTAL);
    gtk_paned_set_start_child(GTK_PANED(paned), GTK_WIDGET(win->scene));
    gtk_paned_set_end_child(GTK_PANED(paned), side);
    gtk_paned_set_resize_end_child(GTK_PANED(paned), FALSE);
    gtk_paned_set_shrink_end_child(GTK_PANED(paned), FALSE);
    gtk_window_set_child(GTK_WINDOW(win), paned);

    GtkDropTarget *drop = gtk_drop_target_new(GDK_TYPE_FILE_LIST, GDK_ACTION_COPY);
    g_signal_connect(drop, "drop", G_CALLBACK(drop_cb), win);
    gtk_widget_add_controller(GTK_WIDGET(win), GTK_EVENT_CONTROLLER(drop));

    g_signal_connect(win->doc, "changed", G_CALLBACK(doc_changed), win);
    update_title(win);
}

VvWindow *
vv_window_new(GtkApplication *app) {
    return g_object_new(VV_TYPE_WINDOW, "application", app, NULL);
}

VvDocument *
vv_window_document(VvWindow *win) {
    return win->doc;
}

typedef struct close_ctx {
    void (*done)(void *user);
    void *user;
} close_ctx;

static void
close_response(GtkDialog *d, int response, gpointer data) {
    close_ctx *c = data;
    gtk_window_destroy(GTK_WINDOW(d));
    if (response == GTK_RESPONSE_ACCEPT)
        c->done(c->user);
    g_free(c);
}

void
vv_window_confirm_close(VvWindow *win, void (*done)(void *user), void *user) {
    if (!vv_document_dirty(win->doc)) {
        done(user);
        return;
    }
    GtkWidget *d = gtk_message_dialog_new(GTK_WINDOW(win), GTK_DIALOG_MODAL, GTK_MESSAGE_QUESTION,
                                          GTK_BUTTONS_NONE, "Discard unsaved changes?");
    gtk_window_set_title(GTK_WINDOW(d), "VolVis: unsaved changes");
    gtk_dialog_add_button(GTK_DIALOG(d), "_Cancel", GTK_RESPONSE_CANCEL);
    gtk_dialog_add_button(GTK_DIALOG(d), "_Discard", GTK_RESPONSE_ACCEPT);
    close_ctx *c = g_new(close_ctx, 1);
    c->done = done;
    c->user = user;
    g_signal_connect(d, "response", G_CALLBACK(close_response), c);
    gtk_widget_show(d);
}
