/*
 * bench_raytrace: volumetric ray tracing of the mirror-and-head scene
 * (examples/head_mirror.json: the CT head, a mirror in a frame, a
 * reflective floor, two directional lights) at 512 x 512, one sample per
 * pixel, shadow rays and one reflection (max_depth 1), printed as
 *   anchor=volvis op=<op> dataset=<scene> value=<number> unit=<unit>
 *
 * ops: raytrace_frame (PARC on), raytrace_frame_noparc, raytrace_rays_per_s
 * (primary rays, i.e. pixels, per second of raytrace_frame), raycast_frame
 * (the plain ray caster on the same World and view at quality 2: it shows
 * the volume only), and the ratios raytrace_parc_speedup and
 * raytrace_vs_raycast. These ray-trace one ray a pixel (refinement=off),
 * as the ray caster at quality 2 with refinement=off (set here: its
 * default refines composite frames) does; raytrace_refined_frame and
 * raytrace_refined_vs_raycast are quality 1 as the renderer's default has
 * it, with adaptive image-space refinement (fewer primary rays).
 * Each time is the median of --runs renders after one warm-up render
 * (caches built). raytrace_orbit_frame: the median frame of the view
 * turned by 2 degrees a frame, 8 frames (a drag in the GUI: the shadow
 * grids kept from the frames before serve the new views);
 * raytrace_first_frame: a new renderer's first frame (every cache cold but
 * the volume's file read).
 *
 * usage: bench_raytrace [SCENE] [--size N] [--runs N] [--threads N]
 *                       [--max-depth N] [--set NAME=VALUE ...] [--outdir DIR]
 * (--set: a ray-tracer option for all its renders, e.g. shadows=0 for the
 * floor without shadows)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;
#define emit(op, value, unit) bench_emit(op, dataset, value, unit)

/* Median render time of @p runs renders after a warm-up; keeps the image. */
static double
time_renders(vv_renderer *r, const vv_world *w, int quality, int threads, int runs, vv_image *img) {
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.quality = quality;
    opt.threads = threads;
    if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
        bench_die("bench_raytrace", "warm-up render");
    double t[64];
    for (int i = 0; i < runs; i++) {
        double t0 = bench_now();
        if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
            bench_die("bench_raytrace", "render");
        t[i] = bench_now() - t0;
    }
    qsort(t, (size_t)runs, sizeof t[0], bench_cmp_double);
    return t[runs / 2];
}

static void
save(const vv_image *img, const char *outdir, const char *name) {
    if (!outdir)
        return;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", outdir, name);
    if (vv_image_write_png(img, path, 1.0, 0) != VV_OK)
        bench_die("bench_raytrace", path);
}

