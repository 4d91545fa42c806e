/*
 * Direct volume ray casting (Levoy, "Display of Surfaces from Volume Data",
 * IEEE CG&A 1988; the VolVis paper, section 5 "Rendering", volume ray
 * casting), with empty-space skipping over a grid of subvolumes holding
 * min/max values (the PARC idea of the VolVis paper's Navigator, section 4).
 *
 * Per volume, a cache holds the voxels as 16-bit offsets (integer data) or
 * float, the unit gradient direction of every voxel quantised to 3 x int8
 * in a separate array (central differences, computed once), and the min/max
 * of every 4^3-cell subvolume. Per object, a transfer-function lookup table
 * (opacity corrected for the step) marks which subvolumes are visible, and
 * each subvolume gets its chessboard distance to the nearest visible one;
 * rays leap over empty cubes of subvolumes. These tables are kept between
 * frames while nothing they depend on changes. The caches, tables, trilinear
 * sampling and ray clipping are shared with the raytrace renderer
 * (src/render/volume_cache.h).
 *
 * Rays are traced in each object's index space: the world ray (unit
 * direction, parameter t in world units) is mapped by the object's
 * world-to-index matrix, so anisotropic spacing, direction matrices and
 * object transforms all come for free, and samples sit at t = k * dt on a
 * grid shared by all objects, which keeps images deterministic and
 * independent of tiling and thread count. The single-volume composite
 * kernel classifies a subvolume's samples first (SSE2, or AVX2 where the
 * processor has it) and then shades and composites the visible ones.
 * docs/rendering.md describes the method and its measurements. */
#include <math.h>
#include <omp.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/raycast/raycast_brick.h"
#include "render/registry.h"
#include "render/volume_cache.h"
#include "volvis/render.h"

#define RC_TILE 16    /* image tile side in pixels */
#define RC_MAX_OBJ 64 /* objects handled in one render (<= VV_VC_MAX) */

typedef struct rc_state {
    vv_vcache_set vc;         /* per-volume caches (src/render/volume_cache.h) */
    double early_termination; /* accumulated opacity that ends a ray */
    int skipping;             /* empty-space skipping on/off (for tests) */
    int simd;                 /* use AVX2 when the processor has it (for tests) */
    /* brick mode (raycast_brick.h) and what a projection brick render
     * leaves for vv_raycast_finish_projection */
    int brick_on;
    vv_raycast_brick brick;
    float *plut; /* VV_VC_LUT x {alpha, r, g, b}, or NULL */
    float plut_lo, plut_scale, pbg[3];
} rc_state;

/* One object prepared for this render. */
typedef struct rc_obj {
    const vv_object *obj;
    vv_vcache *c;
    vv_render_mode mode;
    double w2i[3][4];        /* world -> index */
    double i2w[3][4];        /* index -> world */
    int dims[3];             /* the volume's real dims (box clip) */
    float lut_lo, lut_scale; /* value -> LUT index */
    float *lut;              /* VV_VC_LUT x {alpha, r*alpha, g*alpha, b*alpha} */
    uint8_t *bvis;           /* subvolume visible under the TF / isovalue */
    uint8_t
        *bdist; /* chessboard distance, in subvolumes, to the nearest visible one (0: visible) */
    vv_vtables tab;  /* the tables lut, bvis, bdist come from */
    int owns_tables; /* tab is this object's (else borrowed from the cache) */
    float iso;
    vv_vshading sh; /* shading constants */
    int shading;
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    vv_vextra x;  /* 2-D transfer function and solid texture */
    int extras;   /* x has something: the general kernel handles the object */
    int textured; /* iso mode: an image texture modulates the base colour */
    /* brick mode: the brick, the step and whether the kernel finds its first
     * sample as ceil(t0 * (1 / dt)) (trace_composite_one) or ceil(t0 / dt) */
    const vv_raycast_brick *brick;
    double dt;
    int inv_form;
} rc_obj;

typedef struct rc_frame {
    rc_state *st;
    rc_obj *objs;
    int n_obj;
    int n_comp; /* composite/iso objects first in objs[], then projections */
    const vv_view *view;
    float dt;
    float ambient[3];
    float bg[3];
    vv_vlight lights[VV_MAX_LIGHTS];
    int n_lights;
    float et;         /* early termination */
    int point_lights; /* any point light (needs the world position of samples) */
    int avx2;         /* the processor has AVX2 and FMA (vv_vray_classify) */
    /* primary rays: origin and unnormalised direction are affine in (px, py) */
    vv_vec3 o00, ox, oy, d00, dx, dy;
} rc_frame;

/* ---------------------------------------------------------------------- */
/* Shading                                                                  */

/* Phong with two-sided lighting (vv_vshade), no shadows. */
static inline void
shade(const rc_frame *fr, const rc_obj *o, const float g[3], const float pw[3], const float v[3],
      const float col[3], float alpha, float out[3]) {
    vv_vshade(&o->sh, fr->lights, fr->n_lights, g, pw, v, col, alpha, NULL, NULL, out);
}

/* ---------------------------------------------------------------------- */
/* Ray set-up per object                                                    */

/* Brick mode: whether sample k of r (the point vv_vray_point computes,
 * before the brick offset) lies in the brick's box on axis a, on its low
 * (side 0: p >= lo) or high (side 1: p < hi) side. */
