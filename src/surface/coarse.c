/*
 * Coarse Marching Cubes (VolVis paper, section on the Navigator): Marching
 * Cubes on a reduced grid, each edge crossing restricted to one of four
 * positions so that a vertex is its edge plus 2 bits. The reduced grid is
 * the volume filtered by a separable tent of half-width `stride` (so the
 * preview is smooth, not aliased) and sampled every `stride` voxels; it is
 * built once, and each new isovalue runs the fast extraction on it.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "surface_internal.h"

/* Filters n samples (stride st in src) with the tent of half-width s, decimating by s:
 * out[c] = sum_d w(d) src[c s + d] / sum w, w(d) = s - |d|, taps clamped to the axis. */
static void
tent_decimate(const float *src, size_t st, int n, int s, float *out, size_t ost, int nc) {
    for (int c = 0; c < nc; c++) {
        double acc = 0, wsum = 0;
        int ctr = c * s;
        for (int d = -(s - 1); d <= s - 1; d++) {
            int i = ctr + d;
            if (i < 0 || i >= n)
                continue;
            double w = s - abs(d);
            acc += w * src[(size_t)i * st];
            wsum += w;
        }
        out[(size_t)c * ost] = (float)(acc / wsum);
    }
}

vv_status
vv_coarse_new(vv_coarse_surface **out, const vv_volume *v, int level) {
    if (!out || !v || !v->data)
        return vv_error_set(VV_ERR_INVALID, "coarse surface: NULL argument");
    *out = NULL;
    if (level < 0 || level > 8)
        return vv_error_set(VV_ERR_INVALID, "coarse surface: level %d outside 0..8", level);
    const int s = 1 << level;
    int nd[3];
    for (int a = 0; a < 3; a++)
        nd[a] = (v->dims[a] - 1) / s + 1;
    vv_coarse_surface *c = calloc(1, sizeof *c);
    if (!c)
        return vv_error_set(VV_ERR_NOMEM, "coarse surface: out of memory");
    c->level = level;
    c->stride = s;
    c->isovalue = NAN;
    memcpy(c->dims, nd, sizeof nd);
    vv_status st = vv_volume_new(&c->reduced, nd, VV_F32);
    if (st != VV_OK) {
        free(c);
        return vv_error_prefix(st, "coarse surface");
    }
    vv_volume *r = c->reduced;
    for (int a = 0; a < 3; a++) {
        r->spacing[a] = v->spacing[a] * s;
        r->origin[a] = v->origin[a];
    }
    memcpy(r->direction, v->direction, sizeof r->direction);
    r->unit = v->unit;
    r->space = v->space;
    const int n0 = v->dims[0], n1 = v->dims[1], n2 = v->dims[2];
    /* x then y then z, each pass decimating; intermediate arrays in float */
    float *ax = malloc((size_t)nd[0] * (size_t)n1 * (size_t)n2 * sizeof(float));
    float *ay = malloc((size_t)nd[0] * (size_t)nd[1] * (size_t)n2 * sizeof(float));
    int failed = !ax || !ay;
    if (!failed) {
#pragma omp parallel
        {
            float *row = malloc((size_t)n0 * sizeof(float));
            if (!row) {
#pragma omp atomic write
                failed = 1;
            }
#pragma omp for schedule(static)
            for (long q = 0; q < (long)n1 * n2; q++) {
                if (!row)
                    continue;
                int j = (int)(q % n1), k = (int)(q / n1);
                for (int i = 0; i < n0; i++)
                    row[i] = (float)vv_volume_get(v, i, j, k);
                tent_decimate(row, 1, n0, s, ax + (size_t)q * (size_t)nd[0], 1, nd[0]);
            }
            free(row);
#pragma omp for schedule(static)
            for (long q = 0; q < (long)nd[0] * n2; q++) {
                int i = (int)(q % nd[0]), k = (int)(q / nd[0]);
                tent_decimate(ax + (size_t)k * n1 * nd[0] + (size_t)i, (size_t)nd[0], n1, s,
                              ay + (size_t)k * nd[1] * nd[0] + (size_t)i, (size_t)nd[0], nd[1]);
            }
#pragma omp for schedule(static)
            for (long q = 0; q < (long)nd[0] * nd[1]; q++)
                tent_decimate(ay + q, (size_t)nd[0] * nd[1], n2, s, (float *)r->data + q,
                              (size_t)nd[0] * nd[1], nd[2]);
        }
    }
    free(ax);
    free(ay);
    if (failed) {
        vv_coarse_free(c);
        return vv_error_set(VV_ERR_NOMEM, "coarse surface: out of memory for the reduced grid");
    }
    vv_volume_update_range(r);
    *out = c;
    return VV_OK;
}

