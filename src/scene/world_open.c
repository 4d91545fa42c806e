/*
 * vv_world_open: the one door from what a user names to a World ready to
 * draw (include/volvis/scene.h). The CLI's commands, `volvis serve`, the
 * GUI, MPI ranks and Python all come through here, so what a file looks
 * like when opened -- in memory or out of core, its channels, its default
 * transfer function and slice window -- is decided once, in one place.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scene/scene_internal.h"
#include "volvis/io.h"
#include "volvis/model.h"
#include "volvis/parallel.h"
#include "volvis/render.h"
#include "volvis/scene.h"
#include "volvis/slice.h"
#include "volvis/source.h"

void
vv_world_open_options_init(vv_world_open_options *o) {
    memset(o, 0, sizeof *o);
    o->version = VV_WORLD_OPEN_VERSION;
    vv_load_options_init(&o->load);
    o->level = -1;
    vv_default_scene_options_init(&o->view);
}

/* The last path component of @p path. */
static const char *
base_name(const char *path) {
    const char *s = strrchr(path, '/');
    return s && s[1] ? s + 1 : path;
}

/* The error trace made one line naming @p what (its reason kept). */
static vv_status
fail(vv_status s, const char *what) {
    const char *m = vv_error_message();
    if (!m || !*m)
        return vv_error_set(s, "%s: failed (%s)", what, vv_status_name(s));
    if (!strstr(m, what) && !strstr(m, base_name(what)))
        return vv_error_prefix(s, "%s", what);
    return s;
}

/* A misfit between the options and the input: one line, a usage error. */
static vv_status
misfit(vv_world_open_info *info, const char *what, const char *reason) {
    info->options_misfit = 1;
    return vv_error_set(VV_ERR_INVALID, "%s: %s", what, reason);
}

/* A readable file, or a readable and searchable folder. */
static vv_status
check_readable(const char *path, int folder_ok) {
    if (vv_path_is_url(path)) /* a remote store: its reader fetches */
        return VV_OK;
    struct stat st;
    if (stat(path, &st) != 0)
        return vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode)) {
        if (!folder_ok)
            return vv_error_set(VV_ERR_IO, "%s: is a directory", path);
        if (access(path, R_OK | X_OK) != 0)
            return vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
        return VV_OK;
    }
    if (access(path, R_OK) != 0)
        return vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
    return VV_OK;
}

/* A scene file: extension .json, or content that starts with '{' after whitespace. */
static int
is_scene_file(const char *path) {
    size_t n = strlen(path);
    if (vv_path_is_url(path))
        return 0;
    if (n >= 5 && strcasecmp(path + n - 5, ".json") == 0)
        return 1;
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    int c;
    long k = 0;
    while ((c = fgetc(f)) != EOF && isspace(c) && k++ < 65536)
        ;
    fclose(f);
    return c == '{';
}

/* Maps every point of @p tf linearly from the extent of its opacity points onto [lo, hi]. */
static void
stretch_tf(vv_tf *tf, double lo, double hi) {
    double a = 0, b = 0;
    if (tf->n_opacity >= 2) {
        a = tf->opacity[0].value;
        b = tf->opacity[tf->n_opacity - 1].value;
    }
    if (!(b > a)) {
        double peak = 0;
        for (int i = 0; i < tf->n_opacity; i++)
            if (tf->opacity[i].opacity > peak)
                peak = tf->opacity[i].opacity;
        vv_vec3 color = tf->n_color ? tf->color[tf->n_color - 1].color : vv_vec3_make(1, 1, 1);
        double unit = tf->opacity_unit_distance > 0 ? tf->opacity_unit_distance : 1;
        vv_tf_set_ramp(tf, lo, hi, peak > 0 ? peak : 1, color, unit);
        return;
    }
    double s = (hi - lo) / (b - a);
    for (int i = 0; i < tf->n_opacity; i++)
        tf->opacity[i].value = lo + (tf->opacity[i].value - a) * s;
    for (int i = 0; i < tf->n_color; i++)
        tf->color[i].value = lo + (tf->color[i].value - a) * s;
}

/* @p o's default-scene options (the view's size only when given). */
static void
scene_options(const vv_world_open_options *o, vv_default_scene_options *d) {
    *d = o->view;
    if (!o->has_mode)
        d->mode = VV_MODE_COMPOSITE;
    if (!o->has_size) {
        vv_default_scene_options def;
        vv_default_scene_options_init(&def);
        d->width = def.width;
        d->height = def.height;
    }
}

/* An irregular grid's World (vv_world_new_for_grid). */
static vv_status
world_for_grid(const vv_world_open_options *o, const char *what, vv_grid *g, vv_world **out) {
    vv_default_scene_options d;
    scene_options(o, &d);
    vv_error_clear();
    vv_status s = vv_world_new_for_grid(out, g, o->field, o->load.time >= 0 ? o->load.time : 0, &d);
    return s == VV_OK ? VV_OK : fail(s, what);
}

