/*
 * volvis render INPUT -o OUT.png: renders a scene file or a volume file with
 * any registered renderer and writes an 8-bit PNG (atomically, so a failure
 * never leaves a partial or changed output file).
 */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"

static const cli_opt_spec render_opts[] = {
    {"output", 'o', "OUT.png"},
    {"mode", 0, "composite|mip|minip|xray|iso"},
    {"iso", 0, "V"},
    {"tf", 0, "LO:HI"},
    {"size", 0, "WxH"},
    {"azimuth", 0, "DEG"},
    {"elevation", 0, "DEG"},
    {"zoom", 0, "F"},
    {"threads", 0, "N"},
    {"renderer", 0, "NAME"},
    {"step", 0, "S"},
    {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"gamma", 0, "G"},
    {"quality", 0, "0|1|2"},
    {"set", 0, "KEY=VALUE"},
    {"alpha", 0, NULL},
    {"ortho", 0, NULL},
    {"quiet", 'q', NULL},
};
#define N_RENDER_OPTS ((int)(sizeof render_opts / sizeof render_opts[0]))

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

void
cli_render_usage(FILE *out) {
    fprintf(out,
            "usage: volvis render [OPTIONS] INPUT -o OUT.png\n"
            "\n"
            "Renders INPUT to an 8-bit PNG. INPUT is a scene file (JSON: starts with '{'\n"
            "or ends in .json) or a volume file (SLC, NRRD, NIfTI, MetaImage, VTK, raw),\n"
            "which is shown centred, seen from the front, with a headlight and a\n"
            "transfer function from its histogram. With a scene file the options below\n"
            "override the scene's values only where given; a scene's \"render\" section\n"
            "(renderer, quality, options) gives the defaults of --renderer, --quality\n"
            "and --set. Prints the output path, the image size and the render time.\n"
            "\n"
            "Options:\n"
            "  -o, --output OUT.png  output PNG (required); written atomically\n"
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
            "  --renderer NAME  rendering method (default raycast or the scene's), one of\n"
            "                   the list below; naming another renderer than the scene's\n"
            "                   drops the scene's renderer options\n"
            "  --step S         sample step in units of the smallest voxel spacing\n"
            "                   (default 0.5 or the scene's)\n"
            "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]\n"
            "                   read INPUT as raw voxels (see 'volvis info --help')\n"
            "  --gamma G        8-bit conversion v^(1/G) (default 1: values unchanged)\n"
            "  --quality Q      0 draft, 1 medium, 2 final (default 2 or the scene's; per\n"
            "                   renderer below)\n"
            "  --set KEY=VALUE  renderer-specific option (repeatable), listed with each\n"
            "                   renderer below; adds to or overrides the scene's options;\n"
            "                   see docs/rendering.md\n"
            "  --alpha          write RGBA (coverage in the alpha channel); default RGB\n"
            "  --ortho          parallel projection (orthographic), the view framed on\n"
            "                   the scene; needed by the fourier renderer\n"
            "  -q, --quiet      no progress bar and no 'wrote' line\n"
            "  -h, --help       show this help\n"
            "\n"
            "Renderers:\n",
            VV_IMAGE_MAX_SIDE);
    const vv_renderer_ops *const *reg = vv_renderer_registry();
    for (int i = 0; reg && reg[i]; i++) {
        fprintf(out, "  %-16s %s\n", reg[i]->name, reg[i]->description ? reg[i]->description : "");
        if (reg[i]->options)
            print_wrapped(out, "options: ", reg[i]->options, 19, 79);
    }
    fprintf(out,
            "\n"
            "Examples:\n"
            "  volvis render ../shared/data/volumes/ct_head.nrrd --tf 100:1500 -o head.png\n"
            "  volvis render ../shared/data/volumes/neghip.slc --mode mip --azimuth 30 -o mip.png\n"
            "  volvis render ../shared/data/volumes/ct_head.nrrd --iso 400 --renderer surface \\\n"
            "      --set shading=gouraud -o bone.png\n"
            "  volvis render scene.json --size 1024x1024 --azimuth 45 -o scene.png\n"
            "  volvis render examples/head_mirror.json --renderer raytrace -o mirror.png\n"
            "  volvis render head.nrrd --renderer fourier --ortho --set vvc=head.vvc \\\n"
            "      --mode xray --tf -1024:300 -o fourier.png\n");
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
    const vv_renderer_ops *const *reg = vv_renderer_registry();
    for (int i = 0; reg && reg[i]; i++)
        if (reg[i]->name && strcmp(reg[i]->name, name) == 0)
            return 1;
    return 0;
}

