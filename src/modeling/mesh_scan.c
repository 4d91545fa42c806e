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
 * the triangles around it. Inside/outside is the parity of the crossings
 * along the x rows (a closed mesh: Jordan's theorem; holes leak only along
 * the rows through them). The distance band uses the crossings of all three
 * axes: a voxel near a crossing gets its distance to the crossed triangle's
 * plane, and keeps the smallest; every surface point has a normal component
 * of at least 1/sqrt(3) along some axis, so each voxel near the surface
 * meets a well-conditioned crossing (those with |n_a| < 0.5 are not used
 * for the band).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "modeling_internal.h"

typedef struct crossing {
    float t;     /* crossing position along the row, index units */
    float slope; /* world distance to the triangle's plane per index step; 0: parity only */
} crossing;

static int
cmp_crossing(const void *a, const void *b) {
    const crossing *x = a, *y = b;
    if (x->t != y->t)
        return x->t < y->t ? -1 : 1;
    return (x->slope > y->slope) - (x->slope < y->slope);
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

/* Visits the rows along axis a that cross triangle t; with out == NULL it
 * counts into cnt, else it appends at pos. */
static void
triangle_rows(const scan_ctx *c, size_t t, int a, size_t *cnt, crossing *out, size_t *pos) {
    int b = (a + 1) % 3, cc = (a + 2) % 3;
    const double *P[3];
    double q[3][2];
    for (int v = 0; v < 3; v++) {
        P[v] = c->V + 3 * (size_t)c->tri[3 * t + v];
        q[v][0] = P[v][b];
        q[v][1] = P[v][cc];
    }
    double area = edge_value(q[0], q[1], q[2][0], q[2][1]);
    if (area == 0.0 || !isfinite(area))
        return;
    double lo_b = fmin(q[0][0], fmin(q[1][0], q[2][0]));
    double hi_b = fmax(q[0][0], fmax(q[1][0], q[2][0]));
    double lo_c = fmin(q[0][1], fmin(q[1][1], q[2][1]));
    double hi_c = fmax(q[0][1], fmax(q[1][1], q[2][1]));
    double fb0 = ceil(lo_b), fb1 = floor(hi_b), fc0 = ceil(lo_c), fc1 = floor(hi_c);
    if (fb0 < 0)
        fb0 = 0;
    if (fc0 < 0)
        fc0 = 0;
    if (fb1 > c->dims[b] - 1)
        fb1 = c->dims[b] - 1;
    if (fc1 > c->dims[cc] - 1)
        fc1 = c->dims[cc] - 1;
    if (fb0 > fb1 || fc0 > fc1)
        return;
    int sgn = area > 0 ? 1 : -1;
    float slope = 0.0f;
    if (out) {
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
        if (cosa >= 0.5)
            slope = (float)(c->spacing[a] * cosa);
    }
    for (int jc = (int)fc0; jc <= (int)fc1; jc++) {
        for (int jb = (int)fb0; jb <= (int)fb1; jb++) {
            if (edge_sign(q[0], q[1], jb, jc) != sgn || edge_sign(q[1], q[2], jb, jc) != sgn ||
                edge_sign(q[2], q[0], jb, jc) != sgn)
                continue;
            size_t row = (size_t)jc * (size_t)c->dims[b] + (size_t)jb;
            if (!out) {
#pragma omp atomic
                cnt[row]++;
                continue;
            }
            double l0 = edge_value(q[1], q[2], jb, jc) / area;
            double l1 = edge_value(q[2], q[0], jb, jc) / area;
            double l2 = 1.0 - l0 - l1;
            double tt = l0 * P[0][a] + l1 * P[1][a] + l2 * P[2][a];
            size_t k;
#pragma omp atomic capture
            k = pos[row]++;
            out[k].t = (float)tt;
            out[k].slope = slope;
        }
    }
}

vv_status
vv_mesh_scan(const vv_mesh *mesh, vv_mat4 to_world, int solid, double thickness, const int dims[3],
             const double spacing[3], const double origin[3], double band, float *sd, int threads) {
    size_t nv = mesh->n_vertices;
    double *V = malloc(nv * 3 * sizeof *V);
    if (!V)
        return vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory for %zu vertices", nv);
    for (size_t i = 0; i < nv; i++) {
        vv_vec3 p = vv_mat4_mul_point(to_world, vv_mesh_vertex(mesh, i));
        V[3 * i] = (p.x - origin[0]) / spacing[0];
        V[3 * i + 1] = (p.y - origin[1]) / spacing[1];
        V[3 * i + 2] = (p.z - origin[2]) / spacing[2];
    }
    for (size_t t = 0; t < 3 * mesh->n_triangles; t++) {
        if (mesh->triangles[t] >= nv) {
            free(V);
            return vv_error_set(VV_ERR_INVALID, "mesh scan: triangle %zu has vertex %u of %zu",
                                t / 3, mesh->triangles[t], nv);
        }
    }
    scan_ctx c = {V, mesh->triangles, mesh->n_triangles, dims, spacing};
    double bandw = solid ? band : band + 0.5 * thickness;
    const float far = (float)bandw;
    vv_status st = VV_OK;
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
        long long ntri = (long long)mesh->n_triangles;
#pragma omp parallel for schedule(dynamic, 1024) num_threads(threads)
        for (long long t = 0; t < ntri; t++)
            triangle_rows(&c, (size_t)t, a, cnt, NULL, NULL);
        size_t total = 0;
        for (size_t r = 0; r < nrows; r++) {
            pos[r] = total;
            total += cnt[r];
        }
        pos[nrows] = total;
        crossing *xs = malloc((total ? total : 1) * sizeof *xs);
        if (!xs) {
            free(cnt);
            free(pos);
            st = vv_error_set(VV_ERR_NOMEM, "mesh scan: out of memory for %zu crossings", total);
            break;
        }
        /* pos doubles as the fill cursor; cnt keeps the starts afterwards */
        for (size_t r = 0; r <= nrows; r++)
            cnt[r] = pos[r];
#pragma omp parallel for schedule(dynamic, 1024) num_threads(threads)
        for (long long t = 0; t < ntri; t++)
            triangle_rows(&c, (size_t)t, a, NULL, xs, pos);
        size_t stride[3] = {1, (size_t)dims[0], (size_t)dims[0] * (size_t)dims[1]};
        long long nr = (long long)nrows;
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
        for (long long r = 0; r < nr; r++) {
            size_t jb = (size_t)r % (size_t)dims[b], jc = (size_t)r / (size_t)dims[b];
            size_t base = jb * stride[b] + jc * stride[cc], st_a = stride[a];
            crossing *x = xs + cnt[r];
            size_t m = cnt[r + 1] - cnt[r];
            if (m > 1)
                qsort(x, m, sizeof *x, cmp_crossing);
            int na = dims[a];
            if (a == 0) {
                /* first pass: every voxel of the row gets its side */
                size_t k = 0;
                int inside = 0;
                for (int i = 0; i < na; i++) {
                    while (k < m && x[k].t < (float)i) {
                        inside = !inside;
                        k++;
                    }
                    sd[base + (size_t)i * st_a] = (solid && inside) ? -far : far;
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
                    if (d < fabsf(*v))
                        *v = *v < 0 ? -d : d;
                }
            }
        }
        free(xs);
        free(cnt);
        free(pos);
    }
    free(V);
    if (st == VV_OK && !solid) {
        size_t n = (size_t)dims[0] * dims[1] * dims[2];
        float h = (float)(0.5 * thickness);
        long long nn = (long long)n;
#pragma omp parallel for schedule(static) num_threads(threads)
        for (long long i = 0; i < nn; i++)
            sd[i] = sd[i] - h;
    }
    return st;
}
