/*
 * Splatting: object-order direct volume rendering (the VolVis paper,
 * abstract and section 2, lists it beside ray casting).
 *
 * Every voxel carries a 3-D Gaussian reconstruction kernel, isotropic in
 * index space (sigma and cut-off radius in voxels), so that in world space
 * it is the ellipsoid that the spacing, direction matrix and object
 * transform make of it; seen from the eye its covariance is
 * sigma^2 A A^T with A the index-to-eye linear map. Its footprint (Westover,
 * "Footprint evaluation for volume rendering", SIGGRAPH 1990) is the
 * kernel integrated along the view direction: a 2-D Gaussian, an ellipse,
 * evaluated as a function of the squared radius after mapping the ellipse
 * to a circle (Westover's radial footprint table; for a Gaussian the
 * integral is closed-form, so the exponential itself is computed, four
 * pixels at a time); each footprint is cut off at the kernel radius and
 * normalised over its disc.
 *
 * Composite, MIP and MinIP use image-aligned sheet buffers (Mueller and
 * Crawfis, "Eliminating popping artifacts in sheet buffer-based splatting",
 * Vis '98): sheets parallel to the image plane, one every sheet spacing in
 * depth, each receiving the slices of the kernels that cross its slab. A
 * Gaussian's slice at depth offset s is again a Gaussian: mass given by
 * the 1-D marginal over the slab (a table of slab integrals), centre
 * shifted by b s, covariance the conditional one (plus the shift's spread
 * over the slab). Sheets hold sum(w), sum(w v) and sum(w g) (values and
 * cached voxel gradients); post-classification (Mueller, Moeller and
 * Crawfis, "Splatting without the blur", Vis '99) classifies and shades the
 * normalised sheet value sum(w v) / sum(w) of each pixel, and the sheets
 * are composited front to back. Pre-classified splatting (option
 * classification=pre) classifies and shades each voxel once and splats
 * opacity and colour instead (faster, blurrier). X-ray splats whole
 * footprints: the image is the line integral, divided by the integral of
 * the weights for the mean the ray caster shows.
 *
 * Antialiasing (Zwicker, Pfister, van Baar and Gross, "EWA volume
 * splatting", Vis '01): every screen-space footprint covariance has its
 * eigenvalues raised to at least the variance of the image low-pass filter
 * (default 0.25 pixel^2), which is what convolving a footprint smaller than
 * a pixel with the filter does; larger footprints are left alone so that
 * near data stays as sharp as the ray caster's. In perspective the
 * footprint of every sheet is scaled by the sheet's depth.
 *
 * Sheets sit at depth z = k dt (world units from the eye plane, dt the ray
 * caster's step), and each pixel composites only the sheets inside its
 * ray's clipped interval (volume box and cut planes, vv_vray_setup), so in
 * parallel projection the samples are exactly the ray caster's and only
 * the reconstruction differs. Opacity uses the ray caster's tables
 * (src/render/volume_cache.h), corrected per pixel for the slant of
 * perspective rays.
 *
 * Cost: a voxel is listed only when its subvolume lies within the kernel's
 * reach of a subvolume visible under the transfer function (the min/max
 * grid of the ray caster's tables) and the values within twice the reach
 * of it span a visible table entry (separable min/max filters); the lists
 * are built in the traversal order of the view-direction octant and kept
 * between renders while the octant, transfer function and volume do not
 * change; each render bucket-sorts them by sheet. The image is cut into
 * bands of rows rendered independently (OpenMP, dynamic), each with its
 * own voxel lists, sheet buffer and occlusion map of 8x8-pixel tiles: a
 * footprint whose bounding box covers only finished pixels (opaque, or
 * past their ray's exit) is not splatted. Every pixel sums its voxels in
 * list order, so the image does not depend on the thread count.
 * docs/rendering.md describes the method and its measurements.
 */
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "core/internal.h"
#include "render/registry.h"
#include "render/splat/splat.h"
#include "render/volume_cache.h"
#include "volvis/render.h"

#define SP_MAX_OBJ 64 /* objects handled in one render (<= VV_VC_MAX) */
#define SP_Z_LUT 1024 /* slab-integral table entries */
#define SP_TILE 8     /* occlusion map tile side in pixels */
#define SP_LISTS 16   /* voxel lists kept between renders */
#define SP_CH 5       /* channels of a sheet pixel */
#define SP_WMIN 0.02f /* least sum of weights that is a sample (1 inside) */
#define SP_MAX_SHEETS 65536

/* One cached voxel list: the voxels worth splatting of one volume under one
 * set of visibility flags, in the traversal order of one octant. */
typedef struct sp_list {
    vv_volume *vol; /* reference held */
    uint64_t modified;
    uint64_t hash; /* of everything the selection depended on */
    int octant;
    uint64_t *vox; /* packed i | j << 21 | k << 42 */
    size_t n;
    uint64_t last_used;
} sp_list;

typedef struct sp_state {
    vv_vcache_set vc;
    double radius, sigma; /* kernel, voxels */
    double ewa_var;       /* image low-pass filter variance, pixel^2; 0: off */
    double early_termination;
    int pre;      /* pre-classified splatting */
    int skipping; /* empty-voxel skipping */
    int occlusion;
    int axis;    /* internal: axis-aligned sheets (the popping method, for tests) */
    double rate; /* sheet spacing in ray-caster steps (0: by quality) */
    sp_list lists[SP_LISTS];
    uint64_t clock;
    vv_splat_stats stats;
    float *xray; /* last X-ray line integrals, or NULL */
    int xray_w, xray_h;
} sp_state;

/* A screen-space footprint: inverse covariance (pixel units) a, b, c
 * (q = a dx^2 + 2 b dx dy + c dy^2), bounding half-extents, 1/sqrt(det). */
typedef struct sp_fp {
    float a, b, c, hx, hy, norm;
} sp_fp;

typedef struct sp_obj {
    const vv_object *obj;
    vv_vcache *c;
    vv_render_mode mode;
    double w2i[3][4], i2w[3][4];
    int dims[3];
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    int n_planes;
    vv_vshading sh;
    int shading;
    int labels;  /* a label volume in composite: colour by label (vv_label_color) */
    int pre_cls; /* pre-classified: the option, or always for a label volume */
    vv_vtables tab;
    int owns_tables;
    /* eye space: X, Y (image right, down) and depth z of an index point are
     * rows . (i, j, k, 1) */
    double ex[4], ey[4], ez[4];
    double cxx, cxy, cyy;             /* footprint covariance in eye units^2 (slice or whole) */
    double bx, by;                    /* slice centre shift per unit depth offset */
    double rz;                        /* depth half-extent of the kernel support */
    double vol_det;                   /* |det| of the index-to-world map: a voxel's world volume */
    double rworld;                    /* support radius bound in world units (cut planes) */
    float wz[SP_Z_LUT], dz[SP_Z_LUT]; /* slab mass and mean offset by d */
    double z_lo, z_scale;             /* d -> table position */
    int ns;                           /* sheets a kernel can touch */
    double dt_lut;                    /* the step the opacity table is for */
    int axis_a, axis_sign;            /* axis-aligned variant: major axis, direction */
    const sp_list *list;
    /* per render, bucket-sorted by first sheet */
    uint64_t *sorted;
    float (*pre)[4]; /* pre-classified: alpha, colour * alpha (shaded) */
    float (*v4)[4];  /* post-classified and shaded: value, gradient (in sorted order) */
    float *v1;       /* otherwise: value (in sorted order) */
    int *start;      /* nsheets + 1 offsets into sorted */
    int kbase, nsheets;
    /* per band: lists */
    int **bstart;    /* [band] -> nsheets + 1 offsets into bidx */
    uint32_t **bidx; /* [band] -> indices into sorted */
    int is_comp;     /* composite (sheets, classified) */
} sp_obj;

typedef struct sp_frame {
    sp_state *st;
    const vv_view *view;
    sp_obj *objs;
    int n_obj, n_comp;
    int persp;
    double dt, dts; /* ray-caster step, sheet spacing */
    double rho2;    /* (radius / sigma)^2 */
    float et;
    float ambient[3], bg[3];
    vv_vlight lights[VV_MAX_LIGHTS];
    int n_lights, point_lights;
    vv_vec3 eye, f, r, u; /* eye point (ortho: o00), forward, right, down */
    double pix;           /* ortho: world per pixel; persp: at unit depth */
    double pcx, pcy;      /* persp: pixel of the forward axis, negated */
    vv_vec3 o00, ox, oy, d00, dx, dy;
    double znear;
    float fp_scale; /* 1 / (2 pi (1 - exp(-rho^2 / 2))): the truncated Gaussian's normalisation */
    int band_h, n_bands;
    int kmin, kmax; /* sheets of the composite objects */
    atomic_int cancelled;
    int done_bands;
    const vv_render_options *opt;
    float *xray; /* image of line integrals (X-ray objects), or NULL */
    uint64_t footprints, culled, sheets;
} sp_frame;

/* ---------------------------------------------------------------------- */
/* Footprints                                                               */

/* The screen footprint of eye-space covariance (xx, xy, yy) at s pixels per
 * eye unit, its eigenvalues raised to at least ewa (EWA low-pass). */
static void
fp_setup(double xx, double xy, double yy, double s, double ewa, double rho2, sp_fp *fp) {
    double s2 = s * s;
    xx *= s2;
    xy *= s2;
    yy *= s2;
    if (ewa > 0) {
        double m = 0.5 * (xx + yy), dd = sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
        double l1 = m + dd, l2 = m - dd;
        if (l2 < ewa) {
            /* eigenvectors: (xy, l - xx) or the axes when xy = 0 */
            double e1x, e1y;
            if (fabs(xy) > 1e-300) {
                e1x = xy;
                e1y = l1 - xx;
            } else if (xx >= yy) {
                e1x = 1;
                e1y = 0;
            } else {
                e1x = 0;
                e1y = 1;
            }
            double n1 = sqrt(e1x * e1x + e1y * e1y);
            e1x /= n1;
            e1y /= n1;
            const double e2x = -e1y, e2y = e1x;
            l1 = l1 < ewa ? ewa : l1;
            l2 = ewa;
            xx = l1 * e1x * e1x + l2 * e2x * e2x;
            xy = l1 * e1x * e1y + l2 * e2x * e2y;
            yy = l1 * e1y * e1y + l2 * e2y * e2y;
        }
    }
    double det = xx * yy - xy * xy;
    if (!(det > 1e-30))
        det = 1e-30;
    fp->a = (float)(yy / det);
    fp->b = (float)(-xy / det);
    fp->c = (float)(xx / det);
    fp->hx = (float)sqrt(rho2 * xx);
    fp->hy = (float)sqrt(rho2 * yy);
    fp->norm = (float)(1.0 / sqrt(det));
}

/* exp(x) for x in [-40, 0], relative error below 3e-7: x log2(e) =
 * i + f with i an integer and |f| <= 1/2, 2^i from the exponent bits and
 * 2^f by its Taylor polynomial of degree 5. */
static inline float
exp_neg(float x) {
    const float t = x * 1.44269504f + 64.5f;
    const int i = (int)t; /* t > 0: floor */
    const float f = t - (float)i - 0.5f;
    float p = 1.3333558e-3f;
    p = p * f + 9.6181291e-3f;
    p = p * f + 5.5504109e-2f;
    p = p * f + 2.4022651e-1f;
    p = p * f + 6.9314718e-1f;
    p = p * f + 1.0f;
    const int32_t bits = (i - 64 + 127) << 23;
    float sc;
    memcpy(&sc, &bits, sizeof sc);
    return p * sc;
}

