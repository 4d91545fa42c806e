/*
 * Where a format row's work runs (src/io/transport.h): here, or in the
 * reader sandbox for the rows of third-party parsers. The parent's side of
 * every call: the arguments packed for the reader, its result checked
 * (the sandbox checks volumes, grids and meshes; the load info and the
 * DICOM listing are checked here, field by field).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "io/transport.h"

int
io_sandboxed(const vv_format_record *r) {
    /* VOLVIS_SANDBOX=all: our own parsers too (the built-in rows only) */
    return (!r || (r->flags & VV_FORMAT_FLAG_THIRD_PARTY) ||
            (vv_sandbox_all() && io_format_built_in(r))) &&
           vv_sandbox_enabled();
}

const vv_format_record *
io_row_named(const char *name) {
    int n;
    const vv_format_record *const *t = vv_format_table(&n);
    for (int i = 0; name && *name && i < n; i++)
        if (!strcmp(t[i]->name, name))
            return t[i];
    return NULL;
}

int
io_info_from_wire(vv_load_info *info, const unsigned char *bytes, size_t n) {
    memset(info, 0, sizeof *info);
    if (n != sizeof *info)
        return 0;
    vv_load_info w;
    memcpy(&w, bytes, sizeof w);
    if (w.n_channels < 0 || w.n_channels > VV_VOLUME_MAX_DIM || w.n_times < 0 ||
        w.n_times > VV_VOLUME_MAX_DIM || w.n_levels < 0 || w.n_levels > 64 || w.n_slices < 0 ||
        w.n_slices > VV_VOLUME_MAX_DIM || !memchr(w.channel_name, 0, sizeof w.channel_name) ||
        !(w.time_step >= 0 && w.time_step < 1e12) ||
        !(w.color[0] >= 0 && w.color[0] <= 1 && w.color[1] >= 0 && w.color[1] <= 1 &&
          w.color[2] >= 0 && w.color[2] <= 1))
        return 0;
    info->n_channels = w.n_channels;
    info->n_times = w.n_times;
    info->n_levels = w.n_levels;
    info->n_slices = w.n_slices;
    info->has_color = w.has_color != 0;
    info->is_label = w.is_label == 1;
    memcpy(info->color, w.color, sizeof info->color);
    info->time_step = w.time_step;
    /* offsets into the file, checked against its size by their reader */
    info->has_raw_layout = w.has_raw_layout == 1;
    info->raw_big_endian = w.raw_big_endian != 0;
    info->raw_offset = w.raw_offset;
    info->raw_step_bytes = w.raw_step_bytes;
    info->raw_channel_bytes = w.raw_channel_bytes;
    memcpy(info->channel_name, w.channel_name, sizeof info->channel_name);
    for (char *c = info->channel_name; *c; c++) /* printable, for messages and lists */
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            *c = '?';
    /* the display window when it is two finite numbers in order; the
     * warning a line of printable text */
    info->has_window = w.has_window == 1 && isfinite(w.window[0]) && isfinite(w.window[1]) &&
                       w.window[0] < w.window[1];
    if (info->has_window)
        memcpy(info->window, w.window, sizeof info->window);
    info->inactive = w.inactive == 1;
    if (memchr(w.warning, 0, sizeof w.warning)) {
        memcpy(info->warning, w.warning, sizeof info->warning);
        for (char *c = info->warning; *c; c++)
            if ((unsigned char)*c < 0x20 || *c == 0x7f)
                *c = '?';
    }
    return 1;
}

vv_status
io_geometry_status(const vv_format_record *r, const vv_volume *v, const char *path) {
    static const char axis[3] = {'x', 'y', 'z'};
    const char *what = NULL;
    int a = 0;
    for (int i = 0; i < 3 && !what; i++) {
        a = i;
        if (!(v->spacing[i] > 0) || !isfinite(v->spacing[i]))
            what = "spacing";
        else if (!isfinite(v->origin[i]))
            what = "origin";
        for (int j = 0; j < 3 && !what; j++)
            if (!isfinite(v->direction[3 * i + j]))
                what = "direction";
    }
    if (!what)
        return VV_OK;
    const int spacing = !strcmp(what, "spacing");
    const double x = spacing ? v->spacing[a] : !strcmp(what, "origin") ? v->origin[a] : NAN;
    return vv_error_set(VV_ERR_FORMAT, "%s: %s: the %s along %c is %g (a %s must be %s)",
                        r ? r->name : "load", vv_path_basename(path), what, axis[a], x, what,
                        spacing ? "positive and finite" : "finite");
}

