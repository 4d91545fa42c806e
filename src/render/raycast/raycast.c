/*
 * Direct volume ray casting (Levoy, "Display of Surfaces from Volume Data",
 * IEEE CG&A 1988; the VolVis paper, section 5 "Rendering", volume ray
 * casting), with empty-space skipping over a grid of subvolumes holding
 * min/max values (the PARC idea of the VolVis paper's Navigator, section 4).
 *
 * Per volume, a cache holds the voxels as 16-bit offsets (integer data) or
 * float, the unit gradient direction of every voxel in a 16-bit octahedral
 * code in a separate array (central differences, computed once), and the min/max
 * of every 4^3-cell subvolume. Per object, a transfer-function lookup table
 * (opacity corrected for the step) marks which subvolumes are visible, and
 * each subvolume gets its chessboard distance to the nearest visible one;
 * rays leap over empty cubes of subvolumes. These tables are kept between
 * frames while nothing they depend on changes. The caches, tables, trilinear
 * sampling and ray clipping are shared with the raytrace renderer
 * (src/render/sample.h, ray.h, classify.h, shade.h, project.h).
 *
 * Rays are traced in each object's index space: the world ray (unit
 * direction, parameter t in world units) is mapped by the object's
 * world-to-index matrix, so anisotropic spacing, direction matrices and
 * object transforms all come for free, and samples sit at t = k * dt on a
 * grid shared by all objects, which keeps images deterministic and
 * independent of tiling and thread count. The single-volume composite
 * kernel classifies a subvolume's samples first (SSE2, or AVX2 where the
 * processor has it) and then shades and composites the visible ones.
 * At quality 0 and 1, and at quality 2 in frames of composite, MIP and MinIP objects,
 * pixels come from adaptive image-space refinement (Levoy 1990;
 * vv_frame_refine_tile). docs/rendering.md describes the
 * method and its measurements.
 *
 * This file is one method's kernel, the direct volume ray caster, and is
 * kept whole on purpose although it is over the 1,200 lines of issue 62's
 * rule: its set-up, march and compositing are one loop best read together. */
#include <math.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/classify.h"
#include "render/frame.h"
#include "render/kernels_avx2.h"
#include "render/march.h"
#include "render/project.h"
#include "render/ray.h"
#include "render/registry.h"
#include "render/sample.h"
#include "render/shade.h"
#include "render/shade_table.h"
#include "render/tf_tables.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

#define RC_MAX_OBJ 64 /* objects handled in one render (<= VV_VC_MAX) */

typedef struct rc_state {
    vv_vcache_set vc;                /* per-volume caches (src/render/sample.h); its
                                        gradient_budget: option gradient_budget_mb */
    double early_termination;        /* accumulated opacity that ends a ray (option) */
    int skipping;                    /* option empty_space_skipping (for tests) */
    int simd;                        /* use AVX2 when the processor has it (option simd) */
    vv_frame_refine_settings refine; /* adaptive refinement (options refinement...) */
    int preint;                      /* pre-integrated classification (option preintegration) */
    int shading_table;               /* option shading: 0 phong, 1 table */
    vv_vshade_table stab;            /* the last frame's shading table (shading=table) */
    /* the X-ray table of the last region render in xray mode, which
     * classifies the summed regions' means (vv_region_image.classify), or
     * in attenuated-mip mode their attenuated maxima */
    vv_xray_table xray;
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
    vv_vatten att;  /* attenuated MIP: contrast limits, attenuation per relative step */
    vv_vshading sh; /* shading constants */
    int shading;
    const vv_vshade_table *stab; /* shading=table: shaded by this table (else NULL: Phong) */
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    vv_vextra x;  /* 2-D transfer function and solid texture */
    int extras;   /* x has something: the general kernel handles the object */
    int textured; /* iso mode: an image texture modulates the base colour */
    /* region renders: the region, the step and whether the kernel finds its
     * first sample as ceil(t0 * (1 / dt)) (trace_composite_one) or
     * ceil(t0 / dt) (vv_vray_clip_region) */
    const vv_render_region *region;
    double dt;
    int inv_form;
    /* a multi-channel object (vv_object.channels): its visible channels,
     * each prepared as an object of its own (ray set-up, cache, tables);
     * this slot's own fields set up the rays (every channel shares them) */
    int nch;
    struct rc_obj *ch;
    vv_channel_blend blend;
    int ch_extras; /* some channel has extras (a label channel's colours) */
} rc_obj;

typedef struct rc_frame {
    rc_state *st;
    vv_render_stats *stats; /* the caller's counts (vv_render_options.stats), or NULL */
    rc_obj *objs;
    int n_obj;
    int n_comp; /* composite/iso objects first in objs[], then projections */
    const vv_view *view;
    float dt;
    float ambient[3];
    float bg[3];
    vv_vlight lights[VV_MAX_LIGHTS];
    int n_lights;
    float et; /* early termination */
    /* a region render's opacity in front (vv_render_region.front): one
     * object in composite mode alone, else NULL */
    const vv_image *front;
    int point_lights;   /* any point light (needs the world position of samples) */
    int avx2;           /* the processor has AVX2 and FMA (vv_vray_classify) */
    vv_camera_rays cam; /* primary rays */
    vv_image *out;      /* the image being written */
    float *key;         /* region renders of projections: the key per pixel, else NULL */
    int refine;         /* adaptive image-space refinement (render_tile_refined) */
    float tolerance;    /* its tolerance, in colour and opacity */
    int preint;         /* pre-integrated classification (trace_composite_preint) */
    int xsum;           /* a region render in xray mode: sums and counts (VV_REGION_SUM) */
    int asum;           /* a region render in attenuated-mip mode: maxima and exponents
                           (VV_REGION_ATTENUATED_MAX) */
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

/* The ray clipped to the object in its index space; in a region render,
 * set up in the whole volume's index space and cut to the region's samples
 * (*cont: vv_vray_clip_region's, 0 outside region renders). */
static inline int
ray_setup_cont(const rc_obj *ob, const vv_ray *wr, vv_vray *r, int *cont) {
    *cont = 0;
    if (!vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, wr, 0, INFINITY, r))
        return 0;
    return !ob->region || vv_vray_clip_region(r, ob->region, ob->dt, ob->inv_form, cont);
}

/* ray_setup_cont without *cont (vv_vray_clip_region's). */
static inline int
ray_setup(const rc_obj *ob, const vv_ray *wr, vv_vray *r) {
    int cont;
    return ray_setup_cont(ob, wr, r, &cont);
}

static inline float
lut_index_f(const rc_obj *o, float v) {
    float x = (v - o->lut_lo) * o->lut_scale;
    return x > 0 ? (x < VV_VC_LUT - 1 ? x : VV_VC_LUT - 1) : 0; /* NaN: 0 (vv_vtables_index) */
}

/* ---------------------------------------------------------------------- */
/* Ray kernels                                                              */

typedef struct rc_result {
    float rgb[3];
    float a;
    float depth;
    uint32_t samples, shaded; /* work counted (vv_render_stats) */
} rc_result;

/* A composite kernel's result: colour C, opacity A (at most 1), depth. */
static inline void
result_set(rc_result *res, const float C[3], float A, float depth) {
    res->rgb[0] = C[0];
    res->rgb[1] = C[1];
    res->rgb[2] = C[2];
    res->a = A > 1 ? 1 : A;
    res->depth = depth;
}

/* The colour a sample (or a pre-integrated segment) adds, before
 * attenuation: its colour times opacity @p col, opacity @p alpha, shaded
 * with gradient g at ray parameter t (the world point there is read for
 * point lights); an unshaded object's is col itself. */
static inline void
sample_colour(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, const float v[3], double t,
              const float g[3], const float col[3], float alpha, float out[3]) {
    if (!ob->shading) {
        memcpy(out, col, 3 * sizeof(float));
        return;
    }
    float pw[3] = {0, 0, 0};
    if (fr->point_lights)
        vv_ray_world_point(wr, t, pw);
    shade(fr, ob, g, pw, v, col, alpha, out);
}

