/*
 * bench_animate VOLUME [FRAMES [RUNS]]: what the Animator's final render
 * adds to rendering. An orbit of the volume (default: the CT head,
 * ../shared/data/volumes/ct_head.nrrd, 12 frames of 30 degrees in all) at
 * 512 x 512 with the ray caster, as `volvis animate --tf 100:1500 --orbit 30`
 * builds it, rendered RUNS times (default 3) two ways in alternation:
 *
 *   render_frame   every frame evaluated (vv_animation_eval_frame) and
 *                  rendered, nothing stored: seconds per frame;
 *   animate_frame  vv_animation_render to an MP4 (H.264), with the frames
 *                  kept in the work folder and encoded on the second thread,
 *                  resume off: seconds per frame, the whole call / FRAMES.
 *
 * Each figure is the median over the runs; animate_overhead is
 * animate_frame / render_frame - 1 (the goal: at most 0.05).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util.h"
#include "volvis/volvis.h"

int
main(int argc, char **argv) {
    const char *path = argc > 1 ? argv[1] : "../shared/data/volumes/ct_head.nrrd";
    int frames = argc > 2 ? atoi(argv[2]) : 12;
    int runs = argc > 3 ? atoi(argv[3]) : 3;
    if (frames < 1 || runs < 1 || runs > 100) {
        fprintf(stderr, "usage: bench_animate VOLUME [FRAMES [RUNS]]\n");
        return 2;
    }
    const char *dataset = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    vv_volume *vol;
    if (vv_volume_load(&vol, path, NULL) != VV_OK)
        bench_die("bench_animate", path);
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = 512;
    o.has_tf_range = 1;
    o.tf_lo = 100;
    o.tf_hi = 1500;
    vv_world *w;
    if (vv_world_new_for_volume(&w, vol, &o) != VV_OK)
        bench_die("bench_animate", "world");
    vv_volume_free(vol);
    vv_animation *a;
    vv_anim_sequence q;
    memset(&q, 0, sizeof q);
    q.type = VV_SEQ_ORBIT;
    q.degrees = 30;
    q.zoom = 1;
    if (vv_animation_new(&a) != VV_OK || vv_animation_add_sequence(a, &q) != VV_OK)
        bench_die("bench_animate", "animation");
    a->fps = 30;
    a->duration = frames / a->fps;
    vv_renderer *ren;
    vv_image *img;
    if (vv_renderer_new(&ren, "raycast") != VV_OK || vv_image_new(&img, 512, 512) != VV_OK)
        bench_die("bench_animate", "renderer");
    char out[256];
    snprintf(out, sizeof out, "/tmp/bench_animate_%d.mp4", (int)getpid());

    /* warm-up: the renderer's per-volume caches (gradients, min-max blocks) */
    if (vv_renderer_render(ren, w, &w->view, NULL, img) != VV_OK)
        bench_die("bench_animate", "render");
    double *t_render = malloc(sizeof *t_render * (size_t)runs);
    double *t_anim = malloc(sizeof *t_anim * (size_t)runs);
    double *t_inner = malloc(sizeof *t_inner * (size_t)runs);
    for (int r = 0; r < runs; r++) {
        double t0 = bench_now();
        for (int k = 0; k < frames; k++) {
            vv_world *s;
            if (vv_animation_eval_frame(a, w, k, &s) != VV_OK ||
                vv_renderer_render(ren, s, &s->view, NULL, img) != VV_OK)
                bench_die("bench_animate", "render");
            vv_world_free(s);
        }
        t_render[r] = (bench_now() - t0) / frames;
        vv_anim_render_options ao;
        vv_anim_render_options_init(&ao);
        ao.output = out;
        ao.resume = 0;
        vv_anim_render_stats st;
        if (vv_animation_render(a, w, ren, &ao, &st) != VV_OK)
            bench_die("bench_animate", "animate");
        t_anim[r] = st.total_s / frames;
        t_inner[r] = st.render_s / frames;
        unlink(out);
    }
    double render_frame = bench_median(t_render, runs);
    double animate_frame = bench_median(t_anim, runs);
    bench_emit("render_frame", dataset, render_frame, "s");
    bench_emit("animate_frame", dataset, animate_frame, "s");
    bench_emit("animate_render_part", dataset, bench_median(t_inner, runs), "s");
    bench_emit("animate_overhead", dataset, animate_frame / render_frame - 1, "ratio");
    free(t_render);
    free(t_anim);
    free(t_inner);
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_animation_free(a);
    vv_world_free(w);
    return 0;
}