vv_status
io_check_geometry(const vv_format_record *r, vv_volume **v, const char *path) {
    const vv_status s = io_geometry_status(r, *v, path);
    if (s != VV_OK) {
        vv_volume_free(*v);
        *v = NULL;
    }
    return s;
}

vv_status
io_read_volume(const vv_format_record *r, vv_volume **out, const char *path,
               const vv_load_options *opt, const vv_format_record **used) {
    *out = NULL;
    if (used)
        *used = r;
    /* a remote store (http, https, s3) is fetched and read here: the
     * reader's policy allows no sockets (docs/security.md, "Remote data") */
    if (r && (!io_sandboxed(r) || bs_is_url(path))) {
        vv_status s = r->read(out, path, opt);
        return s == VV_OK ? io_check_geometry(r, out, path) : s;
    }
    io_volume_args a;
    memset(&a, 0, sizeof a);
    a.has_raw = opt->has_raw;
    a.raw = opt->raw;
    a.series = opt->series;
    a.channel = opt->channel;
    a.time = opt->time;
    a.level = opt->level;
    a.z_first = opt->z_first;
    a.z_count = opt->z_count;
    const vv_sandbox_call c = {
        VV_SANDBOX_VOLUME, r ? r->name : "", r ? r->name : "load", r ? r->title : "file", path, &a,
        sizeof a};
    vv_sandbox_result res;
    vv_status s = vv_sandbox_call_reader(&c, &res);
    if (s != VV_OK)
        return s;
    const vv_format_record *named = io_row_named(res.format);
    if (res.info_len != sizeof(vv_load_info)) {
        const size_t got = res.info_len;
        vv_sandbox_result_clear(&res);
        return vv_error_set(VV_ERR_IO,
                            "%s: %s: the reader's load info is %zu bytes where this build's is %zu "
                            "(another build's volvis-reader: set VOLVIS_READER to this build's)",
                            named ? named->name : "load", vv_path_basename(path), got,
                            sizeof(vv_load_info));
    }
    if (!io_info_from_wire(opt->info, res.info, res.info_len) || !res.volume) {
        vv_sandbox_result_clear(&res);
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: %s: the reader's result has broken channel or time axes",
                            named ? named->name : "load", vv_path_basename(path));
    }
    if (used)
        *used = named ? named : r;
    *out = res.volume;
    res.volume = NULL;
    vv_sandbox_result_clear(&res);
    return VV_OK;
}

vv_status
io_read_grid(const vv_format_record *r, vv_grid **out, const char *path) {
    *out = NULL;
    if (!io_sandboxed(r))
        return r->read_grid(out, path);
    const vv_sandbox_call c = {VV_SANDBOX_GRID, r->name, r->name, r->title, path, NULL, 0};
    vv_sandbox_result res;
    vv_status s = vv_sandbox_call_reader(&c, &res);
    if (s == VV_OK) {
        *out = res.grid;
        res.grid = NULL;
    }
    vv_sandbox_result_clear(&res);
    return s;
}

vv_status
io_read_mesh(const vv_format_record *r, vv_mesh **out, const char *path) {
    *out = NULL;
    if (!io_sandboxed(r))
        return r->read_mesh(out, path);
    const vv_sandbox_call c = {VV_SANDBOX_MESH, r->name, r->name, r->title, path, NULL, 0};
    vv_sandbox_result res;
    vv_status s = vv_sandbox_call_reader(&c, &res);
    if (s == VV_OK) {
        *out = res.mesh;
        res.mesh = NULL;
    }
    vv_sandbox_result_clear(&res);
    return s;
}

vv_status
io_open_store(const vv_format_record *r, vv_store *st, const char *path, int channel, int time,
              vv_load_info *info) {
    memset(st, 0, sizeof *st);
    if (!io_sandboxed(r) || bs_is_url(path)) /* a remote store: here, as io_read_volume */
        return r->open_store(st, path, channel, time, info);
    const io_store_args a = {channel, time};
    const vv_sandbox_call c = {VV_SANDBOX_STORE, r->name, r->name, r->title, path, &a, sizeof a};
    unsigned char wire[VV_SANDBOX_INFO_MAX];
    size_t n = 0;
    vv_status s = vv_sandbox_open_store(&c, st, wire, &n);
    vv_load_info got;
    if (s == VV_OK && !io_info_from_wire(&got, wire, n))
        s = vv_error_set(VV_ERR_FORMAT, "%s: %s: the reader's store has a broken channel name",
                         r->name, vv_path_basename(path));
    if (s != VV_OK) {
        vv_store_close(st);
        return s;
    }
    if (info) {
        info->has_color = got.has_color;
        info->is_label = got.is_label;
        memcpy(info->color, got.color, sizeof info->color);
        memcpy(info->channel_name, got.channel_name, sizeof info->channel_name);
        info->has_window = got.has_window;
        memcpy(info->window, got.window, sizeof info->window);
        info->inactive = got.inactive;
        memcpy(info->warning, got.warning, sizeof info->warning);
    }
    return VV_OK;
}

