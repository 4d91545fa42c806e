/*
 * Resampling (separable kernels in the manner of Teem's nrrd resampler,
 * checked against `unu resample`), crop, pad, flip, permute and voxel-type
 * conversion.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "filter/filter_internal.h"

vv_status
vv_filter_kernel_parse(const char *name, vv_filter_kernel *out) {
    if (!name || !out)
        return vv_error_set(VV_ERR_INVALID, "kernel: NULL argument");
    if (strcasecmp(name, "nearest") == 0 || strcasecmp(name, "cheap") == 0)
        *out = VV_KERNEL_NEAREST;
    else if (strcasecmp(name, "linear") == 0 || strcasecmp(name, "tent") == 0 ||
             strcasecmp(name, "trilinear") == 0)
        *out = VV_KERNEL_LINEAR;
    else if (strcasecmp(name, "bspline") == 0 || strcasecmp(name, "cubic") == 0 ||
             strcasecmp(name, "bspln3") == 0)
        *out = VV_KERNEL_BSPLINE3;
    else if (strcasecmp(name, "sinc") == 0 || strcasecmp(name, "hann") == 0)
        *out = VV_KERNEL_SINC;
    else
        return vv_error_set(VV_ERR_INVALID,
                            "unknown resampling kernel \"%s\"; expected nearest, linear, "
                            "bspline or sinc",
                            name);
    return VV_OK;
}

static double
kernel_support(vv_filter_kernel k) {
    return k == VV_KERNEL_LINEAR ? 1.0 : k == VV_KERNEL_BSPLINE3 ? 2.0 : 3.0;
}

static double
kernel_eval(vv_filter_kernel k, double x) {
    double a = fabs(x);
    switch (k) {
    case VV_KERNEL_LINEAR:
        return a < 1 ? 1 - a : 0;
    case VV_KERNEL_BSPLINE3:
        if (a < 1)
            return 2.0 / 3.0 - a * a + 0.5 * a * a * a;
        if (a < 2)
            return (2 - a) * (2 - a) * (2 - a) / 6.0;
        return 0;
    case VV_KERNEL_SINC: {
        if (a >= 3)
            return 0;
        double s = a < 1e-12 ? 1.0 : sin(M_PI * a) / (M_PI * a);
        return s * 0.5 * (1 + cos(M_PI * a / 3.0));
    }
    default:
        return 0;
    }
}

/* The taps of one axis: output index o reads input first[o] .. first[o] +
 * count - 1 (indices clamped to the edge) with weights w[o * count ..]. */
typedef struct axis_taps {
    int n_in, n_out, count;
    int *first;
    float *w;
} axis_taps;

static double
node_pos(int o, int n_in, int n_out) {
    return n_out > 1 ? (double)o * (n_in - 1) / (n_out - 1) : 0.5 * (n_in - 1);
}

static vv_status
taps_make(axis_taps *T, vv_filter_kernel k, int n_in, int n_out) {
    memset(T, 0, sizeof *T);
    T->n_in = n_in;
    T->n_out = n_out;
    double ratio = n_in > 1 && n_out > 1 ? (double)(n_out - 1) / (n_in - 1) : 1.0;
    double scale = ratio < 1 ? ratio : 1.0; /* downsampling widens the kernel */
    double sup = kernel_support(k) / scale;
    T->count = 2 * (int)ceil(sup) + 1;
    T->first = malloc((size_t)n_out * sizeof *T->first);
    T->w = malloc((size_t)n_out * T->count * sizeof *T->w);
    if (!T->first || !T->w) {
        free(T->first);
        free(T->w);
        return vv_error_set(VV_ERR_NOMEM, "resample: out of memory");
    }
    for (int o = 0; o < n_out; o++) {
        double x = node_pos(o, n_in, n_out);
        int f = (int)floor(x) - (T->count - 1) / 2;
        T->first[o] = f;
        double sum = 0;
        float *w = T->w + (size_t)o * T->count;
        for (int t = 0; t < T->count; t++) {
            double d = (f + t - x) * scale;
            double v = kernel_eval(k, d) * scale;
            w[t] = (float)v;
            sum += v;
        }
        if (sum != 0)
            for (int t = 0; t < T->count; t++)
                w[t] = (float)(w[t] / sum);
    }
    return VV_OK;
}

