/*
 * The software rasterizer behind include/volvis/raster.h: the VolVis
 * paper's portable library of basic graphics functions (section 5).
 *
 * A draw runs three parallel stages:
 *  1. vertices: object -> world (positions, normals by the inverse
 *     transpose) -> clip space, an outcode per vertex (which clip planes it
 *     violates), and Gouraud colours when asked for;
 *  2. triangles, in contiguous chunks: trivially rejected by their
 *     outcodes, else clipped (Sutherland-Hodgman in homogeneous clip space
 *     for the frustum planes, in world space for cut planes; new vertices
 *     carry barycentric coordinates of the original triangle), culled by the
 *     sign of their snapped screen area, and binned into tiles; each chunk
 *     sorts its (tile, triangle) entries by tile;
 *  3. tiles, in parallel: every chunk's triangles for the tile, in chunk
 *     order (= draw order), are scanned with integer edge functions at pixel
 *     centres (1/256 pixel vertices, top-left rule) and depth-tested with a
 *     screen-affine key; a pixel that passes keeps the triangle and its
 *     perspective-correct barycentric coordinates (a visibility buffer).
 * vv_raster_finish shades each visible pixel once (deferred shading).
 *
 * Order-dependence (the earlier of two equal depths wins) is resolved by
 * draw order, which neither chunking nor tiling changes, so the image does
 * not depend on the thread count.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

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
/* Context and state                                                        */

vv_status
vv_raster_new(vv_raster **out, int width, int height) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "raster: NULL output");
    *out = NULL;
    if (width < 1 || height < 1 || width > VV_IMAGE_MAX_SIDE || height > VV_IMAGE_MAX_SIDE)
        return vv_error_set(VV_ERR_INVALID, "raster: image size %d x %d is not in 1..%d", width,
                            height, VV_IMAGE_MAX_SIDE);
    vv_raster *r = calloc(1, sizeof *r);
    if (!r)
        return vv_error_set(VV_ERR_NOMEM, "raster: out of memory");
    r->w = width;
    r->h = height;
    r->tx = (width + RS_TILE - 1) / RS_TILE;
    r->ty = (height + RS_TILE - 1) / RS_TILE;
    r->n_tiles = r->tx * r->ty;
    int side = width > height ? width : height;
    /* screen coordinates stay within about +-8192 + side pixels, so edge
     * functions of 1/256-pixel coordinates fit easily in 64 bits */
    r->gb = side < 16384 ? (float)(16384 / side) : 1.0f;
    r->pix = malloc((size_t)width * (size_t)height * sizeof *r->pix);
    if (!r->pix) {
        free(r);
        return vv_error_set(VV_ERR_NOMEM, "raster: out of memory for %d x %d pixels", width,
                            height);
    }
    r->view = vv_mat4_identity();
    r->proj = vv_mat4_identity();
    r->vp = vv_mat4_identity();
    r->fwd = vv_vec3_make(0, 0, -1);
    r->ambient = vv_vec3_make(1, 1, 1);
    r->mat.ambient = 0.1;
    r->mat.diffuse = 0.6;
    r->mat.specular = 0.3;
    r->mat.shininess = 30;
    r->mat.color = vv_vec3_make(1, 1, 1);
    r->mat.ior = 1;
    r->lit = 1;
    r->shading = VV_RASTER_PHONG;
    vv_raster_begin(r, vv_vec3_make(0, 0, 0));
    *out = r;
    return VV_OK;
}

static void
chunk_release(rs_chunk *c) {
    free(c->tris);
    free(c->frags);
    free(c->lams);
    free(c->ent);
    free(c->sorted);
    free(c->off);
}

void
vv_raster_free(vv_raster *r) {
    if (!r)
        return;
    for (int i = 0; i < r->cap_draws; i++) {
        free(r->draws[i].own_nrm);
        free(r->draws[i].vcol);
    }
    free(r->draws);
    for (int i = 0; i < r->n_chunks; i++)
        chunk_release(&r->chunks[i]);
    free(r->chunks);
    free(r->clip);
    free(r->oc);
    free(r->sxy);
    free(r->skw);
    free(r->pix);
    free(r);
}

void
vv_raster_set_threads(vv_raster *r, int n) {
    r->threads = n;
}

void
vv_raster_begin(vv_raster *r, vv_vec3 background) {
    const size_t n = (size_t)r->w * (size_t)r->h;
    const int nt = r->threads > 0 ? r->threads : vv_threads_get();
#pragma omp parallel for schedule(static) num_threads(nt)
    for (size_t i = 0; i < n; i++) {
        r->pix[i].key = -INFINITY;
        r->pix[i].id = RS_NONE;
        r->pix[i].l1 = r->pix[i].l2 = 0;
    }
    r->background = background;
    r->n_draws = 0;
    r->next_base = 0;
    r->drawn = 0;
}

vv_status
vv_raster_set_camera(vv_raster *r, vv_mat4 view, vv_mat4 projection) {
    const double *b = projection.m[3];
    int persp;
    if (b[0] == 0 && b[1] == 0 && b[2] == -1 && b[3] == 0) {
        persp = 1;
        /* near distance n from z_clip = a z + c, w = -z: z + w >= 0 <=> -z >= c / (a - 1) */
        double a = projection.m[2][2], c = projection.m[2][3];
        if (!(a - 1 != 0 && c / (a - 1) > 0))
            return vv_error_set(VV_ERR_INVALID,
                                "raster: perspective projection without a near plane in front "
                                "of the eye");
    } else if (b[0] == 0 && b[1] == 0 && b[2] == 0 && b[3] == 1) {
        persp = 0;
    } else {
        return vv_error_set(VV_ERR_INVALID,
                            "raster: projection bottom row must be (0, 0, -1, 0) or (0, 0, 0, 1)");
    }
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(view, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "raster: singular view matrix");
    r->view = view;
    r->proj = projection;
    r->vp = vv_mat4_mul(projection, view);
    r->persp = persp;
    r->eye = vv_mat4_mul_point(inv, vv_vec3_make(0, 0, 0));
    r->fwd = vv_vec3_normalize(vv_mat4_mul_dir(inv, vv_vec3_make(0, 0, -1)));
    return VV_OK;
}

