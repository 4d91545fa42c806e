/*
 * What the files of the volumetric ray tracer share (not installed): the
 * frame's objects, lights and acceleration structures, and the inline vector,
 * transform and volume-ray helpers of the hot path. raytrace.c holds the
 * method's description.
 */
#ifndef VOLVIS_RT_INTERNAL_H
#define VOLVIS_RT_INTERNAL_H

#include <math.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "core/geom.h"
#include "render/classify.h"
#include "render/project.h"
#include "render/ray.h"
#include "render/registry.h"
#include "render/sample.h"
#include "render/shade.h"
#include "render/tf_tables.h"
#include "volvis/render.h"
#include "volvis/sys/geometry.h"
#include "volvis/sys/renderer.h"

#define RT_MAX_OBJ 64
#define RT_SGRID 4                    /* shadow grid spacing, voxels */
#define RT_LGRID 2                    /* light volume spacing, voxels */
#define RT_MIN_WEIGHT (1.0f / 512.0f) /* secondary rays weighing less are not traced */
#define RT_EPS 1e-6                   /* relative ray offset off surfaces */

/* ---------------------------------------------------------------------- */
/* Vector helpers: the ray tracer's short names for core/geom.h's inline ones */

#define v3 vv_v3
#define v3add vv_v3_add
#define v3sub vv_v3_sub
#define v3scale vv_v3_scale
#define v3dot vv_v3_dot
#define v3cross vv_v3_cross
#define v3len vv_v3_len
#define v3norm vv_v3_norm

static inline vv_vec3
ray_at(const vv_ray *r, double t) {
    return v3add(r->origin, v3scale(r->dir, t));
}

#define RT_LV_CACHE 16 /* light volumes kept between frames */

/* A light volume kept between frames (it does not depend on the view),
 * with everything it depends on. */
typedef struct rt_lv {
    vv_volume *vol; /* reference held; NULL: free slot */
    uint64_t modified;
    double w2i[3][4];
    int point;     /* a point light (pos), else directional (dir) */
    double dir[3]; /* directional light: towards it */
    double pos[3]; /* point light: its position */
    double dt;
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    float lut_lo, lut_scale;
    float ext[VV_VC_LUT];
    const vv_volume *whole; /* swept through the whole volume of region renders
                               (rt_vobj.whole's header; NULL: through vol) */
    uint64_t whole_modified;
    float *T;
    uint64_t used; /* frame that last used it */
} rt_lv;

#define RT_SG_CACHE 32 /* shadow grids kept between frames */

/* A shadow grid kept between frames (rt_cache.c): a grid point's shadow
 * ray does not depend on the view. key: the bytes of every input of its
 * rays; vols: the volumes it names by address (references held). */
typedef struct rt_sg {
    void *grid; /* _Atomic uint32_t (lazily filled) or float (swept); NULL: free slot */
    unsigned char *key;
    size_t key_len;
    vv_volume **vols;
    int n_vols;
    uint64_t used; /* frame that last used it */
} rt_sg;

/*
 * The slot of a renderer-state cache (n entries of @p type, a pointer
 * field @p busy that is NULL in a free slot, a uint64_t field used: the
 * frame that last used it) for a new entry: the first free one, else the
 * least recently used that frame @p frame does not use; -1 when every slot
 * is in use this frame.
 */
static inline int
rt_cache_slot(const unsigned char *base, size_t stride, size_t busy, size_t used, int n,
              uint64_t frame) {
    int slot = -1;
    uint64_t best = 0;
    for (int i = 0; i < n; i++) {
        const unsigned char *e = base + (size_t)i * stride;
        uint64_t u;
        void *p;
        memcpy(&p, e + busy, sizeof p);
        memcpy(&u, e + used, sizeof u);
        if (!p)
            return i;
        if (u != frame && (slot < 0 || u < best)) {
            slot = i;
            best = u;
        }
    }
    return slot;
}
#define RT_CACHE_SLOT(type, arr, busy, n, frame)                                                   \
    rt_cache_slot((const unsigned char *)(arr), sizeof(type), offsetof(type, busy),                \
                  offsetof(type, used), (n), (frame))

