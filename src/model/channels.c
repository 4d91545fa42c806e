/*
 * Multi-channel volume objects:
 * the channels of one object, their default colours and the microscopy
 * shorthand for a channel's transfer function (colour, contrast limits,
 * gamma). The ray caster and the ray tracer draw them (src/render/raycast/,
 * src/render/raytrace/: VV_RENDERER_CHANNELS).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "model/model_internal.h"
#include "volvis/model.h"

static const char *const blend_names[] = {"composite", "additive", "maximum"};

const char *
vv_channel_blend_name(vv_channel_blend b) {
    return (unsigned)b < sizeof blend_names / sizeof blend_names[0] ? blend_names[b] : NULL;
}

vv_status
vv_channel_blend_parse(const char *name, vv_channel_blend *out) {
    for (int i = 0; name && i < (int)(sizeof blend_names / sizeof blend_names[0]); i++)
        if (strcmp(name, blend_names[i]) == 0) {
            *out = (vv_channel_blend)i;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_INVALID, "blend: unknown rule '%s' (composite, additive or maximum)",
                        name ? name : "(null)");
}

vv_vec3
vv_channel_default_color(int index) {
    static const double c[10][3] = {
        {1, 0, 1},          {0, 1, 0},          {0, 1, 1},          {1, 1, 0},
        {0.90, 0.62, 0.00}, {0.34, 0.71, 0.91}, {0.00, 0.62, 0.45}, {0.84, 0.37, 0.00},
        {0.00, 0.45, 0.70}, {0.80, 0.47, 0.65},
    };
    int i = index < 0 ? 0 : index % 10;
    return vv_vec3_make(c[i][0], c[i][1], c[i][2]);
}

void
vv_channel_default_contrast(const vv_volume *v, double *lo, double *hi) {
    /* the background's level and noise from the quartiles: for Gaussian
     * noise of deviation s, q75 - q50 = 0.674 s, so 4.5 (q75 - q50) = 3 s */
    static const double q[3] = {0.5, 0.75, 0.9999};
    double qv[3];
    vv_volume_quantiles(v, 3, q, qv);
    const double q50 = qv[0], q75 = qv[1];
    *lo = q50 + 4.5 * (q75 - q50);
    *hi = qv[2];
    if (*hi > q50 && !(*lo < *hi))
        *lo = q50;
    if (!isfinite(*lo) || !isfinite(*hi) || !(*hi > *lo)) {
        *lo = isfinite(v->range[0]) ? v->range[0] : 0;
        *hi = isfinite(v->range[1]) && v->range[1] > *lo ? v->range[1] : *lo + 1;
    }
}

vv_status
vv_tf_set_contrast(vv_tf *tf, double lo, double hi, double gamma, double max_opacity, vv_vec3 color,
                   double unit_distance) {
    if (!tf)
        return vv_error_set(VV_ERR_INVALID, "contrast: NULL transfer function");
    if (!isfinite(lo) || !isfinite(hi) || !(hi > lo))
        return vv_error_set(VV_ERR_INVALID, "contrast: limits %g..%g (need lo < hi)", lo, hi);
    if (!(gamma >= 0.05 && gamma <= 20))
        return vv_error_set(VV_ERR_INVALID, "contrast: gamma %g outside [0.05, 20]", gamma);
    if (!(max_opacity >= 0 && max_opacity <= 1))
        return vv_error_set(VV_ERR_INVALID, "contrast: opacity %g outside [0, 1]", max_opacity);
    if (!(unit_distance > 0) || !isfinite(unit_distance))
        return vv_error_set(VV_ERR_INVALID, "contrast: unit distance %g (need > 0)", unit_distance);
    vv_tf_set_ramp(tf, lo, hi, max_opacity, color, unit_distance);
    if (gamma != 1.0) {
        tf->n_opacity = 0;
        for (int i = 0; i <= 8; i++) {
            double f = i / 8.0;
            tf->opacity[i].value = lo + f * (hi - lo);
            tf->opacity[i].opacity = max_opacity * pow(f, gamma);
        }
        tf->n_opacity = 9;
    }
    return VV_OK;
}

