/*
 * Cell-by-cell ray casting of irregular grids (VolVis paper, section 5.4;
 * Garrity, "Raytracing irregular volume data", Computer Graphics 24(5),
 * 1990). Each grid object's 3-D cells are split into tetrahedra
 * (src/core/grid_tets.c) with face adjacency; a ray enters the mesh through
 * a boundary face, found with a bounding volume hierarchy over the boundary
 * faces, and walks from tetrahedron to tetrahedron through shared faces.
 * When it leaves through a boundary face the hierarchy gives the next
 * entering face behind it, so non-convex meshes, holes and the gaps left by
 * degenerate or missing cells are crossed.
 *
 * The exit face is chosen with Plücker tests (Platis and Theoharis, "Fast
 * ray-tetrahedron intersection using Plücker coordinates", JGT 2003): the
 * side of the ray against each edge is computed once per edge, always from
 * its lower-numbered point to the higher, so two tetrahedra sharing a face
 * agree exactly on whether the ray crosses it, and rays neither leak nor
 * loop. The same products are the barycentric coordinates of the crossing,
 * so the scalar (linear in a tetrahedron) and the point gradients are
 * interpolated exactly at both ends of every cell segment.
 *
 * Per segment: composite uses a pre-integrated transfer function (Röttger,
 * Kraus and Ertl, "Hardware-accelerated volume and isosurface rendering
 * based on cell-projection", IEEE Vis 2000; the prefix-integral form of
 * Engel, Kraus and Ertl 2001) for the optical depth and emission of the
 * linear value ramp, split into pieces of bounded optical depth, each shaded
 * by the interpolated gradient at its middle; MIP and MinIP take the exact
 * extreme of the segment (an end point), X-ray the exact mean value over the
 * path length, isosurfaces the exact crossing of the linear field.
 *
 * This file is one method's kernel, the cell-by-cell irregular-grid ray
 * caster, kept whole on purpose: its entry, walk and segment compositing
 * are one loop best read together.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/bvh.h"
#include "core/geom.h"
#include "core/grid_internal.h"
#include "render/frame.h"
#include "render/registry.h"
#include "render/shade.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

#define IR_MAX_OBJ 16
#define IR_BINS 4096     /* pre-integration table entries */
#define IR_PIECE_TAU 0.1 /* optical depth of one piece of a cell segment */
#define IR_MAX_PIECES 64 /* pieces of one segment */
/* bytes of first entries kept between frames, every object's together */
#define IR_ENTRY_CACHE_MAX ((size_t)64 << 20)

/* Entering faces and their bounding volume hierarchy (core/bvh.h): the
 * mesh's boundary faces, or those of the tetrahedra a transfer function
 * leaves visible. */
typedef struct ir_layer {
    int32_t *faces; /* 4 * tet + face, in the hierarchy's leaf order */
    size_t n_faces;
    vv_bvh bvh;
} ir_layer;

/* A grid field prepared for rendering: tetrahedra, adjacency, BVH. */
typedef struct ir_mesh {
    const vv_grid *grid; /* key (a reference is held) */
    int field, component;
    vv_tetmesh m;
    ir_layer all; /* the boundary of the mesh */
    double eps;   /* ray-parameter tolerance of a re-entry: 1e-9 of the bounding-box diagonal */
    uint64_t last_used;
    uint64_t serial; /* which build: a slot built again is another mesh */
    /* empty-space skipping for composite: the tetrahedra the transfer
     * function (hashed into vis_key) makes visible, and their boundary */
    uint8_t *vis;
    uint64_t vis_key;
    ir_layer vis_layer;
} ir_mesh;

/* A ray's first entry into an object: the face (-1: none) at t with the
 * barycentric weights of its points, what bvh_enter found. */
typedef struct ir_entry {
    int32_t face;
    double t, w[3];
} ir_entry;

/* What a pixel's first entry depends on: its ray, the object's transform,
 * mesh and entering layer, and the cut planes that end the search. */
typedef struct ir_entry_key {
    vv_camera_rays cam;
    int width, height;
    double w2o[3][4];
    const void *layer; /* the mesh's boundary or its visible part */
    uint64_t serial;   /* the mesh build (ir_mesh.serial) */
    uint64_t vis_key;  /* the visible part's table hash (0: the boundary) */
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
} ir_entry_key;

/* The first entries of every pixel of the last frame of an object (the
 * issue's BVH entry points cached between frames): a frame of the same view
 * and layer (a transfer function edited, a progressive frame drawn again)
 * reads them instead of searching the hierarchy. */
typedef struct ir_entry_cache {
    ir_entry_key key;
    ir_entry *e; /* width x height, row-major */
    int valid;
} ir_entry_cache;

typedef struct ir_state {
    ir_mesh cache[IR_MAX_OBJ];
    ir_entry_cache entries[IR_MAX_OBJ];
    uint64_t serial; /* meshes built */
    uint64_t frame;
    double early_termination;
    int skipping; /* empty-space skipping in composite (option, for tests) */
} ir_state;

typedef struct ir_obj {
    const vv_object *obj;
    const ir_mesh *mesh;
    const ir_layer *layer; /* entering faces: the mesh's, or the visible part's */
    ir_entry *entries;     /* the pixels' first entries (NULL: searched every frame) */
    int fill;              /* 1: search and store them; 0: read them */
    const uint8_t *vis;    /* visible tetrahedra (composite), or NULL: all */
    vv_render_mode mode;
    double w2o[3][4]; /* world -> object (grid coordinates) */
    double o2w[3][4];
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    vv_vshading sh;
    int shading;
    double iso;
    /* pre-integration tables over [vlo, vhi] */
    double vlo, vhi, vscale;
    double inv_vscale; /* 1 / vscale: a table bin's width in value */
    double *T;         /* IR_BINS prefix integrals of extinction over the value */
    double *K;         /* 3 * IR_BINS prefix integrals of extinction times colour */
    float *ext;        /* IR_BINS extinction per world unit */
    float *col;        /* 3 * IR_BINS colour */
    int const_color;   /* one colour over the table: no colour-change term */
} ir_obj;

typedef struct ir_frame {
    ir_state *st;
    vv_image *out; /* the image being written */
    ir_obj *objs;
    int n_obj;
    const vv_view *view;
    vv_camera_rays cam; /* the view's primary rays */
    float bg[3];
    vv_vlight lights[VV_MAX_LIGHTS];
    int n_lights;
    int point_lights;
    double et;
} ir_frame;

/* ---------------------------------------------------------------------- */
/* Boundary-face hierarchy                                                   */

static void
face_points(const vv_tetmesh *m, int32_t f, const double *p[3]) {
    const uint32_t *t = m->tet + 4 * (size_t)(f >> 2);
    const int *fv = vv_tet_face[f & 3];
    for (int i = 0; i < 3; i++)
        p[i] = m->p + 3 * (size_t)t[fv[i]];
}

static void
layer_clear(ir_layer *L) {
    free(L->faces);
    vv_bvh_clear(&L->bvh);
    memset(L, 0, sizeof *L);
}

/* The layer of the faces through which rays enter: boundary faces, or with
 * @p vis the faces of visible tetrahedra whose neighbour is missing or
 * invisible. */
