/*
 * Histograms of a volume or a region of it (Measurement component), and
 * their plots as PNG through cairo.
 */
#include <cairo.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "measure/measure_internal.h"

void
vv_roi_init(vv_roi *r) {
    if (!r)
        return;
    memset(r, 0, sizeof *r);
    r->roi_max[0] = r->roi_max[1] = r->roi_max[2] = -1;
}

vv_status
region_resolve(const vv_volume *v, const vv_roi *r, region_box *out) {
    memset(out, 0, sizeof *out);
    for (int a = 0; a < 3; a++) {
        out->lo[a] = 0;
        out->hi[a] = v->dims[a] - 1;
    }
    if (!r)
        return VV_OK;
    if (r->roi_max[0] >= 0)
        for (int a = 0; a < 3; a++) {
            if (r->roi_min[a] < 0 || r->roi_max[a] >= v->dims[a] || r->roi_min[a] > r->roi_max[a])
                return vv_error_set(VV_ERR_INVALID,
                                    "region %d..%d on axis %c is empty or outside the volume's "
                                    "0..%d",
                                    r->roi_min[a], r->roi_max[a], "ijk"[a], v -> dims[a] - 1);
            out->lo[a] = r->roi_min[a];
            out->hi[a] = r->roi_max[a];
        }
    if (r->n_cut_planes < 0 || r->n_cut_planes > VV_MAX_CUT_PLANES)
        return vv_error_set(VV_ERR_INVALID, "%d cut planes (0..%d)", r->n_cut_planes,
                            VV_MAX_CUT_PLANES);
    vv_mat4 M = vv_volume_index_to_world(v);
    for (int p = 0; p < r->n_cut_planes; p++) {
        vv_vec3 n = r->cut_planes[p].normal;
        if (!(vv_vec3_length(n) > 0))
            return vv_error_set(VV_ERR_INVALID, "cut plane %d has a zero normal", p);
        n = vv_vec3_normalize(n);
        /* n · (M (i,j,k,1) - p) = (M3^T n) · (i,j,k) + n · (t - p) */
        for (int c = 0; c < 3; c++)
            out->a[p][c] = M.m[0][c] * n.x + M.m[1][c] * n.y + M.m[2][c] * n.z;
        vv_vec3 t = vv_vec3_make(M.m[0][3], M.m[1][3], M.m[2][3]);
        out->b[p] = vv_vec3_dot(n, vv_vec3_sub(t, r->cut_planes[p].point));
    }
    out->n_planes = r->n_cut_planes;
    return VV_OK;
}

void
vv_histogram_free(vv_histogram *h) {
    if (!h)
        return;
    free(h->counts);
    free(h);
}

/* What the passes add up: the statistics (pass 1) and the bins (pass 2). */
typedef struct hist_acc {
    double vmin, vmax, sum, sum2;
    uint64_t total, nan, outside;
} hist_acc;

static void
hist_acc_init(hist_acc *a) {
    memset(a, 0, sizeof *a);
    a->vmin = INFINITY;
    a->vmax = -INFINITY;
}

/* Pass 1 over the voxels of @p v in @p rb: added to @p a. */
static void
stats_pass(const vv_volume *v, const region_box *rb, int nt, hist_acc *a) {
    const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
    double vmin = INFINITY, vmax = -INFINITY, sum = 0, sum2 = 0;
    uint64_t total = 0, nan = 0;
#pragma omp parallel for num_threads(nt) schedule(static) reduction(min : vmin)                 \
    reduction(max : vmax) reduction(+ : sum, sum2, total, nan)
    for (int k = rb->lo[2]; k <= rb->hi[2]; k++)
        for (int j = rb->lo[1]; j <= rb->hi[1]; j++)
            for (int i = rb->lo[0]; i <= rb->hi[0]; i++) {
                if (rb->n_planes && !region_keeps(rb, i, j, k))
                    continue;
                double x = vv_voxel_at(v, (size_t)k * sz + (size_t)j * sy + (size_t)i);
                if (isnan(x)) {
                    nan++;
                    continue;
                }
                total++;
                vmin = x < vmin ? x : vmin;
                vmax = x > vmax ? x : vmax;
                sum += x;
                sum2 += x * x;
            }
    a->vmin = vmin < a->vmin ? vmin : a->vmin;
    a->vmax = vmax > a->vmax ? vmax : a->vmax;
    a->sum += sum;
    a->sum2 += sum2;
    a->total += total;
    a->nan += nan;
}

/* Pass 2 over the voxels of @p v in @p rb: their bins added to @p counts
 * (@p local: nt x nbins of scratch), those outside [lo, hi] to a->outside. */
