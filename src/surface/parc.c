/*
 * PARC subvolumes (VolVis paper, section on the Navigator): the boxes of a
 * uniform subdivision that contain part of an isosurface, kept as a sorted
 * list of box indices, and their outer faces as a preview mesh. The min/max
 * of every box is computed once (vv_minmax_grid_build); a new isovalue only
 * scans those numbers, so the list follows an isovalue slider.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "surface_internal.h"

vv_status
vv_parc_new(vv_parc **out, const vv_volume *v, int level) {
    if (!out || !v)
        return vv_error_set(VV_ERR_INVALID, "parc: NULL argument");
    *out = NULL;
    if (level < 0 || level > 16)
        return vv_error_set(VV_ERR_INVALID, "parc: level %d outside 0..16", level);
    int longest = 1;
    for (int a = 0; a < 3; a++)
        longest = v->dims[a] - 1 > longest ? v->dims[a] - 1 : longest;
    int parts = 1 << level;
    int block = (longest + parts - 1) / parts;
    if (block < 1)
        block = 1;
    vv_parc *p = calloc(1, sizeof *p);
    if (!p)
        return vv_error_set(VV_ERR_NOMEM, "parc: out of memory");
    p->level = level;
    p->block = block;
    p->isovalue = NAN;
    vv_status s = vv_minmax_grid_build(&p->grid, v, block);
    if (s != VV_OK) {
        free(p);
        return vv_error_prefix(s, "parc");
    }
    uint64_t n =
        (uint64_t)p->grid->dims[0] * (uint64_t)p->grid->dims[1] * (uint64_t)p->grid->dims[2];
    if (n > UINT32_MAX) {
        vv_parc_free(p);
        return vv_error_set(VV_ERR_LIMIT, "parc: %llu boxes at level %d (at most 2^32)",
                            (unsigned long long)n, level);
    }
    memcpy(p->dims, p->grid->dims, sizeof p->dims);
    memcpy(p->volume_dims, v->dims, sizeof p->volume_dims);
    p->index_to_world = vv_volume_index_to_world(v);
    p->boxes = malloc((size_t)n * sizeof *p->boxes);
    p->kept = calloc((size_t)n, 1);
    if (!p->boxes || !p->kept) {
        vv_parc_free(p);
        return vv_error_set(VV_ERR_NOMEM, "parc: out of memory for %llu boxes",
                            (unsigned long long)n);
    }
    *out = p;
    return VV_OK;
}

vv_status
vv_parc_set_isovalue(vv_parc *p, double isovalue) {
    if (!p)
        return vv_error_set(VV_ERR_INVALID, "parc: NULL argument");
    if (!isfinite(isovalue))
        return vv_error_set(VV_ERR_INVALID, "parc: isovalue %g is not finite", isovalue);
    const size_t n = (size_t)p->dims[0] * (size_t)p->dims[1] * (size_t)p->dims[2];
    size_t k = 0;
    const float *mn = p->grid->min, *mx = p->grid->max;
    for (size_t b = 0; b < n; b++) {
        /* some voxel >= isovalue and some below it: an edge of a cell crosses */
        uint8_t keep = (double)mx[b] >= isovalue && (double)mn[b] < isovalue;
        p->kept[b] = keep;
        if (keep)
            p->boxes[k++] = (uint32_t)b;
    }
    p->n_boxes = k;
    p->isovalue = isovalue;
    return VV_OK;
}

int
vv_parc_box_kept(const vv_parc *p, int bi, int bj, int bk) {
    if (!p || bi < 0 || bj < 0 || bk < 0 || bi >= p->dims[0] || bj >= p->dims[1] ||
        bk >= p->dims[2])
        return 0;
    return p
        ->kept[((size_t)bk * (size_t)p->dims[1] + (size_t)bj) * (size_t)p->dims[0] + (size_t)bi];
}

/* Open-addressing map from a box-corner lattice index to a mesh vertex. */
typedef struct corner_map {
    size_t cap;
    uint64_t *key;
    uint32_t *val;
} corner_map;

static vv_status
corner_vertex(const vv_parc *p, corner_map *cm, vv_mesh *m, const int c[3], uint32_t *out) {
    const uint64_t key = ((uint64_t)c[2] * (uint64_t)(p->dims[1] + 1) + (uint64_t)c[1]) *
                             (uint64_t)(p->dims[0] + 1) +
                         (uint64_t)c[0];
    uint64_t h = key * 0x9E3779B97F4A7C15ULL;
    size_t i = (size_t)(h >> 20) & (cm->cap - 1);
    while (cm->key[i] != UINT64_MAX && cm->key[i] != key)
        i = (i + 1) & (cm->cap - 1);
    if (cm->key[i] == key) {
        *out = cm->val[i];
        return VV_OK;
    }
    double x[3];
    for (int a = 0; a < 3; a++) {
        long q = (long)c[a] * p->block;
        x[a] = (double)(q > p->volume_dims[a] - 1 ? p->volume_dims[a] - 1 : q);
    }
    vv_status s = vv_mesh_add_vertex(
        m, vv_mat4_mul_point(p->index_to_world, vv_vec3_make(x[0], x[1], x[2])), out);
    if (s != VV_OK)
        return s;
    cm->key[i] = key;
    cm->val[i] = *out;
    return VV_OK;
}