static void
taps_free(axis_taps *T) {
    free(T->first);
    free(T->w);
}

static inline int
clampi(int i, int n) {
    return i < 0 ? 0 : i >= n ? n - 1 : i;
}

typedef struct rs_ctx {
    const void *src; /* native data (pass x) or float */
    vv_voxel_type t;
    float *dst;
    int in_dims[3]; /* dims of this pass's input */
    int axis;
    const axis_taps *T;
    float *scratch[VF_MAX_THREADS];
} rs_ctx;

/* Pass along i: item = an input row. */
static void
rs_x(void *cp, long r0, long r1, int w) {
    rs_ctx *C = cp;
    const axis_taps *T = C->T;
    float *row = C->scratch[w];
    for (long r = r0; r < r1; r++) {
        vf_load_f(C->t, C->src, (size_t)r * T->n_in, (size_t)T->n_in, row);
        float *d = C->dst + (size_t)r * T->n_out;
        for (int o = 0; o < T->n_out; o++) {
            const float *wt = T->w + (size_t)o * T->count;
            float s = 0;
            for (int t = 0; t < T->count; t++)
                if (wt[t] != 0)
                    s += wt[t] * row[clampi(T->first[o] + t, T->n_in)];
            d[o] = s;
        }
    }
}

/* Pass along j or k: item = an output row (i runs along the row). */
static void
rs_yz(void *cp, long r0, long r1, int w) {
    (void)w;
    rs_ctx *C = cp;
    const axis_taps *T = C->T;
    const float *src = C->src;
    const int n0 = C->in_dims[0];
    const int n1o = C->axis == 1 ? T->n_out : C->in_dims[1];
    for (long r = r0; r < r1; r++) {
        int j = (int)(r % n1o), k = (int)(r / n1o);
        int o = C->axis == 1 ? j : k;
        float *d = C->dst + (size_t)r * n0;
        for (int i = 0; i < n0; i++)
            d[i] = 0;
        const float *wt = T->w + (size_t)o * T->count;
        for (int t = 0; t < T->count; t++) {
            if (wt[t] == 0)
                continue;
            int q = clampi(T->first[o] + t, T->n_in);
            size_t srow =
                C->axis == 1 ? (size_t)k * C->in_dims[1] + q : (size_t)q * C->in_dims[1] + j;
            const float *s = src + srow * n0;
            const float c = wt[t];
            for (int i = 0; i < n0; i++)
                d[i] += c * s[i];
        }
    }
}

/* Nearest: Teem's "cheap" kernel takes input index ceil(x - 1/2). */
static int
nearest_index(int o, int n_in, int n_out) {
    return clampi((int)ceil(node_pos(o, n_in, n_out) - 0.5), n_in);
}

typedef struct nn_ctx {
    const vv_volume *in;
    vv_volume *out;
    int *map[3];
} nn_ctx;

static void
nn_body(void *cp, long r0, long r1, int w) {
    (void)w;
    nn_ctx *C = cp;
    const int *n = C->in->dims, *m = C->out->dims;
    size_t es = vv_voxel_type_size(C->in->type);
    for (long r = r0; r < r1; r++) {
        int j = (int)(r % m[1]), k = (int)(r / m[1]);
        const unsigned char *s = (const unsigned char *)C->in->data +
                                 ((size_t)C->map[2][k] * n[1] + (size_t)C->map[1][j]) * n[0] * es;
        unsigned char *d = (unsigned char *)C->out->data + (size_t)r * m[0] * es;
        for (int i = 0; i < m[0]; i++)
            memcpy(d + (size_t)i * es, s + (size_t)C->map[0][i] * es, es);
    }
}

static void
set_resampled_geometry(const vv_volume *in, vv_volume *v) {
    for (int a = 0; a < 3; a++)
        if (v->dims[a] > 1)
            v->spacing[a] = in->spacing[a] * (in->dims[a] - 1) / (v->dims[a] - 1);
    v->modification = VV_MOD_RESAMPLED;
}

