/*
 * VolVis slices: multiplanar reconstruction (MPR) of a volume object, the
 * axial, coronal, sagittal and oblique views every medical viewer shows
 * beside the 3-D view (3D Slicer's slice views, ParaView's slice
 * representation), and the probe that reads a voxel value at a world point.
 * The GUI's slice views and `volvis slice` both sample through here, so the
 * CLI writes what the GUI shows.
 *
 * A slice is a plane of the World: a centre, two unit in-plane axes (the
 * image's right and up) and a pixel size in world units. Samples are the
 * object's volume, placed by its transform and the volume's origin,
 * spacing and direction matrix (vv_object_index_to_world), interpolated
 * trilinearly at each pixel centre; a pixel whose point lies outside the
 * volume's node-centred box is NaN. The volume is the object's own, so a
 * filtered object (a scene's "filters") is sliced filtered.
 *
 * Orientations follow the volume's anatomical frame (vv_space): world
 * coordinates are taken as RAS (x to the patient's Right, y Anterior, z
 * Superior) or LPS and shown as radiologists do: axial seen from the feet
 * (patient's right on the image's left, anterior up), coronal from the
 * front (right on the left, superior up), sagittal from the patient's left
 * (anterior on the left, superior up). Without a known frame the axes are
 * the World's: axial is the xy plane (x right, y up), coronal xz (x right,
 * z up), sagittal yz (y right, z up), and the edges are labelled "+x" ...
 *
 * Units: world units (the file's, usually mm) for positions and the pixel
 * size; voxel values in the volume's own units. Thread-safety: every
 * function is reentrant; vv_slice_sample reads the volume only.
 */
#ifndef VOLVIS_SLICE_H
#define VOLVIS_SLICE_H

#include <stddef.h>
#include <stdint.h>

#include "core.h"
#include "math.h"
#include "model.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The orientation of a slice. */
typedef enum vv_slice_axis {
    VV_SLICE_AXIAL = 0,    /**< normal along superior (z) */
    VV_SLICE_CORONAL = 1,  /**< normal along anterior (y) */
    VV_SLICE_SAGITTAL = 2, /**< normal along right (x) */
    VV_SLICE_OBLIQUE = 3   /**< any normal (a cut plane's) */
} vv_slice_axis;

/** "axial", "coronal", "sagittal", "oblique"; "unknown" otherwise. Never NULL. */
const char *vv_slice_axis_name(vv_slice_axis axis);
/** Parses a name of vv_slice_axis_name. Errors: VV_ERR_INVALID (naming the choices). */
vv_status vv_slice_axis_parse(const char *name, vv_slice_axis *out);

/** A slice plane and the image that samples it. */
typedef struct vv_slice_plane {
    vv_slice_axis axis;
    vv_vec3 center; /**< world position of the image's centre */
    vv_vec3 right;  /**< unit world direction of the image's +x (columns to the right) */
    vv_vec3 up;     /**< unit world direction of the image's up (rows go down) */
    double pixel;   /**< world units per pixel, > 0 */
    int width;      /**< image size in pixels, >= 1 */
    int height;
    /** Labels of the image's right, left, top and bottom edges: the anatomical
        direction ("L", "R", "A", "P", "S", "I") or the World's axis ("+x", "-z"). */
    char edge[4][4];
} vv_slice_plane;

/**
 * A plane of orientation @p axis (not oblique) through world point
 * @p through, for a volume in anatomical frame @p space, sampling a
 * @p width x @p height image at @p pixel world units a pixel, centred on
 * @p through. Errors: VV_ERR_INVALID (oblique axis, non-finite point,
 * size < 1, pixel <= 0).
 */
vv_status vv_slice_plane_standard(vv_slice_plane *out, vv_slice_axis axis, vv_space space,
                                  vv_vec3 through, int width, int height, double pixel);
/**
 * An oblique plane through @p point with normal @p normal (a cut plane):
 * the image's up is the World's superior (z) projected into the plane, or
 * its anterior (y) when the normal is along z, so that turning a cut plane
 * turns the image smoothly. Edges are labelled by the nearest anatomical
 * direction (or axis). Errors: VV_ERR_INVALID (zero or non-finite normal,
 * size < 1, pixel <= 0).
 */
vv_status vv_slice_plane_oblique(vv_slice_plane *out, vv_space space, vv_vec3 point, vv_vec3 normal,
                                 int width, int height, double pixel);
/** The unit normal of @p p: right x up (towards the viewer of the image). */
vv_vec3 vv_slice_plane_normal(const vv_slice_plane *p);
/**
 * Moves the image's centre within the plane to the projection of
 * @p box's centre and sets the pixel size so that @p box's projection
 * fits the image with @p margin (a fraction, e.g. 0.05) on each side;
 * the plane's position along its normal is kept. A box that projects to a
 * point keeps the pixel size.
 */
