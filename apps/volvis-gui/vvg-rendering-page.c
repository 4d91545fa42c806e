/* VvgRenderingPage: renderer, options and quality (vvg-rendering-page.h). */
#include "vvg-rendering-page.h"
#include "vvg-widgets.h"

#include <string.h>

struct _VvgRenderingPage {
    GtkBox parent;
    VvgDocument *doc;
    gboolean updating;
    GtkWidget *renderer, *quality, *options_box;
};

G_DEFINE_TYPE(VvgRenderingPage, vvg_rendering_page, GTK_TYPE_BOX)

static void
option_changed(GtkEntry *e, gpointer user) {
    VvgRenderingPage *self = user;
    if (self->updating)
        return;
    const char *key = g_object_get_data(G_OBJECT(e), "key");
    const char *text = gtk_editable_get_text(GTK_EDITABLE(e));
    vv_world *w = vvg_document_world(self->doc);
    /* check the value against the renderer's option table before taking it */
    const vv_renderer_info *info = vv_renderer_info_find(vv_world_renderer(w));
    vv_error_clear();
    if (info && text[0] && vv_renderer_info_check_option(info, key, text) != VV_OK) {
        vvg_show_error(GTK_WIDGET(self), "Bad renderer option", vv_error_message());
        return;
    }
    vvg_document_begin_edit(self->doc, "renderer option");
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
    vvg_document_changed(self->doc);
}

static void
rebuild_options(VvgRenderingPage *self) {
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(self->options_box)))
        gtk_grid_remove(GTK_GRID(self->options_box), c);
    /* one row per entry of the renderer's option table (render.h) */
    guint sel = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->renderer));
    const vv_renderer_info *info = vv_renderer_info_at((int)sel);
    if (!info)
        info = vv_renderer_info_at(0);
    vv_world *w = vvg_document_world(self->doc);
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
        g_signal_connect(e, "activate", G_CALLBACK(option_changed), self);
        vvg_row(self->options_box, o->key, e);
    }
}

static void
fill(VvgRenderingPage *self) {
    self->updating = TRUE;
    vv_world *w = vvg_document_world(self->doc);
    for (int i = 0; i < vv_renderer_count(); i++)
        if (!strcmp(vv_renderer_info_at(i)->name, vv_world_renderer(w)))
            gtk_drop_down_set_selected(GTK_DROP_DOWN(self->renderer), (guint)i);
    vvg_set_spin(self->quality, vv_render_settings_quality(&w->render));
    self->updating = FALSE;
    rebuild_options(self);
}

static void
renderer_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    VvgRenderingPage *self = user;
    if (!self->updating) {
        guint sel = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->renderer));
        const vv_renderer_info *info = vv_renderer_info_at((int)sel);
        vv_world *w = vvg_document_world(self->doc);
        if (info && strcmp(info->name, w->render.renderer)) {
            vvg_document_begin_edit(self->doc, "renderer");
            g_strlcpy(w->render.renderer, info->name, sizeof w->render.renderer);
            w->render.n_options = 0; /* the options belong to the other renderer */
            vvg_document_changed(self->doc);
        }
    }
    rebuild_options(self);
}

static void
quality_changed(GtkSpinButton *s, gpointer user) {
    VvgRenderingPage *self = user;
    if (self->updating)
        return;
    vvg_document_begin_edit(self->doc, "quality");
    vvg_document_world(self->doc)->render.quality = (int)gtk_spin_button_get_value(s);
    vvg_document_changed(self->doc);
}

static void
selection_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    fill(user);
}

static void
vvg_rendering_page_dispose(GObject *o) {
    VvgRenderingPage *self = VVG_RENDERING_PAGE(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    G_OBJECT_CLASS(vvg_rendering_page_parent_class)->dispose(o);
}

static void
vvg_rendering_page_class_init(VvgRenderingPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_rendering_page_dispose;
}

static void
vvg_rendering_page_init(VvgRenderingPage *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    gtk_widget_set_margin_start(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_end(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_bottom(GTK_WIDGET(self), 8);
}

GtkWidget *
vvg_rendering_page_new(VvgDocument *doc) {
    VvgRenderingPage *self = g_object_new(VVG_TYPE_RENDERING_PAGE, NULL);
    self->doc = g_object_ref(doc);
    GtkWidget *box = GTK_WIDGET(self);
    GtkWidget *g = vvg_section(box, "Renderer");
    GtkStringList *names = gtk_string_list_new(NULL);
    for (int i = 0; i < vv_renderer_count(); i++)
        gtk_string_list_append(names, vv_renderer_info_at(i)->name);
    self->renderer = vvg_row(g, "method", gtk_drop_down_new(G_LIST_MODEL(names), NULL));
    g_signal_connect(self->renderer, "notify::selected", G_CALLBACK(renderer_changed), self);
    self->quality = vvg_row(g, "quality", vvg_spin0(0, 2, 1, 0));
    g_signal_connect(self->quality, "value-changed", G_CALLBACK(quality_changed), self);
    self->options_box = vvg_section(box, "Options (Enter to apply; empty: default)");
    gtk_box_append(GTK_BOX(box), vvg_action_button("Render…", "win.render"));
    g_signal_connect(doc, "selection-changed", G_CALLBACK(selection_changed), self);
    fill(self);
    return box;
}
