/*
 * Scene files, the objects: the dispatch on "type", the keys every object
 * takes, and volume objects (a volume file, optionally through a filter
 * chain). The other kinds are in scene_geometry.c, what every object
 * carries in scene_appearance.c.
 */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "scene/scene_internal.h"
#include "volvis/filter.h"
#include "volvis/io.h"
#include "volvis/model.h"

/* Name from a file path: its base name without the extension(s). */
void
vv_scene_name_from_file(char dst[VV_NAME_MAX], const char *file) {
    snprintf(dst, VV_NAME_MAX, "%s", vv_path_basename(file));
    char *dot = strchr(dst, '.');
    if (dot && dot != dst)
        *dot = '\0';
}

/* Checks the keys of object @p e: "name" and "type", the kind's own keys
 * @p own (NULL-terminated), the keys of volume-like objects (mode,
 * segmentation, cut planes) when @p volume_like, and the transform,
 * material, visibility and shading-effect keys every object takes. */
vv_status
vv_scene_check_object_keys(const sctx *c, json_t *e, const char *op, const char *const *own,
                           int volume_like) {
    static const char *const head[] = {"name", "type", NULL};
    static const char *const volume_head[] = {"mode", "isovalue", "attenuation",
                                              "step", "shading",  NULL};
    static const char *const place[] = {"visible",     "position", "rotation",
                                        "orientation", "scale",    NULL};
    static const char *const volume_mid[] = {"transfer_function", "segmentation", "tf2d",
                                             "solid_texture", NULL};
    static const char *const mat[] = {"material", "texture", NULL};
    static const char *const volume_tail[] = {"cut_planes", NULL};
    static const char *const flags[] = {"casts_shadows", "receives_shadows",
                                        "visible_in_reflections", "reflects", NULL};
    const char *const *parts[] = {head,
                                  own,
                                  volume_like ? volume_head : NULL,
                                  place,
                                  volume_like ? volume_mid : NULL,
                                  mat,
                                  volume_like ? volume_tail : NULL,
                                  flags};
    const char *keys[64];
    size_t n = 0;
    for (size_t p = 0; p < sizeof parts / sizeof parts[0]; p++)
        for (size_t i = 0; parts[p] && parts[p][i] && n + 1 < sizeof keys / sizeof keys[0]; i++)
            keys[n++] = parts[p][i];
    keys[n] = NULL;
    return vv_scene_check_keys(c, e, op, keys);
}

/* The optional "name" of object @p e, at most VV_NAME_MAX - 1 bytes. */
vv_status
vv_scene_get_object_name(const sctx *c, json_t *e, const char *op, const char **name) {
    vv_status st = vv_scene_get_string(c, e, op, "name", name);
    if (st == VV_OK && *name && strlen(*name) >= VV_NAME_MAX) {
        char kp[PATH_MAX_LEN];
        vv_scene_path_key(kp, op, "name");
        return vv_scene_serr(c, kp, "longer than %d bytes", VV_NAME_MAX - 1);
    }
    return st;
}

/* A volume object's "filters" value as a filter chain: a string in
 * command-line syntax ("--gaussian 1.5 --median 1") or an array of one-key
 * objects ({"gaussian": 1.5}, {"threshold": "300:"}, {"fill-holes": true}):
 * the key names the filter, the value is its argument (a string, a number,
 * or true/null for a filter without one). On error *@p bad_item is the
 * array index at fault (-1: the value itself) and the message says why.
 * Errors: VV_ERR_INVALID, VV_ERR_NOMEM. */
/* The source an earlier object opened out of core for file @p full at
 * step @p time (the same real path), or NULL. */
static scene_source *
find_source(const sctx *c, const char *full, int time) {
    scene_sources *s = c->sources;
    char *real = s && s->n ? realpath(full, NULL) : NULL;
    scene_source *hit = NULL;
    for (int i = 0; real && i < s->n && !hit; i++)
        if (s->e[i].time == time && !strcmp(s->e[i].real, real))
            hit = &s->e[i];
    free(real);
    return hit;
}

/* Keeps @p source (out of core) for the objects after this one that name
 * file @p full at step @p time; past SCENE_SOURCES_MAX files they open
 * their own. */
static void
keep_source(const sctx *c, const char *full, int time, vv_source *source, int is_label) {
    if (!c->sources || c->sources->n >= SCENE_SOURCES_MAX)
        return;
    char *real = realpath(full, NULL);
    if (!real)
        return;
    scene_source *e = &c->sources->e[c->sources->n++];
    e->real = real;
    e->time = time;
    e->source = vv_source_ref(source);
    e->is_label = is_label;
}

void
vv_scene_sources_clear(scene_sources *s) {
    for (int i = 0; s && i < s->n; i++) {
        free(s->e[i].real);
        vv_source_free(s->e[i].source);
    }
    if (s)
        s->n = 0;
}

