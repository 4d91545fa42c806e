/*
 * Object textures (the colour and texture of the VolVis paper's Object
 * Control, section 4): 2-D image textures mapped by planar, cylindrical or
 * spherical projection, and solid (3-D) textures, procedural or from a
 * second volume.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/model.h"

/* ---- image textures ------------------------------------------------------- */

vv_status
vv_texture_image_new(vv_texture_image **out, vv_image *image, const char *source) {
    if (!out) {
        vv_image_free(image);
        return vv_error_set(VV_ERR_INVALID, "texture: NULL output");
    }
    *out = NULL;
    if (!image)
        return vv_error_set(VV_ERR_INVALID, "texture: NULL image");
    vv_texture_image *t = calloc(1, sizeof *t);
    char *src = source ? vv_strdup(source) : NULL;
    if (!t || (source && !src)) {
        free(t);
        free(src);
        vv_image_free(image);
        return vv_error_set(VV_ERR_NOMEM, "texture: out of memory");
    }
    t->image = image;
    t->source = src;
    t->refcount = 1;
    *out = t;
    return VV_OK;
}

vv_texture_image *
vv_texture_image_ref(vv_texture_image *t) {
    if (t)
        atomic_fetch_add_explicit((_Atomic int *)&t->refcount, 1, memory_order_relaxed);
    return t;
}

void
vv_texture_image_free(vv_texture_image *t) {
    if (!t)
        return;
    if (atomic_fetch_sub_explicit((_Atomic int *)&t->refcount, 1, memory_order_acq_rel) > 1)
        return;
    vv_image_free(t->image);
    free(t->source);
    free(t);
}

/* x mod n in [0, n) for any integer x. */
static int
wrap(long x, int n) {
    long r = x % n;
    return (int)(r < 0 ? r + n : r);
}

/**
 * Bilinear colour at texture coordinates (u, v), repeat wrap: u = 0 is the
 * left edge of the image, v = 0 its top edge (row 0), one repeat per unit.
 */
static vv_vec3
texture_image_sample(const vv_texture_image *t, double u, double v) {
    if (!t || !t->image || !isfinite(u) || !isfinite(v))
        return vv_vec3_make(1, 1, 1);
    const vv_image *im = t->image;
    const int w = im->width, h = im->height;
    /* texel centres at (i + 0.5) / w: bilinear between the four nearest */
    double x = (u - floor(u)) * w - 0.5, y = (v - floor(v)) * h - 0.5;
    double fx = floor(x), fy = floor(y);
    double ax = x - fx, ay = y - fy;
    int x0 = wrap((long)fx, w), x1 = wrap((long)fx + 1, w);
    int y0 = wrap((long)fy, h), y1 = wrap((long)fy + 1, h);
    const float *p00 = im->rgba + 4 * ((size_t)y0 * w + x0);
    const float *p10 = im->rgba + 4 * ((size_t)y0 * w + x1);
    const float *p01 = im->rgba + 4 * ((size_t)y1 * w + x0);
    const float *p11 = im->rgba + 4 * ((size_t)y1 * w + x1);
    double c[3];
    for (int ch = 0; ch < 3; ch++) {
        double top = p00[ch] + ax * (p10[ch] - p00[ch]);
        double bot = p01[ch] + ax * (p11[ch] - p01[ch]);
        c[ch] = top + ay * (bot - top);
    }
    return vv_vec3_make(c[0], c[1], c[2]);
}

/* ---- projections ---------------------------------------------------------- */

void
vv_texture_map_init(vv_texture_map *m) {
    if (!m)
        return;
    memset(m, 0, sizeof *m);
    m->projection = VV_TEXTURE_PLANAR;
    m->axis = vv_vec3_make(0, 0, 1);
    m->scale[0] = m->scale[1] = 1.0;
}

/* The frame U, V, W of a projection axis (docs in model.h). */
static void
texture_frame(vv_vec3 axis, vv_vec3 *U, vv_vec3 *V, vv_vec3 *W) {
    vv_vec3 w = vv_vec3_normalize(axis);
    if (!(vv_vec3_length(w) > 0.5))
        w = vv_vec3_make(0, 0, 1);
    vv_vec3 r = fabs(w.x) < 0.9 ? vv_vec3_make(1, 0, 0) : vv_vec3_make(0, 1, 0);
    vv_vec3 u = vv_vec3_normalize(vv_vec3_sub(r, vv_vec3_scale(w, vv_vec3_dot(r, w))));
    *U = u;
    *V = vv_vec3_cross(w, u);
    *W = w;
}

