/*
 * What the files of the scene reader and writer share (not installed): the
 * parse context, the error reporting and the typed field readers
 * (scene_fields.c), the objects (scene_objects.c: dispatch and volume
 * objects; scene_geometry.c: geometric, "geometry" and grid objects;
 * scene_appearance.c: what every object carries).
 */
#ifndef VOLVIS_SCENE_INTERNAL_H
#define VOLVIS_SCENE_INTERNAL_H

#include <jansson.h>
#include <stddef.h>

#include "core/internal.h"
#include "volvis/filter.h"
#include "volvis/model.h"
#include "volvis/scene.h"

#define SCENE_MAX_BYTES (16u << 20)
#define PATH_MAX_LEN 256
#define IMAGE_MAX_SIDE 32768

/* Files a scene opened out of core, each once: objects naming the same
 * file (and step) share its source, so that its chunks, shard indexes and
 * loader threads are held once and count once against the cache's limit. */
#define SCENE_SOURCES_MAX 64
typedef struct scene_source {
    char *real; /* the file's real path (malloc) */
    int time;
    vv_source *source; /* a reference */
    int is_label;      /* an OME-Zarr label image (vv_load_info.is_label) */
} scene_source;

typedef struct scene_sources {
    scene_source e[SCENE_SOURCES_MAX];
    int n;
} scene_sources;

/** A scene file being read. */
typedef struct sctx {
    const char *path; /* scene file as given */
    const char *text;
    size_t len;
    const vv_progress *progress; /* voxelization of geometry objects; may be NULL */
    vv_filter_cache *fcache;     /* filtered volumes kept between loads; may be NULL */
    /* how unfiltered volume files open (vv_open); NULL: whole, into memory */
    const vv_open_options *open;
    scene_sources *sources;             /* the files opened out of core so far; may be NULL */
    const struct scene_overrides *over; /* may be NULL */
} sctx;

/* What the door (vv_world_open) sets on a scene's World after loading it
 * (its options: the image size, every volume object's mode), which the
 * defaults a scene leaves out are made for, as the door makes a file's:
 * a scene without a view is framed for that size, an object without a
 * transfer function gets the default of that mode. */
typedef struct scene_overrides {
    int width, height; /* 0: the scene's own */
    int has_mode;
    vv_render_mode mode;
} scene_overrides;

/* vv_scene_load_open with the door's overrides @p over (may be NULL). */
vv_status vv_scene_load_for(vv_world **out, const char *path, const vv_progress *progress,
                            vv_filter_cache *cache, const vv_open_options *open,
                            const scene_overrides *over);

/* Frees what @p s holds of the sources (the objects keep theirs). */
void vv_scene_sources_clear(scene_sources *s);

/** The render modes' names in scene files, by vv_render_mode. */
extern const char *const vv_scene_mode_names[VV_MODE_COUNT];

/* @p v scaled to unit length, or @p v itself when it already is to within
 * rounding (|v|^2 within 8 epsilon of 1): normalizing a normalized vector
 * again moves its last bits, and a World saved and loaded again must not
 * drift. @p v must not be zero. */
vv_vec3 vv_scene_unit(vv_vec3 v);

/* Line and column of @p path in the scene text (its nearest ancestor's when
 * the path itself cannot be found). */
void vv_scene_locate(const sctx *c, const char *path, int *line, int *col);

/* Sets and returns a VV_ERR_FORMAT error "FILE:LINE:COL: PATH: message",
 * placed at @p path in the scene text. */
vv_status vv_scene_serr(const sctx *c, const char *path, const char *fmt, ...) VV_PRINTF(3, 4);

/* dst = parent.key (PATH_MAX_LEN bytes; truncated paths only place errors less precisely). */
void vv_scene_path_key(char *dst, const char *parent, const char *key);

/* dst = parent[i] (PATH_MAX_LEN bytes). */
void vv_scene_path_index(char *dst, const char *parent, size_t i);

/* Every key of @p obj must be in the NULL-terminated @p allowed list. */
vv_status vv_scene_check_keys(const sctx *c, json_t *obj, const char *path,
                              const char *const *allowed);

/* A finite number, a 3-vector, an RGB colour in [0, 1]: value readers. */
vv_status vv_scene_value_number(const sctx *c, json_t *v, const char *path, double *out);

vv_status vv_scene_value_vec3(const sctx *c, json_t *v, const char *path, vv_vec3 *out);

vv_status vv_scene_value_color(const sctx *c, json_t *v, const char *path, vv_vec3 *out);

/* Field getters: *present (may be NULL) says whether the key was there; a
 * missing key leaves *out unchanged and is not an error. */
json_t *vv_scene_field(json_t *obj, const char *key, char *kp, const char *path, int *present);

vv_status vv_scene_get_number(const sctx *c, json_t *obj, const char *path, const char *key,
                              double *out, int *present);

/* A number in a range; open ends when lo_open / hi_open. */
vv_status vv_scene_get_number_in(const sctx *c, json_t *obj, const char *path, const char *key,
                                 double *out, int *present, double lo, int lo_open, double hi,
                                 int hi_open);

vv_status vv_scene_get_int_in(const sctx *c, json_t *obj, const char *path, const char *key,
                              int *out, int lo, int hi);

vv_status vv_scene_get_vec3(const sctx *c, json_t *obj, const char *path, const char *key,
                            vv_vec3 *out, int *present);

vv_status vv_scene_get_nonzero_vec3(const sctx *c, json_t *obj, const char *path, const char *key,
                                    vv_vec3 *out, int *present);

vv_status vv_scene_get_color(const sctx *c, json_t *obj, const char *path, const char *key,
                             vv_vec3 *out, int *present);

