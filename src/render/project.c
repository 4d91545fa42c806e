/*
 * The projection stage: maximum and minimum intensity projection, the
 * X-ray mean and sum, several channels' maxima in one pass, and the first
 * isosurface crossing along a ray (project.h describes them). The portable
 * paths are here; the AVX2 march of MIP and MinIP and the eight-lane
 * samples are in kernels_avx2.c.
 */
#include "render/project.h"

#include <math.h>
#include <string.h>

#include "render/frame.h"
#include "render/kernels_avx2.h"

/* The last sample (at most kend, at least k) in the subvolume of p. */
static inline double
proj_block_last(const vv_vray *r, const float p[3], double k, double kend, double dt) {
    double klast = vv_floor_pos(vv_vray_cube_exit(r, p, k * dt, VV_VC_BLOCK) / dt);
    klast = klast < kend ? klast : kend;
    return klast < k ? k : klast;
}

/* The samples k .. klast of ray r in the running maximum of sg * value
 * (best, tbest: the parameter of its first sample): one subvolume's march.
 * inline: GCC inlined it into its callers unasked while they shared a
 * translation unit with the AVX2 code; alone with them it needs the hint. */
static inline void
project_block(const vv_vcache *c, const vv_vray *r, double k, double klast, double dt, float sg,
              int avx2, float *best, double *tbest) {
#if VV_VC_HAVE_AVX2
    if (avx2) {
        while (k <= klast) {
            const int m = klast - k + 1 < VV_VC_CHUNK ? (int)(klast - k + 1) : VV_VC_CHUNK;
            float val[VV_VC_CHUNK];
            vv_vray_values_avx2(c, r, k, dt, m, val);
            for (int s = 0; s < m; s++) {
                const float x = sg * val[s];
                if (x > *best) {
                    *best = x;
                    *tbest = (k + s) * dt;
                }
            }
            k += m;
        }
        return;
    }
#else
    (void)avx2;
#endif
    for (; k <= klast; k++) {
        float p[3], f[3];
        vv_vray_point(r, k * dt, p);
        const size_t o = vv_vcache_cell_in(c, p, f);
        const float x = sg * vv_vcache_value_at(c, o, f);
        if (x > *best) {
            *best = x;
            *tbest = k * dt;
        }
    }
}

/* The maximum of sg * value over the samples k .. kend of r that exceed
 * @p floor0 (floor0 itself when none does, at parameter t0), stopping once
 * it reaches @p stop (at the end of the subvolume where it does);
 * *tbest: the parameter of its first sample. One subvolume at a time. */
static float
project_from(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, double dt, double k,
             double kend, float sg, float floor0, float stop, int skipping, double *tbest_out) {
    const float *bext = sg > 0 ? c->bmax : c->bmin, *gext = sg > 0 ? c->gmax : c->gmin;
    float best = floor0;
    double tbest = r->t0;
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    while (k <= kend && best < stop) {
        float p[3];
        vv_vray_point(r, k * dt, p);
        int bc[3];
        const size_t b = vv_vproj_block(c, p, bc);
        if (skipping && pdist && pdist[b]) {
            /* leave the cube of 2 dist - 1 subvolumes around p that hold
             * nothing beyond the starting bound */
            k = vv_vproj_leap(r, p, bc, pdist[b], k, dt);
            continue;
        }
        if (skipping) {
            /* a group, then a subvolume, that cannot beat the current
             * extreme is skipped whole (the test is strict, so its samples
             * could not change the result) */
            int size = 0;
            if (sg * gext[vv_vproj_group(c, p)] <= best)
                size = gsize;
            else if (sg * bext[b] <= best)
                size = VV_VC_BLOCK;
            if (size) {
                k = vv_vproj_after_cube(r, p, k, dt, size);
                continue;
            }
        }
        const double klast = proj_block_last(r, p, k, kend, dt);
        project_block(c, r, k, klast, dt, sg, 0, &best, &tbest);
        k = klast + 1;
    }
    *tbest_out = tbest;
    return best;
}

/* project_from, or with @p vec its AVX2 path */
static float
march(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, double dt, double k, double kend,
      float sg, float floor0, float stop, int skipping, int vec, double *tbest) {
#if VV_VC_HAVE_AVX2
    if (vec)
        return vv_vproj_from_avx2(c, pdist, r, dt, k, kend, sg, floor0, stop, skipping, tbest);
#else
    (void)vec;
#endif
    return project_from(c, pdist, r, dt, k, kend, sg, floor0, stop, skipping, tbest);
}