vv_status
vv_raster_set_view(vv_raster *r, const vv_view *view, double znear, double zfar) {
    if (!view)
        return vv_error_set(VV_ERR_INVALID, "raster: NULL view");
    const int persp = view->projection != VV_PROJECTION_ORTHOGRAPHIC;
    if (persp ? !(znear > 0 && zfar > znear) : !(znear >= 0 && zfar > znear && isfinite(zfar)))
        return vv_error_set(VV_ERR_INVALID, "raster: bad clip distances near %g far %g", znear,
                            zfar);
    /* the basis of vv_view_ray (src/model/view.c), degenerate fallbacks included */
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    if (!(vv_vec3_length(f) > 0.5))
        f = vv_vec3_make(0, 1, 0);
    vv_vec3 rt = vv_vec3_normalize(vv_vec3_cross(f, view->up));
    if (!(vv_vec3_length(rt) > 0.5)) {
        vv_vec3 alt = fabs(f.z) < 0.9 ? vv_vec3_make(0, 0, 1) : vv_vec3_make(1, 0, 0);
        rt = vv_vec3_normalize(vv_vec3_cross(f, alt));
    }
    vv_vec3 u = vv_vec3_cross(rt, f);
    vv_mat4 V = vv_mat4_identity();
    const vv_vec3 rows[3] = {rt, u, vv_vec3_scale(f, -1)};
    for (int i = 0; i < 3; i++) {
        V.m[i][0] = rows[i].x;
        V.m[i][1] = rows[i].y;
        V.m[i][2] = rows[i].z;
        V.m[i][3] = -vv_vec3_dot(rows[i], view->eye);
    }
    const int w = view->width > 0 ? view->width : 1, h = view->height > 0 ? view->height : 1;
    const double aspect = (double)w / (double)h;
    vv_mat4 P = {{{0}}};
    if (persp) {
        const double t = tan(0.5 * view->fov);
        if (!(t > 0 && isfinite(t)))
            return vv_error_set(VV_ERR_INVALID, "raster: field of view %g rad is not in (0, pi)",
                                view->fov);
        P.m[0][0] = 1.0 / (t * aspect);
        P.m[1][1] = 1.0 / t;
        if (isinf(zfar)) {
            P.m[2][2] = -1;
            P.m[2][3] = -2 * znear;
        } else {
            P.m[2][2] = (zfar + znear) / (znear - zfar);
            P.m[2][3] = 2 * zfar * znear / (znear - zfar);
        }
        P.m[3][2] = -1;
    } else {
        const double hh = 0.5 * view->ortho_height;
        if (!(hh > 0 && isfinite(hh)))
            return vv_error_set(VV_ERR_INVALID, "raster: ortho_height %g is not > 0",
                                view->ortho_height);
        P = vv_mat4_orthographic(-hh * aspect, hh * aspect, -hh, hh, znear, zfar);
    }
    return vv_raster_set_camera(r, V, P);
}

vv_status
vv_raster_set_lights(vv_raster *r, const vv_light *lights, int n, vv_vec3 ambient) {
    if (n < 0 || (n > 0 && !lights))
        return vv_error_set(VV_ERR_INVALID, "raster: bad light list (%d lights)", n);
    if (n > VV_MAX_LIGHTS)
        return vv_error_set(VV_ERR_LIMIT, "raster: %d lights; at most %d", n, VV_MAX_LIGHTS);
    if (n)
        memcpy(r->lights, lights, (size_t)n * sizeof *lights);
    r->n_lights = n;
    r->ambient = ambient;
    return VV_OK;
}

void
vv_raster_set_material(vv_raster *r, const vv_material *m, int lit) {
    if (m)
        r->mat = *m;
    r->lit = lit != 0;
}

void
vv_raster_set_shading(vv_raster *r, vv_raster_shading s) {
    r->shading = s;
}

void
vv_raster_set_cull(vv_raster *r, vv_raster_cull c) {
    r->cull = c;
}

void
vv_raster_set_wireframe(vv_raster *r, int on) {
    r->wireframe = on != 0;
}

vv_status
vv_raster_set_cut_planes(vv_raster *r, const vv_cut_plane *planes, int n) {
    if (n < 0 || (n > 0 && !planes))
        return vv_error_set(VV_ERR_INVALID, "raster: bad cut plane list (%d planes)", n);
    if (n > 2 * VV_MAX_CUT_PLANES)
        return vv_error_set(VV_ERR_LIMIT, "raster: %d cut planes; at most %d", n,
                            2 * VV_MAX_CUT_PLANES);
    for (int i = 0; i < n; i++)
        if (!(vv_vec3_length(planes[i].normal) > 0))
            return vv_error_set(VV_ERR_INVALID, "raster: cut plane %d has a zero normal", i);
    for (int i = 0; i < n; i++)
        r->planes[i] = vv_plane_from_point_normal(planes[i].point, planes[i].normal);
    r->n_planes = n;
    return VV_OK;
}

vv_status
vv_raster_set_capping(vv_raster *r, int on, const vv_cut_plane *bounds, int n_bounds) {
    if (n_bounds < 0 || n_bounds > 6 || (n_bounds > 0 && !bounds))
        return vv_error_set(VV_ERR_INVALID, "raster: %d bounding planes (0..6)", n_bounds);
    for (int i = 0; i < n_bounds; i++)
        if (!(vv_vec3_length(bounds[i].normal) > 0))
            return vv_error_set(VV_ERR_INVALID, "raster: bounding plane %d has a zero normal", i);
    for (int i = 0; i < n_bounds; i++)
        r->bounds[i] = vv_plane_from_point_normal(bounds[i].point, bounds[i].normal);
    r->n_bounds = n_bounds;
    r->capping = on != 0;
    return VV_OK;
}

