/*
 * bench_time_steps: stepping through the time steps of a series already on
 * disk (issue 30's target: 20 steps of a 256^3 u16 series at 512^2, at
 * least 10 steps a second on 2 cores; previews allowed during play, full
 * quality when paused). Printed as
 *   anchor=volvis op=<op> dataset=<name> value=<number> unit=<unit>
 *
 * Data: a NIfTI-1 file (uncompressed, x, y, z, t) of T steps of N^3 u16
 * written here under --outdir (deleted after unless --keep): a bright ball
 * that moves along x from step to step and a second one that grows, on a
 * noisy background. Read through vv_time_series (the reader sandbox, one
 * step a read), the next step read ahead while the current one is drawn,
 * as `volvis render --time-range` does.
 *
 * ops (each a pass over all steps after a warm-up pass; steps a second):
 *   time_steps_read        reading alone (vv_time_series_get, no read-ahead)
 *   time_steps_full        play at full resolution, quality 2 (the `volvis
 *                          render --time-range` loop)
 *   time_steps_preview_2   play with the Navigator's 1/2-resolution ray cast
 *   time_steps_preview_4   play with the 1/4-resolution ray cast
 *   time_steps_first_frame_full  seconds of a full frame of a step not drawn
 *                          before (median over the steps of the full pass)
 *
 * Gradients are computed at the samples drawn (gradient_budget_mb=0), as
 * `volvis render --time-range` and `volvis animate` do for time steps;
 * --gradient-cache measures the ray caster's per-volume gradient cache
 * instead. --resident keeps every step in the cache (drawing alone).
 *
 * usage: bench_time_steps [--dims N] [--steps T] [--size S] [--threads N]
 *                         [--outdir DIR] [--keep] [--gradient-cache] [--resident]
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util.h"
#include "volvis/volvis.h"

static const char *prog = "bench_time_steps";

static void
put32(unsigned char *h, int off, int32_t v) {
    memcpy(h + off, &v, 4);
}
static void
put16(unsigned char *h, int off, int16_t v) {
    memcpy(h + off, &v, 2);
}
static void
putf(unsigned char *h, int off, float v) {
    memcpy(h + off, &v, 4);
}

/* Writes the series as a NIfTI-1 file (352-byte header, little-endian host). */
static void
write_series(const char *path, int n, int steps) {
    unsigned char h[352];
    memset(h, 0, sizeof h);
    put32(h, 0, 348);
    int16_t dim[8] = {4, (int16_t)n, (int16_t)n, (int16_t)n, (int16_t)steps, 1, 1, 1};
    for (int i = 0; i < 8; i++)
        put16(h, 40 + 2 * i, dim[i]);
    put16(h, 70, 512); /* DT_UINT16 */
    put16(h, 72, 16);
    float pixdim[8] = {1, 1, 1, 1, 0.1f, 1, 1, 1};
    for (int i = 0; i < 8; i++)
        putf(h, 76 + 4 * i, pixdim[i]);
    putf(h, 108, 352);
    putf(h, 112, 1);
    h[123] = 2 | 8; /* mm, s */
    memcpy(h + 344, "n+1", 4);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(h, 1, sizeof h, f) != sizeof h)
        bench_die(prog, path);
    size_t slice = (size_t)n * n;
    uint16_t *buf = malloc(slice * sizeof *buf);
    if (!buf)
        bench_die(prog, "memory");
    uint64_t s = 12345;
    for (int t = 0; t < steps; t++) {
        double cx = n * (0.25 + 0.5 * t / (steps > 1 ? steps - 1 : 1)), cy = n * 0.5, cz = n * 0.5,
               r1 = n * 0.12, r2 = n * (0.05 + 0.1 * t / (double)steps);
        for (int k = 0; k < n; k++) {
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    s = s * 6364136223846793005ull + 1442695040888963407ull;
                    double d1 =
                        sqrt((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz));
                    double d2 = sqrt((i - 0.7 * n) * (i - 0.7 * n) + (j - 0.3 * n) * (j - 0.3 * n) +
                                     (k - 0.6 * n) * (k - 0.6 * n));
                    double v = 200 + (double)(s >> 58);
                    if (d1 < r1)
                        v += 2500 * (1 - d1 / r1);
                    if (d2 < r2)
                        v += 1800;
                    buf[(size_t)j * n + i] = (uint16_t)v;
                }
            if (fwrite(buf, sizeof *buf, slice, f) != slice)
                bench_die(prog, path);
        }
    }
    free(buf);
    if (fclose(f) != 0)
        bench_die(prog, path);
}

/* One pass over every step; returns steps a second. @p kind < 0: reading
 * alone; else the representation drawn. *@p first gets the median frame
 * time when not NULL. */
