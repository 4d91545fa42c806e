/*
 * OME-Zarr (not installed): the reader (zarr_read.c) for the format record
 * in zarr_write.c.
 */
#ifndef VOLVIS_IO_ZARR_H
#define VOLVIS_IO_ZARR_H

#include "volvis/io.h"
#include "volvis/sys/format.h"

/**
 * Reads channel opt->channel at step opt->time of level 0 of the OME-Zarr
 * store (or plain Zarr v2 array) at folder @p path, with vv_volume_load's
 * contract; opt->info gets the channel and time counts, the omero name and
 * colour and the time between steps. Errors (prefixed "zarr: NAME"):
 * VV_ERR_FORMAT (malformed metadata, a chunk that does not decode to its
 * size), VV_ERR_UNSUPPORTED (dtype, compressor, filters, F order, axes),
 * VV_ERR_LIMIT, VV_ERR_INVALID (a channel or step out of range), VV_ERR_IO,
 * VV_ERR_NOMEM. Reentrant.
 */
vv_status vv_ome_zarr_read(vv_volume **out, const char *path, const vv_load_options *opt);

/** A folder holding a .zarray, or a .zattrs with "multiscales" (deep 0 only). */
int vv_ome_zarr_looks_like(const vv_format_probe *p, int deep);

#endif
