/* libFuzzer harness: TIFF stacks through libtiff (vv_tiff_read; src/io/tiff.c). */
#include <stdint.h>
#include <stdio.h>
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
    vv_volume *v = NULL;
    if (vv_tiff_read(&v, fuzz_write("in.tif", data, size), -1) == VV_OK)
        check_volume(v);
    return 0;
}
