/* VvRenderingPage: renderer, options and quality (vv-rendering-page.h). */
#include "vv-rendering-page.h"
#include "vvg-widgets.h"

#include <string.h>

struct _VvRenderingPage {
    GtkBox parent;
    VvDocument *doc;
    gboolean updating;
    GtkWidget *renderer, *quality, *options_box;
};

G_DEFINE_TYPE(VvRenderingPage, vv_rendering_page, GTK_TYPE_BOX)

/* The option keys and defaults of a renderer, from its registry text
 * "key (default), key (a|b; default), key" (vv_renderer_ops.options). */
static int
parse_options(const char *text, char keys[][32], char defs[][64], int max) {
    int n = 0;
    const char *p = text ? text : "";
    while (*p && n < max) {
        while (*p == ' ' || *p == ',')
            p++;
        const char *k = p;
        while (*p && *p != ' ' && *p != ',' && *p != '(')
            p++;
        size_t kl = (size_t)(p - k);
        if (kl == 0 || kl >= 32)
            break;
        /* prose after the options ("--quality 0: no shadow rays, 1: ...")
         * is no option: a key is a lower-case identifier */
        gboolean ident = g_ascii_islower(k[0]);
        for (size_t c = 1; c < kl; c++)
            ident = ident && (g_ascii_islower(k[c]) || g_ascii_isdigit(k[c]) || k[c] == '_');
        if (!ident) {
            while (*p && *p != ',')
                p++;
            continue;
        }
        memcpy(keys[n], k, kl);
        keys[n][kl] = '\0';
        defs[n][0] = '\0';
        while (*p == ' ')
            p++;
        if (*p == '(') {
            const char *e = strchr(p, ')');
            if (!e)
                break;
            const char *d = p + 1;
            const char *semi = memchr(d, ';', (size_t)(e - d));
            if (semi)
                d = semi + 1;
            while (*d == ' ')
                d++;
            size_t dl = (size_t)(e - d);
            if (dl >= 64)
                dl = 63;
            memcpy(defs[n], d, dl);
            defs[n][dl] = '\0';
            p = e + 1;
        }
        n++;
        while (*p && *p != ',')
            p++;
    }
    return n;
}

static void
option_changed(GtkEntry *e, gpointer user) {
    VvRenderingPage *self = user;
    if (self->updating)
        return;
    const char *key = g_object_get_data(G_OBJECT(e), "key");
    const char *text = gtk_editable_get_text(GTK_EDITABLE(e));
    vv_world *w = vv_document_world(self->doc);
    /* check the value with the renderer itself before taking it */
    vv_renderer *r = NULL;
    if (vv_renderer_new(&r, vv_render_settings_renderer(&w->render)) == VV_OK) {
        vv_error_clear();
        if (text[0] && vv_renderer_set_option(r, key, text) != VV_OK) {
            vvg_show_error(GTK_WIDGET(self), "Bad renderer option", vv_error_message());
            vv_renderer_free(r);
            return;
        }
        vv_renderer_free(r);
    }
    vv_document_begin_edit(self->doc, "renderer option");
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
    vv_document_changed(self->doc);
}

static void
rebuild_options(VvRenderingPage *self) {
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(self->options_box)))
        gtk_grid_remove(GTK_GRID(self->options_box), c);
    const vv_renderer_ops *const *reg = vv_renderer_registry();
    guint sel = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->renderer));
    const vv_renderer_ops *ops = reg[sel] ? reg[sel] : reg[0];
    char keys[32][32], defs[32][64];
    int n = parse_options(ops->options, keys, defs, 32);
    vv_world *w = vv_document_world(self->doc);
    for (int i = 0; i < n; i++) {
        GtkWidget *e = gtk_entry_new();
        gtk_entry_set_placeholder_text(GTK_ENTRY(e), defs[i][0] ? defs[i] : "default");
        for (int j = 0; j < w->render.n_options; j++)
            if (!strcmp(w->render.option_keys[j], keys[i]))
                gtk_editable_set_text(GTK_EDITABLE(e), w->render.option_values[j]);
        g_object_set_data_full(G_OBJECT(e), "key", g_strdup(keys[i]), g_free);
        g_signal_connect(e, "activate", G_CALLBACK(option_changed), self);
        vvg_row(self->options_box, keys[i], e);
    }
}

static void
fill(VvRenderingPage *self) {
    self->updating = TRUE;
    vv_world *w = vv_document_world(self->doc);
    const vv_renderer_ops *const *reg = vv_renderer_registry();
    for (guint i = 0; reg[i]; i++)
        if (!strcmp(reg[i]->name, vv_render_settings_renderer(&w->render)))
            gtk_drop_down_set_selected(GTK_DROP_DOWN(self->renderer), i);
    vvg_set_spin(self->quality, vv_render_settings_quality(&w->render));
    self->updating = FALSE;
    rebuild_options(self);
}

static void
renderer_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    VvRenderingPage *self = user;
    if (!self->updating) {
        const vv_renderer_ops *const *reg = vv_renderer_registry();
        guint sel = gtk_drop_down_get_selected(GTK_DROP_DOWN(self->renderer));
        vv_world *w = vv_document_world(self->doc);
        if (reg[sel] && strcmp(reg[sel]->name, w->render.renderer)) {
            vv_document_begin_edit(self->doc, "renderer");
            g_strlcpy(w->render.renderer, reg[sel]->name, sizeof w->render.renderer);
            w->render.n_options = 0; /* the options belong to the other renderer */
            vv_document_changed(self->doc);
        }
    }
    rebuild_options(self);
}

static void
quality_changed(GtkSpinButton *s, gpointer user) {
    VvRenderingPage *self = user;
    if (self->updating)
        return;
    vv_document_begin_edit(self->doc, "quality");
    vv_document_world(self->doc)->render.quality = (int)gtk_spin_button_get_value(s);
    vv_document_changed(self->doc);
}

static void
selection_changed(VvDocument *doc, gpointer user) {
    (void)doc;
    fill(user);
}

static void
vv_rendering_page_dispose(GObject *o) {
    VvRenderingPage *self = VV_RENDERING_PAGE(o);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    G_OBJECT_CLASS(vv_rendering_page_parent_class)->dispose(o);
}

static void
vv_rendering_page_class_init(VvRenderingPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vv_rendering_page_dispose;
}

static void
vv_rendering_page_init(VvRenderingPage *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    gtk_widget_set_margin_start(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_end(GTK_WIDGET(self), 8);
    gtk_widget_set_margin_bottom(GTK_WIDGET(self), 8);
}

GtkWidget *
vv_rendering_page_new(VvDocument *doc) {
    VvRenderingPage *self = g_object_new(VV_TYPE_RENDERING_PAGE, NULL);
    self->doc = g_object_ref(doc);
    GtkWidget *box = GTK_WIDGET(self);
    GtkWidget *g = vvg_section(box, "Renderer");
    GtkStringList *names = gtk_string_list_new(NULL);
    for (const vv_renderer_ops *const *r = vv_renderer_registry(); *r; r++)
        gtk_string_list_append(names, (*r)->name);
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
