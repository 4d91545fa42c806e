/*
 * The shading stage of the volume renderers (internal, not part of the
 * public API): the lights and each object's shading constants, prepared
 * once a frame together with what the renderers derive alike from a volume
 * object (its transforms, grid box and cut planes); a multi-channel
 * object's channels as objects of one channel; Phong shading of a sample
 * (vv_vshade; eight samples at a time with AVX2, vv_vshade8, and the
 * shading pass of the AVX2 composite kernel, vv_vchunk_shade8, both in
 * kernels_avx2.c); and the shading inputs of an isosurface hit.
 *
 * Phong's model with the reflection vector (Bui Tuong Phong, "Illumination
 * for computer generated pictures", CACM 1975), two-sided, the normal being
 * the gradient (Levoy, IEEE CG&A 1988). docs/rendering.md ("Shading")
 * describes the method. The shading functions only read and may run on many
 * threads.
 */
#ifndef VV_RENDER_SHADE_H
#define VV_RENDER_SHADE_H

#include <math.h>
#include <stdint.h>

#include "render/classify.h"
#include "render/phong.h"
#include "render/ray.h"
#include "render/sample.h"
#include "volvis/render.h"

#define VV_VC_SPEC 2048 /* specular table entries */

/* A light prepared for volume shading. */
typedef struct vv_vlight {
    int point;
    float dir[3]; /* unit vector towards the light (directional) */
    float pos[3]; /* world position (point) */
    float col[3]; /* colour * intensity */
} vv_vlight;

/* The lights of @p w (a headlight shines along the view direction of
 * @p view); returns how many (at most VV_MAX_LIGHTS). */
int vv_vlights_prepare(vv_vlight out[VV_MAX_LIGHTS], const vv_world *w, const vv_view *view);

/* An object's shading constants. */
typedef struct vv_vshading {
    float nrm[3][3];                /* index-space gradient -> world normal (M^-T) */
    float amb[3];                   /* ka * ambient light */
    float kd_col[VV_MAX_LIGHTS][3]; /* kd * light colour */
    float ks_col[VV_MAX_LIGHTS][3]; /* ks * light colour */
    float base[3];                  /* material colour (iso, threshold) */
    float spec[VV_VC_SPEC + 1];     /* x^shininess for x in [0, 1] */
} vv_vshading;

/* What both renderers derive alike from a volume object: world -> index
 * and index -> world (affine rows), the grid box dims (a single-voxel axis
 * counts as 2, the cache holds it twice), the global then local cut planes
 * (at most 2 * VV_MAX_CUT_PLANES) and the shading constants under
 * @p ambient and @p lights. Errors: VV_ERR_INVALID (singular transform). */
vv_status vv_vobject_prepare(const vv_object *obj, const vv_world *w, const float ambient[3],
                             const vv_vlight *lights, int n_lights, double w2i[3][4],
                             double i2w[3][4], int dims[3], vv_plane *planes, int *n_planes,
                             vv_vshading *sh);

/* Channel @p cc of multi-channel object @p obj as an object of one channel,
 * @p out: a shallow copy of @p obj (it borrows the volume and transfer
 * function, owns nothing: not to be freed) with the channel's volume and
 * transfer function, no channels, no 2-D TF or texture, composite mode
 * (VV_MODE_MIP under VV_BLEND_MAXIMUM), segmented by labels for a label
 * channel (VV_SEG_LABELS: its vv_vextra colours by label). How the ray caster and the ray
 * tracer prepare each visible channel (vv_channel_blend). */
void vv_vchannel_object(const vv_object *obj, const vv_channel *cc, vv_object *out);

/* The visible channels (with a volume) of @p obj: 0 for an object of one
 * channel (n_channels < 2). */
int vv_vchannels_shown(const vv_object *obj);

/* A light's transmittance for shading (shadows), or NULL: none. */
typedef float (*vv_vshadow_fn)(const void *ctx, int light);

/* Phong (reflection vector) with two-sided lighting. g: index-space
 * gradient; pw: world position (read for point lights); v: unit vector
 * towards the eye; col: colour times the sample's opacity, alpha: that
 * opacity. out = (ka*ambient + kd*diffuse) * col + alpha * ks * specular:
 * the highlight is emitted by the sample like its colour, so it too is
 * weighted by the sample's opacity (otherwise it would grow as the step
 * shrinks). With @p shadow, each light's terms are scaled by
 * shadow(ctx, light). */