static vv_status
layer_build(ir_layer *L, const vv_tetmesh *m, const uint8_t *vis) {
    memset(L, 0, sizeof *L);
    size_t nb = 0;
    for (size_t f = 0; f < 4 * m->n_tets; f++)
        nb += vis ? vis[f >> 2] && (m->nb[f] < 0 || !vis[(size_t)m->nb[f] >> 2]) : m->nb[f] < 0;
    L->faces = malloc((nb ? nb : 1) * sizeof *L->faces);
    float *cen = malloc(3 * (nb ? nb : 1) * sizeof *cen);
    float *fbox = malloc(6 * (nb ? nb : 1) * sizeof *fbox);
    if (!L->faces || !cen || !fbox) {
        free(cen);
        free(fbox);
        layer_clear(L);
        return vv_error_set(VV_ERR_NOMEM, "irregular: out of memory for the boundary BVH");
    }
    size_t k = 0;
    for (size_t f = 0; f < 4 * m->n_tets; f++) {
        const int in =
            vis ? vis[f >> 2] && (m->nb[f] < 0 || !vis[(size_t)m->nb[f] >> 2]) : m->nb[f] < 0;
        if (!in)
            continue;
        L->faces[k] = (int32_t)f;
        const double *p[3];
        face_points(m, (int32_t)f, p);
        for (int a = 0; a < 3; a++) {
            cen[3 * k + (size_t)a] = (float)((p[0][a] + p[1][a] + p[2][a]) / 3);
            /* rounded outwards, so the float box never cuts the face */
            const double lo = fmin(p[0][a], fmin(p[1][a], p[2][a]));
            const double hi = fmax(p[0][a], fmax(p[1][a], p[2][a]));
            fbox[6 * k + (size_t)a] = nextafterf((float)lo, -INFINITY);
            fbox[6 * k + 3 + (size_t)a] = nextafterf((float)hi, INFINITY);
        }
        k++;
    }
    L->n_faces = nb;
    vv_status s = vv_bvh_build(&L->bvh, nb, fbox, cen);
    free(cen);
    free(fbox);
    if (s != VV_OK) {
        layer_clear(L);
        return vv_error_prefix(s, "irregular");
    }
    /* the faces in leaf order: a leaf's faces are contiguous */
    int32_t *ordered = malloc((nb ? nb : 1) * sizeof *ordered);
    if (!ordered) {
        layer_clear(L);
        return vv_error_set(VV_ERR_NOMEM, "irregular: out of memory for the boundary BVH");
    }
    for (size_t i = 0; i < nb; i++)
        ordered[i] = L->faces[L->bvh.items[i]];
    free(L->faces);
    L->faces = ordered;
    return VV_OK;
}

static vv_status
mesh_build(ir_mesh *im, const vv_grid *g, int field, int component) {
    memset(im, 0, sizeof *im);
    float *sc = NULL;
    vv_status s = vv_grid_field_scalars(g, field, component, &sc);
    if (s != VV_OK)
        return s;
    s = vv_tetmesh_build(&im->m, g, sc, g->fields[field].cell_data, 1, 1);
    free(sc);
    if (s != VV_OK)
        return s;
    if ((s = layer_build(&im->all, &im->m, NULL)) != VV_OK) {
        vv_tetmesh_clear(&im->m);
        return s;
    }
    {
        const vv_box bb = vv_grid_bounds(g);
        im->eps = 1e-9 * (vv_vec3_length(vv_vec3_sub(bb.max, bb.min)) + 1e-300);
    }
    im->grid = vv_grid_ref((vv_grid *)g);
    im->field = field;
    im->component = component;
    return VV_OK;
}

static void
mesh_clear(ir_mesh *im) {
    vv_tetmesh_clear(&im->m);
    layer_clear(&im->all);
    layer_clear(&im->vis_layer);
    free(im->vis);
    vv_grid_free((vv_grid *)im->grid);
    memset(im, 0, sizeof *im);
}

/* The object-space ray o + t d. */
typedef struct ir_ray {
    double o[3], d[3];
    double dd;     /* d . d */
    double inv_dd; /* 1 / (d . d) */
    float inv[3];
} ir_ray;

/* The search of bvh_enter: the nearest entering face so far. */
typedef struct ir_enter {
    const ir_mesh *im;
    const ir_layer *L;
    const ir_ray *r;
    double tmin;
    int32_t skip, best;
    double t; /* the best face's t */
    double *w;
} ir_enter;

static int
enter_leaf(void *ctx, const uint32_t *items, int count, double *bt) {
    ir_enter *e = ctx;
    const vv_vec3 o = vv_v3_d(e->r->o), d = vv_v3_d(e->r->d);
    const int32_t *faces = e->L->faces + vv_bvh_leaf_offset(&e->L->bvh, items);
    for (int i = 0; i < count; i++) {
        const int32_t f = faces[i];
        if (f == e->skip)
            continue;
        const double *p[3];
        face_points(&e->im->m, f, p);
        const vv_vec3 a = vv_v3_d(p[0]);
        const vv_vec3 e1 = vv_v3_sub(vv_v3_d(p[1]), a), e2 = vv_v3_sub(vv_v3_d(p[2]), a);
        /* entering: d . (e1 x e2) < 0 (outward normal) */
        if (!(vv_v3_dot(d, vv_v3_cross(e1, e2)) < 0))
            continue;
        double t, u, v;
        if (!vv_ray_triangle(o, d, a, e1, e2, &t, &u, &v))
            continue;
        if (t < e->tmin || t > *bt)
            continue;
        if (t == *bt && e->best >= 0 && f > e->best)
            continue; /* ties go to the lower face: deterministic */
        *bt = e->t = t;
        e->best = f;
        e->w[0] = 1 - u - v;
        e->w[1] = u;
        e->w[2] = v;
    }
    return 0;
}

/* The nearest boundary face the ray enters (d . outward normal < 0) at t
 * in [tmin, tmax], other than @p skip; returns the face or -1, with t and
 * the barycentric weights of its three points. */
static int32_t
bvh_enter(const ir_mesh *im, const ir_layer *L, const ir_ray *r, double tmin, double tmax,
          int32_t skip, double *t_hit, double w[3]) {
    ir_enter e = {im, L, r, tmin, skip, -1, tmax, w};
    const double inv[3] = {r->inv[0], r->inv[1], r->inv[2]};
    vv_bvh_ray(&L->bvh, r->o, inv, tmin, tmax, enter_leaf, &e);
    *t_hit = e.t;
    return e.best;
}

/* ---------------------------------------------------------------------- */
/* Transfer-function pre-integration                                         */

