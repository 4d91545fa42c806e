/*
 * Scene files, writing: the World back to JSON (vv_scene_save), every value
 * read back the same.
 */
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "model/model_internal.h"
#include "model/scene_internal.h"
#include "modeling/modeling_internal.h"
#include "volvis/io.h"
#include "volvis/model.h"
#include "volvis/modeling.h"

#include "filter/filter_scene.h"
/* ---- writing ------------------------------------------------------------- */

static void
put_num(FILE *f, double v) {
    char buf[64];
    if (!isfinite(v))
        v = 0.0; /* never produced by a valid World; keep the file parseable */
    snprintf(buf, sizeof buf, "%.15g", v);
    if (strtod(buf, NULL) != v)
        snprintf(buf, sizeof buf, "%.17g", v);
    fputs(buf, f);
}

/* An angle in degrees, written with as few digits as read back to the same radians. */
static void
put_degrees(FILE *f, double rad) {
    double deg = vv_rad_to_deg(rad);
    for (int prec = 6; prec <= 17; prec++) {
        char buf[64];
        snprintf(buf, sizeof buf, "%.*g", prec, deg);
        if (vv_deg_to_rad(strtod(buf, NULL)) == rad || prec == 17) {
            fputs(buf, f);
            return;
        }
    }
}

static void
put_vec3(FILE *f, vv_vec3 v) {
    fputc('[', f);
    put_num(f, v.x);
    fputs(", ", f);
    put_num(f, v.y);
    fputs(", ", f);
    put_num(f, v.z);
    fputc(']', f);
}

