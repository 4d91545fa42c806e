/*
 * Out-of-core rendering through the region contract
 * (vv_renderer_render_bricks, include/volvis/render.h): a volume source
 * (include/volvis/sys/source.h: .vvb, raw, NRRD read by bricks in src/io)
 * is rendered brick by brick, front to back, each brick one region render
 * (include/volvis/sys/renderer.h) of whichever renderer declares the
 * contract, over the pixels its box projects to, and the partial images
 * are combined in that order (over, or max/min for projections) --
 * sort-last compositing on one machine. The front-to-back order of the
 * brick grid is that of its k-d tree (cut the brick range in two along its
 * longest axis; the half holding the eye, or the half the view direction
 * enters first, before the other), valid for every pixel. A brick whose
 * min/max the transfer function maps to zero opacity is skipped before it
 * is read.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/volume_cache.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"
#include "volvis/sys/source.h"

typedef struct ooc_order {
    int *list;
    int n;
    const int *nb;
    const vv_brick_source *src;
    int ortho;
    double E[3], D[3]; /* eye and view direction, index space */
} ooc_order;

/* The index plane between bricks lo .. mid - 1 and mid .. along axis a:
 * the first brick of the upper half starts there. */
static double
split_plane(const ooc_order *o, int a, const int lo[3], int mid) {
    int idx[3] = {lo[0], lo[1], lo[2]};
    idx[a] = mid;
    vv_brick_info in;
    o->src->info(o->src->user, (idx[2] * o->nb[1] + idx[1]) * o->nb[0] + idx[0], &in);
    return in.lo[a];
}

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
    const double plane = split_plane(o, a, lo, mid);
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

/* The argument checks of vv_renderer_render_bricks. */
static vv_status
check_args(vv_renderer *r, const vv_world *w, int object, const vv_brick_source *src,
           const vv_view *view, const vv_image *out) {
    if (!r || !w || !src || !view || !out || object < 0 || object >= w->n_objects)
        return vv_error_set(VV_ERR_INVALID, "bricks: bad arguments");
    if (src->version != VV_BRICK_SOURCE_VERSION)
        return vv_error_set(VV_ERR_UNSUPPORTED, "bricks: source interface version %d, not %d",
                            src->version, VV_BRICK_SOURCE_VERSION);
    if (out->width != view->width || out->height != view->height)
        return vv_error_set(VV_ERR_INVALID, "bricks: image %dx%d for a %dx%d view", out->width,
                            out->height, view->width, view->height);
    const vv_object *obj = w->objects[object];
    if (obj->type != VV_OBJECT_VOLUME || !obj->volume)
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s' is not a volume", obj->name);
    const vv_renderer_info *info = vv_renderer_get_info(r);
    if (!(info->caps & VV_RENDERER_REGION))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "bricks: %s renders no regions; out-of-core rendering needs a "
                            "renderer with the region contract (`volvis renderers`)",
                            info->name);
    const vv_render_mode mode = obj->mode;
    if (mode != VV_MODE_COMPOSITE && mode != VV_MODE_MIP && mode != VV_MODE_MINIP)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "bricks: object '%s': out-of-core rendering draws composite, mip or "
                            "minip, not xray or iso (they do not split into bricks)",
                            obj->name);
    for (int i = 0; i < w->n_objects; i++)
        if (i != object && w->objects[i]->visible)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "bricks: object '%s': out-of-core rendering draws one object",
                                w->objects[i]->name);
    return VV_OK;
}

