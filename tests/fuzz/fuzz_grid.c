/*
 * libFuzzer harness: our irregular-grid parsers (vv_grid_load;
 * src/io/grid/grid_*.c): VTK legacy UNSTRUCTURED_GRID, OpenDX and PLOT3D. The
 * name follows the content; anything else is a PLOT3D grid "inxyz.bin",
 * with the part after a line "--DATA--" as its solution "inq.bin". VTK XML
 * .vtu (libxml2) and NetCDF (libnetcdf) are read in the reader sandbox
 * (volvis-reader), whose parent side fuzz_sandbox fuzzes: inputs that look
 * like them are left alone.
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
    else if (starts(data, size, "<") || starts(data, size, "CDF") || starts(data, size, "\x89HDF"))
        return 0; /* .vtu, NetCDF: read in the sandbox */
    else if (starts(data, size, "object") || starts(data, size, "#"))
        path = fuzz_write("in.dx", data, size);
    else {
        const uint8_t *g, *q;
        size_t ng, nq;
        fuzz_split(data, size, "\n--DATA--\n", &g, &ng, &q, &nq);
        fuzz_write("inq.bin", q, nq);
        path = fuzz_write("inxyz.bin", g, ng);
    }
    vv_grid_format f;
    if (vv_grid_file_detect(path, &f) && (f == VV_GRID_FORMAT_VTU || f == VV_GRID_FORMAT_NETCDF))
        return 0; /* taken for .vtu or NetCDF by its content: the sandbox's */
    vv_grid *g = NULL;
    if (vv_grid_load(&g, path) == VV_OK)
        vv_grid_free(g);
    return 0;
}
