/*
 * The default scene for one volume (what `volvis render FILE` shows): the
 * volume centred on the origin, a framed perspective view from the front, a
 * headlight and a transfer function derived from the histogram. The rule is
 * documented in docs/scene-format.md, "Default scene". Its parts serve scene
 * files too: an object without an appearance of its own
 * (vv_object_default_appearance) and a scene without a view
 * (vv_world_fit_default_view) get what the file opened alone gets.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/model_internal.h"
#include "volvis/model.h"

/* Opacity per smallest voxel spacing at the top of the composite ramp. */
#define DEFAULT_MAX_OPACITY 0.5
#define HIST_MAX_BINS 4096

void
vv_default_scene_options_init(vv_default_scene_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->mode = VV_MODE_COMPOSITE;
    o->width = 512;
    o->height = 512;
    o->zoom = 1.0;
}

typedef struct hist {
    int nb;
    double lo, bw; /* value of the left edge of bin 0, bin width */
    uint64_t *bins;
    double total;
} hist;

static int
type_is_integer(vv_voxel_type t) {
    return t != VV_F32 && t != VV_F64;
}

/* Integer data with few distinct values gets one bin per value. */
static int
hist_build(hist *h, const vv_volume *v) {
    double rmin = v->range[0], rmax = v->range[1];
    memset(h, 0, sizeof *h);
    if (!isfinite(rmin) || !isfinite(rmax) || !(rmax > rmin))
        return 0;
    double lo = rmin, hi = rmax;
    int nb = HIST_MAX_BINS;
    if (type_is_integer(v->type) && rmax - rmin + 1.0 <= HIST_MAX_BINS) {
        nb = (int)(rmax - rmin) + 1;
        lo = rmin - 0.5;
        hi = rmax + 0.5;
    }
    h->bins = malloc((size_t)nb * sizeof *h->bins);
    if (!h->bins)
        return 0;
    if (vv_volume_histogram(v, nb, lo, hi, h->bins) != VV_OK) {
        free(h->bins);
        h->bins = NULL;
        vv_error_clear();
        return 0;
    }
    h->nb = nb;
    h->lo = lo;
    h->bw = (hi - lo) / nb;
    for (int i = 0; i < nb; i++)
        h->total += (double)h->bins[i];
    if (!(h->total > 0.0)) {
        free(h->bins);
        h->bins = NULL;
        return 0;
    }
    return 1;
}

/* The value below which a count @p target of voxels lies (linear inside a bin). */
static double
hist_value_at_count(const hist *h, double target) {
    double cum = 0.0;
    for (int i = 0; i < h->nb; i++) {
        double c = (double)h->bins[i];
        if (c > 0.0 && cum + c >= target) {
            double f = (target - cum) / c;
            if (f < 0.0)
                f = 0.0;
            return h->lo + (i + f) * h->bw;
        }
        cum += c;
    }
    return h->lo + h->nb * h->bw;
}

static double
clampd(double x, double lo, double hi) {
    return x < lo ? lo : (x > hi ? hi : x);
}

#define COARSE_BINS 64

/*
 * Number of background voxels. On a coarse histogram (at most 64 bins): the
 * background peak p is the fullest bin in the lowest quarter of the range
 * (air in CT, the dark surround in MRI, empty space in synthetic data).
 * Walking right from p, the valley is the lowest bin before the histogram
 * first rises clearly above it (by half, and by 0.2% of all voxels) within
 * the lower half of the range (a spike of saturated values at the top end is
 * not a tissue); the background is everything up to the middle of the
 * valley bin. Without a valley, the background is the peak bin and its
 * falling right flank down to 2% of the peak. 0 when the lowest quarter
 * holds no clear mode (its fullest coarse bin has < 5% of the voxels).
 */