static inline int
brick_side(const vv_vray *r, const vv_raycast_brick *b, double dt, int a, int side, int64_t k) {
    const float tf = (float)((double)k * dt - r->tb);
    const float p = r->o[a] + tf * r->d[a];
    return side ? p < b->hi[a] : p >= b->lo[a];
}

/* The samples kg0 .. kg1 that are the brick's: along a ray each coordinate of
 * the sample point is monotonic in k, so on each axis and side they are a
 * prefix or a suffix, found by bisection. Returns 0 when none. */
static int
brick_range(const vv_vray *r, const vv_raycast_brick *b, double dt, int64_t kg0, int64_t kg1,
            int64_t *ka, int64_t *kb) {
    int64_t lo = kg0, hi = kg1;
    for (int a = 0; a < 3; a++)
        for (int side = 0; side < 2; side++) {
            if ((side == 0 && b->lo[a] == -INFINITY) || (side == 1 && b->hi[a] == INFINITY))
                continue;
            const int t_first = brick_side(r, b, dt, a, side, kg0);
            const int t_last = brick_side(r, b, dt, a, side, kg1);
            if (!t_first && !t_last)
                return 0;
            if (t_first && t_last)
                continue;
            /* bisection for the boundary between kg0 and kg1 */
            int64_t x = kg0, y = kg1; /* test(x) == t_first, test(y) == t_last */
            while (y - x > 1) {
                const int64_t m = x + (y - x) / 2;
                if (brick_side(r, b, dt, a, side, m) == t_first)
                    x = m;
                else
                    y = m;
            }
            if (t_last) /* false then true: the suffix from y */
                lo = y > lo ? y : lo;
            else /* true then false: the prefix up to x */
                hi = x < hi ? x : hi;
        }
    *ka = lo;
    *kb = hi;
    return lo <= hi;
}

/* The ray clipped to the object in its index space; in brick mode, set up
 * in the whole volume's index space and cut to the brick's samples. */
static inline int
ray_setup(const rc_obj *ob, const vv_ray *wr, vv_vray *r) {
    if (!vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, wr, 0, INFINITY, r))
        return 0;
    const vv_raycast_brick *b = ob->brick;
    if (!b)
        return 1;
    const double dt = ob->dt;
    const int64_t kg0 =
        (int64_t)(ob->inv_form ? vv_ceil_pos(r->t0 * (1.0 / dt)) : vv_ceil_pos(r->t0 / dt));
    const int64_t kg1 =
        (int64_t)(ob->inv_form ? vv_floor_pos(r->t1 * (1.0 / dt)) : vv_floor_pos(r->t1 / dt));
    for (int a = 0; a < 3; a++)
        r->off[a] = (float)b->off[a];
    if (kg0 > kg1) {
        /* shorter than a step: a projection takes one sample in the middle,
         * which belongs to the brick that holds it */
        float p[3];
        const double tm = 0.5 * (r->t0 + r->t1);
        const float tf = (float)(tm - r->tb);
        for (int a = 0; a < 3; a++) {
            p[a] = r->o[a] + tf * r->d[a];
            if (!(p[a] >= b->lo[a] && p[a] < b->hi[a]))
                return 0;
        }
        return 1;
    }
    int64_t ka, kb;
    if (!brick_range(r, b, dt, kg0, kg1, &ka, &kb))
        return 0;
    /* half a step from the first and last samples: the kernels find them
     * again whatever their rounding */
    const double t0 = ((double)ka - 0.5) * dt, t1 = ((double)kb + 0.5) * dt;
    r->t0 = t0 > r->t0 ? t0 : r->t0;
    r->t1 = t1 < r->t1 ? t1 : r->t1;
    return 1;
}

static inline float
lut_index_f(const rc_obj *o, float v) {
    float x = (v - o->lut_lo) * o->lut_scale;
    return x < 0 ? 0 : x > VV_VC_LUT - 1 ? VV_VC_LUT - 1 : x;
}

/* ---------------------------------------------------------------------- */
/* Ray kernels                                                              */

typedef struct rc_result {
    float rgb[3];
    float a;
    float depth;
} rc_result;

/* Composites one classified sample (table entry e: opacity, then colour
 * times opacity) at ray parameter t under the accumulated C, A. g is the
 * index-space gradient there (read only when the object is shaded). */
static inline void
composite_sample(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, const float v[3],
                 const float *e, double t, const float g[3], float C[3], float *A) {
    const float w = 1 - *A;
    if (ob->shading) {
        float pw[3] = {0, 0, 0}, out[3];
        if (fr->point_lights) {
            pw[0] = (float)(wr->origin.x + t * wr->dir.x);
            pw[1] = (float)(wr->origin.y + t * wr->dir.y);
            pw[2] = (float)(wr->origin.z + t * wr->dir.z);
        }
        shade(fr, ob, g, pw, v, e + 1, e[0], out);
        C[0] += w * out[0];
        C[1] += w * out[1];
        C[2] += w * out[2];
    } else {
        C[0] += w * e[1];
        C[1] += w * e[2];
        C[2] += w * e[3];
    }
    *A += w * e[0];
}

/* The common case, one volume in composite mode, without the bookkeeping
 * of the general loop: a two-level subvolume skip, then a tight march
 * through each visible subvolume. Produces the same samples (t = k dt) as
 * trace_composite. */
