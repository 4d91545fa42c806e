/*
 * Splatting, objects (splat_internal.h): an object's eye-space maps and
 * kernel geometry for the view, the voxel lists kept between renders (the
 * voxels worth splatting, in the traversal order of the view octant) and
 * their bucketing by sheet and band for one render.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "core/internal.h"
#include "render/splat/splat_internal.h"

/* ---------------------------------------------------------------------- */
/* Per-object set-up                                                        */

static double
norm_cdf(double x) {
    return 0.5 * erfc(-x / sqrt(2.0));
}

/* Eye-space maps and kernel geometry of one object for this view. */
void
sp_object_geometry(sp_frame *fr, sp_obj *ob) {
    const sp_state *st = fr->st;
    const double sig = st->sigma;
    double A[3][3];
    const vv_vec3 ax[3] = {fr->r, fr->u, fr->f};
    double *rows[3] = {ob->ex, ob->ey, ob->ez};
    for (int a = 0; a < 3; a++) {
        const double e[3] = {ax[a].x, ax[a].y, ax[a].z};
        for (int cc = 0; cc < 4; cc++) {
            double v = 0;
            for (int q = 0; q < 3; q++)
                v += e[q] * ob->i2w[q][cc];
            rows[a][cc] = v;
        }
        rows[a][3] -= e[0] * fr->eye.x + e[1] * fr->eye.y + e[2] * fr->eye.z;
        for (int cc = 0; cc < 3; cc++)
            A[a][cc] = rows[a][cc];
    }
    double S[3][3];
    for (int p = 0; p < 3; p++)
        for (int q = 0; q < 3; q++)
            S[p][q] = sig * sig * (A[p][0] * A[q][0] + A[p][1] * A[q][1] + A[p][2] * A[q][2]);
    const double det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                       A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                       A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    ob->vol_det = fabs(det);
    const double rho = sqrt(fr->rho2);
    double cmax = 0;
    for (int cc = 0; cc < 3; cc++) {
        double l = sqrt(A[0][cc] * A[0][cc] + A[1][cc] * A[1][cc] + A[2][cc] * A[2][cc]);
        cmax = l > cmax ? l : cmax;
    }
    ob->rworld = st->radius * cmax * 1.7320508 + 1e-9;
    const double szz = S[2][2];
    ob->rz = rho * sqrt(szz);
    if (st->axis || ob->mode == VV_MODE_XRAY) {
        /* whole footprints: the marginal covariance */
        ob->cxx = S[0][0];
        ob->cxy = S[0][1];
        ob->cyy = S[1][1];
        ob->bx = ob->by = 0;
        ob->ns = 1;
        return;
    }
    ob->bx = S[0][2] / szz;
    ob->by = S[1][2] / szz;
    /* the conditional covariance, plus the spread of the centre shift over a
     * slab of thickness dts (uniform: dts^2 / 12) */
    const double v12 = fr->dts * fr->dts / 12.0;
    ob->cxx = S[0][0] - S[0][2] * S[0][2] / szz + ob->bx * ob->bx * v12;
    ob->cxy = S[0][1] - S[0][2] * S[1][2] / szz + ob->bx * ob->by * v12;
    ob->cyy = S[1][1] - S[1][2] * S[1][2] / szz + ob->by * ob->by * v12;
    /* slab integrals of the truncated 1-D marginal N(0, szz) on |s| <= rz */
    const double sz = sqrt(szz), h = 0.5 * fr->dts;
    const double dmax = ob->rz + h;
    ob->z_lo = -dmax;
    ob->z_scale = (SP_Z_LUT - 1) / (2 * dmax);
    const double tot = 2 * norm_cdf(rho) - 1;
    for (int t = 0; t < SP_Z_LUT; t++) {
        const double d = -dmax + t / ob->z_scale;
        double lo = d - h, hi = d + h;
        lo = lo < -ob->rz ? -ob->rz : lo;
        hi = hi > ob->rz ? ob->rz : hi;
        double m = 0, mean = 0;
        if (hi > lo) {
            m = norm_cdf(hi / sz) - norm_cdf(lo / sz);
            const double plo = exp(-0.5 * lo * lo / szz), phi = exp(-0.5 * hi * hi / szz);
            /* int s p(s) ds over [lo, hi] for the N(0, szz) density */
            const double first = sz * (plo - phi) / sqrt(2 * VV_PI);
            mean = m > 1e-12 ? first / m : 0.5 * (lo + hi);
        }
        ob->wz[t] = (float)(m / tot);
        ob->dz[t] = (float)mean;
    }
    ob->ns = (int)ceil(2 * dmax / fr->dts) + 2;
}