size_t
vv_raster_triangles_drawn(const vv_raster *r) {
    return r->drawn;
}

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
        for (int l = 0; l < d->n_lights; l++) {
            const rs_light *lt = &d->lights[l];
            float L0 = lt->dir[0], L1 = lt->dir[1], L2 = lt->dir[2];
            if (lt->point) {
                L0 = lt->pos[0] - p[0];
                L1 = lt->pos[1] - p[1];
                L2 = lt->pos[2] - p[2];
                const float ll = sqrtf(L0 * L0 + L1 * L1 + L2 * L2);
                if (!(ll > 0))
                    continue;
                L0 /= ll;
                L1 /= ll;
                L2 /= ll;
            }
            float ndl = n0 * L0 + n1 * L1 + n2 * L2;
            /* two-sided: a normal facing away from the light is flipped */
            const float ndv = ndl < 0 ? -nv : nv;
            ndl = fabsf(ndl);
            float rv = 2 * ndl * ndv - (L0 * v0 + L1 * v1 + L2 * v2);
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

static void
prepare_draw_shading(const vv_raster *r, rs_draw *d) {
    const vv_material *m = &r->mat;
    d->shading = r->shading;
    d->lit = r->lit;
    d->base_col[0] = (float)m->color.x;
    d->base_col[1] = (float)m->color.y;
    d->base_col[2] = (float)m->color.z;
    d->amb[0] = (float)(m->ambient * r->ambient.x);
    d->amb[1] = (float)(m->ambient * r->ambient.y);
    d->amb[2] = (float)(m->ambient * r->ambient.z);
    d->shininess = (float)m->shininess;
    d->persp = r->persp;
    d->eye[0] = (float)r->eye.x;
    d->eye[1] = (float)r->eye.y;
    d->eye[2] = (float)r->eye.z;
    d->fwd[0] = (float)r->fwd.x;
    d->fwd[1] = (float)r->fwd.y;
    d->fwd[2] = (float)r->fwd.z;
    d->n_lights = 0;
    for (int i = 0; i < r->n_lights; i++) {
        const vv_light *l = &r->lights[i];
        rs_light *o = &d->lights[d->n_lights++];
        o->point = l->type == VV_LIGHT_POINT && !l->headlight;
        vv_vec3 dir = l->headlight ? r->fwd : vv_vec3_normalize(l->direction);
        o->dir[0] = (float)-dir.x;
        o->dir[1] = (float)-dir.y;
        o->dir[2] = (float)-dir.z;
        o->pos[0] = (float)l->position.x;
        o->pos[1] = (float)l->position.y;
        o->pos[2] = (float)l->position.z;
        const double c[3] = {l->color.x * l->intensity, l->color.y * l->intensity,
                             l->color.z * l->intensity};
        for (int k = 0; k < 3; k++) {
            o->kd[k] = (float)(m->diffuse * c[k]);
            o->ks[k] = (float)(m->specular * c[k]);
        }
    }
}

/* ---------------------------------------------------------------------- */
/* Triangle set-up and binning                                              */

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

/* Culls and bins one screen triangle. lam (may be NULL: the identity) gives
 * each vertex's barycentric coordinates in the original triangle; edges:
 * bit i for the edge v_i -> v_(i+1). */
static void
emit_triangle(const rs_setup *s, rs_chunk *ch, const rs_svert *v0, const rs_svert *v1,
              const rs_svert *v2, float lam[3][3], uint32_t prim, uint32_t edges) {
    const vv_raster *r = s->r;
    /* pixels whose centres (p + 1/2) lie in the bounding box (arithmetic
     * shifts floor); most triangles of a fine mesh have none */
    int32_t minx = v0->X < v1->X ? v0->X : v1->X, maxx = v0->X > v1->X ? v0->X : v1->X;
    int32_t miny = v0->Y < v1->Y ? v0->Y : v1->Y, maxy = v0->Y > v1->Y ? v0->Y : v1->Y;
    minx = v2->X < minx ? v2->X : minx;
    maxx = v2->X > maxx ? v2->X : maxx;
    miny = v2->Y < miny ? v2->Y : miny;
    maxy = v2->Y > maxy ? v2->Y : maxy;
    int px0 = (minx - RS_SUB / 2 + RS_SUB - 1) >> 8, px1 = (maxx - RS_SUB / 2) >> 8;
    int py0 = (miny - RS_SUB / 2 + RS_SUB - 1) >> 8, py1 = (maxy - RS_SUB / 2) >> 8;
    if (s->wire) {
        px0--;
        py0--;
        px1++;
        py1++;
    }
    px0 = px0 < 0 ? 0 : px0;
    py0 = py0 < 0 ? 0 : py0;
    px1 = px1 > r->w - 1 ? r->w - 1 : px1;
    py1 = py1 > r->h - 1 ? r->h - 1 : py1;
    if (px0 > px1 || py0 > py1)
        return;
    const int64_t A = ((int64_t)v1->X - v0->X) * ((int64_t)v2->Y - v0->Y) -
                      ((int64_t)v1->Y - v0->Y) * ((int64_t)v2->X - v0->X);
    if (A == 0)
        return;
    /* y points down on screen: a triangle counter-clockwise in the image
     * (front facing) has a negative area here */
    const int front = A < 0;
    if ((front && s->cull_front) || (!front && s->cull_back))
        return;
    const uint32_t back = front == s->flip ? RS_BACK : 0;
    prim |= back;
    rs_stri t;
    const rs_svert *v[3] = {v0, v1, v2};
    int order[3] = {0, 1, 2};
    t.flags = edges;
    if (A < 0) {
        order[1] = 2;
        order[2] = 1;
        /* edges v0->v1, v1->v2, v2->v0 become v0->v2 (old bit 2), v2->v1 (1), v1->v0 (0) */
        t.flags = ((edges & 1u) << 2) | (edges & 2u) | ((edges >> 2) & 1u);
        if (!lam)
            t.flags |= RS_SWAPPED;
    }
    for (int i = 0; i < 3; i++) {
        const rs_svert *q = v[order[i]];
        t.X[i] = q->X;
        t.Y[i] = q->Y;
        t.key[i] = q->key;
        t.iw[i] = q->iw;
    }
    t.px0 = (int16_t)px0;
    t.px1 = (int16_t)px1;
    t.py0 = (int16_t)py0;
    t.py1 = (int16_t)py1;
    t.prim = prim;
    t.lam = RS_NONE;
    if (!s->wire && px0 == px1 && py0 == py1) {
        /* one candidate pixel centre: test and interpolate it now */
        const int64_t Px = (int64_t)px0 * RS_SUB + RS_SUB / 2,
                      Py = (int64_t)py0 * RS_SUB + RS_SUB / 2;
        int64_t E[3];
        for (int e = 0; e < 3; e++) {
            const int a = (e + 1) % 3, b = (e + 2) % 3;
            const int64_t dx = (int64_t)t.X[b] - t.X[a], dy = (int64_t)t.Y[b] - t.Y[a];
            E[e] = -dy * (Px - t.X[a]) + dx * (Py - t.Y[a]);
            if (E[e] < 0 || (E[e] == 0 && !top_left(dx, dy)))
                return;
        }
        const float invA = 1.0f / (float)(A < 0 ? -A : A);
        const float b0 = (float)E[0] * invA, b1 = (float)E[1] * invA, b2 = (float)E[2] * invA;
        float L[9];
        if (lam)
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++)
                    L[3 * i + k] = lam[order[i]][k];
        rs_pix f;
        store_fragment(&f, &t, lam ? L : NULL, b0 * t.key[0] + b1 * t.key[1] + b2 * t.key[2], b0,
                       b1, b2, prim);
        if (!grow_buf((void **)&ch->frags, &ch->cap_frags, ch->n_frags + 1, sizeof *ch->frags) ||
            !grow_buf((void **)&ch->ent, &ch->cap_ent, 2 * (ch->n_ent + 1), sizeof(uint32_t))) {
            ch->err = 1;
            return;
        }
        rs_frag *fr = &ch->frags[ch->n_frags];
        fr->pixel = (uint32_t)py0 * (uint32_t)r->w + (uint32_t)px0;
        fr->key = f.key;
        fr->prim = prim;
        fr->l1 = f.l1;
        fr->l2 = f.l2;
        ch->ent[2 * ch->n_ent] = (uint32_t)((py0 / RS_TILE) * r->tx + px0 / RS_TILE);
        ch->ent[2 * ch->n_ent + 1] = (uint32_t)ch->n_frags | RS_FRAG;
        ch->n_ent++;
        ch->n_frags++;
        return;
    }
    if (lam) {
        if (!grow_buf((void **)&ch->lams, &ch->cap_lams, ch->n_lams + 9, sizeof(float))) {
            ch->err = 1;
            return;
        }
        t.lam = (uint32_t)(ch->n_lams / 9);
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                ch->lams[ch->n_lams + 3 * (size_t)i + (size_t)k] = lam[order[i]][k];
        ch->n_lams += 9;
    }
    const int tx0 = px0 / RS_TILE, tx1 = px1 / RS_TILE;
    const int ty0 = py0 / RS_TILE, ty1 = py1 / RS_TILE;
    const size_t nent = (size_t)(tx1 - tx0 + 1) * (size_t)(ty1 - ty0 + 1);
    if (!grow_buf((void **)&ch->tris, &ch->cap_tris, ch->n_tris + 1, sizeof *ch->tris) ||
        !grow_buf((void **)&ch->ent, &ch->cap_ent, 2 * (ch->n_ent + nent), sizeof(uint32_t))) {
        ch->err = 1;
        return;
    }
    const uint32_t idx = (uint32_t)ch->n_tris;
    ch->tris[ch->n_tris++] = t;
    for (int ty = ty0; ty <= ty1; ty++)
        for (int tx = tx0; tx <= tx1; tx++) {
            ch->ent[2 * ch->n_ent] = (uint32_t)(ty * r->tx + tx);
            ch->ent[2 * ch->n_ent + 1] = idx;
            ch->n_ent++;
        }
}

