/* The GUI's display-free models: undo stack and transfer-function editing. */
#include "vvg-models.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- undo stack ---------------------------------------------------------- */

typedef struct undo_step {
    vv_world *world;
    char label[64];
} undo_step;

struct vvg_undo {
    int limit;
    int n_undo, n_redo;
    int clean;       /* n_undo of the clean state; -1 unreachable */
    undo_step *undo; /* oldest first */
    undo_step *redo; /* most recently undone last */
};

vv_status
vvg_undo_new(vvg_undo **out, int limit) {
    if (!out || limit < 1)
        return vv_error_set(VV_ERR_INVALID, "undo: bad limit %d", limit);
    vvg_undo *u = calloc(1, sizeof *u);
    if (u) {
        u->undo = calloc((size_t)limit, sizeof *u->undo);
        u->redo = calloc((size_t)limit, sizeof *u->redo);
    }
    if (!u || !u->undo || !u->redo) {
        vvg_undo_free(u);
        return vv_error_set(VV_ERR_NOMEM, "undo: out of memory");
    }
    u->limit = limit;
    u->clean = 0;
    *out = u;
    return VV_OK;
}

static void
clear_redo(vvg_undo *u) {
    for (int i = 0; i < u->n_redo; i++)
        vv_world_free(u->redo[i].world);
    u->n_redo = 0;
}

void
vvg_undo_clear(vvg_undo *u) {
    if (!u)
        return;
    for (int i = 0; i < u->n_undo; i++)
        vv_world_free(u->undo[i].world);
    u->n_undo = 0;
    clear_redo(u);
    u->clean = 0;
}

void
vvg_undo_mark_clean(vvg_undo *u) {
    if (u)
        u->clean = u->n_undo;
}

int
vvg_undo_is_clean(const vvg_undo *u) {
    return u && u->clean == u->n_undo;
}

void
vvg_undo_mark_unclean(vvg_undo *u) {
    if (u && u->clean == u->n_undo)
        u->clean = -1;
}

int
vvg_undo_clean_index(const vvg_undo *u) {
    return u ? u->clean : -1;
}

void
vvg_undo_set_clean_index(vvg_undo *u, int index) {
    if (u)
        u->clean = index;
}

void
vvg_undo_free(vvg_undo *u) {
    if (!u)
        return;
    vvg_undo_clear(u);
    free(u->undo);
    free(u->redo);
    free(u);
}

static void
set_label(undo_step *s, const char *label) {
    snprintf(s->label, sizeof s->label, "%s", label ? label : "edit");
}

vv_status
vvg_undo_push(vvg_undo *u, const vv_world *before, const char *label) {
    if (!u || !before)
        return vv_error_set(VV_ERR_INVALID, "undo: NULL argument");
    vv_world *snap = NULL;
    vv_status s = vv_world_clone(&snap, before);
    if (s != VV_OK)
        return s;
    clear_redo(u);
    if (u->clean > u->n_undo) /* the clean state was undone past, its redo step is gone */
        u->clean = -1;
    if (u->n_undo == u->limit) {
        vv_world_free(u->undo[0].world);
        memmove(&u->undo[0], &u->undo[1], (size_t)(u->limit - 1) * sizeof *u->undo);
        u->n_undo--;
        if (u->clean >= 0) /* its step dropped with the oldest: unreachable at 0 */
            u->clean = u->clean > 0 ? u->clean - 1 : -1;
    }
    u->undo[u->n_undo].world = snap;
    set_label(&u->undo[u->n_undo], label);
    u->n_undo++;
    return VV_OK;
}

int
vvg_undo_can_undo(const vvg_undo *u) {
    return u && u->n_undo > 0;
}

int
vvg_undo_can_redo(const vvg_undo *u) {
    return u && u->n_redo > 0;
}

const char *
vvg_undo_label(const vvg_undo *u, int redo) {
    if (!u)
        return NULL;
    if (redo)
        return u->n_redo ? u->redo[u->n_redo - 1].label : NULL;
    return u->n_undo ? u->undo[u->n_undo - 1].label : NULL;
}

/* Moves the top of @p from onto @p to, exchanging it with *world. */
static vv_status
swap_step(undo_step *from, int *n_from, undo_step *to, int *n_to, int limit, vv_world **world) {
    if (*n_from == 0)
        return vv_error_set(VV_ERR_INVALID, "undo: nothing to revert");
    undo_step step = from[--*n_from];
    if (*n_to == limit) {
        vv_world_free(to[0].world);
        memmove(&to[0], &to[1], (size_t)(limit - 1) * sizeof *to);
        (*n_to)--;
    }
    to[*n_to].world = *world;
    memcpy(to[*n_to].label, step.label, sizeof step.label);
    (*n_to)++;
    *world = step.world;
    return VV_OK;
}

vv_status
vvg_undo_undo(vvg_undo *u, vv_world **world) {
    if (!u || !world || !*world)
        return vv_error_set(VV_ERR_INVALID, "undo: NULL argument");
    return swap_step(u->undo, &u->n_undo, u->redo, &u->n_redo, u->limit, world);
}

vv_status
vvg_undo_redo(vvg_undo *u, vv_world **world) {
    if (!u || !world || !*world)
        return vv_error_set(VV_ERR_INVALID, "undo: NULL argument");
    /* the undo steps never outgrow the limit here: a redo step was an undo step */
    return swap_step(u->redo, &u->n_redo, u->undo, &u->n_undo, u->limit, world);
}

/* ---- transfer-function editing ------------------------------------------ */

static double
clamp(double v, double lo, double hi) {
    return v < lo ? lo : v > hi ? hi : v;
}

