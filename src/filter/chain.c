/*
 * Filter chains: the steps of `volvis filter`, of a scene object's
 * "filters" list and of the GUI's Filtering page, parsed from the same
 * text ("--gaussian 1.5 --median 1 --threshold 300:"), applied in order,
 * and a small cache of filtered volumes for scene loading.
 */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "core/internal.h"
#include "filter/filter_internal.h"
#include "volvis/io.h"

enum {
    F_GAUSSIAN,
    F_MEDIAN,
    F_BILATERAL,
    F_DIFFUSION,
    F_RESAMPLE,
    F_RESIZE,
    F_CROP,
    F_PAD,
    F_FLIP,
    F_PERMUTE,
    F_CAST,
    F_GRADIENT,
    F_GRADIENT_COMPONENT,
    F_LAPLACIAN,
    F_VESSELNESS,
    F_THRESHOLD,
    F_WINDOW,
    F_GROW,
    F_COMPONENTS,
    F_LARGEST,
    F_ERODE,
    F_DILATE,
    F_OPEN,
    F_CLOSE,
    F_FILL_HOLES,
    F_COUNT
};

static const vv_filter_info infos[F_COUNT] = {
    [F_GAUSSIAN] = {"gaussian", "SIGMA[,SY,SZ][v]",
                    "Gaussian smoothing, sigma in world units (suffix v: voxels) -> f32"},
    [F_MEDIAN] = {"median", "R", "median over the (2R+1)^3 voxel cube, R in voxels -> same type"},
    [F_BILATERAL] = {"bilateral", "SPATIAL:RANGE",
                     "bilateral filter, spatial sigma in world units, range sigma in value "
                     "units -> f32"},
    [F_DIFFUSION] = {"diffusion", "N:KAPPA[:DT]",
                     "Perona-Malik diffusion, N steps, kappa in value units per world unit, "
                     "time step DT in (0, 1/6] (default 1/8) -> f32"},
    [F_RESAMPLE] = {"resample", "SXxSYxSZ[:KERNEL]",
                    "resample to a voxel spacing in world units; KERNEL nearest, linear "
                    "(default), bspline or sinc -> f32 (nearest: same type)"},
    [F_RESIZE] = {"resize", "NXxNYxNZ[:KERNEL]",
                  "resample to a size in voxels over the same extent (kernels as resample)"},
    [F_CROP] = {"crop", "I0,J0,K0:I1,J1,K1",
                "crop to the voxel box, inclusive; origin moves -> same type"},
    [F_PAD] = {"pad", "N[,NY,NZ][:VALUE]",
               "pad N voxels on both sides of each axis with VALUE (default 0) -> same type"},
    [F_FLIP] = {"flip", "x|y|z", "reverse the voxel order along an axis (world positions kept)"},
    [F_PERMUTE] = {"permute", "AXES",
                   "reorder the axes, e.g. zyx or yxz (world positions kept) -> same type"},
    [F_CAST] = {"cast", "TYPE[:rescale]",
                "convert to u8, i8, u16, i16, u32, i32, f32, f64; clamped, or the value "
                "range rescaled to the type's range"},
    [F_GRADIENT] = {"gradient", "SIGMA",
                    "gradient magnitude in value units per world unit; SIGMA 0: central "
                    "differences, > 0: derivative of Gaussian (world units) -> f32"},
    [F_GRADIENT_COMPONENT] = {"gradient-component", "x|y|z[:SIGMA]",
                              "one world-axis component of the gradient (as gradient) -> f32"},
    [F_LAPLACIAN] = {"laplacian", "SIGMA",
                     "Laplacian in value units per world unit squared; SIGMA 0: second "
                     "differences, > 0: of a Gaussian (world units) -> f32"},
    [F_VESSELNESS] = {"vesselness", "S1[,S2,...][:dark]",
                      "Frangi vesselness, maximum over the scales (world units); bright "
                      "vessels unless :dark -> f32 in [0, 1]"},
    [F_THRESHOLD] = {"threshold", "LO:HI|LO:|:HI|otsu",
                     "1 where LO <= value <= HI (otsu: value >= Otsu's threshold) -> u8 mask"},
    [F_WINDOW] = {"window", "LO:HI", "(clamp(value, LO, HI) - LO) / (HI - LO) -> f32 in [0, 1]"},
    [F_GROW] = {"grow", "I,J,K[+I,J,K...]:LO:HI[:CONN]",
                "region growing from seed voxels through values in LO..HI, 6 (default), 18 "
                "or 26 connected -> u8 mask"},
    [F_COMPONENTS] = {"components", "CONN[:TYPE]",
                      "label the connected components of the non-zero voxels (CONN 6, 18 or 26; "
                      "TYPE u8, u16, u32 default) in raster order -> label volume"},
    [F_LARGEST] = {"largest", "K[:CONN]",
                   "keep the K largest connected components of the non-zero voxels (CONN 6 "
                   "default, 18, 26) -> u8 mask"},
    [F_ERODE] = {"erode", "R", "binary erosion by a ball of R voxels -> u8 mask"},
    [F_DILATE] = {"dilate", "R", "binary dilation by a ball of R voxels -> u8 mask"},
    [F_OPEN] = {"open", "R", "binary opening (erode, then dilate) -> u8 mask"},
    [F_CLOSE] = {"close", "R", "binary closing (dilate, then erode) -> u8 mask"},
    [F_FILL_HOLES] = {"fill-holes", "",
                      "fill background regions not connected to the faces -> u8 mask"},
};

