/*
 * Volumetric radiosity: the view-dependent image of a solution (ray casting
 * that composites voxel radiosities and shows patch radiosities) and the
 * `radiosity` renderer, which keeps the solution while only the view
 * changes. See include/volvis/radiosity.h.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/radiosity/radiosity_internal.h"
#include "render/registry.h"

#define RAD_BLOCK 8

/* Per voxel: sigma, display radiance (power / (4 capacity)), diffuse normal;
 * opaque voxels that are not elements take the mean of their element
 * neighbours so the colour does not darken towards buried voxels. */
vv_status
rad_prepare_render(vv_radiosity *r) {
    for (int vi = 0; vi < r->n_vols; vi++) {
        rad_vol *rv = &r->vols[vi];
        const int nx = rv->n[0], ny = rv->n[1], nz = rv->n[2];
        const size_t nv = (size_t)nx * ny * nz;
        rv->rc = calloc(8 * nv, sizeof *rv->rc);
        uint8_t *is_el = calloc(nv, 1);
        rv->bs = RAD_BLOCK;
        for (int a = 0; a < 3; a++)
            rv->bn[a] = (rv->n[a] + RAD_BLOCK - 1) / RAD_BLOCK;
        size_t nb = (size_t)rv->bn[0] * rv->bn[1] * rv->bn[2];
        rv->bmax = calloc(nb, sizeof *rv->bmax);
        if (!rv->rc || !is_el || !rv->bmax) {
            free(is_el);
            return vv_error_set(VV_ERR_NOMEM, "radiosity: out of memory for the render grid");
        }
        /* opacity of one render step (half a voxel) */
        rv->step = 0.5 * rv->h;
        int lo[3] = {nx, ny, nz}, hi[3] = {-1, -1, -1};
        for (int k = 0; k < nz; k++)
            for (int j = 0; j < ny; j++)
                for (int i = 0; i < nx; i++) {
                    size_t id = ((size_t)k * ny + j) * nx + i;
                    rv->rc[8 * id] = (float)(1 - exp(-rv->sigma[id] * rv->step));
                    if (rv->sigma[id] > 0) {
                        const int p[3] = {i, j, k};
                        for (int a = 0; a < 3; a++) {
                            lo[a] = p[a] < lo[a] ? p[a] : lo[a];
                            hi[a] = p[a] > hi[a] ? p[a] : hi[a];
                        }
                    }
                }
        if (hi[0] < 0) {
            rv->rbox.min = vv_vec3_make(1, 1, 1); /* empty: a box no ray meets */
            rv->rbox.max = vv_vec3_make(-1, -1, -1);
        } else {
            /* one voxel more (samples interpolate from their neighbours),
             * within the cells of the grid */
            double gl[3], gh[3];
            for (int a = 0; a < 3; a++) {
                gl[a] = lo[a] - 1 > -0.5 ? lo[a] - 1 : -0.5;
                gh[a] = hi[a] + 1 < rv->n[a] - 0.5 ? hi[a] + 1 : rv->n[a] - 0.5;
            }
            vv_box gb = {vv_vec3_make(gl[0], gl[1], gl[2]), vv_vec3_make(gh[0], gh[1], gh[2])};
            rv->rbox = vv_box_transform(gb, rv->g2w);
        }
        for (int i = 0; i < r->n_elems; i++) {
            const rad_elem *e = &r->elems[i];
            if (e->kind != RAD_VOXEL || e->obj != rv->obj || !(e->area > 0))
                continue;
            float *d = &rv->rc[8 * (size_t)e->vox];
            for (int c = 0; c < 3; c++) {
                d[1 + c] = e->total[0][c] / (4 * e->area);
                d[4 + c] = e->n[c];
            }
            is_el[e->vox] = 1;
        }
#pragma omp parallel for schedule(static)
        for (int k = 0; k < nz; k++)
            for (int j = 0; j < ny; j++)
                for (int i = 0; i < nx; i++) {
                    size_t id = ((size_t)k * ny + j) * nx + i;
                    if (is_el[id])
                        continue;
                    double acc[6] = {0, 0, 0, 0, 0, 0};
                    int cnt = 0;
                    for (int dk = -1; dk <= 1; dk++)
                        for (int dj = -1; dj <= 1; dj++)
                            for (int di = -1; di <= 1; di++) {
                                int x = i + di, y = j + dj, z = k + dk;
                                if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz)
                                    continue;
                                size_t n = ((size_t)z * ny + y) * nx + x;
                                if (!is_el[n])
                                    continue;
                                for (int c = 0; c < 6; c++)
                                    acc[c] += rv->rc[8 * n + 1 + c];
                                cnt++;
                            }
                    if (cnt)
                        for (int c = 0; c < 6; c++)
                            rv->rc[8 * id + 1 + c] = (float)(acc[c] / cnt);
                }
        free(is_el);
        for (int k = 0; k < nz; k++)
            for (int j = 0; j < ny; j++)
                for (int i = 0; i < nx; i++) {
                    float s = rv->sigma[((size_t)k * ny + j) * nx + i];
                    /* a block holds the samples that interpolate from its voxels */
                    for (int dk = -1; dk <= 0; dk++)
                        for (int dj = -1; dj <= 0; dj++)
                            for (int di = -1; di <= 0; di++) {
                                int bx = (i + di) / RAD_BLOCK, by = (j + dj) / RAD_BLOCK,
                                    bz = (k + dk) / RAD_BLOCK;
                                if (i + di < 0 || j + dj < 0 || k + dk < 0)
                                    continue;
                                float *bm =
                                    &rv->bmax[((size_t)bz * rv->bn[1] + by) * rv->bn[0] + bx];
                                *bm = *bm > s ? *bm : s;
                            }
                }
    }
    return VV_OK;
}

