/*
 * Volumetric radiosity: elements, hierarchies and the progressive
 * hierarchical solver (Sobierajski and Kaufman 1994; Cohen et al. 1988;
 * Hanrahan, Salzman and Aupperle 1991). See include/volvis/radiosity.h.
 *
 * Power bookkeeping: every shot of a candidate cluster sends its unshot
 * power; what its receivers intercept is split into absorbed (1 - rho) and
 * scattered (rho, unshot again); the rest is counted as escaped. Deposits of
 * one shot are scaled down if the approximate form factors add up to more
 * than the power shot, so the solver never creates energy.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "model/geometry.h"
#include "render/radiosity/radiosity_internal.h"

#define RAD_PI 3.14159265358979323846
#define RAD_MAX_ELEMS (8 << 20)
#define RAD_VOXEL_OFF 3.0 /* rays to or from a surface voxel start this many voxels off it */
#define RAD_TAU_MAX 12.0  /* transmittance below exp(-12) is taken as 0 */

/* ---------------------------------------------------------------------- */
/* small vector helpers (float storage, double arithmetic)                  */

static vv_vec3
f3(const float *p) {
    return vv_vec3_make(p[0], p[1], p[2]);
}

static void
set3(float *d, vv_vec3 v) {
    d[0] = (float)v.x;
    d[1] = (float)v.y;
    d[2] = (float)v.z;
}

static double
maxc(const double *v) {
    double m = v[0] > v[1] ? v[0] : v[1];
    return m > v[2] ? m : v[2];
}

void
vv_radiosity_options_init(vv_radiosity_options *o) {
    memset(o, 0, sizeof *o);
    o->tolerance = 1e-3;
    o->error = 1e-4;
    o->near = 0.5;
    o->patch_size = 0;
    o->grid = 128;
    o->diffuse_voxels = 1;
    o->max_shots = 20000;
}

/* ---------------------------------------------------------------------- */
/* growing arrays                                                            */

typedef struct builder {
    rad_elem *e;
    int n, cap;
    rad_node *nodes;
    int n_nodes, cap_nodes;
} builder;

static rad_elem *
new_elem(builder *b) {
    if (b->n == b->cap) {
        if (b->cap >= RAD_MAX_ELEMS)
            return NULL;
        int cap = b->cap ? 2 * b->cap : 1024;
        rad_elem *e = realloc(b->e, (size_t)cap * sizeof *e);
        if (!e)
            return NULL;
        b->e = e;
        b->cap = cap;
    }
    rad_elem *e = &b->e[b->n++];
    memset(e, 0, sizeof *e);
    return e;
}

/* ---------------------------------------------------------------------- */
/* patches                                                                   */

typedef struct patch_ctx {
    builder *b;
    int obj;
    double size2; /* squared longest edge allowed */
    double rho[3], emit[3];
    int depth_max;
} patch_ctx;

static vv_status
add_triangle(patch_ctx *pc, vv_vec3 a, vv_vec3 bb, vv_vec3 c, int depth) {
    double e0 = vv_vec3_dot(vv_vec3_sub(bb, a), vv_vec3_sub(bb, a));
    double e1 = vv_vec3_dot(vv_vec3_sub(c, bb), vv_vec3_sub(c, bb));
    double e2 = vv_vec3_dot(vv_vec3_sub(a, c), vv_vec3_sub(a, c));
    double emax = fmax(e0, fmax(e1, e2));
    if (emax > pc->size2 && depth < pc->depth_max) {
        vv_vec3 ab = vv_vec3_scale(vv_vec3_add(a, bb), 0.5);
        vv_vec3 bc = vv_vec3_scale(vv_vec3_add(bb, c), 0.5);
        vv_vec3 ca = vv_vec3_scale(vv_vec3_add(c, a), 0.5);
        vv_status s;
        if ((s = add_triangle(pc, a, ab, ca, depth + 1)) != VV_OK ||
            (s = add_triangle(pc, ab, bb, bc, depth + 1)) != VV_OK ||
            (s = add_triangle(pc, ca, bc, c, depth + 1)) != VV_OK ||
            (s = add_triangle(pc, ab, bc, ca, depth + 1)) != VV_OK)
            return s;
        return VV_OK;
    }
    vv_vec3 cr = vv_vec3_cross(vv_vec3_sub(bb, a), vv_vec3_sub(c, a));
    double area = 0.5 * vv_vec3_length(cr);
    if (!(area > 0))
        return VV_OK; /* degenerate: no element */
    rad_elem *e = new_elem(pc->b);
    if (!e)
        return vv_error_set(VV_ERR_LIMIT, "more than %d elements or out of memory", RAD_MAX_ELEMS);
    vv_vec3 cen = vv_vec3_scale(vv_vec3_add(a, vv_vec3_add(bb, c)), 1.0 / 3);
    set3(e->p, cen);
    set3(e->n, vv_vec3_normalize(cr));
    e->area = (float)area;
    e->kind = RAD_PATCH;
    e->obj = pc->obj;
    set3(e->tri, a);
    set3(e->tri + 3, bb);
    set3(e->tri + 6, c);
    double r = fmax(vv_vec3_length(vv_vec3_sub(a, cen)), fmax(vv_vec3_length(vv_vec3_sub(bb, cen)),
                                                              vv_vec3_length(vv_vec3_sub(c, cen))));
    e->half = (float)r;
    for (int k = 0; k < 3; k++) {
        e->rho[k] = (float)pc->rho[k];
        for (int s = 0; s < 2; s++) {
            e->unshot[s][k] = (float)(pc->emit[k] * area);
            e->total[s][k] = e->unshot[s][k];
        }
    }
    return VV_OK;
}

/* The geometric object's triangles (its geometry-type record's
 * tessellation, 32 segments around a circle), in world coordinates,
 * subdivided into patches. Planes are unbounded (the caller skips them);
 * grids and volumes have no record. */
static vv_status
tessellate(patch_ctx *pc, const vv_object *obj) {
    const vv_geom_type *gt = vv_geom_type_get(obj->type);
    if (!gt)
        return VV_OK;
    const vv_geom_tess opt = {.segments = 32};
    vv_mesh *m = NULL;
    vv_status s = gt->tessellate(&obj->geometry, &opt, &m);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    const vv_mat4 M = vv_object_matrix(obj);
    for (size_t t = 0; s == VV_OK && t < m->n_triangles; t++) {
        const uint32_t *ix = &m->triangles[3 * t];
        s = add_triangle(pc, vv_mat4_mul_point(M, vv_mesh_vertex(m, ix[0])),
                         vv_mat4_mul_point(M, vv_mesh_vertex(m, ix[1])),
                         vv_mat4_mul_point(M, vv_mesh_vertex(m, ix[2])), 0);
    }
    vv_mesh_free(m);
    return s;
}

/* ---------------------------------------------------------------------- */
/* voxel grids                                                               */

