/*
 * libFuzzer harness: .vvb bricked volumes (src/io/store/bricked.c, vvb_read.c): the header
 * and index checks of vv_bricked_open, then up to 8 bricks read (raw or
 * zstd frames decoded), a box across bricks and a small proxy (from the
 * coarse levels when the file has them); then the file as a pyramid
 * (vv_pyramid_open: the level table and indices checked) and a small box
 * of every level read (level 0 from the bricks, the others from their
 * chunks); then every level asked of the background loader and waited
 * for, and the requests it refuses. The input is the file.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/store/bricked.h"
#include "io/store/pyramid.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The background loader (vv_pyramid_request): every small level's whole
 * box, coarse first, waited for; then the requests it refuses (a level past the
 * last, a box past the level's end, a negative count) and a cancel. */
static void
background(vv_pyramid *p) {
    const int n = vv_pyramid_levels(p);
    int level[VV_PYRAMID_MAX_LEVELS + 1], lo[3 * (VV_PYRAMID_MAX_LEVELS + 1)],
        hi[3 * (VV_PYRAMID_MAX_LEVELS + 1)];
    if (n < 1 || n > VV_PYRAMID_MAX_LEVELS)
        return;
    int m = 0; /* the levels of at most 2^21 voxels: milliseconds */
    for (int l = n - 1; l >= 0; l--) {
        const vv_volume *h = vv_pyramid_level(p, l);
        if ((uint64_t)h->dims[0] * (uint64_t)h->dims[1] * (uint64_t)h->dims[2] > (1u << 21))
            continue;
        level[m] = l;
        for (int a = 0; a < 3; a++) {
            lo[3 * m + a] = 0;
            hi[3 * m + a] = h->dims[a] - 1;
        }
        m++;
    }
    vv_status s = vv_pyramid_request(p, m, level, lo, hi);
    fuzz_check_status(s);
    if (s == VV_OK)
        for (int k = 0; k < 20 && vv_pyramid_loading(p) > 0; k++)
            vv_pyramid_wait(p, 0.1);
    for (int a = 0; a < 3; a++) {
        lo[a] = 0;
        hi[a] = 0;
    }
    level[0] = n;
    fuzz_check_status(vv_pyramid_request(p, 1, level, lo, hi));
    level[0] = 0;
    hi[0] = vv_pyramid_level(p, 0)->dims[0];
    fuzz_check_status(vv_pyramid_request(p, 1, level, lo, hi));
    fuzz_check_status(vv_pyramid_request(p, -1, level, lo, hi));
    fuzz_check_status(vv_pyramid_request(p, 0, level, lo, hi));
    vv_pyramid_stats st;
    vv_pyramid_stats_get(p, &st);
}

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
    vv_bricked_stats st;
    vv_bricked_stats_get(b, &st);
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
    background(p);
    vv_pyramid_free(p);
    return 0;
}
