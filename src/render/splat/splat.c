/*
 * Splatting: object-order direct volume rendering (the VolVis paper,
 * abstract and section 2, lists it beside ray casting).
 *
 * Every voxel carries a 3-D Gaussian reconstruction kernel, isotropic in
 * index space (sigma and cut-off radius in voxels), so that in world space
 * it is the ellipsoid that the spacing, direction matrix and object
 * transform make of it; seen from the eye its covariance is
 * sigma^2 A A^T with A the index-to-eye linear map. Its footprint (Westover,
 * "Footprint evaluation for volume rendering", SIGGRAPH 1990) is the
 * kernel integrated along the view direction: a 2-D Gaussian, an ellipse,
 * evaluated as a function of the squared radius after mapping the ellipse
 * to a circle (Westover's radial footprint table; for a Gaussian the
 * integral is closed-form, so the exponential itself is computed, four
 * pixels at a time); each footprint is cut off at the kernel radius and
 * normalised over its disc.
 *
 * Composite, MIP and MinIP use image-aligned sheet buffers (Mueller and
 * Crawfis, "Eliminating popping artifacts in sheet buffer-based splatting",
 * Vis '98): sheets parallel to the image plane, one every sheet spacing in
 * depth, each receiving the slices of the kernels that cross its slab. A
 * Gaussian's slice at depth offset s is again a Gaussian: mass given by
 * the 1-D marginal over the slab (a table of slab integrals), centre
 * shifted by b s, covariance the conditional one (plus the shift's spread
 * over the slab). Sheets hold sum(w), sum(w v) and sum(w g) (values and
 * cached voxel gradients); post-classification (Mueller, Moeller and
 * Crawfis, "Splatting without the blur", Vis '99) classifies and shades the
 * normalised sheet value sum(w v) / sum(w) of each pixel, and the sheets
 * are composited front to back. Pre-classified splatting (option
 * classification=pre) classifies and shades each voxel once and splats
 * opacity and colour instead (faster, blurrier). X-ray splats whole
 * footprints: the image is the line integral, divided by the integral of
 * the weights for the mean the ray caster shows.
 *
 * Antialiasing (Zwicker, Pfister, van Baar and Gross, "EWA volume
 * splatting", Vis '01): every screen-space footprint covariance has its
 * eigenvalues raised to at least the variance of the image low-pass filter
 * (default 0.25 pixel^2), which is what convolving a footprint smaller than
 * a pixel with the filter does; larger footprints are left alone so that
 * near data stays as sharp as the ray caster's. In perspective the
 * footprint of every sheet is scaled by the sheet's depth.
 *
 * Sheets sit at depth z = k dt (world units from the eye plane, dt the ray
 * caster's step), and each pixel composites only the sheets inside its
 * ray's clipped interval (volume box and cut planes, vv_vray_setup), so in
 * parallel projection the samples are exactly the ray caster's and only
 * the reconstruction differs. Opacity uses the ray caster's tables
 * (src/render/classify.h), corrected per pixel for the slant of
 * perspective rays.
 *
 * Cost: a voxel is listed only when its subvolume lies within the kernel's
 * reach of a subvolume visible under the transfer function (the min/max
 * grid of the ray caster's tables) and the values within twice the reach
 * of it span a visible table entry (separable min/max filters); the lists
 * are built in the traversal order of the view-direction octant and kept
 * between renders while the octant, transfer function and volume do not
 * change; each render bucket-sorts them by sheet. The image is cut into
 * bands of rows rendered independently (OpenMP, dynamic), each with its
 * own voxel lists, sheet buffer and occlusion map of 8x8-pixel tiles: a
 * footprint whose bounding box covers only finished pixels (opaque, or
 * past their ray's exit) is not splatted. Every pixel sums its voxels in
 * list order, so the image does not depend on the thread count.
 * docs/rendering.md describes the method and its measurements.
 *
 * Files, one a stage (splat_internal.h): footprint.c (footprints),
 * object.c (per-object geometry, voxel lists, buckets), band.c (one band:
 * sheets, classification, compositing, occlusion) and this file (the
 * frame: view, objects, the bands as tiles of the frame runner, options).
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/frame.h"
#include "render/splat/splat_internal.h"

/* ---------------------------------------------------------------------- */
/* Frame set-up                                                             */

