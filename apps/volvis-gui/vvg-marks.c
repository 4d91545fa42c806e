/* VvMarks: the slice cursor, window and level, and measurement marks (vvg-marks.h). */
#include "vvg-marks.h"

#include <math.h>

struct _VvMarks {
    GObject parent;
    gboolean has_cursor, has_window;
    vv_vec3 cursor;
    double window, level;
    gboolean has_point[VV_MARK_COUNT];
    vv_vec3 point[VV_MARK_COUNT];
    vv_mesh *region;
    int cut_object, cut_plane;
};

G_DEFINE_TYPE(VvMarks, vv_marks, G_TYPE_OBJECT)

enum { SIGNAL_CHANGED, N_SIGNALS };
static guint signals[N_SIGNALS];

static void
vv_marks_finalize(GObject *o) {
    vv_mesh_free(VV_MARKS(o)->region);
    G_OBJECT_CLASS(vv_marks_parent_class)->finalize(o);
}

static void
vv_marks_class_init(VvMarksClass *klass) {
    G_OBJECT_CLASS(klass)->finalize = vv_marks_finalize;
    signals[SIGNAL_CHANGED] = g_signal_new("changed", G_TYPE_FROM_CLASS(klass), G_SIGNAL_RUN_LAST,
                                           0, NULL, NULL, NULL, G_TYPE_NONE, 0);
}

static void
vv_marks_init(VvMarks *m) {
    m->cut_object = m->cut_plane = -1;
}

VvMarks *
vv_marks_new(void) {
    return g_object_new(VV_TYPE_MARKS, NULL);
}

static void
changed(VvMarks *m) {
    g_signal_emit(m, signals[SIGNAL_CHANGED], 0);
}

gboolean
vv_marks_cursor(VvMarks *m, vv_vec3 *out) {
    if (m->has_cursor)
        *out = m->cursor;
    return m->has_cursor;
}

void
vv_marks_set_cursor(VvMarks *m, vv_vec3 p) {
    if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z))
        return;
    m->cursor = p;
    m->has_cursor = TRUE;
    changed(m);
}

void
vv_marks_reset(VvMarks *m) {
    m->has_cursor = m->has_window = FALSE;
    changed(m);
}

gboolean
vv_marks_window(VvMarks *m, double *window, double *level) {
    if (m->has_window) {
        *window = m->window;
        *level = m->level;
    }
    return m->has_window;
}

void
vv_marks_set_window(VvMarks *m, double window, double level) {
    if (!(window > 0) || !isfinite(window) || !isfinite(level))
        return;
    m->window = window;
    m->level = level;
    m->has_window = TRUE;
    changed(m);
}

gboolean
vv_marks_point(VvMarks *m, VvMark which, vv_vec3 *out) {
    if ((int)which < 0 || which >= VV_MARK_COUNT || !m->has_point[which])
        return FALSE;
    *out = m->point[which];
    return TRUE;
}

void
vv_marks_set_point(VvMarks *m, VvMark which, vv_vec3 p) {
    if ((int)which < 0 || which >= VV_MARK_COUNT)
        return;
    m->point[which] = p;
    m->has_point[which] = TRUE;
    changed(m);
}

void
vv_marks_clear_point(VvMarks *m, VvMark which) {
    if ((int)which < 0 || which >= VV_MARK_COUNT)
        return;
    m->has_point[which] = FALSE;
    changed(m);
}

const vv_mesh *
vv_marks_region(VvMarks *m) {
    return m->region;
}

void
vv_marks_set_region(VvMarks *m, vv_mesh *mesh) {
    if (mesh)
        vv_mesh_ref(mesh);
    vv_mesh_free(m->region);
    m->region = mesh;
    changed(m);
}

void
vv_marks_cut_plane(VvMarks *m, int *object, int *plane) {
    *object = m->cut_object;
    *plane = m->cut_plane;
}

void
vv_marks_set_cut_plane(VvMarks *m, int object, int plane) {
    if (m->cut_object == object && m->cut_plane == plane)
        return;
    m->cut_object = object;
    m->cut_plane = plane;
    changed(m);
}
