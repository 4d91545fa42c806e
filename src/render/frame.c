/*
 * The frame runner, the camera rays and the region images
 * (include/volvis/sys/renderer.h).
 *
 * One tile loop for every renderer that works per pixel: the image is cut
 * into square tiles, row-major, taken dynamically by OpenMP threads (as
 * OSPRay's load balancer hands out tiles); the renderer supplies the work
 * of one tile. Tiles write disjoint pixels and a pixel depends on its tile
 * alone, so the image is the same for any thread count. Progress is the
 * fraction of tiles done, reported under one lock; a non-zero answer
 * cancels the tiles not yet begun.
 */
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/frame.h"
#include "render/shade.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

/* ---- the frame runner ---------------------------------------------------------- */

void
vv_frame_job_init(vv_frame_job *job, int width, int height, vv_frame_tile_fn fn, void *user) {
    memset(job, 0, sizeof *job);
    job->width = width;
    job->height = height;
    job->tile = VV_FRAME_TILE;
    job->fn = fn;
    job->user = user;
    job->progress_to = 1;
}

void
vv_frame_job_region(vv_frame_job *job, const vv_render_region *rg) {
    if (!rg || rg->x1 <= rg->x0)
        return;
    job->x0 = rg->x0;
    job->y0 = rg->y0;
    job->x1 = rg->x1;
    job->y1 = rg->y1;
}

#define FRAME_SCRATCH_ALIGN 64

vv_status
vv_frame_run(const vv_frame_job *job, const vv_render_options *opt) {
    if (!job || !job->fn)
        return vv_error_set(VV_ERR_INVALID, "frame: NULL job");
    vv_render_options def;
    if (!opt) {
        vv_render_options_init(&def);
        opt = &def;
    }
    const int W = job->width, H = job->height;
    if (W <= 0 || H <= 0)
        return VV_OK;
    const int ts = job->tile > 0 ? job->tile : VV_FRAME_TILE;
    const int th = job->tile_h > 0 ? job->tile_h : ts;
    int rx0 = 0, ry0 = 0, rx1 = W, ry1 = H;
    if (job->x1 > job->x0) {
        rx0 = job->x0 > 0 ? job->x0 : 0;
        ry0 = job->y0 > 0 ? job->y0 : 0;
        rx1 = job->x1 < W ? job->x1 : W;
        ry1 = job->y1 < H ? job->y1 : H;
    }
    const int tx = (W + ts - 1) / ts, ty = (H + th - 1) / th;
    const int ntiles = tx * ty;
    const int nt = opt->threads > 0 ? opt->threads : vv_threads_get();
    const double p0 = job->progress_from, p1 = job->progress_to > 0 ? job->progress_to : 1.0;
    /* per-thread scratch, each on its own cache lines */
    size_t stride = 0;
    unsigned char *scratch = NULL;
    if (job->scratch_bytes) {
        stride = (job->scratch_bytes + FRAME_SCRATCH_ALIGN - 1) / FRAME_SCRATCH_ALIGN *
                 FRAME_SCRATCH_ALIGN;
        scratch = aligned_alloc(FRAME_SCRATCH_ALIGN, stride * (size_t)nt);
        if (!scratch)
            return vv_error_set(VV_ERR_NOMEM, "frame: out of memory for %d x %zu bytes of scratch",
                                nt, job->scratch_bytes);
        memset(scratch, 0, stride * (size_t)nt);
    }
    atomic_int stop = 0; /* 1: cancelled, 2: a tile failed */
    int done = 0;
    vv_status failed = VV_OK;
    char message[1024] = "";
    /* 8-bit pixels tile by tile: the caller's image, whole, of the buffer's
     * size; YUV 4:2:0 when no tile splits a 2 x 2 block (even tile sides) */
    vv_pixels8 *p8 = opt->pixels8;
    const int whole = rx0 == 0 && ry0 == 0 && rx1 == W && ry1 == H;
    const int of_image = job->image && p8 && whole && job->image->width == W &&
                         job->image->height == H && p8->width == W && p8->height == H;
    uint8_t *rgbx = of_image && p8->format == VV_PIXELS8_RGBX ? p8->rgbx : NULL;
    uint8_t *yuv = of_image && p8->format == VV_PIXELS8_YUV420 && (ts % 2 == 0 || ts >= W) &&
                           (th % 2 == 0 || th >= H)
                       ? p8->yuv
                       : NULL;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
    for (int tile = 0; tile < ntiles; tile++) {
        if (atomic_load_explicit(&stop, memory_order_relaxed))
            continue;
        vv_frame_tile t;
        t.x0 = (tile % tx) * ts;
        t.y0 = (tile / tx) * th;
        t.x1 = t.x0 + ts < W ? t.x0 + ts : W;
        t.y1 = t.y0 + th < H ? t.y0 + th : H;
        t.x0 = t.x0 > rx0 ? t.x0 : rx0;
        t.y0 = t.y0 > ry0 ? t.y0 : ry0;
        t.x1 = t.x1 < rx1 ? t.x1 : rx1;
        t.y1 = t.y1 < ry1 ? t.y1 : ry1;
        t.index = tile;
        t.thread = omp_get_thread_num();
        t.scratch = scratch ? scratch + stride * (size_t)t.thread : NULL;
        t.run = &stop;
        if (t.x1 > t.x0 && t.y1 > t.y0) {
            vv_status s = job->fn(job->user, &t);
            if (s != VV_OK) {
#pragma omp critical(vv_frame_error)
                {
                    if (failed == VV_OK) {
                        failed = s;
                        snprintf(message, sizeof message, "%s", vv_error_message());
                    }
                }
                atomic_store(&stop, 2);
                continue;
            }
            if (rgbx)
                vv_image_rect_to_rgbx8(job->image, t.x0, t.y0, t.x1, t.y1, rgbx);
            else if (yuv)
                vv_image_rect_to_yuv420(job->image, t.x0, t.y0, t.x1, t.y1, yuv);
        }
        if (opt->progress.fn) {
#pragma omp critical(vv_frame_progress)
            {
                done++;
                if (vv_progress_report(&opt->progress, p0 + (p1 - p0) * ((double)done / ntiles)))
                    atomic_store(&stop, 1);
            }
        }
    }
    free(scratch);
    if (failed != VV_OK)
        return vv_error_set(failed, "%s", message[0] ? message : "a tile failed");
    if (atomic_load(&stop))
        return vv_error_set(VV_ERR_CANCELLED, "cancelled");
    if (rgbx || yuv)
        p8->converted_in_tiles = 1;
    return VV_OK;
}

