/*
 * Volume data shared by the volume renderers (raycast, raytrace, splat):
 * internal, not part of the public API.
 *
 * Per volume, a cache holds the voxels as 16-bit offsets from the minimum
 * when the data are integers spanning at most 65535 (exact, and half the
 * memory traffic of float), else as float; all values inside the renderers
 * ("stored units") are real value - qoff. The unit gradient direction of
 * every voxel (central differences, computed once) is quantised to 3 x int8
 * in a separate array, touched only where a sample is shaded, and every
 * subvolume of 4^3 cells has the min/max of its stored values (the PARC
 * grid of the VolVis paper's Navigator, section 4; computed from the stored
 * values rather than with vv_minmax_grid_build so that it agrees exactly
 * with the samples: NaN voxels are stored as the minimum, a single-voxel
 * axis is held twice).
 *
 * Per object, tables (vv_vtables): the transfer function in a 4096-entry
 * table with opacity corrected for the step, optionally the extinction per
 * world unit, which subvolumes are visible under the transfer function or
 * isovalue, and each subvolume's chessboard distance to the nearest visible
 * one (empty-space leaping). The last tables built for a volume are kept in
 * its cache between frames while nothing they depend on changes.
 *
 * Not thread-safe while building; the sampling functions below only read
 * and may run on many threads. docs/rendering.md describes the method.
 */
#ifndef VV_RENDER_VOLUME_CACHE_H
#define VV_RENDER_VOLUME_CACHE_H

#include <math.h>
#include <stdint.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "render/ray.h"
#include "render/sample.h"
#include "render/tf_tables.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

/* The tables of object @p obj on cache @p c for step @p dt (world units)
 * in @p mode; @p iso in stored units; @p skipping 0 marks every subvolume
 * visible; @p flags VV_VT_EXT also builds the extinction table, VV_VT_PREINT
 * the pre-integration table where the object's classification allows it
 * (composite mode, a 1-D transfer function or a threshold). Borrowed from the
 * cache when nothing they depend on changed (*owned = 0: do not free), else
 * built (*owned = 1 unless handed to the cache; free with
 * vv_vtables_free). Errors: VV_ERR_NOMEM. */
vv_status vv_vtables_get(vv_vcache_set *s, vv_vcache *c, const vv_object *obj, vv_render_mode mode,
                         double dt, float iso, int skipping, int flags, vv_vtables *out,
                         int *owned);

/* Table index (as float) of stored value v. */
static inline float
vv_vtables_index(const vv_vtables *t, float v) {
    float x = (v - t->lut_lo) * t->lut_scale;
    return x < 0 ? 0 : x > VV_VC_LUT - 1 ? VV_VC_LUT - 1 : x;
}

/* An object's per-sample extras beyond the 1-D table: a 2-D transfer
 * function (t->lut2d) and a solid texture. */
typedef struct vv_vextra {
    const float *lut2d;
    float lut_lo, lut_scale;       /* stored value -> table index (as the 1-D table) */
    float lut2_scale;              /* table index -> value bin */
    float g_scale;                 /* gradient magnitude -> gradient bin */
    const vv_solid_texture *solid; /* NULL: none */
    const vv_volume *labels;       /* a label volume (VV_SEG_LABELS) to colour by, or NULL */
    double i2o[3][4];              /* index -> the volume's own world coordinates */
} vv_vextra;

/* The label of a label volume at index point p: of the cell's 8 corner
 * voxels with a non-zero label, the one of largest trilinear weight (the
 * nearest), so colours do not blend across labels; 0 when all are 0. */
static inline uint32_t
vv_vextra_label(const vv_volume *v, const float p[3]) {
    int i0[3];
    float f[3];
    for (int a = 0; a < 3; a++) {
        float q = p[a] < 0 ? 0 : p[a] > (float)(v->dims[a] - 1) ? (float)(v->dims[a] - 1) : p[a];
        i0[a] = (int)q;
        if (i0[a] > v->dims[a] - 2)
            i0[a] = v->dims[a] > 1 ? v->dims[a] - 2 : 0;
        f[a] = q - (float)i0[a];
    }
    uint32_t best = 0;
    float bw = -1;
    for (int c = 0; c < 8; c++) {
        int d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
        int ix[3];
        float w = 1;
        for (int a = 0; a < 3; a++) {
            ix[a] = i0[a] + d[a] < v->dims[a] ? i0[a] + d[a] : v->dims[a] - 1;
            w *= d[a] ? f[a] : 1 - f[a];
        }
        double l = vv_voxel_value(
            v->type, v->data, ((size_t)ix[2] * v->dims[1] + (size_t)ix[1]) * v->dims[0] + ix[0]);
        if (l >= 1 && w > bw) {
            bw = w;
            best = l < 4294967296.0 ? (uint32_t)(l + 0.5) : 0;
        }
    }
    return best;
}

