/*
 * What the reader sandbox costs (issue 33): loading through volvis-reader
 * (a fresh process, Landlock, seccomp, the voxels handed back in a memfd)
 * against loading in this process (VOLVIS_SANDBOX=0), in the same run, on
 *   - the CT head (../shared/data/volumes/ct_head.nrrd, 256 x 256 x 108 i16),
 *   - a 512^3 u16 NRRD (raw encoding, written into a temporary folder),
 *   - a 512 x 512 x 300 DICOM series (scripts/dicom_testdata.py bench,
 *     python3-pydicom and python3-numpy; skipped with a message without).
 *
 *   bench_sandbox [--repeat N] [--keep] [--own]
 *
 * --own measures our own parsers instead (issue 67: which of them should
 * move into the reader): in-process (VOLVIS_SANDBOX unset) against
 * VOLVIS_SANDBOX=all, on the SLC, MetaImage and VTK legacy files of
 * ../shared/data/volumes, and a 512^3 u16 MetaImage (.mha) and .vvb read whole.
 *
 * Each way runs in processes of its own (a worker: two loads that warm
 * the process, its page cache and (from the second) its reader started
 * ahead, then three timed loads, their median); N workers of each way (default 7) alternate,
 * and the figure is the median of their medians. In one process the two
 * ways changed each other's times (malloc's heap and thresholds).
 * Prints anchor lines (op=load_inprocess, op=load_sandbox) and, on stderr,
 * the overhead against the target: at most 5 % or at most 20 ms.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util.h"
#include "volvis/volvis.h"

#define PROG "bench_sandbox"
#define PYTHON "/usr/bin/python3"

/* Writes @p v uncompressed through the format table (vv_volume_save_with). */
static vv_status
save_plain(const vv_volume *v, const char *path, vv_format format) {
    vv_save_options o;
    vv_save_options_init(&o);
    o.format = format;
    o.compress = 0;
    return vv_volume_save_with(v, path, &o);
}

static double
load_once(const char *path) {
    vv_volume *v = NULL;
    double t0 = bench_now();
    if (vv_volume_load(&v, path, NULL) != VV_OK)
        bench_die(PROG, path);
    double t = bench_now() - t0;
    vv_volume_free(v);
    return t;
}

/* A worker: a process of one way (VOLVIS_SANDBOX set by the caller), two
 * loads that warm it (its heap; the second starts the reader ahead), then
 * @p n timed loads; prints their median in seconds. */
static int
worker(const char *path, int n) {
    load_once(path);
    load_once(path);
    double *t = malloc((size_t)n * sizeof *t);
    for (int i = 0; i < n; i++)
        t[i] = load_once(path);
    printf("%.9f\n", bench_median(t, n));
    free(t);
    return 0;
}

/* The two ways a run compares: VOLVIS_SANDBOX's values (in-process, reader). */
static const char *way_in = "0", *way_sb = "1";

/* The median load time of a worker process with VOLVIS_SANDBOX=@p way. */
static double
run_worker(const char *self, const char *path, const char *way, int n) {
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "VOLVIS_SANDBOX=%s '%s' --worker '%s' %d", way, self, path, n);
    FILE *p = popen(cmd, "r");
    double t = -1;
    if (!p || fscanf(p, "%lf", &t) != 1 || t < 0)
        bench_die(PROG, cmd);
    pclose(p);
    return t;
}

static void
measure(const char *self, const char *path, const char *dataset, int repeat) {
    double *in = malloc((size_t)repeat * sizeof *in), *sb = malloc((size_t)repeat * sizeof *sb);
    for (int i = 0; i < repeat; i++) {
        if (i % 2) {
            in[i] = run_worker(self, path, way_in, 3);
            sb[i] = run_worker(self, path, way_sb, 3);
        } else {
            sb[i] = run_worker(self, path, way_sb, 3);
            in[i] = run_worker(self, path, way_in, 3);
        }
    }
    double a = bench_median(in, repeat), b = bench_median(sb, repeat);
    bench_emit("load_inprocess", dataset, a, "s");
    bench_emit("load_sandbox", dataset, b, "s");
    double over = b - a, pct = 100.0 * over / a;
    int ok = pct <= 5.0 || over <= 0.020;
    fprintf(stderr, "%s: %s: in-process %.1f ms, sandbox %.1f ms: %+.1f ms (%+.1f %%) %s\n", PROG,
            dataset, 1e3 * a, 1e3 * b, 1e3 * over, pct,
            ok ? "(target <= 5 % or <= 20 ms: met)" : "(target <= 5 % or <= 20 ms: MISSED)");
    fflush(stdout);
    free(in);
    free(sb);
}

