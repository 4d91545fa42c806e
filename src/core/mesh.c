/*
 * Indexed triangle meshes: storage, normals, bounds, transforms, area,
 * divergence-theorem volume and edge topology (see include/volvis/mesh.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "volvis/mesh.h"

vv_status
vv_mesh_new(vv_mesh **out) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL output");
    *out = calloc(1, sizeof **out);
    if (!*out)
        return vv_error_set(VV_ERR_NOMEM, "mesh: out of memory");
    (*out)->refcount = 1;
    return VV_OK;
}

vv_mesh *
vv_mesh_ref(vv_mesh *m) {
    if (m) {
#pragma omp atomic
        m->refcount++;
    }
    return m;
}

void
vv_mesh_free(vv_mesh *m) {
    if (!m)
        return;
    int left;
#pragma omp atomic capture
    left = --m->refcount;
    if (left > 0)
        return;
    free(m->positions);
    free(m->normals);
    free(m->scalars);
    free(m->triangles);
    free(m);
}

static vv_status
grow(void **p, size_t n, size_t elem) {
    void *q = realloc(*p, n * elem);
    if (!q)
        return vv_error_set(VV_ERR_NOMEM, "mesh: out of memory for %zu elements", n);
    *p = q;
    return VV_OK;
}

vv_status
vv_mesh_reserve(vv_mesh *m, size_t n_vertices, size_t n_triangles) {
    if (!m)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL mesh");
    if (n_vertices > VV_MESH_MAX_ELEMENTS || n_triangles > VV_MESH_MAX_ELEMENTS)
        return vv_error_set(VV_ERR_LIMIT, "mesh: %zu vertices, %zu triangles (at most %zu each)",
                            n_vertices, n_triangles, (size_t)VV_MESH_MAX_ELEMENTS);
    /* positions and normals (and scalars) per vertex, three indices per triangle */
    vv_status s = vv_memory_budget_check((uint64_t)n_vertices * 7 * sizeof(float) +
                                             (uint64_t)n_triangles * 3 * sizeof(uint32_t),
                                         "mesh");
    if (s != VV_OK)
        return s;
    if (n_vertices > m->cap_vertices) {
        if ((s = grow((void **)&m->positions, n_vertices, 3 * sizeof(float))) != VV_OK)
            return s;
        if (m->normals && (s = grow((void **)&m->normals, n_vertices, 3 * sizeof(float))) != VV_OK)
            return s;
        if (m->scalars && (s = grow((void **)&m->scalars, n_vertices, sizeof(float))) != VV_OK)
            return s;
        m->cap_vertices = n_vertices;
    }
    if (n_triangles > m->cap_triangles) {
        if ((s = grow((void **)&m->triangles, n_triangles, 3 * sizeof(uint32_t))) != VV_OK)
            return s;
        m->cap_triangles = n_triangles;
    }
    return VV_OK;
}

vv_status
vv_mesh_enable_attributes(vv_mesh *m, int with_normals, int with_scalars) {
    if (!m)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL mesh");
    size_t cap = m->cap_vertices ? m->cap_vertices : 1;
    if (with_normals && !m->normals) {
        m->normals = calloc(cap, 3 * sizeof(float));
        if (!m->normals)
            return vv_error_set(VV_ERR_NOMEM, "mesh: out of memory for normals");
    }
    if (with_scalars && !m->scalars) {
        m->scalars = calloc(cap, sizeof(float));
        if (!m->scalars)
            return vv_error_set(VV_ERR_NOMEM, "mesh: out of memory for scalars");
    }
    return VV_OK;
}

vv_status
vv_mesh_add_vertex(vv_mesh *m, vv_vec3 p, uint32_t *index) {
    if (!m)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL mesh");
    if (m->n_vertices >= m->cap_vertices) {
        size_t cap = m->cap_vertices < 64 ? 64 : m->cap_vertices * 2;
        if (cap > VV_MESH_MAX_ELEMENTS)
            cap = VV_MESH_MAX_ELEMENTS;
        if (m->n_vertices >= cap)
            return vv_error_set(VV_ERR_LIMIT, "mesh: more than %zu vertices",
                                (size_t)VV_MESH_MAX_ELEMENTS);
        vv_status s = vv_mesh_reserve(m, cap, m->cap_triangles);
        if (s != VV_OK)
            return s;
    }
    size_t i = m->n_vertices++;
    m->positions[3 * i] = (float)p.x;
    m->positions[3 * i + 1] = (float)p.y;
    m->positions[3 * i + 2] = (float)p.z;
    if (m->normals)
        m->normals[3 * i] = m->normals[3 * i + 1] = m->normals[3 * i + 2] = 0.0f;
    if (m->scalars)
        m->scalars[i] = 0.0f;
    if (index)
        *index = (uint32_t)i;
    return VV_OK;
}

