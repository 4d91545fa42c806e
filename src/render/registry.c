/*
 * The renderer registry, the generic renderer object, option validation
 * from the renderers' typed tables and the one setter that stores an
 * option in the field its row binds (defaults included), the World checks
 * and the default renderer of a World (include/volvis/render.h,
 * include/volvis/sys/renderer.h).
 */
#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/drivers.h"
#include "render/frame.h"
#include "render/registry.h"
#include "volvis/model.h"
#include "volvis/render.h"
#include "volvis/source.h"
#include "volvis/sys/renderer.h"

/* An option set on a renderer, kept for vv_renderer_clone. */
typedef struct rn_option {
    const char *key; /* the option table's own key */
    char *value;
} rn_option;

struct vv_renderer {
    const vv_renderer_ops *ops;
    void *state;
    rn_option *opts; /* the options set, each key once, in the order first set */
    int n_opts;
    vv_renderer *stand_in; /* the method ops->stand_in names, made on first use */
};

/* Every rendering method built in, in registry order: --help lists them so,
 * and the default renderer of a World is the first that draws all of it
 * (vv_world_renderer), hence the volume and grid ray casters first. Then
 * those vv_renderer_register adds: a slot is written before the count that
 * shows it is raised, and the array stays NULL-terminated. */
#define N_BUILT_IN 8
static const vv_renderer_ops *registry[N_BUILT_IN + VV_RENDERERS_REGISTERED_MAX + 1] = {
    &vv_raycast_ops,   &vv_raytrace_ops, &vv_irregular_ops, &vv_splat_ops, &vv_raster_ops,
    &vv_radiosity_ops, &vv_fourier_ops,  &vv_gpu_ops,       NULL};
static atomic_int n_registry = N_BUILT_IN;
static pthread_mutex_t register_lock = PTHREAD_MUTEX_INITIALIZER;

#define N_REGISTRY atomic_load_explicit(&n_registry, memory_order_acquire)

/* Names a method once had: "surface" was the raster renderer's until
 * "surface" came to mean only a Marching Cubes mesh (docs/architecture.md,
 * the glossary); scenes and scripts that name it still work. */
static const char *const renamed[][2] = {{"surface", "raster"}};

static const char *
current_name(const char *name) {
    for (size_t i = 0; name && i < sizeof renamed / sizeof renamed[0]; i++)
        if (!strcmp(name, renamed[i][0]))
            return renamed[i][1];
    return name;
}

const vv_renderer_ops *const *
vv_renderer_registry(void) {
    return registry;
}

int
vv_renderer_count(void) {
    return N_REGISTRY;
}

const vv_renderer_info *
vv_renderer_info_at(int i) {
    return i >= 0 && i < N_REGISTRY ? &registry[i]->info : NULL;
}

/* Why @p ops cannot be registered (VV_ERR_INVALID), or VV_OK: a render
 * call, a state for its options, every option row bound inside it. */
static vv_status
check_ops(const vv_renderer_ops *ops) {
    const vv_renderer_info *in = &ops->info;
    if (!ops->render)
        return vv_error_set(VV_ERR_INVALID, "renderer register: %s: no render call", in->name);
    if (in->n_options < 0 || (in->n_options > 0 && !in->options))
        return vv_error_set(VV_ERR_INVALID, "renderer register: %s: %d options without a table",
                            in->name, in->n_options);
    for (int i = 0; i < in->n_options; i++) {
        const vv_option_spec *o = &in->options[i];
        const vv_option_binding *b = o->bind;
        if (!o->key || !b ||
            (b->store != VV_OPTION_STORE_NONE &&
             (b->size == 0 || b->offset + b->size > ops->state_size)))
            return vv_error_set(VV_ERR_INVALID,
                                "renderer register: %s: option %s is not bound to a field of its "
                                "%zu-byte state",
                                in->name, o->key ? o->key : "(null)", ops->state_size);
    }
    return VV_OK;
}

