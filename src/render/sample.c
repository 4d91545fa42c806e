/*
 * The sampling stage: building the per-volume voxel caches of sample.h (the
 * 16-bit or float values, the quantised gradients, the gradient magnitudes
 * and the subvolume min/max pyramid) and the sets that hold them. The
 * method is described in sample.h and docs/rendering.md ("Caching").
 */
#include "render/sample.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <unistd.h>

#include "core/internal.h"
#include "render/kernels_avx2.h"
#include "render/tf_tables.h"

static void
cache_release(vv_vcache *c) {
    vv_volume_free(c->vol);
    if (!c->q16_borrowed)
        free(c->q16);
    free(c->f32);
    free(c->nrm);
    free(c->gmag);
    free(c->bmin);
    free(c->bmax);
    free(c->gmin);
    free(c->gmax);
    vv_vtables_free(&c->tables);
    memset(c, 0, sizeof *c);
}

static int
is_integer_type(vv_voxel_type t) {
    return t != VV_F32 && t != VV_F64;
}

/* Fills one row of stored values from the source volume (clamping indices
 * of duplicated axes). A 16-bit value outside the volume's range is
 * clamped to it: a region's voxels carry the whole volume's range, which
 * a .vvb's header states, and a file whose range does not hold its voxels
 * made the cast to uint16_t undefined (found by fuzz_render). */
static void
fill_row(vv_vcache *c, const vv_volume *vol, int j, int k, size_t base) {
    int sj = j < vol->dims[1] ? j : vol->dims[1] - 1;
    int sk = k < vol->dims[2] ? k : vol->dims[2] - 1;
    const int snx = vol->dims[0];
    for (int i = 0; i < c->nx; i++) {
        const double x = vv_volume_get(vol, i < snx ? i : snx - 1, sj, sk);
        if (c->q16) {
            const double q = x - c->qoff;
            c->q16[base + (size_t)i] = (uint16_t)(q > 0 ? (q < 65535 ? q : 65535) : 0);
        } else
            c->f32[base + (size_t)i] = x == x ? (float)x : (float)vol->range[0]; /* NaN: minimum */
    }
}

/* vv_oct_encode_n: each g is divided by its |x|+|y|+|z| (divided rather
 * than scaled by the reciprocal, so that neither a tiny nor a huge g
 * under- or overflows), the lower half (z < 0) folded over the upper's
 * corners, x and y times 127; of the four roundings of the two codes, the
 * one whose decoded vector is nearest g (about half the angular error of
 * rounding to nearest), compared as cos^2 = (n.g)^2 / |n|^2 cross-
 * multiplied (every candidate is within 90 degrees of g): no division or
 * root but the scaling's. Four directions at a time with SSE2, without a
 * branch; the rest one at a time in the same arithmetic. */
