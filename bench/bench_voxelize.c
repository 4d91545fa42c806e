/*
 * bench_voxelize: volume-sampled voxelization (src/modeling), printed as
 *   anchor=volvis op=<op> dataset=<name> value=<number> unit=<unit>
 * for ../shared/anchors/summarize.py:
 *   voxelize_sphere_256          a sphere filling a 256^3 grid
 *   voxelize_mesh_bunny_256      meshes/bunny.ply (open; filled as a solid) at 256 voxels
 *   voxelize_isosurface_ct_head  the marching-cubes isosurface at 300 of
 *                                volumes/ct_head.nrrd voxelized back onto its
 *                                256x256x108 grid (needs include/volvis/surface.h);
 *                                compare with voxelize_stencil_time of
 *                                ../shared/anchors/bench_vtk.py in the same run
 * Each time is the median of --runs runs (default 5) after one warm-up.
 *
 * usage: bench_voxelize [--data DIR] [--runs N] [--threads N] [--iso V]
 *                       [--only sphere|bunny|ct]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "util.h"
#include "volvis/volvis.h"
#if defined(__has_include)
#if __has_include("volvis/surface.h")
#include "volvis/surface.h"
#define HAVE_SURFACE 1
#endif
#endif

/* Voxels above the 0.5 level of a u8 density volume, times the voxel volume. */
static double
level_volume(const vv_volume *v) {
    const unsigned char *d = v->data;
    size_t n = (size_t)vv_volume_voxel_count(v), c = 0;
    for (size_t i = 0; i < n; i++)
        c += d[i] > 127;
    return (double)c * v->spacing[0] * v->spacing[1] * v->spacing[2];
}

/* Median time of runs voxelizations; the last volume is returned. */
static double
time_voxelize(const vv_shape *s, const vv_voxelize_options *o, int runs, vv_volume **last) {
    double t[64];
    vv_volume *v = NULL;
    if (vv_voxelize(&v, s, o) != VV_OK) /* warm-up */
        bench_die("bench_voxelize", "voxelize");
    vv_volume_free(v);
    for (int r = 0; r < runs; r++) {
        double t0 = bench_now();
        if (vv_voxelize(&v, s, o) != VV_OK)
            bench_die("bench_voxelize", "voxelize");
        t[r] = bench_now() - t0;
        if (r + 1 < runs)
            vv_volume_free(v);
    }
    qsort(t, (size_t)runs, sizeof *t, bench_cmp_double);
    *last = v;
    return t[runs / 2];
}

