/*
 * Scan conversion of triangle meshes onto a voxel grid, for volume sampling.
 *
 * Along every grid row parallel to an axis, the crossings of the row with
 * the triangles are found with exact-rule point-in-triangle tests in the
 * plane of the two other axes. Ties (a row through an edge or a vertex,
 * common for meshes made by marching cubes, whose vertices lie on grid
 * lines) are broken by simulation of simplicity: the row is treated as
 * moved by (eps, eps^2), with each edge evaluated in one canonical vertex
 * order, so a row through a shared edge or vertex crosses exactly one of
 * the triangles around it. Inside/outside is the generalized winding
 * number (see mesh_holes.c): the signed crossings of the mesh closed by
 * caps over its holes, counted along the x, y and z rows (median of the
 * three), less the caps' solid angles near the holes (caps_correct); holes
 * too large for that fall back to row votes (row_votes). The distance band uses the crossings of
 * all three axes: a voxel near a crossing gets its distance to the crossed triangle's plane, and
 * keeps the smallest; every surface point has a normal component of at least 1/sqrt(3) along some
 * axis, so each voxel near the surface meets a well-conditioned crossing (those with |n_a| < 0.5
 * are not used for the band).
 */
#include <immintrin.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "modeling_internal.h"

typedef struct crossing {
    float t;     /* crossing position along the row, index units */
    float slope; /* world distance to the triangle's plane per index step; 0: parity only */
    int sign;    /* +1 or -1: the side the triangle faces along the row */
} crossing;

static int
cmp_crossing(const void *a, const void *b) {
    const crossing *x = a, *y = b;
    if (x->t != y->t)
        return x->t < y->t ? -1 : 1;
    if (x->slope != y->slope)
        return x->slope < y->slope ? -1 : 1;
    return (x->sign > y->sign) - (x->sign < y->sign);
}

/* Sign of the edge function of (a -> b) at p, with the SoS tie-break. The
 * edge is evaluated in lexicographic vertex order so both triangles sharing
 * it get exactly opposite values. */
static int
edge_sign(const double *a, const double *b, double pb, double pc) {
    int flip = 0;
    if (b[0] < a[0] || (b[0] == a[0] && b[1] < a[1])) {
        const double *t = a;
        a = b;
        b = t;
        flip = 1;
    }
    double db = b[0] - a[0], dc = b[1] - a[1];
    double e = db * (pc - a[1]) - dc * (pb - a[0]);
    int s;
    if (e > 0)
        s = 1;
    else if (e < 0)
        s = -1;
    else if (dc != 0)
        s = dc < 0 ? 1 : -1; /* d e / d pb = -dc, moved by eps */
    else
        s = db > 0 ? 1 : -1; /* d e / d pc = db, moved by eps^2 */
    return flip ? -s : s;
}

static double
edge_value(const double *a, const double *b, double pb, double pc) {
    return (b[0] - a[0]) * (pc - a[1]) - (b[1] - a[1]) * (pb - a[0]);
}

typedef struct scan_ctx {
    const double *V; /* index coordinates, 3 per vertex */
    const uint32_t *tri;
    size_t ntri;
    const int *dims;
    const double *spacing;
    size_t ncore; /* triangles from ncore on are caps: they count in the winding, not the band */
} scan_ctx;

/* Clamped to [lo, hi] (NaN gives lo), then floor or ceiling as int: the
 * index ranges below without libm calls. */
static inline double
clampd(double x, double lo, double hi) {
    return x >= lo ? (x <= hi ? x : hi) : lo;
}
static inline int
ifloor(double x) {
    int i = (int)x;
    return i - (x < i);
}
static inline int
iceil(double x) {
    int i = (int)x;
    return i + (x > i);
}
#define MIN3(a, b, c) ((a) < (b) ? ((a) < (c) ? (a) : (c)) : ((b) < (c) ? (b) : (c)))
#define MAX3(a, b, c) ((a) > (b) ? ((a) > (c) ? (a) : (c)) : ((b) > (c) ? (b) : (c)))

/* A crossing with its row, collected per thread. */
typedef struct rowx {
    size_t row;
    crossing x;
} rowx;

typedef struct xbuf {
    rowx *v;
    size_t n, cap;
    int oom;
} xbuf;

static void
xbuf_push(xbuf *b, size_t row, crossing x) {
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 4096;
        rowx *v = realloc(b->v, cap * sizeof *v);
        if (!v) {
            b->oom = 1;
            return;
        }
        b->v = v;
        b->cap = cap;
    }
    b->v[b->n++] = (rowx){row, x};
}

/* Appends the crossings of the triangle P with the rows along axis a whose
 * (b, c) indices lie in [jb0, jb1] x [jc0, jc1]. */
