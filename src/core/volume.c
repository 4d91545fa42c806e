/* Rectilinear scalar volumes (see volvis/volume.h). */
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "core/internal.h"
#include "volvis/volume.h"

size_t
vv_voxel_type_size(vv_voxel_type t) {
    switch (t) {
    case VV_U8:
    case VV_I8:
        return 1;
    case VV_U16:
    case VV_I16:
        return 2;
    case VV_U32:
    case VV_I32:
    case VV_F32:
        return 4;
    case VV_F64:
        return 8;
    }
    return 0;
}

const char *
vv_unit_name(vv_unit u) {
    static const char *const names[] = {"m", "mm", "um", "ft", "in", "unknown", "nm"};
    return (unsigned)u <= VV_UNIT_LAST ? names[u] : "unknown";
}

const char *
vv_volume_length_unit(const vv_volume *v) {
    if (!v)
        return "units";
    if (v->unit != VV_UNIT_UNKNOWN)
        return vv_unit_name(v->unit);
    if (v->spacing[0] == 1 && v->spacing[1] == 1 && v->spacing[2] == 1)
        return "voxel units";
    return "units";
}

vv_unit
vv_unit_parse(const char *u) {
    static const struct {
        const char *name;
        vv_unit unit;
    } alias[] = {{"m", VV_UNIT_METER},
                 {"meter", VV_UNIT_METER},
                 {"meters", VV_UNIT_METER},
                 {"metre", VV_UNIT_METER},
                 {"metres", VV_UNIT_METER},
                 {"mm", VV_UNIT_MM},
                 {"millimeter", VV_UNIT_MM},
                 {"millimeters", VV_UNIT_MM},
                 {"millimetre", VV_UNIT_MM},
                 {"millimetres", VV_UNIT_MM},
                 {"um", VV_UNIT_MICRON},
                 {"micron", VV_UNIT_MICRON},
                 {"microns", VV_UNIT_MICRON},
                 {"micrometer", VV_UNIT_MICRON},
                 {"micrometers", VV_UNIT_MICRON},
                 {"micrometre", VV_UNIT_MICRON},
                 {"micrometres", VV_UNIT_MICRON},
                 {"\xc2\xb5m", VV_UNIT_MICRON}, /* micro sign */
                 {"\xce\xbcm", VV_UNIT_MICRON}, /* Greek mu (BigDataViewer, Fiji) */
                 {"nm", VV_UNIT_NM},
                 {"nanometer", VV_UNIT_NM},
                 {"nanometers", VV_UNIT_NM},
                 {"nanometre", VV_UNIT_NM},
                 {"nanometres", VV_UNIT_NM},
                 {"ft", VV_UNIT_FOOT},
                 {"foot", VV_UNIT_FOOT},
                 {"feet", VV_UNIT_FOOT},
                 {"in", VV_UNIT_INCH},
                 {"inch", VV_UNIT_INCH},
                 {"inches", VV_UNIT_INCH}};
    for (size_t i = 0; u && i < sizeof alias / sizeof alias[0]; i++)
        if (strcmp(u, alias[i].name) == 0)
            return alias[i].unit;
    return VV_UNIT_UNKNOWN;
}

static const char *const type_names[] = {"u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64"};

const char *
vv_voxel_type_name(vv_voxel_type t) {
    return (unsigned)t < 8 ? type_names[t] : "unknown";
}

