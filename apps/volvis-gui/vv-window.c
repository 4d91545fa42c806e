/* VvWindow: the main window, its component pages and actions (vv-window.h). */
#include "vv-window.h"
#include "vvg-widgets.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "vv-animator-page.h"
#include "vv-devices-page.h"
#include "vv-filter-page.h"
#include "vv-image-window.h"
#include "vv-scene-view.h"
#include "vv-tf-editor.h"
#include "vv-tf2d-editor.h"

struct _VvWindow {
    GtkApplicationWindow parent;
    VvDocument *doc;
    VvSceneView *scene;
    gboolean updating; /* set while widgets are filled from the World */

    /* Manipulation */
    GtkWidget *object_list, *nav_target;
    GtkWidget *seg_mode, *threshold, *render_mode, *isovalue, *step;
    VvTfEditor *tf_editor;
    VvTf2dEditor *tf2d_editor;
    GtkWidget *preset, *w2d_color, *w2d_opacity;
    GtkWidget *tex_file, *tex_projection, *tex_scale, *solid_kind, *solid_period;
    GtkWidget *color, *ambient, *diffuse, *specular, *shininess, *reflectance, *transparency;
    GtkWidget *shading, *casts, *receives, *in_reflections, *reflects;
    GtkWidget *cut_scope, *cut_px, *cut_py, *cut_pz, *cut_nx, *cut_ny, *cut_nz;
    GtkWidget *light_index, *light_type, *light_color, *light_intensity;
    GtkWidget *ambient_color, *background_color;
    GtkWidget *view_width, *view_height, *view_fov, *view_projection;
    GtkWidget *eye[3], *at[3], *obj_pos[3], *obj_scale;
    guint placement_source;

    /* Rendering */
    GtkWidget *renderer, *quality, *options_box;

    /* Measurement */
    GtkWidget *measure_iso, *measure_method, *measure_seed, *seed_i, *seed_j, *seed_k;
    GtkWidget *pa[3], *pb[3], *measure_text, *histogram, *hist_log;
    vv_histogram *hist;

    /* Modeling */
    GtkWidget *prim_kind, *prim_size, *prim_res, *model_progress, *prim_mesh, *prim_pos[3];
    GtkWidget *prim_axis, *prim_angle, *csg_a, *csg_b, *csg_op;
    GHashTable *recipes;      /* vv_volume * -> model_recipe * of the objects made here */
    GPtrArray *model_volumes; /* the volumes listed in csg_a and csg_b, in order */
};

G_DEFINE_TYPE(VvWindow, vv_window, GTK_TYPE_APPLICATION_WINDOW)

/* ---- small widget helpers ------------------------------------------------ */

/* A spin button at 0, or at the bound nearest 0 (GTK starts at the lower bound). */
static GtkWidget *
spin(double lo, double hi, double step, int digits) {
    return vvg_spin(lo, hi, step, digits, lo > 0 ? lo : hi < 0 ? hi : 0);
}

static GtkWidget *
dropdown(const char *const *items) {
    return gtk_drop_down_new_from_strings(items);
}

static double
spin_value(GtkWidget *s) {
    return gtk_spin_button_get_value(GTK_SPIN_BUTTON(s));
}

static void
set_spin(GtkWidget *s, double v) {
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(s), v);
}

static GdkRGBA
rgba(vv_vec3 c) {
    return (GdkRGBA){(float)c.x, (float)c.y, (float)c.z, 1};
}

static vv_vec3
vec_of(const GdkRGBA *c) {
    return vv_vec3_make(c->red, c->green, c->blue);
}

static void
show_error(VvWindow *win, const char *what, const char *message) {
    vvg_show_error(GTK_WIDGET(win), what, message);
}

/* ---- filling the widgets from the World ----------------------------------- */

static void rebuild_object_list(VvWindow *win);
static void fill_placement(VvWindow *win);
static void rebuild_options(VvWindow *win);

static void
fill_object_control(VvWindow *win) {
    win->updating = TRUE;
    vv_world *w = vv_document_world(win->doc);
    vv_object *o = vv_document_selected_object(win->doc);
    if (o) {
        gtk_drop_down_set_selected(GTK_DROP_DOWN(win->seg_mode), o->segmentation);
        set_spin(win->threshold, o->threshold);
        gtk_drop_down_set_selected(GTK_DROP_DOWN(win->render_mode), o->mode);
        set_spin(win->isovalue, o->isovalue);
        set_spin(win->step, o->step);
        GdkRGBA c = rgba(o->material.color);
        gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(win->color), &c);
        set_spin(win->ambient, o->material.ambient);
        set_spin(win->diffuse, o->material.diffuse);
        set_spin(win->specular, o->material.specular);
        set_spin(win->shininess, o->material.shininess);
        set_spin(win->reflectance, o->material.reflectance);
        set_spin(win->transparency, o->material.transparency);
        gtk_drop_down_set_selected(GTK_DROP_DOWN(win->preset), 0);
        gtk_editable_set_text(
            GTK_EDITABLE(win->tex_file),
            o->texture.image && o->texture.image->source ? o->texture.image->source : "");
        gtk_drop_down_set_selected(GTK_DROP_DOWN(win->tex_projection), o->texture.projection);
        set_spin(win->tex_scale, o->texture.scale[0]);
        gtk_drop_down_set_selected(
            GTK_DROP_DOWN(win->solid_kind),
            o->solid_texture.kind <= VV_SOLID_TEXTURE_MARBLE ? (guint)o->solid_texture.kind : 0u);
        set_spin(win->solid_period, o->solid_texture.period);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(win->shading), o->shading);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(win->casts), o->casts_shadows);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(win->receives), o->receives_shadows);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(win->in_reflections),
                                    o->visible_in_reflections);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(win->reflects), o->reflects);
        if (o->volume) {
            double lo = o->volume->range[0], hi = o->volume->range[1];
            gtk_spin_button_set_range(GTK_SPIN_BUTTON(win->threshold), lo, hi > lo ? hi : lo + 1);
            gtk_spin_button_set_range(GTK_SPIN_BUTTON(win->isovalue), lo, hi > lo ? hi : lo + 1);
            gtk_spin_button_set_range(GTK_SPIN_BUTTON(win->measure_iso), lo, hi > lo ? hi : lo + 1);
        }
    }
    int li = (int)spin_value(win->light_index);
    gtk_spin_button_set_range(GTK_SPIN_BUTTON(win->light_index), 0,
                              w->n_lights > 0 ? w->n_lights - 1 : 0);
    if (li < w->n_lights) {
        gtk_drop_down_set_selected(GTK_DROP_DOWN(win->light_type),
                                   w->lights[li].headlight ? 2u : (guint)w->lights[li].type);
        GdkRGBA c = rgba(w->lights[li].color);
        gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(win->light_color), &c);
        set_spin(win->light_intensity, w->lights[li].intensity);
    }
    GdkRGBA a = rgba(w->ambient), b = rgba(w->background);
    gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(win->ambient_color), &a);
    gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(win->background_color), &b);
    fill_placement(win);
    set_spin(win->view_width, w->view.width);
    set_spin(win->view_height, w->view.height);
    set_spin(win->view_fov, vv_rad_to_deg(w->view.fov));
    gtk_drop_down_set_selected(GTK_DROP_DOWN(win->view_projection), w->view.projection);
    for (int i = 0; i < vv_renderer_count(); i++)
        if (!strcmp(vv_renderer_info_at(i)->name, vv_world_renderer(w)))
            gtk_drop_down_set_selected(GTK_DROP_DOWN(win->renderer), (guint)i);
    set_spin(win->quality, vv_render_settings_quality(&w->render));
    win->updating = FALSE;
}

/* The numbers the Navigator changes (eye, look-at point, object placement),
 * refreshed on every change of the World so that they are never stale. */
static void
fill_placement(VvWindow *win) {
    gboolean was = win->updating;
    win->updating = TRUE;
    vv_world *w = vv_document_world(win->doc);
    double ev[3] = {w->view.eye.x, w->view.eye.y, w->view.eye.z};
    double av[3] = {w->view.at.x, w->view.at.y, w->view.at.z};
    for (int i = 0; i < 3; i++) {
        set_spin(win->eye[i], ev[i]);
        set_spin(win->at[i], av[i]);
    }
    vv_object *o = vv_document_selected_object(win->doc);
    if (o) {
        double pv[3] = {o->position.x, o->position.y, o->position.z};
        for (int i = 0; i < 3; i++)
            set_spin(win->obj_pos[i], pv[i]);
        set_spin(win->obj_scale, o->scale.x);
    }
    win->updating = was;
}