vv_status
vv_filter_resample(const vv_volume *in, const int dims[3], vv_filter_kernel kernel,
                   const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "resample");
    if (s != VV_OK)
        return s;
    if (!dims)
        return vv_error_set(VV_ERR_INVALID, "resample: NULL size");
    if ((int)kernel < VV_KERNEL_NEAREST || kernel > VV_KERNEL_SINC)
        return vv_error_set(VV_ERR_INVALID, "resample: unknown kernel %d", (int)kernel);
    if ((s = vv_volume_check_size(dims, kernel == VV_KERNEL_NEAREST ? in->type : VV_F32, NULL)) !=
        VV_OK)
        return vv_error_prefix(s, "resample");
    vv_volume *v = NULL;
    if (kernel == VV_KERNEL_NEAREST) {
        if ((s = vf_new_like(in, dims, in->type, &v)) != VV_OK)
            return s;
        nn_ctx C = {.in = in, .out = v};
        for (int a = 0; a < 3 && s == VV_OK; a++) {
            C.map[a] = malloc((size_t)dims[a] * sizeof(int));
            if (!C.map[a])
                s = vv_error_set(VV_ERR_NOMEM, "resample: out of memory");
            else
                for (int q = 0; q < dims[a]; q++)
                    C.map[a][q] = nearest_index(q, in->dims[a], dims[a]);
        }
        if (s == VV_OK)
            s = vf_parallel(o, (long)dims[1] * dims[2], 64, nn_body, &C, 0, 1);
        for (int a = 0; a < 3; a++)
            free(C.map[a]);
    } else {
        axis_taps T[3];
        memset(T, 0, sizeof T);
        for (int a = 0; a < 3 && s == VV_OK; a++)
            s = taps_make(&T[a], kernel, in->dims[a], dims[a]);
        float *A = NULL, *B = NULL;
        if (s == VV_OK)
            s = vf_new_like(in, dims, VV_F32, &v);
        size_t na = (size_t)dims[0] * in->dims[1] * in->dims[2];
        size_t nb = (size_t)dims[0] * dims[1] * in->dims[2];
        if (s == VV_OK) {
            A = malloc(na * sizeof *A);
            B = malloc(nb * sizeof *B);
            if (!A || !B)
                s = vv_error_set(VV_ERR_NOMEM, "resample: out of memory");
        }
        rs_ctx C = {.src = in->data, .t = in->type, .dst = A, .axis = 0, .T = &T[0]};
        int nt = vf_threads(o);
        for (int w = 0; w < nt && s == VV_OK; w++)
            if (!(C.scratch[w] = malloc((size_t)in->dims[0] * sizeof(float))))
                s = vv_error_set(VV_ERR_NOMEM, "resample: out of memory");
        memcpy(C.in_dims, in->dims, sizeof C.in_dims);
        if (s == VV_OK)
            s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 16, rs_x, &C, 0, 0.4);
        for (int w = 0; w < nt; w++)
            free(C.scratch[w]);
        if (s == VV_OK) {
            rs_ctx Y = {.src = A, .t = VV_F32, .dst = B, .axis = 1, .T = &T[1]};
            Y.in_dims[0] = dims[0];
            Y.in_dims[1] = in->dims[1];
            Y.in_dims[2] = in->dims[2];
            s = vf_parallel(o, (long)dims[1] * in->dims[2], 16, rs_yz, &Y, 0.4, 0.7);
        }
        if (s == VV_OK) {
            rs_ctx Z = {.src = B, .t = VV_F32, .dst = v->data, .axis = 2, .T = &T[2]};
            Z.in_dims[0] = dims[0];
            Z.in_dims[1] = dims[1];
            Z.in_dims[2] = in->dims[2];
            s = vf_parallel(o, (long)dims[1] * dims[2], 16, rs_yz, &Z, 0.7, 1.0);
        }
        free(A);
        free(B);
        for (int a = 0; a < 3; a++)
            taps_free(&T[a]);
    }
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    set_resampled_geometry(in, v);
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

