/*
 * bench_preview: the time of each Navigator representation (vv_preview) for
 * a volume shown as `volvis-gui FILE` shows it (the default scene, 512x512),
 * rotated a little between frames as during a drag. The first frame of each
 * representation (cache building) is reported apart.
 *
 * usage: bench_preview VOLUME [--size N] [--runs N] [--renderer NAME] [--only KIND]
 * prints anchor=volvis op=preview_<kind>_ms dataset=VOLUME value=... unit=ms
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"
#include "volvis/volvis.h"

int
main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: bench_preview VOLUME [--size N] [--runs N] [--renderer NAME]\n");
        return 2;
    }
    int size = 512, runs = 15;
    const char *renderer = "raycast";
    int only = -1;
    for (int i = 2; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--size"))
            size = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--runs"))
            runs = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--renderer"))
            renderer = argv[i + 1];
        else if (!strcmp(argv[i], "--only")) {
            vv_preview_kind k;
            if (vv_preview_kind_parse(argv[i + 1], &k) != VV_OK) {
                fprintf(stderr, "bench_preview: %s\n", vv_error_message());
                return 2;
            }
            only = (int)k;
        }
    }
    if (runs < 1 || runs > 1000 || size < 16 || size > 4096) {
        fprintf(stderr, "bench_preview: bad --size or --runs\n");
        return 2;
    }
    const char *ds = strrchr(argv[1], '/') ? strrchr(argv[1], '/') + 1 : argv[1];
    vv_volume *v = NULL;
    vv_world *w = NULL;
    vv_preview *p = NULL;
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = size;
    if (vv_volume_load(&v, argv[1], NULL) != VV_OK || vv_world_new_for_volume(&w, v, &o) != VV_OK ||
        vv_preview_new(&p, renderer) != VV_OK) {
        fprintf(stderr, "bench_preview: %s\n", vv_error_message());
        return 1;
    }
    vv_volume_free(v);
    double *t = malloc(sizeof *t * (size_t)runs);
    for (int k = 0; k < VV_PREVIEW_COUNT; k++) {
        if (only >= 0 && k != only)
            continue;
        int iw, ih;
        vv_preview_size((vv_preview_kind)k, size, size, &iw, &ih);
        vv_image *img = NULL;
        vv_image_new(&img, iw, ih);
        vv_render_options ro;
        vv_render_options_init(&ro);
        ro.quality = 1;
        double t0 = bench_now();
        if (vv_preview_render(p, w, &w->view, (vv_preview_kind)k, &ro, img) != VV_OK) {
            fprintf(stderr, "bench_preview: %s\n", vv_error_message());
            return 1;
        }
        double first = bench_now() - t0;
        int n = k == VV_PREVIEW_FULL ? (runs < 5 ? runs : 5) : runs;
        for (int r = 0; r < n; r++) {
            vv_nav_view_rotate(&w->view, 4, 1);
            t0 = bench_now();
            vv_preview_render(p, w, &w->view, (vv_preview_kind)k, &ro, img);
            t[r] = bench_now() - t0;
        }
        char op[64];
        snprintf(op, sizeof op, "preview_%s_first_ms", vv_preview_kind_name((vv_preview_kind)k));
        for (char *c = op; *c; c++)
            if (*c == '/')
                *c = '_';
        bench_emit(op, ds, first * 1e3, "ms");
        snprintf(op, sizeof op, "preview_%s_ms", vv_preview_kind_name((vv_preview_kind)k));
        for (char *c = op; *c; c++)
            if (*c == '/')
                *c = '_';
        bench_emit(op, ds, bench_median(t, n) * 1e3, "ms");
        vv_image_free(img);
    }
    free(t);
    vv_preview_free(p);
    vv_world_free(w);
    return 0;
}
