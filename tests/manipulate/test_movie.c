/*
 * The Animator's final render: PNG sequences written atomically and resumed
 * after a cancel with the same files; videos (MP4/H.264, WebM/VP9) with the
 * requested frame count and rate (ffprobe -count_frames); failures before the
 * first frame for an unwritable output; no partial video after a cancel, and
 * the kept frames resumed.
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testutil.h"

#define SIZE 48

static vv_world *
small_world(void) {
    vv_volume *v;
    vt_ok(vv_volume_load(&v, vt_data("volumes/neghip.slc"), NULL));
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = SIZE;
    vv_world *w;
    vt_ok(vv_world_new_for_volume(&w, v, &o));
    vv_volume_free(v);
    return w;
}

static vv_animation *
orbit(int frames, double fps) {
    vv_animation *a;
    vt_ok(vv_animation_new(&a));
    a->fps = fps;
    a->duration = frames / fps;
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.type = VV_SEQ_ORBIT;
    q.degrees = 120;
    q.zoom = 1;
    vt_ok(vv_animation_add_sequence(a, &q));
    return a;
}

typedef struct counter {
    int frames, rendered;
    int cancel_at; /* cancel once this many frames are done; 0 never */
} counter;

static void
on_frame(void *user, int frame, const vv_image *img, int reused) {
    counter *c = user;
    (void)frame;
    assert_int_equal(img->width, SIZE);
    c->frames++;
    c->rendered += !reused;
}

static int
on_progress(void *user, double f) {
    counter *c = user;
    assert_true(f >= 0 && f <= 1);
    return c->cancel_at > 0 && c->frames >= c->cancel_at;
}

static vv_status
render(const vv_animation *a, const vv_world *w, const char *out, counter *c,
       vv_anim_render_stats *st) {
    vv_renderer *ren;
    vt_ok(vv_renderer_new(&ren, "raycast"));
    vv_anim_render_options o;
    vv_anim_render_options_init(&o);
    o.output = out;
    o.on_frame = on_frame;
    o.on_frame_user = c;
    o.progress.fn = on_progress;
    o.progress.user = c;
    vv_error_clear();
    vv_status s = vv_animation_render(a, w, ren, &o, st);
    vv_renderer_free(ren);
    return s;
}

static const char *
fresh_dir(const char *name) {
    static char buf[4][1024];
    static int k;
    char *d = buf[k++ & 3];
    snprintf(d, 1024, "%s", vt_path(vt_outdir("manipulate"), name));
    DIR *dir = opendir(d);
    if (dir) {
        struct dirent *e;
        while ((e = readdir(dir)))
            if (e->d_name[0] != '.')
                unlink(vt_path(d, e->d_name));
        closedir(dir);
    }
    mkdir(d, 0777);
    return d;
}

