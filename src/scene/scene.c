/*
 * Scene files: the World as JSON (schema in docs/scene-format.md), read with
 * Jansson. Scene loading is the one place where the model calls io
 * (vv_volume_load): a scene file names its volume files.
 *
 * Error positions: a schema error is located in the raw text by its path
 * (vv_json_locate, src/core/json_text.c).
 */
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "scene/scene_internal.h"
#include "volvis/io.h"
#include "volvis/model.h"
#include "volvis/modeling.h"

/* ---- sections ------------------------------------------------------------ */

vv_status
vv_scene_parse_cut_planes(const sctx *c, json_t *arr, const char *path, vv_cut_plane *planes,
                          int *n) {
    static const char *const keys[] = {"point", "normal", NULL};
    size_t i;
    json_t *e;
    *n = 0;
    json_array_foreach(arr, i, e) {
        char ep[PATH_MAX_LEN];
        vv_scene_path_index(ep, path, i);
        if (!json_is_object(e))
            return vv_scene_serr(c, ep, "expected an object {\"point\", \"normal\"}, got %s",
                                 vv_json_kind(e));
        if (i >= VV_MAX_CUT_PLANES)
            return vv_scene_serr(c, ep, "more than %d cut planes", VV_MAX_CUT_PLANES);
        vv_status st = vv_scene_check_keys(c, e, ep, keys);
        if (st != VV_OK)
            return st;
        int hp, hn;
        vv_vec3 p = {0, 0, 0}, nrm = {0, 0, 0};
        if ((st = vv_scene_get_vec3(c, e, ep, "point", &p, &hp)) != VV_OK ||
            (st = vv_scene_get_nonzero_vec3(c, e, ep, "normal", &nrm, &hn)) != VV_OK)
            return st;
        if (!hp)
            return vv_scene_missing(c, ep, "point", "a point on the plane");
        if (!hn)
            return vv_scene_missing(c, ep, "normal", "the normal of the kept half-space");
        planes[i].point = p;
        planes[i].normal = vv_scene_unit(nrm);
        (*n)++;
    }
    return VV_OK;
}

static vv_status
parse_view(const sctx *c, json_t *v, vv_world *w, int *has_background) {
    static const char *const keys[] = {
        "eye",          "at",    "up",     "fov",        "projection",
        "ortho_height", "width", "height", "background", NULL};
    const char *path = "view";
    vv_status st = vv_scene_check_keys(c, v, path, keys);
    if (st != VV_OK)
        return st;
    vv_view *vw = &w->view;
    double fov = vv_rad_to_deg(vw->fov);
    const char *proj = NULL;
    if ((st = vv_scene_get_vec3(c, v, path, "eye", &vw->eye, NULL)) != VV_OK ||
        (st = vv_scene_get_vec3(c, v, path, "at", &vw->at, NULL)) != VV_OK ||
        (st = vv_scene_get_nonzero_vec3(c, v, path, "up", &vw->up, NULL)) != VV_OK ||
        (st = vv_scene_get_number_in(c, v, path, "fov", &fov, NULL, 0, 1, 180, 1)) != VV_OK ||
        (st = vv_scene_get_string(c, v, path, "projection", &proj)) != VV_OK ||
        (st = vv_scene_get_number_in(c, v, path, "ortho_height", &vw->ortho_height, NULL, 0, 1,
                                     INFINITY, 1)) != VV_OK ||
        (st = vv_scene_get_int_in(c, v, path, "width", &vw->width, 1, IMAGE_MAX_SIDE)) != VV_OK ||
        (st = vv_scene_get_int_in(c, v, path, "height", &vw->height, 1, IMAGE_MAX_SIDE)) != VV_OK ||
        (st = vv_scene_get_color(c, v, path, "background", &w->background, has_background)) !=
            VV_OK)
        return st;
    vw->fov = vv_deg_to_rad(fov);
    if (proj) {
        if (strcmp(proj, "perspective") == 0)
            vw->projection = VV_PROJECTION_PERSPECTIVE;
        else if (strcmp(proj, "orthographic") == 0)
            vw->projection = VV_PROJECTION_ORTHOGRAPHIC;
        else
            return vv_scene_serr(c, "view.projection",
                                 "unknown projection \"%s\"; expected perspective or orthographic",
                                 proj);
    }
    vv_vec3 dir = vv_vec3_sub(vw->at, vw->eye);
    if (!(vv_vec3_length(dir) > 0.0))
        return vv_scene_serr(c, "view.at", "the eye and the point looked at are the same");
    vv_vec3 cr = vv_vec3_cross(vv_vec3_normalize(dir), vv_vec3_normalize(vw->up));
    if (!(vv_vec3_length(cr) > 1e-9))
        return vv_scene_serr(c, "view.up", "up is parallel to the viewing direction");
    return VV_OK;
}

