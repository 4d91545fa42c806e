/*
 * Volume caches and per-object tables shared by the raycast and raytrace
 * renderers (src/render/volume_cache.h describes them).
 */
#include "render/volume_cache.h"

#include <stdlib.h>
#include <unistd.h>
#if VV_VC_HAVE_AVX2
#include <immintrin.h>
#endif

#include "core/geom.h"
#include "core/internal.h"

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

/* ---------------------------------------------------------------------- */
/* Object tables                                                            */

/* Empty-space leaping: the chessboard distance from each subvolume to the
 * nearest visible one, capped at 255, by two chamfer passes over the 26
 * neighbours (exact for the chessboard metric). A ray in a subvolume at
 * distance d can jump to where it leaves the cube of 2d - 1 subvolumes
 * around it, all of them empty. */
static uint8_t *
chessboard_distance(const uint8_t *vis, int nx, int ny, int nz) {
    const size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    uint8_t *d = malloc(n);
    if (!d)
        return NULL;
    for (size_t b = 0; b < n; b++)
        d[b] = vis[b] ? 0 : 255;
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
                col = vv_label_color(l >= 1 && l < 4294967296.0 ? (uint32_t)l : 0);
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
    t->bdist = chessboard_distance(t->bvis, c->bx, c->by, c->bz);
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

/* ---------------------------------------------------------------------- */
/* Objects, lights, projections                                             */

int
vv_vlights_prepare(vv_vlight out[VV_MAX_LIGHTS], const vv_world *w, const vv_view *view) {
    vv_vec3 fwd = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    int n = 0;
    for (int i = 0; i < w->n_lights && i < VV_MAX_LIGHTS; i++) {
        const vv_light *l = &w->lights[i];
        vv_vlight *o = &out[n++];
        o->point = l->type == VV_LIGHT_POINT && !l->headlight;
        vv_vec3 d = l->headlight ? fwd : vv_vec3_normalize(l->direction);
        /* towards the light = against the direction it travels */
        o->dir[0] = (float)-d.x;
        o->dir[1] = (float)-d.y;
        o->dir[2] = (float)-d.z;
        o->pos[0] = (float)l->position.x;
        o->pos[1] = (float)l->position.y;
        o->pos[2] = (float)l->position.z;
        o->col[0] = (float)(l->color.x * l->intensity);
        o->col[1] = (float)(l->color.y * l->intensity);
        o->col[2] = (float)(l->color.z * l->intensity);
    }
    return n;
}

void
vv_vchannel_object(const vv_object *obj, const vv_channel *cc, vv_object *out) {
    *out = *obj;
    out->volume = cc->volume;
    out->tf = cc->tf;
    out->n_channels = 0;
    out->channels = NULL;
    out->mode = obj->blend == VV_BLEND_MAXIMUM ? VV_MODE_MIP : VV_MODE_COMPOSITE;
    out->segmentation = cc->labels ? VV_SEG_LABELS : VV_SEG_TRANSFER_FUNCTION;
    out->texture.image = NULL;
    vv_solid_texture_init(&out->solid_texture);
}

int
vv_vchannels_shown(const vv_object *obj) {
    int n = 0;
    for (int c = 0; obj->n_channels > 1 && c < obj->n_channels; c++)
        n += obj->channels[c].visible && obj->channels[c].volume != NULL;
    return n;
}

vv_status
vv_vobject_prepare(const vv_object *obj, const vv_world *w, const float ambient[3],
                   const vv_vlight *lights, int n_lights, double w2i[3][4], double i2w[3][4],
                   int dims[3], vv_plane *planes, int *n_planes, vv_vshading *sh) {
    vv_mat4 m = vv_object_index_to_world(obj);
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(m, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
    for (int r = 0; r < 3; r++)
        for (int cc = 0; cc < 4; cc++) {
            w2i[r][cc] = inv.m[r][cc];
            i2w[r][cc] = m.m[r][cc];
        }
    /* normals: world normal = (M^-1)^T g_index, M = linear part of i2w */
    for (int r = 0; r < 3; r++)
        for (int cc = 0; cc < 3; cc++)
            sh->nrm[r][cc] = (float)inv.m[cc][r];
    for (int a = 0; a < 3; a++)
        /* a single-voxel axis (a 2-D image) is one voxel thick: the cache
         * holds that slice twice */
        dims[a] = obj->volume->dims[a] > 1 ? obj->volume->dims[a] : 2;
    *n_planes = 0;
    for (int p = 0; p < w->n_cut_planes && *n_planes < 2 * VV_MAX_CUT_PLANES; p++)
        planes[(*n_planes)++] =
            vv_plane_from_point_normal(w->cut_planes[p].point, w->cut_planes[p].normal);
    for (int p = 0; p < obj->n_cut_planes && *n_planes < 2 * VV_MAX_CUT_PLANES; p++)
        planes[(*n_planes)++] =
            vv_plane_from_point_normal(obj->cut_planes[p].point, obj->cut_planes[p].normal);
    const vv_material *mt = &obj->material;
    for (int i = 0; i <= VV_VC_SPEC; i++)
        sh->spec[i] = (float)pow((double)i / VV_VC_SPEC, mt->shininess);
    sh->base[0] = (float)mt->color.x;
    sh->base[1] = (float)mt->color.y;
    sh->base[2] = (float)mt->color.z;
    for (int ch = 0; ch < 3; ch++) {
        sh->amb[ch] = (float)mt->ambient * ambient[ch];
        for (int l = 0; l < n_lights; l++) {
            sh->kd_col[l][ch] = (float)mt->diffuse * lights[l].col[ch];
            sh->ks_col[l][ch] = (float)mt->specular * lights[l].col[ch];
        }
    }
    return VV_OK;
}

#if VV_VC_HAVE_AVX2
/* The trilinear values of samples k = kfirst .. kfirst + m - 1 (m <=
 * VV_VC_CHUNK) of ray r through 16-bit values, eight at a time with AVX2,
 * in exactly the arithmetic of vv_vray_point, vv_vcache_cell_in and
 * vv_vcache_value_at (separate multiplies and adds, no fused ones), so the
 * values are bit-identical to the scalar path's. */
/* The cells of eight index points (px, py, pz) inside the grid box, as
 * vv_vcache_cell_in computes them: their offsets (returned), fractions
 * (*wx, *wy, *wz) and the four x-pairs (v[o], v[o + 1]) of each cell's
 * edges, 16-bit values packed in 32-bit lanes, read by plain loads
 * (hardware gathers are microcoded and slow on processors with the Gather
 * Data Sampling mitigation). Needs c->q16. */
__attribute__((target("avx2"))) static inline __m256i
cell_pairs_avx2(const vv_vcache *c, __m256 px, __m256 py, __m256 pz, __m256 *wx, __m256 *wy,
                __m256 *wz, int32_t p00[8], int32_t p10[8], int32_t p01[8], int32_t p11[8]) {
    const __m256i zero = _mm256_setzero_si256();
    __m256i i = _mm256_cvttps_epi32(px), j = _mm256_cvttps_epi32(py), k = _mm256_cvttps_epi32(pz);
    i = _mm256_max_epi32(_mm256_min_epi32(i, _mm256_set1_epi32(c->nx - 2)), zero);
    j = _mm256_max_epi32(_mm256_min_epi32(j, _mm256_set1_epi32(c->ny - 2)), zero);
    k = _mm256_max_epi32(_mm256_min_epi32(k, _mm256_set1_epi32(c->nz - 2)), zero);
    *wx = _mm256_sub_ps(px, _mm256_cvtepi32_ps(i));
    *wy = _mm256_sub_ps(py, _mm256_cvtepi32_ps(j));
    *wz = _mm256_sub_ps(pz, _mm256_cvtepi32_ps(k));
    const __m256i o =
        _mm256_add_epi32(_mm256_add_epi32(_mm256_mullo_epi32(k, _mm256_set1_epi32((int)c->sz)),
                                          _mm256_mullo_epi32(j, _mm256_set1_epi32((int)c->sy))),
                         i);
    int32_t oo[8];
    _mm256_storeu_si256((__m256i *)(void *)oo, o);
    for (int l = 0; l < 8; l++) {
        const uint16_t *v = c->q16 + oo[l];
        memcpy(&p00[l], v, 4);
        memcpy(&p10[l], v + c->sy, 4);
        memcpy(&p01[l], v + c->sz, 4);
        memcpy(&p11[l], v + c->sz + c->sy, 4);
    }
    return o;
}

/* Eight x-pairs of 16-bit values (low and high halves of each 32-bit
 * lane) lerped by wx: a + (b - a) * wx. */
__attribute__((target("avx2"))) static inline __m256
pair_lerp_avx2(const int32_t pairs[8], __m256 wx) {
    const __m256i g = _mm256_loadu_si256((const __m256i *)(const void *)pairs);
    const __m256 a = _mm256_cvtepi32_ps(_mm256_and_si256(g, _mm256_set1_epi32(0xFFFF)));
    const __m256 b = _mm256_cvtepi32_ps(_mm256_srli_epi32(g, 16));
    return _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), wx));
}