vv_status
vv_filter_resample_spacing(const vv_volume *in, const double spacing[3], vv_filter_kernel kernel,
                           const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "resample");
    if (s != VV_OK)
        return s;
    int dims[3];
    for (int a = 0; a < 3; a++) {
        if (!spacing || !(spacing[a] > 0) || !isfinite(spacing[a]))
            return vv_error_set(VV_ERR_INVALID,
                                "resample: spacing %g along %c: must be > 0 (world units)",
                                spacing ? spacing[a] : 0.0, "xyz"[a]);
        double n = floor((in->dims[a] - 1) * in->spacing[a] / spacing[a] + 0.5) + 1;
        if (n > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT,
                                "resample: spacing %g along %c gives %.0f voxels (at most %d)",
                                spacing[a], "xyz"[a], n, VV_VOLUME_MAX_DIM);
        dims[a] = (int)n;
    }
    return vv_filter_resample(in, dims, kernel, o, out);
}

/* ---- reshaping ----------------------------------------------------------------------------- */

/* world offset of an index step d along the volume's axes */
static void
index_offset(const vv_volume *v, const double d[3], double w[3]) {
    for (int r = 0; r < 3; r++) {
        w[r] = 0;
        for (int a = 0; a < 3; a++)
            w[r] += v->direction[3 * r + a] * v->spacing[a] * d[a];
    }
}

/*
 * Crop, pad, flip and permute are one index map: output axis b reads input
 * axis src[b] at off[b] + sgn[b] * index; outside the input it is the fill
 * value (pad). Rows are copied in parallel, whole when they map to a
 * contiguous input row.
 */
typedef struct reshape {
    const vv_volume *in;
    vv_volume *out;
    int src[3], off[3], sgn[3];
    unsigned char fill[8];
} reshape;

static void
reshape_body(void *cp, long r0, long r1, int w) {
    (void)w;
    reshape *R = cp;
    const int *n = R->in->dims, *m = R->out->dims;
    const size_t es = vv_voxel_type_size(R->in->type);
    const size_t st[3] = {1, (size_t)n[0], (size_t)n[0] * n[1]};
    const unsigned char *in = R->in->data;
    for (long r = r0; r < r1; r++) {
        int idx[3] = {0, (int)(r % m[1]), (int)(r / m[1])};
        unsigned char *d = (unsigned char *)R->out->data + (size_t)r * m[0] * es;
        /* the input coordinates of this row's first voxel, rows j and k fixed */
        long c[3];
        int inside = 1;
        for (int b = 1; b < 3; b++) {
            c[R->src[b]] = R->off[b] + (long)R->sgn[b] * idx[b];
            inside &= c[R->src[b]] >= 0 && c[R->src[b]] < n[R->src[b]];
        }
        const int a0 = R->src[0];
        for (int i = 0; i < m[0]; i++) {
            c[a0] = R->off[0] + (long)R->sgn[0] * i;
            if (!inside || c[a0] < 0 || c[a0] >= n[a0]) {
                memcpy(d + (size_t)i * es, R->fill, es);
                continue;
            }
            if (a0 == 0 && R->sgn[0] == 1) {
                /* a run of the input row: copy what lies inside at once */
                int last = (int)(n[0] - 1 - R->off[0]);
                int i1 = last < m[0] - 1 ? last : m[0] - 1;
                size_t q = (size_t)c[0] + (size_t)c[1] * st[1] + (size_t)c[2] * st[2];
                memcpy(d + (size_t)i * es, in + q * es, (size_t)(i1 - i + 1) * es);
                i = i1;
                continue;
            }
            size_t q = (size_t)c[0] + (size_t)c[1] * st[1] + (size_t)c[2] * st[2];
            memcpy(d + (size_t)i * es, in + q * es, es);
        }
    }
}

static vv_status
reshape_run(reshape *R, const vv_filter_options *o) {
    vv_status s =
        vf_parallel(o, (long)R->out->dims[1] * R->out->dims[2], 32, reshape_body, R, 0, 1);
    if (s != VV_OK) {
        vv_volume_free(R->out);
        R->out = NULL;
        return s;
    }
    vv_volume_update_range(R->out);
    return VV_OK;
}

