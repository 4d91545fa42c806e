/*
 * bench_raycast: the shared benchmark view of ../shared/BENCHMARKS.md,
 * rendered by the ray caster, printed as
 *   anchor=volvis op=<op> dataset=<file> value=<number> unit=<unit>
 * so that ../shared/anchors/summarize.py can put it beside VTK and Teem.
 * Composite also prints the physical anchor: samples and shaded samples a
 * frame (vv_render_stats), shaded samples per second and core, the same
 * kernel's peak on one core (peak_shaded_rate), their ratio, and the frame
 * every shaded sample at the peak would take (docs/rendering.md), and the
 * rate as a fraction of the machine's: trilinear samples a second of one
 * core along rays through a volume of the same voxel type and largest
 * dimension, at the widest vector ISA the processor has (common/limit.h,
 * bench_limit).
 *
 * usage: bench_raycast VOLUME [--iso V] [--tf-lo A] [--tf-hi B] [--size N]
 *                      [--runs N] [--threads N] [--outdir DIR] [--step-vox S]
 *                      [--opacity O] [--modes composite,mip,iso,minip,xray] [--quality Q]
 *                      [--option KEY=VALUE]...   (renderer options, e.g. early_termination=0.98)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "common/bench_scene.h"
#include "common/limit.h"
#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;
#define emit(op, value, unit) bench_emit(op, dataset, value, unit)

typedef struct bench_cfg {
    double iso, tf_lo, tf_hi, step_vox, opacity;
    int size, runs, threads, quality;
    const char *outdir;
    const char *modes;      /* comma list of modes to run */
    const char *options[8]; /* renderer options KEY=VALUE */
    int n_options;
} bench_cfg;

/* The peers' view: volume centred, eye at scale * 11 * normalize(1,-1.6,1)
 * (vvb_peer_view). */
static void
setup_world(vv_world *w, vv_object *obj, const bench_cfg *cfg, vv_render_mode mode) {
    const vv_volume *v = obj->volume;
    double minsp = INFINITY;
    for (int a = 0; a < 3; a++)
        minsp = v->spacing[a] < minsp ? v->spacing[a] : minsp;
    vvb_peer_view(w, obj, cfg->size, cfg->size);
    obj->mode = mode;
    obj->step = cfg->step_vox;
    obj->isovalue = cfg->iso;
    obj->segmentation = VV_SEG_TRANSFER_FUNCTION;
    vv_tf_init(&obj->tf);
    obj->tf.opacity_unit_distance = minsp;
    if (mode == VV_MODE_COMPOSITE) {
        vv_tf_add_opacity(&obj->tf, cfg->tf_lo, 0.0);
        vv_tf_add_opacity(&obj->tf, cfg->tf_hi, cfg->opacity);
        vv_tf_add_color(&obj->tf, cfg->tf_lo, vv_vec3_make(1, 1, 1));
        vv_tf_add_color(&obj->tf, cfg->tf_hi, vv_vec3_make(1, 1, 1));
        obj->shading = 1;
    } else {
        vv_tf_add_opacity(&obj->tf, cfg->tf_lo, 1.0);
        vv_tf_add_opacity(&obj->tf, cfg->tf_hi, 1.0);
        vv_tf_add_color(&obj->tf, cfg->tf_lo, vv_vec3_make(0, 0, 0));
        vv_tf_add_color(&obj->tf, cfg->tf_hi, vv_vec3_make(1, 1, 1));
        obj->shading = mode == VV_MODE_ISO;
    }
}

static void
save(const vv_image *img, const bench_cfg *cfg, const char *stem, const char *mode) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s_volvis_%s.png", cfg->outdir, stem, mode);
    if (vv_image_write_png(img, path, 1.0, 0) != VV_OK)
        bench_die("bench_raycast", "write png");
    printf("# image %s\n", path);
}

/* The machine's limit for @p v's samples: trilinear samples a second of one
 * core along rays through a cube of @p v's largest dimension and voxel type
 * (8-bit as u8, 16-bit as u16, others as f32), at the widest ISA; 0 when
 * out of memory. */
