/*
 * VolVis volumetric radiosity (Sobierajski and Kaufman, "Volumetric
 * radiosity", 1994; the VolVis paper, Avila et al. 1994, section 5.2): the
 * diffuse interreflection of light between volumes and surfaces.
 *
 * Elements: the geometric objects of a World (polygons, boxes, spheres,
 * cylinders, meshes) become triangular surface patches (two-sided, each side
 * with its own radiosity); the volume objects become voxel elements through
 * their transfer function's opacity and colour (opaque voxels hidden inside
 * an object are not elements: they only attenuate). Every element emits
 * (material.emission), absorbs, scatters and transmits: patches reflect
 * diffusely (reflectance kd * colour); voxels scatter isotropically or
 * diffusely about the opacity gradient (albedo kd * transfer-function
 * colour), what they do not intercept is transmitted. Point lights are
 * isotropic emitters (radiant intensity = intensity * colour per steradian,
 * falling off as 1/r^2), directional lights are parallel fluxes (irradiance =
 * intensity * colour); headlights depend on the view and are ignored.
 *
 * Solution: progressive shooting (Cohen et al. 1988) of the cluster with the
 * most unshot power, each shot refined hierarchically (Hanrahan, Salzman and
 * Aupperle 1991, extended to voxel clusters) so that two elements interact
 * at the highest level of their hierarchies (bounding-volume trees of
 * patches and voxels) that the error bound allows; visibility between
 * elements through volumes by attenuated rays and through patches by
 * occlusion tests. Units: power in display units times world area (a
 * diffuse white patch under irradiance 1 has radiosity 1 and shows as 1).
 *
 * Thread-safety: a solution is read-only once solved; views of one solution
 * may be rendered from several threads. Solving uses the calling thread.
 */
#ifndef VOLVIS_RADIOSITY_H
#define VOLVIS_RADIOSITY_H

#include "core.h"
#include "image.h"
#include "model.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Parameters of a radiosity solution (see docs/rendering.md, "radiosity"). */
typedef struct vv_radiosity_options {
    /** Stop when the unshot power is below this fraction of the power in (default 1e-3). */
    double tolerance;
    /**
     * Hierarchical refinement: two clusters interact without subdividing
     * when the power the shooter sends the receiver times its reflectance
     * is below error * power in (default 1e-4); 0 refines every
     * interaction to the finest elements (element to element).
     */
    double error;
    /** Refine while (radius of shooter + radius of receiver) / distance > near (0.5). */
    double near;
    /** Longest patch edge, world units; <= 0: the World's diagonal / 48 (default 0). */
    double patch_size;
    /** Voxels along the longest axis of a volume's radiosity grid (default 128, 2..1024). */
    int grid;
    /** 1: voxels on an opacity gradient scatter diffusely about it (default); 0: isotropic. */
    int diffuse_voxels;
    /** Shots at most (default 20000); more is an error-free stop with power left unshot. */
    int max_shots;
    /**
     * Levels of the hierarchy used (default 0: all): clusters of more than
     * 8^(levels - 1) elements always subdivide, so 1 is the finest-level
     * (element to element) solution. More levels than a volume's grid has
     * (1 + log2 of its longest axis) is an error.
     */
    int levels;
} vv_radiosity_options;

/** The defaults above. */
void vv_radiosity_options_init(vv_radiosity_options *o);

/** Counts and energy balance of a solution (per channel where an array). */
typedef struct vv_radiosity_stats {
    int n_patches;            /**< surface patches (finest level) */
    int n_voxels;             /**< voxel elements (finest level) */
    int n_nodes;              /**< clusters and elements of the hierarchies */
    int n_shots;              /**< progressive shooting steps */
    double interactions;      /**< shooter-receiver interactions (one visibility ray each) */
    double pairwise;          /**< (elements + emitters)^2: one full element-to-element gathering */
    double power_in[3];       /**< emitted by lights and objects (directional: as delivered) */
    double power_absorbed[3]; /**< absorbed by elements */
    double power_escaped[3]; /**< shot out of the scene (or lost to attenuation between elements) */
    double power_unshot[3];  /**< still to shoot when the solver stopped */
    int converged;           /**< 1: unshot below tolerance; 0: stopped at max_shots */
} vv_radiosity_stats;

typedef struct vv_radiosity vv_radiosity;

/**
 * Solves the radiosity of @p world (borrowed; the solution keeps no pointer
 * to it). @p opt may be NULL (defaults), @p progress may be NULL; it reports
 * 1 - log(unshot / power in) / log(tolerance) and can cancel. Errors:
 * VV_ERR_INVALID with a message: no emitter (no light other than a
 * headlight, no object with emission), an emitter with a non-finite or
 * negative power, a reflectance (kd * colour) below 0 or above 1, an option
 * out of range; VV_ERR_NOMEM; VV_ERR_CANCELLED ("... N % of the power left
 * unshot").
 */
vv_status vv_radiosity_solve(vv_radiosity **out, const vv_world *world,
                             const vv_radiosity_options *opt, const vv_progress *progress);

/** Releases a solution. Accepts NULL. */
void vv_radiosity_free(vv_radiosity *r);

/** Counts and energy balance. */
void vv_radiosity_get_stats(const vv_radiosity *r, vv_radiosity_stats *s);

/**
 * Power absorbed by object @p index of the solved World and the power it
 * sends out (emitted + scattered, both sides), RGB; either may be NULL.
 * Errors: VV_ERR_INVALID (index out of range).
 */
vv_status vv_radiosity_object_power(const vv_radiosity *r, int index, double absorbed[3],
                                    double radiated[3]);

/**
 * Radiosity (power per area, display units) of the side of object @p
 * index's patches that faces direction @p side_normal at the patch nearest
 * to world point @p p. Errors: VV_ERR_INVALID (no patch of that object).
 */
vv_status vv_radiosity_patch_at(const vv_radiosity *r, int index, vv_vec3 p, vv_vec3 side_normal,
                                double radiosity[3]);

/**
 * Renders @p view of the solution (ray casting that composites the voxel
 * radiosities along each ray through the transfer function's opacity, over
 * the radiosity of the first patch hit and the background). @p world must
 * be the solved World or one with the same objects (it gives the volumes
 * and transfer functions). @p out is view->width x view->height; threads <=
 * 0: vv_threads_get(). Errors: VV_ERR_INVALID (size mismatch).
 */
vv_status vv_radiosity_view_frame(const vv_radiosity *r, const vv_world *world, const vv_view *view,
                                  int threads, vv_image *out);

#ifdef __cplusplus
}
#endif
#endif