static vv_vec3
f3v(const float *p) {
    return vv_vec3_make(p[0], p[1], p[2]);
}

/* The patch seen at each pixel centre, by rasterizing every patch into an
 * id buffer with depth (cheaper than a ray per pixel through the trees).
 * Returns 0 when a patch crosses the eye plane (the caller then traces
 * rays); ids[] is -1 where no patch is seen. */
static int
raster_patches(const vv_radiosity *r, const vv_view *view, int *ids, float *zb) {
    const int W = view->width, H = view->height;
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    vv_vec3 rt = vv_vec3_cross(f, view->up);
    if (!(vv_vec3_length(rt) > 1e-9) || !(vv_vec3_length(f) > 0))
        return 0;
    rt = vv_vec3_normalize(rt);
    vv_vec3 up = vv_vec3_cross(rt, f);
    const double aspect = (double)W / H;
    const int ortho = view->projection == VV_PROJECTION_ORTHOGRAPHIC;
    const double tf = tan(0.5 * view->fov);
    const double hh = 0.5 * view->ortho_height, hw = hh * aspect;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        ids[i] = -1;
        zb[i] = INFINITY;
    }
    for (int ei = 0; ei < r->n_elems; ei++) {
        const rad_elem *e = &r->elems[ei];
        if (e->kind != RAD_PATCH)
            continue;
        double sx[3], sy[3], sz[3];
        for (int k = 0; k < 3; k++) {
            vv_vec3 rel = vv_vec3_sub(f3v(e->tri + 3 * k), view->eye);
            double zc = vv_vec3_dot(rel, f);
            double x, y;
            if (ortho) {
                x = vv_vec3_dot(rel, rt) / hw;
                y = vv_vec3_dot(rel, up) / hh;
            } else {
                if (!(zc > 1e-6))
                    return 0;
                x = vv_vec3_dot(rel, rt) / (zc * tf * aspect);
                y = vv_vec3_dot(rel, up) / (zc * tf);
            }
            sx[k] = 0.5 * (x + 1) * W - 0.5;
            sy[k] = 0.5 * (1 - y) * H - 0.5;
            sz[k] = ortho ? zc : 1 / zc; /* 1/z is linear on screen */
        }
        double area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
        if (!(fabs(area) > 1e-12))
            continue;
        int x0 = (int)ceil(fmin(sx[0], fmin(sx[1], sx[2])) - 1e-9);
        int x1 = (int)floor(fmax(sx[0], fmax(sx[1], sx[2])) + 1e-9);
        int y0 = (int)ceil(fmin(sy[0], fmin(sy[1], sy[2])) - 1e-9);
        int y1 = (int)floor(fmax(sy[0], fmax(sy[1], sy[2])) + 1e-9);
        x0 = x0 < 0 ? 0 : x0;
        y0 = y0 < 0 ? 0 : y0;
        x1 = x1 >= W ? W - 1 : x1;
        y1 = y1 >= H ? H - 1 : y1;
        const double ia = 1 / area, eps = 1e-7;
        for (int y = y0; y <= y1; y++)
            for (int x = x0; x <= x1; x++) {
                double b0 = ((sx[1] - x) * (sy[2] - y) - (sx[2] - x) * (sy[1] - y)) * ia;
                double b1 = ((sx[2] - x) * (sy[0] - y) - (sx[0] - x) * (sy[2] - y)) * ia;
                double b2 = 1 - b0 - b1;
                if (b0 < -eps || b1 < -eps || b2 < -eps)
                    continue;
                double z = b0 * sz[0] + b1 * sz[1] + b2 * sz[2];
                z = ortho ? z : 1 / z;
                size_t id = (size_t)y * W + x;
                if (z < zb[id]) {
                    zb[id] = (float)z;
                    ids[id] = ei;
                }
            }
    }
    return 1;
}

