/*
 * The region drivers (src/render/drivers.h): out-of-core rendering through
 * the region contract. drv_render_bricks: a brick view of a source
 * (include/volvis/sys/source.h: .vvb, raw, NRRD read by bricks in src/io;
 * an object in memory as one brick) is rendered brick by brick, front to
 * back, each brick one region render
 * (include/volvis/sys/renderer.h) of whichever renderer declares the
 * contract, over the pixels its box projects to, and the partial images
 * are combined in that order (over, or max/min for projections, sums for
 * X-ray, scaled maxima for attenuated MIP: vv_region_op) --
 * sort-last compositing on one machine. The front-to-back order of the
 * brick grid is that of its k-d tree (cut the brick range in two along its
 * longest axis; the half holding the eye, or the half the view direction
 * enters first, before the other), valid for every pixel. A brick whose
 * min/max the transfer function maps to zero opacity is skipped before it
 * is read.
 */
#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/drivers.h"
#include "render/frame.h"
#include "render/shade.h"
#include "render/tf_tables.h"
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

/* The argument checks of drv_render_bricks and drv_render_multires (the
 * source's own checked by the caller). */
static vv_status
check_args(const drv_renderer *r, const vv_world *w, int object, const vv_view *view,
           const vv_image *out) {
    if (!r || !w || !view || !out || object < 0 || object >= w->n_objects)
        return vv_error_set(VV_ERR_INVALID, "bricks: bad arguments");
    if (out->width != view->width || out->height != view->height)
        return vv_error_set(VV_ERR_INVALID, "bricks: image %dx%d for a %dx%d view", out->width,
                            out->height, view->width, view->height);
    const vv_object *obj = w->objects[object];
    if (obj->type != VV_OBJECT_VOLUME || !obj->volume)
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s' is not a volume", obj->name);
    const vv_renderer_info *info = &r->ops->info;
    if (!(info->caps & VV_RENDERER_REGION))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "bricks: %s renders no regions; out-of-core rendering needs a "
                            "renderer with the region contract (`volvis renderers`)",
                            info->name);
    for (int i = 0; i < w->n_objects; i++)
        if (i != object && w->objects[i]->visible)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "bricks: object '%s': out-of-core rendering draws one object",
                                w->objects[i]->name);
    return VV_OK;
}

/* ---- an object's channels by regions -------------------------------------------- */

/* How the drivers draw a multi-channel object (vv_object.channels) by
 * regions. Under the composite rule the channels mix sample by sample,
 * so one region render draws them all (vv_render_region.channel_voxels),
 * combined over as a one-channel composite object's are. Under the
 * additive and maximum rules each channel is composited (or projected)
 * along the whole ray before the channels are added, so each drawn
 * channel is a pass of its own: a region render of the channel as an
 * object of one channel (vv_vchannel_object, as the renderers draw it in
 * memory) into an image of its own, combined over the nodes by over (or
 * max), and the passes added at the end (dc_merge), as raycast.c's
 * trace_channels adds them. A node's channels are read once for all its
 * passes. */
typedef struct drv_chans {
    int multi;                  /* the object has channels (n_channels > 1) */
    int split;                  /* additive or maximum: a pass a channel */
    int npass;                  /* region renders a node: 1, or the drawn channels (split) */
    int n_drawn;                /* the drawn channels (visible, with a volume) */
    int drawn[VV_MAX_CHANNELS]; /* their indices in the object; pass p draws drawn[p] (split) */
    vv_object *chobj;           /* split: the passes' objects of one channel */
    vv_object **slots;          /* split: npass x n_objects, the World's objects with the pass's */
    vv_world *worlds;           /* split: the passes' Worlds */
} drv_chans;

static void
dc_free(drv_chans *c) {
    free(c->chobj);
    free(c->slots);
    free(c->worlds);
    memset(c, 0, sizeof *c);
}

/* @p c for object @p object of @p w. Errors: VV_ERR_INVALID (no channel
 * drawn), VV_ERR_NOMEM. */
