/*
 * VolVis raster: the geometry renderer's "library of basic graphics
 * functions" of the VolVis paper (Avila et al., IEEE Visualization '94,
 * section 5 "Rendering": geometric models are drawn through a small portable
 * graphics library so that the system runs with or without graphics
 * hardware). A software rasterizer with the interface of an immediate-mode
 * graphics API: a context owns a depth buffer and a visibility buffer; the
 * caller sets the camera, lights, material and state, draws indexed triangle
 * meshes, and finally resolves the frame into a vv_image (colour, coverage,
 * depth). A GUI can put OpenGL behind the same calls without changing
 * callers: every call maps onto one OpenGL concept (viewport, view and
 * projection matrices, lights, material, glCullFace, glPolygonMode, user clip
 * planes, glDrawElements, glReadPixels).
 *
 * Method: vertices are transformed in parallel; triangles are clipped in
 * homogeneous clip space against the near and far planes, a guard band
 * around the viewport and the cut planes (Sutherland-Hodgman), culled by
 * their screen winding, snapped to 1/256 pixel and binned into 32 x 32
 * pixel tiles; tiles are rasterized in parallel with exact integer edge
 * functions and the top-left fill rule (watertight: a pixel centre on an
 * edge shared by two triangles is drawn once), depth-tested against a
 * screen-affine depth key (1/w, or -z for affine projections) and stored as
 * (triangle, perspective-correct barycentric coordinates). Shading is
 * deferred to vv_raster_finish, once per visible pixel: flat (one colour
 * per triangle, from its face normal at its centroid), Gouraud (colours
 * lit at the vertices, interpolated perspective-correctly) or Phong
 * (normals and positions interpolated, lit per pixel), with the lighting
 * model of the ray caster (docs/rendering.md): two-sided Phong with the
 * reflection vector, (ka*ambient + kd*sum|N.L|*light) * colour +
 * ks*sum (R.V)^shininess * light.
 *
 * Determinism: triangles are processed in their draw order (ties in depth go
 * to the earlier triangle) whatever the number of threads, so images are
 * bit-identical for every thread count.
 *
 * Output conventions are those of vv_image (image.h): row 0 at the top,
 * colour composited over the background, alpha 1 where something was drawn,
 * depth the world distance from the eye along the primary ray (perspective:
 * |p - eye|; orthographic: (p - eye) . forward), INFINITY elsewhere, so
 * images combine with the ray caster's by depth.
 *
 * Ownership: vv_raster_new allocates a context, vv_raster_free releases it.
 * Meshes drawn are borrowed until vv_raster_finish or vv_raster_begin.
 * Thread-safety: one context must be used by one thread at a time (it
 * parallelises internally with OpenMP); distinct contexts are independent.
 */
#ifndef VOLVIS_RASTER_H
#define VOLVIS_RASTER_H

#include "core.h"
#include "image.h"
#include "math.h"
#include "mesh.h"
#include "model.h"

