/*
 * The `raster` renderer (called `surface` before; the registry still takes
 * that name): the geometry-based rendering method of the VolVis paper
 * (section 5), drawn through the software rasterizer of raster.h.
 *
 * Volume objects are shown as their isosurface, extracted with Marching
 * Cubes (vv_isosurface_extract) and cached until the isovalue or the
 * volume's `modified` counter changes. Which isovalue: the object's
 * isovalue in iso mode; its threshold under threshold segmentation; else
 * (transfer-function modes) the lowest data value at which the opacity
 * transfer function reaches half of its maximum over the volume's range,
 * in the transfer function's colour there. Geometric objects (sphere, box,
 * cylinder, polygon, plane, mesh) are tessellated each frame (a plane as a
 * large finite square around the point nearest the view target) and drawn
 * with their object transform and material. Global and local cut planes
 * clip the triangles. docs/rendering.md describes the options.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/classify.h"
#include "render/registry.h"
#include "volvis/raster.h"
#include "volvis/render.h"
#include "volvis/surface.h"
#include "volvis/sys/geometry.h"

#define SF_MAX_CACHE 64

/* One extracted isosurface. */
typedef struct sf_iso {
    vv_volume *vol; /* reference held */
    uint64_t modified;
    double iso;
    vv_mesh *mesh;
    int closed; /* no inside voxel on the volume's faces: the surface is closed */
    uint64_t last_frame;
} sf_iso;

/* Topology of a geometric mesh object, remembered by identity. */
typedef struct sf_topo {
    const vv_mesh *mesh;
    size_t nv, nt;
    int closed;
    int positive; /* signed volume >= 0 */
    uint64_t last_frame;
} sf_topo;

typedef enum sf_cull { SF_CULL_AUTO = 0, SF_CULL_BACK = 1, SF_CULL_NONE = 2 } sf_cull;

typedef struct sf_state {
    vv_raster *ras;
    int ras_width, ras_height; /* the context's size */
    /* the options (sf_options) */
    int shading; /* vv_raster_shading */
    int wireframe;
    int cull; /* sf_cull */
    int segments;
    int caps;
    sf_iso cache[SF_MAX_CACHE];
    int n_cache;
    sf_topo topo[SF_MAX_CACHE];
    int n_topo;
    uint64_t frame;
} sf_state;

/* ---------------------------------------------------------------------- */
/* Isosurfaces of volume objects                                            */

static void
iso_release(sf_iso *c) {
    vv_volume_free(c->vol);
    vv_mesh_free(c->mesh);
    memset(c, 0, sizeof *c);
}

/* 1 when no voxel on the volume's six faces is inside (>= iso): Marching
 * Cubes then gives a closed surface. */
static int
iso_closed(const vv_volume *v, double iso) {
    const int nx = v->dims[0], ny = v->dims[1], nz = v->dims[2];
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++) {
            const int interior = k > 0 && k < nz - 1 && j > 0 && j < ny - 1;
            for (int i = 0; i < nx; i += interior && nx > 1 ? nx - 1 : 1)
                if (vv_volume_get(v, i, j, k) >= iso)
                    return 0;
        }
    return 1;
}

static vv_status
iso_get(sf_state *st, vv_volume *vol, double iso, int threads, sf_iso **out) {
    for (int i = 0; i < st->n_cache; i++) {
        sf_iso *c = &st->cache[i];
        if (c->vol == vol && c->iso == iso && c->modified == vol->modified) {
            c->last_frame = st->frame;
            *out = c;
            return VV_OK;
        }
    }
    int slot = st->n_cache;
    if (slot == SF_MAX_CACHE) {
        slot = 0;
        for (int i = 1; i < st->n_cache; i++)
            if (st->cache[i].last_frame < st->cache[slot].last_frame)
                slot = i;
        iso_release(&st->cache[slot]);
    } else {
        st->n_cache++;
    }
    sf_iso *c = &st->cache[slot];
    memset(c, 0, sizeof *c);
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    vv_status s = vv_isosurface_extract(&c->mesh, vol, iso, &o);
    if (s != VV_OK) {
        st->cache[slot] = st->cache[--st->n_cache];
        return s;
    }
    c->vol = vv_volume_ref(vol);
    c->modified = vol->modified;
    c->iso = iso;
    c->closed = iso_closed(vol, iso);
    c->last_frame = st->frame;
    *out = c;
    return VV_OK;
}

