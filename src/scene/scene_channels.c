/*
 * The channels of a volume object in a scene file (docs/scene-format.md):
 *
 *   {"type": "volume", "file": "cells.ome.tif", "blend": "maximum",
 *    "channels": [{"channel": 0, "name": "nuclei", "visible": true,
 *                  "transfer_function": {...}}, {"channel": 2},
 *                 {"channel": 3, "labels": true}, ...]}
 *
 * Each entry loads channel "channel" of the object's file (TIFF, DICOM);
 * the object's "origin" and "spacing" place every channel. An object read
 * out of core (its file a pyramid, the scene opened so) has its channels
 * opened out of core together, one source carrying them all.
 */
#include <jansson.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "core/json_internal.h"
#include "scene/scene_internal.h"
#include "volvis/io.h"

vv_status
vv_scene_parse_channels(const sctx *c, json_t *e, const char *op, const char *full, vv_object *o) {
    static const char *const keys[] = {"channel",           "name",   "visible",
                                       "transfer_function", "labels", NULL};
    char kp[PATH_MAX_LEN], ip[PATH_MAX_LEN], fp[PATH_MAX_LEN];
    json_t *arr = NULL;
    vv_status st = vv_scene_get_array(c, e, op, "channels", &arr);
    if (st != VV_OK)
        return st;
    const char *blend = NULL;
    if ((st = vv_scene_get_string(c, e, op, "blend", &blend)) != VV_OK)
        return st;
    vv_scene_path_key(kp, op, "blend");
    if (blend && !arr)
        return vv_scene_serr(c, kp, "\"blend\" needs \"channels\"");
    if (!arr)
        return VV_OK;
    vv_channel_blend rule = VV_BLEND_COMPOSITE;
    if (blend && vv_channel_blend_parse(blend, &rule) != VV_OK)
        return vv_scene_serr(c, kp, "unknown blend \"%s\" (composite, additive or maximum)", blend);
    vv_scene_path_key(kp, op, "channels");
    const size_t n = json_array_size(arr);
    if (n < 2 || n > VV_MAX_CHANNELS)
        return vv_scene_serr(c, kp, "%zu channels (2..%d)", n, VV_MAX_CHANNELS);
    if (json_object_get(e, "filters"))
        return vv_scene_serr(c, kp, "\"filters\" apply to an object of one channel");
    vv_volume *vols[VV_MAX_CHANNELS] = {NULL};
    const char *names[VV_MAX_CHANNELS] = {NULL};
    /* the object out of core (its file opened so: a pyramid): its channels
     * too, one source carrying them all (vv_object_set_channels_source) */
    const int ooc = o->source && vv_source_get_kind(o->source) == VV_SOURCE_PYRAMID && c->open;
    int index[VV_MAX_CHANNELS], visible[VV_MAX_CHANNELS], labels[VV_MAX_CHANNELS];
    json_t *tfs[VV_MAX_CHANNELS] = {NULL};
    for (size_t i = 0; i < n && st == VV_OK; i++) {
        json_t *ch = json_array_get(arr, i);
        vv_scene_path_index(ip, kp, i);
        if (!json_is_object(ch)) {
            st = vv_scene_serr(c, ip, "expected an object, got %s", vv_json_kind(ch));
            break;
        }
        visible[i] = 1;
        labels[i] = 0;
        index[i] = -1;
        if ((st = vv_scene_check_keys(c, ch, ip, keys)) != VV_OK ||
            (st = vv_scene_get_int_in(c, ch, ip, "channel", &index[i], 0, 1000000)) != VV_OK ||
            (st = vv_scene_get_string(c, ch, ip, "name", &names[i])) != VV_OK ||
            (st = vv_scene_get_bool(c, ch, ip, "visible", &visible[i])) != VV_OK ||
            (st = vv_scene_get_bool(c, ch, ip, "labels", &labels[i])) != VV_OK ||
            (st = vv_scene_get_object(c, ch, ip, "transfer_function", &tfs[i])) != VV_OK)
            break;
        if (index[i] < 0) {
            st = vv_scene_missing(c, ip, "channel", "the channel's index in the file, from 0");
            break;
        }
        if (ooc)
            continue; /* read below, every channel at once */
        vv_load_options lo;
        vv_load_options_init(&lo);
        lo.channel = index[i];
        lo.time = o->time; /* the object's time step (its "time") */
        if ((st = vv_volume_load(&vols[i], full, &lo)) != VV_OK) {
            int line, col;
            vv_scene_path_key(fp, ip, "channel");
            vv_scene_locate(c, fp, &line, &col);
            st = vv_error_prefix(st, "%s:%d:%d: %s", c->path, line, col, fp);
            break;
        }
        /* freshly loaded, ours alone: the object's volume places every channel */
        memcpy(vols[i]->origin, o->volume->origin, sizeof vols[i]->origin);
        memcpy(vols[i]->spacing, o->volume->spacing, sizeof vols[i]->spacing);
    }
    if (st == VV_OK && ooc) {
        vv_open_options oo = *c->open;
        vv_load_options_init(&oo.load);
        oo.load.time = o->time;
        oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
        oo.levels = 1;
        oo.n_channels = (int)n;
        memcpy(oo.channels, index, sizeof(int) * n);
        vv_opened od;
        vv_error_clear();
        st = vv_open(&od, full, &oo);
        if (st == VV_OK)
            st = vv_object_set_channels_source(
                o, od.source, c->open->load.level > 0 ? c->open->load.level : 0, names);
        vv_opened_clear(&od);
        if (st != VV_OK)
            st = vv_error_prefix(st, "%s: %s", c->path, kp);
    } else if (st == VV_OK && (st = vv_object_set_channels(o, (int)n, vols, names)) != VV_OK) {
        st = vv_error_prefix(st, "%s: %s", c->path, kp);
    }
    for (size_t i = 0; i < n && st == VV_OK; i++) {
        vv_channel *ch = &o->channels[i];
        ch->index = index[i];
        ch->visible = visible[i];
        if (labels[i] && vv_object_set_channel_labels(o, (int)i, 1) != VV_OK) {
            vv_scene_path_index(ip, kp, i);
            vv_scene_path_key(fp, ip, "labels");
            st = vv_scene_serr(c, fp, "channel %d of the file holds %s voxels; labels are integers",
                               index[i], vv_voxel_type_name(ch->volume->type));
            break;
        }
        if (tfs[i]) {
            vv_scene_path_index(ip, kp, i);
            vv_scene_path_key(fp, ip, "transfer_function");
            st = vv_scene_parse_tf(c, tfs[i], fp, ch->tf.opacity_unit_distance, &ch->tf);
        }
    }
    if (st == VV_OK)
        o->blend = rule;
    for (size_t i = 0; i < n; i++)
        vv_volume_free(vols[i]);
    return st;
}
