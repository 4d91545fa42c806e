/*
 * Sampling-kernel tables of volume sampling (Wang and Kaufman, "Volume Sampled
 * Voxelization of Geometric Primitives", IEEE Visualization '93): the
 * density of a voxel whose centre lies at signed distance d from a locally
 * flat surface is the integral of the 3-D kernel over the half-space beyond
 * the plane at distance d. For a spherically symmetric kernel h(r) that
 * integral only depends on d, through the kernel's projection onto a line,
 *   p(t) = 2 pi * integral_{|t|}^{R} h(r) r dr,
 * so the table is F(d) = integral_{d}^{R} p(t) dt / integral_{-R}^{R} p(t) dt.
 * Both integrals are done numerically here; vv_sampling_kernel_integral gives the
 * closed forms the tests compare against.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "volvis/modeling.h"

const char *
vv_sampling_kernel_name(vv_sampling_kernel_kind k) {
    switch (k) {
    case VV_SAMPLING_KERNEL_BOX:
        return "box";
    case VV_SAMPLING_KERNEL_TENT:
        return "tent";
    case VV_SAMPLING_KERNEL_GAUSS:
        return "gauss";
    }
    return "unknown";
}

vv_status
vv_sampling_kernel_parse(const char *name, vv_sampling_kernel_kind *out) {
    if (!name || !out)
        return vv_error_set(VV_ERR_INVALID, "sampling kernel: NULL argument");
    if (strcmp(name, "box") == 0)
        *out = VV_SAMPLING_KERNEL_BOX;
    else if (strcmp(name, "tent") == 0 || strcmp(name, "linear") == 0)
        *out = VV_SAMPLING_KERNEL_TENT;
    else if (strcmp(name, "gauss") == 0 || strcmp(name, "gaussian") == 0)
        *out = VV_SAMPLING_KERNEL_GAUSS;
    else
        return vv_error_set(VV_ERR_INVALID, "unknown filter \"%s\"; expected box, tent or gauss",
                            name);
    return VV_OK;
}

/* The radial profile h(r), r in [0, R]. */
static double
radial(vv_sampling_kernel_kind k, double R, double r) {
    if (r > R)
        return 0.0;
    switch (k) {
    case VV_SAMPLING_KERNEL_BOX:
        return 1.0;
    case VV_SAMPLING_KERNEL_TENT:
        return 1.0 - r / R;
    case VV_SAMPLING_KERNEL_GAUSS: {
        double s = 0.5 * R;
        return exp(-r * r / (2 * s * s)) - exp(-R * R / (2 * s * s));
    }
    }
    return 0.0;
}

/* Projection p(t) = 2 pi * integral_{|t|}^R h(r) r dr by composite Simpson. */
static double
projection(vv_sampling_kernel_kind k, double R, double t) {
    double a = fabs(t);
    if (a >= R)
        return 0.0;
    const int m = 64; /* even */
    double hstep = (R - a) / m, sum = 0.0;
    for (int i = 0; i <= m; i++) {
        double r = a + i * hstep;
        double w = (i == 0 || i == m) ? 1.0 : ((i & 1) ? 4.0 : 2.0);
        sum += w * radial(k, R, r) * r;
    }
    return 2.0 * VV_PI * sum * hstep / 3.0;
}

