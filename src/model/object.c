/*
 * Volume objects of the World: data, transform, material, segmentation,
 * local shading and cut planes (the paper's "object", section 3).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model/model_internal.h"
#include "volvis/model.h"

double
vv_model_min_spacing(const vv_volume *v) {
    double s = v->spacing[0];
    if (v->spacing[1] < s)
        s = v->spacing[1];
    if (v->spacing[2] < s)
        s = v->spacing[2];
    if (!(s > 0.0) || !isfinite(s))
        s = 1.0;
    return s;
}

void
vv_model_copy_name(char dst[VV_NAME_MAX], const char *src) {
    if (!src)
        src = "";
    size_t n = strlen(src);
    if (n >= VV_NAME_MAX)
        n = VV_NAME_MAX - 1;
    memcpy(dst, src, n);
    dst[n] = '\0';
}

vv_status
vv_object_new_volume(vv_object **out, vv_volume *volume, const char *name) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "object: NULL output");
    *out = NULL;
    if (!volume)
        return vv_error_set(VV_ERR_INVALID, "object: NULL volume");
    if (volume->dims[0] < 1 || volume->dims[1] < 1 || volume->dims[2] < 1)
        return vv_error_set(VV_ERR_INVALID, "object: volume has dimensions %dx%dx%d",
                            volume->dims[0], volume->dims[1], volume->dims[2]);
    vv_object *o = calloc(1, sizeof *o);
    if (!o)
        return vv_error_set(VV_ERR_NOMEM, "object: out of memory");
    vv_model_copy_name(o->name, name ? name : "volume");
    o->type = VV_OBJECT_VOLUME;
    o->volume = vv_volume_ref(volume);
    o->position = vv_vec3_make(0, 0, 0);
    o->orientation = vv_quat_identity();
    o->scale = vv_vec3_make(1, 1, 1);
    o->material.ambient = 0.1;
    o->material.diffuse = 0.6;
    o->material.specular = 0.3;
    o->material.shininess = 30.0;
    o->material.color = vv_vec3_make(1, 1, 1);
    o->segmentation = VV_SEG_TRANSFER_FUNCTION;
    double lo = volume->range[0], hi = volume->range[1];
    if (!isfinite(lo) || !isfinite(hi)) {
        lo = 0.0;
        hi = 1.0;
    }
    if (!(hi > lo))
        hi = lo + 1.0;
    o->threshold = 0.5 * (lo + hi);
    vv_tf_set_ramp(&o->tf, lo, hi, 1.0, vv_vec3_make(1, 1, 1), vv_model_min_spacing(volume));
    o->mode = VV_MODE_COMPOSITE;
    o->isovalue = 0.5 * (lo + hi);
    o->step = 0.5;
    o->shading = 1;
    o->visible = 1;
    o->n_cut_planes = 0;
    *out = o;
    return VV_OK;
}

void
vv_object_free(vv_object *obj) {
    if (!obj)
        return;
    vv_volume_free(obj->volume);
    free(obj);
}

vv_mat4
vv_object_matrix(const vv_object *obj) {
    if (!obj)
        return vv_mat4_identity();
    vv_mat4 t = vv_mat4_translate(obj->position);
    vv_mat4 r = vv_quat_to_mat4(vv_quat_normalize(obj->orientation));
    vv_mat4 s = vv_mat4_scale(obj->scale);
    return vv_mat4_mul(t, vv_mat4_mul(r, s));
}

vv_mat4
vv_object_index_to_world(const vv_object *obj) {
    if (!obj || !obj->volume)
        return vv_object_matrix(obj);
    return vv_mat4_mul(vv_object_matrix(obj), vv_volume_index_to_world(obj->volume));
}

vv_box
vv_object_world_box(const vv_object *obj) {
    vv_box b = {{0, 0, 0}, {0, 0, 0}};
    if (!obj || !obj->volume)
        return b;
    vv_box idx = {
        {0, 0, 0},
        {obj->volume->dims[0] - 1.0, obj->volume->dims[1] - 1.0, obj->volume->dims[2] - 1.0}};
    return vv_box_transform(idx, vv_object_index_to_world(obj));
}
