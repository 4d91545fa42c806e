/*
 * The sampling stage of the volume renderers (raycast, raytrace, splat;
 * internal, not part of the public API): the per-volume voxel cache and the
 * trilinear sampling of its values, gradients and gradient magnitudes.
 *
 * Per volume, a cache holds the voxels as 16-bit offsets from the minimum
 * when the data are integers spanning at most 65535 (exact, and half the
 * memory traffic of float), else as float; all values inside the renderers
 * ("stored units") are real value - qoff. The unit gradient direction of
 * every voxel (central differences, computed once) is stored as a 16-bit
 * octahedral code (vv_oct_decode: 2 bytes a voxel, where 3 x int8 took 3)
 * in a separate array, touched only where a sample is shaded, and every
 * subvolume of 4^3 cells has the min/max of its stored values (the PARC
 * grid of the VolVis paper's Navigator, section 4; computed from the stored
 * values rather than with vv_minmax_grid_build so that it agrees exactly
 * with the samples: NaN voxels are stored as the minimum, a single-voxel
 * axis is held twice).
 *
 * The cache also keeps the last transfer-function tables built for its
 * volume (tf_tables.h) while nothing they depend on changes. Values are
 * interpolated trilinearly and normals are gradients by central
 * differences, as in Levoy's volume ray casting ("Display of surfaces from
 * volume data", IEEE CG&A 1988).
 *
 * Not thread-safe while building; the sampling functions below only read
 * and may run on many threads. docs/rendering.md describes the method.
 */
#ifndef VV_RENDER_SAMPLE_H
#define VV_RENDER_SAMPLE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "render/tf_tables.h"
#include "volvis/render.h"

#define VV_VC_BLOCK 4 /* subvolume side in cells */
/* Whether a cache of nx x ny x nz samples is filled on the frame's threads:
 * a small one (a brick of the out-of-core drivers) on the caller's alone,
 * whose cost a team's wake-up and spinning wait would outweigh (the spin
 * takes the cores a GPU driver's threads draw on: lavapipe). */
#define VV_VC_PARALLEL(nx, ny, nz) ((size_t)(nx) * (size_t)(ny) * (size_t)(nz) >= ((size_t)1 << 19))
#define VV_VC_GROUP 4 /* subvolumes per side of a group (the pyramid's second level) */
/* cached volumes per renderer: >= the objects of one render, so none in use
 * is evicted */
#define VV_VC_MAX 64
#define VV_VC_CHUNK 64 /* samples classified at a time (vv_vray_classify); at most 64 */
#if defined(__x86_64__) && defined(__GNUC__)
#define VV_VC_HAVE_AVX2 1
#else
#define VV_VC_HAVE_AVX2 0
#endif

/* Everything derived from one volume that does not depend on the TF. */
typedef struct vv_vcache {
    vv_volume *vol; /* reference held */
    uint64_t modified;
    int nx, ny, nz;     /* cached grid (each >= 2; a 1-voxel axis is duplicated) */
    size_t sy, sz;      /* strides in voxels */
    uint16_t *q16;      /* values as uint16 (real = q + qoff), or NULL */
    int q16_borrowed;   /* q16 is the volume's own u16 array (qoff 0), not a copy */
    float *f32;         /* values as float (qoff = 0), or NULL */
    double qoff;        /* offset of stored values */
    int8_t *nrm;        /* unit gradients (index space) in octahedral code (vv_oct_decode),
                           2 bytes a voxel (u, v), or NULL: on the fly */
    int nrm_tried;      /* vv_vcache_need_normals ran (nrm NULL: over the budget) */
    float *gmag;        /* gradient magnitudes per voxel (vv_vcache_need_gmag), or NULL */
    int bx, by, bz;     /* subvolume grid */
    float *bmin, *bmax; /* per subvolume, stored units */
    /* the next level of the min/max pyramid: per group of VV_VC_GROUP^3
     * subvolumes (cubes of VV_VC_BLOCK * VV_VC_GROUP cells), the min/max of
     * its subvolumes' */
    int gx, gy, gz;
    float *gmin, *gmax;
    /* the last object tables built for this volume */
    int tables_valid;
    vv_vtables_key key;
    vv_vtables tables;
    uint64_t tables_frame; /* the frame that last borrowed them */
    uint64_t last_used;
} vv_vcache;

