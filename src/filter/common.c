/*
 * Shared machinery of the filters: the row-parallel loop (core/parallel_for.h),
 * voxel-type conversion, output volumes, Gaussian kernels and the separable
 * convolution behind the Gaussian, the derivatives and the Hessian.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "filter/filter_internal.h"

void
vv_filter_options_init(vv_filter_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
}

int
vf_threads(const vv_filter_options *o) {
    int n = o && o->threads > 0 ? o->threads : vv_threads_get();
    if (n < 1)
        n = 1;
    return n > VF_MAX_THREADS ? VF_MAX_THREADS : n;
}

vv_status
vf_report(const vv_filter_options *o, double f) {
    if (o && o->progress.fn && vv_progress_report(&o->progress, f))
        return vv_error_set(VV_ERR_CANCELLED, "filter: cancelled");
    return VV_OK;
}

vv_status
vf_parallel(const vv_filter_options *o, long n, long chunk, vf_body body, void *ctx, double p0,
            double p1) {
    const vv_parallel_progress pr = {o ? &o->progress : NULL, p0, p1, 1};
    vv_status s = vv_parallel_for(n, chunk, vf_threads(o), body, ctx, &pr);
    if (s != VV_OK)
        return vv_error_prefix(s, "filter");
    /* the end of every loop is reported, whoever ran its last chunks, so a
     * cancel is seen at the latest when the loop ends */
    return vf_report(o, p1);
}

vv_status
vf_check_io(const vv_volume *in, const void *out, const char *what) {
    if (!in || !out)
        return vv_error_set(VV_ERR_INVALID, "%s: NULL %s", what, in ? "output" : "volume");
    if (!in->data)
        return vv_error_set(VV_ERR_INVALID, "%s: volume has no data", what);
    return VV_OK;
}

vv_status
vf_new_like(const vv_volume *in, const int dims[3], vv_voxel_type type, vv_volume **out) {
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, type);
    if (s != VV_OK)
        return s;
    memcpy(v->spacing, in->spacing, sizeof v->spacing);
    memcpy(v->origin, in->origin, sizeof v->origin);
    memcpy(v->direction, in->direction, sizeof v->direction);
    v->unit = in->unit;
    v->space = in->space;
    v->data_origin = in->data_origin;
    v->modification = VV_MOD_FILTERED;
    *out = v;
    return VV_OK;
}

#define LOAD_CASE(T, CT, DT)                                                                       \
    case T: {                                                                                      \
        const CT *s_ = (const CT *)src + off;                                                      \
        for (size_t i = 0; i < n; i++)                                                             \
            dst[i] = (DT)s_[i];                                                                    \
    } break;

void
vf_load_f(vv_voxel_type t, const void *src, size_t off, size_t n, float *dst) {
    switch (t) {
        LOAD_CASE(VV_U8, uint8_t, float)
        LOAD_CASE(VV_I8, int8_t, float)
        LOAD_CASE(VV_U16, uint16_t, float)
        LOAD_CASE(VV_I16, int16_t, float)
        LOAD_CASE(VV_U32, uint32_t, float)
        LOAD_CASE(VV_I32, int32_t, float)
    case VV_F32:
        memcpy(dst, (const float *)src + off, n * sizeof *dst);
        break;
        LOAD_CASE(VV_F64, double, float)
    }
}

void
vf_load_d(vv_voxel_type t, const void *src, size_t off, size_t n, double *dst) {
    switch (t) {
        LOAD_CASE(VV_U8, uint8_t, double)
        LOAD_CASE(VV_I8, int8_t, double)
        LOAD_CASE(VV_U16, uint16_t, double)
        LOAD_CASE(VV_I16, int16_t, double)
        LOAD_CASE(VV_U32, uint32_t, double)
        LOAD_CASE(VV_I32, int32_t, double)
        LOAD_CASE(VV_F32, float, double)
    case VV_F64:
        memcpy(dst, (const double *)src + off, n * sizeof *dst);
        break;
    }
}

#define STORE_INT(T, CT, LO, HI)                                                                   \
    case T: {                                                                                      \
        CT *d_ = (CT *)dst + off;                                                                  \
        for (size_t i = 0; i < n; i++) {                                                           \
            double x = src[i];                                                                     \
            d_[i] = x != x ? (CT)0 : x <= (LO) ? (CT)(LO) : x >= (HI) ? (CT)(HI) : (CT)lrint(x);   \
        }                                                                                          \
    } break;