typedef struct rt_state {
    rt_lv lv[RT_LV_CACHE];
    rt_sg sg[RT_SG_CACHE];
    uint64_t frame;
    vv_vcache_set vc;                /* per-volume caches (src/render/sample.h) */
    int parc;                        /* PARC skipping on primary and secondary rays */
    int shadows;                     /* shadow rays */
    int max_depth;                   /* reflection / refraction depth */
    int samples;                     /* supersamples per pixel side at quality 2 */
    int jitter;                      /* jittered supersampling */
    int adaptive;                    /* supersample only where neighbours differ */
    double threshold;                /* adaptive: channel difference that triggers supersampling */
    vv_frame_refine_settings refine; /* adaptive image-space refinement (its options) */
    uint64_t seed;                   /* jitter seed */
    double early_termination;
    int simd;          /* AVX2 classification and shading where the processor has it */
    int shadow_grid;   /* volume samples: cached shadow rays (1) or exact (0) */
    int light_volumes; /* shadow rays of directional lights through volumes: light volumes */
    /* the X-ray table of the last region render in xray mode, which
     * classifies the summed regions' means (vv_region_image.classify) */
    vv_xray_table xray;
} rt_state;

typedef struct rt_light {
    int point;
    double dir[3]; /* unit vector towards the light (directional) */
    double pos[3];
    float col[3]; /* colour * intensity */
} rt_light;

/* One volume object prepared for this render. */
typedef struct rt_vobj {
    const vv_object *obj;
    vv_vcache *c;
    vv_render_mode mode;
    double w2i[3][4], i2w[3][4];
    int dims[3];
    double vox;             /* smallest world length of a voxel step */
    vv_vtables tab;         /* TF table, extinction (composite), PARC flags and distances */
    int owns_tables;        /* tab is this object's (else borrowed from the volume's cache) */
    const float *lut, *ext; /* tab.lut, tab.ext */
    const uint8_t *bvis;    /* tab.bvis: the subvolume may contribute */
    const uint8_t *bdist;   /* tab.bdist: chessboard distance to the nearest that may */
    int bx, by, bz;         /* subvolume grid */
    float iso;
    vv_vshading sh; /* shading constants */
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    int gdim[3];                            /* shadow grid points per axis */
    _Atomic uint32_t *sgrid[VV_MAX_LIGHTS]; /* point lights: bits of (T + 1), 0 = not traced */
    float *sweep[VV_MAX_LIGHTS];            /* directional lights: swept transmittance */
    float lidx[VV_MAX_LIGHTS][3];           /* index-space direction to the light per world unit */
    int ldim[3];                /* light volume points per axis (every RT_LGRID voxels) */
    float *lvol[VV_MAX_LIGHTS]; /* this volume's own transmittance from each point
                                   towards the light (a light volume) */
    unsigned lvol_owned;        /* bit l: lvol[l] is this frame's (else the state's cache) */
    unsigned sgrid_owned;       /* bit l: sgrid[l] and sweep[l] are this frame's (else the
                                   state's cache) */
    vv_vatten att;              /* attenuated-mip mode: napari's parameters (project.h) */
    vv_vextra x;                /* 2-D transfer function and solid texture */
    int extras;                 /* x has something: the general loop handles the object */
    int textured;               /* iso mode: an image texture modulates the base colour */
    /* region renders (sys/renderer.h): the object is traced twice. Its
     * region part samples the region's voxels on primary rays and casts no
     * shadow; its context (the World's own volume of the object: the whole
     * one, or a coarse proxy) casts the shadows and is invisible to rays. */
    const vv_render_region *region; /* the region part: its region, else NULL */
    int context;                    /* the context: shadows only */
    /* a context whose light volumes are swept through the region's whole
     * volume (region->whole, rt_light.c): its geometry is then the
     * whole volume's, and whole_part (the region part) lends the tables */
    const vv_region_volume *whole;
    const struct rt_vobj *whole_part;
    double region_dt; /* the step the region's samples are counted with */
    int inv_form;     /* vv_vray_clip_region's form for this object's kernel */
    /* a channel of a multi-channel object (vv_object.channels), prepared as
     * a volume of its own (its own cache, tables and light volumes, so that
     * shadow rays cross every channel as independent absorbers): group is
     * the index in vobjs of the object's first visible channel, its leader,
     * whose gn is the count of the object's visible channels (the next gn
     * entries); -1 (and gn 0) for an object of one channel */
    int group, gn;
    vv_channel_blend blend;     /* the object's rule for combining its channels */
    const struct rt_vobj *lead; /* whose shading constants and shadow grids its samples
                                   use: itself, or its group's leader (the channels share
                                   one transform, hence one grid of shadow rays) */
} rt_vobj;

