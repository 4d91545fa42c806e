/*
 * The Animator's final render: every frame in order, drawn by any renderer,
 * to a PNG sequence or a video (include/volvis/animate.h). The renderer uses
 * every core on frame k+1 while a second thread stores and encodes frame k.
 *
 * Resuming: PNG frames are written atomically, so a frame file that exists
 * and decodes at the right size is complete. A video keeps its frames in the
 * work folder OUTPUT.frames/ as raw 8-bit RGB files (frame_NNNNNN.rgb, exactly
 * width * height * 3 bytes, written atomically: cheap to write, unlike a PNG,
 * so keeping them costs the render almost nothing); a resumed run reads them
 * back into the encoder instead of rendering them, and the folder is removed
 * once the video is in place (a failed run keeps it only when it holds
 * frames).
 */
#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/internal.h"
#include "volvis/animate.h"
#include "volvis/video.h"

void
vv_anim_render_options_init(vv_anim_render_options *o) {
    memset(o, 0, sizeof *o);
    vv_render_options_init(&o->render);
    o->gamma = 1;
    o->resume = 1;
    vv_video_options_init(&o->video);
}

static double
now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A printf pattern with exactly one integer conversion (%d or %0Nd), no other '%'. */
static int
valid_pattern(const char *p) {
    int conv = 0;
    for (const char *s = p; *s; s++) {
        if (*s != '%')
            continue;
        s++;
        if (*s == '0')
            s++;
        while (*s >= '0' && *s <= '9')
            s++;
        if (*s != 'd')
            return 0;
        conv++;
    }
    return conv == 1;
}

static int
is_dir(const char *p) {
    struct stat st;
    return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

/* Checks that files can be created in the directory of @p file (a probe file
 * is created and removed), so an unwritable output fails before rendering. */
static vv_status
check_writable_dir(const char *file) {
    vv_atomic_file af;
    char *probe = malloc(strlen(file) + 16);
    if (!probe)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    snprintf(probe, strlen(file) + 16, "%s.probe", file);
    vv_status s = vv_atomic_file_open(&af, probe);
    free(probe);
    if (s != VV_OK)
        return s;
    vv_atomic_file_abort(&af);
    return VV_OK;
}

/* Reads a work-folder frame: exactly n bytes. 1 when complete. */
static int
read_raw(const char *path, uint8_t *buf, size_t n) {
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    size_t got = fread(buf, 1, n, f);
    int extra = fgetc(f);
    fclose(f);
    return got == n && extra == EOF;
}

static vv_status
write_raw(const char *path, const uint8_t *buf, size_t n) {
    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, path);
    if (s != VV_OK)
        return s;
    if (fwrite(buf, 1, n, af.fp) != n) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "%s: write failed", path);
    }
    return vv_atomic_file_commit(&af);
}

/* 1 when the PNG at @p path is complete: it decodes at w x h. */
static int
png_complete(const char *path, int w, int h, vv_image **img) {
    if (access(path, F_OK) != 0)
        return 0;
    vv_image *im = NULL;
    if (vv_image_read_png(&im, path) != VV_OK || im->width != w || im->height != h) {
        vv_image_free(im);
        vv_error_clear();
        return 0;
    }
    *img = im;
    return 1;
}

/* ---- the storing and encoding thread -------------------------------------- */

typedef struct job {
    int frame;
    const vv_image *img; /* PNG to write (NULL: none) */
    char png_path[4096];
    const uint8_t *rgb; /* raw frame to keep (work folder) and encode */
    char raw_path[4096];
    int write_raw;
} job;

typedef struct worker {
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int has_job, busy, quit;
    job j;
    double gamma;
    int alpha;
    size_t rgb_bytes;
    vv_video_writer *video;
    vv_status status; /* first failure */
    char message[1024];
} worker;

