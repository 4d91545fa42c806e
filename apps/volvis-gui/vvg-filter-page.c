/* VvgFilterPage: the Filtering page (vvg-filter-page.h). */
#include "vvg-filter-page.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "vvg-widgets.h"

struct _VvgFilterPage {
    GtkBox parent;
    VvgDocument *doc;
    GtkWidget *chain, *apply, *cancel, *progress, *status, *adapt;
    GtkWidget *which, *arg, *help;
    GTask *task;     /* the running filter, or NULL */
    guint tick;      /* progress bar timer */
    atomic_int stop; /* Cancel pressed */
    _Atomic double fraction;
};

G_DEFINE_FINAL_TYPE(VvgFilterPage, vvg_filter_page, GTK_TYPE_BOX)

typedef struct filter_job {
    VvgFilterPage *page; /* a reference */
    vv_volume *in, *out; /* in: a reference to the object's volume */
    vv_filter_chain *chain;
    int object; /* index of the object in the World */
    char name[VV_NAME_MAX];
    char proxy[192]; /* out of core: what was filtered instead of level 0 (else empty) */
    vv_status status;
    char error[512];
    double seconds;
} filter_job;

static void
filter_job_free(gpointer p) {
    filter_job *j = p;
    vv_volume_free(j->in);
    vv_volume_free(j->out);
    vv_filter_chain_free(j->chain);
    g_object_unref(j->page);
    g_free(j);
}

static int
job_progress(void *user, double f) {
    VvgFilterPage *page = user;
    atomic_store(&page->fraction, f);
    return atomic_load(&page->stop);
}

static void
filter_thread(GTask *task, gpointer src, gpointer data, GCancellable *c) {
    (void)task;
    (void)src;
    (void)c;
    filter_job *j = data;
    vv_filter_options o;
    vv_filter_options_init(&o);
    o.progress.fn = job_progress;
    o.progress.user = j->page;
    gint64 t0 = g_get_monotonic_time();
    vv_error_clear();
    j->status = vv_filter_chain_apply(j->chain, j->in, &o, &j->out);
    j->seconds = (double)(g_get_monotonic_time() - t0) / 1e6;
    if (j->status != VV_OK)
        g_strlcpy(j->error, vv_error_message(), sizeof j->error);
}

static void
set_status(VvgFilterPage *page, const char *text) {
    gtk_label_set_text(GTK_LABEL(page->status), text);
}

static void
set_running(VvgFilterPage *page, gboolean running) {
    gtk_widget_set_sensitive(page->apply, !running);
    gtk_widget_set_sensitive(page->cancel, running);
    if (!running && page->tick) {
        g_source_remove(page->tick);
        page->tick = 0;
    }
}

/* The last step names the output: a label volume is shown by label. */
static gboolean
ends_in_labels(const char *chain_text) {
    const char *last = g_strrstr(chain_text, "--");
    return last && g_str_has_prefix(last, "--components");
}

