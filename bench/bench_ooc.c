/*
 * bench_ooc: out-of-core ray casting (include/volvis/bricks.h), run by
 * bench/ooc_2048.sh on a generated 2048^3 volume under a cgroup memory
 * limit:
 *   bench_ooc VOLUME [--raw WxHxD:u8] [--memory-limit MiB] [--size N]
 *             [--frames F] [--tf LO:HI] [--dataset NAME]
 *   bench_ooc --generate N OUT.raw [u16|u16noise]   (the synthetic N^3 u8
 *       volume; u16: the same, 16 times the values; u16noise: and a scanner's
 *       noise inside the sphere, -32 .. 31 uniform, so that it compresses as
 *       scans do rather than 30-fold)
 * Opens VOLUME (.vvb, raw with --raw, or uncompressed NRRD) as a bricked
 * volume with the memory limit (default 1024 MiB), builds the default World
 * from its coarse proxy with a transfer function ramp LO..HI, and renders F
 * frames (default 4) at N x N (default 512), orbiting 10 degrees a frame.
 * Prints, as anchor lines: the open time (the streaming scan of a raw file),
 * the first frame, the median of the next frames, the bytes read and the
 * bricks read and skipped per frame, the peak cache size and the process's
 * peak resident size (getrusage), and writes the last frame to
 * $VV_BENCH_OUT/ooc.png when that is set.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "util.h"
#include "volvis/volvis.h"

/* Writes the synthetic n^3 u8 volume of bench/ooc_2048.sh to @p path, one
 * slice at a time: a sphere of tissue (radius 0.45 n) with a shell of bone
 * and ripples, air around; with @p u16, little-endian u16 voxels of 16
 * times the values (0 .. 4080, a 12-bit scanner's range), and with u16 2
 * a noise of -32 .. 31 added inside the sphere (a hash of the voxel's
 * index: the same file every time). */
static int
generate(const char *path, int n, int u16) {
    FILE *f = fopen(path, "wb");
    unsigned char *sl = malloc((size_t)n * (size_t)n);
    uint16_t *wide = u16 ? malloc(sizeof(uint16_t) * (size_t)n * (size_t)n) : NULL;
    if (!f || !sl || (u16 && !wide))
        return 1;
    const double c = (n - 1) / 2.0, R = 0.45 * n;
    for (int k = 0; k < n; k++) {
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double dx = i - c, dy = j - c, dz = k - c;
                const double r = sqrt(dx * dx + dy * dy + dz * dz) / R;
                double v = 0;
                if (r < 1.0)
                    v = r > 0.9 ? 230 : 90 + 40 * sin(i * 0.05) * cos(j * 0.07 + k * 0.03);
                sl[(size_t)j * n + i] = (unsigned char)(v < 0 ? 0 : v > 255 ? 255 : v);
            }
        if (u16) {
            for (size_t q = 0; q < (size_t)n * n; q++) {
                uint16_t w = (uint16_t)(sl[q] * 16u);
                if (u16 == 2 && sl[q]) {
                    uint64_t h =
                        ((uint64_t)k * (uint64_t)n * (uint64_t)n + q + 1) * 0x9E3779B97F4A7C15ull;
                    h ^= h >> 29;
                    h *= 0xBF58476D1CE4E5B9ull;
                    h ^= h >> 32;
                    w = (uint16_t)(w + (h & 63u) - 32);
                }
                unsigned char *b = (unsigned char *)&wide[q];
                b[0] = (unsigned char)(w & 0xff); /* little-endian on any host */
                b[1] = (unsigned char)(w >> 8);
            }
            if (fwrite(wide, 2, (size_t)n * n, f) != (size_t)n * n)
                return 1;
        } else if (fwrite(sl, 1, (size_t)n * n, f) != (size_t)n * n) {
            return 1;
        }
    }
    free(sl);
    free(wide);
    return fclose(f) != 0;
}