/* Fills @p x for object @p obj in @p mode with tables @p t; returns 1 when
 * the object has extras (the fast single-volume kernels do not handle
 * them). */
int vv_vextra_prepare(vv_vextra *x, const vv_object *obj, vv_render_mode mode, const vv_vtables *t);

/* The classified sample at index point p with value val (stored units)
 * and 1-D entry e under the extras: the 2-D table entry in place of e,
 * then the colour times the solid texture. Returns e itself or @p buf. */
static inline const float *
vv_vextra_apply(const vv_vextra *x, const vv_vcache *c, const float p[3], float val, const float *e,
                float buf[4]) {
    if (x->lut2d) {
        float li = (val - x->lut_lo) * x->lut_scale;
        li = li < 0 ? 0 : li > VV_VC_LUT - 1 ? VV_VC_LUT - 1 : li;
        const int vb = (int)(li * x->lut2_scale + 0.5f);
        int gb = (int)(vv_vcache_gmag(c, p) * x->g_scale + 0.5f);
        gb = gb < 0 ? 0 : gb > VV_VC_LUT2_G - 1 ? VV_VC_LUT2_G - 1 : gb;
        e = x->lut2d + 4 * ((size_t)gb * VV_VC_LUT2_V + (size_t)vb);
    }
    if (x->solid && e[0] > 0) {
        const double q[3] = {p[0], p[1], p[2]};
        vv_vec3 o;
        o.x = x->i2o[0][0] * q[0] + x->i2o[0][1] * q[1] + x->i2o[0][2] * q[2] + x->i2o[0][3];
        o.y = x->i2o[1][0] * q[0] + x->i2o[1][1] * q[1] + x->i2o[1][2] * q[2] + x->i2o[1][3];
        o.z = x->i2o[2][0] * q[0] + x->i2o[2][1] * q[1] + x->i2o[2][2] * q[2] + x->i2o[2][3];
        const vv_vec3 col = vv_solid_texture_eval(x->solid, o);
        buf[0] = e[0];
        buf[1] = e[1] * (float)col.x;
        buf[2] = e[2] * (float)col.y;
        buf[3] = e[3] * (float)col.z;
        return buf;
    }
    if (x->labels && e[0] > 0) {
        const vv_vec3 col = vv_label_color(vv_vextra_label(x->labels, p));
        buf[0] = e[0];
        buf[1] = e[0] * (float)col.x;
        buf[2] = e[0] * (float)col.y;
        buf[3] = e[0] * (float)col.z;
        return buf;
    }
    return e;
}

/* The index point p of an object in its volume's own world coordinates
 * (object coordinates, where textures are defined). */
static inline vv_vec3
vv_vextra_object_point(const vv_vextra *x, const float p[3]) {
    vv_vec3 o;
    o.x = x->i2o[0][0] * p[0] + x->i2o[0][1] * p[1] + x->i2o[0][2] * p[2] + x->i2o[0][3];
    o.y = x->i2o[1][0] * p[0] + x->i2o[1][1] * p[1] + x->i2o[1][2] * p[2] + x->i2o[1][3];
    o.z = x->i2o[2][0] * p[0] + x->i2o[2][1] * p[1] + x->i2o[2][2] * p[2] + x->i2o[2][3];
    return o;
}

/* ---------------------------------------------------------------------- */
/* Volume objects, lights and shading                                       */

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
            float L0 = lt->dir[0], L1 = lt->dir[1], L2 = lt->dir[2];
            if (lt->point) {
                L0 = lt->pos[0] - pw[0];
                L1 = lt->pos[1] - pw[1];
                L2 = lt->pos[2] - pw[2];
                const float ll = sqrtf(L0 * L0 + L1 * L1 + L2 * L2);
                if (!(ll > 0))
                    continue;
                L0 /= ll;
                L1 /= ll;
                L2 /= ll;
            }
            float ndl = (n0 * L0 + n1 * L1 + n2 * L2) * inv;
            /* two-sided: a normal facing away from the light is flipped */
            const float ndv = ndl < 0 ? -nv : nv;
            ndl = ndl < 0 ? -ndl : ndl;
            /* Phong: R.V with R the mirror of L about n */
            const float rv = 2 * ndl * ndv - (L0 * v[0] + L1 * v[1] + L2 * v[2]);
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