#ifdef __SSE2__
/* exp_neg of four lanes, the same arithmetic. */
static inline __m128
exp_neg_ps(__m128 x) {
    const __m128 t = _mm_add_ps(_mm_mul_ps(x, _mm_set1_ps(1.44269504f)), _mm_set1_ps(64.5f));
    const __m128i i = _mm_cvttps_epi32(t);
    const __m128 f = _mm_sub_ps(_mm_sub_ps(t, _mm_cvtepi32_ps(i)), _mm_set1_ps(0.5f));
    __m128 p = _mm_set1_ps(1.3333558e-3f);
    p = _mm_add_ps(_mm_mul_ps(p, f), _mm_set1_ps(9.6181291e-3f));
    p = _mm_add_ps(_mm_mul_ps(p, f), _mm_set1_ps(5.5504109e-2f));
    p = _mm_add_ps(_mm_mul_ps(p, f), _mm_set1_ps(2.4022651e-1f));
    p = _mm_add_ps(_mm_mul_ps(p, f), _mm_set1_ps(6.9314718e-1f));
    p = _mm_add_ps(_mm_mul_ps(p, f), _mm_set1_ps(1.0f));
    const __m128i e = _mm_slli_epi32(_mm_add_epi32(i, _mm_set1_epi32(127 - 64)), 23);
    return _mm_mul_ps(p, _mm_castsi128_ps(e));
}
#endif

/* wrow[x] = w exp(-q / 2), q = (a dx + bq) dx + cq, dx = dx0 + x, for x <
 * len (rounded up to 4: wrow has room). */
static inline void
fp_row_weights(float *wrow, int len, float a, float bq, float cq, float dx0, float w) {
#ifdef __SSE2__
    const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(bq), vc = _mm_set1_ps(cq);
    const __m128 vw = _mm_set1_ps(w), nh = _mm_set1_ps(-0.5f), zero = _mm_setzero_ps();
    __m128 dx = _mm_add_ps(_mm_set1_ps(dx0), _mm_set_ps(3, 2, 1, 0));
    const __m128 four = _mm_set1_ps(4);
    for (int x = 0; x < len; x += 4) {
        __m128 q = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(va, dx), vb), dx), vc);
        q = _mm_max_ps(q, zero);
        _mm_storeu_ps(wrow + x, _mm_mul_ps(vw, exp_neg_ps(_mm_mul_ps(nh, q))));
        dx = _mm_add_ps(dx, four);
    }
#else
    for (int x = 0; x < len; x++) {
        const float dx = dx0 + (float)x;
        float q = (a * dx + bq) * dx + cq;
        q = q < 0 ? 0 : q;
        wrow[x] = w * exp_neg(-0.5f * q);
    }
#endif
}

/* Adds one row of a footprint to the sheet planes: for x < len, with
 * weight w exp(-q / 2), q = (a dx + bq) dx + cq, dx = dx0 + x, plane 0 at
 * p0[x] += weight and plane 1 + ch (stride ps) += weight * val[ch]. Four
 * pixels at a time; lanes past len add 0 (the planes have slack). */
static inline void
fp_row_accum(float *p0, size_t ps, int len, float a, float bq, float cq, float dx0, float w,
             const float *val, const int NV) {
#ifdef __SSE2__
    const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(bq), vc = _mm_set1_ps(cq);
    const __m128 vw = _mm_set1_ps(w), nh = _mm_set1_ps(-0.5f), zero = _mm_setzero_ps();
    __m128 dx = _mm_add_ps(_mm_set1_ps(dx0), _mm_set_ps(3, 2, 1, 0));
    __m128i lane = _mm_set_epi32(3, 2, 1, 0);
    const __m128i vlen = _mm_set1_epi32(len), four_i = _mm_set1_epi32(4);
    const __m128 four = _mm_set1_ps(4);
    __m128 vv[4];
    for (int ch = 0; ch < NV; ch++)
        vv[ch] = _mm_set1_ps(val[ch]);
    for (int x = 0; x < len; x += 4) {
        __m128 q = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(va, dx), vb), dx), vc);
        q = _mm_max_ps(q, zero);
        const __m128 m = _mm_castsi128_ps(_mm_cmplt_epi32(lane, vlen));
        const __m128 wt = _mm_and_ps(m, _mm_mul_ps(vw, exp_neg_ps(_mm_mul_ps(nh, q))));
        float *p = p0 + x;
        _mm_storeu_ps(p, _mm_add_ps(_mm_loadu_ps(p), wt));
        for (int ch = 0; ch < NV; ch++) {
            float *pc = p + (size_t)(ch + 1) * ps;
            _mm_storeu_ps(pc, _mm_add_ps(_mm_loadu_ps(pc), _mm_mul_ps(wt, vv[ch])));
        }
        dx = _mm_add_ps(dx, four);
        lane = _mm_add_epi32(lane, four_i);
    }
#else
    for (int x = 0; x < len; x++) {
        const float dx = dx0 + (float)x;
        float q = (a * dx + bq) * dx + cq;
        q = q < 0 ? 0 : q;
        const float wt = w * exp_neg(-0.5f * q);
        p0[x] += wt;
        for (int ch = 0; ch < NV; ch++)
            p0[x + (size_t)(ch + 1) * ps] += wt * val[ch];
    }
#endif
}

/* Adds footprint fp centred at (cx, cy) (pixel-centre coordinates), weight
 * scale w (times the normalised Gaussian), into the band's sheet planes
 * (rows y0 .. y1 - 1, width W, plane stride ps; plane 0 += weight, plane
 * 1 + ch += weight * val[ch] for ch < NV). Grows the dirty rectangle by the
 * footprint's bounding box. */
static inline void
fp_splat_nv(float *buf, size_t ps, int W, int y0, int y1, float rho2, float cx, float cy,
            const sp_fp *fp, float w, const float *val, const int NV, int rect[4]) {
    int ya = (int)ceilf(cy - fp->hy), yb = (int)floorf(cy + fp->hy);
    ya = ya < y0 ? y0 : ya;
    yb = yb > y1 - 1 ? y1 - 1 : yb;
    if (ya > yb)
        return;
    int bxa = (int)ceilf(cx - fp->hx), bxb = (int)floorf(cx + fp->hx);
    bxa = bxa < 0 ? 0 : bxa;
    bxb = bxb > W - 1 ? W - 1 : bxb;
    if (bxa > bxb)
        return;
    rect[0] = bxa < rect[0] ? bxa : rect[0];
    rect[1] = bxb > rect[1] ? bxb : rect[1];
    rect[2] = ya < rect[2] ? ya : rect[2];
    rect[3] = yb > rect[3] ? yb : rect[3];
    const float ia = 1.0f / fp->a, a = fp->a, bb = fp->b * fp->b;
    for (int y = ya; y <= yb; y++) {
        const float dy = (float)y - cy;
        const float disc = bb * dy * dy - a * (fp->c * dy * dy - rho2);
        if (disc <= 0)
            continue;
        const float half = sqrtf(disc) * ia, xm = cx - fp->b * dy * ia;
        int xa = (int)ceilf(xm - half), xb = (int)floorf(xm + half);
        xa = xa < 0 ? 0 : xa;
        xb = xb > W - 1 ? W - 1 : xb;
        if (xa > xb)
            continue;
        fp_row_accum(buf + (size_t)(y - y0) * (size_t)W + (size_t)xa, ps, xb - xa + 1, a,
                     2 * fp->b * dy, fp->c * dy * dy, (float)xa - cx, w, val, NV);
    }
}

/* The sum over the whole pixel grid (unclipped) of exp(-q / 2) for
 * footprint fp centred at (cx, cy): X-ray footprints are divided by it so
 * that each one's pixels sum exactly to its kernel's integral whatever its
 * size and sub-pixel position (energy conservation). */
static double
fp_discrete_sum(float *wrow, int W, float rho2, float cx, float cy, const sp_fp *fp) {
    const int ya = (int)ceilf(cy - fp->hy), yb = (int)floorf(cy + fp->hy);
    const float ia = 1.0f / fp->a, a = fp->a;
    double sum = 0;
    for (int y = ya; y <= yb; y++) {
        const float dy = (float)y - cy;
        const float disc = fp->b * fp->b * dy * dy - a * (fp->c * dy * dy - rho2);
        if (disc <= 0)
            continue;
        const float half = sqrtf(disc) * ia, xm = cx - fp->b * dy * ia;
        const int xa = (int)ceilf(xm - half), xb = (int)floorf(xm + half);
        const float bq = 2 * fp->b * dy, cq = fp->c * dy * dy;
        for (int x0 = xa; x0 <= xb; x0 += W) {
            const int len = xb - x0 + 1 < W ? xb - x0 + 1 : W;
            fp_row_weights(wrow, len, a, bq, cq, (float)x0 - cx, 1.0f);
            float rs = 0;
            for (int x = 0; x < len; x++)
                rs += wrow[x];
            sum += rs;
        }
    }
    return sum;
}

static void
fp_splat1(float *buf, size_t ps, int W, int y0, int y1, float rho2, float cx, float cy,
          const sp_fp *fp, float w, const float *val, int rect[4]) {
    fp_splat_nv(buf, ps, W, y0, y1, rho2, cx, cy, fp, w, val, 1, rect);
}

static void
fp_splat4(float *buf, size_t ps, int W, int y0, int y1, float rho2, float cx, float cy,
          const sp_fp *fp, float w, const float *val, int rect[4]) {
    fp_splat_nv(buf, ps, W, y0, y1, rho2, cx, cy, fp, w, val, 4, rect);
}

/* ---------------------------------------------------------------------- */
/* Per-object set-up                                                        */

static inline double
lin4(const double r[4], double i, double j, double k) {
    return r[0] * i + r[1] * j + r[2] * k + r[3];
}

static inline void
unpack(uint64_t p, int *i, int *j, int *k) {
    *i = (int)(p & 0x1FFFFF);
    *j = (int)((p >> 21) & 0x1FFFFF);
    *k = (int)(p >> 42);
}

static double
norm_cdf(double x) {
    return 0.5 * erfc(-x / sqrt(2.0));
}

