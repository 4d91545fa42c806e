/*
 * Compression-domain volume rendering by the Fourier projection-slice
 * theorem, per subcube (Chiueh, He, Kaufman, Pfister et al., "Compression
 * Domain Volume Rendering", 1994/1997; Malzbender, "Fourier Volume
 * Rendering", ACM TOG 1993). docs/rendering.md describes the method.
 *
 * The spectra come from a .vvc (entropy decoding and dequantisation only:
 * no inverse 3-D transform, no volume is rebuilt) or, without one, from the
 * World's volume transformed subcube by subcube (exact, or compressed in
 * memory at a quality or rate first). For a parallel view the ray direction
 * in a volume's index space is d; its largest component picks the axis c
 * the rays are parameterised by, and the projection of a subcube onto the
 * plane x_c = const along d is an oblique (sheared) projection
 *   g(P, Q) = sum over z of f(P + a z, Q + b z, z),  a = d_p / d_c, b = d_q / d_c,
 * whose 2-D spectrum is the 3-D spectrum on the plane w = -(a u + b v).
 * The slice is sampled on a 2M x 2M grid (the subcube zero-padded to twice
 * its side in p and q, computed once per axis from the stored M^3
 * coefficients by exact Dirichlet-kernel interpolation in frequency space:
 * this keeps the sheared projection, up to 2M wide, free of wrap-around),
 * and along w it is interpolated with the exact periodic-sinc (Dirichlet)
 * kernel of the M-point DFT. The fractional offset of each slab of subcubes
 * on the sheared plane is applied as a phase ramp, so after a 2-D inverse
 * FFT every subimage adds onto one integer grid (or, with attenuation, is
 * composited front to back with a transmittance per subcube); the sheared
 * image is finally resampled (Catmull-Rom) into the output image.
 */
#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "render/registry.h"
#include "volvis/compress.h"
#include "volvis/render.h"

#define FR_MAX_CACHE 4 /* volumes whose spectra are kept (each several times the volume) */
#define FR_LUT 4096    /* transfer-function table entries, as the ray caster */

/* Storage of the oversampled spectra: float, or with FR_BF16 bfloat16 (half
 * the memory; measured on the CT head: no faster, since the slice is not
 * limited by memory bandwidth with this layout, and 8 significant bits). */
#ifndef FR_BF16
#define FR_BF16 0
#endif
#if FR_BF16
typedef uint16_t fr_coef;
#else
typedef float fr_coef;
#endif

/* Spectra of one volume, kept between frames. */
typedef struct fr_source {
    vv_volume *vol; /* reference held; the key with modified and the parameters */
    uint64_t modified;
    int kind; /* 0 exact, 1 compressed in memory, 2 a .vvc file */
    double quality, rate;
    int block;
    int M, H, nb[3], nsub;
    float *spectra;   /* nsub * 2 * M * M * H, FFTW r2c layout, dequantised */
    uint8_t *nonzero; /* subcube has a non-zero coefficient */
    double offset, unit;
    fr_coef *over[3]; /* per projection axis c: nsub * M * 2M * (M + 1) complex, or NULL */
    double bits_per_voxel;
    uint64_t last_used;
    vv_vvc *own;        /* kind 1: the volume compressed in memory */
    vv_volume *decoded; /* the decoded volume (modes the frequency domain cannot do), or NULL */
} fr_source;

typedef struct fr_state {
    fr_source cache[FR_MAX_CACHE];
    int n_cache;
    uint64_t clock;
    /* the options (fr_options) */
    char vvc_path[VV_RENDER_OPTION_VALUE_MAX]; /* vvc ("": none) */
    vv_vvc *vvc;                               /* loaded from vvc_path */
    double quality;                            /* < 0: exact spectra (no quantisation) */
    double rate;                               /* > 0: compress to this rate instead */
    int block;
    double attenuation;
    /* the World the ray caster draws for the modes other than xray
     * (fr_stand_in): the objects with their decoded volumes */
    vv_world decoded_world;
    vv_object **decoded_objs;
    vv_object *decoded_copies;
    size_t n_decoded;
    fftwf_plan plan2d[3]; /* 2M x 2M c2r for M = 8, 16, 32 (made once, executed on new arrays) */
} fr_state;

/* ---------------------------------------------------------------------- */
/* The state: releasing it, and the options' side effects                 */

static void
source_release(fr_source *s) {
    vv_volume_free(s->vol);
    fftwf_free(s->spectra);
    free(s->nonzero);
    for (int i = 0; i < 3; i++)
        fftwf_free(s->over[i]);
    vv_vvc_free(s->own);
    vv_volume_free(s->decoded);
    memset(s, 0, sizeof *s);
}

static void
fr_release(void *state) {
    fr_state *st = state;
    for (int i = 0; i < st->n_cache; i++)
        source_release(&st->cache[i]);
    free(st->decoded_objs);
    free(st->decoded_copies);
    vv_vvc_free(st->vvc);
    vv_fftw_lock();
    for (int i = 0; i < 3; i++)
        if (st->plan2d[i])
            fftwf_destroy_plan(st->plan2d[i]);
    vv_fftw_unlock();
}

/* A new source of spectra: nothing cached from the old one is valid. */
static void
drop_cache(fr_state *st) {
    for (int i = 0; i < st->n_cache; i++)
        source_release(&st->cache[i]);
    st->n_cache = 0;
}

/* vvc: the file named (stored in vvc_path) is read, or none for "". */
static vv_status
fr_vvc_changed(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    (void)v;
    fr_state *st = state;
    drop_cache(st);
    vv_vvc *c = NULL;
    if (st->vvc_path[0]) {
        vv_status s = vv_vvc_load(&c, st->vvc_path);
        if (s != VV_OK)
            return s;
    }
    vv_vvc_free(st->vvc);
    st->vvc = c;
    return VV_OK;
}

/* quality (exact: -1) overrides rate. */
static vv_status
fr_quality_changed(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    (void)v;
    fr_state *st = state;
    drop_cache(st);
    st->rate = -1;
    return VV_OK;
}

/* rate (none: -1): a rate overrides quality. */
static vv_status
fr_rate_changed(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    fr_state *st = state;
    drop_cache(st);
    if (v->word < 0)
        st->quality = -1;
    return VV_OK;
}