int
vv_filter_info_count(void) {
    return F_COUNT;
}

const vv_filter_info *
vv_filter_info_get(int i) {
    return i >= 0 && i < F_COUNT ? &infos[i] : NULL;
}

static int
find_filter(const char *name) {
    if (!name)
        return -1;
    if (name[0] == '-' && name[1] == '-')
        name += 2;
    for (int i = 0; i < F_COUNT; i++)
        if (strcmp(infos[i].name, name) == 0)
            return i;
    return -1;
}

const vv_filter_info *
vv_filter_info_find(const char *name) {
    int i = find_filter(name);
    return i < 0 ? NULL : &infos[i];
}

typedef struct step {
    int id;
    char *arg;
    double d[4];
    int n[6];
    int voxels, otsu, bright, rescale;
    vv_filter_kernel kernel;
    vv_voxel_type type;
    int (*seeds)[3];
    int n_seeds;
    double *scales;
    int n_scales;
} step;

struct vv_filter_chain {
    int n, cap;
    step *steps;
    char *text;
};

vv_status
vv_filter_chain_new(vv_filter_chain **out) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "filter chain: NULL argument");
    *out = calloc(1, sizeof **out);
    return *out ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
}

static void
step_clear(step *s) {
    free(s->arg);
    free(s->seeds);
    free(s->scales);
}

void
vv_filter_chain_free(vv_filter_chain *c) {
    if (!c)
        return;
    for (int i = 0; i < c->n; i++)
        step_clear(&c->steps[i]);
    free(c->steps);
    free(c->text);
    free(c);
}

int
vv_filter_chain_length(const vv_filter_chain *c) {
    return c ? c->n : 0;
}

/* ---- argument parsing ------------------------------------------------------------ */

/* Parses a finite double from [s, end) (the whole span). */
static int
num(const char *s, const char *end, double *out) {
    char buf[64];
    size_t n = (size_t)(end - s);
    if (n == 0 || n >= sizeof buf)
        return 0;
    memcpy(buf, s, n);
    buf[n] = 0;
    char *e;
    errno = 0;
    double v = strtod(buf, &e);
    if (*e || errno || !isfinite(v))
        return 0;
    *out = v;
    return 1;
}

static int
inum(const char *s, const char *end, int *out) {
    double v;
    if (!num(s, end, &v) || v != floor(v) || fabs(v) > 1e9)
        return 0;
    *out = (int)v;
    return 1;
}

/* Splits @p s at @p sep into at most @p max numbers; returns how many, or -1. */
static int
nums(const char *s, const char *end, char sep, double *out, int max) {
    int k = 0;
    while (s <= end) {
        const char *p = memchr(s, sep, (size_t)(end - s));
        if (!p)
            p = end;
        if (k >= max || !num(s, p, &out[k]))
            return -1;
        k++;
        s = p + 1;
        if (p == end)
            break;
    }
    return k;
}

static vv_status
bad(const step *st, const char *why) {
    const char *name = st->id >= 0 && st->id < F_COUNT ? infos[st->id].name : "?";
    return vv_error_set(VV_ERR_INVALID, "--%s %s: %s", name, st->arg ? st->arg : "", why);
}

static int
parse_conn(const char *s, int *conn) {
    int c;
    if (!inum(s, s + strlen(s), &c) || (c != 6 && c != 18 && c != 26))
        return 0;
    *conn = c;
    return 1;
}

/* A parse_step group returned this: the filter is not one of the group. The
 * groups get the argument text @p a .. @p end and its first colon (or NULL). */
