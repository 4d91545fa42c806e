/*
 * Volumetric ray tracing (Sobierajski and Kaufman, "Volumetric Ray
 * Tracing", Symposium on Volume Visualization 1994; the VolVis paper,
 * section 5): classical ray tracing of scenes that mix volumes and
 * geometric objects. The intensity arriving along a ray is
 *
 *     I(x, w) = I_v(x, x') + tau(x, x') * I_s(x', w)
 *
 * with x' the first surface hit (a geometric primitive or the isosurface of
 * a volume in iso mode), I_s its shading (Phong with shadow rays, plus
 * reflected and transmitted rays to a depth limit), I_v the volume samples
 * composited front to back (each shaded with Phong and shadow rays) and tau
 * what those volumes let through. Volumes in mip, minip or xray mode are
 * projected over the part of the ray in front of the surface and shown over
 * it, as the ray caster shows them over the background.
 *
 * Volumes follow the conventions of the ray caster (docs/rendering.md) so
 * that with every global effect off both give the same image: samples at
 * t = k * dt from the ray origin, the transfer function in a table with
 * opacity corrected for the step, Phong with the reflection vector, two
 * sided, the specular term weighted by the sample opacity, and the same cut
 * planes. Subvolumes of 4^3 cells with min/max values (vv_minmax_grid, the
 * PARC grid) tell every ray, primary or secondary, where a volume can
 * contribute under its transfer function or isovalue: samples start and
 * stop only there.
 *
 * Shadow rays from surfaces are traced exactly: transparent geometry
 * multiplies by its transparency, composite volumes by exp(-sum sigma h)
 * with sigma the extinction of the transfer function opacity, iso volumes
 * block where the ray meets the surface, projection volumes by one minus the
 * opacity of their projected value. A volume sample takes its shadow from a
 * lazily filled grid of shadow rays (one grid point every 4 voxels, each ray
 * starting 6 voxels towards the light so that a surface does not shadow
 * itself), interpolated trilinearly and kept between frames while what
 * casts shadows stays the same (rt_cache.c); option shadow_grid=0 traces
 * one exact shadow ray per sample instead. docs/rendering.md describes the
 * method.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/classify.h"
#include "render/frame.h"
#include "render/kernels_avx2.h"
#include "render/project.h"
#include "render/ray.h"
#include "render/raytrace/rt_internal.h"
#include "render/registry.h"
#include "render/sample.h"
#include "render/shade.h"
#include "render/tf_tables.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"

/* ---------------------------------------------------------------------- */
/* Frame set-up                                                             */

static vv_status
prepare_volume(rt_frame *fr, rt_vobj *ro, const vv_object *obj) {
    const vv_world *w = fr->w;
    memset(ro, 0, sizeof *ro);
    ro->obj = obj;
    ro->mode = obj->mode;
    ro->group = -1;
    ro->lead = ro;
    vv_status s = vv_vcache_get(&fr->st->vc, obj->volume, &ro->c);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    if (ro->mode == VV_MODE_COMPOSITE || ro->mode == VV_MODE_ISO)
        vv_vcache_need_normals(&fr->st->vc, ro->c);
    s = vv_vobject_prepare(obj, w, fr->ambient, fr->vlights, fr->n_lights, ro->w2i, ro->i2w,
                           ro->dims, ro->planes, &ro->n_planes, &ro->sh);
    if (s != VV_OK)
        return s;
    ro->vox = INFINITY;
    for (int a = 0; a < 3; a++) {
        const double l = sqrt(ro->i2w[0][a] * ro->i2w[0][a] + ro->i2w[1][a] * ro->i2w[1][a] +
                              ro->i2w[2][a] * ro->i2w[2][a]);
        if (l > 0 && l < ro->vox)
            ro->vox = l;
    }
    if (!(ro->vox < INFINITY))
        return vv_error_set(VV_ERR_INVALID, "object '%s': zero voxel spacing", obj->name);
    ro->iso = (float)(obj->isovalue - ro->c->qoff); /* stored units */
    ro->bx = ro->c->bx;
    ro->by = ro->c->by;
    ro->bz = ro->c->bz;
    return VV_OK;
}

/* The TF table (opacity corrected for dt, colour premultiplied), the
 * extinction table and the PARC flags and distances (shared with the ray
 * caster, src/render/classify.h), and the shadow grids. */
static vv_status
build_tables(rt_frame *fr, rt_vobj *ro) {
    const vv_object *obj = ro->obj;
    vv_status s =
        vv_vtables_get(&fr->st->vc, ro->c, obj, ro->mode, fr->dt, ro->iso, fr->st->parc,
                       ro->mode == VV_MODE_COMPOSITE ? VV_VT_EXT : 0, &ro->tab, &ro->owns_tables);
    if (s != VV_OK)
        return s;
    ro->lut = ro->tab.lut;
    ro->ext = ro->tab.ext;
    ro->bvis = ro->tab.bvis;
    ro->bdist = ro->tab.bdist;
    ro->extras = vv_vextra_prepare(&ro->x, obj, ro->mode, &ro->tab);
    ro->textured = ro->mode == VV_MODE_ISO && obj->texture.image != NULL;
    /* (a channel's samples use its leader's grids: ro->lead) */
    if (fr->shadows && obj->receives_shadows && obj->shading && ro->mode == VV_MODE_COMPOSITE &&
        fr->st->shadow_grid && !ro->context && ro->lead == ro) {
        /* its shadow grids: once every object is ready (shadow_grids) */
        for (int a = 0; a < 3; a++) {
            ro->gdim[a] = (ro->dims[a] - 1 + RT_SGRID - 1) / RT_SGRID + 1;
            ro->gdim[a] = ro->gdim[a] < 2 ? 2 : ro->gdim[a];
        }
    }
    return VV_OK;
}

