/*
 * Scene files, writing: the World as a Jansson tree (the schema the reader
 * reads, key for key, in docs/scene-format.md), written out by
 * vv_json_write_text (src/core/json_text.c: short members on one line,
 * numbers with as few digits as read back the same) through an atomic file.
 * Every value reads back the same: vv_scene_load of the file reproduces the
 * World.
 */
#include <float.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "scene/scene_internal.h"
#include "volvis/model.h"
#include "volvis/scene.h"

/* ---- building the tree --------------------------------------------------- */

/* The first failure of a build: json_* constructors return NULL when out of
 * memory (or, for strings, on invalid UTF-8, which the reader would refuse). */
typedef struct wctx {
    vv_status st;
} wctx;

static json_t *
num(double v) {
    return json_real(isfinite(v) ? v : 0.0); /* never produced by a valid World */
}

/* An angle in degrees: the value of the shortest decimal (6 to 17 digits)
 * that reads back to the same radians. */
static json_t *
degrees(double rad) {
    double deg = vv_rad_to_deg(rad);
    for (int prec = 6; prec <= 17; prec++) {
        char buf[64];
        snprintf(buf, sizeof buf, "%.*g", prec, deg);
        double d = strtod(buf, NULL);
        if (vv_deg_to_rad(d) == rad || prec == 17)
            return num(d);
    }
    return num(deg);
}

static json_t *
vec3(vv_vec3 v) {
    json_t *a = json_array();
    if (a && (json_array_append_new(a, num(v.x)) || json_array_append_new(a, num(v.y)) ||
              json_array_append_new(a, num(v.z)))) {
        json_decref(a);
        return NULL;
    }
    return a;
}

static json_t *
pair(const double p[2]) {
    json_t *a = json_array();
    if (a && (json_array_append_new(a, num(p[0])) || json_array_append_new(a, num(p[1])))) {
        json_decref(a);
        return NULL;
    }
    return a;
}

/* obj[key] = v (v's reference taken, also on failure). */
static void
put(wctx *c, json_t *obj, const char *key, json_t *v) {
    if (json_object_set_new(obj, key, v) != 0 && c->st == VV_OK)
        c->st = vv_error_set(VV_ERR_NOMEM, "out of memory");
}

/* A string value; @p what names it in the error for invalid UTF-8. */
static void
put_str(wctx *c, json_t *obj, const char *key, const char *s, const char *what) {
    json_t *j = json_string(s ? s : "");
    if (!j) {
        if (c->st == VV_OK)
            c->st = vv_error_set(VV_ERR_INVALID,
                                 "%s is not valid UTF-8 (a scene file is UTF-8 JSON)", what);
        return;
    }
    put(c, obj, key, j);
}

static void
append(wctx *c, json_t *arr, json_t *v) {
    if (json_array_append_new(arr, v) != 0 && c->st == VV_OK)
        c->st = vv_error_set(VV_ERR_NOMEM, "out of memory");
}

static json_t *
cut_planes(wctx *c, const vv_cut_plane *p, int n) {
    json_t *a = json_array();
    for (int i = 0; a && i < n; i++) {
        json_t *o = json_object();
        if (o) {
            put(c, o, "point", vec3(p[i].point));
            put(c, o, "normal", vec3(p[i].normal));
        }
        append(c, a, o);
    }
    return a;
}

static json_t *
material(wctx *c, const vv_material *m) {
    json_t *o = json_object();
    if (!o)
        return NULL;
    put(c, o, "ambient", num(m->ambient));
    put(c, o, "diffuse", num(m->diffuse));
    put(c, o, "specular", num(m->specular));
    put(c, o, "shininess", num(m->shininess));
    put(c, o, "color", vec3(m->color));
    put(c, o, "reflectance", num(m->reflectance));
    put(c, o, "transparency", num(m->transparency));
    put(c, o, "ior", num(m->ior));
    if (m->emission.x != 0 || m->emission.y != 0 || m->emission.z != 0)
        put(c, o, "emission", vec3(m->emission));
    return o;
}