/* The caches of one renderer. */
typedef struct vv_vcache_set {
    vv_vcache cache[VV_VC_MAX];
    int n;
    uint64_t clock;
    uint64_t frame;           /* renders so far (vv_vcache_set_begin_frame) */
    uint64_t gradient_budget; /* bytes allowed for one volume's cached gradients */
} vv_vcache_set;

/* Empty set; gradients allowed up to a quarter of physical memory, at most
 * 8 GiB. */
void vv_vcache_set_init(vv_vcache_set *s);
/* The gradient budget of a new set (the option value "auto"). */
void vv_vcache_set_default_budget(vv_vcache_set *s);
/* Releases every cached volume (the set stays usable). */
void vv_vcache_set_clear(vv_vcache_set *s);
/* Drops the cached volumes that no object of @p w shows. */
void vv_vcache_set_prune(vv_vcache_set *s, const vv_world *w);
/* The cache of @p vol, built (or rebuilt when the volume was modified) on
 * demand; the least recently used one is evicted when the set is full.
 * Errors: VV_ERR_NOMEM; VV_ERR_LIMIT when the copy of the values is more
 * than the memory left (vv_memory_available: a cgroup's limit included). */
vv_status vv_vcache_get(vv_vcache_set *s, vv_volume *vol, vv_vcache **out);

/* Builds c->nrm once, when a shaded object first needs it and it fits
 * @p s's gradient budget and half of the memory left (else, or without memory, it stays NULL and
 * gradients are computed at each sample: slower, never wrong). A volume
 * shown only as MIP, MinIP or X-ray never pays for it. */
void vv_vcache_need_normals(const vv_vcache_set *s, vv_vcache *c);

/* The octahedral codes (vv_oct_decode) of the n directions (gx[i], gy[i],
 * gz[i]) (any length, index space) into out (2 n bytes: u, v for each),
 * VV_OCT_ZERO where the direction is zero; the rounding of the two codes
 * is the one whose decoded vector is nearest the direction (Cigolle et
 * al., JCGT 2014, "precise" encoding). Thread-safe; no errors. */
void vv_oct_encode_n(const float *gx, const float *gy, const float *gz, int n, int8_t *out);

/* Builds c->gmag once: the gradient magnitude of every cached voxel, in
 * data units per world unit of the volume's own coordinates (central
 * differences, one-sided at the faces, mapped by the inverse transpose of
 * the volume's index-to-world matrix; vv_histogram2d_compute's definition).
 * Errors: VV_ERR_NOMEM, VV_ERR_LIMIT (more than the memory left),
 * VV_ERR_INVALID (singular matrix). */
vv_status vv_vcache_need_gmag(vv_vcache *c);

static inline float
vv_lerpf(float a, float b, float t) {
    return a + (b - a) * t;
}

static inline float
vv_vcache_value(const vv_vcache *c, size_t idx) {
    return c->q16 ? (float)c->q16[idx] : c->f32[idx];
}

/* Cell and fractions of index-space point p, clamped so that the cell's far
 * corner is inside the cached grid. */