static vv_status
dc_init(drv_chans *c, const vv_world *w, int object) {
    memset(c, 0, sizeof *c);
    const vv_object *obj = w->objects[object];
    c->npass = 1;
    if (obj->n_channels < 2)
        return VV_OK;
    c->multi = 1;
    for (int k = 0; k < obj->n_channels; k++)
        if (obj->channels[k].visible && obj->channels[k].volume)
            c->drawn[c->n_drawn++] = k;
    if (c->n_drawn == 0)
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s': no channel is shown", obj->name);
    if (obj->blend == VV_BLEND_COMPOSITE)
        return VV_OK;
    c->split = 1;
    c->npass = c->n_drawn;
    const size_t no = (size_t)w->n_objects;
    c->chobj = calloc((size_t)c->npass, sizeof *c->chobj);
    c->slots = calloc((size_t)c->npass * no, sizeof *c->slots);
    c->worlds = calloc((size_t)c->npass, sizeof *c->worlds);
    if (!c->chobj || !c->slots || !c->worlds) {
        dc_free(c);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    for (int p = 0; p < c->npass; p++) {
        vv_vchannel_object(obj, &obj->channels[c->drawn[p]], &c->chobj[p]);
        vv_object **sl = c->slots + (size_t)p * no;
        for (size_t i = 0; i < no; i++)
            sl[i] = i == (size_t)object ? &c->chobj[p] : w->objects[i];
        c->worlds[p] = *w;
        c->worlds[p].objects = sl;
    }
    return VV_OK;
}

/* The World pass @p p draws (the object's own, one pass). */
static const vv_world *
dc_world(const drv_chans *c, const vv_world *w, int p) {
    return c->split ? &c->worlds[p] : w;
}

/* How pass @p p's regions combine, and the mode its image finishes by. */
static vv_render_mode
dc_mode(const drv_chans *c, const vv_object *obj, int p) {
    return c->split ? c->chobj[p].mode : c->multi ? VV_MODE_COMPOSITE : obj->mode;
}

/* Region @p rg's voxels for pass @p p of a node whose channels are
 * @p vols (object channel order; one-channel object: vols[0]). */
static void
dc_voxels(const drv_chans *c, vv_render_region *rg, vv_volume *const *vols, int p) {
    if (!c->multi) {
        rg->voxels = vols[0];
        rg->channel_voxels = NULL;
    } else if (c->split) {
        rg->voxels = vols[c->drawn[p]];
        rg->channel_voxels = NULL;
    } else {
        rg->voxels = vols[c->drawn[0]];
        rg->channel_voxels = (const vv_volume *const *)vols;
    }
}

/* The split passes' images (@p wholes[0 .. c->npass)): each its own image
 * and keys, cleared, combined by its pass's mode. Free with dc_wholes_free,
 * also on error. */
static vv_status
dc_wholes(const drv_chans *c, const vv_object *obj, const vv_view *view, vv_region_image *wholes) {
    const size_t np = (size_t)view->width * (size_t)view->height;
    for (int p = 0; p < c->npass; p++) {
        wholes[p] = (vv_region_image){.op = vv_region_op_for(dc_mode(c, obj, p))};
        wholes[p].key = malloc(sizeof(float) * (np ? np : 1));
        if (!wholes[p].key)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        vv_status s = vv_image_new(&wholes[p].image, view->width, view->height);
        if (s != VV_OK)
            return s;
        vv_region_image_clear(&wholes[p]);
    }
    return VV_OK;
}

static void
dc_wholes_free(vv_region_image *wholes, int n) {
    for (int p = 0; wholes && p < n; p++) {
        vv_image_free(wholes[p].image);
        free(wholes[p].key);
    }
}

/* 1 when a node whose channels' ranges @p range (as @p get gives them,
 * channel k's into vmin, vmax; 0: unknown) is transparent under every
 * drawn channel's transfer function; @p bin: each channel's table entry
 * width. Label channels are never transparent. */
static int
dc_transparent(const drv_chans *c, const vv_object *obj,
               int (*get)(void *u, int ch, float *vmin, float *vmax), void *u, const double *bin) {
    for (int d = 0; d < c->n_drawn; d++) {
        const int k = c->drawn[d];
        const vv_channel *ch = &obj->channels[k];
        float vmin, vmax;
        if (ch->labels || !get(u, k, &vmin, &vmax) ||
            tf_max_opacity(&ch->tf, vmin - bin[k], vmax) > 0)
            return 0;
    }
    return 1;
}

/* The passes' finished images (each over black) added into @p out over
 * @p background: colour the sum, opacity 1 - prod(1 - opacity), depth
 * the nearest (raycast.c trace_channels and trace_channels_maximum). */
static void
dc_merge(vv_region_image *wholes, int n, vv_vec3 background, vv_image *out) {
    const vv_vec3 black = {0, 0, 0};
    for (int p = 0; p < n; p++)
        vv_region_image_finish(&wholes[p], black);
    const size_t np = (size_t)out->width * (size_t)out->height;
    const float bg[3] = {(float)background.x, (float)background.y, (float)background.z};
    for (size_t i = 0; i < np; i++) {
        float C[3] = {0, 0, 0}, T = 1, depth = INFINITY;
        for (int p = 0; p < n; p++) {
            const float *px = wholes[p].image->rgba + 4 * i;
            for (int k = 0; k < 3; k++)
                C[k] += px[k];
            T *= 1 - (px[3] < 1 ? px[3] : 1);
            const float d = wholes[p].image->depth[i];
            depth = d < depth ? d : depth;
        }
        float *o = out->rgba + 4 * i;
        for (int k = 0; k < 3; k++)
            o[k] = C[k] + T * bg[k];
        o[3] = 1 - T;
        out->depth[i] = depth;
    }
}

/* An iso object's brick or node whose voxels (ghosts included) all lie
 * below the isovalue holds no crossing it owns (each is between a sample
 * of its own and the one before, read from its ghosts): skipped unread.
 * The margin covers the rounding of a trilinear sample above its corners. */
static int
iso_below(const vv_object *obj, const vv_volume *hdr, double vmax) {
    const double margin = 1e-5 * (fabs(hdr->range[0]) + fabs(hdr->range[1]) + 1);
    return obj->mode == VV_MODE_ISO && vmax < obj->isovalue - margin;
}

/* The frame's images: @p whole (the output, cleared, combined by the
 * mode's operation) and @p piece (each region's, clear, kept clear outside
 * each region's rectangle); the keys of both in one block at whole->key.
 * Free piece->image and whole->key after, also on error. */
static vv_status
frame_images(const vv_view *view, vv_image *out, vv_render_mode mode, vv_region_image *whole,
             vv_region_image *piece) {
    const size_t np = (size_t)view->width * (size_t)view->height;
    float *keys = malloc(sizeof(float) * 2 * (np ? np : 1));
    const vv_region_op op = vv_region_op_for(mode);
    *whole = (vv_region_image){.image = out, .key = keys, .op = op};
    *piece =
        (vv_region_image){.key = keys ? keys + np : NULL, .op = VV_REGION_OVER, .clear_outside = 1};
    if (!keys)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = vv_image_new(&piece->image, view->width, view->height);
    if (s != VV_OK)
        return s;
    vv_region_image_clear(piece);
    vv_region_image_clear(whole);
    return VV_OK;
}

/* The pixels region @p rg can touch in a @p W x @p H view (its rectangle,
 * or the whole image when it has none): r = {x0, y0, x1, y1}. */
static void
piece_rect(const vv_render_region *rg, int W, int H, int r[4]) {
    const int has = rg->x1 > rg->x0;
    r[0] = has ? rg->x0 : 0;
    r[1] = has ? rg->y0 : 0;
    r[2] = has ? rg->x1 : W;
    r[3] = has ? rg->y1 : H;
}

/* Quality 2 by regions (vv_region_image.supersample): after the first
 * pass (@p whole combined and finished into @p out), the renderer's points
 * to trace again into *rays, and the images the second pass combines them
 * in (@p rw, and @p rp each region's), of at least one entry a point, in
 * rows of at most 4096; rays->n_pixels 0: no second pass. Free with
 * rays_end, also on error. */
static vv_status
rays_begin(const vv_region_image *whole, const vv_image *out, vv_region_rays *rays,
           vv_region_image *rw, vv_region_image *rp) {
    memset(rays, 0, sizeof *rays);
    *rw = (vv_region_image){0};
    *rp = (vv_region_image){0};
    if (!whole->supersample)
        return VV_OK;
    vv_status s = whole->supersample(whole->supersample_ctx, out, rays);
    if (s != VV_OK || rays->n_pixels == 0)
        return s;
    const size_t n = (size_t)rays->per_pixel * rays->n_pixels;
    const size_t cols = n < 4096 ? n : 4096, rows = (n + cols - 1) / cols;
    if (rows > VV_IMAGE_MAX_SIDE)
        return vv_error_set(VV_ERR_LIMIT, "%zu rays to trace again", n);
    float *keys = malloc(sizeof(float) * 2 * cols * rows);
    *rw = (vv_region_image){.key = keys,
                            .op = whole->op,
                            .classify = whole->classify,
                            .classify_ctx = whole->classify_ctx};
    *rp = (vv_region_image){.key = keys ? keys + cols * rows : NULL, .op = VV_REGION_OVER};
    if (!keys)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if ((s = vv_image_new(&rw->image, (int)cols, (int)rows)) != VV_OK ||
        (s = vv_image_new(&rp->image, (int)cols, (int)rows)) != VV_OK)
        return s;
    vv_region_image_clear(rw);
    vv_region_image_clear(rp);
    return VV_OK;
}

/* The second pass's points (@p rw, combined) finished and averaged into
 * their pixels of @p out: each pixel the mean of its points' colours (summed
 * in order) and their nearest depth, as the whole render supersamples. */
static void
rays_finish(vv_region_image *rw, const vv_region_rays *rays, vv_vec3 background, vv_image *out) {
    vv_region_image_finish(rw, background);
    const int per = rays->per_pixel;
    for (size_t i = 0; i < rays->n_pixels; i++) {
        float acc[4] = {0, 0, 0, 0}, dmin = INFINITY;
        for (int k = 0; k < per; k++) {
            const size_t e = i * (size_t)per + (size_t)k;
            for (int ch = 0; ch < 4; ch++)
                acc[ch] += rw->image->rgba[4 * e + (size_t)ch];
            const float d = rw->image->depth[e];
            dmin = d < dmin ? d : dmin;
        }
        const size_t at = rays->pixel[i];
        for (int ch = 0; ch < 4; ch++)
            out->rgba[4 * at + (size_t)ch] = acc[ch] / (float)per;
        out->depth[at] = dmin;
    }
}

/* 1 when a pixel of @p rays lies in region @p rg's rectangle of a view
 * @p W pixels wide (every region without one): a region without any is
 * not read again. */
static int
rays_in_rect(const vv_region_rays *rays, int W, const vv_render_region *rg) {
    if (rg->x1 <= rg->x0)
        return rays->n_pixels > 0;
    for (int y = rg->y0; y < rg->y1; y++) {
        /* the first listed pixel at or after (x0, y): in the row, before x1? */
        const size_t want = (size_t)y * (size_t)W + (size_t)(rg->x0 > 0 ? rg->x0 : 0);
        size_t lo = 0, hi = rays->n_pixels;
        while (lo < hi) {
            const size_t mid = lo + (hi - lo) / 2;
            if (rays->pixel[mid] < want)
                lo = mid + 1;
            else
                hi = mid;
        }
        if (lo < rays->n_pixels && rays->pixel[lo] < (size_t)y * (size_t)W + (size_t)rg->x1)
            return 1;
    }
    return 0;
}

static void
rays_end(vv_region_rays *rays, vv_region_image *rw, vv_region_image *rp) {
    vv_region_rays_free(rays);
    vv_image_free(rw->image);
    vv_image_free(rp->image);
    free(rw->key);
    *rw = (vv_region_image){0};
    *rp = (vv_region_image){0};
}

vv_status
drv_render_region(const vv_renderer_ops *ops, void *state, const vv_world *world,
                  const vv_view *view, const vv_render_region *region, const vv_render_options *opt,
                  vv_region_image *out) {
    vv_render_options def;
    if (!opt) {
        vv_render_options_init(&def);
        opt = &def;
    }
    if (!ops || !world || !view || !region || !out || !out->image || !out->key)
        return vv_error_set(VV_ERR_INVALID, "region render: NULL argument");
    const char *name = ops->info.name;
    if (!ops->render_region || !(ops->info.caps & VV_RENDERER_REGION))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "%s: renders no regions (out-of-core and distributed rendering "
                            "need a renderer with the region contract: `volvis renderers`)",
                            name);
    if (region->rays) {
        const vv_region_rays *rr = region->rays;
        if (rr->per_pixel < 1 || !rr->xy ||
            (size_t)out->image->width * (size_t)out->image->height <
                (size_t)rr->per_pixel * rr->n_pixels)
            return vv_error_set(
                VV_ERR_INVALID, "%s: region image of %d x %d entries for %zu rays of %d a pixel",
                name, out->image->width, out->image->height, rr->n_pixels, rr->per_pixel);
    } else if (out->image->width != view->width || out->image->height != view->height) {
        return vv_error_set(VV_ERR_INVALID, "%s: region image is %d x %d but the view is %d x %d",
                            name, out->image->width, out->image->height, view->width, view->height);
    }
    if (region->front && (region->rays || region->front->width != view->width ||
                          region->front->height != view->height))
        return vv_error_set(VV_ERR_INVALID,
                            "%s: the image in front of a region must be the view's (%d x %d) "
                            "and its rays one a pixel",
                            name, view->width, view->height);
    if (region->object < 0 || region->object >= world->n_objects || !region->voxels)
        return vv_error_set(VV_ERR_INVALID, "%s: region of object %d without voxels", name,
                            region->object);
    const vv_object *obj = world->objects[region->object];
    if (obj->type != VV_OBJECT_VOLUME || !obj->volume)
        return vv_error_set(VV_ERR_INVALID, "%s: object '%s' is not a volume object", name,
                            obj->name);
    vv_status s = vv_renderer_check_world(&ops->info, world);
    if (s == VV_OK) {
        if (out->clear_outside && region->x1 > region->x0 && !region->rays)
            vv_region_image_clear_rect(out, region->x0, region->y0, region->x1, region->y1);
        else
            vv_region_image_clear(out);
        out->op = VV_REGION_OVER;
        out->supersample = NULL; /* the method's to set */
        out->supersample_ctx = NULL;
        s = ops->render_region(state, world, view, region, opt, out);
    }
    return s == VV_OK ? s : vv_error_prefix(s, "%s", name);
}