/* Composites one volume's radiosity along o + t d, t in [t0, t1], into
 * (col, *T); returns the t where the opacity first passed 1/2 (or INFINITY). */
static double
march(const rad_vol *rv, vv_vec3 o, vv_vec3 d, double t0, double t1, double col[3], double *T) {
    vv_vec3 go = vv_mat4_mul_point(rv->w2g, o), gd = vv_mat4_mul_dir(rv->w2g, d);
    const double step = rv->step;
    const int nx = rv->n[0], ny = rv->n[1], nz = rv->n[2];
    const size_t sy = (size_t)nx, sz = (size_t)nx * ny;
    const double hx = nx - 1, hy = ny - 1, hz = nz - 1;
    double depth = INFINITY;
    double t = t0 + 0.5 * step;
    const double w[3] = {-d.x, -d.y, -d.z};
    while (t<t1 && * T> 0.004) {
        double q[3] = {go.x + gd.x * t, go.y + gd.y * t, go.z + gd.z * t};
        /* empty block: jump to its far side */
        int bi[3];
        for (int a = 0; a < 3; a++) {
            double x = q[a] < 0 ? 0 : q[a];
            bi[a] = (int)(x / RAD_BLOCK);
            bi[a] = bi[a] >= rv->bn[a] ? rv->bn[a] - 1 : bi[a];
        }
        if (rv->bmax[((size_t)bi[2] * rv->bn[1] + bi[1]) * rv->bn[0] + bi[0]] <= 0) {
            double te = INFINITY;
            const double dq[3] = {gd.x, gd.y, gd.z};
            for (int a = 0; a < 3; a++) {
                if (dq[a] > 1e-12)
                    te = fmin(te, ((bi[a] + 1) * RAD_BLOCK - q[a]) / dq[a]);
                else if (dq[a] < -1e-12)
                    te = fmin(te, (bi[a] * RAD_BLOCK - q[a]) / dq[a]);
            }
            double adv = te > 0 && isfinite(te) ? ceil(te / step) * step : step;
            t += adv > step ? adv : step;
            continue;
        }
        double x = q[0] < 0 ? 0 : q[0] > hx ? hx : q[0];
        double y = q[1] < 0 ? 0 : q[1] > hy ? hy : q[1];
        double z = q[2] < 0 ? 0 : q[2] > hz ? hz : q[2];
        int i = (int)x, j = (int)y, k = (int)z;
        i = i >= nx - 1 ? (nx > 1 ? nx - 2 : 0) : i;
        j = j >= ny - 1 ? (ny > 1 ? ny - 2 : 0) : j;
        k = k >= nz - 1 ? (nz > 1 ? nz - 2 : 0) : k;
        double fx = nx > 1 ? x - i : 0, fy = ny > 1 ? y - j : 0, fz = nz > 1 ? z - k : 0;
        size_t ox = nx > 1 ? 8 : 0, oy = ny > 1 ? 8 * sy : 0, oz = nz > 1 ? 8 * sz : 0;
        const float *p = &rv->rc[8 * (i + j * sy + k * sz)];
        double v[7];
        for (int c = 0; c < 7; c++) {
            double c00 = p[c] + fx * (p[ox + c] - p[c]);
            double c10 = p[oy + c] + fx * (p[oy + ox + c] - p[oy + c]);
            double c01 = p[oz + c] + fx * (p[oz + ox + c] - p[oz + c]);
            double c11 = p[oz + oy + c] + fx * (p[oz + oy + ox + c] - p[oz + oy + c]);
            double c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
            v[c] = c0 + fz * (c1 - c0);
            if (c == 0 && !(v[0] > 0))
                break; /* transparent here: no colour needed */
        }
        if (v[0] > 0) {
            double a = v[0];
            double nl = sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
            nl = nl > 1 ? 1 : nl;
            /* a diffuse voxel is a piece of surface: the same radiance from
             * every direction in front of it, none behind */
            double cn = nl > 0 ? (v[4] * w[0] + v[5] * w[1] + v[6] * w[2]) / nl : 0;
            double front = 0.5 + 2 * cn;
            front = front < 0 ? 0 : front > 1 ? 1 : front;
            double f = (1 - nl) + 4 * nl * front;
            for (int c = 0; c < 3; c++)
                col[c] += *T * a * v[1 + c] * f;
            *T *= 1 - a;
            if (*T < 0.5 && !isfinite(depth))
                depth = t;
        }
        t += step;
    }
    return depth;
}