/* Typed eye, look-at point or object placement: one undo step. */
static void
on_placement(GtkSpinButton *sb, gpointer user) {
    (void)sb;
    VvWindow *win = user;
    if (win->updating)
        return;
    vv_world *w = vv_document_world(win->doc);
    vv_document_begin_edit(win->doc, "placement");
    vv_view nv = w->view;
    nv.eye =
        vv_vec3_make(spin_value(win->eye[0]), spin_value(win->eye[1]), spin_value(win->eye[2]));
    nv.at = vv_vec3_make(spin_value(win->at[0]), spin_value(win->at[1]), spin_value(win->at[2]));
    if (vv_nav_view_valid(&nv)) /* an eye on the look-at point is refused */
        w->view = nv;
    vv_object *o = vv_document_selected_object(win->doc);
    if (o) {
        o->position = vv_vec3_make(spin_value(win->obj_pos[0]), spin_value(win->obj_pos[1]),
                                   spin_value(win->obj_pos[2]));
        /* a uniform scale typed here; a non-uniform one (from a scene) keeps its ratios */
        double sc = spin_value(win->obj_scale);
        if (sc > 0 && o->scale.x != 0 && fabs(sc - o->scale.x) > 1e-12)
            o->scale = vv_vec3_scale(o->scale, sc / o->scale.x);
    }
    vv_document_changed(win->doc);
}

static void
selection_changed(VvDocument *doc, gpointer user) {
    (void)doc;
    VvWindow *win = user;
    rebuild_object_list(win);
    fill_object_control(win);
    rebuild_options(win);
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

static gboolean
placement_due(gpointer user) {
    VvWindow *win = user;
    win->placement_source = 0;
    fill_placement(win);
    return G_SOURCE_REMOVE;
}

static void
doc_changed(VvDocument *doc, gpointer user) {
    (void)doc;
    VvWindow *win = user;
    update_title(win);
    /* during a drag the World changes a hundred times a second: the numbers
     * follow ten times a second, which costs the view no frames */
    if (!win->placement_source)
        win->placement_source = g_timeout_add(100, placement_due, win);
}

/* ---- edits from the Object Control widgets -------------------------------- */

/* Applies the widgets' values to the selected object and the World: one undo step. */
static void
apply_edit(VvWindow *win, const char *label) {
    if (win->updating)
        return;
    vv_document_begin_edit(win->doc, label);
    vv_world *w = vv_document_world(win->doc);
    vv_object *o = vv_document_selected_object(win->doc);
    if (o) {
        o->segmentation = (vv_segmentation)gtk_drop_down_get_selected(GTK_DROP_DOWN(win->seg_mode));
        o->threshold = spin_value(win->threshold);
        o->mode = (vv_render_mode)gtk_drop_down_get_selected(GTK_DROP_DOWN(win->render_mode));
        o->isovalue = spin_value(win->isovalue);
        o->step = spin_value(win->step);
        GdkRGBA c;
        gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(win->color), &c);
        o->material.color = vec_of(&c);
        o->material.ambient = spin_value(win->ambient);
        o->material.diffuse = spin_value(win->diffuse);
        o->material.specular = spin_value(win->specular);
        o->material.shininess = spin_value(win->shininess);
        o->material.reflectance = spin_value(win->reflectance);
        o->material.transparency = spin_value(win->transparency);
        o->shading = gtk_check_button_get_active(GTK_CHECK_BUTTON(win->shading));
        o->casts_shadows = gtk_check_button_get_active(GTK_CHECK_BUTTON(win->casts));
        o->receives_shadows = gtk_check_button_get_active(GTK_CHECK_BUTTON(win->receives));
        o->visible_in_reflections =
            gtk_check_button_get_active(GTK_CHECK_BUTTON(win->in_reflections));
        o->reflects = gtk_check_button_get_active(GTK_CHECK_BUTTON(win->reflects));
    }
    int li = (int)spin_value(win->light_index);
    if (li < w->n_lights) {
        vv_light *l = &w->lights[li];
        guint t = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->light_type));
        l->headlight = t == 2;
        l->type = t == 1 ? VV_LIGHT_POINT : VV_LIGHT_DIRECTIONAL;
        GdkRGBA c;
        gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(win->light_color), &c);
        l->color = vec_of(&c);
        l->intensity = spin_value(win->light_intensity);
    }
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(win->ambient_color), &c);
    w->ambient = vec_of(&c);
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(win->background_color), &c);
    w->background = vec_of(&c);
    vv_view nv = w->view;
    nv.eye =
        vv_vec3_make(spin_value(win->eye[0]), spin_value(win->eye[1]), spin_value(win->eye[2]));
    nv.at = vv_vec3_make(spin_value(win->at[0]), spin_value(win->at[1]), spin_value(win->at[2]));
    if (vv_nav_view_valid(&nv)) { /* an eye on the look-at point is refused */
        w->view.eye = nv.eye;
        w->view.at = nv.at;
    }
    w->view.width = (int)spin_value(win->view_width);
    w->view.height = (int)spin_value(win->view_height);
    w->view.fov = vv_deg_to_rad(spin_value(win->view_fov));
    w->view.projection =
        (vv_projection)gtk_drop_down_get_selected(GTK_DROP_DOWN(win->view_projection));
    vv_document_changed(win->doc);
    gtk_widget_queue_resize(GTK_WIDGET(win->scene));
}

static void
on_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    apply_edit(user, "edit");
}

static void
on_toggle(GtkCheckButton *b, gpointer user) {
    (void)b;
    apply_edit(user, "edit");
}

static void
on_dropdown(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    apply_edit(user, "edit");
}

static void
on_color(GtkColorButton *b, gpointer user) {
    (void)b;
    apply_edit(user, "edit colour");
}

static GtkWidget *
wire_spin(VvWindow *win, GtkWidget *s) {
    g_signal_connect(s, "value-changed", G_CALLBACK(on_spin), win);
    return s;
}

static GtkWidget *
wire_check(VvWindow *win, const char *label) {
    GtkWidget *b = gtk_check_button_new_with_label(label);
    g_signal_connect(b, "toggled", G_CALLBACK(on_toggle), win);
    return b;
}

static GtkWidget *
wire_drop(VvWindow *win, GtkWidget *d) {
    g_signal_connect(d, "notify::selected", G_CALLBACK(on_dropdown), win);
    return d;
}

static GtkWidget *
wire_color(VvWindow *win) {
    GtkWidget *b = gtk_color_button_new();
    g_signal_connect(b, "color-set", G_CALLBACK(on_color), win);
    return b;
}

/* ---- object list ------------------------------------------------------------ */

static void
visible_toggled(GtkCheckButton *b, gpointer user) {
    VvWindow *win = user;
    if (win->updating)
        return;
    int i = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "index"));
    vv_world *w = vv_document_world(win->doc);
    if (i >= w->n_objects)
        return;
    vv_document_begin_edit(win->doc, "visibility");
    w->objects[i]->visible = gtk_check_button_get_active(b);
    vv_document_changed(win->doc);
}

static void
name_activated(GtkEntry *e, gpointer user) {
    VvWindow *win = user;
    int i = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(e), "index"));
    vv_world *w = vv_document_world(win->doc);
    if (i >= w->n_objects)
        return;
    vv_document_begin_edit(win->doc, "rename");
    g_strlcpy(w->objects[i]->name, gtk_editable_get_text(GTK_EDITABLE(e)),
              sizeof w->objects[i]->name);
    vv_document_changed(win->doc);
}

static void
row_selected(GtkListBox *box, GtkListBoxRow *r, gpointer user) {
    (void)box;
    VvWindow *win = user;
    if (win->updating || !r)
        return;
    int i = gtk_list_box_row_get_index(r);
    if (i != vv_document_selected(win->doc))
        vv_document_select(win->doc, i);
}

static void
rebuild_object_list(VvWindow *win) {
    win->updating = TRUE;
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(win->object_list)))
        gtk_list_box_remove(GTK_LIST_BOX(win->object_list), c);
    vv_world *w = vv_document_world(win->doc);
    for (int i = 0; i < w->n_objects; i++) {
        GtkWidget *r = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
        GtkWidget *vis = gtk_check_button_new();
        gtk_check_button_set_active(GTK_CHECK_BUTTON(vis), w->objects[i]->visible);
        gtk_widget_set_tooltip_text(vis, "visible");
        g_object_set_data(G_OBJECT(vis), "index", GINT_TO_POINTER(i));
        g_signal_connect(vis, "toggled", G_CALLBACK(visible_toggled), win);
        GtkWidget *name = gtk_entry_new();
        gtk_editable_set_text(GTK_EDITABLE(name), w->objects[i]->name);
        gtk_widget_set_hexpand(name, TRUE);
        g_object_set_data(G_OBJECT(name), "index", GINT_TO_POINTER(i));
        g_signal_connect(name, "activate", G_CALLBACK(name_activated), win);
        GtkWidget *type = gtk_label_new(vv_object_type_name(w->objects[i]->type));
        gtk_box_append(GTK_BOX(r), vis);
        gtk_box_append(GTK_BOX(r), name);
        gtk_box_append(GTK_BOX(r), type);
        gtk_list_box_append(GTK_LIST_BOX(win->object_list), r);
    }
    int sel = vv_document_selected(win->doc);
    if (sel >= 0)
        gtk_list_box_select_row(GTK_LIST_BOX(win->object_list),
                                gtk_list_box_get_row_at_index(GTK_LIST_BOX(win->object_list), sel));
    win->updating = FALSE;
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

