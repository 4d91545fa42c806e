/*
 * Streaming output for the volume writers (not installed): bytes go to a
 * FILE as they are, as a zlib stream (MetaImage CompressedData, VTK XML
 * appended blocks) or as a gzip member (.nii.gz), in one pass through a
 * bounded buffer (at most 32 MiB of input and its output, compressed on
 * every core in 1 MiB blocks, pigz's scheme: zout.c), so a writer never
 * holds a second copy of the voxels. The bytes written depend on the input
 * only, never on the thread count.
 *
 * Thread-safety: one vv_zout per thread; the functions are reentrant.
 */
#ifndef VOLVIS_IO_ZOUT_H
#define VOLVIS_IO_ZOUT_H

#include <stdint.h>
#include <stdio.h>

#include "volvis/core.h"

/** How vv_zout_begin encodes. */
typedef enum vv_zout_mode {
    VV_ZOUT_PLAIN = 0, /**< the bytes as they are */
    VV_ZOUT_ZLIB = 1,  /**< RFC 1950 (zlib header and Adler-32) */
    VV_ZOUT_GZIP = 2   /**< RFC 1952 (one gzip member) */
} vv_zout_mode;

/** zlib level of the writers: 1, nibabel's default for .nii.gz (fast; the
 *  files are some 10 % larger than at level 6). */
#define VV_ZOUT_LEVEL 1

typedef struct vv_zout vv_zout;

/** Starts a stream into @p fp (which stays the caller's). Errors: VV_ERR_NOMEM. */
vv_status vv_zout_begin(vv_zout **out, FILE *fp, vv_zout_mode mode);
/** Appends @p n bytes. Errors: VV_ERR_IO (with strerror), VV_ERR_NOMEM. */
vv_status vv_zout_write(vv_zout *z, const void *data, uint64_t n);
/**
 * Finishes the stream (flushes the compressor) and frees @p z; *@p written
 * (may be NULL) gets the number of bytes written to the file. With @p z in
 * error, only frees. Errors: as vv_zout_write.
 */
vv_status vv_zout_end(vv_zout *z, uint64_t *written);
/** Frees @p z without finishing (after an error). NULL is ignored. */
void vv_zout_abort(vv_zout *z);

#endif
