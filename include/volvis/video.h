/*
 * VolVis video output: MP4 (H.264 through libx264) and WebM (VP9 through
 * libvpx-vp9), written with FFmpeg's libavformat, libavcodec and libswscale.
 * The file is written atomically: frames go to a temporary file beside the
 * target, renamed over it by vv_video_writer_finish only when the whole
 * stream is written; vv_video_writer_abort leaves nothing behind. Every
 * packet carries its duration (1 / fps), so players show the last frame for
 * its full time.
 *
 * A build without FFmpeg (the libraries missing at configure time) has these
 * functions too; they fail with VV_ERR_UNSUPPORTED.
 *
 * The first vv_video_writer_open sets FFmpeg's process-wide log level to
 * quiet (the library never prints; errors come back in the trace).
 *
 * Thread-safety: one writer must be used by one thread at a time; distinct
 * writers are independent.
 */
#ifndef VOLVIS_VIDEO_H
#define VOLVIS_VIDEO_H

#include <stdint.h>

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum vv_video_codec {
    VV_VIDEO_H264 = 0, /**< MP4 container, H.264 (libx264), yuv420p */
    VV_VIDEO_VP9 = 1   /**< WebM container, VP9 (libvpx-vp9), yuv420p */
} vv_video_codec;

/** Encoder settings. */
typedef struct vv_video_options {
    double fps;  /**< frames per second, > 0 (default 30) */
    int crf;     /**< constant rate factor, lower is better: -1 default (H.264 20, VP9 31);
                      H.264 0..51, VP9 0..63 */
    int threads; /**< encoder threads (default 1: the renderer keeps the other cores) */
} vv_video_options;

/** fps 30, crf -1 (the codec's default), 1 thread. */
void vv_video_options_init(vv_video_options *o);

/**
 * The codec for a file name: ".mp4" (also ".m4v", ".mov") H.264, ".webm" VP9,
 * ignoring case. Returns 1 and sets *codec, 0 when the name is not a video.
 */
int vv_video_codec_for_path(const char *path, vv_video_codec *codec);

/** 1 when this build can encode @p codec (FFmpeg present and the encoder found). */
int vv_video_codec_available(vv_video_codec codec);

typedef struct vv_video_writer vv_video_writer;

/**
 * Opens a video of @p width x @p height pixels (made even for yuv420p by
 * repeating the last column or row) at @p path, codec from its extension.
 * Checks the encoder and opens the temporary file before returning, so a
 * missing codec or an unwritable directory fails here. @p opt may be NULL.
 * Errors: VV_ERR_INVALID (not a video name, bad size or options),
 * VV_ERR_UNSUPPORTED (no encoder), VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_video_writer_open(vv_video_writer **out, const char *path, int width, int height,
                               const vv_video_options *opt);

/**
 * Encodes one frame: @p rgb is width * height * 3 bytes, 8-bit RGB, rows top
 * to bottom (vv_image_to_8bit). Errors: VV_ERR_IO (encoder or write failure).
 */
vv_status vv_video_writer_add(vv_video_writer *w, const uint8_t *rgb);

/** Frames added so far. */
int vv_video_writer_frames(const vv_video_writer *w);

/**
 * Flushes the encoder, writes the trailer, renames the temporary file over
 * the target and frees the writer (also on failure, when the temporary is
 * removed). Errors: VV_ERR_IO, VV_ERR_INVALID (no frames).
 */
vv_status vv_video_writer_finish(vv_video_writer *w);

/** Removes the temporary file and frees the writer. Accepts NULL. */
void vv_video_writer_abort(vv_video_writer *w);

#ifdef __cplusplus
}
#endif
#endif