vv_status
vv_renderer_register(const vv_renderer_ops *ops) {
    if (!ops || !ops->info.name || !ops->info.name[0])
        return vv_error_set(VV_ERR_INVALID, "renderer register: a method needs a name");
    if (ops->version != VV_RENDERER_OPS_VERSION)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "renderer register: %s: interface version %d (this library's is %d)",
                            ops->info.name, ops->version, VV_RENDERER_OPS_VERSION);
    vv_status s = check_ops(ops);
    if (s != VV_OK)
        return s;
    pthread_mutex_lock(&register_lock);
    const int n = atomic_load(&n_registry);
    for (int i = 0; i < n && s == VV_OK; i++)
        if (!strcmp(registry[i]->info.name, current_name(ops->info.name)))
            s = vv_error_set(VV_ERR_INVALID, "renderer register: %s: a method of that name exists",
                             ops->info.name);
    if (s == VV_OK && n >= N_BUILT_IN + VV_RENDERERS_REGISTERED_MAX)
        s = vv_error_set(VV_ERR_LIMIT, "renderer register: %s: over %d methods registered",
                         ops->info.name, VV_RENDERERS_REGISTERED_MAX);
    if (s == VV_OK) {
        registry[n] = ops;
        atomic_store_explicit(&n_registry, n + 1, memory_order_release);
    }
    pthread_mutex_unlock(&register_lock);
    return s;
}

const vv_renderer_info *
vv_renderer_info_find(const char *name) {
    name = current_name(name);
    for (int i = 0; name && i < N_REGISTRY; i++)
        if (strcmp(registry[i]->info.name, name) == 0)
            return &registry[i]->info;
    return NULL;
}

void
vv_render_options_init(vv_render_options *o) {
    memset(o, 0, sizeof *o);
    o->quality = 2;
}

/* ---- option values ------------------------------------------------------ */

const char *
vv_option_type_name(vv_option_type t) {
    switch (t) {
    case VV_OPTION_BOOL:
        return "bool";
    case VV_OPTION_INT:
        return "int";
    case VV_OPTION_REAL:
        return "real";
    case VV_OPTION_ENUM:
        return "enum";
    case VV_OPTION_STRING:
        return "string";
    }
    return "unknown";
}

/* Appends printf-style text to buf (cap bytes), truncating. */
static void
append(char *buf, size_t cap, const char *fmt, const char *a, double x) {
    const size_t n = strlen(buf);
    if (n + 1 >= cap)
        return;
    if (a)
        snprintf(buf + n, cap - n, fmt, a);
    else
        snprintf(buf + n, cap - n, fmt, x);
}

const char *
vv_option_describe(const vv_option_spec *spec, char *buf, size_t cap) {
    if (!cap)
        return buf;
    buf[0] = '\0';
    const int nw = spec->words != NULL;
    switch (spec->type) {
    case VV_OPTION_BOOL:
        append(buf, cap, "%s", "0|1", 0);
        break;
    case VV_OPTION_INT:
        append(buf, cap, "integer in %.17g", NULL, spec->min);
        append(buf, cap, "..%.17g", NULL, spec->max);
        break;
    case VV_OPTION_REAL: {
        const int hi_inf = spec->max == INFINITY;
        if (hi_inf) {
            append(buf, cap, (spec->flags & VV_OPTION_MIN_OPEN) ? "real > %.17g" : "real >= %.17g",
                   NULL, spec->min);
        } else {
            append(buf, cap,
                   (spec->flags & VV_OPTION_MIN_OPEN) ? "real in (%.17g" : "real in [%.17g", NULL,
                   spec->min);
            append(buf, cap, (spec->flags & VV_OPTION_MAX_OPEN) ? ", %.17g)" : ", %.17g]", NULL,
                   spec->max);
        }
        break;
    }
    case VV_OPTION_ENUM:
        for (int i = 0; nw && spec->words[i]; i++)
            append(buf, cap, i ? "|%s" : "%s", spec->words[i], 0);
        return buf;
    case VV_OPTION_STRING:
        append(buf, cap, "%s", "text", 0);
        break;
    }
    for (int i = 0; nw && spec->words[i]; i++)
        append(buf, cap, i ? "|%s" : " or %s", spec->words[i], 0);
    return buf;
}

