/*
 * Video files through FFmpeg: libavcodec encodes (libx264 for MP4,
 * libvpx-vp9 for WebM), libswscale converts RGB to yuv420p (BT.601, limited
 * range, the colour space tagged in the stream) and libavformat writes the
 * container. The stream goes through a custom AVIO into an atomic file
 * (vv_atomic_file: unnamed until complete, then renamed over the target;
 * include/volvis/video.h).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/internal.h"
#include "volvis/video.h"

void
vv_video_options_init(vv_video_options *o) {
    o->fps = 30;
    o->crf = -1;
    o->threads = 1;
}

static int
ends_with(const char *s, const char *suffix) {
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

int
vv_video_codec_for_path(const char *path, vv_video_codec *codec) {
    if (!path)
        return 0;
    if (ends_with(path, ".mp4") || ends_with(path, ".m4v") || ends_with(path, ".mov")) {
        *codec = VV_VIDEO_H264;
        return 1;
    }
    if (ends_with(path, ".webm")) {
        *codec = VV_VIDEO_VP9;
        return 1;
    }
    return 0;
}

#ifndef VV_HAVE_FFMPEG

struct vv_video_writer {
    int unused;
};

int
vv_video_codec_available(vv_video_codec codec) {
    (void)codec;
    return 0;
}

vv_status
vv_video_writer_open(vv_video_writer **out, const char *path, int width, int height,
                     const vv_video_options *opt) {
    (void)width;
    (void)height;
    (void)opt;
    *out = NULL;
    return vv_error_set(VV_ERR_UNSUPPORTED, "video: %s: this build has no FFmpeg (libavcodec)",
                        path ? path : "(null)");
}

vv_status
vv_video_writer_add(vv_video_writer *w, const uint8_t *rgb) {
    (void)w;
    (void)rgb;
    return vv_error_set(VV_ERR_UNSUPPORTED, "video: this build has no FFmpeg");
}

int
vv_video_writer_frames(const vv_video_writer *w) {
    (void)w;
    return 0;
}

vv_status
vv_video_writer_finish(vv_video_writer *w) {
    (void)w;
    return vv_error_set(VV_ERR_UNSUPPORTED, "video: this build has no FFmpeg");
}

void
vv_video_writer_abort(vv_video_writer *w) {
    (void)w;
}

#else

#include <dlfcn.h>
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
#include <pthread.h>

/* FFmpeg is opened on first use (dlopen) rather than linked: its four
 * libraries bring about 90 shared objects with them, which every run of the
 * library paid at start (0.08 s a process, 0.14 s under AddressSanitizer)
 * though few runs write video. The sonames are the majors of the headers
 * this file was compiled against, so the ABI is the one compiled for; a
 * machine without them gets VV_ERR_UNSUPPORTED naming the library. */
#define VV_SONAME_(name, major) "lib" name ".so." #major
#define VV_SONAME(name, major) VV_SONAME_(name, major)
/* X(library, function): U libavutil, C libavcodec, F libavformat, S libswscale */
#define VV_FFMPEG_FUNCTIONS                                                                        \
    X(U, av_d2q)                                                                                   \
    X(U, av_frame_alloc)                                                                           \
    X(U, av_frame_free)                                                                            \
    X(U, av_frame_get_buffer)                                                                      \
    X(U, av_frame_make_writable)                                                                   \
    X(U, av_free)                                                                                  \
    X(U, av_freep)                                                                                 \
    X(F, av_interleaved_write_frame)                                                               \
    X(U, av_log_set_level)                                                                         \
    X(U, av_malloc)                                                                                \
    X(U, av_opt_set)                                                                               \
    X(U, av_opt_set_int)                                                                           \
    X(C, av_packet_alloc)                                                                          \
    X(C, av_packet_free)                                                                           \
    X(C, av_packet_rescale_ts)                                                                     \
    X(C, av_packet_unref)                                                                          \
    X(U, av_strerror)                                                                              \
    X(F, av_write_trailer)                                                                         \
    X(C, avcodec_alloc_context3)                                                                   \
    X(C, avcodec_find_encoder_by_name)                                                             \
    X(C, avcodec_free_context)                                                                     \
    X(C, avcodec_open2)                                                                            \
    X(C, avcodec_parameters_from_context)                                                          \
    X(C, avcodec_receive_packet)                                                                   \
    X(C, avcodec_send_frame)                                                                       \
    X(F, avformat_alloc_output_context2)                                                           \
    X(F, avformat_free_context)                                                                    \
    X(F, avformat_new_stream)                                                                      \
    X(F, avformat_write_header)                                                                    \
    X(F, avio_alloc_context)                                                                       \
    X(F, avio_context_free)                                                                        \
    X(F, avio_flush)                                                                               \
    X(S, sws_freeContext)                                                                          \
    X(S, sws_getContext)                                                                           \
    X(S, sws_scale)                                                                                \
    /* end */