static void
triangle_rows_axis(const scan_ctx *c, const double *const P[3], int cap, int a, int jb0, int jb1,
                   int jc0, int jc1, xbuf *out) {
    int b = (a + 1) % 3, cc = (a + 2) % 3;
    double q[3][2];
    for (int v = 0; v < 3; v++) {
        q[v][0] = P[v][b];
        q[v][1] = P[v][cc];
    }
    double area = edge_value(q[0], q[1], q[2][0], q[2][1]);
    if (area == 0.0 || !isfinite(area))
        return;
    int sgn = area > 0 ? 1 : -1;
    float slope = cap ? 0.0f : -1.0f; /* computed at the first crossing */
    for (int jc = jc0; jc <= jc1; jc++) {
        for (int jb = jb0; jb <= jb1; jb++) {
            if (edge_sign(q[0], q[1], jb, jc) != sgn || edge_sign(q[1], q[2], jb, jc) != sgn ||
                edge_sign(q[2], q[0], jb, jc) != sgn)
                continue;
            if (slope < 0) {
                /* world normal: index edges scaled by the spacing */
                double e1[3], e2[3];
                for (int k = 0; k < 3; k++) {
                    e1[k] = (P[1][k] - P[0][k]) * c->spacing[k];
                    e2[k] = (P[2][k] - P[0][k]) * c->spacing[k];
                }
                double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                               e1[0] * e2[1] - e1[1] * e2[0]};
                double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                double cosa = len > 0 ? fabs(n[a]) / len : 0.0;
                slope = cosa >= 0.5 ? (float)(c->spacing[a] * cosa) : 0.0f;
            }
            double l0 = edge_value(q[1], q[2], jb, jc) / area;
            double l1 = edge_value(q[2], q[0], jb, jc) / area;
            double l2 = 1.0 - l0 - l1;
            double tt = l0 * P[0][a] + l1 * P[1][a] + l2 * P[2][a];
            crossing x = {(float)tt, slope, sgn};
            xbuf_push(out, (size_t)jc * (size_t)c->dims[b] + (size_t)jb, x);
        }
    }
}

/* Appends the crossings of triangle t with the rows along each axis. */
static void
triangle_rows(const scan_ctx *c, size_t t, xbuf out[3]) {
    const double *P[3];
    for (int v = 0; v < 3; v++)
        P[v] = c->V + 3 * (size_t)c->tri[3 * t + v];
    /* the rows a triangle can cross: index ranges of its box, per axis */
    int lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = iceil(clampd(MIN3(P[0][k], P[1][k], P[2][k]), -1.0, c->dims[k]));
        hi[k] = ifloor(clampd(MAX3(P[0][k], P[1][k], P[2][k]), -1.0, c->dims[k]));
        if (lo[k] < 0)
            lo[k] = 0;
        if (hi[k] > c->dims[k] - 1)
            hi[k] = c->dims[k] - 1;
    }
    for (int a = 0; a < 3; a++) {
        int b = (a + 1) % 3, cc = (a + 2) % 3;
        if (lo[b] > hi[b] || lo[cc] > hi[cc])
            continue;
        triangle_rows_axis(c, P, t >= c->ncore, a, lo[b], hi[b], lo[cc], hi[cc], &out[a]);
    }
}

/* ---- triangles in index coordinates ----------------------------------- */

typedef struct tri_list {
    uint32_t *t; /* 3 per triangle */
    size_t n, cap;
    double *V; /* index coordinates, 3 per vertex */
    size_t nv, capv;
} tri_list;

static int
tl_grow(tri_list *L, size_t nt, size_t nv) {
    if (nt > L->cap) {
        size_t cap = nt + nt / 2 + 16;
        uint32_t *t = realloc(L->t, cap * 3 * sizeof *t);
        if (!t)
            return 0;
        L->t = t;
        L->cap = cap;
    }
    if (nv > L->capv) {
        size_t cap = nv + nv / 2 + 16;
        double *v = realloc(L->V, cap * 3 * sizeof *v);
        if (!v)
            return 0;
        L->V = v;
        L->capv = cap;
    }
    return 1;
}

/* ---- exact distances for shells ------------------------------------------ */

/* Squared distance from p to triangle abc (Ericson, Real-Time Collision
 * Detection, 5.1.5). */
static double
point_triangle_d2(const double p[3], const double a[3], const double b[3], const double c[3]) {
    double ab[3], ac[3], ap[3], q[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
    double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        for (int k = 0; k < 3; k++)
            q[k] = a[k];
        goto out;
    }
    double bp[3];
    for (int k = 0; k < 3; k++)
        bp[k] = p[k] - b[k];
    double d3 = DOT(ab, bp), d4 = DOT(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
        for (int k = 0; k < 3; k++)
            q[k] = b[k];
        goto out;
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        for (int k = 0; k < 3; k++)
            q[k] = a[k] + v * ab[k];
        goto out;
    }
    double cp[3];
    for (int k = 0; k < 3; k++)
        cp[k] = p[k] - c[k];
    double d5 = DOT(ab, cp), d6 = DOT(ac, cp);
    if (d6 >= 0 && d5 <= d6) {
        for (int k = 0; k < 3; k++)
            q[k] = c[k];
        goto out;
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        for (int k = 0; k < 3; k++)
            q[k] = a[k] + w * ac[k];
        goto out;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++)
            q[k] = b[k] + w * (c[k] - b[k]);
        goto out;
    }
    {
        double den = 1.0 / (va + vb + vc), v = vb * den, w = vc * den;
        for (int k = 0; k < 3; k++)
            q[k] = a[k] + ab[k] * v + ac[k] * w;
    }
out:;
    double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    return DOT(d, d);
#undef DOT
}

/* Unsigned distance (world units, clamped to band) of every voxel to the
 * triangles: each slab of SLAB z layers is one task over the triangles
 * whose expanded box meets it, so no two threads write the same voxel. */
