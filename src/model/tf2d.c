/*
 * 2-D transfer functions over data value x gradient magnitude (Kniss,
 * Kindlmann and Hansen, "Multidimensional transfer functions for
 * interactive volume rendering", IEEE TVCG 2002): rectangle and triangle
 * widgets combined as independent absorbers.
 */
#include <math.h>
#include <string.h>

#include "volvis/model.h"

void
vv_tf2d_init(vv_tf2d *tf) {
    if (!tf)
        return;
    memset(tf, 0, sizeof *tf);
    tf->opacity_unit_distance = 1.0;
}

void
vv_tf2d_widget_init_rectangle(vv_tf2d_widget *w, double v0, double v1, double g0, double g1,
                              vv_vec3 color, double opacity) {
    memset(w, 0, sizeof *w);
    w->shape = VV_TF2D_RECTANGLE;
    w->value[0] = v0;
    w->value[1] = v1;
    w->gradient[0] = g0;
    w->gradient[1] = g1;
    w->center = 0.5 * (v0 + v1);
    w->width = v1 - v0;
    w->color = color;
    w->opacity = opacity;
}

void
vv_tf2d_widget_init_triangle(vv_tf2d_widget *w, double center, double width, double g1,
                             vv_vec3 color, double opacity) {
    memset(w, 0, sizeof *w);
    w->shape = VV_TF2D_TRIANGLE;
    w->center = center;
    w->width = width;
    w->value[0] = center - 0.5 * width;
    w->value[1] = center + 0.5 * width;
    w->gradient[0] = 0.0;
    w->gradient[1] = g1;
    w->color = color;
    w->opacity = opacity;
}

static int
unit_ok(double x) {
    return x >= 0.0 && x <= 1.0;
}

vv_status
vv_tf2d_widget_check(const vv_tf2d_widget *w) {
    if (!w)
        return vv_error_set(VV_ERR_INVALID, "2-D transfer function: NULL widget");
    const double p[] = {w->value[0],      w->value[1], w->gradient[0], w->gradient[1], w->ramp,
                        w->gradient_ramp, w->center,   w->width,       w->opacity};
    static const char *const names[] = {"value[0]",    "value[1]", "gradient[0]",
                                        "gradient[1]", "ramp",     "gradient_ramp",
                                        "center",      "width",    "opacity"};
    for (size_t i = 0; i < sizeof p / sizeof p[0]; i++)
        if (!isfinite(p[i]))
            return vv_error_set(VV_ERR_INVALID, "2-D transfer function widget: %s is not finite",
                                names[i]);
    if (w->shape != VV_TF2D_RECTANGLE && w->shape != VV_TF2D_TRIANGLE)
        return vv_error_set(VV_ERR_INVALID, "2-D transfer function widget: unknown shape %d",
                            (int)w->shape);
    if (!(w->gradient[0] >= 0.0 && w->gradient[0] <= w->gradient[1]))
        return vv_error_set(VV_ERR_INVALID,
                            "2-D transfer function widget: gradient range [%g, %g] must have "
                            "0 <= lo <= hi",
                            w->gradient[0], w->gradient[1]);
    if (w->shape == VV_TF2D_RECTANGLE) {
        if (!(w->value[0] <= w->value[1]))
            return vv_error_set(VV_ERR_INVALID,
                                "2-D transfer function widget: value range [%g, %g] is reversed",
                                w->value[0], w->value[1]);
        if (!(w->ramp >= 0.0) || !(w->gradient_ramp >= 0.0))
            return vv_error_set(VV_ERR_INVALID, "2-D transfer function widget: negative ramp");
    } else {
        if (!(w->width > 0.0))
            return vv_error_set(VV_ERR_INVALID,
                                "2-D transfer function widget: triangle width %g must be > 0",
                                w->width);
        if (!(w->gradient[1] > 0.0))
            return vv_error_set(VV_ERR_INVALID,
                                "2-D transfer function widget: triangle gradient[1] must be > 0");
    }
    if (!unit_ok(w->opacity))
        return vv_error_set(VV_ERR_INVALID,
                            "2-D transfer function widget: opacity %g is outside [0, 1]",
                            w->opacity);
    if (!unit_ok(w->color.x) || !unit_ok(w->color.y) || !unit_ok(w->color.z))
        return vv_error_set(VV_ERR_INVALID,
                            "2-D transfer function widget: colour (%g, %g, %g) is outside [0, 1]",
                            w->color.x, w->color.y, w->color.z);
    return VV_OK;
}

vv_status
vv_tf2d_add_widget(vv_tf2d *tf, const vv_tf2d_widget *w) {
    if (!tf)
        return vv_error_set(VV_ERR_INVALID, "2-D transfer function: NULL");
    vv_status st = vv_tf2d_widget_check(w);
    if (st != VV_OK)
        return st;
    if (tf->n_widgets >= VV_TF2D_MAX_WIDGETS)
        return vv_error_set(VV_ERR_LIMIT, "2-D transfer function: more than %d widgets",
                            VV_TF2D_MAX_WIDGETS);
    tf->widgets[tf->n_widgets++] = *w;
    return VV_OK;
}

/* 1 inside [lo, hi] farther than ramp from both edges, falling linearly to
 * 0 at the edges; 0 outside. */
static double
soft_box(double x, double lo, double hi, double ramp) {
    if (!(x >= lo && x <= hi))
        return 0.0;
    if (!(ramp > 0.0))
        return 1.0;
    double d = fmin(x - lo, hi - x) / ramp;
    return d >= 1.0 ? 1.0 : d;
}

double
vv_tf2d_widget_opacity(const vv_tf2d_widget *w, double value, double gradient) {
    if (!w || isnan(value) || isnan(gradient))
        return 0.0;
    if (w->shape == VV_TF2D_RECTANGLE)
        return w->opacity * soft_box(value, w->value[0], w->value[1], w->ramp) *
               soft_box(gradient, w->gradient[0], w->gradient[1], w->gradient_ramp);
    if (!(gradient >= w->gradient[0] && gradient <= w->gradient[1]) || !(w->gradient[1] > 0))
        return 0.0;
    double half = 0.5 * w->width * gradient / w->gradient[1];
    double d = fabs(value - w->center);
    if (!(half > 0.0))
        return d == 0.0 ? w->opacity : 0.0;
    return d >= half ? 0.0 : w->opacity * (1.0 - d / half);
}

void
vv_tf2d_eval(const vv_tf2d *tf, double value, double gradient, double *opacity, vv_vec3 *color) {
    double keep = 1.0, wsum = 0.0;
    vv_vec3 c = {0, 0, 0};
    if (tf)
        for (int i = 0; i < tf->n_widgets; i++) {
            const vv_tf2d_widget *w = &tf->widgets[i];
            double a = vv_tf2d_widget_opacity(w, value, gradient);
            if (!(a > 0.0))
                continue;
            keep *= 1.0 - a;
            wsum += a;
            c = vv_vec3_add(c, vv_vec3_scale(w->color, a));
        }
    if (opacity)
        *opacity = wsum > 0.0 ? 1.0 - keep : 0.0;
    if (color)
        *color = wsum > 0.0 ? vv_vec3_scale(c, 1.0 / wsum) : vv_vec3_make(1, 1, 1);
}

double
vv_tf2d_gradient_max(const vv_tf2d *tf) {
    double g = 0.0;
    if (tf)
        for (int i = 0; i < tf->n_widgets; i++)
            g = fmax(g, tf->widgets[i].gradient[1]);
    return g;
}
