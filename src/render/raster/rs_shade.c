/*
 * The rasterizer's deferred shading: each visible pixel shaded once by
 * vv_raster_finish, with the ray caster's lighting model (rs_internal.h).
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "render/raster/rs_internal.h"
#include "volvis/raster.h"

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
    const int nt = rs_thread_count(r);
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
