/*
 * VvgObjectList: the World's objects (the paper's Figure 3, Manipulation):
 * one row per object with its visibility, its name (Enter renames) and its
 * type; the row selected is the document's selection. Every change is one
 * undo step of the document. UI thread only.
 */
#ifndef VVG_OBJECT_LIST_H
#define VVG_OBJECT_LIST_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_OBJECT_LIST (vvg_object_list_get_type())
G_DECLARE_FINAL_TYPE(VvgObjectList, vvg_object_list, VVG, OBJECT_LIST, GtkBox)

/** The list for @p doc (a reference is held), with Open… and Delete buttons. */
GtkWidget *vvg_object_list_new(VvgDocument *doc);
/** Appends @p button to the row of buttons under the list. */
void vvg_object_list_add_button(VvgObjectList *list, GtkWidget *button);

G_END_DECLS
#endif