static double
hist_background(const hist *h) {
    int nc = h->nb < COARSE_BINS ? h->nb : COARSE_BINS;
    double c[COARSE_BINS];
    int first[COARSE_BINS + 1];
    for (int k = 0; k <= nc; k++)
        first[k] = (int)((int64_t)k * h->nb / nc);
    for (int k = 0; k < nc; k++) {
        c[k] = 0.0;
        for (int i = first[k]; i < first[k + 1]; i++)
            c[k] += (double)h->bins[i];
    }
    int quarter = nc / 4 > 1 ? nc / 4 : 1;
    int p = 0;
    for (int k = 1; k < quarter; k++)
        if (c[k] > c[p])
            p = k;
    if (c[p] < 0.05 * h->total)
        return 0.0;
    /* the valley: walking right from p, the lowest bin before the histogram
     * first rises clearly (by half and by 0.2% of the voxels) above it */
    int valley = -1;
    int run_min = p;
    for (int q = p + 1; q <= nc / 2 && q < nc; q++) {
        if (c[q] < c[run_min])
            run_min = q;
        if (run_min > p && c[q] > 1.5 * c[run_min] + 0.002 * h->total) {
            valley = run_min;
            break;
        }
    }
    double mass = 0.0;
    if (valley >= 0) {
        int mid = (first[valley] + first[valley + 1]) / 2;
        for (int i = 0; i < mid; i++)
            mass += (double)h->bins[i];
        return mass;
    }
    int e = p;
    while (e + 1 < nc && c[e + 1] <= c[e] && c[e + 1] >= 0.02 * c[p])
        e++;
    for (int k = 0; k <= e; k++)
        mass += c[k];
    return mass;
}

static void
composite_tf(vv_tf *tf, double lo, double hi, double unit) {
    vv_tf_init(tf);
    tf->opacity_unit_distance = unit;
    if (!(hi > lo))
        hi = lo + 1.0;
    double mid = 0.5 * (lo + hi);
    (void)vv_tf_add_opacity(tf, lo, 0.0);
    (void)vv_tf_add_opacity(tf, hi, DEFAULT_MAX_OPACITY);
    /* warm map: flesh at the low end through light tan to ivory (bone) */
    (void)vv_tf_add_color(tf, lo, vv_vec3_make(0.85, 0.55, 0.45));
    (void)vv_tf_add_color(tf, mid, vv_vec3_make(0.95, 0.85, 0.70));
    (void)vv_tf_add_color(tf, hi, vv_vec3_make(1.0, 1.0, 0.95));
}

static void
grey_tf(vv_tf *tf, double lo, double hi, double unit) {
    vv_tf_init(tf);
    tf->opacity_unit_distance = unit;
    if (!(hi > lo))
        hi = lo + 1.0;
    (void)vv_tf_add_opacity(tf, lo, 0.0);
    (void)vv_tf_add_opacity(tf, hi, 1.0);
    (void)vv_tf_add_color(tf, lo, vv_vec3_make(0, 0, 0));
    (void)vv_tf_add_color(tf, hi, vv_vec3_make(1, 1, 1));
}

static int
is_projection_mode(vv_render_mode m) {
    return m == VV_MODE_MIP || m == VV_MODE_MINIP || m == VV_MODE_XRAY ||
           m == VV_MODE_ATTENUATED_MIP;
}

/* @p v's value range made usable: [0, 1] when not finite, one wide when empty. */
static void
usable_range(const vv_volume *v, double *rmin, double *rmax) {
    *rmin = v->range[0];
    *rmax = v->range[1];
    if (!isfinite(*rmin) || !isfinite(*rmax)) {
        *rmin = 0.0;
        *rmax = 1.0;
    }
    if (!(*rmax > *rmin))
        *rmax = *rmin + 1.0;
}

/* The values between the foreground's quantiles @p q_lo and @p q_hi of
 * histogram @p h (the background peak set aside; all voxels when almost
 * all are background) into [*lo, *hi], left as they are when they
 * coincide. */
static void
hist_foreground_range(const hist *h, double q_lo, double q_hi, double rmin, double rmax, double *lo,
                      double *hi) {
    double bg = hist_background(h);
    double fg = h->total - bg;
    if (fg < 0.001 * h->total) {
        /* (almost) everything is background: show what is above it */
        bg = 0.0;
        fg = h->total;
    }
    double l = clampd(hist_value_at_count(h, bg + q_lo * fg), rmin, rmax);
    double u = clampd(hist_value_at_count(h, bg + q_hi * fg), rmin, rmax);
    if (u > l) {
        *lo = l;
        *hi = u;
    }
}

