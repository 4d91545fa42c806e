/* The DICOM browser: patients, studies and series (vvg-dicom-dialog.h). */
#include "vvg-dicom-dialog.h"
#include "vvg-widgets.h"

#include <stdlib.h>
#include <string.h>

typedef struct dicom_dialog {
    GtkWidget *window, *folder, *list, *show_phi, *status, *open;
    VvgDocument *doc;
    vv_dicom_series *series;
    int n;
    char *path; /* the folder listed */
} dicom_dialog;

/* The patient of series @p i as shown: the name and ID only when asked. */
static char *
patient_label(dicom_dialog *d, int i, int number) {
    const vv_dicom_series *s = &d->series[i];
    if (gtk_check_button_get_active(GTK_CHECK_BUTTON(d->show_phi)))
        return g_strdup_printf("Patient %s (ID %s)", s->patient_name[0] ? s->patient_name : "?",
                               s->patient_id[0] ? s->patient_id : "?");
    return g_strdup_printf("Patient %d", number);
}

static GtkWidget *
header_row(const char *markup, int indent) {
    GtkWidget *l = gtk_label_new(NULL);
    gtk_label_set_markup(GTK_LABEL(l), markup);
    gtk_label_set_xalign(GTK_LABEL(l), 0);
    gtk_widget_set_margin_start(l, indent);
    GtkWidget *row = gtk_list_box_row_new();
    gtk_list_box_row_set_child(GTK_LIST_BOX_ROW(row), l);
    gtk_list_box_row_set_selectable(GTK_LIST_BOX_ROW(row), FALSE);
    gtk_list_box_row_set_activatable(GTK_LIST_BOX_ROW(row), FALSE);
    return row;
}

/* Patients, their studies and their series, in vv_dicom_list's order. */
static void
rebuild(dicom_dialog *d) {
    GtkWidget *c;
    while ((c = gtk_widget_get_first_child(d->list)))
        gtk_list_box_remove(GTK_LIST_BOX(d->list), c);
    int patients = 0;
    for (int i = 0; i < d->n; i++) {
        const vv_dicom_series *s = &d->series[i];
        /* a new patient or study header when it changes (series are listed by number) */
        int new_patient = 1, new_study = 1;
        for (int k = 0; k < i; k++) {
            const vv_dicom_series *t = &d->series[k];
            if (!strcmp(t->patient_id, s->patient_id) &&
                !strcmp(t->patient_name, s->patient_name)) {
                new_patient = 0;
                if (!strcmp(t->study_description, s->study_description) &&
                    !strcmp(t->study_date, s->study_date))
                    new_study = 0;
            }
        }
        if (new_patient) {
            g_autofree char *p = patient_label(d, i, ++patients);
            g_autofree char *m = g_markup_printf_escaped("<b>%s</b>", p);
            gtk_list_box_append(GTK_LIST_BOX(d->list), header_row(m, 0));
        }
        if (new_patient || new_study) {
            g_autofree char *m = g_markup_printf_escaped(
                "Study %s, %s", s->study_description[0] ? s->study_description : "(no description)",
                s->study_date[0] ? s->study_date : "no date");
            gtk_list_box_append(GTK_LIST_BOX(d->list), header_row(m, 16));
        }
        g_autofree char *steps =
            s->time_steps > 1 ? g_strdup_printf(" × %d time steps", s->time_steps) : g_strdup("");
        g_autofree char *t = g_strdup_printf(
            "Series %d: %s %s — %d × %d × %d%s, %d file%s", s->number,
            s->modality[0] ? s->modality : "?", s->description[0] ? s->description : "", s->dims[0],
            s->dims[1], s->dims[2], steps, s->n_files, s->n_files == 1 ? "" : "s");
        GtkWidget *l = gtk_label_new(t);
        gtk_label_set_xalign(GTK_LABEL(l), 0);
        gtk_widget_set_margin_start(l, 32);
        GtkWidget *row = gtk_list_box_row_new();
        gtk_list_box_row_set_child(GTK_LIST_BOX_ROW(row), l);
        g_object_set_data(G_OBJECT(row), "series", GINT_TO_POINTER(i + 1));
        gtk_list_box_append(GTK_LIST_BOX(d->list), row);
    }
}

static void
list_folder(dicom_dialog *d) {
    const char *path = gtk_editable_get_text(GTK_EDITABLE(d->folder));
    free(d->series);
    d->series = NULL;
    d->n = 0;
    g_free(d->path);
    d->path = g_strdup(path);
    vv_error_clear();
    if (!path[0]) {
        gtk_label_set_text(GTK_LABEL(d->status), "choose a folder");
    } else if (vv_dicom_list(&d->series, &d->n, path) != VV_OK) {
        gtk_label_set_text(GTK_LABEL(d->status), vv_error_message());
    } else {
        g_autofree char *m = g_strdup_printf("%d series", d->n);
        gtk_label_set_text(GTK_LABEL(d->status), m);
    }
    rebuild(d);
}

static void
folder_activated(GtkEntry *e, gpointer user) {
    (void)e;
    list_folder(user);
}

static void
phi_toggled(GtkCheckButton *b, gpointer user) {
    (void)b;
    rebuild(user);
}

static void
chosen(GtkNativeDialog *fc, int response, gpointer user) {
    dicom_dialog *d = user;
    if (response == GTK_RESPONSE_ACCEPT) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(fc));
        g_autofree char *p = g_file_get_path(f);
        if (p) {
            gtk_editable_set_text(GTK_EDITABLE(d->folder), p);
            list_folder(d);
        }
        g_object_unref(f);
    }
    g_object_unref(fc);
}