/* Signed distance of a polygon vertex to clip plane k (>= 0: kept). */
static inline double
plane_dist(const vv_raster *r, int k, const rs_cvert *v) {
    const double *c = v->c;
    const double g = r->gb;
    switch (k) {
    case 0:
        return c[2] + c[3]; /* near */
    case 1:
        return c[3] - c[2]; /* far */
    case 2:
        return g * c[3] - c[0];
    case 3:
        return g * c[3] + c[0];
    case 4:
        return g * c[3] - c[1];
    case 5:
        return g * c[3] + c[1];
    default: {
        const double *pl = r->oplanes[k - 6];
        return pl[0] * v->p[0] + pl[1] * v->p[1] + pl[2] * v->p[2] + pl[3];
    }
    }
}

/* Clips the triangle against the planes in @p mask and emits the fan. */
static void
clip_triangle(const rs_setup *s, rs_chunk *ch, const uint32_t vi[3], uint32_t prim, uint32_t mask) {
    const vv_raster *r = s->r;
    rs_cvert buf[2][RS_MAX_POLY];
    rs_cvert *in = buf[0], *out = buf[1];
    int n = 3;
    for (int i = 0; i < 3; i++) {
        const float *cc = r->clip + 4 * (size_t)vi[i];
        const float *p = s->d->mesh->positions + 3 * (size_t)vi[i];
        for (int k = 0; k < 4; k++)
            in[i].c[k] = cc[k];
        for (int k = 0; k < 3; k++) {
            in[i].p[k] = p[k];
            in[i].lam[k] = k == i ? 1.0f : 0.0f;
        }
        in[i].edge = 1;
    }
    for (int k = 0; k < 6 + r->n_planes && n >= 3; k++) {
        if (!(mask & (1u << k)))
            continue;
        double dist[RS_MAX_POLY];
        for (int i = 0; i < n; i++)
            dist[i] = plane_dist(r, k, &in[i]);
        int m = 0;
        for (int i = 0; i < n; i++) {
            const rs_cvert *a = &in[i], *b = &in[(i + 1) % n];
            const double da = dist[i], db = dist[(i + 1) % n];
            const int ain = da >= 0, bin = db >= 0;
            if (ain)
                out[m++] = *a;
            if (ain != bin) {
                const double t = da / (da - db);
                rs_cvert *v = &out[m++];
                for (int q = 0; q < 4; q++)
                    v->c[q] = a->c[q] + t * (b->c[q] - a->c[q]);
                for (int q = 0; q < 3; q++) {
                    v->p[q] = a->p[q] + t * (b->p[q] - a->p[q]);
                    v->lam[q] = (float)(a->lam[q] + t * (b->lam[q] - a->lam[q]));
                }
                /* entering: I -> b is part of a -> b; leaving: I runs along the plane */
                v->edge = ain ? 0 : a->edge;
            }
        }
        rs_cvert *tmp = in;
        in = out;
        out = tmp;
        n = m;
    }
    rs_svert sv[RS_MAX_POLY];
    for (int i = 0; i < n; i++)
        project(r, in[i].c, &sv[i]);
    for (int i = 1; i + 1 < n; i++) {
        float lam[3][3];
        const rs_cvert *v[3] = {&in[0], &in[i], &in[i + 1]};
        for (int j = 0; j < 3; j++)
            memcpy(lam[j], v[j]->lam, sizeof lam[j]);
        uint32_t edges = (uint32_t)in[i].edge << 1;
        if (i == 1)
            edges |= (uint32_t)in[0].edge;
        if (i + 2 == n)
            edges |= (uint32_t)in[n - 1].edge << 2;
        emit_triangle(s, ch, &sv[0], &sv[i], &sv[i + 1], lam, prim, edges);
    }
}

