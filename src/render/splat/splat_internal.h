/*
 * Splatting (src/render/splat), internal: what the files of the renderer
 * share. Stages, one file each: footprint.c (screen footprints of the
 * Gaussian kernels and their rasterisation), object.c (per-object eye-space
 * geometry, the voxel lists kept between renders and their bucketing by
 * sheet and band), band.c (one band of image rows: sheet buffers,
 * post-classification, compositing, occlusion), splat.c (the frame, the
 * options and the operation table). splat.c's comment describes the
 * method.
 */
#ifndef VV_RENDER_SPLAT_INTERNAL_H
#define VV_RENDER_SPLAT_INTERNAL_H

#include <math.h>
#include <stdatomic.h>
#include <stdint.h>

#include "render/classify.h"
#include "render/ray.h"
#include "render/registry.h"
#include "render/sample.h"
#include "render/shade.h"
#include "render/splat/splat.h"
#include "render/tf_tables.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

#define SP_MAX_OBJ 64 /* objects handled in one render (<= VV_VC_MAX) */
#define SP_Z_LUT 1024 /* slab-integral table entries */
#define SP_TILE 8     /* occlusion map tile side in pixels */
#define SP_LISTS 16   /* voxel lists kept between renders */
#define SP_CH 5       /* channels of a sheet pixel */
#define SP_WMIN 0.02f /* least sum of weights that is a sample (1 inside) */
#define SP_MAX_SHEETS 65536

/* One cached voxel list: the voxels worth splatting of one volume under one
 * set of visibility flags, in the traversal order of one octant. */
typedef struct sp_list {
    vv_volume *vol; /* reference held */
    uint64_t modified;
    uint64_t hash; /* of everything the selection depended on */
    int octant;
    uint64_t *vox; /* packed i | j << 21 | k << 42 */
    size_t n;
    uint64_t last_used;
} sp_list;

/* The options (sp_options in splat.c) are bound to their fields here. */
typedef struct sp_state {
    vv_vcache_set vc;     /* its gradient_budget: option gradient_budget_mb */
    double radius, sigma; /* kernel, voxels */
    double ewa_var;       /* image low-pass filter variance, pixel^2; 0: off (ewa_variance) */
    double early_termination;
    int pre;       /* pre-classified splatting (classification: post 0, pre 1) */
    int skipping;  /* empty-voxel skipping (empty_space_skipping) */
    int occlusion; /* occlusion_culling */
    int axis;      /* internal: axis-aligned sheets (the popping method, for tests; sheets:
                      image 0, axis 1) */
    double rate;   /* sheet spacing in ray-caster steps (0: by quality; sheet_spacing) */
    sp_list lists[SP_LISTS];
    uint64_t clock;
    vv_splat_stats stats;
    float *xray; /* last X-ray line integrals, or NULL */
    int xray_w, xray_h;
} sp_state;

/* A screen-space footprint: inverse covariance (pixel units) a, b, c
 * (q = a dx^2 + 2 b dx dy + c dy^2), bounding half-extents, 1/sqrt(det). */
typedef struct sp_fp {
    float a, b, c, hx, hy, norm;
} sp_fp;

typedef struct sp_obj {
    const vv_object *obj;
    vv_vcache *c;
    vv_render_mode mode;
    double w2i[3][4], i2w[3][4];
    int dims[3];
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    int n_planes;
    vv_vshading sh;
    int shading;
    int labels;  /* a label volume in composite: colour by label (vv_label_color) */
    int pre_cls; /* pre-classified: the option, or always for a label volume */
    vv_vtables tab;
    int owns_tables;
    /* eye space: X, Y (image right, down) and depth z of an index point are
     * rows . (i, j, k, 1) */
    double ex[4], ey[4], ez[4];
    double cxx, cxy, cyy;             /* footprint covariance in eye units^2 (slice or whole) */
    double bx, by;                    /* slice centre shift per unit depth offset */
    double rz;                        /* depth half-extent of the kernel support */
    double vol_det;                   /* |det| of the index-to-world map: a voxel's world volume */
    double rworld;                    /* support radius bound in world units (cut planes) */
    float wz[SP_Z_LUT], dz[SP_Z_LUT]; /* slab mass and mean offset by d */
    double z_lo, z_scale;             /* d -> table position */
    int ns;                           /* sheets a kernel can touch */
    double dt_lut;                    /* the step the opacity table is for */
    int axis_a, axis_sign;            /* axis-aligned variant: major axis, direction */
    const sp_list *list;
    /* per render, bucket-sorted by first sheet */
    uint64_t *sorted;
    float (*pre)[4]; /* pre-classified: alpha, colour * alpha (shaded) */
    float (*v4)[4];  /* post-classified and shaded: value, gradient (in sorted order) */
    float *v1;       /* otherwise: value (in sorted order) */
    int *start;      /* nsheets + 1 offsets into sorted */
    int kbase, nsheets;
    /* per band: lists */
    int **bstart;    /* [band] -> nsheets + 1 offsets into bidx */
    uint32_t **bidx; /* [band] -> indices into sorted */
    int is_comp;     /* composite (sheets, classified) */
} sp_obj;