static void
prepare_view(sp_frame *fr, const vv_view *view) {
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(view->at, view->eye));
    vv_ray r00 = vv_view_ray(view, 0, 0), r10 = vv_view_ray(view, 1, 0),
           r01 = vv_view_ray(view, 0, 1);
    f = r00.dir;
    fr->persp = view->projection != VV_PROJECTION_ORTHOGRAPHIC;
    if (fr->persp) {
        /* the forward axis: the ray through the image centre */
        vv_ray rc = vv_view_ray(view, 0.5 * view->width - 0.5, 0.5 * view->height - 0.5);
        f = rc.dir;
    }
    fr->f = f;
    vv_ray *rs[3] = {&r00, &r10, &r01};
    for (int i = 0; i < 3; i++) {
        const double df = vv_vec3_dot(rs[i]->dir, f);
        if (fr->persp && df > 0)
            rs[i]->dir = vv_vec3_scale(rs[i]->dir, 1.0 / df);
    }
    fr->o00 = r00.origin;
    fr->ox = vv_vec3_sub(r10.origin, r00.origin);
    fr->oy = vv_vec3_sub(r01.origin, r00.origin);
    fr->d00 = r00.dir;
    fr->dx = vv_vec3_sub(r10.dir, r00.dir);
    fr->dy = vv_vec3_sub(r01.dir, r00.dir);
    if (fr->persp) {
        fr->eye = view->eye;
        fr->pix = vv_vec3_length(fr->dx);
        fr->r = vv_vec3_scale(fr->dx, 1.0 / fr->pix);
        fr->u = vv_vec3_normalize(fr->dy);
        fr->pcx = vv_vec3_dot(fr->d00, fr->r) / fr->pix;
        fr->pcy = vv_vec3_dot(fr->d00, fr->u) / fr->pix;
    } else {
        fr->eye = fr->o00;
        fr->pix = vv_vec3_length(fr->ox);
        fr->r = vv_vec3_scale(fr->ox, 1.0 / fr->pix);
        fr->u = vv_vec3_normalize(fr->oy);
    }
}

static vv_status
prepare_object(sp_frame *fr, sp_obj *ob, const vv_object *obj, const vv_world *w) {
    sp_state *st = fr->st;
    memset(ob, 0, sizeof *ob);
    ob->obj = obj;
    ob->mode = obj->mode;
    if (obj->mode == VV_MODE_ISO)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': iso mode is not drawn by splatting (use raycast or "
                            "surface)",
                            obj->name);
    if (obj->mode == VV_MODE_COMPOSITE && obj->segmentation == VV_SEG_TRANSFER_FUNCTION_2D)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': 2-D transfer functions are not drawn by splatting (use "
                            "raycast)",
                            obj->name);
    if (obj->mode == VV_MODE_COMPOSITE && obj->solid_texture.kind != VV_SOLID_TEXTURE_NONE)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': solid textures are not drawn by splatting (use raycast)",
                            obj->name);
    const int dims_ok = obj->volume->dims[0] < (1 << 21) && obj->volume->dims[1] < (1 << 21) &&
                        obj->volume->dims[2] < (1 << 21);
    if (!dims_ok)
        return vv_error_set(VV_ERR_LIMIT, "object '%s': more than 2^21 voxels along an axis",
                            obj->name);
    ob->is_comp = obj->mode == VV_MODE_COMPOSITE;
    ob->labels = ob->is_comp && obj->segmentation == VV_SEG_LABELS;
    /* a label volume is classified per voxel: a value reconstructed
     * between a label and the background (0) is no label */
    ob->pre_cls = fr->st->pre || ob->labels;
    vv_status s = vv_vcache_get(&st->vc, obj->volume, &ob->c);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    s = vv_vobject_prepare(obj, w, fr->ambient, fr->lights, fr->n_lights, ob->w2i, ob->i2w,
                           ob->dims, ob->planes, &ob->n_planes, &ob->sh);
    if (s != VV_OK)
        return s;
    ob->shading = obj->shading;
    return VV_OK;
}

/* The visible volume objects of @p w (composite and iso first, then the
 * projections), their geometry, tables, voxel lists and buckets, the sheet
 * spacing and the image bands. */
