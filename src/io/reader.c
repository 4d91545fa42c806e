/*
 * The reader process's side of the format table (volvis-reader; the
 * transport is include/volvis/sys/sandbox.h): each handler finds the row
 * the parent named -- or detects it, the deep tests included -- names it
 * (vv_sandbox_announce, so that a crash is named after its reader) and
 * calls the row's own read directly. The dispatch of the parent
 * (transport.c) is never run here.
 */
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/transport.h"
#include "volvis/sys/format.h"

/* The row @p format names, else the one detection finds among the rows
 * holding @p kind, announced; NULL (announced as "load") when none. */
static const vv_format_record *
row_for(vv_sandbox_server *srv, const char *format, const char *path, int kind, int raw) {
    const vv_format_record *r = io_row_named(format);
    if (!r) {
        vv_format f = vv_format_detect_kind(path, kind, 1);
        if (f == VV_FORMAT_UNKNOWN && raw)
            f = VV_FORMAT_RAW;
        r = vv_format_record_of(f);
    }
    vv_sandbox_announce(srv, r ? r->name : "load", r ? r->title : "file");
    return r;
}

static vv_status
no_row(const char *path) {
    return vv_error_set(VV_ERR_FORMAT, "cannot tell the format of %s", path);
}

static vv_status
h_volume(vv_sandbox_server *srv, const char *format, const char *path, const void *args, size_t n,
         vv_volume **out, unsigned char *info, size_t *info_len) {
    io_volume_args a;
    if (n != sizeof a)
        return vv_error_set(VV_ERR_INVALID, "the reader's arguments are %zu bytes", n);
    memcpy(&a, args, sizeof a);
    const vv_format_record *r = row_for(srv, format, path, VV_DATA_VOLUME, a.has_raw);
    if (!r || !r->read)
        return io_unknown_volume_format(path, 0);
    if (a.z_count > 0 && !(r->flags & VV_FORMAT_FLAG_SLICES))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "load: %s: %s is read whole, not a range of slices (TIFF stacks are)",
                            vv_path_basename(path), r->title);
    vv_load_info li;
    memset(&li, 0, sizeof li);
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_AUTO;
    o.has_raw = a.has_raw;
    o.raw = a.raw;
    o.series = a.series;
    o.channel = a.channel;
    o.time = a.time;
    o.level = a.level;
    o.z_first = a.z_first;
    o.z_count = a.z_count;
    o.info = &li;
    o.one_shot = 1; /* this process ends after the read */
    vv_status s = r->read(out, path, &o);
    if (s == VV_OK)
        s = io_check_geometry(r, out, path);
    if (s == VV_OK) {
        memcpy(info, &li, sizeof li);
        *info_len = sizeof li;
    }
    return s;
}

static vv_status
h_list(vv_sandbox_server *srv, const char *format, const char *path, const void *args, size_t n,
       void **blob, size_t *len) {
    (void)args;
    (void)n;
    (void)format;
    vv_sandbox_announce(srv, "dicom", "DICOM");
    vv_dicom_series *ser = NULL;
    int count = 0;
    vv_status s = io_dicom_list_local(&ser, &count, path);
    if (s == VV_OK) {
        *blob = ser;
        *len = (size_t)count * sizeof *ser;
    }
    return s;
}

static vv_status
h_mesh(vv_sandbox_server *srv, const char *format, const char *path, vv_mesh **out) {
    const vv_format_record *r = row_for(srv, format, path, VV_DATA_MESH, 0);
    return r && r->read_mesh ? r->read_mesh(out, path) : no_row(path);
}

static vv_status
h_grid(vv_sandbox_server *srv, const char *format, const char *path, vv_grid **out) {
    const vv_format_record *r = row_for(srv, format, path, VV_DATA_GRID, 0);
    return r && r->read_grid ? r->read_grid(out, path) : no_row(path);
}

static vv_status
h_store(vv_sandbox_server *srv, const char *format, const char *path, const void *args, size_t n,
        vv_store *st, unsigned char *info, size_t *info_len) {
    io_store_args a;
    if (n != sizeof a)
        return vv_error_set(VV_ERR_INVALID, "the reader's arguments are %zu bytes", n);
    memcpy(&a, args, sizeof a);
    const vv_format_record *r = row_for(srv, format, path, VV_DATA_VOLUME, 0);
    if (!r || !r->open_store)
        return no_row(path);
    vv_load_info li;
    memset(&li, 0, sizeof li);
    vv_status s = r->open_store(st, path, a.channel, a.time, &li);
    if (s == VV_OK) {
        memcpy(info, &li, sizeof li);
        *info_len = sizeof li;
    }
    return s;
}

static const vv_sandbox_handler handlers = {h_volume, h_list, h_mesh, h_grid, h_store};

int
vv_format_reader_main(int argc, char **argv) {
    return vv_sandbox_serve(argc, argv, &handlers);
}
