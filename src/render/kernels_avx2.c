/*
 * The AVX2 kernels of the volume renderers: the vector paths of the
 * sampling (eight trilinear samples at a time), classification (a chunk of
 * samples, with FMA), shading (Phong, eight samples at a time; and by
 * table, shade_table.h), ray (runs
 * of visible subvolumes found by sample) and projection (the MIP and MinIP
 * march in chunks of samples) stages. They are compiled for AVX2 through
 * target attributes, the rest of the library keeping the x86-64 baseline,
 * and chosen at run time (vv_vc_have_avx2). Each keeps its scalar path's
 * arithmetic, so that the images are the portable code's; where they may
 * differ (the rounding of classification's fused multiply-adds, where a
 * projection stops) the functions say so. Voxels, table entries and
 * subvolume distances are read by hardware gathers where they measured
 * faster, and by scalar loads put into lanes where not (the normals' codes).
 * The methods are their stages' (sample.h, classify.h, shade.h, ray.h,
 * project.h); docs/rendering.md ("SIMD", "Runs by sample", "MIP and MinIP",
 * "Issue 65: runs, gathers and refined MIP") gives the measurements.
 */
#include "render/kernels_avx2.h"

#include <float.h>
#include <math.h>
#include <string.h>
#if VV_VC_HAVE_AVX2
#include <immintrin.h>
#endif

#include "render/classify.h"
#include "render/project.h"
#include "render/ray.h"
#include "render/sample.h"
#include "render/shade.h"
#include "render/shade_table.h"

#if VV_VC_HAVE_AVX2
/* ---------------------------------------------------------------------- */
/* Sampling: the cells of eight points */

/* The trilinear values of samples k = kfirst .. kfirst + m - 1 (m <=
 * VV_VC_CHUNK) of ray r through 16-bit values, eight at a time with AVX2,
 * in exactly the arithmetic of vv_vray_point, vv_vcache_cell_in and
 * vv_vcache_value_at (separate multiplies and adds, no fused ones), so the
 * values are bit-identical to the scalar path's. */
/* The cells of eight index points (px, py, pz) inside the grid box, as
 * vv_vcache_cell_in computes them: their offsets (returned), fractions
 * (*wx, *wy, *wz) and the four x-pairs (v[o], v[o + 1]) of each cell's
 * edges, 16-bit values packed in 32-bit lanes, by hardware gathers of
 * 4 bytes a lane. Needs c->q16 and fewer than 2^30 voxels (32-bit
 * offsets). */
__attribute__((target("avx2"))) static inline __m256i
cell_pairs_avx2(const vv_vcache *c, __m256 px, __m256 py, __m256 pz, __m256 *wx, __m256 *wy,
                __m256 *wz, __m256i *p00, __m256i *p10, __m256i *p01, __m256i *p11) {
    const __m256i zero = _mm256_setzero_si256();
    __m256i i = _mm256_cvttps_epi32(px), j = _mm256_cvttps_epi32(py), k = _mm256_cvttps_epi32(pz);
    i = _mm256_max_epi32(_mm256_min_epi32(i, _mm256_set1_epi32(c->nx - 2)), zero);
    j = _mm256_max_epi32(_mm256_min_epi32(j, _mm256_set1_epi32(c->ny - 2)), zero);
    k = _mm256_max_epi32(_mm256_min_epi32(k, _mm256_set1_epi32(c->nz - 2)), zero);
    *wx = _mm256_sub_ps(px, _mm256_cvtepi32_ps(i));
    *wy = _mm256_sub_ps(py, _mm256_cvtepi32_ps(j));
    *wz = _mm256_sub_ps(pz, _mm256_cvtepi32_ps(k));
    const __m256i o =
        _mm256_add_epi32(_mm256_add_epi32(_mm256_mullo_epi32(k, _mm256_set1_epi32((int)c->sz)),
                                          _mm256_mullo_epi32(j, _mm256_set1_epi32((int)c->sy))),
                         i);
    const int *base = (const int *)(const void *)c->q16;
    const __m256i sy = _mm256_set1_epi32((int)c->sy), sz = _mm256_set1_epi32((int)c->sz);
    const __m256i oz = _mm256_add_epi32(o, sz);
    *p00 = _mm256_i32gather_epi32(base, o, 2);
    *p10 = _mm256_i32gather_epi32(base, _mm256_add_epi32(o, sy), 2);
    *p01 = _mm256_i32gather_epi32(base, oz, 2);
    *p11 = _mm256_i32gather_epi32(base, _mm256_add_epi32(oz, sy), 2);
    return o;
}

/* Eight x-pairs of 16-bit values (low and high halves of each 32-bit
 * lane) lerped by wx: a + (b - a) * wx. */
__attribute__((target("avx2"))) static inline __m256
pair_lerp_avx2(__m256i g, __m256 wx) {
    const __m256 a = _mm256_cvtepi32_ps(_mm256_and_si256(g, _mm256_set1_epi32(0xFFFF)));
    const __m256 b = _mm256_cvtepi32_ps(_mm256_srli_epi32(g, 16));
    return _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), wx));
}

/* ---------------------------------------------------------------------- */
/* Shading: eight samples at a time (shade.h) */

/* vv_vshade8 on registers: eight lanes of vv_vshade, in its order of
 * operations; *r, *g, *b the shaded colours. Inlined into the chunk's
 * shading pass (vv_vchunk_shade8), whose gradients and table entries stay
 * in registers (measured neither faster nor slower than the call). */
