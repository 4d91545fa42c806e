/*
 * Model trees: primitive constructors, their signed distance functions and
 * bounds, CSG nodes. The distance functions follow the usual exact forms
 * (sphere, box with rounded edges, torus, capped cylinder as a profile of
 * revolution); 2-D profiles (revolution, extrusion, helix) are measured to
 * their polygon, whose sign comes from the even-odd rule.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "modeling_internal.h"
#include "volvis/sys/geometry.h"

const char *
vv_csg_op_name(vv_csg_op op) {
    switch (op) {
    case VV_CSG_UNION:
        return "union";
    case VV_CSG_INTERSECTION:
        return "intersection";
    case VV_CSG_DIFFERENCE:
        return "difference";
    }
    return "unknown";
}

static int
positive(double v) {
    return isfinite(v) && v > 0.0;
}

static vv_status
shape_alloc(vv_shape **out, shape_kind kind, const char *name) {
    vv_shape *s = calloc(1, sizeof *s);
    if (!s)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", name);
    s->kind = kind;
    s->name = name;
    s->M = vv_mat4_identity();
    s->frame = vv_mat4_identity();
    *out = s;
    return VV_OK;
}

static vv_status
bad_size(vv_shape **out, const char *prim, const char *what, double v) {
    *out = NULL;
    return vv_error_set(VV_ERR_INVALID, "%s: %s must be finite and > 0, got %g", prim, what, v);
}

/* Copies a 2-D polygon after checking it: n >= 3, finite, non-zero area. */
static vv_status
set_polygon(vv_shape *s, int n, const double *pts, int need_nonneg_x) {
    if (n < 3 || !pts)
        return vv_error_set(VV_ERR_INVALID, "%s: a polygon needs at least 3 points, got %d",
                            s->name, pts ? n : 0);
    if (n > (1 << 20))
        return vv_error_set(VV_ERR_LIMIT, "%s: %d polygon points is over the limit of 2^20",
                            s->name, n);
    double area = 0.0;
    s->pbox[0] = s->pbox[1] = INFINITY;
    s->pbox[2] = s->pbox[3] = -INFINITY;
    for (int i = 0; i < n; i++) {
        double x = pts[2 * i], y = pts[2 * i + 1];
        if (!isfinite(x) || !isfinite(y))
            return vv_error_set(VV_ERR_INVALID, "%s: point %d is not finite", s->name, i);
        if (need_nonneg_x && x < 0.0)
            return vv_error_set(VV_ERR_INVALID, "%s: point %d has radius %g < 0", s->name, i, x);
        int j = (i + 1) % n;
        area += x * pts[2 * j + 1] - pts[2 * j] * y;
        s->pbox[0] = fmin(s->pbox[0], x);
        s->pbox[1] = fmin(s->pbox[1], y);
        s->pbox[2] = fmax(s->pbox[2], x);
        s->pbox[3] = fmax(s->pbox[3], y);
    }
    double size = fmax(s->pbox[2] - s->pbox[0], s->pbox[3] - s->pbox[1]);
    if (!(fabs(area) > 1e-12 * size * size) || !(size > 0))
        return vv_error_set(VV_ERR_INVALID, "%s: the polygon has zero area", s->name);
    s->pts = malloc((size_t)n * 2 * sizeof *s->pts);
    if (!s->pts)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", s->name);
    memcpy(s->pts, pts, (size_t)n * 2 * sizeof *s->pts);
    s->n = n;
    return VV_OK;
}

static vv_status
finish(vv_shape **out, vv_shape *s, vv_status st) {
    if (st != VV_OK) {
        vv_shape_free(s);
        *out = NULL;
        return st;
    }
    *out = s;
    return VV_OK;
}

vv_status
vv_shape_sphere(vv_shape **out, double radius) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "sphere: NULL output");
    if (!positive(radius))
        return bad_size(out, "sphere", "radius", radius);
    vv_status st = shape_alloc(out, SHAPE_SPHERE, "sphere");
    if (st == VV_OK)
        (*out)->p[0] = radius;
    return st;
}