/* vv_vshade8: eight lanes of vv_vshade, in its order of operations. */
__attribute__((target("avx2"))) void
vv_vshade8(const vv_vshading *o, const vv_vlight *lights, int n_lights, const float v[3],
           const float *shadow, const float gx[8], const float gy[8], const float gz[8],
           const float a[8], const float cr[8], const float cg[8], const float cb[8],
           float out_r[8], float out_g[8], float out_b[8]) {
    const __m256 g0 = _mm256_loadu_ps(gx), g1 = _mm256_loadu_ps(gy), g2 = _mm256_loadu_ps(gz);
#define VS_MUL(x, y) _mm256_mul_ps((x), (y))
#define VS_ADD(x, y) _mm256_add_ps((x), (y))
#define VS_B(x) _mm256_set1_ps(x)
    /* n_k = (nrm[k][0] g0 + nrm[k][1] g1) + nrm[k][2] g2 */
    __m256 nn[3];
    for (int k = 0; k < 3; k++)
        nn[k] = VS_ADD(VS_ADD(VS_MUL(VS_B(o->nrm[k][0]), g0), VS_MUL(VS_B(o->nrm[k][1]), g1)),
                       VS_MUL(VS_B(o->nrm[k][2]), g2));
    const __m256 len2 =
        VS_ADD(VS_ADD(VS_MUL(nn[0], nn[0]), VS_MUL(nn[1], nn[1])), VS_MUL(nn[2], nn[2]));
    const __m256 lit = _mm256_cmp_ps(len2, VS_B(1e-12f), _CMP_GT_OQ);
    const __m256 inv = _mm256_div_ps(VS_B(1.0f), _mm256_sqrt_ps(len2));
    const __m256 nv = VS_MUL(VS_ADD(VS_ADD(VS_MUL(nn[0], VS_B(v[0])), VS_MUL(nn[1], VS_B(v[1]))),
                                    VS_MUL(nn[2], VS_B(v[2]))),
                             inv);
    const __m256 sign = VS_B(-0.0f), zero = _mm256_setzero_ps();
    __m256 d0 = VS_B(o->amb[0]), d1 = VS_B(o->amb[1]), d2 = VS_B(o->amb[2]);
    __m256 s0 = zero, s1 = zero, s2 = zero;
    for (int l = 0; l < n_lights; l++) {
        const vv_vlight *lt = &lights[l];
        const float L0 = lt->dir[0], L1 = lt->dir[1], L2 = lt->dir[2];
        __m256 ndl = VS_MUL(VS_ADD(VS_ADD(VS_MUL(nn[0], VS_B(L0)), VS_MUL(nn[1], VS_B(L1))),
                                   VS_MUL(nn[2], VS_B(L2))),
                            inv);
        /* two-sided: where ndl < 0 both ndv and ndl change sign */
        const __m256 back = _mm256_cmp_ps(ndl, zero, _CMP_LT_OQ);
        const __m256 ndv = _mm256_blendv_ps(nv, _mm256_xor_ps(nv, sign), back);
        ndl = _mm256_blendv_ps(ndl, _mm256_xor_ps(ndl, sign), back);
        const float lv = L0 * v[0] + L1 * v[1] + L2 * v[2];
        const __m256 rv = _mm256_sub_ps(VS_MUL(VS_MUL(VS_B(2.0f), ndl), ndv), VS_B(lv));
        const __m256 on = _mm256_and_ps(_mm256_cmp_ps(rv, zero, _CMP_GT_OQ), lit);
        const __m256i at =
            _mm256_cvttps_epi32(VS_ADD(VS_MUL(rv, VS_B((float)VV_VC_SPEC)), VS_B(0.5f)));
        int32_t ix[8];
        float sv[8];
        _mm256_storeu_si256((__m256i *)(void *)ix, at);
        const int onm = _mm256_movemask_ps(on);
        for (int q = 0; q < 8; q++)
            sv[q] = onm >> q & 1 ? o->spec[ix[q]] : 0.0f;
        __m256 sp = _mm256_loadu_ps(sv);
        __m256 wd = _mm256_and_ps(ndl, lit);
        if (shadow) { /* vv_vshade's wd = sh ndl, sp = sh sp */
            const __m256 sh = _mm256_loadu_ps(shadow + 8 * l);
            wd = VS_MUL(sh, wd);
            sp = VS_MUL(sh, sp);
        }
        d0 = VS_ADD(d0, VS_MUL(wd, VS_B(o->kd_col[l][0])));
        d1 = VS_ADD(d1, VS_MUL(wd, VS_B(o->kd_col[l][1])));
        d2 = VS_ADD(d2, VS_MUL(wd, VS_B(o->kd_col[l][2])));
        s0 = VS_ADD(s0, VS_MUL(sp, VS_B(o->ks_col[l][0])));
        s1 = VS_ADD(s1, VS_MUL(sp, VS_B(o->ks_col[l][1])));
        s2 = VS_ADD(s2, VS_MUL(sp, VS_B(o->ks_col[l][2])));
    }
    /* unlit lanes (a gradient of length 0): vv_vshade's d = amb, s = 0 */
    d0 = _mm256_blendv_ps(VS_B(o->amb[0]), d0, lit);
    d1 = _mm256_blendv_ps(VS_B(o->amb[1]), d1, lit);
    d2 = _mm256_blendv_ps(VS_B(o->amb[2]), d2, lit);
    s0 = _mm256_and_ps(s0, lit);
    s1 = _mm256_and_ps(s1, lit);
    s2 = _mm256_and_ps(s2, lit);
    const __m256 al = _mm256_loadu_ps(a);
    _mm256_storeu_ps(out_r, VS_ADD(VS_MUL(d0, _mm256_loadu_ps(cr)), VS_MUL(al, s0)));
    _mm256_storeu_ps(out_g, VS_ADD(VS_MUL(d1, _mm256_loadu_ps(cg)), VS_MUL(al, s1)));
    _mm256_storeu_ps(out_b, VS_ADD(VS_MUL(d2, _mm256_loadu_ps(cb)), VS_MUL(al, s2)));
#undef VS_MUL
#undef VS_ADD
#undef VS_B
}

