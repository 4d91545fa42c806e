/*
 * Opening anything (include/volvis/io.h, vv_open): one probe of the file
 * through the format table (formats.c), then the row does what the file
 * holds and the options ask -- a volume read whole or opened out of core
 * (a pyramid through the row's store, a bricked file through its raw layout
 * or its own bricks), a grid, a mesh -- each here or in the reader sandbox
 * as the row's flag says (transport.c). Also the entry points of grids and
 * meshes, and the pyramid opener the tests use, over the same table.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/bricked.h"
#include "io/store/bytesrc.h"
#include "io/store/pyramid.h"
#include "io/transport.h"

void
vv_open_options_init(vv_open_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    vv_load_options_init(&o->load);
    o->mode = VV_OPEN_DEFAULT;
}

void
vv_opened_clear(vv_opened *o) {
    if (!o)
        return;
    vv_source_free(o->source);
    vv_grid_free(o->grid);
    vv_mesh_free(o->mesh);
    memset(o, 0, sizeof *o);
}

/* A folder of TIFF files: told by their first bytes alone (the TIFF row's
 * deep test reads no more), so here rather than in the sandbox; what the
 * sandbox's deep detection would say too, the TIFF row coming before
 * DICOM's deep test. Its store then reads it out of core. */
static int
tiff_folder(const char *path) {
    struct stat st;
    const vv_format_record *t = vv_format_record_of(VV_FORMAT_TIFF);
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode) || !t || !t->looks_like)
        return 0;
    unsigned char buf[VV_FORMAT_PROBE_BYTES + 1];
    char text[VV_FORMAT_PROBE_BYTES + 1];
    vv_format_probe p;
    vv_format_probe_fill(&p, path, buf, text);
    return t->looks_like(&p, 1);
}

/* The row of @p path: the caller's @p f, else detected (signatures; the
 * deep tests of grids and meshes, which read names only, here; those of
 * volumes run where the volume is read); NULL when unknown. */
static const vv_format_record *
row_of(const char *path, vv_format f, int *deep_volume) {
    *deep_volume = 0;
    if (f != VV_FORMAT_AUTO)
        return vv_format_record_of(f);
    vv_format g = vv_format_detect_kind(path, -1, 0);
    if (g == VV_FORMAT_UNKNOWN)
        g = vv_format_detect_kind(path, VV_DATA_GRID, 1);
    if (g == VV_FORMAT_UNKNOWN)
        g = vv_format_detect_kind(path, VV_DATA_MESH, 1);
    if (g == VV_FORMAT_UNKNOWN)
        g = io_detect_registered(path, VV_DATA_VOLUME);
    if (g == VV_FORMAT_UNKNOWN && tiff_folder(path))
        g = VV_FORMAT_TIFF;
    if (g == VV_FORMAT_UNKNOWN)
        *deep_volume = 1; /* vv_volume_load's detection, in the sandbox when wanted */
    return vv_format_record_of(g);
}

/* The store of row @p r over @p path for channels @p channels[0 .. n)
 * (n > 1; else channel @p channel alone) at step @p time into @p st: the
 * row's store of several channels, else one store a channel stacked.
 * @p info: n entries (channel k's name and colour), may be NULL. */
static vv_status
open_store_of(const vv_format_record *r, vv_store *st, const char *path, int channel, int n,
              const int *channels, int time, vv_load_info *info) {
    if (n <= 1)
        return io_open_store(r, st, path, n == 1 ? channels[0] : channel, time, info);
    if (n > VV_STORE_MAX_CHANNELS)
        return vv_error_set(VV_ERR_LIMIT, "%d channels at once (at most %d)", n,
                            VV_STORE_MAX_CHANNELS);
    memset(st, 0, sizeof *st);
    if (r->version >= 3 && r->open_store_channels)
        return r->open_store_channels(st, path, n, channels, time, info);
    vv_store parts[VV_STORE_MAX_CHANNELS];
    memset(parts, 0, sizeof parts);
    vv_status s = VV_OK;
    for (int k = 0; k < n && s == VV_OK; k++) {
        vv_load_info one;
        memset(&one, 0, sizeof one);
        s = io_open_store(r, &parts[k], path, channels[k], time, info ? &info[k] : &one);
        if (s != VV_OK)
            s = vv_error_prefix(s, "channel %d", channels[k]);
    }
    if (s != VV_OK) {
        for (int k = 0; k < n; k++)
            vv_store_close(&parts[k]);
        return s;
    }
    return vv_store_stack(st, parts, n);
}

/* The store of row @p r over @p path as a pyramid in @p cache (channels
 * as open_store_of takes them). */
