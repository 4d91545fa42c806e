/*
 * Geodesic distance along a triangle mesh by Dijkstra's algorithm on a
 * Steiner graph (Lanthier, Maheshwari and Sack, "Approximating shortest
 * paths on weighted polyhedral surfaces", Algorithmica 30, 2001): the mesh
 * vertices plus k points evenly spaced on every edge; within each triangle
 * every pair of its boundary points is joined by a straight segment. The
 * result is the length of a real path on the surface, so it is never below
 * the true geodesic, and it converges to it as k grows (a path crossing a
 * triangle deviates from the straight line by at most half a Steiner
 * spacing per crossed edge).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "measure/measure_internal.h"

typedef struct geo_mesh {
    const vv_mesh *m;
    int k; /* Steiner points per edge */
    size_t n_edges;
    uint32_t (*edge_v)[2]; /* edge -> its two vertices (lower first) */
    uint32_t (*edge_t)[2]; /* edge -> its triangles (UINT32_MAX: none) */
    uint32_t (*tri_e)[3];  /* triangle -> edges of (v0 v1), (v1 v2), (v2 v0) */
    uint32_t *vt_start;    /* vertex -> triangles, CSR */
    uint32_t *vt;
} geo_mesh;

static void
geo_free(geo_mesh *g) {
    free(g->edge_v);
    free(g->edge_t);
    free(g->tri_e);
    free(g->vt_start);
    free(g->vt);
}

static vv_status
geo_build(geo_mesh *g, const vv_mesh *m, int k) {
    memset(g, 0, sizeof *g);
    g->m = m;
    g->k = k;
    const size_t nt = m->n_triangles, nv = m->n_vertices;
    size_t cap = 64;
    while (cap < 4 * nt)
        cap *= 2;
    uint64_t *key = malloc(cap * sizeof *key);
    uint32_t *val = malloc(cap * sizeof *val);
    g->edge_v = malloc(3 * nt * sizeof *g->edge_v);
    g->edge_t = malloc(3 * nt * sizeof *g->edge_t);
    g->tri_e = malloc(nt * sizeof *g->tri_e);
    g->vt_start = calloc(nv + 1, sizeof *g->vt_start);
    g->vt = malloc(3 * nt * sizeof *g->vt);
    if (!key || !val || !g->edge_v || !g->edge_t || !g->tri_e || !g->vt_start || !g->vt) {
        free(key);
        free(val);
        geo_free(g);
        return vv_error_set(VV_ERR_NOMEM, "geodesic: out of memory for %zu triangles", nt);
    }
    memset(key, 0xff, cap * sizeof *key);
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *tr = m->triangles + 3 * t;
        for (int c = 0; c < 3; c++) {
            uint32_t a = tr[c], b = tr[(c + 1) % 3], lo = a < b ? a : b, hi = a < b ? b : a;
            uint64_t kk = ((uint64_t)lo << 32) | hi;
            size_t h = (size_t)((kk * 0x9E3779B97F4A7C15ULL) >> 17) & (cap - 1);
            while (key[h] != UINT64_MAX && key[h] != kk)
                h = (h + 1) & (cap - 1);
            uint32_t e;
            if (key[h] == kk) {
                e = val[h];
                if (g->edge_t[e][1] == UINT32_MAX)
                    g->edge_t[e][1] = (uint32_t)t;
            } else {
                e = (uint32_t)g->n_edges++;
                key[h] = kk;
                val[h] = e;
                g->edge_v[e][0] = lo;
                g->edge_v[e][1] = hi;
                g->edge_t[e][0] = (uint32_t)t;
                g->edge_t[e][1] = UINT32_MAX;
            }
            g->tri_e[t][c] = e;
        }
        for (int c = 0; c < 3; c++)
            g->vt_start[tr[c] + 1]++;
    }
    free(key);
    free(val);
    for (size_t v = 0; v < nv; v++)
        g->vt_start[v + 1] += g->vt_start[v];
    uint32_t *fill = malloc((nv + 1) * sizeof *fill);
    if (!fill) {
        geo_free(g);
        return vv_error_set(VV_ERR_NOMEM, "geodesic: out of memory");
    }
    memcpy(fill, g->vt_start, (nv + 1) * sizeof *fill);
    for (size_t t = 0; t < nt; t++)
        for (int c = 0; c < 3; c++)
            g->vt[fill[m->triangles[3 * t + c]]++] = (uint32_t)t;
    free(fill);
    return VV_OK;
}