static inline size_t
vv_vcache_cell_of(const vv_vcache *c, const float p[3], float f[3]) {
    float x = p[0], y = p[1], z = p[2];
    x = x < 0 ? 0 : x;
    y = y < 0 ? 0 : y;
    z = z < 0 ? 0 : z;
    int i = (int)x, j = (int)y, k = (int)z;
    if (i > c->nx - 2)
        i = c->nx - 2;
    if (j > c->ny - 2)
        j = c->ny - 2;
    if (k > c->nz - 2)
        k = c->nz - 2;
    f[0] = x - (float)i;
    f[1] = y - (float)j;
    f[2] = z - (float)k;
    f[0] = f[0] > 1 ? 1 : f[0];
    f[1] = f[1] > 1 ? 1 : f[1];
    f[2] = f[2] > 1 ? 1 : f[2];
    return (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
}

/* vv_vcache_cell_of for points inside the grid box (a clipped ray), up to
 * float rounding: no float clamps, only the integer clamps that keep every
 * read inside the grid. A point a rounding error outside extrapolates by
 * that error, which is harmless. */
static inline size_t
vv_vcache_cell_in(const vv_vcache *c, const float p[3], float f[3]) {
    int i = (int)p[0], j = (int)p[1], k = (int)p[2];
    i = i < c->nx - 2 ? i : c->nx - 2;
    j = j < c->ny - 2 ? j : c->ny - 2;
    k = k < c->nz - 2 ? k : c->nz - 2;
    i = i > 0 ? i : 0;
    j = j > 0 ? j : 0;
    k = k > 0 ? k : 0;
    f[0] = p[0] - (float)i;
    f[1] = p[1] - (float)j;
    f[2] = p[2] - (float)k;
    return (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
}

/* Trilinear value in the cell at offset o with fractions f. */
static inline float
vv_vcache_value_at(const vv_vcache *c, size_t o, const float f[3]) {
    const size_t sy = c->sy, sz = c->sz;
    float c00, c10, c01, c11;
#ifdef __SSE2__
    if (c->q16) {
        /* the four x-pairs of the cell in one register, both corners of each
         * pair lerped at once */
        const uint16_t *v = c->q16 + o;
        int32_t a0, a1, a2, a3;
        memcpy(&a0, v, 4);
        memcpy(&a1, v + sy, 4);
        memcpy(&a2, v + sz, 4);
        memcpy(&a3, v + sz + sy, 4);
        const __m128i x = _mm_set_epi32(a3, a2, a1, a0);
        const __m128 lo = _mm_cvtepi32_ps(_mm_and_si128(x, _mm_set1_epi32(0xFFFF)));
        const __m128 hi = _mm_cvtepi32_ps(_mm_srli_epi32(x, 16));
        const __m128 cx = _mm_add_ps(lo, _mm_mul_ps(_mm_sub_ps(hi, lo), _mm_set1_ps(f[0])));
        /* cx = (c00, c10, c01, c11): lerp (c00, c01) towards (c10, c11) in y */
        const __m128 y0 = _mm_shuffle_ps(cx, cx, _MM_SHUFFLE(2, 0, 2, 0));
        const __m128 y1 = _mm_shuffle_ps(cx, cx, _MM_SHUFFLE(3, 1, 3, 1));
        const __m128 cy = _mm_add_ps(y0, _mm_mul_ps(_mm_sub_ps(y1, y0), _mm_set1_ps(f[1])));
        const float z0 = _mm_cvtss_f32(cy);
        const float z1 = _mm_cvtss_f32(_mm_shuffle_ps(cy, cy, _MM_SHUFFLE(1, 1, 1, 1)));
        return vv_lerpf(z0, z1, f[2]);
    }
#endif
    if (c->q16) {
        const uint16_t *v = c->q16 + o;
        c00 = vv_lerpf(v[0], v[1], f[0]);
        c10 = vv_lerpf(v[sy], v[sy + 1], f[0]);
        c01 = vv_lerpf(v[sz], v[sz + 1], f[0]);
        c11 = vv_lerpf(v[sz + sy], v[sz + sy + 1], f[0]);
    } else {
        const float *v = c->f32 + o;
        c00 = vv_lerpf(v[0], v[1], f[0]);
        c10 = vv_lerpf(v[sy], v[sy + 1], f[0]);
        c01 = vv_lerpf(v[sz], v[sz + 1], f[0]);
        c11 = vv_lerpf(v[sz + sy], v[sz + sy + 1], f[0]);
    }
    return vv_lerpf(vv_lerpf(c00, c10, f[1]), vv_lerpf(c01, c11, f[1]), f[2]);
}

/* Trilinear value at index point p (clamped to the grid). */
static inline float
vv_vcache_sample(const vv_vcache *c, const float p[3]) {
    float f[3];
    size_t o = vv_vcache_cell_of(c, p, f);
    return vv_vcache_value_at(c, o, f);
}

typedef float vv_v4f __attribute__((vector_size(16)));

/* The cached gradients' code for a voxel whose gradient is zero: no
 * direction, contributes nothing to an interpolated gradient. */
#define VV_OCT_ZERO (-128)

/* Unit vector of octahedral code (u, v) (Meyer et al., "On floating-point
 * normal vectors", EGSR 2010; Cigolle et al., "A survey of efficient
 * representations for independent unit vectors", JCGT 2014): the point
 * (u, v) / 127 of the square [-1, 1]^2 is the octahedron |x|+|y|+|z| = 1
 * unfolded (the lower half folded over the upper's corners), projected
 * onto the sphere. Zero vector for VV_OCT_ZERO. */
/* The octahedron's point (n[0], n[1], n[2]), |x|+|y|+|z| = 127, of code
 * (u, v) in [-127, 127]^2, not normalised: where z would be negative the
 * square's corner folds back over the lower half. */
static inline void
vv_oct_unfold(float u, float v, float n[3]) {
    const float z = 127.0f - (u < 0 ? -u : u) - (v < 0 ? -v : v);
    const float t = z < 0 ? -z : 0;
    n[0] = u + (u >= 0 ? -t : t);
    n[1] = v + (v >= 0 ? -t : t);
    n[2] = z;
}

static inline vv_v4f
vv_oct_decode(int u, int v) {
    if (u == VV_OCT_ZERO) {
        vv_v4f r = {0, 0, 0, 0};
        return r;
    }
    float p[3];
    vv_oct_unfold((float)u, (float)v, p);
    const float r = 1.0f / sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    vv_v4f n = {p[0] * r, p[1] * r, p[2] * r, 0};
    return n;
}

/* The cached unit gradient of voxel idx as 4 floats (x, y, z, 0); zero
 * where the gradient is. */
static inline vv_v4f
vv_vcache_normal(const vv_vcache *c, size_t idx) {
    return vv_oct_decode(c->nrm[2 * idx], c->nrm[2 * idx + 1]);
}

#ifdef __SSE2__
/* vv_oct_decode of four codes, the lanes of u and v (int32). */
static inline void
vv_oct_decode4(__m128i u, __m128i v, __m128 *x, __m128 *y, __m128 *z) {
    const __m128 sign = _mm_set1_ps(-0.0f), zero = _mm_setzero_ps();
    const __m128 none = _mm_castsi128_ps(_mm_cmpeq_epi32(u, _mm_set1_epi32(VV_OCT_ZERO)));
    __m128 fu = _mm_cvtepi32_ps(u), fv = _mm_cvtepi32_ps(v);
    const __m128 fz = _mm_sub_ps(_mm_sub_ps(_mm_set1_ps(127.0f), _mm_andnot_ps(sign, fu)),
                                 _mm_andnot_ps(sign, fv));
    const __m128 t = _mm_max_ps(_mm_sub_ps(zero, fz), zero);
    fu = _mm_sub_ps(fu, _mm_or_ps(t, _mm_and_ps(fu, sign)));
    fv = _mm_sub_ps(fv, _mm_or_ps(t, _mm_and_ps(fv, sign)));
    const __m128 len2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(fu, fu), _mm_mul_ps(fv, fv)), _mm_mul_ps(fz, fz));
    const __m128 r = _mm_andnot_ps(none, _mm_rsqrt_ps(len2));
    *x = _mm_mul_ps(fu, r);
    *y = _mm_mul_ps(fv, r);
    *z = _mm_mul_ps(fz, r);
}
#endif

