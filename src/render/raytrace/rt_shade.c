/*
 * Volumetric ray tracing, lighting: shadow rays through geometry and
 * volumes, the lazily filled shadow grids of volume samples, the light
 * volumes' cache and lookups (their sweeps: rt_light.c), and Phong shading
 * with those shadows for volume samples and geometric surfaces (with the
 * reflected and transmitted rays they spawn).
 */
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/ray.h"
#include "render/raytrace/rt_internal.h"
#include "render/registry.h"
#include "render/sample.h"
#include "render/shade.h"
#include "volvis/render.h"

/* ---------------------------------------------------------------------- */
/* Shadow rays                                                               */

/* Trilinear interpolation of a cell's eight corners v (x fastest, then y,
 * then z) at fractions f. */
static inline float
cell_lerp(const float v[8], const float f[3]) {
    const float x0 = vv_lerpf(v[0], v[1], f[0]), x1 = vv_lerpf(v[2], v[3], f[0]);
    const float x2 = vv_lerpf(v[4], v[5], f[0]), x3 = vv_lerpf(v[6], v[7], f[0]);
    return vv_lerpf(vv_lerpf(x0, x1, f[1]), vv_lerpf(x2, x3, f[1]), f[2]);
}

/* This volume's own transmittance towards light l from index point p: its
 * light volume, interpolated trilinearly. A point light's holds the mean
 * extinction s_i of each grid point's way to the light; each corner then
 * gives the transmittance exp(-s_i r) over the query's own distance r to the
 * light, and those are interpolated: exact in a constant medium (where the
 * transmittance itself is curved across the grid by the light's distance),
 * and linear in the transmittance at shadow edges, as the directional
 * lights' are. */
static float
light_volume_at(const rt_vobj *ob, int l, const float p[3], float r) {
    float f[3];
    int i0[3];
    for (int a = 0; a < 3; a++) {
        float x = p[a] * (1.0f / RT_LGRID);
        x = x < 0 ? 0 : x > (float)(ob->ldim[a] - 1) ? (float)(ob->ldim[a] - 1) : x;
        int i = (int)x;
        i = i > ob->ldim[a] - 2 ? ob->ldim[a] - 2 : i;
        i0[a] = i;
        f[a] = x - (float)i;
    }
    const size_t sy = (size_t)ob->ldim[0], sz = sy * (size_t)ob->ldim[1];
    const float *v = ob->lvol[l] + (size_t)i0[2] * sz + (size_t)i0[1] * sy + (size_t)i0[0];
    float c[8] = {v[0], v[1], v[sy], v[sy + 1], v[sz], v[sz + 1], v[sz + sy], v[sz + sy + 1]};
    if (r > 0)
        for (int k = 0; k < 8; k++)
            c[k] = expf(-c[k] * r);
    return cell_lerp(c, f);
}

float
rt_composite_march(const rt_frame *fr, const rt_vobj *ob, const vv_vray *r, const vv_vcache *c,
                   const float o[3], const rt_vobj *tab) {
    /* exp(-sum sigma h): each visible subvolume's piece of the ray is cut
     * into equal parts no longer than dt, sampled at their midpoints */
    const double dt = fr->dt;
    const double ds = 2 * ob->vox > dt ? 2 * ob->vox : dt; /* shadows are smooth */
    const float z[3] = {0, 0, 0};
    const float *off = o ? o : z;
    double tau = 0;
    double t = r->t0;
    while (t < r->t1) {
        float p[3];
        vv_vray_point(r, t, p);
        /* in memory, the PARC flags and distances; through a box, every subvolume */
        const size_t b = o ? 0 : vv_vcache_block(c, p);
        double te = !o && ob->bdist[b] ? leap_exit(ob, r, p, t, ob->bdist[b]) : block_exit(r, p, t);
        te = te < r->t1 ? te : r->t1;
        if (o || ob->bvis[b]) {
            const double len = te - t;
            int n = (int)vv_ceil_pos(len / ds);
            n = n < 1 ? 1 : n;
            const double h = len / n;
            for (int s = 0; s < n; s++) {
                float q[3];
                vv_vray_point(r, t + (s + 0.5) * h, q);
                for (int a = 0; a < 3; a++)
                    q[a] -= off[a];
                tau += tab->ext[(int)lut_index_f(tab, vv_vcache_sample(c, q))] * h;
            }
            if (tau > 5.6) /* T < 0.0037, under one 8-bit level */
                return 0.0f;
        }
        t = te;
    }
    return (float)exp(-tau);
}

