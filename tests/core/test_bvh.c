/*
 * core/bvh.c: the hierarchy's structure (every item once, boxes nested,
 * the depth bound) and its two traversals against brute force over all
 * items: nearest ray hits on random triangles, the set of boxes a ray
 * crosses, the nearest box to a point.
 */
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/bvh.h"

static int last_depth; /* of the last tree check_tree walked */

/* Walks the tree: every item in exactly one leaf, each node's box holding
 * its children's and its items' boxes; returns the depth. */
static int
check_node(const vv_bvh *b, const float *boxes, int32_t id, int *seen) {
    const vv_bvh_node *n = &b->nodes[id];
    if (n->count) {
        assert_true(n->count <= VV_BVH_LEAF);
        for (int i = 0; i < n->count; i++) {
            const uint32_t it = b->items[n->left + i];
            assert_true(it < b->n_items);
            seen[it]++;
            for (int a = 0; a < 3; a++) {
                assert_true(n->lo[a] <= boxes[6 * it + a]);
                assert_true(n->hi[a] >= boxes[6 * it + 3 + a]);
            }
        }
        return 1;
    }
    assert_true(n->left > id && (size_t)n->left + 1 < b->n_nodes);
    int d = 0;
    for (int c = 0; c < 2; c++) {
        const vv_bvh_node *ch = &b->nodes[n->left + c];
        for (int a = 0; a < 3; a++) {
            assert_true(n->lo[a] <= ch->lo[a]);
            assert_true(n->hi[a] >= ch->hi[a]);
        }
        const int dc = check_node(b, boxes, n->left + c, seen);
        d = dc > d ? dc : d;
    }
    return d + 1;
}

static void
check_tree(const vv_bvh *b, const float *boxes, size_t n) {
    int *seen = calloc(n ? n : 1, sizeof *seen);
    assert_non_null(seen);
    const int depth = n ? check_node(b, boxes, 0, seen) : 0;
    for (size_t i = 0; i < n; i++)
        assert_int_equal(seen[i], 1);
    free(seen);
    /* within the traversal stack */
    assert_true(depth < VV_BVH_STACK);
    assert_true(b->n_nodes <= (n ? 2 * n - 1 : 0));
    last_depth = depth;
}

static void
random_triangles(uint64_t *seed, size_t n, float *pos, uint32_t *tri) {
    for (size_t t = 0; t < n; t++) {
        /* small triangles scattered in [-1, 1]^3 */
        const double cx = vt_rnd(seed, -1, 1), cy = vt_rnd(seed, -1, 1), cz = vt_rnd(seed, -1, 1);
        for (int k = 0; k < 3; k++) {
            pos[9 * t + 3 * k] = (float)(cx + vt_rnd(seed, -0.08, 0.08));
            pos[9 * t + 3 * k + 1] = (float)(cy + vt_rnd(seed, -0.08, 0.08));
            pos[9 * t + 3 * k + 2] = (float)(cz + vt_rnd(seed, -0.08, 0.08));
            tri[3 * t + k] = (uint32_t)(3 * t + k);
        }
    }
}

typedef struct tri_ctx {
    const float *pos;
    const uint32_t *tri;
    vv_vec3 o, d;
    double t;
    uint32_t best;
    int leaves;
} tri_ctx;

static int
hit_triangle(const tri_ctx *c, uint32_t t, double *th) {
    const float *p0 = c->pos + 3 * c->tri[3 * t], *p1 = c->pos + 3 * c->tri[3 * t + 1],
                *p2 = c->pos + 3 * c->tri[3 * t + 2];
    double u, v;
    return vv_ray_triangle3(c->o, c->d, vv_v3_f(p0), vv_v3_f(p1), vv_v3_f(p2), th, &u, &v) &&
           *th > 0;
}

/* Nearest hit; of equal t the lowest triangle, so the answer does not depend
 * on the order of the walk. */
static int
leaf_nearest(void *ctx, const uint32_t *items, int count, double *t1) {
    tri_ctx *c = ctx;
    c->leaves++;
    for (int i = 0; i < count; i++) {
        double t;
        if (hit_triangle(c, items[i], &t) &&
            (t < *t1 || (t == *t1 && c->best != UINT32_MAX && items[i] < c->best))) {
            *t1 = c->t = t;
            c->best = items[i];
        }
    }
    return 0;
}