int
vv_vchunk_shade8(const vv_vcache *c, const float *lut, const vv_vshading *o,
                 const vv_vlight *lights, int n_lights, const float v[3], int m, const size_t *cell,
                 const float *fx, const float *fy, const float *fz, const int32_t *entry,
                 vv_vshadow8_fn shadow, void *ctx, float et, float C[3], float *A, int *first,
                 uint32_t *shaded) {
    int vis[VV_VC_CHUNK], nvis = 0;
    for (int s = 0; s < m; s++)
        if (lut[entry[s]] > 0)
            vis[nvis++] = s;
    for (int i0 = 0; i0 < nvis; i0 += 8) {
        const int n8 = nvis - i0 < 8 ? nvis - i0 : 8;
        float gx[8] = {0}, gy[8] = {0}, gz[8] = {0}, al[8] = {0};
        float cr[8] = {0}, cg[8] = {0}, cb[8] = {0}, sh[VV_MAX_LIGHTS * 8];
        float orr[8], org[8], orb[8];
        int shadowed = 0;
        if (shadow)
            memset(sh, 0, sizeof(float) * 8 * (size_t)n_lights);
        for (int q = 0; q < n8; q++) {
            const int s = vis[i0 + q];
            const float *e = lut + entry[s];
            const float f[3] = {fx[s], fy[s], fz[s]};
            float g[3];
            vv_vcache_gradient_at(c, cell[s], f, g);
            if (shadow)
                shadowed = shadow(ctx, s, sh + q, 8);
            gx[q] = g[0];
            gy[q] = g[1];
            gz[q] = g[2];
            al[q] = e[0];
            cr[q] = e[1];
            cg[q] = e[2];
            cb[q] = e[3];
        }
        vv_vshade8(o, lights, n_lights, v, shadowed ? sh : NULL, gx, gy, gz, al, cr, cg, cb, orr,
                   org, orb);
        for (int q = 0; q < n8; q++) {
            ++*shaded;
            const float w = 1 - *A;
            C[0] += w * orr[q];
            C[1] += w * org[q];
            C[2] += w * orb[q];
            *A += w * al[q];
            if (*first < 0)
                *first = vis[i0 + q];
            if (*A >= et)
                return 1;
        }
    }
    return 0;
}

/* The index points of the samples k .. k + 7 of r, as vv_vray_point
 * computes them (no fused multiply-add). */
__attribute__((target("avx2"))) static inline void
points8_avx2(const vv_vray *r, double k, double dt, __m256 *px, __m256 *py, __m256 *pz) {
    float u[8];
    for (int l = 0; l < 8; l++)
        u[l] = (float)((k + l) * dt - r->tb);
    const __m256 t = _mm256_loadu_ps(u);
    *px = _mm256_sub_ps(
        _mm256_add_ps(_mm256_set1_ps(r->o[0]), _mm256_mul_ps(t, _mm256_set1_ps(r->d[0]))),
        _mm256_set1_ps(r->off[0]));
    *py = _mm256_sub_ps(
        _mm256_add_ps(_mm256_set1_ps(r->o[1]), _mm256_mul_ps(t, _mm256_set1_ps(r->d[1]))),
        _mm256_set1_ps(r->off[1]));
    *pz = _mm256_sub_ps(
        _mm256_add_ps(_mm256_set1_ps(r->o[2]), _mm256_mul_ps(t, _mm256_set1_ps(r->d[2]))),
        _mm256_set1_ps(r->off[2]));
}

/* The trilinear values at index points px, py, pz (16-bit values), in the
 * lerp order of vv_vcache_value_at. */
