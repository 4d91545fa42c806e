/* VvgObjectPanel: placement, material, textures and shading flags (vvg-object-panel.h). */
#include "vvg-object-panel.h"
#include "vvg-widgets.h"

#include <math.h>

struct _VvgObjectPanel {
    GtkBox parent;
    VvgDocument *doc;
    gboolean updating; /* set while widgets are filled from the World */
    guint placement_source;
    GtkWidget *obj_pos[3], *obj_scale, *up_axis;
    GtkWidget *color, *ambient, *diffuse, *specular, *shininess, *reflectance, *transparency;
    GtkWidget *tex_file, *tex_projection, *tex_scale, *solid_kind, *solid_period;
    GtkWidget *shading, *casts, *receives, *in_reflections, *reflects;
};

G_DEFINE_TYPE(VvgObjectPanel, vvg_object_panel, GTK_TYPE_BOX)

/* The numbers the Navigator changes, refreshed on every change of the World. */
static void
fill_placement(VvgObjectPanel *self) {
    gboolean was = self->updating;
    self->updating = TRUE;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (o) {
        double pv[3] = {o->position.x, o->position.y, o->position.z};
        for (int i = 0; i < 3; i++)
            vvg_set_spin(self->obj_pos[i], pv[i]);
        vvg_set_spin(self->obj_scale, o->scale.x);
        /* the up axis: as stored, turned from Y-up, or some other turn */
        vv_quat q = vv_quat_normalize(o->orientation);
        vv_quat y_up = vv_quat_from_axis_angle(vv_vec3_make(1, 0, 0), VV_PI / 2);
        double dz = fabs(fabs(q.w) - 1);
        double dy = 1 - fabs(q.w * y_up.w + q.x * y_up.x + q.y * y_up.y + q.z * y_up.z);
        gtk_drop_down_set_selected(GTK_DROP_DOWN(self->up_axis), dz < 1e-9   ? 0u
                                                                 : dy < 1e-9 ? 1u
                                                                             : 2u);
    }
    self->updating = was;
}

static void
fill(VvgObjectPanel *self) {
    self->updating = TRUE;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (o) {
        GdkRGBA c = vvg_rgba(o->material.color);
        gtk_color_chooser_set_rgba(GTK_COLOR_CHOOSER(self->color), &c);
        vvg_set_spin(self->ambient, o->material.ambient);
        vvg_set_spin(self->diffuse, o->material.diffuse);
        vvg_set_spin(self->specular, o->material.specular);
        vvg_set_spin(self->shininess, o->material.shininess);
        vvg_set_spin(self->reflectance, o->material.reflectance);
        vvg_set_spin(self->transparency, o->material.transparency);
        gtk_editable_set_text(
            GTK_EDITABLE(self->tex_file),
            o->texture.image && o->texture.image->source ? o->texture.image->source : "");
        gtk_drop_down_set_selected(GTK_DROP_DOWN(self->tex_projection), o->texture.projection);
        vvg_set_spin(self->tex_scale, o->texture.scale[0]);
        gtk_drop_down_set_selected(
            GTK_DROP_DOWN(self->solid_kind),
            o->solid_texture.kind <= VV_SOLID_TEXTURE_MARBLE ? (guint)o->solid_texture.kind : 0u);
        vvg_set_spin(self->solid_period, o->solid_texture.period);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(self->shading), o->shading);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(self->casts), o->casts_shadows);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(self->receives), o->receives_shadows);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(self->in_reflections),
                                    o->visible_in_reflections);
        gtk_check_button_set_active(GTK_CHECK_BUTTON(self->reflects), o->reflects);
    }
    fill_placement(self);
    self->updating = FALSE;
}

/* Typed object placement: one undo step. */
static void
on_placement(GtkSpinButton *sb, gpointer user) {
    (void)sb;
    VvgObjectPanel *self = user;
    vv_object *o = vvg_document_selected_object(self->doc);
    if (self->updating || !o)
        return;
    vvg_document_begin_edit(self->doc, "placement");
    o->position = vv_vec3_make(vvg_spin_value(self->obj_pos[0]), vvg_spin_value(self->obj_pos[1]),
                               vvg_spin_value(self->obj_pos[2]));
    /* a uniform scale typed here (a non-uniform one from a scene keeps its
     * ratios), about the object's centre, which stays where it was */
    double sc = vvg_spin_value(self->obj_scale);
    if (sc > 0 && o->scale.x != 0 && fabs(sc - o->scale.x) > 1e-12) {
        vv_box b = vv_object_world_box(o);
        vv_vec3 c0 = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
        o->scale = vv_vec3_scale(o->scale, sc / o->scale.x);
        b = vv_object_world_box(o);
        vv_vec3 c1 = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
        o->position = vv_vec3_add(o->position, vv_vec3_sub(c0, c1));
    }
    vvg_document_changed(self->doc);
    fill_placement(self);
}