static vv_status
chain_from_json(const json_t *j, vv_filter_chain **out, int *bad_item) {
    *bad_item = -1;
    if (json_is_string(j))
        return vv_filter_chain_parse(json_string_value(j), out);
    if (!json_is_array(j))
        return vv_error_set(VV_ERR_INVALID,
                            "expected a string (\"--gaussian 1.5 --median 1\") or an array of "
                            "{\"filter\": argument} objects");
    vv_filter_chain *c;
    vv_status s = vv_filter_chain_new(&c);
    if (s != VV_OK)
        return s;
    size_t i;
    json_t *e;
    json_array_foreach(j, i, e) {
        *bad_item = (int)i;
        if (!json_is_object(e) || json_object_size(e) != 1) {
            s = vv_error_set(VV_ERR_INVALID,
                             "expected an object with one key, the filter's name, e.g. "
                             "{\"gaussian\": 1.5}");
            break;
        }
        const char *name = json_object_iter_key(json_object_iter((json_t *)e));
        json_t *v = json_object_iter_value(json_object_iter((json_t *)e));
        char arg[256];
        const char *a = arg;
        if (json_is_string(v)) {
            a = json_string_value(v);
        } else if (json_is_integer(v)) {
            snprintf(arg, sizeof arg, "%lld", (long long)json_integer_value(v));
        } else if (json_is_real(v)) {
            snprintf(arg, sizeof arg, "%.15g", json_real_value(v));
        } else if (json_is_true(v) || json_is_null(v)) {
            a = NULL;
        } else {
            s = vv_error_set(VV_ERR_INVALID, "\"%s\": expected a string or a number argument",
                             name);
            break;
        }
        if ((s = vv_filter_chain_add(c, name, a)) != VV_OK)
            break;
    }
    if (s != VV_OK) {
        vv_filter_chain_free(c);
        return s;
    }
    *bad_item = -1;
    *out = c;
    return VV_OK;
}

vv_volume *
vv_scene_coarsest_level(const char *path, vv_source *src, const vv_open_options *again) {
    vv_opened od;
    memset(&od, 0, sizeof od);
    vv_source *from = src && !vv_source_volume(src) ? src : NULL;
    if (!from) { /* read whole: its levels opened again, out of core */
        vv_open_options oo;
        if (again)
            oo = *again;
        else
            vv_open_options_init(&oo);
        oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
        oo.levels = 1;
        oo.load.level = 0;
        oo.header_only = 1;
        oo.n_channels = 0;
        if (vv_open(&od, path, &oo) == VV_OK && od.kind == VV_DATA_VOLUME)
            from = od.source;
    }
    vv_volume *coarse = NULL;
    if (!from || vv_source_proxy(from, 0, &coarse) != VV_OK)
        coarse = NULL;
    vv_opened_clear(&od);
    vv_error_clear(); /* the level shown's defaults stay */
    return coarse;
}

