/*
 * What the scene view draws over the rendered image (internal to
 * VvgSceneView): the cut planes as translucent outlines where they cross the
 * World's box (the one a drag moves highlighted, with its handle), the
 * selected light's handle, the measurement marks (points A and B with the
 * distance between them, the seed, the surface-tracked region), an
 * orientation marker (R/A/S or x/y/z axes, bottom left) and a scale bar in
 * world units (bottom right). Pure drawing with cairo, from values; UI
 * thread only.
 */
#ifndef VVG_SCENE_OVERLAY_H
#define VVG_SCENE_OVERLAY_H

#include <gtk/gtk.h>
#include <volvis/volvis.h>

#include "vvg-marks.h"

G_BEGIN_DECLS

/** What to draw and where the image lies in the widget. */
typedef struct VvgSceneOverlay {
    const vv_world *world;
    const vv_view *view;  /**< the camera of the image on screen */
    double x0, y0, scale; /**< image pixel (x, y) is at widget (x0 + scale x, y0 + scale y) */
    int width, height;    /**< the widget's size */
    int target;           /**< VvgNavTarget: what a drag moves */
    const vv_cut_plane *moving_plane; /**< the plane a cut-plane drag moves, or NULL */
    int light;                        /**< the light a light drag moves */
    VvgMarks *marks;
    vv_space space;    /**< anatomical frame of the selected volume */
    const char *units; /**< the selected volume's length unit (vvg_unit_label) */
} VvgSceneOverlay;

/** Draws everything of @p o with @p cr (widget coordinates). */
void vvg_scene_overlay_draw(cairo_t *cr, const VvgSceneOverlay *o);

/**
 * The polygon where plane (@p point, @p normal) crosses box @p b: up to 6
 * corners in order around it into @p out; returns their number (0 when the
 * plane misses the box).
 */
int vvg_scene_overlay_plane_polygon(vv_vec3 point, vv_vec3 normal, vv_box b, vv_vec3 out[6]);

/** A length of 1, 2 or 5 times a power of ten near @p target (> 0). */
double vvg_scene_overlay_nice_length(double target);

G_END_DECLS
#endif