/* ---------------------------------------------------------------------- */
/* Voxel lists                                                              */

static uint64_t
hash_bytes(uint64_t h, const void *p, size_t n) {
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 1099511628211ULL;
    }
    return h;
}

/* Empty-voxel skipping: *out[v] = 1 when the values within 2 reach of voxel
 * v (every sample its kernel reaches, and every voxel those samples blend)
 * span a visible table entry: separable running min / max of table indices
 * over 2 reach + 1 voxels per axis. */
static vv_status
need_mask(const sp_obj *ob, int reach, uint8_t **out) {
    const vv_vcache *c = ob->c;
    const int nx = c->nx, ny = c->ny, nz = c->nz;
    const size_t nvox = c->sz * (size_t)nz;
    int *nzc = malloc(sizeof(int) * (VV_VC_LUT + 1));
    uint16_t *mn = malloc(nvox * sizeof *mn), *mx = malloc(nvox * sizeof *mx);
    uint8_t *need = malloc(nvox);
    if (!nzc || !mn || !mx || !need) {
        free(nzc);
        free(mn);
        free(mx);
        free(need);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for the voxel list of %zu voxels", nvox);
    }
    nzc[0] = 0;
    for (int i = 0; i < VV_VC_LUT; i++)
        nzc[i + 1] = nzc[i] + (ob->tab.lut[4 * i] > 0);
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nvox; v++)
        mn[v] = mx[v] = (uint16_t)vv_vtables_index(&ob->tab, vv_vcache_value(c, v));
    /* separable running min / max over 2 reach + 1 voxels per axis */
    const int R = 2 * reach;
    const int len[3] = {nx, ny, nz};
    const size_t stride[3] = {1, c->sy, c->sz};
    for (int a = 0; a < 3; a++) {
        const int L_ = len[a];
        const size_t st_ = stride[a];
        const size_t lines = nvox / (size_t)L_;
#pragma omp parallel
        {
            uint16_t *bmn = malloc((size_t)L_ * sizeof *bmn), *bmx = malloc((size_t)L_ * 2);
#pragma omp for schedule(static)
            for (size_t line = 0; line < lines; line++) {
                if (!bmn || !bmx)
                    continue;
                /* the line's first voxel: line enumerates the other two axes */
                size_t base;
                if (a == 0)
                    base = line * c->sy;
                else if (a == 1)
                    base = (line / (size_t)nx) * c->sz + line % (size_t)nx;
                else
                    base = line;
                for (int t = 0; t < L_; t++) {
                    bmn[t] = mn[base + (size_t)t * st_];
                    bmx[t] = mx[base + (size_t)t * st_];
                }
                for (int t = 0; t < L_; t++) {
                    const int t0 = t - R < 0 ? 0 : t - R, t1 = t + R > L_ - 1 ? L_ - 1 : t + R;
                    uint16_t lo = bmn[t0], hi = bmx[t0];
                    for (int u = t0 + 1; u <= t1; u++) {
                        lo = bmn[u] < lo ? bmn[u] : lo;
                        hi = bmx[u] > hi ? bmx[u] : hi;
                    }
                    mn[base + (size_t)t * st_] = lo;
                    mx[base + (size_t)t * st_] = hi;
                }
            }
            free(bmn);
            free(bmx);
        }
    }
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < nvox; v++)
        need[v] = nzc[mx[v] + 1] - nzc[mn[v]] > 0;
    free(nzc);
    free(mn);
    free(mx);
    *out = need;
    return VV_OK;
}