static void
run_job(worker *w, const job *j) {
    vv_status s = VV_OK;
    if (j->img)
        s = vv_image_write_png(j->img, j->png_path, w->gamma, w->alpha);
    if (s == VV_OK && j->write_raw)
        s = write_raw(j->raw_path, j->rgb, w->rgb_bytes);
    if (s == VV_OK && w->video && j->rgb)
        s = vv_video_writer_add(w->video, j->rgb);
    if (s != VV_OK) {
        pthread_mutex_lock(&w->mu);
        if (w->status == VV_OK) {
            w->status = s;
            snprintf(w->message, sizeof w->message, "frame %d: %s", j->frame, vv_error_message());
        }
        pthread_mutex_unlock(&w->mu);
    }
}

static void *
worker_main(void *arg) {
    worker *w = arg;
#ifdef __linux__
    /* Storing and encoding yield to the renderer's threads: the renderer is
     * the critical path, the encoder only has to keep up over the run. */
    if (setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), 4) != 0)
        (void)0; /* keeps the normal priority */
#endif
    pthread_mutex_lock(&w->mu);
    for (;;) {
        while (!w->has_job && !w->quit)
            pthread_cond_wait(&w->cv, &w->mu);
        if (!w->has_job && w->quit)
            break;
        job j = w->j;
        w->has_job = 0;
        w->busy = 1;
        pthread_mutex_unlock(&w->mu);
        run_job(w, &j);
        pthread_mutex_lock(&w->mu);
        w->busy = 0;
        pthread_cond_broadcast(&w->cv);
    }
    pthread_mutex_unlock(&w->mu);
    return NULL;
}

/* Waits until the worker has finished everything posted; its status. */
static vv_status
worker_drain(worker *w) {
    pthread_mutex_lock(&w->mu);
    while (w->has_job || w->busy)
        pthread_cond_wait(&w->cv, &w->mu);
    vv_status s = w->status;
    pthread_mutex_unlock(&w->mu);
    return s;
}

static vv_status
worker_post(worker *w, const job *j) {
    vv_status s = worker_drain(w);
    if (s != VV_OK)
        return s;
    pthread_mutex_lock(&w->mu);
    w->j = *j;
    w->has_job = 1;
    pthread_cond_broadcast(&w->cv);
    pthread_mutex_unlock(&w->mu);
    return VV_OK;
}

/* ---- progress --------------------------------------------------------------- */

typedef struct frame_progress {
    const vv_progress *user;
    int frame, n;
} frame_progress;

static int
on_render_progress(void *u, double f) {
    frame_progress *fp = u;
    return vv_progress_report(fp->user, (fp->frame + f) / fp->n);
}

/* Removes the work folder and the files in it (only names this code writes). */
static void
remove_work_dir(const char *dir, int n) {
    size_t len = strlen(dir) + 32;
    char *p = malloc(len);
    if (!p)
        return;
    for (int k = 0; k < n; k++) {
        snprintf(p, len, "%s/frame_%06d.rgb", dir, k);
        unlink(p);
    }
    free(p);
    rmdir(dir);
}

/* Kept whole: the output (a video writer and its work folder, or a PNG
 * pattern), the encoding thread and the frame loop (resume, render, post)
 * share one teardown that must run in one order (join the thread, abort a
 * partial video, keep finished frames). */