/* The shadow grids of a volume whose samples receive shadows, one per
 * light: lazily filled, or for directional lights swept (shadow_grid=2);
 * from the renderer state when an earlier frame had the same content
 * (rt_cache.c), else new and kept there. */
static vv_status
shadow_grids(rt_frame *fr, rt_vobj *ro, int nt) {
    const size_t ng = (size_t)ro->gdim[0] * (size_t)ro->gdim[1] * (size_t)ro->gdim[2];
    for (int l = 0; l < fr->n_lights; l++) {
        const int swept = !fr->lights[l].point && fr->st->shadow_grid == 2;
        rt_sgkey key;
        void *g = rt_sgrid_find(fr, ro, l, swept, &key);
        if (swept) {
            ro->sweep[l] = g;
            vv_status s = rt_sweep_light(fr, ro, l, nt); /* sweeps only when not kept */
            if (s == VV_OK && !g && ro->sweep[l] && !rt_sgrid_keep(fr, &key, ro->sweep[l]))
                ro->sgrid_owned |= 1u << l;
            rt_sgkey_free(&key);
            if (s != VV_OK)
                return s;
            continue;
        }
        if (!g) {
            g = calloc(ng, sizeof *ro->sgrid[l]);
            if (!g) {
                rt_sgkey_free(&key);
                return vv_error_set(VV_ERR_NOMEM, "out of memory for a shadow grid");
            }
            if (!rt_sgrid_keep(fr, &key, g))
                ro->sgrid_owned |= 1u << l;
        }
        rt_sgkey_free(&key);
        ro->sgrid[l] = g;
    }
    return VV_OK;
}