/* A 512^3 u16 volume: a smooth field with some structure. */
static vv_volume *
cube512(void) {
    int dims[3] = {512, 512, 512};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_U16) != VV_OK)
        bench_die(PROG, "512^3 volume");
    uint16_t *d = v->data;
    for (long k = 0; k < 512; k++)
        for (long j = 0; j < 512; j++)
            for (long i = 0; i < 512; i++)
                d[(k * 512 + j) * 512 + i] = (uint16_t)((i * 7 + j * 13 + k * 29) & 0xfff);
    return v;
}

/* --own: our own parsers in this process against in the reader. */
static int
measure_own(const char *self, int repeat, int keep) {
    way_in = "1";
    way_sb = "all";
    static const char *const files[][2] = {{"nut.slc", "slc_nut"},
                                           {"HeadMRVolume.mhd", "mhd_headmr"},
                                           {"ironProt.vtk", "vtk_ironprot"}};
    char path[1200], cmd[4096];
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        snprintf(path, sizeof path, VV_SOURCE_DIR "/../shared/data/volumes/%s", files[i][0]);
        measure(self, path, files[i][1], repeat);
    }
    char tmp[] = "/tmp/vv_bench_sandbox_XXXXXX";
    if (!mkdtemp(tmp)) {
        perror(PROG ": mkdtemp");
        return 1;
    }
    vv_volume *v = cube512();
    snprintf(path, sizeof path, "%s/cube512.mha", tmp);
    if (save_plain(v, path, VV_FORMAT_MHD) != VV_OK)
        bench_die(PROG, path);
    measure(self, path, "mha512", repeat);
    snprintf(path, sizeof path, "%s/cube512.vvb", tmp);
    if (vv_volume_save(v, path, VV_FORMAT_VVB, 0) != VV_OK)
        bench_die(PROG, path);
    measure(self, path, "vvb512", repeat);
    vv_volume_free(v);
    if (!keep) {
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
        if (system(cmd) != 0)
            fprintf(stderr, "%s: could not remove %s\n", PROG, tmp);
    }
    return 0;
}

int
main(int argc, char **argv) {
    if (argc == 4 && !strcmp(argv[1], "--worker"))
        return worker(argv[2], atoi(argv[3]));
    int repeat = 7, keep = 0, own = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
            repeat = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--keep"))
            keep = 1;
        else if (!strcmp(argv[i], "--own"))
            own = 1;
        else {
            fprintf(stderr, "usage: %s [--repeat N] [--keep] [--own]\n", PROG);
            return 2;
        }
    }
    if (repeat < 1)
        repeat = 1;
    if (own)
        return measure_own(argv[0], repeat, keep);
    const char *head = VV_SOURCE_DIR "/../shared/data/volumes/ct_head.nrrd";
    measure(argv[0], head, "ct_head", repeat);

    char tmp[] = "/tmp/vv_bench_sandbox_XXXXXX";
    if (!mkdtemp(tmp)) {
        perror(PROG ": mkdtemp");
        return 1;
    }
    char path[1200], cmd[4096];
    /* 512^3 u16, written raw */
    vv_volume *v = cube512();
    snprintf(path, sizeof path, "%s/cube512.nrrd", tmp);
    if (save_plain(v, path, VV_FORMAT_NRRD) != VV_OK)
        bench_die(PROG, path);
    vv_volume_free(v);
    measure(argv[0], path, "nrrd512", repeat);

    snprintf(path, sizeof path, "%s/series", tmp);
    snprintf(cmd, sizeof cmd,
             PYTHON " %s/scripts/dicom_testdata.py bench %s %s --size 512 --slices 300 "
                    ">/dev/null",
             VV_SOURCE_DIR, head, path);
    if (system(cmd) == 0)
        measure(argv[0], path, "dicom512x512x300", repeat);
    else
        fprintf(stderr, "%s: DICOM series not measured (python3-pydicom, python3-numpy)\n", PROG);

    if (!keep) {
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
        if (system(cmd) != 0)
            fprintf(stderr, "%s: could not remove %s\n", PROG, tmp);
    } else {
        fprintf(stderr, "%s: kept %s\n", PROG, tmp);
    }
    return 0;
}
