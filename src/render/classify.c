/*
 * The classification stage: an object's transfer-function tables built
 * (opacity corrected for the step, extinction, the 2-D and pre-integration
 * tables, the subvolumes' visibility and chessboard distances) and kept in
 * the volume's cache between frames, the extras of an object prepared, and
 * chunks of samples classified (the portable path; the AVX2 one is in
 * kernels_avx2.c). classify.h and tf_tables.h describe them and cite the
 * methods.
 */
#include "render/classify.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/kernels_avx2.h"

static void
vtables_clear(vv_vtables *t) {
    free(t->lut);
    free(t->ext);
    free(t->bvis);
    free(t->bdist);
    free(t->pdist);
    free(t->lut2d);
    free(t->pre);
    free(t->pre_nz);
    memset(t, 0, sizeof *t);
}

void
vv_vtables_free(vv_vtables *t) {
    if (t)
        vtables_clear(t);
}

/* Empty-space leaping: into d (n = nx ny nz bytes), the chessboard
 * distance from each subvolume to the nearest one with vis[b] == want,
 * capped at 255, by two chamfer passes over the 26 neighbours (exact for
 * the chessboard metric). With want 1, a ray in a subvolume at distance d
 * can jump to where it leaves the cube of 2d - 1 subvolumes around it, all
 * of them empty; with want 0, that cube is all visible. */
static void
chessboard_distance_to(const uint8_t *vis, int want, int nx, int ny, int nz, uint8_t *d) {
    const size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    for (size_t b = 0; b < n; b++)
        d[b] = !vis[b] == !want ? 0 : 255;
    for (int pass = 0; pass < 2; pass++) {
        const int step = pass == 0 ? 1 : -1;
        for (int k = pass == 0 ? 0 : nz - 1; k >= 0 && k < nz; k += step)
            for (int j = pass == 0 ? 0 : ny - 1; j >= 0 && j < ny; j += step)
                for (int i = pass == 0 ? 0 : nx - 1; i >= 0 && i < nx; i += step) {
                    size_t b = ((size_t)k * (size_t)ny + (size_t)j) * (size_t)nx + (size_t)i;
                    int best = d[b];
                    if (best == 0)
                        continue;
                    /* the 13 neighbours already visited in this pass */
                    for (int dk = -1; dk <= 0; dk++)
                        for (int dj = -1; dj <= 1; dj++)
                            for (int di = -1; di <= 1; di++) {
                                if (dk == 0 && (dj > 0 || (dj == 0 && di >= 0)))
                                    continue;
                                int kk = k + step * dk, jj = j + step * dj, ii = i + step * di;
                                if (kk < 0 || kk >= nz || jj < 0 || jj >= ny || ii < 0 || ii >= nx)
                                    continue;
                                int v = d[((size_t)kk * (size_t)ny + (size_t)jj) * (size_t)nx +
                                          (size_t)ii] +
                                        1;
                                best = v < best ? v : best;
                            }
                    d[b] = (uint8_t)(best > 255 ? 255 : best);
                }
    }
}

/* chessboard_distance_to the nearest visible subvolume, in a new array. */
static uint8_t *
chessboard_distance(const uint8_t *vis, int nx, int ny, int nz) {
    uint8_t *d = malloc((size_t)nx * (size_t)ny * (size_t)nz);
    if (d)
        chessboard_distance_to(vis, 1, nx, ny, nz, d);
    return d;
}

/* The 2-D table of vv_vtables (opacity corrected for dt, colour
 * premultiplied) over value [lo, hi] (real units) and gradient magnitude. */
static vv_status
build_lut2d(const vv_tf2d *tf, double lo, double hi, double dt, vv_vtables *t) {
    t->lut2d = malloc(sizeof(float) * 4 * VV_VC_LUT2_V * VV_VC_LUT2_G);
    if (!t->lut2d)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    double gmax = vv_tf2d_gradient_max(tf);
    if (!(gmax > 0))
        gmax = 1;
    /* bin LUT2_G - 2 is gmax, the last one beyond every widget */
    const double gstep = gmax / (VV_VC_LUT2_G - 2);
    t->g_scale = (float)(1.0 / gstep);
    const double unit = tf->opacity_unit_distance > 0 ? tf->opacity_unit_distance : 1.0;
    for (int g = 0; g < VV_VC_LUT2_G; g++)
        for (int v = 0; v < VV_VC_LUT2_V; v++) {
            const double x = lo + (hi - lo) * v / (VV_VC_LUT2_V - 1);
            double a;
            vv_vec3 col;
            vv_tf2d_eval(tf, x, g * gstep, &a, &col);
            a = a <= 0 ? 0 : a >= 1 ? 1 : 1.0 - pow(1.0 - a, dt / unit);
            float *e = t->lut2d + 4 * ((size_t)g * VV_VC_LUT2_V + (size_t)v);
            e[0] = (float)a;
            e[1] = (float)(col.x * a);
            e[2] = (float)(col.y * a);
            e[3] = (float)(col.z * a);
        }
    return VV_OK;
}

