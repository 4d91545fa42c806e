/*
 * Volumetric ray tracing: the sweeps of light volumes and swept shadow
 * grids, from a volume in memory or, for a region render's context, tile
 * by tile through the whole volume (vv_render_region.whole) rather than
 * through the World's coarse proxy, so that the shadows of a volume
 * rendered brick by brick out of core are those of the in-memory render.
 * rt_shade.c looks them up.
 *
 * A light volume holds, every RT_LGRID voxels, the
 * transmittance towards a directional light or the mean extinction of the
 * way to a point light. Each point's value is computed from points one
 * grid layer nearer the light (bilinear in that layer) and one sample of
 * its own segment; points whose way to the light leaves the grid march to
 * the volume's face. Every value therefore depends only on points and
 * voxels towards the light. Here the grid is cut into tiles (two of the
 * reader's boxes a side), swept one after another in the light's order:
 * - a tile comes after every tile towards the light on some axis and not
 *   away from it on another, i.e. by the sum of its distances in tiles from
 *   the light's side of every axis (a directional light) or from the
 *   light's own tile (a point light, the tiles centred on it so that no
 *   point's way to it crosses a tile face towards the light's far side);
 * - within a tile, a directional light's points go layer by layer from its
 *   side (sweep_grid), a point light's in order of their L-infinity
 *   distance to it (sweep_point), those of one layer or distance at once;
 * - a tile's samples come from one box of voxels: the tile's own and, on
 *   the light's side of each axis, the three more its samples reach (two
 *   towards the light and the trilinear neighbour).
 * In memory the whole grid is one tile, sampled from the volume's own
 * cache, and a swept shadow grid (shadow_grid=2, every RT_SGRID voxels)
 * goes the same way with each segment's transmittance through every object
 * that casts shadows. Through tiles the values are the in-memory sweep's:
 * the same points in an order that
 * respects the same dependencies, the same sample positions and tables
 * (the region part's, built from voxels of the same type and value range);
 * the marches step through every subvolume rather than leaping over empty
 * ones, which adds zeros. On the CT head the light volumes came out bit for
 * bit those of the in-memory render (five directional lights, four point
 * lights inside and outside the volume).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/raytrace/rt_internal.h"
#include "render/sample.h"

/* 1 when light volumes of @p n_vol volumes of @p h's dims fit in half the
 * memory available (counting those the frame's earlier regions already
 * keep, so that every region of a frame decides alike). */
static int
light_volumes_fit(const rt_frame *fr, const vv_volume *h, int n_vol) {
    uint64_t points = 1;
    for (int a = 0; a < 3; a++)
        points *= (uint64_t)((h->dims[a] - 1 + RT_LGRID - 1) / RT_LGRID + 1);
    const uint64_t one = points * sizeof(float);
    uint64_t avail = vv_memory_available();
    for (int i = 0; i < RT_LV_CACHE && avail < UINT64_MAX - one; i++)
        if (fr->st->lv[i].vol && fr->st->lv[i].whole == h)
            avail += one;
    return one * (uint64_t)fr->n_lights * (uint64_t)n_vol <= avail / 2;
}

/* rt_context_whole of a multi-channel region part (the composite rule):
 * the k-th channel of the World's object (a context) casts its shadows
 * through its channel's whole volume (region->channel_whole), classified
 * by the part's k-th channel. */
static int
context_whole_channels(rt_frame *fr, const vv_render_region *region) {
    const rt_vobj *p0 = &fr->vobjs[0];
    const vv_object *obj = fr->w->objects[region->object];
    int drawn[VV_MAX_CHANNELS], n = 0;
    for (int k = 0; k < obj->n_channels && n < VV_MAX_CHANNELS; k++)
        if (obj->channels[k].visible && obj->channels[k].volume)
            drawn[n++] = k;
    if (n != p0->gn || n < 1)
        return 0;
    for (int k = 0; k < n; k++) {
        const vv_volume *h = region->channel_whole[drawn[k]].header;
        if (!h || !region->channel_whole[drawn[k]].read_box)
            return 0;
        for (int a = 0; a < 3; a++)
            if (h->dims[a] != region->dims[a] || h->dims[a] < 2)
                return 0;
    }
    if (!light_volumes_fit(fr, region->channel_whole[drawn[0]].header, n))
        return 0;
    int any = 0, k = 0;
    for (int i = n; i < fr->n_vobj && k < n; i++) {
        rt_vobj *ro = &fr->vobjs[i];
        if (!ro->context || ro->group < 0)
            continue;
        const rt_vobj *part = &fr->vobjs[k];
        const vv_region_volume *wv = &region->channel_whole[drawn[k++]];
        if (ro->mode != VV_MODE_COMPOSITE || !ro->obj->casts_shadows ||
            part->mode != VV_MODE_COMPOSITE)
            continue;
        memcpy(ro->w2i, part->w2i, sizeof ro->w2i);
        memcpy(ro->i2w, part->i2w, sizeof ro->i2w);
        memcpy(ro->dims, part->dims, sizeof ro->dims);
        ro->vox = part->vox;
        ro->whole = wv;
        ro->whole_part = part;
        any = 1;
    }
    return any;
}

