/*
 * What every volume writer checks before it opens a file (not installed):
 * that the volume has voxels of a type the format holds, and a geometry
 * the header can say (finite spacing and origin, a finite direction
 * matrix). One place, so the six writers (MetaImage, VTK legacy and XML,
 * NRRD, NIfTI, TIFF, OME-Zarr) refuse alike, in the same words.
 *
 * Thread-safety: reentrant.
 */
#ifndef VOLVIS_IO_WRITE_CHECK_H
#define VOLVIS_IO_WRITE_CHECK_H

#include "volvis/volume.h"

/** io_write_check_geometry: the spacing need only be finite (VTK's may
 *  be zero or negative); else it must be positive. */
#define IO_WRITE_ANY_SPACING 1u
/** io_write_check_geometry: the format holds no direction matrix (TIFF,
 *  OME-Zarr 0.4): it is not looked at. */
#define IO_WRITE_NO_DIRECTION 2u

/**
 * @p v has voxels (@p has_data) and @p writable says the format holds its
 * voxel type. Errors: VV_ERR_INVALID "volume has no data",
 * VV_ERR_UNSUPPORTED "voxel type N cannot be written".
 */
vv_status io_write_check_voxels(const vv_volume *v, int has_data, int writable);

/**
 * The geometry of @p v as a writer's header holds it, under @p flags
 * (IO_WRITE_*). Errors: VV_ERR_INVALID "axis A: spacing S, origin O" (the
 * first axis at fault), "the direction matrix is not finite".
 */
vv_status io_write_check_geometry(const vv_volume *v, unsigned flags);

#endif
