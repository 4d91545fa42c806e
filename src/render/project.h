/*
 * The projection stage of the volume renderers (internal, not part of the
 * public API): maximum and minimum intensity projection and the X-ray mean
 * along a ray (several channels' maxima in one pass; a region render's
 * X-ray sums), with the two-level min/max pyramid and the transfer
 * function's flat ends bounding the work, and the first crossing of an
 * isosurface along a ray, refined by bisection. The ray caster and the ray
 * tracer share them, so that their images agree bit for bit; the AVX2
 * march of MIP and MinIP is in kernels_avx2.c. docs/rendering.md ("Other
 * modes", "MIP and MinIP") describes the method.
 */
#ifndef VV_RENDER_PROJECT_H
#define VV_RENDER_PROJECT_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "render/ray.h"
#include "render/sample.h"
#include "render/tf_tables.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

/* The isosurface crossing between ray parameters ta (value va, on one side
 * of iso) and tb (on the other), by ten bisection steps. */
static inline double
vv_vray_iso_refine(const vv_vcache *c, const vv_vray *r, double ta, float va, double tb,
                   float iso) {
    for (int it = 0; it < 10; it++) {
        double tm = 0.5 * (ta + tb);
        float pm[3];
        vv_vray_point(r, tm, pm);
        float vm = vv_vcache_sample(c, pm);
        if ((va < iso) == (vm < iso)) {
            ta = tm;
            va = vm;
        } else {
            tb = tm;
        }
    }
    return 0.5 * (ta + tb);
}

/* An iso crossing search meets visible sample k after skipping hidden ones
 * (the multi-object marches of the ray caster and the ray tracer: *has ==
 * 2), or starts a region's samples at k (vv_vray_iso_first): it restarts
 * at sample k - 1, *pt its parameter, *pv its value, as a march of every
 * sample has it. */
static inline void
vv_vray_iso_restart(const vv_vcache *c, const vv_vray *r, double k, double dt, float *pv,
                    double *pt, int *has) {
    float p[3];
    *pt = (k - 1) * dt;
    vv_vray_point(r, *pt, p);
    *pv = vv_vcache_sample(c, p);
    *has = 1;
}

/* Maximum (VV_MODE_MIP) or minimum (VV_MODE_MINIP) intensity projection or
 * mean (VV_MODE_XRAY) of the samples t = k dt of the clipped ray r, one
 * sample in the middle when it is shorter than a step; *depth: the
 * parameter of the extreme (xray: the entry). With @p skipping, groups of
 * subvolumes, then subvolumes, that cannot beat the current extreme are
 * skipped whole (same result).
 *
 * @p lo and @p hi (stored units; -INFINITY and INFINITY for none) say what
 * the caller's classification cannot tell apart: every value <= lo maps to
 * the same colour, and every value >= hi. MIP then starts its maximum at lo
 * (a ray whose maximum is at most lo returns lo and depth t0) and stops once
 * it reaches hi; MinIP starts at hi and stops at lo. The value returned
 * always classifies exactly as the true extreme does; only the depth may
 * name an earlier sample of the same colour. */
void vv_vray_project(const vv_vcache *c, const vv_vray *r, vv_render_mode mode, double dt,
                     int skipping, float lo, float hi, float *value, float *depth);
/* The X-ray sum of ray r: the values of its samples t = k dt added in
 * order (eight at a time with @p avx2 and 16-bit values: the same values
 * and order) into *sum, their number returned, *depth its entry; a ray
 * shorter than a step has one sample, in the middle (its depth).
 * vv_vray_project's X-ray mean is *sum / n; region renders (VV_REGION_SUM)
 * add up the sums of their rays' pieces. Thread-safe. */
long vv_vray_xray_sum(const vv_vcache *c, const vv_vray *r, double dt, int avx2, double *sum,
                      float *depth);
/* The table that classifies the means of a region render's X-ray sums
 * (vv_region_image.classify): a copy of the object's transfer-function
 * table, its entries {alpha, r alpha, g alpha, b alpha}. */
typedef struct vv_xray_table {
    float lut_lo, lut_scale; /* value -> entry */
    float lut[4 * VV_VC_LUT];
} vv_xray_table;

