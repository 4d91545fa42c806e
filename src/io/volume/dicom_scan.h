/*
 * DICOM series, internal to src/io: what the series listing (dicom.c:
 * finding the files, reading their headers, grouping them by series) and
 * the volume assembly (dicom_volume.c: one series into a volume) share.
 * Built with GDCM only (VV_HAVE_GDCM).
 *
 * Thread-safety: a scan is read by one thread at a time; nothing global.
 */
#ifndef VV_IO_DICOM_SCAN_H
#define VV_IO_DICOM_SCAN_H

#include "io/volume/dicom.h"
#include "volvis/io.h"

/* The image files of a path, grouped by series (dicom.c, scan_path). */
typedef struct dicom_scan {
    vv_dcm_file *f; /* image files */
    int n;
    int looked; /* files looked at */
    int *order; /* f indices grouped by series */
    int *start; /* series s: order[start[s] .. start[s+1]) */
    int n_series;
} dicom_scan;

/* The time steps of series @p si (of @p frames images in all) as
 * dicom_read_series finds them: 1 when the images have no positions or one
 * each (dicom_volume.c). */
int dicom_series_time_steps(const dicom_scan *sc, int si, long frames);

/* Series @p si (0-based) of @p sc as a volume: channel @p channel at time
 * step @p time, the steps' count and spacing into @p info (may be NULL).
 * Errors name the files (dicom_volume.c). */
vv_status dicom_read_series(vv_volume **out, const dicom_scan *sc, int si, int channel, int time,
                            vv_load_info *info);

#endif