#define SLAB 4
static vv_status
shell_distance(const tri_list *L, const int dims[3], const double spacing[3], double band,
               float *sd, int threads) {
    size_t n = (size_t)dims[0] * dims[1] * dims[2];
    for (size_t i = 0; i < n; i++)
        sd[i] = (float)band;
    int nslab = (dims[2] + SLAB - 1) / SLAB;
    size_t *cnt = calloc((size_t)nslab + 1, sizeof *cnt), *pos = NULL;
    uint32_t *bins = NULL;
    double r[3];
    for (int k = 0; k < 3; k++)
        r[k] = band / spacing[k];
    if (!cnt)
        return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory");
    for (int pass = 0; pass < 2; pass++) {
        for (size_t t = 0; t < L->n; t++) {
            double lo = INFINITY, hi = -INFINITY;
            for (int v = 0; v < 3; v++) {
                double z = L->V[3 * (size_t)L->t[3 * t + v] + 2];
                lo = fmin(lo, z);
                hi = fmax(hi, z);
            }
            int k0 = (int)fmax(0, ceil(lo - r[2])), k1 = (int)fmin(dims[2] - 1, floor(hi + r[2]));
            for (int s = k0 / SLAB; k0 <= k1 && s <= k1 / SLAB; s++) {
                if (pass == 0)
                    cnt[s]++;
                else
                    bins[pos[s]++] = (uint32_t)t;
            }
        }
        if (pass == 0) {
            size_t total = 0;
            pos = malloc(((size_t)nslab + 1) * sizeof *pos);
            for (int s = 0; pos && s <= nslab; s++) {
                size_t c = s < nslab ? cnt[s] : 0;
                pos[s] = cnt[s] = total;
                total += c;
            }
            bins = malloc((total ? total : 1) * sizeof *bins);
            if (!pos || !bins) {
                free(cnt);
                free(pos);
                free(bins);
                return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory");
            }
        }
    }
    float b2 = (float)(band * band);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (int s = 0; s < nslab; s++) {
        int z0 = s * SLAB, z1 = z0 + SLAB - 1 < dims[2] - 1 ? z0 + SLAB - 1 : dims[2] - 1;
        for (size_t q = cnt[s]; q < pos[s]; q++) {
            size_t t = bins[q];
            double P[3][3], lo[3] = {INFINITY, INFINITY, INFINITY},
                            hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (int v = 0; v < 3; v++)
                for (int k = 0; k < 3; k++) {
                    double x = L->V[3 * (size_t)L->t[3 * t + v] + k];
                    lo[k] = fmin(lo[k], x);
                    hi[k] = fmax(hi[k], x);
                    P[v][k] = x * spacing[k];
                }
            int i0[3], i1[3];
            for (int k = 0; k < 3; k++) {
                i0[k] = (int)fmax(0, ceil(lo[k] - r[k]));
                i1[k] = (int)fmin(dims[k] - 1, floor(hi[k] + r[k]));
            }
            if (i0[2] < z0)
                i0[2] = z0;
            if (i1[2] > z1)
                i1[2] = z1;
            for (int z = i0[2]; z <= i1[2]; z++)
                for (int y = i0[1]; y <= i1[1]; y++)
                    for (int x = i0[0]; x <= i1[0]; x++) {
                        double p[3] = {x * spacing[0], y * spacing[1], z * spacing[2]};
                        double d2 = point_triangle_d2(p, P[0], P[1], P[2]);
                        float *o = sd + ((size_t)z * dims[1] + y) * dims[0] + x;
                        if (d2 < b2 && (float)d2 < *o * *o)
                            *o = (float)sqrt(d2);
                    }
        }
    }
    free(cnt);
    free(pos);
    free(bins);
    return VV_OK;
}

/* ---- solid angles of the hole caps ---------------------------------------- */

/* Signed 4-bit count of axis a in a packed per-voxel winding word. */
static inline int
nibble(uint16_t v, int a) {
    int n = (v >> (4 * a)) & 15;
    return n >= 8 ? n - 16 : n;
}

/* Work above which the caps' exact solid angles take too long (triangle-voxel pairs). */
#define CAP_WORK_MAX 4.0e9
/* The winding number error allowed from the caps' far fields left out. */
#define CAP_FAR_ERROR 0.005

/* atan2 by the polynomial of Abramowitz and Stegun 4.4.49 (|error| <= 2e-8
 * rad on [0, 1]), without branches so a loop of it vectorizes: ample for a
 * sum of solid angles compared with 2 pi. */
static inline __attribute__((always_inline)) double
atan2_as(double y, double x) {
    double ax = fabs(x), ay = fabs(y), mx = ax > ay ? ax : ay, mn = ax > ay ? ay : ax;
    double a = mn / (mx > 0 ? mx : 1.0), t = a * a;
    double r = -0.0040540580;
    r = r * t + 0.0218612288;
    r = r * t - 0.0559098861;
    r = r * t + 0.0964200441;
    r = r * t - 0.1390853351;
    r = r * t + 0.1994653599;
    r = r * t - 0.3332985605;
    r = (r * t + 0.9999993329) * a;
    r = ay > ax ? M_PI_2 - r : r;
    r = x < 0 ? M_PI - r : r;
    return y < 0 ? -r : r;
}

typedef struct cap_info {
    double c[3];       /* the fan's centre, world-scaled index frame */
    double A[3];       /* vector area of the fan */
    double R;          /* radius of the ball around c holding the fan */
    double n[3];       /* unit normal of the fan's mean plane (A / |A|) */
    double h0, h1;     /* the fan's extent along n, from c */
    double reach2;     /* squared distance beyond which the far field is left out */
    size_t i0, i1;     /* the loop in H->loop_v */
    double *X, *Y, *Z; /* its vertices, world-scaled, i1 - i0 + 1 (the first repeated) */
} cap_info;

/* Half the solid angle of cap k's fan at p (d = c - p, ld = |d|): the
 * Van Oosterom-Strackee sum over the fan triangles (c, next, this) from
 * triangle i on. */
