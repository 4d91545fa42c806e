/*
 * libFuzzer harness: meshes through Assimp (vv_mesh_load; src/io/mesh.c).
 * The file name's extension follows the content (OFF, PLY, STL, else OBJ),
 * as a user's file would be named.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/*
 * Assimp 5.2 leaks the aiMesh / aiNode it was building when many of its
 * loaders (PLY, OBJ, ...) throw on a malformed file (about 1.4 KB per failed
 * load). That is Assimp's bug, not fixable from here for every format (OFF
 * and STL are validated before Assimp sees them, src/io/mesh.c), so those
 * leaks are suppressed to let the fuzzer look for crashes.
 */
const char *__lsan_default_suppressions(void);
const char *__asan_default_options(void);
const char *
__lsan_default_suppressions(void) {
    return "leak:libassimp.so\n";
}
/* full stacks on malloc, so that a leak's libassimp frames are seen (a
 * std::string Assimp leaks shows only libstdc++ frames with the fast
 * unwinder) */
const char *
__asan_default_options(void) {
    return "fast_unwind_on_malloc=0";
}

static int
starts(const uint8_t *d, size_t n, const char *p) {
    size_t k = strlen(p);
    return n >= k && memcmp(d, p, k) == 0;
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *name = "in.obj";
    if (starts(data, size, "OFF") || starts(data, size, "COFF") || starts(data, size, "NOFF"))
        name = "in.off";
    else if (starts(data, size, "ply"))
        name = "in.ply";
    else if (starts(data, size, "solid") || (size >= 84 && !starts(data, size, "v ")))
        name = "in.stl";
    vv_mesh *m = NULL;
    if (vv_mesh_load(&m, fuzz_write(name, data, size)) == VV_OK) {
        for (size_t t = 0; t < m->n_triangles; t++)
            for (int k = 0; k < 3; k++)
                if (m->triangles[3 * t + k] >= m->n_vertices)
                    __builtin_trap();
        vv_mesh_free(m);
    }
    return 0;
}
