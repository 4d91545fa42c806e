/*
 * libFuzzer harness: our checks of a mesh file before Assimp sees it
 * (vv_mesh_prescan; src/io/mesh/mesh.c): the size, and the structure of OFF,
 * STL and PLY files against what the file holds. Assimp itself runs in the
 * reader sandbox (volvis-reader), whose parent side fuzz_sandbox fuzzes;
 * it is not called here. The file name's extension follows the content
 * (OFF, PLY, STL, else OBJ), as a user's file would be named.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/prescan.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

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
    fuzz_check_status(vv_mesh_prescan(fuzz_write(name, data, size)));
    return 0;
}