static vv_status
parse_lights(const sctx *c, json_t *arr, vv_world *w) {
    static const char *const keys[] = {"type", "direction", "position", "color", "intensity", NULL};
    size_t i;
    json_t *e;
    vv_vec3 view_dir = vv_vec3_normalize(vv_vec3_sub(w->view.at, w->view.eye));
    json_array_foreach(arr, i, e) {
        char ep[PATH_MAX_LEN];
        vv_scene_path_index(ep, "lights", i);
        if (!json_is_object(e))
            return vv_scene_serr(c, ep, "expected an object, got %s", vv_json_kind(e));
        if (i >= VV_MAX_LIGHTS)
            return vv_scene_serr(c, ep, "more than %d lights", VV_MAX_LIGHTS);
        vv_status st = vv_scene_check_keys(c, e, ep, keys);
        if (st != VV_OK)
            return st;
        vv_light l;
        memset(&l, 0, sizeof l);
        l.color = vv_vec3_make(1, 1, 1);
        l.intensity = 1.0;
        const char *type = "directional";
        int hd, hp;
        if ((st = vv_scene_get_string(c, e, ep, "type", &type)) != VV_OK ||
            (st = vv_scene_get_nonzero_vec3(c, e, ep, "direction", &l.direction, &hd)) != VV_OK ||
            (st = vv_scene_get_vec3(c, e, ep, "position", &l.position, &hp)) != VV_OK ||
            (st = vv_scene_get_color(c, e, ep, "color", &l.color, NULL)) != VV_OK ||
            (st = vv_scene_get_number_in(c, e, ep, "intensity", &l.intensity, NULL, 0, 0, INFINITY,
                                         1)) != VV_OK)
            return st;
        char kp[PATH_MAX_LEN];
        if (strcmp(type, "directional") == 0) {
            l.type = VV_LIGHT_DIRECTIONAL;
            if (hp) {
                vv_scene_path_key(kp, ep, "position");
                return vv_scene_serr(c, kp,
                                     "a directional light has no position (use \"type\": "
                                     "\"point\")");
            }
            if (hd) {
                l.direction = vv_scene_unit(l.direction);
            } else {
                l.headlight = 1;
                l.direction = view_dir;
            }
        } else if (strcmp(type, "point") == 0) {
            l.type = VV_LIGHT_POINT;
            if (hd) {
                vv_scene_path_key(kp, ep, "direction");
                return vv_scene_serr(c, kp, "a point light has no direction");
            }
            if (!hp)
                return vv_scene_missing(c, ep, "position", "where the point light is");
        } else {
            vv_scene_path_key(kp, ep, "type");
            return vv_scene_serr(c, kp, "unknown light type \"%s\"; expected directional or point",
                                 type);
        }
        w->lights[w->n_lights++] = l;
    }
    return VV_OK;
}

/* An option value as the text a renderer's set-option reads: strings as they
 * are, booleans "1"/"0", numbers with as few digits as read back the same
 * double (%.15g, else %.17g). */
static vv_status
render_option_text(const sctx *c, json_t *v, const char *kp, char *buf, size_t cap) {
    switch (json_typeof(v)) {
    case JSON_STRING: {
        size_t n = json_string_length(v);
        if (n >= cap)
            return vv_scene_serr(c, kp, "value is %zu bytes; at most %zu", n, cap - 1);
        if (strlen(json_string_value(v)) != n)
            return vv_scene_serr(c, kp, "value contains a NUL character");
        memcpy(buf, json_string_value(v), n + 1);
        return VV_OK;
    }
    case JSON_TRUE:
    case JSON_FALSE:
        snprintf(buf, cap, "%s", json_is_true(v) ? "1" : "0");
        return VV_OK;
    case JSON_INTEGER:
    case JSON_REAL: {
        double d = 0.0;
        vv_status st = vv_scene_value_number(c, v, kp, &d);
        if (st != VV_OK)
            return st;
        snprintf(buf, cap, "%.15g", d);
        if (strtod(buf, NULL) != d)
            snprintf(buf, cap, "%.17g", d);
        return VV_OK;
    }
    default:
        break;
    }
    return vv_scene_serr(c, kp, "expected a string, a number or a boolean, got %s",
                         vv_json_kind(v));
}