static vv_status
bad_value(const vv_option_spec *spec, const char *text) {
    char what[256];
    return vv_error_set(VV_ERR_INVALID, "%s: '%s' is not %s%s", spec->key, text,
                        spec->type == VV_OPTION_ENUM ? "one of " : "",
                        vv_option_describe(spec, what, sizeof what));
}

vv_status
vv_option_parse(const vv_option_spec *spec, const char *text, vv_option_value *out) {
    if (!spec || !text || !out)
        return vv_error_set(VV_ERR_INVALID, "option: NULL argument");
    memset(out, 0, sizeof *out);
    out->type = spec->type;
    out->word = -1;
    out->text = text;
    out->r = NAN;
    for (int i = 0; spec->words && spec->words[i]; i++)
        if (strcmp(text, spec->words[i]) == 0) {
            out->word = i;
            return VV_OK;
        }
    switch (spec->type) {
    case VV_OPTION_ENUM:
        return bad_value(spec, text);
    case VV_OPTION_STRING:
        if (strlen(text) >= VV_RENDER_OPTION_VALUE_MAX)
            return vv_error_set(VV_ERR_INVALID, "%s: value of %zu bytes (at most %d)", spec->key,
                                strlen(text), VV_RENDER_OPTION_VALUE_MAX - 1);
        return VV_OK;
    case VV_OPTION_BOOL:
        if (strcmp(text, "1") == 0 || strcmp(text, "0") == 0) {
            out->b = text[0] == '1';
            out->i = out->b;
            out->r = out->b;
            return VV_OK;
        }
        return bad_value(spec, text);
    case VV_OPTION_INT: {
        char *end = NULL;
        errno = 0;
        const long long v = strtoll(text, &end, 10);
        if (!end || end == text || *end || errno || (double)v < spec->min || (double)v > spec->max)
            return bad_value(spec, text);
        out->i = v;
        out->r = (double)v;
        return VV_OK;
    }
    case VV_OPTION_REAL: {
        char *end = NULL;
        const double v = strtod(text, &end);
        if (!end || end == text || *end || v != v || v == INFINITY || v == -INFINITY)
            return bad_value(spec, text);
        const int lo_ok = (spec->flags & VV_OPTION_MIN_OPEN) ? v > spec->min : v >= spec->min;
        const int hi_ok = (spec->flags & VV_OPTION_MAX_OPEN) ? v < spec->max : v <= spec->max;
        if (!lo_ok || !hi_ok)
            return bad_value(spec, text);
        out->r = v;
        return VV_OK;
    }
    }
    return vv_error_set(VV_ERR_INVALID, "%s: option of unknown type %d", spec->key,
                        (int)spec->type);
}

const vv_option_spec *
vv_renderer_info_option(const vv_renderer_info *info, const char *key) {
    for (int i = 0; info && key && i < info->n_options; i++)
        if (strcmp(info->options[i].key, key) == 0)
            return &info->options[i];
    return NULL;
}

static vv_status
unknown_key(const vv_renderer_info *info, const char *key) {
    char known[1024] = "";
    for (int i = 0; i < info->n_options; i++)
        append(known, sizeof known, i ? ", %s" : "%s", info->options[i].key, 0);
    if (!info->n_options)
        return vv_error_set(VV_ERR_INVALID, "unknown option '%s' (%s takes no options)", key,
                            info->name);
    return vv_error_set(VV_ERR_INVALID, "unknown option '%s' (%s)", key, known);
}

vv_status
vv_renderer_info_check_option(const vv_renderer_info *info, const char *key, const char *value) {
    if (!info || !key || !value)
        return vv_error_set(VV_ERR_INVALID, "option: NULL argument");
    const vv_option_spec *spec = vv_renderer_info_option(info, key);
    if (!spec)
        return unknown_key(info, key);
    vv_option_value v;
    return vv_option_parse(spec, value, &v);
}

/* ---- what a renderer draws ------------------------------------------------- */

/* 1 when @p obj is a visible object with something to draw. */
static int
has_content(const vv_object *obj) {
    if (!obj || !obj->visible)
        return 0;
    if (obj->type == VV_OBJECT_VOLUME)
        return obj->volume != NULL;
    if (obj->type == VV_OBJECT_GRID)
        return obj->grid != NULL;
    return 1;
}

