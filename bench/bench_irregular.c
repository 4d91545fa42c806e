/*
 * bench_irregular: the irregular renderer on grid files at the view of the
 * VTK peers (../shared/anchors/grids/grids_common.py: focal point the
 * bounding-box centre, eye = centre + scale * 11 * normalize(1, -1.6, 1)
 * with scale half the largest extent, up +z, 20 degrees, 512^2, black;
 * transfer function white, opacity 0 at tf_lo rising to 0.5 at tf_hi per
 * unit-frac x the largest extent, unshaded, per-file fractions as in its
 * TF_DEFAULTS), printed as
 *   anchor=volvis op=<op> dataset=<file> value=<number> unit=<unit>
 * A regular volume (.slc, .nrrd, ...) is split into tetrahedra (6 a cube)
 * and also rendered by the ray caster at the same view, with the PSNR
 * between the two and the time ratio.
 *
 * usage: bench_irregular FILE... [--runs N] [--threads N] [--size N]
 *                        [--outdir DIR] [--modes composite,mip]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"
#include "volvis/volvis.h"

typedef struct tf_default {
    const char *file;
    double lo, hi, unit;
} tf_default;

static const tf_default tf_defaults[] = {
    {"hyper.dx", 0.1, 1.0, 0.2},
    {"fire_ug.vtu", 0.1, 1.0, 0.05},
    {"bluntfinxyz.bin", 0.2, 1.0, 0.02},
    {"combxyz.bin", 0.3, 1.0, 0.1},
    {"levitus_climatology.cdf", 0.1, 1.0, 0.1},
    {"neghip.slc", 0.1, 1.0, 1.0 / 65.0},
};

static const char *
base_name(const char *p) {
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

static void
view_for_bounds(vv_world *w, vv_box b, int size) {
    vv_vec3 c = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
    double scale = 0.5 * fmax(b.max.x - b.min.x, fmax(b.max.y - b.min.y, b.max.z - b.min.z));
    vv_vec3 dir = vv_vec3_normalize(vv_vec3_make(1, -1.6, 1));
    w->view.eye = vv_vec3_add(c, vv_vec3_scale(dir, scale * 11));
    w->view.at = c;
    w->view.up = vv_vec3_make(0, 0, 1);
    w->view.fov = vv_deg_to_rad(20);
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    w->view.width = w->view.height = size;
    w->background = vv_vec3_make(0, 0, 0);
    w->ambient = vv_vec3_make(1, 1, 1);
}

/* The peers' ramp. VTK's unstructured integrators read the opacity a of
 * the transfer function as the attenuation a / unit per world unit, where
 * VolVis reads it as 1 - (1 - a)^(d / unit), an attenuation of
 * -ln(1 - a) / unit: the VolVis ramp is written with 128 points of
 * 1 - exp(-a) so that both integrate the same attenuation. */
static void
set_tf(vv_object *o, double lo, double hi, const tf_default *d, vv_box b) {
    const double ext = fmax(b.max.x - b.min.x, fmax(b.max.y - b.min.y, b.max.z - b.min.z));
    const double a = lo + d->lo * (hi - lo), z = lo + d->hi * (hi - lo);
    vv_tf_init(&o->tf);
    o->tf.opacity_unit_distance = d->unit * ext;
    for (int i = 0; i <= 128; i++) {
        const double x = a + (z - a) * i / 128.0;
        vv_tf_add_opacity(&o->tf, x, 1 - exp(-0.5 * i / 128.0));
    }
    vv_tf_add_color(&o->tf, lo, vv_vec3_make(1, 1, 1));
    o->shading = 0;
}

static double
render_time(vv_renderer *r, const vv_world *w, int threads, vv_image *img) {
    vv_render_options o;
    vv_render_options_init(&o);
    o.threads = threads;
    double t0 = bench_now();
    if (vv_renderer_render(r, w, &w->view, &o, img) != VV_OK)
        bench_die("bench_irregular", "render");
    return bench_now() - t0;
}