/* Index-space gradient direction (not normalised) in the cell at offset o
 * with fractions f: trilinear interpolation of the cached unit gradients
 * of its eight corners. Needs c->nrm. */
static inline void
vv_vcache_gradient_at(const vv_vcache *c, size_t o, const float f[3], float g[3]) {
    const size_t sy = c->sy, sz = c->sz;
#ifdef __SSE2__
    /* the cell's four x-pairs of codes in one register (lane r: row r of
     * (j, k), (j+1, k), (j, k+1), (j+1, k+1); bytes u0 v0 u1 v1), decoded
     * four at a time, lerped in x, then weighted by the rows' bilinear
     * weights and summed across the lanes */
    const int8_t *q = c->nrm + 2 * o;
    int32_t a0, a1, a2, a3;
    memcpy(&a0, q, 4);
    memcpy(&a1, q + 2 * sy, 4);
    memcpy(&a2, q + 2 * sz, 4);
    memcpy(&a3, q + 2 * (sz + sy), 4);
    const __m128i w = _mm_set_epi32(a3, a2, a1, a0);
    __m128 x0, y0, z0, x1, y1, z1;
    vv_oct_decode4(_mm_srai_epi32(_mm_slli_epi32(w, 24), 24),
                   _mm_srai_epi32(_mm_slli_epi32(w, 16), 24), &x0, &y0, &z0);
    vv_oct_decode4(_mm_srai_epi32(_mm_slli_epi32(w, 8), 24), _mm_srai_epi32(w, 24), &x1, &y1, &z1);
    const __m128 fx = _mm_set1_ps(f[0]);
    const float gy = 1.0f - f[1], gz = 1.0f - f[2];
    const __m128 wr = _mm_set_ps(f[1] * f[2], gy * f[2], f[1] * gz, gy * gz);
    const __m128 x = _mm_mul_ps(_mm_add_ps(x0, _mm_mul_ps(_mm_sub_ps(x1, x0), fx)), wr);
    const __m128 y = _mm_mul_ps(_mm_add_ps(y0, _mm_mul_ps(_mm_sub_ps(y1, y0), fx)), wr);
    const __m128 z = _mm_mul_ps(_mm_add_ps(z0, _mm_mul_ps(_mm_sub_ps(z1, z0), fx)), wr);
    /* (x0+x2, y0+y2, x1+x3, y1+y3), then the halves added */
    const __m128 xy = _mm_add_ps(_mm_unpacklo_ps(x, y), _mm_unpackhi_ps(x, y));
    const __m128 xys = _mm_add_ps(xy, _mm_movehl_ps(xy, xy));
    const __m128 zs = _mm_add_ps(z, _mm_movehl_ps(z, z));
    g[0] = _mm_cvtss_f32(xys);
    g[1] = _mm_cvtss_f32(_mm_shuffle_ps(xys, xys, _MM_SHUFFLE(1, 1, 1, 1)));
    g[2] = _mm_cvtss_f32(_mm_add_ss(zs, _mm_shuffle_ps(zs, zs, _MM_SHUFFLE(1, 1, 1, 1))));
#else
    vv_v4f c00 = vv_vcache_normal(c, o), c01 = vv_vcache_normal(c, o + 1);
    vv_v4f c10 = vv_vcache_normal(c, o + sy), c11 = vv_vcache_normal(c, o + sy + 1);
    vv_v4f c20 = vv_vcache_normal(c, o + sz), c21 = vv_vcache_normal(c, o + sz + 1);
    vv_v4f c30 = vv_vcache_normal(c, o + sz + sy), c31 = vv_vcache_normal(c, o + sz + sy + 1);
    c00 += (c01 - c00) * f[0];
    c10 += (c11 - c10) * f[0];
    c20 += (c21 - c20) * f[0];
    c30 += (c31 - c30) * f[0];
    c00 += (c10 - c00) * f[1];
    c20 += (c30 - c20) * f[1];
    c00 += (c20 - c00) * f[2];
    g[0] = c00[0];
    g[1] = c00[1];
    g[2] = c00[2];
#endif
}