static void
filter_done(GObject *src, GAsyncResult *res, gpointer user) {
    (void)src;
    (void)user;
    filter_job *j = g_task_get_task_data(G_TASK(res));
    VvgFilterPage *page = j->page;
    page->task = NULL;
    if (!page->doc)
        return; /* the page went away (window closed) while the filter ran */
    set_running(page, FALSE);
    char t[1024];
    if (j->status != VV_OK) {
        snprintf(t, sizeof t, "%s: %s", j->status == VV_ERR_CANCELLED ? "cancelled" : "failed",
                 j->error);
        set_status(page, t);
        gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(page->progress), 0);
        if (j->status != VV_ERR_CANCELLED)
            vvg_show_error(GTK_WIDGET(page), "Filtering failed", j->error);
        return;
    }
    /* the object may have gone (deleted, undone) while the filter ran */
    vv_world *w = vvg_document_world(page->doc);
    if (j->object >= w->n_objects || w->objects[j->object]->volume != j->in) {
        set_status(page, "the object changed while filtering: result dropped");
        return;
    }
    vvg_document_begin_edit(page->doc, "Filter");
    w = vvg_document_world(page->doc);
    vv_object *o = w->objects[j->object];
    const vv_volume *old = o->volume;
    double olo = old->range[0], ohi = old->range[1];
    int same_kind = j->out->type == old->type || (j->out->type == VV_F32 && old->type != VV_U8);
    if (o->n_channels == 0) {
        /* in memory from now on: the object's file out of core, if any, is dropped */
        if (vv_object_set_volume(o, j->out) != VV_OK)
            g_warning("volvis-gui: %s", vv_error_message());
    } else { /* channel 0 of several: the object's volume only */
        vv_volume_free(o->volume);
        o->volume = vv_volume_ref(j->out);
    }
    const char *text = vv_filter_chain_text(j->chain);
    /* a volume from a file is saved as the file and its filters; one made in
     * the session is saved as it is (vvg_document_save) */
    if (o->geometry.source) {
        char *f = o->geometry.filters ? g_strdup_printf("%s %s", o->geometry.filters, text)
                                      : g_strdup(text);
        free(o->geometry.filters);
        /* the library frees it with free() */
        size_t n = strlen(f) + 1;
        o->geometry.filters = malloc(n);
        if (o->geometry.filters)
            memcpy(o->geometry.filters, f, n);
        g_free(f);
    }
    double lo = j->out->range[0], hi = j->out->range[1];
    gboolean new_range = !same_kind || lo < olo || hi > ohi || hi - lo < 0.5 * (ohi - olo);
    if (ends_in_labels(text)) {
        o->segmentation = VV_SEG_LABELS;
    } else if (new_range && gtk_check_button_get_active(GTK_CHECK_BUTTON(page->adapt))) {
        /* a new value range, and the user asked: a ramp over it (else the
         * user's transfer function stays as it was) */
        if (o->segmentation == VV_SEG_LABELS || o->segmentation == VV_SEG_THRESHOLD)
            o->segmentation = VV_SEG_TRANSFER_FUNCTION;
        vv_tf_set_ramp(&o->tf, lo, hi > lo ? hi : lo + 1, 1.0, o->material.color,
                       o->tf.opacity_unit_distance);
        if (o->mode == VV_MODE_ISO)
            o->isovalue = 0.5 * (lo + hi);
    }
    vvg_document_changed(page->doc);
    snprintf(t, sizeof t, "%s: %s -> %d x %d x %d %s, values %g..%g, in %.2f s%s", j->name, text,
             j->out->dims[0], j->out->dims[1], j->out->dims[2], vv_voxel_type_name(j->out->type),
             lo, hi, j->seconds, j->proxy);
    set_status(page, t);
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(page->progress), 1);
    /* scripts and tests read what happened from stderr */
    g_printerr("volvis-gui: filtered %s\n", t);
}

static gboolean
tick(gpointer user) {
    VvgFilterPage *page = user;
    gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(page->progress), atomic_load(&page->fraction));
    return G_SOURCE_CONTINUE;
}

static void
apply_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgFilterPage *page = user;
    if (page->task)
        return;
    int idx = vvg_document_selected(page->doc);
    vv_object *o = vvg_document_selected_object(page->doc);
    if (!o || o->type != VV_OBJECT_VOLUME || !o->volume) {
        vvg_show_error(GTK_WIDGET(page), "Nothing to filter", "select a volume object first");
        return;
    }
    const char *text = gtk_editable_get_text(GTK_EDITABLE(page->chain));
    vv_filter_chain *chain = NULL;
    vv_error_clear();
    if (vv_filter_chain_parse(text, &chain) != VV_OK) {
        set_status(page, vv_error_message());
        vvg_show_error(GTK_WIDGET(page), "Bad filter chain", vv_error_message());
        return;
    }
    if (vv_filter_chain_length(chain) == 0) {
        vv_filter_chain_free(chain);
        vvg_show_error(GTK_WIDGET(page), "No filter",
                       "type a chain such as --gaussian 1.5 --threshold 300: or add steps below");
        return;
    }
    filter_job *j = g_new0(filter_job, 1);
    vv_source *src = vvg_object_source(o);
    if (src) { /* said with the result: the proxy, not level 0 */
        const vv_volume *h0 = vv_source_level(src, 0);
        snprintf(j->proxy, sizeof j->proxy,
                 " -- the coarse proxy (level 0, %d x %d x %d, is out of core; a saved session "
                 "keeps the chain for the whole file)",
                 h0->dims[0], h0->dims[1], h0->dims[2]);
    }
    j->page = g_object_ref(page);
    j->in = vv_volume_ref(o->volume);
    j->chain = chain;
    j->object = idx;
    g_strlcpy(j->name, o->name, sizeof j->name);
    atomic_store(&page->stop, 0);
    atomic_store(&page->fraction, 0.0);
    set_running(page, TRUE);
    set_status(page, "filtering...");
    page->tick = g_timeout_add(100, tick, page);
    page->task = g_task_new(NULL, NULL, filter_done, NULL);
    g_task_set_task_data(page->task, j, filter_job_free);
    g_task_run_in_thread(page->task, filter_thread);
    g_object_unref(page->task); /* the thread holds it until filter_done */
}

