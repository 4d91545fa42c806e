/*
 * The ray stage: a volume object's step, a world ray set up in a volume's
 * index space and clipped to its grid box and cut planes, and cut to the
 * samples a region owns (ray.h describes them).
 */
#include "render/ray.h"

#include <math.h>

#include "core/geom.h"

double
vv_vobject_step(const vv_object *obj) {
    vv_mat4 m = vv_object_index_to_world(obj);
    double best = INFINITY;
    for (int cc = 0; cc < 3; cc++) {
        double l =
            sqrt(m.m[0][cc] * m.m[0][cc] + m.m[1][cc] * m.m[1][cc] + m.m[2][cc] * m.m[2][cc]);
        if (l > 0 && l < best)
            best = l;
    }
    return obj->step * best;
}

int
vv_vray_setup(const double w2i[3][4], const int dims[3], const vv_plane *planes, int n_planes,
              const vv_ray *wr, double tmin, double tmax, vv_vray *r) {
    double o[3], d[3];
    for (int a = 0; a < 3; a++) {
        o[a] = w2i[a][0] * wr->origin.x + w2i[a][1] * wr->origin.y + w2i[a][2] * wr->origin.z +
               w2i[a][3];
        d[a] = w2i[a][0] * wr->dir.x + w2i[a][1] * wr->dir.y + w2i[a][2] * wr->dir.z;
    }
    double t0 = tmin, t1 = tmax;
    const double lo[3] = {0, 0, 0}, hi[3] = {dims[0] - 1, dims[1] - 1, dims[2] - 1};
    if (!vv_slab(lo, hi, o, d, &t0, &t1))
        return 0;
    for (int p = 0; p < n_planes; p++)
        if (!vv_plane_clip_ray(planes[p], *wr, &t0, &t1))
            return 0;
    if (!(t0 <= t1))
        return 0;
    r->tb = t0;
    for (int a = 0; a < 3; a++) {
        r->o[a] = (float)(o[a] + t0 * d[a]);
        r->d[a] = (float)d[a];
        r->inv[a] = fabs(d[a]) < 1e-30 ? 0.0f : (float)(1.0 / d[a]);
        r->off[a] = 0;
    }
    r->t0 = t0;
    r->t1 = t1;
    return 1;
}

/* Whether sample k of r (the point vv_vray_point computes, before the
 * region offset) lies in the region's box on axis a, on its low (side 0:
 * p >= lo) or high (side 1: p < hi) side. */
static inline int
region_side(const vv_vray *r, const vv_render_region *b, double dt, int a, int side, int64_t k) {
    const float tf = (float)((double)k * dt - r->tb);
    const float p = r->o[a] + tf * r->d[a];
    return side ? p < b->hi[a] : p >= b->lo[a];
}

/* The samples kg0 .. kg1 that are the region's: on each axis and side they
 * are a prefix or a suffix, found by bisection. Returns 0 when none. */
static int
region_range(const vv_vray *r, const vv_render_region *b, double dt, int64_t kg0, int64_t kg1,
             int64_t *ka, int64_t *kb) {
    int64_t lo = kg0, hi = kg1;
    for (int a = 0; a < 3; a++)
        for (int side = 0; side < 2; side++) {
            if ((side == 0 && b->lo[a] == -INFINITY) || (side == 1 && b->hi[a] == INFINITY))
                continue;
            const int t_first = region_side(r, b, dt, a, side, kg0);
            const int t_last = region_side(r, b, dt, a, side, kg1);
            if (!t_first && !t_last)
                return 0;
            if (t_first && t_last)
                continue;
            int64_t x = kg0, y = kg1; /* test(x) == t_first, test(y) == t_last */
            while (y - x > 1) {
                const int64_t m = x + (y - x) / 2;
                if (region_side(r, b, dt, a, side, m) == t_first)
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

int
vv_vray_clip_region(vv_vray *r, const vv_render_region *b, double dt, int inv_form, int *cont) {
    const int64_t kg0 =
        (int64_t)(inv_form ? vv_ceil_pos(r->t0 * (1.0 / dt)) : vv_ceil_pos(r->t0 / dt));
    const int64_t kg1 =
        (int64_t)(inv_form ? vv_floor_pos(r->t1 * (1.0 / dt)) : vv_floor_pos(r->t1 / dt));
    for (int a = 0; a < 3; a++)
        r->off[a] = (float)b->offset[a];
    if (cont)
        *cont = 0;
    if (kg0 > kg1) {
        /* shorter than a step: a projection takes one sample in the middle,
         * which belongs to the region that holds it */
        const double tm = 0.5 * (r->t0 + r->t1);
        const float tf = (float)(tm - r->tb);
        for (int a = 0; a < 3; a++) {
            const float p = r->o[a] + tf * r->d[a];
            if (!(p >= b->lo[a] && p < b->hi[a]))
                return 0;
        }
        return 1;
    }
    int64_t ka, kb;
    if (!region_range(r, b, dt, kg0, kg1, &ka, &kb))
        return 0;
    if (cont)
        *cont = ka > kg0;
    const double t0 = ((double)ka - 0.5) * dt, t1 = ((double)kb + 0.5) * dt;
    r->t0 = t0 > r->t0 ? t0 : r->t0;
    r->t1 = t1 < r->t1 ? t1 : r->t1;
    return 1;
}