/* The composite range [lo, hi] and the projection range [plo, phi]. */
static void
default_ranges(const vv_volume *v, double *lo, double *hi, double *plo, double *phi) {
    double rmin, rmax;
    usable_range(v, &rmin, &rmax);
    *lo = rmin + 0.1 * (rmax - rmin);
    *hi = rmax;
    *plo = rmin;
    *phi = rmax;
    hist h;
    if (!hist_build(&h, v))
        return;
    hist_foreground_range(&h, 0.02, 0.995, rmin, rmax, lo, hi);
    double pl = clampd(hist_value_at_count(&h, 0.01 * h.total), rmin, rmax);
    double pu = clampd(hist_value_at_count(&h, 0.999 * h.total), rmin, rmax);
    if (pu > pl) {
        *plo = pl;
        *phi = pu;
    }
    free(h.bins);
}

void
vv_volume_foreground_range(const vv_volume *v, double q_lo, double q_hi, double *lo, double *hi) {
    double rmin, rmax;
    usable_range(v, &rmin, &rmax);
    *lo = rmin;
    *hi = rmax;
    hist h;
    if (!hist_build(&h, v))
        return;
    hist_foreground_range(&h, q_lo, q_hi, rmin, rmax, lo, hi);
    free(h.bins);
}

void
vv_tf_default(vv_tf *tf, const vv_volume *v, vv_render_mode mode, double *iso_lo) {
    double lo, hi, plo, phi;
    default_ranges(v, &lo, &hi, &plo, &phi);
    double unit = vv_tf_default_unit_distance(v);
    if (is_projection_mode(mode))
        grey_tf(tf, plo, phi, unit);
    else
        composite_tf(tf, lo, hi, unit);
    if (iso_lo)
        *iso_lo = lo;
}

void
vv_object_default_appearance(vv_object *obj, const vv_volume *histogram, const vv_volume *shown) {
    if (!obj || obj->type != VV_OBJECT_VOLUME || !obj->volume)
        return;
    double iso_lo;
    vv_tf_default(&obj->tf, histogram ? histogram : obj->volume, obj->mode, &iso_lo);
    obj->tf.opacity_unit_distance = vv_tf_default_unit_distance(shown ? shown : obj->volume);
    obj->isovalue = iso_lo;
    obj->threshold = iso_lo;
}

/* The default view's axes for @p volume: perspective, fov 30 degrees,
 * looking at the origin from the front of the patient (or face on at a
 * single slice), up +z; framed later. */
static void
volume_view_axes(vv_view *v, const vv_volume *volume) {
    v->projection = VV_PROJECTION_PERSPECTIVE;
    v->fov = vv_deg_to_rad(30.0);
    /* In front of the patient: anterior is -y in LPS and +y in RAS; data
     * without a known frame (most CT and MRI exports, e.g. the InVesalius
     * head) are far more often RAS-like, so +y is the default. */
    v->eye = vv_vec3_make(0, volume->space == VV_SPACE_LPS ? -1 : 1, 0);
    v->at = vv_vec3_make(0, 0, 0);
    v->up = vv_vec3_make(0, 0, 1);
    /* a single slice (a 2-D image) is looked at face on, along its one-voxel
     * axis (as seen through the direction matrix), not edge on */
    for (int a = 0; a < 3; a++)
        if (volume->dims[a] == 1 && volume->dims[(a + 1) % 3] > 1 &&
            volume->dims[(a + 2) % 3] > 1) {
            const double *d = volume->direction;
            vv_vec3 axis = vv_vec3_make(d[a], d[3 + a], d[6 + a]);
            int b = (a + 1) % 3; /* the slice's first in-plane axis gives "up" */
            v->eye = axis;
            v->up = vv_vec3_make(d[b + 3 * 0], d[b + 3 * 1], d[b + 3 * 2]);
            if (a == 2) /* z-slices: x right, y up, as an image is shown */
                v->up = vv_vec3_make(d[1], d[4], d[7]);
            break;
        }
}

