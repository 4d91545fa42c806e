/*
 * Bricked volumes (include/volvis/bricks.h), internal to src/io: what the
 * bricked reader (bricked.c) needs of the NRRD reader (nrrd.c).
 */
#ifndef VV_IO_BRICKED_INTERNAL_H
#define VV_IO_BRICKED_INTERNAL_H

#include "volvis/bricks.h"

/* The NRRD reader's raw layout (src/io/volume/nrrd.c): the header of an
 * uncompressed NRRD as a one-voxel volume holding the geometry (its dims
 * set to the file's), the file holding the data (malloc'ed), the byte
 * offset of the data in it, and the byte order. Errors: VV_ERR_FORMAT (not
 * raw encoding, several data files, line skips), VV_ERR_IO. */
vv_status vv_nrrd_raw_layout(const char *path, vv_volume **header, char **data_path,
                             uint64_t *offset, int *big_endian);
/* vv_nrrd_raw_layout that also takes gzip and bzip2 encodings when
 * *@p gzip is 1 on entry (a byte skip refused): *@p gzip then says which
 * it is (0 raw, 1 gzip, 2 bzip2), and the offset is where the compressed
 * stream starts (vv_slabs streams it). */
vv_status vv_nrrd_data_layout(const char *path, vv_volume **header, char **data_path,
                              uint64_t *offset, int *big_endian, int *gzip);

#endif