vv_status
vv_voxel_type_parse(const char *name, vv_voxel_type *out) {
    static const struct {
        const char *name;
        vv_voxel_type t;
    } alias[] = {{"u8", VV_U8},       {"uint8", VV_U8},   {"uchar", VV_U8},   {"i8", VV_I8},
                 {"int8", VV_I8},     {"char", VV_I8},    {"u16", VV_U16},    {"uint16", VV_U16},
                 {"ushort", VV_U16},  {"i16", VV_I16},    {"int16", VV_I16},  {"short", VV_I16},
                 {"u32", VV_U32},     {"uint32", VV_U32}, {"uint", VV_U32},   {"i32", VV_I32},
                 {"int32", VV_I32},   {"int", VV_I32},    {"f32", VV_F32},    {"float", VV_F32},
                 {"float32", VV_F32}, {"f64", VV_F64},    {"double", VV_F64}, {"float64", VV_F64}};
    for (size_t i = 0; i < sizeof alias / sizeof alias[0]; i++)
        if (strcmp(name, alias[i].name) == 0) {
            *out = alias[i].t;
            return VV_OK;
        }
    return vv_error_set(VV_ERR_INVALID,
                        "unknown voxel type '%s' (u8, i8, u16, i16, u32, i32, f32, f64)", name);
}

vv_status
vv_volume_check_limits(const int dims[3], vv_voxel_type t, uint64_t *bytes) {
    for (int a = 0; a < 3; a++)
        if (dims[a] < 1 || dims[a] > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT, "volume size %d x %d x %d: axis %d is outside 1..%d",
                                dims[0], dims[1], dims[2], a, VV_VOLUME_MAX_DIM);
    size_t vs = vv_voxel_type_size(t);
    if (vs == 0)
        return vv_error_set(VV_ERR_INVALID, "invalid voxel type %d", (int)t);
    uint64_t n = (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2];
    if (n > VV_VOLUME_MAX_VOXELS)
        return vv_error_set(VV_ERR_LIMIT,
                            "volume size %d x %d x %d = %llu voxels is over the limit of %llu",
                            dims[0], dims[1], dims[2], (unsigned long long)n,
                            (unsigned long long)VV_VOLUME_MAX_VOXELS);
    uint64_t b = n * vs;
    if (b > VV_VOLUME_MAX_BYTES || b > (uint64_t)SIZE_MAX)
        return vv_error_set(VV_ERR_LIMIT,
                            "volume size %d x %d x %d %s = %llu bytes is over the limit of %llu",
                            dims[0], dims[1], dims[2], vv_voxel_type_name(t), (unsigned long long)b,
                            (unsigned long long)VV_VOLUME_MAX_BYTES);
    if (bytes)
        *bytes = b;
    return VV_OK;
}

vv_status
vv_volume_check_size(const int dims[3], vv_voxel_type t, uint64_t *bytes) {
    uint64_t b = 0;
    vv_status s = vv_volume_check_limits(dims, t, &b);
    if (s != VV_OK)
        return s;
    char what[96];
    snprintf(what, sizeof what, "volume of %d x %d x %d %s", dims[0], dims[1], dims[2],
             vv_voxel_type_name(t));
    if ((s = vv_memory_budget_check(b, what)) != VV_OK)
        return s;
    if (bytes)
        *bytes = b;
    return VV_OK;
}

/* vv_volume_set_allocator: set once at the start of volvis-reader. */
static void *(*data_alloc)(size_t bytes);
static void (*data_release)(void *user, void *data);

void
vv_volume_set_allocator(void *(*alloc)(size_t bytes), void (*release)(void *user, void *data)) {
    data_alloc = alloc;
    data_release = alloc ? release : NULL;
}

/* Zeroed voxels of @p bytes (calloc: the kernel's zero pages, untouched).
 * A volume of a few MiB or more asks for transparent huge pages over the
 * 2 MiB-aligned part of its block: where the kernel gives them only on
 * request (transparent_hugepage "madvise"), a decoder's first writes
 * otherwise fault a 4 KiB page at a time (a 512^3 u16 level: 65536 faults,
 * a fifth of its read). Advice only: refused, nothing changes. */
