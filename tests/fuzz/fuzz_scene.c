/*
 * libFuzzer harness: scene files (JSON; vv_scene_load, and
 * vv_scene_load_open, which opens each volume through vv_open as the GUI
 * and Python do; src/scene/scene.c).
 * Volume and mesh files a scene names are resolved beside it, in the
 * harness's private folder, where only the scene itself lies.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Voxelized geometry in a scene builds its volume on every input: under
 * the harnesses' 256 MiB budget a 512^3 grid took a second, holding the
 * fuzzer to under 300 inputs a second. 4 MiB (160^3 voxels of u8) keeps
 * every path (the budget's refusal included) at a fraction of the cost. */
#define SCENE_FUZZ_BUDGET ((uint64_t)4 << 20)

/* Writes @p v uncompressed through the format table (vv_volume_save_with). */
static vv_status
save_plain(const vv_volume *v, const char *path, vv_format format) {
    vv_save_options o;
    vv_save_options_init(&o);
    o.format = format;
    o.compress = 0;
    return vv_volume_save_with(v, path, &o);
}

/* The files the error tests' scenes name (tests/scene/test_errors.c, whose
 * scenes seed the corpus: tests/fuzz/corpus_from_tests.py), beside in.json,
 * so that mutations reach the fields read after a volume or grid is
 * loaded (appearance, transfer functions, channels): vol.mhd (+ vol.raw),
 * vol.vvb (8^3 u8 ramps) and grid.vtk (one tetrahedron). */
static void
scene_files(void) {
    const int dims[3] = {8, 8, 8};
    vv_volume *v = NULL;
    if (vv_volume_new(&v, dims, VV_U8) != VV_OK)
        abort();
    for (int i = 0; i < 512; i++)
        ((uint8_t *)v->data)[i] = (uint8_t)(i * 7);
    vv_volume_update_range(v);
    char p[1024];
    snprintf(p, sizeof p, "%s/vol.mhd", fuzz_dir());
    if (save_plain(v, p, VV_FORMAT_MHD) != VV_OK)
        abort();
    snprintf(p, sizeof p, "%s/vol.vvb", fuzz_dir());
    if (vv_volume_save(v, p, VV_FORMAT_VVB, 0) != VV_OK)
        abort();
    vv_volume_free(v);
    static const char grid[] = "# vtk DataFile Version 3.0\ng\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                               "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\n"
                               "CELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS s float\n"
                               "LOOKUP_TABLE default\n0 1 2 3\n";
    fuzz_write("grid.vtk", (const uint8_t *)grid, sizeof grid - 1);
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static int once;
    if (!once) {
        vv_memory_budget_set(SCENE_FUZZ_BUDGET);
        scene_files();
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