vv_status
vv_coarse_set_isovalue(vv_coarse_surface *c, double isovalue, int threads) {
    if (!c)
        return vv_error_set(VV_ERR_INVALID, "coarse surface: NULL argument");
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    o.compute_normals = 0;
    mc_extra x = {1, NULL, NULL};
    vv_mesh *m = NULL;
    vv_status s = vv_isosurface_extract_ex(&m, c->reduced, isovalue, &o, &x);
    if (s != VV_OK)
        return vv_error_prefix(s, "coarse surface");
    size_t nv = m->n_vertices, ncent = 0;
    for (size_t i = 0; i < nv; i++)
        ncent += x.edge_ids[i] == UINT32_MAX;
    uint8_t *codes = calloc(nv / 4 + 1, 1);
    float *cent = malloc((ncent ? ncent : 1) * 3 * sizeof(float));
    if (!codes || !cent) {
        free(codes);
        free(cent);
        free(x.edge_ids);
        free(x.codes);
        vv_mesh_free(m);
        return vv_error_set(VV_ERR_NOMEM, "coarse surface: out of memory");
    }
    size_t q = 0;
    for (size_t i = 0; i < nv; i++) {
        codes[i / 4] |= (uint8_t)((x.codes[i] & 3) << (2 * (i % 4)));
        if (x.edge_ids[i] == UINT32_MAX)
            memcpy(cent + 3 * q++, m->positions + 3 * i, 3 * sizeof(float));
    }
    free(x.codes);
    free(c->edges);
    free(c->codes);
    free(c->triangles);
    free(c->centres);
    c->edges = x.edge_ids;
    c->codes = codes;
    c->centres = cent;
    c->n_centres = ncent;
    c->n_vertices = nv;
    c->n_triangles = m->n_triangles;
    c->triangles = m->triangles; /* taken over from the mesh */
    m->triangles = NULL;
    vv_mesh_free(m);
    c->isovalue = isovalue;
    return VV_OK;
}

vv_status
vv_coarse_mesh(const vv_coarse_surface *c, vv_mesh **out) {
    if (!c || !out)
        return vv_error_set(VV_ERR_INVALID, "coarse surface: NULL argument");
    *out = NULL;
    vv_mesh *m = NULL;
    vv_status s;
    if ((s = vv_mesh_new(&m)) != VV_OK)
        return s;
    if ((s = vv_mesh_reserve(m, c->n_vertices + 1, c->n_triangles + 1)) != VV_OK ||
        (s = vv_mesh_enable_attributes(m, 1, 0)) != VV_OK) {
        vv_mesh_free(m);
        return s;
    }
    const vv_volume *r = c->reduced;
    const vv_mat4 M = vv_volume_index_to_world(r);
    const size_t sy = (size_t)r->dims[0], sz = sy * (size_t)r->dims[1];
    size_t q = 0;
    for (size_t i = 0; i < c->n_vertices; i++) {
        vv_vec3 p;
        if (c->edges[i] == UINT32_MAX) {
            const float *f = c->centres + 3 * q++;
            p = vv_vec3_make(f[0], f[1], f[2]);
        } else {
            size_t vox = c->edges[i] / 3;
            int axis = (int)(c->edges[i] % 3);
            double x[3] = {(double)(vox % sy), (double)(vox % sz / sy), (double)(vox / sz)};
            x[axis] += (((c->codes[i / 4] >> (2 * (i % 4))) & 3) + 0.5) * 0.25;
            p = vv_mat4_mul_point(M, vv_vec3_make(x[0], x[1], x[2]));
        }
        m->positions[3 * i] = (float)p.x;
        m->positions[3 * i + 1] = (float)p.y;
        m->positions[3 * i + 2] = (float)p.z;
        vv_vec3 g;
        vv_volume_gradient_world(r, p, &g);
        g = vv_vec3_normalize(vv_vec3_scale(g, -1));
        m->normals[3 * i] = (float)g.x;
        m->normals[3 * i + 1] = (float)g.y;
        m->normals[3 * i + 2] = (float)g.z;
    }
    m->n_vertices = c->n_vertices;
    memcpy(m->triangles, c->triangles, 3 * c->n_triangles * sizeof(uint32_t));
    m->n_triangles = c->n_triangles;
    *out = m;
    return VV_OK;
}

size_t
vv_coarse_bytes(const vv_coarse_surface *c) {
    if (!c)
        return 0;
    return c->n_vertices * sizeof(uint32_t) + (c->n_vertices + 3) / 4 +
           c->n_triangles * 3 * sizeof(uint32_t) + c->n_centres * 3 * sizeof(float);
}

void
vv_coarse_free(vv_coarse_surface *c) {
    if (!c)
        return;
    free(c->edges);
    free(c->codes);
    free(c->triangles);
    free(c->centres);
    vv_volume_free(c->reduced);
    free(c);
}