/* Node ids: vertex v is v; Steiner point s (0..k-1) of edge e is nv + e k + s. */
static vv_vec3
node_pos(const geo_mesh *g, size_t node) {
    const size_t nv = g->m->n_vertices;
    if (node < nv)
        return vv_mesh_vertex(g->m, node);
    size_t e = (node - nv) / (size_t)g->k, s = (node - nv) % (size_t)g->k;
    return vv_vec3_lerp(vv_mesh_vertex(g->m, g->edge_v[e][0]),
                        vv_mesh_vertex(g->m, g->edge_v[e][1]), (double)(s + 1) / (g->k + 1));
}

/* The boundary nodes of triangle t (3 + 3k of them) into out; returns the count. */
static int
tri_nodes(const geo_mesh *g, size_t t, size_t *out) {
    int n = 0;
    const size_t nv = g->m->n_vertices;
    for (int c = 0; c < 3; c++) {
        out[n++] = g->m->triangles[3 * t + c];
        size_t e = g->tri_e[t][c];
        for (int s = 0; s < g->k; s++)
            out[n++] = nv + e * (size_t)g->k + (size_t)s;
    }
    return n;
}

/* Binary min-heap of (distance, node) with lazy deletion. */
typedef struct heap {
    size_t n, cap;
    double *d;
    size_t *v;
} heap;

static int
heap_push(heap *h, double d, size_t v) {
    if (h->n == h->cap) {
        size_t cap = h->cap ? 2 * h->cap : 1024;
        double *nd = realloc(h->d, cap * sizeof *nd);
        if (!nd)
            return 0;
        h->d = nd;
        size_t *nvv = realloc(h->v, cap * sizeof *nvv);
        if (!nvv)
            return 0;
        h->v = nvv;
        h->cap = cap;
    }
    size_t i = h->n++;
    while (i > 0 && h->d[(i - 1) / 2] > d) {
        h->d[i] = h->d[(i - 1) / 2];
        h->v[i] = h->v[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h->d[i] = d;
    h->v[i] = v;
    return 1;
}

static void
heap_pop(heap *h, double *d, size_t *v) {
    *d = h->d[0];
    *v = h->v[0];
    double ld = h->d[--h->n];
    size_t lv = h->v[h->n], i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= h->n)
            break;
        if (c + 1 < h->n && h->d[c + 1] < h->d[c])
            c++;
        if (h->d[c] >= ld)
            break;
        h->d[i] = h->d[c];
        h->v[i] = h->v[c];
        i = c;
    }
    h->d[i] = ld;
    h->v[i] = lv;
}

