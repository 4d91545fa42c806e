/*
 * Streaming plain, zlib or gzip output (zout.h) over zlib's deflate, on
 * every core.
 *
 * The input is cut into blocks of ZOUT_BLOCK bytes at fixed offsets of the
 * stream. Each block is deflated on its own (raw deflate, the 32 KiB of
 * input before it as the dictionary, so the ratio is that of one stream),
 * ended with a sync flush, which leaves it on a byte boundary; the blocks
 * are written in order and the stream ends with an empty final block. The
 * check value (CRC-32 for gzip, Adler-32 for zlib) of each block is
 * computed by the same worker and combined in order. This is pigz's
 * scheme: the output is one valid deflate stream that any inflater reads,
 * and it depends on the block size only, never on the thread count.
 *
 * Blocks are gathered into a batch of a few per thread before they are
 * compressed together (vv_parallel_for), so memory stays bounded by two
 * batches (input and output) whatever the size of the volume.
 */
#include "zout.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include "core/parallel_for.h"

#define ZOUT_BLOCK (1u << 20) /* input bytes per independently deflated block */
#define ZOUT_DICT 32768u      /* deflate's window: the dictionary of a block */

typedef struct zout_block {
    unsigned char *out;
    size_t cap, n;
    uLong check; /* crc32 or adler32 of the block's input */
    size_t in_n;
    int failed;
} zout_block;

struct vv_zout {
    FILE *fp;
    vv_zout_mode mode;
    uint64_t written;
    uint64_t total_in;
    uLong check; /* of everything compressed so far */
    int started; /* the header is out */
    int first;   /* no block compressed yet: no dictionary */
    int threads;
    size_t batch;       /* blocks per batch */
    unsigned char *in;  /* ZOUT_DICT of dictionary, then batch * ZOUT_BLOCK */
    size_t in_n;        /* bytes of input after the dictionary */
    zout_block *blocks; /* batch */
};

vv_status
vv_zout_begin(vv_zout **out, FILE *fp, vv_zout_mode mode) {
    vv_zout *z = calloc(1, sizeof *z);
    if (!z)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    z->fp = fp;
    z->mode = mode;
    z->first = 1;
    if (mode != VV_ZOUT_PLAIN) {
        z->threads = vv_threads_get();
        if (z->threads < 1)
            z->threads = 1;
        if (z->threads > 64)
            z->threads = 64;
        /* two blocks per thread, at most 32 MiB of input in flight */
        z->batch = (size_t)(z->threads > 1 ? 2 * z->threads : 1);
        if (z->batch > 32)
            z->batch = 32;
        z->check = mode == VV_ZOUT_GZIP ? crc32(0, NULL, 0) : adler32(0, NULL, 0);
        z->in = malloc(ZOUT_DICT + z->batch * ZOUT_BLOCK);
        z->blocks = calloc(z->batch, sizeof *z->blocks);
        size_t cap = deflateBound(NULL, ZOUT_BLOCK) + 64;
        for (size_t b = 0; z->blocks && b < z->batch; b++) {
            z->blocks[b].out = malloc(cap);
            z->blocks[b].cap = cap;
            if (!z->blocks[b].out) {
                z->in = (free(z->in), NULL);
                break;
            }
        }
        if (!z->in || !z->blocks) {
            vv_zout_abort(z);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
    }
    *out = z;
    return VV_OK;
}

static vv_status
put(vv_zout *z, const void *p, size_t n) {
    if (n && fwrite(p, 1, n, z->fp) != n)
        return vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno ? errno : EIO));
    z->written += n;
    return VV_OK;
}

static void
put_le32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

/* The gzip header (zlib's own at level 1: no name, mtime 0, XFL 4 "fastest",
 * OS 3 Unix) or the zlib header (deflate, 32 KiB window, FLEVEL 0). */
static vv_status
header(vv_zout *z) {
    static const unsigned char gz[10] = {0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 4, 3};
    static const unsigned char zl[2] = {0x78, 0x01};
    z->started = 1;
    return z->mode == VV_ZOUT_GZIP ? put(z, gz, sizeof gz) : put(z, zl, sizeof zl);
}

typedef struct batch_job {
    vv_zout *z;
    size_t nblocks;
} batch_job;

/* Deflates block @p b of the batch: raw, with the 32 KiB before it as the
 * dictionary (none for the stream's first), ended by a sync flush. */
