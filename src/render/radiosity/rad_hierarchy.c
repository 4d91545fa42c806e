/*
 * Volumetric radiosity, the hierarchy and the geometry of transfers: one
 * binary bounding-volume tree of clusters per object (Hanrahan, Salzman and
 * Aupperle 1991; clusters as in Sillion 1995), point-to-triangle form
 * factors (Lambert's contour integral), and visibility: the nearest patch
 * along a ray and the optical depth through the voxel grids. See
 * radiosity.c.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "render/radiosity/radiosity_internal.h"
#include "volvis/sys/geometry.h"

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

/* Reorders b->e[lo, hi) so that the elements below @p mid come first: with
 * axis >= 0 their centroid's coordinate on that axis, with axis -1 their
 * normal's class; returns the first of the others. */
static int
partition(builder *b, int lo, int hi, int axis, float mid) {
    int i = lo, j = hi - 1;
    while (i <= j) {
        const rad_elem *e = &b->e[i];
        if (axis >= 0 ? e->p[axis] < mid : normal_class(e->n) <= (int)mid) {
            i++;
        } else {
            rad_elem t = b->e[i];
            b->e[i] = b->e[j];
            b->e[j] = t;
            j--;
        }
    }
    return i;
}

/* The subtrees of node @p id over [lo, m) and [m, hi); id, or -1. */
static int
children(builder *b, int id, int lo, int m, int hi) {
    int c0 = rad_build_tree(b, lo, m);
    if (c0 < 0)
        return -1;
    int c1 = rad_build_tree(b, m, hi);
    if (c1 < 0)
        return -1;
    b->nodes[id].child[0] = c0;
    b->nodes[id].child[1] = c1;
    return id;
}

int
rad_build_tree(builder *b, int lo, int hi) {
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
            const int i = partition(b, lo, hi, -1, (kmin + kmax) / 2);
            return children(b, id, lo, i, hi);
        }
    }
    int ax = 0;
    for (int a = 1; a < 3; a++)
        if (cmax[a] - cmin[a] > cmax[ax] - cmin[ax])
            ax = a;
    int m = partition(b, lo, hi, ax, 0.5f * (cmin[ax] + cmax[ax]));
    if (m == lo || m == hi) /* every centroid at one point */
        m = lo + (hi - lo) / 2;
    return children(b, id, lo, m, hi);
}

/* ---------------------------------------------------------------------- */
/* geometry of transfers                                                    */

/* Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom and
 * Strackee 1983). */
double
rad_solid_angle(vv_vec3 a, vv_vec3 b, vv_vec3 c) {
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
double
rad_point_form_factor(vv_vec3 n, vv_vec3 a, vv_vec3 b, vv_vec3 c) {
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
int
rad_sub_points(const float *tri, vv_vec3 *out) {
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
int
rad_box_ray(const float *mn, const float *mx, vv_vec3 o, vv_vec3 d, double *t0, double *t1) {
    const double lo[3] = {mn[0], mn[1], mn[2]}, hi[3] = {mx[0], mx[1], mx[2]};
    const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
    *t0 = -INFINITY;
    *t1 = INFINITY;
    return vv_slab(lo, hi, oo, dd, t0, t1);
}

/* Optical depth along the ray o + t d, t in [t0, t1] (d unit, world),
 * through a voxel grid (piecewise constant extinction, 3-D DDA). Stops
 * once over RAD_TAU_MAX. */
double
rad_grid_tau(const rad_vol *rv, vv_vec3 o, vv_vec3 d, double t0, double t1) {
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
            if (!rad_box_ray(nd->bmin, nd->bmax, o, d, &a, &b) || b < t0 || a > tb)
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
double
rad_transmittance(const vv_radiosity *r, vv_vec3 o, vv_vec3 d, double t0, double t1) {
    if (!(t1 > t0))
        return 1;
    double th;
    if (rad_patch_hit(r, o, d, t0, t1, 1, &th) >= 0)
        return 0;
    double tau = 0;
    for (int i = 0; i < r->n_vols && tau <= RAD_TAU_MAX; i++)
        tau += rad_grid_tau(&r->vols[i], o, d, t0, t1);
    return tau > RAD_TAU_MAX ? 0 : exp(-tau);
}