static vv_status
build_volume(builder *b, rad_vol *rv, const vv_object *obj, int obj_index,
             const vv_radiosity_options *opt) {
    const vv_volume *v = obj->volume;
    int gmax = opt->grid;
    int dmax = v->dims[0];
    for (int a = 1; a < 3; a++)
        dmax = v->dims[a] > dmax ? v->dims[a] : dmax;
    double f = dmax > gmax ? (double)(dmax - 1) / (gmax - 1) : 1.0;
    double sidx[3];
    for (int a = 0; a < 3; a++) {
        rv->n[a] = v->dims[a] == 1 ? 1 : (int)ceil((v->dims[a] - 1) / f) + 1;
        sidx[a] = rv->n[a] > 1 ? (double)(v->dims[a] - 1) / (rv->n[a] - 1) : 1.0;
    }
    rv->obj = obj_index;
    rv->g2w = vv_mat4_mul(vv_object_index_to_world(obj),
                          vv_mat4_scale(vv_vec3_make(sidx[0], sidx[1], sidx[2])));
    int ok = 0;
    rv->w2g = vv_mat4_inverse(rv->g2w, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
    double det = 0;
    {
        double m[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                m[i][j] = rv->g2w.m[i][j];
        det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
              m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
              m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    }
    rv->h = cbrt(fabs(det));
    vv_box gb = {vv_vec3_make(-0.5, -0.5, -0.5),
                 vv_vec3_make(rv->n[0] - 0.5, rv->n[1] - 0.5, rv->n[2] - 0.5)};
    rv->wbox = vv_box_transform(gb, rv->g2w);
    const size_t nv = (size_t)rv->n[0] * rv->n[1] * rv->n[2];
    rv->sigma = malloc(nv * sizeof *rv->sigma);
    float *alpha = malloc(nv * sizeof *alpha);
    float *col = malloc(3 * nv * sizeof *col);
    float *val = malloc(nv * sizeof *val);
    if (!rv->sigma || !alpha || !col || !val) {
        free(alpha);
        free(col);
        free(val);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a %d x %d x %d radiosity grid",
                            rv->n[0], rv->n[1], rv->n[2]);
    }
    const double unit = obj->tf.opacity_unit_distance > 0 ? obj->tf.opacity_unit_distance : 1;
    const double h = rv->h;
    /* opacity and colour through a table of the transfer function */
    enum { LUT = 4096 };
    static const int lut_n = LUT;
    float *lut = malloc(4 * (size_t)lut_n * sizeof *lut);
    if (!lut) {
        free(alpha);
        free(col);
        free(val);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    const double lo = v->range[0], hi = v->range[1] > v->range[0] ? v->range[1] : v->range[0] + 1;
    for (int i = 0; i < lut_n; i++) {
        double x = lo + (hi - lo) * i / (lut_n - 1);
        double a;
        vv_vec3 c;
        if (obj->segmentation == VV_SEG_THRESHOLD) {
            a = x >= obj->threshold ? 1 : 0;
            c = obj->material.color;
        } else {
            a = vv_tf_eval_opacity(&obj->tf, x);
            c = vv_tf_eval_color(&obj->tf, x);
        }
        a = a < 0 ? 0 : a > 1 - 1e-6 ? 1 - 1e-6 : a;
        lut[4 * i] = (float)(-log(1 - a) / unit);
        lut[4 * i + 1] = (float)c.x;
        lut[4 * i + 2] = (float)c.y;
        lut[4 * i + 3] = (float)c.z;
    }
#pragma omp parallel for schedule(static)
    for (int k = 0; k < rv->n[2]; k++)
        for (int j = 0; j < rv->n[1]; j++)
            for (int i = 0; i < rv->n[0]; i++) {
                size_t id = ((size_t)k * rv->n[1] + j) * rv->n[0] + i;
                double x = vv_volume_sample_index(v, i * sidx[0], j * sidx[1], k * sidx[2]);
                val[id] = (float)x;
                int li = isfinite(x) ? (int)lrint((x - lo) / (hi - lo) * (lut_n - 1)) : 0;
                li = li < 0 ? 0 : li >= lut_n ? lut_n - 1 : li;
                const float *L = &lut[4 * li];
                rv->sigma[id] = L[0];
                alpha[id] = (float)(1 - exp(-L[0] * h));
                col[3 * id] = L[1];
                col[3 * id + 1] = L[2];
                col[3 * id + 2] = L[3];
            }
    free(lut);
    /* elements: voxels that intercept light and are not buried in opaque
     * neighbours (those only attenuate) */
    const int nx = rv->n[0], ny = rv->n[1], nz = rv->n[2];
    vv_mat4 g2w = rv->g2w;
    vv_mat4 nrm_m = vv_mat4_transpose(rv->w2g); /* gradients: index -> world */
    vv_status s = VV_OK;
    for (int k = 0; s == VV_OK && k < nz; k++)
        for (int j = 0; s == VV_OK && j < ny; j++)
            for (int i = 0; i < nx; i++) {
                size_t id = ((size_t)k * ny + j) * nx + i;
                float a = alpha[id];
                if (!(a > 1e-4f))
                    continue;
                const int ii[3] = {i, j, k}, nn[3] = {nx, ny, nz};
                const size_t st[3] = {1, (size_t)nx, (size_t)nx * ny};
                int exposed = 0;
                double grad[3], gv[3];
                for (int ax = 0; ax < 3; ax++) {
                    int hm = ii[ax] > 0, hp = ii[ax] + 1 < nn[ax];
                    double am = hm ? alpha[id - st[ax]] : 0;
                    double ap = hp ? alpha[id + st[ax]] : 0;
                    if (nn[ax] > 1 && (am < 0.99 || ap < 0.99))
                        exposed = 1;
                    grad[ax] = nn[ax] > 1 ? 0.5 * (ap - am) : 0;
                }
                /* the data's gradient, smoother than the opacity's: a 3-D
                 * Sobel operator (central differences smoothed 1 2 1 across),
                 * whose normals of a voxelized surface err by far less than
                 * those of central differences (these showed as rings of
                 * the light's cosine near the terminator) */
                for (int ax = 0; ax < 3; ax++) {
                    int hm = ii[ax] > 0, hp = ii[ax] + 1 < nn[ax];
                    if (!(hm + hp)) {
                        gv[ax] = 0;
                        continue;
                    }
                    const int a1 = (ax + 1) % 3, a2 = (ax + 2) % 3;
                    double sum = 0, wsum = 0;
                    for (int u = -1; u <= 1; u++) {
                        if (ii[a1] + u < 0 || ii[a1] + u >= nn[a1])
                            continue;
                        for (int q = -1; q <= 1; q++) {
                            if (ii[a2] + q < 0 || ii[a2] + q >= nn[a2])
                                continue;
                            double wgt = (u ? 1 : 2) * (q ? 1 : 2);
                            size_t c0 = id + u * (ptrdiff_t)st[a1] + q * (ptrdiff_t)st[a2];
                            double vm = val[c0 - (hm ? st[ax] : 0)],
                                   vp = val[c0 + (hp ? st[ax] : 0)];
                            sum += wgt * (vp - vm) / (hm + hp);
                            wsum += wgt;
                        }
                    }
                    gv[ax] = sum / wsum;
                }
                double dg = gv[0] * grad[0] + gv[1] * grad[1] + gv[2] * grad[2];
                double lv = sqrt(gv[0] * gv[0] + gv[1] * gv[1] + gv[2] * gv[2]);
                {
                    if (lv > 0 && dg != 0)
                        for (int ax = 0; ax < 3; ax++)
                            gv[ax] = (dg > 0 ? 1 : -1) * gv[ax];
                    else
                        memcpy(gv, grad, sizeof gv);
                }
                if (!exposed)
                    continue;
                rad_elem *e = new_elem(b);
                if (!e) {
                    s = vv_error_set(VV_ERR_LIMIT, "more than %d elements or out of memory",
                                     RAD_MAX_ELEMS);
                    break;
                }
                e->kind = RAD_VOXEL;
                e->obj = obj_index;
                e->vox = (int)id;
                set3(e->p, vv_mat4_mul_point(g2w, vv_vec3_make(i, j, k)));
                e->half = (float)(0.5 * h * sqrt(3.0));
                e->area = (float)(h * h * a);
                e->tau = (float)(rv->sigma[id] * h);
                double gl = sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]);
                /* an opaque voxel just under a nearly opaque one is as much
                 * a piece of the surface (its alpha gradient is small, the
                 * data's is not): as an isotropic voxel it would take its
                 * light through its neighbour and show as a dark speckle */
                if (opt->diffuse_voxels &&
                    (gl > 0.05 || (a > 0.5 && dg != 0 && lv > 0.05 * (hi - lo)))) {
                    vv_vec3 gw = vv_mat4_mul_dir(nrm_m, vv_vec3_make(gv[0], gv[1], gv[2]));
                    set3(e->n, vv_vec3_scale(vv_vec3_normalize(gw), -1));
                }
                int diffuse = e->n[0] != 0 || e->n[1] != 0 || e->n[2] != 0;
                for (int c = 0; c < 3; c++) {
                    double rho = obj->material.diffuse * col[3 * id + c];
                    e->rho[c] = (float)rho;
                    /* emission: an opaque emitting region shows material.emission */
                    double em = (&obj->material.emission.x)[c];
                    double p = (diffuse ? 1.0 : 4.0) * em * e->area;
                    e->unshot[0][c] = e->total[0][c] = (float)p;
                }
            }
    free(alpha);
    free(col);
    free(val);
    return s;
}

/* ---------------------------------------------------------------------- */
/* hierarchy: a binary bounding-volume tree per object                      */

static void
elem_box(const rad_elem *e, float *mn, float *mx) {
    if (e->kind == RAD_PATCH) {
        for (int a = 0; a < 3; a++) {
            mn[a] = fminf(e->tri[a], fminf(e->tri[3 + a], e->tri[6 + a]));
            mx[a] = fmaxf(e->tri[a], fmaxf(e->tri[3 + a], e->tri[6 + a]));
        }
    } else {
        float hh = e->half / sqrtf(3.0f);
        for (int a = 0; a < 3; a++) {
            mn[a] = e->p[a] - hh;
            mx[a] = e->p[a] + hh;
        }
    }
}

static int
normal_class(const float *n) {
    int a = fabsf(n[0]) >= fabsf(n[1]) ? (fabsf(n[0]) >= fabsf(n[2]) ? 0 : 2)
                                       : (fabsf(n[1]) >= fabsf(n[2]) ? 1 : 2);
    return 2 * a + (n[a] < 0);
}

static int
build_tree(builder *b, int lo, int hi) {
    if (b->n_nodes == b->cap_nodes) {
        int cap = b->cap_nodes ? 2 * b->cap_nodes : 1024;
        rad_node *n = realloc(b->nodes, (size_t)cap * sizeof *n);
        if (!n)
            return -1;
        b->nodes = n;
        b->cap_nodes = cap;
    }
    int id = b->n_nodes++;
    rad_node nd;
    memset(&nd, 0, sizeof nd);
    nd.lo = lo;
    nd.hi = hi;
    nd.child[0] = nd.child[1] = -1;
    nd.obj = b->e[lo].obj;
    nd.kind = b->e[lo].kind;
    float cmin[3] = {INFINITY, INFINITY, INFINITY}, cmax[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int a = 0; a < 3; a++) {
        nd.bmin[a] = INFINITY;
        nd.bmax[a] = -INFINITY;
    }
    for (int i = lo; i < hi; i++) {
        const rad_elem *e = &b->e[i];
        float mn[3], mx[3];
        elem_box(e, mn, mx);
        for (int a = 0; a < 3; a++) {
            nd.bmin[a] = fminf(nd.bmin[a], mn[a]);
            nd.bmax[a] = fmaxf(nd.bmax[a], mx[a]);
            cmin[a] = fminf(cmin[a], e->p[a]);
            cmax[a] = fmaxf(cmax[a], e->p[a]);
        }
        int diffuse = e->n[0] != 0 || e->n[1] != 0 || e->n[2] != 0;
        if (e->kind == RAD_PATCH) {
            nd.s_pat += e->area;
            for (int a = 0; a < 3; a++)
                nd.m_pat[a] += e->area * e->n[a];
        } else if (diffuse) {
            nd.s_dif += e->area;
            for (int a = 0; a < 3; a++)
                nd.m_dif[a] += e->area * e->n[a];
        } else {
            nd.s_iso += e->area;
        }
        for (int c = 0; c < 3; c++)
            nd.rho_max = fmaxf(nd.rho_max, e->rho[c]);
        nd.thick = fmaxf(nd.thick, e->tau);
    }
    float d2 = 0;
    for (int a = 0; a < 3; a++) {
        nd.c[a] = 0.5f * (nd.bmin[a] + nd.bmax[a]);
        d2 += (nd.bmax[a] - nd.bmin[a]) * (nd.bmax[a] - nd.bmin[a]);
    }
    nd.r = 0.5f * sqrtf(d2);
    if (nd.kind == RAD_VOXEL && hi - lo > 1) {
        /* voxels across the cluster times the densest one's optical depth */
        float h = 2 * b->e[lo].half / sqrtf(3.0f);
        nd.thick *= h > 0 ? 2 * nd.r / h : 1;
    }
    b->nodes[id] = nd;
    if (hi - lo == 1)
        return id;
    if (nd.kind == RAD_PATCH) {
        /* patches facing different ways are not clustered before those
         * facing one way: a cluster's emission is modelled about its
         * normals, which works for one orientation class (6 classes by the
         * dominant axis and sign of the normal) */
        int kmin = 6, kmax = -1;
        for (int i = lo; i < hi; i++) {
            int k = normal_class(b->e[i].n);
            kmin = k < kmin ? k : kmin;
            kmax = k > kmax ? k : kmax;
        }
        if (kmin != kmax) {
            int mid = (kmin + kmax) / 2, i = lo, j = hi - 1;
            while (i <= j) {
                if (normal_class(b->e[i].n) <= mid) {
                    i++;
                } else {
                    rad_elem t = b->e[i];
                    b->e[i] = b->e[j];
                    b->e[j] = t;
                    j--;
                }
            }
            int c0 = build_tree(b, lo, i);
            if (c0 < 0)
                return -1;
            int c1 = build_tree(b, i, hi);
            if (c1 < 0)
                return -1;
            b->nodes[id].child[0] = c0;
            b->nodes[id].child[1] = c1;
            return id;
        }
    }
    int ax = 0;
    for (int a = 1; a < 3; a++)
        if (cmax[a] - cmin[a] > cmax[ax] - cmin[ax])
            ax = a;
    float mid = 0.5f * (cmin[ax] + cmax[ax]);
    int i = lo, j = hi - 1;
    while (i <= j) {
        if (b->e[i].p[ax] < mid) {
            i++;
        } else {
            rad_elem t = b->e[i];
            b->e[i] = b->e[j];
            b->e[j] = t;
            j--;
        }
    }
    int m = i;
    if (m == lo || m == hi) /* every centroid at one point */
        m = lo + (hi - lo) / 2;
    int c0 = build_tree(b, lo, m);
    if (c0 < 0)
        return -1;
    int c1 = build_tree(b, m, hi);
    if (c1 < 0)
        return -1;
    b->nodes[id].child[0] = c0;
    b->nodes[id].child[1] = c1;
    return id;
}