__attribute__((target("avx2"))) static inline void
shade8_avx2(const vv_vshading *o, const vv_vlight *lights, int n_lights, const float v[3],
            const float *shadow, __m256 g0, __m256 g1, __m256 g2, __m256 al, __m256 cr, __m256 cg,
            __m256 cb, __m256 *out_r, __m256 *out_g, __m256 *out_b) {
#define VS_MUL(x, y) _mm256_mul_ps((x), (y))
#define VS_ADD(x, y) _mm256_add_ps((x), (y))
#define VS_B(x) _mm256_set1_ps(x)
    /* n_k = (nrm[k][0] g0 + nrm[k][1] g1) + nrm[k][2] g2 */
    __m256 nn[3];
    for (int k = 0; k < 3; k++)
        nn[k] = VS_ADD(VS_ADD(VS_MUL(VS_B(o->nrm[k][0]), g0), VS_MUL(VS_B(o->nrm[k][1]), g1)),
                       VS_MUL(VS_B(o->nrm[k][2]), g2));
    const __m256 len2 =
        VS_ADD(VS_ADD(VS_MUL(nn[0], nn[0]), VS_MUL(nn[1], nn[1])), VS_MUL(nn[2], nn[2]));
    const __m256 lit = _mm256_cmp_ps(len2, VS_B(1e-12f), _CMP_GT_OQ);
    const __m256 inv = _mm256_div_ps(VS_B(1.0f), _mm256_sqrt_ps(len2));
    const __m256 nv = VS_MUL(VS_ADD(VS_ADD(VS_MUL(nn[0], VS_B(v[0])), VS_MUL(nn[1], VS_B(v[1]))),
                                    VS_MUL(nn[2], VS_B(v[2]))),
                             inv);
    const __m256 sign = VS_B(-0.0f), zero = _mm256_setzero_ps();
    __m256 d0 = VS_B(o->amb[0]), d1 = VS_B(o->amb[1]), d2 = VS_B(o->amb[2]);
    __m256 s0 = zero, s1 = zero, s2 = zero;
    for (int l = 0; l < n_lights; l++) {
        const vv_vlight *lt = &lights[l];
        const float L0 = lt->dir[0], L1 = lt->dir[1], L2 = lt->dir[2];
        __m256 ndl = VS_MUL(VS_ADD(VS_ADD(VS_MUL(nn[0], VS_B(L0)), VS_MUL(nn[1], VS_B(L1))),
                                   VS_MUL(nn[2], VS_B(L2))),
                            inv);
        /* two-sided: where ndl < 0 both ndv and ndl change sign */
        const __m256 back = _mm256_cmp_ps(ndl, zero, _CMP_LT_OQ);
        const __m256 ndv = _mm256_blendv_ps(nv, _mm256_xor_ps(nv, sign), back);
        ndl = _mm256_blendv_ps(ndl, _mm256_xor_ps(ndl, sign), back);
        const float lv = L0 * v[0] + L1 * v[1] + L2 * v[2];
        const __m256 rv = _mm256_sub_ps(VS_MUL(VS_MUL(VS_B(2.0f), ndl), ndv), VS_B(lv));
        const __m256 on = _mm256_and_ps(_mm256_cmp_ps(rv, zero, _CMP_GT_OQ), lit);
        const __m256i at =
            _mm256_cvttps_epi32(VS_ADD(VS_MUL(rv, VS_B((float)VV_VC_SPEC)), VS_B(0.5f)));
        __m256 sp = _mm256_mask_i32gather_ps(zero, o->spec, at, on, 4);
        __m256 wd = _mm256_and_ps(ndl, lit);
        if (shadow) { /* vv_vshade's wd = sh ndl, sp = sh sp */
            const __m256 sh = _mm256_loadu_ps(shadow + 8 * l);
            wd = VS_MUL(sh, wd);
            sp = VS_MUL(sh, sp);
        }
        d0 = VS_ADD(d0, VS_MUL(wd, VS_B(o->kd_col[l][0])));
        d1 = VS_ADD(d1, VS_MUL(wd, VS_B(o->kd_col[l][1])));
        d2 = VS_ADD(d2, VS_MUL(wd, VS_B(o->kd_col[l][2])));
        s0 = VS_ADD(s0, VS_MUL(sp, VS_B(o->ks_col[l][0])));
        s1 = VS_ADD(s1, VS_MUL(sp, VS_B(o->ks_col[l][1])));
        s2 = VS_ADD(s2, VS_MUL(sp, VS_B(o->ks_col[l][2])));
    }
    /* unlit lanes (a gradient of length 0): vv_vshade's d = amb, s = 0 */
    d0 = _mm256_blendv_ps(VS_B(o->amb[0]), d0, lit);
    d1 = _mm256_blendv_ps(VS_B(o->amb[1]), d1, lit);
    d2 = _mm256_blendv_ps(VS_B(o->amb[2]), d2, lit);
    s0 = _mm256_and_ps(s0, lit);
    s1 = _mm256_and_ps(s1, lit);
    s2 = _mm256_and_ps(s2, lit);
    *out_r = VS_ADD(VS_MUL(d0, cr), VS_MUL(al, s0));
    *out_g = VS_ADD(VS_MUL(d1, cg), VS_MUL(al, s1));
    *out_b = VS_ADD(VS_MUL(d2, cb), VS_MUL(al, s2));
#undef VS_MUL
#undef VS_ADD
#undef VS_B
}

/* vv_vshade8: shade8_avx2 from and to arrays. */
__attribute__((target("avx2"))) void
vv_vshade8(const vv_vshading *o, const vv_vlight *lights, int n_lights, const float v[3],
           const float *shadow, const float gx[8], const float gy[8], const float gz[8],
           const float a[8], const float cr[8], const float cg[8], const float cb[8],
           float out_r[8], float out_g[8], float out_b[8]) {
    __m256 r, g, b;
    shade8_avx2(o, lights, n_lights, v, shadow, _mm256_loadu_ps(gx), _mm256_loadu_ps(gy),
                _mm256_loadu_ps(gz), _mm256_loadu_ps(a), _mm256_loadu_ps(cr), _mm256_loadu_ps(cg),
                _mm256_loadu_ps(cb), &r, &g, &b);
    _mm256_storeu_ps(out_r, r);
    _mm256_storeu_ps(out_g, g);
    _mm256_storeu_ps(out_b, b);
}

/* ---------------------------------------------------------------------- */
/* Gradients: the octahedral codes of a run of a row */