static void
act_add_light(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_world *w = vv_document_world(win->doc);
    vv_document_begin_edit(win->doc, "add light");
    vv_box b = vv_world_bounds(w);
    vv_light l = {VV_LIGHT_POINT, 0, {0, 1, 0}, b.max, {1, 1, 1}, 0.5};
    if (vv_world_add_light(w, &l) != VV_OK)
        show_error(win, "Cannot add a light", vv_error_message());
    set_spin(win->light_index, w->n_lights - 1);
    vv_document_changed(win->doc);
    fill_object_control(win);
}

static void
act_remove_light(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_world *w = vv_document_world(win->doc);
    int li = (int)spin_value(win->light_index);
    if (li >= w->n_lights)
        return;
    vv_document_begin_edit(win->doc, "remove light");
    memmove(&w->lights[li], &w->lights[li + 1],
            (size_t)(w->n_lights - li - 1) * sizeof w->lights[0]);
    w->n_lights--;
    vv_document_changed(win->doc);
    fill_object_control(win);
}

static void
cut_apply(VvWindow *win) {
    vv_vec3 pt =
        vv_vec3_make(spin_value(win->cut_px), spin_value(win->cut_py), spin_value(win->cut_pz));
    vv_vec3 n =
        vv_vec3_make(spin_value(win->cut_nx), spin_value(win->cut_ny), spin_value(win->cut_nz));
    if (!(vv_vec3_length(n) > 0)) {
        show_error(win, "Cannot add the cut plane", "the normal is zero");
        return;
    }
    vv_world *w = vv_document_world(win->doc);
    gboolean local = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->cut_scope)) == 1;
    vv_object *o = vv_document_selected_object(win->doc);
    vv_document_begin_edit(win->doc, "add cut plane");
    if (local && o) {
        if (o->n_cut_planes < VV_MAX_CUT_PLANES)
            o->cut_planes[o->n_cut_planes++] = (vv_cut_plane){pt, vv_vec3_normalize(n)};
    } else if (vv_world_add_cut_plane(w, pt, n) != VV_OK) {
        show_error(win, "Cannot add the cut plane", vv_error_message());
    }
    vv_document_changed(win->doc);
}

static void
act_add_cut(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    cut_apply(user);
}

static void
act_clear_cuts(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_document_begin_edit(win->doc, "remove cut planes");
    vv_world *w = vv_document_world(win->doc);
    w->n_cut_planes = 0;
    vv_object *o = vv_document_selected_object(win->doc);
    if (o)
        o->n_cut_planes = 0;
    vv_document_changed(win->doc);
}

/* ---- Rendering page: the registry's renderers and their options ------------ */

static void
option_changed(GtkEntry *e, gpointer user) {
    VvWindow *win = user;
    if (win->updating)
        return;
    const char *key = g_object_get_data(G_OBJECT(e), "key");
    const char *text = gtk_editable_get_text(GTK_EDITABLE(e));
    vv_world *w = vv_document_world(win->doc);
    /* check the value against the renderer's option table before taking it */
    const vv_renderer_info *info = vv_renderer_info_find(vv_world_renderer(w));
    vv_error_clear();
    if (info && text[0] && vv_renderer_info_check_option(info, key, text) != VV_OK) {
        show_error(win, "Bad renderer option", vv_error_message());
        return;
    }
    vv_document_begin_edit(win->doc, "renderer option");
    vv_render_settings *rs = &w->render;
    if (text[0]) {
        vv_render_settings_set_option(rs, key, text);
    } else {
        for (int i = 0; i < rs->n_options; i++)
            if (!strcmp(rs->option_keys[i], key)) {
                memmove(rs->option_keys[i], rs->option_keys[i + 1],
                        (size_t)(rs->n_options - i - 1) * sizeof rs->option_keys[0]);
                memmove(rs->option_values[i], rs->option_values[i + 1],
                        (size_t)(rs->n_options - i - 1) * sizeof rs->option_values[0]);
                rs->n_options--;
                break;
            }
    }
    vv_document_changed(win->doc);
}

static void
rebuild_options(VvWindow *win) {
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(win->options_box)))
        gtk_grid_remove(GTK_GRID(win->options_box), c);
    /* one row per entry of the renderer's option table (render.h) */
    guint sel = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->renderer));
    const vv_renderer_info *info = vv_renderer_info_at((int)sel);
    if (!info)
        info = vv_renderer_info_at(0);
    vv_world *w = vv_document_world(win->doc);
    for (int i = 0; i < info->n_options; i++) {
        const vv_option_spec *o = &info->options[i];
        char what[256];
        GtkWidget *e = gtk_entry_new();
        gtk_entry_set_placeholder_text(GTK_ENTRY(e), o->def[0] ? o->def : "default");
        char *tip =
            g_strdup_printf("%s (%s; default %s)", o->doc, vv_option_describe(o, what, sizeof what),
                            o->def[0] ? o->def : "none");
        gtk_widget_set_tooltip_text(e, tip);
        g_free(tip);
        for (int j = 0; j < w->render.n_options; j++)
            if (!strcmp(w->render.option_keys[j], o->key))
                gtk_editable_set_text(GTK_EDITABLE(e), w->render.option_values[j]);
        g_object_set_data_full(G_OBJECT(e), "key", g_strdup(o->key), g_free);
        g_signal_connect(e, "activate", G_CALLBACK(option_changed), win);
        vvg_row(win->options_box, o->key, e);
    }
}

static void
renderer_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    VvWindow *win = user;
    if (!win->updating) {
        guint sel = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->renderer));
        const vv_renderer_info *info = vv_renderer_info_at((int)sel);
        vv_world *w = vv_document_world(win->doc);
        if (info && strcmp(info->name, w->render.renderer)) {
            vv_document_begin_edit(win->doc, "renderer");
            g_strlcpy(w->render.renderer, info->name, sizeof w->render.renderer);
            w->render.n_options = 0; /* the options belong to the other renderer */
            vv_document_changed(win->doc);
        }
    }
    rebuild_options(win);
}

static void
quality_changed(GtkSpinButton *s, gpointer user) {
    VvWindow *win = user;
    if (win->updating)
        return;
    vv_document_begin_edit(win->doc, "quality");
    vv_document_world(win->doc)->render.quality = (int)gtk_spin_button_get_value(s);
    vv_document_changed(win->doc);
}

/* ---- Measurement page ------------------------------------------------------- */

static void
measure_print(VvWindow *win, const char *text) {
    GtkTextBuffer *b = gtk_text_view_get_buffer(GTK_TEXT_VIEW(win->measure_text));
    GtkTextIter end;
    gtk_text_buffer_get_end_iter(b, &end);
    gtk_text_buffer_insert(b, &end, text, -1);
}

static void
hist_draw(GtkDrawingArea *area, cairo_t *cr, int W, int H, gpointer user) {
    (void)area;
    VvWindow *win = user;
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    if (!win->hist)
        return;
    gboolean lg = gtk_check_button_get_active(GTK_CHECK_BUTTON(win->hist_log));
    double mx = 1;
    for (int i = 0; i < win->hist->nbins; i++) {
        double c = lg ? log10(1.0 + (double)win->hist->counts[i]) : (double)win->hist->counts[i];
        mx = c > mx ? c : mx;
    }
    cairo_set_source_rgb(cr, 0.2, 0.3, 0.6);
    for (int i = 0; i < win->hist->nbins; i++) {
        double c = lg ? log10(1.0 + (double)win->hist->counts[i]) : (double)win->hist->counts[i];
        double h = c / mx * (H - 4);
        cairo_rectangle(cr, (double)i * W / win->hist->nbins, H - h, (double)W / win->hist->nbins,
                        h);
    }
    cairo_fill(cr);
}

static void
act_histogram(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_object *o = vv_document_selected_object(win->doc);
    if (!o || !o->volume) {
        show_error(win, "No histogram", "select a volume object first");
        return;
    }
    vv_histogram_free(win->hist);
    win->hist = NULL;
    vv_error_clear();
    if (vv_measure_histogram(&win->hist, o->volume, 128, 0, 0, NULL) != VV_OK) {
        show_error(win, "Histogram failed", vv_error_message());
        return;
    }
    char t[256];
    snprintf(t, sizeof t, "histogram of %s: %llu voxels, min %g, max %g, mean %g, sd %g\n", o->name,
             (unsigned long long)win->hist->total, win->hist->min, win->hist->max, win->hist->mean,
             win->hist->sd);
    measure_print(win, t);
    gtk_widget_queue_draw(win->histogram);
}

typedef struct measure_job {
    vv_volume *volume;
    double iso;
    vv_isosurface_measure_options opt;
    vv_isosurface_measure result;
    char name[VV_NAME_MAX];
    vv_status status;
    char error[512];
} measure_job;

