/*
 * Volumetric radiosity, setup: the elements of the World -- patches from the
 * geometric objects (their geometry-type records' tessellations,
 * subdivided to the patch size), voxels from the volumes (a resampled grid
 * of extinction, with the surface-like voxels made diffuse), and patches
 * split where a light's shadow boundary crosses them. See radiosity.c.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "render/radiosity/radiosity_internal.h"
#include "volvis/sys/geometry.h"

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

/* The object's resampled grid (at most opt->grid voxels along an axis): its
 * transforms, voxel size and box in @p rv, and per voxel the extinction
 * (rv->sigma), the opacity of one voxel (alpha), the colour (col, 3 per
 * voxel) and the data value (val), through a table of the transfer
 * function (or the threshold). The caller frees alpha, col and val. */
static vv_status
volume_grid(rad_vol *rv, const vv_object *obj, const vv_radiosity_options *opt, float **alpha_out,
            float **col_out, float **val_out) {
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
    /* opacity and colour through a table of the transfer function */
    enum { LUT = 4096 };
    static const int lut_n = LUT;
    float *lut = malloc(4 * (size_t)lut_n * sizeof *lut);
    if (!rv->sigma || !alpha || !col || !val || !lut) {
        free(alpha);
        free(col);
        free(val);
        free(lut);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a %d x %d x %d radiosity grid",
                            rv->n[0], rv->n[1], rv->n[2]);
    }
    const double unit = obj->tf.opacity_unit_distance > 0 ? obj->tf.opacity_unit_distance : 1;
    const double h = rv->h;
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
    *alpha_out = alpha;
    *col_out = col;
    *val_out = val;
    return VV_OK;
}

/* Voxel @p id (grid index ii) of the grid of sizes nn and strides st: the
 * central-difference gradient of the opacity in grad, the data's gradient
 * (oriented like the opacity's) in gv; returns whether a neighbour lets
 * light in (the voxel is exposed). */
static int
voxel_gradients(const float *alpha, const float *val, size_t id, const int ii[3], const int nn[3],
                const size_t st[3], double grad[3], double gv[3]) {
    int exposed = 0;
    for (int ax = 0; ax < 3; ax++) {
        int hm = ii[ax] > 0, hp = ii[ax] + 1 < nn[ax];
        double am = hm ? alpha[id - st[ax]] : 0;
        double ap = hp ? alpha[id + st[ax]] : 0;
        if (nn[ax] > 1 && (am < 0.99 || ap < 0.99))
            exposed = 1;
        grad[ax] = nn[ax] > 1 ? 0.5 * (ap - am) : 0;
    }
    /* the data's gradient, smoother than the opacity's: a 3-D Sobel
     * operator (central differences smoothed 1 2 1 across), whose normals
     * of a voxelized surface err by far less than those of central
     * differences (these showed as rings of the light's cosine near the
     * terminator) */
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
                double vm = val[c0 - (hm ? st[ax] : 0)], vp = val[c0 + (hp ? st[ax] : 0)];
                sum += wgt * (vp - vm) / (hm + hp);
                wsum += wgt;
            }
        }
        gv[ax] = sum / wsum;
    }
    return exposed;
}

/* The voxel elements of a volume object: voxels that intercept light and are
 * not buried in opaque neighbours (those only attenuate); diffuse (with a
 * normal) where they belong to a surface. */
static vv_status
build_volume(builder *b, rad_vol *rv, const vv_object *obj, int obj_index,
             const vv_radiosity_options *opt) {
    rv->obj = obj_index;
    float *alpha = NULL, *col = NULL, *val = NULL;
    vv_status s = volume_grid(rv, obj, opt, &alpha, &col, &val);
    if (s != VV_OK)
        return s;
    const vv_volume *v = obj->volume;
    const double h = rv->h;
    const double lo = v->range[0], hi = v->range[1] > v->range[0] ? v->range[1] : v->range[0] + 1;
    const int nx = rv->n[0], ny = rv->n[1], nz = rv->n[2];
    vv_mat4 g2w = rv->g2w;
    vv_mat4 nrm_m = vv_mat4_transpose(rv->w2g); /* gradients: index -> world */
    for (int k = 0; s == VV_OK && k < nz; k++)
        for (int j = 0; s == VV_OK && j < ny; j++)
            for (int i = 0; i < nx; i++) {
                size_t id = ((size_t)k * ny + j) * nx + i;
                float a = alpha[id];
                if (!(a > 1e-4f))
                    continue;
                const int ii[3] = {i, j, k}, nn[3] = {nx, ny, nz};
                const size_t st[3] = {1, (size_t)nx, (size_t)nx * ny};
                double grad[3], gv[3];
                const int exposed = voxel_gradients(alpha, val, id, ii, nn, st, grad, gv);
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

vv_status
rad_build_elements(builder *b, vv_radiosity *r, const vv_world *w, const vv_radiosity_options *opt,
                   double patch_size, int *obj_lo) {
    vv_status s = VV_OK;
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        const vv_object *o = w->objects[i];
        obj_lo[i] = b->n;
        if (!o->visible)
            continue;
        if (o->type == VV_OBJECT_VOLUME) {
            if (!o->volume)
                continue;
            s = build_volume(b, &r->vols[r->n_vols], o, i, opt);
            r->n_vols++;
        } else if (o->type != VV_OBJECT_PLANE) {
            patch_ctx pc;
            memset(&pc, 0, sizeof pc);
            pc.b = b;
            pc.obj = i;
            pc.size2 = patch_size * patch_size;
            pc.depth_max = 12;
            for (int c = 0; c < 3; c++) {
                pc.rho[c] = o->material.diffuse * (&o->material.color.x)[c];
                pc.emit[c] = (&o->material.emission.x)[c];
            }
            s = tessellate(&pc, o);
        }
    }
    obj_lo[w->n_objects] = b->n;
    return s;
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
        return rad_transmittance(r, l->position, vv_vec3_scale(d, 1 / L), 0, L * (1 - 1e-4));
    }
    vv_vec3 d = vv_vec3_scale(vv_vec3_normalize(l->direction), -1);
    return rad_transmittance(r, p, d, 1e-4 * far_t, far_t);
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
vv_status
rad_shadow_split(vv_radiosity *r, const vv_world *w, double far_t, int *obj_lo) {
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
        int root = rad_build_tree(&nb, lo[o], lo[o + 1]);
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
