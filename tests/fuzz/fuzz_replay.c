/*
 * libFuzzer harness: input-device recordings (vv_input_manager_open_replay;
 * src/input/replay.c), fed at once and polled until drained.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static vv_input_devinfo_db *db;

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    /* the built-in information base (no directories), loaded once */
    const char *none[1] = {NULL};
    if (!db && vv_input_devinfo_db_load(&db, none, 1) != VV_OK)
        __builtin_trap();
    vv_input_manager *m = NULL;
    if (vv_input_manager_new(&m, db) != VV_OK)
        return 0;
    int first = 0, n = 0;
    if (vv_input_manager_open_replay(m, fuzz_write("in.rec", data, size), 0, INFINITY, &first,
                                     &n) == VV_OK) {
        for (int i = 0; i < 64 && vv_input_manager_replay_pending(m); i++)
            vv_input_manager_dispatch(m, 1e9);
    }
    vv_input_manager_free(m);
    return 0;
}