static void
measure_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    measure_job *j = data;
    vv_error_clear();
    j->status = vv_measure_isosurface(&j->result, j->volume, j->iso, &j->opt);
    if (j->status != VV_OK)
        g_strlcpy(j->error, vv_error_message(), sizeof j->error);
}

static void
measure_job_free(gpointer p) {
    measure_job *j = p;
    vv_volume_free(j->volume);
    g_free(j);
}

static void
measure_done(GObject *src, GAsyncResult *res, gpointer user) {
    (void)user;
    VvWindow *win = VV_WINDOW(src);
    measure_job *j = g_task_get_task_data(G_TASK(res));
    if (j->status != VV_OK) {
        show_error(win, "Measurement failed", j->error);
        return;
    }
    const char *u = vv_unit_name(j->result.unit);
    char t[512];
    snprintf(t, sizeof t,
             "%s isovalue %g (%s%s): area %.6g %s^2, volume %.6g %s^3, %llu voxels, %zu "
             "triangles\n",
             j->name, j->iso, j->result.method == VV_MEASURE_MC ? "marching cubes" : "voxel count",
             j->opt.has_seed ? ", surface-tracked" : "", j->result.area, u, j->result.volume, u,
             (unsigned long long)j->result.voxels, j->result.n_triangles);
    measure_print(win, t);
}

static void
act_measure(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_object *o = vv_document_selected_object(win->doc);
    if (!o) {
        show_error(win, "Nothing to measure", "select an object first");
        return;
    }
    if (o->type == VV_OBJECT_MESH) {
        double vol = 0;
        vv_error_clear();
        vv_status s = vv_measure_mesh_volume(o->geometry.mesh, &vol);
        char t[256];
        snprintf(t, sizeof t, "%s mesh: area %.6g, volume %s%.6g\n", o->name,
                 vv_mesh_area(o->geometry.mesh), s == VV_OK ? "" : "(open mesh) ",
                 s == VV_OK ? vol : NAN);
        measure_print(win, t);
        return;
    }
    if (!o->volume)
        return;
    measure_job *j = g_new0(measure_job, 1);
    j->volume = vv_volume_ref(o->volume);
    j->iso = spin_value(win->measure_iso);
    g_strlcpy(j->name, o->name, sizeof j->name);
    vv_isosurface_measure_options_init(&j->opt);
    j->opt.method = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->measure_method)) == 1
                        ? VV_MEASURE_VOXEL
                        : VV_MEASURE_MC;
    if (gtk_check_button_get_active(GTK_CHECK_BUTTON(win->measure_seed))) {
        j->opt.has_seed = 1;
        j->opt.seed[0] = spin_value(win->seed_i);
        j->opt.seed[1] = spin_value(win->seed_j);
        j->opt.seed[2] = spin_value(win->seed_k);
    }
    GTask *task = g_task_new(win, NULL, measure_done, NULL);
    g_task_set_task_data(task, j, measure_job_free);
    g_task_run_in_thread(task, measure_thread);
    g_object_unref(task);
}

/* Picking in the view: the next click sets the seed voxel or a point. */
static void
picked_seed(gpointer user, vv_vec3 p) {
    VvWindow *win = user;
    vv_object *o = vv_document_selected_object(win->doc);
    if (!o || !o->volume)
        return;
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(vv_object_index_to_world(o), &ok);
    if (!ok)
        return;
    vv_vec3 ijk = vv_mat4_mul_point(inv, p);
    set_spin(win->seed_i, round(ijk.x));
    set_spin(win->seed_j, round(ijk.y));
    set_spin(win->seed_k, round(ijk.z));
    gtk_check_button_set_active(GTK_CHECK_BUTTON(win->measure_seed), TRUE);
    char t[160];
    snprintf(t, sizeof t, "picked voxel (%.0f, %.0f, %.0f) at world (%g, %g, %g)\n", round(ijk.x),
             round(ijk.y), round(ijk.z), p.x, p.y, p.z);
    measure_print(win, t);
}

static void
picked_a(gpointer user, vv_vec3 p) {
    VvWindow *win = user;
    set_spin(win->pa[0], p.x);
    set_spin(win->pa[1], p.y);
    set_spin(win->pa[2], p.z);
}

static void
picked_b(gpointer user, vv_vec3 p) {
    VvWindow *win = user;
    set_spin(win->pb[0], p.x);
    set_spin(win->pb[1], p.y);
    set_spin(win->pb[2], p.z);
}

static void
act_pick_seed(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vv_scene_view_pick_next(VV_WINDOW(user)->scene, picked_seed, user);
}

static void
act_pick_a(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vv_scene_view_pick_next(VV_WINDOW(user)->scene, picked_a, user);
}

static void
act_pick_b(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    vv_scene_view_pick_next(VV_WINDOW(user)->scene, picked_b, user);
}

static void
act_distance(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    vv_vec3 pa =
        vv_vec3_make(spin_value(win->pa[0]), spin_value(win->pa[1]), spin_value(win->pa[2]));
    vv_vec3 pb =
        vv_vec3_make(spin_value(win->pb[0]), spin_value(win->pb[1]), spin_value(win->pb[2]));
    char t[256];
    snprintf(t, sizeof t, "distance (%g, %g, %g) - (%g, %g, %g): %.6g world units\n", pa.x, pa.y,
             pa.z, pb.x, pb.y, pb.z, vv_vec3_length(vv_vec3_sub(pa, pb)));
    measure_print(win, t);
}

/* ---- Modeling page ------------------------------------------------------------ */

/*
 * How an object of the Modeling page was made, so that CSG can rebuild both
 * operands as shapes (vv_shape_csg takes its children): a primitive or a mesh
 * file with its placement, or a CSG of two recipes. Kept per volume made
 * (the volume's address; the object may be renamed, moved in the list or
 * copied by undo, and keeps its volume).
 */
typedef struct model_recipe {
    int kind; /* index of prim_names; PRIM_MESH: a mesh file; PRIM_CSG: op of a and b */
    double size;
    char *mesh;
    vv_vec3 position;
    int axis;     /* 0 x, 1 y, 2 z */
    double angle; /* degrees */
    vv_csg_op op;
    struct model_recipe *a, *b;
} model_recipe;

static const char *const prim_names[] = {"sphere", "box",       "torus", "cylinder",
                                         "cone",   "mesh file", NULL};
#define PRIM_MESH 5
#define PRIM_CSG 6

static void
recipe_free(gpointer p) {
    model_recipe *r = p;
    if (!r)
        return;
    g_free(r->mesh);
    recipe_free(r->a);
    recipe_free(r->b);
    g_free(r);
}

static model_recipe *
recipe_copy(const model_recipe *r) {
    if (!r)
        return NULL;
    model_recipe *c = g_new(model_recipe, 1);
    *c = *r;
    c->mesh = g_strdup(r->mesh);
    c->a = recipe_copy(r->a);
    c->b = recipe_copy(r->b);
    return c;
}

/* A fresh shape tree for @p r (caller frees). */
static vv_status
recipe_shape(const model_recipe *r, vv_shape **out) {
    *out = NULL;
    vv_status st;
    double h = r->size / 2;
    switch (r->kind) {
    case 0:
        st = vv_shape_sphere(out, h);
        break;
    case 1:
        st = vv_shape_box(out, vv_vec3_make(r->size, r->size, r->size), 0.1 * h);
        break;
    case 2:
        st = vv_shape_torus(out, 0.7 * h, 0.25 * h);
        break;
    case 3:
        st = vv_shape_cylinder(out, 0.5 * h, r->size);
        break;
    case 4:
        st = vv_shape_cone(out, 0.6 * h, 0, r->size);
        break;
    case PRIM_MESH:
        st = vv_shape_mesh_load(out, r->mesh, VV_MESH_AUTO, 0);
        break;
    default: {
        vv_shape *kids[2] = {NULL, NULL};
        st = recipe_shape(r->a, &kids[0]);
        if (st == VV_OK)
            st = recipe_shape(r->b, &kids[1]);
        if (st != VV_OK) {
            vv_shape_free(kids[0]);
            vv_shape_free(kids[1]);
            return st;
        }
        return vv_shape_csg(out, r->op, 2, kids);
    }
    }
    if (st != VV_OK)
        return st;
    vv_vec3 ax = vv_vec3_make(r->axis == 0, r->axis == 1, r->axis == 2);
    vv_shape_transform(*out, vv_mat4_mul(vv_mat4_translate(r->position),
                                         vv_mat4_rotate(ax, vv_deg_to_rad(r->angle))));
    return VV_OK;
}

static char *
recipe_name(const model_recipe *r) {
    if (r->kind == PRIM_CSG)
        return g_strdup_printf("%s", vv_csg_op_name(r->op));
    if (r->kind == PRIM_MESH) {
        char *b = g_path_get_basename(r->mesh);
        char *dot = strrchr(b, '.');
        if (dot && dot != b)
            *dot = '\0';
        return b;
    }
    return g_strdup(prim_names[r->kind]);
}