__attribute__((target("avx2"))) static inline __m256
values_at8_avx2(const vv_vcache *c, __m256 px, __m256 py, __m256 pz) {
    __m256 wx, wy, wz;
    int32_t p00[8], p10[8], p01[8], p11[8];
    (void)cell_pairs_avx2(c, px, py, pz, &wx, &wy, &wz, p00, p10, p01, p11);
    const __m256 c00 = pair_lerp_avx2(p00, wx), c10 = pair_lerp_avx2(p10, wx);
    const __m256 c01 = pair_lerp_avx2(p01, wx), c11 = pair_lerp_avx2(p11, wx);
    const __m256 c0 = _mm256_add_ps(c00, _mm256_mul_ps(_mm256_sub_ps(c10, c00), wy));
    const __m256 c1 = _mm256_add_ps(c01, _mm256_mul_ps(_mm256_sub_ps(c11, c01), wy));
    return _mm256_add_ps(c0, _mm256_mul_ps(_mm256_sub_ps(c1, c0), wz));
}

/* values_chunk_avx2 of the eight samples kfirst .. kfirst + 7, in a
 * register. */
__attribute__((target("avx2"))) static inline __m256
values8_avx2(const vv_vcache *c, const vv_vray *r, double kfirst, double dt) {
    __m256 px, py, pz;
    points8_avx2(r, kfirst, dt, &px, &py, &pz);
    return values_at8_avx2(c, px, py, pz);
}

/* The trilinear values of the samples kfirst .. kfirst + m - 1 (m <=
 * VV_VC_CHUNK) of r, eight at a time: the scalar path's arithmetic. */
__attribute__((target("avx2"))) static void
values_chunk_avx2(const vv_vcache *c, const vv_vray *r, double kfirst, double dt, int m,
                  float *val) {
    float out[VV_VC_CHUNK + 8];
    for (int s = 0; s < m; s += 8)
        _mm256_storeu_ps(out + s, values8_avx2(c, r, kfirst + s, dt));
    memcpy(val, out, (size_t)m * sizeof *val);
}
#endif

/* The subvolume of index point p: its grid coordinates in bc (clamped)
 * and its index. */
static inline size_t
proj_block(const vv_vcache *c, const float p[3], int bc[3]) {
    for (int a = 0; a < 3; a++) {
        bc[a] = (int)((p[a] > 0 ? p[a] : 0) * (1.0f / VV_VC_BLOCK));
        const int bn = a == 0 ? c->bx : a == 1 ? c->by : c->bz;
        bc[a] = bc[a] >= bn ? bn - 1 : bc[a];
    }
    return ((size_t)bc[2] * (size_t)c->by + (size_t)bc[1]) * (size_t)c->bx + (size_t)bc[0];
}

/* The group of subvolumes of index point p (clamped). */
static inline size_t
proj_group(const vv_vcache *c, const float p[3]) {
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    int gi = (int)((p[0] > 0 ? p[0] : 0) * (1.0f / gsize));
    int gj = (int)((p[1] > 0 ? p[1] : 0) * (1.0f / gsize));
    int gk = (int)((p[2] > 0 ? p[2] : 0) * (1.0f / gsize));
    gi = gi >= c->gx ? c->gx - 1 : gi;
    gj = gj >= c->gy ? c->gy - 1 : gj;
    gk = gk >= c->gz ? c->gz - 1 : gk;
    return ((size_t)gk * (size_t)c->gy + (size_t)gj) * (size_t)c->gx + (size_t)gi;
}

/* The sample after leaving the cube of 2 dist - 1 subvolumes around
 * subvolume bc (p, sample k, in it). */
static inline double
proj_leap(const vv_vray *r, const float p[3], const int bc[3], int dist, double k, double dt) {
    float te = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        const float bound = r->d[a] > 0 ? (float)(bc[a] + dist) * VV_VC_BLOCK
                                        : (float)(bc[a] - dist + 1) * VV_VC_BLOCK;
        const float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    const double ks = vv_ceil_pos((k * dt + te) / dt);
    return ks > k + 1 ? ks : k + 1;
}

/* The sample after the cube of @p size index units around p (sample k). */
static inline double
proj_after_cube(const vv_vray *r, const float p[3], double k, double dt, int size) {
    const double ks = vv_ceil_pos(vv_vray_cube_exit(r, p, k * dt, size) / dt);
    return ks > k + 1 ? ks : k + 1;
}

/* The last sample (at most kend, at least k) in the subvolume of p. */
static inline double
proj_block_last(const vv_vray *r, const float p[3], double k, double kend, double dt) {
    double klast = vv_floor_pos(vv_vray_cube_exit(r, p, k * dt, VV_VC_BLOCK) / dt);
    klast = klast < kend ? klast : kend;
    return klast < k ? k : klast;
}

/* The samples k .. klast of ray r in the running maximum of sg * value
 * (best, tbest: the parameter of its first sample): one subvolume's march. */
static void
project_block(const vv_vcache *c, const vv_vray *r, double k, double klast, double dt, float sg,
              int avx2, float *best, double *tbest) {
#if VV_VC_HAVE_AVX2
    if (avx2) {
        while (k <= klast) {
            const int m = klast - k + 1 < VV_VC_CHUNK ? (int)(klast - k + 1) : VV_VC_CHUNK;
            float val[VV_VC_CHUNK];
            values_chunk_avx2(c, r, k, dt, m, val);
            for (int s = 0; s < m; s++) {
                const float x = sg * val[s];
                if (x > *best) {
                    *best = x;
                    *tbest = (k + s) * dt;
                }
            }
            k += m;
        }
        return;
    }
#else
    (void)avx2;
#endif
    for (; k <= klast; k++) {
        float p[3], f[3];
        vv_vray_point(r, k * dt, p);
        const size_t o = vv_vcache_cell_in(c, p, f);
        const float x = sg * vv_vcache_value_at(c, o, f);
        if (x > *best) {
            *best = x;
            *tbest = k * dt;
        }
    }
}

#if VV_VC_HAVE_AVX2
/* The subvolumes (proj_block's, vv_vblock_of's) of the samples k .. k + 7
 * of r, their points computed as vv_vray_point does. */
__attribute__((target("avx2"))) static inline __m256i
blocks8_avx2(const vv_vcache *c, const vv_vray *r, double k, double dt) {
    const __m256 zero = _mm256_setzero_ps(), quarter = _mm256_set1_ps(1.0f / VV_VC_BLOCK);
    __m256 px, py, pz;
    points8_avx2(r, k, dt, &px, &py, &pz);
    const __m256i bi =
        _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(px, zero), quarter)),
                         _mm256_set1_epi32(c->bx - 1));
    const __m256i bj =
        _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(py, zero), quarter)),
                         _mm256_set1_epi32(c->by - 1));
    const __m256i bk =
        _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(_mm256_max_ps(pz, zero), quarter)),
                         _mm256_set1_epi32(c->bz - 1));
    return _mm256_add_epi32(
        _mm256_mullo_epi32(_mm256_add_epi32(_mm256_mullo_epi32(bk, _mm256_set1_epi32(c->by)), bj),
                           _mm256_set1_epi32(c->bx)),
        bi);
}