static int
has_mode(vv_object_type t) {
    return t == VV_OBJECT_VOLUME || t == VV_OBJECT_GRID;
}

/** 1 when @p info draws @p obj: its kind, for volumes and grids its mode, and
 * for a volume of several channels VV_RENDERER_CHANNELS. */
static int
renderer_info_draws(const vv_renderer_info *info, const vv_object *obj) {
    if (!info || !obj || !(info->draws & VV_DRAWS(obj->type)))
        return 0;
    if (obj->n_channels > 1 && !(info->caps & VV_RENDERER_CHANNELS))
        return 0;
    return !has_mode(obj->type) || (info->modes & VV_MODE_BIT(obj->mode)) != 0;
}

static const char *const mode_names[VV_MODE_COUNT] = {"composite", "mip", "minip",
                                                      "xray",      "iso", "attenuated-mip"};

static const char *
mode_name(vv_render_mode m) {
    return (int)m >= 0 && (int)m < VV_MODE_COUNT ? mode_names[m] : "unknown";
}

/* The renderers that draw @p obj, comma-separated, into buf. */
static const char *
drawn_by(const vv_object *obj, char *buf, size_t cap) {
    buf[0] = '\0';
    for (int i = 0; i < N_REGISTRY; i++)
        if (renderer_info_draws(&registry[i]->info, obj))
            append(buf, cap, buf[0] ? ", %s" : "%s", registry[i]->info.name, 0);
    if (!buf[0])
        snprintf(buf, cap, "none");
    return buf;
}

vv_status
vv_renderer_check_world(const vv_renderer_info *info, const vv_world *w) {
    if (!info || !w)
        return vv_error_set(VV_ERR_INVALID, "render: NULL renderer or World");
    int drawn = 0, left = 0;
    const vv_object *first_left = NULL;
    char who[256];
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!has_content(o))
            continue;
        if (!(info->draws & VV_DRAWS(o->type))) {
            if (!left++)
                first_left = o;
            continue;
        }
        if (has_mode(o->type) && !(info->modes & VV_MODE_BIT(o->mode)))
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "object '%s': %s mode is not drawn by %s (drawn by %s)", o->name,
                                mode_name(o->mode), info->name, drawn_by(o, who, sizeof who));
        if (o->n_channels > 1 && !(info->caps & VV_RENDERER_CHANNELS))
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "object '%s' has %d channels; %s draws one channel an object "
                                "(channels are drawn by %s)",
                                o->name, o->n_channels, info->name, drawn_by(o, who, sizeof who));
        drawn++;
    }
    if (drawn == 0 && left == 1)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "object '%s' is a %s object, which %s does not draw; it is drawn by %s",
                            first_left->name, vv_object_type_name(first_left->type), info->name,
                            drawn_by(first_left, who, sizeof who));
    if (drawn == 0 && left > 1)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "none of the World's %d visible objects is drawn by %s ('%s' is a "
                            "%s object, drawn by %s)",
                            left, info->name, first_left->name,
                            vv_object_type_name(first_left->type),
                            drawn_by(first_left, who, sizeof who));
    return VV_OK;
}

const char *
vv_world_renderer(const vv_world *w) {
    if (!w)
        return "raycast";
    if (w->render.renderer[0])
        return current_name(w->render.renderer);
    int n = 0;
    for (int i = 0; i < w->n_objects; i++)
        n += has_content(w->objects[i]);
    int best = -1, best_n = 0;
    for (int r = 0; r < N_REGISTRY; r++) {
        int k = 0;
        for (int i = 0; i < w->n_objects; i++)
            k += has_content(w->objects[i]) &&
                 renderer_info_draws(&registry[r]->info, w->objects[i]);
        if (k == n)
            return registry[r]->info.name;
        if (k > best_n) {
            best = r;
            best_n = k;
        }
    }
    return best >= 0 ? registry[best]->info.name : "raycast";
}

/* ---- options: the one setter ---------------------------------------------------- */