static void
trace_composite_one(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, rc_result *res) {
    vv_vray r;
    float C[3] = {0, 0, 0}, A = 0;
    float depth = INFINITY;
    if (!ray_setup(ob, wr, &r))
        goto done;
    const vv_vcache *c = ob->c;
    const double dt = fr->dt, inv_dt = 1.0 / fr->dt;
    const float et = fr->et;
    const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
    double k = vv_ceil_pos(r.t0 * inv_dt);
    const double kend = vv_floor_pos(r.t1 * inv_dt);
    const unsigned bxm = (unsigned)c->bx - 1, bym = (unsigned)c->by - 1, bzm = (unsigned)c->bz - 1;
    while (k <= kend) {
        double t = k * dt;
        float p[3];
        vv_vray_point(&r, t, p);
        {
            /* Without skipping every subvolume is marked visible and at
             * distance 0, so both cases run this same code and produce the
             * same samples. p >= 0 up to rounding: a negative index wraps and clamps high,
             * so clamp the float instead */
            unsigned bi = (unsigned)(int)((p[0] > 0 ? p[0] : 0) * (1.0f / VV_VC_BLOCK));
            unsigned bj = (unsigned)(int)((p[1] > 0 ? p[1] : 0) * (1.0f / VV_VC_BLOCK));
            unsigned bk = (unsigned)(int)((p[2] > 0 ? p[2] : 0) * (1.0f / VV_VC_BLOCK));
            bi = bi > bxm ? bxm : bi;
            bj = bj > bym ? bym : bj;
            bk = bk > bzm ? bzm : bk;
            size_t b = ((size_t)bk * (size_t)c->by + (size_t)bj) * (size_t)c->bx + (size_t)bi;
            const int dist = ob->bdist[b];
            if (dist) {
                /* leave the empty cube of 2 dist - 1 subvolumes around b */
                const unsigned bc[3] = {bi, bj, bk};
                float te = INFINITY;
                for (int a = 0; a < 3; a++) {
                    if (r.inv[a] == 0)
                        continue;
                    float bound = r.d[a] > 0 ? (float)((int)bc[a] + dist) * VV_VC_BLOCK
                                             : (float)((int)bc[a] - dist + 1) * VV_VC_BLOCK;
                    float ta = (bound - p[a]) * r.inv[a];
                    te = ta < te ? ta : te;
                }
                double ks = vv_ceil_pos((t + te) * inv_dt);
                k = ks > k + 1 ? ks : k + 1;
                continue;
            }
            double te = vv_vray_cube_exit(&r, p, t, VV_VC_BLOCK);
            /* march to the last sample inside this subvolume */
            double klast = vv_floor_pos(te * inv_dt);
            klast = klast < kend ? klast : kend;
            klast = klast < k ? k : klast;
            int n = (int)(klast - k) + 1;
            k = klast + 1;
            /* Two passes per chunk of samples: first every value and its
             * table entry, with no branches, so that the independent samples
             * overlap in the pipeline; then shading and compositing of the
             * non-transparent ones only. */
            for (int s0 = 0; s0 < n; s0 += VV_VC_CHUNK) {
                const int m = n - s0 < VV_VC_CHUNK ? n - s0 : VV_VC_CHUNK;
                size_t cell[VV_VC_CHUNK];
                int32_t entry[VV_VC_CHUNK];
                float fx[VV_VC_CHUNK], fy[VV_VC_CHUNK], fz[VV_VC_CHUNK];
                const double kfirst = klast - (n - 1 - s0);
                vv_vray_classify(c, &ob->tab, &r, kfirst, dt, m, fr->avx2, cell, fx, fy, fz, entry);
                for (int s = 0; s < m; s++) {
                    const float *e = ob->lut + entry[s];
                    const float alpha = e[0];
                    if (alpha <= 0)
                        continue;
                    t = (klast - (n - 1 - (s0 + s))) * dt;
                    float g[3] = {0, 0, 0};
                    if (ob->shading && c->nrm) {
                        const float f[3] = {fx[s], fy[s], fz[s]};
                        vv_vcache_gradient_at(c, cell[s], f, g);
                    } else if (ob->shading) {
                        vv_vray_point(&r, t, p);
                        vv_vcache_gradient(c, p, g);
                    }
                    composite_sample(fr, ob, wr, v, e, t, g, C, &A);
                    if (depth == INFINITY)
                        depth = (float)t;
                    if (A >= et)
                        goto done;
                }
            }
            continue;
        }
    }
done:
    res->rgb[0] = C[0];
    res->rgb[1] = C[1];
    res->rgb[2] = C[2];
    res->a = A > 1 ? 1 : A;
    res->depth = depth;
}

