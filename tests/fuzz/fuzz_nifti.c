/*
 * libFuzzer harness: NIfTI-1/NIfTI-2 and Analyze through nifti_clib
 * (vv_nifti_read; src/io/nifti.c). The input is a single file (in.nii, gzip
 * or not); when it holds a line "--DATA--", the part before is a header
 * in.hdr and the part after its image in.img.
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
        path = fuzz_write(size >= 2 && data[0] == 0x1f && data[1] == 0x8b ? "in.nii.gz" : "in.nii",
                          data, size);
    } else {
        fuzz_write("in.img", d, nd);
        path = fuzz_write("in.hdr", h, nh);
    }
    vv_volume *v = NULL;
    if (vv_nifti_read(&v, path) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