/* The number a value stands for: the word's value, else the parsed number
 * (BOOL 0 or 1). */
static double
option_number(const vv_option_binding *b, const vv_option_value *v) {
    if (v->word >= 0)
        return b->word_values[v->word];
    return v->type == VV_OPTION_BOOL ? (double)v->b : v->r;
}

/* Stores @p v into the field @p b binds (vv_option_binding). */
static vv_status
option_store(unsigned char *field, const vv_option_spec *spec, const vv_option_binding *b,
             const vv_option_value *v) {
    /* a word without a value of its own is the hook's, except an index */
    const int hooked = v->word >= 0 && !b->word_values;
    switch (b->store) {
    case VV_OPTION_STORE_NONE:
        return VV_OK;
    case VV_OPTION_STORE_DOUBLE: {
        if (hooked)
            return VV_OK;
        const double x = option_number(b, v) * b->scale;
        memcpy(field, &x, sizeof x);
        return VV_OK;
    }
    case VV_OPTION_STORE_FLOAT: {
        if (hooked)
            return VV_OK;
        const float x = (float)(option_number(b, v) * b->scale);
        memcpy(field, &x, sizeof x);
        return VV_OK;
    }
    case VV_OPTION_STORE_INT: {
        const int x = hooked                      ? v->word
                      : v->word >= 0              ? (int)b->word_values[v->word]
                      : v->type == VV_OPTION_BOOL ? v->b
                                                  : (int)v->i;
        memcpy(field, &x, sizeof x);
        return VV_OK;
    }
    case VV_OPTION_STORE_UINT64: {
        if (hooked)
            return VV_OK;
        const uint64_t x = (uint64_t)(option_number(b, v) * b->scale);
        memcpy(field, &x, sizeof x);
        return VV_OK;
    }
    case VV_OPTION_STORE_CHARS: {
        const size_t n = strlen(v->text);
        if (n >= b->size)
            return vv_error_set(VV_ERR_INVALID, "%s: value of %zu bytes (at most %zu)", spec->key,
                                n, b->size - 1);
        memset(field, 0, b->size);
        memcpy(field, v->text, n);
        return VV_OK;
    }
    }
    return vv_error_set(VV_ERR_UNSUPPORTED, "%s: option stored as unknown kind %d", spec->key,
                        (int)b->store);
}

/* Sets option @p spec of a method's @p state from @p text: parsed and
 * validated, stored in its bound field, then its hook; a failing hook
 * gives the field its previous bytes back. The one setter of every
 * option, defaults included. */
static vv_status
option_apply(void *state, const vv_option_spec *spec, const char *text) {
    vv_option_value v;
    vv_status s = vv_option_parse(spec, text, &v);
    if (s != VV_OK)
        return s;
    const vv_option_binding *b = spec->bind;
    if (!b)
        return vv_error_set(VV_ERR_UNSUPPORTED, "%s: option bound to no field", spec->key);
    unsigned char *field = (unsigned char *)state + b->offset;
    unsigned char small[64], *old = NULL;
    const size_t bytes = b->store == VV_OPTION_STORE_NONE ? 0 : b->size;
    if (b->hook && bytes) {
        old = bytes <= sizeof small ? small : malloc(bytes);
        if (!old)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        memcpy(old, field, bytes);
    }
    s = option_store(field, spec, b, &v);
    if (s == VV_OK && b->hook && (s = b->hook(state, spec, &v)) != VV_OK && old)
        memcpy(field, old, bytes);
    if (old != small)
        free(old);
    return s;
}

/* ---- renderer objects ---------------------------------------------------------- */

/* Frees a method's state (release first). */
static void
state_free(const vv_renderer_ops *ops, void *state) {
    if (!state)
        return;
    if (ops->release)
        ops->release(state);
    free(state);
}