void vv_slice_plane_fit(vv_slice_plane *p, vv_box box, double margin);
/** World position of image point (x, y) (pixel (i, j)'s centre is (i + 0.5, j + 0.5)). */
vv_vec3 vv_slice_plane_to_world(const vv_slice_plane *p, double x, double y);
/**
 * Image position of the projection of world point @p w onto the plane; the
 * signed distance of @p w from the plane along the normal goes to @p depth
 * (may be NULL).
 */
void vv_slice_plane_from_world(const vv_slice_plane *p, vv_vec3 w, double *x, double *y,
                               double *depth);

/**
 * The world distance between neighbouring slices along @p normal for the
 * volume of @p obj: the step whose displacement in voxel index space has a
 * largest component of exactly one voxel (the spacing itself for a normal
 * along a volume axis). Errors as 0 when the object has no volume.
 */
double vv_slice_step(const vv_object *obj, vv_vec3 normal);

/**
 * Samples volume object @p obj on plane @p p into @p values (p->width x
 * p->height floats, row-major, row 0 at the top): the trilinear value at
 * each pixel centre, NaN outside the volume's box. Rows are sampled in
 * parallel (OpenMP); the result is the same for any thread count. An object
 * showing a file out of core (its `source`, vv_object_new_source) is
 * sampled from the file, not its proxy: the coarsest level whose voxel is at
 * most a pixel (level 0 at worst; a coarser one when that box would take
 * more than a quarter of the cache's limit), only the box the plane
 * crosses, read through the source's cache (vv_source_read_box, which any
 * thread may call). Errors: VV_ERR_INVALID (NULL
 * argument, an object without a volume, a transform that cannot be
 * inverted); out of core, those of vv_source_read_box.
 */
vv_status vv_slice_sample(const vv_object *obj, const vv_slice_plane *p, float *values);

/**
 * As vv_slice_sample, the voxels of channel @p channel (0..n_channels-1) of
 * multi-channel volume object @p obj (vv_object_set_channels): every
 * channel shares channel 0's grid and the object's placement; a label
 * channel (vv_channel.labels) takes each pixel's nearest voxel (trilinear
 * for the others), so labels never blend into ids between them. Errors:
 * VV_ERR_INVALID (NULL argument, a channel the object does not have, a
 * transform that cannot be inverted).
 */
vv_status vv_slice_sample_channel(const vv_object *obj, int channel, const vv_slice_plane *p,
                                  float *values);

/**
 * The channels of @p obj blended into opaque RGBA8 (4 bytes a pixel) as a
 * fluorescence microscope's viewer shows a slice (napari's additive
 * blending, Fiji's composite display): each visible channel adds its
 * transfer function's colour at the value times its opacity there relative
 * to the function's highest opacity (so a contrast function,
 * vv_tf_set_contrast, gives colour x ((v - lo) / (hi - lo))^gamma,
 * saturating at hi); a label channel adds half its label's colour
 * (vv_label_color; label 0 nothing); each component clamped to 1. @p values holds
 * n_channels arrays of @p n samples (vv_slice_sample_channel); a pixel NaN
 * in every channel is @p outside (RGB, 0..1). Hidden channels add nothing.
 * Reads its arguments only; reentrant.
 */
void vv_slice_blend_channels(const vv_object *obj, const float *const *values, size_t n,
                             vv_vec3 outside, uint8_t *rgba);

/**
 * The voxel value of volume object @p obj at world point @p world
 * (trilinear), with its continuous voxel index in @p ijk (may be NULL).
 * Returns NaN outside the volume's box or for an object without a volume.
 * An object out of core is probed in level 0 of its file (a box of 4^3
 * voxels read around the point; NaN when it cannot be read), its level-0
 * index in @p ijk.
 */
double vv_slice_probe(const vv_object *obj, vv_vec3 world, double ijk[3]);

/**
 * A window and level that show most of @p v: from the 1st to the 99.5th
 * percentile of its foreground (vv_volume_foreground_range: the
 * histogram's background peak set aside), the whole range when those
 * coincide.
 * *window > 0.
 */
void vv_slice_auto_window(const vv_volume *v, double *window, double *level);

/**
 * Maps values to opaque grey RGBA8 (4 bytes a pixel): level - window/2 is
 * black, level + window/2 white, linear between (DICOM's linear VOI
 * function without its half-step offsets); NaN gives @p outside (RGB, 0..1).
 * @p window <= 0 is taken as the smallest positive double.
 */
void vv_slice_window_level(const float *values, size_t n, double window, double level,
                           vv_vec3 outside, uint8_t *rgba);

#ifdef __cplusplus
}
#endif
#endif
