/*
 * bench_gpu: frame times of the gpu renderer (src/render/gpu) at 512²,
 * 1920x1080 and 3840x2160, beside the CPU ray caster's at 512² in the same
 * run, on the shared benchmark view of ../shared/BENCHMARKS.md (the peers'
 * view: volume centred, eye at 11 half-extents along (1, -1.6, 1), 20°
 * field of view, transfer-function ramp --tf-lo .. --tf-hi, shaded, step
 * 0.5 voxel). Prints the Vulkan devices found, then per mode and size
 *   anchor=volvis op=gpu_<mode>_<W>x<H> dataset=<file> value=<ms> unit=ms
 * (the median wall time of vv_renderer_render: uploads, the dispatch and
 * the copy back of the float image) with the median device time between
 * the frame's timestamps and the frame rate on a comment line, and the
 * PSNR of the gpu image against raycast's at 512². Not a timed test: run it
 * by hand, on a GPU (docs/rendering.md, "GPU ray casting").
 *
 * usage: bench_gpu VOLUME [--tf-lo A] [--tf-hi B] [--runs N] [--device N]
 *                  [--modes composite,mip] [--sizes 512x512,1920x1080,3840x2160]
 *                  [--outdir DIR] [--no-cpu]
 *        bench_gpu --phantom N ...  (the phantom of bench/phantom512.py, N^3 8-bit
 *                  voxels made in memory: 2048^3 is 8 GiB, a pyramid's finest level)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/bench_scene.h"
#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;

/* bench/phantom512.py's phantom, @p n voxels a side, 8-bit (0 .. 255 for
 * its 0 .. 30000), made on all threads. */
static vv_volume *
phantom(int n) {
    const int dims[3] = {n, n, n};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_U8) != VV_OK)
        return NULL;
    uint8_t *d = v->data;
    const double sig2 = 2 * 0.6 * 0.6;
#pragma omp parallel for schedule(static)
    for (int k = 0; k < n; k++) {
        const double z = -1 + 2.0 * k / (n - 1);
        for (int j = 0; j < n; j++) {
            const double y = -1 + 2.0 * j / (n - 1);
            uint8_t *row = d + ((size_t)k * n + (size_t)j) * (size_t)n;
            for (int i = 0; i < n; i++) {
                const double x = -1 + 2.0 * i / (n - 1);
                const double blob = exp(-(x * x + y * y + z * z) / sig2);
                const double tex = 0.6 + 0.4 * sin(18 * x) * sin(18 * y) * sin(18 * z);
                row[i] = (uint8_t)(blob * tex * 255.0);
            }
        }
    }
    vv_volume_update_range(v);
    return v;
}

/* The peers' view (vvb_peer_view) of @p mode: composite a ramp lo .. hi to
 * opacity 0.5, white, shaded; projections opaque grey lo .. hi. */
static void
setup(vv_world *w, vv_object *obj, vv_render_mode mode, double lo, double hi, int width,
      int height) {
    vvb_peer_view(w, obj, width, height);
    const vv_volume *v = obj->volume;
    double minsp = INFINITY;
    for (int a = 0; a < 3; a++)
        minsp = v->spacing[a] < minsp ? v->spacing[a] : minsp;
    obj->mode = mode;
    obj->segmentation = VV_SEG_TRANSFER_FUNCTION;
    vv_tf_init(&obj->tf);
    obj->tf.opacity_unit_distance = minsp;
    const int comp = mode == VV_MODE_COMPOSITE;
    vv_tf_add_opacity(&obj->tf, lo, comp ? 0.0 : 1.0);
    vv_tf_add_opacity(&obj->tf, hi, comp ? 0.5 : 1.0);
    vv_tf_add_color(&obj->tf, lo, comp ? vv_vec3_make(1, 1, 1) : vv_vec3_make(0, 0, 0));
    vv_tf_add_color(&obj->tf, hi, vv_vec3_make(1, 1, 1));
    obj->shading = comp;
}