/* What the tiles of one view frame share. */
typedef struct rad_view {
    const vv_radiosity *r;
    vv_camera_rays cam;
    const int *ids; /* rasterized patch per pixel, or NULL: trace rays for patches */
    int has_patches;
    vv_vec3 bg;
    vv_image *out;
} rad_view;

/* One pixel: the first patch, then the volumes in front of it front to back. */
static void
view_pixel(const rad_view *c, int x, int y) {
    const vv_radiosity *r = c->r;
    const int W = c->out->width;
    const vv_ray ray = vv_camera_ray(&c->cam, x, y);
    double tp = INFINITY;
    int pe = -1;
    if (c->ids) {
        pe = c->ids[(size_t)y * W + x];
        if (pe >= 0) {
            const rad_elem *e = &r->elems[pe];
            vv_vec3 n = f3v(e->n);
            double dn = vv_vec3_dot(n, ray.dir);
            tp = fabs(dn) > 1e-12 ? vv_vec3_dot(n, vv_vec3_sub(f3v(e->p), ray.origin)) / dn
                                  : vv_vec3_length(vv_vec3_sub(f3v(e->p), ray.origin));
        }
    } else if (c->has_patches) {
        pe = rad_patch_hit(r, ray.origin, ray.dir, 0, INFINITY, 0, &tp);
    }
    double col[3] = {0, 0, 0}, T = 1, depth = pe >= 0 ? tp : INFINITY;
    /* volumes front to back by entry (overlapping volumes are taken one after another) */
    int order[8], n = 0;
    double ent[8];
    for (int v = 0; v < r->n_vols && n < 8; v++) {
        double a, b;
        if (r->vols[v].rbox.min.x > r->vols[v].rbox.max.x ||
            !vv_box_intersect_ray(r->vols[v].rbox, ray, &a, &b) || b < 0 || a > tp)
            continue;
        int i = n++;
        while (i > 0 && ent[i - 1] > a) {
            ent[i] = ent[i - 1];
            order[i] = order[i - 1];
            i--;
        }
        ent[i] = a;
        order[i] = v;
    }
    for (int i = 0; i < n && T > 0.01; i++) {
        const rad_vol *rv = &r->vols[order[i]];
        double a, b;
        vv_box_intersect_ray(rv->rbox, ray, &a, &b);
        a = a > 0 ? a : 0;
        b = b < tp ? b : tp;
        double dd = march(rv, ray.origin, ray.dir, a, b, col, &T);
        depth = dd < depth ? dd : depth;
    }
    double alpha = 1 - T;
    if (pe >= 0) {
        const rad_elem *e = &r->elems[pe];
        int side = vv_vec3_dot(f3v(e->n), ray.dir) > 0;
        for (int ch = 0; ch < 3; ch++)
            col[ch] += T * e->total[side][ch] / e->area;
        alpha = 1;
    } else {
        col[0] += T * c->bg.x;
        col[1] += T * c->bg.y;
        col[2] += T * c->bg.z;
    }
    float *px = &c->out->rgba[4 * ((size_t)y * W + x)];
    for (int ch = 0; ch < 3; ch++)
        px[ch] = (float)col[ch];
    px[3] = (float)alpha;
    c->out->depth[(size_t)y * W + x] = alpha > 0 ? (float)depth : INFINITY;
}

