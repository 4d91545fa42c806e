/*
 * Flight paths (VolVis paper, section 4: a path flown in the Navigator can
 * be replayed by the Animator): the camera sampled while the user flies,
 * thinned to editable keyframes by a Douglas–Peucker-like split on the
 * eye and look-at positions, the camera orientation and the field of view.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "volvis/animate.h"

typedef struct sample {
    double time;
    vv_view view;
    vv_quat q; /* camera orientation */
} sample;

struct vv_flight_recorder {
    int n, cap;
    sample *s;
};

vv_status
vv_flight_recorder_new(vv_flight_recorder **out) {
    *out = calloc(1, sizeof **out);
    return *out ? VV_OK : vv_error_set(VV_ERR_NOMEM, "flight recorder: out of memory");
}

void
vv_flight_recorder_free(vv_flight_recorder *r) {
    if (!r)
        return;
    free(r->s);
    free(r);
}

int
vv_flight_recorder_count(const vv_flight_recorder *r) {
    return r ? r->n : 0;
}

/* The camera's rotation: columns right, true up, -forward (vv_view_ray's basis). */
static vv_quat
view_quat(const vv_view *v) {
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(v->at, v->eye));
    vv_vec3 r = vv_vec3_cross(f, v->up);
    if (!(vv_vec3_length(r) > 1e-12))
        r = vv_vec3_cross(f, fabs(f.z) < 0.9 ? vv_vec3_make(0, 0, 1) : vv_vec3_make(1, 0, 0));
    r = vv_vec3_normalize(r);
    vv_vec3 u = vv_vec3_cross(r, f);
    double m[3][3] = {{r.x, u.x, -f.x}, {r.y, u.y, -f.y}, {r.z, u.z, -f.z}};
    double tr = m[0][0] + m[1][1] + m[2][2];
    vv_quat q;
    if (tr > 0) {
        double s = sqrt(tr + 1) * 2;
        q.w = s / 4;
        q.x = (m[2][1] - m[1][2]) / s;
        q.y = (m[0][2] - m[2][0]) / s;
        q.z = (m[1][0] - m[0][1]) / s;
    } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
        double s = sqrt(1 + m[0][0] - m[1][1] - m[2][2]) * 2;
        q.w = (m[2][1] - m[1][2]) / s;
        q.x = s / 4;
        q.y = (m[0][1] + m[1][0]) / s;
        q.z = (m[0][2] + m[2][0]) / s;
    } else if (m[1][1] > m[2][2]) {
        double s = sqrt(1 + m[1][1] - m[0][0] - m[2][2]) * 2;
        q.w = (m[0][2] - m[2][0]) / s;
        q.x = (m[0][1] + m[1][0]) / s;
        q.y = s / 4;
        q.z = (m[1][2] + m[2][1]) / s;
    } else {
        double s = sqrt(1 + m[2][2] - m[0][0] - m[1][1]) * 2;
        q.w = (m[1][0] - m[0][1]) / s;
        q.x = (m[0][2] + m[2][0]) / s;
        q.y = (m[1][2] + m[2][1]) / s;
        q.z = s / 4;
    }
    return vv_quat_normalize(q);
}

vv_status
vv_flight_recorder_add(vv_flight_recorder *r, double time, const vv_view *view) {
    if (!r || !view || !isfinite(time))
        return vv_error_set(VV_ERR_INVALID, "flight recorder: bad sample");
    if (!isfinite(vv_vec3_length(view->eye)) || !isfinite(vv_vec3_length(view->at)) ||
        !isfinite(vv_vec3_length(view->up)) || !isfinite(view->fov) ||
        !(vv_vec3_length(vv_vec3_sub(view->at, view->eye)) > 0))
        return vv_error_set(VV_ERR_INVALID,
                            "flight recorder: sample at %g s: the view is not finite "
                            "or its eye is at its look-at point",
                            time);
    if (r->n > 0 && !(time > r->s[r->n - 1].time))
        return vv_error_set(VV_ERR_INVALID, "flight recorder: sample time %g is not after %g", time,
                            r->s[r->n - 1].time);
    if (r->n == r->cap) {
        int cap = r->cap ? 2 * r->cap : 256;
        sample *ns = realloc(r->s, sizeof *ns * (size_t)cap);
        if (!ns)
            return vv_error_set(VV_ERR_NOMEM, "flight recorder: out of memory");
        r->s = ns;
        r->cap = cap;
    }
    sample *s = &r->s[r->n++];
    s->time = time;
    s->view = *view;
    s->q = view_quat(view);
    return VV_OK;
}

