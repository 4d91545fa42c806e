/*
 * A World with volume objects out of core (drv_render_sources,
 * src/render/drivers.h; what vv_renderer_render draws when an object holds
 * a source): each visible volume object is rendered alone into a layer of
 * its own -- from its source's bricks (drv_render_bricks), its pyramid
 * (drv_render_multires) or its in-memory volume (one region over the whole
 * volume) -- on a black background, and the layers are
 * combined per pixel as the ray caster combines objects along a ray
 * (src/render/raycast/raycast.c, cast_pixel): the composite and iso objects
 * composited front to back, the projections (MIP, MinIP, X-ray) by the
 * largest classified value behind them, the background last. The
 * composite and iso objects' boxes must not overlap: along any ray their
 * stretches are then apart, and a layer's first depth orders them exactly.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/drivers.h"
#include "volvis/render.h"
#include "volvis/sys/renderer.h"
#include "volvis/sys/source.h"

/* ---- the objects' boxes -------------------------------------------------------- */

/* The eight corners of @p obj's index box (0 .. dims - 1 of @p geo, its
 * voxels' geometry) in world space. */
static void
box_corners(const vv_object *obj, const vv_volume *geo, vv_vec3 c[8]) {
    vv_object placed = *obj; /* shallow: nothing in it is released */
    placed.volume = (vv_volume *)geo;
    const vv_mat4 m = vv_object_index_to_world(&placed);
    for (int i = 0; i < 8; i++) {
        const vv_vec3 p = {(i & 1) ? geo->dims[0] - 1 : 0, (i & 2) ? geo->dims[1] - 1 : 0,
                           (i & 4) ? geo->dims[2] - 1 : 0};
        c[i] = vv_mat4_mul_point(m, p);
    }
}

/* 1 when a plane normal to @p axis separates the corner sets (touching
 * counts as apart: the two boxes then share no inside point). */
static int
separated_along(vv_vec3 axis, const vv_vec3 a[8], const vv_vec3 b[8]) {
    const double len = vv_vec3_length(axis);
    if (!(len > 1e-12))
        return 0;
    double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
    for (int i = 0; i < 8; i++) {
        const double pa = vv_vec3_dot(a[i], axis) / len, pb = vv_vec3_dot(b[i], axis) / len;
        a0 = pa < a0 ? pa : a0;
        a1 = pa > a1 ? pa : a1;
        b0 = pb < b0 ? pb : b0;
        b1 = pb > b1 ? pb : b1;
    }
    const double tol = 1e-9 * (fabs(a0) + fabs(a1) + fabs(b0) + fabs(b1) + 1);
    return a1 <= b0 + tol || b1 <= a0 + tol;
}

/* 1 when the boxes (parallelepipeds) with corners @p a and @p b overlap:
 * no separating axis among their edge directions and the cross products
 * of pairs of them (the separating axis theorem). */
static int
boxes_overlap(const vv_vec3 a[8], const vv_vec3 b[8]) {
    vv_vec3 ea[3], eb[3];
    for (int k = 0; k < 3; k++) {
        ea[k] = vv_vec3_sub(a[1 << k], a[0]);
        eb[k] = vv_vec3_sub(b[1 << k], b[0]);
    }
    /* the faces' normals of each, then the edge pairs */
    for (int k = 0; k < 3; k++) {
        if (separated_along(vv_vec3_cross(ea[(k + 1) % 3], ea[(k + 2) % 3]), a, b) ||
            separated_along(vv_vec3_cross(eb[(k + 1) % 3], eb[(k + 2) % 3]), a, b))
            return 0;
    }
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (separated_along(vv_vec3_cross(ea[i], eb[j]), a, b))
                return 0;
    /* flat boxes (a dimension of one voxel) have no face normal there:
     * the edge axes themselves */
    for (int k = 0; k < 3; k++)
        if (separated_along(ea[k], a, b) || separated_along(eb[k], a, b))
            return 0;
    return 1;
}

/* ---- the frame ----------------------------------------------------------------- */