/* One geometric object prepared for this render. */
typedef struct rt_gobj {
    const vv_object *obj;
    vv_object_type type;
    double w2o[3][4];         /* world -> object */
    double nrm[3][3];         /* object normal -> world normal (M^-T) */
    const vv_geom_type *geom; /* its record of the geometry-type table */
    void *prep;               /* what geom->prepare built, or NULL */
    float col[3];
    float kr, kt; /* reflectance (0 when the object does not reflect), transparency */
    double ior;
    int closed;         /* refracts (a solid); planes and polygons transmit straight */
    int bounded;        /* polygon, box: a world-space bounding sphere rejects rays early */
    vv_vec3 bc;         /* its centre */
    double br2;         /* its squared radius */
    vv_geometry wplane; /* plane: its world-space point and normal (M^-T n) */
} rt_gobj;

typedef struct rt_frame {
    rt_state *st;
    const vv_world *w;
    rt_vobj *vobjs;
    int n_vobj;
    rt_gobj *gobjs;
    int n_gobj;
    vv_object *chobjs; /* the channels of multi-channel objects as objects of one channel */
    int n_chobj;
    float dt;
    float bg[3];
    float ambient[3];
    rt_light lights[VV_MAX_LIGHTS];
    vv_vlight vlights[VV_MAX_LIGHTS]; /* the same, for volume shading */
    int n_lights;
    float et;
    int shadows, max_depth;
    int avx2;           /* the processor has AVX2 and FMA (vv_vray_classify) */
    double scene_size;  /* for ray offsets */
    vv_camera_rays cam; /* primary rays (the ray caster's arithmetic) */
    /* the pass being run by the frame runner */
    const vv_view *view;
    vv_image *out;
    float *key;         /* region renders of projections: the key per pixel, else NULL */
    int nss;            /* supersamples per pixel side */
    int adaptive;       /* pass 1 traces pixel centres, pass 2 supersamples where they differ */
    int refine;         /* pixels by vv_frame_refine_tile (pass_refined) */
    float tolerance;    /* its tolerance */
    const float *first; /* pass 2: the image of pass 1 */
    /* the shadow-grid cache's key of what casts shadows (rt_cache.c) */
    const vv_render_region *region; /* a region render (keeps no shadow grid) */
    /* a region render in xray mode: its object, whose primary rays give
     * their sums and counts (vv_vray_xray_region_pixel), else NULL */
    const struct rt_vobj *xsum;
    unsigned char *skey;
    size_t skey_len;
    int skey_failed;
    vv_volume *svols[RT_MAX_OBJ]; /* the volumes skey names */
    int n_svols;
} rt_frame;

/* A surface hit. */
typedef struct rt_hit {
    double t;
    int gobj;  /* index into gobjs */
    vv_vec3 n; /* world normal (unit, outward for solids) */
} rt_hit;

/* The last shadow-grid cell a ray's samples looked up, per light: its 8
 * corner transmittances, so that the samples of one ray inside one cell
 * (about 8 at a step of half a voxel) read the shared grid once. */
typedef struct rt_scache {
    const rt_vobj *ob;          /* the volume the cells belong to, NULL: none */
    size_t cell[VV_MAX_LIGHTS]; /* grid index of the cell's first corner */
    float v[VV_MAX_LIGHTS][8];  /* its corners' transmittances */
} rt_scache;

/* ---------------------------------------------------------------------- */
/* Volume rays (the caches and sampling are src/render/sample.h)           */

/* The world ray over [tmin, tmax] clipped to a volume in its index space;
 * *cont as vv_vray_clip_region's (0 outside region renders). */
static inline int
vray_setup_cont(const rt_vobj *ob, const vv_ray *wr, double tmin, double tmax, vv_vray *r,
                int *cont) {
    *cont = 0;
    if (!vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, wr, tmin, tmax, r))
        return 0;
    return !ob->region || vv_vray_clip_region(r, ob->region, ob->region_dt, ob->inv_form, cont);
}

/* vray_setup_cont without *cont. */
static inline int
vray_setup(const rt_vobj *ob, const vv_ray *wr, double tmin, double tmax, vv_vray *r) {
    int cont;
    return vray_setup_cont(ob, wr, tmin, tmax, r, &cont);
}

/* World point of index point q of volume ob. */
static inline vv_vec3
rt_index_to_world(const rt_vobj *ob, const double q[3]) {
    return v3(ob->i2w[0][0] * q[0] + ob->i2w[0][1] * q[1] + ob->i2w[0][2] * q[2] + ob->i2w[0][3],
              ob->i2w[1][0] * q[0] + ob->i2w[1][1] * q[1] + ob->i2w[1][2] * q[2] + ob->i2w[1][3],
              ob->i2w[2][0] * q[0] + ob->i2w[2][1] * q[1] + ob->i2w[2][2] * q[2] + ob->i2w[2][3]);
}

