/*
 * Helpers shared by the files of src/model (not installed).
 */
#ifndef VOLVIS_MODEL_INTERNAL_H
#define VOLVIS_MODEL_INTERNAL_H

#include "volvis/model.h"

/** Smallest voxel spacing of @p v (1 if the spacing is not positive and finite). */
double vv_model_min_spacing(const vv_volume *v);

/** Copies @p src (NULL: "") into a name field, truncating to VV_NAME_MAX - 1 bytes. */
void vv_model_copy_name(char dst[VV_NAME_MAX], const char *src);

/**
 * The default transfer function of @p v for @p mode (docs/scene-format.md,
 * "Default scene"): fills @p tf and stores the composite ramp's lower end in
 * *iso_lo (a default isovalue). Never fails.
 */
void vv_model_default_tf(const vv_volume *v, vv_render_mode mode, vv_tf *tf, double *iso_lo);

#endif