/* 1: the caller asked for every channel by colours, contrast or a blend rule (the
 * file's channels must then fit them); 0: every channel only where it has several. */
static int
channels_asked(const vv_world_open_options *o) {
    return o->all_channels && (o->n_colors || o->n_contrast || o->has_blend);
}

/* vv_open's options for @p o: out of core as asked; under MPI each rank
 * reads its own box. @p scene: for a scene's files (NULL result: read whole). */
static const vv_open_options *
open_options(const vv_world_open_options *o, int scene, vv_open_options *oo) {
    vv_open_options_init(oo);
    vv_cache_set_limit(vv_cache_process(), o->memory_limit); /* 0: the default, 1 GiB */
    const int ooc = o->memory != VV_WORLD_MEMORY_AUTO;
    oo->mode = ooc || (o->distributed && !scene) ? VV_OPEN_OUT_OF_CORE : VV_OPEN_DEFAULT;
    oo->levels = o->levels || o->level >= 0;
    if (o->memory == VV_WORLD_OUT_OF_CORE_IF_LARGE) {
        oo->mode = VV_OPEN_AUTO;
        oo->levels = 1;
    }
    if (o->memory == VV_WORLD_IN_MEMORY)
        oo->mode = VV_OPEN_WHOLE;
    oo->load.level = o->level > 0 ? o->level : 0;
    if (scene) /* a scene's files are read whole unless asked */
        return ooc && o->memory != VV_WORLD_IN_MEMORY ? oo : NULL;
    oo->load.series = o->load.series;
    oo->load.channel = o->load.channel;
    oo->load.time = o->load.time;
    oo->load.format = o->load.format;
    oo->load.has_raw = o->load.has_raw;
    oo->load.raw = o->load.raw;
    oo->header_only = o->distributed; /* the ranks learn the range from their boxes */
    return oo;
}

/* The bytes a volume of header @p h takes to render in memory: its
 * voxels, the renderers' copy of them (none for u16, 16-bit offsets for
 * the other 8- and 16-bit types, float for the rest) and, when shaded, the
 * cached gradients (2 bytes a voxel): src/render/sample.h's caches. */
static uint64_t
in_memory_bytes(const vv_volume *h, int shaded) {
    const uint64_t n = (uint64_t)h->dims[0] * (uint64_t)h->dims[1] * (uint64_t)h->dims[2];
    const uint64_t vox = vv_voxel_type_size(h->type);
    const uint64_t copy = h->type == VV_U16 ? 0 : vox <= 2 ? 2 : 4;
    return n * (vox + copy + (shaded ? 2 : 0));
}

/* VV_WORLD_MEMORY_AUTO's switch: whether rendering the file in memory would
 * take more than the memory budget, for a file that can be read out of
 * core, drawn by a renderer with the region contract, one channel, no time
 * step asked for. Then *od holds it opened out of core, the process cache's
 * limit is a quarter of the budget (and of the memory available, at most
 * 1 GiB), and info says so. Returns 1 when switched. */
static int
too_big_for_memory(const vv_world_open_options *o, const char *what, const vv_open_options *oo,
                   vv_opened *od, vv_world_open_info *info) {
    const vv_renderer_info *in = vv_renderer_info_find(o->renderer ? o->renderer : "raycast");
    if (oo->mode != VV_OPEN_DEFAULT || o->distributed || o->load.time >= 0 || !in ||
        !(in->caps & VV_RENDERER_REGION))
        return 0;
    /* several channels: as many volumes (the first one's size each) */
    const uint64_t nch = oo->n_channels > 1 ? (uint64_t)oo->n_channels : 1;
    const uint64_t budget = vv_memory_budget_get(), avail = vv_memory_available();
    uint64_t limit = budget / 4;
    limit = limit > avail / 4 ? avail / 4 : limit; /* a raised budget past a cgroup's limit */
    limit = limit > ((uint64_t)1 << 30) ? (uint64_t)1 << 30 : limit;
    /* the header alone first (no pass over the voxels) */
    vv_open_options probe = *oo;
    probe.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    probe.header_only = 1;
    probe.n_channels = 0;
    if (nch > 1)
        probe.load.channel = oo->channels[0];
    vv_cache_set_limit(vv_cache_process(), limit);
    vv_error_clear();
    memset(od, 0, sizeof *od);
    uint64_t need = 0;
    if (vv_open(od, what, &probe) == VV_OK && od->kind == VV_DATA_VOLUME) {
        const vv_volume *h = vv_source_level(od->source, 0);
        const int shaded =
            !o->has_mode || o->view.mode == VV_MODE_COMPOSITE || o->view.mode == VV_MODE_ISO;
        need = h ? in_memory_bytes(h, shaded) * nch : 0;
    }
    vv_opened_clear(od);
    vv_error_clear();
    probe.header_only = oo->header_only;
    probe.n_channels = oo->n_channels;
    if (need <= budget || vv_open(od, what, &probe) != VV_OK) {
        vv_opened_clear(od);
        vv_error_clear(); /* read whole, as before */
        vv_cache_set_limit(vv_cache_process(), o->memory_limit);
        return 0;
    }
    info->switched = 1;
    info->need_bytes = need;
    info->budget_bytes = budget;
    info->cache_bytes = limit;
    return 1;
}