#define NOT_IN_GROUP 1

/* The argument of a step of smoothing: gaussian, median and morphology, bilateral, diffusion;
 * NOT_IN_GROUP for other filters. */
static vv_status
parse_smoothing_step(step *st, const char *a, const char *end, const char *colon) {
    (void)colon;
    double v[8];
    int k;
    switch (st->id) {
    case F_GAUSSIAN: {
        const char *e = end;
        if (e > a && (e[-1] == 'v' || e[-1] == 'V')) {
            st->voxels = 1;
            e--;
        }
        k = nums(a, e, ',', v, 3);
        if (k != 1 && k != 3)
            return bad(st, "expected SIGMA or SX,SY,SZ (world units; suffix v for voxels)");
        for (int i = 0; i < 3; i++) {
            st->d[i] = v[k == 1 ? 0 : i];
            if (!(st->d[i] > 0))
                return bad(st, "sigma must be > 0");
        }
        return VV_OK;
    }
    case F_MEDIAN:
    case F_ERODE:
    case F_DILATE:
    case F_OPEN:
    case F_CLOSE: {
        int lo = st->id == F_MEDIAN ? 0 : 1;
        if (!inum(a, end, &st->n[0]) || st->n[0] < lo || st->n[0] > VV_FILTER_MAX_RADIUS) {
            char m[96];
            snprintf(m, sizeof m, "expected a radius in voxels, %d..%d", lo, VV_FILTER_MAX_RADIUS);
            return bad(st, m);
        }
        return VV_OK;
    }
    case F_BILATERAL:
        if (nums(a, end, ':', v, 2) != 2 || !(v[0] > 0) || !(v[1] > 0))
            return bad(st, "expected SPATIAL:RANGE, both > 0");
        st->d[0] = v[0];
        st->d[1] = v[1];
        return VV_OK;
    case F_DIFFUSION:
        k = nums(a, end, ':', v, 3);
        if (k < 2 || v[0] != floor(v[0]) || v[0] < 1 || v[0] > 10000 || !(v[1] > 0) ||
            (k == 3 && !(v[2] > 0 && v[2] <= 1.0 / 6.0 + 1e-12)))
            return bad(st, "expected N:KAPPA[:DT] with N 1..10000, KAPPA > 0, DT in (0, 1/6]");
        st->n[0] = (int)v[0];
        st->d[0] = v[1];
        st->d[1] = k == 3 ? v[2] : 0.125;
        return VV_OK;
    default:
        return NOT_IN_GROUP;
    }
}

/* The argument of a step of resampling and reshaping: resample, resize, crop, pad, flip, permute,
 * cast; NOT_IN_GROUP for other filters. */