/* The optional "render" section: renderer, quality and renderer options.
 * Renderer names and option keys are not checked here (the model does not
 * know the renderers); vv_renderer_new and vv_renderer_set_option do. */
static vv_status
parse_render(const sctx *c, json_t *r, vv_render_settings *rs) {
    static const char *const keys[] = {"renderer", "quality", "options", NULL};
    const char *path = "render";
    const char *name = NULL;
    json_t *opts = NULL;
    int quality = rs->quality;
    vv_status st;
    if ((st = vv_scene_check_keys(c, r, path, keys)) != VV_OK ||
        (st = vv_scene_get_string(c, r, path, "renderer", &name)) != VV_OK ||
        (st = vv_scene_get_int_in(c, r, path, "quality", &quality, 0, 2)) != VV_OK ||
        (st = vv_scene_get_object(c, r, path, "options", &opts)) != VV_OK)
        return st;
    if (name) {
        size_t n = strlen(name);
        if (n == 0)
            return vv_scene_serr(c, "render.renderer", "the renderer name is empty");
        if (n >= sizeof rs->renderer)
            return vv_scene_serr(c, "render.renderer",
                                 "renderer name \"%.40s\" is %zu bytes; at most %zu", name, n,
                                 sizeof rs->renderer - 1);
        memcpy(rs->renderer, name, n + 1);
    }
    rs->quality = quality;
    if (!opts)
        return VV_OK;
    const char *key;
    json_t *v;
    json_object_foreach(opts, key, v) {
        char kp[PATH_MAX_LEN];
        vv_scene_path_key(kp, "render.options", key);
        size_t kl = strlen(key);
        if (kl == 0)
            return vv_scene_serr(c, kp, "the option name is empty");
        if (kl >= VV_RENDER_OPTION_KEY_MAX)
            return vv_scene_serr(c, kp, "option name is %zu bytes; at most %d", kl,
                                 VV_RENDER_OPTION_KEY_MAX - 1);
        if (rs->n_options >= VV_MAX_RENDER_OPTIONS)
            return vv_scene_serr(c, kp, "more than %d options", VV_MAX_RENDER_OPTIONS);
        char text[VV_RENDER_OPTION_VALUE_MAX];
        if ((st = render_option_text(c, v, kp, text, sizeof text)) != VV_OK)
            return st;
        if ((st = vv_render_settings_set_option(rs, key, text)) != VV_OK)
            return vv_scene_serr(c, kp, "%s", vv_error_message());
    }
    return VV_OK;
}