/* The closest point of the mesh to p: its triangle and position. */
static size_t
closest_triangle(const vv_mesh *m, vv_vec3 p, vv_vec3 *q) {
    size_t best_t = 0;
    double best = INFINITY;
    for (size_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *tr = m->triangles + 3 * t;
        vv_vec3 a = vv_mesh_vertex(m, tr[0]), b = vv_mesh_vertex(m, tr[1]),
                c = vv_mesh_vertex(m, tr[2]);
        /* closest point on the triangle (Ericson 5.1.5) */
        vv_vec3 ab = vv_vec3_sub(b, a), ac = vv_vec3_sub(c, a), ap = vv_vec3_sub(p, a), x;
        double d1 = vv_vec3_dot(ab, ap), d2 = vv_vec3_dot(ac, ap);
        vv_vec3 bp = vv_vec3_sub(p, b), cp = vv_vec3_sub(p, c);
        double d3 = vv_vec3_dot(ab, bp), d4 = vv_vec3_dot(ac, bp), d5 = vv_vec3_dot(ab, cp),
               d6 = vv_vec3_dot(ac, cp);
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d1 <= 0 && d2 <= 0)
            x = a;
        else if (d3 >= 0 && d4 <= d3)
            x = b;
        else if (vc <= 0 && d1 >= 0 && d3 <= 0)
            x = vv_vec3_add(a, vv_vec3_scale(ab, d1 / (d1 - d3)));
        else if (d6 >= 0 && d5 <= d6)
            x = c;
        else if (vb <= 0 && d2 >= 0 && d6 <= 0)
            x = vv_vec3_add(a, vv_vec3_scale(ac, d2 / (d2 - d6)));
        else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
            x = vv_vec3_add(b,
                            vv_vec3_scale(vv_vec3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
        else {
            double den = va + vb + vc;
            x = den > 0 ? vv_vec3_add(a, vv_vec3_add(vv_vec3_scale(ab, vb / den),
                                                     vv_vec3_scale(ac, vc / den)))
                        : a;
        }
        double d = vv_vec3_length(vv_vec3_sub(p, x));
        if (d < best) {
            best = d;
            best_t = t;
            *q = x;
        }
    }
    return best_t;
}

vv_status
vv_measure_geodesic(const vv_mesh *m, vv_vec3 a, vv_vec3 b, int steiner, double *out, vv_vec3 *a_on,
                    vv_vec3 *b_on) {
    if (!m || !out)
        return vv_error_set(VV_ERR_INVALID, "geodesic: NULL argument");
    if (m->n_triangles == 0)
        return vv_error_set(VV_ERR_INVALID, "geodesic: the mesh has no triangles");
    if (steiner < 0 || steiner > 64)
        return vv_error_set(VV_ERR_INVALID, "geodesic: %d Steiner points per edge (0..64)",
                            steiner);
    if (!isfinite(a.x + a.y + a.z + b.x + b.y + b.z))
        return vv_error_set(VV_ERR_INVALID, "geodesic: coordinates are not finite");
    geo_mesh g;
    vv_status s = geo_build(&g, m, steiner);
    if (s != VV_OK)
        return s;
    const size_t nv = m->n_vertices, nn = nv + g.n_edges * (size_t)steiner;
    vv_vec3 pa, pb;
    size_t ta = closest_triangle(m, a, &pa), tb = closest_triangle(m, b, &pb);
    if (a_on)
        *a_on = pa;
    if (b_on)
        *b_on = pb;
    double *dist = malloc(nn * sizeof *dist);
    unsigned char *done = calloc(nn, 1);
    size_t *tn = malloc((3 + 3 * (size_t)steiner) * sizeof *tn);
    size_t *un = malloc((3 + 3 * (size_t)steiner) * sizeof *un);
    heap h = {0, 0, NULL, NULL};
    if (!dist || !done || !tn || !un) {
        s = vv_error_set(VV_ERR_NOMEM, "geodesic: out of memory for %zu graph nodes", nn);
        goto out;
    }
    for (size_t i = 0; i < nn; i++)
        dist[i] = INFINITY;
    /* start: straight segments from pa to the nodes of its triangle */
    int n = tri_nodes(&g, ta, tn);
    for (int i = 0; i < n; i++) {
        double d = vv_vec3_length(vv_vec3_sub(node_pos(&g, tn[i]), pa));
        if (d < dist[tn[i]]) {
            dist[tn[i]] = d;
            if (!heap_push(&h, d, tn[i])) {
                s = vv_error_set(VV_ERR_NOMEM, "geodesic: out of memory");
                goto out;
            }
        }
    }
    /* the end: reached from the nodes of its triangle */
    double best = ta == tb ? vv_vec3_length(vv_vec3_sub(pa, pb)) : INFINITY;
    int nb = tri_nodes(&g, tb, un);
    while (h.n) {
        double d;
        size_t v;
        heap_pop(&h, &d, &v);
        if (done[v] || d > dist[v])
            continue;
        if (d >= best)
            break; /* every remaining path is longer */
        done[v] = 1;
        for (int i = 0; i < nb; i++)
            if (un[i] == v) {
                double e = d + vv_vec3_length(vv_vec3_sub(node_pos(&g, v), pb));
                best = e < best ? e : best;
            }
        /* relax across the triangles around the node */
        vv_vec3 pv = node_pos(&g, v);
        size_t q0, q1, single[2];
        const size_t *list = NULL;
        const uint32_t *list32 = NULL;
        if (v < nv) {
            q0 = g.vt_start[v];
            q1 = g.vt_start[v + 1];
            list32 = g.vt;
        } else {
            size_t e = (v - nv) / (size_t)steiner;
            single[0] = g.edge_t[e][0];
            single[1] = g.edge_t[e][1];
            q0 = 0;
            q1 = single[1] == UINT32_MAX ? 1 : 2;
            list = single;
        }
        for (size_t q = q0; q < q1; q++) {
            n = tri_nodes(&g, list32 ? list32[q] : list[q], tn);
            for (int i = 0; i < n; i++) {
                size_t w = tn[i];
                if (done[w])
                    continue;
                double nd = d + vv_vec3_length(vv_vec3_sub(node_pos(&g, w), pv));
                if (nd < dist[w]) {
                    dist[w] = nd;
                    if (!heap_push(&h, nd, w)) {
                        s = vv_error_set(VV_ERR_NOMEM, "geodesic: out of memory");
                        goto out;
                    }
                }
            }
        }
    }
    if (!isfinite(best)) {
        s = vv_error_set(VV_ERR_INVALID,
                         "geodesic: the two points lie on different connected parts of the "
                         "surface");
        goto out;
    }
    *out = best;
out:
    free(dist);
    free(done);
    free(tn);
    free(un);
    free(h.d);
    free(h.v);
    geo_free(&g);
    return s;
}
