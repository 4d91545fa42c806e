/*
 * VvgMarks: what the scene view and the slice views show on top of the
 * data, linked between them: the slice cursor (the world point the three
 * orthogonal slices pass through, moved by a click in any slice view), the
 * slice views' window and level, and the measurement marks (picked points
 * A and B with the line between them, the seed voxel, the surface-tracked
 * region as a mesh). No undo: these are views of the World, not part of
 * it. Emits "changed" when anything changes. UI thread only.
 */
#ifndef VVG_MARKS_H
#define VVG_MARKS_H

#include <gtk/gtk.h>
#include <volvis/volvis.h>

G_BEGIN_DECLS

#define VVG_TYPE_MARKS (vvg_marks_get_type())
G_DECLARE_FINAL_TYPE(VvgMarks, vvg_marks, VVG, MARKS, GObject)

/** Which measurement point. */
typedef enum VvgMark {
    VVG_MARK_A = 0,
    VVG_MARK_B = 1,
    VVG_MARK_SEED = 2,
    VVG_MARK_COUNT = 3
} VvgMark;

VvgMarks *vvg_marks_new(void);

/** The slice cursor, world units; FALSE (and @p out untouched) before one is set. */
gboolean vvg_marks_cursor(VvgMarks *m, vv_vec3 *out);
void vvg_marks_set_cursor(VvgMarks *m, vv_vec3 p);
/** Forgets the cursor and the window (a new volume): the views start again from its centre. */
void vvg_marks_reset(VvgMarks *m);
/** The slice views' window and level; FALSE before they are set. */
gboolean vvg_marks_window(VvgMarks *m, double *window, double *level);
void vvg_marks_set_window(VvgMarks *m, double window, double level);
/**
 * The window and level the slice views show for volume @p v: the ones set,
 * else @p v's automatic ones (vv_slice_auto_window: the 1st to the 99.5th
 * percentile), computed once a version of @p v (a pass over every voxel) and
 * kept for every view and page that asks.
 */
void vvg_marks_window_for(VvgMarks *m, const vv_volume *v, double *window, double *level);

/**
 * The cut plane chosen in the Cut planes list (object -1: global), which
 * the oblique slice view shows and a cut-plane drag moves; *plane -1: none.
 */
void vvg_marks_cut_plane(VvgMarks *m, int *object, int *plane);
void vvg_marks_set_cut_plane(VvgMarks *m, int object, int plane);
/** Measurement point @p which (world), or FALSE when it is not set. */
gboolean vvg_marks_point(VvgMarks *m, VvgMark which, vv_vec3 *out);
void vvg_marks_set_point(VvgMarks *m, VvgMark which, vv_vec3 p);
void vvg_marks_clear_point(VvgMarks *m, VvgMark which);
/** The surface-tracked region (world coordinates; a reference is held), or NULL. */
const vv_mesh *vvg_marks_region(VvgMarks *m);
/** Replaces the region (@p mesh may be NULL; a reference is taken). */
void vvg_marks_set_region(VvgMarks *m, vv_mesh *mesh);

G_END_DECLS
#endif