/* ---------------------------------------------------------------------- */
/* geometry of transfers                                                    */

/* Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom and
 * Strackee 1983). */
static double
solid_angle(vv_vec3 a, vv_vec3 b, vv_vec3 c) {
    double la = vv_vec3_length(a), lb = vv_vec3_length(b), lc = vv_vec3_length(c);
    double num = fabs(vv_vec3_dot(a, vv_vec3_cross(b, c)));
    double den =
        la * lb * lc + vv_vec3_dot(a, b) * lc + vv_vec3_dot(a, c) * lb + vv_vec3_dot(b, c) * la;
    double w = 2 * atan2(num, den);
    return w < 0 ? w + 2 * RAD_PI : w;
}

/* Form factor from a differential area at the origin with normal n to the
 * triangle (a, b, c) (positions relative to it), by Lambert's contour
 * integral over the part of the triangle above the tangent plane. */
static double
point_form_factor(vv_vec3 n, vv_vec3 a, vv_vec3 b, vv_vec3 c) {
    vv_vec3 in[3] = {a, b, c}, poly[4];
    int np = 0;
    const double eps = 1e-12;
    for (int i = 0; i < 3; i++) {
        vv_vec3 p = in[i], q = in[(i + 1) % 3];
        double dp = vv_vec3_dot(n, p), dq = vv_vec3_dot(n, q);
        if (dp > eps)
            poly[np++] = p;
        if ((dp > eps) != (dq > eps)) {
            double t = (eps - dp) / (dq - dp);
            poly[np++] = vv_vec3_add(p, vv_vec3_scale(vv_vec3_sub(q, p), t));
        }
    }
    if (np < 3)
        return 0;
    double sum = 0;
    for (int i = 0; i < np; i++) {
        vv_vec3 p = vv_vec3_normalize(poly[i]), q = vv_vec3_normalize(poly[(i + 1) % np]);
        vv_vec3 g = vv_vec3_cross(p, q);
        double gl = vv_vec3_length(g);
        if (!(gl > 0))
            continue;
        double th = atan2(gl, vv_vec3_dot(p, q));
        sum += th * vv_vec3_dot(n, g) / gl;
    }
    return fabs(sum) / (2 * RAD_PI);
}

/* The centroids of the 16 triangles of two midpoint subdivisions of tri. */
static int
sub_points(const float *tri, vv_vec3 *out) {
    vv_vec3 A = f3(tri), B = f3(tri + 3), C = f3(tri + 6);
    int n = 0;
    /* barycentric centroids of the level-2 subdivision: a 4 x 4 grid of
     * upward and downward triangles */
    for (int i = 0; i < 4; i++)
        for (int j = 0; i + j < 4; j++) {
            /* upward triangle (i, j) */
            double u = (i + 1.0 / 3) / 4, v = (j + 1.0 / 3) / 4;
            out[n++] = vv_vec3_add(A, vv_vec3_add(vv_vec3_scale(vv_vec3_sub(B, A), u),
                                                  vv_vec3_scale(vv_vec3_sub(C, A), v)));
            if (i + j < 3) {
                u = (i + 2.0 / 3) / 4;
                v = (j + 2.0 / 3) / 4;
                out[n++] = vv_vec3_add(A, vv_vec3_add(vv_vec3_scale(vv_vec3_sub(B, A), u),
                                                      vv_vec3_scale(vv_vec3_sub(C, A), v)));
            }
        }
    return n;
}

/* Ray parameter range [t0, t1] of a box; 0 on a miss. */
static int
box_ray(const float *mn, const float *mx, vv_vec3 o, vv_vec3 d, double *t0, double *t1) {
    const double lo[3] = {mn[0], mn[1], mn[2]}, hi[3] = {mx[0], mx[1], mx[2]};
    const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
    *t0 = -INFINITY;
    *t1 = INFINITY;
    return vv_slab(lo, hi, oo, dd, t0, t1);
}

/* Optical depth along the ray o + t d, t in [t0, t1] (d unit, world),
 * through a voxel grid (piecewise constant extinction, 3-D DDA). Stops
 * once over RAD_TAU_MAX. */
static double
grid_tau(const rad_vol *rv, vv_vec3 o, vv_vec3 d, double t0, double t1) {
    double a, b;
    vv_ray r = {o, d};
    if (!vv_box_intersect_ray(rv->wbox, r, &a, &b))
        return 0;
    t0 = t0 > a ? t0 : a;
    t1 = t1 < b ? t1 : b;
    if (!(t1 > t0))
        return 0;
    /* trilinear extinction sampled every half voxel: the staircase of
     * nearest-voxel sums would shadow a voxel surface in rings */
    vv_vec3 go = vv_mat4_mul_point(rv->w2g, o), gd = vv_mat4_mul_dir(rv->w2g, d);
    double glen = vv_vec3_length(gd);
    if (!(glen > 0))
        return 0;
    const double dt = 0.5 / glen; /* world length of half a voxel */
    const int nx = rv->n[0], ny = rv->n[1], nz = rv->n[2];
    const size_t sy = (size_t)nx, sz = (size_t)nx * ny;
    double tau = 0;
    for (double t = t0 + 0.5 * dt; t < t1; t += dt) {
        double x = go.x + gd.x * t, y = go.y + gd.y * t, z = go.z + gd.z * t;
        x = x < 0 ? 0 : x > nx - 1 ? nx - 1 : x;
        y = y < 0 ? 0 : y > ny - 1 ? ny - 1 : y;
        z = z < 0 ? 0 : z > nz - 1 ? nz - 1 : z;
        int i = (int)x, j = (int)y, k = (int)z;
        i = i >= nx - 1 ? (nx > 1 ? nx - 2 : 0) : i;
        j = j >= ny - 1 ? (ny > 1 ? ny - 2 : 0) : j;
        k = k >= nz - 1 ? (nz > 1 ? nz - 2 : 0) : k;
        double fx = nx > 1 ? x - i : 0, fy = ny > 1 ? y - j : 0, fz = nz > 1 ? z - k : 0;
        size_t ox = nx > 1 ? 1 : 0, oy = ny > 1 ? sy : 0, oz = nz > 1 ? sz : 0;
        const float *p = &rv->sigma[i + j * sy + k * sz];
        double c00 = p[0] + fx * (p[ox] - p[0]), c10 = p[oy] + fx * (p[oy + ox] - p[oy]);
        double c01 = p[oz] + fx * (p[oz + ox] - p[oz]);
        double c11 = p[oz + oy] + fx * (p[oz + oy + ox] - p[oz + oy]);
        double c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
        double len = t + dt > t1 ? t1 - t + 0.5 * dt : dt;
        tau += (c0 + fz * (c1 - c0)) * (len < dt ? len : dt);
        if (tau > RAD_TAU_MAX)
            return tau;
    }
    return tau;
}

int
rad_patch_hit(const vv_radiosity *r, vv_vec3 o, vv_vec3 d, double t0, double t1, int any,
              double *thit) {
    int best = -1;
    double tb = t1;
    int stack[128];
    for (int ri = 0; ri < r->n_roots; ri++) {
        const rad_node *root = &r->nodes[r->roots[ri]];
        if (root->kind != RAD_PATCH)
            continue;
        int sp = 0;
        stack[sp++] = r->roots[ri];
        while (sp) {
            const rad_node *nd = &r->nodes[stack[--sp]];
            double a, b;
            if (!box_ray(nd->bmin, nd->bmax, o, d, &a, &b) || b < t0 || a > tb)
                continue;
            if (nd->child[0] < 0) {
                const float *tri = r->elems[nd->lo].tri;
                double t, u, v;
                if (vv_ray_triangle3(o, d, vv_v3_f(tri), vv_v3_f(tri + 3), vv_v3_f(tri + 6), &t, &u,
                                     &v) &&
                    t > t0 && t < tb) {
                    tb = t;
                    best = nd->lo;
                    if (any) {
                        *thit = t;
                        return best;
                    }
                }
                continue;
            }
            if (sp + 2 <= 128) {
                /* the nearer child last, so it is taken first */
                const rad_node *c0 = &r->nodes[nd->child[0]], *c1 = &r->nodes[nd->child[1]];
                const double d0 = vv_v3_dot(vv_v3_sub(vv_v3_f(c0->c), o), d);
                const double d1 = vv_v3_dot(vv_v3_sub(vv_v3_f(c1->c), o), d);
                const int n0 = d0 <= d1 ? nd->child[0] : nd->child[1];
                stack[sp++] = n0 == nd->child[0] ? nd->child[1] : nd->child[0];
                stack[sp++] = n0;
            }
        }
    }
    *thit = tb;
    return best;
}

