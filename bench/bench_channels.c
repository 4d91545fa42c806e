/*
 * bench_channels: several channels of one volume drawn in one pass by the
 * ray caster (vv_object_set_channels), against one channel alone and
 * against the same channels as separate objects of one World (issue 30's
 * targets: a 4-channel frame at most 2.5x a one-channel frame, and at
 * least 2x faster than 4 separate objects). Printed as
 *   anchor=volvis op=<op> dataset=<name> value=<number> unit=<unit>
 *
 * Data: a synthetic fluorescence stack, C channels of NX x NY x NZ u16
 * (default 4 of 512 x 512 x 128): each channel a few hundred Gaussian
 * spots (nuclei-like, 3..9 voxels across) on a dim noisy background,
 * spacing 0.2 x 0.2 x 0.5 um; the spots of each channel at places of its
 * own (dataset "spots": the channels cover C times the space one does, the
 * worst case for one pass), or with --colocalised at the same places in
 * every channel with sizes and brightness of their own (dataset "cells":
 * the channels label the same cells). Each channel's contrast limits
 * are its 0.5 % and 99.5 % quantiles (the defaults), its colour the default
 * set; view from the front, orthographic, SIZE^2 pixels (default 512).
 *
 * ops (times are medians of --runs renders after a warm-up render, the
 * configurations interleaved run by run):
 *   channels_one_frame         channel 0 alone (a one-channel object)
 *   channels_one_mip_frame     channel 0 alone, maximum intensity projection
 *   channels_<rule>_frame      all channels, one object, rule composite,
 *                              additive or maximum
 *   channels_separate_frame    the channels as C objects of one World
 *                              (composite, each with its channel's TF)
 *   channels_<rule>_over_one   composite, additive: ratio to channels_one_frame
 *                              (target <= 2.5)
 *   channels_maximum_over_one_mip  ratio to channels_one_mip_frame (target <= 2.5)
 *   channels_separate_over_composite  (target >= 2)
 *
 * usage: bench_channels [--channels C] [--dims NXxNYxNZ] [--size N]
 *                       [--runs N] [--threads N] [--outdir DIR] [--colocalised]
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"
#include "volvis/volvis.h"

static char dataset[64];

static uint64_t
next(uint64_t *s) {
    *s += 0x9E3779B97F4A7C15ull;
    uint64_t z = *s;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double
uniform(uint64_t *s) {
    return (double)(next(s) >> 11) * (1.0 / 9007199254740992.0);
}

/* One channel: background ~100 with noise, spots up to ~3000; the spots'
 * centres from the stream @p pos_seed (the same for every channel: the
 * channels label the same cells), their sizes, peaks and the noise from
 * @p seed. */
static vv_volume *
make_channel(const int dims[3], uint64_t seed, uint64_t pos_seed) {
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_U16) != VV_OK)
        bench_die("bench_channels", "volume");
    v->spacing[0] = v->spacing[1] = 0.2;
    v->spacing[2] = 0.5;
    uint16_t *d = v->data;
    const size_t nx = (size_t)dims[0], ny = (size_t)dims[1], nz = (size_t)dims[2];
    uint64_t s = seed, ps = pos_seed;
    for (size_t i = 0; i < nx * ny * nz; i++)
        d[i] = (uint16_t)(100 + (next(&s) & 31));
    int spots = (int)(300.0 * (double)(nx * ny * nz) / (512.0 * 512 * 128));
    for (int k = 0; k < spots; k++) {
        double cx = uniform(&ps) * (double)nx, cy = uniform(&ps) * (double)ny;
        double cz = uniform(&ps) * (double)nz, r = 1.5 + 3 * uniform(&s);
        double peak = 1500 + 1500 * uniform(&s);
        int R = (int)ceil(2.5 * r);
        for (int z = (int)cz - R; z <= (int)cz + R; z++)
            for (int y = (int)cy - R; y <= (int)cy + R; y++)
                for (int x = (int)cx - R; x <= (int)cx + R; x++) {
                    if (x < 0 || y < 0 || z < 0 || x >= (int)nx || y >= (int)ny || z >= (int)nz)
                        continue;
                    /* z in voxels of 0.5 um, x and y of 0.2: spots round in space */
                    double dx = x - cx, dy = y - cy, dz = (z - cz) * 2.5;
                    double g = peak * exp(-(dx * dx + dy * dy + dz * dz) / (2 * r * r));
                    size_t at = ((size_t)z * ny + (size_t)y) * nx + (size_t)x;
                    double val = d[at] + g;
                    d[at] = (uint16_t)(val > 65535 ? 65535 : val);
                }
    }
    vv_volume_update_range(v);
    return v;
}

