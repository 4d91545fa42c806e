/*
 * What the files of the software rasterizer share (not installed): the
 * context, the per-draw and per-chunk records, the visibility buffer, and the
 * inline lighting and set-up helpers of the hot path. raster.c describes the
 * pipeline.
 */
#ifndef VOLVIS_RS_INTERNAL_H
#define VOLVIS_RS_INTERNAL_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "render/phong.h"
#include "volvis/raster.h"

#define RS_TILE 32 /* tile side, pixels */
#define RS_SUB 256 /* sub-pixel steps per pixel */
#define RS_MAX_PLANES (6 + 2 * VV_MAX_CUT_PLANES)
#define RS_MAX_POLY (3 + RS_MAX_PLANES + 1) /* each plane adds at most one vertex */
#define RS_NONE 0xffffffffu
#define RS_SWAPPED 8u       /* flags: vertices 1 and 2 were swapped (unclipped triangles) */
#define RS_BACK 0x80000000u /* visibility id and prim flag: the triangle is seen from behind */
#define RS_MAX_CAP (2 * VV_MAX_CUT_PLANES + 6)
#define RS_OC_BAD 0x80000000u /* outcode of a vertex with a NaN or infinite coordinate */
#define RS_OFF INT32_MIN      /* sxy marker of a vertex outside a clip plane */

typedef struct rs_light {
    int point;
    float dir[3]; /* towards the light (directional) */
    float pos[3]; /* point light position */
    float kd[3];  /* kd * colour * intensity */
    float ks[3];  /* ks * colour * intensity */
} rs_light;

/* One draw call: what shading needs after rasterization. Buffers are kept
 * with their capacity between frames. */
typedef struct rs_draw {
    const vv_mesh *mesh;
    uint32_t base;    /* visibility id of triangle 0 */
    const float *nrm; /* object-space vertex normals: the mesh's, or own_nrm */
    float *own_nrm;   /* 3 * n_vertices normals computed for a mesh without */
    float *vcol;      /* 3 * n_vertices Gouraud colours */
    size_t cap_nrm, cap_col;
    int cap; /* show cut faces where the surface is seen from behind */
    int n_cap;
    float capp[RS_MAX_CAP][4]; /* world half-spaces n.x + d >= 0 bounding the solid */
    float M[3][4];             /* object to world */
    float N[3][3];             /* normals: inverse transpose of M's linear part */
    vv_raster_shading shading;
    int lit;
    float base_col[3], amb[3];
    float shininess;
    int n_lights;
    rs_light lights[VV_MAX_LIGHTS];
    int persp;
    float eye[3], fwd[3];
} rs_draw;

/* A triangle ready to scan: snapped screen vertices (y down, 1/256 pixel),
 * depth keys, 1/w, the original triangle and how its barycentric
 * coordinates map to the original ones. */
typedef struct rs_stri {
    int32_t X[3], Y[3];
    float key[3], iw[3];
    uint32_t prim;  /* triangle index in the draw */
    uint32_t lam;   /* index of 9 floats in the chunk's lams (rows: screen vertices), or RS_NONE */
    uint32_t flags; /* bit i: edge v_i -> v_(i+1) is an original edge; RS_SWAPPED */
    int16_t px0, px1, py0, py1; /* pixel bounding box, clamped to the image */
} rs_stri;

/* A triangle that covers a single pixel centre, already interpolated there
 * (most triangles of a fine mesh): only the depth test is left. */
typedef struct rs_frag {
    uint32_t pixel; /* y * width + x */
    float key;
    uint32_t prim;
    float l1, l2;
} rs_frag;

#define RS_FRAG 0x80000000u /* entry flag: the index is a fragment's */

typedef struct rs_chunk {
    rs_stri *tris;
    size_t n_tris, cap_tris;
    rs_frag *frags;
    size_t n_frags, cap_frags;
    float *lams;
    size_t n_lams, cap_lams;
    uint32_t *ent; /* pairs (tile, triangle) */
    size_t n_ent, cap_ent;
    uint32_t *sorted; /* triangles by tile */
    size_t cap_sorted;
    uint32_t *off; /* n_tiles + 1 */
    int err;       /* 1: out of memory, 2: bad triangle index */
} rs_chunk;