/* The registered renderers' names, comma-separated, in @p buf. */
static const char *
renderer_names(char *buf, size_t cap) {
    buf[0] = '\0';
    const vv_renderer_ops *const *reg = vv_renderer_registry();
    for (int i = 0; reg && reg[i]; i++) {
        size_t n = strlen(buf);
        snprintf(buf + n, cap - n, "%s%s", i ? ", " : "", reg[i]->name);
    }
    return buf[0] ? buf : "none";
}

/* A scene file: extension .json, or content that starts with '{' after whitespace. */
static int
is_scene_file(const char *path) {
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

typedef struct render_args {
    const char *input, *output, *renderer;
    int has_mode;
    vv_render_mode mode;
    int has_iso;
    double iso;
    int has_tf;
    double tf_lo, tf_hi;
    int has_size, width, height;
    double azimuth, elevation, zoom; /* degrees for the angles */
    int has_view;                    /* azimuth, elevation or zoom given */
    int threads;
    int has_step;
    double step;
    int has_raw;
    vv_raw_params raw;
    double gamma;
    int has_quality, quality;
    int alpha, quiet, ortho;
} render_args;

static int
parse_render_args(cli_args *a, render_args *r) {
    int rc;
    const char *s;
    memset(r, 0, sizeof *r);
    r->renderer = NULL; /* not given: the scene's, else raycast */
    r->zoom = 1;
    r->gamma = 1;
    r->quality = 2;
    if (a->n_pos == 0)
        return cli_usage_error(a, "missing INPUT");
    if (a->n_pos > 1)
        return cli_usage_error(a, "expected one INPUT, got %d arguments", a->n_pos);
    r->input = a->pos[0];
    r->output = cli_get(a, "output");
    if (!r->output || !*r->output)
        return cli_usage_error(a, "missing -o OUT.png");
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
                                   renderer_names(names, sizeof names));
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
    return 0;
}

/* Builds the World for a volume file. */
static int
world_for_volume(const render_args *r, vv_world **out) {
    vv_volume *v;
    int rc = cli_load_volume(r->input, r->has_raw ? &r->raw : NULL, &v);
    if (rc)
        return rc;
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
    o.azimuth = vv_deg_to_rad(r->azimuth);
    o.elevation = vv_deg_to_rad(r->elevation);
    o.zoom = r->zoom;
    vv_error_clear();
    vv_status s = vv_world_new_for_volume(out, v, &o);
    vv_volume_free(v); /* the World holds its own reference */
    if (s != VV_OK)
        return cli_fail(s, r->input);
    return 0;
}

/* Loads a scene file and applies the overrides given on the command line. */
static int
world_for_scene(const render_args *r, vv_world **out) {
    vv_error_clear();
    cli_progress pr; /* geometry objects are voxelized while loading */
    cli_progress_begin(&pr, r->quiet);
    vv_status s = vv_scene_load_progress(out, r->input, &pr.p);
    cli_progress_end(&pr);
    if (s != VV_OK)
        return cli_fail(s, r->input);
    vv_world *w = *out;
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *obj = w->objects[i];
        if (!obj || obj->type != VV_OBJECT_VOLUME)
            continue;
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
    if (r->azimuth != 0 || r->elevation != 0)
        vv_view_orbit(&w->view, vv_deg_to_rad(r->azimuth), vv_deg_to_rad(r->elevation));
    if (r->zoom != 1) {
        vv_vec3 d = vv_vec3_sub(w->view.eye, w->view.at);
        w->view.eye = vv_vec3_add(w->view.at, vv_vec3_scale(d, 1.0 / r->zoom));
        w->view.ortho_height /= r->zoom; /* an orthographic view zooms by its height */
    }
    return 0;
}

/*
 * The renderer, quality and options to render @p w with: the scene's render
 * section (w->render; never set for a volume file) gives the defaults, the
 * command line overrides. The scene's options belong to the scene's renderer
 * (raycast when it names none), so they are dropped when --renderer names
 * another. The --set options are applied after these (apply_options), so
 * they add to or override them.
 */
static int
resolve_render_settings(const render_args *r, const vv_world *w, vv_render_settings *out) {
    const vv_render_settings *sc = &w->render;
    const char *scene_renderer = sc->renderer[0] ? sc->renderer : "raycast";
    vv_render_settings_init(out);
    snprintf(out->renderer, sizeof out->renderer, "%s", r->renderer ? r->renderer : scene_renderer);
    if (!r->renderer && !renderer_known(out->renderer)) {
        char names[512];
        cli_error("%s: render.renderer: unknown renderer '%s' (available: %s)", r->input,
                  out->renderer, renderer_names(names, sizeof names));
        return CLI_EXIT_FAIL;
    }
    out->quality = r->has_quality ? r->quality : (sc->quality >= 0 ? sc->quality : 2);
    if (strcmp(out->renderer, scene_renderer) == 0)
        for (int i = 0; i < sc->n_options && i < VV_MAX_RENDER_OPTIONS; i++)
            if (vv_render_settings_set_option(out, sc->option_keys[i], sc->option_values[i]) !=
                VV_OK)
                return cli_fail(VV_ERR_INVALID, r->input);
    return 0;
}

