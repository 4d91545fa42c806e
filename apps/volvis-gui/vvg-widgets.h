/*
 * Small form-building helpers shared by the GUI's pages: titled sections of
 * label/value rows, spin buttons, and the error dialog. UI thread only.
 */
#ifndef VVG_WIDGETS_H
#define VVG_WIDGETS_H

#include <gtk/gtk.h>

G_BEGIN_DECLS

/** Appends a bold @p title and a new grid to the vertical @p box; returns the grid. */
GtkWidget *vvg_section(GtkWidget *box, const char *title);
/** Rows used in @p grid so far. */
int vvg_grid_rows(GtkWidget *grid);
/** Appends a row "@p label  @p w" to @p grid (w expands); returns @p w. */
GtkWidget *vvg_row(GtkWidget *grid, const char *label, GtkWidget *w);
/** A spin button over [lo, hi] by @p step with @p digits decimals, set to @p value. */
GtkWidget *vvg_spin(double lo, double hi, double step, int digits, double value);
/**
 * A modal error dialog titled "VolVis: error" over the window of @p any
 * (may be NULL): @p what in bold, the library's @p message under it. The
 * message also goes to stderr, for scripts and tests.
 */
void vvg_show_error(GtkWidget *any, const char *what, const char *message);

G_END_DECLS
#endif