static void
save(const vv_image *img, const char *outdir, const char *name) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.png", outdir, name);
    if (vv_image_write_png(img, path, 1.0, 0) != VV_OK)
        bench_die("bench_channels", path);
}

/* The configurations timed, each with its own renderer (its caches and
 * tables built by a warm-up render), interleaved run by run so that a slow
 * phase of a shared machine hits every one alike. */
enum { ONE, ONE_MIP, COMPOSITE, ADDITIVE, MAXIMUM, SEPARATE, NCONF };
static const char *const conf_name[NCONF] = {"one",      "one_mip", "composite",
                                             "additive", "maximum", "separate"};

static void
time_interleaved(vv_world *const w[NCONF], int threads, int runs, vv_image *img, const char *outdir,
                 double med[NCONF]) {
    vv_renderer *r[NCONF];
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = threads;
    for (int c = 0; c < NCONF; c++) {
        if (vv_renderer_new(&r[c], "raycast") != VV_OK)
            bench_die("bench_channels", "renderer");
        if (vv_renderer_render(r[c], w[c], &w[c]->view, &opt, img) != VV_OK)
            bench_die("bench_channels", "warm-up render");
        save(img, outdir, conf_name[c]);
    }
    double t[NCONF][64];
    for (int i = 0; i < runs; i++)
        for (int c = 0; c < NCONF; c++) {
            double t0 = bench_now();
            if (vv_renderer_render(r[c], w[c], &w[c]->view, &opt, img) != VV_OK)
                bench_die("bench_channels", "render");
            t[c][i] = bench_now() - t0;
        }
    for (int c = 0; c < NCONF; c++) {
        med[c] = bench_median(t[c], runs);
        vv_renderer_free(r[c]);
    }
}

/* A World framed on the volume, orthographic, SIZE^2. */
static vv_world *
framed_world(vv_volume *v0, int size) {
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = size;
    vv_world *w = NULL;
    if (vv_world_new_for_volume(&w, v0, &o) != VV_OK)
        bench_die("bench_channels", "world");
    w->view.projection = VV_PROJECTION_ORTHOGRAPHIC;
    vv_view_frame_box(&w->view, vv_world_bounds(w));
    return w;
}