vv_status
vv_filter_crop(const vv_volume *in, const int lo[3], const int hi[3], const vv_filter_options *o,
               vv_volume **out) {
    vv_status s = vf_check_io(in, out, "crop");
    if (s != VV_OK)
        return s;
    if (!lo || !hi)
        return vv_error_set(VV_ERR_INVALID, "crop: NULL box");
    int dims[3];
    for (int a = 0; a < 3; a++) {
        if (lo[a] < 0 || hi[a] >= in->dims[a] || lo[a] > hi[a])
            return vv_error_set(VV_ERR_INVALID,
                                "crop: box %d..%d along %c is not inside 0..%d (or empty)", lo[a],
                                hi[a], "xyz"[a], in -> dims[a] - 1);
        dims[a] = hi[a] - lo[a] + 1;
    }
    reshape R = {.in = in, .src = {0, 1, 2}, .off = {lo[0], lo[1], lo[2]}, .sgn = {1, 1, 1}};
    if ((s = vf_new_like(in, dims, in->type, &R.out)) != VV_OK)
        return s;
    double d[3] = {lo[0], lo[1], lo[2]}, w[3];
    index_offset(in, d, w);
    for (int a = 0; a < 3; a++)
        R.out->origin[a] += w[a];
    if ((s = reshape_run(&R, o)) != VV_OK)
        return s;
    *out = R.out;
    return VV_OK;
}

vv_status
vv_filter_pad(const vv_volume *in, const int before[3], const int after[3], double value,
              const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "pad");
    if (s != VV_OK)
        return s;
    if (!before || !after)
        return vv_error_set(VV_ERR_INVALID, "pad: NULL counts");
    int dims[3];
    for (int a = 0; a < 3; a++) {
        if (before[a] < 0 || after[a] < 0 ||
            (long)in->dims[a] + before[a] + after[a] > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_INVALID,
                                "pad: %d and %d voxels along %c: must be >= 0 and give at most "
                                "%d voxels",
                                before[a], after[a], "xyz"[a], VV_VOLUME_MAX_DIM);
        dims[a] = in->dims[a] + before[a] + after[a];
    }
    if ((s = vv_volume_check_size(dims, in->type, NULL)) != VV_OK)
        return vv_error_prefix(s, "pad");
    reshape R = {
        .in = in, .src = {0, 1, 2}, .off = {-before[0], -before[1], -before[2]}, .sgn = {1, 1, 1}};
    vf_store_d(in->type, R.fill, 0, 1, &value); /* converted: rounded and clamped */
    if ((s = vf_new_like(in, dims, in->type, &R.out)) != VV_OK)
        return s;
    double d[3] = {-before[0], -before[1], -before[2]}, w[3];
    index_offset(in, d, w);
    for (int a = 0; a < 3; a++)
        R.out->origin[a] += w[a];
    if ((s = reshape_run(&R, o)) != VV_OK)
        return s;
    *out = R.out;
    return VV_OK;
}

vv_status
vv_filter_flip(const vv_volume *in, int axis, const vv_filter_options *o, vv_volume **out) {
    vv_status s = vf_check_io(in, out, "flip");
    if (s != VV_OK)
        return s;
    if (axis < 0 || axis > 2)
        return vv_error_set(VV_ERR_INVALID, "flip: axis %d: must be 0, 1 or 2 (x, y, z)", axis);
    reshape R = {.in = in, .src = {0, 1, 2}, .sgn = {1, 1, 1}};
    R.off[axis] = in->dims[axis] - 1;
    R.sgn[axis] = -1;
    if ((s = vf_new_like(in, in->dims, in->type, &R.out)) != VV_OK)
        return s;
    double d[3] = {0, 0, 0}, w[3];
    d[axis] = in->dims[axis] - 1;
    index_offset(in, d, w);
    for (int a = 0; a < 3; a++) {
        R.out->origin[a] += w[a];
        R.out->direction[3 * a + axis] = -in->direction[3 * a + axis];
    }
    if ((s = reshape_run(&R, o)) != VV_OK)
        return s;
    *out = R.out;
    return VV_OK;
}