/* Transmittance of one volume along the world ray over (tmin, tmax).
 * light >= 0: the ray is a whole shadow ray towards that light (tmax
 * infinite for a directional light, the light's distance for a point
 * light), answered from the light volume where there is one. */
static float
volume_transmittance(const rt_frame *fr, const rt_vobj *ob, const vv_ray *wr, double tmin,
                     double tmax, int light) {
    vv_vray r;
    if (!vray_setup(ob, wr, tmin, tmax, &r))
        return 1.0f;
    const vv_vcache *c = ob->c;
    const double dt = fr->dt;
    if (light >= 0 && ob->lvol[light]) {
        /* r.o: where the ray enters, at r.t0; a point light's distance from there */
        const rt_light *lt = &fr->lights[light];
        const float dist =
            lt->point
                ? (float)v3len(v3sub(v3(lt->pos[0], lt->pos[1], lt->pos[2]), ray_at(wr, r.t0)))
                : 0.0f;
        return light_volume_at(ob, light, r.o, dist);
    }
    if (ob->mode == VV_MODE_COMPOSITE)
        return rt_composite_march(fr, ob, &r, c, NULL, ob);
    if (ob->mode == VV_MODE_ISO) {
        /* blocked where the ray is inside the surface (value >= isovalue) */
        double t = r.t0;
        while (t <= r.t1) {
            float p[3];
            vv_vray_point(&r, t, p);
            const size_t b = vv_vcache_block(ob->c, p);
            double te = ob->bdist[b] ? leap_exit(ob, &r, p, t, ob->bdist[b]) : block_exit(&r, p, t);
            if (ob->bvis[b]) {
                double tl = te < r.t1 ? te : r.t1;
                for (double ts = t; ts <= tl; ts += dt) {
                    vv_vray_point(&r, ts, p);
                    if (vv_vcache_sample(c, p) >= ob->iso)
                        return 0.0f;
                }
                vv_vray_point(&r, tl, p);
                if (vv_vcache_sample(c, p) >= ob->iso)
                    return 0.0f;
            }
            t = te;
        }
        return 1.0f;
    }
    /* projections: one minus the opacity of the projected value (attenuated
     * MIP: napari's, along the shadow ray from where it enters the volume) */
    if (ob->mode == VV_MODE_ATTENUATED_MIP) {
        float val, d;
        vv_vray_attenuated_mip(c, &r, dt, &ob->att, &val, &d);
        return val == val ? 1.0f - ob->lut[4 * (int)lut_index_f(ob, val)] : 1.0f;
    }
    const int mip = ob->mode == VV_MODE_MIP, minip = ob->mode == VV_MODE_MINIP;
    float best = mip ? -INFINITY : INFINITY;
    double sum = 0;
    long cnt = 0;
    for (double t = r.t0; t <= r.t1; t += dt) {
        float p[3];
        vv_vray_point(&r, t, p);
        float x = vv_vcache_sample(c, p);
        if (mip)
            best = x > best ? x : best;
        else if (minip)
            best = x < best ? x : best;
        sum += x;
        cnt++;
    }
    if (!cnt)
        return 1.0f;
    float val = mip || minip ? best : (float)(sum / (double)cnt);
    return 1.0f - ob->lut[4 * (int)lut_index_f(ob, val)];
}

/* Transmittance from world point p towards light l over [start, limit]
 * world units from p (limit INFINITY: up to the light), past every object
 * that casts shadows. */