vv_status
vv_parc_mesh(const vv_parc *p, vv_mesh **out) {
    if (!p || !out)
        return vv_error_set(VV_ERR_INVALID, "parc: NULL argument");
    *out = NULL;
    /* count the outer faces first */
    size_t faces = 0;
    for (size_t q = 0; q < p->n_boxes; q++) {
        size_t b = p->boxes[q];
        int bi = (int)(b % (size_t)p->dims[0]), bj = (int)(b / (size_t)p->dims[0] % p->dims[1]),
            bk = (int)(b / ((size_t)p->dims[0] * (size_t)p->dims[1]));
        faces += !vv_parc_box_kept(p, bi - 1, bj, bk) + !vv_parc_box_kept(p, bi + 1, bj, bk) +
                 !vv_parc_box_kept(p, bi, bj - 1, bk) + !vv_parc_box_kept(p, bi, bj + 1, bk) +
                 !vv_parc_box_kept(p, bi, bj, bk - 1) + !vv_parc_box_kept(p, bi, bj, bk + 1);
    }
    vv_mesh *m = NULL;
    vv_status s;
    corner_map cm = {64, NULL, NULL};
    while (cm.cap < 8 * faces)
        cm.cap *= 2;
    if ((s = vv_mesh_new(&m)) != VV_OK)
        return s;
    if ((s = vv_mesh_reserve(m, 4 * faces + 1, 2 * faces + 1)) != VV_OK)
        goto fail;
    cm.key = malloc(cm.cap * sizeof *cm.key);
    cm.val = malloc(cm.cap * sizeof *cm.val);
    if (!cm.key || !cm.val) {
        s = vv_error_set(VV_ERR_NOMEM, "parc: out of memory");
        goto fail;
    }
    memset(cm.key, 0xff, cm.cap * sizeof *cm.key);
    /* a reflecting index-to-world map reverses the winding */
    const vv_mat4 M = p->index_to_world;
    double det = M.m[0][0] * (M.m[1][1] * M.m[2][2] - M.m[1][2] * M.m[2][1]) -
                 M.m[0][1] * (M.m[1][0] * M.m[2][2] - M.m[1][2] * M.m[2][0]) +
                 M.m[0][2] * (M.m[1][0] * M.m[2][1] - M.m[1][1] * M.m[2][0]);
    for (size_t q = 0; q < p->n_boxes; q++) {
        size_t b = p->boxes[q];
        int B[3] = {(int)(b % (size_t)p->dims[0]), (int)(b / (size_t)p->dims[0] % p->dims[1]),
                    (int)(b / ((size_t)p->dims[0] * (size_t)p->dims[1]))};
        for (int a = 0; a < 3; a++)
            for (int side = 0; side < 2; side++) {
                int nb[3] = {B[0], B[1], B[2]};
                nb[a] += side ? 1 : -1;
                if (vv_parc_box_kept(p, nb[0], nb[1], nb[2]))
                    continue;
                const int u = (a + 1) % 3, w = (a + 2) % 3;
                /* corners (u0,w0) (u1,w0) (u1,w1) (u0,w1): counter-clockwise around +a */
                const int du[4] = {0, 1, 1, 0}, dw[4] = {0, 0, 1, 1};
                uint32_t id[4];
                for (int c = 0; c < 4; c++) {
                    int C[3];
                    C[a] = B[a] + side;
                    C[u] = B[u] + du[c];
                    C[w] = B[w] + dw[c];
                    if ((s = corner_vertex(p, &cm, m, C, &id[c])) != VV_OK)
                        goto fail;
                }
                int flip = (side == 0) != (det < 0);
                if (flip) {
                    uint32_t t0 = id[1];
                    id[1] = id[3];
                    id[3] = t0;
                }
                if ((s = vv_mesh_add_triangle(m, id[0], id[1], id[2])) != VV_OK ||
                    (s = vv_mesh_add_triangle(m, id[0], id[2], id[3])) != VV_OK)
                    goto fail;
            }
    }
    free(cm.key);
    free(cm.val);
    *out = m;
    return VV_OK;
fail:
    free(cm.key);
    free(cm.val);
    vv_mesh_free(m);
    return s;
}

void
vv_parc_free(vv_parc *p) {
    if (!p)
        return;
    vv_minmax_grid_free(p->grid);
    free(p->boxes);
    free(p->kept);
    free(p);
}
