/* The scene view's overlays: cut planes, handles, marks, orientation, scale (vvg-scene-overlay.h).
 */
#include "vvg-scene-overlay.h"

#include <math.h>
#include <stdio.h>

/* Widget position of world point @p p; FALSE behind the eye. */
static gboolean
widget_xy(const VvgSceneOverlay *o, vv_vec3 p, double *x, double *y) {
    double px, py;
    if (!vv_nav_view_project(o->view, p, &px, &py))
        return FALSE;
    *x = o->x0 + o->scale * px;
    *y = o->y0 + o->scale * py;
    return TRUE;
}

int
vvg_scene_overlay_plane_polygon(vv_vec3 point, vv_vec3 normal, vv_box b, vv_vec3 out[6]) {
    vv_vec3 n = vv_vec3_normalize(normal);
    vv_vec3 c[8];
    double d[8];
    for (int i = 0; i < 8; i++) {
        c[i] = vv_vec3_make(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                            i & 4 ? b.max.z : b.min.z);
        d[i] = vv_vec3_dot(n, vv_vec3_sub(c[i], point));
    }
    static const int edges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                     {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    vv_vec3 pts[12];
    int n_pts = 0;
    for (int e = 0; e < 12; e++) {
        double da = d[edges[e][0]], db = d[edges[e][1]];
        if ((da < 0) == (db < 0) || da == db)
            continue;
        double t = da / (da - db);
        pts[n_pts++] = vv_vec3_add(c[edges[e][0]],
                                   vv_vec3_scale(vv_vec3_sub(c[edges[e][1]], c[edges[e][0]]), t));
    }
    if (n_pts < 3)
        return 0;
    /* in order of angle about the centre, in a basis of the plane */
    vv_vec3 ctr = vv_vec3_make(0, 0, 0);
    for (int i = 0; i < n_pts; i++)
        ctr = vv_vec3_add(ctr, pts[i]);
    ctr = vv_vec3_scale(ctr, 1.0 / n_pts);
    vv_vec3 u = vv_vec3_normalize(vv_vec3_sub(pts[0], ctr));
    vv_vec3 v = vv_vec3_cross(n, u);
    double ang[12];
    for (int i = 0; i < n_pts; i++) {
        vv_vec3 q = vv_vec3_sub(pts[i], ctr);
        ang[i] = atan2(vv_vec3_dot(q, v), vv_vec3_dot(q, u));
    }
    for (int i = 1; i < n_pts; i++) /* insertion sort: at most 6 distinct points */
        for (int j = i; j > 0 && ang[j] < ang[j - 1]; j--) {
            double ta = ang[j];
            ang[j] = ang[j - 1];
            ang[j - 1] = ta;
            vv_vec3 tp = pts[j];
            pts[j] = pts[j - 1];
            pts[j - 1] = tp;
        }
    int m = 0;
    for (int i = 0; i < n_pts && m < 6; i++)
        if (m == 0 || vv_vec3_length(vv_vec3_sub(pts[i], out[m - 1])) > 1e-9)
            out[m++] = pts[i];
    return m;
}

double
vvg_scene_overlay_nice_length(double target) {
    if (!(target > 0) || !isfinite(target))
        return 1;
    double p = pow(10.0, floor(log10(target)));
    double f = target / p;
    return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * p;
}

static void
draw_plane(cairo_t *cr, const VvgSceneOverlay *o, const vv_cut_plane *pl, vv_box box) {
    vv_vec3 poly[6];
    int n = vvg_scene_overlay_plane_polygon(pl->point, pl->normal, box, poly);
    double x[6], y[6];
    for (int i = 0; i < n; i++)
        if (!widget_xy(o, poly[i], &x[i], &y[i]))
            return;
    if (n < 3)
        return;
    gboolean moving = pl == o->moving_plane;
    for (int i = 0; i < n; i++)
        (i ? cairo_line_to : cairo_move_to)(cr, x[i], y[i]);
    cairo_close_path(cr);
    cairo_set_source_rgba(cr, 0.2, 0.9, 1.0, moving ? 0.18 : 0.08);
    cairo_fill_preserve(cr);
    cairo_set_source_rgba(cr, 0.2, 0.9, 1.0, moving ? 0.95 : 0.55);
    cairo_set_line_width(cr, moving ? 2 : 1);
    cairo_stroke(cr);
}

/* Every cut plane, global and local, where it crosses the World's box. */
static void
draw_planes(cairo_t *cr, const VvgSceneOverlay *o) {
    const vv_world *w = o->world;
    vv_box box = vv_world_bounds(w);
    /* a little larger, so that a plane on a face still shows */
    vv_vec3 pad = vv_vec3_scale(vv_vec3_sub(box.max, box.min), 0.01);
    box.min = vv_vec3_sub(box.min, pad);
    box.max = vv_vec3_add(box.max, pad);
    for (int i = 0; i < w->n_cut_planes; i++)
        draw_plane(cr, o, &w->cut_planes[i], box);
    for (int k = 0; k < w->n_objects; k++)
        for (int i = 0; i < w->objects[k]->n_cut_planes; i++)
            draw_plane(cr, o, &w->objects[k]->cut_planes[i], box);
}

/* The handle of the plane a drag moves: a ring at its point, its normal. */
static void
draw_plane_handle(cairo_t *cr, const VvgSceneOverlay *o) {
    const vv_cut_plane *pl = o->moving_plane;
    const vv_view *v = o->view;
    double dist = vv_vec3_length(vv_vec3_sub(v->at, v->eye));
    double ax, ay, bx, by;
    if (!pl || !widget_xy(o, pl->point, &ax, &ay) ||
        !widget_xy(o, vv_vec3_add(pl->point, vv_vec3_scale(pl->normal, 0.15 * dist)), &bx, &by))
        return;
    cairo_set_line_width(cr, 2);
    cairo_set_source_rgb(cr, 0.2, 0.9, 1.0);
    cairo_arc(cr, ax, ay, 7, 0, 2 * G_PI);
    cairo_stroke(cr);
    cairo_move_to(cr, ax, ay);
    cairo_line_to(cr, bx, by);
    cairo_stroke(cr);
    cairo_arc(cr, bx, by, 3.5, 0, 2 * G_PI);
    cairo_fill(cr);
}

/* The selected light: a sun at a point light, an arrow for a directional one. */
static void
draw_light_handle(cairo_t *cr, const VvgSceneOverlay *o) {
    const vv_world *w = o->world;
    const vv_view *v = o->view;
    if (o->light < 0 || o->light >= w->n_lights)
        return;
    const vv_light *l = &w->lights[o->light];
    double dist = vv_vec3_length(vv_vec3_sub(v->at, v->eye));
    double ax, ay, bx, by;
    cairo_set_line_width(cr, 2);
    cairo_set_source_rgb(cr, 1.0, 0.85, 0.2);
    if (l->type == VV_LIGHT_POINT && widget_xy(o, l->position, &ax, &ay)) {
        cairo_arc(cr, ax, ay, 6, 0, 2 * G_PI);
        cairo_fill(cr);
        for (int k = 0; k < 8; k++) {
            double a = k * G_PI / 4;
            cairo_move_to(cr, ax + 9 * cos(a), ay + 9 * sin(a));
            cairo_line_to(cr, ax + 14 * cos(a), ay + 14 * sin(a));
        }
        cairo_stroke(cr);
    } else if (l->type == VV_LIGHT_DIRECTIONAL && !l->headlight &&
               widget_xy(o, vv_vec3_sub(v->at, vv_vec3_scale(l->direction, 0.3 * dist)), &ax,
                         &ay) &&
               widget_xy(o, v->at, &bx, &by)) {
        /* an arrow from where the light comes from towards the look-at point */
        cairo_move_to(cr, ax, ay);
        cairo_line_to(cr, bx, by);
        cairo_stroke(cr);
        cairo_arc(cr, ax, ay, 6, 0, 2 * G_PI);
        cairo_fill(cr);
    }
}

/* Points A and B with the distance between them, the seed, the region. */
static void
draw_marks(cairo_t *cr, const VvgSceneOverlay *o) {
    if (!o->marks)
        return;
    const vv_mesh *m = vvg_marks_region(o->marks);
    if (m && m->n_vertices > 0) {
        size_t step = m->n_vertices / 6000 + 1;
        cairo_set_source_rgba(cr, 1.0, 0.4, 1.0, 0.5);
        for (size_t i = 0; i < m->n_vertices; i += step) {
            const float *q = m->positions + 3 * i;
            double x, y;
            if (widget_xy(o, vv_vec3_make(q[0], q[1], q[2]), &x, &y))
                cairo_rectangle(cr, x - 1, y - 1, 2, 2);
        }
        cairo_fill(cr);
    }
    static const double rgb[VVG_MARK_COUNT][3] = {{0.2, 1, 0.4}, {1, 0.6, 0.2}, {1, 0.3, 1}};
    static const char *const names[VVG_MARK_COUNT] = {"A", "B", "seed"};
    vv_vec3 p[VVG_MARK_COUNT];
    double x[VVG_MARK_COUNT], y[VVG_MARK_COUNT];
    gboolean on[VVG_MARK_COUNT];
    cairo_select_font_face(cr, "Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 12);
    for (int k = 0; k < VVG_MARK_COUNT; k++) {
        on[k] = vvg_marks_point(o->marks, (VvgMark)k, &p[k]) && widget_xy(o, p[k], &x[k], &y[k]);
        if (!on[k])
            continue;
        cairo_set_source_rgb(cr, rgb[k][0], rgb[k][1], rgb[k][2]);
        cairo_arc(cr, x[k], y[k], 5, 0, 2 * G_PI);
        cairo_fill(cr);
        cairo_move_to(cr, x[k] + 7, y[k] - 7);
        cairo_show_text(cr, names[k]);
    }
    if (on[VVG_MARK_A] && on[VVG_MARK_B]) {
        cairo_set_source_rgba(cr, 1, 1, 0.3, 0.9);
        cairo_set_line_width(cr, 1.5);
        cairo_move_to(cr, x[0], y[0]);
        cairo_line_to(cr, x[1], y[1]);
        cairo_stroke(cr);
        char t[64];
        snprintf(t, sizeof t, "%.4g %s", vv_vec3_length(vv_vec3_sub(p[0], p[1])),
                 o->units ? o->units : "units");
        cairo_move_to(cr, 0.5 * (x[0] + x[1]) + 6, 0.5 * (y[0] + y[1]) + 4);
        cairo_show_text(cr, t);
    }
}

/* Axes at the bottom left turning with the camera, labelled by the
 * anatomical direction of their positive end (or x, y, z). */
static void
draw_orientation(cairo_t *cr, const VvgSceneOverlay *o) {
    const vv_view *v = o->view;
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(v->at, v->eye));
    vv_vec3 r = vv_vec3_normalize(vv_vec3_cross(f, v->up));
    vv_vec3 u = vv_vec3_cross(r, f);
    static const char *const ras[3] = {"R", "A", "S"}, *lps[3] = {"L", "P", "S"},
                             *xyz[3] = {"x", "y", "z"};
    const char *const *names = o->space == VV_SPACE_RAS   ? ras
                               : o->space == VV_SPACE_LPS ? lps
                                                          : xyz;
    static const double rgb[3][3] = {{0.95, 0.3, 0.3}, {0.3, 0.9, 0.3}, {0.4, 0.55, 1.0}};
    double cx = 44, cy = o->height - 44, len = 30;
    int order[3] = {0, 1, 2};
    double depth[3];
    for (int k = 0; k < 3; k++) {
        vv_vec3 a = vv_vec3_make(k == 0, k == 1, k == 2);
        depth[k] = vv_vec3_dot(a, f);
    }
    for (int i = 0; i < 3; i++) /* the farthest first */
        for (int j = i + 1; j < 3; j++)
            if (depth[order[j]] > depth[order[i]]) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    cairo_set_line_width(cr, 2.5);
    cairo_select_font_face(cr, "Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 12);
    for (int i = 0; i < 3; i++) {
        int k = order[i];
        vv_vec3 a = vv_vec3_make(k == 0, k == 1, k == 2);
        double ex = cx + len * vv_vec3_dot(a, r), ey = cy - len * vv_vec3_dot(a, u);
        cairo_set_source_rgb(cr, rgb[k][0], rgb[k][1], rgb[k][2]);
        cairo_move_to(cr, cx, cy);
        cairo_line_to(cr, ex, ey);
        cairo_stroke(cr);
        cairo_move_to(cr, cx + 1.35 * (ex - cx) - 4, cy + 1.35 * (ey - cy) + 4);
        cairo_show_text(cr, names[k]);
    }
}

/* A bar of a round length at the look-at distance, bottom right. */
static void
draw_scale_bar(cairo_t *cr, const VvgSceneOverlay *o) {
    const vv_view *v = o->view;
    double wpp; /* world units per view pixel at the look-at point */
    if (v->projection == VV_PROJECTION_ORTHOGRAPHIC)
        wpp = v->ortho_height / v->height;
    else
        wpp = 2 * vv_vec3_length(vv_vec3_sub(v->at, v->eye)) * tan(0.5 * v->fov) / v->height;
    wpp /= o->scale; /* per widget pixel */
    if (!(wpp > 0) || !isfinite(wpp))
        return;
    double len = vvg_scene_overlay_nice_length(120 * wpp), px = len / wpp;
    double x1 = o->width - 16, x0 = x1 - px, y = o->height - 18;
    cairo_set_source_rgba(cr, 0, 0, 0, 0.45);
    cairo_rectangle(cr, x0 - 6, y - 20, px + 12, 28);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_set_line_width(cr, 2);
    cairo_move_to(cr, x0, y - 4);
    cairo_line_to(cr, x0, y);
    cairo_line_to(cr, x1, y);
    cairo_line_to(cr, x1, y - 4);
    cairo_stroke(cr);
    char t[48];
    snprintf(t, sizeof t, "%g %s", len, o->units ? o->units : "units");
    cairo_select_font_face(cr, "Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 12);
    cairo_text_extents_t ext;
    cairo_text_extents(cr, t, &ext);
    cairo_move_to(cr, 0.5 * (x0 + x1) - 0.5 * ext.width, y - 7);
    cairo_show_text(cr, t);
}

void
vvg_scene_overlay_draw(cairo_t *cr, const VvgSceneOverlay *o) {
    if (!o->world || !o->view || !vv_nav_view_valid(o->view) || o->view->height < 1)
        return;
    draw_planes(cr, o);
    if (o->target == 3)
        draw_plane_handle(cr, o);
    else if (o->target == 2)
        draw_light_handle(cr, o);
    draw_marks(cr, o);
    draw_orientation(cr, o);
    draw_scale_bar(cr, o);
}