float
rt_shadow_segment(const rt_frame *fr, vv_vec3 p, const rt_light *l, double start, double limit) {
    vv_ray r;
    double tmax;
    if (l->point) {
        vv_vec3 d = v3sub(v3(l->pos[0], l->pos[1], l->pos[2]), p);
        tmax = v3len(d);
        if (!(tmax > 0))
            return 1.0f;
        r.dir = v3scale(d, 1.0 / tmax);
    } else {
        r.dir = v3(l->dir[0], l->dir[1], l->dir[2]);
        tmax = INFINITY;
    }
    /* a whole shadow ray towards a light: light volumes answer it */
    const int light = limit == INFINITY ? (int)(l - fr->lights) : -1;
    tmax = limit < tmax ? limit : tmax;
    r.origin = p;
    float T = 1.0f;
    const double eps = RT_EPS * fr->scene_size;
    for (int i = 0; i < fr->n_gobj && T > 0; i++) {
        const rt_gobj *g = &fr->gobjs[i];
        if (!g->obj->casts_shadows)
            continue;
        double t;
        if (rt_gobj_hit(g, &r, start > eps ? start : eps, tmax, &t, NULL))
            T *= g->kt;
    }
    for (int i = 0; i < fr->n_vobj && T > 0.0037f; i++) {
        const rt_vobj *ob = &fr->vobjs[i];
        if (ob->obj->casts_shadows && !ob->region)
            T *= volume_transmittance(fr, ob, &r, start, tmax, light);
    }
    return T;
}

float
rt_volume_march(const rt_frame *fr, const rt_vobj *ob, vv_vec3 wp, vv_vec3 ldir, double tmax) {
    return volume_transmittance(fr, ob, &(vv_ray){wp, ldir}, 0, tmax, -1);
}

static float
shadow_ray(const rt_frame *fr, vv_vec3 p, const rt_light *l, double start) {
    return rt_shadow_segment(fr, p, l, start, INFINITY);
}

/* The shadow grid of directional light l for the volume's own samples
 * (shadow_grid=2): swept through every object that casts shadows, unless
 * ob->sweep[l] holds one kept from an earlier frame. */
vv_status
rt_sweep_light(const rt_frame *fr, rt_vobj *ob, int l, int nt) {
    vv_status s = ob->sweep[l] ? VV_OK : rt_sweep_shadow_grid(fr, ob, l, nt, &ob->sweep[l]);
    for (int a = 0; a < 3; a++)
        ob->lidx[l][a] =
            (float)(ob->w2i[a][0] * fr->lights[l].dir[0] + ob->w2i[a][1] * fr->lights[l].dir[1] +
                    ob->w2i[a][2] * fr->lights[l].dir[2]);
    return s;
}

/* The light volume of a composite volume for light l: its own
 * transmittance towards the light from every point of a grid RT_LGRID
 * voxels apart, swept layer by layer from the light's side (a directional
 * light, sweep_grid) or in order of distance to it (a point light,
 * sweep_point). Whole shadow rays towards the light then cross the volume
 * in one lookup where they enter it (light_volume_at). */
static int
lv_matches(const rt_lv *e, const rt_frame *fr, const rt_vobj *ob, int l) {
    if (e->vol != ob->obj->volume || e->modified != ob->obj->volume->modified || e->dt != fr->dt ||
        e->n_planes != ob->n_planes || e->lut_lo != ob->tab.lut_lo ||
        e->lut_scale != ob->tab.lut_scale)
        return 0;
    const rt_light *lt = &fr->lights[l];
    if (e->point != lt->point)
        return 0;
    for (int a = 0; a < 3; a++)
        if (lt->point ? e->pos[a] != lt->pos[a] : e->dir[a] != lt->dir[a])
            return 0;
    const vv_volume *wh = ob->whole ? ob->whole->header : NULL;
    if (e->whole != wh || (wh && e->whole_modified != wh->modified))
        return 0;
    return memcmp(e->w2i, ob->w2i, sizeof e->w2i) == 0 &&
           memcmp(e->planes, ob->planes, (size_t)ob->n_planes * sizeof *ob->planes) == 0 &&
           memcmp(e->ext, ob->ext, sizeof e->ext) == 0;
}