/* Region @p rg rendered by @p r into @p piece, which must combine by @p op. */
static vv_status
render_into(const drv_renderer *r, const vv_world *w, const vv_view *view,
            const vv_render_region *rg, const vv_render_options *opt, vv_region_image *piece,
            vv_region_op op) {
    vv_status s = drv_render_region(r->ops, r->state, w, view, rg, opt, piece);
    if (s == VV_OK && piece->op != op)
        s = vv_error_set(VV_ERR_INVALID, "bricks: %s combined its regions by %d, not %d",
                         r->ops->info.name, (int)piece->op, (int)op);
    return s;
}

/* One region render, composited under the image so far over its
 * rectangle; the piece is cleared there again after (it stays clear
 * outside every rectangle: the renderer clears only the next one). */
static vv_status
render_piece(const drv_renderer *r, const vv_world *w, const vv_view *view,
             const vv_render_region *rg, const vv_render_options *opt, vv_region_image *piece,
             vv_region_image *whole) {
    int rc[4] = {0, 0, piece->image->width, piece->image->height}; /* points: every entry */
    if (!rg->rays)
        piece_rect(rg, view->width, view->height, rc);
    vv_status s = render_into(r, w, view, rg, opt, piece, whole->op);
    if (s == VV_OK) /* in front over it */
        vv_region_image_combine_rect(whole, piece, rc[0], rc[1], rc[2], rc[3]);
    vv_region_image_clear_rect(piece, rc[0], rc[1], rc[2], rc[3]);
    return s;
}

/* The whole volume of a brick source read by boxes (vv_region_volume):
 * each voxel of a box copied from the brick whose cells own it (brick i
 * of an axis owns voxels cut[i] <= v < cut[i + 1], the last one the
 * volume's last voxel too). */
typedef struct brick_reader {
    const vv_brick_source *src;
    const vv_volume *hdr;
    int nb[3];
    int *cut[3]; /* nb[a] + 1 voxel indices a axis */
} brick_reader;

static void
brick_reader_free(brick_reader *b) {
    for (int a = 0; a < 3; a++)
        free(b->cut[a]);
}

static vv_status
brick_reader_init(brick_reader *b, const vv_brick_source *src, const vv_volume *hdr,
                  const int nb[3]) {
    memset(b, 0, sizeof *b);
    b->src = src;
    b->hdr = hdr;
    for (int a = 0; a < 3; a++) {
        b->nb[a] = nb[a];
        b->cut[a] = malloc(sizeof(int) * (size_t)(nb[a] + 1));
        if (!b->cut[a]) {
            brick_reader_free(b);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        for (int i = 0; i < nb[a]; i++) {
            int at[3] = {0, 0, 0};
            at[a] = i;
            vv_brick_info in;
            src->info(src->user, (at[2] * nb[1] + at[1]) * nb[0] + at[0], &in);
            b->cut[a][i] = in.lo[a];
        }
        b->cut[a][nb[a]] = hdr->dims[a];
    }
    return VV_OK;
}

/* The bricks whose voxels a box lo .. hi takes (by the bricks' cells):
 * first .. last along each axis; 0 when the box is outside the volume. */
static int
brick_reader_span(const brick_reader *b, const int lo[3], const int hi[3], int first[3],
                  int last[3]) {
    for (int a = 0; a < 3; a++) {
        if (lo[a] < 0 || hi[a] >= b->hdr->dims[a] || lo[a] > hi[a])
            return 0;
        first[a] = 0;
        while (first[a] + 1 < b->nb[a] && b->cut[a][first[a] + 1] <= lo[a])
            first[a]++;
        last[a] = first[a];
        while (last[a] + 1 < b->nb[a] && b->cut[a][last[a] + 1] <= hi[a])
            last[a]++;
    }
    return 1;
}

/* vv_region_volume.box_range: the union of those bricks' min and max. */
static int
brick_reader_range(void *user, const int lo[3], const int hi[3], float *vmin, float *vmax) {
    const brick_reader *b = user;
    int first[3], last[3];
    if (!brick_reader_span(b, lo, hi, first, last))
        return 0;
    *vmin = INFINITY;
    *vmax = -INFINITY;
    for (int k = first[2]; k <= last[2]; k++)
        for (int j = first[1]; j <= last[1]; j++)
            for (int i = first[0]; i <= last[0]; i++) {
                vv_brick_info in;
                b->src->info(b->src->user, (k * b->nb[1] + j) * b->nb[0] + i, &in);
                *vmin = in.vmin < *vmin ? in.vmin : *vmin;
                *vmax = in.vmax > *vmax ? in.vmax : *vmax;
            }
    return 1;
}

static vv_status
brick_reader_box(void *user, const int lo[3], const int hi[3], vv_volume **out) {
    const brick_reader *b = user;
    const vv_volume *h = b->hdr;
    *out = NULL;
    int d[3], first[3], last[3];
    if (!brick_reader_span(b, lo, hi, first, last))
        return vv_error_set(VV_ERR_INVALID, "bricks: box outside the volume");
    for (int a = 0; a < 3; a++)
        d[a] = hi[a] - lo[a] + 1;
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, d, h->type);
    if (s != VV_OK)
        return s;
    const size_t es = vv_voxel_type_size(h->type);
    for (int k = first[2]; k <= last[2] && s == VV_OK; k++)
        for (int j = first[1]; j <= last[1] && s == VV_OK; j++)
            for (int i = first[0]; i <= last[0] && s == VV_OK; i++) {
                const int idx = (k * b->nb[1] + j) * b->nb[0] + i, at[3] = {i, j, k};
                vv_brick_info in;
                b->src->info(b->src->user, idx, &in);
                int c0[3], c1[3]; /* the voxels this brick gives the box */
                for (int a = 0; a < 3; a++) {
                    const int own1 =
                        at[a] + 1 < b->nb[a] ? b->cut[a][at[a] + 1] - 1 : h->dims[a] - 1;
                    c0[a] = b->cut[a][at[a]] > lo[a] ? b->cut[a][at[a]] : lo[a];
                    c1[a] = own1 < hi[a] ? own1 : hi[a];
                }
                vv_volume *bv = NULL;
                if ((s = b->src->load(b->src->user, idx, &bv)) != VV_OK)
                    break;
                if (bv->type != h->type)
                    s = vv_error_set(VV_ERR_FORMAT, "bricks: brick %d is %s, not %s", idx,
                                     vv_voxel_type_name(bv->type), vv_voxel_type_name(h->type));
                for (int z = c0[2]; z <= c1[2] && s == VV_OK; z++)
                    for (int y = c0[1]; y <= c1[1]; y++) {
                        const size_t from = (((size_t)(z - in.slo[2]) * (size_t)bv->dims[1] +
                                              (size_t)(y - in.slo[1])) *
                                                 (size_t)bv->dims[0] +
                                             (size_t)(c0[0] - in.slo[0])) *
                                            es;
                        const size_t to =
                            (((size_t)(z - lo[2]) * (size_t)d[1] + (size_t)(y - lo[1])) *
                                 (size_t)d[0] +
                             (size_t)(c0[0] - lo[0])) *
                            es;
                        memcpy((char *)v->data + to, (const char *)bv->data + from,
                               (size_t)(c1[0] - c0[0] + 1) * es);
                    }
                vv_volume_free(bv);
            }
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    memcpy(v->spacing, h->spacing, sizeof v->spacing);
    memcpy(v->origin, h->origin, sizeof v->origin);
    memcpy(v->direction, h->direction, sizeof v->direction);
    memcpy(v->range, h->range, sizeof v->range);
    v->unit = h->unit;
    *out = v;
    return VV_OK;
}

