/*
 * Splatting, bands (splat_internal.h): one band of image rows rendered on
 * its own: sheet buffers, post-classification and shading of sheet
 * samples, front-to-back compositing, projections, the occlusion map.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "core/internal.h"
#include "render/splat/splat_internal.h"

/* ---------------------------------------------------------------------- */
/* Bands                                                                    */

/* Per-pixel data of one band. */
typedef struct sp_band {
    int y0, y1, W, n;
    float *buf;         /* SP_CH planes of n */
    float *wrow;        /* one row of footprint weights */
    size_t ps;          /* plane stride: n plus slack for 4-wide rows */
    float *C, *A, *D;   /* colour (3 a pixel), opacity, depth (ray parameter) */
    float *P, *PA, *PD; /* projections: colour (3), opacity, depth */
    int *k0, *k1;       /* per object (n_obj x n): sheets inside the pixel's ray */
    int *kend;          /* the last sheet of any composite object on the pixel's ray */
    float *cosv;        /* forward . ray direction */
    float *vdir;        /* towards the eye, 3 a pixel */
    float *rdir;        /* ray direction (3) and origin (3) a pixel, for world points */
    uint8_t *done;      /* pixel needs nothing more (occlusion map) */
    uint16_t *tcount;   /* finished pixels per tile */
    uint16_t *tcap;     /* pixels per tile */
    int tw, th;         /* tiles across, down */
} sp_band;

static inline void
mark_done(sp_band *bd, int x, int yl) {
    const int pi = yl * bd->W + x;
    if (bd->done[pi])
        return;
    bd->done[pi] = 1;
    bd->tcount[(yl / SP_TILE) * bd->tw + x / SP_TILE]++;
}

/* The box [x0, x1] x [y0, y1] (pixels) covers only finished tiles. */
static inline int
occluded_box(const sp_band *bd, double x0, double x1, double y0, double y1) {
    x0 = x0 < -1 ? -1 : x0;
    y0 = y0 < -1 ? -1 : y0;
    x1 = x1 > bd->W ? bd->W : x1;
    y1 = y1 > bd->y1 ? bd->y1 : y1;
    int xa = (int)x0, xb = (int)x1 + 1;
    int ya = (int)y0 - bd->y0, yb = (int)y1 + 1 - bd->y0;
    xa = xa < 0 ? 0 : xa;
    xb = xb > bd->W - 1 ? bd->W - 1 : xb;
    ya = ya < 0 ? 0 : ya;
    yb = yb > bd->y1 - bd->y0 - 1 ? bd->y1 - bd->y0 - 1 : yb;
    if (xa > xb || ya > yb)
        return 1;
    for (int ty = ya / SP_TILE; ty <= yb / SP_TILE; ty++)
        for (int tx = xa / SP_TILE; tx <= xb / SP_TILE; tx++)
            if (bd->tcount[ty * bd->tw + tx] < bd->tcap[ty * bd->tw + tx])
                return 0;
    return 1;
}

static void
band_free(sp_band *bd) {
    free(bd->buf);
    free(bd->C);
    free(bd->k0);
    free(bd->cosv);
    free(bd->done);
    free(bd->tcount);
}

