/*
 * libFuzzer harness: .vvc compressed volumes (vv_vvc_from_memory,
 * vv_vvc_get_info, one subcube decoded alone, then the whole volume;
 * src/compress/).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_vvc *c = NULL;
    if (vv_vvc_from_memory(&c, data, size, "in.vvc") != VV_OK)
        return 0;
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    int n = vv_vvc_subcube_count(c);
    if (n > 0 && info.block > 0 && info.block <= 32) {
        size_t m = (size_t)info.block;
        float *vals = malloc(m * m * m * sizeof *vals);
        if (vals) {
            vv_vvc_decode_subcube(c, n - 1, vals);
            free(vals);
        }
    }
    vv_volume *v = NULL;
    if (vv_vvc_decompress(&v, c, 1, NULL) == VV_OK)
        fuzz_check_volume(v);
    vv_vvc_free(c);
    return 0;
}
