/*
 * Transfer functions: piecewise-linear opacity and colour of the data value
 * (the paper's "segmentation" of a volume object by a transfer function).
 */
#include <math.h>
#include <string.h>

#include "volvis/model.h"

void
vv_tf_init(vv_tf *tf) {
    if (!tf)
        return;
    memset(tf, 0, sizeof *tf);
    tf->opacity_unit_distance = 1.0;
}

/* Index at which a point of @p value goes: after every point <= value, so
 * that two points at the same value make a step (the later one wins above). */
static int
insert_index_opacity(const vv_tf *tf, double value) {
    int i = tf->n_opacity;
    while (i > 0 && tf->opacity[i - 1].value > value)
        i--;
    return i;
}

static int
insert_index_color(const vv_tf *tf, double value) {
    int i = tf->n_color;
    while (i > 0 && tf->color[i - 1].value > value)
        i--;
    return i;
}

vv_status
vv_tf_add_opacity(vv_tf *tf, double value, double opacity) {
    if (!tf)
        return vv_error_set(VV_ERR_INVALID, "transfer function: NULL");
    if (!isfinite(value))
        return vv_error_set(VV_ERR_INVALID, "transfer function: value %g is not finite", value);
    if (!(opacity >= 0.0 && opacity <= 1.0))
        return vv_error_set(VV_ERR_INVALID, "transfer function: opacity %g is outside [0, 1]",
                            opacity);
    if (tf->n_opacity >= VV_TF_MAX_POINTS)
        return vv_error_set(VV_ERR_LIMIT, "transfer function: more than %d opacity points",
                            VV_TF_MAX_POINTS);
    int i = insert_index_opacity(tf, value);
    memmove(&tf->opacity[i + 1], &tf->opacity[i],
            (size_t)(tf->n_opacity - i) * sizeof tf->opacity[0]);
    tf->opacity[i].value = value;
    tf->opacity[i].opacity = opacity;
    tf->n_opacity++;
    return VV_OK;
}

static int
color_ok(vv_vec3 c) {
    return c.x >= 0.0 && c.x <= 1.0 && c.y >= 0.0 && c.y <= 1.0 && c.z >= 0.0 && c.z <= 1.0;
}

vv_status
vv_tf_add_color(vv_tf *tf, double value, vv_vec3 color) {
    if (!tf)
        return vv_error_set(VV_ERR_INVALID, "transfer function: NULL");
    if (!isfinite(value))
        return vv_error_set(VV_ERR_INVALID, "transfer function: value %g is not finite", value);
    if (!color_ok(color))
        return vv_error_set(VV_ERR_INVALID,
                            "transfer function: colour (%g, %g, %g) is outside [0, 1]", color.x,
                            color.y, color.z);
    if (tf->n_color >= VV_TF_MAX_POINTS)
        return vv_error_set(VV_ERR_LIMIT, "transfer function: more than %d colour points",
                            VV_TF_MAX_POINTS);
    int i = insert_index_color(tf, value);
    memmove(&tf->color[i + 1], &tf->color[i], (size_t)(tf->n_color - i) * sizeof tf->color[0]);
    tf->color[i].value = value;
    tf->color[i].color = color;
    tf->n_color++;
    return VV_OK;
}

/* Last index i with point[i].value <= value, or -1; binary search. */
#define LAST_LE(arr, n, v, out)                                                                    \
    do {                                                                                           \
        int lo_ = 0, hi_ = (n)-1, r_ = -1;                                                         \
        while (lo_ <= hi_) {                                                                       \
            int mid_ = lo_ + (hi_ - lo_) / 2;                                                      \
            if ((arr)[mid_].value <= (v)) {                                                        \
                r_ = mid_;                                                                         \
                lo_ = mid_ + 1;                                                                    \
            } else {                                                                               \
                hi_ = mid_ - 1;                                                                    \
            }                                                                                      \
        }                                                                                          \
        (out) = r_;                                                                                \
    } while (0)