vv_status
vv_animation_render(const vv_animation *a, const vv_world *base, vv_renderer *renderer,
                    const vv_anim_render_options *opt, vv_anim_render_stats *stats) {
    double t_start = now_s();
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!a || !base || !renderer || !opt || !opt->output || !*opt->output)
        return vv_error_set(VV_ERR_INVALID,
                            "animate: missing animation, World, renderer or output");
    vv_status s;
    if ((s = vv_animation_validate(a)) != VV_OK || (s = vv_animation_check_world(a, base)) != VV_OK)
        return s;
    const char *out = opt->output;
    int width = base->view.width, height = base->view.height;
    if (width < 1 || height < 1 || width > VV_IMAGE_MAX_SIDE || height > VV_IMAGE_MAX_SIDE)
        return vv_error_set(VV_ERR_INVALID, "animate: bad image size %dx%d", width, height);
    int n = vv_animation_frame_count(a);
    vv_video_codec codec;
    int is_video = vv_video_codec_for_path(out, &codec);
    char *pattern = NULL, *work = NULL, *path = NULL;
    size_t path_len = strlen(out) + 64;
    vv_video_writer *video = NULL;
    vv_image *img = NULL, *img2 = NULL;
    uint8_t *rgb[2] = {NULL, NULL};
    worker w;
    int worker_started = 0;
    memset(&w, 0, sizeof w);
    if (!(path = malloc(path_len)))
        return vv_error_set(VV_ERR_NOMEM, "animate: out of memory");

    if (is_video) {
        if (!vv_video_codec_available(codec)) {
            free(path);
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "animate: %s: no %s encoder in this build (FFmpeg with %s needed)",
                                out, codec == VV_VIDEO_VP9 ? "VP9" : "H.264",
                                codec == VV_VIDEO_VP9 ? "libvpx-vp9" : "libx264");
        }
        vv_video_options vo = opt->video;
        vo.fps = a->fps;
        if ((s = vv_video_writer_open(&video, out, width, height, &vo)) != VV_OK) {
            free(path);
            return vv_error_prefix(s, "animate");
        }
        if (!(work = malloc(strlen(out) + 16))) {
            s = vv_error_set(VV_ERR_NOMEM, "animate: out of memory");
            goto done;
        }
        snprintf(work, strlen(out) + 16, "%s.frames", out);
        if (mkdir(work, 0777) != 0 && errno != EEXIST) {
            s = vv_error_set(VV_ERR_IO, "animate: %s: cannot create the work folder: %s", work,
                             strerror(errno));
            goto done;
        }
        if (!is_dir(work)) {
            s = vv_error_set(VV_ERR_IO, "animate: %s: exists and is not a folder", work);
            goto done;
        }
    } else {
        size_t pl = strlen(out) + 32;
        if (!(pattern = malloc(pl))) {
            s = vv_error_set(VV_ERR_NOMEM, "animate: out of memory");
            goto done;
        }
        if (is_dir(out)) {
            size_t l = strlen(out);
            snprintf(pattern, pl, "%s%sframe_%%04d.png", out, l && out[l - 1] == '/' ? "" : "/");
        } else if (valid_pattern(out) && strlen(out) > 4 &&
                   strcasecmp(out + strlen(out) - 4, ".png") == 0) {
            snprintf(pattern, pl, "%s", out);
        } else {
            s = vv_error_set(VV_ERR_INVALID,
                             "animate: %s: the output must be a video (.mp4, .webm), an existing "
                             "folder, or a PNG pattern with one %%d such as out/frame_%%04d.png",
                             out);
            goto done;
        }
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
        snprintf(path, path_len, pattern, 0);
#pragma GCC diagnostic pop
        if ((s = check_writable_dir(path)) != VV_OK) {
            s = vv_error_prefix(s, "animate");
            goto done;
        }
    }

    size_t rgb_bytes = (size_t)width * (size_t)height * 3;
    if ((s = vv_image_new(&img, width, height)) != VV_OK ||
        (s = vv_image_new(&img2, width, height)) != VV_OK)
        goto done;
    if (is_video && (!(rgb[0] = malloc(rgb_bytes)) || !(rgb[1] = malloc(rgb_bytes)))) {
        s = vv_error_set(VV_ERR_NOMEM, "animate: out of memory");
        goto done;
    }
    w.gamma = opt->gamma > 0 ? opt->gamma : 1;
    w.alpha = opt->alpha;
    w.rgb_bytes = rgb_bytes;
    w.video = video;
    pthread_mutex_init(&w.mu, NULL);
    pthread_cond_init(&w.cv, NULL);
    if (pthread_create(&w.thread, NULL, worker_main, &w) != 0) {
        pthread_mutex_destroy(&w.mu);
        pthread_cond_destroy(&w.cv);
        s = vv_error_set(VV_ERR_NOMEM, "animate: cannot start the encoding thread");
        goto done;
    }
    worker_started = 1;

    vv_image *bufs[2] = {img, img2};
    for (int k = 0; k < n; k++) {
        vv_image *cur = bufs[k & 1];
        uint8_t *crgb = rgb[k & 1];
        job j;
        memset(&j, 0, sizeof j);
        j.frame = k;
        int reused = 0;
        if (is_video) {
            snprintf(j.raw_path, sizeof j.raw_path, "%s/frame_%06d.rgb", work, k);
            /* the buffers alternate: job k - 2, which used this one, finished
             * before job k - 1 was posted (worker_post drains) */
            if (opt->resume && read_raw(j.raw_path, crgb, rgb_bytes))
                reused = 1;
        } else {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
            snprintf(j.png_path, sizeof j.png_path, pattern, k);
#pragma GCC diagnostic pop
            vv_image *old = NULL;
            if (opt->resume && png_complete(j.png_path, width, height, &old)) {
                reused = 1;
                if (opt->on_frame)
                    opt->on_frame(opt->on_frame_user, k, old, 1);
                vv_image_free(old);
            }
        }
        if (reused) {
            if (stats)
                stats->reused++;
            if (is_video) {
                j.rgb = crgb;
                if ((s = worker_post(&w, &j)) != VV_OK)
                    break;
            }
        } else {
            vv_world *snap = NULL;
            if ((s = vv_animation_eval_frame(a, base, k, &snap)) != VV_OK)
                break;
            if (opt->prepare_frame &&
                (s = opt->prepare_frame(opt->prepare_frame_user, k, snap)) != VV_OK) {
                vv_world_free(snap);
                break;
            }
            vv_render_options ro = opt->render;
            frame_progress fp = {&opt->progress, k, n};
            ro.progress.fn = on_render_progress;
            ro.progress.user = &fp;
            double t0 = now_s();
            s = opt->render_frame
                    ? opt->render_frame(opt->render_frame_user, k, snap, &snap->view, &ro, cur)
                    : vv_renderer_render(renderer, snap, &snap->view, &ro, cur);
            if (stats)
                stats->render_s += now_s() - t0;
            vv_world_free(snap);
            if (s != VV_OK)
                break;
            if (stats)
                stats->rendered++;
            if (opt->on_frame)
                opt->on_frame(opt->on_frame_user, k, cur, 0);
            if (is_video) {
                vv_image_to_8bit(cur, 3, w.gamma, crgb);
                j.rgb = crgb;
                j.write_raw = 1;
            } else {
                j.img = cur;
            }
            if ((s = worker_post(&w, &j)) != VV_OK)
                break;
        }
        if (vv_progress_report(&opt->progress, (double)(k + 1) / n)) {
            s = vv_error_set(VV_ERR_CANCELLED, "animate: cancelled after frame %d of %d", k + 1, n);
            break;
        }
    }
    {
        vv_status ws = worker_drain(&w);
        if (s == VV_OK && ws != VV_OK)
            s = vv_error_set(ws, "animate: %s", w.message);
        else if (s != VV_OK && s != VV_ERR_CANCELLED && w.status != VV_OK && w.message[0] &&
                 !strstr(vv_error_message(), "frame"))
            s = vv_error_set(w.status, "animate: %s", w.message);
    }
    if (s == VV_OK && is_video) {
        vv_video_writer *v = video;
        video = NULL;
        if ((s = vv_video_writer_finish(v)) != VV_OK)
            s = vv_error_prefix(s, "animate");
        else
            remove_work_dir(work, n);
    }
done:
    if (worker_started) {
        pthread_mutex_lock(&w.mu);
        w.quit = 1;
        pthread_cond_broadcast(&w.cv);
        pthread_mutex_unlock(&w.mu);
        pthread_join(w.thread, NULL);
        pthread_mutex_destroy(&w.mu);
        pthread_cond_destroy(&w.cv);
    }
    vv_video_writer_abort(video); /* no partial video: the temporary goes */
    /* a failed run keeps its finished frames for --resume; a work folder
     * with none (a full disk at the first frame) is not left behind */
    if (s != VV_OK && work)
        rmdir(work);
    vv_image_free(img);
    vv_image_free(img2);
    free(rgb[0]);
    free(rgb[1]);
    free(pattern);
    free(work);
    free(path);
    if (stats) {
        stats->frames = n;
        stats->total_s = now_s() - t_start;
    }
    return s;
}