int
main(int argc, char **argv) {
    int nc = 4, dims[3] = {512, 512, 128}, size = 512, runs = 3, threads = 0, coloc = 0;
    const char *outdir = "build/bench-out/channels";
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--channels") == 0 && i + 1 < argc)
            nc = atoi(argv[++i]);
        else if (strcmp(argv[i], "--dims") == 0 && i + 1 < argc) {
            if (sscanf(argv[++i], "%dx%dx%d", &dims[0], &dims[1], &dims[2]) != 3)
                nc = -1;
        } else if (strcmp(argv[i], "--size") == 0 && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (strcmp(argv[i], "--runs") == 0 && i + 1 < argc)
            runs = atoi(argv[++i]);
        else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (strcmp(argv[i], "--outdir") == 0 && i + 1 < argc)
            outdir = argv[++i];
        else if (strcmp(argv[i], "--colocalised") == 0)
            coloc = 1;
        else
            nc = -1;
    }
    if (nc < 2 || nc > VV_MAX_CHANNELS || dims[0] < 8 || dims[1] < 8 || dims[2] < 8 ||
        dims[0] > 4096 || dims[1] > 4096 || dims[2] > 4096 || size < 16 || size > 8192 ||
        runs < 1 || runs > 64 || threads < 0) {
        fprintf(stderr, "usage: bench_channels [--channels 2..16] [--dims NXxNYxNZ] [--size N] "
                        "[--runs 1..64] [--threads N] [--outdir DIR] [--colocalised]\n");
        return 2;
    }
    if (bench_mkdirs(outdir) != 0) {
        fprintf(stderr, "bench_channels: cannot create %s\n", outdir);
        return 1;
    }
    snprintf(dataset, sizeof dataset, "%s_%dch_%dx%dx%d_u16", coloc ? "cells" : "spots", nc,
             dims[0], dims[1], dims[2]);
    vv_volume *v[VV_MAX_CHANNELS];
    for (int c = 0; c < nc; c++)
        v[c] = make_channel(dims, 0x5EED0000u + (uint64_t)c,
                            coloc ? 0xCE11u : 0x5EED0000u + 16 + (uint64_t)c);
    vv_image *img = NULL;
    if (vv_image_new(&img, size, size) != VV_OK)
        bench_die("bench_channels", "image");

    /* all channels, one object: under each rule (its channel TFs are reused below) */
    vv_world *w[NCONF];
    w[COMPOSITE] = framed_world(v[0], size);
    vv_object *mo = w[COMPOSITE]->objects[0];
    if (vv_object_set_channels(mo, nc, v, NULL) != VV_OK)
        bench_die("bench_channels", "channels");
    for (int b = ADDITIVE; b <= MAXIMUM; b++) {
        if (vv_world_clone(&w[b], w[COMPOSITE]) != VV_OK)
            bench_die("bench_channels", "clone");
        w[b]->objects[0]->blend = b == ADDITIVE ? VV_BLEND_ADDITIVE : VV_BLEND_MAXIMUM;
    }
    /* channel 0 alone, with its channel TF, composite and MIP */
    w[ONE] = framed_world(v[0], size);
    w[ONE]->objects[0]->tf = mo->channels[0].tf;
    if (vv_world_clone(&w[ONE_MIP], w[ONE]) != VV_OK)
        bench_die("bench_channels", "clone");
    w[ONE_MIP]->objects[0]->mode = VV_MODE_MIP;
    /* the same channels as separate objects (composite) */
    w[SEPARATE] = framed_world(v[0], size);
    vv_world *sep = w[SEPARATE];
    sep->objects[0]->tf = mo->channels[0].tf;
    for (int c = 1; c < nc; c++) {
        vv_object *o = NULL;
        if (vv_object_new_volume(&o, v[c], NULL) != VV_OK)
            bench_die("bench_channels", "object");
        const vv_object *o0 = sep->objects[0]; /* the same transform, material, step */
        o->position = o0->position;
        o->orientation = o0->orientation;
        o->scale = o0->scale;
        o->material = o0->material;
        o->step = o0->step;
        o->shading = o0->shading;
        o->tf = mo->channels[c].tf;
        if (vv_world_add_object(sep, o) != VV_OK)
            bench_die("bench_channels", "add object");
    }
    double t[NCONF];
    time_interleaved(w, threads, runs, img, outdir, t);

    char op[64];
    for (int c = 0; c < NCONF; c++) {
        snprintf(op, sizeof op, "channels_%s_frame", conf_name[c]);
        bench_emit(op, dataset, t[c], "s");
    }
    bench_emit("channels_composite_over_one", dataset, t[COMPOSITE] / t[ONE], "x");
    bench_emit("channels_additive_over_one", dataset, t[ADDITIVE] / t[ONE], "x");
    bench_emit("channels_maximum_over_one_mip", dataset, t[MAXIMUM] / t[ONE_MIP], "x");
    bench_emit("channels_separate_over_composite", dataset, t[SEPARATE] / t[COMPOSITE], "x");
    for (int c = 0; c < NCONF; c++)
        vv_world_free(w[c]);
    for (int c = 0; c < nc; c++)
        vv_volume_free(v[c]);
    vv_image_free(img);
    return 0;
}