/* vv_region_image.classify over a vv_xray_table (@p ctx): the entry of
 * value @p v (clamped to the table) into @p e. (The ray caster's
 * attenuated-MIP regions use it too, its lut_lo moved to real units.) */
void vv_xray_table_classify(const void *ctx, float v, float e[4]);

/* A ray caster's frame (raycast's, gpu's render_frame): @p w through
 * @p view into @p out, only the samples of @p region when not NULL (then
 * with its keys in @p key, vv_region_image.key). */
typedef vv_status (*vv_region_frame_fn)(void *state, const vv_world *w, const vv_view *view,
                                        const vv_render_options *opt,
                                        const vv_render_region *region, vv_image *out, float *key);

/* The region contract (vv_renderer_ops.render_region) of a ray caster
 * that draws a region as a frame: @p frame of @p state draws the World
 * seen with the region's object alone, its volume the region's voxels
 * (vv_render_region_world: they carry the whole volume's geometry and
 * range, so rays stay in the whole volume's index box and only the
 * region's samples are taken); in xray mode (VV_REGION_SUM) the summed
 * means, and in attenuated-mip mode (VV_REGION_ATTENUATED_MAX) the
 * attenuated maxima, are classified by @p xray (the state's table, which
 * the frame fills). Errors: those of vv_render_region_world and @p frame. */
vv_status vv_region_render_by_frame(vv_region_frame_fn frame, void *state,
                                    const vv_xray_table *xray, const vv_world *w,
                                    const vv_view *view, const vv_render_region *region,
                                    const vv_render_options *opt, vv_region_image *out);

/* A region render's X-ray pixel (VV_REGION_SUM, include/volvis/sys/renderer.h)
 * along primary ray @p wr (world space) through the volume of cache @p c
 * (@p w2i, @p dims and cut planes as vv_vray_setup takes them; @p inv_form as
 * vv_vray_clip_region): the sum of the region's sample values at t = k dt,
 * split into *key (the sum rounded to float) and px[0] (the rest), their
 * count in px[1], px[2] = px[3] = 0, and *depth the whole ray's depth -- its
 * entry, or on a ray too short for a sample its one middle sample, and
 * +inf when the region is not where the ray enters. Nothing taken: px 0,
 * *key NAN, *depth +inf. Returns the samples taken. The ray caster's and the
 * ray tracer's region renders in xray mode share it, so their sums are the
 * same bit for bit. Thread-safe. */
long vv_vray_xray_region_pixel(const vv_vcache *c, const double w2i[3][4], const int dims[3],
                               const vv_plane *planes, int n_planes, const vv_render_region *rg,
                               double dt, int inv_form, const vv_ray *wr, int avx2, float px[4],
                               float *depth, float *key);
/* vv_vray_project with the bounds of tables @p t (plo, phi) and, with
 * @p skipping, their distances pdist to leap through subvolumes that hold
 * nothing beyond the starting bound. With @p avx2 (vv_vc_have_avx2) and
 * 16-bit values, MIP and MinIP march in chunks of samples, testing their
 * subvolumes and interpolating them eight at a time with the scalar
 * path's arithmetic: the same value, except that a ray reaching @p hi
 * (MinIP: @p lo) may stop a few samples later, at a value that classifies
 * the same, and its depth may differ; X-ray adds the same values in the
 * same order (the same result). */
void vv_vray_project_tables(const vv_vcache *c, const vv_vtables *t, const vv_vray *r,
                            vv_render_mode mode, double dt, int skipping, int avx2, float *value,
                            float *depth);
/* The maximum intensity projections of @p n channels (1..VV_MAX_CHANNELS;
 * one, or a ray shorter than a step: vv_vray_project_tables per channel)
 * on one ray, in one pass: cs[ch], ts[ch] each channel's cache and MIP
 * tables (every channel has the same grid), value[ch] and depth[ch] what
 * vv_vray_project_tables gives channel ch alone (a channel that reaches
 * its table's flat top stops at the end of a subvolume here, at the end of
 * a run of eight samples there: the same colour, the depth of a sample of
 * it that may differ), marching one subvolume at a time with the same
 * arithmetic. With @p skipping the rays leap over the cubes of
 * subvolumes where no channel still short of its upper bound holds
 * anything beyond its starting bound, skip groups and subvolumes where none
 * can beat its maximum, and inside a subvolume only the channels that can
 * are sampled: the traversal is shared, the sampling is per channel. */