/* Front-to-back compositing of all composite and iso objects along one ray. */
static void
trace_composite(const rc_frame *fr, const vv_ray *wr, rc_result *res) {
    vv_vray rays[RC_MAX_OBJ];
    int act[RC_MAX_OBJ];
    int na = 0;
    double tmin = INFINITY, tmax = -INFINITY;
    for (int i = 0; i < fr->n_comp; i++)
        if (ray_setup(&fr->objs[i], wr, &rays[i])) {
            act[na++] = i;
            tmin = rays[i].t0 < tmin ? rays[i].t0 : tmin;
            tmax = rays[i].t1 > tmax ? rays[i].t1 : tmax;
        }
    float C[3] = {0, 0, 0}, A = 0;
    float depth = INFINITY;
    if (na == 0)
        goto done;
    const double dt = fr->dt;
    const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
    /* iso bookkeeping: previous sample per object */
    float prev_v[RC_MAX_OBJ];
    double prev_t[RC_MAX_OBJ];
    int has_prev[RC_MAX_OBJ];
    for (int i = 0; i < na; i++)
        has_prev[i] = 0;

    double k = vv_ceil_pos(tmin / dt);
    const double kend = vv_floor_pos(tmax / dt);
    while (k <= kend) {
        const double t = k * dt;
        double next_k = k + 1;
        double skip_to = INFINITY; /* min block exit over objects in empty blocks */
        int sampled = 0;
        for (int ai = 0; ai < na; ai++) {
            const rc_obj *ob = &fr->objs[act[ai]];
            const vv_vray *r = &rays[act[ai]];
            if (t < r->t0 || t > r->t1) {
                if (t < r->t0 && r->t0 < skip_to)
                    skip_to = r->t0;
                has_prev[ai] = 0;
                continue;
            }
            float p[3];
            vv_vray_point(r, t, p);
            const vv_vcache *c = ob->c;
            size_t b = vv_vcache_block(c, p);
            if (!ob->bvis[b]) {
                double te = vv_vray_cube_exit(r, p, t, VV_VC_BLOCK);
                if (te < skip_to)
                    skip_to = te;
                if (ob->mode == VV_MODE_ISO) {
                    /* restart the crossing search at the block exit */
                    double tx = te < r->t1 ? te : r->t1;
                    float px[3];
                    vv_vray_point(r, tx, px);
                    prev_v[ai] = vv_vcache_sample(c, px);
                    prev_t[ai] = tx;
                    has_prev[ai] = 1;
                }
                continue;
            }
            sampled = 1;
            const float val = vv_vcache_sample(c, p);
            if (ob->mode == VV_MODE_ISO) {
                float iso = ob->iso;
                double th = -1;
                if (!has_prev[ai]) {
                    if (val >= iso && t - r->t0 < dt)
                        th = t; /* entered already inside (cut face) */
                } else if ((prev_v[ai] < iso) != (val < iso)) {
                    /* bisection between the previous sample and this one */
                    th = vv_vray_iso_refine(c, r, prev_t[ai], prev_v[ai], t, iso);
                }
                prev_v[ai] = val;
                prev_t[ai] = t;
                has_prev[ai] = 1;
                if (th >= 0) {
                    float ph[3], g[3], pw[3], col[3];
                    vv_vray_point(r, th, ph);
                    vv_vcache_gradient(c, ph, g);
                    pw[0] = (float)(wr->origin.x + th * wr->dir.x);
                    pw[1] = (float)(wr->origin.y + th * wr->dir.y);
                    pw[2] = (float)(wr->origin.z + th * wr->dir.z);
                    float base[3] = {ob->sh.base[0], ob->sh.base[1], ob->sh.base[2]};
                    if (ob->textured) {
                        const vv_vec3 tc = vv_texture_map_eval(&ob->obj->texture,
                                                               vv_vextra_object_point(&ob->x, ph));
                        base[0] *= (float)tc.x;
                        base[1] *= (float)tc.y;
                        base[2] *= (float)tc.z;
                    }
                    if (ob->shading)
                        shade(fr, ob, g, pw, v, base, 1.0f, col);
                    else
                        memcpy(col, base, sizeof col);
                    float w = 1 - A;
                    C[0] += w * col[0];
                    C[1] += w * col[1];
                    C[2] += w * col[2];
                    A = 1;
                    if (th < depth)
                        depth = (float)th;
                }
                continue;
            }
            const float *e = ob->lut + 4 * (int)lut_index_f(ob, val);
            if (e[0] <= 0)
                continue;
            float ebuf[4];
            if (ob->extras && (e = vv_vextra_apply(&ob->x, c, p, val, e, ebuf))[0] <= 0)
                continue;
            float g[3] = {0, 0, 0};
            if (ob->shading)
                vv_vcache_gradient(c, p, g);
            composite_sample(fr, ob, wr, v, e, t, g, C, &A);
            if (depth == INFINITY)
                depth = (float)t;
        }
        if (A >= fr->et)
            break;
        if (!sampled && skip_to < INFINITY) {
            double ks = vv_ceil_pos(skip_to / dt);
            if (ks > next_k)
                next_k = ks;
        }
        k = next_k;
    }
done:
    res->rgb[0] = C[0];
    res->rgb[1] = C[1];
    res->rgb[2] = C[2];
    res->a = A > 1 ? 1 : A;
    res->depth = depth;
}

/* Maximum / minimum intensity projection and X-ray (mean) of one object
 * (vv_vray_project). Returns 0 when the ray misses the object. */
static int
trace_projection(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, float *value,
                 float *depth) {
    vv_vray r;
    if (!ray_setup(ob, wr, &r))
        return 0;
    /* MIP and MinIP need not tell apart values the table shows alike */
    vv_vray_project_tables(ob->c, &ob->tab, &r, ob->mode, fr->dt, fr->st->skipping, fr->avx2, value,
                           depth);
    return 1;
}

/* ---------------------------------------------------------------------- */
/* Frame set-up                                                             */