/* A pyramid's default appearance, the same whether it is read whole or out
 * of core: the transfer function's range from the histogram of its
 * coarsest level (what the proxy out of core holds; level 0 may be larger
 * than memory) and its opacity unit from the spacing of the level shown
 * (not the proxy's stretched one). @p src is the opened file; a memory
 * source (read whole) has its coarsest level read once more, out of core.
 * A failure to read it leaves the defaults of the level shown. */
static void
pyramid_appearance(const vv_world_open_options *o, const char *what, vv_source *src, vv_world *w) {
    vv_object *obj = w->objects[0];
    const int level = o->level > 0 ? o->level : 0;
    const vv_volume *shown =
        vv_source_volume(src) ? vv_source_volume(src) : vv_source_level(src, level);
    vv_volume *coarse = NULL;
    if (!o->view.has_tf_range) {
        vv_open_options oo;
        if (vv_source_volume(src)) /* read whole: opened again for its coarsest level */
            open_options(o, 0, &oo);
        coarse = vv_scene_coarsest_level(what, src, vv_source_volume(src) ? &oo : NULL);
    }
    if (coarse) { /* the object's mode is the options' (scene_options) */
        const double iso = obj->isovalue;
        vv_object_default_appearance(obj, coarse, shown);
        if (o->view.has_isovalue)
            obj->isovalue = obj->threshold = iso;
    } else if (shown) {
        obj->tf.opacity_unit_distance = vv_tf_default_unit_distance(shown);
    }
    vv_volume_free(coarse);
}

/* What the file's metadata says of channel @p c (name, colour, window,
 * inactive) and the default contrast of the channel: the options', else
 * the metadata's window (omero start and end), else the quantiles of
 * @p coarse (the coarsest level of a pyramid, whether read whole or out
 * of core: the same either way), else of @p own (its voxels in memory). */
static void
channel_contrast(const vv_world_open_options *o, int c, const vv_load_info *info,
                 const vv_volume *coarse, const vv_volume *own, double *lo, double *hi) {
    if (c < o->n_contrast) {
        *lo = o->contrast[c][0];
        *hi = o->contrast[c][1];
    } else if (info->has_window) {
        *lo = info->window[0];
        *hi = info->window[1];
    } else {
        vv_channel_default_contrast(coarse ? coarse : own, lo, hi);
    }
}

/* The coarsest level of channel @p channel of a pyramid file of
 * @p n_levels levels, read whole (small), or NULL (one level, or it could
 * not be read: the caller's own volume gives the contrast then). */
static vv_volume *
coarsest_level(const vv_world_open_options *o, const char *what, int channel, int n_levels) {
    if (n_levels < 2)
        return NULL;
    vv_load_options lo = o->load;
    lo.channel = channel;
    lo.level = n_levels - 1;
    lo.info = NULL;
    vv_volume *v = NULL;
    if (vv_volume_load(&v, what, &lo) != VV_OK) {
        vv_error_clear();
        return NULL;
    }
    return v;
}

/* Appends @p w to @p oi's warning, once. */
static void
add_warning(vv_world_open_info *oi, const char *w) {
    if (!w || !*w || strstr(oi->warning, w))
        return;
    const size_t n = strlen(oi->warning);
    snprintf(oi->warning + n, sizeof oi->warning - n, "%s%s", n ? "; " : "", w);
}

/* Channels @p channels[0 .. n) of @p what opened together out of core,
 * into *od, when the options ask for it or they do not fit in memory
 * (too_big_for_memory): *opened 1. *opened 0: read them whole. Errors:
 * VV_WORLD_OUT_OF_CORE of a file that cannot be read so, and those of
 * opening it. */