static void *
voxels_alloc(size_t bytes) {
    void *p = calloc(bytes, 1);
#ifdef MADV_HUGEPAGE
    const uintptr_t huge = (uintptr_t)2 << 20;
    if (p && bytes >= 2 * huge) {
        const uintptr_t a = ((uintptr_t)p + huge - 1) & ~(huge - 1),
                        b = ((uintptr_t)p + bytes) & ~(huge - 1);
        if (b > a)
            (void)madvise((void *)a, b - a, MADV_HUGEPAGE);
    }
#endif
    return p;
}

vv_status
vv_volume_new(vv_volume **out, const int dims[3], vv_voxel_type t) {
    *out = NULL;
    uint64_t bytes;
    vv_status s = vv_volume_check_size(dims, t, &bytes);
    if (s != VV_OK)
        return s;
    vv_volume *v = calloc(1, sizeof *v);
    if (!v)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    v->data = data_alloc ? data_alloc((size_t)bytes) : voxels_alloc((size_t)bytes);
    v->release = data_alloc ? data_release : NULL;
    if (!v->data) {
        free(v);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a volume of %llu bytes",
                            (unsigned long long)bytes);
    }
    memcpy(v->dims, dims, sizeof v->dims);
    for (int a = 0; a < 3; a++)
        v->spacing[a] = 1.0;
    v->direction[0] = v->direction[4] = v->direction[8] = 1.0;
    v->type = t;
    v->unit = VV_UNIT_UNKNOWN;
    v->data_origin = VV_ORIGIN_OTHER;
    v->modification = VV_MOD_ORIGINAL;
    v->refcount = 1;
    *out = v;
    return VV_OK;
}

/* The release of a wrapped volume whose caller frees the voxels itself. */
static void
release_nothing(void *user, void *data) {
    (void)user;
    (void)data;
}