void vv_vray_project_channels(const vv_vcache *const *cs, const vv_vtables *const *ts, int n,
                              const vv_vray *r, double dt, int skipping, int avx2, float *value,
                              float *depth);

/* What napari's attenuated maximum intensity projection
 * (VV_MODE_ATTENUATED_MIP) takes from the object: the transfer function's
 * contrast limits [lo, lo + 1 / inv_range] in stored units (real value -
 * qoff), the cache's offset qoff, its largest stored value vmax, and
 * k = attenuation / relative step (the step in units of the smallest voxel
 * spacing). */
typedef struct vv_vatten {
    float lo, inv_range, qoff, vmax;
    double k;
} vv_vatten;

/* The vv_vatten of volume object @p obj in attenuated-mip mode, drawn from
 * cache @p c (its volume's, or a region's voxels) at the frame's sample
 * step @p dt (world units, as the frame holds it): the contrast limits
 * (the span of the transfer function's opacity points, a contrast ramp's
 * or napari's limits, else the volume's range; [lo, lo + 1] when that
 * spans nothing), c's offset and largest stored value (its groups' max),
 * and k = attenuation / relative step, the relative step being dt in units
 * of obj's smallest voxel spacing times its step. The ray caster and the
 * gpu renderer share it, so their images agree. Errors: VV_ERR_INVALID
 * (an attenuation below 0 or not finite). Thread-safe; reads @p c only. */
vv_status vv_vatten_prepare(vv_vatten *a, const vv_object *obj, const vv_vcache *c, float dt);

/* The attenuated maximum intensity projection of ray r (napari's, VisPy's
 * volume shader): over the samples t = j dt in order (one in the middle of
 * a ray shorter than a step), S accumulates each sample's normalised value
 * clamp((v - lo) * inv_range, 0, 1); the sample's real value v + qoff is
 * scaled by exp(-k (S - 1)), S including the sample itself, and the largest
 * scaled value (back in stored units) is *value, the parameter of its first
 * sample *depth. With k == 0 every scale is exactly 1 and the result is the
 * plain maximum. The sum needs every sample up to the last that can win:
 * the scale only shrinks along the ray, so once vmax at the current scale
 * (real vmax + qoff >= 0) cannot beat the maximum the march stops (the same
 * result). Thread-safe. */
void vv_vray_attenuated_mip(const vv_vcache *c, const vv_vray *r, double dt, const vv_vatten *a,
                            float *value, float *depth);

/* A region render's attenuated-MIP pixel (VV_REGION_ATTENUATED_MAX,
 * include/volvis/sys/renderer.h) along primary ray @p wr (world space)
 * through the volume of cache @p c (@p w2i, @p dims, cut planes and
 * @p inv_form as vv_vray_xray_region_pixel takes them): over the region's
 * samples t = k dt in order (the ray's one middle sample when it is shorter
 * than a step and the region owns it), E accumulates each sample's
 * exponent a->k w n (n its value normalised as vv_vray_attenuated_mip
 * normalises it, w the region's step_scale, 1 when 0), starting at 0; the
 * sample's real value v + qoff is scaled by exp(a->k - E'), E' the E of
 * the samples before it plus a->k n (the sample counted once, as a step of
 * the finest level: it stands at the start of its run of w of them, whose
 * first has the largest scale; with w = 1, E' is napari's E including the
 * sample), and the largest scaled value (real units) is *key, the
 * parameter of its first sample *depth, the total E in px[0] (px[1] =
 * px[2] = px[3] = 0).
 * Every sample is taken (the regions behind need the whole E). Nothing
 * taken: px 0, *key NAN, *depth +inf. Returns the samples taken.
 * Thread-safe. */
