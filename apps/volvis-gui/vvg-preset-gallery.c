/* VvgPresetGallery: presets with thumbnails from the current volume (vvg-preset-gallery.h). */
#include "vvg-preset-gallery.h"
#include "vvg-widgets.h"

#include <math.h>
#include <string.h>

#define THUMB 80
#define MAX_PRESETS 64

struct _VvgPresetGallery {
    GtkBox parent;
    VvgDocument *doc;
    GtkWidget *active_label, *flow;
    GtkWidget *buttons[MAX_PRESETS], *pictures[MAX_PRESETS];
    int n;
    /* the presets as applied to the current volume, for "active" */
    const vv_volume *volume; /* compared only */
    uint64_t modified;
    vv_tf *tfs; /* MAX_PRESETS (large: on the heap) */
    gboolean have_tf[MAX_PRESETS];
    int active;
    int rendered;
    guint gen;      /* of the thumbnails being rendered */
    gboolean stale; /* the thumbnails wait until the gallery is shown */
    GCancellable *cancel;
};

G_DEFINE_TYPE(VvgPresetGallery, vvg_preset_gallery, GTK_TYPE_BOX)

static vv_object *
volume_object(VvgPresetGallery *self) {
    vv_object *o = vvg_document_selected_object(self->doc);
    return o && o->type == VV_OBJECT_VOLUME && o->volume ? o : NULL;
}

/* Equal up to rounding: the function a preset gave, perhaps saved and read again. */
static gboolean
tf_equal(const vv_tf *a, const vv_tf *b) {
    if (a->n_opacity != b->n_opacity || a->n_color != b->n_color)
        return FALSE;
    double tol = 1e-6 * (1 + fabs(a->opacity_unit_distance));
    if (fabs(a->opacity_unit_distance - b->opacity_unit_distance) > tol)
        return FALSE;
    for (int i = 0; i < a->n_opacity; i++) {
        double t = 1e-9 * (1 + fabs(a->opacity[i].value));
        if (fabs(a->opacity[i].value - b->opacity[i].value) > t ||
            fabs(a->opacity[i].opacity - b->opacity[i].opacity) > 1e-9)
            return FALSE;
    }
    for (int i = 0; i < a->n_color; i++) {
        double t = 1e-9 * (1 + fabs(a->color[i].value));
        if (fabs(a->color[i].value - b->color[i].value) > t ||
            vv_vec3_length(vv_vec3_sub(a->color[i].color, b->color[i].color)) > 1e-9)
            return FALSE;
    }
    return TRUE;
}

static void
show_active(VvgPresetGallery *self) {
    vv_object *o = volume_object(self);
    int active = -1;
    for (int i = 0; o && i < self->n && active < 0; i++)
        if (self->have_tf[i] && o->segmentation == VV_SEG_TRANSFER_FUNCTION &&
            tf_equal(&o->tf, &self->tfs[i]))
            active = i;
    if (active == self->active && gtk_label_get_text(GTK_LABEL(self->active_label))[0])
        return;
    self->active = active;
    for (int i = 0; i < self->n; i++) {
        if (i == active)
            gtk_widget_add_css_class(self->buttons[i], "suggested-action");
        else
            gtk_widget_remove_css_class(self->buttons[i], "suggested-action");
    }
    g_autofree char *t =
        !o ? g_strdup("Presets: select a volume object")
        : active >= 0
            ? g_strdup_printf("Active preset: %s", vv_tf_preset_names()[active])
            : g_strdup("Active preset: none (the transfer function is edited or from a file)");
    gtk_label_set_text(GTK_LABEL(self->active_label), t);
}

/* ---- thumbnails ------------------------------------------------------------------ */

typedef struct thumb_job {
    VvgPresetGallery *gallery; /* a reference */
    guint gen;
    vv_world *world; /* the selected object alone, its lights, the view at THUMB x THUMB */
    vv_tf *tfs;      /* MAX_PRESETS */
    gboolean have_tf[MAX_PRESETS];
    int n;
    GCancellable *cancel;
} thumb_job;

typedef struct thumb_done {
    VvgPresetGallery *gallery; /* a reference */
    guint gen;
    int index;
    GdkTexture *texture;
} thumb_done;

static gboolean
thumb_show(gpointer data) {
    thumb_done *d = data;
    VvgPresetGallery *self = d->gallery;
    if (self->doc && d->gen == self->gen && d->index < self->n) {
        gtk_picture_set_paintable(GTK_PICTURE(self->pictures[d->index]), GDK_PAINTABLE(d->texture));
        self->rendered++;
    }
    g_object_unref(d->texture);
    g_object_unref(d->gallery);
    g_free(d);
    return G_SOURCE_REMOVE;
}

static int
thumb_cancel(void *user, double f) {
    (void)f;
    return g_cancellable_is_cancelled(user);
}