int
vv_frame_cancelled(const vv_frame_tile *t) {
    return atomic_load_explicit((const atomic_int *)t->run, memory_order_relaxed) != 0;
}

/* ---- adaptive image-space refinement --------------------------------------------- */

/* Levoy, "Volume Rendering by Adaptive Refinement" (1990), as
 * vv_frame_refine_tile says. A pixel interpolated from a cell of side s is
 * replaced by an interpolation from a smaller cell sharing it, and never
 * replaces a cast pixel; the order of the cells is fixed, so a tile always
 * gives the same pixels. */

#define RF_LATTICE VV_FRAME_REFINE_LATTICE
#define RF_RANGE 8          /* corners may differ by this many tolerances when the centre agrees */
#define RF_TS VV_FRAME_TILE /* the largest tile (a multiple of RF_LATTICE) */
#define RF_TL (RF_TS + 1)   /* the tile plus the next tile's first row and column */

typedef struct rf_tile {
    int x0, y0;
    vv_frame_pixel_fn fn;
    void *user, *work;
    float tolerance;
    float px[RF_TL * RF_TL][5];  /* colour and opacity, depth */
    int8_t level[RF_TL * RF_TL]; /* 0 cast; s interpolated from a cell of side s; -1 not yet */
} rf_tile;

const char *const vv_frame_refine_modes[] = {"auto", "on", "off", NULL};
const char *const vv_frame_refine_auto[] = {"auto", NULL};

