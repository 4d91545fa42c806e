/*
 * Smoothing and denoising: Gaussian (separable), median (sorted columns
 * merged), bilateral (Tomasi and Manduchi 1998) and Perona-Malik anisotropic
 * diffusion (Perona and Malik, IEEE PAMI 1990).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "filter/filter_internal.h"

vv_status
vv_filter_gaussian(const vv_volume *in, const double sigma[3], const vv_filter_options *o,
                   vv_volume **out) {
    vv_status s = vf_check_io(in, out, "gaussian");
    if (s != VV_OK)
        return s;
    if (!sigma)
        return vv_error_set(VV_ERR_INVALID, "gaussian: NULL sigma");
    for (int a = 0; a < 3; a++)
        if (!(sigma[a] > 0) || !isfinite(sigma[a]))
            return vv_error_set(VV_ERR_INVALID,
                                "gaussian: sigma %g along axis %c: must be > 0 (world units)",
                                sigma[a], "xyz"[a]);
    vf_kernel k[3] = {{0}};
    for (int a = 0; a < 3 && s == VV_OK; a++)
        if ((s = vf_kernel_gauss(&k[a], sigma[a] / in->spacing[a], 0)) != VV_OK)
            vv_error_prefix(s, "gaussian: axis %c", "xyz"[a]);
    vv_volume *v = NULL;
    float *tmp = NULL;
    if (s == VV_OK)
        s = vf_new_like(in, in->dims, VV_F32, &v);
    if (s == VV_OK) {
        tmp = malloc((size_t)vv_volume_voxel_count(in) * sizeof *tmp);
        if (!tmp)
            s = vv_error_set(VV_ERR_NOMEM, "gaussian: out of memory");
    }
    if (s == VV_OK) {
        const vf_kernel *kp[3] = {&k[0], &k[1], &k[2]};
        s = vf_separable(in->data, in->type, in->dims, kp, v->data, tmp, o, 0, 1);
    }
    free(tmp);
    for (int a = 0; a < 3; a++)
        vf_kernel_free(&k[a]);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

/* ---- median ------------------------------------------------------------------------- */

/*
 * For each output row the (2r+1)^2 rows of its neighbourhood are fixed; the
 * window at i is the union of the columns (the (2r+1)^2 values at one i)
 * at i-r..i+r. Each column is sorted once (and used by 2r+1 windows), and
 * the median is found by merging the 2r+1 sorted columns up to the middle
 * element. NaN values are left out of the columns.
 */
#define MEDIAN_IMPL(NAME, T)                                                                       \
    static void NAME(const void *src, vv_voxel_type type, const int n[3], int r, long row0,        \
                     long row1, T *rowbuf, T *cols, int *ncol, void *dst, double *outrow,          \
                     void (*load)(vv_voxel_type, const void *, size_t, size_t, T *)) {             \
        const int n0 = n[0], n1 = n[1], n2 = n[2], side = 2 * r + 1, cs = side * side;             \
        const int W = n0 + 2 * r; /* padded columns */                                             \
        for (long row = row0; row < row1; row++) {                                                 \
            int j = (int)(row % n1), k = (int)(row / n1);                                          \
            /* gather: column c (padded index, i = c - r) holds the (2r+1)^2 values */             \
            int q = 0;                                                                             \
            for (int dk = -r; dk <= r; dk++)                                                       \
                for (int dj = -r; dj <= r; dj++, q++) {                                            \
                    size_t srow = (size_t)vf_reflect((long)k + dk, n2) * n1 +                      \
                                  (size_t)vf_reflect((long)j + dj, n1);                            \
                    load(type, src, srow *n0, (size_t)n0, rowbuf);                                 \
                    for (int c = 0; c < W; c++)                                                    \
                        cols[(size_t)c * cs + q] = rowbuf[vf_reflect((long)c - r, n0)];            \
                }                                                                                  \
            for (int c = 0; c < W; c++) {                                                          \
                T *col = cols + (size_t)c * cs;                                                    \
                int m = 0;                                                                         \
                for (int e = 0; e < cs; e++)                                                       \
                    if (col[e] == col[e])                                                          \
                        col[m++] = col[e];                                                         \
                for (int a = 1; a < m; a++) { /* insertion sort: columns are short */              \
                    T x = col[a];                                                                  \
                    int b = a - 1;                                                                 \
                    while (b >= 0 && col[b] > x) {                                                 \
                        col[b + 1] = col[b];                                                       \
                        b--;                                                                       \
                    }                                                                              \
                    col[b + 1] = x;                                                                \
                }                                                                                  \
                ncol[c] = m;                                                                       \
            }                                                                                      \
            for (int i = 0; i < n0; i++) {                                                         \
                int pos[2 * VV_FILTER_MAX_RADIUS + 1];                                             \
                int total = 0;                                                                     \
                for (int c = 0; c < side; c++) {                                                   \
                    pos[c] = 0;                                                                    \
                    total += ncol[i + c];                                                          \
                }                                                                                  \
                if (total == 0) {                                                                  \
                    outrow[i] = NAN;                                                               \
                    continue;                                                                      \
                }                                                                                  \
                int want = total / 2;                                                              \
                T v = 0;                                                                           \
                for (int step = 0; step <= want; step++) {                                         \
                    int best = -1;                                                                 \
                    T bv = 0;                                                                      \
                    for (int c = 0; c < side; c++) {                                               \
                        if (pos[c] < ncol[i + c]) {                                                \
                            T x = cols[(size_t)(i + c) * cs + pos[c]];                             \
                            if (best < 0 || x < bv) {                                              \
                                best = c;                                                          \
                                bv = x;                                                            \
                            }                                                                      \
                        }                                                                          \
                    }                                                                              \
                    pos[best]++;                                                                   \
                    v = bv;                                                                        \
                }                                                                                  \
                outrow[i] = (double)v;                                                             \
            }                                                                                      \
            vf_store_d(type, dst, (size_t)row *n0, (size_t)n0, outrow);                            \
        }                                                                                          \
    }

