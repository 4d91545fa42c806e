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

vv_status
vv_error_set(vv_status s, const char *fmt, ...) {
    /* format into a local buffer: the arguments may point into the trace
     * itself (vv_error_set(s, "outer: %s", vv_error_message())) */
    char buf[VV_TRACE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    memcpy(trace, buf, sizeof trace);
    return s;
}

vv_status
vv_error_prefix(vv_status s, const char *fmt, ...) {
    char prefix[VV_TRACE_MAX];
    char old[VV_TRACE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, ap);
    va_end(ap);
    memcpy(old, trace, sizeof old);
    size_t np = strlen(prefix);
    if (np > sizeof trace - 1)
        np = sizeof trace - 1;
    memcpy(trace, prefix, np);
    size_t pos = np;
    if (old[0] && pos + 2 < sizeof trace) {
        trace[pos++] = ':';
        trace[pos++] = ' ';
        size_t no = strlen(old);
        if (no > sizeof trace - 1 - pos)
            no = sizeof trace - 1 - pos;
        memcpy(trace + pos, old, no);
        pos += no;
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