size_t
vv_frame_refine_scratch_bytes(void) {
    return sizeof(rf_tile);
}

float
vv_frame_refine_tolerance(int quality) {
    static const float by_quality[3] = {1.0f / 16, 1.0f / 64, 1.0f / 1024};
    return by_quality[quality < 0 ? 0 : quality > 2 ? 2 : quality];
}

int
vv_frame_refine_for(const vv_frame_refine_settings *s, int quality, int region, int final_pays,
                    float *tolerance) {
    *tolerance = s->tolerance >= 0 ? (float)s->tolerance : vv_frame_refine_tolerance(quality);
    return !region && (s->mode == 1 || (s->mode == 0 && (quality <= 1 || final_pays)));
}

static inline float *
rf_cast(rf_tile *tb, int x, int y) {
    const int i = (y - tb->y0) * RF_TL + (x - tb->x0);
    if (tb->level[i] != 0) {
        tb->fn(tb->user, x, y, tb->px[i], tb->work);
        tb->level[i] = 0;
    }
    return tb->px[i];
}

/* Whether four corners differ by at most @p limit in every channel. */
static inline int
corners_within(const float *c00, const float *c10, const float *c01, const float *c11,
               float limit) {
    for (int ch = 0; ch < 4; ch++) {
        float lo = c00[ch], hi = c00[ch];
        lo = c10[ch] < lo ? c10[ch] : lo;
        hi = c10[ch] > hi ? c10[ch] : hi;
        lo = c01[ch] < lo ? c01[ch] : lo;
        hi = c01[ch] > hi ? c01[ch] : hi;
        lo = c11[ch] < lo ? c11[ch] : lo;
        hi = c11[ch] > hi ? c11[ch] : hi;
        if (hi - lo > limit)
            return 0;
    }
    return 1;
}

static void
refine_cell(rf_tile *tb, int xa, int ya, int xb, int yb) {
    const int w = xb - xa, h = yb - ya;
    const float *c00 = rf_cast(tb, xa, ya), *c10 = rf_cast(tb, xb, ya);
    const float *c01 = rf_cast(tb, xa, yb), *c11 = rf_cast(tb, xb, yb);
    if (w <= 1 && h <= 1)
        return; /* every pixel is a corner */
    /* the cell's centre against the corners' bilinear prediction, and
     * the corners' range against RF_RANGE tolerances */
    const int xc = xa + w / 2, yc = ya + h / 2;
    const float *cc = rf_cast(tb, xc, yc);
    const float fxc = (float)(xc - xa) / (float)w, fyc = (float)(yc - ya) / (float)h;
    int agree = corners_within(c00, c10, c01, c11, RF_RANGE * tb->tolerance);
    for (int ch = 0; ch < 4 && agree; ch++) {
        const float pred = (1 - fxc) * ((1 - fyc) * c00[ch] + fyc * c01[ch]) +
                           fxc * ((1 - fyc) * c10[ch] + fyc * c11[ch]);
        agree = fabsf(cc[ch] - pred) <= tb->tolerance;
    }
    if (!agree) {
        const int xm = w > 1 ? xa + w / 2 : xb, ym = h > 1 ? ya + h / 2 : yb;
        refine_cell(tb, xa, ya, xm, ym);
        if (xm < xb)
            refine_cell(tb, xm, ya, xb, ym);
        if (ym < yb)
            refine_cell(tb, xa, ym, xm, yb);
        if (xm < xb && ym < yb)
            refine_cell(tb, xm, ym, xb, yb);
        return;
    }
    /* interpolate; the depth is the corners' where they all hit, else the
     * nearest corner's */
    const int s = w > h ? w : h;
    float dmin = c00[4];
    dmin = c10[4] < dmin ? c10[4] : dmin;
    dmin = c01[4] < dmin ? c01[4] : dmin;
    dmin = c11[4] < dmin ? c11[4] : dmin;
    const int finite = isfinite(c00[4]) && isfinite(c10[4]) && isfinite(c01[4]) && isfinite(c11[4]);
    for (int y = ya; y <= yb; y++) {
        const float fy = (float)(y - ya) / (float)h;
        for (int x = xa; x <= xb; x++) {
            const int i = (y - tb->y0) * RF_TL + (x - tb->x0);
            if (tb->level[i] >= 0 && tb->level[i] <= s)
                continue; /* cast, or from a cell no larger */
            const float fx = (float)(x - xa) / (float)w;
            const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy);
            const float w01 = (1 - fx) * fy, w11 = fx * fy;
            float *p = tb->px[i];
            for (int ch = 0; ch < 4; ch++)
                p[ch] = w00 * c00[ch] + w10 * c10[ch] + w01 * c01[ch] + w11 * c11[ch];
            p[4] = finite ? w00 * c00[4] + w10 * c10[4] + w01 * c01[4] + w11 * c11[4] : dmin;
            tb->level[i] = (int8_t)s;
        }
    }
}