static int
count_files(const char *dir) {
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

static void
test_png_sequence_cancel_resume(void **state) {
    (void)state;
    vv_world *w = small_world();
    vv_animation *a = orbit(6, 10);
    const char *full = fresh_dir("seq_full"), *part = fresh_dir("seq_part");
    counter c = {0, 0, 0};
    vv_anim_render_stats st;
    vt_ok(render(a, w, full, &c, &st)); /* an existing folder: frame_%04d.png in it */
    assert_int_equal(st.frames, 6);
    assert_int_equal(st.rendered, 6);
    assert_int_equal(count_files(full), 6);
    /* cancel after 2 frames */
    counter c2 = {0, 0, 2};
    char pattern[1100];
    snprintf(pattern, sizeof pattern, "%s/f_%%03d.png", part);
    assert_int_equal(render(a, w, pattern, &c2, &st), VV_ERR_CANCELLED);
    assert_int_equal(count_files(part), 2);
    /* a stale, truncated frame 2 (as if a crash had left one) is redone */
    vt_write_file(vt_path(part, "f_002.png"), "\x89PNG", 4);
    counter c3 = {0, 0, 0};
    vt_ok(render(a, w, pattern, &c3, &st));
    assert_int_equal(st.reused, 2);
    assert_int_equal(st.rendered, 4);
    assert_int_equal(c3.frames, 6);
    assert_int_equal(c3.rendered, 4);
    for (int k = 0; k < 6; k++) {
        char n1[64], n2[64];
        snprintf(n1, sizeof n1, "frame_%04d.png", k);
        snprintf(n2, sizeof n2, "f_%03d.png", k);
        size_t s1, s2;
        unsigned char *b1 = vt_read_file(vt_path(full, n1), &s1);
        unsigned char *b2 = vt_read_file(vt_path(part, n2), &s2);
        assert_int_equal(s1, s2);
        assert_memory_equal(b1, b2, s1);
        free(b1);
        free(b2);
    }
    /* frame 0 is the still of the World, frame k the World orbited by 120 k / 6 */
    vv_world *s;
    vt_ok(vv_animation_eval_frame(a, w, 0, &s));
    assert_memory_equal(&s->view, &w->view, sizeof w->view);
    vv_world_free(s);
    vv_animation_free(a);
    vv_world_free(w);
}

static void
test_bad_outputs(void **state) {
    (void)state;
    vv_world *w = small_world();
    vv_animation *a = orbit(3, 10);
    counter c = {0, 0, 0};
    vv_anim_render_stats st;
    const char *bad[] = {"/nonexistent-dir/x/frame_%04d.png", "/nonexistent-dir/x/movie.mp4",
                         "/nonexistent-dir/x/movie.webm", "frames_without_pattern.png",
                         "two_%d_%d.png"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        vt_err(render(a, w, bad[i], &c, &st));
        assert_int_equal(c.frames, 0); /* failed before the first frame */
    }
    /* a missing object fails before the first frame too */
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.type = VV_SEQ_ROTATE_OBJECT;
    snprintf(q.object, sizeof q.object, "nobody");
    q.axis = vv_vec3_make(0, 0, 1);
    vt_ok(vv_animation_add_sequence(a, &q));
    vt_err(render(a, w, fresh_dir("bad_target"), &c, &st));
    assert_non_null(strstr(vv_error_message(), "nobody"));
    assert_int_equal(c.frames, 0);
    vv_animation_free(a);
    vv_world_free(w);
}

static int
have_ffprobe(void) {
    return system("command -v ffprobe >/dev/null 2>&1") == 0;
}

/* ffprobe's frame count and frame rate of the first video stream. */
static void
probe(const char *path, int *frames, double *fps) {
    char cmd[2048];
    snprintf(cmd, sizeof cmd,
             "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
             "stream=nb_read_frames,avg_frame_rate -of default=nw=1 '%s'",
             path);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char line[256];
    *frames = -1;
    *fps = -1;
    while (fgets(line, sizeof line, p)) {
        int a, b;
        if (sscanf(line, "nb_read_frames=%d", &a) == 1)
            *frames = a;
        if (sscanf(line, "avg_frame_rate=%d/%d", &a, &b) == 2 && b > 0)
            *fps = (double)a / b;
    }
    assert_int_equal(pclose(p), 0);
}

static void
test_video_frames_and_rate(void **state) {
    (void)state;
    vv_world *w = small_world();
    const char *dir = fresh_dir("video");
    const char *names[2] = {"orbit.mp4", "orbit.webm"};
    const double rates[2] = {25, 12};
    for (int i = 0; i < 2; i++) {
        vv_video_codec codec;
        assert_true(vv_video_codec_for_path(names[i], &codec));
        if (!vv_video_codec_available(codec)) {
            print_message("skipped %s: this build has no %s encoder\n", names[i],
                          i ? "VP9" : "H.264");
            continue;
        }
        vv_animation *a = orbit(7, rates[i]);
        counter c = {0, 0, 0};
        vv_anim_render_stats st;
        const char *out = vt_path(dir, names[i]);
        vt_ok(render(a, w, out, &c, &st));
        assert_int_equal(c.frames, 7);
        char work[1100];
        snprintf(work, sizeof work, "%s.frames", out);
        assert_int_equal(access(work, F_OK), -1);  /* the work folder is gone */
        assert_int_equal(count_files(dir), i + 1); /* no temporary left */
        if (!have_ffprobe()) {
            print_message("skipped the ffprobe check: ffprobe not found (install ffmpeg)\n");
        } else {
            int n;
            double fps;
            probe(out, &n, &fps);
            assert_int_equal(n, 7);
            assert_near(fps, rates[i], 1e-9);
        }
        vv_animation_free(a);
    }
    vv_world_free(w);
}

static void
test_video_cancel_resume(void **state) {
    (void)state;
    if (!vv_video_codec_available(VV_VIDEO_H264)) {
        print_message("skipped: no H.264 encoder in this build\n");
        return;
    }
    vv_world *w = small_world();
    vv_animation *a = orbit(6, 30);
    const char *dir = fresh_dir("video_resume");
    const char *out = vt_path(dir, "movie.mp4");
    char work[1100];
    snprintf(work, sizeof work, "%s.frames", out);
    counter c = {0, 0, 3};
    vv_anim_render_stats st;
    assert_int_equal(render(a, w, out, &c, &st), VV_ERR_CANCELLED);
    assert_int_equal(access(out, F_OK), -1); /* no partial video */
    assert_int_equal(count_files(work), 3);  /* the finished frames are kept */
    assert_int_equal(count_files(dir), 1);   /* only the work folder, no temporary */
    counter c2 = {0, 0, 0};
    vt_ok(render(a, w, out, &c2, &st));
    assert_int_equal(st.reused, 3);
    assert_int_equal(st.rendered, 3);
    assert_int_equal(access(work, F_OK), -1);
    /* the same file as an uninterrupted run */
    const char *out2 = vt_path(dir, "movie2.mp4");
    counter c3 = {0, 0, 0};
    vt_ok(render(a, w, out2, &c3, &st));
    size_t s1, s2;
    unsigned char *b1 = vt_read_file(out, &s1), *b2 = vt_read_file(out2, &s2);
    assert_int_equal(s1, s2);
    assert_memory_equal(b1, b2, s1);
    free(b1);
    free(b2);
    if (have_ffprobe()) {
        int n;
        double fps;
        probe(out, &n, &fps);
        assert_int_equal(n, 6);
    }
    vv_animation_free(a);
    vv_world_free(w);
}

static void
test_video_writer_direct(void **state) {
    (void)state;
    vv_video_writer *vw = NULL;
    vt_err(vv_video_writer_open(&vw, "x.avi", 16, 16, NULL));
    vt_err(vv_video_writer_open(&vw, "x.mp4", 1, 16, NULL));
    assert_null(vw);
    if (!vv_video_codec_available(VV_VIDEO_H264))
        return;
    const char *dir = fresh_dir("writer");
    const char *out = vt_path(dir, "odd.mp4");
    vt_ok(vv_video_writer_open(&vw, out, 33, 17, NULL)); /* odd sizes are padded */
    uint8_t rgb[33 * 17 * 3];
    memset(rgb, 128, sizeof rgb);
    vt_ok(vv_video_writer_add(vw, rgb));
    assert_int_equal(vv_video_writer_frames(vw), 1);
    vt_ok(vv_video_writer_finish(vw));
    assert_int_equal(count_files(dir), 1);
    vt_ok(vv_video_writer_open(&vw, vt_path(dir, "aborted.mp4"), 32, 32, NULL));
    vv_video_writer_abort(vw);
    assert_int_equal(count_files(dir), 1);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_png_sequence_cancel_resume),
        cmocka_unit_test(test_bad_outputs),
        cmocka_unit_test(test_video_frames_and_rate),
        cmocka_unit_test(test_video_cancel_resume),
        cmocka_unit_test(test_video_writer_direct),
    };
    return vt_run_tests(tests, NULL, NULL);
}
