/*
 * libtiff's per-file message handlers (src/io/volume/tiff_msg.c), internal to
 * src/io: what the TIFF reader (tiff.c) and writer (tiff_write.c) share.
 * They keep libtiff's first message for our trace and print nothing
 * (TIFFOpenExt and TIFFClientOpenExt, libtiff >= 4.5, nothing global
 * touched).
 *
 * Thread-safety: reentrant; each open file has its own tiff_msg.
 */
#ifndef VV_IO_TIFF_MSG_H
#define VV_IO_TIFF_MSG_H

#include <stdarg.h>

#include <tiffio.h>

/* The first message libtiff reported for one open file. */
typedef struct tiff_msg {
    char text[256];
} tiff_msg;

/* libtiff's error handler: keeps the first message in the tiff_msg @p user. */
int tiff_on_error(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap);
/* libtiff's warning handler: ignores them (unknown tags and the like). */
int tiff_on_warning(TIFF *tif, void *user, const char *module, const char *fmt, va_list ap);
/* The message kept in @p m, else @p fallback. */
const char *tiff_msg_or(const tiff_msg *m, const char *fallback);

#endif
