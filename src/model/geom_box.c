/* The box record of the geometry-type table: geometry.box, axis-aligned in object space. */
#include <math.h>

#include "core/geom.h"
#include "model/model_internal.h"
#include "volvis/sys/geometry.h"

static vv_status
box_check(const vv_geometry *g) {
    if (!(g->box.max.x >= g->box.min.x && g->box.max.y >= g->box.min.y &&
          g->box.max.z >= g->box.min.z))
        return vv_error_set(VV_ERR_INVALID, "box with min > max");
    return VV_OK;
}

static int
box_solid(const vv_geometry *g) {
    (void)g;
    return 1;
}

static int
box_bounds(const vv_geometry *g, vv_box *b) {
    *b = g->box;
    return 1;
}

/* Six quads of four vertices each (flat normals), two triangles a quad. */
static vv_status
box_tessellate(const vv_geometry *g, const vv_geom_tess *opt, vv_mesh **out) {
    (void)opt;
    vv_status s = box_check(g);
    if (s != VV_OK)
        return s;
    const vv_box b = g->box;
    /* corner i: bit 0 picks max x, bit 1 max y, bit 2 max z; each face's
     * corners counter-clockwise seen from outside */
    static const int face[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                   {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    static const double normal[6][3] = {{0, 0, -1}, {0, 0, 1},  {0, -1, 0},
                                        {0, 1, 0},  {-1, 0, 0}, {1, 0, 0}};
    s = vv_geom_mesh_new(out, 24, 12);
    vv_mesh *m = *out;
    for (int f = 0; f < 6 && s == VV_OK; f++) {
        const uint32_t first = (uint32_t)m->n_vertices;
        const vv_vec3 n = vv_v3(normal[f][0], normal[f][1], normal[f][2]);
        for (int k = 0; k < 4 && s == VV_OK; k++) {
            const int i = face[f][k];
            s = vv_geom_mesh_vertex(m,
                                    vv_v3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                          i & 4 ? b.max.z : b.min.z),
                                    n);
        }
        if (s == VV_OK)
            s = vv_mesh_add_triangle(m, first, first + 1, first + 2);
        if (s == VV_OK)
            s = vv_mesh_add_triangle(m, first, first + 2, first + 3);
    }
    if (s != VV_OK) {
        vv_mesh_free(*out);
        *out = NULL;
    }
    return s;
}

/* The slab test, keeping which face the ray enters and leaves by. */
static int
box_intersect(const vv_geometry *g, const void *prep, vv_vec3 o, vv_vec3 d, double tmin,
              double tmax, double *t, vv_vec3 *n) {
    (void)prep;
    const double lo[3] = {g->box.min.x, g->box.min.y, g->box.min.z};
    const double hi[3] = {g->box.max.x, g->box.max.y, g->box.max.z};
    const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
    double t0 = -INFINITY, t1 = INFINITY;
    int a0 = 0, a1 = 0;
    double s0 = -1, s1 = 1;
    for (int a = 0; a < 3; a++) {
        double ta, tb;
        const int k = vv_slab_span(lo[a], hi[a], oo[a], dd[a], &ta, &tb);
        if (k == VV_SLAB_OUTSIDE)
            return 0;
        if (k == VV_SLAB_INSIDE)
            continue;
        /* the outward normal of the face entered and of the face left */
        const double sa = k == VV_SLAB_DOWN ? 1 : -1;
        if (ta > t0) {
            t0 = ta;
            a0 = a;
            s0 = sa;
        }
        if (tb < t1) {
            t1 = tb;
            a1 = a;
            s1 = -sa;
        }
    }
    if (t0 > t1)
        return 0;
    const int entering = t0 > tmin;
    const double th = entering ? t0 : t1;
    if (!(th > tmin && th < tmax))
        return 0;
    const int ax = entering ? a0 : a1;
    const double sg = entering ? s0 : s1;
    *t = th;
    *n = vv_v3(ax == 0 ? sg : 0, ax == 1 ? sg : 0, ax == 2 ? sg : 0);
    return 1;
}

static double
box_distance(const vv_geometry *g, const void *prep, vv_vec3 q) {
    (void)prep;
    const vv_vec3 c = vv_v3_scale(vv_v3_add(g->box.min, g->box.max), 0.5);
    const vv_vec3 h = vv_v3_scale(vv_v3_sub(g->box.max, g->box.min), 0.5);
    return vv_geom_box_distance(vv_v3_sub(q, c), h, 0);
}

const vv_geom_type vv_geom_box = {
    .version = VV_GEOM_TYPE_VERSION,
    .type = VV_OBJECT_BOX,
    .name = "box",
    .check = box_check,
    .solid = box_solid,
    .bounds = box_bounds,
    .tessellate = box_tessellate,
    .intersect = box_intersect,
    .distance = box_distance,
};
