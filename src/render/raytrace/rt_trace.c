/*
 * Volumetric ray tracing, the rays: volume samples composited front to
 * back, the first surface hit, reflected and transmitted rays to the depth
 * limit.
 */
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/classify.h"
#include "render/march.h"
#include "render/project.h"
#include "render/ray.h"
#include "render/raytrace/rt_internal.h"
#include "render/registry.h"
#include "render/sample.h"
#include "render/shade.h"
#include "volvis/render.h"

/* ---------------------------------------------------------------------- */
/* Ray tracing                                                               */

/* Composites one classified sample (opacity and premultiplied colour e) at
 * index point p, ray parameter t, under the accumulated C, A; gin: the
 * index-space gradient there, or NULL to compute it. A channel's sample is
 * shaded with its own gradient under its leader's shading constants and
 * shadow grids (ob->lead). */
static inline void
composite_sample(const rt_frame *fr, const rt_vobj *ob, const vv_ray *wr, const float v[3],
                 const float *e, const float p[3], double t, const float *gin, rt_scache *sc,
                 float C[3], float *A) {
    const float w = 1 - *A;
    if (ob->obj->shading) {
        float g[3], pw[3], o3[3];
        if (gin)
            memcpy(g, gin, sizeof g);
        else
            vv_vcache_gradient(ob->c, p, g);
        vv_ray_world_point(wr, t, pw);
        rt_shade_volume(fr, ob->lead, g, p, pw, v, e + 1, e[0], sc, o3);
        C[0] += w * o3[0];
        C[1] += w * o3[1];
        C[2] += w * o3[2];
    } else {
        C[0] += w * e[1];
        C[1] += w * e[2];
        C[2] += w * e[3];
    }
    *A += w * e[0];
}

/* The accumulated opacity that ends a ray of weight @p weight (its share
 * of the pixel): the light it would still gather is at most weight (1 -
 * A), so it stops once that is under what a primary ray leaves, 1 - et
 * (the contribution-based pruning of the ray tree: Hall and Greenberg, "A
 * Testbed for Realistic Image Synthesis", IEEE CG&A 1983). */
static inline float
ray_et(const rt_frame *fr, float weight) {
    return weight >= 1 ? fr->et : 1 - (1 - fr->et) / weight;
}

/* march_one's shadows of sample s of a chunk (vv_vchunk_shade8). */
typedef struct rt_chunk_ctx {
    const rt_frame *fr;
    const rt_vobj *ob;
    const vv_vray *r;
    const vv_ray *wr;
    double kfirst;
    rt_scache *sc;
} rt_chunk_ctx;

static int
chunk_shadows(void *ctx, int s, float *sh, int stride) {
    const rt_chunk_ctx *x = ctx;
    const double t = (x->kfirst + s) * x->fr->dt;
    float p[3], pw[3];
    vv_vray_point(x->r, t, p);
    vv_ray_world_point(x->wr, t, pw);
    return rt_volume_shadows(x->fr, x->ob->lead, p, pw, x->sc, sh, stride);
}

/* The common case, one composite volume on the ray: run of visible
 * subvolumes by run, leaping over empty ones, the same samples t = k dt as
 * the general loop below, classified a chunk at a time (vv_vray_classify,
 * the ray caster's kernel) before the visible ones are shaded. */