/* The isosurface crossing between ray parameters ta (value va, on one side
 * of iso) and tb (on the other), by ten bisection steps. */
static inline double
vv_vray_iso_refine(const vv_vcache *c, const vv_vray *r, double ta, float va, double tb,
                   float iso) {
    for (int it = 0; it < 10; it++) {
        double tm = 0.5 * (ta + tb);
        float pm[3];
        vv_vray_point(r, tm, pm);
        float vm = vv_vcache_sample(c, pm);
        if ((va < iso) == (vm < iso)) {
            ta = tm;
            va = vm;
        } else {
            tb = tm;
        }
    }
    return 0.5 * (ta + tb);
}

/* An iso crossing search meets visible sample k after skipping hidden ones
 * (the multi-object marches of the ray caster and the ray tracer: *has ==
 * 2), or starts a region's samples at k (vv_vray_iso_first): it restarts
 * at sample k - 1, *pt its parameter, *pv its value, as a march of every
 * sample has it. */
static inline void
vv_vray_iso_restart(const vv_vcache *c, const vv_vray *r, double k, double dt, float *pv,
                    double *pt, int *has) {
    float p[3];
    *pt = (k - 1) * dt;
    vv_vray_point(r, *pt, p);
    *pv = vv_vcache_sample(c, p);
    *has = 1;
}

/* Maximum (VV_MODE_MIP) or minimum (VV_MODE_MINIP) intensity projection or
 * mean (VV_MODE_XRAY) of the samples t = k dt of the clipped ray r, one
 * sample in the middle when it is shorter than a step; *depth: the
 * parameter of the extreme (xray: the entry). With @p skipping, groups of
 * subvolumes, then subvolumes, that cannot beat the current extreme are
 * skipped whole (same result).
 *
 * @p lo and @p hi (stored units; -INFINITY and INFINITY for none) say what
 * the caller's classification cannot tell apart: every value <= lo maps to
 * the same colour, and every value >= hi. MIP then starts its maximum at lo
 * (a ray whose maximum is at most lo returns lo and depth t0) and stops once
 * it reaches hi; MinIP starts at hi and stops at lo. The value returned
 * always classifies exactly as the true extreme does; only the depth may
 * name an earlier sample of the same colour. */
void vv_vray_project(const vv_vcache *c, const vv_vray *r, vv_render_mode mode, double dt,
                     int skipping, float lo, float hi, float *value, float *depth);
/* The X-ray sum of ray r: the values of its samples t = k dt added in
 * order (eight at a time with @p avx2 and 16-bit values: the same values
 * and order) into *sum, their number returned, *depth its entry; a ray
 * shorter than a step has one sample, in the middle (its depth).
 * vv_vray_project's X-ray mean is *sum / n; region renders (VV_REGION_SUM)
 * add up the sums of their rays' pieces. Thread-safe. */
long vv_vray_xray_sum(const vv_vcache *c, const vv_vray *r, double dt, int avx2, double *sum,
                      float *depth);
/* A region render's X-ray pixel (VV_REGION_SUM, include/volvis/sys/renderer.h)
 * along primary ray @p wr (world space) through the volume of cache @p c
 * (@p w2i, @p dims and cut planes as vv_vray_setup takes them; @p inv_form as
 * vv_vray_clip_region): the sum of the region's sample values at t = k dt,
 * split into *key (the sum rounded to float) and px[0] (the rest), their
 * count in px[1], px[2] = px[3] = 0, and *depth the whole ray's depth -- its
 * entry, or on a ray too short for a sample its one middle sample, and
 * +inf when the region is not where the ray enters. Nothing taken: px 0,
 * *key NAN, *depth +inf. Returns the samples taken. The ray caster's and the
 * ray tracer's region renders in xray mode share it, so their sums are the
 * same bit for bit. Thread-safe. */
/* The table that classifies the means of a region render's X-ray sums
 * (vv_region_image.classify): a copy of the object's transfer-function
 * table, its entries {alpha, r alpha, g alpha, b alpha}. */