__attribute__((target("avx2"))) void
vv_oct_encode_n_avx2(const float *gx, const float *gy, const float *gz, int n, int8_t *out) {
    const __m256 sign = _mm256_set1_ps(-0.0f), lim = _mm256_set1_ps(127.0f);
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 nlim = _mm256_set1_ps(-127.0f), off = _mm256_set1_ps(128.0f);
    const __m256 zc = _mm256_set1_ps((float)VV_OCT_ZERO), fmax = _mm256_set1_ps(FLT_MAX);
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const __m256 gx0 = _mm256_loadu_ps(gx + i), gy0 = _mm256_loadu_ps(gy + i);
        const __m256 gz0 = _mm256_loadu_ps(gz + i);
        const __m256 l1 =
            _mm256_add_ps(_mm256_add_ps(_mm256_andnot_ps(sign, gx0), _mm256_andnot_ps(sign, gy0)),
                          _mm256_andnot_ps(sign, gz0));
        /* no direction: 0, or not finite (NaN or infinite differences) */
        const __m256 flat = _mm256_or_ps(_mm256_cmp_ps(l1, zero, _CMP_NGT_UQ),
                                         _mm256_cmp_ps(l1, fmax, _CMP_NLE_UQ));
        const __m256 dv = _mm256_blendv_ps(l1, one, flat);
        const __m256 x0 = _mm256_div_ps(gx0, dv), y0 = _mm256_div_ps(gy0, dv);
        const __m256 z0 = _mm256_div_ps(gz0, dv);
        __m256 x = _mm256_mul_ps(x0, lim), y = _mm256_mul_ps(y0, lim);
        const __m256 fx =
            _mm256_or_ps(_mm256_sub_ps(lim, _mm256_andnot_ps(sign, y)), _mm256_and_ps(x, sign));
        const __m256 fy =
            _mm256_or_ps(_mm256_sub_ps(lim, _mm256_andnot_ps(sign, x)), _mm256_and_ps(y, sign));
        const __m256 low = _mm256_cmp_ps(z0, zero, _CMP_LT_OQ);
        x = _mm256_blendv_ps(x, fx, low);
        y = _mm256_blendv_ps(y, fy, low);
        const __m256 bx =
            _mm256_sub_ps(_mm256_cvtepi32_ps(_mm256_cvttps_epi32(_mm256_add_ps(x, off))), off);
        const __m256 by =
            _mm256_sub_ps(_mm256_cvtepi32_ps(_mm256_cvttps_epi32(_mm256_add_ps(y, off))), off);
        __m256 bu = bx, bv = by, bnum = _mm256_set1_ps(-1.0f), bden = one;
        for (int d = 0; d < 4; d++) {
            const __m256 cu =
                _mm256_max_ps(_mm256_min_ps(d & 1 ? _mm256_add_ps(bx, one) : bx, lim), nlim);
            const __m256 cv =
                _mm256_max_ps(_mm256_min_ps(d >> 1 ? _mm256_add_ps(by, one) : by, lim), nlim);
            const __m256 nz = _mm256_sub_ps(_mm256_sub_ps(lim, _mm256_andnot_ps(sign, cu)),
                                            _mm256_andnot_ps(sign, cv));
            const __m256 t = _mm256_max_ps(_mm256_sub_ps(zero, nz), zero);
            const __m256 nx = _mm256_sub_ps(cu, _mm256_or_ps(t, _mm256_and_ps(cu, sign)));
            const __m256 ny = _mm256_sub_ps(cv, _mm256_or_ps(t, _mm256_and_ps(cv, sign)));
            const __m256 dot = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(nx, x0), _mm256_mul_ps(ny, y0)), _mm256_mul_ps(nz, z0));
            const __m256 num = _mm256_mul_ps(dot, dot);
            const __m256 den = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(nx, nx), _mm256_mul_ps(ny, ny)), _mm256_mul_ps(nz, nz));
            const __m256 better =
                _mm256_cmp_ps(_mm256_mul_ps(num, bden), _mm256_mul_ps(bnum, den), _CMP_GT_OQ);
            bu = _mm256_blendv_ps(bu, cu, better);
            bv = _mm256_blendv_ps(bv, cv, better);
            bnum = _mm256_blendv_ps(bnum, num, better);
            bden = _mm256_blendv_ps(bden, den, better);
        }
        bu = _mm256_blendv_ps(bu, zc, flat);
        bv = _mm256_blendv_ps(bv, zc, flat);
        /* (u, v) interleaved: unpack works within 128-bit halves, so lanes
         * 0-1, 4-5 | 2-3, 6-7; the packs keep that order per half */
        const __m256i lo = _mm256_cvtps_epi32(_mm256_unpacklo_ps(bu, bv));
        const __m256i hi = _mm256_cvtps_epi32(_mm256_unpackhi_ps(bu, bv));
        /* per half: u0 v0 u1 v1 u2 v2 u3 v3 (half 0: voxels 0-3, half 1: 4-7) */
        const __m256i w16 = _mm256_packs_epi32(lo, hi);
        const __m256i w8 = _mm256_packs_epi16(w16, w16);
        const int64_t h0 = _mm256_extract_epi64(w8, 0), h1 = _mm256_extract_epi64(w8, 2);
        memcpy(out + 2 * i, &h0, 8);
        memcpy(out + 2 * i + 8, &h1, 8);
    }
    if (i < n)
        vv_oct_encode_n(gx + i, gy + i, gz + i, n - i, out + 2 * i);
}

/* vv_oct_decode4 eight lanes wide. */
__attribute__((target("avx2"))) static inline void
oct_decode8(__m256i u, __m256i v, __m256 *x, __m256 *y, __m256 *z) {
    const __m256 sign = _mm256_set1_ps(-0.0f), zero = _mm256_setzero_ps();
    const __m256 none = _mm256_castsi256_ps(_mm256_cmpeq_epi32(u, _mm256_set1_epi32(VV_OCT_ZERO)));
    __m256 fu = _mm256_cvtepi32_ps(u), fv = _mm256_cvtepi32_ps(v);
    const __m256 fz =
        _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(127.0f), _mm256_andnot_ps(sign, fu)),
                      _mm256_andnot_ps(sign, fv));
    const __m256 t = _mm256_max_ps(_mm256_sub_ps(zero, fz), zero);
    fu = _mm256_sub_ps(fu, _mm256_or_ps(t, _mm256_and_ps(fu, sign)));
    fv = _mm256_sub_ps(fv, _mm256_or_ps(t, _mm256_and_ps(fv, sign)));
    const __m256 len2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(fu, fu), _mm256_mul_ps(fv, fv)),
                                      _mm256_mul_ps(fz, fz));
    const __m256 r = _mm256_andnot_ps(none, _mm256_rsqrt_ps(len2));
    *x = _mm256_mul_ps(fu, r);
    *y = _mm256_mul_ps(fv, r);
    *z = _mm256_mul_ps(fz, r);
}

