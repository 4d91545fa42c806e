/*
 * libFuzzer harness: raw volumes and their descriptions. The first line of
 * the input is a --raw description as the CLI parses it
 * (cli_parse_raw, apps/volvis/options.c: "WxHxD:TYPE[:be|le][:SXxSYxSZ]
 * [:skip=N]"), the rest the file read with vv_volume_load (src/io/volume/raw.c).
 * Then the file is opened by bricks as the CLI opens a raw file out of
 * core (vv_bricked_open: its layout, vv_raw_layout, and the scan for the
 * range and every brick's min/max; vv_bricked_open_header: without the
 * scan), each brick read, a box across bricks and a proxy, in a cache of
 * its own (32 KiB for a file of an odd size, so that bricks are evicted;
 * 1 MiB otherwise). An input starting with '@' is a vv_raw_params as it
 * is in memory, then the file, read by vv_volume_load: vv_raw_read's own
 * checks of what a library caller passes (a voxel type, sizes, spacing or
 * origin the CLI's parser would refuse).
 */
#include "cli.h"
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "io/store/bricked.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The file by bricks (with the scan for the range, or its header alone and
 * a range set): every brick (at most 8), a box across the first two along
 * x, a proxy, the statistics. */
static void
by_bricks(const char *path, const vv_raw_params *raw, int scan, uint64_t limit) {
    static vv_cache *cache; /* one cache for every input, as a process has */
    if (!cache && vv_cache_new(&cache, limit) != VV_OK)
        __builtin_trap();
    vv_cache_set_limit(cache, limit);
    vv_bricked *b = NULL;
    vv_status s =
        scan ? vv_bricked_open(&b, path, raw, cache) : vv_bricked_open_header(&b, path, raw, cache);
    fuzz_check_status(s);
    if (s != VV_OK)
        return;
    if (!scan)
        vv_bricked_set_range(b, 0, 1);
    for (int i = 0; i < vv_bricked_count(b) && i < 8; i++) {
        vv_volume *v = NULL;
        if ((s = vv_bricked_load(b, i, &v)) == VV_OK)
            fuzz_check_volume(v);
        fuzz_check_status(s);
    }
    const vv_volume *h = vv_bricked_header(b);
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = h->dims[a] > 70 ? 60 : 0;
        hi[a] = h->dims[a] - 1 < lo[a] + 9 ? h->dims[a] - 1 : lo[a] + 9;
    }
    vv_volume *v = NULL;
    if ((s = vv_bricked_box(b, lo, hi, &v)) == VV_OK)
        fuzz_check_volume(v);
    fuzz_check_status(s);
    v = NULL;
    if ((s = vv_bricked_proxy(b, 8, &v)) == VV_OK)
        fuzz_check_volume(v);
    fuzz_check_status(s);
    vv_bricked_stats st;
    vv_bricked_stats_get(b, &st);
    vv_bricked_free(b);
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size > sizeof(vv_raw_params) && data[0] == '@') {
        /* the parameters as a library caller passes them, unchecked */
        vv_load_options o;
        vv_load_options_init(&o);
        o.format = VV_FORMAT_RAW;
        o.has_raw = 1;
        memcpy(&o.raw, data + 1, sizeof o.raw);
        const char *path = fuzz_write("in.raw", data + 1 + sizeof o.raw, size - 1 - sizeof o.raw);
        vv_volume *v = NULL;
        vv_status s = vv_volume_load(&v, path, &o);
        fuzz_check_status(s);
        if (s == VV_OK)
            fuzz_check_volume(v);
        return 0;
    }
    const uint8_t *h, *d;
    size_t nh, nd;
    fuzz_split(data, size, "\n", &h, &nh, &d, &nd);
    if (nh > 256)
        return 0;
    char spec[257];
    memcpy(spec, h, nh);
    spec[nh] = '\0';
    if (strlen(spec) != nh)
        return 0; /* a NUL inside: not something a command line can hold */
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_RAW;
    o.has_raw = 1;
    if (cli_parse_raw(NULL, "raw", spec, &o.raw) != 0)
        return 0;
    const char *path = fuzz_write("in.raw", d, nd);
    vv_volume *v = NULL;
    if (vv_volume_load(&v, path, &o) == VV_OK)
        fuzz_check_volume(v);
    /* a cache of 32 KiB for an odd file (bricks evicted), 1 MiB otherwise */
    const uint64_t limit = nd & 1 ? (uint64_t)32 << 10 : (uint64_t)1 << 20;
    by_bricks(path, &o.raw, 1, limit);
    by_bricks(path, &o.raw, 0, limit);
    /* no description: by the format detected (not an NRRD, whose layout Teem reads) */
    if (nd < 4 || memcmp(d, "NRRD", 4) != 0)
        by_bricks(path, NULL, 1, limit);
    return 0;
}