static vv_status
parse_scene(const sctx *c, json_t *root, vv_world *w) {
    static const char *const keys[] = {"view",       "lights", "shading", "objects",
                                       "cut_planes", "render", NULL};
    if (!json_is_object(root))
        return vv_scene_serr(c, "", "expected a JSON object at the top level, got %s",
                             vv_json_kind(root));
    vv_status st = vv_scene_check_keys(c, root, "", keys);
    if (st != VV_OK)
        return st;
    json_t *view, *lights, *shading, *objects, *cuts, *render;
    if ((st = vv_scene_get_object(c, root, "", "view", &view)) != VV_OK ||
        (st = vv_scene_get_object(c, root, "", "render", &render)) != VV_OK ||
        (st = vv_scene_get_array(c, root, "", "lights", &lights)) != VV_OK ||
        (st = vv_scene_get_object(c, root, "", "shading", &shading)) != VV_OK ||
        (st = vv_scene_get_array(c, root, "", "objects", &objects)) != VV_OK ||
        (st = vv_scene_get_array(c, root, "", "cut_planes", &cuts)) != VV_OK)
        return st;
    int view_bg = 0;
    if (view && (st = parse_view(c, view, w, &view_bg)) != VV_OK)
        return st;
    if (shading) {
        static const char *const skeys[] = {"ambient", "background", NULL};
        vv_vec3 bg;
        int has_bg;
        if ((st = vv_scene_check_keys(c, shading, "shading", skeys)) != VV_OK ||
            (st = vv_scene_get_color(c, shading, "shading", "ambient", &w->ambient, NULL)) !=
                VV_OK ||
            (st = vv_scene_get_color(c, shading, "shading", "background", &bg, &has_bg)) != VV_OK)
            return st;
        if (has_bg && view_bg)
            return vv_scene_serr(c, "shading.background",
                                 "the background is also given in view.background; give it once");
        if (has_bg)
            w->background = bg;
    }
    if (render && (st = parse_render(c, render, &w->render)) != VV_OK)
        return st;
    if (lights && (st = parse_lights(c, lights, w)) != VV_OK)
        return st;
    if (cuts && (st = vv_scene_parse_cut_planes(c, cuts, "cut_planes", w->cut_planes,
                                                &w->n_cut_planes)) != VV_OK)
        return st;
    if (objects) {
        size_t i;
        json_t *e;
        json_array_foreach(objects, i, e) {
            if ((st = vv_scene_parse_object(c, e, i, w)) != VV_OK)
                return st;
        }
    }
    /* no view: the one the file opened alone gets (for several objects,
     * framing them all), with its headlight when no lights are given */
    if (!view && w->n_objects > 0) {
        if (c->over && c->over->width > 0 && c->over->height > 0) {
            w->view.width = c->over->width;
            w->view.height = c->over->height;
        }
        if ((st = vv_world_fit_default_view(w, NULL, !lights)) != VV_OK)
            return vv_error_prefix(st, "%s", c->path);
        const vv_vec3 dir = vv_vec3_normalize(vv_vec3_sub(w->view.at, w->view.eye));
        for (int i = 0; i < w->n_lights; i++)
            if (w->lights[i].headlight)
                w->lights[i].direction = dir;
    }
    return VV_OK;
}

vv_status
vv_scene_load(vv_world **out, const char *path) {
    return vv_scene_load_progress(out, path, NULL);
}

vv_status
vv_scene_load_progress(vv_world **out, const char *path, const vv_progress *progress) {
    return vv_scene_load_cached(out, path, progress, NULL);
}

vv_status
vv_scene_load_cached(vv_world **out, const char *path, const vv_progress *progress,
                     vv_filter_cache *cache) {
    return vv_scene_load_open(out, path, progress, cache, NULL);
}

vv_status
vv_scene_load_open(vv_world **out, const char *path, const vv_progress *progress,
                   vv_filter_cache *cache, const vv_open_options *open) {
    return vv_scene_load_for(out, path, progress, cache, open, NULL);
}

vv_status
vv_scene_load_for(vv_world **out, const char *path, const vv_progress *progress,
                  vv_filter_cache *cache, const vv_open_options *open,
                  const scene_overrides *over) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "scene: NULL output");
    *out = NULL;
    if (!path)
        return vv_error_set(VV_ERR_INVALID, "scene: NULL path");
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status st = vv_read_file(path, SCENE_MAX_BYTES, &data, &size);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene");
    scene_sources *shared = calloc(1, sizeof *shared); /* NULL: each object its own */
    sctx c = {path, (const char *)data, (size_t)size, progress, cache, open, shared, over};
    json_error_t jerr;
    json_t *root = json_loadb((const char *)data, (size_t)size,
                              JSON_REJECT_DUPLICATES | JSON_DECODE_INT_AS_REAL, &jerr);
    if (!root) {
        st = vv_error_set(VV_ERR_FORMAT, "%s:%d:%d: %s", path, jerr.line > 0 ? jerr.line : 1,
                          jerr.column > 0 ? jerr.column : 1, jerr.text);
        free(data);
        free(shared);
        return st;
    }
    vv_world *w = NULL;
    st = vv_world_new(&w);
    if (st == VV_OK)
        st = parse_scene(&c, root, w);
    vv_scene_sources_clear(shared);
    free(shared);
    json_decref(root);
    free(data);
    if (st != VV_OK) {
        vv_world_free(w);
        return st;
    }
    *out = w;
    return VV_OK;
}