static double
quat_angle(vv_quat a, vv_quat b) {
    double d = fabs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
    return 2 * acos(d > 1 ? 1 : d);
}

/* How far sample i is from the straight path between samples a and b, in
 * units of the tolerances (> 1: keep it). */
static double
deviation(const sample *s, int a, int b, int i, double ptol, double atol) {
    double u = (s[i].time - s[a].time) / (s[b].time - s[a].time);
    vv_vec3 eye = vv_vec3_lerp(s[a].view.eye, s[b].view.eye, u);
    vv_vec3 at = vv_vec3_lerp(s[a].view.at, s[b].view.at, u);
    vv_quat q = vv_quat_slerp(s[a].q, s[b].q, u);
    double fov = s[a].view.fov + u * (s[b].view.fov - s[a].view.fov);
    double dp = fmax(vv_vec3_length(vv_vec3_sub(eye, s[i].view.eye)),
                     vv_vec3_length(vv_vec3_sub(at, s[i].view.at)));
    double da = fmax(quat_angle(q, s[i].q), fabs(fov - s[i].view.fov));
    double ep = ptol > 0 ? dp / ptol : (dp > 1e-12 ? INFINITY : 0);
    double ea = atol > 0 ? da / atol : (da > 1e-12 ? INFINITY : 0);
    return fmax(ep, ea);
}

vv_status
vv_flight_recorder_finish(const vv_flight_recorder *r, double position_tolerance,
                          double angle_tolerance, double fps, vv_animation **out) {
    *out = NULL;
    if (!r || r->n < 2)
        return vv_error_set(VV_ERR_INVALID,
                            "flight recorder: a flight path needs 2 samples or more");
    if (!(position_tolerance >= 0) || !(angle_tolerance >= 0) || !(fps > 0 && fps <= 1000))
        return vv_error_set(VV_ERR_INVALID,
                            "flight recorder: tolerances must be >= 0 and fps in (0, 1000]");
    int n = r->n;
    const sample *s = r->s;
    char *keep = calloc((size_t)n, 1);
    int *stack = malloc(sizeof *stack * 2 * (size_t)n);
    if (!keep || !stack) {
        free(keep);
        free(stack);
        return vv_error_set(VV_ERR_NOMEM, "flight recorder: out of memory");
    }
    keep[0] = keep[n - 1] = 1;
    int top = 0;
    stack[top++] = 0;
    stack[top++] = n - 1;
    while (top > 0) {
        int b = stack[--top], a = stack[--top];
        int worst = -1;
        double wd = 1;
        for (int i = a + 1; i < b; i++) {
            double d = deviation(s, a, b, i, position_tolerance, angle_tolerance);
            if (d > wd) {
                wd = d;
                worst = i;
            }
        }
        if (worst >= 0) {
            keep[worst] = 1;
            stack[top++] = a;
            stack[top++] = worst;
            stack[top++] = worst;
            stack[top++] = b;
        }
    }
    free(stack);
    int fov_changes = 0;
    for (int i = 1; i < n; i++)
        fov_changes |= s[i].view.fov != s[0].view.fov;
    vv_animation *a;
    vv_status st = vv_animation_new(&a);
    const char *props[4] = {"view.eye", "view.at", "view.up", "view.fov"};
    for (int p = 0; p < (fov_changes ? 4 : 3) && st == VV_OK; p++) {
        int ti;
        if ((st = vv_animation_add_track(a, props[p], &ti)) != VV_OK)
            break;
        for (int i = 0; i < n && st == VV_OK; i++) {
            if (!keep[i])
                continue;
            vv_anim_key k;
            vv_anim_key_init(&k, s[i].time - s[0].time);
            vv_vec3 v = p == 0 ? s[i].view.eye : (p == 1 ? s[i].view.at : s[i].view.up);
            k.value[0] = v.x, k.value[1] = v.y, k.value[2] = v.z;
            if (p == 3)
                k.value[0] = s[i].view.fov;
            st = vv_anim_track_add_key(&a->tracks[ti], &k);
        }
    }
    free(keep);
    if (st != VV_OK) {
        vv_animation_free(a);
        return st;
    }
    a->fps = fps;
    a->duration = s[n - 1].time - s[0].time + 1 / fps;
    *out = a;
    return VV_OK;
}
