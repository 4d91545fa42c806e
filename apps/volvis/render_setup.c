/*
 * What `volvis render` and `volvis animate` share: the rendering options
 * (parsing and --help text), building the World from a volume or a scene
 * file with those options, the view turn (--azimuth, --elevation, --zoom,
 * --ortho) and creating the renderer with its --set options. Both commands
 * go through these functions, so frame k of `volvis animate --orbit` is the
 * still `volvis render --azimuth` draws.
 */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"

static const char *const mode_names[] = {"composite", "mip", "minip", "xray", "iso"};
static const vv_render_mode mode_values[] = {VV_MODE_COMPOSITE, VV_MODE_MIP, VV_MODE_MINIP,
                                             VV_MODE_XRAY, VV_MODE_ISO};

/* Prints @p prefix and @p text word-wrapped to @p width columns, every line
 * indented by @p indent spaces. */
static void
print_wrapped(FILE *out, const char *prefix, const char *text, int indent, int width) {
    int col = fprintf(out, "%*s%s", indent, "", prefix);
    for (const char *w = text; *w;) {
        size_t n = strcspn(w, " ");
        if (col > indent && col + 1 + (int)n > width)
            col = fprintf(out, "\n%*s", indent, "") - 1;
        else if (w != text)
            col += fprintf(out, " ");
        col += fprintf(out, "%.*s", (int)n, w);
        w += n;
        while (*w == ' ')
            w++;
    }
    fputc('\n', out);
}

static int
parse_mode(const cli_args *a, const char *text, vv_render_mode *out) {
    for (size_t i = 0; i < sizeof mode_names / sizeof mode_names[0]; i++)
        if (strcmp(text, mode_names[i]) == 0) {
            *out = mode_values[i];
            return 0;
        }
    return cli_usage_error(a, "--mode: unknown mode '%s' (composite, mip, minip, xray, iso)", text);
}

static int
renderer_known(const char *name) {
    return vv_renderer_info_find(name) != NULL;
}

