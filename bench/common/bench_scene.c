/*
 * Shared set-up of the benchmark programs (see bench_scene.h).
 */
#include "bench_scene.h"

#include "util.h"

#include <stdlib.h>
#include <string.h>

vv_status
vvb_volume_world(vv_world **out, vv_object **out_obj, vv_volume *vol, const char *name) {
    *out = NULL;
    vv_world *w = NULL;
    vv_object *obj = NULL;
    vv_status s = vv_world_new(&w);
    if (s == VV_OK)
        s = vv_object_new_volume(&obj, vol, name);
    if (s == VV_OK)
        s = vv_world_add_object(w, obj); /* owns obj from here, also on failure */
    vv_light head;
    memset(&head, 0, sizeof head);
    head.type = VV_LIGHT_DIRECTIONAL;
    head.headlight = 1;
    head.color = vv_vec3_make(1, 1, 1);
    head.intensity = 1;
    if (s == VV_OK)
        s = vv_world_add_light(w, &head);
    if (s != VV_OK) {
        vv_world_free(w);
        return s;
    }
    *out = w;
    if (out_obj)
        *out_obj = obj;
    return VV_OK;
}

void
vvb_center(vv_volume *vol) {
    for (int a = 0; a < 3; a++)
        vol->origin[a] = -(vol->dims[a] - 1) * vol->spacing[a] / 2.0;
    for (int a = 0; a < 9; a++)
        vol->direction[a] = a % 4 == 0;
    vol->modified++;
}

void
vvb_peer_view(vv_world *w, vv_object *obj, int width, int height) {
    const vv_volume *vol = obj->volume;
    double ext = 0;
    for (int a = 0; a < 3; a++) {
        double e = (vol->dims[a] - 1) * vol->spacing[a];
        ext = e > ext ? e : ext;
    }
    vv_vec3 dir = vv_vec3_normalize(vv_vec3_make(1, -1.6, 1));
    w->view.eye = vv_vec3_scale(dir, ext / 2 * 11);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.up = vv_vec3_make(0, 0, 1);
    w->view.fov = vv_deg_to_rad(20);
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    w->view.width = width;
    w->view.height = height;
    w->background = vv_vec3_make(0, 0, 0);
    w->ambient = vv_vec3_make(1, 1, 1);
    obj->step = 0.5;
    obj->material.ambient = 0.1;
    obj->material.diffuse = 0.6;
    obj->material.specular = 0.3;
    obj->material.shininess = 30;
    obj->material.color = vv_vec3_make(1, 1, 1);
}

vv_status
vvb_surface_world(vv_world **out, vv_object **out_obj, vv_volume *vol, double iso, int size) {
    vvb_center(vol); /* the peers' placement */
    vv_world *w = NULL;
    vv_object *obj = NULL;
    vv_status s = vvb_volume_world(&w, &obj, vol, "bench");
    if (s != VV_OK)
        return s;
    vvb_peer_view(w, obj, size, size);
    obj->mode = VV_MODE_ISO;
    obj->isovalue = iso;
    obj->shading = 1;
    *out = w;
    if (out_obj)
        *out_obj = obj;
    return VV_OK;
}

vv_status
vvb_median_frame(double *wall, double *cpu, vv_renderer *r, const vv_world *w,
                 const vv_render_options *opt, vv_image *img, int runs) {
    double *t = malloc(2 * (size_t)runs * sizeof *t);
    if (!t)
        return vv_error_set(VV_ERR_NOMEM, "bench: out of memory");
    for (int i = 0; i < runs; i++) {
        double t0 = bench_now(), c0 = bench_cpu_now();
        vv_status s = vv_renderer_render(r, w, &w->view, opt, img);
        if (s != VV_OK) {
            free(t);
            return s;
        }
        t[i] = bench_now() - t0;
        t[runs + i] = bench_cpu_now() - c0;
    }
    *wall = bench_median(t, runs);
    if (cpu)
        *cpu = bench_median(t + runs, runs);
    free(t);
    return VV_OK;
}
