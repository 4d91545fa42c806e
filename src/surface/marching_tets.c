/*
 * Surfaces of irregular grids (volvis/grid.h): Marching Tetrahedra
 * isosurfaces (Doi and Koide, "An efficient method of triangulating
 * equi-valued surfaces by using tetrahedral cells", IEICE Trans. E74(1),
 * 1991) over the grid's cells split into tetrahedra (src/core/grid_tets.c,
 * whose face diagonals agree between neighbours, so the surface has no
 * cracks), and the surface cells of a grid as a mesh.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/grid_internal.h"
#include "volvis/grid.h"
#include "volvis/mesh.h"

/* Vertices on tetrahedron edges, shared through a hash of the edge's two
 * point indices. */
typedef struct edge_map {
    uint64_t *keys;
    uint32_t *vals;
    size_t cap, n;
} edge_map;

static uint64_t
edge_hash(uint64_t k) {
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    return k;
}

static vv_status
edge_map_grow(edge_map *e) {
    const size_t cap = e->cap ? 2 * e->cap : 4096;
    uint64_t *keys = malloc(cap * sizeof *keys);
    uint32_t *vals = malloc(cap * sizeof *vals);
    if (!keys || !vals) {
        free(keys);
        free(vals);
        return vv_error_set(VV_ERR_NOMEM, "isosurface: out of memory");
    }
    memset(keys, 0xff, cap * sizeof *keys);
    for (size_t i = 0; i < e->cap; i++) {
        if (e->keys[i] == UINT64_MAX)
            continue;
        size_t s = (size_t)edge_hash(e->keys[i]) & (cap - 1);
        while (keys[s] != UINT64_MAX)
            s = (s + 1) & (cap - 1);
        keys[s] = e->keys[i];
        vals[s] = e->vals[i];
    }
    free(e->keys);
    free(e->vals);
    e->keys = keys;
    e->vals = vals;
    e->cap = cap;
    return VV_OK;
}

/* The mesh vertex on edge (a, b) at the isovalue, made on first use. */
static vv_status
edge_vertex(edge_map *e, vv_mesh *mesh, const vv_tetmesh *m, uint32_t a, uint32_t b, double iso,
            uint32_t *out) {
    if (a > b) {
        uint32_t x = a;
        a = b;
        b = x;
    }
    /* a crossing on a point is that point's vertex, whatever the edge */
    if ((double)m->val[a] == iso)
        b = a;
    else if ((double)m->val[b] == iso)
        a = b;
    const uint64_t key = (uint64_t)a << 32 | b;
    if (2 * (e->n + 1) > e->cap) {
        vv_status s = edge_map_grow(e);
        if (s != VV_OK)
            return s;
    }
    size_t s = (size_t)edge_hash(key) & (e->cap - 1);
    while (e->keys[s] != UINT64_MAX) {
        if (e->keys[s] == key) {
            *out = e->vals[s];
            return VV_OK;
        }
        s = (s + 1) & (e->cap - 1);
    }
    const double va = m->val[a], vb = m->val[b];
    const double u = vb != va ? (iso - va) / (vb - va) : 0.5;
    const double *pa = m->p + 3 * (size_t)a, *pb = m->p + 3 * (size_t)b;
    vv_vec3 p = vv_vec3_make(pa[0] + u * (pb[0] - pa[0]), pa[1] + u * (pb[1] - pa[1]),
                             pa[2] + u * (pb[2] - pa[2]));
    vv_status st = vv_mesh_add_vertex(mesh, p, out);
    if (st != VV_OK)
        return st;
    if (mesh->scalars)
        mesh->scalars[*out] = (float)iso;
    e->keys[s] = key;
    e->vals[s] = *out;
    e->n++;
    return VV_OK;
}

/* Adds triangle (a, b, c) facing away from the higher values (gradient g). */
static vv_status
add_oriented(vv_mesh *mesh, uint32_t a, uint32_t b, uint32_t c, const double g[3]) {
    if (a == b || b == c || a == c)
        return VV_OK;
    const vv_vec3 pa = vv_mesh_vertex(mesh, a), pb = vv_mesh_vertex(mesh, b),
                  pc = vv_mesh_vertex(mesh, c);
    const vv_vec3 n = vv_vec3_cross(vv_vec3_sub(pb, pa), vv_vec3_sub(pc, pa));
    if (n.x * g[0] + n.y * g[1] + n.z * g[2] > 0)
        return vv_mesh_add_triangle(mesh, a, c, b);
    return vv_mesh_add_triangle(mesh, a, b, c);
}

