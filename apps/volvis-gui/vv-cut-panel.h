/*
 * VvCutPanel: cut planes (VolVis paper, section 4: global cut planes and
 * per-object ones): a plane typed as a point and a normal, added to the
 * World or to the selected object; Remove all. A plane is then moved with
 * its handle in the scene view ("drag moves: cut plane"). Every edit is one
 * undo step. Installs the actions "add-cut-plane" and "clear-cut-planes" in
 * the given action map. UI thread only.
 */
#ifndef VV_CUT_PANEL_H
#define VV_CUT_PANEL_H

#include "vv-document.h"

G_BEGIN_DECLS

#define VV_TYPE_CUT_PANEL (vv_cut_panel_get_type())
G_DECLARE_FINAL_TYPE(VvCutPanel, vv_cut_panel, VV, CUT_PANEL, GtkBox)

/** The panel for @p doc (a reference is held); actions go into @p actions (borrowed). */
GtkWidget *vv_cut_panel_new(VvDocument *doc, GActionMap *actions);

G_END_DECLS
#endif