static vv_status
view_tile(void *user, const vv_frame_tile *t) {
    const rad_view *c = user;
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++)
            view_pixel(c, x, y);
    return VV_OK;
}

vv_status
vv_radiosity_view_frame(const vv_radiosity *r, const vv_world *world, const vv_view *view,
                        int threads, vv_image *out) {
    if (!r || !view || !out)
        return vv_error_set(VV_ERR_INVALID, "radiosity: NULL solution, view or image");
    if (out->width != view->width || out->height != view->height)
        return vv_error_set(VV_ERR_INVALID, "radiosity: image is %d x %d but the view is %d x %d",
                            out->width, out->height, view->width, view->height);
    vv_vec3 bg = world ? world->background : vv_vec3_make(0, 0, 0);
    int nt = threads > 0 ? threads : vv_threads_get();
    const int W = view->width, H = view->height;
    int has_patches = 0;
    for (int i = 0; i < r->n_roots; i++)
        has_patches |= r->nodes[r->roots[i]].kind == RAD_PATCH;
    int *ids = NULL;
    float *zb = NULL;
    if (has_patches) {
        ids = malloc((size_t)W * H * sizeof *ids);
        zb = malloc((size_t)W * H * sizeof *zb);
        if (!ids || !zb || !raster_patches(r, view, ids, zb)) {
            free(ids);
            ids = NULL; /* trace rays instead */
        }
        free(zb);
    }
    rad_view c;
    memset(&c, 0, sizeof c);
    c.r = r;
    vv_camera_rays_init(&c.cam, view);
    c.ids = ids;
    c.has_patches = has_patches;
    c.bg = bg;
    c.out = out;
    vv_frame_job job;
    vv_frame_job_init(&job, W, H, view_tile, &c);
    vv_render_options ro;
    vv_render_options_init(&ro);
    ro.threads = nt;
    vv_status s = vv_frame_run(&job, &ro);
    free(ids);
    return s;
}

/* ---------------------------------------------------------------------- */
/* the renderer: the solution is kept while the World's content is the same */

typedef struct rad_state {
    vv_radiosity_options opt;
    vv_radiosity *sol;
    uint64_t key;
} rad_state;

static void
hash_bytes(uint64_t *h, const void *p, size_t n) {
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) {
        *h ^= b[i];
        *h *= 1099511628211ull;
    }
}

#define HASH(h, v) hash_bytes((h), &(v), sizeof(v))

/* A key of everything the solution depends on (not the view). */
static uint64_t
world_key(const vv_world *w, const vv_radiosity_options *o) {
    uint64_t h = 1469598103934665603ull;
    HASH(&h, o->tolerance);
    HASH(&h, o->error);
    HASH(&h, o->near);
    HASH(&h, o->patch_size);
    HASH(&h, o->grid);
    HASH(&h, o->diffuse_voxels);
    HASH(&h, o->max_shots);
    HASH(&h, o->levels);
    for (int i = 0; i < w->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        if (l->headlight)
            continue;
        HASH(&h, l->type);
        HASH(&h, l->direction);
        HASH(&h, l->position);
        HASH(&h, l->color);
        HASH(&h, l->intensity);
    }
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *ob = w->objects[i];
        HASH(&h, ob->type);
        HASH(&h, ob->visible);
        if (!ob->visible)
            continue;
        HASH(&h, ob->position);
        HASH(&h, ob->orientation);
        HASH(&h, ob->scale);
        HASH(&h, ob->material.diffuse);
        HASH(&h, ob->material.color);
        HASH(&h, ob->material.emission);
        HASH(&h, ob->segmentation);
        HASH(&h, ob->threshold);
        HASH(&h, ob->tf.n_opacity);
        hash_bytes(&h, ob->tf.opacity, (size_t)ob->tf.n_opacity * sizeof ob->tf.opacity[0]);
        HASH(&h, ob->tf.n_color);
        hash_bytes(&h, ob->tf.color, (size_t)ob->tf.n_color * sizeof ob->tf.color[0]);
        HASH(&h, ob->tf.opacity_unit_distance);
        const vv_geometry *g = &ob->geometry;
        HASH(&h, g->center);
        HASH(&h, g->radius);
        HASH(&h, g->box);
        HASH(&h, g->base);
        HASH(&h, g->top);
        HASH(&h, g->capped);
        HASH(&h, g->n_vertices);
        if (g->vertices)
            hash_bytes(&h, g->vertices, (size_t)g->n_vertices * sizeof *g->vertices);
        uintptr_t mp = (uintptr_t)g->mesh, vp = (uintptr_t)ob->volume;
        HASH(&h, mp);
        HASH(&h, vp);
        if (ob->volume)
            HASH(&h, ob->volume->modified);
    }
    return h;
}