static void
choose_clicked(GtkButton *b, gpointer user) {
    (void)b;
    dicom_dialog *d = user;
    GtkFileChooserNative *fc =
        gtk_file_chooser_native_new("DICOM folder", GTK_WINDOW(d->window),
                                    GTK_FILE_CHOOSER_ACTION_SELECT_FOLDER, "_Choose", "_Cancel");
    g_signal_connect(fc, "response", G_CALLBACK(chosen), d);
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(fc));
}

static void
open_series(dicom_dialog *d, int series) {
    vv_load_options opt;
    vv_load_options_init(&opt);
    opt.series = series;
    vv_volume *v = NULL;
    vv_error_clear();
    if (vv_volume_load(&v, d->path, &opt) != VV_OK) {
        vvg_show_error(d->window, "Cannot read the series", vv_error_message());
        return;
    }
    const vv_dicom_series *s = &d->series[series - 1];
    g_autofree char *name =
        g_strdup_printf("%s %d", s->modality[0] ? s->modality : "series", s->number);
    GError *err = NULL;
    /* a scene names a folder, not one of its series: one series is read again
     * from the folder, one of several is written beside the scene */
    if (!vvg_document_add_volume(d->doc, v, name, d->n == 1 ? d->path : NULL, &err)) {
        vvg_show_error(d->window, "Cannot open the series", err->message);
        g_error_free(err);
    } else {
        gtk_window_destroy(GTK_WINDOW(d->window));
    }
    vv_volume_free(v);
}

static void
open_clicked(GtkButton *b, gpointer user) {
    (void)b;
    dicom_dialog *d = user;
    GtkListBoxRow *r = gtk_list_box_get_selected_row(GTK_LIST_BOX(d->list));
    int series = r ? GPOINTER_TO_INT(g_object_get_data(G_OBJECT(r), "series")) : 0;
    if (series > 0)
        open_series(d, series);
}

static void
row_activated(GtkListBox *box, GtkListBoxRow *r, gpointer user) {
    (void)box;
    int series = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(r), "series"));
    if (series > 0)
        open_series(user, series);
}

static void
dialog_free(gpointer p) {
    dicom_dialog *d = p;
    g_object_unref(d->doc);
    free(d->series);
    g_free(d->path);
    g_free(d);
}

void
vvg_dicom_dialog_present(GtkWindow *parent, VvgDocument *doc) {
    dicom_dialog *d = g_new0(dicom_dialog, 1);
    d->doc = g_object_ref(doc);
    d->window = gtk_window_new();
    gtk_window_set_title(GTK_WINDOW(d->window), "VolVis — DICOM");
    gtk_window_set_transient_for(GTK_WINDOW(d->window), parent);
    gtk_window_set_modal(GTK_WINDOW(d->window), TRUE);
    gtk_window_set_default_size(GTK_WINDOW(d->window), 640, 480);
    vvg_close_on_escape(GTK_WINDOW(d->window));
    g_object_set_data_full(G_OBJECT(d->window), "dicom-dialog", d, dialog_free);
    GtkWidget *box = vvg_page_box();
    gtk_widget_set_margin_top(box, 8);
    GtkWidget *g = vvg_section(box, "Folder or DICOMDIR");
    GtkWidget *frow = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    d->folder = gtk_entry_new();
    gtk_widget_set_hexpand(d->folder, TRUE);
    gtk_entry_set_placeholder_text(GTK_ENTRY(d->folder), "path, Enter to list");
    g_signal_connect(d->folder, "activate", G_CALLBACK(folder_activated), d);
    GtkWidget *choose = gtk_button_new_with_label("Choose…");
    g_signal_connect(choose, "clicked", G_CALLBACK(choose_clicked), d);
    gtk_box_append(GTK_BOX(frow), d->folder);
    gtk_box_append(GTK_BOX(frow), choose);
    vvg_row(g, "folder", frow);
    vvg_name(d->folder, "folder");
    d->show_phi = gtk_check_button_new_with_label("Show patient names and IDs");
    g_signal_connect(d->show_phi, "toggled", G_CALLBACK(phi_toggled), d);
    gtk_box_append(GTK_BOX(box), d->show_phi);
    d->list = gtk_list_box_new();
    /* a click selects a series, a double click (or Open series) opens it */
    gtk_list_box_set_activate_on_single_click(GTK_LIST_BOX(d->list), FALSE);
    vvg_name(d->list, "series");
    g_signal_connect(d->list, "row-activated", G_CALLBACK(row_activated), d);
    GtkWidget *sc = vvg_scrolled(d->list);
    gtk_box_append(GTK_BOX(box), sc);
    d->status = gtk_label_new("choose a folder");
    gtk_label_set_xalign(GTK_LABEL(d->status), 0);
    gtk_label_set_wrap(GTK_LABEL(d->status), TRUE);
    vvg_name(d->status, "DICOM status");
    gtk_box_append(GTK_BOX(box), d->status);
    GtkWidget *buttons = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 6);
    gtk_widget_set_halign(buttons, GTK_ALIGN_END);
    GtkWidget *close = gtk_button_new_with_label("Close");
    g_signal_connect_swapped(close, "clicked", G_CALLBACK(gtk_window_destroy), d->window);
    d->open = gtk_button_new_with_label("Open series");
    gtk_widget_add_css_class(d->open, "suggested-action");
    g_signal_connect(d->open, "clicked", G_CALLBACK(open_clicked), d);
    gtk_box_append(GTK_BOX(buttons), close);
    gtk_box_append(GTK_BOX(buttons), d->open);
    gtk_box_append(GTK_BOX(box), buttons);
    gtk_window_set_child(GTK_WINDOW(d->window), box);
    gtk_window_present(GTK_WINDOW(d->window));
}