/* The default view of a grid (and of a World without a volume): from -y, up +z. */
static void
grid_view_axes(vv_view *v) {
    v->projection = VV_PROJECTION_PERSPECTIVE;
    v->fov = vv_deg_to_rad(30.0);
    v->eye = vv_vec3_make(0, -1, 0);
    v->at = vv_vec3_make(0, 0, 0);
    v->up = vv_vec3_make(0, 0, 1);
}

/* The view (already pointed along its axis) framed on the World's bounds,
 * orbited and zoomed as @p opt asks, with the orthographic height of the
 * same extent. */
static void
frame_default_view(vv_world *w, const vv_default_scene_options *opt) {
    vv_view *v = &w->view;
    vv_view_frame_box(v, vv_world_bounds(w));
    vv_view_orbit(v, opt->azimuth, opt->elevation);
    vv_vec3 off = vv_vec3_sub(v->eye, v->at);
    v->eye = vv_vec3_add(v->at, vv_vec3_scale(off, 1.0 / opt->zoom));
    /* a view of the same extent if the user switches to orthographic */
    v->ortho_height = 2.0 * vv_vec3_length(off) / opt->zoom * tan(0.5 * v->fov);
}

/* A white headlight of intensity 1 along the view. */
static vv_status
add_headlight(vv_world *w) {
    vv_light light;
    memset(&light, 0, sizeof light);
    light.type = VV_LIGHT_DIRECTIONAL;
    light.headlight = 1;
    light.direction = vv_vec3_normalize(vv_vec3_sub(w->view.at, w->view.eye));
    light.color = vv_vec3_make(1, 1, 1);
    light.intensity = 1.0;
    return vv_world_add_light(w, &light);
}

/* The default scenes' common end: the view framed (frame_default_view); a
 * white headlight, white ambient light, black background. */
static void
finish_default_view(vv_world *w, const vv_default_scene_options *opt) {
    frame_default_view(w, opt);
    (void)add_headlight(w);
    w->ambient = vv_vec3_make(1, 1, 1);
    w->background = vv_vec3_make(0, 0, 0);
}

vv_status
vv_world_fit_default_view(vv_world *w, const vv_default_scene_options *opt, int headlight) {
    if (!w)
        return vv_error_set(VV_ERR_INVALID, "default view: NULL world");
    vv_default_scene_options defaults;
    if (!opt) {
        vv_default_scene_options_init(&defaults);
        opt = &defaults;
    }
    if (!(opt->zoom > 0.0) || !isfinite(opt->zoom) || !isfinite(opt->azimuth) ||
        !isfinite(opt->elevation))
        return vv_error_set(VV_ERR_INVALID, "default view: bad zoom or angles");
    const vv_volume *first = NULL;
    for (int i = 0; i < w->n_objects && !first; i++) {
        const vv_object *o = w->objects[i];
        if (o && o->visible && o->type == VV_OBJECT_VOLUME && o->volume)
            first = o->volume;
    }
    if (first)
        volume_view_axes(&w->view, first);
    else
        grid_view_axes(&w->view);
    frame_default_view(w, opt);
    return headlight ? add_headlight(w) : VV_OK;
}

