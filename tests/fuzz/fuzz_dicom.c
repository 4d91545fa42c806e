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
int LLVMFuzzerInitialize(int *argc, char ***argv);

int
LLVMFuzzerInitialize(int *argc, char ***argv) {
    (void)argc;
    (void)argv;
    fuzz_init();
    return 0;
}

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

/* Loads @p path with @p fn; a volume that loads must be consistent. */
static void
check_volume(vv_volume *v) {
    if (!v)
        return;
    uint64_t n = vv_volume_voxel_count(v);
    if (n == 0 || !v->data)
        __builtin_trap();
    /* touch the first and last voxel: ASan checks the buffer holds them */
    volatile unsigned char sink = ((unsigned char *)v->data)[0];
    sink = ((unsigned char *)v->data)[n * vv_voxel_type_size(v->type) - 1];
    (void)sink;
    vv_volume_free(v);
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
        check_volume(v);
    return 0;
}
