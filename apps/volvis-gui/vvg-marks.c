/* VvgMarks: the slice cursor, window and level, and measurement marks (vvg-marks.h). */
#include "vvg-marks.h"

#include <math.h>

struct _VvgMarks {
    GObject parent;
    gboolean has_cursor, has_window;
    vv_vec3 cursor;
    double window, level;
    /* the automatic window and level of auto_volume as it was at
     * auto_modified (with its range: a new volume at a freed one's address
     * differs there) */
    const vv_volume *auto_volume;
    uint64_t auto_modified;
    double auto_range[2], auto_wl[2];
    gboolean has_point[VVG_MARK_COUNT];
    vv_vec3 point[VVG_MARK_COUNT];
    vv_mesh *region;
    int cut_object, cut_plane;
};

G_DEFINE_TYPE(VvgMarks, vvg_marks, G_TYPE_OBJECT)

enum { SIGNAL_CHANGED, N_SIGNALS };
static guint signals[N_SIGNALS];

static void
vvg_marks_finalize(GObject *o) {
    vv_mesh_free(VVG_MARKS(o)->region);
    G_OBJECT_CLASS(vvg_marks_parent_class)->finalize(o);
}

static void
vvg_marks_class_init(VvgMarksClass *klass) {
    G_OBJECT_CLASS(klass)->finalize = vvg_marks_finalize;
    signals[SIGNAL_CHANGED] = g_signal_new("changed", G_TYPE_FROM_CLASS(klass), G_SIGNAL_RUN_LAST,
                                           0, NULL, NULL, NULL, G_TYPE_NONE, 0);
}

static void
vvg_marks_init(VvgMarks *m) {
    m->cut_object = m->cut_plane = -1;
}

VvgMarks *
vvg_marks_new(void) {
    return g_object_new(VVG_TYPE_MARKS, NULL);
}

static void
changed(VvgMarks *m) {
    g_signal_emit(m, signals[SIGNAL_CHANGED], 0);
}

gboolean
vvg_marks_cursor(VvgMarks *m, vv_vec3 *out) {
    if (m->has_cursor)
        *out = m->cursor;
    return m->has_cursor;
}

void
vvg_marks_set_cursor(VvgMarks *m, vv_vec3 p) {
    if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z))
        return;
    m->cursor = p;
    m->has_cursor = TRUE;
    changed(m);
}

void
vvg_marks_reset(VvgMarks *m) {
    m->has_cursor = m->has_window = FALSE;
    changed(m);
}

gboolean
vvg_marks_window(VvgMarks *m, double *window, double *level) {
    if (m->has_window) {
        *window = m->window;
        *level = m->level;
    }
    return m->has_window;
}

void
vvg_marks_window_for(VvgMarks *m, const vv_volume *v, double *window, double *level) {
    if (vvg_marks_window(m, window, level))
        return;
    if (m->auto_volume != v || m->auto_modified != v->modified || m->auto_range[0] != v->range[0] ||
        m->auto_range[1] != v->range[1]) {
        vv_slice_auto_window(v, &m->auto_wl[0], &m->auto_wl[1]);
        m->auto_volume = v;
        m->auto_modified = v->modified;
        m->auto_range[0] = v->range[0];
        m->auto_range[1] = v->range[1];
    }
    *window = m->auto_wl[0];
    *level = m->auto_wl[1];
}

void
vvg_marks_set_window(VvgMarks *m, double window, double level) {
    if (!(window > 0) || !isfinite(window) || !isfinite(level))
        return;
    m->window = window;
    m->level = level;
    m->has_window = TRUE;
    changed(m);
}

gboolean
vvg_marks_point(VvgMarks *m, VvgMark which, vv_vec3 *out) {
    if ((int)which < 0 || which >= VVG_MARK_COUNT || !m->has_point[which])
        return FALSE;
    *out = m->point[which];
    return TRUE;
}

void
vvg_marks_set_point(VvgMarks *m, VvgMark which, vv_vec3 p) {
    if ((int)which < 0 || which >= VVG_MARK_COUNT)
        return;
    m->point[which] = p;
    m->has_point[which] = TRUE;
    changed(m);
}

void
vvg_marks_clear_point(VvgMarks *m, VvgMark which) {
    if ((int)which < 0 || which >= VVG_MARK_COUNT)
        return;
    m->has_point[which] = FALSE;
    changed(m);
}

const vv_mesh *
vvg_marks_region(VvgMarks *m) {
    return m->region;
}

void
vvg_marks_set_region(VvgMarks *m, vv_mesh *mesh) {
    if (mesh)
        vv_mesh_ref(mesh);
    vv_mesh_free(m->region);
    m->region = mesh;
    changed(m);
}

void
vvg_marks_cut_plane(VvgMarks *m, int *object, int *plane) {
    *object = m->cut_object;
    *plane = m->cut_plane;
}

void
vvg_marks_set_cut_plane(VvgMarks *m, int object, int plane) {
    if (m->cut_object == object && m->cut_plane == plane)
        return;
    m->cut_object = object;
    m->cut_plane = plane;
    changed(m);
}