void
vv_oct_encode_n(const float *gx, const float *gy, const float *gz, int n, int8_t *out) {
    int i = 0;
#ifdef __SSE2__
    const __m128 sign = _mm_set1_ps(-0.0f), lim = _mm_set1_ps(127.0f), one = _mm_set1_ps(1.0f);
    const __m128 zero = _mm_setzero_ps(), nlim = _mm_set1_ps(-127.0f);
    const __m128 fmax = _mm_set1_ps(FLT_MAX);
    for (; i + 4 <= n; i += 4) {
        const __m128 gx0 = _mm_loadu_ps(gx + i), gy0 = _mm_loadu_ps(gy + i);
        const __m128 gz0 = _mm_loadu_ps(gz + i);
        const __m128 l1 = _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, gx0), _mm_andnot_ps(sign, gy0)),
                                     _mm_andnot_ps(sign, gz0));
        /* no direction: 0, or not finite (NaN or infinite differences) */
        const __m128 flat = _mm_or_ps(_mm_cmpngt_ps(l1, zero), _mm_cmpnle_ps(l1, fmax));
        /* divided rather than scaled by 1 / l1, which overflows for a
         * denormal l1 */
        const __m128 dv = _mm_or_ps(_mm_andnot_ps(flat, l1), _mm_and_ps(flat, one));
        const __m128 x0 = _mm_div_ps(gx0, dv), y0 = _mm_div_ps(gy0, dv), z0 = _mm_div_ps(gz0, dv);
        __m128 x = _mm_mul_ps(x0, lim), y = _mm_mul_ps(y0, lim);
        /* the fold: (127 - |y|) sign(x), (127 - |x|) sign(y) where z < 0 */
        const __m128 fx = _mm_or_ps(_mm_sub_ps(lim, _mm_andnot_ps(sign, y)), _mm_and_ps(x, sign));
        const __m128 fy = _mm_or_ps(_mm_sub_ps(lim, _mm_andnot_ps(sign, x)), _mm_and_ps(y, sign));
        const __m128 low = _mm_cmplt_ps(z0, zero);
        x = _mm_or_ps(_mm_and_ps(low, fx), _mm_andnot_ps(low, x));
        y = _mm_or_ps(_mm_and_ps(low, fy), _mm_andnot_ps(low, y));
        /* floor (|x|, |y| <= 127) */
        const __m128 off = _mm_set1_ps(128.0f);
        const __m128 bx = _mm_sub_ps(_mm_cvtepi32_ps(_mm_cvttps_epi32(_mm_add_ps(x, off))), off);
        const __m128 by = _mm_sub_ps(_mm_cvtepi32_ps(_mm_cvttps_epi32(_mm_add_ps(y, off))), off);
        __m128 bu = bx, bv = by, bnum = _mm_set1_ps(-1.0f), bden = one;
        for (int d = 0; d < 4; d++) {
            const __m128 cu = _mm_max_ps(_mm_min_ps(d & 1 ? _mm_add_ps(bx, one) : bx, lim), nlim);
            const __m128 cv = _mm_max_ps(_mm_min_ps(d >> 1 ? _mm_add_ps(by, one) : by, lim), nlim);
            const __m128 nz =
                _mm_sub_ps(_mm_sub_ps(lim, _mm_andnot_ps(sign, cu)), _mm_andnot_ps(sign, cv));
            const __m128 t = _mm_max_ps(_mm_sub_ps(zero, nz), zero);
            const __m128 nx = _mm_sub_ps(cu, _mm_or_ps(t, _mm_and_ps(cu, sign)));
            const __m128 ny = _mm_sub_ps(cv, _mm_or_ps(t, _mm_and_ps(cv, sign)));
            const __m128 dot =
                _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, x0), _mm_mul_ps(ny, y0)), _mm_mul_ps(nz, z0));
            const __m128 num = _mm_mul_ps(dot, dot);
            const __m128 den =
                _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, nx), _mm_mul_ps(ny, ny)), _mm_mul_ps(nz, nz));
            const __m128 better = _mm_cmpgt_ps(_mm_mul_ps(num, bden), _mm_mul_ps(bnum, den));
            bu = _mm_or_ps(_mm_and_ps(better, cu), _mm_andnot_ps(better, bu));
            bv = _mm_or_ps(_mm_and_ps(better, cv), _mm_andnot_ps(better, bv));
            bnum = _mm_or_ps(_mm_and_ps(better, num), _mm_andnot_ps(better, bnum));
            bden = _mm_or_ps(_mm_and_ps(better, den), _mm_andnot_ps(better, bden));
        }
        const __m128 zc = _mm_set1_ps((float)VV_OCT_ZERO);
        bu = _mm_or_ps(_mm_and_ps(flat, zc), _mm_andnot_ps(flat, bu));
        bv = _mm_or_ps(_mm_and_ps(flat, zc), _mm_andnot_ps(flat, bv));
        /* interleave u, v and pack to bytes */
        const __m128i uv16 = _mm_packs_epi32(_mm_cvtps_epi32(_mm_unpacklo_ps(bu, bv)),
                                             _mm_cvtps_epi32(_mm_unpackhi_ps(bu, bv)));
        _mm_storel_epi64((__m128i *)(void *)(out + 2 * i), _mm_packs_epi16(uv16, uv16));
    }