void
rt_lv_release(rt_lv *e) {
    vv_volume_free(e->vol);
    free(e->T);
    memset(e, 0, sizeof *e);
}

vv_status
rt_build_light_volume(const rt_frame *fr, rt_vobj *ob, int l, int nt) {
    for (int a = 0; a < 3; a++) {
        ob->ldim[a] = (ob->dims[a] - 1 + RT_LGRID - 1) / RT_LGRID + 1;
        ob->ldim[a] = ob->ldim[a] < 2 ? 2 : ob->ldim[a];
    }
    rt_state *st = fr->st;
    for (int i = 0; i < RT_LV_CACHE; i++)
        if (st->lv[i].vol && lv_matches(&st->lv[i], fr, ob, l)) {
            st->lv[i].used = st->frame;
            ob->lvol[l] = st->lv[i].T;
            return VV_OK;
        }
    vv_status s = rt_sweep_light_volume(fr, ob, l, nt, &ob->lvol[l]);
    if (s != VV_OK || !ob->lvol[l])
        return s;
    /* keep it: in a free slot, else in place of the least recently used one
     * that this frame does not use */
    const int slot = RT_CACHE_SLOT(rt_lv, st->lv, vol, RT_LV_CACHE, st->frame);
    if (slot < 0) {
        ob->lvol_owned |= 1u << l;
        return VV_OK;
    }
    rt_lv *e = &st->lv[slot];
    rt_lv_release(e);
    e->vol = vv_volume_ref(ob->obj->volume);
    e->modified = ob->obj->volume->modified;
    memcpy(e->w2i, ob->w2i, sizeof e->w2i);
    e->point = fr->lights[l].point;
    for (int a = 0; a < 3; a++) {
        e->dir[a] = fr->lights[l].dir[a];
        e->pos[a] = fr->lights[l].pos[a];
    }
    e->dt = fr->dt;
    e->n_planes = ob->n_planes;
    memcpy(e->planes, ob->planes, (size_t)ob->n_planes * sizeof *ob->planes);
    e->lut_lo = ob->tab.lut_lo;
    e->lut_scale = ob->tab.lut_scale;
    memcpy(e->ext, ob->ext, sizeof e->ext);
    e->whole = ob->whole ? ob->whole->header : NULL;
    e->whole_modified = ob->whole ? ob->whole->header->modified : 0;
    e->T = ob->lvol[l];
    e->used = st->frame;
    return VV_OK;
}

/* The cell of the lazily traced shadow grid holding whole-volume index
 * point pi: its first corner i0 (returned as a grid index) and the
 * fractions f. */
static inline size_t
sgrid_cell(const rt_vobj *ob, const float pi[3], int i0[3], float f[3]) {
    for (int a = 0; a < 3; a++) {
        float x = pi[a] < 0 ? 0 : pi[a];
        x *= 1.0f / RT_SGRID;
        int i = (int)x;
        i = i > ob->gdim[a] - 2 ? ob->gdim[a] - 2 : i;
        i0[a] = i;
        f[a] = x - (float)i;
        f[a] = f[a] > 1 ? 1 : f[a];
    }
    return ((size_t)i0[2] * (size_t)ob->gdim[1] + (size_t)i0[1]) * (size_t)ob->gdim[0] +
           (size_t)i0[0];
}