double
vv_tf_eval_opacity(const vv_tf *tf, double value) {
    if (!tf || tf->n_opacity <= 0 || isnan(value))
        return 0.0;
    int n = tf->n_opacity;
    int i;
    LAST_LE(tf->opacity, n, value, i);
    if (i < 0)
        return tf->opacity[0].opacity;
    if (i >= n - 1)
        return tf->opacity[n - 1].opacity;
    /* opacity[i].value <= value < opacity[i + 1].value, so the span is > 0 */
    const vv_tf_opacity_point *a = &tf->opacity[i], *b = &tf->opacity[i + 1];
    double t = (value - a->value) / (b->value - a->value);
    return a->opacity + t * (b->opacity - a->opacity);
}

uint32_t
vv_label_key(double id) {
    if (!(id >= 0.5)) /* also NaN */
        return 0;
    if (id < 4294967295.5)
        return (uint32_t)(id + 0.5);
    const uint64_t x = id < 18446744073709551615.0 ? (uint64_t)id : UINT64_MAX;
    const uint32_t k = (uint32_t)(x ^ (x >> 32));
    return k ? k : 1;
}

vv_vec3
vv_label_color(uint32_t label) {
    if (label == 0)
        return vv_vec3_make(0, 0, 0);
    double h = fmod(0.1 + 0.6180339887498949 * (double)(label - 1), 1.0) * 6.0;
    double s = 0.65, v = 0.95;
    int sector = (int)h;
    double f = h - sector, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    switch (sector % 6) {
    case 0:
        return vv_vec3_make(v, t, p);
    case 1:
        return vv_vec3_make(q, v, p);
    case 2:
        return vv_vec3_make(p, v, t);
    case 3:
        return vv_vec3_make(p, q, v);
    case 4:
        return vv_vec3_make(t, p, v);
    default:
        return vv_vec3_make(v, p, q);
    }
}

vv_vec3
vv_tf_eval_color(const vv_tf *tf, double value) {
    if (!tf || tf->n_color <= 0)
        return vv_vec3_make(1.0, 1.0, 1.0);
    int n = tf->n_color;
    if (isnan(value))
        return tf->color[0].color;
    int i;
    LAST_LE(tf->color, n, value, i);
    if (i < 0)
        return tf->color[0].color;
    if (i >= n - 1)
        return tf->color[n - 1].color;
    const vv_tf_color_point *a = &tf->color[i], *b = &tf->color[i + 1];
    double t = (value - a->value) / (b->value - a->value);
    return vv_vec3_lerp(a->color, b->color, t);
}

static double
clamp01(double x) {
    if (!(x > 0.0))
        return 0.0;
    return x > 1.0 ? 1.0 : x;
}

void
vv_tf_set_ramp(vv_tf *tf, double lo, double hi, double max_opacity, vv_vec3 color,
               double unit_distance) {
    if (!tf)
        return;
    vv_tf_init(tf);
    if (isfinite(unit_distance) && unit_distance > 0.0)
        tf->opacity_unit_distance = unit_distance;
    if (!isfinite(lo) || !isfinite(hi))
        return;
    if (hi < lo) {
        double t = lo;
        lo = hi;
        hi = t;
    }
    color.x = clamp01(color.x);
    color.y = clamp01(color.y);
    color.z = clamp01(color.z);
    max_opacity = clamp01(max_opacity);
    tf->opacity[0].value = lo;
    tf->opacity[0].opacity = 0.0;
    tf->opacity[1].value = hi;
    tf->opacity[1].opacity = max_opacity;
    tf->n_opacity = 2;
    tf->color[0].value = lo;
    tf->color[0].color = color;
    tf->color[1].value = hi;
    tf->color[1].color = color;
    tf->n_color = 2;
}

/* ---- presets -------------------------------------------------------------- */

