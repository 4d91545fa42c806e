/*
 * Exact clipping of an indexed triangle mesh by a plane (cut planes of
 * vv_isosurface_extract). Each mesh edge that crosses the plane gets one new
 * vertex, found again through a hash of the edge, so the two triangles of
 * the edge share it and the clipped mesh has no cracks.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "surface_internal.h"

typedef struct edge_map {
    size_t cap; /* power of two */
    uint64_t *key;
    uint32_t *value;
} edge_map;

static size_t
hash64(uint64_t k) {
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    return (size_t)k;
}

vv_status
vv_mesh_clip_plane(vv_mesh *m, vv_vec3 n, double d) {
    const size_t nv = m->n_vertices, nt = m->n_triangles;
    double *dist = malloc((nv ? nv : 1) * sizeof(double));
    uint32_t *tris = malloc((nt ? 2 * nt : 1) * 3 * sizeof(uint32_t));
    size_t ncut = 0;
    edge_map map = {0, NULL, NULL};
    if (!dist || !tris)
        goto nomem;
    for (size_t i = 0; i < nv; i++) {
        const float *p = m->positions + 3 * i;
        dist[i] = n.x * p[0] + n.y * p[1] + n.z * p[2] + d;
    }
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *tr = m->triangles + 3 * t;
        int in = (dist[tr[0]] >= 0) + (dist[tr[1]] >= 0) + (dist[tr[2]] >= 0);
        ncut += in == 1 || in == 2;
    }
    map.cap = 64;
    while (map.cap < 4 * ncut)
        map.cap *= 2;
    map.key = malloc(map.cap * sizeof(uint64_t));
    map.value = malloc(map.cap * sizeof(uint32_t));
    if (!map.key || !map.value)
        goto nomem;
    memset(map.key, 0xff, map.cap * sizeof(uint64_t));
    vv_status s;
    size_t out = 0;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *tr = m->triangles + 3 * t;
        int in[3];
        for (int c = 0; c < 3; c++)
            in[c] = dist[tr[c]] >= 0;
        if (in[0] && in[1] && in[2]) {
            memcpy(tris + 3 * out++, tr, 3 * sizeof(uint32_t));
            continue;
        }
        if (!in[0] && !in[1] && !in[2])
            continue;
        uint32_t poly[4];
        int np = 0;
        for (int c = 0; c < 3; c++) {
            uint32_t a = tr[c], b = tr[(c + 1) % 3];
            if (in[c])
                poly[np++] = a;
            if (in[c] == in[(c + 1) % 3])
                continue;
            /* the crossing of edge (a, b); a vertex exactly on the plane is the crossing */
            uint32_t hitv;
            if (in[c] && dist[a] == 0) {
                continue;
            } else if (!in[c] && dist[b] == 0) {
                continue;
            }
            uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
            uint64_t key = ((uint64_t)lo << 32) | hi;
            size_t h = hash64(key) & (map.cap - 1);
            while (map.key[h] != key && map.key[h] != UINT64_MAX)
                h = (h + 1) & (map.cap - 1);
            if (map.key[h] == key) {
                hitv = map.value[h];
            } else {
                double tt = dist[lo] / (dist[lo] - dist[hi]);
                vv_vec3 pl = vv_mesh_vertex(m, lo), ph = vv_mesh_vertex(m, hi);
                float nl[3] = {0, 0, 0}, nh[3] = {0, 0, 0}, sl = 0, sh = 0;
                if (m->normals) {
                    memcpy(nl, m->normals + 3 * lo, sizeof nl);
                    memcpy(nh, m->normals + 3 * hi, sizeof nh);
                }
                if (m->scalars) {
                    sl = m->scalars[lo];
                    sh = m->scalars[hi];
                }
                if ((s = vv_mesh_add_vertex(m, vv_vec3_lerp(pl, ph, tt), &hitv)) != VV_OK)
                    goto fail;
                if (m->normals) {
                    double q[3], l = 0;
                    for (int k = 0; k < 3; k++) {
                        q[k] = nl[k] + tt * (nh[k] - nl[k]);
                        l += q[k] * q[k];
                    }
                    l = l > 0 ? 1.0 / sqrt(l) : 0;
                    for (int k = 0; k < 3; k++)
                        m->normals[3 * hitv + k] = (float)(q[k] * l);
                }
                if (m->scalars)
                    m->scalars[hitv] = (float)(sl + tt * (sh - sl));
                map.key[h] = key;
                map.value[h] = hitv;
            }
            poly[np++] = hitv;
        }
        for (int k = 1; k + 1 < np; k++) {
            uint32_t *o = tris + 3 * out++;
            o[0] = poly[0];
            o[1] = poly[k];
            o[2] = poly[k + 1];
        }
    }
    /* drop unused vertices */
    {
        size_t nv2 = m->n_vertices;
        uint32_t *remap = malloc((nv2 ? nv2 : 1) * sizeof(uint32_t));
        if (!remap)
            goto nomem;
        for (size_t i = 0; i < nv2; i++)
            remap[i] = UINT32_MAX;
        for (size_t i = 0; i < 3 * out; i++)
            remap[tris[i]] = 0;
        uint32_t k = 0;
        for (size_t i = 0; i < nv2; i++)
            if (remap[i] == 0) {
                remap[i] = k;
                if (k != i) {
                    memcpy(m->positions + 3 * k, m->positions + 3 * i, 3 * sizeof(float));
                    if (m->normals)
                        memcpy(m->normals + 3 * k, m->normals + 3 * i, 3 * sizeof(float));
                    if (m->scalars)
                        m->scalars[k] = m->scalars[i];
                }
                k++;
            }
        for (size_t i = 0; i < 3 * out; i++)
            tris[i] = remap[tris[i]];
        free(remap);
        m->n_vertices = k;
    }
    if ((s = vv_mesh_reserve(m, m->n_vertices, out)) != VV_OK)
        goto fail;
    memcpy(m->triangles, tris, 3 * out * sizeof(uint32_t));
    m->n_triangles = out;
    free(dist);
    free(tris);
    free(map.key);
    free(map.value);
    return VV_OK;
nomem:
    s = vv_error_set(VV_ERR_NOMEM, "mesh clip: out of memory");
fail:
    free(dist);
    free(tris);
    free(map.key);
    free(map.value);
    return s;
}