/* Shadow of a volume sample at index point pi (world pw) for light l. */
static float
volume_sample_shadow(const rt_frame *fr, const rt_vobj *ob, int l, const float pi_in[3],
                     const float pw[3], rt_scache *sc) {
    /* a region part samples its voxels in their own index space: the
     * shadow grids are the whole volume's */
    float pr[3];
    const float *pi = pi_in;
    if (ob->region) {
        for (int a = 0; a < 3; a++)
            pr[a] = pi_in[a] + (float)ob->region->offset[a];
        pi = pr;
    }
    if (ob->sweep[l]) {
        /* the swept grid, looked up 1.5 grid cells towards the light so that
         * a surface does not shadow itself */
        const float bias = (float)(1.5 * RT_SGRID * ob->vox);
        float f[3];
        int i0[3];
        for (int a = 0; a < 3; a++) {
            float x = (pi[a] + ob->lidx[l][a] * bias) * (1.0f / RT_SGRID);
            x = x < 0 ? 0 : x > (float)(ob->gdim[a] - 1) ? (float)(ob->gdim[a] - 1) : x;
            int i = (int)x;
            i = i > ob->gdim[a] - 2 ? ob->gdim[a] - 2 : i;
            i0[a] = i;
            f[a] = x - (float)i;
        }
        const float *T = ob->sweep[l];
        const size_t sy = (size_t)ob->gdim[0], sz = sy * (size_t)ob->gdim[1];
        const float *v = T + (size_t)i0[2] * sz + (size_t)i0[1] * sy + (size_t)i0[0];
        float x0 = vv_lerpf(v[0], v[1], f[0]), x1 = vv_lerpf(v[sy], v[sy + 1], f[0]);
        float x2 = vv_lerpf(v[sz], v[sz + 1], f[0]),
              x3 = vv_lerpf(v[sz + sy], v[sz + sy + 1], f[0]);
        return vv_lerpf(vv_lerpf(x0, x1, f[1]), vv_lerpf(x2, x3, f[1]), f[2]);
    }
    if (!ob->sgrid[l]) /* isosurfaces, or shadow_grid=0: an exact shadow ray */
        return shadow_ray(fr, v3(pw[0], pw[1], pw[2]), &fr->lights[l], ob->vox);
    _Atomic uint32_t *g = ob->sgrid[l];
    float f[3];
    int i0[3];
    const size_t base = sgrid_cell(ob, pi, i0, f);
    float vloc[8], *v = vloc;
    if (sc) {
        if (sc->ob != ob) {
            sc->ob = ob;
            for (int k = 0; k < VV_MAX_LIGHTS; k++)
                sc->cell[k] = SIZE_MAX;
        }
        v = sc->v[l];
        if (sc->cell[l] == base) {
            return cell_lerp(v, f);
        }
        sc->cell[l] = base;
    }
    for (int k = 0; k < 8; k++) {
        int gi = i0[0] + (k & 1), gj = i0[1] + ((k >> 1) & 1), gk = i0[2] + ((k >> 2) & 1);
        size_t idx =
            ((size_t)gk * (size_t)ob->gdim[1] + (size_t)gj) * (size_t)ob->gdim[0] + (size_t)gi;
        uint32_t bits = atomic_load_explicit(&g[idx], memory_order_relaxed);
        float T;
        if (bits) {
            float x;
            memcpy(&x, &bits, sizeof x);
            T = x - 1.0f;
        } else {
            /* trace it: deterministic, so two threads racing store the same */
            double q[3] = {(double)gi * RT_SGRID, (double)gj * RT_SGRID, (double)gk * RT_SGRID};
            for (int a = 0; a < 3; a++)
                q[a] = q[a] > ob->dims[a] - 1 ? ob->dims[a] - 1 : q[a];
            const vv_vec3 wp = rt_index_to_world(ob, q);
            T = shadow_ray(fr, wp, &fr->lights[l], 1.5 * RT_SGRID * ob->vox);
            float x = T + 1.0f;
            memcpy(&bits, &x, sizeof bits);
            atomic_store_explicit(&g[idx], bits, memory_order_relaxed);
            T = x - 1.0f; /* as the other threads will read it: images do not
                           * depend on which thread traced a grid point */
        }
        v[k] = T;
    }
    return cell_lerp(v, f);
}

/* ---------------------------------------------------------------------- */
/* Shading                                                                   */

/* Where a volume sample's shadow is looked up (vv_vshadow_fn). */
typedef struct rt_shadow_ctx {
    const rt_frame *fr;
    const rt_vobj *ob;
    const float *pi, *pw; /* index and world position */
    rt_scache *sc;        /* the ray's last cells, or NULL */
} rt_shadow_ctx;

