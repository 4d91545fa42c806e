/*
 * libFuzzer harness: irregular grids (vv_grid_load; src/io/grid_*.c): VTK
 * legacy UNSTRUCTURED_GRID, VTK XML .vtu, OpenDX, NetCDF and PLOT3D. The
 * name follows the content; anything else is a PLOT3D grid "inxyz.bin",
 * with the part after a line "--DATA--" as its solution "inq.bin".
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int
starts(const uint8_t *d, size_t n, const char *p) {
    size_t k = strlen(p);
    return n >= k && memcmp(d, p, k) == 0;
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path;
    if (starts(data, size, "# vtk"))
        path = fuzz_write("in.vtk", data, size);
    else if (starts(data, size, "<"))
        path = fuzz_write("in.vtu", data, size);
    else if (starts(data, size, "CDF") || starts(data, size, "\x89HDF"))
        path = fuzz_write("in.nc", data, size);
    else if (starts(data, size, "object") || starts(data, size, "#"))
        path = fuzz_write("in.dx", data, size);
    else {
        const uint8_t *g, *q;
        size_t ng, nq;
        fuzz_split(data, size, "\n--DATA--\n", &g, &ng, &q, &nq);
        fuzz_write("inq.bin", q, nq);
        path = fuzz_write("inxyz.bin", g, ng);
    }
    vv_grid *g = NULL;
    if (vv_grid_load(&g, path) == VV_OK)
        vv_grid_free(g);
    return 0;
}
