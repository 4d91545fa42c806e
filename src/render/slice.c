/*
 * Multiplanar reconstruction: slice planes in the volume's anatomical frame,
 * trilinear sampling of a volume object on them, the probe, and window and
 * level (include/volvis/slice.h).
 */
#include <math.h>
#include <string.h>

#include "volvis/slice.h"
#include "volvis/source.h"

static const char *const axis_names[] = {"axial", "coronal", "sagittal", "oblique"};

const char *
vv_slice_axis_name(vv_slice_axis axis) {
    if ((int)axis < 0 || (int)axis > VV_SLICE_OBLIQUE)
        return "unknown";
    return axis_names[axis];
}

vv_status
vv_slice_axis_parse(const char *name, vv_slice_axis *out) {
    for (int i = 0; name && i <= VV_SLICE_OBLIQUE; i++)
        if (!strcmp(name, axis_names[i])) {
            *out = (vv_slice_axis)i;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_INVALID,
                        "unknown slice orientation '%s' (axial, coronal, sagittal, oblique)",
                        name ? name : "(null)");
}

/* The World directions of patient Right, Anterior and Superior; for an
 * unknown frame the World's axes. */
static void
frame_axes(vv_space space, vv_vec3 *r, vv_vec3 *a, vv_vec3 *s) {
    double f = space == VV_SPACE_LPS ? -1.0 : 1.0;
    *r = vv_vec3_make(f, 0, 0);
    *a = vv_vec3_make(0, f, 0);
    *s = vv_vec3_make(0, 0, 1);
}

/* The label of world direction @p d: the anatomical direction or axis it
 * is nearest to. */
static void
direction_label(vv_space space, vv_vec3 d, char out[4]) {
    vv_vec3 ax[3];
    frame_axes(space, &ax[0], &ax[1], &ax[2]);
    static const char *const anat[3][2] = {{"R", "L"}, {"A", "P"}, {"S", "I"}};
    static const char *const world[3][2] = {{"+x", "-x"}, {"+y", "-y"}, {"+z", "-z"}};
    int best = 0;
    double bv = 0;
    for (int k = 0; k < 3; k++) {
        double c = vv_vec3_dot(d, ax[k]);
        if (fabs(c) > fabs(bv)) {
            bv = c;
            best = k;
        }
    }
    const char *l = space == VV_SPACE_UNKNOWN ? world[best][bv < 0] : anat[best][bv < 0];
    strncpy(out, l, 3);
    out[3] = '\0';
}

static void
set_edges(vv_slice_plane *p, vv_space space) {
    direction_label(space, p->right, p->edge[0]);
    direction_label(space, vv_vec3_scale(p->right, -1), p->edge[1]);
    direction_label(space, p->up, p->edge[2]);
    direction_label(space, vv_vec3_scale(p->up, -1), p->edge[3]);
}