typedef struct model_job {
    model_recipe *recipe;
    int res;
    vv_volume *result;
    vv_status status;
    char error[512];
    double fraction; /* atomic */
    VvWindow *win;
    const vv_volume *operands[2]; /* CSG: the volumes of A and B (compared only) */
} model_job;

static int
model_progress(void *user, double f) {
    model_job *j = user;
    __atomic_store(&j->fraction, &f, __ATOMIC_RELAXED);
    return 0;
}

static void
model_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    model_job *j = data;
    vv_shape *sh = NULL;
    vv_error_clear();
    j->status = recipe_shape(j->recipe, &sh);
    if (j->status == VV_OK) {
        vv_voxelize_options o;
        vv_voxelize_options_init(&o);
        o.size = j->res;
        o.progress.fn = model_progress;
        o.progress.user = j;
        j->status = vv_voxelize(&j->result, sh, &o);
    }
    if (j->status != VV_OK)
        g_strlcpy(j->error, vv_error_message(), sizeof j->error);
    vv_shape_free(sh);
}

static void
model_job_free(gpointer p) {
    model_job *j = p;
    vv_volume_free(j->result);
    recipe_free(j->recipe);
    g_free(j);
}

static gboolean
model_tick(gpointer user) {
    model_job *j = user;
    double f;
    __atomic_load(&j->fraction, &f, __ATOMIC_RELAXED);
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(j->win->model_progress), f);
    return G_SOURCE_CONTINUE;
}

static void rebuild_model_lists(VvWindow *win);

static void
model_done(GObject *src, GAsyncResult *res, gpointer user) {
    VvWindow *win = VV_WINDOW(src);
    g_source_remove(GPOINTER_TO_UINT(user));
    model_job *j = g_task_get_task_data(G_TASK(res));
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(win->model_progress), 1);
    if (j->status != VV_OK) {
        show_error(win, "Voxelization failed", j->error);
        return;
    }
    vv_object *o = NULL;
    char *name = recipe_name(j->recipe);
    vv_status st = vv_object_new_volume(&o, j->result, name);
    g_free(name);
    if (st != VV_OK) {
        show_error(win, "Voxelization failed", vv_error_message());
        return;
    }
    /* the density surface (127.5 of 255) as an opaque isosurface */
    o->mode = VV_MODE_ISO;
    o->isovalue = 127.5;
    if (!g_hash_table_contains(win->recipes, j->result))
        g_hash_table_insert(win->recipes, vv_volume_ref(j->result), recipe_copy(j->recipe));
    vv_world *w = vv_document_world(win->doc);
    gboolean first = w->n_objects == 0;
    vv_document_add_object(win->doc, o, NULL);
    /* a CSG result stands in for its operands: they are hidden (same undo step) */
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->volume &&
            (w->objects[i]->volume == j->operands[0] || w->objects[i]->volume == j->operands[1]))
            w->objects[i]->visible = 0;
    if (j->operands[0])
        vv_document_changed(win->doc);
    if (first) {
        if (w->n_lights == 0) {
            vv_light l = {VV_LIGHT_DIRECTIONAL, 1, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}, 1.0};
            vv_world_add_light(w, &l);
        }
        vv_view_frame_box(&w->view, vv_world_bounds(w));
        vv_document_changed(win->doc);
    }
    rebuild_model_lists(win);
}

static model_job *
start_model(VvWindow *win, model_recipe *r) {
    model_job *j = g_new0(model_job, 1);
    j->recipe = r;
    j->res = (int)spin_value(win->prim_res);
    j->win = win;
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(win->model_progress), 0);
    guint tick = g_timeout_add(100, model_tick, j);
    GTask *task = g_task_new(win, NULL, model_done, GUINT_TO_POINTER(tick));
    g_task_set_task_data(task, j, model_job_free);
    g_task_run_in_thread(task, model_thread);
    g_object_unref(task);
    return j;
}

static void
act_voxelize(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    model_recipe *r = g_new0(model_recipe, 1);
    r->kind = (int)gtk_drop_down_get_selected(GTK_DROP_DOWN(win->prim_kind));
    r->size = spin_value(win->prim_size);
    if (r->kind == PRIM_MESH) {
        const char *m = gtk_editable_get_text(GTK_EDITABLE(win->prim_mesh));
        if (!m[0]) {
            g_free(r);
            show_error(win, "No mesh file", "enter the mesh file to voxelize");
            return;
        }
        r->mesh = g_strdup(m);
    }
    r->position = vv_vec3_make(spin_value(win->prim_pos[0]), spin_value(win->prim_pos[1]),
                               spin_value(win->prim_pos[2]));
    r->axis = (int)gtk_drop_down_get_selected(GTK_DROP_DOWN(win->prim_axis));
    r->angle = spin_value(win->prim_angle);
    start_model(win, r);
}

/* The objects made on this page (their recipes), in World order, into the CSG lists. */
static void
rebuild_model_lists(VvWindow *win) {
    GtkStringList *names = gtk_string_list_new(NULL);
    g_ptr_array_set_size(win->model_volumes, 0);
    vv_world *w = vv_document_world(win->doc);
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->volume && g_hash_table_contains(win->recipes, o->volume)) {
            gtk_string_list_append(names, o->name);
            g_ptr_array_add(win->model_volumes, o->volume);
        }
    }
    gtk_drop_down_set_model(GTK_DROP_DOWN(win->csg_a), G_LIST_MODEL(names));
    gtk_drop_down_set_model(GTK_DROP_DOWN(win->csg_b), G_LIST_MODEL(names));
    if (g_list_model_get_n_items(G_LIST_MODEL(names)) > 1)
        gtk_drop_down_set_selected(GTK_DROP_DOWN(win->csg_b), 1);
    g_object_unref(names);
}

static void
act_csg(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvWindow *win = user;
    guint ia = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->csg_a));
    guint ib = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->csg_b));
    if (ia >= win->model_volumes->len || ib >= win->model_volumes->len) {
        show_error(win, "No CSG", "make two objects on this page first");
        return;
    }
    const model_recipe *ra = g_hash_table_lookup(win->recipes, win->model_volumes->pdata[ia]);
    const model_recipe *rb = g_hash_table_lookup(win->recipes, win->model_volumes->pdata[ib]);
    if (!ra || !rb)
        return;
    model_recipe *r = g_new0(model_recipe, 1);
    r->kind = PRIM_CSG;
    r->op = (vv_csg_op)gtk_drop_down_get_selected(GTK_DROP_DOWN(win->csg_op));
    r->a = recipe_copy(ra);
    r->b = recipe_copy(rb);
    model_job *j = start_model(win, r);
    j->operands[0] = win->model_volumes->pdata[ia];
    j->operands[1] = win->model_volumes->pdata[ib];
}

/* ---- pages -------------------------------------------------------------------- */

static GtkWidget *
scrolled(GtkWidget *child) {
    GtkWidget *s = gtk_scrolled_window_new();
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(s), GTK_POLICY_NEVER, GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_child(GTK_SCROLLED_WINDOW(s), child);
    gtk_widget_set_vexpand(s, TRUE);
    return s;
}

static GtkWidget *
page_box(void) {
    GtkWidget *b = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_widget_set_margin_start(b, 8);
    gtk_widget_set_margin_end(b, 8);
    gtk_widget_set_margin_bottom(b, 8);
    return b;
}

static GtkWidget *
action_button(const char *label, const char *action) {
    GtkWidget *b = gtk_button_new_with_label(label);
    gtk_actionable_set_action_name(GTK_ACTIONABLE(b), action);
    return b;
}

static void
target_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvWindow *win = user;
    vv_scene_view_set_target(win->scene, (VvNavTarget)gtk_drop_down_get_selected(GTK_DROP_DOWN(o)));
}

static void
preview_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvWindow *win = user;
    vv_scene_view_set_preview(win->scene, (int)gtk_drop_down_get_selected(GTK_DROP_DOWN(o)) - 1);
}

static void
delay_changed(GtkSpinButton *s, gpointer user) {
    VvWindow *win = user;
    vv_scene_view_set_refine_delay(win->scene, (int)gtk_spin_button_get_value(s));
}

static void
flight_toggled(GtkCheckButton *b, gpointer user) {
    VvWindow *win = user;
    vv_scene_view_set_flight(win->scene, gtk_check_button_get_active(b));
    gtk_widget_grab_focus(GTK_WIDGET(win->scene));
}

static void
light_index_changed(GtkSpinButton *s, gpointer user) {
    VvWindow *win = user;
    vv_scene_view_set_light(win->scene, (int)gtk_spin_button_get_value(s));
    if (!win->updating)
        fill_object_control(win);
}

static void
log_toggled(GtkCheckButton *b, gpointer user) {
    VvWindow *win = user;
    vv_tf_editor_set_log(win->tf_editor, gtk_check_button_get_active(b));
}