static inline float
lut_index_f(const rt_vobj *o, float v) {
    return vv_vtables_index(&o->tab, v);
}

/* World parameter where the ray leaves the subvolume containing p. */
static inline double
block_exit(const vv_vray *r, const float p[3], double t) {
    float te = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        float b = (float)(int)((p[a] > 0 ? p[a] : 0) * (1.0f / VV_VC_BLOCK));
        float bound = (r->d[a] > 0 ? b + 1 : b) * (float)VV_VC_BLOCK;
        float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    /* a rounding error must not stall the march */
    return t + (te > 1e-6f ? te : 1e-6f);
}

/* World parameter where the ray leaves the cube of 2 dist - 1 subvolumes
 * around the one containing p, all of which are empty (dist >= 1). */
static inline double
leap_exit(const rt_vobj *ob, const vv_vray *r, const float p[3], double t, int dist) {
    float te = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        const int nb = a == 0 ? ob->bx : a == 1 ? ob->by : ob->bz;
        int b = (int)((p[a] > 0 ? p[a] : 0) * (1.0f / VV_VC_BLOCK));
        b = b >= nb ? nb - 1 : b;
        float bound =
            r->d[a] > 0 ? (float)(b + dist) * VV_VC_BLOCK : (float)(b - dist + 1) * VV_VC_BLOCK;
        float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    return t + (te > 1e-6f ? te : 1e-6f);
}

/* Object <-> world transforms of points and directions (3 x 4 affine). */
static inline vv_vec3
xf_point(const double m[3][4], vv_vec3 p) {
    return v3(m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
              m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
              m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]);
}

static inline vv_vec3
xf_dir(const double m[3][4], vv_vec3 d) {
    return v3(m[0][0] * d.x + m[0][1] * d.y + m[0][2] * d.z,
              m[1][0] * d.x + m[1][1] * d.y + m[1][2] * d.z,
              m[2][0] * d.x + m[2][1] * d.y + m[2][2] * d.z);
}

/* Nearest hit of one geometric object in (tmin, tmax); its object-space
 * normal in *no (not normalised, not flipped towards the ray; gobj_normal
 * turns it into the world normal), or NULL when not needed. */
int rt_gobj_hit(const rt_gobj *g, const vv_ray *wr, double tmin, double tmax, double *t,
                vv_vec3 *no);

/* Nearest geometric hit among the objects a ray of this kind sees. */
int rt_nearest_hit(const rt_frame *fr, const vv_ray *wr, double tmin, double tmax, int primary,
                   rt_hit *h);

/* The shadow grid of directional light l for the volume's own samples
 * (shadow_grid=2): swept through every object that casts shadows into
 * ob->sweep[l], unless that holds one kept from an earlier frame; sets
 * ob->lidx[l]. */
vv_status rt_sweep_light(const rt_frame *fr, rt_vobj *ob, int l, int nt);

/* A shadow grid's key: its own part (placement, light), then the frame's
 * shadow-casting content (rt_cache.c); b NULL: none (nothing is kept). */
typedef struct rt_sgkey {
    unsigned char *b;
    size_t n;
} rt_sgkey;

/* The shadow grid of volume ob (a group leader) and light l, lazily
 * filled (swept 0) or swept (1), kept from an earlier frame of the same
 * shadow-casting content; NULL when there is none. Its key is left in
 * *key either way, for rt_sgrid_keep or rt_sgkey_free. */
void *rt_sgrid_find(rt_frame *fr, const rt_vobj *ob, int l, int swept, rt_sgkey *key);
/* Keeps @p grid (filled, or to be filled lazily, by this and later frames)
 * in the renderer state under *key (taken: emptied): 1 when kept (the
 * state owns it), 0 when not (a region render, no memory: the caller frees
 * it after the frame). */
int rt_sgrid_keep(rt_frame *fr, rt_sgkey *key, void *grid);
void rt_sgkey_free(rt_sgkey *key);
/* Empties a shadow-grid cache slot. */
void rt_sg_release(rt_sg *e);

/* Empties a light-volume cache slot: its volume reference and transmittances. */
void rt_lv_release(rt_lv *e);

/* The light volume of light l (directional or point) for volume ob:
 * transmittances towards the light every RT_LGRID voxels (ob->lvol[l]),
 * from the renderer state's cache when the volume, light and transfer
 * function match, else swept with nt threads and cached (least recently
 * used slot replaced). */
vv_status rt_build_light_volume(const rt_frame *fr, rt_vobj *ob, int l, int nt);