/* Triangles [t0, t1) of the draw into chunk @p ch, then its entries sorted by tile. */
static void
setup_chunk(const rs_setup *s, rs_chunk *ch, size_t t0, size_t t1) {
    const vv_raster *r = s->r;
    ch->n_tris = ch->n_frags = ch->n_lams = ch->n_ent = 0;
    ch->err = 0;
    for (size_t t = t0; t < t1 && !ch->err; t++) {
        const uint32_t vi[3] = {s->tri[3 * t], s->tri[3 * t + 1], s->tri[3 * t + 2]};
        if (vi[0] >= s->n_vertices || vi[1] >= s->n_vertices || vi[2] >= s->n_vertices) {
            ch->err = 2;
            return;
        }
        const int32_t *A = r->sxy + 2 * (size_t)vi[0], *B = r->sxy + 2 * (size_t)vi[1],
                      *C = r->sxy + 2 * (size_t)vi[2];
        if (A[0] == RS_OFF || B[0] == RS_OFF || C[0] == RS_OFF) {
            const uint32_t o0 = r->oc[vi[0]], o1 = r->oc[vi[1]], o2 = r->oc[vi[2]];
            const uint32_t any = o0 | o1 | o2;
            if ((o0 & o1 & o2) || (any & RS_OC_BAD))
                continue; /* outside one plane, or a vertex that is not a finite point */
            clip_triangle(s, ch, vi, (uint32_t)t, any);
            continue;
        }
        if (!s->wire) {
            /* the common case of a fine mesh, without a call: no pixel
             * centre between the extreme x (or y) of the vertices */
            int32_t lo = A[0] < B[0] ? A[0] : B[0], hi = A[0] > B[0] ? A[0] : B[0];
            lo = C[0] < lo ? C[0] : lo;
            hi = C[0] > hi ? C[0] : hi;
            if (((lo - RS_SUB / 2 + RS_SUB - 1) >> 8) > ((hi - RS_SUB / 2) >> 8))
                continue;
            lo = A[1] < B[1] ? A[1] : B[1];
            hi = A[1] > B[1] ? A[1] : B[1];
            lo = C[1] < lo ? C[1] : lo;
            hi = C[1] > hi ? C[1] : hi;
            if (((lo - RS_SUB / 2 + RS_SUB - 1) >> 8) > ((hi - RS_SUB / 2) >> 8))
                continue;
        }
        rs_svert v[3];
        for (int k = 0; k < 3; k++) {
            const size_t q = 2 * (size_t)vi[k];
            v[k].X = r->sxy[q];
            v[k].Y = r->sxy[q + 1];
            v[k].key = r->skw[q];
            v[k].iw = r->skw[q + 1];
        }
        emit_triangle(s, ch, &v[0], &v[1], &v[2], NULL, (uint32_t)t, 7u);
    }
    if (ch->err)
        return;
    /* counting sort of the entries by tile (stable: draw order within a tile) */
    const int nt = r->n_tiles;
    if (!grow_buf((void **)&ch->sorted, &ch->cap_sorted, ch->n_ent + 1, sizeof(uint32_t))) {
        ch->err = 1;
        return;
    }
    memset(ch->off, 0, ((size_t)nt + 1) * sizeof *ch->off);
    for (size_t e = 0; e < ch->n_ent; e++)
        ch->off[ch->ent[2 * e] + 1]++;
    for (int i = 0; i < nt; i++)
        ch->off[i + 1] += ch->off[i];
    for (size_t e = 0; e < ch->n_ent; e++)
        ch->sorted[ch->off[ch->ent[2 * e]]++] = ch->ent[2 * e + 1];
    /* off[i] now ends tile i; shift back so that tile i is [off[i], off[i + 1]) */
    for (int i = nt; i > 0; i--)
        ch->off[i] = ch->off[i - 1];
    ch->off[0] = 0;
}

/* ---------------------------------------------------------------------- */
/* Scanning                                                                 */

/* Fills the part of triangle @p t inside the tile rectangle. */
static void
scan_fill(vv_raster *r, const rs_stri *t, const float *lams, uint32_t id, int x0, int x1, int y0,
          int y1) {
    const float *L = t->lam == RS_NONE ? NULL : lams + 9 * (size_t)t->lam;
    int64_t ax[3], ay[3], bias[3];
    for (int e = 0; e < 3; e++) {
        /* edge opposite vertex e: from v_(e+1) to v_(e+2) */
        const int a = (e + 1) % 3, b = (e + 2) % 3;
        const int64_t dx = (int64_t)t->X[b] - t->X[a], dy = (int64_t)t->Y[b] - t->Y[a];
        ax[e] = -dy;
        ay[e] = dx;
        bias[e] = top_left(dx, dy) ? 0 : -1;
    }
    const int64_t A = ((int64_t)t->X[1] - t->X[0]) * ((int64_t)t->Y[2] - t->Y[0]) -
                      ((int64_t)t->Y[1] - t->Y[0]) * ((int64_t)t->X[2] - t->X[0]);
    const float invA = 1.0f / (float)A;
    const int64_t Px = (int64_t)x0 * RS_SUB + RS_SUB / 2, Py = (int64_t)y0 * RS_SUB + RS_SUB / 2;
    int64_t row[3];
    for (int e = 0; e < 3; e++) {
        const int a = (e + 1) % 3;
        row[e] = ax[e] * (Px - t->X[a]) + ay[e] * (Py - t->Y[a]) + bias[e];
    }
    for (int y = y0; y <= y1; y++) {
        int64_t E0 = row[0], E1 = row[1], E2 = row[2];
        rs_pix *px = r->pix + (size_t)y * (size_t)r->w + (size_t)x0;
        for (int x = x0; x <= x1; x++, px++) {
            if ((E0 | E1 | E2) >= 0) {
                const float b0 = (float)(E0 - bias[0]) * invA, b1 = (float)(E1 - bias[1]) * invA;
                const float b2 = (float)(E2 - bias[2]) * invA;
                const float key = b0 * t->key[0] + b1 * t->key[1] + b2 * t->key[2];
                if (key > px->key)
                    store_fragment(px, t, L, key, b0, b1, b2, id);
            }
            E0 += ax[0] * RS_SUB;
            E1 += ax[1] * RS_SUB;
            E2 += ax[2] * RS_SUB;
        }
        row[0] += ay[0] * RS_SUB;
        row[1] += ay[1] * RS_SUB;
        row[2] += ay[2] * RS_SUB;
    }
}

/* Draws the original edges of @p t, one pixel wide: pixels whose centre is
 * within half a pixel of an edge segment. */
static void
scan_wire(vv_raster *r, const rs_stri *t, const float *lams, uint32_t id, int x0, int x1, int y0,
          int y1) {
    const float *L = t->lam == RS_NONE ? NULL : lams + 9 * (size_t)t->lam;
    const double A = ((double)t->X[1] - t->X[0]) * ((double)t->Y[2] - t->Y[0]) -
                     ((double)t->Y[1] - t->Y[0]) * ((double)t->X[2] - t->X[0]);
    for (int y = y0; y <= y1; y++) {
        const double Py = (double)y * RS_SUB + RS_SUB / 2;
        rs_pix *px = r->pix + (size_t)y * (size_t)r->w + (size_t)x0;
        for (int x = x0; x <= x1; x++, px++) {
            const double Px = (double)x * RS_SUB + RS_SUB / 2;
            int on = 0;
            for (int i = 0; i < 3 && !on; i++) {
                if (!(t->flags & (1u << i)))
                    continue;
                const int j = (i + 1) % 3;
                const double dx = (double)t->X[j] - t->X[i], dy = (double)t->Y[j] - t->Y[i];
                const double qx = Px - t->X[i], qy = Py - t->Y[i];
                const double l2 = dx * dx + dy * dy;
                double s = l2 > 0 ? (qx * dx + qy * dy) / l2 : 0;
                s = s < 0 ? 0 : s > 1 ? 1 : s;
                const double ex = qx - s * dx, ey = qy - s * dy;
                on = ex * ex + ey * ey <= 0.25 * RS_SUB * RS_SUB;
            }
            if (!on)
                continue;
            /* barycentric coordinates (extended beyond the triangle by half a pixel) */
            double b[3];
            for (int e = 0; e < 3; e++) {
                const int a = (e + 1) % 3, c = (e + 2) % 3;
                b[e] = (((double)t->X[c] - t->X[a]) * (Py - t->Y[a]) -
                        ((double)t->Y[c] - t->Y[a]) * (Px - t->X[a])) /
                       A;
            }
            const float key = (float)(b[0] * t->key[0] + b[1] * t->key[1] + b[2] * t->key[2]);
            if (key > px->key && b[0] * t->iw[0] + b[1] * t->iw[1] + b[2] * t->iw[2] > 0)
                store_fragment(px, t, L, key, (float)b[0], (float)b[1], (float)b[2], id);
        }
    }
}