static vv_status
band_init(const sp_frame *fr, sp_band *bd, int band) {
    memset(bd, 0, sizeof *bd);
    bd->W = fr->view->width;
    bd->y0 = band * fr->band_h;
    bd->y1 = bd->y0 + fr->band_h < fr->view->height ? bd->y0 + fr->band_h : fr->view->height;
    const int n = bd->n = bd->W * (bd->y1 - bd->y0);
    const int no = fr->n_obj ? fr->n_obj : 1;
    bd->tw = (bd->W + SP_TILE - 1) / SP_TILE;
    bd->th = (bd->y1 - bd->y0 + SP_TILE - 1) / SP_TILE;
    bd->ps = (size_t)n + 8;
    bd->buf = calloc(bd->ps * SP_CH + (size_t)bd->W + 8, sizeof(float));
    bd->wrow = bd->buf ? bd->buf + bd->ps * SP_CH : NULL;
    bd->C = malloc((size_t)n * 10 * sizeof(float));
    bd->k0 = malloc((size_t)n * (2 * (size_t)no + 1) * sizeof(int));
    bd->cosv = malloc((size_t)n * 10 * sizeof(float));
    bd->done = calloc((size_t)n, 1);
    bd->tcount = calloc((size_t)bd->tw * (size_t)bd->th * 2, sizeof(uint16_t));
    if (!bd->buf || !bd->C || !bd->k0 || !bd->cosv || !bd->done || !bd->tcount) {
        band_free(bd);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for an image band");
    }
    bd->A = bd->C + 3 * (size_t)n;
    bd->D = bd->A + n;
    bd->P = bd->D + n;
    bd->PA = bd->P + 3 * (size_t)n;
    bd->PD = bd->PA + n;
    bd->k1 = bd->k0 + (size_t)n * (size_t)no;
    bd->kend = bd->k1 + (size_t)n * (size_t)no;
    bd->vdir = bd->cosv + n;
    bd->rdir = bd->vdir + 3 * (size_t)n;
    bd->tcap = bd->tcount + (size_t)bd->tw * (size_t)bd->th;
    for (int ty = 0; ty < bd->th; ty++)
        for (int tx = 0; tx < bd->tw; tx++) {
            const int w = bd->W - tx * SP_TILE < SP_TILE ? bd->W - tx * SP_TILE : SP_TILE;
            const int h =
                bd->y1 - bd->y0 - ty * SP_TILE < SP_TILE ? bd->y1 - bd->y0 - ty * SP_TILE : SP_TILE;
            bd->tcap[ty * bd->tw + tx] = (uint16_t)(w * h);
        }
    for (int i = 0; i < n; i++) {
        bd->C[3 * i] = bd->C[3 * i + 1] = bd->C[3 * i + 2] = 0;
        bd->A[i] = 0;
        bd->D[i] = INFINITY;
        bd->P[3 * i] = bd->P[3 * i + 1] = bd->P[3 * i + 2] = 0;
        bd->PA[i] = 0;
        bd->PD[i] = INFINITY;
    }
    /* rays, as the ray caster makes them */
    for (int yl = 0; yl < bd->y1 - bd->y0; yl++)
        for (int x = 0; x < bd->W; x++) {
            const int pi = yl * bd->W + x;
            const double fx = x, fy = bd->y0 + yl;
            vv_ray wr;
            wr.origin.x = fr->o00.x + fx * fr->ox.x + fy * fr->oy.x;
            wr.origin.y = fr->o00.y + fx * fr->ox.y + fy * fr->oy.y;
            wr.origin.z = fr->o00.z + fx * fr->ox.z + fy * fr->oy.z;
            double dx = fr->d00.x + fx * fr->dx.x + fy * fr->dy.x;
            double dy = fr->d00.y + fx * fr->dx.y + fy * fr->dy.y;
            double dz = fr->d00.z + fx * fr->dx.z + fy * fr->dy.z;
            const double inv = 1.0 / sqrt(dx * dx + dy * dy + dz * dz);
            wr.dir.x = dx * inv;
            wr.dir.y = dy * inv;
            wr.dir.z = dz * inv;
            const double cs = vv_vec3_dot(wr.dir, fr->f);
            bd->cosv[pi] = (float)cs;
            bd->vdir[3 * pi] = (float)-wr.dir.x;
            bd->vdir[3 * pi + 1] = (float)-wr.dir.y;
            bd->vdir[3 * pi + 2] = (float)-wr.dir.z;
            float *rd = bd->rdir + 6 * (size_t)pi;
            rd[0] = (float)wr.dir.x;
            rd[1] = (float)wr.dir.y;
            rd[2] = (float)wr.dir.z;
            rd[3] = (float)wr.origin.x;
            rd[4] = (float)wr.origin.y;
            rd[5] = (float)wr.origin.z;
            int any = 0, kend = INT32_MIN;
            for (int o = 0; o < fr->n_obj; o++) {
                const sp_obj *ob = &fr->objs[o];
                vv_vray r;
                int k0 = 1, k1 = 0;
                if (vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, &wr, 0, INFINITY,
                                  &r)) {
                    const double z0 = r.t0 * cs, z1 = r.t1 * cs;
                    double a = ceil(z0 / fr->dts), b = floor(z1 / fr->dts);
                    const double kn = ceil(fr->znear / fr->dts);
                    if (a > b && ob->mode != VV_MODE_COMPOSITE) /* one sample in the middle */
                        a = b = floor(0.5 * (z0 + z1) / fr->dts + 0.5);
                    a = a < kn ? kn : a;
                    if (fr->st->axis && ob->mode != VV_MODE_XRAY) {
                        a = -1e9;
                        b = 1e9;
                    }
                    if (a <= b) {
                        k0 = (int)(a < -2e9 ? -2e9 : a);
                        k1 = (int)(b > 2e9 ? 2e9 : b);
                        any |= ob->is_comp;
                    }
                }
                bd->k0[(size_t)o * (size_t)n + (size_t)pi] = k0;
                bd->k1[(size_t)o * (size_t)n + (size_t)pi] = k1;
                if (ob->is_comp && k0 <= k1 && k1 > kend)
                    kend = k1;
            }
            bd->kend[pi] = kend;
            if (!any)
                mark_done(bd, x, yl);
        }
    return VV_OK;
}

