/*
 * Volumetric ray tracing, out of core: the light volumes of a region
 * render's context swept through the whole volume (vv_render_region.whole)
 * rather than through the World's coarse proxy, so that the shadows of a
 * volume rendered brick by brick are those of the in-memory render.
 *
 * A directional light's light volume (rt_shade.c, sweep_grid) is swept
 * layer by layer from the light's side: a grid point's transmittance is the
 * bilinear one of the layer before it, towards the light, times its own
 * segment's (one sample at the segment's middle); points whose way to the
 * light leaves the grid march to the volume's face. Every value therefore
 * depends only on points and voxels towards the light. Here the grid is cut
 * into tiles of the reader's size, swept one after another in the light's
 * order (a tile after every tile that lies towards the light on some axis
 * and not away from it on another: by the sum of their distances from the
 * light's corner), each from one box of voxels: the tile's own, and on the
 * light's side of each axis the three more that its samples reach (two
 * towards the light and the trilinear neighbour). The values are the
 * in-memory sweep's: the same points, sample positions and tables (the
 * region part's, built from voxels of the same type and value range); the
 * marches step through every subvolume rather than leaping over empty
 * ones, which adds zeros, and may place their cuts a rounding apart.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/raytrace/rt_internal.h"
#include "render/sample.h"

int
rt_context_whole(rt_frame *fr, const vv_render_region *region) {
    if (!region || !region->whole || !region->whole->read_box || !fr->shadows ||
        !fr->st->light_volumes || fr->st->shadow_grid == 2 || fr->n_vobj < 1)
        return 0;
    for (int l = 0; l < fr->n_lights; l++)
        if (fr->lights[l].point)
            return 0;
    const rt_vobj *part = &fr->vobjs[0]; /* prepare_frame: the region part first */
    const vv_volume *h = region->whole->header;
    if (!part->region || part->mode != VV_MODE_COMPOSITE || part->group >= 0 || !h)
        return 0;
    for (int a = 0; a < 3; a++)
        if (h->dims[a] != region->dims[a] || h->dims[a] < 2)
            return 0;
    int any = 0;
    for (int i = 1; i < fr->n_vobj; i++) {
        rt_vobj *ro = &fr->vobjs[i];
        if (!ro->context || ro->mode != VV_MODE_COMPOSITE || ro->group >= 0 ||
            !ro->obj->casts_shadows)
            continue;
        memcpy(ro->w2i, part->w2i, sizeof ro->w2i);
        memcpy(ro->i2w, part->i2w, sizeof ro->i2w);
        memcpy(ro->dims, part->dims, sizeof ro->dims);
        ro->vox = part->vox;
        ro->whole = region->whole;
        ro->whole_part = part;
        any = 1;
    }
    return any;
}

/* A tile's voxels: their cache and the index of its voxel (0, 0, 0). */
typedef struct lw_tile {
    const vv_vcache *c;
    float o[3];
} lw_tile;

static inline float
tile_sample(const lw_tile *t, const float q[3]) {
    const float x[3] = {q[0] - t->o[0], q[1] - t->o[1], q[2] - t->o[2]};
    return vv_vcache_sample(t->c, x);
}

static inline float
tile_ext(const rt_vobj *pt, float v) {
    return pt->ext[(int)vv_vtables_index(&pt->tab, v)];
}

/* own_depth (rt_shade.c) from the tile: the segment's optical depth, one
 * sample at its middle. */
static float
tile_depth(const rt_vobj *ob, const lw_tile *t, const double p[3], const double li[3], double seg,
           vv_vec3 wp, vv_vec3 ldir) {
    float q[3];
    for (int a = 0; a < 3; a++) {
        q[a] = (float)(p[a] + li[a] * seg * 0.5);
        if (!(q[a] >= 0 && q[a] <= (float)(ob->dims[a] - 1)))
            return 0.0f;
    }
    if (ob->n_planes) {
        const vv_vec3 wm = v3add(wp, v3scale(ldir, 0.5 * seg));
        for (int i = 0; i < ob->n_planes; i++)
            if (vv_plane_distance(ob->planes[i], wm) < 0)
                return 0.0f;
    }
    return tile_ext(ob->whole_part, tile_sample(t, q)) * (float)seg;
}

/* volume_transmittance's march (rt_shade.c) from world point wp towards
 * the light, through the tile: each subvolume's piece cut into equal parts
 * no longer than the shadow step, sampled at their middles. */