/* Index-space gradient direction at p (not normalised): cached gradients
 * when there are, else central differences of trilinear samples half a
 * voxel apart. */
static inline void
vv_vcache_gradient(const vv_vcache *c, const float p[3], float g[3]) {
    if (c->nrm) {
        float f[3];
        size_t o = vv_vcache_cell_of(c, p, f);
        vv_vcache_gradient_at(c, o, f, g);
        return;
    }
    for (int a = 0; a < 3; a++) {
        float pa[3] = {p[0], p[1], p[2]}, pb[3] = {p[0], p[1], p[2]};
        pa[a] -= 0.5f;
        pb[a] += 0.5f;
        g[a] = vv_vcache_sample(c, pb) - vv_vcache_sample(c, pa);
    }
}

/* Trilinear gradient magnitude at index point p (needs c->gmag). */
static inline float
vv_vcache_gmag(const vv_vcache *c, const float p[3]) {
    float f[3];
    const size_t o = vv_vcache_cell_of(c, p, f);
    const float *v = c->gmag + o;
    const size_t sy = c->sy, sz = c->sz;
    const float c00 = vv_lerpf(v[0], v[1], f[0]), c10 = vv_lerpf(v[sy], v[sy + 1], f[0]);
    const float c01 = vv_lerpf(v[sz], v[sz + 1], f[0]);
    const float c11 = vv_lerpf(v[sz + sy], v[sz + sy + 1], f[0]);
    return vv_lerpf(vv_lerpf(c00, c10, f[1]), vv_lerpf(c01, c11, f[1]), f[2]);
}