/** Texture coordinates (u, v) of object point @p q (before wrapping). */
static void
texture_map_uv(const vv_texture_map *m, vv_vec3 q, double *u, double *v) {
    vv_vec3 U, V, W;
    texture_frame(m->axis, &U, &V, &W);
    vv_vec3 d = vv_vec3_sub(q, m->center);
    double du = vv_vec3_dot(d, U), dv = vv_vec3_dot(d, V), dw = vv_vec3_dot(d, W);
    double s, t;
    switch (m->projection) {
    case VV_TEXTURE_CYLINDRICAL:
    case VV_TEXTURE_SPHERICAL: {
        double a = atan2(dv, du);
        if (a < 0)
            a += 2 * M_PI;
        s = a / (2 * M_PI);
        if (m->projection == VV_TEXTURE_CYLINDRICAL) {
            t = dw;
        } else {
            double len = vv_vec3_length(d);
            double c = len > 0 ? dw / len : 1.0;
            c = c > 1 ? 1 : c < -1 ? -1 : c;
            t = acos(c) / M_PI;
        }
        break;
    }
    case VV_TEXTURE_PLANAR:
    default:
        s = du;
        t = dv;
        break;
    }
    *u = m->scale[0] * s;
    *v = m->scale[1] * t;
}

vv_vec3
vv_texture_map_eval(const vv_texture_map *m, vv_vec3 q) {
    if (!m || !m->image)
        return vv_vec3_make(1, 1, 1);
    double u, v;
    texture_map_uv(m, q, &u, &v);
    return texture_image_sample(m->image, u, v);
}

static const char *const projection_names[] = {"planar", "cylindrical", "spherical"};

const char *
vv_texture_projection_name(vv_texture_projection p) {
    return (int)p >= 0 && (int)p < 3 ? projection_names[p] : "unknown";
}

vv_status
vv_texture_projection_parse(const char *name, vv_texture_projection *out) {
    for (int i = 0; name && i < 3; i++)
        if (strcmp(name, projection_names[i]) == 0) {
            *out = (vv_texture_projection)i;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_INVALID,
                        "unknown projection \"%s\"; expected planar, cylindrical or spherical",
                        name ? name : "(null)");
}

void
vv_object_set_texture_image(vv_object *obj, vv_texture_image *image) {
    if (!obj)
        return;
    vv_texture_image_ref(image);
    vv_texture_image_free(obj->texture.image);
    obj->texture.image = image;
}

/* ---- solid textures ------------------------------------------------------- */

void
vv_solid_texture_init(vv_solid_texture *s) {
    if (!s)
        return;
    memset(s, 0, sizeof *s);
    s->color0 = vv_vec3_make(0, 0, 0);
    s->color1 = vv_vec3_make(1, 1, 1);
    s->period = 1.0;
    s->axis = vv_vec3_make(0, 0, 1);
    s->seed = 1;
}

void
vv_solid_texture_clear(vv_solid_texture *s) {
    if (!s)
        return;
    vv_volume_free(s->volume);
    free(s->source);
    vv_solid_texture_init(s);
}

vv_status
vv_solid_texture_set_volume(vv_solid_texture *s, vv_volume *volume, const char *source) {
    if (!s || !volume)
        return vv_error_set(VV_ERR_INVALID, "solid texture: NULL %s", s ? "volume" : "texture");
    char *src = NULL;
    if (source && !(src = vv_strdup(source)))
        return vv_error_set(VV_ERR_NOMEM, "solid texture: out of memory");
    vv_volume_ref(volume);
    vv_volume_free(s->volume);
    free(s->source);
    s->volume = volume;
    s->source = src;
    s->kind = VV_SOLID_TEXTURE_VOLUME;
    return VV_OK;
}

static const char *const solid_names[] = {"none", "checker3d", "wood", "marble", "volume"};

const char *
vv_solid_texture_kind_name(vv_solid_texture_kind k) {
    return (int)k >= 0 && (int)k < 5 ? solid_names[k] : "unknown";
}