int
rt_context_whole(rt_frame *fr, const vv_render_region *region) {
    if (!region || !fr->shadows || !fr->st->light_volumes || fr->st->shadow_grid == 2 ||
        fr->n_vobj < 1)
        return 0;
    for (int l = 0; l < fr->n_lights; l++)
        if (fr->lights[l].point &&
            !(isfinite(fr->lights[l].pos[0]) && isfinite(fr->lights[l].pos[1]) &&
              isfinite(fr->lights[l].pos[2])))
            return 0;
    if (region->channel_whole && fr->vobjs[0].region && fr->vobjs[0].group >= 0)
        return context_whole_channels(fr, region);
    if (!region->whole || !region->whole->read_box)
        return 0;
    const rt_vobj *part = &fr->vobjs[0]; /* prepare_frame: the region part first */
    const vv_volume *h = region->whole->header;
    if (!part->region || part->mode != VV_MODE_COMPOSITE || part->group >= 0 || !h)
        return 0;
    for (int a = 0; a < 3; a++)
        if (h->dims[a] != region->dims[a] || h->dims[a] < 2)
            return 0;
    /* the light volumes (4 bytes every RT_LGRID^3 voxels a light) are held
     * whole: past half the memory available, the proxy's */
    if (!light_volumes_fit(fr, h, 1))
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

/* Where a sweep samples the volume: the whole volume in memory (its own
 * cache, subvolume flags and tables), or a tile of a region render's whole
 * volume (a box's cache, the index of its voxel (0, 0, 0), the region
 * part's tables, no subvolume flags). */
typedef struct lw_tile {
    const vv_vcache *c;
    float o[3];
    const uint8_t *bvis; /* the volume's own (in memory), else NULL */
    const rt_vobj *tab;  /* whose tables classify the samples */
} lw_tile;

static inline float
tile_sample(const lw_tile *t, const float q[3]) {
    const float x[3] = {q[0] - t->o[0], q[1] - t->o[1], q[2] - t->o[2]};
    return vv_vcache_sample(t->c, x);
}

static inline float
tile_ext(const lw_tile *t, float v) {
    return t->tab->ext[(int)vv_vtables_index(&t->tab->tab, v)];
}

/* A composite volume's own optical depth over the segment of world length
 * seg from index point p (world wp) along the index direction li (world
 * direction ldir): one sample at its middle, sigma seg; 0 where the middle
 * is outside the volume, cut away or (in memory) in a subvolume that
 * cannot contribute, whose samples all have sigma 0. */
static float
tile_depth(const rt_vobj *ob, const lw_tile *t, const double p[3], const double li[3], double seg,
           vv_vec3 wp, vv_vec3 ldir) {
    float q[3];
    for (int a = 0; a < 3; a++) {
        q[a] = (float)(p[a] + li[a] * seg * 0.5);
        if (!(q[a] >= 0 && q[a] <= (float)(ob->dims[a] - 1)))
            return 0.0f;
    }
    if (!t->c || (t->bvis && !t->bvis[vv_vcache_block(t->c, q)]))
        return 0.0f; /* an empty tile (no voxels read), or an empty subvolume */
    if (ob->n_planes) {
        const vv_vec3 wm = v3add(wp, v3scale(ldir, 0.5 * seg));
        for (int i = 0; i < ob->n_planes; i++)
            if (vv_plane_distance(ob->planes[i], wm) < 0)
                return 0.0f;
    }
    return tile_ext(t, tile_sample(t, q)) * (float)seg;
}

/* The volume's own transmittance from world point wp towards the light
 * over (0, tmax): in memory its shadow march (rt_volume_march); through a
 * tile the same march (each subvolume's piece cut into equal parts no
 * longer than the shadow step, sampled at their middles), stepping through
 * every subvolume rather than leaping over empty ones, which adds zeros. */
static float
tile_march(const rt_frame *fr, const rt_vobj *ob, const lw_tile *tl, vv_vec3 wp, vv_vec3 ldir,
           double tmax) {
    if (!tl->c) /* an empty tile: exp(-0) */
        return 1.0f;
    if (tl->bvis)
        return rt_volume_march(fr, ob, wp, ldir, tmax);
    vv_vray r;
    if (!vray_setup(ob, &(vv_ray){wp, ldir}, 0, tmax, &r))
        return 1.0f;
    return rt_composite_march(fr, ob, &r, tl->c, tl->o, tl->tab);
}

/* What the tiles of one light's sweep share. */
typedef struct lw_sweep {
    const rt_frame *fr;
    const rt_vobj *ob;
    const rt_light *lt;
    int nt;
    double G;      /* grid spacing, voxels */
    const int *gd; /* grid points per axis */
    float *T;      /* the grid */
    int own;       /* the volume's own light volume; 0: a shadow grid through every object that
                      casts shadows (rt_shadow_segment) */
    /* a directional light (sweep_grid): its index-space direction per world
     * unit, the axis it is most along and the two others, the layer
     * towards it, the first layer, a layer's segment */
    double li[3], seg;
    int A, B, Cc, up, first;
    vv_vec3 ldir;
    /* a point light (sweep_point): its position in grid units */
    double Lg[3];
} lw_sweep;

/* The tile's points of a directional light, layer by layer from the light's
 * side: sweep_grid's values. */
static void
tile_directional(const lw_sweep *w, const lw_tile *tl, const int g0[3], const int g1[3]) {
    const double G = w->G;
    const int *gd = w->gd, A = w->A, B = w->B, Cc = w->Cc, up = w->up;
    const int nb = gd[B], nc = gd[Cc];
    const int nlay = g1[A] - g0[A], bw = g1[B] - g0[B], cw = g1[Cc] - g0[Cc];
    for (int m = 0; m < nlay; m++) {
        const int la = up > 0 ? g1[A] - 1 - m : g0[A] + m;
#pragma omp parallel for schedule(dynamic, 16) num_threads(w->nt)
        for (int bc = 0; bc < bw * cw; bc++) {
            int id[3];
            id[A] = la;
            id[B] = g0[B] + bc % bw;
            id[Cc] = g0[Cc] + bc / bw;
            const double p[3] = {id[0] * G, id[1] * G, id[2] * G};
            const vv_vec3 wp = rt_index_to_world(w->ob, p);
            float tv = -1;
            if (la != w->first) {
                const double qb = (p[B] + w->li[B] * w->seg) / G,
                             qc = (p[Cc] + w->li[Cc] * w->seg) / G;
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
                            w->T[((size_t)at[2] * (size_t)gd[1] + (size_t)at[1]) * (size_t)gd[0] +
                                 (size_t)at[0]];
                    }
                    const float tq =
                        vv_lerpf(vv_lerpf(v[0], v[1], fb), vv_lerpf(v[2], v[3], fb), fc);
                    tv = tq <= 0  ? 0.0f
                         : w->own ? tq * expf(-tile_depth(w->ob, tl, p, w->li, w->seg, wp, w->ldir))
                                  : tq * rt_shadow_segment(w->fr, wp, w->lt, 0, w->seg);
                }
            }
            if (tv < 0)
                tv = w->own ? tile_march(w->fr, w->ob, tl, wp, w->ldir, INFINITY)
                            : rt_shadow_segment(w->fr, wp, w->lt, 0, INFINITY);
            w->T[((size_t)id[2] * (size_t)gd[1] + (size_t)id[1]) * (size_t)gd[0] + (size_t)id[0]] =
                tv;
        }
    }
}

