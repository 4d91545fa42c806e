/*
 * Internal interface between the DICOM reader (dicom.c, C) and the GDCM shim
 * (dicom_gdcm.cpp, C++). The shim parses and decodes; the reader groups,
 * sorts, checks and builds the volume. Everything here is plain C.
 *
 * Thread-safety: the shim's functions are reentrant (each call has its own
 * GDCM reader objects; GDCM's dictionaries are initialised once, before the
 * first parallel call, by vv_dcm_init).
 */
#ifndef VV_IO_DICOM_H
#define VV_IO_DICOM_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** What the reader needs of one DICOM file's header. */
typedef struct vv_dcm_file {
    char *path; /**< owned by the caller */
    char series_uid[72], series_desc[72], modality[20], study_desc[72], study_date[20];
    char patient_name[72], patient_id[72]; /**< PHI: listing only */
    int series_number, instance_number;
    int rows, cols, frames, samples, planar;
    int bits_allocated, bits_stored, pixel_rep;
    int encapsulated;    /**< compressed transfer syntax (pixel data size unknown) */
    int native_le;       /**< explicit or implicit VR little endian (not deflated) */
    long long pixel_end; /**< native syntaxes: where GDCM's reading ended after the
                              Pixel Data element, -1 unknown */
    int has_ipp, has_iop, has_spacing;
    double ipp[3], iop[6];   /**< Image Position / Orientation (Patient), LPS */
    double pixel_spacing[2]; /**< DICOM order: between rows, between columns */
    double frame_spacing;    /**< multi-frame: GDCM's slice spacing, 0 unknown */
    double slope, intercept;
    double *frame_ipp; /**< multi-frame: frames * 3 positions (malloc'ed), or NULL */
    /** the image's place in a time series (cardiac phases, perfusion):
     *  Temporal Position Identifier (0020,0100), 0 when absent, and Trigger
     *  Time (0018,1060) in ms when has_trigger */
    int temporal_position, has_trigger;
    double trigger_time;
} vv_dcm_file;

/** Initialises GDCM's global dictionaries (idempotent, not thread-safe). */
void vv_dcm_init(void);

/**
 * Our walk of the data elements' lengths and the meta-group patterns GDCM
 * asserts on, alone (no GDCM call): 0, or -1 with the reason in @p err.
 */
int vv_dcm_prescan(const char *path, char *err, size_t errlen);

/**
 * Reads the header of @p path (pixel data skipped) into @p f (f->path is
 * left alone). Returns 1 for a DICOM image, 0 for a file that is not DICOM or
 * holds no image (no rows/columns), -1 on a broken DICOM file with the
 * reason in @p err.
 */
int vv_dcm_read_header(const char *path, vv_dcm_file *f, char *err, size_t errlen);

/**
 * Decodes the pixel data of @p path (any transfer syntax GDCM decodes) into
 * @p dst, which holds exactly @p bytes: rows * cols * frames * samples *
 * bits_allocated / 8 as the header said. Returns 0, or -1 with the reason.
 */
int vv_dcm_read_pixels(const char *path, void *dst, size_t bytes, char *err, size_t errlen);

/**
 * 1 when @p path is a DICOMDIR (Media Storage Directory); then *@p files gets
 * the referenced image files (full paths, malloc'ed, *@p n of them). 0 when
 * it is not a DICOMDIR, -1 with the reason on errors.
 */
int vv_dcm_dicomdir_files(const char *path, char ***files, int *n, char *err, size_t errlen);

/** 1 when @p path starts like a DICOM file without a preamble (a cheap check, no GDCM). */
int vv_dicom_sniff(const char *path);

#ifdef __cplusplus
}
#endif
#endif