/* Eye-space maps and kernel geometry of one object for this view. */
static void
object_geometry(sp_frame *fr, sp_obj *ob) {
    const sp_state *st = fr->st;
    const double sig = st->sigma;
    double A[3][3];
    const vv_vec3 ax[3] = {fr->r, fr->u, fr->f};
    double *rows[3] = {ob->ex, ob->ey, ob->ez};
    for (int a = 0; a < 3; a++) {
        const double e[3] = {ax[a].x, ax[a].y, ax[a].z};
        for (int cc = 0; cc < 4; cc++) {
            double v = 0;
            for (int q = 0; q < 3; q++)
                v += e[q] * ob->i2w[q][cc];
            rows[a][cc] = v;
        }
        rows[a][3] -= e[0] * fr->eye.x + e[1] * fr->eye.y + e[2] * fr->eye.z;
        for (int cc = 0; cc < 3; cc++)
            A[a][cc] = rows[a][cc];
    }
    double S[3][3];
    for (int p = 0; p < 3; p++)
        for (int q = 0; q < 3; q++)
            S[p][q] = sig * sig * (A[p][0] * A[q][0] + A[p][1] * A[q][1] + A[p][2] * A[q][2]);
    const double det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                       A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                       A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    ob->vol_det = fabs(det);
    const double rho = sqrt(fr->rho2);
    double cmax = 0;
    for (int cc = 0; cc < 3; cc++) {
        double l = sqrt(A[0][cc] * A[0][cc] + A[1][cc] * A[1][cc] + A[2][cc] * A[2][cc]);
        cmax = l > cmax ? l : cmax;
    }
    ob->rworld = st->radius * cmax * 1.7320508 + 1e-9;
    const double szz = S[2][2];
    ob->rz = rho * sqrt(szz);
    if (st->axis || ob->mode == VV_MODE_XRAY) {
        /* whole footprints: the marginal covariance */
        ob->cxx = S[0][0];
        ob->cxy = S[0][1];
        ob->cyy = S[1][1];
        ob->bx = ob->by = 0;
        ob->ns = 1;
        return;
    }
    ob->bx = S[0][2] / szz;
    ob->by = S[1][2] / szz;
    /* the conditional covariance, plus the spread of the centre shift over a
     * slab of thickness dts (uniform: dts^2 / 12) */
    const double v12 = fr->dts * fr->dts / 12.0;
    ob->cxx = S[0][0] - S[0][2] * S[0][2] / szz + ob->bx * ob->bx * v12;
    ob->cxy = S[0][1] - S[0][2] * S[1][2] / szz + ob->bx * ob->by * v12;
    ob->cyy = S[1][1] - S[1][2] * S[1][2] / szz + ob->by * ob->by * v12;
    /* slab integrals of the truncated 1-D marginal N(0, szz) on |s| <= rz */
    const double sz = sqrt(szz), h = 0.5 * fr->dts;
    const double dmax = ob->rz + h;
    ob->z_lo = -dmax;
    ob->z_scale = (SP_Z_LUT - 1) / (2 * dmax);
    const double tot = 2 * norm_cdf(rho) - 1;
    for (int t = 0; t < SP_Z_LUT; t++) {
        const double d = -dmax + t / ob->z_scale;
        double lo = d - h, hi = d + h;
        lo = lo < -ob->rz ? -ob->rz : lo;
        hi = hi > ob->rz ? ob->rz : hi;
        double m = 0, mean = 0;
        if (hi > lo) {
            m = norm_cdf(hi / sz) - norm_cdf(lo / sz);
            const double plo = exp(-0.5 * lo * lo / szz), phi = exp(-0.5 * hi * hi / szz);
            /* int s p(s) ds over [lo, hi] for the N(0, szz) density */
            const double first = sz * (plo - phi) / sqrt(2 * VV_PI);
            mean = m > 1e-12 ? first / m : 0.5 * (lo + hi);
        }
        ob->wz[t] = (float)(m / tot);
        ob->dz[t] = (float)mean;
    }
    ob->ns = (int)ceil(2 * dmax / fr->dts) + 2;
}

/* Pixel position of eye-space (X, Y) at depth z. */
static inline void
to_pixel(const sp_frame *fr, double X, double Y, double z, double *px, double *py) {
    if (fr->persp) {
        const double s = 1.0 / (z * fr->pix);
        *px = X * s - fr->pcx;
        *py = Y * s - fr->pcy;
    } else {
        *px = X / fr->pix;
        *py = Y / fr->pix;
    }
}

/* Pixels per eye unit at depth z. */
static inline double
pix_scale(const sp_frame *fr, double z) {
    return fr->persp ? 1.0 / (z * fr->pix) : 1.0 / fr->pix;
}

/* ---------------------------------------------------------------------- */
/* Voxel lists                                                              */

static uint64_t
hash_bytes(uint64_t h, const void *p, size_t n) {
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 1099511628211ULL;
    }
    return h;
}

/* The object's voxel list for octant @p oct (bit a set: index axis a runs
 * backwards, from the far side), from the cache or built. */
static vv_status
get_list(sp_state *st, sp_obj *ob, int oct, int *built) {
    const vv_vcache *c = ob->c;
    const int comp = ob->mode == VV_MODE_COMPOSITE;
    const int skip = st->skipping && comp;
    const int pre = skip && ob->pre_cls;
    /* the kernel's reach in voxels (the footprint's truncation is a
     * cylinder: up to sqrt 2 radius from the centre) */
    const int reach = (int)ceil(1.4142136 * st->radius);
    uint64_t h = 1469598103934665603ULL;
    h = hash_bytes(h, &skip, sizeof skip);
    h = hash_bytes(h, &ob->pre_cls, sizeof ob->pre_cls);
    h = hash_bytes(h, &reach, sizeof reach);
    if (skip)
        for (int i = 0; i < VV_VC_LUT; i++) {
            const int vis = ob->tab.lut[4 * i] > 0;
            h = hash_bytes(h, &vis, sizeof vis);
        }
    st->clock++;
    for (int l = 0; l < SP_LISTS; l++) {
        sp_list *L = &st->lists[l];
        if (L->vol == c->vol && L->modified == c->vol->modified && L->hash == h &&
            L->octant == oct) {
            L->last_used = st->clock;
            ob->list = L;
            return VV_OK;
        }
    }
    int slot = 0;
    for (int l = 1; l < SP_LISTS; l++)
        if (st->lists[l].last_used < st->lists[slot].last_used)
            slot = l;
    sp_list *L = &st->lists[slot];
    vv_volume_free(L->vol);
    free(L->vox);
    memset(L, 0, sizeof *L);
    const int nx = c->nx, ny = c->ny, nz = c->nz;
    const size_t nvox = c->sz * (size_t)nz;
    /* empty-voxel skipping: a voxel is needed when the values within
     * 2 reach of it (every sample it reaches, and every voxel those samples
     * blend) span a visible table entry; pre-classified, when its own value
     * is visible */
    uint8_t *need = NULL;
    if (skip && !pre) {
        int *nzc = malloc(sizeof(int) * (VV_VC_LUT + 1));
        uint16_t *mn = malloc(nvox * sizeof *mn), *mx = malloc(nvox * sizeof *mx);
        need = malloc(nvox);
        if (!nzc || !mn || !mx || !need) {
            free(nzc);
            free(mn);
            free(mx);
            free(need);
            return vv_error_set(VV_ERR_NOMEM, "out of memory for the voxel list of %zu voxels",
                                nvox);
        }
        nzc[0] = 0;
        for (int i = 0; i < VV_VC_LUT; i++)
            nzc[i + 1] = nzc[i] + (ob->tab.lut[4 * i] > 0);
#pragma omp parallel for schedule(static)
        for (size_t v = 0; v < nvox; v++)
            mn[v] = mx[v] = (uint16_t)vv_vtables_index(&ob->tab, vv_vcache_value(c, v));
        /* separable running min / max over 2 reach + 1 voxels per axis */
        const int R = 2 * reach;
        const int len[3] = {nx, ny, nz};
        const size_t stride[3] = {1, c->sy, c->sz};
        for (int a = 0; a < 3; a++) {
            const int L_ = len[a];
            const size_t st_ = stride[a];
            const size_t lines = nvox / (size_t)L_;
#pragma omp parallel
            {
                uint16_t *bmn = malloc((size_t)L_ * sizeof *bmn), *bmx = malloc((size_t)L_ * 2);
#pragma omp for schedule(static)
                for (size_t line = 0; line < lines; line++) {
                    if (!bmn || !bmx)
                        continue;
                    /* the line's first voxel: line enumerates the other two axes */
                    size_t base;
                    if (a == 0)
                        base = line * c->sy;
                    else if (a == 1)
                        base = (line / (size_t)nx) * c->sz + line % (size_t)nx;
                    else
                        base = line;
                    for (int t = 0; t < L_; t++) {
                        bmn[t] = mn[base + (size_t)t * st_];
                        bmx[t] = mx[base + (size_t)t * st_];
                    }
                    for (int t = 0; t < L_; t++) {
                        const int t0 = t - R < 0 ? 0 : t - R, t1 = t + R > L_ - 1 ? L_ - 1 : t + R;
                        uint16_t lo = bmn[t0], hi = bmx[t0];
                        for (int u = t0 + 1; u <= t1; u++) {
                            lo = bmn[u] < lo ? bmn[u] : lo;
                            hi = bmx[u] > hi ? bmx[u] : hi;
                        }
                        mn[base + (size_t)t * st_] = lo;
                        mx[base + (size_t)t * st_] = hi;
                    }
                }
                free(bmn);
                free(bmx);
            }
        }
#pragma omp parallel for schedule(static)
        for (size_t v = 0; v < nvox; v++)
            need[v] = nzc[mx[v] + 1] - nzc[mn[v]] > 0;
        free(nzc);
        free(mn);
        free(mx);
    }
    /* subvolumes (of VV_VC_BLOCK cells) within reach of a visible one */
    const int bdil = 1 + (reach + 1 + VV_VC_BLOCK - 1) / VV_VC_BLOCK;
    size_t n = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (int kk = 0; kk < nz; kk++) {
            const int k = oct & 4 ? nz - 1 - kk : kk;
            for (int jj = 0; jj < ny; jj++) {
                const int j = oct & 2 ? ny - 1 - jj : jj;
                const size_t row = (size_t)k * c->sz + (size_t)j * c->sy;
                for (int ii = 0; ii < nx; ii++) {
                    const int i = oct & 1 ? nx - 1 - ii : ii;
                    if (need) {
                        /* the subvolume grid first: far from every visible
                         * subvolume, no sample the voxel reaches can show */
                        int bi = i / VV_VC_BLOCK, bj = j / VV_VC_BLOCK, bk = k / VV_VC_BLOCK;
                        bi = bi >= c->bx ? c->bx - 1 : bi;
                        bj = bj >= c->by ? c->by - 1 : bj;
                        bk = bk >= c->bz ? c->bz - 1 : bk;
                        const size_t b =
                            ((size_t)bk * (size_t)c->by + (size_t)bj) * (size_t)c->bx + (size_t)bi;
                        if (ob->tab.bdist[b] > bdil || !need[row + (size_t)i])
                            continue;
                    }
                    if (pre &&
                        ob->tab.lut[4 * (int)vv_vtables_index(
                                            &ob->tab, vv_vcache_value(c, row + (size_t)i))] <= 0)
                        continue;
                    if (pass == 1)
                        L->vox[n] = (uint64_t)i | (uint64_t)j << 21 | (uint64_t)k << 42;
                    n++;
                }
            }
        }
        if (pass == 0) {
            L->vox = malloc((n ? n : 1) * sizeof *L->vox);
            if (!L->vox) {
                free(need);
                return vv_error_set(VV_ERR_NOMEM, "out of memory for a list of %zu voxels", n);
            }
            n = 0;
        }
    }
    free(need);
    L->n = n;
    L->vol = vv_volume_ref(c->vol);
    L->modified = c->vol->modified;
    L->hash = h;
    L->octant = oct;
    L->last_used = st->clock;
    ob->list = L;
    *built += 1;
    return VV_OK;
}

/* The sheet range [k0, k1] a voxel at depth zc touches (k1 < k0: none). */
static inline void
voxel_sheets(const sp_frame *fr, const sp_obj *ob, double zc, int *k0, int *k1) {
    if (fr->st->axis) {
        *k0 = *k1 = 0; /* set by the caller */
        return;
    }
    if (ob->mode == VV_MODE_XRAY) {
        *k0 = *k1 = 0;
        if (fr->persp && zc - ob->rz < fr->znear)
            *k1 = -1;
        return;
    }
    double a = (zc - ob->rz) / fr->dts - 0.5, b = (zc + ob->rz) / fr->dts + 0.5;
    const double kn = ceil(fr->znear / fr->dts);
    a = ceil(a);
    a = a < kn ? kn : a;
    b = floor(b);
    if (b - a > SP_MAX_SHEETS || a > 1e9 || b < -1e9) {
        *k0 = 1;
        *k1 = 0;
        return;
    }
    *k0 = (int)a;
    *k1 = (int)b;
}