vv_status
vv_object_set_channels(vv_object *obj, int n, vv_volume *const *volumes, const char *const *names) {
    if (!obj || obj->type != VV_OBJECT_VOLUME)
        return vv_error_set(VV_ERR_INVALID, "channels: %s is not a volume object",
                            obj ? obj->name : "(null)");
    if (n < 2 || n > VV_MAX_CHANNELS)
        return vv_error_set(VV_ERR_INVALID, "channels: %d channels (2..%d)", n, VV_MAX_CHANNELS);
    if (!volumes)
        return vv_error_set(VV_ERR_INVALID, "channels: NULL volumes");
    for (int c = 0; c < n; c++) {
        if (!volumes[c])
            return vv_error_set(VV_ERR_INVALID, "channels: channel %d has no volume", c);
        const int *d = volumes[c]->dims, *d0 = volumes[0]->dims;
        if (d[0] != d0[0] || d[1] != d0[1] || d[2] != d0[2])
            return vv_error_set(VV_ERR_INVALID,
                                "channels: channel %d is %dx%dx%d, channel 0 is %dx%dx%d (every "
                                "channel of an object has the same size)",
                                c, d[0], d[1], d[2], d0[0], d0[1], d0[2]);
    }
    vv_channel *ch = calloc((size_t)n, sizeof *ch);
    if (!ch)
        return vv_error_set(VV_ERR_NOMEM, "channels: out of memory");
    for (int c = 0; c < n; c++) {
        const vv_volume *v = volumes[c];
        if (names && names[c])
            vv_model_copy_name(ch[c].name, names[c]);
        else
            snprintf(ch[c].name, sizeof ch[c].name, "channel %d", c);
        ch[c].visible = 1;
        ch[c].index = c;
        double lo, hi;
        vv_channel_default_contrast(v, &lo, &hi);
        /* the arguments are valid by construction */
        (void)vv_tf_set_contrast(&ch[c].tf, lo, hi, 1.0, 0.5, vv_channel_default_color(c),
                                 vv_tf_default_unit_distance(v));
    }
    for (int c = 0; c < n; c++)
        ch[c].volume = vv_volume_ref(volumes[c]);
    for (int c = 0; c < obj->n_channels; c++)
        vv_volume_free(obj->channels[c].volume);
    free(obj->channels);
    vv_volume_ref(volumes[0]);
    vv_volume_free(obj->volume);
    obj->volume = volumes[0];
    obj->channels = ch;
    obj->n_channels = n;
    vv_source_free(obj->source); /* in memory now */
    obj->source = NULL;
    return VV_OK;
}

vv_status
vv_object_set_channels_source(vv_object *obj, vv_source *source, int level,
                              const char *const *names) {
    if (!obj || obj->type != VV_OBJECT_VOLUME || !source)
        return vv_error_set(VV_ERR_INVALID, "channels: not a volume object, or no source");
    const int n = vv_source_channels(source);
    if (n < 2 || n > VV_MAX_CHANNELS)
        return vv_error_set(VV_ERR_INVALID,
                            "channels: %s carries %d channel%s (an object of channels needs 2 .. "
                            "%d)",
                            vv_path_basename(vv_source_path(source)), n, n == 1 ? "" : "s",
                            VV_MAX_CHANNELS);
    const vv_volume *h = vv_source_level(source, level);
    if (!h)
        return vv_error_set(VV_ERR_INVALID, "channels: %s has no level %d",
                            vv_path_basename(vv_source_path(source)), level);
    vv_volume *proxy[VV_MAX_CHANNELS] = {NULL};
    vv_status s = VV_OK;
    for (int c = 0; c < n && s == VV_OK; c++)
        s = vv_source_channel_proxy(source, c, level, &proxy[c]);
    vv_object o = *obj; /* the channels made on a copy: obj unchanged on error */
    o.n_channels = 0;
    o.channels = NULL;
    o.source = NULL;
    o.volume = NULL;
    if (s == VV_OK)
        s = vv_object_set_channels(&o, n, proxy, names);
    for (int c = 0; c < n; c++)
        vv_volume_free(proxy[c]);
    if (s != VV_OK) {
        for (int c = 0; c < o.n_channels; c++)
            vv_volume_free(o.channels[c].volume);
        free(o.channels);
        vv_volume_free(o.volume);
        return s;
    }
    /* opacity per the level's smallest voxel edge, not the proxy's */
    const double unit = vv_tf_default_unit_distance(h);
    for (int c = 0; c < n; c++)
        o.channels[c].tf.opacity_unit_distance = unit;
    for (int c = 0; c < obj->n_channels; c++)
        vv_volume_free(obj->channels[c].volume);
    free(obj->channels);
    vv_volume_free(obj->volume);
    vv_source_free(obj->source);
    obj->volume = o.volume;
    obj->channels = o.channels;
    obj->n_channels = o.n_channels;
    obj->source = vv_source_ref(source);
    return VV_OK;
}

