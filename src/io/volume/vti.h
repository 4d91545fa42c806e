/*
 * VTK XML image data (not installed): the reader (vti_read.c) for the
 * format record in vtk_write.c.
 */
#ifndef VOLVIS_IO_VTI_H
#define VOLVIS_IO_VTI_H

#include "volvis/io.h"
#include "volvis/sys/format.h"

/**
 * Reads component opt->channel (-1: 0) of the point data of the VTK XML
 * image data file @p path (ParaView's .vti; "VTK File Formats", XML
 * ImageData): the array PointData's Scalars attribute names, else its
 * first; inline ascii or base64, or appended raw or base64, zlib-compressed
 * or not, either byte order, UInt32 or UInt64 headers. Geometry: the
 * WholeExtent's size, Spacing, Direction (row-major, columns the index
 * axes) and Origin moved to the extent's first point. opt->info gets the
 * component count as the channels and ComponentName<c> as the name.
 * Errors (prefixed "vti: NAME"): VV_ERR_FORMAT (malformed XML or
 * attributes, truncated or inconsistent data), VV_ERR_UNSUPPORTED (64-bit
 * integers, several pieces, cell data only, another compressor),
 * VV_ERR_LIMIT, VV_ERR_INVALID (a channel past the components), VV_ERR_IO,
 * VV_ERR_NOMEM. Reentrant.
 */
vv_status vv_vti_read(vv_volume **out, const char *path, const vv_load_options *opt);

/** A file that starts as a VTK XML ImageData file (deep 0 only). */
int vv_vti_looks_like(const vv_format_probe *p, int deep);

#endif
