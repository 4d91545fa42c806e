/*
 * One HTTP response checked against its request (http_resp.h): status
 * line, Content-Length, Content-Range, ETag and Content-Encoding parsed
 * strictly, the body kept up to what was asked (never more than the
 * caller's budget, whatever Content-Length says), then the bytes asked cut
 * out and checked. Every way a server can answer a byte range is handled
 * or refused: 206 with the exact range, 200 with the whole object (sliced,
 * up to HTTP_WHOLE_MAX), 416 past the end, a Content-Range that is not the
 * range asked, a body shorter or longer than announced.
 */
#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "io/store/http_resp.h"

void
http_resp_init(http_resp *r, uint64_t off, uint64_t len, uint64_t max, int ranged, int head) {
    memset(r, 0, sizeof *r);
    r->off = off;
    r->len = len;
    r->max = max;
    r->ranged = ranged;
    r->head = head;
    r->whole_max = HTTP_WHOLE_MAX;
}

void
http_resp_free(http_resp *r) {
    free(r->buf);
    r->buf = NULL;
    r->n = r->cap = r->alloc = 0;
}

void
http_resp_reset(http_resp *r) {
    const uint64_t wm = r->whole_max;
    http_resp_free(r);
    http_resp_init(r, r->off, r->len, r->max, r->ranged, r->head);
    r->whole_max = wm;
}

/* Stops the transfer: 0 with r->why. */
static int stop(http_resp *r, vv_status s, const char *fmt, ...) VV_PRINTF(3, 4);
static int
stop(http_resp *r, vv_status s, const char *fmt, ...) {
    if (!r->why[0]) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(r->why, sizeof r->why, fmt, ap);
        va_end(ap);
        r->why_status = s;
    }
    return 0;
}

/* A decimal number of @p p (@p n bytes, digits only, no overflow) into *v. */
static int
parse_u64(const char *p, size_t n, uint64_t *v) {
    if (n == 0 || n > 20)
        return 0;
    uint64_t x = 0;
    for (size_t i = 0; i < n; i++) {
        if (p[i] < '0' || p[i] > '9')
            return 0;
        const uint64_t d = (uint64_t)(p[i] - '0');
        if (x > (UINT64_MAX - d) / 10)
            return 0;
        x = x * 10 + d;
    }
    *v = x;
    return 1;
}

/* A Content-Range value (@p n bytes at @p p, trimmed): "bytes A-B/T", with T a
 * number or a star (size unknown), or a star and T (an unsatisfied range). */
static void
parse_crange(http_resp *r, const char *p, size_t n) {
    r->has_crange = 1;
    r->crange_bad = 1;
    r->cr_total = UINT64_MAX;
    if (n < 6 || strncasecmp(p, "bytes", 5) || (p[5] != ' ' && p[5] != '='))
        return;
    p += 6;
    n -= 6;
    while (n && *p == ' ')
        p++, n--;
    const char *slash = memchr(p, '/', n);
    if (!slash)
        return;
    const char *t = slash + 1;
    const size_t tn = n - (size_t)(t - p);
    uint64_t total = UINT64_MAX;
    if (!(tn == 1 && *t == '*') && !parse_u64(t, tn, &total))
        return;
    r->cr_total = total;
    const size_t rn = (size_t)(slash - p);
    if (rn == 1 && *p == '*')
        return; /* "* /T": an unsatisfied range (416), no bytes */
    const char *dash = memchr(p, '-', rn);
    uint64_t a, b;
    if (!dash || !parse_u64(p, (size_t)(dash - p), &a) ||
        !parse_u64(dash + 1, rn - (size_t)(dash - p) - 1, &b) || b < a ||
        (total != UINT64_MAX && b >= total))
        return;
    r->cr_first = a;
    r->cr_last = b;
    r->crange_bad = 0;
}

/* The body's cap once the headers are heard; 0 when the transfer stops. */
static int
headers_done(http_resp *r) {
    r->headers_done = 1;
    if (r->head) {
        r->cap = 0;
        return 1;
    }
    if (r->status < 200 || r->status >= 300) {
        r->cap = HTTP_ERR_BODY_MAX;
        return 1;
    }
    if (r->encoding[0] && strcasecmp(r->encoding, "identity")) {
        snprintf(r->why, sizeof r->why,
                 "the server sent Content-Encoding \"%.60s\", not asked for (refused)",
                 r->encoding);
        r->why_status = VV_ERR_FORMAT;
        return 0;
    }
    if (r->status == 206) {
        if (!r->has_crange || r->crange_bad)
            return stop(r, VV_ERR_FORMAT, "206 without a valid Content-Range");
        if (!r->ranged)
            return stop(r, VV_ERR_FORMAT, "206 (a part) to a request for the whole object");
        const uint64_t count = r->cr_last - r->cr_first + 1;
        if (count > r->max)
            return stop(r, VV_ERR_LIMIT, "a part of %llu bytes (limit %llu)",
                        (unsigned long long)count, (unsigned long long)r->max);
        r->cap = (size_t)count;
    } else if (r->ranged) {
        /* the whole object for a range: taken up to whole_max, sliced */
        r->cap = (size_t)r->whole_max;
        if (r->has_clen && r->clen > r->whole_max)
            return stop(r, VV_ERR_LIMIT,
                        "the server ignored the byte range: the whole object of %llu bytes "
                        "(at most %llu taken)",
                        (unsigned long long)r->clen, (unsigned long long)r->whole_max);
    } else {
        r->cap = r->max > SIZE_MAX ? SIZE_MAX : (size_t)r->max;
        if (r->has_clen && r->clen > r->max)
            return stop(r, VV_ERR_LIMIT, "%llu bytes (limit %llu)", (unsigned long long)r->clen,
                        (unsigned long long)r->max);
    }
    if (r->has_clen && r->clen > r->cap)
        return stop(r, VV_ERR_FORMAT, "Content-Length %llu, more than the %llu bytes asked",
                    (unsigned long long)r->clen, (unsigned long long)r->cap);
    return 1;
}