/* Composites @p n shaded samples (colour orr, org, orb; opacity alf) front
 * to back into C and *A, one at a time, in order (so that the image does
 * not depend on which samples share a vector), the sums in locals rather
 * than through the pointers, which may alias the arrays; *shaded counts
 * them. 1 once the opacity reaches @p et (the rest are not used). */
static inline int
composite8(const float *orr, const float *org, const float *orb, const float *alf, int n, float et,
           float C[3], float *A, uint32_t *shaded) {
    float c0 = C[0], c1 = C[1], c2 = C[2], acc = *A;
    int q = 0, end = 0;
    while (q < n) {
        const float w = 1 - acc;
        c0 += w * orr[q];
        c1 += w * org[q];
        c2 += w * orb[q];
        acc += w * alf[q];
        q++;
        if (acc >= et) {
            end = 1;
            break;
        }
    }
    C[0] = c0;
    C[1] = c1;
    C[2] = c2;
    *A = acc;
    *shaded += (uint32_t)q;
    return end;
}

/* vv_vcache_gradient_at of eight samples (cells cell[vis[q]], fractions
 * fx, fy, fz at vis[q]; lanes past n8 repeat the first), one lane a
 * sample: each of the cells' four x-pairs of octahedral codes decoded
 * eight at a time, in the order of vv_vcache_gradient_at's operations so
 * that the gradients are its own. Needs c->nrm. */
__attribute__((target("avx2"))) static void
gradient8_avx2(const vv_vcache *c, const size_t *cell, const float *fx, const float *fy,
               const float *fz, const int *vis, int n8, __m256 *gx, __m256 *gy, __m256 *gz) {
    const size_t sy = 2 * c->sy, sz = 2 * c->sz;
    const int8_t *p[8];
    for (int q = 0; q < 8; q++)
        p[q] = c->nrm + 2 * cell[vis[q < n8 ? q : 0]];
    /* the fractions by gathers (eight scalar stores and a vector load of
     * them would wait for all eight) */
    const __m256i live =
        _mm256_cmpgt_epi32(_mm256_set1_epi32(n8), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    const __m256i at =
        _mm256_blendv_epi8(_mm256_set1_epi32(vis[0]), _mm256_maskload_epi32(vis, live), live);
    /* each row's eight 32-bit pairs put into lanes by inserts, not stored
     * and reloaded (a vector load of eight scalar stores waits for all);
     * hardware gathers measured 10 % slower here (docs/rendering.md) */
    const size_t off[4] = {0, sy, sz, sz + sy};
    const __m256 one = _mm256_set1_ps(1.0f), f0 = _mm256_i32gather_ps(fx, at, 4);
    const __m256 f1 = _mm256_i32gather_ps(fy, at, 4), f2 = _mm256_i32gather_ps(fz, at, 4);
    const __m256 g1 = _mm256_sub_ps(one, f1), g2 = _mm256_sub_ps(one, f2);
    const __m256 w[4] = {_mm256_mul_ps(g1, g2), _mm256_mul_ps(f1, g2), _mm256_mul_ps(g1, f2),
                         _mm256_mul_ps(f1, f2)};
    __m256 X[4], Y[4], Z[4];
    for (int r = 0; r < 4; r++) {
        int32_t a[8];
        for (int q = 0; q < 8; q++)
            memcpy(&a[q], p[q] + off[r], 4);
        const __m256i b = _mm256_setr_epi32(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]);
        __m256 x0, y0, z0, x1, y1, z1;
        oct_decode8(_mm256_srai_epi32(_mm256_slli_epi32(b, 24), 24),
                    _mm256_srai_epi32(_mm256_slli_epi32(b, 16), 24), &x0, &y0, &z0);
        oct_decode8(_mm256_srai_epi32(_mm256_slli_epi32(b, 8), 24), _mm256_srai_epi32(b, 24), &x1,
                    &y1, &z1);
        X[r] = _mm256_mul_ps(_mm256_add_ps(x0, _mm256_mul_ps(_mm256_sub_ps(x1, x0), f0)), w[r]);
        Y[r] = _mm256_mul_ps(_mm256_add_ps(y0, _mm256_mul_ps(_mm256_sub_ps(y1, y0), f0)), w[r]);
        Z[r] = _mm256_mul_ps(_mm256_add_ps(z0, _mm256_mul_ps(_mm256_sub_ps(z1, z0), f0)), w[r]);
    }
    /* vv_vcache_gradient_at's sums: (r0 + r2) + (r1 + r3) */
    *gx = _mm256_add_ps(_mm256_add_ps(X[0], X[2]), _mm256_add_ps(X[1], X[3]));
    *gy = _mm256_add_ps(_mm256_add_ps(Y[0], Y[2]), _mm256_add_ps(Y[1], Y[3]));
    *gz = _mm256_add_ps(_mm256_add_ps(Z[0], Z[2]), _mm256_add_ps(Z[1], Z[3]));
}

