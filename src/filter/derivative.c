/*
 * Derivatives: gradient (central differences or derivative of Gaussian),
 * Laplacian, and Frangi's Hessian-based vesselness (Frangi et al., MICCAI
 * 1998, "Multiscale vessel enhancement filtering").
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "filter/filter_internal.h"

/* M = (D S)^-T: maps index-space derivatives (per voxel step) to world ones. */
static vv_status
index_to_world_gradient(const vv_volume *v, double M[9]) {
    double A[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            A[3 * r + c] = v->direction[3 * r + c] * v->spacing[c];
    double det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
                 A[2] * (A[3] * A[7] - A[4] * A[6]);
    if (!(fabs(det) > 0) || !isfinite(det))
        return vv_error_set(VV_ERR_INVALID, "gradient: the direction matrix is singular");
    /* inverse transpose = cofactor matrix / det */
    M[0] = (A[4] * A[8] - A[5] * A[7]) / det;
    M[1] = -(A[3] * A[8] - A[5] * A[6]) / det;
    M[2] = (A[3] * A[7] - A[4] * A[6]) / det;
    M[3] = -(A[1] * A[8] - A[2] * A[7]) / det;
    M[4] = (A[0] * A[8] - A[2] * A[6]) / det;
    M[5] = -(A[0] * A[7] - A[1] * A[6]) / det;
    M[6] = (A[1] * A[5] - A[2] * A[4]) / det;
    M[7] = -(A[0] * A[5] - A[2] * A[3]) / det;
    M[8] = (A[0] * A[4] - A[1] * A[3]) / det;
    return VV_OK;
}

/* Central differences along i, j, k (per voxel step) into g[0..2]. */
typedef struct cd_ctx {
    const vv_volume *in;
    float *g[3];
    double *buf[VF_MAX_THREADS]; /* 3 rows: k-1.., j.. */
    double M[9];
} cd_ctx;

static double
at(const vv_volume *v, int i, int j, int k) {
    return vv_voxel_value(v->type, v->data, ((size_t)k * v->dims[1] + j) * v->dims[0] + i);
}

static double
diff(const vv_volume *v, int i, int j, int k, int a) {
    int idx[3] = {i, j, k};
    int n = v->dims[a];
    if (n == 1)
        return 0;
    int lo = idx[a] > 0 ? idx[a] - 1 : 0, hi = idx[a] < n - 1 ? idx[a] + 1 : n - 1;
    int p[3] = {i, j, k}, q[3] = {i, j, k};
    p[a] = hi;
    q[a] = lo;
    return (at(v, p[0], p[1], p[2]) - at(v, q[0], q[1], q[2])) / (hi - lo);
}

static void
cd_body(void *cp, long r0, long r1, int w) {
    (void)w;
    cd_ctx *C = cp;
    const vv_volume *v = C->in;
    const int n0 = v->dims[0], n1 = v->dims[1];
    for (long r = r0; r < r1; r++) {
        int j = (int)(r % n1), k = (int)(r / n1);
        for (int i = 0; i < n0; i++) {
            double d[3] = {diff(v, i, j, k, 0), diff(v, i, j, k, 1), diff(v, i, j, k, 2)};
            size_t q = (size_t)r * n0 + i;
            for (int c = 0; c < 3; c++)
                C->g[c][q] =
                    (float)(C->M[3 * c] * d[0] + C->M[3 * c + 1] * d[1] + C->M[3 * c + 2] * d[2]);
        }
    }
}

typedef struct mix_ctx {
    float *g[3];
    double M[9];
    size_t n0;
} mix_ctx;

static void
mix_body(void *cp, long r0, long r1, int w) {
    (void)w;
    mix_ctx *C = cp;
    for (size_t q = (size_t)r0 * C->n0; q < (size_t)r1 * C->n0; q++) {
        double d[3] = {C->g[0][q], C->g[1][q], C->g[2][q]};
        for (int c = 0; c < 3; c++)
            C->g[c][q] =
                (float)(C->M[3 * c] * d[0] + C->M[3 * c + 1] * d[1] + C->M[3 * c + 2] * d[2]);
    }
}

vv_status
vv_filter_gradient(const vv_volume *in, double sigma, const vv_filter_options *o,
                   vv_volume *out[3]) {
    vv_status s = vf_check_io(in, out, "gradient");
    if (s != VV_OK)
        return s;
    if (!(sigma >= 0) || !isfinite(sigma))
        return vv_error_set(VV_ERR_INVALID,
                            "gradient: sigma %g: must be 0 (central differences) or > 0 (world "
                            "units)",
                            sigma);
    double M[9];
    if ((s = index_to_world_gradient(in, M)) != VV_OK)
        return s;
    vv_volume *g[3] = {NULL, NULL, NULL};
    for (int c = 0; c < 3 && s == VV_OK; c++)
        s = vf_new_like(in, in->dims, VV_F32, &g[c]);
    if (s == VV_OK && sigma == 0) {
        cd_ctx C = {.in = in, .g = {g[0]->data, g[1]->data, g[2]->data}};
        memcpy(C.M, M, sizeof M);
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 16, cd_body, &C, 0, 1);
    } else if (s == VV_OK) {
        vf_kernel k0[3] = {{0}}, k1[3] = {{0}};
        for (int a = 0; a < 3 && s == VV_OK; a++) {
            double sv = sigma / in->spacing[a];
            if ((s = vf_kernel_gauss(&k0[a], sv, 0)) == VV_OK)
                s = vf_kernel_gauss(&k1[a], sv, 1);
            if (s != VV_OK)
                vv_error_prefix(s, "gradient: axis %c", "xyz"[a]);
        }
        float *tmp = NULL;
        if (s == VV_OK && !(tmp = malloc((size_t)vv_volume_voxel_count(in) * sizeof(float))))
            s = vv_error_set(VV_ERR_NOMEM, "gradient: out of memory");
        for (int c = 0; c < 3 && s == VV_OK; c++) {
            const vf_kernel *kp[3] = {&k0[0], &k0[1], &k0[2]};
            kp[c] = &k1[c];
            s = vf_separable(in->data, in->type, in->dims, kp, g[c]->data, tmp, o, c / 3.0,
                             (c + 1) / 3.0);
        }
        free(tmp);
        for (int a = 0; a < 3; a++) {
            vf_kernel_free(&k0[a]);
            vf_kernel_free(&k1[a]);
        }
        if (s == VV_OK) {
            mix_ctx X = {.g = {g[0]->data, g[1]->data, g[2]->data}, .n0 = (size_t)in->dims[0]};
            memcpy(X.M, M, sizeof M);
            vv_filter_options q = o ? *o : (vv_filter_options){0};
            q.progress.fn = NULL;
            s = vf_parallel(&q, (long)in->dims[1] * in->dims[2], 64, mix_body, &X, 0, 0);
        }
    }
    if (s != VV_OK) {
        for (int c = 0; c < 3; c++)
            vv_volume_free(g[c]);
        return s;
    }
    for (int c = 0; c < 3; c++) {
        vv_volume_update_range(g[c]);
        out[c] = g[c];
    }
    return VV_OK;
}