vv_status
vv_volume_wrap(vv_volume **out, const int dims[3], vv_voxel_type t, void *data,
               void (*release)(void *user, void *data), void *user) {
    *out = NULL;
    if (!data)
        return vv_error_set(VV_ERR_INVALID, "vv_volume_wrap: no voxel data");
    vv_status s = vv_volume_check_size(dims, t, NULL);
    if (s != VV_OK)
        return s;
    vv_volume *v = calloc(1, sizeof *v);
    if (!v)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    memcpy(v->dims, dims, sizeof v->dims);
    for (int a = 0; a < 3; a++)
        v->spacing[a] = 1.0;
    v->direction[0] = v->direction[4] = v->direction[8] = 1.0;
    v->type = t;
    v->data = data;
    v->unit = VV_UNIT_UNKNOWN;
    v->data_origin = VV_ORIGIN_OTHER;
    v->modification = VV_MOD_ORIGINAL;
    v->refcount = 1;
    v->release = release ? release : release_nothing;
    v->release_user = user;
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

vv_volume *
vv_volume_ref(vv_volume *v) {
    if (v)
        atomic_fetch_add_explicit((_Atomic int *)&v->refcount, 1, memory_order_relaxed);
    return v;
}

void
vv_volume_free(vv_volume *v) {
    if (!v)
        return;
    if (atomic_fetch_sub_explicit((_Atomic int *)&v->refcount, 1, memory_order_acq_rel) > 1)
        return;
    if (v->release)
        v->release(v->release_user, v->data);
    else
        free(v->data);
    free(v);
}

uint64_t
vv_volume_voxel_count(const vv_volume *v) {
    return (uint64_t)v->dims[0] * (uint64_t)v->dims[1] * (uint64_t)v->dims[2];
}

/* Min and max in the voxel type itself (the compiler vectorizes integer
 * min/max; a conversion to double per voxel did not: 0.7 GB/s a thread).
 * Floats compare in their type; NaN compares false and is skipped. */
#define VV_RANGE_ACC(T, START_LO, START_HI)                                                        \
    do {                                                                                           \
        const T *q = (const T *)p;                                                                 \
        T l = (START_LO), h = (START_HI);                                                          \
        for (size_t i = 0; i < n; i++) {                                                           \
            T x = q[i];                                                                            \
            l = x < l ? x : l;                                                                     \
            h = x > h ? x : h;                                                                     \
        }                                                                                          \
        lo = (double)l;                                                                            \
        hi = (double)h;                                                                            \
    } while (0)

/* cloned for AVX2: its unsigned 16-bit min/max (vpminuw) are one
 * instruction for 16 voxels, where the SSE2 baseline has none and
 * emulates them; the readers run it over every row they copy */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void
vv_range_accumulate(vv_voxel_type type, const void *p, size_t n, double range[2]) {
    double lo = INFINITY, hi = -INFINITY;
    switch (type) {
    case VV_U8:
        VV_RANGE_ACC(uint8_t, UINT8_MAX, 0);
        break;
    case VV_I8:
        VV_RANGE_ACC(int8_t, INT8_MAX, INT8_MIN);
        break;
    case VV_U16:
        VV_RANGE_ACC(uint16_t, UINT16_MAX, 0);
        break;
    case VV_I16:
        VV_RANGE_ACC(int16_t, INT16_MAX, INT16_MIN);
        break;
    case VV_U32:
        VV_RANGE_ACC(uint32_t, UINT32_MAX, 0);
        break;
    case VV_I32:
        VV_RANGE_ACC(int32_t, INT32_MAX, INT32_MIN);
        break;
    case VV_F32:
        VV_RANGE_ACC(float, INFINITY, -INFINITY);
        break;
    case VV_F64:
        VV_RANGE_ACC(double, INFINITY, -INFINITY);
        break;
    }
    /* an integer piece's start values are the type's ends, which its voxels
     * may equal: only a piece of voxels widens the range */
    if (n) {
        range[0] = lo < range[0] ? lo : range[0];
        range[1] = hi > range[1] ? hi : range[1];
    }
}

void
vv_volume_set_range(vv_volume *v, const double range[2]) {
    double lo = range[0], hi = range[1];
    if (!(lo <= hi))
        lo = hi = 0;
    v->range[0] = lo;
    v->range[1] = hi;
    v->modified++;
}

/* Pieces of this many voxels at least, one at a time per thread. */
#define VV_RANGE_PIECE ((size_t)1 << 16)

void
vv_volume_update_range(vv_volume *v) {
    const size_t n = (size_t)vv_volume_voxel_count(v);
    const size_t es = vv_voxel_type_size(v->type);
    const int64_t pieces = (int64_t)((n + VV_RANGE_PIECE - 1) / VV_RANGE_PIECE);
    double range[2] = {INFINITY, -INFINITY};
#pragma omp parallel if (pieces > 1)
    {
        double mine[2] = {INFINITY, -INFINITY};
#pragma omp for schedule(static)
        for (int64_t p = 0; p < pieces; p++) {
            const size_t first = (size_t)p * VV_RANGE_PIECE;
            const size_t len = n - first < VV_RANGE_PIECE ? n - first : VV_RANGE_PIECE;
            vv_range_accumulate(v->type, (const unsigned char *)v->data + first * es, len, mine);
        }
#pragma omp critical(vv_volume_range)
        {
            range[0] = mine[0] < range[0] ? mine[0] : range[0];
            range[1] = mine[1] > range[1] ? mine[1] : range[1];
        }
    }
    vv_volume_set_range(v, range);
}

double
vv_volume_get(const vv_volume *v, int i, int j, int k) {
    size_t idx = ((size_t)k * (size_t)v->dims[1] + (size_t)j) * (size_t)v->dims[0] + (size_t)i;
    return vv_voxel_at(v, idx);
}

static double
clamp_round(double x, double lo, double hi) {
    if (!(x == x))
        return 0;
    x = nearbyint(x);
    return x < lo ? lo : x > hi ? hi : x;
}

void
vv_volume_set(vv_volume *v, int i, int j, int k, double value) {
    size_t idx = ((size_t)k * (size_t)v->dims[1] + (size_t)j) * (size_t)v->dims[0] + (size_t)i;
    switch (v->type) {
    case VV_U8:
        ((uint8_t *)v->data)[idx] = (uint8_t)clamp_round(value, 0, 255);
        break;
    case VV_I8:
        ((int8_t *)v->data)[idx] = (int8_t)clamp_round(value, -128, 127);
        break;
    case VV_U16:
        ((uint16_t *)v->data)[idx] = (uint16_t)clamp_round(value, 0, 65535);
        break;
    case VV_I16:
        ((int16_t *)v->data)[idx] = (int16_t)clamp_round(value, -32768, 32767);
        break;
    case VV_U32:
        ((uint32_t *)v->data)[idx] = (uint32_t)clamp_round(value, 0, 4294967295.0);
        break;
    case VV_I32:
        ((int32_t *)v->data)[idx] = (int32_t)clamp_round(value, -2147483648.0, 2147483647.0);
        break;
    case VV_F32:
        ((float *)v->data)[idx] = (float)value;
        break;
    case VV_F64:
        ((double *)v->data)[idx] = value;
        break;
    }
}

vv_mat4
vv_volume_index_to_world(const vv_volume *v) {
    vv_mat4 m = vv_mat4_identity();
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++)
            m.m[r][c] = v->direction[3 * r + c] * v->spacing[c];
        m.m[r][3] = v->origin[r];
    }
    return m;
}

