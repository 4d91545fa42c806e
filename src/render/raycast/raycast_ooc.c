/*
 * Out-of-core ray casting (include/volvis/bricks.h): a bricked volume is
 * rendered brick by brick, front to back, each brick with the ordinary ray
 * caster in brick mode (raycast_brick.h: rays set up in the whole volume's
 * index space, each sample taken by exactly one brick) over the pixels its
 * box projects to, and the partial images composited in that order (over,
 * premultiplied) -- sort-last compositing on one machine. The front-to-back
 * order of the brick grid is that of its k-d tree (cut the brick range in
 * two along its longest axis; the half holding the eye, or the half the
 * view direction enters first, before the other), valid for every pixel.
 * A brick whose min/max the transfer function maps to zero opacity is
 * skipped before it is read.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/bricks_internal.h"
#include "core/internal.h"
#include "render/raycast/raycast_brick.h"
#include "render/volume_cache.h"
#include "volvis/bricks.h"

typedef struct ooc_order {
    int *list;
    int n;
    const int *nb;
    int ortho;
    double E[3], D[3]; /* eye and view direction, index space */
} ooc_order;

static void
order_bricks(ooc_order *o, const int lo[3], const int hi[3]) {
    int a = 0, len = 0;
    for (int k = 0; k < 3; k++)
        if (hi[k] - lo[k] > len) {
            len = hi[k] - lo[k];
            a = k;
        }
    if (len <= 1) {
        o->list[o->n++] = (lo[2] * o->nb[1] + lo[1]) * o->nb[0] + lo[0];
        return;
    }
    const int mid = lo[a] + len / 2;
    const double plane = (double)mid * VV_BRICK_CELLS;
    const int low_first = o->ortho ? o->D[a] >= 0 : o->E[a] < plane;
    int l1[3], h1[3], l2[3], h2[3];
    memcpy(l1, lo, sizeof l1);
    memcpy(h1, hi, sizeof h1);
    memcpy(l2, lo, sizeof l2);
    memcpy(h2, hi, sizeof h2);
    h1[a] = mid;
    l2[a] = mid;
    if (low_first) {
        order_bricks(o, l1, h1);
        order_bricks(o, l2, h2);
    } else {
        order_bricks(o, l2, h2);
        order_bricks(o, l1, h1);
    }
}

/* The largest opacity of the transfer function over values [a, b]: it is
 * piecewise linear, so the ends and the points between. */
static double
tf_max_opacity(const vv_tf *tf, double a, double b) {
    double m = vv_tf_eval_opacity(tf, a);
    const double mb = vv_tf_eval_opacity(tf, b);
    m = mb > m ? mb : m;
    for (int i = 0; i < tf->n_opacity; i++)
        if (tf->opacity[i].value > a && tf->opacity[i].value < b)
            m = tf->opacity[i].opacity > m ? tf->opacity[i].opacity : m;
    return m;
}