vv_status
vv_object_replace_source(vv_object *obj, vv_source *source, int level) {
    if (!obj || obj->type != VV_OBJECT_VOLUME || !obj->source || !source || !obj->volume)
        return vv_error_set(VV_ERR_INVALID, "replace source: not a volume object out of core");
    const int n = obj->n_channels > 1 ? obj->n_channels : 1;
    if (vv_source_channels(source) != n)
        return vv_error_set(
            VV_ERR_INVALID, "replace source: %s: %s carries %d channel%s, the object has %d",
            obj->name, vv_path_basename(vv_source_path(source)), vv_source_channels(source),
            vv_source_channels(source) == 1 ? "" : "s", n);
    vv_volume *proxy[VV_MAX_CHANNELS] = {NULL};
    vv_status s = VV_OK;
    for (int c = 0; c < n && s == VV_OK; c++) {
        s = vv_source_channel_proxy(source, c, level, &proxy[c]);
        const vv_volume *old = n > 1 ? obj->channels[c].volume : obj->volume;
        if (s == VV_OK && old &&
            (proxy[c]->dims[0] != old->dims[0] || proxy[c]->dims[1] != old->dims[1] ||
             proxy[c]->dims[2] != old->dims[2]))
            s = vv_error_set(VV_ERR_INVALID,
                             "replace source: %s: channel %d's proxy is %dx%dx%d, the old one "
                             "%dx%dx%d",
                             obj->name, c, proxy[c]->dims[0], proxy[c]->dims[1], proxy[c]->dims[2],
                             old->dims[0], old->dims[1], old->dims[2]);
    }
    if (s != VV_OK) {
        for (int c = 0; c < n; c++)
            vv_volume_free(proxy[c]);
        return s;
    }
    for (int c = 0; c < obj->n_channels; c++) {
        vv_volume_free(obj->channels[c].volume);
        obj->channels[c].volume = vv_volume_ref(proxy[c]);
    }
    vv_volume_free(obj->volume);
    obj->volume = proxy[0]; /* the reference read */
    for (int c = 1; c < n; c++)
        vv_volume_free(proxy[c]); /* the channels hold their own */
    vv_source_ref(source);
    vv_source_free(obj->source);
    obj->source = source;
    return VV_OK;
}

void
vv_object_drop_source(vv_object *obj) {
    if (!obj || !obj->source)
        return;
    vv_source_free(obj->source);
    obj->source = NULL;
}

vv_status
vv_object_set_channel_labels(vv_object *obj, int c, int labels) {
    if (!obj || obj->type != VV_OBJECT_VOLUME || obj->n_channels < 2)
        return vv_error_set(VV_ERR_INVALID, "label channel: %s is not an object of channels",
                            obj ? obj->name : "(null)");
    if (c < 0 || c >= obj->n_channels)
        return vv_error_set(VV_ERR_INVALID, "label channel: %s has channels 0..%d, not %d",
                            obj->name, obj->n_channels - 1, c);
    if (labels != 0 && labels != 1)
        return vv_error_set(VV_ERR_INVALID, "label channel: %d (0 or 1)", labels);
    const vv_volume *v = obj->channels[c].volume;
    if (labels && v && (v->type == VV_F32 || v->type == VV_F64))
        return vv_error_set(VV_ERR_INVALID,
                            "label channel: channel %d ('%s') of %s holds %s voxels; labels are "
                            "integers",
                            c, obj->channels[c].name, obj->name, vv_voxel_type_name(v->type));
    obj->channels[c].labels = labels;
    return VV_OK;
}