vv_mat4
vv_volume_world_to_index(const vv_volume *v) {
    return vv_mat4_inverse(vv_volume_index_to_world(v), NULL);
}

vv_box
vv_volume_world_box(const vv_volume *v) {
    vv_box b = {{0, 0, 0}, {v->dims[0] - 1, v->dims[1] - 1, v->dims[2] - 1}};
    return vv_box_transform(b, vv_volume_index_to_world(v));
}

float
vv_volume_sample_index(const vv_volume *v, double x, double y, double z) {
    const double p[3] = {x, y, z};
    int i0[3], i1[3];
    double f[3];
    for (int a = 0; a < 3; a++) {
        double c = p[a];
        double mx = v->dims[a] - 1;
        if (!(c > 0))
            c = 0;
        if (c > mx)
            c = mx;
        double fl = floor(c);
        i0[a] = (int)fl;
        i1[a] = i0[a] + 1 < v->dims[a] ? i0[a] + 1 : i0[a];
        f[a] = c - fl;
    }
    double c00 = vv_volume_get(v, i0[0], i0[1], i0[2]) * (1 - f[0]) +
                 vv_volume_get(v, i1[0], i0[1], i0[2]) * f[0];
    double c10 = vv_volume_get(v, i0[0], i1[1], i0[2]) * (1 - f[0]) +
                 vv_volume_get(v, i1[0], i1[1], i0[2]) * f[0];
    double c01 = vv_volume_get(v, i0[0], i0[1], i1[2]) * (1 - f[0]) +
                 vv_volume_get(v, i1[0], i0[1], i1[2]) * f[0];
    double c11 = vv_volume_get(v, i0[0], i1[1], i1[2]) * (1 - f[0]) +
                 vv_volume_get(v, i1[0], i1[1], i1[2]) * f[0];
    double c0 = c00 * (1 - f[1]) + c10 * f[1];
    double c1 = c01 * (1 - f[1]) + c11 * f[1];
    return (float)(c0 * (1 - f[2]) + c1 * f[2]);
}

static int
inside_index(const vv_volume *v, vv_vec3 q) {
    const double eps = 1e-9;
    return q.x >= -eps && q.y >= -eps && q.z >= -eps && q.x <= v->dims[0] - 1 + eps &&
           q.y <= v->dims[1] - 1 + eps && q.z <= v->dims[2] - 1 + eps;
}

