/*
 * VvChannelPanel: the channels and time steps of the selected volume object
 * (issue: several channels and time steps). For an object of several
 * channels (vv_object_set_channels): the blend rule (vv_channel_blend) and
 * one row per channel, its name with its visibility, its colour, its
 * contrast limits and gamma over its histogram (vv_tf_set_contrast, the
 * microscopy shorthand of its transfer function), and which channel the
 * Transfer function page edits (vv_document_set_edited_channel). For a file
 * with time steps: a time-step slider, a Play button (10 steps a second,
 * round and round) and the step shown (vv_document_set_time). Every edit is
 * an undo step of the document (a slider dragged or time played makes one).
 * UI thread only.
 */
#ifndef VV_CHANNEL_PANEL_H
#define VV_CHANNEL_PANEL_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VV_TYPE_CHANNEL_PANEL (vv_channel_panel_get_type())
G_DECLARE_FINAL_TYPE(VvChannelPanel, vv_channel_panel, VV, CHANNEL_PANEL, GtkBox)

/** The panel for the selected object of @p doc (a reference is held). */
GtkWidget *vv_channel_panel_new(VvDocument *doc);

G_END_DECLS
#endif