/* How a preset's abscissae are placed on a volume's values. */
typedef enum preset_scale {
    PRESET_HU = 0,     /* Hounsfield units (hu_map_of) */
    PRESET_MEDIAN = 1, /* 0..1 over the 50th to the 99th percentile (MR without units) */
    PRESET_RANGE = 2   /* 0..1 over the 1st to the 99.5th percentile (any data) */
} preset_scale;

typedef struct preset_point {
    double x;
    double a;
    double r, g, b;
} preset_point;

#define PRESET_MAX_POINTS 10

typedef struct preset {
    const char *name, *doc;
    preset_scale scale;
    int n;
    preset_point p[PRESET_MAX_POINTS];
} preset;

/*
 * The presets: CT tissues in Hounsfield units (windows of radiology
 * practice: lung -1000..-400, fat -150..-50, soft tissue 20..80, contrast
 * vessels 150..500, bone above 300), MR from the median of the volume up
 * (T1: white matter brighter than grey; T2: fluid brightest; angiography:
 * the brightest voxels), and colour maps over the range of any data
 * (microscopy channels as ImageJ/Fiji colours them; viridis and inferno,
 * van der Walt and Smith's perceptually uniform maps; Moreland's cool-warm).
 */
static const preset presets[] = {
    {"ct-bone",
     "CT: bone opaque and ivory, below about 150 HU transparent",
     PRESET_HU,
     5,
     {{-1024, 0, 0, 0, 0},
      {150, 0, 0.55, 0.25, 0.15},
      {300, 0.25, 0.85, 0.65, 0.45},
      {600, 0.8, 0.95, 0.9, 0.8},
      {1500, 1, 1, 1, 0.95}}},
    {"ct-soft-tissue",
     "CT: skin and soft tissue faint and reddish, bone opaque",
     PRESET_HU,
     8,
     {{-1024, 0, 0, 0, 0},
      {-600, 0, 0.4, 0.15, 0.1},
      {-400, 0.03, 0.7, 0.35, 0.25},
      {-100, 0.03, 0.85, 0.55, 0.45},
      {40, 0.12, 0.9, 0.45, 0.4},
      {150, 0.12, 0.9, 0.6, 0.5},
      {300, 0.6, 0.95, 0.9, 0.8},
      {1000, 0.95, 1, 1, 0.95}}},
    {"ct-lung",
     "CT: lung parenchyma faint pink, airways clear, vessels and bone faint",
     PRESET_HU,
     7,
     {{-1024, 0, 0, 0, 0},
      {-950, 0, 0.9, 0.6, 0.6},
      {-800, 0.04, 0.95, 0.65, 0.65},
      {-550, 0.08, 0.9, 0.45, 0.45},
      {-400, 0, 0.8, 0.3, 0.3},
      {300, 0, 0.9, 0.9, 0.85},
      {1000, 0.15, 1, 1, 1}}},
    {"ct-vessels",
     "CT angiography: contrast-filled vessels red, bone faint ivory",
     PRESET_HU,
     7,
     {{-1024, 0, 0, 0, 0},
      {100, 0, 0.6, 0.05, 0.05},
      {180, 0.35, 0.85, 0.1, 0.1},
      {400, 0.7, 1, 0.35, 0.25},
      {550, 0.05, 1, 0.9, 0.8},
      {1000, 0.1, 1, 1, 0.95},
      {2000, 0.3, 1, 1, 1}}},
    {"ct-muscle",
     "CT: muscle and organs (20..80 HU) red, fat and air clear, bone faint",
     PRESET_HU,
     7,
     {{-1024, 0, 0, 0, 0},
      {-50, 0, 0.7, 0.3, 0.25},
      {20, 0.15, 0.8, 0.25, 0.2},
      {80, 0.3, 0.9, 0.35, 0.3},
      {150, 0, 0.95, 0.8, 0.7},
      {400, 0.2, 1, 0.95, 0.9},
      {1500, 0.6, 1, 1, 1}}},
    {"ct-skin",
     "CT: the skin surface opaque, everything inside hidden by it",
     PRESET_HU,
     4,
     {{-1024, 0, 0, 0, 0},
      {-300, 0, 0.9, 0.7, 0.6},
      {-150, 0.9, 0.95, 0.75, 0.65},
      {3000, 0.9, 1, 0.85, 0.75}}},
    {"ct-fat",
     "CT: fat (-150..-50 HU) yellow, soft tissue faint, bone white",
     PRESET_HU,
     7,
     {{-1024, 0, 0, 0, 0},
      {-200, 0, 1, 0.9, 0.4},
      {-110, 0.25, 1, 0.85, 0.3},
      {-40, 0, 0.9, 0.6, 0.4},
      {60, 0.03, 0.9, 0.5, 0.45},
      {300, 0.3, 1, 0.95, 0.9},
      {1500, 0.8, 1, 1, 1}}},
    {"mr",
     "MR: a grey ramp from the median to the 99th percentile",
     PRESET_MEDIAN,
     3,
     {{0, 0, 0.3, 0.3, 0.3}, {0.5, 0.3, 0.8, 0.75, 0.7}, {1, 0.8, 1, 0.95, 0.9}}},
    {"mr-t1-brain",
     "MR T1: grey matter faint, white matter and fat bright and warm",
     PRESET_MEDIAN,
     5,
     {{0, 0, 0.2, 0.15, 0.1},
      {0.25, 0.02, 0.55, 0.45, 0.4},
      {0.55, 0.15, 0.85, 0.75, 0.65},
      {0.8, 0.5, 0.98, 0.92, 0.82},
      {1, 0.9, 1, 1, 0.95}}},
    {"mr-t2-brain",
     "MR T2: fluid (the brightest) blue and opaque, tissue faint",
     PRESET_MEDIAN,
     5,
     {{0, 0, 0.2, 0.2, 0.25},
      {0.4, 0.02, 0.5, 0.5, 0.6},
      {0.7, 0.05, 0.6, 0.7, 0.9},
      {0.85, 0.45, 0.4, 0.7, 1},
      {1, 0.9, 0.8, 0.95, 1}}},
    {"mr-angio",
     "MR angiography: the brightest voxels (vessels) red and opaque",
     PRESET_MEDIAN,
     4,
     {{0, 0, 0.3, 0, 0},
      {0.8, 0, 0.6, 0.05, 0.05},
      {0.92, 0.5, 0.95, 0.2, 0.15},
      {1, 1, 1, 0.9, 0.8}}},
    {"mip",
     "maximum intensity projection: grey from black to white over the range",
     PRESET_RANGE,
     2,
     {{0, 0, 0, 0, 0}, {1, 1, 1, 1, 1}}},
    {"grey",
     "a grey ramp over the range, half opaque at the top",
     PRESET_RANGE,
     2,
     {{0, 0, 0.2, 0.2, 0.2}, {1, 0.5, 1, 1, 1}}},
    {"fire",
     "microscopy (Fiji's Fire): black, red, yellow, white",
     PRESET_RANGE,
     5,
     {{0, 0, 0, 0, 0},
      {0.25, 0.05, 0.55, 0, 0.35},
      {0.5, 0.2, 0.95, 0.25, 0},
      {0.75, 0.5, 1, 0.75, 0},
      {1, 0.9, 1, 1, 1}}},
    {"microscopy-green",
     "microscopy: a green channel (GFP), black to green",
     PRESET_RANGE,
     3,
     {{0, 0, 0, 0, 0}, {0.5, 0.2, 0, 0.6, 0}, {1, 0.8, 0.4, 1, 0.4}}},
    {"microscopy-magenta",
     "microscopy: a magenta channel, black to magenta",
     PRESET_RANGE,
     3,
     {{0, 0, 0, 0, 0}, {0.5, 0.2, 0.6, 0, 0.6}, {1, 0.8, 1, 0.4, 1}}},
    {"microscopy-cyan",
     "microscopy: a cyan channel (DAPI shown cyan), black to cyan",
     PRESET_RANGE,
     3,
     {{0, 0, 0, 0, 0}, {0.5, 0.2, 0, 0.55, 0.6}, {1, 0.8, 0.4, 1, 1}}},
    {"hot-iron",
     "hot iron: black, red, orange, yellow, white",
     PRESET_RANGE,
     5,
     {{0, 0, 0, 0, 0},
      {0.3, 0.1, 0.7, 0, 0},
      {0.6, 0.35, 1, 0.5, 0},
      {0.85, 0.7, 1, 0.9, 0.2},
      {1, 0.95, 1, 1, 1}}},
    {"viridis",
     "viridis colour map (perceptually uniform), opacity rising with the value",
     PRESET_RANGE,
     5,
     {{0, 0, 0.267, 0.005, 0.329},
      {0.25, 0.1, 0.229, 0.322, 0.546},
      {0.5, 0.3, 0.128, 0.567, 0.551},
      {0.75, 0.55, 0.369, 0.789, 0.383},
      {1, 0.85, 0.993, 0.906, 0.144}}},
    {"inferno",
     "inferno colour map (perceptually uniform), opacity rising with the value",
     PRESET_RANGE,
     5,
     {{0, 0, 0.001, 0, 0.014},
      {0.25, 0.1, 0.341, 0.062, 0.429},
      {0.5, 0.3, 0.735, 0.216, 0.33},
      {0.75, 0.55, 0.978, 0.557, 0.035},
      {1, 0.85, 0.988, 1, 0.644}}},
    {"cool-warm",
     "Moreland's diverging cool-warm map: low blue, middle clear, high red",
     PRESET_RANGE,
     5,
     {{0, 0.6, 0.23, 0.299, 0.754},
      {0.3, 0.15, 0.55, 0.69, 0.99},
      {0.5, 0, 0.865, 0.865, 0.865},
      {0.7, 0.15, 0.96, 0.61, 0.48},
      {1, 0.6, 0.706, 0.016, 0.15}}},
    {"top-5-percent",
     "only the brightest 5 % of the range, opaque white; the rest clear",
     PRESET_RANGE,
     3,
     {{0, 0, 0.5, 0.5, 0.5}, {0.93, 0, 0.9, 0.9, 0.9}, {0.97, 1, 1, 1, 1}}},
};
#define N_PRESETS ((int)(sizeof presets / sizeof presets[0]))

