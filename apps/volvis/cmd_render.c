/*
 * volvis render INPUT -o OUT.png: renders a scene file or a volume file with
 * any registered renderer and writes an 8-bit PNG (atomically, so a failure
 * never leaves a partial or changed output file). The options and the World
 * they build are shared with `volvis animate` (render_setup.c).
 */
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_opt_spec render_opts[] = {CLI_RENDER_OPT_SPECS,
                                           {"time-range", 0, "A:B[:STEP]"},
                                           {"repeat", 0, "N"},
                                           {"orbit", 0, "DEG"},
                                           {"stats", 0, NULL}};
#define N_RENDER_OPTS ((int)(sizeof render_opts / sizeof render_opts[0]))

void
cli_render_usage(FILE *out) {
    fprintf(out, "usage: volvis render [OPTIONS] INPUT -o OUT.png\n"
                 "\n"
                 "Renders INPUT to an 8-bit PNG. INPUT is a scene file (JSON: starts with '{'\n"
                 "or ends in .json), a volume file (SLC, NRRD, NIfTI, MetaImage, VTK, raw)\n"
                 "or an irregular grid (VTK UNSTRUCTURED_GRID, .vtu, OpenDX, PLOT3D, NetCDF;\n"
                 "rendered cell by cell by the irregular renderer),\n"
                 "which is shown centred, seen from the front, with a headlight and a\n"
                 "transfer function from its histogram. With a scene file the options below\n"
                 "override the scene's values only where given; a scene's \"render\" section\n"
                 "(renderer, quality, options) gives the defaults of --renderer, --quality\n"
                 "and --set. Prints the output path, the image size and the render time.\n"
                 "\n"
                 "Options:\n"
                 "  -o, --output OUT.png  output PNG (required); written atomically\n");
    cli_render_print_options(out);
    fprintf(out, "  --time-range A:B[:STEP]  a volume file's time steps A to B (inclusive,\n"
                 "                   every STEP-th, default 1), one PNG each: OUT's name with\n"
                 "                   _tNNNN before .png (head.png: head_t0000.png, ...); the\n"
                 "                   transfer function and view of step A for all; each step\n"
                 "                   read while the one before is drawn (out of core, with\n"
                 "                   --memory-limit: the chunks the step before read)\n"
                 "  --repeat N       render the same frame N times (1 .. 100000) with one\n"
                 "                   renderer, whose caches carry over (the gpu renderer's\n"
                 "                   bricks on the device); writes the last frame, and the\n"
                 "                   `wrote` line gives the last frame's time\n"
                 "  --orbit DEG      with --repeat: each frame after the first turns the\n"
                 "                   camera DEG degrees further about the view's up axis\n"
                 "                   (as --azimuth), an orbit of the same renderer, its\n"
                 "                   caches warm (-360 .. 360; default 0)\n"
                 "  --stats          print one line a frame to stdout, key=value pairs:\n"
                 "                   frame= ms= (wall clock) device_ms= upload_bytes=\n"
                 "                   (volume data sent to a device) cache_hits= cache_misses=\n"
                 "                   (bricks found on, or uploaded to, the device) samples=\n"
                 "                   (only renderers that count them report non-zero)\n"
                 "  -h, --help       show this help\n"
                 "\n"
                 "Renderers:\n");
    cli_render_print_renderers(out);
    fprintf(out,
            "\n"
            "Examples:\n"
            "  volvis render ../shared/data/volumes/ct_head.nrrd --tf 100:1500 -o head.png\n"
            "  volvis render ../shared/data/volumes/neghip.slc --mode mip --azimuth 30 -o mip.png\n"
            "  volvis render ../shared/data/volumes/ct_head.nrrd --iso 400 --renderer raster \\\n"
            "      --set shading=gouraud -o bone.png\n"
            "  volvis render ../shared/data/grids/fire_ug.vtu --field t -o fire.png\n"
            "  volvis render beating_heart.nii.gz --time-range 0:19 -o heart.png\n"
            "  volvis render scene.json --size 1024x1024 --azimuth 45 -o scene.png\n"
            "  volvis render examples/head_mirror.json --renderer raytrace -o mirror.png\n"
            "  volvis render head.nrrd --renderer fourier --ortho --set vvc=head.vvc \\\n"
            "      --mode xray --tf -1024:300 -o fourier.png\n");
}