vv_status
vv_shape_ellipsoid(vv_shape **out, vv_vec3 r) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "ellipsoid: NULL output");
    if (!positive(r.x) || !positive(r.y) || !positive(r.z))
        return bad_size(out, "ellipsoid", "every semi-axis", fmin(r.x, fmin(r.y, r.z)));
    vv_status st = shape_alloc(out, SHAPE_ELLIPSOID, "ellipsoid");
    if (st == VV_OK) {
        (*out)->p[0] = r.x;
        (*out)->p[1] = r.y;
        (*out)->p[2] = r.z;
    }
    return st;
}

vv_status
vv_shape_box(vv_shape **out, vv_vec3 size, double rounding) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "box: NULL output");
    if (!positive(size.x) || !positive(size.y) || !positive(size.z))
        return bad_size(out, "box", "every edge length", fmin(size.x, fmin(size.y, size.z)));
    double emin = fmin(size.x, fmin(size.y, size.z));
    if (!(rounding >= 0.0 && rounding <= 0.5 * emin)) {
        *out = NULL;
        return vv_error_set(VV_ERR_INVALID,
                            "box: rounding radius %g is outside [0, half the smallest edge = %g]",
                            rounding, 0.5 * emin);
    }
    vv_status st = shape_alloc(out, SHAPE_BOX, "box");
    if (st == VV_OK) {
        (*out)->p[0] = 0.5 * size.x;
        (*out)->p[1] = 0.5 * size.y;
        (*out)->p[2] = 0.5 * size.z;
        (*out)->p[3] = rounding;
    }
    return st;
}

vv_status
vv_shape_cylinder(vv_shape **out, double radius, double height) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "cylinder: NULL output");
    if (!positive(radius))
        return bad_size(out, "cylinder", "radius", radius);
    if (!positive(height))
        return bad_size(out, "cylinder", "height", height);
    double h = 0.5 * height;
    double prof[8] = {0, -h, radius, -h, radius, h, 0, h};
    vv_shape *s = NULL;
    vv_status st = shape_alloc(&s, SHAPE_REVOLUTION, "cylinder");
    if (st != VV_OK)
        return st;
    return finish(out, s, set_polygon(s, 4, prof, 1));
}

vv_status
vv_shape_cone(vv_shape **out, double r_bottom, double r_top, double height) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "cone: NULL output");
    if (!(isfinite(r_bottom) && isfinite(r_top) && r_bottom >= 0 && r_top >= 0 &&
          r_bottom + r_top > 0)) {
        *out = NULL;
        return vv_error_set(VV_ERR_INVALID,
                            "cone: radii must be finite, >= 0 and not both 0, got %g and %g",
                            r_bottom, r_top);
    }
    if (!positive(height))
        return bad_size(out, "cone", "height", height);
    double h = 0.5 * height;
    double prof[8];
    int n = 0;
    prof[n++] = 0;
    prof[n++] = -h;
    if (r_bottom > 0) {
        prof[n++] = r_bottom;
        prof[n++] = -h;
    }
    if (r_top > 0) {
        prof[n++] = r_top;
        prof[n++] = h;
    }
    prof[n++] = 0;
    prof[n++] = h;
    vv_shape *s = NULL;
    vv_status st = shape_alloc(&s, SHAPE_REVOLUTION, "cone");
    if (st != VV_OK)
        return st;
    return finish(out, s, set_polygon(s, n / 2, prof, 1));
}

vv_status
vv_shape_torus(vv_shape **out, double major, double minor) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "torus: NULL output");
    if (!positive(major))
        return bad_size(out, "torus", "major radius", major);
    if (!positive(minor))
        return bad_size(out, "torus", "minor radius", minor);
    if (!(minor < major)) {
        *out = NULL;
        return vv_error_set(VV_ERR_INVALID,
                            "torus: minor radius %g must be smaller than the major radius %g",
                            minor, major);
    }
    vv_status st = shape_alloc(out, SHAPE_TORUS, "torus");
    if (st == VV_OK) {
        (*out)->p[0] = major;
        (*out)->p[1] = minor;
    }
    return st;
}