static const char *const preset_names[N_PRESETS + 1] = {"ct-bone",
                                                        "ct-soft-tissue",
                                                        "ct-lung",
                                                        "ct-vessels",
                                                        "ct-muscle",
                                                        "ct-skin",
                                                        "ct-fat",
                                                        "mr",
                                                        "mr-t1-brain",
                                                        "mr-t2-brain",
                                                        "mr-angio",
                                                        "mip",
                                                        "grey",
                                                        "fire",
                                                        "microscopy-green",
                                                        "microscopy-magenta",
                                                        "microscopy-cyan",
                                                        "hot-iron",
                                                        "viridis",
                                                        "inferno",
                                                        "cool-warm",
                                                        "top-5-percent",
                                                        NULL};

const char *const *
vv_tf_preset_names(void) {
    return preset_names;
}

static const preset *
find_preset(const char *name) {
    for (int i = 0; name && i < N_PRESETS; i++)
        if (!strcmp(presets[i].name, name))
            return &presets[i];
    return NULL;
}

const char *
vv_tf_preset_description(const char *name) {
    const preset *p = find_preset(name);
    return p ? p->doc : NULL;
}

/* Maps Hounsfield units onto the volume's values (vv_tf_preset). */
typedef struct hu_map {
    double scale, offset; /* value = scale * HU + offset */
    double top;           /* relative presets: the value at 1 (exactly hi) */
} hu_map;

