/* libFuzzer harness: VTK legacy STRUCTURED_POINTS volumes (vv_vtk_read;
 * src/io/volume/vtk_legacy.c). A small volume read is written back
 * (vv_volume_save as VTK: the format's fits and write, src/io/volume/vtk_write.c)
 * and must read again with the same dimensions and voxel type. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/io_internal.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* the round trip: for volumes of at most this many voxels */
#define MAX_ROUND_TRIP ((uint64_t)1 << 16)

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_volume *v = NULL;
    if (vv_vtk_read(&v, fuzz_write("in.vtk", data, size)) != VV_OK)
        return 0;
    if ((uint64_t)v->dims[0] * (uint64_t)v->dims[1] * (uint64_t)v->dims[2] <= MAX_ROUND_TRIP) {
        const char *out = fuzz_write("out.vtk", NULL, 0);
        const vv_status s = vv_volume_save(v, out, VV_FORMAT_VTK, 1);
        fuzz_check_status(s);
        vv_volume *w = NULL;
        if (s == VV_OK) {
            if (vv_vtk_read(&w, out) != VV_OK || memcmp(w->dims, v->dims, sizeof v->dims) != 0 ||
                w->type != v->type)
                __builtin_trap(); /* what the writer wrote, the reader reads */
            fuzz_check_volume(w);
        }
    }
    fuzz_check_volume(v);
    return 0;
}
