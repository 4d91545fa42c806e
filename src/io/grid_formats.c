/*
 * The grid format table (include/volvis/sys/format.h): one record per grid
 * format, defined in the format's file (grid_vtk.c, grid_vtu.c, grid_dx.c,
 * grid_plot3d.c, grid_netcdf.c), listed once below in the order of the
 * vv_grid_format values. Detection and vv_grid_load read it.
 */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "core/internal.h"
#include "io/sandbox.h"
#include "volvis/grid.h"
#include "volvis/sys/format.h"

/* One row per format, VV_GRID_FORMAT_VTK first. Adding a format: its file
 * defines vv_grid_format_<name>, and one X(<name>) row goes here. */
#define VV_GRID_FORMAT_TABLE(X)                                                                    \
    X(vtk)                                                                                         \
    X(vtu)                                                                                         \
    X(dx)                                                                                          \
    X(plot3d)                                                                                      \
    X(netcdf)

#define DECLARE(name) extern const vv_grid_format_record vv_grid_format_##name;
VV_GRID_FORMAT_TABLE(DECLARE)
#undef DECLARE

#define ROW(name) &vv_grid_format_##name,
static const vv_grid_format_record *const table[] = {VV_GRID_FORMAT_TABLE(ROW)};
#undef ROW

#define N_FORMATS ((int)(sizeof table / sizeof table[0]))

const vv_grid_format_record *const *
vv_grid_format_table(int *n) {
    if (n)
        *n = N_FORMATS;
    return table;
}

/* The row of the first format that @p p looks like at @p deep, or -1. */
static int
ask(const vv_format_probe *p, int deep) {
    for (int i = 0; i < N_FORMATS; i++)
        if ((!p->gzip || (table[i]->flags & VV_FORMAT_FLAG_GZIP)) && table[i]->looks_like(p, deep))
            return i;
    return -1;
}

int
vv_grid_file_detect(const char *path, vv_grid_format *fmt) {
    if (fmt)
        *fmt = VV_GRID_FORMAT_AUTO;
    if (!path)
        return 0;
    unsigned char buf[VV_FORMAT_PROBE_BYTES + 1];
    char text[VV_FORMAT_PROBE_BYTES + 1];
    vv_format_probe p;
    if (vv_format_probe_fill(&p, path, buf, text) != 0 || p.is_dir)
        return 0;
    int row = ask(&p, 0);
    if (row < 0)
        row = ask(&p, 1);
    if (row < 0)
        return 0;
    if (fmt)
        *fmt = (vv_grid_format)(row + 1);
    return 1;
}

vv_status
vv_grid_load(vv_grid **out, const char *path) {
    *out = NULL;
    vv_grid_format f;
    if (!vv_grid_file_detect(path, &f)) {
        FILE *fp = fopen(path, "rb");
        if (!fp)
            return vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
        fclose(fp);
        char list[256] = "";
        for (int i = 0; i < N_FORMATS; i++) {
            size_t k = strlen(list);
            snprintf(list + k, sizeof list - k, "%s%s", i ? ", " : "", table[i]->title);
        }
        return vv_error_set(VV_ERR_FORMAT, "%s: not a grid file this build reads (%s)", path, list);
    }
    /* libxml2 and libnetcdf read in volvis-reader (issue 33) */
    if ((table[(int)f - 1]->flags & VV_FORMAT_FLAG_THIRD_PARTY) && vv_sandbox_wanted(NULL))
        return vv_sandbox_grid_load(out, path, table[(int)f - 1]);
    return table[(int)f - 1]->read(out, path);
}
