/*
 * libFuzzer harness: the HTTP response handling of the remote byte
 * sources (src/io/store/http_resp.c), fed as libcurl feeds it: header
 * lines one at a time (status lines of interim responses and redirects
 * included), then the body (chunked transfer encoding already undone by
 * libcurl) in pieces of any size, then the check of the whole against the
 * request.
 *
 * Input: 8 bytes of request -- flags (bit 0: a range was asked, bit 1: a
 * HEAD, bits 2-3: the range's kind: bytes [off, off + len), the last len
 * bytes, from off to the end, the whole object), off, len and max (16 bits
 * each, little-endian), the body's piece size (1 + byte) -- then header
 * lines ending at "\n", an empty line, and the body.
 *
 * What must hold: never more body kept than the budget (the range asked,
 * at most max; a whole object answering a range up to HTTP_WHOLE_MAX);
 * on success exactly the bytes asked (len, or the suffix, or the object's
 * rest) and at most max of them; a missing object holds no bytes; every
 * error is one printable line; nothing leaks (ASan).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/store/http_resp.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void
one_line(const char *m) {
    if (!m || !m[0])
        __builtin_trap();
    for (const char *p = m; *p; p++)
        if ((unsigned char)*p < 0x20)
            __builtin_trap();
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 8)
        return 0;
    const int flags = data[0];
    uint64_t off = (uint64_t)data[1] | (uint64_t)data[2] << 8;
    uint64_t len = (uint64_t)data[3] | (uint64_t)data[4] << 8;
    const uint64_t max = (uint64_t)data[5] | (uint64_t)data[6] << 8;
    const size_t piece = 1 + (size_t)data[7];
    const int kind = (flags >> 2) & 3;
    int ranged = flags & 1, head = (flags >> 1) & 1;
    if (kind == 1)
        off = HTTP_SUFFIX;
    else if (kind == 2)
        len = HTTP_ALL;
    else if (kind == 3) {
        off = 0;
        len = HTTP_ALL;
        ranged = 0;
    }
    if (kind != 3)
        ranged = 1;
    if (len == 0 && kind != 2)
        head = 1;
    http_resp r;
    http_resp_init(&r, off, len, max, ranged, head);
    const char *p = (const char *)data + 8;
    size_t n = size - 8;
    int go = 1;
    /* header lines to the first empty one */
    while (go && n > 0) {
        const char *e = memchr(p, '\n', n);
        const size_t l = e ? (size_t)(e - p) + 1 : n;
        go = http_resp_header(&r, p, l);
        const int blank = l == 1 || (l == 2 && p[0] == '\r');
        p += l;
        n -= l;
        if (blank)
            break;
    }
    /* the body in pieces */
    while (go && n > 0 && !head) {
        const size_t k = n < piece ? n : piece;
        go = http_resp_body(&r, p, k);
        p += k;
        n -= k;
        /* the budget is never passed: what is kept fits the cap */
        if (r.n > r.cap || (r.status == 206 && r.n > max))
            __builtin_trap();
    }
    unsigned char *out = NULL;
    size_t got = 0;
    uint64_t osize = 0;
    int missing = 0;
    const vv_status s = http_resp_finish(&r, &out, &got, &osize, &missing);
    if (s == VV_OK) {
        if (missing && out)
            __builtin_trap();
        if (!missing && !out)
            __builtin_trap();
        if (!missing && !head) {
            if (got > max)
                __builtin_trap();
            if (len != HTTP_ALL && got != len)
                __builtin_trap();
            if (len == HTTP_ALL && osize != UINT64_MAX && off != HTTP_SUFFIX && got != osize - off)
                __builtin_trap();
        }
    } else {
        one_line(vv_error_message());
        if (out)
            __builtin_trap();
    }
    free(out);
    http_resp_free(&r);
    vv_error_clear();
    return 0;
}
