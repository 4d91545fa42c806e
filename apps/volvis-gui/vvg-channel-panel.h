/*
 * VvgChannelPanel: the channels and time steps of the selected volume
 * object. For an object of several
 * channels (vv_object_set_channels): the blend rule (vv_channel_blend) and
 * one row per channel, its name with its visibility, its colour, its
 * contrast limits and gamma over its histogram (vv_tf_set_contrast, the
 * microscopy shorthand of its transfer function), and which channel the
 * Transfer function page edits (vvg_document_set_edited_channel). For a file
 * with time steps: a time-step slider, a Play button (10 steps a second,
 * round and round) and the step shown (vvg_document_set_time). Every edit is
 * an undo step of the document (a slider dragged or time played makes one).
 * UI thread only.
 */
#ifndef VVG_CHANNEL_PANEL_H
#define VVG_CHANNEL_PANEL_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_CHANNEL_PANEL (vvg_channel_panel_get_type())
G_DECLARE_FINAL_TYPE(VvgChannelPanel, vvg_channel_panel, VVG, CHANNEL_PANEL, GtkBox)

/** The panel for the selected object of @p doc (a reference is held). */
GtkWidget *vvg_channel_panel_new(VvgDocument *doc);

G_END_DECLS
#endif
