/*
 * bench_surface: Marching Cubes, isosurface measurement and the Navigator's
 * previews on one volume, printed as
 *   anchor=volvis op=<op> dataset=<file> value=<number> unit=<unit>
 * beside ../shared/anchors/bench_vtk.py (run both in the same session and
 * compare ratios; see ../shared/BENCHMARKS.md).
 *
 * usage: bench_surface VOLUME [--iso V] [--runs N] [--threads N] [--level L]
 *        (--level: the PARC subdivision level, default 4)
 *
 * Timings are the median of --runs (default 5) after one warm-up run, wall
 * clock, --threads threads (default 2, the peers' count):
 *   iso_mc_time            vv_isosurface_extract, no normals (as VTK's
 *                          iso_flyingedges3d_t2_time: normals and gradients off)
 *   iso_mc_normals_time    the same with gradient normals (VTK: ..._normals_t2)
 *   iso_mc_grid_time       no normals, with the PARC min/max grid given
 *   iso_mc_triangles, iso_mc_tri_rate (of iso_mc_time)
 *   measure_mc_time        vv_measure_isosurface by Marching Cubes (area and
 *                          capped divergence volume; VTK: extraction + massprops)
 *   measure_voxel_time     the same by voxel counting
 *   parc_build_time        vv_parc_set_isovalue + vv_parc_mesh at a new isovalue
 *   coarse_mc_build_time   vv_coarse_set_isovalue at a new isovalue (level 1)
 *   parc_grid_time, coarse_grid_time: the one-off reduced structures
 *   raster_frame           a 512x512 frame of the `surface` renderer drawing
 *                          the isosurface, cached (bench_raster's scene and
 *                          settings: the shared benchmark view, Phong,
 *                          headlight; the volume is centred for it);
 *                          raster_frame_cpu its CPU time, all threads
 * The PARC and coarse rebuilds alternate between iso and iso + 1 so each
 * run is a real change of isovalue.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/bench_scene.h"
#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;

#define emit(op, value, unit) bench_emit(op, dataset, value, unit)
#define die(what) bench_die("bench_surface", what)

#define MAX_RUNS 101

/* Median time of extracting with options o; the last mesh goes to *keep if asked. */
static double
time_extract(const vv_volume *v, double iso, const vv_isosurface_options *o, int runs,
             vv_mesh **keep) {
    double t[MAX_RUNS];
    vv_mesh *m = NULL;
    if (vv_isosurface_extract(&m, v, iso, o) != VV_OK) /* warm-up */
        die("isosurface");
    vv_mesh_free(m);
    for (int r = 0; r < runs; r++) {
        double t0 = bench_now();
        if (vv_isosurface_extract(&m, v, iso, o) != VV_OK)
            die("isosurface");
        t[r] = bench_now() - t0;
        if (r + 1 < runs || !keep)
            vv_mesh_free(m);
        else
            *keep = m;
    }
    return bench_median(t, runs);
}

