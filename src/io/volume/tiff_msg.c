/*
 * libtiff's per-file message handlers (tiff_msg.h): the first message of
 * an open file kept for our trace, nothing printed, nothing global touched.
 * Shared by the TIFF reader (tiff.c) and writer (tiff_write.c).
 *
 * Thread-safety: reentrant; each open file has its own tiff_msg.
 */
#include <stdarg.h>
#include <stdio.h>

#include <tiffio.h>

#include "io/volume/tiff_msg.h"

int
tiff_on_error(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap) {
    (void)tif;
    (void)module;
    tiff_msg *m = user;
    if (m && !m->text[0])
        vsnprintf(m->text, sizeof m->text, fmt, ap);
    return 1; /* handled: libtiff prints nothing */
}

int
tiff_on_warning(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap) {
    (void)tif;
    (void)user;
    (void)module;
    (void)fmt;
    (void)ap;
    return 1; /* unknown tags and the like: not our business */
}

const char *
tiff_msg_or(const tiff_msg *m, const char *fallback) {
    return m->text[0] ? m->text : fallback;
}