/* A boolean field (absent: *out unchanged). */
vv_status vv_scene_get_bool(const sctx *c, json_t *obj, const char *path, const char *key,
                            int *out);

/* A string field (absent: *out unchanged); borrowed from the JSON tree. */
vv_status vv_scene_get_string(const sctx *c, json_t *obj, const char *path, const char *key,
                              const char **out);

vv_status vv_scene_get_object(const sctx *c, json_t *obj, const char *path, const char *key,
                              json_t **out);

vv_status vv_scene_get_array(const sctx *c, json_t *obj, const char *path, const char *key,
                             json_t **out);

/* The error for a required @p key missing from the object at @p path. */
vv_status vv_scene_missing(const sctx *c, const char *path, const char *key, const char *what);

/* Cut planes (scene.c): at most VV_MAX_CUT_PLANES into @p planes, their count in *n. */
vv_status vv_scene_parse_cut_planes(const sctx *c, json_t *arr, const char *path,
                                    vv_cut_plane *planes, int *n);

/* Object @p idx of the "objects" array, added to @p w (scene_objects.c). */
vv_status vv_scene_parse_object(const sctx *c, json_t *e, size_t idx, vv_world *w);

/* ---- scene_objects.c: what the object kinds share ---- */

/* A default object name from a file path: its base name without the
 * extension(s), truncated to VV_NAME_MAX - 1 bytes. */
void vv_scene_name_from_file(char dst[VV_NAME_MAX], const char *file);

/* Checks the keys of object @p e: "name" and "type", the kind's own keys
 * @p own (NULL-terminated), the keys of volume-like objects (mode,
 * segmentation, cut planes) when @p volume_like, and the transform,
 * material, visibility and shading-effect keys every object takes. */
vv_status vv_scene_check_object_keys(const sctx *c, json_t *e, const char *op,
                                     const char *const *own, int volume_like);

/* The optional "name" of object @p e (borrowed), at most VV_NAME_MAX - 1 bytes. */
vv_status vv_scene_get_object_name(const sctx *c, json_t *e, const char *op, const char **name);

/* ---- scene_appearance.c ---- */

/* A 1-D transfer function {"opacity": ..., "color": ...,
 * "opacity_unit_distance": ...} at @p tp into *out (unchanged on error);
 * @p unit: the unit distance when the key is absent. */
vv_status vv_scene_parse_tf(const sctx *c, json_t *tfj, const char *tp, double unit, vv_tf *out);

/* ---- scene_channels.c ---- */

/* The "channels" and "blend" of volume object @p e (at @p op; its file
 * @p full, its own keys parsed into @p o): each channel loaded from @p full
 * (its "channel" index), named, shown or hidden, with its transfer function
 * (else vv_object_set_channels' defaults). No "channels": nothing. */
vv_status vv_scene_parse_channels(const sctx *c, json_t *e, const char *op, const char *full,
                                  vv_object *o);

/* What a volume object read from a file gets when it gives no appearance
 * of its own (no "transfer_function", "segmentation" or "tf2d"): what the
 * file opened alone gets (vv_object_default_appearance, for the object's
 * mode) from the histogram of @p histogram (NULL: the object's volume),
 * with the opacity unit of level @p shown (NULL: the object's volume). */
typedef struct scene_file_defaults {
    const vv_volume *histogram;
    const vv_volume *shown;
} scene_file_defaults;

/* Object fields other than the source (file, shape): mode, isovalue,
 * step, shading, visibility, transform, segmentation (TF, 2-D TF,
 * threshold, labels), textures, material and local cut planes. @p fd: the
 * defaults of an object read from a file (an isovalue among them, so that
 * mode "iso" needs none), NULL for other objects (a transfer function from
 * vv_tf_default of their volume; "iso" needs an isovalue). */
vv_status vv_scene_parse_object_fields(const sctx *c, json_t *e, const char *op, vv_object *o,
                                       const scene_file_defaults *fd);

/* The coarsest level of pyramid file @p path (more than one level) as a
 * whole volume with the pyramid's value range, whose histogram gives the
 * default transfer function of the file in memory and out of core alike
 * (docs/scene-format.md, "Default scene"): vv_source_proxy of @p src when
 * it holds the file out of core, else of the file opened again out of
 * core, header only, with @p again's options (NULL: the defaults). NULL
 * when it cannot be read (the error cleared): the level shown gives the
 * defaults then. The door (vv_world_open) and scene files share it. */
vv_volume *vv_scene_coarsest_level(const char *path, vv_source *src, const vv_open_options *again);

/* The shading-effect flags every object takes (casts_shadows, ...). */
vv_status vv_scene_parse_effect_flags(const sctx *c, json_t *e, const char *op, vv_object *o);

/* @p st (set by loading a file named at key path @p kp) prefixed with
 * "scene:line:col: kp". */
vv_status vv_scene_file_err(const sctx *c, vv_status st, const char *kp);

/* ---- scene_geometry.c ---- */

/* The geometric object type named @p name ("plane", ..., "mesh"), or
 * VV_OBJECT_VOLUME for "volume" and names that are not geometric types. */
vv_object_type vv_scene_geometry_type(const char *name);

/* A geometric object (ray tracer): shape, transform, material, flags. */
vv_status vv_scene_parse_geometry_object(const sctx *c, json_t *e, const char *op, vv_world *w);

/* A "geometry" object: a Modeling primitive or CSG tree volume-sampled now. */
vv_status vv_scene_parse_voxelized_geometry(const sctx *c, json_t *e, const char *op, vv_world *w);

/* An irregular grid object. */
vv_status vv_scene_parse_grid_object(const sctx *c, json_t *e, const char *op, vv_world *w);

#endif