/* The pixel rows a voxel's footprints can reach. */
static void
voxel_rows(const sp_frame *fr, const sp_obj *ob, double X, double Y, double zc, const sp_fp *fpo,
           double *ylo, double *yhi) {
    const double shift = fabs(ob->by) * (ob->rz + fr->dts);
    if (!fr->persp) {
        const double cy = Y / fr->pix, e = shift / fr->pix + fpo->hy + 1;
        *ylo = cy - e;
        *yhi = cy + e;
        return;
    }
    double zn = zc - ob->rz - fr->dts, zf = zc + ob->rz + fr->dts;
    zn = zn < fr->znear ? fr->znear : zn;
    zf = zf < zn ? zn : zf;
    double lo = INFINITY, hi = -INFINITY;
    const double zs[2] = {zn, zf}, ys[2] = {Y - shift, Y + shift};
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            double px, py;
            to_pixel(fr, X, ys[b], zs[a], &px, &py);
            lo = py < lo ? py : lo;
            hi = py > hi ? py : hi;
        }
    /* the footprint is largest at the near depth */
    const double s = pix_scale(fr, zn);
    const double hy = sqrt(fr->rho2 * ob->cyy) * s + sqrt(fr->rho2 * fr->st->ewa_var) + 1;
    *ylo = lo - hy;
    *yhi = hi + hy;
}

/* The footprint of an object at depth z (the same for all its voxels there). */
static void
object_fp(const sp_frame *fr, const sp_obj *ob, double z, sp_fp *fp) {
    fp_setup(ob->cxx, ob->cxy, ob->cyy, pix_scale(fr, z), fr->st->ewa_var, fr->rho2, fp);
}

/* A label volume's table entry @p e for value @p v: its opacity, the colour
 * of the label v rounds to (premultiplied, into @p buf). A voxel holds its
 * label exactly (pre-classification); a reconstructed value between two
 * labels takes the nearer (post-classification). */
static inline const float *
label_entry(const float *e, float v, float buf[4]) {
    if (!(e[0] > 0))
        return e;
    const double r = floor((double)v + 0.5);
    const vv_vec3 col = vv_label_color(r >= 1 && r < 4294967296.0 ? (uint32_t)r : 0);
    buf[0] = e[0];
    buf[1] = e[0] * (float)col.x;
    buf[2] = e[0] * (float)col.y;
    buf[3] = e[0] * (float)col.z;
    return buf;
}

/* Pre-classification of one voxel: opacity for the sheet spacing and shaded
 * colour times opacity. */
