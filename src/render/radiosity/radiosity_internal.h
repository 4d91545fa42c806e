/*
 * Volumetric radiosity, internal data (src/render/radiosity): elements,
 * hierarchies, voxel grids. See include/volvis/radiosity.h for the method.
 */
#ifndef VV_RADIOSITY_INTERNAL_H
#define VV_RADIOSITY_INTERNAL_H

#include <math.h>

#include "volvis/radiosity.h"

#define RAD_PI 3.14159265358979323846

enum { RAD_PATCH = 0, RAD_VOXEL = 1 };

/* A finest-level element: a triangular patch (two sides) or a voxel (side 0). */
typedef struct rad_elem {
    float p[3];   /* centroid, world */
    float n[3];   /* unit normal (patch: of its plane; diffuse voxel: outward); zero: isotropic */
    float area;   /* patch area; voxel cross-section h^2 (1 - exp(-sigma h)) */
    float rho[3]; /* reflectance / scattering albedo */
    float half;   /* half the voxel size, or the patch's circumradius */
    float tau;    /* voxel: optical depth across it (sigma h); patch: 0 */
    float tri[9]; /* patch vertices */
    int kind;     /* RAD_PATCH, RAD_VOXEL */
    int obj;      /* object index in the World */
    int vox;      /* voxel: linear index in its grid */
    int cand;     /* the shooting candidate holding it */
    float unshot[2][3];
    float total[2][3]; /* emitted + scattered power, per side */
    float absorbed[3];
} rad_elem;

/* A cluster of the hierarchy (binary bounding-volume tree per object); its
 * elements are elems[lo, hi). */
typedef struct rad_node {
    float c[3], r;          /* centre and bounding radius */
    float bmin[3], bmax[3]; /* world box */
    int lo, hi;
    int child[2]; /* -1 -1: leaf (hi = lo + 1) */
    int obj, kind;
    float s_iso;           /* capacity of isotropic voxels */
    float s_dif, m_dif[3]; /* diffuse voxels: sum of xs, sum of xs n */
    float s_pat, m_pat[3]; /* patches: sum of area, sum of area n */
    float rho_max;         /* largest reflectance of its elements */
    float thick;           /* largest optical depth across it (voxels: tau x size / h) */
} rad_node;

/* A volume object's radiosity grid. */
typedef struct rad_vol {
    int obj;
    int n[3];
    double h;         /* world size of a grid voxel (cube root of its volume) */
    vv_mat4 g2w, w2g; /* grid index <-> world */
    vv_box wbox;      /* world box of the grid cells */
    float *sigma;     /* extinction per world unit, n0 n1 n2 */
    float *rc;        /* render data, 8 floats a voxel: sigma, display radiance rgb,
                         normal (scaled to the voxel's diffuse share), pad */
    int bs, bn[3];    /* empty-space blocks: side, count per axis */
    float *bmax;      /* largest sigma per block */
    double step;      /* render step, world units */
    vv_box rbox;      /* world box of the voxels that are not empty (rendering) */
} rad_vol;

struct vv_radiosity {
    vv_radiosity_options opt;
    int n_elems, n_nodes;
    rad_elem *elems;
    rad_node *nodes;
    int n_roots;
    int *roots; /* root node per object with elements */
    int n_vols;
    rad_vol *vols;
    int n_objects;
    vv_radiosity_stats stats;
};

#define RAD_MAX_ELEMS (8 << 20)
#define RAD_VOXEL_OFF 3.0 /* rays to or from a surface voxel start this many voxels off it */
#define RAD_TAU_MAX 12.0  /* transmittance below exp(-12) is taken as 0 */

/* ---------------------------------------------------------------------- */
/* small vector helpers (float storage, double arithmetic)                  */

static inline vv_vec3
f3(const float *p) {
    return vv_vec3_make(p[0], p[1], p[2]);
}

static inline void
set3(float *d, vv_vec3 v) {
    d[0] = (float)v.x;
    d[1] = (float)v.y;
    d[2] = (float)v.z;
}

static inline double
maxc(const double *v) {
    double m = v[0] > v[1] ? v[0] : v[1];
    return m > v[2] ? m : v[2];
}

/* ---------------------------------------------------------------------- */
/* growing arrays                                                            */

typedef struct builder {
    rad_elem *e;
    int n, cap;
    rad_node *nodes;
    int n_nodes, cap_nodes;
} builder;

/* ---------------------------------------------------------------------- */
/* the solver                                                                */

enum { SH_CLUSTER = 0, SH_POINT = 1, SH_DIRECTIONAL = 2 };