MEDIAN_IMPL(median_rows_f, float)
MEDIAN_IMPL(median_rows_d, double)

/*
 * Radius 1 without NaN (the common case): vectorised along i. The nine
 * values of each column (the 3 x 3 rows at one i) are sorted by an odd-even
 * transposition network run on whole rows at once; the median of the 27
 * values in three sorted columns A, B, C is their 14th smallest, which is
 * min over a + b + c = 14 of max(A[a-1], B[b-1], C[c-1]) (a split takes a, b,
 * c smallest elements of each; its largest bounds the 14th from above, and
 * the true split attains it). Only copies, min and max: the result is exact.
 */
static void
median3_fast(const float *const rows[9], int n0, float *s /* 9 x (n0 + 2) */, float *best) {
    const int W = n0 + 2;
    for (int q = 0; q < 9; q++) {
        float *d = s + (size_t)q * W;
        const float *src = rows[q];
        d[0] = src[vf_reflect(-1, n0)];
        memcpy(d + 1, src, (size_t)n0 * sizeof *d);
        d[n0 + 1] = src[vf_reflect(n0, n0)];
    }
    for (int round = 0; round < 9; round++)
        for (int q = round & 1; q + 1 < 9; q += 2) {
            float *x = s + (size_t)q * W, *y = x + W;
            for (int c = 0; c < W; c++) {
                float a = x[c], b = y[c];
                x[c] = a < b ? a : b;
                y[c] = a < b ? b : a;
            }
        }
    for (int i = 0; i < n0; i++)
        best[i] = INFINITY;
    for (int a = 0; a <= 9; a++)
        for (int b = 0; b <= 9; b++) {
            int c = 14 - a - b;
            if (c < 0 || c > 9)
                continue;
            const float *A = a ? s + (size_t)(a - 1) * W : NULL;
            const float *B = b ? s + (size_t)(b - 1) * W + 1 : NULL;
            const float *C = c ? s + (size_t)(c - 1) * W + 2 : NULL;
            /* a + b + c = 14 > 9 + 0: at most one of them is empty */
            if (!A)
                for (int i = 0; i < n0; i++) {
                    float m = B[i] > C[i] ? B[i] : C[i];
                    best[i] = m < best[i] ? m : best[i];
                }
            else if (!B)
                for (int i = 0; i < n0; i++) {
                    float m = A[i] > C[i] ? A[i] : C[i];
                    best[i] = m < best[i] ? m : best[i];
                }
            else if (!C)
                for (int i = 0; i < n0; i++) {
                    float m = A[i] > B[i] ? A[i] : B[i];
                    best[i] = m < best[i] ? m : best[i];
                }
            else
                for (int i = 0; i < n0; i++) {
                    float m = A[i] > B[i] ? A[i] : B[i];
                    m = m > C[i] ? m : C[i];
                    best[i] = m < best[i] ? m : best[i];
                }
        }
}