static vv_status
channels_out_of_core(const vv_world_open_options *o, const char *what, int n, const int *channels,
                     vv_opened *od, vv_world_open_info *oi, int *opened) {
    *opened = 0;
    memset(od, 0, sizeof *od);
    if (o->memory == VV_WORLD_IN_MEMORY)
        return VV_OK;
    vv_open_options oo;
    open_options(o, 0, &oo);
    if (n > 1) {
        oo.n_channels = n;
        memcpy(oo.channels, channels, sizeof(int) * (size_t)n);
    } else {
        oo.load.channel = channels[0];
    }
    if (o->memory == VV_WORLD_OUT_OF_CORE && !o->distributed)
        oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    vv_status s = VV_OK;
    vv_error_clear();
    if (too_big_for_memory(o, what, &oo, od, oi)) {
        *opened = 1;
        return VV_OK;
    }
    if (oo.mode == VV_OPEN_DEFAULT)
        return VV_OK; /* fits: whole */
    s = vv_open(od, what, &oo);
    if (s == VV_ERR_UNSUPPORTED && oo.mode != VV_OPEN_OUT_OF_CORE_ONLY) {
        vv_error_clear();
        return VV_OK; /* cannot, and need not: whole */
    }
    if (s == VV_ERR_UNSUPPORTED && vv_error_message()[0]) /* the store's reason */
        return fail(s, what);
    if (s == VV_ERR_UNSUPPORTED)
        return n > 1 ? vv_error_set(s,
                                    "%s: cannot be read out of core: several channels are read "
                                    "together from a pyramid (OME-Zarr, BigDataViewer, Imaris); "
                                    "without --memory-limit they are read whole, or draw one "
                                    "(--channel C)",
                                    what)
                     : vv_error_set(s,
                                    "%s: cannot be read out of core (by bricks: .vvb, raw or "
                                    "uncompressed NRRD; by levels: a pyramid); convert it to .vvb "
                                    "first (volvis convert IN OUT.vvb)",
                                    what);
    if (s != VV_OK)
        return fail(s, what);
    if (od->kind != VV_DATA_VOLUME) {
        vv_opened_clear(od);
        return vv_error_set(VV_ERR_FORMAT, "%s: not a volume file", what);
    }
    *opened = vv_source_get_kind(od->source) != VV_SOURCE_MEMORY;
    if (!*opened)
        vv_opened_clear(od);
    return VV_OK;
}

/* The file's channels as one object of several channels, coloured,
 * limited and shown by the options or the file's metadata (its names,
 * colours, omero windows and active flags), combined by the blend rule;
 * one channel alone is a one-channel object with that colour and
 * contrast. In memory (each channel read whole) or out of core (one
 * source carrying them all: vv_object_set_channels_source) as the options
 * and the file's size decide; the defaults are the same either way. */