static vv_status
tables_build(ir_obj *ob) {
    const vv_object *obj = ob->obj;
    double lo = ob->mesh->m.range[0], hi = ob->mesh->m.range[1];
    if (obj->tf.n_opacity > 0) {
        lo = fmin(lo, obj->tf.opacity[0].value);
        hi = fmax(hi, obj->tf.opacity[obj->tf.n_opacity - 1].value);
    }
    if (!(hi > lo))
        hi = lo + 1;
    ob->vlo = lo;
    ob->vhi = hi;
    ob->vscale = (IR_BINS - 1) / (hi - lo);
    ob->inv_vscale = (hi - lo) / (IR_BINS - 1);
    ob->T = malloc(IR_BINS * sizeof *ob->T);
    ob->K = malloc(3 * IR_BINS * sizeof *ob->K);
    ob->ext = malloc(IR_BINS * sizeof *ob->ext);
    ob->col = malloc(3 * IR_BINS * sizeof *ob->col);
    if (!ob->T || !ob->K || !ob->ext || !ob->col)
        return vv_error_set(VV_ERR_NOMEM, "irregular: out of memory");
    const double unit = obj->tf.opacity_unit_distance > 0 ? obj->tf.opacity_unit_distance : 1;
    const double dv = (hi - lo) / (IR_BINS - 1);
    for (int i = 0; i < IR_BINS; i++) {
        const double v = lo + dv * i;
        double a = vv_tf_eval_opacity(&obj->tf, v);
        a = a < 0 ? 0 : a > 0.999999 ? 0.999999 : a;
        ob->ext[i] = (float)(-log1p(-a) / unit);
        const vv_vec3 c = vv_tf_eval_color(&obj->tf, v);
        ob->col[3 * i] = (float)c.x;
        ob->col[3 * i + 1] = (float)c.y;
        ob->col[3 * i + 2] = (float)c.z;
    }
    ob->const_color = 1;
    for (int i = 1; i < IR_BINS && ob->const_color; i++)
        for (int c = 0; c < 3; c++)
            if (ob->col[3 * i + c] != ob->col[c])
                ob->const_color = 0;
    ob->T[0] = 0;
    ob->K[0] = ob->K[1] = ob->K[2] = 0;
    for (int i = 1; i < IR_BINS; i++) {
        ob->T[i] = ob->T[i - 1] + 0.5 * dv * ((double)ob->ext[i - 1] + ob->ext[i]);
        for (int c = 0; c < 3; c++)
            ob->K[3 * i + c] =
                ob->K[3 * (i - 1) + c] + 0.5 * dv *
                                             ((double)ob->ext[i - 1] * ob->col[3 * (i - 1) + c] +
                                              (double)ob->ext[i] * ob->col[3 * i + c]);
    }
    return VV_OK;
}

/* The prefix integral of extinction at value v (prefix_eval's T). */
static inline double
prefix_T(const ir_obj *ob, double v) {
    const double x = (v - ob->vlo) * ob->vscale;
    if (x <= 0)
        return (v - ob->vlo) * ob->ext[0];
    if (x >= IR_BINS - 1)
        return ob->T[IR_BINS - 1] + (v - ob->vhi) * ob->ext[IR_BINS - 1];
    const int i = (int)x;
    const double f = x - i, e0 = ob->ext[i], e1 = ob->ext[i + 1];
    return ob->T[i] + f * (e0 + 0.5 * f * (e1 - e0)) * ob->inv_vscale;
}

/* Prefix integrals at value v: T (extinction) and K (extinction x colour),
 * continued linearly with the end values outside the table. */
static inline void
prefix_eval(const ir_obj *ob, double v, double *T, double K[3]) {
    double x = (v - ob->vlo) * ob->vscale;
    if (ob->const_color) {
        /* one colour: K = c T, only T is integrated */
        *T = prefix_T(ob, v);
        K[0] = *T * ob->col[0];
        K[1] = *T * ob->col[1];
        K[2] = *T * ob->col[2];
        return;
    }
    if (x <= 0) {
        const double dv = v - ob->vlo;
        *T = dv * ob->ext[0];
        for (int c = 0; c < 3; c++)
            K[c] = dv * ob->ext[0] * ob->col[c];
        return;
    }
    if (x >= IR_BINS - 1) {
        const double dv = v - ob->vhi;
        const int e = IR_BINS - 1;
        *T = ob->T[e] + dv * ob->ext[e];
        for (int c = 0; c < 3; c++)
            K[c] = ob->K[3 * e + c] + dv * ob->ext[e] * ob->col[3 * e + c];
        return;
    }
    const int i = (int)x;
    const double f = x - i, dvb = ob->inv_vscale;
    /* exact integral of the linear extinction within the bin */
    const double e0 = ob->ext[i], e1 = ob->ext[i + 1];
    *T = ob->T[i] + dvb * f * (e0 + 0.5 * f * (e1 - e0));
    for (int c = 0; c < 3; c++) {
        const double k0 = e0 * ob->col[3 * i + c], k1 = e1 * ob->col[3 * (i + 1) + c];
        K[c] = ob->K[3 * i + c] + dvb * f * (k0 + 0.5 * f * (k1 - k0));
    }
}

static inline double
ext_at(const ir_obj *ob, double v, double col[3]) {
    double x = (v - ob->vlo) * ob->vscale;
    x = x < 0 ? 0 : x > IR_BINS - 1 ? IR_BINS - 1 : x;
    int i = (int)x;
    i = i > IR_BINS - 2 ? IR_BINS - 2 : i;
    const double f = x - i;
    for (int c = 0; c < 3; c++)
        col[c] = ob->col[3 * i + c] * (1 - f) + ob->col[3 * (i + 1) + c] * f;
    return ob->ext[i] * (1 - f) + ob->ext[i + 1] * f;
}

/* ---------------------------------------------------------------------- */
/* The walk                                                                 */

typedef struct ir_acc {
    double C[3], A;
    double depth;
    /* one-colour unshaded composite: the optical depth of the segments not
     * yet composited into C and A, and the depth at which A reaches the
     * early termination (segment_thin) */
    double tau, tau_stop;
    /* projections */
    double best, tbest;
    double sum, len;
    int any;
    int done;
} ir_acc;

/* Point gradient interpolated with the weights b over the tetrahedron t,
 * in object coordinates. */
static inline void
grad_at(const vv_tetmesh *m, const uint32_t *t, const double b[4], float g[3]) {
    g[0] = g[1] = g[2] = 0;
    if (!m->grad)
        return;
    for (int i = 0; i < 4; i++) {
        const float *gi = m->grad + 3 * (size_t)t[i];
        g[0] += (float)b[i] * gi[0];
        g[1] += (float)b[i] * gi[1];
        g[2] += (float)b[i] * gi[2];
    }
}

static void
world_point(const ir_ray *wr, double t, float pw[3]) {
    for (int a = 0; a < 3; a++)
        pw[a] = (float)(wr->o[a] + t * wr->d[a]);
}

/* The prefix integrals at the end of the last segment, reused at the start
 * of the next one (the value is continuous across a shared face). */
typedef struct ir_pre {
    int valid;
    double s, T, K[3];
} ir_pre;

/* The optical depth after which the opacity A of @p acc reaches @p et. */
static inline double
stop_depth(double A, double et) {
    return A >= et ? 0 : log((1 - A) / (1 - et));
}

/* Composites the pending optical depth of one-colour segments: with one
 * colour c and no shading, compositing pieces of opacity 1 - e^-tau_i front
 * to back gives c (1 - e^-sum tau_i), so a run of them is one piece. */
static inline void
acc_flush(const ir_frame *fr, const ir_obj *ob, ir_acc *acc) {
    if (!(acc->tau > 0))
        return;
    const double alpha = -expm1(-acc->tau);
    const double w = 1 - acc->A;
    for (int k = 0; k < 3; k++)
        acc->C[k] += w * ob->col[k] * alpha;
    acc->A += w * alpha;
    acc->tau = 0;
    acc->tau_stop = stop_depth(acc->A, fr->et);
}

/* Composite of one colour, unshaded (segment's common case): only the
 * optical depth is integrated, and added to the pending depth that
 * acc_flush composites. A segment thin enough to be one piece is done
 * here, with segment's arithmetic; returns 0 for a thicker one, which
 * segment then cuts into pieces. */
