/*
 * VolVis's bricked file format, .vvb (docs/file-formats.md): the writer's
 * flags.
 * A .vvb holds a volume larger than memory as bricks of VV_BRICK_CELLS^3
 * cells with a one-voxel ghost border, each with its min and max in an
 * index, optionally a coarse level per brick and pyramid levels; vv_open
 * (io.h) opens one out of core by bricks or, with levels, as a pyramid.
 * A .vvb is written through the format table: vv_volume_save_with or
 * vv_volume_save_boxes (io.h) with VV_FORMAT_VVB (or the extension .vvb)
 * and these flags in vv_save_options.vvb_flags.
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

/** vv_save_options.vvb_flags: each brick also gets its coarse level
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

#ifdef __cplusplus
}
#endif
#endif