static double
machine_rate(const vv_volume *v) {
    int n = v->dims[0];
    n = v->dims[1] > n ? v->dims[1] : n;
    n = v->dims[2] > n ? v->dims[2] : n;
    const size_t bytes = vv_voxel_type_size(v->type);
    bench_limit_type t = bytes == 1   ? BENCH_LIMIT_U8
                         : bytes == 2 ? BENCH_LIMIT_U16
                                      : BENCH_LIMIT_F32;
    bench_limit_case *c = bench_limit_case_new(t, n < 32 ? 32 : n, BENCH_LIMIT_RAYS);
    if (!c)
        return 0;
    double r = bench_limit_trilinear(c, bench_isa_widest(), 0.3);
    bench_limit_case_free(c);
    return r;
}

/* The physical anchor's peak: shaded samples per second of one thread on
 * a synthetic volume of the dataset's voxel type small enough to stay in
 * cache (48^3, a smooth field over the dataset's range), every sample
 * visible (a flat, faint opacity: no ray terminates early) and every pixel
 * on it: the same kernel, classification, gradients, shading and
 * compositing, with nothing skipped and no memory stalls. */
static double
peak_shaded_rate(const vv_volume *like, const bench_cfg *cfg) {
    const int dims[3] = {48, 48, 48};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, like->type) != VV_OK)
        bench_die("bench_raycast", "peak volume");
    const double lo = like->range[0], hi = like->range[1];
    for (int k = 0; k < 48; k++)
        for (int j = 0; j < 48; j++)
            for (int i = 0; i < 48; i++)
                vv_volume_set(v, i, j, k,
                              lo + (hi - lo) * (0.5 + 0.45 * sin(0.31 * i) * cos(0.23 * j) *
                                                          sin(0.17 * k + 0.5)));
    for (int a = 0; a < 3; a++)
        v->origin[a] = -23.5;
    vv_volume_update_range(v);
    vv_world *w;
    vv_object *obj;
    if (vvb_volume_world(&w, &obj, v, "peak") != VV_OK)
        bench_die("bench_raycast", "peak world");
    bench_cfg pc = *cfg;
    pc.size = 256;
    setup_world(w, obj, &pc, VV_MODE_COMPOSITE);
    w->view.fov = vv_deg_to_rad(9); /* every pixel on the cube */
    vv_tf_init(&obj->tf);
    obj->tf.opacity_unit_distance = 1;
    vv_tf_add_opacity(&obj->tf, v->range[0], 0.02);
    vv_tf_add_opacity(&obj->tf, v->range[1], 0.02);
    vv_image *img;
    vv_renderer *r;
    if (vv_image_new(&img, pc.size, pc.size) != VV_OK || vv_renderer_new(&r, "raycast") != VV_OK)
        bench_die("bench_raycast", "peak renderer");
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = 1;
    vv_render_stats st = {0};
    opt.stats = &st;
    if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK) /* warm-up, and the count */
        bench_die("bench_raycast", "peak render");
    opt.stats = NULL;
    double best = INFINITY;
    for (int i = 0; i < 3; i++) {
        const double a = bench_now();
        if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
            bench_die("bench_raycast", "peak render");
        const double t = bench_now() - a;
        best = t < best ? t : best;
    }
    if (st.samples != st.shaded || st.shaded < (uint64_t)pc.size * pc.size * 48)
        bench_die("bench_raycast", "peak: not every sample shaded");
    vv_renderer_free(r);
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(v);
    return (double)st.shaded / best;
}

