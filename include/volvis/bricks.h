/*
 * VolVis's bricked file format, .vvb (docs/file-formats.md): the writers.
 * A .vvb holds a volume larger than memory as bricks of VV_BRICK_CELLS^3
 * cells with a one-voxel ghost border, each with its min and max in an
 * index, optionally a coarse level per brick and pyramid levels; vv_open
 * (io.h) opens one out of core by bricks or, with levels, as a pyramid.
 *
 * Thread-safety: the writers are reentrant.
 */
#ifndef VOLVIS_BRICKS_H
#define VOLVIS_BRICKS_H

#include <stdint.h>

#include "core.h"
#include "io.h"
#include "sys/source.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/** vv_bricked_write_vvb flags: each brick also gets its coarse level
 * (every 4th voxel; previews read those). */
#define VV_VVB_COARSE 1u
/** Each brick's voxels are one zstd frame (level 3), decoded when the brick
 * is read; implies VV_VVB_COARSE (docs/file-formats.md). */
#define VV_VVB_ZSTD 2u
/** The pyramid levels after the bricks: each level half the one before
 * along every axis longer than one voxel (rounding up; each voxel the mean
 * of the 2x2x2 under it, as the OME-Zarr writer's levels) until every axis
 * fits one chunk of 64 voxels, stored as chunks of 64^3 (raw, or zstd
 * frames with VV_VVB_ZSTD) with their min/max; vv_open reads them
 * (docs/file-formats.md). Written from level 0 read back, a chunk at a
 * time: memory stays bounded. */
#define VV_VVB_LEVELS 4u

/**
 * Writes the in-memory volume @p v as a .vvb file (for formats that cannot
 * be read by bricks: compressed NRRD, SLC, NIfTI, ...); @p flags as
 * vv_bricked_write_vvb. Errors: VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_volume_write_vvb(const vv_volume *v, const char *path, unsigned flags);

/**
 * Writes a .vvb file of the volume @p hdr describes (dims, type, geometry;
 * its voxels are not read) from a box reader, one brick (with its ghost
 * voxels) at a time in brick order (i fastest, then j, then k): memory is
 * the reader's and a brick's (vv_slabs: one slab of 66 slices, the ghost
 * slices the next layer of bricks shares kept). @p flags as
 * vv_bricked_write_vvb. Atomic as it: on failure nothing is left. Errors:
 * VV_ERR_IO, VV_ERR_NOMEM, the reader's, VV_ERR_INVALID (a box of another
 * shape or type from @p read).
 */
vv_status vv_boxes_write_vvb(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                             unsigned flags, const vv_progress *progress);

#ifdef __cplusplus
}
#endif
#endif
