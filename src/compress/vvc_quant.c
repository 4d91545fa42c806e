/*
 * The .vvc quantiser: the scan (the M^3 independent real numbers of a
 * subcube's r2c spectrum ordered by increasing frequency, a 3-D zig-zag),
 * the frequency-dependent quantisation table scaled by a quality, and the
 * rounding of a subcube's coefficients to integers. The method is in
 * include/volvis/compress.h, the file in docs/file-formats.md.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "compress/vvc_internal.h"

typedef struct scan_key {
    int sum, sq, order, entry, fold;
} scan_key;

static int
cmp_scan_key(const void *a, const void *b) {
    const scan_key *x = a, *y = b;
    if (x->sum != y->sum)
        return x->sum < y->sum ? -1 : 1;
    if (x->sq != y->sq)
        return x->sq < y->sq ? -1 : 1;
    return x->order < y->order ? -1 : x->order > y->order;
}

void
vvc_scan_free(vvc_scan *s) {
    free(s->entry);
    free(s->fold);
    free(s->mirror);
    free(s->band);
    free(s->nbr);
    free(s->band_end);
    memset(s, 0, sizeof *s);
}

vv_status
vvc_scan_init(vvc_scan *s, int M) {
    memset(s, 0, sizeof *s);
    s->M = M;
    s->H = M / 2 + 1;
    s->N = M * M * M;
    const int H = s->H;
    scan_key *keys = malloc(sizeof *keys * (size_t)s->N);
    s->entry = malloc(sizeof(int32_t) * (size_t)s->N);
    s->fold = malloc(sizeof(int32_t) * (size_t)s->N);
    s->mirror = malloc(sizeof(int32_t) * 2 * (size_t)M * (size_t)M * 2);
    if (!keys || !s->entry || !s->fold || !s->mirror) {
        free(keys);
        vvc_scan_free(s);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    int n = 0, order = 0;
    for (int kz = 0; kz < M; kz++)
        for (int ky = 0; ky < M; ky++)
            for (int kx = 0; kx < H; kx++) {
                const int c = (kz * M + ky) * H + kx;
                const int fy = ky < M - ky ? ky : M - ky, fz = kz < M - kz ? kz : M - kz;
                const int fold = (fz * H + fy) * H + kx;
                int parts = 2;
                if (kx == 0 || kx == M / 2) {
                    /* Hermitian plane: F(kx, -ky, -kz) = conj F(kx, ky, kz) */
                    const int my = (M - ky) % M, mz = (M - kz) % M;
                    if (mz < kz || (mz == kz && my < ky))
                        continue; /* the duplicate of one kept */
                    if (mz == kz && my == ky) {
                        parts = 1; /* self-conjugate: real */
                    } else {
                        s->mirror[2 * s->nmirror] = c;
                        s->mirror[2 * s->nmirror + 1] = (mz * M + my) * H + kx;
                        s->nmirror++;
                    }
                }
                for (int p = 0; p < parts; p++) {
                    keys[n].sum = kx + fy + fz;
                    keys[n].sq = kx * kx + fy * fy + fz * fz;
                    keys[n].order = order++;
                    keys[n].entry = 2 * c + p;
                    keys[n].fold = fold;
                    n++;
                }
            }
    qsort(keys, (size_t)n, sizeof *keys, cmp_scan_key);
    s->nb = 3 * (M / 2) + 1;
    s->band = malloc((size_t)s->N);
    s->nbr = malloc(sizeof(int32_t) * VVC_NBR * (size_t)s->N);
    s->band_end = malloc(sizeof(int32_t) * (size_t)(s->nb + 1));
    int32_t *pos = malloc(sizeof(int32_t) * 2 * (size_t)M * M * H);
    if (n != s->N || !s->band || !s->nbr || !s->band_end || !pos) {
        free(keys);
        free(pos);
        vvc_scan_free(s);
        return n != s->N ? vv_error_set(VV_ERR_INVALID,
                                        "internal: scan has %d entries, expected %d", n, M * M * M)
                         : vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < 2 * M * M * H; i++)
        pos[i] = -1;
    for (int i = 0; i < n; i++) {
        s->entry[i] = keys[i].entry;
        s->fold[i] = keys[i].fold;
        s->band[i] = (uint8_t)keys[i].sum;
        pos[keys[i].entry] = i;
    }
    free(keys);
    /* a Hermitian duplicate stands for the coefficient it mirrors (same magnitudes) */
    for (int m = 0; m < s->nmirror; m++)
        for (int p = 0; p < 2; p++)
            pos[2 * s->mirror[2 * m + 1] + p] = pos[2 * s->mirror[2 * m] + p];
    for (int b = 0, i = 0; b <= s->nb; b++) {
        while (i < n && s->band[i] <= b)
            i++;
        s->band_end[b] = i; /* first position past band b */
    }
    /* the three neighbours one step lower in folded frequency, same part */
    for (int i = 0; i < n; i++) {
        const int e = s->entry[i], c = e >> 1, p = e & 1;
        const int kx = c % H, ky = (c / H) % M, kz = c / (H * M);
        const int lower[3][3] = {{kx - 1, ky, kz},
                                 {kx,
                                  ky == 0       ? -1
                                  : ky <= M / 2 ? ky - 1
                                                : (ky + 1) % M,
                                  kz},
                                 {kx, ky,
                                  kz == 0       ? -1
                                  : kz <= M / 2 ? kz - 1
                                                : (kz + 1) % M}};
        for (int a = 0; a < 3; a++) {
            int32_t q = -1;
            if (lower[a][0] >= 0 && lower[a][1] >= 0 && lower[a][2] >= 0)
                q = pos[2 * ((lower[a][2] * M + lower[a][1]) * H + lower[a][0]) + p];
            s->nbr[VVC_NBR * i + a] = q >= 0 && q < i ? q : s->N;
        }
        /* the real part of the same coefficient, coded just before its imaginary part */
        const int32_t re = p == 1 ? pos[e - 1] : -1;
        s->nbr[VVC_NBR * i + 3] = re >= 0 && re < i ? re : s->N;
    }
    free(pos);
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* Quantisation table                                                       */