/* A new state of @p ops: zeroed, init, every option at its default. */
static vv_status
state_new(const vv_renderer_ops *ops, void **out) {
    *out = NULL;
    void *st = calloc(1, ops->state_size ? ops->state_size : 1);
    if (!st)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = ops->init ? ops->init(st) : VV_OK;
    for (int i = 0; s == VV_OK && i < ops->info.n_options; i++) {
        const vv_option_spec *spec = &ops->info.options[i];
        if ((s = option_apply(st, spec, spec->def)) != VV_OK)
            vv_error_prefix(s, "default of %s", spec->key);
    }
    if (s != VV_OK) {
        state_free(ops, st);
        return s;
    }
    *out = st;
    return VV_OK;
}

vv_status
vv_renderer_new(vv_renderer **out, const char *name) {
    *out = NULL;
    name = current_name(name);
    for (int i = 0; name && registry[i]; i++) {
        if (strcmp(registry[i]->info.name, name) != 0)
            continue;
        if (registry[i]->version != VV_RENDERER_OPS_VERSION)
            return vv_error_set(VV_ERR_UNSUPPORTED, "renderer '%s': interface version %d, not %d",
                                name, registry[i]->version, VV_RENDERER_OPS_VERSION);
        vv_renderer *r = calloc(1, sizeof *r);
        if (!r)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        r->ops = registry[i];
        vv_status s = state_new(r->ops, &r->state);
        if (s != VV_OK) {
            free(r);
            return vv_error_prefix(s, "%s", name);
        }
        *out = r;
        return VV_OK;
    }
    char known[256] = "";
    for (int i = 0; registry[i]; i++)
        append(known, sizeof known, i ? ", %s" : "%s", registry[i]->info.name, 0);
    return vv_error_set(VV_ERR_INVALID, "unknown renderer '%s' (available: %s)",
                        name ? name : "(null)", known);
}

void
vv_renderer_free(vv_renderer *r) {
    if (!r)
        return;
    state_free(r->ops, r->state);
    vv_renderer_free(r->stand_in);
    for (int i = 0; i < r->n_opts; i++)
        free(r->opts[i].value);
    free(r->opts);
    free(r);
}

/* Keeps @p value as the option @p key's (vv_renderer_clone). */
static vv_status
remember_option(vv_renderer *r, const char *key, const char *value) {
    char *v = strdup(value);
    if (!v)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < r->n_opts; i++)
        if (r->opts[i].key == key) {
            free(r->opts[i].value);
            r->opts[i].value = v;
            return VV_OK;
        }
    rn_option *o = realloc(r->opts, sizeof *o * (size_t)(r->n_opts + 1));
    if (!o) {
        free(v);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    r->opts = o;
    r->opts[r->n_opts++] = (rn_option){key, v};
    return VV_OK;
}

vv_status
vv_renderer_clone(vv_renderer **out, const vv_renderer *r) {
    if (!out || !r)
        return vv_error_set(VV_ERR_INVALID, "clone: NULL renderer");
    vv_status s = vv_renderer_new(out, r->ops->info.name);
    for (int i = 0; i < r->n_opts && s == VV_OK; i++)
        s = vv_renderer_set_option(*out, r->opts[i].key, r->opts[i].value);
    if (s != VV_OK) {
        vv_renderer_free(*out);
        *out = NULL;
    }
    return s;
}

const char *
vv_renderer_name(const vv_renderer *r) {
    return r->ops->info.name;
}

const vv_renderer_info *
vv_renderer_get_info(const vv_renderer *r) {
    return &r->ops->info;
}

const vv_renderer_ops *
vv_renderer_ops_of(const vv_renderer *r) {
    return r->ops;
}

void *
vv_renderer_state(const vv_renderer *r) {
    return r->state;
}

vv_status
vv_renderer_set_option(vv_renderer *r, const char *key, const char *value) {
    if (!r || !key || !value)
        return vv_error_set(VV_ERR_INVALID, "set option: NULL argument");
    const vv_option_spec *spec = vv_renderer_info_option(&r->ops->info, key);
    vv_status s;
    if (!spec) {
        s = unknown_key(&r->ops->info, key);
    } else {
        s = option_apply(r->state, spec, value);
        if (s == VV_OK)
            s = remember_option(r, spec->key, value);
    }
    return s == VV_OK ? s : vv_error_prefix(s, "%s", r->ops->info.name);
}

/* The drivers' clones of a renderer (drv_renderer.clone): a vv_renderer of
 * the same method and options (vv_renderer_clone). */