int
main(int argc, char **argv) {
    bench_cfg cfg = {
        NAN, NAN, NAN, 0.5, 0.5, 512, 5, 0, 2, "build/bench-out", "composite,mip,iso", {NULL}, 0};
    const char *path = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (a[0] != '-') {
            path = a;
            continue;
        }
        if (!val) {
            fprintf(stderr, "bench_raycast: %s needs a value\n", a);
            return 2;
        }
        if (!strcmp(a, "--iso"))
            cfg.iso = atof(val);
        else if (!strcmp(a, "--tf-lo"))
            cfg.tf_lo = atof(val);
        else if (!strcmp(a, "--tf-hi"))
            cfg.tf_hi = atof(val);
        else if (!strcmp(a, "--size"))
            cfg.size = atoi(val);
        else if (!strcmp(a, "--runs"))
            cfg.runs = atoi(val);
        else if (!strcmp(a, "--threads"))
            cfg.threads = atoi(val);
        else if (!strcmp(a, "--quality"))
            cfg.quality = atoi(val);
        else if (!strcmp(a, "--outdir"))
            cfg.outdir = val;
        else if (!strcmp(a, "--step-vox"))
            cfg.step_vox = atof(val);
        else if (!strcmp(a, "--option") && cfg.n_options < 8)
            cfg.options[cfg.n_options++] = val;
        else if (!strcmp(a, "--modes"))
            cfg.modes = val;
        else if (!strcmp(a, "--opacity"))
            cfg.opacity = atof(val);
        else {
            fprintf(stderr, "bench_raycast: unknown option %s\n", a);
            return 2;
        }
        i++;
    }
    if (!path || cfg.size < 1 || cfg.runs < 1 || cfg.quality < 0 || cfg.quality > 2) {
        fprintf(stderr, "usage: bench_raycast VOLUME [--iso V] [--tf-lo A] [--tf-hi B] "
                        "[--size N] [--runs N] [--threads N] [--outdir DIR]\n"
                        "       [--modes composite,mip,iso,minip,xray] [--quality Q] "
                        "[--option KEY=VALUE]\n");
        return 2;
    }
    dataset = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    bench_mkdirs(cfg.outdir);
    if (cfg.threads > 0)
        vv_threads_set(cfg.threads);

    double t0 = bench_now();
    vv_volume *vol;
    if (vv_volume_load(&vol, path, NULL) != VV_OK)
        bench_die("bench_raycast", path);
    emit("load", bench_now() - t0, "s");
    /* the peers' defaults: iso (min+max)/2, ramp [min, max] */
    if (isnan(cfg.iso))
        cfg.iso = 0.5 * (vol->range[0] + vol->range[1]);
    if (isnan(cfg.tf_lo))
        cfg.tf_lo = vol->range[0];
    if (isnan(cfg.tf_hi))
        cfg.tf_hi = vol->range[1];
    vvb_center(vol);
    char stem[256];
    snprintf(stem, sizeof stem, "%s", dataset);
    char *dot = strchr(stem, '.');
    if (dot)
        *dot = 0;
    printf("# %s %dx%dx%d %s, iso %g, ramp [%g, %g], threads %d, quality %d\n", dataset,
           vol->dims[0], vol->dims[1], vol->dims[2], vv_voxel_type_name(vol->type), cfg.iso,
           cfg.tf_lo, cfg.tf_hi, vv_threads_get(), cfg.quality);

    vv_world *w;
    vv_object *obj;
    if (vvb_volume_world(&w, &obj, vol, "bench") != VV_OK)
        bench_die("bench_raycast", "world");

    vv_image *img;
    if (vv_image_new(&img, cfg.size, cfg.size) != VV_OK)
        bench_die("bench_raycast", "image");
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = cfg.threads;
    opt.quality = cfg.quality;

    static const struct {
        vv_render_mode mode;
        const char *name;
    } modes[] = {{VV_MODE_COMPOSITE, "composite"},
                 {VV_MODE_MIP, "mip"},
                 {VV_MODE_ISO, "iso"},
                 {VV_MODE_MINIP, "minip"},
                 {VV_MODE_XRAY, "xray"}};
    for (size_t m = 0; m < sizeof modes / sizeof modes[0]; m++) {
        if (!strstr(cfg.modes, modes[m].name))
            continue;
        setup_world(w, obj, &cfg, modes[m].mode);
        vv_renderer *r;
        if (vv_renderer_new(&r, "raycast") != VV_OK)
            bench_die("bench_raycast", "renderer");
        for (int o = 0; o < cfg.n_options; o++) {
            char key[128];
            const char *eq = strchr(cfg.options[o], '=');
            if (!eq || (size_t)(eq - cfg.options[o]) >= sizeof key) {
                fprintf(stderr, "bench_raycast: --option needs KEY=VALUE\n");
                return 2;
            }
            memcpy(key, cfg.options[o], (size_t)(eq - cfg.options[o]));
            key[eq - cfg.options[o]] = 0;
            if (vv_renderer_set_option(r, key, eq + 1) != VV_OK)
                bench_die("bench_raycast", "option");
        }
        /* first frame: a fresh renderer, so gradients and subvolumes are built */
        double a = bench_now();
        if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
            bench_die("bench_raycast", "render");
        double first = bench_now() - a;
        double *times = malloc(sizeof(double) * (size_t)cfg.runs);
        double *util = malloc(sizeof(double) * (size_t)cfg.runs);
        if (!times || !util)
            bench_die("bench_raycast", "out of memory");
        vv_render_stats work = {0};
        opt.stats = &work; /* (the same counts every frame) */
        if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK) /* warm-up */
            bench_die("bench_raycast", "render");
        opt.stats = NULL;
        for (int i = 0; i < cfg.runs; i++) {
            const double c0 = bench_cpu_now();
            a = bench_now();
            if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
                bench_die("bench_raycast", "render");
            times[i] = bench_now() - a;
            util[i] = (bench_cpu_now() - c0) / (times[i] > 1e-9 ? times[i] : 1e-9);
        }
        qsort(times, (size_t)cfg.runs, sizeof(double), bench_cmp_double);
        qsort(util, (size_t)cfg.runs, sizeof(double), bench_cmp_double);
        double med = times[cfg.runs / 2];
        char op[64];
        snprintf(op, sizeof op, "dvr_%s_first_frame", modes[m].name);
        emit(op, first, "s");
        snprintf(op, sizeof op, "dvr_%s_frame", modes[m].name);
        emit(op, med, "s");
        snprintf(op, sizeof op, "dvr_%s_fps", modes[m].name);
        emit(op, 1.0 / med, "frames/s");
        /* process CPU seconds over wall seconds of a frame (median), as the
         * anchors' bench_vtk.py reports it: on a loaded machine the CPU
         * time a frame took says more than its wall time */
        snprintf(op, sizeof op, "dvr_%s_cpu_per_wall", modes[m].name);
        emit(op, util[cfg.runs / 2], "ratio");
        if (modes[m].mode == VV_MODE_COMPOSITE && work.samples) {
            /* the physical anchor: shaded samples per second and core
             * against the same kernel's peak on one core */
            const int nt = cfg.threads > 0 ? cfg.threads : vv_threads_get();
            const double rate = (double)work.shaded / med / nt;
            const double peak = peak_shaded_rate(vol, &cfg);
            emit("dvr_composite_samples", (double)work.samples, "samples");
            emit("dvr_composite_shaded", (double)work.shaded, "samples");
            emit("dvr_composite_shaded_per_s_per_core", rate, "samples/s");
            emit("dvr_composite_peak_shaded_per_s_per_core", peak, "samples/s");
            emit("dvr_composite_of_peak", rate / peak, "x");
            emit("dvr_composite_floor_frame", (double)work.shaded / peak / nt, "s");
            const double machine = machine_rate(vol);
            if (machine > 0) {
                emit("dvr_composite_machine_trilinear_per_s_per_core", machine, "samples/s");
                emit("dvr_composite_of_machine", rate / machine, "x");
            }
        }
        save(img, &cfg, stem, modes[m].name);
        free(times);
        free(util);
        vv_renderer_free(r);
    }
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(vol);
    return 0;
}