__attribute__((target("avx2"))) int
vv_vchunk_shade8(const vv_vcache *c, const float *lut, const vv_vshading *o,
                 const vv_vlight *lights, int n_lights, const float v[3], int m, const size_t *cell,
                 const float *fx, const float *fy, const float *fz, const int32_t *entry,
                 vv_vshadow8_fn shadow, void *ctx, float et, float C[3], float *A, int *first,
                 uint32_t *shaded) {
    /* the visible samples, found without a branch a sample */
    int vis[VV_VC_CHUNK + 8], nvis = 0;
    for (int s = 0; s < m; s++) {
        vis[nvis] = s;
        nvis += lut[entry[s]] > 0;
    }
    for (int i0 = 0; i0 < nvis; i0 += 8) {
        const int n8 = nvis - i0 < 8 ? nvis - i0 : 8;
        float sh[VV_MAX_LIGHTS * 8];
        int shadowed = 0;
        if (shadow)
            memset(sh, 0, sizeof(float) * 8 * (size_t)n_lights);
        __m256 gx, gy, gz;
        gradient8_avx2(c, cell, fx, fy, fz, vis + i0, n8, &gx, &gy, &gz);
        /* the table entries of the eight (zero in lanes past n8) */
        const __m256i live =
            _mm256_cmpgt_epi32(_mm256_set1_epi32(n8), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
        const __m256i at = _mm256_mask_i32gather_epi32(
            _mm256_setzero_si256(), entry, _mm256_maskload_epi32(vis + i0, live), live, 4);
        const __m256 zero = _mm256_setzero_ps(), lm = _mm256_castsi256_ps(live);
        const __m256 al = _mm256_mask_i32gather_ps(zero, lut, at, lm, 4);
        const __m256 cr = _mm256_mask_i32gather_ps(zero, lut + 1, at, lm, 4);
        const __m256 cg = _mm256_mask_i32gather_ps(zero, lut + 2, at, lm, 4);
        const __m256 cb = _mm256_mask_i32gather_ps(zero, lut + 3, at, lm, 4);
        for (int q = 0; shadow && q < n8; q++)
            shadowed = shadow(ctx, vis[i0 + q], sh + q, 8);
        __m256 sr, sg, sb;
        shade8_avx2(o, lights, n_lights, v, shadowed ? sh : NULL, gx, gy, gz, al, cr, cg, cb, &sr,
                    &sg, &sb);
        float orr[8], org[8], orb[8], alf[8];
        _mm256_storeu_ps(orr, sr);
        _mm256_storeu_ps(org, sg);
        _mm256_storeu_ps(orb, sb);
        _mm256_storeu_ps(alf, al);
        if (*first < 0)
            *first = vis[i0];
        if (composite8(orr, org, orb, alf, n8, et, C, A, shaded))
            return 1;
    }
    return 0;
}

/* vv_vchunk_shade8_table: shading=table eight samples at a time (one a
 * lane): each row of a cell's corners is a 32-bit load of two 16-bit codes,
 * which index the packed table by a gather each; the diffuse and specular
 * halves are lerped in x, weighted by the rows' bilinear weights and
 * summed, as vv_vcache_gradient_at blends normals. */
__attribute__((target("avx2,fma"))) int
vv_vchunk_shade8_table(const vv_vcache *c, const float *lut, const vv_vshade_table *t, int m,
                       const size_t *cell, const float *fx, const float *fy, const float *fz,
                       const int32_t *entry, float et, float C[3], float *A, int *first,
                       uint32_t *shaded) {
    int vis[VV_VC_CHUNK + 8], nvis = 0;
    for (int s = 0; s < m; s++) {
        vis[nvis] = s;
        nvis += lut[entry[s]] > 0;
    }
    const size_t sy = 2 * c->sy, sz = 2 * c->sz;
    const size_t off[4] = {0, sy, sz, sz + sy};
    const int *tab = (const int *)t->packed;
    const __m256i lo16 = _mm256_set1_epi32(0xffff);
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 dscale = _mm256_set1_ps(t->dscale), sscale = _mm256_set1_ps(t->sscale);
    for (int i0 = 0; i0 < nvis; i0 += 8) {
        const int n8 = nvis - i0 < 8 ? nvis - i0 : 8;
        const int8_t *p[8];
        for (int q = 0; q < 8; q++)
            p[q] = c->nrm + 2 * cell[vis[i0 + (q < n8 ? q : 0)]];
        const __m256i live =
            _mm256_cmpgt_epi32(_mm256_set1_epi32(n8), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
        const __m256i at = _mm256_blendv_epi8(_mm256_set1_epi32(vis[i0]),
                                              _mm256_maskload_epi32(vis + i0, live), live);
        const __m256 f0 = _mm256_i32gather_ps(fx, at, 4), f1 = _mm256_i32gather_ps(fy, at, 4);
        const __m256 f2 = _mm256_i32gather_ps(fz, at, 4);
        const __m256 g1 = _mm256_sub_ps(one, f1), g2 = _mm256_sub_ps(one, f2);
        const __m256 w[4] = {_mm256_mul_ps(g1, g2), _mm256_mul_ps(f1, g2), _mm256_mul_ps(g1, f2),
                             _mm256_mul_ps(f1, f2)};
        __m256 d = zero, sp = zero;
        for (int r = 0; r < 4; r++) {
            int32_t a[8];
            for (int q = 0; q < 8; q++)
                memcpy(&a[q], p[q] + off[r], 4);
            const __m256i b = _mm256_setr_epi32(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]);
            const __m256i e0 = _mm256_i32gather_epi32(tab, _mm256_and_si256(b, lo16), 4);
            const __m256i e1 = _mm256_i32gather_epi32(tab, _mm256_srli_epi32(b, 16), 4);
            const __m256 d0 = _mm256_cvtepi32_ps(_mm256_and_si256(e0, lo16));
            const __m256 d1 = _mm256_cvtepi32_ps(_mm256_and_si256(e1, lo16));
            const __m256 s0 = _mm256_cvtepi32_ps(_mm256_srli_epi32(e0, 16));
            const __m256 s1 = _mm256_cvtepi32_ps(_mm256_srli_epi32(e1, 16));
            d = _mm256_fmadd_ps(_mm256_fmadd_ps(_mm256_sub_ps(d1, d0), f0, d0), w[r], d);
            sp = _mm256_fmadd_ps(_mm256_fmadd_ps(_mm256_sub_ps(s1, s0), f0, s0), w[r], sp);
        }
        d = _mm256_mul_ps(d, dscale);
        sp = _mm256_mul_ps(sp, sscale);
        const __m256i ea = _mm256_mask_i32gather_epi32(
            _mm256_setzero_si256(), entry, _mm256_maskload_epi32(vis + i0, live), live, 4);
        const __m256 lm = _mm256_castsi256_ps(live);
        const __m256 al = _mm256_mask_i32gather_ps(zero, lut, ea, lm, 4);
        const __m256 cr = _mm256_mask_i32gather_ps(zero, lut + 1, ea, lm, 4);
        const __m256 cg = _mm256_mask_i32gather_ps(zero, lut + 2, ea, lm, 4);
        const __m256 cb = _mm256_mask_i32gather_ps(zero, lut + 3, ea, lm, 4);
        const __m256 as = _mm256_mul_ps(al, sp);
        float orr[8], org[8], orb[8], alf[8];
        _mm256_storeu_ps(orr, _mm256_fmadd_ps(d, cr, as));
        _mm256_storeu_ps(org, _mm256_fmadd_ps(d, cg, as));
        _mm256_storeu_ps(orb, _mm256_fmadd_ps(d, cb, as));
        _mm256_storeu_ps(alf, al);
        if (*first < 0)
            *first = vis[i0];
        if (composite8(orr, org, orb, alf, n8, et, C, A, shaded))
            return 1;
    }
    return 0;
}

/* ---------------------------------------------------------------------- */
/* Sampling along a ray: eight samples at a time */

/* The index points of the samples k .. k + 7 of r, as vv_vray_point
 * computes them (no fused multiply-add). */
__attribute__((target("avx2"))) static inline void
points8_avx2(const vv_vray *r, double k, double dt, __m256 *px, __m256 *py, __m256 *pz) {
    float u[8];
    for (int l = 0; l < 8; l++)
        u[l] = (float)((k + l) * dt - r->tb);
    const __m256 t = _mm256_loadu_ps(u);
    *px = _mm256_sub_ps(
        _mm256_add_ps(_mm256_set1_ps(r->o[0]), _mm256_mul_ps(t, _mm256_set1_ps(r->d[0]))),
        _mm256_set1_ps(r->off[0]));
    *py = _mm256_sub_ps(
        _mm256_add_ps(_mm256_set1_ps(r->o[1]), _mm256_mul_ps(t, _mm256_set1_ps(r->d[1]))),
        _mm256_set1_ps(r->off[1]));
    *pz = _mm256_sub_ps(
        _mm256_add_ps(_mm256_set1_ps(r->o[2]), _mm256_mul_ps(t, _mm256_set1_ps(r->d[2]))),
        _mm256_set1_ps(r->off[2]));
}

/* The trilinear values at index points px, py, pz (16-bit values), in the
 * lerp order of vv_vcache_value_at. */
__attribute__((target("avx2"))) static inline __m256
values_at8_avx2(const vv_vcache *c, __m256 px, __m256 py, __m256 pz) {
    __m256 wx, wy, wz;
    __m256i p00, p10, p01, p11;
    (void)cell_pairs_avx2(c, px, py, pz, &wx, &wy, &wz, &p00, &p10, &p01, &p11);
    const __m256 c00 = pair_lerp_avx2(p00, wx), c10 = pair_lerp_avx2(p10, wx);
    const __m256 c01 = pair_lerp_avx2(p01, wx), c11 = pair_lerp_avx2(p11, wx);
    const __m256 c0 = _mm256_add_ps(c00, _mm256_mul_ps(_mm256_sub_ps(c10, c00), wy));
    const __m256 c1 = _mm256_add_ps(c01, _mm256_mul_ps(_mm256_sub_ps(c11, c01), wy));
    return _mm256_add_ps(c0, _mm256_mul_ps(_mm256_sub_ps(c1, c0), wz));
}

/* vv_vray_values_avx2 of the eight samples kfirst .. kfirst + 7, in a
 * register. */
__attribute__((target("avx2"))) static inline __m256
values8_avx2(const vv_vcache *c, const vv_vray *r, double kfirst, double dt) {
    __m256 px, py, pz;
    points8_avx2(r, kfirst, dt, &px, &py, &pz);
    return values_at8_avx2(c, px, py, pz);
}

/* The trilinear values of the samples kfirst .. kfirst + m - 1 (m <=
 * VV_VC_CHUNK) of r, eight at a time: the scalar path's arithmetic. */
__attribute__((target("avx2"))) void
vv_vray_values_avx2(const vv_vcache *c, const vv_vray *r, double kfirst, double dt, int m,
                    float *val) {
    float out[VV_VC_CHUNK + 8];
    for (int s = 0; s < m; s += 8)
        _mm256_storeu_ps(out + s, values8_avx2(c, r, kfirst + s, dt));
    memcpy(val, out, (size_t)m * sizeof *val);
}

/* The subvolumes (vv_vproj_block's, vv_vblock_of's) of the samples k .. k + 7
 * of r, their points computed as vv_vray_point does. */
__attribute__((target("avx2"))) static inline __m256i
blocks8_avx2(const vv_vcache *c, const vv_vray *r, double k, double dt) {
    const __m256 zero = _mm256_setzero_ps(), quarter = _mm256_set1_ps(1.0f / VV_VC_BLOCK);
    __m256 px, py, pz;
    points8_avx2(r, k, dt, &px, &py, &pz);
    const __m256i bi =
        _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(px, zero), quarter)),
                         _mm256_set1_epi32(c->bx - 1));
    const __m256i bj =
        _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(py, zero), quarter)),
                         _mm256_set1_epi32(c->by - 1));
    const __m256i bk =
        _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(pz, zero), quarter)),
                         _mm256_set1_epi32(c->bz - 1));
    return _mm256_add_epi32(
        _mm256_mullo_epi32(_mm256_add_epi32(_mm256_mullo_epi32(bk, _mm256_set1_epi32(c->by)), bj),
                           _mm256_set1_epi32(c->bx)),
        bi);
}