vv_status
vv_filter_gradient_magnitude(const vv_volume *in, double sigma, const vv_filter_options *o,
                             vv_volume **out) {
    vv_volume *g[3];
    vv_status s = vf_check_io(in, out, "gradient magnitude");
    if (s != VV_OK || (s = vv_filter_gradient(in, sigma, o, g)) != VV_OK)
        return s;
    float *a = g[0]->data, *b = g[1]->data, *c = g[2]->data;
    size_t n = (size_t)vv_volume_voxel_count(in);
    for (size_t q = 0; q < n; q++)
        a[q] = sqrtf(a[q] * a[q] + b[q] * b[q] + c[q] * c[q]);
    vv_volume_free(g[1]);
    vv_volume_free(g[2]);
    vv_volume_update_range(g[0]);
    *out = g[0];
    return VV_OK;
}

/* ---- Laplacian ---------------------------------------------------------------------------- */

typedef struct lap_ctx {
    const vv_volume *in;
    float *d;
    double ih2[3];
} lap_ctx;

static void
lap_body(void *cp, long r0, long r1, int w) {
    (void)w;
    lap_ctx *C = cp;
    const vv_volume *v = C->in;
    const int n0 = v->dims[0], n1 = v->dims[1], n2 = v->dims[2];
    for (long r = r0; r < r1; r++) {
        int j = (int)(r % n1), k = (int)(r / n1);
        for (int i = 0; i < n0; i++) {
            double c = at(v, i, j, k);
            double s =
                (at(v, vf_reflect(i - 1, n0), j, k) + at(v, vf_reflect(i + 1, n0), j, k) - 2 * c) *
                C->ih2[0];
            s += (at(v, i, vf_reflect(j - 1, n1), k) + at(v, i, vf_reflect(j + 1, n1), k) - 2 * c) *
                 C->ih2[1];
            s += (at(v, i, j, vf_reflect(k - 1, n2)) + at(v, i, j, vf_reflect(k + 1, n2)) - 2 * c) *
                 C->ih2[2];
            C->d[(size_t)r * n0 + i] = (float)s;
        }
    }
}

/* Sum over axes of the separable second derivatives, scaled by 1/h_a^2 (or
 * for the Hessian, the product of two first derivatives). */
