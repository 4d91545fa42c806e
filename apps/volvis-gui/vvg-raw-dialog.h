/*
 * The raw-import dialog: a file of raw voxels described by hand (dimensions,
 * voxel type, endianness, voxel spacing, header bytes to skip), with a live
 * preview of its middle slice that changes as the description does (a wrong
 * width shows as slanted stripes at once), and the size check the reader
 * makes (the file must hold the header and every voxel). Import reads it
 * with vv_volume_load (VV_FORMAT_RAW) and adds it to the document as a
 * volume made in the session (a saved session writes it as NRRD beside the
 * scene, since a scene file cannot describe raw data). UI thread only.
 */
#ifndef VVG_RAW_DIALOG_H
#define VVG_RAW_DIALOG_H

#include "vvg-document.h"

G_BEGIN_DECLS

/** Opens the dialog over @p parent for @p doc; @p path (may be NULL) is the file. */
void vvg_raw_dialog_present(GtkWindow *parent, VvgDocument *doc, const char *path);

/**
 * The middle slice (k = dims[2] / 2) of raw file @p path as described by
 * @p p: dims[0] x dims[1] floats into @p out. FALSE with a message in
 * @p why (why_size bytes) when the file is too short or cannot be read.
 */
gboolean vvg_raw_preview_slice(const char *path, const vv_raw_params *p, float *out, char *why,
                               size_t why_size);

G_END_DECLS
#endif
