/* The raw-import dialog with a live slice preview (vvg-raw-dialog.h). */
#define _POSIX_C_SOURCE 200809L /* fseeko */
#include "vvg-raw-dialog.h"
#include "vvg-widgets.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

typedef struct raw_dialog {
    GtkWidget *window, *file, *dims[3], *type, *endian, *spacing[3], *skip, *preview, *status;
    GtkWidget *import;
    VvgDocument *doc;
    float *slice;
    int sw, sh;
    gboolean ok;
} raw_dialog;

static const vv_voxel_type types[] = {VV_U8, VV_I8, VV_U16, VV_I16, VV_U32, VV_I32, VV_F32, VV_F64};
static const char *const type_names[] = {"u8",  "i8",  "u16", "i16", "u32",
                                         "i32", "f32", "f64", NULL};
static const int type_bytes[] = {1, 1, 2, 2, 4, 4, 4, 8};

/* One voxel of @p size bytes at @p b, of type @p t, byte-swapped when the
 * file's order is not the machine's. */
static double
voxel_value(const unsigned char *b, int t, int swap) {
    unsigned char v[8];
    int n = type_bytes[t];
    for (int i = 0; i < n; i++)
        v[i] = swap ? b[n - 1 - i] : b[i];
    switch (types[t]) {
    case VV_U8:
        return v[0];
    case VV_I8:
        return (signed char)v[0];
    case VV_U16: {
        uint16_t x;
        memcpy(&x, v, 2);
        return x;
    }
    case VV_I16: {
        int16_t x;
        memcpy(&x, v, 2);
        return x;
    }
    case VV_U32: {
        uint32_t x;
        memcpy(&x, v, 4);
        return x;
    }
    case VV_I32: {
        int32_t x;
        memcpy(&x, v, 4);
        return x;
    }
    case VV_F32: {
        float x;
        memcpy(&x, v, 4);
        return x;
    }
    default: {
        double x;
        memcpy(&x, v, 8);
        return x;
    }
    }
}

static int
type_index(vv_voxel_type t) {
    for (int i = 0; i < 8; i++)
        if (types[i] == t)
            return i;
    return 0;
}

gboolean
vvg_raw_preview_slice(const char *path, const vv_raw_params *p, float *out, char *why,
                      size_t why_size) {
    int t = type_index(p->type), n = type_bytes[t];
    size_t row = (size_t)p->dims[0] * n, plane = row * p->dims[1];
    uint64_t need = p->header_skip + (uint64_t)plane * p->dims[2];
    struct stat st;
    if (stat(path, &st) != 0) {
        snprintf(why, why_size, "%s: %s", path, g_strerror(errno));
        return FALSE;
    }
    if ((uint64_t)st.st_size < need) {
        snprintf(why, why_size,
                 "the file has %llu bytes; %llu header bytes and %d × %d × %d %s voxels need "
                 "%llu",
                 (unsigned long long)st.st_size, (unsigned long long)p->header_skip, p->dims[0],
                 p->dims[1], p->dims[2], type_names[t], (unsigned long long)need);
        return FALSE;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(why, why_size, "%s: %s", path, g_strerror(errno));
        return FALSE;
    }
    unsigned char *buf = g_malloc(plane);
    off_t at = (off_t)(p->header_skip + (uint64_t)plane * (p->dims[2] / 2));
    gboolean ok = fseeko(f, at, SEEK_SET) == 0 && fread(buf, 1, plane, f) == plane;
    fclose(f);
    if (!ok) {
        snprintf(why, why_size, "%s: cannot read the middle slice", path);
        g_free(buf);
        return FALSE;
    }
    int swap = p->big_endian != (G_BYTE_ORDER == G_BIG_ENDIAN);
    for (size_t i = 0; i < (size_t)p->dims[0] * p->dims[1]; i++)
        out[i] = (float)voxel_value(buf + i * n, t, swap);
    g_free(buf);
    if ((uint64_t)st.st_size > need)
        snprintf(why, why_size, "%llu bytes after the voxels are not used",
                 (unsigned long long)(st.st_size - need));
    else
        snprintf(why, why_size, "the file holds exactly the header and the voxels");
    return TRUE;
}

static void
params_of(raw_dialog *d, vv_raw_params *p) {
    vv_raw_params_init(p);
    for (int i = 0; i < 3; i++) {
        p->dims[i] = (int)vvg_spin_value(d->dims[i]);
        p->spacing[i] = vvg_spin_value(d->spacing[i]);
    }
    p->type = types[gtk_drop_down_get_selected(GTK_DROP_DOWN(d->type))];
    p->big_endian = gtk_drop_down_get_selected(GTK_DROP_DOWN(d->endian)) == 1;
    p->header_skip = (uint64_t)vvg_spin_value(d->skip);
}