static vv_status
second_derivative(const vv_volume *in, double sigma, int a, int b, const vv_filter_options *o,
                  float *dst, float *tmp, double p0, double p1) {
    vf_kernel k[3] = {{0}};
    vv_status s = VV_OK;
    const vf_kernel *kp[3];
    for (int x = 0; x < 3 && s == VV_OK; x++) {
        double sv = sigma / in->spacing[x];
        int order = (x == a) + (x == b);
        s = vf_kernel_gauss(&k[x], sv, order);
        kp[x] = &k[x];
    }
    if (s == VV_OK)
        s = vf_separable(in->data, in->type, in->dims, kp, dst, tmp, o, p0, p1);
    for (int x = 0; x < 3; x++)
        vf_kernel_free(&k[x]);
    if (s == VV_OK) {
        float f = (float)(1.0 / (in->spacing[a] * in->spacing[b]));
        size_t n = (size_t)vv_volume_voxel_count(in);
        for (size_t q = 0; q < n; q++)
            dst[q] *= f;
    }
    return s;
}

vv_status
vv_filter_laplacian(const vv_volume *in, double sigma, const vv_filter_options *o,
                    vv_volume **out) {
    vv_status s = vf_check_io(in, out, "laplacian");
    if (s != VV_OK)
        return s;
    if (!(sigma >= 0) || !isfinite(sigma))
        return vv_error_set(VV_ERR_INVALID,
                            "laplacian: sigma %g: must be 0 (differences) or > 0 (world units)",
                            sigma);
    vv_volume *v;
    if ((s = vf_new_like(in, in->dims, VV_F32, &v)) != VV_OK)
        return s;
    if (sigma == 0) {
        lap_ctx C = {.in = in, .d = v->data};
        for (int a = 0; a < 3; a++)
            C.ih2[a] = in->dims[a] > 1 ? 1.0 / (in->spacing[a] * in->spacing[a]) : 0;
        s = vf_parallel(o, (long)in->dims[1] * in->dims[2], 16, lap_body, &C, 0, 1);
    } else {
        size_t n = (size_t)vv_volume_voxel_count(in);
        float *tmp = malloc(n * sizeof *tmp), *part = malloc(n * sizeof *part);
        float *d = v->data;
        if (!tmp || !part)
            s = vv_error_set(VV_ERR_NOMEM, "laplacian: out of memory");
        for (int a = 0; a < 3 && s == VV_OK; a++) {
            s = second_derivative(in, sigma, a, a, o, a == 0 ? d : part, tmp, a / 3.0,
                                  (a + 1) / 3.0);
            if (s == VV_OK && a > 0)
                for (size_t q = 0; q < n; q++)
                    d[q] += part[q];
        }
        free(tmp);
        free(part);
    }
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

/* ---- Frangi vesselness --------------------------------------------------------------------- */

/* Eigenvalues of the symmetric matrix [a d e; d b f; e f c], sorted by absolute value. */
static void
sym3_eigen(double a, double b, double c, double d, double e, double f, double l[3]) {
    double p1 = d * d + e * e + f * f;
    double q = (a + b + c) / 3.0;
    double ev[3];
    if (p1 <= 1e-30 * (a * a + b * b + c * c) || p1 == 0) {
        ev[0] = a;
        ev[1] = b;
        ev[2] = c;
    } else {
        double p2 = (a - q) * (a - q) + (b - q) * (b - q) + (c - q) * (c - q) + 2 * p1;
        double p = sqrt(p2 / 6.0);
        double B[6] = {(a - q) / p, (b - q) / p, (c - q) / p, d / p, e / p, f / p};
        double detB = B[0] * (B[1] * B[2] - B[5] * B[5]) - B[3] * (B[3] * B[2] - B[5] * B[4]) +
                      B[4] * (B[3] * B[5] - B[1] * B[4]);
        double r = detB / 2.0;
        double phi = r <= -1 ? M_PI / 3.0 : r >= 1 ? 0 : acos(r) / 3.0;
        ev[0] = q + 2 * p * cos(phi);
        ev[2] = q + 2 * p * cos(phi + 2.0 * M_PI / 3.0);
        ev[1] = 3 * q - ev[0] - ev[2];
    }
    /* sort by |value| */
    for (int i = 1; i < 3; i++)
        for (int j = i; j > 0 && fabs(ev[j]) < fabs(ev[j - 1]); j--) {
            double t = ev[j];
            ev[j] = ev[j - 1];
            ev[j - 1] = t;
        }
    memcpy(l, ev, sizeof ev);
}

typedef struct frangi_ctx {
    float *H[6]; /* xx yy zz xy xz yz */
    float *S;    /* Frobenius norm, then reused */
    float *V;    /* running maximum */
    size_t n0;
    double a2, b2, c2; /* 2 alpha^2, 2 beta^2, 2 c^2 */
    int bright, pass;  /* pass 0: S; pass 1: V */
} frangi_ctx;

static void
frangi_body(void *cp, long r0, long r1, int w) {
    (void)w;
    frangi_ctx *C = cp;
    for (size_t q = (size_t)r0 * C->n0; q < (size_t)r1 * C->n0; q++) {
        double l[3];
        sym3_eigen(C->H[0][q], C->H[1][q], C->H[2][q], C->H[3][q], C->H[4][q], C->H[5][q], l);
        if (!C->bright) {
            l[0] = -l[0];
            l[1] = -l[1];
            l[2] = -l[2];
        }
        double S = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
        if (C->pass == 0) {
            C->S[q] = (float)S;
            continue;
        }
        double v = 0;
        if (l[1] < 0 && l[2] < 0) {
            double Ra = fabs(l[1]) / fabs(l[2]);
            double Rb = fabs(l[0]) / sqrt(fabs(l[1] * l[2]));
            v = (1 - exp(-Ra * Ra / C->a2)) * exp(-Rb * Rb / C->b2) * (1 - exp(-S * S / C->c2));
        }
        if (v > C->V[q] || v != v)
            C->V[q] = (float)v;
    }
}

vv_status
vv_filter_vesselness(const vv_volume *in, const double *sigmas, int n_scales, double alpha,
                     double beta, double c, int bright, const vv_filter_options *o,
                     vv_volume **out) {
    vv_status s = vf_check_io(in, out, "vesselness");
    if (s != VV_OK)
        return s;
    if (!sigmas || n_scales < 1 || n_scales > 16)
        return vv_error_set(VV_ERR_INVALID, "vesselness: %d scales: must be 1..16", n_scales);
    for (int i = 0; i < n_scales; i++)
        if (!(sigmas[i] > 0) || !isfinite(sigmas[i]))
            return vv_error_set(VV_ERR_INVALID, "vesselness: scale %g: must be > 0 (world units)",
                                sigmas[i]);
    if (!(alpha > 0) || !(beta > 0) || !(c >= 0) || !isfinite(alpha) || !isfinite(beta) ||
        !isfinite(c))
        return vv_error_set(VV_ERR_INVALID,
                            "vesselness: alpha %g, beta %g must be > 0 and c %g >= 0", alpha, beta,
                            c);
    size_t n = (size_t)vv_volume_voxel_count(in);
    vv_volume *v;
    if ((s = vf_new_like(in, in->dims, VV_F32, &v)) != VV_OK)
        return s;
    frangi_ctx C = {.V = v->data, .n0 = (size_t)in->dims[0], .bright = bright != 0};
    C.a2 = 2 * alpha * alpha;
    C.b2 = 2 * beta * beta;
    float *tmp = malloc(n * sizeof *tmp);
    C.S = malloc(n * sizeof *C.S);
    if (!tmp || !C.S)
        s = vv_error_set(VV_ERR_NOMEM, "vesselness: out of memory");
    for (int h = 0; h < 6 && s == VV_OK; h++)
        if (!(C.H[h] = malloc(n * sizeof(float))))
            s = vv_error_set(VV_ERR_NOMEM, "vesselness: out of memory");
    static const int pa[6] = {0, 1, 2, 0, 0, 1}, pb[6] = {0, 1, 2, 1, 2, 2};
    long rows = (long)in->dims[1] * in->dims[2];
    for (int sc = 0; sc < n_scales && s == VV_OK; sc++) {
        double f0 = (double)sc / n_scales, df = 1.0 / n_scales;
        for (int h = 0; h < 6 && s == VV_OK; h++) {
            s = second_derivative(in, sigmas[sc], pa[h], pb[h], o, C.H[h], tmp,
                                  f0 + df * 0.9 * h / 6, f0 + df * 0.9 * (h + 1) / 6);
            float f = (float)(sigmas[sc] * sigmas[sc]); /* scale normalisation */
            for (size_t q = 0; s == VV_OK && q < n; q++)
                C.H[h][q] *= f;
        }
        if (s != VV_OK)
            break;
        vv_filter_options q = o ? *o : (vv_filter_options){0};
        q.progress.fn = NULL;
        C.pass = 0;
        vf_parallel(&q, rows, 16, frangi_body, &C, 0, 0);
        double cc = c;
        if (cc == 0) {
            float m = 0;
            for (size_t i = 0; i < n; i++)
                if (C.S[i] > m)
                    m = C.S[i];
            cc = m > 0 ? 0.5 * m : 1;
        }
        C.c2 = 2 * cc * cc;
        C.pass = 1;
        s = vf_parallel(o, rows, 16, frangi_body, &C, f0 + 0.9 * df, f0 + df);
    }
    free(tmp);
    free(C.S);
    for (int h = 0; h < 6; h++)
        free(C.H[h]);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}