static void
put_effect_flags(wctx *c, json_t *o, const vv_object *obj) {
    put(c, o, "casts_shadows", json_boolean(obj->casts_shadows));
    put(c, o, "receives_shadows", json_boolean(obj->receives_shadows));
    put(c, o, "visible_in_reflections", json_boolean(obj->visible_in_reflections));
    put(c, o, "reflects", json_boolean(obj->reflects));
}

static json_t *
tf2d(wctx *c, const vv_tf2d *tf) {
    json_t *o = json_object(), *ws = json_array();
    for (int i = 0; ws && i < tf->n_widgets; i++) {
        const vv_tf2d_widget *w = &tf->widgets[i];
        json_t *wj = json_object();
        if (wj && w->shape == VV_TF2D_TRIANGLE) {
            put_str(c, wj, "shape", "triangle", "a widget shape");
            put(c, wj, "center", num(w->center));
            put(c, wj, "width", num(w->width));
        } else if (wj) {
            put_str(c, wj, "shape", "rectangle", "a widget shape");
            put(c, wj, "value", pair(w->value));
            put(c, wj, "ramp", num(w->ramp));
            put(c, wj, "gradient_ramp", num(w->gradient_ramp));
        }
        if (wj) {
            put(c, wj, "gradient", pair(w->gradient));
            put(c, wj, "color", vec3(w->color));
            put(c, wj, "opacity", num(w->opacity));
        }
        append(c, ws, wj);
    }
    if (!o) {
        json_decref(ws);
        return NULL;
    }
    put(c, o, "widgets", ws);
    put(c, o, "opacity_unit_distance", num(tf->opacity_unit_distance));
    return o;
}

static json_t *
tf1d(wctx *c, const vv_tf *tf) {
    json_t *o = json_object(), *op = json_array(), *col = json_array();
    for (int i = 0; op && i < tf->n_opacity; i++) {
        json_t *p = json_array();
        if (p) {
            append(c, p, num(tf->opacity[i].value));
            append(c, p, num(tf->opacity[i].opacity));
        }
        append(c, op, p);
    }
    for (int i = 0; col && i < tf->n_color; i++) {
        json_t *p = json_array();
        if (p) {
            append(c, p, num(tf->color[i].value));
            append(c, p, vec3(tf->color[i].color));
        }
        append(c, col, p);
    }
    if (!o) {
        json_decref(op);
        json_decref(col);
        return NULL;
    }
    put(c, o, "opacity", op);
    put(c, o, "color", col);
    put(c, o, "opacity_unit_distance", num(tf->opacity_unit_distance));
    return o;
}

static void
put_textures(wctx *c, json_t *oj, const vv_object *o) {
    const vv_texture_map *m = &o->texture;
    if (m->image) {
        json_t *t = json_object();
        if (t) {
            put_str(c, t, "image", m->image->source, "a texture image's file name");
            put_str(c, t, "projection", vv_texture_projection_name(m->projection), "a projection");
            put(c, t, "center", vec3(m->center));
            put(c, t, "axis", vec3(m->axis));
            put(c, t, "scale", pair(m->scale));
        }
        put(c, oj, "texture", t);
    }
    const vv_solid_texture *s = &o->solid_texture;
    if (s->kind == VV_SOLID_TEXTURE_NONE)
        return;
    json_t *t = json_object();
    if (t) {
        if (s->kind == VV_SOLID_TEXTURE_VOLUME)
            put_str(c, t, "volume", s->source, "a solid texture's file name");
        else
            put_str(c, t, "procedural", vv_solid_texture_kind_name(s->kind), "a texture kind");
        put(c, t, "period", num(s->period));
        put(c, t, "center", vec3(s->center));
        put(c, t, "axis", vec3(s->axis));
        put(c, t, "turbulence", num(s->turbulence));
        put(c, t, "seed", json_integer((json_int_t)s->seed));
        put(c, t, "color0", vec3(s->color0));
        put(c, t, "color1", vec3(s->color1));
    }
    put(c, oj, "solid_texture", t);
}

