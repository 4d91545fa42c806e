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
 * the triangles around it. Inside/outside is voted by the crossing
 * parities of the x, y and z rows through the voxel. A row whose signed
 * crossings (the side each triangle faces) do not sum to zero passes through
 * a hole, or starts inside a solid cut by the grid (an isosurface of a
 * cropped scan), and abstains; the trusted rows decide by majority, all
 * three rows when none or a tie is trusted. A closed mesh gets Jordan's
 * parity on every row. The distance band uses the crossings of all three
 * axes: a voxel near a crossing gets its distance to the crossed triangle's
 * plane, and keeps the smallest; every surface point has a normal component
 * of at least 1/sqrt(3) along some axis, so each voxel near the surface
 * meets a well-conditioned crossing (those with |n_a| < 0.5 are not used
 * for the band).
 */
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
triangle_rows_axis(const scan_ctx *c, const double *const P[3], int a, int jb0, int jb1, int jc0,
                   int jc1, xbuf *out) {
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
    float slope = -1.0f; /* computed at the first crossing */
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
        triangle_rows_axis(c, P, a, lo[b], hi[b], lo[cc], hi[cc], &out[a]);
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
    unsigned char *votes = malloc((size_t)dims[0] * dims[1] * dims[2]);
    if (!votes) {
        free(L.t);
        free(L.V);
        return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory");
    }
    V = L.V;
    scan_ctx c = {V, L.t, L.n, dims, spacing};
    double bandw = band;
    const float far = (float)bandw;
    /* one pass over the triangles collects the crossings of all three axes,
     * per thread (bufs[3 * thread + axis]); most triangles of a fine mesh lie
     * between rows and leave at the box test */
    int nth = threads > 0 ? threads : 1;
    xbuf *bufs = calloc((size_t)nth * 3, sizeof *bufs);
    if (!bufs) {
        free(votes);
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
        memset(votes, 0, (size_t)nn);
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
            /* parity along the row: one vote per axis. A row whose signed
             * crossings do not sum to zero enters or leaves through a hole
             * (or starts inside a solid cut by the grid): its vote is kept
             * apart as untrusted. votes: bits 0-1 trusted inside votes,
             * 2-3 untrusted rows, 4-5 all inside votes. Only the inside
             * runs of a row are visited (voxel i is inside when an odd
             * number of crossings lie below it). */
            int sum = 0;
            for (size_t q = 0; q < m; q++)
                sum += x[q].sign;
            int trusted = sum == 0;
            if (!trusted)
                for (int i = 0; i < na; i++)
                    votes[base + (size_t)i * st_a] += 4;
            unsigned char add = (unsigned char)(16 + trusted);
            for (size_t q = 0; q < m; q += 2) {
                int i0 = (int)floorf(x[q].t) + 1;
                int i1 = q + 1 < m ? (int)floorf(x[q + 1].t) : na - 1;
                if (i0 < 0)
                    i0 = 0;
                if (i1 > na - 1)
                    i1 = na - 1;
                for (int i = i0; i <= i1; i++)
                    votes[base + (size_t)i * st_a] += add;
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
        long long nn = (long long)dims[0] * dims[1] * dims[2];
#pragma omp parallel for schedule(dynamic, 32768) num_threads(threads)
        for (long long i = 0; i < nn; i++) {
            int tin = votes[i] & 3, tn = 3 - ((votes[i] >> 2) & 3), all = votes[i] >> 4;
            int in = tn > 0 && 2 * tin != tn ? 2 * tin > tn : all >= 2;
            if (in)
                sd[i] = -sd[i];
        }
    }
    for (int i = 0; i < 3 * nth; i++)
        free(bufs[i].v);
    free(bufs);
    free(votes);
    free(L.t);
    free(L.V);
    return st;
}