static inline int
segment_thin(const ir_frame *fr, const ir_obj *ob, double t0, double L, double s0, double s1,
             ir_acc *acc, ir_pre *pre) {
    const double Ta = pre->valid && pre->s == s0 ? pre->T : prefix_T(ob, s0);
    const double Tb = prefix_T(ob, s1);
    if (!(L > 0)) {
        pre->valid = 1;
        pre->s = s1;
        pre->T = Tb;
        return 1;
    }
    const double dsv = s1 - s0;
    const int ramp = fabs(dsv) * ob->vscale > 1e-3;
    double c[3], tau;
    if (ramp)
        tau = L / dsv * (Tb - Ta);
    else
        tau = L * ext_at(ob, 0.5 * (s0 + s1), c);
    if (tau > 1e-7 && 1 + (int)(tau * (1.0 / IR_PIECE_TAU)) > 1)
        return 0;
    pre->valid = 1;
    pre->s = s1;
    pre->T = Tb;
    if (!(tau > 1e-7))
        return 1;
    acc->tau += tau;
    if (acc->depth == INFINITY)
        acc->depth = t0;
    if (acc->tau >= acc->tau_stop) {
        acc_flush(fr, ob, acc);
        acc->done = 1;
    }
    return 1;
}

/* Over 150 lines on purpose: the per-segment integration of every mode
 * (pre-integrated composite with shading, projections, iso crossings) on
 * the hot path of each cell a ray crosses; its cases share the segment's
 * values and weights, kept in registers. */
/* One cell segment [t0, t1] of tetrahedron t, with barycentric weights b0
 * and b1 at its ends and values s0, s1 there. */
static void
segment(const ir_frame *fr, const ir_obj *ob, const ir_ray *wr, const uint32_t *t, double t0,
        double t1, const double b0[4], const double b1[4], double s0, double s1, ir_acc *acc,
        ir_pre *pre) {
    const double L = t1 - t0;
    switch (ob->mode) {
    case VV_MODE_MIP:
    case VV_MODE_MINIP: {
        const int mip = ob->mode == VV_MODE_MIP;
        if (!acc->any || (mip ? s0 > acc->best : s0 < acc->best)) {
            acc->best = s0;
            acc->tbest = t0;
        }
        if (mip ? s1 > acc->best : s1 < acc->best) {
            acc->best = s1;
            acc->tbest = t1;
        }
        acc->any = 1;
        return;
    }
    case VV_MODE_XRAY:
        if (!acc->any)
            acc->tbest = t0;
        acc->any = 1;
        acc->sum += L * 0.5 * (s0 + s1);
        acc->len += L;
        return;
    case VV_MODE_ISO: {
        const double iso = ob->iso;
        double u = -1;
        if (acc->any && (acc->best < iso) != (s0 < iso))
            u = 0; /* a jump between cells (cell data) */
        else if ((s0 < iso) != (s1 < iso))
            u = (iso - s0) / (s1 - s0);
        acc->any = 1;
        acc->best = s1;
        if (u < 0)
            return;
        double b[4];
        for (int i = 0; i < 4; i++)
            b[i] = b0[i] + u * (b1[i] - b0[i]);
        float g[3], pw[3], out[3];
        grad_at(&ob->mesh->m, t, b, g);
        const double th = t0 + u * L;
        world_point(wr, th, pw);
        const float v[3] = {(float)-wr->d[0], (float)-wr->d[1], (float)-wr->d[2]};
        if (ob->shading)
            vv_vshade(&ob->sh, fr->lights, fr->n_lights, g, pw, v, ob->sh.base, 1.0f, NULL, NULL,
                      out);
        else
            memcpy(out, ob->sh.base, sizeof out);
        for (int c = 0; c < 3; c++)
            acc->C[c] += (1 - acc->A) * out[c];
        acc->A = 1;
        acc->depth = th;
        acc->done = 1;
        return;
    }
    default:
        break;
    }
    /* composite (one-colour unshaded segments thin enough: segment_thin,
     * which the walk calls first) */
    acc_flush(fr, ob, acc);
    double Ta, Tb, Ka[3], Kb[3];
    if (pre->valid && pre->s == s0) {
        Ta = pre->T;
        memcpy(Ka, pre->K, sizeof Ka);
    } else {
        prefix_eval(ob, s0, &Ta, Ka);
    }
    prefix_eval(ob, s1, &Tb, Kb);
    pre->valid = 1;
    pre->s = s1;
    pre->T = Tb;
    memcpy(pre->K, Kb, sizeof Kb);
    if (!(L > 0))
        return;
    const double dsv = s1 - s0;
    const int ramp = fabs(dsv) * ob->vscale > 1e-3; /* else a constant value */
    /* L / (s1 - s0): every piece of the segment has the same ratio of
     * length to value change, so one division serves them all */
    const double l_ds = ramp ? L / dsv : 0;
    double tau_all;
    if (ramp) {
        tau_all = l_ds * (Tb - Ta);
    } else {
        double c[3];
        tau_all = L * ext_at(ob, 0.5 * (s0 + s1), c);
    }
    if (!(tau_all > 1e-7))
        return;
    int n = 1 + (int)(tau_all * (1.0 / IR_PIECE_TAU));
    n = n > IR_MAX_PIECES ? IR_MAX_PIECES : n;
    const double inv_n = n == 1 ? 1.0 : 1.0 / n;
    const float v[3] = {(float)-wr->d[0], (float)-wr->d[1], (float)-wr->d[2]};
    double Tp = Ta, Kp[3] = {Ka[0], Ka[1], Ka[2]};
    for (int k = 0; k < n; k++) {
        const double ua = k * inv_n, ub = (k + 1) * inv_n;
        const double va = s0 + ua * dsv, vb = s0 + ub * dsv, l = L * inv_n;
        double tau, E[3];
        double Tn, Kn[3];
        if (k + 1 == n) {
            Tn = Tb;
            memcpy(Kn, Kb, sizeof Kn);
        } else {
            prefix_eval(ob, vb, &Tn, Kn);
        }
        if (ramp) {
            tau = l_ds * (Tn - Tp);
            for (int c = 0; c < 3; c++)
                E[c] = l_ds * (Kn[c] - Kp[c]);
        } else {
            double cc[3];
            const double e = ext_at(ob, 0.5 * (va + vb), cc);
            tau = l * e;
            for (int c = 0; c < 3; c++)
                E[c] = tau * cc[c];
        }
        Tp = Tn;
        memcpy(Kp, Kn, sizeof Kp);
        if (!(tau > 1e-9))
            continue;
        /* The emission-weighted mean colour of the piece, attenuated over
         * it, plus the first-order term of the colour's change along the
         * piece (its front part is seen through less of the piece):
         * c(u) = cbar + dc (u - 1/2) with constant extinction integrates to
         * cbar alpha + dc ((alpha / tau - (1 - alpha)) - alpha / 2). */
        /* 1 - e^-tau: its Taylor series to tau^5 (error below 1e-7) for
         * the thin pieces most segments are */
        const double alpha =
            tau < 0.1 ? tau * (1 - tau * (0.5 - tau * (1.0 / 6 - tau * (1.0 / 24 - tau / 120))))
                      : -expm1(-tau);
        float col[3], out[3];
        if (ob->const_color) {
            for (int c = 0; c < 3; c++)
                col[c] = (float)(ob->col[c] * alpha);
        } else {
            const double corr =
                tau > 1e-4 ? alpha / tau - (1 - alpha) - 0.5 * alpha : tau * (-1.0 / 12 + tau / 24);
            double ca[3], cb[3];
            ext_at(ob, va, ca);
            ext_at(ob, vb, cb);
            for (int c = 0; c < 3; c++) {
                const double cv = E[c] / tau * alpha + (cb[c] - ca[c]) * corr;
                col[c] = (float)(cv > 0 ? cv : 0);
            }
        }
        if (ob->shading) {
            const double um = 0.5 * (ua + ub);
            double b[4];
            for (int i = 0; i < 4; i++)
                b[i] = b0[i] + um * (b1[i] - b0[i]);
            float g[3], pw[3] = {0, 0, 0};
            grad_at(&ob->mesh->m, t, b, g);
            if (fr->point_lights)
                world_point(wr, t0 + um * L, pw);
            vv_vshade(&ob->sh, fr->lights, fr->n_lights, g, pw, v, col, (float)alpha, NULL, NULL,
                      out);
        } else {
            memcpy(out, col, sizeof out);
        }
        const double w = 1 - acc->A;
        for (int c = 0; c < 3; c++)
            acc->C[c] += w * out[c];
        acc->A += w * alpha;
        if (acc->depth == INFINITY)
            acc->depth = t0 + ua * L;
        if (acc->A >= fr->et) {
            acc->done = 1;
            return;
        }
    }
}

