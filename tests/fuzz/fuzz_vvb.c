/*
 * libFuzzer harness: .vvb bricked volumes (src/io/store/bricked.c, vvb_read.c): the header
 * and index checks of vv_bricked_open, then up to 8 bricks read (raw or
 * zstd frames decoded), a box across bricks and a small proxy (from the
 * coarse levels when the file has them); then the file as a pyramid
 * (vv_pyramid_open: the level table and indices checked) and a small box
 * of every level read (level 0 from the bricks, the others from their
 * chunks). The input is the file.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/store/bricked.h"
#include "io/store/pyramid.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static vv_cache *cache; /* one budget for every input, as a process has */
    if (!cache && vv_cache_new(&cache, (uint64_t)64 << 20) != VV_OK)
        __builtin_trap();
    vv_bricked *b = NULL;
    const char *path = fuzz_write("in.vvb", data, size);
    if (vv_bricked_open(&b, path, NULL, cache) != VV_OK)
        return 0;
    const int n = vv_bricked_count(b);
    for (int i = 0; i < n && i < 8; i++) {
        vv_volume *v = NULL;
        if (vv_bricked_load(b, i, &v) == VV_OK)
            fuzz_check_volume(v);
    }
    const vv_volume *h = vv_bricked_header(b);
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = h->dims[a] > 70 ? 60 : 0;
        hi[a] = h->dims[a] - 1 < lo[a] + 9 ? h->dims[a] - 1 : lo[a] + 9;
    }
    vv_volume *v = NULL;
    if (vv_bricked_read_box(b, lo, hi, &v) == VV_OK)
        fuzz_check_volume(v);
    v = NULL;
    if (vv_bricked_proxy(b, 16, &v) == VV_OK)
        fuzz_check_volume(v);
    vv_bricked_free(b);
    vv_pyramid *p = NULL;
    if (vv_pyramid_open(&p, path, -1, -1, cache, NULL) != VV_OK)
        return 0;
    for (int l = 0; l < vv_pyramid_levels(p); l++) {
        const vv_volume *lh = vv_pyramid_level(p, l);
        for (int a = 0; a < 3; a++) {
            lo[a] = lh->dims[a] / 3;
            hi[a] = lh->dims[a] - 1 < lo[a] + 9 ? lh->dims[a] - 1 : lo[a] + 9;
        }
        v = NULL;
        if (vv_pyramid_read_box(p, l, lo, hi, &v) == VV_OK)
            fuzz_check_volume(v);
    }
    vv_pyramid_free(p);
    return 0;
}
