/*
 * Volumetric ray tracing (Sobierajski and Kaufman, "Volumetric Ray
 * Tracing", Symposium on Volume Visualization 1994; the VolVis paper,
 * section 5): classical ray tracing of scenes that mix volumes and
 * geometric objects. The intensity arriving along a ray is
 *
 *     I(x, w) = I_v(x, x') + tau(x, x') * I_s(x', w)
 *
 * with x' the first surface hit (a geometric primitive or the isosurface of
 * a volume in iso mode), I_s its shading (Phong with shadow rays, plus
 * reflected and transmitted rays to a depth limit), I_v the volume samples
 * composited front to back (each shaded with Phong and shadow rays) and tau
 * what those volumes let through. Volumes in mip, minip or xray mode are
 * projected over the part of the ray in front of the surface and shown over
 * it, as the ray caster shows them over the background.
 *
 * Volumes follow the conventions of the ray caster (docs/rendering.md) so
 * that with every global effect off both give the same image: samples at
 * t = k * dt from the ray origin, the transfer function in a table with
 * opacity corrected for the step, Phong with the reflection vector, two
 * sided, the specular term weighted by the sample opacity, and the same cut
 * planes. Subvolumes of 4^3 cells with min/max values (vv_minmax_grid, the
 * PARC grid) tell every ray, primary or secondary, where a volume can
 * contribute under its transfer function or isovalue: samples start and
 * stop only there.
 *
 * Shadow rays from surfaces are traced exactly: transparent geometry
 * multiplies by its transparency, composite volumes by exp(-sum sigma h)
 * with sigma the extinction of the transfer function opacity, iso volumes
 * block where the ray meets the surface, projection volumes by one minus the
 * opacity of their projected value. A volume sample takes its shadow from a
 * lazily filled grid of shadow rays (one grid point every 4 voxels, each ray
 * starting 6 voxels towards the light so that a surface does not shadow
 * itself), interpolated trilinearly; option shadow_grid=0 traces one exact
 * shadow ray per sample instead. docs/rendering.md describes the method.
 */
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/registry.h"
#include "render/volume_cache.h"
#include "volvis/render.h"

#define RT_TILE 16 /* image tile side in pixels */
#define RT_MAX_OBJ 64
#define RT_SGRID 4                    /* shadow grid spacing, voxels */
#define RT_LGRID 2                    /* light volume spacing, voxels */
#define RT_MIN_WEIGHT (1.0f / 512.0f) /* secondary rays weighing less are not traced */
#define RT_EPS 1e-6                   /* relative ray offset off surfaces */

/* ---------------------------------------------------------------------- */
/* Vector helpers, inline (the library's are in another translation unit
 * and sit on the hot path of every intersection)                            */