static float
tile_march(const rt_frame *fr, const rt_vobj *ob, const lw_tile *tl, vv_vec3 wp, vv_vec3 ldir) {
    vv_vray r;
    if (!vray_setup(ob, &(vv_ray){wp, ldir}, 0, INFINITY, &r))
        return 1.0f;
    const double dt = fr->dt;
    const double ds = 2 * ob->vox > dt ? 2 * ob->vox : dt;
    double tau = 0;
    double t = r.t0;
    while (t < r.t1) {
        float p[3];
        vv_vray_point(&r, t, p);
        double te = block_exit(&r, p, t);
        te = te < r.t1 ? te : r.t1;
        const double len = te - t;
        int n = (int)vv_ceil_pos(len / ds);
        n = n < 1 ? 1 : n;
        const double h = len / n;
        for (int s = 0; s < n; s++) {
            float q[3];
            vv_vray_point(&r, t + (s + 0.5) * h, q);
            tau += tile_ext(ob->whole_part, tile_sample(tl, q)) * h;
        }
        if (tau > 5.6) /* T < 0.0037, under one 8-bit level */
            return 0.0f;
        t = te;
    }
    return (float)exp(-tau);
}

static inline vv_vec3
lw_index_to_world(const rt_vobj *ob, const double q[3]) {
    return v3(ob->i2w[0][0] * q[0] + ob->i2w[0][1] * q[1] + ob->i2w[0][2] * q[2] + ob->i2w[0][3],
              ob->i2w[1][0] * q[0] + ob->i2w[1][1] * q[1] + ob->i2w[1][2] * q[2] + ob->i2w[1][3],
              ob->i2w[2][0] * q[0] + ob->i2w[2][1] * q[1] + ob->i2w[2][2] * q[2] + ob->i2w[2][3]);
}