/* The object's voxel list for octant @p oct (bit a set: index axis a runs
 * backwards, from the far side), from the cache or built. */
vv_status
sp_object_list(sp_state *st, sp_obj *ob, int oct, int *built) {
    const vv_vcache *c = ob->c;
    const int comp = ob->mode == VV_MODE_COMPOSITE;
    const int skip = st->skipping && comp;
    const int pre = skip && ob->pre_cls;
    /* the kernel's reach in voxels (the footprint's truncation is a
     * cylinder: up to sqrt 2 radius from the centre) */
    const int reach = (int)ceil(1.4142136 * st->radius);
    uint64_t h = 1469598103934665603ULL;
    h = hash_bytes(h, &skip, sizeof skip);
    h = hash_bytes(h, &ob->pre_cls, sizeof ob->pre_cls);
    h = hash_bytes(h, &reach, sizeof reach);
    if (skip)
        for (int i = 0; i < VV_VC_LUT; i++) {
            const int vis = ob->tab.lut[4 * i] > 0;
            h = hash_bytes(h, &vis, sizeof vis);
        }
    st->clock++;
    for (int l = 0; l < SP_LISTS; l++) {
        sp_list *L = &st->lists[l];
        if (L->vol == c->vol && L->modified == c->vol->modified && L->hash == h &&
            L->octant == oct) {
            L->last_used = st->clock;
            ob->list = L;
            return VV_OK;
        }
    }
    int slot = 0;
    for (int l = 1; l < SP_LISTS; l++)
        if (st->lists[l].last_used < st->lists[slot].last_used)
            slot = l;
    sp_list *L = &st->lists[slot];
    vv_volume_free(L->vol);
    free(L->vox);
    memset(L, 0, sizeof *L);
    const int nx = c->nx, ny = c->ny, nz = c->nz;
    /* empty-voxel skipping: a voxel is needed when the values within
     * 2 reach of it (every sample it reaches, and every voxel those samples
     * blend) span a visible table entry; pre-classified, when its own value
     * is visible */
    uint8_t *need = NULL;
    if (skip && !pre) {
        vv_status sn = need_mask(ob, reach, &need);
        if (sn != VV_OK)
            return sn;
    }
    /* subvolumes (of VV_VC_BLOCK cells) within reach of a visible one */
    const int bdil = 1 + (reach + 1 + VV_VC_BLOCK - 1) / VV_VC_BLOCK;
    size_t n = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (int kk = 0; kk < nz; kk++) {
            const int k = oct & 4 ? nz - 1 - kk : kk;
            for (int jj = 0; jj < ny; jj++) {
                const int j = oct & 2 ? ny - 1 - jj : jj;
                const size_t row = (size_t)k * c->sz + (size_t)j * c->sy;
                for (int ii = 0; ii < nx; ii++) {
                    const int i = oct & 1 ? nx - 1 - ii : ii;
                    if (need) {
                        /* the subvolume grid first: far from every visible
                         * subvolume, no sample the voxel reaches can show */
                        int bi = i / VV_VC_BLOCK, bj = j / VV_VC_BLOCK, bk = k / VV_VC_BLOCK;
                        bi = bi >= c->bx ? c->bx - 1 : bi;
                        bj = bj >= c->by ? c->by - 1 : bj;
                        bk = bk >= c->bz ? c->bz - 1 : bk;
                        const size_t b =
                            ((size_t)bk * (size_t)c->by + (size_t)bj) * (size_t)c->bx + (size_t)bi;
                        if (ob->tab.bdist[b] > bdil || !need[row + (size_t)i])
                            continue;
                    }
                    if (pre &&
                        ob->tab.lut[4 * (int)vv_vtables_index(
                                            &ob->tab, vv_vcache_value(c, row + (size_t)i))] <= 0)
                        continue;
                    if (pass == 1)
                        L->vox[n] = (uint64_t)i | (uint64_t)j << 21 | (uint64_t)k << 42;
                    n++;
                }
            }
        }
        if (pass == 0) {
            L->vox = malloc((n ? n : 1) * sizeof *L->vox);
            if (!L->vox) {
                free(need);
                return vv_error_set(VV_ERR_NOMEM, "out of memory for a list of %zu voxels", n);
            }
            n = 0;
        }
    }
    free(need);
    L->n = n;
    L->vol = vv_volume_ref(c->vol);
    L->modified = c->vol->modified;
    L->hash = h;
    L->octant = oct;
    L->last_used = st->clock;
    ob->list = L;
    *built += 1;
    return VV_OK;
}