/* The median wall time (ms) of @p runs frames after a warm-up, and the
 * median device time (*device_ms). */
static double
time_frames(vv_renderer *r, const vv_world *w, vv_image *img, int runs, double *device_ms) {
    vv_render_options opt;
    vv_render_options_init(&opt);
    const double t0 = bench_now();
    if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK) {
        fprintf(stderr, "bench_gpu: %s: %s\n", vv_renderer_name(r), vv_error_message());
        exit(1);
    }
    printf("# %s: first frame %.3f s (caches, tables and uploads)\n", vv_renderer_name(r),
           bench_now() - t0);
    double *t = calloc((size_t)runs, sizeof *t), *d = calloc((size_t)runs, sizeof *d);
    if (!t || !d)
        bench_die("bench_gpu", "out of memory");
    for (int i = 0; i < runs; i++) {
        vv_render_stats st = {0};
        opt.stats = &st;
        const double a = bench_now();
        if (vv_renderer_render(r, w, &w->view, &opt, img) != VV_OK)
            bench_die("bench_gpu", "render");
        t[i] = (bench_now() - a) * 1e3;
        d[i] = st.device_ms;
    }
    const double m = bench_median(t, runs);
    *device_ms = bench_median(d, runs);
    free(t);
    free(d);
    return m;
}