static inline vv_vec3
v3(double x, double y, double z) {
    vv_vec3 r = {x, y, z};
    return r;
}
static inline vv_vec3
v3add(vv_vec3 a, vv_vec3 b) {
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline vv_vec3
v3sub(vv_vec3 a, vv_vec3 b) {
    return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline vv_vec3
v3scale(vv_vec3 a, double k) {
    return v3(a.x * k, a.y * k, a.z * k);
}
static inline double
v3dot(vv_vec3 a, vv_vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline vv_vec3
v3cross(vv_vec3 a, vv_vec3 b) {
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double
v3len(vv_vec3 a) {
    return sqrt(v3dot(a, a));
}
static inline vv_vec3
v3norm(vv_vec3 a) {
    double l = v3len(a);
    return l > 0 ? v3scale(a, 1.0 / l) : a;
}
static inline vv_vec3
ray_at(const vv_ray *r, double t) {
    return v3add(r->origin, v3scale(r->dir, t));
}

#define RT_LV_CACHE 16 /* light volumes kept between frames */

/* A light volume kept between frames (it does not depend on the view),
 * with everything it depends on. */
typedef struct rt_lv {
    vv_volume *vol; /* reference held; NULL: free slot */
    uint64_t modified;
    double w2i[3][4];
    double dir[3];
    double dt;
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    float lut_lo, lut_scale;
    float ext[VV_VC_LUT];
    float *T;
    uint64_t used; /* frame that last used it */
} rt_lv;

typedef struct rt_state {
    rt_lv lv[RT_LV_CACHE];
    uint64_t frame;
    vv_vcache_set vc; /* per-volume caches (src/render/volume_cache.h) */
    int parc;         /* PARC skipping on primary and secondary rays */
    int shadows;      /* shadow rays */
    int max_depth;    /* reflection / refraction depth */
    int samples;      /* supersamples per pixel side at quality 2 */
    int jitter;       /* jittered supersampling */
    int adaptive;     /* supersample only where neighbours differ */
    double threshold; /* adaptive: channel difference that triggers supersampling */
    uint64_t seed;    /* jitter seed */
    double early_termination;
    int shadow_grid;   /* volume samples: cached shadow rays (1) or exact (0) */
    int light_volumes; /* shadow rays of directional lights through volumes: light volumes */
} rt_state;

typedef struct rt_light {
    int point;
    double dir[3]; /* unit vector towards the light (directional) */
    double pos[3];
    float col[3]; /* colour * intensity */
} rt_light;

/* One volume object prepared for this render. */
typedef struct rt_vobj {
    const vv_object *obj;
    vv_vcache *c;
    vv_render_mode mode;
    double w2i[3][4], i2w[3][4];
    int dims[3];
    double vox;             /* smallest world length of a voxel step */
    vv_vtables tab;         /* TF table, extinction (composite), PARC flags and distances */
    int owns_tables;        /* tab is this object's (else borrowed from the volume's cache) */
    const float *lut, *ext; /* tab.lut, tab.ext */
    const uint8_t *bvis;    /* tab.bvis: the subvolume may contribute */
    const uint8_t *bdist;   /* tab.bdist: chessboard distance to the nearest that may */
    int bx, by, bz;         /* subvolume grid */
    float iso;
    vv_vshading sh; /* shading constants */
    int n_planes;
    vv_plane planes[2 * VV_MAX_CUT_PLANES];
    int gdim[3];                            /* shadow grid points per axis */
    _Atomic uint32_t *sgrid[VV_MAX_LIGHTS]; /* point lights: bits of (T + 1), 0 = not traced */
    float *sweep[VV_MAX_LIGHTS];            /* directional lights: swept transmittance */
    float lidx[VV_MAX_LIGHTS][3];           /* index-space direction to the light per world unit */
    int ldim[3];                /* light volume points per axis (every RT_LGRID voxels) */
    float *lvol[VV_MAX_LIGHTS]; /* directional lights: this volume's own transmittance
                                   from each point towards the light (a light volume) */
    unsigned lvol_owned;        /* bit l: lvol[l] is this frame's (else the state's cache) */
    vv_vextra x;                /* 2-D transfer function and solid texture */
    int extras;                 /* x has something: the general loop handles the object */
    int textured;               /* iso mode: an image texture modulates the base colour */
} rt_vobj;

/* Bounding volume hierarchy over a mesh's triangles (object space). */
typedef struct rt_bvh_node {
    float lo[3], hi[3];
    int left;       /* child index, or -1 for a leaf */
    int first, cnt; /* leaf: triangles tri[first .. first + cnt) */
} rt_bvh_node;

typedef struct rt_bvh {
    rt_bvh_node *nodes;
    int n_nodes;
    uint32_t *tri; /* triangle order */
} rt_bvh;

/* One geometric object prepared for this render. */
typedef struct rt_gobj {
    const vv_object *obj;
    vv_object_type type;
    double w2o[3][4]; /* world -> object */
    double nrm[3][3]; /* object normal -> world normal (M^-T) */
    vv_plane plane;   /* polygon: its plane (object space); axis dropped for 2-D test */
    int drop;
    rt_bvh bvh;
    vv_box obox; /* object-space bounds (not for planes) */
    float col[3];
    float kr, kt; /* reflectance (0 when the object does not reflect), transparency */
    double ior;
    int closed;     /* refracts (a solid); planes and polygons transmit straight */
    int bounded;    /* polygon, box: a world-space bounding sphere rejects rays early */
    vv_vec3 bc;     /* its centre */
    double br2;     /* its squared radius */
    vv_vec3 pn, pp; /* plane: world-space normal (M^-T n) and point */
} rt_gobj;

typedef struct rt_frame {
    rt_state *st;
    const vv_world *w;
    rt_vobj *vobjs;
    int n_vobj;
    rt_gobj *gobjs;
    int n_gobj;
    float dt;
    float bg[3];
    float ambient[3];
    rt_light lights[VV_MAX_LIGHTS];
    vv_vlight vlights[VV_MAX_LIGHTS]; /* the same, for volume shading */
    int n_lights;
    float et;
    int shadows, max_depth;
    int avx2;          /* the processor has AVX2 and FMA (vv_vray_classify) */
    double scene_size; /* for ray offsets */
    /* primary rays, affine in the pixel position before normalisation (as
     * the ray caster's): origin o00 + x ox + y oy, direction d00 + x dx + y dy */
    vv_vec3 o00, ox, oy, d00, dx, dy;
} rt_frame;

/* A surface hit. */
typedef struct rt_hit {
    double t;
    int gobj;  /* index into gobjs */
    vv_vec3 n; /* world normal (unit, outward for solids) */
} rt_hit;

/* ---------------------------------------------------------------------- */
/* Volume rays (the caches and sampling are src/render/volume_cache.h)      */

/* The world ray over [tmin, tmax] clipped to a volume in its index space. */
static inline int
vray_setup(const rt_vobj *ob, const vv_ray *wr, double tmin, double tmax, vv_vray *r) {
    return vv_vray_setup(ob->w2i, ob->dims, ob->planes, ob->n_planes, wr, tmin, tmax, r);
}

static inline float
lut_index_f(const rt_vobj *o, float v) {
    return vv_vtables_index(&o->tab, v);
}

/* World parameter where the ray leaves the subvolume containing p. */
static inline double
block_exit(const vv_vray *r, const float p[3], double t) {
    float te = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        float b = (float)(int)((p[a] > 0 ? p[a] : 0) * (1.0f / VV_VC_BLOCK));
        float bound = (r->d[a] > 0 ? b + 1 : b) * (float)VV_VC_BLOCK;
        float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    /* a rounding error must not stall the march */
    return t + (te > 1e-6f ? te : 1e-6f);
}

/* World parameter where the ray leaves the cube of 2 dist - 1 subvolumes
 * around the one containing p, all of which are empty (dist >= 1). */
static inline double
leap_exit(const rt_vobj *ob, const vv_vray *r, const float p[3], double t, int dist) {
    float te = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->inv[a] == 0)
            continue;
        const int nb = a == 0 ? ob->bx : a == 1 ? ob->by : ob->bz;
        int b = (int)((p[a] > 0 ? p[a] : 0) * (1.0f / VV_VC_BLOCK));
        b = b >= nb ? nb - 1 : b;
        float bound =
            r->d[a] > 0 ? (float)(b + dist) * VV_VC_BLOCK : (float)(b - dist + 1) * VV_VC_BLOCK;
        float ta = (bound - p[a]) * r->inv[a];
        te = ta < te ? ta : te;
    }
    return t + (te > 1e-6f ? te : 1e-6f);
}

/* ---------------------------------------------------------------------- */
/* Geometry                                                                  */

static inline vv_vec3
xf_point(const double m[3][4], vv_vec3 p) {
    return v3(m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
              m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
              m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]);
}

static inline vv_vec3
xf_dir(const double m[3][4], vv_vec3 d) {
    return v3(m[0][0] * d.x + m[0][1] * d.y + m[0][2] * d.z,
              m[1][0] * d.x + m[1][1] * d.y + m[1][2] * d.z,
              m[2][0] * d.x + m[2][1] * d.y + m[2][2] * d.z);
}

static inline double
v3get(vv_vec3 v, int a) {
    return a == 0 ? v.x : a == 1 ? v.y : v.z;
}

/* Slab test of an object-space box; returns the entry and exit. */
static int
box_slabs(const float lo[3], const float hi[3], const double o[3], const double inv[3], double tmax,
          double *tn) {
    double t0 = 0, t1 = tmax;
    for (int a = 0; a < 3; a++) {
        double ta = (lo[a] - o[a]) * inv[a], tb = (hi[a] - o[a]) * inv[a];
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
        if (t0 > t1)
            return 0;
    }
    *tn = t0;
    return 1;
}

/* Ray/triangle (Moeller-Trumbore); object space. */
static int
tri_hit(const float *P, const uint32_t *T, uint32_t ti, vv_vec3 o, vv_vec3 d, double tmin,
        double tmax, double *t, vv_vec3 *n) {
    const float *a = P + 3 * (size_t)T[3 * ti], *b = P + 3 * (size_t)T[3 * ti + 1],
                *c = P + 3 * (size_t)T[3 * ti + 2];
    vv_vec3 A = v3(a[0], a[1], a[2]);
    vv_vec3 e1 = v3(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    vv_vec3 e2 = v3(c[0] - a[0], c[1] - a[1], c[2] - a[2]);
    vv_vec3 pv = v3cross(d, e2);
    double det = v3dot(e1, pv);
    if (fabs(det) < 1e-300)
        return 0;
    double id = 1.0 / det;
    vv_vec3 tv = v3sub(o, A);
    double u = v3dot(tv, pv) * id;
    if (u < 0 || u > 1)
        return 0;
    vv_vec3 qv = v3cross(tv, e1);
    double v = v3dot(d, qv) * id;
    if (v < 0 || u + v > 1)
        return 0;
    double tt = v3dot(e2, qv) * id;
    if (!(tt > tmin && tt < tmax))
        return 0;
    *t = tt;
    *n = v3cross(e1, e2);
    return 1;
}

static int
bvh_hit(const rt_bvh *bvh, const vv_mesh *m, vv_vec3 o, vv_vec3 d, double tmin, double tmax,
        double *t, vv_vec3 *n) {
    if (!bvh->n_nodes)
        return 0;
    const double oo[3] = {o.x, o.y, o.z};
    const double inv[3] = {1.0 / d.x, 1.0 / d.y, 1.0 / d.z};
    int stack[128], sp = 0, hit = 0;
    stack[sp++] = 0;
    while (sp) {
        const rt_bvh_node *nd = &bvh->nodes[stack[--sp]];
        double tn;
        if (!box_slabs(nd->lo, nd->hi, oo, inv, tmax, &tn))
            continue;
        if (nd->left < 0) {
            for (int i = 0; i < nd->cnt; i++)
                if (tri_hit(m->positions, m->triangles, bvh->tri[nd->first + i], o, d, tmin, tmax,
                            t, n)) {
                    tmax = *t;
                    hit = 1;
                }
        } else if (sp < 126) {
            stack[sp++] = nd->left;
            stack[sp++] = nd->left + 1;
        }
    }
    return hit;
}

static void
bvh_bounds(const vv_mesh *m, const uint32_t *tri, int first, int cnt, rt_bvh_node *nd, float clo[3],
           float chi[3]) {
    for (int a = 0; a < 3; a++) {
        nd->lo[a] = clo[a] = INFINITY;
        nd->hi[a] = chi[a] = -INFINITY;
    }
    for (int i = first; i < first + cnt; i++)
        for (int a = 0; a < 3; a++) {
            float cen = 0;
            for (int k = 0; k < 3; k++) {
                float x = m->positions[3 * (size_t)m->triangles[3 * (size_t)tri[i] + k] + a];
                nd->lo[a] = x < nd->lo[a] ? x : nd->lo[a];
                nd->hi[a] = x > nd->hi[a] ? x : nd->hi[a];
                cen += x / 3;
            }
            clo[a] = cen < clo[a] ? cen : clo[a];
            chi[a] = cen > chi[a] ? cen : chi[a];
        }
}

static float
tri_centroid(const vv_mesh *m, uint32_t t, int a) {
    float s = 0;
    for (int k = 0; k < 3; k++)
        s += m->positions[3 * (size_t)m->triangles[3 * (size_t)t + k] + a];
    return s / 3;
}

/* Median split on the longest centroid axis, 4 triangles per leaf. Nodes
 * are stored with siblings adjacent (left, left + 1). */
static vv_status
bvh_build(rt_bvh *bvh, const vv_mesh *m) {
    memset(bvh, 0, sizeof *bvh);
    if (m->n_triangles == 0)
        return VV_OK;
    if (m->n_triangles > (size_t)1 << 28)
        return vv_error_set(VV_ERR_LIMIT, "mesh of %zu triangles is too large to ray trace",
                            m->n_triangles);
    const int n = (int)m->n_triangles;
    bvh->tri = malloc((size_t)n * sizeof *bvh->tri);
    bvh->nodes = malloc((size_t)(2 * n) * sizeof *bvh->nodes);
    int *stack = malloc((size_t)(2 * n) * sizeof *stack);
    if (!bvh->tri || !bvh->nodes || !stack) {
        free(stack);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a BVH of %d triangles", n);
    }
    for (int i = 0; i < n; i++)
        bvh->tri[i] = (uint32_t)i;
    bvh->n_nodes = 1;
    bvh->nodes[0].first = 0;
    bvh->nodes[0].cnt = n;
    int nt = 0;
    stack[nt++] = 0;
    while (nt) {
        rt_bvh_node *nd = &bvh->nodes[stack[--nt]];
        float clo[3], chi[3];
        bvh_bounds(m, bvh->tri, nd->first, nd->cnt, nd, clo, chi);
        nd->left = -1;
        if (nd->cnt <= 4)
            continue;
        int ax = 0;
        for (int a = 1; a < 3; a++)
            if (chi[a] - clo[a] > chi[ax] - clo[ax])
                ax = a;
        /* partial sort by centroid around the median (quickselect) */
        int lo = nd->first, hi = nd->first + nd->cnt - 1, mid = nd->first + nd->cnt / 2;
        while (lo < hi) {
            float pv = tri_centroid(m, bvh->tri[(lo + hi) / 2], ax);
            int i = lo, j = hi;
            while (i <= j) {
                while (tri_centroid(m, bvh->tri[i], ax) < pv)
                    i++;
                while (tri_centroid(m, bvh->tri[j], ax) > pv)
                    j--;
                if (i <= j) {
                    uint32_t x = bvh->tri[i];
                    bvh->tri[i] = bvh->tri[j];
                    bvh->tri[j] = x;
                    i++;
                    j--;
                }
            }
            if (mid <= j)
                hi = j;
            else if (mid >= i)
                lo = i;
            else
                break;
        }
        int l = bvh->n_nodes;
        bvh->n_nodes += 2;
        rt_bvh_node *L = &bvh->nodes[l], *R = &bvh->nodes[l + 1];
        L->first = nd->first;
        L->cnt = mid - nd->first;
        R->first = mid;
        R->cnt = nd->first + nd->cnt - mid;
        nd->left = l;
        stack[nt++] = l;
        stack[nt++] = l + 1;
    }
    free(stack);
    return VV_OK;
}

/* Nearest hit of one geometric object in (tmin, tmax); its object-space
 * normal in *no (not normalised, not flipped towards the ray; gobj_normal
 * turns it into the world normal), or NULL when not needed. */
static int
gobj_hit(const rt_gobj *g, const vv_ray *wr, double tmin, double tmax, double *t, vv_vec3 *no) {
    if (g->bounded) {
        /* the ray (t >= 0) misses the bounding sphere: its origin is outside
         * and the sphere lies behind it or off its line */
        const vv_vec3 oc = v3sub(g->bc, wr->origin);
        const double b = v3dot(oc, wr->dir), c = v3dot(oc, oc) - g->br2;
        if (c > 0 && (b <= 0 || b * b < c * v3dot(wr->dir, wr->dir)))
            return 0;
    }
    const vv_geometry *ge = &g->obj->geometry;
    if (g->type == VV_OBJECT_PLANE) {
        /* in world space: the plane's world normal and point, no transform */
        const double dn = v3dot(g->pn, wr->dir);
        if (fabs(dn) < 1e-300)
            return 0;
        const double tp = v3dot(g->pn, v3sub(g->pp, wr->origin)) / dn;
        if (!(tp > tmin && tp < tmax))
            return 0;
        *t = tp;
        if (no)
            *no = ge->normal;
        return 1;
    }
    vv_vec3 o = xf_point(g->w2o, wr->origin), d = xf_dir(g->w2o, wr->dir);
    vv_vec3 n = {0, 0, 1};
    double th = INFINITY;
    switch (g->type) {
    case VV_OBJECT_PLANE: {
        double dn = v3dot(ge->normal, d);
        if (fabs(dn) < 1e-300)
            return 0;
        th = v3dot(ge->normal, v3sub(ge->point, o)) / dn;
        n = ge->normal;
        break;
    }
    case VV_OBJECT_POLYGON: {
        double dn = v3dot(g->plane.n, d);
        if (fabs(dn) < 1e-300)
            return 0;
        th = -vv_plane_distance(g->plane, o) / dn;
        if (!(th > tmin && th < tmax))
            return 0;
        vv_vec3 p = v3add(o, v3scale(d, th));
        const int u = g->drop == 0 ? 1 : 0, v = g->drop == 2 ? 1 : 2;
        const double pu = v3get(p, u), pv = v3get(p, v);
        int inside = 0;
        for (int i = 0, j = ge->n_vertices - 1; i < ge->n_vertices; j = i++) {
            double ui = v3get(ge->vertices[i], u), vi = v3get(ge->vertices[i], v);
            double uj = v3get(ge->vertices[j], u), vj = v3get(ge->vertices[j], v);
            if ((vi > pv) != (vj > pv) && pu < (uj - ui) * (pv - vi) / (vj - vi) + ui)
                inside = !inside;
        }
        if (!inside)
            return 0;
        n = g->plane.n;
        break;
    }
    case VV_OBJECT_SPHERE: {
        vv_vec3 oc = v3sub(o, ge->center);
        double a = v3dot(d, d), b = v3dot(oc, d), c = v3dot(oc, oc) - ge->radius * ge->radius;
        double disc = b * b - a * c;
        if (disc < 0)
            return 0;
        double sq = sqrt(disc);
        double t0 = (-b - sq) / a, t1 = (-b + sq) / a;
        th = t0 > tmin ? t0 : t1;
        if (!(th > tmin && th < tmax))
            return 0;
        n = v3sub(v3add(o, v3scale(d, th)), ge->center);
        break;
    }
    case VV_OBJECT_BOX: {
        const double lo[3] = {ge->box.min.x, ge->box.min.y, ge->box.min.z};
        const double hi[3] = {ge->box.max.x, ge->box.max.y, ge->box.max.z};
        const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
        double t0 = -INFINITY, t1 = INFINITY;
        int a0 = 0, a1 = 0;
        double s0 = -1, s1 = 1;
        for (int a = 0; a < 3; a++) {
            if (fabs(dd[a]) < 1e-300) {
                if (oo[a] < lo[a] || oo[a] > hi[a])
                    return 0;
                continue;
            }
            double ta = (lo[a] - oo[a]) / dd[a], tb = (hi[a] - oo[a]) / dd[a];
            double sa = -1, sb = 1;
            if (ta > tb) {
                double x = ta;
                ta = tb;
                tb = x;
                sa = 1;
                sb = -1;
            }
            if (ta > t0) {
                t0 = ta;
                a0 = a;
                s0 = sa;
            }
            if (tb < t1) {
                t1 = tb;
                a1 = a;
                s1 = sb;
            }
        }
        if (t0 > t1)
            return 0;
        int ax;
        double sg;
        if (t0 > tmin) {
            th = t0;
            ax = a0;
            sg = s0;
        } else {
            th = t1;
            ax = a1;
            sg = s1;
        }
        n = v3(ax == 0 ? sg : 0, ax == 1 ? sg : 0, ax == 2 ? sg : 0);
        break;
    }
    case VV_OBJECT_CYLINDER: {
        vv_vec3 axis = v3sub(ge->top, ge->base);
        double h = v3len(axis);
        if (!(h > 0))
            return 0;
        vv_vec3 a = v3scale(axis, 1.0 / h);
        vv_vec3 oc = v3sub(o, ge->base);
        double da = v3dot(d, a), oa = v3dot(oc, a);
        vv_vec3 dp = v3sub(d, v3scale(a, da)), op = v3sub(oc, v3scale(a, oa));
        double A = v3dot(dp, dp), B = v3dot(op, dp), C = v3dot(op, op) - ge->radius * ge->radius;
        if (A > 1e-300) {
            double disc = B * B - A * C;
            if (disc >= 0) {
                double sq = sqrt(disc);
                double ts[2] = {(-B - sq) / A, (-B + sq) / A};
                for (int i = 0; i < 2; i++) {
                    double z = oa + ts[i] * da;
                    if (ts[i] > tmin && ts[i] < th && z >= 0 && z <= h) {
                        th = ts[i];
                        n = v3add(op, v3scale(dp, ts[i]));
                    }
                }
            }
        }
        if (ge->capped && fabs(da) > 1e-300) {
            for (int i = 0; i < 2; i++) {
                double tc = ((i ? h : 0) - oa) / da;
                if (!(tc > tmin && tc < th))
                    continue;
                vv_vec3 q = v3add(op, v3scale(dp, tc));
                if (v3dot(q, q) <= ge->radius * ge->radius) {
                    th = tc;
                    n = i ? a : v3scale(a, -1);
                }
            }
        }
        break;
    }
    case VV_OBJECT_MESH: {
        if (!ge->mesh || !bvh_hit(&g->bvh, ge->mesh, o, d, tmin, tmax, &th, &n))
            return 0;
        break;
    }
    default:
        return 0;
    }
    if (!(th > tmin && th < tmax))
        return 0;
    *t = th;
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
static int
nearest_hit(const rt_frame *fr, const vv_ray *wr, double tmin, double tmax, int primary,
            rt_hit *h) {
    int found = 0;
    for (int i = 0; i < fr->n_gobj; i++) {
        const rt_gobj *g = &fr->gobjs[i];
        if (!primary && !g->obj->visible_in_reflections)
            continue;
        double t;
        vv_vec3 n;
        if (gobj_hit(g, wr, tmin, tmax, &t, &n)) {
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

/* ---------------------------------------------------------------------- */
/* Shadow rays                                                               */

/* This volume's own transmittance towards directional light l from index
 * point p: its light volume, interpolated trilinearly. */
static float
light_volume_at(const rt_vobj *ob, int l, const float p[3]) {
    float f[3];
    int i0[3];
    for (int a = 0; a < 3; a++) {
        float x = p[a] * (1.0f / RT_LGRID);
        x = x < 0 ? 0 : x > (float)(ob->ldim[a] - 1) ? (float)(ob->ldim[a] - 1) : x;
        int i = (int)x;
        i = i > ob->ldim[a] - 2 ? ob->ldim[a] - 2 : i;
        i0[a] = i;
        f[a] = x - (float)i;
    }
    const size_t sy = (size_t)ob->ldim[0], sz = sy * (size_t)ob->ldim[1];
    const float *v = ob->lvol[l] + (size_t)i0[2] * sz + (size_t)i0[1] * sy + (size_t)i0[0];
    float x0 = vv_lerpf(v[0], v[1], f[0]), x1 = vv_lerpf(v[sy], v[sy + 1], f[0]);
    float x2 = vv_lerpf(v[sz], v[sz + 1], f[0]), x3 = vv_lerpf(v[sz + sy], v[sz + sy + 1], f[0]);
    return vv_lerpf(vv_lerpf(x0, x1, f[1]), vv_lerpf(x2, x3, f[1]), f[2]);
}

/* Transmittance of one volume along the world ray over (tmin, tmax).
 * light >= 0: the ray is a whole shadow ray towards that directional
 * light (tmax infinite), answered from the light volume where there is
 * one. */
static float
volume_transmittance(const rt_frame *fr, const rt_vobj *ob, const vv_ray *wr, double tmin,
                     double tmax, int light) {
    vv_vray r;
    if (!vray_setup(ob, wr, tmin, tmax, &r))
        return 1.0f;
    const vv_vcache *c = ob->c;
    const double dt = fr->dt;
    if (light >= 0 && ob->lvol[light])
        return light_volume_at(ob, light, r.o); /* r.o: where the ray enters */
    if (ob->mode == VV_MODE_COMPOSITE) {
        /* exp(-sum sigma h): each visible subvolume's piece of the ray is cut
         * into equal parts no longer than dt, sampled at their midpoints */
        double tau = 0;
        double t = r.t0;
        const double ds = 2 * ob->vox > dt ? 2 * ob->vox : dt; /* shadows are smooth */
        while (t < r.t1) {
            float p[3];
            vv_vray_point(&r, t, p);
            const size_t b = vv_vcache_block(ob->c, p);
            double te = ob->bdist[b] ? leap_exit(ob, &r, p, t, ob->bdist[b]) : block_exit(&r, p, t);
            te = te < r.t1 ? te : r.t1;
            if (ob->bvis[b]) {
                const double len = te - t;
                int n = (int)vv_ceil_pos(len / ds);
                n = n < 1 ? 1 : n;
                const double h = len / n;
                for (int s = 0; s < n; s++) {
                    float q[3];
                    vv_vray_point(&r, t + (s + 0.5) * h, q);
                    tau += ob->ext[(int)lut_index_f(ob, vv_vcache_sample(c, q))] * h;
                }
                if (tau > 5.6) /* T < 0.0037, under one 8-bit level */
                    return 0.0f;
            }
            t = te;
        }
        return (float)exp(-tau);
    }
    if (ob->mode == VV_MODE_ISO) {
        /* blocked where the ray is inside the surface (value >= isovalue) */
        double t = r.t0;
        while (t <= r.t1) {
            float p[3];
            vv_vray_point(&r, t, p);
            const size_t b = vv_vcache_block(ob->c, p);
            double te = ob->bdist[b] ? leap_exit(ob, &r, p, t, ob->bdist[b]) : block_exit(&r, p, t);
            if (ob->bvis[b]) {
                double tl = te < r.t1 ? te : r.t1;
                for (double ts = t; ts <= tl; ts += dt) {
                    vv_vray_point(&r, ts, p);
                    if (vv_vcache_sample(c, p) >= ob->iso)
                        return 0.0f;
                }
                vv_vray_point(&r, tl, p);
                if (vv_vcache_sample(c, p) >= ob->iso)
                    return 0.0f;
            }
            t = te;
        }
        return 1.0f;
    }
    /* projections: one minus the opacity of the projected value */
    const int mip = ob->mode == VV_MODE_MIP, minip = ob->mode == VV_MODE_MINIP;
    float best = mip ? -INFINITY : INFINITY;
    double sum = 0;
    long cnt = 0;
    for (double t = r.t0; t <= r.t1; t += dt) {
        float p[3];
        vv_vray_point(&r, t, p);
        float x = vv_vcache_sample(c, p);
        if (mip)
            best = x > best ? x : best;
        else if (minip)
            best = x < best ? x : best;
        sum += x;
        cnt++;
    }
    if (!cnt)
        return 1.0f;
    float val = mip || minip ? best : (float)(sum / (double)cnt);
    return 1.0f - ob->lut[4 * (int)lut_index_f(ob, val)];
}

/* Transmittance from world point p towards light l over [start, limit]
 * world units from p (limit INFINITY: up to the light), past every object
 * that casts shadows. */
static float
shadow_segment(const rt_frame *fr, vv_vec3 p, const rt_light *l, double start, double limit) {
    vv_ray r;
    double tmax;
    if (l->point) {
        vv_vec3 d = v3sub(v3(l->pos[0], l->pos[1], l->pos[2]), p);
        tmax = v3len(d);
        if (!(tmax > 0))
            return 1.0f;
        r.dir = v3scale(d, 1.0 / tmax);
    } else {
        r.dir = v3(l->dir[0], l->dir[1], l->dir[2]);
        tmax = INFINITY;
    }
    /* a whole shadow ray towards a directional light: light volumes answer it */
    const int light = !l->point && limit == INFINITY ? (int)(l - fr->lights) : -1;
    tmax = limit < tmax ? limit : tmax;
    r.origin = p;
    float T = 1.0f;
    const double eps = RT_EPS * fr->scene_size;
    for (int i = 0; i < fr->n_gobj && T > 0; i++) {
        const rt_gobj *g = &fr->gobjs[i];
        if (!g->obj->casts_shadows)
            continue;
        double t;
        if (gobj_hit(g, &r, start > eps ? start : eps, tmax, &t, NULL))
            T *= g->kt;
    }
    for (int i = 0; i < fr->n_vobj && T > 0.0037f; i++) {
        const rt_vobj *ob = &fr->vobjs[i];
        if (ob->obj->casts_shadows)
            T *= volume_transmittance(fr, ob, &r, start, tmax, light);
    }
    return T;
}

static float
shadow_ray(const rt_frame *fr, vv_vec3 p, const rt_light *l, double start) {
    return shadow_segment(fr, p, l, start, INFINITY);
}

static inline vv_vec3
index_to_world(const rt_vobj *ob, const double q[3]) {
    return v3(ob->i2w[0][0] * q[0] + ob->i2w[0][1] * q[1] + ob->i2w[0][2] * q[2] + ob->i2w[0][3],
              ob->i2w[1][0] * q[0] + ob->i2w[1][1] * q[1] + ob->i2w[1][2] * q[2] + ob->i2w[1][3],
              ob->i2w[2][0] * q[0] + ob->i2w[2][1] * q[1] + ob->i2w[2][2] * q[2] + ob->i2w[2][3]);
}

/* A composite volume's own transmittance over the segment of world length
 * seg from index point p (world wp) along the index direction li (world
 * direction ldir): one sample at its middle, exp(-sigma seg); 1 where the
 * middle is outside the volume, cut away or in a subvolume that cannot
 * contribute. */
static float
own_segment(const rt_vobj *ob, const double p[3], const double li[3], double seg, vv_vec3 wp,
            vv_vec3 ldir) {
    float q[3];
    for (int a = 0; a < 3; a++) {
        q[a] = (float)(p[a] + li[a] * seg * 0.5);
        if (!(q[a] >= 0 && q[a] <= (float)(ob->dims[a] - 1)))
            return 1.0f;
    }
    if (!ob->bvis[vv_vcache_block(ob->c, q)])
        return 1.0f;
    if (ob->n_planes) {
        const vv_vec3 wm = v3add(wp, v3scale(ldir, 0.5 * seg));
        for (int i = 0; i < ob->n_planes; i++)
            if (vv_plane_distance(ob->planes[i], wm) < 0)
                return 1.0f;
    }
    return expf(-ob->ext[(int)lut_index_f(ob, vv_vcache_sample(ob->c, q))] * (float)seg);
}

/* The shadow grid of a directional light, swept layer by layer from the
 * light's side (a light volume): a grid point's transmittance is that of
 * the point one layer towards the light (bilinear in that layer) times the
 * transmittance of the segment between them (shadow_segment: this volume,
 * the other volumes and geometry). The first layer, and points whose
 * upstream point leaves the grid, trace a whole shadow ray. */
static vv_status
sweep_grid(const rt_frame *fr, const rt_vobj *ob, int l, int nt, double G, const int *gd, int own,
           float **out) {
    const rt_light *lt = &fr->lights[l];
    *out = NULL;
    double li[3];
    for (int a = 0; a < 3; a++)
        li[a] =
            ob->w2i[a][0] * lt->dir[0] + ob->w2i[a][1] * lt->dir[1] + ob->w2i[a][2] * lt->dir[2];
    int A = 0;
    for (int a = 1; a < 3; a++)
        if (fabs(li[a]) > fabs(li[A]))
            A = a;
    if (!(fabs(li[A]) > 0))
        return VV_OK;
    const int B = (A + 1) % 3, Cc = (A + 2) % 3;
    const vv_vec3 ldir = v3(lt->dir[0], lt->dir[1], lt->dir[2]);
    const size_t ng = (size_t)gd[0] * (size_t)gd[1] * (size_t)gd[2];
    float *T = malloc(ng * sizeof *T);
    if (!T)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a shadow grid");
    const double seg = G / fabs(li[A]);
    const int up = li[A] > 0 ? 1 : -1; /* the layer towards the light */
    const int first = up > 0 ? gd[A] - 1 : 0;
    const int nb = gd[B], nc = gd[Cc];
    for (int n = 0; n < gd[A]; n++) {
        const int la = first - up * n;
#pragma omp parallel for schedule(dynamic, 16) num_threads(nt)
        for (int bc = 0; bc < nb * nc; bc++) {
            int id[3];
            id[A] = la;
            id[B] = bc % nb;
            id[Cc] = bc / nb;
            const double p[3] = {id[0] * G, id[1] * G, id[2] * G};
            const vv_vec3 wp = index_to_world(ob, p);
            float t = -1;
            if (n > 0) {
                const double qb = (p[B] + li[B] * seg) / G, qc = (p[Cc] + li[Cc] * seg) / G;
                if (qb >= 0 && qb <= nb - 1 && qc >= 0 && qc <= nc - 1) {
                    int ib = (int)qb, ic = (int)qc;
                    ib = ib > nb - 2 ? nb - 2 : ib;
                    ic = ic > nc - 2 ? nc - 2 : ic;
                    const float fb = (float)(qb - ib), fc = (float)(qc - ic);
                    float v[4];
                    for (int k = 0; k < 4; k++) {
                        int q[3];
                        q[A] = la + up;
                        q[B] = ib + (k & 1);
                        q[Cc] = ic + (k >> 1);
                        v[k] = T[((size_t)q[2] * (size_t)gd[1] + (size_t)q[1]) * (size_t)gd[0] +
                                 (size_t)q[0]];
                    }
                    const float tq =
                        vv_lerpf(vv_lerpf(v[0], v[1], fb), vv_lerpf(v[2], v[3], fb), fc);
                    t = tq <= 0 ? 0.0f
                        : own   ? tq * own_segment(ob, p, li, seg, wp, ldir)
                                : tq * shadow_segment(fr, wp, lt, 0, seg);
                }
            }
            if (t < 0)
                t = own ? volume_transmittance(fr, ob, &(vv_ray){wp, ldir}, 0, INFINITY, -1)
                        : shadow_ray(fr, wp, lt, 0);
            T[((size_t)id[2] * (size_t)gd[1] + (size_t)id[1]) * (size_t)gd[0] + (size_t)id[0]] = t;
        }
    }
    *out = T;
    return VV_OK;
}

/* The shadow grid of directional light l for the volume's own samples
 * (shadow_grid=2): swept through every object that casts shadows. */
static vv_status
sweep_light(const rt_frame *fr, rt_vobj *ob, int l, int nt) {
    vv_status s = sweep_grid(fr, ob, l, nt, RT_SGRID, ob->gdim, 0, &ob->sweep[l]);
    for (int a = 0; a < 3; a++)
        ob->lidx[l][a] =
            (float)(ob->w2i[a][0] * fr->lights[l].dir[0] + ob->w2i[a][1] * fr->lights[l].dir[1] +
                    ob->w2i[a][2] * fr->lights[l].dir[2]);
    return s;
}

/* The light volume of a composite volume for directional light l: its own
 * transmittance towards the light from every point of a grid RT_LGRID
 * voxels apart, swept layer by layer from the light's side. Whole shadow
 * rays towards the light then cross the volume in one lookup where they
 * enter it (light_volume_at). */
static int
lv_matches(const rt_lv *e, const rt_frame *fr, const rt_vobj *ob, int l) {
    if (e->vol != ob->obj->volume || e->modified != ob->obj->volume->modified || e->dt != fr->dt ||
        e->n_planes != ob->n_planes || e->lut_lo != ob->tab.lut_lo ||
        e->lut_scale != ob->tab.lut_scale)
        return 0;
    for (int a = 0; a < 3; a++)
        if (e->dir[a] != fr->lights[l].dir[a])
            return 0;
    return memcmp(e->w2i, ob->w2i, sizeof e->w2i) == 0 &&
           memcmp(e->planes, ob->planes, (size_t)ob->n_planes * sizeof *ob->planes) == 0 &&
           memcmp(e->ext, ob->ext, sizeof e->ext) == 0;
}

static void
lv_release(rt_lv *e) {
    vv_volume_free(e->vol);
    free(e->T);
    memset(e, 0, sizeof *e);
}

static vv_status
build_light_volume(const rt_frame *fr, rt_vobj *ob, int l, int nt) {
    for (int a = 0; a < 3; a++) {
        ob->ldim[a] = (ob->dims[a] - 1 + RT_LGRID - 1) / RT_LGRID + 1;
        ob->ldim[a] = ob->ldim[a] < 2 ? 2 : ob->ldim[a];
    }
    rt_state *st = fr->st;
    for (int i = 0; i < RT_LV_CACHE; i++)
        if (st->lv[i].vol && lv_matches(&st->lv[i], fr, ob, l)) {
            st->lv[i].used = st->frame;
            ob->lvol[l] = st->lv[i].T;
            return VV_OK;
        }
    vv_status s = sweep_grid(fr, ob, l, nt, RT_LGRID, ob->ldim, 1, &ob->lvol[l]);
    if (s != VV_OK || !ob->lvol[l])
        return s;
    /* keep it: in a free slot, else in place of the least recently used one
     * that this frame does not use */
    int slot = -1;
    for (int i = 0; i < RT_LV_CACHE; i++)
        if (!st->lv[i].vol) {
            slot = i;
            break;
        } else if (st->lv[i].used != st->frame &&
                   (slot < 0 || st->lv[i].used < st->lv[slot].used)) {
            slot = i;
        }
    if (slot < 0) {
        ob->lvol_owned |= 1u << l;
        return VV_OK;
    }
    rt_lv *e = &st->lv[slot];
    lv_release(e);
    e->vol = vv_volume_ref(ob->obj->volume);
    e->modified = ob->obj->volume->modified;
    memcpy(e->w2i, ob->w2i, sizeof e->w2i);
    for (int a = 0; a < 3; a++)
        e->dir[a] = fr->lights[l].dir[a];
    e->dt = fr->dt;
    e->n_planes = ob->n_planes;
    memcpy(e->planes, ob->planes, (size_t)ob->n_planes * sizeof *ob->planes);
    e->lut_lo = ob->tab.lut_lo;
    e->lut_scale = ob->tab.lut_scale;
    memcpy(e->ext, ob->ext, sizeof e->ext);
    e->T = ob->lvol[l];
    e->used = st->frame;
    return VV_OK;
}

/* Shadow of a volume sample at index point pi (world pw) for light l. */
/* The last shadow-grid cell a ray's samples looked up, per light: its 8
 * corner transmittances, so that the samples of one ray inside one cell
 * (about 8 at a step of half a voxel) read the shared grid once. */
typedef struct rt_scache {
    const rt_vobj *ob;          /* the volume the cells belong to, NULL: none */
    size_t cell[VV_MAX_LIGHTS]; /* grid index of the cell's first corner */
    float v[VV_MAX_LIGHTS][8];  /* its corners' transmittances */
} rt_scache;

static float
volume_sample_shadow(const rt_frame *fr, const rt_vobj *ob, int l, const float pi[3],
                     const float pw[3], rt_scache *sc) {
    if (ob->sweep[l]) {
        /* the swept grid, looked up 1.5 grid cells towards the light so that
         * a surface does not shadow itself */
        const float bias = (float)(1.5 * RT_SGRID * ob->vox);
        float f[3];
        int i0[3];
        for (int a = 0; a < 3; a++) {
            float x = (pi[a] + ob->lidx[l][a] * bias) * (1.0f / RT_SGRID);
            x = x < 0 ? 0 : x > (float)(ob->gdim[a] - 1) ? (float)(ob->gdim[a] - 1) : x;
            int i = (int)x;
            i = i > ob->gdim[a] - 2 ? ob->gdim[a] - 2 : i;
            i0[a] = i;
            f[a] = x - (float)i;
        }
        const float *T = ob->sweep[l];
        const size_t sy = (size_t)ob->gdim[0], sz = sy * (size_t)ob->gdim[1];
        const float *v = T + (size_t)i0[2] * sz + (size_t)i0[1] * sy + (size_t)i0[0];
        float x0 = vv_lerpf(v[0], v[1], f[0]), x1 = vv_lerpf(v[sy], v[sy + 1], f[0]);
        float x2 = vv_lerpf(v[sz], v[sz + 1], f[0]),
              x3 = vv_lerpf(v[sz + sy], v[sz + sy + 1], f[0]);
        return vv_lerpf(vv_lerpf(x0, x1, f[1]), vv_lerpf(x2, x3, f[1]), f[2]);
    }
    if (!ob->sgrid[l]) /* isosurfaces, or shadow_grid=0: an exact shadow ray */
        return shadow_ray(fr, v3(pw[0], pw[1], pw[2]), &fr->lights[l], ob->vox);
    _Atomic uint32_t *g = ob->sgrid[l];
    float f[3];
    int i0[3];
    for (int a = 0; a < 3; a++) {
        float x = pi[a] < 0 ? 0 : pi[a];
        x *= 1.0f / RT_SGRID;
        int i = (int)x;
        i = i > ob->gdim[a] - 2 ? ob->gdim[a] - 2 : i;
        i0[a] = i;
        f[a] = x - (float)i;
        f[a] = f[a] > 1 ? 1 : f[a];
    }
    const size_t base =
        ((size_t)i0[2] * (size_t)ob->gdim[1] + (size_t)i0[1]) * (size_t)ob->gdim[0] + (size_t)i0[0];
    float vloc[8], *v = vloc;
    if (sc) {
        if (sc->ob != ob) {
            sc->ob = ob;
            for (int k = 0; k < VV_MAX_LIGHTS; k++)
                sc->cell[k] = SIZE_MAX;
        }
        v = sc->v[l];
        if (sc->cell[l] == base) {
            float x0 = vv_lerpf(v[0], v[1], f[0]), x1 = vv_lerpf(v[2], v[3], f[0]);
            float x2 = vv_lerpf(v[4], v[5], f[0]), x3 = vv_lerpf(v[6], v[7], f[0]);
            return vv_lerpf(vv_lerpf(x0, x1, f[1]), vv_lerpf(x2, x3, f[1]), f[2]);
        }
        sc->cell[l] = base;
    }
    for (int k = 0; k < 8; k++) {
        int gi = i0[0] + (k & 1), gj = i0[1] + ((k >> 1) & 1), gk = i0[2] + ((k >> 2) & 1);
        size_t idx =
            ((size_t)gk * (size_t)ob->gdim[1] + (size_t)gj) * (size_t)ob->gdim[0] + (size_t)gi;
        uint32_t bits = atomic_load_explicit(&g[idx], memory_order_relaxed);
        float T;
        if (bits) {
            float x;
            memcpy(&x, &bits, sizeof x);
            T = x - 1.0f;
        } else {
            /* trace it: deterministic, so two threads racing store the same */
            double q[3] = {(double)gi * RT_SGRID, (double)gj * RT_SGRID, (double)gk * RT_SGRID};
            for (int a = 0; a < 3; a++)
                q[a] = q[a] > ob->dims[a] - 1 ? ob->dims[a] - 1 : q[a];
            vv_vec3 wp = v3(
                ob->i2w[0][0] * q[0] + ob->i2w[0][1] * q[1] + ob->i2w[0][2] * q[2] + ob->i2w[0][3],
                ob->i2w[1][0] * q[0] + ob->i2w[1][1] * q[1] + ob->i2w[1][2] * q[2] + ob->i2w[1][3],
                ob->i2w[2][0] * q[0] + ob->i2w[2][1] * q[1] + ob->i2w[2][2] * q[2] + ob->i2w[2][3]);
            T = shadow_ray(fr, wp, &fr->lights[l], 1.5 * RT_SGRID * ob->vox);
            float x = T + 1.0f;
            memcpy(&bits, &x, sizeof bits);
            atomic_store_explicit(&g[idx], bits, memory_order_relaxed);
            T = x - 1.0f; /* as the other threads will read it: images do not
                           * depend on which thread traced a grid point */
        }
        v[k] = T;
    }
    float x0 = vv_lerpf(v[0], v[1], f[0]), x1 = vv_lerpf(v[2], v[3], f[0]);
    float x2 = vv_lerpf(v[4], v[5], f[0]), x3 = vv_lerpf(v[6], v[7], f[0]);
    return vv_lerpf(vv_lerpf(x0, x1, f[1]), vv_lerpf(x2, x3, f[1]), f[2]);
}

/* ---------------------------------------------------------------------- */
/* Shading                                                                   */

/* Where a volume sample's shadow is looked up (vv_vshadow_fn). */
typedef struct rt_shadow_ctx {
    const rt_frame *fr;
    const rt_vobj *ob;
    const float *pi, *pw; /* index and world position */
    rt_scache *sc;        /* the ray's last cells, or NULL */
} rt_shadow_ctx;

static inline float
sample_shadow(const void *ctx, int l) {
    const rt_shadow_ctx *c = ctx;
    return volume_sample_shadow(c->fr, c->ob, l, c->pi, c->pw, c->sc);
}

/* The ray caster's volume Phong (vv_vshade: reflection vector, two-sided,
 * specular weighted by the sample opacity), each light scaled by its
 * shadow. */
static void
shade_volume(const rt_frame *fr, const rt_vobj *o, const float g[3], const float pi[3],
             const float pw[3], const float v[3], const float col[3], float alpha, rt_scache *sc,
             float out[3]) {
    const int shadows = fr->shadows && o->obj->receives_shadows;
    const rt_shadow_ctx ctx = {fr, o, pi, pw, sc};
    /* two calls, so that the compiler inlines the shadow lookup */
    if (shadows)
        vv_vshade(&o->sh, fr->vlights, fr->n_lights, g, pw, v, col, alpha, sample_shadow, &ctx,
                  out);
    else
        vv_vshade(&o->sh, fr->vlights, fr->n_lights, g, pw, v, col, alpha, NULL, NULL, out);
}

static void trace(const rt_frame *fr, const vv_ray *wr, int depth, int primary, float weight,
                  float out[3], float *alpha, float *tdepth);

/* Local Phong of a surface point with shadows: one-sided, the normal n
 * facing the viewer. */
static void
shade_surface_local(const rt_frame *fr, const vv_material *m, const float col[3], int receives,
                    vv_vec3 p, vv_vec3 n, vv_vec3 v, float out[3]) {
    float d[3], s[3] = {0, 0, 0};
    for (int ch = 0; ch < 3; ch++)
        d[ch] = (float)m->ambient * fr->ambient[ch];
    const double eps = RT_EPS * fr->scene_size;
    vv_vec3 po = v3add(p, v3scale(n, eps));
    for (int l = 0; l < fr->n_lights; l++) {
        const rt_light *lt = &fr->lights[l];
        vv_vec3 L = v3(lt->dir[0], lt->dir[1], lt->dir[2]);
        if (lt->point)
            L = v3norm(v3sub(v3(lt->pos[0], lt->pos[1], lt->pos[2]), p));
        double ndl = v3dot(n, L);
        if (ndl <= 0)
            continue;
        float sh = fr->shadows && receives ? shadow_ray(fr, po, lt, 0) : 1.0f;
        if (sh <= 0)
            continue;
        vv_vec3 R = v3sub(v3scale(n, 2 * ndl), L);
        double rv = v3dot(R, v);
        double sp = rv > 0 && m->specular > 0 ? pow(rv, m->shininess) : 0;
        for (int ch = 0; ch < 3; ch++) {
            d[ch] += sh * (float)(m->diffuse * ndl) * lt->col[ch];
            s[ch] += sh * (float)(m->specular * sp) * lt->col[ch];
        }
    }
    for (int ch = 0; ch < 3; ch++)
        out[ch] = d[ch] * col[ch] + s[ch];
}

/* Reflected and transmitted light at a surface point, added to out with
 * weights kr and kt. n: unit normal facing the incoming ray's origin side;
 * outward: the object's outward normal (solids refract). */
static void
shade_secondary(const rt_frame *fr, const vv_ray *wr, vv_vec3 p, vv_vec3 n, vv_vec3 outward,
                float kr, float kt, double ior, int solid, int depth, float weight, float out[3]) {
    if (depth >= fr->max_depth)
        return;
    const double eps = RT_EPS * fr->scene_size;
    const double dn = v3dot(wr->dir, n);
    float tmp[3], a, dd;
    if (kr > 0 && weight * kr >= RT_MIN_WEIGHT) {
        vv_ray rr;
        rr.dir = v3norm(v3sub(wr->dir, v3scale(n, 2 * dn)));
        rr.origin = v3add(p, v3scale(n, eps));
        trace(fr, &rr, depth + 1, 0, weight * kr, tmp, &a, &dd);
        for (int ch = 0; ch < 3; ch++)
            out[ch] += kr * tmp[ch];
    }
    if (kt > 0 && weight * kt >= RT_MIN_WEIGHT) {
        vv_ray tr;
        tr.dir = wr->dir;
        if (solid && ior > 0 && ior != 1) {
            /* Snell: entering when the ray meets the outward normal head on */
            const int entering = v3dot(wr->dir, outward) < 0;
            const double eta = entering ? 1.0 / ior : ior;
            const double ci = -dn; /* cos of incidence, n faces the ray origin */
            const double k = 1 - eta * eta * (1 - ci * ci);
            if (k < 0) /* total internal reflection */
                tr.dir = v3norm(v3sub(wr->dir, v3scale(n, 2 * dn)));
            else
                tr.dir = v3norm(v3add(v3scale(wr->dir, eta), v3scale(n, eta * ci - sqrt(k))));
        }
        const double side = v3dot(tr.dir, n) < 0 ? -1 : 1;
        tr.origin = v3add(p, v3scale(n, side * eps));
        trace(fr, &tr, depth + 1, 0, weight * kt, tmp, &a, &dd);
        for (int ch = 0; ch < 3; ch++)
            out[ch] += kt * tmp[ch];
    }
}

/* I_s of a geometric hit. */
static void
shade_geometry(const rt_frame *fr, const vv_ray *wr, const rt_hit *h, int depth, float weight,
               float out[3]) {
    const rt_gobj *g = &fr->gobjs[h->gobj];
    vv_vec3 p = ray_at(wr, h->t);
    vv_vec3 n = h->n;
    if (v3dot(n, wr->dir) > 0)
        n = v3scale(n, -1);
    vv_vec3 v = v3scale(wr->dir, -1);
    float loc[3], col[3] = {g->col[0], g->col[1], g->col[2]};
    if (g->obj->texture.image) {
        /* the texture is defined on the object's own coordinates */
        const vv_vec3 tc = vv_texture_map_eval(&g->obj->texture, xf_point(g->w2o, p));
        col[0] *= (float)tc.x;
        col[1] *= (float)tc.y;
        col[2] *= (float)tc.z;
    }
    shade_surface_local(fr, &g->obj->material, col, g->obj->receives_shadows, p, n, v, loc);
    float kl = 1 - g->kr - g->kt;
    kl = kl < 0 ? 0 : kl;
    for (int ch = 0; ch < 3; ch++)
        out[ch] = kl * loc[ch];
    shade_secondary(fr, wr, p, n, h->n, g->kr, g->kt, g->ior, g->closed, depth, weight, out);
}

/* ---------------------------------------------------------------------- */
/* Ray tracing                                                               */

/* Composites one classified sample (opacity and premultiplied colour e) at
 * index point p, ray parameter t, under the accumulated C, A; gin: the
 * index-space gradient there, or NULL to compute it. */
static inline void
composite_sample(const rt_frame *fr, const rt_vobj *ob, const vv_ray *wr, const float v[3],
                 const float *e, const float p[3], double t, const float *gin, rt_scache *sc,
                 float C[3], float *A) {
    const float w = 1 - *A;
    if (ob->obj->shading) {
        float g[3], pw[3], o3[3];
        if (gin)
            memcpy(g, gin, sizeof g);
        else
            vv_vcache_gradient(ob->c, p, g);
        pw[0] = (float)(wr->origin.x + t * wr->dir.x);
        pw[1] = (float)(wr->origin.y + t * wr->dir.y);
        pw[2] = (float)(wr->origin.z + t * wr->dir.z);
        shade_volume(fr, ob, g, p, pw, v, e + 1, e[0], sc, o3);
        C[0] += w * o3[0];
        C[1] += w * o3[1];
        C[2] += w * o3[2];
    } else {
        C[0] += w * e[1];
        C[1] += w * e[2];
        C[2] += w * e[3];
    }
    *A += w * e[0];
}

/* The common case, one composite volume on the ray: subvolume by
 * subvolume, leaping over empty ones, the same samples t = k dt as the
 * general loop below, classified a chunk at a time (vv_vray_classify, the
 * ray caster's kernel) before the visible ones are shaded. */
static void
march_one(const rt_frame *fr, const rt_vobj *ob, const vv_vray *r, const vv_ray *wr,
          const float v[3], float C[3], float *Aout, float *dep) {
    const double dt = fr->dt, inv_dt = 1.0 / fr->dt;
    const vv_vcache *c = ob->c;
    const int shading = ob->obj->shading;
    rt_scache sc;
    sc.ob = NULL; /* the rest is filled when first used */
    float A = 0;
    double k = vv_ceil_pos(r->t0 * inv_dt);
    const double kend = floor(r->t1 * inv_dt);
    while (k <= kend) {
        float p[3];
        vv_vray_point(r, k * dt, p);
        const size_t b = vv_vcache_block(ob->c, p);
        if (!ob->bvis[b]) {
            const double ks = vv_ceil_pos(leap_exit(ob, r, p, k * dt, ob->bdist[b]) * inv_dt);
            k = ks > k + 1 ? ks : k + 1;
            continue;
        }
        double klast = floor(block_exit(r, p, k * dt) * inv_dt);
        klast = klast < kend ? klast : kend;
        klast = klast < k ? k : klast;
        const int n = (int)(klast - k) + 1;
        for (int s0 = 0; s0 < n; s0 += VV_VC_CHUNK) {
            const int m = n - s0 < VV_VC_CHUNK ? n - s0 : VV_VC_CHUNK;
            const double kfirst = k + s0;
            size_t cell[VV_VC_CHUNK];
            int32_t entry[VV_VC_CHUNK];
            float fx[VV_VC_CHUNK], fy[VV_VC_CHUNK], fz[VV_VC_CHUNK];
            vv_vray_classify(c, &ob->tab, r, kfirst, dt, m, fr->avx2, cell, fx, fy, fz, entry);
            for (int s = 0; s < m; s++) {
                const float *e = ob->lut + entry[s];
                if (e[0] <= 0)
                    continue;
                const double t = (kfirst + s) * dt;
                float g[3] = {0, 0, 0};
                if (shading) {
                    vv_vray_point(r, t, p);
                    if (c->nrm) {
                        const float f[3] = {fx[s], fy[s], fz[s]};
                        vv_vcache_gradient_at(c, cell[s], f, g);
                    } else {
                        vv_vcache_gradient(c, p, g);
                    }
                }
                composite_sample(fr, ob, wr, v, e, p, t, g, &sc, C, &A);
                if (*dep == INFINITY)
                    *dep = (float)t;
                if (A >= fr->et) {
                    *Aout = A > 1 ? 1 : A;
                    return;
                }
            }
        }
        k = klast + 1;
    }
    *Aout = A > 1 ? 1 : A;
}

/* Front-to-back compositing of the composite and iso volumes along the ray
 * over [0, tlim] on the samples t = k dt (the ray caster's grid). An iso
 * hit is a surface: shaded with shadows and reflections, it ends the ray. */
static void
march_volumes(const rt_frame *fr, const vv_ray *wr, double tlim, int depth, int primary,
              float weight, float C[3], float *Aout, float *dep) {
    vv_vray rays[RT_MAX_OBJ];
    int act[RT_MAX_OBJ];
    rt_scache sc;
    sc.ob = NULL; /* the rest is filled when first used */
    int na = 0;
    double tmin = INFINITY, tmax = -INFINITY;
    for (int i = 0; i < fr->n_vobj; i++) {
        const rt_vobj *ob = &fr->vobjs[i];
        if (ob->mode != VV_MODE_COMPOSITE && ob->mode != VV_MODE_ISO)
            continue;
        if (!primary && !ob->obj->visible_in_reflections)
            continue;
        if (vray_setup(ob, wr, 0, tlim, &rays[na])) {
            act[na] = i;
            tmin = rays[na].t0 < tmin ? rays[na].t0 : tmin;
            tmax = rays[na].t1 > tmax ? rays[na].t1 : tmax;
            na++;
        }
    }
    float A = 0;
    if (na == 0) {
        *Aout = 0;
        return;
    }
    const double dt = fr->dt;
    const float v[3] = {(float)-wr->dir.x, (float)-wr->dir.y, (float)-wr->dir.z};
    if (na == 1 && fr->vobjs[act[0]].mode == VV_MODE_COMPOSITE && !fr->vobjs[act[0]].extras) {
        march_one(fr, &fr->vobjs[act[0]], &rays[0], wr, v, C, Aout, dep);
        return;
    }
    float prev_v[RT_MAX_OBJ];
    double prev_t[RT_MAX_OBJ];
    int has_prev[RT_MAX_OBJ];
    for (int i = 0; i < na; i++)
        has_prev[i] = 0;
    double k = vv_ceil_pos(tmin / dt);
    const double kend = floor(tmax / dt);
    while (k <= kend) {
        const double t = k * dt;
        double next_k = k + 1;
        double skip_to = INFINITY;
        int sampled = 0;
        for (int ai = 0; ai < na; ai++) {
            const rt_vobj *ob = &fr->vobjs[act[ai]];
            const vv_vray *r = &rays[ai];
            if (t < r->t0 || t > r->t1) {
                if (t < r->t0 && r->t0 < skip_to)
                    skip_to = r->t0;
                has_prev[ai] = 0;
                continue;
            }
            float p[3];
            vv_vray_point(r, t, p);
            const vv_vcache *c = ob->c;
            const size_t b = vv_vcache_block(ob->c, p);
            if (!ob->bvis[b]) {
                double te = leap_exit(ob, r, p, t, ob->bdist[b]);
                if (te < skip_to)
                    skip_to = te;
                if (ob->mode == VV_MODE_ISO) {
                    double tx = te < r->t1 ? te : r->t1;
                    float px[3];
                    vv_vray_point(r, tx, px);
                    prev_v[ai] = vv_vcache_sample(c, px);
                    prev_t[ai] = tx;
                    has_prev[ai] = 1;
                }
                continue;
            }
            sampled = 1;
            const float val = vv_vcache_sample(c, p);
            if (ob->mode == VV_MODE_ISO) {
                const float iso = ob->iso;
                double th = -1;
                if (!has_prev[ai]) {
                    if (val >= iso && t - r->t0 < dt)
                        th = t;
                } else if ((prev_v[ai] < iso) != (val < iso)) {
                    th = vv_vray_iso_refine(c, r, prev_t[ai], prev_v[ai], t, iso);
                }
                prev_v[ai] = val;
                prev_t[ai] = t;
                has_prev[ai] = 1;
                if (th >= 0) {
                    float ph[3], g[3], pw[3], col[3];
                    vv_vray_point(r, th, ph);
                    vv_vcache_gradient(c, ph, g);
                    pw[0] = (float)(wr->origin.x + th * wr->dir.x);
                    pw[1] = (float)(wr->origin.y + th * wr->dir.y);
                    pw[2] = (float)(wr->origin.z + th * wr->dir.z);
                    float base[3] = {ob->sh.base[0], ob->sh.base[1], ob->sh.base[2]};
                    if (ob->textured) {
                        const vv_vec3 tc = vv_texture_map_eval(&ob->obj->texture,
                                                               vv_vextra_object_point(&ob->x, ph));
                        base[0] *= (float)tc.x;
                        base[1] *= (float)tc.y;
                        base[2] *= (float)tc.z;
                    }
                    if (ob->obj->shading)
                        shade_volume(fr, ob, g, ph, pw, v, base, 1.0f, NULL, col);
                    else
                        memcpy(col, base, sizeof col);
                    const vv_material *m = &ob->obj->material;
                    float kr = ob->obj->reflects ? (float)m->reflectance : 0.0f;
                    float kt = (float)m->transparency;
                    if ((kr > 0 || kt > 0) && fr->max_depth > depth) {
                        /* the isosurface as a mirror or a window: world
                         * normal from the gradient, facing the ray */
                        vv_vec3 nw = v3(ob->sh.nrm[0][0] * g[0] + ob->sh.nrm[0][1] * g[1] +
                                            ob->sh.nrm[0][2] * g[2],
                                        ob->sh.nrm[1][0] * g[0] + ob->sh.nrm[1][1] * g[1] +
                                            ob->sh.nrm[1][2] * g[2],
                                        ob->sh.nrm[2][0] * g[0] + ob->sh.nrm[2][1] * g[1] +
                                            ob->sh.nrm[2][2] * g[2]);
                        nw = v3norm(nw);
                        /* gradients point to higher values: inside; outward is minus */
                        vv_vec3 outward = v3scale(nw, -1);
                        vv_vec3 nf = v3dot(outward, wr->dir) > 0 ? nw : outward;
                        float kl = 1 - kr - kt;
                        kl = kl < 0 ? 0 : kl;
                        for (int ch = 0; ch < 3; ch++)
                            col[ch] *= kl;
                        shade_secondary(fr, wr, ray_at(wr, th), nf, outward, kr, kt, m->ior, 1,
                                        depth, weight * (1 - A), col);
                    }
                    const float w = 1 - A;
                    C[0] += w * col[0];
                    C[1] += w * col[1];
                    C[2] += w * col[2];
                    A = 1;
                    if (th < *dep)
                        *dep = (float)th;
                }
                continue;
            }
            const float *e = ob->lut + 4 * (int)lut_index_f(ob, val);
            if (e[0] <= 0)
                continue;
            float ebuf[4];
            if (ob->extras && (e = vv_vextra_apply(&ob->x, c, p, val, e, ebuf))[0] <= 0)
                continue;
            composite_sample(fr, ob, wr, v, e, p, t, NULL, &sc, C, &A);
            if (*dep == INFINITY)
                *dep = (float)t;
        }
        if (A >= fr->et)
            break;
        if (!sampled && skip_to < INFINITY) {
            double ks = vv_ceil_pos(skip_to / dt);
            if (ks > next_k)
                next_k = ks;
        }
        k = next_k;
    }
    *Aout = A > 1 ? 1 : A;
}

/* Maximum / minimum intensity projection or X-ray of one volume over the
 * part of the ray in [0, tlim] (vv_vray_project). Returns 0 when the ray
 * misses it. */
static int
project_volume(const rt_frame *fr, const rt_vobj *ob, const vv_ray *wr, double tlim, float *value,
               float *depth) {
    vv_vray r;
    if (!vray_setup(ob, wr, 0, tlim, &r))
        return 0;
    vv_vray_project(ob->c, &r, ob->mode, fr->dt, fr->st->parc, -INFINITY, INFINITY, value, depth);
    return 1;
}

/* I(x, w) = I_v + tau I_s along one ray: out is the colour, *alpha the
 * coverage (1 where a surface is hit), *tdepth the first visible hit. */
static void
trace(const rt_frame *fr, const vv_ray *wr, int depth, int primary, float weight, float out[3],
      float *alpha, float *tdepth) {
    rt_hit h;
    /* secondary rays start off their surface already (offset along the normal) */
    const int geo = nearest_hit(fr, wr, 0, INFINITY, primary, &h);
    const double tlim = geo ? h.t : INFINITY;
    float C[3] = {0, 0, 0}, A = 0, dep = INFINITY;
    march_volumes(fr, wr, tlim, depth, primary, weight, C, &A, &dep);
    float P[3] = {0, 0, 0}, PA = 0, pdepth = INFINITY;
    for (int i = 0; i < fr->n_vobj; i++) {
        const rt_vobj *ob = &fr->vobjs[i];
        if (ob->mode == VV_MODE_COMPOSITE || ob->mode == VV_MODE_ISO)
            continue;
        if (!primary && !ob->obj->visible_in_reflections)
            continue;
        float val, d;
        if (!project_volume(fr, ob, wr, tlim, &val, &d))
            continue;
        const float *e = ob->lut + 4 * (int)lut_index_f(ob, val);
        for (int ch = 0; ch < 3; ch++) {
            float cv = e[1 + ch] * e[0];
            P[ch] = cv > P[ch] ? cv : P[ch];
        }
        PA = e[0] > PA ? e[0] : PA;
        pdepth = d < pdepth ? d : pdepth;
    }
    const float rest = 1 - A;
    const float A2 = A + rest * PA;
    float behind[3] = {fr->bg[0], fr->bg[1], fr->bg[2]};
    float balpha = 0;
    if (geo && A < fr->et && A < 1) {
        shade_geometry(fr, wr, &h, depth, weight * (1 - A2), behind);
        balpha = 1;
        dep = dep < h.t ? dep : (float)h.t;
    }
    for (int ch = 0; ch < 3; ch++)
        out[ch] = C[ch] + rest * P[ch] + (1 - A2) * behind[ch];
    *alpha = A2 + (1 - A2) * balpha;
    *tdepth = dep < pdepth ? dep : pdepth;
}

/* ---------------------------------------------------------------------- */
/* Frame set-up                                                             */

static vv_status
prepare_volume(rt_frame *fr, rt_vobj *ro, const vv_object *obj) {
    const vv_world *w = fr->w;
    memset(ro, 0, sizeof *ro);
    ro->obj = obj;
    ro->mode = obj->mode;
    vv_status s = vv_vcache_get(&fr->st->vc, obj->volume, &ro->c);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    if (ro->mode == VV_MODE_COMPOSITE || ro->mode == VV_MODE_ISO)
        vv_vcache_need_normals(&fr->st->vc, ro->c);
    s = vv_vobject_prepare(obj, w, fr->ambient, fr->vlights, fr->n_lights, ro->w2i, ro->i2w,
                           ro->dims, ro->planes, &ro->n_planes, &ro->sh);
    if (s != VV_OK)
        return s;
    ro->vox = INFINITY;
    for (int a = 0; a < 3; a++) {
        const double l = sqrt(ro->i2w[0][a] * ro->i2w[0][a] + ro->i2w[1][a] * ro->i2w[1][a] +
                              ro->i2w[2][a] * ro->i2w[2][a]);
        if (l > 0 && l < ro->vox)
            ro->vox = l;
    }
    if (!(ro->vox < INFINITY))
        return vv_error_set(VV_ERR_INVALID, "object '%s': zero voxel spacing", obj->name);
    ro->iso = (float)(obj->isovalue - ro->c->qoff); /* stored units */
    ro->bx = ro->c->bx;
    ro->by = ro->c->by;
    ro->bz = ro->c->bz;
    return VV_OK;
}

/* The TF table (opacity corrected for dt, colour premultiplied), the
 * extinction table and the PARC flags and distances (shared with the ray
 * caster, src/render/volume_cache.h), and the shadow grids. */
static vv_status
build_tables(rt_frame *fr, rt_vobj *ro) {
    const vv_object *obj = ro->obj;
    vv_status s = vv_vtables_get(&fr->st->vc, ro->c, obj, ro->mode, fr->dt, ro->iso, fr->st->parc,
                                 ro->mode == VV_MODE_COMPOSITE, &ro->tab, &ro->owns_tables);
    if (s != VV_OK)
        return s;
    ro->lut = ro->tab.lut;
    ro->ext = ro->tab.ext;
    ro->bvis = ro->tab.bvis;
    ro->bdist = ro->tab.bdist;
    ro->extras = vv_vextra_prepare(&ro->x, obj, ro->mode, &ro->tab);
    ro->textured = ro->mode == VV_MODE_ISO && obj->texture.image != NULL;
    if (fr->shadows && obj->receives_shadows && obj->shading && ro->mode == VV_MODE_COMPOSITE &&
        fr->st->shadow_grid) {
        size_t ng = 1;
        for (int a = 0; a < 3; a++) {
            ro->gdim[a] = (ro->dims[a] - 1 + RT_SGRID - 1) / RT_SGRID + 1;
            ro->gdim[a] = ro->gdim[a] < 2 ? 2 : ro->gdim[a];
            ng *= (size_t)ro->gdim[a];
        }
        for (int l = 0; l < fr->n_lights; l++) {
            if (!fr->lights[l].point && fr->st->shadow_grid == 2)
                continue; /* swept once all objects are ready (sweep_light) */
            ro->sgrid[l] = calloc(ng, sizeof *ro->sgrid[l]);
            if (!ro->sgrid[l])
                return vv_error_set(VV_ERR_NOMEM, "out of memory for a shadow grid");
        }
    }
    return VV_OK;
}

static vv_status
prepare_geometry(rt_frame *fr, rt_gobj *g, const vv_object *obj) {
    memset(g, 0, sizeof *g);
    g->obj = obj;
    g->type = obj->type;
    vv_mat4 o2w = vv_object_matrix(obj);
    int ok = 0;
    vv_mat4 w2o = vv_mat4_inverse(o2w, &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            g->w2o[r][c] = w2o.m[r][c];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            g->nrm[r][c] = w2o.m[c][r];
    const vv_material *m = &obj->material;
    g->col[0] = (float)m->color.x;
    g->col[1] = (float)m->color.y;
    g->col[2] = (float)m->color.z;
    g->kr = obj->reflects ? (float)m->reflectance : 0.0f;
    g->kt = (float)m->transparency;
    g->ior = m->ior;
    const vv_geometry *ge = &obj->geometry;
    switch (obj->type) {
    case VV_OBJECT_PLANE:
        if (!(v3len(ge->normal) > 0))
            return vv_error_set(VV_ERR_INVALID, "object '%s': plane with a zero normal", obj->name);
        g->pp = vv_mat4_mul_point(o2w, ge->point);
        g->pn = v3(
            g->nrm[0][0] * ge->normal.x + g->nrm[0][1] * ge->normal.y + g->nrm[0][2] * ge->normal.z,
            g->nrm[1][0] * ge->normal.x + g->nrm[1][1] * ge->normal.y + g->nrm[1][2] * ge->normal.z,
            g->nrm[2][0] * ge->normal.x + g->nrm[2][1] * ge->normal.y +
                g->nrm[2][2] * ge->normal.z);
        break;
    case VV_OBJECT_POLYGON: {
        if (ge->n_vertices < 3 || !ge->vertices)
            return vv_error_set(VV_ERR_INVALID, "object '%s': polygon with %d vertices", obj->name,
                                ge->n_vertices);
        vv_vec3 nn = {0, 0, 0}; /* Newell's normal */
        for (int i = 0; i < ge->n_vertices; i++) {
            vv_vec3 a = ge->vertices[i], b = ge->vertices[(i + 1) % ge->n_vertices];
            nn.x += (a.y - b.y) * (a.z + b.z);
            nn.y += (a.z - b.z) * (a.x + b.x);
            nn.z += (a.x - b.x) * (a.y + b.y);
        }
        if (!(v3len(nn) > 0))
            return vv_error_set(VV_ERR_INVALID, "object '%s': degenerate polygon", obj->name);
        g->plane = vv_plane_from_point_normal(ge->vertices[0], nn);
        double ax = fabs(nn.x), ay = fabs(nn.y), az = fabs(nn.z);
        g->drop = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
        break;
    }
    case VV_OBJECT_SPHERE:
        if (!(ge->radius > 0))
            return vv_error_set(VV_ERR_INVALID, "object '%s': sphere radius must be > 0",
                                obj->name);
        g->closed = 1;
        break;
    case VV_OBJECT_BOX:
        if (!(ge->box.max.x >= ge->box.min.x && ge->box.max.y >= ge->box.min.y &&
              ge->box.max.z >= ge->box.min.z))
            return vv_error_set(VV_ERR_INVALID, "object '%s': box with min > max", obj->name);
        g->closed = 1;
        break;
    case VV_OBJECT_CYLINDER:
        if (!(ge->radius > 0) || !(v3len(v3sub(ge->top, ge->base)) > 0))
            return vv_error_set(VV_ERR_INVALID,
                                "object '%s': cylinder needs radius > 0 and base != top",
                                obj->name);
        g->closed = ge->capped;
        break;
    case VV_OBJECT_MESH: {
        if (!ge->mesh)
            return vv_error_set(VV_ERR_INVALID, "object '%s': mesh object without a mesh",
                                obj->name);
        vv_status s = bvh_build(&g->bvh, ge->mesh);
        if (s != VV_OK)
            return vv_error_prefix(s, "object '%s'", obj->name);
        g->closed = 1;
        break;
    }
    default:
        return vv_error_set(VV_ERR_INVALID, "object '%s': unsupported type %d", obj->name,
                            (int)obj->type);
    }
    if (obj->type == VV_OBJECT_POLYGON || obj->type == VV_OBJECT_BOX) {
        /* world-space bounding sphere of the object-space bounding box */
        vv_vec3 lo = ge->box.min, hi = ge->box.max;
        if (obj->type == VV_OBJECT_POLYGON) {
            lo = hi = ge->vertices[0];
            for (int i = 1; i < ge->n_vertices; i++) {
                const vv_vec3 q = ge->vertices[i];
                lo = v3(q.x < lo.x ? q.x : lo.x, q.y < lo.y ? q.y : lo.y, q.z < lo.z ? q.z : lo.z);
                hi = v3(q.x > hi.x ? q.x : hi.x, q.y > hi.y ? q.y : hi.y, q.z > hi.z ? q.z : hi.z);
            }
        }
        g->bc = vv_mat4_mul_point(o2w, v3scale(v3add(lo, hi), 0.5));
        double r = 0;
        for (int k = 0; k < 8; k++) {
            const vv_vec3 q = v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
            const double d = v3len(v3sub(vv_mat4_mul_point(o2w, q), g->bc));
            r = d > r ? d : r;
        }
        r = r * (1 + 1e-6) + 1e-9; /* rounding margin: never reject a hit */
        g->br2 = r * r;
        g->bounded =
            isfinite(g->br2) && isfinite(g->bc.x) && isfinite(g->bc.y) && isfinite(g->bc.z);
    }
    (void)fr;
    return VV_OK;
}

static void
prepare_lights(rt_frame *fr, const vv_world *w, const vv_view *view) {
    vv_vec3 fwd = v3norm(v3sub(view->at, view->eye));
    fr->n_lights = vv_vlights_prepare(fr->vlights, w, view);
    for (int i = 0; i < fr->n_lights; i++) {
        const vv_light *l = &w->lights[i];
        rt_light *o = &fr->lights[i];
        o->point = l->type == VV_LIGHT_POINT && !l->headlight;
        vv_vec3 d = l->headlight ? fwd : v3norm(l->direction);
        o->dir[0] = -d.x;
        o->dir[1] = -d.y;
        o->dir[2] = -d.z;
        o->pos[0] = l->position.x;
        o->pos[1] = l->position.y;
        o->pos[2] = l->position.z;
        o->col[0] = (float)(l->color.x * l->intensity);
        o->col[1] = (float)(l->color.y * l->intensity);
        o->col[2] = (float)(l->color.z * l->intensity);
    }
}

static void
frame_release(rt_frame *fr) {
    for (int i = 0; i < fr->n_vobj; i++) {
        if (fr->vobjs[i].owns_tables)
            vv_vtables_free(&fr->vobjs[i].tab);
        for (int l = 0; l < VV_MAX_LIGHTS; l++) {
            free(fr->vobjs[i].sgrid[l]);
            free(fr->vobjs[i].sweep[l]);
            if (fr->vobjs[i].lvol_owned & (1u << l))
                free(fr->vobjs[i].lvol[l]);
        }
    }
    for (int i = 0; i < fr->n_gobj; i++) {
        free(fr->gobjs[i].bvh.nodes);
        free(fr->gobjs[i].bvh.tri);
    }
    free(fr->vobjs);
    free(fr->gobjs);
}

/* ---------------------------------------------------------------------- */
/* Pixels                                                                    */

static inline uint64_t
mix64(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

/* vv_view_ray is affine in the pixel position before the direction is
 * normalised (the ray caster's prepare_rays): take the affine form from
 * three rays so that a primary ray costs a few multiply-adds instead of a
 * camera set-up. */
static void
prepare_rays(rt_frame *fr, const vv_view *view) {
    vv_vec3 f = v3norm(v3sub(view->at, view->eye));
    vv_ray r00 = vv_view_ray(view, 0, 0), r10 = vv_view_ray(view, 1, 0),
           r01 = vv_view_ray(view, 0, 1);
    vv_ray *rs[3] = {&r00, &r10, &r01};
    for (int i = 0; i < 3; i++) {
        double df = v3dot(rs[i]->dir, f);
        if (view->projection != VV_PROJECTION_ORTHOGRAPHIC && df > 0)
            rs[i]->dir = v3scale(rs[i]->dir, 1.0 / df);
    }
    fr->o00 = r00.origin;
    fr->ox = v3sub(r10.origin, r00.origin);
    fr->oy = v3sub(r01.origin, r00.origin);
    fr->d00 = r00.dir;
    fr->dx = v3sub(r10.dir, r00.dir);
    fr->dy = v3sub(r01.dir, r00.dir);
}

static void
trace_primary(const rt_frame *fr, const vv_view *view, double px, double py, float rgba[4],
              float *depth) {
    (void)view;
    vv_ray wr;
    /* the ray caster's arithmetic, so that without effects the images agree */
    wr.origin.x = fr->o00.x + px * fr->ox.x + py * fr->oy.x;
    wr.origin.y = fr->o00.y + px * fr->ox.y + py * fr->oy.y;
    wr.origin.z = fr->o00.z + px * fr->ox.z + py * fr->oy.z;
    const double dx = fr->d00.x + px * fr->dx.x + py * fr->dy.x;
    const double dy = fr->d00.y + px * fr->dx.y + py * fr->dy.y;
    const double dz = fr->d00.z + px * fr->dx.z + py * fr->dy.z;
    const double inv = 1.0 / sqrt(dx * dx + dy * dy + dz * dz);
    wr.dir.x = dx * inv;
    wr.dir.y = dy * inv;
    wr.dir.z = dz * inv;
    trace(fr, &wr, 0, 1, 1.0f, rgba, &rgba[3], depth);
}

/* n x n supersamples of pixel (x, y), regular or jittered (seeded by the
 * pixel, so images do not depend on threads). */
static void
supersample(const rt_frame *fr, const vv_view *view, int x, int y, int n, float rgba[4],
            float *depth) {
    float acc[4] = {0, 0, 0, 0};
    float dmin = INFINITY;
    for (int s = 0; s < n * n; s++) {
        double ox = (s % n + 0.5) / n - 0.5, oy = (s / n + 0.5) / n - 0.5;
        if (fr->st->jitter) {
            uint64_t h =
                mix64(fr->st->seed ^ mix64(((uint64_t)(uint32_t)y << 32) ^ (uint64_t)(uint32_t)x) ^
                      (uint64_t)s * 0x632BE59BD9B4E019ull);
            ox = (s % n + (double)(h >> 40) / 16777216.0) / n - 0.5;
            oy = (s / n + (double)(h & 0xFFFFFF) / 16777216.0) / n - 0.5;
        }
        float c[4], d;
        trace_primary(fr, view, x + ox, y + oy, c, &d);
        for (int ch = 0; ch < 4; ch++)
            acc[ch] += c[ch];
        dmin = d < dmin ? d : dmin;
    }
    for (int ch = 0; ch < 4; ch++)
        rgba[ch] = acc[ch] / (float)(n * n);
    *depth = dmin;
}

/* ---------------------------------------------------------------------- */
/* The renderer                                                             */

typedef struct rt_progress {
    const vv_progress *p;
    atomic_int cancelled;
    int done, total;
} rt_progress;

static void
tile_done(rt_progress *pr) {
    if (!pr->p->fn)
        return;
#pragma omp critical(vv_raytrace_progress)
    {
        pr->done++;
        if (vv_progress_report(pr->p, (double)pr->done / pr->total))
            atomic_store(&pr->cancelled, 1);
    }
}

static vv_status
rt_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    rt_state *st = state;
    rt_frame fr;
    memset(&fr, 0, sizeof fr);
    fr.st = st;
    fr.w = w;
    st->vc.frame++;
    fr.avx2 = vv_vc_have_avx2();
    st->frame++;
    fr.et = (float)st->early_termination;
    fr.ambient[0] = (float)w->ambient.x;
    fr.ambient[1] = (float)w->ambient.y;
    fr.ambient[2] = (float)w->ambient.z;
    fr.bg[0] = (float)w->background.x;
    fr.bg[1] = (float)w->background.y;
    fr.bg[2] = (float)w->background.z;
    /* quality: 0 preview (no secondary rays, one sample), 1 one sample
     * with shadows and reflections, 2 final (supersampling as set) */
    fr.shadows = opt->quality >= 1 && st->shadows;
    fr.max_depth = opt->quality >= 1 ? st->max_depth : 0;
    const int nss = opt->quality >= 2 ? st->samples : 1;
    prepare_lights(&fr, w, view);
    prepare_rays(&fr, view);

    int nv = 0, ng = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *o = w->objects[i];
        if (!o || !o->visible || o->type == VV_OBJECT_GRID) /* grids: the irregular renderer */
            continue;
        if (o->type == VV_OBJECT_VOLUME)
            nv += o->volume != NULL;
        else
            ng++;
    }
    if (nv > RT_MAX_OBJ || ng > RT_MAX_OBJ * 16)
        return vv_error_set(VV_ERR_LIMIT, "%d volume and %d geometric objects; at most %d and %d",
                            nv, ng, RT_MAX_OBJ, RT_MAX_OBJ * 16);
    fr.vobjs = calloc(nv ? (size_t)nv : 1, sizeof *fr.vobjs);
    fr.gobjs = calloc(ng ? (size_t)ng : 1, sizeof *fr.gobjs);
    if (!fr.vobjs || !fr.gobjs) {
        frame_release(&fr);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    vv_status s = VV_OK;
    double dt = INFINITY;
    vv_box bounds = vv_world_bounds(w);
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        const vv_object *o = w->objects[i];
        if (!o || !o->visible || o->type == VV_OBJECT_GRID)
            continue;
        if (o->type == VV_OBJECT_VOLUME) {
            if (!o->volume)
                continue;
            if (!(o->step > 0)) {
                s = vv_error_set(VV_ERR_INVALID, "object '%s': step must be > 0", o->name);
                break;
            }
            s = prepare_volume(&fr, &fr.vobjs[fr.n_vobj++], o);
            double sd = vv_vobject_step(o);
            dt = sd < dt ? sd : dt;
        } else {
            s = prepare_geometry(&fr, &fr.gobjs[fr.n_gobj++], o);
        }
    }
    fr.dt = (float)(dt < INFINITY ? dt : 1.0);
    double size = v3len(v3sub(bounds.max, bounds.min));
    size += v3len(v3sub(view->eye, v3scale(v3add(bounds.max, bounds.min), 0.5)));
    fr.scene_size = size > 0 && size < INFINITY ? size : 1.0;
    for (int i = 0; i < fr.n_vobj && s == VV_OK; i++) {
        s = build_tables(&fr, &fr.vobjs[i]);
    }
    if (s != VV_OK) {
        frame_release(&fr);
        return s;
    }

    const int nt = opt->threads > 0 ? opt->threads : vv_threads_get();
    /* light volumes of directional lights through composite volumes that
     * cast shadows, then the shadow grids, now that every object is ready */
    for (int i = 0; i < fr.n_vobj && s == VV_OK && fr.shadows && st->light_volumes; i++) {
        rt_vobj *ro = &fr.vobjs[i];
        if (ro->mode != VV_MODE_COMPOSITE || !ro->obj->casts_shadows)
            continue;
        for (int l = 0; l < fr.n_lights && s == VV_OK; l++)
            if (!fr.lights[l].point)
                s = build_light_volume(&fr, ro, l, nt);
    }
    for (int i = 0; i < fr.n_vobj && s == VV_OK; i++) {
        rt_vobj *ro = &fr.vobjs[i];
        if (ro->gdim[0] == 0)
            continue;
        for (int l = 0; l < fr.n_lights && s == VV_OK; l++)
            if (!fr.lights[l].point && st->shadow_grid == 2)
                s = sweep_light(&fr, ro, l, nt);
    }
    if (s != VV_OK) {
        frame_release(&fr);
        return s;
    }
    const int W = view->width, H = view->height;
    const int tx = (W + RT_TILE - 1) / RT_TILE, ty = (H + RT_TILE - 1) / RT_TILE;
    const int ntiles = tx * ty;
    const int adaptive = nss > 1 && st->adaptive;
    rt_progress pr;
    pr.p = &opt->progress;
    atomic_init(&pr.cancelled, 0);
    pr.done = 0;
    pr.total = adaptive ? 2 * ntiles : ntiles;
    /* pass 1: one ray per pixel (or the full supersampling when not adaptive) */
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
    for (int tile = 0; tile < ntiles; tile++) {
        if (atomic_load_explicit(&pr.cancelled, memory_order_relaxed))
            continue;
        int x0 = (tile % tx) * RT_TILE, y0 = (tile / tx) * RT_TILE;
        int x1 = x0 + RT_TILE < W ? x0 + RT_TILE : W, y1 = y0 + RT_TILE < H ? y0 + RT_TILE : H;
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++) {
                float *pix = out->rgba + 4 * ((size_t)y * (size_t)W + (size_t)x);
                float *dp = out->depth + (size_t)y * (size_t)W + (size_t)x;
                if (nss > 1 && !adaptive)
                    supersample(&fr, view, x, y, nss, pix, dp);
                else
                    trace_primary(&fr, view, x, y, pix, dp);
            }
        tile_done(&pr);
    }
    /* pass 2 (adaptive): supersample pixels that differ from a neighbour */
    if (adaptive && !atomic_load(&pr.cancelled)) {
        const size_t np = (size_t)W * (size_t)H;
        float *first = malloc(np * 4 * sizeof(float));
        if (!first) {
            frame_release(&fr);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        memcpy(first, out->rgba, np * 4 * sizeof(float));
        const float thr = (float)st->threshold;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
        for (int tile = 0; tile < ntiles; tile++) {
            if (atomic_load_explicit(&pr.cancelled, memory_order_relaxed))
                continue;
            int x0 = (tile % tx) * RT_TILE, y0 = (tile / tx) * RT_TILE;
            int x1 = x0 + RT_TILE < W ? x0 + RT_TILE : W, y1 = y0 + RT_TILE < H ? y0 + RT_TILE : H;
            for (int y = y0; y < y1; y++)
                for (int x = x0; x < x1; x++) {
                    const float *c = first + 4 * ((size_t)y * (size_t)W + (size_t)x);
                    int differs = 0;
                    const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
                    for (int k = 0; k < 4 && !differs; k++) {
                        if (nb[k][0] < 0 || nb[k][0] >= W || nb[k][1] < 0 || nb[k][1] >= H)
                            continue;
                        const float *q =
                            first + 4 * ((size_t)nb[k][1] * (size_t)W + (size_t)nb[k][0]);
                        for (int ch = 0; ch < 4; ch++)
                            differs |= fabsf(q[ch] - c[ch]) > thr;
                    }
                    if (differs)
                        supersample(&fr, view, x, y, nss,
                                    out->rgba + 4 * ((size_t)y * (size_t)W + (size_t)x),
                                    out->depth + (size_t)y * (size_t)W + (size_t)x);
                }
            tile_done(&pr);
        }
        free(first);
    }
    frame_release(&fr);
    if (atomic_load(&pr.cancelled))
        return vv_error_set(VV_ERR_CANCELLED, "cancelled");
    /* drop cached volumes the World no longer shows */
    vv_vcache_set_prune(&st->vc, w);
    /* light volumes this frame did not use: gone (they can be large) */
    for (int i = 0; i < RT_LV_CACHE; i++)
        if (st->lv[i].vol && st->lv[i].used != st->frame)
            lv_release(&st->lv[i]);
    return VV_OK;
}

static vv_status
rt_create(void **state) {
    rt_state *st = calloc(1, sizeof *st);
    if (!st)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    st->parc = 1;
    st->shadows = 1;
    st->max_depth = 3;
    st->samples = 2;
    st->jitter = 0;
    st->adaptive = 1;
    st->threshold = 0.05;
    st->seed = 1;
    st->early_termination = 0.99;
    st->shadow_grid = 1;
    st->light_volumes = 1;
    vv_vcache_set_init(&st->vc);
    *state = st;
    return VV_OK;
}

static vv_status
rt_set_option(void *state, const char *key, const char *value) {
    rt_state *st = state;
    char *end = NULL;
    double x = strtod(value, &end);
    if (!end || *end || end == value || x != x)
        return vv_error_set(VV_ERR_INVALID, "option %s: '%s' is not a number", key, value);
    if (strcmp(key, "parc") == 0) {
        st->parc = x != 0;
    } else if (strcmp(key, "shadows") == 0) {
        st->shadows = x != 0;
    } else if (strcmp(key, "shadow_grid") == 0) {
        if (x != 0 && x != 1 && x != 2)
            return vv_error_set(VV_ERR_INVALID, "shadow_grid must be 0, 1 or 2");
        st->shadow_grid = (int)x;
    } else if (strcmp(key, "light_volumes") == 0) {
        st->light_volumes = x != 0;
    } else if (strcmp(key, "max_depth") == 0) {
        if (!(x >= 0 && x <= 64) || x != floor(x))
            return vv_error_set(VV_ERR_INVALID, "max_depth must be an integer in 0..64");
        st->max_depth = (int)x;
    } else if (strcmp(key, "samples") == 0) {
        if (!(x >= 1 && x <= 16) || x != floor(x))
            return vv_error_set(VV_ERR_INVALID,
                                "samples (per pixel side) must be an integer in 1..16");
        st->samples = (int)x;
    } else if (strcmp(key, "jitter") == 0) {
        st->jitter = x != 0;
    } else if (strcmp(key, "adaptive") == 0) {
        st->adaptive = x != 0;
    } else if (strcmp(key, "adaptive_threshold") == 0) {
        if (!(x >= 0))
            return vv_error_set(VV_ERR_INVALID, "adaptive_threshold must be >= 0");
        st->threshold = x;
    } else if (strcmp(key, "seed") == 0) {
        if (!(x >= 0 && x < 1.8e19))
            return vv_error_set(VV_ERR_INVALID, "seed must be a non-negative integer");
        st->seed = (uint64_t)x;
    } else if (strcmp(key, "early_termination") == 0) {
        if (!(x > 0 && x <= 1))
            return vv_error_set(VV_ERR_INVALID, "early_termination must be in (0, 1]");
        st->early_termination = x;
    } else {
        return vv_error_set(
            VV_ERR_INVALID,
            "unknown option '%s' (parc, shadows, shadow_grid, light_volumes, max_depth, "
            "samples, "
            "jitter, adaptive, adaptive_threshold, seed, early_termination)",
            key);
    }
    return VV_OK;
}

static void
rt_destroy(void *state) {
    rt_state *st = state;
    if (!st)
        return;
    vv_vcache_set_clear(&st->vc);
    for (int i = 0; i < RT_LV_CACHE; i++)
        lv_release(&st->lv[i]);
    free(st);
}

const vv_renderer_ops vv_raytrace_ops = {
    "raytrace",
    "volumetric ray tracing: volumes and geometry, shadows, mirrors, refraction, PARC",
    rt_create,
    rt_set_option,
    rt_render,
    rt_destroy,
    "shadows (1), max_depth (3), samples (2: 2x2 a pixel at quality 2), jitter (0), seed (1), "
    "adaptive (1), adaptive_threshold (0.05), parc (1), shadow_grid (1), light_volumes (1), "
    "early_termination (0.99); --quality 0: no shadow or secondary rays, 1: one ray a pixel, "
    "2: supersampled",
};