/* The sheet range [k0, k1] a voxel at depth zc touches (k1 < k0: none). */
static inline void
voxel_sheets(const sp_frame *fr, const sp_obj *ob, double zc, int *k0, int *k1) {
    if (fr->st->axis) {
        *k0 = *k1 = 0; /* set by the caller */
        return;
    }
    if (ob->mode == VV_MODE_XRAY) {
        *k0 = *k1 = 0;
        if (fr->persp && zc - ob->rz < fr->znear)
            *k1 = -1;
        return;
    }
    double a = (zc - ob->rz) / fr->dts - 0.5, b = (zc + ob->rz) / fr->dts + 0.5;
    const double kn = ceil(fr->znear / fr->dts);
    a = ceil(a);
    a = a < kn ? kn : a;
    b = floor(b);
    if (b - a > SP_MAX_SHEETS || a > 1e9 || b < -1e9) {
        *k0 = 1;
        *k1 = 0;
        return;
    }
    *k0 = (int)a;
    *k1 = (int)b;
}

/* The pixel rows a voxel's footprints can reach. */
static void
voxel_rows(const sp_frame *fr, const sp_obj *ob, double X, double Y, double zc, const sp_fp *fpo,
           double *ylo, double *yhi) {
    const double shift = fabs(ob->by) * (ob->rz + fr->dts);
    if (!fr->persp) {
        const double cy = Y / fr->pix, e = shift / fr->pix + fpo->hy + 1;
        *ylo = cy - e;
        *yhi = cy + e;
        return;
    }
    double zn = zc - ob->rz - fr->dts, zf = zc + ob->rz + fr->dts;
    zn = zn < fr->znear ? fr->znear : zn;
    zf = zf < zn ? zn : zf;
    double lo = INFINITY, hi = -INFINITY;
    const double zs[2] = {zn, zf}, ys[2] = {Y - shift, Y + shift};
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            double px, py;
            sp_to_pixel(fr, X, ys[b], zs[a], &px, &py);
            lo = py < lo ? py : lo;
            hi = py > hi ? py : hi;
        }
    /* the footprint is largest at the near depth */
    const double s = sp_pix_scale(fr, zn);
    const double hy = sqrt(fr->rho2 * ob->cyy) * s + sqrt(fr->rho2 * fr->st->ewa_var) + 1;
    *ylo = lo - hy;
    *yhi = hi + hy;
}

/* Pre-classification of one voxel: opacity for the sheet spacing and shaded
 * colour times opacity. */
