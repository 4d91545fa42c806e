/*
 * The generic load and save entry points of volumes, over the format table
 * (formats.c): a format's record reads (here or in the reader sandbox:
 * transport.c), fits and writes; nothing here knows a particular format.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/bytesrc.h"
#include "io/transport.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"
#include "volvis/sys/sandbox.h"

void
vv_load_options_init(vv_load_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->format = VV_FORMAT_AUTO;
    o->has_raw = 0;
    vv_raw_params_init(&o->raw);
    o->series = 0;
    o->channel = -1;
    o->time = -1;
    o->level = 0;
    o->z_first = o->z_count = 0;
    o->info = NULL;
}

void
vv_save_options_init(vv_save_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->format = VV_FORMAT_AUTO;
    o->strict = 0;
    o->compress = -1;
}

/* The record of volume format @p f, or NULL. */
static const vv_format_record *
format_of(vv_format f) {
    const vv_format_record *r = vv_format_record_of(f);
    return r && r->holds == VV_DATA_VOLUME ? r : NULL;
}

/* Checks @p path can be opened (a folder only by a format that reads folders). */
static vv_status
check_input(const char *path, vv_format f, int *is_dir) {
    if (bs_is_url(path)) { /* a remote store: a folder of objects, looked at by its reader */
        *is_dir = 1;
        return VV_OK;
    }
    struct stat st;
    if (stat(path, &st) != 0) {
        int e = errno;
        return vv_error_set(VV_ERR_IO, "cannot open %s: %s", path, strerror(e));
    }
    *is_dir = S_ISDIR(st.st_mode);
    if (!*is_dir) {
        FILE *fp = fopen(path, "rb");
        if (!fp) {
            int e = errno;
            return vv_error_set(VV_ERR_IO, "cannot open %s: %s", path, strerror(e));
        }
        fclose(fp);
    }
    const vv_format_record *r = format_of(f);
    if (*is_dir && r && !(r->flags & VV_FORMAT_FLAG_FOLDER)) {
        char list[256];
        io_format_titles(list, sizeof list, VV_FORMAT_FLAG_FOLDER, 1, 0);
        return vv_error_set(VV_ERR_INVALID,
                            "load: %s is a folder (only %s stacks are read from "
                            "folders)",
                            path, list);
    }
    return VV_OK;
}

/*
 * After a read: a reader that reported no time axis read a file of one time
 * step, and a time step past the file's is an error here for the readers
 * that do not select them (they read the only one). A reader that reported
 * no channels has one channel, or selects its samples itself (DICOM).
 * Copies the axes to @p want. On error frees *@p out.
 */
static vv_status
finish_axes(vv_volume **out, const char *path, const vv_load_options *opt, vv_load_info *want) {
    vv_load_info *info = opt->info;
    int channels_known = info->n_channels > 0;
    if (info->n_channels < 1)
        info->n_channels = 1;
    if (info->n_times < 1)
        info->n_times = 1;
    if (info->n_levels < 1)
        info->n_levels = 1;
    if (info->n_slices < 1)
        info->n_slices = (*out)->dims[2];
    info->channel_name[VV_CHANNEL_NAME_MAX - 1] = '\0';
    const char *what = NULL;
    int asked = 0, have = 0;
    if (channels_known && opt->channel >= info->n_channels) {
        what = "channel";
        asked = opt->channel;
        have = info->n_channels;
    } else if (opt->time >= info->n_times) {
        what = "time step";
        asked = opt->time;
        have = info->n_times;
    } else if (opt->level >= info->n_levels || opt->level < 0) {
        what = "level";
        asked = opt->level;
        have = info->n_levels;
    }
    if (what) {
        vv_volume_free(*out);
        *out = NULL;
        return vv_error_set(VV_ERR_INVALID, "load: %s: %s %d asked, the file has %d %s%s (from 0)",
                            vv_path_basename(path), what, asked, have, what, have == 1 ? "" : "s");
    }
    if (want)
        *want = *info;
    return VV_OK;
}