void
vv_frame_refine_tile(const vv_frame_tile *t, int width, int height, float tolerance,
                     vv_frame_pixel_fn fn, void *user, void *work, float *rgba, float *depth) {
    if (t->x1 - t->x0 > RF_TS || t->y1 - t->y0 > RF_TS || !t->scratch) {
        /* not a tile this can hold: every pixel cast */
        for (int y = t->y0; y < t->y1; y++)
            for (int x = t->x0; x < t->x1; x++) {
                float p[5];
                fn(user, x, y, p, work);
                const size_t at = (size_t)y * (size_t)width + (size_t)x;
                memcpy(rgba + 4 * at, p, 4 * sizeof(float));
                depth[at] = p[4];
            }
        return;
    }
    rf_tile *tb = t->scratch;
    tb->x0 = t->x0;
    tb->y0 = t->y0;
    tb->fn = fn;
    tb->user = user;
    tb->work = work;
    tb->tolerance = tolerance;
    memset(tb->level, -1, sizeof tb->level);
    /* the corners this tile reaches: the next tile's first column and row,
     * or the image's last */
    const int ex = t->x1 < width ? t->x1 : width - 1, ey = t->y1 < height ? t->y1 : height - 1;
    const int whole = ex <= t->x0 || ey <= t->y0; /* a one-pixel strip at the image's edge */
    int cells = 0, calm = 0;
    /* the lattice first: a tile where most cells' corners differ beyond
     * the range is cast whole (refining it would cast more rays) */
    for (int ya = t->y0; ya < ey && !whole; ya += RF_LATTICE)
        for (int xa = t->x0; xa < ex; xa += RF_LATTICE) {
            const int xb = xa + RF_LATTICE < ex ? xa + RF_LATTICE : ex;
            const int yb = ya + RF_LATTICE < ey ? ya + RF_LATTICE : ey;
            cells++;
            calm += corners_within(rf_cast(tb, xa, ya), rf_cast(tb, xb, ya), rf_cast(tb, xa, yb),
                                   rf_cast(tb, xb, yb), RF_RANGE * tolerance);
        }
    if (whole || 2 * calm < cells) {
        for (int y = t->y0; y < t->y1; y++)
            for (int x = t->x0; x < t->x1; x++)
                rf_cast(tb, x, y);
    } else {
        for (int ya = t->y0; ya < ey; ya += RF_LATTICE)
            for (int xa = t->x0; xa < ex; xa += RF_LATTICE)
                refine_cell(tb, xa, ya, xa + RF_LATTICE < ex ? xa + RF_LATTICE : ex,
                            ya + RF_LATTICE < ey ? ya + RF_LATTICE : ey);
    }
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++) {
            const float *p = tb->px[(y - t->y0) * RF_TL + (x - t->x0)];
            const size_t at = (size_t)y * (size_t)width + (size_t)x;
            memcpy(rgba + 4 * at, p, 4 * sizeof(float));
            depth[at] = p[4];
        }
}

/* ---- camera rays ------------------------------------------------------------------ */