#ifdef __cplusplus
extern "C" {
#endif

/** How triangles are shaded. */
typedef enum vv_raster_shading {
    VV_RASTER_FLAT = 0,    /**< one colour per triangle (face normal, lit at its centroid) */
    VV_RASTER_GOURAUD = 1, /**< lit at the vertices, colours interpolated */
    VV_RASTER_PHONG = 2    /**< normals interpolated, lit per pixel (default) */
} vv_raster_shading;

/** Which triangles are discarded by their winding on screen. */
typedef enum vv_raster_cull {
    VV_RASTER_CULL_NONE = 0, /**< draw both sides (default) */
    VV_RASTER_CULL_BACK = 1, /**< discard triangles seen from behind */
    VV_RASTER_CULL_FRONT = 2 /**< discard triangles seen from the front */
} vv_raster_cull;

/** Opaque rasterizer context. */
typedef struct vv_raster vv_raster;

/**
 * A context for @p width x @p height pixels (1..VV_IMAGE_MAX_SIDE) with an
 * identity camera, no lights, ambient (1,1,1), background black, the
 * default material of vv_object_new_volume, Phong shading, no culling, no
 * wireframe, no cut planes, no capping, threads from vv_threads_get(). Errors:
 * VV_ERR_INVALID (size), VV_ERR_NOMEM.
 */
vv_status vv_raster_new(vv_raster **out, int width, int height);

/** Releases a context and its buffers. Accepts NULL. */
void vv_raster_free(vv_raster *r);

/** Threads of the parallel stages; n <= 0: vv_threads_get() at each draw. */
void vv_raster_set_threads(vv_raster *r, int n);

/**
 * Starts a frame: clears the depth and visibility buffers and forgets the
 * draws of the previous frame. @p background is the colour vv_raster_finish
 * writes where nothing was drawn.
 */
void vv_raster_begin(vv_raster *r, vv_vec3 background);

/**
 * Sets the camera: @p view maps world to camera coordinates (a rigid
 * motion; the camera looks down -z, +y up, like vv_mat4_look_at) and
 * @p projection maps camera to clip coordinates: either perspective with
 * bottom row (0, 0, -1, 0) (vv_mat4_perspective, glFrustum) or affine with
 * bottom row (0, 0, 0, 1) (vv_mat4_orthographic, glOrtho). Clip space is
 * OpenGL's: x, y, z in [-w, w]; the near and far planes clip. Applies to
 * later draws. Errors: VV_ERR_INVALID (another bottom row, a singular view).
 */
vv_status vv_raster_set_camera(vv_raster *r, vv_mat4 view, vv_mat4 projection);

/**
 * Sets the camera of a vv_view exactly as vv_view_ray shoots its rays: the
 * pixel centre (px + 0.5, py + 0.5) of the context's image sees the same
 * world points (basis, field of view, aspect from view->width / height,
 * ortho_height). @p znear > 0 and @p zfar > znear are distances along the
 * view direction (perspective; zfar may be INFINITY); orthographic views
 * clip at @p znear >= 0 and a finite @p zfar. Errors: VV_ERR_INVALID.
 */
vv_status vv_raster_set_view(vv_raster *r, const vv_view *view, double znear, double zfar);

/**
 * Sets the lights (copied; at most VV_MAX_LIGHTS) and the ambient light
 * colour for later draws. A headlight shines along the camera's view
 * direction at the time of the draw. Errors: VV_ERR_LIMIT (n too large),
 * VV_ERR_INVALID (n < 0, NULL with n > 0).
 */
vv_status vv_raster_set_lights(vv_raster *r, const vv_light *lights, int n, vv_vec3 ambient);

/**
 * Sets the material of later draws (copied: ambient, diffuse, specular,
 * shininess, color are used). @p lit 0 draws the material colour unlit
 * (emission only, like an object with shading off in the ray caster).
 */
void vv_raster_set_material(vv_raster *r, const vv_material *m, int lit);

/** Sets the shading of later draws. */
void vv_raster_set_shading(vv_raster *r, vv_raster_shading s);

/**
 * Sets the culling of later draws. Front faces are counter-clockwise seen
 * from outside in object coordinates (mesh.h); a model matrix with a
 * negative determinant is accounted for.
 */
void vv_raster_set_cull(vv_raster *r, vv_raster_cull c);

/**
 * 1: later draws draw only the edges of their triangles, one pixel wide
 * (edges created by clipping are not drawn), depth-tested against each
 * other and everything else; 0: filled triangles.
 */
void vv_raster_set_wireframe(vv_raster *r, int on);

/**
 * Sets the cut planes of later draws (copied, world coordinates; each keeps
 * n . (x - point) >= 0, like the ray caster's global and local cut planes).
 * Errors: VV_ERR_LIMIT (more than 2 * VV_MAX_CUT_PLANES), VV_ERR_INVALID.
 */
vv_status vv_raster_set_cut_planes(vv_raster *r, const vv_cut_plane *planes, int n);

/**
 * Solid cut faces for later draws (the ray caster shows a cut volume as
 * solid; a cut surface is open). With @p on, a pixel where a triangle is
 * seen from behind, i.e. the view looks into the inside of a closed,
 * outward-oriented surface through an opening, shows instead the face
 * where the pixel's ray entered the solid: the last crossing into the
 * half-spaces of the current cut planes and of @p bounds (0..6 extra
 * half-spaces that also bound the solid, e.g. the faces of the volume an
 * isosurface was extracted from, where Marching Cubes leaves the surface
 * open), lit with that plane's normal in the current material. Only for
 * surfaces that are closed up to those planes and whose triangles are
 * counter-clockwise seen from outside. Errors: VV_ERR_INVALID.
 */
vv_status vv_raster_set_capping(vv_raster *r, int on, const vv_cut_plane *bounds, int n_bounds);

/**
 * Draws the triangles of @p mesh placed by @p model (object to world) with
 * the current camera, lights, material and state. Per-vertex normals are
 * taken from the mesh (transformed by the inverse transpose of @p model);
 * a mesh without normals gets area-weighted vertex normals. Triangles with
 * a NaN or infinite vertex are skipped. The mesh is
 * borrowed: it must stay alive and unchanged until vv_raster_finish or the
 * next vv_raster_begin. Errors: VV_ERR_INVALID (NULL mesh, a triangle index
 * out of range, a singular model matrix), VV_ERR_LIMIT (more than 2^31
 * triangles in a frame), VV_ERR_NOMEM.
 */
vv_status vv_raster_draw_mesh(vv_raster *r, const vv_mesh *mesh, vv_mat4 model);

/**
 * Shades the visible pixels and writes the frame into @p out (which must
 * be the context's size). @p merge 0 writes every pixel (background colour,
 * alpha 0 and depth INFINITY where nothing was drawn); @p merge 1 writes
 * only the pixels whose drawn depth is smaller than out->depth (combining
 * opaque geometry with another renderer's image by depth). Errors:
 * VV_ERR_INVALID (size mismatch).
 */
vv_status vv_raster_finish(vv_raster *r, vv_image *out, int merge);

/** Triangles rasterized (after clipping and culling, before the depth
 * test) since vv_raster_begin; for tests and benchmarks. */
size_t vv_raster_triangles_drawn(const vv_raster *r);

#ifdef __cplusplus
}
#endif
#endif