/* vv_vray_visible_run_avx2 leaps from a hidden subvolume at this chessboard
 * distance or more, and scans the samples ahead from one closer (1 measured
 * faster than 2 or 4, docs/rendering.md). */
#define VRUN_LEAP 2
__attribute__((target("avx2"))) int
vv_vray_visible_run_avx2(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt,
                         double kend, double *kp, double *klastp) {
    double k = *kp;
    while (k <= kend) {
        float p[3];
        double t;
        unsigned bc[3];
        if (vv_vray_leap_from(c, bdist, r, dt, VRUN_LEAP, &k, p, &t, bc))
            continue;
        /* near a visible subvolume: the first sample of the next VV_VC_CHUNK
         * in a visible subvolume, and the run on from it while they are */
        const int n = kend - k + 1 < VV_VC_CHUNK ? (int)(kend - k + 1) : VV_VC_CHUNK;
        int first = -1, len = 0;
        for (int s = 0, open = 1; open && s < n; s += 8) {
            int32_t id[8];
            _mm256_storeu_si256((__m256i *)(void *)id, blocks8_avx2(c, r, k + s, dt));
            for (int l = 0; open && l < 8 && s + l < n; l++) {
                const int vis = !bdist[id[l]];
                if (first >= 0)
                    open = vis;
                else if (vis)
                    first = s + l;
                len += first >= 0 && open;
            }
        }
        if (first < 0) {
            k += n;
            continue;
        }
        k += first;
        *kp = k;
        *klastp = k + len - 1;
        return 1;
    }
    *kp = k;
    return 0;
}

#define PROJ_CHUNK 64 /* samples a chunk of project_from_avx2 */
/* project_from's AVX2 path (16-bit values): the ray is marched in chunks of
 * PROJ_CHUNK consecutive samples instead of one subvolume at a time. At
 * the first chunk, and after a chunk that had nothing to interpolate, the
 * leaps of project_from are tried at its first sample (the distance map,
 * then the group); then every sample's subvolume is found eight lanes at a
 * time and its extreme gathered, and only the runs of eight holding a
 * sample whose subvolume can beat the running extreme (as of the chunk's
 * start) are interpolated, each reduced in registers to its extreme and
 * the first lane holding it. A sample in a subvolume that cannot beat it
 * cannot change the result, so the value is project_from's, at its first
 * sample (the same arithmetic); only a ray that reaches @p stop may stop
 * later (at the end of a run of eight), with a value beyond the stop as
 * well. The traversal's cost per subvolume, which dominated magnified
 * views (a subvolume holds about eight samples at the usual half-voxel
 * step), becomes a few vector instructions per eight samples. 64 samples
 * a chunk measured faster than 16, 32, 128 or 256 (docs/rendering.md). */
__attribute__((target("avx2"))) static float
project_from_avx2(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, double dt, double k,
                  double kend, float sg, float floor0, float stop, int skipping,
                  double *tbest_out) {
    const float *bext = sg > 0 ? c->bmax : c->bmin, *gext = sg > 0 ? c->gmax : c->gmin;
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    float best = floor0;
    double tbest = r->t0;
    const __m256 zero = _mm256_setzero_ps(), vsg = _mm256_set1_ps(sg);
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    int dead = 1; /* the last chunk had nothing to interpolate (or this is the first) */
    while (k <= kend && best < stop) {
        if (skipping && dead) {
            float p[3];
            vv_vray_point(r, k * dt, p);
            int bc[3];
            const size_t b = proj_block(c, p, bc);
            if (pdist && pdist[b]) {
                k = proj_leap(r, p, bc, pdist[b], k, dt);
                continue;
            }
            if (sg * gext[proj_group(c, p)] <= best) {
                k = proj_after_cube(r, p, k, dt, gsize);
                continue;
            }
        }
        const int m = kend - k + 1 < PROJ_CHUNK ? (int)(kend - k + 1) : PROJ_CHUNK;
        uint64_t live = ~(uint64_t)0 >> (64 - (m + 7) / 8); /* runs of eight to interpolate */
        if (skipping) {
            const __m256 vbest = _mm256_set1_ps(best);
            live = 0;
            for (int s = 0; s < m; s += 8) {
                const __m256i idx = blocks8_avx2(c, r, k + s, dt); /* proj_block's */
                const __m256i in = _mm256_cmpgt_epi32(_mm256_set1_epi32(m - s), lane);
                const __m256 ext =
                    _mm256_mask_i32gather_ps(zero, bext, idx, _mm256_castsi256_ps(in), 4);
                const __m256 beat =
                    _mm256_and_ps(_mm256_cmp_ps(_mm256_mul_ps(vsg, ext), vbest, _CMP_GT_OQ),
                                  _mm256_castsi256_ps(in));
                if (_mm256_movemask_ps(beat))
                    live |= (uint64_t)1 << (s / 8);
            }
        }
        dead = !live;
        for (int s = 0; live && s < m && best < stop; s += 8) {
            if (!(live & ((uint64_t)1 << (s / 8))))
                continue;
            const int n = m - s < 8 ? m - s : 8;
            /* the run's largest sg * value, at its first lane: where a
             * sample-by-sample scan would leave the maximum */
            __m256 x = _mm256_mul_ps(vsg, values8_avx2(c, r, k + s, dt));
            if (n < 8)
                x = _mm256_blendv_ps(
                    _mm256_set1_ps(-INFINITY), x,
                    _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(n), lane)));
            __m256 h = _mm256_max_ps(x, _mm256_permute2f128_ps(x, x, 1));
            h = _mm256_max_ps(h, _mm256_shuffle_ps(h, h, _MM_SHUFFLE(1, 0, 3, 2)));
            h = _mm256_max_ps(h, _mm256_shuffle_ps(h, h, _MM_SHUFFLE(2, 3, 0, 1)));
            const float top = _mm256_cvtss_f32(h);
            if (top > best) {
                const int at =
                    __builtin_ctz((unsigned)_mm256_movemask_ps(_mm256_cmp_ps(x, h, _CMP_EQ_OQ)));
                best = top;
                tbest = (k + s + at) * dt;
            }
        }
        k += m;
    }
    *tbest_out = tbest;
    return best;
}
#endif