vv_status
drv_render_bricks(const drv_renderer *r, const vv_world *w, int object, const vv_brick_source *src,
                  const vv_view *view, const vv_render_options *opt, vv_image *out) {
    if (src && src->version != VV_BRICK_SOURCE_VERSION)
        return vv_error_set(VV_ERR_UNSUPPORTED, "bricks: source interface version %d, not %d",
                            src->version, VV_BRICK_SOURCE_VERSION);
    vv_status s = src ? check_args(r, w, object, view, out)
                      : vv_error_set(VV_ERR_INVALID, "bricks: no source");
    if (s != VV_OK)
        return s;
    const vv_object *obj = w->objects[object];
    const vv_volume *hdr = src->header(src->user);
    int nb[3];
    src->grid(src->user, nb);
    const int n = nb[0] * nb[1] * nb[2];
    drv_chans dc;
    if ((s = dc_init(&dc, w, object)) != VV_OK)
        return s;
    const vv_render_mode mode = dc_mode(&dc, obj, 0);
    /* a bricked file holds one channel: an object of several is one brick
     * here, in memory (its channels' own volumes) */
    if (dc.multi &&
        (n != 1 || hdr->dims[0] != obj->volume->dims[0] || hdr->dims[1] != obj->volume->dims[1] ||
         hdr->dims[2] != obj->volume->dims[2])) {
        dc_free(&dc);
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "bricks: object '%s' has %d channels; they are drawn in memory or from "
                            "a pyramid's nodes, not from a bricked file",
                            obj->name, obj->n_channels);
    }

    /* the whole volume's index space: the object placed with the source's
     * geometry (its own volume may be a coarse proxy) */
    vv_object geo = *obj; /* shallow: nothing in it is released */
    geo.volume = (vv_volume *)hdr;
    const vv_mat4 i2w = vv_object_index_to_world(&geo);
    int ok = 0;
    const vv_mat4 w2i = vv_mat4_inverse(i2w, &ok);
    if (!ok) {
        dc_free(&dc);
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s': singular transform", obj->name);
    }
    ooc_order ord;
    memset(&ord, 0, sizeof ord);
    ord.list = malloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
    if (!ord.list) {
        dc_free(&dc);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
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

    vv_region_image whole, piece;
    s = frame_images(view, out, mode, &whole, &piece);
    vv_region_image wholes[VV_MAX_CHANNELS];
    memset(wholes, 0, sizeof wholes);
    if (s == VV_OK && dc.split)
        s = dc_wholes(&dc, obj, view, wholes);
    /* the whole volume by boxes, where the World's volume is a coarse proxy */
    brick_reader reader;
    memset(&reader, 0, sizeof reader);
    vv_region_volume wv = {.user = &reader,
                           .header = hdr,
                           .read_box = brick_reader_box,
                           .box_range = brick_reader_range};
    const int proxy = obj->volume->dims[0] != hdr->dims[0] ||
                      obj->volume->dims[1] != hdr->dims[1] || obj->volume->dims[2] != hdr->dims[2];
    if (s == VV_OK && proxy && n > 0) {
        s = brick_reader_init(&reader, src, hdr, nb);
        wv.tile = reader.cut[0][1] - reader.cut[0][0];
    }
    const int skip =
        !dc.multi && mode == VV_MODE_COMPOSITE && obj->segmentation == VV_SEG_TRANSFER_FUNCTION;
    /* pass 0: a ray a pixel; pass 1 (quality 2 of a renderer that
     * supersamples): the points it asks for, the bricks read again */
    vv_region_rays rays;
    vv_region_image rwhole, rpiece;
    memset(&rays, 0, sizeof rays);
    rwhole = rpiece = (vv_region_image){0};
    for (int pass = 0; pass < 2 && s == VV_OK; pass++) {
        for (int oi = 0; oi < n && s == VV_OK; oi++) {
            const int idx = ord.list[oi];
            vv_brick_info in;
            src->info(src->user, idx, &in);
            /* the ray caster's table maps a value to the entry at or below it:
             * one entry's width lower too (src/render/classify.h) */
            const double bin = (hdr->range[1] - hdr->range[0]) / (VV_VC_LUT - 1);
            if ((skip && !(tf_max_opacity(&obj->tf, in.vmin - bin, in.vmax) > 0)) ||
                iso_below(obj, hdr, in.vmax)) {
                if (src->note_skip && pass == 0)
                    src->note_skip(src->user);
                continue;
            }
            vv_render_region rg;
            memset(&rg, 0, sizeof rg);
            rg.object = object;
            rg.whole = proxy ? &wv : NULL;
            rg.rays = pass ? &rays : NULL;
            /* the bricks come front to back: what is composited so far lies
             * in front of this one (a renderer's early ray termination) */
            rg.front = !pass && !dc.split && whole.op == VV_REGION_OVER ? whole.image : NULL;
            rg.from = hdr; /* the brick known by its box: a renderer may keep it */
            vv_region_rect(&rg, i2w, view, in.slo, in.shi);
            if (rg.x1 > rg.x0 && rg.y1 <= rg.y0)
                continue; /* off screen */
            if (pass && !rays_in_rect(&rays, view->width, &rg))
                continue; /* no ray of the second pass */
            for (int a = 0; a < 3; a++) {
                const int last = hdr->dims[a] - 1;
                rg.dims[a] = hdr->dims[a];
                rg.offset[a] = in.slo[a];
                rg.lo[a] = in.lo[a] > 0 ? in.lo[a] : -INFINITY;
                rg.hi[a] = in.hi[a] < last ? in.hi[a] : INFINITY;
            }
            vv_volume *vols[VV_MAX_CHANNELS] = {NULL};
            if (dc.multi) /* in memory: the channels' own volumes */
                for (int d = 0; d < dc.n_drawn; d++)
                    vols[dc.drawn[d]] = vv_volume_ref(obj->channels[dc.drawn[d]].volume);
            else if ((s = src->load(src->user, idx, &vols[0])) != VV_OK)
                break;
            for (int p = 0; p < dc.npass && s == VV_OK; p++) {
                dc_voxels(&dc, &rg, vols, p);
                const vv_world *pw = dc_world(&dc, w, p);
                s = pass       ? render_piece(r, pw, view, &rg, opt, &rpiece, &rwhole)
                    : dc.split ? render_piece(r, pw, view, &rg, opt, &piece, &wholes[p])
                               : render_piece(r, pw, view, &rg, opt, &piece, &whole);
            }
            for (int k = 0; k < VV_MAX_CHANNELS; k++)
                vv_volume_free(vols[k]); /* the renderer's cache may keep its own reference */
        }
        if (s == VV_OK && pass == 0 && dc.split) {
            /* the channels added (the second pass of quality 2 is for one image) */
            dc_merge(wholes, dc.npass, w->background, out);
            break;
        }
        if (s == VV_OK && pass == 0) {
            vv_region_image_finish(&whole, w->background);
            s = rays_begin(&whole, out, &rays, &rwhole, &rpiece);
            if (rays.n_pixels == 0)
                break;
        } else if (s == VV_OK) {
            rays_finish(&rwhole, &rays, w->background, out);
        }
    }
    rays_end(&rays, &rwhole, &rpiece);
    brick_reader_free(&reader);
    vv_image_free(piece.image);
    free(whole.key);
    free(ord.list);
    dc_wholes_free(wholes, dc.npass);
    dc_free(&dc);
    return s;
}

/* ---- multiresolution sources: level of detail per node ------------------------ */

#define MR_MAX_THREADS 8 /* nodes rendered at a time (render_nodes_concurrent) */

/* A node to render: its level, region (voxels unset) and box of voxels. */
typedef struct mr_node {
    int level;
    vv_render_region rg;
    int lo[3], hi[3]; /* its voxels at that level */
    int n0[3], n1[3]; /* its level-0 cells */
} mr_node;

/* What one multiresolution frame shares. */
typedef struct mr_frame {
    mr_node *nodes; /* the frame's nodes front to back */
    int n_nodes, cap_nodes;
    const drv_renderer *r;
    const vv_world *w;
    const vv_multires_source *src;
    const vv_view *view;
    const vv_render_options *opt;
    vv_lod *lod;
    const vv_object *obj;
    int object, n_levels, cells[3], ortho, skip;
    int leaf;  /* the octree leaves' side, level-0 cells */
    int ghost; /* voxels read beyond a node's box: 1, iso 2 (vv_render_region.voxels) */
    vv_mat4 i2w[VV_LOD_MAX_LEVELS];
    double a[VV_LOD_MAX_LEVELS][3], b[VV_LOD_MAX_LEVELS][3]; /* level L index = (x0 - b) / a */
    double vox[VV_LOD_MAX_LEVELS]; /* a level's smallest voxel edge, world units */
    double E[3], D[3];             /* eye and view direction, level 0's index space */
    vv_vec3 fwd;                   /* unit view direction, world */
    double ppw;                    /* pixels a world unit at depth 1 (perspective) or anywhere */
    double bin;                    /* a transfer-function table entry's width */
    vv_region_image *whole, *piece;
    const vv_region_rays *rays; /* the second pass of quality 2 (rays_begin), else NULL */
    /* render_nodes_concurrent: the renderers of threads 1.. (clones of r;
     * freed after the frame is finished: whole->classify may be theirs) */
    drv_renderer clones[MR_MAX_THREADS];
    /* progressive frames: the boxes its pending nodes want loaded (level,
     * lo[3], hi[3] each), front to back (vv_multires_source.request) */
    int *want, n_want, cap_want;
    /* a multi-channel object: its passes (drv_chans), the split passes'
     * images, each channel's table entry width */
    drv_chans dc;
    vv_region_image *wholes;
    double cbin[VV_MAX_CHANNELS];
    /* level 0 of each channel by boxes (global effects of a frame at level 0) */
    vv_region_volume cwhole[VV_MAX_CHANNELS];
    struct mr_channel_reader {
        const vv_multires_source *src;
        int channel;
    } creader[VV_MAX_CHANNELS];
    int have_cwhole; /* 1: the nodes take cwhole (every node at level 0) */
    int collect;     /* 1: render_tree only notes the leaves pending (a subtree drawn whole) */
} mr_frame;

/* Level 0 of one channel by boxes (vv_region_volume of mr_frame.cwhole). */
static vv_status
channel0_box(void *user, const int lo[3], const int hi[3], vv_volume **out) {
    const struct mr_channel_reader *c = user;
    return c->src->channel_read_box(c->src->user, c->channel, 0, lo, hi, out);
}

static int
channel0_range(void *user, const int lo[3], const int hi[3], float *vmin, float *vmax) {
    const struct mr_channel_reader *c = user;
    return c->src->channel_range(c->src->user, c->channel, 0, lo, hi, vmin, vmax);
}

/* Whether drawn channel @p k of the object is transparent in node @p nd
 * (its range there, as the source knows it, shows nothing under its
 * transfer function); never under the maximum rule, nor for a renderer
 * with global effects (the ray tracer's shadows through a channel come
 * from all of it, with the tables of its part in each region). */
