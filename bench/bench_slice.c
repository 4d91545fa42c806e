/*
 * bench_slice: multiplanar reconstruction (include/volvis/slice.h), the
 * library part of the GUI's slice views: scrolling through 100 axial slices
 * of a 512^3 volume (u16, 256 MiB, made in memory: a sphere shell) at a
 * 512 x 512 view, one vv_slice_sample and one window/level a slice, as the
 * axial view does for each notch of the wheel; also the coronal and
 * sagittal slices through the same volume (strided access). Issue 28's
 * target: >= 30 slices a second on 2 cores (this is the library's share;
 * bench/bench_gui.py measures the GUI's, drawing included).
 *
 * usage: bench_slice [--size N] [--view N] [--slices N]
 * prints anchor=volvis op=slice_<axis>_per_s dataset=sphere<N> value=... unit=slices/s
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"
#include "volvis/volvis.h"

int
main(int argc, char **argv) {
    int n = 512, view = 512, slices = 100;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--size"))
            n = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--view"))
            view = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--slices"))
            slices = atoi(argv[i + 1]);
    }
    if (n < 8 || n > 2048 || view < 16 || view > 8192 || slices < 1 || slices > n) {
        fprintf(stderr, "bench_slice: bad --size, --view or --slices\n");
        return 2;
    }
    int dims[3] = {n, n, n};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_U16) != VV_OK)
        bench_die("bench_slice", "volume");
    uint16_t *d = v->data;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double r = sqrt((i - n / 2.0) * (i - n / 2.0) + (j - n / 2.0) * (j - n / 2.0) +
                                (k - n / 2.0) * (k - n / 2.0));
                d[((size_t)k * n + j) * n + i] = (uint16_t)fmax(0, 4000 - fabs(r - n / 3.0) * 80);
            }
    vv_volume_update_range(v);
    vv_object *o = NULL;
    if (vv_object_new_volume(&o, v, "sphere") != VV_OK)
        bench_die("bench_slice", "object");
    vv_volume_free(v);
    char ds[32];
    snprintf(ds, sizeof ds, "sphere%d", n);
    float *values = malloc(sizeof(float) * (size_t)view * view);
    uint8_t *rgba = malloc((size_t)view * view * 4);
    double win, lev;
    vv_slice_auto_window(o->volume, &win, &lev);
    vv_box box = vv_object_world_box(o);
    vv_vec3 c = vv_vec3_scale(vv_vec3_add(box.min, box.max), 0.5);
    for (int axis = VV_SLICE_AXIAL; axis <= VV_SLICE_SAGITTAL; axis++) {
        vv_slice_plane p;
        if (vv_slice_plane_standard(&p, (vv_slice_axis)axis, VV_SPACE_UNKNOWN, c, view, view, 1) !=
            VV_OK)
            bench_die("bench_slice", "plane");
        vv_slice_plane_fit(&p, box, 0.03);
        vv_vec3 nrm = vv_slice_plane_normal(&p);
        double step = vv_slice_step(o, nrm);
        p.center = vv_vec3_sub(p.center, vv_vec3_scale(nrm, step * slices / 2));
        double t0 = bench_now();
        for (int s = 0; s < slices; s++) {
            p.center = vv_vec3_add(p.center, vv_vec3_scale(nrm, step));
            if (vv_slice_sample(o, &p, values) != VV_OK)
                bench_die("bench_slice", "sample");
            vv_slice_window_level(values, (size_t)view * view, win, lev, vv_vec3_make(0, 0, 0),
                                  rgba);
        }
        double secs = bench_now() - t0;
        char op[64];
        snprintf(op, sizeof op, "slice_%s_per_s", vv_slice_axis_name((vv_slice_axis)axis));
        bench_emit(op, ds, slices / secs, "slices/s");
    }
    free(values);
    free(rgba);
    vv_object_free(o);
    return 0;
}