void
vf_store_d(vv_voxel_type t, void *dst, size_t off, size_t n, const double *src) {
    switch (t) {
        STORE_INT(VV_U8, uint8_t, 0, 255)
        STORE_INT(VV_I8, int8_t, -128, 127)
        STORE_INT(VV_U16, uint16_t, 0, 65535)
        STORE_INT(VV_I16, int16_t, -32768, 32767)
        STORE_INT(VV_U32, uint32_t, 0, 4294967295.0)
        STORE_INT(VV_I32, int32_t, -2147483648.0, 2147483647.0)
    case VV_F32: {
        float *d_ = (float *)dst + off;
        for (size_t i = 0; i < n; i++)
            d_[i] = (float)src[i];
    } break;
    case VV_F64:
        memcpy((double *)dst + off, src, n * sizeof *src);
        break;
    }
}

/* ---- kernels ----------------------------------------------------------------------- */

vv_status
vf_kernel_gauss(vf_kernel *k, double sigma, int order) {
    memset(k, 0, sizeof *k);
    if (!(sigma > 0) || !isfinite(sigma))
        return vv_error_set(VV_ERR_INVALID, "sigma %g voxels: must be > 0", sigma);
    double rr = floor(4.0 * sigma + 0.5);
    if (rr > 100000)
        return vv_error_set(VV_ERR_LIMIT, "sigma %g voxels: kernel too large", sigma);
    int r = (int)rr;
    if (order > 0 && r < 1)
        r = 1;
    k->r = r;
    k->w = malloc((size_t)(2 * r + 1) * sizeof *k->w);
    double *g = malloc((size_t)(2 * r + 1) * sizeof *g);
    if (!k->w || !g) {
        free(k->w);
        free(g);
        k->w = NULL;
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    double sum = 0;
    for (int t = -r; t <= r; t++) {
        g[t + r] = exp(-0.5 * (double)t * t / (sigma * sigma));
        sum += g[t + r];
    }
    for (int t = 0; t <= 2 * r; t++)
        g[t] /= sum;
    if (order == 0) {
        for (int t = 0; t <= 2 * r; t++)
            k->w[t] = (float)g[t];
    } else if (order == 1) {
        /* w(t) proportional to t g(t) (the derivative of g, sign chosen for
         * out[i] = sum w[t] f[i + t]), scaled so a unit ramp gives 1 */
        double m = 0;
        for (int t = -r; t <= r; t++)
            m += (double)t * t * g[t + r];
        for (int t = -r; t <= r; t++)
            k->w[t + r] = (float)(t * g[t + r] / m);
    } else {
        /* (t^2 / s^2 - 1) g(t) / s^2 with its mean removed (a constant gives 0),
         * scaled so a parabola t^2 gives 2 */
        double *h = malloc((size_t)(2 * r + 1) * sizeof *h);
        if (!h) {
            free(g);
            vf_kernel_free(k);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        double mean = 0;
        for (int t = -r; t <= r; t++) {
            h[t + r] = ((double)t * t / (sigma * sigma) - 1.0) * g[t + r];
            mean += h[t + r];
        }
        mean /= 2 * r + 1;
        double m2 = 0;
        for (int t = -r; t <= r; t++) {
            h[t + r] -= mean;
            m2 += (double)t * t * h[t + r];
        }
        for (int t = 0; t <= 2 * r; t++)
            k->w[t] = (float)(2.0 * h[t] / m2);
        free(h);
    }
    free(g);
    return VV_OK;
}

void
vf_kernel_free(vf_kernel *k) {
    if (k) {
        free(k->w);
        k->w = NULL;
    }
}

/* ---- separable convolution ------------------------------------------------------------ */

typedef struct sep_ctx {
    const void *src;
    vv_voxel_type t;
    float *dst;
    int n[3];
    const vf_kernel *k;
    float *scratch[VF_MAX_THREADS];
} sep_ctx;

/* Along i: each row through a mirrored, padded copy (converted to float). */
static void
sep_x(void *cp, long r0, long r1, int w) {
    sep_ctx *C = cp;
    const int n0 = C->n[0];
    const vf_kernel *k = C->k;
    float *pad = C->scratch[w];
    for (long row = r0; row < r1; row++) {
        size_t off = (size_t)row * n0;
        float *d = C->dst + off;
        if (!k) {
            vf_load_f(C->t, C->src, off, (size_t)n0, d);
            continue;
        }
        const int r = k->r;
        vf_load_f(C->t, C->src, off, (size_t)n0, pad + r);
        for (int i = 1; i <= r; i++) {
            pad[r - i] = pad[r + vf_reflect(-i, n0)];
            pad[r + n0 - 1 + i] = pad[r + vf_reflect(n0 - 1 + i, n0)];
        }
        const float *wt = k->w;
        for (int i = 0; i < n0; i++)
            d[i] = wt[0] * pad[i];
        for (int t = 1; t <= 2 * r; t++) {
            const float c = wt[t];
            const float *p = pad + t;
            for (int i = 0; i < n0; i++)
                d[i] += c * p[i];
        }
    }
}

/* Along j (axis 1) or k (axis 2): whole rows weighted and summed, which
 * vectorises along i. Item = one output row (j, k). */
typedef struct sep_yz {
    const float *src;
    float *dst;
    int n[3];
    int axis;
    const vf_kernel *k;
} sep_yz;

static void
sep_yz_body(void *cp, long r0, long r1, int w) {
    (void)w;
    sep_yz *C = cp;
    const int n0 = C->n[0], n1 = C->n[1], n2 = C->n[2];
    const int r = C->k->r;
    const float *wt = C->k->w;
    for (long row = r0; row < r1; row++) {
        int j = (int)(row % n1), kk = (int)(row / n1);
        float *d = C->dst + (size_t)row * n0;
        for (int t = 0; t <= 2 * r; t++) {
            size_t srow;
            if (C->axis == 1)
                srow = (size_t)kk * n1 + (size_t)vf_reflect((long)j + t - r, n1);
            else
                srow = (size_t)vf_reflect((long)kk + t - r, n2) * n1 + (size_t)j;
            const float *s = C->src + srow * n0;
            const float c = wt[t];
            if (t == 0)
                for (int i = 0; i < n0; i++)
                    d[i] = c * s[i];
            else
                for (int i = 0; i < n0; i++)
                    d[i] += c * s[i];
        }
    }
}

vv_status
vf_separable(const void *data, vv_voxel_type t, const int dims[3], const vf_kernel *const k[3],
             float *out, float *tmp, const vv_filter_options *o, double p0, double p1) {
    sep_ctx C = {.src = data, .t = t, .dst = out, .k = k[0]};
    memcpy(C.n, dims, sizeof C.n);
    int nt = vf_threads(o);
    vv_status s = VV_OK;
    if (k[0]) {
        for (int w = 0; w < nt; w++) {
            C.scratch[w] = malloc(((size_t)dims[0] + 2 * (size_t)k[0]->r) * sizeof(float));
            if (!C.scratch[w])
                s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
    }
    long rows = (long)dims[1] * dims[2];
    double dp = (p1 - p0) / 3.0;
    if (s == VV_OK)
        s = vf_parallel(o, rows, 16, sep_x, &C, p0, p0 + dp);
    for (int w = 0; w < nt; w++)
        free(C.scratch[w]);
    float *cur = out, *other = tmp;
    for (int axis = 1; axis <= 2 && s == VV_OK; axis++) {
        if (!k[axis])
            continue;
        sep_yz Y = {.src = cur, .dst = other, .axis = axis, .k = k[axis]};
        memcpy(Y.n, dims, sizeof Y.n);
        s = vf_parallel(o, rows, 16, sep_yz_body, &Y, p0 + dp * axis, p0 + dp * (axis + 1));
        float *x = cur;
        cur = other;
        other = x;
    }
    if (s == VV_OK && cur != out)
        memcpy(out, cur, (size_t)rows * dims[0] * sizeof *out);
    return s;
}

/* ---- masks ----------------------------------------------------------------------------- */

typedef struct mask_ctx {
    const vv_volume *in;
    uint8_t *m;
    size_t n0;
} mask_ctx;

#define MASK_CASE(T, CT)                                                                           \
    case T: {                                                                                      \
        const CT *s_ = (const CT *)C->in->data;                                                    \
        for (size_t q = q0; q < q1; q++)                                                           \
            C->m[q] = (uint8_t)(s_[q] != 0 && s_[q] == s_[q]);                                     \
    } break;

static void
mask_body(void *cp, long r0, long r1, int w) {
    (void)w;
    mask_ctx *C = cp;
    size_t q0 = (size_t)r0 * C->n0, q1 = (size_t)r1 * C->n0;
    switch (C->in->type) {
        MASK_CASE(VV_U8, uint8_t)
        MASK_CASE(VV_I8, int8_t)
        MASK_CASE(VV_U16, uint16_t)
        MASK_CASE(VV_I16, int16_t)
        MASK_CASE(VV_U32, uint32_t)
        MASK_CASE(VV_I32, int32_t)
        MASK_CASE(VV_F32, float)
        MASK_CASE(VV_F64, double)
    }
}

vv_status
vf_mask_u8(const vv_volume *in, const vv_filter_options *o, uint8_t **mask) {
    size_t n = (size_t)vv_volume_voxel_count(in);
    uint8_t *m = malloc(n ? n : 1);
    if (!m)
        return vv_error_set(VV_ERR_NOMEM, "out of memory (%zu voxels)", n);
    mask_ctx C = {in, m, (size_t)in->dims[0]};
    vv_filter_options q = o ? *o : (vv_filter_options){0};
    q.progress.fn = NULL;
    vf_parallel(&q, (long)in->dims[1] * in->dims[2], 64, mask_body, &C, 0, 0);
    *mask = m;
    return VV_OK;
}