static int
mr_channel_hidden(const mr_frame *f, const mr_node *nd, int k) {
    const vv_channel *ch = &f->obj->channels[k];
    float vmin, vmax;
    return f->skip && !ch->labels && !(f->r->ops->info.caps & VV_RENDERER_GLOBAL) &&
           f->src->channel_range(f->src->user, k, nd->level, nd->lo, nd->hi, &vmin, &vmax) &&
           !(tf_max_opacity(&ch->tf, vmin - f->cbin[k], vmax) > 0);
}

/* The channels of node @p nd a region render takes (@p vols with the
 * channels transparent there left out, into @p out). */
static void
mr_node_channels(const mr_frame *f, const mr_node *nd, vv_volume *const *vols, vv_volume **out) {
    for (int k = 0; k < f->obj->n_channels; k++)
        out[k] = vols[k] && !mr_channel_hidden(f, nd, k) ? vols[k] : NULL;
}

/* dc_voxels, and the node's whole volume for the pass: the channel's
 * (split passes draw it as an object of one channel), or every channel's.
 * @p vols: the node's channels (mr_node_channels: those transparent there
 * left out). Returns 0 when the pass draws nothing here (its channel, or
 * every channel, transparent in the node). */
static int
mr_voxels(const mr_frame *f, vv_render_region *rg, vv_volume *const *vols, int p) {
    if (f->dc.split && !vols[f->dc.drawn[p]])
        return 0;
    if (f->dc.multi && !f->dc.split) {
        int any = 0;
        for (int d = 0; d < f->dc.n_drawn; d++)
            any |= vols[f->dc.drawn[d]] != NULL;
        if (!any)
            return 0;
    }
    dc_voxels(&f->dc, rg, vols, p);
    if (f->dc.multi && !f->dc.split)
        for (int d = 0; d < f->dc.n_drawn; d++) /* the first channel drawn here */
            if (vols[f->dc.drawn[d]]) {
                rg->voxels = vols[f->dc.drawn[d]];
                break;
            }
    if (!f->have_cwhole)
        return 1;
    if (f->dc.split) {
        rg->whole = &f->cwhole[f->dc.drawn[p]];
        rg->channel_whole = NULL;
    } else {
        rg->whole = NULL;
        rg->channel_whole = f->cwhole;
    }
    return 1;
}

/* A node's voxels at its level: every channel's (vols in object channel
 * order) of a multi-channel object, else vols[0]. */
static vv_status
read_node(const mr_frame *f, const mr_node *nd, vv_volume **vols) {
    if (f->dc.multi)
        return f->src->read_channels(f->src->user, nd->level, nd->lo, nd->hi, vols);
    return f->src->read_box(f->src->user, nd->level, nd->lo, nd->hi, &vols[0]);
}

/* dc_transparent's ranges: channel k's over a node's box (mr_range_at). */
typedef struct mr_range_at {
    const mr_frame *f;
    int level;
    const int *lo, *hi;
} mr_range_at;

static int
mr_channel_range(void *u, int ch, float *vmin, float *vmax) {
    const mr_range_at *a = u;
    return a->f->src->channel_range(a->f->src->user, ch, a->level, a->lo, a->hi, vmin, vmax);
}

/* The coarsest level whose voxel projects to at most lod->voxel_pixels at
 * the node's point nearest the eye (the fixed level when one is asked). */
static int
desired_level(const mr_frame *f, const int n0[3], const int n1[3]) {
    if (f->lod->level >= 0)
        return f->lod->level < f->n_levels ? f->lod->level : f->n_levels - 1;
    double p[3];
    for (int k = 0; k < 3; k++)
        p[k] = f->E[k] < n0[k] ? n0[k] : f->E[k] > n1[k] ? n1[k] : f->E[k];
    double scale = f->ppw;
    if (!f->ortho) {
        const vv_vec3 q = vv_mat4_mul_point(f->i2w[0], vv_vec3_make(p[0], p[1], p[2]));
        const double z = vv_vec3_dot(vv_vec3_sub(q, f->view->eye), f->fwd);
        if (!(z > 0))
            return 0; /* the eye in or beside the node */
        scale = f->ppw / z;
    }
    const double limit = f->lod->voxel_pixels > 0 ? f->lod->voxel_pixels : 1.0;
    int best = 0;
    for (int L = 1; L < f->n_levels; L++)
        if (f->vox[L] * scale <= limit)
            best = L;
    return best;
}

/* The region of the node of level-0 cells n0 .. n1 drawn with the voxels
 * of level L (rg, without voxels or rectangle) and its box of voxels slo ..
 * shi; 0 when the node lies beyond the level's voxels. */
static int
node_region(const mr_frame *f, int L, const int n0[3], const int n1[3], vv_render_region *rg,
            int slo[3], int shi[3]) {
    const vv_volume *h = f->src->level(f->src->user, L);
    memset(rg, 0, sizeof *rg);
    rg->object = f->object;
    rg->from = h; /* the node known by its level and box: a renderer may keep it */
    rg->level = L;
    /* a step of level L against one of level 0 (its samples weigh as many of level 0's) */
    rg->step_scale = f->vox[0] > 0 ? f->vox[L] / f->vox[0] : 1;
    for (int k = 0; k < 3; k++) {
        const double lo = (n0[k] - f->b[L][k]) / f->a[L][k], hi = (n1[k] - f->b[L][k]) / f->a[L][k];
        slo[k] = (int)floor(lo) - f->ghost;
        shi[k] = (int)ceil(hi) + f->ghost;
        slo[k] = slo[k] < 0 ? 0 : slo[k];
        shi[k] = shi[k] > h->dims[k] - 1 ? h->dims[k] - 1 : shi[k];
        if (slo[k] > shi[k])
            return 0;
        rg->dims[k] = h->dims[k];
        rg->offset[k] = slo[k];
        rg->lo[k] = n0[k] > 0 ? lo : -INFINITY;
        rg->hi[k] = n1[k] < f->cells[k] ? hi : INFINITY;
    }
    return 1;
}

static void want_levels(mr_frame *f, const mr_node *nd, int pending);

/* The node of level-0 cells n0 .. n1 with the voxels of level L, added to
 * the frame's list unless it is off screen or known to be transparent. */
static vv_status
plan_node(mr_frame *f, int L, const int n0[3], const int n1[3]) {
    vv_render_region rg;
    int slo[3], shi[3];
    if (!node_region(f, L, n0, n1, &rg, slo, shi))
        return VV_OK; /* beyond this level's voxels */
    float vmin, vmax;
    if (f->dc.multi) {
        const mr_range_at at = {f, L, slo, shi};
        if (f->skip && dc_transparent(&f->dc, f->obj, mr_channel_range, (void *)&at, f->cbin)) {
            f->lod->skipped++;
            return VV_OK;
        }
    } else if ((f->skip || f->obj->mode == VV_MODE_ISO) && f->src->box_range &&
               f->src->box_range(f->src->user, L, slo, shi, &vmin, &vmax) &&
               (f->skip ? !(tf_max_opacity(&f->obj->tf, vmin - f->bin, vmax) > 0)
                        : iso_below(f->obj, f->src->level(f->src->user, L), vmax))) {
        f->lod->skipped++;
        return VV_OK;
    }
    vv_region_rect(&rg, f->i2w[L], f->view, slo, shi);
    if (rg.x1 > rg.x0 && rg.y1 <= rg.y0)
        return VV_OK; /* off screen */
    if (f->n_nodes == f->cap_nodes) {
        const int cap = f->cap_nodes ? 2 * f->cap_nodes : 256;
        mr_node *nn = realloc(f->nodes, sizeof *nn * (size_t)cap);
        if (!nn)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        f->nodes = nn;
        f->cap_nodes = cap;
    }
    if (f->collect) {
        /* a leaf of a subtree drawn whole, coarse: pending, its boxes asked */
        mr_node leaf = {.level = L, .rg = rg};
        memcpy(leaf.lo, slo, sizeof leaf.lo);
        memcpy(leaf.hi, shi, sizeof leaf.hi);
        memcpy(leaf.n0, n0, sizeof leaf.n0);
        memcpy(leaf.n1, n1, sizeof leaf.n1);
        f->lod->pending++;
        want_levels(f, &leaf, 1);
        return VV_OK;
    }
    mr_node *nd = &f->nodes[f->n_nodes++];
    nd->level = L;
    nd->rg = rg;
    memcpy(nd->lo, slo, sizeof nd->lo);
    memcpy(nd->hi, shi, sizeof nd->hi);
    memcpy(nd->n0, n0, sizeof nd->n0);
    memcpy(nd->n1, n1, sizeof nd->n1);
    return VV_OK;
}

/* Progressive frames (lod->progressive): node @p nd redrawn at the finest
 * level coarser than its own whose chunks are all in the source's cache
 * (the coarsest when none is); 0 when it then lies beyond that level. */
static int
coarser_resident(const mr_frame *f, mr_node *nd) {
    for (int L = nd->level + 1; L < f->n_levels; L++) {
        vv_render_region rg;
        int lo[3], hi[3];
        if (!node_region(f, L, nd->n0, nd->n1, &rg, lo, hi))
            return 0;
        if (L < f->n_levels - 1 && f->src->missing_chunks(f->src->user, L, lo, hi) > 0)
            continue;
        vv_region_rect(&rg, f->i2w[L], f->view, lo, hi);
        nd->level = L;
        nd->rg = rg;
        memcpy(nd->lo, lo, sizeof lo);
        memcpy(nd->hi, hi, sizeof hi);
        return 1;
    }
    return 0;
}