/* The subvolume containing index point p (clamped to the grid). */
static inline size_t
vv_vcache_block(const vv_vcache *c, const float p[3]) {
    int bi = (int)((p[0] > 0 ? p[0] : 0) * (1.0f / VV_VC_BLOCK));
    int bj = (int)((p[1] > 0 ? p[1] : 0) * (1.0f / VV_VC_BLOCK));
    int bk = (int)((p[2] > 0 ? p[2] : 0) * (1.0f / VV_VC_BLOCK));
    bi = bi >= c->bx ? c->bx - 1 : bi;
    bj = bj >= c->by ? c->by - 1 : bj;
    bk = bk >= c->bz ? c->bz - 1 : bk;
    return ((size_t)bk * (size_t)c->by + (size_t)bj) * (size_t)c->bx + (size_t)bi;
}

/* The subvolume of index point p: its index, and its coordinates in bc.
 * p >= 0 up to rounding: a negative index would wrap and clamp high, so the
 * float is clamped instead. bxm, bym, bzm: the grid's last subvolume. */
static inline size_t
vv_vblock_of(const vv_vcache *c, const float p[3], unsigned bxm, unsigned bym, unsigned bzm,
             unsigned bc[3]) {
    unsigned bi = (unsigned)(int)((p[0] > 0 ? p[0] : 0) * (1.0f / VV_VC_BLOCK));
    unsigned bj = (unsigned)(int)((p[1] > 0 ? p[1] : 0) * (1.0f / VV_VC_BLOCK));
    unsigned bk = (unsigned)(int)((p[2] > 0 ? p[2] : 0) * (1.0f / VV_VC_BLOCK));
    bc[0] = bi > bxm ? bxm : bi;
    bc[1] = bj > bym ? bym : bj;
    bc[2] = bk > bzm ? bzm : bk;
    return ((size_t)bc[2] * (size_t)c->by + (size_t)bc[1]) * (size_t)c->bx + (size_t)bc[0];
}

#endif
