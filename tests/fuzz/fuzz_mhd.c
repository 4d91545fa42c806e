/*
 * libFuzzer harness: MetaImage (vv_mhd_read; src/io/volume/mhd.c). The input is an
 * .mha (header and LOCAL data); when it holds a line "--DATA--", the part
 * before is the header in.mhd and the part after "data.raw" beside it.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/io_internal.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const uint8_t *h, *d;
    size_t nh, nd;
    fuzz_split(data, size, "\n--DATA--\n", &h, &nh, &d, &nd);
    const char *path;
    if (h + nh == data + size) {
        path = fuzz_write("in.mha", data, size);
    } else {
        fuzz_write("data.raw", d, nd);
        path = fuzz_write("in.mhd", h, nh);
    }
    vv_volume *v = NULL;
    if (vv_mhd_read(&v, path) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