static vv_status
prepare_objects(sp_frame *fr, const vv_world *w, const vv_view *view, double rate, int nt) {
    sp_state *st = fr->st;
    int nvis = 0;
    for (int i = 0; i < w->n_objects; i++)
        if (w->objects[i]->visible && w->objects[i]->type == VV_OBJECT_VOLUME &&
            w->objects[i]->volume)
            nvis++;
    vv_status s = VV_OK;
    if (nvis > SP_MAX_OBJ)
        s = vv_error_set(VV_ERR_LIMIT, "%d visible objects; at most %d are supported", nvis,
                         SP_MAX_OBJ);
    sp_obj *objs = s == VV_OK ? calloc(nvis ? (size_t)nvis : 1, sizeof *objs) : NULL;
    if (s == VV_OK && !objs)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    fr->objs = objs;
    double dt = INFINITY;
    for (int pass = 0; pass < 2 && s == VV_OK; pass++)
        for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
            const vv_object *ob = w->objects[i];
            if (!ob->visible || ob->type != VV_OBJECT_VOLUME || !ob->volume)
                continue;
            const int comp = ob->mode == VV_MODE_COMPOSITE || ob->mode == VV_MODE_ISO;
            if (comp != (pass == 0))
                continue;
            if (!(ob->step > 0))
                s = vv_error_set(VV_ERR_INVALID, "object '%s': step must be > 0", ob->name);
            else
                s = prepare_object(fr, &objs[fr->n_obj++], ob, w);
            if (s == VV_OK) {
                const double sd = vv_vobject_step(ob);
                dt = sd < dt ? sd : dt;
            }
            if (pass == 0)
                fr->n_comp = fr->n_obj;
        }
    fr->dt = dt < INFINITY ? dt : 1.0;
    fr->dts = fr->dt * rate;
    fr->znear = fr->persp ? fr->dts : -INFINITY;
    /* bands: several per thread for balance, at least 8 rows */
    int bh = (view->height + 4 * nt - 1) / (4 * nt);
    bh = bh < 8 ? 8 : bh;
    fr->band_h = bh;
    fr->n_bands = (view->height + bh - 1) / bh;
    if (fr->n_bands > 32767)
        s = s == VV_OK ? vv_error_set(VV_ERR_LIMIT, "image of %d rows is too tall", view->height)
                       : s;
    for (int o = 0; o < fr->n_obj && s == VV_OK; o++) {
        sp_obj *ob = &objs[o];
        sp_object_geometry(fr, ob);
        /* the opacity table for the sheet spacing (axis variant: the slice
         * distance along the view) */
        double dtl = fr->dts;
        if (st->axis) {
            double best = -1;
            for (int a = 0; a < 3; a++) {
                const double g =
                    ob->w2i[a][0] * fr->f.x + ob->w2i[a][1] * fr->f.y + ob->w2i[a][2] * fr->f.z;
                if (fabs(g) > best) {
                    best = fabs(g);
                    ob->axis_a = a;
                    ob->axis_sign = g > 0 ? 1 : -1;
                }
            }
            dtl = 1.0 / best;
        }
        ob->dt_lut = dtl;
        s = vv_vtables_get(&st->vc, ob->c, ob->obj, ob->mode, dtl, 0, 1, 0, &ob->tab,
                           &ob->owns_tables);
        if (s != VV_OK)
            break;
        /* octant of the view direction in index space */
        int oct = 0;
        for (int a = 0; a < 3; a++) {
            const double g =
                ob->w2i[a][0] * fr->f.x + ob->w2i[a][1] * fr->f.y + ob->w2i[a][2] * fr->f.z;
            oct |= g < 0 ? 1 << a : 0;
        }
        s = sp_object_list(st, ob, oct, &st->stats.lists_built);
        if (s == VV_OK)
            s = sp_object_buckets(fr, ob);
        st->stats.voxels += (uint64_t)ob->c->nx * (uint64_t)ob->c->ny * (uint64_t)ob->c->nz;
        st->stats.listed += ob->list ? ob->list->n : 0;
    }
    return s;
}

static vv_status
render_band_tile(void *user, const vv_frame_tile *t) {
    sp_frame *fr = user;
    return sp_render_band(fr, t, fr->out);
}

