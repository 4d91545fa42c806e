/*
 * The closed completion of an imperfect triangle mesh, for classifying
 * voxels by the generalized winding number (Jacobson, Kavan and
 * Sorkine-Hornung, "Robust Inside-Outside Segmentation using Generalized
 * Winding Numbers", SIGGRAPH 2013).
 *
 * The winding number of a mesh M at p is the sum of the signed solid angles
 * of its triangles over 4 pi. Cap every boundary loop of M with a fan S and
 * the union M + S is closed (every directed edge cancelled), so its winding
 * number is an integer that a ray from p counts exactly by signed
 * crossings. Hence w_M(p) = crossings_{M+S}(p) - Omega_S(p) / (4 pi): the
 * scan converter counts the crossings along its rows, and only the caps'
 * solid angles are summed directly, near the holes (see mesh_scan.c). This
 * file finds the caps: vertices are welded by position, triangles are
 * oriented consistently across their manifold edges (the majority of each
 * connected component keeps its orientation, so a flipped patch is turned
 * back), and the boundary 1-chain left is split into closed loops.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "modeling_internal.h"

typedef struct edge_rec {
    uint64_t key; /* lo << 32 | hi, welded vertex ids */
    uint32_t tri;
    uint32_t fwd; /* 1 when the triangle goes lo -> hi */
} edge_rec;

static int
edge_cmp(const void *a, const void *b) {
    const edge_rec *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->tri > y->tri) - (x->tri < y->tri);
}

/* Hash of a vertex position's bits (FNV-1a over its 12 bytes, then mixed). */
static inline uint64_t
pos_hash(const float *p) {
    uint32_t w[3];
    memcpy(w, p, sizeof w);
    uint64_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; k++)
        h = (h ^ w[k]) * 1099511628211ull;
    return h ^ (h >> 29);
}

/* weld[v] = the first vertex at v's exact position (bits: -0 and 0 differ,
 * NaNs weld only to the same NaN), through an open-addressing table of
 * @p cap slots (a power of two above 2 nv). */
static void
weld_by_position(const float *P, size_t nv, uint32_t *table, size_t cap, uint32_t *weld) {
    for (size_t i = 0; i < cap; i++)
        table[i] = UINT32_MAX;
    for (size_t v = 0; v < nv; v++) {
        const float *p = P + 3 * v;
        size_t h = (size_t)pos_hash(p) & (cap - 1);
        for (;;) {
            uint32_t u = table[h];
            if (u == UINT32_MAX) {
                table[h] = (uint32_t)v;
                weld[v] = (uint32_t)v;
                break;
            }
            if (memcmp(P + 3 * (size_t)u, p, 3 * sizeof *p) == 0) {
                weld[v] = u;
                break;
            }
            h = (h + 1) & (cap - 1);
        }
    }
}

static double
tri_area(const float *P, uint32_t a, uint32_t b, uint32_t c) {
    const float *A = P + 3 * (size_t)a, *B = P + 3 * (size_t)b, *C = P + 3 * (size_t)c;
    double u[3], v[3];
    for (int k = 0; k < 3; k++) {
        u[k] = (double)B[k] - A[k];
        v[k] = (double)C[k] - A[k];
    }
    double n0 = u[1] * v[2] - u[2] * v[1], n1 = u[2] * v[0] - u[0] * v[2],
           n2 = u[0] * v[1] - u[1] * v[0];
    return 0.5 * sqrt(n0 * n0 + n1 * n1 + n2 * n2);
}

void
vv_mesh_holes_free(vv_mesh_holes *h) {
    if (!h)
        return;
    free(h->tri);
    free(h->loop_start);
    free(h->loop_v);
    memset(h, 0, sizeof *h);
}

/* The end of the group of equal keys that starts at E[i]. */
static size_t
group_end(const edge_rec *E, size_t ne, size_t i) {
    size_t j = i;
    while (j < ne && E[j].key == E[i].key)
        j++;
    return j;
}

