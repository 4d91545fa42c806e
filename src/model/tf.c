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