/* Splats the slices of object ob's voxels that cross sheet k into the band
 * buffer (ns buckets back: the voxels whose first sheet is k - ns + 1 .. k).
 * Axis variant and X-ray: whole footprints of the voxels of bucket k. */
static void
band_splat_sheet(sp_frame *fr, sp_band *bd, const sp_obj *ob, int band, int k, int rect[4],
                 int cull, uint8_t *dead, uint64_t *nfp, uint64_t *nculled) {
    const int whole = fr->st->axis || ob->mode == VV_MODE_XRAY;
    const int s1 = k - ob->kbase;
    int s0 = whole ? s1 : s1 - ob->ns + 1;
    s0 = s0 < 0 ? 0 : s0;
    if (s1 < 0 || s0 > ob->nsheets - 1)
        return;
    const int *bs = ob->bstart[band];
    const uint32_t *bidx = ob->bidx[band];
    const double zk = k * fr->dts;
    sp_fp fp;
    double s = 1;
    if (!whole) {
        if (zk < fr->znear)
            return;
        sp_object_fp(fr, ob, zk, &fp);
        s = sp_pix_scale(fr, zk);
    } else if (!fr->persp) {
        sp_object_fp(fr, ob, 1, &fp);
        s = sp_pix_scale(fr, 1);
    }
    const int shaded = ob->shading && ob->is_comp && !ob->pre_cls;
    const int nv = ob->is_comp ? (ob->pre_cls ? 4 : shaded ? 4 : 1) : 1;
    const double wbase = whole ? ob->vol_det : ob->vol_det / fr->dts;
    const int s_end = s1 < ob->nsheets - 1 ? s1 : ob->nsheets - 1;
    const double dlo = ob->z_lo, dhi = ob->z_lo + (SP_Z_LUT - 1) / ob->z_scale;
    for (int q = bs[s0]; q < bs[s_end + 1]; q++) {
        if (dead && dead[q])
            continue;
        const uint32_t v = bidx[q];
        int i, j, kk;
        sp_unpack(ob->sorted[v], &i, &j, &kk);
        const double zc = sp_lin4(ob->ez, i, j, kk);
        if (!whole && !(zk - zc >= dlo && zk - zc <= dhi))
            continue;
        const double X = sp_lin4(ob->ex, i, j, kk), Y = sp_lin4(ob->ey, i, j, kk);
        double w, cxe = X, cye = Y, zp = zk;
        if (whole) {
            w = wbase;
            zp = zc;
            if (fr->persp) {
                if (zc < fr->znear)
                    continue;
                s = sp_pix_scale(fr, zc);
                sp_object_fp(fr, ob, zc, &fp);
            }
        } else {
            const double d = zk - zc;
            double t = (d - ob->z_lo) * ob->z_scale;
            if (!(t >= 0 && t <= SP_Z_LUT - 1))
                continue;
            const int ti = (int)t;
            const double fr_ = t - ti;
            const int tn = ti + 1 < SP_Z_LUT ? ti + 1 : ti;
            const double m = ob->wz[ti] + (ob->wz[tn] - ob->wz[ti]) * fr_;
            if (!(m > 0))
                continue;
            const double dc = ob->dz[ti] + (ob->dz[tn] - ob->dz[ti]) * fr_;
            w = wbase * m;
            cxe += ob->bx * dc;
            cye += ob->by * dc;
        }
        double cx, cy;
        sp_to_pixel(fr, cxe, cye, zp, &cx, &cy);
        if (cy + fp.hy < bd->y0 || cy - fp.hy > bd->y1 - 1 || cx + fp.hx < 0 ||
            cx - fp.hx > bd->W - 1)
            continue;
        if (cull && occluded_box(bd, cx - fp.hx, cx + fp.hx, cy - fp.hy, cy + fp.hy)) {
            (*nculled)++;
            if (dead && !whole) {
                /* the voxel's later slices shift by at most |b| 2 rz (and
                 * in perspective move with depth): if that whole box is
                 * finished too, the voxel is done in this band */
                const double ex = fabs(ob->bx) * (2 * ob->rz + fr->dts) * s + 1;
                const double ey = fabs(ob->by) * (2 * ob->rz + fr->dts) * s + 1;
                double x0 = cx - fp.hx - ex, x1 = cx + fp.hx + ex;
                double y0 = cy - fp.hy - ey, y1 = cy + fp.hy + ey;
                if (fr->persp) {
                    double cx2, cy2;
                    sp_to_pixel(fr, X, Y, zc + ob->rz + fr->dts, &cx2, &cy2);
                    x0 = cx2 - fp.hx - ex < x0 ? cx2 - fp.hx - ex : x0;
                    x1 = cx2 + fp.hx + ex > x1 ? cx2 + fp.hx + ex : x1;
                    y0 = cy2 - fp.hy - ey < y0 ? cy2 - fp.hy - ey : y0;
                    y1 = cy2 + fp.hy + ey > y1 ? cy2 + fp.hy + ey : y1;
                }
                if (occluded_box(bd, x0, x1, y0, y1))
                    dead[q] = 1;
            }
            continue;
        }
        float val[4];
        if (ob->pre && ob->is_comp)
            memcpy(val, ob->pre[v], sizeof val);
        else if (shaded)
            memcpy(val, ob->v4[v], sizeof val);
        else
            val[0] = ob->v1[v];
        (*nfp)++;
        float wt = (float)(w * s * s * fp.norm) * fr->fp_scale;
        if (ob->mode == VV_MODE_XRAY) {
            const double sum =
                sp_fp_discrete_sum(bd->wrow, bd->W, (float)fr->rho2, (float)cx, (float)cy, &fp);
            wt = sum > 0 ? (float)(w * s * s / sum) : 0;
        }
        if (nv == 1)
            sp_fp_splat1(bd->buf, bd->ps, bd->W, bd->y0, bd->y1, (float)fr->rho2, (float)cx,
                         (float)cy, &fp, wt, val, rect);
        else
            sp_fp_splat4(bd->buf, bd->ps, bd->W, bd->y0, bd->y1, (float)fr->rho2, (float)cx,
                         (float)cy, &fp, wt, val, rect);
    }
}

