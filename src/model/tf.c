/*
 * Transfer functions: piecewise-linear opacity and colour of the data value
 * (the paper's "segmentation" of a volume object by a transfer function).
 */
#include <math.h>
#include <string.h>

#include "volvis/model.h"

void
vv_tf_init(vv_tf *tf) {
    if (!tf)
        return;
    memset(tf, 0, sizeof *tf);
    tf->opacity_unit_distance = 1.0;
}

/* Index at which a point of @p value goes: after every point <= value, so
 * that two points at the same value make a step (the later one wins above). */
static int
insert_index_opacity(const vv_tf *tf, double value) {
    int i = tf->n_opacity;
    while (i > 0 && tf->opacity[i - 1].value > value)
        i--;
    return i;
}

static int
insert_index_color(const vv_tf *tf, double value) {
    int i = tf->n_color;
    while (i > 0 && tf->color[i - 1].value > value)
        i--;
    return i;
}

vv_status
vv_tf_add_opacity(vv_tf *tf, double value, double opacity) {
    if (!tf)
        return vv_error_set(VV_ERR_INVALID, "transfer function: NULL");
    if (!isfinite(value))
        return vv_error_set(VV_ERR_INVALID, "transfer function: value %g is not finite", value);
    if (!(opacity >= 0.0 && opacity <= 1.0))
        return vv_error_set(VV_ERR_INVALID, "transfer function: opacity %g is outside [0, 1]",
                            opacity);
    if (tf->n_opacity >= VV_TF_MAX_POINTS)
        return vv_error_set(VV_ERR_LIMIT, "transfer function: more than %d opacity points",
                            VV_TF_MAX_POINTS);
    int i = insert_index_opacity(tf, value);
    memmove(&tf->opacity[i + 1], &tf->opacity[i],
            (size_t)(tf->n_opacity - i) * sizeof tf->opacity[0]);
    tf->opacity[i].value = value;
    tf->opacity[i].opacity = opacity;
    tf->n_opacity++;
    return VV_OK;
}

static int
color_ok(vv_vec3 c) {
    return c.x >= 0.0 && c.x <= 1.0 && c.y >= 0.0 && c.y <= 1.0 && c.z >= 0.0 && c.z <= 1.0;
}

vv_status
vv_tf_add_color(vv_tf *tf, double value, vv_vec3 color) {
    if (!tf)
        return vv_error_set(VV_ERR_INVALID, "transfer function: NULL");
    if (!isfinite(value))
        return vv_error_set(VV_ERR_INVALID, "transfer function: value %g is not finite", value);
    if (!color_ok(color))
        return vv_error_set(VV_ERR_INVALID,
                            "transfer function: colour (%g, %g, %g) is outside [0, 1]", color.x,
                            color.y, color.z);
    if (tf->n_color >= VV_TF_MAX_POINTS)
        return vv_error_set(VV_ERR_LIMIT, "transfer function: more than %d colour points",
                            VV_TF_MAX_POINTS);
    int i = insert_index_color(tf, value);
    memmove(&tf->color[i + 1], &tf->color[i], (size_t)(tf->n_color - i) * sizeof tf->color[0]);
    tf->color[i].value = value;
    tf->color[i].color = color;
    tf->n_color++;
    return VV_OK;
}

/* Last index i with point[i].value <= value, or -1; binary search. */
#define LAST_LE(arr, n, v, out)                                                                    \
    do {                                                                                           \
        int lo_ = 0, hi_ = (n)-1, r_ = -1;                                                         \
        while (lo_ <= hi_) {                                                                       \
            int mid_ = lo_ + (hi_ - lo_) / 2;                                                      \
            if ((arr)[mid_].value <= (v)) {                                                        \
                r_ = mid_;                                                                         \
                lo_ = mid_ + 1;                                                                    \
            } else {                                                                               \
                hi_ = mid_ - 1;                                                                    \
            }                                                                                      \
        }                                                                                          \
        (out) = r_;                                                                                \
    } while (0)