static double
fan_half_omega_from(const cap_info *k, size_t i, const double p[3], const double d[3], double ld) {
    const double *X = k->X, *Y = k->Y, *Z = k->Z;
    size_t n = k->i1 - k->i0;
    double o = 0.0;
    for (; i < n; i++) {
        double ax = X[i] - p[0], ay = Y[i] - p[1], az = Z[i] - p[2];
        double bx = X[i + 1] - p[0], by = Y[i + 1] - p[1], bz = Z[i + 1] - p[2];
        double al = sqrt(ax * ax + ay * ay + az * az), bl = sqrt(bx * bx + by * by + bz * bz);
        double det =
            d[0] * (by * az - bz * ay) - d[1] * (bx * az - bz * ax) + d[2] * (bx * ay - by * ax);
        double db = d[0] * bx + d[1] * by + d[2] * bz, da = d[0] * ax + d[1] * ay + d[2] * az;
        double ba = bx * ax + by * ay + bz * az;
        o += atan2_as(det, ld * bl * al + db * al + da * bl + ba * ld);
    }
    return o;
}

/* fan_half_omega_from(k, 0, ...), four fan triangles at a time (AVX2 and FMA). */
__attribute__((target("avx2,fma"))) static double
fan_half_omega_avx2(const cap_info *k, const double p[3], const double d[3], double ld) {
    const double *X = k->X, *Y = k->Y, *Z = k->Z;
    size_t n = k->i1 - k->i0, i = 0;
    const __m256d px = _mm256_set1_pd(p[0]), py = _mm256_set1_pd(p[1]), pz = _mm256_set1_pd(p[2]);
    const __m256d dx = _mm256_set1_pd(d[0]), dy = _mm256_set1_pd(d[1]), dz = _mm256_set1_pd(d[2]);
    const __m256d vld = _mm256_set1_pd(ld), zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
    const __m256d sign = _mm256_set1_pd(-0.0), half_pi = _mm256_set1_pd(M_PI_2),
                  pi = _mm256_set1_pd(M_PI);
    static const double cf[8] = {-0.0040540580, 0.0218612288, -0.0559098861, 0.0964200441,
                                 -0.1390853351, 0.1994653599, -0.3332985605, 0.9999993329};
    __m256d acc = zero;
    for (; i + 4 <= n; i += 4) {
        __m256d ax = _mm256_sub_pd(_mm256_loadu_pd(X + i), px);
        __m256d ay = _mm256_sub_pd(_mm256_loadu_pd(Y + i), py);
        __m256d az = _mm256_sub_pd(_mm256_loadu_pd(Z + i), pz);
        __m256d bx = _mm256_sub_pd(_mm256_loadu_pd(X + i + 1), px);
        __m256d by = _mm256_sub_pd(_mm256_loadu_pd(Y + i + 1), py);
        __m256d bz = _mm256_sub_pd(_mm256_loadu_pd(Z + i + 1), pz);
        __m256d al =
            _mm256_sqrt_pd(_mm256_fmadd_pd(ax, ax, _mm256_fmadd_pd(ay, ay, _mm256_mul_pd(az, az))));
        __m256d bl =
            _mm256_sqrt_pd(_mm256_fmadd_pd(bx, bx, _mm256_fmadd_pd(by, by, _mm256_mul_pd(bz, bz))));
        __m256d cx = _mm256_fmsub_pd(by, az, _mm256_mul_pd(bz, ay));
        __m256d cy = _mm256_fmsub_pd(bz, ax, _mm256_mul_pd(bx, az));
        __m256d cz = _mm256_fmsub_pd(bx, ay, _mm256_mul_pd(by, ax));
        __m256d det = _mm256_fmadd_pd(dx, cx, _mm256_fmadd_pd(dy, cy, _mm256_mul_pd(dz, cz)));
        __m256d db = _mm256_fmadd_pd(dx, bx, _mm256_fmadd_pd(dy, by, _mm256_mul_pd(dz, bz)));
        __m256d da = _mm256_fmadd_pd(dx, ax, _mm256_fmadd_pd(dy, ay, _mm256_mul_pd(dz, az)));
        __m256d ba = _mm256_fmadd_pd(bx, ax, _mm256_fmadd_pd(by, ay, _mm256_mul_pd(bz, az)));
        __m256d den = _mm256_fmadd_pd(
            _mm256_mul_pd(vld, bl), al,
            _mm256_fmadd_pd(db, al, _mm256_fmadd_pd(da, bl, _mm256_mul_pd(ba, vld))));
        /* atan2(det, den), as atan2_as */
        __m256d fx = _mm256_andnot_pd(sign, den), fy = _mm256_andnot_pd(sign, det);
        __m256d mx = _mm256_max_pd(fx, fy), mn = _mm256_min_pd(fx, fy);
        mx = _mm256_blendv_pd(one, mx, _mm256_cmp_pd(mx, zero, _CMP_GT_OQ));
        __m256d a = _mm256_div_pd(mn, mx), t = _mm256_mul_pd(a, a);
        __m256d r = _mm256_set1_pd(cf[0]);
        for (int c = 1; c < 8; c++)
            r = _mm256_fmadd_pd(r, t, _mm256_set1_pd(cf[c]));
        r = _mm256_mul_pd(r, a);
        r = _mm256_blendv_pd(r, _mm256_sub_pd(half_pi, r), _mm256_cmp_pd(fy, fx, _CMP_GT_OQ));
        r = _mm256_blendv_pd(r, _mm256_sub_pd(pi, r), _mm256_cmp_pd(den, zero, _CMP_LT_OQ));
        r = _mm256_blendv_pd(r, _mm256_sub_pd(zero, r), _mm256_cmp_pd(det, zero, _CMP_LT_OQ));
        acc = _mm256_add_pd(acc, r);
    }
    double lanes[4];
    _mm256_storeu_pd(lanes, acc);
    /* the last n mod 4 triangles */
    return (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + fan_half_omega_from(k, i, p, d, ld);
}

/* Solid angle of cap k's fan at p: exact near it, the dipole term
 * A . (c - p) / |c - p|^3 beyond two radii (the first-order far field of
 * Barill et al. 2018), nothing beyond its reach. */
static double
cap_omega(const cap_info *k, int avx2, const double p[3]) {
    double d[3] = {k->c[0] - p[0], k->c[1] - p[1], k->c[2] - p[2]};
    double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (r2 > k->reach2)
        return 0.0;
    if (r2 >= 4.0 * k->R * k->R)
        return (k->A[0] * d[0] + k->A[1] * d[1] + k->A[2] * d[2]) / (r2 * sqrt(r2));
    double ld = sqrt(r2);
    return 2.0 * (avx2 ? fan_half_omega_avx2(k, p, d, ld) : fan_half_omega_from(k, 0, p, d, ld));
}

/* The median of a voxel's three row counts: they agree on a closed
 * completion but for rounding at grazing rows. */
static inline int
winding_median(uint16_t v) {
    int w0 = nibble(v, 0), w1 = nibble(v, 1), w2 = nibble(v, 2);
    return w0 > w1 ? (w1 > w2 ? w1 : (w0 > w2 ? w2 : w0)) : (w0 > w2 ? w0 : (w1 > w2 ? w2 : w1));
}

/* Whether p lies in cap k's ball (times 1.1) and slab (plus @p margin). */
static inline int
in_cap_zone(const cap_info *k, const double p[3], double margin) {
    double dx = p[0] - k->c[0], dy = p[1] - k->c[1], dz = p[2] - k->c[2];
    double hn = dx * k->n[0] + dy * k->n[1] + dz * k->n[2];
    return dx * dx + dy * dy + dz * dz <= 1.21 * k->R * k->R && hn >= k->h0 - margin &&
           hn <= k->h1 + margin;
}

/*
 * The fallback for holes too large to evaluate: parity votes of the rows.
 * A row whose signed crossings do not sum to zero enters or leaves through a
 * hole (or where a solid cut by the grid's edge meets it) and abstains;
 * the trusted rows decide by majority, all three when none or a tie is
 * trusted. Per voxel (the low byte of its word): bits 0-1 trusted inside
 * votes, 2-3 untrusted rows, 4-5 all inside votes. Only the inside runs of
 * a row are visited.
 */
static void
row_votes(const crossing *x, size_t m, int na, uint16_t *w, size_t st_a) {
    int sum = 0;
    for (size_t q = 0; q < m; q++)
        sum += x[q].sign;
    int trusted = sum == 0;
    if (!trusted)
        for (int i = 0; i < na; i++)
            w[(size_t)i * st_a] += 4;
    uint16_t add = (uint16_t)(16 + trusted);
    for (size_t q = 0; q < m; q += 2) {
        int i0 = (int)floorf(x[q].t) + 1;
        int i1 = q + 1 < m ? (int)floorf(x[q + 1].t) : na - 1;
        if (i0 < 0)
            i0 = 0;
        if (i1 > na - 1)
            i1 = na - 1;
        for (int i = i0; i <= i1; i++)
            w[(size_t)i * st_a] += add;
    }
}

static inline int
votes_inside(uint16_t v) {
    int tin = v & 3, tn = 3 - ((v >> 2) & 3), all = (v >> 4) & 3;
    return tn > 0 && 2 * tin != tn ? 2 * tin > tn : all >= 2;
}

static void
caps_free(cap_info *caps, size_t n) {
    for (size_t l = 0; l < n; l++)
        free(caps[l].X);
    free(caps);
}

/*
 * The hole caps' data and the work (triangle-voxel solid angles, an
 * estimate) of caps_correct, which corrects the inside/outside signs of sd
 * near the holes: w is the voxel's
 * crossing count (wn) less the solid angles of the hole caps (the fans
 * appended to L after its nv mesh vertices) over 4 pi, in the grid's
 * world-scaled index frame (index times spacing).
 * A cap lies in the ball of radius R around its centre, and from outside
 * that ball it covers less than a hemisphere of directions, |Omega| < 2 pi:
 * it cannot move |w| across 1/2 there. The same holds beyond the slab
 * between the planes, normal to the fan's vector area, that enclose its
 * loop (a plane separates the point from the fan). So only the voxels in a
 * cap's ball (times 1.1, for loops that are not simple) and slab (plus a
 * voxel) are evaluated, each with the sum over every cap (cap_omega): a
 * flat hole is evaluated only in the layer of voxels around it. Each voxel
 * is corrected once (in the first zone holding it), summed in cap order:
 * the same signs for every thread count.
 */
static vv_status
caps_prepare(const tri_list *L, const vv_mesh_holes *H, size_t nv, const int dims[3],
             const double spacing[3], cap_info **out, double *work_out) {
    size_t nloops = H->n_loops;
    *out = NULL;
    cap_info *caps = calloc(nloops, sizeof *caps);
    if (!caps)
        return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory for the hole caps");
    double work = 0.0, zone_voxels = 0.0, loop_len = 0.0;
    for (size_t l = 0; l < nloops; l++) {
        cap_info *k = &caps[l];
        k->i0 = H->loop_start[l];
        k->i1 = H->loop_start[l + 1];
        size_t n = k->i1 - k->i0;
        k->X = malloc(3 * (n + 1) * sizeof *k->X);
        if (!k->X) {
            caps_free(caps, l);
            return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory for the hole caps");
        }
        k->Y = k->X + n + 1;
        k->Z = k->Y + n + 1;
        for (size_t i = 0; i <= n; i++) {
            const double *v = L->V + 3 * (size_t)H->loop_v[k->i0 + (i < n ? i : 0)];
            k->X[i] = v[0] * spacing[0];
            k->Y[i] = v[1] * spacing[1];
            k->Z[i] = v[2] * spacing[2];
        }
        for (int j = 0; j < 3; j++)
            k->c[j] = L->V[3 * (nv + l) + j] * spacing[j];
        double R2 = 0;
        for (size_t i = k->i0; i < k->i1; i++) {
            const double *va = L->V + 3 * (size_t)H->loop_v[i];
            const double *vb = L->V + 3 * (size_t)H->loop_v[i + 1 < k->i1 ? i + 1 : k->i0];
            double u[3], v[3];
            for (int j = 0; j < 3; j++) {
                u[j] = vb[j] * spacing[j] - k->c[j]; /* the fan triangle (c, b, a) */
                v[j] = va[j] * spacing[j] - k->c[j];
            }
            k->A[0] += 0.5 * (u[1] * v[2] - u[2] * v[1]);
            k->A[1] += 0.5 * (u[2] * v[0] - u[0] * v[2]);
            k->A[2] += 0.5 * (u[0] * v[1] - u[1] * v[0]);
            double d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            R2 = d2 > R2 ? d2 : R2;
        }
        k->R = sqrt(R2);
        double alen = sqrt(k->A[0] * k->A[0] + k->A[1] * k->A[1] + k->A[2] * k->A[2]);
        if (alen > 0)
            for (int j = 0; j < 3; j++)
                k->n[j] = k->A[j] / alen;
        for (size_t i = k->i0; i < k->i1; i++) {
            const double *va = L->V + 3 * (size_t)H->loop_v[i];
            double h = 0;
            for (int j = 0; j < 3; j++)
                h += (va[j] * spacing[j] - k->c[j]) * k->n[j];
            k->h0 = h < k->h0 ? h : k->h0;
            k->h1 = h > k->h1 ? h : k->h1;
        }
        double reach = sqrt((double)nloops * alen / (4.0 * M_PI * CAP_FAR_ERROR));
        if (reach < 2.0 * k->R)
            reach = 2.0 * k->R;
        k->reach2 = reach * reach;
        double box = 1.0;
        for (int j = 0; j < 3; j++)
            box *= fmin(dims[j], 2.2 * k->R / spacing[j] + 1.0);
        /* the slab holds a share of the ball's box */
        double hmin = fmin(spacing[0], fmin(spacing[1], spacing[2]));
        zone_voxels += box * fmin(1.0, (k->h1 - k->h0 + 2.0 * hmin) / (2.2 * k->R + hmin));
        loop_len += (double)(k->i1 - k->i0);
    }
    work = zone_voxels * loop_len;
    *work_out = work;
    *out = caps;
    return VV_OK;
}

/* The correction itself (see caps_prepare's comment). */
static void
caps_correct(const cap_info *caps, size_t nloops, const int dims[3], const double spacing[3],
             int threads, const uint16_t *wn, float *sd) {
    int avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    double margin = fmax(spacing[0], fmax(spacing[1], spacing[2]));
    const double inv4pi = 0.25 / M_PI;
    for (size_t l = 0; l < nloops; l++) {
        const cap_info *k = &caps[l];
        int lo[3], hi[3];
        for (int j = 0; j < 3; j++) {
            double zone = 1.1 * k->R;
            lo[j] = (int)fmax(0.0, ceil((k->c[j] - zone) / spacing[j]));
            hi[j] = (int)fmin(dims[j] - 1.0, floor((k->c[j] + zone) / spacing[j]));
        }
        if (lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2])
            continue;
#pragma omp parallel for collapse(2) schedule(dynamic, 4) num_threads(threads)
        for (int z = lo[2]; z <= hi[2]; z++)
            for (int y = lo[1]; y <= hi[1]; y++)
                for (int x = lo[0]; x <= hi[0]; x++) {
                    double p[3] = {x * spacing[0], y * spacing[1], z * spacing[2]};
                    /* each voxel once: in the first zone that holds it */
                    if (!in_cap_zone(k, p, margin))
                        continue;
                    int seen = 0;
                    for (size_t j = 0; j < l && !seen; j++)
                        seen = in_cap_zone(&caps[j], p, margin);
                    if (seen)
                        continue;
                    size_t v = ((size_t)z * dims[1] + (size_t)y) * dims[0] + (size_t)x;
                    double o = 0.0;
                    for (size_t j = 0; j < nloops; j++)
                        o += cap_omega(&caps[j], avx2, p);
                    int med = winding_median(wn[v]);
                    if ((fabs(med - o * inv4pi) > 0.5) != (med != 0))
                        sd[v] = -sd[v];
                }
    }
}