static void
march_one(const rt_frame *fr, const rt_vobj *ob, const vv_vray *r, const vv_ray *wr,
          const float v[3], float et, float C[3], float *Aout, float *dep) {
    const double dt = fr->dt, inv_dt = 1.0 / fr->dt;
    const vv_vcache *c = ob->c;
    const int shading = ob->obj->shading;
    rt_scache sc;
    sc.ob = NULL; /* the rest is filled when first used */
    float A = 0;
    /* shading eight samples at a time: cached gradients, directional lights,
     * no label colours */
    int shade8 = VV_VC_HAVE_AVX2 && fr->avx2 && shading && c->nrm && !ob->extras;
    for (int l = 0; l < fr->n_lights; l++)
        shade8 &= !fr->vlights[l].point;
    double k = vv_ceil_pos(r->t0 * inv_dt);
    const double kend = floor(r->t1 * inv_dt);
    double klast;
    /* the ray caster's runs of visible subvolumes (trace_composite_one) */
    while (vv_vray_visible_run_simd(fr->avx2, c, ob->bdist, r, dt, kend, &k, &klast)) {
        const int n = (int)(klast - k) + 1;
        for (int s0 = 0; s0 < n; s0 += VV_VC_CHUNK) {
            const int m = n - s0 < VV_VC_CHUNK ? n - s0 : VV_VC_CHUNK;
            const double kfirst = k + s0;
            size_t cell[VV_VC_CHUNK];
            int32_t entry[VV_VC_CHUNK];
            float fx[VV_VC_CHUNK], fy[VV_VC_CHUNK], fz[VV_VC_CHUNK];
            vv_vray_classify(c, &ob->tab, r, kfirst, dt, m, fr->avx2, cell, fx, fy, fz, entry,
                             NULL);
            if (shade8) {
                /* eight at a time, shadows included (vv_vchunk_shade8: the
                 * loop below's results bit for bit) */
                rt_chunk_ctx x = {fr, ob, r, wr, kfirst, &sc};
                int first = -1;
                uint32_t shaded = 0;
                const int end = vv_vchunk_shade8(c, ob->lut, &ob->lead->sh, fr->vlights,
                                                 fr->n_lights, v, m, cell, fx, fy, fz, entry,
                                                 chunk_shadows, &x, et, C, &A, &first, &shaded);
                if (*dep == INFINITY && first >= 0)
                    *dep = (float)((kfirst + first) * dt);
                if (end) {
                    *Aout = A > 1 ? 1 : A;
                    return;
                }
                continue;
            }
            for (int s = 0; s < m; s++) {
                const float *e = ob->lut + entry[s];
                if (e[0] <= 0)
                    continue;
                const double t = (kfirst + s) * dt;
                float ebuf[4], p[3] = {0, 0, 0};
                if (ob->extras) { /* a label channel (channel_overlay): colours by label */
                    vv_vray_point(r, t, p);
                    const float val = ob->x.lut2d ? vv_vcache_sample(c, p) : 0;
                    if ((e = vv_vextra_apply(&ob->x, c, p, val, e, ebuf))[0] <= 0)
                        continue;
                }
                float g[3] = {0, 0, 0};
                if (shading) {
                    vv_vray_point(r, t, p);
                    if (c->nrm) {
                        const float f[3] = {fx[s], fy[s], fz[s]};
                        vv_vcache_gradient_at(c, cell[s], f, g);
                    } else {
                        vv_vcache_gradient(c, p, g);
                    }
                }
                composite_sample(fr, ob, wr, v, e, p, t, g, &sc, C, &A);
                if (*dep == INFINITY)
                    *dep = (float)t;
                if (A >= et) {
                    *Aout = A > 1 ? 1 : A;
                    return;
                }
            }
        }
        k = klast + 1;
    }
    *Aout = A > 1 ? 1 : A;
}

/* The samples of one multi-channel object's channels at one point under
 * the composite rule (VV_BLEND_COMPOSITE), mixed as the ray caster mixes
 * them (vv_channel_blend): opacities as independent absorbers, alpha = 1 -
 * prod(1 - a_c), shaded colours weighted by opacity. */
typedef struct rt_mix {
    int group; /* the object's leader in vobjs; -1: nothing gathered */
    float col[3], sum_a, T;
} rt_mix;

