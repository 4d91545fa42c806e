/* The machine's limit for the ray caster's inner loop on one core: trilinear
 * samples and fused multiply-adds, scalar, AVX2 and AVX-512 (limit.h). */
#include <immintrin.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "limit.h"
#include "util.h"

enum { NPOS = 1 << 16 };

typedef bench_limit_type vtype;
#define T_U8 BENCH_LIMIT_U8
#define T_U16 BENCH_LIMIT_U16
#define T_F32 BENCH_LIMIT_F32
static const char *const type_name[] = {"u8", "u16", "f32"};
static const int type_size[] = {1, 2, 4};

struct bench_limit_case {
    vtype type;
    int n;               /* n^3 voxels */
    uint8_t *data;       /* n^3 voxels of type, then 4 bytes of padding (the
                            vector gathers read 4 bytes at a u8 or u16 voxel) */
    float *px, *py, *pz; /* NPOS positions, each in [0, n - 1) */
};
typedef struct bench_limit_case gather_case;

/* ---- scalar ------------------------------------------------------------------- */

static inline float
voxel(const gather_case *c, size_t i) {
    switch (c->type) {
    case T_U8:
        return c->data[i];
    case T_U16:
        return ((const uint16_t *)c->data)[i];
    default:
        return ((const float *)c->data)[i];
    }
}

static float
pass_scalar(const gather_case *c) {
    const size_t n = (size_t)c->n, sy = n, sz = n * n;
    double sum = 0; /* the reference of bench_limit_agreement: no float drift */
    for (int p = 0; p < NPOS; p++) {
        float x = c->px[p], y = c->py[p], z = c->pz[p];
        int ix = (int)x, iy = (int)y, iz = (int)z;
        float fx = x - ix, fy = y - iy, fz = z - iz;
        size_t i = (size_t)ix + sy * iy + sz * iz;
        float c00 = voxel(c, i) + fx * (voxel(c, i + 1) - voxel(c, i));
        float c10 = voxel(c, i + sy) + fx * (voxel(c, i + sy + 1) - voxel(c, i + sy));
        float c01 = voxel(c, i + sz) + fx * (voxel(c, i + sz + 1) - voxel(c, i + sz));
        float c11 =
            voxel(c, i + sy + sz) + fx * (voxel(c, i + sy + sz + 1) - voxel(c, i + sy + sz));
        float c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
        sum += c0 + fz * (c1 - c0);
    }
    return (float)sum;
}

/* ---- AVX2: 8 lanes ------------------------------------------------------------- */

__attribute__((target("avx2,fma"))) static inline __m256
gather8(const gather_case *c, __m256i idx) {
    switch (c->type) {
    case T_U8:
        return _mm256_cvtepi32_ps(_mm256_and_si256(
            _mm256_i32gather_epi32((const int *)c->data, idx, 1), _mm256_set1_epi32(0xff)));
    case T_U16:
        return _mm256_cvtepi32_ps(_mm256_and_si256(
            _mm256_i32gather_epi32((const int *)c->data, idx, 2), _mm256_set1_epi32(0xffff)));
    default:
        return _mm256_i32gather_ps((const float *)c->data, idx, 4);
    }
}

__attribute__((target("avx2,fma"))) static inline __m256
lerp8(__m256 a, __m256 b, __m256 t) {
    return _mm256_fmadd_ps(t, _mm256_sub_ps(b, a), a);
}