static void
tf_color_set(GtkColorButton *b, gpointer user) {
    VvWindow *win = user;
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(b), &c);
    vv_tf_editor_set_color(win->tf_editor, &c);
}

static void
preset_chosen(GObject *o, GParamSpec *p, gpointer user) {
    (void)p;
    VvWindow *win = user;
    guint i = gtk_drop_down_get_selected(GTK_DROP_DOWN(o));
    vv_object *obj = vv_document_selected_object(win->doc);
    if (win->updating || i == 0 || !obj || !obj->volume)
        return;
    const char *name = vv_tf_preset_names()[i - 1];
    vv_document_begin_edit(win->doc, "transfer-function preset");
    vv_error_clear();
    if (vv_tf_preset(&obj->tf, name, obj->volume) != VV_OK)
        show_error(win, "Cannot apply the preset", vv_error_message());
    obj->segmentation = VV_SEG_TRANSFER_FUNCTION;
    vv_document_changed(win->doc);
    fill_object_control(win);
}

static void
add_rectangle(GtkButton *b, gpointer user) {
    (void)b;
    VvWindow *win = user;
    vv_tf2d_editor_add(win->tf2d_editor, VV_TF2D_RECTANGLE);
    fill_object_control(win);
}

static void
add_triangle(GtkButton *b, gpointer user) {
    (void)b;
    VvWindow *win = user;
    vv_tf2d_editor_add(win->tf2d_editor, VV_TF2D_TRIANGLE);
    fill_object_control(win);
}

static void
w2d_style(GtkColorButton *b, gpointer user) {
    (void)b;
    VvWindow *win = user;
    if (win->updating)
        return;
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(win->w2d_color), &c);
    vv_tf2d_editor_set_style(win->tf2d_editor, &c, spin_value(win->w2d_opacity));
}

static void
w2d_style_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    w2d_style(NULL, user);
}

/* Applies the texture widgets to the selected object (one undo step). */
static void
texture_update(VvWindow *win, gboolean load_image) {
    vv_object *o = vv_document_selected_object(win->doc);
    if (win->updating || !o)
        return;
    vv_texture_image *img = NULL;
    const char *path = gtk_editable_get_text(GTK_EDITABLE(win->tex_file));
    if (load_image && path[0]) {
        vv_error_clear();
        if (vv_texture_image_load(&img, path, path) != VV_OK) {
            show_error(win, "Cannot load the texture", vv_error_message());
            return;
        }
    }
    vv_document_begin_edit(win->doc, "texture");
    if (load_image)
        vv_object_set_texture_image(o, img); /* NULL removes it */
    vv_texture_image_free(img);
    o->texture.projection =
        (vv_texture_projection)gtk_drop_down_get_selected(GTK_DROP_DOWN(win->tex_projection));
    o->texture.scale[0] = o->texture.scale[1] = spin_value(win->tex_scale);
    guint k = gtk_drop_down_get_selected(GTK_DROP_DOWN(win->solid_kind));
    if (o->solid_texture.kind == VV_SOLID_TEXTURE_VOLUME && k != VV_SOLID_TEXTURE_VOLUME)
        vv_solid_texture_clear(&o->solid_texture);
    o->solid_texture.kind = (vv_solid_texture_kind)k;
    o->solid_texture.period = spin_value(win->solid_period);
    if (o->solid_texture.kind != VV_SOLID_TEXTURE_NONE) {
        /* light and dark wood-like colours unless the scene set its own */
        vv_vec3 c0 = o->solid_texture.color0, c1 = o->solid_texture.color1;
        if (c0.x == 0 && c0.y == 0 && c0.z == 0 && c1.x == 1 && c1.y == 1 && c1.z == 1) {
            o->solid_texture.color0 = vv_vec3_make(0.95, 0.8, 0.6);
            o->solid_texture.color1 = vv_vec3_make(0.55, 0.35, 0.2);
        }
        if (o->volume) { /* centred on the volume */
            vv_object tmp = *o;
            tmp.position = vv_vec3_make(0, 0, 0);
            tmp.orientation = vv_quat_identity();
            tmp.scale = vv_vec3_make(1, 1, 1);
            vv_box b = vv_object_world_box(&tmp);
            o->solid_texture.center = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
        }
    }
    vv_document_changed(win->doc);
}

static void
texture_apply(GtkEntry *e, gpointer user) {
    (void)e;
    texture_update(user, TRUE);
}

static void
texture_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    texture_update(user, FALSE);
}

static void
texture_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    texture_update(user, FALSE);
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

