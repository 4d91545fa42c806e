/*
 * The classification stage's tables, their types (internal to the volume
 * renderers, not part of the public API): an object's transfer-function
 * tables (vv_vtables) and what they depend on besides the volume
 * (vv_vtables_key). classify.h builds and reads them; the voxel cache of
 * sample.h keeps the last ones built for its volume between frames, so the
 * types sit here, below both.
 *
 * Per object: the transfer function in a 4096-entry table with opacity
 * corrected for the step (post-classification, as in Levoy's volume ray
 * casting, IEEE CG&A 1988), optionally the extinction per world unit, a 2-D
 * table over value and gradient magnitude (Kniss, Kindlmann and Hansen,
 * IEEE TVCG 2002) and the pre-integration table (Engel, Kraus and Ertl,
 * Graphics Hardware 2001), which subvolumes are visible under the transfer
 * function or isovalue (the PARC grid of the VolVis paper's Navigator,
 * section 4), and each subvolume's chessboard distance to the nearest
 * visible one (empty-space leaping). docs/rendering.md describes the
 * method.
 */
#ifndef VV_RENDER_TF_TABLES_H
#define VV_RENDER_TF_TABLES_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/render.h"

#define VV_VC_LUT 4096    /* transfer-function table entries */
#define VV_VC_LUT2_V 1024 /* 2-D transfer-function table: value bins */
#define VV_VC_LUT2_G 128  /* 2-D transfer-function table: gradient-magnitude bins */

/* What an object's tables depend on besides the volume. */
typedef struct vv_vtables_key {
    vv_render_mode mode;
    vv_segmentation segmentation;
    double threshold, iso, dt;
    vv_vec3 base;
    int skipping, flags; /* VV_VT_EXT, VV_VT_PREINT */
    vv_tf tf;
    vv_tf2d tf2d; /* VV_SEG_TRANSFER_FUNCTION_2D in composite mode */
} vv_vtables_key;

/* An object's tables. lut: VV_VC_LUT x {alpha, r*alpha, g*alpha, b*alpha}
 * with alpha corrected for the step (composite), or {alpha, r, g, b}
 * (projections); NULL in iso mode. ext: VV_VC_LUT extinctions per world
 * unit, -ln(1 - alpha) / opacity_unit_distance, or NULL when not asked
 * for. bvis: per subvolume, visible; bdist: chessboard distance in
 * subvolumes to the nearest visible one, at most 255 (0: visible),
 * followed in the same allocation by vdist (vv_vtables_vdist): the
 * chessboard distance to the nearest hidden one, at most 255 (0: hidden;
 * d: the cube of 2d - 1 subvolumes around it is all visible). */
/* lut2d (2-D transfer function, composite mode only; else NULL):
 * VV_VC_LUT2_G rows (gradient magnitude) of VV_VC_LUT2_V entries (value) of
 * {alpha, r*alpha, g*alpha, b*alpha}; value bin = nearest of table index *
 * (LUT2_V - 1) / (LUT - 1); gradient bin = nearest of gm * g_scale, the
 * last bin lying beyond every widget (transparent). lut (and ext) then hold,
 * per value, the entry of the largest opacity over all gradient
 * magnitudes: the subvolume flags, shadows and light volumes use that
 * conservative bound. */
typedef struct vv_vtables {
    float lut_lo, lut_scale; /* stored value -> table index */
    float *lut, *ext;
    uint8_t *bvis, *bdist;
    /* MIP and MinIP: the table's flat ends (vv_vtables_flat_ends) and, per
     * subvolume, the chessboard distance to the nearest one holding a value
     * beyond the flat end the projection starts from (vv_vray_project); 0
     * and NULL in other modes */
    float plo, phi;
    uint8_t *pdist;
    float *lut2d;
    float g_scale; /* gradient magnitude (data units per volume world unit) -> bin */
    /* pre-integrated classification (VV_VT_PREINT, composite mode with a
     * 1-D transfer function or a threshold; else NULL): VV_VC_LUT rows of 8
     * doubles over the table position x, {T, tau, K[3], tau c[3]}: tau the
     * extinction per world unit at the entry (-ln(1 - opacity) /
     * opacity_unit_distance, at most 40 / dt), c its colour, and T, K the
     * integrals over x from 0 to the entry of tau and of tau c, with tau
     * and tau c linear between entries (vv_vpre_at) */
    double *pre;
    int32_t *pre_nz; /* VV_VC_LUT + 1: entries below i with tau > 0 */
} vv_vtables;

/* The vdist array that follows bdist (vv_vtables) of @p nb subvolumes. */
static inline const uint8_t *
vv_vtables_vdist(const uint8_t *bdist, size_t nb) {
    return bdist + nb;
}

/* vv_vtables_get flags: also build the extinction table (ext), the
 * pre-integration table (pre). */
#define VV_VT_EXT 1
#define VV_VT_PREINT 2

/* Frees the arrays of tables @p t (NULL: nothing) and zeroes it. */
void vv_vtables_free(vv_vtables *t);

#endif