static vv_status
open_pyramid(vv_pyramid **out, const vv_format_record *r, const char *path, int channel, int n,
             const int *channels, int time, vv_cache *cache, vv_load_info *info) {
    *out = NULL;
    if (strlen(path) >= 4096)
        return vv_error_set(VV_ERR_LIMIT, "%s: path too long", r->name);
    vv_store st;
    vv_status s = open_store_of(r, &st, path, channel, n, channels, time, info);
    if (s != VV_OK) {
        vv_store_close(&st);
        return vv_pyramid_prefix(s, r->name, path);
    }
    return vv_pyramid_open_store(out, &st, path, cache, info);
}

/* The format table's row of the multiresolution file @p path into @p r. */
static vv_status
store_record(const char *path, const vv_format_record **r) {
    *r = vv_format_record_of(vv_format_detect_kind(path, VV_DATA_VOLUME, 0));
    if (!*r || !(*r)->open_store)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: not a multiresolution file (OME-Zarr, N5, Neuroglancer "
                            "precomputed, BigDataViewer or Imaris HDF5, TIFF, a .vvb)",
                            vv_path_basename(path));
    return VV_OK;
}

vv_status
vv_pyramid_open(vv_pyramid **out, const char *path, int channel, int time, vv_cache *cache,
                vv_load_info *info) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "pyramid: NULL argument");
    *out = NULL;
    const vv_format_record *r;
    const vv_status s = store_record(path, &r);
    return s != VV_OK ? s : open_pyramid(out, r, path, channel, 0, NULL, time, cache, info);
}

vv_status
vv_pyramid_open_channels(vv_pyramid **out, const char *path, int n, const int *channels, int time,
                         vv_cache *cache, vv_load_info *info) {
    if (!out || !path || !channels)
        return vv_error_set(VV_ERR_INVALID, "pyramid: NULL argument");
    *out = NULL;
    if (n < 1 || n > VV_STORE_MAX_CHANNELS)
        return vv_error_set(VV_ERR_INVALID, "pyramid: %d channels (1 .. %d)", n,
                            VV_STORE_MAX_CHANNELS);
    const vv_format_record *r;
    const vv_status s = store_record(path, &r);
    return s != VV_OK ? s : open_pyramid(out, r, path, channels[0], n, channels, time, cache, info);
}

/* Bytes of a volume of @p h's dims and type. */
static uint64_t
bytes_of(const vv_volume *h) {
    return (uint64_t)h->dims[0] * (uint64_t)h->dims[1] * (uint64_t)h->dims[2] *
           vv_voxel_type_size(h->type);
}

/* 1 when @p path is a regular file of at most @p bytes: a stack (a TIFF)
 * that small holds at most a few times as many voxel bytes, read whole
 * sooner than its store is opened in the sandbox to tell its size. */
static int
file_under(const char *path, uint64_t bytes) {
    struct stat st;
    return !bs_is_url(path) && stat(path, &st) == 0 && S_ISREG(st.st_mode) &&
           (uint64_t)st.st_size <= bytes;
}

/* @p path opened out of core as row @p r can: a pyramid (its store) when
 * the row has one and either the caller prefers levels or the row has no
 * bricks; else by bricks (the row's own, or its raw layout). VV_ERR_UNSUPPORTED
 * (nothing set, no error kept): the row cannot, or not this file (a
 * compressed NRRD): read it whole. With @p auto_small, a volume whose level
 * 0 holds at most a quarter of the cache's budget is VV_ERR_UNSUPPORTED too. */
