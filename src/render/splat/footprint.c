/*
 * Splatting, footprints (splat_internal.h): the screen-space Gaussian of a
 * kernel (or of its slice by a sheet), with the EWA low-pass, rasterised
 * four pixels at a time with an exact SIMD exponential.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "core/internal.h"
#include "render/splat/splat_internal.h"

/* ---------------------------------------------------------------------- */
/* Footprints                                                               */

/* The screen footprint of eye-space covariance (xx, xy, yy) at s pixels per
 * eye unit, its eigenvalues raised to at least ewa (EWA low-pass). */
void
sp_fp_setup(double xx, double xy, double yy, double s, double ewa, double rho2, sp_fp *fp) {
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

#ifndef __SSE2__ /* else exp_neg_ps below, four lanes at a time */
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
#endif

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
double
sp_fp_discrete_sum(float *wrow, int W, float rho2, float cx, float cy, const sp_fp *fp) {
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

void
sp_fp_splat1(float *buf, size_t ps, int W, int y0, int y1, float rho2, float cx, float cy,
             const sp_fp *fp, float w, const float *val, int rect[4]) {
    fp_splat_nv(buf, ps, W, y0, y1, rho2, cx, cy, fp, w, val, 1, rect);
}

void
sp_fp_splat4(float *buf, size_t ps, int W, int y0, int y1, float rho2, float cx, float cy,
             const sp_fp *fp, float w, const float *val, int rect[4]) {
    fp_splat_nv(buf, ps, W, y0, y1, rho2, cx, cy, fp, w, val, 4, rect);
}
