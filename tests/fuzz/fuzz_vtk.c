/* libFuzzer harness: VTK legacy STRUCTURED_POINTS volumes (vv_vtk_read;
 * src/io/volume/vtk_legacy.c). */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/io_internal.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_volume *v = NULL;
    if (vv_vtk_read(&v, fuzz_write("in.vtk", data, size)) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
