/* The bounding volume hierarchy: middle splits, medians where they fail (see core/bvh.h). */
#include "core/bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct bvh_build {
    const float *box; /* 6 per item */
    const float *cen; /* 3 per item */
    uint32_t *items;
    vv_bvh_node *nodes;
    size_t n_nodes;
} bvh_build;

static inline float
key(const bvh_build *b, uint32_t item, int axis) {
    return b->cen[3 * (size_t)item + (size_t)axis];
}

/* Reorders items[lo .. hi] so that items[mid] has the key it would have in
 * sorted order, lower keys before it and higher after (Hoare's selection). */
static void
select_median(bvh_build *b, int64_t lo, int64_t hi, int64_t mid, int axis) {
    uint32_t *it = b->items;
    while (lo < hi) {
        const float pv = key(b, it[lo + (hi - lo) / 2], axis);
        int64_t i = lo, j = hi;
        while (i <= j) {
            while (key(b, it[i], axis) < pv)
                i++;
            while (key(b, it[j], axis) > pv)
                j--;
            if (i <= j) {
                const uint32_t x = it[i];
                it[i] = it[j];
                it[j] = x;
                i++;
                j--;
            }
        }
        if (mid <= j)
            hi = j;
        else if (mid >= i)
            lo = i;
        else
            break;
    }
}

/* Splits items[first .. first + count) at the middle of their centroids'
 * box along @p axis (a spatial split: it follows the shapes, and the
 * traversals of the ray tracers visit fewer boxes than behind a median
 * split); returns the first item of the upper side. */
static size_t
split_middle(bvh_build *b, size_t first, size_t count, int axis, float lo, float hi) {
    const float m = 0.5f * (lo + hi);
    size_t i = first, j = first + count;
    while (i < j) {
        if (key(b, b->items[i], axis) < m) {
            i++;
        } else {
            j--;
            const uint32_t t = b->items[i];
            b->items[i] = b->items[j];
            b->items[j] = t;
        }
    }
    return i;
}

static void
split(bvh_build *b, size_t node, size_t first, size_t count, int depth) {
    vv_bvh_node *n = &b->nodes[node];
    float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int a = 0; a < 3; a++) {
        n->lo[a] = INFINITY;
        n->hi[a] = -INFINITY;
    }
    for (size_t i = first; i < first + count; i++) {
        const float *bx = b->box + 6 * (size_t)b->items[i];
        const float *c = b->cen + 3 * (size_t)b->items[i];
        for (int a = 0; a < 3; a++) {
            n->lo[a] = bx[a] < n->lo[a] ? bx[a] : n->lo[a];
            n->hi[a] = bx[3 + a] > n->hi[a] ? bx[3 + a] : n->hi[a];
            clo[a] = c[a] < clo[a] ? c[a] : clo[a];
            chi[a] = c[a] > chi[a] ? c[a] : chi[a];
        }
    }
    if (count <= VV_BVH_LEAF) {
        n->left = (int32_t)first;
        n->count = (int32_t)count;
        n->axis = 0;
        return;
    }
    int axis = 0;
    for (int a = 1; a < 3; a++)
        if (chi[a] - clo[a] > chi[axis] - clo[axis])
            axis = a;
    size_t mid = depth < VV_BVH_SPATIAL_DEPTH
                     ? split_middle(b, first, count, axis, clo[axis], chi[axis])
                     : first;
    if (mid == first || mid == first + count) {
        /* all on one side (or too deep): the median, which halves */
        mid = first + count / 2;
        select_median(b, (int64_t)first, (int64_t)(first + count - 1), (int64_t)mid, axis);
    }
    const size_t left = b->n_nodes;
    b->n_nodes += 2;
    n->left = (int32_t)left;
    n->count = 0;
    n->axis = axis;
    /* depth below VV_BVH_SPATIAL_DEPTH + 31 (medians halve): recursion is bounded */
    split(b, left, first, mid - first, depth + 1);
    split(b, left + 1, mid, first + count - mid, depth + 1);
}

vv_status
vv_bvh_build(vv_bvh *bvh, size_t n, const float *boxes, const float *centroids) {
    memset(bvh, 0, sizeof *bvh);
    if (n == 0)
        return VV_OK;
    if (n > (size_t)INT32_MAX / 2)
        return vv_error_set(VV_ERR_LIMIT, "bounding volume hierarchy: %zu items (at most %d)", n,
                            INT32_MAX / 2);
    float *cen = NULL;
    if (!centroids) {
        cen = malloc(3 * n * sizeof *cen);
        if (!cen)
            return vv_error_set(VV_ERR_NOMEM, "bounding volume hierarchy: out of memory");
        for (size_t i = 0; i < n; i++)
            for (int a = 0; a < 3; a++)
                cen[3 * i + (size_t)a] =
                    0.5f * boxes[6 * i + (size_t)a] + 0.5f * boxes[6 * i + 3 + (size_t)a];
        centroids = cen;
    }
    bvh->items = malloc(n * sizeof *bvh->items);
    bvh->nodes = malloc(2 * n * sizeof *bvh->nodes);
    if (!bvh->items || !bvh->nodes) {
        free(cen);
        vv_bvh_clear(bvh);
        return vv_error_set(VV_ERR_NOMEM, "bounding volume hierarchy: out of memory for %zu items",
                            n);
    }
    for (size_t i = 0; i < n; i++)
        bvh->items[i] = (uint32_t)i;
    bvh_build b = {boxes, centroids, bvh->items, bvh->nodes, 1};
    split(&b, 0, 0, n, 0);
    bvh->n_nodes = b.n_nodes;
    bvh->n_items = n;
    free(cen);
    return VV_OK;
}

vv_status
vv_bvh_build_triangles(vv_bvh *bvh, const float *positions, const uint32_t *tri, size_t n_tri) {
    memset(bvh, 0, sizeof *bvh);
    if (n_tri == 0)
        return VV_OK;
    if (n_tri > (size_t)INT32_MAX / 2)
        return vv_error_set(VV_ERR_LIMIT, "bounding volume hierarchy: %zu triangles (at most %d)",
                            n_tri, INT32_MAX / 2);
    float *box = malloc(6 * n_tri * sizeof *box), *cen = malloc(3 * n_tri * sizeof *cen);
    if (!box || !cen) {
        free(box);
        free(cen);
        return vv_error_set(VV_ERR_NOMEM,
                            "bounding volume hierarchy: out of memory for %zu triangles", n_tri);
    }
    for (size_t t = 0; t < n_tri; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++)
            p[k] = positions + 3 * (size_t)tri[3 * t + (size_t)k];
        for (int a = 0; a < 3; a++) {
            const float x = p[0][a], y = p[1][a], z = p[2][a];
            const float lo = x < y ? (x < z ? x : z) : (y < z ? y : z);
            const float hi = x > y ? (x > z ? x : z) : (y > z ? y : z);
            box[6 * t + (size_t)a] = lo;
            box[6 * t + 3 + (size_t)a] = hi;
            cen[3 * t + (size_t)a] = (float)(((double)x + y + z) / 3);
        }
    }
    vv_status s = vv_bvh_build(bvh, n_tri, box, cen);
    free(box);
    free(cen);
    return s;
}

void
vv_bvh_clear(vv_bvh *bvh) {
    if (!bvh)
        return;
    free(bvh->nodes);
    free(bvh->items);
    memset(bvh, 0, sizeof *bvh);
}