static vv_status
prepare_object(rc_frame *fr, rc_obj *ro, const vv_object *obj, const vv_world *w) {
    rc_state *st = fr->st;
    memset(ro, 0, sizeof *ro);
    ro->obj = obj;
    ro->mode = obj->mode;
    vv_status s = vv_vcache_get(&st->vc, obj->volume, &ro->c);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    s = vv_vobject_prepare(obj, w, fr->ambient, fr->lights, fr->n_lights, ro->w2i, ro->i2w,
                           ro->dims, ro->planes, &ro->n_planes, &ro->sh);
    if (s != VV_OK)
        return s;
    if (st->brick_on) {
        ro->brick = &st->brick;
        for (int a = 0; a < 3; a++)
            ro->dims[a] = st->brick.gdims[a] > 1 ? st->brick.gdims[a] : 2;
    }
    ro->shading = obj->shading;
    if (ro->mode == VV_MODE_COMPOSITE || ro->mode == VV_MODE_ISO)
        vv_vcache_need_normals(&st->vc, ro->c);
    ro->iso = (float)(obj->isovalue - ro->c->qoff);
    return VV_OK;
}

/* The object's tables (vv_vtables_get: borrowed from its volume's cache
 * when nothing they depend on changed). */
static vv_status
prepare_tables(rc_frame *fr, rc_obj *ro) {
    vv_status s = vv_vtables_get(&fr->st->vc, ro->c, ro->obj, ro->mode, fr->dt, ro->iso,
                                 fr->st->skipping, 0, &ro->tab, &ro->owns_tables);
    if (s != VV_OK)
        return s;
    ro->lut_lo = ro->tab.lut_lo;
    ro->lut_scale = ro->tab.lut_scale;
    ro->lut = ro->tab.lut;
    ro->bvis = ro->tab.bvis;
    ro->bdist = ro->tab.bdist;
    ro->extras = vv_vextra_prepare(&ro->x, ro->obj, ro->mode, &ro->tab);
    ro->textured = ro->mode == VV_MODE_ISO && ro->obj->texture.image != NULL;
    return VV_OK;
}

static void
prepare_lights(rc_frame *fr, const vv_world *w, const vv_view *view) {
    fr->n_lights = vv_vlights_prepare(fr->lights, w, view);
    for (int l = 0; l < fr->n_lights; l++)
        fr->point_lights |= fr->lights[l].point;
}

/* vv_view_ray is affine in the pixel position before the direction is
 * normalised; take the affine form from three rays so that every pixel costs
 * a few multiply-adds instead of a camera set-up. */
static void
prepare_rays(rc_frame *fr, const vv_view *view) {
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    vv_ray r00 = vv_view_ray(view, 0, 0), r10 = vv_view_ray(view, 1, 0),
           r01 = vv_view_ray(view, 0, 1);
    vv_ray *rs[3] = {&r00, &r10, &r01};
    for (int i = 0; i < 3; i++) {
        double df = vv_vec3_dot(rs[i]->dir, f);
        if (view->projection != VV_PROJECTION_ORTHOGRAPHIC && df > 0)
            rs[i]->dir = vv_vec3_scale(rs[i]->dir, 1.0 / df);
    }
    fr->o00 = r00.origin;
    fr->ox = vv_vec3_sub(r10.origin, r00.origin);
    fr->oy = vv_vec3_sub(r01.origin, r00.origin);
    fr->d00 = r00.dir;
    fr->dx = vv_vec3_sub(r10.dir, r00.dir);
    fr->dy = vv_vec3_sub(r01.dir, r00.dir);
}

/* ---------------------------------------------------------------------- */
/* The renderer                                                             */

static void
render_pixel(const rc_frame *fr, int x, int y, vv_image *out) {
    /* inline: this runs for every pixel, most of which miss the volume */
    const double fx = x, fy = y;
    vv_ray wr;
    wr.origin.x = fr->o00.x + fx * fr->ox.x + fy * fr->oy.x;
    wr.origin.y = fr->o00.y + fx * fr->ox.y + fy * fr->oy.y;
    wr.origin.z = fr->o00.z + fx * fr->ox.z + fy * fr->oy.z;
    double dx = fr->d00.x + fx * fr->dx.x + fy * fr->dy.x;
    double dy = fr->d00.y + fx * fr->dx.y + fy * fr->dy.y;
    double dz = fr->d00.z + fx * fr->dx.z + fy * fr->dy.z;
    double inv = 1.0 / sqrt(dx * dx + dy * dy + dz * dz);
    wr.dir.x = dx * inv;
    wr.dir.y = dy * inv;
    wr.dir.z = dz * inv;
    rc_result res = {{0, 0, 0}, 0, INFINITY};
    if (fr->n_comp == 1 && fr->objs[0].mode == VV_MODE_COMPOSITE && !fr->objs[0].extras)
        trace_composite_one(fr, &fr->objs[0], &wr, &res);
    else if (fr->n_comp > 0)
        trace_composite(fr, &wr, &res);
    /* projection objects: combined behind the composited ones */
    float P[3] = {0, 0, 0}, PA = 0, pdepth = INFINITY;
    for (int i = fr->n_comp; i < fr->n_obj; i++) {
        const rc_obj *ob = &fr->objs[i];
        float val, dep;
        if (!trace_projection(fr, ob, &wr, &val, &dep))
            continue;
        const float *e = ob->lut + 4 * (int)lut_index_f(ob, val);
        for (int ch = 0; ch < 3; ch++) {
            float cv = e[1 + ch] * e[0];
            P[ch] = cv > P[ch] ? cv : P[ch];
        }
        PA = e[0] > PA ? e[0] : PA;
        pdepth = dep < pdepth ? dep : pdepth;
    }
    float *pix = out->rgba + 4 * ((size_t)y * (size_t)out->width + (size_t)x);
    if (fr->st->brick_on && fr->n_comp == 0) {
        /* a projection brick: its extreme value, classified once the bricks
         * are combined (vv_raycast_finish_projection) */
        float val = 0, dep = INFINITY;
        const int hit = fr->n_obj == 1 && trace_projection(fr, &fr->objs[0], &wr, &val, &dep);
        pix[0] = hit ? val : 0;
        pix[1] = (float)hit;
        pix[2] = pix[3] = 0;
        out->depth[(size_t)y * (size_t)out->width + (size_t)x] = hit ? dep : INFINITY;
        return;
    }
    float A = res.a;
    float rest = 1 - A;
    float A2 = A + rest * PA;
    for (int ch = 0; ch < 3; ch++)
        pix[ch] = res.rgb[ch] + rest * P[ch] + (1 - A2) * fr->bg[ch];
    pix[3] = A2;
    out->depth[(size_t)y * (size_t)out->width + (size_t)x] =
        res.depth < pdepth ? res.depth : pdepth;
}