static vv_status
prepare_geometry(rt_frame *fr, rt_gobj *g, const vv_object *obj) {
    memset(g, 0, sizeof *g);
    g->obj = obj;
    g->type = obj->type;
    vv_mat4 o2w = vv_object_matrix(obj);
    int ok = 0;
    vv_mat4 w2o = vv_mat4_inverse(o2w, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            g->w2o[r][c] = w2o.m[r][c];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            g->nrm[r][c] = w2o.m[c][r];
    const vv_material *m = &obj->material;
    g->col[0] = (float)m->color.x;
    g->col[1] = (float)m->color.y;
    g->col[2] = (float)m->color.z;
    g->kr = obj->reflects ? (float)m->reflectance : 0.0f;
    g->kt = (float)m->transparency;
    g->ior = m->ior;
    const vv_geometry *ge = &obj->geometry;
    vv_status s = vv_geom_object_type(obj, &g->geom);
    if (s != VV_OK)
        return s;
    if (g->geom->prepare && (s = g->geom->prepare(ge, &g->prep)) != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    g->closed = g->geom->solid(ge);
    if (obj->type == VV_OBJECT_PLANE) {
        /* traced in world space: its world point and normal (M^-T n) */
        g->wplane.point = vv_mat4_mul_point(o2w, ge->point);
        g->wplane.normal = v3(
            g->nrm[0][0] * ge->normal.x + g->nrm[0][1] * ge->normal.y + g->nrm[0][2] * ge->normal.z,
            g->nrm[1][0] * ge->normal.x + g->nrm[1][1] * ge->normal.y + g->nrm[1][2] * ge->normal.z,
            g->nrm[2][0] * ge->normal.x + g->nrm[2][1] * ge->normal.y +
                g->nrm[2][2] * ge->normal.z);
    }
    vv_box ob;
    if ((obj->type == VV_OBJECT_POLYGON || obj->type == VV_OBJECT_BOX) &&
        g->geom->bounds(ge, &ob)) {
        /* world-space bounding sphere of the object-space bounding box */
        const vv_vec3 lo = ob.min, hi = ob.max;
        g->bc = vv_mat4_mul_point(o2w, v3scale(v3add(lo, hi), 0.5));
        double r = 0;
        for (int k = 0; k < 8; k++) {
            const vv_vec3 q = v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
            const double d = v3len(v3sub(vv_mat4_mul_point(o2w, q), g->bc));
            r = d > r ? d : r;
        }
        r = r * (1 + 1e-6) + 1e-9; /* rounding margin: never reject a hit */
        g->br2 = r * r;
        g->bounded =
            isfinite(g->br2) && isfinite(g->bc.x) && isfinite(g->bc.y) && isfinite(g->bc.z);
    }
    (void)fr;
    return VV_OK;
}

static void
prepare_lights(rt_frame *fr, const vv_world *w, const vv_view *view) {
    vv_vec3 fwd = v3norm(v3sub(view->at, view->eye));
    fr->n_lights = vv_vlights_prepare(fr->vlights, w, view);
    for (int i = 0; i < fr->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        rt_light *o = &fr->lights[i];
        o->point = l->type == VV_LIGHT_POINT && !l->headlight;
        vv_vec3 d = l->headlight ? fwd : v3norm(l->direction);
        o->dir[0] = -d.x;
        o->dir[1] = -d.y;
        o->dir[2] = -d.z;
        o->pos[0] = l->position.x;
        o->pos[1] = l->position.y;
        o->pos[2] = l->position.z;
        o->col[0] = (float)(l->color.x * l->intensity);
        o->col[1] = (float)(l->color.y * l->intensity);
        o->col[2] = (float)(l->color.z * l->intensity);
    }
}

static void
frame_release(rt_frame *fr) {
    for (int i = 0; i < fr->n_vobj; i++) {
        if (fr->vobjs[i].owns_tables)
            vv_vtables_free(&fr->vobjs[i].tab);
        for (int l = 0; l < VV_MAX_LIGHTS; l++) {
            if (fr->vobjs[i].sgrid_owned & (1u << l)) {
                free(fr->vobjs[i].sgrid[l]);
                free(fr->vobjs[i].sweep[l]);
            }
            if (fr->vobjs[i].lvol_owned & (1u << l))
                free(fr->vobjs[i].lvol[l]);
        }
    }
    for (int i = 0; i < fr->n_gobj; i++)
        if (fr->gobjs[i].prep)
            fr->gobjs[i].geom->release(fr->gobjs[i].prep);
    free(fr->vobjs);
    free(fr->gobjs);
    free(fr->chobjs);
    free(fr->skey);
}

/* ---------------------------------------------------------------------- */
/* Pixels                                                                    */

static inline uint64_t
mix64(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

static void
trace_primary(const rt_frame *fr, double px, double py, float rgba[4], float *depth, float *key) {
    /* the ray caster's arithmetic, so that without effects the images agree */
    const vv_ray wr = vv_camera_ray(&fr->cam, px, py);
    rt_trace_key(fr, &wr, 0, 1, 1.0f, rgba, &rgba[3], depth, key);
}

/* Supersample s of n x n of pixel (x, y): its offset from the pixel
 * centre, regular or jittered (seeded by the pixel, so images do not
 * depend on threads). */
static void
ss_offset(const rt_state *st, int x, int y, int s, int n, double *ox, double *oy) {
    *ox = (s % n + 0.5) / n - 0.5;
    *oy = (s / n + 0.5) / n - 0.5;
    if (st->jitter) {
        uint64_t h = mix64(st->seed ^ mix64(((uint64_t)(uint32_t)y << 32) ^ (uint64_t)(uint32_t)x) ^
                           (uint64_t)s * 0x632BE59BD9B4E019ull);
        *ox = (s % n + (double)(h >> 40) / 16777216.0) / n - 0.5;
        *oy = (s / n + (double)(h & 0xFFFFFF) / 16777216.0) / n - 0.5;
    }
}

/* n x n supersamples of pixel (x, y) (ss_offset), their mean colour and
 * nearest depth. */
static void
supersample(const rt_frame *fr, int x, int y, int n, float rgba[4], float *depth) {
    float acc[4] = {0, 0, 0, 0};
    float dmin = INFINITY;
    for (int s = 0; s < n * n; s++) {
        double ox, oy;
        ss_offset(fr->st, x, y, s, n, &ox, &oy);
        float c[4], d;
        trace_primary(fr, x + ox, y + oy, c, &d, NULL);
        for (int ch = 0; ch < 4; ch++)
            acc[ch] += c[ch];
        dmin = d < dmin ? d : dmin;
    }
    for (int ch = 0; ch < 4; ch++)
        rgba[ch] = acc[ch] / (float)(n * n);
    *depth = dmin;
}

/* ---------------------------------------------------------------------- */
/* The renderer                                                             */

/* Pass 1: one ray per pixel (or the full supersampling when not adaptive);
 * region renders: one ray per pixel and the projection key. */
static vv_status
pass_first(void *user, const vv_frame_tile *t) {
    const rt_frame *fr = user;
    const int W = fr->out->width;
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++) {
            const size_t at = (size_t)y * (size_t)W + (size_t)x;
            float *pix = fr->out->rgba + 4 * at;
            float *dp = fr->out->depth + at;
            if (fr->xsum) { /* a region in xray mode: the ray caster's sums, bit for bit */
                const rt_vobj *ob = fr->xsum;
                const vv_ray wr = vv_camera_ray(&fr->cam, x, y);
                vv_vray_xray_region_pixel(ob->c, ob->w2i, ob->dims, ob->planes, ob->n_planes,
                                          ob->region, fr->dt, ob->inv_form, &wr, fr->avx2, pix, dp,
                                          fr->key + at);
            } else if (fr->nss > 1 && !fr->adaptive)
                supersample(fr, x, y, fr->nss, pix, dp);
            else
                trace_primary(fr, x, y, pix, dp, fr->key ? fr->key + at : NULL);
        }
    return VV_OK;
}

/* A region render on its rays' points only (vv_render_region.rays): each
 * into its entry of the one-row image, as pass_first fills a pixel. */
static void
pass_rays(const rt_frame *fr, int nt) {
    const vv_render_region *rg = fr->region;
    const vv_region_rays *rr = rg->rays;
    const long n = (long)rr->per_pixel * (long)rr->n_pixels;
    const size_t W = (size_t)fr->view->width;
    const int rect = rg->x1 > rg->x0;
#pragma omp parallel for schedule(dynamic, 64) num_threads(nt)
    for (long i = 0; i < n; i++) {
        const size_t px = rr->pixel[i / rr->per_pixel];
        const int x = (int)(px % W), y = (int)(px / W);
        if (rect && (x < rg->x0 || x >= rg->x1 || y < rg->y0 || y >= rg->y1))
            continue;
        const double sx = rr->xy[2 * i], sy = rr->xy[2 * i + 1];
        float *pix = fr->out->rgba + 4 * i;
        float *dp = fr->out->depth + i;
        if (fr->xsum) {
            const rt_vobj *ob = fr->xsum;
            const vv_ray wr = vv_camera_ray(&fr->cam, sx, sy);
            vv_vray_xray_region_pixel(ob->c, ob->w2i, ob->dims, ob->planes, ob->n_planes,
                                      ob->region, fr->dt, ob->inv_form, &wr, fr->avx2, pix, dp,
                                      fr->key + i);
        } else {
            trace_primary(fr, sx, sy, pix, dp, fr->key ? fr->key + i : NULL);
        }
    }
}

/* The rays of quality 2 for a frame drawn by regions
 * (vv_region_image.supersample): the pixels pass_refine would supersample
 * in @p first (every pixel when not adaptive), each with its n x n points
 * (ss_offset) in supersample's order. */
static vv_status
rt_region_supersample(const void *ctx, const vv_image *first, vv_region_rays *rays) {
    const rt_state *st = ctx;
    memset(rays, 0, sizeof *rays);
    const int W = first->width, H = first->height, n = st->samples;
    const float thr = (float)st->threshold;
    const size_t np = (size_t)W * (size_t)H;
    unsigned char *pick = malloc(np ? np : 1);
    if (!pick)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    size_t count = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float *c = first->rgba + 4 * ((size_t)y * (size_t)W + (size_t)x);
            int differs = !st->adaptive;
            const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
            for (int k = 0; k < 4 && !differs; k++) {
                if (nb[k][0] < 0 || nb[k][0] >= W || nb[k][1] < 0 || nb[k][1] >= H)
                    continue;
                const float *q =
                    first->rgba + 4 * ((size_t)nb[k][1] * (size_t)W + (size_t)nb[k][0]);
                for (int ch = 0; ch < 4; ch++)
                    differs |= fabsf(q[ch] - c[ch]) > thr;
            }
            pick[(size_t)y * (size_t)W + (size_t)x] = (unsigned char)differs;
            count += (size_t)differs;
        }
    const size_t per = (size_t)n * (size_t)n;
    if (count == 0 || n < 2) {
        free(pick);
        return VV_OK;
    }
    if (count * per > (size_t)INT32_MAX) {
        free(pick);
        return vv_error_set(VV_ERR_LIMIT, "%zu rays to trace again; at most %d", count * per,
                            (int)INT32_MAX);
    }
    rays->pixel = malloc(count * sizeof *rays->pixel);
    rays->xy = malloc(2 * count * per * sizeof *rays->xy);
    if (!rays->pixel || !rays->xy) {
        free(pick);
        vv_region_rays_free(rays);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    rays->per_pixel = (int)per;
    size_t k = 0;
    for (size_t i = 0; i < np; i++) {
        if (!pick[i])
            continue;
        const int x = (int)(i % (size_t)W), y = (int)(i / (size_t)W);
        rays->pixel[k] = i;
        for (int s = 0; s < (int)per; s++) {
            double ox, oy;
            ss_offset(st, x, y, s, n, &ox, &oy);
            rays->xy[2 * (k * per + (size_t)s)] = x + ox;
            rays->xy[2 * (k * per + (size_t)s) + 1] = y + oy;
        }
        k++;
    }
    rays->n_pixels = count;
    free(pick);
    return VV_OK;
}

/* Adaptive image-space refinement at quality 0 and 1 (vv_frame_refine_tile):
 * one pixel, its centre ray (supersampled at quality 2 with refinement on). */
static void
refine_pixel(void *user, int x, int y, float px[5], void *work) {
    const rt_frame *fr = user;
    (void)work;
    if (fr->nss > 1)
        supersample(fr, x, y, fr->nss, px, &px[4]);
    else
        trace_primary(fr, x, y, px, &px[4], NULL);
}

static vv_status
pass_refined(void *user, const vv_frame_tile *t) {
    const rt_frame *fr = user;
    vv_frame_refine_tile(t, fr->out->width, fr->out->height, fr->tolerance, refine_pixel,
                         (void *)fr, NULL, fr->out->rgba, fr->out->depth);
    return VV_OK;
}

/* Pass 2 (adaptive): supersample the pixels that differ from a neighbour
 * in the image of pass 1 by more than the threshold. */
static vv_status
pass_refine(void *user, const vv_frame_tile *t) {
    const rt_frame *fr = user;
    const int W = fr->out->width, H = fr->out->height;
    const float thr = (float)fr->st->threshold;
    const float *first = fr->first;
    for (int y = t->y0; y < t->y1; y++)
        for (int x = t->x0; x < t->x1; x++) {
            const float *c = first + 4 * ((size_t)y * (size_t)W + (size_t)x);
            int differs = 0;
            const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
            for (int k = 0; k < 4 && !differs; k++) {
                if (nb[k][0] < 0 || nb[k][0] >= W || nb[k][1] < 0 || nb[k][1] >= H)
                    continue;
                const float *q = first + 4 * ((size_t)nb[k][1] * (size_t)W + (size_t)nb[k][0]);
                for (int ch = 0; ch < 4; ch++)
                    differs |= fabsf(q[ch] - c[ch]) > thr;
            }
            if (differs)
                supersample(fr, x, y, fr->nss, fr->out->rgba + 4 * ((size_t)y * (size_t)W + x),
                            fr->out->depth + (size_t)y * (size_t)W + (size_t)x);
        }
    return VV_OK;
}

/* Counts the volumes (a multi-channel object's visible channels each
 * count) and geometric objects a render prepares, and the channels among
 * the volumes; errors beyond the limits. */
static vv_status
count_objects(const vv_world *w, int *nv, int *ng, int *nch) {
    *nv = *ng = *nch = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o || !o->visible || o->type == VV_OBJECT_GRID) /* grids: the irregular renderer */
            continue;
        if (o->type == VV_OBJECT_VOLUME && o->n_channels > 1) {
            *nv += vv_vchannels_shown(o);
            *nch += vv_vchannels_shown(o);
        } else if (o->type == VV_OBJECT_VOLUME) {
            *nv += o->volume != NULL;
        } else {
            (*ng)++;
        }
    }
    if (*nv > RT_MAX_OBJ || *ng > RT_MAX_OBJ * 16)
        return vv_error_set(VV_ERR_LIMIT, "%d volume and %d geometric objects; at most %d and %d",
                            *nv, *ng, RT_MAX_OBJ, RT_MAX_OBJ * 16);
    return VV_OK;
}