static void
update(raw_dialog *d) {
    vv_raw_params p;
    params_of(d, &p);
    const char *path = gtk_editable_get_text(GTK_EDITABLE(d->file));
    g_free(d->slice);
    d->slice = g_new(float, (size_t)p.dims[0] * p.dims[1]);
    d->sw = p.dims[0];
    d->sh = p.dims[1];
    char why[256];
    d->ok = path[0] && vvg_raw_preview_slice(path, &p, d->slice, why, sizeof why);
    if (!path[0])
        g_strlcpy(why, "choose a file", sizeof why);
    gtk_label_set_text(GTK_LABEL(d->status), why);
    gtk_widget_set_sensitive(d->import, d->ok);
    gtk_widget_queue_draw(d->preview);
}

static void
preview_draw(GtkDrawingArea *a, cairo_t *cr, int W, int H, gpointer user) {
    (void)a;
    raw_dialog *d = user;
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    cairo_paint(cr);
    if (!d->ok || d->sw < 1 || d->sh < 1)
        return;
    size_t n = (size_t)d->sw * d->sh;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++)
        if (isfinite(d->slice[i])) {
            lo = fmin(lo, d->slice[i]);
            hi = fmax(hi, d->slice[i]);
        }
    cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, d->sw, d->sh);
    cairo_surface_flush(s);
    unsigned char *data = cairo_image_surface_get_data(s);
    int stride = cairo_image_surface_get_stride(s);
    for (int y = 0; y < d->sh; y++) /* row j = dims[1] - 1 at the top: y up */
        vv_slice_window_level(d->slice + (size_t)(d->sh - 1 - y) * d->sw, (size_t)d->sw,
                              hi > lo ? hi - lo : 1, 0.5 * (lo + hi), vv_vec3_make(0, 0, 0),
                              data + (size_t)y * stride);
    cairo_surface_mark_dirty(s);
    double sc = fmin((double)W / d->sw, (double)H / d->sh);
    cairo_translate(cr, 0.5 * (W - sc * d->sw), 0.5 * (H - sc * d->sh));
    cairo_scale(cr, sc, sc);
    cairo_set_source_surface(cr, s, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_paint(cr);
    cairo_surface_destroy(s);
}

static void
changed_spin(GtkSpinButton *s, gpointer user) {
    (void)s;
    update(user);
}

static void
changed_drop(GObject *o, GParamSpec *p, gpointer user) {
    (void)o;
    (void)p;
    update(user);
}

static void
changed_entry(GtkEditable *e, gpointer user) {
    (void)e;
    update(user);
}

static void
chosen(GtkNativeDialog *fc, int response, gpointer user) {
    raw_dialog *d = user;
    if (response == GTK_RESPONSE_ACCEPT) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(fc));
        g_autofree char *p = g_file_get_path(f);
        if (p)
            gtk_editable_set_text(GTK_EDITABLE(d->file), p);
        g_object_unref(f);
    }
    g_object_unref(fc);
}

static void
choose_clicked(GtkButton *b, gpointer user) {
    (void)b;
    raw_dialog *d = user;
    GtkFileChooserNative *fc = gtk_file_chooser_native_new(
        "Raw file", GTK_WINDOW(d->window), GTK_FILE_CHOOSER_ACTION_OPEN, "_Choose", "_Cancel");
    g_signal_connect(fc, "response", G_CALLBACK(chosen), d);
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(fc));
}

static void
import_clicked(GtkButton *b, gpointer user) {
    (void)b;
    raw_dialog *d = user;
    vv_load_options opt;
    vv_load_options_init(&opt);
    opt.format = VV_FORMAT_RAW;
    opt.has_raw = 1;
    params_of(d, &opt.raw);
    const char *path = gtk_editable_get_text(GTK_EDITABLE(d->file));
    vv_volume *v = NULL;
    vv_error_clear();
    if (vv_volume_load(&v, path, &opt) != VV_OK) {
        vvg_show_error(d->window, "Cannot import the raw file", vv_error_message());
        return;
    }
    g_autofree char *base = g_path_get_basename(path);
    GError *err = NULL;
    /* a scene cannot describe raw data: saved as NRRD beside the scene */
    if (!vvg_document_add_volume(d->doc, v, base, NULL, &err)) {
        vvg_show_error(d->window, "Cannot import the raw file", err->message);
        g_error_free(err);
    } else {
        gtk_window_destroy(GTK_WINDOW(d->window));
    }
    vv_volume_free(v);
}

static void
dialog_free(gpointer p) {
    raw_dialog *d = p;
    g_object_unref(d->doc);
    g_free(d->slice);
    g_free(d);
}

