/*
 * One bounding volume hierarchy for every search over many primitives (not
 * installed): the ray tracer's meshes (src/render/raytrace), the boundary
 * faces of the irregular-grid renderer (src/render/irregular) and the
 * triangle pairs of mesh measurement (src/measure/mesh_measure.c).
 *
 * The hierarchy knows boxes only. A user hands it one box per item (a
 * triangle, a tetrahedron face, ...) and, in the spirit of Embree's user
 * geometry, tests its own items in a leaf callback: vv_bvh_ray walks the
 * boxes a ray crosses, nearest child first, and vv_bvh_query the boxes a
 * user's predicate accepts (a distance bound, an overlap).
 *
 * Build: each node splits its items at the middle of their centroids' box
 * along its longest axis (the spatial median: splits follow the shapes, so
 * a ray visits fewer boxes than behind object medians), and at the median
 * centroid (quickselect; Kay and Kajiya's object median, SIGGRAPH 1986)
 * where the middle leaves one side empty or below depth
 * VV_BVH_SPATIAL_DEPTH. Medians halve, so the depth stays below
 * VV_BVH_SPATIAL_DEPTH + 31 and a traversal stack of VV_BVH_STACK entries
 * is never exceeded. Leaves hold at most VV_BVH_LEAF items. Deterministic:
 * the same boxes in the same order give the same tree.
 *
 * Layout: nodes[0] is the root; an inner node's children are nodes[left]
 * and nodes[left + 1], the first holding the lower centroids along `axis`;
 * a leaf's items are items[left .. left + count).
 *
 * Ownership: vv_bvh_build fills a caller's struct; vv_bvh_clear frees it.
 * Thread-safety: a built hierarchy is read-only; any number of threads may
 * traverse it at once.
 */
#ifndef VOLVIS_CORE_BVH_H
#define VOLVIS_CORE_BVH_H

#include <stddef.h>
#include <stdint.h>

#include "core/geom.h"
#include "volvis/core.h"

/** Most items in a leaf. */
#define VV_BVH_LEAF 4
/** Levels split at the middle before medians take over. */
#define VV_BVH_SPATIAL_DEPTH 48
/** Traversal stack: enough for any tree vv_bvh_build makes (depth < 48 + 31). */
#define VV_BVH_STACK 96

typedef struct vv_bvh_node {
    float lo[3], hi[3]; /**< box of the node's items */
    int32_t left;       /**< inner: first child (the second is left + 1); leaf: first item */
    int32_t count;      /**< leaf: items (>= 1); inner: 0 */
    int32_t axis;       /**< inner: the split axis; leaf: 0 */
} vv_bvh_node;

typedef struct vv_bvh {
    vv_bvh_node *nodes; /**< n_nodes nodes, root first; NULL when empty */
    size_t n_nodes;
    uint32_t *items; /**< item indices in leaf order (n_items) */
    size_t n_items;
} vv_bvh;

/**
 * Builds the hierarchy over @p n items. @p boxes holds 6 floats per item
 * (min x, y, z, max x, y, z), @p centroids 3 per item (the split key; NULL:
 * the boxes' centres). Both are read only during the call. An item's box
 * must contain what its leaf test can hit: a caller with double coordinates
 * rounds the box outwards (nextafterf). n = 0 gives an empty hierarchy that
 * every traversal leaves at once. Errors: VV_ERR_LIMIT (n over 2^31 - 1),
 * VV_ERR_NOMEM; @p bvh is then empty.
 */
vv_status vv_bvh_build(vv_bvh *bvh, size_t n, const float *boxes, const float *centroids);

/**
 * Builds the hierarchy over the triangles of an indexed mesh: item t is
 * triangle t with corners positions[3 * tri[3t + k]] (float x, y, z), its box
 * exact and its centroid the corners' mean. Indices are not checked (the
 * caller's mesh is valid). Errors as vv_bvh_build.
 */