/* The visible channels of multi-channel object @p obj, each prepared as a
 * volume of its own (the ray caster's rules: the object with the channel's
 * volume and transfer function, one channel, no 2-D TF or texture;
 * composite mode under the composite and additive rules, MIP under the
 * maximum rule), in consecutive vobjs with the first as their leader.
 * @p region: the region part's channels (their volumes its voxels), each
 * sampling the region's samples as a one-channel part does. */
static vv_status
prepare_channels(rt_frame *fr, const vv_object *obj, int context, const vv_render_region *region) {
    const int first = fr->n_vobj;
    for (int c = 0; c < obj->n_channels; c++) {
        const vv_channel *cc = &obj->channels[c];
        if (!cc->visible || !cc->volume)
            continue;
        vv_object *o = &fr->chobjs[fr->n_chobj++];
        vv_vchannel_object(obj, cc, o);
        rt_vobj *ro = &fr->vobjs[fr->n_vobj++];
        vv_status s = prepare_volume(fr, ro, o);
        if (s != VV_OK)
            return vv_error_prefix(s, "object '%s', channel %d ('%s')", obj->name, c, cc->name);
        ro->context = context;
        ro->group = first;
        ro->blend = obj->blend;
        ro->lead = &fr->vobjs[first];
        if (region) {
            ro->region = region;
            for (int a = 0; a < 3; a++)
                ro->dims[a] = region->dims[a] > 1 ? region->dims[a] : 2;
        }
    }
    fr->vobjs[first].gn = fr->n_vobj - first;
    return VV_OK;
}