/* --time-range A:B[:STEP] into @p range; 0 or a usage error. */
static int
parse_time_range(const cli_args *a, const char *s, int range[3]) {
    char *e = NULL;
    long v[3] = {0, 0, 1};
    const char *p = s;
    int n = 0;
    for (; n < 3; n++) {
        v[n] = strtol(p, &e, 10);
        if (e == p || v[n] < 0 || v[n] > 1000000)
            break;
        if (*e != ':')
            break;
        p = e + 1;
    }
    if (n < 1 || n > 2 || *e || v[2] < 1 || v[1] < v[0])
        return cli_usage_error(a,
                               "--time-range: '%s' is not A:B or A:B:STEP (0 <= A <= B, "
                               "STEP >= 1)",
                               s);
    for (int i = 0; i < 3; i++)
        range[i] = (int)v[i];
    return 0;
}

/*
 * --time-range: the steps of the World's volume object read one after the
 * other through a time series per channel (the next read ahead while this
 * one is drawn), each drawn with the first step's World and written to its
 * own PNG.
 */
static int
render_time_range(const cli_render_args *r, const int range[3], vv_world *w, vv_renderer *ren,
                  const vv_render_options *ro, vv_image *img) {
    vv_object *o = NULL;
    for (int i = 0; i < w->n_objects && !o; i++)
        if (w->objects[i]->type == VV_OBJECT_VOLUME)
            o = w->objects[i];
    if (!o) {
        cli_error("%s: --time-range needs a volume file", r->input);
        return CLI_EXIT_USAGE;
    }
    vv_time_steps *src = NULL;
    vv_status s = cli_time_steps_open(r, NULL, o, &src);
    int rc = s == VV_OK ? 0 : cli_fail(s, r->input);
    int steps = rc ? 0 : vv_time_steps_count(src);
    if (!rc && range[1] >= steps) {
        cli_error("%s: --time-range %d:%d: the file has %d time step%s (from 0)", r->input,
                  range[0], range[1], steps, steps == 1 ? "" : "s");
        rc = CLI_EXIT_FAIL;
    }
    double t_all = cli_now();
    int frames = 0;
    for (int t = range[0]; !rc && t <= range[1]; t += range[2]) {
        vv_error_clear();
        s = vv_time_steps_show(src, o, t, t + range[2] <= range[1] ? t + range[2] : -1);
        double t0 = cli_now();
        if (s == VV_OK)
            s = vv_renderer_render(ren, w, &w->view, ro, img);
        if (s == VV_OK && cli_interrupted())
            s = vv_error_set(VV_ERR_CANCELLED, "interrupted");
        char path[4096];
        cli_numbered_path(r->output, 't', t, path, sizeof path);
        if (s == VV_OK && (s = vv_image_write_png(img, path, r->gamma, r->alpha)) != VV_OK) {
            rc = cli_fail(s, path);
            break;
        }
        if (s != VV_OK) {
            rc = s == VV_ERR_CANCELLED && cli_interrupted() ? CLI_EXIT_CANCEL
                                                            : cli_fail(s, r->input);
            break;
        }
        frames++;
        if (!r->quiet)
            printf("wrote %s (%dx%d, time step %d, %.2f s)\n", path, img->width, img->height, t,
                   cli_now() - t0);
    }
    if (!rc && !r->quiet) {
        double secs = cli_now() - t_all;
        printf("%d time steps in %.2f s (%.2f steps a second)\n", frames, secs,
               secs > 0 ? frames / secs : 0.0);
    }
    vv_time_steps_free(src);
    return rc;
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
    cli_render_args r;
    memset(&r, 0, sizeof r);
    if ((rc = cli_render_parse(&a, &r)))
        return rc;
    int range[3] = {0, 0, 1};
    const char *tr = cli_get(&a, "time-range");
    int repeat = 1;
    const char *rs = cli_get(&a, "repeat");
    if (rs && (rc = cli_parse_int(&a, "repeat", rs, 1, 100000, &repeat)))
        return rc;
    double orbit = 0;
    const char *os = cli_get(&a, "orbit");
    if (os && (rc = cli_parse_double(&a, "orbit", os, -360, 360, &orbit)))
        return rc;
    if (os && !rs)
        return cli_usage_error(&a, "--orbit: with --repeat");
    const int show_stats = cli_count(&a, "stats") > 0;
    if ((rs || show_stats) && (tr || r.progressive > 0))
        return cli_usage_error(&a, "--repeat and --stats: one frame, not with --time-range or "
                                   "--progressive");
    if ((rs || show_stats) && vv_parallel_launched())
        return cli_usage_error(&a, "--repeat and --stats: one process, not under mpirun");
    if (tr) {
        if ((rc = parse_time_range(&a, tr, range)))
            return rc;
        if (r.has_time)
            return cli_usage_error(&a, "--time-range: not with --time");
        if (vv_parallel_launched())
            return cli_usage_error(&a, "--time-range: one process");
        r.has_time = 1; /* the World from step A */
        r.time = range[0];
        r.time_range = 1;
    }
    if (vv_parallel_launched()) {
        int rank = 0, size = 1;
        vv_parallel_init(NULL, NULL, &rank, &size);
        if (size > 1 && (r.memory_limit > 0 || r.has_lod || r.progressive > 0)) {
            cli_error("render: --memory-limit (out of core) runs on one rank, not under mpirun "
                      "-np %d",
                      size);
            return CLI_EXIT_USAGE;
        }
        /* each rank reads its own box of a file read by boxes */
        return cli_render_parallel(&a, &r);
    }
    vv_world *w = NULL;
    vv_world_open_info opened;
    if ((rc = cli_render_world(&r, &w, &opened)))
        return rc;
    cli_render_turn(&r, w);

    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    vv_status s;
    int quality = 2;
    if ((rc = cli_render_renderer(&a, &r, w, &ren, &quality)))
        goto done;
    if (!r.quiet)
        cli_render_note_left_out(ren, w);
    if ((s = vv_image_new(&img, w->view.width, w->view.height)) != VV_OK) {
        rc = cli_fail(s, NULL);
        goto done;
    }
    if (r.threads > 0)
        vv_threads_set(r.threads);

    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = r.threads;
    ro.quality = quality;
    cli_progress pr;
    cli_progress_begin(&pr, r.quiet);
    ro.progress = pr.p;
    vv_render_stats stats = {0};
    ro.stats = &stats;
    if (tr) {
        cli_time_steps_gradients(&a, ren);
        rc = render_time_range(&r, range, w, ren, &ro, img);
        cli_progress_end(&pr);
        goto done;
    }
    /* objects out of core: by level of detail (--lod, --level), and with
     * --progressive every step from what is resident, each next one reading
     * at most N chunks more, until nothing is pending */
    vv_lod lod;
    cli_render_lod(&r, &lod);
    ro.lod = &lod;
    lod.progressive = r.progressive > 0 && cli_world_out_of_core(w);
    int steps = 0;
    double t0 = cli_now(), seconds = 0;
    lod.load_budget = 0; /* a progressive frame's first step: from what is resident */
    /* --repeat: the same frame again, the renderer's caches warm */
    for (int frame = 1; frame <= repeat; frame++) {
        if (frame > 1 && orbit != 0)
            vv_anim_view_turn(&w->view, vv_deg_to_rad(orbit), 0, 1);
        stats = (vv_render_stats){0};
        t0 = cli_now();
        vv_error_clear();
        s = vv_renderer_render(ren, w, &w->view, &ro, img);
        seconds = cli_now() - t0;
        if (s != VV_OK || (frame < repeat && cli_interrupted()))
            break;
        if (show_stats) {
            printf("frame=%d ms=%.3f device_ms=%.3f upload_bytes=%llu cache_hits=%u "
                   "cache_misses=%u samples=%llu\n",
                   frame, 1000 * seconds, stats.device_ms, (unsigned long long)stats.upload_bytes,
                   (unsigned)stats.cache_hits, (unsigned)stats.cache_misses,
                   (unsigned long long)stats.samples);
            fflush(stdout);
        }
    }
    for (; s == VV_OK && lod.progressive;) {
        lod.load_budget = steps == 0 ? 0 : r.progressive;
        vv_error_clear();
        if (steps > 0)
            s = vv_renderer_render(ren, w, &w->view, &ro, img);
        if (s != VV_OK)
            break;
        char step[4200];
        cli_numbered_path(r.output, 'p', steps, step, sizeof step);
        if ((s = vv_image_write_png(img, step, r.gamma, r.alpha)) != VV_OK) {
            cli_progress_end(&pr);
            rc = cli_fail(s, step);
            goto done;
        }
        steps++;
        if (lod.pending == 0)
            break;
    }
    if (lod.progressive)
        seconds = cli_now() - t0;
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
    if (steps > 0 && !r.quiet)
        printf("wrote %d progressive steps (_p0000 .. _p%04d)\n", steps, steps - 1);
    if (stats.gradients_at_samples && !r.quiet)
        fprintf(stderr,
                "volvis: note: %d volume%s shaded with gradients computed at the samples "
                "(slower): cached gradients (2 bytes a voxel) fit neither the gradient budget "
                "(--set gradient_budget_mb) nor half the memory left\n",
                (int)stats.gradients_at_samples, stats.gradients_at_samples == 1 ? "" : "s");
    cli_render_report(&r, w, img, seconds, &lod, opened.input == VV_INPUT_SCENE);
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    return rc;
}