static vv_status
parse_geometry_step(step *st, const char *a, const char *end, const char *colon) {
    double v[8];
    int k;
    switch (st->id) {
    case F_RESAMPLE:
    case F_RESIZE: {
        const char *e = colon ? colon : end;
        st->kernel = VV_KERNEL_LINEAR;
        if (colon && vv_filter_kernel_parse(colon + 1, &st->kernel) != VV_OK)
            return bad(st, "unknown kernel; expected nearest, linear, bspline or sinc");
        k = nums(a, e, 'x', v, 3);
        if (k != 3)
            return bad(st, st->id == F_RESAMPLE ? "expected SXxSYxSZ[:KERNEL] (world units)"
                                                : "expected NXxNYxNZ[:KERNEL] (voxels)");
        for (int i = 0; i < 3; i++) {
            if (st->id == F_RESAMPLE && !(v[i] > 0))
                return bad(st, "spacing must be > 0");
            if (st->id == F_RESIZE && (v[i] != floor(v[i]) || v[i] < 1 || v[i] > VV_VOLUME_MAX_DIM))
                return bad(st, "sizes must be whole numbers of voxels, 1..65536");
            st->d[i] = v[i];
            st->n[i] = (int)v[i];
        }
        return VV_OK;
    }
    case F_CROP:
        if (!colon || nums(a, colon, ',', v, 3) != 3 || nums(colon + 1, end, ',', v + 3, 3) != 3)
            return bad(st, "expected I0,J0,K0:I1,J1,K1 (voxels, inclusive)");
        for (int i = 0; i < 6; i++) {
            if (v[i] != floor(v[i]) || v[i] < 0 || v[i] > VV_VOLUME_MAX_DIM)
                return bad(st, "voxel indices must be whole numbers >= 0");
            st->n[i] = (int)v[i];
        }
        return VV_OK;
    case F_PAD: {
        const char *e = colon ? colon : end;
        k = nums(a, e, ',', v, 3);
        if (k != 1 && k != 3)
            return bad(st, "expected N[,NY,NZ][:VALUE]");
        for (int i = 0; i < 3; i++) {
            double x = v[k == 1 ? 0 : i];
            if (x != floor(x) || x < 0 || x > VV_VOLUME_MAX_DIM)
                return bad(st, "pad counts must be whole numbers of voxels >= 0");
            st->n[i] = (int)x;
        }
        st->d[0] = 0;
        if (colon && !num(colon + 1, end, &st->d[0]))
            return bad(st, "VALUE must be a number");
        return VV_OK;
    }
    case F_FLIP:
        if (strlen(a) != 1 || !strchr("xyz", a[0]))
            return bad(st, "expected x, y or z");
        st->n[0] = a[0] - 'x';
        return VV_OK;
    case F_PERMUTE:
        if (strlen(a) != 3)
            return bad(st, "expected three axis letters, e.g. zyx");
        for (int i = 0; i < 3; i++) {
            if (!strchr("xyz", a[i]))
                return bad(st, "axes are x, y and z");
            st->n[i] = a[i] - 'x';
        }
        if (st->n[0] == st->n[1] || st->n[1] == st->n[2] || st->n[0] == st->n[2])
            return bad(st, "each axis must appear once");
        return VV_OK;
    case F_CAST: {
        char t[16];
        size_t n = (size_t)((colon ? colon : end) - a);
        if (n == 0 || n >= sizeof t)
            return bad(st, "expected TYPE[:rescale]");
        memcpy(t, a, n);
        t[n] = 0;
        if (vv_voxel_type_parse(t, &st->type) != VV_OK)
            return bad(st, "unknown voxel type; expected u8, i8, u16, i16, u32, i32, f32, f64");
        if (colon && strcmp(colon + 1, "rescale") != 0 && strcmp(colon + 1, "clamp") != 0)
            return bad(st, "expected :rescale or :clamp after the type");
        st->rescale = colon && strcmp(colon + 1, "rescale") == 0;
        return VV_OK;
    }
    default:
        return NOT_IN_GROUP;
    }
}

/* The argument of a step of derivatives: gradient, Laplacian, a gradient component, vesselness;
 * NOT_IN_GROUP for other filters. */
static vv_status
parse_derivative_step(step *st, const char *a, const char *end, const char *colon) {
    int k;
    switch (st->id) {
    case F_GRADIENT:
    case F_LAPLACIAN:
        if (!num(a, end, &st->d[0]) || !(st->d[0] >= 0))
            return bad(st, "expected SIGMA >= 0 (world units; 0: differences)");
        return VV_OK;
    case F_GRADIENT_COMPONENT:
        if (!a[0] || !strchr("xyz", a[0]) || (a[1] && a[1] != ':'))
            return bad(st, "expected x|y|z[:SIGMA]");
        st->n[0] = a[0] - 'x';
        st->d[0] = 0;
        if (a[1] && (!num(a + 2, end, &st->d[0]) || !(st->d[0] >= 0)))
            return bad(st, "SIGMA must be >= 0");
        return VV_OK;
    case F_VESSELNESS: {
        const char *e = colon ? colon : end;
        st->bright = 1;
        if (colon) {
            if (strcmp(colon + 1, "dark") == 0)
                st->bright = 0;
            else if (strcmp(colon + 1, "bright") != 0)
                return bad(st, "expected :bright or :dark after the scales");
        }
        double sc[16];
        k = nums(a, e, ',', sc, 16);
        if (k < 1)
            return bad(st, "expected 1..16 scales S1,S2,... (world units)");
        st->scales = malloc((size_t)k * sizeof *st->scales);
        if (!st->scales)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        for (int i = 0; i < k; i++) {
            if (!(sc[i] > 0))
                return bad(st, "scales must be > 0");
            st->scales[i] = sc[i];
        }
        st->n_scales = k;
        return VV_OK;
    }
    default:
        return NOT_IN_GROUP;
    }
}

/* The argument of a step of segmentation: threshold, window, region growing, components, largest,
 * fill holes; NOT_IN_GROUP for other filters. */