int
http_resp_header(http_resp *r, const char *line, size_t n) {
    while (n && (line[n - 1] == '\n' || line[n - 1] == '\r'))
        n--;
    if (n == 0) /* the end of one response's headers */
        return r->status ? headers_done(r) : 1;
    if (n > 5 && !strncmp(line, "HTTP/", 5)) {
        /* a new response (an interim 100, a redirect's): what the last said is forgotten */
        http_resp_free(r);
        const uint64_t wm = r->whole_max;
        http_resp_init(r, r->off, r->len, r->max, r->ranged, r->head);
        r->whole_max = wm;
        const char *sp = memchr(line, ' ', n);
        const size_t rest = sp ? n - (size_t)(sp + 1 - line) : 0;
        if (!sp || rest < 3 || !isdigit((unsigned char)sp[1]) || !isdigit((unsigned char)sp[2]) ||
            !isdigit((unsigned char)sp[3]) || (rest > 3 && sp[4] != ' '))
            return stop(r, VV_ERR_FORMAT, "a malformed status line");
        r->status = (sp[1] - '0') * 100 + (sp[2] - '0') * 10 + (sp[3] - '0');
        if (r->status < 100)
            return stop(r, VV_ERR_FORMAT, "a malformed status line");
        return 1;
    }
    if (!r->status)
        return stop(r, VV_ERR_FORMAT, "a header before the status line");
    const char *colon = memchr(line, ':', n);
    if (!colon)
        return 1; /* a folded or malformed line: ignored, as curl does */
    const size_t kn = (size_t)(colon - line);
    const char *v = colon + 1;
    size_t vn = n - kn - 1;
    while (vn && (*v == ' ' || *v == '\t'))
        v++, vn--;
    while (vn && (v[vn - 1] == ' ' || v[vn - 1] == '\t'))
        vn--;
    if (kn == 14 && !strncasecmp(line, "Content-Length", 14)) {
        uint64_t x;
        if (!parse_u64(v, vn, &x) || (r->has_clen && x != r->clen))
            return stop(r, VV_ERR_FORMAT, "a malformed Content-Length");
        r->has_clen = 1;
        r->clen = x;
    } else if (kn == 13 && !strncasecmp(line, "Content-Range", 13)) {
        if (r->has_crange)
            return stop(r, VV_ERR_FORMAT, "two Content-Range headers");
        parse_crange(r, v, vn);
    } else if (kn == 4 && !strncasecmp(line, "ETag", 4)) {
        snprintf(r->etag, sizeof r->etag, "%.*s", (int)(vn < 127 ? vn : 127), v);
    } else if (kn == 16 && !strncasecmp(line, "Content-Encoding", 16)) {
        snprintf(r->encoding, sizeof r->encoding, "%.*s", (int)(vn < 63 ? vn : 63), v);
    }
    return 1;
}

int
http_resp_body(http_resp *r, const void *p, size_t n) {
    if (r->why[0])
        return 0;
    if (!r->headers_done && !headers_done(r))
        return 0;
    r->received += n;
    const int ok = r->status >= 200 && r->status < 300;
    if (!ok) { /* an error's body: its start kept, the rest dropped (up to 16 MiB) */
        if (r->received > ((uint64_t)16 << 20))
            return stop(r, VV_ERR_FORMAT, "an error response of over %llu bytes",
                        (unsigned long long)(16u << 20));
        n = r->n + n > r->cap ? r->cap - r->n : n;
    } else if (n > r->cap - r->n) {
        if (r->status == 206)
            return stop(r, VV_ERR_FORMAT, "more bytes than the Content-Range says (%llu)",
                        (unsigned long long)r->cap);
        if (r->ranged)
            return stop(r, VV_ERR_LIMIT,
                        "the server ignored the byte range: over %llu bytes of the whole object",
                        (unsigned long long)r->cap);
        return stop(r, VV_ERR_LIMIT, "over %llu bytes (the limit)", (unsigned long long)r->cap);
    }
    if (n == 0)
        return 1;
    if (r->n + n > r->alloc) {
        size_t a = r->alloc ? r->alloc : 4096;
        while (a < r->n + n)
            a = a > SIZE_MAX / 2 ? SIZE_MAX : a * 2;
        if (a > r->cap)
            a = r->cap;
        unsigned char *b = realloc(r->buf, a);
        if (!b)
            return stop(r, VV_ERR_NOMEM, "out of memory for %llu bytes", (unsigned long long)a);
        r->buf = b;
        r->alloc = a;
    }
    memcpy(r->buf + r->n, p, n);
    r->n += n;
    return 1;
}