static vv_status
driven_clone(const drv_renderer *d, drv_renderer *out) {
    vv_renderer *c = NULL;
    vv_status s = vv_renderer_clone(&c, d->user);
    if (s == VV_OK)
        drv_renderer_of(c, out);
    else
        *out = (drv_renderer){0};
    return s;
}

static void
driven_release(drv_renderer *d) {
    vv_renderer_free(d->user);
    *d = (drv_renderer){0};
}

const drv_renderer *
drv_renderer_of(vv_renderer *r, drv_renderer *out) {
    *out = (drv_renderer){.ops = r->ops,
                          .state = r->state,
                          .clone = driven_clone,
                          .release = driven_release,
                          .user = r};
    return out;
}

/* @p w with every object's file out of core dropped (vv_object_set_volume
 * of its own proxy, which its volume already is): the proxies drawn in
 * memory. */
static vv_status
proxies_in_memory(const vv_world *w, vv_world **out) {
    vv_status s = vv_world_clone(out, w);
    for (int i = 0; s == VV_OK && i < (*out)->n_objects; i++) {
        vv_object *o = (*out)->objects[i];
        if (o->type == VV_OBJECT_VOLUME && o->source && o->volume &&
            vv_source_get_kind(o->source) != VV_SOURCE_MEMORY)
            vv_object_drop_source(o);
    }
    if (s != VV_OK) {
        vv_world_free(*out);
        *out = NULL;
    }
    return s;
}

size_t
vv_pixels8_bytes(int format, int width, int height) {
    if (width < 1 || height < 1)
        return 0;
    const size_t pw = (size_t)width + (size_t)(width & 1),
                 ph = (size_t)height + (size_t)(height & 1);
    switch (format) {
    case VV_PIXELS8_RGBX:
        return 4 * (size_t)width * (size_t)height;
    case VV_PIXELS8_YUV420:
        return pw * ph + 2 * (pw / 2) * (ph / 2);
    default:
        return 0;
    }
}

/* @p img in 8 bits in p8 (vv_pixels8's conversion, its format), rows (pairs
 * of rows for YUV 4:2:0) on @p threads threads. */
static void
pixels8_of(const vv_image *img, vv_pixels8 *p8, int threads) {
    const int nt = threads > 0 ? threads : vv_threads_get();
    const int W = img->width, H = img->height;
    if (p8->format == VV_PIXELS8_YUV420) {
#pragma omp parallel for schedule(static) num_threads(nt)
        for (int y = 0; y < H; y += 2)
            vv_image_rect_to_yuv420(img, 0, y, W, y + 2 < H ? y + 2 : H, p8->yuv);
        return;
    }
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int y = 0; y < H; y++)
        vv_image_rect_to_rgbx8(img, 0, y, W, y + 1, p8->rgbx);
}

static vv_status render_method(vv_renderer *r, const vv_world *world, const vv_view *view,
                               const vv_render_options *opt, vv_image *out);

vv_status
vv_renderer_render(vv_renderer *r, const vv_world *world, const vv_view *view,
                   const vv_render_options *opt, vv_image *out) {
    vv_render_options def;
    if (!opt) {
        vv_render_options_init(&def);
        opt = &def;
    }
    if (!r || !world || !view || !out)
        return vv_error_set(VV_ERR_INVALID, "render: NULL renderer, world, view or image");
    if (out->width != view->width || out->height != view->height)
        return vv_error_set(VV_ERR_INVALID, "render: image is %d x %d but the view is %d x %d",
                            out->width, out->height, view->width, view->height);
    vv_pixels8 *p8 = opt->pixels8;
    if (p8 &&
        (p8->format == VV_PIXELS8_YUV420 ? !p8->yuv : p8->format != VV_PIXELS8_RGBX || !p8->rgbx))
        return vv_error_set(VV_ERR_INVALID,
                            "render: 8-bit pixels of format %d: no buffer for it, or no such "
                            "format (%d RGBX, %d YUV 4:2:0)",
                            p8->format, VV_PIXELS8_RGBX, VV_PIXELS8_YUV420);
    if (p8 && (p8->width != view->width || p8->height != view->height))
        return vv_error_set(VV_ERR_INVALID,
                            "render: 8-bit pixels of %d x %d but the view is %d x %d", p8->width,
                            p8->height, view->width, view->height);
    if (p8) {
        /* the method's own frame converts its tiles (frame runner); the
         * drivers' composites and other methods' frames are converted here */
        p8->converted_in_tiles = 0;
        vv_status s = render_method(r, world, view, opt, out);
        if (s == VV_OK && !p8->converted_in_tiles)
            pixels8_of(out, p8, opt->threads);
        return s;
    }
    return render_method(r, world, view, opt, out);
}