vv_status
vv_shape_polygon(vv_shape **out, int n, const vv_vec3 *v, double thickness) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "polygon: NULL output");
    *out = NULL;
    if (!positive(thickness))
        return bad_size(out, "polygon", "thickness", thickness);
    if (n < 3 || !v)
        return vv_error_set(VV_ERR_INVALID, "polygon: needs at least 3 vertices, got %d",
                            v ? n : 0);
    if (n > (1 << 20))
        return vv_error_set(VV_ERR_LIMIT, "polygon: %d vertices is over the limit of 2^20", n);
    /* Newell normal and centroid give the plane; u along the first edge */
    vv_vec3 nrm = {0, 0, 0}, c = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        vv_vec3 a = v[i], b = v[(i + 1) % n];
        if (!isfinite(a.x) || !isfinite(a.y) || !isfinite(a.z))
            return vv_error_set(VV_ERR_INVALID, "polygon: vertex %d is not finite", i);
        nrm.x += (a.y - b.y) * (a.z + b.z);
        nrm.y += (a.z - b.z) * (a.x + b.x);
        nrm.z += (a.x - b.x) * (a.y + b.y);
        c = vv_vec3_add(c, a);
    }
    c = vv_vec3_scale(c, 1.0 / n);
    double len = vv_vec3_length(nrm);
    if (!(len > 0))
        return vv_error_set(VV_ERR_INVALID, "polygon: the vertices enclose zero area");
    vv_vec3 w = vv_vec3_scale(nrm, 1.0 / len);
    vv_vec3 u = vv_vec3_sub(v[1], v[0]);
    u = vv_vec3_sub(u, vv_vec3_scale(w, vv_vec3_dot(u, w)));
    if (!(vv_vec3_length(u) > 0)) {
        u = fabs(w.x) < 0.9 ? vv_vec3_make(1, 0, 0) : vv_vec3_make(0, 1, 0);
        u = vv_vec3_sub(u, vv_vec3_scale(w, vv_vec3_dot(u, w)));
    }
    u = vv_vec3_normalize(u);
    vv_vec3 vv = vv_vec3_cross(w, u);
    double *p2 = malloc((size_t)n * 2 * sizeof *p2);
    if (!p2)
        return vv_error_set(VV_ERR_NOMEM, "polygon: out of memory");
    double size = 0.0, off = 0.0;
    for (int i = 0; i < n; i++) {
        vv_vec3 d = vv_vec3_sub(v[i], c);
        p2[2 * i] = vv_vec3_dot(d, u);
        p2[2 * i + 1] = vv_vec3_dot(d, vv);
        size = fmax(size, vv_vec3_length(d));
        off = fmax(off, fabs(vv_vec3_dot(d, w)));
    }
    if (off > 1e-6 * size) {
        free(p2);
        return vv_error_set(VV_ERR_INVALID,
                            "polygon: the vertices are not planar (%g off the plane, size %g)", off,
                            size);
    }
    vv_shape *s = NULL;
    vv_status st = shape_alloc(&s, SHAPE_EXTRUSION, "polygon");
    if (st != VV_OK) {
        free(p2);
        return st;
    }
    s->p[0] = 0.5 * thickness;
    vv_mat4 F = vv_mat4_identity();
    F.m[0][0] = u.x, F.m[1][0] = u.y, F.m[2][0] = u.z;
    F.m[0][1] = vv.x, F.m[1][1] = vv.y, F.m[2][1] = vv.z;
    F.m[0][2] = w.x, F.m[1][2] = w.y, F.m[2][2] = w.z;
    F.m[0][3] = c.x, F.m[1][3] = c.y, F.m[2][3] = c.z;
    s->frame = F;
    st = set_polygon(s, n, p2, 0);
    free(p2);
    return finish(out, s, st);
}

vv_status
vv_shape_revolution(vv_shape **out, int n, const double *profile) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "revolution: NULL output");
    vv_shape *s = NULL;
    vv_status st = shape_alloc(&s, SHAPE_REVOLUTION, "revolution");
    if (st != VV_OK)
        return st;
    return finish(out, s, set_polygon(s, n, profile, 1));
}

vv_status
vv_shape_extrusion(vv_shape **out, int n, const double *polygon, double height) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "extrusion: NULL output");
    if (!positive(height))
        return bad_size(out, "extrusion", "height", height);
    vv_shape *s = NULL;
    vv_status st = shape_alloc(&s, SHAPE_EXTRUSION, "extrusion");
    if (st != VV_OK)
        return st;
    s->p[0] = 0.5 * height;
    return finish(out, s, set_polygon(s, n, polygon, 0));
}