static int
finite3(vv_vec3 v) {
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static vv_status
check_image(int width, int height, double pixel) {
    if (width < 1 || height < 1 || !(pixel > 0) || !isfinite(pixel))
        return vv_error_set(VV_ERR_INVALID, "slice: image %dx%d at %g world units a pixel", width,
                            height, pixel);
    return VV_OK;
}

vv_status
vv_slice_plane_standard(vv_slice_plane *out, vv_slice_axis axis, vv_space space, vv_vec3 through,
                        int width, int height, double pixel) {
    if (!out || (int)axis < VV_SLICE_AXIAL || (int)axis > VV_SLICE_SAGITTAL)
        return vv_error_set(VV_ERR_INVALID, "slice: not a standard orientation: %s",
                            vv_slice_axis_name(axis));
    if (!finite3(through))
        return vv_error_set(VV_ERR_INVALID, "slice: the point is not finite");
    vv_status s = check_image(width, height, pixel);
    if (s != VV_OK)
        return s;
    vv_vec3 r, a, sup;
    frame_axes(space, &r, &a, &sup);
    vv_slice_plane p;
    memset(&p, 0, sizeof p);
    p.axis = axis;
    if (space == VV_SPACE_UNKNOWN) {
        /* the World's own axes, not mirrored */
        static const double rt[3][3] = {{1, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        static const double upv[3][3] = {{0, 1, 0}, {0, 0, 1}, {0, 0, 1}};
        p.right = vv_vec3_make(rt[axis][0], rt[axis][1], rt[axis][2]);
        p.up = vv_vec3_make(upv[axis][0], upv[axis][1], upv[axis][2]);
    } else if (axis == VV_SLICE_AXIAL) { /* from the feet */
        p.right = vv_vec3_scale(r, -1);
        p.up = a;
    } else if (axis == VV_SLICE_CORONAL) { /* from the front */
        p.right = vv_vec3_scale(r, -1);
        p.up = sup;
    } else { /* sagittal, from the patient's left: anterior on the left */
        p.right = vv_vec3_scale(a, -1);
        p.up = sup;
    }
    p.center = through;
    p.pixel = pixel;
    p.width = width;
    p.height = height;
    set_edges(&p, space);
    *out = p;
    return VV_OK;
}

vv_status
vv_slice_plane_oblique(vv_slice_plane *out, vv_space space, vv_vec3 point, vv_vec3 normal,
                       int width, int height, double pixel) {
    double ln = vv_vec3_length(normal);
    if (!out || !finite3(point) || !finite3(normal) || !(ln > 0))
        return vv_error_set(VV_ERR_INVALID, "slice: an oblique plane needs a point and a normal");
    vv_status s = check_image(width, height, pixel);
    if (s != VV_OK)
        return s;
    vv_vec3 n = vv_vec3_scale(normal, 1.0 / ln);
    vv_vec3 r, a, sup;
    frame_axes(space, &r, &a, &sup);
    vv_vec3 up = vv_vec3_sub(sup, vv_vec3_scale(n, vv_vec3_dot(sup, n)));
    if (vv_vec3_length(up) < 1e-6)
        up = vv_vec3_sub(a, vv_vec3_scale(n, vv_vec3_dot(a, n)));
    up = vv_vec3_normalize(up);
    vv_slice_plane p;
    memset(&p, 0, sizeof p);
    p.axis = VV_SLICE_OBLIQUE;
    p.up = up;
    p.right = vv_vec3_normalize(vv_vec3_cross(up, n)); /* right x up = n */
    p.center = point;
    p.pixel = pixel;
    p.width = width;
    p.height = height;
    set_edges(&p, space);
    *out = p;
    return VV_OK;
}

vv_vec3
vv_slice_plane_normal(const vv_slice_plane *p) {
    return vv_vec3_normalize(vv_vec3_cross(p->right, p->up));
}

void
vv_slice_plane_fit(vv_slice_plane *p, vv_box box, double margin) {
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int c = 0; c < 8; c++) {
        vv_vec3 q = vv_vec3_make(c & 1 ? box.max.x : box.min.x, c & 2 ? box.max.y : box.min.y,
                                 c & 4 ? box.max.z : box.min.z);
        vv_vec3 d = vv_vec3_sub(q, p->center);
        double u = vv_vec3_dot(d, p->right), v = vv_vec3_dot(d, p->up);
        lo[0] = fmin(lo[0], u);
        hi[0] = fmax(hi[0], u);
        lo[1] = fmin(lo[1], v);
        hi[1] = fmax(hi[1], v);
    }
    if (!(hi[0] >= lo[0]) || !(hi[1] >= lo[1]) || !isfinite(hi[0] - lo[0]) ||
        !isfinite(hi[1] - lo[1]))
        return;
    p->center = vv_vec3_add(p->center, vv_vec3_add(vv_vec3_scale(p->right, 0.5 * (lo[0] + hi[0])),
                                                   vv_vec3_scale(p->up, 0.5 * (lo[1] + hi[1]))));
    double room = 1.0 - 2.0 * (margin > 0 && margin < 0.45 ? margin : 0.0);
    double px = fmax((hi[0] - lo[0]) / (p->width * room), (hi[1] - lo[1]) / (p->height * room));
    if (px > 0 && isfinite(px))
        p->pixel = px;
}

vv_vec3
vv_slice_plane_to_world(const vv_slice_plane *p, double x, double y) {
    double u = (x - 0.5 * p->width) * p->pixel, v = (0.5 * p->height - y) * p->pixel;
    return vv_vec3_add(p->center, vv_vec3_add(vv_vec3_scale(p->right, u), vv_vec3_scale(p->up, v)));
}

void
vv_slice_plane_from_world(const vv_slice_plane *p, vv_vec3 w, double *x, double *y, double *depth) {
    vv_vec3 d = vv_vec3_sub(w, p->center);
    *x = vv_vec3_dot(d, p->right) / p->pixel + 0.5 * p->width;
    *y = 0.5 * p->height - vv_vec3_dot(d, p->up) / p->pixel;
    if (depth)
        *depth = vv_vec3_dot(d, vv_slice_plane_normal(p));
}

/* World-to-index matrix of the object's volume; 0 when it cannot be inverted. */
static int
world_to_index(const vv_object *obj, vv_mat4 *out) {
    int ok = 0;
    *out = vv_mat4_inverse(vv_object_index_to_world(obj), &ok);
    return ok;
}

double
vv_slice_step(const vv_object *obj, vv_vec3 normal) {
    vv_mat4 m;
    if (!obj || !obj->volume || !world_to_index(obj, &m))
        return 0.0;
    vv_vec3 n = vv_vec3_normalize(normal);
    vv_vec3 d = vv_vec3_sub(vv_mat4_mul_point(m, n), vv_mat4_mul_point(m, vv_vec3_make(0, 0, 0)));
    double big = fmax(fabs(d.x), fmax(fabs(d.y), fabs(d.z)));
    return big > 0 && isfinite(big) ? 1.0 / big : 0.0;
}

/* The trilinear value at continuous index (x, y, z), NaN outside the
 * node-centred box (with a tolerance of 1e-6 voxel for rounding). */
static float
sample_inside(const vv_volume *v, double x, double y, double z, int nearest) {
    const double e = 1e-6;
    if (!(x >= -e && y >= -e && z >= -e && x <= v->dims[0] - 1 + e && y <= v->dims[1] - 1 + e &&
          z <= v->dims[2] - 1 + e))
        return NAN;
    if (nearest) /* labels: the nearest voxel's, never a blend of two ids */
        return (float)vv_volume_get(v, (int)lrint(x < 0 ? 0 : x), (int)lrint(y < 0 ? 0 : y),
                                    (int)lrint(z < 0 ? 0 : z));
    return vv_volume_sample_index(v, x, y, z);
}

/* Samples @p v (the object's volume or one of its channels: the same
 * grid) on plane @p p through the object's placement; @p nearest: the
 * nearest voxel's value (a label channel), else trilinear. */
static vv_status
sample_volume(const vv_object *obj, const vv_volume *v, const vv_slice_plane *p, int nearest,
              float *values) {
    vv_status s = check_image(p->width, p->height, p->pixel);
    if (s != VV_OK)
        return s;
    vv_mat4 m;
    if (!world_to_index(obj, &m))
        return vv_error_set(VV_ERR_INVALID, "slice: %s: the object's transform is singular",
                            obj->name);
    vv_vec3 o = vv_mat4_mul_point(m, vv_vec3_make(0, 0, 0));
    vv_vec3 dx = vv_vec3_sub(vv_mat4_mul_point(m, vv_vec3_scale(p->right, p->pixel)), o);
    const int w = p->width, h = p->height;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < h; y++) {
        /* exact per pixel from the row start: the same values for any threads */
        vv_vec3 r0 = vv_mat4_mul_point(m, vv_slice_plane_to_world(p, 0.5, y + 0.5));
        float *row = values + (size_t)y * w;
        for (int x = 0; x < w; x++)
            row[x] = sample_inside(v, r0.x + x * dx.x, r0.y + x * dx.y, r0.z + x * dx.z, nearest);
    }
    return VV_OK;
}

/* ---- an object out of core: its file sliced ------------------------------------------- */

/* Object @p obj with volume @p v instead (a shallow copy: nothing in it is
 * released, and it has no source, so slicing it reads @p v). */
static vv_object
with_volume(const vv_object *obj, const vv_volume *v) {
    vv_object o = *obj;
    o.volume = (vv_volume *)v;
    o.source = NULL;
    o.n_channels = 0;
    o.channels = NULL;
    return o;
}

/* The box lo .. hi of level @p L of @p src holding world points @p pts (n
 * of them) with @p margin voxels more each side; 0 when the points lie
 * outside the level. */
static int
level_box(vv_source *src, const vv_object *obj, int L, const vv_vec3 *pts, int n, int margin,
          int lo[3], int hi[3]) {
    const vv_volume *h = vv_source_level(src, L);
    const vv_object geo = with_volume(obj, h);
    int ok = 0;
    const vv_mat4 w2i = vv_mat4_inverse(vv_object_index_to_world(&geo), &ok);
    if (!ok)
        return 0;
    double a[3] = {INFINITY, INFINITY, INFINITY}, b[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < n; i++) {
        const vv_vec3 q = vv_mat4_mul_point(w2i, pts[i]);
        const double c[3] = {q.x, q.y, q.z};
        for (int k = 0; k < 3; k++) {
            a[k] = fmin(a[k], c[k]);
            b[k] = fmax(b[k], c[k]);
        }
    }
    for (int k = 0; k < 3; k++) {
        if (!isfinite(a[k]) || !isfinite(b[k]))
            return 0;
        lo[k] = (int)fmax(0, floor(a[k]) - margin);
        hi[k] = (int)fmin(h->dims[k] - 1, ceil(b[k]) + margin);
        if (lo[k] > hi[k])
            return 0;
    }
    return 1;
}

/* Box lo .. hi of level @p L of @p src, read (through the source's cache)
 * and placed in the world: its origin that of its first voxel. */
static vv_status
read_level_box(vv_source *src, int L, const int lo[3], const int hi[3], vv_volume **out) {
    const vv_volume *h = vv_source_level(src, L);
    vv_volume *v = NULL;
    vv_status s = vv_source_read_box(src, L, lo, hi, &v);
    if (s != VV_OK)
        return s;
    if (lo[0] != 0 || lo[1] != 0 || lo[2] != 0) /* else perhaps the level itself: shared */
        for (int r = 0; r < 3; r++)             /* its origin: the level's voxel lo */
            for (int k = 0; k < 3; k++)
                v->origin[r] += h->direction[3 * r + k] * h->spacing[k] * lo[k];
    *out = v;
    return VV_OK;
}

/* Plane @p p of object @p obj out of core sampled from the coarsest level of
 * its file whose voxel is at most a pixel (level 0 at worst; a coarser one
 * when that box would take more than a quarter of the cache's limit): the
 * box the plane crosses, read through the source's cache. */
static vv_status
sample_source(vv_source *src, const vv_object *obj, const vv_slice_plane *p, float *values) {
    const int levels = vv_source_levels(src);
    int L = levels - 1;
    for (; L > 0; L--) {
        const vv_object geo = with_volume(obj, vv_source_level(src, L));
        const vv_mat4 m = vv_object_index_to_world(&geo);
        double edge = INFINITY;
        for (int k = 0; k < 3; k++)
            edge = fmin(
                edge, sqrt(m.m[0][k] * m.m[0][k] + m.m[1][k] * m.m[1][k] + m.m[2][k] * m.m[2][k]));
        if (edge <= p->pixel)
            break;
    }
    const vv_cache *cache = vv_source_cache(src);
    const double most = (double)vv_cache_limit(cache ? cache : vv_cache_process()) / 4;
    const double hw = p->width * p->pixel / 2, hh = p->height * p->pixel / 2;
    vv_vec3 pts[4];
    for (int i = 0; i < 4; i++)
        pts[i] = vv_vec3_add(p->center, vv_vec3_add(vv_vec3_scale(p->right, i & 1 ? hw : -hw),
                                                    vv_vec3_scale(p->up, i & 2 ? hh : -hh)));
    for (; L < levels; L++) {
        int lo[3], hi[3];
        if (!level_box(src, obj, L, pts, 4, 1, lo, hi)) {
            /* the plane misses the volume: nothing to show */
            for (size_t i = 0; i < (size_t)p->width * p->height; i++)
                values[i] = NAN;
            return VV_OK;
        }
        const double bytes = (double)(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) *
                             (hi[2] - lo[2] + 1) *
                             (double)vv_voxel_type_size(vv_source_level(src, L)->type);
        if (bytes > most && L + 1 < levels)
            continue;
        vv_volume *v = NULL;
        vv_status s = read_level_box(src, L, lo, hi, &v);
        if (s != VV_OK)
            return s;
        const vv_object o = with_volume(obj, v);
        s = vv_slice_sample(&o, p, values);
        vv_volume_free(v);
        return s;
    }
    return vv_error_set(VV_ERR_LIMIT,
                        "slice: %s: even the coarsest level's box is over the "
                        "cache's limit",
                        obj->name);
}

/* The value of object @p obj out of core at world point @p c from level 0
 * of its file (a box of 4^3 voxels around it), its level-0 voxel index in
 * @p ijk; NaN outside or when it cannot be read. */
static double
probe_source(vv_source *src, const vv_object *obj, vv_vec3 c, double ijk[3]) {
    int lo[3], hi[3];
    if (!level_box(src, obj, 0, &c, 1, 2, lo, hi))
        return NAN;
    vv_volume *v = NULL;
    if (read_level_box(src, 0, lo, hi, &v) != VV_OK)
        return NAN;
    const vv_object o = with_volume(obj, v);
    double q[3];
    const double val = vv_slice_probe(&o, c, q);
    if (ijk)
        for (int k = 0; k < 3; k++)
            ijk[k] = q[k] + lo[k];
    vv_volume_free(v);
    return val;
}

/* 1 when @p obj shows a file out of core (its voxels come from its source). */
static int
out_of_core(const vv_object *obj) {
    return obj->type == VV_OBJECT_VOLUME && obj->source &&
           vv_source_get_kind(obj->source) != VV_SOURCE_MEMORY;
}

vv_status
vv_slice_sample(const vv_object *obj, const vv_slice_plane *p, float *values) {
    if (!obj || !p || !values || !obj->volume)
        return vv_error_set(VV_ERR_INVALID, "slice: %s",
                            !obj || !obj->volume ? "the object has no volume" : "NULL argument");
    if (out_of_core(obj))
        return sample_source(obj->source, obj, p, values);
    return sample_volume(obj, obj->volume, p, 0, values);
}

vv_status
vv_slice_sample_channel(const vv_object *obj, int channel, const vv_slice_plane *p, float *values) {
    if (!obj || !p || !values)
        return vv_error_set(VV_ERR_INVALID, "slice: NULL argument");
    if (channel < 0 || channel >= obj->n_channels || !obj->channels[channel].volume)
        return vv_error_set(VV_ERR_INVALID, "slice: %s has no channel %d (%d channels)", obj->name,
                            channel, obj->n_channels);
    return sample_volume(obj, obj->channels[channel].volume, p, obj->channels[channel].labels,
                         values);
}

void
vv_slice_blend_channels(const vv_object *obj, const float *const *values, size_t n, vv_vec3 outside,
                        uint8_t *rgba) {
    double peak[VV_MAX_CHANNELS];
    const int nc = obj && obj->n_channels <= VV_MAX_CHANNELS ? obj->n_channels : 0;
    for (int c = 0; c < nc; c++) {
        const vv_tf *tf = &obj->channels[c].tf;
        peak[c] = 0;
        for (int i = 0; i < tf->n_opacity; i++)
            peak[c] = fmax(peak[c], tf->opacity[i].opacity);
    }
    const uint8_t out[3] = {(uint8_t)lrint(fmin(fmax(outside.x, 0), 1) * 255),
                            (uint8_t)lrint(fmin(fmax(outside.y, 0), 1) * 255),
                            (uint8_t)lrint(fmin(fmax(outside.z, 0), 1) * 255)};
    for (size_t i = 0; i < n; i++) {
        uint8_t *px = rgba + 4 * i;
        double r = 0, g = 0, b = 0;
        int inside = 0;
        for (int c = 0; c < nc; c++) {
            const float v = values[c][i];
            if (v != v)
                continue;
            inside = 1;
            if (!obj->channels[c].visible)
                continue;
            if (obj->channels[c].labels) {
                /* a label: its colour at half strength over the other channels */
                const double l = floor(v + 0.5);
                if (l >= 1) {
                    vv_vec3 col = vv_label_color(vv_label_key(l));
                    r += 0.5 * col.x;
                    g += 0.5 * col.y;
                    b += 0.5 * col.z;
                }
                continue;
            }
            if (!(peak[c] > 0))
                continue;
            const vv_tf *tf = &obj->channels[c].tf;
            double k = vv_tf_eval_opacity(tf, v) / peak[c];
            if (k <= 0)
                continue;
            vv_vec3 col = vv_tf_eval_color(tf, v);
            r += k * col.x;
            g += k * col.y;
            b += k * col.z;
        }
        if (!inside) {
            px[0] = out[0];
            px[1] = out[1];
            px[2] = out[2];
        } else {
            px[0] = (uint8_t)lrint(fmin(r, 1) * 255);
            px[1] = (uint8_t)lrint(fmin(g, 1) * 255);
            px[2] = (uint8_t)lrint(fmin(b, 1) * 255);
        }
        px[3] = 255;
    }
}

double
vv_slice_probe(const vv_object *obj, vv_vec3 world, double ijk[3]) {
    vv_mat4 m;
    if (!obj || !obj->volume || !finite3(world))
        return NAN;
    if (out_of_core(obj))
        return probe_source(obj->source, obj, world, ijk);
    if (!world_to_index(obj, &m))
        return NAN;
    vv_vec3 q = vv_mat4_mul_point(m, world);
    if (ijk) {
        ijk[0] = q.x;
        ijk[1] = q.y;
        ijk[2] = q.z;
    }
    return sample_inside(obj->volume, q.x, q.y, q.z, 0);
}

void
vv_slice_auto_window(const vv_volume *v, double *window, double *level) {
    /* the foreground's quantiles: a background of a single value that fills most of
     * the volume (an MRI's surround) would otherwise take the window's lower half */
    double lo, hi;
    vv_volume_foreground_range(v, 0.01, 0.995, &lo, &hi);
    if (!(hi > lo) || !isfinite(lo) || !isfinite(hi)) {
        lo = v->range[0];
        hi = v->range[1];
    }
    if (!(hi > lo))
        hi = lo + 1.0;
    *window = hi - lo;
    *level = 0.5 * (lo + hi);
}

void
vv_slice_window_level(const float *values, size_t n, double window, double level, vv_vec3 outside,
                      uint8_t *rgba) {
    if (!(window > 0) || !isfinite(window))
        window = 0x1p-1022;
    double lo = level - 0.5 * window, k = 255.0 / window;
    uint8_t out[3] = {(uint8_t)lrint(fmin(fmax(outside.x, 0), 1) * 255),
                      (uint8_t)lrint(fmin(fmax(outside.y, 0), 1) * 255),
                      (uint8_t)lrint(fmin(fmax(outside.z, 0), 1) * 255)};
    for (size_t i = 0; i < n; i++) {
        uint8_t *px = rgba + 4 * i;
        float v = values[i];
        if (v != v) {
            px[0] = out[0];
            px[1] = out[1];
            px[2] = out[2];
        } else {
            double g = (v - lo) * k;
            uint8_t c = g <= 0 ? 0 : g >= 255 ? 255 : (uint8_t)lrint(g);
            px[0] = px[1] = px[2] = c;
        }
        px[3] = 255;
    }
}
