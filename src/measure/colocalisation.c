/* Colocalisation of two channels: Pearson's correlation coefficient and
 * Manders' overlap coefficients M1 and M2 (Manders, Verbeek and Aten 1993;
 * thresholds as in Costes et al. 2004), within an optional mask. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/measure.h"

/* Sums over one slice; slices are added in order, so the result does not
 * depend on the thread count. */
typedef struct slice_sums {
    uint64_t n;
    double sa, sb;         /* pass 1: Σ a, Σ b */
    double saa, sbb, sab;  /* pass 2: centred second moments */
    double a_over, a_both; /* Σ a [a > tA], Σ a [a > tA ∧ b > tB] */
    double b_over, b_both;
} slice_sums;

/* 1 when voxel @p q is measured (inside the mask, both values finite), its
 * values in *@p x and *@p y. */
static inline int
pair_at(const vv_volume *a, const vv_volume *b, const vv_volume *mask, size_t q, double *x,
        double *y) {
    if (mask && vv_voxel_at(mask, q) == 0)
        return 0;
    *x = vv_voxel_at(a, q);
    *y = vv_voxel_at(b, q);
    return isfinite(*x) && isfinite(*y);
}

static int
same_dims(const vv_volume *x, const vv_volume *y) {
    return x->dims[0] == y->dims[0] && x->dims[1] == y->dims[1] && x->dims[2] == y->dims[2];
}

vv_status
vv_measure_colocalisation(const vv_volume *a, const vv_volume *b, const vv_volume *mask,
                          double threshold_a, double threshold_b, vv_colocalisation *out) {
    if (!a || !b || !out || !a->data || !b->data || (mask && !mask->data))
        return vv_error_set(VV_ERR_INVALID, "colocalisation: NULL argument");
    const vv_volume *other = !same_dims(a, b) ? b : mask && !same_dims(a, mask) ? mask : NULL;
    if (other)
        return vv_error_set(VV_ERR_INVALID,
                            "colocalisation: the %s is %d x %d x %d voxels, channel A %d x %d x %d "
                            "(the channels and the mask must have the same dimensions)",
                            other == b ? "channel B" : "mask", other->dims[0], other->dims[1],
                            other->dims[2], a->dims[0], a->dims[1], a->dims[2]);
    if (!isfinite(threshold_a) || !isfinite(threshold_b))
        return vv_error_set(VV_ERR_INVALID, "colocalisation: threshold %g is not finite",
                            isfinite(threshold_a) ? threshold_b : threshold_a);
    const int nz = a->dims[2];
    const size_t slice = (size_t)a->dims[0] * (size_t)a->dims[1];
    slice_sums *ss = calloc((size_t)nz, sizeof *ss);
    if (!ss)
        return vv_error_set(VV_ERR_NOMEM, "colocalisation: out of memory");

#pragma omp parallel for num_threads(vv_threads_get()) schedule(dynamic, 1)
    for (int k = 0; k < nz; k++) {
        slice_sums *s = &ss[k];
        const size_t q0 = (size_t)k * slice;
        for (size_t q = q0; q < q0 + slice; q++) {
            double x, y;
            if (!pair_at(a, b, mask, q, &x, &y))
                continue;
            s->n++;
            s->sa += x;
            s->sb += y;
            int xa = x > threshold_a, yb = y > threshold_b;
            s->a_over += xa ? x : 0;
            s->b_over += yb ? y : 0;
            s->a_both += xa && yb ? x : 0;
            s->b_both += xa && yb ? y : 0;
        }
    }
    slice_sums t;
    memset(&t, 0, sizeof t);
    for (int k = 0; k < nz; k++) {
        t.n += ss[k].n;
        t.sa += ss[k].sa;
        t.sb += ss[k].sb;
        t.a_over += ss[k].a_over;
        t.b_over += ss[k].b_over;
        t.a_both += ss[k].a_both;
        t.b_both += ss[k].b_both;
    }
    const double ma = t.n ? t.sa / (double)t.n : NAN, mb = t.n ? t.sb / (double)t.n : NAN;

#pragma omp parallel for num_threads(vv_threads_get()) schedule(dynamic, 1)
    for (int k = 0; k < nz; k++) {
        slice_sums *s = &ss[k];
        const size_t q0 = (size_t)k * slice;
        for (size_t q = q0; q < q0 + slice; q++) {
            double x, y;
            if (!pair_at(a, b, mask, q, &x, &y))
                continue;
            double dx = x - ma, dy = y - mb;
            s->saa += dx * dx;
            s->sbb += dy * dy;
            s->sab += dx * dy;
        }
    }
    for (int k = 0; k < nz; k++) {
        t.saa += ss[k].saa;
        t.sbb += ss[k].sbb;
        t.sab += ss[k].sab;
    }
    free(ss);

    memset(out, 0, sizeof *out);
    out->voxels = t.n;
    out->pearson = t.saa > 0 && t.sbb > 0 ? t.sab / sqrt(t.saa * t.sbb) : NAN;
    if (out->pearson > 1)
        out->pearson = 1;
    if (out->pearson < -1)
        out->pearson = -1;
    out->manders_m1 = t.a_over != 0 ? t.a_both / t.a_over : NAN;
    out->manders_m2 = t.b_over != 0 ? t.b_both / t.b_over : NAN;
    out->threshold[0] = threshold_a;
    out->threshold[1] = threshold_b;
    out->mean[0] = ma;
    out->mean[1] = mb;
    return VV_OK;
}