vv_status
vv_shape_helix(vv_shape **out, int n, const double *profile, double pitch, double z0, double z1) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "helix: NULL output");
    *out = NULL;
    if (!isfinite(pitch) || pitch == 0.0)
        return vv_error_set(VV_ERR_INVALID, "helix: pitch must be finite and non-zero, got %g",
                            pitch);
    if (!(isfinite(z0) && isfinite(z1) && z1 > z0))
        return vv_error_set(VV_ERR_INVALID, "helix: need z0 < z1, got %g and %g", z0, z1);
    vv_shape *s = NULL;
    vv_status st = shape_alloc(&s, SHAPE_HELIX, "helix");
    if (st != VV_OK)
        return st;
    s->p[0] = pitch;
    s->p[1] = z0;
    s->p[2] = z1;
    st = set_polygon(s, n, profile, 1);
    if (st == VV_OK && !(s->pbox[0] > 0))
        st = vv_error_set(VV_ERR_INVALID, "helix: the profile must lie at radius > 0");
    return finish(out, s, st);
}

vv_status
vv_shape_mesh(vv_shape **out, vv_mesh *mesh, vv_mesh_mode mode, double thickness) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "mesh shape: NULL output");
    *out = NULL;
    if (!mesh || mesh->n_triangles == 0)
        return vv_error_set(VV_ERR_INVALID, "mesh shape: the mesh has no triangles");
    if (mode != VV_MESH_AUTO && mode != VV_MESH_SOLID && mode != VV_MESH_SHELL)
        return vv_error_set(VV_ERR_INVALID, "mesh shape: unknown mode %d", (int)mode);
    if (!isfinite(thickness))
        return vv_error_set(VV_ERR_INVALID, "mesh shape: thickness is not finite");
    if (mode == VV_MESH_AUTO) {
        vv_mesh_topology t;
        vv_status st = vv_mesh_topology_compute(mesh, &t);
        if (st != VV_OK)
            return vv_error_prefix(st, "mesh shape");
        mode = VV_MESH_SOLID;
        if (!t.closed) {
            /* a solid with a few holes, or a surface meant as a shell: by the
             * area of the caps that would close it */
            vv_mesh_holes h;
            for (size_t i = 0; i < 3 * mesh->n_triangles; i++)
                if (mesh->triangles[i] >= mesh->n_vertices)
                    return vv_error_set(VV_ERR_INVALID,
                                        "mesh shape: triangle %zu has vertex %u of %zu", i / 3,
                                        mesh->triangles[i], mesh->n_vertices);
            st = vv_mesh_holes_find(mesh, &h);
            if (st != VV_OK)
                return vv_error_prefix(st, "mesh shape");
            if (!(h.cap_area <= VV_MESH_AUTO_HOLE_AREA * h.mesh_area))
                mode = VV_MESH_SHELL;
            vv_mesh_holes_free(&h);
        }
    }
    vv_status st = shape_alloc(out, SHAPE_MESH, "mesh");
    if (st != VV_OK)
        return st;
    (*out)->mesh = vv_mesh_ref(mesh);
    (*out)->mesh_mode = mode;
    (*out)->thickness = thickness;
    return VV_OK;
}

vv_status
vv_shape_mesh_load(vv_shape **out, const char *path, vv_mesh_mode mode, double thickness) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "mesh shape: NULL output");
    *out = NULL;
    vv_mesh *m = NULL;
    vv_status st = vv_mesh_load(&m, path);
    if (st != VV_OK)
        return st;
    st = vv_shape_mesh(out, m, mode, thickness);
    vv_mesh_free(m);
    return st;
}