static vv_status
rc_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    rc_state *st = state;
    rc_frame fr;
    memset(&fr, 0, sizeof fr);
    fr.st = st;
    st->vc.frame++;
    fr.avx2 = st->simd && vv_vc_have_avx2();
    fr.view = view;
    fr.et = (float)st->early_termination;
    fr.ambient[0] = (float)w->ambient.x;
    fr.ambient[1] = (float)w->ambient.y;
    fr.ambient[2] = (float)w->ambient.z;
    fr.bg[0] = (float)w->background.x;
    fr.bg[1] = (float)w->background.y;
    fr.bg[2] = (float)w->background.z;
    prepare_lights(&fr, w, view);
    prepare_rays(&fr, view);

    int nvis = 0;
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->visible && w->objects[i]->type == VV_OBJECT_VOLUME &&
            w->objects[i]->volume)
            nvis++;
    if (nvis > RC_MAX_OBJ)
        return vv_error_set(VV_ERR_LIMIT, "%d visible objects; at most %d are supported", nvis,
                            RC_MAX_OBJ);
    if (st->brick_on) {
        if (nvis != 1)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "raycast: a brick render draws one volume object, not %d", nvis);
        for (int i = 0; i < w->n_objects; i++) {
            const vv_object *ob = w->objects[i];
            if (ob->visible && ob->type == VV_OBJECT_VOLUME && ob->volume &&
                ob->mode != VV_MODE_COMPOSITE && ob->mode != VV_MODE_MIP &&
                ob->mode != VV_MODE_MINIP)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "raycast: object '%s': a brick render draws composite, mip "
                                    "or minip, not this mode",
                                    ob->name);
        }
        /* partial pixels: no background, it is added once to the whole */
        fr.bg[0] = fr.bg[1] = fr.bg[2] = 0;
    }
    rc_obj *objs = calloc(nvis ? (size_t)nvis : 1, sizeof *objs);
    if (!objs)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    fr.objs = objs;
    /* composite and iso objects first, projections after */
    double dt = INFINITY;
    vv_status s = VV_OK;
    for (int pass = 0; pass < 2 && s == VV_OK; pass++)
        for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
            const vv_object *ob = w->objects[i];
            if (!ob->visible || ob->type != VV_OBJECT_VOLUME || !ob->volume)
                continue;
            int comp = ob->mode == VV_MODE_COMPOSITE || ob->mode == VV_MODE_ISO;
            if (comp != (pass == 0))
                continue;
            if (!(ob->step > 0))
                s = vv_error_set(VV_ERR_INVALID, "object '%s': step must be > 0", ob->name);
            else
                s = prepare_object(&fr, &objs[fr.n_obj++], ob, w);
            if (s == VV_OK) {
                double sd = vv_vobject_step(ob);
                dt = sd < dt ? sd : dt;
            }
            if (pass == 0)
                fr.n_comp = fr.n_obj;
        }
    fr.dt = (float)(dt < INFINITY ? dt : 1.0);
    for (int i = 0; i < fr.n_obj && s == VV_OK; i++) {
        s = prepare_tables(&fr, &objs[i]);
        objs[i].dt = fr.dt;
        objs[i].inv_form = fr.n_comp == 1 && objs[i].mode == VV_MODE_COMPOSITE && !objs[i].extras;
    }
    if (s == VV_OK && st->brick_on && fr.n_comp == 0 && fr.n_obj == 1) {
        /* keep the projection table for vv_raycast_finish_projection */
        if (!st->plut)
            st->plut = malloc(sizeof(float) * 4 * VV_VC_LUT);
        if (!st->plut) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        } else {
            memcpy(st->plut, objs[0].lut, sizeof(float) * 4 * VV_VC_LUT);
            st->plut_lo = objs[0].lut_lo;
            st->plut_scale = objs[0].lut_scale;
            st->pbg[0] = (float)w->background.x;
            st->pbg[1] = (float)w->background.y;
            st->pbg[2] = (float)w->background.z;
        }
    }

    int rx0 = 0, ry0 = 0, rx1 = view->width, ry1 = view->height;
    if (s == VV_OK && st->brick_on && st->brick.x1 > st->brick.x0) {
        /* only the brick's rectangle is traced; the rest stays empty */
        const size_t np = (size_t)view->width * (size_t)view->height;
        memset(out->rgba, 0, sizeof(float) * 4 * np);
        for (size_t i = 0; i < np; i++)
            out->depth[i] = INFINITY;
        rx0 = st->brick.x0 > 0 ? st->brick.x0 : 0;
        ry0 = st->brick.y0 > 0 ? st->brick.y0 : 0;
        rx1 = st->brick.x1 < view->width ? st->brick.x1 : view->width;
        ry1 = st->brick.y1 < view->height ? st->brick.y1 : view->height;
    }
    if (s == VV_OK) {
        const int tx = (view->width + RC_TILE - 1) / RC_TILE;
        const int ty = (view->height + RC_TILE - 1) / RC_TILE;
        const int ntiles = tx * ty;
        const int nt = opt->threads > 0 ? opt->threads : vv_threads_get();
        atomic_int cancelled = 0;
        int done = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
        for (int tile = 0; tile < ntiles; tile++) {
            if (atomic_load_explicit(&cancelled, memory_order_relaxed))
                continue;
            int x0 = (tile % tx) * RC_TILE, y0 = (tile / tx) * RC_TILE;
            int x1 = x0 + RC_TILE < view->width ? x0 + RC_TILE : view->width;
            int y1 = y0 + RC_TILE < view->height ? y0 + RC_TILE : view->height;
            x0 = x0 > rx0 ? x0 : rx0;
            y0 = y0 > ry0 ? y0 : ry0;
            x1 = x1 < rx1 ? x1 : rx1;
            y1 = y1 < ry1 ? y1 : ry1;
            for (int y = y0; y < y1; y++)
                for (int x = x0; x < x1; x++)
                    render_pixel(&fr, x, y, out);
            if (opt->progress.fn) {
#pragma omp critical(vv_raycast_progress)
                {
                    done++;
                    if (vv_progress_report(&opt->progress, (double)done / ntiles))
                        atomic_store(&cancelled, 1);
                }
            }
        }
        if (atomic_load(&cancelled))
            s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
    }
    for (int i = 0; i < fr.n_obj; i++) {
        if (objs[i].owns_tables)
            vv_vtables_free(&objs[i].tab);
    }
    free(objs);
    /* drop cached volumes the World no longer shows */
    vv_vcache_set_prune(&st->vc, w);
    return s;
}