static vv_status
sp_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    sp_state *st = state;
    memset(&st->stats, 0, sizeof st->stats);
    free(st->xray);
    st->xray = NULL;
    if (!(st->sigma > 0) || !(st->radius > 0))
        return vv_error_set(VV_ERR_INVALID, "kernel radius and sigma must be > 0");
    sp_frame *fr = calloc(1, sizeof *fr);
    if (!fr)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    fr->st = st;
    fr->opt = opt;
    fr->view = view;
    st->vc.frame++;
    fr->et = (float)st->early_termination;
    vv_frame_colours(w, 0, fr->ambient, fr->bg);
    fr->n_lights = vv_vlights_prepare(fr->lights, w, view);
    for (int l = 0; l < fr->n_lights; l++)
        fr->point_lights |= fr->lights[l].point;
    prepare_view(fr, view);

    /* quality: sheet spacing and kernel radius */
    double rate = st->rate, radius = st->radius;
    if (!(rate > 0))
        rate = opt->quality >= 2 ? 1.0 : opt->quality == 1 ? 1.5 : 2.0;
    if (opt->quality <= 0)
        radius = radius < 1.0 ? radius : 1.0;
    else if (opt->quality == 1)
        radius = radius * 0.85 > 1.0 ? radius * 0.85 : (radius < 1.0 ? radius : 1.0);
    fr->rho2 = (radius / st->sigma) * (radius / st->sigma);
    if (fr->rho2 > 64.0)
        fr->rho2 = 64.0; /* the Gaussian is below 1e-14 beyond 8 sigma */
    const double rho2 = fr->rho2;
    fr->fp_scale = (float)(1.0 / (2 * VV_PI * (1.0 - exp(-0.5 * rho2))));

    const int nt = opt->threads > 0 ? opt->threads : vv_threads_get();
    vv_status s = prepare_objects(fr, w, view, rate, nt);
    sp_obj *objs = fr->objs;
    int has_xray = 0;
    for (int o = 0; o < fr->n_obj; o++)
        has_xray |= objs[o].mode == VV_MODE_XRAY;
    if (s == VV_OK && has_xray) {
        fr->xray = calloc((size_t)view->width * (size_t)view->height, sizeof(float));
        if (!fr->xray)
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    if (s == VV_OK) {
        /* one tile a band, full width: bands render independently */
        fr->out = out;
        vv_frame_job job;
        vv_frame_job_init(&job, view->width, view->height, render_band_tile, fr);
        job.tile = view->width;
        job.tile_h = fr->band_h;
        s = vv_frame_run(&job, opt);
    }
    st->stats.footprints = fr->footprints;
    st->stats.culled = fr->culled;
    st->stats.sheets = fr->sheets;
    if (s == VV_OK && fr->xray) {
        /* the line integrals in world units: footprints were in world units
         * per pixel area; nothing to rescale */
        st->xray = fr->xray;
        st->xray_w = view->width;
        st->xray_h = view->height;
        fr->xray = NULL;
    }
    free(fr->xray);
    for (int o = 0; o < fr->n_obj; o++)
        sp_object_free(&objs[o], fr->n_bands);
    free(objs);
    free(fr);
    vv_vcache_set_prune(&st->vc, w);
    return s;
}

/* ---------------------------------------------------------------------- */
/* Options and the operation table                                          */

static vv_status
sp_init(void *state) {
    sp_state *st = state;
    vv_vcache_set_init(&st->vc);
    return VV_OK;
}

static void
lists_clear(sp_state *st) {
    for (int l = 0; l < SP_LISTS; l++) {
        vv_volume_free(st->lists[l].vol);
        free(st->lists[l].vox);
        memset(&st->lists[l], 0, sizeof st->lists[l]);
    }
}

/* sheet_spacing: 0 (by quality) or at least a quarter step. */
static vv_status
sp_spacing_check(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    (void)v;
    const sp_state *st = state;
    if (!(st->rate == 0 || st->rate >= 0.25))
        return vv_error_set(VV_ERR_INVALID,
                            "sheet_spacing must be 0 (by quality) or in [0.25, 8] steps");
    return VV_OK;
}

/* gradient_budget_mb: the number is stored (bytes); auto is the cache's
 * default; either way the cached gradients go. */
static vv_status
sp_budget_changed(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    sp_state *st = state;
    if (v->word >= 0)
        vv_vcache_set_default_budget(&st->vc);
    vv_vcache_set_clear(&st->vc);
    return VV_OK;
}

static void
sp_release(void *state) {
    sp_state *st = state;
    lists_clear(st);
    vv_vcache_set_clear(&st->vc);
    free(st->xray);
}