static void
cancel_clicked(GtkButton *b, gpointer user) {
    (void)b;
    atomic_store(&VVG_FILTER_PAGE(user)->stop, 1);
}

static void
show_help(VvgFilterPage *page) {
    const vv_filter_info *f =
        vv_filter_info_get((int)gtk_drop_down_get_selected(GTK_DROP_DOWN(page->which)));
    if (!f)
        return;
    char t[512];
    snprintf(t, sizeof t, "--%s %s\n%s", f->name, f->metavar, f->help);
    gtk_label_set_text(GTK_LABEL(page->help), t);
}

static void
which_changed(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    show_help(VVG_FILTER_PAGE(user));
}

/* Appends the chosen filter and its argument to the chain, checked first. */
static void
add_clicked(GtkButton *b, gpointer user) {
    (void)b;
    VvgFilterPage *page = user;
    const vv_filter_info *f =
        vv_filter_info_get((int)gtk_drop_down_get_selected(GTK_DROP_DOWN(page->which)));
    if (!f)
        return;
    const char *arg = gtk_editable_get_text(GTK_EDITABLE(page->arg));
    vv_filter_chain *c = NULL;
    vv_error_clear();
    vv_status s = vv_filter_chain_new(&c);
    if (s == VV_OK)
        s = vv_filter_chain_add(c, f->name, arg[0] ? arg : NULL);
    if (s != VV_OK) {
        set_status(page, vv_error_message());
        vv_filter_chain_free(c);
        return;
    }
    const char *cur = gtk_editable_get_text(GTK_EDITABLE(page->chain));
    char *next = cur[0] ? g_strdup_printf("%s %s", cur, vv_filter_chain_text(c))
                        : g_strdup(vv_filter_chain_text(c));
    gtk_editable_set_text(GTK_EDITABLE(page->chain), next);
    g_free(next);
    vv_filter_chain_free(c);
    set_status(page, "");
}

static void
clear_clicked(GtkButton *b, gpointer user) {
    (void)b;
    gtk_editable_set_text(GTK_EDITABLE(VVG_FILTER_PAGE(user)->chain), "");
}

static void
vvg_filter_page_dispose(GObject *obj) {
    VvgFilterPage *page = VVG_FILTER_PAGE(obj);
    atomic_store(&page->stop, 1);
    if (page->tick) {
        g_source_remove(page->tick);
        page->tick = 0;
    }
    g_clear_object(&page->doc);
    G_OBJECT_CLASS(vvg_filter_page_parent_class)->dispose(obj);
}

static void
vvg_filter_page_class_init(VvgFilterPageClass *klass) {
    G_OBJECT_CLASS(klass)->dispose = vvg_filter_page_dispose;
}

static void
vvg_filter_page_init(VvgFilterPage *page) {
    (void)page;
}