typedef struct median_ctx {
    const vv_volume *in;
    vv_volume *out;
    int r, wide;
    void *rowbuf[VF_MAX_THREADS], *cols[VF_MAX_THREADS];
    int *ncol[VF_MAX_THREADS];
    double *outrow[VF_MAX_THREADS];
    float *fast_rows[VF_MAX_THREADS]; /* radius 1: 9 loaded rows, 9 sorted columns, best */
} median_ctx;

static int
has_nan(const float *x, int n) {
    int bad = 0;
    for (int i = 0; i < n; i++)
        bad |= x[i] != x[i];
    return bad;
}

/* Radius 1, float-exact types: the vectorised kernel, rows with a NaN
 * neighbourhood through the general one. */
static void
median_fast_rows(median_ctx *C, long r0, long r1, int w) {
    const vv_volume *in = C->in;
    const int n0 = in->dims[0], n1 = in->dims[1], n2 = in->dims[2];
    float *rowsbuf = C->fast_rows[w], *s = rowsbuf + (size_t)9 * n0,
          *best = s + (size_t)9 * (n0 + 2);
    for (long row = r0; row < r1; row++) {
        int j = (int)(row % n1), k = (int)(row / n1);
        const float *rows[9];
        int q = 0, nan = 0;
        for (int dk = -1; dk <= 1; dk++)
            for (int dj = -1; dj <= 1; dj++, q++) {
                size_t srow = (size_t)vf_reflect((long)k + dk, n2) * n1 +
                              (size_t)vf_reflect((long)j + dj, n1);
                float *dst = rowsbuf + (size_t)q * n0;
                vf_load_f(in->type, in->data, srow * n0, (size_t)n0, dst);
                if (in->type == VV_F32)
                    nan |= has_nan(dst, n0);
                rows[q] = dst;
            }
        if (nan) {
            median_rows_f(in->data, in->type, in->dims, 1, row, row + 1, C->rowbuf[w], C->cols[w],
                          C->ncol[w], C->out->data, C->outrow[w], vf_load_f);
            continue;
        }
        median3_fast(rows, n0, s, best);
        double *o = C->outrow[w];
        for (int i = 0; i < n0; i++)
            o[i] = best[i];
        vf_store_d(in->type, C->out->data, (size_t)row * n0, (size_t)n0, o);
    }
}

static void
median_body(void *cp, long r0, long r1, int w) {
    median_ctx *C = cp;
    if (C->fast_rows[w])
        median_fast_rows(C, r0, r1, w);
    else if (C->wide)
        median_rows_d(C->in->data, C->in->type, C->in->dims, C->r, r0, r1, C->rowbuf[w], C->cols[w],
                      C->ncol[w], C->out->data, C->outrow[w], vf_load_d);
    else
        median_rows_f(C->in->data, C->in->type, C->in->dims, C->r, r0, r1, C->rowbuf[w], C->cols[w],
                      C->ncol[w], C->out->data, C->outrow[w], vf_load_f);
}

vv_status
vv_filter_median(const vv_volume *in, int radius, const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "median");
    if (s != VV_OK)
        return s;
    if (radius < 0 || radius > VV_FILTER_MAX_RADIUS)
        return vv_error_set(VV_ERR_INVALID, "median: radius %d voxels: must be 0..%d", radius,
                            VV_FILTER_MAX_RADIUS);
    vv_volume *v = NULL;
    if ((s = vf_new_like(in, in->dims, in->type, &v)) != VV_OK)
        return s;
    if (radius == 0) {
        memcpy(v->data, in->data, (size_t)vv_volume_voxel_count(in) * vv_voxel_type_size(in->type));
        vv_volume_update_range(v);
        *out = v;
        return vf_report(o, 1);
    }
    median_ctx C = {.in = in, .out = v, .r = radius};
    /* 32-bit integers and doubles are not all exact in float */
    C.wide = in->type == VV_U32 || in->type == VV_I32 || in->type == VV_F64;
    size_t es = C.wide ? sizeof(double) : sizeof(float);
    size_t W = (size_t)in->dims[0] + 2 * (size_t)radius, side = 2 * (size_t)radius + 1;
    int nt = vf_threads(o);
    for (int w = 0; w < nt && s == VV_OK; w++) {
        C.rowbuf[w] = malloc((size_t)in->dims[0] * es);
        C.cols[w] = malloc(W * side * side * es);
        C.ncol[w] = malloc(W * sizeof(int));
        C.outrow[w] = malloc((size_t)in->dims[0] * sizeof(double));
        if (radius == 1 && !C.wide)
            C.fast_rows[w] = malloc(
                ((size_t)9 * in->dims[0] + (size_t)9 * (in->dims[0] + 2) + (size_t)in->dims[0]) *
                sizeof(float));
        if (!C.rowbuf[w] || !C.cols[w] || !C.ncol[w] || !C.outrow[w] ||
            (radius == 1 && !C.wide && !C.fast_rows[w]))
            s = vv_error_set(VV_ERR_NOMEM, "median: out of memory");
    }
    if (s == VV_OK)
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 4, median_body, &C, 0, 1);
    for (int w = 0; w < nt; w++) {
        free(C.rowbuf[w]);
        free(C.cols[w]);
        free(C.ncol[w]);
        free(C.outrow[w]);
        free(C.fast_rows[w]);
    }
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

