/*
 * The DICOM browser: the image series of a folder (or DICOMDIR) listed by
 * patient, study and series (modality, description, number, size, files),
 * as vv_dicom_list finds them. Patient names and IDs are protected health
 * information: they are shown only while "Show patient names" is on (as
 * the CLI's --show-phi); otherwise patients are "Patient 1", "Patient 2".
 * Open reads the selected series (vv_volume_load with its series number)
 * into the document. UI thread only.
 */
#ifndef VVG_DICOM_DIALOG_H
#define VVG_DICOM_DIALOG_H

#include "vvg-document.h"

G_BEGIN_DECLS

/** Opens the browser over @p parent for @p doc. */
void vvg_dicom_dialog_present(GtkWindow *parent, VvgDocument *doc);

G_END_DECLS
#endif