static void
bins_pass(const vv_volume *v, const region_box *rb, int nt, double lo, double hi, int nbins,
          uint64_t *counts, uint64_t *local, hist_acc *a) {
    const size_t sy = (size_t)v->dims[0], sz = sy * (size_t)v->dims[1];
    memset(local, 0, sizeof(uint64_t) * (size_t)nt * (size_t)nbins);
    uint64_t outside = 0;
    const double scale = nbins / (hi - lo);
#pragma omp parallel num_threads(nt) reduction(+ : outside)
    {
        uint64_t *mine = local + (size_t)omp_get_thread_num() * (size_t)nbins;
#pragma omp for schedule(static)
        for (int k = rb->lo[2]; k <= rb->hi[2]; k++)
            for (int j = rb->lo[1]; j <= rb->hi[1]; j++)
                for (int i = rb->lo[0]; i <= rb->hi[0]; i++) {
                    if (rb->n_planes && !region_keeps(rb, i, j, k))
                        continue;
                    double x = vv_voxel_at(v, (size_t)k * sz + (size_t)j * sy + (size_t)i);
                    if (isnan(x))
                        continue;
                    if (x < lo || x > hi) {
                        outside++;
                        continue;
                    }
                    int b = (int)((x - lo) * scale);
                    mine[b >= nbins ? nbins - 1 : b]++;
                }
    }
    for (int t = 0; t < nt; t++)
        for (int b = 0; b < nbins; b++)
            counts[b] += local[(size_t)t * (size_t)nbins + (size_t)b];
    a->outside += outside;
}

/* The bins' range: [lo, hi] as asked, or with lo >= hi the voxels' own. */
static void
bins_range(const hist_acc *a, double *lo, double *hi) {
    if (*lo >= *hi) {
        *lo = a->total ? a->vmin : 0;
        *hi = a->total ? a->vmax : 1;
        if (*hi <= *lo)
            *hi = *lo + 1;
    }
}

static vv_status
hist_new(vv_histogram **out, int nbins, int nt, uint64_t **local) {
    vv_histogram *h = calloc(1, sizeof *h);
    *local = calloc((size_t)nt * (size_t)nbins, sizeof(uint64_t));
    if (!h || !*local || !(h->counts = calloc((size_t)nbins, sizeof(uint64_t)))) {
        free(*local);
        *local = NULL;
        vv_histogram_free(h);
        return vv_error_set(VV_ERR_NOMEM, "histogram: out of memory for %d bins", nbins);
    }
    *out = h;
    return VV_OK;
}

static void
hist_finish(vv_histogram *h, const hist_acc *a, int nbins, double lo, double hi) {
    h->nbins = nbins;
    h->lo = lo;
    h->hi = hi;
    h->total = a->total;
    h->outside = a->outside;
    h->nan = a->nan;
    h->min = a->total ? a->vmin : NAN;
    h->max = a->total ? a->vmax : NAN;
    h->mean = a->total ? a->sum / (double)a->total : NAN;
    double var = a->total ? a->sum2 / (double)a->total - h->mean * h->mean : NAN;
    h->sd = a->total ? sqrt(var > 0 ? var : 0) : NAN;
}

static vv_status
check_args(int nbins, double lo, double hi) {
    if (nbins < 1 || nbins > (1 << 20))
        return vv_error_set(VV_ERR_INVALID, "histogram: %d bins (1..1048576)", nbins);
    if (!isfinite(lo) || !isfinite(hi))
        return vv_error_set(VV_ERR_INVALID, "histogram: range [%g, %g] is not finite", lo, hi);
    return VV_OK;
}

vv_status
vv_measure_histogram(vv_histogram **out, const vv_volume *v, int nbins, double lo, double hi,
                     const vv_roi *region) {
    if (out)
        *out = NULL;
    if (!out || !v || !v->data)
        return vv_error_set(VV_ERR_INVALID, "histogram: NULL argument");
    vv_status s = check_args(nbins, lo, hi);
    if (s != VV_OK)
        return s;
    region_box rb;
    if ((s = region_resolve(v, region, &rb)) != VV_OK)
        return vv_error_prefix(s, "histogram");
    const int nt = vv_threads_get();
    hist_acc a;
    hist_acc_init(&a);
    stats_pass(v, &rb, nt, &a);
    if (a.total == 0 && a.nan == 0)
        return vv_error_set(VV_ERR_INVALID, "histogram: the region holds no voxel");
    bins_range(&a, &lo, &hi);
    vv_histogram *h = NULL;
    uint64_t *local = NULL;
    if ((s = hist_new(&h, nbins, nt, &local)) != VV_OK)
        return s;
    bins_pass(v, &rb, nt, lo, hi, nbins, h->counts, local, &a);
    free(local);
    hist_finish(h, &a, nbins, lo, hi);
    *out = h;
    return VV_OK;
}

/* Box @p b of the boxes vv_measure_histogram_boxes reads (HB_X x HB_Y x
 * HB_Z voxels, x fastest): voxels lo .. hi. */