vv_status
vv_sampling_kernel_table_new(vv_sampling_kernel_table **out, vv_sampling_kernel_kind kind,
                             double radius, int n) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "sampling kernel table: NULL output");
    *out = NULL;
    if (kind != VV_SAMPLING_KERNEL_BOX && kind != VV_SAMPLING_KERNEL_TENT &&
        kind != VV_SAMPLING_KERNEL_GAUSS)
        return vv_error_set(VV_ERR_INVALID, "sampling kernel table: unknown kernel %d", (int)kind);
    if (!(radius >= 0.25 && radius <= 16.0))
        return vv_error_set(VV_ERR_INVALID,
                            "sampling kernel table: radius %g voxels is outside [0.25, 16]",
                            radius);
    if (n <= 0)
        n = VV_SAMPLING_KERNEL_TABLE_SIZE;
    if (n < 2 || n > (1 << 20))
        return vv_error_set(VV_ERR_INVALID,
                            "sampling kernel table: %d entries is outside [2, 2^20]", n);
    vv_sampling_kernel_table *t = calloc(1, sizeof *t);
    /* cumulative integral on a grid 8x finer than the table, trapezoid rule */
    int fine = 8 * (n - 1);
    double *cum = malloc((size_t)(fine + 1) * sizeof *cum);
    if (t)
        t->density = malloc((size_t)n * sizeof *t->density);
    if (!t || !cum || !t->density) {
        free(cum);
        vv_sampling_kernel_table_free(t);
        return vv_error_set(VV_ERR_NOMEM, "sampling kernel table: out of memory");
    }
    t->kind = kind;
    t->radius = radius;
    t->n = n;
    double h = 2.0 * radius / fine;
    /* cum[i] = integral from d_i = -R + i h to R, built from the right */
    cum[fine] = 0.0;
    double prev = projection(kind, radius, radius);
    for (int i = fine - 1; i >= 0; i--) {
        double cur = projection(kind, radius, -radius + i * h);
        /* Simpson on each fine interval with its midpoint */
        double mid = projection(kind, radius, -radius + (i + 0.5) * h);
        cum[i] = cum[i + 1] + h * (cur + 4.0 * mid + prev) / 6.0;
        prev = cur;
    }
    double total = cum[0];
    for (int i = 0; i < n; i++)
        t->density[i] = (float)(cum[i * 8] / total);
    /* exact symmetry and end values: F(-d) = 1 - F(d) */
    for (int i = 0; i < n / 2; i++) {
        double a = 0.5 * (t->density[i] + 1.0 - t->density[n - 1 - i]);
        t->density[i] = (float)a;
        t->density[n - 1 - i] = (float)(1.0 - a);
    }
    if (n & 1)
        t->density[n / 2] = 0.5f;
    t->density[0] = 1.0f;
    t->density[n - 1] = 0.0f;
    free(cum);
    *out = t;
    return VV_OK;
}

void
vv_sampling_kernel_table_free(vv_sampling_kernel_table *t) {
    if (!t)
        return;
    free(t->density);
    free(t);
}

double
vv_sampling_kernel_table_eval(const vv_sampling_kernel_table *t, double d) {
    double x = (d / t->radius + 1.0) * 0.5 * (t->n - 1);
    if (!(x > 0.0))
        return 1.0;
    if (x >= t->n - 1)
        return 0.0;
    int i = (int)x;
    double f = x - i;
    return t->density[i] + f * (t->density[i + 1] - t->density[i]);
}

/* Closed-form integral beyond d >= 0 (unnormalised) of each projection. */
static double
beyond(vv_sampling_kernel_kind k, double R, double d) {
    switch (k) {
    case VV_SAMPLING_KERNEL_BOX: /* p ~ R^2 - t^2 */
        return R * R * (R - d) - (R * R * R - d * d * d) / 3.0;
    case VV_SAMPLING_KERNEL_TENT: /* p ~ R^2/6 - t^2/2 + |t|^3/(3R) */
        return R * R * R / 12.0 - R * R * d / 6.0 + d * d * d / 6.0 - d * d * d * d / (12.0 * R);
    case VV_SAMPLING_KERNEL_GAUSS: {
        /* p ~ s^2 (exp(-t^2/2s^2) - E) - E (R^2 - t^2) / 2, E = exp(-R^2/2s^2) */
        double s = 0.5 * R, c = s * sqrt(2.0), E = exp(-R * R / (2 * s * s));
        return s * s * (s * sqrt(VV_PI / 2.0) * (erf(R / c) - erf(d / c)) - E * (R - d)) -
               0.5 * E * (R * R * (R - d) - (R * R * R - d * d * d) / 3.0);
    }
    }
    return 0.0;
}

double
vv_sampling_kernel_integral(vv_sampling_kernel_kind kind, double radius, double d) {
    if (d <= -radius)
        return 1.0;
    if (d >= radius)
        return 0.0;
    double total = 2.0 * beyond(kind, radius, 0.0);
    if (d >= 0)
        return beyond(kind, radius, d) / total;
    return 1.0 - beyond(kind, radius, -d) / total;
}