/* One point of a point light's light volume from the tile: point_lv_value
 * (rt_shade.c), the mean extinction of its way to the light. */
static float
tile_point_value(const lw_sweep *w, const lw_tile *tl, const int id[3]) {
    const double G = w->G;
    const rt_vobj *ob = w->ob;
    const int *gd = w->gd;
    const double p[3] = {id[0] * G, id[1] * G, id[2] * G};
    const vv_vec3 wp = rt_index_to_world(ob, p);
    const vv_vec3 to = v3sub(v3(w->lt->pos[0], w->lt->pos[1], w->lt->pos[2]), wp);
    const double dist = v3len(to);
    if (!(dist > 0))
        return 0.0f;
    const vv_vec3 ldir = v3scale(to, 1 / dist);
    double d[3];
    int A = 0;
    for (int a = 0; a < 3; a++) {
        d[a] = w->Lg[a] - id[a];
        if (fabs(d[a]) > fabs(d[A]))
            A = a;
    }
    const double k = fabs(d[A]);
    double li[3];
    for (int a = 0; a < 3; a++)
        li[a] = d[a] * G / dist;
    double tau;
    const int B = (A + 1) % 3, Cc = (A + 2) % 3;
    const int la = id[A] + (d[A] > 0 ? 1 : -1);
    const double qb = id[B] + d[B] / (k > 0 ? k : 1), qc = id[Cc] + d[Cc] / (k > 0 ? k : 1);
    if (k <= 1) { /* the light is within a layer: the segment to it */
        tau = tile_depth(ob, tl, p, li, dist, wp, ldir);
    } else if (la < 0 || la > gd[A] - 1 || !(qb >= 0 && qb <= gd[B] - 1) ||
               !(qc >= 0 && qc <= gd[Cc] - 1)) {
        const float T = tile_march(w->fr, ob, tl, wp, ldir, dist);
        tau = T > 0 ? -log(T) : INFINITY;
    } else {
        const int ib = (int)qb, ic = (int)qc;
        const float fb = (float)(qb - ib), fc = (float)(qc - ic);
        float v[4] = {0, 0, 0, 0};
        for (int m = 0; m < 4; m++) {
            if (((m & 1) && fb == 0) || ((m >> 1) && fc == 0))
                continue;
            int q[3];
            q[A] = la;
            q[B] = ib + (m & 1);
            q[Cc] = ic + (m >> 1);
            v[m] =
                w->T[((size_t)q[2] * (size_t)gd[1] + (size_t)q[1]) * (size_t)gd[0] + (size_t)q[0]];
        }
        const double seg = dist / k;
        for (int m = 0; m < 4; m++)
            v[m] = expf(-v[m] * (float)(dist - seg));
        const double tq = vv_lerpf(vv_lerpf(v[0], v[1], fb), vv_lerpf(v[2], v[3], fb), fc);
        tau = (tq > 0 ? -log(tq) : INFINITY) + tile_depth(ob, tl, p, li, seg, wp, ldir);
    }
    const double sv = tau / dist;
    return (float)(sv < FLT_MAX ? sv : FLT_MAX);
}