/* Point values of a field: cell data averaged onto the points (missing
 * values left out; a point with only missing cells is missing). */
static vv_status
point_values(const vv_grid *g, int field, int component, float **out) {
    float *sc = NULL;
    vv_status s = vv_grid_field_scalars(g, field, component, &sc);
    if (s != VV_OK || !g->fields[field].cell_data) {
        *out = sc;
        return s;
    }
    float *pv = calloc(g->n_points ? g->n_points : 1, sizeof *pv);
    uint32_t *cnt = calloc(g->n_points ? g->n_points : 1, sizeof *cnt);
    if (!pv || !cnt) {
        free(sc);
        free(pv);
        free(cnt);
        return vv_error_set(VV_ERR_NOMEM, "isosurface: out of memory");
    }
    for (size_t c = 0; c < g->n_cells; c++) {
        if (sc[c] != sc[c])
            continue;
        for (size_t k = g->cell_offsets[c]; k < g->cell_offsets[c + 1]; k++) {
            pv[g->connectivity[k]] += sc[c];
            cnt[g->connectivity[k]]++;
        }
    }
    for (size_t i = 0; i < g->n_points; i++)
        pv[i] = cnt[i] ? pv[i] / (float)cnt[i] : NAN;
    free(sc);
    free(cnt);
    *out = pv;
    return VV_OK;
}

vv_status
vv_grid_isosurface(const vv_grid *g, int field, int component, double isovalue, vv_mesh **out) {
    *out = NULL;
    if (!g || field < 0 || field >= g->n_fields || !isfinite(isovalue))
        return vv_error_set(VV_ERR_INVALID, "isosurface: bad grid, field or isovalue");
    float *pv = NULL;
    vv_status s = point_values(g, field, component, &pv);
    if (s != VV_OK)
        return s;
    vv_tetmesh m;
    s = vv_tetmesh_build(&m, g, pv, 0, 0, 0);
    free(pv);
    if (s != VV_OK)
        return s;
    vv_mesh *mesh = NULL;
    edge_map e = {NULL, NULL, 0, 0};
    if ((s = vv_mesh_new(&mesh)) == VV_OK)
        s = vv_mesh_enable_attributes(mesh, 0, 1);
    for (size_t t = 0; t < m.n_tets && s == VV_OK; t++) {
        const uint32_t *v = m.tet + 4 * t;
        int in[4], n_in = 0;
        for (int i = 0; i < 4; i++) {
            in[i] = m.val[v[i]] >= isovalue;
            n_in += in[i];
        }
        if (n_in == 0 || n_in == 4)
            continue;
        /* the tetrahedron's gradient orients the triangles */
        const double *p0 = m.p + 3 * (size_t)v[0];
        double E[3][3], df[3], gr[3];
        for (int i = 0; i < 3; i++) {
            for (int c = 0; c < 3; c++)
                E[i][c] = m.p[3 * (size_t)v[i + 1] + (size_t)c] - p0[c];
            df[i] = (double)m.val[v[i + 1]] - m.val[v[0]];
        }
        /* g = E^-1 df through the cross products of the edges */
        const double c12[3] = {E[1][1] * E[2][2] - E[1][2] * E[2][1],
                               E[1][2] * E[2][0] - E[1][0] * E[2][2],
                               E[1][0] * E[2][1] - E[1][1] * E[2][0]};
        const double c20[3] = {E[2][1] * E[0][2] - E[2][2] * E[0][1],
                               E[2][2] * E[0][0] - E[2][0] * E[0][2],
                               E[2][0] * E[0][1] - E[2][1] * E[0][0]};
        const double c01[3] = {E[0][1] * E[1][2] - E[0][2] * E[1][1],
                               E[0][2] * E[1][0] - E[0][0] * E[1][2],
                               E[0][0] * E[1][1] - E[0][1] * E[1][0]};
        for (int c = 0; c < 3; c++)
            gr[c] = df[0] * c12[c] + df[1] * c20[c] + df[2] * c01[c];
        if (n_in == 1 || n_in == 3) {
            int lone = 0;
            for (int i = 0; i < 4; i++)
                if (in[i] == (n_in == 1))
                    lone = i;
            uint32_t w[3];
            int k = 0;
            for (int i = 0; i < 4 && s == VV_OK; i++)
                if (i != lone)
                    s = edge_vertex(&e, mesh, &m, v[lone], v[i], isovalue, &w[k++]);
            if (s == VV_OK)
                s = add_oriented(mesh, w[0], w[1], w[2], gr);
        } else {
            int a[2], b[2], na = 0, nb = 0;
            for (int i = 0; i < 4; i++) {
                if (in[i])
                    a[na++] = i;
                else
                    b[nb++] = i;
            }
            uint32_t q[4];
            if ((s = edge_vertex(&e, mesh, &m, v[a[0]], v[b[0]], isovalue, &q[0])) != VV_OK ||
                (s = edge_vertex(&e, mesh, &m, v[a[0]], v[b[1]], isovalue, &q[1])) != VV_OK ||
                (s = edge_vertex(&e, mesh, &m, v[a[1]], v[b[1]], isovalue, &q[2])) != VV_OK ||
                (s = edge_vertex(&e, mesh, &m, v[a[1]], v[b[0]], isovalue, &q[3])) != VV_OK)
                break;
            if ((s = add_oriented(mesh, q[0], q[1], q[2], gr)) == VV_OK)
                s = add_oriented(mesh, q[0], q[2], q[3], gr);
        }
    }
    free(e.keys);
    free(e.vals);
    vv_tetmesh_clear(&m);
    if (s == VV_OK && mesh->n_triangles > 0)
        s = vv_mesh_compute_normals(mesh);
    if (s != VV_OK) {
        vv_mesh_free(mesh);
        return s;
    }
    *out = mesh;
    return VV_OK;
}

