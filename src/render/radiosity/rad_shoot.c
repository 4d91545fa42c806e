/*
 * Volumetric radiosity, shooting: the progressive hierarchical solver.
 * A shooter (a light, or a candidate cluster with its unshot power) is
 * refined against the receivers' trees until a transfer is accurate enough
 * (Hanrahan, Salzman and Aupperle 1991), with cluster intensities from the
 * moments of their unshot power and visibility by rays; deposits of one
 * shot are applied together, scaled so that no energy is created. See
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

static int
is_leaf(const rad_node *n) {
    return n->child[0] < 0;
}

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
void
rad_unshot_moments(solver *sv, int id) {
    const vv_radiosity *r = sv->r;
    const rad_node *nd = &r->nodes[id];
    float *u = &sv->u[RAD_U * (size_t)id];
    memset(u, 0, RAD_U * sizeof *u);
    if (!is_leaf(nd)) {
        for (int c = 0; c < 2; c++) {
            rad_unshot_moments(sv, nd->child[c]);
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
            return rad_transmittance(r, p, d, 0, sv->far_t);
        double a, b;
        if (!rad_box_ray(R->bmin, R->bmax, p, d, &a, &b))
            b = 0;
        b = b > 0 ? b : 0;
        if (R->kind == RAD_VOXEL)
            b += voxel_margin(r, R);
        return rad_transmittance(r, p, d, b, sv->far_t);
    }
    vv_vec3 d = vv_vec3_sub(p, xs);
    double L = vv_vec3_length(d);
    if (!(L > 0))
        return 1;
    d = vv_vec3_scale(d, 1 / L);
    double t0 = 0, a, b;
    if (sh->kind == SH_CLUSTER) {
        const rad_node *Sn = &r->nodes[S];
        if (!is_leaf(Sn) && rad_box_ray(Sn->bmin, Sn->bmax, xs, d, &a, &b))
            t0 = b;
        t0 += 1e-4 * L; /* not the shooter's own plane */
        if (Sn->kind == RAD_VOXEL && !(is_leaf(Sn) && elem_diffuse(&r->elems[Sn->lo])))
            t0 += voxel_margin(r, Sn);
    }
    double t1 = L;
    if (!r_off && rad_box_ray(R->bmin, R->bmax, xs, d, &a, &b))
        t1 = a < L ? a : L;
    t1 -= 1e-4 * L; /* not the receiver's own plane */
    if (R->kind == RAD_VOXEL && !r_off)
        t1 -= voxel_margin(r, R);
    if (!(t1 > t0))
        return 1;
    return rad_transmittance(r, xs, d, t0, t1);
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
                double om = rad_solid_angle(a, b, cc) * T;
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
                        np = rad_sub_points(se->tri, pts);
                    for (int k = 0; k < np; k++) {
                        vv_vec3 ak = vv_vec3_sub(f3(e->tri), pts[k]),
                                bk = vv_vec3_sub(f3(e->tri + 3), pts[k]),
                                ck = vv_vec3_sub(f3(e->tri + 6), pts[k]);
                        F0 += rad_point_form_factor(sn, ak, bk, ck) / np;
                        F1 += rad_point_form_factor(vv_vec3_scale(sn, -1), ak, bk, ck) / np;
                    }
                    F0 *= T;
                    F1 *= T;
                    for (int c = 0; c < 3; c++)
                        P[c] = se->unshot[0][c] * F0 + se->unshot[1][c] * F1;
                } else if (diffuse) {
                    double F = rad_point_form_factor(sn, a, b, cc) * T;
                    for (int c = 0; c < 3; c++)
                        P[c] = se->unshot[0][c] * F;
                } else {
                    double om = rad_solid_angle(a, b, cc) * T / (4 * RAD_PI);
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
            g = rad_solid_angle(vv_vec3_sub(f3(e->tri), xs), vv_vec3_sub(f3(e->tri + 3), xs),
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

void
rad_refine(solver *sv, const shooter *sh, int S, int R) {
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
                rad_refine(sv, sh, S, Rn->child[0]);
                rad_refine(sv, sh, S, Rn->child[1]);
            } else {
                rad_refine(sv, sh, Sn->child[0], R);
                rad_refine(sv, sh, Sn->child[1], R);
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
                rad_refine(sv, sh, Sn->child[0], R);
                rad_refine(sv, sh, Sn->child[1], R);
            } else {
                rad_refine(sv, sh, S, Rn->child[0]);
                rad_refine(sv, sh, S, Rn->child[1]);
            }
            return;
        }
    }
    transfer(sv, sh, S, R, -1);
}

/* Applies the shot's deposits, scaled so they never exceed the power shot
 * (shot[c] < 0: no limit). */
void
rad_apply_deposits(solver *sv, const double shot[3], double *cand_unshot) {
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

int
rad_candidate_cut(vv_radiosity *r, int id, int K, int *cands, int n) {
    const rad_node *nd = &r->nodes[id];
    if (nd->hi - nd->lo <= K || is_leaf(nd)) {
        for (int i = nd->lo; i < nd->hi; i++)
            r->elems[i].cand = n;
        cands[n] = id;
        return n + 1;
    }
    n = rad_candidate_cut(r, nd->child[0], K, cands, n);
    return rad_candidate_cut(r, nd->child[1], K, cands, n);
}

double
rad_elem_unshot(const rad_elem *e) {
    double s = 0;
    for (int c = 0; c < 3; c++)
        s += (double)e->unshot[0][c] + e->unshot[1][c];
    return s;
}
