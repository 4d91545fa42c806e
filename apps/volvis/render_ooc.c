/*
 * `volvis render INPUT --memory-limit SIZE` (or a .vvb INPUT): a volume
 * larger than memory rendered brick by brick within the memory budget
 * (include/volvis/bricks.h) by any renderer with the region contract
 * (vv_renderer_render_bricks: raycast, raytrace). The World's defaults
 * (view framing, transfer function from the histogram) come from a coarse
 * proxy of the volume (vv_bricked_proxy), so the volume is never read
 * whole; the proxy stays the object's volume, through which a renderer
 * with global effects (raytrace's shadows) traces them.
 *
 * An OME-Zarr store is rendered from its pyramid (vv_pyramid) by level of
 * detail (vv_renderer_render_multires): --lod PIXELS, or --level L for
 * every node at one level; the proxy is its coarsest level, placed over the
 * box of level 0 (or of --level L), which the view frames.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

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

/* The World from the proxy (its transfer function's opacity per @p whole's
 * voxel), turned; the renderer, the image and the options of the frame.
 * 0 or an exit code. */
static int
frame_setup(cli_args *a, cli_render_args *r, vv_volume *proxy, const vv_volume *whole, vv_world **w,
            vv_renderer **ren, vv_image **img, vv_render_options *ro) {
    int rc = cli_render_world_volume(r, proxy, w);
    if (rc)
        return rc;
    cli_proxy_opacity_unit(*w, whole, proxy);
    cli_render_turn(r, *w);
    int quality = 2;
    if ((rc = cli_render_renderer(a, r, *w, ren, &quality)))
        return rc;
    vv_status s = vv_image_new(img, (*w)->view.width, (*w)->view.height);
    if (s != VV_OK)
        return cli_fail(s, NULL);
    if (r->threads > 0)
        vv_threads_set(r->threads);
    vv_render_options_init(ro);
    ro->threads = r->threads;
    ro->quality = quality;
    return 0;
}

static int
render_pyramid(cli_args *a, cli_render_args *r) {
    vv_pyramid *p = NULL;
    vv_world *w = NULL;
    vv_volume *proxy = NULL;
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    int rc;
    vv_error_clear();
    vv_status s = vv_pyramid_open(&p, r->input, r->channel, r->has_time ? r->time : -1,
                                  r->memory_limit, NULL);
    if (s != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    if (r->has_level && r->level >= vv_pyramid_levels(p)) {
        cli_error("%s: level %d asked, the store has %d", r->input, r->level, vv_pyramid_levels(p));
        rc = CLI_EXIT_FAIL;
        goto done;
    }
    const int frame = r->has_level ? r->level : 0;
    if ((s = vv_pyramid_proxy(p, frame, &proxy)) != VV_OK) {
        rc = cli_fail(s, r->input);
        goto done;
    }
    vv_render_options ro;
    if ((rc = frame_setup(a, r, proxy, vv_pyramid_level(p, frame), &w, &ren, &img, &ro)))
        goto done;
    vv_lod lod;
    vv_lod_init(&lod);
    lod.level = r->has_level ? r->level : -1;
    lod.voxel_pixels = r->lod;
    vv_multires_source src;
    vv_pyramid_source(p, &src);
    double t0 = cli_now();
    vv_error_clear();
    /* --progressive: step 0 from what is resident (the coarsest level), each
     * next step reading at most N chunks more, until nothing is pending */
    lod.progressive = r->progressive > 0;
    int steps = 0;
    for (;;) {
        lod.load_budget = steps == 0 ? 0 : r->progressive;
        s = vv_renderer_render_multires(ren, w, 0, &src, &w->view, &ro, &lod, img);
        if (s != VV_OK || !lod.progressive)
            break;
        char step[4200];
        cli_numbered_path(r->output, 'p', steps, step, sizeof step);
        if ((s = vv_image_write_png(img, step, r->gamma, r->alpha)) != VV_OK) {
            rc = cli_fail(s, step);
            goto done;
        }
        steps++;
        if (lod.pending == 0)
            break;
    }
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
        vv_pyramid_stats st;
        vv_pyramid_stats_get(p, &st);
        char levels[512] = "";
        int len = 0;
        for (int l = 0; l < vv_pyramid_levels(p) && len < (int)sizeof levels - 64; l++)
            len += snprintf(levels + len, sizeof levels - (size_t)len, "%s%d: %d nodes %llu chunks",
                            l ? ", " : "", l, lod.nodes[l], (unsigned long long)st.chunk_reads[l]);
        if (steps > 0)
            printf("wrote %d progressive steps (_p0000 .. _p%04d)\n", steps, steps - 1);
        printf("wrote %s (%dx%d, %.2f s; out of core from %d levels: %s; %d nodes skipped, "
               "%.1f MiB read, peak cache %.1f MiB, a chunk read at most %d times a frame)\n",
               r->output, img->width, img->height, seconds, vv_pyramid_levels(p), levels,
               lod.skipped, (double)st.bytes_read / 1048576.0, (double)st.peak_bytes / 1048576.0,
               st.max_reads_per_frame);
    }
    rc = CLI_EXIT_OK;
done:
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_volume_free(proxy);
    vv_pyramid_free(p);
    return rc;
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
    /* a .vvb with pyramid levels reads by bricks unless asked for its levels */
    const int multires = r->has_lod || r->progressive > 0 || r->has_level;
    if (!r->has_raw && vv_pyramid_probe(r->input) && (multires || !cli_ends_with(r->input, ".vvb")))
        return render_pyramid(a, r);
    if (multires && (r->has_lod || r->progressive > 0 || r->level > 0)) {
        cli_error("%s: --lod, --level and --progressive need a multiresolution file (OME-Zarr, "
                  "BigDataViewer or Imaris HDF5, or a .vvb with pyramid levels)",
                  r->input);
        return CLI_EXIT_USAGE;
    }
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
    vv_render_options ro;
    if ((rc = frame_setup(a, r, proxy, vv_bricked_header(b), &w, &ren, &img, &ro)))
        goto done;
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