static void
put_str(FILE *f, const char *s) {
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

static void
put_cut_planes(FILE *f, const vv_cut_plane *p, int n, const char *indent) {
    fputc('[', f);
    for (int i = 0; i < n; i++) {
        fprintf(f, "%s\n%s  {\"point\": ", i ? "," : "", indent);
        put_vec3(f, p[i].point);
        fputs(", \"normal\": ", f);
        put_vec3(f, p[i].normal);
        fputc('}', f);
    }
    if (n)
        fprintf(f, "\n%s", indent);
    fputc(']', f);
}

static void
put_material_global(FILE *f, const vv_material *m) {
    fputs(", \"reflectance\": ", f);
    put_num(f, m->reflectance);
    fputs(", \"transparency\": ", f);
    put_num(f, m->transparency);
    fputs(", \"ior\": ", f);
    put_num(f, m->ior);
    if (m->emission.x != 0 || m->emission.y != 0 || m->emission.z != 0) {
        fputs(", \"emission\": ", f);
        put_vec3(f, m->emission);
    }
}

static void
put_effect_flags(FILE *f, const vv_object *o) {
    fprintf(f,
            ",\n      \"casts_shadows\": %s, \"receives_shadows\": %s,"
            "\n      \"visible_in_reflections\": %s, \"reflects\": %s",
            o->casts_shadows ? "true" : "false", o->receives_shadows ? "true" : "false",
            o->visible_in_reflections ? "true" : "false", o->reflects ? "true" : "false");
}

static void
put_pair(FILE *f, const double p[2]) {
    fputc('[', f);
    put_num(f, p[0]);
    fputs(", ", f);
    put_num(f, p[1]);
    fputc(']', f);
}

static void
put_tf2d(FILE *f, const vv_tf2d *tf) {
    fputs(",\n      \"tf2d\": {\n        \"widgets\": [", f);
    for (int i = 0; i < tf->n_widgets; i++) {
        const vv_tf2d_widget *w = &tf->widgets[i];
        fputs(i ? ",\n          {" : "\n          {", f);
        if (w->shape == VV_TF2D_TRIANGLE) {
            fputs("\"shape\": \"triangle\", \"center\": ", f);
            put_num(f, w->center);
            fputs(", \"width\": ", f);
            put_num(f, w->width);
        } else {
            fputs("\"shape\": \"rectangle\", \"value\": ", f);
            put_pair(f, w->value);
            fputs(", \"ramp\": ", f);
            put_num(f, w->ramp);
            fputs(", \"gradient_ramp\": ", f);
            put_num(f, w->gradient_ramp);
        }
        fputs(", \"gradient\": ", f);
        put_pair(f, w->gradient);
        fputs(", \"color\": ", f);
        put_vec3(f, w->color);
        fputs(", \"opacity\": ", f);
        put_num(f, w->opacity);
        fputc('}', f);
    }
    fputs(tf->n_widgets ? "\n        ],\n" : "],\n", f);
    fputs("        \"opacity_unit_distance\": ", f);
    put_num(f, tf->opacity_unit_distance);
    fputs("\n      }", f);
}

static void
put_textures(FILE *f, const vv_object *o) {
    const vv_texture_map *m = &o->texture;
    if (m->image) {
        fputs(",\n      \"texture\": {\"image\": ", f);
        put_str(f, m->image->source ? m->image->source : "");
        fprintf(
            f, ", \"projection\": \"%s\", \"center\": ", vv_texture_projection_name(m->projection));
        put_vec3(f, m->center);
        fputs(", \"axis\": ", f);
        put_vec3(f, m->axis);
        fputs(", \"scale\": ", f);
        put_pair(f, m->scale);
        fputc('}', f);
    }
    const vv_solid_texture *s = &o->solid_texture;
    if (s->kind == VV_SOLID_TEXTURE_NONE)
        return;
    fputs(",\n      \"solid_texture\": {", f);
    if (s->kind == VV_SOLID_TEXTURE_VOLUME) {
        fputs("\"volume\": ", f);
        put_str(f, s->source ? s->source : "");
    } else {
        fprintf(f, "\"procedural\": \"%s\"", vv_solid_texture_kind_name(s->kind));
    }
    fputs(", \"period\": ", f);
    put_num(f, s->period);
    fputs(", \"center\": ", f);
    put_vec3(f, s->center);
    fputs(", \"axis\": ", f);
    put_vec3(f, s->axis);
    fputs(", \"turbulence\": ", f);
    put_num(f, s->turbulence);
    fprintf(f, ", \"seed\": %u, \"color0\": ", s->seed);
    put_vec3(f, s->color0);
    fputs(", \"color1\": ", f);
    put_vec3(f, s->color1);
    fputc('}', f);
}

/* A geometric object; @p file names a mesh's file (else geometry.source). */
static void
put_geometry_object(FILE *f, const vv_object *o, const char *file) {
    const vv_geometry *g = &o->geometry;
    fputs("    {\n      \"name\": ", f);
    put_str(f, o->name);
    fprintf(f, ",\n      \"type\": \"%s\"", vv_object_type_name(o->type));
    switch (o->type) {
    case VV_OBJECT_PLANE:
        fputs(",\n      \"point\": ", f);
        put_vec3(f, g->point);
        fputs(", \"normal\": ", f);
        put_vec3(f, g->normal);
        break;
    case VV_OBJECT_POLYGON:
        fputs(",\n      \"vertices\": [", f);
        for (int i = 0; i < g->n_vertices; i++) {
            fputs(i ? ", " : "", f);
            put_vec3(f, g->vertices[i]);
        }
        fputc(']', f);
        break;
    case VV_OBJECT_SPHERE:
        fputs(",\n      \"center\": ", f);
        put_vec3(f, g->center);
        fputs(", \"radius\": ", f);
        put_num(f, g->radius);
        break;
    case VV_OBJECT_BOX:
        fputs(",\n      \"min\": ", f);
        put_vec3(f, g->box.min);
        fputs(", \"max\": ", f);
        put_vec3(f, g->box.max);
        break;
    case VV_OBJECT_CYLINDER:
        fputs(",\n      \"base\": ", f);
        put_vec3(f, g->base);
        fputs(", \"top\": ", f);
        put_vec3(f, g->top);
        fputs(", \"radius\": ", f);
        put_num(f, g->radius);
        fprintf(f, ", \"capped\": %s", g->capped ? "true" : "false");
        break;
    case VV_OBJECT_MESH:
        fputs(",\n      \"file\": ", f);
        put_str(f, file && file[0] ? file : g->source ? g->source : "");
        break;
    default:
        break;
    }
    fputs(",\n      \"position\": ", f);
    put_vec3(f, o->position);
    vv_quat q = vv_quat_normalize(o->orientation);
    fputs(",\n      \"orientation\": [", f);
    put_num(f, q.w);
    fputs(", ", f);
    put_num(f, q.x);
    fputs(", ", f);
    put_num(f, q.y);
    fputs(", ", f);
    put_num(f, q.z);
    fputs("],\n      \"scale\": ", f);
    put_vec3(f, o->scale);
    fprintf(f, ",\n      \"visible\": %s", o->visible ? "true" : "false");
    fputs(",\n      \"material\": {\"ambient\": ", f);
    put_num(f, o->material.ambient);
    fputs(", \"diffuse\": ", f);
    put_num(f, o->material.diffuse);
    fputs(", \"specular\": ", f);
    put_num(f, o->material.specular);
    fputs(", \"shininess\": ", f);
    put_num(f, o->material.shininess);
    fputs(", \"color\": ", f);
    put_vec3(f, o->material.color);
    put_material_global(f, &o->material);
    fputc('}', f);
    put_textures(f, o);
    put_effect_flags(f, o);
    fputs("\n    }", f);
}

static void
put_object(FILE *f, const vv_object *o, const char *file) {
    if (o->type != VV_OBJECT_VOLUME && o->type != VV_OBJECT_GRID) {
        put_geometry_object(f, o, file);
        return;
    }
    fputs("    {\n      \"name\": ", f);
    put_str(f, o->name);
    if (o->type == VV_OBJECT_GRID) {
        fputs(",\n      \"type\": \"grid\",\n      \"file\": ", f);
        put_str(f, file && file[0] ? file : o->geometry.source ? o->geometry.source : "");
        if (o->field[0]) {
            fputs(",\n      \"field\": ", f);
            put_str(f, o->field);
        }
        fprintf(f, ",\n      \"component\": %d,\n      \"time\": %d", o->component, o->time);
    } else {
        const vv_volume *v = o->volume;
        fputs(",\n      \"type\": \"volume\",\n      \"file\": ", f);
        put_str(f, file && file[0] ? file : o->geometry.source ? o->geometry.source : "");
        fputs(",\n      \"origin\": ", f);
        put_vec3(f, vv_vec3_make(v->origin[0], v->origin[1], v->origin[2]));
        fputs(",\n      \"spacing\": ", f);
        put_vec3(f, vv_vec3_make(v->spacing[0], v->spacing[1], v->spacing[2]));
        if (o->geometry.filters) {
            fputs(",\n      \"filters\": ", f);
            put_str(f, o->geometry.filters);
        }
    }
    fputs(",\n      \"position\": ", f);
    put_vec3(f, o->position);
    vv_quat q = vv_quat_normalize(o->orientation);
    fputs(",\n      \"orientation\": [", f);
    put_num(f, q.w);
    fputs(", ", f);
    put_num(f, q.x);
    fputs(", ", f);
    put_num(f, q.y);
    fputs(", ", f);
    put_num(f, q.z);
    fputs("],\n      \"scale\": ", f);
    put_vec3(f, o->scale);
    int mode = (int)o->mode;
    fprintf(f, ",\n      \"mode\": \"%s\"", vv_scene_mode_names[mode >= 0 && mode < 5 ? mode : 0]);
    fputs(",\n      \"isovalue\": ", f);
    put_num(f, o->isovalue);
    fputs(",\n      \"step\": ", f);
    put_num(f, o->step);
    fprintf(f, ",\n      \"shading\": %s,\n      \"visible\": %s", o->shading ? "true" : "false",
            o->visible ? "true" : "false");
    if (o->segmentation == VV_SEG_THRESHOLD) {
        fputs(",\n      \"segmentation\": {\"threshold\": ", f);
        put_num(f, o->threshold);
        fputc('}', f);
    } else {
        fputs(",\n      \"transfer_function\": {\n        \"opacity\": [", f);
        for (int i = 0; i < o->tf.n_opacity; i++) {
            fputs(i ? ", [" : "[", f);
            put_num(f, o->tf.opacity[i].value);
            fputs(", ", f);
            put_num(f, o->tf.opacity[i].opacity);
            fputc(']', f);
        }
        fputs("],\n        \"color\": [", f);
        for (int i = 0; i < o->tf.n_color; i++) {
            fputs(i ? ", [" : "[", f);
            put_num(f, o->tf.color[i].value);
            fputs(", ", f);
            put_vec3(f, o->tf.color[i].color);
            fputc(']', f);
        }
        fputs("],\n        \"opacity_unit_distance\": ", f);
        put_num(f, o->tf.opacity_unit_distance);
        fputs("\n      }", f);
        if (o->segmentation == VV_SEG_TRANSFER_FUNCTION_2D)
            fputs(",\n      \"segmentation\": \"tf2d\"", f);
        if (o->segmentation == VV_SEG_LABELS)
            fputs(",\n      \"segmentation\": \"labels\"", f);
    }
    if (o->segmentation == VV_SEG_TRANSFER_FUNCTION_2D || o->tf2d.n_widgets > 0)
        put_tf2d(f, &o->tf2d);
    fputs(",\n      \"material\": {\"ambient\": ", f);
    put_num(f, o->material.ambient);
    fputs(", \"diffuse\": ", f);
    put_num(f, o->material.diffuse);
    fputs(", \"specular\": ", f);
    put_num(f, o->material.specular);
    fputs(", \"shininess\": ", f);
    put_num(f, o->material.shininess);
    fputs(", \"color\": ", f);
    put_vec3(f, o->material.color);
    put_material_global(f, &o->material);
    fputc('}', f);
    put_textures(f, o);
    fputs(",\n      \"cut_planes\": ", f);
    put_cut_planes(f, o->cut_planes, o->n_cut_planes, "      ");
    put_effect_flags(f, o);
    fputs("\n    }", f);
}

static int
render_settings_any(const vv_render_settings *rs) {
    return rs->renderer[0] || rs->quality >= 0 || rs->n_options > 0;
}

static void
put_render(FILE *f, const vv_render_settings *rs) {
    const char *sep = "";
    fputs(",\n  \"render\": {", f);
    if (rs->renderer[0]) {
        fputs("\"renderer\": ", f);
        put_str(f, rs->renderer);
        sep = ", ";
    }
    if (rs->quality >= 0) {
        fprintf(f, "%s\"quality\": %d", sep, rs->quality);
        sep = ", ";
    }
    if (rs->n_options > 0) {
        fprintf(f, "%s\"options\": {", sep);
        for (int i = 0; i < rs->n_options; i++) {
            fputs(i ? ",\n    " : "\n    ", f);
            put_str(f, rs->option_keys[i]);
            fputs(": ", f);
            put_str(f, rs->option_values[i]);
        }
        fputs("\n  }", f);
    }
    fputc('}', f);
}

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

vv_status
vv_scene_save(const vv_world *w, const char *path, const char *const *volume_files) {
    if (!w || !path)
        return vv_error_set(VV_ERR_INVALID, "scene: NULL %s", w ? "path" : "world");
    vv_status st = check_saveable(w, volume_files);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene: %s", path);
    vv_atomic_file af;
    st = vv_atomic_file_open(&af, path);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene");
    FILE *f = af.fp;
    const vv_view *v = &w->view;
    fputs("{\n  \"view\": {\n    \"eye\": ", f);
    put_vec3(f, v->eye);
    fputs(",\n    \"at\": ", f);
    put_vec3(f, v->at);
    fputs(",\n    \"up\": ", f);
    put_vec3(f, v->up);
    fputs(",\n    \"fov\": ", f);
    put_degrees(f, v->fov);
    fprintf(f, ",\n    \"projection\": \"%s\"",
            v->projection == VV_PROJECTION_ORTHOGRAPHIC ? "orthographic" : "perspective");
    fputs(",\n    \"ortho_height\": ", f);
    put_num(f, v->ortho_height);
    fprintf(f, ",\n    \"width\": %d,\n    \"height\": %d", v->width, v->height);
    fputs(",\n    \"background\": ", f);
    put_vec3(f, w->background);
    fputs("\n  },\n  \"lights\": [", f);
    for (int i = 0; i < w->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        fprintf(f, "%s\n    {\"type\": \"%s\"", i ? "," : "",
                l->type == VV_LIGHT_POINT ? "point" : "directional");
        if (l->type == VV_LIGHT_POINT) {
            fputs(", \"position\": ", f);
            put_vec3(f, l->position);
        } else if (!l->headlight) {
            fputs(", \"direction\": ", f);
            put_vec3(f, l->direction);
        }
        fputs(", \"color\": ", f);
        put_vec3(f, l->color);
        fputs(", \"intensity\": ", f);
        put_num(f, l->intensity);
        fputc('}', f);
    }
    fputs(w->n_lights ? "\n  ],\n" : "],\n", f);
    fputs("  \"shading\": {\"ambient\": ", f);
    put_vec3(f, w->ambient);
    fputc('}', f);
    if (render_settings_any(&w->render))
        put_render(f, &w->render);
    fputs(",\n  \"cut_planes\": ", f);
    put_cut_planes(f, w->cut_planes, w->n_cut_planes, "  ");
    fputs(",\n  \"objects\": [", f);
    for (int i = 0; i < w->n_objects; i++) {
        fputs(i ? ",\n" : "\n", f);
        put_object(f, w->objects[i], volume_files ? volume_files[i] : NULL);
    }
    fputs(w->n_objects ? "\n  ]\n}\n" : "]\n}\n", f);
    if (ferror(f)) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "scene: %s: write failed", path);
    }
    st = vv_atomic_file_commit(&af);
    if (st != VV_OK)
        return vv_error_prefix(st, "scene");
    return VV_OK;
}
