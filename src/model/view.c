/*
 * Views (cameras): primary rays, framing a box, orbiting. The paper's
 * "view" of the abstract model (section 3).
 */
#include <math.h>

#include "volvis/model.h"

/* Orthonormal camera basis. forward = normalize(at - eye), right =
 * normalize(forward x up), up = right x forward. Degenerate inputs (eye ==
 * at, up parallel to the view direction) fall back to +y forward and +z (or
 * +x) up so that a ray is always defined. */
static void
view_basis(const vv_view *v, vv_vec3 *f, vv_vec3 *r, vv_vec3 *u) {
    vv_vec3 fw = vv_vec3_normalize(vv_vec3_sub(v->at, v->eye));
    if (!(vv_vec3_length(fw) > 0.5))
        fw = vv_vec3_make(0, 1, 0);
    vv_vec3 rt = vv_vec3_normalize(vv_vec3_cross(fw, v->up));
    if (!(vv_vec3_length(rt) > 0.5)) {
        vv_vec3 alt = fabs(fw.z) < 0.9 ? vv_vec3_make(0, 0, 1) : vv_vec3_make(1, 0, 0);
        rt = vv_vec3_normalize(vv_vec3_cross(fw, alt));
    }
    *f = fw;
    *r = rt;
    *u = vv_vec3_cross(rt, fw);
}

static double
view_aspect(const vv_view *v) {
    int w = v->width > 0 ? v->width : 1;
    int h = v->height > 0 ? v->height : 1;
    return (double)w / (double)h;
}

vv_ray
vv_view_ray(const vv_view *view, double px, double py) {
    vv_ray ray;
    vv_vec3 f, r, u;
    view_basis(view, &f, &r, &u);
    int w = view->width > 0 ? view->width : 1;
    int h = view->height > 0 ? view->height : 1;
    double aspect = view_aspect(view);
    /* normalised device coordinates in [-1, 1], +y up */
    double x = 2.0 * (px + 0.5) / w - 1.0;
    double y = 1.0 - 2.0 * (py + 0.5) / h;
    if (view->projection == VV_PROJECTION_ORTHOGRAPHIC) {
        double half_h = 0.5 * view->ortho_height;
        double half_w = half_h * aspect;
        ray.origin = vv_vec3_add(
            view->eye, vv_vec3_add(vv_vec3_scale(r, x * half_w), vv_vec3_scale(u, y * half_h)));
        ray.dir = f;
    } else {
        double t = tan(0.5 * view->fov);
        ray.origin = view->eye;
        ray.dir = vv_vec3_normalize(
            vv_vec3_add(f, vv_vec3_add(vv_vec3_scale(r, x * t * aspect), vv_vec3_scale(u, y * t))));
    }
    return ray;
}

void
vv_view_frame_box(vv_view *view, vv_box box) {
    vv_vec3 f, r, u;
    view_basis(view, &f, &r, &u);
    vv_vec3 c = vv_vec3_scale(vv_vec3_add(box.min, box.max), 0.5);
    double radius = 0.5 * vv_vec3_length(vv_vec3_sub(box.max, box.min));
    if (!(radius > 0.0) || !isfinite(radius))
        radius = 1.0;
    double aspect = view_aspect(view);
    double dist;
    if (view->projection == VV_PROJECTION_ORTHOGRAPHIC) {
        /* both the height and the width (height * aspect) must hold 2r */
        view->ortho_height = 2.0 * radius / (aspect < 1.0 ? aspect : 1.0);
        dist = 2.0 * radius;
    } else {
        double fov = view->fov;
        if (!(fov > 0.0 && fov < VV_PI))
            fov = vv_deg_to_rad(30.0);
        double half_v = 0.5 * fov;
        double half_h = atan(tan(half_v) * aspect);
        double half = half_v < half_h ? half_v : half_h;
        /* a sphere of radius r at distance d subtends asin(r / d) */
        dist = radius / sin(half);
    }
    view->at = c;
    view->eye = vv_vec3_sub(c, vv_vec3_scale(f, dist));
    (void)u;
}

void
vv_view_orbit(vv_view *view, double azimuth, double elevation) {
    vv_vec3 f, r, u;
    view_basis(view, &f, &r, &u);
    vv_vec3 off = vv_vec3_sub(view->eye, view->at);
    double dist = vv_vec3_length(off);
    if (!(dist > 0.0)) {
        dist = 1.0;
        off = vv_vec3_scale(f, -1.0);
    }
    vv_vec3 axis_up = vv_vec3_normalize(view->up);
    if (!(vv_vec3_length(axis_up) > 0.5))
        axis_up = u;
    /* azimuth: about the up vector */
    vv_quat qa = vv_quat_from_axis_angle(axis_up, azimuth);
    off = vv_quat_rotate(qa, off);
    vv_vec3 up = vv_quat_rotate(qa, view->up);
    /* elevation: about the (rotated) right axis, moving the eye towards up;
     * the up vector turns with it so the view never degenerates at a pole */
    vv_vec3 right = vv_quat_rotate(qa, r);
    vv_quat qe = vv_quat_from_axis_angle(right, -elevation);
    off = vv_quat_rotate(qe, off);
    up = vv_quat_rotate(qe, up);
    off = vv_vec3_scale(vv_vec3_normalize(off), dist);
    view->eye = vv_vec3_add(view->at, off);
    view->up = up;
}