/* Transmittance from o along d over (t0, t1): volumes attenuate, patches block. */
static double
transmittance(const vv_radiosity *r, vv_vec3 o, vv_vec3 d, double t0, double t1) {
    if (!(t1 > t0))
        return 1;
    double th;
    if (rad_patch_hit(r, o, d, t0, t1, 1, &th) >= 0)
        return 0;
    double tau = 0;
    for (int i = 0; i < r->n_vols && tau <= RAD_TAU_MAX; i++)
        tau += grid_tau(&r->vols[i], o, d, t0, t1);
    return tau > RAD_TAU_MAX ? 0 : exp(-tau);
}

/* ---------------------------------------------------------------------- */
/* the solver                                                                */

enum { SH_CLUSTER = 0, SH_POINT = 1, SH_DIRECTIONAL = 2 };

typedef struct shooter {
    int kind;
    vv_vec3 pos, dir; /* point: position; directional: the direction light travels */
    double I[3];      /* point: radiant intensity; directional: irradiance */
} shooter;

typedef struct deposit {
    int e, side;
    float p[3];
} deposit;

typedef struct solver {
    vv_radiosity *r;
    float *u; /* per node: RAD_U floats of unshot power (unshot_moments) */
    deposit *dep;
    size_t n_dep, cap_dep;
    double eps_power;
    double far_t; /* beyond the scene, world units */
    int max_cluster;
    vv_status status;
} solver;

static int
is_leaf(const rad_node *n) {
    return n->child[0] < 0;
}

/* Per node: unshot power of its isotropic voxels (rgb), and of its
 * directional (Lambertian) emitters projected on the six half-axes: an
 * emitter of power U about unit normal n adds U n_a^2 to half-axis (a,
 * sign n_a), so the cluster's intensity sum_a U_a max(0, +-w_a) / pi keeps
 * the power exactly and the direction of axis-aligned emitters exactly. */
#define RAD_U 21

static void
cube_add(float *u, const float *n, const float *p, float sign) {
    for (int a = 0; a < 3; a++) {
        float na = n[a] * sign, wgt = na * na;
        if (!(wgt > 0))
            continue;
        float *cube = &u[3 + 3 * (2 * a + (na < 0))];
        for (int c = 0; c < 3; c++)
            cube[c] += wgt * p[c];
    }
}

/* Unshot power moments of node id's subtree (post-order). */
static void
unshot_moments(solver *sv, int id) {
    const vv_radiosity *r = sv->r;
    const rad_node *nd = &r->nodes[id];
    float *u = &sv->u[RAD_U * (size_t)id];
    memset(u, 0, RAD_U * sizeof *u);
    if (!is_leaf(nd)) {
        for (int c = 0; c < 2; c++) {
            unshot_moments(sv, nd->child[c]);
            const float *uc = &sv->u[RAD_U * (size_t)nd->child[c]];
            for (int k = 0; k < RAD_U; k++)
                u[k] += uc[k];
        }
        return;
    }
    const rad_elem *e = &r->elems[nd->lo];
    if (e->kind == RAD_PATCH) {
        cube_add(u, e->n, e->unshot[0], 1);
        cube_add(u, e->n, e->unshot[1], -1);
    } else if (e->n[0] != 0 || e->n[1] != 0 || e->n[2] != 0) {
        cube_add(u, e->n, e->unshot[0], 1);
    } else {
        for (int c = 0; c < 3; c++)
            u[c] = e->unshot[0][c];
    }
}

static double
unshot_sum(const solver *sv, int id) {
    const float *u = &sv->u[RAD_U * (size_t)id];
    double s = 0;
    for (int k = 0; k < RAD_U; k++)
        s += u[k];
    return s;
}

/* Radiant intensity of shooter node id towards unit direction w. */
static void
node_intensity(const solver *sv, int id, vv_vec3 w, double I[3]) {
    const vv_radiosity *r = sv->r;
    const rad_node *nd = &r->nodes[id];
    if (is_leaf(nd)) {
        const rad_elem *e = &r->elems[nd->lo];
        double cn = vv_vec3_dot(f3(e->n), w);
        for (int c = 0; c < 3; c++) {
            if (e->kind == RAD_PATCH)
                I[c] = (e->unshot[0][c] * fmax(0, cn) + e->unshot[1][c] * fmax(0, -cn)) / RAD_PI;
            else if (e->n[0] != 0 || e->n[1] != 0 || e->n[2] != 0)
                I[c] = e->unshot[0][c] * fmax(0, cn) / RAD_PI;
            else
                I[c] = e->unshot[0][c] / (4 * RAD_PI);
        }
        return;
    }
    const float *u = &sv->u[RAD_U * (size_t)id];
    const double wa[3] = {w.x, w.y, w.z};
    for (int c = 0; c < 3; c++) {
        double v = u[c] / (4 * RAD_PI);
        for (int a = 0; a < 3; a++) {
            v += u[3 + 3 * (2 * a) + c] * fmax(0, wa[a]) / RAD_PI;
            v += u[3 + 3 * (2 * a + 1) + c] * fmax(0, -wa[a]) / RAD_PI;
        }
        I[c] = v;
    }
}

/* Estimated capacity (cross-section) of a receiver node for light travelling w. */
static double
node_capacity(const rad_node *n, vv_vec3 w) {
    vv_vec3 md = vv_vec3_make(n->m_dif[0], n->m_dif[1], n->m_dif[2]);
    vv_vec3 mp = vv_vec3_make(n->m_pat[0], n->m_pat[1], n->m_pat[2]);
    double ld = vv_vec3_length(md), lp = vv_vec3_length(mp);
    double c = n->s_iso;
    c += fmax(0, -vv_vec3_dot(md, w)) + 0.25 * fmax(0, n->s_dif - ld);
    c += fabs(vv_vec3_dot(mp, w)) + 0.5 * fmax(0, n->s_pat - lp);
    return c;
}

static double
elem_capacity(const rad_elem *e, vv_vec3 w, int *side) {
    double cn = vv_vec3_dot(f3(e->n), w);
    *side = 0;
    if (e->kind == RAD_PATCH) {
        *side = cn > 0;
        return e->area * fabs(cn);
    }
    if (e->n[0] != 0 || e->n[1] != 0 || e->n[2] != 0)
        return e->area * fmax(0, -cn);
    return e->area;
}

static void
add_deposit(solver *sv, int e, int side, const double p[3]) {
    if (!(p[0] > 0 || p[1] > 0 || p[2] > 0))
        return;
    if (sv->n_dep == sv->cap_dep) {
        size_t cap = sv->cap_dep ? 2 * sv->cap_dep : 4096;
        deposit *d = realloc(sv->dep, cap * sizeof *d);
        if (!d) {
            sv->status = vv_error_set(VV_ERR_NOMEM, "out of memory");
            return;
        }
        sv->dep = d;
        sv->cap_dep = cap;
    }
    deposit *d = &sv->dep[sv->n_dep++];
    d->e = e;
    d->side = side;
    for (int c = 0; c < 3; c++)
        d->p[c] = (float)p[c];
}

/* How far a visibility ray stays from a voxel node: none for isotropic
 * (fog-like) voxels, whose capacity counts their own attenuation; one voxel
 * for a cluster of mostly surface voxels; three for a single diffuse voxel, a piece of surface
 * whose own capacity already counts its slant (the shell around it would shadow it twice at grazing
 * angles, and it is one-sided, so light through a thin wall from behind
 * finds no capacity). ray_visibility moves a single diffuse voxel's end of
 * the ray off the surface along its normal instead (see there). */
static double voxel_margin(const vv_radiosity *r, const rad_node *n);

/* Size of the voxel grid of object obj (0 for patches). */
static double
voxel_size(const vv_radiosity *r, int obj) {
    for (int i = 0; i < r->n_vols; i++)
        if (r->vols[i].obj == obj)
            return r->vols[i].h;
    return 0;
}

static double
voxel_margin(const vv_radiosity *r, const rad_node *n) {
    double h = voxel_size(r, n->obj);
    if (n->child[0] < 0) {
        const rad_elem *e = &r->elems[n->lo];
        return e->n[0] != 0 || e->n[1] != 0 || e->n[2] != 0 ? 3 * h : 0;
    }
    return n->s_dif > n->s_iso ? h : 0;
}

static int
elem_diffuse(const rad_elem *e) {
    return e->kind == RAD_VOXEL && (e->n[0] != 0 || e->n[1] != 0 || e->n[2] != 0);
}

/* Where the shooter sends from (*xs). */
static vv_vec3
shooter_point(const solver *sv, const shooter *sh, int S) {
    const vv_radiosity *r = sv->r;
    if (sh->kind == SH_POINT)
        return sh->pos;
    const rad_node *Sn = &r->nodes[S];
    return is_leaf(Sn) ? f3(r->elems[Sn->lo].p) : f3(Sn->c);
}

/* Transmittance from the shooter to target point p of receiver R: the ray
 * runs from the shooter's box exit to R's box entry (a cluster's own
 * content is its elements' business), one voxel short of each so that a
 * voxel surface does not shadow itself through its staircase. */