static void
preclassify(const sp_frame *fr, const sp_obj *ob, int i, int j, int k, float out[4]) {
    const vv_vcache *c = ob->c;
    const size_t idx = (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
    const float val = vv_vcache_value(c, idx);
    const float *e = ob->tab.lut + 4 * (int)vv_vtables_index(&ob->tab, val);
    float lab[4];
    if (ob->labels)
        e = sp_label_entry(e, val, lab);
    out[0] = e[0];
    if (!ob->shading || e[0] <= 0) {
        out[1] = e[1];
        out[2] = e[2];
        out[3] = e[3];
        return;
    }
    float g[3] = {0, 0, 0};
    if (c->nrm) {
        const vv_v4f n = vv_vcache_normal(c, idx);
        g[0] = n[0];
        g[1] = n[1];
        g[2] = n[2];
    } else {
        const float p[3] = {(float)i, (float)j, (float)k};
        vv_vcache_gradient(c, p, g);
    }
    float pw[3];
    for (int a = 0; a < 3; a++)
        pw[a] = (float)(ob->i2w[a][0] * i + ob->i2w[a][1] * j + ob->i2w[a][2] * k + ob->i2w[a][3]);
    float v[3] = {(float)-fr->f.x, (float)-fr->f.y, (float)-fr->f.z};
    if (fr->persp) {
        /* towards the eye */
        const float d0 = (float)fr->view->eye.x - pw[0], d1 = (float)fr->view->eye.y - pw[1],
                    d2 = (float)fr->view->eye.z - pw[2];
        const float l = sqrtf(d0 * d0 + d1 * d1 + d2 * d2);
        if (l > 0) {
            v[0] = d0 / l;
            v[1] = d1 / l;
            v[2] = d2 / l;
        }
    }
    vv_vshade(&ob->sh, fr->lights, fr->n_lights, g, pw, v, e + 1, e[0], NULL, NULL, out + 1);
}

/* The first sheet of every voxel of the object's list (INT32_MIN: none,
 * behind the near plane or beyond a cut plane) into a new array *k0s, and
 * the range of sheets any voxel touches (*kmin > *kmax: none). */
static vv_status
first_sheets(const sp_frame *fr, const sp_obj *ob, int **k0s_out, int *kmin_out, int *kmax_out) {
    const sp_list *L = ob->list;
    const size_t n = L->n;
    int *k0s = malloc((n ? n : 1) * sizeof *k0s);
    if (!k0s)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    int kmin = INT32_MAX, kmax = INT32_MIN;
    /* axis-aligned variant: the sheet is the slice along the major axis */
    for (size_t v = 0; v < n; v++) {
        int i, j, k;
        sp_unpack(L->vox[v], &i, &j, &k);
        const double zc = sp_lin4(ob->ez, i, j, k);
        int a, b;
        voxel_sheets(fr, ob, zc, &a, &b);
        if (fr->st->axis) {
            const int idx[3] = {i, j, k};
            const int nax = ob->axis_a == 0 ? ob->c->nx : ob->axis_a == 1 ? ob->c->ny : ob->c->nz;
            a = b = ob->axis_sign > 0 ? idx[ob->axis_a] : nax - 1 - idx[ob->axis_a];
            if (fr->persp && zc - ob->rz < fr->znear)
                b = a - 1;
        }
        for (int p = 0; p < ob->n_planes && a <= b; p++) {
            vv_vec3 pw = {sp_lin4(ob->i2w[0], i, j, k), sp_lin4(ob->i2w[1], i, j, k),
                          sp_lin4(ob->i2w[2], i, j, k)};
            if (vv_plane_distance(ob->planes[p], pw) < -ob->rworld)
                b = a - 1;
        }
        if (a > b) {
            k0s[v] = INT32_MIN;
            continue;
        }
        k0s[v] = a;
        kmin = a < kmin ? a : kmin;
        kmax = b > kmax ? b : kmax;
    }
    *k0s_out = k0s;
    *kmin_out = kmin;
    *kmax_out = kmax;
    return VV_OK;
}

/* The values (and, shaded, gradients) of the object's m sorted voxels in
 * splatting order: read once per slice, they are then a stream instead of
 * scattered loads. */
static vv_status
stream_values(sp_obj *ob, size_t m) {
    const int shaded = ob->shading && ob->is_comp;
    if (shaded)
        ob->v4 = malloc((m ? m : 1) * sizeof *ob->v4);
    else
        ob->v1 = malloc((m ? m : 1) * sizeof *ob->v1);
    if (!ob->v4 && !ob->v1)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %zu splats", m);
    const vv_vcache *c = ob->c;
#pragma omp parallel for schedule(static)
    for (size_t v = 0; v < m; v++) {
        int i, j, k;
        sp_unpack(ob->sorted[v], &i, &j, &k);
        const size_t idx = (size_t)k * c->sz + (size_t)j * c->sy + (size_t)i;
        const float val = vv_vcache_value(c, idx);
        if (!shaded) {
            ob->v1[v] = val;
            continue;
        }
        ob->v4[v][0] = val;
        if (c->nrm) {
            const vv_v4f g = vv_vcache_normal(c, idx);
            ob->v4[v][1] = g[0];
            ob->v4[v][2] = g[1];
            ob->v4[v][3] = g[2];
        } else {
            const float p[3] = {(float)i, (float)j, (float)k};
            vv_vcache_gradient(c, p, &ob->v4[v][1]);
        }
    }
    return VV_OK;
}

/* Buckets the object's list by first sheet and distributes it over the
 * image bands. */
vv_status
sp_object_buckets(sp_frame *fr, sp_obj *ob) {
    const sp_list *L = ob->list;
    const size_t n = L->n;
    int *k0s = NULL, kmin = 0, kmax = -1;
    vv_status sr = first_sheets(fr, ob, &k0s, &kmin, &kmax);
    if (sr != VV_OK)
        return sr;
    if (kmin > kmax) {
        ob->nsheets = 0;
        ob->kbase = 0;
        free(k0s);
        return VV_OK;
    }
    if ((double)kmax - kmin + 1 > SP_MAX_SHEETS) {
        free(k0s);
        return vv_error_set(VV_ERR_LIMIT,
                            "object '%s': %d sheets (at most %d): the sheet spacing is too small "
                            "for the view",
                            ob->obj->name, kmax - kmin + 1, SP_MAX_SHEETS);
    }
    ob->kbase = kmin;
    ob->nsheets = kmax - kmin + 1;
    const int ns = ob->nsheets;
    const int nbands = fr->n_bands;
    ob->start = calloc((size_t)ns + 1, sizeof *ob->start);
    ob->bstart = calloc((size_t)nbands, sizeof *ob->bstart);
    ob->bidx = calloc((size_t)nbands, sizeof *ob->bidx);
    if (!ob->start || !ob->bstart || !ob->bidx) {
        free(k0s);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    size_t m = 0;
    for (size_t v = 0; v < n; v++)
        if (k0s[v] != INT32_MIN) {
            ob->start[k0s[v] - kmin + 1]++;
            m++;
        }
    for (int s = 0; s < ns; s++)
        ob->start[s + 1] += ob->start[s];
    ob->sorted = malloc((m ? m : 1) * sizeof *ob->sorted);
    int *fill = malloc(((size_t)ns + 1) * sizeof *fill);
    int16_t(*brange)[2] = malloc((m ? m : 1) * sizeof *brange);
    if (ob->pre_cls && ob->is_comp)
        ob->pre = malloc((m ? m : 1) * sizeof *ob->pre);
    if (!ob->sorted || !fill || !brange || (ob->pre_cls && ob->is_comp && !ob->pre)) {
        free(k0s);
        free(fill);
        free(brange);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %zu splats", m);
    }
    memcpy(fill, ob->start, ((size_t)ns + 1) * sizeof *fill);
    for (size_t v = 0; v < n; v++)
        if (k0s[v] != INT32_MIN)
            ob->sorted[fill[k0s[v] - kmin]++] = L->vox[v];
    free(k0s);
    /* the voxels' values (and gradients) in splatting order */
    if (!ob->pre && (sr = stream_values(ob, m)) != VV_OK) {
        free(fill);
        free(brange);
        return sr;
    }
    /* band of every voxel, then per band a counting sort by sheet */
    int *bcount = calloc((size_t)nbands * ((size_t)ns + 1), sizeof *bcount);
    if (!bcount) {
        free(fill);
        free(brange);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    sp_fp fpo;
    sp_object_fp(fr, ob, fr->persp ? 1.0 : 1.0, &fpo);
    int s = 0;
    for (size_t v = 0; v < m; v++) {
        while ((size_t)ob->start[s + 1] <= v)
            s++;
        int i, j, k;
        sp_unpack(ob->sorted[v], &i, &j, &k);
        const double X = sp_lin4(ob->ex, i, j, k), Y = sp_lin4(ob->ey, i, j, k),
                     zc = sp_lin4(ob->ez, i, j, k);
        double ylo, yhi;
        voxel_rows(fr, ob, X, Y, zc, &fpo, &ylo, &yhi);
        if (fr->st->axis && fr->persp) {
            /* whole footprints scale with the voxel's own depth */
            const double sc = sp_pix_scale(fr, zc > fr->znear ? zc : fr->znear);
            const double e = sqrt(fr->rho2 * ob->cyy) * sc + 2;
            double px, py;
            sp_to_pixel(fr, X, Y, zc, &px, &py);
            ylo = py - e;
            yhi = py + e;
        }
        int b0 = (int)floor(ylo / fr->band_h), b1 = (int)floor(yhi / fr->band_h);
        b0 = b0 < 0 ? 0 : b0;
        b1 = b1 > nbands - 1 ? nbands - 1 : b1;
        if (!(ylo < fr->view->height && yhi >= 0) || b0 > b1) {
            brange[v][0] = 1;
            brange[v][1] = 0;
            continue;
        }
        brange[v][0] = (int16_t)b0;
        brange[v][1] = (int16_t)b1;
        for (int b = b0; b <= b1; b++)
            bcount[(size_t)b * ((size_t)ns + 1) + (size_t)s + 1]++;
        if (ob->pre)
            preclassify(fr, ob, i, j, k, ob->pre[v]);
    }
    vv_status st = VV_OK;
    for (int b = 0; b < nbands && st == VV_OK; b++) {
        int *bc = bcount + (size_t)b * ((size_t)ns + 1);
        for (int q = 0; q < ns; q++)
            bc[q + 1] += bc[q];
        ob->bstart[b] = malloc(((size_t)ns + 1) * sizeof(int));
        ob->bidx[b] = malloc(((size_t)bc[ns] ? (size_t)bc[ns] : 1) * sizeof(uint32_t));
        if (!ob->bstart[b] || !ob->bidx[b])
            st = vv_error_set(VV_ERR_NOMEM, "out of memory");
        else
            memcpy(ob->bstart[b], bc, ((size_t)ns + 1) * sizeof(int));
    }
    if (st == VV_OK) {
        /* reuse bcount as fill pointers */
        s = 0;
        for (size_t v = 0; v < m; v++) {
            while ((size_t)ob->start[s + 1] <= v)
                s++;
            for (int b = brange[v][0]; b <= brange[v][1]; b++) {
                int *bc = bcount + (size_t)b * ((size_t)ns + 1);
                ob->bidx[b][bc[s]++] = (uint32_t)v;
            }
        }
    }
    free(bcount);
    free(fill);
    free(brange);
    return st;
}

void
sp_object_free(sp_obj *ob, int nbands) {
    if (ob->owns_tables)
        vv_vtables_free(&ob->tab);
    free(ob->sorted);
    free(ob->pre);
    free(ob->v4);
    free(ob->v1);
    free(ob->start);
    for (int b = 0; ob->bstart && b < nbands; b++)
        free(ob->bstart[b]);
    for (int b = 0; ob->bidx && b < nbands; b++)
        free(ob->bidx[b]);
    free(ob->bstart);
    free(ob->bidx);
}