typedef struct vv_xray_table {
    float lut_lo, lut_scale; /* value -> entry */
    float lut[4 * VV_VC_LUT];
} vv_xray_table;

/* vv_region_image.classify over a vv_xray_table (@p ctx): the entry of
 * value @p v (clamped to the table) into @p e. */
void vv_xray_table_classify(const void *ctx, float v, float e[4]);

long vv_vray_xray_region_pixel(const vv_vcache *c, const double w2i[3][4], const int dims[3],
                               const vv_plane *planes, int n_planes, const vv_render_region *rg,
                               double dt, int inv_form, const vv_ray *wr, int avx2, float px[4],
                               float *depth, float *key);
/* vv_vray_project with the bounds of tables @p t (plo, phi) and, with
 * @p skipping, their distances pdist to leap through subvolumes that hold
 * nothing beyond the starting bound. With @p avx2 (vv_vc_have_avx2) and
 * 16-bit values, MIP and MinIP march in chunks of samples, testing their
 * subvolumes and interpolating them eight at a time with the scalar
 * path's arithmetic: the same value, except that a ray reaching @p hi
 * (MinIP: @p lo) may stop a few samples later, at a value that classifies
 * the same, and its depth may differ; X-ray adds the same values in the
 * same order (the same result). */
void vv_vray_project_tables(const vv_vcache *c, const vv_vtables *t, const vv_vray *r,
                            vv_render_mode mode, double dt, int skipping, int avx2, float *value,
                            float *depth);
/* The maximum intensity projections of @p n channels (1..VV_MAX_CHANNELS;
 * one, or a ray shorter than a step: vv_vray_project_tables per channel)
 * on one ray, in one pass: cs[ch], ts[ch] each channel's cache and MIP
 * tables (every channel has the same grid), value[ch] and depth[ch] what
 * vv_vray_project_tables gives channel ch alone (a channel that reaches
 * its table's flat top stops at the end of a subvolume here, at the end of
 * a run of eight samples there: the same colour, the depth of a sample of
 * it that may differ), marching one subvolume at a time with the same
 * arithmetic. With @p skipping the rays leap over the cubes of
 * subvolumes where no channel still short of its upper bound holds
 * anything beyond its starting bound, skip groups and subvolumes where none
 * can beat its maximum, and inside a subvolume only the channels that can
 * are sampled: the traversal is shared, the sampling is per channel. */
void vv_vray_project_channels(const vv_vcache *const *cs, const vv_vtables *const *ts, int n,
                              const vv_vray *r, double dt, int skipping, int avx2, float *value,
                              float *depth);

/* The first crossing of @p iso along ray r (step dt) through the runs of
 * visible subvolumes (@p bdist of tables made for iso mode: a subvolume is
 * hidden when its values all lie below iso): the sample values in
 * order (eight at a time with @p avx2 and 16-bit values: the same values),
 * a crossing between two consecutive ones refined by vv_vray_iso_refine;
 * after a stretch of hidden subvolumes the search restarts at the sample
 * before the run (so the crossing is the same with skipping on or off, and
 * in a region's voxels), and the ray's first sample counts as a hit
 * when it is already at or above iso (a cut face). With @p cont (a region
 * render whose first sample is not the whole ray's: vv_vray_clip_region
 * said so) the search starts from the sample before the region's first,
 * read from its ghost voxels, so that the crossing between them is found
 * here (VV_REGION_NEAREST); when that sample is already at or above iso
 * the whole ray crossed before it, and it is returned as a hit (the
 * region in front holds a crossing at most as deep, which the combine
 * keeps; a neighbour of another level may not, and this hit then closes
 * the crack). Returns the crossing's ray parameter, or -1 for none.
 * Shared by the ray caster and the ray tracer, so that their isosurfaces
 * agree bit for bit. Thread-safe. */
double vv_vray_iso_first(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt,
                         float iso, int avx2, int cont);

/* The bounds @p lo, @p hi of vv_vray_project for a projection table @p t
 * ({alpha, r, g, b} entries): the largest stored value below which every
 * entry equals the first, and the smallest above which every entry equals
 * the last (with a margin of one entry for rounding). */
void vv_vtables_flat_ends(const vv_vtables *t, float *lo, float *hi);