typedef struct shooter {
    int kind;
    vv_vec3 pos, dir; /* point: position; directional: the direction light travels */
    double I[3];      /* point: radiant intensity; directional: irradiance */
} shooter;

typedef struct deposit {
    int e, side;
    float p[3];
} deposit;

typedef struct solver {
    vv_radiosity *r;
    float *u; /* per node: RAD_U floats of unshot power (rad_unshot_moments) */
    deposit *dep;
    size_t n_dep, cap_dep;
    double eps_power;
    double far_t; /* beyond the scene, world units */
    int max_cluster;
    vv_status status;
} solver;

/* Per node: unshot power of its isotropic voxels (rgb), and of its
 * directional (Lambertian) emitters projected on the six half-axes: an
 * emitter of power U about unit normal n adds U n_a^2 to half-axis (a,
 * sign n_a), so the cluster's intensity sum_a U_a max(0, +-w_a) / pi keeps
 * the power exactly and the direction of axis-aligned emitters exactly. */
#define RAD_U 21

/* ---------------------------------------------------------------------- */
/* the stages' functions                                                     */

/* rad_setup.c: the elements of every visible object of @p w (voxels of the
 * volumes, patches of the geometric objects no larger than @p patch_size),
 * appended to @p b; obj_lo[i] is object i's first element, obj_lo[n_objects]
 * the end. */
vv_status rad_build_elements(builder *b, vv_radiosity *r, const vv_world *w,
                             const vv_radiosity_options *opt, double patch_size, int *obj_lo);
/* rad_setup.c: splits the patches a light's shadow boundary crosses (down
 * to 1/8 of their size), rebuilding the objects' trees. */
vv_status rad_shadow_split(vv_radiosity *r, const vv_world *w, double far_t, int *obj_lo);

/* rad_hierarchy.c: the cluster tree over b->e[lo, hi); its root node, or -1
 * when out of memory. Reorders the elements. */
int rad_build_tree(builder *b, int lo, int hi);
/* Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom and
 * Strackee 1983), in [0, 4 pi). */
double rad_solid_angle(vv_vec3 a, vv_vec3 b, vv_vec3 c);
/* Form factor from a differential area at the origin with normal n to the
 * triangle (a, b, c) (positions relative to it). */
double rad_point_form_factor(vv_vec3 n, vv_vec3 a, vv_vec3 b, vv_vec3 c);
/* The centroids of the 16 triangles of two midpoint subdivisions of tri. */
int rad_sub_points(const float *tri, vv_vec3 *out);
/* Ray parameter range [t0, t1] of a box; 0 on a miss. */
int rad_box_ray(const float *mn, const float *mx, vv_vec3 o, vv_vec3 d, double *t0, double *t1);
/* Optical depth along o + t d, t in [t0, t1] (d unit, world), through a
 * voxel grid; stops once over RAD_TAU_MAX. */
double rad_grid_tau(const rad_vol *rv, vv_vec3 o, vv_vec3 d, double t0, double t1);
/* Transmittance from o along d over (t0, t1): volumes attenuate, patches block. */
double rad_transmittance(const vv_radiosity *r, vv_vec3 o, vv_vec3 d, double t0, double t1);

/* rad_shoot.c: the moments of the unshot power under node @p id. */
void rad_unshot_moments(solver *sv, int id);
/* Refines shooter @p sh (a light: S = -1; a cluster: node S) against the
 * receiver tree under node R, recording deposits. */
void rad_refine(solver *sv, const shooter *sh, int S, int R);
/* Applies the deposits of one shot of power @p shot (rgb; a directional
 * light: -1), scaled so that no energy is created. */
void rad_apply_deposits(solver *sv, const double shot[3], double *cand_unshot);
/* The shooting candidates: a cut through the tree under @p id into clusters
 * of about K elements, appended to cands[n ..]; returns the new count. */
int rad_candidate_cut(vv_radiosity *r, int id, int K, int *cands, int n);
/* The unshot power of an element (both sides, summed over rgb). */
double rad_elem_unshot(const rad_elem *e);

/* view.c: the render grid of each volume (display radiance, normals,
 * empty-space blocks) once the solution is known. */
vv_status rad_prepare_render(vv_radiosity *r);

/**
 * The nearest patch the ray o + t d (d unit, world) hits with t0 < t < t1,
 * through the patch objects' trees, nearer child first: its element index,
 * or -1; *thit the hit (t1 when none). any: return at the first hit found
 * (a shadow ray).
 */
int rad_patch_hit(const vv_radiosity *r, vv_vec3 o, vv_vec3 d, double t0, double t1, int any,
                  double *thit);

#endif