/* Composites the gathered mix, if any, at ray parameter t under C, A. */
static inline void
mix_flush(rt_mix *m, double t, float C[3], float *A, float *dep) {
    if (m->group >= 0 && m->sum_a > 0) {
        const float a = 1 - m->T, scale = a / m->sum_a, w = 1 - *A;
        C[0] += w * scale * m->col[0];
        C[1] += w * scale * m->col[1];
        C[2] += w * scale * m->col[2];
        *A += w * a;
        if (*dep == INFINITY)
            *dep = (float)t;
    }
    m->group = -1;
    m->col[0] = m->col[1] = m->col[2] = m->sum_a = 0;
    m->T = 1;
}

/* The isosurface of object ob hit at ray parameter th (ray r, world ray
 * wr, towards the eye v): shaded with shadows, as a mirror or a window
 * where its material says, composited under C, A, which becomes opaque. */
static void
iso_hit(const rt_frame *fr, const rt_vobj *ob, const vv_vray *r, const vv_ray *wr, const float v[3],
        double th, int depth, float weight, float C[3], float *Ap) {
    const float A = *Ap;
    float ph[3], g[3], pw[3], col[3], base[3];
    vv_viso_hit_point(ob->c, r, wr, th, ob->sh.base, ob->textured ? &ob->obj->texture : NULL,
                      &ob->x, ph, g, pw, base);
    if (ob->obj->shading)
        rt_shade_volume(fr, ob, g, ph, pw, v, base, 1.0f, NULL, col);
    else
        memcpy(col, base, sizeof col);
    const vv_material *m = &ob->obj->material;
    float kr = ob->obj->reflects ? (float)m->reflectance : 0.0f;
    float kt = (float)m->transparency;
    if ((kr > 0 || kt > 0) && fr->max_depth > depth) {
        /* the isosurface as a mirror or a window: world
         * normal from the gradient, facing the ray */
        vv_vec3 nw =
            v3(ob->sh.nrm[0][0] * g[0] + ob->sh.nrm[0][1] * g[1] + ob->sh.nrm[0][2] * g[2],
               ob->sh.nrm[1][0] * g[0] + ob->sh.nrm[1][1] * g[1] + ob->sh.nrm[1][2] * g[2],
               ob->sh.nrm[2][0] * g[0] + ob->sh.nrm[2][1] * g[1] + ob->sh.nrm[2][2] * g[2]);
        nw = v3norm(nw);
        /* gradients point to higher values: inside; outward is minus */
        vv_vec3 outward = v3scale(nw, -1);
        vv_vec3 nf = v3dot(outward, wr->dir) > 0 ? nw : outward;
        float kl = 1 - kr - kt;
        kl = kl < 0 ? 0 : kl;
        for (int ch = 0; ch < 3; ch++)
            col[ch] *= kl;
        rt_shade_secondary(fr, wr, ray_at(wr, th), nf, outward, kr, kt, m->ior, 1, depth,
                           weight * (1 - A), col);
    }
    const float w = 1 - A;
    C[0] += w * col[0];
    C[1] += w * col[1];
    C[2] += w * col[2];
    *Ap = 1;
}

/* march_volumes' march (vv_march): the objects along the ray (obs[ai]),
 * the channels being gathered and what the ray gathered so far. */
typedef struct rt_march {
    const rt_frame *fr;
    const vv_ray *wr;
    const rt_vobj *obs[RT_MAX_OBJ];
    float v[3];
    int depth;
    float weight;
    rt_scache sc;
    rt_mix mix;
    float *C, A, *dep;
} rt_march;

/* Before object ai's sample at t: the channels gathered so far flushed
 * when ai is not one of them (an object's channels are consecutive). */
static inline void
rt_march_enter(void *ctx, int ai, double t) {
    rt_march *m = ctx;
    if (m->mix.group >= 0 && m->obs[ai]->group != m->mix.group)
        mix_flush(&m->mix, t, m->C, &m->A, m->dep);
}

/* One object's sample at index point p (ray parameter t): a hidden
 * subvolume leaps by its distance to the nearest visible one, a channel's
 * sample is gathered with its object's other channels, a composite
 * object's sample composites, an iso object's value goes to the march's
 * crossing search. */