const vv_splat_stats *
vv_splat_stats_get(const vv_renderer *r) {
    if (!r || vv_renderer_ops_of(r) != &vv_splat_ops)
        return NULL;
    const sp_state *st = vv_renderer_state(r);
    return &st->stats;
}

const float *
vv_splat_xray_integral(const vv_renderer *r) {
    if (!r || vv_renderer_ops_of(r) != &vv_splat_ops)
        return NULL;
    const sp_state *st = vv_renderer_state(r);
    return st->xray;
}

static const char *const sp_classification[] = {"post", "pre", NULL};
static const char *const sp_sheets[] = {"image", "axis", NULL};
static const char *const sp_auto[] = {"auto", NULL};

/* The splatter's options, each bound to its field of sp_state. */
static const vv_option_spec sp_options[] = {
    {"radius", VV_OPTION_REAL, "1.2", 0, 8, VV_OPTION_MIN_OPEN, NULL,
     "kernel cut-off, voxels (quality 1 shrinks it to 0.85 of it, quality 0 to 1 voxel)",
     VV_OPTION_BIND(sp_state, radius, DOUBLE)},
    {"sigma", VV_OPTION_REAL, "0.55", 0, 4, VV_OPTION_MIN_OPEN, NULL, "Gaussian sigma, voxels",
     VV_OPTION_BIND(sp_state, sigma, DOUBLE)},
    {"ewa_variance", VV_OPTION_REAL, "0.25", 0, 16, 0, NULL,
     "least footprint variance, pixel^2 (0: no EWA antialiasing)",
     VV_OPTION_BIND(sp_state, ewa_var, DOUBLE)},
    {"classification", VV_OPTION_ENUM, "post", 0, 0, 0, sp_classification,
     "post: classify sheet samples; pre: classify and shade voxels, splat colours (faster, "
     "blurrier)",
     VV_OPTION_BIND(sp_state, pre, INT)},
    {"sheet_spacing", VV_OPTION_REAL, "0", 0, 8, 0, NULL,
     "sheet spacing in ray-caster steps, 0 or in [0.25, 8] (0: 1, 1.5, 2 at quality 2, 1, 0)",
     VV_OPTION_BIND_HOOK(sp_state, rate, DOUBLE, sp_spacing_check)},
    {"early_termination", VV_OPTION_REAL, "0.99", 0, 1, VV_OPTION_MIN_OPEN, NULL,
     "opacity at which a pixel is finished", VV_OPTION_BIND(sp_state, early_termination, DOUBLE)},
    {"empty_space_skipping", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "list only voxels that can be visible (0 lists every voxel; same image)",
     VV_OPTION_BIND(sp_state, skipping, INT)},
    {"occlusion_culling", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "skip footprints on finished pixels (0 splats every footprint; same image)",
     VV_OPTION_BIND(sp_state, occlusion, INT)},
    {"gradient_budget_mb", VV_OPTION_REAL, "auto", 0, INFINITY, 0, sp_auto,
     "MiB allowed for cached gradients (auto: a quarter of RAM, at most 8192)",
     VV_OPTION_BIND_FULL(sp_state, vc.gradient_budget, UINT64, 1048576.0, NULL, sp_budget_changed)},
    {"sheets", VV_OPTION_ENUM, "image", 0, 0, 0, sp_sheets,
     "image-aligned sheets; axis: Westover's axis-aligned sheets (for the popping test)",
     VV_OPTION_BIND(sp_state, axis, INT)},
};

const vv_renderer_ops vv_splat_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "splat",
            .description = "splatting (object order): Gaussian footprints, image-aligned "
                           "sheets, EWA; composite, mip, minip, xray",
            .draws = VV_DRAWS(VV_OBJECT_VOLUME),
            .modes = VV_MODES_ALL & ~VV_MODE_BIT(VV_MODE_ISO),
            .caps = VV_RENDERER_QUALITY,
            .quality = "sheets 1, 1.5, 2 ray-caster steps apart at quality 2, 1, 0 (unless "
                       "sheet_spacing is set); quality 1 and 0 also shrink the kernel",
            .options = sp_options,
            .n_options = VV_OPTIONS_COUNT(sp_options),
        },
    .state_size = sizeof(sp_state),
    .init = sp_init,
    .release = sp_release,
    .render = sp_render,
    .render_region = NULL,
};