/* Prepares every object of the frame: geometry, volumes, tables, light
 * volumes and swept shadow grids. With @p region, the region's object is
 * traced twice (rt_vobj.region, rt_vobj.context) and no other object is
 * visible. */
static vv_status
prepare_frame(rt_frame *fr, const vv_world *w, const vv_view *view, const vv_render_region *region,
              const vv_object *part, int nt) {
    rt_state *st = fr->st;
    int nv = 0, ng = 0, nch = 0;
    vv_status s = count_objects(w, &nv, &ng, &nch);
    if (s != VV_OK)
        return s;
    nv += region == NULL ? 0 : part->n_channels > 1 ? vv_vchannels_shown(part) : 1;
    nch += region && part->n_channels > 1 ? vv_vchannels_shown(part) : 0;
    fr->vobjs = calloc(nv ? (size_t)nv : 1, sizeof *fr->vobjs);
    fr->gobjs = calloc(ng ? (size_t)ng : 1, sizeof *fr->gobjs);
    fr->chobjs = calloc(nch ? (size_t)nch : 1, sizeof *fr->chobjs);
    if (!fr->vobjs || !fr->gobjs || !fr->chobjs)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    double dt = INFINITY;
    vv_box bounds = vv_world_bounds(w);
    if (region && part->n_channels > 1) {
        /* the region part's channels first (the composite rule) */
        s = prepare_channels(fr, part, 0, region);
        dt = vv_vobject_step(part);
    } else if (region) {
        /* the region part first: the samples of the whole volume that the
         * region owns, from its voxels */
        rt_vobj *ro = &fr->vobjs[fr->n_vobj++];
        s = prepare_volume(fr, ro, part);
        ro->region = region;
        for (int a = 0; a < 3; a++)
            ro->dims[a] = region->dims[a] > 1 ? region->dims[a] : 2;
        dt = vv_vobject_step(part);
    }
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        const vv_object *o = w->objects[i];
        if (!o || !o->visible || o->type == VV_OBJECT_GRID)
            continue;
        if (o->type == VV_OBJECT_VOLUME) {
            if (!o->volume)
                continue;
            if (!(o->step > 0)) {
                s = vv_error_set(VV_ERR_INVALID, "object '%s': step must be > 0", o->name);
                break;
            }
            if (o->n_channels > 1 && !vv_vchannels_shown(o))
                continue;
            if (o->n_channels > 1) {
                s = prepare_channels(fr, o, region != NULL, NULL);
            } else {
                rt_vobj *ro = &fr->vobjs[fr->n_vobj++];
                s = prepare_volume(fr, ro, o);
                ro->context = region != NULL;
            }
            if (!region) {
                double sd = vv_vobject_step(o);
                dt = sd < dt ? sd : dt;
            }
        } else {
            s = prepare_geometry(fr, &fr->gobjs[fr->n_gobj++], o);
        }
    }
    fr->dt = (float)(dt < INFINITY ? dt : 1.0);
    double size = v3len(v3sub(bounds.max, bounds.min));
    size += v3len(v3sub(view->eye, v3scale(v3add(bounds.max, bounds.min), 0.5)));
    fr->scene_size = size > 0 && size < INFINITY ? size : 1.0;
    for (int i = 0; i < fr->n_vobj && s == VV_OK; i++) {
        rt_vobj *ro = &fr->vobjs[i];
        s = build_tables(fr, ro);
        if (s == VV_OK && ro->mode == VV_MODE_ATTENUATED_MIP)
            s = vv_vatten_prepare(&ro->att, ro->obj, ro->c, fr->dt); /* the ray caster's */
        ro->region_dt = fr->dt;
        ro->inv_form = ro->mode == VV_MODE_COMPOSITE && !ro->extras; /* march_one */
    }
    /* light volumes of the lights through composite volumes that cast
     * shadows (a region's context: through its whole volume where it can,
     * rt_light.c), then the shadow grids, now that every object is
     * ready */
    if (s == VV_OK)
        rt_context_whole(fr, region);
    for (int i = 0; i < fr->n_vobj && s == VV_OK && fr->shadows && st->light_volumes; i++) {
        rt_vobj *ro = &fr->vobjs[i];
        if (ro->mode != VV_MODE_COMPOSITE || !ro->obj->casts_shadows || ro->region)
            continue;
        for (int l = 0; l < fr->n_lights && s == VV_OK; l++)
            s = rt_build_light_volume(fr, ro, l, nt);
    }
    for (int i = 0; i < fr->n_vobj && s == VV_OK; i++)
        if (fr->vobjs[i].gdim[0])
            s = shadow_grids(fr, &fr->vobjs[i], nt);
    return s;
}

