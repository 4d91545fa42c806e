/*
 * Bricked volumes (include/volvis/bricks.h), internal: what the out-of-core
 * renderer (src/render/raycast/raycast_ooc.c) needs of a brick.
 */
#ifndef VV_CORE_BRICKS_INTERNAL_H
#define VV_CORE_BRICKS_INTERNAL_H

#include "volvis/bricks.h"

typedef struct vv_brick_info {
    int lo[3], hi[3];   /* the brick's cells: voxel indices lo .. hi (its faces) */
    int slo[3], shi[3]; /* the voxels read: one beyond each face, within the volume */
    float vmin, vmax;   /* min and max of the voxels read */
} vv_brick_info;

/* Bricks in all (nb[0] nb[1] nb[2], i fastest). */
int vv_bricked_count(const vv_bricked *b);
/* Brick @p index's boxes and min/max. */
void vv_bricked_info(const vv_bricked *b, int index, vv_brick_info *info);
/* Brick @p index as a volume of its voxels read (the box slo .. shi) with
 * the whole volume's geometry and value range (src/render/raycast/
 * raycast_brick.h), from the cache or the file; a new reference (free it).
 * Errors: VV_ERR_IO, VV_ERR_FORMAT (short read), VV_ERR_NOMEM. */
vv_status vv_bricked_load(vv_bricked *b, int index, vv_volume **out);
/* Counts a brick skipped unread. */
void vv_bricked_note_skip(vv_bricked *b);

/* The NRRD reader's raw layout (src/io/nrrd.c): the header of an
 * uncompressed NRRD as a one-voxel volume holding the geometry (its dims
 * set to the file's), the file holding the data (malloc'ed), the byte
 * offset of the data in it, and the byte order. Errors: VV_ERR_FORMAT (not
 * raw encoding, several data files, line skips), VV_ERR_IO. */
vv_status vv_nrrd_raw_layout(const char *path, vv_volume **header, char **data_path,
                             uint64_t *offset, int *big_endian);

#endif