static double
ray_visibility(const solver *sv, const shooter *sh, int S, const rad_node *R, vv_vec3 xs,
               vv_vec3 p) {
    const vv_radiosity *r = sv->r;
    /* a diffuse voxel is a piece of surface: its ray leaves from
     * RAD_VOXEL_OFF voxels off the surface along its normal, outside the shell of its neighbours
     * (stopping short along the ray instead would not leave the shell at
     * grazing angles, and the staircase of the voxel surface would shadow
     * it in speckles and rings near the terminator) */
    int r_off = R->kind == RAD_VOXEL && is_leaf(R) && elem_diffuse(&r->elems[R->lo]);
    if (r_off)
        p = vv_vec3_add(
            p, vv_vec3_scale(f3(r->elems[R->lo].n), RAD_VOXEL_OFF * voxel_size(r, R->obj)));
    if (sh->kind == SH_CLUSTER) {
        const rad_node *Sn = &r->nodes[S];
        if (Sn->kind == RAD_VOXEL && is_leaf(Sn) && elem_diffuse(&r->elems[Sn->lo]))
            xs = vv_vec3_add(
                xs, vv_vec3_scale(f3(r->elems[Sn->lo].n), RAD_VOXEL_OFF * voxel_size(r, Sn->obj)));
    }
    if (sh->kind == SH_DIRECTIONAL) {
        vv_vec3 d = vv_vec3_scale(sh->dir, -1);
        if (r_off)
            return transmittance(r, p, d, 0, sv->far_t);
        double a, b;
        if (!box_ray(R->bmin, R->bmax, p, d, &a, &b))
            b = 0;
        b = b > 0 ? b : 0;
        if (R->kind == RAD_VOXEL)
            b += voxel_margin(r, R);
        return transmittance(r, p, d, b, sv->far_t);
    }
    vv_vec3 d = vv_vec3_sub(p, xs);
    double L = vv_vec3_length(d);
    if (!(L > 0))
        return 1;
    d = vv_vec3_scale(d, 1 / L);
    double t0 = 0, a, b;
    if (sh->kind == SH_CLUSTER) {
        const rad_node *Sn = &r->nodes[S];
        if (!is_leaf(Sn) && box_ray(Sn->bmin, Sn->bmax, xs, d, &a, &b))
            t0 = b;
        t0 += 1e-4 * L; /* not the shooter's own plane */
        if (Sn->kind == RAD_VOXEL && !(is_leaf(Sn) && elem_diffuse(&r->elems[Sn->lo])))
            t0 += voxel_margin(r, Sn);
    }
    double t1 = L;
    if (!r_off && box_ray(R->bmin, R->bmax, xs, d, &a, &b))
        t1 = a < L ? a : L;
    t1 -= 1e-4 * L; /* not the receiver's own plane */
    if (R->kind == RAD_VOXEL && !r_off)
        t1 -= voxel_margin(r, R);
    if (!(t1 > t0))
        return 1;
    return transmittance(r, xs, d, t0, t1);
}

/* Visibility of receiver R: one ray to its centre for an element, five for
 * a cluster (centre and four corners of its box shrunk by half); *spread is
 * the largest difference between them. */
static double
visibility(const solver *sv, const shooter *sh, int S, const rad_node *R, double *spread) {
    vv_vec3 xs = sh->kind == SH_DIRECTIONAL ? f3(R->c) : shooter_point(sv, sh, S);
    *spread = 0;
    if (is_leaf(R) && R->kind == RAD_PATCH && sh->kind != SH_CLUSTER) {
        /* a patch under a light: the mean of rays to the centroids of its
         * four midpoint triangles, so a shadow edge across it is shaded by
         * the part that is lit (not all or nothing) */
        const float *tri = sv->r->elems[R->lo].tri;
        vv_vec3 A = f3(tri), B = f3(tri + 3), C = f3(tri + 6);
        const vv_vec3 q[4] = {
            vv_vec3_scale(vv_vec3_add(A, vv_vec3_add(B, C)), 1.0 / 3),
            vv_vec3_add(vv_vec3_scale(A, 4.0 / 6), vv_vec3_scale(vv_vec3_add(B, C), 1.0 / 6)),
            vv_vec3_add(vv_vec3_scale(B, 4.0 / 6), vv_vec3_scale(vv_vec3_add(A, C), 1.0 / 6)),
            vv_vec3_add(vv_vec3_scale(C, 4.0 / 6), vv_vec3_scale(vv_vec3_add(A, B), 1.0 / 6))};
        double sum = 0;
        for (int k = 0; k < 4; k++)
            sum += ray_visibility(sv, sh, S, R, sh->kind == SH_DIRECTIONAL ? q[k] : xs, q[k]);
        return sum / 4;
    }
    double t = ray_visibility(sv, sh, S, R, xs, f3(R->c));
    if (is_leaf(R))
        return t;
    double tmin = t, tmax = t, sum = t;
    static const int corner[4] = {0, 3, 5, 6};
    for (int i = 0; i < 4; i++) {
        vv_vec3 p;
        double *pp = &p.x;
        for (int a = 0; a < 3; a++)
            pp[a] = R->c[a] + 0.25 * ((corner[i] >> a & 1) ? 1 : -1) * (R->bmax[a] - R->bmin[a]);
        double ti = ray_visibility(sv, sh, S, R, xs, p);
        tmin = ti < tmin ? ti : tmin;
        tmax = ti > tmax ? ti : tmax;
        sum += ti;
    }
    *spread = tmax - tmin;
    return sum / 5;
}

static void
transfer(solver *sv, const shooter *sh, int S, int R, double T_known) {
    vv_radiosity *r = sv->r;
    const rad_node *Rn = &r->nodes[R];
    double spread;
    double T = T_known >= 0 ? T_known : visibility(sv, sh, S, Rn, &spread);
    r->stats.interactions += 1;
    vv_vec3 xs = sh->kind == SH_DIRECTIONAL ? f3(Rn->c) : shooter_point(sv, sh, S), w;
    double dist = 1;
    if (sh->kind == SH_DIRECTIONAL) {
        w = sh->dir;
    } else {
        w = vv_vec3_sub(f3(Rn->c), xs);
        dist = vv_vec3_length(w);
        w = dist > 0 ? vv_vec3_scale(w, 1 / dist) : vv_vec3_make(0, 0, 1);
    }
    if (!(T > 0))
        return;
    const rad_node *Sn = sh->kind == SH_CLUSTER ? &r->nodes[S] : NULL;
    int s_leaf = !Sn || is_leaf(Sn);
    double P[3];
    if (is_leaf(Rn) && r->elems[Rn->lo].kind == RAD_PATCH && s_leaf) {
        const rad_elem *e = &r->elems[Rn->lo];
        vv_vec3 n = f3(e->n);
        int side = vv_vec3_dot(n, w) > 0;
        if (sh->kind == SH_DIRECTIONAL) {
            double g = e->area * fabs(vv_vec3_dot(n, w)) * T;
            for (int c = 0; c < 3; c++)
                P[c] = sh->I[c] * g;
        } else {
            vv_vec3 a = vv_vec3_sub(f3(e->tri), xs), b = vv_vec3_sub(f3(e->tri + 3), xs),
                    cc = vv_vec3_sub(f3(e->tri + 6), xs);
            if (sh->kind == SH_POINT) {
                double om = solid_angle(a, b, cc) * T;
                for (int c = 0; c < 3; c++)
                    P[c] = sh->I[c] * om;
            } else {
                const rad_elem *se = &r->elems[Sn->lo];
                vv_vec3 sn = f3(se->n);
                int diffuse = se->n[0] != 0 || se->n[1] != 0 || se->n[2] != 0;
                if (se->kind == RAD_PATCH) {
                    /* near patches: the form factor averaged over 16 points
                     * of the shooter (it grows fast towards a shared edge) */
                    double F0 = 0, F1 = 0;
                    vv_vec3 pts[16];
                    int np = 1;
                    pts[0] = xs;
                    double reach = 3 * ((double)se->half + e->half);
                    if (vv_vec3_dot(vv_vec3_sub(f3(e->p), xs), vv_vec3_sub(f3(e->p), xs)) <
                        reach * reach)
                        np = sub_points(se->tri, pts);
                    for (int k = 0; k < np; k++) {
                        vv_vec3 ak = vv_vec3_sub(f3(e->tri), pts[k]),
                                bk = vv_vec3_sub(f3(e->tri + 3), pts[k]),
                                ck = vv_vec3_sub(f3(e->tri + 6), pts[k]);
                        F0 += point_form_factor(sn, ak, bk, ck) / np;
                        F1 += point_form_factor(vv_vec3_scale(sn, -1), ak, bk, ck) / np;
                    }
                    F0 *= T;
                    F1 *= T;
                    for (int c = 0; c < 3; c++)
                        P[c] = se->unshot[0][c] * F0 + se->unshot[1][c] * F1;
                } else if (diffuse) {
                    double F = point_form_factor(sn, a, b, cc) * T;
                    for (int c = 0; c < 3; c++)
                        P[c] = se->unshot[0][c] * F;
                } else {
                    double om = solid_angle(a, b, cc) * T / (4 * RAD_PI);
                    for (int c = 0; c < 3; c++)
                        P[c] = se->unshot[0][c] * om;
                }
            }
        }
        add_deposit(sv, Rn->lo, side, P);
        return;
    }
    double I[3];
    if (sh->kind == SH_CLUSTER)
        node_intensity(sv, S, w, I);
    else
        memcpy(I, sh->I, sizeof I);
    /* each element of R takes its share by its own direction and distance
     * from the shooter (the shooter's intensity is that of the cluster) */
    double caps = 0;
    for (int i = Rn->lo; i < Rn->hi; i++) {
        int side;
        caps += elem_capacity(&r->elems[i], w, &side);
    }
    if (!(caps > 0))
        return;
    for (int i = Rn->lo; i < Rn->hi; i++) {
        const rad_elem *e = &r->elems[i];
        vv_vec3 we = w;
        double den = 1;
        if (sh->kind != SH_DIRECTIONAL) {
            vv_vec3 d = vv_vec3_sub(f3(e->p), xs);
            double l2 = vv_vec3_dot(d, d);
            if (!(l2 > 0))
                continue;
            we = vv_vec3_scale(d, 1 / sqrt(l2));
            den = l2;
        }
        int side;
        double cp = elem_capacity(e, we, &side);
        if (!(cp > 0))
            continue;
        double Ie[3];
        if (sh->kind == SH_CLUSTER)
            node_intensity(sv, S, we, Ie);
        else
            memcpy(Ie, I, sizeof Ie);
        double g;
        if (sh->kind == SH_DIRECTIONAL)
            g = cp;
        else if (e->kind == RAD_PATCH) /* the patch's solid angle, exactly */
            g = solid_angle(vv_vec3_sub(f3(e->tri), xs), vv_vec3_sub(f3(e->tri + 3), xs),
                            vv_vec3_sub(f3(e->tri + 6), xs));
        else
            g = cp / (den + cp / RAD_PI); /* keeps adjacent voxels finite */
        for (int c = 0; c < 3; c++)
            P[c] = Ie[c] * T * g;
        add_deposit(sv, i, side, P);
    }
}

static int
ranges_overlap(const rad_node *a, const rad_node *b) {
    return a->lo < b->hi && b->lo < a->hi;
}