/* ---------------------------------------------------------------------- */
/* Ray: runs of visible subvolumes by sample (ray.h) */

/* vv_vray_visible_run_avx2 leaps from a hidden subvolume at this chessboard
 * distance or more, and scans the samples ahead from one closer (1 measured
 * faster than 2 or 4, docs/rendering.md). */
#define VRUN_LEAP 2

/* Bit s of the result: sample k + s (s < n <= VV_VC_CHUNK <= 64) of r
 * lies in a visible subvolume (bdist 0), eight lanes at a time by gathers,
 * sixteen samples between tests of whether the run has ended (a hidden
 * sample after the first visible one): the bits are exact up to there and
 * zero after. A test after each eight waited on each gather (measured 1 %
 * slower than none; every sixteen, 0-3 % faster than none). */
__attribute__((target("avx2"))) static uint64_t
visible_bits_avx2(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double k, double dt,
                  int n) {
    uint64_t bits = 0;
    for (int s = 0; s < n; s += 8) {
        /* every 16: stop where the run has ended (a hidden sample after
         * the first visible one) */
        if (s && !(s & 15) && bits &&
            (~bits & (((uint64_t)1 << s) - 1) & ~((bits & (0 - bits)) - 1)))
            break;
        /* four bytes a lane (bdist is followed by vdist: vv_vtables) */
        const __m256i d = _mm256_and_si256(_mm256_i32gather_epi32((const int *)(const void *)bdist,
                                                                  blocks8_avx2(c, r, k + s, dt), 1),
                                           _mm256_set1_epi32(0xFF));
        bits |= (uint64_t)(uint32_t)_mm256_movemask_ps(
                    _mm256_castsi256_ps(_mm256_cmpeq_epi32(d, _mm256_setzero_si256())))
                << s;
    }
    return n < 64 ? bits & (((uint64_t)1 << n) - 1) : bits;
}