/* A scene file: extension .json, or content that starts with '{' after whitespace. */
int
cli_is_scene_file(const char *path) {
    size_t n = strlen(path);
    if (n >= 5 && strcasecmp(path + n - 5, ".json") == 0)
        return 1;
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

/* One colour: a name of the table or #rrggbb. */
static int
parse_color(const char *text, size_t n, vv_vec3 *out) {
    static const struct {
        const char *name;
        double r, g, b;
    } names[] = {{"red", 1, 0, 0},          {"green", 0, 1, 0},       {"blue", 0, 0, 1},
                 {"magenta", 1, 0, 1},      {"cyan", 0, 1, 1},        {"yellow", 1, 1, 0},
                 {"white", 1, 1, 1},        {"gray", 0.5, 0.5, 0.5},  {"grey", 0.5, 0.5, 0.5},
                 {"orange", 0.90, 0.62, 0}, {"sky", 0.34, 0.71, 0.91}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strlen(names[i].name) == n && strncasecmp(text, names[i].name, n) == 0) {
            *out = vv_vec3_make(names[i].r, names[i].g, names[i].b);
            return 1;
        }
    if (n == 7 && text[0] == '#' && strspn(text + 1, "0123456789abcdefABCDEF") >= 6) {
        char hex[3] = {0, 0, 0};
        double c[3];
        for (int k = 0; k < 3; k++) {
            memcpy(hex, text + 1 + 2 * k, 2);
            c[k] = (double)strtol(hex, NULL, 16) / 255.0;
        }
        *out = vv_vec3_make(c[0], c[1], c[2]);
        return 1;
    }
    return 0;
}

/* --channels, --colors, --contrast, --blend (a file's channels as one object). */
static int
parse_channel_options(cli_args *a, cli_render_args *r) {
    const char *s;
    int rc;
    if ((s = cli_get(a, "channels"))) {
        if (cli_get(a, "channel"))
            return cli_usage_error(a, "--channels: give either --channel C or --channels LIST");
        for (const char *p = s;;) {
            char *end;
            long c = strtol(p, &end, 10);
            if (end == p || c < 0 || c > 1000000 || (*end && *end != ','))
                return cli_usage_error(a,
                                       "--channels: '%s' is not a list of channel indices "
                                       "(e.g. 0,2)",
                                       s);
            if (r->n_channels == VV_MAX_CHANNELS)
                return cli_usage_error(a, "--channels: at most %d channels", VV_MAX_CHANNELS);
            for (int i = 0; i < r->n_channels; i++)
                if (r->channels[i] == (int)c)
                    return cli_usage_error(a, "--channels: channel %ld twice", c);
            r->channels[r->n_channels++] = (int)c;
            if (!*end)
                break;
            p = end + 1;
        }
    }
    if ((s = cli_get(a, "colors"))) {
        for (const char *p = s;;) {
            size_t n = strcspn(p, ",");
            if (r->n_colors == VV_MAX_CHANNELS || !parse_color(p, n, &r->colors[r->n_colors]))
                return cli_usage_error(a,
                                       "--colors: '%.*s' is not a colour (red, green, blue, "
                                       "magenta, cyan, yellow, white, gray, orange, sky or "
                                       "#rrggbb)",
                                       (int)n, p);
            r->n_colors++;
            if (!p[n])
                break;
            p += n + 1;
        }
    }
    if ((s = cli_get(a, "contrast"))) {
        for (const char *p = s;;) {
            size_t n = strcspn(p, ",");
            char one[128];
            if (n >= sizeof one || r->n_contrast == VV_MAX_CHANNELS)
                return cli_usage_error(a, "--contrast: '%s' is too long", s);
            memcpy(one, p, n);
            one[n] = '\0';
            double *lim = r->contrast[r->n_contrast];
            if ((rc = cli_parse_range(a, "contrast", one, &lim[0], &lim[1])))
                return rc;
            if (!(lim[1] > lim[0]))
                return cli_usage_error(a, "--contrast: '%s' needs LO < HI", one);
            r->n_contrast++;
            if (!p[n])
                break;
            p += n + 1;
        }
    }
    if ((s = cli_get(a, "blend"))) {
        vv_error_clear();
        if (vv_channel_blend_parse(s, &r->blend) != VV_OK)
            return cli_usage_error(a,
                                   "--blend: unknown rule '%s' (composite, additive or "
                                   "maximum)",
                                   s);
        r->has_blend = 1;
    }
    if ((s = cli_get(a, "label-channels"))) {
        for (const char *p = s;;) {
            char *end;
            long c = strtol(p, &end, 10);
            int at = -1;
            for (int i = 0; end != p && i < r->n_channels; i++)
                if (r->channels[i] == c)
                    at = i;
            if (end == p || (*end && *end != ','))
                return cli_usage_error(a,
                                       "--label-channels: '%s' is not a list of channel indices "
                                       "(e.g. 3)",
                                       s);
            if (at < 0 && r->n_channels)
                return cli_usage_error(a, "--label-channels: channel %ld is not in --channels %s",
                                       c, cli_get(a, "channels"));
            if (at >= 0)
                r->label_channel[at] = 1;
            if (!*end)
                break;
            p = end + 1;
        }
    }
    if (cli_get(a, "label-channels") && !r->n_channels)
        return cli_usage_error(a, "--label-channels: only with --channels LIST");
    /* colours, contrast limits or a blend rule alone: every channel of the file in
     * order (napari's colormap=[...]); how many the file has is known once open */
    r->all_channels = !r->n_channels && (r->n_colors || r->n_contrast || r->has_blend);
    if (r->n_channels && (r->n_colors > r->n_channels || r->n_contrast > r->n_channels))
        return cli_usage_error(a, "%s: %d given for %d channel%s",
                               r->n_colors > r->n_channels ? "--colors" : "--contrast",
                               r->n_colors > r->n_channels ? r->n_colors : r->n_contrast,
                               r->n_channels, r->n_channels == 1 ? "" : "s");
    const char *chan = r->n_channels   ? "--channels"
                       : r->n_colors   ? "--colors"
                       : r->n_contrast ? "--contrast"
                                       : "--blend";
    if ((r->n_channels || r->all_channels) && cli_get(a, "memory-limit"))
        return cli_usage_error(a,
                               "%s: volumes larger than memory are drawn one "
                               "channel at a time (--channel C with --memory-limit)",
                               chan);
    if ((r->n_channels || r->all_channels) &&
        (cli_get(a, "mode") || cli_get(a, "iso") || cli_get(a, "tf")))
        return cli_usage_error(a,
                               "%s: the channels show by --blend and --contrast, "
                               "not --mode, --iso or --tf",
                               chan);
    if (r->all_channels && cli_get(a, "channel"))
        return cli_usage_error(a,
                               "%s: for every channel, not with --channel C (give "
                               "--channels LIST)",
                               chan);
    return 0;
}

int
cli_render_parse(cli_args *a, cli_render_args *r) {
    int rc;
    const char *s;
    int input_optional = r->input_optional;
    memset(r, 0, sizeof *r);
    r->input_optional = input_optional;
    r->renderer = NULL; /* not given: the scene's, else raycast */
    r->zoom = 1;
    r->gamma = 1;
    r->quality = 2;
    if (a->n_pos == 0 && !r->input_optional)
        return cli_usage_error(a, "missing INPUT");
    if (a->n_pos > 1)
        return cli_usage_error(a, "expected one INPUT, got %d arguments", a->n_pos);
    r->input = a->n_pos ? a->pos[0] : NULL;
    r->output = cli_get(a, "output");
    if (!r->output || !*r->output)
        return cli_usage_error(a, "missing -o %s",
                               strcmp(a->cmd, "render") == 0 ? "OUT.png" : "OUT");
    if ((s = cli_get(a, "mode"))) {
        if ((rc = parse_mode(a, s, &r->mode)))
            return rc;
        r->has_mode = 1;
    }
    if ((s = cli_get(a, "iso"))) {
        if ((rc = cli_parse_double(a, "iso", s, -HUGE_VAL, HUGE_VAL, &r->iso)))
            return rc;
        r->has_iso = 1;
        if (!r->has_mode) {
            r->has_mode = 1;
            r->mode = VV_MODE_ISO;
        }
    }
    if ((s = cli_get(a, "tf"))) {
        if ((rc = cli_parse_range(a, "tf", s, &r->tf_lo, &r->tf_hi)))
            return rc;
        r->has_tf = 1;
    }
    if ((s = cli_get(a, "size"))) {
        if ((rc = cli_parse_size(a, "size", s, &r->width, &r->height)))
            return rc;
        r->has_size = 1;
    }
    if ((s = cli_get(a, "azimuth"))) {
        if ((rc = cli_parse_double(a, "azimuth", s, -1e6, 1e6, &r->azimuth)))
            return rc;
        r->has_view = 1;
    }
    if ((s = cli_get(a, "elevation"))) {
        if ((rc = cli_parse_double(a, "elevation", s, -1e6, 1e6, &r->elevation)))
            return rc;
        r->has_view = 1;
    }
    if ((s = cli_get(a, "zoom"))) {
        if ((rc = cli_parse_double(a, "zoom", s, 1e-6, 1e6, &r->zoom)))
            return rc;
        r->has_view = 1;
    }
    if ((s = cli_get(a, "threads")) && (rc = cli_parse_int(a, "threads", s, 0, 4096, &r->threads)))
        return rc;
    r->radix = 4;
    if ((s = cli_get(a, "compositing"))) {
        if (strcmp(s, "binary-swap") == 0) {
            r->compositing = VV_COMPOSITING_BINARY_SWAP;
        } else if (strncmp(s, "radix-k", 7) == 0 && (s[7] == 0 || s[7] == ':')) {
            r->compositing = VV_COMPOSITING_RADIX_K;
            if (s[7] == ':' && (rc = cli_parse_int(a, "compositing", s + 8, 2, 4096, &r->radix)))
                return rc;
        } else {
            return cli_usage_error(a, "--compositing: '%s' is not binary-swap or radix-k[:K]", s);
        }
    }
    if ((s = cli_get(a, "memory-limit")) &&
        (rc = cli_parse_bytes(a, "memory-limit", s, &r->memory_limit)))
        return rc;
    if ((s = cli_get(a, "level"))) {
        if ((rc = cli_parse_int(a, "level", s, 0, 64, &r->level)))
            return rc;
        r->has_level = 1;
    }
    r->lod = 1;
    if ((s = cli_get(a, "lod"))) {
        if ((rc = cli_parse_double(a, "lod", s, 1e-3, 1e3, &r->lod)))
            return rc;
        r->has_lod = 1;
        if (r->has_level)
            return cli_usage_error(a, "--lod and --level: one or the other");
    }
    if ((s = cli_get(a, "progressive")) &&
        (rc = cli_parse_int(a, "progressive", s, 1, 1000000000, &r->progressive)))
        return rc;
    r->field = cli_get(a, "field");
    if ((s = cli_get(a, "time"))) {
        if ((rc = cli_parse_int(a, "time", s, 0, 1000000, &r->time)))
            return rc;
        r->has_time = 1;
    }
    if ((s = cli_get(a, "step"))) {
        if ((rc = cli_parse_double(a, "step", s, 1e-4, 1e4, &r->step)))
            return rc;
        if (!(r->step > 0))
            return cli_usage_error(a, "--step: must be > 0, got '%s'", s);
        r->has_step = 1;
    }
    if ((s = cli_get(a, "raw"))) {
        if ((rc = cli_parse_raw(a, "raw", s, &r->raw)))
            return rc;
        r->has_raw = 1;
    }
    int time_unused; /* --time is parsed above: a grid's step, or the volume file's */
    if ((rc = cli_parse_series_channel(a, &r->series, &r->channel, &time_unused)))
        return rc;
    if ((rc = parse_channel_options(a, r)))
        return rc;
    if ((s = cli_get(a, "gamma"))) {
        if ((rc = cli_parse_double(a, "gamma", s, 0.01, 100, &r->gamma)))
            return rc;
    }
    if ((s = cli_get(a, "quality"))) {
        if ((rc = cli_parse_int(a, "quality", s, 0, 2, &r->quality)))
            return rc;
        r->has_quality = 1;
    }
    if ((s = cli_get(a, "renderer"))) {
        r->renderer = s;
        if (!renderer_known(s)) {
            char names[512];
            return cli_usage_error(a, "--renderer: unknown renderer '%s' (available: %s)", s,
                                   cli_renderer_names(names, sizeof names));
        }
    }
    for (int i = 0; i < a->n_seen; i++) {
        if (strcmp(a->specs[a->seen[i].opt].name, "set") != 0)
            continue;
        const char *kv = a->seen[i].value;
        const char *eq = strchr(kv, '=');
        if (!eq || eq == kv)
            return cli_usage_error(a, "--set: expected KEY=VALUE, got '%s'", kv);
    }
    r->alpha = cli_count(a, "alpha") > 0;
    r->quiet = cli_count(a, "quiet") > 0;
    r->ortho = cli_count(a, "ortho") > 0;
    r->labels = cli_count(a, "labels") > 0;
    return 0;
}

/* Builds the World for a grid file (vv_world_new_for_grid). */
static int
world_for_grid(const cli_render_args *r, vv_grid *g, vv_world **out) {
    if (r->time_range) {
        cli_error("%s: --time-range is for a volume file's time steps, not a grid", r->input);
        return CLI_EXIT_FAIL;
    }
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    if (r->has_mode)
        o.mode = r->mode;
    if (r->has_tf) {
        o.has_tf_range = 1;
        o.tf_lo = r->tf_lo;
        o.tf_hi = r->tf_hi;
    }
    if (r->has_iso) {
        o.has_isovalue = 1;
        o.isovalue = r->iso;
    }
    if (r->has_size) {
        o.width = r->width;
        o.height = r->height;
    }
    vv_error_clear();
    vv_status s = vv_world_new_for_grid(out, g, r->field, r->time, &o);
    if (s != VV_OK)
        return cli_fail(s, r->input);
    return 0;
}

/* --channels: the file's channels as one object of several channels
 * (vv_object_set_channels), coloured and limited by --colors and
 * --contrast, combined by --blend; one channel alone is a one-channel
 * object with that colour and contrast. */
static int
world_for_channels(const cli_render_args *r, vv_world **out) {
    vv_volume *v[VV_MAX_CHANNELS] = {NULL};
    vv_load_info info[VV_MAX_CHANNELS];
    char names[VV_MAX_CHANNELS][VV_CHANNEL_NAME_MAX];
    const char *np[VV_MAX_CHANNELS];
    int rc = 0;
    for (int c = 0; c < r->n_channels && !rc; c++) {
        rc = cli_load_volume_sc(r->input, r->has_raw ? &r->raw : NULL, r->series, r->channels[c],
                                r->has_time ? r->time : -1, &info[c], &v[c]);
        /* the file's name for the channel (OME Channel Name), else its index */
        if (!rc && info[c].channel_name[0])
            snprintf(names[c], sizeof names[c], "%s", info[c].channel_name);
        else
            snprintf(names[c], sizeof names[c], "channel %d", r->channels[c]);
        np[c] = names[c];
    }
    if (!rc)
        rc = cli_render_world_volume(r, v[0], out);
    vv_object *o = rc ? NULL : (*out)->objects[0];
    vv_status s = VV_OK;
    if (o && r->n_channels > 1) {
        vv_error_clear();
        s = vv_object_set_channels(o, r->n_channels, v, np);
        o->blend = r->has_blend ? r->blend : VV_BLEND_COMPOSITE;
        for (int c = 0; s == VV_OK && c < r->n_channels; c++) {
            o->channels[c].index = r->channels[c];
            if (r->label_channel[c])
                s = vv_object_set_channel_labels(o, c, 1);
        }
    }
    for (int c = 0; o && s == VV_OK && c < r->n_channels; c++) {
        vv_tf *tf = r->n_channels > 1 ? &o->channels[c].tf : &o->tf;
        double lo, hi;
        if (c < r->n_contrast) {
            lo = r->contrast[c][0];
            hi = r->contrast[c][1];
        } else if (r->n_channels > 1) { /* vv_object_set_channels' quantiles */
            lo = tf->opacity[0].value;
            hi = tf->opacity[tf->n_opacity - 1].value;
        } else {
            vv_channel_default_contrast(v[0], &lo, &hi);
        }
        /* --colors, else the file's colour (OME Channel Color), else the default set */
        vv_vec3 col = c < r->n_colors ? r->colors[c]
                      : info[c].has_color
                          ? vv_vec3_make(info[c].color[0], info[c].color[1], info[c].color[2])
                          : vv_channel_default_color(c);
        vv_error_clear();
        s = vv_tf_set_contrast(tf, lo, hi, 1.0, 0.5, col, vv_tf_default_unit_distance(v[c]));
        if (r->n_channels == 1 && r->has_blend && r->blend == VV_BLEND_MAXIMUM)
            o->mode = VV_MODE_MIP;
        if (r->n_channels == 1 && r->label_channel[0])
            o->segmentation = VV_SEG_LABELS;
    }
    for (int c = 0; c < r->n_channels; c++)
        vv_volume_free(v[c]); /* the object holds its own references */
    if (s != VV_OK)
        return cli_fail(s, r->input);
    if (o && r->has_time)
        o->time = r->time; /* the file's step it shows */
    return rc;
}

const vv_open_options *
cli_render_open_options(const cli_render_args *r, int scene, vv_open_options *o) {
    vv_open_options_init(o);
    vv_cache_set_limit(vv_cache_process(), r->memory_limit); /* 0: the default, 1 GiB */
    const int ooc = r->memory_limit > 0 || r->has_lod || r->progressive > 0;
    /* under mpirun a file read by boxes is read so by each rank: its own box */
    const int ranks = vv_parallel_launched();
    o->mode = ooc || (ranks && !scene) ? VV_OPEN_OUT_OF_CORE : VV_OPEN_DEFAULT;
    o->levels = r->has_lod || r->progressive > 0 || r->has_level;
    o->load.level = r->has_level ? r->level : 0;
    if (scene)
        return ooc ? o : NULL; /* a scene's files are read whole unless asked */
    o->load.series = r->series;
    o->load.channel = r->channel;
    o->load.time = r->has_time ? r->time : -1;
    if (r->has_raw) {
        o->load.format = VV_FORMAT_RAW;
        o->load.has_raw = 1;
        o->load.raw = r->raw;
    }
    /* under mpirun each rank reads its own box: the range comes from them */
    o->header_only = ranks;
    return o;
}

void
cli_render_lod(const cli_render_args *r, vv_lod *lod) {
    vv_lod_init(lod);
    lod->level = r->has_level ? r->level : -1;
    lod->voxel_pixels = r->lod;
}

int
cli_world_out_of_core(const vv_world *w) {
    for (int i = 0; w && i < w->n_objects; i++)
        if (w->objects[i]->visible && w->objects[i]->source)
            return 1;
    return 0;
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

/* Whether the file must be read out of core because rendering it in
 * memory would take more than the memory budget (--max-memory; by default
 * half the memory available): a volume file that can be read out of core
 * (bricks: .vvb, raw or uncompressed NRRD; levels: a pyramid), drawn by a
 * renderer with the region contract (raycast, raytrace), one channel, no
 * time step asked for (--time, --time-range: steps are read whole), no
 * out-of-core option given. Then *od holds it opened out of core, the
 * process cache's limit is set to a quarter of the budget
 * (and of the memory available, at most 1 GiB) and the switch is said in
 * one line. Returns 1 when switched. */
static int
too_big_for_memory(const cli_render_args *r, const vv_open_options *oo, vv_opened *od) {
    const vv_renderer_info *in = vv_renderer_info_find(r->renderer ? r->renderer : "raycast");
    if (oo->mode != VV_OPEN_DEFAULT || vv_parallel_launched() || r->all_channels || r->has_time ||
        r->time_range || !in || !(in->caps & VV_RENDERER_REGION))
        return 0;
    const uint64_t budget = vv_memory_budget_get(), avail = vv_memory_available();
    uint64_t limit = budget / 4;
    limit = limit > avail / 4 ? avail / 4 : limit; /* a raised budget past a cgroup's limit */
    limit = limit > ((uint64_t)1 << 30) ? (uint64_t)1 << 30 : limit;
    /* the header alone first (no pass over the voxels) */
    vv_open_options probe = *oo;
    probe.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    probe.header_only = 1;
    vv_cache_set_limit(vv_cache_process(), limit);
    vv_error_clear();
    memset(od, 0, sizeof *od);
    uint64_t need = 0;
    if (vv_open(od, r->input, &probe) == VV_OK && od->kind == VV_DATA_VOLUME) {
        const vv_volume *h = vv_source_level(od->source, 0);
        const int shaded = !r->has_mode || r->mode == VV_MODE_COMPOSITE || r->mode == VV_MODE_ISO;
        need = h ? in_memory_bytes(h, shaded) : 0;
    }
    vv_opened_clear(od);
    vv_error_clear();
    probe.header_only = oo->header_only;
    if (need <= budget || vv_open(od, r->input, &probe) != VV_OK) {
        vv_opened_clear(od);
        vv_error_clear(); /* read whole, as before */
        vv_cache_set_limit(vv_cache_process(), r->memory_limit);
        return 0;
    }
    if (!r->quiet)
        fprintf(stderr,
                "volvis: note: %s: rendering it in memory would take %llu MiB, more than the "
                "memory budget of %llu MiB (--max-memory): read out of core (--memory-limit "
                "%lluM)\n",
                r->input, (unsigned long long)(need >> 20), (unsigned long long)(budget >> 20),
                (unsigned long long)(limit >> 20));
    return 1;
}

/* Builds the World for a file: opened once through the format table
 * (vv_open), a volume in memory or out of core as the options say (or
 * because it does not fit in memory: too_big_for_memory), or an irregular
 * grid. */
static int
world_for_file(const cli_render_args *r, vv_world **out) {
    if (r->n_channels)
        return world_for_channels(r, out);
    int rc = r->has_raw ? cli_check_readable(r->input) : cli_check_readable_input(r->input);
    if (rc)
        return rc;
    vv_open_options oo;
    cli_render_open_options(r, 0, &oo);
    /* out of core asked for (--memory-limit, --lod, --progressive): a file
     * that cannot be is refused, not read whole */
    if (oo.mode == VV_OPEN_OUT_OF_CORE && !vv_parallel_launched())
        oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    vv_opened od;
    vv_error_clear();
    vv_status s = VV_OK;
    if (too_big_for_memory(r, &oo, &od))
        oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    else
        s = vv_open(&od, r->input, &oo);
    if (s == VV_ERR_UNSUPPORTED && vv_error_message()[0]) /* the store's reason */
        return cli_fail(s, r->input);
    if (s == VV_ERR_UNSUPPORTED) {
        cli_error("%s: cannot be read out of core (by bricks: .vvb, raw or uncompressed NRRD; by "
                  "levels: a pyramid); convert it to .vvb first (volvis convert IN OUT.vvb)",
                  r->input);
        return CLI_EXIT_FAIL;
    }
    if (s == VV_OK && od.kind == VV_DATA_VOLUME && r->all_channels) {
        /* --colors, --contrast or --blend alone: the file's channels, all of them */
        const int n = od.info.n_channels > 1 ? od.info.n_channels : 1;
        vv_opened_clear(&od);
        const char *opt = r->n_colors > n ? "--colors" : r->n_contrast > n ? "--contrast" : NULL;
        if (opt) {
            cli_error("%s: %s: %d given for the file's %d channel%s", r->input, opt,
                      r->n_colors > n ? r->n_colors : r->n_contrast, n, n == 1 ? "" : "s");
            return CLI_EXIT_USAGE;
        }
        if (n > VV_MAX_CHANNELS) {
            cli_error("%s: %d channels: at most %d show as one object (--channels LIST)", r->input,
                      n, VV_MAX_CHANNELS);
            return CLI_EXIT_FAIL;
        }
        cli_render_args every = *r;
        every.all_channels = 0;
        every.n_channels = n;
        for (int c = 0; c < n; c++)
            every.channels[c] = c;
        return world_for_channels(&every, out);
    }
    if (s == VV_OK && od.kind == VV_DATA_GRID) { /* an irregular grid: its own World */
        rc = world_for_grid(r, od.grid, out);
        vv_opened_clear(&od);
        return rc;
    }
    if (s == VV_OK && od.kind != VV_DATA_VOLUME)
        s = vv_error_set(VV_ERR_FORMAT, "%s: not a volume or grid file", r->input);
    if (s != VV_OK) {
        vv_opened_clear(&od);
        return cli_fail(s, r->input);
    }
    if (oo.levels && (r->has_lod || r->progressive > 0 || r->level > 0) &&
        vv_source_get_kind(od.source) != VV_SOURCE_PYRAMID && oo.mode == VV_OPEN_OUT_OF_CORE_ONLY) {
        vv_opened_clear(&od);
        cli_error("%s: --lod, --level and --progressive need a multiresolution file (OME-Zarr, "
                  "BigDataViewer or Imaris HDF5, or a .vvb with pyramid levels)",
                  r->input);
        return CLI_EXIT_USAGE;
    }
    if (r->file_channels)
        *r->file_channels = od.info.n_channels > 1 ? od.info.n_channels : 1;
    rc = cli_render_world_source(r, od.source, out);
    vv_opened_clear(&od); /* the World holds its own reference */
    if (!rc && r->has_time)
        (*out)->objects[0]->time = r->time; /* the file's step it shows */
    return rc;
}

/* @p r's options of a default scene. */
static void
default_options(const cli_render_args *r, vv_default_scene_options *o) {
    vv_default_scene_options_init(o);
    if (r->has_mode)
        o->mode = r->mode;
    if (r->has_tf) {
        o->has_tf_range = 1;
        o->tf_lo = r->tf_lo;
        o->tf_hi = r->tf_hi;
    }
    if (r->has_iso) {
        o->has_isovalue = 1;
        o->isovalue = r->iso;
    }
    if (r->has_size) {
        o->width = r->width;
        o->height = r->height;
    }
    /* the view turn (--azimuth, --elevation, --zoom) is cli_render_turn's */
}

/* The step override of --step on every object of *@p out. */
static void
apply_step(const cli_render_args *r, vv_world *w) {
    if (r->has_step)
        for (int i = 0; i < w->n_objects; i++)
            w->objects[i]->step = r->step;
}

int
cli_render_world_volume(const cli_render_args *r, vv_volume *v, vv_world **out) {
    vv_default_scene_options o;
    default_options(r, &o);
    vv_error_clear();
    vv_status s = vv_world_new_for_volume(out, v, &o);
    if (s != VV_OK)
        return cli_fail(s, r->input);
    apply_step(r, *out);
    return 0;
}

int
cli_render_world_source(const cli_render_args *r, vv_source *src, vv_world **out) {
    vv_default_scene_options o;
    default_options(r, &o);
    vv_error_clear();
    /* out of core, the view frames level --level's box */
    vv_status s = vv_world_new_for_source(out, src, r->has_level ? r->level : 0, &o);
    if (s != VV_OK)
        return cli_fail(s, r->input);
    apply_step(r, *out);
    return 0;
}

/* Loads a scene file (its volume files out of core when the options ask)
 * and applies the overrides given on the command line. */
static int
world_for_scene(const cli_render_args *r, vv_world **out) {
    vv_error_clear();
    cli_progress pr; /* geometry objects are voxelized while loading */
    cli_progress_begin(&pr, r->quiet);
    vv_open_options oo;
    const vv_open_options *open = cli_render_open_options(r, 1, &oo);
    vv_status s = vv_scene_load_open(out, r->input, &pr.p, NULL, open);
    cli_progress_end(&pr);
    if (s != VV_OK)
        return cli_fail(s, r->input);
    vv_world *w = *out;
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *obj = w->objects[i];
        if (!obj || (obj->type != VV_OBJECT_VOLUME && obj->type != VV_OBJECT_GRID))
            continue;
        if (obj->type == VV_OBJECT_GRID && r->field)
            snprintf(obj->field, sizeof obj->field, "%s", r->field);
        if (obj->type == VV_OBJECT_GRID && r->has_time)
            obj->time = r->time;
        if (r->has_mode)
            obj->mode = r->mode;
        if (r->has_iso)
            obj->isovalue = r->iso;
        if (r->has_tf) {
            obj->segmentation = VV_SEG_TRANSFER_FUNCTION;
            stretch_tf(&obj->tf, r->tf_lo, r->tf_hi);
        }
    }
    if (r->has_size) {
        w->view.width = r->width;
        w->view.height = r->height;
    }
    return 0;
}

/* The end of every World's set-up: on failure (@p rc) *@p out freed and
 * NULL; else the overrides of the command line (step, labels). Returns
 * @p rc. */
static int
world_done(const cli_render_args *r, int rc, vv_world **out) {
    if (rc) {
        vv_world_free(*out);
        *out = NULL;
        return rc;
    }
    vv_world *w = *out;
    if (r->has_step)
        for (int i = 0; i < w->n_objects; i++)
            if (w->objects[i])
                w->objects[i]->step = r->step;
    if (r->labels)
        for (int i = 0; i < w->n_objects; i++)
            if (w->objects[i] && w->objects[i]->type == VV_OBJECT_VOLUME)
                w->objects[i]->segmentation = VV_SEG_LABELS;
    return 0;
}

int
cli_render_world(const cli_render_args *r, vv_world **out) {
    *out = NULL;
    int rc = cli_check_readable_input(r->input);
    if (rc)
        return rc;
    int scene = !r->has_raw && cli_is_scene_file(r->input);
    if (scene && (r->n_channels || r->all_channels || r->time_range)) {
        fprintf(stderr, "volvis: %s: %s is for a volume file's %s, not a scene\n", r->input,
                r->n_channels     ? "--channels"
                : r->all_channels ? (r->n_colors     ? "--colors"
                                     : r->n_contrast ? "--contrast"
                                                     : "--blend")
                                  : "--time-range",
                r->n_channels || r->all_channels ? "channels" : "time steps");
        return CLI_EXIT_FAIL;
    }
    /* a file: vv_open says what it holds (a volume, or an irregular grid) */
    rc = scene ? world_for_scene(r, out) : world_for_file(r, out);
    return world_done(r, rc, out);
}

void
cli_render_ortho(const cli_render_args *r, vv_world *w) {
    if (r->ortho && w->view.projection != VV_PROJECTION_ORTHOGRAPHIC) {
        /* the same direction, parallel rays, the scene framed */
        w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
        vv_view_frame_box(&w->view, vv_world_bounds(w));
        if (r->zoom != 1)
            w->view.ortho_height /= r->zoom;
    }
}

void
cli_render_turn(const cli_render_args *r, vv_world *w) {
    vv_anim_view_turn(&w->view, vv_deg_to_rad(r->azimuth), vv_deg_to_rad(r->elevation), r->zoom);
    cli_render_ortho(r, w);
}

const char *
cli_renderer_names(char *buf, size_t cap) {
    buf[0] = '\0';
    for (int i = 0; i < vv_renderer_count(); i++) {
        size_t n = strlen(buf);
        snprintf(buf + n, cap - n, "%s%s", i ? ", " : "", vv_renderer_info_at(i)->name);
    }
    return buf[0] ? buf : "none";
}

int
cli_render_renderer(const cli_args *a, const cli_render_args *r, const vv_world *w,
                    vv_renderer **out, int *quality) {
    *out = NULL;
    const vv_render_settings *sc = &w->render;
    /* the scene's renderer, else the one its objects call for (render.h) */
    const char *scene_renderer = vv_world_renderer(w);
    const char *name = r->renderer ? r->renderer : scene_renderer;
    if (!r->renderer && !renderer_known(name)) {
        char names[512];
        cli_error("%s: render.renderer: unknown renderer '%s' (available: %s)", r->input, name,
                  cli_renderer_names(names, sizeof names));
        return CLI_EXIT_FAIL;
    }
    *quality = r->has_quality ? r->quality : vv_render_settings_quality(sc);
    vv_renderer *ren = NULL;
    vv_error_clear();
    vv_status s = vv_renderer_new(&ren, name);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    /* the scene's options belong to the scene's renderer */
    if (strcmp(name, scene_renderer) == 0)
        for (int i = 0; i < sc->n_options; i++) {
            vv_error_clear();
            if (vv_renderer_set_option(ren, sc->option_keys[i], sc->option_values[i]) != VV_OK) {
                const char *m = vv_error_message();
                cli_error("%s: render.options.%s: %s", r->input, sc->option_keys[i],
                          m && *m ? m : "the renderer does not accept it");
                vv_renderer_free(ren);
                return CLI_EXIT_FAIL;
            }
        }
    for (int i = 0; i < a->n_seen; i++) {
        if (strcmp(a->specs[a->seen[i].opt].name, "set") != 0)
            continue;
        char key[256];
        const char *kv = a->seen[i].value;
        size_t klen = (size_t)(strchr(kv, '=') - kv);
        if (klen >= sizeof key) {
            vv_renderer_free(ren);
            return cli_usage_error(a, "--set: key too long in '%s'", kv);
        }
        memcpy(key, kv, klen);
        key[klen] = '\0';
        vv_error_clear();
        if ((s = vv_renderer_set_option(ren, key, kv + klen + 1)) != VV_OK) {
            const char *m = vv_error_message();
            int rc = cli_usage_error(a, "--set %s: %s", kv,
                                     m && *m ? m : "the renderer does not accept it");
            vv_renderer_free(ren);
            return rc;
        }
    }
    *out = ren;
    return 0;
}

void
cli_render_print_options(FILE *out) {
    fprintf(out,
            "  --mode MODE      composite (default), mip (maximum intensity projection),\n"
            "                   minip (minimum intensity projection), xray (average\n"
            "                   along the ray) or iso (shaded isosurface); for a scene,\n"
            "                   applies to every volume object (geometric objects have none)\n"
            "  --iso V          isovalue for --mode iso (alone it implies --mode iso)\n"
            "  --tf LO:HI       transfer function ramp from LO (transparent) to HI (opaque)\n"
            "                   in data values (default: from the histogram); for a scene,\n"
            "                   the scene's transfer functions are stretched onto [LO, HI]\n"
            "  --size WxH       image size in pixels, 1..%d (default 512x512 or the scene's)\n"
            "  --azimuth DEG    orbit the camera about the up axis, degrees (default 0)\n"
            "  --elevation DEG  orbit the camera towards the up axis, degrees (default 0)\n"
            "  --zoom F         > 1 moves the camera closer, < 1 farther (default 1)\n"
            "  --threads N      threads, 0 = all cores (default 0)\n"
            "  --renderer NAME  rendering method, one of the list below (default: the\n"
            "                   scene's, else the first that draws every object: raycast\n"
            "                   for volumes, raytrace with geometry, irregular for grids);\n"
            "                   naming another renderer than the scene's drops the\n"
            "                   scene's renderer options\n"
            "  --step S         sample step in units of the smallest voxel spacing\n"
            "                   (default 0.5 or the scene's)\n"
            "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]\n"
            "                   read INPUT as raw voxels (see 'volvis info --help')\n"
            "  --series N       DICOM: series N of INPUT as 'volvis info' lists them (a\n"
            "                   folder with one series needs none)\n"
            "  --channel C      channel C, from 0 (default 0): TIFF, DICOM, NIfTI dim[5],\n"
            "                   NRRD (an axis of kind RGB-color, vector, list, ...),\n"
            "                   VTK legacy (a component of SCALARS)\n"
            "  --channels C,C,...  these channels of the file (up to %d) as one\n"
            "                   object, each in its own colour, drawn by raycast (in\n"
            "                   one pass) or raytrace; docs/rendering.md, \"Channels\"\n"
            "  --colors COLOR,...  the channels' colours: red, green, blue, magenta,\n"
            "                   cyan, yellow, white, gray, orange, sky or #rrggbb\n"
            "                   (default magenta, green, cyan, yellow, then Okabe-Ito);\n"
            "                   without --channels, every channel of the file in order\n"
            "                   (so too --contrast and --blend)\n"
            "  --contrast LO:HI,...  the channels' contrast limits in data values:\n"
            "                   transparent up to LO, opacity 0.5 from HI (default: LO\n"
            "                   the background plus 3 deviations of its noise, from the\n"
            "                   quartiles; HI the 99.99 %% quantile)\n"
            "  --blend RULE     how the channels combine: composite (default; opacities\n"
            "                   as independent absorbers, colours mixed by opacity),\n"
            "                   additive (each channel composited alone, colours added)\n"
            "                   or maximum (a MIP per channel, coloured, added)\n"
            "  --label-channels C,...  these of the --channels hold labels (segment ids):\n"
            "                   each label in its own colour, label 0 transparent\n",
            VV_IMAGE_MAX_SIDE, VV_MAX_CHANNELS);
    fprintf(out, "  --gamma G        8-bit conversion v^(1/G) (default 1: values unchanged)\n"
                 "  --quality Q      0 draft, 1 medium, 2 final (default 2 or the scene's; per\n"
                 "                   renderer below)\n"
                 "  --set KEY=VALUE  renderer-specific option (repeatable), listed with each\n"
                 "                   renderer below; adds to or overrides the scene's options;\n"
                 "                   see docs/rendering.md\n"
                 "  --alpha          write RGBA (coverage in the alpha channel); default RGB\n"
                 "  --ortho          parallel projection (orthographic), the view framed on\n"
                 "                   the scene; needed by the fourier renderer\n"
                 "  --labels         the volumes are label volumes (volvis filter --components):\n"
                 "                   each label in its own colour, label 0 transparent\n"
                 "  --field NAME     a grid's field to show (default: its first scalar field;\n"
                 "                   vectors by magnitude); for a scene, every grid object's\n"
                 "  --time T         time step T, from 0: a grid's field NAME<T> (blow.vtk:\n"
                 "                   thickness3), or a volume file's (OME-TIFF, ImageJ\n"
                 "                   hyperstacks, NIfTI dim[4], NRRD's axis of kind time,\n"
                 "                   a DICOM time series)\n"
                 "  --memory-limit SIZE  the process's one cache for reading volumes out\n"
                 "                   of core, SIZE bytes (K, M, G suffixes; default 1G):\n"
                 "                   raw (--raw), uncompressed NRRD or .vvb brick by brick\n"
                 "                   ('volvis convert IN OUT.vvb'; a .vvb INPUT is always\n"
                 "                   rendered so); an OME-Zarr store, BigDataViewer .h5 or\n"
                 "                   .xml, Imaris .ims or .vvb with levels from its pyramid\n"
                 "                   by level of detail (--lod); a scene: each of its\n"
                 "                   volume files so, all in the one cache of SIZE (others\n"
                 "                   read whole), side by side (composite and iso objects\n"
                 "                   apart), by raycast. Without it, a file that can be\n"
                 "                   read so and would take more than the memory budget\n"
                 "                   (--max-memory) to render in memory (its voxels, the\n"
                 "                   renderers' copy and gradients) is read out of core\n"
                 "                   anyway, by raycast or raytrace, in a quarter of the\n"
                 "                   budget (at most 1G), said in one line\n"
                 "  --lod PIXELS     a pyramid out of core: each 64^3 node of the volume at\n"
                 "                   the coarsest level whose voxel covers at most PIXELS\n"
                 "                   pixels (default 1; larger is coarser and faster);\n"
                 "                   implies --memory-limit 1G when not given\n"
                 "  --level L        level L of a multiresolution file (OME-Zarr,\n"
                 "                   BigDataViewer, Imaris, .vvb; from 0, the finest;\n"
                 "                   default 0):\n"
                 "                   in memory, or out of core\n"
                 "                   (--memory-limit) every node at level L\n"
                 "  --progressive CHUNKS  a pyramid out of core: write the refinement too, one\n"
                 "                   PNG a step (OUT's name with _pNNNN before .png): step 0\n"
                 "                   from the coarsest level, each next step reading at most\n"
                 "                   CHUNKS more chunks, nearest first, until every node is at\n"
                 "                   its level; OUT is the converged image\n"
                 "  --compositing binary-swap|radix-k[:K]\n"
                 "                   under mpirun -np N: how the ranks' partial images are\n"
                 "                   composited (default binary-swap; radix-k: groups of at\n"
                 "                   most K ranks a round, default 4); docs/parallel.md\n"
                 "  -q, --quiet      no progress bar and no 'wrote' line\n");
}

/* "volume, grid" etc.: the object kinds in @p draws, into buf. */
const char *
cli_renderer_kinds(unsigned draws, char *buf, size_t cap) {
    buf[0] = '\0';
    for (int t = 0; t <= VV_OBJECT_GRID; t++) {
        if (!(draws & VV_DRAWS(t)))
            continue;
        size_t n = strlen(buf);
        snprintf(buf + n, cap - n, "%s%s", n ? ", " : "", vv_object_type_name((vv_object_type)t));
    }
    return buf;
}

/* "composite, mip, ...": the modes in @p modes, into buf. */
const char *
cli_renderer_modes(unsigned modes, char *buf, size_t cap) {
    buf[0] = '\0';
    for (size_t m = 0; m < sizeof mode_names / sizeof mode_names[0]; m++) {
        if (!(modes & VV_MODE_BIT(mode_values[m])))
            continue;
        size_t n = strlen(buf);
        snprintf(buf + n, cap - n, "%s%s", n ? ", " : "", mode_names[m]);
    }
    return buf;
}

void
cli_render_print_renderers(FILE *out) {
    for (int i = 0; i < vv_renderer_count(); i++) {
        const vv_renderer_info *in = vv_renderer_info_at(i);
        char kinds[256], modes[128], line[1024], what[256];
        fprintf(out, "  %-16s %s\n", in->name, in->description);
        snprintf(line, sizeof line, "draws %s (%s)%s",
                 cli_renderer_kinds(in->draws, kinds, sizeof kinds),
                 cli_renderer_modes(in->modes, modes, sizeof modes),
                 (in->caps & VV_RENDERER_REGION) ? "; renders regions (--memory-limit, mpirun)"
                                                 : "");
        print_wrapped(out, "", line, 19, 79);
        print_wrapped(out, "quality: ", in->quality, 19, 79);
        for (int k = 0; k < in->n_options; k++) {
            const vv_option_spec *o = &in->options[k];
            snprintf(line, sizeof line, "%s=%s (default %s): %s", o->key,
                     vv_option_describe(o, what, sizeof what), o->def[0] ? o->def : "none", o->doc);
            print_wrapped(out, "--set ", line, 19, 79);
        }
    }
}

void
cli_render_note_left_out(const vv_renderer *ren, const vv_world *w) {
    const vv_renderer_info *in = vv_renderer_get_info(ren);
    if (vv_renderer_check_world(in, w) != VV_OK) {
        vv_error_clear(); /* the render says why */
        return;
    }
    char names[1024] = "";
    int n = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o || !o->visible || (in->draws & VV_DRAWS(o->type)))
            continue;
        if ((o->type == VV_OBJECT_VOLUME && !o->volume) || (o->type == VV_OBJECT_GRID && !o->grid))
            continue;
        size_t len = strlen(names);
        if (n < 4)
            snprintf(names + len, sizeof names - len, "%s'%s' (%s)", n ? ", " : "", o->name,
                     vv_object_type_name(o->type));
        n++;
    }
    if (!n)
        return;
    fprintf(stderr,
            "volvis: note: %s leaves out %s%s: it does not draw those kinds ('volvis "
            "renderers' lists what each renderer draws)\n",
            in->name, names, n > 4 ? " and more" : "");
}