/* The maximum of sg * value over the samples k .. kend of r that exceed
 * @p floor0 (floor0 itself when none does, at parameter t0), stopping once
 * it reaches @p stop (at the end of the subvolume where it does);
 * *tbest: the parameter of its first sample. One subvolume at a time. */
static float
project_from(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, double dt, double k,
             double kend, float sg, float floor0, float stop, int skipping, double *tbest_out) {
    const float *bext = sg > 0 ? c->bmax : c->bmin, *gext = sg > 0 ? c->gmax : c->gmin;
    float best = floor0;
    double tbest = r->t0;
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    while (k <= kend && best < stop) {
        float p[3];
        vv_vray_point(r, k * dt, p);
        int bc[3];
        const size_t b = proj_block(c, p, bc);
        if (skipping && pdist && pdist[b]) {
            /* leave the cube of 2 dist - 1 subvolumes around p that hold
             * nothing beyond the starting bound */
            k = proj_leap(r, p, bc, pdist[b], k, dt);
            continue;
        }
        if (skipping) {
            /* a group, then a subvolume, that cannot beat the current
             * extreme is skipped whole (the test is strict, so its samples
             * could not change the result) */
            int size = 0;
            if (sg * gext[proj_group(c, p)] <= best)
                size = gsize;
            else if (sg * bext[b] <= best)
                size = VV_VC_BLOCK;
            if (size) {
                k = proj_after_cube(r, p, k, dt, size);
                continue;
            }
        }
        const double klast = proj_block_last(r, p, k, kend, dt);
        project_block(c, r, k, klast, dt, sg, 0, &best, &tbest);
        k = klast + 1;
    }
    *tbest_out = tbest;
    return best;
}

/* project_from, or with @p vec its AVX2 path */
static float
march(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, double dt, double k, double kend,
      float sg, float floor0, float stop, int skipping, int vec, double *tbest) {
#if VV_VC_HAVE_AVX2
    if (vec)
        return project_from_avx2(c, pdist, r, dt, k, kend, sg, floor0, stop, skipping, tbest);
#else
    (void)vec;
#endif
    return project_from(c, pdist, r, dt, k, kend, sg, floor0, stop, skipping, tbest);
}

/* A ray shorter than one step: its one sample, in the middle (*depth). */
static float
middle_sample(const vv_vcache *c, const vv_vray *r, float *depth) {
    float p[3];
    const double tm = 0.5 * (r->t0 + r->t1);
    vv_vray_point(r, tm, p);
    *depth = (float)tm;
    return vv_vcache_sample(c, p);
}

void
vv_xray_table_classify(const void *ctx, float v, float e[4]) {
    const vv_xray_table *x = ctx;
    float i = (v - x->lut_lo) * x->lut_scale;
    i = i < 0 ? 0 : i > VV_VC_LUT - 1 ? VV_VC_LUT - 1 : i;
    memcpy(e, x->lut + 4 * (int)i, 4 * sizeof(float));
}

long
vv_vray_xray_region_pixel(const vv_vcache *c, const double w2i[3][4], const int dims[3],
                          const vv_plane *planes, int n_planes, const vv_render_region *rg,
                          double dt, int inv_form, const vv_ray *wr, int avx2, float px[4],
                          float *depth, float *key) {
    px[0] = px[1] = px[2] = px[3] = 0;
    *depth = INFINITY;
    *key = NAN;
    vv_vray r;
    int cont = 0;
    if (!vv_vray_setup(w2i, dims, planes, n_planes, wr, 0, INFINITY, &r))
        return 0;
    const float entry = (float)r.t0;
    const int shortray = vv_ceil_pos(r.t0 / dt) > vv_floor_pos(r.t1 / dt);
    if (!vv_vray_clip_region(&r, rg, dt, inv_form, &cont))
        return 0;
    double sum;
    float mid;
    const long n = vv_vray_xray_sum(c, &r, dt, avx2, &sum, &mid);
    if (n <= 0)
        return 0;
    const float hi = (float)sum;
    *key = hi;
    px[0] = (float)(sum - (double)hi);
    px[1] = (float)n;
    /* the whole ray's depth: its entry, or its one middle sample */
    *depth = shortray ? mid : cont ? INFINITY : entry;
    return n;
}

long
vv_vray_xray_sum(const vv_vcache *c, const vv_vray *r, double dt, int avx2, double *sum,
                 float *depth) {
    double k = vv_ceil_pos(r->t0 / dt);
    const double kend = vv_floor_pos(r->t1 / dt);
    if (k > kend) {
        *sum = middle_sample(c, r, depth);
        return 1;
    }
    const int vec = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
    double acc = 0;
    long n = 0;
#if VV_VC_HAVE_AVX2
    /* the same values, eight at a time, added in the same order */
    for (; vec && k <= kend; k += VV_VC_CHUNK) {
        const int m = kend - k + 1 < VV_VC_CHUNK ? (int)(kend - k + 1) : VV_VC_CHUNK;
        float val[VV_VC_CHUNK];
        values_chunk_avx2(c, r, k, dt, m, val);
        for (int s = 0; s < m; s++)
            acc += val[s];
        n += m;
    }
#else
    (void)vec;
#endif
    for (; k <= kend; k++) {
        float p[3], f[3];
        vv_vray_point(r, k * dt, p);
        const size_t o = vv_vcache_cell_in(c, p, f);
        acc += vv_vcache_value_at(c, o, f);
        n++;
    }
    *sum = acc;
    *depth = (float)r->t0;
    return n;
}

static void
project(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, vv_render_mode mode, double dt,
        int skipping, int avx2, float lo, float hi, float *value, float *depth) {
    if (mode == VV_MODE_XRAY) {
        double sum;
        const long n = vv_vray_xray_sum(c, r, dt, avx2, &sum, depth);
        *value = (float)(sum / (double)n);
        return;
    }
    double k = vv_ceil_pos(r->t0 / dt);
    const double kend = vv_floor_pos(r->t1 / dt);
    if (k > kend) {
        *value = middle_sample(c, r, depth);
        return;
    }
    const int vec = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
    const int mip = mode == VV_MODE_MIP;
    /* work on the maximum of +-value, so MinIP is MIP of the negation */
    const float sg = mip ? 1.0f : -1.0f;
    const float floor0 = mip ? lo : -hi; /* what nothing below can change */
    const float stop = mip ? hi : -lo;   /* what nothing above can change */
    double tbest;
    const float best = march(c, pdist, r, dt, k, kend, sg, floor0, stop, skipping, vec, &tbest);
    *value = sg * best;
    *depth = (float)tbest;
}