static vv_status
parse_segment_step(step *st, const char *a, const char *end, const char *colon) {
    double v[8];
    int k;
    switch (st->id) {
    case F_THRESHOLD:
        if (strcasecmp(a, "otsu") == 0) {
            st->otsu = 1;
            return VV_OK;
        }
        /* fall through */
    case F_WINDOW:
        if (!colon || strchr(colon + 1, ':'))
            return bad(st,
                       st->id == F_WINDOW ? "expected LO:HI" : "expected LO:HI, LO:, :HI or otsu");
        st->d[0] = -INFINITY;
        st->d[1] = INFINITY;
        if ((colon > a || st->id == F_WINDOW) && !num(a, colon, &st->d[0]))
            return bad(st, "LO must be a number");
        if ((colon + 1 < end || st->id == F_WINDOW) && !num(colon + 1, end, &st->d[1]))
            return bad(st, "HI must be a number");
        if (st->id == F_WINDOW ? !(st->d[0] < st->d[1]) : !(st->d[0] <= st->d[1]))
            return bad(st, "need LO < HI");
        return VV_OK;
    case F_GROW: {
        if (!colon)
            return bad(st, "expected I,J,K[+I,J,K...]:LO:HI[:CONN]");
        int ns = 1;
        for (const char *p = a; p < colon; p++)
            ns += *p == '+';
        st->seeds = malloc((size_t)ns * sizeof *st->seeds);
        if (!st->seeds)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        const char *p = a;
        for (int q = 0; q < ns; q++) {
            const char *e = memchr(p, '+', (size_t)(colon - p));
            if (!e)
                e = colon;
            if (nums(p, e, ',', v, 3) != 3)
                return bad(st, "each seed is I,J,K (voxel indices)");
            for (int i = 0; i < 3; i++) {
                if (v[i] != floor(v[i]) || fabs(v[i]) > 1e9)
                    return bad(st, "seed indices must be whole numbers");
                st->seeds[q][i] = (int)v[i];
            }
            p = e + 1;
        }
        st->n_seeds = ns;
        k = nums(colon + 1, end, ':', v, 3);
        if (k < 2 || !(v[0] <= v[1]))
            return bad(st, "expected the range LO:HI after the seeds, LO <= HI");
        st->d[0] = v[0];
        st->d[1] = v[1];
        st->n[0] = 6;
        if (k == 3 && (v[2] != 6 && v[2] != 18 && v[2] != 26))
            return bad(st, "connectivity must be 6, 18 or 26");
        if (k == 3)
            st->n[0] = (int)v[2];
        return VV_OK;
    }
    case F_COMPONENTS: {
        st->n[0] = 6;
        st->type = VV_U32;
        char buf[64];
        if (strlen(a) >= sizeof buf)
            return bad(st, "expected [CONN][:TYPE]");
        strcpy(buf, a);
        char *c2 = strchr(buf, ':');
        if (c2)
            *c2++ = 0;
        if (buf[0] && !parse_conn(buf, &st->n[0]))
            return bad(st, "connectivity must be 6, 18 or 26");
        if (c2 && (vv_voxel_type_parse(c2, &st->type) != VV_OK ||
                   (st->type != VV_U8 && st->type != VV_U16 && st->type != VV_U32)))
            return bad(st, "label type must be u8, u16 or u32");
        return VV_OK;
    }
    case F_LARGEST: {
        st->n[1] = 6;
        const char *e = colon ? colon : end;
        if (!inum(a, e, &st->n[0]) || st->n[0] < 1)
            return bad(st, "expected K >= 1 components");
        if (colon && !parse_conn(colon + 1, &st->n[1]))
            return bad(st, "connectivity must be 6, 18 or 26");
        return VV_OK;
    }
    case F_FILL_HOLES:
        if (a[0])
            return bad(st, "takes no argument");
        return VV_OK;
    default:
        return NOT_IN_GROUP;
    }
}

static vv_status
parse_step(step *st) {
    vv_status (*const groups[])(step *, const char *, const char *, const char *) = {
        parse_smoothing_step, parse_geometry_step, parse_derivative_step, parse_segment_step};
    const char *a = st->arg ? st->arg : "";
    const char *end = a + strlen(a);
    const char *colon = strchr(a, ':');
    for (size_t i = 0; i < sizeof groups / sizeof groups[0]; i++) {
        vv_status s = groups[i](st, a, end, colon);
        if (s != NOT_IN_GROUP)
            return s;
    }
    return bad(st, "unknown filter");
}

