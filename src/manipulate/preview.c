/*
 * The Navigator's representations of a World while it moves (VolVis paper,
 * section 4): bounding boxes, PARC subvolume boxes and coarse Marching Cubes
 * drawn by the `surface` renderer, the ray caster at reduced resolution, and
 * the final renderer; plus the policy that picks one to hold a frame rate.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/navigator.h"
#include "volvis/surface.h"

static const char *const kind_names[VV_PREVIEW_COUNT] = {
    "bbox", "boxes", "coarse_mc", "raycast_1/8", "raycast_1/4", "raycast_1/2", "full"};

const char *
vv_preview_kind_name(vv_preview_kind k) {
    if ((int)k < 0 || (int)k >= VV_PREVIEW_COUNT)
        return "unknown";
    return kind_names[k];
}

vv_status
vv_preview_kind_parse(const char *name, vv_preview_kind *out) {
    for (int i = 0; name && i < VV_PREVIEW_COUNT; i++)
        if (!strcmp(name, kind_names[i])) {
            *out = (vv_preview_kind)i;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_INVALID,
                        "unknown preview '%s' (bbox, boxes, coarse_mc, raycast_1/8, "
                        "raycast_1/4, raycast_1/2, full)",
                        name ? name : "(null)");
}

static int
divide_up(int n, int d) {
    int r = (n + d - 1) / d;
    return r > 0 ? r : 1;
}

void
vv_preview_size(vv_preview_kind k, int width, int height, int *w, int *h) {
    int d = k == VV_PREVIEW_RAYCAST_8   ? 8
            : k == VV_PREVIEW_RAYCAST_4 ? 4
            : k == VV_PREVIEW_RAYCAST_2 ? 2
                                        : 1;
    *w = divide_up(width, d);
    *h = divide_up(height, d);
}

/* ---- cached reduced surfaces ------------------------------------------- */

#define PV_CACHE 8

/* One volume's PARC subdivision or coarse grid, and its mesh at one value. */
typedef struct pv_surface {
    const vv_volume *volume; /* a reference is held */
    uint64_t modified;
    vv_preview_kind kind; /* boxes or coarse_mc */
    vv_parc *parc;
    vv_coarse_surface *coarse;
    double iso; /* of mesh */
    vv_mesh *mesh;
    uint64_t used;
} pv_surface;

struct vv_preview {
    vv_renderer *final;
    /* the renderer of the reduced-resolution previews: the first that
     * declares VV_RENDERER_PREVIEW (the ray caster), the final renderer
     * itself when it declares it (one gradient cache) */
    vv_renderer *raycast;
    /* How far the renderers' caches are built for a volume: 1 after its first
     * ray cast (subvolume min/max, tables), 2 after its first shaded one
     * (gradients), 3 after its first full frame (the final renderer's). */
    const vv_volume *warm[PV_CACHE]; /* compared only, never dereferenced */
    uint64_t warm_modified[PV_CACHE];
    int warm_level[PV_CACHE];
    int n_warm;
    int warmup; /* the last frame built caches */
    vv_renderer *surface;
    pv_surface cache[PV_CACHE];
    uint64_t clock;
};

static void
surface_clear(pv_surface *s) {
    vv_parc_free(s->parc);
    vv_coarse_free(s->coarse);
    vv_mesh_free(s->mesh);
    vv_volume_free((vv_volume *)s->volume);
    memset(s, 0, sizeof *s);
}

vv_status
vv_preview_new(vv_preview **out, const char *final_renderer) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "preview: NULL output");
    *out = NULL;
    vv_preview *p = calloc(1, sizeof *p);
    if (!p)
        return vv_error_set(VV_ERR_NOMEM, "preview: out of memory");
    vv_status s =
        vv_renderer_new(&p->final, final_renderer ? final_renderer : vv_renderer_info_at(0)->name);
    /* one renderer for previews and the final frame: one gradient cache */
    if (s == VV_OK && (vv_renderer_get_info(p->final)->caps & VV_RENDERER_PREVIEW)) {
        p->raycast = p->final;
    } else if (s == VV_OK) {
        const vv_renderer_info *pv = NULL;
        for (int i = 0; i < vv_renderer_count() && !pv; i++)
            if (vv_renderer_info_at(i)->caps & VV_RENDERER_PREVIEW)
                pv = vv_renderer_info_at(i);
        s = pv ? vv_renderer_new(&p->raycast, pv->name)
               : vv_error_set(VV_ERR_UNSUPPORTED, "preview: no renderer draws previews");
    }
    if (s == VV_OK)
        s = vv_renderer_new(&p->surface, "raster");
    if (s != VV_OK) {
        vv_preview_free(p);
        return s;
    }
    *out = p;
    return VV_OK;
}

