/* libFuzzer harness: animation files (JSON; vv_animation_load; src/animate/). */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_animation *a = NULL;
    if (vv_animation_load(&a, fuzz_write("in.json", data, size)) == VV_OK)
        vv_animation_free(a);
    return 0;
}
