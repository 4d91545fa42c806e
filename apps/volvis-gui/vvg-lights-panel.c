/* VvgLightsPanel: lights, ambient light and background (vvg-lights-panel.h). */
#include "vvg-lights-panel.h"
#include "vvg-widgets.h"

#include <string.h>

struct _VvgLightsPanel {
    GtkBox parent;
    VvgDocument *doc;
    VvgSceneView *scene; /* borrowed */
    gboolean updating;
    GtkWidget *light_index, *light_type, *light_color, *light_intensity;
    GtkWidget *ambient_color, *background_color;
};

G_DEFINE_TYPE(VvgLightsPanel, vvg_lights_panel, GTK_TYPE_BOX)

static void
fill(VvgLightsPanel *self) {
    self->updating = TRUE;
    vv_world *w = vvg_document_world(self->doc);
    int li = (int)vvg_spin_value(self->light_index);
    gtk_spin_button_set_range(GTK_SPIN_BUTTON(self->light_index), 0,
                              w->n_lights > 0 ? w->n_lights - 1 : 0);
    li = (int)vvg_spin_value(self->light_index);
    vvg_scene_view_set_light(self->scene, li);
    if (li < w->n_lights) {
        gtk_drop_down_set_selected(GTK_DROP_DOWN(self->light_type),
                                   w->lights[li].headlight ? 2u : (guint)w->lights[li].type);
        GdkRGBA c = vvg_rgba(w->lights[li].color);
        gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(self->light_color), &c);
        vvg_set_spin(self->light_intensity, w->lights[li].intensity);
    }
    GdkRGBA a = vvg_rgba(w->ambient), b = vvg_rgba(w->background);
    gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(self->ambient_color), &a);
    gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(self->background_color), &b);
    self->updating = FALSE;
}

static void
apply(VvgLightsPanel *self, const char *label) {
    if (self->updating)
        return;
    vv_world *w = vvg_document_world(self->doc);
    vvg_document_begin_edit(self->doc, label);
    int li = (int)vvg_spin_value(self->light_index);
    if (li < w->n_lights) {
        vv_light *l = &w->lights[li];
        guint t = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->light_type));
        l->headlight = t == 2;
        l->type = t == 1 ? VV_LIGHT_POINT : VV_LIGHT_DIRECTIONAL;
        GdkRGBA c;
        gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(self->light_color), &c);
        l->color = vvg_vec3(&c);
        l->intensity = vvg_spin_value(self->light_intensity);
    }
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(self->ambient_color), &c);
    w->ambient = vvg_vec3(&c);
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(self->background_color), &c);
    w->background = vvg_vec3(&c);
    vvg_document_changed(self->doc);
}

static void
on_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    apply(user, "light");
}

static void
on_dropdown(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    apply(user, "light");
}

static void
on_color(GtkColorButton *b, gpointer user) {
    (void)b;
    apply(user, "edit colour");
}

static void
light_index_changed(GtkSpinButton *s, gpointer user) {
    VvgLightsPanel *self = user;
    vvg_scene_view_set_light(self->scene, (int)gtk_spin_button_get_value(s));
    if (!self->updating)
        fill(self);
}

static void
act_add_light(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgLightsPanel *self = user;
    vv_world *w = vvg_document_world(self->doc);
    vvg_document_begin_edit(self->doc, "add light");
    vv_box b = vv_world_bounds(w);
    vv_light l = {VV_LIGHT_POINT, 0, {0, 1, 0}, b.max, {1, 1, 1}, 0.5};
    if (vv_world_add_light(w, &l) != VV_OK)
        vvg_show_error(GTK_WIDGET(self), "Cannot add a light", vv_error_message());
    fill(self);
    vvg_set_spin(self->light_index, w->n_lights - 1);
    vvg_document_changed(self->doc);
}

static void
act_remove_light(GSimpleAction *a, GVariant *p, gpointer user) {
    (void)a;
    (void)p;
    VvgLightsPanel *self = user;
    vv_world *w = vvg_document_world(self->doc);
    int li = (int)vvg_spin_value(self->light_index);
    if (li >= w->n_lights)
        return;
    vvg_document_begin_edit(self->doc, "remove light");
    memmove(&w->lights[li], &w->lights[li + 1],
            (size_t)(w->n_lights - li - 1) * sizeof w->lights[0]);
    w->n_lights--;
    vvg_document_changed(self->doc);
    fill(self);
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    fill(user);
}

static void
vvg_lights_panel_dispose(GObject *o) {
    VvgLightsPanel *self = VVG_LIGHTS_PANEL(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    G_OBJECT_CLASS(vvg_lights_panel_parent_class)->dispose(o);
}

static void
vvg_lights_panel_class_init(VvgLightsPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_lights_panel_dispose;
}

static void
vvg_lights_panel_init(VvgLightsPanel *self) {
    vvg_vbox_init(GTK_WIDGET(self));
}

static GtkWidget *
color_button(VvgLightsPanel *self) {
    GtkWidget *b = gtk_color_button_new();
    g_signal_connect(b, "color-set", G_CALLBACK(on_color), self);
    return b;
}

GtkWidget *
vvg_lights_panel_new(VvgDocument *doc, VvgSceneView *scene, GActionMap *actions) {
    VvgLightsPanel *self = g_object_new(VVG_TYPE_LIGHTS_PANEL, NULL);
    self->doc = g_object_ref(doc);
    self->scene = scene;
    const GActionEntry entries[] = {
        {"add-light", act_add_light, NULL, NULL, NULL, {0}},
        {"remove-light", act_remove_light, NULL, NULL, NULL, {0}},
    };
    g_action_map_add_action_entries(actions, entries, G_N_ELEMENTS(entries), self);
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "Lights");
    self->light_index = vvg_row(g, "light", vvg_spin0(0, 0, 1, 0));
    g_signal_connect(self->light_index, "value-changed", G_CALLBACK(light_index_changed), self);
    static const char *const ltypes[] = {"directional", "point", "headlight", NULL};
    self->light_type = vvg_row(g, "type", gtk_drop_down_new_from_strings(ltypes));
    g_signal_connect(self->light_type, "notify::selected", G_CALLBACK(on_dropdown), self);
    self->light_color = vvg_row(g, "colour", color_button(self));
    self->light_intensity = vvg_row(g, "intensity", vvg_spin0(0, 10, 0.1, 2));
    g_signal_connect(self->light_intensity, "value-changed", G_CALLBACK(on_spin), self);
    self->ambient_color = vvg_row(g, "ambient light", color_button(self));
    self->background_color = vvg_row(g, "background", color_button(self));
    GtkWidget *lb = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(lb), vvg_action_button("Add light", "win.add-light"));
    gtk_box_append(GTK_BOX(lb), vvg_action_button("Remove light", "win.remove-light"));
    gtk_box_append(GTK_BOX(self), lb);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), self);
    fill(self);
    return GTK_WIDGET(self);
}