/* The traversals lo -> hi minus hi -> lo of the edge group E[i .. j). */
static long
edge_net(const edge_rec *E, size_t i, size_t j, const unsigned char *flip) {
    long net = 0;
    for (; i < j; i++)
        net += (E[i].fwd ^ flip[E[i].tri]) ? 1 : -1;
    return net;
}

/* Kept whole: one pass after another over the edge records it builds
 * (weld, edges, grouping, orientation per component, the boundary chain,
 * its loops, the caps' area), all freed at one exit. */
vv_status
vv_mesh_holes_find(const vv_mesh *m, vv_mesh_holes *out) {
    memset(out, 0, sizeof *out);
    size_t nv = m->n_vertices, nt = m->n_triangles;
    if (nt > UINT32_MAX / 3 || nv > UINT32_MAX)
        return vv_error_set(VV_ERR_INVALID, "mesh holes: %zu triangles is too many", nt);
    const float *P = m->positions;
    vv_status st = VV_OK;
    /* scratch, freed at the end */
    uint32_t *weld = NULL, *ids = NULL, *deg = NULL, *adj = NULL, *queue = NULL, *comp = NULL,
             *fill = NULL, *out_start = NULL, *order = NULL, *cur = NULL;
    size_t *start = NULL;
    edge_rec *E = NULL, *S = NULL;
    unsigned char *flip = NULL, *used = NULL;
    uint32_t(*be)[2] = NULL;
#define ALLOC(p, n) ((p) = malloc(((n) > 0 ? (n) : 1) * sizeof *(p)))
#define CALLOC(p, n) ((p) = calloc((n) > 0 ? (n) : 1, sizeof *(p)))
    size_t cap = 16;
    while (cap < 2 * nv)
        cap *= 2;
    if (!ALLOC(weld, nv) || !ALLOC(ids, cap) || !ALLOC(E, 3 * nt) || !ALLOC(out->tri, 3 * nt) ||
        !CALLOC(flip, nt) || !CALLOC(start, nv + 1) || !ALLOC(S, 3 * nt))
        goto nomem;
    out->n_tri = nt;
    memcpy(out->tri, m->triangles, 3 * nt * sizeof *out->tri);
    /* weld: every vertex maps to the first vertex at its exact position */
    weld_by_position(P, nv, ids, cap, weld);
    /* the edges of the non-degenerate triangles */
    size_t ne = 0;
    for (size_t t = 0; t < nt; t++) {
        uint32_t w[3];
        for (int k = 0; k < 3; k++)
            w[k] = m->triangles[3 * t + k] < nv ? weld[m->triangles[3 * t + k]] : UINT32_MAX;
        if (w[0] == UINT32_MAX || w[1] == UINT32_MAX || w[2] == UINT32_MAX || w[0] == w[1] ||
            w[1] == w[2] || w[0] == w[2])
            continue;
        out->mesh_area += tri_area(P, w[0], w[1], w[2]);
        for (int k = 0; k < 3; k++) {
            uint32_t a = w[k], b = w[(k + 1) % 3];
            uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
            E[ne++] = (edge_rec){(uint64_t)lo << 32 | hi, (uint32_t)t, a < b};
        }
    }
    /* grouped by key: a counting sort on the low vertex, then insertion
     * sorts of the few edges per vertex */
    for (size_t i = 0; i < ne; i++)
        start[(E[i].key >> 32) + 1]++;
    for (size_t v = 0; v < nv; v++)
        start[v + 1] += start[v];
    for (size_t i = 0; i < ne; i++)
        S[start[E[i].key >> 32]++] = E[i];
    for (size_t v = nv; v > 0; v--)
        start[v] = start[v - 1];
    start[0] = 0;
    for (size_t v = 0; v < nv; v++)
        for (size_t i = start[v] + 1; i < start[v + 1]; i++) {
            edge_rec key = S[i];
            size_t j = i;
            while (j > start[v] && edge_cmp(&S[j - 1], &key) > 0) {
                S[j] = S[j - 1];
                j--;
            }
            S[j] = key;
        }
    /* a mesh whose two-triangle edges are all traversed both ways is
     * consistently oriented already (marching cubes output, clean models):
     * nothing to turn */
    size_t misoriented = 0;
    for (size_t i = 0, j; i < ne; i = j) {
        j = group_end(S, ne, i);
        misoriented += j - i == 2 && S[i].tri != S[i + 1].tri && S[i].fwd == S[i + 1].fwd;
    }
    if (misoriented > 0) {
        if (!CALLOC(deg, nt + 1) || !ALLOC(queue, nt) || !ALLOC(comp, nt) || !CALLOC(fill, nt))
            goto nomem;
        /* manifold adjacency (edges of exactly two triangles) as CSR; entries
         * neighbour << 1 | (both traverse the edge the same way) */
        for (size_t i = 0, j; i < ne; i = j) {
            j = group_end(S, ne, i);
            if (j - i == 2 && S[i].tri != S[i + 1].tri) {
                deg[S[i].tri + 1]++;
                deg[S[i + 1].tri + 1]++;
            }
        }
        for (size_t t = 0; t < nt; t++)
            deg[t + 1] += deg[t];
        if (!ALLOC(adj, deg[nt]))
            goto nomem;
        for (size_t i = 0, j; i < ne; i = j) {
            j = group_end(S, ne, i);
            if (j - i == 2 && S[i].tri != S[i + 1].tri) {
                uint32_t t0 = S[i].tri, t1 = S[i + 1].tri, same = S[i].fwd == S[i + 1].fwd;
                adj[deg[t0] + fill[t0]++] = t1 << 1 | same;
                adj[deg[t1] + fill[t1]++] = t0 << 1 | same;
            }
        }
        /* orient each component by breadth-first search; the majority keeps its
         * orientation */
        for (size_t t = 0; t < nt; t++)
            comp[t] = UINT32_MAX;
        for (size_t s = 0; s < nt; s++) {
            if (comp[s] != UINT32_MAX)
                continue;
            size_t head = 0, tail = 0, flipped = 0;
            queue[tail++] = (uint32_t)s;
            comp[s] = (uint32_t)s;
            while (head < tail) {
                uint32_t t = queue[head++];
                flipped += flip[t];
                for (uint32_t k = deg[t]; k < deg[t + 1]; k++) {
                    uint32_t u = adj[k] >> 1, same = adj[k] & 1;
                    if (comp[u] != UINT32_MAX)
                        continue; /* a non-orientable loop keeps the first choice */
                    comp[u] = (uint32_t)s;
                    flip[u] = (unsigned char)(flip[t] ^ same);
                    queue[tail++] = u;
                }
            }
            if (2 * flipped > tail)
                for (size_t q = 0; q < tail; q++)
                    flip[queue[q]] ^= 1;
        }
        for (size_t t = 0; t < nt; t++) {
            if (!flip[t])
                continue;
            out->n_flipped++;
            uint32_t x = out->tri[3 * t + 1];
            out->tri[3 * t + 1] = out->tri[3 * t + 2];
            out->tri[3 * t + 2] = x;
        }
    }
    /* the boundary 1-chain, as directed edges (from, to) */
    size_t nb = 0;
    for (size_t i = 0, j; i < ne; i = j) {
        j = group_end(S, ne, i);
        nb += (size_t)labs(edge_net(S, i, j, flip));
    }
    if (!ALLOC(be, nb) || !CALLOC(out_start, nv + 1) || !ALLOC(order, nb) || !CALLOC(used, nb) ||
        !ALLOC(out->loop_v, nb) || !ALLOC(out->loop_start, nb + 1) || !CALLOC(cur, nv))
        goto nomem;
    size_t k = 0;
    for (size_t i = 0, j; i < ne; i = j) {
        j = group_end(S, ne, i);
        long net = edge_net(S, i, j, flip);
        uint32_t lo = (uint32_t)(S[i].key >> 32), hi = (uint32_t)S[i].key;
        for (long r = 0; r < labs(net); r++, k++) {
            be[k][0] = net > 0 ? lo : hi;
            be[k][1] = net > 0 ? hi : lo;
            out_start[be[k][0] + 1]++;
        }
    }
    for (size_t v = 0; v < nv; v++)
        out_start[v + 1] += out_start[v];
    for (size_t e = 0; e < nb; e++)
        order[out_start[be[e][0]] + cur[be[e][0]]++] = (uint32_t)e;
    for (size_t v = 0; v < nv; v++)
        cur[v] = out_start[v]; /* the next unused out-edge of each vertex */
    /* closed walks: every vertex of a boundary chain has as many edges in as
     * out, so a walk from an edge returns to its start */
    size_t nl = 0, nvl = 0;
    for (size_t e0 = 0; e0 < nb; e0++) {
        if (used[e0])
            continue;
        out->loop_start[nl] = nvl;
        uint32_t first = be[e0][0], e = (uint32_t)e0;
        for (;;) {
            used[e] = 1;
            out->loop_v[nvl++] = be[e][0];
            uint32_t v = be[e][1];
            if (v == first)
                break;
            while (cur[v] < out_start[v + 1] && used[order[cur[v]]])
                cur[v]++;
            if (cur[v] == out_start[v + 1])
                break; /* cannot happen for a boundary chain; closed by the fan */
            e = order[cur[v]++];
        }
        nl++;
    }
    out->loop_start[nl] = nvl;
    out->n_loops = nl;
    /* the caps' area: fans from each loop's centroid */
    for (size_t l = 0; l < out->n_loops; l++) {
        double c[3];
        vv_mesh_loop_centroid(m, out, l, c);
        size_t a = out->loop_start[l], b = out->loop_start[l + 1];
        for (size_t i = a; i < b; i++) {
            const float *p = P + 3 * (size_t)out->loop_v[i];
            const float *q = P + 3 * (size_t)out->loop_v[i + 1 < b ? i + 1 : a];
            double u[3], v[3];
            for (int d = 0; d < 3; d++) {
                u[d] = p[d] - c[d];
                v[d] = q[d] - c[d];
            }
            double n0 = u[1] * v[2] - u[2] * v[1], n1 = u[2] * v[0] - u[0] * v[2],
                   n2 = u[0] * v[1] - u[1] * v[0];
            out->cap_area += 0.5 * sqrt(n0 * n0 + n1 * n1 + n2 * n2);
        }
    }
    goto done;
nomem:
    st = vv_error_set(VV_ERR_NOMEM, "mesh holes: out of memory for %zu triangles", nt);
    vv_mesh_holes_free(out);
done:
#undef ALLOC
#undef CALLOC
    free(weld);
    free(ids);
    free(deg);
    free(adj);
    free(queue);
    free(comp);
    free(fill);
    free(out_start);
    free(order);
    free(cur);
    free(start);
    free(E);
    free(S);
    free(flip);
    free(used);
    free(be);
    return st;
}

void
vv_mesh_loop_centroid(const vv_mesh *m, const vv_mesh_holes *h, size_t l, double c[3]) {
    size_t a = h->loop_start[l], b = h->loop_start[l + 1];
    c[0] = c[1] = c[2] = 0;
    for (size_t i = a; i < b; i++)
        for (int d = 0; d < 3; d++)
            c[d] += m->positions[3 * (size_t)h->loop_v[i] + d];
    for (int d = 0; d < 3; d++)
        c[d] /= (double)(b - a);
}

double
vv_solid_angle(const double a[3], const double b[3], const double c[3]) {
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                 a[2] * (b[0] * c[1] - b[1] * c[0]);
    double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    double ac = a[0] * c[0] + a[1] * c[1] + a[2] * c[2];
    double bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
    return 2.0 * atan2(det, la * lb * lc + ab * lc + ac * lb + bc * la);
}