double
vv_vray_iso_first(const vv_vcache *c, const uint8_t *bdist, const vv_vray *r, double dt, float iso,
                  int avx2, int cont) {
    const double k0 = vv_ceil_pos(r->t0 / dt), kend = vv_floor_pos(r->t1 / dt);
    const int vec = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
    double k = k0, klast, kprev = k0 - 2; /* the last sample of the previous run */
    float pv = 0;                         /* the value at pt (one side of iso) */
    double pt = 0;
    int have = 0;
    if (cont && k0 <= kend) {
        /* a region's search starts at the whole ray's sample before it */
        vv_vray_iso_restart(c, r, k0, dt, &pv, &pt, &have);
        if (pv >= iso)
            return pt;
        kprev = k0 - 1;
    }
    while (vv_vray_visible_run_simd(avx2, c, bdist, r, dt, kend, &k, &klast)) {
        if (k > k0 && k != kprev + 1) {
            /* after hidden samples (all below iso): the crossing search
             * restarts at the sample before the run, as a march of every
             * sample has it, so that the crossing does not depend on the
             * subvolume grid (skipping on or off, a region's voxels) */
            vv_vray_iso_restart(c, r, k, dt, &pv, &pt, &have);
        }
        /* a run of the portable traversal may exceed a chunk (its first
         * subvolume is whole, and holds more than VV_VC_CHUNK samples at a
         * step under 1/8 voxel) */
        for (double j = k; j <= klast; j += VV_VC_CHUNK) {
            const int n = klast - j + 1 < VV_VC_CHUNK ? (int)(klast - j) + 1 : VV_VC_CHUNK;
            float val[VV_VC_CHUNK];
#if VV_VC_HAVE_AVX2
            if (vec)
                values_chunk_avx2(c, r, j, dt, n, val);
#else
            (void)vec;
#endif
            for (int s = 0; s < n; s++) {
                const double t = (j + s) * dt;
                if (!vec) {
                    float p[3];
                    vv_vray_point(r, t, p);
                    val[s] = vv_vcache_sample(c, p);
                }
                if (!have) {
                    if (val[s] >= iso && t - r->t0 < dt)
                        return t; /* entered already inside (a cut face) */
                } else if ((pv < iso) != (val[s] < iso)) {
                    return vv_vray_iso_refine(c, r, pt, pv, t, iso);
                }
                pv = val[s];
                pt = t;
                have = 1;
            }
        }
        kprev = klast;
        k = klast + 1;
    }
    return -1;
}

void
vv_vray_project(const vv_vcache *c, const vv_vray *r, vv_render_mode mode, double dt, int skipping,
                float lo, float hi, float *value, float *depth) {
    project(c, NULL, r, mode, dt, skipping, 0, lo, hi, value, depth);
}

void
vv_vray_project_tables(const vv_vcache *c, const vv_vtables *t, const vv_vray *r,
                       vv_render_mode mode, double dt, int skipping, int avx2, float *value,
                       float *depth) {
    if (t->pdist)
        project(c, t->pdist, r, mode, dt, skipping, avx2, t->plo, t->phi, value, depth);
    else
        project(c, NULL, r, mode, dt, skipping, avx2, -INFINITY, INFINITY, value, depth);
}

void
vv_vray_project_channels(const vv_vcache *const *cs, const vv_vtables *const *ts, int n,
                         const vv_vray *r, double dt, int skipping, int avx2, float *value,
                         float *depth) {
    double k = vv_ceil_pos(r->t0 / dt);
    const double kend = vv_floor_pos(r->t1 / dt);
    if (k > kend || n < 2 || n > VV_MAX_CHANNELS) {
        for (int ch = 0; ch < n; ch++)
            vv_vray_project_tables(cs[ch], ts[ch], r, VV_MODE_MIP, dt, skipping, avx2, &value[ch],
                                   &depth[ch]);
        return;
    }
    float best[VV_MAX_CHANNELS], stop[VV_MAX_CHANNELS];
    double tbest[VV_MAX_CHANNELS];
    int vec[VV_MAX_CHANNELS], act[VV_MAX_CHANNELS], na = 0;
    for (int ch = 0; ch < n; ch++) {
        const vv_vcache *c = cs[ch];
        best[ch] = ts[ch]->pdist ? ts[ch]->plo : -INFINITY;
        stop[ch] = ts[ch]->pdist ? ts[ch]->phi : INFINITY;
        tbest[ch] = r->t0;
        vec[ch] = avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30);
        if (best[ch] < stop[ch])
            act[na++] = ch;
    }
    const vv_vcache *c0 = cs[0]; /* every channel has its grid */
    const int gsize = VV_VC_BLOCK * VV_VC_GROUP;
    while (k <= kend && na > 0) {
        float p[3];
        vv_vray_point(r, k * dt, p);
        int bc[3];
        const size_t b = proj_block(c0, p, bc);
        if (skipping) {
            /* the cube of subvolumes that no live channel has anything in
             * beyond its starting bound (the smallest of their distances),
             * then the group or subvolume that no live channel can beat
             * its maximum in */
            int dist = 255, size = gsize;
            const size_t g = proj_group(c0, p);
            for (int i = 0; i < na; i++) {
                const int ch = act[i];
                const int d = ts[ch]->pdist ? ts[ch]->pdist[b] : 0;
                dist = d < dist ? d : dist;
                const int sz = cs[ch]->gmax[g] <= best[ch]   ? gsize
                               : cs[ch]->bmax[b] <= best[ch] ? VV_VC_BLOCK
                                                             : 0;
                size = sz < size ? sz : size;
            }
            if (dist) {
                k = proj_leap(r, p, bc, dist, k, dt);
                continue;
            }
            if (size) {
                k = proj_after_cube(r, p, k, dt, size);
                continue;
            }
        }
        const double klast = proj_block_last(r, p, k, kend, dt);
        /* each live channel that can change its maximum here marches the
         * subvolume as its one-channel projection does */
        int keep = 0;
        for (int i = 0; i < na; i++) {
            const int ch = act[i];
            if (!skipping ||
                ((!ts[ch]->pdist || ts[ch]->pdist[b] == 0) && cs[ch]->bmax[b] > best[ch]))
                project_block(cs[ch], r, k, klast, dt, 1.0f, vec[ch], &best[ch], &tbest[ch]);
            if (best[ch] < stop[ch])
                act[keep++] = ch;
        }
        na = keep;
        k = klast + 1;
    }
    for (int ch = 0; ch < n; ch++) {
        value[ch] = best[ch];
        depth[ch] = (float)tbest[ch];
    }
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

