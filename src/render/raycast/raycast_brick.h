/*
 * The ray caster on one brick of a volume (internal): what sort-last
 * parallel rendering (src/parallel) needs from it.
 *
 * The object's volume holds only a brick of the whole volume (its voxels
 * plus ghost voxels), with the whole volume's geometry (origin, spacing,
 * direction: the brick's voxel (0, 0, 0) is the whole volume's voxel off)
 * and value range. Rays are set up in the whole volume's index space
 * exactly as a render of the whole volume sets them up, and a brick keeps
 * the samples t = k dt whose point lies in its box lo <= p < hi: every
 * sample of the whole render is taken by exactly one brick, at the same
 * point, so bricks composited in visibility order give the whole image
 * (bit for bit for maximum and minimum intensity projection).
 */
#ifndef VV_RENDER_RAYCAST_BRICK_H
#define VV_RENDER_RAYCAST_BRICK_H

#include "volvis/render.h"

typedef struct vv_raycast_brick {
    int gdims[3];        /* dims of the whole volume */
    int off[3];          /* whole-volume index of the brick's voxel (0, 0, 0) */
    double lo[3], hi[3]; /* samples owned: lo <= p < hi, whole-volume index units (+-INFINITY) */
    /* pixels x0 <= x < x1, y0 <= y < y1 that can see the brick (the rest of
     * the image is left empty); x1 <= x0: the whole image */
    int x0, y0, x1, y1;
} vv_raycast_brick;

/*
 * The pixel rectangle that can see the index box lo .. hi (voxel indices,
 * the whole volume's) of object @p obj through @p view, two pixels wider on
 * each side; the whole image when the box reaches behind the eye. Fills
 * b->x0 .. b->y1.
 */
void vv_raycast_brick_rect(vv_raycast_brick *b, const vv_object *obj, const vv_view *view,
                           const int lo[3], const int hi[3]);

/*
 * Puts raycast renderer @p r in brick mode (@p b copied) or back to whole
 * renders (@p b NULL). In brick mode a render draws one visible volume
 * object, in composite, mip or minip mode (else VV_ERR_UNSUPPORTED), and
 * writes partial pixels without background: composite, the premultiplied
 * colour and opacity and the depth of the first visible sample;
 * projections, {value in stored units, 1, 0, 0} where the brick took a
 * sample, {0, 0, 0, 0} where not, and the depth of the value. Errors:
 * VV_ERR_INVALID (@p r is not a raycast renderer).
 */
vv_status vv_raycast_set_brick(vv_renderer *r, const vv_raycast_brick *b);

/*
 * Turns a projection image of partial pixels (as a brick render writes
 * them, combined over the bricks) into the colours a whole render draws,
 * with the table and background of the last brick render of @p r. Errors:
 * VV_ERR_INVALID (no brick render of a projection before).
 */
vv_status vv_raycast_finish_projection(vv_renderer *r, vv_image *img);

#endif
