/*
 * The World: lights, objects, the current view, global cut planes and
 * global shading (the paper's abstract model, section 3).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "volvis/model.h"

void
vv_render_settings_init(vv_render_settings *rs) {
    if (!rs)
        return;
    memset(rs, 0, sizeof *rs);
    rs->quality = -1;
}

vv_status
vv_render_settings_set_option(vv_render_settings *rs, const char *key, const char *value) {
    if (!rs || !key || !value)
        return vv_error_set(VV_ERR_INVALID, "render settings: NULL %s",
                            !rs ? "settings" : (!key ? "key" : "value"));
    size_t kl = strlen(key), vl = strlen(value);
    if (kl == 0)
        return vv_error_set(VV_ERR_INVALID, "render settings: empty option key");
    if (kl >= VV_RENDER_OPTION_KEY_MAX)
        return vv_error_set(VV_ERR_INVALID,
                            "render settings: option key \"%.40s...\" is %zu bytes; at most %d",
                            key, kl, VV_RENDER_OPTION_KEY_MAX - 1);
    if (vl >= VV_RENDER_OPTION_VALUE_MAX)
        return vv_error_set(VV_ERR_INVALID,
                            "render settings: option %s: value is %zu bytes; at most %d", key, vl,
                            VV_RENDER_OPTION_VALUE_MAX - 1);
    int n = rs->n_options < 0 ? 0 : rs->n_options;
    if (n > VV_MAX_RENDER_OPTIONS)
        n = VV_MAX_RENDER_OPTIONS;
    int i = 0;
    while (i < n && strcmp(rs->option_keys[i], key) != 0)
        i++;
    if (i == n) {
        if (n >= VV_MAX_RENDER_OPTIONS)
            return vv_error_set(VV_ERR_LIMIT, "render settings: more than %d options (adding %s)",
                                VV_MAX_RENDER_OPTIONS, key);
        memcpy(rs->option_keys[i], key, kl + 1);
        rs->n_options = n + 1;
    }
    memcpy(rs->option_values[i], value, vl + 1);
    return VV_OK;
}

const char *
vv_render_settings_get_option(const vv_render_settings *rs, const char *key) {
    if (!rs || !key)
        return NULL;
    for (int i = 0; i < rs->n_options && i < VV_MAX_RENDER_OPTIONS; i++)
        if (strcmp(rs->option_keys[i], key) == 0)
            return rs->option_values[i];
    return NULL;
}

vv_status
vv_world_new(vv_world **out) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "world: NULL output");
    *out = NULL;
    vv_world *w = calloc(1, sizeof *w);
    if (!w)
        return vv_error_set(VV_ERR_NOMEM, "world: out of memory");
    w->view.eye = vv_vec3_make(0, -1000, 0);
    w->view.at = vv_vec3_make(0, 0, 0);
    w->view.up = vv_vec3_make(0, 0, 1);
    w->view.fov = vv_deg_to_rad(30.0);
    w->view.ortho_height = 500.0;
    w->view.projection = VV_PROJECTION_PERSPECTIVE;
    w->view.width = 512;
    w->view.height = 512;
    w->ambient = vv_vec3_make(1, 1, 1);
    w->background = vv_vec3_make(0, 0, 0);
    vv_render_settings_init(&w->render);
    *out = w;
    return VV_OK;
}

void
vv_world_free(vv_world *w) {
    if (!w)
        return;
    for (int i = 0; i < w->n_objects; i++)
        vv_object_free(w->objects[i]);
    free(w->objects);
    free(w);
}

vv_status
vv_world_add_object(vv_world *w, vv_object *obj) {
    if (!w || !obj) {
        vv_object_free(obj);
        return vv_error_set(VV_ERR_INVALID, "world: NULL %s", w ? "object" : "world");
    }
    if (w->n_objects >= w->cap_objects) {
        if (w->cap_objects > (1 << 20)) {
            vv_object_free(obj);
            return vv_error_set(VV_ERR_LIMIT, "world: more than %d objects", w->cap_objects);
        }
        int cap = w->cap_objects ? 2 * w->cap_objects : 4;
        vv_object **p = realloc(w->objects, (size_t)cap * sizeof *p);
        if (!p) {
            vv_object_free(obj);
            return vv_error_set(VV_ERR_NOMEM, "world: out of memory");
        }
        w->objects = p;
        w->cap_objects = cap;
    }
    w->objects[w->n_objects++] = obj;
    return VV_OK;
}

vv_status
vv_world_clone(vv_world **out, const vv_world *w) {
    if (!out || !w)
        return vv_error_set(VV_ERR_INVALID, "world clone: NULL %s", out ? "world" : "output");
    *out = NULL;
    vv_world *c = malloc(sizeof *c);
    if (!c)
        return vv_error_set(VV_ERR_NOMEM, "world clone: out of memory");
    *c = *w;
    c->n_objects = 0;
    c->cap_objects = w->n_objects;
    c->objects = NULL;
    if (w->n_objects > 0) {
        c->objects = malloc((size_t)w->n_objects * sizeof *c->objects);
        if (!c->objects) {
            free(c);
            return vv_error_set(VV_ERR_NOMEM, "world clone: out of memory");
        }
    }
    for (int i = 0; i < w->n_objects; i++) {
        vv_status st = vv_object_clone(&c->objects[i], w->objects[i]);
        if (st != VV_OK) {
            vv_world_free(c);
            return st;
        }
        c->n_objects = i + 1;
    }
    *out = c;
    return VV_OK;
}

vv_status
vv_world_take_object(vv_world *w, int index, vv_object **out) {
    if (!w || !out || index < 0 || index >= w->n_objects)
        return vv_error_set(VV_ERR_INVALID, "world: no object %d", index);
    *out = w->objects[index];
    memmove(&w->objects[index], &w->objects[index + 1],
            (size_t)(w->n_objects - index - 1) * sizeof *w->objects);
    w->n_objects--;
    return VV_OK;
}

vv_status
vv_world_insert_object(vv_world *w, int index, vv_object *obj) {
    if (!w || !obj || index < 0 || index > w->n_objects) {
        vv_object_free(obj);
        return vv_error_set(VV_ERR_INVALID, "world: cannot insert an object at %d", index);
    }
    vv_status st = vv_world_add_object(w, obj);
    if (st != VV_OK)
        return st;
    memmove(&w->objects[index + 1], &w->objects[index],
            (size_t)(w->n_objects - 1 - index) * sizeof *w->objects);
    w->objects[index] = obj;
    return VV_OK;
}

vv_status
vv_world_add_light(vv_world *w, const vv_light *light) {
    if (!w || !light)
        return vv_error_set(VV_ERR_INVALID, "world: NULL %s", w ? "light" : "world");
    if (w->n_lights >= VV_MAX_LIGHTS)
        return vv_error_set(VV_ERR_LIMIT, "world: more than %d lights", VV_MAX_LIGHTS);
    w->lights[w->n_lights++] = *light;
    return VV_OK;
}

vv_status
vv_world_add_cut_plane(vv_world *w, vv_vec3 point, vv_vec3 normal) {
    if (!w)
        return vv_error_set(VV_ERR_INVALID, "world: NULL world");
    double len = vv_vec3_length(normal);
    if (!(len > 0.0) || !isfinite(len) || !isfinite(point.x) || !isfinite(point.y) ||
        !isfinite(point.z))
        return vv_error_set(VV_ERR_INVALID, "world: cut plane normal (%g, %g, %g) is not usable",
                            normal.x, normal.y, normal.z);
    if (w->n_cut_planes >= VV_MAX_CUT_PLANES)
        return vv_error_set(VV_ERR_LIMIT, "world: more than %d global cut planes",
                            VV_MAX_CUT_PLANES);
    w->cut_planes[w->n_cut_planes].point = point;
    w->cut_planes[w->n_cut_planes].normal = vv_vec3_scale(normal, 1.0 / len);
    w->n_cut_planes++;
    return VV_OK;
}

vv_box
vv_world_bounds(const vv_world *w) {
    vv_box b = {{0, 0, 0}, {0, 0, 0}};
    if (!w)
        return b;
    int any = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o || !o->visible || (o->type == VV_OBJECT_VOLUME && !o->volume))
            continue;
        vv_box ob = vv_object_world_box(o);
        if (ob.min.x > ob.max.x)
            continue; /* unbounded (a plane) or empty */
        if (!any) {
            b = ob;
            any = 1;
            continue;
        }
        b.min.x = fmin(b.min.x, ob.min.x);
        b.min.y = fmin(b.min.y, ob.min.y);
        b.min.z = fmin(b.min.z, ob.min.z);
        b.max.x = fmax(b.max.x, ob.max.x);
        b.max.y = fmax(b.max.y, ob.max.y);
        b.max.z = fmax(b.max.z, ob.max.z);
    }
    return b;
}