static inline float
sample_shadow(const void *ctx, int l) {
    const rt_shadow_ctx *c = ctx;
    return volume_sample_shadow(c->fr, c->ob, l, c->pi, c->pw, c->sc);
}

int
rt_volume_shadows(const rt_frame *fr, const rt_vobj *o, const float pi[3], const float pw[3],
                  rt_scache *sc, float *sh, int stride) {
    if (!(fr->shadows && o->obj->receives_shadows))
        return 0;
    /* the common case, lazily traced grids: the sample's cell found once
     * for every light, and each light's corners from the ray's cache while
     * the ray stays in that cell (volume_sample_shadow's arithmetic) */
    int cached = sc && sc->ob == o;
    for (int l = 0; l < fr->n_lights && cached; l++)
        cached = o->sgrid[l] && !o->sweep[l];
    if (cached) {
        float pr[3];
        const float *pp = pi;
        if (o->region) {
            for (int a = 0; a < 3; a++)
                pr[a] = pi[a] + (float)o->region->offset[a];
            pp = pr;
        }
        float f[3];
        int i0[3];
        const size_t base = sgrid_cell(o, pp, i0, f);
        for (int l = 0; l < fr->n_lights; l++) {
            const float *v = sc->v[l];
            if (sc->cell[l] != base) {
                sh[(size_t)stride * (size_t)l] = volume_sample_shadow(fr, o, l, pi, pw, sc);
                continue;
            }
            sh[(size_t)stride * (size_t)l] = cell_lerp(v, f);
        }
        return 1;
    }
    for (int l = 0; l < fr->n_lights; l++)
        sh[(size_t)stride * (size_t)l] = volume_sample_shadow(fr, o, l, pi, pw, sc);
    return 1;
}

/* The ray caster's volume Phong (vv_vshade: reflection vector, two-sided,
 * specular weighted by the sample opacity), each light scaled by its
 * shadow. */
void
rt_shade_volume(const rt_frame *fr, const rt_vobj *o, const float g[3], const float pi[3],
                const float pw[3], const float v[3], const float col[3], float alpha, rt_scache *sc,
                float out[3]) {
    const int shadows = fr->shadows && o->obj->receives_shadows;
    const rt_shadow_ctx ctx = {fr, o, pi, pw, sc};
    /* two calls, so that the compiler inlines the shadow lookup */
    if (shadows)
        vv_vshade(&o->sh, fr->vlights, fr->n_lights, g, pw, v, col, alpha, sample_shadow, &ctx,
                  out);
    else
        vv_vshade(&o->sh, fr->vlights, fr->n_lights, g, pw, v, col, alpha, NULL, NULL, out);
}

/* Local Phong of a surface point with shadows: one-sided, the normal n
 * facing the viewer. */
static void
shade_surface_local(const rt_frame *fr, const vv_material *m, const float col[3], int receives,
                    vv_vec3 p, vv_vec3 n, vv_vec3 v, float out[3]) {
    float d[3], s[3] = {0, 0, 0};
    for (int ch = 0; ch < 3; ch++)
        d[ch] = (float)m->ambient * fr->ambient[ch];
    const double eps = RT_EPS * fr->scene_size;
    vv_vec3 po = v3add(p, v3scale(n, eps));
    for (int l = 0; l < fr->n_lights; l++) {
        const rt_light *lt = &fr->lights[l];
        vv_vec3 L = v3(lt->dir[0], lt->dir[1], lt->dir[2]);
        if (lt->point)
            L = v3norm(v3sub(v3(lt->pos[0], lt->pos[1], lt->pos[2]), p));
        double ndl = v3dot(n, L);
        if (ndl <= 0)
            continue;
        float sh = fr->shadows && receives ? shadow_ray(fr, po, lt, 0) : 1.0f;
        if (sh <= 0)
            continue;
        vv_vec3 R = v3sub(v3scale(n, 2 * ndl), L);
        double rv = v3dot(R, v);
        double sp = rv > 0 && m->specular > 0 ? pow(rv, m->shininess) : 0;
        for (int ch = 0; ch < 3; ch++) {
            d[ch] += sh * (float)(m->diffuse * ndl) * lt->col[ch];
            s[ch] += sh * (float)(m->specular * sp) * lt->col[ch];
        }
    }
    for (int ch = 0; ch < 3; ch++)
        out[ch] = d[ch] * col[ch] + s[ch];
}