long vv_vray_attenuated_region_pixel(const vv_vcache *c, const double w2i[3][4], const int dims[3],
                                     const vv_plane *planes, int n_planes,
                                     const vv_render_region *rg, double dt, int inv_form,
                                     const vv_ray *wr, const vv_vatten *a, float px[4],
                                     float *depth, float *key);

/* The first crossing of @p iso along ray r (step dt) through the runs of
 * visible subvolumes (@p bdist of tables made for iso mode: a subvolume is
 * hidden when its values all lie below iso): the sample values in
 * order (eight at a time with @p avx2 and 16-bit values: the same values),
 * a crossing between two consecutive ones refined by vv_vray_iso_refine;
 * after a stretch of hidden subvolumes the search restarts at the sample
 * before the run (so the crossing is the same with skipping on or off, and
 * in a region's voxels), and the ray's first sample counts as a hit
 * when it is already at or above iso (a cut face). With @p cont (a region
 * render whose first sample is not the whole ray's: vv_vray_clip_region
 * said so) the search starts from the sample before the region's first,
 * read from its ghost voxels, so that the crossing between them is found
 * here (VV_REGION_NEAREST); when that sample is already at or above iso
 * the whole ray crossed before it, and it is returned as a hit (the
 * region in front holds a crossing at most as deep, which the combine
 * keeps; a neighbour of another level may not, and this hit then closes
 * the crack). Returns the crossing's ray parameter, or -1 for none.
 * Shared by the ray caster and the ray tracer, so that their isosurfaces
 * agree bit for bit. Thread-safe. */
double vv_vray_iso_first(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt,
                         float iso, int avx2, int cont);

/* ---------------------------------------------------------------------- */
/* The projection march's traversal, shared by project.c and its AVX2 path
 * (vv_vproj_from_avx2, kernels_avx2.c) */

/* The subvolume of index point p: its grid coordinates in bc (clamped)
 * and its index. */
static inline size_t
vv_vproj_block(const vv_vcache *c, const float p[3], int bc[3]) {
    for (int a = 0; a < 3; a++) {
        bc[a] = (int)((p[a] > 0 ? p[a] : 0) * (1.0f / VV_VC_BLOCK));
        const int bn = a == 0 ? c->bx : a == 1 ? c->by : c->bz;
        bc[a] = bc[a] >= bn ? bn - 1 : bc[a];
    }
    return ((size_t)bc[2] * (size_t)c->by + (size_t)bc[1]) * (size_t)c->bx + (size_t)bc[0];
}

/* The group of subvolumes of index point p (clamped). */
static inline size_t
vv_vproj_group(const vv_vcache *c, const float p[3]) {
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    int gi = (int)((p[0] > 0 ? p[0] : 0) * (1.0f / gsize));
    int gj = (int)((p[1] > 0 ? p[1] : 0) * (1.0f / gsize));
    int gk = (int)((p[2] > 0 ? p[2] : 0) * (1.0f / gsize));
    gi = gi >= c->gx ? c->gx - 1 : gi;
    gj = gj >= c->gy ? c->gy - 1 : gj;
    gk = gk >= c->gz ? c->gz - 1 : gk;
    return ((size_t)gk * (size_t)c->gy + (size_t)gj) * (size_t)c->gx + (size_t)gi;
}

/* The sample after leaving the cube of 2 dist - 1 subvolumes around
 * subvolume bc (p, sample k, in it). */
static inline double
vv_vproj_leap(const vv_vray *r, const float p[3], const int bc[3], int dist, double k, double dt) {
    float te = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        const float bound = r->d[a] > 0 ? (float)(bc[a] + dist) * VV_VC_BLOCK
                                        : (float)(bc[a] - dist + 1) * VV_VC_BLOCK;
        const float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    const double ks = vv_ceil_pos((k * dt + te) / dt);
    return ks > k + 1 ? ks : k + 1;
}

/* The sample after the cube of @p size index units around p (sample k). */
static inline double
vv_vproj_after_cube(const vv_vray *r, const float p[3], double k, double dt, int size) {
    const double ks = vv_ceil_pos(vv_vray_cube_exit(r, p, k * dt, size) / dt);
    return ks > k + 1 ? ks : k + 1;
}

#endif