/* The number of ones at the bottom of x. */
static inline int
trailing_ones64(uint64_t x) {
    return ~x ? __builtin_ctzll(~x) : 64;
}

__attribute__((target("avx2"))) int
vv_vray_visible_run_avx2(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt,
                         double kend, double *kp, double *klastp) {
    const uint8_t *vdist = vv_vtables_vdist(bdist, (size_t)c->bx * (size_t)c->by * (size_t)c->bz);
    const unsigned bxm = (unsigned)c->bx - 1, bym = (unsigned)c->by - 1, bzm = (unsigned)c->bz - 1;
    const double inv_dt = 1.0 / dt;
    double k = *kp;
    while (k <= kend) {
        float p[3];
        double t;
        unsigned bc[3];
        if (vv_vray_leap_from(c, bdist, r, dt, VRUN_LEAP, &k, p, &t, bc))
            continue;
        /* near or in a visible subvolume: a run of at most VV_VC_CHUNK
         * samples from k */
        const double cap = kend < k + (VV_VC_CHUNK - 1) ? kend : k + (VV_VC_CHUNK - 1);
        double first = -1, klast = k - 1;
        /* inside a cube of visible subvolumes (vdist >= 2) the run takes
         * the samples up to the cube's exit whole, without a scan */
        for (;;) {
            const size_t b = ((size_t)bc[2] * (size_t)c->by + bc[1]) * (size_t)c->bx + bc[0];
            if (bdist[b] || vdist[b] < 2)
                break;
            if (first < 0)
                first = k;
            const double ke = vv_floor_pos((t + vv_vray_cube_span(r, p, bc, vdist[b])) * inv_dt);
            klast = ke < k ? k : ke < cap ? ke : cap;
            k = klast + 1;
            if (k > cap)
                break;
            t = k * dt;
            vv_vray_point(r, t, p);
            (void)vv_vblock_of(c, p, bxm, bym, bzm, bc);
        }
        if (k <= cap) {
            /* the rest by each sample's subvolume, eight lanes at a time */
            const int n = (int)(cap - k) + 1;
            const uint64_t bits = visible_bits_avx2(c, bdist, r, k, dt, n);
            if (first < 0) {
                if (!bits) {
                    k += n;
                    continue;
                }
                const int f = __builtin_ctzll(bits);
                first = k + f;
                klast = first + trailing_ones64(bits >> f) - 1;
            } else {
                klast = k + trailing_ones64(bits) - 1;
            }
        }
        *kp = first;
        *klastp = klast;
        return 1;
    }
    *kp = k;
    return 0;
}

/* ---------------------------------------------------------------------- */
/* Projection: the MIP and MinIP march (project.c) */

#define PROJ_CHUNK 64 /* samples a chunk of vv_vproj_from_avx2 */
/* project_from's AVX2 path (project.c; 16-bit values): the ray is marched in chunks of
 * PROJ_CHUNK consecutive samples instead of one subvolume at a time. At
 * the first chunk, and after a chunk that had nothing to interpolate, the
 * leaps of project_from are tried at its first sample (the distance map,
 * then the group); then every sample's subvolume is found eight lanes at a
 * time and its extreme gathered, and only the runs of eight holding a
 * sample whose subvolume can beat the running extreme (as of the chunk's
 * start) are interpolated, each reduced in registers to its extreme and
 * the first lane holding it. A sample in a subvolume that cannot beat it
 * cannot change the result, so the value is project_from's, at its first
 * sample (the same arithmetic); only a ray that reaches @p stop may stop
 * later (at the end of a run of eight), with a value beyond the stop as
 * well. The traversal's cost per subvolume, which dominated magnified
 * views (a subvolume holds about eight samples at the usual half-voxel
 * step), becomes a few vector instructions per eight samples. 64 samples
 * a chunk measured faster than 16, 32, 128 or 256 (docs/rendering.md). */
__attribute__((target("avx2"))) float
vv_vproj_from_avx2(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, double dt, double k,
                   double kend, float sg, float floor0, float stop, int skipping,
                   double *tbest_out) {
    const float *bext = sg > 0 ? c->bmax : c->bmin, *gext = sg > 0 ? c->gmax : c->gmin;
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    float best = floor0;
    double tbest = r->t0;
    const __m256 zero = _mm256_setzero_ps(), vsg = _mm256_set1_ps(sg);
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    int dead = 1; /* the last chunk had nothing to interpolate (or this is the first) */
    while (k <= kend && best < stop) {
        if (skipping && dead) {
            float p[3];
            vv_vray_point(r, k * dt, p);
            int bc[3];
            const size_t b = vv_vproj_block(c, p, bc);
            if (pdist && pdist[b]) {
                k = vv_vproj_leap(r, p, bc, pdist[b], k, dt);
                continue;
            }
            if (sg * gext[vv_vproj_group(c, p)] <= best) {
                k = vv_vproj_after_cube(r, p, k, dt, gsize);
                continue;
            }
        }
        const int m = kend - k + 1 < PROJ_CHUNK ? (int)(kend - k + 1) : PROJ_CHUNK;
        uint64_t live = ~(uint64_t)0 >> (64 - (m + 7) / 8); /* runs of eight to interpolate */
        if (skipping) {
            const __m256 vbest = _mm256_set1_ps(best);
            live = 0;
            for (int s = 0; s < m; s += 8) {
                const __m256i idx = blocks8_avx2(c, r, k + s, dt); /* vv_vproj_block's */
                const __m256i in = _mm256_cmpgt_epi32(_mm256_set1_epi32(m - s), lane);
                const __m256 ext =
                    _mm256_mask_i32gather_ps(zero, bext, idx, _mm256_castsi256_ps(in), 4);
                const __m256 beat =
                    _mm256_and_ps(_mm256_cmp_ps(_mm256_mul_ps(vsg, ext), vbest, _CMP_GT_OQ),
                                  _mm256_castsi256_ps(in));
                if (_mm256_movemask_ps(beat))
                    live |= (uint64_t)1 << (s / 8);
            }
        }
        dead = !live;
        for (int s = 0; live && s < m && best < stop; s += 8) {
            if (!(live & ((uint64_t)1 << (s / 8))))
                continue;
            const int n = m - s < 8 ? m - s : 8;
            /* the run's largest sg * value, at its first lane: where a
             * sample-by-sample scan would leave the maximum */
            __m256 x = _mm256_mul_ps(vsg, values8_avx2(c, r, k + s, dt));
            if (n < 8)
                x = _mm256_blendv_ps(
                    _mm256_set1_ps(-INFINITY), x,
                    _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(n), lane)));
            __m256 h = _mm256_max_ps(x, _mm256_permute2f128_ps(x, x, 1));
            h = _mm256_max_ps(h, _mm256_shuffle_ps(h, h, _MM_SHUFFLE(1, 0, 3, 2)));
            h = _mm256_max_ps(h, _mm256_shuffle_ps(h, h, _MM_SHUFFLE(2, 3, 0, 1)));
            const float top = _mm256_cvtss_f32(h);
            if (top > best) {
                const int at =
                    __builtin_ctz((unsigned)_mm256_movemask_ps(_mm256_cmp_ps(x, h, _CMP_EQ_OQ)));
                best = top;
                tbest = (k + s + at) * dt;
            }
        }
        k += m;
    }
    *tbest_out = tbest;
    return best;
}

