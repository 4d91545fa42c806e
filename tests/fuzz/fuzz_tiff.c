/*
 * libFuzzer harness: our parsers of a TIFF stack's ImageDescription, the
 * OME-XML and ImageJ metadata (vv_tiff_prescan_description;
 * src/io/volume/tiff.c), the text libtiff hands over. libtiff itself runs in the
 * reader sandbox (volvis-reader), whose parent side fuzz_sandbox fuzzes;
 * it is not called here. The input is the description (cut at its first
 * NUL, as a TIFF ASCII tag is).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/prescan.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *desc = malloc(size + 1); /* exactly the text: ASan sees a read past it */
    if (!desc)
        return 0;
    memcpy(desc, data, size);
    desc[size] = '\0';
    int kind = vv_tiff_prescan_description(desc);
    free(desc);
    if (kind < 0 || kind > 2)
        __builtin_trap();
    return 0;
}
