/*
 * libFuzzer harness: NRRD through Teem (vv_nrrd_read; src/io/nrrd.c).
 * The input is a header; when it holds a line "--DATA--", what follows is
 * written to "data.raw" beside it (for a detached header naming data.raw)
 * and the header alone to "in.nhdr". Otherwise the whole input is "in.nrrd".
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const uint8_t *h, *d;
    size_t nh, nd;
    fuzz_split(data, size, "\n--DATA--\n", &h, &nh, &d, &nd);
    const char *path;
    if (h + nh == data + size) {
        path = fuzz_write("in.nrrd", data, size);
    } else {
        fuzz_write("data.raw", d, nd);
        path = fuzz_write("in.nhdr", h, nh);
    }
    vv_volume *v = NULL;
    if (vv_nrrd_read(&v, path) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