int
main(int argc, char **argv) {
    if ((argc == 4 || argc == 5) && strcmp(argv[1], "--generate") == 0)
        return generate(argv[3], atoi(argv[2]),
                        argc < 5                           ? 0
                        : strcmp(argv[4], "u16") == 0      ? 1
                        : strcmp(argv[4], "u16noise") == 0 ? 2
                                                           : 0);
    const char *path = NULL, *dataset = "ooc";
    vv_raw_params raw;
    vv_raw_params_init(&raw);
    int has_raw = 0, size = 512, frames = 4;
    double limit_mib = 1024, tf_lo = 60, tf_hi = 255;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--raw") == 0 && i + 1 < argc) {
            char type[16] = "";
            if (sscanf(argv[++i], "%dx%dx%d:%15s", &raw.dims[0], &raw.dims[1], &raw.dims[2],
                       type) != 4 ||
                strcmp(type, "u8") != 0) {
                fprintf(stderr, "bench_ooc: --raw WxHxD:u8\n");
                return 2;
            }
            raw.type = VV_U8;
            has_raw = 1;
        } else if (strcmp(argv[i], "--memory-limit") == 0 && i + 1 < argc) {
            limit_mib = atof(argv[++i]);
        } else if (strcmp(argv[i], "--size") == 0 && i + 1 < argc) {
            size = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
            frames = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--tf") == 0 && i + 1 < argc) {
            if (sscanf(argv[++i], "%lf:%lf", &tf_lo, &tf_hi) != 2)
                return 2;
        } else if (strcmp(argv[i], "--dataset") == 0 && i + 1 < argc) {
            dataset = argv[++i];
        } else {
            path = argv[i];
        }
    }
    if (!path || frames < 1 || frames > 100) {
        fprintf(stderr, "usage: bench_ooc VOLUME [--raw WxHxD:u8] [--memory-limit MiB] "
                        "[--size N] [--frames F] [--tf LO:HI] [--dataset NAME]\n");
        return 2;
    }
    double t0 = bench_now();
    vv_cache_set_limit(vv_cache_process(), (uint64_t)(limit_mib * 1048576.0));
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    if (has_raw) {
        oo.load.format = VV_FORMAT_RAW;
        oo.load.has_raw = 1;
        oo.load.raw = raw;
    }
    vv_opened od;
    if (vv_open(&od, path, &oo) != VV_OK || vv_source_get_kind(od.source) != VV_SOURCE_BRICKS)
        bench_die("bench_ooc", path);
    vv_source *b = od.source;
    bench_emit("ooc_open", dataset, bench_now() - t0, "s");
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = size;
    o.has_tf_range = 1;
    o.tf_lo = tf_lo;
    o.tf_hi = tf_hi;
    vv_world *w = NULL; /* from the proxy; opacity per the volume's voxel spacing */
    if (vv_world_new_for_source(&w, b, 0, &o) != VV_OK)
        bench_die("bench_ooc", "world");
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    if (vv_renderer_new(&ren, "raycast") != VV_OK || vv_image_new(&img, size, size) != VV_OK)
        bench_die("bench_ooc", "renderer");
    double times[100];
    vv_source_stats st0, st1;
    vv_source_stats_get(b, &st0);
    const uint64_t open_bytes = st0.bytes_read;
    for (int f = 0; f < frames; f++) {
        if (f > 0)
            vv_view_orbit(&w->view, 10 * 3.14159265358979 / 180, 0);
        vv_source_stats_get(b, &st0);
        const double t = bench_now();
        if (vv_renderer_render(ren, w, &w->view, NULL, img) != VV_OK)
            bench_die("bench_ooc", "render");
        times[f] = bench_now() - t;
        vv_source_stats_get(b, &st1);
        fprintf(stderr,
                "bench_ooc: frame %d: %.2f s, %llu bricks read, %llu from the cache, %llu "
                "skipped, %.1f MiB read\n",
                f, times[f], (unsigned long long)(st1.loads - st0.loads),
                (unsigned long long)(st1.hits - st0.hits),
                (unsigned long long)(st1.skipped - st0.skipped),
                (double)(st1.bytes_read - st0.bytes_read) / 1048576.0);
    }
    bench_emit("ooc_first_frame", dataset, times[0], "s");
    if (frames > 1)
        bench_emit("ooc_next_frames", dataset, bench_median(times + 1, frames - 1), "s");
    vv_source_stats st;
    vv_source_stats_get(b, &st);
    bench_emit("ooc_bytes_read_open", dataset, (double)open_bytes / 1048576.0, "MiB");
    bench_emit("ooc_bytes_read_frames", dataset, (double)(st.bytes_read - open_bytes) / 1048576.0,
               "MiB");
    bench_emit("ooc_bricks_read", dataset, (double)st.loads, "bricks");
    bench_emit("ooc_bricks_skipped", dataset, (double)st.skipped, "bricks");
    bench_emit("ooc_peak_cache", dataset, (double)st.peak_bytes / 1048576.0, "MiB");
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    bench_emit("ooc_peak_rss", dataset, (double)ru.ru_maxrss / 1024.0, "MiB");
    const char *out = getenv("VV_BENCH_OUT");
    if (out && *out) {
        char png[4096];
        snprintf(png, sizeof png, "%s/ooc.png", out);
        vv_image_write_png(img, png, 1, 0);
    }
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    vv_opened_clear(&od);
    return 0;
}
