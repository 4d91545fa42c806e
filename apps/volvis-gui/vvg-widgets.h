/*
 * Small form-building helpers shared by the GUI's pages: titled sections of
 * label/value rows, spin buttons, and the error dialog. UI thread only.
 */
#ifndef VVG_WIDGETS_H
#define VVG_WIDGETS_H

#include <gtk/gtk.h>
#include <volvis/volvis.h>

G_BEGIN_DECLS

/** Appends a bold @p title and a new grid to the vertical @p box; returns the grid. */
GtkWidget *vvg_section(GtkWidget *box, const char *title);
/** vvg_section folded: a closed expander titled @p title (its accessible name) holding the
 *  grid, for what few people change (the first screen holds the common). */
GtkWidget *vvg_section_folded(GtkWidget *box, const char *title);
/** Rows used in @p grid so far. */
int vvg_grid_rows(GtkWidget *grid);
/**
 * Appends a row "@p label  @p w" to @p grid (w expands); returns @p w. The
 * label names @p w for assistive technologies (GTK's labelled-by relation),
 * so a screen reader and the AT-SPI tests find it by its visible label.
 */
GtkWidget *vvg_row(GtkWidget *grid, const char *label, GtkWidget *w);
/** Names @p w for assistive technologies by the label widget @p label (labelled-by). */
void vvg_label_for(GtkWidget *w, GtkWidget *label);
/** Sets the accessible name of @p w to @p name (for widgets without a visible label). */
void vvg_name(GtkWidget *w, const char *name);
/** A spin button over [lo, hi] by @p step with @p digits decimals, set to @p value. */
GtkWidget *vvg_spin(double lo, double hi, double step, int digits, double value);
/** vvg_spin at 0, or at the bound nearest 0 (GTK would start at the lower bound). */
GtkWidget *vvg_spin0(double lo, double hi, double step, int digits);
/** The value of spin button @p s. */
double vvg_spin_value(GtkWidget *s);
/** Sets spin button @p s to @p v. */
void vvg_set_spin(GtkWidget *s, double v);
/** An opaque GdkRGBA of colour @p c (components in [0, 1]). */
GdkRGBA vvg_rgba(vv_vec3 c);
/** The RGB of @p c. */
vv_vec3 vvg_vec3(const GdkRGBA *c);
/** A button labelled @p label that activates the action @p action ("win.open"). */
GtkWidget *vvg_action_button(const char *label, const char *action);
/**
 * The name of a volume's length unit for people: "mm" and the like when
 * the file gives one; "voxel units" when it gives neither unit nor spacing
 * (all spacings 1); "units" when it gives spacing without a unit. Never
 * "unknown". Static storage.
 */
const char *vvg_unit_label(const vv_volume *v);
/** Makes @p box (a GtkBox subclass being initialised) vertical with a spacing of 4. */
void vvg_vbox_init(GtkWidget *box);
/** A vertical box with the side bar's margins, for a page's content. */
GtkWidget *vvg_page_box(void);
/**
 * @p w (a spin button, slider or drop-down) takes the mouse wheel only when
 * it has the keyboard focus; otherwise the wheel scrolls the side bar it is
 * in, as a user scrolling down a page expects (the wheel over a spin button
 * used to change "position y" and shrink "scale" on the way). vvg_spin and
 * vvg_row apply it to what they make.
 */
void vvg_wheel_when_focused(GtkWidget *w);
/** vvg_wheel_when_focused for every spin button, slider and drop-down under @p root. */
void vvg_wheel_when_focused_all(GtkWidget *root);
/** Escape and Ctrl+W close @p window (as its Close button does). */
void vvg_close_on_escape(GtkWindow *window);
/** @p child in a vertically scrolling window that expands (a side-bar page). */
GtkWidget *vvg_scrolled(GtkWidget *child);
/**
 * A modal error dialog titled "VolVis: error" over the window of @p any
 * (may be NULL): @p what in bold, the library's @p message under it. The
 * message also goes to stderr, for scripts and tests.
 */
void vvg_show_error(GtkWidget *any, const char *what, const char *message);

G_END_DECLS
#endif
