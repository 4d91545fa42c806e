/*
 * One HTTP response as libcurl hands it over (not installed; the transport
 * of bytesrc_http.c and the fuzz harness tests/fuzz/fuzz_http.c): header
 * lines one at a time (the status line of each response, redirects and
 * interim ones included), body pieces, then a check of the whole against
 * what was asked (a byte range, a suffix, a whole object) and the budget.
 * Pure: no network, no allocation beyond the body (at most the budget).
 */
#ifndef VOLVIS_IO_HTTP_RESP_H
#define VOLVIS_IO_HTTP_RESP_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/core.h"

/* asked.off: the last asked.len bytes (a suffix); asked.len: to the end */
#define HTTP_SUFFIX UINT64_MAX
#define HTTP_ALL UINT64_MAX
/* The bytes of an error response's body kept (the S3 error code). */
#define HTTP_ERR_BODY_MAX 16384
/* The most bytes of a whole object taken when a server answers a byte
 * range with 200 and the whole object (sliced here). */
#define HTTP_WHOLE_MAX ((uint64_t)64 << 20)

/* What one response says and holds. */
typedef struct http_resp {
    /* asked: bytes [off, off + len) (off HTTP_SUFFIX: the last len; len
     * HTTP_ALL: to the end), ranged when a Range header was sent; head: a
     * HEAD request (no body); max: the most bytes the caller takes */
    uint64_t off, len, max;
    int ranged, head;
    /* the most of a whole object taken for a range (HTTP_WHOLE_MAX unless
     * the caller lowers it: the transport shares a quarter of the memory
     * budget among its requests in flight) */
    uint64_t whole_max;
    /* heard (the last response's headers) */
    int status; /* 0 until a status line */
    int has_clen, has_crange, crange_bad;
    uint64_t clen, cr_first, cr_last, cr_total; /* cr_total UINT64_MAX: "*" */
    char etag[128];
    char encoding[64]; /* Content-Encoding, "" none */
    int headers_done;
    /* the body: kept up to cap (set when the headers are done) */
    unsigned char *buf;
    size_t n, cap, alloc;
    uint64_t received; /* body bytes heard, kept or not */
    /* why the transfer was stopped ("" none) */
    char why[256];
    vv_status why_status;
} http_resp;

/* @p r ready for a request of bytes [off, off + len) (see http_resp),
 * at most @p max bytes taken. */
void http_resp_init(http_resp *r, uint64_t off, uint64_t len, uint64_t max, int ranged, int head);

/* Frees @p r's body; @p r may be zeroed. */
void http_resp_free(http_resp *r);

/* Forgets what a previous response said (a retry, a redirect). */
void http_resp_reset(http_resp *r);

/* One header line (@p n bytes, not NUL-terminated, CRLF included or not)
 * heard. 1 to go on, 0 to stop the transfer (r->why says why: a
 * Content-Length over the budget, a Content-Encoding not asked for). */
int http_resp_header(http_resp *r, const char *line, size_t n);

/* @p n body bytes heard. 1 to go on, 0 to stop the transfer (over the
 * budget: r->why). */
int http_resp_body(http_resp *r, const void *p, size_t n);

/* The S3 error code (<Code>X</Code>) of an error response's body into
 * @p code (@p cap bytes; "" when none). */
void http_resp_s3_code(const http_resp *r, char *code, size_t cap);

/* The end of a response (status 2xx, or 404/416; the caller handles the
 * rest): the asked bytes checked against the status, Content-Range and
 * Content-Length and moved into *out (free it; its bytes *n), the object's
 * size into *size (UINT64_MAX when the server did not say). 404: VV_OK
 * with *missing = 1. Errors (the message does not name the URL: the
 * caller prefixes it): VV_ERR_FORMAT (a wrong Content-Range, a truncated
 * body, a range past the end), VV_ERR_LIMIT (over max). */
vv_status http_resp_finish(http_resp *r, unsigned char **out, size_t *n, uint64_t *size,
                           int *missing);

#endif