double
vv_tf_eval_opacity(const vv_tf *tf, double value) {
    if (!tf || tf->n_opacity <= 0 || isnan(value))
        return 0.0;
    int n = tf->n_opacity;
    int i;
    LAST_LE(tf->opacity, n, value, i);
    if (i < 0)
        return tf->opacity[0].opacity;
    if (i >= n - 1)
        return tf->opacity[n - 1].opacity;
    /* opacity[i].value <= value < opacity[i + 1].value, so the span is > 0 */
    const vv_tf_opacity_point *a = &tf->opacity[i], *b = &tf->opacity[i + 1];
    double t = (value - a->value) / (b->value - a->value);
    return a->opacity + t * (b->opacity - a->opacity);
}

vv_vec3
vv_label_color(uint32_t label) {
    if (label == 0)
        return vv_vec3_make(0, 0, 0);
    double h = fmod(0.1 + 0.6180339887498949 * (double)(label - 1), 1.0) * 6.0;
    double s = 0.65, v = 0.95;
    int sector = (int)h;
    double f = h - sector, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    switch (sector % 6) {
    case 0:
        return vv_vec3_make(v, t, p);
    case 1:
        return vv_vec3_make(q, v, p);
    case 2:
        return vv_vec3_make(p, v, t);
    case 3:
        return vv_vec3_make(p, q, v);
    case 4:
        return vv_vec3_make(t, p, v);
    default:
        return vv_vec3_make(v, p, q);
    }
}

vv_vec3
vv_tf_eval_color(const vv_tf *tf, double value) {
    if (!tf || tf->n_color <= 0)
        return vv_vec3_make(1.0, 1.0, 1.0);
    int n = tf->n_color;
    if (isnan(value))
        return tf->color[0].color;
    int i;
    LAST_LE(tf->color, n, value, i);
    if (i < 0)
        return tf->color[0].color;
    if (i >= n - 1)
        return tf->color[n - 1].color;
    const vv_tf_color_point *a = &tf->color[i], *b = &tf->color[i + 1];
    double t = (value - a->value) / (b->value - a->value);
    return vv_vec3_lerp(a->color, b->color, t);
}

static double
clamp01(double x) {
    if (!(x > 0.0))
        return 0.0;
    return x > 1.0 ? 1.0 : x;
}

void
vv_tf_set_ramp(vv_tf *tf, double lo, double hi, double max_opacity, vv_vec3 color,
               double unit_distance) {
    if (!tf)
        return;
    vv_tf_init(tf);
    if (isfinite(unit_distance) && unit_distance > 0.0)
        tf->opacity_unit_distance = unit_distance;
    if (!isfinite(lo) || !isfinite(hi))
        return;
    if (hi < lo) {
        double t = lo;
        lo = hi;
        hi = t;
    }
    color.x = clamp01(color.x);
    color.y = clamp01(color.y);
    color.z = clamp01(color.z);
    max_opacity = clamp01(max_opacity);
    tf->opacity[0].value = lo;
    tf->opacity[0].opacity = 0.0;
    tf->opacity[1].value = hi;
    tf->opacity[1].opacity = max_opacity;
    tf->n_opacity = 2;
    tf->color[0].value = lo;
    tf->color[0].color = color;
    tf->color[1].value = hi;
    tf->color[1].color = color;
    tf->n_color = 2;
}

/* ---- presets -------------------------------------------------------------- */

static const char *const preset_names[] = {"ct-bone", "ct-soft-tissue", "mr", NULL};

const char *const *
vv_tf_preset_names(void) {
    return preset_names;
}

/* Maps Hounsfield units onto the volume's values (vv_tf_preset). */
typedef struct hu_map {
    double scale, offset; /* value = scale * HU + offset */
} hu_map;