/* ---------------------------------------------------------------------- */
/* Drawing                                                                  */

static int
thread_count(const vv_raster *r) {
    return r->threads > 0 ? r->threads : vv_threads_get();
}

static vv_status
ensure_chunks(vv_raster *r, int n) {
    if (n <= r->n_chunks)
        return VV_OK;
    rs_chunk *c = realloc(r->chunks, (size_t)n * sizeof *c);
    if (!c)
        return vv_error_set(VV_ERR_NOMEM, "raster: out of memory");
    r->chunks = c;
    for (int i = r->n_chunks; i < n; i++) {
        memset(&c[i], 0, sizeof c[i]);
        c[i].off = malloc(((size_t)r->n_tiles + 1) * sizeof *c[i].off);
        if (!c[i].off) {
            r->n_chunks = i;
            return vv_error_set(VV_ERR_NOMEM, "raster: out of memory");
        }
    }
    r->n_chunks = n;
    return VV_OK;
}

static double
det3(vv_mat4 m) {
    return m.m[0][0] * (m.m[1][1] * m.m[2][2] - m.m[1][2] * m.m[2][1]) -
           m.m[0][1] * (m.m[1][0] * m.m[2][2] - m.m[1][2] * m.m[2][0]) +
           m.m[0][2] * (m.m[1][0] * m.m[2][1] - m.m[1][1] * m.m[2][0]);
}

vv_status
vv_raster_draw_mesh(vv_raster *r, const vv_mesh *mesh, vv_mat4 model) {
    if (!r || !mesh)
        return vv_error_set(VV_ERR_INVALID, "raster: NULL context or mesh");
    if (mesh->n_triangles == 0)
        return VV_OK;
    if (!mesh->positions || !mesh->triangles)
        return vv_error_set(VV_ERR_INVALID, "raster: mesh without positions or triangles");
    const double det = det3(model);
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(model, &ok);
    if (!ok || !(fabs(det) > 0) || !isfinite(det))
        return vv_error_set(VV_ERR_INVALID, "raster: singular model matrix");
    if (r->next_base + mesh->n_triangles >= RS_BACK - 1)
        return vv_error_set(VV_ERR_LIMIT, "raster: more than %u triangles in one frame",
                            RS_BACK - 2);
    const size_t nv = mesh->n_vertices;
    if (r->n_draws == r->cap_draws) {
        int nc = r->cap_draws ? 2 * r->cap_draws : 8;
        rs_draw *d = realloc(r->draws, (size_t)nc * sizeof *d);
        if (!d)
            return vv_error_set(VV_ERR_NOMEM, "raster: out of memory");
        memset(d + r->cap_draws, 0, (size_t)(nc - r->cap_draws) * sizeof *d);
        r->draws = d;
        r->cap_draws = nc;
    }
    rs_draw *d = &r->draws[r->n_draws];
    const int gouraud = r->shading == VV_RASTER_GOURAUD && r->lit;
    const int has_normals = mesh->normals != NULL;
    if (!has_normals && !grow_buf((void **)&d->own_nrm, &d->cap_nrm, 3 * nv, sizeof(float)))
        return vv_error_set(VV_ERR_NOMEM, "raster: out of memory for %zu normals", nv);
    if (gouraud && !grow_buf((void **)&d->vcol, &d->cap_col, 3 * nv, sizeof(float)))
        return vv_error_set(VV_ERR_NOMEM, "raster: out of memory for %zu colours", nv);
    if (nv > r->cap_scratch) {
        free(r->clip);
        free(r->oc);
        free(r->sxy);
        free(r->skw);
        r->clip = malloc(4 * nv * sizeof(float));
        r->oc = malloc(nv * sizeof(uint32_t));
        r->sxy = malloc(2 * nv * sizeof(int32_t));
        r->skw = malloc(2 * nv * sizeof(float));
        r->cap_scratch = nv;
        if (!r->clip || !r->oc || !r->sxy || !r->skw) {
            free(r->clip);
            free(r->oc);
            free(r->sxy);
            free(r->skw);
            r->clip = NULL;
            r->oc = NULL;
            r->sxy = NULL;
            r->skw = NULL;
            r->cap_scratch = 0;
            return vv_error_set(VV_ERR_NOMEM, "raster: out of memory for %zu vertices", nv);
        }
    }
    const int nt = thread_count(r);
    vv_status s = ensure_chunks(r, 4 * nt);
    if (s != VV_OK)
        return s;
    d->mesh = mesh;
    d->base = (uint32_t)r->next_base;
    prepare_draw_shading(r, d);
    d->cap = r->capping;
    d->n_cap = 0;
    for (int k = 0; k < r->n_planes + r->n_bounds; k++) {
        const vv_plane *pl = k < r->n_planes ? &r->planes[k] : &r->bounds[k - r->n_planes];
        d->capp[d->n_cap][0] = (float)pl->n.x;
        d->capp[d->n_cap][1] = (float)pl->n.y;
        d->capp[d->n_cap][2] = (float)pl->n.z;
        d->capp[d->n_cap][3] = (float)pl->d;
        d->n_cap++;
    }

    /* 1. vertices (object coordinates: world positions and normals are
     * only needed where a pixel is shaded) */
    const vv_mat4 MVP = vv_mat4_mul(r->vp, model);
    const vv_mat4 N = vv_mat4_transpose(inv);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 4; k++) {
            d->M[i][k] = (float)model.m[i][k];
            if (k < 3)
                d->N[i][k] = (float)N.m[i][k];
        }
    /* world cut plane n.x + c >= 0 with x = A p + t: (A^T n).p + (n.t + c) >= 0 */
    const int n_planes = r->n_planes;
    for (int k = 0; k < n_planes; k++) {
        const vv_plane *pl = &r->planes[k];
        const double n[3] = {pl->n.x, pl->n.y, pl->n.z};
        for (int a = 0; a < 3; a++)
            r->oplanes[k][a] = n[0] * model.m[0][a] + n[1] * model.m[1][a] + n[2] * model.m[2][a];
        r->oplanes[k][3] =
            n[0] * model.m[0][3] + n[1] * model.m[1][3] + n[2] * model.m[2][3] + pl->d;
    }
    const double gb = r->gb;