static void
test_ray_vs_brute_force(void **state) {
    (void)state;
    const size_t n = 3000;
    float *pos = malloc(9 * n * sizeof *pos), *box = malloc(6 * n * sizeof *box);
    uint32_t *tri = malloc(3 * n * sizeof *tri);
    assert_true(pos && box && tri);
    uint64_t seed = 42;
    random_triangles(&seed, n, pos, tri);
    vv_bvh b;
    vt_ok(vv_bvh_build_triangles(&b, pos, tri, n));
    for (size_t t = 0; t < n; t++)
        for (int a = 0; a < 3; a++) {
            box[6 * t + a] = fminf(pos[9 * t + a], fminf(pos[9 * t + 3 + a], pos[9 * t + 6 + a]));
            box[6 * t + 3 + a] =
                fmaxf(pos[9 * t + a], fmaxf(pos[9 * t + 3 + a], pos[9 * t + 6 + a]));
        }
    check_tree(&b, box, n);
    int hits = 0;
    long leaves = 0;
    for (int r = 0; r < 4000; r++) {
        tri_ctx c = {pos, tri, {0, 0, 0}, {0, 0, 0}, INFINITY, UINT32_MAX, 0};
        c.o = vv_v3(vt_rnd(&seed, -3, 3), vt_rnd(&seed, -3, 3), vt_rnd(&seed, -3, 3));
        c.d =
            vv_v3_sub(vv_v3(vt_rnd(&seed, -1, 1), vt_rnd(&seed, -1, 1), vt_rnd(&seed, -1, 1)), c.o);
        if (r % 10 == 0)
            c.d.z = 0; /* axis-parallel components: infinite reciprocals */
        const double o[3] = {c.o.x, c.o.y, c.o.z}, inv[3] = {1 / c.d.x, 1 / c.d.y, 1 / c.d.z};
        vv_bvh_ray(&b, o, inv, 0, INFINITY, leaf_nearest, &c);
        /* brute force */
        double bt = INFINITY;
        uint32_t bb = UINT32_MAX;
        for (uint32_t t = 0; t < n; t++) {
            double th;
            if (hit_triangle(&c, t, &th) && (th < bt || (th == bt && t < bb))) {
                bt = th;
                bb = t;
            }
        }
        assert_int_equal(c.best, bb);
        if (bb != UINT32_MAX) {
            assert_true(c.t == bt);
            hits++;
        }
        leaves += c.leaves;
    }
    assert_true(hits > 500);
    /* the hierarchy prunes: far fewer leaves than items per ray */
    assert_true(leaves / 4000 < (long)n / VV_BVH_LEAF / 10);
    vv_bvh_clear(&b);
    free(pos);
    free(box);
    free(tri);
}

typedef struct box_ctx {
    const float *box;
    const double *o, *inv;
    uint8_t *hit;
} box_ctx;

/* Collects every item whose own box the ray crosses (no shrinking). */
static int
leaf_boxes(void *ctx, const uint32_t *items, int count, double *t1) {
    box_ctx *c = ctx;
    (void)t1;
    for (int i = 0; i < count; i++) {
        double a = 0, b = INFINITY;
        if (vv_slab_inv_f(c->box + 6 * items[i], c->box + 6 * items[i] + 3, c->o, c->inv, &a, &b))
            c->hit[items[i]] = 1;
    }
    return 0;
}

static void
test_boxes_vs_brute_force(void **state) {
    (void)state;
    const size_t n = 2000;
    float *box = malloc(6 * n * sizeof *box);
    uint8_t *hit = malloc(n);
    assert_true(box && hit);
    uint64_t seed = 9;
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            const double c = vt_rnd(&seed, -1, 1), h = vt_rnd(&seed, 0, 0.05);
            box[6 * i + a] = (float)(c - h);
            box[6 * i + 3 + a] = (float)(c + h);
        }
    vv_bvh b;
    vt_ok(vv_bvh_build(&b, n, box, NULL));
    check_tree(&b, box, n);
    for (int r = 0; r < 500; r++) {
        const double o[3] = {vt_rnd(&seed, -2, 2), vt_rnd(&seed, -2, 2), vt_rnd(&seed, -2, 2)};
        const double d[3] = {vt_rnd(&seed, -1, 1), vt_rnd(&seed, -1, 1),
                             r % 5 ? vt_rnd(&seed, -1, 1) : 0};
        const double inv[3] = {1 / d[0], 1 / d[1], 1 / d[2]};
        memset(hit, 0, n);
        box_ctx c = {box, o, inv, hit};
        vv_bvh_ray(&b, o, inv, 0, INFINITY, leaf_boxes, &c);
        for (size_t i = 0; i < n; i++) {
            double a = 0, bb = INFINITY;
            const int want = vv_slab_inv_f(box + 6 * i, box + 6 * i + 3, o, inv, &a, &bb);
            assert_int_equal(hit[i], want);
        }
    }
    vv_bvh_clear(&b);
    free(box);
    free(hit);
}

typedef struct near_ctx {
    const float *box;
    vv_vec3 p;
    double best;
    uint32_t item;
} near_ctx;

static int
near_box(void *ctx, const float lo[3], const float hi[3]) {
    const near_ctx *c = ctx;
    return vv_box_distance2_f(lo, hi, c->p) <= c->best;
}

