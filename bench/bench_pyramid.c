/*
 * bench_pyramid: OME-Zarr pyramids rendered out of core by level of detail
 * (vv_open of the store by its levels, an object holding the pyramid
 * source, vv_renderer_render with vv_render_options.lod), run by
 * bench/zarr_pyramid.sh
 * on a generated store under a cgroup memory limit:
 *   bench_pyramid STORE [--memory-limit MiB] [--size N] [--frames F]
 *                 [--tf LO:HI] [--lod PIXELS | --level L] [--dataset NAME] [--sharpen]
 *                 [--set KEY=VALUE]...
 * Opens STORE with the process's cache at the memory limit (default 1024 MiB), builds the default
 * World from its coarsest level (the proxy, over level 0's box) with a
 * transfer function ramp LO..HI, and renders F frames (default 4) at N x N
 * (default 512), orbiting 10 degrees a frame, each node at the coarsest
 * level within PIXELS (default 1) or every node at level L. Prints, as
 * anchor lines: the open time (metadata and the coarsest level), the first
 * image (open plus a progressive frame that reads nothing: every node from
 * what the cache holds, the coarsest level at worst); with --sharpen, the
 * time until the image is converged by progressive frames that leave the
 * reading to the pyramid's background loader (each frame drawn from what
 * is resident, then a wait for the next chunk: what the GUI and Python do
 * while the view stands still; when the view needs more chunks than the
 * limit holds, the loader stalls and one converged frame streams the rest)
 * and the frames drawn meanwhile; the first
 * frame (chunks cold in the cache; the files as the page cache has them),
 * the median of the next frames, the chunks read and the nodes per level,
 * the most reads of one chunk in a frame, the peak cache and the process's
 * peak resident size (getrusage); writes the last frame to
 * $VV_BENCH_OUT/pyramid.png when that is set. --set passes a ray-caster
 * option (up to 8: gradient_budget_mb=0 computes gradients at the samples
 * instead of for every voxel of every node).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "util.h"
#include "volvis/volvis.h"

static uint64_t
chunks_read(const vv_source_stats *st) {
    uint64_t n = 0;
    for (int l = 0; l < VV_SOURCE_MAX_LEVELS; l++)
        n += st->chunk_reads[l];
    return n;
}

int
main(int argc, char **argv) {
    const char *path = NULL, *dataset = "store";
    double limit_mib = 1024, tf_lo = 60, tf_hi = 255, lod_px = 1;
    int size = 512, frames = 4, level = -1, sharpen = 0, n_set = 0;
    const char *set[8]; /* --set KEY=VALUE: renderer options */
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--memory-limit") == 0 && i + 1 < argc)
            limit_mib = atof(argv[++i]);
        else if (strcmp(argv[i], "--size") == 0 && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc)
            frames = atoi(argv[++i]);
        else if (strcmp(argv[i], "--lod") == 0 && i + 1 < argc)
            lod_px = atof(argv[++i]);
        else if (strcmp(argv[i], "--level") == 0 && i + 1 < argc)
            level = atoi(argv[++i]);
        else if (strcmp(argv[i], "--tf") == 0 && i + 1 < argc) {
            if (sscanf(argv[++i], "%lf:%lf", &tf_lo, &tf_hi) != 2)
                return 2;
        } else if (strcmp(argv[i], "--dataset") == 0 && i + 1 < argc)
            dataset = argv[++i];
        else if (strcmp(argv[i], "--sharpen") == 0)
            sharpen = 1;
        else if (strcmp(argv[i], "--set") == 0 && i + 1 < argc && n_set < 8)
            set[n_set++] = argv[++i];
        else
            path = argv[i];
    }
    if (!path || size < 1 || frames < 1 || frames > 100 || !(limit_mib > 0)) {
        fprintf(stderr, "usage: bench_pyramid STORE [--memory-limit MiB] [--size N] [--frames F] "
                        "[--tf LO:HI] [--lod PIXELS | --level L] [--dataset NAME] [--sharpen] "
                        "[--set KEY=VALUE]...\n");
        return 2;
    }
    double t0 = bench_now();
    vv_cache_set_limit(vv_cache_process(), (uint64_t)(limit_mib * 1048576.0));
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    oo.levels = 1;
    vv_opened od;
    if (vv_open(&od, path, &oo) != VV_OK || vv_source_get_kind(od.source) != VV_SOURCE_PYRAMID)
        bench_die("bench_pyramid", path);
    vv_source *p = od.source;
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = size;
    o.has_tf_range = 1;
    o.tf_lo = tf_lo;
    o.tf_hi = tf_hi;
    vv_world *w = NULL; /* from the proxy; opacity per level 0's voxel spacing */
    if (vv_world_new_for_source(&w, p, 0, &o) != VV_OK)
        bench_die("bench_pyramid", "world");
    bench_emit("pyramid_open", dataset, bench_now() - t0, "s");
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    if (vv_renderer_new(&ren, "raycast") != VV_OK || vv_image_new(&img, size, size) != VV_OK)
        bench_die("bench_pyramid", "renderer");
    for (int i = 0; i < n_set; i++) {
        char key[128];
        const char *eq = strchr(set[i], '=');
        if (!eq || (size_t)(eq - set[i]) >= sizeof key)
            bench_die("bench_pyramid", "--set KEY=VALUE");
        memcpy(key, set[i], (size_t)(eq - set[i]));
        key[eq - set[i]] = '\0';
        if (vv_renderer_set_option(ren, key, eq + 1) != VV_OK)
            bench_die("bench_pyramid", set[i]);
    }
    double times[100];
    vv_source_stats st0, st1;
    vv_lod lod;
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.lod = &lod;
    /* the first image: a progressive frame from what the cache holds */
    vv_lod_init(&lod);
    lod.level = level;
    lod.voxel_pixels = lod_px;
    lod.progressive = 1;
    lod.background = sharpen;
    lod.load_budget = 0;
    if (vv_renderer_render(ren, w, &w->view, &ro, img) != VV_OK)
        bench_die("bench_pyramid", "first image");
    const double first = bench_now() - t0;
    bench_emit("pyramid_first_image", dataset, first, "s");
    fprintf(stderr, "bench_pyramid: first image %.2f s after opening began, %d nodes pending\n",
            first, lod.pending);
    if (sharpen) {
        const double ts = bench_now();
        int n = 1;
        for (; lod.pending > 0 && n < 100000; n++) {
            const int stalled = lod.stalled;
            if (!stalled)
                vv_source_wait(p, 1.0);
            lod.progressive = !stalled; /* stalled: the converged frame streams the rest */
            if (vv_renderer_render(ren, w, &w->view, &ro, img) != VV_OK)
                bench_die("bench_pyramid", "progressive frame");
            if (n % 10 == 0 || lod.pending == 0 || stalled)
                fprintf(stderr,
                        "bench_pyramid: sharpening frame %d at %.2f s: %d nodes pending%s\n", n,
                        bench_now() - ts, lod.pending,
                        stalled ? " (the loader stalled: a converged frame)" : "");
        }
        vv_source_stats_get(p, &st0);
        bench_emit("pyramid_sharpened", dataset, bench_now() - ts, "s");
        bench_emit("pyramid_sharpening_frames", dataset, n, "frames");
        fprintf(stderr,
                "bench_pyramid: the loader read %llu chunks, %llu cancelled, %llu left "
                "when the cache was full\n",
                (unsigned long long)st0.loaded, (unsigned long long)st0.cancelled,
                (unsigned long long)st0.load_stopped);
    }
    for (int f = 0; f < frames; f++) {
        if (f > 0)
            vv_view_orbit(&w->view, 10 * 3.14159265358979 / 180, 0);
        vv_lod_init(&lod);
        lod.level = level;
        lod.voxel_pixels = lod_px;
        vv_source_stats_get(p, &st0);
        const double t = bench_now();
        if (vv_renderer_render(ren, w, &w->view, &ro, img) != VV_OK)
            bench_die("bench_pyramid", "render");
        times[f] = bench_now() - t;
        vv_source_stats_get(p, &st1);
        char nodes[256] = "";
        int len = 0;
        for (int l = 0; l < vv_source_levels(p) && len < 200; l++)
            len += snprintf(nodes + len, sizeof nodes - (size_t)len, " %d", lod.nodes[l]);
        fprintf(stderr,
                "bench_pyramid: frame %d: %.2f s, nodes per level%s, %d skipped, %llu chunks "
                "read, %llu from the cache, %.1f MiB read\n",
                f, times[f], nodes, lod.skipped,
                (unsigned long long)(chunks_read(&st1) - chunks_read(&st0)),
                (unsigned long long)(st1.chunk_hits - st0.chunk_hits),
                (double)(st1.bytes_read - st0.bytes_read) / 1048576.0);
    }
    bench_emit("pyramid_first_frame", dataset, times[0], "s");
    if (frames > 1)
        bench_emit("pyramid_next_frames", dataset, bench_median(times + 1, frames - 1), "s");
    vv_source_stats st;
    vv_source_stats_get(p, &st);
    bench_emit("pyramid_chunks_read", dataset, (double)chunks_read(&st), "chunks");
    bench_emit("pyramid_bytes_read", dataset, (double)st.bytes_read / 1048576.0, "MiB");
    bench_emit("pyramid_most_reads_a_frame", dataset, st.max_reads_per_frame, "reads");
    bench_emit("pyramid_peak_cache", dataset, (double)st.peak_bytes / 1048576.0, "MiB");
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    bench_emit("pyramid_peak_rss", dataset, (double)ru.ru_maxrss / 1024.0, "MiB");
    const char *out = getenv("VV_BENCH_OUT");
    if (out && *out) {
        char png[4096];
        snprintf(png, sizeof png, "%s/pyramid.png", out);
        vv_image_write_png(img, png, 1, 0);
    }
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_opened_clear(&od);
    return 0;
}
