/*
 * bench_zarr_read: one level of a Zarr store (v2 or v3, sharded or not)
 * read whole into memory through the format table (vv_volume_load), run by
 * bench/zarr_read_pairs.py beside zarr-python 3 and tensorstore reading the
 * same level in the same run:
 *   bench_zarr_read STORE [--level L] [--threads N] [--repeat R]
 * Reads level L (default 0) once untimed, as the pairs script does for the
 * peers, then R times (default 3) with N threads (default 2),
 * checks that every read gives the same voxels (a checksum), and prints one
 * anchor line with the median seconds a read (op=zarr_read), one with its
 * CPU seconds, all threads (op=zarr_read_cpu: what a loaded machine
 * distorts least; this process's median plus its readers' mean: a
 * sandboxed read's reader processes, counted once all of them have been
 * reaped at the end, the spare started for a next read included), and one with
 * the checksum (op=zarr_read_sum, the sum of the voxels as doubles, which
 * the pairs script compares with the peers' sum).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include "util.h"
#include "volvis/sys/sandbox.h"
#include "volvis/volvis.h"

static double
voxel_sum(const vv_volume *v) {
    double s = 0;
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int i = 0; i < v->dims[0]; i++)
                s += vv_volume_get(v, i, j, k);
    return s;
}

int
main(int argc, char **argv) {
    const char *store = NULL;
    int level = 0, threads = 2, repeat = 3;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--level") && i + 1 < argc)
            level = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
            repeat = atoi(argv[++i]);
        else if (argv[i][0] != '-' && !store)
            store = argv[i];
        else {
            fprintf(stderr,
                    "usage: bench_zarr_read STORE [--level L] [--threads N] [--repeat R]\n");
            return 2;
        }
    }
    if (!store || threads < 1 || repeat < 1 || repeat > 100 || level < 0) {
        fprintf(stderr, "usage: bench_zarr_read STORE [--level L] [--threads N] [--repeat R]\n");
        return 2;
    }
    vv_threads_set(threads);
    double t[100], cpu[100], sum0 = 0;
    /* read 0 is not timed: the peers' protocol (zarr_read_pairs.py reads
     * once before timing: files in the page cache, readers set up) */
    for (int r = -1; r < repeat; r++) {
        vv_load_options o;
        vv_load_options_init(&o);
        o.level = level;
        vv_volume *v = NULL;
        const double t0 = bench_now(), c0 = bench_cpu_now();
        if (vv_volume_load(&v, store, &o) != VV_OK)
            bench_die("bench_zarr_read", store);
        if (r >= 0) {
            t[r] = bench_now() - t0;
            cpu[r] = bench_cpu_now() - c0;
        }
        const double sum = voxel_sum(v);
        if (r < 0)
            sum0 = sum;
        else if (sum != sum0) {
            fprintf(stderr, "bench_zarr_read: read %d gave another sum (%.17g, %.17g)\n", r, sum,
                    sum0);
            return 1;
        }
        vv_volume_free(v);
    }
    /* the reader processes' CPU: known once they have been reaped (the
     * library reaps the readers it killed later; the spare is stopped) */
    vv_sandbox_release_spare();
    while (waitpid(-1, NULL, 0) > 0)
        ;
    struct rusage ru;
    double readers = 0;
    if (getrusage(RUSAGE_CHILDREN, &ru) == 0)
        readers = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
                  (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
    const char *name = strrchr(store, '/');
    name = name && name[1] ? name + 1 : store;
    bench_emit("zarr_read", name, bench_median(t, repeat), "s");
    bench_emit("zarr_read_cpu", name, bench_median(cpu, repeat) + readers / (repeat + 1), "s");
    /* every digit: the pairs script compares it with the peers' sums */
    printf("anchor=volvis op=zarr_read_sum dataset=%s value=%.17g unit=sum\n", name, sum0);
    return 0;
}