void
vv_preview_free(vv_preview *p) {
    if (!p)
        return;
    for (int i = 0; i < PV_CACHE; i++)
        surface_clear(&p->cache[i]);
    if (p->raycast != p->final)
        vv_renderer_free(p->raycast);
    vv_renderer_free(p->final);
    vv_renderer_free(p->surface);
    free(p);
}

vv_renderer *
vv_preview_final_renderer(vv_preview *p) {
    return p ? p->final : NULL;
}

/* Subdivision level giving boxes of about 8 voxels along the longest axis,
 * and a coarse grid of stride 4 (at most 2 for small volumes). */
static int
parc_level(const vv_volume *v) {
    int n = v->dims[0];
    if (v->dims[1] > n)
        n = v->dims[1];
    if (v->dims[2] > n)
        n = v->dims[2];
    int level = 0;
    while (level < 12 && ((n - 1) >> level) > 8)
        level++;
    return level;
}

static int
coarse_level(const vv_volume *v) {
    int n = v->dims[0];
    if (v->dims[1] < n)
        n = v->dims[1];
    if (v->dims[2] < n)
        n = v->dims[2];
    return n >= 64 ? 2 : n >= 16 ? 1 : 0;
}

/* The cached mesh of @p v at @p iso for boxes or coarse_mc (borrowed). */
static vv_status
surface_mesh(vv_preview *p, const vv_volume *v, vv_preview_kind kind, double iso,
             const vv_mesh **out) {
    pv_surface *hit = NULL, *victim = &p->cache[0];
    for (int i = 0; i < PV_CACHE; i++) {
        pv_surface *c = &p->cache[i];
        if (c->volume == v && c->modified == v->modified && c->kind == kind) {
            hit = c;
            break;
        }
        if (!c->volume || c->used < victim->used)
            victim = !victim->volume ? victim : c;
    }
    vv_status s = VV_OK;
    if (!hit) {
        p->warmup = 1;
        surface_clear(victim);
        hit = victim;
        if (kind == VV_PREVIEW_BOXES)
            s = vv_parc_new(&hit->parc, v, parc_level(v));
        else
            s = vv_coarse_new(&hit->coarse, v, coarse_level(v));
        if (s != VV_OK) {
            surface_clear(hit);
            return s;
        }
        hit->volume = vv_volume_ref((vv_volume *)v);
        hit->modified = v->modified;
        hit->kind = kind;
        hit->iso = NAN;
    }
    hit->used = ++p->clock;
    if (!hit->mesh || hit->iso != iso) {
        vv_mesh_free(hit->mesh);
        hit->mesh = NULL;
        if (kind == VV_PREVIEW_BOXES) {
            s = vv_parc_set_isovalue(hit->parc, iso);
            if (s == VV_OK && hit->parc->n_boxes > 0)
                s = vv_parc_mesh(hit->parc, &hit->mesh);
        } else {
            s = vv_coarse_set_isovalue(hit->coarse, iso, 0);
            if (s == VV_OK && hit->coarse->n_triangles > 0)
                s = vv_coarse_mesh(hit->coarse, &hit->mesh);
        }
        if (s != VV_OK)
            return s;
        hit->iso = iso;
    }
    *out = hit->mesh;
    return VV_OK;
}

/* The stand-in for a volume object: a mesh object with its transform,
 * material and cut planes, or NULL when nothing is to be drawn. */