/* Kept whole: the passes of the winding-number scan (the closed
 * completion, crossings along x, y and z, medians, the distance band, the
 * caps' solid angles near holes) share grid-sized arrays with one
 * cleanup. */
vv_status
vv_mesh_scan(const vv_mesh *mesh, vv_mat4 to_world, int solid, double thickness, const int dims[3],
             const double spacing[3], const double origin[3], double band, float *sd, int threads) {
    size_t nv = mesh->n_vertices;
    for (size_t t = 0; t < 3 * mesh->n_triangles; t++) {
        if (mesh->triangles[t] >= nv)
            return vv_error_set(VV_ERR_INVALID, "mesh scan: triangle %zu has vertex %u of %zu",
                                t / 3, mesh->triangles[t], nv);
    }
    tri_list L = {0};
    if (!tl_grow(&L, mesh->n_triangles, nv)) {
        free(L.t);
        free(L.V);
        return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory for %zu triangles",
                            mesh->n_triangles);
    }
    memcpy(L.t, mesh->triangles, 3 * mesh->n_triangles * sizeof *L.t);
    L.n = mesh->n_triangles;
    L.nv = nv;
    double *V = L.V;
    long long nvl = (long long)nv;
#pragma omp parallel for schedule(dynamic, 32768) num_threads(threads)
    for (long long i = 0; i < nvl; i++) {
        vv_vec3 p = vv_mat4_mul_point(to_world, vv_mesh_vertex(mesh, (size_t)i));
        V[3 * i] = (p.x - origin[0]) / spacing[0];
        V[3 * i + 1] = (p.y - origin[1]) / spacing[1];
        V[3 * i + 2] = (p.z - origin[2]) / spacing[2];
    }
    vv_status st = VV_OK;
    if (!solid) {
        double bandw = band + 0.5 * thickness;
        st = shell_distance(&L, dims, spacing, bandw, sd, threads);
        free(L.t);
        free(L.V);
        if (st == VV_OK) {
            long long nn = (long long)dims[0] * dims[1] * dims[2];
            float h = (float)(0.5 * thickness);
#pragma omp parallel for schedule(dynamic, 32768) num_threads(threads)
            for (long long i = 0; i < nn; i++)
                sd[i] = sd[i] - h;
        }
        return st;
    }
    /* the closed completion: triangles oriented per component, a fan over
     * each hole from its centroid (mesh_holes.c) */
    vv_mesh_holes H;
    st = vv_mesh_holes_find(mesh, &H);
    if (st != VV_OK) {
        free(L.t);
        free(L.V);
        return vv_error_prefix(st, "mesh scan");
    }
    memcpy(L.t, H.tri, 3 * H.n_tri * sizeof *L.t);
    size_t ncore = L.n, nloops = H.n_loops;
    if (nloops) {
        size_t ncap = H.loop_start[nloops];
        if (!tl_grow(&L, L.n + ncap, nv + nloops)) {
            vv_mesh_holes_free(&H);
            free(L.t);
            free(L.V);
            return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory for the hole caps");
        }
        for (size_t l = 0; l < nloops; l++) {
            double cm[3];
            vv_mesh_loop_centroid(mesh, &H, l, cm);
            vv_vec3 p = vv_mat4_mul_point(to_world, vv_vec3_make(cm[0], cm[1], cm[2]));
            double *cv = L.V + 3 * (nv + l);
            cv[0] = (p.x - origin[0]) / spacing[0];
            cv[1] = (p.y - origin[1]) / spacing[1];
            cv[2] = (p.z - origin[2]) / spacing[2];
            size_t i0 = H.loop_start[l], i1 = H.loop_start[l + 1];
            for (size_t i = i0; i < i1; i++) {
                uint32_t *t = L.t + 3 * L.n++;
                t[0] = (uint32_t)(nv + l);
                t[1] = H.loop_v[i + 1 < i1 ? i + 1 : i0];
                t[2] = H.loop_v[i];
            }
        }
        L.nv = nv + nloops;
    }
    /* holes too large for the caps' solid angles (a mesh cropped by the
     * edges of a scan, whose loops run round the volume's corners) fall back
     * to votes of the rows that meet no hole */
    cap_info *caps = NULL;
    int votes = 0;
    if (nloops) {
        double work = 0;
        st = caps_prepare(&L, &H, nv, dims, spacing, &caps, &work);
        if (st != VV_OK) {
            vv_mesh_holes_free(&H);
            free(L.t);
            free(L.V);
            return st;
        }
        if (!(work <= CAP_WORK_MAX)) {
            caps_free(caps, nloops);
            caps = NULL;
            votes = 1;
            L.n = ncore;
        }
    }
    size_t nvox = (size_t)dims[0] * dims[1] * dims[2];
    /* per voxel, the winding numbers counted along the x, y and z rows: a
     * signed nibble each (bits 4a .. 4a + 3), clamped to [-8, 7] */
    uint16_t *wn = calloc(nvox, sizeof *wn);
    if (!wn) {
        caps_free(caps, caps ? nloops : 0);
        vv_mesh_holes_free(&H);
        free(L.t);
        free(L.V);
        return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory");
    }
    V = L.V;
    scan_ctx c = {V, L.t, L.n, dims, spacing, ncore};
    double bandw = band;
    const float far = (float)bandw;
    /* one pass over the triangles collects the crossings of all three axes,
     * per thread (bufs[3 * thread + axis]); most triangles of a fine mesh lie
     * between rows and leave at the box test */
    int nth = threads > 0 ? threads : 1;
    xbuf *bufs = calloc((size_t)nth * 3, sizeof *bufs);
    if (!bufs) {
        free(wn);
        caps_free(caps, caps ? nloops : 0);
        vv_mesh_holes_free(&H);
        free(L.t);
        free(L.V);
        return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory");
    }
    {
        long long ntri = (long long)L.n;
#pragma omp parallel num_threads(nth)
        {
            xbuf *mine = &bufs[3 * (omp_get_thread_num() % nth)];
#pragma omp for schedule(dynamic, 4096)
            for (long long t = 0; t < ntri; t++)
                triangle_rows(&c, (size_t)t, mine);
        }
    }
    {
        long long nn = (long long)dims[0] * dims[1] * dims[2];
#pragma omp parallel for schedule(dynamic, 32768) num_threads(threads)
        for (long long i = 0; i < nn; i++)
            sd[i] = far;
    }
    for (int a = 0; a < 3 && st == VV_OK; a++) {
        int b = (a + 1) % 3, cc = (a + 2) % 3;
        size_t nrows = (size_t)dims[b] * (size_t)dims[cc];
        size_t *cnt = calloc(nrows + 1, sizeof *cnt);
        size_t *pos = malloc((nrows + 1) * sizeof *pos);
        if (!cnt || !pos) {
            free(cnt);
            free(pos);
            st = vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory");
            break;
        }
        /* crossings grouped by row (in thread order, sorted per row below) */
        int oom = 0;
        for (int th = 0; th < nth; th++) {
            const xbuf *B = &bufs[3 * th + a];
            oom |= B->oom;
            for (size_t i = 0; i < B->n; i++)
                cnt[B->v[i].row]++;
        }
        size_t total = 0;
        for (size_t r = 0; r < nrows; r++) {
            pos[r] = total;
            total += cnt[r];
        }
        pos[nrows] = total;
        crossing *xs = oom ? NULL : malloc((total ? total : 1) * sizeof *xs);
        if (!xs) {
            free(cnt);
            free(pos);
            st = vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory for the crossings");
            break;
        }
        for (size_t r = 0; r <= nrows; r++)
            cnt[r] = pos[r];
        for (int th = 0; th < nth; th++) {
            xbuf *B = &bufs[3 * th + a];
            for (size_t i = 0; i < B->n; i++)
                xs[pos[B->v[i].row]++] = B->v[i].x;
            free(B->v);
            B->v = NULL;
        }
        size_t stride[3] = {1, (size_t)dims[0], (size_t)dims[0] * (size_t)dims[1]};
        long long nr = (long long)nrows;
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
        for (long long r = 0; r < nr; r++) {
            size_t jb = (size_t)r % (size_t)dims[b], jc = (size_t)r / (size_t)dims[b];
            size_t base = jb * stride[b] + jc * stride[cc], st_a = stride[a];
            crossing *x = xs + cnt[r];
            size_t m = cnt[r + 1] - cnt[r];
            if (m > 24) {
                qsort(x, m, sizeof *x, cmp_crossing);
            } else {
                for (size_t u = 1; u < m; u++) {
                    crossing key = x[u];
                    size_t w = u;
                    while (w > 0 && cmp_crossing(&x[w - 1], &key) > 0) {
                        x[w] = x[w - 1];
                        w--;
                    }
                    x[w] = key;
                }
            }
            int na = dims[a];
            if (votes) {
                row_votes(x, m, na, wn + base, st_a);
            } else {
                /* the winding number along the row, from -infinity (crossings
                 * beyond the grid are kept): entering the solid (a triangle
                 * facing -a, sign -1) adds one. Only the runs with w != 0 are
                 * visited (voxel i lies after the crossings below it). */
                int w = 0;
                for (size_t q = 0; q < m; q++) {
                    w -= x[q].sign;
                    if (w == 0)
                        continue;
                    int i0 = (int)floorf(x[q].t) + 1;
                    int i1 = q + 1 < m ? (int)floorf(x[q + 1].t) : na - 1;
                    if (i0 < 0)
                        i0 = 0;
                    if (i1 > na - 1)
                        i1 = na - 1;
                    uint16_t nib = (uint16_t)(((w < -8 ? -8 : w > 7 ? 7 : w) & 15) << (4 * a));
                    for (int i = i0; i <= i1; i++)
                        wn[base + (size_t)i * st_a] |= nib;
                }
            }
            for (size_t k = 0; k < m; k++) {
                if (!(x[k].slope > 0))
                    continue;
                double s = x[k].slope, t = x[k].t, reach = bandw / s;
                int i0 = (int)fmax(0.0, ceil(t - reach)),
                    i1 = (int)fmin(na - 1.0, floor(t + reach));
                for (int i = i0; i <= i1; i++) {
                    float d = (float)(fabs(i - t) * s);
                    float *v = sd + base + (size_t)i * st_a;
                    if (d < *v)
                        *v = d;
                }
            }
        }
        free(xs);
        free(cnt);
        free(pos);
    }
    if (st == VV_OK) {
        /* the decision of every 12-bit word, looked up (4 KB) */
        unsigned char inside[4096];
        for (unsigned v = 0; v < 4096; v++)
            inside[v] = (unsigned char)(votes ? votes_inside((uint16_t)v)
                                              : winding_median((uint16_t)v) != 0);
        long long nn = (long long)nvox;
#pragma omp parallel for schedule(dynamic, 32768) num_threads(threads)
        for (long long i = 0; i < nn; i++)
            if (inside[wn[i] & 4095])
                sd[i] = -sd[i];
    }
    /* near the holes, the caps' solid angles move |w| across 1/2 */
    if (st == VV_OK && caps)
        caps_correct(caps, nloops, dims, spacing, threads, wn, sd);
    caps_free(caps, caps ? nloops : 0);
    vv_mesh_holes_free(&H);
    for (int i = 0; i < 3 * nth; i++)
        free(bufs[i].v);
    free(bufs);
    free(wn);
    free(L.t);
    free(L.V);
    return st;
}
