/*
 * Streaming plain, zlib or gzip output (zout.h) over zlib's deflate.
 */
#include "zout.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#define ZOUT_BUF (1u << 18)

struct vv_zout {
    FILE *fp;
    vv_zout_mode mode;
    z_stream zs;
    uint64_t written;
    unsigned char buf[ZOUT_BUF];
};

vv_status
vv_zout_begin(vv_zout **out, FILE *fp, vv_zout_mode mode) {
    vv_zout *z = calloc(1, sizeof *z);
    if (!z)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    z->fp = fp;
    z->mode = mode;
    if (mode != VV_ZOUT_PLAIN &&
        deflateInit2(&z->zs, VV_ZOUT_LEVEL, Z_DEFLATED, mode == VV_ZOUT_GZIP ? 31 : 15, 8,
                     Z_DEFAULT_STRATEGY) != Z_OK) {
        free(z);
        return vv_error_set(VV_ERR_NOMEM, "zlib: cannot initialise the compressor");
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

/* Runs deflate over what is in z->zs with @p flush, writing every full buffer. */
static vv_status
pump(vv_zout *z, int flush) {
    int rc;
    do {
        z->zs.next_out = z->buf;
        z->zs.avail_out = ZOUT_BUF;
        rc = deflate(&z->zs, flush);
        if (rc == Z_STREAM_ERROR)
            return vv_error_set(VV_ERR_IO, "zlib: compressor error");
        vv_status s = put(z, z->buf, ZOUT_BUF - z->zs.avail_out);
        if (s != VV_OK)
            return s;
    } while (z->zs.avail_out == 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
    return VV_OK;
}

vv_status
vv_zout_write(vv_zout *z, const void *data, uint64_t n) {
    const unsigned char *p = data;
    if (z->mode == VV_ZOUT_PLAIN)
        return put(z, p, (size_t)n);
    while (n > 0) {
        uInt k = n > (1u << 30) ? (1u << 30) : (uInt)n;
        z->zs.next_in = (Bytef *)p;
        z->zs.avail_in = k;
        vv_status s = pump(z, Z_NO_FLUSH);
        if (s != VV_OK)
            return s;
        p += k;
        n -= k;
    }
    return VV_OK;
}

vv_status
vv_zout_end(vv_zout *z, uint64_t *written) {
    vv_status s = VV_OK;
    if (z->mode != VV_ZOUT_PLAIN) {
        z->zs.next_in = NULL;
        z->zs.avail_in = 0;
        s = pump(z, Z_FINISH);
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
    if (z->mode != VV_ZOUT_PLAIN)
        deflateEnd(&z->zs);
    free(z);
}