static vv_status
stand_in(vv_preview *p, const vv_object *obj, vv_preview_kind kind, vv_object **out) {
    *out = NULL;
    vv_status s;
    vv_object *o = NULL;
    vv_vec3 color = obj->material.color;
    if (kind == VV_PREVIEW_BBOX) {
        s = vv_object_new_geometry(&o, VV_OBJECT_BOX, obj->name);
        if (s != VV_OK)
            return s;
        vv_box ib = {
            {0, 0, 0},
            {obj->volume->dims[0] - 1, obj->volume->dims[1] - 1, obj->volume->dims[2] - 1}};
        /* the box in the volume's own world coordinates (the object's) */
        vv_object tmp = *obj;
        tmp.position = vv_vec3_make(0, 0, 0);
        tmp.orientation = vv_quat_identity();
        tmp.scale = vv_vec3_make(1, 1, 1);
        o->geometry.box = vv_box_transform(ib, vv_object_index_to_world(&tmp));
    } else {
        double iso;
        if (!vv_object_surface_value(obj, &iso, &color))
            return VV_OK;
        const vv_mesh *mesh = NULL;
        s = surface_mesh(p, obj->volume, kind, iso, &mesh);
        if (s != VV_OK || !mesh)
            return s;
        s = vv_object_new_geometry(&o, VV_OBJECT_MESH, obj->name);
        if (s == VV_OK)
            s = vv_object_set_mesh(o, (vv_mesh *)mesh, NULL);
        if (s != VV_OK) {
            vv_object_free(o);
            return s;
        }
    }
    o->position = obj->position;
    o->orientation = obj->orientation;
    o->scale = obj->scale;
    o->material = obj->material;
    o->material.color = color;
    o->n_cut_planes = obj->n_cut_planes;
    memcpy(o->cut_planes, obj->cut_planes, sizeof o->cut_planes);
    *out = o;
    return VV_OK;
}

/* Draws volumes as boxes, coarse surfaces or bounding boxes with the
 * `surface` renderer; geometric objects as they are. */
static vv_status
render_surfaces(vv_preview *p, const vv_world *world, const vv_view *view, vv_preview_kind kind,
                const vv_render_options *opt, vv_image *out) {
    vv_world *w = NULL;
    vv_status s = vv_world_new(&w);
    if (s != VV_OK)
        return s;
    w->view = world->view;
    w->n_lights = world->n_lights;
    memcpy(w->lights, world->lights, sizeof w->lights);
    w->n_cut_planes = world->n_cut_planes;
    memcpy(w->cut_planes, world->cut_planes, sizeof w->cut_planes);
    w->ambient = world->ambient;
    w->background = world->background;
    for (int i = 0; i < world->n_objects && s == VV_OK; i++) {
        const vv_object *obj = world->objects[i];
        if (!obj->visible)
            continue;
        vv_object *o = NULL;
        if (obj->type == VV_OBJECT_VOLUME) {
            if (!obj->volume)
                continue;
            s = stand_in(p, obj, kind, &o);
        } else {
            s = vv_object_clone(&o, obj);
        }
        if (s == VV_OK && o)
            s = vv_world_add_object(w, o);
    }
    vv_view v = *view; /* at the representation's resolution */
    v.width = out->width;
    v.height = out->height;
    w->view = v;
    if (s == VV_OK) {
        const char *shading = kind == VV_PREVIEW_BOXES ? "flat" : "phong";
        s = vv_renderer_set_option(p->surface, "shading", shading);
        if (s == VV_OK)
            s = vv_renderer_set_option(p->surface, "wireframe",
                                       kind == VV_PREVIEW_BBOX ? "1" : "0");
        if (s == VV_OK)
            s = vv_renderer_render(p->surface, w, &v, opt, out);
    }
    vv_world_free(w);
    return s;
}

/* The warm-up level of @p v (an entry is made at 0 when there is none). */
static int *
warm_entry(vv_preview *p, const vv_volume *v) {
    for (int k = 0; k < p->n_warm; k++)
        if (p->warm[k] == v && p->warm_modified[k] == v->modified)
            return &p->warm_level[k];
    int k = p->n_warm < PV_CACHE ? p->n_warm++ : (int)(p->clock++ % PV_CACHE);
    p->warm[k] = v;
    p->warm_modified[k] = v->modified;
    p->warm_level[k] = 0;
    return &p->warm_level[k];
}

int
vv_preview_last_warmup(const vv_preview *p) {
    return p ? p->warmup : 0;
}