static void
thumb_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    thumb_job *j = data;
    vv_renderer *r = NULL;
    vv_image *img = NULL;
    if (vv_renderer_new(&r, "raycast") != VV_OK || vv_image_new(&img, THUMB, THUMB) != VV_OK) {
        vv_renderer_free(r);
        return;
    }
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.quality = 0;
    ro.progress.fn = thumb_cancel;
    ro.progress.user = j->cancel;
    vv_object *o = j->world->objects[0];
    for (int i = 0; i < j->n && !g_cancellable_is_cancelled(j->cancel); i++) {
        if (!j->have_tf[i])
            continue;
        o->tf = j->tfs[i];
        if (vv_renderer_render(r, j->world, &j->world->view, &ro, img) != VV_OK)
            continue;
        guint8 *px = g_malloc(THUMB * THUMB * 4);
        vv_image_to_8bit(img, 4, 1.0, px);
        for (int k = 3; k < THUMB * THUMB * 4; k += 4)
            px[k] = 255;
        GBytes *b = g_bytes_new_take(px, THUMB * THUMB * 4);
        thumb_done *d = g_new(thumb_done, 1);
        d->gallery = g_object_ref(j->gallery);
        d->gen = j->gen;
        d->index = i;
        d->texture = gdk_memory_texture_new(THUMB, THUMB, GDK_MEMORY_R8G8B8A8, b, THUMB * 4);
        g_bytes_unref(b);
        g_idle_add(thumb_show, d);
    }
    vv_image_free(img);
    vv_renderer_free(r);
}

static void
thumb_job_free(gpointer p) {
    thumb_job *j = p;
    vv_world_free(j->world);
    g_object_unref(j->gallery);
    g_object_unref(j->cancel);
    g_free(j->tfs);
    g_free(j);
}

/* The World a thumbnail shows: the object alone, as the 3-D view sees it
 * (a square image framing it), composite unless it is projected. */
static vv_world *
thumb_world(VvgPresetGallery *self, const vv_object *o) {
    vv_world *src = vvg_document_world(self->doc), *w = NULL;
    vv_object *copy = NULL;
    if (vv_world_new(&w) != VV_OK)
        return NULL;
    if (vv_object_clone(&copy, o) != VV_OK || vv_world_add_object(w, copy) != VV_OK) {
        vv_world_free(w);
        return NULL;
    }
    copy->segmentation = VV_SEG_TRANSFER_FUNCTION;
    copy->n_cut_planes = 0;
    if (copy->mode == VV_MODE_ISO)
        copy->mode = VV_MODE_COMPOSITE;
    copy->step *= 2;
    w->n_lights = src->n_lights;
    memcpy(w->lights, src->lights, sizeof w->lights);
    w->ambient = src->ambient;
    w->background = src->background;
    w->view = src->view;
    w->view.width = w->view.height = THUMB;
    vv_view_frame_box(&w->view, vv_object_world_box(copy));
    return w;
}

/* The presets on a newly selected (or changed) volume: their functions for
 * "active", and their thumbnails. */
static void
volume_changed(VvgPresetGallery *self, const vv_object *o) {
    self->volume = o ? o->volume : NULL;
    self->modified = o ? o->volume->modified : 0;
    self->gen++;
    self->rendered = 0;
    if (self->cancel)
        g_cancellable_cancel(self->cancel);
    g_clear_object(&self->cancel);
    for (int i = 0; i < self->n; i++) {
        gtk_picture_set_paintable(GTK_PICTURE(self->pictures[i]), NULL);
        self->have_tf[i] =
            o && vv_tf_preset(&self->tfs[i], vv_tf_preset_names()[i], o->volume) == VV_OK;
    }
    self->active = -2; /* to be shown again */
    /* rendered when the page is shown: at start the 3-D view goes first */
    self->stale = !gtk_widget_get_mapped(GTK_WIDGET(self));
    vv_world *w = o && !self->stale ? thumb_world(self, o) : NULL;
    if (!w)
        return;
    thumb_job *j = g_new0(thumb_job, 1);
    j->tfs = g_new(vv_tf, MAX_PRESETS);
    j->gallery = g_object_ref(self);
    j->gen = self->gen;
    j->world = w;
    j->n = self->n;
    memcpy(j->tfs, self->tfs, sizeof j->tfs[0] * MAX_PRESETS);
    memcpy(j->have_tf, self->have_tf, sizeof j->have_tf);
    self->cancel = g_cancellable_new();
    j->cancel = g_object_ref(self->cancel);
    GTask *task = g_task_new(NULL, NULL, NULL, NULL);
    g_task_set_task_data(task, j, thumb_job_free);
    g_task_run_in_thread(task, thumb_thread);
    g_object_unref(task);
}

static void
doc_changed(VvgDocument *doc, gpointer user) {
    (void)doc;
    VvgPresetGallery *self = user;
    vv_object *o = volume_object(self);
    if ((o ? o->volume : NULL) != self->volume || (o && o->volume->modified != self->modified))
        volume_changed(self, o);
    show_active(self);
}

static void
mapped(GtkWidget *w, gpointer user) {
    (void)user;
    VvgPresetGallery *self = VVG_PRESET_GALLERY(w);
    if (self->stale)
        volume_changed(self, volume_object(self));
}

