/*
 * libFuzzer harness: our NRRD header scan (vv_nrrd_prescan; src/io/volume/nrrd.c),
 * the checks made before Teem sees a file. Teem itself runs in the reader
 * sandbox (volvis-reader), whose parent side fuzz_sandbox fuzzes; it is not
 * called here. The input is a header; when it holds a line "--DATA--", what
 * follows is written to "data.raw" beside it (for a detached header naming
 * data.raw) and the header alone to "in.nhdr". Otherwise the whole input
 * is "in.nrrd".
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/prescan.h"

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
    fuzz_check_status(vv_nrrd_prescan(path));
    return 0;
}