int
main(int argc, char **argv) {
    int runs = 3, threads = 2, size = 512;
    const char *outdir = NULL, *modes = "composite,mip";
    const char *files[32];
    int nf = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--runs") && i + 1 < argc)
            runs = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--size") && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--outdir") && i + 1 < argc)
            outdir = argv[++i];
        else if (!strcmp(argv[i], "--modes") && i + 1 < argc)
            modes = argv[++i];
        else if (nf < 32)
            files[nf++] = argv[i];
    }
    if (nf == 0 || runs < 1 || size < 8) {
        fprintf(stderr, "usage: bench_irregular FILE... [--runs N] [--threads N] [--size N] "
                        "[--outdir DIR] [--modes composite,mip]\n");
        return 2;
    }
    for (int fi = 0; fi < nf; fi++) {
        const char *ds = base_name(files[fi]);
        const tf_default *d = &tf_defaults[0];
        for (size_t k = 0; k < sizeof tf_defaults / sizeof tf_defaults[0]; k++)
            if (!strcmp(tf_defaults[k].file, ds))
                d = &tf_defaults[k];
        vv_grid *g = NULL;
        vv_volume *vol = NULL;
        double t0 = bench_now();
        const int is_grid = vv_grid_file_detect(files[fi], NULL);
        if (is_grid) {
            if (vv_grid_load(&g, files[fi]) != VV_OK)
                bench_die("bench_irregular", files[fi]);
        } else {
            if (vv_volume_load(&vol, files[fi], NULL) != VV_OK ||
                vv_grid_new_from_volume(&g, vol, 1) != VV_OK)
                bench_die("bench_irregular", files[fi]);
        }
        bench_emit("irregular_load_time", ds, bench_now() - t0, "s");
        vv_world *w = NULL;
        vv_object *o = NULL;
        if (vv_world_new(&w) != VV_OK || vv_object_new_grid(&o, g, NULL, "grid") != VV_OK)
            bench_die("bench_irregular", "world");
        const int f = vv_object_grid_field(o);
        const double lo = g->fields[f].range[0], hi = g->fields[f].range[1];
        const vv_box b = vv_grid_bounds(g);
        set_tf(o, lo, hi, d, b);
        view_for_bounds(w, b, size);
        vv_world_add_object(w, o);
        vv_image *img = NULL, *ref = NULL;
        vv_image_new(&img, size, size);
        vv_image_new(&ref, size, size);
        char mlist[64];
        snprintf(mlist, sizeof mlist, "%s", modes);
        for (char *m = strtok(mlist, ","); m; m = strtok(NULL, ",")) {
            o->mode = !strcmp(m, "mip") ? VV_MODE_MIP : VV_MODE_COMPOSITE;
            vv_renderer *r = NULL;
            if (vv_renderer_new(&r, "irregular") != VV_OK)
                bench_die("bench_irregular", "renderer");
            char op[128];
            snprintf(op, sizeof op, "irregular_%s_first_frame_time", m);
            bench_emit(op, ds, render_time(r, w, threads, img), "s");
            double ts[16];
            const int n = runs < 16 ? runs : 16;
            for (int k = 0; k < n; k++)
                ts[k] = render_time(r, w, threads, img);
            const double t_ir = bench_median(ts, n);
            snprintf(op, sizeof op, "irregular_%s_time", m);
            bench_emit(op, ds, t_ir, "s");
            if (outdir) {
                char path[1024];
                snprintf(path, sizeof path, "%s/irregular_%s_%s.png", outdir, m, ds);
                vv_image_write_png(img, path, 1.0, 0);
            }
            vv_renderer_free(r);
            if (vol) {
                /* the ray caster on the volume at the same view and TF */
                vv_world *wv = NULL;
                vv_object *ov = NULL;
                if (vv_world_new(&wv) != VV_OK || vv_object_new_volume(&ov, vol, "v") != VV_OK)
                    bench_die("bench_irregular", "volume world");
                ov->tf = o->tf;
                ov->mode = o->mode;
                ov->shading = 0;
                wv->view = w->view;
                wv->background = w->background;
                vv_world_add_object(wv, ov);
                vv_renderer *rc = NULL;
                vv_renderer_new(&rc, "raycast");
                render_time(rc, wv, threads, ref);
                for (int k = 0; k < n; k++)
                    ts[k] = render_time(rc, wv, threads, ref);
                const double t_rc = bench_median(ts, n);
                snprintf(op, sizeof op, "raycast_%s_time", m);
                bench_emit(op, ds, t_rc, "s");
                snprintf(op, sizeof op, "irregular_over_raycast_%s_time_ratio", m);
                bench_emit(op, ds, t_ir / t_rc, "x");
                snprintf(op, sizeof op, "irregular_vs_raycast_%s_psnr", m);
                bench_emit(op, ds, vv_image_psnr(ref, img), "dB");
                if (outdir) {
                    char path[1024];
                    snprintf(path, sizeof path, "%s/raycast_%s_%s.png", outdir, m, ds);
                    vv_image_write_png(ref, path, 1.0, 0);
                }
                vv_renderer_free(rc);
                vv_world_free(wv);
            }
        }
        vv_image_free(img);
        vv_image_free(ref);
        vv_world_free(w);
        vv_grid_free(g);
        vv_volume_free(vol);
    }
    return 0;
}