void
http_resp_s3_code(const http_resp *r, char *code, size_t cap) {
    code[0] = '\0';
    if (!r->buf || !r->n || cap == 0)
        return;
    const char *b = (const char *)r->buf;
    for (size_t i = 0; i + 6 <= r->n; i++) {
        if (memcmp(b + i, "<Code>", 6))
            continue;
        size_t j = i + 6, k = 0;
        while (j < r->n && b[j] != '<' && k + 1 < cap) {
            const char c = b[j++];
            code[k++] = isalnum((unsigned char)c) || c == '.' || c == '-' || c == '_' ? c : '?';
        }
        code[k] = '\0';
        return;
    }
}

#define ULL(x) ((unsigned long long)(x))

vv_status
http_resp_finish(http_resp *r, unsigned char **out, size_t *n, uint64_t *size, int *missing) {
    *out = NULL;
    *n = 0;
    *size = UINT64_MAX;
    *missing = 0;
    if (r->why[0])
        return vv_error_set(r->why_status, "%s", r->why);
    if (r->status == 404) {
        *missing = 1;
        return VV_OK;
    }
    if (r->status == 416)
        return r->has_crange && r->cr_total != UINT64_MAX
                   ? vv_error_set(VV_ERR_FORMAT,
                                  "the range asked lies past the object's end (%llu bytes)",
                                  (unsigned long long)r->cr_total)
                   : vv_error_set(VV_ERR_FORMAT, "the range asked lies past the object's end");
    if (r->status < 200 || r->status >= 300)
        return vv_error_set(VV_ERR_FORMAT, "HTTP status %d", r->status);
    if (!r->headers_done && !r->head && !headers_done(r))
        return vv_error_set(r->why_status, "%s", r->why);
    if (r->head) {
        *size = r->has_clen ? r->clen : UINT64_MAX;
        *out = malloc(1);
        return *out ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    if (r->has_clen && r->status != 206 && r->clen != r->received)
        return vv_error_set(VV_ERR_FORMAT, "truncated: %llu of the %llu bytes announced",
                            ULL(r->received), ULL(r->clen));
    uint64_t off = r->off, len = r->len, total;
    if (r->status == 206) {
        const uint64_t count = r->cr_last - r->cr_first + 1;
        total = r->cr_total;
        if (r->received != count || (r->has_clen && r->clen != count))
            return vv_error_set(VV_ERR_FORMAT, "truncated: %llu of the %llu bytes of the part",
                                ULL(r->received), ULL(count));
        if (off == HTTP_SUFFIX) {
            if (total == UINT64_MAX)
                return vv_error_set(VV_ERR_FORMAT, "a suffix answered without the object's size");
            if (total < len)
                return vv_error_set(VV_ERR_FORMAT,
                                    "%llu bytes, fewer than the %llu asked at its end", ULL(total),
                                    ULL(len));
            off = total - len;
        }
        const uint64_t want_last =
            len == HTTP_ALL ? (total == UINT64_MAX ? r->cr_last : total - 1) : off + len - 1;
        if (r->cr_first != off || r->cr_last != want_last) {
            if (r->cr_first == off && total != UINT64_MAX && r->cr_last == total - 1)
                return vv_error_set(VV_ERR_FORMAT, "bytes %llu..%llu past its end (%llu bytes)",
                                    ULL(off), ULL(off + len), ULL(total));
            return vv_error_set(VV_ERR_FORMAT,
                                "Content-Range bytes %llu-%llu is not the range asked (from byte "
                                "%llu)",
                                ULL(r->cr_first), ULL(r->cr_last), ULL(off));
        }
    } else {
        /* 200: the whole object */
        total = r->n;
        if (off == HTTP_SUFFIX) {
            if (total < len)
                return vv_error_set(VV_ERR_FORMAT,
                                    "%llu bytes, fewer than the %llu asked at its end", ULL(total),
                                    ULL(len));
            off = total - len;
        }
        if (len == HTTP_ALL)
            len = off <= total ? total - off : 0;
        if (off > total || len > total - off)
            return vv_error_set(VV_ERR_FORMAT, "bytes %llu..%llu past its end (%llu bytes)",
                                ULL(off), ULL(off + len), ULL(total));
        if (len > r->max)
            return vv_error_set(VV_ERR_LIMIT, "%llu bytes to read (limit %llu)",
                                (unsigned long long)len, (unsigned long long)r->max);
        if (off)
            memmove(r->buf, r->buf + off, (size_t)len);
        r->n = (size_t)len;
    }
    *size = total;
    *n = r->n;
    *out = r->buf ? r->buf : malloc(1);
    r->buf = NULL;
    r->n = r->alloc = 0;
    return *out ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
}
