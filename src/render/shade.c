/*
 * The shading stage: the lights of a World and the shading constants,
 * transforms, grid box and cut planes of a volume object prepared for a
 * frame, and a multi-channel object's channels as objects of one channel
 * (shade.h describes them and cites the method).
 */
#include "render/shade.h"

#include <math.h>

#include "core/geom.h"
#include "core/internal.h"

int
vv_vlights_prepare(vv_vlight out[VV_MAX_LIGHTS], const vv_world *w, const vv_view *view) {
    vv_vec3 fwd = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    int n = 0;
    for (int i = 0; i < w->n_lights && i < VV_MAX_LIGHTS; i++) {
        const vv_light *l = &w->lights[i];
        vv_vlight *o = &out[n++];
        o->point = l->type == VV_LIGHT_POINT && !l->headlight;
        vv_vec3 d = l->headlight ? fwd : vv_vec3_normalize(l->direction);
        /* towards the light = against the direction it travels */
        o->dir[0] = (float)-d.x;
        o->dir[1] = (float)-d.y;
        o->dir[2] = (float)-d.z;
        o->pos[0] = (float)l->position.x;
        o->pos[1] = (float)l->position.y;
        o->pos[2] = (float)l->position.z;
        o->col[0] = (float)(l->color.x * l->intensity);
        o->col[1] = (float)(l->color.y * l->intensity);
        o->col[2] = (float)(l->color.z * l->intensity);
    }
    return n;
}

void
vv_vchannel_object(const vv_object *obj, const vv_channel *cc, vv_object *out) {
    *out = *obj;
    out->volume = cc->volume;
    out->tf = cc->tf;
    out->n_channels = 0;
    out->channels = NULL;
    out->mode = obj->blend == VV_BLEND_MAXIMUM ? VV_MODE_MIP : VV_MODE_COMPOSITE;
    out->segmentation = cc->labels ? VV_SEG_LABELS : VV_SEG_TRANSFER_FUNCTION;
    out->texture.image = NULL;
    vv_solid_texture_init(&out->solid_texture);
}

int
vv_vchannels_shown(const vv_object *obj) {
    int n = 0;
    for (int c = 0; obj->n_channels > 1 && c < obj->n_channels; c++)
        n += obj->channels[c].visible && obj->channels[c].volume != NULL;
    return n;
}

vv_status
vv_vobject_prepare(const vv_object *obj, const vv_world *w, const float ambient[3],
                   const vv_vlight *lights, int n_lights, double w2i[3][4], double i2w[3][4],
                   int dims[3], vv_plane *planes, int *n_planes, vv_vshading *sh) {
    vv_mat4 m = vv_object_index_to_world(obj);
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(m, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
    for (int r = 0; r < 3; r++)
        for (int cc = 0; cc < 4; cc++) {
            w2i[r][cc] = inv.m[r][cc];
            i2w[r][cc] = m.m[r][cc];
        }
    /* normals: world normal = (M^-1)^T g_index, M = linear part of i2w */
    for (int r = 0; r < 3; r++)
        for (int cc = 0; cc < 3; cc++)
            sh->nrm[r][cc] = (float)inv.m[cc][r];
    for (int a = 0; a < 3; a++)
        /* a single-voxel axis (a 2-D image) is one voxel thick: the cache
         * holds that slice twice */
        dims[a] = obj->volume->dims[a] > 1 ? obj->volume->dims[a] : 2;
    *n_planes = 0;
    for (int p = 0; p < w->n_cut_planes && *n_planes < 2 * VV_MAX_CUT_PLANES; p++)
        planes[(*n_planes)++] =
            vv_plane_from_point_normal(w->cut_planes[p].point, w->cut_planes[p].normal);
    for (int p = 0; p < obj->n_cut_planes && *n_planes < 2 * VV_MAX_CUT_PLANES; p++)
        planes[(*n_planes)++] =
            vv_plane_from_point_normal(obj->cut_planes[p].point, obj->cut_planes[p].normal);
    const vv_material *mt = &obj->material;
    for (int i = 0; i <= VV_VC_SPEC; i++)
        sh->spec[i] = (float)pow((double)i / VV_VC_SPEC, mt->shininess);
    sh->base[0] = (float)mt->color.x;
    sh->base[1] = (float)mt->color.y;
    sh->base[2] = (float)mt->color.z;
    for (int ch = 0; ch < 3; ch++) {
        sh->amb[ch] = (float)mt->ambient * ambient[ch];
        for (int l = 0; l < n_lights; l++) {
            sh->kd_col[l][ch] = (float)mt->diffuse * lights[l].col[ch];
            sh->ks_col[l][ch] = (float)mt->specular * lights[l].col[ch];
        }
    }
    return VV_OK;
}