vv_status
vv_object_replace_volumes(vv_object *obj, int n, vv_volume *const *volumes) {
    if (!obj || !volumes || obj->type != VV_OBJECT_VOLUME || !obj->volume)
        return vv_error_set(VV_ERR_INVALID, "replace volumes: not a volume object");
    int want = obj->n_channels > 0 ? obj->n_channels : 1;
    if (n != want)
        return vv_error_set(VV_ERR_INVALID,
                            "replace volumes: %s: %d volume%s given, the object has %d channel%s",
                            obj->name, n, n == 1 ? "" : "s", want, want == 1 ? "" : "s");
    for (int c = 0; c < n; c++) {
        const vv_volume *old = obj->n_channels > 0 ? obj->channels[c].volume : obj->volume;
        const vv_volume *v = volumes[c];
        if (!v || v->dims[0] != old->dims[0] || v->dims[1] != old->dims[1] ||
            v->dims[2] != old->dims[2])
            return vv_error_set(VV_ERR_INVALID,
                                "replace volumes: %s: channel %d's new volume is %s, the old one "
                                "%dx%dx%d",
                                obj->name, c, v ? "another size" : "missing", old->dims[0],
                                old->dims[1], old->dims[2]);
    }
    for (int c = 0; c < obj->n_channels; c++) {
        vv_volume_ref(volumes[c]);
        vv_volume_free(obj->channels[c].volume);
        obj->channels[c].volume = volumes[c];
    }
    vv_volume_ref(volumes[0]);
    vv_volume_free(obj->volume);
    obj->volume = volumes[0];
    vv_source_free(obj->source); /* in memory now */
    obj->source = NULL;
    return VV_OK;
}

int
vv_tf_get_contrast(const vv_tf *tf, double *lo, double *hi, double *gamma, double *max_opacity,
                   vv_vec3 *color) {
    if (!tf || tf->n_opacity < 2)
        return 0;
    const vv_tf_opacity_point *p = tf->opacity;
    const int n = tf->n_opacity;
    double top = 0;
    for (int i = 0; i < n; i++)
        top = fmax(top, p[i].opacity);
    int first_top = n - 1;
    for (int i = 0; i < n; i++)
        if (p[i].opacity >= top) {
            first_top = i;
            break;
        }
    const double l = p[0].value, h = p[first_top].value > l ? p[first_top].value : l + 1;
    /* gamma: the least-squares fit of log(opacity / top) = gamma log(f) over
     * the points strictly inside the ramp (1 for a straight ramp) */
    double sxy = 0, sxx = 0;
    for (int i = 1; i < first_top && top > 0; i++) {
        double f = (p[i].value - l) / (h - l);
        if (f > 0 && f < 1 && p[i].opacity > 0) {
            double x = log(f), y = log(p[i].opacity / top);
            sxy += x * y;
            sxx += x * x;
        }
    }
    double g = sxx > 0 ? sxy / sxx : 1.0;
    g = fmin(fmax(g, 0.05), 20);
    vv_vec3 col = vv_tf_eval_color(tf, h);
    if (lo)
        *lo = l;
    if (hi)
        *hi = h;
    if (gamma)
        *gamma = g;
    if (max_opacity)
        *max_opacity = top;
    if (color)
        *color = col;
    /* exact when vv_tf_set_contrast with these makes the same function */
    vv_tf same = *tf;
    if (vv_tf_set_contrast(&same, l, h, fabs(g - 1) < 1e-9 ? 1.0 : g, top, col,
                           tf->opacity_unit_distance > 0 ? tf->opacity_unit_distance : 1) !=
            VV_OK ||
        same.n_opacity != n || same.n_color != tf->n_color)
        return 0;
    for (int i = 0; i < n; i++)
        if (fabs(same.opacity[i].value - p[i].value) > 1e-9 * fmax(1, fabs(p[i].value)) ||
            fabs(same.opacity[i].opacity - p[i].opacity) > 1e-6)
            return 0;
    for (int i = 0; i < tf->n_color; i++)
        if (vv_vec3_length(vv_vec3_sub(same.color[i].color, tf->color[i].color)) > 1e-6)
            return 0;
    return 1;
}