/* A ray shorter than one step: its one sample, in the middle (*depth). */
static float
middle_sample(const vv_vcache *c, const vv_vray *r, float *depth) {
    float p[3];
    const double tm = 0.5 * (r->t0 + r->t1);
    vv_vray_point(r, tm, p);
    *depth = (float)tm;
    return vv_vcache_sample(c, p);
}

void
vv_xray_table_classify(const void *ctx, float v, float e[4]) {
    const vv_xray_table *x = ctx;
    float i = (v - x->lut_lo) * x->lut_scale;
    i = i > 0 ? (i < VV_VC_LUT - 1 ? i : VV_VC_LUT - 1) : 0; /* NaN: 0 (vv_vtables_index) */
    memcpy(e, x->lut + 4 * (int)i, 4 * sizeof(float));
}

vv_status
vv_region_render_by_frame(vv_region_frame_fn frame, void *state, const vv_xray_table *xray,
                          const vv_world *w, const vv_view *view, const vv_render_region *region,
                          const vv_render_options *opt, vv_region_image *out) {
    vv_region_world rw;
    vv_status s = vv_render_region_world(w, region, &out->op, &rw);
    if (s != VV_OK)
        return s;
    s = frame(state, &rw.world, view, opt, region, out->image, out->key);
    vv_region_world_release(&rw);
    const int table = out->op == VV_REGION_SUM || out->op == VV_REGION_ATTENUATED_MAX;
    out->classify = table ? vv_xray_table_classify : NULL;
    out->classify_ctx = table ? xray : NULL;
    return s;
}

long
vv_vray_xray_region_pixel(const vv_vcache *c, const double w2i[3][4], const int dims[3],
                          const vv_plane *planes, int n_planes, const vv_render_region *rg,
                          double dt, int inv_form, const vv_ray *wr, int avx2, float px[4],
                          float *depth, float *key) {
    px[0] = px[1] = px[2] = px[3] = 0;
    *depth = INFINITY;
    *key = NAN;
    vv_vray r;
    int cont = 0;
    if (!vv_vray_setup(w2i, dims, planes, n_planes, wr, 0, INFINITY, &r))
        return 0;
    const float entry = (float)r.t0;
    const int shortray = vv_ceil_pos(r.t0 / dt) > vv_floor_pos(r.t1 / dt);
    if (!vv_vray_clip_region(&r, rg, dt, inv_form, &cont))
        return 0;
    double sum;
    float mid;
    const long n = vv_vray_xray_sum(c, &r, dt, avx2, &sum, &mid);
    if (n <= 0)
        return 0;
    const float hi = (float)sum;
    *key = hi;
    px[0] = (float)(sum - (double)hi);
    px[1] = (float)n;
    /* the whole ray's depth: its entry, or its one middle sample */
    *depth = shortray ? mid : cont ? INFINITY : entry;
    return n;
}

long
vv_vray_xray_sum(const vv_vcache *c, const vv_vray *r, double dt, int avx2, double *sum,
                 float *depth) {
    double k = vv_ceil_pos(r->t0 / dt);
    const double kend = vv_floor_pos(r->t1 / dt);
    if (k > kend) {
        *sum = middle_sample(c, r, depth);
        return 1;
    }
    const int vec = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
    double acc = 0;
    long n = 0;
#if VV_VC_HAVE_AVX2
    /* the same values, eight at a time, added in the same order */
    for (; vec && k <= kend; k += VV_VC_CHUNK) {
        const int m = kend - k + 1 < VV_VC_CHUNK ? (int)(kend - k + 1) : VV_VC_CHUNK;
        float val[VV_VC_CHUNK];
        vv_vray_values_avx2(c, r, k, dt, m, val);
        for (int s = 0; s < m; s++)
            acc += val[s];
        n += m;
    }
#else
    (void)vec;
#endif
    for (; k <= kend; k++) {
        float p[3], f[3];
        vv_vray_point(r, k * dt, p);
        const size_t o = vv_vcache_cell_in(c, p, f);
        acc += vv_vcache_value_at(c, o, f);
        n++;
    }
    *sum = acc;
    *depth = (float)r->t0;
    return n;
}