vv_status
vv_scene_parse_object(const sctx *c, json_t *e, size_t idx, vv_world *w) {
    static const char *const own[] = {"file",     "origin", "spacing", "filters",
                                      "channels", "blend",  "time",    NULL};
    char op[PATH_MAX_LEN], kp[PATH_MAX_LEN];
    vv_scene_path_index(op, "objects", idx);
    if (json_is_object(e)) {
        json_t *tj = json_object_get(e, "type");
        if (json_is_string(tj) && strcmp(json_string_value(tj), "geometry") == 0)
            return vv_scene_parse_voxelized_geometry(c, e, op, w);
        if (json_is_string(tj) && strcmp(json_string_value(tj), "grid") == 0)
            return vv_scene_parse_grid_object(c, e, op, w);
        if (json_is_string(tj) && vv_scene_geometry_type(json_string_value(tj)) != VV_OBJECT_VOLUME)
            return vv_scene_parse_geometry_object(c, e, op, w);
    }
    if (!json_is_object(e))
        return vv_scene_serr(c, op, "expected an object, got %s", vv_json_kind(e));
    vv_status st = vv_scene_check_object_keys(c, e, op, own, 1);
    if (st != VV_OK)
        return st;
    const char *type = "volume", *name = NULL, *file = NULL;
    if ((st = vv_scene_get_string(c, e, op, "type", &type)) != VV_OK ||
        (st = vv_scene_get_object_name(c, e, op, &name)) != VV_OK ||
        (st = vv_scene_get_string(c, e, op, "file", &file)) != VV_OK)
        return st;
    if (strcmp(type, "volume") != 0) {
        vv_scene_path_key(kp, op, "type");
        return vv_scene_serr(
            c, kp,
            "unsupported object type \"%s\"; expected volume, grid, geometry, plane, "
            "polygon, sphere, box, cylinder or mesh",
            type);
    }
    if (!file)
        return vv_scene_missing(c, op, "file", "the volume file, relative to the scene file");
    vv_scene_path_key(kp, op, "file");
    if (!file[0])
        return vv_scene_serr(c, kp, "empty file name");
    vv_vec3 origin, spacing;
    int has_origin, has_spacing;
    if ((st = vv_scene_get_vec3(c, e, op, "origin", &origin, &has_origin)) != VV_OK ||
        (st = vv_scene_get_vec3(c, e, op, "spacing", &spacing, &has_spacing)) != VV_OK)
        return st;
    if (has_spacing && !(spacing.x > 0.0 && spacing.y > 0.0 && spacing.z > 0.0)) {
        vv_scene_path_key(kp, op, "spacing");
        return vv_scene_serr(c, kp, "voxel spacing must be > 0");
    }
    /* "time": the file's time step the object shows (OME-TIFF, NIfTI, NRRD) */
    int time = -1;
    if ((st = vv_scene_get_int_in(c, e, op, "time", &time, 0, 1000000)) != VV_OK)
        return st;
    if (time > 0 && json_object_get(e, "filters")) {
        vv_scene_path_key(kp, op, "time");
        return vv_scene_serr(c, kp, "\"filters\" apply to time step 0 of a file");
    }

    /* a URL (a remote store) as it is; a path relative to the scene's folder */
    char *full = vv_path_is_url(file) ? vv_strdup(file) : vv_path_join_dir(c->path, file);
    if (!full)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    vv_volume *vol = NULL;
    vv_source *source = NULL; /* the file out of core (vol its proxy) */
    int source_level = 0;
    int is_label = 0;            /* the file is an OME-Zarr label image */
    int n_levels = 1;            /* of a pyramid read whole */
    double scale[3] = {1, 1, 1}; /* the volume's voxel over the file's */
    /* "filters": a filter chain applied at load (src/filter), the result cached */
    json_t *fj = json_object_get(e, "filters");
    vv_filter_chain *chain = NULL;
    if (fj) {
        int bad;
        vv_scene_path_key(kp, op, "filters");
        if ((st = chain_from_json(fj, &chain, &bad)) != VV_OK) {
            char msg[512], ip[PATH_MAX_LEN];
            snprintf(msg, sizeof msg, "%s", vv_error_message());
            free(full);
            if (bad >= 0)
                vv_scene_path_index(ip, kp, (size_t)bad);
            return vv_scene_serr(c, bad >= 0 ? ip : kp, "%s", msg);
        }
        double o3[3] = {origin.x, origin.y, origin.z}, s3[3] = {spacing.x, spacing.y, spacing.z};
        vv_filter_options fo;
        vv_filter_options_init(&fo);
        if (c->progress)
            fo.progress = *c->progress; /* and its cancel */
        st = vv_filter_load_cached(c->fcache, full, has_origin ? o3 : NULL, has_spacing ? s3 : NULL,
                                   chain, &fo, &vol);
    } else if (c->open && c->open->mode != VV_OPEN_WHOLE) {
        /* out of core where the file and the options allow (vv_open); a
         * file an earlier object opened out of core: its source, shared */
        const int level = c->open->load.level > 0 ? c->open->load.level : 0;
        scene_source *shared = find_source(c, full, time);
        vv_opened od;
        memset(&od, 0, sizeof od);
        if (shared) {
            od.source = vv_source_ref(shared->source);
            od.info.is_label = shared->is_label;
            st = VV_OK;
        } else {
            vv_open_options oo = *c->open;
            vv_load_options_init(&oo.load);
            oo.load.time = time;
            vv_error_clear();
            st = vv_open(&od, full, &oo);
            if (st == VV_OK && od.kind != 0)
                st = vv_error_set(VV_ERR_FORMAT, "%s: not a volume file", full);
        }
        if (st == VV_OK && (vol = vv_source_volume(od.source))) {
            vv_volume_ref(vol);
            n_levels = od.info.n_levels;
        } else if (st == VV_OK && (st = vv_source_proxy(od.source, level, &vol)) == VV_OK) {
            const vv_volume *h0 = vv_source_level(od.source, 0);
            source = vv_source_ref(od.source);
            source_level = level;
            for (int k = 0; k < 3; k++) /* a "spacing" is the file's, of its level 0 */
                scale[k] = vol->spacing[k] / h0->spacing[k];
            if (!shared)
                keep_source(c, full, time, source, od.info.is_label);
        }
        is_label = st == VV_OK && od.info.is_label;
        vv_opened_clear(&od);
    } else {
        vv_load_options lo;
        vv_load_options_init(&lo);
        lo.time = time;
        vv_load_info li;
        memset(&li, 0, sizeof li);
        lo.info = &li;
        vv_error_clear();
        st = vv_volume_load(&vol, full, &lo);
        is_label = st == VV_OK && li.is_label;
        n_levels = li.n_levels;
    }
    if (st != VV_OK) {
        vv_filter_chain_free(chain);
        free(full);
        int line, col;
        vv_scene_path_key(kp, op, fj ? "filters" : time > 0 ? "time" : "file");
        vv_scene_locate(c, kp, &line, &col);
        return vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, kp);
    }
    /* a file out of core places itself: a scene's origin and spacing must be
     * its own (a saved session gives them back, equal up to rounding) */
    for (int k = 0; source && k < 3 && (has_origin || has_spacing); k++) {
        const double o = k == 0 ? origin.x : k == 1 ? origin.y : origin.z;
        const double sp = (k == 0 ? spacing.x : k == 1 ? spacing.y : spacing.z) * scale[k];
        if ((has_origin &&
             fabs(o - vol->origin[k]) > 1e-9 * (fabs(vol->origin[k]) + vol->spacing[k])) ||
            (has_spacing && fabs(sp - vol->spacing[k]) > 1e-9 * vol->spacing[k])) {
            vv_source_free(source);
            vv_volume_free(vol);
            vv_filter_chain_free(chain);
            free(full);
            vv_scene_path_key(kp, op, has_origin ? "origin" : "spacing");
            return vv_scene_serr(c, kp,
                                 "object '%s': out of core its file's own origin and spacing "
                                 "place it; leave out \"origin\" and \"spacing\" (\"position\" "
                                 "and \"scale\" move it)",
                                 name ? name : file);
        }
    }
    if (source)
        has_origin = has_spacing = 0;
    /* the volume is freshly loaded and ours alone, so overriding is safe (a
     * filtered one is shared with the cache and already has them) */
    if (has_origin && !fj) {
        vol->origin[0] = origin.x;
        vol->origin[1] = origin.y;
        vol->origin[2] = origin.z;
    }
    if (has_spacing && !fj) { /* scaled for a loader's proxy */
        vol->spacing[0] = spacing.x * scale[0];
        vol->spacing[1] = spacing.y * scale[1];
        vol->spacing[2] = spacing.z * scale[2];
    }
    char defname[VV_NAME_MAX];
    vv_scene_name_from_file(defname, file);
    vv_object *o = NULL;
    st = vv_object_new_volume(&o, vol, name ? name : defname);
    vv_volume_free(vol);
    if (st == VV_OK && source && (st = vv_object_attach_source(o, source, source_level)) != VV_OK) {
        vv_object_free(o);
        o = NULL;
    }
    vv_source_free(source);
    if (st != VV_OK) {
        vv_filter_chain_free(chain);
        free(full);
        return vv_error_prefix(st, "%s: %s", c->path, op);
    }
    o->geometry.source = full; /* kept for saving the scene again */
    o->time = time > 0 ? time : 0;
    if (chain && vv_filter_chain_length(chain) > 0 &&
        !(o->geometry.filters = vv_strdup(vv_filter_chain_text(chain)))) {
        vv_filter_chain_free(chain);
        vv_object_free(o);
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", c->path);
    }
    vv_filter_chain_free(chain);
    /* without an appearance of its own, what the file opened alone shows:
     * a pyramid read whole takes its coarsest level's histogram (out of
     * core the proxy is that level), the opacity unit of the level drawn */
    vv_volume *coarse = NULL;
    if (n_levels > 1 && !fj && !json_object_get(e, "transfer_function") &&
        !json_object_get(e, "segmentation") && !json_object_get(e, "tf2d")) {
        vv_open_options again;
        vv_open_options_init(&again);
        again.load.time = time;
        coarse = vv_scene_coarsest_level(full, NULL, &again);
    }
    const scene_file_defaults fd = {coarse,
                                    o->source ? vv_source_level(o->source, source_level) : NULL};
    st = vv_scene_parse_object_fields(c, e, op, o, &fd);
    vv_volume_free(coarse);
    /* an OME-Zarr label image (image-label) without an appearance of its
     * own shows as a label volume (a saved scene always names its
     * transfer_function, so a saved one keeps what it had) */
    if (st == VV_OK && is_label && !json_object_get(e, "segmentation") &&
        !json_object_get(e, "transfer_function"))
        o->segmentation = VV_SEG_LABELS;
    if (st == VV_OK)
        st = vv_scene_parse_effect_flags(c, e, op, o);
    if (st == VV_OK)
        st = vv_scene_parse_channels(c, e, op, full, o);
    if (st != VV_OK) {
        vv_object_free(o);
        return st;
    }
    return vv_world_add_object(w, o);
}