/* Node @p nd's boxes onto the frame's wanted boxes (when the source loads
 * in the background): a pending node's at its own level and every coarser
 * one short of the coarsest, a node drawn at its level its own box (held:
 * asking for it keeps it from being evicted for the others). A box that
 * cannot be added is left out: the request is a hint. */
static void
want_levels(mr_frame *f, const mr_node *nd, int pending) {
    if (!f->lod->background || f->src->version < 2 || !f->src->request)
        return;
    const int last = pending ? f->n_levels - 2 : nd->level;
    for (int L = nd->level; L <= last; L++) {
        vv_render_region rg;
        int lo[3], hi[3];
        if (L == nd->level) {
            memcpy(lo, nd->lo, sizeof lo);
            memcpy(hi, nd->hi, sizeof hi);
        } else if (!node_region(f, L, nd->n0, nd->n1, &rg, lo, hi)) {
            return;
        }
        if (f->n_want == f->cap_want) {
            const int cap = f->cap_want ? 2 * f->cap_want : 256;
            int *nw = realloc(f->want, sizeof(int) * 7 * (size_t)cap);
            if (!nw)
                return;
            f->want = nw;
            f->cap_want = cap;
        }
        int *b = f->want + 7 * f->n_want++;
        b[0] = L;
        memcpy(b + 1, lo, sizeof lo);
        memcpy(b + 4, hi, sizeof hi);
    }
}

/* The frame's wanted boxes asked of the source, coarse levels first and
 * within a level front to back (the order they were noted); none cancels
 * what an earlier frame asked. A request that fails is dropped: the frame
 * is drawn, and the next one asks again. */
static void
request_wanted(mr_frame *f) {
    if (f->src->version < 2 || !f->src->request)
        return;
    /* the previous request's fate, before this one replaces it */
    f->lod->stalled = f->lod->pending > 0 && f->src->stalled && f->src->stalled(f->src->user);
    const int n = f->n_want;
    int *lv = malloc(sizeof(int) * (size_t)(n ? n : 1));
    int *lo = malloc(sizeof(int) * 3 * (size_t)(n ? n : 1));
    int *hi = malloc(sizeof(int) * 3 * (size_t)(n ? n : 1));
    if (lv && lo && hi) {
        int m = 0;
        for (int L = f->n_levels - 1; L >= 0; L--)
            for (int i = 0; i < n; i++) {
                const int *b = f->want + 7 * i;
                if (b[0] != L)
                    continue;
                lv[m] = L;
                memcpy(lo + 3 * m, b + 1, sizeof(int) * 3);
                memcpy(hi + 3 * m, b + 4, sizeof(int) * 3);
                m++;
            }
        if (f->src->request(f->src->user, m, lv, lo, hi) == VV_OK)
            f->lod->requested = m;
        else
            vv_error_clear();
    }
    free(lv);
    free(lo);
    free(hi);
}

/* Node @p nd of a progressive frame: 1 when it is drawn at its own level
 * (its chunks are held, or fit in what is left of *budget, which they
 * then use up), else redrawn coarser (coarser_resident) and counted as
 * pending; 0 when it is then not drawn at all. */
static int
progressive_level(mr_frame *f, mr_node *nd, int *budget) {
    const int miss = f->src->missing_chunks(f->src->user, nd->level, nd->lo, nd->hi);
    if (miss > *budget && nd->level < f->n_levels - 1) {
        f->lod->pending++;
        want_levels(f, nd, 1);
        return coarser_resident(f, nd);
    }
    want_levels(f, nd, 0); /* held: kept, so that loading the others does not evict it */
    *budget -= miss;
    return 1;
}

/* How many nodes render_nodes_concurrent draws at a time: the source's
 * boxes, the threads the frame may use, at most MR_MAX_THREADS; 1 (render
 * them in turn, each on every thread) for a renderer with global effects
 * (its whole-volume context would be built once per thread), one on a
 * device (VV_RENDERER_DEVICE: a clone's device and bricks would last one
 * frame), or when nested
 * parallel regions are active (each node's own loops would then fork). */
static int
node_threads(const mr_frame *f) {
    const int boxes = f->src->boxes > 1 ? f->src->boxes : 1;
    int t = f->opt && f->opt->threads > 0 ? f->opt->threads : omp_get_max_threads();
    t = t < boxes ? t : boxes;
    t = t < MR_MAX_THREADS ? t : MR_MAX_THREADS;
    if (t < 2 || f->n_nodes < 2 || omp_get_max_active_levels() > 1 || omp_in_parallel() ||
        (f->r->ops->info.caps & (VV_RENDERER_GLOBAL | VV_RENDERER_DEVICE)) || !f->r->clone)
        return 1;
    /* a piece of the view's size a thread and pass: at most 8 of them */
    while (t > 1 && t * f->dc.npass > MR_MAX_THREADS)
        t--;
    return t;
}

/* The planned nodes rendered several at a time, one a thread (each node's
 * region render then runs on its thread alone: its own parallel loops are
 * nested, hence serial), with a renderer a thread (f->r and its clones):
 * the boxes are read one at a time in the plan's order (a ticket), and the
 * partial images are combined into the frame in that order (ordered), so
 * the image is the one render_nodes makes in turn, bit for bit. Per node
 * the ray caster spends most of a small node's time setting up its caches
 * (16-bit values, gradients, min/max) in short parallel loops, between
 * which the other thread waited (spinning, which on this project's 2-core
 * machine also slowed the serial reads 4-fold); a node a thread keeps both
 * busy. */
static vv_status
render_nodes_concurrent(mr_frame *f, int T) {
    const int n = f->n_nodes;
    const int progressive = f->lod->progressive && f->src->missing_chunks;
    const int W = f->view->width, H = f->view->height;
    const size_t np = (size_t)W * (size_t)H;
    /* a piece a thread and pass: the passes of a node are combined together, in order */
    const int npass = f->dc.npass;
    vv_region_image pieces[MR_MAX_THREADS][VV_MAX_CHANNELS];
    const drv_renderer *rs[MR_MAX_THREADS];
    memset(pieces, 0, sizeof pieces);
    rs[0] = f->r;
    vv_status s = VV_OK;
    for (int t = 1; t < T && s == VV_OK; t++)
        if ((s = f->r->clone(f->r, &f->clones[t])) == VV_OK)
            rs[t] = &f->clones[t];
    pieces[0][0] = *f->piece; /* the frame's own (clear); the others made here */
    for (int t = 0; t < T && s == VV_OK; t++)
        for (int p = t == 0 ? 1 : 0; p < npass && s == VV_OK; p++) {
            vv_region_image *pc = &pieces[t][p];
            pc->op = VV_REGION_OVER;
            pc->clear_outside = 1;
            pc->key = malloc(sizeof(float) * (np ? np : 1));
            s = pc->key ? vv_image_new(&pc->image, W, H)
                        : vv_error_set(VV_ERR_NOMEM, "out of memory");
            if (s == VV_OK)
                vv_region_image_clear(pc);
        }
    /* the nodes' renders report no progress of their own (several at once) */
    vv_render_options o;
    vv_render_options_init(&o);
    if (f->opt)
        o = *f->opt;
    o.progress.fn = NULL;
    int next_read = 0, failed = 0, budget = f->lod->load_budget;
    pthread_mutex_t turn_lock = PTHREAD_MUTEX_INITIALIZER;
    pthread_cond_t turn = PTHREAD_COND_INITIALIZER;
    vv_status first = VV_OK;
    char msg[1024] = "";
    if (s == VV_OK) {
#pragma omp parallel for ordered schedule(dynamic, 1) num_threads(T)
        for (int i = 0; i < n; i++) {
            const int t = omp_get_thread_num();
            mr_node *nd = &f->nodes[i];
            vv_volume *vols[VV_MAX_CHANNELS] = {NULL};
            vv_status ns = VV_OK;
            int draw = 0;
            /* the reads one at a time, in the plan's order: a thread
             * whose turn has not come yields for up to 2 ms (a box read
             * from local chunks ends within that: sleeping made a local
             * frame 10 % slower on the loaded 2-core machine), then sleeps
             * (a read may wait seconds on the network: yielding throughout
             * took the core its fetching and decoding needed, 8.8 s of
             * system time in an 11 s frame by URL) */
            const double until = omp_get_wtime() + 0.002;
            for (int k = 0; __atomic_load_n(&next_read, __ATOMIC_ACQUIRE) != i; k++) {
                if ((k & 15) == 15 && omp_get_wtime() > until)
                    break;
                sched_yield();
            }
            if (__atomic_load_n(&next_read, __ATOMIC_ACQUIRE) != i) {
                pthread_mutex_lock(&turn_lock);
                while (__atomic_load_n(&next_read, __ATOMIC_ACQUIRE) != i)
                    pthread_cond_wait(&turn, &turn_lock);
                pthread_mutex_unlock(&turn_lock);
            }
            if (!__atomic_load_n(&failed, __ATOMIC_ACQUIRE)) {
                draw = !progressive || progressive_level(f, nd, &budget);
                if (draw)
                    ns = read_node(f, nd, vols);
            }
            pthread_mutex_lock(&turn_lock);
            __atomic_store_n(&next_read, i + 1, __ATOMIC_RELEASE);
            pthread_cond_broadcast(&turn);
            pthread_mutex_unlock(&turn_lock);
            vv_volume *use[VV_MAX_CHANNELS] = {NULL};
            if (draw && ns == VV_OK && f->dc.multi)
                mr_node_channels(f, nd, vols, use);
            for (int p = 0; draw && ns == VV_OK && p < npass; p++) {
                if (!mr_voxels(f, &nd->rg, f->dc.multi ? use : vols, p))
                    continue; /* nothing of its channel here: the piece stays clear */
                const vv_region_image *wh = f->dc.split ? &f->wholes[p] : f->whole;
                ns = render_into(rs[t], dc_world(&f->dc, f->w, p), f->view, &nd->rg, &o,
                                 &pieces[t][p], wh->op);
                nd->rg.voxels = NULL;
                nd->rg.channel_voxels = NULL;
            }
            int rc[4];
            piece_rect(&nd->rg, W, H, rc);
#pragma omp ordered
            {
                if (ns != VV_OK && !failed) {
                    first = ns;
                    snprintf(msg, sizeof msg, "%s", vv_error_message());
                    __atomic_store_n(&failed, 1, __ATOMIC_RELEASE);
                }
                if (draw && ns == VV_OK && !failed) {
                    for (int p = 0; p < npass; p++)
                        vv_region_image_combine_rect(f->dc.split ? &f->wholes[p] : f->whole,
                                                     &pieces[t][p], rc[0], rc[1], rc[2], rc[3]);
                    f->lod->nodes[nd->level]++;
                }
                /* progress by nodes combined; cancelling stops the frame */
                if (!failed && f->opt &&
                    vv_progress_report(&f->opt->progress, (double)(i + 1) / n)) {
                    first = vv_error_set(VV_ERR_CANCELLED, "cancelled");
                    snprintf(msg, sizeof msg, "%s", vv_error_message());
                    __atomic_store_n(&failed, 1, __ATOMIC_RELEASE);
                }
            }
            for (int p = 0; draw && p < npass; p++)
                vv_region_image_clear_rect(&pieces[t][p], rc[0], rc[1], rc[2], rc[3]);
            for (int k = 0; k < VV_MAX_CHANNELS; k++)
                vv_volume_free(vols[k]);
        }
        if (failed)
            s = vv_error_set(first, "%s", msg);
    }
    for (int t = 0; t < T; t++)
        for (int p = t == 0 ? 1 : 0; p < npass; p++) {
            vv_image_free(pieces[t][p].image);
            free(pieces[t][p].key);
        }
    return s;
}