static vv_status
world_for_channels(const vv_world_open_options *o, const char *what, int n, const int *channels,
                   vv_world **out, vv_world_open_info *oi) {
    vv_volume *v[VV_MAX_CHANNELS] = {NULL};
    vv_volume *coarse[VV_MAX_CHANNELS] = {NULL};
    vv_load_info info[VV_MAX_CHANNELS];
    char names[VV_MAX_CHANNELS][VV_CHANNEL_NAME_MAX];
    const char *np[VV_MAX_CHANNELS];
    memset(info, 0, sizeof info);
    vv_opened od;
    int ooc = 0;
    vv_status s = channels_out_of_core(o, what, n, channels, &od, oi, &ooc);
    if (s != VV_OK)
        return s;
    if (ooc) {
        for (int c = 0; c < n; c++)
            info[c] = n > 1 ? od.ch_info[c] : od.info;
    }
    for (int c = 0; c < n && s == VV_OK && !ooc; c++) {
        vv_load_options lo = o->load;
        lo.channel = channels[c];
        lo.level = o->level > 0 ? o->level : 0; /* a pyramid's level read whole */
        lo.info = &info[c];
        vv_error_clear();
        s = vv_volume_load(&v[c], what, &lo);
    }
    for (int c = 0; c < n;
         c++) { /* the file's name for the channel (OME Channel Name), else its index */
        if (s == VV_OK && info[c].channel_name[0])
            snprintf(names[c], sizeof names[c], "%s", info[c].channel_name);
        else
            snprintf(names[c], sizeof names[c], "channel %d", channels[c]);
        np[c] = names[c];
    }
    if (s == VV_OK) { /* the file's channels and steps, as vv_open tells them */
        oi->n_channels = info[0].n_channels > 1 ? info[0].n_channels : 1;
        oi->n_times = info[0].n_times > 1 ? info[0].n_times : 1;
        for (int c = 0; c < n; c++)
            add_warning(oi, info[c].warning);
    }
    vv_default_scene_options d;
    scene_options(o, &d);
    const int level = o->level > 0 ? o->level : 0;
    if (s == VV_OK) {
        vv_error_clear();
        s = ooc ? vv_world_new_for_source(out, od.source, level, &d)
                : vv_world_new_for_volume(out, v[0], &d);
    }
    vv_object *obj = s == VV_OK ? (*out)->objects[0] : NULL;
    if (obj && n > 1) {
        vv_error_clear();
        s = ooc ? vv_object_set_channels_source(obj, od.source, level, np)
                : vv_object_set_channels(obj, n, v, np);
        obj->blend = o->has_blend ? o->blend : VV_BLEND_COMPOSITE;
        for (int c = 0; s == VV_OK && c < n; c++) {
            obj->channels[c].index = channels[c];
            obj->channels[c].visible = !info[c].inactive;
            if (o->label_channel[c])
                s = vv_object_set_channel_labels(obj, c, 1);
        }
    }
    /* a pyramid's coarsest level gives the contrast, in memory as out of
     * core (whose channels' volumes are those levels) */
    const int n_levels = info[0].n_levels > 1 ? info[0].n_levels : 1;
    for (int c = 0; obj && s == VV_OK && c < n; c++) {
        if (c >= o->n_contrast && !info[c].has_window && !ooc)
            coarse[c] = coarsest_level(o, what, channels[c], n_levels);
        vv_tf *tf = n > 1 ? &obj->channels[c].tf : &obj->tf;
        const vv_volume *own = n > 1 ? obj->channels[c].volume : obj->volume;
        double lo, hi;
        channel_contrast(o, c, &info[c], coarse[c], own, &lo, &hi);
        /* given colours, else the file's (OME Channel Color), else the default set */
        vv_vec3 col = c < o->n_colors ? o->colors[c]
                      : info[c].has_color
                          ? vv_vec3_make(info[c].color[0], info[c].color[1], info[c].color[2])
                          : vv_channel_default_color(c);
        /* opacity per the smallest voxel spacing of the level shown */
        const double unit = tf->opacity_unit_distance;
        vv_error_clear();
        s = vv_tf_set_contrast(tf, lo, hi, 1.0, 0.5, col, unit);
        if (n == 1 && o->has_blend && o->blend == VV_BLEND_MAXIMUM)
            obj->mode = VV_MODE_MIP;
        if (n == 1 && o->label_channel[0])
            obj->segmentation = VV_SEG_LABELS;
    }
    for (int c = 0; c < n; c++) {
        vv_volume_free(v[c]); /* the object holds its own references */
        vv_volume_free(coarse[c]);
    }
    vv_opened_clear(&od);
    if (s != VV_OK) {
        vv_world_free(*out);
        *out = NULL;
        return fail(s, what);
    }
    if (o->load.time >= 0)
        obj->time = o->load.time; /* the file's step it shows */
    return VV_OK;
}

/* A volume file, a folder, a store or a grid: opened once through the
 * format table (vv_open), in memory or out of core as the options say (or
 * because it does not fit in memory: too_big_for_memory). */
