/* The renderer registry and the generic renderer object (see volvis/render.h). */
#include <stdlib.h>
#include <string.h>

#include "render/registry.h"
#include "volvis/render.h"

struct vv_renderer {
    const vv_renderer_ops *ops;
    void *state;
};

/* Every rendering method built in, in the order --help lists them. */
static const vv_renderer_ops *const registry[] = {
    &vv_raycast_ops, &vv_raytrace_ops, &vv_radiosity_ops, &vv_splat_ops,
    &vv_surface_ops, &vv_fourier_ops,  &vv_irregular_ops, NULL};

const vv_renderer_ops *const *
vv_renderer_registry(void) {
    return registry;
}

void
vv_render_options_init(vv_render_options *o) {
    memset(o, 0, sizeof *o);
    o->quality = 2;
}

vv_status
vv_renderer_new(vv_renderer **out, const char *name) {
    *out = NULL;
    for (int i = 0; registry[i]; i++) {
        if (strcmp(registry[i]->name, name) != 0)
            continue;
        vv_renderer *r = calloc(1, sizeof *r);
        if (!r)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        r->ops = registry[i];
        vv_status s = r->ops->create(&r->state);
        if (s != VV_OK) {
            free(r);
            return vv_error_prefix(s, "%s", name);
        }
        *out = r;
        return VV_OK;
    }
    char known[256] = "";
    for (int i = 0; registry[i]; i++) {
        if (i)
            strncat(known, ", ", sizeof known - strlen(known) - 1);
        strncat(known, registry[i]->name, sizeof known - strlen(known) - 1);
    }
    return vv_error_set(VV_ERR_INVALID, "unknown renderer '%s' (available: %s)", name, known);
}

void
vv_renderer_free(vv_renderer *r) {
    if (!r)
        return;
    r->ops->destroy(r->state);
    free(r);
}

const char *
vv_renderer_name(const vv_renderer *r) {
    return r->ops->name;
}

void *
vv_renderer_state(const vv_renderer *r) {
    return r->state;
}

vv_status
vv_renderer_set_option(vv_renderer *r, const char *key, const char *value) {
    vv_status s = r->ops->set_option(r->state, key, value);
    return s == VV_OK ? s : vv_error_prefix(s, "%s", r->ops->name);
}

vv_status
vv_renderer_render(vv_renderer *r, const vv_world *world, const vv_view *view,
                   const vv_render_options *opt, vv_image *out) {
    vv_render_options def;
    if (!opt) {
        vv_render_options_init(&def);
        opt = &def;
    }
    if (!world || !view || !out)
        return vv_error_set(VV_ERR_INVALID, "render: NULL world, view or image");
    if (out->width != view->width || out->height != view->height)
        return vv_error_set(VV_ERR_INVALID, "render: image is %d x %d but the view is %d x %d",
                            out->width, out->height, view->width, view->height);
    vv_status s = r->ops->render(r->state, world, view, opt, out);
    return s == VV_OK ? s : vv_error_prefix(s, "%s", r->ops->name);
}

/* Samples of the transfer function searched for its surface value. */
#define VV_SURFACE_TF_SAMPLES 4096

int
vv_object_surface_value(const vv_object *obj, double *iso, vv_vec3 *color) {
    *color = obj->material.color;
    if (obj->mode == VV_MODE_ISO) {
        *iso = obj->isovalue;
        return 1;
    }
    if (obj->segmentation == VV_SEG_THRESHOLD) {
        *iso = obj->threshold;
        return 1;
    }
    if (obj->segmentation == VV_SEG_LABELS) {
        *iso = 0.5; /* between the background and the first label */
        return 1;
    }
    double lo = 0, hi = 1;
    if (obj->type == VV_OBJECT_GRID) {
        const int f = obj->grid ? vv_object_grid_field(obj) : -1;
        if (f < 0)
            return 0;
        lo = obj->grid->fields[f].range[0];
        hi = obj->grid->fields[f].range[1];
    } else if (obj->volume) {
        lo = obj->volume->range[0];
        hi = obj->volume->range[1];
    } else {
        return 0;
    }
    double amax = 0;
    for (int i = 0; i < VV_SURFACE_TF_SAMPLES; i++) {
        double a = vv_tf_eval_opacity(&obj->tf, lo + (hi - lo) * i / (VV_SURFACE_TF_SAMPLES - 1));
        amax = a > amax ? a : amax;
    }
    if (!(amax > 0))
        return 0;
    double prev_x = lo, prev_a = vv_tf_eval_opacity(&obj->tf, lo);
    for (int i = 0; i < VV_SURFACE_TF_SAMPLES; i++) {
        const double x = lo + (hi - lo) * i / (VV_SURFACE_TF_SAMPLES - 1);
        const double a = vv_tf_eval_opacity(&obj->tf, x);
        if (a >= 0.5 * amax) {
            *iso = i == 0 || a == prev_a
                       ? x
                       : prev_x + (x - prev_x) * (0.5 * amax - prev_a) / (a - prev_a);
            *color = vv_tf_eval_color(&obj->tf, *iso);
            return 1;
        }
        prev_x = x;
        prev_a = a;
    }
    return 0;
}

const char *
vv_render_settings_renderer(const vv_render_settings *rs) {
    return rs && rs->renderer[0] ? rs->renderer : "raycast";
}

int
vv_render_settings_quality(const vv_render_settings *rs) {
    return rs && rs->quality >= 0 ? rs->quality : 2;
}

vv_status
vv_renderer_apply_settings(vv_renderer *r, const vv_render_settings *rs) {
    for (int i = 0; rs && i < rs->n_options; i++) {
        vv_status s = vv_renderer_set_option(r, rs->option_keys[i], rs->option_values[i]);
        if (s != VV_OK)
            return vv_error_prefix(s, "render option %s", rs->option_keys[i]);
    }
    return VV_OK;
}

vv_status
vv_renderer_new_from_settings(vv_renderer **out, const vv_render_settings *rs) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "renderer: NULL output");
    *out = NULL;
    vv_renderer *r = NULL;
    vv_status s = vv_renderer_new(&r, vv_render_settings_renderer(rs));
    if (s == VV_OK)
        s = vv_renderer_apply_settings(r, rs);
    if (s != VV_OK) {
        vv_renderer_free(r);
        return s;
    }
    *out = r;
    return VV_OK;
}
