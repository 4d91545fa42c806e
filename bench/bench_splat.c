/*
 * bench_splat: splatting against ray casting at the same view, transfer
 * function and lights (issue 15), printed as
 *   anchor=volvis op=<op> dataset=<name> value=<number> unit=<unit>
 *
 * Datasets: the voxelized nut and bolt of examples/nut_bolt.json (sparse:
 * two objects, composite shaded), neghip.slc with a transfer function that
 * keeps the top 10 % of the voxels (sparse), and the CT head
 * (ct_head.nrrd, dense) with its default scene, all composite shaded.
 * Each frame is rendered once to warm the caches (gradients, tables, voxel
 * lists), then timed --runs times; the median is reported.
 *
 * Ops: raycast_frame and splat_frame (s), the same in CPU seconds of all
 * threads (raycast_frame_cpu, splat_frame_cpu), splat_speedup (ray-cast time /
 * splat time), splats_per_s_per_thread (voxels of the lists splatted per
 * CPU second of all threads, steady under load; _wall: per wall second and
 * thread), footprints_per_s_per_thread (kernel slices rasterised, per CPU
 * second), splat_fraction_listed (voxels not skipped as empty / all),
 * splat_fraction_culled (footprints skipped by the occlusion map / those
 * considered).
 *
 * usage: bench_splat [--size N] [--threads N] [--runs N] [--quality Q] [--outdir DIR]
 *                    [--only nut_bolt|neghip|ct_head] [--volume FILE] [--option KEY=VALUE]...
 * --volume FILE measures that volume alone, in its default scene (shaded
 * composite): a large volume at a small --size is a minified view.
 * Run from the repository root (reads ../shared/data and examples/).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/splat/splat.h"
#include "util.h"
#include "volvis/volvis.h"

typedef struct cfg {
    int size, threads, runs, quality;
    const char *outdir, *only;
    const char *volume; /* --volume: this file instead of the three datasets */
    const char *options[8];
    int n_options;
} cfg;

/* Median wall-clock seconds of a frame; *cpu: median CPU seconds (all
 * threads), steadier than the wall clock on a loaded machine. */
static double
time_frame(vv_renderer *r, const vv_world *w, const cfg *c, vv_image *img, const char *what,
           double *cpu) {
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = c->threads;
    opt.quality = c->quality;
    if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK) /* warm */
        bench_die("bench_splat", what);
    double *t = malloc(sizeof(double) * 2 * (size_t)c->runs), *u = t + c->runs;
    for (int i = 0; i < c->runs; i++) {
        const double t0 = bench_now(), c0 = bench_cpu_now();
        if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
            bench_die("bench_splat", what);
        t[i] = bench_now() - t0;
        u[i] = bench_cpu_now() - c0;
    }
    const double med = bench_median(t, c->runs);
    *cpu = bench_median(u, c->runs);
    free(t);
    return med;
}