int
vv_volume_sample_world(const vv_volume *v, vv_vec3 p, float *value) {
    vv_vec3 q = vv_mat4_mul_point(vv_volume_world_to_index(v), p);
    if (!inside_index(v, q)) {
        *value = 0;
        return 0;
    }
    *value = vv_volume_sample_index(v, q.x, q.y, q.z);
    return 1;
}

int
vv_volume_gradient_world(const vv_volume *v, vv_vec3 p, vv_vec3 *gradient) {
    vv_vec3 q = vv_mat4_mul_point(vv_volume_world_to_index(v), p);
    if (!inside_index(v, q)) {
        *gradient = vv_vec3_make(0, 0, 0);
        return 0;
    }
    /* d/d(index) by central differences half a voxel apart, then to world:
     * grad_world = D^-T S^-1 grad_index; D is orthonormal so D^-T = D. */
    double gi[3];
    const double h = 0.5;
    for (int a = 0; a < 3; a++) {
        double qa[3] = {q.x, q.y, q.z}, qb[3] = {q.x, q.y, q.z};
        qa[a] -= h;
        qb[a] += h;
        double lo = fmax(qa[a], 0), hi = fmin(qb[a], v->dims[a] - 1);
        qa[a] = lo;
        qb[a] = hi;
        double d = hi - lo;
        gi[a] = d > 0 ? (vv_volume_sample_index(v, qb[0], qb[1], qb[2]) -
                         vv_volume_sample_index(v, qa[0], qa[1], qa[2])) /
                            (d * v->spacing[a])
                      : 0;
    }
    vv_vec3 g = {0, 0, 0};
    g.x = v->direction[0] * gi[0] + v->direction[1] * gi[1] + v->direction[2] * gi[2];
    g.y = v->direction[3] * gi[0] + v->direction[4] * gi[1] + v->direction[5] * gi[2];
    g.z = v->direction[6] * gi[0] + v->direction[7] * gi[1] + v->direction[8] * gi[2];
    *gradient = g;
    return 1;
}

vv_status
vv_volume_histogram(const vv_volume *v, int nbins, double lo, double hi, uint64_t *bins) {
    if (nbins < 1 || !(hi > lo))
        return vv_error_set(VV_ERR_INVALID,
                            "histogram: need nbins >= 1 and hi > lo (got %d, [%g, %g])", nbins, lo,
                            hi);
    memset(bins, 0, sizeof *bins * (size_t)nbins);
    uint64_t n = vv_volume_voxel_count(v);
    double scale = nbins / (hi - lo);
    int nt = vv_threads_get();
    uint64_t *local = calloc((size_t)nt * (size_t)nbins, sizeof *local);
    if (!local)
        return vv_error_set(VV_ERR_NOMEM, "histogram: out of memory");
#pragma omp parallel num_threads(nt)
    {
        uint64_t *mine = local + (size_t)omp_get_thread_num() * (size_t)nbins;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < (int64_t)n; i++) {
            double x = vv_voxel_at(v, (size_t)i);
            if (x != x)
                continue;
            double b = (x - lo) * scale;
            int bi = b < 0 ? 0 : b >= nbins ? nbins - 1 : (int)b;
            mine[bi]++;
        }
    }
    for (int t = 0; t < nt; t++)
        for (int b = 0; b < nbins; b++)
            bins[b] += local[(size_t)t * (size_t)nbins + (size_t)b];
    free(local);
    return VV_OK;
}

