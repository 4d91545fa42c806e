/*
 * libFuzzer harness: our NIfTI-1/NIfTI-2 and Analyze header checks
 * (vv_nifti_prescan; src/io/volume/nifti.c), made before nifti_clib sees a file.
 * nifti_clib itself runs in the reader sandbox (volvis-reader), whose
 * parent side fuzz_sandbox fuzzes; it is not called here. The input is a
 * single file (in.nii, gzip or not); when it holds a line "--DATA--", the
 * part before is a header in.hdr and the part after its image in.img.
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
        path = fuzz_write(size >= 2 && data[0] == 0x1f && data[1] == 0x8b ? "in.nii.gz" : "in.nii",
                          data, size);
    } else {
        fuzz_write("in.img", d, nd);
        path = fuzz_write("in.hdr", h, nh);
    }
    fuzz_check_status(vv_nifti_prescan(path));
    return 0;
}
