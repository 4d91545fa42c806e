/*
 * VvgPresetGallery: the transfer-function presets of the library
 * (vv_tf_preset_names) as a gallery of buttons, each with a thumbnail
 * rendered from the selected volume with that preset (the ray caster at
 * 80 x 80 pixels and quality 0, seen as the 3-D view sees it, on a worker
 * thread; drawn again when another volume is selected or the volume
 * changes), its name and its description as a tooltip. A click applies the
 * preset (one undo step). The preset the object's transfer function equals
 * is shown as active (highlighted, and named in the line above); after an
 * edit none is. UI thread only.
 */
#ifndef VVG_PRESET_GALLERY_H
#define VVG_PRESET_GALLERY_H

#include "vvg-document.h"

G_BEGIN_DECLS

#define VVG_TYPE_PRESET_GALLERY (vvg_preset_gallery_get_type())
G_DECLARE_FINAL_TYPE(VvgPresetGallery, vvg_preset_gallery, VVG, PRESET_GALLERY, GtkBox)

/** The gallery for the selected object of @p doc (a reference is held). */
GtkWidget *vvg_preset_gallery_new(VvgDocument *doc);
/** The active preset's name, or NULL when the function is no preset's. */
const char *vvg_preset_gallery_active(VvgPresetGallery *gallery);
/** How many thumbnails have been rendered for the current volume. */
int vvg_preset_gallery_thumbnails(VvgPresetGallery *gallery);

G_END_DECLS
#endif