typedef struct sp_frame {
    sp_state *st;
    const vv_view *view;
    sp_obj *objs;
    int n_obj, n_comp;
    int persp;
    double dt, dts; /* ray-caster step, sheet spacing */
    double rho2;    /* (radius / sigma)^2 */
    float et;
    float ambient[3], bg[3];
    vv_vlight lights[VV_MAX_LIGHTS];
    int n_lights, point_lights;
    vv_vec3 eye, f, r, u; /* eye point (ortho: o00), forward, right, down */
    double pix;           /* ortho: world per pixel; persp: at unit depth */
    double pcx, pcy;      /* persp: pixel of the forward axis, negated */
    vv_vec3 o00, ox, oy, d00, dx, dy;
    double znear;
    float fp_scale; /* 1 / (2 pi (1 - exp(-rho^2 / 2))): the truncated Gaussian's normalisation */
    int band_h, n_bands;
    int kmin, kmax; /* sheets of the composite objects */
    vv_image *out;  /* the image being written */
    const vv_render_options *opt;
    float *xray; /* image of line integrals (X-ray objects), or NULL */
    uint64_t footprints, culled, sheets;
} sp_frame;

/* ---- footprint.c ---------------------------------------------------------- */

/* The screen footprint of eye-space covariance (xx, xy, yy) at s pixels per
 * eye unit, its eigenvalues raised to at least ewa (EWA low-pass). */
void sp_fp_setup(double xx, double xy, double yy, double s, double ewa, double rho2, sp_fp *fp);

/* The sum over the whole pixel grid (unclipped) of exp(-q / 2) for
 * footprint fp centred at (cx, cy): X-ray footprints are divided by it so
 * that each one's pixels sum exactly to its kernel's integral whatever its
 * size and sub-pixel position (energy conservation). */
double sp_fp_discrete_sum(float *wrow, int W, float rho2, float cx, float cy, const sp_fp *fp);

/* Adds footprint fp centred at (cx, cy), weight w, cut off at rho2, to the
 * rows y0 .. y1 - 1 of a band buffer (planes ps floats apart, W wide): one
 * value (sp_fp_splat1: sum w) or four (sp_fp_splat4: sum w, w val[0..2]);
 * rect receives the pixel box touched. */
void sp_fp_splat1(float *buf, size_t ps, int W, int y0, int y1, float rho2, float cx, float cy,
                  const sp_fp *fp, float w, const float *val, int rect[4]);
void sp_fp_splat4(float *buf, size_t ps, int W, int y0, int y1, float rho2, float cx, float cy,
                  const sp_fp *fp, float w, const float *val, int rect[4]);

/* ---- object.c -------------------------------------------------------------- */

/* Eye-space maps and kernel geometry of one object for this view. */
void sp_object_geometry(sp_frame *fr, sp_obj *ob);

/* The object's voxel list for octant @p oct (bit a set: index axis a runs
 * backwards, from the far side), from the cache or built. */
vv_status sp_object_list(sp_state *st, sp_obj *ob, int oct, int *built);

/* Buckets the object's list by first sheet and distributes it over the
 * image bands. */
vv_status sp_object_buckets(sp_frame *fr, sp_obj *ob);

/* Frees what one render allocated for the object (its tables when owned,
 * buckets and band lists). */
void sp_object_free(sp_obj *ob, int nbands);

/* ---- band.c ----------------------------------------------------------------- */

/* Renders band @p t->index (the frame runner's tile: rows of fr->band_h)
 * of the image into @p out: splats, classifies and composites its sheets
 * front to back; stops early once the run is cancelled. Errors:
 * VV_ERR_NOMEM. Runs on one thread; bands are independent. */
vv_status sp_render_band(sp_frame *fr, const vv_frame_tile *t, vv_image *out);

/* ---- inline helpers ------------------------------------------------------------ */

static inline double
sp_lin4(const double r[4], double i, double j, double k) {
    return r[0] * i + r[1] * j + r[2] * k + r[3];
}

static inline void
sp_unpack(uint64_t p, int *i, int *j, int *k) {
    *i = (int)(p & 0x1FFFFF);
    *j = (int)((p >> 21) & 0x1FFFFF);
    *k = (int)(p >> 42);
}

/* Pixel position of eye-space (X, Y) at depth z. */
static inline void
sp_to_pixel(const sp_frame *fr, double X, double Y, double z, double *px, double *py) {
    if (fr->persp) {
        const double s = 1.0 / (z * fr->pix);
        *px = X * s - fr->pcx;
        *py = Y * s - fr->pcy;
    } else {
        *px = X / fr->pix;
        *py = Y / fr->pix;
    }
}

/* Pixels per eye unit at depth z. */
static inline double
sp_pix_scale(const sp_frame *fr, double z) {
    return fr->persp ? 1.0 / (z * fr->pix) : 1.0 / fr->pix;
}

/* The footprint of an object at depth z (the same for all its voxels there). */
static inline void
sp_object_fp(const sp_frame *fr, const sp_obj *ob, double z, sp_fp *fp) {
    sp_fp_setup(ob->cxx, ob->cxy, ob->cyy, sp_pix_scale(fr, z), fr->st->ewa_var, fr->rho2, fp);
}

/* A label volume's table entry @p e for value @p v: its opacity, the colour
 * of the label v rounds to (premultiplied, into @p buf). A voxel holds its
 * label exactly (pre-classification); a reconstructed value between two
 * labels takes the nearer (post-classification). */
static inline const float *
sp_label_entry(const float *e, float v, float buf[4]) {
    if (!(e[0] > 0))
        return e;
    const double r = floor((double)v + 0.5);
    const vv_vec3 col = vv_label_color(vv_label_key(r));
    buf[0] = e[0];
    buf[1] = e[0] * (float)col.x;
    buf[2] = e[0] * (float)col.y;
    buf[3] = e[0] * (float)col.z;
    return buf;
}

#endif
