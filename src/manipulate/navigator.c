/*
 * Navigator manipulation maths: trackball, pan, zoom, flight simulator, and
 * object and light dragging (VolVis paper, section 4, "Navigator"). Every
 * input is sanitised and every result checked, so no input can make the
 * camera NaN.
 */
#include <math.h>
#include <string.h>

#include "volvis/navigator.h"

/* A finite value clamped to [-lim, lim]; NaN becomes 0. */
static double
clampf(double v, double lim) {
    if (!isfinite(v)) {
        if (isnan(v))
            return 0.0;
        return v > 0 ? lim : -lim;
    }
    return v < -lim ? -lim : v > lim ? lim : v;
}

static int
vec_finite(vv_vec3 v) {
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

int
vv_nav_view_valid(const vv_view *v) {
    if (!v || !vec_finite(v->eye) || !vec_finite(v->at) || !vec_finite(v->up))
        return 0;
    if (!isfinite(v->fov) || !isfinite(v->ortho_height))
        return 0;
    vv_vec3 f = vv_vec3_sub(v->at, v->eye);
    double lf = vv_vec3_length(f);
    if (!(lf > 0.0))
        return 0;
    if (!(vv_vec3_length(vv_vec3_cross(f, v->up)) > 1e-12 * lf))
        return 0;
    return 1;
}

/* Camera basis as vv_view_ray uses it. */
static void
basis(const vv_view *v, vv_vec3 *f, vv_vec3 *r, vv_vec3 *u) {
    *f = vv_vec3_normalize(vv_vec3_sub(v->at, v->eye));
    *r = vv_vec3_normalize(vv_vec3_cross(*f, v->up));
    *u = vv_vec3_cross(*r, *f);
}

/* World units per pixel at the look-at distance. */
static double
world_per_pixel(const vv_view *v) {
    int h = v->height > 0 ? v->height : 1;
    if (v->projection == VV_PROJECTION_ORTHOGRAPHIC)
        return v->ortho_height / h;
    double d = vv_vec3_length(vv_vec3_sub(v->at, v->eye));
    return 2.0 * d * tan(0.5 * v->fov) / h;
}

/* Keeps @p v when @p candidate is not a valid camera. */
static void
commit_view(vv_view *v, const vv_view *candidate) {
    if (vv_nav_view_valid(candidate))
        *v = *candidate;
}

/* Radians of trackball rotation per pixel: half a turn over the view height. */
static double
radians_per_pixel(const vv_view *v) {
    int h = v->height > 0 ? v->height : 512;
    return VV_PI / h;
}

void
vv_nav_view_rotate(vv_view *view, double dx, double dy) {
    if (!view || !vv_nav_view_valid(view))
        return;
    dx = clampf(dx, VV_NAV_MAX_PIXELS);
    dy = clampf(dy, VV_NAV_MAX_PIXELS);
    double k = radians_per_pixel(view);
    vv_view c = *view;
    /* The scene follows the mouse: to turn the object's front to the left
     * (dx < 0), the eye orbits to the right, i.e. a positive azimuth about
     * up for a negative dx; dragging down (dy > 0) lifts the eye. */
    vv_view_orbit(&c, -dx * k, dy * k);
    commit_view(view, &c);
}

void
vv_nav_view_pan(vv_view *view, double dx, double dy) {
    if (!view || !vv_nav_view_valid(view))
        return;
    dx = clampf(dx, VV_NAV_MAX_PIXELS);
    dy = clampf(dy, VV_NAV_MAX_PIXELS);
    vv_vec3 f, r, u;
    basis(view, &f, &r, &u);
    double s = world_per_pixel(view);
    /* the scene follows the mouse: the camera moves the other way */
    vv_vec3 d = vv_vec3_add(vv_vec3_scale(r, -dx * s), vv_vec3_scale(u, dy * s));
    vv_view c = *view;
    c.eye = vv_vec3_add(c.eye, d);
    c.at = vv_vec3_add(c.at, d);
    commit_view(view, &c);
}

void
vv_nav_view_zoom(vv_view *view, double factor) {
    if (!view || !vv_nav_view_valid(view) || !isfinite(factor) || !(factor > 0.0))
        return;
    if (factor < 1.0 / 16.0)
        factor = 1.0 / 16.0;
    if (factor > 16.0)
        factor = 16.0;
    vv_view c = *view;
    if (c.projection == VV_PROJECTION_ORTHOGRAPHIC) {
        c.ortho_height /= factor;
        if (!(c.ortho_height > 0.0))
            return;
    } else {
        vv_vec3 off = vv_vec3_sub(c.eye, c.at);
        double d = vv_vec3_length(off);
        double nd = d / factor;
        if (!(nd > 1e-6 * d))
            nd = 1e-6 * d;
        c.eye = vv_vec3_add(c.at, vv_vec3_scale(off, nd / d));
    }
    commit_view(view, &c);
}

void
vv_nav_view_fly(vv_view *view, double yaw, double pitch, double roll, double speed, double dt) {
    if (!view || !vv_nav_view_valid(view))
        return;
    yaw = clampf(yaw, 2 * VV_PI);
    pitch = clampf(pitch, 2 * VV_PI);
    roll = clampf(roll, 2 * VV_PI);
    speed = clampf(speed, 1e9);
    dt = clampf(dt, 1.0);
    if (dt < 0.0)
        dt = 0.0;
    vv_vec3 f, r, u;
    basis(view, &f, &r, &u);
    double dist = vv_vec3_length(vv_vec3_sub(view->at, view->eye));
    /* yaw about up, pitch about right, roll about forward: body axes, like
     * an aircraft; the composition is applied to the basis */
    vv_quat q = vv_quat_from_axis_angle(u, yaw * dt);
    q = vv_quat_mul(vv_quat_from_axis_angle(r, pitch * dt), q);
    q = vv_quat_mul(vv_quat_from_axis_angle(f, roll * dt), q);
    q = vv_quat_normalize(q);
    vv_vec3 nf = vv_quat_rotate(q, f);
    vv_vec3 nu = vv_quat_rotate(q, u);
    vv_view c = *view;
    c.eye = vv_vec3_add(view->eye, vv_vec3_scale(nf, speed * dt));
    c.at = vv_vec3_add(c.eye, vv_vec3_scale(nf, dist));
    c.up = nu;
    commit_view(view, &c);
}

/* ---- objects and lights ---------------------------------------------- */

/* The rotation the trackball applies to the scene for a drag (dx, dy):
 * about the view's up axis by dx and about its right axis by dy. */
static vv_quat
drag_rotation(const vv_view *view, double dx, double dy) {
    dx = clampf(dx, VV_NAV_MAX_PIXELS);
    dy = clampf(dy, VV_NAV_MAX_PIXELS);
    vv_vec3 f, r, u;
    basis(view, &f, &r, &u);
    double k = radians_per_pixel(view);
    vv_quat qa = vv_quat_from_axis_angle(u, dx * k);
    vv_quat qe = vv_quat_from_axis_angle(r, dy * k);
    return vv_quat_normalize(vv_quat_mul(qe, qa));
}

static int
quat_finite(vv_quat q) {
    return isfinite(q.w) && isfinite(q.x) && isfinite(q.y) && isfinite(q.z);
}

static vv_vec3
box_centre(const vv_object *obj) {
    vv_box b = vv_object_world_box(obj);
    if (!(b.min.x <= b.max.x))
        return obj->position;
    return vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
}

void
vv_nav_object_rotate(vv_object *obj, const vv_view *view, double dx, double dy) {
    if (!obj || !view || !vv_nav_view_valid(view))
        return;
    vv_quat q = drag_rotation(view, dx, dy);
    vv_vec3 c = box_centre(obj);
    /* p' = c + q (p - c) with p = position + R(...): position' = c + q(position - c) */
    vv_vec3 pos = vv_vec3_add(c, vv_quat_rotate(q, vv_vec3_sub(obj->position, c)));
    vv_quat o = vv_quat_normalize(vv_quat_mul(q, obj->orientation));
    if (vec_finite(pos) && quat_finite(o)) {
        obj->position = pos;
        obj->orientation = o;
    }
}

void
vv_nav_object_translate(vv_object *obj, const vv_view *view, double dx, double dy) {
    if (!obj || !view || !vv_nav_view_valid(view))
        return;
    dx = clampf(dx, VV_NAV_MAX_PIXELS);
    dy = clampf(dy, VV_NAV_MAX_PIXELS);
    vv_vec3 f, r, u;
    basis(view, &f, &r, &u);
    double s = world_per_pixel(view);
    vv_vec3 pos = vv_vec3_add(obj->position,
                              vv_vec3_add(vv_vec3_scale(r, dx * s), vv_vec3_scale(u, -dy * s)));
    if (vec_finite(pos))
        obj->position = pos;
}

void
vv_nav_object_scale(vv_object *obj, double factor) {
    if (!obj || !isfinite(factor) || !(factor > 0.0))
        return;
    if (factor < 1.0 / 16.0)
        factor = 1.0 / 16.0;
    if (factor > 16.0)
        factor = 16.0;
    vv_vec3 c = box_centre(obj);
    vv_vec3 sc = vv_vec3_scale(obj->scale, factor);
    vv_vec3 pos = vv_vec3_add(c, vv_vec3_scale(vv_vec3_sub(obj->position, c), factor));
    if (vec_finite(sc) && vec_finite(pos) && fabs(sc.x) > 0 && fabs(sc.y) > 0 && fabs(sc.z) > 0) {
        obj->scale = sc;
        obj->position = pos;
    }
}

void
vv_nav_light_drag(vv_light *light, const vv_view *view, double dx, double dy) {
    if (!light || !view || !vv_nav_view_valid(view))
        return;
    if (light->type == VV_LIGHT_POINT) {
        dx = clampf(dx, VV_NAV_MAX_PIXELS);
        dy = clampf(dy, VV_NAV_MAX_PIXELS);
        vv_vec3 f, r, u;
        basis(view, &f, &r, &u);
        double s = world_per_pixel(view);
        vv_vec3 p = vv_vec3_add(light->position,
                                vv_vec3_add(vv_vec3_scale(r, dx * s), vv_vec3_scale(u, -dy * s)));
        if (vec_finite(p))
            light->position = p;
        return;
    }
    vv_vec3 dir = light->direction;
    if (light->headlight) {
        vv_vec3 f, r, u;
        basis(view, &f, &r, &u);
        dir = f;
    }
    vv_vec3 nd = vv_vec3_normalize(vv_quat_rotate(drag_rotation(view, dx, dy), dir));
    if (vec_finite(nd) && vv_vec3_length(nd) > 0.5) {
        light->direction = nd;
        light->headlight = 0;
    }
}

/* ---- vv_nav_apply ---------------------------------------------------------- */

int
vv_nav_view_project(const vv_view *v, vv_vec3 p, double *px, double *py) {
    if (!v || !px || !py || !vv_nav_view_valid(v) || v->width <= 0 || v->height <= 0)
        return 0;
    vv_vec3 f, r, u;
    basis(v, &f, &r, &u);
    vv_vec3 d = vv_vec3_sub(p, v->eye);
    double aspect = (double)v->width / v->height, x, y;
    if (v->projection == VV_PROJECTION_ORTHOGRAPHIC) {
        double hh = 0.5 * v->ortho_height;
        x = vv_vec3_dot(d, r) / (hh * aspect);
        y = vv_vec3_dot(d, u) / hh;
    } else {
        double z = vv_vec3_dot(d, f);
        if (!(z > 1e-9 * (1.0 + vv_vec3_length(d))))
            return 0;
        double t = tan(0.5 * v->fov);
        x = vv_vec3_dot(d, r) / (z * t * aspect);
        y = vv_vec3_dot(d, u) / (z * t);
    }
    double ix = (x + 1) / 2 * v->width, iy = (1 - y) / 2 * v->height;
    if (!isfinite(ix) || !isfinite(iy))
        return 0;
    *px = ix;
    *py = iy;
    return 1;
}

/* The cut plane of @p t, or NULL. */
static vv_cut_plane *
target_plane(vv_world *w, const vv_nav_target *t) {
    vv_cut_plane *list;
    int n;
    if (t->index >= 0) {
        if (t->index >= w->n_objects)
            return NULL;
        list = w->objects[t->index]->cut_planes;
        n = w->objects[t->index]->n_cut_planes;
    } else {
        list = w->cut_planes;
        n = w->n_cut_planes;
    }
    int k = t->plane < 0 ? n - 1 : t->plane;
    return k >= 0 && k < n ? &list[k] : NULL;
}

/* A cut plane moved along its normal by the drag's component along the
 * normal's image direction: the handle drawn 0.15 of the eye distance long
 * follows the mouse. */
static void
plane_slide(vv_cut_plane *pl, const vv_view *v, double dx, double dy) {
    dx = clampf(dx, VV_NAV_MAX_PIXELS);
    dy = clampf(dy, VV_NAV_MAX_PIXELS);
    double len3 = 0.15 * vv_vec3_length(vv_vec3_sub(v->at, v->eye));
    double ax, ay, bx, by;
    if (!vv_nav_view_project(v, pl->point, &ax, &ay) ||
        !vv_nav_view_project(v, vv_vec3_add(pl->point, vv_vec3_scale(pl->normal, len3)), &bx, &by))
        return;
    double lx = bx - ax, ly = by - ay, len = hypot(lx, ly);
    if (!(len > 1e-6))
        return; /* the normal points at the viewer: no image direction to follow */
    double along = (dx * lx + dy * ly) / len; /* pixels along the handle */
    vv_vec3 np = vv_vec3_add(pl->point, vv_vec3_scale(pl->normal, along * len3 / len));
    if (vec_finite(np))
        pl->point = np;
}

/* A cut plane's normal turned as the trackball turns a direction. */
static void
plane_turn(vv_cut_plane *pl, const vv_view *v, double dx, double dy) {
    vv_vec3 n = vv_vec3_normalize(vv_quat_rotate(drag_rotation(v, dx, dy), pl->normal));
    if (vec_finite(n) && vv_vec3_length(n) > 0.5)
        pl->normal = n;
}

/* The scene turned by @p q given in view axes: the camera turns the other
 * way about the look-at point. */
static void
view_turn(vv_view *view, vv_quat q) {
    if (!quat_finite(q))
        return;
    q = vv_quat_normalize(q);
    if (fabs(q.w) >= 1 - 1e-15)
        return;
    vv_vec3 f, r, u;
    basis(view, &f, &r, &u);
    vv_vec3 axis = vv_vec3_add(vv_vec3_add(vv_vec3_scale(r, q.x), vv_vec3_scale(u, q.y)),
                               vv_vec3_scale(f, -q.z));
    vv_quat cam = vv_quat_normalize((vv_quat){q.w, -axis.x, -axis.y, -axis.z});
    vv_view c = *view;
    c.eye = vv_vec3_add(view->at, vv_quat_rotate(cam, vv_vec3_sub(view->eye, view->at)));
    c.up = vv_quat_rotate(cam, view->up);
    commit_view(view, &c);
}

static void
apply_view(vv_view *v, const vv_nav_motion *m) {
    switch (m->kind) {
    case VV_NAV_ROTATE:
        vv_nav_view_rotate(v, m->dx, m->dy);
        break;
    case VV_NAV_PAN:
        vv_nav_view_pan(v, m->dx, m->dy);
        break;
    case VV_NAV_ZOOM:
        vv_nav_view_zoom(v, m->factor);
        break;
    case VV_NAV_FLY:
        vv_nav_view_fly(v, m->yaw, m->pitch, m->roll, m->speed, m->dt);
        break;
    case VV_NAV_TURN:
        view_turn(v, m->rotation);
        break;
    }
}

vv_status
vv_nav_apply(vv_world *world, const vv_nav_target *target, const vv_nav_motion *motion) {
    if (!world || !target || !motion)
        return vv_error_set(VV_ERR_INVALID, "navigator: NULL %s",
                            !world    ? "world"
                            : !target ? "target"
                                      : "motion");
    if ((int)motion->kind < VV_NAV_ROTATE || (int)motion->kind > VV_NAV_TURN)
        return vv_error_set(VV_ERR_INVALID, "navigator: unknown motion %d", (int)motion->kind);
    vv_view *v = &world->view;
    if (!vv_nav_view_valid(v))
        return vv_error_set(VV_ERR_INVALID, "navigator: the World's view is not valid");
    switch (target->kind) {
    case VV_NAV_TARGET_VIEW:
        apply_view(v, motion);
        return VV_OK;
    case VV_NAV_TARGET_OBJECT: {
        if (target->index < 0 || target->index >= world->n_objects)
            return vv_error_set(VV_ERR_INVALID, "navigator: no object %d (the World has %d)",
                                target->index, world->n_objects);
        vv_object *o = world->objects[target->index];
        if (motion->kind == VV_NAV_ROTATE)
            vv_nav_object_rotate(o, v, motion->dx, motion->dy);
        else if (motion->kind == VV_NAV_PAN)
            vv_nav_object_translate(o, v, motion->dx, motion->dy);
        else if (motion->kind == VV_NAV_ZOOM)
            vv_nav_object_scale(o, motion->factor);
        return VV_OK;
    }
    case VV_NAV_TARGET_LIGHT: {
        if (target->index < 0 || target->index >= world->n_lights)
            return vv_error_set(VV_ERR_INVALID, "navigator: no light %d (the World has %d)",
                                target->index, world->n_lights);
        vv_light *l = &world->lights[target->index];
        /* a point light follows the mouse whichever way it is dragged; a
         * directional one turns */
        if (motion->kind == VV_NAV_ROTATE || motion->kind == VV_NAV_PAN)
            vv_nav_light_drag(l, v, motion->dx, motion->dy);
        return VV_OK;
    }
    case VV_NAV_TARGET_CUT: {
        vv_cut_plane *pl = target_plane(world, target);
        if (!pl)
            return vv_error_set(VV_ERR_INVALID, "navigator: no cut plane %d of %s %d",
                                target->plane, target->index < 0 ? "the World" : "object",
                                target->index);
        if (motion->kind == VV_NAV_PAN)
            plane_slide(pl, v, motion->dx, motion->dy);
        else if (motion->kind == VV_NAV_ROTATE)
            plane_turn(pl, v, motion->dx, motion->dy);
        return VV_OK;
    }
    }
    return vv_error_set(VV_ERR_INVALID, "navigator: unknown target %d", (int)target->kind);
}
