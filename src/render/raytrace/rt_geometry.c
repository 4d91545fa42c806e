/*
 * Volumetric ray tracing, the geometry: ray intersections with the
 * geometric primitives and meshes (a BVH), their normals, and the nearest
 * hit among the objects a ray sees.
 */
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/raytrace/rt_internal.h"
#include "render/registry.h"
#include "render/volume_cache.h"
#include "volvis/render.h"

/* ---------------------------------------------------------------------- */
/* Geometry                                                                  */

static inline double
v3get(vv_vec3 v, int a) {
    return a == 0 ? v.x : a == 1 ? v.y : v.z;
}

/* Slab test of an object-space box; returns the entry and exit. */
static int
box_slabs(const float lo[3], const float hi[3], const double o[3], const double inv[3], double tmax,
          double *tn) {
    double t0 = 0, t1 = tmax;
    for (int a = 0; a < 3; a++) {
        double ta = (lo[a] - o[a]) * inv[a], tb = (hi[a] - o[a]) * inv[a];
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
        if (t0 > t1)
            return 0;
    }
    *tn = t0;
    return 1;
}

/* Ray/triangle (Moeller-Trumbore); object space. */
static int
tri_hit(const float *P, const uint32_t *T, uint32_t ti, vv_vec3 o, vv_vec3 d, double tmin,
        double tmax, double *t, vv_vec3 *n) {
    const float *a = P + 3 * (size_t)T[3 * ti], *b = P + 3 * (size_t)T[3 * ti + 1],
                *c = P + 3 * (size_t)T[3 * ti + 2];
    vv_vec3 A = v3(a[0], a[1], a[2]);
    vv_vec3 e1 = v3(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    vv_vec3 e2 = v3(c[0] - a[0], c[1] - a[1], c[2] - a[2]);
    vv_vec3 pv = v3cross(d, e2);
    double det = v3dot(e1, pv);
    if (fabs(det) < 1e-300)
        return 0;
    double id = 1.0 / det;
    vv_vec3 tv = v3sub(o, A);
    double u = v3dot(tv, pv) * id;
    if (u < 0 || u > 1)
        return 0;
    vv_vec3 qv = v3cross(tv, e1);
    double v = v3dot(d, qv) * id;
    if (v < 0 || u + v > 1)
        return 0;
    double tt = v3dot(e2, qv) * id;
    if (!(tt > tmin && tt < tmax))
        return 0;
    *t = tt;
    *n = v3cross(e1, e2);
    return 1;
}

static int
bvh_hit(const rt_bvh *bvh, const vv_mesh *m, vv_vec3 o, vv_vec3 d, double tmin, double tmax,
        double *t, vv_vec3 *n) {
    if (!bvh->n_nodes)
        return 0;
    const double oo[3] = {o.x, o.y, o.z};
    const double inv[3] = {1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
    int stack[128], sp = 0, hit = 0;
    stack[sp++] = 0;
    while (sp) {
        const rt_bvh_node *nd = &bvh->nodes[stack[--sp]];
        double tn;
        if (!box_slabs(nd->lo, nd->hi, oo, inv, tmax, &tn))
            continue;
        if (nd->left < 0) {
            for (int i = 0; i < nd->cnt; i++)
                if (tri_hit(m->positions, m->triangles, bvh->tri[nd->first + i], o, d, tmin, tmax,
                            t, n)) {
                    tmax = *t;
                    hit = 1;
                }
        } else if (sp < 126) {
            stack[sp++] = nd->left;
            stack[sp++] = nd->left + 1;
        }
    }
    return hit;
}

static void
bvh_bounds(const vv_mesh *m, const uint32_t *tri, int first, int cnt, rt_bvh_node *nd, float clo[3],
           float chi[3]) {
    for (int a = 0; a < 3; a++) {
        nd->lo[a] = clo[a] = INFINITY;
        nd->hi[a] = chi[a] = -INFINITY;
    }
    for (int i = first; i < first + cnt; i++)
        for (int a = 0; a < 3; a++) {
            float cen = 0;
            for (int k = 0; k < 3; k++) {
                float x = m->positions[3 * (size_t)m->triangles[3 * (size_t)tri[i] + k] + a];
                nd->lo[a] = x < nd->lo[a] ? x : nd->lo[a];
                nd->hi[a] = x > nd->hi[a] ? x : nd->hi[a];
                cen += x / 3;
            }
            clo[a] = cen < clo[a] ? cen : clo[a];
            chi[a] = cen > chi[a] ? cen : chi[a];
        }
}

static float
tri_centroid(const vv_mesh *m, uint32_t t, int a) {
    float s = 0;
    for (int k = 0; k < 3; k++)
        s += m->positions[3 * (size_t)m->triangles[3 * (size_t)t + k] + a];
    return s / 3;
}

/* Median split on the longest centroid axis, 4 triangles per leaf. Nodes
 * are stored with siblings adjacent (left, left + 1). */
vv_status
rt_bvh_build(rt_bvh *bvh, const vv_mesh *m) {
    memset(bvh, 0, sizeof *bvh);
    if (m->n_triangles == 0)
        return VV_OK;
    if (m->n_triangles > (size_t)1 << 28)
        return vv_error_set(VV_ERR_LIMIT, "mesh of %zu triangles is too large to ray trace",
                            m->n_triangles);
    const int n = (int)m->n_triangles;
    bvh->tri = malloc((size_t)n * sizeof *bvh->tri);
    bvh->nodes = malloc((size_t)(2 * n) * sizeof *bvh->nodes);
    int *stack = malloc((size_t)(2 * n) * sizeof *stack);
    if (!bvh->tri || !bvh->nodes || !stack) {
        free(stack);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a BVH of %d triangles", n);
    }
    for (int i = 0; i < n; i++)
        bvh->tri[i] = (uint32_t)i;
    bvh->n_nodes = 1;
    bvh->nodes[0].first = 0;
    bvh->nodes[0].cnt = n;
    int nt = 0;
    stack[nt++] = 0;
    while (nt) {
        rt_bvh_node *nd = &bvh->nodes[stack[--nt]];
        float clo[3], chi[3];
        bvh_bounds(m, bvh->tri, nd->first, nd->cnt, nd, clo, chi);
        nd->left = -1;
        if (nd->cnt <= 4)
            continue;
        int ax = 0;
        for (int a = 1; a < 3; a++)
            if (chi[a] - clo[a] > chi[ax] - clo[ax])
                ax = a;
        /* partial sort by centroid around the median (quickselect) */
        int lo = nd->first, hi = nd->first + nd->cnt - 1, mid = nd->first + nd->cnt / 2;
        while (lo < hi) {
            float pv = tri_centroid(m, bvh->tri[(lo + hi) / 2], ax);
            int i = lo, j = hi;
            while (i <= j) {
                while (tri_centroid(m, bvh->tri[i], ax) < pv)
                    i++;
                while (tri_centroid(m, bvh->tri[j], ax) > pv)
                    j--;
                if (i <= j) {
                    uint32_t x = bvh->tri[i];
                    bvh->tri[i] = bvh->tri[j];
                    bvh->tri[j] = x;
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
        int l = bvh->n_nodes;
        bvh->n_nodes += 2;
        rt_bvh_node *L = &bvh->nodes[l], *R = &bvh->nodes[l + 1];
        L->first = nd->first;
        L->cnt = mid - nd->first;
        R->first = mid;
        R->cnt = nd->first + nd->cnt - mid;
        nd->left = l;
        stack[nt++] = l;
        stack[nt++] = l + 1;
    }
    free(stack);
    return VV_OK;
}

/* Nearest hit of one geometric object in (tmin, tmax); its object-space
 * normal in *no (not normalised, not flipped towards the ray; gobj_normal
 * turns it into the world normal), or NULL when not needed. */
int
rt_gobj_hit(const rt_gobj *g, const vv_ray *wr, double tmin, double tmax, double *t, vv_vec3 *no) {
    if (g->bounded) {
        /* the ray (t >= 0) misses the bounding sphere: its origin is outside
         * and the sphere lies behind it or off its line */
        const vv_vec3 oc = v3sub(g->bc, wr->origin);
        const double b = v3dot(oc, wr->dir), c = v3dot(oc, oc) - g->br2;
        if (c > 0 && (b <= 0 || b * b < c * v3dot(wr->dir, wr->dir)))
            return 0;
    }
    const vv_geometry *ge = &g->obj->geometry;
    if (g->type == VV_OBJECT_PLANE) {
        /* in world space: the plane's world normal and point, no transform */
        const double dn = v3dot(g->pn, wr->dir);
        if (fabs(dn) < 1e-300)
            return 0;
        const double tp = v3dot(g->pn, v3sub(g->pp, wr->origin)) / dn;
        if (!(tp > tmin && tp < tmax))
            return 0;
        *t = tp;
        if (no)
            *no = ge->normal;
        return 1;
    }
    vv_vec3 o = xf_point(g->w2o, wr->origin), d = xf_dir(g->w2o, wr->dir);
    vv_vec3 n = {0, 0, 1};
    double th = INFINITY;
    switch (g->type) {
    case VV_OBJECT_PLANE: {
        double dn = v3dot(ge->normal, d);
        if (fabs(dn) < 1e-300)
            return 0;
        th = v3dot(ge->normal, v3sub(ge->point, o)) / dn;
        n = ge->normal;
        break;
    }
    case VV_OBJECT_POLYGON: {
        double dn = v3dot(g->plane.n, d);
        if (fabs(dn) < 1e-300)
            return 0;
        th = -vv_plane_distance(g->plane, o) / dn;
        if (!(th > tmin && th < tmax))
            return 0;
        vv_vec3 p = v3add(o, v3scale(d, th));
        const int u = g->drop == 0 ? 1 : 0, v = g->drop == 2 ? 1 : 2;
        const double pu = v3get(p, u), pv = v3get(p, v);
        int inside = 0;
        for (int i = 0, j = ge->n_vertices - 1; i < ge->n_vertices; j = i++) {
            double ui = v3get(ge->vertices[i], u), vi = v3get(ge->vertices[i], v);
            double uj = v3get(ge->vertices[j], u), vj = v3get(ge->vertices[j], v);
            if ((vi > pv) != (vj > pv) && pu < (uj - ui) * (pv - vi) / (vj - vi) + ui)
                inside = !inside;
        }
        if (!inside)
            return 0;
        n = g->plane.n;
        break;
    }
    case VV_OBJECT_SPHERE: {
        vv_vec3 oc = v3sub(o, ge->center);
        double a = v3dot(d, d), b = v3dot(oc, d), c = v3dot(oc, oc) - ge->radius * ge->radius;
        double disc = b * b - a * c;
        if (disc < 0)
            return 0;
        double sq = sqrt(disc);
        double t0 = (-b - sq) / a, t1 = (-b + sq) / a;
        th = t0 > tmin ? t0 : t1;
        if (!(th > tmin && th < tmax))
            return 0;
        n = v3sub(v3add(o, v3scale(d, th)), ge->center);
        break;
    }
    case VV_OBJECT_BOX: {
        const double lo[3] = {ge->box.min.x, ge->box.min.y, ge->box.min.z};
        const double hi[3] = {ge->box.max.x, ge->box.max.y, ge->box.max.z};
        const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
        double t0 = -INFINITY, t1 = INFINITY;
        int a0 = 0, a1 = 0;
        double s0 = -1, s1 = 1;
        for (int a = 0; a < 3; a++) {
            if (fabs(dd[a]) < 1e-300) {
                if (oo[a] < lo[a] || oo[a] > hi[a])
                    return 0;
                continue;
            }
            double ta = (lo[a] - oo[a]) / dd[a], tb = (hi[a] - oo[a]) / dd[a];
            double sa = -1, sb = 1;
            if (ta > tb) {
                double x = ta;
                ta = tb;
                tb = x;
                sa = 1;
                sb = -1;
            }
            if (ta > t0) {
                t0 = ta;
                a0 = a;
                s0 = sa;
            }
            if (tb < t1) {
                t1 = tb;
                a1 = a;
                s1 = sb;
            }
        }
        if (t0 > t1)
            return 0;
        int ax;
        double sg;
        if (t0 > tmin) {
            th = t0;
            ax = a0;
            sg = s0;
        } else {
            th = t1;
            ax = a1;
            sg = s1;
        }
        n = v3(ax == 0 ? sg : 0, ax == 1 ? sg : 0, ax == 2 ? sg : 0);
        break;
    }
    case VV_OBJECT_CYLINDER: {
        vv_vec3 axis = v3sub(ge->top, ge->base);
        double h = v3len(axis);
        if (!(h > 0))
            return 0;
        vv_vec3 a = v3scale(axis, 1.0 / h);
        vv_vec3 oc = v3sub(o, ge->base);
        double da = v3dot(d, a), oa = v3dot(oc, a);
        vv_vec3 dp = v3sub(d, v3scale(a, da)), op = v3sub(oc, v3scale(a, oa));
        double A = v3dot(dp, dp), B = v3dot(op, dp), C = v3dot(op, op) - ge->radius * ge->radius;
        if (A > 1e-300) {
            double disc = B * B - A * C;
            if (disc >= 0) {
                double sq = sqrt(disc);
                double ts[2] = {(-B - sq) / A, (-B + sq) / A};
                for (int i = 0; i < 2; i++) {
                    double z = oa + ts[i] * da;
                    if (ts[i] > tmin && ts[i] < th && z >= 0 && z <= h) {
                        th = ts[i];
                        n = v3add(op, v3scale(dp, ts[i]));
                    }
                }
            }
        }
        if (ge->capped && fabs(da) > 1e-300) {
            for (int i = 0; i < 2; i++) {
                double tc = ((i ? h : 0) - oa) / da;
                if (!(tc > tmin && tc < th))
                    continue;
                vv_vec3 q = v3add(op, v3scale(dp, tc));
                if (v3dot(q, q) <= ge->radius * ge->radius) {
                    th = tc;
                    n = i ? a : v3scale(a, -1);
                }
            }
        }
        break;
    }
    case VV_OBJECT_MESH: {
        if (!ge->mesh || !bvh_hit(&g->bvh, ge->mesh, o, d, tmin, tmax, &th, &n))
            return 0;
        break;
    }
    default:
        return 0;
    }
    if (!(th > tmin && th < tmax))
        return 0;
    *t = th;
    if (no)
        *no = n;
    return 1;
}

/* The world-space unit normal of object-space normal n of g. */
static inline vv_vec3
gobj_normal(const rt_gobj *g, vv_vec3 n) {
    vv_vec3 w = v3(g->nrm[0][0] * n.x + g->nrm[0][1] * n.y + g->nrm[0][2] * n.z,
                   g->nrm[1][0] * n.x + g->nrm[1][1] * n.y + g->nrm[1][2] * n.z,
                   g->nrm[2][0] * n.x + g->nrm[2][1] * n.y + g->nrm[2][2] * n.z);
    return v3norm(w);
}

/* Nearest geometric hit among the objects a ray of this kind sees. */
int
rt_nearest_hit(const rt_frame *fr, const vv_ray *wr, double tmin, double tmax, int primary,
               rt_hit *h) {
    int found = 0;
    for (int i = 0; i < fr->n_gobj; i++) {
        const rt_gobj *g = &fr->gobjs[i];
        if (!primary && !g->obj->visible_in_reflections)
            continue;
        double t;
        vv_vec3 n;
        if (rt_gobj_hit(g, wr, tmin, tmax, &t, &n)) {
            tmax = t;
            h->t = t;
            h->gobj = i;
            h->n = n;
            found = 1;
        }
    }
    if (found) /* the world normal of the nearest hit only */
        h->n = gobj_normal(&fr->gobjs[h->gobj], h->n);
    return found;
}
