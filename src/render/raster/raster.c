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

#include "render/raster/rs_internal.h"
#include "volvis/raster.h"

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
/* Drawing                                                                  */

int
rs_thread_count(const vv_raster *r) {
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

/* Over 150 lines on purpose: one pass of the immediate-mode pipeline for a
 * mesh (transform, clip, snap, cull, bin) whose stages hand each other the
 * per-mesh arrays; the stages are marked inside. */
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
    const int nt = rs_thread_count(r);
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
        rs_setup_chunk(&su, &r->chunks[c], ntri * (size_t)c / (size_t)nch,
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
                    rs_scan_wire(r, t, ch->lams, base + t->prim, a0, a1, b0, b1);
                else
                    rs_scan_fill(r, t, ch->lams, base + t->prim, a0, a1, b0, b1);
            }
        }
    }
    r->next_base += mesh->n_triangles;
    r->n_draws++;
    return VV_OK;
}