/* Post-classifies and shades the sheet's dirty rectangle and composites it
 * (composite objects), then clears it. */
static void
band_composite_sheet(sp_frame *fr, sp_band *bd, const sp_obj *ob, int o, int k, const int rect[4]) {
    const int n = bd->n;
    const int *k0 = bd->k0 + (size_t)o * (size_t)n, *k1 = bd->k1 + (size_t)o * (size_t)n;
    const float et = fr->et;
    const int pre = ob->pre_cls;
    const double zk = k * fr->dts;
    for (int y = rect[2]; y <= rect[3]; y++) {
        const int yl = y - bd->y0;
        for (int x = rect[0]; x <= rect[1]; x++) {
            const int pi = yl * bd->W + x;
            float *p = bd->buf + (size_t)pi;
            const float w = p[0];
            if (w == 0)
                continue;
            float sv[SP_CH];
            for (int ch = 0; ch < SP_CH; ch++) {
                sv[ch] = p[(size_t)ch * bd->ps];
                p[(size_t)ch * bd->ps] = 0;
            }
            if (bd->done[pi])
                continue;
            if (k > k1[pi]) {
                /* finished once past every composite object's exit */
                if (k > bd->kend[pi])
                    mark_done(bd, x, yl);
                continue;
            }
            if (k < k0[pi])
                continue;
            float e4[4];
            const float *e;
            if (pre) {
                e4[0] = sv[1] > 1 ? 1 : sv[1];
                e4[1] = sv[2];
                e4[2] = sv[3];
                e4[3] = sv[4];
                e = e4;
            } else {
                if (w < SP_WMIN)
                    continue;
                e = ob->tab.lut + 4 * (int)vv_vtables_index(&ob->tab, sv[1] / w);
                if (ob->labels)
                    e = sp_label_entry(e, sv[1] / w, e4);
            }
            float alpha = e[0];
            if (alpha <= 0)
                continue;
            float col[3] = {e[1], e[2], e[3]};
            const float cs = bd->cosv[pi];
            if (fr->persp && cs < 0.99999f) {
                /* the slab is crossed over dts / cos */
                const float a2 = 1.0f - powf(1.0f - (alpha < 1 ? alpha : 1), 1.0f / cs);
                const float sc = a2 / alpha;
                col[0] *= sc;
                col[1] *= sc;
                col[2] *= sc;
                alpha = a2;
            }
            float out[3];
            if (ob->shading && !pre) {
                float pw[3] = {0, 0, 0};
                const float t = (float)(zk / cs);
                if (fr->point_lights) {
                    const float *rd = bd->rdir + 6 * (size_t)pi;
                    pw[0] = rd[3] + t * rd[0];
                    pw[1] = rd[4] + t * rd[1];
                    pw[2] = rd[5] + t * rd[2];
                }
                vv_vshade(&ob->sh, fr->lights, fr->n_lights, sv + 2, pw, bd->vdir + 3 * pi, col,
                          alpha, NULL, NULL, out);
            } else {
                out[0] = col[0];
                out[1] = col[1];
                out[2] = col[2];
            }
            float *C = bd->C + 3 * (size_t)pi;
            const float A = bd->A[pi], tr = 1 - A;
            C[0] += tr * out[0];
            C[1] += tr * out[1];
            C[2] += tr * out[2];
            bd->A[pi] = A + tr * alpha;
            if (bd->D[pi] == INFINITY)
                bd->D[pi] = (float)(zk / cs);
            if (bd->A[pi] >= et)
                mark_done(bd, x, yl);
        }
    }
}