/* The faces of a volume object's grid box [0, n - 1] as world half-spaces
 * keeping the inside (axes of one voxel are left out). */
static int
volume_bounds(const vv_object *obj, vv_cut_plane out[6]) {
    const vv_mat4 M = vv_object_index_to_world(obj);
    int ok = 0;
    const vv_mat4 NT = vv_mat4_transpose(vv_mat4_inverse(M, &ok));
    if (!ok)
        return 0;
    int n = 0;
    for (int a = 0; a < 3; a++) {
        const int hi = obj->volume->dims[a] - 1;
        if (hi < 1)
            continue;
        vv_vec3 e = vv_vec3_make(a == 0, a == 1, a == 2);
        vv_vec3 nrm = vv_vec3_normalize(vv_mat4_mul_dir(NT, e));
        vv_vec3 lo = vv_vec3_make(0, 0, 0), up = vv_vec3_scale(e, hi);
        out[n].point = vv_mat4_mul_point(M, lo);
        out[n++].normal = nrm;
        out[n].point = vv_mat4_mul_point(M, up);
        out[n++].normal = vv_vec3_scale(nrm, -1);
    }
    return n;
}

/* Topology of a mesh object's mesh, computed once per mesh. */
static vv_status
mesh_topo(sf_state *st, const vv_mesh *m, sf_topo **out) {
    for (int i = 0; i < st->n_topo; i++) {
        sf_topo *t = &st->topo[i];
        if (t->mesh == m && t->nv == m->n_vertices && t->nt == m->n_triangles) {
            t->last_frame = st->frame;
            *out = t;
            return VV_OK;
        }
    }
    int slot = st->n_topo;
    if (slot == SF_MAX_CACHE) {
        slot = 0;
        for (int i = 1; i < st->n_topo; i++)
            if (st->topo[i].last_frame < st->topo[slot].last_frame)
                slot = i;
    } else {
        st->n_topo++;
    }
    vv_mesh_topology tp;
    vv_status s = vv_mesh_topology_compute(m, &tp);
    if (s != VV_OK) {
        st->topo[slot] = st->topo[--st->n_topo];
        return s;
    }
    sf_topo *t = &st->topo[slot];
    t->mesh = m;
    t->nv = m->n_vertices;
    t->nt = m->n_triangles;
    t->closed = tp.closed && tp.oriented;
    t->positive = vv_mesh_signed_volume(m) >= 0;
    t->last_frame = st->frame;
    *out = t;
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* The renderer                                                             */

static void
sf_release(void *state) {
    sf_state *st = state;
    for (int i = 0; i < st->n_cache; i++)
        iso_release(&st->cache[i]);
    vv_raster_free(st->ras);
}

/* The geometric object's triangles in object coordinates (a plane: in world
 * coordinates, *world set), from its geometry-type record, and whether they
 * enclose a volume. */
static vv_status
tessellate(const sf_state *st, const vv_object *obj, const vv_view *view, double scene,
           vv_mesh **out, int *closed, int *world) {
    const vv_geom_type *gt;
    *closed = 0;
    *world = 0;
    vv_status s = vv_geom_object_type(obj, &gt);
    if (s != VV_OK)
        return s;
    vv_geom_tess opt = {.segments = st->segments};
    vv_geometry wg;
    const vv_geometry *g = &obj->geometry;
    if (obj->type == VV_OBJECT_PLANE) {
        /* in world coordinates, centred on the point of the plane nearest the
         * view target */
        vv_mat4 M = vv_object_matrix(obj);
        int ok = 0;
        vv_mat4 inv = vv_mat4_inverse(M, &ok);
        if (!ok)
            return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
        memset(&wg, 0, sizeof wg);
        wg.point = vv_mat4_mul_point(M, g->point);
        wg.normal = vv_vec3_normalize(vv_mat4_mul_dir(vv_mat4_transpose(inv), g->normal));
        opt.center = view->at;
        opt.half = 1000 * scene;
        g = &wg;
        *world = 1;
    }
    s = gt->tessellate(g, &opt, out);
    if (s != VV_OK)
        return vv_error_prefix(s, "object '%s'", obj->name);
    *closed = gt->solid(g);
    return VV_OK;
}

/* Colour bands of a grid surface coloured by its field. */
#define SF_BANDS 32

/* A grid object's surface: the Marching Tetrahedra isosurface of its field
 * (src/surface/marching_tets.c) at the object's surface value, or, for a
 * grid of surface cells only (blow.vtk), those cells displaced by the
 * "displacement" field of its time step and coloured by its field
 * (*banded 1). *out NULL with VV_ERR_INVALID: nothing to show. */
static vv_status
grid_surface(const vv_object *obj, vv_mesh **out, int *banded, vv_vec3 *color) {
    *out = NULL;
    *banded = 0;
    const vv_grid *g = obj->grid;
    const int f = vv_object_grid_field(obj);
    if (f < 0)
        return VV_ERR_INVALID;
    size_t n3 = 0, ns = 0;
    vv_grid_count_cells(g, &n3, &ns);
    if (n3 == 0) {
        const int d = vv_grid_find_field(g, "displacement", obj->time);
        const int disp =
            d >= 0 && g->fields[d].n_components == 3 && !g->fields[d].cell_data ? d : -1;
        *banded = 1;
        return vv_grid_surface_mesh(g, f, disp, out);
    }
    double iso;
    if (!vv_object_surface_value(obj, &iso, color))
        return vv_error_set(VV_ERR_INVALID, "transparent");
    return vv_grid_isosurface(g, f, g->fields[f].n_components > 1 ? obj->component : -1, iso, out);
}

/* Meshes drawn for a frame and kept until vv_raster_finish (it reads them). */
typedef struct sf_keep {
    vv_mesh **m;
    int n, cap;
} sf_keep;

static vv_status
keep_push(sf_keep *k, vv_mesh *m) {
    if (k->n == k->cap) {
        int cap = k->cap ? 2 * k->cap : 16;
        vv_mesh **nm = realloc(k->m, (size_t)cap * sizeof *nm);
        if (!nm) {
            vv_mesh_free(m);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        k->m = nm;
        k->cap = cap;
    }
    k->m[k->n++] = m;
    return VV_OK;
}

typedef struct tri_label {
    uint32_t label, tri;
} tri_label;

static int
cmp_tri_label(const void *a, const void *b) {
    const tri_label *x = a, *y = b;
    if (x->label != y->label)
        return x->label < y->label ? -1 : 1;
    return (x->tri > y->tri) - (x->tri < y->tri);
}

/* Draws the boundary surface @p mesh of label volume @p vol (world
 * coordinates of the volume) with each triangle in the colour of its label
 * (vv_label_color): the label of the labelled voxel nearest the triangle's
 * centroid (of its cell's eight corners, the non-zero one of largest
 * trilinear weight, as the ray caster colours). One draw per label present,
 * the meshes appended to @p keep. */
static vv_status
draw_labels(vv_raster *ras, const vv_mesh *mesh, vv_mat4 model, const vv_object *obj,
            vv_material mat, sf_keep *keep) {
    const vv_volume *vol = obj->volume;
    const vv_mat4 w2i = vv_volume_world_to_index(vol);
    size_t nt = mesh->n_triangles;
    tri_label *tl = malloc((nt ? nt : 1) * sizeof *tl);
    if (!tl)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t t = 0; t < nt; t++) {
        vv_vec3 c = vv_vec3_make(0, 0, 0);
        for (int k = 0; k < 3; k++)
            c = vv_vec3_add(c, vv_mesh_vertex(mesh, mesh->triangles[3 * t + (size_t)k]));
        vv_vec3 q = vv_mat4_mul_point(w2i, vv_vec3_scale(c, 1.0 / 3.0));
        const float p[3] = {(float)q.x, (float)q.y, (float)q.z};
        tl[t] = (tri_label){vv_vextra_label(vol, p), (uint32_t)t};
    }
    qsort(tl, nt, sizeof *tl, cmp_tri_label);
    vv_status s = VV_OK;
    for (size_t i = 0; i < nt && s == VV_OK;) {
        size_t j = i;
        while (j < nt && tl[j].label == tl[i].label)
            j++;
        vv_mesh *sub = NULL;
        if ((s = vv_mesh_new(&sub)) != VV_OK)
            break;
        s = vv_mesh_reserve(sub, 3 * (j - i), j - i);
        if (s == VV_OK)
            s = vv_mesh_enable_attributes(sub, mesh->normals != NULL, 0);
        for (size_t u = i; u < j && s == VV_OK; u++) {
            uint32_t idx[3];
            for (int k = 0; k < 3 && s == VV_OK; k++) {
                const uint32_t v = mesh->triangles[3 * (size_t)tl[u].tri + (size_t)k];
                s = vv_mesh_add_vertex(sub, vv_mesh_vertex(mesh, v), &idx[k]);
                if (s == VV_OK && mesh->normals)
                    memcpy(sub->normals + 3 * (size_t)idx[k], mesh->normals + 3 * (size_t)v,
                           3 * sizeof(float));
            }
            if (s == VV_OK)
                s = vv_mesh_add_triangle(sub, idx[0], idx[1], idx[2]);
        }
        if (s != VV_OK) {
            vv_mesh_free(sub);
            break;
        }
        if (tl[i].label != 0)
            mat.color = vv_label_color(tl[i].label);
        vv_raster_set_material(ras, &mat, obj->shading);
        s = vv_raster_draw_mesh(ras, sub, model);
        vv_status ks = keep_push(keep, sub);
        if (s == VV_OK)
            s = ks;
        i = j;
    }
    free(tl);
    return s;
}

/* Draws @p mesh in SF_BANDS colour bands of its scalars, each in the
 * object's transfer-function colour at the band's middle. The band meshes
 * are appended to @p keep (at most SF_BANDS): the raster reads them until
 * vv_raster_finish. */
static vv_status
draw_banded(vv_raster *ras, const vv_mesh *mesh, vv_mat4 model, const vv_object *obj,
            vv_material mat, vv_mesh **keep, int *n_keep) {
    const vv_tf *tf = &obj->tf;
    double lo = 0, hi = 1;
    const int f = vv_object_grid_field(obj);
    if (tf->n_color >= 2) {
        lo = tf->color[0].value;
        hi = tf->color[tf->n_color - 1].value;
    } else if (f >= 0) {
        lo = obj->grid->fields[f].range[0];
        hi = obj->grid->fields[f].range[1];
    }
    if (!(hi > lo))
        hi = lo + 1;
    int *band = malloc((mesh->n_triangles ? mesh->n_triangles : 1) * sizeof *band);
    if (!band)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (size_t t = 0; t < mesh->n_triangles; t++) {
        double v = 0;
        for (int k = 0; k < 3; k++)
            v += mesh->scalars ? mesh->scalars[mesh->triangles[3 * t + (size_t)k]] : lo;
        int b = (int)((v / 3 - lo) / (hi - lo) * SF_BANDS);
        band[t] = b < 0 ? 0 : b >= SF_BANDS ? SF_BANDS - 1 : b;
    }
    vv_status s = VV_OK;
    for (int b = 0; b < SF_BANDS && s == VV_OK; b++) {
        vv_mesh *sub = NULL;
        if ((s = vv_mesh_new(&sub)) != VV_OK)
            break;
        s = vv_mesh_enable_attributes(sub, mesh->normals != NULL, 0);
        for (size_t t = 0; t < mesh->n_triangles && s == VV_OK; t++) {
            if (band[t] != b)
                continue;
            uint32_t idx[3];
            for (int k = 0; k < 3 && s == VV_OK; k++) {
                const uint32_t v = mesh->triangles[3 * t + (size_t)k];
                s = vv_mesh_add_vertex(sub, vv_mesh_vertex(mesh, v), &idx[k]);
                if (s == VV_OK && mesh->normals)
                    memcpy(sub->normals + 3 * (size_t)idx[k], mesh->normals + 3 * (size_t)v,
                           3 * sizeof(float));
            }
            if (s == VV_OK)
                s = vv_mesh_add_triangle(sub, idx[0], idx[1], idx[2]);
        }
        if (s == VV_OK && sub->n_triangles > 0) {
            mat.color = vv_tf_eval_color(tf, lo + (hi - lo) * (b + 0.5) / SF_BANDS);
            vv_raster_set_material(ras, &mat, obj->shading);
            s = vv_raster_draw_mesh(ras, sub, model);
        }
        keep[(*n_keep)++] = sub;
    }
    free(band);
    return s;
}

/* How big the scene is, for the clip distances and the size of plane
 * squares: its bounds, the eye's distance to them and to the target, and
 * to every plane (planes are squares 1000 times larger than that, which
 * puts their edges near the horizon). */
static double
scene_size(const vv_world *w, const vv_view *view) {
    vv_box b = vv_world_bounds(w);
    vv_vec3 centre = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
    double radius = 0.5 * vv_vec3_length(vv_vec3_sub(b.max, b.min));
    double dist = vv_vec3_length(vv_vec3_sub(centre, view->eye));
    double atd = vv_vec3_length(vv_vec3_sub(view->at, view->eye));
    double scene = radius > dist ? radius : dist;
    scene = scene > atd ? scene : atd;
    if (view->projection == VV_PROJECTION_ORTHOGRAPHIC) {
        double half = 0.5 * view->ortho_height;
        scene = scene > half ? scene : half;
    }
    if (!(scene > 0) || !isfinite(scene))
        scene = 1;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *obj = w->objects[i];
        if (!obj->visible || obj->type != VV_OBJECT_PLANE)
            continue;
        vv_mat4 M = vv_object_matrix(obj);
        int ok = 0;
        vv_mat4 inv = vv_mat4_inverse(M, &ok);
        vv_vec3 p = vv_mat4_mul_point(M, obj->geometry.point);
        vv_vec3 n =
            vv_vec3_normalize(vv_mat4_mul_dir(vv_mat4_transpose(inv), obj->geometry.normal));
        double dp = fabs(vv_vec3_dot(n, vv_vec3_sub(view->eye, p)));
        if (ok && isfinite(dp) && dp > scene)
            scene = dp;
    }
    return scene;
}