/* Builds the TF table (opacity corrected for dt, colour premultiplied),
 * the extinction table when asked, the subvolume visibility flags and
 * distances. */
static vv_status
build_tables(const vv_vcache *c, const vv_object *obj, const vv_vtables_key *key, vv_vtables *t) {
    memset(t, 0, sizeof *t);
    const size_t nb = (size_t)c->bx * (size_t)c->by * (size_t)c->bz;
    double lo = obj->volume->range[0], hi = obj->volume->range[1];
    /* a range too narrow for the table's scale in float (a constant volume,
     * or denormal values whose width makes the scale infinite: NaN table
     * indices crashed the ray caster) is widened; it then falls in one bin */
    if (!(hi > lo) || !((VV_VC_LUT - 1) / (hi - lo) < 1e30))
        hi = lo + fmax(1.0, fabs(lo) * 1e-6);
    t->lut_lo = (float)(lo - c->qoff);
    t->lut_scale = (float)((VV_VC_LUT - 1) / (hi - lo));
    t->bvis = malloc(nb);
    if (!t->bvis)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (key->mode == VV_MODE_ISO) {
        for (size_t b = 0; b < nb; b++)
            /* only subvolumes wholly below the isovalue are empty: one wholly
             * above may hold the start of a ray that enters the surface
             * through a cut plane or the box face */
            t->bvis[b] = !(c->bmax[b] < (float)key->iso) || !key->skipping;
    } else {
        t->lut = malloc(sizeof(float) * 4 * VV_VC_LUT);
        const int ext = key->flags & VV_VT_EXT;
        if (ext)
            t->ext = malloc(sizeof(float) * VV_VC_LUT);
        /* pre-integration: composite mode, a 1-D transfer function or a
         * threshold (labels take the nearest label's colour instead) */
        const int pre = (key->flags & VV_VT_PREINT) && key->mode == VV_MODE_COMPOSITE &&
                        (key->segmentation == VV_SEG_TRANSFER_FUNCTION ||
                         key->segmentation == VV_SEG_THRESHOLD);
        if (pre) {
            t->pre = malloc(sizeof(double) * 8 * VV_VC_LUT);
            t->pre_nz = malloc(sizeof(int32_t) * (VV_VC_LUT + 1));
        }
        int *nz = malloc(sizeof(int) * (VV_VC_LUT + 1));
        if (!t->lut || (ext && !t->ext) || (pre && (!t->pre || !t->pre_nz)) || !nz) {
            free(nz);
            vtables_clear(t);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        const double unit = obj->tf.opacity_unit_distance > 0 ? obj->tf.opacity_unit_distance : 1.0;
        if (key->segmentation == VV_SEG_TRANSFER_FUNCTION_2D && key->mode == VV_MODE_COMPOSITE) {
            vv_status st = build_lut2d(&key->tf2d, lo, hi, key->dt, t);
            if (st != VV_OK) {
                free(nz);
                vtables_clear(t);
                return st;
            }
        }
        nz[0] = 0;
        for (int i = 0; i < VV_VC_LUT && t->lut2d; i++) {
            /* the largest opacity over the gradient magnitudes of this value */
            const int vb = (int)((float)i * ((float)(VV_VC_LUT2_V - 1) / (VV_VC_LUT - 1)) + 0.5f);
            const float *best = t->lut2d + 4 * (size_t)vb;
            for (int g = 1; g < VV_VC_LUT2_G; g++) {
                const float *e = t->lut2d + 4 * ((size_t)g * VV_VC_LUT2_V + (size_t)vb);
                best = e[0] > best[0] ? e : best;
            }
            memcpy(t->lut + 4 * i, best, 4 * sizeof(float));
            if (t->ext) {
                /* back from the step-corrected opacity to the extinction */
                const double a = best[0];
                t->ext[i] = a >= 1 ? 1e30f : (float)(-log1p(-a) / key->dt);
            }
            nz[i + 1] = nz[i] + (best[0] > 0);
        }
        for (int i = 0; i < VV_VC_LUT && !t->lut2d; i++) {
            double x = lo + (hi - lo) * i / (VV_VC_LUT - 1);
            double a;
            vv_vec3 col;
            if (obj->segmentation == VV_SEG_THRESHOLD) {
                a = x >= obj->threshold ? 1.0 : 0.0;
                col = obj->material.color;
            } else if (obj->segmentation == VV_SEG_LABELS) {
                /* a categorical transfer function: opaque where the interpolated
                 * label is >= 1/2 (the surface against the background); the
                 * colour is the nearest label's (vv_vextra_label) in composite
                 * mode, the rounded value's in the projections */
                double l = floor(x + 0.5);
                a = l >= 1 ? 1.0 : 0.0;
                col = vv_label_color(vv_label_key(l));
            } else {
                a = vv_tf_eval_opacity(&obj->tf, x);
                col = vv_tf_eval_color(&obj->tf, x);
            }
            a = a <= 0 ? 0 : a >= 1 ? 1 : a;
            if (t->pre) {
                /* extinction per world unit, bounded so that a step's optical
                 * depth stays finite (40: opacity 1 in double) */
                const double cap = 40.0 / key->dt;
                double tau = a >= 1 ? cap : -log1p(-a) / unit;
                tau = tau < cap ? tau : cap;
                double *e = t->pre + 8 * (size_t)i;
                e[1] = tau;
                e[5] = tau * col.x;
                e[6] = tau * col.y;
                e[7] = tau * col.z;
            }
            if (t->ext)
                /* extinction: exp(-ext * unit) = 1 - a */
                t->ext[i] = a >= 1 ? 1e30f : (float)(-log1p(-a) / unit);
            if (key->mode == VV_MODE_COMPOSITE) {
                a = a <= 0 ? 0 : a >= 1 ? 1 : 1.0 - pow(1.0 - a, key->dt / unit);
                t->lut[4 * i + 0] = (float)a;
                t->lut[4 * i + 1] = (float)(col.x * a);
                t->lut[4 * i + 2] = (float)(col.y * a);
                t->lut[4 * i + 3] = (float)(col.z * a);
            } else {
                /* projections show the TF colour and opacity at the projected value */
                t->lut[4 * i + 0] = (float)a;
                t->lut[4 * i + 1] = (float)col.x;
                t->lut[4 * i + 2] = (float)col.y;
                t->lut[4 * i + 3] = (float)col.z;
            }
            nz[i + 1] = nz[i] + (t->lut[4 * i] > 0);
        }
        if (t->pre) {
            /* the prefix integrals: the trapezoid rule is exact for tau
             * and tau c linear between entries */
            double *e = t->pre;
            e[0] = e[2] = e[3] = e[4] = 0;
            for (int i = 1; i < VV_VC_LUT; i++, e += 8)
                for (int q = 0; q < 4; q++) {
                    const int at = q ? 1 + q : 0, of = q ? 4 + q : 1;
                    e[8 + at] = e[at] + 0.5 * (e[of] + e[8 + of]);
                }
            t->pre_nz[0] = 0;
            for (int i = 0; i < VV_VC_LUT; i++)
                t->pre_nz[i + 1] = t->pre_nz[i] + (t->pre[8 * i + 1] > 0);
        }
        for (size_t b = 0; b < nb; b++) {
            const float xhi = vv_vtables_index(t, c->bmax[b]);
            int i0 = (int)vv_vtables_index(t, c->bmin[b]), i1 = (int)xhi;
            /* pre-integration interpolates between entries: the entry
             * above the largest value counts too (vv_vpre_visible) */
            i1 += t->pre && (float)i1 < xhi && i1 < VV_VC_LUT - 1;
            t->bvis[b] = nz[i1 + 1] - nz[i0] > 0 || !key->skipping;
        }
        free(nz);
    }
    /* bdist, then vdist in the same allocation (tf_tables.h), and 3 bytes
     * for the AVX2 run's 4-byte gathers */
    t->bdist = malloc(2 * nb + 3);
    if (t->bdist) {
        chessboard_distance_to(t->bvis, 1, c->bx, c->by, c->bz, t->bdist);
        chessboard_distance_to(t->bvis, 0, c->bx, c->by, c->bz, t->bdist + nb);
    }
    if (!t->bdist) {
        vtables_clear(t);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    if (t->lut && (key->mode == VV_MODE_MIP || key->mode == VV_MODE_MINIP)) {
        vv_vtables_flat_ends(t, &t->plo, &t->phi);
        /* a subvolume all of whose values classify like the starting bound
         * cannot change the projection: leap through it */
        uint8_t *pv = malloc(nb);
        if (pv) {
            const int mip = key->mode == VV_MODE_MIP;
            for (size_t b = 0; b < nb; b++)
                pv[b] = (mip ? c->bmax[b] > t->plo : c->bmin[b] < t->phi) || !key->skipping;
            t->pdist = chessboard_distance(pv, c->bx, c->by, c->bz);
            free(pv);
        }
        if (!t->pdist) {
            vtables_clear(t);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
    }
    return VV_OK;
}

static int
tf_equal(const vv_tf *a, const vv_tf *b) {
    if (a->n_opacity != b->n_opacity || a->n_color != b->n_color ||
        a->opacity_unit_distance != b->opacity_unit_distance)
        return 0;
    for (int i = 0; i < a->n_opacity; i++)
        if (a->opacity[i].value != b->opacity[i].value ||
            a->opacity[i].opacity != b->opacity[i].opacity)
            return 0;
    for (int i = 0; i < a->n_color; i++)
        if (a->color[i].value != b->color[i].value || a->color[i].color.x != b->color[i].color.x ||
            a->color[i].color.y != b->color[i].color.y ||
            a->color[i].color.z != b->color[i].color.z)
            return 0;
    return 1;
}

static int
tf2d_equal(const vv_tf2d *a, const vv_tf2d *b) {
    if (a->n_widgets != b->n_widgets || a->opacity_unit_distance != b->opacity_unit_distance)
        return 0;
    for (int i = 0; i < a->n_widgets; i++) {
        const vv_tf2d_widget *x = &a->widgets[i], *y = &b->widgets[i];
        if (x->shape != y->shape || x->value[0] != y->value[0] || x->value[1] != y->value[1] ||
            x->gradient[0] != y->gradient[0] || x->gradient[1] != y->gradient[1] ||
            x->ramp != y->ramp || x->gradient_ramp != y->gradient_ramp || x->center != y->center ||
            x->width != y->width || x->color.x != y->color.x || x->color.y != y->color.y ||
            x->color.z != y->color.z || x->opacity != y->opacity)
            return 0;
    }
    return 1;
}

static int
key_equal(const vv_vtables_key *a, const vv_vtables_key *b) {
    return a->mode == b->mode && a->segmentation == b->segmentation &&
           a->threshold == b->threshold && a->iso == b->iso && a->dt == b->dt &&
           a->base.x == b->base.x && a->base.y == b->base.y && a->base.z == b->base.z &&
           a->skipping == b->skipping && a->flags == b->flags && tf_equal(&a->tf, &b->tf) &&
           tf2d_equal(&a->tf2d, &b->tf2d);
}

vv_status
vv_vtables_get(vv_vcache_set *s, vv_vcache *c, const vv_object *obj, vv_render_mode mode, double dt,
               float iso, int skipping, int flags, vv_vtables *out, int *owned) {
    vv_vtables_key key;
    memset(&key, 0, sizeof key);
    key.mode = mode;
    key.segmentation = obj->segmentation;
    key.threshold = obj->threshold;
    key.iso = iso;
    key.dt = dt;
    key.base = obj->material.color;
    key.skipping = skipping;
    key.flags = flags;
    key.tf = obj->tf;
    if (obj->segmentation == VV_SEG_TRANSFER_FUNCTION_2D && mode == VV_MODE_COMPOSITE) {
        vv_status sg = vv_vcache_need_gmag(c);
        if (sg != VV_OK)
            return sg;
        key.tf2d = obj->tf2d;
    }
    if (c->tables_valid && key_equal(&c->key, &key)) {
        *out = c->tables;
        *owned = 0;
        c->tables_frame = s->frame;
        return VV_OK;
    }
    *owned = 1;
    vv_status st = build_tables(c, obj, &key, out);
    /* keep them unless another object of this frame borrows the cached ones */
    if (st != VV_OK || (c->tables_valid && c->tables_frame == s->frame))
        return st;
    vtables_clear(&c->tables);
    c->tables_valid = 1;
    c->key = key;
    c->tables = *out;
    c->tables_frame = s->frame;
    *owned = 0;
    return VV_OK;
}

int
vv_vextra_prepare(vv_vextra *x, const vv_object *obj, vv_render_mode mode, const vv_vtables *t) {
    memset(x, 0, sizeof *x);
    x->lut_lo = t->lut_lo;
    x->lut_scale = t->lut_scale;
    x->lut2_scale = (float)(VV_VC_LUT2_V - 1) / (float)(VV_VC_LUT - 1);
    x->g_scale = t->g_scale;
    x->lut2d = mode == VV_MODE_COMPOSITE ? t->lut2d : NULL;
    if (mode == VV_MODE_COMPOSITE && obj->solid_texture.kind != VV_SOLID_TEXTURE_NONE)
        x->solid = &obj->solid_texture;
    if (mode == VV_MODE_COMPOSITE && obj->segmentation == VV_SEG_LABELS && obj->volume)
        x->labels = obj->volume;
    vv_mat4 m = vv_volume_index_to_world(obj->volume);
    for (int r = 0; r < 3; r++)
        for (int cc = 0; cc < 4; cc++)
            x->i2o[r][cc] = m.m[r][cc];
    return x->lut2d != NULL || x->solid != NULL || x->labels != NULL;
}

void
vv_vtables_flat_ends(const vv_vtables *t, float *lo, float *hi) {
    const float *e = t->lut;
    int i0 = 0;
    while (i0 + 1 < VV_VC_LUT && memcmp(e + 4 * (i0 + 1), e, 4 * sizeof *e) == 0)
        i0++;
    int j0 = VV_VC_LUT - 1;
    while (j0 > 0 && memcmp(e + 4 * (j0 - 1), e + 4 * (VV_VC_LUT - 1), 4 * sizeof *e) == 0)
        j0--;
    /* value v has entry (int)((v - lut_lo) * lut_scale), clamped: below
     * lut_lo + (i0 + 1) / lut_scale it is at most i0; the bounds keep one
     * entry of margin for rounding */
    *lo = i0 > 0 ? t->lut_lo + (float)i0 / t->lut_scale : -INFINITY;
    *hi = j0 < VV_VC_LUT - 2 ? t->lut_lo + (float)(j0 + 1) / t->lut_scale : INFINITY;
}

/* Pass 1 of the composite kernel: for samples k = kfirst .. kfirst + m - 1
 * of ray r, the cell offset, the fractions and the TF table entry (4 *
 * index). Portable version; the AVX2 one below computes offsets in 32 bits
 * and is used only for grids of fewer than 2^30 voxels. */
static void
classify_chunk(const vv_vcache *c, const vv_vtables *ob, const vv_vray *r, double kfirst, double dt,
               int m, size_t *cell, float *fx, float *fy, float *fz, int32_t *entry, float *x) {
    for (int s = 0; s < m; s++) {
        float p[3], f[3];
        vv_vray_point(r, (kfirst + s) * dt, p);
        const size_t o = vv_vcache_cell_in(c, p, f);
        cell[s] = o;
        fx[s] = f[0];
        fy[s] = f[1];
        fz[s] = f[2];
        const float xs = vv_vtables_index(ob, vv_vcache_value_at(c, o, f));
        entry[s] = 4 * (int)xs;
        if (x)
            x[s] = xs;
    }
}

void
vv_vray_classify(const vv_vcache *c, const vv_vtables *t, const vv_vray *r, double kfirst,
                 double dt, int m, int avx2, size_t *cell, float *fx, float *fy, float *fz,
                 int32_t *entry, float *x) {
#if VV_VC_HAVE_AVX2
    if (avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30)) {
        vv_vray_classify_avx2(c, t, r, kfirst, dt, m, cell, fx, fy, fz, entry, x);
        return;
    }
#else
    (void)avx2;
#endif
    classify_chunk(c, t, r, kfirst, dt, m, cell, fx, fy, fz, entry, x);
}
