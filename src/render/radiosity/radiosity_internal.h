/*
 * Volumetric radiosity, internal data (src/render/radiosity): elements,
 * hierarchies, voxel grids. See include/volvis/radiosity.h for the method.
 */
#ifndef VV_RADIOSITY_INTERNAL_H
#define VV_RADIOSITY_INTERNAL_H

#include "volvis/radiosity.h"

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

/**
 * The nearest patch the ray o + t d (d unit, world) hits with t0 < t < t1,
 * through the patch objects' trees, nearer child first: its element index,
 * or -1; *thit the hit (t1 when none). any: return at the first hit found
 * (a shadow ray).
 */
int rad_patch_hit(const vv_radiosity *r, vv_vec3 o, vv_vec3 d, double t0, double t1, int any,
                  double *thit);

#endif