/* ---- bilateral ------------------------------------------------------------------------ */

typedef struct bilat_ctx {
    const float *f;
    float *d;
    int n[3], r[3];
    const float *ws; /* spatial weights, (2r0+1)(2r1+1)(2r2+1) */
    float inv2sr2;
} bilat_ctx;

static void
bilat_body(void *cp, long r0, long r1, int w) {
    (void)w;
    bilat_ctx *C = cp;
    const int n0 = C->n[0], n1 = C->n[1], n2 = C->n[2];
    const int rx = C->r[0], ry = C->r[1], rz = C->r[2];
    for (long row = r0; row < r1; row++) {
        int j = (int)(row % n1), k = (int)(row / n1);
        for (int i = 0; i < n0; i++) {
            float c = C->f[(size_t)row * n0 + i];
            if (c != c) {
                C->d[(size_t)row * n0 + i] = c;
                continue;
            }
            double sw = 0, sv = 0;
            const float *ws = C->ws;
            for (int dk = -rz; dk <= rz; dk++) {
                size_t pk = (size_t)vf_reflect((long)k + dk, n2) * n1;
                for (int dj = -ry; dj <= ry; dj++) {
                    const float *line =
                        C->f + (pk + (size_t)vf_reflect((long)j + dj, n1)) * (size_t)n0;
                    for (int di = -rx; di <= rx; di++, ws++) {
                        float x = line[vf_reflect((long)i + di, n0)];
                        if (x != x)
                            continue;
                        float dv = x - c;
                        float wt = *ws * expf(-dv * dv * C->inv2sr2);
                        sw += wt;
                        sv += (double)wt * x;
                    }
                }
            }
            C->d[(size_t)row * n0 + i] = (float)(sv / sw);
        }
    }
}

vv_status
vv_filter_bilateral(const vv_volume *in, double sigma_spatial, double sigma_range,
                    const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "bilateral");
    if (s != VV_OK)
        return s;
    if (!(sigma_spatial > 0) || !isfinite(sigma_spatial))
        return vv_error_set(VV_ERR_INVALID,
                            "bilateral: spatial sigma %g: must be > 0 (world units)",
                            sigma_spatial);
    if (!(sigma_range > 0) || !isfinite(sigma_range))
        return vv_error_set(VV_ERR_INVALID, "bilateral: range sigma %g: must be > 0 (value units)",
                            sigma_range);
    bilat_ctx C = {.inv2sr2 = (float)(0.5 / (sigma_range * sigma_range))};
    memcpy(C.n, in->dims, sizeof C.n);
    double sv[3];
    size_t nw = 1;
    for (int a = 0; a < 3; a++) {
        sv[a] = sigma_spatial / in->spacing[a];
        double rr = ceil(2.0 * sv[a]);
        if (rr > VV_FILTER_MAX_RADIUS)
            return vv_error_set(VV_ERR_INVALID,
                                "bilateral: spatial sigma %g is %g voxels along %c: the window "
                                "radius would exceed %d voxels",
                                sigma_spatial, sv[a], "xyz"[a], VV_FILTER_MAX_RADIUS);
        C.r[a] = (int)rr;
        nw *= (size_t)(2 * C.r[a] + 1);
    }
    float *ws = malloc(nw * sizeof *ws);
    float *f = malloc((size_t)vv_volume_voxel_count(in) * sizeof *f);
    vv_volume *v = NULL;
    if (!ws || !f)
        s = vv_error_set(VV_ERR_NOMEM, "bilateral: out of memory");
    if (s == VV_OK)
        s = vf_new_like(in, in->dims, VV_F32, &v);
    if (s == VV_OK) {
        size_t q = 0;
        for (int dk = -C.r[2]; dk <= C.r[2]; dk++)
            for (int dj = -C.r[1]; dj <= C.r[1]; dj++)
                for (int di = -C.r[0]; di <= C.r[0]; di++)
                    ws[q++] = (float)exp(-0.5 * ((double)di * di / (sv[0] * sv[0]) +
                                                 (double)dj * dj / (sv[1] * sv[1]) +
                                                 (double)dk * dk / (sv[2] * sv[2])));
        vf_load_f(in->type, in->data, 0, (size_t)vv_volume_voxel_count(in), f);
        C.f = f;
        C.d = v->data;
        C.ws = ws;
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 4, bilat_body, &C, 0, 1);
    }
    free(ws);
    free(f);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