/* Front-to-back "over": colour @p out (already times its opacity) and
 * opacity @p alpha under the accumulated C, A. */
static inline void
over(float C[3], float *A, const float out[3], float alpha) {
    const float w = 1 - *A;
    C[0] += w * out[0];
    C[1] += w * out[1];
    C[2] += w * out[2];
    *A += w * alpha;
}

/* Composites one classified sample (table entry e: opacity, then colour
 * times opacity) at ray parameter t under the accumulated C, A. g is the
 * index-space gradient there (read only when the object is shaded). */
static inline void
composite_sample(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, const float v[3],
                 const float *e, double t, const float g[3], float C[3], float *A) {
    float out[3];
    sample_colour(fr, ob, wr, v, t, g, e + 1, e[0], out);
    over(C, A, out, e[0]);
}

/* Shades and composites one classified sample of channel co (table entry
 * e) at cell o, fractions f (point p, ray parameter t) under C, A. */
static inline void
channel_composite(const rc_frame *fr, const rc_obj *co, const vv_ray *wr, const float v[3],
                  const float *e, size_t o, const float f[3], const float p[3], double t,
                  float C[3], float *A) {
    float g[3] = {0, 0, 0};
    if (co->shading && co->c->nrm)
        vv_vcache_gradient_at(co->c, o, f, g);
    else if (co->shading)
        vv_vcache_gradient(co->c, p, g);
    composite_sample(fr, co, wr, v, e, t, g, C, A);
}

/* Channel co's table entry e at index point p with its extras applied (a
 * label channel's colour by label, vv_vextra_apply); buf holds the result
 * when it is not e itself. */
static inline const float *
channel_entry(const rc_obj *co, const float *e, const float p[3], float buf[4]) {
    if (!co->extras || e[0] <= 0)
        return e;
    const float val = co->x.lut2d ? vv_vcache_sample(co->c, p) : 0;
    return vv_vextra_apply(&co->x, co->c, p, val, e, buf);
}

/* One sample of a multi-channel object under the composite rule
 * (VV_BLEND_COMPOSITE) at cell o, fractions f (point p, ray parameter t):
 * e[ch] is channel ch's table entry there, NULL where its subvolume cannot
 * show. Each channel with opacity is shaded with its own gradient; the
 * opacities combine as independent absorbers, alpha = 1 - prod(1 - a_c),
 * the colours mix weighted by opacity, and the mixed sample is composited
 * under C, A. Returns 1 when the sample had any opacity. */
static inline int
mix_channels(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, const float v[3],
             const float *const *e, size_t o, const float f[3], const float p[3], double t,
             float C[3], float *A) {
    float T = 1, sum_a = 0, col[3] = {0, 0, 0};
    for (int k = 0; k < ob->nch; k++) {
        if (!e[k] || e[k][0] <= 0)
            continue;
        /* the channel's shaded, opacity-weighted colour: composited under
         * nothing, composite_sample adds exactly that */
        float one[3] = {0, 0, 0}, a = 0;
        channel_composite(fr, &ob->ch[k], wr, v, e[k], o, f, p, t, one, &a);
        col[0] += one[0];
        col[1] += one[1];
        col[2] += one[2];
        sum_a += e[k][0];
        T *= 1 - e[k][0];
    }
    if (!(sum_a > 0))
        return 0;
    const float a = 1 - T, scale = a / sum_a, w = 1 - *A;
    C[0] += w * scale * col[0];
    C[1] += w * scale * col[1];
    C[2] += w * scale * col[2];
    *A += w * a;
    return 1;
}

/* A multi-channel object on its own ray: under the composite rule (alone
 * among the composited objects) the channels mixed per sample
 * (mix_channels), under the additive rule (VV_BLEND_ADDITIVE) every
 * visible channel composited front to back on its own, ending at its own
 * early termination, and the colours added, res->a = 1 - prod(1 - A_c).
 * As trace_composite_one does for one channel: the rays leap over cubes of
 * subvolumes that no channel shows (the smallest of the channels'
 * distances), and inside a subvolume each channel that may show there
 * classifies a chunk of samples at a time (vv_vray_classify: the same
 * values, hence the same image, as the one-channel kernel's). */
static void
trace_channels(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, float et, rc_result *res) {
    const int additive = ob->blend == VV_BLEND_ADDITIVE, nch = ob->nch;
    float C[VV_MAX_CHANNELS][3], A[VV_MAX_CHANNELS];
    int live = additive ? nch : 1;
    float depth = INFINITY;
    memset(C, 0, sizeof C);
    memset(A, 0, sizeof A);
    vv_vray r;
    if (ray_setup(ob, wr, &r)) {
        const vv_vcache *c = ob->ch[0].c;
        const double dt = fr->dt, inv_dt = 1.0 / fr->dt;
        const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
        const unsigned bxm = (unsigned)c->bx - 1, bym = (unsigned)c->by - 1,
                       bzm = (unsigned)c->bz - 1;
        double k = vv_ceil_pos(r.t0 * inv_dt);
        const double kend = vv_floor_pos(r.t1 * inv_dt);
        while (k <= kend && live > 0) {
            double t = k * dt;
            float p[3];
            vv_vray_point(&r, t, p);
            unsigned bc[3];
            const size_t b = vv_vblock_of(c, p, bxm, bym, bzm, bc);
            int dist = 255;
            for (int ch = 0; ch < nch; ch++)
                if (A[additive ? ch : 0] < et && ob->ch[ch].bdist[b] < dist)
                    dist = ob->ch[ch].bdist[b];
            if (dist) {
                k = vv_vray_leap(&r, p, t, bc, dist, inv_dt, k);
                continue;
            }
            double klast = vv_floor_pos(vv_vray_cube_exit(&r, p, t, VV_VC_BLOCK) * inv_dt);
            klast = klast < kend ? klast : kend;
            klast = klast < k ? k : klast;
            const int n = (int)(klast - k) + 1;
            for (int s0 = 0; s0 < n && live > 0; s0 += VV_VC_CHUNK) {
                const int m = n - s0 < VV_VC_CHUNK ? n - s0 : VV_VC_CHUNK;
                size_t cell[VV_VC_CHUNK];
                int32_t entry[VV_MAX_CHANNELS][VV_VC_CHUNK];
                float fx[VV_VC_CHUNK], fy[VV_VC_CHUNK], fz[VV_VC_CHUNK];
                int shows[VV_MAX_CHANNELS];
                const double kfirst = k + s0;
                for (int ch = 0; ch < nch; ch++) {
                    const rc_obj *co = &ob->ch[ch];
                    shows[ch] = co->bvis[b] && A[additive ? ch : 0] < et;
                    if (shows[ch])
                        vv_vray_classify(co->c, &co->tab, &r, kfirst, dt, m, fr->avx2, cell, fx, fy,
                                         fz, entry[ch], NULL);
                }
                for (int s = 0; s < m && live > 0; s++) {
                    t = (kfirst + s) * dt;
                    const float f[3] = {fx[s], fy[s], fz[s]};
                    if (ob->ch[0].shading || fr->point_lights || ob->ch_extras)
                        vv_vray_point(&r, t, p);
                    if (!additive) {
                        const float *e[VV_MAX_CHANNELS];
                        float ebuf[VV_MAX_CHANNELS][4];
                        for (int ch = 0; ch < nch; ch++)
                            e[ch] = shows[ch]
                                        ? channel_entry(&ob->ch[ch], ob->ch[ch].lut + entry[ch][s],
                                                        p, ebuf[ch])
                                        : NULL;
                        if (mix_channels(fr, ob, wr, v, e, cell[s], f, p, t, C[0], &A[0]) &&
                            depth == INFINITY)
                            depth = (float)t;
                        live = A[0] < et;
                        continue;
                    }
                    for (int ch = 0; ch < nch; ch++) {
                        const rc_obj *co = &ob->ch[ch];
                        if (!shows[ch] || A[ch] >= et)
                            continue;
                        float ebuf[4];
                        const float *e = channel_entry(co, co->lut + entry[ch][s], p, ebuf);
                        if (e[0] <= 0)
                            continue;
                        channel_composite(fr, co, wr, v, e, cell[s], f, p, t, C[ch], &A[ch]);
                        if (depth == INFINITY)
                            depth = (float)t;
                        live -= A[ch] >= et;
                    }
                }
            }
            k = klast + 1;
        }
    }
    float T = 1;
    res->rgb[0] = res->rgb[1] = res->rgb[2] = 0;
    for (int ch = 0; ch < (additive ? nch : 1); ch++) {
        res->rgb[0] += C[ch][0];
        res->rgb[1] += C[ch][1];
        res->rgb[2] += C[ch][2];
        T *= 1 - (A[ch] > 1 ? 1 : A[ch]);
    }
    res->a = additive ? 1 - T : A[0] > 1 ? 1 : A[0];
    res->depth = depth;
}