vv_status
vv_renderer_render_bricks(vv_renderer *r, const vv_world *w, int object, const vv_brick_source *src,
                          const vv_view *view, const vv_render_options *opt, vv_image *out) {
    vv_status s = check_args(r, w, object, src, view, out);
    if (s != VV_OK)
        return s;
    const vv_object *obj = w->objects[object];
    const vv_render_mode mode = obj->mode;
    const vv_volume *hdr = src->header(src->user);
    int nb[3];
    src->grid(src->user, nb);
    const int n = nb[0] * nb[1] * nb[2];

    /* the whole volume's index space: the object placed with the source's
     * geometry (its own volume may be a coarse proxy) */
    vv_object geo = *obj; /* shallow: nothing in it is released */
    geo.volume = (vv_volume *)hdr;
    const vv_mat4 i2w = vv_object_index_to_world(&geo);
    int ok = 0;
    const vv_mat4 w2i = vv_mat4_inverse(i2w, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s': singular transform", obj->name);
    ooc_order ord;
    memset(&ord, 0, sizeof ord);
    ord.list = malloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
    if (!ord.list)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    ord.nb = nb;
    ord.src = src;
    ord.ortho = view->projection == VV_PROJECTION_ORTHOGRAPHIC;
    const vv_vec3 e = vv_mat4_mul_point(w2i, view->eye);
    const vv_vec3 fwd = vv_vec3_sub(view->at, view->eye);
    ord.E[0] = e.x;
    ord.E[1] = e.y;
    ord.E[2] = e.z;
    for (int a = 0; a < 3; a++)
        ord.D[a] = w2i.m[a][0] * fwd.x + w2i.m[a][1] * fwd.y + w2i.m[a][2] * fwd.z;
    const int zero[3] = {0, 0, 0};
    if (n > 0)
        order_bricks(&ord, zero, nb);

    const size_t np = (size_t)view->width * (size_t)view->height;
    vv_image *part = NULL;
    float *keys = malloc(sizeof(float) * 2 * (np ? np : 1));
    vv_region_image whole = {out, keys, VV_REGION_OVER};
    vv_region_image piece = {NULL, keys ? keys + np : NULL, VV_REGION_OVER};
    s = keys ? vv_image_new(&part, view->width, view->height)
             : vv_error_set(VV_ERR_NOMEM, "out of memory");
    piece.image = part;
    if (s == VV_OK) {
        vv_region_image_clear(&whole);
        whole.op = mode == VV_MODE_MIP     ? VV_REGION_MAX
                   : mode == VV_MODE_MINIP ? VV_REGION_MIN
                                           : VV_REGION_OVER;
    }
    const int skip = mode == VV_MODE_COMPOSITE && obj->segmentation == VV_SEG_TRANSFER_FUNCTION;
    for (int oi = 0; oi < n && s == VV_OK; oi++) {
        const int idx = ord.list[oi];
        vv_brick_info in;
        src->info(src->user, idx, &in);
        /* the ray caster's table maps a value to the entry at or below it:
         * one entry's width lower too (src/render/volume_cache.h) */
        const double bin = (hdr->range[1] - hdr->range[0]) / (VV_VC_LUT - 1);
        if (skip && !(tf_max_opacity(&obj->tf, in.vmin - bin, in.vmax) > 0)) {
            if (src->note_skip)
                src->note_skip(src->user);
            continue;
        }
        vv_render_region rg;
        memset(&rg, 0, sizeof rg);
        rg.object = object;
        vv_region_rect(&rg, i2w, view, in.slo, in.shi);
        if (rg.x1 > rg.x0 && rg.y1 <= rg.y0)
            continue; /* off screen */
        for (int a = 0; a < 3; a++) {
            const int last = hdr->dims[a] - 1;
            rg.dims[a] = hdr->dims[a];
            rg.offset[a] = in.slo[a];
            rg.lo[a] = in.lo[a] > 0 ? in.lo[a] : -INFINITY;
            rg.hi[a] = in.hi[a] < last ? in.hi[a] : INFINITY;
        }
        vv_volume *bv = NULL;
        if ((s = src->load(src->user, idx, &bv)) != VV_OK)
            break;
        rg.voxels = bv;
        s = vv_renderer_render_region(r, w, view, &rg, opt, &piece);
        vv_volume_free(bv); /* the renderer's cache may keep its own reference */
        if (s != VV_OK)
            break;
        if (piece.op != whole.op) {
            s = vv_error_set(VV_ERR_INVALID, "bricks: %s combined its regions by %d, not %d",
                             vv_renderer_name(r), (int)piece.op, (int)whole.op);
            break;
        }
        vv_region_image_combine(&whole, &piece); /* in front over this brick */
    }
    if (s == VV_OK)
        vv_region_image_finish(&whole, w->background);
    vv_image_free(part);
    free(keys);
    free(ord.list);
    return s;
}