vv_status
io_dicom_series_from_wire(vv_dicom_series **out, int *count, void *bytes, size_t n,
                          const char *file) {
    vv_dicom_series *a = bytes;
    const size_t k = n / sizeof *a;
    if (n == 0 || n % sizeof *a || k > 200000) {
        free(bytes);
        return vv_error_set(VV_ERR_FORMAT, "dicom: %s: the reader's list of series is malformed",
                            file);
    }
    for (size_t i = 0; i < k; i++) {
        vv_dicom_series *e = &a[i];
        e->uid[sizeof e->uid - 1] = e->description[sizeof e->description - 1] = '\0';
        e->modality[sizeof e->modality - 1] = e->first_file[sizeof e->first_file - 1] = '\0';
        e->study_description[sizeof e->study_description - 1] = '\0';
        e->study_date[sizeof e->study_date - 1] = '\0';
        e->patient_name[sizeof e->patient_name - 1] = '\0';
        e->patient_id[sizeof e->patient_id - 1] = '\0';
        if (e->dims[0] < 0 || e->dims[1] < 0 || e->dims[2] < 0 || e->n_files < 0 ||
            e->time_steps < 1) {
            free(bytes);
            return vv_error_set(VV_ERR_FORMAT,
                                "dicom: %s: the reader's list of series is malformed", file);
        }
    }
    *out = a;
    *count = (int)k;
    return VV_OK;
}

vv_status
vv_dicom_list(vv_dicom_series **out, int *n, const char *path) {
    if (!out || !n || !path)
        return vv_error_set(VV_ERR_INVALID, "dicom: NULL argument");
    *out = NULL;
    *n = 0;
    const vv_format_record *r = vv_format_record_of(VV_FORMAT_DICOM);
    if (!io_sandboxed(r)) /* GDCM reads the headers here, or in volvis-reader */
        return io_dicom_list_local(out, n, path);
    const vv_sandbox_call c = {VV_SANDBOX_LIST, r->name, r->name, r->title, path, NULL, 0};
    vv_sandbox_result res;
    vv_status s = vv_sandbox_call_reader(&c, &res);
    if (s == VV_OK) {
        s = io_dicom_series_from_wire(out, n, res.blob, res.blob_len, vv_path_basename(path));
        res.blob = NULL;
    }
    vv_sandbox_result_clear(&res);
    return s;
}

/* "A, B or C" of the titles of the formats with (@p with) or without the
 * flags in @p mask, among those that can be detected when @p detectable. */
void
io_format_titles(char *buf, size_t cap, unsigned mask, int with, int detectable) {
    int n;
    const vv_format_record *const *t = vv_format_table(&n);
    const vv_format_record *pick[64];
    int k = 0;
    for (int i = 0; i < n && k < 64; i++)
        if (t[i]->holds == VV_DATA_VOLUME && !!(t[i]->flags & mask) == with &&
            (!detectable || t[i]->looks_like))
            pick[k++] = t[i];
    buf[0] = '\0';
    for (int i = 0; i < k; i++) {
        size_t len = strlen(buf);
        snprintf(buf + len, cap - len, "%s%s",
                 i == 0      ? ""
                 : i + 1 < k ? ", "
                             : " or ",
                 pick[i]->title);
    }
}

vv_status
io_unknown_volume_format(const char *path, int is_dir) {
    char list[512];
    if (is_dir) {
        io_format_titles(list, sizeof list, VV_FORMAT_FLAG_FOLDER, 1, 0);
        return vv_error_set(VV_ERR_FORMAT, "%s: no %s files in the folder", path, list);
    }
    io_format_titles(list, sizeof list, VV_FORMAT_FLAG_DESCRIBED, 0, 1);
    return vv_error_set(
        VV_ERR_FORMAT, "cannot tell the format of %s (not %s; use --raw for raw data)", path, list);
}