static void
project(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, vv_render_mode mode, double dt,
        int skipping, int avx2, float lo, float hi, float *value, float *depth) {
    if (mode == VV_MODE_XRAY) {
        double sum;
        const long n = vv_vray_xray_sum(c, r, dt, avx2, &sum, depth);
        *value = (float)(sum / (double)n);
        return;
    }
    double k = vv_ceil_pos(r->t0 / dt);
    const double kend = vv_floor_pos(r->t1 / dt);
    if (k > kend) {
        *value = middle_sample(c, r, depth);
        return;
    }
    const int vec = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
    const int mip = mode == VV_MODE_MIP;
    /* work on the maximum of +-value, so MinIP is MIP of the negation */
    const float sg = mip ? 1.0f : -1.0f;
    const float floor0 = mip ? lo : -hi; /* what nothing below can change */
    const float stop = mip ? hi : -lo;   /* what nothing above can change */
    double tbest;
    const float best = march(c, pdist, r, dt, k, kend, sg, floor0, stop, skipping, vec, &tbest);
    *value = sg * best;
    *depth = (float)tbest;
}

vv_status
vv_vatten_prepare(vv_vatten *a, const vv_object *obj, const vv_vcache *c, float dt) {
    if (!(obj->attenuation >= 0) || !isfinite(obj->attenuation))
        return vv_error_set(VV_ERR_INVALID, "object '%s': attenuation must be >= 0, got %g",
                            obj->name, obj->attenuation);
    /* the normalisation of napari's sum, its contrast limits: the span of
     * the transfer function's opacity points (a contrast ramp's, or
     * napari's table over its limits), else the volume's range */
    const vv_tf *tf = &obj->tf;
    double lo = obj->volume->range[0], hi = obj->volume->range[1];
    if (tf->n_opacity >= 2 && tf->opacity[tf->n_opacity - 1].value > tf->opacity[0].value) {
        lo = tf->opacity[0].value;
        hi = tf->opacity[tf->n_opacity - 1].value;
    }
    if (!(hi > lo))
        hi = lo + 1;
    a->lo = (float)(lo - c->qoff);
    a->inv_range = (float)(1.0 / (hi - lo));
    a->qoff = (float)c->qoff;
    float vmax = -INFINITY;
    for (size_t g = 0; g < (size_t)c->gx * (size_t)c->gy * (size_t)c->gz; g++)
        vmax = c->gmax[g] > vmax ? c->gmax[g] : vmax;
    a->vmax = vmax;
    /* napari's relative step: the frame's step in units of the object's
     * smallest voxel spacing */
    const double rel = dt * obj->step / vv_vobject_step(obj);
    a->k = obj->attenuation / rel;
    return VV_OK;
}

void
vv_vray_attenuated_mip(const vv_vcache *c, const vv_vray *r, double dt, const vv_vatten *a,
                       float *value, float *depth) {
    double k = vv_ceil_pos(r->t0 / dt);
    const double kend = vv_floor_pos(r->t1 / dt);
    if (k > kend) {
        /* one sample: S is its own normalised value */
        const float v = middle_sample(c, r, depth);
        float n = (v - a->lo) * a->inv_range;
        n = n < 0 ? 0 : n > 1 ? 1 : n;
        const float f = (float)exp(-a->k * ((double)n - 1.0));
        *value = v * f + a->qoff * (f - 1);
        return;
    }
    double sum = 0;
    float best = -INFINITY;
    double tbest = k * dt;
    /* (a real maximum below 0 grows as its scale shrinks: no bound) */
    const int stop = (double)a->vmax + (double)a->qoff >= 0;
    for (; k <= kend; k++) {
        float p[3];
        vv_vray_point(r, k * dt, p);
        const float v = vv_vcache_sample(c, p);
        float n = (v - a->lo) * a->inv_range;
        n = n < 0 ? 0 : n > 1 ? 1 : n;
        sum += n;
        /* (v + qoff) f - qoff, written so that f == 1 gives v exactly */
        const float f = a->k == 0 ? 1.0f : (float)exp(-a->k * (sum - 1.0));
        const float x = v * f + a->qoff * (f - 1);
        if (x > best) {
            best = x;
            tbest = k * dt;
        }
        /* every later sample is at most vmax, scaled by at most f */
        if (stop && a->vmax * f + a->qoff * (f - 1) <= best)
            break;
    }
    *value = best;
    *depth = (float)tbest;
}