int
main(int argc, char **argv) {
    const char *scene = "examples/head_mirror.json", *outdir = NULL, *depth = "1";
    int size = 512, runs = 3, threads = 2;
    const char *sets[16];
    int nsets = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--size") == 0 && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (strcmp(argv[i], "--runs") == 0 && i + 1 < argc)
            runs = atoi(argv[++i]);
        else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (strcmp(argv[i], "--max-depth") == 0 && i + 1 < argc)
            depth = argv[++i];
        else if (strcmp(argv[i], "--outdir") == 0 && i + 1 < argc)
            outdir = argv[++i];
        else if (strcmp(argv[i], "--set") == 0 && i + 1 < argc && nsets < 16)
            sets[nsets++] = argv[++i];
        else if (argv[i][0] != '-')
            scene = argv[i];
        else {
            fprintf(stderr, "usage: bench_raytrace [SCENE] [--size N] [--runs N] [--threads N] "
                            "[--max-depth N] [--set NAME=VALUE ...] [--outdir DIR]\n");
            return 2;
        }
    }
    if (size < 1 || size > 16384 || runs < 1 || runs > 64 || threads < 0) {
        fprintf(stderr, "bench_raytrace: bad --size, --runs or --threads\n");
        return 2;
    }
    const char *slash = strrchr(scene, '/');
    dataset = slash ? slash + 1 : scene;
    vv_world *w = NULL;
    if (vv_scene_load(&w, scene) != VV_OK)
        bench_die("bench_raytrace", scene);
    w->view.width = w->view.height = size;
    vv_image *img = NULL;
    if (vv_image_new(&img, size, size) != VV_OK)
        bench_die("bench_raytrace", "image");

    vv_renderer *rt = NULL, *rn = NULL, *rr = NULL, *rc = NULL;
    if (vv_renderer_new(&rt, "raytrace") != VV_OK || vv_renderer_new(&rn, "raytrace") != VV_OK ||
        vv_renderer_new(&rr, "raytrace") != VV_OK || vv_renderer_new(&rc, "raycast") != VV_OK)
        bench_die("bench_raytrace", "renderer");
    vv_renderer *all[3] = {rt, rn, rr};
    for (int i = 0; i < 3; i++)
        if (vv_renderer_set_option(all[i], "samples", "1") != VV_OK ||
            vv_renderer_set_option(all[i], "max_depth", depth) != VV_OK ||
            vv_renderer_set_option(all[i], "parc", i == 1 ? "0" : "1") != VV_OK ||
            vv_renderer_set_option(all[i], "refinement", i == 2 ? "auto" : "off") != VV_OK)
            bench_die("bench_raytrace", "option");
    /* the ray tracers' other options (--set: floors, e.g. shadows=0) */
    for (int k = 0; k < nsets; k++) {
        char name[64];
        const char *eq = strchr(sets[k], '=');
        if (!eq || eq == sets[k] || (size_t)(eq - sets[k]) >= sizeof name)
            bench_die("bench_raytrace", "--set takes NAME=VALUE");
        memcpy(name, sets[k], (size_t)(eq - sets[k]));
        name[eq - sets[k]] = 0;
        for (int i = 0; i < 3; i++)
            if (vv_renderer_set_option(all[i], name, eq + 1) != VV_OK)
                bench_die("bench_raytrace", sets[k]);
    }
    /* one ray a pixel like the ray tracer's (the ray caster refines
     * composite frames at quality 2 by default) */
    if (vv_renderer_set_option(rc, "refinement", "off") != VV_OK)
        bench_die("bench_raytrace", "option");

    /* interleaved, so that a slow phase of a shared machine hits both */
    double t_rt = time_renders(rt, w, 1, threads, runs, img);
    save(img, outdir, "raytrace.png");
    double t_rc = time_renders(rc, w, 2, threads, runs, img);
    save(img, outdir, "raycast.png");
    double t_rn = time_renders(rn, w, 1, threads, runs, img);
    save(img, outdir, "raytrace_noparc.png");
    double t_rr = time_renders(rr, w, 1, threads, runs, img);
    save(img, outdir, "raytrace_refined.png");
    /* a drag: the view turned 2 degrees a frame */
    double t_orbit[8];
    {
        vv_render_options opt;
        vv_render_options_init(&opt);
        opt.quality = 1;
        opt.threads = threads;
        for (int i = 0; i < 8; i++) {
            vv_view v = w->view;
            vv_anim_view_turn(&v, (i + 1) * 2.0 * 3.14159265358979 / 180, 0, 1);
            double t0 = bench_now();
            if (vv_renderer_render(rt, w, &v, &opt, img) != VV_OK)
                bench_die("bench_raytrace", "render");
            t_orbit[i] = bench_now() - t0;
        }
        qsort(t_orbit, 8, sizeof t_orbit[0], bench_cmp_double);
    }
    /* a new renderer's first frame */
    double t_first;
    {
        vv_renderer *r1 = NULL;
        if (vv_renderer_new(&r1, "raytrace") != VV_OK ||
            vv_renderer_set_option(r1, "samples", "1") != VV_OK ||
            vv_renderer_set_option(r1, "max_depth", depth) != VV_OK ||
            vv_renderer_set_option(r1, "refinement", "off") != VV_OK)
            bench_die("bench_raytrace", "renderer");
        vv_render_options opt;
        vv_render_options_init(&opt);
        opt.quality = 1;
        opt.threads = threads;
        double t0 = bench_now();
        if (vv_renderer_render(r1, w, &w->view, &opt, img) != VV_OK)
            bench_die("bench_raytrace", "render");
        t_first = bench_now() - t0;
        vv_renderer_free(r1);
    }
    emit("raytrace_frame", t_rt, "s");
    emit("raytrace_frame_noparc", t_rn, "s");
    emit("raytrace_orbit_frame", t_orbit[4], "s");
    emit("raytrace_first_frame", t_first, "s");
    emit("raytrace_rays_per_s", (double)size * size / t_rt, "rays/s");
    emit("raycast_frame", t_rc, "s");
    emit("raytrace_parc_speedup", t_rn / t_rt, "x");
    emit("raytrace_vs_raycast", t_rt / t_rc, "x");
    emit("raytrace_orbit_vs_raycast", t_orbit[4] / t_rc, "x");
    emit("raytrace_refined_frame", t_rr, "s");
    emit("raytrace_refined_vs_raycast", t_rr / t_rc, "x");
    vv_renderer_free(rt);
    vv_renderer_free(rn);
    vv_renderer_free(rr);
    vv_renderer_free(rc);
    vv_image_free(img);
    vv_world_free(w);
    return 0;
}