/* The material and shading widgets applied to the selected object: one undo step. */
static void
apply(VvgObjectPanel *self, const char *label) {
    vv_object *o = vvg_document_selected_object(self->doc);
    if (self->updating || !o)
        return;
    vvg_document_begin_edit(self->doc, label);
    GdkRGBA c;
    gtk_color_chooser_get_rgba(GTK_COLOR_CHOOSER(self->color), &c);
    o->material.color = vvg_vec3(&c);
    o->material.ambient = vvg_spin_value(self->ambient);
    o->material.diffuse = vvg_spin_value(self->diffuse);
    o->material.specular = vvg_spin_value(self->specular);
    o->material.shininess = vvg_spin_value(self->shininess);
    o->material.reflectance = vvg_spin_value(self->reflectance);
    o->material.transparency = vvg_spin_value(self->transparency);
    o->shading = gtk_check_button_get_active(GTK_CHECK_BUTTON(self->shading));
    o->casts_shadows = gtk_check_button_get_active(GTK_CHECK_BUTTON(self->casts));
    o->receives_shadows = gtk_check_button_get_active(GTK_CHECK_BUTTON(self->receives));
    o->visible_in_reflections = gtk_check_button_get_active(GTK_CHECK_BUTTON(self->in_reflections));
    o->reflects = gtk_check_button_get_active(GTK_CHECK_BUTTON(self->reflects));
    vvg_document_changed(self->doc);
}

/* Z up (the object as stored) or Y up (its Y turned to the World's Z, the
 * convention of OBJ, PLY and glTF exporters): one undo step. */
static void
up_axis_changed(GObject *d, GParamSpec *p, gpointer user) {
    (void)p;
    VvgObjectPanel *self = user;
    vv_object *o = vvg_document_selected_object(self->doc);
    guint k = gtk_drop_down_get_selected(GTK_DROP_DOWN(d));
    if (self->updating || !o || k > 1)
        return;
    vvg_document_begin_edit(self->doc, "up axis");
    vv_box before = vv_object_world_box(o);
    o->orientation =
        k == 1 ? vv_quat_from_axis_angle(vv_vec3_make(1, 0, 0), VV_PI / 2) : vv_quat_identity();
    /* turned about its box centre, which stays where it was */
    vv_box after = vv_object_world_box(o);
    vv_vec3 shift = vv_vec3_scale(
        vv_vec3_sub(vv_vec3_add(before.min, before.max), vv_vec3_add(after.min, after.max)), 0.5);
    o->position = vv_vec3_add(o->position, shift);
    vvg_document_changed(self->doc);
}

static void
on_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    apply(user, "material");
}

static void
on_toggle(GtkCheckButton *b, gpointer user) {
    (void)b;
    apply(user, "shading");
}

static void
on_color(GtkColorButton *b, gpointer user) {
    (void)b;
    apply(user, "edit colour");
}

/* Applies the texture widgets to the selected object (one undo step). */
static void
texture_update(VvgObjectPanel *self, gboolean load_image) {
    vv_object *o = vvg_document_selected_object(self->doc);
    if (self->updating || !o)
        return;
    vv_texture_image *img = NULL;
    const char *path = gtk_editable_get_text(GTK_EDITABLE(self->tex_file));
    if (load_image && path[0]) {
        vv_error_clear();
        if (vv_texture_image_load(&img, path, path) != VV_OK) {
            vvg_show_error(GTK_WIDGET(self), "Cannot load the texture", vv_error_message());
            return;
        }
    }
    vvg_document_begin_edit(self->doc, "texture");
    if (load_image)
        vv_object_set_texture_image(o, img); /* NULL removes it */
    vv_texture_image_free(img);
    o->texture.projection =
        (vv_texture_projection)gtk_drop_down_get_selected(GTK_DROP_DOWN(self->tex_projection));
    o->texture.scale[0] = o->texture.scale[1] = vvg_spin_value(self->tex_scale);
    guint k = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->solid_kind));
    if (o->solid_texture.kind == VV_SOLID_TEXTURE_VOLUME && k != VV_SOLID_TEXTURE_VOLUME)
        vv_solid_texture_clear(&o->solid_texture);
    o->solid_texture.kind = (vv_solid_texture_kind)k;
    o->solid_texture.period = vvg_spin_value(self->solid_period);
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
    vvg_document_changed(self->doc);
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

static gboolean
placement_due(gpointer user) {
    VvgObjectPanel *self = user;
    self->placement_source = 0;
    fill_placement(self);
    return G_SOURCE_REMOVE;
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgObjectPanel *self = user;
    /* during a drag the World changes a hundred times a second: the numbers
     * follow ten times a second, which costs the view no frames */
    if (!self->placement_source)
        self->placement_source = g_timeout_add(100, placement_due, self);
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    fill(user);
}