#endif
    for (; i < n; i++) {
        const float l1 = fabsf(gx[i]) + fabsf(gy[i]) + fabsf(gz[i]);
        if (!(l1 > 0 && l1 <= FLT_MAX)) { /* 0, NaN or infinite: no direction */
            out[2 * i] = out[2 * i + 1] = VV_OCT_ZERO;
            continue;
        }
        const float x0 = gx[i] / l1, y0 = gy[i] / l1, z0 = gz[i] / l1;
        float x = x0 * 127.0f, y = y0 * 127.0f;
        if (z0 < 0) {
            const float fx = copysignf(127.0f - fabsf(y), x), fy = copysignf(127.0f - fabsf(x), y);
            x = fx;
            y = fy;
        }
        const float bx = (float)((int)(x + 128.0f) - 128), by = (float)((int)(y + 128.0f) - 128);
        float best_num = -1, best_den = 1;
        for (int d = 0; d < 4; d++) {
            float u = bx + (float)(d & 1), v = by + (float)(d >> 1);
            u = u > 127 ? 127 : u < -127 ? -127 : u;
            v = v > 127 ? 127 : v < -127 ? -127 : v;
            float p[3];
            vv_oct_unfold(u, v, p);
            const float dot = p[0] * x0 + p[1] * y0 + p[2] * z0;
            const float num = dot * dot, den = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
            if (num * best_den > best_num * den) {
                best_num = num;
                best_den = den;
                out[2 * i] = (int8_t)u;
                out[2 * i + 1] = (int8_t)v;
            }
        }
    }
}

/* The central differences of voxels r0 .. r0 + m - 1 of the row at base
 * (rows y0, y1, z0, z1 its neighbours, fy and fz the reciprocals of their
 * distances), fill_gradients's arithmetic: the 16-bit values' interior
 * without a branch, so that the compiler vectorises it. */
static void
differences_run(const vv_vcache *c, size_t base, size_t y0, size_t y1, size_t z0, size_t z1,
                float fy, float fz, int r0, int m, float *gx, float *gy, float *gz) {
    const int nx = c->nx;
    int q = 0;
    if (c->q16) {
        const uint16_t *v = c->q16, *vc = v + base, *vy0 = v + y0, *vy1 = v + y1;
        const uint16_t *vz0 = v + z0, *vz1 = v + z1;
        /* the interior, i in 1 .. nx - 2: (v[i+1] - v[i-1]) / 2 exactly */
        const int qa = r0 == 0 ? 1 : 0, qb = r0 + m > nx - 1 ? nx - 1 - r0 : m;
        for (q = 0; q < qa; q++) {
            const int i = r0 + q, i1 = i < nx - 1 ? i + 1 : i;
            gx[q] = ((float)vc[i1] - (float)vc[i]) / (float)(i1 - i);
            gy[q] = ((float)vy1[i] - (float)vy0[i]) * fy;
            gz[q] = ((float)vz1[i] - (float)vz0[i]) * fz;
        }
        for (q = qa; q < qb; q++) {
            const int i = r0 + q;
            gx[q] = ((float)vc[i + 1] - (float)vc[i - 1]) * 0.5f;
            gy[q] = ((float)vy1[i] - (float)vy0[i]) * fy;
            gz[q] = ((float)vz1[i] - (float)vz0[i]) * fz;
        }
    }
    for (; q < m; q++) {
        const int i = r0 + q;
        const int i0 = i > 0 ? i - 1 : i, i1 = i < nx - 1 ? i + 1 : i;
        gx[q] = (vv_vcache_value(c, base + (size_t)i1) - vv_vcache_value(c, base + (size_t)i0)) /
                (float)(i1 - i0);
        gy[q] = (vv_vcache_value(c, y1 + (size_t)i) - vv_vcache_value(c, y0 + (size_t)i)) * fy;
        gz[q] = (vv_vcache_value(c, z1 + (size_t)i) - vv_vcache_value(c, z0 + (size_t)i)) * fz;
    }
}

/* Unit gradients by central differences in index units, one-sided at the
 * borders, in octahedral code (vv_oct_encode_n, with AVX2 where the
 * processor has it: the same codes), a run of a row at a time. */
static void
fill_gradients(vv_vcache *c) {
    enum { RUN = 256 };
    const int nx = c->nx, ny = c->ny, nz = c->nz;
    void (*encode)(const float *, const float *, const float *, int, int8_t *) = vv_oct_encode_n;
#if VV_VC_HAVE_AVX2
    if (vv_vc_have_avx2())
        encode = vv_oct_encode_n_avx2;
#endif
#pragma omp parallel for schedule(static) if (VV_VC_PARALLEL(nx, ny, nz))
    for (int k = 0; k < nz; k++) {
        float gx[RUN], gy[RUN], gz[RUN];
        for (int j = 0; j < ny; j++) {
            const size_t base = (size_t)k * c->sz + (size_t)j * c->sy;
            const int j0 = j > 0 ? j - 1 : j, j1 = j < ny - 1 ? j + 1 : j;
            const int k0 = k > 0 ? k - 1 : k, k1 = k < nz - 1 ? k + 1 : k;
            const float fy = 1.0f / (float)(j1 - j0), fz = 1.0f / (float)(k1 - k0);
            const size_t y0 = (size_t)k * c->sz + (size_t)j0 * c->sy;
            const size_t y1 = (size_t)k * c->sz + (size_t)j1 * c->sy;
            const size_t z0 = (size_t)k0 * c->sz + (size_t)j * c->sy;
            const size_t z1 = (size_t)k1 * c->sz + (size_t)j * c->sy;
            for (int r0 = 0; r0 < nx; r0 += RUN) {
                const int m = nx - r0 < RUN ? nx - r0 : RUN;
                differences_run(c, base, y0, y1, z0, z1, fy, fz, r0, m, gx, gy, gz);
                encode(gx, gy, gz, m, c->nrm + 2 * (base + (size_t)r0));
            }
        }
    }
}