int
main(int argc, char **argv) {
    const char *path = NULL;
    double iso = NAN;
    int runs = 5, threads = 2, level = 4;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (a[0] == '-' && i + 1 >= argc) {
            fprintf(stderr, "bench_surface: %s needs a value\n", a);
            return 2;
        }
        if (!strcmp(a, "--iso"))
            iso = atof(argv[++i]);
        else if (!strcmp(a, "--runs"))
            runs = atoi(argv[++i]);
        else if (!strcmp(a, "--threads"))
            threads = atoi(argv[++i]);
        else if (!strcmp(a, "--level"))
            level = atoi(argv[++i]);
        else if (a[0] == '-') {
            fprintf(stderr, "bench_surface: unknown option %s\n", a);
            return 2;
        } else
            path = a;
    }
    if (!path || runs < 1 || runs > MAX_RUNS) {
        fprintf(stderr,
                "usage: bench_surface VOLUME [--iso V] [--runs 1..%d] [--threads N] "
                "[--level L]\n",
                MAX_RUNS);
        return 2;
    }
    dataset = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    vv_volume *v = NULL;
    if (vv_volume_load(&v, path, NULL) != VV_OK)
        die(path);
    if (isnan(iso))
        iso = 0.5 * (v->range[0] + v->range[1]);
    printf("# %s %dx%dx%d %s, iso %g, %d threads, median of %d runs\n", dataset, v->dims[0],
           v->dims[1], v->dims[2], vv_voxel_type_name(v->type), iso, threads, runs);
    emit("isovalue", iso, "scalar");

    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    o.compute_normals = 0;
    vv_mesh *m = NULL;
    double t_mc = time_extract(v, iso, &o, runs, &m);
    emit("iso_mc_time", t_mc, "s");
    emit("iso_mc_triangles", (double)m->n_triangles, "triangles");
    emit("iso_mc_tri_rate", (double)m->n_triangles / t_mc, "triangles/s");
    emit("iso_mc_voxel_rate", (double)vv_volume_voxel_count(v) / t_mc, "voxels/s");
    vv_mesh_free(m);
    o.compute_normals = 1;
    emit("iso_mc_normals_time", time_extract(v, iso, &o, runs, NULL), "s");
    o.compute_normals = 0;
    o.threads = 1;
    emit("iso_mc_t1_time", time_extract(v, iso, &o, runs, NULL), "s");
    o.threads = threads;
    vv_minmax_grid *g = NULL;
    if (vv_minmax_grid_build(&g, v, 8) != VV_OK)
        die("min/max grid");
    o.minmax = g;
    emit("iso_mc_grid_time", time_extract(v, iso, &o, runs, NULL), "s");
    o.minmax = NULL;
    vv_minmax_grid_free(g);

    /* measurement: Marching Cubes area + capped volume, and voxel counting */
    vv_isosurface_measure_options mo;
    vv_isosurface_measure_options_init(&mo);
    mo.threads = threads;
    vv_isosurface_measure res;
    double t[MAX_RUNS];
    for (int method = 0; method < 2; method++) {
        mo.method = method ? VV_MEASURE_VOXEL : VV_MEASURE_MC;
        if (vv_measure_isosurface(&res, v, iso, &mo) != VV_OK)
            die("measure");
        for (int r = 0; r < runs; r++) {
            double t0 = bench_now();
            if (vv_measure_isosurface(&res, v, iso, &mo) != VV_OK)
                die("measure");
            t[r] = bench_now() - t0;
        }
        emit(method ? "measure_voxel_time" : "measure_mc_time", bench_median(t, runs), "s");
        emit(method ? "measure_voxel_area" : "measure_mc_area", res.area, "world^2");
        emit(method ? "measure_voxel_volume" : "measure_mc_volume", res.volume, "world^3");
    }

    /* PARC: grid once, then rebuilds at alternating isovalues */
    vv_parc *p = NULL;
    double t0 = bench_now();
    if (vv_parc_new(&p, v, level) != VV_OK)
        die("parc");
    emit("parc_grid_time", bench_now() - t0, "s");
    size_t faces = 0;
    for (int r = -1; r < runs; r++) {
        double q0 = bench_now();
        vv_mesh *pm = NULL;
        if (vv_parc_set_isovalue(p, iso + (r & 1)) != VV_OK || vv_parc_mesh(p, &pm) != VV_OK)
            die("parc");
        if (r >= 0)
            t[r] = bench_now() - q0;
        faces = pm->n_triangles / 2;
        vv_mesh_free(pm);
    }
    emit("parc_build_time", bench_median(t, runs), "s");
    emit("parc_boxes", (double)p->n_boxes, "boxes");
    emit("parc_faces", (double)faces, "quads");
    printf("# PARC level %d: %d-cell boxes, %d x %d x %d\n", level, p->block, p->dims[0],
           p->dims[1], p->dims[2]);
    vv_parc_free(p);

    /* coarse Marching Cubes at level 1 (every second voxel) */
    vv_coarse_surface *c = NULL;
    t0 = bench_now();
    if (vv_coarse_new(&c, v, 1) != VV_OK)
        die("coarse");
    emit("coarse_grid_time", bench_now() - t0, "s");
    for (int r = -1; r < runs; r++) {
        double q0 = bench_now();
        if (vv_coarse_set_isovalue(c, iso + (r & 1), threads) != VV_OK)
            die("coarse");
        if (r >= 0)
            t[r] = bench_now() - q0;
    }
    emit("coarse_mc_build_time", bench_median(t, runs), "s");
    emit("coarse_mc_triangles", (double)c->n_triangles, "triangles");
    emit("coarse_mc_bytes", (double)vv_coarse_bytes(c), "bytes");
    vv_coarse_free(c);

    /* the geometry renderer: bench_raster's scene, surface cached */
    vv_world *w = NULL;
    vv_renderer *rr = NULL;
    vv_image *img = NULL;
    if (vvb_surface_world(&w, NULL, v, iso, 512) != VV_OK ||
        vv_image_new(&img, 512, 512) != VV_OK || vv_renderer_new(&rr, "raster") != VV_OK)
        die("surface renderer");
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = threads;
    if (vv_renderer_render(rr, w, &w->view, &ro, img) != VV_OK) /* extracts, caches */
        die("render");
    double tf = 0, cpu = 0;
    if (vvb_median_frame(&tf, &cpu, rr, w, &ro, img, runs) != VV_OK)
        die("render");
    emit("raster_frame", tf, "s");
    emit("raster_frame_cpu", cpu, "s");
    vv_renderer_free(rr);
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(v);
    return 0;
}