static void
preclassify(const sp_frame *fr, const sp_obj *ob, int i, int j, int k, float out[4]) {
    const vv_vcache *c = ob->c;
    const size_t idx = (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
    const float val = vv_vcache_value(c, idx);
    const float *e = ob->tab.lut + 4 * (int)vv_vtables_index(&ob->tab, val);
    float lab[4];
    if (ob->labels)
        e = label_entry(e, val, lab);
    out[0] = e[0];
    if (!ob->shading || e[0] <= 0) {
        out[1] = e[1];
        out[2] = e[2];
        out[3] = e[3];
        return;
    }
    float g[3] = {0, 0, 0};
    if (c->nrm) {
        const vv_v4f n = vv_vcache_normal(c, idx);
        g[0] = n[0];
        g[1] = n[1];
        g[2] = n[2];
    } else {
        const float p[3] = {(float)i, (float)j, (float)k};
        vv_vcache_gradient(c, p, g);
    }
    float pw[3];
    for (int a = 0; a < 3; a++)
        pw[a] = (float)(ob->i2w[a][0] * i + ob->i2w[a][1] * j + ob->i2w[a][2] * k + ob->i2w[a][3]);
    float v[3] = {(float)-fr->f.x, (float)-fr->f.y, (float)-fr->f.z};
    if (fr->persp) {
        /* towards the eye */
        const float d0 = (float)fr->view->eye.x - pw[0], d1 = (float)fr->view->eye.y - pw[1],
                    d2 = (float)fr->view->eye.z - pw[2];
        const float l = sqrtf(d0 * d0 + d1 * d1 + d2 * d2);
        if (l > 0) {
            v[0] = d0 / l;
            v[1] = d1 / l;
            v[2] = d2 / l;
        }
    }
    vv_vshade(&ob->sh, fr->lights, fr->n_lights, g, pw, v, e + 1, e[0], NULL, NULL, out + 1);
}

/* Buckets the object's list by first sheet and distributes it over the
 * image bands. */
static vv_status
object_buckets(sp_frame *fr, sp_obj *ob) {
    const sp_list *L = ob->list;
    const size_t n = L->n;
    int *k0s = malloc((n ? n : 1) * sizeof *k0s);
    if (!k0s)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    int kmin = INT32_MAX, kmax = INT32_MIN;
    /* axis-aligned variant: the sheet is the slice along the major axis */
    for (size_t v = 0; v < n; v++) {
        int i, j, k;
        unpack(L->vox[v], &i, &j, &k);
        const double zc = lin4(ob->ez, i, j, k);
        int a, b;
        voxel_sheets(fr, ob, zc, &a, &b);
        if (fr->st->axis) {
            const int idx[3] = {i, j, k};
            const int nax = ob->axis_a == 0 ? ob->c->nx : ob->axis_a == 1 ? ob->c->ny : ob->c->nz;
            a = b = ob->axis_sign > 0 ? idx[ob->axis_a] : nax - 1 - idx[ob->axis_a];
            if (fr->persp && zc - ob->rz < fr->znear)
                b = a - 1;
        }
        for (int p = 0; p < ob->n_planes && a <= b; p++) {
            vv_vec3 pw = {lin4(ob->i2w[0], i, j, k), lin4(ob->i2w[1], i, j, k),
                          lin4(ob->i2w[2], i, j, k)};
            if (vv_plane_distance(ob->planes[p], pw) < -ob->rworld)
                b = a - 1;
        }
        if (a > b) {
            k0s[v] = INT32_MIN;
            continue;
        }
        k0s[v] = a;
        kmin = a < kmin ? a : kmin;
        kmax = b > kmax ? b : kmax;
    }
    if (kmin > kmax) {
        ob->nsheets = 0;
        ob->kbase = 0;
        free(k0s);
        return VV_OK;
    }
    if ((double)kmax - kmin + 1 > SP_MAX_SHEETS) {
        free(k0s);
        return vv_error_set(VV_ERR_LIMIT,
                            "object '%s': %d sheets (at most %d): the sheet spacing is too small "
                            "for the view",
                            ob->obj->name, kmax - kmin + 1, SP_MAX_SHEETS);
    }
    ob->kbase = kmin;
    ob->nsheets = kmax - kmin + 1;
    const int ns = ob->nsheets;
    const int nbands = fr->n_bands;
    ob->start = calloc((size_t)ns + 1, sizeof *ob->start);
    ob->bstart = calloc((size_t)nbands, sizeof *ob->bstart);
    ob->bidx = calloc((size_t)nbands, sizeof *ob->bidx);
    if (!ob->start || !ob->bstart || !ob->bidx) {
        free(k0s);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    size_t m = 0;
    for (size_t v = 0; v < n; v++)
        if (k0s[v] != INT32_MIN) {
            ob->start[k0s[v] - kmin + 1]++;
            m++;
        }
    for (int s = 0; s < ns; s++)
        ob->start[s + 1] += ob->start[s];
    ob->sorted = malloc((m ? m : 1) * sizeof *ob->sorted);
    int *fill = malloc(((size_t)ns + 1) * sizeof *fill);
    int16_t(*brange)[2] = malloc((m ? m : 1) * sizeof *brange);
    if (ob->pre_cls && ob->is_comp)
        ob->pre = malloc((m ? m : 1) * sizeof *ob->pre);
    if (!ob->sorted || !fill || !brange || (ob->pre_cls && ob->is_comp && !ob->pre)) {
        free(k0s);
        free(fill);
        free(brange);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %zu splats", m);
    }
    memcpy(fill, ob->start, ((size_t)ns + 1) * sizeof *fill);
    for (size_t v = 0; v < n; v++)
        if (k0s[v] != INT32_MIN)
            ob->sorted[fill[k0s[v] - kmin]++] = L->vox[v];
    free(k0s);
    /* the voxels' values (and gradients) in splatting order: read once per
     * slice, they are then a stream instead of scattered loads */
    if (!ob->pre) {
        const int shaded = ob->shading && ob->is_comp;
        if (shaded)
            ob->v4 = malloc((m ? m : 1) * sizeof *ob->v4);
        else
            ob->v1 = malloc((m ? m : 1) * sizeof *ob->v1);
        if (!ob->v4 && !ob->v1) {
            free(fill);
            free(brange);
            return vv_error_set(VV_ERR_NOMEM, "out of memory for %zu splats", m);
        }
        const vv_vcache *c = ob->c;
#pragma omp parallel for schedule(static)
        for (size_t v = 0; v < m; v++) {
            int i, j, k;
            unpack(ob->sorted[v], &i, &j, &k);
            const size_t idx = (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
            const float val = vv_vcache_value(c, idx);
            if (!shaded) {
                ob->v1[v] = val;
                continue;
            }
            ob->v4[v][0] = val;
            if (c->nrm) {
                const vv_v4f g = vv_vcache_normal(c, idx);
                ob->v4[v][1] = g[0];
                ob->v4[v][2] = g[1];
                ob->v4[v][3] = g[2];
            } else {
                const float p[3] = {(float)i, (float)j, (float)k};
                vv_vcache_gradient(c, p, &ob->v4[v][1]);
            }
        }
    }
    /* band of every voxel, then per band a counting sort by sheet */
    int *bcount = calloc((size_t)nbands * ((size_t)ns + 1), sizeof *bcount);
    if (!bcount) {
        free(fill);
        free(brange);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    sp_fp fpo;
    object_fp(fr, ob, fr->persp ? 1.0 : 1.0, &fpo);
    int s = 0;
    for (size_t v = 0; v < m; v++) {
        while ((size_t)ob->start[s + 1] <= v)
            s++;
        int i, j, k;
        unpack(ob->sorted[v], &i, &j, &k);
        const double X = lin4(ob->ex, i, j, k), Y = lin4(ob->ey, i, j, k),
                     zc = lin4(ob->ez, i, j, k);
        double ylo, yhi;
        voxel_rows(fr, ob, X, Y, zc, &fpo, &ylo, &yhi);
        if (fr->st->axis && fr->persp) {
            /* whole footprints scale with the voxel's own depth */
            const double sc = pix_scale(fr, zc > fr->znear ? zc : fr->znear);
            const double e = sqrt(fr->rho2 * ob->cyy) * sc + 2;
            double px, py;
            to_pixel(fr, X, Y, zc, &px, &py);
            ylo = py - e;
            yhi = py + e;
        }
        int b0 = (int)floor(ylo / fr->band_h), b1 = (int)floor(yhi / fr->band_h);
        b0 = b0 < 0 ? 0 : b0;
        b1 = b1 > nbands - 1 ? nbands - 1 : b1;
        if (!(ylo < fr->view->height && yhi >= 0) || b0 > b1) {
            brange[v][0] = 1;
            brange[v][1] = 0;
            continue;
        }
        brange[v][0] = (int16_t)b0;
        brange[v][1] = (int16_t)b1;
        for (int b = b0; b <= b1; b++)
            bcount[(size_t)b * ((size_t)ns + 1) + (size_t)s + 1]++;
        if (ob->pre)
            preclassify(fr, ob, i, j, k, ob->pre[v]);
    }
    vv_status st = VV_OK;
    for (int b = 0; b < nbands && st == VV_OK; b++) {
        int *bc = bcount + (size_t)b * ((size_t)ns + 1);
        for (int q = 0; q < ns; q++)
            bc[q + 1] += bc[q];
        ob->bstart[b] = malloc(((size_t)ns + 1) * sizeof(int));
        ob->bidx[b] = malloc(((size_t)bc[ns] ? (size_t)bc[ns] : 1) * sizeof(uint32_t));
        if (!ob->bstart[b] || !ob->bidx[b])
            st = vv_error_set(VV_ERR_NOMEM, "out of memory");
        else
            memcpy(ob->bstart[b], bc, ((size_t)ns + 1) * sizeof(int));
    }
    if (st == VV_OK) {
        /* reuse bcount as fill pointers */
        s = 0;
        for (size_t v = 0; v < m; v++) {
            while ((size_t)ob->start[s + 1] <= v)
                s++;
            for (int b = brange[v][0]; b <= brange[v][1]; b++) {
                int *bc = bcount + (size_t)b * ((size_t)ns + 1);
                ob->bidx[b][bc[s]++] = (uint32_t)v;
            }
        }
    }
    free(bcount);
    free(fill);
    free(brange);
    return st;
}

static void
object_free(sp_obj *ob, int nbands) {
    if (ob->owns_tables)
        vv_vtables_free(&ob->tab);
    free(ob->sorted);
    free(ob->pre);
    free(ob->v4);
    free(ob->v1);
    free(ob->start);
    for (int b = 0; ob->bstart && b < nbands; b++)
        free(ob->bstart[b]);
    for (int b = 0; ob->bidx && b < nbands; b++)
        free(ob->bidx[b]);
    free(ob->bstart);
    free(ob->bidx);
}

/* ---------------------------------------------------------------------- */
/* Bands                                                                    */

/* Per-pixel data of one band. */
typedef struct sp_band {
    int y0, y1, W, n;
    float *buf;         /* SP_CH planes of n */
    float *wrow;        /* one row of footprint weights */
    size_t ps;          /* plane stride: n plus slack for 4-wide rows */
    float *C, *A, *D;   /* colour (3 a pixel), opacity, depth (ray parameter) */
    float *P, *PA, *PD; /* projections: colour (3), opacity, depth */
    int *k0, *k1;       /* per object (n_obj x n): sheets inside the pixel's ray */
    int *kend;          /* the last sheet of any composite object on the pixel's ray */
    float *cosv;        /* forward . ray direction */
    float *vdir;        /* towards the eye, 3 a pixel */
    float *rdir;        /* ray direction (3) and origin (3) a pixel, for world points */
    uint8_t *done;      /* pixel needs nothing more (occlusion map) */
    uint16_t *tcount;   /* finished pixels per tile */
    uint16_t *tcap;     /* pixels per tile */
    int tw, th;         /* tiles across, down */
} sp_band;

static inline void
mark_done(sp_band *bd, int x, int yl) {
    const int pi = yl * bd->W + x;
    if (bd->done[pi])
        return;
    bd->done[pi] = 1;
    bd->tcount[(yl / SP_TILE) * bd->tw + x / SP_TILE]++;
}

/* The box [x0, x1] x [y0, y1] (pixels) covers only finished tiles. */
static inline int
occluded_box(const sp_band *bd, double x0, double x1, double y0, double y1) {
    x0 = x0 < -1 ? -1 : x0;
    y0 = y0 < -1 ? -1 : y0;
    x1 = x1 > bd->W ? bd->W : x1;
    y1 = y1 > bd->y1 ? bd->y1 : y1;
    int xa = (int)x0, xb = (int)x1 + 1;
    int ya = (int)y0 - bd->y0, yb = (int)y1 + 1 - bd->y0;
    xa = xa < 0 ? 0 : xa;
    xb = xb > bd->W - 1 ? bd->W - 1 : xb;
    ya = ya < 0 ? 0 : ya;
    yb = yb > bd->y1 - bd->y0 - 1 ? bd->y1 - bd->y0 - 1 : yb;
    if (xa > xb || ya > yb)
        return 1;
    for (int ty = ya / SP_TILE; ty <= yb / SP_TILE; ty++)
        for (int tx = xa / SP_TILE; tx <= xb / SP_TILE; tx++)
            if (bd->tcount[ty * bd->tw + tx] < bd->tcap[ty * bd->tw + tx])
                return 0;
    return 1;
}

static void
band_free(sp_band *bd) {
    free(bd->buf);
    free(bd->C);
    free(bd->k0);
    free(bd->cosv);
    free(bd->done);
    free(bd->tcount);
}

static vv_status
band_init(const sp_frame *fr, sp_band *bd, int band) {
    memset(bd, 0, sizeof *bd);
    bd->W = fr->view->width;
    bd->y0 = band * fr->band_h;
    bd->y1 = bd->y0 + fr->band_h < fr->view->height ? bd->y0 + fr->band_h : fr->view->height;
    const int n = bd->n = bd->W * (bd->y1 - bd->y0);
    const int no = fr->n_obj ? fr->n_obj : 1;
    bd->tw = (bd->W + SP_TILE - 1) / SP_TILE;
    bd->th = (bd->y1 - bd->y0 + SP_TILE - 1) / SP_TILE;
    bd->ps = (size_t)n + 8;
    bd->buf = calloc(bd->ps * SP_CH + (size_t)bd->W + 8, sizeof(float));
    bd->wrow = bd->buf ? bd->buf + bd->ps * SP_CH : NULL;
    bd->C = malloc((size_t)n * 10 * sizeof(float));
    bd->k0 = malloc((size_t)n * (2 * (size_t)no + 1) * sizeof(int));
    bd->cosv = malloc((size_t)n * 10 * sizeof(float));
    bd->done = calloc((size_t)n, 1);
    bd->tcount = calloc((size_t)bd->tw * (size_t)bd->th * 2, sizeof(uint16_t));
    if (!bd->buf || !bd->C || !bd->k0 || !bd->cosv || !bd->done || !bd->tcount) {
        band_free(bd);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for an image band");
    }
    bd->A = bd->C + 3 * (size_t)n;
    bd->D = bd->A + n;
    bd->P = bd->D + n;
    bd->PA = bd->P + 3 * (size_t)n;
    bd->PD = bd->PA + n;
    bd->k1 = bd->k0 + (size_t)n * (size_t)no;
    bd->kend = bd->k1 + (size_t)n * (size_t)no;
    bd->vdir = bd->cosv + n;
    bd->rdir = bd->vdir + 3 * (size_t)n;
    bd->tcap = bd->tcount + (size_t)bd->tw * (size_t)bd->th;
    for (int ty = 0; ty < bd->th; ty++)
        for (int tx = 0; tx < bd->tw; tx++) {
            const int w = bd->W - tx * SP_TILE < SP_TILE ? bd->W - tx * SP_TILE : SP_TILE;
            const int h =
                bd->y1 - bd->y0 - ty * SP_TILE < SP_TILE ? bd->y1 - bd->y0 - ty * SP_TILE : SP_TILE;
            bd->tcap[ty * bd->tw + tx] = (uint16_t)(w * h);
        }
    for (int i = 0; i < n; i++) {
        bd->C[3 * i] = bd->C[3 * i + 1] = bd->C[3 * i + 2] = 0;
        bd->A[i] = 0;
        bd->D[i] = INFINITY;
        bd->P[3 * i] = bd->P[3 * i + 1] = bd->P[3 * i + 2] = 0;
        bd->PA[i] = 0;
        bd->PD[i] = INFINITY;
    }
    /* rays, as the ray caster makes them */
    for (int yl = 0; yl < bd->y1 - bd->y0; yl++)
        for (int x = 0; x < bd->W; x++) {
            const int pi = yl * bd->W + x;
            const double fx = x, fy = bd->y0 + yl;
            vv_ray wr;
            wr.origin.x = fr->o00.x + fx * fr->ox.x + fy * fr->oy.x;
            wr.origin.y = fr->o00.y + fx * fr->ox.y + fy * fr->oy.y;
            wr.origin.z = fr->o00.z + fx * fr->ox.z + fy * fr->oy.z;
            double dx = fr->d00.x + fx * fr->dx.x + fy * fr->dy.x;
            double dy = fr->d00.y + fx * fr->dx.y + fy * fr->dy.y;
            double dz = fr->d00.z + fx * fr->dx.z + fy * fr->dy.z;
            const double inv = 1.0 / sqrt(dx * dx + dy * dy + dz * dz);
            wr.dir.x = dx * inv;
            wr.dir.y = dy * inv;
            wr.dir.z = dz * inv;
            const double cs = vv_vec3_dot(wr.dir, fr->f);
            bd->cosv[pi] = (float)cs;
            bd->vdir[3 * pi] = (float)-wr.dir.x;
            bd->vdir[3 * pi + 1] = (float)-wr.dir.y;
            bd->vdir[3 * pi + 2] = (float)-wr.dir.z;
            float *rd = bd->rdir + 6 * (size_t)pi;
            rd[0] = (float)wr.dir.x;
            rd[1] = (float)wr.dir.y;
            rd[2] = (float)wr.dir.z;
            rd[3] = (float)wr.origin.x;
            rd[4] = (float)wr.origin.y;
            rd[5] = (float)wr.origin.z;
            int any = 0, kend = INT32_MIN;
            for (int o = 0; o < fr->n_obj; o++) {
                const sp_obj *ob = &fr->objs[o];
                vv_vray r;
                int k0 = 1, k1 = 0;
                if (vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, &wr, 0, INFINITY,
                                  &r)) {
                    const double z0 = r.t0 * cs, z1 = r.t1 * cs;
                    double a = ceil(z0 / fr->dts), b = floor(z1 / fr->dts);
                    const double kn = ceil(fr->znear / fr->dts);
                    if (a > b && ob->mode != VV_MODE_COMPOSITE) /* one sample in the middle */
                        a = b = floor(0.5 * (z0 + z1) / fr->dts + 0.5);
                    a = a < kn ? kn : a;
                    if (fr->st->axis && ob->mode != VV_MODE_XRAY) {
                        a = -1e9;
                        b = 1e9;
                    }
                    if (a <= b) {
                        k0 = (int)(a < -2e9 ? -2e9 : a);
                        k1 = (int)(b > 2e9 ? 2e9 : b);
                        any |= ob->is_comp;
                    }
                }
                bd->k0[(size_t)o * (size_t)n + (size_t)pi] = k0;
                bd->k1[(size_t)o * (size_t)n + (size_t)pi] = k1;
                if (ob->is_comp && k0 <= k1 && k1 > kend)
                    kend = k1;
            }
            bd->kend[pi] = kend;
            if (!any)
                mark_done(bd, x, yl);
        }
    return VV_OK;
}

/* Splats the slices of object ob's voxels that cross sheet k into the band
 * buffer (ns buckets back: the voxels whose first sheet is k - ns + 1 .. k).
 * Axis variant and X-ray: whole footprints of the voxels of bucket k. */
static void
band_splat_sheet(sp_frame *fr, sp_band *bd, const sp_obj *ob, int band, int k, int rect[4],
                 int cull, uint8_t *dead, uint64_t *nfp, uint64_t *nculled) {
    const int whole = fr->st->axis || ob->mode == VV_MODE_XRAY;
    const int s1 = k - ob->kbase;
    int s0 = whole ? s1 : s1 - ob->ns + 1;
    s0 = s0 < 0 ? 0 : s0;
    if (s1 < 0 || s0 > ob->nsheets - 1)
        return;
    const int *bs = ob->bstart[band];
    const uint32_t *bidx = ob->bidx[band];
    const double zk = k * fr->dts;
    sp_fp fp;
    double s = 1;
    if (!whole) {
        if (zk < fr->znear)
            return;
        object_fp(fr, ob, zk, &fp);
        s = pix_scale(fr, zk);
    } else if (!fr->persp) {
        object_fp(fr, ob, 1, &fp);
        s = pix_scale(fr, 1);
    }
    const int shaded = ob->shading && ob->is_comp && !ob->pre_cls;
    const int nv = ob->is_comp ? (ob->pre_cls ? 4 : shaded ? 4 : 1) : 1;
    const double wbase = whole ? ob->vol_det : ob->vol_det / fr->dts;
    const int s_end = s1 < ob->nsheets - 1 ? s1 : ob->nsheets - 1;
    const double dlo = ob->z_lo, dhi = ob->z_lo + (SP_Z_LUT - 1) / ob->z_scale;
    for (int q = bs[s0]; q < bs[s_end + 1]; q++) {
        if (dead && dead[q])
            continue;
        const uint32_t v = bidx[q];
        int i, j, kk;
        unpack(ob->sorted[v], &i, &j, &kk);
        const double zc = lin4(ob->ez, i, j, kk);
        if (!whole && !(zk - zc >= dlo && zk - zc <= dhi))
            continue;
        const double X = lin4(ob->ex, i, j, kk), Y = lin4(ob->ey, i, j, kk);
        double w, cxe = X, cye = Y, zp = zk;
        if (whole) {
            w = wbase;
            zp = zc;
            if (fr->persp) {
                if (zc < fr->znear)
                    continue;
                s = pix_scale(fr, zc);
                object_fp(fr, ob, zc, &fp);
            }
        } else {
            const double d = zk - zc;
            double t = (d - ob->z_lo) * ob->z_scale;
            if (!(t >= 0 && t <= SP_Z_LUT - 1))
                continue;
            const int ti = (int)t;
            const double fr_ = t - ti;
            const int tn = ti + 1 < SP_Z_LUT ? ti + 1 : ti;
            const double m = ob->wz[ti] + (ob->wz[tn] - ob->wz[ti]) * fr_;
            if (!(m > 0))
                continue;
            const double dc = ob->dz[ti] + (ob->dz[tn] - ob->dz[ti]) * fr_;
            w = wbase * m;
            cxe += ob->bx * dc;
            cye += ob->by * dc;
        }
        double cx, cy;
        to_pixel(fr, cxe, cye, zp, &cx, &cy);
        if (cy + fp.hy < bd->y0 || cy - fp.hy > bd->y1 - 1 || cx + fp.hx < 0 ||
            cx - fp.hx > bd->W - 1)
            continue;
        if (cull && occluded_box(bd, cx - fp.hx, cx + fp.hx, cy - fp.hy, cy + fp.hy)) {
            (*nculled)++;
            if (dead && !whole) {
                /* the voxel's later slices shift by at most |b| 2 rz (and
                 * in perspective move with depth): if that whole box is
                 * finished too, the voxel is done in this band */
                const double ex = fabs(ob->bx) * (2 * ob->rz + fr->dts) * s + 1;
                const double ey = fabs(ob->by) * (2 * ob->rz + fr->dts) * s + 1;
                double x0 = cx - fp.hx - ex, x1 = cx + fp.hx + ex;
                double y0 = cy - fp.hy - ey, y1 = cy + fp.hy + ey;
                if (fr->persp) {
                    double cx2, cy2;
                    to_pixel(fr, X, Y, zc + ob->rz + fr->dts, &cx2, &cy2);
                    x0 = cx2 - fp.hx - ex < x0 ? cx2 - fp.hx - ex : x0;
                    x1 = cx2 + fp.hx + ex > x1 ? cx2 + fp.hx + ex : x1;
                    y0 = cy2 - fp.hy - ey < y0 ? cy2 - fp.hy - ey : y0;
                    y1 = cy2 + fp.hy + ey > y1 ? cy2 + fp.hy + ey : y1;
                }
                if (occluded_box(bd, x0, x1, y0, y1))
                    dead[q] = 1;
            }
            continue;
        }
        float val[4];
        if (ob->pre && ob->is_comp)
            memcpy(val, ob->pre[v], sizeof val);
        else if (shaded)
            memcpy(val, ob->v4[v], sizeof val);
        else
            val[0] = ob->v1[v];
        (*nfp)++;
        float wt = (float)(w * s * s * fp.norm) * fr->fp_scale;
        if (ob->mode == VV_MODE_XRAY) {
            const double sum =
                fp_discrete_sum(bd->wrow, bd->W, (float)fr->rho2, (float)cx, (float)cy, &fp);
            wt = sum > 0 ? (float)(w * s * s / sum) : 0;
        }
        if (nv == 1)
            fp_splat1(bd->buf, bd->ps, bd->W, bd->y0, bd->y1, (float)fr->rho2, (float)cx, (float)cy,
                      &fp, wt, val, rect);
        else
            fp_splat4(bd->buf, bd->ps, bd->W, bd->y0, bd->y1, (float)fr->rho2, (float)cx, (float)cy,
                      &fp, wt, val, rect);
    }
}

/* Post-classifies and shades the sheet's dirty rectangle and composites it
 * (composite objects), then clears it. */
static void
band_composite_sheet(sp_frame *fr, sp_band *bd, const sp_obj *ob, int o, int k, const int rect[4]) {
    const int n = bd->n;
    const int *k0 = bd->k0 + (size_t)o * (size_t)n, *k1 = bd->k1 + (size_t)o * (size_t)n;
    const float et = fr->et;
    const int pre = ob->pre_cls;
    const double zk = k * fr->dts;
    for (int y = rect[2]; y <= rect[3]; y++) {
        const int yl = y - bd->y0;
        for (int x = rect[0]; x <= rect[1]; x++) {
            const int pi = yl * bd->W + x;
            float *p = bd->buf + (size_t)pi;
            const float w = p[0];
            if (w == 0)
                continue;
            float sv[SP_CH];
            for (int ch = 0; ch < SP_CH; ch++) {
                sv[ch] = p[(size_t)ch * bd->ps];
                p[(size_t)ch * bd->ps] = 0;
            }
            if (bd->done[pi])
                continue;
            if (k > k1[pi]) {
                /* finished once past every composite object's exit */
                if (k > bd->kend[pi])
                    mark_done(bd, x, yl);
                continue;
            }
            if (k < k0[pi])
                continue;
            float e4[4];
            const float *e;
            if (pre) {
                e4[0] = sv[1] > 1 ? 1 : sv[1];
                e4[1] = sv[2];
                e4[2] = sv[3];
                e4[3] = sv[4];
                e = e4;
            } else {
                if (w < SP_WMIN)
                    continue;
                e = ob->tab.lut + 4 * (int)vv_vtables_index(&ob->tab, sv[1] / w);
                if (ob->labels)
                    e = label_entry(e, sv[1] / w, e4);
            }
            float alpha = e[0];
            if (alpha <= 0)
                continue;
            float col[3] = {e[1], e[2], e[3]};
            const float cs = bd->cosv[pi];
            if (fr->persp && cs < 0.99999f) {
                /* the slab is crossed over dts / cos */
                const float a2 = 1.0f - powf(1.0f - (alpha < 1 ? alpha : 1), 1.0f / cs);
                const float sc = a2 / alpha;
                col[0] *= sc;
                col[1] *= sc;
                col[2] *= sc;
                alpha = a2;
            }
            float out[3];
            if (ob->shading && !pre) {
                float pw[3] = {0, 0, 0};
                const float t = (float)(zk / cs);
                if (fr->point_lights) {
                    const float *rd = bd->rdir + 6 * (size_t)pi;
                    pw[0] = rd[3] + t * rd[0];
                    pw[1] = rd[4] + t * rd[1];
                    pw[2] = rd[5] + t * rd[2];
                }
                vv_vshade(&ob->sh, fr->lights, fr->n_lights, sv + 2, pw, bd->vdir + 3 * pi, col,
                          alpha, NULL, NULL, out);
            } else {
                out[0] = col[0];
                out[1] = col[1];
                out[2] = col[2];
            }
            float *C = bd->C + 3 * (size_t)pi;
            const float A = bd->A[pi], tr = 1 - A;
            C[0] += tr * out[0];
            C[1] += tr * out[1];
            C[2] += tr * out[2];
            bd->A[pi] = A + tr * alpha;
            if (bd->D[pi] == INFINITY)
                bd->D[pi] = (float)(zk / cs);
            if (bd->A[pi] >= et)
                mark_done(bd, x, yl);
        }
    }
}

/* Accumulates object ob's projection (MIP, MinIP: per sheet; X-ray: once)
 * into best[] / the line integrals. */
static void
band_project_sheet(sp_frame *fr, sp_band *bd, const sp_obj *ob, int o, int k, const int rect[4],
                   float *best, float *bdepth) {
    const int n = bd->n;
    const int *k0 = bd->k0 + (size_t)o * (size_t)n, *k1 = bd->k1 + (size_t)o * (size_t)n;
    const int mip = ob->mode == VV_MODE_MIP;
    for (int y = rect[2]; y <= rect[3]; y++) {
        const int yl = y - bd->y0;
        for (int x = rect[0]; x <= rect[1]; x++) {
            const int pi = yl * bd->W + x;
            float *p = bd->buf + (size_t)pi;
            const float w = p[0], wv = p[bd->ps];
            p[0] = p[bd->ps] = 0;
            if (ob->mode == VV_MODE_XRAY && fr->xray)
                fr->xray[(size_t)y * (size_t)bd->W + (size_t)x] += wv;
            if (w == 0 || k < k0[pi] || k > k1[pi])
                continue;
            if (ob->mode == VV_MODE_XRAY) {
                best[pi] = wv / w;
                continue;
            }
            if (w < SP_WMIN)
                continue;
            const float v = wv / w;
            if (mip ? v > best[pi] : v < best[pi]) {
                best[pi] = v;
                bdepth[pi] = (float)(k * fr->dts / bd->cosv[pi]);
            }
        }
    }
}

static vv_status
render_band(sp_frame *fr, int band, vv_image *out) {
    sp_band bd;
    vv_status s = band_init(fr, &bd, band);
    if (s != VV_OK)
        return s;
    uint64_t nfp = 0, ncull = 0, nsheets = 0;
    const int cull = fr->st->occlusion;
    /* composite objects: sheets front to back */
    if (fr->n_comp > 0) {
        int kmin = INT32_MAX, kmax = INT32_MIN;
        for (int o = 0; o < fr->n_comp; o++)
            for (int pi = 0; pi < bd.n; pi++) {
                const int a = bd.k0[(size_t)o * (size_t)bd.n + (size_t)pi],
                          b = bd.k1[(size_t)o * (size_t)bd.n + (size_t)pi];
                if (a > b)
                    continue;
                kmin = a < kmin ? a : kmin;
                kmax = b > kmax ? b : kmax;
            }
        if (fr->st->axis) {
            kmin = INT32_MAX;
            kmax = INT32_MIN;
            for (int o = 0; o < fr->n_comp; o++)
                if (fr->objs[o].nsheets) {
                    kmin = fr->objs[o].kbase < kmin ? fr->objs[o].kbase : kmin;
                    const int e = fr->objs[o].kbase + fr->objs[o].nsheets - 1;
                    kmax = e > kmax ? e : kmax;
                }
        }
        /* per object, the band's voxels found finished (occlusion) */
        uint8_t *dead[SP_MAX_OBJ] = {0};
        int dead_ok = cull;
        for (int o = 0; o < fr->n_comp && dead_ok; o++) {
            const sp_obj *ob = &fr->objs[o];
            const size_t m = ob->nsheets ? (size_t)ob->bstart[band][ob->nsheets] : 0;
            dead[o] = calloc(m ? m : 1, 1);
            dead_ok = dead[o] != NULL;
        }
        int alldone = 0;
        for (int k = kmin; k <= kmax && !alldone; k++) {
            if (atomic_load_explicit(&fr->cancelled, memory_order_relaxed))
                break;
            for (int o = 0; o < fr->n_comp; o++) {
                const sp_obj *ob = &fr->objs[o];
                int rect[4] = {INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN};
                band_splat_sheet(fr, &bd, ob, band, k, rect, cull, dead_ok ? dead[o] : NULL, &nfp,
                                 &ncull);
                if (rect[0] <= rect[1]) {
                    band_composite_sheet(fr, &bd, ob, o, k, rect);
                    nsheets++;
                }
            }
            /* every pixel finished: nothing behind can show */
            alldone = 1;
            for (int t = 0; t < bd.tw * bd.th && alldone; t++)
                alldone = bd.tcount[t] == bd.tcap[t];
        }
        for (int o = 0; o < fr->n_comp; o++)
            free(dead[o]);
    }
    /* projection objects, combined by their maximum like the ray caster */
    float *best = NULL, *bdepth = NULL;
    if (fr->n_obj > fr->n_comp) {
        best = malloc((size_t)bd.n * 2 * sizeof(float));
        if (!best) {
            band_free(&bd);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        bdepth = best + bd.n;
    }
    for (int o = fr->n_comp; o < fr->n_obj; o++) {
        const sp_obj *ob = &fr->objs[o];
        const int mip = ob->mode == VV_MODE_MIP;
        for (int pi = 0; pi < bd.n; pi++) {
            best[pi] = ob->mode == VV_MODE_XRAY ? NAN : mip ? -INFINITY : INFINITY;
            bdepth[pi] = INFINITY;
        }
        if (ob->mode == VV_MODE_XRAY) {
            int rect[4] = {INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN};
            for (int k = ob->kbase; k < ob->kbase + ob->nsheets; k++)
                band_splat_sheet(fr, &bd, ob, band, k, rect, 0, NULL, &nfp, &ncull);
            if (rect[0] <= rect[1]) {
                /* every pixel of the object has k0 <= 0 <= k1 for X-ray:
                 * pass a sheet index inside */
                const int n = bd.n;
                for (int pi = 0; pi < n; pi++)
                    if (bd.k0[(size_t)o * (size_t)n + (size_t)pi] <=
                        bd.k1[(size_t)o * (size_t)n + (size_t)pi]) {
                        bd.k0[(size_t)o * (size_t)n + (size_t)pi] = 0;
                        bd.k1[(size_t)o * (size_t)n + (size_t)pi] = 0;
                    }
                band_project_sheet(fr, &bd, ob, o, 0, rect, best, bdepth);
            }
        } else {
            for (int k = ob->kbase; k < ob->kbase + ob->nsheets; k++) {
                if (atomic_load_explicit(&fr->cancelled, memory_order_relaxed))
                    break;
                int rect[4] = {INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN};
                band_splat_sheet(fr, &bd, ob, band, k, rect, 0, NULL, &nfp, &ncull);
                if (rect[0] <= rect[1]) {
                    band_project_sheet(fr, &bd, ob, o, k, rect, best, bdepth);
                    nsheets++;
                }
            }
        }
        for (int pi = 0; pi < bd.n; pi++) {
            const float v = best[pi];
            if (!isfinite(v))
                continue;
            const float *e = ob->tab.lut + 4 * (int)vv_vtables_index(&ob->tab, v);
            for (int ch = 0; ch < 3; ch++) {
                const float cv = e[1 + ch] * e[0];
                bd.P[3 * pi + ch] = cv > bd.P[3 * pi + ch] ? cv : bd.P[3 * pi + ch];
            }
            bd.PA[pi] = e[0] > bd.PA[pi] ? e[0] : bd.PA[pi];
            if (ob->mode == VV_MODE_XRAY) {
                /* the ray caster reports the entry point */
                vv_vray r;
                const float *rd = bd.rdir + 6 * (size_t)pi;
                vv_ray wr = {{rd[3], rd[4], rd[5]}, {rd[0], rd[1], rd[2]}};
                if (vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, &wr, 0, INFINITY,
                                  &r))
                    bdepth[pi] = (float)r.t0;
            }
            bd.PD[pi] = bdepth[pi] < bd.PD[pi] ? bdepth[pi] : bd.PD[pi];
        }
    }
    free(best);
    /* the image: composited objects over the projections over the background */
    for (int yl = 0; yl < bd.y1 - bd.y0; yl++)
        for (int x = 0; x < bd.W; x++) {
            const int pi = yl * bd.W + x;
            const size_t oi = (size_t)(bd.y0 + yl) * (size_t)bd.W + (size_t)x;
            float *pix = out->rgba + 4 * oi;
            const float A = bd.A[pi] > 1 ? 1 : bd.A[pi];
            const float rest = 1 - A;
            const float A2 = A + rest * bd.PA[pi];
            for (int ch = 0; ch < 3; ch++)
                pix[ch] = bd.C[3 * pi + ch] + rest * bd.P[3 * pi + ch] + (1 - A2) * fr->bg[ch];
            pix[3] = A2;
            out->depth[oi] = bd.D[pi] < bd.PD[pi] ? bd.D[pi] : bd.PD[pi];
        }
#pragma omp critical(vv_splat_stats)
    {
        fr->footprints += nfp;
        fr->culled += ncull;
        fr->sheets += nsheets;
    }
    band_free(&bd);
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* Frame set-up                                                             */

static void
prepare_view(sp_frame *fr, const vv_view *view) {
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    vv_ray r00 = vv_view_ray(view, 0, 0), r10 = vv_view_ray(view, 1, 0),
           r01 = vv_view_ray(view, 0, 1);
    f = r00.dir;
    fr->persp = view->projection != VV_PROJECTION_ORTHOGRAPHIC;
    if (fr->persp) {
        /* the forward axis: the ray through the image centre */
        vv_ray rc = vv_view_ray(view, 0.5 * view->width - 0.5, 0.5 * view->height - 0.5);
        f = rc.dir;
    }
    fr->f = f;
    vv_ray *rs[3] = {&r00, &r10, &r01};
    for (int i = 0; i < 3; i++) {
        const double df = vv_vec3_dot(rs[i]->dir, f);
        if (fr->persp && df > 0)
            rs[i]->dir = vv_vec3_scale(rs[i]->dir, 1.0 / df);
    }
    fr->o00 = r00.origin;
    fr->ox = vv_vec3_sub(r10.origin, r00.origin);
    fr->oy = vv_vec3_sub(r01.origin, r00.origin);
    fr->d00 = r00.dir;
    fr->dx = vv_vec3_sub(r10.dir, r00.dir);
    fr->dy = vv_vec3_sub(r01.dir, r00.dir);
    if (fr->persp) {
        fr->eye = view->eye;
        fr->pix = vv_vec3_length(fr->dx);
        fr->r = vv_vec3_scale(fr->dx, 1.0 / fr->pix);
        fr->u = vv_vec3_normalize(fr->dy);
        fr->pcx = vv_vec3_dot(fr->d00, fr->r) / fr->pix;
        fr->pcy = vv_vec3_dot(fr->d00, fr->u) / fr->pix;
    } else {
        fr->eye = fr->o00;
        fr->pix = vv_vec3_length(fr->ox);
        fr->r = vv_vec3_scale(fr->ox, 1.0 / fr->pix);
        fr->u = vv_vec3_normalize(fr->oy);
    }
}

static vv_status
prepare_object(sp_frame *fr, sp_obj *ob, const vv_object *obj, const vv_world *w) {
    sp_state *st = fr->st;
    memset(ob, 0, sizeof *ob);
    ob->obj = obj;
    ob->mode = obj->mode;
    if (obj->mode == VV_MODE_ISO)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': iso mode is not drawn by splatting (use raycast or "
                            "surface)",
                            obj->name);
    if (obj->mode == VV_MODE_COMPOSITE && obj->segmentation == VV_SEG_TRANSFER_FUNCTION_2D)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': 2-D transfer functions are not drawn by splatting (use "
                            "raycast)",
                            obj->name);
    if (obj->mode == VV_MODE_COMPOSITE && obj->solid_texture.kind != VV_SOLID_TEXTURE_NONE)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': solid textures are not drawn by splatting (use raycast)",
                            obj->name);
    const int dims_ok = obj->volume->dims[0] < (1 << 21) && obj->volume->dims[1] < (1 << 21) &&
                        obj->volume->dims[2] < (1 << 21);
    if (!dims_ok)
        return vv_error_set(VV_ERR_LIMIT, "object '%s': more than 2^21 voxels along an axis",
                            obj->name);
    ob->is_comp = obj->mode == VV_MODE_COMPOSITE;
    ob->labels = ob->is_comp && obj->segmentation == VV_SEG_LABELS;
    /* a label volume is classified per voxel: a value reconstructed
     * between a label and the background (0) is no label */
    ob->pre_cls = fr->st->pre || ob->labels;
    vv_status s = vv_vcache_get(&st->vc, obj->volume, &ob->c);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    s = vv_vobject_prepare(obj, w, fr->ambient, fr->lights, fr->n_lights, ob->w2i, ob->i2w,
                           ob->dims, ob->planes, &ob->n_planes, &ob->sh);
    if (s != VV_OK)
        return s;
    ob->shading = obj->shading;
    return VV_OK;
}

static vv_status
sp_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    sp_state *st = state;
    memset(&st->stats, 0, sizeof st->stats);
    free(st->xray);
    st->xray = NULL;
    if (!(st->sigma > 0) || !(st->radius > 0))
        return vv_error_set(VV_ERR_INVALID, "kernel radius and sigma must be > 0");
    sp_frame *fr = calloc(1, sizeof *fr);
    if (!fr)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    fr->st = st;
    fr->opt = opt;
    fr->view = view;
    st->vc.frame++;
    fr->et = (float)st->early_termination;
    fr->ambient[0] = (float)w->ambient.x;
    fr->ambient[1] = (float)w->ambient.y;
    fr->ambient[2] = (float)w->ambient.z;
    fr->bg[0] = (float)w->background.x;
    fr->bg[1] = (float)w->background.y;
    fr->bg[2] = (float)w->background.z;
    fr->n_lights = vv_vlights_prepare(fr->lights, w, view);
    for (int l = 0; l < fr->n_lights; l++)
        fr->point_lights |= fr->lights[l].point;
    prepare_view(fr, view);

    /* quality: sheet spacing and kernel radius */
    double rate = st->rate, radius = st->radius;
    if (!(rate > 0))
        rate = opt->quality >= 2 ? 1.0 : opt->quality == 1 ? 1.5 : 2.0;
    if (opt->quality <= 0)
        radius = radius < 1.0 ? radius : 1.0;
    else if (opt->quality == 1)
        radius = radius * 0.85 > 1.0 ? radius * 0.85 : (radius < 1.0 ? radius : 1.0);
    fr->rho2 = (radius / st->sigma) * (radius / st->sigma);
    if (fr->rho2 > 64.0)
        fr->rho2 = 64.0; /* the Gaussian is below 1e-14 beyond 8 sigma */
    const double rho2 = fr->rho2;
    fr->fp_scale = (float)(1.0 / (2 * VV_PI * (1.0 - exp(-0.5 * rho2))));

    int nvis = 0;
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->visible && w->objects[i]->type == VV_OBJECT_VOLUME &&
            w->objects[i]->volume)
            nvis++;
    vv_status s = VV_OK;
    if (nvis > SP_MAX_OBJ)
        s = vv_error_set(VV_ERR_LIMIT, "%d visible objects; at most %d are supported", nvis,
                         SP_MAX_OBJ);
    sp_obj *objs = s == VV_OK ? calloc(nvis ? (size_t)nvis : 1, sizeof *objs) : NULL;
    if (s == VV_OK && !objs)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    fr->objs = objs;
    double dt = INFINITY;
    for (int pass = 0; pass < 2 && s == VV_OK; pass++)
        for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
            const vv_object *ob = w->objects[i];
            if (!ob->visible || ob->type != VV_OBJECT_VOLUME || !ob->volume)
                continue;
            const int comp = ob->mode == VV_MODE_COMPOSITE || ob->mode == VV_MODE_ISO;
            if (comp != (pass == 0))
                continue;
            if (!(ob->step > 0))
                s = vv_error_set(VV_ERR_INVALID, "object '%s': step must be > 0", ob->name);
            else
                s = prepare_object(fr, &objs[fr->n_obj++], ob, w);
            if (s == VV_OK) {
                const double sd = vv_vobject_step(ob);
                dt = sd < dt ? sd : dt;
            }
            if (pass == 0)
                fr->n_comp = fr->n_obj;
        }
    fr->dt = dt < INFINITY ? dt : 1.0;
    fr->dts = fr->dt * rate;
    fr->znear = fr->persp ? fr->dts : -INFINITY;
    const int nt = opt->threads > 0 ? opt->threads : vv_threads_get();
    /* bands: several per thread for balance, at least 8 rows */
    int bh = (view->height + 4 * nt - 1) / (4 * nt);
    bh = bh < 8 ? 8 : bh;
    fr->band_h = bh;
    fr->n_bands = (view->height + bh - 1) / bh;
    if (fr->n_bands > 32767)
        s = s == VV_OK ? vv_error_set(VV_ERR_LIMIT, "image of %d rows is too tall", view->height)
                       : s;
    for (int o = 0; o < fr->n_obj && s == VV_OK; o++) {
        sp_obj *ob = &objs[o];
        object_geometry(fr, ob);
        /* the opacity table for the sheet spacing (axis variant: the slice
         * distance along the view) */
        double dtl = fr->dts;
        if (st->axis) {
            double best = -1;
            for (int a = 0; a < 3; a++) {
                const double g =
                    ob->w2i[a][0] * fr->f.x + ob->w2i[a][1] * fr->f.y + ob->w2i[a][2] * fr->f.z;
                if (fabs(g) > best) {
                    best = fabs(g);
                    ob->axis_a = a;
                    ob->axis_sign = g > 0 ? 1 : -1;
                }
            }
            dtl = 1.0 / best;
        }
        ob->dt_lut = dtl;
        s = vv_vtables_get(&st->vc, ob->c, ob->obj, ob->mode, dtl, 0, 1, 0, &ob->tab,
                           &ob->owns_tables);
        if (s != VV_OK)
            break;
        /* octant of the view direction in index space */
        int oct = 0;
        for (int a = 0; a < 3; a++) {
            const double g =
                ob->w2i[a][0] * fr->f.x + ob->w2i[a][1] * fr->f.y + ob->w2i[a][2] * fr->f.z;
            oct |= g < 0 ? 1 << a : 0;
        }
        s = get_list(st, ob, oct, &st->stats.lists_built);
        if (s == VV_OK)
            s = object_buckets(fr, ob);
        st->stats.voxels += (uint64_t)ob->c->nx * (uint64_t)ob->c->ny * (uint64_t)ob->c->nz;
        st->stats.listed += ob->list ? ob->list->n : 0;
    }
    int has_xray = 0;
    for (int o = 0; o < fr->n_obj; o++)
        has_xray |= objs[o].mode == VV_MODE_XRAY;
    if (s == VV_OK && has_xray) {
        fr->xray = calloc((size_t)view->width * (size_t)view->height, sizeof(float));
        if (!fr->xray)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    if (s == VV_OK) {
        atomic_init(&fr->cancelled, 0);
        vv_status bs = VV_OK;
        const int nb = fr->n_bands;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
        for (int b = 0; b < nb; b++) {
            if (atomic_load_explicit(&fr->cancelled, memory_order_relaxed))
                continue;
            vv_status r = render_band(fr, b, out);
#pragma omp critical(vv_splat_progress)
            {
                if (r != VV_OK && bs == VV_OK)
                    bs = r;
                if (r != VV_OK)
                    atomic_store(&fr->cancelled, 1);
                fr->done_bands++;
                if (opt->progress.fn &&
                    vv_progress_report(&opt->progress, (double)fr->done_bands / nb))
                    atomic_store(&fr->cancelled, 1);
            }
        }
        if (bs != VV_OK)
            s = bs;
        else if (atomic_load(&fr->cancelled))
            s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
    }
    st->stats.footprints = fr->footprints;
    st->stats.culled = fr->culled;
    st->stats.sheets = fr->sheets;
    if (s == VV_OK && fr->xray) {
        /* the line integrals in world units: footprints were in world units
         * per pixel area; nothing to rescale */
        st->xray = fr->xray;
        st->xray_w = view->width;
        st->xray_h = view->height;
        fr->xray = NULL;
    }
    free(fr->xray);
    for (int o = 0; o < fr->n_obj; o++)
        object_free(&objs[o], fr->n_bands);
    free(objs);
    free(fr);
    vv_vcache_set_prune(&st->vc, w);
    return s;
}