vv_status
vv_world_new_for_volume(vv_world **out, vv_volume *volume, const vv_default_scene_options *opt) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "default scene: NULL output");
    *out = NULL;
    vv_default_scene_options defaults;
    if (!opt) {
        vv_default_scene_options_init(&defaults);
        opt = &defaults;
    }
    if (!volume)
        return vv_error_set(VV_ERR_INVALID, "default scene: NULL volume");
    if (opt->mode < VV_MODE_COMPOSITE || opt->mode >= VV_MODE_COUNT)
        return vv_error_set(VV_ERR_INVALID, "default scene: unknown mode %d", (int)opt->mode);
    if (opt->width < 1 || opt->width > 32768 || opt->height < 1 || opt->height > 32768)
        return vv_error_set(VV_ERR_INVALID, "default scene: image size %dx%d outside 1..32768",
                            opt->width, opt->height);
    if (!(opt->zoom > 0.0) || !isfinite(opt->zoom))
        return vv_error_set(VV_ERR_INVALID, "default scene: zoom %g must be > 0", opt->zoom);
    if (!isfinite(opt->azimuth) || !isfinite(opt->elevation))
        return vv_error_set(VV_ERR_INVALID, "default scene: azimuth and elevation must be finite");
    if (opt->has_tf_range &&
        (!isfinite(opt->tf_lo) || !isfinite(opt->tf_hi) || !(opt->tf_hi > opt->tf_lo)))
        return vv_error_set(VV_ERR_INVALID, "default scene: transfer function range %g..%g",
                            opt->tf_lo, opt->tf_hi);
    if (opt->has_isovalue && !isfinite(opt->isovalue))
        return vv_error_set(VV_ERR_INVALID, "default scene: isovalue is not finite");

    vv_world *w;
    vv_status st = vv_world_new(&w);
    if (st != VV_OK)
        return st;
    vv_object *o;
    st = vv_object_new_volume(&o, volume, "volume");
    if (st != VV_OK) {
        vv_world_free(w);
        return vv_error_prefix(st, "default scene");
    }
    o->mode = opt->mode;
    vv_object_default_appearance(o, NULL, NULL);
    if (opt->has_tf_range) {
        double unit = vv_tf_default_unit_distance(volume);
        if (is_projection_mode(opt->mode))
            grey_tf(&o->tf, opt->tf_lo, opt->tf_hi, unit);
        else
            composite_tf(&o->tf, opt->tf_lo, opt->tf_hi, unit);
        o->isovalue = opt->tf_lo;
    }
    if (opt->has_isovalue)
        o->isovalue = opt->isovalue;
    o->threshold = o->isovalue;

    /* centre the volume's own world box on the origin */
    vv_box vb = vv_volume_world_box(volume);
    vv_vec3 c = vv_vec3_scale(vv_vec3_add(vb.min, vb.max), 0.5);
    o->position = vv_vec3_scale(c, -1.0);
    st = vv_world_add_object(w, o);
    if (st != VV_OK) {
        vv_world_free(w);
        return st;
    }

    vv_view *v = &w->view;
    v->width = opt->width;
    v->height = opt->height;
    volume_view_axes(v, volume);
    finish_default_view(w, opt);
    *out = w;
    return VV_OK;
}

