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

static const char *const mode_names[] = {"composite", "mip", "minip",
                                         "xray",      "iso", "attenuated-mip"};
static const vv_render_mode mode_values[] = {VV_MODE_COMPOSITE, VV_MODE_MIP,
                                             VV_MODE_MINIP,     VV_MODE_XRAY,
                                             VV_MODE_ISO,       VV_MODE_ATTENUATED_MIP};

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
    return cli_usage_error(
        a, "--mode: unknown mode '%s' (composite, mip, minip, xray, iso, attenuated-mip)", text);
}

static int
renderer_known(const char *name) {
    return vv_renderer_info_find(name) != NULL;
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
    if ((s = cli_get(a, "attenuation"))) {
        if ((rc = cli_parse_double(a, "attenuation", s, 0, 1e4, &r->attenuation)))
            return rc;
        r->has_attenuation = 1;
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

/* @p r's options of the door (vv_world_open). */
static void
world_options(const cli_render_args *r, vv_world_open_options *o, cli_progress *pr) {
    vv_world_open_options_init(o);
    o->load.series = r->series;
    o->load.channel = r->channel;
    o->load.time = r->has_time ? r->time : r->time_range ? 0 : -1;
    if (r->has_raw) {
        o->load.format = VV_FORMAT_RAW;
        o->load.has_raw = 1;
        o->load.raw = r->raw;
    }
    o->level = r->has_level ? r->level : -1;
    o->levels = r->has_lod || r->progressive > 0;
    o->memory = r->memory_limit > 0 || r->has_lod || r->progressive > 0 ? VV_WORLD_OUT_OF_CORE
                                                                        : VV_WORLD_MEMORY_AUTO;
    o->memory_limit = r->memory_limit;
    /* under mpirun each rank reads its own box of a file read by boxes */
    o->distributed = vv_parallel_launched();
    o->renderer = r->renderer;
    o->n_channels = r->n_channels;
    memcpy(o->channels, r->channels, sizeof o->channels);
    /* a file of several channels shows them all in their colours unless one
     * channel, a mode, an isovalue, a transfer function or labels is asked */
    o->all_channels = r->all_channels ||
                      (r->channel < 0 && !r->has_mode && !r->has_iso && !r->has_tf && !r->labels);
    o->n_colors = r->n_colors;
    memcpy(o->colors, r->colors, sizeof o->colors);
    o->n_contrast = r->n_contrast;
    memcpy(o->contrast, r->contrast, sizeof o->contrast);
    o->has_blend = r->has_blend;
    o->blend = r->blend;
    memcpy(o->label_channel, r->label_channel, sizeof o->label_channel);
    o->has_mode = r->has_mode;
    if (r->has_mode)
        o->view.mode = r->mode;
    if (r->has_tf) {
        o->view.has_tf_range = 1;
        o->view.tf_lo = r->tf_lo;
        o->view.tf_hi = r->tf_hi;
    }
    if (r->has_iso) {
        o->view.has_isovalue = 1;
        o->view.isovalue = r->iso;
    }
    o->has_size = r->has_size;
    if (r->has_size) {
        o->view.width = r->width;
        o->view.height = r->height;
    }
    o->field = r->field;
    o->step = r->has_step ? r->step : 0;
    o->has_attenuation = r->has_attenuation;
    o->attenuation = r->attenuation;
    o->labels = r->labels;
    o->progress = &pr->p; /* a scene's geometry objects are voxelized while loading */
}

int
cli_render_world(const cli_render_args *r, vv_world **out, vv_world_open_info *info) {
    vv_world_open_info scratch;
    if (!info)
        info = &scratch;
    *out = NULL;
    vv_world_open_options o;
    cli_progress pr;
    cli_progress_begin(&pr, r->quiet);
    world_options(r, &o, &pr);
    vv_error_clear();
    vv_status s = vv_world_open(out, r->input, &o, info);
    cli_progress_end(&pr);
    if (s != VV_OK) {
        int rc = cli_fail(s, r->input);
        return info->options_misfit && rc == CLI_EXIT_FAIL ? CLI_EXIT_USAGE : rc;
    }
    const char *refused = NULL;
    if (r->time_range && info->input != VV_INPUT_VOLUME)
        refused = info->input == VV_INPUT_SCENE ? "--time-range is for a volume file's time "
                                                  "steps, not a scene"
                                                : "--time-range is for a volume file's time "
                                                  "steps, not a grid";
    if (refused) {
        vv_world_free(*out);
        *out = NULL;
        cli_error("%s: %s", r->input, refused);
        return CLI_EXIT_FAIL;
    }
    if (info->warning[0])
        fprintf(stderr, "volvis: warning: %s: %s\n", r->input, info->warning);
    if (info->switched && !r->quiet)
        fprintf(stderr,
                "volvis: note: %s: rendering it in memory would take %llu MiB, more than the "
                "memory budget of %llu MiB (--max-memory): read out of core (--memory-limit "
                "%lluM)\n",
                r->input, (unsigned long long)(info->need_bytes >> 20),
                (unsigned long long)(info->budget_bytes >> 20),
                (unsigned long long)(info->cache_bytes >> 20));
    if (r->file_channels)
        *r->file_channels = info->n_channels;
    return 0;
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
            "                   along the ray), iso (shaded isosurface) or attenuated-mip\n"
            "                   (napari's attenuated MIP: far values fade behind bright\n"
            "                   ones; raycast and gpu); for a scene,\n"
            "                   applies to every volume object (geometric objects have none)\n"
            "  --iso V          isovalue for --mode iso (alone it implies --mode iso)\n"
            "  --attenuation A  attenuation of --mode attenuated-mip, >= 0 (default 0.05,\n"
            "                   napari's; 0 gives mip)\n"
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
            "  --channel C      channel C alone, from 0: TIFF, DICOM, NIfTI dim[5],\n"
            "                   NRRD (an axis of kind RGB-color, vector, list, ...),\n"
            "                   VTK legacy (a component of SCALARS), OME-Zarr; without\n"
            "                   it (and without --mode, --iso, --tf, --labels) a file of\n"
            "                   several channels draws them all (up to %d), its active\n"
            "                   ones visible, in their colours\n"
            "  --channels C,C,...  these channels of the file as one object, each in\n"
            "                   its own colour, drawn by raycast (in one pass), raytrace\n"
            "                   or gpu (up to 4); out of core (--memory-limit) a pyramid\n"
            "                   reads every channel of a node at once; docs/rendering.md,\n"
            "                   \"Channels\"\n"
            "  --colors COLOR,...  the channels' colours: red, green, blue, magenta,\n"
            "                   cyan, yellow, white, gray, orange, sky or #rrggbb\n"
            "                   (default magenta, green, cyan, yellow, then Okabe-Ito);\n"
            "                   without --channels, every channel of the file in order\n"
            "                   (so too --contrast and --blend)\n"
            "  --contrast LO:HI,...  the channels' contrast limits in data values:\n"
            "                   transparent up to LO, opacity 0.5 from HI (default: the\n"
            "                   file's omero window start and end, else LO the\n"
            "                   background plus 3 deviations of its noise, from the\n"
            "                   quartiles, HI the 99.99 %% quantile, of a pyramid's\n"
            "                   coarsest level: the same in memory and out of core)\n"
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
                 "                   rendered so); an OME-Zarr store, N5, Neuroglancer\n"
                 "                   precomputed, BigDataViewer .h5 or .xml, Imaris .ims,\n"
                 "                   a TIFF stack (tile by tile; an OME-TIFF's SubIFD\n"
                 "                   levels) or .vvb with levels from its pyramid\n"
                 "                   by level of detail (--lod), its channels together; a\n"
                 "                   scene: each of its volume files so, all in the one\n"
                 "                   cache of SIZE (others read whole), side by side\n"
                 "                   (composite and iso objects apart), by raycast.\n"
                 "                   Without it, a file that can be\n"
                 "                   read so and would take more than the memory budget\n"
                 "                   (--max-memory) to render in memory (its voxels, the\n"
                 "                   renderers' copy and gradients) is read out of core\n"
                 "                   anyway, by raycast or raytrace, in a quarter of the\n"
                 "                   budget (at most 1G), said in one line\n"
                 "  --lod PIXELS     a pyramid out of core: each 64^3 node of the volume at\n"
                 "                   the coarsest level whose voxel covers at most PIXELS\n"
                 "                   pixels (default 1; larger is coarser and faster);\n"
                 "                   implies --memory-limit 1G when not given\n"
                 "  --level L        level L of a multiresolution file (OME-Zarr, N5,\n"
                 "                   precomputed, BigDataViewer, Imaris, OME-TIFF with\n"
                 "                   SubIFDs, .vvb; from 0, the finest;\n"
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
cli_time_steps_open(const cli_render_args *r, const char *path, const vv_object *o,
                    vv_time_steps **out) {
    vv_load_options load;
    vv_load_options_init(&load);
    if (r && !path) {
        load.series = r->series;
        load.channel = r->channel;
        if (r->has_raw) {
            load.format = VV_FORMAT_RAW;
            load.has_raw = 1;
            load.raw = r->raw;
        }
    }
    return vv_time_steps_open(out, path ? path : r->input, &load, o);
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