int
main(int argc, char **argv) {
    const char *path = NULL, *modes = "composite,mip", *outdir = "build/bench-out";
    const char *sizes = "512x512,1920x1080,3840x2160", *device = "auto";
    double lo = NAN, hi = NAN;
    int runs = 10, cpu = 1, nphantom = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (a[0] != '-') {
            path = a;
            continue;
        }
        if (!strcmp(a, "--no-cpu")) {
            cpu = 0;
            continue;
        }
        if (!val) {
            fprintf(stderr, "bench_gpu: %s needs a value\n", a);
            return 2;
        }
        if (!strcmp(a, "--tf-lo"))
            lo = atof(val);
        else if (!strcmp(a, "--tf-hi"))
            hi = atof(val);
        else if (!strcmp(a, "--runs"))
            runs = atoi(val);
        else if (!strcmp(a, "--device"))
            device = val;
        else if (!strcmp(a, "--modes"))
            modes = val;
        else if (!strcmp(a, "--sizes"))
            sizes = val;
        else if (!strcmp(a, "--outdir"))
            outdir = val;
        else if (!strcmp(a, "--phantom"))
            nphantom = atoi(val);
        else {
            fprintf(stderr, "bench_gpu: unknown option %s\n", a);
            return 2;
        }
        i++;
    }
    if ((!path && nphantom < 2) || runs < 1) {
        fprintf(stderr, "usage: bench_gpu VOLUME [--tf-lo A] [--tf-hi B] [--runs N] [--device N] "
                        "[--modes composite,mip] [--sizes WxH,...] [--outdir DIR] [--no-cpu]\n");
        return 2;
    }
    vv_gpu_device devs[16];
    const char *why;
    const int nd = vv_gpu_devices(devs, 16, &why);
    if (nd == 0) {
        fprintf(stderr, "bench_gpu: no Vulkan device: %s\n", why);
        return 1;
    }
    for (int i = 0; i < nd && i < 16; i++)
        printf("# device %d: %s (%s, %.1f GiB)\n", i, devs[i].name, devs[i].kind,
               (double)devs[i].memory_bytes / (1 << 30));
    char pname[64];
    snprintf(pname, sizeof pname, "phantom%d_u8", nphantom);
    dataset = nphantom ? pname : strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    vv_volume *vol;
    double t0 = bench_now();
    if (nphantom) {
        if (!(vol = phantom(nphantom))) {
            fprintf(stderr, "bench_gpu: a %d^3 phantom: %s\n", nphantom, vv_error_message());
            return 1;
        }
    } else if (vv_volume_load(&vol, path, NULL) != VV_OK) {
        fprintf(stderr, "bench_gpu: %s: %s\n", path, vv_error_message());
        return 1;
    }
    printf("# loaded %s (%d x %d x %d) in %.2f s\n", dataset, vol->dims[0], vol->dims[1],
           vol->dims[2], bench_now() - t0);
    vvb_center(vol); /* the peers' placement (bench_raycast's) */
    if (!(lo == lo))
        lo = vol->range[0] + 0.25 * (vol->range[1] - vol->range[0]);
    if (!(hi == hi))
        hi = vol->range[0] + 0.75 * (vol->range[1] - vol->range[0]);
    vv_world *w;
    vv_object *obj;
    if (vvb_volume_world(&w, &obj, vol, "bench") != VV_OK)
        bench_die("bench_gpu", "world");
    vv_renderer *gpu, *ref = NULL;
    if (vv_renderer_new(&gpu, "gpu") != VV_OK ||
        vv_renderer_set_option(gpu, "device", device) != VV_OK ||
        (cpu && vv_renderer_new(&ref, "raycast") != VV_OK))
        bench_die("bench_gpu", vv_error_message());
    bench_mkdirs(outdir);
    char list[256];
    snprintf(list, sizeof list, "%s", modes);
    for (char *m = strtok(list, ","); m; m = strtok(NULL, ",")) {
        const vv_render_mode mode = !strcmp(m, "mip")     ? VV_MODE_MIP
                                    : !strcmp(m, "minip") ? VV_MODE_MINIP
                                    : !strcmp(m, "xray")  ? VV_MODE_XRAY
                                                          : VV_MODE_COMPOSITE;
        char sl[256];
        snprintf(sl, sizeof sl, "%s", sizes);
        char *save = NULL;
        for (char *s = strtok_r(sl, ",", &save); s; s = strtok_r(NULL, ",", &save)) {
            int W = 0, H = 0;
            if (sscanf(s, "%dx%d", &W, &H) != 2 || W < 1 || H < 1)
                bench_die("bench_gpu", "--sizes: WxH,...");
            setup(w, obj, mode, lo, hi, W, H);
            vv_image *img;
            if (vv_image_new(&img, W, H) != VV_OK)
                bench_die("bench_gpu", "image");
            double dev_ms;
            const double ms = time_frames(gpu, w, img, runs, &dev_ms);
            char op[96];
            snprintf(op, sizeof op, "gpu_%s_%dx%d", m, W, H);
            bench_emit(op, dataset, ms, "ms");
            printf("# %s: %.2f ms a frame (%.1f frames/s), device %.2f ms (%.1f frames/s)\n", op,
                   ms, 1e3 / ms, dev_ms, dev_ms > 0 ? 1e3 / dev_ms : 0.0);
            if (ref && W * H <= 512 * 512) {
                vv_image *ri;
                if (vv_image_new(&ri, W, H) != VV_OK)
                    bench_die("bench_gpu", "image");
                double unused;
                const double rms = time_frames(ref, w, ri, runs < 3 ? runs : 3, &unused);
                snprintf(op, sizeof op, "raycast_%s_%dx%d", m, W, H);
                bench_emit(op, dataset, rms, "ms");
                double se = 0;
                for (size_t i = 0; i < (size_t)W * H * 4; i++) {
                    const double e = (double)img->rgba[i] - ri->rgba[i];
                    se += e * e;
                }
                const double psnr = se > 0 ? 10 * log10((double)W * H * 4 / se) : INFINITY;
                printf("# %s: gpu against raycast %.1f dB; raycast %.2f ms, gpu %.1fx faster\n", m,
                       psnr, rms, rms / ms);
                char png[4096];
                snprintf(png, sizeof png, "%s/gpu_%s_%s.png", outdir, dataset, m);
                if (vv_image_write_png(img, png, 1.0, 0) == VV_OK)
                    printf("# image %s\n", png);
                vv_image_free(ri);
            }
            vv_image_free(img);
        }
    }
    vv_renderer_free(gpu);
    vv_renderer_free(ref);
    vv_world_free(w);
    vv_volume_free(vol);
    return 0;
}