typedef struct src_layer {
    int object;
    const vv_brick_source *bricks;
    const vv_multires_source *multires;
    vv_brick_source bview;    /* the source's bricks (bricks points here) */
    vv_multires_source mview; /* the source's levels (multires points here) */
    vv_brick_source mem;      /* no source: the object's own volume */
    const vv_volume *geo;
    int comp; /* composite or iso: composited front to back */
    vv_image *img;
} src_layer;

/* Adds the counts of one object's multiresolution frame to the caller's. */
static void
lod_add(vv_lod *sum, const vv_lod *one) {
    for (int l = 0; l < VV_LOD_MAX_LEVELS; l++)
        sum->nodes[l] += one->nodes[l];
    sum->skipped += one->skipped;
    sum->pending += one->pending;
    sum->requested += one->requested;
    sum->stalled |= one->stalled;
}

/* Object @p L->object alone (the others hidden) into L->img, on a black
 * background (a layer), or with @p background on the World's (the one
 * object of a frame). */
static vv_status
render_layer(const drv_renderer *r, const vv_world *w, src_layer *L, const vv_view *view,
             const vv_render_options *opt, vv_lod *lod, vv_lod *sum, int background) {
    vv_object *copies = malloc(sizeof *copies * (size_t)w->n_objects);
    vv_object **ptrs = malloc(sizeof *ptrs * (size_t)w->n_objects);
    if (!copies || !ptrs) {
        free(copies);
        free(ptrs);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < w->n_objects; i++) {
        copies[i] = *w->objects[i]; /* shallow: nothing in it is released */
        copies[i].visible = i == L->object;
        ptrs[i] = &copies[i];
    }
    vv_world lw = *w;
    lw.objects = ptrs;
    if (!background)
        lw.background = (vv_vec3){0, 0, 0};
    vv_status s;
    if (L->multires) {
        vv_lod one = *lod; /* the inputs; the frame sets the counts */
        s = drv_render_multires(r, &lw, L->object, L->multires, view, opt, &one, L->img);
        lod_add(sum, &one);
    } else {
        s = drv_render_bricks(r, &lw, L->object, L->bricks ? L->bricks : &L->mem, view, opt,
                              L->img);
    }
    free(copies);
    free(ptrs);
    return s;
}

/* The layers combined into @p out as cast_pixel combines objects along a
 * ray, the background last. */
static void
combine_layers(const vv_world *w, src_layer *L, int n, vv_image *out) {
    const size_t np = (size_t)out->width * (size_t)out->height;
    const float bg[3] = {(float)w->background.x, (float)w->background.y, (float)w->background.z};
    int order[VV_SOURCES_MAX];
    for (size_t i = 0; i < np; i++) {
        /* the composite layers seen here, nearest first */
        int m = 0;
        for (int k = 0; k < n; k++) {
            if (!L[k].comp || !(L[k].img->rgba[4 * i + 3] > 0))
                continue;
            const float d = L[k].img->depth[i];
            int at = m++;
            while (at > 0 && L[order[at - 1]].img->depth[i] > d) {
                order[at] = order[at - 1];
                at--;
            }
            order[at] = k;
        }
        float C[3] = {0, 0, 0}, A = 0, depth = INFINITY;
        for (int j = 0; j < m; j++) {
            const float *p = L[order[j]].img->rgba + 4 * i;
            const float rest = 1 - A;
            for (int ch = 0; ch < 3; ch++)
                C[ch] += rest * p[ch];
            A += rest * p[3];
        }
        /* the projections: the largest classified colour and opacity */
        float P[3] = {0, 0, 0}, PA = 0;
        for (int k = 0; k < n; k++) {
            const float *p = L[k].img->rgba + 4 * i;
            const float d = L[k].img->depth[i];
            depth = d < depth ? d : depth;
            if (L[k].comp)
                continue;
            for (int ch = 0; ch < 3; ch++)
                P[ch] = p[ch] > P[ch] ? p[ch] : P[ch];
            PA = p[3] > PA ? p[3] : PA;
        }
        const float rest = 1 - A;
        const float A2 = A + rest * PA;
        float *o = out->rgba + 4 * i;
        for (int ch = 0; ch < 3; ch++)
            o[ch] = C[ch] + rest * P[ch] + (1 - A2) * bg[ch];
        o[3] = A2;
        out->depth[i] = depth;
    }
}

