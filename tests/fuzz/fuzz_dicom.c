/*
 * libFuzzer harness: our DICOM length walk (vv_dicom_prescan;
 * src/io/volume/dicom_gdcm.cpp, check_lengths), made before GDCM sees a file:
 * explicit and implicit VR, both byte orders, nested sequences and items,
 * encapsulated pixel data, the meta-group patterns GDCM asserts on. GDCM
 * itself runs in the reader sandbox (volvis-reader), whose parent side
 * fuzz_sandbox fuzzes; it is not called here.
 */
#include <stdint.h>
#include <stdio.h>

#include "fuzz_util.h"
#include "io/prescan.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    fuzz_check_status(vv_dicom_prescan(fuzz_write("in.dcm", data, size)));
    return 0;
}