/* A whole render, or with @p region only its samples, one ray a pixel,
 * into @p out (and the projection keys into @p key). */
static vv_status
render_frame(rt_state *st, const vv_world *w, const vv_view *view, const vv_render_options *opt,
             const vv_render_region *region, const vv_object *part, vv_image *out, float *key) {
    rt_frame fr;
    memset(&fr, 0, sizeof fr);
    fr.st = st;
    fr.w = w;
    st->vc.frame++;
    fr.avx2 = st->simd && vv_vc_have_avx2();
    st->frame++;
    fr.et = (float)st->early_termination;
    vv_frame_colours(w, region != NULL, fr.ambient, fr.bg);
    /* quality: 0 preview (no secondary rays, one sample), 1 one sample
     * with shadows and reflections, 2 final (supersampling as set) */
    fr.shadows = opt->quality >= 1 && st->shadows;
    fr.max_depth = opt->quality >= 1 ? st->max_depth : 0;
    fr.nss = opt->quality >= 2 && !region ? st->samples : 1;
    /* adaptive image-space refinement: whole renders only (a region's
     * pixels are composited with other ranks' by depth and key) */
    fr.refine = vv_frame_refine_for(&st->refine, opt->quality, region != NULL, 0, &fr.tolerance);
    fr.adaptive = fr.nss > 1 && st->adaptive && !fr.refine;
    fr.view = view;
    fr.out = out;
    fr.key = key;
    fr.region = region;
    prepare_lights(&fr, w, view);
    vv_camera_rays_init(&fr.cam, view);
    const int nt = opt->threads > 0 ? opt->threads : vv_threads_get();
    vv_status s = prepare_frame(&fr, w, view, region, part, nt);
    /* a region in xray mode: the sums of its samples, classified by its
     * table when the regions are combined (rt_render_region) */
    for (int i = 0;
         s == VV_OK && region && key && part && part->mode == VV_MODE_XRAY && i < fr.n_vobj; i++) {
        const rt_vobj *ob = &fr.vobjs[i];
        if (!ob->region || ob->context)
            continue;
        if (ob->group >= 0) {
            s = vv_error_set(VV_ERR_UNSUPPORTED,
                             "object '%s': xray regions of a multi-channel object are not "
                             "rendered",
                             part->name);
            break;
        }
        fr.xsum = ob;
        st->xray.lut_lo = ob->tab.lut_lo;
        st->xray.lut_scale = ob->tab.lut_scale;
        memcpy(st->xray.lut, ob->lut, sizeof st->xray.lut);
    }
    if (s == VV_OK && region && key && part && part->mode == VV_MODE_XRAY && !fr.xsum)
        s = vv_error_set(VV_ERR_INVALID, "object '%s': no region part to sum", part->name);
    if (s != VV_OK) {
        frame_release(&fr);
        return s;
    }
    if (region && region->rays) { /* the points of quality 2 only */
        pass_rays(&fr, nt);
        frame_release(&fr);
        return VV_OK;
    }
    vv_frame_job job;
    vv_frame_job_init(&job, view->width, view->height, fr.refine ? pass_refined : pass_first, &fr);
    if (fr.refine)
        job.scratch_bytes = vv_frame_refine_scratch_bytes();
    vv_frame_job_region(&job, region);
    job.progress_to = fr.adaptive ? 0.5 : 1.0;
    s = vv_frame_run(&job, opt);
    if (s == VV_OK && fr.adaptive) {
        const size_t np = (size_t)view->width * (size_t)view->height;
        float *first = malloc(np * 4 * sizeof(float));
        if (!first) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        } else {
            memcpy(first, out->rgba, np * 4 * sizeof(float));
            fr.first = first;
            job.fn = pass_refine;
            job.progress_from = 0.5;
            job.progress_to = 1.0;
            s = vv_frame_run(&job, opt);
            free(first);
        }
    }
    frame_release(&fr);
    if (s != VV_OK)
        return s;
    /* drop cached volumes the World no longer shows */
    vv_vcache_set_prune(&st->vc, w);
    /* light volumes and shadow grids a frame with shadows did not use: gone
     * (they can be large). A frame without shadows (a preview between the
     * frames of a drag) leaves them, and so does a region render for the
     * shadow grids (it keeps none of its own). */
    if (fr.shadows)
        for (int i = 0; i < RT_LV_CACHE; i++)
            if (st->lv[i].vol && st->lv[i].used != st->frame)
                rt_lv_release(&st->lv[i]);
    if (fr.shadows && !region)
        for (int i = 0; i < RT_SG_CACHE; i++)
            if (st->sg[i].grid && st->sg[i].used != st->frame)
                rt_sg_release(&st->sg[i]);
    return VV_OK;
}