/* Reflected and transmitted light at a surface point, added to out with
 * weights kr and kt. n: unit normal facing the incoming ray's origin side;
 * outward: the object's outward normal (solids refract). */
void
rt_shade_secondary(const rt_frame *fr, const vv_ray *wr, vv_vec3 p, vv_vec3 n, vv_vec3 outward,
                   float kr, float kt, double ior, int solid, int depth, float weight,
                   float out[3]) {
    if (depth >= fr->max_depth)
        return;
    const double eps = RT_EPS * fr->scene_size;
    const double dn = v3dot(wr->dir, n);
    float tmp[3], a, dd;
    if (kr > 0 && weight * kr >= RT_MIN_WEIGHT) {
        vv_ray rr;
        rr.dir = v3norm(v3sub(wr->dir, v3scale(n, 2 * dn)));
        rr.origin = v3add(p, v3scale(n, eps));
        rt_trace(fr, &rr, depth + 1, 0, weight * kr, tmp, &a, &dd);
        for (int ch = 0; ch < 3; ch++)
            out[ch] += kr * tmp[ch];
    }
    if (kt > 0 && weight * kt >= RT_MIN_WEIGHT) {
        vv_ray tr;
        tr.dir = wr->dir;
        if (solid && ior > 0 && ior != 1) {
            /* Snell: entering when the ray meets the outward normal head on */
            const int entering = v3dot(wr->dir, outward) < 0;
            const double eta = entering ? 1.0 / ior : ior;
            const double ci = -dn; /* cos of incidence, n faces the ray origin */
            const double k = 1 - eta * eta * (1 - ci * ci);
            if (k < 0) /* total internal reflection */
                tr.dir = v3norm(v3sub(wr->dir, v3scale(n, 2 * dn)));
            else
                tr.dir = v3norm(v3add(v3scale(wr->dir, eta), v3scale(n, eta * ci - sqrt(k))));
        }
        const double side = v3dot(tr.dir, n) < 0 ? -1 : 1;
        tr.origin = v3add(p, v3scale(n, side * eps));
        rt_trace(fr, &tr, depth + 1, 0, weight * kt, tmp, &a, &dd);
        for (int ch = 0; ch < 3; ch++)
            out[ch] += kt * tmp[ch];
    }
}

/* I_s of a geometric hit. */
void
rt_shade_geometry(const rt_frame *fr, const vv_ray *wr, const rt_hit *h, int depth, float weight,
                  float out[3]) {
    const rt_gobj *g = &fr->gobjs[h->gobj];
    vv_vec3 p = ray_at(wr, h->t);
    vv_vec3 n = h->n;
    if (v3dot(n, wr->dir) > 0)
        n = v3scale(n, -1);
    vv_vec3 v = v3scale(wr->dir, -1);
    float loc[3], col[3] = {g->col[0], g->col[1], g->col[2]};
    if (g->obj->texture.image) {
        /* the texture is defined on the object's own coordinates */
        const vv_vec3 tc = vv_texture_map_eval(&g->obj->texture, xf_point(g->w2o, p));
        col[0] *= (float)tc.x;
        col[1] *= (float)tc.y;
        col[2] *= (float)tc.z;
    }
    shade_surface_local(fr, &g->obj->material, col, g->obj->receives_shadows, p, n, v, loc);
    float kl = 1 - g->kr - g->kt;
    kl = kl < 0 ? 0 : kl;
    for (int ch = 0; ch < 3; ch++)
        out[ch] = kl * loc[ch];
    rt_shade_secondary(fr, wr, p, n, h->n, g->kr, g->kt, g->ior, g->closed, depth, weight, out);
}