vv_status vv_bvh_build_triangles(vv_bvh *bvh, const float *positions, const uint32_t *tri,
                                 size_t n_tri);

/**
 * Where a leaf's items start in the leaf order: a user that stores its
 * per-item data in leaf order (data[k] for item items[k], after the build)
 * finds a leaf's data at data + vv_bvh_leaf_offset(bvh, items), saving an
 * indirection per item in the leaf test.
 */
static inline size_t
vv_bvh_leaf_offset(const vv_bvh *bvh, const uint32_t *items) {
    return (size_t)(items - bvh->items);
}

/** Frees the hierarchy and empties @p bvh. Accepts an empty or zeroed struct. */
void vv_bvh_clear(vv_bvh *bvh);

/**
 * Leaf test of a ray traversal: tests items[0 .. count) along the ray; where
 * one is hit nearer than *t1, sets *t1 to the hit (later boxes beyond it are
 * skipped). Returns 1 to end the traversal (an occlusion query that found a
 * hit), else 0.
 */
typedef int (*vv_bvh_ray_fn)(void *ctx, const uint32_t *items, int count, double *t1);

/**
 * Walks the boxes the ray o + t d (inv = 1 / d per axis, IEEE infinities
 * for zero components) crosses over [t0, t1], nearer child first, calling
 * @p leaf on each leaf it reaches; t1 shrinks as the leaf test reports
 * hits. Returns 1 when a leaf test ended the walk, else 0. Boxes are tested
 * with vv_slab_inv (a box touching the interval's end is still visited, so
 * a leaf test may resolve ties by its own rule). Inline, so a constant
 * @p leaf is inlined too.
 */
static inline int
vv_bvh_ray(const vv_bvh *bvh, const double o[3], const double inv[3], double t0, double t1,
           vv_bvh_ray_fn leaf, void *ctx) {
    if (!bvh->n_nodes)
        return 0;
    int32_t stack[VV_BVH_STACK];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const vv_bvh_node *n = &bvh->nodes[stack[--sp]];
        double a = t0, b = t1;
        if (!vv_slab_inv_f(n->lo, n->hi, o, inv, &a, &b))
            continue;
        if (n->count) {
            if (leaf(ctx, bvh->items + n->left, n->count, &t1))
                return 1;
            continue;
        }
        /* the far child below the near one, so the near one is taken first
         * and its hits shrink the search */
        const int near = inv[n->axis] < 0;
        stack[sp++] = n->left + 1 - near;
        stack[sp++] = n->left + near;
    }
    return 0;
}

/** Box predicate of a query: 1 to visit the node with box [lo, hi] (its subtree). */
typedef int (*vv_bvh_box_fn)(void *ctx, const float lo[3], const float hi[3]);
/** Leaf visit of a query: items[0 .. count). Returns 1 to end the query. */
typedef int (*vv_bvh_leaf_fn)(void *ctx, const uint32_t *items, int count);

/**
 * Depth-first walk of the nodes whose boxes @p box accepts (the predicate
 * may depend on what earlier leaves found: a shrinking distance bound),
 * first child first, calling @p leaf on the accepted leaves. Returns 1 when
 * a leaf ended the query, else 0. Inline, as vv_bvh_ray.
 */
static inline int
vv_bvh_query(const vv_bvh *bvh, vv_bvh_box_fn box, vv_bvh_leaf_fn leaf, void *ctx) {
    if (!bvh->n_nodes)
        return 0;
    int32_t stack[VV_BVH_STACK];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const vv_bvh_node *n = &bvh->nodes[stack[--sp]];
        if (!box(ctx, n->lo, n->hi))
            continue;
        if (n->count) {
            if (leaf(ctx, bvh->items + n->left, n->count))
                return 1;
            continue;
        }
        stack[sp++] = n->left + 1;
        stack[sp++] = n->left;
    }
    return 0;
}

#endif