/* A vector of eight floats: one shading table entry (shade_table.h). */
typedef float rc_v8f __attribute__((vector_size(32)));

/* The table entries of the eight corners of the cell at offset @p o. */
static inline void
table_corners(const vv_vcache *c, const vv_vshade_table *t, size_t o, rc_v8f k[8]) {
    const size_t sy = c->sy, sz = c->sz;
    const size_t at[8] = {o,      o + 1,      o + sy,      o + sy + 1,
                          o + sz, o + sz + 1, o + sz + sy, o + sz + sy + 1};
    for (int q = 0; q < 8; q++)
        memcpy(&k[q], vv_vshade_table_entry(t, c, at[q]), sizeof k[q]);
}

/* The second pass of the one-volume composite kernel under shading=table
 * (shade_table.h): the visible samples of a classified chunk of @p m,
 * each shaded by its cell's eight corners' table entries (diffuse factor
 * and specular term) blended trilinearly, then composited in order under
 * C, A, stopping when A reaches @p et. The corners' entries (@p k) are
 * read again only when a sample's cell differs from the one they hold
 * (*kcell; SIZE_MAX: none), as VTK's VTKKWRCHelper_InterpolateShading keeps
 * its corner data while the ray stays in a cell. *first (when < 0) gets
 * the chunk index of the first sample composited; *shaded counts them.
 * Returns 1 when the ray ended. */
__attribute__((noinline)) static int
chunk_shade_table(const rc_obj *ob, int m, const size_t *cell, const float *fx, const float *fy,
                  const float *fz, const int32_t *entry, float et, float C[3], float *A, int *first,
                  uint32_t *shaded, size_t *kcell, rc_v8f k[8]) {
    const vv_vcache *c = ob->c;
    float c0 = C[0], c1 = C[1], c2 = C[2], acc = *A;
    int end = 0;
    uint32_t n = 0;
    for (int s = 0; s < m; s++) {
        const float *e = ob->lut + entry[s];
        const float alpha = e[0];
        if (alpha <= 0)
            continue;
        if (cell[s] != *kcell) {
            *kcell = cell[s];
            table_corners(c, ob->stab, cell[s], k);
        }
        const float x = fx[s], y = fy[s], z = fz[s];
        rc_v8f a0 = k[0] + (k[1] - k[0]) * x, a1 = k[2] + (k[3] - k[2]) * x;
        rc_v8f a2 = k[4] + (k[5] - k[4]) * x, a3 = k[6] + (k[7] - k[6]) * x;
        a0 += (a1 - a0) * y;
        a2 += (a3 - a2) * y;
        a0 += (a2 - a0) * z;
        if (*first < 0)
            *first = s;
        n++;
        const float w = 1 - acc;
        c0 += w * (a0[0] * e[1] + alpha * a0[4]);
        c1 += w * (a0[1] * e[2] + alpha * a0[5]);
        c2 += w * (a0[2] * e[3] + alpha * a0[6]);
        acc += w * alpha;
        if (acc >= et) {
            end = 1;
            break;
        }
    }
    C[0] = c0;
    C[1] = c1;
    C[2] = c2;
    *A = acc;
    *shaded += n;
    return end;
}

/* The common case, one volume in composite mode, without the bookkeeping
 * of the general loop: a two-level subvolume skip, then a tight march
 * through each run of visible subvolumes (up to VV_VC_CHUNK samples),
 * classified, shaded (eight at a time with AVX2: vv_vshade8) and
 * composited. Produces the same samples (t = k dt) as trace_composite. */