static vv_status
rebuild_text(vv_filter_chain *c) {
    size_t n = 1;
    for (int i = 0; i < c->n; i++)
        n += strlen(infos[c->steps[i].id].name) + strlen(c->steps[i].arg) + 5;
    char *t = malloc(n), *p = t;
    if (!t)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    *p = 0;
    for (int i = 0; i < c->n; i++) {
        const step *st = &c->steps[i];
        p += sprintf(p, "%s--%s%s%s", i ? " " : "", infos[st->id].name, st->arg[0] ? " " : "",
                     st->arg);
    }
    free(c->text);
    c->text = t;
    return VV_OK;
}

vv_status
vv_filter_chain_add(vv_filter_chain *c, const char *name, const char *arg) {
    if (!c || !name)
        return vv_error_set(VV_ERR_INVALID, "filter chain: NULL argument");
    int id = find_filter(name);
    if (id < 0)
        return vv_error_set(VV_ERR_INVALID, "unknown filter \"%s\" (see 'volvis filter --help')",
                            name);
    if (infos[id].metavar[0] && (!arg || !arg[0]) && id != F_COMPONENTS)
        return vv_error_set(VV_ERR_INVALID, "--%s needs an argument %s", infos[id].name,
                            infos[id].metavar);
    step st;
    memset(&st, 0, sizeof st);
    st.id = id;
    st.arg = vv_strdup(arg ? arg : "");
    if (!st.arg)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (strchr(st.arg, ' ') || strlen(st.arg) > 4096) {
        vv_status s = bad(&st, "argument must not contain spaces");
        step_clear(&st);
        return s;
    }
    vv_status s = parse_step(&st);
    if (s != VV_OK) {
        step_clear(&st);
        return s;
    }
    if (c->n == c->cap) {
        int cap = c->cap ? 2 * c->cap : 8;
        step *ns = realloc(c->steps, (size_t)cap * sizeof *ns);
        if (!ns) {
            step_clear(&st);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        c->steps = ns;
        c->cap = cap;
    }
    c->steps[c->n++] = st;
    s = rebuild_text(c);
    if (s != VV_OK) {
        step_clear(&c->steps[--c->n]);
        return s;
    }
    return VV_OK;
}

vv_status
vv_filter_chain_parse(const char *text, vv_filter_chain **out) {
    if (!text || !out)
        return vv_error_set(VV_ERR_INVALID, "filter chain: NULL argument");
    vv_filter_chain *c;
    vv_status s = vv_filter_chain_new(&c);
    if (s != VV_OK)
        return s;
    char *buf = vv_strdup(text);
    if (!buf) {
        vv_filter_chain_free(c);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    char *save = NULL, *w = strtok_r(buf, " \t\r\n", &save);
    while (w && s == VV_OK) {
        if (strncmp(w, "--", 2) != 0) {
            s = vv_error_set(VV_ERR_INVALID, "filter chain: \"%s\" is not a filter (--NAME)", w);
            break;
        }
        int id = find_filter(w);
        if (id < 0) {
            s = vv_error_set(VV_ERR_INVALID, "unknown filter \"%s\"", w + 2);
            break;
        }
        char *arg = NULL;
        if (infos[id].metavar[0]) {
            arg = strtok_r(NULL, " \t\r\n", &save);
            if (arg && strncmp(arg, "--", 2) == 0 && id != F_COMPONENTS) {
                s = vv_error_set(VV_ERR_INVALID, "--%s needs an argument %s", infos[id].name,
                                 infos[id].metavar);
                break;
            }
            if (arg && strncmp(arg, "--", 2) == 0) {
                /* --components without its optional argument */
                s = vv_filter_chain_add(c, w, NULL);
                w = arg;
                continue;
            }
        }
        s = vv_filter_chain_add(c, w, arg);
        w = strtok_r(NULL, " \t\r\n", &save);
    }
    free(buf);
    if (s != VV_OK) {
        vv_filter_chain_free(c);
        return s;
    }
    *out = c;
    return VV_OK;
}

const char *
vv_filter_chain_text(const vv_filter_chain *c) {
    return c && c->text ? c->text : "";
}

/* ---- applying ---------------------------------------------------------------------- */

typedef struct sub_progress {
    const vv_filter_options *o;
    double p0, p1;
} sub_progress;

static int
sub_report(void *u, double f) {
    sub_progress *P = u;
    return vv_progress_report(&P->o->progress, P->p0 + (P->p1 - P->p0) * f);
}

static vv_status
apply_step(const step *st, const vv_volume *in, const vv_filter_options *o, vv_volume **out) {
    switch (st->id) {
    case F_GAUSSIAN: {
        double s[3];
        for (int a = 0; a < 3; a++)
            s[a] = st->voxels ? st->d[a] * in->spacing[a] : st->d[a];
        return vv_filter_gaussian(in, s, o, out);
    }
    case F_MEDIAN:
        return vv_filter_median(in, st->n[0], o, out);
    case F_BILATERAL:
        return vv_filter_bilateral(in, st->d[0], st->d[1], o, out);
    case F_DIFFUSION:
        return vv_filter_diffusion(in, st->n[0], st->d[0], st->d[1], o, out);
    case F_RESAMPLE:
        return vv_filter_resample_spacing(in, st->d, st->kernel, o, out);
    case F_RESIZE:
        return vv_filter_resample(in, st->n, st->kernel, o, out);
    case F_CROP:
        return vv_filter_crop(in, st->n, st->n + 3, o, out);
    case F_PAD:
        return vv_filter_pad(in, st->n, st->n, st->d[0], o, out);
    case F_FLIP:
        return vv_filter_flip(in, st->n[0], o, out);
    case F_PERMUTE:
        return vv_filter_permute(in, st->n, o, out);
    case F_CAST:
        return vv_filter_cast(in, st->type, st->rescale, o, out);
    case F_GRADIENT:
        return vv_filter_gradient_magnitude(in, st->d[0], o, out);
    case F_GRADIENT_COMPONENT: {
        vv_volume *g[3];
        vv_status s = vv_filter_gradient(in, st->d[0], o, g);
        if (s != VV_OK)
            return s;
        for (int a = 0; a < 3; a++)
            if (a != st->n[0])
                vv_volume_free(g[a]);
        *out = g[st->n[0]];
        return VV_OK;
    }
    case F_LAPLACIAN:
        return vv_filter_laplacian(in, st->d[0], o, out);
    case F_VESSELNESS:
        return vv_filter_vesselness(in, st->scales, st->n_scales, 0.5, 0.5, 0, st->bright, o, out);
    case F_THRESHOLD: {
        double lo = st->d[0];
        if (st->otsu) {
            vv_status s = vv_filter_otsu(in, &lo);
            if (s != VV_OK)
                return s;
            return vv_filter_threshold(in, lo, INFINITY, o, out);
        }
        return vv_filter_threshold(in, lo, st->d[1], o, out);
    }
    case F_WINDOW:
        return vv_filter_window(in, st->d[0], st->d[1], o, out);
    case F_GROW:
        return vv_filter_region_grow(in, (const int(*)[3])st->seeds, st->n_seeds, st->d[0],
                                     st->d[1], st->n[0], o, out);
    case F_COMPONENTS:
        return vv_filter_components(in, st->n[0], st->type, o, out, NULL, NULL);
    case F_LARGEST:
        return vv_filter_largest(in, st->n[0], st->n[1], o, out);
    case F_ERODE:
        return vv_filter_morphology(in, VV_MORPH_ERODE, st->n[0], o, out);
    case F_DILATE:
        return vv_filter_morphology(in, VV_MORPH_DILATE, st->n[0], o, out);
    case F_OPEN:
        return vv_filter_morphology(in, VV_MORPH_OPEN, st->n[0], o, out);
    case F_CLOSE:
        return vv_filter_morphology(in, VV_MORPH_CLOSE, st->n[0], o, out);
    case F_FILL_HOLES:
        return vv_filter_fill_holes(in, o, out);
    }
    return vv_error_set(VV_ERR_INVALID, "unknown filter step");
}

vv_status
vv_filter_chain_apply(const vv_filter_chain *c, const vv_volume *in, const vv_filter_options *o,
                      vv_volume **out) {
    if (!c || !in || !out)
        return vv_error_set(VV_ERR_INVALID, "filter chain: NULL argument");
    vv_filter_options base;
    vv_filter_options_init(&base);
    if (o)
        base = *o;
    vv_volume *cur = vv_volume_ref((vv_volume *)in);
    for (int i = 0; i < c->n; i++) {
        sub_progress P = {&base, (double)i / c->n, (double)(i + 1) / c->n};
        vv_filter_options so = base;
        so.progress.fn = base.progress.fn ? sub_report : NULL;
        so.progress.user = &P;
        vv_volume *next = NULL;
        vv_status s = apply_step(&c->steps[i], cur, &so, &next);
        vv_volume_free(cur);
        if (s != VV_OK) {
            const step *st = &c->steps[i];
            return vv_error_prefix(s, "step %d (--%s%s%s)", i + 1, infos[st->id].name,
                                   st->arg[0] ? " " : "", st->arg);
        }
        cur = next;
    }
    *out = cur;
    return VV_OK;
}

/* ---- cache of filtered volumes --------------------------------------------------------- */

typedef struct cache_entry {
    char *key;
    vv_volume *vol;
    uint64_t used;
} cache_entry;

/* Loaded, filtered volumes are immutable and keyed by everything they
 * depend on. */
struct vv_filter_cache {
    pthread_mutex_t lock;
    int n;
    cache_entry *e;
    uint64_t tick;
};

vv_status
vv_filter_cache_new(vv_filter_cache **out, int capacity) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "filter cache: NULL output");
    *out = NULL;
    if (capacity < 1 || capacity > 64)
        return vv_error_set(VV_ERR_INVALID, "filter cache: capacity %d is not in 1..64", capacity);
    vv_filter_cache *c = calloc(1, sizeof *c);
    if (c)
        c->e = calloc((size_t)capacity, sizeof *c->e);
    if (!c || !c->e) {
        free(c);
        return vv_error_set(VV_ERR_NOMEM, "filter cache: out of memory");
    }
    pthread_mutex_init(&c->lock, NULL);
    c->n = capacity;
    *out = c;
    return VV_OK;
}