/* ---------------------------------------------------------------------- */
/* Classification in chunks                                                 */

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

#if VV_VC_HAVE_AVX2
/* classify_chunk for 16-bit values, eight samples at a time with AVX2
 * gathers and FMA; chosen at run time when the processor has them. The
 * arithmetic differs from the portable version only in the rounding of
 * fused multiply-adds, and one render uses one version throughout. */
__attribute__((target("avx2,fma"))) static void
classify_chunk_avx2(const vv_vcache *c, const vv_vtables *ob, const vv_vray *r, double kfirst,
                    double dt, int m, size_t *cell, float *fx, float *fy, float *fz, int32_t *entry,
                    float *x) {
    float u[VV_VC_CHUNK + 8];
    for (int s = 0; s < m; s++)
        u[s] = (float)((kfirst + s) * dt - r->tb);
    for (int s = m; s < m + 8; s++)
        u[s] = u[m - 1]; /* padding lanes repeat the last sample */
    const __m256 ox = _mm256_set1_ps(r->o[0]), oy = _mm256_set1_ps(r->o[1]),
                 oz = _mm256_set1_ps(r->o[2]);
    const __m256 dx = _mm256_set1_ps(r->d[0]), dy = _mm256_set1_ps(r->d[1]),
                 dz = _mm256_set1_ps(r->d[2]);
    const __m256 offx = _mm256_set1_ps(r->off[0]), offy = _mm256_set1_ps(r->off[1]),
                 offz = _mm256_set1_ps(r->off[2]);
    const __m256i lo16 = _mm256_set1_epi32(0xFFFF);
    const __m256 llo = _mm256_set1_ps(ob->lut_lo), lsc = _mm256_set1_ps(ob->lut_scale);
    const __m256 lmax = _mm256_set1_ps((float)(VV_VC_LUT - 1)), fzero = _mm256_setzero_ps();
    for (int s = 0; s < m; s += 8) {
        const __m256 t = _mm256_loadu_ps(u + s);
        const __m256 px = _mm256_sub_ps(_mm256_fmadd_ps(t, dx, ox), offx),
                     py = _mm256_sub_ps(_mm256_fmadd_ps(t, dy, oy), offy),
                     pz = _mm256_sub_ps(_mm256_fmadd_ps(t, dz, oz), offz);
        __m256 wx, wy, wz;
        int32_t p00[8], p10[8], p01[8], p11[8];
        const __m256i o = cell_pairs_avx2(c, px, py, pz, &wx, &wy, &wz, p00, p10, p01, p11);
        const __m256i g00 = _mm256_loadu_si256((const __m256i *)(const void *)p00);
        const __m256i g10 = _mm256_loadu_si256((const __m256i *)(const void *)p10);
        const __m256i g01 = _mm256_loadu_si256((const __m256i *)(const void *)p01);
        const __m256i g11 = _mm256_loadu_si256((const __m256i *)(const void *)p11);
#define VV_PAIR_LERP(g)                                                                            \
    _mm256_fmadd_ps(_mm256_sub_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(g, 16)),                    \
                                  _mm256_cvtepi32_ps(_mm256_and_si256(g, lo16))),                  \
                    wx, _mm256_cvtepi32_ps(_mm256_and_si256(g, lo16)))
        const __m256 c00 = VV_PAIR_LERP(g00), c10 = VV_PAIR_LERP(g10);
        const __m256 c01 = VV_PAIR_LERP(g01), c11 = VV_PAIR_LERP(g11);
#undef VV_PAIR_LERP
        const __m256 c0 = _mm256_fmadd_ps(_mm256_sub_ps(c10, c00), wy, c00);
        const __m256 c1 = _mm256_fmadd_ps(_mm256_sub_ps(c11, c01), wy, c01);
        const __m256 val = _mm256_fmadd_ps(_mm256_sub_ps(c1, c0), wz, c0);
        __m256 li = _mm256_mul_ps(_mm256_sub_ps(val, llo), lsc);
        li = _mm256_min_ps(_mm256_max_ps(li, fzero), lmax);
        const __m256i e = _mm256_slli_epi32(_mm256_cvttps_epi32(li), 2);
        /* all eight lanes (s + 8 <= VV_VC_CHUNK); offsets >= 0, widened */
        _mm256_storeu_si256((__m256i *)(void *)(entry + s), e);
        _mm256_storeu_ps(fx + s, wx);
        _mm256_storeu_ps(fy + s, wy);
        _mm256_storeu_ps(fz + s, wz);
        _mm256_storeu_si256((__m256i *)(void *)(cell + s),
                            _mm256_cvtepi32_epi64(_mm256_castsi256_si128(o)));
        _mm256_storeu_si256((__m256i *)(void *)(cell + s + 4),
                            _mm256_cvtepi32_epi64(_mm256_extracti128_si256(o, 1)));
        if (x)
            _mm256_storeu_ps(x + s, li);
    }
}
#endif

void
vv_vray_classify(const vv_vcache *c, const vv_vtables *t, const vv_vray *r, double kfirst,
                 double dt, int m, int avx2, size_t *cell, float *fx, float *fy, float *fz,
                 int32_t *entry, float *x) {
#if VV_VC_HAVE_AVX2
    if (avx2 && c->q16 && c->sz * (size_t)c->nz < ((size_t)1 << 30)) {
        classify_chunk_avx2(c, t, r, kfirst, dt, m, cell, fx, fy, fz, entry, x);
        return;
    }
#else
    (void)avx2;
#endif
    classify_chunk(c, t, r, kfirst, dt, m, cell, fx, fy, fz, entry, x);
}

int
vv_vc_have_avx2(void) {
#if VV_VC_HAVE_AVX2
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    return 0;
#endif
}
