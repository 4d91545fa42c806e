/*
 * bench_parallel: strong scaling of sort-last distributed ray casting
 * (src/parallel), run under mpirun by bench/parallel_scaling.sh:
 *   mpirun -np N bench_parallel [VOLUME] [--size N] [--side S] [--frames F]
 *                               [--threads T] [--compositing binary-swap|radix-k]
 * The volume (default ../shared/data/volumes/ct_head.nrrd, 16-bit) is resampled
 * trilinearly to S^3 16-bit voxels (default 512, the same world extent) on every
 * rank, shown with a composite transfer function (100..1500, shaded) from
 * the default view at N x N pixels (default 512). One frame warms the
 * caches (each rank's brick, gradients, tables); then F frames (default 3)
 * are timed with a barrier between rendering and compositing, so that the
 * compositing time is the exchanges' own. Rank 0 prints the medians as
 *   anchor=volvis op=<op> dataset=<name> value=<number> unit=<unit>
 * with op mpi_frame_<method>_np<N> (the whole frame, as `volvis render`
 * sees it), mpi_render_cpu_max_np<N> (the CPU seconds of the busiest
 * rank's brick render: its render time with a core of its own, which a
 * shared, loaded machine cannot show in wall-clock time), mpi_render_max_np<N> (slowest rank's
 * brick render), mpi_composite_np<N> (slowest rank's compositing rounds), mpi_gather_np<N> and
 * mpi_composite_share_np<N> (compositing / frame).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"
#include "volvis/volvis.h"

static vv_volume *
upsample(const vv_volume *v, int side) {
    const int dims[3] = {side, side, side};
    vv_volume *o = NULL;
    if (vv_volume_new(&o, dims, VV_I16) != VV_OK)
        return NULL;
    int16_t *d = o->data;
    double sc[3];
    for (int a = 0; a < 3; a++) {
        sc[a] = (double)(v->dims[a] - 1) / (side - 1);
        o->spacing[a] = v->spacing[a] * sc[a];
        o->origin[a] = v->origin[a];
    }
    memcpy(o->direction, v->direction, sizeof o->direction);
    o->space = v->space;
#pragma omp parallel for schedule(static)
    for (int k = 0; k < side; k++)
        for (int j = 0; j < side; j++)
            for (int i = 0; i < side; i++) {
                const double p[3] = {i * sc[0], j * sc[1], k * sc[2]};
                int c[3];
                double f[3];
                for (int a = 0; a < 3; a++) {
                    c[a] = (int)p[a];
                    c[a] = c[a] > v->dims[a] - 2 ? v->dims[a] - 2 : c[a];
                    f[a] = p[a] - c[a];
                }
                double val = 0;
                for (int n = 0; n < 8; n++) {
                    const int di = n & 1, dj = (n >> 1) & 1, dk = n >> 2;
                    const double wgt =
                        (di ? f[0] : 1 - f[0]) * (dj ? f[1] : 1 - f[1]) * (dk ? f[2] : 1 - f[2]);
                    val += wgt * vv_volume_get(v, c[0] + di, c[1] + dj, c[2] + dk);
                }
                d[((size_t)k * side + j) * side + i] = (int16_t)lrint(val);
            }
    vv_volume_update_range(o);
    return o;
}

int
main(int argc, char **argv) {
    int rank = 0, size = 1;
    if (vv_parallel_init(&argc, &argv, &rank, &size) != VV_OK || !vv_parallel_available()) {
        fprintf(stderr, "bench_parallel: this build has no MPI\n");
        return 0;
    }
    const char *path = "../shared/data/volumes/ct_head.nrrd";
    int side = 512, px = 512, frames = 3, threads = 1;
    vv_parallel_options po;
    vv_parallel_options_init(&po);
    po.barrier = 1;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--size") == 0 && i + 1 < argc)
            px = atoi(argv[++i]);
        else if (strcmp(argv[i], "--side") == 0 && i + 1 < argc)
            side = atoi(argv[++i]);
        else if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc)
            frames = atoi(argv[++i]);
        else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (strcmp(argv[i], "--compositing") == 0 && i + 1 < argc)
            po.method = strcmp(argv[++i], "radix-k") == 0 ? VV_COMPOSITING_RADIX_K
                                                          : VV_COMPOSITING_BINARY_SWAP;
        else if (argv[i][0] != '-')
            path = argv[i];
    }
    if (frames < 1 || frames > 100)
        frames = 3;
    vv_threads_set(threads);
    vv_volume *src = NULL, *vol = NULL;
    if (vv_volume_load(&src, path, NULL) != VV_OK)
        bench_die("bench_parallel", path);
    vol = upsample(src, side);
    vv_volume_free(src);
    if (!vol)
        bench_die("bench_parallel", "upsample");
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = px;
    o.has_tf_range = 1;
    o.tf_lo = 100;
    o.tf_hi = 1500;
    vv_world *w = NULL;
    if (vv_world_new_for_volume(&w, vol, &o) != VV_OK)
        bench_die("bench_parallel", "world");
    vv_volume_free(vol);
    vv_parallel *par = NULL;
    if (vv_parallel_new(&par, NULL, &po) != VV_OK)
        bench_die("bench_parallel", "parallel");
    vv_image *img = NULL;
    if (rank == 0 && vv_image_new(&img, px, px) != VV_OK)
        bench_die("bench_parallel", "image");
    double tf[100], tr[100], tc[100], tg[100], tcpu[100];
    vv_parallel_stats st;
    for (int f = -1; f < frames; f++) {
        vv_parallel_agree(VV_OK); /* start together */
        const double t0 = bench_now(), c0 = bench_cpu_now();
        if (vv_parallel_render(par, w, &w->view, NULL, img, &st) != VV_OK)
            bench_die("bench_parallel", "render");
        const double t = bench_now() - t0;
        (void)c0;
        if (f >= 0) {
            tf[f] = t;
            tr[f] = st.max_render;
            tc[f] = st.max_composite;
            tg[f] = st.gather;
            /* CPU seconds of the busiest rank's brick render: its render
             * time on a core of its own (MPI waits spin, so the process's
             * CPU time over the frame would count them) */
            tcpu[f] = st.max_render_cpu;
        }
    }
    if (rank == 0) {
        char dataset[64], op[96];
        snprintf(dataset, sizeof dataset, "ct_head_%d_%dpx_t%d", side, px, threads);
        const double frame = bench_median(tf, frames), comp = bench_median(tc, frames);
        snprintf(op, sizeof op, "mpi_frame_%s_np%d",
                 po.method == VV_COMPOSITING_RADIX_K ? "radixk" : "bswap", size);
        bench_emit(op, dataset, frame, "s");
        snprintf(op, sizeof op, "mpi_render_max_np%d", size);
        bench_emit(op, dataset, bench_median(tr, frames), "s");
        snprintf(op, sizeof op, "mpi_render_cpu_max_np%d", size);
        bench_emit(op, dataset, bench_median(tcpu, frames), "s");
        snprintf(op, sizeof op, "mpi_composite_np%d", size);
        bench_emit(op, dataset, comp, "s");
        snprintf(op, sizeof op, "mpi_gather_np%d", size);
        bench_emit(op, dataset, bench_median(tg, frames), "s");
        snprintf(op, sizeof op, "mpi_composite_share_np%d", size);
        bench_emit(op, dataset, comp / frame, "fraction");
        fprintf(stderr, "bench_parallel: rank 0 brick %d..%d x %d..%d x %d..%d (%zu voxels)\n",
                st.brick_lo[0], st.brick_hi[0], st.brick_lo[1], st.brick_hi[1], st.brick_lo[2],
                st.brick_hi[2], st.brick_voxels);
    }
    vv_image_free(img);
    vv_parallel_free(par);
    vv_world_free(w);
    vv_parallel_finalize();
    return 0;
}