/* The ray caster at 1/divisor resolution and @p step_factor x the sample step. */
static vv_status
render_reduced(vv_preview *p, const vv_world *world, const vv_view *view, int step_factor,
               const vv_render_options *opt, vv_image *out) {
    vv_world *w = NULL;
    vv_status s = vv_world_clone(&w, world);
    if (s != VV_OK)
        return s;
    for (int i = 0; i < w->n_objects; i++) {
        vv_object *o = w->objects[i];
        if (o->type != VV_OBJECT_VOLUME || !o->volume)
            continue;
        o->step *= step_factor;
        /* The first frame of a volume builds the ray caster's cache and the
         * first shaded one its gradients (about half a second each for
         * 256^3): the first preview is drawn unshaded so that something is
         * on screen at once; shading starts with the next frame. */
        int *level = warm_entry(p, o->volume);
        if (*level < 1) {
            p->warmup = 1;
            *level = o->shading ? 1 : 2;
            o->shading = 0;
        } else if (*level < 2 && o->shading) {
            p->warmup = 1;
            *level = 2;
        }
    }
    vv_view v = *view;
    v.width = out->width;
    v.height = out->height;
    w->view = v;
    /* a World the preview renderer draws nothing of (only grids): the
     * final renderer at the reduced size instead of an error */
    vv_renderer *r = p->raycast;
    vv_error_clear();
    if (vv_renderer_check_world(vv_renderer_get_info(r), w) != VV_OK)
        r = p->final;
    vv_error_clear();
    s = vv_renderer_render(r, w, &v, opt, out);
    vv_world_free(w);
    return s;
}

vv_status
vv_preview_render(vv_preview *p, const vv_world *world, const vv_view *view, vv_preview_kind kind,
                  const vv_render_options *opt, vv_image *out) {
    if (!p || !world || !view || !out)
        return vv_error_set(VV_ERR_INVALID, "preview: NULL argument");
    int w, h;
    vv_preview_size(kind, view->width, view->height, &w, &h);
    if (out->width != w || out->height != h)
        return vv_error_set(VV_ERR_INVALID, "preview: %s image is %dx%d, expected %dx%d",
                            vv_preview_kind_name(kind), out->width, out->height, w, h);
    vv_render_options o;
    vv_render_options_init(&o);
    if (opt)
        o = *opt;
    p->warmup = 0;
    if (kind == VV_PREVIEW_FULL) {
        /* the final renderer's first frame of a volume builds its caches */
        for (int i = 0; i < world->n_objects; i++) {
            const vv_object *ob = world->objects[i];
            if (ob->type != VV_OBJECT_VOLUME || !ob->volume || !ob->visible)
                continue;
            int *level = warm_entry(p, ob->volume);
            if (*level < 3) {
                p->warmup = 1;
                *level = 3;
            }
        }
        return vv_renderer_render(p->final, world, view, &o, out);
    }
    o.quality = 0;
    o.fast_shading = 1; /* the ray caster's shading=table: the final frame keeps its own */
    switch (kind) {
    case VV_PREVIEW_RAYCAST_8: /* a coarser step would lose thin structures */
        return render_reduced(p, world, view, 4, &o, out);
    case VV_PREVIEW_RAYCAST_4:
        return render_reduced(p, world, view, 4, &o, out);
    case VV_PREVIEW_RAYCAST_2:
        return render_reduced(p, world, view, 2, &o, out);
    case VV_PREVIEW_BBOX:
    case VV_PREVIEW_BOXES:
    case VV_PREVIEW_COARSE_MC:
        return render_surfaces(p, world, view, kind, &o, out);
    default:
        return vv_error_set(VV_ERR_INVALID, "preview: unknown representation %d", (int)kind);
    }
}

/* ---- policy ------------------------------------------------------------ */

void
vv_preview_policy_init(vv_preview_policy *pol) {
    for (int i = 0; i < VV_PREVIEW_COUNT; i++) {
        pol->seconds[i] = -1.0;
        pol->allowed[i] = i != VV_PREVIEW_FULL;
    }
    pol->forced = -1;
    pol->choices = 0;
}

void
vv_preview_policy_record(vv_preview_policy *pol, vv_preview_kind kind, double seconds) {
    if (!pol || (int)kind < 0 || (int)kind >= VV_PREVIEW_COUNT || !isfinite(seconds) ||
        seconds < 0.0)
        return;
    double *s = &pol->seconds[kind];
    /* an exponential average that follows a slower machine within a few frames */
    *s = *s < 0.0 ? seconds : 0.6 * *s + 0.4 * seconds;
}

/* Expected seconds of kind k; < 0 when nothing can be said. A ray cast
 * not measured yet is taken as 4 times the next coarser one (4 times the
 * rays) or a quarter of the next finer one. */