static inline void
vv_vshade(const vv_vshading *o, const vv_vlight *lights, int n_lights, const float g[3],
          const float pw[3], const float v[3], const float col[3], float alpha,
          vv_vshadow_fn shadow, const void *ctx, float out[3]) {
    const float n0 = o->nrm[0][0] * g[0] + o->nrm[0][1] * g[1] + o->nrm[0][2] * g[2];
    const float n1 = o->nrm[1][0] * g[0] + o->nrm[1][1] * g[1] + o->nrm[1][2] * g[2];
    const float n2 = o->nrm[2][0] * g[0] + o->nrm[2][1] * g[1] + o->nrm[2][2] * g[2];
    const float len2 = n0 * n0 + n1 * n1 + n2 * n2;
    float d0 = o->amb[0], d1 = o->amb[1], d2 = o->amb[2];
    float s0 = 0, s1 = 0, s2 = 0;
    if (len2 > 1e-12f) {
        const float inv = 1.0f / sqrtf(len2);
        const float nv = (n0 * v[0] + n1 * v[1] + n2 * v[2]) * inv;
        for (int l = 0; l < n_lights; l++) {
            const vv_vlight *lt = &lights[l];
            float L[3], ndl;
            if (!vv_phong_light_dir(lt->point, lt->dir, lt->pos, pw, L))
                continue;
            const float rv = vv_phong_rv((n0 * L[0] + n1 * L[1] + n2 * L[2]) * inv, nv, L, v, &ndl);
            float sp = rv > 0 ? o->spec[(int)(rv * VV_VC_SPEC + 0.5f)] : 0;
            float wd = ndl;
            if (shadow) {
                const float sh = shadow(ctx, l);
                wd = sh * ndl;
                sp = sh * sp;
            }
            d0 += wd * o->kd_col[l][0];
            d1 += wd * o->kd_col[l][1];
            d2 += wd * o->kd_col[l][2];
            s0 += sp * o->ks_col[l][0];
            s1 += sp * o->ks_col[l][1];
            s2 += sp * o->ks_col[l][2];
        }
    }
    out[0] = d0 * col[0] + alpha * s0;
    out[1] = d1 * col[1] + alpha * s1;
    out[2] = d2 * col[2] + alpha * s2;
}

/* vv_vshade of eight samples at once with AVX2 (the caller checks
 * vv_vc_have_avx2; directional lights only): sample i has the index-space
 * gradient (gx[i], gy[i], gz[i]), opacity a[i] and colour times opacity
 * (cr[i], cg[i], cb[i]); its shaded colour goes to (out_r[i], out_g[i],
 * out_b[i]). @p shadow: NULL, or n_lights rows of 8 transmittances (light
 * l of sample i at shadow[8 l + i]), vv_vshade's shadow(ctx, l). The
 * arithmetic is vv_vshade's, operation for operation (separate multiplies
 * and adds, IEEE square root and division), so each result is
 * bit-identical to vv_vshade's. Every lane is computed: lanes the caller
 * does not use may hold anything finite. */
void vv_vshade8(const vv_vshading *o, const vv_vlight *lights, int n_lights, const float v[3],
                const float *shadow, const float gx[8], const float gy[8], const float gz[8],
                const float a[8], const float cr[8], const float cg[8], const float cb[8],
                float out_r[8], float out_g[8], float out_b[8]);

/* The lights' transmittances at sample @p s of a chunk (vv_vchunk_shade8):
 * light l's into sh[stride * l]; returns 0 (sh untouched) when the sample
 * receives no shadows. */
typedef int (*vv_vshadow8_fn)(void *ctx, int s, float *sh, int stride);

/* The second pass of a composite kernel with AVX2 (the caller checks
 * vv_vc_have_avx2, cached gradients, directional lights): the visible
 * samples of a classified chunk of @p m (vv_vray_classify: cell, fractions,
 * entries into @p lut) shaded eight at a time (vv_vshade8, with @p shadow's
 * transmittances when not NULL), then composited one by one under C, A in
 * order, stopping when A reaches @p et. *first (when still < 0) gets the
 * chunk index of the first sample composited; *shaded counts them.
 * Returns 1 when the ray ended. */
int vv_vchunk_shade8(const vv_vcache *c, const float *lut, const vv_vshading *o,
                     const vv_vlight *lights, int n_lights, const float v[3], int m,
                     const size_t *cell, const float *fx, const float *fy, const float *fz,
                     const int32_t *entry, vv_vshadow8_fn shadow, void *ctx, float et, float C[3],
                     float *A, int *first, uint32_t *shaded);

/* The world point of ray @p wr at parameter @p t (world units), in float:
 * where point lights and shadows are evaluated for a sample. */
static inline void
vv_ray_world_point(const vv_ray *wr, double t, float pw[3]) {
    pw[0] = (float)(wr->origin.x + t * wr->dir.x);
    pw[1] = (float)(wr->origin.y + t * wr->dir.y);
    pw[2] = (float)(wr->origin.z + t * wr->dir.z);
}

/* An isosurface hit at ray parameter th of ray r (world ray wr): its index
 * point ph, gradient g (vv_vcache_gradient), world point pw, and its
 * material colour base0 times the texture @p tex at its object point
 * (x: vv_vextra_object_point) where there is one (NULL: none). */
static inline void
vv_viso_hit_point(const vv_vcache *c, const vv_vray *r, const vv_ray *wr, double th,
                  const float base0[3], const vv_texture_map *tex, const vv_vextra *x, float ph[3],
                  float g[3], float pw[3], float base[3]) {
    vv_vray_point(r, th, ph);
    vv_vcache_gradient(c, ph, g);
    vv_ray_world_point(wr, th, pw);
    base[0] = base0[0];
    base[1] = base0[1];
    base[2] = base0[2];
    if (tex) {
        const vv_vec3 tc = vv_texture_map_eval(tex, vv_vextra_object_point(x, ph));
        base[0] *= (float)tc.x;
        base[1] *= (float)tc.y;
        base[2] *= (float)tc.z;
    }
}

#endif