static vv_status
open_out_of_core(vv_opened *out, const vv_format_record *r, const char *path,
                 const vv_open_options *opt, vv_cache *cache, int auto_small) {
    const vv_load_options *lo = &opt->load;
    const uint64_t quarter = vv_cache_limit(cache) / 4;
    const int bricks = r->open_bricks || r->raw_layout;
    const int nch = opt->n_channels > 1 ? opt->n_channels : 0;
    if (nch > VV_MAX_CHANNELS)
        return vv_error_set(VV_ERR_LIMIT, "%s: %d channels at once (at most %d)",
                            vv_path_basename(path), nch, VV_MAX_CHANNELS);
    /* a small stack, opened to be drawn whole if it fits or to tell its
     * size (a header, no levels asked): whole, without opening its store */
    if ((auto_small || (opt->header_only && !opt->levels)) && (r->flags & VV_FORMAT_FLAG_SLICES) &&
        file_under(path, quarter / 8))
        return VV_ERR_UNSUPPORTED;
    if (r->open_store && (opt->levels || !bricks || nch)) {
        vv_pyramid *p = NULL;
        vv_load_info *info = out->ch_info;
        memset(out->ch_info, 0, sizeof out->ch_info);
        vv_status s =
            open_pyramid(&p, r, path, lo->channel, nch, opt->channels, lo->time, cache, info);
        if (s != VV_OK)
            return s;
        const int level = lo->level > 0 ? lo->level : 0;
        if (level >= vv_pyramid_levels(p)) {
            s = vv_error_set(VV_ERR_INVALID, "%s: level %d asked, the store has %d",
                             vv_path_basename(path), level, vv_pyramid_levels(p));
            vv_pyramid_free(p);
            return s;
        }
        if (auto_small && bytes_of(vv_pyramid_level(p, 0)) * (uint64_t)(nch ? nch : 1) <= quarter) {
            vv_pyramid_free(p);
            return VV_ERR_UNSUPPORTED;
        }
        if (bricks && vv_pyramid_levels(p) == 1 &&
            !nch) { /* no levels (a .vvb without): by bricks */
            vv_pyramid_free(p);
            goto by_bricks;
        }
        if ((s = vv_pyramid_source_new(&out->source, p, r->name)) != VV_OK)
            return s;
        for (int k = 0; k < (nch ? nch : 1); k++)
            info[k].n_levels = vv_pyramid_levels(p);
        out->info = info[0];
        return VV_OK;
    }
    if (!bricks)
        return VV_ERR_UNSUPPORTED;
by_bricks:
    if (nch) /* a bricked file holds one channel */
        return VV_ERR_UNSUPPORTED;
    if (lo->channel > 0 || lo->time > 0) /* bricks hold channel 0 at step 0: read whole */
        return VV_ERR_UNSUPPORTED;
    vv_status s;
    vv_bricked *b = NULL;
    if (r->open_bricks) {
        if (auto_small) { /* its index gives the size: open it to know */
            vv_source *src = NULL;
            if ((s = r->open_bricks(&src, path, opt->header_only, cache)) != VV_OK)
                return s;
            if (bytes_of(vv_source_level(src, 0)) <= quarter) {
                vv_source_free(src);
                return VV_ERR_UNSUPPORTED;
            }
            out->source = src;
        } else if ((s = r->open_bricks(&out->source, path, opt->header_only, cache)) != VV_OK) {
            return s;
        }
    } else {
        vv_volume *h = NULL;
        char *data = NULL;
        uint64_t off = 0;
        int big = 0;
        s = r->raw_layout(path, lo, &h, &data, &off, &big);
        if (s == VV_ERR_UNSUPPORTED) {
            vv_error_clear();
            return VV_ERR_UNSUPPORTED;
        }
        if (s != VV_OK)
            return s;
        if (auto_small && bytes_of(h) <= quarter) {
            vv_volume_free(h);
            free(data);
            return VV_ERR_UNSUPPORTED;
        }
        s = vv_bricked_open_layout(&b, path, h, data, off, big, cache, !opt->header_only);
        if (s == VV_OK)
            s = vv_bricked_source_new(&out->source, b, r->name);
        if (s != VV_OK)
            return s;
    }
    out->info.n_channels = out->info.n_times = 1;
    out->info.n_levels = 1;
    return VV_OK;
}

