/*
 * Our own checks of a file, run before a third-party parser sees it (issue
 * 33; docs/security.md, "Fuzzing"). In volvis-reader they run in front of
 * the library; the fuzz harnesses of the sandboxed formats
 * (tests/fuzz/fuzz_nrrd.c, ...) call them alone, in their own process, so
 * that what the fuzzers find is ours (the libraries are contained by the
 * sandbox, and the parent's side of it is fuzzed by fuzz_sandbox).
 *
 * Each reads @p path (or @p desc) and returns VV_OK when the library may
 * be given the file, or the error vv_nrrd_read (vv_nifti_read,
 * vv_dicom_read, vv_mesh_load) would report; none calls a third-party
 * parser. Reentrant; not installed.
 */
#ifndef VOLVIS_IO_PRESCAN_H
#define VOLVIS_IO_PRESCAN_H

#include "volvis/core.h"

/** NRRD: the header text read whole and checked line by line (length,
 *  fields, detached data files against the folder policy, their sizes). */
vv_status vv_nrrd_prescan(const char *path);

/** NIfTI-1/2 and Analyze: the raw header's sizes, offsets and the data
 *  the header promises against what the image file holds. */
vv_status vv_nifti_prescan(const char *path);

/** DICOM: the walk of the data elements' lengths (explicit and implicit
 *  VR, both byte orders, nested sequences, encapsulated pixel data) and the
 *  meta-group patterns GDCM asserts on (src/io/volume/dicom_gdcm.cpp). */
vv_status vv_dicom_prescan(const char *path);

/** Meshes: the file's size and, for OFF, STL and PLY, their structure
 *  against what the file holds, before Assimp (src/io/mesh/mesh.c). */
vv_status vv_mesh_prescan(const char *path);

/** TIFF: the OME-XML or ImageJ ImageDescription @p desc (a NUL-terminated
 *  string as libtiff returns it) parsed into the stack's axes, spacing,
 *  unit and origin; returns 1 for OME, 2 for ImageJ, 0 for neither. */
int vv_tiff_prescan_description(const char *desc);

#endif