__attribute__((target("avx2,fma"))) static float
pass_avx2(const gather_case *c) {
    const int n = c->n;
    const __m256i sy = _mm256_set1_epi32(n), sz = _mm256_set1_epi32(n * n);
    const __m256i one = _mm256_set1_epi32(1), syz = _mm256_set1_epi32(n + n * n);
    __m256 acc = _mm256_setzero_ps();
    for (int p = 0; p < NPOS; p += 8) {
        __m256 x = _mm256_loadu_ps(c->px + p), y = _mm256_loadu_ps(c->py + p),
               z = _mm256_loadu_ps(c->pz + p);
        __m256i ix = _mm256_cvttps_epi32(x), iy = _mm256_cvttps_epi32(y),
                iz = _mm256_cvttps_epi32(z);
        __m256 fx = _mm256_sub_ps(x, _mm256_cvtepi32_ps(ix)),
               fy = _mm256_sub_ps(y, _mm256_cvtepi32_ps(iy)),
               fz = _mm256_sub_ps(z, _mm256_cvtepi32_ps(iz));
        __m256i i = _mm256_add_epi32(
            ix, _mm256_add_epi32(_mm256_mullo_epi32(iy, sy), _mm256_mullo_epi32(iz, sz)));
        __m256i i1 = _mm256_add_epi32(i, sy), i2 = _mm256_add_epi32(i, sz),
                i3 = _mm256_add_epi32(i, syz);
        __m256 c00 = lerp8(gather8(c, i), gather8(c, _mm256_add_epi32(i, one)), fx);
        __m256 c10 = lerp8(gather8(c, i1), gather8(c, _mm256_add_epi32(i1, one)), fx);
        __m256 c01 = lerp8(gather8(c, i2), gather8(c, _mm256_add_epi32(i2, one)), fx);
        __m256 c11 = lerp8(gather8(c, i3), gather8(c, _mm256_add_epi32(i3, one)), fx);
        acc = _mm256_add_ps(acc, lerp8(lerp8(c00, c10, fy), lerp8(c01, c11, fy), fz));
    }
    float l[8];
    _mm256_storeu_ps(l, acc);
    return l[0] + l[1] + l[2] + l[3] + l[4] + l[5] + l[6] + l[7];
}

/* ---- AVX-512: 16 lanes --------------------------------------------------------- */

__attribute__((target("avx512f"))) static inline __m512
gather16(const gather_case *c, __m512i idx) {
    switch (c->type) {
    case T_U8:
        return _mm512_cvtepi32_ps(
            _mm512_and_si512(_mm512_i32gather_epi32(idx, c->data, 1), _mm512_set1_epi32(0xff)));
    case T_U16:
        return _mm512_cvtepi32_ps(
            _mm512_and_si512(_mm512_i32gather_epi32(idx, c->data, 2), _mm512_set1_epi32(0xffff)));
    default:
        return _mm512_i32gather_ps(idx, c->data, 4);
    }
}

__attribute__((target("avx512f"))) static inline __m512
lerp16(__m512 a, __m512 b, __m512 t) {
    return _mm512_fmadd_ps(t, _mm512_sub_ps(b, a), a);
}

__attribute__((target("avx512f"))) static float
pass_avx512(const gather_case *c) {
    const int n = c->n;
    const __m512i sy = _mm512_set1_epi32(n), sz = _mm512_set1_epi32(n * n);
    const __m512i one = _mm512_set1_epi32(1), syz = _mm512_set1_epi32(n + n * n);
    __m512 acc = _mm512_setzero_ps();
    for (int p = 0; p < NPOS; p += 16) {
        __m512 x = _mm512_loadu_ps(c->px + p), y = _mm512_loadu_ps(c->py + p),
               z = _mm512_loadu_ps(c->pz + p);
        __m512i ix = _mm512_cvttps_epi32(x), iy = _mm512_cvttps_epi32(y),
                iz = _mm512_cvttps_epi32(z);
        __m512 fx = _mm512_sub_ps(x, _mm512_cvtepi32_ps(ix)),
               fy = _mm512_sub_ps(y, _mm512_cvtepi32_ps(iy)),
               fz = _mm512_sub_ps(z, _mm512_cvtepi32_ps(iz));
        __m512i i = _mm512_add_epi32(
            ix, _mm512_add_epi32(_mm512_mullo_epi32(iy, sy), _mm512_mullo_epi32(iz, sz)));
        __m512i i1 = _mm512_add_epi32(i, sy), i2 = _mm512_add_epi32(i, sz),
                i3 = _mm512_add_epi32(i, syz);
        __m512 c00 = lerp16(gather16(c, i), gather16(c, _mm512_add_epi32(i, one)), fx);
        __m512 c10 = lerp16(gather16(c, i1), gather16(c, _mm512_add_epi32(i1, one)), fx);
        __m512 c01 = lerp16(gather16(c, i2), gather16(c, _mm512_add_epi32(i2, one)), fx);
        __m512 c11 = lerp16(gather16(c, i3), gather16(c, _mm512_add_epi32(i3, one)), fx);
        acc = _mm512_add_ps(acc, lerp16(lerp16(c00, c10, fy), lerp16(c01, c11, fy), fz));
    }
    return _mm512_reduce_add_ps(acc);
}