static void
refine(solver *sv, const shooter *sh, int S, int R) {
    if (sv->status != VV_OK)
        return;
    vv_radiosity *r = sv->r;
    const rad_node *Rn = &r->nodes[R];
    const rad_node *Sn = sh->kind == SH_CLUSTER ? &r->nodes[S] : NULL;
    if (Sn) {
        if (ranges_overlap(Sn, Rn)) {
            if (S == R && is_leaf(Sn))
                return;
            if (Rn->lo <= Sn->lo && Sn->hi <= Rn->hi && !is_leaf(Rn)) {
                refine(sv, sh, S, Rn->child[0]);
                refine(sv, sh, S, Rn->child[1]);
            } else {
                refine(sv, sh, Sn->child[0], R);
                refine(sv, sh, Sn->child[1], R);
            }
            return;
        }
        if (!(unshot_sum(sv, S) > 0))
            return;
    }
    int s_leaf = !Sn || is_leaf(Sn), r_leaf = is_leaf(Rn);
    if (!(s_leaf && r_leaf)) {
        vv_vec3 xs = sh->kind == SH_POINT ? sh->pos : Sn ? f3(Sn->c) : f3(Rn->c);
        vv_vec3 d = vv_vec3_sub(f3(Rn->c), xs);
        double dist = vv_vec3_length(d);
        vv_vec3 w = sh->kind == SH_DIRECTIONAL ? sh->dir
                    : dist > 0                 ? vv_vec3_scale(d, 1 / dist)
                                               : vv_vec3_make(0, 0, 1);
        double cap = node_capacity(Rn, w);
        if (!(cap > 0))
            return;
        double I[3];
        if (Sn)
            node_intensity(sv, S, w, I);
        else
            memcpy(I, sh->I, sizeof I);
        double rs = Sn ? Sn->r : 0;
        double den = sh->kind == SH_DIRECTIONAL ? 1 : dist * dist + cap / RAD_PI;
        /* error of the receiver's radiosity (reflectance) and, for black
         * receivers, of the power they absorb */
        double est = maxc(I) / den * cap * (0.1 + 0.9 * Rn->rho_max);
        int near = sh->kind != SH_DIRECTIONAL && (rs + Rn->r) > sv->r->opt.near * dist;
        int big =
            (Rn->hi - Rn->lo) > sv->max_cluster || (Sn && (Sn->hi - Sn->lo) > sv->max_cluster);
        /* near pairs of patches always subdivide (the form factor of a
         * cluster from its centre is poor there, towards shared edges
         * most); other near pairs count a hundred times */
        int must = big || (near && Rn->kind == RAD_PATCH && (!Sn || Sn->kind == RAD_PATCH));
        /* direct light on surface voxels goes to each voxel: one ray per
         * cluster cannot tell a voxel surface's self-shadowing near the
         * terminator (speckles) */
        if (!Sn && Rn->kind == RAD_VOXEL && Rn->s_dif > Rn->s_iso)
            must = 1;
        /* optically thick clusters of fog-like voxels count like near ones:
         * their inner voxels are shadowed by the outer ones, which the
         * cluster's single visibility ray does not see */
        if ((!r_leaf && Rn->kind == RAD_VOXEL && Rn->s_iso > Rn->s_dif && Rn->thick > 1) ||
            (Sn && !s_leaf && Sn->kind == RAD_VOXEL && Sn->s_iso > Sn->s_dif && Sn->thick > 1))
            near = 1;
        if (!must && !((near ? 100 * est : est) > sv->eps_power)) {
            /* direct light: a partly shadowed cluster subdivides unless its
             * share is negligible (sharp shadows and terminators) */
            double T = -1, spread = 0;
            if (sh->kind != SH_CLUSTER && !r_leaf)
                T = visibility(sv, sh, S, Rn, &spread);
            /* a patch cluster in a light's partial or full shadow is looked
             * into: its five rays cannot tell a partly lit cluster from a
             * shadowed one (the shadow would take the clusters' shape) */
            int shaded = !Sn && !r_leaf && Rn->kind == RAD_PATCH && T < 1 - 1e-6;
            if (!(spread > 0.1 && est > 1e-3 * sv->eps_power) && !shaded) {
                transfer(sv, sh, S, R, T);
                return;
            }
        }
        /* (not for direct light on patches or surface voxels, whose
         * clusters may be lit where none of the five rays is) */
        if (!r_leaf && !(!Sn && (Rn->kind == RAD_PATCH || Rn->s_dif > Rn->s_iso))) {
            /* nothing of R is visible: no need to look inside */
            double spread;
            double T = visibility(sv, sh, S, Rn, &spread);
            if (!(T > 1e-6) && spread <= 1e-6)
                return;
        }
        {
            if (!s_leaf && (r_leaf || Sn->r > Rn->r || (Sn->hi - Sn->lo) > sv->max_cluster)) {
                refine(sv, sh, Sn->child[0], R);
                refine(sv, sh, Sn->child[1], R);
            } else {
                refine(sv, sh, S, Rn->child[0]);
                refine(sv, sh, S, Rn->child[1]);
            }
            return;
        }
    }
    transfer(sv, sh, S, R, -1);
}

/* Applies the shot's deposits, scaled so they never exceed the power shot
 * (shot[c] < 0: no limit). */
static void
apply_deposits(solver *sv, const double shot[3], double *cand_unshot) {
    vv_radiosity *r = sv->r;
    double sum[3] = {0, 0, 0};
    for (size_t i = 0; i < sv->n_dep; i++)
        for (int c = 0; c < 3; c++)
            sum[c] += sv->dep[i].p[c];
    double sc[3];
    for (int c = 0; c < 3; c++) {
        sc[c] = shot[c] >= 0 && sum[c] > shot[c] ? shot[c] / sum[c] : 1;
        double got = sum[c] * sc[c];
        if (shot[c] >= 0)
            r->stats.power_escaped[c] += shot[c] - got;
        else
            r->stats.power_in[c] += got;
    }
    for (size_t i = 0; i < sv->n_dep; i++) {
        const deposit *d = &sv->dep[i];
        rad_elem *e = &r->elems[d->e];
        double added = 0;
        for (int c = 0; c < 3; c++) {
            double p = d->p[c] * sc[c];
            double s = p * e->rho[c];
            e->absorbed[c] += (float)(p - s);
            r->stats.power_absorbed[c] += p - s;
            e->unshot[d->side][c] += (float)s;
            e->total[d->side][c] += (float)s;
            added += s;
        }
        cand_unshot[e->cand] += added;
    }
    sv->n_dep = 0;
}

static int
candidate_cut(vv_radiosity *r, int id, int K, int *cands, int n) {
    const rad_node *nd = &r->nodes[id];
    if (nd->hi - nd->lo <= K || is_leaf(nd)) {
        for (int i = nd->lo; i < nd->hi; i++)
            r->elems[i].cand = n;
        cands[n] = id;
        return n + 1;
    }
    n = candidate_cut(r, nd->child[0], K, cands, n);
    return candidate_cut(r, nd->child[1], K, cands, n);
}

static double
elem_unshot(const rad_elem *e) {
    double s = 0;
    for (int c = 0; c < 3; c++)
        s += (double)e->unshot[0][c] + e->unshot[1][c];
    return s;
}

static vv_status
check_reflectance(const vv_object *o, vv_vec3 col) {
    const double kd = o->material.diffuse;
    const double v[3] = {kd * col.x, kd * col.y, kd * col.z};
    for (int c = 0; c < 3; c++)
        if (!(v[c] >= 0 && v[c] <= 1))
            return vv_error_set(VV_ERR_INVALID,
                                "object '%s': reflectance (material.diffuse %g * colour %g) = %g "
                                "is outside [0, 1]",
                                o->name, kd, (&col.x)[c], v[c]);
    const double *em = &o->material.emission.x;
    for (int c = 0; c < 3; c++)
        if (!(isfinite(em[c]) && em[c] >= 0))
            return vv_error_set(VV_ERR_INVALID, "object '%s': emission %g is not a power >= 0",
                                o->name, em[c]);
    return VV_OK;
}

static vv_status
check_options(const vv_radiosity_options *o) {
    if (!(o->tolerance > 0 && o->tolerance < 1))
        return vv_error_set(VV_ERR_INVALID, "tolerance %g is not in (0, 1)", o->tolerance);
    if (!(o->error >= 0 && isfinite(o->error)))
        return vv_error_set(VV_ERR_INVALID, "error %g is not a number >= 0", o->error);
    if (!(o->near > 0 && isfinite(o->near)))
        return vv_error_set(VV_ERR_INVALID, "near %g is not a number > 0", o->near);
    if (!(o->patch_size >= 0 || o->patch_size < 0) || !isfinite(o->patch_size))
        return vv_error_set(VV_ERR_INVALID, "patch_size %g is not finite", o->patch_size);
    if (o->grid < 2 || o->grid > 1024)
        return vv_error_set(VV_ERR_INVALID, "grid %d is not in 2..1024", o->grid);
    if (o->max_shots < 1)
        return vv_error_set(VV_ERR_INVALID, "max_shots %d is not >= 1", o->max_shots);
    if (o->levels < 0 || o->levels > 30)
        return vv_error_set(VV_ERR_INVALID, "levels %d is not in 0..30", o->levels);
    return VV_OK;
}

void
vv_radiosity_free(vv_radiosity *r) {
    if (!r)
        return;
    for (int i = 0; i < r->n_vols; i++) {
        free(r->vols[i].sigma);
        free(r->vols[i].rc);
        free(r->vols[i].bmax);
    }
    free(r->vols);
    free(r->elems);
    free(r->nodes);
    free(r->roots);
    free(r);
}

void
vv_radiosity_get_stats(const vv_radiosity *r, vv_radiosity_stats *s) {
    *s = r->stats;
}

vv_status
vv_radiosity_object_power(const vv_radiosity *r, int index, double absorbed[3],
                          double radiated[3]) {
    if (!r || index < 0 || index >= r->n_objects)
        return vv_error_set(VV_ERR_INVALID, "radiosity: object %d out of range", index);
    double a[3] = {0, 0, 0}, t[3] = {0, 0, 0};
    for (int i = 0; i < r->n_elems; i++) {
        const rad_elem *e = &r->elems[i];
        if (e->obj != index)
            continue;
        for (int c = 0; c < 3; c++) {
            a[c] += e->absorbed[c];
            t[c] += (double)e->total[0][c] + e->total[1][c];
        }
    }
    if (absorbed)
        memcpy(absorbed, a, sizeof a);
    if (radiated)
        memcpy(radiated, t, sizeof t);
    return VV_OK;
}

