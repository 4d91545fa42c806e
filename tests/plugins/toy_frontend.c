/*
 * A toy front end: the door's contract (include/volvis/scene.h). Whatever a
 * user names -- a NIfTI file, a DICOM folder, an OME-Zarr store, a scene,
 * a BigDataViewer XML -- becomes a World through vv_world_open alone, and
 * the World's own renderer, options and quality draw it, as `volvis
 * render INPUT --size WxH --threads 1` does (door_frontends.py compares).
 *   toy_frontend INPUT W H OUT.png
 */
#include <stdio.h>
#include <stdlib.h>

#include "volvis/volvis.h"

int
main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: toy_frontend INPUT W H OUT.png\n");
        return 2;
    }
    vv_world_open_options o;
    vv_world_open_options_init(&o);
    o.has_size = 1;
    o.view.width = atoi(argv[2]);
    o.view.height = atoi(argv[3]);
    vv_world *w = NULL;
    vv_renderer *ren = NULL;
    vv_image *img = NULL;
    vv_threads_set(1);
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = 1;
    vv_status s = vv_world_open(&w, argv[1], &o, NULL);
    if (s == VV_OK && (s = vv_renderer_new_for_world(&ren, w)) == VV_OK)
        s = vv_image_new(&img, w->view.width, w->view.height);
    if (s == VV_OK) {
        ro.quality = vv_render_settings_quality(&w->render);
        s = vv_renderer_render(ren, w, &w->view, &ro, img);
    }
    if (s == VV_OK)
        s = vv_image_write_png(img, argv[4], 1.0, 0);
    if (s != VV_OK)
        fprintf(stderr, "toy_frontend: %s\n", vv_error_message());
    vv_image_free(img);
    vv_renderer_free(ren);
    vv_world_free(w);
    return s == VV_OK ? 0 : 1;
}