/* A range of slices asked of a format that reads whole volumes only. */
static vv_status
slices_unsupported(const char *path, const vv_format_record *r) {
    return vv_error_set(VV_ERR_UNSUPPORTED,
                        "load: %s: %s is read whole, not a range of slices (TIFF stacks are)",
                        vv_path_basename(path), r->title);
}

static vv_status volume_load(vv_volume **out, const char *path, const vv_load_options *opt);

vv_status
vv_volume_load(vv_volume **out, const char *path, const vv_load_options *opt) {
    vv_status s = volume_load(out, path, opt);
    /* the next reader is started once this load is done with the voxels
     * (its range measured included): its start takes no core from them */
    vv_sandbox_after_load();
    return s;
}

static vv_status
volume_load(vv_volume **out, const char *path, const vv_load_options *opt) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "load: NULL argument");
    *out = NULL;
    vv_load_options defaults;
    vv_load_options_init(&defaults);
    if (!opt)
        opt = &defaults;
    /* the readers always report the file's axes: the checks below need them */
    vv_load_info info_local;
    vv_load_info *want = opt->info;
    vv_load_options with_info = *opt;
    memset(&info_local, 0, sizeof info_local);
    with_info.info = &info_local;
    opt = &with_info;
    if (want)
        memset(want, 0, sizeof *want);
    vv_format f = opt->format;
    if (f != VV_FORMAT_AUTO && !format_of(f))
        return vv_error_set(VV_ERR_INVALID, "load: %s: no format of id %d", vv_path_basename(path),
                            (int)f);
    const vv_format_record *r = format_of(f);
    if (r && (r->flags & VV_FORMAT_FLAG_DESCRIBED) && !opt->has_raw)
        return vv_error_set(VV_ERR_INVALID,
                            "load: %s: %s format needs the dimensions and voxel type",
                            vv_path_basename(path), r->name);
    if (opt->z_first < 0 || opt->z_count < 0 || (opt->z_first > 0 && opt->z_count == 0))
        return vv_error_set(VV_ERR_INVALID, "load: %s: slices from %d, %d of them",
                            vv_path_basename(path), opt->z_first, opt->z_count);
    if (opt->z_count > 0 && r && !(r->flags & VV_FORMAT_FLAG_SLICES))
        return slices_unsupported(path, r);
    int is_dir = 0;
    vv_status s = check_input(path, f, &is_dir);
    if (s != VV_OK)
        return s;
    if (f == VV_FORMAT_AUTO) {
        /* signatures here; the deep tests, which may call a third-party
         * parser, in the reader sandbox with the read */
        f = vv_format_detect_kind(path, VV_DATA_VOLUME, 0);
        if (f == VV_FORMAT_UNKNOWN)
            f = io_detect_registered(path, VV_DATA_VOLUME);
        if (f == VV_FORMAT_UNKNOWN && io_sandboxed(NULL)) {
            const vv_format_record *used = NULL;
            s = io_read_volume(NULL, out, path, opt, &used);
            r = used;
            goto read;
        }
        if (f == VV_FORMAT_UNKNOWN)
            f = vv_format_detect_kind(path, VV_DATA_VOLUME, 1);
        if (f == VV_FORMAT_UNKNOWN && opt->has_raw)
            f = VV_FORMAT_RAW;
        r = format_of(f);
    }
    if (!r)
        return io_unknown_volume_format(path, is_dir);
    if (!r->read)
        return vv_error_set(VV_ERR_UNSUPPORTED, "load: %s: VolVis writes %s but does not read it",
                            vv_path_basename(path), r->title);
    if (opt->z_count > 0 && !(r->flags & VV_FORMAT_FLAG_SLICES))
        return slices_unsupported(path, r);
    s = io_read_volume(r, out, path, opt, NULL);
read:
    if (s != VV_OK) {
        vv_volume_free(*out);
        *out = NULL;
        return s;
    }
    if (!*out)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: reader returned no volume",
                            r ? r->name : "load", vv_path_basename(path));
    /* every reader computes range[]; a reader that left it unset gets it here
     * (a second pass over a large volume costs as much as a fast reader) */
    if ((*out)->range[0] == 0 && (*out)->range[1] == 0)
        vv_volume_update_range(*out);
    info_local.format = io_format_id(r); /* ours, not the reader's word */
    return finish_axes(out, path, &with_info, want);
}