static vv_status
rad_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
           vv_image *out) {
    rad_state *st = state;
    uint64_t key = world_key(w, &st->opt);
    if (!st->sol || key != st->key) {
        vv_radiosity_free(st->sol);
        st->sol = NULL;
        vv_status s = vv_radiosity_solve(&st->sol, w, &st->opt, &opt->progress);
        if (s != VV_OK)
            return s;
        st->key = key;
    }
    return vv_radiosity_view_frame(st->sol, w, view, opt->threads, out);
}

static void
rad_release(void *state) {
    rad_state *st = state;
    vv_radiosity_free(st->sol);
}

/* The options, each bound to its field of the solver's options in
 * rad_state (their defaults those of vv_radiosity_options_init). */
static const vv_option_spec rad_options[] = {
    {"tolerance", VV_OPTION_REAL, "0.001", 0, 1, VV_OPTION_MIN_OPEN | VV_OPTION_MAX_OPEN, NULL,
     "stop when the unshot power is below this fraction of the power received",
     VV_OPTION_BIND(rad_state, opt.tolerance, DOUBLE)},
    {"error", VV_OPTION_REAL, "0.0001", 0, INFINITY, 0, NULL,
     "hierarchical refinement bound, fraction of the power in (0: element to element)",
     VV_OPTION_BIND(rad_state, opt.error, DOUBLE)},
    {"near", VV_OPTION_REAL, "0.5", 0, INFINITY, VV_OPTION_MIN_OPEN, NULL,
     "a pair is near when (radius + radius) > near x distance",
     VV_OPTION_BIND(rad_state, opt.near, DOUBLE)},
    {"patch_size", VV_OPTION_REAL, "0", 0, INFINITY, 0, NULL,
     "longest patch edge, world units (0: the World's diagonal / 48)",
     VV_OPTION_BIND(rad_state, opt.patch_size, DOUBLE)},
    {"grid", VV_OPTION_INT, "128", 2, 1024, 0, NULL, "voxels along a volume's longest axis",
     VV_OPTION_BIND(rad_state, opt.grid, INT)},
    {"diffuse_voxels", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "voxels scatter diffusely about their gradient (0: isotropically)",
     VV_OPTION_BIND(rad_state, opt.diffuse_voxels, INT)},
    {"max_shots", VV_OPTION_INT, "20000", 1, 100000000, 0, NULL,
     "shots at most (then it stops with power left unshot)",
     VV_OPTION_BIND(rad_state, opt.max_shots, INT)},
    {"levels", VV_OPTION_INT, "0", 0, 30, 0, NULL,
     "hierarchy levels used (0: all; 1: element to element)",
     VV_OPTION_BIND(rad_state, opt.levels, INT)},
};

const vv_renderer_ops vv_radiosity_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "radiosity",
            .description = "volumetric radiosity: diffuse interreflection between volumes and "
                           "surfaces",
            /* infinite planes have no finite patches: left out */
            .draws = VV_DRAWS(VV_OBJECT_VOLUME) | (VV_DRAWS_GEOMETRY & ~VV_DRAWS(VV_OBJECT_PLANE)),
            .modes = VV_MODES_ALL,
            .caps = VV_RENDERER_GLOBAL,
            .quality = "ignored; the solution is kept while only the view changes (volumes "
                       "scatter by their transfer function or threshold in every mode)",
            .options = rad_options,
            .n_options = VV_OPTIONS_COUNT(rad_options),
        },
    .state_size = sizeof(rad_state),
    .release = rad_release,
    .render = rad_render,
    .render_region = NULL,
};