static double
pass(vv_time_series *ts, vv_world *w, vv_preview *pv, int kind, int size, double *first) {
    const int steps = vv_time_series_count(ts);
    double *frame = malloc((size_t)steps * sizeof *frame);
    vv_image *img = NULL;
    int pw = size, ph = size;
    if (kind >= 0) {
        vv_preview_size((vv_preview_kind)kind, size, size, &pw, &ph);
        if (vv_image_new(&img, pw, ph) != VV_OK)
            bench_die(prog, "image");
    }
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.quality = 2;
    double t0 = bench_now();
    for (int t = 0; t < steps; t++) {
        vv_volume *v = NULL;
        if (vv_time_series_get(ts, t, &v) != VV_OK)
            bench_die(prog, "time step");
        if (kind >= 0) {
            vv_time_series_prefetch(ts, t + 1);
            if (vv_object_replace_volumes(w->objects[0], 1, &v) != VV_OK)
                bench_die(prog, "replace");
            double f0 = bench_now();
            if (vv_preview_render(pv, w, &w->view, (vv_preview_kind)kind, &ro, img) != VV_OK)
                bench_die(prog, "render");
            frame[t] = bench_now() - f0;
        }
        vv_volume_free(v);
    }
    double secs = bench_now() - t0;
    if (first)
        *first = bench_median(frame, steps);
    free(frame);
    vv_image_free(img);
    return steps / secs;
}

int
main(int argc, char **argv) {
    int n = 256, steps = 20, size = 512, threads = 0, keep = 0, gradients_on_the_fly = 1;
    int resident = 0; /* 1: every step stays in the cache (drawing alone after the warm-up) */
    const char *outdir = "build/bench-out/time_steps";
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--dims") && i + 1 < argc)
            n = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--steps") && i + 1 < argc)
            steps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--size") && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--outdir") && i + 1 < argc)
            outdir = argv[++i];
        else if (!strcmp(argv[i], "--keep"))
            keep = 1;
        else if (!strcmp(argv[i], "--gradient-cache"))
            gradients_on_the_fly = 0;
        else if (!strcmp(argv[i], "--resident"))
            resident = 1;
        else {
            fprintf(stderr,
                    "usage: %s [--dims N] [--steps T] [--size S] [--threads N] [--outdir DIR] "
                    "[--keep] [--gradient-cache] [--resident]\n",
                    prog);
            return 2;
        }
    }
    if (n < 8 || n > 1024 || steps < 2 || steps > 1000 || size < 16 || size > 4096) {
        fprintf(stderr, "%s: --dims 8..1024, --steps 2..1000, --size 16..4096\n", prog);
        return 2;
    }
    if (threads > 0)
        vv_threads_set(threads);
    if (bench_mkdirs(outdir) != 0)
        bench_die(prog, outdir);
    char path[4096], dataset[64];
    snprintf(path, sizeof path, "%s/series_%d_%d.nii", outdir, n, steps);
    snprintf(dataset, sizeof dataset, "series%dx%d_u16_%dpx", n, steps, size);
    double tw = bench_now();
    write_series(path, n, steps);
    fprintf(stderr, "%s: wrote %s (%d steps of %d^3 u16) in %.1f s\n", prog, path, steps, n,
            bench_now() - tw);

    vv_time_series *ts = NULL;
    uint64_t step_bytes = (uint64_t)n * n * n * 2;
    if (vv_time_series_open(&ts, path, NULL, resident ? step_bytes * (uint64_t)steps : 0) != VV_OK)
        bench_die(prog, path);
    vv_volume *v0 = NULL;
    if (vv_time_series_get(ts, 0, &v0) != VV_OK)
        bench_die(prog, "step 0");
    vv_default_scene_options so;
    vv_default_scene_options_init(&so);
    so.width = so.height = size;
    vv_world *w = NULL;
    if (vv_world_new_for_volume(&w, v0, &so) != VV_OK)
        bench_die(prog, "world");
    vv_volume_free(v0);
    vv_preview *pv = NULL;
    if (vv_preview_new(&pv, "raycast") != VV_OK)
        bench_die(prog, "preview");
    if (gradients_on_the_fly &&
        vv_renderer_set_option(vv_preview_final_renderer(pv), "gradient_budget_mb", "0") != VV_OK)
        bench_die(prog, "gradient_budget_mb");

    static const struct {
        const char *op;
        int kind;
    } ops[] = {{"time_steps_read", -1},
               {"time_steps_full", VV_PREVIEW_FULL},
               {"time_steps_preview_2", VV_PREVIEW_RAYCAST_2},
               {"time_steps_preview_4", VV_PREVIEW_RAYCAST_4}};
    for (size_t o = 0; o < sizeof ops / sizeof ops[0]; o++) {
        double first = 0;
        pass(ts, w, pv, ops[o].kind, size, NULL); /* warm-up: the renderers' caches */
        double rate = pass(ts, w, pv, ops[o].kind, size, &first);
        bench_emit(ops[o].op, dataset, rate, "steps/s");
        if (ops[o].kind == VV_PREVIEW_FULL)
            bench_emit("time_steps_first_frame_full", dataset, first, "s");
        fprintf(stderr, "%s: %s: %.2f steps a second (target >= 10 while playing)\n", prog,
                ops[o].op, rate);
    }
    vv_preview_free(pv);
    vv_world_free(w);
    vv_time_series_free(ts);
    if (!keep)
        unlink(path);
    return 0;
}
