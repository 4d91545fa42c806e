/*
 * The ray stage of the volume renderers (internal, not part of the public
 * API): a world ray mapped into a volume's index space, clipped to its grid
 * box (the slab test, core/geom.h) and cut planes, or cut to the samples a
 * region owns; its samples at t = k dt, one grid shared by all objects; and
 * the march over them with empty-space leaping: runs of samples in visible
 * subvolumes, leaps over cubes of hidden ones by their chessboard distance
 * (the PARC subvolumes of the VolVis paper's Navigator, section 4).
 * docs/rendering.md ("Rays", "Samples", "Empty-space skipping", "Runs by
 * sample") describes the method. The functions only read and may run on
 * many threads.
 */
#ifndef VV_RENDER_RAY_H
#define VV_RENDER_RAY_H

#include <math.h>
#include <stdint.h>

#include "render/sample.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

/* Step in world units of an object: step * smallest voxel spacing in world. */
double vv_vobject_step(const vv_object *obj);

/* A world ray (unit direction, parameter t in world units) mapped into a
 * volume's index space and clipped to its grid box [0, dims - 1] and cut
 * planes. */
typedef struct vv_vray {
    float o[3], d[3]; /* index point at t = tb, index direction per world unit */
    float inv[3];     /* 1/d, or 0 where d == 0 (axis never crossed) */
    double t0, t1;    /* clipped interval, world units */
    double tb;        /* o is the index point at t = tb (keeps float offsets small) */
    /* subtracted from every point after it is computed (0 after
     * vv_vray_setup): a brick of a larger volume (src/parallel) sets up the
     * ray in the whole volume's index space, so its samples are those of
     * the whole volume bit for bit, and reads them from a cache that starts
     * at voxel off (the subtraction of an integer below the point is exact,
     * and the brick's own subvolume grids are consistent in its frame) */
    float off[3];
} vv_vray;

/* Clips @p wr, within [tmin, tmax], to the grid box of @p dims (index
 * space through @p w2i, world to index) and the planes; returns 0 when
 * nothing is left. */
int vv_vray_setup(const double w2i[3][4], const int dims[3], const vv_plane *planes, int n_planes,
                  const vv_ray *wr, double tmin, double tmax, vv_vray *r);

/* Region renders (include/volvis/sys/renderer.h): cuts @p r, set up in the
 * whole volume's index space, to the samples t = k dt that region @p rg
 * owns (lo <= p < hi per axis; along a ray each coordinate is monotonic in
 * k, so they are found by bisection), and points it at the region's voxels
 * (r->off = rg->offset). @p inv_form says how the kernel finds its first
 * and last samples: ceil(t0 * (1 / dt)) (1) or ceil(t0 / dt) (0), so that
 * the whole ray's samples are counted as the whole render counts them. A
 * ray shorter than a step keeps its one middle sample when the region owns
 * it. The cut ends lie half a step beyond the first and last owned
 * samples, so any kernel rounding finds them again. *cont (may be NULL):
 * 1 when the region's first sample is not the whole ray's (an iso search
 * then starts at the one before it: vv_vray_iso_first). Returns 0 when the
 * region owns no sample of the ray. */
int vv_vray_clip_region(vv_vray *r, const vv_render_region *rg, double dt, int inv_form, int *cont);

static inline void
vv_vray_point(const vv_vray *r, double t, float p[3]) {
    float tf = (float)(t - r->tb);
    p[0] = (r->o[0] + tf * r->d[0]) - r->off[0];
    p[1] = (r->o[1] + tf * r->d[1]) - r->off[1];
    p[2] = (r->o[2] + tf * r->d[2]) - r->off[2];
}

/* ceil and floor of a non-negative double without libm: the x86-64
 * baseline (SSE2) has no rounding instruction, and these sit on the
 * traversal's hot path. Parameters are sample indices, well inside int64. */
static inline double
vv_ceil_pos(double x) {
    double i = (double)(int64_t)x;
    return i < x ? i + 1 : i;
}

static inline double
vv_floor_pos(double x) {
    return (double)(int64_t)x;
}

/* World parameter at which the ray leaves the cube of side @p size cells
 * (aligned to multiples of size) containing p. */
static inline double
vv_vray_cube_exit(const vv_vray *r, const float p[3], double t, int size) {
    float te = INFINITY;
    const float inv_size = 1.0f / (float)size;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        float b = (float)(int)(p[a] * inv_size); /* floor: p >= 0 up to rounding */
        b = b < 0 ? 0 : b;
        float bound = (r->d[a] > 0 ? b + 1 : b) * (float)size;
        float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    return t + te;
}

/* The ray parameter from point p in subvolume bc to where r leaves the
 * cube of 2 dist - 1 subvolumes around bc. */
static inline float
vv_vray_cube_span(const vv_vray *r, const float p[3], const unsigned bc[3], int dist) {
    float te = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        float bound = r->d[a] > 0 ? (float)((int)bc[a] + dist) * VV_VC_BLOCK
                                  : (float)((int)bc[a] - dist + 1) * VV_VC_BLOCK;
        float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    return te;
}

/* The sample index after leaving the empty cube of 2 dist - 1 subvolumes
 * around subvolume bc (p, at ray parameter t, in it; k its sample index). */
