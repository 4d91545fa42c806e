/*
 * The classification stage of the volume renderers (internal, not part of
 * the public API): the transfer-function tables of tf_tables.h, built per
 * object and looked up per sample; the extras beyond the 1-D table (a 2-D
 * transfer function over value and gradient magnitude, a solid texture, the
 * colours of a label volume); the first pass of a composite kernel, which
 * classifies a chunk of samples at once (vv_vray_classify; its AVX2 path is
 * in kernels_avx2.c); and pre-integrated classification.
 *
 * Post-classification as in Levoy's volume ray casting (IEEE CG&A 1988):
 * the interpolated value is looked up in a table, with opacity corrected
 * for the step. 2-D transfer functions: Kniss, Kindlmann and Hansen,
 * "Multidimensional transfer functions for interactive volume rendering",
 * IEEE TVCG 2002. Pre-integration: Engel, Kraus and Ertl 2001 (vv_vpre
 * below). docs/rendering.md describes the method. Building tables is not
 * thread-safe; the lookups only read and may run on many threads.
 */
#ifndef VV_RENDER_CLASSIFY_H
#define VV_RENDER_CLASSIFY_H

#include <math.h>
#include <stdint.h>

#include "render/ray.h"
#include "render/sample.h"
#include "render/tf_tables.h"
#include "volvis/render.h"

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

/* Table index (as float) of stored value v; a NaN index is 0, as the AVX2
 * kernel's max makes it: a float volume whose range is wider than a float
 * holds (values near -FLT_MAX and +FLT_MAX) stores some as infinite, and a
 * sample between them is NaN, and the callers' (int) of a NaN index was
 * undefined behaviour (x86 gives INT_MIN, and 4 times it overflows; found
 * by fuzz_render). */
static inline float
vv_vtables_index(const vv_vtables *t, float v) {
    float x = (v - t->lut_lo) * t->lut_scale;
    return x > 0 ? (x < VV_VC_LUT - 1 ? x : VV_VC_LUT - 1) : 0;
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
            best = vv_label_key(l);
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
        li = li > 0 ? (li < VV_VC_LUT - 1 ? li : VV_VC_LUT - 1) : 0; /* NaN: 0 */
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

#endif
