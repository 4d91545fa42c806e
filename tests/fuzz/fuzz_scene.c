/*
 * libFuzzer harness: scene files (JSON; vv_scene_load; src/model/scene.c).
 * Volume and mesh files a scene names are resolved beside it, in the
 * harness's private folder, where only the scene itself lies.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    vv_world *w = NULL;
    if (vv_scene_load(&w, fuzz_write("in.json", data, size)) == VV_OK)
        vv_world_free(w);
    return 0;
}