/* The band's pixels of the image: the composited objects over the
 * projections over the background. */
static void
band_write(const sp_frame *fr, const sp_band *bdp, vv_image *out) {
    const sp_band bd = *bdp;
    for (int yl = 0; yl < bd.y1 - bd.y0; yl++)
        for (int x = 0; x < bd.W; x++) {
            const int pi = yl * bd.W + x;
            const size_t oi = (size_t)(bd.y0 + yl) * (size_t)bd.W + (size_t)x;
            float *pix = out->rgba + 4 * oi;
            const float A = bd.A[pi] > 1 ? 1 : bd.A[pi];
            const float rest = 1 - A;
            const float A2 = A + rest * bd.PA[pi];
            for (int ch = 0; ch < 3; ch++)
                pix[ch] = bd.C[3 * pi + ch] + rest * bd.P[3 * pi + ch] + (1 - A2) * fr->bg[ch];
            pix[3] = A2;
            out->depth[oi] = bd.D[pi] < bd.PD[pi] ? bd.D[pi] : bd.PD[pi];
        }
}

/* Accumulates object ob's projection (MIP, MinIP: per sheet; X-ray: once)
 * into best[] / the line integrals. */
static void
band_project_sheet(sp_frame *fr, sp_band *bd, const sp_obj *ob, int o, int k, const int rect[4],
                   float *best, float *bdepth) {
    const int n = bd->n;
    const int *k0 = bd->k0 + (size_t)o * (size_t)n, *k1 = bd->k1 + (size_t)o * (size_t)n;
    const int mip = ob->mode == VV_MODE_MIP;
    for (int y = rect[2]; y <= rect[3]; y++) {
        const int yl = y - bd->y0;
        for (int x = rect[0]; x <= rect[1]; x++) {
            const int pi = yl * bd->W + x;
            float *p = bd->buf + (size_t)pi;
            const float w = p[0], wv = p[bd->ps];
            p[0] = p[bd->ps] = 0;
            if (ob->mode == VV_MODE_XRAY && fr->xray)
                fr->xray[(size_t)y * (size_t)bd->W + (size_t)x] += wv;
            if (w == 0 || k < k0[pi] || k > k1[pi])
                continue;
            if (ob->mode == VV_MODE_XRAY) {
                best[pi] = wv / w;
                continue;
            }
            if (w < SP_WMIN)
                continue;
            const float v = wv / w;
            if (mip ? v > best[pi] : v < best[pi]) {
                best[pi] = v;
                bdepth[pi] = (float)(k * fr->dts / bd->cosv[pi]);
            }
        }
    }
}