static void
deflate_block(vv_zout *z, size_t b) {
    zout_block *bl = &z->blocks[b];
    const unsigned char *in = z->in + ZOUT_DICT + b * ZOUT_BLOCK;
    size_t n = z->in_n - b * ZOUT_BLOCK < ZOUT_BLOCK ? z->in_n - b * ZOUT_BLOCK : ZOUT_BLOCK;
    bl->in_n = n;
    bl->n = 0;
    bl->failed = 0;
    bl->check = z->mode == VV_ZOUT_GZIP ? crc32(crc32(0, NULL, 0), in, (uInt)n)
                                        : adler32(adler32(0, NULL, 0), in, (uInt)n);
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (deflateInit2(&zs, VV_ZOUT_LEVEL, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        bl->failed = 1;
        return;
    }
    if (!(z->first && b == 0) && deflateSetDictionary(&zs, in - ZOUT_DICT, ZOUT_DICT) != Z_OK)
        bl->failed = 1;
    zs.next_in = (Bytef *)in;
    zs.avail_in = (uInt)n;
    zs.next_out = bl->out;
    zs.avail_out = (uInt)bl->cap;
    if (!bl->failed &&
        (deflate(&zs, Z_SYNC_FLUSH) != Z_OK || zs.avail_in != 0 || zs.avail_out == 0))
        bl->failed = 1; /* the bound was not enough: cannot happen */
    bl->n = bl->cap - zs.avail_out;
    deflateEnd(&zs);
}

static void
batch_body(void *ctx, long i0, long i1, int worker) {
    (void)worker;
    batch_job *j = ctx;
    for (long b = i0; b < i1; b++)
        deflate_block(j->z, (size_t)b);
}

/* Compresses the gathered input and writes it; keeps its last 32 KiB as the
 * next batch's dictionary. */
static vv_status
flush_batch(vv_zout *z) {
    if (z->in_n == 0)
        return VV_OK;
    vv_status s = z->started ? VV_OK : header(z);
    if (s != VV_OK)
        return s;
    batch_job j = {z, (z->in_n + ZOUT_BLOCK - 1) / ZOUT_BLOCK};
    vv_parallel_for((long)j.nblocks, 1, z->threads, batch_body, &j, NULL);
    for (size_t b = 0; b < j.nblocks && s == VV_OK; b++) {
        const zout_block *bl = &z->blocks[b];
        if (bl->failed)
            return vv_error_set(VV_ERR_IO, "zlib: compressor error");
        s = put(z, bl->out, bl->n);
        z->check = z->mode == VV_ZOUT_GZIP
                       ? crc32_combine(z->check, bl->check, (z_off_t)bl->in_n)
                       : adler32_combine(z->check, bl->check, (z_off_t)bl->in_n);
        z->total_in += bl->in_n;
    }
    /* the dictionary of what comes next: the last ZOUT_DICT bytes of input
     * (a short first batch is never followed: flush_batch runs on a full
     * batch or at the end) */
    if (z->in_n >= ZOUT_DICT)
        memmove(z->in, z->in + ZOUT_DICT + z->in_n - ZOUT_DICT, ZOUT_DICT);
    z->in_n = 0;
    z->first = 0;
    return s;
}

vv_status
vv_zout_write(vv_zout *z, const void *data, uint64_t n) {
    const unsigned char *p = data;
    if (z->mode == VV_ZOUT_PLAIN)
        return put(z, p, (size_t)n);
    size_t cap = z->batch * ZOUT_BLOCK;
    while (n > 0) {
        size_t k = cap - z->in_n < n ? cap - z->in_n : (size_t)n;
        memcpy(z->in + ZOUT_DICT + z->in_n, p, k);
        z->in_n += k;
        p += k;
        n -= k;
        if (z->in_n == cap) {
            vv_status s = flush_batch(z);
            if (s != VV_OK)
                return s;
        }
    }
    return VV_OK;
}

vv_status
vv_zout_end(vv_zout *z, uint64_t *written) {
    vv_status s = VV_OK;
    if (z->mode != VV_ZOUT_PLAIN) {
        s = flush_batch(z);
        if (s == VV_OK && !z->started)
            s = header(z);
        /* an empty final block with fixed codes (BFINAL 1, BTYPE 01, end of
         * block), then the trailer */
        static const unsigned char last[2] = {0x03, 0x00};
        if (s == VV_OK)
            s = put(z, last, sizeof last);
        unsigned char t[8];
        if (s == VV_OK && z->mode == VV_ZOUT_GZIP) {
            put_le32(t, (uint32_t)z->check);
            put_le32(t + 4, (uint32_t)z->total_in);
            s = put(z, t, 8);
        } else if (s == VV_OK) {
            for (int i = 0; i < 4; i++)
                t[i] = (unsigned char)(z->check >> (24 - 8 * i));
            s = put(z, t, 4);
        }
    }
    if (written)
        *written = z->written;
    vv_zout_abort(z);
    return s;
}

void
vv_zout_abort(vv_zout *z) {
    if (!z)
        return;
    for (size_t b = 0; z->blocks && b < z->batch; b++)
        free(z->blocks[b].out);
    free(z->blocks);
    free(z->in);
    free(z);
}
