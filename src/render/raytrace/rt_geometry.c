/*
 * Volumetric ray tracing, the geometry: the nearest hit among the geometric
 * objects a ray sees and its world normal. Each object's intersection is
 * its record of the geometry-type table (include/volvis/sys/geometry.h; a mesh's
 * through its bounding volume hierarchy, core/bvh.h).
 */
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/raytrace/rt_internal.h"
#include "render/registry.h"
#include "volvis/render.h"

/* ---------------------------------------------------------------------- */
/* Geometry: the intersections are the geometry-type table's (src/model)    */

/* Nearest hit of one geometric object in (tmin, tmax); its object-space
 * normal in *no (not normalised, not flipped towards the ray; gobj_normal
 * turns it into the world normal), or NULL when not needed. */
int
rt_gobj_hit(const rt_gobj *g, const vv_ray *wr, double tmin, double tmax, double *t, vv_vec3 *no) {
    if (g->bounded) {
        /* the ray (t >= 0) misses the bounding sphere: its origin is outside
         * and the sphere lies behind it or off its line */
        const vv_vec3 oc = v3sub(g->bc, wr->origin);
        const double b = v3dot(oc, wr->dir), c = v3dot(oc, oc) - g->br2;
        if (c > 0 && (b <= 0 || b * b < c * v3dot(wr->dir, wr->dir)))
            return 0;
    }
    vv_vec3 n;
    if (g->type == VV_OBJECT_PLANE) {
        /* in world space, no transform; the normal reported is the object's */
        if (!g->geom->intersect(&g->wplane, NULL, wr->origin, wr->dir, tmin, tmax, t, &n))
            return 0;
        if (no)
            *no = g->obj->geometry.normal;
        return 1;
    }
    const vv_vec3 o = xf_point(g->w2o, wr->origin), d = xf_dir(g->w2o, wr->dir);
    if (!g->geom->intersect(&g->obj->geometry, g->prep, o, d, tmin, tmax, t, &n))
        return 0;
    if (no)
        *no = n;
    return 1;
}

/* The world-space unit normal of object-space normal n of g. */
static inline vv_vec3
gobj_normal(const rt_gobj *g, vv_vec3 n) {
    vv_vec3 w = v3(g->nrm[0][0] * n.x + g->nrm[0][1] * n.y + g->nrm[0][2] * n.z,
                   g->nrm[1][0] * n.x + g->nrm[1][1] * n.y + g->nrm[1][2] * n.z,
                   g->nrm[2][0] * n.x + g->nrm[2][1] * n.y + g->nrm[2][2] * n.z);
    return v3norm(w);
}

/* Nearest geometric hit among the objects a ray of this kind sees. */
int
rt_nearest_hit(const rt_frame *fr, const vv_ray *wr, double tmin, double tmax, int primary,
               rt_hit *h) {
    int found = 0;
    for (int i = 0; i < fr->n_gobj; i++) {
        const rt_gobj *g = &fr->gobjs[i];
        if (!primary && !g->obj->visible_in_reflections)
            continue;
        double t;
        vv_vec3 n;
        if (rt_gobj_hit(g, wr, tmin, tmax, &t, &n)) {
            tmax = t;
            h->t = t;
            h->gobj = i;
            h->n = n;
            found = 1;
        }
    }
    if (found) /* the world normal of the nearest hit only */
        h->n = gobj_normal(&fr->gobjs[h->gobj], h->n);
    return found;
}