static vv_status
fr_block_changed(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    (void)v;
    drop_cache(state);
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* Spectra                                                                  */

static vv_status
source_fill(fr_state *st, fr_source *s, vv_volume *vol, int threads) {
    vv_status r;
    s->vol = vv_volume_ref(vol);
    s->modified = vol->modified;
    s->quality = st->quality;
    s->rate = st->rate;
    s->block = st->block;
    vv_vvc *tmp = NULL;
    const vv_vvc *c = NULL;
    if (st->vvc) {
        s->kind = 2;
        c = st->vvc;
        vv_vvc_info in;
        vv_vvc_get_info(c, &in);
        for (int i = 0; i < 3; i++)
            if (in.dims[i] != vol->dims[i])
                return vv_error_set(VV_ERR_INVALID,
                                    "vvc %s holds %d x %d x %d voxels but the volume object has "
                                    "%d x %d x %d",
                                    st->vvc_path, in.dims[0], in.dims[1], in.dims[2], vol->dims[0],
                                    vol->dims[1], vol->dims[2]);
    } else if (st->quality >= 0 || st->rate > 0) {
        s->kind = 1;
        vv_vvc_params p;
        vv_vvc_params_init(&p);
        p.block = st->block;
        p.threads = threads;
        if (st->rate > 0) {
            p.target = VV_VVC_RATE;
            p.rate = st->rate;
        } else {
            p.quality = st->quality;
        }
        if ((r = vv_vvc_compress(&tmp, vol, &p)) != VV_OK)
            return r;
        c = tmp;
    }
    if (!c) {
        s->kind = 0;
        s->M = st->block;
        if ((r = vv_vvc_spectra(vol, s->M, threads, &s->spectra, &s->offset, &s->unit, NULL)) !=
            VV_OK)
            return r;
        s->bits_per_voxel = 32;
    } else {
        vv_vvc_info in;
        vv_vvc_get_info(c, &in);
        s->M = in.block;
        s->offset = in.value_offset;
        s->unit = in.value_unit;
        s->bits_per_voxel = in.bits_per_voxel;
        const int nsub = vv_vvc_subcube_count(c);
        const size_t per = 2 * (size_t)s->M * s->M * (s->M / 2 + 1);
        s->spectra = fftwf_malloc(sizeof(float) * per * (size_t)nsub);
        if (!s->spectra) {
            vv_vvc_free(tmp);
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        int failed = 0;
        char msg[256] = "";
#pragma omp parallel for num_threads(threads) schedule(dynamic, 8)
        for (int k = 0; k < nsub; k++) {
            if (failed)
                continue;
            /* entropy decoding and dequantisation: all the compressed data sees */
            if (vv_vvc_decode_spectrum(c, k, s->spectra + per * (size_t)k) != VV_OK) {
#pragma omp critical(fr_err)
                {
                    if (!failed)
                        snprintf(msg, sizeof msg, "%s", vv_error_message());
                    failed = 1;
                }
            }
        }
        s->own = tmp; /* kept for a decode (modes other than xray) */
        if (failed)
            return vv_error_set(VV_ERR_FORMAT, "%s", msg);
    }
    const int M = s->M;
    s->H = M / 2 + 1;
    for (int i = 0; i < 3; i++)
        s->nb[i] = (vol->dims[i] + M - 1) / M;
    s->nsub = s->nb[0] * s->nb[1] * s->nb[2];
    s->nonzero = malloc((size_t)s->nsub);
    if (!s->nonzero)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    const size_t per = 2 * (size_t)M * M * s->H;
    for (int k = 0; k < s->nsub; k++) {
        const float *sp = s->spectra + per * (size_t)k;
        uint8_t nz = 0;
        for (size_t i = 0; i < per && !nz; i++)
            nz = sp[i] != 0;
        s->nonzero[k] = nz;
    }
    return VV_OK;
}

static vv_status
get_source(fr_state *st, vv_volume *vol, int threads, fr_source **out) {
    st->clock++;
    const int kind = st->vvc ? 2 : (st->quality >= 0 || st->rate > 0) ? 1 : 0;
    for (int i = 0; i < st->n_cache; i++) {
        fr_source *s = &st->cache[i];
        if (s->vol == vol && s->modified == vol->modified && s->kind == kind &&
            (kind == 2 ||
             (s->quality == st->quality && s->rate == st->rate && s->block == st->block))) {
            s->last_used = st->clock;
            *out = s;
            return VV_OK;
        }
    }
    int slot = st->n_cache;
    if (slot == FR_MAX_CACHE) {
        slot = 0;
        for (int i = 1; i < st->n_cache; i++)
            if (st->cache[i].last_used < st->cache[slot].last_used)
                slot = i;
        source_release(&st->cache[slot]);
    } else {
        st->n_cache++;
    }
    fr_source *s = &st->cache[slot];
    memset(s, 0, sizeof *s);
    vv_status r = source_fill(st, s, vol, threads);
    if (r != VV_OK) {
        source_release(s);
        st->cache[slot] = st->cache[st->n_cache - 1];
        memset(&st->cache[st->n_cache - 1], 0, sizeof(fr_source));
        st->n_cache--;
        return r;
    }
    s->last_used = st->clock;
    *out = s;
    return VV_OK;
}

/* bfloat16: the upper half of a float, rounded to nearest even (8
 * significant bits, the range of float). */
static inline fr_coef
to_coef(float f) {
#if FR_BF16
    uint32_t u;
    memcpy(&u, &f, 4);
    u += 0x7FFFu + ((u >> 16) & 1u);
    return (uint16_t)(u >> 16);
#else
    return f;
#endif
}

static inline float
from_coef(fr_coef h) {
#if FR_BF16
    const uint32_t u = (uint32_t)h << 16;
    float f;
    memcpy(&f, &u, 4);
    return f;
#else
    return h;
#endif
}

/* D(delta) = (1/M) sum_{x=0}^{M-1} e^{-2 pi i delta x / M}: evaluates the
 * DTFT of M samples from their DFT, F(nu) = sum_k F[k] D(nu - k). */
static void
dirichlet(int M, double delta, double *re, double *im) {
    const double s = sin(VV_PI * delta / M);
    double mag;
    if (fabs(s) < 1e-9) {
        /* delta a multiple of M: every term is e^{-2 pi i m x} = 1 */
        *re = 1;
        *im = 0;
        return;
    }
    mag = sin(VV_PI * delta) / (M * s);
    const double ph = -VV_PI * delta * (M - 1) / M;
    *re = mag * cos(ph);
    *im = mag * sin(ph);
}

/* The spectrum of every subcube zero-padded to 2M along the axes p and q
 * other than c, sampled at half-integer frequencies there and at the M
 * integer frequencies along c:  U[uq][up][kc], up in 0..M (the other half
 * is Hermitian), uq in 0..2M-1. Computed in frequency space alone. */
static vv_status
build_over(fr_source *s, int c, int threads) {
    if (s->over[c])
        return VV_OK;
    const int M = s->M, H = s->H, M2 = 2 * M, W = M + 1;
    const int p = (c + 1) % 3, q = (c + 2) % 3;
    const size_t per_over = (size_t)M * M2 * W * 2;
    const size_t per = 2 * (size_t)M * M * H;
    fr_coef *over = fftwf_malloc(sizeof(fr_coef) * per_over * (size_t)s->nsub);
    double *dodd = malloc(sizeof(double) * 2 * (size_t)M * M);
    if (!over || !dodd) {
        fftwf_free(over);
        free(dodd);
        return vv_error_set(VV_ERR_NOMEM, "out of memory (%zu MB of oversampled spectra)",
                            sizeof(fr_coef) * per_over * (size_t)s->nsub >> 20);
    }
    for (int j = 0; j < M; j++)
        for (int k = 0; k < M; k++)
            dirichlet(M, j + 0.5 - k, &dodd[2 * (j * M + k)], &dodd[2 * (j * M + k) + 1]);
    _Atomic int failed = 0; /* set by one thread, read by all */
#pragma omp parallel num_threads(threads)
    {
        float *G = malloc(sizeof(float) * 2 * (size_t)M * M * M);  /* [kc][kq][kp] */
        float *G1 = malloc(sizeof(float) * 2 * (size_t)M * M * W); /* [kc][kq][up] */
        if (!G || !G1)
            failed = 1;
#pragma omp for schedule(dynamic, 4)
        for (int sub = 0; sub < s->nsub; sub++) {
            fr_coef *U = over + per_over * (size_t)sub;
            if (failed)
                continue;
            if (!s->nonzero[sub]) {
                memset(U, 0, sizeof(fr_coef) * per_over);
                continue;
            }
            const float *S = s->spectra + per * (size_t)sub;
            for (int kc = 0; kc < M; kc++)
                for (int kq = 0; kq < M; kq++)
                    for (int kp = 0; kp < M; kp++) {
                        int k[3];
                        k[c] = kc;
                        k[p] = kp;
                        k[q] = kq;
                        float re, im;
                        if (k[0] <= M / 2) {
                            const float *e = S + 2 * ((size_t)(k[2] * M + k[1]) * H + k[0]);
                            re = e[0];
                            im = e[1];
                        } else {
                            const float *e =
                                S + 2 * ((size_t)(((M - k[2]) % M) * M + (M - k[1]) % M) * H +
                                         (M - k[0]));
                            re = e[0];
                            im = -e[1];
                        }
                        float *g = G + 2 * ((size_t)(kc * M + kq) * M + kp);
                        g[0] = re;
                        g[1] = im;
                    }
            /* along p: up even copies, up odd interpolates */
            for (int line = 0; line < M * M; line++) {
                const float *gl = G + 2 * (size_t)line * M;
                float *ol = G1 + 2 * (size_t)line * W;
                for (int up = 0; up < W; up++) {
                    if (!(up & 1)) {
                        ol[2 * up] = gl[2 * (up / 2)];
                        ol[2 * up + 1] = gl[2 * (up / 2) + 1];
                        continue;
                    }
                    const double *d = dodd + 2 * (size_t)(up / 2) * M;
                    double re = 0, im = 0;
                    for (int k = 0; k < M; k++) {
                        re += gl[2 * k] * d[2 * k] - gl[2 * k + 1] * d[2 * k + 1];
                        im += gl[2 * k] * d[2 * k + 1] + gl[2 * k + 1] * d[2 * k];
                    }
                    ol[2 * up] = (float)re;
                    ol[2 * up + 1] = (float)im;
                }
            }
            /* along q; stored per kc: the M2 * W real parts of the points
             * (uq * W + up), then their imaginary parts, so that the slice
             * runs over the points in SIMD lanes for one kc at a time */
            const size_t npts = (size_t)M2 * W;
            for (int kc = 0; kc < M; kc++)
                for (int uq = 0; uq < M2; uq++) {
                    const double *d = dodd + 2 * (size_t)(uq / 2) * M;
                    for (int up = 0; up < W; up++) {
                        fr_coef *ue = U + 2 * npts * kc + (size_t)uq * W + up;
                        float re, im;
                        if (!(uq & 1)) {
                            const float *g = G1 + 2 * ((size_t)(kc * M + uq / 2) * W + up);
                            re = g[0];
                            im = g[1];
                        } else {
                            double r = 0, i = 0;
                            for (int k = 0; k < M; k++) {
                                const float *g = G1 + 2 * ((size_t)(kc * M + k) * W + up);
                                r += g[0] * d[2 * k] - g[1] * d[2 * k + 1];
                                i += g[0] * d[2 * k + 1] + g[1] * d[2 * k];
                            }
                            re = (float)r;
                            im = (float)i;
                        }
                        ue[0] = to_coef(re);
                        ue[npts] = to_coef(im);
                    }
                }
        }
        free(G);
        free(G1);
    }
    free(dodd);
    if (failed) {
        fftwf_free(over);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    s->over[c] = over;
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* One object                                                               */

typedef struct fr_obj {
    const vv_object *obj;
    fr_source *src;
    int c, p, q;
    double a, b;      /* shear */
    double lscale;    /* world length per unit of x_c along the ray */
    double w2i[3][4]; /* world -> index */
    double di[3];     /* view direction in index space */
    /* index position of the ray through pixel (px, py): X0 + px * Xx + py * Xy */
    double X0[3], Xx[3], Xy[3];
} fr_obj;

typedef struct fr_frame {
    const vv_view *view;
    vv_vec3 o00, ox, oy, dir; /* orthographic rays: origin o00 + px ox + py oy, direction dir */
    int W, Hh;
    double attenuation;
} fr_frame;

/* Catmull-Rom weights. */
static inline void
cubic_w(float t, float w[4]) {
    const float t2 = t * t, t3 = t2 * t;
    w[0] = -0.5f * t3 + t2 - 0.5f * t;
    w[1] = 1.5f * t3 - 2.5f * t2 + 1.0f;
    w[2] = -1.5f * t3 + 2.0f * t2 + 0.5f * t;
    w[3] = 0.5f * t3 - 0.5f * t2;
}

/* Chord (in x_c units) of the ray (P + a z, Q + b z, z), local subcube coordinates,
 * through the box lo..hi (per axis p, q, c in that order). */
static inline double
chord_local(double P, double Q, double a, double b, const double lo[3], const double hi[3]) {
    double z0 = lo[2], z1 = hi[2];
    if (!vv_slab_axis(lo[0], hi[0], P, a, &z0, &z1) || !vv_slab_axis(lo[1], hi[1], Q, b, &z0, &z1))
        return 0;
    return z1 > z0 ? z1 - z0 : 0;
}

typedef struct sub_key {
    double depth;
    int index;
} sub_key;

static int
cmp_sub(const void *x, const void *y) {
    const sub_key *a = x, *b = y;
    return a->depth < b->depth   ? -1
           : a->depth > b->depth ? 1
                                 : (a->index > b->index) - (a->index < b->index);
}

/* The projection of one object in the sheared plane x_c = 0 (index
 * units): an nP x nQ grid at integer (P, Q), P = Pg0 + column, Q = Qg0 +
 * row; C the (attenuated) line integral of coded values (world units), L
 * the attenuated chord (with attenuation only). */
typedef struct fr_sheared {
    int nP, nQ, Pg0, Qg0;
    float *C, *L;
} fr_sheared;

/* The slice: for each of the n points, the sum over kc of the oversampled
 * spectrum times the frame's weights (both stored per kc as n real then n
 * imaginary parts), accumulated in sr, si and written interleaved to
 * slice. The hot loop of a frame: compiled for AVX2 as well where the
 * compiler can, picked at run time. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
static void
slice_points(const fr_coef *U, const float *wsl, int M, int n, float *sr, float *si, float *slice) {
    for (int e = 0; e < n; e++)
        sr[e] = si[e] = 0;
    for (int kc = 0; kc < M; kc++) {
        const fr_coef *ur = U + 2 * (size_t)kc * n, *ui = ur + n;
        const float *wr = wsl + 2 * (size_t)kc * n, *wi = wr + n;
#pragma omp simd
        for (int e = 0; e < n; e++) {
            const float xr = from_coef(ur[e]), xi = from_coef(ui[e]);
            sr[e] += xr * wr[e] - xi * wi[e];
            si[e] += xr * wi[e] + xi * wr[e];
        }
    }
    for (int e = 0; e < n; e++) {
        slice[2 * e] = sr[e];
        slice[2 * e + 1] = si[e];
    }
}

/* The 2M x 2M inverse FFT, planned once per renderer. FFTW_ESTIMATE, not
 * MEASURE: a measured plan depends on timing, and so would the image. */
static fftwf_plan
plan_for(fr_state *st, int M) {
    const int slot = M == 8 ? 0 : M == 16 ? 1 : 2;
    if (st->plan2d[slot])
        return st->plan2d[slot];
    const int M2 = 2 * M;
    float *in = fftwf_malloc(sizeof(float) * 2 * (size_t)M2 * (M + 1));
    float *out = fftwf_malloc(sizeof(float) * (size_t)M2 * M2);
    if (in && out) {
        vv_fftw_lock();
        st->plan2d[slot] = fftwf_plan_dft_c2r_2d(M2, M2, (fftwf_complex *)in, out, FFTW_ESTIMATE);
        vv_fftw_unlock();
    }
    fftwf_free(in);
    fftwf_free(out);
    return st->plan2d[slot];
}

/* Over 150 lines on purpose: one subcube's slice extraction, inverse FFT
 * and shear-warp accumulation share the thread's buffers, its FFTW plan and
 * the progress bookkeeping inside one OpenMP region; split into functions
 * they would pass a dozen pointers per subcube (the frame's hot loop). */
static vv_status
project_object(fr_state *st, const fr_frame *fr, fr_obj *ob, int threads,
               const vv_progress *progress, fr_sheared *sh) {
    fr_source *s = ob->src;
    const int M = s->M, M2 = 2 * M, W = M + 1;
    const int c = ob->c, p = ob->p, q = ob->q;
    memset(sh, 0, sizeof *sh);
    vv_status r = build_over(s, c, threads);
    if (r != VV_OK)
        return r;
    const size_t per_over = (size_t)M * M2 * W * 2;
    const double a = ob->a, b = ob->b;
    const int att = fr->attenuation > 0;
    const vv_volume *vol = ob->obj->volume;
    const double vrange = vol->range[1] - vol->range[0] > 0 ? vol->range[1] - vol->range[0] : 1;
    const double kappa = fr->attenuation / vrange; /* per value unit and world unit */
    const int dims[3] = {vol->dims[0], vol->dims[1], vol->dims[2]};
    const int nslab = s->nb[c];

    /* front-to-back order of the subcubes (empty ones only matter for the
     * chord under attenuation) */
    sub_key *order = malloc(sizeof *order * (size_t)s->nsub);
    if (!order)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    int n = 0;
    const vv_mat4 i2w = vv_object_index_to_world(ob->obj);
    for (int k = 0; k < s->nsub; k++) {
        if (!s->nonzero[k] && !att)
            continue;
        const int bx = k % s->nb[0], by = (k / s->nb[0]) % s->nb[1], bz = k / (s->nb[0] * s->nb[1]);
        vv_vec3 ctr = vv_mat4_mul_point(
            i2w, vv_vec3_make((bx + 0.5) * M - 0.5, (by + 0.5) * M - 0.5, (bz + 0.5) * M - 0.5));
        order[n].depth = vv_vec3_dot(ctr, fr->dir);
        order[n].index = k;
        n++;
    }
    qsort(order, (size_t)n, sizeof *order, cmp_sub);

    /* Each subimage covers the window [P0, P0 + 2M) x [Q0, Q0 + 2M) of its
     * own periodic grid, centred on the sheared data (width (M-1)(1+|a|) < 2M). */
    const double span_p = (M - 1) * (1 + fabs(a)), span_q = (M - 1) * (1 + fabs(b));
    const int P0 = (int)floor((a > 0 ? -a * (M - 1) : 0) - 0.5 * (M2 - 1 - span_p));
    const int Q0 = (int)floor((b > 0 ? -b * (M - 1) : 0) - 0.5 * (M2 - 1 - span_q));
    /* A subcube at (Pb, Qb, Zb) lands at global P = local P + Pb - a Zb: an
     * integer part and a fraction that depends on the slab Zb only; the
     * fraction is applied as a phase ramp, so subimages add on one grid. */
    int pmin = INT32_MAX, pmax = INT32_MIN, qmin = INT32_MAX, qmax = INT32_MIN;
    for (int sl = 0; sl < nslab; sl++) {
        const int ip = (int)floor(-a * sl * M), iq = (int)floor(-b * sl * M);
        pmin = ip < pmin ? ip : pmin;
        pmax = ip > pmax ? ip : pmax;
        qmin = iq < qmin ? iq : qmin;
        qmax = iq > qmax ? iq : qmax;
    }
    sh->Pg0 = pmin + P0;
    sh->Qg0 = qmin + Q0;
    sh->nP = pmax - pmin + (s->nb[p] - 1) * M + M2;
    sh->nQ = qmax - qmin + (s->nb[q] - 1) * M + M2;
    const size_t nsh = (size_t)sh->nP * sh->nQ;
    const double gscale = s->unit * ob->lscale / ((double)M2 * M2);

    /* Dirichlet weights D(w - kc) of every slice point times the phase of
     * the slab's fractional shift: the same for all subcubes of a slab
     * (stored per kc as the real parts of all points, then the imaginary
     * parts, as the spectra). The Nyquist row and column
     * (up or uq = M) stand for both +M/2 and -M/2, whose planes and phases
     * differ: their weights are averaged. */
    const size_t per_w = 2 * (size_t)M2 * W * M;
    float *wtab = malloc(sizeof(float) * per_w * (size_t)nslab);
    double *dw = malloc(sizeof(double) * 2 * 4 * (size_t)M);
    if (!wtab || !dw) {
        free(order);
        free(wtab);
        free(dw);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    for (int uq = 0; uq < M2; uq++)
        for (int up = 0; up < W; up++) {
            const double vq0 = uq < M ? uq * 0.5 : (uq - M2) * 0.5, vp0 = up * 0.5;
            const int np = up == M ? 2 : 1, nq = uq == M ? 2 : 1;
            double vps[4], vqs[4];
            int ncomb = 0;
            for (int i = 0; i < np; i++)
                for (int j = 0; j < nq; j++, ncomb++) {
                    vps[ncomb] = i ? -vp0 : vp0;
                    vqs[ncomb] = j ? -vq0 : vq0;
                    for (int kc = 0; kc < M; kc++)
                        dirichlet(M, -(a * vps[ncomb] + b * vqs[ncomb]) - kc,
                                  &dw[2 * (ncomb * M + kc)], &dw[2 * (ncomb * M + kc) + 1]);
                }
            for (int sl = 0; sl < nslab; sl++) {
                const double fp = -a * sl * M - floor(-a * sl * M);
                const double fq = -b * sl * M - floor(-b * sl * M);
                float *wt = wtab + per_w * (size_t)sl;
                const size_t e = (size_t)uq * W + up, npts = (size_t)M2 * W;
                double wre[64], wim[64];
                for (int kc = 0; kc < M; kc++)
                    wre[kc] = wim[kc] = 0;
                for (int cb = 0; cb < ncomb; cb++) {
                    /* h(m) = g(m - f): multiply by e^{-2 pi i (vp fp + vq fq) / M} */
                    const double ph = -2 * VV_PI * (vps[cb] * fp + vqs[cb] * fq) / M;
                    const double cr = cos(ph) / ncomb, ci = sin(ph) / ncomb;
                    for (int kc = 0; kc < M; kc++) {
                        const double dre = dw[2 * (cb * M + kc)], dim = dw[2 * (cb * M + kc) + 1];
                        wre[kc] += dre * cr - dim * ci;
                        wim[kc] += dre * ci + dim * cr;
                    }
                }
                for (int kc = 0; kc < M; kc++) {
                    wt[2 * npts * kc + e] = (float)wre[kc];
                    wt[2 * npts * kc + npts + e] = (float)wim[kc];
                }
            }
        }
    free(dw);

    const int nthreads = threads < 1 ? 1 : threads;
    const fftwf_plan plan = plan_for(st, M);
    float *bufs = calloc((size_t)nthreads * (att ? 3 : 1) * nsh, sizeof(float));
    if (!bufs || !plan) {
        free(bufs);
        free(order);
        free(wtab);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    /* atomic: set by one thread, read by the others in their loop test */
    _Atomic int failed = 0, cancelled = 0;
    long done = 0;
#pragma omp parallel num_threads(nthreads)
    {
        const int tid = omp_get_thread_num(), nt = omp_get_num_threads();
        float *C = bufs + (size_t)tid * (att ? 3 : 1) * nsh;
        float *L = att ? C + nsh : NULL, *T = att ? C + 2 * nsh : NULL;
        if (att)
            for (size_t i = 0; i < nsh; i++)
                T[i] = 1;
        float *slice = fftwf_malloc(sizeof(float) * 2 * (size_t)M2 * W);
        float *sr = malloc(sizeof(float) * 2 * (size_t)M2 * W), *si = sr ? sr + M2 * W : NULL;
        float *g = fftwf_malloc(sizeof(float) * (size_t)M2 * M2);
        if (!slice || !g || !sr)
            failed = 1;
        /* with attenuation each thread composites a contiguous run of the
         * ordered subcubes; without, thread t sums subcubes t, t + nt, ...
         * (balanced, and a fixed assignment: the image depends on the
         * thread count only, never on timing) */
        const int lo = att ? (int)((long)n * tid / nt) : tid;
        const int hi = att ? (int)((long)n * (tid + 1) / nt) : n;
        const int stride = att ? 1 : nt;
        for (int oi = lo; oi < hi && !failed && !cancelled; oi += stride) {
            const int sub = order[oi].index;
            const int bi[3] = {sub % s->nb[0], (sub / s->nb[0]) % s->nb[1],
                               sub / (s->nb[0] * s->nb[1])};
            const int sl = bi[c];
            const int nz = s->nonzero[sub];
            if (nz) {
                /* the slice w = -(a u + b v) through the oversampled spectrum */
                const fr_coef *U = s->over[c] + per_over * (size_t)sub;
                const float *wsl = wtab + per_w * (size_t)sl;
                slice_points(U, wsl, M, M2 * W, sr, si, slice);
                fftwf_execute_dft_c2r(plan, (fftwf_complex *)slice, g);
            }
            /* where the window lands on the global grid */
            const int ipo = (int)floor(-a * sl * M), iqo = (int)floor(-b * sl * M);
            const int gp0 = bi[p] * M + ipo + P0 - sh->Pg0, gq0 = bi[q] * M + iqo + Q0 - sh->Qg0;
            /* the subcube's box inside the volume in local (p, q, c) coordinates,
             * and the local position of global grid point (gp0, gq0) */
            double blo[3], bhi[3];
            const int axes[3] = {p, q, c}, offs[3] = {bi[p] * M, bi[q] * M, sl * M};
            for (int i = 0; i < 3; i++) {
                blo[i] = -0.5;
                const double vhi = dims[axes[i]] - 0.5 - offs[i];
                bhi[i] = M - 0.5 < vhi ? M - 0.5 : vhi;
            }
            const double fpo = -a * sl * M - ipo, fqo = -b * sl * M - iqo;
            for (int mq = 0; mq < M2; mq++) {
                const float *grow = g + (size_t)((Q0 + mq) & (M2 - 1)) * M2;
                float *crow = C + (size_t)(gq0 + mq) * sh->nP + gp0;
                if (!att) {
                    if (nz)
                        for (int mp = 0; mp < M2; mp++)
                            crow[mp] += (float)gscale * grow[(P0 + mp) & (M2 - 1)];
                    continue;
                }
                float *lrow = L + (size_t)(gq0 + mq) * sh->nP + gp0;
                float *trow = T + (size_t)(gq0 + mq) * sh->nP + gp0;
                for (int mp = 0; mp < M2; mp++) {
                    /* local position of this ray on the subcube's plane x_c = 0 */
                    const double Pl = P0 + mp - fpo, Ql = Q0 + mq - fqo;
                    const double ch = chord_local(Pl, Ql, a, b, blo, bhi) * ob->lscale;
                    if (ch <= 0)
                        continue;
                    const float v = nz ? (float)gscale * grow[(P0 + mp) & (M2 - 1)] : 0.0f;
                    const float t = trow[mp];
                    crow[mp] += t * v;
                    lrow[mp] += t * (float)ch;
                    const double tau = kappa * s->unit * (v > 0 ? v : 0);
                    trow[mp] = t * (float)exp(-tau);
                }
            }
            if (progress && progress->fn) {
#pragma omp critical(fr_progress)
                {
                    done++;
                    if (vv_progress_report(progress, (double)done / (n > 0 ? n : 1)))
                        cancelled = 1;
                }
            }
        }
        fftwf_free(slice);
        free(sr);
        fftwf_free(g);
    }
    free(order);
    free(wtab);
    if (failed || cancelled) {
        free(bufs);
        return cancelled && !failed ? vv_error_set(VV_ERR_CANCELLED, "cancelled")
                                    : vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    /* combine the threads' runs in order: (C1, L1, T1) then (C2, L2, T2) */
    if (att) {
        float *C = bufs, *L = bufs + nsh, *T = bufs + 2 * nsh;
        for (int t = 1; t < nthreads; t++) {
            const float *C2 = bufs + (size_t)t * 3 * nsh, *L2 = C2 + nsh, *T2 = C2 + 2 * nsh;
            for (size_t i = 0; i < nsh; i++) {
                C[i] += T[i] * C2[i];
                L[i] += T[i] * L2[i];
                T[i] *= T2[i];
            }
        }
        sh->L = L;
    } else {
        for (int t = 1; t < nthreads; t++)
            for (size_t i = 0; i < nsh; i++)
                bufs[i] += bufs[(size_t)t * nsh + i];
    }
    sh->C = bufs; /* owns the block (L points into it) */
    return VV_OK;
}

/* Catmull-Rom sample of a sheared image at global (P, Q); 0 outside. */
static inline float
sheared_sample(const fr_sheared *sh, const float *img, double P, double Q) {
    const double x = P - sh->Pg0, y = Q - sh->Qg0;
    const double fx = floor(x), fy = floor(y);
    const int ix = (int)fx - 1, iy = (int)fy - 1;
    if (ix < 0 || iy < 0 || ix + 3 >= sh->nP || iy + 3 >= sh->nQ)
        return 0;
    float wx[4], wy[4];
    cubic_w((float)(x - fx), wx);
    cubic_w((float)(y - fy), wy);
    float v = 0;
    for (int j = 0; j < 4; j++) {
        const float *row = img + (size_t)(iy + j) * sh->nP + ix;
        v += wy[j] * (wx[0] * row[0] + wx[1] * row[1] + wx[2] * row[2] + wx[3] * row[3]);
    }
    return v;
}

/* Slab test of a ray in index space against the box [lo, hi]^3 per axis
 * (inv = 1 / d, infinite for a zero component). */
static int
box_hit(const double o[3], const double inv[3], const double lo[3], const double hi[3], double *t0,
        double *t1) {
    *t0 = -INFINITY;
    *t1 = INFINITY;
    return vv_slab_inv(lo, hi, o, inv, t0, t1);
}

/* The modes other than xray are not linear along the ray (maximum, minimum,
 * compositing through a transfer function, the first isosurface crossing),
 * so no slice of the spectrum gives them: the frame is drawn by the ray
 * caster (the registry's "raycast", through vv_renderer_ops.stand_in) from
 * the decoded volume (entropy decoding, dequantisation and one inverse DFT
 * per subcube, with the voxel corrections of an error-bounded file; cached
 * with the spectra) -- from the uncompressed volume when no compression is
 * asked for. *draw is st->decoded_world, whose objects are shallow copies
 * of the World's with the decoded volumes (nothing in them is released). */
static vv_status
fr_stand_in(void *state, const vv_world *w, const vv_render_options *opt, const char **stand_in,
            const vv_world **draw) {
    fr_state *st = state;
    int linear = 1;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *obj = w->objects[i];
        if (obj && obj->visible && obj->type == VV_OBJECT_VOLUME && obj->volume &&
            obj->mode != VV_MODE_XRAY)
            linear = 0;
    }
    if (linear)
        return VV_OK;
    const int threads = opt->threads > 0 ? opt->threads : vv_threads_get();
    const size_t n = (size_t)(w->n_objects > 0 ? w->n_objects : 1);
    if (n > st->n_decoded) {
        vv_object **objs = realloc(st->decoded_objs, n * sizeof *objs);
        if (objs)
            st->decoded_objs = objs;
        vv_object *copies = realloc(st->decoded_copies, n * sizeof *copies);
        if (copies)
            st->decoded_copies = copies;
        if (!objs || !copies)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        st->n_decoded = n;
    }
    vv_status s = VV_OK;
    for (int i = 0; i < w->n_objects && s == VV_OK; i++) {
        const vv_object *obj = w->objects[i];
        st->decoded_objs[i] = w->objects[i];
        if (!obj || obj->type != VV_OBJECT_VOLUME || !obj->volume || !obj->visible)
            continue;
        if (!st->vvc && !(st->quality >= 0 || st->rate > 0))
            continue; /* exact: the volume itself */
        fr_source *src;
        if ((s = get_source(st, obj->volume, threads, &src)) != VV_OK)
            break;
        if (!src->decoded) {
            const vv_vvc *c = src->kind == 2 ? st->vvc : src->own;
            if ((s = vv_vvc_decompress(&src->decoded, c, threads, NULL)) != VV_OK)
                break;
        }
        st->decoded_copies[i] = *obj;
        st->decoded_copies[i].volume = src->decoded;
        st->decoded_objs[i] = &st->decoded_copies[i];
    }
    if (s != VV_OK)
        return s;
    st->decoded_world = *w;
    st->decoded_world.objects = st->decoded_objs;
    *stand_in = "raycast";
    *draw = &st->decoded_world;
    return VV_OK;
}

/* The object's projection geometry: the view direction in its index space,
 * the major axis c and the shear (a, b) of the other two, and the pixel
 * rays' origins in index space. Errors: VV_ERR_INVALID (singular). */
static vv_status
object_setup(const fr_frame *fr, fr_obj *ob, const vv_object *obj) {
    int ok;
    const vv_mat4 w2i = vv_mat4_inverse(vv_object_index_to_world(obj), &ok);
    if (!ok)
        return vv_error_set(VV_ERR_INVALID, "object '%s': singular transform", obj->name);
    const vv_vec3 di = vv_mat4_mul_dir(w2i, fr->dir);
    ob->di[0] = di.x;
    ob->di[1] = di.y;
    ob->di[2] = di.z;
    ob->c = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(ob->di[i]) > fabs(ob->di[ob->c]))
            ob->c = i;
    ob->p = (ob->c + 1) % 3;
    ob->q = (ob->c + 2) % 3;
    ob->a = ob->di[ob->p] / ob->di[ob->c];
    ob->b = ob->di[ob->q] / ob->di[ob->c];
    ob->lscale = 1.0 / fabs(ob->di[ob->c]); /* |index-to-world(di)| = 1 */
    const vv_vec3 X0 = vv_mat4_mul_point(w2i, fr->o00);
    const vv_vec3 Xx = vv_mat4_mul_dir(w2i, fr->ox), Xy = vv_mat4_mul_dir(w2i, fr->oy);
    const double x0[3] = {X0.x, X0.y, X0.z}, xx[3] = {Xx.x, Xx.y, Xx.z}, xy[3] = {Xy.x, Xy.y, Xy.z};
    memcpy(ob->X0, x0, sizeof x0);
    memcpy(ob->Xx, xx, sizeof xx);
    memcpy(ob->Xy, xy, sizeof xy);
    return VV_OK;
}

/* As the ray caster: FR_LUT entries {opacity, colour} over the volume's
 * value range, looked up by truncation at (value - *lo) * *scale. */
static void
build_lut(const vv_object *obj, float *lut, double *lo_out, double *scale_out) {
    const vv_volume *vol = obj->volume;
    double lut_lo = vol->range[0], lut_hi = vol->range[1];
    if (!(lut_hi > lut_lo))
        lut_hi = lut_lo + 1;
    const double lut_scale = (FR_LUT - 1) / (lut_hi - lut_lo);
    for (int k = 0; k < FR_LUT; k++) {
        const double x = lut_lo + (lut_hi - lut_lo) * k / (FR_LUT - 1);
        double a;
        vv_vec3 col;
        if (obj->segmentation == VV_SEG_THRESHOLD) {
            a = x >= obj->threshold ? 1.0 : 0.0;
            col = obj->material.color;
        } else {
            a = vv_tf_eval_opacity(&obj->tf, x);
            col = vv_tf_eval_color(&obj->tf, x);
        }
        lut[4 * k] = (float)(a < 0 ? 0 : a > 1 ? 1 : a);
        lut[4 * k + 1] = (float)col.x;
        lut[4 * k + 2] = (float)col.y;
        lut[4 * k + 3] = (float)col.z;
    }
    *lo_out = lut_lo;
    *scale_out = lut_scale;
}

static vv_status
fr_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
          vv_image *out) {
    fr_state *st = state; /* only X-ray frames: fr_stand_in gives the rest to the ray caster */
    if (view->projection != VV_PROJECTION_ORTHOGRAPHIC)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "perspective projection is not supported: the projection-slice "
                            "theorem needs parallel rays (use an orthographic view)");
    if (w->n_cut_planes > 0)
        return vv_error_set(VV_ERR_UNSUPPORTED, "cut planes are not supported");
    const int threads = opt->threads > 0 ? opt->threads : vv_threads_get();
    fr_frame fr;
    memset(&fr, 0, sizeof fr);
    fr.view = view;
    fr.W = view->width;
    fr.Hh = view->height;
    fr.attenuation = st->attenuation;
    vv_camera_rays cam; /* parallel rays: one direction */
    vv_camera_rays_init(&cam, view);
    fr.o00 = cam.o00;
    fr.ox = cam.ox;
    fr.oy = cam.oy;
    fr.dir = vv_vec3_normalize(cam.d00);
    const size_t npix = (size_t)fr.W * fr.Hh;

    float *P = calloc(3 * npix, sizeof(float)); /* projections combined by maximum */
    float *PA = calloc(npix, sizeof(float));
    float *dep = malloc(sizeof(float) * npix);
    float *lut = malloc(sizeof(float) * 4 * FR_LUT);
    vv_status s = VV_OK;
    if (!P || !PA || !dep || !lut) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (size_t i = 0; i < npix; i++)
        dep[i] = INFINITY;
    for (int oi = 0; oi < w->n_objects; oi++) {
        const vv_object *obj = w->objects[oi];
        if (!obj || !obj->visible || obj->type != VV_OBJECT_VOLUME || !obj->volume)
            continue;
        if (obj->n_cut_planes > 0) {
            s = vv_error_set(VV_ERR_UNSUPPORTED, "object '%s': cut planes are not supported",
                             obj->name);
            goto done;
        }
        fr_obj ob;
        memset(&ob, 0, sizeof ob);
        ob.obj = obj;
        if ((s = get_source(st, obj->volume, threads, &ob.src)) != VV_OK)
            goto done;
        if ((s = object_setup(&fr, &ob, obj)) != VV_OK)
            goto done;
        fr_sheared sh;
        if ((s = project_object(st, &fr, &ob, threads, &opt->progress, &sh)) != VV_OK)
            goto done;
        /* pixel -> (P, Q) on the plane x_c = 0 */
        const double Pp0 = ob.X0[ob.p] - ob.a * ob.X0[ob.c], Ppx = ob.Xx[ob.p] - ob.a * ob.Xx[ob.c],
                     Ppy = ob.Xy[ob.p] - ob.a * ob.Xy[ob.c];
        const double Qp0 = ob.X0[ob.q] - ob.b * ob.X0[ob.c], Qpx = ob.Xx[ob.q] - ob.b * ob.Xx[ob.c],
                     Qpy = ob.Xy[ob.q] - ob.b * ob.Xy[ob.c];
        /* the mean value along each ray, through the transfer function */
        const vv_volume *vol = obj->volume;
        const double blo[3] = {-0.5, -0.5, -0.5},
                     bhi[3] = {vol->dims[0] - 0.5, vol->dims[1] - 0.5, vol->dims[2] - 0.5};
        const double glo[3] = {0, 0, 0},
                     ghi[3] = {vol->dims[0] - 1, vol->dims[1] - 1, vol->dims[2] - 1};
        const int att = fr.attenuation > 0;
        const double offset = ob.src->offset;
        double dinv[3];
        for (int k = 0; k < 3; k++)
            dinv[k] = 1.0 / ob.di[k];
        double lut_lo, lut_scale;
        build_lut(obj, lut, &lut_lo, &lut_scale);
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int py = 0; py < fr.Hh; py++)
            for (int px = 0; px < fr.W; px++) {
                const size_t i = (size_t)py * fr.W + px;
                double o[3];
                for (int k = 0; k < 3; k++)
                    o[k] = ob.X0[k] + px * ob.Xx[k] + py * ob.Xy[k];
                double t0, t1, u0, u1;
                /* the samples of the spatial X-ray lie in the node-centred grid
                 * box; each voxel's band-limited footprint reaches half a voxel
                 * further, which is the length the integral is divided by */
                if (!box_hit(o, dinv, glo, ghi, &t0, &t1) || !box_hit(o, dinv, blo, bhi, &u0, &u1))
                    continue;
                const double Pq = Pp0 + Ppx * px + Ppy * py, Qq = Qp0 + Qpx * px + Qpy * py;
                const double len = att ? sheared_sample(&sh, sh.L, Pq, Qq) : u1 - u0;
                if (!(len > 0))
                    continue;
                const double mean = offset + sheared_sample(&sh, sh.C, Pq, Qq) / len;
                /* the transfer-function table of the ray caster's projections */
                double xi = (mean - lut_lo) * lut_scale;
                xi = !(xi > 0) ? 0 : xi > FR_LUT - 1 ? FR_LUT - 1 : xi; /* NaN: 0 */
                const float *e = lut + 4 * (int)xi;
                const float a = e[0];
                const float cv[3] = {e[1] * a, e[2] * a, e[3] * a};
                for (int ch = 0; ch < 3; ch++)
                    P[3 * i + ch] = cv[ch] > P[3 * i + ch] ? cv[ch] : P[3 * i + ch];
                PA[i] = a > PA[i] ? a : PA[i];
                dep[i] = (float)t0 < dep[i] ? (float)t0 : dep[i];
            }
        free(sh.C);
    }
    {
        const float bg[3] = {(float)w->background.x, (float)w->background.y,
                             (float)w->background.z};
        for (size_t i = 0; i < npix; i++) {
            for (int ch = 0; ch < 3; ch++)
                out->rgba[4 * i + ch] = P[3 * i + ch] + (1 - PA[i]) * bg[ch];
            out->rgba[4 * i + 3] = PA[i];
            out->depth[i] = dep[i];
        }
    }
done:
    free(P);
    free(PA);
    free(dep);
    free(lut);
    return s;
}

static const char *const fr_exact[] = {"exact", NULL};
static const char *const fr_blocks[] = {"8", "16", "32", NULL};
static const char *const fr_none[] = {"none", NULL};

/* The options, each bound to its field of fr_state; the spectra depend on
 * the first four (their hooks drop them). */
static const vv_option_spec fr_options[] = {
    {"vvc", VV_OPTION_STRING, "", 0, 0, 0, NULL,
     "a .vvc file of the volume: its coded spectra are projected (empty: none)",
     VV_OPTION_BIND_HOOK(fr_state, vvc_path, CHARS, fr_vvc_changed)},
    {"quality", VV_OPTION_REAL, "exact", 0, 100, 0, fr_exact,
     "exact: the volume's own spectra; 0..100: compressed in memory at this quality first",
     VV_OPTION_BIND_WORDS(fr_state, quality, DOUBLE, VV_OPTION_WORD_VALUES(-1),
                          fr_quality_changed)},
    {"rate", VV_OPTION_REAL, "none", 0, 64, VV_OPTION_MIN_OPEN, fr_none,
     "compressed in memory at this many bits per voxel first (none: by quality)",
     VV_OPTION_BIND_WORDS(fr_state, rate, DOUBLE, VV_OPTION_WORD_VALUES(-1), fr_rate_changed)},
    {"block", VV_OPTION_ENUM, "16", 0, 0, 0, fr_blocks, "subcube side, voxels",
     VV_OPTION_BIND_WORDS(fr_state, block, INT, VV_OPTION_WORD_VALUES(8, 16, 32),
                          fr_block_changed)},
    {"attenuation", VV_OPTION_REAL, "0", 0, 1e6, 0, NULL,
     "attenuation of the projection per world unit (0: a plain X-ray)",
     VV_OPTION_BIND(fr_state, attenuation, DOUBLE)},
};

const vv_renderer_ops vv_fourier_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "fourier",
            .description = "compression-domain X-ray projection by the Fourier projection-slice "
                           "theorem (parallel views); other modes: the ray caster on the decoded "
                           "volume",
            .draws = VV_DRAWS(VV_OBJECT_VOLUME),
            .modes = VV_MODES_ALL,
            .caps = 0,
            .quality = "ignored (its option quality sets the compression); xray needs an "
                       "orthographic view (--ortho)",
            .options = fr_options,
            .n_options = VV_OPTIONS_COUNT(fr_options),
        },
    .state_size = sizeof(fr_state),
    .release = fr_release,
    .render = fr_render,
    .render_region = NULL,
    .stand_in = fr_stand_in,
};