int
main(int argc, char **argv) {
    const char *data = "../shared/data";
    int runs = 5, threads = 0;
    double iso = 300;
    const char *only = NULL;
    for (int i = 1; i < argc; i++) {
        if (i + 1 < argc && strcmp(argv[i], "--data") == 0)
            data = argv[++i];
        else if (i + 1 < argc && strcmp(argv[i], "--runs") == 0)
            runs = atoi(argv[++i]);
        else if (i + 1 < argc && strcmp(argv[i], "--threads") == 0)
            threads = atoi(argv[++i]);
        else if (i + 1 < argc && strcmp(argv[i], "--iso") == 0)
            iso = atof(argv[++i]);
        else if (i + 1 < argc && strcmp(argv[i], "--only") == 0)
            only = argv[++i];
        else {
            fprintf(stderr, "usage: bench_voxelize [--data DIR] [--runs N] [--threads N] "
                            "[--iso V] [--only sphere|bunny|ct]\n");
            return 2;
        }
    }
    if (runs < 1 || runs > 64)
        runs = 5;
    if (threads > 0)
        vv_threads_set(threads);
    printf("# threads %d, median of %d runs\n", vv_threads_get(), runs);
    char path[1024];
    vv_volume *v = NULL;
    vv_voxelize_options o;

    /* a sphere filling a 256^3 grid */
    if (!only || strcmp(only, "sphere") == 0) {
        vv_shape *s = NULL;
        if (vv_shape_sphere(&s, 124.0) != VV_OK)
            bench_die("bench_voxelize", "sphere");
        vv_voxelize_options_init(&o);
        o.dims[0] = o.dims[1] = o.dims[2] = 256;
        o.spacing[0] = o.spacing[1] = o.spacing[2] = 1.0;
        o.origin[0] = o.origin[1] = o.origin[2] = -127.5;
        double sec = time_voxelize(s, &o, runs, &v);
        double want = 4.0 / 3.0 * VV_PI * 124.0 * 124.0 * 124.0;
        bench_emit("voxelize_sphere_256", "sphere_r124", sec, "s");
        bench_emit("voxelize_sphere_256_voxel_rate", "sphere_r124", 256.0 * 256 * 256 / sec,
                   "voxels/s");
        bench_emit("voxelize_sphere_256_volume_relerr", "sphere_r124",
                   (level_volume(v) - want) / want, "fraction");
        vv_volume_free(v);
        vv_shape_free(s);
    }

    /* the Stanford bunny at 256 voxels (open: a solid by the winding number) */
    if (!only || strcmp(only, "bunny") == 0) {
        snprintf(path, sizeof path, "%s/meshes/bunny.ply", data);
        vv_mesh *m = NULL;
        if (vv_mesh_load(&m, path) != VV_OK)
            bench_die("bench_voxelize", path);
        vv_shape *s = NULL;
        if (vv_shape_mesh(&s, m, VV_MESH_SOLID, 0) != VV_OK)
            bench_die("bench_voxelize", "bunny shape");
        vv_voxelize_options_init(&o);
        o.size = 256;
        double sec = time_voxelize(s, &o, runs, &v);
        double nvox = (double)vv_volume_voxel_count(v);
        printf("# bunny: %zu triangles, grid %d x %d x %d\n", m->n_triangles, v->dims[0],
               v->dims[1], v->dims[2]);
        bench_emit("voxelize_mesh_bunny_256", "bunny.ply", sec, "s");
        bench_emit("voxelize_mesh_bunny_256_voxel_rate", "bunny.ply", nvox / sec, "voxels/s");
        double mv = fabs(vv_mesh_signed_volume(m));
        bench_emit("voxelize_mesh_bunny_256_volume", "bunny.ply", level_volume(v), "world^3");
        printf("# bunny divergence volume (an open mesh: approximate) %.6g\n", mv);
        vv_volume_free(v);
        vv_shape_free(s);
        vv_mesh_free(m);
    }

#ifdef HAVE_SURFACE
    /* the CT head's isosurface, voxelized back onto its grid */
    if (!only || strcmp(only, "ct") == 0) {
        snprintf(path, sizeof path, "%s/volumes/ct_head.nrrd", data);
        vv_volume *ct = NULL;
        if (vv_volume_load(&ct, path, NULL) != VV_OK)
            bench_die("bench_voxelize", path);
        vv_isosurface_options io;
        vv_isosurface_options_init(&io);
        io.compute_normals = 0;
        vv_mesh *m = NULL;
        if (vv_isosurface_extract(&m, ct, iso, &io) != VV_OK)
            bench_die("bench_voxelize", "isosurface");
        vv_voxelize_options_init(&o);
        for (int a = 0; a < 3; a++) {
            o.dims[a] = ct->dims[a];
            o.spacing[a] = ct->spacing[a];
            o.origin[a] = ct->origin[a];
        }
        /* time the whole conversion: the shape (topology check) and the voxelization */
        double t[64];
        for (int r = -1; r < runs; r++) {
            double t0 = bench_now();
            vv_shape *s = NULL;
            if (vv_shape_mesh(&s, m, VV_MESH_SOLID, 0) != VV_OK)
                bench_die("bench_voxelize", "isosurface shape");
            if (vv_voxelize(&v, s, &o) != VV_OK)
                bench_die("bench_voxelize", "voxelize isosurface");
            double dt = bench_now() - t0;
            if (r >= 0)
                t[r] = dt;
            vv_shape_free(s);
            if (r + 1 < runs)
                vv_volume_free(v);
        }
        qsort(t, (size_t)runs, sizeof *t, bench_cmp_double);
        double sec = t[runs / 2];
        printf("# ct_head isosurface %g: %zu triangles, grid %d x %d x %d\n", iso, m->n_triangles,
               ct->dims[0], ct->dims[1], ct->dims[2]);
        bench_emit("voxelize_isosurface_ct_head", "ct_head.nrrd", sec, "s");
        bench_emit("voxelize_isosurface_ct_head_voxel_rate", "ct_head.nrrd",
                   (double)vv_volume_voxel_count(ct) / sec, "voxels/s");
        bench_emit("voxelize_isosurface_ct_head_volume", "ct_head.nrrd", level_volume(v),
                   "world^3");
        /* voxel counting of the input at the isovalue, as the VTK script does */
        size_t cnt = 0, n = (size_t)vv_volume_voxel_count(ct);
        for (size_t i = 0; i < n; i++)
            cnt += ((const int16_t *)ct->data)[i] > iso;
        bench_emit("voxelcount_volume", "ct_head.nrrd",
                   (double)cnt * ct->spacing[0] * ct->spacing[1] * ct->spacing[2], "world^3");
        vv_volume_free(v);
        vv_mesh_free(m);
        vv_volume_free(ct);
    }
#else
    (void)iso;
    (void)only;
    printf("# voxelize_isosurface_ct_head skipped: no include/volvis/surface.h (marching cubes)\n");
#endif
    return 0;
}