static vv_status
world_for_file(const vv_world_open_options *o, const char *what, vv_world **out,
               vv_world_open_info *info) {
    if (o->n_channels)
        return world_for_channels(o, what, o->n_channels, o->channels, out, info);
    vv_status s = check_readable(what, !o->load.has_raw);
    if (s != VV_OK)
        return s;
    vv_open_options oo;
    open_options(o, 0, &oo);
    /* out of core asked for: a file that cannot be is refused, not read whole */
    if (o->memory == VV_WORLD_OUT_OF_CORE && !o->distributed)
        oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    vv_opened od;
    vv_error_clear();
    if (too_big_for_memory(o, what, &oo, &od, info))
        oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    else
        s = vv_open(&od, what, &oo);
    if (s == VV_ERR_UNSUPPORTED && vv_error_message()[0]) /* the store's reason */
        return fail(s, what);
    if (s == VV_ERR_UNSUPPORTED && o->all_channels)
        return vv_error_set(s,
                            "%s: cannot be read out of core (by bricks: .vvb, raw or "
                            "uncompressed NRRD, one channel; by levels: a pyramid, its channels "
                            "together); convert it to .vvb first (volvis convert IN OUT.vvb, a "
                            "channel at a time), or read it whole (no --memory-limit)",
                            what);
    if (s == VV_ERR_UNSUPPORTED)
        return vv_error_set(s,
                            "%s: cannot be read out of core (by bricks: .vvb, raw or "
                            "uncompressed NRRD; by levels: a pyramid); convert it to .vvb first "
                            "(volvis convert IN OUT.vvb)",
                            what);
    if (s == VV_OK && od.kind == VV_DATA_VOLUME) {
        info->n_channels = od.info.n_channels > 1 ? od.info.n_channels : 1;
        info->n_times = od.info.n_times > 1 ? od.info.n_times : 1;
    }
    if (s == VV_OK && od.kind == VV_DATA_VOLUME)
        add_warning(info, od.info.warning);
    if (s == VV_OK && od.kind == VV_DATA_VOLUME &&
        (channels_asked(o) || (o->all_channels && info->n_channels > 1))) {
        /* every channel of the file, as one object (not asked for: the first ones) */
        const int n = channels_asked(o) || info->n_channels <= VV_MAX_CHANNELS ? info->n_channels
                                                                               : VV_MAX_CHANNELS;
        vv_opened_clear(&od);
        if (o->n_colors > n || o->n_contrast > n) {
            char why[160];
            snprintf(why, sizeof why, "%s: %d given for the file's %d channel%s",
                     o->n_colors > n ? "--colors" : "--contrast",
                     o->n_colors > n ? o->n_colors : o->n_contrast, n, n == 1 ? "" : "s");
            return misfit(info, what, why);
        }
        if (n > VV_MAX_CHANNELS)
            return vv_error_set(VV_ERR_INVALID,
                                "%s: %d channels: at most %d show as one object (--channels "
                                "LIST)",
                                what, n, VV_MAX_CHANNELS);
        int every[VV_MAX_CHANNELS];
        for (int c = 0; c < n; c++)
            every[c] = c;
        return world_for_channels(o, what, n, every, out, info);
    }
    if (s == VV_OK && od.kind == VV_DATA_GRID) { /* an irregular grid: its own World */
        info->input = VV_INPUT_GRID;
        s = world_for_grid(o, what, od.grid, out);
        vv_opened_clear(&od);
        return s;
    }
    if (s == VV_OK && od.kind == VV_DATA_MESH) {
        info->input = VV_INPUT_MESH;
        s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: a triangle mesh, not a volume or grid file",
                         what);
    }
    if (s == VV_OK && od.kind != VV_DATA_VOLUME)
        s = vv_error_set(VV_ERR_FORMAT, "%s: not a volume or grid file", what);
    if (s != VV_OK) {
        vv_opened_clear(&od);
        return fail(s, what);
    }
    if (oo.levels && (o->levels || o->level > 0) &&
        vv_source_get_kind(od.source) != VV_SOURCE_PYRAMID && oo.mode == VV_OPEN_OUT_OF_CORE_ONLY) {
        vv_opened_clear(&od);
        return misfit(info, what,
                      "--lod, --level and --progressive need a multiresolution file (OME-Zarr, "
                      "BigDataViewer or Imaris HDF5, or a .vvb with pyramid levels)");
    }
    vv_default_scene_options d;
    scene_options(o, &d);
    vv_error_clear();
    /* out of core, the view frames the level's box */
    s = vv_world_new_for_source(out, od.source, o->level > 0 ? o->level : 0, &d);
    if (s == VV_OK && od.info.n_levels > 1)
        pyramid_appearance(o, what, od.source, *out);
    if (s == VV_OK && od.info.is_label) /* an OME-Zarr label image: segment ids */
        (*out)->objects[0]->segmentation = VV_SEG_LABELS;
    vv_opened_clear(&od); /* the World holds its own reference */
    if (s != VV_OK)
        return fail(s, what);
    if (o->load.time >= 0)
        (*out)->objects[0]->time = o->load.time; /* the file's step it shows */
    return VV_OK;
}

/* A scene file (its volume files out of core when the options ask), with
 * the options' overrides. */
static vv_status
world_for_scene(const vv_world_open_options *o, const char *what, vv_world **out) {
    vv_open_options oo;
    const vv_open_options *open = open_options(o, 1, &oo);
    vv_error_clear();
    /* what a scene leaves out is made for the size and mode drawn, as a file's */
    const scene_overrides over = {o->has_size ? o->view.width : 0, o->has_size ? o->view.height : 0,
                                  o->has_mode, o->view.mode};
    vv_status s = vv_scene_load_for(out, what, o->progress, o->filter_cache, open, &over);
    if (s != VV_OK)
        return fail(s, what);
    vv_world *w = *out;
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *obj = w->objects[i];
        if (!obj || (obj->type != VV_OBJECT_VOLUME && obj->type != VV_OBJECT_GRID))
            continue;
        if (obj->type == VV_OBJECT_GRID && o->field)
            snprintf(obj->field, sizeof obj->field, "%s", o->field);
        if (obj->type == VV_OBJECT_GRID && o->load.time >= 0)
            obj->time = o->load.time;
        if (o->has_mode)
            obj->mode = o->view.mode;
        if (o->view.has_isovalue)
            obj->isovalue = o->view.isovalue;
        if (o->view.has_tf_range) {
            obj->segmentation = VV_SEG_TRANSFER_FUNCTION;
            stretch_tf(&obj->tf, o->view.tf_lo, o->view.tf_hi);
        }
    }
    if (o->has_size) {
        w->view.width = o->view.width;
        w->view.height = o->view.height;
    }
    return VV_OK;
}