vv_status
vv_vcache_need_gmag(vv_vcache *c) {
    if (c->gmag)
        return VV_OK;
    vv_mat4 m = vv_volume_index_to_world(c->vol);
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(m, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "singular index-to-world matrix");
    float g2w[3][3];
    for (int r = 0; r < 3; r++)
        for (int cc = 0; cc < 3; cc++)
            g2w[r][cc] = (float)inv.m[cc][r];
    const size_t n = c->sz * (size_t)c->nz;
    uint64_t left = vv_memory_available();
    if ((uint64_t)n * sizeof(float) > left)
        return vv_error_set(VV_ERR_LIMIT,
                            "gradient magnitudes of %zu voxels need %llu bytes, more than the %llu "
                            "bytes of memory left (the machine's or the memory cgroup's)",
                            n, (unsigned long long)(n * sizeof(float)), (unsigned long long)left);
    float *gm = malloc(n * sizeof *gm);
    if (!gm)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for gradient magnitudes of %zu voxels", n);
    /* the volume's own dims: a duplicated single-voxel axis has no gradient */
    const int dims[3] = {c->vol->dims[0], c->vol->dims[1], c->vol->dims[2]};
    const int nx = c->nx, ny = c->ny, nz = c->nz;
#pragma omp parallel for schedule(static) if (VV_VC_PARALLEL(nx, ny, nz))
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                const int idx[3] = {i, j, k};
                const size_t st[3] = {1, c->sy, c->sz};
                const size_t at = (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
                float g[3];
                for (int a = 0; a < 3; a++) {
                    const int lo = idx[a] > 0 ? idx[a] - 1 : idx[a];
                    const int hi = idx[a] < dims[a] - 1 ? idx[a] + 1 : idx[a];
                    if (hi <= lo || idx[a] >= dims[a]) {
                        g[a] = 0;
                        continue;
                    }
                    const size_t base = at - (size_t)idx[a] * st[a];
                    g[a] = (vv_vcache_value(c, base + (size_t)hi * st[a]) -
                            vv_vcache_value(c, base + (size_t)lo * st[a])) /
                           (float)(hi - lo);
                }
                float w[3];
                for (int r = 0; r < 3; r++)
                    w[r] = g2w[r][0] * g[0] + g2w[r][1] * g[1] + g2w[r][2] * g[2];
                gm[at] = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            }
    c->gmag = gm;
    return VV_OK;
}

