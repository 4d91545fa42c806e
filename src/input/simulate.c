/*
 * Simulation methods as pure functions: the direct mapping (dead zone and
 * response curve), the dominant-axis filter, snap-dragging and the two-hand
 * gesture solver (VolVis, Avila et al. 1994, sec. 6), and the name tables.
 */
#include <math.h>
#include <string.h>

#include "input_internal.h"

static const char *const kind_names[VV_INPUT_KIND_COUNT] = {
    "keyboard", "mouse", "spaceball", "gamecontroller", "dataglove", "network"};

const char *
vv_input_kind_name(vv_input_kind k) {
    return (unsigned)k < VV_INPUT_KIND_COUNT ? kind_names[k] : "unknown";
}

vv_status
vv_input_kind_parse(const char *name, vv_input_kind *out) {
    for (int i = 0; name && i < VV_INPUT_KIND_COUNT; i++)
        if (strcmp(name, kind_names[i]) == 0) {
            *out = (vv_input_kind)i;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_INVALID,
                        "unknown device kind '%s' (keyboard, mouse, spaceball, gamecontroller, "
                        "dataglove, network)",
                        name ? name : "(null)");
}

static const char *const raw_names[VV_RAW_KIND_COUNT] = {
    "key", "button", "pointer", "scroll", "axis", "motion6", "pose", "added", "removed"};
static const int raw_values[VV_RAW_KIND_COUNT] = {1, 1, 2, 2, 1, 7, 7, 0, 0};

const char *
vv_input_raw_kind_name(vv_input_raw_kind k) {
    return (unsigned)k < VV_RAW_KIND_COUNT ? raw_names[k] : "unknown";
}

int
vv_input_raw_kind_values(vv_input_raw_kind k) {
    return (unsigned)k < VV_RAW_KIND_COUNT ? raw_values[k] : 0;
}

static const char *const action_names[VV_ACTION_KIND_COUNT] = {
    "motion", "press",     "release",  "click", "command",
    "pose",   "snap-drag", "two-hand", "added", "removed"};

const char *
vv_input_action_kind_name(vv_input_action_kind k) {
    return (unsigned)k < VV_ACTION_KIND_COUNT ? action_names[k] : "unknown";
}

const char *
vv_input_method_name(vv_input_method_kind k) {
    switch (k) {
    case VV_METHOD_DIRECT:
        return "direct";
    case VV_METHOD_SNAP_DRAG:
        return "snap-drag";
    case VV_METHOD_TWO_HAND:
        return "two-hand";
    }
    return "unknown";
}

vv_input_method
vv_input_method_default(void) {
    vv_input_method m;
    memset(&m, 0, sizeof m);
    m.kind = VV_METHOD_DIRECT;
    m.exponent = 1;
    m.gain = 1;
    m.snap_axes = 1;
    m.snap_angle = 15 * VV_PI / 180;
    return m;
}

double
vv_input_response(double x, double dead_zone, double exponent) {
    if (!isfinite(x))
        return 0;
    if (!(dead_zone >= 0) || dead_zone >= 1)
        dead_zone = 0;
    if (!(exponent >= 1) || !isfinite(exponent))
        exponent = 1;
    double a = fabs(x);
    if (a <= dead_zone)
        return 0;
    double t = (a - dead_zone) / (1 - dead_zone);
    if (t > 1)
        t = 1;
    t = exponent == 1 ? t : pow(t, exponent);
    return x < 0 ? -t : t;
}

void
vv_input_dominant_axis(double v[6]) {
    int best = 0;
    for (int i = 1; i < 6; i++)
        if (fabs(v[i]) > fabs(v[best]))
            best = i;
    for (int i = 0; i < 6; i++)
        if (i != best)
            v[i] = 0;
}

static double
round_to(double x, double g) {
    return g * floor(x / g + 0.5);
}

vv_vec3
vv_input_snap(const vv_input_snap_params *p, vv_vec3 start, vv_vec3 pos, int *snapped,
              int *feature) {
    int s = 0, f = -1;
    vv_vec3 out = pos;
    if (p && p->feature_radius > 0 && p->features) {
        double best = p->feature_radius;
        for (int i = 0; i < p->n_features; i++) {
            double d = vv_vec3_length(vv_vec3_sub(p->features[i], pos));
            if (d <= best) {
                best = d;
                f = i;
            }
        }
        if (f >= 0) {
            out = p->features[f];
            s = VV_SNAP_FEATURE;
        }
    }
    if (p && f < 0) {
        vv_vec3 d = vv_vec3_sub(pos, start);
        double len = vv_vec3_length(d);
        int axis = -1;
        if (p->snap_axes && len > 0) {
            double c[3] = {fabs(d.x) / len, fabs(d.y) / len, fabs(d.z) / len};
            int best = c[1] > c[0] ? 1 : 0;
            if (c[2] > c[best])
                best = 2;
            if (c[best] >= cos(p->snap_angle)) {
                axis = best;
                out = start;
                if (axis == 0)
                    out.x = pos.x;
                else if (axis == 1)
                    out.y = pos.y;
                else
                    out.z = pos.z;
                s |= VV_SNAP_AXIS;
            }
        }
        if (p->grid > 0) {
            /* along the snapped axis only when axis-snapped: the drag stays on its line */
            if (axis < 0 || axis == 0)
                out.x = round_to(out.x, p->grid);
            if (axis < 0 || axis == 1)
                out.y = round_to(out.y, p->grid);
            if (axis < 0 || axis == 2)
                out.z = round_to(out.z, p->grid);
            s |= VV_SNAP_GRID;
        }
    }
    if (snapped)
        *snapped = s;
    if (feature)
        *feature = f;
    return out;
}

/* Shortest-arc rotation taking unit u to unit v. */
static vv_quat
quat_between(vv_vec3 u, vv_vec3 v) {
    double d = vv_vec3_dot(u, v);
    if (d < -1 + 1e-12) {
        /* opposite: half turn about any axis perpendicular to u */
        vv_vec3 axis = vv_vec3_cross(u, vv_vec3_make(1, 0, 0));
        if (vv_vec3_length(axis) < 1e-6)
            axis = vv_vec3_cross(u, vv_vec3_make(0, 1, 0));
        return vv_quat_from_axis_angle(axis, VV_PI);
    }
    vv_vec3 c = vv_vec3_cross(u, v);
    vv_quat q = {1 + d, c.x, c.y, c.z};
    return vv_quat_normalize(q);
}

vv_input_two_hand
vv_input_two_hand_solve(vv_vec3 a0, vv_vec3 b0, vv_vec3 a1, vv_vec3 b1) {
    vv_input_two_hand r;
    vv_vec3 m0 = vv_vec3_scale(vv_vec3_add(a0, b0), 0.5);
    vv_vec3 m1 = vv_vec3_scale(vv_vec3_add(a1, b1), 0.5);
    r.translation = vv_vec3_sub(m1, m0);
    r.center = m1;
    vv_vec3 d0 = vv_vec3_sub(b0, a0), d1 = vv_vec3_sub(b1, a1);
    double l0 = vv_vec3_length(d0), l1 = vv_vec3_length(d1);
    if (!(l0 > 1e-12) || !(l1 > 1e-12)) {
        r.rotation = vv_quat_identity();
        r.scale = 1;
        return r;
    }
    r.scale = l1 / l0;
    r.rotation = quat_between(vv_vec3_scale(d0, 1 / l0), vv_vec3_scale(d1, 1 / l1));
    return r;
}