/* position, orientation (the unit quaternion [w, x, y, z]) and scale. */
static void
put_transform(wctx *c, json_t *oj, const vv_object *o) {
    put(c, oj, "position", vec3(o->position));
    vv_quat q = o->orientation;
    double n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
    if (fabs(n2 - 1.0) > 8 * DBL_EPSILON) /* as the reader: a unit one is kept bit for bit */
        q = vv_quat_normalize(q);
    json_t *qa = json_array();
    if (qa) {
        append(c, qa, num(q.w));
        append(c, qa, num(q.x));
        append(c, qa, num(q.y));
        append(c, qa, num(q.z));
    }
    put(c, oj, "orientation", qa);
    put(c, oj, "scale", vec3(o->scale));
}

/* The shape keys of a geometric object; @p file names a mesh's file. */
static void
put_shape(wctx *c, json_t *oj, const vv_object *o, const char *file) {
    const vv_geometry *g = &o->geometry;
    switch (o->type) {
    case VV_OBJECT_PLANE:
        put(c, oj, "point", vec3(g->point));
        put(c, oj, "normal", vec3(g->normal));
        break;
    case VV_OBJECT_POLYGON: {
        json_t *vs = json_array();
        for (int i = 0; vs && i < g->n_vertices; i++)
            append(c, vs, vec3(g->vertices[i]));
        put(c, oj, "vertices", vs);
        break;
    }
    case VV_OBJECT_SPHERE:
        put(c, oj, "center", vec3(g->center));
        put(c, oj, "radius", num(g->radius));
        break;
    case VV_OBJECT_BOX:
        put(c, oj, "min", vec3(g->box.min));
        put(c, oj, "max", vec3(g->box.max));
        break;
    case VV_OBJECT_CYLINDER:
        put(c, oj, "base", vec3(g->base));
        put(c, oj, "top", vec3(g->top));
        put(c, oj, "radius", num(g->radius));
        put(c, oj, "capped", json_boolean(g->capped));
        break;
    case VV_OBJECT_MESH:
        put_str(c, oj, "file", file && file[0] ? file : g->source, "the mesh's file name");
        break;
    default:
        break;
    }
}

/* A geometric object; @p file names a mesh's file (else geometry.source). */
static json_t *
geometry_object(wctx *c, const vv_object *o, const char *file) {
    json_t *oj = json_object();
    if (!oj)
        return NULL;
    put_str(c, oj, "name", o->name, "the object's name");
    put_str(c, oj, "type", vv_object_type_name(o->type), "the object's type");
    put_shape(c, oj, o, file);
    put_transform(c, oj, o);
    put(c, oj, "visible", json_boolean(o->visible));
    put(c, oj, "material", material(c, &o->material));
    put_textures(c, oj, o);
    put_effect_flags(c, oj, o);
    return oj;
}

/* The segmentation of a volume or grid object: a threshold, or the 1-D TF
 * (kept also under a 2-D TF or labels, which name themselves). */
static void
put_segmentation(wctx *c, json_t *oj, const vv_object *o) {
    if (o->segmentation == VV_SEG_THRESHOLD) {
        json_t *s = json_object();
        if (s)
            put(c, s, "threshold", num(o->threshold));
        put(c, oj, "segmentation", s);
    } else {
        put(c, oj, "transfer_function", tf1d(c, &o->tf));
        if (o->segmentation == VV_SEG_TRANSFER_FUNCTION_2D)
            put_str(c, oj, "segmentation", "tf2d", "a segmentation");
        if (o->segmentation == VV_SEG_LABELS)
            put_str(c, oj, "segmentation", "labels", "a segmentation");
    }
    if (o->segmentation == VV_SEG_TRANSFER_FUNCTION_2D || o->tf2d.n_widgets > 0)
        put(c, oj, "tf2d", tf2d(c, &o->tf2d));
}