static double
span(const vvg_tf_axes *a) {
    double s = a->vmax - a->vmin;
    return s > 0 ? s : 1.0;
}

double
vvg_tf_x(const vvg_tf_axes *a, double value) {
    return (value - a->vmin) / span(a) * a->width;
}

double
vvg_tf_value(const vvg_tf_axes *a, double x) {
    return a->vmin + clamp(x, 0, a->width) / (a->width > 0 ? a->width : 1) * span(a);
}

double
vvg_tf_y(const vvg_tf_axes *a, double opacity) {
    return (1.0 - opacity) * a->height;
}

double
vvg_tf_opacity(const vvg_tf_axes *a, double y) {
    return clamp(1.0 - y / (a->height > 0 ? a->height : 1), 0, 1);
}

int
vvg_tf_hit(const vv_tf *tf, const vvg_tf_axes *a, double x, double y, double radius) {
    int best = -1;
    double bd = radius * radius;
    for (int i = 0; i < tf->n_opacity; i++) {
        double dx = vvg_tf_x(a, tf->opacity[i].value) - x;
        double dy = vvg_tf_y(a, tf->opacity[i].opacity) - y;
        double d = dx * dx + dy * dy;
        if (d <= bd) {
            bd = d;
            best = i;
        }
    }
    return best;
}

int
vvg_tf_add_point(vv_tf *tf, const vvg_tf_axes *a, double x, double y) {
    if (!isfinite(x) || !isfinite(y))
        return -1;
    double v = vvg_tf_value(a, x), op = vvg_tf_opacity(a, y);
    if (vv_tf_add_opacity(tf, v, op) != VV_OK)
        return -1;
    /* the new point is the last one at its value (vv_tf_add_opacity inserts after equals) */
    for (int i = tf->n_opacity - 1; i >= 0; i--)
        if (tf->opacity[i].value == v && tf->opacity[i].opacity == op)
            return i;
    return -1;
}

void
vvg_tf_move_point(vv_tf *tf, int i, const vvg_tf_axes *a, double x, double y) {
    if (i < 0 || i >= tf->n_opacity || !isfinite(x) || !isfinite(y))
        return;
    double v = vvg_tf_value(a, x);
    if (i > 0 && v < tf->opacity[i - 1].value)
        v = tf->opacity[i - 1].value;
    if (i + 1 < tf->n_opacity && v > tf->opacity[i + 1].value)
        v = tf->opacity[i + 1].value;
    tf->opacity[i].value = v;
    tf->opacity[i].opacity = vvg_tf_opacity(a, y);
}

void
vvg_tf_delete_point(vv_tf *tf, int i) {
    if (i < 0 || i >= tf->n_opacity)
        return;
    memmove(&tf->opacity[i], &tf->opacity[i + 1],
            (size_t)(tf->n_opacity - i - 1) * sizeof tf->opacity[0]);
    tf->n_opacity--;
}

int
vvg_tf_hit_color(const vv_tf *tf, const vvg_tf_axes *a, double x, double radius) {
    int best = -1;
    double bd = radius;
    for (int i = 0; i < tf->n_color; i++) {
        double d = fabs(vvg_tf_x(a, tf->color[i].value) - x);
        if (d <= bd) {
            bd = d;
            best = i;
        }
    }
    return best;
}

int
vvg_tf_add_color(vv_tf *tf, const vvg_tf_axes *a, double x, vv_vec3 color) {
    if (!isfinite(x))
        return -1;
    double v = vvg_tf_value(a, x);
    if (vv_tf_add_color(tf, v, color) != VV_OK)
        return -1;
    for (int i = tf->n_color - 1; i >= 0; i--)
        if (tf->color[i].value == v)
            return i;
    return -1;
}

void
vvg_tf_move_color(vv_tf *tf, int i, const vvg_tf_axes *a, double x) {
    if (i < 0 || i >= tf->n_color || !isfinite(x))
        return;
    double v = vvg_tf_value(a, x);
    if (i > 0 && v < tf->color[i - 1].value)
        v = tf->color[i - 1].value;
    if (i + 1 < tf->n_color && v > tf->color[i + 1].value)
        v = tf->color[i + 1].value;
    tf->color[i].value = v;
}

void
vvg_tf_delete_color(vv_tf *tf, int i) {
    if (i < 0 || i >= tf->n_color)
        return;
    memmove(&tf->color[i], &tf->color[i + 1], (size_t)(tf->n_color - i - 1) * sizeof tf->color[0]);
    tf->n_color--;
}

const char *
vvg_gui_renderer(const vv_world *w, const char *dflt) {
    const char *env = getenv("VOLVIS_GUI_GPU");
    if (!dflt || strcmp(dflt, "raycast") != 0 || (env && !strcmp(env, "0")))
        return dflt;
    const int any = env && !strcmp(env, "any");
    int volumes = 0, drawn = 1;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o->visible || o->type != VV_OBJECT_VOLUME || !o->volume)
            continue;
        volumes++;
        int shown = 0;
        for (int c = 0; c < o->n_channels; c++) {
            const int on = o->channels[c].visible && o->channels[c].volume;
            shown += on;
            drawn &= !on || !o->channels[c].labels;
        }
        drawn &= (o->n_channels < 2 || shown <= 4) &&
                 o->solid_texture.kind == VV_SOLID_TEXTURE_NONE && o->segmentation != VV_SEG_LABELS;
    }
    if (volumes != 1 || !drawn)
        return dflt;
    vv_gpu_device d[16];
    const int n = vv_gpu_devices(d, 16, NULL);
    for (int i = 0; i < n && i < 16; i++)
        if (!d[i].cpu || any)
            return "gpu";
    return dflt;
}