/* ---- fused multiply-adds: ten independent chains --------------------------------- */

enum { FMA_ITERS = 1 << 22 };

static float
fma_scalar(float s) {
    float a[10];
    for (int k = 0; k < 10; k++)
        a[k] = s + (float)k;
    for (int i = 0; i < FMA_ITERS; i++)
        for (int k = 0; k < 10; k++)
            a[k] = a[k] * 0.999999f + 1e-7f; /* a multiply and an add: SSE2 has no FMA */
    float r = 0;
    for (int k = 0; k < 10; k++)
        r += a[k];
    return r;
}

__attribute__((target("avx2,fma"))) static float
fma_avx2(float s) {
    __m256 a[10];
    const __m256 m = _mm256_set1_ps(0.999999f), b = _mm256_set1_ps(1e-7f);
    for (int k = 0; k < 10; k++)
        a[k] = _mm256_set1_ps(s + (float)k);
    for (int i = 0; i < FMA_ITERS; i++)
        for (int k = 0; k < 10; k++)
            a[k] = _mm256_fmadd_ps(a[k], m, b);
    float l[8], r = 0;
    for (int k = 0; k < 10; k++) {
        _mm256_storeu_ps(l, a[k]);
        r += l[0] + l[7];
    }
    return r;
}

__attribute__((target("avx512f"))) static float
fma_avx512(float s) {
    __m512 a[10];
    const __m512 m = _mm512_set1_ps(0.999999f), b = _mm512_set1_ps(1e-7f);
    for (int k = 0; k < 10; k++)
        a[k] = _mm512_set1_ps(s + (float)k);
    for (int i = 0; i < FMA_ITERS; i++)
        for (int k = 0; k < 10; k++)
            a[k] = _mm512_fmadd_ps(a[k], m, b);
    float r = 0;
    for (int k = 0; k < 10; k++)
        r += _mm512_reduce_add_ps(a[k]);
    return r;
}

/* ---- set-up and timing ------------------------------------------------------------ */

/* a smooth field with some detail: the values do not change the timing, but
 * the sums must not be constant */
static int
fill(gather_case *c) {
    const size_t n = (size_t)c->n, nv = n * n * n;
    c->data = malloc(nv * (size_t)type_size[c->type] + 4);
    if (!c->data)
        return -1;
    memset(c->data + nv * (size_t)type_size[c->type], 0, 4);
    for (size_t i = 0; i < nv; i++) {
        unsigned v = (unsigned)((i * 2654435761u) >> 7) & 0xff;
        if (c->type == T_U8)
            c->data[i] = (uint8_t)v;
        else if (c->type == T_U16)
            ((uint16_t *)c->data)[i] = (uint16_t)(v * 257);
        else
            ((float *)c->data)[i] = (float)v / 255.0f;
    }
    return 0;
}

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static float
uniform(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (float)((rng >> 11) * 0x1p-53);
}

