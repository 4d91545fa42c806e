/*
 * bench_raycast: the shared benchmark view of ../shared/BENCHMARKS.md,
 * rendered by the ray caster, printed as
 *   anchor=volvis op=<op> dataset=<file> value=<number> unit=<unit>
 * so that ../shared/anchors/summarize.py can put it beside VTK and Teem.
 *
 * usage: bench_raycast VOLUME [--iso V] [--tf-lo A] [--tf-hi B] [--size N]
 *                      [--runs N] [--threads N] [--outdir DIR] [--step-vox S]
 *                      [--opacity O] [--modes composite,mip,iso]
 *                      [--option KEY=VALUE]...   (renderer options, e.g. early_termination=0.98)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;
#define emit(op, value, unit) bench_emit(op, dataset, value, unit)

typedef struct bench_cfg {
    double iso, tf_lo, tf_hi, step_vox, opacity;
    int size, runs, threads;
    const char *outdir;
    const char *modes;      /* comma list of modes to run */
    const char *options[8]; /* renderer options KEY=VALUE */
    int n_options;
} bench_cfg;

/* The peers' view: volume centred, eye at scale * 11 * normalize(1,-1.6,1). */
static void
setup_world(vv_world *w, vv_object *obj, const bench_cfg *cfg, vv_render_mode mode) {
    const vv_volume *v = obj->volume;
    double ext = 0, minsp = INFINITY;
    for (int a = 0; a < 3; a++) {
        double e = (v->dims[a] - 1) * v->spacing[a];
        ext = e > ext ? e : ext;
        minsp = v->spacing[a] < minsp ? v->spacing[a] : minsp;
    }
    double scale = ext / 2;
    vv_vec3 dir = vv_vec3_normalize(vv_vec3_make(1, -1.6, 1));
    w->view.eye = vv_vec3_scale(dir, scale * 11);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.up = vv_vec3_make(0, 0, 1);
    w->view.fov = vv_deg_to_rad(20);
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    w->view.width = w->view.height = cfg->size;
    w->background = vv_vec3_make(0, 0, 0);
    w->ambient = vv_vec3_make(1, 1, 1);
    obj->mode = mode;
    obj->step = cfg->step_vox;
    obj->isovalue = cfg->iso;
    obj->material.ambient = 0.1;
    obj->material.diffuse = 0.6;
    obj->material.specular = 0.3;
    obj->material.shininess = 30;
    obj->material.color = vv_vec3_make(1, 1, 1);
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

int
main(int argc, char **argv) {
    bench_cfg cfg = {NAN,    NAN, NAN, 0.5, 0.5, 512, 5, 0, "build/bench-out", "composite,mip,iso",
                     {NULL}, 0};
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
    if (!path || cfg.size < 1 || cfg.runs < 1) {
        fprintf(stderr,
                "usage: bench_raycast VOLUME [--iso V] [--tf-lo A] [--tf-hi B] "
                "[--size N] [--runs N] [--threads N] [--outdir DIR] [--modes composite,mip,iso] "
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
    for (int a = 0; a < 3; a++)
        vol->origin[a] = -(vol->dims[a] - 1) * vol->spacing[a] / 2.0;
    for (int a = 0; a < 9; a++)
        vol->direction[a] = a % 4 == 0;
    vol->modified++;
    char stem[256];
    snprintf(stem, sizeof stem, "%s", dataset);
    char *dot = strchr(stem, '.');
    if (dot)
        *dot = 0;
    printf("# %s %dx%dx%d %s, iso %g, ramp [%g, %g], threads %d\n", dataset, vol->dims[0],
           vol->dims[1], vol->dims[2], vv_voxel_type_name(vol->type), cfg.iso, cfg.tf_lo, cfg.tf_hi,
           vv_threads_get());

    vv_world *w;
    vv_object *obj;
    if (vv_world_new(&w) != VV_OK || vv_object_new_volume(&obj, vol, "bench") != VV_OK ||
        vv_world_add_object(w, obj) != VV_OK)
        bench_die("bench_raycast", "world");
    vv_light head;
    memset(&head, 0, sizeof head);
    head.type = VV_LIGHT_DIRECTIONAL;
    head.headlight = 1;
    head.color = vv_vec3_make(1, 1, 1);
    head.intensity = 1;
    vv_world_add_light(w, &head);

    vv_image *img;
    if (vv_image_new(&img, cfg.size, cfg.size) != VV_OK)
        bench_die("bench_raycast", "image");
    vv_render_options opt;
    vv_render_options_init(&opt);
    opt.threads = cfg.threads;

    static const struct {
        vv_render_mode mode;
        const char *name;
    } modes[] = {{VV_MODE_COMPOSITE, "composite"}, {VV_MODE_MIP, "mip"}, {VV_MODE_ISO, "iso"}};
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
        if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK) /* warm-up */
            bench_die("bench_raycast", "render");
        for (int i = 0; i < cfg.runs; i++) {
            a = bench_now();
            if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
                bench_die("bench_raycast", "render");
            times[i] = bench_now() - a;
        }
        qsort(times, (size_t)cfg.runs, sizeof(double), bench_cmp_double);
        double med = times[cfg.runs / 2];
        char op[64];
        snprintf(op, sizeof op, "dvr_%s_first_frame", modes[m].name);
        emit(op, first, "s");
        snprintf(op, sizeof op, "dvr_%s_frame", modes[m].name);
        emit(op, med, "s");
        snprintf(op, sizeof op, "dvr_%s_fps", modes[m].name);
        emit(op, 1.0 / med, "frames/s");
        save(img, &cfg, stem, modes[m].name);
        free(times);
        vv_renderer_free(r);
    }
    vv_image_free(img);
    vv_world_free(w);
    vv_volume_free(vol);
    return 0;
}