/* The planned nodes read and rendered in order. */
static vv_status
render_nodes(mr_frame *f) {
    const int n = f->n_nodes;
    const int progressive = f->lod->progressive && f->src->missing_chunks;
    if (f->src->plan && n > 0 && !progressive) {
        int *lv = malloc(sizeof(int) * (size_t)n);
        int *lo = malloc(sizeof(int) * 3 * (size_t)n), *hi = malloc(sizeof(int) * 3 * (size_t)n);
        if (lv && lo && hi) {
            for (int i = 0; i < n; i++) {
                lv[i] = f->nodes[i].level;
                memcpy(lo + 3 * i, f->nodes[i].lo, sizeof f->nodes[i].lo);
                memcpy(hi + 3 * i, f->nodes[i].hi, sizeof f->nodes[i].hi);
            }
            if (f->src->plan(f->src->user, n, lv, lo, hi) != VV_OK)
                vv_error_clear(); /* unplanned reads: least recently used out */
        }
        free(lv);
        free(lo);
        free(hi);
    }
    const int T = f->rays ? 1 : node_threads(f);
    if (T > 1)
        return render_nodes_concurrent(f, T);
    int budget = f->lod->load_budget;
    for (int i = 0; i < n; i++) {
        mr_node *nd = &f->nodes[i];
        /* progressive: its own level when resident or within the chunks left
         * to read (the nearest nodes come first), else a coarser resident one */
        if (progressive && !progressive_level(f, nd, &budget))
            continue;
        if (f->rays && !rays_in_rect(f->rays, f->view->width, &nd->rg))
            continue; /* no ray of the second pass */
        vv_volume *vols[VV_MAX_CHANNELS] = {NULL};
        vv_status s = read_node(f, nd, vols);
        if (s != VV_OK)
            return s;
        nd->rg.rays = f->rays;
        vv_volume *use[VV_MAX_CHANNELS] = {NULL};
        if (f->dc.multi)
            mr_node_channels(f, nd, vols, use);
        for (int p = 0; p < f->dc.npass && s == VV_OK; p++) {
            if (!mr_voxels(f, &nd->rg, f->dc.multi ? use : vols, p))
                continue; /* nothing of its channel here */
            s = render_piece(f->r, dc_world(&f->dc, f->w, p), f->view, &nd->rg, f->opt, f->piece,
                             f->dc.split ? &f->wholes[p] : f->whole);
        }
        nd->rg.voxels = NULL;
        nd->rg.channel_voxels = NULL;
        nd->rg.rays = NULL;
        for (int k = 0; k < VV_MAX_CHANNELS; k++)
            vv_volume_free(vols[k]);
        if (s != VV_OK)
            return s;
        if (!f->rays) /* the second pass reads them again: not more nodes */
            f->lod->nodes[nd->level]++;
    }
    return VV_OK;
}

/* The octree node of depth @p depth (f->leaf << depth level-0 cells
 * a side) at cell @p o: rendered at its level when that level is at least
 * its depth, else its children front to back. */
static vv_status
render_tree(mr_frame *f, int depth, const int o[3]) {
    const int side = f->leaf << depth;
    int n0[3], n1[3];
    for (int k = 0; k < 3; k++) {
        if (o[k] > 0 && o[k] >= f->cells[k])
            return VV_OK; /* past the volume */
        n0[k] = o[k];
        n1[k] = o[k] + side < f->cells[k] ? o[k] + side : f->cells[k];
    }
    int want = desired_level(f, n0, n1);
    /* a node's box stays within VV_PYRAMID_MAX_BOX voxels of its level (a
     * level not halved along an axis takes deeper nodes) */
    int fits = 1;
    for (int k = 0; k < 3; k++)
        fits &= (n1[k] - n0[k]) / f->a[want][k] <= f->leaf + 1e-9;
    if (depth == 0 || (want >= depth && fits)) {
        while (!fits && want > 0) { /* a leaf: the coarsest level that fits */
            want--;
            fits = 1;
            for (int k = 0; k < 3; k++)
                fits &= (n1[k] - n0[k]) / f->a[want][k] <= f->leaf + 1e-9;
        }
        return plan_node(f, want, n0, n1);
    }
    if (f->lod->progressive && f->lod->background && f->lod->load_budget <= 0 && !f->collect &&
        f->src->version >= 3 && f->src->resident_chunks && f->src->missing_chunks) {
        /* (a frame that reads nothing itself, the loader reading for it)
         * nothing of the levels its subtree wants resident: the node whole
         * at the finest resident level that fits it (one region, not one a
         * leaf a region of that level: the coarsest is always there); its
         * leaves pending, their boxes asked as each would ask for them */
        int none = 1;
        for (int L = want; L < depth && L < f->n_levels && none; L++) {
            vv_render_region rg;
            int lo[3], hi[3];
            none = !node_region(f, L, n0, n1, &rg, lo, hi) ||
                   f->src->resident_chunks(f->src->user, L, lo, hi) == 0;
        }
        for (int L = depth; none && L < f->n_levels; L++) {
            int fit = 1;
            for (int k = 0; k < 3; k++)
                fit &= (n1[k] - n0[k]) / f->a[L][k] <= f->leaf + 1e-9;
            vv_render_region rg;
            int lo[3], hi[3];
            if (!fit || !node_region(f, L, n0, n1, &rg, lo, hi) ||
                (L < f->n_levels - 1 && f->src->missing_chunks(f->src->user, L, lo, hi) > 0))
                continue;
            vv_status s = plan_node(f, L, n0, n1);
            f->collect = 1;
            for (int c = 0; c < 8 && s == VV_OK; c++) {
                const int half = side / 2;
                const int co[3] = {o[0] + (c & 1) * half, o[1] + ((c >> 1) & 1) * half,
                                   o[2] + ((c >> 2) & 1) * half};
                s = render_tree(f, depth - 1, co);
            }
            f->collect = 0;
            return s;
        }
    }
    const int half = side / 2;
    int near = 0;
    for (int k = 0; k < 3; k++) {
        const double plane = o[k] + half;
        near |= (f->ortho ? f->D[k] < 0 : f->E[k] >= plane) << k; /* the upper half first */
    }
    for (int c = 0; c < 8; c++) {
        const int bits = c ^ near;
        const int co[3] = {o[0] + (bits & 1) * half, o[1] + ((bits >> 1) & 1) * half,
                           o[2] + ((bits >> 2) & 1) * half};
        vv_status s = render_tree(f, depth - 1, co);
        if (s != VV_OK)
            return s;
    }
    return VV_OK;
}

/* Level 0 of a multiresolution source by boxes (vv_region_volume). */
static vv_status
level0_box(void *user, const int lo[3], const int hi[3], vv_volume **out) {
    const vv_multires_source *src = user;
    return src->read_box(src->user, 0, lo, hi, out);
}

static int
level0_range(void *user, const int lo[3], const int hi[3], float *vmin, float *vmax) {
    const vv_multires_source *src = user;
    return src->box_range && src->box_range(src->user, 0, lo, hi, vmin, vmax);
}