static vv_status
rt_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    return render_frame(state, w, view, opt, NULL, NULL, out, NULL);
}

/* The region contract: the region's object traced twice, its region part
 * sampling the region's voxels on primary rays (one a pixel: the adaptive
 * supersampling of quality 2 decides from finished pixels, which a region
 * does not have) and its context, the World's own volume of the object,
 * casting the shadows. */
static vv_status
rt_render_region(void *state, const vv_world *w, const vv_view *view,
                 const vv_render_region *region, const vv_render_options *opt,
                 vv_region_image *out) {
    vv_object part;
    vv_channel *chan = NULL;
    vv_status s = vv_render_region_part(w, region, &out->op, &part, &chan);
    if (s != VV_OK)
        return s;
    if (part.n_channels > 1) { /* the composite rule: over, as a composite part */
        rt_state *st = state;
        s = render_frame(st, w, view, opt, region, &part, out->image, NULL);
        free(chan);
        out->classify = NULL;
        out->classify_ctx = NULL;
        const int ss = opt->quality >= 2 && st->samples > 1 && !region->rays &&
                       vv_frame_refine_for(&st->refine, opt->quality, 0, 0, &(float){0}) == 0;
        out->supersample = ss ? rt_region_supersample : NULL;
        out->supersample_ctx = ss ? st : NULL;
        return s;
    }
    /* an isosurface shadowed by a coarse proxy's surface shows the proxy's
     * steps as shadow bands: iso regions only with the whole volume as the
     * context (distributed rendering of a volume every rank holds) */
    const vv_volume *ctx = w->objects[region->object]->volume;
    if (part.mode == VV_MODE_ATTENUATED_MIP)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': attenuated-mip regions (out of core, MPI) are drawn by "
                            "raycast and gpu, not raytrace",
                            part.name);
    if (part.mode == VV_MODE_ISO &&
        (ctx->dims[0] != region->dims[0] || ctx->dims[1] != region->dims[1] ||
         ctx->dims[2] != region->dims[2]))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s': iso regions need the whole volume for their "
                            "shadows, not a coarse proxy; draw it out of core with raycast",
                            part.name);
    rt_state *st = state;
    s = render_frame(st, w, view, opt, region, &part, out->image,
                     part.mode == VV_MODE_COMPOSITE ? NULL : out->key);
    /* xray: the regions' sums add up, their mean classified once */
    out->classify = out->op == VV_REGION_SUM ? vv_xray_table_classify : NULL;
    out->classify_ctx = out->op == VV_REGION_SUM ? &st->xray : NULL;
    /* quality 2: the whole render's supersampling, ray by ray in every region */
    const int ss = opt->quality >= 2 && st->samples > 1 && !region->rays &&
                   vv_frame_refine_for(&st->refine, opt->quality, 0, 0, &(float){0}) == 0;
    out->supersample = ss ? rt_region_supersample : NULL;
    out->supersample_ctx = ss ? st : NULL;
    return s;
}