vv_status
vv_radiosity_patch_at(const vv_radiosity *r, int index, vv_vec3 p, vv_vec3 side_normal,
                      double radiosity[3]) {
    int best = -1;
    double bd = INFINITY;
    for (int i = 0; r && i < r->n_elems; i++) {
        const rad_elem *e = &r->elems[i];
        if (e->obj != index || e->kind != RAD_PATCH)
            continue;
        double d = vv_vec3_length(vv_vec3_sub(f3(e->p), p));
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    if (best < 0)
        return vv_error_set(VV_ERR_INVALID, "radiosity: object %d has no patches", index);
    const rad_elem *e = &r->elems[best];
    int side = vv_vec3_dot(f3(e->n), side_normal) < 0;
    for (int c = 0; c < 3; c++)
        radiosity[c] = e->total[side][c] / e->area;
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* shadow boundaries                                                         */

#define RAD_SHADOW_DEPTH 3 /* patches split down to 1/8 of their size */

/* Transmittance from light l to point p (through the current trees). */
static double
light_visibility(const vv_radiosity *r, const vv_light *l, vv_vec3 p, double far_t) {
    if (l->type == VV_LIGHT_POINT) {
        vv_vec3 d = vv_vec3_sub(p, l->position);
        double L = vv_vec3_length(d);
        if (!(L > 0))
            return 1;
        return transmittance(r, l->position, vv_vec3_scale(d, 1 / L), 0, L * (1 - 1e-4));
    }
    vv_vec3 d = vv_vec3_scale(vv_vec3_normalize(l->direction), -1);
    return transmittance(r, p, d, 1e-4 * far_t, far_t);
}

typedef struct split_ctx {
    const vv_radiosity *r;
    const vv_world *w;
    double far_t;
    double min_edge2; /* no split of patches with a shorter longest edge (squared) */
    builder *b;
} split_ctx;

/* Adds patch e (a copy of element tri a b c of parent e) to the builder,
 * split in four while a light's visibility changes across it. */
static vv_status
split_patch(split_ctx *sc, const rad_elem *e, vv_vec3 a, vv_vec3 bb, vv_vec3 c, int depth) {
    vv_vec3 cen = vv_vec3_scale(vv_vec3_add(a, vv_vec3_add(bb, c)), 1.0 / 3);
    int split = 0;
    double e0 = vv_vec3_dot(vv_vec3_sub(bb, a), vv_vec3_sub(bb, a));
    double e1 = vv_vec3_dot(vv_vec3_sub(c, bb), vv_vec3_sub(c, bb));
    double e2 = vv_vec3_dot(vv_vec3_sub(a, c), vv_vec3_sub(a, c));
    int small = fmax(e0, fmax(e1, e2)) < sc->min_edge2;
    for (int li = 0; li < sc->w->n_lights && !split && !small && depth < RAD_SHADOW_DEPTH; li++) {
        const vv_light *l = &sc->w->lights[li];
        if (l->headlight || !(l->intensity > 0))
            continue;
        /* the corners (a hair inside) and the centre */
        const vv_vec3 q[4] = {cen, vv_vec3_add(a, vv_vec3_scale(vv_vec3_sub(cen, a), 1e-3)),
                              vv_vec3_add(bb, vv_vec3_scale(vv_vec3_sub(cen, bb), 1e-3)),
                              vv_vec3_add(c, vv_vec3_scale(vv_vec3_sub(cen, c), 1e-3))};
        double tmin = 1, tmax = 0;
        for (int k = 0; k < 4; k++) {
            double t = light_visibility(sc->r, l, q[k], sc->far_t);
            tmin = t < tmin ? t : tmin;
            tmax = t > tmax ? t : tmax;
        }
        split = tmax - tmin > 0.3;
    }
    if (split) {
        vv_vec3 ab = vv_vec3_scale(vv_vec3_add(a, bb), 0.5);
        vv_vec3 bc = vv_vec3_scale(vv_vec3_add(bb, c), 0.5);
        vv_vec3 ca = vv_vec3_scale(vv_vec3_add(c, a), 0.5);
        vv_status s;
        if ((s = split_patch(sc, e, a, ab, ca, depth + 1)) != VV_OK ||
            (s = split_patch(sc, e, ab, bb, bc, depth + 1)) != VV_OK ||
            (s = split_patch(sc, e, ca, bc, c, depth + 1)) != VV_OK ||
            (s = split_patch(sc, e, ab, bc, ca, depth + 1)) != VV_OK)
            return s;
        return VV_OK;
    }
    rad_elem *d = new_elem(sc->b);
    if (!d)
        return vv_error_set(VV_ERR_LIMIT, "more than %d elements or out of memory", RAD_MAX_ELEMS);
    *d = *e;
    if (depth == 0)
        return VV_OK;
    double area = 0.5 * vv_vec3_length(vv_vec3_cross(vv_vec3_sub(bb, a), vv_vec3_sub(c, a)));
    double f = e->area > 0 ? area / e->area : 0;
    set3(d->p, cen);
    set3(d->tri, a);
    set3(d->tri + 3, bb);
    set3(d->tri + 6, c);
    d->area = (float)area;
    d->half =
        (float)fmax(vv_vec3_length(vv_vec3_sub(a, cen)), fmax(vv_vec3_length(vv_vec3_sub(bb, cen)),
                                                              vv_vec3_length(vv_vec3_sub(c, cen))));
    for (int k = 0; k < 3; k++)
        for (int sd = 0; sd < 2; sd++) {
            d->unshot[sd][k] = (float)(e->unshot[sd][k] * f);
            d->total[sd][k] = (float)(e->total[sd][k] * f);
        }
    return VV_OK;
}

/* Splits the patches across which a light's visibility changes (its shadow
 * boundaries: a patch is lit from its centre or not, so the shadow edge
 * would be the patches' staircase), then rebuilds the trees. obj_lo: the
 * first element of each object, updated. */
static vv_status
shadow_split(vv_radiosity *r, const vv_world *w, double far_t, int *obj_lo) {
    int lights = 0;
    for (int i = 0; i < w->n_lights; i++)
        lights += !w->lights[i].headlight && w->lights[i].intensity > 0;
    int patches = 0;
    for (int i = 0; i < r->n_elems; i++)
        patches += r->elems[i].kind == RAD_PATCH;
    if (!lights || !patches)
        return VV_OK;
    builder nb;
    memset(&nb, 0, sizeof nb);
    /* a shadow edge is no sharper than the voxels of the volumes that cast
     * it: patches are not split into ones smaller than the finest voxel */
    double hmin = INFINITY;
    for (int i = 0; i < r->n_vols; i++)
        hmin = r->vols[i].h < hmin ? r->vols[i].h : hmin;
    double me = isfinite(hmin) ? 2 * hmin : 0;
    split_ctx sc = {r, w, far_t, me * me, &nb};
    vv_status s = VV_OK;
    int *lo = malloc(((size_t)w->n_objects + 1) * sizeof *lo);
    if (!lo)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int o = 0; o < w->n_objects && s == VV_OK; o++) {
        lo[o] = nb.n;
        for (int i = obj_lo[o]; i < obj_lo[o + 1] && s == VV_OK; i++) {
            const rad_elem *e = &r->elems[i];
            if (e->kind == RAD_PATCH) {
                s = split_patch(&sc, e, f3(e->tri), f3(e->tri + 3), f3(e->tri + 6), 0);
            } else {
                rad_elem *d = new_elem(&nb);
                if (!d)
                    s = vv_error_set(VV_ERR_LIMIT, "more than %d elements or out of memory",
                                     RAD_MAX_ELEMS);
                else
                    *d = *e;
            }
        }
    }
    lo[w->n_objects] = nb.n;
    r->n_roots = 0;
    for (int o = 0; o < w->n_objects && s == VV_OK; o++) {
        if (lo[o + 1] == lo[o])
            continue;
        int root = build_tree(&nb, lo[o], lo[o + 1]);
        if (root < 0)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        else
            r->roots[r->n_roots++] = root;
    }
    if (s != VV_OK) {
        free(nb.e);
        free(nb.nodes);
        free(lo);
        return s;
    }
    free(r->elems);
    free(r->nodes);
    r->elems = nb.e;
    r->n_elems = nb.n;
    r->nodes = nb.nodes;
    r->n_nodes = nb.n_nodes;
    memcpy(obj_lo, lo, ((size_t)w->n_objects + 1) * sizeof *lo);
    free(lo);
    return VV_OK;
}

vv_status rad_prepare_render(vv_radiosity *r);

vv_status
vv_radiosity_solve(vv_radiosity **out, const vv_world *w, const vv_radiosity_options *opt_in,
                   const vv_progress *progress) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "radiosity: NULL output");
    *out = NULL;
    if (!w)
        return vv_error_set(VV_ERR_INVALID, "radiosity: NULL World");
    vv_radiosity_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        vv_radiosity_options_init(&opt);
    vv_status s = check_options(&opt);
    if (s != VV_OK)
        return vv_error_prefix(s, "radiosity");
    /* emitters and materials first: bad input is refused before any work */
    double power_ref = 0;
    int n_emit = 0;
    vv_box wb = vv_world_bounds(w);
    double diag = vv_vec3_length(vv_vec3_sub(wb.max, wb.min));
    if (!(diag > 0))
        diag = 1;
    for (int i = 0; i < w->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        if (l->headlight)
            continue;
        const double p[3] = {l->intensity * l->color.x, l->intensity * l->color.y,
                             l->intensity * l->color.z};
        for (int c = 0; c < 3; c++)
            if (!(isfinite(p[c]) && p[c] >= 0))
                return vv_error_set(VV_ERR_INVALID,
                                    "radiosity: light %d: power (intensity %g * colour) is %g, "
                                    "not a finite number >= 0",
                                    i, l->intensity, p[c]);
        if (!(maxc(p) > 0))
            continue;
        n_emit++;
        power_ref += l->type == VV_LIGHT_POINT ? 4 * RAD_PI * maxc(p)
                                               : maxc(p) * RAD_PI * 0.25 * diag * diag;
    }
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o->visible)
            continue;
        vv_vec3 col = o->material.color;
        if (o->type == VV_OBJECT_VOLUME && o->segmentation != VV_SEG_THRESHOLD)
            col = vv_vec3_make(1, 1, 1); /* transfer function colours are in [0, 1] */
        if ((s = check_reflectance(o, col)) != VV_OK)
            return vv_error_prefix(s, "radiosity");
        if (o->material.emission.x > 0 || o->material.emission.y > 0 || o->material.emission.z > 0)
            n_emit++;
        if (o->type == VV_OBJECT_VOLUME && opt.levels > 0) {
            int dmax = 1;
            for (int a = 0; a < 3; a++)
                dmax = o->volume->dims[a] > dmax ? o->volume->dims[a] : dmax;
            dmax = dmax < opt.grid ? dmax : opt.grid;
            int lv = 1;
            while ((1 << (lv - 1)) < dmax)
                lv++;
            if (opt.levels > lv)
                return vv_error_set(VV_ERR_INVALID,
                                    "radiosity: levels %d is beyond the %d levels of object "
                                    "'%s' (%d voxels along its longest axis)",
                                    opt.levels, lv, o->name, dmax);
        }
    }
    if (n_emit == 0)
        return vv_error_set(VV_ERR_INVALID,
                            "radiosity: the World has no emitter (no point or directional light "
                            "other than a headlight, no object with material.emission)");
    vv_radiosity *r = calloc(1, sizeof *r);
    if (!r)
        return vv_error_set(VV_ERR_NOMEM, "radiosity: out of memory");
    r->opt = opt;
    r->n_objects = w->n_objects;
    builder b;
    memset(&b, 0, sizeof b);
    solver sv;
    memset(&sv, 0, sizeof sv);
    int *cands = NULL;
    double *cand_unshot = NULL;
    int *obj_lo = calloc((size_t)w->n_objects + 1, sizeof *obj_lo);
    r->vols = calloc((size_t)w->n_objects + 1, sizeof *r->vols);
    r->roots = calloc((size_t)w->n_objects + 1, sizeof *r->roots);
    if (!obj_lo || !r->vols || !r->roots) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto fail;
    }
    const double psize = opt.patch_size > 0 ? opt.patch_size : diag / 48;
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        const vv_object *o = w->objects[i];
        obj_lo[i] = b.n;
        if (!o->visible)
            continue;
        if (o->type == VV_OBJECT_VOLUME) {
            if (!o->volume)
                continue;
            s = build_volume(&b, &r->vols[r->n_vols], o, i, &opt);
            r->n_vols++;
        } else if (o->type != VV_OBJECT_PLANE) {
            patch_ctx pc;
            memset(&pc, 0, sizeof pc);
            pc.b = &b;
            pc.obj = i;
            pc.size2 = psize * psize;
            pc.depth_max = 12;
            for (int c = 0; c < 3; c++) {
                pc.rho[c] = o->material.diffuse * (&o->material.color.x)[c];
                pc.emit[c] = (&o->material.emission.x)[c];
            }
            s = tessellate(&pc, o);
        }
    }
    obj_lo[w->n_objects] = b.n;
    if (s != VV_OK)
        goto fail;
    for (int i = 0; i < w->n_objects; i++) {
        if (obj_lo[i + 1] == obj_lo[i])
            continue;
        int root = build_tree(&b, obj_lo[i], obj_lo[i + 1]);
        if (root < 0) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
            goto fail;
        }
        r->roots[r->n_roots++] = root;
    }
    r->elems = b.e;
    r->n_elems = b.n;
    r->nodes = b.nodes;
    r->n_nodes = b.n_nodes;
    b.e = NULL;
    b.nodes = NULL;
    if ((s = shadow_split(r, w, 4 * diag + 1e-9, obj_lo)) != VV_OK)
        goto fail;
    r->stats.n_nodes = r->n_nodes;
    int n_emitters = 0;
    for (int i = 0; i < r->n_elems; i++) {
        if (r->elems[i].kind == RAD_PATCH)
            r->stats.n_patches++;
        else
            r->stats.n_voxels++;
        for (int c = 0; c < 3; c++)
            r->stats.power_in[c] += (double)r->elems[i].unshot[0][c] + r->elems[i].unshot[1][c];
    }
    for (int i = 0; i < w->n_lights; i++)
        n_emitters += !w->lights[i].headlight;
    {
        double ne = (double)r->n_elems + n_emitters;
        r->stats.pairwise = ne * ne;
    }
    /* shooting candidates: a cut through the hierarchies, about 256 clusters */
    cands = malloc(((size_t)r->n_elems + 1) * sizeof *cands);
    cand_unshot = calloc((size_t)r->n_elems + 1, sizeof *cand_unshot);
    sv.u = calloc(RAD_U * ((size_t)r->n_nodes + 1), sizeof *sv.u);
    if (!cands || !cand_unshot || !sv.u) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto fail;
    }
    int K = r->n_elems / 256 > 1 ? r->n_elems / 256 : 1;
    int n_cands = 0;
    for (int i = 0; i < r->n_roots; i++)
        n_cands = candidate_cut(r, r->roots[i], K, cands, n_cands);
    for (int i = 0; i < r->n_elems; i++)
        cand_unshot[r->elems[i].cand] += elem_unshot(&r->elems[i]);
    sv.r = r;
    sv.status = VV_OK;
    sv.far_t = 4 * diag + 1e-9;
    {
        /* levels: clusters of at most 8^(levels-1) elements interact */
        double mc = opt.levels > 0 ? pow(8.0, opt.levels - 1) : 2e9;
        sv.max_cluster = mc > 2e9 ? 2000000000 : (int)mc;
    }
    /* lights shoot first, once */
    for (int i = 0; i < w->n_lights && sv.status == VV_OK; i++) {
        const vv_light *l = &w->lights[i];
        if (l->headlight)
            continue;
        shooter sh;
        memset(&sh, 0, sizeof sh);
        sh.kind = l->type == VV_LIGHT_POINT ? SH_POINT : SH_DIRECTIONAL;
        sh.pos = l->position;
        sh.dir = vv_vec3_normalize(l->direction);
        sh.I[0] = l->intensity * l->color.x;
        sh.I[1] = l->intensity * l->color.y;
        sh.I[2] = l->intensity * l->color.z;
        if (!(maxc(sh.I) > 0))
            continue;
        if (sh.kind == SH_DIRECTIONAL && !(vv_vec3_length(sh.dir) > 0))
            continue;
        {
            /* refinement bound: relative to what reaches the scene */
            double R = 0.5 * diag;
            vv_vec3 cen = vv_vec3_scale(vv_vec3_add(wb.min, wb.max), 0.5);
            double d = vv_vec3_length(vv_vec3_sub(sh.pos, cen));
            double om = d > R ? fmin(4 * RAD_PI, RAD_PI * R * R / (d * d)) : 4 * RAD_PI;
            sv.eps_power = opt.error * maxc(sh.I) * (sh.kind == SH_POINT ? om : RAD_PI * R * R);
        }
        for (int j = 0; j < r->n_roots; j++)
            refine(&sv, &sh, -1, r->roots[j]);
        double shot[3];
        for (int c = 0; c < 3; c++) {
            shot[c] = sh.kind == SH_POINT ? 4 * RAD_PI * sh.I[c] : -1;
            if (sh.kind == SH_POINT)
                r->stats.power_in[c] += shot[c];
        }
        apply_deposits(&sv, shot, cand_unshot);
    }
    if (sv.status != VV_OK) {
        s = sv.status;
        goto fail;
    }
    /* the power the scene holds after the lights shot: tolerance and
     * refinement are relative to it (most of a light's power may miss) */
    double pin =
        r->stats.power_absorbed[0] + r->stats.power_absorbed[1] + r->stats.power_absorbed[2];
    for (int i = 0; i < n_cands; i++)
        pin += cand_unshot[i];
    sv.eps_power = opt.error * pin;
    shooter cl;
    memset(&cl, 0, sizeof cl);
    cl.kind = SH_CLUSTER;
    for (;;) {
        double left = 0;
        int best = -1;
        for (int i = 0; i < n_cands; i++) {
            left += cand_unshot[i];
            if (best < 0 || cand_unshot[i] > cand_unshot[best])
                best = i;
        }
        if (!(pin > 0) || best < 0 || left <= opt.tolerance * pin || !(cand_unshot[best] > 0)) {
            r->stats.converged = 1;
            break;
        }
        if (r->stats.n_shots >= opt.max_shots)
            break;
        if (progress && progress->fn && (r->stats.n_shots & 7) == 0) {
            double f = log(left / pin) / log(opt.tolerance);
            f = f < 0 ? 0 : f > 1 ? 1 : f;
            if (vv_progress_report(progress, f)) {
                s = vv_error_set(VV_ERR_CANCELLED,
                                 "radiosity: cancelled with %.3g %% of the power left unshot",
                                 100 * left / pin);
                goto fail;
            }
        }
        int S = cands[best];
        unshot_moments(&sv, S);
        double shot[3] = {0, 0, 0};
        const rad_node *Sn = &r->nodes[S];
        for (int i = Sn->lo; i < Sn->hi; i++)
            for (int c = 0; c < 3; c++)
                shot[c] += (double)r->elems[i].unshot[0][c] + r->elems[i].unshot[1][c];
        for (int j = 0; j < r->n_roots; j++)
            refine(&sv, &cl, S, r->roots[j]);
        if (sv.status != VV_OK) {
            s = sv.status;
            goto fail;
        }
        /* the candidate's power is shot: clear it before its receivers
         * (itself among them) get theirs */
        for (int i = Sn->lo; i < Sn->hi; i++)
            memset(r->elems[i].unshot, 0, sizeof r->elems[i].unshot);
        cand_unshot[best] = 0;
        apply_deposits(&sv, shot, cand_unshot);
        r->stats.n_shots++;
    }
    for (int i = 0; i < r->n_elems; i++)
        for (int c = 0; c < 3; c++)
            r->stats.power_unshot[c] += (double)r->elems[i].unshot[0][c] + r->elems[i].unshot[1][c];
    s = rad_prepare_render(r);
    if (s != VV_OK)
        goto fail;
    free(obj_lo);
    free(cands);
    free(cand_unshot);
    free(sv.u);
    free(sv.dep);
    *out = r;
    return VV_OK;
fail:
    free(b.e);
    free(b.nodes);
    free(obj_lo);
    free(cands);
    free(cand_unshot);
    free(sv.u);
    free(sv.dep);
    vv_radiosity_free(r);
    return s;
}