vv_status
vv_grid_surface_mesh(const vv_grid *g, int field, int displacement, vv_mesh **out) {
    *out = NULL;
    if (!g || field >= g->n_fields || displacement >= g->n_fields ||
        (displacement >= 0 &&
         (g->fields[displacement].n_components != 3 || g->fields[displacement].cell_data)))
        return vv_error_set(VV_ERR_INVALID, "surface mesh: bad field or displacement");
    size_t ns = 0;
    vv_grid_count_cells(g, NULL, &ns);
    if (ns == 0)
        return vv_error_set(VV_ERR_INVALID, "surface mesh: the grid has no surface cells");
    float *pv = NULL;
    vv_status s = VV_OK;
    if (field >= 0 && (s = point_values(g, field, -1, &pv)) != VV_OK)
        return s;
    vv_mesh *mesh = NULL;
    if ((s = vv_mesh_new(&mesh)) == VV_OK)
        s = vv_mesh_enable_attributes(mesh, 0, field >= 0);
    if (s == VV_OK)
        s = vv_mesh_reserve(mesh, g->n_points, 2 * ns);
    const float *dv = displacement >= 0 ? g->fields[displacement].values : NULL;
    for (size_t i = 0; i < g->n_points && s == VV_OK; i++) {
        const double *p = g->points + 3 * i;
        vv_vec3 q = vv_vec3_make(p[0], p[1], p[2]);
        if (dv)
            q = vv_vec3_add(q, vv_vec3_make(dv[3 * i], dv[3 * i + 1], dv[3 * i + 2]));
        uint32_t idx;
        s = vv_mesh_add_vertex(mesh, q, &idx);
        if (s == VV_OK && pv)
            mesh->scalars[idx] = pv[i];
    }
    for (size_t c = 0; c < g->n_cells && s == VV_OK; c++) {
        const int t = g->cell_types[c];
        if (t != VV_CELL_TRIANGLE && t != VV_CELL_QUAD && t != VV_CELL_POLYGON)
            continue;
        const uint32_t *p = g->connectivity + g->cell_offsets[c];
        const size_t n = g->cell_offsets[c + 1] - g->cell_offsets[c];
        for (size_t k = 1; k + 1 < n && s == VV_OK; k++)
            s = vv_mesh_add_triangle(mesh, p[0], p[k], p[k + 1]);
    }
    free(pv);
    if (s == VV_OK)
        s = vv_mesh_compute_normals(mesh);
    if (s != VV_OK) {
        vv_mesh_free(mesh);
        return s;
    }
    *out = mesh;
    return VV_OK;
}