static inline double
vv_vray_leap(const vv_vray *r, const float p[3], double t, const unsigned bc[3], int dist,
             double inv_dt, double k) {
    const float te = vv_vray_cube_span(r, p, bc, dist);
    double ks = vv_ceil_pos((t + te) * inv_dt);
    return ks > k + 1 ? ks : k + 1;
}

/* At sample *k of ray r: its point p and subvolume; when the subvolume's
 * chessboard distance (bdist) is at least @p min_dist, *k moves past the
 * empty cube around it (vv_vray_leap) and 1 is returned, else 0 (p, t
 * and bc then describe sample *k). */
static inline int
vv_vray_leap_from(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt,
                  int min_dist, double *k, float p[3], double *t, unsigned bc[3]) {
    *t = *k * dt;
    vv_vray_point(r, *t, p);
    const size_t b =
        vv_vblock_of(c, p, (unsigned)c->bx - 1, (unsigned)c->by - 1, (unsigned)c->bz - 1, bc);
    const int dist = bdist[b];
    if (dist < min_dist)
        return 0;
    *k = vv_vray_leap(r, p, *t, bc, dist, 1.0 / dt, *k);
    return 1;
}

/* The next run of samples of ray r in visible subvolumes (bdist 0: vv_vtables.bdist) from
 * sample *k on, up to kend: *k and *klast get its first and last sample;
 * returns 0 when none is left. Empty cubes of subvolumes are leapt over;
 * the visible subvolumes that follow the first join, whole, while their
 * samples fit a chunk (VV_VC_CHUNK): the same samples in the same order as
 * one subvolume at a time (which subvolumes are visible does not depend on
 * what was composited), in fuller vectors. Without skipping every
 * subvolume is marked visible and at distance 0, so both cases run this
 * same code and produce the same samples. */
static inline int
vv_vray_visible_run(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt,
                    double kend, double *kp, double *klastp) {
    const double inv_dt = 1.0 / dt;
    const unsigned bxm = (unsigned)c->bx - 1, bym = (unsigned)c->by - 1, bzm = (unsigned)c->bz - 1;
    double k = *kp;
    while (k <= kend) {
        float p[3];
        double t;
        unsigned bc[3];
        if (vv_vray_leap_from(c, bdist, r, dt, 1, &k, p, &t, bc))
            continue;
        double te = vv_vray_cube_exit(r, p, t, VV_VC_BLOCK);
        /* march to the last sample inside this subvolume */
        double klast = vv_floor_pos(te * inv_dt);
        klast = klast < kend ? klast : kend;
        klast = klast < k ? k : klast;
        while (klast < kend && klast - k + 1 < VV_VC_CHUNK) {
            const double kn = klast + 1, tn = kn * dt;
            float pn[3];
            vv_vray_point(r, tn, pn);
            unsigned bcn[3];
            if (bdist[vv_vblock_of(c, pn, bxm, bym, bzm, bcn)])
                break;
            double kl = vv_floor_pos(vv_vray_cube_exit(r, pn, tn, VV_VC_BLOCK) * inv_dt);
            kl = kl < kend ? kl : kend;
            kl = kl < kn ? kn : kl;
            if (kl - k + 1 > VV_VC_CHUNK)
                break;
            klast = kl;
        }
        *kp = k;
        *klastp = klast;
        return 1;
    }
    *kp = k;
    return 0;
}

#if VV_VC_HAVE_AVX2
/* vv_vray_visible_run with AVX2: from a sample in a visible subvolume
 * whose distance to the nearest hidden one (vdist, vv_vtables) is d >= 2,
 * the run takes every sample up to where the ray leaves the all-visible
 * cube of 2 d - 1 subvolumes around it, and goes on so from the next; from
 * one with vdist 1 it goes on while the subvolume of each sample (found
 * eight lanes at a time by gathers, from the point its interpolation uses)
 * is visible; in a hidden subvolume at chessboard distance 1 the next
 * VV_VC_CHUNK samples are scanned so for the first visible one instead of
 * leaping (distance 2 and more: vv_vray_leap). A run holds at most
 * VV_VC_CHUNK samples. The samples it leaves out lie in hidden subvolumes,
 * their cells' values in those subvolumes' ranges, so they are
 * transparent (and a sample of a hidden subvolume that a cube's rounded
 * exit takes in is transparent too): a kernel that composites the runs
 * gives the image of vv_vray_visible_run (and of no skipping) bit for bit,
 * with one traversal step a run instead of one a subvolume. @p bdist must
 * be a vv_vtables' (vdist follows it). */
int vv_vray_visible_run_avx2(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt,
                             double kend, double *kp, double *klastp);
#endif

/* vv_vray_visible_run, or with @p avx2 (vv_vc_have_avx2) its vector form:
 * the same image from a kernel that composites the runs. */
static inline int
vv_vray_visible_run_simd(int avx2, const vv_vcache *c, const uint8_t *bdist, const vv_vray *r,
                         double dt, double kend, double *kp, double *klastp) {
#if VV_VC_HAVE_AVX2
    if (avx2)
        return vv_vray_visible_run_avx2(c, bdist, r, dt, kend, kp, klastp);
#else
    (void)avx2;
#endif
    return vv_vray_visible_run(c, bdist, r, dt, kend, kp, klastp);
}

#endif