static vv_status
rc_create(void **state) {
    rc_state *st = calloc(1, sizeof *st);
    if (!st)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    st->early_termination = 0.99;
    vv_vcache_set_init(&st->vc);
    st->skipping = 1;
    st->simd = 1;
    *state = st;
    return VV_OK;
}

static vv_status
rc_set_option(void *state, const char *key, const char *value) {
    rc_state *st = state;
    char *end = NULL;
    double x = strtod(value, &end);
    if (!end || *end || end == value || x != x)
        return vv_error_set(VV_ERR_INVALID, "option %s: '%s' is not a number", key, value);
    if (strcmp(key, "early_termination") == 0) {
        if (!(x > 0 && x <= 1))
            return vv_error_set(VV_ERR_INVALID, "early_termination must be in (0, 1]");
        st->early_termination = x;
    } else if (strcmp(key, "gradient_budget_mb") == 0) {
        if (!(x >= 0))
            return vv_error_set(VV_ERR_INVALID, "gradient_budget_mb must be >= 0");
        st->vc.gradient_budget = (uint64_t)(x * 1048576.0);
        vv_vcache_set_clear(&st->vc);
    } else if (strcmp(key, "empty_space_skipping") == 0) {
        st->skipping = x != 0;
    } else if (strcmp(key, "simd") == 0) {
        st->simd = x != 0;
    } else {
        return vv_error_set(VV_ERR_INVALID,
                            "unknown option '%s' (early_termination, gradient_budget_mb, "
                            "empty_space_skipping, simd)",
                            key);
    }
    return VV_OK;
}

static void
rc_destroy(void *state) {
    rc_state *st = state;
    if (!st)
        return;
    vv_vcache_set_clear(&st->vc);
    free(st->plut);
    free(st);
}

vv_status
vv_raycast_set_brick(vv_renderer *r, const vv_raycast_brick *b) {
    if (!r || strcmp(vv_renderer_name(r), "raycast") != 0)
        return vv_error_set(VV_ERR_INVALID, "brick rendering needs the raycast renderer");
    rc_state *st = vv_renderer_state(r);
    st->brick_on = b != NULL;
    if (b)
        st->brick = *b;
    return VV_OK;
}

/* Solves the 3x3 system with columns c0, c1, c2 for rhs (Cramer); 0 when
 * singular. */