/* The levels' placements in level 0's index space and their voxel sizes. */
static vv_status
setup_levels(mr_frame *f) {
    const vv_volume *h0 = f->src->level(f->src->user, 0);
    for (int L = 0; L < f->n_levels; L++) {
        const vv_volume *h = f->src->level(f->src->user, L);
        if (!h)
            return vv_error_set(VV_ERR_INVALID, "multires: level %d has no header", L);
        vv_object geo = *f->obj; /* shallow: nothing in it is released */
        geo.volume = (vv_volume *)h;
        f->i2w[L] = vv_object_index_to_world(&geo);
        double best = INFINITY;
        for (int k = 0; k < 3; k++) {
            f->a[L][k] = h->spacing[k] / h0->spacing[k];
            f->b[L][k] = (h->origin[k] - h0->origin[k]) / h0->spacing[k];
            const vv_mat4 *m = &f->i2w[L];
            const double l =
                sqrt(m->m[0][k] * m->m[0][k] + m->m[1][k] * m->m[1][k] + m->m[2][k] * m->m[2][k]);
            best = l > 0 && l < best ? l : best;
        }
        f->vox[L] = best;
    }
    int ok = 0;
    const vv_mat4 w2i = vv_mat4_inverse(f->i2w[0], &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "bricks: object '%s': singular transform",
                            f->obj->name);
    const vv_vec3 e = vv_mat4_mul_point(w2i, f->view->eye);
    const vv_vec3 fwd = vv_vec3_sub(f->view->at, f->view->eye);
    f->E[0] = e.x;
    f->E[1] = e.y;
    f->E[2] = e.z;
    for (int k = 0; k < 3; k++) {
        f->D[k] = w2i.m[k][0] * fwd.x + w2i.m[k][1] * fwd.y + w2i.m[k][2] * fwd.z;
        f->cells[k] = h0->dims[k] > 1 ? h0->dims[k] - 1 : 0;
    }
    f->fwd = vv_vec3_normalize(fwd);
    f->ortho = f->view->projection == VV_PROJECTION_ORTHOGRAPHIC;
    f->ppw = f->ortho ? f->view->height / f->view->ortho_height
                      : f->view->height / (2 * tan(f->view->fov / 2));
    f->bin = (h0->range[1] - h0->range[0]) / (VV_VC_LUT - 1);
    return VV_OK;
}

void
vv_lod_init(vv_lod *lod) {
    memset(lod, 0, sizeof *lod);
    lod->level = -1;
    lod->voxel_pixels = 1.0;
}

vv_status
drv_render_multires(const drv_renderer *r, const vv_world *w, int object,
                    const vv_multires_source *src, const vv_view *view,
                    const vv_render_options *opt, vv_lod *lod, vv_image *out) {
    if (!src || !lod)
        return vv_error_set(VV_ERR_INVALID, "multires: no source or level-of-detail options");
    if (src->version < 1 || src->version > VV_MULTIRES_SOURCE_VERSION)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "multires: source interface version %d, not 1 .. %d", src->version,
                            VV_MULTIRES_SOURCE_VERSION);
    if (src->n_levels < 1 || src->n_levels > VV_LOD_MAX_LEVELS || !src->level || !src->read_box)
        return vv_error_set(VV_ERR_INVALID, "multires: a source of %d levels (1 to %d)",
                            src->n_levels, VV_LOD_MAX_LEVELS);
    vv_status s = check_args(r, w, object, view, out);
    if (s != VV_OK)
        return s;
    memset(lod->nodes, 0, sizeof lod->nodes);
    lod->skipped = 0;
    lod->pending = 0;
    lod->requested = 0;
    lod->stalled = 0;
    mr_frame f;
    memset(&f, 0, sizeof f);
    f.r = r;
    f.w = w;
    f.src = src;
    f.view = view;
    f.opt = opt;
    f.lod = lod;
    f.object = object;
    f.obj = w->objects[object];
    f.n_levels = src->n_levels;
    f.leaf = src->node_cells > 0 ? src->node_cells : VV_BRICK_CELLS;
    if ((s = setup_levels(&f)) != VV_OK)
        return s;
    if ((s = dc_init(&f.dc, w, object)) != VV_OK)
        return s;
    if (f.dc.multi) {
        const int nch = src->version >= 3 ? src->n_channels : 1;
        if (nch != f.obj->n_channels || !src->read_channels || !src->channel_range ||
            !src->channel_level) {
            dc_free(&f.dc);
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "multires: object '%s' has %d channels, its source carries %d",
                                f.obj->name, f.obj->n_channels, nch);
        }
        for (int k = 0; k < nch; k++) {
            const vv_volume *hk = src->channel_level(src->user, k, 0);
            f.cbin[k] = hk ? (hk->range[1] - hk->range[0]) / (VV_VC_LUT - 1) : 0;
        }
        /* each drawn channel composited (composite, additive) skips what its
         * transfer function hides; maximum projects everything */
        f.skip = f.obj->blend != VV_BLEND_MAXIMUM;
    } else {
        f.skip =
            f.obj->mode == VV_MODE_COMPOSITE && f.obj->segmentation == VV_SEG_TRANSFER_FUNCTION;
    }
    f.ghost = !f.dc.multi && f.obj->mode == VV_MODE_ISO ? 2 : 1;

    vv_region_image whole, piece;
    vv_region_image wholes[VV_MAX_CHANNELS];
    memset(wholes, 0, sizeof wholes);
    s = frame_images(view, out, dc_mode(&f.dc, f.obj, 0), &whole, &piece);
    if (s == VV_OK && f.dc.split)
        s = dc_wholes(&f.dc, f.obj, view, wholes);
    f.whole = &whole;
    f.piece = &piece;
    f.wholes = wholes;
    if (s == VV_OK) {
        /* the root: the smallest node that covers every axis */
        int depth = 0, big = f.cells[0] > f.cells[1] ? f.cells[0] : f.cells[1];
        big = f.cells[2] > big ? f.cells[2] : big;
        while ((f.leaf << depth) < big && depth < 24)
            depth++;
        const int zero[3] = {0, 0, 0};
        if (src->frame)
            src->frame(src->user, 1);
        s = render_tree(&f, depth, zero);
        /* the whole volume by boxes of level 0 for the global effects of a
         * frame drawn at level 0 from a coarse proxy (not of coarser
         * levels: the sweep would read level 0 whole) */
        const vv_volume *h0 = src->level(src->user, 0);
        vv_region_volume wv = {.user = (void *)src,
                               .header = h0,
                               .read_box = level0_box,
                               .box_range = level0_range,
                               .tile = f.leaf};
        int at0 = !lod->progressive &&
                  (f.obj->volume->dims[0] != h0->dims[0] || f.obj->volume->dims[1] != h0->dims[1] ||
                   f.obj->volume->dims[2] != h0->dims[2]);
        for (int i = 0; i < f.n_nodes && at0; i++)
            at0 = f.nodes[i].level == 0;
        for (int i = 0; i < f.n_nodes && at0 && !f.dc.multi; i++)
            f.nodes[i].rg.whole = &wv;
        if (at0 && f.dc.multi && src->channel_read_box) {
            /* each channel's level 0 by boxes, unplanned (mr_voxels) */
            for (int k = 0; k < f.obj->n_channels; k++) {
                f.creader[k] = (struct mr_channel_reader){src, k};
                f.cwhole[k] = (vv_region_volume){.user = &f.creader[k],
                                                 .header = src->channel_level(src->user, k, 0),
                                                 .read_box = channel0_box,
                                                 .box_range = channel0_range,
                                                 .tile = f.leaf};
            }
            f.have_cwhole = 1;
        }
        if (s == VV_OK)
            s = render_nodes(&f);
        /* quality 2 of a renderer that supersamples: its points, the nodes
         * read again (not in progressive frames, whose nodes may be
         * pending) */
        vv_region_rays rays;
        vv_region_image rwhole, rpiece;
        memset(&rays, 0, sizeof rays);
        rwhole = rpiece = (vv_region_image){0};
        if (s == VV_OK && f.dc.split) {
            /* the channels added (the second pass of quality 2 is for one image) */
            dc_merge(wholes, f.dc.npass, w->background, out);
            whole.image = NULL; /* finished */
        } else if (s == VV_OK && !lod->progressive) {
            vv_region_image_finish(&whole, w->background);
            s = rays_begin(&whole, out, &rays, &rwhole, &rpiece);
            if (s == VV_OK && rays.n_pixels > 0) {
                f.whole = &rwhole;
                f.piece = &rpiece;
                f.rays = &rays;
                s = render_nodes(&f);
                if (s == VV_OK)
                    rays_finish(&rwhole, &rays, w->background, out);
            }
            whole.image = NULL; /* finished */
        }
        rays_end(&rays, &rwhole, &rpiece);
        if (src->frame)
            src->frame(src->user, 0);
        if (s == VV_OK && lod->progressive && lod->background)
            request_wanted(&f);
    }
    free(f.nodes);
    free(f.want);
    if (s == VV_OK && whole.image)
        vv_region_image_finish(&whole, w->background);
    for (int t = 0; t < MR_MAX_THREADS; t++)
        if (f.clones[t].release) /* after the finish: classify may be theirs */
            f.clones[t].release(&f.clones[t]);
    vv_image_free(piece.image);
    free(whole.key);
    dc_wholes_free(wholes, f.dc.npass);
    dc_free(&f.dc);
    return s;
}
