/*
 * libFuzzer harness: animation files (JSON; vv_animation_load;
 * src/manipulate/animation_json.c). An animation read is written back
 * (vv_animation_save: its tracks, keys, transfer functions and sequences)
 * and what was written must read again with as many tracks, keys and
 * sequences.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_animation *a = NULL;
    vv_status s = vv_animation_load(&a, fuzz_write("in.json", data, size));
    fuzz_check_status(s);
    if (s != VV_OK)
        return 0;
    const char *out = fuzz_write("out.json", NULL, 0);
    s = vv_animation_save(a, out);
    fuzz_check_status(s);
    if (s == VV_OK) {
        vv_animation *b = NULL;
        if (vv_animation_load(&b, out) != VV_OK)
            __builtin_trap(); /* what the writer wrote, the reader reads */
        if (b->n_tracks != a->n_tracks || b->n_sequences != a->n_sequences)
            __builtin_trap();
        for (int i = 0; i < a->n_tracks; i++)
            if (b->tracks[i].n_keys != a->tracks[i].n_keys)
                __builtin_trap();
        vv_animation_free(b);
    }
    vv_animation_free(a);
    return 0;
}