typedef struct rs_pix {
    float key; /* greater is nearer */
    uint32_t id;
    float l1, l2; /* barycentric coordinates of the triangle's vertices 1 and 2 */
} rs_pix;

struct vv_raster {
    int w, h, threads;
    int tx, ty, n_tiles;
    float gb; /* guard band, in units of w */
    rs_pix *pix;
    /* camera */
    vv_mat4 view, proj, vp;
    int persp;
    vv_vec3 eye, fwd;
    /* state */
    vv_light lights[VV_MAX_LIGHTS];
    int n_lights;
    vv_vec3 ambient, background;
    vv_material mat;
    int lit, wireframe;
    vv_raster_shading shading;
    vv_raster_cull cull;
    int capping;
    int n_bounds;
    vv_plane bounds[6];
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    int n_planes;
    double oplanes[2 * VV_MAX_CUT_PLANES][4]; /* the cut planes in the object space of a draw */
    /* frame */
    rs_draw *draws;
    int n_draws, cap_draws;
    uint64_t next_base;
    size_t drawn;
    /* scratch of one draw */
    float *clip;  /* 4 * n_vertices */
    uint32_t *oc; /* outcodes */
    int32_t *sxy; /* 2 * n_vertices: 1/256-pixel screen position, X = RS_OFF if outcode */
    float *skw;   /* 2 * n_vertices: depth key and 1/w of the vertices with no outcode */
    size_t cap_scratch;
    rs_chunk *chunks;
    int n_chunks;
};

/* ---------------------------------------------------------------------- */
/* Lighting: the ray caster's model (raycast.c shade())                      */

static inline void
light_eval(const rs_draw *d, const float p[3], const float nin[3], float out[3]) {
    float dr = d->amb[0], dg = d->amb[1], db = d->amb[2];
    float sr = 0, sg = 0, sb = 0;
    const float len2 = nin[0] * nin[0] + nin[1] * nin[1] + nin[2] * nin[2];
    if (len2 > 1e-24f) {
        const float inv = 1.0f / sqrtf(len2);
        const float n0 = nin[0] * inv, n1 = nin[1] * inv, n2 = nin[2] * inv;
        float v0, v1, v2;
        if (d->persp) {
            v0 = d->eye[0] - p[0];
            v1 = d->eye[1] - p[1];
            v2 = d->eye[2] - p[2];
            const float vl = sqrtf(v0 * v0 + v1 * v1 + v2 * v2);
            const float iv = vl > 0 ? 1.0f / vl : 0.0f;
            v0 *= iv;
            v1 *= iv;
            v2 *= iv;
        } else {
            v0 = -d->fwd[0];
            v1 = -d->fwd[1];
            v2 = -d->fwd[2];
        }
        const float nv = n0 * v0 + n1 * v1 + n2 * v2;
        const float v[3] = {v0, v1, v2};
        for (int l = 0; l < d->n_lights; l++) {
            const rs_light *lt = &d->lights[l];
            float L[3], ndl;
            if (!vv_phong_light_dir(lt->point, lt->dir, lt->pos, p, L))
                continue;
            float rv = vv_phong_rv(n0 * L[0] + n1 * L[1] + n2 * L[2], nv, L, v, &ndl);
            rv = rv > 1 ? 1 : rv;
            const float sp = rv > 0 ? powf(rv, d->shininess) : 0;
            dr += ndl * lt->kd[0];
            dg += ndl * lt->kd[1];
            db += ndl * lt->kd[2];
            sr += sp * lt->ks[0];
            sg += sp * lt->ks[1];
            sb += sp * lt->ks[2];
        }
    }
    out[0] = dr * d->base_col[0] + sr;
    out[1] = dg * d->base_col[1] + sg;
    out[2] = db * d->base_col[2] + sb;
}

/* World position and (unnormalised) normal of an object-space point. */
static inline void
to_world(const rs_draw *d, const float p[3], const float n[3], float pw[3], float nw[3]) {
    for (int k = 0; k < 3; k++) {
        pw[k] = d->M[k][0] * p[0] + d->M[k][1] * p[1] + d->M[k][2] * p[2] + d->M[k][3];
        nw[k] = d->N[k][0] * n[0] + d->N[k][1] * n[1] + d->N[k][2] * n[2];
    }
}

