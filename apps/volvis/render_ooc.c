/*
 * `volvis render INPUT --memory-limit SIZE` (or a .vvb INPUT): a volume
 * larger than memory rendered brick by brick within the memory budget
 * (include/volvis/bricks.h) by any renderer with the region contract
 * (vv_renderer_render_bricks: raycast, raytrace). The World's defaults
 * (view framing, transfer function from the histogram) come from a coarse
 * proxy of the volume (vv_bricked_proxy), so the volume is never read
 * whole; the proxy stays the object's volume, through which a renderer
 * with global effects (raytrace's shadows) traces them.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

void
cli_proxy_opacity_unit(vv_world *w, const vv_volume *whole, const vv_volume *proxy) {
    /* the default transfer function's opacity is per smallest voxel spacing:
     * the volume's, not the proxy's */
    double ph = INFINITY, pp = INFINITY;
    for (int k = 0; k < 3; k++) {
        ph = whole->spacing[k] < ph ? whole->spacing[k] : ph;
        pp = proxy->spacing[k] < pp ? proxy->spacing[k] : pp;
    }
    for (int i = 0; i < w->n_objects; i++)
        if (fabs(w->objects[i]->tf.opacity_unit_distance - pp) <= 1e-12 * pp)
            w->objects[i]->tf.opacity_unit_distance = ph;
}

int
cli_render_out_of_core(cli_args *a, cli_render_args *r) {
    if (vv_parallel_launched()) {
        int rank = 0, size = 1;
        vv_parallel_init(NULL, NULL, &rank, &size);
        if (size > 1) {
            cli_error("render: --memory-limit (out of core) runs on one rank, not under mpirun "
                      "-np %d",
                      size);
            return CLI_EXIT_USAGE;
        }
    }
    if (cli_ends_with(r->input, ".json")) {
        cli_error("%s: out-of-core rendering (--memory-limit, .vvb) takes a volume file, not a "
                  "scene",
                  r->input);
        return CLI_EXIT_USAGE;
    }
    int rc = cli_check_readable_input(r->input);
    if (rc)
        return rc;
    vv_bricked *b = NULL;
    vv_world *w = NULL;
    vv_volume *proxy = NULL;
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    vv_error_clear();
    vv_status s = vv_bricked_open(&b, r->input, r->has_raw ? &r->raw : NULL, r->memory_limit);
    if (s != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    if ((s = vv_bricked_proxy(b, 128, &proxy)) != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    if ((rc = cli_render_world_volume(r, proxy, &w)))
        goto done;
    cli_proxy_opacity_unit(w, vv_bricked_header(b), proxy);
    cli_render_turn(r, w);
    int quality = 2;
    if ((rc = cli_render_renderer(a, r, w, &ren, &quality)))
        goto done;
    if ((s = vv_image_new(&img, w->view.width, w->view.height)) != VV_OK) {
        rc = cli_fail(s, NULL);
        goto done;
    }
    if (r->threads > 0)
        vv_threads_set(r->threads);
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = r->threads;
    ro.quality = quality;
    double t0 = cli_now();
    vv_error_clear();
    vv_brick_source src;
    vv_bricked_source(b, &src);
    s = vv_renderer_render_bricks(ren, w, 0, &src, &w->view, &ro, img);
    double seconds = cli_now() - t0;
    if (s != VV_OK) {
        rc = cli_fail(s, NULL);
        goto done;
    }
    vv_error_clear();
    if ((s = vv_image_write_png(img, r->output, r->gamma, r->alpha)) != VV_OK) {
        rc = cli_fail(s, r->output);
        goto done;
    }
    if (!r->quiet) {
        vv_bricked_stats st;
        vv_bricked_stats_get(b, &st);
        int nb[3];
        vv_bricked_grid(b, nb);
        printf("wrote %s (%dx%d, %.2f s; out of core: %llu of %d bricks read, %llu skipped, "
               "%.1f MiB read, peak cache %.1f MiB)\n",
               r->output, img->width, img->height, seconds, (unsigned long long)st.loads,
               nb[0] * nb[1] * nb[2], (unsigned long long)st.skipped,
               (double)st.bytes_read / 1048576.0, (double)st.peak_bytes / 1048576.0);
    }
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_volume_free(proxy);
    vv_bricked_free(b);
    return rc;
}