static double
expected(const vv_preview_policy *pol, int k) {
    if (pol->seconds[k] >= 0.0)
        return pol->seconds[k];
    if (k >= VV_PREVIEW_RAYCAST_8 && k <= VV_PREVIEW_RAYCAST_2) {
        for (int c = k - 1, f = 4; c >= VV_PREVIEW_RAYCAST_8; c--, f *= 4)
            if (pol->seconds[c] >= 0.0)
                return f * pol->seconds[c];
        for (int c = k + 1, f = 4; c <= VV_PREVIEW_RAYCAST_2; c++, f *= 4)
            if (pol->seconds[c] >= 0.0)
                return pol->seconds[c] / f;
        if (pol->seconds[VV_PREVIEW_FULL] >= 0.0) /* at least 4 times the rays of 1/2 */
            return pol->seconds[VV_PREVIEW_FULL] / (k == VV_PREVIEW_RAYCAST_2   ? 8.0
                                                    : k == VV_PREVIEW_RAYCAST_4 ? 32.0
                                                                                : 128.0);
    }
    return -1.0;
}

/* The finest allowed ray cast expected within @p budget, or -1. */
static int
fitting_cast(const vv_preview_policy *pol, double budget) {
    for (int k = VV_PREVIEW_RAYCAST_2; k >= VV_PREVIEW_RAYCAST_8; k--) {
        double e = expected(pol, k);
        if (pol->allowed[k] && e >= 0.0 && e <= budget)
            return k;
    }
    return -1;
}

vv_preview_kind
vv_preview_policy_choose(vv_preview_policy *pol, double budget) {
    if (pol->forced >= 0 && pol->forced < VV_PREVIEW_COUNT)
        return (vv_preview_kind)pol->forced;
    int best = fitting_cast(pol, budget);
    /* nothing known yet: the 1/8 cast, the cheapest view of the data */
    if (best < 0 && pol->allowed[VV_PREVIEW_RAYCAST_8] && expected(pol, VV_PREVIEW_RAYCAST_8) < 0.0)
        best = VV_PREVIEW_RAYCAST_8;
    /* the data cannot be cast within the budget: a surface that fits and
     * is at least twice as quick as the 1/8 cast (under a passing load
     * every representation is slow, and boxes would show nothing gained);
     * bounding boxes unmeasured only for data whose 1/8 cast takes more than
     * 4 times the budget; else the 1/8 cast, slow as it is */
    double e8 = expected(pol, VV_PREVIEW_RAYCAST_8);
    for (int k = VV_PREVIEW_COARSE_MC; k >= VV_PREVIEW_BBOX && best < 0; k--) {
        double e = expected(pol, k);
        if (pol->allowed[k] && e >= 0.0 && e <= budget && (e8 < 0.0 || e < 0.5 * e8))
            best = k;
    }
    if (best < 0 && pol->allowed[VV_PREVIEW_BBOX] && e8 > 4.0 * budget &&
        expected(pol, VV_PREVIEW_BBOX) < 0.0)
        best = VV_PREVIEW_BBOX;
    if (best < 0 && pol->allowed[VV_PREVIEW_RAYCAST_8])
        best = VV_PREVIEW_RAYCAST_8;
    if (best < 0) { /* nothing fits: the cheapest allowed */
        for (int k = 0; k < VV_PREVIEW_COUNT && best < 0; k++)
            if (pol->allowed[k])
                best = k;
        if (best < 0)
            return VV_PREVIEW_BBOX;
    }
    /* now and then the next finer cast is tried again, so that the choice
     * follows a machine that has become less busy */
    if (++pol->choices % 24 == 0) {
        int next = best < VV_PREVIEW_RAYCAST_8 ? VV_PREVIEW_RAYCAST_8 : best + 1;
        if (next <= VV_PREVIEW_RAYCAST_2 && pol->allowed[next]) {
            /* only one that could fit: a probe must not stall the view (the
             * 1/8 cast is probed from surfaces even at 4 times the budget:
             * its time under a passing load must not keep boxes for good) */
            double e = expected(pol, next);
            double slack = next == VV_PREVIEW_RAYCAST_8 ? 4.0 : 1.5;
            if (e >= 0.0 && e <= slack * budget)
                return (vv_preview_kind)next;
        }
    }
    return (vv_preview_kind)best;
}