#pragma omp parallel for schedule(static) num_threads(nt)
    for (size_t i = 0; i < nv; i++) {
        const float *p = mesh->positions + 3 * i;
        const double x = p[0], y = p[1], z = p[2];
        double c[4];
        for (int k = 0; k < 4; k++)
            c[k] = MVP.m[k][0] * x + MVP.m[k][1] * y + MVP.m[k][2] * z + MVP.m[k][3];
        float *co = r->clip + 4 * i;
        for (int k = 0; k < 4; k++)
            co[k] = (float)c[k];
        uint32_t oc = 0;
        oc |= (uint32_t)(c[2] + c[3] < 0) << 0;
        oc |= (uint32_t)(c[3] - c[2] < 0) << 1;
        oc |= (uint32_t)(gb * c[3] - c[0] < 0) << 2;
        oc |= (uint32_t)(gb * c[3] + c[0] < 0) << 3;
        oc |= (uint32_t)(gb * c[3] - c[1] < 0) << 4;
        oc |= (uint32_t)(gb * c[3] + c[1] < 0) << 5;
        for (int k = 0; k < n_planes; k++) {
            const double *pl = r->oplanes[k];
            oc |= (uint32_t)(pl[0] * x + pl[1] * y + pl[2] * z + pl[3] < 0) << (6 + k);
        }
        if (!(isfinite(c[0]) && isfinite(c[1]) && isfinite(c[2]) && isfinite(c[3])))
            oc = RS_OC_BAD;
        r->oc[i] = oc;
        if (!oc) {
            /* from the stored floats, as the clipping path does */
            const double cf[4] = {co[0], co[1], co[2], co[3]};
            rs_svert sv;
            project(r, cf, &sv);
            r->sxy[2 * i] = sv.X;
            r->sxy[2 * i + 1] = sv.Y;
            r->skw[2 * i] = sv.key;
            r->skw[2 * i + 1] = sv.iw;
        } else {
            r->sxy[2 * i] = RS_OFF;
        }
    }
    if (!has_normals) {
        /* area-weighted face normals, summed in triangle order (deterministic) */
        float *on = d->own_nrm;
        memset(on, 0, 3 * nv * sizeof(float));
        for (size_t t = 0; t < mesh->n_triangles; t++) {
            const uint32_t *v = mesh->triangles + 3 * t;
            if (v[0] >= nv || v[1] >= nv || v[2] >= nv)
                return vv_error_set(VV_ERR_INVALID,
                                    "raster: triangle %zu has a vertex index out of range", t);
            const float *a = mesh->positions + 3 * (size_t)v[0],
                        *b = mesh->positions + 3 * (size_t)v[1],
                        *c = mesh->positions + 3 * (size_t)v[2];
            const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            const float fn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                 e1[0] * e2[1] - e1[1] * e2[0]};
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++)
                    on[3 * (size_t)v[j] + (size_t)k] += fn[k];
        }
        d->nrm = on;
    } else {
        d->nrm = mesh->normals;
    }
    if (gouraud) {
#pragma omp parallel for schedule(static) num_threads(nt)
        for (size_t i = 0; i < nv; i++) {
            float pw[3], nw[3];
            to_world(d, mesh->positions + 3 * i, d->nrm + 3 * i, pw, nw);
            light_eval(d, pw, nw, d->vcol + 3 * i);
        }
    }

    /* 2. triangles, in chunks */
    rs_setup su;
    su.r = r;
    su.d = d;
    su.tri = mesh->triangles;
    su.n_vertices = nv;
    int flip = (det < 0) != (det3(r->view) < 0);
    su.cull_back = r->cull == (flip ? VV_RASTER_CULL_FRONT : VV_RASTER_CULL_BACK);
    su.cull_front = r->cull == (flip ? VV_RASTER_CULL_BACK : VV_RASTER_CULL_FRONT);
    su.flip = flip;
    su.wire = r->wireframe;
    const int nch = 4 * nt;
    const size_t ntri = mesh->n_triangles;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
    for (int c = 0; c < nch; c++)
        setup_chunk(&su, &r->chunks[c], ntri * (size_t)c / (size_t)nch,
                    ntri * (size_t)(c + 1) / (size_t)nch);
    for (int c = 0; c < nch; c++) {
        if (r->chunks[c].err == 2)
            return vv_error_set(VV_ERR_INVALID,
                                "raster: a triangle has a vertex index out of range (%zu vertices)",
                                nv);
        if (r->chunks[c].err)
            return vv_error_set(VV_ERR_NOMEM, "raster: out of memory for triangles");
        r->drawn += r->chunks[c].n_tris + r->chunks[c].n_frags;
    }

    /* 3. tiles */
    const uint32_t base = d->base;
    const int wire = r->wireframe;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
    for (int tile = 0; tile < r->n_tiles; tile++) {
        const int x0 = (tile % r->tx) * RS_TILE, y0 = (tile / r->tx) * RS_TILE;
        const int x1 = x0 + RS_TILE - 1 < r->w - 1 ? x0 + RS_TILE - 1 : r->w - 1;
        const int y1 = y0 + RS_TILE - 1 < r->h - 1 ? y0 + RS_TILE - 1 : r->h - 1;
        for (int c = 0; c < nch; c++) {
            const rs_chunk *ch = &r->chunks[c];
            for (uint32_t e = ch->off[tile]; e < ch->off[tile + 1]; e++) {
                const uint32_t idx = ch->sorted[e];
                if (idx & RS_FRAG) {
                    const rs_frag *f = &ch->frags[idx & ~RS_FRAG];
                    rs_pix *px = &r->pix[f->pixel];
                    if (f->key > px->key) {
                        px->key = f->key;
                        px->id = base + f->prim;
                        px->l1 = f->l1;
                        px->l2 = f->l2;
                    }
                    continue;
                }
                const rs_stri *t = &ch->tris[idx];
                const int a0 = t->px0 > x0 ? t->px0 : x0, a1 = t->px1 < x1 ? t->px1 : x1;
                const int b0 = t->py0 > y0 ? t->py0 : y0, b1 = t->py1 < y1 ? t->py1 : y1;
                if (wire)
                    scan_wire(r, t, ch->lams, base + t->prim, a0, a1, b0, b1);
                else
                    scan_fill(r, t, ch->lams, base + t->prim, a0, a1, b0, b1);
            }
        }
    }
    r->next_base += mesh->n_triangles;
    r->n_draws++;
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* Shading                                                                  */