static void
trace_composite_one(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, float et,
                    rc_result *res) {
    vv_vray r;
    float C[3] = {0, 0, 0}, A = 0;
    float depth = INFINITY;
    if (!ray_setup(ob, wr, &r))
        goto done;
    const vv_vcache *c = ob->c;
    const double dt = fr->dt, inv_dt = 1.0 / fr->dt;
    const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
    double k = vv_ceil_pos(r.t0 * inv_dt);
    const double kend = vv_floor_pos(r.t1 * inv_dt);
    /* shading eight samples at a time: cached gradients, directional lights */
    const int shade8 = VV_VC_HAVE_AVX2 && fr->avx2 && ob->shading && c->nrm && !fr->point_lights;
    /* shading=table: the corners' entries of the cell last shaded */
    size_t kcell = SIZE_MAX;
    rc_v8f kc[8];
    double klast;
    while (vv_vray_visible_run_simd(fr->avx2, c, ob->bdist, &r, dt, kend, &k, &klast)) {
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
            vv_vray_classify(c, &ob->tab, &r, kfirst, dt, m, fr->avx2, cell, fx, fy, fz, entry,
                             NULL);
            res->samples += (uint32_t)m;
            if (ob->stab) {
                int first = -1;
                const int end =
#if VV_VC_HAVE_AVX2
                    fr->avx2 && ob->stab->packed
                        ? vv_vchunk_shade8_table(c, ob->lut, ob->stab, m, cell, fx, fy, fz, entry,
                                                 et, C, &A, &first, &res->shaded)
                        :
#endif
                        chunk_shade_table(ob, m, cell, fx, fy, fz, entry, et, C, &A, &first,
                                          &res->shaded, &kcell, kc);
                if (depth == INFINITY && first >= 0)
                    depth = (float)((kfirst + first) * dt);
                if (end)
                    goto done;
                continue;
            }
            if (shade8) {
                /* the visible samples shaded eight at a time (vv_vshade8:
                 * vv_vshade's results bit for bit), then composited one by
                 * one as below */
                int first = -1;
                const int end =
                    vv_vchunk_shade8(c, ob->lut, &ob->sh, fr->lights, fr->n_lights, v, m, cell, fx,
                                     fy, fz, entry, NULL, NULL, et, C, &A, &first, &res->shaded);
                if (depth == INFINITY && first >= 0)
                    depth = (float)((kfirst + first) * dt);
                if (end)
                    goto done;
                continue;
            }
            for (int s = 0; s < m; s++) {
                const float *e = ob->lut + entry[s];
                const float alpha = e[0];
                if (alpha <= 0)
                    continue;
                res->shaded++;
                const double t = (klast - (n - 1 - (s0 + s))) * dt;
                float g[3] = {0, 0, 0};
                if (ob->shading && c->nrm) {
                    const float f[3] = {fx[s], fy[s], fz[s]};
                    vv_vcache_gradient_at(c, cell[s], f, g);
                } else if (ob->shading) {
                    float p[3];
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
    }
done:
    result_set(res, C, A, depth);
}

/* Pre-integrated classification (Engel, Kraus and Ertl 2001; option
 * preintegration, vv_vpre_segment): the one-volume composite kernel over
 * segments rather than samples. Segment j runs from sample j - 1 to sample
 * j (the ray's first one from its entry point, at the value of sample
 * k0); its opacity and colour are the transfer function integrated along
 * the linear value ramp between the two samples' values, and it is shaded
 * with the gradient at its middle (the ends' mean gradient, a trapezoid
 * rule, lost up to 2.7 dB against the converged image; docs/rendering.md).
 * The runs of visible subvolumes are those of trace_composite_one
 * (vv_vray_visible_run); a run
 * evaluates the sample before its first (unless the previous run ended
 * there) and the one after its last, so that the segments crossing into
 * hidden subvolumes count, and no segment is composited twice. Per chunk:
 * the values, then which segments are visible (vv_vpre_visible) and their
 * opacity and colour, then their shading (eight at a time with AVX2), then
 * compositing in order. */
static void
trace_composite_preint(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, float et,
                       rc_result *res) {
    vv_vray r;
    float C[3] = {0, 0, 0}, A = 0;
    float depth = INFINITY;
    if (!ray_setup(ob, wr, &r))
        goto done;
    const vv_vcache *c = ob->c;
    const vv_vtables *tab = &ob->tab;
    const double dt = fr->dt, inv_dt = 1.0 / fr->dt;
    const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
    const double k0 = vv_ceil_pos(r.t0 * inv_dt);
    double k = k0, klast;
    const double kend = vv_floor_pos(r.t1 * inv_dt);
    const int shade8 = VV_VC_HAVE_AVX2 && fr->avx2 && ob->shading && !fr->point_lights;
    /* the front of the next segment: sample kf and its table position */
    int have_f = 0;
    double kf = -1;
    float xf = 0;
    /* and its integrals, when the last segment computed them */
    int have_pf = 0;
    vv_vpre pf;
    memset(&pf, 0, sizeof pf);
    while (vv_vray_visible_run(c, ob->bdist, &r, dt, kend, &k, &klast)) {
        /* the samples to evaluate: from the front of the run's first
         * segment to the end of the segment after its last sample */
        double ja;
        if (have_f && kf >= k - 1) {
            ja = kf + 1;
        } else {
            ja = k > k0 ? k - 1 : k;
            have_f = 0;
        }
        const double jb = klast + 1 <= kend ? klast + 1 : kend;
        k = klast + 1;
        for (double j0 = ja; j0 <= jb; j0 += VV_VC_CHUNK) {
            const int m = jb - j0 + 1 < VV_VC_CHUNK ? (int)(jb - j0) + 1 : VV_VC_CHUNK;
            size_t cell[VV_VC_CHUNK];
            int32_t entry[VV_VC_CHUNK];
            float fx[VV_VC_CHUNK], fy[VV_VC_CHUNK], fz[VV_VC_CHUNK], x[VV_VC_CHUNK];
            vv_vray_classify(c, tab, &r, j0, dt, m, fr->avx2, cell, fx, fy, fz, entry, x);
            res->samples += (uint32_t)m;
            /* the visible segments of the chunk: their opacity, colour
             * times opacity, middle, and (below) the gradient there */
            int nvis = 0;
            float al[VV_VC_CHUNK + 8], cr[VV_VC_CHUNK + 8], cg[VV_VC_CHUNK + 8],
                cb[VV_VC_CHUNK + 8];
            float gx[VV_VC_CHUNK + 8], gy[VV_VC_CHUNK + 8], gz[VV_VC_CHUNK + 8];
            double tm[VV_VC_CHUNK];
            for (int s = 0; s < m; s++) {
                const double j = j0 + s;
                const int front = have_f;
                const float xa = front ? xf : x[s];
                have_f = 1;
                xf = x[s];
                kf = j;
                double len = dt;
                if (!front) {
                    have_pf = 0;
                    /* only the front of the run's first segment, unless it
                     * is the ray's first sample: then the segment from the
                     * entry point, at its value */
                    len = j * dt - r.t0;
                    if (j != k0 || !(len > 0))
                        continue;
                }
                if (!vv_vpre_visible(tab, xa, x[s])) {
                    have_pf = 0;
                    continue;
                }
                vv_vpre pb;
                if (!have_pf || !front)
                    vv_vpre_at(tab, xa, &pf);
                vv_vpre_at(tab, x[s], &pb);
                float col[3];
                const int lit = vv_vpre_segment(&pf, xa, &pb, x[s], len, &al[nvis], col);
                pf = pb; /* the next segment's front */
                have_pf = 1;
                if (!lit)
                    continue;
                cr[nvis] = col[0];
                cg[nvis] = col[1];
                cb[nvis] = col[2];
                tm[nvis++] = j * dt - 0.5 * len;
            }
            res->shaded += (uint32_t)nvis;
            for (int q = nvis; q < nvis + 8; q++) /* the last vector's unused lanes */
                gx[q] = gy[q] = gz[q] = al[q] = cr[q] = cg[q] = cb[q] = 0;
            float orr[VV_VC_CHUNK + 8], org[VV_VC_CHUNK + 8], orb[VV_VC_CHUNK + 8];
            if (ob->shading) {
                for (int q = 0; q < nvis; q++) {
                    float p[3], g[3];
                    vv_vray_point(&r, tm[q], p);
                    vv_vcache_gradient(c, p, g);
                    gx[q] = g[0];
                    gy[q] = g[1];
                    gz[q] = g[2];
                }
                for (int q = 0; shade8 && q < nvis; q += 8)
                    vv_vshade8(&ob->sh, fr->lights, fr->n_lights, v, NULL, gx + q, gy + q, gz + q,
                               al + q, cr + q, cg + q, cb + q, orr + q, org + q, orb + q);
                for (int q = 0; !shade8 && q < nvis; q++) {
                    const float g[3] = {gx[q], gy[q], gz[q]}, col[3] = {cr[q], cg[q], cb[q]};
                    float out[3];
                    sample_colour(fr, ob, wr, v, tm[q], g, col, al[q], out);
                    orr[q] = out[0];
                    org[q] = out[1];
                    orb[q] = out[2];
                }
            } else {
                memcpy(orr, cr, sizeof(float) * (size_t)nvis);
                memcpy(org, cg, sizeof(float) * (size_t)nvis);
                memcpy(orb, cb, sizeof(float) * (size_t)nvis);
            }
            for (int q = 0; q < nvis; q++) {
                const float out[3] = {orr[q], org[q], orb[q]};
                over(C, &A, out, al[q]);
                if (depth == INFINITY)
                    depth = (float)tm[q];
                if (A >= et)
                    goto done;
            }
        }
    }
    /* the ray's last segment, from its last sample to the exit point, at
     * that sample's value */
    if (have_f && kf == kend && r.t1 > kend * dt && vv_vpre_visible(tab, xf, xf)) {
        const double len = r.t1 - kend * dt, tm = kend * dt + 0.5 * len;
        vv_vpre pa;
        vv_vpre_at(tab, xf, &pa);
        float alpha, col[3], out[3];
        if (vv_vpre_segment(&pa, xf, &pa, xf, len, &alpha, col)) {
            res->shaded++;
            float g[3] = {0, 0, 0};
            if (ob->shading) {
                float p[3];
                vv_vray_point(&r, tm, p);
                vv_vcache_gradient(c, p, g);
            }
            sample_colour(fr, ob, wr, v, tm, g, col, alpha, out);
            over(C, &A, out, alpha);
            if (depth == INFINITY)
                depth = (float)tm;
        }
    }
done:
    result_set(res, C, A, depth);
}

/* The isosurface of object ob hit at ray parameter th: its colour
 * (shaded, textured) composited under C, A, which becomes opaque. */
static void
iso_hit(const rc_frame *fr, const rc_obj *ob, const vv_vray *r, const vv_ray *wr, const float v[3],
        double th, float C[3], float *A) {
    float ph[3], g[3], pw[3], col[3], base[3];
    vv_viso_hit_point(ob->c, r, wr, th, ob->sh.base, ob->textured ? &ob->obj->texture : NULL,
                      &ob->x, ph, g, pw, base);
    if (ob->shading)
        shade(fr, ob, g, pw, v, base, 1.0f, col);
    else
        memcpy(col, base, sizeof col);
    const float w = 1 - *A;
    C[0] += w * col[0];
    C[1] += w * col[1];
    C[2] += w * col[2];
    *A = 1;
}

/* One volume in iso mode: the first crossing along its runs of visible
 * subvolumes (vv_vray_iso_first, shared with the ray tracer); in a region
 * render the crossings between the region's samples and the one before
 * them (VV_REGION_NEAREST). */
static void
trace_iso_one(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, rc_result *res) {
    vv_vray r;
    float C[3] = {0, 0, 0}, A = 0, depth = INFINITY;
    int cont;
    if (ray_setup_cont(ob, wr, &r, &cont)) {
        const double th = vv_vray_iso_first(ob->c, ob->bdist, &r, fr->dt, ob->iso, fr->avx2, cont);
        if (th >= 0) {
            const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
            iso_hit(fr, ob, &r, wr, v, th, C, &A);
            depth = (float)th;
        }
    }
    result_set(res, C, A, depth);
}

/* trace_composite's march (vv_march): the objects along the ray (obs[ai])
 * and what they gathered so far. */
typedef struct rc_march {
    const rc_frame *fr;
    const vv_ray *wr;
    const rc_obj *obs[RC_MAX_OBJ];
    float v[3];
    float C[3], A, depth;
} rc_march;

/* One object's sample at index point p (ray parameter t): a hidden
 * subvolume leaps to its exit, a multi-channel object's channels mix, a
 * composite object's sample composites, an iso object's value goes to
 * the march's crossing search. */
static inline int
rc_march_sample(void *ctx, int ai, const vv_vray *r, const float p[3], double t,
                vv_march_sample *out) {
    rc_march *m = ctx;
    const rc_obj *ob = m->obs[ai];
    const vv_vcache *c = ob->c;
    if (ob->nch) { /* a multi-channel object: its channels mixed */
        const size_t b = vv_vcache_block(c, p);
        int may = 0;
        for (int ch = 0; ch < ob->nch; ch++)
            may |= ob->ch[ch].bvis[b];
        if (!may) {
            out->te = vv_vray_cube_exit(r, p, t, VV_VC_BLOCK);
            return VV_MARCH_EMPTY;
        }
        float f[3];
        const size_t o = vv_vcache_cell_of(c, p, f);
        const float *e[VV_MAX_CHANNELS];
        float ebuf[VV_MAX_CHANNELS][4];
        for (int ch = 0; ch < ob->nch; ch++) {
            const rc_obj *co = &ob->ch[ch];
            e[ch] =
                co->bvis[b]
                    ? channel_entry(
                          co, co->lut + 4 * (int)lut_index_f(co, vv_vcache_value_at(co->c, o, f)),
                          p, ebuf[ch])
                    : NULL;
        }
        if (mix_channels(m->fr, ob, m->wr, m->v, e, o, f, p, t, m->C, &m->A) &&
            m->depth == INFINITY)
            m->depth = (float)t;
        return VV_MARCH_SAMPLED;
    }
    size_t b = vv_vcache_block(c, p);
    if (!ob->bvis[b]) {
        out->te = vv_vray_cube_exit(r, p, t, VV_VC_BLOCK);
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
    float g[3] = {0, 0, 0};
    if (ob->shading)
        vv_vcache_gradient(c, p, g);
    composite_sample(m->fr, ob, m->wr, m->v, e, t, g, m->C, &m->A);
    if (m->depth == INFINITY)
        m->depth = (float)t;
    return VV_MARCH_SAMPLED;
}

/* Object ai's isosurface crossed at th. */
static inline void
rc_march_iso(void *ctx, int ai, const vv_vray *r, double th) {
    rc_march *m = ctx;
    iso_hit(m->fr, m->obs[ai], r, m->wr, m->v, th, m->C, &m->A);
    if (th < m->depth)
        m->depth = (float)th;
}

/* Front-to-back compositing of all composite and iso objects along one ray. */
static void
trace_composite(const rc_frame *fr, const vv_ray *wr, float et, rc_result *res) {
    vv_vray rays[RC_MAX_OBJ];
    rc_march m; /* fields set one by one: an initializer would clear obs[] on every ray */
    m.fr = fr;
    m.wr = wr;
    m.v[0] = (float)-wr->dir.x;
    m.v[1] = (float)-wr->dir.y;
    m.v[2] = (float)-wr->dir.z;
    m.C[0] = m.C[1] = m.C[2] = 0;
    m.A = 0;
    m.depth = INFINITY;
    int na = 0;
    double tmin = INFINITY, tmax = -INFINITY;
    for (int i = 0; i < fr->n_comp; i++)
        if (ray_setup(&fr->objs[i], wr, &rays[na])) {
            m.obs[na] = &fr->objs[i];
            tmin = rays[na].t0 < tmin ? rays[na].t0 : tmin;
            tmax = rays[na].t1 > tmax ? rays[na].t1 : tmax;
            na++;
        }
    if (na > 0)
        vv_march(rays, na, tmin, tmax, fr->dt, et, &m.A, &m, NULL, rc_march_sample, rc_march_iso,
                 NULL);
    result_set(res, m.C, m.A, m.depth);
}

/* Maximum / minimum intensity projection and X-ray (mean) of one object
 * (vv_vray_project). Returns 0 when the ray misses the object. */
static int
trace_projection(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, float *value,
                 float *depth) {
    vv_vray r;
    if (!ray_setup(ob, wr, &r))
        return 0;
    if (ob->mode == VV_MODE_ATTENUATED_MIP) {
        vv_vray_attenuated_mip(ob->c, &r, fr->dt, &ob->att, value, depth);
        return 1;
    }
    /* MIP and MinIP need not tell apart values the table shows alike */
    vv_vray_project_tables(ob->c, &ob->tab, &r, ob->mode, fr->dt, fr->st->skipping, fr->avx2, value,
                           depth);
    return 1;
}

/* A multi-channel object under the maximum rule (VV_BLEND_MAXIMUM): a
 * maximum intensity projection per visible channel, each maximum coloured
 * as a one-channel MIP is (colour times opacity at that value), the
 * channels added. res->a = 1 - prod(1 - a_c). The projections share one
 * traversal of the ray (vv_vray_project_channels: the values of the
 * one-channel projections). */
static void
trace_channels_maximum(const rc_frame *fr, const rc_obj *ob, const vv_ray *wr, rc_result *res) {
    float T = 1;
    res->rgb[0] = res->rgb[1] = res->rgb[2] = 0;
    res->depth = INFINITY;
    res->a = 0;
    vv_vray r;
    if (!ray_setup(ob, wr, &r))
        return; /* every channel shares the object's rays */
    const vv_vcache *cs[VV_MAX_CHANNELS];
    const vv_vtables *ts[VV_MAX_CHANNELS];
    float vals[VV_MAX_CHANNELS], deps[VV_MAX_CHANNELS];
    for (int c = 0; c < ob->nch; c++) {
        cs[c] = ob->ch[c].c;
        ts[c] = &ob->ch[c].tab;
    }
    vv_vray_project_channels(cs, ts, ob->nch, &r, fr->dt, fr->st->skipping, fr->avx2, vals, deps);
    for (int c = 0; c < ob->nch; c++) {
        const rc_obj *co = &ob->ch[c];
        const float val = vals[c], dep = deps[c];
        const float *e = co->lut + 4 * (int)lut_index_f(co, val);
        for (int k = 0; k < 3; k++)
            res->rgb[k] += e[1 + k] * e[0];
        T *= 1 - e[0];
        res->depth = dep < res->depth ? dep : res->depth;
    }
    res->a = 1 - T;
}

/* ---------------------------------------------------------------------- */
/* Frame set-up                                                             */

static vv_status
prepare_object(rc_frame *fr, rc_obj *ro, const vv_object *obj, const vv_world *w,
               const vv_render_region *region) {
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
    if (region) {
        /* rays in the whole volume's index box, samples from the region's voxels */
        ro->region = region;
        for (int a = 0; a < 3; a++)
            ro->dims[a] = region->dims[a] > 1 ? region->dims[a] : 2;
    }
    ro->shading = obj->shading;
    if (ro->mode == VV_MODE_COMPOSITE || ro->mode == VV_MODE_ISO) {
        vv_vcache_need_normals(&st->vc, ro->c);
        if (obj->shading && !ro->c->nrm && fr->stats)
            fr->stats->gradients_at_samples++;
    }
    ro->iso = (float)(obj->isovalue - ro->c->qoff);
    return VV_OK;
}

/* A multi-channel object: each visible channel prepared as an object of its
 * own, chobj[k] (the object with the channel's volume and transfer
 * function, one channel, no 2-D TF or texture; composite mode for the
 * composite and additive rules, MIP for the maximum rule) into ch[k]; the
 * slot ro set up as the first of them (rays, the skipping grid's layout).
 * With @p region (the composite rule by regions) each channel's volume is
 * its voxels of the region, sampled as a one-channel region's are. */
static vv_status
prepare_channels(rc_frame *fr, rc_obj *ro, const vv_object *obj, const vv_world *w, rc_obj *ch,
                 vv_object *chobj, const vv_render_region *region) {
    int n = 0;
    for (int c = 0; c < obj->n_channels; c++) {
        const vv_channel *cc = &obj->channels[c];
        if (!cc->visible || !cc->volume)
            continue;
        vv_object *o = &chobj[n];
        vv_vchannel_object(obj, cc, o);
        vv_status s = prepare_object(fr, &ch[n], o, w, region);
        if (s != VV_OK)
            return vv_error_prefix(s, "channel %d ('%s')", c, cc->name);
        n++;
    }
    vv_status s = prepare_object(fr, ro, &chobj[0], w, region);
    if (s != VV_OK)
        return s;
    ro->obj = obj;
    ro->nch = n;
    ro->ch = ch;
    ro->blend = obj->blend;
    return VV_OK;
}

/* The object's tables (vv_vtables_get: borrowed from its volume's cache
 * when nothing they depend on changed). */
static vv_status
prepare_tables(rc_frame *fr, rc_obj *ro) {
    vv_status s =
        vv_vtables_get(&fr->st->vc, ro->c, ro->obj, ro->mode, fr->dt, ro->iso, fr->st->skipping,
                       fr->preint ? VV_VT_PREINT : 0, &ro->tab, &ro->owns_tables);
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

/* ---------------------------------------------------------------------- */
/* The renderer                                                             */

/* Casts the ray of pixel (x, y): px gets the pixel's colour and opacity
 * over the background, and its depth (px[4]); key (region renders of
 * projections) the projected value. */
static void
cast_pixel(const rc_frame *fr, int x, int y, vv_render_stats *work, float px[5], float *key_out) {
    /* inline: this runs for every pixel, most of which miss the volume */
    const vv_ray wr = vv_camera_ray(&fr->cam, x, y);
    rc_result res = {{0, 0, 0}, 0, INFINITY, 0, 0};
    float et = fr->et;
    if (fr->front) {
        /* early ray termination across regions (vv_render_region.front):
         * the ray ends once af + (1 - af) A >= et, as the whole ray would */
        const float af =
            fr->front->rgba[4 * ((size_t)y * (size_t)fr->front->width + (size_t)x) + 3];
        if (af >= et) {
            px[0] = px[1] = px[2] = px[3] = 0;
            px[4] = INFINITY;
            if (key_out)
                *key_out = NAN;
            return;
        }
        et = (et - af) / (1 - af);
    }
    if (fr->n_comp == 1 && fr->objs[0].nch)
        trace_channels(fr, &fr->objs[0], &wr, et, &res);
    else if (fr->preint)
        trace_composite_preint(fr, &fr->objs[0], &wr, et, &res);
    else if (fr->n_comp == 1 && fr->objs[0].mode == VV_MODE_COMPOSITE && !fr->objs[0].extras)
        trace_composite_one(fr, &fr->objs[0], &wr, et, &res);
    else if (fr->n_comp == 1 && fr->objs[0].mode == VV_MODE_ISO)
        trace_iso_one(fr, &fr->objs[0], &wr, &res);
    else if (fr->n_comp > 0)
        trace_composite(fr, &wr, et, &res);
    /* projection objects: combined behind the composited ones */
    float P[3] = {0, 0, 0}, PA = 0, pdepth = INFINITY, key = NAN;
    for (int i = fr->n_comp; i < fr->n_obj; i++) {
        const rc_obj *ob = &fr->objs[i];
        float val, dep;
        if (ob->nch) { /* a multi-channel object, additive or maximum */
            rc_result g;
            if (ob->blend == VV_BLEND_ADDITIVE)
                trace_channels(fr, ob, &wr, fr->et, &g);
            else
                trace_channels_maximum(fr, ob, &wr, &g);
            for (int ch = 0; ch < 3; ch++)
                P[ch] = g.rgb[ch] > P[ch] ? g.rgb[ch] : P[ch];
            PA = g.a > PA ? g.a : PA;
            pdepth = g.depth < pdepth ? g.depth : pdepth;
            continue;
        }
        if (!trace_projection(fr, ob, &wr, &val, &dep))
            continue;
        key = val;
        const float *e = ob->lut + 4 * (int)lut_index_f(ob, val);
        for (int ch = 0; ch < 3; ch++) {
            float cv = e[1 + ch] * e[0];
            P[ch] = cv > P[ch] ? cv : P[ch];
        }
        PA = e[0] > PA ? e[0] : PA;
        pdepth = dep < pdepth ? dep : pdepth;
    }
    float A = res.a;
    float rest = 1 - A;
    float A2 = A + rest * PA;
    /* (a region render's background is black: the driver adds it once) */
    for (int ch = 0; ch < 3; ch++)
        px[ch] = res.rgb[ch] + rest * P[ch] + (1 - A2) * fr->bg[ch];
    px[3] = A2;
    px[4] = res.depth < pdepth ? res.depth : pdepth;
    if (key_out)
        *key_out = key;
    work->samples += res.samples;
    work->shaded += res.shaded;
}

static inline void
store_pixel(const rc_frame *fr, int x, int y, const float px[5]) {
    const size_t at = (size_t)y * (size_t)fr->out->width + (size_t)x;
    memcpy(fr->out->rgba + 4 * at, px, 4 * sizeof(float));
    fr->out->depth[at] = px[4];
}

static inline void
tile_stats(const rc_frame *fr, const vv_render_stats *work) {
    if (fr->stats) {
#pragma omp atomic
        fr->stats->samples += work->samples;
#pragma omp atomic
        fr->stats->shaded += work->shaded;
    }
}

/* A region render in xray mode: pixel (x, y)'s sum of the region's
 * sample values and their count (vv_region_image.key, VV_REGION_SUM), the
 * whole ray's entry as the depth where the region holds its first sample. */
static void
xray_sum_pixel(const rc_frame *fr, int x, int y, vv_render_stats *work) {
    const rc_obj *ob = &fr->objs[0];
    const vv_ray wr = vv_camera_ray(&fr->cam, x, y);
    const size_t at = (size_t)y * (size_t)fr->out->width + (size_t)x;
    work->samples += (uint64_t)vv_vray_xray_region_pixel(
        ob->c, ob->w2i, ob->dims, ob->planes, ob->n_planes, ob->region, fr->dt, ob->inv_form, &wr,
        fr->avx2, fr->out->rgba + 4 * at, &fr->out->depth[at], &fr->key[at]);
}

/* A region render in attenuated-mip mode: pixel (x, y)'s largest
 * attenuated value of the region's samples (real units) and the sum of
 * their exponents (vv_region_image.key, VV_REGION_ATTENUATED_MAX). */
static void
attenuated_pixel(const rc_frame *fr, int x, int y, vv_render_stats *work) {
    const rc_obj *ob = &fr->objs[0];
    const vv_ray wr = vv_camera_ray(&fr->cam, x, y);
    const size_t at = (size_t)y * (size_t)fr->out->width + (size_t)x;
    work->samples += (uint64_t)vv_vray_attenuated_region_pixel(
        ob->c, ob->w2i, ob->dims, ob->planes, ob->n_planes, ob->region, fr->dt, ob->inv_form, &wr,
        &ob->att, fr->out->rgba + 4 * at, &fr->out->depth[at], &fr->key[at]);
}

static vv_status
render_tile(void *user, const vv_frame_tile *t) {
    const rc_frame *fr = user;
    vv_render_stats work = {0};
    if (fr->xsum || fr->asum) {
        for (int y = t->y0; y < t->y1; y++)
            for (int x = t->x0; x < t->x1; x++) {
                if (fr->xsum)
                    xray_sum_pixel(fr, x, y, &work);
                else
                    attenuated_pixel(fr, x, y, &work);
            }
        tile_stats(fr, &work);
        return VV_OK;
    }
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++) {
            float px[5], key;
            cast_pixel(fr, x, y, &work, px, &key);
            store_pixel(fr, x, y, px);
            if (fr->key)
                fr->key[(size_t)y * (size_t)fr->out->width + (size_t)x] = key;
        }
    tile_stats(fr, &work);
    return VV_OK;
}

/* Adaptive refinement (vv_frame_refine_tile): the frame runner's lattice
 * asks for single pixels. */
static void
refine_pixel(void *user, int x, int y, float px[5], void *work) {
    cast_pixel(user, x, y, work, px, NULL);
}

static vv_status
render_tile_refined(void *user, const vv_frame_tile *t) {
    const rc_frame *fr = user;
    vv_render_stats work = {0};
    vv_frame_refine_tile(t, fr->out->width, fr->out->height, fr->tolerance, refine_pixel,
                         (void *)fr, &work, fr->out->rgba, fr->out->depth);
    tile_stats(fr, &work);
    return VV_OK;
}

/* The classification of @p obj has a pre-integrated form
 * (trace_composite_preint): composite mode, a 1-D transfer function or a
 * threshold, no solid texture. */
static int
preint_applies(const vv_object *obj) {
    return obj->mode == VV_MODE_COMPOSITE &&
           (obj->segmentation == VV_SEG_TRANSFER_FUNCTION ||
            obj->segmentation == VV_SEG_THRESHOLD) &&
           obj->solid_texture.kind == VV_SOLID_TEXTURE_NONE;
}

/* A whole render, or with @p region only its samples (the World then has
 * that one visible object, a copy whose volume is the region's voxels). */
static vv_status
render_frame(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
             const vv_render_region *region, vv_image *out, float *key) {
    rc_state *st = state;
    rc_frame fr;
    memset(&fr, 0, sizeof fr);
    fr.st = st;
    st->vc.frame++;
    fr.avx2 = st->simd && vv_vc_have_avx2();
    fr.view = view;
    fr.out = out;
    fr.et = (float)st->early_termination;
    fr.stats = opt ? opt->stats : NULL;
    vv_frame_colours(w, region != NULL, fr.ambient, fr.bg);
    prepare_lights(&fr, w, view);
    vv_camera_rays_init(&fr.cam, view);

    int nvis = 0, nch = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *ob = w->objects[i];
        if (ob->visible && ob->type == VV_OBJECT_VOLUME && ob->volume &&
            (ob->n_channels < 2 || vv_vchannels_shown(ob))) {
            nvis++;
            nch += ob->n_channels > 1 ? vv_vchannels_shown(ob) : 0;
        }
    }
    if (nvis > RC_MAX_OBJ || nvis + nch > VV_VC_MAX)
        return vv_error_set(VV_ERR_LIMIT,
                            "%d visible objects and %d channels; at most %d objects and %d volumes "
                            "are supported",
                            nvis, nch, RC_MAX_OBJ, VV_VC_MAX);
    rc_obj *objs = calloc((size_t)nvis + 1, sizeof *objs);
    rc_obj *chans = calloc((size_t)nch + 1, sizeof *chans);
    vv_object *chobj = calloc((size_t)nch + 1, sizeof *chobj);
    if (!objs || !chans || !chobj) {
        free(objs);
        free(chans);
        free(chobj);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    fr.objs = objs;
    /* composite and iso objects first (a multi-channel object under the
     * composite rule among them), projections after (the additive and
     * maximum rules among them) */
    double dt = INFINITY;
    vv_status s = VV_OK;
    int n_chans = 0;
    for (int pass = 0; pass < 2 && s == VV_OK; pass++)
        for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
            const vv_object *ob = w->objects[i];
            if (!ob->visible || ob->type != VV_OBJECT_VOLUME || !ob->volume)
                continue;
            const int multi = ob->n_channels > 1;
            if (multi && !vv_vchannels_shown(ob))
                continue;
            int comp = multi ? ob->blend == VV_BLEND_COMPOSITE
                             : ob->mode == VV_MODE_COMPOSITE || ob->mode == VV_MODE_ISO;
            if (comp != (pass == 0))
                continue;
            if (!(ob->step > 0))
                s = vv_error_set(VV_ERR_INVALID, "object '%s': step must be > 0", ob->name);
            else if (multi)
                s = prepare_channels(&fr, &objs[fr.n_obj++], ob, w, chans + n_chans,
                                     chobj + n_chans, region);
            else
                s = prepare_object(&fr, &objs[fr.n_obj++], ob, w, region);
            if (s == VV_OK) {
                n_chans += objs[fr.n_obj - 1].nch;
                double sd = vv_vobject_step(ob);
                dt = sd < dt ? sd : dt;
            }
            if (pass == 0)
                fr.n_comp = fr.n_obj;
        }
    /* pre-integration: one volume in composite mode with a 1-D transfer
     * function or a threshold, whole renders only (a region's first
     * segment would need the sample before it, in another region) */
    fr.preint = st->preint && s == VV_OK && !region && fr.n_obj == 1 && fr.n_comp == 1 &&
                !objs[0].nch && preint_applies(objs[0].obj);
    fr.dt = (float)(dt < INFINITY ? dt : 1.0);
    for (int i = 0; i < fr.n_obj && s == VV_OK; i++) {
        objs[i].dt = fr.dt;
        if (objs[i].mode == VV_MODE_ATTENUATED_MIP && !objs[i].nch &&
            (s = vv_vatten_prepare(&objs[i].att, objs[i].obj, objs[i].c, fr.dt)) != VV_OK)
            break;
        if (objs[i].nch) {
            /* its channels have the tables; trace_channels finds its
             * first sample as ceil(t0 * (1 / dt)) (a region's clip too) */
            objs[i].inv_form = 1;
            continue;
        }
        s = prepare_tables(&fr, &objs[i]);
        objs[i].inv_form =
            fr.n_comp == 1 && objs[i].mode == VV_MODE_COMPOSITE && !objs[i].extras && !objs[i].nch;
    }
    for (int i = 0; i < n_chans && s == VV_OK; i++) {
        s = prepare_tables(&fr, &chans[i]);
        chans[i].dt = fr.dt;
    }
    for (int i = 0; i < fr.n_obj && s == VV_OK; i++)
        for (int k = 0; k < objs[i].nch; k++)
            objs[i].ch_extras |= objs[i].ch[k].extras;
    /* shading=table (or a preview's fast shading): the one-volume
     * composite kernel's objects with cached gradients and directional
     * lights (trace_composite_one); others keep Phong */
    if (s == VV_OK && (st->shading_table || (opt && opt->fast_shading)) && fr.n_comp == 1 &&
        !fr.preint && !objs[0].nch && objs[0].mode == VV_MODE_COMPOSITE && !objs[0].extras &&
        objs[0].shading && objs[0].c->nrm && !fr.point_lights) {
        /* the view direction: the camera's (orthographic rays all have
         * it; perspective ones deviate from it by up to half the field) */
        const double fx = view->at.x - view->eye.x, fy = view->at.y - view->eye.y,
                     fz = view->at.z - view->eye.z;
        const double fl = sqrt(fx * fx + fy * fy + fz * fz);
        if (fl > 0) {
            const float v[3] = {(float)(-fx / fl), (float)(-fy / fl), (float)(-fz / fl)};
            int built = 0;
            s = vv_vshade_table_update(&st->stab, &objs[0].sh, fr.lights, fr.n_lights, v, &built);
            if (s == VV_OK)
                objs[0].stab = &st->stab;
            if (s == VV_OK && fr.stats)
                fr.stats->shading_tables_built += (uint32_t)built;
        }
    }
    fr.xsum = region && fr.n_obj == 1 && objs[0].mode == VV_MODE_XRAY;
    fr.asum = region && fr.n_obj == 1 && objs[0].mode == VV_MODE_ATTENUATED_MIP;
    if (s == VV_OK && (fr.xsum || fr.asum) && objs[0].nch)
        s = vv_error_set(VV_ERR_UNSUPPORTED,
                         "object '%s': %s regions of a multi-channel object are not rendered",
                         objs[0].obj->name, fr.xsum ? "xray" : "attenuated-mip");
    if (s == VV_OK && (fr.xsum || fr.asum)) {
        /* the table that classifies the summed means (vv_xray_table_classify),
         * or the attenuated maxima, whose keys are real values (value + qoff) */
        st->xray.lut_lo = objs[0].lut_lo + (fr.asum ? (float)objs[0].c->qoff : 0.0f);
        st->xray.lut_scale = objs[0].lut_scale;
        memcpy(st->xray.lut, objs[0].lut, sizeof st->xray.lut);
    }
    if (s == VV_OK) {
        fr.key = region && fr.n_comp == 0 ? key : NULL;
        /* adaptive refinement: whole renders only (a region's pixels are
         * composited with other ranks' by their depth and key); auto at
         * quality 2 too where it was measured to pay (issue 65;
         * docs/rendering.md, "Quality and adaptive refinement"): frames of
         * composite, MIP and MinIP objects, at the tolerance 1/1024, lose
         * at most 0.001 dB against the converged reference and are
         * 4-17 % (composite) and 25 % (MIP) faster (calm cells, and rays
         * through empty space, interpolated rather than cast). Region
         * renders cast every pixel, so out-of-core and multi-channel
         * maximum images are the unrefined ones (refinement=off) bit for
         * bit, 73 dB or more from the refined default. X-ray lost up to
         * 2 dB. */
        int pays = fr.n_obj > 0;
        for (int i = 0; i < fr.n_obj; i++)
            pays &= objs[i].mode == VV_MODE_COMPOSITE || objs[i].mode == VV_MODE_MIP ||
                    objs[i].mode == VV_MODE_MINIP;
        /* early ray termination across the caller's regions: one object
         * under the composite rule, a ray a pixel */
        if (region && region->front && fr.n_obj == 1 && fr.n_comp == 1 &&
            objs[0].mode == VV_MODE_COMPOSITE &&
            (!objs[0].nch || objs[0].blend == VV_BLEND_COMPOSITE))
            fr.front = region->front;
        fr.refine = vv_frame_refine_for(&st->refine, opt ? opt->quality : 2, region != NULL, pays,
                                        &fr.tolerance);
        vv_frame_job job;
        vv_frame_job_init(&job, view->width, view->height,
                          fr.refine ? render_tile_refined : render_tile, &fr);
        if (fr.refine)
            job.scratch_bytes = vv_frame_refine_scratch_bytes();
        vv_frame_job_region(&job, region); /* the rest stays empty */
        if (!region)
            job.image = out; /* a tile's pixels are final: 8 bits there (vv_pixels8) */
        s = vv_frame_run(&job, opt);
    }
    for (int i = 0; i < fr.n_obj; i++) {
        if (objs[i].owns_tables)
            vv_vtables_free(&objs[i].tab);
    }
    for (int i = 0; i < n_chans; i++)
        if (chans[i].owns_tables)
            vv_vtables_free(&chans[i].tab);
    free(objs);
    free(chans);
    free(chobj);
    /* drop cached volumes the World no longer shows */
    vv_vcache_set_prune(&st->vc, w);
    return s;
}

static vv_status
rc_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    return render_frame(state, w, view, opt, NULL, out, NULL);
}

/* The region contract: a frame of the region's World
 * (vv_region_render_by_frame, as the gpu renderer's). */
static vv_status
rc_render_region(void *state, const vv_world *w, const vv_view *view,
                 const vv_render_region *region, const vv_render_options *opt,
                 vv_region_image *out) {
    return vv_region_render_by_frame(render_frame, state, &((rc_state *)state)->xray, w, view,
                                     region, opt, out);
}

static vv_status
rc_init(void *state) {
    rc_state *st = state;
    vv_vcache_set_init(&st->vc);
    return VV_OK;
}

static void
rc_release(void *state) {
    rc_state *st = state;
    vv_vcache_set_clear(&st->vc);
    vv_vshade_table_free(&st->stab);
}

/* gradient_budget_mb: the number is stored (bytes); auto is the cache's
 * default; either way the cached gradients go. */
static vv_status
rc_budget_changed(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    rc_state *st = state;
    if (v->word >= 0)
        vv_vcache_set_default_budget(&st->vc);
    vv_vcache_set_clear(&st->vc);
    return VV_OK;
}

static const char *const rc_auto[] = {"auto", NULL};
static const char *const rc_shadings[] = {"phong", "table", NULL};

/* The ray caster's options (docs/rendering.md), each bound to its field of
 * rc_state; gradient_budget_mb is splat's too (vv_vcache_set.gradient_budget,
 * sample.h). */
static const vv_option_spec rc_options[] = {
    {"early_termination", VV_OPTION_REAL, "0.99", 0, 1, VV_OPTION_MIN_OPEN, NULL,
     "accumulated opacity that ends a composite ray",
     VV_OPTION_BIND(rc_state, early_termination, DOUBLE)},
    {"gradient_budget_mb", VV_OPTION_REAL, "auto", 0, INFINITY, 0, rc_auto,
     "MiB allowed for cached gradients (auto: a quarter of RAM, at most 8192; 0: on the fly)",
     VV_OPTION_BIND_FULL(rc_state, vc.gradient_budget, UINT64, 1048576.0, NULL, rc_budget_changed)},
    {"empty_space_skipping", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "leap over subvolumes the transfer function hides (0 for tests; same image)",
     VV_OPTION_BIND(rc_state, skipping, INT)},
    {"simd", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "AVX2 classification where the processor has it (0: the portable path)",
     VV_OPTION_BIND(rc_state, simd, INT)},
    VV_FRAME_REFINE_OPTIONS(rc_state, refine,
                            "at quality 0 and 1, and at quality 2 in frames of composite, MIP and "
                            "MinIP objects"),
    {"preintegration", VV_OPTION_BOOL, "0", 0, 1, 0, NULL,
     "pre-integrated classification (Engel et al. 2001) for one volume in composite mode with "
     "a 1-D transfer function: sharp transfer functions without slab artefacts, at about "
     "1.5-2x the time a step",
     VV_OPTION_BIND(rc_state, preint, INT)},
    {"shading", VV_OPTION_ENUM, "phong", 0, 0, 0, rc_shadings,
     "phong: Phong on the interpolated normal at every sample; table: a diffuse and a specular "
     "term per normal code (65,536, rebuilt when a light, the view direction or the material "
     "changes) blended over the cell's corners, VTK's method, faster, >= 40 dB from phong (one "
     "volume in composite mode, directional lights; else phong). The Navigator's previews use "
     "table",
     VV_OPTION_BIND(rc_state, shading_table, INT)},
};

const vv_renderer_ops vv_raycast_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "raycast",
            .description = "direct volume ray casting: composite, mip, minip, xray, iso, "
                           "attenuated-mip; subvolume skipping",
            .draws = VV_DRAWS(VV_OBJECT_VOLUME),
            .modes = VV_MODES_ALL | VV_MODE_BIT(VV_MODE_ATTENUATED_MIP),
            .caps = VV_RENDERER_REGION | VV_RENDERER_QUALITY | VV_RENDERER_PREVIEW |
                    VV_RENDERER_CHANNELS,
            .quality = "0 and 1: adaptive refinement from a lattice of every 4th pixel "
                       "(option refinement); 2: the same at the tolerance 1/1024 in "
                       "composite, MIP and MinIP frames, else one ray a pixel; all at the "
                       "objects' step",
            .options = rc_options,
            .n_options = VV_OPTIONS_COUNT(rc_options),
        },
    .state_size = sizeof(rc_state),
    .init = rc_init,
    .release = rc_release,
    .render = rc_render,
    .render_region = rc_render_region,
};