vv_status
vv_bricked_render(vv_bricked *b, vv_renderer *ren, const vv_world *w, int object,
                  const vv_view *view, const vv_render_options *opt, vv_image *out) {
    if (!b || !ren || !w || !view || !out || object < 0 || object >= w->n_objects)
        return vv_error_set(VV_ERR_INVALID, "bricks: bad arguments");
    if (out->width != view->width || out->height != view->height)
        return vv_error_set(VV_ERR_INVALID, "bricks: image %dx%d for a %dx%d view", out->width,
                            out->height, view->width, view->height);
    const vv_object *obj = w->objects[object];
    if (obj->type != VV_OBJECT_VOLUME || !obj->volume)
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s' is not a volume", obj->name);
    const vv_render_mode mode = obj->mode;
    if (mode != VV_MODE_COMPOSITE && mode != VV_MODE_MIP && mode != VV_MODE_MINIP)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "bricks: object '%s': out-of-core rendering draws composite, mip or "
                            "minip, not xray or iso",
                            obj->name);
    for (int i = 0; i < w->n_objects; i++)
        if (i != object && w->objects[i]->visible)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "bricks: object '%s': out-of-core rendering draws one object",
                                w->objects[i]->name);
    const vv_volume *hdr = vv_bricked_header(b);
    int nb[3];
    vv_bricked_grid(b, nb);
    const int n = vv_bricked_count(b);

    /* the World the ray caster sees: the object with each brick in turn,
     * first with the bricked volume's header (its geometry: the object's
     * own volume may be a coarse proxy, vv_bricked_proxy) */
    vv_world *bw = NULL;
    vv_status s = vv_world_clone(&bw, w);
    if (s != VV_OK)
        return s;
    vv_object *bo = bw->objects[object];
    vv_volume_free(bo->volume);
    bo->volume = vv_volume_ref((vv_volume *)hdr);
    /* the eye and view direction in the volume's index space */
    int ok = 0;
    const vv_mat4 w2i = vv_mat4_inverse(vv_object_index_to_world(bo), &ok);
    if (!ok) {
        vv_world_free(bw);
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s': singular transform", obj->name);
    }
    ooc_order ord;
    memset(&ord, 0, sizeof ord);
    ord.list = malloc(sizeof(int) * (size_t)n);
    if (!ord.list) {
        vv_world_free(bw);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    ord.nb = nb;
    ord.ortho = view->projection == VV_PROJECTION_ORTHOGRAPHIC;
    const vv_vec3 e = vv_mat4_mul_point(w2i, view->eye);
    const vv_vec3 fwd = vv_vec3_sub(view->at, view->eye);
    ord.E[0] = e.x;
    ord.E[1] = e.y;
    ord.E[2] = e.z;
    for (int a = 0; a < 3; a++)
        ord.D[a] = w2i.m[a][0] * fwd.x + w2i.m[a][1] * fwd.y + w2i.m[a][2] * fwd.z;
    const int zero[3] = {0, 0, 0};
    order_bricks(&ord, zero, nb);

    vv_image *part = NULL;
    s = vv_image_new(&part, view->width, view->height);
    const size_t np = (size_t)view->width * (size_t)view->height;
    memset(out->rgba, 0, sizeof(float) * 4 * np);
    for (size_t i = 0; i < np; i++)
        out->depth[i] = INFINITY;
    const int skip = mode == VV_MODE_COMPOSITE && obj->segmentation == VV_SEG_TRANSFER_FUNCTION;
    int any_projection = 0;
    for (int oi = 0; oi < n && s == VV_OK; oi++) {
        const int idx = ord.list[oi];
        vv_brick_info in;
        vv_bricked_info(b, idx, &in);
        /* the ray caster's table maps a value to the entry at or below it:
         * one entry's width lower too (src/render/volume_cache.h) */
        const double bin = (hdr->range[1] - hdr->range[0]) / (VV_VC_LUT - 1);
        if (skip && !(tf_max_opacity(&obj->tf, in.vmin - bin, in.vmax) > 0)) {
            vv_bricked_note_skip(b);
            continue;
        }
        vv_raycast_brick rb;
        memset(&rb, 0, sizeof rb);
        vv_raycast_brick_rect(&rb, bo, view, in.slo, in.shi);
        if (rb.x1 > rb.x0 && rb.y1 <= rb.y0)
            continue; /* off screen */
        for (int a = 0; a < 3; a++) {
            const int last = hdr->dims[a] - 1;
            rb.gdims[a] = hdr->dims[a];
            rb.off[a] = in.slo[a];
            rb.lo[a] = in.lo[a] > 0 ? in.lo[a] : -INFINITY;
            rb.hi[a] = in.hi[a] < last ? in.hi[a] : INFINITY;
        }
        vv_volume *bv = NULL;
        if ((s = vv_bricked_load(b, idx, &bv)) != VV_OK)
            break;
        vv_volume_free(bo->volume);
        bo->volume = bv;
        if ((s = vv_raycast_set_brick(ren, &rb)) != VV_OK)
            break;
        if ((s = vv_renderer_render(ren, bw, view, opt, part)) != VV_OK)
            break;
        any_projection |= mode != VV_MODE_COMPOSITE;
        /* out (in front) over part */
        for (size_t i = 0; i < np; i++) {
            float *f = out->rgba + 4 * i;
            const float *p = part->rgba + 4 * i;
            if (mode == VV_MODE_COMPOSITE) {
                const float wgt = 1 - f[3];
                f[0] += wgt * p[0];
                f[1] += wgt * p[1];
                f[2] += wgt * p[2];
                f[3] += wgt * p[3];
                if (out->depth[i] == INFINITY)
                    out->depth[i] = part->depth[i];
            } else if (p[1] > 0 &&
                       (!(f[1] > 0) || (mode == VV_MODE_MIP ? p[0] > f[0] : p[0] < f[0]))) {
                f[0] = p[0];
                f[1] = 1;
                out->depth[i] = part->depth[i];
            }
        }
    }
    vv_raycast_set_brick(ren, NULL);
    if (bw) {
        /* the ray caster's caches drop the last brick with this World */
        vv_world_free(bw);
    }
    vv_image_free(part);
    free(ord.list);
    if (s != VV_OK)
        return s;
    if (mode == VV_MODE_COMPOSITE) {
        const float bg[3] = {(float)w->background.x, (float)w->background.y,
                             (float)w->background.z};
        for (size_t i = 0; i < np; i++) {
            float *pix = out->rgba + 4 * i;
            const float A = pix[3] > 1 ? 1 : pix[3];
            for (int ch = 0; ch < 3; ch++)
                pix[ch] = pix[ch] + (1 - A) * bg[ch];
            pix[3] = A;
        }
        return VV_OK;
    }
    if (!any_projection) {
        /* nothing on screen: the background */
        for (size_t i = 0; i < np; i++) {
            float *pix = out->rgba + 4 * i;
            pix[0] = (float)w->background.x;
            pix[1] = (float)w->background.y;
            pix[2] = (float)w->background.z;
            pix[3] = 0;
        }
        return VV_OK;
    }
    return vv_raycast_finish_projection(ren, out);
}