static hu_map
hu_map_of(const vv_volume *v) {
    hu_map m = {1.0, 0.0, 0.0};
    if (!v)
        return m;
    double lo = v->range[0], hi = v->range[1];
    if (!isfinite(lo) || !isfinite(hi) || lo < -200.0)
        return m; /* Hounsfield units */
    if (hi >= 1200.0 && hi <= 65535.0) {
        m.offset = 1024.0; /* stored unsigned: HU + 1024 */
        return m;
    }
    if (!(hi > lo))
        hi = lo + 1.0;
    /* [-1024, 3071] HU stretched over the range */
    m.scale = (hi - lo) / 4095.0;
    m.offset = lo + 1024.0 * m.scale;
    return m;
}

/* The values a preset's 0..1 abscissae span on @p v: lo + x (hi - lo),
 * exactly hi at x = 1 (the offset is lo, the scale hi - lo). */
static hu_map
range_map_of(const vv_volume *v, preset_scale scale) {
    const double q[2] = {scale == PRESET_MEDIAN ? 0.5 : 0.01,
                         scale == PRESET_MEDIAN ? 0.99 : 0.995};
    double lh[2];
    vv_volume_quantiles(v, 2, q, lh);
    double lo = lh[0], hi = lh[1];
    if (!isfinite(lo) || !isfinite(hi) || !(hi > lo)) {
        lo = v->range[0];
        hi = v->range[1] > lo ? v->range[1] : lo + 1.0;
    }
    return (hu_map){hi - lo, lo, hi};
}