/* d x q: a point's part of the ray's sides against its edges. */
static inline void
point_cross(const ir_ray *r, const double q[3], double u[3]) {
    u[0] = r->d[1] * q[2] - r->d[2] * q[1];
    u[1] = r->d[2] * q[0] - r->d[0] * q[2];
    u[2] = r->d[0] * q[1] - r->d[1] * q[0];
}

/* Canonical side of the ray against the edge between points a and b
 * (relative to the ray origin), d . (a x b) = (d x a) . b from the lower
 * global index to the higher (ua = d x a, ub = d x b), so every tetrahedron
 * with the edge gets the same value. */
static inline double
edge_canon(const double *a, const double *ua, const double *b, const double *ub, uint32_t ga,
           uint32_t gb) {
    const int lo_a = ga < gb;
    const double *u = lo_a ? ua : ub, *q = lo_a ? b : a;
    const double v = u[0] * q[0] + u[1] * q[1] + u[2] * q[2];
    return lo_a ? v : -v;
}

/* Over 150 lines on purpose: the cell-to-cell walk of one ray, whose
 * carried state (the shared face's points and edge sides, the entry
 * record, the restart after a gap) is what makes each step cost one point
 * and three edge sides; splitting it would spill that state per cell (a
 * walker struct stepped by functions, tried, was 3 % slower, and four
 * such walkers interleaved 30 % slower: the walk is bound by its
 * instructions, not by latency). */
/* Walks one object along the ray, clipped to [tc0, tc1]. The points
 * (relative to the ray origin), d x point, values and edge sides of the
 * current tetrahedron sit in four slots; a step replaces the slot of the
 * point opposite the exit face with the neighbour's fourth point, so the
 * three shared points keep their slots, edge sides and weights, each step
 * fetches one point and computes three edge sides, and the slots'
 * orientation flips (sg: the exit test reads every side times sg). */
