/* libFuzzer harness: SLC volumes (vv_slc_read; src/io/volume/slc.c). */
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
    if (vv_slc_read(&v, fuzz_write("in.slc", data, size)) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