vv_status
cli_time_source_open(const cli_render_args *r, const vv_object *o, cli_time_source *src) {
    return cli_time_source_open_file(r->input, r, o, src);
}

vv_status
cli_time_source_open_file(const char *path, const cli_render_args *r, const vv_object *o,
                          cli_time_source *src) {
    memset(src, 0, sizeof *src);
    src->n = o->n_channels > 0 ? o->n_channels : 1;
    vv_status s = VV_OK;
    for (int c = 0; c < src->n && s == VV_OK; c++) {
        vv_load_options opt;
        vv_load_options_init(&opt);
        opt.series = r ? r->series : 0;
        opt.channel = o->n_channels > 0 ? o->channels[c].index : r ? r->channel : -1;
        if (r && r->has_raw) {
            opt.format = VV_FORMAT_RAW;
            opt.has_raw = 1;
            opt.raw = r->raw;
        }
        vv_error_clear();
        s = vv_time_series_open(&src->ts[c], path, &opt, 0);
    }
    if (s != VV_OK)
        cli_time_source_close(src);
    return s;
}

vv_status
cli_time_source_apply(cli_time_source *src, vv_object *o, int t, int next) {
    vv_volume *v[VV_MAX_CHANNELS] = {NULL};
    vv_status s = VV_OK;
    for (int c = 0; c < src->n && s == VV_OK; c++)
        s = vv_time_series_get(src->ts[c], t, &v[c]);
    for (int c = 0; c < src->n && s == VV_OK && next >= 0; c++)
        vv_time_series_prefetch(src->ts[c], next);
    if (s == VV_OK && (s = vv_object_replace_volumes(o, src->n, v)) == VV_OK)
        o->time = t;
    for (int c = 0; c < src->n; c++)
        vv_volume_free(v[c]); /* the object holds its own references */
    return s;
}

void
cli_time_source_close(cli_time_source *src) {
    for (int c = 0; c < VV_MAX_CHANNELS; c++)
        vv_time_series_free(src->ts[c]);
    memset(src, 0, sizeof *src);
}

void
cli_time_steps_gradients(const cli_args *a, vv_renderer *ren) {
    for (int i = 0; i < a->n_seen; i++)
        if (!strcmp(a->specs[a->seen[i].opt].name, "set") && a->seen[i].value &&
            !strncmp(a->seen[i].value, "gradient_budget_mb=", 19))
            return;
    /* renderers without the option refuse it: nothing to change there */
    if (vv_renderer_set_option(ren, "gradient_budget_mb", "0") != VV_OK)
        vv_error_clear();
}
