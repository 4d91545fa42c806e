/*
 * Helpers shared by the files of src/model (not installed).
 */
#ifndef VOLVIS_MODEL_INTERNAL_H
#define VOLVIS_MODEL_INTERNAL_H

#include "volvis/model.h"

/** Copies @p src (NULL: "") into a name field, truncating to VV_NAME_MAX - 1 bytes. */
void vv_model_copy_name(char dst[VV_NAME_MAX], const char *src);

#endif