/* ---------------------------------------------------------------------- */
/* Triangle set-up: records and inline helpers shared with the draw driver  */

typedef struct rs_cvert {
    double c[4]; /* clip coordinates */
    double p[3]; /* object-space position (cut planes) */
    float lam[3];
    int edge; /* the polygon edge from this vertex to the next is an original edge */
} rs_cvert;

/* What one draw's triangle stage needs. */
typedef struct rs_setup {
    const vv_raster *r;
    const rs_draw *d;
    const uint32_t *tri;
    size_t n_vertices;
    int cull_front; /* discard screen-counter-clockwise-in-world (front) triangles */
    int cull_back;
    int flip; /* the model matrix or view mirrors: screen winding is reversed */
    int wire;
} rs_setup;

static inline int
grow_buf(void **p, size_t *cap, size_t need, size_t elem) {
    if (need <= *cap)
        return 1;
    size_t nc = *cap ? *cap : 256;
    while (nc < need)
        nc *= 2;
    void *q = realloc(*p, nc * elem);
    if (!q)
        return 0;
    *p = q;
    *cap = nc;
    return 1;
}

static inline int
top_left(int64_t dx, int64_t dy) {
    return dy < 0 || (dy == 0 && dx > 0);
}

/* Writes a fragment of @p t with screen barycentric coordinates b0..b2: the
 * perspective-correct barycentric coordinates of the original triangle's
 * vertices 1 and 2. L: 3 x 3 rows mapping t's vertices to the original
 * triangle's, or NULL (t is the original, vertices 1 and 2 swapped when
 * RS_SWAPPED). */
static inline void
store_fragment(rs_pix *px, const rs_stri *t, const float *L, float key, float b0, float b1,
               float b2, uint32_t id) {
    const float q0 = b0 * t->iw[0], q1 = b1 * t->iw[1], q2 = b2 * t->iw[2];
    const float inv = 1.0f / (q0 + q1 + q2);
    float l1, l2;
    if (!L) {
        if (t->flags & RS_SWAPPED) {
            l1 = q2 * inv;
            l2 = q1 * inv;
        } else {
            l1 = q1 * inv;
            l2 = q2 * inv;
        }
    } else {
        l1 = (q0 * L[1] + q1 * L[4] + q2 * L[7]) * inv;
        l2 = (q0 * L[2] + q1 * L[5] + q2 * L[8]) * inv;
    }
    px->key = key;
    px->id = id;
    px->l1 = l1;
    px->l2 = l2;
}

/* A vertex on screen: 1/256-pixel position (y down), depth key, 1/w. */
typedef struct rs_svert {
    int32_t X, Y;
    float key, iw;
} rs_svert;

/* Rounds half away from zero (no libm call, same result everywhere). */
static inline int32_t
snap(double v) {
    v *= RS_SUB;
    return (int32_t)(v >= 0 ? v + 0.5 : v - 0.5);
}

/* Screen position of a clip-space vertex inside the guard band. */
static inline void
project(const vv_raster *r, const double c[4], rs_svert *o) {
    const double iw = r->persp ? 1.0 / c[3] : 1.0;
    o->X = snap((c[0] * iw + 1.0) * (0.5 * r->w));
    o->Y = snap((1.0 - c[1] * iw) * (0.5 * r->h));
    o->key = (float)(r->persp ? iw : -c[2]);
    o->iw = (float)iw;
}

/* Triangles [t0, t1) of the draw into chunk @p ch, then its entries sorted by tile. */
void rs_setup_chunk(const rs_setup *s, rs_chunk *ch, size_t t0, size_t t1);

/* Fills the part of triangle @p t inside the tile rectangle. */
void rs_scan_fill(vv_raster *r, const rs_stri *t, const float *lams, uint32_t id, int x0, int x1,
                  int y0, int y1);

/* Draws the original edges of @p t, one pixel wide: pixels whose centre is
 * within half a pixel of an edge segment. */
void rs_scan_wire(vv_raster *r, const rs_stri *t, const float *lams, uint32_t id, int x0, int x1,
                  int y0, int y1);

/* Worker threads for a stage: the context's setting, else the library's (vv_threads_get). */
int rs_thread_count(const vv_raster *r);

#endif
