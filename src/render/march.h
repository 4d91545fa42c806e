/*
 * The multi-volume march (internal, not part of the public API): several
 * composite and iso objects composited front to back along one world ray
 * on the shared samples t = k dt (docs/rendering.md, "Samples"). The ray
 * caster (trace_composite) and the ray tracer (march_volumes) share it;
 * what differs between them, the work at one object's sample (its
 * classification, shading, channel mixing), the isosurface hit and the
 * end of a sample, comes as callbacks. The march is always inlined and
 * each caller passes constant functions, so the compiler inlines those
 * too: the loop is the one each renderer had written out.
 */
#ifndef VV_RENDER_MARCH_H
#define VV_RENDER_MARCH_H

#include <math.h>

#include "render/project.h"
#include "render/ray.h"
#include "render/sample.h"

/* Up to this many objects along one ray. */
#define VV_MARCH_MAX 64

/* What an object's sample callback found at its sample. */
enum {
    VV_MARCH_EMPTY = 0,   /* its subvolume is hidden: te says where the ray leaves it */
    VV_MARCH_SAMPLED = 1, /* a sample taken (and composited, if it had opacity) */
    VV_MARCH_ISO = 2      /* an iso object's sample: val, for the march's crossing search */
};

/* A sample callback's answer beside its kind. */
typedef struct vv_march_sample {
    double te;          /* VV_MARCH_EMPTY: where the ray leaves the hidden subvolumes */
    float val;          /* VV_MARCH_ISO: the value at the sample */
    float iso;          /* VV_MARCH_ISO: the isovalue */
    const vv_vcache *c; /* VV_MARCH_ISO: the object's cache (crossing refinement) */
} vv_march_sample;

/* Object ai (of n) with its ray rays[ai]; per object and sample, in this
 * order: enter(ctx, ai, t) (may be NULL) before the ray's interval is
 * checked; where t lies in it, sample(ctx, ai, r, p, t, out) at index
 * point p; for an iso crossing at th, iso_hit(ctx, ai, r, th). After all
 * objects at a sample, end(ctx, t) (may be NULL); the march stops once *A
 * reaches et. Empty samples of every object leap to the nearest exit
 * (out->te) or interval start. */
typedef int (*vv_march_sample_fn)(void *ctx, int ai, const vv_vray *r, const float p[3], double t,
                                  vv_march_sample *out);
typedef void (*vv_march_iso_fn)(void *ctx, int ai, const vv_vray *r, double th);
typedef void (*vv_march_enter_fn)(void *ctx, int ai, double t);
typedef void (*vv_march_end_fn)(void *ctx, double t);

static inline __attribute__((always_inline)) void
vv_march(const vv_vray *rays, int n, double tmin, double tmax, double dt, float et, const float *A,
         void *ctx, vv_march_enter_fn enter, vv_march_sample_fn sample, vv_march_iso_fn iso_hit,
         vv_march_end_fn end) {
    /* iso bookkeeping: the previous sample per object (has_prev 2: restart
     * at the sample before the next visible one) */
    float prev_v[VV_MARCH_MAX];
    double prev_t[VV_MARCH_MAX];
    int has_prev[VV_MARCH_MAX];
    for (int i = 0; i < n; i++)
        has_prev[i] = 0;
    double k = vv_ceil_pos(tmin / dt);
    const double kend = vv_floor_pos(tmax / dt);
    while (k <= kend) {
        const double t = k * dt;
        double next_k = k + 1;
        double skip_to = INFINITY; /* the nearest leap over objects in empty subvolumes */
        int sampled = 0;
        for (int ai = 0; ai < n; ai++) {
            const vv_vray *r = &rays[ai];
            if (enter)
                enter(ctx, ai, t);
            if (t < r->t0 || t > r->t1) {
                if (t < r->t0 && r->t0 < skip_to)
                    skip_to = r->t0;
                has_prev[ai] = 0;
                continue;
            }
            float p[3];
            vv_vray_point(r, t, p);
            vv_march_sample s;
            const int kind = sample(ctx, ai, r, p, t, &s);
            if (kind == VV_MARCH_EMPTY) {
                if (s.te < skip_to)
                    skip_to = s.te;
                has_prev[ai] = 2; /* read by iso objects only */
                continue;
            }
            sampled = 1;
            if (kind != VV_MARCH_ISO)
                continue;
            const float val = s.val, iso = s.iso;
            double th = -1;
            if (has_prev[ai] == 2)
                vv_vray_iso_restart(s.c, r, k, dt, &prev_v[ai], &prev_t[ai], &has_prev[ai]);
            if (!has_prev[ai]) {
                if (val >= iso && t - r->t0 < dt)
                    th = t; /* entered already inside (cut face) */
            } else if ((prev_v[ai] < iso) != (val < iso)) {
                /* bisection between the previous sample and this one */
                th = vv_vray_iso_refine(s.c, r, prev_t[ai], prev_v[ai], t, iso);
            }
            prev_v[ai] = val;
            prev_t[ai] = t;
            has_prev[ai] = 1;
            if (th >= 0)
                iso_hit(ctx, ai, r, th);
        }
        if (end)
            end(ctx, t);
        if (*A >= et)
            break;
        if (!sampled && skip_to < INFINITY) {
            double ks = vv_ceil_pos(skip_to / dt);
            if (ks > next_k)
                next_k = ks;
        }
        k = next_k;
    }
}

#endif