void
vv_camera_rays_init(vv_camera_rays *c, const vv_view *view) {
    const vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    vv_ray r00 = vv_view_ray(view, 0, 0), r10 = vv_view_ray(view, 1, 0),
           r01 = vv_view_ray(view, 0, 1);
    vv_ray *rs[3] = {&r00, &r10, &r01};
    c->ortho = view->projection == VV_PROJECTION_ORTHOGRAPHIC;
    for (int i = 0; i < 3; i++) {
        /* perspective: to unit depth along the view axis, where the
         * direction is affine in the pixel position */
        const double df = vv_vec3_dot(rs[i]->dir, f);
        if (!c->ortho && df > 0)
            rs[i]->dir = vv_vec3_scale(rs[i]->dir, 1.0 / df);
    }
    c->forward = f;
    c->o00 = r00.origin;
    c->ox = vv_vec3_sub(r10.origin, r00.origin);
    c->oy = vv_vec3_sub(r01.origin, r00.origin);
    c->d00 = r00.dir;
    c->dx = vv_vec3_sub(r10.dir, r00.dir);
    c->dy = vv_vec3_sub(r01.dir, r00.dir);
}

/* ---- region images ------------------------------------------------------------------ */

vv_status
vv_render_region_check(const vv_world *w, const vv_render_region *rg, vv_region_op *op) {
    const vv_object *obj = w->objects[rg->object];
    for (int i = 0; i < w->n_objects; i++)
        if (i != rg->object && w->objects[i]->visible)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "object '%s': a region render draws one object, not '%s' too",
                                obj->name, w->objects[i]->name);
    if (obj->solid_texture.kind != VV_SOLID_TEXTURE_NONE)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': solid textures are not rendered by regions", obj->name);
    if (obj->n_channels > 1 && rg->pass_channel > 0) {
        const int c = rg->pass_channel - 1;
        if (c >= obj->n_channels)
            return vv_error_set(VV_ERR_INVALID, "object '%s': no channel %d (it has %d)", obj->name,
                                c, obj->n_channels);
        *op = obj->blend == VV_BLEND_MAXIMUM ? VV_REGION_MAX : VV_REGION_OVER;
        return VV_OK;
    }
    if (rg->pass_channel > 0)
        return vv_error_set(VV_ERR_INVALID,
                            "object '%s': a channel's pass of an object of one channel", obj->name);
    if (obj->n_channels > 1) {
        /* the channels mixed sample by sample and composited (the
         * composite rule): over, whatever the object's own mode */
        if (obj->blend != VV_BLEND_COMPOSITE)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "object '%s': its channels under the %s rule are drawn by regions "
                                "a channel at a time (the drivers' way), not all at once",
                                obj->name, vv_channel_blend_name(obj->blend));
        if (!rg->channel_voxels)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "object '%s' has %d channels; a region render of it needs every "
                                "drawn channel's voxels (vv_render_region.channel_voxels)",
                                obj->name, obj->n_channels);
        *op = VV_REGION_OVER;
        return VV_OK;
    }
    *op = vv_region_op_for(obj->mode);
    return VV_OK;
}

vv_status
vv_render_region_part(const vv_world *w, const vv_render_region *rg, vv_region_op *op,
                      vv_object *part, vv_channel **chan) {
    *chan = NULL;
    vv_status s = vv_render_region_check(w, rg, op);
    if (s != VV_OK)
        return s;
    const vv_object *obj = w->objects[rg->object];
    if (rg->pass_channel > 0) { /* one channel alone: the region's voxels are its */
        vv_vchannel_object(obj, &obj->channels[rg->pass_channel - 1], part);
        part->volume = (vv_volume *)rg->voxels;
        return VV_OK;
    }
    *part = *obj;
    part->volume = (vv_volume *)rg->voxels;
    if (obj->n_channels > 1) {
        vv_channel *c = malloc(sizeof *c * (size_t)obj->n_channels);
        if (!c)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        int shown = 0;
        for (int k = 0; k < obj->n_channels; k++) {
            c[k] = obj->channels[k];
            c[k].volume = (vv_volume *)rg->channel_voxels[k];
            c[k].visible &= c[k].volume != NULL; /* none: nothing of it here */
            shown += c[k].visible;
        }
        if (!shown) {
            free(c);
            return vv_error_set(VV_ERR_INVALID,
                                "object '%s': the region has the voxels of no channel shown",
                                obj->name);
        }
        part->channels = c;
        *chan = c;
    }
    return VV_OK;
}