long
vv_vray_attenuated_region_pixel(const vv_vcache *c, const double w2i[3][4], const int dims[3],
                                const vv_plane *planes, int n_planes, const vv_render_region *rg,
                                double dt, int inv_form, const vv_ray *wr, const vv_vatten *a,
                                float px[4], float *depth, float *key) {
    px[0] = px[1] = px[2] = px[3] = 0;
    *depth = INFINITY;
    *key = NAN;
    vv_vray r;
    if (!vv_vray_setup(w2i, dims, planes, n_planes, wr, 0, INFINITY, &r) ||
        !vv_vray_clip_region(&r, rg, dt, inv_form, NULL))
        return 0;
    /* a sample's exponent per unit of normalised value: k, weighed by the
     * world length of the region's step against the finest level's */
    const double ke = a->k * (rg->step_scale > 0 ? rg->step_scale : 1);
    double k = vv_ceil_pos(r.t0 / dt);
    const double kend = vv_floor_pos(r.t1 / dt);
    /* a ray shorter than a step: its one middle sample */
    const int one = k > kend;
    const long n = one ? 1 : (long)(kend - k) + 1;
    double e = 0, best = -INFINITY;
    float tbest = INFINITY;
    for (long j = 0; j < n; j++, k++) {
        float v, t;
        if (one) {
            v = middle_sample(c, &r, &t);
        } else {
            float p[3];
            t = (float)(k * dt);
            vv_vray_point(&r, k * dt, p);
            v = vv_vcache_sample(c, p);
        }
        float nv = (v - a->lo) * a->inv_range;
        nv = nv < 0 ? 0 : nv > 1 ? 1 : nv;
        /* the real value scaled by exp(k - E) (exactly itself when k is 0),
         * E counting the sample itself once, as one sample of the finest
         * level: it stands at the start of its run of step_scale of them,
         * the first of which (the largest scale) a finer render takes */
        const double x =
            ((double)v + (double)a->qoff) * (a->k == 0 ? 1.0 : exp(a->k - (e + a->k * nv)));
        if (x > best) {
            best = x;
            tbest = t;
        }
        e += ke * nv; /* the samples behind it see all of its run */
    }
    *key = (float)best;
    *depth = tbest;
    px[0] = (float)e;
    return n;
}

double
vv_vray_iso_first(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt, float iso,
                  int avx2, int cont) {
    const double k0 = vv_ceil_pos(r->t0 / dt), kend = vv_floor_pos(r->t1 / dt);
    const int vec = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
    double k = k0, klast, kprev = k0 - 2; /* the last sample of the previous run */
    float pv = 0;                         /* the value at pt (one side of iso) */
    double pt = 0;
    int have = 0;
    if (cont && k0 <= kend) {
        /* a region's search starts at the whole ray's sample before it */
        vv_vray_iso_restart(c, r, k0, dt, &pv, &pt, &have);
        if (pv >= iso)
            return pt;
        kprev = k0 - 1;
    }
    while (vv_vray_visible_run_simd(avx2, c, bdist, r, dt, kend, &k, &klast)) {
        if (k > k0 && k != kprev + 1) {
            /* after hidden samples (all below iso): the crossing search
             * restarts at the sample before the run, as a march of every
             * sample has it, so that the crossing does not depend on the
             * subvolume grid (skipping on or off, a region's voxels) */
            vv_vray_iso_restart(c, r, k, dt, &pv, &pt, &have);
        }
        /* a run of the portable traversal may exceed a chunk (its first
         * subvolume is whole, and holds more than VV_VC_CHUNK samples at a
         * step under 1/8 voxel) */
        for (double j = k; j <= klast; j += VV_VC_CHUNK) {
            const int n = klast - j + 1 < VV_VC_CHUNK ? (int)(klast - j) + 1 : VV_VC_CHUNK;
            float val[VV_VC_CHUNK];
#if VV_VC_HAVE_AVX2
            if (vec)
                vv_vray_values_avx2(c, r, j, dt, n, val);
#else
            (void)vec;
#endif
            for (int s = 0; s < n; s++) {
                const double t = (j + s) * dt;
                if (!vec) {
                    float p[3];
                    vv_vray_point(r, t, p);
                    val[s] = vv_vcache_sample(c, p);
                }
                if (!have) {
                    if (val[s] >= iso && t - r->t0 < dt)
                        return t; /* entered already inside (a cut face) */
                } else if ((pv < iso) != (val[s] < iso)) {
                    return vv_vray_iso_refine(c, r, pt, pv, t, iso);
                }
                pv = val[s];
                pt = t;
                have = 1;
            }
        }
        kprev = klast;
        k = klast + 1;
    }
    return -1;
}