vv_status
vv_open(vv_opened *out, const char *path, const vv_open_options *opt) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "open: NULL argument");
    memset(out, 0, sizeof *out);
    vv_open_options def;
    if (!opt) {
        vv_open_options_init(&def);
        opt = &def;
    }
    struct stat st;
    if (!bs_is_url(path) && stat(path, &st) != 0) { /* a URL: its reader fetches */
        const int e = errno;
        return vv_error_set(VV_ERR_IO, "cannot open %s: %s", path, strerror(e));
    }
    int deep = 0;
    const vv_format_record *r = row_of(path, opt->load.format, &deep);
    if (opt->load.format != VV_FORMAT_AUTO && !r)
        return vv_error_set(VV_ERR_INVALID, "open: %s: no format of id %d", vv_path_basename(path),
                            (int)opt->load.format);
    out->format = io_format_id(r);
    if (r && r->holds != VV_DATA_VOLUME) { /* a grid or a mesh: read whole */
        out->kind = r->holds;
        const vv_status s = r->holds == VV_DATA_GRID ? io_read_grid(r, &out->grid, path)
                                                     : io_read_mesh(r, &out->mesh, path);
        if (s != VV_OK)
            vv_opened_clear(out);
        return s;
    }
    out->kind = VV_DATA_VOLUME;
    vv_cache *cache = opt->cache ? opt->cache : vv_cache_process();
    const vv_open_mode mode = opt->mode;
    if (!r && opt->load.has_raw)
        r = vv_format_record_of(VV_FORMAT_RAW);
    const int only = mode == VV_OPEN_OUT_OF_CORE_ONLY;
    const int ooc = r && mode != VV_OPEN_WHOLE &&
                    (mode == VV_OPEN_OUT_OF_CORE || mode == VV_OPEN_AUTO || only ||
                     (r->flags & VV_FORMAT_FLAG_OUT_OF_CORE));
    vv_status s = VV_ERR_UNSUPPORTED;
    if (ooc)
        s = open_out_of_core(out, r, path, opt, cache,
                             mode == VV_OPEN_AUTO && !(r->flags & VV_FORMAT_FLAG_OUT_OF_CORE));
    if (s == VV_ERR_UNSUPPORTED && only) {
        /* a store row's own reason is kept (an unknown compressor) */
        if (!r || !r->open_store || r->open_bricks || r->raw_layout)
            vv_error_clear();
        vv_opened_clear(out);
        return VV_ERR_UNSUPPORTED;
    }
    if (s == VV_ERR_UNSUPPORTED && opt->n_channels > 1) {
        /* several channels are opened together out of core only: the
         * caller reads them whole one by one (the row's reason is kept) */
        if (!r || !r->open_store)
            vv_error_clear();
        vv_opened_clear(out);
        return VV_ERR_UNSUPPORTED;
    }
    if (s == VV_ERR_UNSUPPORTED) { /* whole, into memory */
        vv_load_options lo = opt->load;
        lo.info = &out->info;
        if (r && !deep)
            lo.format = out->format; /* detected once */
        vv_volume *v = NULL;
        s = vv_volume_load(&v, path, &lo);
        if (s == VV_OK) {
            s = vv_source_new_memory(&out->source, v);
            vv_volume_free(v);
        }
    }
    /* out of core: each level's geometry, as io_read_volume checks a
     * volume read whole */
    for (int l = 0; s == VV_OK && ooc && l < vv_source_levels(out->source); l++) {
        const vv_volume *lv = vv_source_level(out->source, l);
        s = lv ? io_geometry_status(r, lv, path) : VV_OK;
    }
    if (s != VV_OK) {
        vv_opened_clear(out);
        return s;
    }
    if (out->format == VV_FORMAT_UNKNOWN) /* detected with the read, in the reader */
        out->format = out->info.format;
    return VV_OK;
}

/* ---- grids and meshes ---------------------------------------------------------------- */

int
vv_grid_file_detect(const char *path, vv_grid_format *fmt) {
    if (fmt)
        *fmt = VV_GRID_FORMAT_AUTO;
    struct stat st;
    if (!path || stat(path, &st) != 0 || S_ISDIR(st.st_mode))
        return 0;
    const vv_format f = vv_format_detect_kind(path, VV_DATA_GRID, 1);
    if (f == VV_FORMAT_UNKNOWN)
        return 0;
    /* the grid formats' own ids: their order among the grid rows */
    int n, k = 0;
    const vv_format_record *const *t = vv_format_table(&n);
    for (int i = 0; i < (int)f - 1; i++)
        k += t[i]->holds == VV_DATA_GRID;
    if (fmt)
        *fmt = (vv_grid_format)(k + 1);
    return 1;
}

vv_status
vv_grid_load(vv_grid **out, const char *path) {
    *out = NULL;
    const vv_format_record *r =
        path ? vv_format_record_of(vv_format_detect_kind(path, VV_DATA_GRID, 1)) : NULL;
    if (!r) {
        FILE *fp = path ? fopen(path, "rb") : NULL;
        if (!fp)
            return vv_error_set(VV_ERR_IO, "%s: %s", path ? path : "(null)", strerror(errno));
        fclose(fp);
        char list[256] = "";
        int n;
        const vv_format_record *const *t = vv_format_table(&n);
        for (int i = 0; i < n; i++) {
            if (t[i]->holds != VV_DATA_GRID)
                continue;
            size_t k = strlen(list);
            snprintf(list + k, sizeof list - k, "%s%s", k ? ", " : "", t[i]->title);
        }
        return vv_error_set(VV_ERR_FORMAT, "%s: not a grid file this build reads (%s)", path, list);
    }
    /* libxml2 and libnetcdf read in volvis-reader (transport.c) */
    return io_read_grid(r, out, path);
}

vv_status
vv_mesh_load(vv_mesh **out, const char *path) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL argument");
    *out = NULL;
    /* every file is asked of Assimp's row: the meshes it reads have no common signature */
    const vv_format_record *r = io_row_named("mesh");
    if (!r)
        return vv_error_set(VV_ERR_UNSUPPORTED, "mesh: %s: this build reads no meshes",
                            vv_path_basename(path));
    /* Assimp reads it in volvis-reader (transport.c) */
    return io_read_mesh(r, out, path);
}