/* The solid's cut face seen where the surface is seen from behind at the
 * world point @p p, @p t from the eye: the ray entered the solid where it
 * last crossed into the half-spaces that bound it. Writes that distance and
 * the face's shaded colour; 0 when no bounding plane explains the view
 * (the surface is then shown as it is). */
static int
cap_face(const rs_draw *d, const float p[3], float t, float *t_out, float col[3]) {
    float dir[3];
    if (d->persp) {
        const float it = t > 0 ? 1.0f / t : 0.0f;
        for (int k = 0; k < 3; k++)
            dir[k] = (p[k] - d->eye[k]) * it;
    } else {
        memcpy(dir, d->fwd, sizeof dir);
    }
    float te = -INFINITY;
    int best = -1;
    for (int k = 0; k < d->n_cap; k++) {
        const float *pl = d->capp[k];
        const float nd = pl[0] * dir[0] + pl[1] * dir[1] + pl[2] * dir[2];
        if (!(nd > 1e-6f))
            continue; /* not entered along the ray */
        const float sp = pl[0] * p[0] + pl[1] * p[1] + pl[2] * p[2] + pl[3];
        const float tk = t - sp / nd;
        if (tk > te) {
            te = tk;
            best = k;
        }
    }
    if (best < 0 || !(te < t))
        return 0;
    float q[3], n[3];
    if (te <= 0) {
        /* the eye is inside the solid: the face is at the eye */
        te = 0;
        for (int k = 0; k < 3; k++) {
            q[k] = p[k] - t * dir[k];
            n[k] = -dir[k];
        }
    } else {
        for (int k = 0; k < 3; k++) {
            q[k] = p[k] + (te - t) * dir[k];
            n[k] = d->capp[best][k];
        }
    }
    if (d->lit)
        light_eval(d, q, n, col);
    else
        memcpy(col, d->base_col, 3 * sizeof(float));
    *t_out = te;
    return 1;
}

static const rs_draw *
find_draw(const vv_raster *r, uint32_t id) {
    int lo = 0, hi = r->n_draws - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (r->draws[mid].base <= id)
            lo = mid;
        else
            hi = mid - 1;
    }
    return &r->draws[lo];
}

vv_status
vv_raster_finish(vv_raster *r, vv_image *out, int merge) {
    if (!r || !out)
        return vv_error_set(VV_ERR_INVALID, "raster: NULL context or image");
    if (out->width != r->w || out->height != r->h)
        return vv_error_set(VV_ERR_INVALID, "raster: image is %d x %d but the context is %d x %d",
                            out->width, out->height, r->w, r->h);
    const int nt = thread_count(r);
    const float bg[3] = {(float)r->background.x, (float)r->background.y, (float)r->background.z};
#pragma omp parallel for schedule(dynamic, 8) num_threads(nt)
    for (int y = 0; y < r->h; y++) {
        for (int x = 0; x < r->w; x++) {
            const size_t i = (size_t)y * (size_t)r->w + (size_t)x;
            const rs_pix *px = &r->pix[i];
            float *o = out->rgba + 4 * i;
            if (px->id == RS_NONE) {
                if (!merge) {
                    o[0] = bg[0];
                    o[1] = bg[1];
                    o[2] = bg[2];
                    o[3] = 0;
                    out->depth[i] = INFINITY;
                }
                continue;
            }
            const uint32_t id = px->id & ~RS_BACK;
            const rs_draw *d = find_draw(r, id);
            const uint32_t *tv = d->mesh->triangles + 3 * (size_t)(id - d->base);
            float l[3] = {1.0f - px->l1 - px->l2, px->l1, px->l2};
            /* wireframe pixels may lie up to half a pixel outside */
            float sum = 0;
            for (int k = 0; k < 3; k++) {
                l[k] = l[k] < 0 ? 0 : l[k] > 1 ? 1 : l[k];
                sum += l[k];
            }
            for (int k = 0; k < 3; k++)
                l[k] /= sum;
            const float *pos = d->mesh->positions;
            const float *P[3] = {pos + 3 * (size_t)tv[0], pos + 3 * (size_t)tv[1],
                                 pos + 3 * (size_t)tv[2]};
            const float *Nn[3] = {d->nrm + 3 * (size_t)tv[0], d->nrm + 3 * (size_t)tv[1],
                                  d->nrm + 3 * (size_t)tv[2]};
            float po[3], no[3], p[3], n[3];
            for (int k = 0; k < 3; k++) {
                po[k] = l[0] * P[0][k] + l[1] * P[1][k] + l[2] * P[2][k];
                no[k] = l[0] * Nn[0][k] + l[1] * Nn[1][k] + l[2] * Nn[2][k];
            }
            to_world(d, po, no, p, n);
            float depth;
            if (d->persp) {
                const float dx = p[0] - d->eye[0], dy = p[1] - d->eye[1], dz = p[2] - d->eye[2];
                depth = sqrtf(dx * dx + dy * dy + dz * dz);
            } else {
                depth = (p[0] - d->eye[0]) * d->fwd[0] + (p[1] - d->eye[1]) * d->fwd[1] +
                        (p[2] - d->eye[2]) * d->fwd[2];
            }
            float col[3];
            if ((px->id & RS_BACK) && d->cap && cap_face(d, p, depth, &depth, col)) {
                if (merge && !(depth < out->depth[i]))
                    continue;
            } else if (merge && !(depth < out->depth[i])) {
                continue;
            } else if (!d->lit) {
                memcpy(col, d->base_col, sizeof col);
            } else if (d->shading == VV_RASTER_GOURAUD && d->vcol) {
                const float *C[3] = {d->vcol + 3 * (size_t)tv[0], d->vcol + 3 * (size_t)tv[1],
                                     d->vcol + 3 * (size_t)tv[2]};
                for (int k = 0; k < 3; k++)
                    col[k] = l[0] * C[0][k] + l[1] * C[1][k] + l[2] * C[2][k];
            } else if (d->shading == VV_RASTER_FLAT) {
                float e1[3], e2[3], c[3];
                for (int k = 0; k < 3; k++) {
                    e1[k] = P[1][k] - P[0][k];
                    e2[k] = P[2][k] - P[0][k];
                    c[k] = (P[0][k] + P[1][k] + P[2][k]) * (1.0f / 3.0f);
                }
                /* the face normal transforms like a vertex normal (up to the
                 * sign, which two-sided lighting ignores) */
                const float fn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                     e1[0] * e2[1] - e1[1] * e2[0]};
                float cw[3], fw[3];
                to_world(d, c, fn, cw, fw);
                light_eval(d, cw, fw, col);
            } else {
                light_eval(d, p, n, col);
            }
            o[0] = col[0];
            o[1] = col[1];
            o[2] = col[2];
            o[3] = 1;
            out->depth[i] = depth;
        }
    }
    return VV_OK;
}