void
vv_filter_cache_free(vv_filter_cache *c) {
    if (!c)
        return;
    for (int i = 0; i < c->n; i++) {
        free(c->e[i].key);
        vv_volume_free(c->e[i].vol);
    }
    pthread_mutex_destroy(&c->lock);
    free(c->e);
    free(c);
}

vv_status
vv_filter_load_cached(vv_filter_cache *cache, const char *path, const double *origin,
                      const double *spacing, const vv_filter_chain *chain,
                      const vv_filter_options *o, vv_volume **out) {
    if (!path || !out)
        return vv_error_set(VV_ERR_INVALID, "filter: NULL argument");
    struct stat sb;
    char *key = NULL;
    if (cache && stat(path, &sb) == 0) {
        const char *ct = vv_filter_chain_text(chain);
        size_t n = strlen(path) + strlen(ct) + 256;
        key = malloc(n);
        if (!key)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        int m = snprintf(key, n, "%s\n%lld %lld.%09ld\n", path, (long long)sb.st_size,
                         (long long)sb.st_mtim.tv_sec, (long)sb.st_mtim.tv_nsec);
        if (origin)
            m += snprintf(key + m, n - (size_t)m, "o %.17g %.17g %.17g\n", origin[0], origin[1],
                          origin[2]);
        if (spacing)
            m += snprintf(key + m, n - (size_t)m, "s %.17g %.17g %.17g\n", spacing[0], spacing[1],
                          spacing[2]);
        snprintf(key + m, n - (size_t)m, "%s", ct);
        pthread_mutex_lock(&cache->lock);
        for (int i = 0; i < cache->n; i++)
            if (cache->e[i].key && strcmp(cache->e[i].key, key) == 0) {
                cache->e[i].used = ++cache->tick;
                *out = vv_volume_ref(cache->e[i].vol);
                pthread_mutex_unlock(&cache->lock);
                free(key);
                return VV_OK;
            }
        pthread_mutex_unlock(&cache->lock);
    }
    vv_volume *v = NULL, *f = NULL;
    vv_status s = vv_volume_load(&v, path, NULL);
    if (s != VV_OK) {
        free(key);
        return s;
    }
    if (chain && chain->n > 0) {
        s = vv_filter_chain_apply(chain, v, o, &f);
        vv_volume_free(v);
        if (s != VV_OK) {
            free(key);
            return s;
        }
    } else {
        f = v;
    }
    /* f is ours alone until it goes into the cache */
    for (int a = 0; a < 3; a++) {
        if (origin)
            f->origin[a] = origin[a];
        if (spacing)
            f->spacing[a] = spacing[a];
    }
    if (key) {
        pthread_mutex_lock(&cache->lock);
        int slot = 0;
        for (int i = 0; i < cache->n; i++) {
            if (!cache->e[i].key) {
                slot = i;
                break;
            }
            if (cache->e[i].used < cache->e[slot].used)
                slot = i;
        }
        free(cache->e[slot].key);
        vv_volume_free(cache->e[slot].vol);
        cache->e[slot].key = key;
        cache->e[slot].vol = vv_volume_ref(f);
        cache->e[slot].used = ++cache->tick;
        pthread_mutex_unlock(&cache->lock);
    }
    *out = f;
    return VV_OK;
}