static void
trace_object(const ir_frame *fr, const ir_obj *ob, const ir_ray *wr, double tc0, double tc1,
             ir_acc *acc, ir_entry *first) {
    const ir_mesh *im = ob->mesh;
    const vv_tetmesh *m = &im->m;
    ir_ray r;
    for (int a = 0; a < 3; a++) {
        r.o[a] = ob->w2o[a][3];
        r.d[a] = 0;
        for (int c = 0; c < 3; c++) {
            r.o[a] += ob->w2o[a][c] * wr->o[c];
            r.d[a] += ob->w2o[a][c] * wr->d[c];
        }
    }
    /* A ray exactly along grid edges (the pole axis of a spherical grid, a
     * lattice line seen head on) meets cells only in their edges: shift
     * every ray by 1e-7 of the grid's size, in a fixed direction with
     * irrational ratios, so that such alignments do not occur. */
    {
        static const double jitter[3] = {0.5772156649, 0.3183098862, 0.7071067812};
        for (int a = 0; a < 3; a++)
            r.o[a] += 100 * im->eps * jitter[a];
    }
    r.dd = r.d[0] * r.d[0] + r.d[1] * r.d[1] + r.d[2] * r.d[2];
    r.inv_dd = 1.0 / r.dd;
    for (int a = 0; a < 3; a++)
        r.inv[a] = (float)(1.0 / r.d[a]);
    /* Entering again after leaving through a boundary face at tsearch: a
     * face up to eps before it counts (the two sides of a gap computed
     * apart), unless the last entry made no progress, when only faces
     * strictly behind it do: the ray parameter always grows, so the walk
     * ends. */
    double tsearch = -INFINITY;
    int strict = 0, entries = 0;
    int32_t skip = -1;
    long steps = 0;
    const long max_steps = (long)m->n_tets + 1024;
    const int cell_data = m->tval != NULL;
    /* segments of one colour, unshaded: thin ones composited here, the
     * rest by segment */
    const int thin = ob->mode == VV_MODE_COMPOSITE && ob->const_color && !ob->shading;
    ir_pre pre = {0, 0, 0, {0, 0, 0}};
    (void)tc0;
    while (!acc->done && steps < max_steps && entries++ < 100000) {
        double t_in, w3[3];
        /* The first search starts behind the ray's origin: an eye inside
         * the grid (flying through it) sees the cells around it; what lies
         * before tc0 (>= 0) is walked through but not integrated. */
        const double from = strict                ? nextafter(tsearch, INFINITY)
                            : tsearch > -INFINITY ? tsearch - im->eps
                                                  : -INFINITY;
        int32_t f;
        if (first && entries == 1 && !ob->fill) { /* the entry this view found before */
            f = first->face;
            t_in = first->t;
            memcpy(w3, first->w, sizeof w3);
        } else {
            f = bvh_enter(im, ob->layer, &r, from, tc1, skip, &t_in, w3);
            if (first && entries == 1) {
                first->face = f;
                first->t = t_in;
                memcpy(first->w, w3, sizeof first->w);
            }
        }
        if (f < 0)
            break;
        skip = f;
        const double t_entry = t_in > tsearch ? t_in : tsearch;
        t_in = t_entry;
        int32_t cur = f >> 2;
        int face_in = f & 3;
        double b_in[4] = {0, 0, 0, 0};
        for (int i = 0; i < 3; i++)
            b_in[vv_tet_face[face_in][i]] = w3[i];
        double t_prev = t_in;
        double s_prev = 0;
        int have_s = 0;
        pre.valid = 0;
        /* the first tetrahedron: all four points and six edges */
        uint32_t gid[4];
        double q[4][3], u[4][3], es[4][4], qv[4] = {0, 0, 0, 0}; /* points, d x points, edge
                                                                  sides, values */
        double sg = 1;
        for (int i = 0; i < 4; i++) {
            gid[i] = m->tet[4 * (size_t)cur + (size_t)i];
            for (int a = 0; a < 3; a++)
                q[i][a] = m->p[3 * (size_t)gid[i] + (size_t)a] - r.o[a];
            point_cross(&r, q[i], u[i]);
            if (!cell_data)
                qv[i] = m->val[gid[i]];
        }
        for (int i = 0; i < 4; i++)
            for (int j = i + 1; j < 4; j++) {
                es[i][j] = edge_canon(q[i], u[i], q[j], u[j], gid[i], gid[j]);
                es[j][i] = -es[i][j];
            }
        for (;;) {
            steps++;
            /* exit face: all three oriented edge sides >= 0 */
            int exit = -1;
            double we[3] = {0, 0, 0}, best_min = -INFINITY;
            for (int fi = 0; fi < 4; fi++) {
                if (fi == face_in)
                    continue;
                const int *fv = vv_tet_face[fi];
                const double sab = sg * es[fv[0]][fv[1]], sbc = sg * es[fv[1]][fv[2]],
                             sca = sg * es[fv[2]][fv[0]];
                double mn = sab < sbc ? sab : sbc;
                mn = sca < mn ? sca : mn;
                if (mn >= 0 && sab + sbc + sca > 0) {
                    exit = fi;
                    we[0] = sbc;
                    we[1] = sca;
                    we[2] = sab;
                    break;
                }
                if (mn > best_min) { /* fallback for a numerically degenerate case */
                    best_min = mn;
                    exit = fi;
                    we[0] = sbc > 0 ? sbc : 0;
                    we[1] = sca > 0 ? sca : 0;
                    we[2] = sab > 0 ? sab : 0;
                }
            }
            double ws = we[0] + we[1] + we[2];
            if (!(ws > 0)) {
                we[0] = we[1] = we[2] = 1;
                ws = 3;
            }
            double b_out[4] = {0, 0, 0, 0};
            double pt[3] = {0, 0, 0};
            const double inv_ws = 1.0 / ws;
            for (int i = 0; i < 3; i++) {
                const int vi = vv_tet_face[exit][i];
                b_out[vi] = we[i] * inv_ws;
                for (int a = 0; a < 3; a++)
                    pt[a] += b_out[vi] * q[vi][a];
            }
            double t_out = (pt[0] * r.d[0] + pt[1] * r.d[1] + pt[2] * r.d[2]) * r.inv_dd;
            t_out = t_out > t_prev ? t_out : t_prev;
            /* the segment, clipped to the cut planes */
            double s0, s1;
            if (cell_data) {
                s0 = s1 = m->tval[cur];
            } else {
                s1 = 0;
                for (int i = 0; i < 4; i++)
                    s1 += b_out[i] * qv[i];
                if (have_s) {
                    s0 = s_prev; /* continuous across the shared face */
                } else {
                    s0 = 0;
                    for (int i = 0; i < 4; i++)
                        s0 += b_in[i] * qv[i];
                }
            }
            s_prev = s1;
            have_s = 1;
            if (t_out > tc0 && t_prev < tc1) {
                if (t_prev < tc0 || t_out > tc1) {
                    double a0 = t_prev, a1 = t_out, c0[4], c1[4];
                    const double len = a1 - a0;
                    const double u0 = a0 < tc0 && len > 0 ? (tc0 - a0) / len : 0;
                    const double u1 = a1 > tc1 && len > 0 ? (tc1 - a0) / len : 1;
                    for (int i = 0; i < 4; i++) {
                        c0[i] = b_in[i] + u0 * (b_out[i] - b_in[i]);
                        c1[i] = b_in[i] + u1 * (b_out[i] - b_in[i]);
                    }
                    pre.valid = 0;
                    const double ta = a0 + u0 * len, sa = s0 + u0 * (s1 - s0),
                                 sb = s0 + u1 * (s1 - s0);
                    if (!thin || !segment_thin(fr, ob, ta, a0 + u1 * len - ta, sa, sb, acc, &pre))
                        segment(fr, ob, wr, gid, ta, a0 + u1 * len, c0, c1, sa, sb, acc, &pre);
                    pre.valid = 0;
                } else {
                    if (!thin || !segment_thin(fr, ob, t_prev, t_out - t_prev, s0, s1, acc, &pre))
                        segment(fr, ob, wr, gid, t_prev, t_out, b_in, b_out, s0, s1, acc, &pre);
                }
                if (acc->done)
                    return;
            } else {
                pre.valid = 0;
            }
            if (t_out >= tc1)
                return;
            /* the exit face in the mesh's numbering: opposite the same point */
            const uint32_t *t = m->tet + 4 * (size_t)cur;
            const uint32_t gx = gid[exit];
            const int k = (t[1] == gx) + 2 * (t[2] == gx) + 3 * (t[3] == gx);
            const int32_t nb = m->nb[4 * (size_t)cur + (size_t)k];
            if (nb < 0 || (ob->vis && !ob->vis[nb >> 2]) || steps >= max_steps) {
                strict = !(t_out > t_entry);
                tsearch = t_out;
                break;
            }
            /* the neighbour: its fourth point takes the exit slot */
            cur = nb >> 2;
            const uint32_t gn = m->tet[(size_t)nb];
            gid[exit] = gn;
            for (int a = 0; a < 3; a++)
                q[exit][a] = m->p[3 * (size_t)gn + (size_t)a] - r.o[a];
            qv[exit] = cell_data ? 0 : m->val[gn];
            point_cross(&r, q[exit], u[exit]);
            for (int j = 0; j < 4; j++) {
                if (j == exit)
                    continue;
                es[exit][j] = edge_canon(q[exit], u[exit], q[j], u[j], gn, gid[j]);
                es[j][exit] = -es[exit][j];
            }
            memcpy(b_in, b_out, sizeof b_in);
            face_in = exit;
            sg = -sg;
            t_prev = t_out;
        }
    }
}

/* ---------------------------------------------------------------------- */
/* Frame                                                                    */

static void
render_pixel(const ir_frame *fr, int x, int y, vv_image *out) {
    const vv_ray vr = vv_camera_ray(&fr->cam, x, y);
    ir_ray wr;
    wr.o[0] = vr.origin.x;
    wr.o[1] = vr.origin.y;
    wr.o[2] = vr.origin.z;
    wr.d[0] = vr.dir.x;
    wr.d[1] = vr.dir.y;
    wr.d[2] = vr.dir.z;
    double C[3] = {0, 0, 0}, A = 0, depth = INFINITY;
    double P[3] = {0, 0, 0}, PA = 0;
    /* composite and iso objects, nearest first (by the depth each reaches) */
    ir_acc accs[IR_MAX_OBJ];
    int order[IR_MAX_OBJ], n = 0;
    for (int i = 0; i < fr->n_obj; i++) {
        const ir_obj *ob = &fr->objs[i];
        double t0 = 0, t1 = INFINITY;
        int ok = 1;
        for (int p = 0; p < ob->n_planes && ok; p++)
            ok = vv_plane_clip_ray(ob->planes[p], vr, &t0, &t1);
        if (!ok)
            continue;
        ir_acc *acc = &accs[i];
        memset(acc, 0, sizeof *acc);
        acc->depth = INFINITY;
        acc->tau_stop = stop_depth(0, fr->et);
        trace_object(fr, ob, &wr, t0, t1, acc,
                     ob->entries ? ob->entries + (size_t)y * fr->view->width + (size_t)x : NULL);
        acc_flush(fr, ob, acc);
        if (ob->mode == VV_MODE_COMPOSITE || ob->mode == VV_MODE_ISO) {
            if (acc->A > 0)
                order[n++] = i;
            continue;
        }
        if (!acc->any)
            continue;
        const double val =
            ob->mode == VV_MODE_XRAY ? (acc->len > 0 ? acc->sum / acc->len : 0) : acc->best;
        const double a = vv_tf_eval_opacity(&ob->obj->tf, val);
        const vv_vec3 c = vv_tf_eval_color(&ob->obj->tf, val);
        const double cc[3] = {c.x, c.y, c.z};
        for (int ch = 0; ch < 3; ch++)
            P[ch] = cc[ch] * a > P[ch] ? cc[ch] * a : P[ch];
        PA = a > PA ? a : PA;
        depth = acc->tbest < depth ? acc->tbest : depth;
    }
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && accs[order[j]].depth < accs[order[j - 1]].depth; j--) {
            int x2 = order[j];
            order[j] = order[j - 1];
            order[j - 1] = x2;
        }
    for (int k = 0; k < n; k++) {
        const ir_acc *acc = &accs[order[k]];
        for (int ch = 0; ch < 3; ch++)
            C[ch] += (1 - A) * acc->C[ch];
        A += (1 - A) * acc->A;
        depth = acc->depth < depth ? acc->depth : depth;
    }
    float *pix = out->rgba + 4 * ((size_t)y * (size_t)out->width + (size_t)x);
    A = A > 1 ? 1 : A;
    const double rest = 1 - A, A2 = A + rest * PA;
    for (int ch = 0; ch < 3; ch++)
        pix[ch] = (float)(C[ch] + rest * P[ch] + (1 - A2) * fr->bg[ch]);
    pix[3] = (float)A2;
    out->depth[(size_t)y * (size_t)out->width + (size_t)x] = (float)depth;
}