/* The channels of a multi-channel volume object: each its index in the
 * object's file, name, visibility, whether it holds labels and transfer
 * function; the blend rule. */
static void
put_channels(wctx *c, json_t *oj, const vv_object *o) {
    if (o->n_channels < 2)
        return;
    json_t *arr = json_array();
    for (int k = 0; arr && k < o->n_channels; k++) {
        const vv_channel *ch = &o->channels[k];
        json_t *cj = json_object();
        append(c, arr, cj);
        if (!cj)
            break;
        put(c, cj, "channel", json_integer(ch->index));
        put_str(c, cj, "name", ch->name, "a channel's name");
        put(c, cj, "visible", json_boolean(ch->visible));
        if (ch->labels)
            put(c, cj, "labels", json_true());
        put(c, cj, "transfer_function", tf1d(c, &ch->tf));
    }
    put(c, oj, "channels", arr);
    put_str(c, oj, "blend", vv_channel_blend_name(o->blend), "the blend rule");
}

/* A volume or grid object (@p file: its file, else geometry.source), or a
 * geometric one. */
static json_t *
object(wctx *c, const vv_object *o, const char *file) {
    if (o->type != VV_OBJECT_VOLUME && o->type != VV_OBJECT_GRID)
        return geometry_object(c, o, file);
    json_t *oj = json_object();
    if (!oj)
        return NULL;
    const char *src = file && file[0] ? file : o->geometry.source;
    put_str(c, oj, "name", o->name, "the object's name");
    if (o->type == VV_OBJECT_GRID) {
        put_str(c, oj, "type", "grid", "the object's type");
        put_str(c, oj, "file", src, "the grid's file name");
        if (o->field[0])
            put_str(c, oj, "field", o->field, "the grid's field name");
        put(c, oj, "component", json_integer(o->component));
        put(c, oj, "time", json_integer(o->time));
    } else {
        /* a file out of core: its own geometry (level 0's), not the proxy's */
        const vv_volume *v = o->source ? vv_source_level(o->source, 0) : o->volume;
        put_str(c, oj, "type", "volume", "the object's type");
        put_str(c, oj, "file", src, "the volume's file name");
        put(c, oj, "origin", vec3(vv_vec3_make(v->origin[0], v->origin[1], v->origin[2])));
        put(c, oj, "spacing", vec3(vv_vec3_make(v->spacing[0], v->spacing[1], v->spacing[2])));
        if (o->geometry.filters)
            put_str(c, oj, "filters", o->geometry.filters, "the filter chain");
        if (o->time > 0)
            put(c, oj, "time", json_integer(o->time));
        put_channels(c, oj, o);
    }
    put_transform(c, oj, o);
    int mode = (int)o->mode;
    put_str(c, oj, "mode", vv_scene_mode_names[mode >= 0 && mode < VV_MODE_COUNT ? mode : 0],
            "a mode");
    put(c, oj, "isovalue", num(o->isovalue));
    if (o->mode == VV_MODE_ATTENUATED_MIP || o->attenuation != 0.05)
        put(c, oj, "attenuation", num(o->attenuation)); /* (older files have none) */
    put(c, oj, "step", num(o->step));
    put(c, oj, "shading", json_boolean(o->shading));
    put(c, oj, "visible", json_boolean(o->visible));
    put_segmentation(c, oj, o);
    put(c, oj, "material", material(c, &o->material));
    put_textures(c, oj, o);
    put(c, oj, "cut_planes", cut_planes(c, o->cut_planes, o->n_cut_planes));
    put_effect_flags(c, oj, o);
    return oj;
}