static int
solve3(vv_vec3 c0, vv_vec3 c1, vv_vec3 c2, vv_vec3 rhs, double x[3]) {
    const double det = vv_vec3_dot(c0, vv_vec3_cross(c1, c2));
    if (!(fabs(det) > 1e-300))
        return 0;
    x[0] = vv_vec3_dot(rhs, vv_vec3_cross(c1, c2)) / det;
    x[1] = vv_vec3_dot(c0, vv_vec3_cross(rhs, c2)) / det;
    x[2] = vv_vec3_dot(c0, vv_vec3_cross(c1, rhs)) / det;
    return 1;
}

void
vv_raycast_brick_rect(vv_raycast_brick *b, const vv_object *obj, const vv_view *view,
                      const int lo[3], const int hi[3]) {
    b->x0 = b->y0 = 0;
    b->x1 = b->y1 = 0; /* whole image until proven smaller */
    /* primary rays are affine in the pixel position (prepare_rays): origin
     * O00 + px OX + py OY, direction along D00 + px DX + py DY */
    const vv_ray r00 = vv_view_ray(view, 0, 0), r10 = vv_view_ray(view, 1, 0),
                 r01 = vv_view_ray(view, 0, 1);
    const int ortho = view->projection == VV_PROJECTION_ORTHOGRAPHIC;
    const vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    vv_vec3 d[3] = {r00.dir, r10.dir, r01.dir};
    if (!ortho)
        for (int i = 0; i < 3; i++) {
            const double df = vv_vec3_dot(d[i], f);
            if (!(df > 0))
                return;
            d[i] = vv_vec3_scale(d[i], 1.0 / df);
        }
    const vv_vec3 DX = vv_vec3_sub(d[1], d[0]), DY = vv_vec3_sub(d[2], d[0]);
    const vv_vec3 OX = vv_vec3_sub(r10.origin, r00.origin),
                  OY = vv_vec3_sub(r01.origin, r00.origin);
    const vv_mat4 m = vv_object_index_to_world(obj);
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int c = 0; c < 8; c++) {
        const vv_vec3 pi =
            vv_vec3_make(c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]);
        const vv_vec3 pw = vv_mat4_mul_point(m, pi);
        double x[3];
        if (ortho) {
            if (!solve3(OX, OY, f, vv_vec3_sub(pw, r00.origin), x))
                return;
        } else {
            if (!solve3(DX, DY, d[0], vv_vec3_sub(pw, r00.origin), x) || !(x[2] > 1e-9))
                return; /* behind the eye: every pixel may see it */
            x[0] /= x[2];
            x[1] /= x[2];
        }
        xmin = x[0] < xmin ? x[0] : xmin;
        xmax = x[0] > xmax ? x[0] : xmax;
        ymin = x[1] < ymin ? x[1] : ymin;
        ymax = x[1] > ymax ? x[1] : ymax;
    }
    if (!(xmax - xmin < 1e7 && ymax - ymin < 1e7))
        return;
    /* pixel px's ray is at px: the pixels within two of the projection */
    const double X0 = floor(xmin) - 2, X1 = ceil(xmax) + 3, Y0 = floor(ymin) - 2,
                 Y1 = ceil(ymax) + 3;
    b->x0 = X0 < 0 ? 0 : X0 > view->width ? view->width : (int)X0;
    b->x1 = X1 < 0 ? 0 : X1 > view->width ? view->width : (int)X1;
    b->y0 = Y0 < 0 ? 0 : Y0 > view->height ? view->height : (int)Y0;
    b->y1 = Y1 < 0 ? 0 : Y1 > view->height ? view->height : (int)Y1;
    if (b->x1 <= b->x0 || b->y1 <= b->y0) {
        /* off screen: an empty rectangle that is not "whole image" */
        b->x0 = 0;
        b->x1 = 1;
        b->y0 = b->y1 = 0;
    }
}

vv_status
vv_raycast_finish_projection(vv_renderer *r, vv_image *img) {
    if (!r || strcmp(vv_renderer_name(r), "raycast") != 0)
        return vv_error_set(VV_ERR_INVALID, "brick rendering needs the raycast renderer");
    const rc_state *st = vv_renderer_state(r);
    if (!st->plut)
        return vv_error_set(VV_ERR_INVALID, "no projection brick was rendered");
    const size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++) {
        float *pix = img->rgba + 4 * i;
        /* as render_pixel: no composite object (A = 0), one projection */
        float P[3] = {0, 0, 0}, PA = 0;
        if (pix[1] > 0) {
            float x = (pix[0] - st->plut_lo) * st->plut_scale;
            x = x < 0 ? 0 : x > VV_VC_LUT - 1 ? VV_VC_LUT - 1 : x;
            const float *e = st->plut + 4 * (int)x;
            for (int ch = 0; ch < 3; ch++) {
                float cv = e[1 + ch] * e[0];
                P[ch] = cv > P[ch] ? cv : P[ch];
            }
            PA = e[0] > PA ? e[0] : PA;
        }
        const float A = 0, rest = 1 - A, A2 = A + rest * PA;
        for (int ch = 0; ch < 3; ch++)
            pix[ch] = 0 + rest * P[ch] + (1 - A2) * st->pbg[ch];
        pix[3] = A2;
    }
    return VV_OK;
}

const vv_renderer_ops vv_raycast_ops = {
    "raycast",
    "direct volume ray casting: composite, mip, minip, xray, iso; subvolume skipping",
    rc_create,
    rc_set_option,
    rc_render,
    rc_destroy,
    "early_termination (0.99), gradient_budget_mb, empty_space_skipping (1), simd (1)",
};