/* Pass 1 of a composite kernel: for the samples k = kfirst .. kfirst + m - 1
 * (m <= VV_VC_CHUNK; every array holds VV_VC_CHUNK, and the entries from m
 * up to the next multiple of 8 may be overwritten) of ray r, the cell
 * offset, the fractions and the
 * table entry (4 * index), with no branches so that the independent
 * samples overlap in the pipeline. With @p avx2 (vv_vc_have_avx2) and
 * 16-bit values, eight samples at a time with AVX2 and FMA; the two differ
 * only in the rounding of fused multiply-adds. With @p x not NULL, x[s]
 * gets each sample's table position (the entry's index before truncation,
 * in [0, VV_VC_LUT - 1]). */
void vv_vray_classify(const vv_vcache *c, const vv_vtables *t, const vv_vray *r, double kfirst,
                      double dt, int m, int avx2, size_t *cell, float *fx, float *fy, float *fz,
                      int32_t *entry, float *x);

/* Pre-integrated classification (Engel, Kraus and Ertl, "High-quality
 * pre-integrated volume rendering using hardware-accelerated pixel
 * shading", Graphics Hardware 2001; the prefix-integral form): between two
 * samples the value is taken to run linearly, and the segment's opacity
 * and emission are the exact integrals of the transfer function along that
 * ramp, from the prefix integrals of vv_vtables.pre. vv_vpre: those
 * integrals and the extinction at one table position. */
typedef struct vv_vpre {
    double T, K[3];    /* prefix integrals of tau and tau c */
    double tau, tk[3]; /* tau and tau c at the position */
} vv_vpre;

/* vv_vpre at table position @p x in [0, VV_VC_LUT - 1] of tables @p t
 * (t->pre not NULL): tau and tau c interpolated linearly between the
 * entries, T and K integrated exactly under that interpolation. */
static inline void
vv_vpre_at(const vv_vtables *t, float x, vv_vpre *p) {
    int i = (int)x;
    i = i > VV_VC_LUT - 2 ? VV_VC_LUT - 2 : i;
    const double f = (double)x - i;
    const double *a = t->pre + 8 * (size_t)i, *b = a + 8;
    const double dtau = b[1] - a[1];
    p->tau = a[1] + f * dtau;
    p->T = a[0] + f * (a[1] + 0.5 * f * dtau);
    for (int c = 0; c < 3; c++) {
        const double dk = b[5 + c] - a[5 + c];
        p->tk[c] = a[5 + c] + f * dk;
        p->K[c] = a[2 + c] + f * (a[5 + c] + 0.5 * f * dk);
    }
}

/* Whether the transfer function is anywhere non-transparent between table
 * positions @p xa and @p xb (the entries around both, inclusive): a
 * segment that is not has opacity 0. */
static inline int
vv_vpre_visible(const vv_vtables *t, float xa, float xb) {
    const float lo = xa < xb ? xa : xb, hi = xa < xb ? xb : xa;
    const int i0 = (int)lo;
    int i1 = (int)hi;
    i1 += (float)i1 < hi && i1 < VV_VC_LUT - 1;
    return t->pre_nz[i1 + 1] > t->pre_nz[i0];
}

/* The segment of length @p len (world units) over which the table position
 * runs linearly from @p xf (integrals @p f) to @p xb (@p b): its opacity
 * 1 - exp(-len * mean tau) and its colour times that opacity, the colour
 * being the mean of c weighted by tau (the emission without attenuation
 * inside the segment, Engel et al.'s approximation). Returns 0 (and sets
 * nothing) when the segment is transparent. */
static inline int
vv_vpre_segment(const vv_vpre *f, float xf, const vv_vpre *b, float xb, double len, float *alpha,
                float col[3]) {
    const double d = (double)xb - (double)xf;
    double tau, k[3];
    if (fabs(d) > 1e-3) {
        const double inv = 1.0 / d;
        tau = (b->T - f->T) * inv;
        for (int c = 0; c < 3; c++)
            k[c] = (b->K[c] - f->K[c]) * inv;
    } else { /* nearly constant: the trapezoid rule */
        tau = 0.5 * (f->tau + b->tau);
        for (int c = 0; c < 3; c++)
            k[c] = 0.5 * (f->tk[c] + b->tk[c]);
    }
    if (!(tau > 1e-12))
        return 0;
    const float a = -expm1f((float)(-tau * len));
    const double s = a / tau;
    *alpha = a;
    for (int c = 0; c < 3; c++)
        col[c] = (float)(k[c] * s);
    return 1;
}
/* The processor has AVX2 and FMA. */
int vv_vc_have_avx2(void);

#endif