static json_t *
view(wctx *c, const vv_world *w) {
    const vv_view *v = &w->view;
    json_t *o = json_object();
    if (!o)
        return NULL;
    put(c, o, "eye", vec3(v->eye));
    put(c, o, "at", vec3(v->at));
    put(c, o, "up", vec3(v->up));
    put(c, o, "fov", degrees(v->fov));
    put_str(c, o, "projection",
            v->projection == VV_PROJECTION_ORTHOGRAPHIC ? "orthographic" : "perspective",
            "a projection");
    put(c, o, "ortho_height", num(v->ortho_height));
    put(c, o, "width", json_integer(v->width));
    put(c, o, "height", json_integer(v->height));
    put(c, o, "background", vec3(w->background));
    return o;
}

static json_t *
lights(wctx *c, const vv_world *w) {
    json_t *a = json_array();
    for (int i = 0; a && i < w->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        json_t *o = json_object();
        if (o) {
            put_str(c, o, "type", l->type == VV_LIGHT_POINT ? "point" : "directional",
                    "a light type");
            if (l->type == VV_LIGHT_POINT)
                put(c, o, "position", vec3(l->position));
            else if (!l->headlight)
                put(c, o, "direction", vec3(l->direction));
            put(c, o, "color", vec3(l->color));
            put(c, o, "intensity", num(l->intensity));
        }
        append(c, a, o);
    }
    return a;
}

/* The "render" section: only what is set (renderer, quality, options). */
static json_t *
render_settings(wctx *c, const vv_render_settings *rs) {
    json_t *o = json_object();
    if (!o)
        return NULL;
    if (rs->renderer[0])
        put_str(c, o, "renderer", rs->renderer, "the renderer's name");
    if (rs->quality >= 0)
        put(c, o, "quality", json_integer(rs->quality));
    if (rs->n_options > 0) {
        json_t *opts = json_object();
        for (int i = 0; opts && i < rs->n_options; i++) {
            json_t *key = json_string(rs->option_keys[i]);
            if (!key && c->st == VV_OK)
                c->st = vv_error_set(VV_ERR_INVALID,
                                     "renderer option %d: the key is not valid UTF-8", i);
            json_decref(key);
            if (key)
                put_str(c, opts, rs->option_keys[i], rs->option_values[i], "a renderer option");
        }
        put(c, o, "options", opts);
    }
    return o;
}

/* The whole World; @p files as vv_scene_save's volume_files. */
static json_t *
scene_tree(wctx *c, const vv_world *w, const char *const *files) {
    json_t *root = json_object();
    if (!root)
        return NULL;
    put(c, root, "view", view(c, w));
    put(c, root, "lights", lights(c, w));
    json_t *sh = json_object();
    if (sh)
        put(c, sh, "ambient", vec3(w->ambient));
    put(c, root, "shading", sh);
    const vv_render_settings *rs = &w->render;
    if (rs->renderer[0] || rs->quality >= 0 || rs->n_options > 0)
        put(c, root, "render", render_settings(c, rs));
    put(c, root, "cut_planes", cut_planes(c, w->cut_planes, w->n_cut_planes));
    json_t *objs = json_array();
    for (int i = 0; objs && i < w->n_objects && c->st == VV_OK; i++) {
        append(c, objs, object(c, w->objects[i], files ? files[i] : NULL));
        if (c->st != VV_OK)
            vv_error_prefix(c->st, "object %d", i);
    }
    put(c, root, "objects", objs);
    return root;
}

/* ---- checks ---------------------------------------------------------------- */

/* The render settings must read back as they are: terminated strings,
 * distinct non-empty keys, a quality the loader accepts. */