/* The cached mesh of a grid field, built when missing. */
static vv_status
mesh_get(ir_state *st, const vv_grid *g, int field, int component, const ir_mesh **out) {
    int free_slot = -1, oldest = 0;
    for (int i = 0; i < IR_MAX_OBJ; i++) {
        ir_mesh *im = &st->cache[i];
        if (im->grid == g && im->field == field && im->component == component) {
            im->last_used = st->frame;
            *out = im;
            return VV_OK;
        }
        if (!im->grid && free_slot < 0)
            free_slot = i;
        if (im->last_used < st->cache[oldest].last_used)
            oldest = i;
    }
    const int slot = free_slot >= 0 ? free_slot : oldest;
    mesh_clear(&st->cache[slot]);
    vv_status s = mesh_build(&st->cache[slot], g, field, component);
    if (s != VV_OK)
        return s;
    st->cache[slot].last_used = st->frame;
    st->cache[slot].serial = ++st->serial;
    *out = &st->cache[slot];
    return VV_OK;
}

/* Empty-space skipping for composite (the role the subvolume min/max grid
 * plays in the ray caster): the tetrahedra whose value range meets a
 * non-zero opacity, and the boundary of that visible part as the layer
 * rays enter through, so they jump over transparent cells instead of
 * walking through them. Kept in the mesh while the transfer function's
 * table (hashed) stays the same. */
static vv_status
vis_prepare(ir_mesh *im, ir_obj *ob) {
    uint64_t key = 1469598103934665603ull;
    const unsigned char *bytes = (const unsigned char *)ob->ext;
    for (size_t i = 0; i < IR_BINS * sizeof *ob->ext; i++)
        key = (key ^ bytes[i]) * 1099511628211ull;
    key ^= (uint64_t)(ob->vlo * 1e6) * 31 + (uint64_t)(ob->vhi * 1e6);
    if (im->vis && im->vis_key == key)
        return VV_OK;
    free(im->vis);
    layer_clear(&im->vis_layer);
    im->vis = NULL;
    const vv_tetmesh *m = &im->m;
    int *nz = malloc((IR_BINS + 1) * sizeof *nz);
    uint8_t *vis = malloc(m->n_tets ? m->n_tets : 1);
    if (!nz || !vis) {
        free(nz);
        free(vis);
        return vv_error_set(VV_ERR_NOMEM, "irregular: out of memory");
    }
    nz[0] = 0;
    for (int i = 0; i < IR_BINS; i++)
        nz[i + 1] = nz[i] + (ob->ext[i] > 0);
    for (size_t t = 0; t < m->n_tets; t++) {
        double lo, hi;
        if (m->tval) {
            lo = hi = m->tval[t];
        } else {
            lo = hi = m->val[m->tet[4 * t]];
            for (int k = 1; k < 4; k++) {
                const double v = m->val[m->tet[4 * t + (size_t)k]];
                lo = v < lo ? v : lo;
                hi = v > hi ? v : hi;
            }
        }
        double x0 = floor((lo - ob->vlo) * ob->vscale), x1 = ceil((hi - ob->vlo) * ob->vscale);
        x0 = x0 < 0 ? 0 : x0 > IR_BINS - 1 ? IR_BINS - 1 : x0;
        x1 = x1 < 0 ? 0 : x1 > IR_BINS - 1 ? IR_BINS - 1 : x1;
        vis[t] = nz[(int)x1 + 1] - nz[(int)x0] > 0;
    }
    free(nz);
    vv_status s = layer_build(&im->vis_layer, m, vis);
    if (s != VV_OK) {
        free(vis);
        return s;
    }
    im->vis = vis;
    im->vis_key = key;
    return VV_OK;
}

static vv_status
prepare_object(ir_frame *fr, ir_obj *ob, const vv_object *obj, const vv_world *w,
               const float ambient[3]) {
    memset(ob, 0, sizeof *ob);
    ob->obj = obj;
    ob->mode = obj->mode;
    const int field = vv_object_grid_field(obj);
    if (field < 0)
        return VV_ERR_INVALID;
    const int comp = obj->grid->fields[field].n_components > 1 ? obj->component : -1;
    vv_status s = mesh_get(fr->st, obj->grid, field, comp, &ob->mesh);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    const vv_mat4 m = vv_object_matrix(obj);
    int ok = 0;
    const vv_mat4 inv = vv_mat4_inverse(m, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) {
            ob->w2o[r][c] = inv.m[r][c];
            ob->o2w[r][c] = m.m[r][c];
        }
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            ob->sh.nrm[r][c] = (float)inv.m[c][r];
    for (int p = 0; p < w->n_cut_planes; p++)
        ob->planes[ob->n_planes++] =
            vv_plane_from_point_normal(w->cut_planes[p].point, w->cut_planes[p].normal);
    for (int p = 0; p < obj->n_cut_planes; p++)
        ob->planes[ob->n_planes++] =
            vv_plane_from_point_normal(obj->cut_planes[p].point, obj->cut_planes[p].normal);
    const vv_material *mt = &obj->material;
    for (int i = 0; i <= VV_VC_SPEC; i++)
        ob->sh.spec[i] = (float)pow((double)i / VV_VC_SPEC, mt->shininess);
    ob->sh.base[0] = (float)mt->color.x;
    ob->sh.base[1] = (float)mt->color.y;
    ob->sh.base[2] = (float)mt->color.z;
    for (int ch = 0; ch < 3; ch++) {
        ob->sh.amb[ch] = (float)mt->ambient * ambient[ch];
        for (int l = 0; l < fr->n_lights; l++) {
            ob->sh.kd_col[l][ch] = (float)mt->diffuse * fr->lights[l].col[ch];
            ob->sh.ks_col[l][ch] = (float)mt->specular * fr->lights[l].col[ch];
        }
    }
    ob->shading = obj->shading && ob->mesh->m.grad != NULL;
    ob->iso = obj->mode == VV_MODE_ISO
                  ? obj->isovalue
                  : (obj->segmentation == VV_SEG_THRESHOLD ? obj->threshold : obj->isovalue);
    if (ob->mode == VV_MODE_COMPOSITE && obj->segmentation == VV_SEG_THRESHOLD) {
        ob->mode = VV_MODE_ISO; /* a threshold shows the surface where it is reached */
        ob->iso = obj->threshold;
    }
    vv_status ts = tables_build(ob);
    if (ts != VV_OK)
        return ts;
    ob->layer = &ob->mesh->all;
    ob->vis = NULL;
    if (ob->mode == VV_MODE_COMPOSITE && fr->st->skipping) {
        ir_mesh *im = (ir_mesh *)ob->mesh; /* the state's own cache */
        if ((ts = vis_prepare(im, ob)) != VV_OK)
            return ts;
        ob->layer = &im->vis_layer;
        ob->vis = im->vis;
    }
    return VV_OK;
}

