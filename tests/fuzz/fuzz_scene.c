/*
 * libFuzzer harness: scene files (JSON; vv_scene_load, and
 * vv_scene_load_open, which opens each volume through vv_open as the GUI
 * and Python do; src/scene/scene.c).
 * Volume and mesh files a scene names are resolved beside it, in the
 * harness's private folder, where only the scene itself lies.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Voxelized geometry in a scene builds its volume on every input: under
 * the harnesses' 256 MiB budget a 512^3 grid took a second, holding the
 * fuzzer to under 300 inputs a second. 4 MiB (160^3 voxels of u8) keeps
 * every path (the budget's refusal included) at a fraction of the cost. */
#define SCENE_FUZZ_BUDGET ((uint64_t)4 << 20)

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static int once;
    if (!once) {
        vv_memory_budget_set(SCENE_FUZZ_BUDGET);
        once = 1;
    }
    vv_world *w = NULL;
    const char *path = fuzz_write("in.json", data, size);
    if (vv_scene_load(&w, path) == VV_OK)
        vv_world_free(w);
    /* as the GUI and Python open it: each volume by vv_open, out of core
     * when large (its source attached) */
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_AUTO;
    w = NULL;
    if (vv_scene_load_open(&w, path, NULL, NULL, &oo) == VV_OK)
        vv_world_free(w);
    return 0;
}