vv_status
vv_render_region_world(const vv_world *w, const vv_render_region *rg, vv_region_op *op,
                       vv_region_world *out) {
    vv_status s = vv_render_region_part(w, rg, op, &out->part, &out->chan);
    if (s != VV_OK)
        return s;
    out->slot[0] = &out->part;
    out->world = *w;
    out->world.objects = out->slot;
    out->world.n_objects = 1;
    return VV_OK;
}

void
vv_region_world_release(vv_region_world *rw) {
    if (!rw)
        return;
    free(rw->chan);
    rw->chan = NULL;
}

void
vv_region_rays_free(vv_region_rays *r) {
    if (!r)
        return;
    free(r->pixel);
    free(r->xy);
    memset(r, 0, sizeof *r);
}

void
vv_region_image_clear_rect(vv_region_image *img, int x0, int y0, int x1, int y1) {
    const int W = img->image->width;
    x0 = x0 < 0 ? 0 : x0;
    y0 = y0 < 0 ? 0 : y0;
    x1 = x1 > W ? W : x1;
    y1 = y1 > img->image->height ? img->image->height : y1;
    for (int y = y0; y < y1 && x1 > x0; y++) {
        const size_t row = (size_t)y * (size_t)W;
        memset(img->image->rgba + 4 * (row + (size_t)x0), 0, sizeof(float) * 4 * (size_t)(x1 - x0));
        for (size_t i = row + (size_t)x0; i < row + (size_t)x1; i++) {
            img->image->depth[i] = INFINITY;
            img->key[i] = NAN;
        }
    }
}

void
vv_region_image_clear(vv_region_image *img) {
    vv_region_image_clear_rect(img, 0, 0, img->image->width, img->image->height);
}

void
vv_region_image_combine_rect(vv_region_image *front, const vv_region_image *back, int x0, int y0,
                             int x1, int y1) {
    const int W = front->image->width;
    const vv_region_op op = front->op;
    if (back->classify) { /* the renderer's table for the summed means */
        front->classify = back->classify;
        front->classify_ctx = back->classify_ctx;
    }
    if (back->supersample) { /* the renderer's rays of quality 2 */
        front->supersample = back->supersample;
        front->supersample_ctx = back->supersample_ctx;
    }
    x0 = x0 < 0 ? 0 : x0;
    y0 = y0 < 0 ? 0 : y0;
    x1 = x1 > W ? W : x1;
    y1 = y1 > front->image->height ? front->image->height : y1;
    for (int y = y0; y < y1; y++)
        for (size_t i = (size_t)y * (size_t)W + (size_t)x0; i < (size_t)y * (size_t)W + (size_t)x1;
             i++)
            vv_region_pixel_combine(op, front->image->rgba + 4 * i, front->image->depth + i,
                                    front->key + i, back->image->rgba + 4 * i,
                                    back->image->depth[i], back->key[i]);
}

void
vv_region_image_combine(vv_region_image *front, const vv_region_image *back) {
    vv_region_image_combine_rect(front, back, 0, 0, front->image->width, front->image->height);
}

