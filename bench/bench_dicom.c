/*
 * Loading a DICOM series: VolVis (GDCM underneath) against VTK's
 * vtkDICOMImageReader on the same folder in the same run, and against
 * reading the same voxels from an uncompressed NRRD.
 *
 *   bench_dicom [FOLDER] [--repeat N] [--keep]
 *
 * Without FOLDER, a 512 x 512 x 300 uncompressed CT series (the CT head
 * scaled up, 16-bit, one file per slice) is written into a temporary folder
 * by scripts/dicom_testdata.py bench (python3-pydicom, python3-numpy) and
 * removed afterwards (--keep leaves it). The NRRD twin is written by VolVis
 * from the loaded series (raw encoding). Every figure is the median of N
 * loads (default 5) after one load that warms the page cache. Prints
 *   anchor=volvis op=dicom_load ...   anchor=volvis op=nrrd_load ...
 *   anchor=vtk op=dicom_load ...      (from bench/dicom_vtk.py, python3-vtk9)
 * and the ratios on stderr. Targets: dicom_load <= VTK's, <= 1.5 x nrrd_load.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util.h"
#include "volvis/volvis.h"

#define PROG "bench_dicom"
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
time_load(const char *path, int repeat, vv_volume **keep) {
    double *t = malloc((size_t)repeat * sizeof *t);
    vv_volume *v = NULL;
    if (vv_volume_load(&v, path, NULL) != VV_OK) /* warm the page cache */
        bench_die(PROG, path);
    for (int i = 0; i < repeat; i++) {
        vv_volume_free(v);
        v = NULL;
        double t0 = bench_now();
        if (vv_volume_load(&v, path, NULL) != VV_OK)
            bench_die(PROG, path);
        t[i] = bench_now() - t0;
    }
    double m = bench_median(t, repeat);
    free(t);
    if (keep)
        *keep = v;
    else
        vv_volume_free(v);
    return m;
}

int
main(int argc, char **argv) {
    const char *folder = NULL;
    int repeat = 5, keep = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
            repeat = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--keep"))
            keep = 1;
        else if (argv[i][0] != '-')
            folder = argv[i];
        else {
            fprintf(stderr, "usage: %s [FOLDER] [--repeat N] [--keep]\n", PROG);
            return 2;
        }
    }
    if (repeat < 1)
        repeat = 1;
    char tmp[] = "/tmp/vv_bench_dicom_XXXXXX";
    char cmd[4096], series[1100], nrrd[1100];
    if (!folder) {
        if (!mkdtemp(tmp)) {
            perror(PROG ": mkdtemp");
            return 1;
        }
        snprintf(series, sizeof series, "%s/series", tmp);
        snprintf(cmd, sizeof cmd,
                 PYTHON
                 " %s/scripts/dicom_testdata.py bench %s/../shared/data/volumes/ct_head.nrrd "
                 "%s --size 512 --slices 300",
                 VV_SOURCE_DIR, VV_SOURCE_DIR, series);
        fprintf(stderr, "%s: writing the series: %s\n", PROG, cmd);
        if (system(cmd) != 0) {
            fprintf(stderr, "%s: could not write the series (python3-pydicom, python3-numpy)\n",
                    PROG);
            return 1;
        }
        folder = series;
        snprintf(nrrd, sizeof nrrd, "%s/twin.nrrd", tmp);
    } else {
        snprintf(nrrd, sizeof nrrd, "/tmp/vv_bench_dicom_twin_%d.nrrd", (int)getpid());
    }
    vv_volume *v = NULL;
    double t_dicom = time_load(folder, repeat, &v);
    char dataset[64];
    snprintf(dataset, sizeof dataset, "ct%dx%dx%d", v->dims[0], v->dims[1], v->dims[2]);
    fprintf(stderr, "%s: %s: %d x %d x %d %s, range %g .. %g\n", PROG, folder, v->dims[0],
            v->dims[1], v->dims[2], vv_voxel_type_name(v->type), v->range[0], v->range[1]);
    if (save_plain(v, nrrd, VV_FORMAT_NRRD) != VV_OK)
        bench_die(PROG, nrrd);
    vv_volume_free(v);
    double t_nrrd = time_load(nrrd, repeat, NULL);
    bench_emit("dicom_load", dataset, t_dicom, "s");
    bench_emit("nrrd_load", dataset, t_nrrd, "s");

    /* the peer, in the same run on the same folder */
    snprintf(cmd, sizeof cmd, PYTHON " %s/bench/dicom_vtk.py %s --repeat %d --dataset %s",
             VV_SOURCE_DIR, folder, repeat, dataset);
    FILE *p = popen(cmd, "r");
    double t_vtk = -1;
    char line[512];
    while (p && fgets(line, sizeof line, p)) {
        fputs(line, stdout);
        const char *val = strstr(line, "value=");
        if (!strncmp(line, "anchor=vtk", 10) && val)
            t_vtk = atof(val + 6);
    }
    if (p)
        pclose(p);
    fflush(stdout);
    fprintf(stderr, "%s: dicom / nrrd = %.2f (target <= 1.5)", PROG, t_dicom / t_nrrd);
    if (t_vtk > 0)
        fprintf(stderr, ", dicom / vtk = %.2f (target <= 1)\n", t_dicom / t_vtk);
    else
        fprintf(stderr, ", VTK not measured (python3-vtk9 missing?)\n");
    unlink(nrrd);
    if (folder == series && !keep) {
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
        if (system(cmd) != 0)
            fprintf(stderr, "%s: could not remove %s\n", PROG, tmp);
    } else if (keep) {
        fprintf(stderr, "%s: kept %s\n", PROG, folder);
    }
    return 0;
}