static inline int
rt_march_sample(void *ctx, int ai, const vv_vray *r, const float p[3], double t,
                vv_march_sample *out) {
    rt_march *m = ctx;
    const rt_vobj *ob = m->obs[ai];
    const vv_vcache *c = ob->c;
    const size_t b = vv_vcache_block(ob->c, p);
    if (!ob->bvis[b]) {
        out->te = leap_exit(ob, r, p, t, ob->bdist[b]);
        return VV_MARCH_EMPTY;
    }
    const float val = vv_vcache_sample(c, p);
    if (ob->mode == VV_MODE_ISO) {
        out->val = val;
        out->iso = ob->iso;
        out->c = c;
        return VV_MARCH_ISO;
    }
    const float *e = ob->lut + 4 * (int)lut_index_f(ob, val);
    if (e[0] <= 0)
        return VV_MARCH_SAMPLED;
    float ebuf[4];
    if (ob->extras && (e = vv_vextra_apply(&ob->x, c, p, val, e, ebuf))[0] <= 0)
        return VV_MARCH_SAMPLED;
    if (ob->group >= 0) {
        /* a channel: its shaded colour (composited under nothing)
         * gathered with the object's other channels at this point */
        float one[3] = {0, 0, 0}, a = 0;
        composite_sample(m->fr, ob, m->wr, m->v, e, p, t, NULL, &m->sc, one, &a);
        m->mix.group = ob->group;
        m->mix.col[0] += one[0];
        m->mix.col[1] += one[1];
        m->mix.col[2] += one[2];
        m->mix.sum_a += e[0];
        m->mix.T *= 1 - e[0];
        return VV_MARCH_SAMPLED;
    }
    composite_sample(m->fr, ob, m->wr, m->v, e, p, t, NULL, &m->sc, m->C, &m->A);
    if (*m->dep == INFINITY)
        *m->dep = (float)t;
    return VV_MARCH_SAMPLED;
}

/* Object ai's isosurface crossed at th: a surface, shaded with shadows and
 * reflections. */
static inline void
rt_march_iso(void *ctx, int ai, const vv_vray *r, double th) {
    rt_march *m = ctx;
    iso_hit(m->fr, m->obs[ai], r, m->wr, m->v, th, m->depth, m->weight, m->C, &m->A);
    if (th < *m->dep)
        *m->dep = (float)th;
}

/* After all objects' samples at t: the gathered channels composited. */
static inline void
rt_march_end(void *ctx, double t) {
    rt_march *m = ctx;
    mix_flush(&m->mix, t, m->C, &m->A, m->dep);
}

/* Front-to-back compositing of the composite and iso volumes along the ray
 * over [0, tlim] on the samples t = k dt (the ray caster's grid). An iso
 * hit is a surface: shaded with shadows and reflections, it ends the ray. */
