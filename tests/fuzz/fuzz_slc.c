/*
 * libFuzzer harness: SLC volumes (vv_slc_read; src/io/volume/slc.c). A
 * volume read is written back (vv_volume_save: run-length compressed and
 * not, with the icon) and read again, which must give the same voxels; a
 * copy of it in 16 bits is written too (refused when strict; rescaled to 8
 * bits by the writer otherwise) and must read back with the same
 * dimensions; what was written is detected as SLC.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/io_internal.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* the round trips: for volumes of at most this many voxels */
#define MAX_ROUND_TRIP ((uint64_t)1 << 16)

static uint64_t
voxels(const vv_volume *v) {
    return (uint64_t)v->dims[0] * (uint64_t)v->dims[1] * (uint64_t)v->dims[2];
}

/* Writes @p v as SLC (run-length or not) and reads it back: the same
 * dimensions, and with @p same the same voxels. */
static void
round_trip(const vv_volume *v, int rle, int same) {
    vv_save_options so;
    vv_save_options_init(&so);
    so.format = VV_FORMAT_SLC;
    so.compress = rle;
    const char *path = fuzz_write("out.slc", NULL, 0);
    vv_status s;
    if (v->type != VV_U8) { /* strict: what SLC cannot hold is refused */
        so.strict = 1;
        if ((s = vv_volume_save_with(v, path, &so)) != VV_ERR_UNSUPPORTED)
            __builtin_trap();
        fuzz_check_status(s);
        so.strict = 0;
    }
    s = vv_volume_save_with(v, path, &so);
    fuzz_check_status(s);
    if (s != VV_OK)
        return;
    vv_volume *w = NULL;
    s = vv_slc_read(&w, path);
    if (s != VV_OK || vv_format_detect(path) != VV_FORMAT_SLC)
        __builtin_trap(); /* what the writer wrote, the reader reads */
    if (memcmp(w->dims, v->dims, sizeof v->dims) != 0 || w->type != VV_U8 ||
        (same && memcmp(w->data, v->data, (size_t)voxels(v)) != 0))
        __builtin_trap();
    fuzz_check_volume(w);
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_volume *v = NULL;
    vv_status s = vv_slc_read(&v, fuzz_write("in.slc", data, size));
    fuzz_check_status(s);
    if (s != VV_OK)
        return 0;
    if (voxels(v) <= MAX_ROUND_TRIP) {
        round_trip(v, 1, 1);
        round_trip(v, 0, 1);
        vv_volume *w = NULL;
        if (vv_volume_new(&w, v->dims, VV_I16) == VV_OK) {
            const uint8_t *src = v->data;
            int16_t *dst = w->data;
            for (uint64_t i = 0; i < voxels(v); i++)
                dst[i] = (int16_t)(3 * src[i] - 100);
            vv_volume_update_range(w);
            round_trip(w, (int)(size & 1), 0);
            vv_volume_free(w);
        }
    }
    fuzz_check_volume(v);
    return 0;
}