GtkWidget *
vvg_filter_page_new(VvgDocument *doc) {
    VvgFilterPage *page = g_object_new(VVG_TYPE_FILTER_PAGE, "orientation",
                                       GTK_ORIENTATION_VERTICAL, "spacing", 4, NULL);
    page->doc = g_object_ref(doc);
    GtkWidget *box = GTK_WIDGET(page);
    gtk_widget_set_margin_start(box, 8);
    gtk_widget_set_margin_end(box, 8);
    gtk_widget_set_margin_bottom(box, 8);

    vvg_section(box, "Filter chain, applied in order to the selected volume");
    page->chain = gtk_entry_new();
    vvg_name(page->chain, "filter chain");
    gtk_entry_set_placeholder_text(GTK_ENTRY(page->chain),
                                   "--gaussian 1.5 --threshold 300: --largest 1");
    g_signal_connect_swapped(page->chain, "activate", G_CALLBACK(apply_clicked), page);
    gtk_box_append(GTK_BOX(box), page->chain);
    GtkWidget *row = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    page->apply = gtk_button_new_with_label("Apply");
    page->cancel = gtk_button_new_with_label("Cancel");
    GtkWidget *clear = gtk_button_new_with_label("Clear");
    g_signal_connect(page->apply, "clicked", G_CALLBACK(apply_clicked), page);
    g_signal_connect(page->cancel, "clicked", G_CALLBACK(cancel_clicked), page);
    g_signal_connect(clear, "clicked", G_CALLBACK(clear_clicked), page);
    gtk_widget_set_sensitive(page->cancel, FALSE);
    gtk_box_append(GTK_BOX(row), page->apply);
    gtk_box_append(GTK_BOX(row), page->cancel);
    gtk_box_append(GTK_BOX(row), clear);
    gtk_box_append(GTK_BOX(box), row);
    page->adapt = gtk_check_button_new_with_label(
        "adapt the transfer function to a new value range (a ramp over it)");
    gtk_box_append(GTK_BOX(box), page->adapt);
    page->progress = gtk_progress_bar_new();
    gtk_box_append(GTK_BOX(box), page->progress);
    page->status = gtk_label_new("");
    gtk_label_set_wrap(GTK_LABEL(page->status), TRUE);
    gtk_label_set_selectable(GTK_LABEL(page->status), TRUE);
    gtk_label_set_xalign(GTK_LABEL(page->status), 0);
    gtk_label_set_yalign(GTK_LABEL(page->status), 0);
    /* two lines kept for it, so the controls below never move */
    gtk_widget_set_size_request(page->status, -1, 36);
    gtk_box_append(GTK_BOX(box), page->status);

    GtkWidget *g = vvg_section(box, "Add a step");
    const char **names = g_new0(const char *, (gsize)vv_filter_info_count() + 1);
    for (int i = 0; i < vv_filter_info_count(); i++)
        names[i] = vv_filter_info_get(i)->name;
    page->which = vvg_row(g, "filter", gtk_drop_down_new_from_strings(names));
    g_free(names);
    g_signal_connect(page->which, "notify::selected", G_CALLBACK(which_changed), page);
    page->arg = vvg_row(g, "argument", gtk_entry_new());
    g_signal_connect_swapped(page->arg, "activate", G_CALLBACK(add_clicked), page);
    page->help = gtk_label_new("");
    gtk_label_set_wrap(GTK_LABEL(page->help), TRUE);
    gtk_label_set_xalign(GTK_LABEL(page->help), 0);
    gtk_label_set_max_width_chars(GTK_LABEL(page->help), 40);
    gtk_label_set_yalign(GTK_LABEL(page->help), 0);
    gtk_widget_set_size_request(page->help, -1, 66); /* up to four lines: no moving below */
    gtk_grid_attach(GTK_GRID(g), page->help, 0, vvg_grid_rows(g), 2, 1);
    GtkWidget *add = gtk_button_new_with_label("Add step");
    g_signal_connect(add, "clicked", G_CALLBACK(add_clicked), page);
    gtk_box_append(GTK_BOX(box), add);
    show_help(page);
    GtkWidget *note = gtk_label_new(
        "Sigmas and spacings are in world units (the volume's, usually mm), radii in voxels. "
        "Results are identical for any thread count. A chain ending in --components gives a "
        "label volume, shown by label. See docs/filtering.md.");
    gtk_label_set_wrap(GTK_LABEL(note), TRUE);
    gtk_label_set_xalign(GTK_LABEL(note), 0);
    gtk_label_set_max_width_chars(GTK_LABEL(note), 40);
    gtk_box_append(GTK_BOX(box), note);
    return box;
}