/* The options' overrides every World takes (step, labels) and what info
 * tells about the World as built. */
static void
finish(const vv_world_open_options *o, vv_world *w, vv_world_open_info *info) {
    const vv_object *first = NULL;
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *obj = w->objects[i];
        if (!obj)
            continue;
        if (o->step > 0)
            obj->step = o->step;
        if (o->has_attenuation)
            obj->attenuation = o->attenuation;
        if (o->labels && obj->type == VV_OBJECT_VOLUME)
            obj->segmentation = VV_SEG_LABELS;
        if (obj->visible && obj->source)
            info->out_of_core = 1;
        if (!first && obj->type == VV_OBJECT_VOLUME && obj->volume)
            first = obj;
    }
    if (first && o->slice_window)
        vv_slice_auto_window(first->volume, &info->window, &info->level);
}

vv_status
vv_world_open(vv_world **out, const char *what, const vv_world_open_options *opt,
              vv_world_open_info *info) {
    vv_world_open_options defaults;
    vv_world_open_info scratch;
    if (!info)
        info = &scratch;
    memset(info, 0, sizeof *info);
    info->n_channels = info->n_times = 1;
    info->window = 1;
    info->level = 0.5;
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "world open: NULL output");
    *out = NULL;
    if (!what || !*what)
        return vv_error_set(VV_ERR_INVALID, "world open: no input named");
    if (!opt) {
        vv_world_open_options_init(&defaults);
        opt = &defaults;
    }
    if (opt->version != VV_WORLD_OPEN_VERSION)
        return vv_error_set(VV_ERR_INVALID,
                            "%s: options of version %d, this library takes version %d "
                            "(vv_world_open_options_init)",
                            what, opt->version, VV_WORLD_OPEN_VERSION);
    if (opt->n_channels < 0 || opt->n_channels > VV_MAX_CHANNELS || opt->n_colors < 0 ||
        opt->n_colors > VV_MAX_CHANNELS || opt->n_contrast < 0 || opt->n_contrast > VV_MAX_CHANNELS)
        return vv_error_set(VV_ERR_INVALID, "%s: at most %d channels, colours and contrasts", what,
                            VV_MAX_CHANNELS);
    vv_status s = check_readable(what, 1);
    if (s != VV_OK)
        return s;
    const int scene = !opt->load.has_raw && is_scene_file(what);
    if (scene && (opt->n_channels || channels_asked(opt))) {
        const char *which = opt->n_channels   ? "--channels"
                            : opt->n_colors   ? "--colors"
                            : opt->n_contrast ? "--contrast"
                                              : "--blend";
        char why[128];
        snprintf(why, sizeof why, "%s is for a volume file's channels, not a scene", which);
        s = misfit(info, what, why);
        info->options_misfit = 0; /* the input's kind, not a usage error */
        return s;
    }
    info->input = scene ? VV_INPUT_SCENE : VV_INPUT_VOLUME;
    s = scene ? world_for_scene(opt, what, out) : world_for_file(opt, what, out, info);
    if (s != VV_OK) {
        vv_world_free(*out);
        *out = NULL;
        return s;
    }
    finish(opt, *out, info);
    return VV_OK;
}

/* ---- time steps ---------------------------------------------------------------------------- */

struct vv_time_steps {
    int n;                               /* channels (1 for an object of one) */
    vv_time_series *ts[VV_MAX_CHANNELS]; /* channel c's steps */
    /* out of core: each step a source of the object's channels */
    int ooc, n_times;
    char *path;
    vv_open_options oo;
    vv_source *ahead; /* the next step's, opened and read ahead */
    int ahead_step;
};

/* Step @p step of @p t's file out of core (every channel of the object). */
static vv_status
steps_open_source(vv_time_steps *t, int step, vv_source **out, int *n_times) {
    vv_open_options oo = t->oo;
    oo.load.time = step;
    vv_opened od;
    vv_error_clear();
    vv_status s = vv_open(&od, t->path, &oo);
    if (s == VV_OK &&
        (od.kind != VV_DATA_VOLUME || vv_source_get_kind(od.source) == VV_SOURCE_MEMORY))
        s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: step %d is not out of core", t->path, step);
    if (s == VV_OK) {
        *out = vv_source_ref(od.source);
        if (n_times)
            *n_times = od.info.n_times > 1 ? od.info.n_times : 1;
    }
    vv_opened_clear(&od);
    return s;
}