void
vv_volume_quantiles(const vv_volume *v, int n, const double *q, double *out) {
    enum { NB = 4096 };
    double lo = v->range[0], hi = v->range[1];
    if (!(hi > lo)) {
        for (int i = 0; i < n; i++)
            out[i] = lo;
        return;
    }
    uint64_t *bins = malloc(sizeof *bins * NB);
    if (!bins || vv_volume_histogram(v, NB, lo, hi, bins) != VV_OK) {
        free(bins);
        for (int i = 0; i < n; i++)
            out[i] = lo + q[i] * (hi - lo);
        return;
    }
    uint64_t total = 0;
    for (int b = 0; b < NB; b++)
        total += bins[b];
    for (int i = 0; i < n; i++) {
        double target = q[i] * (double)total, acc = 0;
        out[i] = hi;
        for (int b = 0; b < NB; b++) {
            if (acc + (double)bins[b] >= target) {
                double frac = bins[b] ? (target - acc) / (double)bins[b] : 0;
                out[i] = lo + (b + frac) * (hi - lo) / NB;
                break;
            }
            acc += (double)bins[b];
        }
    }
    free(bins);
}

double
vv_volume_quantile(const vv_volume *v, double q) {
    double r;
    vv_volume_quantiles(v, 1, &q, &r);
    return r;
}

vv_status
vv_minmax_grid_build(vv_minmax_grid **out, const vv_volume *v, int block) {
    if (!out || !v)
        return vv_error_set(VV_ERR_INVALID, "min/max grid: NULL argument");
    *out = NULL;
    if (block < 1)
        return vv_error_set(VV_ERR_INVALID, "min/max grid: block %d < 1", block);
    vv_minmax_grid *g = calloc(1, sizeof *g);
    if (!g)
        return vv_error_set(VV_ERR_NOMEM, "min/max grid: out of memory");
    g->block = block;
    for (int a = 0; a < 3; a++) {
        int cells = v->dims[a] - 1;
        g->dims[a] = cells < 1 ? 1 : (cells + block - 1) / block;
    }
    size_t n = (size_t)g->dims[0] * (size_t)g->dims[1] * (size_t)g->dims[2];
    g->min = malloc(n * sizeof *g->min);
    g->max = malloc(n * sizeof *g->max);
    if (!g->min || !g->max) {
        vv_minmax_grid_free(g);
        return vv_error_set(VV_ERR_NOMEM, "min/max grid: out of memory for %zu subvolumes", n);
    }
    const int bx = g->dims[0], by = g->dims[1], bz = g->dims[2];
    const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
#pragma omp parallel for schedule(dynamic, 1) collapse(2)
    for (int bk = 0; bk < bz; bk++)
        for (int bj = 0; bj < by; bj++)
            for (int bi = 0; bi < bx; bi++) {
                int lo[3] = {bi * block, bj * block, bk * block}, hi[3];
                for (int a = 0; a < 3; a++) {
                    hi[a] = lo[a] + block;
                    if (hi[a] > v->dims[a] - 1)
                        hi[a] = v->dims[a] - 1;
                }
                float mn = INFINITY, mx = -INFINITY;
                for (int k = lo[2]; k <= hi[2]; k++)
                    for (int j = lo[1]; j <= hi[1]; j++) {
                        size_t base = (size_t)k * sz + (size_t)j * sy;
                        for (int i = lo[0]; i <= hi[0]; i++) {
                            float x = (float)vv_voxel_at(v, base + (size_t)i);
                            mn = x < mn ? x : mn; /* NaN compares false: ignored */
                            mx = x > mx ? x : mx;
                        }
                    }
                size_t b = ((size_t)bk * (size_t)by + (size_t)bj) * (size_t)bx + (size_t)bi;
                g->min[b] = mn;
                g->max[b] = mx;
            }
    *out = g;
    return VV_OK;
}

void
vv_minmax_grid_free(vv_minmax_grid *g) {
    if (!g)
        return;
    free(g->min);
    free(g->max);
    free(g);
}

void
vv_volume_take_geometry(vv_volume *v, const vv_volume *h) {
    memcpy(v->spacing, h->spacing, sizeof v->spacing);
    memcpy(v->origin, h->origin, sizeof v->origin);
    memcpy(v->direction, h->direction, sizeof v->direction);
    v->unit = h->unit;
    v->space = h->space;
}
