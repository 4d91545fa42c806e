/*
 * VolVis volume input and output.
 *
 * Formats: SLC (VolVis's own, read and write, plain and run-length
 * compressed), NRRD (Teem's nrrd library; read and write), NIfTI-1/NIfTI-2
 * (nifti_clib; .nii, .nii.gz, .hdr/.img), MetaImage (.mhd/.mha), VTK legacy
 * STRUCTURED_POINTS (binary and ASCII) and raw files described by the caller.
 * File formats are documented in docs/formats.md.
 *
 * Every reader checks header sizes with vv_volume_check_size() before
 * allocating, never reads past the data it was given, and on failure returns
 * an error whose trace names the file and the problem ("slc: nut.slc: slice
 * 12: ..."). Every writer writes a temporary file beside the target and
 * renames it, so a failed write leaves an existing file untouched.
 *
 * Thread-safety: readers and writers are reentrant; calls into Teem are
 * serialised internally (its error state is global).
 */
#ifndef VOLVIS_IO_H
#define VOLVIS_IO_H

#include <stdint.h>

#include "core.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum vv_format {
    VV_FORMAT_AUTO = 0, /**< detect from content, extension as a hint */
    VV_FORMAT_SLC,
    VV_FORMAT_NRRD,
    VV_FORMAT_NIFTI,
    VV_FORMAT_MHD,
    VV_FORMAT_VTK,
    VV_FORMAT_RAW,
    VV_FORMAT_UNKNOWN
} vv_format;

/** Lower-case format name ("slc", "nrrd", ...). */
const char *vv_format_name(vv_format f);
/** Parses a format name as printed by vv_format_name. */
vv_status vv_format_parse(const char *name, vv_format *out);

/**
 * Detects the format of @p path: magic numbers first (SLC "11111", "NRRD000",
 * NIfTI sizeof_hdr 348/540 also gzip-compressed, "# vtk DataFile",
 * MetaImage keys), the extension as a hint when the content is ambiguous.
 * Returns VV_FORMAT_UNKNOWN when nothing matches (and for raw files, which
 * have no signature).
 */
vv_format vv_format_detect(const char *path);

/** How to read a raw file: nothing in the file describes it. */
typedef struct vv_raw_params {
    int dims[3];
    vv_voxel_type type;
    int big_endian;       /**< 1: big-endian voxels */
    double spacing[3];    /**< default 1 */
    double origin[3];     /**< default 0 */
    uint64_t header_skip; /**< bytes to skip before the data */
} vv_raw_params;

/** Unset dims (0), u8, little-endian, spacing 1, origin 0, no skip. */
void vv_raw_params_init(vv_raw_params *p);

/** Options for vv_volume_load. */
typedef struct vv_load_options {
    vv_format format; /**< VV_FORMAT_AUTO to detect */
    int has_raw;      /**< 1: raw is valid (required for VV_FORMAT_RAW) */
    vv_raw_params raw;
} vv_load_options;

/** Format VV_FORMAT_AUTO, no raw parameters (has_raw 0, raw as vv_raw_params_init). */
void vv_load_options_init(vv_load_options *o);

/**
 * Loads any supported volume file. @p opt may be NULL (detect the format).
 * On success *out holds a new volume (refcount 1) with range[] computed.
 * Errors: VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_LIMIT, VV_ERR_UNSUPPORTED,
 * VV_ERR_NOMEM; the trace starts with the format and file name.
 */
vv_status vv_volume_load(vv_volume **out, const char *path, const vv_load_options *opt);

/**
 * Writes @p v to @p path as @p format (VV_FORMAT_AUTO: from the extension,
 * .slc or .nrrd/.nhdr). SLC holds 8-bit data only: other types are rescaled
 * from range[] to 0..255 (and the modification set to "other") unless
 * @p strict, in which case VV_ERR_UNSUPPORTED is returned.
 */
vv_status vv_volume_save(const vv_volume *v, const char *path, vv_format format, int strict);

/* ---- per-format entry points (same contracts as above) ---------------- */

vv_status vv_slc_read(vv_volume **out, const char *path);
/** Writes 8-bit SLC, RLE-compressed when @p rle, with a maximum-projection icon. */
vv_status vv_slc_write(const vv_volume *v, const char *path, int rle);

/** NRRD through Teem (attached or detached header, lists, patterns). */
vv_status vv_nrrd_read(vv_volume **out, const char *path);
/** Writes NRRD with gzip encoding (raw when @p gzip is 0), spacing and origin. */
vv_status vv_nrrd_write(const vv_volume *v, const char *path, int gzip);

/** NIfTI-1/NIfTI-2 (.nii, .nii.gz, .hdr/.img) through nifti_clib; scaling applied. */
vv_status vv_nifti_read(vv_volume **out, const char *path);
/** MetaImage .mhd (detached data) or .mha (LOCAL data), optionally zlib-compressed. */
vv_status vv_mhd_read(vv_volume **out, const char *path);
/** VTK legacy STRUCTURED_POINTS, BINARY (big-endian) or ASCII, first SCALARS array. */
vv_status vv_vtk_read(vv_volume **out, const char *path);
/**
 * Raw voxels described by @p params (borrowed). The file must hold at least
 * header_skip + the volume's bytes; VV_ERR_FORMAT names both sizes otherwise.
 */
vv_status vv_raw_read(vv_volume **out, const char *path, const vv_raw_params *params);

#ifdef __cplusplus
}
#endif
#endif