static vv_status
check_render_settings(const vv_render_settings *rs) {
    if (!memchr(rs->renderer, '\0', sizeof rs->renderer))
        return vv_error_set(VV_ERR_INVALID, "render settings: renderer name not terminated");
    if (rs->quality < -1 || rs->quality > 2)
        return vv_error_set(VV_ERR_INVALID, "render settings: quality %d outside -1..2",
                            rs->quality);
    if (rs->n_options < 0 || rs->n_options > VV_MAX_RENDER_OPTIONS)
        return vv_error_set(VV_ERR_INVALID, "render settings: %d options outside 0..%d",
                            rs->n_options, VV_MAX_RENDER_OPTIONS);
    for (int i = 0; i < rs->n_options; i++) {
        if (!memchr(rs->option_keys[i], '\0', sizeof rs->option_keys[i]) ||
            !memchr(rs->option_values[i], '\0', sizeof rs->option_values[i]))
            return vv_error_set(VV_ERR_INVALID, "render settings: option %d not terminated", i);
        if (!rs->option_keys[i][0])
            return vv_error_set(VV_ERR_INVALID, "render settings: option %d has an empty key", i);
        for (int j = 0; j < i; j++)
            if (strcmp(rs->option_keys[i], rs->option_keys[j]) == 0)
                return vv_error_set(VV_ERR_INVALID, "render settings: option %s given twice",
                                    rs->option_keys[i]);
    }
    return VV_OK;
}

static vv_status
check_saveable(const vv_world *w, const char *const *volume_files) {
    const vv_view *v = &w->view;
    vv_status st = check_render_settings(&w->render);
    if (st != VV_OK)
        return st;
    if (v->width < 1 || v->width > IMAGE_MAX_SIDE || v->height < 1 || v->height > IMAGE_MAX_SIDE)
        return vv_error_set(VV_ERR_INVALID, "view size %dx%d outside 1..%d", v->width, v->height,
                            IMAGE_MAX_SIDE);
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o)
            return vv_error_set(VV_ERR_INVALID, "object %d is NULL", i);
        if (o->type == VV_OBJECT_MESH && !o->geometry.source && !(volume_files && volume_files[i]))
            return vv_error_set(VV_ERR_INVALID, "object %d: a mesh without a file name", i);
        if (o->texture.image && !o->texture.image->source)
            return vv_error_set(VV_ERR_INVALID, "object %d: a texture image without a file name",
                                i);
        if (o->solid_texture.kind == VV_SOLID_TEXTURE_VOLUME && !o->solid_texture.source)
            return vv_error_set(VV_ERR_INVALID,
                                "object %d: a solid-texture volume without a file name", i);
    }
    for (int i = 0; i < w->n_objects; i++) {
        if (w->objects[i]->type != VV_OBJECT_VOLUME)
            continue;
        if (!w->objects[i]->volume)
            return vv_error_set(VV_ERR_INVALID, "object %d has no volume", i);
        const char *file =
            volume_files && volume_files[i] ? volume_files[i] : w->objects[i]->geometry.source;
        if (!file || !file[0])
            return vv_error_set(VV_ERR_INVALID, "object %d: no volume file name", i);
    }
    return VV_OK;
}

/* ---- writing --------------------------------------------------------------- */

vv_status
vv_scene_save(const vv_world *w, const char *path, const char *const *volume_files) {
    if (!w || !path)
        return vv_error_set(VV_ERR_INVALID, "scene: NULL %s", w ? "path" : "world");
    vv_status st = check_saveable(w, volume_files);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene: %s", path);
    wctx c = {VV_OK};
    json_t *root = scene_tree(&c, w, volume_files);
    char *text = NULL;
    size_t len = 0;
    if (c.st == VV_OK && !root)
        c.st = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (c.st == VV_OK)
        c.st = vv_json_write_text(root, &text, &len);
    json_decref(root);
    if (c.st != VV_OK)
        return vv_error_prefix(c.st, "scene: %s", path);
    vv_atomic_file af;
    st = vv_atomic_file_open(&af, path);
    if (st != VV_OK) {
        free(text);
        return vv_error_prefix(st, "scene");
    }
    size_t put_n = fwrite(text, 1, len, af.fp);
    free(text);
    if (put_n != len || ferror(af.fp)) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "scene: %s: write failed", path);
    }
    st = vv_atomic_file_commit(&af);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene");
    return VV_OK;
}