/* Sorts n (key, index) pairs by key (non-negative doubles, whose bits
 * order as unsigned integers): least significant digit first, 16 bits a
 * pass. tmp: room for n more. Returns 0 when out of memory. */
typedef struct rt_kidx {
    uint64_t key;
    uint32_t idx;
} rt_kidx;

static int
radix_sort(rt_kidx *a, rt_kidx *tmp, size_t n) {
    size_t *count = malloc(65536 * sizeof *count);
    if (!count)
        return 0;
    for (int pass = 0; pass < 4; pass++) {
        const int shift = 16 * pass;
        memset(count, 0, 65536 * sizeof *count);
        for (size_t i = 0; i < n; i++)
            count[(a[i].key >> shift) & 0xFFFF]++;
        size_t sum = 0;
        for (int d = 0; d < 65536; d++) {
            const size_t c = count[d];
            count[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            tmp[count[(a[i].key >> shift) & 0xFFFF]++] = a[i];
        rt_kidx *t = a;
        a = tmp;
        tmp = t;
    }
    free(count); /* four passes: the result is back in the caller's array */
    return 1;
}

/* The tile's points of a point light in order of their distance to it in
 * the grid's L-infinity norm (sweep_point), those of one distance at once. */
static vv_status
tile_point(const lw_sweep *w, const lw_tile *tl, const int g0[3], const int g1[3]) {
    const int *gd = w->gd;
    const size_t bw = (size_t)(g1[0] - g0[0]), bh = (size_t)(g1[1] - g0[1]),
                 n = bw * bh * (size_t)(g1[2] - g0[2]);
    if (n > UINT32_MAX)
        return vv_error_set(VV_ERR_LIMIT, "a light volume tile of %zu points", n);
    rt_kidx *ord = malloc(2 * (n ? n : 1) * sizeof *ord);
    if (!ord)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a light volume");
#pragma omp parallel for schedule(static) num_threads(w->nt)
    for (size_t i = 0; i < n; i++) {
        const double x = (double)(g0[0] + (int)(i % bw)), y = (double)(g0[1] + (int)(i / bw % bh)),
                     z = (double)(g0[2] + (int)(i / (bw * bh)));
        double k = fabs(w->Lg[0] - x);
        k = fmax(k, fabs(w->Lg[1] - y));
        k = fmax(k, fabs(w->Lg[2] - z));
        uint64_t bits;
        memcpy(&bits, &k, sizeof bits);
        ord[i].key = bits;
        ord[i].idx = (uint32_t)i;
    }
    if (!radix_sort(ord, ord + n, n)) {
        free(ord);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a light volume");
    }
    for (size_t s0 = 0; s0 < n;) {
        size_t s1 = s0 + 1;
        while (s1 < n && ord[s1].key == ord[s0].key)
            s1++;
#pragma omp parallel for schedule(dynamic, 64) num_threads(w->nt) if (s1 - s0 >= 256)
        for (size_t i = s0; i < s1; i++) {
            const size_t j = ord[i].idx;
            const int id[3] = {g0[0] + (int)(j % bw), g0[1] + (int)(j / bw % bh),
                               g0[2] + (int)(j / (bw * bh))};
            w->T[((size_t)id[2] * (size_t)gd[1] + (size_t)id[1]) * (size_t)gd[0] + (size_t)id[0]] =
                tile_point_value(w, tl, id);
        }
        s0 = s1;
    }
    free(ord);
    return VV_OK;
}

/* floor(a / b) for b > 0 */
static inline long
floor_div(long a, long b) {
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/* Sets up @p w for light l over the grid of G voxels a side, gd points an
 * axis; 0 when there is nothing to sweep (a directional light along no
 * axis of the index space; a point light at no finite position). */
static int
lw_setup(lw_sweep *w, const rt_frame *fr, const rt_vobj *ob, int l, int nt, double G, const int *gd,
         int own) {
    memset(w, 0, sizeof *w);
    w->fr = fr;
    w->ob = ob;
    w->lt = &fr->lights[l];
    w->nt = nt;
    w->G = G;
    w->gd = gd;
    w->own = own;
    if (w->lt->point) {
        for (int a = 0; a < 3; a++)
            w->Lg[a] = (ob->w2i[a][0] * w->lt->pos[0] + ob->w2i[a][1] * w->lt->pos[1] +
                        ob->w2i[a][2] * w->lt->pos[2] + ob->w2i[a][3]) /
                       G;
        return isfinite(w->Lg[0]) && isfinite(w->Lg[1]) && isfinite(w->Lg[2]);
    }
    for (int a = 0; a < 3; a++)
        w->li[a] = ob->w2i[a][0] * w->lt->dir[0] + ob->w2i[a][1] * w->lt->dir[1] +
                   ob->w2i[a][2] * w->lt->dir[2];
    for (int a = 1; a < 3; a++)
        if (fabs(w->li[a]) > fabs(w->li[w->A]))
            w->A = a;
    if (!(fabs(w->li[w->A]) > 0))
        return 0;
    w->B = (w->A + 1) % 3;
    w->Cc = (w->A + 2) % 3;
    w->ldir = v3(w->lt->dir[0], w->lt->dir[1], w->lt->dir[2]);
    w->seg = G / fabs(w->li[w->A]);
    w->up = w->li[w->A] > 0 ? 1 : -1;
    w->first = w->up > 0 ? gd[w->A] - 1 : 0;
    return 1;
}

/* 1 when the reader knows the values of voxels lo .. hi and the region
 * part's tables give every value between them (an entry either side for
 * the rounding of a trilinear sample) no extinction. */
static int
box_transparent(const vv_region_volume *wv, const rt_vobj *pt, const int lo[3], const int hi[3]) {
    float vmin, vmax;
    if (!wv->box_range || !wv->box_range(wv->user, lo, hi, &vmin, &vmax) || !(vmin <= vmax))
        return 0;
    const float q = (float)pt->c->qoff; /* data units to stored ones */
    int e0 = (int)vv_vtables_index(&pt->tab, vmin - q) - 1,
        e1 = (int)vv_vtables_index(&pt->tab, vmax - q) + 1;
    e0 = e0 < 0 ? 0 : e0;
    e1 = e1 > VV_VC_LUT - 1 ? VV_VC_LUT - 1 : e1;
    for (int e = e0; e <= e1; e++)
        if (pt->ext[e] != 0)
            return 0;
    return 1;
}

/* The whole grid at once from the volume in memory: one tile, its own
 * cache, subvolume flags and tables. */
static vv_status
sweep_memory(lw_sweep *w, float **out) {
    const int *gd = w->gd;
    const size_t ng = (size_t)gd[0] * (size_t)gd[1] * (size_t)gd[2];
    if (w->lt->point && ng > UINT32_MAX)
        return VV_OK; /* shadow rays then march */
    w->T = calloc(ng ? ng : 1, sizeof *w->T);
    if (!w->T)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a %s",
                            w->own ? "light volume" : "shadow grid");
    const lw_tile tile = {w->ob->c, {0, 0, 0}, w->ob->bvis, w->ob};
    const int g0[3] = {0, 0, 0};
    vv_status s = VV_OK;
    if (w->lt->point)
        s = tile_point(w, &tile, g0, gd);
    else
        tile_directional(w, &tile, g0, gd);
    if (s != VV_OK) {
        free(w->T);
        return s;
    }
    *out = w->T;
    return VV_OK;
}

/* The grid tile by tile through a region render's whole volume, read by
 * boxes (w->ob->whole), in the light's order. */
static vv_status
sweep_tiles(lw_sweep *w, float **out) {
    const rt_vobj *ob = w->ob;
    const vv_region_volume *wv = ob->whole;
    const int *gd = w->gd;
    const int point = w->lt->point;
    const double G = w->G;
    double L[3]; /* the light in voxel units, where the tiles centre on it */
    for (int a = 0; a < 3; a++)
        L[a] = w->Lg[a] * G;
    /* tiles of TS cells a side (two of the reader's: fewer reads of the
     * boxes' edges; a multiple of the grid's spacing), from off on each
     * axis: 0 for a directional light (the reader's own boxes); centred on
     * a point light, so that no point's way to it crosses a tile face
     * towards the light's far side */
    int TS = 2 * (wv->tile > 0 ? wv->tile : 64);
    TS = (TS + RT_LGRID - 1) / RT_LGRID * RT_LGRID;
    long off[3];
    int ntile[3], tl[3];
    for (int a = 0; a < 3; a++) {
        off[a] = 0;
        if (point && fabs(L[a]) < 1e9) {
            const long c = (long)floor(L[a]) - TS / 2;
            off[a] = c - floor_div(c, TS) * TS; /* in 0 .. TS - 1 */
            off[a] = off[a] > 0 ? off[a] - TS : 0;
            off[a] = (off[a] / RT_LGRID) * RT_LGRID; /* tiles start on grid points */
        }
        /* tiles over the cells, the last one taking the grid's points past
         * the last voxel too */
        const long span = (long)(ob->dims[a] - 1) - off[a];
        ntile[a] = span > 0 ? (int)((span + TS - 1) / TS) : 1;
        if (point) { /* the light's tile (the nearest one when outside) */
            long t = fabs(L[a]) < 1e9 ? floor_div((long)floor(L[a]) - off[a], TS)
                                      : (L[a] < 0 ? 0 : ntile[a] - 1);
            tl[a] = (int)(t < 0 ? 0 : t > ntile[a] - 1 ? ntile[a] - 1 : t);
        }
    }
    const size_t ng = (size_t)gd[0] * (size_t)gd[1] * (size_t)gd[2];
    const int n = ntile[0] * ntile[1] * ntile[2];
    int *order = malloc(sizeof(int) * (size_t)n);
    int *rank = malloc(sizeof(int) * (size_t)n);
    w->T = calloc(ng ? ng : 1, sizeof *w->T);
    vv_vcache_set *set = malloc(sizeof *set);
    if (!order || !rank || !w->T || !set) {
        free(order);
        free(rank);
        free(w->T);
        free(set);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a light volume");
    }
    vv_vcache_set_init(set);
    /* the light's order: by the sum of each tile's distances, in tiles,
     * from the light's side of every axis (a directional light) or from the
     * light's tile (a point light; a counting sort, stable) */
    int maxr = 0;
    for (int i = 0; i < n; i++) {
        const int t[3] = {i % ntile[0], i / ntile[0] % ntile[1], i / (ntile[0] * ntile[1])};
        rank[i] = 0;
        for (int a = 0; a < 3; a++)
            rank[i] += point ? abs(t[a] - tl[a]) : w->li[a] > 0 ? ntile[a] - 1 - t[a] : t[a];
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
            const int last = t[a] == ntile[a] - 1;
            const long x0 = off[a] + (long)t[a] * TS, x1 = x0 + TS;
            /* the grid points x0 <= id G < x1 (the last tile: every one from x0) */
            g0[a] = x0 > 0 ? (int)((x0 + RT_LGRID - 1) / RT_LGRID) : 0;
            g1[a] = last ? gd[a] : (int)((x1 + RT_LGRID - 1) / RT_LGRID);
            g1[a] = g1[a] < gd[a] ? g1[a] : gd[a];
            empty |= g0[a] >= g1[a];
            /* its voxels, and those its samples reach towards the light */
            long v0 = x0 > 0 ? x0 : 0, v1 = last ? ob->dims[a] - 1 : x1;
            const int reach = RT_LGRID + 1;
            if (point) {
                if (L[a] >= v0)
                    v1 += reach;
                if (L[a] <= v1)
                    v0 -= reach;
            } else if (w->li[a] > 0) {
                v1 += reach;
            } else if (w->li[a] < 0) {
                v0 -= reach;
            } else {
                v1 += 1;
            }
            /* within the volume, and at least its last cell for a tile of
             * the grid's points past it (their samples clamp to it) */
            lo[a] = (int)(v0 < 0 ? 0 : v0 > ob->dims[a] - 2 ? ob->dims[a] - 2 : v0);
            hi[a] = (int)(v1 > ob->dims[a] - 1 ? ob->dims[a] - 1 : v1);
            hi[a] = hi[a] > lo[a] ? hi[a] : lo[a] + 1;
        }
        if (empty)
            continue;
        vv_volume *box = NULL;
        vv_vcache *c = NULL;
        /* a box whose values the transfer function shows as empty is not
         * read: every segment through it has optical depth 0 */
        if (!box_transparent(wv, ob->whole_part, lo, hi)) {
            s = wv->read_box(wv->user, lo, hi, &box);
            if (s == VV_OK)
                s = vv_vcache_get(set, box, &c);
        }
        if (s == VV_OK) {
            const lw_tile tile = {
                c, {(float)lo[0], (float)lo[1], (float)lo[2]}, NULL, ob->whole_part};
            if (point)
                s = tile_point(w, &tile, g0, g1);
            else
                tile_directional(w, &tile, g0, g1);
        }
        vv_vcache_set_clear(set);
        vv_volume_free(box);
    }
    free(set);
    free(order);
    free(rank);
    if (s != VV_OK) {
        free(w->T);
        return s;
    }
    *out = w->T;
    return VV_OK;
}

vv_status
rt_sweep_light_volume(const rt_frame *fr, const rt_vobj *ob, int l, int nt, float **out) {
    *out = NULL;
    lw_sweep w;
    if (!lw_setup(&w, fr, ob, l, nt, RT_LGRID, ob->ldim, 1))
        return VV_OK;
    return ob->whole ? sweep_tiles(&w, out) : sweep_memory(&w, out);
}

vv_status
rt_sweep_shadow_grid(const rt_frame *fr, const rt_vobj *ob, int l, int nt, float **out) {
    *out = NULL;
    lw_sweep w;
    if (fr->lights[l].point || !lw_setup(&w, fr, ob, l, nt, RT_SGRID, ob->gdim, 0))
        return VV_OK;
    return sweep_memory(&w, out);
}
