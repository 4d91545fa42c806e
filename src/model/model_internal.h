/*
 * Helpers shared by the files of src/model (not installed).
 */
#ifndef VOLVIS_MODEL_INTERNAL_H
#define VOLVIS_MODEL_INTERNAL_H

#include "volvis/model.h"
#include "volvis/sys/geometry.h"

/** Copies @p src (NULL: "") into a name field, truncating to VV_NAME_MAX - 1 bytes. */
void vv_model_copy_name(char dst[VV_NAME_MAX], const char *src);

/** A new empty mesh with normals and room for @p nv vertices, @p nt triangles. */
vv_status vv_geom_mesh_new(vv_mesh **out, size_t nv, size_t nt);

/** Appends a vertex at @p p with unit normal @p n. */
vv_status vv_geom_mesh_vertex(vv_mesh *m, vv_vec3 p, vv_vec3 n);

/** Segments around a circle of radius @p radius for @p opt (3..4096, even). */
int vv_geom_tess_segments(const vv_geom_tess *opt, double radius);

#endif