vv_status
vv_world_new_for_grid(vv_world **out, vv_grid *grid, const char *field, int time,
                      const vv_default_scene_options *opt) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "default scene: NULL output");
    *out = NULL;
    vv_default_scene_options defaults;
    if (!opt) {
        vv_default_scene_options_init(&defaults);
        opt = &defaults;
    }
    if (!grid)
        return vv_error_set(VV_ERR_INVALID, "default scene: NULL grid");
    if (opt->mode < VV_MODE_COMPOSITE || opt->mode >= VV_MODE_COUNT)
        return vv_error_set(VV_ERR_INVALID, "default scene: unknown mode %d", (int)opt->mode);
    if (opt->width < 1 || opt->width > 32768 || opt->height < 1 || opt->height > 32768)
        return vv_error_set(VV_ERR_INVALID, "default scene: image size %dx%d outside 1..32768",
                            opt->width, opt->height);
    if (!(opt->zoom > 0.0) || !isfinite(opt->zoom) || !isfinite(opt->azimuth) ||
        !isfinite(opt->elevation))
        return vv_error_set(VV_ERR_INVALID, "default scene: bad zoom or angles");
    if (opt->has_tf_range &&
        (!isfinite(opt->tf_lo) || !isfinite(opt->tf_hi) || !(opt->tf_hi > opt->tf_lo)))
        return vv_error_set(VV_ERR_INVALID, "default scene: transfer function range %g..%g",
                            opt->tf_lo, opt->tf_hi);
    /* the first scalar field unless one is named */
    char fname[VV_GRID_FIELD_NAME_MAX] = "";
    if (field) {
        snprintf(fname, sizeof fname, "%s", field);
    } else {
        for (int i = 0; i < grid->n_fields && !fname[0]; i++)
            if (grid->fields[i].n_components == 1) {
                snprintf(fname, sizeof fname, "%s", grid->fields[i].name);
                /* a time series "name<digits>": the series' name */
                size_t n = strlen(fname);
                while (n > 0 && fname[n - 1] >= '0' && fname[n - 1] <= '9')
                    n--;
                if (n > 0 && n < strlen(fname) && time >= 0) {
                    char base[VV_GRID_FIELD_NAME_MAX];
                    snprintf(base, sizeof base, "%.*s", (int)n, fname);
                    if (vv_grid_find_field(grid, base, time) >= 0)
                        snprintf(fname, sizeof fname, "%s", base);
                }
            }
    }
    vv_world *w;
    vv_status st = vv_world_new(&w);
    if (st != VV_OK)
        return st;
    vv_object *o;
    st = vv_object_new_grid(&o, grid, fname[0] ? fname : NULL, "grid");
    if (st == VV_OK) {
        o->time = time;
        const int f = vv_object_grid_field(o);
        if (f < 0 && grid->n_fields > 0) {
            vv_object_free(o);
            st = VV_ERR_INVALID;
        } else {
            double lo = f >= 0 ? grid->fields[f].range[0] : 0;
            double hi = f >= 0 ? grid->fields[f].range[1] : 1;
            if (!(hi > lo))
                hi = lo + 1;
            vv_box b = vv_grid_bounds(grid);
            double ext = fmax(b.max.x - b.min.x, fmax(b.max.y - b.min.y, b.max.z - b.min.z));
            ext = ext > 0 ? ext : 1;
            o->mode = opt->mode;
            double tlo = lo + 0.1 * (hi - lo), thi = hi;
            if (opt->has_tf_range) {
                tlo = opt->tf_lo;
                thi = opt->tf_hi;
            }
            if (is_projection_mode(opt->mode))
                grey_tf(&o->tf, opt->has_tf_range ? tlo : lo, thi, ext / 20);
            else
                vv_tf_set_ramp(&o->tf, tlo, thi, 0.5, vv_vec3_make(1, 1, 1), ext / 20);
            size_t n3d = 0;
            vv_grid_count_cells(grid, &n3d, NULL);
            if (n3d == 0) {
                /* a surface coloured by its field: blue, green, red over the range */
                vv_tf_init(&o->tf);
                o->tf.opacity_unit_distance = ext / 20;
                (void)vv_tf_add_opacity(&o->tf, lo, 1);
                (void)vv_tf_add_color(&o->tf, lo, vv_vec3_make(0.1, 0.2, 0.9));
                (void)vv_tf_add_color(&o->tf, 0.5 * (lo + hi), vv_vec3_make(0.2, 0.8, 0.2));
                (void)vv_tf_add_color(&o->tf, hi, vv_vec3_make(0.9, 0.15, 0.1));
            }
            o->isovalue = opt->has_isovalue ? opt->isovalue : 0.5 * (lo + hi);
            o->threshold = o->isovalue;
            vv_vec3 c = vv_vec3_scale(vv_vec3_add(b.min, b.max), 0.5);
            o->position = vv_vec3_scale(c, -1.0);
            st = vv_world_add_object(w, o);
        }
    }
    if (st != VV_OK) {
        vv_world_free(w);
        return vv_error_prefix(st, "default scene");
    }
    size_t n3 = 0, ns = 0;
    vv_grid_count_cells(grid, &n3, &ns);
    snprintf(w->render.renderer, sizeof w->render.renderer, "%s", n3 > 0 ? "irregular" : "raster");
    vv_view *v = &w->view;
    v->width = opt->width;
    v->height = opt->height;
    grid_view_axes(v);
    finish_default_view(w, opt);
    *out = w;
    return VV_OK;
}

vv_status
vv_world_new_for_source(vv_world **out, vv_source *source, int level,
                        const vv_default_scene_options *opt) {
    if (!out || !source)
        return vv_error_set(VV_ERR_INVALID, "default scene: NULL argument");
    *out = NULL;
    vv_volume *whole = vv_source_volume(source);
    if (whole)
        return vv_world_new_for_volume(out, whole, opt);
    vv_volume *proxy = NULL;
    vv_status s = vv_source_proxy(source, level, &proxy);
    if (s != VV_OK)
        return s;
    s = vv_world_new_for_volume(out, proxy, opt);
    vv_volume_free(proxy);
    if (s == VV_OK && (s = vv_object_attach_source((*out)->objects[0], source, level)) != VV_OK) {
        vv_world_free(*out);
        *out = NULL;
    }
    return s;
}