vv_status
vv_mesh_add_triangle(vv_mesh *m, uint32_t a, uint32_t b, uint32_t c) {
    if (!m)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL mesh");
    if (a >= m->n_vertices || b >= m->n_vertices || c >= m->n_vertices)
        return vv_error_set(VV_ERR_INVALID, "mesh: triangle (%u, %u, %u) names a vertex >= %zu", a,
                            b, c, m->n_vertices);
    if (m->n_triangles >= m->cap_triangles) {
        size_t cap = m->cap_triangles < 64 ? 64 : m->cap_triangles * 2;
        if (cap > VV_MESH_MAX_ELEMENTS)
            cap = VV_MESH_MAX_ELEMENTS;
        if (m->n_triangles >= cap)
            return vv_error_set(VV_ERR_LIMIT, "mesh: more than %zu triangles",
                                (size_t)VV_MESH_MAX_ELEMENTS);
        vv_status s = vv_mesh_reserve(m, m->cap_vertices, cap);
        if (s != VV_OK)
            return s;
    }
    uint32_t *t = m->triangles + 3 * m->n_triangles++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    return VV_OK;
}

vv_vec3
vv_mesh_vertex(const vv_mesh *m, size_t i) {
    const float *p = m->positions + 3 * i;
    return vv_vec3_make(p[0], p[1], p[2]);
}

vv_status
vv_mesh_compute_normals(vv_mesh *m) {
    if (!m)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL mesh");
    vv_status s = vv_mesh_enable_attributes(m, 1, 0);
    if (s != VV_OK)
        return s;
    double *acc = calloc(m->n_vertices ? m->n_vertices : 1, 3 * sizeof(double));
    if (!acc)
        return vv_error_set(VV_ERR_NOMEM, "mesh: out of memory for normals");
    for (size_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        vv_vec3 p0 = vv_mesh_vertex(m, tri[0]), p1 = vv_mesh_vertex(m, tri[1]),
                p2 = vv_mesh_vertex(m, tri[2]);
        /* the cross product's length is twice the area: area weighting for free */
        vv_vec3 n = vv_vec3_cross(vv_vec3_sub(p1, p0), vv_vec3_sub(p2, p0));
        for (int k = 0; k < 3; k++) {
            acc[3 * tri[k]] += n.x;
            acc[3 * tri[k] + 1] += n.y;
            acc[3 * tri[k] + 2] += n.z;
        }
    }
    for (size_t i = 0; i < m->n_vertices; i++) {
        double *a = acc + 3 * i;
        double l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        double inv = l > 0 ? 1.0 / l : 0.0;
        for (int k = 0; k < 3; k++)
            m->normals[3 * i + k] = (float)(a[k] * inv);
    }
    free(acc);
    return VV_OK;
}

vv_box
vv_mesh_bounds(const vv_mesh *m) {
    vv_box b = {{0, 0, 0}, {0, 0, 0}};
    if (!m || m->n_vertices == 0)
        return b;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < m->n_vertices; i++)
        for (int k = 0; k < 3; k++) {
            float v = m->positions[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    b.min = vv_vec3_make(lo[0], lo[1], lo[2]);
    b.max = vv_vec3_make(hi[0], hi[1], hi[2]);
    return b;
}

void
vv_mesh_transform(vv_mesh *m, vv_mat4 M) {
    if (!m)
        return;
    for (size_t i = 0; i < m->n_vertices; i++) {
        vv_vec3 p = vv_mat4_mul_point(M, vv_mesh_vertex(m, i));
        m->positions[3 * i] = (float)p.x;
        m->positions[3 * i + 1] = (float)p.y;
        m->positions[3 * i + 2] = (float)p.z;
    }
    /* normals transform by the cofactor matrix (inverse transpose times the determinant) */
    double(*a)[4] = M.m;
    double c[3][3];
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            c[r][k] = a[r1][k1] * a[r2][k2] - a[r1][k2] * a[r2][k1];
        }
    double det = a[0][0] * c[0][0] + a[0][1] * c[0][1] + a[0][2] * c[0][2];
    if (m->normals) {
        double sgn = det < 0 ? -1.0 : 1.0;
        for (size_t i = 0; i < m->n_vertices; i++) {
            float *n = m->normals + 3 * i;
            double q[3];
            for (int r = 0; r < 3; r++)
                q[r] = sgn * (c[r][0] * n[0] + c[r][1] * n[1] + c[r][2] * n[2]);
            double l = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
            double inv = l > 0 ? 1.0 / l : 0.0;
            for (int k = 0; k < 3; k++)
                n[k] = (float)(q[k] * inv);
        }
    }
    if (det < 0)
        for (size_t t = 0; t < m->n_triangles; t++) {
            uint32_t tmp = m->triangles[3 * t + 1];
            m->triangles[3 * t + 1] = m->triangles[3 * t + 2];
            m->triangles[3 * t + 2] = tmp;
        }
}