static void
march_volumes(const rt_frame *fr, const vv_ray *wr, double tlim, int depth, int primary,
              float weight, float C[3], float *Aout, float *dep) {
    vv_vray rays[RT_MAX_OBJ];
    int act[RT_MAX_OBJ], cont[RT_MAX_OBJ];
    int na = 0;
    double tmin = INFINITY, tmax = -INFINITY;
    for (int i = 0; i < fr->n_vobj; i++) {
        const rt_vobj *ob = &fr->vobjs[i];
        if ((ob->mode != VV_MODE_COMPOSITE && ob->mode != VV_MODE_ISO) || ob->context)
            continue;
        if (ob->group >= 0 && ob->blend != VV_BLEND_COMPOSITE)
            continue; /* additive channels: channel_overlay */
        if (!primary && !ob->obj->visible_in_reflections)
            continue;
        if (vray_setup_cont(ob, wr, 0, tlim, &rays[na], &cont[na])) {
            act[na] = i;
            tmin = rays[na].t0 < tmin ? rays[na].t0 : tmin;
            tmax = rays[na].t1 > tmax ? rays[na].t1 : tmax;
            na++;
        }
    }
    if (na == 0) {
        *Aout = 0;
        return;
    }
    const float et = ray_et(fr, weight);
    const double dt = fr->dt;
    const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
    if (na == 1 && fr->vobjs[act[0]].mode == VV_MODE_COMPOSITE && !fr->vobjs[act[0]].extras) {
        march_one(fr, &fr->vobjs[act[0]], &rays[0], wr, v, et, C, Aout, dep);
        return;
    }
    if (na == 1 && fr->vobjs[act[0]].mode == VV_MODE_ISO && fr->vobjs[act[0]].group < 0) {
        /* one isosurface: the ray caster's search (vv_vray_iso_first; in a
         * region render from the sample before the region's: VV_REGION_NEAREST) */
        const rt_vobj *ob = &fr->vobjs[act[0]];
        float A = 0;
        const double th =
            vv_vray_iso_first(ob->c, ob->bdist, &rays[0], dt, ob->iso, fr->avx2, cont[0]);
        if (th >= 0) {
            iso_hit(fr, ob, &rays[0], wr, v, th, depth, weight, C, &A);
            *dep = th < *dep ? (float)th : *dep;
        }
        *Aout = A;
        return;
    }
    /* fields set one by one: an initializer would clear obs[] and the
     * shadow cache on every ray */
    rt_march m;
    m.fr = fr;
    m.wr = wr;
    memcpy(m.v, v, sizeof v);
    m.depth = depth;
    m.weight = weight;
    m.mix = (rt_mix){-1, {0, 0, 0}, 0, 1};
    m.C = C;
    m.A = 0;
    m.dep = dep;
    m.sc.ob = NULL; /* the rest is filled when first used */
    for (int i = 0; i < na; i++)
        m.obs[i] = &fr->vobjs[act[i]];
    vv_march(rays, na, tmin, tmax, dt, et, &m.A, &m, rt_march_enter, rt_march_sample, rt_march_iso,
             rt_march_end);
    *Aout = m.A > 1 ? 1 : m.A;
}

/* Maximum / minimum intensity projection, X-ray or attenuated MIP of one
 * volume over the part of the ray in [0, tlim] (vv_vray_project,
 * vv_vray_attenuated_mip: the ray caster's). Returns 0 when the ray misses
 * it. */
static int
project_volume(const rt_frame *fr, const rt_vobj *ob, const vv_ray *wr, double tlim, float *value,
               float *depth) {
    vv_vray r;
    if (!vray_setup(ob, wr, 0, tlim, &r))
        return 0;
    if (ob->mode == VV_MODE_ATTENUATED_MIP)
        vv_vray_attenuated_mip(ob->c, &r, fr->dt, &ob->att, value, depth);
    else
        vv_vray_project(ob->c, &r, ob->mode, fr->dt, fr->st->parc, -INFINITY, INFINITY, value,
                        depth);
    return 1;
}

/* A multi-channel object under the additive or maximum rule (leader ob of
 * its channels) over the part of the ray in [0, tlim], as the ray caster
 * draws it: additive, each visible channel composited front to back on its
 * own (march_one) and the colours added; maximum, a MIP per channel
 * coloured as a one-channel MIP is (colour times opacity at that value),
 * added. *a = 1 - prod(1 - a_c). Returns 0 when the ray misses it. */
