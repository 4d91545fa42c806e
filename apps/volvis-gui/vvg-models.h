/*
 * The GUI's models that need no display: the undo stack of World snapshots
 * and transfer-function editing in widget coordinates. Plain C over
 * libvolvis, unit-tested without GTK (tests/gui/test_models.c).
 *
 * Thread-safety: none; the GUI uses them from the UI thread only.
 */
#ifndef VVG_MODELS_H
#define VVG_MODELS_H

#include <volvis/volvis.h>

/* ---- undo stack ---------------------------------------------------------- */

/**
 * Undo and redo as whole-World snapshots (vv_world_clone: objects copied,
 * voxels shared), so undo restores the World exactly, whatever the edit was.
 * At most `limit` steps are kept; the oldest are dropped.
 */
typedef struct vvg_undo vvg_undo;

/** A stack keeping at most @p limit (>= 1) steps. Errors: VV_ERR_INVALID, VV_ERR_NOMEM. */
vv_status vvg_undo_new(vvg_undo **out, int limit);
/** Releases the stack and its snapshots. Accepts NULL. */
void vvg_undo_free(vvg_undo *u);
/**
 * Records the World as it is before an edit called @p label (copied; a
 * snapshot of @p before is taken) and clears the redo steps. Errors:
 * VV_ERR_NOMEM (the stack is unchanged).
 */
vv_status vvg_undo_push(vvg_undo *u, const vv_world *before, const char *label);
/** 1 when there is a step to undo (redo). */
int vvg_undo_can_undo(const vvg_undo *u);
int vvg_undo_can_redo(const vvg_undo *u);
/** Label of the step undo (redo) would revert (re-apply), or NULL. Owned by @p u. */
const char *vvg_undo_label(const vvg_undo *u, int redo);
/**
 * Undo: *@p world (owned by the caller) goes onto the redo steps and is
 * replaced by the snapshot before the last edit. Redo is the reverse.
 * Errors: VV_ERR_INVALID when there is nothing to undo (redo).
 */
vv_status vvg_undo_undo(vvg_undo *u, vv_world **world);
vv_status vvg_undo_redo(vvg_undo *u, vv_world **world);
/** Forgets every step; the state now is the clean one. */
void vvg_undo_clear(vvg_undo *u);
/**
 * Clean-state tracking (Qt's QUndoStack::setClean and isClean, GTK text
 * buffers' modified flag): marks the state now (the one opened or saved) as
 * clean. Undoing or redoing back to it makes vvg_undo_is_clean true again;
 * an edit pushed after undoing past it, or dropping its step off the
 * bottom of the stack, makes it unreachable (never clean until marked).
 */
void vvg_undo_mark_clean(vvg_undo *u);
/** 1 when the state now is the clean one. */
int vvg_undo_is_clean(const vvg_undo *u);
/** The state now changed without a step (an edit merged into the last one):
 *  the clean state is unreachable until marked again. */
void vvg_undo_mark_unclean(vvg_undo *u);
/** Where the clean state is (to put it back with vvg_undo_set_clean_index), -1 nowhere. */
int vvg_undo_clean_index(const vvg_undo *u);
void vvg_undo_set_clean_index(vvg_undo *u, int index);

/* ---- transfer-function editing ------------------------------------------ */

/**
 * How an editor maps a transfer function onto its area: data values
 * [vmin, vmax] along x over [0, width) pixels, opacity 0 at the bottom
 * (y = height) to 1 at the top (y = 0).
 */
typedef struct vvg_tf_axes {
    double vmin, vmax;
    double width, height;
} vvg_tf_axes;

double vvg_tf_x(const vvg_tf_axes *a, double value);
double vvg_tf_value(const vvg_tf_axes *a, double x);
double vvg_tf_y(const vvg_tf_axes *a, double opacity);
double vvg_tf_opacity(const vvg_tf_axes *a, double y);

/** Index of the opacity point within @p radius pixels of (x, y) (the nearest), or -1. */
int vvg_tf_hit(const vv_tf *tf, const vvg_tf_axes *a, double x, double y, double radius);
/**
 * Adds an opacity point at (x, y) (clamped into the area) and returns its
 * index, or -1 when the function is full.
 */
int vvg_tf_add_point(vv_tf *tf, const vvg_tf_axes *a, double x, double y);
/**
 * Moves opacity point @p i to (x, y), clamped into the area and between its
 * neighbours' values, so the points stay sorted and the index stays valid.
 */
void vvg_tf_move_point(vv_tf *tf, int i, const vvg_tf_axes *a, double x, double y);
/** Deletes opacity point @p i (ignored when out of range). */
void vvg_tf_delete_point(vv_tf *tf, int i);
/** Index of the colour point whose value is within @p radius pixels of x, or -1. */
int vvg_tf_hit_color(const vv_tf *tf, const vvg_tf_axes *a, double x, double radius);
/** Adds a colour point at x with @p color; returns its index or -1. */
int vvg_tf_add_color(vv_tf *tf, const vvg_tf_axes *a, double x, vv_vec3 color);
/** Moves colour point @p i to x, between its neighbours. */
void vvg_tf_move_color(vv_tf *tf, int i, const vvg_tf_axes *a, double x);
/** Deletes colour point @p i. */
void vvg_tf_delete_color(vv_tf *tf, int i);

/**
 * The renderer the GUI picks on its own for @p w, given the World's default
 * @p dflt (vv_world_renderer): "gpu" where the default is "raycast", the
 * gpu renderer draws the World (one visible volume object of at most four
 * channels, without solid textures or label colours) and a real GPU is
 * there, never a CPU device such as Mesa's lavapipe; else @p dflt. The
 * environment's VOLVIS_GUI_GPU changes the rule: 0 never picks it, `any`
 * also picks a CPU device (for the tests). Returns a static string or
 * @p dflt.
 */
const char *vvg_gui_renderer(const vv_world *w, const char *dflt);

#endif