static void
obj_clear(ir_obj *ob) {
    free(ob->T);
    free(ob->K);
    free(ob->ext);
    free(ob->col);
}

static vv_status
render_tile(void *user, const vv_frame_tile *t) {
    const ir_frame *fr = user;
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++)
            render_pixel(fr, x, y, fr->out);
    return VV_OK;
}

static int
entry_key_same(const ir_entry_key *a, const ir_entry_key *b) {
    const vv_vec3 *va[6] = {&a->cam.o00, &a->cam.ox, &a->cam.oy,
                            &a->cam.d00, &a->cam.dx, &a->cam.dy};
    const vv_vec3 *vb[6] = {&b->cam.o00, &b->cam.ox, &b->cam.oy,
                            &b->cam.d00, &b->cam.dx, &b->cam.dy};
    for (int i = 0; i < 6; i++)
        if (va[i]->x != vb[i]->x || va[i]->y != vb[i]->y || va[i]->z != vb[i]->z)
            return 0;
    if (a->cam.ortho != b->cam.ortho || a->width != b->width || a->height != b->height ||
        a->layer != b->layer || a->serial != b->serial || a->vis_key != b->vis_key ||
        a->n_planes != b->n_planes || memcmp(a->w2o, b->w2o, sizeof a->w2o) != 0)
        return 0;
    for (int p = 0; p < a->n_planes; p++)
        if (a->planes[p].n.x != b->planes[p].n.x || a->planes[p].n.y != b->planes[p].n.y ||
            a->planes[p].n.z != b->planes[p].n.z || a->planes[p].d != b->planes[p].d)
            return 0;
    return 1;
}

/* Object @p i's first entries: read from the last frame's when its key is
 * this frame's, else searched and stored (within IR_ENTRY_CACHE_MAX for
 * every object: beyond it, searched every frame). */
static void
entries_prepare(ir_frame *fr, int i) {
    ir_obj *ob = &fr->objs[i];
    ir_entry_cache *ec = &fr->st->entries[i];
    ir_entry_key k;
    memset(&k, 0, sizeof k);
    k.cam = fr->cam;
    k.width = fr->view->width;
    k.height = fr->view->height;
    memcpy(k.w2o, ob->w2o, sizeof k.w2o);
    k.layer = ob->layer;
    k.serial = ob->mesh->serial;
    k.vis_key = ob->layer == &ob->mesh->all ? 0 : ob->mesh->vis_key;
    k.n_planes = ob->n_planes;
    memcpy(k.planes, ob->planes, (size_t)ob->n_planes * sizeof k.planes[0]);
    if (ec->valid && ec->e && entry_key_same(&ec->key, &k)) {
        ob->entries = ec->e;
        ob->fill = 0;
        return;
    }
    const size_t n = (size_t)k.width * (size_t)k.height;
    ec->valid = 0;
    ir_entry *e = n * sizeof *e * (size_t)fr->n_obj <= IR_ENTRY_CACHE_MAX
                      ? realloc(ec->e, (n ? n : 1) * sizeof *e)
                      : NULL;
    if (!e) {
        free(ec->e);
        ec->e = NULL;
        return; /* searched every frame */
    }
    ec->e = e;
    ec->key = k;
    ob->entries = e;
    ob->fill = 1;
}

static vv_status
ir_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    ir_state *st = state;
    st->frame++;
    ir_frame fr;
    memset(&fr, 0, sizeof fr);
    fr.st = st;
    fr.view = view;
    vv_camera_rays_init(&fr.cam, view);
    fr.et = st->early_termination;
    float ambient[3];
    vv_frame_colours(w, 0, ambient, fr.bg);
    fr.n_lights = vv_vlights_prepare(fr.lights, w, view);
    for (int l = 0; l < fr.n_lights; l++)
        fr.point_lights |= fr.lights[l].point;
    int n = 0;
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->visible && w->objects[i]->type == VV_OBJECT_GRID && w->objects[i]->grid)
            n++;
    if (n > IR_MAX_OBJ)
        return vv_error_set(VV_ERR_LIMIT, "%d visible grid objects; at most %d are supported", n,
                            IR_MAX_OBJ);
    ir_obj objs[IR_MAX_OBJ];
    fr.objs = objs;
    vv_status s = VV_OK;
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        const vv_object *o = w->objects[i];
        if (!o->visible || o->type != VV_OBJECT_GRID || !o->grid)
            continue;
        s = prepare_object(&fr, &objs[fr.n_obj], o, w, ambient);
        fr.n_obj++;
    }
    for (int i = 0; i < fr.n_obj && s == VV_OK; i++)
        entries_prepare(&fr, i);
    if (s == VV_OK) {
        fr.out = out;
        vv_frame_job job;
        vv_frame_job_init(&job, view->width, view->height, render_tile, &fr);
        s = vv_frame_run(&job, opt);
    }
    /* entries filled by a whole frame serve the next of the same key */
    for (int i = 0; i < fr.n_obj; i++)
        if (objs[i].entries && objs[i].fill)
            st->entries[i].valid = s == VV_OK;
    for (int i = 0; i < fr.n_obj; i++)
        obj_clear(&objs[i]);
    return s;
}

static void
ir_release(void *state) {
    ir_state *st = state;
    for (int i = 0; i < IR_MAX_OBJ; i++) {
        mesh_clear(&st->cache[i]);
        free(st->entries[i].e);
    }
}

/* The options, each bound to its field of ir_state. */
static const vv_option_spec ir_options[] = {
    {"early_termination", VV_OPTION_REAL, "0.99", 0, 1, VV_OPTION_MIN_OPEN, NULL,
     "accumulated opacity that ends a composite ray",
     VV_OPTION_BIND(ir_state, early_termination, DOUBLE)},
    {"empty_space_skipping", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "skip tetrahedra the transfer function hides (0 for tests; same image)",
     VV_OPTION_BIND(ir_state, skipping, INT)},
};

const vv_renderer_ops vv_irregular_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "irregular",
            .description = "cell-by-cell ray casting of irregular grids (grid objects): "
                           "composite (pre-integrated), mip, minip, xray, iso",
            .draws = VV_DRAWS(VV_OBJECT_GRID),
            .modes = VV_MODES_ALL,
            .caps = 0,
            .quality = "ignored: one ray a pixel, every cell crossed",
            .options = ir_options,
            .n_options = VV_OPTIONS_COUNT(ir_options),
        },
    .state_size = sizeof(ir_state),
    .release = ir_release,
    .render = ir_render,
    .render_region = NULL,
};
