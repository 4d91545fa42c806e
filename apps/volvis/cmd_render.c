/*
 * volvis render INPUT -o OUT.png: renders a scene file or a volume file with
 * any registered renderer and writes an 8-bit PNG (atomically, so a failure
 * never leaves a partial or changed output file). The options and the World
 * they build are shared with `volvis animate` (render_setup.c).
 */
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_opt_spec render_opts[] = {CLI_RENDER_OPT_SPECS};
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
    fprintf(out, "  -h, --help       show this help\n"
                 "\n"
                 "Renderers:\n");
    cli_render_print_renderers(out);
    fprintf(out,
            "\n"
            "Examples:\n"
            "  volvis render ../shared/data/volumes/ct_head.nrrd --tf 100:1500 -o head.png\n"
            "  volvis render ../shared/data/volumes/neghip.slc --mode mip --azimuth 30 -o mip.png\n"
            "  volvis render ../shared/data/volumes/ct_head.nrrd --iso 400 --renderer surface \\\n"
            "      --set shading=gouraud -o bone.png\n"
            "  volvis render ../shared/data/grids/fire_ug.vtu --field t -o fire.png\n"
            "  volvis render scene.json --size 1024x1024 --azimuth 45 -o scene.png\n"
            "  volvis render examples/head_mirror.json --renderer raytrace -o mirror.png\n"
            "  volvis render head.nrrd --renderer fourier --ortho --set vvc=head.vvc \\\n"
            "      --mode xray --tf -1024:300 -o fourier.png\n");
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
    /* under mpirun a .vvb is read by bricks, each rank its own box */
    if (r.memory_limit > 0 || (cli_ends_with(r.input, ".vvb") && !vv_parallel_launched()))
        return cli_render_out_of_core(&a, &r);
    if (vv_parallel_launched())
        return cli_render_parallel(&a, &r);
    vv_world *w = NULL;
    if ((rc = cli_render_world(&r, &w)))
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