/* ---- Perona-Malik diffusion ---------------------------------------------------------- */

typedef struct pm_ctx {
    const float *f;
    float *d;
    int n[3];
    float c[3];  /* (h_min / h_a)^2 */
    float ih[3]; /* 1 / (h_a kappa) */
    float dt;
} pm_ctx;

static inline float
pm_flux(float diff, float ih, float c) {
    float x = diff * ih;
    return c * expf(-x * x) * diff;
}

static void
pm_body(void *cp, long r0, long r1, int w) {
    (void)w;
    pm_ctx *C = cp;
    const int n0 = C->n[0], n1 = C->n[1], n2 = C->n[2];
    const size_t sj = (size_t)n0, sk = (size_t)n0 * n1;
    for (long row = r0; row < r1; row++) {
        int j = (int)(row % n1), k = (int)(row / n1);
        const float *f = C->f + (size_t)row * n0;
        float *d = C->d + (size_t)row * n0;
        for (int i = 0; i < n0; i++) {
            float v = f[i], sum = 0;
            /* the same fixed order of terms for every voxel */
            if (i > 0)
                sum += pm_flux(f[i - 1] - v, C->ih[0], C->c[0]);
            if (i < n0 - 1)
                sum += pm_flux(f[i + 1] - v, C->ih[0], C->c[0]);
            if (j > 0)
                sum += pm_flux(f[i - sj] - v, C->ih[1], C->c[1]);
            if (j < n1 - 1)
                sum += pm_flux(f[i + sj] - v, C->ih[1], C->c[1]);
            if (k > 0)
                sum += pm_flux(f[i - sk] - v, C->ih[2], C->c[2]);
            if (k < n2 - 1)
                sum += pm_flux(f[i + sk] - v, C->ih[2], C->c[2]);
            d[i] = v + C->dt * sum;
        }
    }
}

vv_status
vv_filter_diffusion(const vv_volume *in, int iterations, double kappa, double dt,
                    const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "diffusion");
    if (s != VV_OK)
        return s;
    if (iterations < 1 || iterations > 10000)
        return vv_error_set(VV_ERR_INVALID, "diffusion: %d iterations: must be 1..10000",
                            iterations);
    if (!(kappa > 0) || !isfinite(kappa))
        return vv_error_set(VV_ERR_INVALID, "diffusion: kappa %g: must be > 0", kappa);
    if (!(dt > 0) || dt > 1.0 / 6.0 + 1e-12)
        return vv_error_set(VV_ERR_INVALID,
                            "diffusion: time step %g: must be in (0, 1/6] for stability", dt);
    vv_volume *v = NULL;
    size_t n = (size_t)vv_volume_voxel_count(in);
    float *tmp = malloc(n * sizeof *tmp);
    if (!tmp)
        return vv_error_set(VV_ERR_NOMEM, "diffusion: out of memory");
    if ((s = vf_new_like(in, in->dims, VV_F32, &v)) != VV_OK) {
        free(tmp);
        return s;
    }
    pm_ctx C = {.dt = (float)dt};
    memcpy(C.n, in->dims, sizeof C.n);
    double hmin = fmin(in->spacing[0], fmin(in->spacing[1], in->spacing[2]));
    for (int a = 0; a < 3; a++) {
        C.c[a] = (float)((hmin / in->spacing[a]) * (hmin / in->spacing[a]));
        C.ih[a] = (float)(1.0 / (in->spacing[a] * kappa));
    }
    float *a = v->data, *b = tmp;
    vf_load_f(in->type, in->data, 0, n, a);
    for (int it = 0; it < iterations && s == VV_OK; it++) {
        C.f = a;
        C.d = b;
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 16, pm_body, &C,
                        (double)it / iterations, (double)(it + 1) / iterations);
        float *x = a;
        a = b;
        b = x;
    }
    if (s == VV_OK && a != v->data)
        memcpy(v->data, a, n * sizeof *a);
    free(tmp);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}