static vv_status
rt_init(void *state) {
    rt_state *st = state;
    vv_vcache_set_init(&st->vc);
    return VV_OK;
}

static void
rt_release(void *state) {
    rt_state *st = state;
    vv_vcache_set_clear(&st->vc);
    for (int i = 0; i < RT_LV_CACHE; i++)
        rt_lv_release(&st->lv[i]);
    for (int i = 0; i < RT_SG_CACHE; i++)
        rt_sg_release(&st->sg[i]);
}

/* The ray tracer's options, each bound to its field of rt_state. */
static const vv_option_spec rt_options[] = {
    {"shadows", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "shadow rays (0: every light reaches every point)", VV_OPTION_BIND(rt_state, shadows, INT)},
    {"max_depth", VV_OPTION_INT, "3", 0, 64, 0, NULL, "reflection and transmission depth",
     VV_OPTION_BIND(rt_state, max_depth, INT)},
    {"samples", VV_OPTION_INT, "2", 1, 16, 0, NULL,
     "rays per pixel side at quality 2 (2: 2 x 2 a pixel)", VV_OPTION_BIND(rt_state, samples, INT)},
    {"jitter", VV_OPTION_BOOL, "0", 0, 1, 0, NULL, "jittered supersampling",
     VV_OPTION_BIND(rt_state, jitter, INT)},
    {"seed", VV_OPTION_INT, "1", 0, 9007199254740992.0, 0, NULL,
     "seed of the jitter (a hash of it and the pixel)", VV_OPTION_BIND(rt_state, seed, UINT64)},
    {"adaptive", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "supersample only pixels that differ from a neighbour",
     VV_OPTION_BIND(rt_state, adaptive, INT)},
    {"adaptive_threshold", VV_OPTION_REAL, "0.05", 0, INFINITY, 0, NULL,
     "channel difference that triggers supersampling", VV_OPTION_BIND(rt_state, threshold, DOUBLE)},
    VV_FRAME_REFINE_OPTIONS(rt_state, refine, "at quality 0 and 1"),
    {"parc", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "leap over empty subvolumes on every ray (0 for measurements; same image)",
     VV_OPTION_BIND(rt_state, parc, INT)},
    {"shadow_grid", VV_OPTION_INT, "1", 0, 2, 0, NULL,
     "volume samples' shadows: 1 a lazily traced grid of shadow rays, 0 an exact ray per "
     "sample, 2 a swept light volume for directional lights",
     VV_OPTION_BIND(rt_state, shadow_grid, INT)},
    {"light_volumes", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "shadow rays through composite volumes from a light volume, directional and point "
     "lights (0: marched)",
     VV_OPTION_BIND(rt_state, light_volumes, INT)},
    {"early_termination", VV_OPTION_REAL, "0.99", 0, 1, VV_OPTION_MIN_OPEN, NULL,
     "accumulated opacity that ends compositing (a secondary ray of weight w: 1 - (1 - "
     "value) / w)",
     VV_OPTION_BIND(rt_state, early_termination, DOUBLE)},
    {"simd", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "AVX2 classification and eight-sample shading where the processor has it (0: the portable "
     "path)",
     VV_OPTION_BIND(rt_state, simd, INT)},
};

const vv_renderer_ops vv_raytrace_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "raytrace",
            .description = "volumetric ray tracing: volumes and geometry, shadows, mirrors, "
                           "refraction, PARC",
            .draws = VV_DRAWS(VV_OBJECT_VOLUME) | VV_DRAWS_GEOMETRY,
            .modes = VV_MODES_ALL | VV_MODE_BIT(VV_MODE_ATTENUATED_MIP),
            .caps = VV_RENDERER_REGION | VV_RENDERER_QUALITY | VV_RENDERER_GLOBAL |
                    VV_RENDERER_CHANNELS,
            .quality = "0: no shadow or secondary rays; 1: every effect; both adaptive "
                       "refinement from a lattice of every 4th pixel (option refinement); 2: "
                       "supersampled (samples, adaptive); region renders (out of core, MPI) "
                       "trace one ray a pixel",
            .options = rt_options,
            .n_options = VV_OPTIONS_COUNT(rt_options),
        },
    .state_size = sizeof(rt_state),
    .init = rt_init,
    .release = rt_release,
    .render = rt_render,
    .render_region = rt_render_region,
};