static struct {
#define X(lib, fn) __typeof__(&fn) fn;
    VV_FFMPEG_FUNCTIONS
#undef X
} ff;
static pthread_once_t g_ff_once = PTHREAD_ONCE_INIT;
static char g_ff_error[320]; /* empty: loaded */

static void *
ff_open(const char *soname) {
    void *h = dlopen(soname, RTLD_NOW | RTLD_LOCAL);
    if (!h && !g_ff_error[0]) {
        const char *e = dlerror();
        snprintf(g_ff_error, sizeof g_ff_error, "%s", e ? e : soname);
    }
    return h;
}

/* Opens the four libraries (kept open for the process's life) and resolves
 * every function; the library never prints, so FFmpeg's own log (codec
 * banners, statistics) is silenced: failures come back as statuses with
 * av_strerror's text. */
static void
ff_load(void) {
    void *U = ff_open(VV_SONAME("avutil", LIBAVUTIL_VERSION_MAJOR));
    void *C = ff_open(VV_SONAME("avcodec", LIBAVCODEC_VERSION_MAJOR));
    void *F = ff_open(VV_SONAME("avformat", LIBAVFORMAT_VERSION_MAJOR));
    void *S = ff_open(VV_SONAME("swscale", LIBSWSCALE_VERSION_MAJOR));
    if (g_ff_error[0])
        return;
#define X(lib, fn)                                                                                 \
    {                                                                                              \
        void *sym = dlsym(lib, #fn);                                                               \
        if (!sym) {                                                                                \
            snprintf(g_ff_error, sizeof g_ff_error, "FFmpeg has no function %s", #fn);             \
            return;                                                                                \
        }                                                                                          \
        memcpy(&ff.fn, &sym, sizeof sym);                                                          \
    }
    VV_FFMPEG_FUNCTIONS
#undef X
    ff.av_log_set_level(AV_LOG_QUIET);
}

/* VV_OK when FFmpeg is loaded; otherwise VV_ERR_UNSUPPORTED naming what is missing. */
static vv_status
ff_ready(const char *path) {
    pthread_once(&g_ff_once, ff_load);
    if (!g_ff_error[0])
        return VV_OK;
    return vv_error_set(VV_ERR_UNSUPPORTED, "video: %s: FFmpeg cannot be loaded: %s",
                        path ? path : "(null)", g_ff_error);
}

struct vv_video_writer {
    vv_atomic_file af; /* the output, written through af.fd by the AVIO below */
    const char *path;  /* af.path */
    int write_err;     /* errno of a failed write or seek, 0: none */
    int width, height; /* input size */
    int ew, eh;        /* encoded size (even) */
    AVFormatContext *oc;
    AVCodecContext *cc;
    AVStream *st;
    AVFrame *frame;
    AVPacket *pkt;
    struct SwsContext *sws;
    uint8_t *pad; /* ew * eh * 3 when the size is odd */
    int64_t next_pts;
    int header_written;
};

static const char *
encoder_name(vv_video_codec codec) {
    return codec == VV_VIDEO_VP9 ? "libvpx-vp9" : "libx264";
}

int
vv_video_codec_available(vv_video_codec codec) {
    pthread_once(&g_ff_once, ff_load);
    return !g_ff_error[0] && ff.avcodec_find_encoder_by_name(encoder_name(codec)) != NULL;
}

static vv_status
av_fail(vv_video_writer *w, const char *what, int err) {
    char buf[AV_ERROR_MAX_STRING_SIZE] = "";
    ff.av_strerror(err, buf, sizeof buf);
    return vv_error_set(VV_ERR_IO, "video: %s: %s: %s", w->path, what, buf);
}

/* FFmpeg's output goes through the atomic file's descriptor (custom AVIO),
 * so nothing but vv_atomic_file names the file. */
static int
io_write(void *opaque, uint8_t *buf, int n) {
    vv_video_writer *w = opaque;
    int left = n;
    while (left > 0) {
        ssize_t k = write(w->af.fd, buf, (size_t)left);
        if (k < 0) {
            if (errno == EINTR)
                continue;
            w->write_err = errno;
            return AVERROR(errno);
        }
        buf += k;
        left -= (int)k;
    }
    return n;
}

static int64_t
io_seek(void *opaque, int64_t offset, int whence) {
    vv_video_writer *w = opaque;
    if (whence & AVSEEK_SIZE) {
        struct stat st;
        if (fstat(w->af.fd, &st) != 0)
            return AVERROR(errno);
        return st.st_size;
    }
    off_t r = lseek(w->af.fd, (off_t)offset, whence & ~AVSEEK_FORCE);
    if (r < 0) {
        w->write_err = errno;
        return AVERROR(errno);
    }
    return r;
}

static void
io_free(vv_video_writer *w) {
    if (w->oc && w->oc->pb) {
        ff.av_freep(&w->oc->pb->buffer);
        ff.avio_context_free(&w->oc->pb);
    }
}

static void
writer_release(vv_video_writer *w, int remove_tmp) {
    if (!w)
        return;
    if (w->oc) {
        io_free(w);
        ff.avformat_free_context(w->oc);
    }
    ff.avcodec_free_context(&w->cc);
    ff.av_frame_free(&w->frame);
    ff.av_packet_free(&w->pkt);
    ff.sws_freeContext(w->sws);
    if (remove_tmp)
        vv_atomic_file_abort(&w->af);
    free(w->pad);
    free(w);
}

void
vv_video_writer_abort(vv_video_writer *w) {
    writer_release(w, 1);
}

vv_status
vv_video_writer_open(vv_video_writer **out, const char *path, int width, int height,
                     const vv_video_options *opt) {
    *out = NULL;
    vv_video_options dflt;
    if (!opt) {
        vv_video_options_init(&dflt);
        opt = &dflt;
    }
    vv_video_codec codec;
    if (!path || !vv_video_codec_for_path(path, &codec))
        return vv_error_set(VV_ERR_INVALID, "video: %s: not a video file name (.mp4 or .webm)",
                            path ? path : "(null)");
    if (width < 2 || height < 2 || width > 16384 || height > 16384)
        return vv_error_set(VV_ERR_INVALID, "video: %s: size %dx%d is outside 2..16384", path,
                            width, height);
    if (!(opt->fps > 0 && opt->fps <= 1000))
        return vv_error_set(VV_ERR_INVALID, "video: %s: frame rate %g is outside (0, 1000]", path,
                            opt->fps);
    int crf_max = codec == VV_VIDEO_VP9 ? 63 : 51;
    if (opt->crf > crf_max)
        return vv_error_set(VV_ERR_INVALID, "video: %s: crf %d is over %d for %s", path, opt->crf,
                            crf_max, encoder_name(codec));
    vv_status loaded = ff_ready(path);
    if (loaded != VV_OK)
        return loaded;
    const AVCodec *enc = ff.avcodec_find_encoder_by_name(encoder_name(codec));
    if (!enc)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "video: %s: the %s encoder is not in this FFmpeg (libavcodec)", path,
                            encoder_name(codec));

    vv_video_writer *w = calloc(1, sizeof *w);
    if (!w)
        return vv_error_set(VV_ERR_NOMEM, "video: out of memory");
    /* the temporary file gets the usual permissions (umask), as every output */
    vv_status s0 = vv_atomic_file_open(&w->af, path);
    if (s0 != VV_OK) {
        free(w);
        return vv_error_prefix(s0, "video");
    }
    w->path = w->af.path;
    w->width = width;
    w->height = height;
    w->ew = (width + 1) & ~1;
    w->eh = (height + 1) & ~1;

    vv_status s = VV_OK;
    int err;
    const char *fmt = codec == VV_VIDEO_VP9 ? "webm" : "mp4";
    if ((err = ff.avformat_alloc_output_context2(&w->oc, NULL, fmt, w->path)) < 0 || !w->oc) {
        s = av_fail(w, "cannot create the container", err);
        goto fail;
    }
    w->cc = ff.avcodec_alloc_context3(enc);
    w->frame = ff.av_frame_alloc();
    w->pkt = ff.av_packet_alloc();
    if (!w->cc || !w->frame || !w->pkt) {
        s = vv_error_set(VV_ERR_NOMEM, "video: out of memory");
        goto fail;
    }
    AVRational rate = ff.av_d2q(opt->fps, 100000);
    w->cc->width = w->ew;
    w->cc->height = w->eh;
    w->cc->pix_fmt = AV_PIX_FMT_YUV420P;
    w->cc->time_base = av_inv_q(rate);
    w->cc->framerate = rate;
    w->cc->thread_count = opt->threads > 0 ? opt->threads : 1;
    w->cc->color_range = AVCOL_RANGE_MPEG;
    w->cc->colorspace = AVCOL_SPC_SMPTE170M;
    w->cc->color_primaries = AVCOL_PRI_SMPTE170M;
    w->cc->color_trc = AVCOL_TRC_SMPTE170M;
    int crf = opt->crf >= 0 ? opt->crf : (codec == VV_VIDEO_VP9 ? 31 : 20);
    if (codec == VV_VIDEO_H264) {
        ff.av_opt_set(w->cc->priv_data, "preset", "superfast", 0);
        ff.av_opt_set_int(w->cc->priv_data, "crf", crf, 0);
    } else {
        w->cc->bit_rate = 0; /* constant quality */
        ff.av_opt_set_int(w->cc->priv_data, "crf", crf, 0);
        ff.av_opt_set(w->cc->priv_data, "deadline", "good", 0);
        ff.av_opt_set_int(w->cc->priv_data, "cpu-used", 4, 0);
        ff.av_opt_set_int(w->cc->priv_data, "row-mt", 1, 0);
    }
    if (w->oc->oformat->flags & AVFMT_GLOBALHEADER)
        w->cc->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    if ((err = ff.avcodec_open2(w->cc, enc, NULL)) < 0) {
        s = av_fail(w, "cannot open the encoder", err);
        if (s == VV_ERR_IO)
            s = VV_ERR_UNSUPPORTED;
        goto fail;
    }
    w->st = ff.avformat_new_stream(w->oc, NULL);
    if (!w->st) {
        s = vv_error_set(VV_ERR_NOMEM, "video: out of memory");
        goto fail;
    }
    w->st->time_base = w->cc->time_base;
    w->st->avg_frame_rate = rate;
    w->st->r_frame_rate = rate;
    if ((err = ff.avcodec_parameters_from_context(w->st->codecpar, w->cc)) < 0) {
        s = av_fail(w, "cannot set the stream parameters", err);
        goto fail;
    }
    {
        unsigned char *buf = ff.av_malloc(1 << 16);
        w->oc->pb = buf ? ff.avio_alloc_context(buf, 1 << 16, 1, w, NULL, io_write, io_seek) : NULL;
        if (!w->oc->pb) {
            ff.av_free(buf);
            s = vv_error_set(VV_ERR_NOMEM, "video: out of memory");
            goto fail;
        }
        w->oc->flags |= AVFMT_FLAG_CUSTOM_IO;
    }
    if ((err = ff.avformat_write_header(w->oc, NULL)) < 0) {
        s = av_fail(w, "cannot write the header", err);
        goto fail;
    }
    w->header_written = 1;
    w->frame->format = AV_PIX_FMT_YUV420P;
    w->frame->width = w->ew;
    w->frame->height = w->eh;
    if ((err = ff.av_frame_get_buffer(w->frame, 0)) < 0) {
        s = av_fail(w, "cannot allocate a frame", err);
        goto fail;
    }
    w->sws =
        ff.sws_getContext(w->ew, w->eh, AV_PIX_FMT_RGB24, w->ew, w->eh, AV_PIX_FMT_YUV420P,
                          SWS_BICUBIC | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INP, NULL, NULL, NULL);
    if (!w->sws) {
        s = vv_error_set(VV_ERR_NOMEM, "video: %s: cannot create the colour converter", path);
        goto fail;
    }
    if (w->ew != width || w->eh != height) {
        w->pad = malloc((size_t)w->ew * (size_t)w->eh * 3);
        if (!w->pad) {
            s = vv_error_set(VV_ERR_NOMEM, "video: out of memory");
            goto fail;
        }
    }
    *out = w;
    return VV_OK;
fail:
    writer_release(w, 1);
    return s;
}

/* Sends @p frame (NULL: flush) and writes every packet the encoder has ready. */
static vv_status
encode(vv_video_writer *w, AVFrame *frame) {
    int err = ff.avcodec_send_frame(w->cc, frame);
    if (err < 0)
        return av_fail(w, "encoder refused a frame", err);
    for (;;) {
        err = ff.avcodec_receive_packet(w->cc, w->pkt);
        if (err == AVERROR(EAGAIN) || err == AVERROR_EOF)
            return VV_OK;
        if (err < 0)
            return av_fail(w, "encoding failed", err);
        /* every frame lasts 1 / fps: without a duration MP4 loses the last frame */
        w->pkt->duration = 1;
        ff.av_packet_rescale_ts(w->pkt, w->cc->time_base, w->st->time_base);
        w->pkt->stream_index = w->st->index;
        err = ff.av_interleaved_write_frame(w->oc, w->pkt);
        ff.av_packet_unref(w->pkt);
        if (err < 0)
            return av_fail(w, "cannot write a packet", err);
    }
}

vv_status
vv_video_writer_add(vv_video_writer *w, const uint8_t *rgb) {
    if (!w || !rgb)
        return vv_error_set(VV_ERR_INVALID, "video: no writer or no pixels");
    const uint8_t *src = rgb;
    if (w->pad) {
        size_t ins = (size_t)w->width * 3, outs = (size_t)w->ew * 3;
        for (int y = 0; y < w->eh; y++) {
            int sy = y < w->height ? y : w->height - 1;
            uint8_t *d = w->pad + (size_t)y * outs;
            memcpy(d, rgb + (size_t)sy * ins, ins);
            if (w->ew > w->width)
                memcpy(d + ins, d + ins - 3, 3);
        }
        src = w->pad;
    }
    int err = ff.av_frame_make_writable(w->frame);
    if (err < 0)
        return av_fail(w, "frame not writable", err);
    const uint8_t *planes[1] = {src};
    int strides[1] = {w->ew * 3};
    ff.sws_scale(w->sws, planes, strides, 0, w->eh, w->frame->data, w->frame->linesize);
    w->frame->pts = w->next_pts++;
    return encode(w, w->frame);
}

int
vv_video_writer_frames(const vv_video_writer *w) {
    return w ? (int)w->next_pts : 0;
}

vv_status
vv_video_writer_finish(vv_video_writer *w) {
    if (!w)
        return vv_error_set(VV_ERR_INVALID, "video: no writer");
    vv_status s;
    if (w->next_pts == 0) {
        s = vv_error_set(VV_ERR_INVALID, "video: %s: no frames", w->path);
        writer_release(w, 1);
        return s;
    }
    if ((s = encode(w, NULL)) != VV_OK) {
        writer_release(w, 1);
        return s;
    }
    int err = ff.av_write_trailer(w->oc);
    if (err < 0) {
        s = av_fail(w, "cannot write the trailer", err);
        writer_release(w, 1);
        return s;
    }
    ff.avio_flush(w->oc->pb);
    if (w->write_err || w->oc->pb->error < 0) {
        s = vv_error_set(VV_ERR_IO, "video: %s: write failed: %s", w->path,
                         strerror(w->write_err ? w->write_err : EIO));
        writer_release(w, 1);
        return s;
    }
    io_free(w);
    s = vv_atomic_file_commit(&w->af);
    if (s != VV_OK)
        s = vv_error_prefix(s, "video");
    writer_release(w, 0);
    return s;
}

#endif