/* Min and max of the stored values of every subvolume (its cells' corners). */
static void
fill_minmax(vv_vcache *c) {
    const int nx = c->nx, ny = c->ny, nz = c->nz;
#pragma omp parallel for schedule(static) collapse(2) if (VV_VC_PARALLEL(nx, ny, nz))
    for (int bk = 0; bk < c->bz; bk++)
        for (int bj = 0; bj < c->by; bj++)
            for (int bi = 0; bi < c->bx; bi++) {
                float lo = INFINITY, hi = -INFINITY;
                int k1 = bk * VV_VC_BLOCK + VV_VC_BLOCK, j1 = bj * VV_VC_BLOCK + VV_VC_BLOCK,
                    i1 = bi * VV_VC_BLOCK + VV_VC_BLOCK;
                k1 = k1 > nz - 1 ? nz - 1 : k1;
                j1 = j1 > ny - 1 ? ny - 1 : j1;
                i1 = i1 > nx - 1 ? nx - 1 : i1;
                for (int k = bk * VV_VC_BLOCK; k <= k1; k++)
                    for (int j = bj * VV_VC_BLOCK; j <= j1; j++) {
                        size_t base = (size_t)k * c->sz + (size_t)j * c->sy;
                        for (int i = bi * VV_VC_BLOCK; i <= i1; i++) {
                            float x = vv_vcache_value(c, base + (size_t)i);
                            lo = x < lo ? x : lo;
                            hi = x > hi ? x : hi;
                        }
                    }
                size_t b = ((size_t)bk * (size_t)c->by + (size_t)bj) * (size_t)c->bx + (size_t)bi;
                c->bmin[b] = lo;
                c->bmax[b] = hi;
            }
    /* the groups of subvolumes: the pyramid's second level */
    for (int gk = 0; gk < c->gz; gk++)
        for (int gj = 0; gj < c->gy; gj++)
            for (int gi = 0; gi < c->gx; gi++) {
                float lo = INFINITY, hi = -INFINITY;
                for (int bk = gk * VV_VC_GROUP; bk < (gk + 1) * VV_VC_GROUP && bk < c->bz; bk++)
                    for (int bj = gj * VV_VC_GROUP; bj < (gj + 1) * VV_VC_GROUP && bj < c->by; bj++)
                        for (int bi = gi * VV_VC_GROUP; bi < (gi + 1) * VV_VC_GROUP && bi < c->bx;
                             bi++) {
                            size_t b = ((size_t)bk * (size_t)c->by + (size_t)bj) * (size_t)c->bx +
                                       (size_t)bi;
                            lo = c->bmin[b] < lo ? c->bmin[b] : lo;
                            hi = c->bmax[b] > hi ? c->bmax[b] : hi;
                        }
                size_t g = ((size_t)gk * (size_t)c->gy + (size_t)gj) * (size_t)c->gx + (size_t)gi;
                c->gmin[g] = lo;
                c->gmax[g] = hi;
            }
}

static vv_status
cache_build(const vv_vcache_set *s, vv_vcache *c, vv_volume *vol) {
    memset(c, 0, sizeof *c);
    c->nx = vol->dims[0] < 2 ? 2 : vol->dims[0];
    c->ny = vol->dims[1] < 2 ? 2 : vol->dims[1];
    c->nz = vol->dims[2] < 2 ? 2 : vol->dims[2];
    c->sy = (size_t)c->nx;
    c->sz = (size_t)c->nx * (size_t)c->ny;
    const size_t n = c->sz * (size_t)c->nz;
    const int ny = c->ny, nz = c->nz;
    const int whole = c->nx == vol->dims[0] && c->ny == vol->dims[1] && c->nz == vol->dims[2];
    if (vol->type == VV_U16 && whole) {
        /* the volume's own array serves: no copy of a large volume */
        c->qoff = 0;
        c->q16 = vol->data;
        c->q16_borrowed = 1;
    } else {
        /* the renderers' copy: refused when the memory left cannot hold it
         * (under a cgroup's limit the allocation would succeed and the OOM
         * killer end the process when the copy is filled) */
        int q = is_integer_type(vol->type) && vol->range[1] - vol->range[0] <= 65535.0;
        uint64_t bytes = (uint64_t)n * (q ? sizeof *c->q16 : sizeof *c->f32);
        uint64_t left = vv_memory_available();
        if (bytes > left)
            return vv_error_set(VV_ERR_LIMIT,
                                "the renderers' copy of a %d x %d x %d volume needs %llu bytes, "
                                "more than the %llu bytes of memory left (the machine's or the "
                                "memory cgroup's)",
                                vol->dims[0], vol->dims[1], vol->dims[2], (unsigned long long)bytes,
                                (unsigned long long)left);
        if (q) {
            c->qoff = vol->range[0];
            c->q16 = malloc(n * sizeof *c->q16);
        } else {
            c->f32 = malloc(n * sizeof *c->f32);
        }
    }
    c->bx = (c->nx - 2) / VV_VC_BLOCK + 1;
    c->by = (c->ny - 2) / VV_VC_BLOCK + 1;
    c->bz = (c->nz - 2) / VV_VC_BLOCK + 1;
    size_t nb = (size_t)c->bx * (size_t)c->by * (size_t)c->bz;
    c->bmin = malloc(nb * sizeof(float));
    c->bmax = malloc(nb * sizeof(float));
    c->gx = (c->bx + VV_VC_GROUP - 1) / VV_VC_GROUP;
    c->gy = (c->by + VV_VC_GROUP - 1) / VV_VC_GROUP;
    c->gz = (c->bz + VV_VC_GROUP - 1) / VV_VC_GROUP;
    size_t ng = (size_t)c->gx * (size_t)c->gy * (size_t)c->gz;
    c->gmin = malloc(ng * sizeof(float));
    c->gmax = malloc(ng * sizeof(float));
    if ((!c->q16 && !c->f32) || !c->bmin || !c->bmax || !c->gmin || !c->gmax) {
        cache_release(c);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %zu voxels", n);
    }
    if (!c->q16_borrowed) {
#pragma omp parallel for schedule(static) if (VV_VC_PARALLEL(c->nx, c->ny, c->nz))
        for (int k = 0; k < nz; k++)
            for (int j = 0; j < ny; j++)
                fill_row(c, vol, j, k, (size_t)k * c->sz + (size_t)j * c->sy);
    }
    (void)s;
    fill_minmax(c);
    c->vol = vv_volume_ref(vol);
    c->modified = vol->modified;
    return VV_OK;
}