static GtkWidget *
manipulation_page(VvWindow *win) {
    GtkWidget *box = page_box();
    GtkWidget *g;
    /* objects */
    GtkWidget *l = gtk_label_new(NULL);
    gtk_label_set_markup(GTK_LABEL(l), "<b>Objects</b>");
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_box_append(GTK_BOX(box), l);
    win->object_list = gtk_list_box_new();
    g_signal_connect(win->object_list, "row-selected", G_CALLBACK(row_selected), win);
    gtk_box_append(GTK_BOX(box), win->object_list);
    GtkWidget *ob = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(ob), action_button("Open…", "win.open"));
    gtk_box_append(GTK_BOX(ob), action_button("Delete", "win.delete-object"));
    gtk_box_append(GTK_BOX(ob), main_menu_button());
    gtk_box_append(GTK_BOX(box), ob);

    /* Navigator */
    g = vvg_section(box, "Navigator");
    static const char *const targets[] = {"view", "selected object", "selected light", "cut plane",
                                          NULL};
    GtkWidget *t = vvg_row(g, "drag moves", dropdown(targets));
    win->nav_target = t;
    g_signal_connect(t, "notify::selected", G_CALLBACK(target_changed), win);
    static const char *const previews[] = {
        "automatic",    "bounding boxes", "PARC boxes",   "coarse MC",
        "ray cast 1/4", "ray cast 1/2",   "full quality", NULL};
    GtkWidget *pv = vvg_row(g, "preview", dropdown(previews));
    g_signal_connect(pv, "notify::selected", G_CALLBACK(preview_changed), win);
    GtkWidget *dl = vvg_row(g, "refine after (ms)", spin(0, 2000, 10, 0));
    set_spin(dl, 100);
    g_signal_connect(dl, "value-changed", G_CALLBACK(delay_changed), win);
    GtkWidget *fl = gtk_check_button_new_with_label("flight simulator keys (arrows, Q/E, W/S)");
    g_signal_connect(fl, "toggled", G_CALLBACK(flight_toggled), win);
    gtk_grid_attach(GTK_GRID(g), fl, 0, vvg_grid_rows(g), 2, 1);

    /* segmentation */
    g = vvg_section(box, "Segmentation");
    /* in vv_segmentation's order; "labels": a label volume (Filtering) */
    static const char *const segs[] = {"transfer function", "threshold", "2-D transfer function",
                                       "labels", NULL};
    win->seg_mode = vvg_row(g, "by", wire_drop(win, dropdown(segs)));
    win->threshold = vvg_row(g, "threshold", wire_spin(win, spin(-1e9, 1e9, 1, 2)));
    static const char *const modes[] = {"composite", "MIP", "MinIP", "X-ray", "isosurface", NULL};
    win->render_mode = vvg_row(g, "mode", wire_drop(win, dropdown(modes)));
    win->isovalue = vvg_row(g, "isovalue", wire_spin(win, spin(-1e9, 1e9, 1, 2)));
    win->step = vvg_row(g, "sample step", wire_spin(win, spin(0.05, 8, 0.05, 2)));
    win->tf_editor = vv_tf_editor_new(win->doc);
    gtk_box_append(GTK_BOX(box), GTK_WIDGET(win->tf_editor));
    GtkWidget *tb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    GtkWidget *lg = gtk_check_button_new_with_label("log histogram");
    g_signal_connect(lg, "toggled", G_CALLBACK(log_toggled), win);
    GtkWidget *tc = gtk_color_button_new();
    gtk_widget_set_tooltip_text(tc, "colour of new colour points");
    g_signal_connect(tc, "color-set", G_CALLBACK(tf_color_set), win);
    gtk_box_append(GTK_BOX(tb), lg);
    gtk_box_append(GTK_BOX(tb), gtk_label_new("new colour"));
    gtk_box_append(GTK_BOX(tb), tc);
    gtk_box_append(GTK_BOX(box), tb);
    g = vvg_section(box, "Presets");
    GtkStringList *pn = gtk_string_list_new(NULL);
    gtk_string_list_append(pn, "(choose)");
    for (const char *const *n = vv_tf_preset_names(); *n; n++)
        gtk_string_list_append(pn, *n);
    win->preset = vvg_row(g, "transfer function", gtk_drop_down_new(G_LIST_MODEL(pn), NULL));
    g_signal_connect(win->preset, "notify::selected", G_CALLBACK(preset_chosen), win);

    /* 2-D transfer function over value x gradient magnitude */
    g = vvg_section(box, "2-D transfer function (value × gradient magnitude)");
    win->tf2d_editor = vv_tf2d_editor_new(win->doc);
    gtk_grid_attach(GTK_GRID(g), GTK_WIDGET(win->tf2d_editor), 0, 0, 2, 1);
    GtkWidget *wb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    GtkWidget *add_r = gtk_button_new_with_label("Add rectangle");
    GtkWidget *add_t = gtk_button_new_with_label("Add triangle");
    g_signal_connect(add_r, "clicked", G_CALLBACK(add_rectangle), win);
    g_signal_connect(add_t, "clicked", G_CALLBACK(add_triangle), win);
    gtk_box_append(GTK_BOX(wb), add_r);
    gtk_box_append(GTK_BOX(wb), add_t);
    gtk_grid_attach(GTK_GRID(g), wb, 0, 1, 2, 1);
    win->w2d_color = vvg_row(g, "widget colour", gtk_color_button_new());
    win->w2d_opacity = vvg_row(g, "widget opacity", spin(0, 1, 0.05, 2));
    set_spin(win->w2d_opacity, 0.5);
    g_signal_connect(win->w2d_color, "color-set", G_CALLBACK(w2d_style), win);
    g_signal_connect(win->w2d_opacity, "value-changed", G_CALLBACK(w2d_style_spin), win);

    /* placement, numerically (the Navigator moves it too) */
    g = vvg_section(box, "Placement of the object (world units)");
    const char *posn[] = {"position x", "position y", "position z"};
    for (int i = 0; i < 3; i++) {
        win->obj_pos[i] = vvg_row(g, posn[i], spin(-1e6, 1e6, 1, 3));
        g_signal_connect(win->obj_pos[i], "value-changed", G_CALLBACK(on_placement), win);
    }
    win->obj_scale = vvg_row(g, "scale", spin(1e-3, 1e3, 0.1, 3));
    g_signal_connect(win->obj_scale, "value-changed", G_CALLBACK(on_placement), win);

    /* material */
    g = vvg_section(box, "Colour and material");
    win->color = vvg_row(g, "colour", wire_color(win));
    win->ambient = vvg_row(g, "ambient", wire_spin(win, spin(0, 1, 0.05, 2)));
    win->diffuse = vvg_row(g, "diffuse", wire_spin(win, spin(0, 1, 0.05, 2)));
    win->specular = vvg_row(g, "specular", wire_spin(win, spin(0, 1, 0.05, 2)));
    win->shininess = vvg_row(g, "shininess", wire_spin(win, spin(1, 256, 1, 0)));
    win->reflectance = vvg_row(g, "reflectance", wire_spin(win, spin(0, 1, 0.05, 2)));
    win->transparency = vvg_row(g, "transparency", wire_spin(win, spin(0, 1, 0.05, 2)));

    /* textures */
    g = vvg_section(box, "Texture");
    win->tex_file = vvg_row(g, "image (PNG)", gtk_entry_new());
    gtk_entry_set_placeholder_text(GTK_ENTRY(win->tex_file), "path, Enter to apply; empty: none");
    g_signal_connect(win->tex_file, "activate", G_CALLBACK(texture_apply), win);
    static const char *const projections[] = {"planar", "cylindrical", "spherical", NULL};
    win->tex_projection = vvg_row(g, "projection", dropdown(projections));
    win->tex_scale = vvg_row(g, "repeats", spin(0.01, 1000, 0.5, 2));
    set_spin(win->tex_scale, 1);
    g_signal_connect(win->tex_projection, "notify::selected", G_CALLBACK(texture_changed), win);
    g_signal_connect(win->tex_scale, "value-changed", G_CALLBACK(texture_spin), win);
    static const char *const solids[] = {"none", "checker", "wood", "marble", NULL};
    win->solid_kind = vvg_row(g, "solid texture", dropdown(solids));
    win->solid_period = vvg_row(g, "period (world units)", spin(0.01, 1e5, 1, 2));
    set_spin(win->solid_period, 10);
    g_signal_connect(win->solid_kind, "notify::selected", G_CALLBACK(texture_changed), win);
    g_signal_connect(win->solid_period, "value-changed", G_CALLBACK(texture_spin), win);

    /* shading */
    g = vvg_section(box, "Shading");
    win->shading = wire_check(win, "Phong shading from gradients");
    win->casts = wire_check(win, "casts shadows");
    win->receives = wire_check(win, "receives shadows");
    win->in_reflections = wire_check(win, "visible in reflections");
    win->reflects = wire_check(win, "reflects");
    GtkWidget *checks[] = {win->shading, win->casts, win->receives, win->in_reflections,
                           win->reflects};
    for (int i = 0; i < 5; i++)
        gtk_grid_attach(GTK_GRID(g), checks[i], 0, i, 2, 1);

    /* cut planes */
    g = vvg_section(box, "Cut planes");
    static const char *const scopes[] = {"global", "selected object", NULL};
    win->cut_scope = vvg_row(g, "scope", dropdown(scopes));
    win->cut_px = vvg_row(g, "point x", spin(-1e6, 1e6, 1, 2));
    win->cut_py = vvg_row(g, "point y", spin(-1e6, 1e6, 1, 2));
    win->cut_pz = vvg_row(g, "point z", spin(-1e6, 1e6, 1, 2));
    win->cut_nx = vvg_row(g, "normal x", spin(-1, 1, 0.1, 3));
    win->cut_ny = vvg_row(g, "normal y", spin(-1, 1, 0.1, 3));
    win->cut_nz = vvg_row(g, "normal z", spin(-1, 1, 0.1, 3));
    set_spin(win->cut_nz, 1);
    GtkWidget *cb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(cb), action_button("Add cut plane", "win.add-cut-plane"));
    gtk_box_append(GTK_BOX(cb), action_button("Remove all", "win.clear-cut-planes"));
    gtk_box_append(GTK_BOX(box), cb);

    /* lights */
    g = vvg_section(box, "Lights");
    win->light_index = vvg_row(g, "light", spin(0, 0, 1, 0));
    g_signal_connect(win->light_index, "value-changed", G_CALLBACK(light_index_changed), win);
    static const char *const ltypes[] = {"directional", "point", "headlight", NULL};
    win->light_type = vvg_row(g, "type", wire_drop(win, dropdown(ltypes)));
    win->light_color = vvg_row(g, "colour", wire_color(win));
    win->light_intensity = vvg_row(g, "intensity", wire_spin(win, spin(0, 10, 0.1, 2)));
    win->ambient_color = vvg_row(g, "ambient light", wire_color(win));
    win->background_color = vvg_row(g, "background", wire_color(win));
    GtkWidget *lb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(lb), action_button("Add light", "win.add-light"));
    gtk_box_append(GTK_BOX(lb), action_button("Remove light", "win.remove-light"));
    gtk_box_append(GTK_BOX(box), lb);

    /* view */
    g = vvg_section(box, "View");
    const char *en[] = {"eye x", "eye y", "eye z"}, *an[] = {"look at x", "look at y", "look at z"};
    for (int i = 0; i < 3; i++) {
        win->eye[i] = vvg_row(g, en[i], spin(-1e7, 1e7, 1, 3));
        g_signal_connect(win->eye[i], "value-changed", G_CALLBACK(on_placement), win);
    }
    for (int i = 0; i < 3; i++) {
        win->at[i] = vvg_row(g, an[i], spin(-1e7, 1e7, 1, 3));
        g_signal_connect(win->at[i], "value-changed", G_CALLBACK(on_placement), win);
    }
    win->view_width = vvg_row(g, "image width", wire_spin(win, spin(16, 4096, 16, 0)));
    win->view_height = vvg_row(g, "image height", wire_spin(win, spin(16, 4096, 16, 0)));
    win->view_fov = vvg_row(g, "field of view (°)", wire_spin(win, spin(1, 170, 1, 1)));
    static const char *const projs[] = {"perspective", "orthographic", NULL};
    win->view_projection = vvg_row(g, "projection", wire_drop(win, dropdown(projs)));
    GtkWidget *vb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(vb), action_button("Front", "win.view-front"));
    gtk_box_append(GTK_BOX(vb), action_button("Side", "win.view-side"));
    gtk_box_append(GTK_BOX(vb), action_button("Top", "win.view-top"));
    gtk_box_append(GTK_BOX(vb), action_button("Reset", "win.view-reset"));
    gtk_box_append(GTK_BOX(box), vb);
    return scrolled(box);
}

static GtkWidget *
rendering_page(VvWindow *win) {
    GtkWidget *box = page_box();
    GtkWidget *g = vvg_section(box, "Renderer");
    GtkStringList *names = gtk_string_list_new(NULL);
    for (int i = 0; i < vv_renderer_count(); i++)
        gtk_string_list_append(names, vv_renderer_info_at(i)->name);
    win->renderer = vvg_row(g, "method", gtk_drop_down_new(G_LIST_MODEL(names), NULL));
    g_signal_connect(win->renderer, "notify::selected", G_CALLBACK(renderer_changed), win);
    win->quality = vvg_row(g, "quality", spin(0, 2, 1, 0));
    g_signal_connect(win->quality, "value-changed", G_CALLBACK(quality_changed), win);
    win->options_box = vvg_section(box, "Options (Enter to apply; empty: default)");
    gtk_box_append(GTK_BOX(box), action_button("Render…", "win.render"));
    return scrolled(box);
}

