/* A program outside the project: loads a volume and renders it through the
 * installed library (find_package(VolVis) and pkg-config both build it). */
#include <stdio.h>
#include <volvis/volvis.h>

int
main(int argc, char **argv) {
    vv_volume *v;
    if (argc < 2 || vv_volume_load(&v, argv[1], NULL) != VV_OK) {
        fprintf(stderr, "consumer: %s\n", vv_error_message());
        return 1;
    }
    vv_default_scene_options o;
    vv_default_scene_options_init(&o);
    o.width = o.height = 64;
    vv_world *w;
    vv_renderer *r;
    vv_image *img;
    if (vv_world_new_for_volume(&w, v, &o) != VV_OK || vv_renderer_new(&r, "raycast") != VV_OK ||
        vv_image_new(&img, 64, 64) != VV_OK) {
        fprintf(stderr, "consumer: %s\n", vv_error_message());
        return 1;
    }
    vv_status s = vv_renderer_render(r, w, &w->view, NULL, img);
    printf("volvis %s: %d x %d x %d, render %s\n", vv_version(), v->dims[0], v->dims[1], v->dims[2],
           vv_status_name(s));
    vv_image_free(img);
    vv_renderer_free(r);
    vv_world_free(w);
    vv_volume_free(v);
    return s != VV_OK;
}