/* random positions, or along rays at half a voxel a step */
static int
positions(gather_case *c, int along_rays) {
    const float hi = (float)c->n - 1.001f;
    c->px = malloc(sizeof(float) * NPOS);
    c->py = malloc(sizeof(float) * NPOS);
    c->pz = malloc(sizeof(float) * NPOS);
    if (!c->px || !c->py || !c->pz)
        return -1;
    float x = 0, y = 0, z = 0, dx = 0, dy = 0, dz = 0;
    for (int p = 0; p < NPOS; p++) {
        if (!along_rays || p % 256 == 0 || x < 0 || y < 0 || z < 0 || x > hi || y > hi || z > hi) {
            x = uniform() * hi;
            y = uniform() * hi;
            z = uniform() * hi;
            /* a direction, half a voxel long */
            dx = uniform() - 0.5f;
            dy = uniform() - 0.5f;
            dz = uniform() - 0.5f;
            float l = sqrtf(dx * dx + dy * dy + dz * dz) * 2;
            dx /= l;
            dy /= l;
            dz /= l;
        }
        c->px[p] = x;
        c->py[p] = y;
        c->pz[p] = z;
        x += dx;
        y += dy;
        z += dz;
    }
    return 0;
}

static volatile float sink;

/* passes of NPOS samples until min_seconds: the best rate of three tries */
static double
time_gather(float (*pass)(const gather_case *), const gather_case *c, double min_seconds) {
    double best = 0;
    for (int t = 0; t < 3; t++) {
        double t0 = bench_now(), el;
        long passes = 0;
        float s = 0;
        do {
            s += pass(c);
            passes++;
            el = bench_now() - t0;
        } while (el < min_seconds / 3);
        sink = s;
        best = fmax(best, (double)passes * NPOS / el);
    }
    return best;
}

static double
time_fma(float (*f)(float), int lanes) {
    double best = 0;
    for (int t = 0; t < 3; t++) {
        double t0 = bench_now();
        sink = f((float)t);
        double el = bench_now() - t0;
        best = fmax(best, 2.0 * 10 * lanes * (double)FMA_ITERS / el);
    }
    return best;
}

/* one pass of a case, by bench_isa */
static float (*const pass[])(const gather_case *) = {pass_scalar, pass_avx2, pass_avx512};

/* ---- the interface (limit.h) --------------------------------------------------------- */

int
bench_isa_available(bench_isa isa) {
    __builtin_cpu_init();
    switch (isa) {
    case BENCH_ISA_SCALAR:
        return 1;
    case BENCH_ISA_AVX2:
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    default:
        return __builtin_cpu_supports("avx512f");
    }
}

bench_isa
bench_isa_widest(void) {
    return bench_isa_available(BENCH_ISA_AVX512) ? BENCH_ISA_AVX512
           : bench_isa_available(BENCH_ISA_AVX2) ? BENCH_ISA_AVX2
                                                 : BENCH_ISA_SCALAR;
}

const char *
bench_isa_name(bench_isa isa) {
    static const char *const names[] = {"scalar", "avx2", "avx512"};
    return names[isa];
}

const char *
bench_limit_type_name(bench_limit_type t) {
    return type_name[t];
}

bench_limit_case *
bench_limit_case_new(bench_limit_type type, int n, bench_limit_pattern pattern) {
    gather_case *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->type = type;
    c->n = n;
    if (fill(c) != 0 || positions(c, pattern == BENCH_LIMIT_RAYS) != 0) {
        bench_limit_case_free(c);
        return NULL;
    }
    return c;
}

void
bench_limit_case_free(bench_limit_case *c) {
    if (!c)
        return;
    free(c->data);
    free(c->px);
    free(c->py);
    free(c->pz);
    free(c);
}

double
bench_limit_trilinear(const bench_limit_case *c, bench_isa isa, double seconds) {
    if (!bench_isa_available(isa))
        return 0;
    return time_gather(pass[isa], c, seconds);
}

double
bench_limit_agreement(const bench_limit_case *c, bench_isa isa) {
    if (!bench_isa_available(isa))
        return 0;
    double a = pass_scalar(c), b = pass[isa](c);
    return fabs(a - b) / fmax(fabs(a), 1e-30);
}

double
bench_limit_fma(bench_isa isa) {
    switch (isa) {
    case BENCH_ISA_SCALAR:
        return time_fma(fma_scalar, 1);
    case BENCH_ISA_AVX2:
        return bench_isa_available(isa) ? time_fma(fma_avx2, 8) : 0;
    default:
        return bench_isa_available(isa) ? time_fma(fma_avx512, 16) : 0;
    }
}