static void
hist_log_toggled(GtkCheckButton *b, gpointer user) {
    (void)b;
    gtk_widget_queue_draw(VV_WINDOW(user)->histogram);
}

static GtkWidget *
measurement_page(VvWindow *win) {
    GtkWidget *box = page_box();
    vvg_section(box, "Histogram");
    win->histogram = gtk_drawing_area_new();
    gtk_widget_set_size_request(win->histogram, 280, 120);
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(win->histogram), hist_draw, win, NULL);
    gtk_box_append(GTK_BOX(box), win->histogram);
    win->hist_log = gtk_check_button_new_with_label("log scale");
    g_signal_connect(win->hist_log, "toggled", G_CALLBACK(hist_log_toggled), win);
    gtk_box_append(GTK_BOX(box), win->hist_log);
    gtk_box_append(GTK_BOX(box), action_button("Histogram", "win.histogram"));
    GtkWidget *g = vvg_section(box, "Isosurface area and volume");
    win->measure_iso = vvg_row(g, "isovalue", spin(-1e9, 1e9, 1, 2));
    static const char *const methods[] = {"marching cubes", "voxel counting", NULL};
    win->measure_method = vvg_row(g, "method", dropdown(methods));
    win->measure_seed = gtk_check_button_new_with_label("surface-tracked from voxel");
    gtk_grid_attach(GTK_GRID(g), win->measure_seed, 0, vvg_grid_rows(g), 2, 1);
    win->seed_i = vvg_row(g, "i", spin(0, 1e5, 1, 0));
    win->seed_j = vvg_row(g, "j", spin(0, 1e5, 1, 0));
    win->seed_k = vvg_row(g, "k", spin(0, 1e5, 1, 0));
    gtk_box_append(GTK_BOX(box), action_button("Pick the seed voxel in the view", "win.pick-seed"));
    gtk_box_append(GTK_BOX(box), action_button("Measure", "win.measure"));
    g = vvg_section(box, "Distance (world units)");
    const char *ax[] = {"A x", "A y", "A z", "B x", "B y", "B z"};
    for (int i = 0; i < 3; i++)
        win->pa[i] = vvg_row(g, ax[i], spin(-1e6, 1e6, 1, 3));
    for (int i = 0; i < 3; i++)
        win->pb[i] = vvg_row(g, ax[3 + i], spin(-1e6, 1e6, 1, 3));
    GtkWidget *pb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(pb), action_button("Pick A", "win.pick-a"));
    gtk_box_append(GTK_BOX(pb), action_button("Pick B", "win.pick-b"));
    gtk_box_append(GTK_BOX(box), pb);
    gtk_box_append(GTK_BOX(box), action_button("Distance", "win.distance"));
    vvg_section(box, "Results (select and copy)");
    win->measure_text = gtk_text_view_new();
    gtk_text_view_set_editable(GTK_TEXT_VIEW(win->measure_text), FALSE);
    gtk_text_view_set_wrap_mode(GTK_TEXT_VIEW(win->measure_text), GTK_WRAP_WORD_CHAR);
    gtk_widget_set_size_request(win->measure_text, -1, 160);
    gtk_box_append(GTK_BOX(box), win->measure_text);
    return scrolled(box);
}

static void
model_doc_changed(VvDocument *doc, gpointer user) {
    (void)doc;
    VvWindow *win = user;
    /* names and objects change with renames, deletes and undo */
    vv_world *w = vv_document_world(win->doc);
    guint n = 0;
    for (int i = 0; i < w->n_objects; i++)
        n += w->objects[i]->volume && g_hash_table_contains(win->recipes, w->objects[i]->volume);
    if (n != win->model_volumes->len)
        rebuild_model_lists(win);
}

static GtkWidget *
modeling_page(VvWindow *win) {
    GtkWidget *box = page_box();
    GtkWidget *g = vvg_section(box, "Voxelized primitive or mesh (volume sampling)");
    win->prim_kind = vvg_row(g, "model", dropdown(prim_names));
    win->prim_size = vvg_row(g, "size (world units)", spin(0.1, 1e5, 1, 2));
    set_spin(win->prim_size, 100);
    win->prim_mesh = vvg_row(g, "mesh file", gtk_entry_new());
    gtk_entry_set_placeholder_text(GTK_ENTRY(win->prim_mesh), "OBJ, PLY, STL, OFF, ...");
    const char *axes[] = {"position x", "position y", "position z"};
    for (int i = 0; i < 3; i++)
        win->prim_pos[i] = vvg_row(g, axes[i], spin(-1e5, 1e5, 1, 2));
    static const char *const rot_axes[] = {"x", "y", "z", NULL};
    win->prim_axis = vvg_row(g, "rotation axis", dropdown(rot_axes));
    gtk_drop_down_set_selected(GTK_DROP_DOWN(win->prim_axis), 2);
    win->prim_angle = vvg_row(g, "rotation (°)", spin(-360, 360, 5, 1));
    win->prim_res = vvg_row(g, "voxels on the longest axis", spin(8, 1024, 8, 0));
    set_spin(win->prim_res, 128);
    gtk_box_append(GTK_BOX(box), action_button("Add", "win.voxelize"));
    g = vvg_section(box, "CSG of two objects made here");
    win->csg_a = vvg_row(g, "A", gtk_drop_down_new(NULL, NULL));
    static const char *const ops[] = {"union", "intersection", "difference (A - B)", NULL};
    win->csg_op = vvg_row(g, "operation", dropdown(ops));
    win->csg_b = vvg_row(g, "B", gtk_drop_down_new(NULL, NULL));
    gtk_box_append(GTK_BOX(box), action_button("Combine", "win.csg"));
    win->model_progress = gtk_progress_bar_new();
    gtk_box_append(GTK_BOX(box), win->model_progress);
    return scrolled(box);
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
    vv_histogram_free(win->hist);
    win->hist = NULL;
    if (win->placement_source) {
        g_source_remove(win->placement_source);
        win->placement_source = 0;
    }
    g_clear_pointer(&win->recipes, g_hash_table_destroy);
    g_clear_pointer(&win->model_volumes, g_ptr_array_unref);
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
    gtk_drop_down_set_selected(GTK_DROP_DOWN(win->nav_target), k);
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
    {"add-light", act_add_light, NULL, NULL, NULL, {0}},
    {"remove-light", act_remove_light, NULL, NULL, NULL, {0}},
    {"add-cut-plane", act_add_cut, NULL, NULL, NULL, {0}},
    {"clear-cut-planes", act_clear_cuts, NULL, NULL, NULL, {0}},
    {"histogram", act_histogram, NULL, NULL, NULL, {0}},
    {"measure", act_measure, NULL, NULL, NULL, {0}},
    {"distance", act_distance, NULL, NULL, NULL, {0}},
    {"pick-seed", act_pick_seed, NULL, NULL, NULL, {0}},
    {"drag-target", act_drag_target, "s", NULL, NULL, {0}},
    {"pick-a", act_pick_a, NULL, NULL, NULL, {0}},
    {"pick-b", act_pick_b, NULL, NULL, NULL, {0}},
    {"voxelize", act_voxelize, NULL, NULL, NULL, {0}},
    {"csg", act_csg, NULL, NULL, NULL, {0}},
};

static void
vv_window_init(VvWindow *win) {
    win->doc = vv_document_new();
    /* a reference is held on each key so that an address is never reused */
    win->recipes = g_hash_table_new_full(g_direct_hash, g_direct_equal,
                                         (GDestroyNotify)vv_volume_free, recipe_free);
    win->model_volumes = g_ptr_array_new();
    g_action_map_add_action_entries(G_ACTION_MAP(win), win_actions, G_N_ELEMENTS(win_actions), win);
    win->scene = vv_scene_view_new(win->doc);

    GtkWidget *stack = gtk_stack_new();
    gtk_stack_add_titled(GTK_STACK(stack), manipulation_page(win), "manipulation", "Manipulation");
    gtk_stack_add_titled(GTK_STACK(stack), rendering_page(win), "rendering", "Rendering");
    gtk_stack_add_titled(GTK_STACK(stack), measurement_page(win), "measurement", "Measurement");
    gtk_stack_add_titled(GTK_STACK(stack), modeling_page(win), "modeling", "Modeling");
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
    g_signal_connect(win->doc, "selection-changed", G_CALLBACK(selection_changed), win);
    g_signal_connect(win->doc, "changed", G_CALLBACK(model_doc_changed), win);
    rebuild_object_list(win);
    fill_object_control(win);
    rebuild_options(win);
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