/* A hash of a lattice point and the seed to [0, 1). */
static double
lattice(unsigned seed, long i, long j, long k) {
    uint64_t h = (uint64_t)seed * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)i * 0xBF58476D1CE4E5B9ull;
    h = (h ^ (h >> 31)) * 0x94D049BB133111EBull;
    h ^= (uint64_t)j * 0xD6E8FEB86659FD93ull;
    h = (h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull;
    h ^= (uint64_t)k * 0x9E3779B97F4A7C15ull;
    h = (h ^ (h >> 32)) * 0xD6E8FEB86659FD93ull;
    h ^= h >> 29;
    return (double)(h >> 11) * (1.0 / 9007199254740992.0);
}

/* Value noise in [0, 1]: lattice values blended with smoothstep weights. */
static double
value_noise(unsigned seed, double x, double y, double z) {
    double fx = floor(x), fy = floor(y), fz = floor(z);
    long i = (long)fx, j = (long)fy, k = (long)fz;
    double u = x - fx, v = y - fy, w = z - fz;
    u = u * u * (3 - 2 * u);
    v = v * v * (3 - 2 * v);
    w = w * w * (3 - 2 * w);
    double c[2][2];
    for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++) {
            double l0 = lattice(seed, i, j + a, k + b), l1 = lattice(seed, i + 1, j + a, k + b);
            c[b][a] = l0 + u * (l1 - l0);
        }
    double c0 = c[0][0] + v * (c[0][1] - c[0][0]);
    double c1 = c[1][0] + v * (c[1][1] - c[1][0]);
    return c0 + w * (c1 - c0);
}

/* Turbulence: four octaves of |2 noise - 1|, in [0, about 1]. */
static double
turbulence(unsigned seed, vv_vec3 p) {
    double sum = 0, amp = 0.5, f = 1;
    for (int o = 0; o < 4; o++) {
        sum += amp * fabs(2 * value_noise(seed + (unsigned)o, p.x * f, p.y * f, p.z * f) - 1);
        amp *= 0.5;
        f *= 2;
    }
    return sum / 0.9375;
}

vv_vec3
vv_solid_texture_eval(const vv_solid_texture *s, vv_vec3 q) {
    if (!s || s->kind == VV_SOLID_TEXTURE_NONE)
        return vv_vec3_make(1, 1, 1);
    double f = 0.0;
    const double per = s->period > 0 ? s->period : 1.0;
    vv_vec3 d = vv_vec3_scale(vv_vec3_sub(q, s->center), 1.0 / per);
    switch (s->kind) {
    case VV_SOLID_TEXTURE_CHECKER: {
        long n = (long)floor(d.x) + (long)floor(d.y) + (long)floor(d.z);
        f = (n & 1) ? 1.0 : 0.0;
        break;
    }
    case VV_SOLID_TEXTURE_WOOD: {
        vv_vec3 a = vv_vec3_normalize(s->axis);
        vv_vec3 radial = vv_vec3_sub(d, vv_vec3_scale(a, vv_vec3_dot(d, a)));
        double r = vv_vec3_length(radial) + s->turbulence * turbulence(s->seed, d);
        double x = r - floor(r);
        /* sharp dark late wood, wide light early wood */
        f = pow(0.5 + 0.5 * cos(2 * M_PI * x), 4.0);
        break;
    }
    case VV_SOLID_TEXTURE_MARBLE: {
        vv_vec3 a = vv_vec3_normalize(s->axis);
        double x = vv_vec3_dot(d, a) + s->turbulence * turbulence(s->seed, d);
        f = 0.5 + 0.5 * sin(2 * M_PI * x);
        break;
    }
    case VV_SOLID_TEXTURE_VOLUME: {
        float val = 0;
        const vv_volume *v = s->volume;
        if (!v || !vv_volume_sample_world(v, q, &val) || !(v->range[1] > v->range[0]))
            f = 0.0;
        else
            f = ((double)val - v->range[0]) / (v->range[1] - v->range[0]);
        f = f < 0 ? 0 : f > 1 ? 1 : f;
        break;
    }
    default:
        return vv_vec3_make(1, 1, 1);
    }
    return vv_vec3_lerp(s->color0, s->color1, f);
}