static hu_map
hu_map_of(const vv_volume *v) {
    hu_map m = {1.0, 0.0};
    if (!v)
        return m;
    double lo = v->range[0], hi = v->range[1];
    if (!isfinite(lo) || !isfinite(hi) || lo < -200.0)
        return m; /* Hounsfield units */
    if (hi >= 1200.0 && hi <= 65535.0) {
        m.offset = 1024.0; /* stored unsigned: HU + 1024 */
        return m;
    }
    if (!(hi > lo))
        hi = lo + 1.0;
    /* [-1024, 3071] HU stretched over the range */
    m.scale = (hi - lo) / 4095.0;
    m.offset = lo + 1024.0 * m.scale;
    return m;
}

typedef struct preset_point {
    double x;
    double a;
    double r, g, b;
} preset_point;

static vv_status
preset_fill(vv_tf *tf, const preset_point *p, int n, hu_map m) {
    for (int i = 0; i < n; i++) {
        double x = m.scale * p[i].x + m.offset;
        vv_status st = vv_tf_add_opacity(tf, x, p[i].a);
        if (st == VV_OK)
            st = vv_tf_add_color(tf, x, vv_vec3_make(p[i].r, p[i].g, p[i].b));
        if (st != VV_OK)
            return st;
    }
    return VV_OK;
}

vv_status
vv_tf_preset(vv_tf *tf, const char *name, const vv_volume *v) {
    if (!tf || !name)
        return vv_error_set(VV_ERR_INVALID, "transfer function preset: NULL %s",
                            tf ? "name" : "transfer function");
    double unit = 1.0;
    if (v) {
        unit = v->spacing[0];
        unit = v->spacing[1] < unit ? v->spacing[1] : unit;
        unit = v->spacing[2] < unit ? v->spacing[2] : unit;
        if (!(unit > 0.0) || !isfinite(unit))
            unit = 1.0;
    }
    vv_tf out;
    vv_tf_init(&out);
    out.opacity_unit_distance = unit;
    vv_status st;
    if (strcmp(name, "ct-bone") == 0) {
        static const preset_point p[] = {{-1024, 0, 0, 0, 0},
                                         {150, 0, 0.55, 0.25, 0.15},
                                         {300, 0.25, 0.85, 0.65, 0.45},
                                         {600, 0.8, 0.95, 0.9, 0.8},
                                         {1500, 1, 1, 1, 0.95}};
        st = preset_fill(&out, p, 5, hu_map_of(v));
    } else if (strcmp(name, "ct-soft-tissue") == 0) {
        static const preset_point p[] = {
            {-1024, 0, 0, 0, 0},           {-600, 0, 0.4, 0.15, 0.1},
            {-400, 0.03, 0.7, 0.35, 0.25}, {-100, 0.03, 0.85, 0.55, 0.45},
            {40, 0.12, 0.9, 0.45, 0.4},    {150, 0.12, 0.9, 0.6, 0.5},
            {300, 0.6, 0.95, 0.9, 0.8},    {1000, 0.95, 1, 1, 0.95}};
        st = preset_fill(&out, p, 8, hu_map_of(v));
    } else if (strcmp(name, "mr") == 0) {
        if (!v)
            return vv_error_set(VV_ERR_INVALID, "transfer function preset mr: needs a volume");
        double lo = vv_volume_quantile(v, 0.5), hi = vv_volume_quantile(v, 0.99);
        if (!isfinite(lo) || !isfinite(hi) || !(hi > lo)) {
            lo = v->range[0];
            hi = v->range[1] > lo ? v->range[1] : lo + 1.0;
        }
        const preset_point p[] = {{lo, 0, 0.3, 0.3, 0.3},
                                  {lo + 0.5 * (hi - lo), 0.3, 0.8, 0.75, 0.7},
                                  {hi, 0.8, 1, 0.95, 0.9}};
        st = preset_fill(&out, p, 3, (hu_map){1.0, 0.0});
    } else {
        return vv_error_set(VV_ERR_INVALID,
                            "transfer function preset \"%s\" is unknown; expected ct-bone, "
                            "ct-soft-tissue or mr",
                            name);
    }
    if (st != VV_OK)
        return vv_error_prefix(st, "transfer function preset %s", name);
    *tf = out;
    return VV_OK;
}