void
vv_region_image_finish(vv_region_image *img, vv_vec3 background) {
    const size_t n = (size_t)img->image->width * (size_t)img->image->height;
    const float bg[3] = {(float)background.x, (float)background.y, (float)background.z};
    for (size_t i = 0; i < n; i++) {
        float *pix = img->image->rgba + 4 * i;
        if (img->op == VV_REGION_SUM || img->op == VV_REGION_ATTENUATED_MAX) {
            /* the mean of the pixel's samples (or its attenuated maximum),
             * classified as the whole render classifies it (raycast:
             * cast_pixel's projections) */
            const float k = img->key ? img->key[i] : NAN;
            float e[4] = {0, 0, 0, 0};
            if (k == k && img->classify && img->op == VV_REGION_ATTENUATED_MAX)
                img->classify(img->classify_ctx, k, e);
            else if (k == k && img->classify && pix[1] > 0)
                img->classify(img->classify_ctx,
                              (float)(((double)k + (double)pix[0]) / (double)pix[1]), e);
            pix[0] = e[1] * e[0];
            pix[1] = e[2] * e[0];
            pix[2] = e[3] * e[0];
            pix[3] = e[0];
        }
        /* as the whole render writes a pixel: C + (1 - A) background */
        const float A = pix[3] > 1 ? 1 : pix[3];
        for (int ch = 0; ch < 3; ch++)
            pix[ch] = pix[ch] + (1 - A) * bg[ch];
        pix[3] = A;
    }
}

/* Solves the 3x3 system with columns c0, c1, c2 for rhs (Cramer); 0 when
 * singular. */
static int
solve3(vv_vec3 c0, vv_vec3 c1, vv_vec3 c2, vv_vec3 rhs, double x[3]) {
    const double det = vv_vec3_dot(c0, vv_vec3_cross(c1, c2));
    if (!(fabs(det) > 1e-300))
        return 0;
    x[0] = vv_vec3_dot(rhs, vv_vec3_cross(c1, c2)) / det;
    x[1] = vv_vec3_dot(c0, vv_vec3_cross(rhs, c2)) / det;
    x[2] = vv_vec3_dot(c0, vv_vec3_cross(c1, rhs)) / det;
    return 1;
}

void
vv_region_rect(vv_render_region *b, vv_mat4 m, const vv_view *view, const int lo[3],
               const int hi[3]) {
    b->x0 = b->y0 = 0;
    b->x1 = b->y1 = 0; /* whole image until proven smaller */
    vv_camera_rays c;
    vv_camera_rays_init(&c, view);
    const vv_vec3 f = c.forward;
    /* the pixel position of a point: solve o00 + x ox + y oy + z f = p
     * (orthographic) or o00 + z (d00 + x dx + y dy) = p (perspective) */
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int k = 0; k < 8; k++) {
        const vv_vec3 pi =
            vv_vec3_make(k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]);
        const vv_vec3 pw = vv_mat4_mul_point(m, pi);
        double x[3];
        if (c.ortho) {
            if (!solve3(c.ox, c.oy, f, vv_vec3_sub(pw, c.o00), x))
                return;
        } else {
            if (!(vv_vec3_dot(c.d00, f) > 0) ||
                !solve3(c.dx, c.dy, c.d00, vv_vec3_sub(pw, c.o00), x) || !(x[2] > 1e-9))
                return; /* behind the eye: every pixel may see it */
            x[0] /= x[2];
            x[1] /= x[2];
        }
        xmin = x[0] < xmin ? x[0] : xmin;
        xmax = x[0] > xmax ? x[0] : xmax;
        ymin = x[1] < ymin ? x[1] : ymin;
        ymax = x[1] > ymax ? x[1] : ymax;
    }
    if (!(xmax - xmin < 1e7 && ymax - ymin < 1e7))
        return;
    /* pixel px's ray is at px: the pixels within two of the projection */
    const double X0 = floor(xmin) - 2, X1 = ceil(xmax) + 3, Y0 = floor(ymin) - 2,
                 Y1 = ceil(ymax) + 3;
    b->x0 = X0 < 0 ? 0 : X0 > view->width ? view->width : (int)X0;
    b->x1 = X1 < 0 ? 0 : X1 > view->width ? view->width : (int)X1;
    b->y0 = Y0 < 0 ? 0 : Y0 > view->height ? view->height : (int)Y0;
    b->y1 = Y1 < 0 ? 0 : Y1 > view->height ? view->height : (int)Y1;
    if (b->x1 <= b->x0 || b->y1 <= b->y0) {
        /* off screen: an empty rectangle that is not "whole image" */
        b->x0 = 0;
        b->x1 = 1;
        b->y0 = b->y1 = 0;
    }
}