/* One loop over the World's objects turns each kind into meshes
 * (isosurfaces, grid surfaces, tessellated primitives) and draws them; the
 * geometry-type table (model) gives each kind's part. */
static vv_status
sf_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    sf_state *st = state;
    st->frame++;
    vv_status s = VV_OK;
    /* a new context when the image size changes (the Navigator's previews
     * draw at several sizes with one renderer) */
    if (!st->ras || st->ras_width != view->width || st->ras_height != view->height) {
        vv_raster_free(st->ras);
        st->ras = NULL;
        s = vv_raster_new(&st->ras, view->width, view->height);
        if (s != VV_OK)
            return s;
        st->ras_width = view->width;
        st->ras_height = view->height;
    }
    vv_raster *ras = st->ras;
    const double scene = scene_size(w, view);
    if (view->projection == VV_PROJECTION_ORTHOGRAPHIC)
        s = vv_raster_set_view(ras, view, 0, 3000 * scene);
    else
        s = vv_raster_set_view(ras, view, 1e-5 * scene, INFINITY);
    if (s != VV_OK)
        return s;
    vv_raster_set_threads(ras, opt->threads);
    vv_raster_begin(ras, w->background);
    s = vv_raster_set_lights(ras, w->lights, w->n_lights, w->ambient);
    vv_raster_set_shading(ras, st->shading);
    vv_raster_set_wireframe(ras, st->wireframe);

    int n_vis = 0;
    for (int i = 0; i < w->n_objects; i++)
        n_vis += w->objects[i]->visible;
    vv_mesh **temp = calloc((size_t)(n_vis ? n_vis : 1), sizeof *temp);
    int n_temp = 0, done = 0, n_bands = 0, n_grids = 0;
    for (int i = 0; i < w->n_objects; i++)
        n_grids += w->objects[i]->visible && w->objects[i]->type == VV_OBJECT_GRID;
    /* colour bands of grid surfaces, kept until the raster is finished */
    vv_mesh **bands = calloc((size_t)(n_grids ? n_grids : 1) * SF_BANDS, sizeof *bands);
    sf_keep labels = {NULL, 0, 0}; /* per-label meshes of label volumes */
    if (!temp || !bands)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        const vv_object *obj = w->objects[i];
        if (!obj->visible)
            continue;
        vv_cut_plane planes[2 * VV_MAX_CUT_PLANES];
        int np = 0;
        for (int k = 0; k < w->n_cut_planes && k < VV_MAX_CUT_PLANES; k++)
            planes[np++] = w->cut_planes[k];
        for (int k = 0; k < obj->n_cut_planes && k < VV_MAX_CUT_PLANES; k++)
            planes[np++] = obj->cut_planes[k];
        s = vv_raster_set_cut_planes(ras, planes, np);
        if (s != VV_OK)
            break;
        vv_material mat = obj->material;
        vv_mat4 model = vv_object_matrix(obj);
        const vv_mesh *mesh = NULL;
        int closed = 0, positive = 1, solid = 0;
        vv_cut_plane bounds[6];
        int n_bounds = 0;
        if (obj->type == VV_OBJECT_VOLUME) {
            if (!obj->volume)
                continue;
            double iso;
            if (!vv_object_surface_value(obj, &iso, &mat.color))
                continue;
            sf_iso *c = NULL;
            s = iso_get(st, obj->volume, iso, opt->threads, &c);
            if (s != VV_OK) {
                s = vv_error_prefix(s, "object '%s': isosurface %g", obj->name, iso);
                break;
            }
            mesh = c->mesh;
            closed = c->closed;
            /* Marching Cubes leaves the surface open where it leaves the
             * volume: the volume's faces bound the solid */
            solid = 1;
            n_bounds = volume_bounds(obj, bounds);
        } else if (obj->type == VV_OBJECT_GRID) {
            if (!obj->grid)
                continue;
            int banded = 0;
            s = grid_surface(obj, &temp[n_temp], &banded, &mat.color);
            if (s == VV_ERR_INVALID && !temp[n_temp]) {
                s = VV_OK; /* nothing to show (transparent TF, no surface) */
                vv_error_clear();
                continue;
            }
            if (s != VV_OK) {
                s = vv_error_prefix(s, "object '%s'", obj->name);
                break;
            }
            mesh = temp[n_temp++];
            if (banded) {
                vv_raster_set_cull(ras, VV_RASTER_CULL_NONE);
                s = vv_raster_set_capping(ras, 0, bounds, 0);
                if (s == VV_OK)
                    s = draw_banded(ras, mesh, model, obj, mat, bands, &n_bands);
                if (s != VV_OK)
                    break;
                done++;
                if (vv_progress_report(&opt->progress, (double)done / (n_vis + 1)))
                    s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
                continue;
            }
        } else if (obj->type == VV_OBJECT_MESH) {
            if (!obj->geometry.mesh)
                continue;
            mesh = obj->geometry.mesh;
            sf_topo *t = NULL;
            if (st->cull == SF_CULL_AUTO && np == 0) {
                s = mesh_topo(st, mesh, &t);
                if (s != VV_OK)
                    break;
                closed = t->closed;
                positive = t->positive;
            } else if (np > 0 && st->caps) {
                s = mesh_topo(st, mesh, &t);
                if (s != VV_OK)
                    break;
                solid = t->closed && t->positive;
            }
        } else {
            int world = 0;
            s = tessellate(st, obj, view, scene, &temp[n_temp], &closed, &world);
            if (s != VV_OK) {
                vv_mesh_free(temp[n_temp]);
                temp[n_temp] = NULL;
                break;
            }
            mesh = temp[n_temp++];
            solid = closed;
            if (world)
                model = vv_mat4_identity();
        }
        vv_raster_cull cull = VV_RASTER_CULL_NONE;
        if (st->cull == SF_CULL_BACK || (st->cull == SF_CULL_AUTO && closed && np == 0))
            cull = positive ? VV_RASTER_CULL_BACK : VV_RASTER_CULL_FRONT;
        vv_raster_set_cull(ras, cull);
        s = vv_raster_set_capping(ras, st->caps && solid && !st->wireframe, bounds, n_bounds);
        if (s != VV_OK)
            break;
        if (obj->type == VV_OBJECT_VOLUME && obj->segmentation == VV_SEG_LABELS) {
            s = draw_labels(ras, mesh, model, obj, mat, &labels);
        } else {
            vv_raster_set_material(ras, &mat, obj->shading);
            s = vv_raster_draw_mesh(ras, mesh, model);
        }
        if (s != VV_OK) {
            s = vv_error_prefix(s, "object '%s'", obj->name);
            break;
        }
        done++;
        if (vv_progress_report(&opt->progress, (double)done / (n_vis + 1)))
            s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
    }
    if (s == VV_OK)
        s = vv_raster_finish(ras, out, 0);
    if (s == VV_OK && vv_progress_report(&opt->progress, 1.0))
        s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
    for (int i = 0; i < n_temp; i++)
        vv_mesh_free(temp[i]);
    free(temp);
    for (int i = 0; i < n_bands; i++)
        vv_mesh_free(bands[i]);
    free(bands);
    for (int i = 0; i < labels.n; i++)
        vv_mesh_free(labels.m[i]);
    free(labels.m);
    /* forget isosurfaces not shown in this frame */
    for (int i = 0; i < st->n_cache;) {
        if (st->cache[i].last_frame != st->frame) {
            iso_release(&st->cache[i]);
            st->cache[i] = st->cache[--st->n_cache];
        } else {
            i++;
        }
    }
    for (int i = 0; i < st->n_topo;) {
        if (st->topo[i].last_frame != st->frame)
            st->topo[i] = st->topo[--st->n_topo];
        else
            i++;
    }
    return s;
}