static int
channel_overlay(const rt_frame *fr, const rt_vobj *ob, const vv_ray *wr, double tlim, float rgb[3],
                float *a, float *depth) {
    const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
    float T = 1;
    int hit = 0;
    rgb[0] = rgb[1] = rgb[2] = 0;
    *depth = INFINITY;
    for (int k = 0; k < ob->gn; k++) {
        const rt_vobj *co = ob + k;
        float col[3] = {0, 0, 0}, ac = 0, d = INFINITY;
        if (co->mode == VV_MODE_MIP) {
            float val;
            if (!project_volume(fr, co, wr, tlim, &val, &d))
                continue;
            const float *e = co->lut + 4 * (int)lut_index_f(co, val);
            for (int i = 0; i < 3; i++)
                col[i] = e[1 + i] * e[0];
            ac = e[0];
        } else {
            vv_vray r;
            if (!vray_setup(co, wr, 0, tlim, &r))
                continue;
            march_one(fr, co, &r, wr, v, fr->et, col, &ac, &d);
        }
        hit = 1;
        for (int i = 0; i < 3; i++)
            rgb[i] += col[i];
        T *= 1 - ac;
        *depth = d < *depth ? d : *depth;
    }
    *a = 1 - T;
    return hit;
}

/* I(x, w) = I_v + tau I_s along one ray: out is the colour, *alpha the
 * coverage (1 where a surface is hit), *tdepth the first visible hit. */
void
rt_trace(const rt_frame *fr, const vv_ray *wr, int depth, int primary, float weight, float out[3],
         float *alpha, float *tdepth) {
    rt_trace_key(fr, wr, depth, primary, weight, out, alpha, tdepth, NULL);
}

void
rt_trace_key(const rt_frame *fr, const vv_ray *wr, int depth, int primary, float weight,
             float out[3], float *alpha, float *tdepth, float *key) {
    rt_hit h;
    /* secondary rays start off their surface already (offset along the normal) */
    const int geo = rt_nearest_hit(fr, wr, 0, INFINITY, primary, &h);
    const double tlim = geo ? h.t : INFINITY;
    float C[3] = {0, 0, 0}, A = 0, dep = INFINITY;
    march_volumes(fr, wr, tlim, depth, primary, weight, C, &A, &dep);
    float P[3] = {0, 0, 0}, PA = 0, pdepth = INFINITY;
    if (key)
        *key = NAN;
    for (int i = 0; i < fr->n_vobj; i++) {
        const rt_vobj *ob = &fr->vobjs[i];
        if (ob->context || (!primary && !ob->obj->visible_in_reflections))
            continue;
        if (ob->group >= 0) {
            /* a multi-channel object under the additive or maximum rule:
             * shown with the projections (the ray caster's order) */
            float g[3], ga, gd;
            if (ob->lead != ob || ob->blend == VV_BLEND_COMPOSITE ||
                !channel_overlay(fr, ob, wr, tlim, g, &ga, &gd))
                continue;
            for (int ch = 0; ch < 3; ch++)
                P[ch] = g[ch] > P[ch] ? g[ch] : P[ch];
            PA = ga > PA ? ga : PA;
            pdepth = gd < pdepth ? gd : pdepth;
            continue;
        }
        if (ob->mode == VV_MODE_COMPOSITE || ob->mode == VV_MODE_ISO)
            continue;
        float val, d;
        if (!project_volume(fr, ob, wr, tlim, &val, &d))
            continue;
        if (key)
            *key = val;
        const float *e = ob->lut + 4 * (int)lut_index_f(ob, val);
        for (int ch = 0; ch < 3; ch++) {
            float cv = e[1 + ch] * e[0];
            P[ch] = cv > P[ch] ? cv : P[ch];
        }
        PA = e[0] > PA ? e[0] : PA;
        pdepth = d < pdepth ? d : pdepth;
    }
    const float rest = 1 - A;
    const float A2 = A + rest * PA;
    float behind[3] = {fr->bg[0], fr->bg[1], fr->bg[2]};
    float balpha = 0;
    if (geo && A < fr->et && A < 1) {
        rt_shade_geometry(fr, wr, &h, depth, weight * (1 - A2), behind);
        balpha = 1;
        dep = dep < h.t ? dep : (float)h.t;
    }
    for (int ch = 0; ch < 3; ch++)
        out[ch] = C[ch] + rest * P[ch] + (1 - A2) * behind[ch];
    *alpha = A2 + (1 - A2) * balpha;
    *tdepth = dep < pdepth ? dep : pdepth;
}