vv_status
vv_shape_object(vv_shape **out, const vv_object *obj) {
    if (!out || !obj)
        return vv_error_set(VV_ERR_INVALID, "object shape: NULL argument");
    *out = NULL;
    const vv_geom_type *gt = vv_geom_type_get(obj->type);
    if (!gt)
        return vv_error_set(VV_ERR_INVALID, "object '%s': a %s is not a geometric shape", obj->name,
                            vv_object_type_name(obj->type));
    vv_status st = gt->check(&obj->geometry);
    if (st != VV_OK)
        return vv_error_prefix(st, "object '%s'", obj->name);
    vv_box b;
    if (!gt->bounds(&obj->geometry, &b))
        return vv_error_set(VV_ERR_INVALID, "object '%s': a %s has no bounds to voxelize",
                            obj->name, gt->name);
    if (!gt->solid(&obj->geometry))
        return vv_error_set(VV_ERR_INVALID,
                            "object '%s': a %s encloses no volume (a model's polygon has a "
                            "thickness; a capped cylinder is a solid)",
                            obj->name, gt->name);
    if (obj->type == VV_OBJECT_MESH) {
        /* Modeling's own scan conversion (generalized winding numbers) */
        st = vv_shape_mesh(out, obj->geometry.mesh, VV_MESH_AUTO, 0);
    } else {
        vv_shape *s = NULL;
        st = shape_alloc(&s, SHAPE_OBJECT, gt->name);
        if (st == VV_OK) {
            s->geom = gt;
            st = vv_object_clone(&s->obj, obj);
            if (st == VV_OK && gt->prepare)
                st = gt->prepare(&s->obj->geometry, &s->prep);
            st = finish(out, s, st);
        }
    }
    if (st != VV_OK)
        return vv_error_prefix(st, "object '%s'", obj->name);
    (*out)->M = vv_object_matrix(obj);
    return VV_OK;
}

vv_status
vv_shape_csg(vv_shape **out, vv_csg_op op, int n, vv_shape **children) {
    vv_status st = VV_OK;
    const char *opn = vv_csg_op_name(op);
    if (op != VV_CSG_UNION && op != VV_CSG_INTERSECTION && op != VV_CSG_DIFFERENCE)
        st = vv_error_set(VV_ERR_INVALID, "csg: unknown operation %d", (int)op);
    else if (n < 1 || !children)
        st = vv_error_set(VV_ERR_INVALID, "csg %s: needs at least one child, got none", opn);
    else if (!out)
        st = vv_error_set(VV_ERR_INVALID, "csg %s: NULL output", opn);
    for (int i = 0; st == VV_OK && i < n; i++)
        if (!children[i])
            st = vv_error_set(VV_ERR_INVALID, "csg %s: child %d of %d is missing", opn, i + 1, n);
    vv_shape *s = NULL;
    if (st == VV_OK && (st = shape_alloc(&s, SHAPE_CSG, opn)) == VV_OK) {
        s->children = malloc((size_t)n * sizeof *s->children);
        if (!s->children) {
            free(s);
            s = NULL;
            st = vv_error_set(VV_ERR_NOMEM, "csg: out of memory");
        }
    }
    if (st != VV_OK) {
        for (int i = 0; children && i < n; i++)
            vv_shape_free(children[i]);
        if (out)
            *out = NULL;
        return st;
    }
    s->op = op;
    s->n_children = n;
    memcpy(s->children, children, (size_t)n * sizeof *children);
    *out = s;
    return VV_OK;
}

static void
shape_free_one(vv_shape *s) {
    if (s->prep)
        s->geom->release(s->prep);
    vv_object_free(s->obj);
    free(s->children);
    free(s->pts);
    vv_mesh_free(s->mesh);
    free(s);
}

void
vv_shape_free(vv_shape *s) {
    if (!s)
        return;
    /* without recursion, for trees of any depth: a node's children are
     * pushed on a stack before the node goes; if the stack cannot grow,
     * fall back to recursion */
    size_t n = 0, cap = 64;
    vv_shape **st = malloc(cap * sizeof *st);
    if (!st) {
        for (int i = 0; i < s->n_children; i++)
            vv_shape_free(s->children[i]);
        shape_free_one(s);
        return;
    }
    st[n++] = s;
    while (n) {
        vv_shape *t = st[--n];
        for (int i = 0; i < t->n_children; i++) {
            if (n == cap) {
                vv_shape **g = realloc(st, 2 * cap * sizeof *st);
                if (!g) {
                    vv_shape_free(t->children[i]);
                    continue;
                }
                st = g;
                cap *= 2;
            }
            st[n++] = t->children[i];
        }
        shape_free_one(t);
    }
    free(st);
}

void
vv_shape_transform(vv_shape *s, vv_mat4 M) {
    if (s)
        s->M = vv_mat4_mul(M, s->M);
}

vv_mat4
vv_shape_get_transform(const vv_shape *s) {
    return s ? s->M : vv_mat4_identity();
}

