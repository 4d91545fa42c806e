/*
 * libFuzzer harness: .vvc compressed volumes (vv_vvc_from_memory,
 * vv_vvc_get_info, one subcube decoded alone, then the whole volume;
 * src/compress/).
 *
 * Every section of a .vvc ends with a CRC-32 (the header, version 2's
 * header extension, the tables, the subcube index, the data), so a mutated
 * input rarely gets past the first check. The input is read twice: as it
 * is, then (when that differs) with each CRC-32 it holds made right for the
 * bytes it covers, so that the fuzzer explores the fields behind the
 * checksums. The first also goes through a file (vv_vvc_load: the magic and
 * size checks before the read, and vv_vvc_save of what was read). A small
 * volume decoded is compressed again (the writer) and must parse.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* the layout of src/compress/vvc_internal.h and vvc_format.c */
#define HDR1 244  /* version 1's header; its CRC-32 in the last 4 bytes */
#define HDR2 264  /* version 2's: + max error, correction step, their CRC-32 */
#define SIZES 216 /* the tables', index's and data's sizes (3 x u64) */
/* a valid file decompressed: at most this many voxel bytes (one exec, milliseconds) */
#define MAX_RAW ((uint64_t)1 << 21)
/* ... and compressed again: at most this many voxels in its subcubes */
#define MAX_RECOMPRESS ((uint64_t)1 << 13)

static uint32_t
get32(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t
get64(const uint8_t *p) {
    return (uint64_t)get32(p) | (uint64_t)get32(p + 4) << 32;
}

/* Writes at @p at the CRC-32 of the @p n bytes at @p from. */
static void
put_crc(uint8_t *from, uint64_t n, uint8_t *at) {
    const uint32_t c = (uint32_t)crc32(crc32(0L, Z_NULL, 0), from, (uInt)n);
    for (int i = 0; i < 4; i++)
        at[i] = (uint8_t)(c >> (8 * i));
}

/* Makes every CRC-32 of @p b right where the sizes the header claims fit. */
static void
fix_crcs(uint8_t *b, size_t size) {
    if (size < HDR1)
        return;
    const uint32_t version = get32(b + 8);
    const uint64_t hbytes = version >= 2 ? HDR2 : HDR1;
    if (hbytes > HDR1 && size >= hbytes)
        put_crc(b + HDR1, hbytes - HDR1 - 4, b + hbytes - 4);
    const uint64_t ts = get64(b + SIZES), is = get64(b + SIZES + 8), ds = get64(b + SIZES + 16);
    const uint64_t rest = size >= hbytes ? size - hbytes : 0;
    if (ts >= 8 && ts <= rest)
        put_crc(b + hbytes, ts - 4, b + hbytes + ts - 4);
    if (ts <= rest && is >= 4 && is <= rest - ts)
        put_crc(b + hbytes + ts, is - 4, b + hbytes + ts + is - 4);
    if (ts <= rest && is <= rest - ts && ds >= 4 && ds <= rest - ts - is)
        put_crc(b + hbytes + ts + is, ds - 4, b + hbytes + ts + is + ds - 4);
    put_crc(b, HDR1 - 4, b + HDR1 - 4);
}

/* A small volume decoded is compressed again as its file was (version,
 * subcube side, quality or error bound, slope): what the writer makes must
 * parse. */
static void
recompress(const vv_volume *v, const vv_vvc_info *info) {
    const uint64_t M = (uint64_t)info->block;
    if ((uint64_t)info->subcubes[0] * (uint64_t)info->subcubes[1] * (uint64_t)info->subcubes[2] *
            M * M * M >
        MAX_RECOMPRESS)
        return;
    vv_vvc_params p;
    vv_vvc_params_init(&p);
    p.block = info->block;
    p.version = info->version;
    p.threads = 1;
    p.quality = info->quality >= 0 && info->quality <= 100 ? info->quality : 50;
    p.slope = info->slope >= 0 && info->slope <= 100 ? info->slope : 0.5;
    if (info->version >= 2 && info->max_error > 0) {
        p.target = VV_VVC_MAX_ERROR;
        p.max_error = info->max_error;
    }
    vv_vvc *c = NULL;
    const vv_status s = vv_vvc_compress(&c, v, &p);
    fuzz_check_status(s);
    if (s != VV_OK)
        return;
    size_t n = 0;
    const unsigned char *bytes = vv_vvc_bytes(c, &n);
    vv_vvc *d = NULL;
    if (vv_vvc_from_memory(&d, bytes, n, "again.vvc") != VV_OK)
        __builtin_trap(); /* what the writer wrote, the reader reads */
    vv_vvc_free(d);
    vv_vvc_free(c);
}

static void
read_one(const uint8_t *data, size_t size, int through_file) {
    vv_vvc *c = NULL;
    vv_status s;
    if (through_file) {
        s = vv_vvc_load(&c, fuzz_write("in.vvc", data, size));
        fuzz_check_status(s);
        if (s != VV_OK)
            return;
        size_t n = 0;
        if (vv_vvc_bytes(c, &n) == NULL || n != size)
            __builtin_trap(); /* what was read is the file */
        fuzz_check_status(vv_vvc_save(c, fuzz_write("out.vvc", NULL, 0)));
        vv_vvc_free(c);
        return;
    }
    s = vv_vvc_from_memory(&c, data, size, "in.vvc");
    fuzz_check_status(s);
    if (s != VV_OK)
        return;
    vv_vvc_info info;
    vv_vvc_get_info(c, &info);
    int n = vv_vvc_subcube_count(c);
    if (n > 0 && info.block > 0 && info.block <= 32) {
        size_t m = (size_t)info.block;
        float *vals = malloc(m * m * m * sizeof *vals);
        if (vals) {
            vv_vvc_decode_subcube(c, n - 1, vals);
            free(vals);
        }
    }
    vv_volume *v = NULL;
    if (info.raw_bytes <= MAX_RAW && vv_vvc_decompress(&v, c, 1, NULL) == VV_OK) {
        recompress(v, &info);
        fuzz_check_volume(v);
    }
    vv_vvc_free(c);
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    read_one(data, size, 0);
    read_one(data, size, 1);
    uint8_t *fixed = malloc(size ? size : 1);
    if (!fixed)
        return 0;
    memcpy(fixed, data, size);
    fix_crcs(fixed, size);
    if (memcmp(fixed, data, size) != 0)
        read_one(fixed, size, 0);
    free(fixed);
    return 0;
}