/* vv_renderer_render's work; opt->pixels8 reaches only the method's own
 * whole frame of @p out. */
static vv_status
render_method(vv_renderer *r, const vv_world *world, const vv_view *view,
              const vv_render_options *opt, vv_image *out) {
    vv_render_options no8 = *opt;
    no8.pixels8 = NULL;
    vv_status s = vv_renderer_check_world(&r->ops->info, world);
    vv_world *proxies = NULL;
    if (s == VV_OK && drv_world_out_of_core(world)) {
        /* objects out of core: object by object through the region
         * contract (its errors name their driver: "bricks:", "sources:") */
        vv_lod own;
        vv_lod *lod = opt->lod;
        if (!lod) {
            vv_lod_init(&own);
            lod = &own;
        }
        lod->note[0] = '\0';
        drv_renderer dr;
        s = drv_render_sources(drv_renderer_of(r, &dr), world, view, &no8, lod, out);
        if (s != VV_ERR_UNSUPPORTED || !opt->proxy_fallback)
            return s;
        /* the renderer, not the front end, falls back: the proxies in memory */
        snprintf(lod->note, sizeof lod->note, "%s", vv_error_message());
        vv_error_clear();
        if ((s = proxies_in_memory(world, &proxies)) != VV_OK)
            return s;
        world = proxies;
    }
    const char *stand_in = NULL;
    const vv_world *draw = NULL;
    if (s == VV_OK && r->ops->stand_in)
        s = r->ops->stand_in(r->state, world, opt, &stand_in, &draw);
    if (s == VV_OK && stand_in) {
        /* the frame drawn by another method, from the World this one made */
        if (!strcmp(stand_in, r->ops->info.name) || !draw)
            s = vv_error_set(VV_ERR_INVALID, "stands in for itself, or with no World");
        if (s == VV_OK && r->stand_in && strcmp(r->stand_in->ops->info.name, stand_in)) {
            vv_renderer_free(r->stand_in);
            r->stand_in = NULL;
        }
        if (s == VV_OK && !r->stand_in)
            s = vv_renderer_new(&r->stand_in, stand_in);
        if (s == VV_OK)
            s = vv_renderer_render(r->stand_in, draw, view, &no8, out);
    } else if (s == VV_OK) {
        s = r->ops->render(r->state, world, view, opt, out);
    }
    vv_world_free(proxies);
    return s == VV_OK ? s : vv_error_prefix(s, "%s", r->ops->info.name);
}

vv_status
vv_renderer_render_region(vv_renderer *r, const vv_world *world, const vv_view *view,
                          const vv_render_region *region, const vv_render_options *opt,
                          vv_region_image *out) {
    if (!r)
        return vv_error_set(VV_ERR_INVALID, "region render: NULL argument");
    return drv_render_region(r->ops, r->state, world, view, region, opt, out);
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

vv_status
vv_renderer_new_for_world(vv_renderer **out, const vv_world *w) {
    if (!out || !w)
        return vv_error_set(VV_ERR_INVALID, "renderer: NULL argument");
    *out = NULL;
    vv_renderer *r = NULL;
    vv_status s = vv_renderer_new(&r, vv_world_renderer(w));
    /* the settings' options belong to the World's renderer */
    if (s == VV_OK)
        s = vv_renderer_apply_settings(r, &w->render);
    if (s != VV_OK) {
        vv_renderer_free(r);
        return s;
    }
    *out = r;
    return VV_OK;
}