/* ---------------------------------------------------------------------- */
/* Options and the operation table                                          */

static vv_status
sp_create(void **state) {
    sp_state *st = calloc(1, sizeof *st);
    if (!st)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_vcache_set_init(&st->vc);
    st->radius = 1.2;
    st->sigma = 0.55;
    st->ewa_var = 0.25;
    st->early_termination = 0.99;
    st->skipping = 1;
    st->occlusion = 1;
    *state = st;
    return VV_OK;
}

static void
lists_clear(sp_state *st) {
    for (int l = 0; l < SP_LISTS; l++) {
        vv_volume_free(st->lists[l].vol);
        free(st->lists[l].vox);
        memset(&st->lists[l], 0, sizeof st->lists[l]);
    }
}

static vv_status
sp_set_option(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    sp_state *st = state;
    const char *key = spec->key;
    if (strcmp(key, "classification") == 0) {
        st->pre = v->word == 1;
    } else if (strcmp(key, "sheets") == 0) {
        st->axis = v->word == 1;
    } else if (strcmp(key, "radius") == 0) {
        st->radius = v->r;
    } else if (strcmp(key, "sigma") == 0) {
        st->sigma = v->r;
    } else if (strcmp(key, "ewa_variance") == 0) {
        st->ewa_var = v->r;
    } else if (strcmp(key, "early_termination") == 0) {
        st->early_termination = v->r;
    } else if (strcmp(key, "sheet_spacing") == 0) {
        if (!(v->r == 0 || v->r >= 0.25))
            return vv_error_set(VV_ERR_INVALID,
                                "sheet_spacing must be 0 (by quality) or in [0.25, 8] steps");
        st->rate = v->r;
    } else if (strcmp(key, "empty_space_skipping") == 0) {
        st->skipping = v->b;
    } else if (strcmp(key, "occlusion_culling") == 0) {
        st->occlusion = v->b;
    } else if (strcmp(key, "gradient_budget_mb") == 0) {
        if (v->word >= 0)
            vv_vcache_set_default_budget(&st->vc);
        else
            st->vc.gradient_budget = (uint64_t)(v->r * 1048576.0);
        vv_vcache_set_clear(&st->vc);
    }
    return VV_OK;
}