static void
preset_clicked(GtkButton *b, gpointer user) {
    VvgPresetGallery *self = user;
    int i = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(b), "index"));
    vv_object *o = volume_object(self);
    if (!o || i < 0 || i >= self->n)
        return;
    vvg_document_begin_edit(self->doc, "transfer-function preset");
    o = volume_object(self);
    vv_error_clear();
    if (vv_tf_preset(&o->tf, vv_tf_preset_names()[i], o->volume) != VV_OK) {
        vvg_show_error(GTK_WIDGET(self), "Cannot apply the preset", vv_error_message());
        return;
    }
    o->segmentation = VV_SEG_TRANSFER_FUNCTION;
    vvg_document_changed(self->doc);
    show_active(self);
}

static void
vvg_preset_gallery_dispose(GObject *obj) {
    VvgPresetGallery *self = VVG_PRESET_GALLERY(obj);
    if (self->cancel)
        g_cancellable_cancel(self->cancel);
    g_clear_object(&self->cancel);
    if (self->doc) {
        g_signal_handlers_disconnect_by_data(self->doc, self);
        g_clear_object(&self->doc);
    }
    G_OBJECT_CLASS(vvg_preset_gallery_parent_class)->dispose(obj);
}

static void
vvg_preset_gallery_finalize(GObject *obj) {
    g_free(VVG_PRESET_GALLERY(obj)->tfs);
    G_OBJECT_CLASS(vvg_preset_gallery_parent_class)->finalize(obj);
}

static void
vvg_preset_gallery_class_init(VvgPresetGalleryClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_preset_gallery_dispose;
    G_OBJECT_CLASS(klass)->finalize = vvg_preset_gallery_finalize;
}

static void
vvg_preset_gallery_init(VvgPresetGallery *self) {
    vvg_vbox_init(GTK_WIDGET(self));
    self->active = -2;
    self->tfs = g_new0(vv_tf, MAX_PRESETS);
    g_signal_connect(self, "map", G_CALLBACK(mapped), NULL);
    self->active_label = gtk_label_new("");
    gtk_label_set_xalign(GTK_LABEL(self->active_label), 0);
    gtk_label_set_wrap(GTK_LABEL(self->active_label), TRUE);
    vvg_name(self->active_label, "active preset");
    gtk_box_append(GTK_BOX(self), self->active_label);
    self->flow = gtk_flow_box_new();
    gtk_flow_box_set_selection_mode(GTK_FLOW_BOX(self->flow), GTK_SELECTION_NONE);
    gtk_flow_box_set_homogeneous(GTK_FLOW_BOX(self->flow), TRUE);
    gtk_flow_box_set_max_children_per_line(GTK_FLOW_BOX(self->flow), 8);
    gtk_flow_box_set_min_children_per_line(GTK_FLOW_BOX(self->flow), 3);
    vvg_name(self->flow, "transfer-function presets");
    gtk_box_append(GTK_BOX(self), self->flow);
    const char *const *names = vv_tf_preset_names();
    for (int i = 0; names[i] && i < MAX_PRESETS; i++) {
        GtkWidget *b = gtk_button_new();
        GtkWidget *v = gtk_box_new(GTK_ORIENTATION_VERTICAL, 2);
        self->pictures[i] = gtk_picture_new();
        gtk_widget_set_size_request(self->pictures[i], THUMB, THUMB);
        gtk_picture_set_can_shrink(GTK_PICTURE(self->pictures[i]), FALSE);
        GtkWidget *l = gtk_label_new(names[i]);
        gtk_label_set_ellipsize(GTK_LABEL(l), PANGO_ELLIPSIZE_END);
        gtk_label_set_max_width_chars(GTK_LABEL(l), 11);
        gtk_box_append(GTK_BOX(v), self->pictures[i]);
        gtk_box_append(GTK_BOX(v), l);
        gtk_button_set_child(GTK_BUTTON(b), v);
        gtk_widget_set_tooltip_text(b, vv_tf_preset_description(names[i]));
        vvg_name(b, names[i]);
        g_object_set_data(G_OBJECT(b), "index", GINT_TO_POINTER(i));
        g_signal_connect(b, "clicked", G_CALLBACK(preset_clicked), self);
        gtk_flow_box_append(GTK_FLOW_BOX(self->flow), b);
        self->buttons[i] = b;
        self->n = i + 1;
    }
}

GtkWidget *
vvg_preset_gallery_new(VvgDocument *doc) {
    VvgPresetGallery *self = g_object_new(VVG_TYPE_PRESET_GALLERY, NULL);
    self->doc = g_object_ref(doc);
    g_signal_connect(doc, "changed", G_CALLBACK(doc_changed), self);
    g_signal_connect(doc, "selection-changed", G_CALLBACK(doc_changed), self);
    doc_changed(doc, self);
    return GTK_WIDGET(self);
}

const char *
vvg_preset_gallery_active(VvgPresetGallery *self) {
    return self->active >= 0 ? vv_tf_preset_names()[self->active] : NULL;
}

int
vvg_preset_gallery_thumbnails(VvgPresetGallery *self) {
    return self->rendered;
}