static int
near_leaf(void *ctx, const uint32_t *items, int count) {
    near_ctx *c = ctx;
    for (int i = 0; i < count; i++) {
        const double d = vv_box_distance2_f(c->box + 6 * items[i], c->box + 6 * items[i] + 3, c->p);
        if (d < c->best || (d == c->best && items[i] < c->item)) {
            c->best = d;
            c->item = items[i];
        }
    }
    return 0;
}

static void
test_query_vs_brute_force(void **state) {
    (void)state;
    const size_t n = 1500;
    float *box = malloc(6 * n * sizeof *box);
    assert_non_null(box);
    uint64_t seed = 17;
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            const double c = vt_rnd(&seed, -1, 1), h = vt_rnd(&seed, 0, 0.02);
            box[6 * i + a] = (float)(c - h);
            box[6 * i + 3 + a] = (float)(c + h);
        }
    vv_bvh b;
    vt_ok(vv_bvh_build(&b, n, box, NULL));
    for (int q = 0; q < 500; q++) {
        near_ctx c = {
            box,
            vv_v3(vt_rnd(&seed, -1.5, 1.5), vt_rnd(&seed, -1.5, 1.5), vt_rnd(&seed, -1.5, 1.5)),
            INFINITY, UINT32_MAX};
        vv_bvh_query(&b, near_box, near_leaf, &c);
        double best = INFINITY;
        uint32_t item = UINT32_MAX;
        for (uint32_t i = 0; i < n; i++) {
            const double d = vv_box_distance2_f(box + 6 * i, box + 6 * i + 3, c.p);
            if (d < best) {
                best = d;
                item = i;
            }
        }
        assert_true(c.best == best);
        assert_int_equal(c.item, item);
    }
    vv_bvh_clear(&b);
    free(box);
}

/* Degenerate inputs: nothing, one item, all centroids equal (still
 * balanced), and a count over the limit (refused before reading). */
static void
test_degenerate(void **state) {
    (void)state;
    vv_bvh b;
    vt_ok(vv_bvh_build(&b, 0, NULL, NULL));
    assert_int_equal(b.n_nodes, 0);
    const double o0[3] = {0, 0, 0}, inv0[3] = {1, 1, 1};
    assert_int_equal(vv_bvh_ray(&b, o0, inv0, 0, INFINITY, leaf_boxes, NULL), 0);
    vv_bvh_clear(&b);
    const float one[6] = {0, 0, 0, 1, 1, 1};
    vt_ok(vv_bvh_build(&b, 1, one, NULL));
    assert_int_equal(b.n_nodes, 1);
    assert_int_equal(b.nodes[0].count, 1);
    vv_bvh_clear(&b);
    const size_t n = 1000;
    float *box = malloc(6 * n * sizeof *box);
    assert_non_null(box);
    for (size_t i = 0; i < 6 * n; i++)
        box[i] = i % 6 < 3 ? 0.0f : 1.0f;
    vt_ok(vv_bvh_build(&b, n, box, NULL));
    check_tree(&b, box, n);
    /* every centroid at one point: medians, a balanced tree */
    int bound = 1;
    while (((size_t)VV_BVH_LEAF << (bound - 1)) < n)
        bound++;
    assert_true(last_depth <= bound);
    vv_bvh_clear(&b);
    /* centroids spaced geometrically: each middle split peels off one item,
     * so medians take over at VV_BVH_SPATIAL_DEPTH and the depth stays
     * bounded; rays still find every box */
    for (size_t i = 0; i < n; i++) {
        const float x = (float)pow(1.08, (double)i);
        for (int a = 0; a < 3; a++) {
            box[6 * i + a] = a ? 0.0f : x;
            box[6 * i + 3 + a] = a ? 1.0f : x * 1.01f;
        }
    }
    vt_ok(vv_bvh_build(&b, n, box, NULL));
    check_tree(&b, box, n);
    assert_true(last_depth > VV_BVH_SPATIAL_DEPTH / 2 && last_depth < VV_BVH_SPATIAL_DEPTH + 12);
    uint8_t *hit = calloc(n, 1);
    assert_non_null(hit);
    const double o[3] = {0, 0.5, 0.5}, inv[3] = {1, INFINITY, INFINITY};
    box_ctx c = {box, o, inv, hit};
    vv_bvh_ray(&b, o, inv, 0, INFINITY, leaf_boxes, &c);
    for (size_t i = 0; i < n; i++)
        assert_int_equal(hit[i], 1);
    free(hit);
    vv_bvh_clear(&b);
    free(box);
    vt_err(vv_bvh_build(&b, (size_t)1 << 40, NULL, NULL));
    assert_int_equal(b.n_nodes, 0);
    vv_bvh_clear(NULL);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ray_vs_brute_force),
        cmocka_unit_test(test_boxes_vs_brute_force),
        cmocka_unit_test(test_query_vs_brute_force),
        cmocka_unit_test(test_degenerate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