static void
vvg_object_panel_dispose(GObject *o) {
    VvgObjectPanel *self = VVG_OBJECT_PANEL(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    if (self->placement_source) {
        g_source_remove(self->placement_source);
        self->placement_source = 0;
    }
    G_OBJECT_CLASS(vvg_object_panel_parent_class)->dispose(o);
}

static void
vvg_object_panel_class_init(VvgObjectPanelClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_object_panel_dispose;
}

static void
vvg_object_panel_init(VvgObjectPanel *self) {
    vvg_vbox_init(GTK_WIDGET(self));
}

static GtkWidget *
wire_spin(VvgObjectPanel *self, GtkWidget *s) {
    g_signal_connect(s, "value-changed", G_CALLBACK(on_spin), self);
    return s;
}

static GtkWidget *
wire_check(VvgObjectPanel *self, const char *label) {
    GtkWidget *b = gtk_check_button_new_with_label(label);
    g_signal_connect(b, "toggled", G_CALLBACK(on_toggle), self);
    return b;
}

static void
build_material(VvgObjectPanel *self) {
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "Colour and material");
    self->color = vvg_row(g, "colour", gtk_color_button_new());
    g_signal_connect(self->color, "color-set", G_CALLBACK(on_color), self);
    self->ambient = vvg_row(g, "ambient", wire_spin(self, vvg_spin0(0, 1, 0.05, 2)));
    self->diffuse = vvg_row(g, "diffuse", wire_spin(self, vvg_spin0(0, 1, 0.05, 2)));
    self->specular = vvg_row(g, "specular", wire_spin(self, vvg_spin0(0, 1, 0.05, 2)));
    self->shininess = vvg_row(g, "shininess", wire_spin(self, vvg_spin0(1, 256, 1, 0)));
    self->reflectance = vvg_row(g, "reflectance", wire_spin(self, vvg_spin0(0, 1, 0.05, 2)));
    self->transparency = vvg_row(g, "transparency", wire_spin(self, vvg_spin0(0, 1, 0.05, 2)));
}

static void
build_texture(VvgObjectPanel *self) {
    GtkWidget *g = vvg_section_folded(GTK_WIDGET(self), "Texture");
    self->tex_file = vvg_row(g, "image (PNG)", gtk_entry_new());
    gtk_entry_set_placeholder_text(GTK_ENTRY(self->tex_file), "path, Enter to apply; empty: none");
    g_signal_connect(self->tex_file, "activate", G_CALLBACK(texture_apply), self);
    static const char *const projections[] = {"planar", "cylindrical", "spherical", NULL};
    self->tex_projection = vvg_row(g, "projection", gtk_drop_down_new_from_strings(projections));
    self->tex_scale = vvg_row(g, "repeats", vvg_spin(0.01, 1000, 0.5, 2, 1));
    g_signal_connect(self->tex_projection, "notify::selected", G_CALLBACK(texture_changed), self);
    g_signal_connect(self->tex_scale, "value-changed", G_CALLBACK(texture_spin), self);
    static const char *const solids[] = {"none", "checker", "wood", "marble", NULL};
    self->solid_kind = vvg_row(g, "solid texture", gtk_drop_down_new_from_strings(solids));
    self->solid_period = vvg_row(g, "period (world units)", vvg_spin(0.01, 1e5, 1, 2, 10));
    g_signal_connect(self->solid_kind, "notify::selected", G_CALLBACK(texture_changed), self);
    g_signal_connect(self->solid_period, "value-changed", G_CALLBACK(texture_spin), self);
}

GtkWidget *
vvg_object_panel_new(VvgDocument *doc) {
    VvgObjectPanel *self = g_object_new(VVG_TYPE_OBJECT_PANEL, NULL);
    self->doc = g_object_ref(doc);
    GtkWidget *g = vvg_section(GTK_WIDGET(self), "Placement of the object (world units)");
    const char *posn[] = {"position x", "position y", "position z"};
    for (int i = 0; i < 3; i++) {
        self->obj_pos[i] = vvg_row(g, posn[i], vvg_spin0(-1e6, 1e6, 1, 3));
        g_signal_connect(self->obj_pos[i], "value-changed", G_CALLBACK(on_placement), self);
    }
    self->obj_scale = vvg_row(g, "scale", vvg_spin0(1e-3, 1e3, 0.1, 3));
    g_signal_connect(self->obj_scale, "value-changed", G_CALLBACK(on_placement), self);
    static const char *const ups[] = {"Z (as stored)", "Y (OBJ, PLY, glTF)", "other", NULL};
    self->up_axis = vvg_row(g, "up axis", gtk_drop_down_new_from_strings(ups));
    g_signal_connect(self->up_axis, "notify::selected", G_CALLBACK(up_axis_changed), self);
    build_material(self);
    build_texture(self);
    g = vvg_section_folded(GTK_WIDGET(self), "Shading and global effects");
    self->shading = wire_check(self, "Phong shading from gradients");
    self->casts = wire_check(self, "casts shadows");
    self->receives = wire_check(self, "receives shadows");
    self->in_reflections = wire_check(self, "visible in reflections");
    self->reflects = wire_check(self, "reflects");
    GtkWidget *checks[] = {self->shading, self->casts, self->receives, self->in_reflections,
                           self->reflects};
    for (int i = 0; i < 5; i++)
        gtk_grid_attach(GTK_GRID(g), checks[i], 0, i, 2, 1);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), self);
    fill(self);
    return GTK_WIDGET(self);
}