#define HB_X 128
#define HB_Y 128
#define HB_Z 64
static void
hist_box(const vv_volume *hdr, long b, int lo[3], int hi[3]) {
    const int *d = hdr->dims;
    const long nx = (d[0] + HB_X - 1) / HB_X, ny = (d[1] + HB_Y - 1) / HB_Y;
    const int c[3] = {(int)(b % nx), (int)(b / nx % ny), (int)(b / (nx * ny))};
    const int side[3] = {HB_X, HB_Y, HB_Z};
    for (int a = 0; a < 3; a++) {
        lo[a] = c[a] * side[a];
        hi[a] = lo[a] + side[a] - 1 < d[a] - 1 ? lo[a] + side[a] - 1 : d[a] - 1;
    }
}

vv_status
vv_measure_histogram_boxes(vv_histogram **out, const vv_volume *hdr, vv_box_reader read, void *ctx,
                           int nbins, double lo, double hi, const vv_progress *progress) {
    if (out)
        *out = NULL;
    if (!out || !hdr || !read)
        return vv_error_set(VV_ERR_INVALID, "histogram: NULL argument");
    vv_status s = check_args(nbins, lo, hi);
    if (s != VV_OK)
        return s;
    const int *d = hdr->dims;
    const long nb =
        (long)((d[0] + HB_X - 1) / HB_X) * ((d[1] + HB_Y - 1) / HB_Y) * ((d[2] + HB_Z - 1) / HB_Z);
    const int nt = vv_threads_get();
    hist_acc a;
    hist_acc_init(&a);
    vv_histogram *h = NULL;
    uint64_t *local = NULL;
    /* pass 1 (the statistics, and the range when not given), then pass 2 */
    for (int pass = 1; pass <= 2 && s == VV_OK; pass++) {
        if (pass == 2) {
            bins_range(&a, &lo, &hi);
            if ((s = hist_new(&h, nbins, nt, &local)) != VV_OK)
                break;
        }
        for (long b = 0; b < nb && s == VV_OK; b++) {
            int blo[3], bhi[3];
            hist_box(hdr, b, blo, bhi);
            vv_volume *v = NULL;
            if ((s = read(ctx, blo, bhi, &v)) != VV_OK)
                break;
            if (!v || v->dims[0] != bhi[0] - blo[0] + 1 || v->dims[1] != bhi[1] - blo[1] + 1 ||
                v->dims[2] != bhi[2] - blo[2] + 1) {
                vv_volume_free(v);
                s = vv_error_set(VV_ERR_INVALID, "histogram: the reader gave a box of another "
                                                 "shape");
                break;
            }
            region_box rb;
            memset(&rb, 0, sizeof rb);
            for (int k = 0; k < 3; k++)
                rb.hi[k] = v->dims[k] - 1;
            if (pass == 1)
                stats_pass(v, &rb, nt, &a);
            else
                bins_pass(v, &rb, nt, lo, hi, nbins, h->counts, local, &a);
            vv_volume_free(v);
            if (progress && vv_progress_report(progress, (pass - 1 + (double)(b + 1) / nb) / 2))
                s = vv_error_set(VV_ERR_CANCELLED, "histogram: cancelled");
        }
    }
    free(local);
    if (s != VV_OK) {
        vv_histogram_free(h);
        return s;
    }
    hist_finish(h, &a, nbins, lo, hi);
    *out = h;
    return VV_OK;
}

/* ---- plot ------------------------------------------------------------------ */

/* A "nice" tick step (1, 2 or 5 x 10^k) giving about n ticks over span. */
static double
nice_step(double span, int n) {
    double raw = span / n, p = pow(10, floor(log10(raw))), f = raw / p;
    return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * p;
}

static cairo_status_t
write_cb(void *closure, const unsigned char *data, unsigned int length) {
    return fwrite(data, 1, length, (FILE *)closure) == length ? CAIRO_STATUS_SUCCESS
                                                              : CAIRO_STATUS_WRITE_ERROR;
}

static void
text(cairo_t *cr, double x, double y, const char *s, double ax, double ay, double angle) {
    cairo_text_extents_t e;
    cairo_text_extents(cr, s, &e);
    cairo_save(cr);
    cairo_translate(cr, x, y);
    cairo_rotate(cr, angle);
    cairo_move_to(cr, -e.x_bearing - ax * e.width, -e.y_bearing - ay * e.height);
    cairo_show_text(cr, s);
    cairo_restore(cr);
}