static const char *const sf_shadings[] = {"flat", "gouraud", "phong", NULL};
static const char *const sf_culls[] = {"auto", "back", "none", NULL};

/* The options, each bound to its field of sf_state; shading and cull store
 * the word's index, which is the vv_raster_shading and sf_cull value. */
_Static_assert(VV_RASTER_FLAT == 0 && VV_RASTER_GOURAUD == 1 && VV_RASTER_PHONG == 2,
               "shading: the words' indices are the shadings");
_Static_assert(SF_CULL_AUTO == 0 && SF_CULL_BACK == 1 && SF_CULL_NONE == 2,
               "cull: the words' indices are the modes");
static const vv_option_spec sf_options[] = {
    {"shading", VV_OPTION_ENUM, "phong", 0, 0, 0, sf_shadings,
     "flat: a normal a triangle; gouraud: colours at vertices; phong: normals at pixels",
     VV_OPTION_BIND(sf_state, shading, INT)},
    {"wireframe", VV_OPTION_BOOL, "0", 0, 1, 0, NULL, "triangle edges only",
     VV_OPTION_BIND(sf_state, wireframe, INT)},
    {"cull", VV_OPTION_ENUM, "auto", 0, 0, 0, sf_culls,
     "auto: back faces of closed surfaces; back: every back face; none",
     VV_OPTION_BIND(sf_state, cull, INT)},
    {"caps", VV_OPTION_BOOL, "1", 0, 1, 0, NULL, "close surfaces cut by cut planes",
     VV_OPTION_BIND(sf_state, caps, INT)},
    {"segments", VV_OPTION_INT, "64", 3, 4096, 0, NULL,
     "meridians of spheres and sides of cylinders", VV_OPTION_BIND(sf_state, segments, INT)},
};

const vv_renderer_ops vv_raster_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "raster",
            .description = "geometry rendering: Marching Cubes isosurfaces and geometric "
                           "objects, rasterized",
            .draws = VV_DRAWS(VV_OBJECT_VOLUME) | VV_DRAWS(VV_OBJECT_GRID) | VV_DRAWS_GEOMETRY,
            .modes = VV_MODES_ALL,
            .caps = 0,
            .quality = "ignored: volumes and grids are drawn as isosurfaces in every mode "
                       "(iso: the isovalue; else the transfer function's half-opacity value)",
            .options = sf_options,
            .n_options = VV_OPTIONS_COUNT(sf_options),
        },
    .state_size = sizeof(sf_state),
    .release = sf_release,
    .render = sf_render,
    .render_region = NULL,
};
