/*
 * bench_radiosity: volumetric radiosity on the paper's Figure 6 scene
 * (examples/radiosity_sphere_polygon.json: a voxelized sphere, 128^3, above
 * a red polygon under a point light), printed as
 *   anchor=volvis op=<op> dataset=<scene> value=<number> unit=<unit>
 *
 * radiosity_solve: seconds to solve (median of --runs), with the element
 * and interaction counts; radiosity_view_frame: a new view of the solved
 * scene (orbited 30 degrees), --size^2 pixels; raycast_composite_frame: the
 * ray caster's composite frame of the same scene and view, for the ratio.
 *
 * usage: bench_radiosity [SCENE] [--size N] [--runs N] [--threads N] [--grid N]
 *                        [--error E] [--outdir DIR]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"
#include "volvis/volvis.h"

int
main(int argc, char **argv) {
    const char *scene = "examples/radiosity_sphere_polygon.json", *outdir = NULL;
    int size = 512, runs = 1, threads = 2;
    vv_radiosity_options ro;
    vv_radiosity_options_init(&ro);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--size") && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--runs") && i + 1 < argc)
            runs = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--grid") && i + 1 < argc)
            ro.grid = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--error") && i + 1 < argc)
            ro.error = atof(argv[++i]);
        else if (!strcmp(argv[i], "--outdir") && i + 1 < argc)
            outdir = argv[++i];
        else if (argv[i][0] != '-')
            scene = argv[i];
        else {
            fprintf(stderr, "usage: bench_radiosity [SCENE] [--size N] [--runs N] [--threads N] "
                            "[--grid N] [--error E] [--outdir DIR]\n");
            return 2;
        }
    }
    runs = runs < 1 ? 1 : runs;
    vv_threads_set(threads);
    const char *ds = strrchr(scene, '/') ? strrchr(scene, '/') + 1 : scene;
    vv_world *w = NULL;
    if (vv_scene_load(&w, scene) != VV_OK)
        bench_die("bench_radiosity", scene);
    w->view.width = w->view.height = size;
    double *t = calloc((size_t)runs, sizeof *t);
    vv_radiosity *sol = NULL;
    for (int r = 0; r < runs; r++) {
        vv_radiosity_free(sol);
        sol = NULL;
        double t0 = bench_now();
        if (vv_radiosity_solve(&sol, w, &ro, NULL) != VV_OK)
            bench_die("bench_radiosity", "radiosity_solve");
        t[r] = bench_now() - t0;
    }
    vv_radiosity_stats st;
    vv_radiosity_get_stats(sol, &st);
    bench_emit("radiosity_solve", ds, bench_median(t, runs), "s");
    bench_emit("radiosity_voxel_elements", ds, st.n_voxels, "count");
    bench_emit("radiosity_patch_elements", ds, st.n_patches, "count");
    bench_emit("radiosity_shots", ds, st.n_shots, "count");
    bench_emit("radiosity_interactions", ds, st.interactions, "count");
    bench_emit("radiosity_pairwise", ds, st.pairwise, "count");
    bench_emit("radiosity_pairwise_over_interactions", ds, st.pairwise / st.interactions, "ratio");
    double pin = st.power_in[0] + st.power_in[1] + st.power_in[2];
    double un = st.power_unshot[0] + st.power_unshot[1] + st.power_unshot[2];
    bench_emit("radiosity_unshot_fraction", ds, un / pin, "ratio");
    printf("# grid %d error %g: %d voxels + %d patches, %d nodes, %d shots, converged %d; power "
           "in %.4g absorbed %.4g escaped %.4g unshot %.4g (sums of RGB)\n",
           ro.grid, ro.error, st.n_voxels, st.n_patches, st.n_nodes, st.n_shots, st.converged, pin,
           st.power_absorbed[0] + st.power_absorbed[1] + st.power_absorbed[2],
           st.power_escaped[0] + st.power_escaped[1] + st.power_escaped[2], un);
    /* a new view of the solved scene */
    vv_view v = w->view;
    vv_view_orbit(&v, vv_deg_to_rad(30), 0);
    vv_image *img = NULL, *ref = NULL;
    if (vv_image_new(&img, size, size) != VV_OK || vv_image_new(&ref, size, size) != VV_OK)
        bench_die("bench_radiosity", "image");
    /* the two renderers alternate, so a change of load hits both */
    vv_renderer *rc = NULL;
    if (vv_renderer_new(&rc, "raycast") != VV_OK)
        bench_die("bench_radiosity", "raycast");
    vv_render_options o;
    vv_render_options_init(&o);
    o.threads = threads;
    int vr = runs < 7 ? 7 : runs;
    double *tv = calloc((size_t)vr, sizeof *tv), *tr = calloc((size_t)vr, sizeof *tr);
    for (int r = 0; r < vr; r++) {
        double t0 = bench_now();
        if (vv_radiosity_view_frame(sol, w, &v, threads, img) != VV_OK)
            bench_die("bench_radiosity", "radiosity_view_frame");
        tv[r] = bench_now() - t0;
        t0 = bench_now();
        if (vv_renderer_render(rc, w, &v, &o, ref) != VV_OK)
            bench_die("bench_radiosity", "raycast render");
        tr[r] = bench_now() - t0;
    }
    double tview = bench_median(tv, vr), tray = bench_median(tr, vr);
    bench_emit("radiosity_view_frame", ds, tview, "s");
    bench_emit("raycast_composite_frame", ds, tray, "s");
    bench_emit("radiosity_view_over_raycast", ds, tview / tray, "ratio");
    if (outdir) {
        char p[4096];
        snprintf(p, sizeof p, "%s/radiosity_view.png", outdir);
        vv_image_write_png(img, p, 1, 0);
        snprintf(p, sizeof p, "%s/raycast_view.png", outdir);
        vv_image_write_png(ref, p, 1, 0);
        vv_image *i0 = NULL;
        if (vv_image_new(&i0, size, size) == VV_OK &&
            vv_radiosity_view_frame(sol, w, &w->view, threads, i0) == VV_OK) {
            snprintf(p, sizeof p, "%s/radiosity_scene_view.png", outdir);
            vv_image_write_png(i0, p, 1, 0);
        }
        vv_image_free(i0);
    }
    vv_renderer_free(rc);
    vv_image_free(img);
    vv_image_free(ref);
    vv_radiosity_free(sol);
    vv_world_free(w);
    free(t);
    free(tv);
    free(tr);
    return 0;
}