vv_status
sp_render_band(sp_frame *fr, const vv_frame_tile *t, vv_image *out) {
    const int band = t->index;
    sp_band bd;
    vv_status s = band_init(fr, &bd, band);
    if (s != VV_OK)
        return s;
    uint64_t nfp = 0, ncull = 0, nsheets = 0;
    const int cull = fr->st->occlusion;
    /* composite objects: sheets front to back */
    if (fr->n_comp > 0) {
        int kmin = INT32_MAX, kmax = INT32_MIN;
        for (int o = 0; o < fr->n_comp; o++)
            for (int pi = 0; pi < bd.n; pi++) {
                const int a = bd.k0[(size_t)o * (size_t)bd.n + (size_t)pi],
                          b = bd.k1[(size_t)o * (size_t)bd.n + (size_t)pi];
                if (a > b)
                    continue;
                kmin = a < kmin ? a : kmin;
                kmax = b > kmax ? b : kmax;
            }
        if (fr->st->axis) {
            kmin = INT32_MAX;
            kmax = INT32_MIN;
            for (int o = 0; o < fr->n_comp; o++)
                if (fr->objs[o].nsheets) {
                    kmin = fr->objs[o].kbase < kmin ? fr->objs[o].kbase : kmin;
                    const int e = fr->objs[o].kbase + fr->objs[o].nsheets - 1;
                    kmax = e > kmax ? e : kmax;
                }
        }
        /* per object, the band's voxels found finished (occlusion) */
        uint8_t *dead[SP_MAX_OBJ] = {0};
        int dead_ok = cull;
        for (int o = 0; o < fr->n_comp && dead_ok; o++) {
            const sp_obj *ob = &fr->objs[o];
            const size_t m = ob->nsheets ? (size_t)ob->bstart[band][ob->nsheets] : 0;
            dead[o] = calloc(m ? m : 1, 1);
            dead_ok = dead[o] != NULL;
        }
        int alldone = 0;
        for (int k = kmin; k <= kmax && !alldone; k++) {
            if (vv_frame_cancelled(t))
                break;
            for (int o = 0; o < fr->n_comp; o++) {
                const sp_obj *ob = &fr->objs[o];
                int rect[4] = {INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN};
                band_splat_sheet(fr, &bd, ob, band, k, rect, cull, dead_ok ? dead[o] : NULL, &nfp,
                                 &ncull);
                if (rect[0] <= rect[1]) {
                    band_composite_sheet(fr, &bd, ob, o, k, rect);
                    nsheets++;
                }
            }
            /* every pixel finished: nothing behind can show */
            alldone = 1;
            for (int ti = 0; ti < bd.tw * bd.th && alldone; ti++)
                alldone = bd.tcount[ti] == bd.tcap[ti];
        }
        for (int o = 0; o < fr->n_comp; o++)
            free(dead[o]);
    }
    /* projection objects, combined by their maximum like the ray caster */
    float *best = NULL, *bdepth = NULL;
    if (fr->n_obj > fr->n_comp) {
        best = malloc((size_t)bd.n * 2 * sizeof(float));
        if (!best) {
            band_free(&bd);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        bdepth = best + bd.n;
    }
    for (int o = fr->n_comp; o < fr->n_obj; o++) {
        const sp_obj *ob = &fr->objs[o];
        const int mip = ob->mode == VV_MODE_MIP;
        for (int pi = 0; pi < bd.n; pi++) {
            best[pi] = ob->mode == VV_MODE_XRAY ? NAN : mip ? -INFINITY : INFINITY;
            bdepth[pi] = INFINITY;
        }
        if (ob->mode == VV_MODE_XRAY) {
            int rect[4] = {INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN};
            for (int k = ob->kbase; k < ob->kbase + ob->nsheets; k++)
                band_splat_sheet(fr, &bd, ob, band, k, rect, 0, NULL, &nfp, &ncull);
            if (rect[0] <= rect[1]) {
                /* every pixel of the object has k0 <= 0 <= k1 for X-ray:
                 * pass a sheet index inside */
                const int n = bd.n;
                for (int pi = 0; pi < n; pi++)
                    if (bd.k0[(size_t)o * (size_t)n + (size_t)pi] <=
                        bd.k1[(size_t)o * (size_t)n + (size_t)pi]) {
                        bd.k0[(size_t)o * (size_t)n + (size_t)pi] = 0;
                        bd.k1[(size_t)o * (size_t)n + (size_t)pi] = 0;
                    }
                band_project_sheet(fr, &bd, ob, o, 0, rect, best, bdepth);
            }
        } else {
            for (int k = ob->kbase; k < ob->kbase + ob->nsheets; k++) {
                if (vv_frame_cancelled(t))
                    break;
                int rect[4] = {INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN};
                band_splat_sheet(fr, &bd, ob, band, k, rect, 0, NULL, &nfp, &ncull);
                if (rect[0] <= rect[1]) {
                    band_project_sheet(fr, &bd, ob, o, k, rect, best, bdepth);
                    nsheets++;
                }
            }
        }
        for (int pi = 0; pi < bd.n; pi++) {
            const float v = best[pi];
            if (!isfinite(v))
                continue;
            const float *e = ob->tab.lut + 4 * (int)vv_vtables_index(&ob->tab, v);
            for (int ch = 0; ch < 3; ch++) {
                const float cv = e[1 + ch] * e[0];
                bd.P[3 * pi + ch] = cv > bd.P[3 * pi + ch] ? cv : bd.P[3 * pi + ch];
            }
            bd.PA[pi] = e[0] > bd.PA[pi] ? e[0] : bd.PA[pi];
            if (ob->mode == VV_MODE_XRAY) {
                /* the ray caster reports the entry point */
                vv_vray r;
                const float *rd = bd.rdir + 6 * (size_t)pi;
                vv_ray wr = {{rd[3], rd[4], rd[5]}, {rd[0], rd[1], rd[2]}};
                if (vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, &wr, 0, INFINITY,
                                  &r))
                    bdepth[pi] = (float)r.t0;
            }
            bd.PD[pi] = bdepth[pi] < bd.PD[pi] ? bdepth[pi] : bd.PD[pi];
        }
    }
    free(best);
    band_write(fr, &bd, out);
#pragma omp critical(vv_splat_stats)
    {
        fr->footprints += nfp;
        fr->culled += ncull;
        fr->sheets += nsheets;
    }
    band_free(&bd);
    return VV_OK;
}