void
vv_vray_project(const vv_vcache *c, const vv_vray *r, vv_render_mode mode, double dt, int skipping,
                float lo, float hi, float *value, float *depth) {
    project(c, NULL, r, mode, dt, skipping, 0, lo, hi, value, depth);
}

void
vv_vray_project_tables(const vv_vcache *c, const vv_vtables *t, const vv_vray *r,
                       vv_render_mode mode, double dt, int skipping, int avx2, float *value,
                       float *depth) {
    if (t->pdist)
        project(c, t->pdist, r, mode, dt, skipping, avx2, t->plo, t->phi, value, depth);
    else
        project(c, NULL, r, mode, dt, skipping, avx2, -INFINITY, INFINITY, value, depth);
}

void
vv_vray_project_channels(const vv_vcache *const *cs, const vv_vtables *const *ts, int n,
                         const vv_vray *r, double dt, int skipping, int avx2, float *value,
                         float *depth) {
    double k = vv_ceil_pos(r->t0 / dt);
    const double kend = vv_floor_pos(r->t1 / dt);
    if (k > kend || n < 2 || n > VV_MAX_CHANNELS) {
        for (int ch = 0; ch < n; ch++)
            vv_vray_project_tables(cs[ch], ts[ch], r, VV_MODE_MIP, dt, skipping, avx2, &value[ch],
                                   &depth[ch]);
        return;
    }
    float best[VV_MAX_CHANNELS], stop[VV_MAX_CHANNELS];
    double tbest[VV_MAX_CHANNELS];
    int vec[VV_MAX_CHANNELS], act[VV_MAX_CHANNELS], na = 0;
    for (int ch = 0; ch < n; ch++) {
        const vv_vcache *c = cs[ch];
        best[ch] = ts[ch]->pdist ? ts[ch]->plo : -INFINITY;
        stop[ch] = ts[ch]->pdist ? ts[ch]->phi : INFINITY;
        tbest[ch] = r->t0;
        vec[ch] = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
        if (best[ch] < stop[ch])
            act[na++] = ch;
    }
    const vv_vcache *c0 = cs[0]; /* every channel has its grid */
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    while (k <= kend && na > 0) {
        float p[3];
        vv_vray_point(r, k * dt, p);
        int bc[3];
        const size_t b = vv_vproj_block(c0, p, bc);
        if (skipping) {
            /* the cube of subvolumes that no live channel has anything in
             * beyond its starting bound (the smallest of their distances),
             * then the group or subvolume that no live channel can beat
             * its maximum in */
            int dist = 255, size = gsize;
            const size_t g = vv_vproj_group(c0, p);
            for (int i = 0; i < na; i++) {
                const int ch = act[i];
                const int d = ts[ch]->pdist ? ts[ch]->pdist[b] : 0;
                dist = d < dist ? d : dist;
                const int sz = cs[ch]->gmax[g] <= best[ch]   ? gsize
                               : cs[ch]->bmax[b] <= best[ch] ? VV_VC_BLOCK
                                                             : 0;
                size = sz < size ? sz : size;
            }
            if (dist) {
                k = vv_vproj_leap(r, p, bc, dist, k, dt);
                continue;
            }
            if (size) {
                k = vv_vproj_after_cube(r, p, k, dt, size);
                continue;
            }
        }
        const double klast = proj_block_last(r, p, k, kend, dt);
        /* each live channel that can change its maximum here marches the
         * subvolume as its one-channel projection does */
        int keep = 0;
        for (int i = 0; i < na; i++) {
            const int ch = act[i];
            if (!skipping ||
                ((!ts[ch]->pdist || ts[ch]->pdist[b] == 0) && cs[ch]->bmax[b] > best[ch]))
                project_block(cs[ch], r, k, klast, dt, 1.0f, vec[ch], &best[ch], &tbest[ch]);
            if (best[ch] < stop[ch])
                act[keep++] = ch;
        }
        na = keep;
        k = klast + 1;
    }
    for (int ch = 0; ch < n; ch++) {
        value[ch] = best[ch];
        depth[ch] = (float)tbest[ch];
    }
}