vv_status
vv_filter_permute(const vv_volume *in, const int perm[3], const vv_filter_options *o,
                  vv_volume **out) {
    vv_status s = vf_check_io(in, out, "permute");
    if (s != VV_OK)
        return s;
    if (!perm || perm[0] < 0 || perm[0] > 2 || perm[1] < 0 || perm[1] > 2 || perm[2] < 0 ||
        perm[2] > 2 || perm[0] == perm[1] || perm[1] == perm[2] || perm[0] == perm[2])
        return vv_error_set(VV_ERR_INVALID,
                            "permute: axes must be a permutation of 0, 1, 2 (x, y, z)");
    int dims[3];
    for (int a = 0; a < 3; a++)
        dims[a] = in->dims[perm[a]];
    reshape R = {.in = in, .src = {perm[0], perm[1], perm[2]}, .sgn = {1, 1, 1}};
    if ((s = vf_new_like(in, dims, in->type, &R.out)) != VV_OK)
        return s;
    for (int a = 0; a < 3; a++) {
        R.out->spacing[a] = in->spacing[perm[a]];
        for (int r = 0; r < 3; r++)
            R.out->direction[3 * r + a] = in->direction[3 * r + perm[a]];
    }
    if ((s = reshape_run(&R, o)) != VV_OK)
        return s;
    *out = R.out;
    return VV_OK;
}

/* ---- voxel type ---------------------------------------------------------------------------- */

typedef struct cast_ctx {
    const vv_volume *in;
    vv_volume *out;
    double a, b; /* out = a * in + b */
    double *buf[VF_MAX_THREADS];
} cast_ctx;

static void
cast_body(void *cp, long r0, long r1, int w) {
    cast_ctx *C = cp;
    size_t n0 = (size_t)C->in->dims[0];
    double *b = C->buf[w];
    for (long r = r0; r < r1; r++) {
        vf_load_d(C->in->type, C->in->data, (size_t)r * n0, n0, b);
        if (C->a != 1 || C->b != 0)
            for (size_t i = 0; i < n0; i++)
                b[i] = C->a * b[i] + C->b;
        vf_store_d(C->out->type, C->out->data, (size_t)r * n0, n0, b);
    }
}

static void
type_limits(vv_voxel_type t, double *lo, double *hi) {
    static const double L[] = {0, -128, 0, -32768, 0, -2147483648.0, 0, 0};
    static const double H[] = {255, 127, 65535, 32767, 4294967295.0, 2147483647.0, 1, 1};
    *lo = L[t];
    *hi = H[t];
}

vv_status
vv_filter_cast(const vv_volume *in, vv_voxel_type type, int rescale, const vv_filter_options *o,
               vv_volume **out) {
    vv_status s = vf_check_io(in, out, "cast");
    if (s != VV_OK)
        return s;
    if ((int)type < VV_U8 || type > VV_F64)
        return vv_error_set(VV_ERR_INVALID, "cast: unknown voxel type %d", (int)type);
    cast_ctx C = {.in = in, .a = 1, .b = 0};
    if (rescale) {
        vv_volume tmp = *in;
        vv_volume_update_range(&tmp); /* a copy: the input stays untouched */
        double lo, hi, vlo = tmp.range[0], vhi = tmp.range[1];
        type_limits(type, &lo, &hi);
        if (vhi > vlo && isfinite(vlo) && isfinite(vhi)) {
            C.a = (hi - lo) / (vhi - vlo);
            C.b = lo - vlo * C.a;
        } else {
            C.a = 0;
            C.b = lo;
        }
    }
    vv_volume *v;
    if ((s = vf_new_like(in, in->dims, type, &v)) != VV_OK)
        return s;
    C.out = v;
    v->modification = in->modification;
    int nt = vf_threads(o);
    for (int w = 0; w < nt && s == VV_OK; w++)
        if (!(C.buf[w] = malloc((size_t)in->dims[0] * sizeof(double))))
            s = vv_error_set(VV_ERR_NOMEM, "cast: out of memory");
    if (s == VV_OK)
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 64, cast_body, &C, 0, 1);
    for (int w = 0; w < nt; w++)
        free(C.buf[w]);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}