vv_status
vv_time_steps_open(vv_time_steps **out, const char *what, const vv_load_options *load,
                   const vv_object *o) {
    if (!out || !what || !o)
        return vv_error_set(VV_ERR_INVALID, "time steps: NULL argument");
    *out = NULL;
    vv_time_steps *t = calloc(1, sizeof *t);
    if (!t)
        return vv_error_set(VV_ERR_NOMEM, "%s: time steps: out of memory", what);
    t->n = o->n_channels > 0 ? o->n_channels : 1;
    vv_status s = VV_OK;
    if (o->source && vv_source_get_kind(o->source) == VV_SOURCE_PYRAMID) {
        /* out of core: a step a source, opened as the object's was */
        t->ooc = 1;
        t->ahead_step = -1;
        const size_t len = strlen(what) + 1;
        if ((t->path = malloc(len)))
            memcpy(t->path, what, len);
        vv_open_options_init(&t->oo);
        t->oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
        t->oo.levels = 1;
        t->oo.cache = vv_source_cache(o->source);
        t->oo.load.series = load ? load->series : 0;
        if (o->n_channels > 1) {
            t->oo.n_channels = o->n_channels;
            for (int c = 0; c < o->n_channels; c++)
                t->oo.channels[c] = o->channels[c].index;
        } else {
            t->oo.load.channel = load ? load->channel : -1;
        }
        vv_source *s0 = NULL;
        s = t->path ? steps_open_source(t, 0, &s0, &t->n_times)
                    : vv_error_set(VV_ERR_NOMEM, "%s: out of memory", what);
        vv_source_free(s0);
        if (s != VV_OK) {
            vv_time_steps_free(t);
            return s;
        }
        *out = t;
        return VV_OK;
    }
    for (int c = 0; c < t->n && s == VV_OK; c++) {
        vv_load_options opt;
        vv_load_options_init(&opt);
        opt.series = load ? load->series : 0;
        opt.channel = o->n_channels > 0 ? o->channels[c].index : load ? load->channel : -1;
        if (load && load->has_raw) {
            opt.format = VV_FORMAT_RAW;
            opt.has_raw = 1;
            opt.raw = load->raw;
        }
        vv_error_clear();
        s = vv_time_series_open(&t->ts[c], what, &opt, 0);
    }
    if (s != VV_OK) {
        vv_time_steps_free(t);
        return s;
    }
    *out = t;
    return VV_OK;
}

int
vv_time_steps_count(const vv_time_steps *t) {
    return !t ? 0 : t->ooc ? t->n_times : vv_time_series_count(t->ts[0]);
}

/* vv_time_steps_show out of core: step @p step's source (the one read
 * ahead, else opened now) into @p o, the next step's opened and asked for
 * what the step before read. */
static vv_status
show_ooc(vv_time_steps *t, vv_object *o, int step, int next) {
    if (step < 0 || step >= t->n_times)
        return vv_error_set(VV_ERR_INVALID, "%s: time step %d asked, the file has %d", t->path,
                            step, t->n_times);
    vv_source *src = NULL;
    vv_status s = VV_OK;
    if (t->ahead && t->ahead_step == step) {
        src = t->ahead;
        t->ahead = NULL;
    } else {
        s = steps_open_source(t, step, &src, NULL);
    }
    vv_source *before = o->source ? vv_source_ref(o->source) : NULL;
    if (s == VV_OK && (s = vv_object_replace_source(o, src, 0)) == VV_OK)
        o->time = step;
    vv_source_free(src);
    if (s == VV_OK && next >= 0 && next < t->n_times && next != t->ahead_step) {
        vv_source_free(t->ahead);
        t->ahead = NULL;
        t->ahead_step = -1;
        /* a failure to read ahead only costs the next step its head start */
        if (steps_open_source(t, next, &t->ahead, NULL) == VV_OK) {
            t->ahead_step = next;
            if (before && vv_source_read_ahead(t->ahead, before) != VV_OK)
                vv_error_clear();
        } else {
            vv_error_clear();
        }
    }
    vv_source_free(before);
    return s;
}

vv_status
vv_time_steps_show(vv_time_steps *t, vv_object *o, int step, int next) {
    if (t->ooc)
        return show_ooc(t, o, step, next);
    vv_volume *v[VV_MAX_CHANNELS] = {NULL};
    vv_status s = VV_OK;
    for (int c = 0; c < t->n && s == VV_OK; c++)
        s = vv_time_series_get(t->ts[c], step, &v[c]);
    for (int c = 0; c < t->n && s == VV_OK && next >= 0; c++)
        vv_time_series_prefetch(t->ts[c], next);
    if (s == VV_OK && (s = vv_object_replace_volumes(o, t->n, v)) == VV_OK)
        o->time = step;
    for (int c = 0; c < t->n; c++)
        vv_volume_free(v[c]); /* the object holds its own references */
    return s;
}

void
vv_time_steps_free(vv_time_steps *t) {
    if (!t)
        return;
    for (int c = 0; c < VV_MAX_CHANNELS; c++)
        vv_time_series_free(t->ts[c]);
    vv_source_free(t->ahead);
    free(t->path);
    free(t);
}