/* ---- distances ----------------------------------------------------------- */

/* Signed distance to a 2-D polygon (even-odd inside). With skip_axis, edges
 * lying on x = 0 (the axis of a profile of revolution) are not surface. */
static double
poly_sdf(const double *p, int n, double x, double y, int skip_axis) {
    double best = INFINITY;
    int inside = 0;
    for (int i = 0, j = n - 1; i < n; j = i++) {
        double ax = p[2 * j], ay = p[2 * j + 1], bx = p[2 * i], by = p[2 * i + 1];
        if ((by > y) != (ay > y) && x < ax + (y - ay) * (bx - ax) / (by - ay))
            inside = !inside;
        if (skip_axis && ax == 0.0 && bx == 0.0)
            continue;
        double ex = bx - ax, ey = by - ay, wx = x - ax, wy = y - ay;
        double ee = ex * ex + ey * ey;
        double t = ee > 0 ? (wx * ex + wy * ey) / ee : 0.0;
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        double dx = wx - t * ex, dy = wy - t * ey, d2 = dx * dx + dy * dy;
        if (d2 < best)
            best = d2;
    }
    double d = sqrt(best);
    return inside ? -d : d;
}

static double
helix_sdf(const vv_shape *s, vv_vec3 q) {
    double pitch = s->p[0], ap = fabs(pitch);
    double r = sqrt(q.x * q.x + q.y * q.y);
    double th = atan2(q.y, q.x);
    double zz = q.z - pitch * th / (2.0 * VV_PI);
    double zc = 0.5 * (s->pbox[1] + s->pbox[3]);
    double k = floor((zz - zc) / ap + 0.5);
    double d = INFINITY;
    for (int i = -1; i <= 1; i++) {
        double di = poly_sdf(s->pts, s->n, r, zz - (k + i) * ap, 0);
        if (di < d)
            d = di;
    }
    double slab = fmax(s->p[1] - q.z, q.z - s->p[2]);
    return fmax(d, slab);
}

double
vv_shape_sdf(const vv_shape *s, vv_vec3 q) {
    switch (s->kind) {
    case SHAPE_SPHERE:
        return vv_geom_sphere_distance(q, s->p[0]);
    case SHAPE_ELLIPSOID: {
        /* first-order distance k0 (k0 - 1) / k1: exact zero set, accurate near it */
        double ax = q.x / s->p[0], ay = q.y / s->p[1], az = q.z / s->p[2];
        double k0 = sqrt(ax * ax + ay * ay + az * az);
        double bx = ax / s->p[0], by = ay / s->p[1], bz = az / s->p[2];
        double k1 = sqrt(bx * bx + by * by + bz * bz);
        if (!(k1 > 0))
            return -fmin(s->p[0], fmin(s->p[1], s->p[2]));
        return k0 * (k0 - 1.0) / k1;
    }
    case SHAPE_BOX:
        return vv_geom_box_distance(q, vv_vec3_make(s->p[0], s->p[1], s->p[2]), s->p[3]);
    case SHAPE_OBJECT:
        return s->geom->distance(&s->obj->geometry, s->prep, q);
    case SHAPE_TORUS: {
        double a = sqrt(q.x * q.x + q.y * q.y) - s->p[0];
        return sqrt(a * a + q.z * q.z) - s->p[1];
    }
    case SHAPE_REVOLUTION:
        return poly_sdf(s->pts, s->n, sqrt(q.x * q.x + q.y * q.y), q.z, 1);
    case SHAPE_EXTRUSION:
        return vv_geom_prism_distance(poly_sdf(s->pts, s->n, q.x, q.y, 0), fabs(q.z) - s->p[0]);
    case SHAPE_HELIX:
        return helix_sdf(s, q);
    case SHAPE_MESH:
    case SHAPE_CSG:
        break;
    }
    return INFINITY;
}