static void
sp_destroy(void *state) {
    sp_state *st = state;
    if (!st)
        return;
    lists_clear(st);
    vv_vcache_set_clear(&st->vc);
    free(st->xray);
    free(st);
}

const vv_splat_stats *
vv_splat_stats_get(const vv_renderer *r) {
    if (!r || strcmp(vv_renderer_name(r), "splat") != 0)
        return NULL;
    const sp_state *st = vv_renderer_state(r);
    return &st->stats;
}

const float *
vv_splat_xray_integral(const vv_renderer *r) {
    if (!r || strcmp(vv_renderer_name(r), "splat") != 0)
        return NULL;
    const sp_state *st = vv_renderer_state(r);
    return st->xray;
}

static const char *const sp_classification[] = {"post", "pre", NULL};
static const char *const sp_sheets[] = {"image", "axis", NULL};
static const char *const sp_auto[] = {"auto", NULL};

static const vv_option_spec sp_options[] = {
    {"radius", VV_OPTION_REAL, "1.2", 0, 8, VV_OPTION_MIN_OPEN, NULL,
     "kernel cut-off, voxels (quality 1 shrinks it to 0.85 of it, quality 0 to 1 voxel)"},
    {"sigma", VV_OPTION_REAL, "0.55", 0, 4, VV_OPTION_MIN_OPEN, NULL, "Gaussian sigma, voxels"},
    {"ewa_variance", VV_OPTION_REAL, "0.25", 0, 16, 0, NULL,
     "least footprint variance, pixel^2 (0: no EWA antialiasing)"},
    {"classification", VV_OPTION_ENUM, "post", 0, 0, 0, sp_classification,
     "post: classify sheet samples; pre: classify and shade voxels, splat colours (faster, "
     "blurrier)"},
    {"sheet_spacing", VV_OPTION_REAL, "0", 0, 8, 0, NULL,
     "sheet spacing in ray-caster steps, 0 or in [0.25, 8] (0: 1, 1.5, 2 at quality 2, 1, 0)"},
    {"early_termination", VV_OPTION_REAL, "0.99", 0, 1, VV_OPTION_MIN_OPEN, NULL,
     "opacity at which a pixel is finished"},
    {"empty_space_skipping", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "list only voxels that can be visible (0 lists every voxel; same image)"},
    {"occlusion_culling", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "skip footprints on finished pixels (0 splats every footprint; same image)"},
    {"gradient_budget_mb", VV_OPTION_REAL, "auto", 0, INFINITY, 0, sp_auto,
     "MiB allowed for cached gradients (auto: a quarter of RAM, at most 8192)"},
    {"sheets", VV_OPTION_ENUM, "image", 0, 0, 0, sp_sheets,
     "image-aligned sheets; axis: Westover's axis-aligned sheets (for the popping test)"},
};

const vv_renderer_ops vv_splat_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "splat",
            .description = "splatting (object order): Gaussian footprints, image-aligned "
                           "sheets, EWA; composite, mip, minip, xray",
            .draws = VV_DRAWS(VV_OBJECT_VOLUME),
            .modes = VV_MODES_ALL & ~VV_MODE_BIT(VV_MODE_ISO),
            .caps = VV_RENDERER_QUALITY,
            .quality = "sheets 1, 1.5, 2 ray-caster steps apart at quality 2, 1, 0 (unless "
                       "sheet_spacing is set); quality 1 and 0 also shrink the kernel",
            .options = sp_options,
            .n_options = VV_OPTIONS_COUNT(sp_options),
        },
    .create = sp_create,
    .destroy = sp_destroy,
    .set_option = sp_set_option,
    .render = sp_render,
    .render_region = NULL,
};