vv_status
vv_histogram_plot_png(const vv_histogram *h, const char *path, int width, int height,
                      const char *title, const char *xlabel, int log_scale) {
    if (!h || !path || !h->counts || h->nbins < 1)
        return vv_error_set(VV_ERR_INVALID, "histogram plot: NULL argument");
    if (width < 200 || height < 200 || width > 8192 || height > 8192)
        return vv_error_set(VV_ERR_INVALID, "histogram plot: %dx%d pixels (200..8192 each)", width,
                            height);
    cairo_surface_t *sf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
    if (cairo_surface_status(sf) != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(sf);
        return vv_error_set(VV_ERR_NOMEM, "histogram plot: cannot create a %dx%d image", width,
                            height);
    }
    cairo_t *cr = cairo_create(sf);
    const double fs = height / 36.0 < 11 ? 11 : height / 36.0;
    const double L = 5.5 * fs, R = 1.5 * fs, T = 2.6 * fs, B = 4.2 * fs;
    const double pw = width - L - R, ph = height - T - B;
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, fs);
    uint64_t cmax = 1;
    for (int b = 0; b < h->nbins; b++)
        cmax = h->counts[b] > cmax ? h->counts[b] : cmax;
    const double ymax = log_scale ? log10(1.0 + (double)cmax) : (double)cmax;
    /* bars */
    cairo_set_source_rgb(cr, 0.25, 0.45, 0.75);
    for (int b = 0; b < h->nbins; b++) {
        double c = log_scale ? log10(1.0 + (double)h->counts[b]) : (double)h->counts[b];
        if (c <= 0)
            continue;
        double x0 = L + pw * b / h->nbins, x1 = L + pw * (b + 1) / h->nbins;
        double y = T + ph * (1 - c / ymax);
        cairo_rectangle(cr, x0, y, x1 - x0 < 1 ? 1 : x1 - x0, T + ph - y);
    }
    cairo_fill(cr);
    /* axes and ticks */
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1);
    cairo_move_to(cr, L, T);
    cairo_line_to(cr, L, T + ph);
    cairo_line_to(cr, L + pw, T + ph);
    cairo_stroke(cr);
    char buf[64];
    double step = nice_step(h->hi - h->lo, 8);
    for (double x = ceil(h->lo / step) * step; x <= h->hi + 1e-9 * step; x += step) {
        double px = L + pw * (x - h->lo) / (h->hi - h->lo);
        cairo_move_to(cr, px, T + ph);
        cairo_line_to(cr, px, T + ph + 0.4 * fs);
        cairo_stroke(cr);
        snprintf(buf, sizeof buf, "%g", fabs(x) < 1e-12 * step ? 0.0 : x);
        text(cr, px, T + ph + 0.6 * fs, buf, 0.5, 0, 0);
    }
    if (log_scale) {
        for (int e = 0; e <= (int)floor(ymax); e++) {
            double py = T + ph * (1 - log10(1.0 + pow(10, e)) / ymax);
            if (py < T - 1)
                break;
            cairo_move_to(cr, L, py);
            cairo_line_to(cr, L - 0.4 * fs, py);
            cairo_stroke(cr);
            snprintf(buf, sizeof buf, "1e%d", e);
            text(cr, L - 0.6 * fs, py, buf, 1, 0.5, 0);
        }
    } else {
        double ys = nice_step((double)cmax, 6);
        for (double y = 0; y <= (double)cmax + 1e-9; y += ys) {
            double py = T + ph * (1 - y / ymax);
            cairo_move_to(cr, L, py);
            cairo_line_to(cr, L - 0.4 * fs, py);
            cairo_stroke(cr);
            snprintf(buf, sizeof buf, "%.4g", y);
            text(cr, L - 0.6 * fs, py, buf, 1, 0.5, 0);
        }
    }
    text(cr, L + pw / 2, height - 1.4 * fs, xlabel ? xlabel : "value", 0.5, 0, 0);
    text(cr, 0.8 * fs, T + ph / 2, log_scale ? "voxels (log scale)" : "voxels", 0.5, 0, -VV_PI / 2);
    char head[320];
    snprintf(head, sizeof head, "%s%s%llu voxels, %d bins over [%g, %g]", title ? title : "",
             title ? ": " : "", (unsigned long long)h->total, h->nbins, h->lo, h->hi);
    text(cr, L + pw / 2, 0.7 * fs, head, 0.5, 0, 0);
    cairo_destroy(cr);
    cairo_surface_flush(sf);
    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, path);
    if (s != VV_OK) {
        cairo_surface_destroy(sf);
        return vv_error_prefix(s, "histogram plot");
    }
    cairo_status_t cs = cairo_surface_write_to_png_stream(sf, write_cb, af.fp);
    cairo_surface_destroy(sf);
    if (cs != CAIRO_STATUS_SUCCESS) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "histogram plot: %s: %s", path, cairo_status_to_string(cs));
    }
    if ((s = vv_atomic_file_commit(&af)) != VV_OK)
        return vv_error_prefix(s, "histogram plot");
    return VV_OK;
}