double
vv_shape_sdf_bound(const vv_shape *s, vv_vec3 q) {
    switch (s->kind) {
    case SHAPE_ELLIPSOID: {
        /* the ellipsoid is A * (unit ball), so |d| >= min semi-axis * |k0 - 1| */
        double ax = q.x / s->p[0], ay = q.y / s->p[1], az = q.z / s->p[2];
        double k0 = sqrt(ax * ax + ay * ay + az * az);
        return fmin(s->p[0], fmin(s->p[1], s->p[2])) * (k0 - 1.0);
    }
    case SHAPE_HELIX: {
        /* outside the annular cylinder holding the thread, its distance bounds */
        double r = sqrt(q.x * q.x + q.y * q.y);
        double a = fabs(r - 0.5 * (s->pbox[0] + s->pbox[2])) - 0.5 * (s->pbox[2] - s->pbox[0]);
        double zlo = s->p[1] + s->pbox[1] - fabs(s->p[0]), zhi = s->p[2] + s->pbox[3];
        zlo = fmax(zlo, s->p[1]);
        zhi = fmin(zhi + fabs(s->p[0]), s->p[2]);
        double b = fabs(q.z - 0.5 * (zlo + zhi)) - 0.5 * (zhi - zlo);
        double d = vv_geom_prism_distance(a, b);
        return d > 0 ? d : 0.0;
    }
    default:
        return vv_shape_sdf(s, q);
    }
}

static vv_box
empty_box(void) {
    return (vv_box){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
}

static int
box_empty(vv_box b) {
    return !(b.min.x <= b.max.x && b.min.y <= b.max.y && b.min.z <= b.max.z);
}

vv_box
vv_shape_local_box(const vv_shape *s) {
    vv_box b;
    switch (s->kind) {
    case SHAPE_SPHERE:
        b.max = vv_vec3_make(s->p[0], s->p[0], s->p[0]);
        break;
    case SHAPE_ELLIPSOID:
    case SHAPE_BOX:
        b.max = vv_vec3_make(s->p[0], s->p[1], s->p[2]);
        break;
    case SHAPE_TORUS:
        b.max = vv_vec3_make(s->p[0] + s->p[1], s->p[0] + s->p[1], s->p[1]);
        break;
    case SHAPE_REVOLUTION:
        return (vv_box){{-s->pbox[2], -s->pbox[2], s->pbox[1]},
                        {s->pbox[2], s->pbox[2], s->pbox[3]}};
    case SHAPE_EXTRUSION:
        return (vv_box){{s->pbox[0], s->pbox[1], -s->p[0]}, {s->pbox[2], s->pbox[3], s->p[0]}};
    case SHAPE_HELIX:
        return (vv_box){{-s->pbox[2], -s->pbox[2], s->p[1]}, {s->pbox[2], s->pbox[2], s->p[2]}};
    case SHAPE_MESH:
        return vv_mesh_bounds(s->mesh);
    case SHAPE_OBJECT:
        return s->geom->bounds(&s->obj->geometry, &b) ? b : empty_box();
    case SHAPE_CSG:
    default:
        return empty_box();
    }
    b.min = vv_vec3_scale(b.max, -1.0);
    return b;
}

vv_box
vv_shape_bounds(const vv_shape *s) {
    if (!s)
        return empty_box();
    vv_box b;
    if (s->kind != SHAPE_CSG) {
        b = vv_shape_local_box(s);
        return vv_box_transform(b, vv_mat4_mul(s->M, s->frame));
    }
    b = vv_shape_bounds(s->children[0]);
    for (int i = 1; i < s->n_children && s->op != VV_CSG_DIFFERENCE; i++) {
        vv_box c = vv_shape_bounds(s->children[i]);
        if (s->op == VV_CSG_UNION) {
            if (box_empty(b)) {
                b = c;
            } else if (!box_empty(c)) {
                b.min = vv_vec3_make(fmin(b.min.x, c.min.x), fmin(b.min.y, c.min.y),
                                     fmin(b.min.z, c.min.z));
                b.max = vv_vec3_make(fmax(b.max.x, c.max.x), fmax(b.max.y, c.max.y),
                                     fmax(b.max.z, c.max.z));
            }
        } else {
            b.min = vv_vec3_make(fmax(b.min.x, c.min.x), fmax(b.min.y, c.min.y),
                                 fmax(b.min.z, c.min.z));
            b.max = vv_vec3_make(fmin(b.max.x, c.max.x), fmin(b.max.y, c.max.y),
                                 fmin(b.max.z, c.max.z));
        }
    }
    if (box_empty(b))
        return empty_box();
    return vv_box_transform(b, s->M);
}