double
vv_mesh_area(const vv_mesh *m) {
    if (!m)
        return 0.0;
    double area = 0.0;
    for (size_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        vv_vec3 p0 = vv_mesh_vertex(m, tri[0]), p1 = vv_mesh_vertex(m, tri[1]),
                p2 = vv_mesh_vertex(m, tri[2]);
        area += 0.5 * vv_vec3_length(vv_vec3_cross(vv_vec3_sub(p1, p0), vv_vec3_sub(p2, p0)));
    }
    return area;
}

double
vv_mesh_signed_volume(const vv_mesh *m) {
    if (!m || m->n_triangles == 0)
        return 0.0;
    /* Relative to the bounds' centre: the same exact sum, less cancellation
     * for meshes far from the origin. */
    vv_box b = vv_mesh_bounds(m);
    vv_vec3 c = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
    double vol = 0.0;
    for (size_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        vv_vec3 p0 = vv_vec3_sub(vv_mesh_vertex(m, tri[0]), c);
        vv_vec3 p1 = vv_vec3_sub(vv_mesh_vertex(m, tri[1]), c);
        vv_vec3 p2 = vv_vec3_sub(vv_mesh_vertex(m, tri[2]), c);
        vol += vv_vec3_dot(p0, vv_vec3_cross(p1, p2));
    }
    return vol / 6.0;
}

/* A directed edge (from, to) of triangle t, sorted by its undirected key. */
typedef struct edge_rec {
    uint64_t key;     /* min << 32 | max */
    uint32_t forward; /* 1 when from < to */
} edge_rec;

static int
edge_cmp(const void *a, const void *b) {
    const edge_rec *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (int)x->forward - (int)y->forward;
}

vv_status
vv_mesh_topology_compute(const vv_mesh *m, vv_mesh_topology *out) {
    if (!m || !out)
        return vv_error_set(VV_ERR_INVALID, "mesh topology: NULL argument");
    memset(out, 0, sizeof *out);
    size_t ne = 3 * m->n_triangles;
    edge_rec *e = malloc((ne ? ne : 1) * sizeof *e);
    unsigned char *used = calloc(m->n_vertices ? m->n_vertices : 1, 1);
    if (!e || !used) {
        free(e);
        free(used);
        return vv_error_set(VV_ERR_NOMEM, "mesh topology: out of memory");
    }
    size_t n = 0, faces = 0;
    for (size_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
            out->n_degenerate++;
            continue;
        }
        faces++;
        for (int k = 0; k < 3; k++) {
            uint32_t a = tri[k], b = tri[(k + 1) % 3];
            used[a] = 1;
            uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
            e[n].key = (uint64_t)lo << 32 | hi;
            e[n].forward = a < b;
            n++;
        }
    }
    qsort(e, n, sizeof *e, edge_cmp);
    for (size_t i = 0; i < n;) {
        size_t j = i, fwd = 0;
        while (j < n && e[j].key == e[i].key)
            fwd += e[j++].forward;
        size_t cnt = j - i;
        out->n_edges++;
        if (cnt == 1)
            out->n_boundary_edges++;
        else if (cnt > 2)
            out->n_nonmanifold_edges++;
        else if (fwd != 1)
            out->n_misoriented_edges++;
        i = j;
    }
    for (size_t i = 0; i < m->n_vertices; i++)
        out->n_vertices_used += used[i];
    out->euler = (long)out->n_vertices_used - (long)out->n_edges + (long)faces;
    out->closed = out->n_boundary_edges == 0 && out->n_nonmanifold_edges == 0 && faces > 0;
    out->oriented = out->n_misoriented_edges == 0;
    free(e);
    free(used);
    return VV_OK;
}