void
vv_vcache_need_normals(const vv_vcache_set *s, vv_vcache *c) {
    if (c->nrm || c->nrm_tried)
        return;
    c->nrm_tried = 1;
    const size_t n = c->sz * (size_t)c->nz;
    /* within the set's budget and half of the memory left now (a cgroup's
     * limit included): the cache is an optimisation, never a reason for the
     * OOM killer */
    uint64_t left = vv_memory_available();
    if ((uint64_t)n * 2 <= s->gradient_budget && (uint64_t)n * 2 <= left / 2)
        c->nrm = malloc(n * 2); /* NULL: gradients on the fly */
    if (c->nrm)
        fill_gradients(c);
}

void
vv_vcache_set_init(vv_vcache_set *s) {
    memset(s, 0, sizeof *s);
    vv_vcache_set_default_budget(s);
}

void
vv_vcache_set_default_budget(vv_vcache_set *s) {
    /* cached gradients take 2 bytes a voxel: allow them up to a quarter of
     * physical memory (at most 8 GiB); beyond, gradients are computed on the
     * fly from the values */
    uint64_t budget = (uint64_t)8 << 30;
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    if (pages > 0 && page > 0 && (uint64_t)pages * (uint64_t)page / 4 < budget)
        budget = (uint64_t)pages * (uint64_t)page / 4;
    s->gradient_budget = budget;
}

void
vv_vcache_set_clear(vv_vcache_set *s) {
    for (int i = 0; i < s->n; i++)
        cache_release(&s->cache[i]);
    s->n = 0;
}

void
vv_vcache_set_prune(vv_vcache_set *s, const vv_world *w) {
    for (int i = 0; i < s->n;) {
        int used = 0;
        for (int j = 0; j < w->n_objects; j++) {
            const vv_object *o = w->objects[j];
            used |= o && o->volume == s->cache[i].vol;
            for (int c = 0; o && c < o->n_channels; c++)
                used |= o->channels[c].volume == s->cache[i].vol;
        }
        if (!used) {
            cache_release(&s->cache[i]);
            s->cache[i] = s->cache[--s->n];
        } else {
            i++;
        }
    }
}

vv_status
vv_vcache_get(vv_vcache_set *s, vv_volume *vol, vv_vcache **out) {
    s->clock++;
    for (int i = 0; i < s->n; i++)
        if (s->cache[i].vol == vol) {
            if (s->cache[i].modified != vol->modified) {
                cache_release(&s->cache[i]);
                vv_status st = cache_build(s, &s->cache[i], vol);
                if (st != VV_OK) {
                    s->cache[i] = s->cache[--s->n];
                    return st;
                }
            }
            s->cache[i].last_used = s->clock;
            *out = &s->cache[i];
            return VV_OK;
        }
    int slot = s->n;
    if (slot == VV_VC_MAX) {
        slot = 0;
        for (int i = 1; i < s->n; i++)
            if (s->cache[i].last_used < s->cache[slot].last_used)
                slot = i;
        cache_release(&s->cache[slot]);
    } else {
        s->n++;
    }
    vv_status st = cache_build(s, &s->cache[slot], vol);
    if (st != VV_OK) {
        s->cache[slot] = s->cache[--s->n];
        return st;
    }
    s->cache[slot].last_used = s->clock;
    *out = &s->cache[slot];
    return VV_OK;
}
