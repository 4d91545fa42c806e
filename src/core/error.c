/* Status names, the thread-local error trace, progress and threads. */
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "volvis/core.h"
#include "vv_version.h"

#define VV_TRACE_MAX 2048

static _Thread_local char trace[VV_TRACE_MAX];

const char *
vv_status_name(vv_status s) {
    switch (s) {
    case VV_OK:
        return "VV_OK";
    case VV_ERR_NOMEM:
        return "VV_ERR_NOMEM";
    case VV_ERR_IO:
        return "VV_ERR_IO";
    case VV_ERR_FORMAT:
        return "VV_ERR_FORMAT";
    case VV_ERR_INVALID:
        return "VV_ERR_INVALID";
    case VV_ERR_UNSUPPORTED:
        return "VV_ERR_UNSUPPORTED";
    case VV_ERR_LIMIT:
        return "VV_ERR_LIMIT";
    case VV_ERR_CANCELLED:
        return "VV_ERR_CANCELLED";
    }
    return "VV_ERR_UNKNOWN";
}

const char *
vv_error_message(void) {
    return trace;
}

void
vv_error_clear(void) {
    trace[0] = '\0';
}

/*
 * Copies @p src into @p dst (capacity @p cap, at least 5) as one printable
 * line: a control byte (below 0x20, or 0x7f) and a byte that is not part of
 * valid UTF-8 become \xNN (four characters). Messages quote what hostile files hold (names,
 * paths, keys), and a message is one line that prints only what it meant to.
 * Truncates at a character boundary. Returns the length written.
 */
static size_t
printable_copy(char *dst, size_t cap, const char *src) {
    static const char hex[] = "0123456789abcdef";
    const unsigned char *p = (const unsigned char *)src;
    size_t o = 0;
    while (*p) {
        unsigned c = p[0];
        size_t n = 0; /* bytes of a valid UTF-8 sequence starting here */
        if (c >= 0x20 && c < 0x7f)
            n = 1;
        else if (c >= 0xc2 && c <= 0xdf && (p[1] & 0xc0) == 0x80)
            n = 2;
        else if (c >= 0xe0 && c <= 0xef && (p[1] & 0xc0) == 0x80 && (p[2] & 0xc0) == 0x80 &&
                 !(c == 0xe0 && p[1] < 0xa0) && !(c == 0xed && p[1] > 0x9f))
            n = 3;
        else if (c >= 0xf0 && c <= 0xf4 && (p[1] & 0xc0) == 0x80 && (p[2] & 0xc0) == 0x80 &&
                 (p[3] & 0xc0) == 0x80 && !(c == 0xf0 && p[1] < 0x90) &&
                 !(c == 0xf4 && p[1] > 0x8f))
            n = 4;
        if (n) {
            if (o + n >= cap)
                break;
            memcpy(dst + o, p, n);
            o += n;
            p += n;
        } else {
            if (o + 4 >= cap)
                break;
            dst[o++] = '\\';
            dst[o++] = 'x';
            dst[o++] = hex[c >> 4];
            dst[o++] = hex[c & 15];
            p++;
        }
    }
    dst[o] = '\0';
    return o;
}

vv_status
vv_error_set(vv_status s, const char *fmt, ...) {
    /* format into a local buffer: the arguments may point into the trace
     * itself (vv_error_set(s, "outer: %s", vv_error_message())) */
    char buf[VV_TRACE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    printable_copy(trace, sizeof trace, buf);
    return s;
}

vv_status
vv_error_prefix(vv_status s, const char *fmt, ...) {
    char raw[VV_TRACE_MAX];
    char old[VV_TRACE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(raw, sizeof raw, fmt, ap);
    va_end(ap);
    memcpy(old, trace, sizeof old);
    size_t pos = printable_copy(trace, sizeof trace, raw);
    if (old[0] && pos + 2 < sizeof trace) {
        trace[pos++] = ':';
        trace[pos++] = ' ';
        pos += printable_copy(trace + pos, sizeof trace - pos, old);
    }
    trace[pos] = '\0';
    return s;
}

int
vv_progress_report(const vv_progress *p, double fraction) {
    if (!p || !p->fn)
        return 0;
    if (!(fraction >= 0)) /* also NaN */
        fraction = 0;
    if (fraction > 1)
        fraction = 1;
    return p->fn(p->user, fraction) != 0;
}

void
vv_threads_set(int n) {
    omp_set_num_threads(n > 0 ? n : omp_get_num_procs());
}

int
vv_threads_get(void) {
    return omp_get_max_threads();
}

const char *
vv_version(void) {
    return VV_VERSION_STRING;
}