vv_format
vv_format_from_extension(const char *path) {
    int n;
    const vv_format_record *const *t = vv_format_table(&n);
    for (int i = 0; i < n; i++)
        for (const char *const *e = t[i]->extensions;
             t[i]->holds == VV_DATA_VOLUME && t[i]->write && e && *e; e++)
            if (vv_format_path_has_ext(path, *e))
                return (vv_format)(i + 1);
    return VV_FORMAT_UNKNOWN;
}

/* ".a, .b or .c": the extensions of the formats that write. */
static void
writable_extensions(char *buf, size_t cap) {
    int n, k = 0, total = 0;
    const vv_format_record *const *t = vv_format_table(&n);
    for (int i = 0; i < n; i++)
        for (const char *const *e = vv_format_record_write_extensions(t[i]);
             t[i]->holds == VV_DATA_VOLUME && e && *e; e++)
            total++;
    buf[0] = '\0';
    for (int i = 0; i < n; i++)
        for (const char *const *e = vv_format_record_write_extensions(t[i]);
             t[i]->holds == VV_DATA_VOLUME && e && *e; e++, k++) {
            size_t len = strlen(buf);
            snprintf(buf + len, cap - len, "%s.%s",
                     k == 0          ? ""
                     : k + 1 < total ? ", "
                                     : " or ",
                     *e);
        }
}

vv_status
vv_volume_save_with(const vv_volume *v, const char *path, const vv_save_options *opt) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "save: NULL argument");
    vv_save_options o;
    vv_save_options_init(&o);
    if (opt)
        o = *opt;
    if (o.format == VV_FORMAT_AUTO) {
        o.format = vv_format_from_extension(path);
        if (o.format == VV_FORMAT_UNKNOWN) {
            char list[256];
            writable_extensions(list, sizeof list);
            return vv_error_set(VV_ERR_INVALID,
                                "save: %s: cannot tell the format from the extension (use %s)",
                                vv_path_basename(path), list);
        }
    }
    const vv_format_record *r = format_of(o.format);
    if (!r || !r->write)
        return vv_error_set(VV_ERR_UNSUPPORTED, "save: %s: writing %s is not supported",
                            vv_path_basename(path), vv_format_name(o.format));
    char why[256];
    if (o.strict && r->fits && !r->fits(v, why, sizeof why))
        return vv_error_set(VV_ERR_UNSUPPORTED, "%s: %s: %s", r->name, vv_path_basename(path), why);
    return r->write(v, path, &o);
}

vv_status
vv_volume_save(const vv_volume *v, const char *path, vv_format format, int strict) {
    vv_save_options o;
    vv_save_options_init(&o);
    o.format = format;
    o.strict = strict;
    return vv_volume_save_with(v, path, &o);
}

vv_status
vv_volume_save_boxes(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                     const vv_save_options *opt) {
    if (!hdr || !read || !path)
        return vv_error_set(VV_ERR_INVALID, "save: NULL argument");
    vv_save_options o;
    vv_save_options_init(&o);
    if (opt)
        o = *opt;
    vv_format f = o.format;
    if (f == VV_FORMAT_AUTO) {
        int n;
        const vv_format_record *const *t = vv_format_table(&n);
        f = VV_FORMAT_UNKNOWN;
        for (int i = 0; i < n && f == VV_FORMAT_UNKNOWN; i++)
            for (const char *const *e = t[i]->extensions; t[i]->write_boxes && e && *e; e++)
                if (vv_format_path_has_ext(path, *e))
                    f = (vv_format)(i + 1);
        if (f == VV_FORMAT_UNKNOWN)
            return vv_error_set(VV_ERR_INVALID,
                                "save: %s: cannot tell a format that writes box by box from the "
                                "extension (.zarr, .ome.zarr or .vvb)",
                                vv_path_basename(path));
    }
    const vv_format_record *r = format_of(f);
    if (!r || !r->write_boxes)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "save: %s: %s is written from a volume in memory, not box by box",
                            vv_path_basename(path), r ? r->title : vv_format_name(f));
    return r->write_boxes(hdr, read, ctx, path, &o);
}
