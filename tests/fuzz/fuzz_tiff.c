/* libFuzzer harness: TIFF stacks through libtiff (vv_tiff_read; src/io/tiff.c). */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_volume *v = NULL;
    if (vv_tiff_read(&v, fuzz_write("in.tif", data, size), -1) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