static void
run(const char *name, vv_world *w, const cfg *c) {
    w->view.width = w->view.height = c->size;
    vv_renderer *rc = NULL, *sp = NULL;
    if (vv_renderer_new(&rc, "raycast") != VV_OK || vv_renderer_new(&sp, "splat") != VV_OK)
        bench_die("bench_splat", "renderer");
    for (int i = 0; i < c->n_options; i++) {
        char kv[256];
        snprintf(kv, sizeof kv, "%s", c->options[i]);
        char *eq = strchr(kv, '=');
        if (!eq)
            bench_die("bench_splat", "--option needs KEY=VALUE");
        *eq = 0;
        if (vv_renderer_set_option(sp, kv, eq + 1) != VV_OK)
            bench_die("bench_splat", "--option");
    }
    vv_image *a = NULL, *b = NULL;
    if (vv_image_new(&a, c->size, c->size) != VV_OK || vv_image_new(&b, c->size, c->size) != VV_OK)
        bench_die("bench_splat", "image");
    double cr, cs;
    const double tr = time_frame(rc, w, c, a, "raycast", &cr);
    const double ts = time_frame(sp, w, c, b, "splat", &cs);
    const vv_splat_stats *st = vv_splat_stats_get(sp);
    const int nt = c->threads > 0 ? c->threads : vv_threads_get();
    bench_emit("raycast_frame", name, tr, "s");
    bench_emit("splat_frame", name, ts, "s");
    bench_emit("raycast_frame_cpu", name, cr, "s");
    bench_emit("splat_frame_cpu", name, cs, "s");
    bench_emit("splat_speedup", name, tr / ts, "x");
    /* per thread: per CPU second of all threads (on a loaded machine the
     * wall clock counts time the threads waited for a core) */
    bench_emit("splats_per_s_per_thread", name, (double)st->listed / cs, "voxels/s");
    bench_emit("footprints_per_s_per_thread", name, (double)st->footprints / cs, "footprints/s");
    bench_emit("splats_per_s_per_thread_wall", name, (double)st->listed / ts / nt, "voxels/s");
    bench_emit("splat_fraction_listed", name, (double)st->listed / (double)st->voxels, "fraction");
    bench_emit("splat_fraction_culled", name,
               (double)st->culled / (double)(st->culled + st->footprints + 1e-30), "fraction");
    printf("# %s: PSNR splat vs raycast %.2f dB; %llu voxels, %llu listed, %llu footprints, "
           "%llu culled, %llu sheets\n",
           name, vv_image_psnr(a, b), (unsigned long long)st->voxels,
           (unsigned long long)st->listed, (unsigned long long)st->footprints,
           (unsigned long long)st->culled, (unsigned long long)st->sheets);
    if (c->outdir) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s_raycast.png", c->outdir, name);
        vv_image_write_png(a, path, 1.0, 0);
        snprintf(path, sizeof path, "%s/%s_splat.png", c->outdir, name);
        vv_image_write_png(b, path, 1.0, 0);
    }
    vv_image_free(a);
    vv_image_free(b);
    vv_renderer_free(rc);
    vv_renderer_free(sp);
}

/* Lights and material of the shaded composite scenes. */
static void
shaded(vv_object *o) {
    o->mode = VV_MODE_COMPOSITE;
    o->shading = 1;
}

static void
bench_nut_bolt(const cfg *c) {
    vv_world *w = NULL;
    const double t0 = bench_now();
    if (vv_scene_load(&w, "examples/nut_bolt.json") != VV_OK)
        bench_die("bench_splat", "examples/nut_bolt.json");
    printf("# nut_bolt: voxelized in %.2f s\n", bench_now() - t0);
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->type != VV_OBJECT_VOLUME || !o->volume)
            continue;
        /* the occupancy field (0 outside, 1 inside): a sharp opaque ramp
         * at the surface, in the material's colour */
        const double lo = o->volume->range[0], hi = o->volume->range[1];
        vv_tf_init(&o->tf);
        vv_tf_add_opacity(&o->tf, lo + 0.4 * (hi - lo), 0.0);
        vv_tf_add_opacity(&o->tf, lo + 0.6 * (hi - lo), 1.0);
        vv_tf_add_color(&o->tf, lo, o->material.color);
        vv_tf_add_color(&o->tf, hi, o->material.color);
        o->segmentation = VV_SEG_TRANSFER_FUNCTION;
        shaded(o);
        printf("# nut_bolt: object '%s' %d x %d x %d\n", o->name, o->volume->dims[0],
               o->volume->dims[1], o->volume->dims[2]);
    }
    run("nut_bolt", w, c);
    vv_world_free(w);
}

/* The default scene of the volume file @p path turned 30 degrees and 20. */
static vv_world *
default_world_at(const char *path) {
    vv_volume *v = NULL;
    if (vv_volume_load(&v, path, NULL) != VV_OK)
        bench_die("bench_splat", path);
    vv_default_scene_options so;
    vv_default_scene_options_init(&so);
    so.azimuth = vv_deg_to_rad(30);
    so.elevation = vv_deg_to_rad(20);
    vv_world *w = NULL;
    if (vv_world_new_for_volume(&w, v, &so) != VV_OK)
        bench_die("bench_splat", path);
    vv_volume_free(v);
    return w;
}

static vv_world *
default_world(const char *rel) {
    char path[512];
    snprintf(path, sizeof path, "../shared/data/volumes/%s", rel);
    return default_world_at(path);
}

