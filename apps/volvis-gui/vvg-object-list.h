/*
 * VvObjectList: the World's objects (the paper's Figure 3, Manipulation):
 * one row per object with its visibility, its name (Enter renames) and its
 * type; the row selected is the document's selection. Every change is one
 * undo step of the document. UI thread only.
 */
#ifndef VV_OBJECT_LIST_H
#define VV_OBJECT_LIST_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VV_TYPE_OBJECT_LIST (vv_object_list_get_type())
G_DECLARE_FINAL_TYPE(VvObjectList, vv_object_list, VV, OBJECT_LIST, GtkBox)

/** The list for @p doc (a reference is held), with Open… and Delete buttons. */
GtkWidget *vv_object_list_new(VvDocument *doc);
/** Appends @p button to the row of buttons under the list. */
void vv_object_list_add_button(VvObjectList *list, GtkWidget *button);

G_END_DECLS
#endif
