/*
 * bench_filter: the Filtering component on a volume (the CT head of
 * ../shared/BENCHMARKS.md) beside SciPy's ndimage in the same run. For each
 * operation it times VolVis (median of --runs), then runs the peer
 * bench/filter_scipy.py on the same voxels (Debian's /usr/bin/python3), and
 * prints both anchor lines and their ratio:
 *   anchor=volvis op=filter_<op> dataset=<file> value=<ms> unit=ms
 *   anchor=scipy  op=filter_<op> dataset=<file> value=<ms> unit=ms
 *   # <op>: scipy/volvis = R (load ...)
 * Operations: gaussian2 (sigma 2 voxels along each axis, f32 out), median1
 * (3x3x3), cc6 and cc26 (connected components of value >= --threshold; the
 * mask is made beforehand for both). --pairs repeats the whole alternation.
 *
 * usage: bench_filter VOLUME [--runs N] [--threads N] [--pairs N]
 *                     [--threshold T] [--no-peer] [--ops gaussian2,median1,cc6,cc26]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util.h"
#include "volvis/volvis.h"

static const char *dataset;

static double
load1(void) {
    double l = -1;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1)
            l = -1;
        fclose(f);
    }
    return l;
}

static double
time_op(const char *op, const vv_volume *v, const vv_volume *mask, int runs,
        const vv_filter_options *o) {
    double t[64];
    if (runs > 64)
        runs = 64;
    for (int r = 0; r < runs; r++) {
        vv_volume *out = NULL;
        vv_status s = VV_OK;
        double t0 = bench_now();
        if (!strcmp(op, "gaussian2")) {
            double sg[3] = {2 * v->spacing[0], 2 * v->spacing[1], 2 * v->spacing[2]};
            s = vv_filter_gaussian(v, sg, o, &out);
        } else if (!strcmp(op, "median1")) {
            s = vv_filter_median(v, 1, o, &out);
        } else if (!strcmp(op, "cc6") || !strcmp(op, "cc26")) {
            s = vv_filter_components(mask, op[2] == '6' ? 6 : 26, VV_U32, o, &out, NULL, NULL);
        } else {
            fprintf(stderr, "bench_filter: unknown op %s\n", op);
            exit(2);
        }
        t[r] = (bench_now() - t0) * 1000;
        if (s != VV_OK)
            bench_die("bench_filter", op);
        vv_volume_free(out);
    }
    return bench_median(t, runs);
}

int
main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: bench_filter VOLUME [--runs N] [--threads N] [--pairs N] "
                        "[--threshold T] [--no-peer] [--ops LIST]\n");
        return 2;
    }
    const char *path = argv[1];
    int runs = 5, threads = 2, pairs = 1, peer = 1;
    double thr = 300;
    const char *ops = "gaussian2,median1,cc6,cc26";
    for (int i = 2; i < argc; i++) {
        const char *val = i + 1 < argc ? argv[i + 1] : "";
        if (!strcmp(argv[i], "--runs"))
            runs = atoi(val), i++;
        else if (!strcmp(argv[i], "--threads"))
            threads = atoi(val), i++;
        else if (!strcmp(argv[i], "--pairs"))
            pairs = atoi(val), i++;
        else if (!strcmp(argv[i], "--threshold"))
            thr = atof(val), i++;
        else if (!strcmp(argv[i], "--ops"))
            ops = val, i++;
        else if (!strcmp(argv[i], "--no-peer"))
            peer = 0;
        else {
            fprintf(stderr, "bench_filter: unknown option %s\n", argv[i]);
            return 2;
        }
    }
    dataset = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    vv_volume *v = NULL, *mask = NULL;
    if (vv_volume_load(&v, path, NULL) != VV_OK)
        bench_die("bench_filter", path);
    vv_filter_options o;
    vv_filter_options_init(&o);
    o.threads = threads;
    if (vv_filter_threshold(v, thr, INFINITY, &o, &mask) != VV_OK)
        bench_die("bench_filter", "threshold");

    /* the peer reads the same voxels as raw */
    char raw[] = "/tmp/bench_filter_XXXXXX";
    int fd = mkstemp(raw);
    size_t bytes = (size_t)vv_volume_voxel_count(v) * vv_voxel_type_size(v->type);
    if (fd < 0 || write(fd, v->data, bytes) != (ssize_t)bytes)
        peer = 0;
    if (fd >= 0)
        close(fd);
    static const char *np[] = {"uint8",  "int8",  "uint16",  "int16",
                               "uint32", "int32", "float32", "float64"};
    char script[1024];
    snprintf(script, sizeof script, "%s/filter_scipy.py", VV_BENCH_DIR);
    if (peer && access("/usr/bin/python3", X_OK) != 0)
        peer = 0;
    printf("# %s %dx%dx%d %s, %d threads, %d runs per median, peer %s\n", dataset, v->dims[0],
           v->dims[1], v->dims[2], vv_voxel_type_name(v->type), threads, runs,
           peer ? "scipy.ndimage (single-threaded)" : "none");
    for (int p = 0; p < pairs; p++) {
        char list[256];
        snprintf(list, sizeof list, "%s", ops);
        for (char *op = strtok(list, ","); op; op = strtok(NULL, ",")) {
            double l0 = load1();
            double ms = time_op(op, v, mask, runs, &o);
            char name[64];
            snprintf(name, sizeof name, "filter_%s", op);
            bench_emit(name, dataset, ms, "ms");
            if (!peer)
                continue;
            char cmd[2048];
            snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s %s %d %d %d %s %s %d %g", script, raw,
                     v->dims[0], v->dims[1], v->dims[2], np[v->type], op, runs, thr);
            FILE *f = popen(cmd, "r");
            char line[512];
            double peer_ms = -1;
            while (f && fgets(line, sizeof line, f)) {
                fputs(line, stdout);
                const char *q = strstr(line, "value=");
                if (q)
                    peer_ms = atof(q + 6);
            }
            if (f)
                pclose(f);
            if (peer_ms > 0)
                printf("# %s: scipy/volvis = %.2f (load %.2f before, %.2f after)\n", op,
                       peer_ms / ms, l0, load1());
            fflush(stdout);
        }
    }
    unlink(raw);
    vv_volume_free(mask);
    vv_volume_free(v);
    return 0;
}