/* Region renders with the whole volume (vv_render_region.whole): 1 when
 * the context objects of the frame can take their light volumes from it
 * (composite, shadows through light volumes, every light directional or a
 * point at a finite position, shadow_grid 0 or 1: nothing else marches
 * the context's proxy), and then each such context takes the region
 * part's geometry (the whole volume's index space). */
int rt_context_whole(rt_frame *fr, const vv_render_region *region);

/* The light volume of light l for volume ob (rt_light.c): swept from the
 * light's side (directional) or in order of distance to it (point), from
 * the volume in memory, or for a region render's context tile by tile in
 * the light's order through its whole volume (ob->whole), the tiles read by
 * boxes, with the same values. *out: ob->ldim points, malloc'd; NULL when
 * there is nothing to sweep (then shadow rays march). Errors: those of the
 * reads, VV_ERR_NOMEM. */
vv_status rt_sweep_light_volume(const rt_frame *fr, const rt_vobj *ob, int l, int nt, float **out);

/* The swept shadow grid of directional light l for ob's samples
 * (shadow_grid=2, every RT_SGRID voxels, ob->gdim points): the same sweep
 * through every object that casts shadows (rt_shadow_segment). *out
 * malloc'd, NULL for a point light. Errors: VV_ERR_NOMEM. */
vv_status rt_sweep_shadow_grid(const rt_frame *fr, const rt_vobj *ob, int l, int nt, float **out);

/* Transmittance from world point p towards light l over [start, limit]
 * world units from p (limit INFINITY: up to the light), past every object
 * that casts shadows (rt_shade.c). */
float rt_shadow_segment(const rt_frame *fr, vv_vec3 p, const rt_light *l, double start,
                        double limit);

/* A composite volume's transmittance along ray r (index space of ob),
 * exp(-sum sigma h): each subvolume's piece cut into equal parts no longer
 * than the shadow step, sampled at their middles and classified by tab's
 * tables. From ob's own cache @p c (o NULL: it leaps over the subvolumes
 * that cannot contribute, by ob's PARC flags and distances) or from the
 * cache @p c of a box whose voxel (0, 0, 0) is index point o (every
 * subvolume). */
float rt_composite_march(const rt_frame *fr, const rt_vobj *ob, const vv_vray *r,
                         const vv_vcache *c, const float o[3], const rt_vobj *tab);

/* Volume ob's own transmittance from world point wp along ldir over (0,
 * tmax), marched through its samples (rt_shade.c). */
float rt_volume_march(const rt_frame *fr, const rt_vobj *ob, vv_vec3 wp, vv_vec3 ldir, double tmax);

/* The shadows rt_shade_volume gives a sample of object @p o (its lead) at
 * index point @p pi, world point @p pw: each light's transmittance into
 * sh[stride * l], l < n_lights; returns 0 (sh untouched) when the sample
 * receives none (shadows off, or the object does not receive them). */
int rt_volume_shadows(const rt_frame *fr, const rt_vobj *o, const float pi[3], const float pw[3],
                      rt_scache *sc, float *sh, int stride);

/* The ray caster's volume Phong (vv_vshade: reflection vector, two-sided,
 * specular weighted by the sample opacity), each light scaled by its
 * shadow. */
void rt_shade_volume(const rt_frame *fr, const rt_vobj *o, const float g[3], const float pi[3],
                     const float pw[3], const float v[3], const float col[3], float alpha,
                     rt_scache *sc, float out[3]);

/* Reflected and transmitted light at a surface point, added to out with
 * weights kr and kt. n: unit normal facing the incoming ray's origin side;
 * outward: the object's outward normal (solids refract). */
void rt_shade_secondary(const rt_frame *fr, const vv_ray *wr, vv_vec3 p, vv_vec3 n, vv_vec3 outward,
                        float kr, float kt, double ior, int solid, int depth, float weight,
                        float out[3]);

/* I_s of a geometric hit. */
void rt_shade_geometry(const rt_frame *fr, const vv_ray *wr, const rt_hit *h, int depth,
                       float weight, float out[3]);

/* I(x, w) = I_v + tau I_s along one ray: out is the colour, *alpha the
 * coverage (1 where a surface is hit), *tdepth the first visible hit. */
void rt_trace(const rt_frame *fr, const vv_ray *wr, int depth, int primary, float weight,
              float out[3], float *alpha, float *tdepth);
/* rt_trace, and *key (when not NULL) the value projected by the last
 * projection volume on the ray, NAN when none (region renders). */
void rt_trace_key(const rt_frame *fr, const vv_ray *wr, int depth, int primary, float weight,
                  float out[3], float *alpha, float *tdepth, float *key);

#endif
