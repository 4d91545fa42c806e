/*
 * Joint histograms of data value x gradient magnitude (Measurement), the
 * domain of 2-D transfer functions (Kniss, Kindlmann and Hansen 2002).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/measure.h"

/** The index-gradient to world-gradient matrix of @p v. Returns 0 when singular. */
static int
gradient_matrix(const vv_volume *v, double g2w[3][3]) {
    vv_mat4 m = vv_volume_index_to_world(v);
    int ok = 0;
    vv_mat4 inv = vv_mat4_inverse(m, &ok);
    if (!ok)
        return 0;
    /* world gradient = M^-T (index gradient), M the linear part of index -> world */
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            g2w[r][c] = inv.m[c][r];
    return 1;
}

/**
 * Gradient magnitude of voxel (i, j, k) of @p v as vv_histogram2d_compute
 * defines it; @p g2w is the 3x3 inverse transpose of the linear part of the
 * volume's index-to-world matrix (gradient_matrix).
 */
static double
gradient_at(const vv_volume *v, const double g2w[3][3], int i, int j, int k) {
    const int idx[3] = {i, j, k};
    double g[3];
    for (int a = 0; a < 3; a++) {
        int lo = idx[a] > 0 ? idx[a] - 1 : idx[a];
        int hi = idx[a] < v->dims[a] - 1 ? idx[a] + 1 : idx[a];
        if (hi == lo) {
            g[a] = 0.0;
            continue;
        }
        int p[3] = {i, j, k}, q[3] = {i, j, k};
        p[a] = lo;
        q[a] = hi;
        g[a] = (vv_volume_get(v, q[0], q[1], q[2]) - vv_volume_get(v, p[0], p[1], p[2])) /
               (double)(hi - lo);
    }
    double w[3];
    for (int r = 0; r < 3; r++)
        w[r] = g2w[r][0] * g[0] + g2w[r][1] * g[1] + g2w[r][2] * g[2];
    return sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
}

void
vv_histogram2d_free(vv_histogram2d *h) {
    if (!h)
        return;
    free(h->counts);
    free(h);
}

vv_status
vv_histogram2d_compute(vv_histogram2d **out, const vv_volume *v, int nbins_value,
                       int nbins_gradient, double value_lo, double value_hi, double gradient_hi) {
    if (!out || !v)
        return vv_error_set(VV_ERR_INVALID, "joint histogram: NULL %s", out ? "volume" : "output");
    *out = NULL;
    if (nbins_value < 1 || nbins_value > 65536 || nbins_gradient < 1 || nbins_gradient > 65536)
        return vv_error_set(VV_ERR_INVALID, "joint histogram: %d x %d bins (each 1..65536)",
                            nbins_value, nbins_gradient);
    if (!isfinite(value_lo) || !isfinite(value_hi) || !isfinite(gradient_hi))
        return vv_error_set(VV_ERR_INVALID, "joint histogram: non-finite range");
    double g2w[3][3];
    if (!gradient_matrix(v, g2w))
        return vv_error_set(VV_ERR_INVALID, "joint histogram: singular index-to-world matrix");
    const int nx = v->dims[0], ny = v->dims[1], nz = v->dims[2];
    const size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    float *gm = malloc(n * sizeof *gm);
    vv_histogram2d *h = calloc(1, sizeof *h);
    if (h)
        h->counts = calloc((size_t)nbins_value * (size_t)nbins_gradient, sizeof *h->counts);
    if (!gm || !h || !h->counts) {
        free(gm);
        vv_histogram2d_free(h);
        return vv_error_set(VV_ERR_NOMEM, "joint histogram: out of memory for %zu voxels", n);
    }
    double gmax = 0.0;
#pragma omp parallel for schedule(static) reduction(max : gmax)
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                double g = gradient_at(v, (const double(*)[3])g2w, i, j, k);
                gm[((size_t)k * ny + j) * nx + i] = (float)g;
                if (g > gmax)
                    gmax = g;
            }
    if (!(value_lo < value_hi)) {
        value_lo = v->range[0];
        value_hi = v->range[1];
        if (!(value_hi > value_lo))
            value_hi = value_lo + 1.0;
    }
    if (!(gradient_hi > 0.0))
        gradient_hi = gmax > 0.0 ? gmax : 1.0;
    h->nbins_value = nbins_value;
    h->nbins_gradient = nbins_gradient;
    h->value_lo = value_lo;
    h->value_hi = value_hi;
    h->gradient_lo = 0.0;
    h->gradient_hi = gradient_hi;
    h->gradient_max = gmax;
    const double vs = nbins_value / (value_hi - value_lo), gs = nbins_gradient / gradient_hi;
    size_t idx = 0;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++, idx++) {
                double x = vv_volume_get(v, i, j, k), g = gm[idx];
                if (isnan(x) || isnan(g))
                    continue;
                h->total++;
                if (x < value_lo || x > value_hi || g > gradient_hi) {
                    h->outside++;
                    continue;
                }
                int bv = (int)((x - value_lo) * vs), bg = (int)(g * gs);
                bv = bv >= nbins_value ? nbins_value - 1 : bv;
                bg = bg >= nbins_gradient ? nbins_gradient - 1 : bg;
                h->counts[(size_t)bg * nbins_value + bv]++;
            }
    free(gm);
    *out = h;
    return VV_OK;
}