static vv_status
preset_fill(vv_tf *tf, const preset_point *p, int n, hu_map m, int relative) {
    for (int i = 0; i < n; i++) {
        double x = m.scale * p[i].x + m.offset;
        if (relative) /* lo + x (hi - lo), the top exactly hi */
            x = p[i].x == 1.0 ? m.top : m.offset + p[i].x * m.scale;
        vv_status st = vv_tf_add_opacity(tf, x, p[i].a);
        if (st == VV_OK)
            st = vv_tf_add_color(tf, x, vv_vec3_make(p[i].r, p[i].g, p[i].b));
        if (st != VV_OK)
            return st;
    }
    return VV_OK;
}

vv_status
vv_tf_preset(vv_tf *tf, const char *name, const vv_volume *v) {
    if (!tf || !name)
        return vv_error_set(VV_ERR_INVALID, "transfer function preset: NULL %s",
                            tf ? "name" : "transfer function");
    const preset *p = find_preset(name);
    if (!p) {
        char list[1024] = "";
        for (int i = 0; i < N_PRESETS; i++) {
            strncat(list, presets[i].name, sizeof list - strlen(list) - 1);
            if (i + 1 < N_PRESETS)
                strncat(list, ", ", sizeof list - strlen(list) - 1);
        }
        return vv_error_set(VV_ERR_INVALID,
                            "transfer function preset \"%s\" is unknown; expected %s", name, list);
    }
    if (p->scale != PRESET_HU && !v)
        return vv_error_set(VV_ERR_INVALID, "transfer function preset %s: needs a volume", name);
    double unit = 1.0;
    if (v) {
        unit = v->spacing[0];
        unit = v->spacing[1] < unit ? v->spacing[1] : unit;
        unit = v->spacing[2] < unit ? v->spacing[2] : unit;
        if (!(unit > 0.0) || !isfinite(unit))
            unit = 1.0;
    }
    vv_tf out;
    vv_tf_init(&out);
    out.opacity_unit_distance = unit;
    hu_map m = p->scale == PRESET_HU ? hu_map_of(v) : range_map_of(v, p->scale);
    vv_status st = preset_fill(&out, p->p, p->n, m, p->scale != PRESET_HU);
    if (st != VV_OK)
        return vv_error_prefix(st, "transfer function preset %s", name);
    *tf = out;
    return VV_OK;
}