static void
bench_neghip(const cfg *c) {
    vv_world *w = default_world("neghip.slc");
    vv_object *o = w->objects[0];
    /* the value above which 10 % of the voxels lie */
    const vv_volume *v = o->volume;
    long hist[256] = {0};
    const size_t n = (size_t)v->dims[0] * v->dims[1] * v->dims[2];
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int i = 0; i < v->dims[0]; i++) {
                int b = (int)((vv_volume_get(v, i, j, k) - v->range[0]) /
                              (v->range[1] - v->range[0]) * 255.0);
                hist[b < 0 ? 0 : b > 255 ? 255 : b]++;
            }
    long acc = 0;
    int b10 = 255;
    while (b10 > 0 && acc + hist[b10] <= (long)(0.1 * (double)n))
        acc += hist[b10--];
    const double t = v->range[0] + (v->range[1] - v->range[0]) * (b10 + 1) / 255.0;
    vv_tf_init(&o->tf);
    vv_tf_add_opacity(&o->tf, t, 0.0);
    vv_tf_add_opacity(&o->tf, v->range[1], 0.8);
    vv_tf_add_color(&o->tf, t, vv_vec3_make(0.9, 0.5, 0.3));
    vv_tf_add_color(&o->tf, v->range[1], vv_vec3_make(1, 1, 0.9));
    o->segmentation = VV_SEG_TRANSFER_FUNCTION;
    shaded(o);
    printf("# neghip: TF from %.1f keeps %.1f %% of the voxels\n", t, 100.0 * (double)acc / n);
    run("neghip_10pct", w, c);
    vv_world_free(w);
}

static void
bench_ct_head(const cfg *c) {
    vv_world *w = default_world("ct_head.nrrd");
    shaded(w->objects[0]);
    run("ct_head", w, c);
    vv_world_free(w);
}

/* --volume PATH: any volume file, its default scene, shaded composite
 * (for minified views: a large volume at a small image size). */
static void
bench_volume(const cfg *c) {
    vv_world *w = default_world_at(c->volume);
    shaded(w->objects[0]);
    const char *name = strrchr(c->volume, '/');
    run(name ? name + 1 : c->volume, w, c);
    vv_world_free(w);
}

int
main(int argc, char **argv) {
    cfg c = {512, 2, 5, 2, NULL, NULL, NULL, {0}, 0};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!val) {
            fprintf(stderr, "bench_splat: %s needs a value\n", a);
            return 2;
        }
        if (!strcmp(a, "--size"))
            c.size = atoi(val);
        else if (!strcmp(a, "--threads"))
            c.threads = atoi(val);
        else if (!strcmp(a, "--runs"))
            c.runs = atoi(val);
        else if (!strcmp(a, "--quality"))
            c.quality = atoi(val);
        else if (!strcmp(a, "--outdir"))
            c.outdir = val;
        else if (!strcmp(a, "--only"))
            c.only = val;
        else if (!strcmp(a, "--volume"))
            c.volume = val;
        else if (!strcmp(a, "--option") && c.n_options < 8)
            c.options[c.n_options++] = val;
        else {
            fprintf(stderr, "usage: bench_splat [--size N] [--threads N] [--runs N] [--quality Q] "
                            "[--outdir DIR] [--only nut_bolt|neghip|ct_head] [--volume FILE] "
                            "[--option KEY=VALUE]...\n");
            return 2;
        }
        i++;
    }
    if (c.size < 1 || c.runs < 1 || c.threads < 1) {
        fprintf(stderr, "bench_splat: size, runs and threads must be >= 1\n");
        return 2;
    }
    vv_threads_set(c.threads);
    printf("# bench_splat: %d x %d, %d threads, quality %d (both renderers), median of %d runs\n",
           c.size, c.size, c.threads, c.quality, c.runs);
    if (c.volume) {
        bench_volume(&c);
        return 0;
    }
    if (!c.only || !strcmp(c.only, "nut_bolt"))
        bench_nut_bolt(&c);
    if (!c.only || !strcmp(c.only, "neghip"))
        bench_neghip(&c);
    if (!c.only || !strcmp(c.only, "ct_head"))
        bench_ct_head(&c);
    return 0;
}