int
drv_world_out_of_core(const vv_world *w) {
    for (int i = 0; w && i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (o->visible && o->type == VV_OBJECT_VOLUME && o->source)
            return 1;
    }
    return 0;
}

vv_status
drv_render_sources(const drv_renderer *r, const vv_world *w, const vv_view *view,
                   const vv_render_options *opt, vv_lod *lod, vv_image *out) {
    if (!r || !w || !view || !out)
        return vv_error_set(VV_ERR_INVALID, "sources: bad arguments");
    if (out->width != view->width || out->height != view->height)
        return vv_error_set(VV_ERR_INVALID, "sources: image %dx%d for a %dx%d view", out->width,
                            out->height, view->width, view->height);
    /* the layers: every visible object, a volume object */
    src_layer L[VV_SOURCES_MAX];
    int n = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o->visible)
            continue;
        if (o->type != VV_OBJECT_VOLUME || !o->volume)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "sources: object '%s': out-of-core rendering draws volume "
                                "objects only",
                                o->name);
        if (n == VV_SOURCES_MAX)
            return vv_error_set(VV_ERR_LIMIT, "sources: more than %d visible objects",
                                VV_SOURCES_MAX);
        src_layer *l = &L[n++];
        memset(l, 0, sizeof *l);
        l->object = i;
        if (o->source && vv_source_multires_view(o->source, &l->mview))
            l->multires = &l->mview;
        else if (o->source && vv_source_brick_view(o->source, &l->bview))
            l->bricks = &l->bview;
        vv_volume_brick_view(o->volume, &l->mem);
        l->geo = l->multires ? l->multires->level(l->multires->user, 0)
                 : l->bricks ? l->bricks->header(l->bricks->user)
                             : o->volume;
        /* a multi-channel object: composited under the composite rule, a
         * projection under the additive and maximum rules (as the ray
         * caster orders them) */
        l->comp = o->n_channels > 1 ? o->blend == VV_BLEND_COMPOSITE
                                    : o->mode == VV_MODE_COMPOSITE || o->mode == VV_MODE_ISO;
    }
    if (n > 1 && (r->ops->info.caps & VV_RENDERER_GLOBAL))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "sources: %s draws light between objects (shadows); out of core "
                            "it draws one object (several: raycast)",
                            r->ops->info.name);
    /* composited objects one after another: their boxes apart */
    for (int a = 0; a < n; a++)
        for (int b = a + 1; b < n; b++) {
            if (!L[a].comp || !L[b].comp)
                continue;
            vv_vec3 ca[8], cb[8];
            box_corners(w->objects[L[a].object], L[a].geo, ca);
            box_corners(w->objects[L[b].object], L[b].geo, cb);
            if (boxes_overlap(ca, cb))
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "sources: objects '%s' and '%s' overlap; out of core, "
                                    "composite and iso objects are drawn one after another, so "
                                    "their boxes must be apart (MIP, MinIP and X-ray objects may "
                                    "overlap)",
                                    w->objects[L[a].object]->name, w->objects[L[b].object]->name);
        }
    vv_lod def, sum;
    vv_lod_init(&def);
    if (!lod)
        lod = &def;
    sum = *lod;
    memset(sum.nodes, 0, sizeof sum.nodes);
    sum.skipped = sum.pending = sum.requested = sum.stalled = 0;
    vv_status s = VV_OK; /* (no layer: combine_layers gives the background) */
    if (n == 1) {        /* one object: its image is the frame, the World's background behind it */
        L[0].img = out;
        s = render_layer(r, w, &L[0], view, opt, lod, &sum, 1);
        L[0].img = NULL;
        if (s == VV_OK)
            *lod = sum;
        return s;
    }
    for (int k = 0; k < n && s == VV_OK; k++) {
        s = vv_image_new(&L[k].img, view->width, view->height);
        if (s == VV_OK)
            s = render_layer(r, w, &L[k], view, opt, lod, &sum, 0);
    }
    if (s == VV_OK) {
        combine_layers(w, L, n, out);
        *lod = sum;
    }
    for (int k = 0; k < n; k++)
        vv_image_free(L[k].img);
    return s;
}