vv_status
rt_sweep_whole(const rt_frame *fr, const rt_vobj *ob, int l, int nt, float **out) {
    const rt_light *lt = &fr->lights[l];
    const vv_region_volume *wv = ob->whole;
    *out = NULL;
    const double G = RT_LGRID;
    const int *gd = ob->ldim;
    double li[3];
    for (int a = 0; a < 3; a++)
        li[a] =
            ob->w2i[a][0] * lt->dir[0] + ob->w2i[a][1] * lt->dir[1] + ob->w2i[a][2] * lt->dir[2];
    int A = 0;
    for (int a = 1; a < 3; a++)
        if (fabs(li[a]) > fabs(li[A]))
            A = a;
    if (!(fabs(li[A]) > 0))
        return VV_OK;
    const int B = (A + 1) % 3, Cc = (A + 2) % 3;
    const vv_vec3 ldir = v3(lt->dir[0], lt->dir[1], lt->dir[2]);
    const size_t ng = (size_t)gd[0] * (size_t)gd[1] * (size_t)gd[2];
    const double seg = G / fabs(li[A]);
    const int up = li[A] > 0 ? 1 : -1; /* the layer towards the light */
    const int first = up > 0 ? gd[A] - 1 : 0;
    const int nb = gd[B], nc = gd[Cc];
    /* tiles of TS cells a side (two of the reader's: fewer reads of the boxes' edges; a
     * multiple of the grid's spacing) */
    int TS = 2 * (wv->tile > 0 ? wv->tile : 64);
    TS = (TS + RT_LGRID - 1) / RT_LGRID * RT_LGRID;
    int ntile[3];
    for (int a = 0; a < 3; a++) {
        const int cells = ob->dims[a] - 1;
        ntile[a] = cells > 0 ? (cells + TS - 1) / TS : 1;
    }
    const int n = ntile[0] * ntile[1] * ntile[2];
    int *order = malloc(sizeof(int) * (size_t)n);
    int *rank = malloc(sizeof(int) * (size_t)n);
    float *T = calloc(ng ? ng : 1, sizeof *T);
    vv_vcache_set *set = malloc(sizeof *set);
    if (!order || !rank || !T || !set) {
        free(order);
        free(rank);
        free(T);
        free(set);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a light volume");
    }
    vv_vcache_set_init(set);
    /* the light's order: by the sum of each tile's distances, in tiles,
     * from the light's side of every axis (a counting sort, stable) */
    int maxr = 0;
    for (int i = 0; i < n; i++) {
        const int t[3] = {i % ntile[0], i / ntile[0] % ntile[1], i / (ntile[0] * ntile[1])};
        rank[i] = 0;
        for (int a = 0; a < 3; a++)
            rank[i] += li[a] > 0 ? ntile[a] - 1 - t[a] : t[a];
        maxr = rank[i] > maxr ? rank[i] : maxr;
    }
    int k = 0;
    for (int r = 0; r <= maxr; r++)
        for (int i = 0; i < n; i++)
            if (rank[i] == r)
                order[k++] = i;
    vv_status s = VV_OK;
    for (int oi = 0; oi < n && s == VV_OK; oi++) {
        const int i = order[oi];
        const int t[3] = {i % ntile[0], i / ntile[0] % ntile[1], i / (ntile[0] * ntile[1])};
        int g0[3], g1[3], lo[3], hi[3];
        int empty = 0;
        for (int a = 0; a < 3; a++) {
            const int last = t[a] == ntile[a] - 1, x0 = t[a] * TS;
            /* the grid points x0 <= id G < x0 + TS (the last tile: every one from x0) */
            g0[a] = (x0 + RT_LGRID - 1) / RT_LGRID;
            g1[a] = last ? gd[a] : (x0 + TS + RT_LGRID - 1) / RT_LGRID;
            empty |= g0[a] >= g1[a];
            /* its voxels, and those its samples reach towards the light */
            int v0 = x0, v1 = last ? ob->dims[a] - 1 : x0 + TS;
            if (li[a] > 0)
                v1 += RT_LGRID + 1;
            else if (li[a] < 0)
                v0 -= RT_LGRID + 1;
            else
                v1 += 1;
            lo[a] = v0 < 0 ? 0 : v0;
            hi[a] = v1 > ob->dims[a] - 1 ? ob->dims[a] - 1 : v1;
        }
        if (empty)
            continue;
        vv_volume *box = NULL;
        vv_vcache *c = NULL;
        s = wv->read_box(wv->user, lo, hi, &box);
        if (s == VV_OK)
            s = vv_vcache_get(set, box, &c);
        if (s != VV_OK) {
            vv_volume_free(box);
            break;
        }
        const lw_tile tl = {c, {(float)lo[0], (float)lo[1], (float)lo[2]}};
        const int nlay = g1[A] - g0[A];
        const int bw = g1[B] - g0[B], cw = g1[Cc] - g0[Cc];
        for (int m = 0; m < nlay; m++) {
            const int la = up > 0 ? g1[A] - 1 - m : g0[A] + m;
#pragma omp parallel for schedule(dynamic, 16) num_threads(nt)
            for (int bc = 0; bc < bw * cw; bc++) {
                int id[3];
                id[A] = la;
                id[B] = g0[B] + bc % bw;
                id[Cc] = g0[Cc] + bc / bw;
                const double p[3] = {id[0] * G, id[1] * G, id[2] * G};
                const vv_vec3 wp = lw_index_to_world(ob, p);
                float tv = -1;
                if (la != first) {
                    const double qb = (p[B] + li[B] * seg) / G, qc = (p[Cc] + li[Cc] * seg) / G;
                    if (qb >= 0 && qb <= nb - 1 && qc >= 0 && qc <= nc - 1) {
                        int ib = (int)qb, ic = (int)qc;
                        ib = ib > nb - 2 ? nb - 2 : ib;
                        ic = ic > nc - 2 ? nc - 2 : ic;
                        const float fb = (float)(qb - ib), fc = (float)(qc - ic);
                        float v[4];
                        for (int q = 0; q < 4; q++) {
                            int at[3];
                            at[A] = la + up;
                            at[B] = ib + (q & 1);
                            at[Cc] = ic + (q >> 1);
                            v[q] =
                                T[((size_t)at[2] * (size_t)gd[1] + (size_t)at[1]) * (size_t)gd[0] +
                                  (size_t)at[0]];
                        }
                        const float tq =
                            vv_lerpf(vv_lerpf(v[0], v[1], fb), vv_lerpf(v[2], v[3], fb), fc);
                        tv = tq <= 0 ? 0.0f : tq * expf(-tile_depth(ob, &tl, p, li, seg, wp, ldir));
                    }
                }
                if (tv < 0)
                    tv = tile_march(fr, ob, &tl, wp, ldir);
                T[((size_t)id[2] * (size_t)gd[1] + (size_t)id[1]) * (size_t)gd[0] + (size_t)id[0]] =
                    tv;
            }
        }
        vv_vcache_set_clear(set);
        vv_volume_free(box);
    }
    vv_vcache_set_clear(set);
    free(set);
    free(order);
    free(rank);
    if (s != VV_OK) {
        free(T);
        return s;
    }
    *out = T;
    return VV_OK;
}