/* The form: file, dimensions, type, endianness, spacing, header skip. */
static GtkWidget *
form(raw_dialog *d, const char *path) {
    GtkWidget *box = vvg_page_box();
    GtkWidget *g = vvg_section(box, "Raw voxels");
    GtkWidget *frow = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    d->file = gtk_entry_new();
    gtk_widget_set_hexpand(d->file, TRUE);
    gtk_editable_set_text(GTK_EDITABLE(d->file), path ? path : "");
    GtkWidget *choose = gtk_button_new_with_label("Choose…");
    g_signal_connect(choose, "clicked", G_CALLBACK(choose_clicked), d);
    gtk_box_append(GTK_BOX(frow), d->file);
    gtk_box_append(GTK_BOX(frow), choose);
    vvg_row(g, "file", frow);
    vvg_name(d->file, "file");
    const char *dn[] = {"width (i)", "height (j)", "slices (k)"};
    const char *sn[] = {"spacing i", "spacing j", "spacing k"};
    for (int i = 0; i < 3; i++)
        d->dims[i] = vvg_row(g, dn[i], vvg_spin(1, VV_VOLUME_MAX_DIM, 1, 0, 64));
    d->type = vvg_row(g, "voxel type", gtk_drop_down_new_from_strings(type_names));
    static const char *const endians[] = {"little-endian", "big-endian", NULL};
    d->endian = vvg_row(g, "byte order", gtk_drop_down_new_from_strings(endians));
    for (int i = 0; i < 3; i++)
        d->spacing[i] = vvg_row(g, sn[i], vvg_spin(1e-6, 1e6, 0.1, 4, 1));
    d->skip = vvg_row(g, "header bytes to skip", vvg_spin(0, 1e12, 1, 0, 0));
    g_signal_connect(d->file, "changed", G_CALLBACK(changed_entry), d);
    for (int i = 0; i < 3; i++) {
        g_signal_connect(d->dims[i], "value-changed", G_CALLBACK(changed_spin), d);
        g_signal_connect(d->spacing[i], "value-changed", G_CALLBACK(changed_spin), d);
    }
    g_signal_connect(d->skip, "value-changed", G_CALLBACK(changed_spin), d);
    g_signal_connect(d->type, "notify::selected", G_CALLBACK(changed_drop), d);
    g_signal_connect(d->endian, "notify::selected", G_CALLBACK(changed_drop), d);
    return box;
}

void
vvg_raw_dialog_present(GtkWindow *parent, VvgDocument *doc, const char *path) {
    raw_dialog *d = g_new0(raw_dialog, 1);
    d->doc = g_object_ref(doc);
    d->window = gtk_window_new();
    gtk_window_set_title(GTK_WINDOW(d->window), "VolVis — import raw");
    gtk_window_set_transient_for(GTK_WINDOW(d->window), parent);
    gtk_window_set_modal(GTK_WINDOW(d->window), TRUE);
    gtk_window_set_default_size(GTK_WINDOW(d->window), 760, 520);
    vvg_close_on_escape(GTK_WINDOW(d->window));
    g_object_set_data_full(G_OBJECT(d->window), "raw-dialog", d, dialog_free);
    GtkWidget *h = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 8);
    GtkWidget *left = form(d, path);
    gtk_box_append(GTK_BOX(h), left);
    GtkWidget *right = gtk_box_new(GTK_ORIENTATION_VERTICAL, 6);
    gtk_widget_set_margin_end(right, 8);
    gtk_widget_set_margin_top(right, 8);
    GtkWidget *pt = gtk_label_new("Middle slice (k = slices / 2)");
    gtk_label_set_xalign(GTK_LABEL(pt), 0);
    gtk_box_append(GTK_BOX(right), pt);
    d->preview = gtk_drawing_area_new();
    gtk_widget_set_hexpand(d->preview, TRUE);
    gtk_widget_set_vexpand(d->preview, TRUE);
    gtk_widget_set_size_request(d->preview, 300, 300);
    vvg_name(d->preview, "raw preview");
    gtk_drawing_area_set_draw_func(GTK_DRAWING_AREA(d->preview), preview_draw, d, NULL);
    gtk_box_append(GTK_BOX(right), d->preview);
    d->status = gtk_label_new("");
    gtk_label_set_wrap(GTK_LABEL(d->status), TRUE);
    gtk_label_set_xalign(GTK_LABEL(d->status), 0);
    vvg_name(d->status, "raw status");
    gtk_box_append(GTK_BOX(right), d->status);
    GtkWidget *buttons = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 6);
    gtk_widget_set_halign(buttons, GTK_ALIGN_END);
    GtkWidget *cancel = gtk_button_new_with_label("Cancel");
    g_signal_connect_swapped(cancel, "clicked", G_CALLBACK(gtk_window_destroy), d->window);
    d->import = gtk_button_new_with_label("Import");
    gtk_widget_add_css_class(d->import, "suggested-action");
    g_signal_connect(d->import, "clicked", G_CALLBACK(import_clicked), d);
    gtk_box_append(GTK_BOX(buttons), cancel);
    gtk_box_append(GTK_BOX(buttons), d->import);
    gtk_box_append(GTK_BOX(right), buttons);
    gtk_box_append(GTK_BOX(h), right);
    gtk_window_set_child(GTK_WINDOW(d->window), h);
    update(d);
    gtk_window_present(GTK_WINDOW(d->window));
}