/* ---------------------------------------------------------------------- */
/* Classification: a chunk of samples (classify.c) */

/* classify_chunk (classify.c) for 16-bit values, eight samples at a time with AVX2
 * gathers and FMA; chosen at run time when the processor has them. The
 * arithmetic differs from the portable version only in the rounding of
 * fused multiply-adds, and one render uses one version throughout. */
__attribute__((target("avx2,fma"))) void
vv_vray_classify_avx2(const vv_vcache *c, const vv_vtables *ob, const vv_vray *r, double kfirst,
                      double dt, int m, size_t *cell, float *fx, float *fy, float *fz,
                      int32_t *entry, float *x) {
    float u[VV_VC_CHUNK + 8];
    for (int s = 0; s < m; s++)
        u[s] = (float)((kfirst + s) * dt - r->tb);
    for (int s = m; s < m + 8; s++)
        u[s] = u[m - 1]; /* padding lanes repeat the last sample */
    const __m256 ox = _mm256_set1_ps(r->o[0]), oy = _mm256_set1_ps(r->o[1]),
                 oz = _mm256_set1_ps(r->o[2]);
    const __m256 dx = _mm256_set1_ps(r->d[0]), dy = _mm256_set1_ps(r->d[1]),
                 dz = _mm256_set1_ps(r->d[2]);
    const __m256 offx = _mm256_set1_ps(r->off[0]), offy = _mm256_set1_ps(r->off[1]),
                 offz = _mm256_set1_ps(r->off[2]);
    const __m256i lo16 = _mm256_set1_epi32(0xFFFF);
    const __m256 llo = _mm256_set1_ps(ob->lut_lo), lsc = _mm256_set1_ps(ob->lut_scale);
    const __m256 lmax = _mm256_set1_ps((float)(VV_VC_LUT - 1)), fzero = _mm256_setzero_ps();
    for (int s = 0; s < m; s += 8) {
        const __m256 t = _mm256_loadu_ps(u + s);
        const __m256 px = _mm256_sub_ps(_mm256_fmadd_ps(t, dx, ox), offx),
                     py = _mm256_sub_ps(_mm256_fmadd_ps(t, dy, oy), offy),
                     pz = _mm256_sub_ps(_mm256_fmadd_ps(t, dz, oz), offz);
        __m256 wx, wy, wz;
        __m256i g00, g10, g01, g11;
        const __m256i o = cell_pairs_avx2(c, px, py, pz, &wx, &wy, &wz, &g00, &g10, &g01, &g11);
#define VV_PAIR_LERP(g)                                                                            \
    _mm256_fmadd_ps(_mm256_sub_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(g, 16)),                    \
                                  _mm256_cvtepi32_ps(_mm256_and_si256(g, lo16))),                  \
                    wx, _mm256_cvtepi32_ps(_mm256_and_si256(g, lo16)))
        const __m256 c00 = VV_PAIR_LERP(g00), c10 = VV_PAIR_LERP(g10);
        const __m256 c01 = VV_PAIR_LERP(g01), c11 = VV_PAIR_LERP(g11);
#undef VV_PAIR_LERP
        const __m256 c0 = _mm256_fmadd_ps(_mm256_sub_ps(c10, c00), wy, c00);
        const __m256 c1 = _mm256_fmadd_ps(_mm256_sub_ps(c11, c01), wy, c01);
        const __m256 val = _mm256_fmadd_ps(_mm256_sub_ps(c1, c0), wz, c0);
        __m256 li = _mm256_mul_ps(_mm256_sub_ps(val, llo), lsc);
        li = _mm256_min_ps(_mm256_max_ps(li, fzero), lmax);
        const __m256i e = _mm256_slli_epi32(_mm256_cvttps_epi32(li), 2);
        /* all eight lanes (s + 8 <= VV_VC_CHUNK); offsets >= 0, widened */
        _mm256_storeu_si256((__m256i *)(void *)(entry + s), e);
        _mm256_storeu_ps(fx + s, wx);
        _mm256_storeu_ps(fy + s, wy);
        _mm256_storeu_ps(fz + s, wz);
        _mm256_storeu_si256((__m256i *)(void *)(cell + s),
                            _mm256_cvtepi32_epi64(_mm256_castsi256_si128(o)));
        _mm256_storeu_si256((__m256i *)(void *)(cell + s + 4),
                            _mm256_cvtepi32_epi64(_mm256_extracti128_si256(o, 1)));
        if (x)
            _mm256_storeu_ps(x + s, li);
    }
}
#endif

int
vv_vc_have_avx2(void) {
#if VV_VC_HAVE_AVX2
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    return 0;
#endif
}