/* Passes the scene's options in @p rs, then the --set options in order, to
 * @p ren. A scene option the renderer refuses is bad input naming the scene,
 * a --set option a usage error. */
static int
apply_options(const cli_args *a, const render_args *r, const vv_render_settings *rs,
              vv_renderer *ren) {
    for (int i = 0; i < rs->n_options; i++) {
        vv_error_clear();
        if (vv_renderer_set_option(ren, rs->option_keys[i], rs->option_values[i]) != VV_OK) {
            const char *m = vv_error_message();
            cli_error("%s: render.options.%s: %s", r->input, rs->option_keys[i],
                      m && *m ? m : "the renderer does not accept it");
            return CLI_EXIT_FAIL;
        }
    }
    for (int i = 0; i < a->n_seen; i++) {
        if (strcmp(a->specs[a->seen[i].opt].name, "set") != 0)
            continue;
        char key[256];
        const char *kv = a->seen[i].value;
        size_t klen = (size_t)(strchr(kv, '=') - kv);
        if (klen >= sizeof key)
            return cli_usage_error(a, "--set: key too long in '%s'", kv);
        memcpy(key, kv, klen);
        key[klen] = '\0';
        vv_error_clear();
        if (vv_renderer_set_option(ren, key, kv + klen + 1) != VV_OK) {
            const char *m = vv_error_message();
            return cli_usage_error(a, "--set %s: %s", kv,
                                   m && *m ? m : "the renderer does not accept it");
        }
    }
    return 0;
}

int
cli_render_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "render", render_opts, N_RENDER_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_render_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    render_args r;
    if ((rc = parse_render_args(&a, &r)))
        return rc;
    if ((rc = cli_check_readable(r.input)))
        return rc;

    vv_world *w = NULL;
    int scene = !r.has_raw && is_scene_file(r.input);
    rc = scene ? world_for_scene(&r, &w) : world_for_volume(&r, &w);
    if (rc) {
        vv_world_free(w);
        return rc;
    }
    if (r.ortho && w->view.projection != VV_PROJECTION_ORTHOGRAPHIC) {
        /* the same direction, parallel rays, the scene framed */
        w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
        vv_view_frame_box(&w->view, vv_world_bounds(w));
        if (r.zoom != 1)
            w->view.ortho_height /= r.zoom;
    }
    if (r.has_step)
        for (int i = 0; i < w->n_objects; i++)
            if (w->objects[i])
                w->objects[i]->step = r.step;

    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    vv_status s;
    vv_render_settings rs;
    if ((rc = resolve_render_settings(&r, w, &rs)))
        goto done;
    vv_error_clear();
    if ((s = vv_renderer_new(&ren, rs.renderer)) != VV_OK) {
        rc = cli_fail(s, NULL);
        goto done;
    }
    if ((rc = apply_options(&a, &r, &rs, ren)))
        goto done;
    if ((s = vv_image_new(&img, w->view.width, w->view.height)) != VV_OK) {
        rc = cli_fail(s, NULL);
        goto done;
    }
    if (r.threads > 0)
        vv_threads_set(r.threads);

    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = r.threads;
    ro.quality = rs.quality;
    cli_progress pr;
    cli_progress_begin(&pr, r.quiet);
    ro.progress = pr.p;
    double t0 = cli_now();
    vv_error_clear();
    s = vv_renderer_render(ren, w, &w->view, &ro, img);
    double seconds = cli_now() - t0;
    cli_progress_end(&pr);
    if (s == VV_OK && cli_interrupted())
        s = vv_error_set(VV_ERR_CANCELLED, "interrupted");
    if (s != VV_OK) {
        if (s == VV_ERR_CANCELLED && cli_interrupted()) {
            cli_error("render: interrupted; %s not written", r.output);
            rc = CLI_EXIT_CANCEL;
        } else {
            rc = cli_fail(s, NULL);
        }
        goto done;
    }
    vv_error_clear();
    if ((s = vv_image_write_png(img, r.output, r.gamma, r.alpha)) != VV_OK) {
        rc = cli_fail(s, r.output);
        goto done;
    }
    if (!r.quiet)
        printf("wrote %s (%dx%d, %.2f s)\n", r.output, img->width, img->height, seconds);
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    return rc;
}
