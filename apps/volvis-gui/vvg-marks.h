/*
 * VvMarks: what the scene view and the slice views show on top of the
 * data, linked between them: the slice cursor (the world point the three
 * orthogonal slices pass through, moved by a click in any slice view), the
 * slice views' window and level, and the measurement marks (picked points
 * A and B with the line between them, the seed voxel, the surface-tracked
 * region as a mesh). No undo: these are views of the World, not part of
 * it. Emits "changed" when anything changes. UI thread only.
 */
#ifndef VV_MARKS_H
#define VV_MARKS_H

#include <gtk/gtk.h>
#include <volvis/volvis.h>

G_BEGIN_DECLS

#define VV_TYPE_MARKS (vv_marks_get_type())
G_DECLARE_FINAL_TYPE(VvMarks, vv_marks, VV, MARKS, GObject)

/** Which measurement point. */
typedef enum VvMark { VV_MARK_A = 0, VV_MARK_B = 1, VV_MARK_SEED = 2, VV_MARK_COUNT = 3 } VvMark;

VvMarks *vv_marks_new(void);

/** The slice cursor, world units; FALSE (and @p out untouched) before one is set. */
gboolean vv_marks_cursor(VvMarks *m, vv_vec3 *out);
void vv_marks_set_cursor(VvMarks *m, vv_vec3 p);
/** Forgets the cursor and the window (a new volume): the views start again from its centre. */
void vv_marks_reset(VvMarks *m);
/** The slice views' window and level; FALSE before they are set. */
gboolean vv_marks_window(VvMarks *m, double *window, double *level);
void vv_marks_set_window(VvMarks *m, double window, double level);

/**
 * The cut plane chosen in the Cut planes list (object -1: global), which
 * the oblique slice view shows and a cut-plane drag moves; *plane -1: none.
 */
void vv_marks_cut_plane(VvMarks *m, int *object, int *plane);
void vv_marks_set_cut_plane(VvMarks *m, int object, int plane);
/** Measurement point @p which (world), or FALSE when it is not set. */
gboolean vv_marks_point(VvMarks *m, VvMark which, vv_vec3 *out);
void vv_marks_set_point(VvMarks *m, VvMark which, vv_vec3 p);
void vv_marks_clear_point(VvMarks *m, VvMark which);
/** The surface-tracked region (world coordinates; a reference is held), or NULL. */
const vv_mesh *vv_marks_region(VvMarks *m);
/** Replaces the region (@p mesh may be NULL; a reference is taken). */
void vv_marks_set_region(VvMarks *m, vv_mesh *mesh);

G_END_DECLS
#endif
