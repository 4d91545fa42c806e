/*
 * libFuzzer harness: DICOM through GDCM (vv_dicom_list and vv_dicom_read
 * of one file; src/io/dicom.c, src/io/dicom_gdcm.cpp).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/*
 * A GDCM call interrupted by its own failed assertion (the abort guard,
 * src/core/guard.c) loses what GDCM had allocated for it: those leaks are
 * GDCM's and suppressed, so the fuzzer keeps looking for crashes.
 */
const char *__lsan_default_suppressions(void);
const char *
__lsan_default_suppressions(void) {
    return "leak:libgdcmDSED.so\nleak:libgdcmMSFF.so\nleak:libgdcmCommon.so\n"
           "leak:_M_allocate_internal_buffer\n";
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path = fuzz_write("in.dcm", data, size);
    vv_dicom_series *list = NULL;
    int n = 0;
    if (vv_dicom_list(&list, &n, path) == VV_OK)
        free(list);
    vv_volume *v = NULL;
    if (vv_dicom_read(&v, path, 0, -1) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