void
vv_vvc_params_init(vv_vvc_params *p) {
    memset(p, 0, sizeof *p);
    p->block = 16;
    p->target = VV_VVC_QUALITY;
    p->quality = 75;
    p->rate = 1;
    p->slope = 0.5;
}

/* Steps of the unitary coefficients per folded frequency, (M/2+1)^3 entries. */
void
vvc_make_table(float *tab, int M, double quality, double slope) {
    const int H = M / 2 + 1;
    /* at quality 100 the step of the unnormalised coefficients is 0.5, so
     * no voxel can move by more than 0.5 * sqrt(2) / 2 < 0.5 grey levels
     * however the rounding errors of the coefficients line up */
    const double s = 0.5 / sqrt((double)M * M * M) * pow(2.0, (100.0 - quality) / 5.0);
    double b = slope * (100.0 - quality) / 20.0;
    b = b < slope ? b : slope;
    for (int fz = 0; fz < H; fz++)
        for (int fy = 0; fy < H; fy++)
            for (int fx = 0; fx < H; fx++) {
                const double r = sqrt((double)(fx * fx + fy * fy + fz * fz)) / (M / 2);
                tab[(fz * H + fy) * H + fx] = (float)(s * (1.0 + b * r));
            }
}

void
vv_vvc_value_scale(const vv_volume *v, double *offset, double *unit) {
    const double lo = v->range[0], hi = v->range[1];
    const int integer = v->type != VV_F32 && v->type != VV_F64;
    *offset = isfinite(lo) ? lo : 0;
    const double span = isfinite(hi - lo) ? hi - lo : 0;
    *unit = (integer && span <= 65535) || !(span > 0) ? 1.0 : span / 65535.0;
}

void
vvc_make_step_abs(const vvc_scan *sc, const float *qtab, float *step_abs) {
    const double rn = sqrt((double)sc->N);
    for (int e = 0; e < sc->N; e++)
        step_abs[e] = (float)(qtab[sc->fold[e]] * rn);
}

/* Quantises one subcube's spectrum to N integers in scan order. */
void
vvc_quantise(const vvc_scan *sc, const float *sp, const double *inv_step, int64_t *q) {
    /* sp is in scan order already; round halves away from zero, branch-free */
    for (int e = 0; e < sc->N; e++) {
        const double x = (double)sp[e] * inv_step[e];
        q[e] = (int64_t)(x + copysign(0.5, x));
    }
}

void
vvc_quantise_dz(const vvc_scan *sc, const float *sp, const double *inv_step, double theta,
                int64_t *q) {
    /* magnitudes rounded down past theta (< 0.5: a dead zone around zero), except the DC term */
    const double x0 = (double)sp[0] * inv_step[0];
    q[0] = (int64_t)(x0 + copysign(0.5, x0));
    for (int e = 1; e < sc->N; e++) {
        const double x = (double)sp[e] * inv_step[e];
        q[e] = (int64_t)(x + copysign(theta, x));
    }
}
