/*
 * bench_raster: the geometry renderer (`surface`) on the Marching Cubes
 * isosurface of a volume, in the shared benchmark view of
 * ../shared/BENCHMARKS.md (512^2, perspective fov 20 deg, eye at
 * scale * 11 * normalize(1, -1.6, 1) around the centred volume, Phong ka 0.1
 * kd 0.6 ks 0.3 n 30, white, one headlight), printed as
 *   anchor=volvis op=<op> dataset=<file> value=<number> unit=<unit>
 *
 * ops: raster_triangles (the mesh drawn), raster_first_frame (extraction
 * included), raster_frame (median of --runs frames with the surface
 * cached: what an interactive viewer pays per frame), raster_frame_cpu (the
 * median CPU time of those frames, all threads: steadier on a loaded
 * machine), raster_frame_<shading>
 * for flat and gouraud, raster_frame_wireframe, raster_tri_rate (triangles
 * per second of raster_frame) and raster_iso_psnr (the frame against the
 * ray caster's iso image of the same view, dB).
 *
 * usage: bench_raster VOLUME [--iso V] [--size N] [--runs N] [--threads N]
 *                     [--outdir DIR] [--variants 0|1]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/bench_scene.h"
#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;
#define emit(op, value, unit) bench_emit(op, dataset, value, unit)

static void
save(const vv_image *img, const char *outdir, const char *stem, const char *what) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s_volvis_%s.png", outdir, stem, what);
    if (vv_image_write_png(img, path, 1.0, 0) != VV_OK)
        bench_die("bench_raster", "write png");
    printf("# image %s\n", path);
}

int
main(int argc, char **argv) {
    double iso = NAN;
    int size = 512, runs = 5, threads = 0, with_variants = 1;
    const char *outdir = "build/bench-out", *path = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (a[0] != '-') {
            path = a;
            continue;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, "bench_raster: %s needs a value\n", a);
            return 2;
        }
        const char *val = argv[++i];
        if (!strcmp(a, "--iso"))
            iso = atof(val);
        else if (!strcmp(a, "--size"))
            size = atoi(val);
        else if (!strcmp(a, "--runs"))
            runs = atoi(val);
        else if (!strcmp(a, "--threads"))
            threads = atoi(val);
        else if (!strcmp(a, "--outdir"))
            outdir = val;
        else if (!strcmp(a, "--variants"))
            with_variants = atoi(val);
        else {
            fprintf(stderr, "bench_raster: unknown option %s\n", a);
            return 2;
        }
    }
    if (!path || size < 1 || runs < 1) {
        fprintf(stderr, "usage: bench_raster VOLUME [--iso V] [--size N] [--runs N] "
                        "[--threads N] [--outdir DIR] [--variants 0|1]\n");
        return 2;
    }
    dataset = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    bench_mkdirs(outdir);
    if (threads > 0)
        vv_threads_set(threads);
    vv_volume *vol;
    if (vv_volume_load(&vol, path, NULL) != VV_OK)
        bench_die("bench_raster", path);
    if (isnan(iso))
        iso = 0.5 * (vol->range[0] + vol->range[1]);
    char stem[256];
    snprintf(stem, sizeof stem, "%s", dataset);
    char *dot = strchr(stem, '.');
    if (dot)
        *dot = 0;

    vv_world *w;
    if (vvb_surface_world(&w, NULL, vol, iso, size) != VV_OK)
        bench_die("bench_raster", "world");

    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    vv_image *img, *ref;
    if (vv_image_new(&img, size, size) != VV_OK || vv_image_new(&ref, size, size) != VV_OK)
        bench_die("bench_raster", "image");

    /* the mesh alone, for its size */
    vv_isosurface_options io;
    vv_isosurface_options_init(&io);
    io.threads = threads;
    vv_mesh *mesh;
    double t0 = bench_now();
    if (vv_isosurface_extract(&mesh, vol, iso, &io) != VV_OK)
        bench_die("bench_raster", "isosurface");
    printf("# %s %dx%dx%d, iso %g: %zu triangles, %zu vertices (extracted in %.3f s), %d threads, "
           "%dx%d\n",
           dataset, vol->dims[0], vol->dims[1], vol->dims[2], iso, mesh->n_triangles,
           mesh->n_vertices, bench_now() - t0, vv_threads_get(), size, size);
    emit("raster_triangles", (double)mesh->n_triangles, "triangles");

    vv_renderer *r;
    if (vv_renderer_new(&r, "raster") != VV_OK)
        bench_die("bench_raster", "surface renderer");
    t0 = bench_now();
    if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
        bench_die("bench_raster", "render");
    emit("raster_first_frame", bench_now() - t0, "s");
    double cpu = 0, tf = 0;
    if (vvb_median_frame(&tf, &cpu, r, w, &opt, img, runs) != VV_OK)
        bench_die("bench_raster", "render");
    emit("raster_frame", tf, "s");
    emit("raster_frame_cpu", cpu, "s");
    emit("raster_tri_rate", (double)mesh->n_triangles / tf, "triangles/s");
    save(img, outdir, stem, "raster_phong");

    vv_renderer *rc;
    if (vv_renderer_new(&rc, "raycast") != VV_OK ||
        vv_renderer_render(rc, w, &w->view, &opt, ref) != VV_OK)
        bench_die("bench_raster", "raycast");
    emit("raster_iso_psnr", vv_image_psnr(img, ref), "dB");
    save(ref, outdir, stem, "raster_raycast_iso");

    const char *variants[3][2] = {{"shading", "flat"}, {"shading", "gouraud"}, {"wireframe", "1"}};
    const char *names[3] = {"raster_frame_flat", "raster_frame_gouraud", "raster_frame_wireframe"};
    for (int v = 0; v < 3 && with_variants; v++) {
        vv_renderer *rv;
        if (vv_renderer_new(&rv, "raster") != VV_OK ||
            vv_renderer_set_option(rv, variants[v][0], variants[v][1]) != VV_OK ||
            vv_renderer_render(rv, w, &w->view, &opt, img) != VV_OK)
            bench_die("bench_raster", "render variant");
        double tv = 0;
        if (vvb_median_frame(&tv, NULL, rv, w, &opt, img, runs) != VV_OK)
            bench_die("bench_raster", "render variant");
        emit(names[v], tv, "s");
        save(img, outdir, stem, names[v] + 7);
        vv_renderer_free(rv);
    }

    vv_renderer_free(rc);
    vv_renderer_free(r);
    vv_mesh_free(mesh);
    vv_image_free(img);
    vv_image_free(ref);
    vv_world_free(w);
    vv_volume_free(vol);
    return 0;
}
