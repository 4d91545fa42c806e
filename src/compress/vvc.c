/*
 * The .vvc volume codec: M^3 subcubes, real-to-complex 3-D DFT (FFTW),
 * frequency-dependent quantisation scaled by a quality, 3-D zig-zag order,
 * zero run-length + canonical Huffman coding as in baseline JPEG; a
 * versioned file with a subcube index and a CRC-32 per section. The method
 * is described in include/volvis/compress.h, the file in
 * docs/file-formats.md.
 */
#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "compress/huffman.h"
#include "compress/vvc_internal.h"
#include "core/internal.h"

#define VVC_MAGIC "\x89VVC\r\n\x1a\n"
#define VVC_HEADER_BYTES 244
#define VVC_MAX_SIZE 40 /* largest amplitude size category accepted */
#define VVC_DC_SYMS 64
#define VVC_AC_SYMS 1024
#define VVC_EOB 0
#define VVC_ZRL (15 * 64)
#define VVC_MAX_FILE (((uint64_t)64) << 30)

static pthread_mutex_t fftw_lock = PTHREAD_MUTEX_INITIALIZER;

void
vv_fftw_lock(void) {
    pthread_mutex_lock(&fftw_lock);
}

void
vv_fftw_unlock(void) {
    pthread_mutex_unlock(&fftw_lock);
}

/* ---------------------------------------------------------------------- */
/* The scan: M^3 independent real numbers of the r2c spectrum, by frequency */

typedef struct vvc_scan {
    int M, H, N;     /* side, M/2 + 1, M^3 */
    int32_t *entry;  /* N: 2 * complex index + part (0 re, 1 im) */
    int32_t *fold;   /* N: folded-frequency table index (fz * H + fy) * H + fx */
    int32_t *mirror; /* nmirror pairs (from, to): Hermitian duplicates to fill */
    int nmirror;
} vvc_scan;

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

static void
scan_free(vvc_scan *s) {
    free(s->entry);
    free(s->fold);
    free(s->mirror);
    memset(s, 0, sizeof *s);
}

static vv_status
scan_init(vvc_scan *s, int M) {
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
        scan_free(s);
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
    for (int i = 0; i < n; i++) {
        s->entry[i] = keys[i].entry;
        s->fold[i] = keys[i].fold;
    }
    free(keys);
    if (n != s->N) {
        scan_free(s);
        return vv_error_set(VV_ERR_INVALID, "internal: scan has %d entries, expected %d", n,
                            M * M * M);
    }
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
static void
make_table(float *tab, int M, double quality, double slope) {
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

/* ---------------------------------------------------------------------- */
/* Forward transform of every subcube                                       */

/* Writes n values (rounded and clamped to the native type; NaN as 0) at element idx. */
static void
store_row(vv_volume *v, size_t idx, const float *vals, int n) {
#define VVC_STORE(T, LO, HI)                                                                       \
    do {                                                                                           \
        T *d = (T *)v->data + idx;                                                                 \
        for (int i = 0; i < n; i++) {                                                              \
            double x = vals[i];                                                                    \
            x = x == x ? floor(x + 0.5) : 0;                                                       \
            d[i] = (T)(x < (LO) ? (LO) : x > (HI) ? (HI) : x);                                     \
        }                                                                                          \
    } while (0)
    switch (v->type) {
    case VV_U8:
        VVC_STORE(uint8_t, 0, 255);
        break;
    case VV_I8:
        VVC_STORE(int8_t, -128, 127);
        break;
    case VV_U16:
        VVC_STORE(uint16_t, 0, 65535);
        break;
    case VV_I16:
        VVC_STORE(int16_t, -32768, 32767);
        break;
    case VV_U32:
        VVC_STORE(uint32_t, 0, 4294967295.0);
        break;
    case VV_I32:
        VVC_STORE(int32_t, -2147483648.0, 2147483647.0);
        break;
    case VV_F32:
        for (int i = 0; i < n; i++)
            ((float *)v->data)[idx + (size_t)i] = vals[i];
        break;
    case VV_F64:
        for (int i = 0; i < n; i++)
            ((double *)v->data)[idx + (size_t)i] = vals[i];
        break;
    }
#undef VVC_STORE
}

vv_status
vv_vvc_spectra(const vv_volume *v, int M, int threads, float **spectra, double *offset,
               double *unit, const vv_progress *progress) {
    *spectra = NULL;
    const int H = M / 2 + 1;
    const int nb[3] = {(v->dims[0] + M - 1) / M, (v->dims[1] + M - 1) / M,
                       (v->dims[2] + M - 1) / M};
    const size_t nsub = (size_t)nb[0] * nb[1] * nb[2];
    const size_t per = 2 * (size_t)M * M * H;
    const uint64_t bytes = (uint64_t)nsub * per * sizeof(float);
    if (bytes > (((uint64_t)48) << 30))
        return vv_error_set(VV_ERR_LIMIT, "spectra of %zu subcubes would take %llu bytes", nsub,
                            (unsigned long long)bytes);
    vv_vvc_value_scale(v, offset, unit);
    float *out = fftwf_malloc(bytes ? (size_t)bytes : 1);
    float *tmp_in = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
    float *tmp_out = fftwf_malloc(sizeof(float) * per);
    if (!out || !tmp_in || !tmp_out) {
        fftwf_free(out);
        fftwf_free(tmp_in);
        fftwf_free(tmp_out);
        return vv_error_set(VV_ERR_NOMEM, "out of memory (%llu bytes of spectra)",
                            (unsigned long long)bytes);
    }
    vv_fftw_lock();
    fftwf_plan plan =
        fftwf_plan_dft_r2c_3d(M, M, M, tmp_in, (fftwf_complex *)tmp_out, FFTW_ESTIMATE);
    vv_fftw_unlock();
    if (!plan) {
        fftwf_free(out);
        fftwf_free(tmp_in);
        fftwf_free(tmp_out);
        return vv_error_set(VV_ERR_NOMEM, "FFTW could not make a %d^3 plan", M);
    }
    const double off = *offset, inv = 1.0 / *unit;
    int nthreads = threads > 0 ? threads : vv_threads_get();
    int cancelled = 0;
    long done = 0;
#pragma omp parallel num_threads(nthreads)
    {
        float *in = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
        float *sp = fftwf_malloc(sizeof(float) * per);
#pragma omp for schedule(dynamic, 4)
        for (long s = 0; s < (long)nsub; s++) {
            if (cancelled || !in || !sp)
                continue;
            const int bx = (int)(s % nb[0]), by = (int)((s / nb[0]) % nb[1]),
                      bz = (int)(s / ((long)nb[0] * nb[1]));
            for (int z = 0; z < M; z++)
                for (int y = 0; y < M; y++) {
                    const int j = by * M + y, k = bz * M + z;
                    float *row = in + (z * M + y) * M;
                    int x = 0;
                    if (j < v->dims[1] && k < v->dims[2]) {
                        const size_t base =
                            ((size_t)k * v->dims[1] + (size_t)j) * v->dims[0] + (size_t)bx * M;
                        const int nx = v->dims[0] - bx * M < M ? v->dims[0] - bx * M : M;
                        for (; x < nx; x++) {
                            const double d = vv_voxel_at(v, base + (size_t)x);
                            row[x] = d == d ? (float)((d - off) * inv) : 0.0f;
                        }
                    }
                    for (; x < M; x++)
                        row[x] = 0; /* padding: the minimum */
                }
            fftwf_execute_dft_r2c(plan, in, (fftwf_complex *)sp);
            memcpy(out + (size_t)s * per, sp, sizeof(float) * per);
            if (progress && progress->fn) {
#pragma omp critical(vvc_progress)
                {
                    done++;
                    if (vv_progress_report(progress, 0.3 * (double)done / (double)nsub))
                        cancelled = 1;
                }
            }
        }
        if (!in || !sp)
            cancelled = 2;
        fftwf_free(in);
        fftwf_free(sp);
    }
    vv_fftw_lock();
    fftwf_destroy_plan(plan);
    vv_fftw_unlock();
    fftwf_free(tmp_in);
    fftwf_free(tmp_out);
    if (cancelled) {
        fftwf_free(out);
        return cancelled == 2 ? vv_error_set(VV_ERR_NOMEM, "out of memory")
                              : vv_error_set(VV_ERR_CANCELLED, "cancelled");
    }
    *spectra = out;
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* Symbols                                                                  */

static inline int
size_of(int64_t v) {
    uint64_t a = v < 0 ? (uint64_t)(-v) : (uint64_t)v;
    int n = 0;
    while (a) {
        n++;
        a >>= 1;
    }
    return n;
}

/* Amplitude bits of v in `size` bits (JPEG: negative values as v - 1 in two's complement). */
static inline uint64_t
amp_bits(int64_t v, int size) {
    return (uint64_t)(v < 0 ? v - 1 : v) & ((size >= 64 ? 0 : (1ull << size)) - 1);
}

/* Quantises one subcube's spectrum to N integers in scan order. */
static void
quantise(const vvc_scan *sc, const float *sp, const double *inv_step, int64_t *q) {
    /* sp is in scan order already; round halves away from zero, branch-free */
    for (int e = 0; e < sc->N; e++) {
        const double x = (double)sp[e] * inv_step[e];
        q[e] = (int64_t)(x + copysign(0.5, x));
    }
}

/* Where the JPEG symbol sequence of a subcube goes: symbol statistics
 * (dcf, acf, amp) or, with w, Huffman codes and amplitude bits. */
typedef struct sym_counter {
    uint64_t *dcf, *acf;
    uint64_t amp;                 /* amplitude bits */
    const vv_huff_enc *dce, *ace; /* codes, for writing */
    vv_bitwriter *w;              /* for writing, or NULL */
} sym_counter;

static inline void
emit(sym_counter *c, int is_dc, int sym, int64_t v, int size) {
    if (c->w) {
        const vv_huff_enc *e = is_dc ? c->dce : c->ace;
        vv_bw_put(c->w, e->code[sym], e->len[sym]);
        if (size > 32) {
            uint64_t b = amp_bits(v, size);
            vv_bw_put(c->w, (uint32_t)(b >> 32), size - 32);
            vv_bw_put(c->w, (uint32_t)b, 32);
        } else if (size > 0) {
            vv_bw_put(c->w, (uint32_t)amp_bits(v, size), size);
        }
        return;
    }
    (is_dc ? c->dcf : c->acf)[sym]++;
    c->amp += (uint64_t)size;
}

static void
symbolise(const int64_t *q, int N, sym_counter *c) {
    int s = size_of(q[0]);
    emit(c, 1, s, q[0], s);
    int run = 0;
    for (int k = 1; k < N; k++) {
        if (q[k] == 0) {
            run++;
            continue;
        }
        while (run > 15) {
            emit(c, 0, VVC_ZRL, 0, 0);
            run -= 16;
        }
        s = size_of(q[k]);
        emit(c, 0, run * 64 + s, q[k], s);
        run = 0;
    }
    if (run > 0)
        emit(c, 0, VVC_EOB, 0, 0);
}

/* ---------------------------------------------------------------------- */
/* The object                                                               */

struct vv_vvc {
    unsigned char *bytes;
    size_t size;
    vv_vvc_info info;
    int M, nsub;
    vvc_scan scan;
    float *qtab;     /* (M/2+1)^3 unitary steps, as stored */
    float *step_abs; /* N: steps of the unnormalised coefficients in scan order */
    vv_huff_table dct, act;
    vv_huff_dec dc, ac;
    uint64_t data_start, data_len; /* bit streams (without the CRC) */
    uint64_t *offsets;             /* nsub + 1 */
    fftwf_plan c2r;                /* for vv_vvc_decode_subcube */
};

void
vv_vvc_free(vv_vvc *c) {
    if (!c)
        return;
    if (c->c2r) {
        vv_fftw_lock();
        fftwf_destroy_plan(c->c2r);
        vv_fftw_unlock();
    }
    free(c->bytes);
    scan_free(&c->scan);
    free(c->qtab);
    free(c->step_abs);
    free(c->offsets);
    free(c);
}

static void
make_step_abs(const vvc_scan *sc, const float *qtab, float *step_abs) {
    const double rn = sqrt((double)sc->N);
    for (int e = 0; e < sc->N; e++)
        step_abs[e] = (float)(qtab[sc->fold[e]] * rn);
}

/* ---- little-endian writing and reading ------------------------------------ */

typedef struct bytebuf {
    unsigned char *p;
    size_t len, cap;
    int failed;
} bytebuf;

static void
bb_put(bytebuf *b, const void *data, size_t n) {
    if (b->failed)
        return;
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + n)
            cap *= 2;
        unsigned char *np = realloc(b->p, cap);
        if (!np) {
            b->failed = 1;
            return;
        }
        b->p = np;
        b->cap = cap;
    }
    memcpy(b->p + b->len, data, n);
    b->len += n;
}

static void
bb_u8(bytebuf *b, unsigned v) {
    unsigned char c = (unsigned char)v;
    bb_put(b, &c, 1);
}

static void
bb_u16(bytebuf *b, unsigned v) {
    unsigned char c[2] = {(unsigned char)v, (unsigned char)(v >> 8)};
    bb_put(b, c, 2);
}

static void
bb_u32(bytebuf *b, uint32_t v) {
    unsigned char c[4];
    for (int i = 0; i < 4; i++)
        c[i] = (unsigned char)(v >> (8 * i));
    bb_put(b, c, 4);
}

static void
bb_u64(bytebuf *b, uint64_t v) {
    unsigned char c[8];
    for (int i = 0; i < 8; i++)
        c[i] = (unsigned char)(v >> (8 * i));
    bb_put(b, c, 8);
}

static void
bb_f64(bytebuf *b, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    bb_u64(b, v);
}

static void
bb_f32(bytebuf *b, float f) {
    uint32_t v;
    memcpy(&v, &f, 4);
    bb_u32(b, v);
}

static void
bb_crc(bytebuf *b, size_t from) {
    if (b->failed)
        return;
    uLong crc = crc32(0L, Z_NULL, 0);
    size_t n = b->len - from;
    const unsigned char *p = b->p + from;
    while (n > 0) {
        uInt chunk = n > (1u << 30) ? (1u << 30) : (uInt)n;
        crc = crc32(crc, p, chunk);
        p += chunk;
        n -= chunk;
    }
    bb_u32(b, (uint32_t)crc);
}

static uint32_t
crc_of(const unsigned char *p, uint64_t n) {
    uLong crc = crc32(0L, Z_NULL, 0);
    while (n > 0) {
        uInt chunk = n > (1u << 30) ? (1u << 30) : (uInt)n;
        crc = crc32(crc, p, chunk);
        p += chunk;
        n -= chunk;
    }
    return (uint32_t)crc;
}

static uint32_t
rd_u32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t
rd_u64(const unsigned char *p) {
    return (uint64_t)rd_u32(p) | (uint64_t)rd_u32(p + 4) << 32;
}

static double
rd_f64(const unsigned char *p) {
    uint64_t v = rd_u64(p);
    double d;
    memcpy(&d, &v, 8);
    return d;
}

static float
rd_f32(const unsigned char *p) {
    uint32_t v = rd_u32(p);
    float f;
    memcpy(&f, &v, 4);
    return f;
}

/* ---------------------------------------------------------------------- */
/* Encoding                                                                 */

typedef struct enc {
    const vvc_scan *sc;
    const float *spectra; /* per subcube: its M^3 numbers in scan order */
    size_t per;           /* floats per subcube (M^3) */
    int nsub;
    int threads;
} enc;

/* Symbol statistics of all subcubes at the given steps. */
static vv_status
gather_stats(const enc *en, const float *step_abs, uint64_t *dcf, uint64_t *acf, uint64_t *amp) {
    memset(dcf, 0, sizeof(uint64_t) * VVC_DC_SYMS);
    memset(acf, 0, sizeof(uint64_t) * VVC_AC_SYMS);
    *amp = 0;
    double *inv = malloc(sizeof(double) * (size_t)en->sc->N);
    if (!inv)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int e = 0; e < en->sc->N; e++)
        inv[e] = 1.0 / (double)step_abs[e];
    int failed = 0;
#pragma omp parallel num_threads(en->threads)
    {
        uint64_t ldc[VVC_DC_SYMS] = {0};
        uint64_t *lac = calloc(VVC_AC_SYMS, sizeof *lac);
        int64_t *q = malloc(sizeof *q * (size_t)en->sc->N);
        sym_counter c = {ldc, lac, 0, NULL, NULL, NULL};
#pragma omp for schedule(dynamic, 8)
        for (int s = 0; s < en->nsub; s++) {
            if (!lac || !q)
                continue;
            quantise(en->sc, en->spectra + (size_t)s * en->per, inv, q);
            symbolise(q, en->sc->N, &c);
        }
#pragma omp critical(vvc_stats)
        {
            if (!lac || !q) {
                failed = 1;
            } else {
                for (int i = 0; i < VVC_DC_SYMS; i++)
                    dcf[i] += ldc[i];
                for (int i = 0; i < VVC_AC_SYMS; i++)
                    acf[i] += lac[i];
                *amp += c.amp;
            }
        }
        free(lac);
        free(q);
    }
    free(inv);
    return failed ? vv_error_set(VV_ERR_NOMEM, "out of memory") : VV_OK;
}

static size_t
tables_bytes(int M, const vv_huff_table *dc, const vv_huff_table *ac) {
    const size_t H = (size_t)M / 2 + 1;
    return 4 + 4 * H * H * H + 16 + 2 * (size_t)dc->nvals + 16 + 2 * (size_t)ac->nvals + 4;
}

/* File size for the given steps (tables built from the statistics): exact
 * but for the byte padding of each subcube, counted as 7 bits (an upper bound). */
static vv_status
count_file_bytes(const enc *en, const float *step_abs, int M, uint64_t *file_bytes) {
    uint64_t *dcf = malloc(sizeof *dcf * VVC_DC_SYMS), *acf = malloc(sizeof *acf * VVC_AC_SYMS);
    vv_huff_table *t = malloc(2 * sizeof *t);
    vv_huff_enc *e = malloc(2 * sizeof *e);
    vv_status s = VV_ERR_NOMEM;
    if (!dcf || !acf || !t || !e) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    uint64_t amp;
    if ((s = gather_stats(en, step_abs, dcf, acf, &amp)) != VV_OK)
        goto done;
    vv_huff_build(dcf, VVC_DC_SYMS, &t[0]);
    vv_huff_build(acf, VVC_AC_SYMS, &t[1]);
    if ((s = vv_huff_make_enc(&t[0], &e[0])) != VV_OK || (s = vv_huff_make_enc(&t[1], &e[1])))
        goto done;
    /* the code bits follow from the statistics; each subcube's stream is
     * padded to a byte, at most 7 bits, counted in full so that the
     * estimate is an upper bound */
    uint64_t bits = amp + 7 * (uint64_t)en->nsub;
    for (int i = 0; i < VVC_DC_SYMS; i++)
        bits += dcf[i] * e[0].len[i];
    for (int i = 0; i < VVC_AC_SYMS; i++)
        bits += acf[i] * e[1].len[i];
    const uint64_t data = bits / 8;
    const uint64_t total_data = data + 4;
    const uint64_t index = (uint64_t)en->nsub * (total_data - 4 < (1ull << 32) ? 4 : 8) + 4;
    *file_bytes = VVC_HEADER_BYTES + tables_bytes(M, &t[0], &t[1]) + index + total_data;
    s = VV_OK;
done:
    free(dcf);
    free(acf);
    free(t);
    free(e);
    return s;
}

/* Writes the whole file for the given quality into b. */
static vv_status
encode_file(const enc *en, const vv_volume *v, int M, double quality, double slope, double offset,
            double unit, bytebuf *b, const vv_progress *progress) {
    const vvc_scan *sc = en->sc;
    const int H = M / 2 + 1;
    float *qtab = malloc(sizeof(float) * (size_t)H * H * H);
    float *step_abs = malloc(sizeof(float) * (size_t)sc->N);
    uint64_t *dcf = malloc(sizeof *dcf * VVC_DC_SYMS), *acf = malloc(sizeof *acf * VVC_AC_SYMS);
    vv_huff_table *t = malloc(2 * sizeof *t);
    vv_huff_enc *e = malloc(2 * sizeof *e);
    vv_bitwriter *streams = calloc((size_t)en->nsub, sizeof *streams);
    vv_status s;
    if (!qtab || !step_abs || !dcf || !acf || !t || !e || !streams) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    make_table(qtab, M, quality, slope);
    make_step_abs(sc, qtab, step_abs);
    uint64_t amp;
    if ((s = gather_stats(en, step_abs, dcf, acf, &amp)) != VV_OK)
        goto done;
    vv_huff_build(dcf, VVC_DC_SYMS, &t[0]);
    vv_huff_build(acf, VVC_AC_SYMS, &t[1]);
    if ((s = vv_huff_make_enc(&t[0], &e[0])) != VV_OK || (s = vv_huff_make_enc(&t[1], &e[1])))
        goto done;
    double *inv = malloc(sizeof(double) * (size_t)sc->N);
    if (!inv) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < sc->N; i++)
        inv[i] = 1.0 / (double)step_abs[i];
    int failed = 0;
    int cancelled = 0;
    long done_n = 0;
#pragma omp parallel num_threads(en->threads)
    {
        int64_t *q = malloc(sizeof *q * (size_t)sc->N);
#pragma omp for schedule(dynamic, 8)
        for (int k = 0; k < en->nsub; k++) {
            if (!q || cancelled) {
                failed |= !q;
                continue;
            }
            sym_counter c = {NULL, NULL, 0, &e[0], &e[1], &streams[k]};
            quantise(sc, en->spectra + (size_t)k * en->per, inv, q);
            symbolise(q, sc->N, &c);
            vv_bw_flush(&streams[k]);
            if (streams[k].failed)
                failed = 1;
            if (progress && progress->fn) {
#pragma omp critical(vvc_progress)
                {
                    done_n++;
                    if (vv_progress_report(progress, 0.7 + 0.3 * (double)done_n / en->nsub))
                        cancelled = 1;
                }
            }
        }
        free(q);
    }
    free(inv);
    if (failed) {
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (cancelled) {
        s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
        goto done;
    }
    uint64_t data_len = 0;
    for (int k = 0; k < en->nsub; k++)
        data_len += streams[k].len;
    const int off_bytes = data_len < (1ull << 32) ? 4 : 8;
    const uint64_t tables_size = tables_bytes(M, &t[0], &t[1]);
    const uint64_t index_size = (uint64_t)en->nsub * (uint64_t)off_bytes + 4;
    const uint64_t data_size = data_len + 4;

    /* header */
    bb_put(b, VVC_MAGIC, 8);
    bb_u32(b, VV_VVC_VERSION);
    bb_u32(b, VVC_HEADER_BYTES);
    for (int i = 0; i < 3; i++)
        bb_u32(b, (uint32_t)v->dims[i]);
    bb_u8(b, (unsigned)v->type);
    bb_u8(b, (unsigned)v->unit);
    bb_u8(b, (unsigned)v->data_origin);
    bb_u8(b, (unsigned)v->modification);
    bb_u8(b, (unsigned)v->space);
    bb_u8(b, (unsigned)M);
    bb_u8(b, 0);
    bb_u8(b, 0);
    for (int i = 0; i < 3; i++)
        bb_f64(b, v->spacing[i]);
    for (int i = 0; i < 3; i++)
        bb_f64(b, v->origin[i]);
    for (int i = 0; i < 9; i++)
        bb_f64(b, v->direction[i]);
    bb_f64(b, v->range[0]);
    bb_f64(b, v->range[1]);
    bb_f64(b, offset);
    bb_f64(b, unit);
    bb_f64(b, quality);
    bb_f64(b, slope);
    for (int i = 0; i < 3; i++)
        bb_u32(b, (uint32_t)((v->dims[i] + M - 1) / M));
    bb_u64(b, tables_size);
    bb_u64(b, index_size);
    bb_u64(b, data_size);
    bb_crc(b, 0);
    /* tables */
    size_t from = b->len;
    bb_u32(b, (uint32_t)(H * H * H));
    for (int i = 0; i < H * H * H; i++)
        bb_f32(b, qtab[i]);
    for (int k = 0; k < 2; k++) {
        for (int l = 1; l <= VV_HUFF_MAX_LEN; l++)
            bb_u8(b, t[k].bits[l]);
        for (int i = 0; i < t[k].nvals; i++)
            bb_u16(b, t[k].vals[i]);
    }
    bb_crc(b, from);
    /* index */
    from = b->len;
    uint64_t off = 0;
    for (int k = 0; k < en->nsub; k++) {
        if (off_bytes == 4)
            bb_u32(b, (uint32_t)off);
        else
            bb_u64(b, off);
        off += streams[k].len;
    }
    bb_crc(b, from);
    /* data */
    from = b->len;
    for (int k = 0; k < en->nsub; k++)
        bb_put(b, streams[k].buf, streams[k].len);
    bb_crc(b, from);
    s = b->failed ? vv_error_set(VV_ERR_NOMEM, "out of memory") : VV_OK;
    (void)index_size;
    (void)data_size;
done:
    if (streams)
        for (int k = 0; k < en->nsub; k++)
            free(streams[k].buf);
    free(streams);
    free(qtab);
    free(step_abs);
    free(dcf);
    free(acf);
    free(t);
    free(e);
    return s;
}

static vv_status parse(vv_vvc *c, const char *name);

vv_status
vv_vvc_compress(vv_vvc **out, const vv_volume *v, const vv_vvc_params *p) {
    *out = NULL;
    vv_vvc_params def;
    if (!p) {
        vv_vvc_params_init(&def);
        p = &def;
    }
    if (!v || !v->data)
        return vv_error_set(VV_ERR_INVALID, "vvc: no volume");
    if (p->block != 8 && p->block != 16 && p->block != 32)
        return vv_error_set(VV_ERR_INVALID, "vvc: block size %d (expected 8, 16 or 32)", p->block);
    if (p->target == VV_VVC_QUALITY && !(p->quality >= 0 && p->quality <= 100))
        return vv_error_set(VV_ERR_INVALID, "vvc: quality %g outside [0, 100]", p->quality);
    if (p->target == VV_VVC_RATE && !(p->rate > 0 && isfinite(p->rate)))
        return vv_error_set(VV_ERR_INVALID, "vvc: rate %g bits per voxel (must be > 0)", p->rate);
    if (!(p->slope >= 0 && p->slope <= 100))
        return vv_error_set(VV_ERR_INVALID, "vvc: slope %g outside [0, 100]", p->slope);
    if (!(v->range[1] >= v->range[0]) || !isfinite(v->range[0]) || !isfinite(v->range[1]))
        return vv_error_set(VV_ERR_INVALID, "vvc: the volume's value range [%g, %g] is not valid",
                            v->range[0], v->range[1]);
    const int M = p->block;
    vvc_scan sc;
    vv_status s = scan_init(&sc, M);
    if (s != VV_OK)
        return s;
    float *spectra = NULL;
    double offset, unit;
    const int threads = p->threads > 0 ? p->threads : vv_threads_get();
    if ((s = vv_vvc_spectra(v, M, threads, &spectra, &offset, &unit, &p->progress)) != VV_OK) {
        scan_free(&sc);
        return s;
    }
    enc en = {&sc, NULL, (size_t)sc.N, 0, threads};
    en.nsub = (int)(((v->dims[0] + M - 1) / M) * (size_t)((v->dims[1] + M - 1) / M) *
                    (size_t)((v->dims[2] + M - 1) / M));
    {
        /* the M^3 independent numbers of each spectrum in scan order, so that
         * every quantisation pass reads them contiguously */
        const size_t per = 2 * (size_t)M * M * (M / 2 + 1);
        float *scanned = malloc(sizeof(float) * (size_t)sc.N * (size_t)en.nsub);
        if (!scanned) {
            fftwf_free(spectra);
            scan_free(&sc);
            return vv_error_set(VV_ERR_NOMEM, "vvc: out of memory");
        }
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int k = 0; k < en.nsub; k++) {
            const float *src = spectra + per * (size_t)k;
            float *dst = scanned + (size_t)sc.N * (size_t)k;
            for (int e = 0; e < sc.N; e++)
                dst[e] = src[sc.entry[e]];
        }
        fftwf_free(spectra);
        spectra = NULL;
        en.spectra = scanned;
    }
    double quality = p->quality;
    if (p->target == VV_VVC_RATE) {
        const int H = M / 2 + 1;
        float *qtab = malloc(sizeof(float) * (size_t)H * H * H);
        float *step_abs = malloc(sizeof(float) * (size_t)sc.N);
        if (!qtab || !step_abs) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory");
        } else {
            const double target_bytes = p->rate * (double)vv_volume_voxel_count(v) / 8.0;
            /* The file grows with quality and log(size) is nearly linear in
             * it: regula falsi on log(size / target) (Illinois variant), keeping
             * the bracket [lo (fits), hi (too big)]; stops within 0.3 % of the
             * target or after 16 sizes. */
            double lo = 0, hi = 100, flo = 0, fhi = 0;
            uint64_t bytes = 0;
            int side = 0;
            make_table(qtab, M, hi, p->slope);
            make_step_abs(&sc, qtab, step_abs);
            s = count_file_bytes(&en, step_abs, M, &bytes);
            fhi = log((double)bytes / target_bytes);
            if (s == VV_OK && fhi <= 0) {
                lo = hi;
            } else if (s == VV_OK) {
                make_table(qtab, M, lo, p->slope);
                make_step_abs(&sc, qtab, step_abs);
                s = count_file_bytes(&en, step_abs, M, &bytes);
                flo = log((double)bytes / target_bytes);
                for (int it = 0; it < 14 && s == VV_OK && flo < 0 && flo < -0.003; it++) {
                    double mid = lo - flo * (hi - lo) / (fhi - flo);
                    if (!(mid > lo && mid < hi))
                        mid = 0.5 * (lo + hi);
                    make_table(qtab, M, mid, p->slope);
                    make_step_abs(&sc, qtab, step_abs);
                    if ((s = count_file_bytes(&en, step_abs, M, &bytes)) != VV_OK)
                        break;
                    const double f = log((double)bytes / target_bytes);
                    if (f <= 0) {
                        lo = mid;
                        flo = f;
                        if (side == -1)
                            fhi *= 0.5;
                        side = -1;
                    } else {
                        hi = mid;
                        fhi = f;
                        if (side == 1)
                            flo *= 0.5;
                        side = 1;
                    }
                    if (vv_progress_report(&p->progress, 0.3 + 0.4 * (it + 1) / 14.0)) {
                        s = vv_error_set(VV_ERR_CANCELLED, "cancelled");
                        break;
                    }
                }
            }
            quality = lo;
        }
        free(qtab);
        free(step_abs);
    }
    bytebuf b = {0};
    if (s == VV_OK)
        s = encode_file(&en, v, M, quality, p->slope, offset, unit, &b, &p->progress);
    free((void *)en.spectra);
    scan_free(&sc);
    if (s != VV_OK) {
        free(b.p);
        return vv_error_prefix(s, "vvc");
    }
    vv_vvc *c = calloc(1, sizeof *c);
    if (!c) {
        free(b.p);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    c->bytes = b.p;
    c->size = b.len;
    if ((s = parse(c, "(compressed)")) != VV_OK) {
        vv_vvc_free(c);
        return s;
    }
    *out = c;
    return VV_OK;
}

/* ---------------------------------------------------------------------- */
/* Parsing                                                                  */

static vv_status
parse_huff(const unsigned char **pp, const unsigned char *end, vv_huff_table *t, int nsym,
           const char *what) {
    const unsigned char *p = *pp;
    if (end - p < VV_HUFF_MAX_LEN)
        return vv_error_set(VV_ERR_FORMAT, "%s Huffman table truncated", what);
    memset(t, 0, sizeof *t);
    int total = 0;
    for (int l = 1; l <= VV_HUFF_MAX_LEN; l++) {
        t->bits[l] = *p++;
        total += t->bits[l];
    }
    if (total > nsym)
        return vv_error_set(VV_ERR_FORMAT, "%s Huffman table has %d codes (at most %d)", what,
                            total, nsym);
    if (end - p < 2 * total)
        return vv_error_set(VV_ERR_FORMAT, "%s Huffman table truncated", what);
    for (int i = 0; i < total; i++) {
        unsigned v = (unsigned)p[0] | (unsigned)p[1] << 8;
        p += 2;
        if ((int)v >= nsym)
            return vv_error_set(VV_ERR_FORMAT, "%s Huffman symbol %u out of range", what, v);
        if (nsym == VVC_DC_SYMS ? v > VVC_MAX_SIZE : (v & 63) > VVC_MAX_SIZE || v >> 6 > 15)
            return vv_error_set(VV_ERR_FORMAT, "%s Huffman symbol %u is not valid", what, v);
        t->vals[i] = (uint16_t)v;
    }
    t->nvals = total;
    *pp = p;
    return VV_OK;
}

static vv_status
parse(vv_vvc *c, const char *name) {
    const unsigned char *b = c->bytes;
    const uint64_t size = c->size;
    (void)name;
    if (size < 8 || memcmp(b, VVC_MAGIC, 8) != 0)
        return vv_error_set(VV_ERR_FORMAT, "not a .vvc file (bad magic number)");
    if (size < VVC_HEADER_BYTES)
        return vv_error_set(VV_ERR_FORMAT, "truncated header (%llu of %d bytes)",
                            (unsigned long long)size, VVC_HEADER_BYTES);
    const uint32_t version = rd_u32(b + 8);
    if (rd_u32(b + VVC_HEADER_BYTES - 4) != crc_of(b, VVC_HEADER_BYTES - 4))
        return vv_error_set(VV_ERR_FORMAT, "header CRC-32 mismatch (corrupt file)");
    if (version != VV_VVC_VERSION)
        return vv_error_set(VV_ERR_FORMAT, "format version %u (this build reads version %d)",
                            version, VV_VVC_VERSION);
    if (rd_u32(b + 12) != VVC_HEADER_BYTES)
        return vv_error_set(VV_ERR_FORMAT, "header size %u (expected %d)", rd_u32(b + 12),
                            VVC_HEADER_BYTES);
    vv_vvc_info *in = &c->info;
    memset(in, 0, sizeof *in);
    in->version = (int)version;
    for (int i = 0; i < 3; i++) {
        uint32_t d = rd_u32(b + 16 + 4 * i);
        if (d < 1 || d > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_FORMAT, "dimension %d is %u", i, d);
        in->dims[i] = (int)d;
    }
    if (b[28] > VV_F64 || b[29] > VV_UNIT_UNKNOWN || b[30] > VV_ORIGIN_OTHER ||
        b[31] > VV_MOD_OTHER || b[32] > VV_SPACE_LPS)
        return vv_error_set(VV_ERR_FORMAT, "bad enumeration in the header");
    in->type = (vv_voxel_type)b[28];
    in->unit = (vv_unit)b[29];
    in->data_origin = (vv_data_origin)b[30];
    in->modification = (vv_modification)b[31];
    in->space = (vv_space)b[32];
    const int M = b[33];
    if (M != 8 && M != 16 && M != 32)
        return vv_error_set(VV_ERR_FORMAT, "subcube side %d (expected 8, 16 or 32)", M);
    vv_status s = vv_volume_check_size(in->dims, in->type, &in->raw_bytes);
    if (s != VV_OK)
        return s;
    const unsigned char *p = b + 36;
    for (int i = 0; i < 3; i++)
        in->spacing[i] = rd_f64(p + 8 * i);
    for (int i = 0; i < 3; i++)
        in->origin[i] = rd_f64(p + 24 + 8 * i);
    for (int i = 0; i < 9; i++)
        in->direction[i] = rd_f64(p + 48 + 8 * i);
    p += 120;
    in->range[0] = rd_f64(p);
    in->range[1] = rd_f64(p + 8);
    in->value_offset = rd_f64(p + 16);
    in->value_unit = rd_f64(p + 24);
    in->quality = rd_f64(p + 32);
    in->slope = rd_f64(p + 40);
    p += 48;
    if (!isfinite(in->value_offset) || !(in->value_unit > 0) || !isfinite(in->value_unit))
        return vv_error_set(VV_ERR_FORMAT, "bad value offset or unit");
    for (int i = 0; i < 3; i++) {
        in->subcubes[i] = (int)rd_u32(p + 4 * i);
        if (in->subcubes[i] != (in->dims[i] + M - 1) / M)
            return vv_error_set(VV_ERR_FORMAT, "%d subcubes along axis %d for %d voxels of %d",
                                in->subcubes[i], i, in->dims[i], M);
    }
    p += 12;
    const uint64_t tables_size = rd_u64(p), index_size = rd_u64(p + 8), data_size = rd_u64(p + 16);
    const uint64_t rest = size - VVC_HEADER_BYTES;
    if (tables_size > rest || index_size > rest - tables_size ||
        data_size != rest - tables_size - index_size)
        return vv_error_set(VV_ERR_FORMAT,
                            "section sizes %llu + %llu + %llu do not match the %llu bytes after "
                            "the header (truncated or corrupt file)",
                            (unsigned long long)tables_size, (unsigned long long)index_size,
                            (unsigned long long)data_size, (unsigned long long)rest);
    c->M = M;
    in->block = M;
    c->nsub = in->subcubes[0] * in->subcubes[1] * in->subcubes[2];
    in->file_bytes = size;
    in->data_bytes = data_size >= 4 ? data_size - 4 : 0;
    in->ratio = (double)in->raw_bytes / (double)size;
    in->bits_per_voxel =
        8.0 * (double)size / ((double)in->dims[0] * (double)in->dims[1] * (double)in->dims[2]);

    /* tables */
    const unsigned char *t0 = b + VVC_HEADER_BYTES;
    if (tables_size < 8 || rd_u32(t0 + tables_size - 4) != crc_of(t0, tables_size - 4))
        return vv_error_set(VV_ERR_FORMAT, "tables CRC-32 mismatch (corrupt file)");
    const int H = M / 2 + 1;
    if (rd_u32(t0) != (uint32_t)(H * H * H) || tables_size < 4 + 4ull * H * H * H + 4)
        return vv_error_set(VV_ERR_FORMAT, "quantisation table size %u (expected %d)", rd_u32(t0),
                            H * H * H);
    if ((s = scan_init(&c->scan, M)) != VV_OK)
        return s;
    c->qtab = malloc(sizeof(float) * (size_t)H * H * H);
    c->step_abs = malloc(sizeof(float) * (size_t)c->scan.N);
    if (!c->qtab || !c->step_abs)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < H * H * H; i++) {
        float q = rd_f32(t0 + 4 + 4 * (size_t)i);
        if (!(q > 0) || !(q < 1e30f))
            return vv_error_set(VV_ERR_FORMAT, "quantisation step %d is %g", i, (double)q);
        c->qtab[i] = q;
    }
    make_step_abs(&c->scan, c->qtab, c->step_abs);
    const unsigned char *hp = t0 + 4 + 4 * (size_t)H * H * H, *hend = t0 + tables_size - 4;
    if ((s = parse_huff(&hp, hend, &c->dct, VVC_DC_SYMS, "DC")) != VV_OK ||
        (s = parse_huff(&hp, hend, &c->act, VVC_AC_SYMS, "AC")) != VV_OK)
        return s;
    if (hp != hend)
        return vv_error_set(VV_ERR_FORMAT, "%lld stray bytes after the Huffman tables",
                            (long long)(hend - hp));
    if ((s = vv_huff_make_dec(&c->dct, &c->dc)) != VV_OK ||
        (s = vv_huff_make_dec(&c->act, &c->ac)) != VV_OK)
        return s;

    /* index */
    const unsigned char *i0 = t0 + tables_size;
    if (data_size < 4)
        return vv_error_set(VV_ERR_FORMAT, "data section of %llu bytes",
                            (unsigned long long)data_size);
    const uint64_t data_len = data_size - 4;
    const int ob = data_len < (1ull << 32) ? 4 : 8;
    if (index_size != (uint64_t)c->nsub * (uint64_t)ob + 4)
        return vv_error_set(VV_ERR_FORMAT, "subcube index of %llu bytes (expected %llu)",
                            (unsigned long long)index_size,
                            (unsigned long long)((uint64_t)c->nsub * (uint64_t)ob + 4));
    if (rd_u32(i0 + index_size - 4) != crc_of(i0, index_size - 4))
        return vv_error_set(VV_ERR_FORMAT, "subcube index CRC-32 mismatch (corrupt file)");
    c->offsets = malloc(sizeof(uint64_t) * ((size_t)c->nsub + 1));
    if (!c->offsets)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int k = 0; k < c->nsub; k++) {
        uint64_t o = ob == 4 ? rd_u32(i0 + 4 * (size_t)k) : rd_u64(i0 + 8 * (size_t)k);
        if ((k == 0 && o != 0) || (k > 0 && o < c->offsets[k - 1]) || o > data_len)
            return vv_error_set(VV_ERR_FORMAT, "subcube %d: offset %llu out of order", k,
                                (unsigned long long)o);
        c->offsets[k] = o;
    }
    c->offsets[c->nsub] = data_len;
    const unsigned char *d0 = i0 + index_size;
    if (rd_u32(d0 + data_len) != crc_of(d0, data_len))
        return vv_error_set(VV_ERR_FORMAT, "data CRC-32 mismatch (corrupt file)");
    c->data_start = (uint64_t)(d0 - b);
    c->data_len = data_len;
    return VV_OK;
}

vv_status
vv_vvc_from_memory(vv_vvc **out, const void *data, size_t size, const char *name) {
    *out = NULL;
    if (!name)
        name = "(memory)";
    if ((uint64_t)size > VVC_MAX_FILE)
        return vv_error_set(VV_ERR_LIMIT, "vvc: %s: %zu bytes is over the limit", name, size);
    vv_vvc *c = calloc(1, sizeof *c);
    if (!c || !(c->bytes = malloc(size ? size : 1))) {
        free(c);
        return vv_error_set(VV_ERR_NOMEM, "vvc: %s: out of memory", name);
    }
    memcpy(c->bytes, data, size);
    c->size = size;
    vv_status s = parse(c, name);
    if (s != VV_OK) {
        vv_vvc_free(c);
        return vv_error_prefix(s, "vvc: %s", name);
    }
    *out = c;
    return VV_OK;
}

vv_status
vv_vvc_load(vv_vvc **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, VVC_MAX_FILE, &data, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "vvc: %s", path);
    vv_vvc *c = calloc(1, sizeof *c);
    if (!c) {
        free(data);
        return vv_error_set(VV_ERR_NOMEM, "vvc: %s: out of memory", path);
    }
    c->bytes = data;
    c->size = (size_t)size;
    if ((s = parse(c, path)) != VV_OK) {
        vv_vvc_free(c);
        return vv_error_prefix(s, "vvc: %s", path);
    }
    *out = c;
    return VV_OK;
}

vv_status
vv_vvc_save(const vv_vvc *c, const char *path) {
    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, path);
    if (s != VV_OK)
        return vv_error_prefix(s, "vvc");
    if (fwrite(c->bytes, 1, c->size, af.fp) != c->size) {
        vv_atomic_file_abort(&af);
        return vv_error_set(VV_ERR_IO, "vvc: %s: write failed", path);
    }
    if ((s = vv_atomic_file_commit(&af)) != VV_OK)
        return vv_error_prefix(s, "vvc");
    return VV_OK;
}

const unsigned char *
vv_vvc_bytes(const vv_vvc *c, size_t *size) {
    if (size)
        *size = c->size;
    return c->bytes;
}

void
vv_vvc_get_info(const vv_vvc *c, vv_vvc_info *info) {
    *info = c->info;
}

int
vv_vvc_detect(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    unsigned char m[8];
    int ok = fread(m, 1, 8, f) == 8 && memcmp(m, VVC_MAGIC, 8) == 0;
    fclose(f);
    return ok;
}

int
vv_vvc_subcube_count(const vv_vvc *c) {
    return c->nsub;
}

/* ---------------------------------------------------------------------- */
/* Decoding                                                                 */

/* Entropy decoding of one subcube into N integers in scan order. */
static vv_status
decode_ints(const vv_vvc *c, int index, int64_t *q) {
    const int N = c->scan.N;
    vv_bitreader r = {c->bytes + c->data_start + c->offsets[index],
                      c->bytes + c->data_start + c->offsets[index + 1], 0, 0, 0};
    memset(q, 0, sizeof *q * (size_t)N);
    int sym = vv_huff_decode(&r, &c->dc);
    if (sym < 0 || sym > VVC_MAX_SIZE)
        goto bad;
    int64_t v = 0;
    if (sym > 0) {
        uint64_t bits = sym > 32 ? ((uint64_t)vv_br_get(&r, sym - 32) << 32) | vv_br_get(&r, 32)
                                 : vv_br_get(&r, sym);
        v = (bits >> (sym - 1)) ? (int64_t)bits : (int64_t)bits - (int64_t)((1ull << sym) - 1);
    }
    q[0] = v;
    for (int k = 1; k < N;) {
        sym = vv_huff_decode(&r, &c->ac);
        if (sym < 0)
            goto bad;
        if (sym == VVC_EOB)
            break;
        const int run = sym >> 6, size = sym & 63;
        if (size == 0) {
            if (sym != VVC_ZRL)
                goto bad;
            k += 16;
            if (k >= N) /* a ZRL must be followed by a coefficient */
                goto bad;
            continue;
        }
        k += run;
        if (k >= N || size > VVC_MAX_SIZE)
            goto bad;
        uint64_t bits = size > 32 ? ((uint64_t)vv_br_get(&r, size - 32) << 32) | vv_br_get(&r, 32)
                                  : vv_br_get(&r, size);
        q[k] = (bits >> (size - 1)) ? (int64_t)bits : (int64_t)bits - (int64_t)((1ull << size) - 1);
        k++;
        if (vv_br_overrun(&r))
            goto bad;
    }
    if (vv_br_overrun(&r))
        goto bad;
    return VV_OK;
bad:
    return vv_error_set(VV_ERR_FORMAT, "subcube %d: bit stream does not decode", index);
}

vv_status
vv_vvc_decode_spectrum(const vv_vvc *c, int index, float *spectrum) {
    if (index < 0 || index >= c->nsub)
        return vv_error_set(VV_ERR_INVALID, "vvc: subcube %d out of range (0..%d)", index,
                            c->nsub - 1);
    const vvc_scan *sc = &c->scan;
    int64_t *q = malloc(sizeof *q * (size_t)sc->N);
    if (!q)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    vv_status s = decode_ints(c, index, q);
    if (s != VV_OK) {
        free(q);
        return vv_error_prefix(s, "vvc");
    }
    memset(spectrum, 0, sizeof(float) * 2 * (size_t)sc->M * sc->M * sc->H);
    for (int e = 0; e < sc->N; e++)
        spectrum[sc->entry[e]] = (float)((double)q[e] * (double)c->step_abs[e]);
    for (int m = 0; m < sc->nmirror; m++) {
        const int from = sc->mirror[2 * m], to = sc->mirror[2 * m + 1];
        spectrum[2 * to] = spectrum[2 * from];
        spectrum[2 * to + 1] = -spectrum[2 * from + 1];
    }
    free(q);
    return VV_OK;
}

static vv_status
ensure_plan(const vv_vvc *cc) {
    vv_vvc *c = (vv_vvc *)cc;
    vv_status s = VV_OK;
    vv_fftw_lock();
    if (!c->c2r) {
        const int M = c->M;
        float *in = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * (M / 2 + 1));
        float *out = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
        if (in && out)
            c->c2r = fftwf_plan_dft_c2r_3d(M, M, M, (fftwf_complex *)in, out, FFTW_ESTIMATE);
        if (!c->c2r)
            s = vv_error_set(VV_ERR_NOMEM, "FFTW could not make a %d^3 plan", M);
        fftwf_free(in);
        fftwf_free(out);
    }
    vv_fftw_unlock();
    return s;
}

/* Inverse transform of one subcube (spectrum is destroyed) into values. */
static void
subcube_values(const vv_vvc *c, float *spectrum, float *values) {
    fftwf_execute_dft_c2r(c->c2r, (fftwf_complex *)spectrum, values);
    const int N = c->scan.N;
    const float scale = (float)(c->info.value_unit / N);
    const float off = (float)c->info.value_offset;
    for (int i = 0; i < N; i++)
        values[i] = off + scale * values[i];
}

vv_status
vv_vvc_decode_subcube(const vv_vvc *c, int index, float *values) {
    vv_status s = ensure_plan(c);
    if (s != VV_OK)
        return s;
    const int M = c->M;
    float *sp = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * (M / 2 + 1));
    float *vals = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
    if (!sp || !vals) {
        fftwf_free(sp);
        fftwf_free(vals);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    if ((s = vv_vvc_decode_spectrum(c, index, sp)) == VV_OK) {
        subcube_values(c, sp, vals);
        memcpy(values, vals, sizeof(float) * (size_t)M * M * M);
    }
    fftwf_free(sp);
    fftwf_free(vals);
    return s;
}

vv_status
vv_vvc_decompress(vv_volume **out, const vv_vvc *c, int threads, const vv_progress *progress) {
    *out = NULL;
    vv_status s = ensure_plan(c);
    if (s != VV_OK)
        return s;
    vv_volume *v;
    if ((s = vv_volume_new(&v, c->info.dims, c->info.type)) != VV_OK)
        return vv_error_prefix(s, "vvc");
    for (int i = 0; i < 3; i++) {
        v->spacing[i] = c->info.spacing[i];
        v->origin[i] = c->info.origin[i];
    }
    memcpy(v->direction, c->info.direction, sizeof v->direction);
    v->unit = c->info.unit;
    v->data_origin = c->info.data_origin;
    v->modification = c->info.modification;
    v->space = c->info.space;
    const int M = c->M;
    const int *nb = c->info.subcubes;
    const int nthreads = threads > 0 ? threads : vv_threads_get();
    int failed = 0, cancelled = 0;
    long done = 0;
    char msg[256] = "";
#pragma omp parallel num_threads(nthreads)
    {
        float *sp = fftwf_malloc(sizeof(float) * 2 * (size_t)M * M * (M / 2 + 1));
        float *vals = fftwf_malloc(sizeof(float) * (size_t)M * M * M);
#pragma omp for schedule(dynamic, 4)
        for (int k = 0; k < c->nsub; k++) {
            if (failed || cancelled)
                continue;
            if (!sp || !vals) {
                failed = 1;
                continue;
            }
            if (vv_vvc_decode_spectrum(c, k, sp) != VV_OK) {
#pragma omp critical(vvc_err)
                {
                    if (!failed)
                        snprintf(msg, sizeof msg, "%s", vv_error_message());
                    failed = 2;
                }
                continue;
            }
            subcube_values(c, sp, vals);
            const int bx = k % nb[0], by = (k / nb[0]) % nb[1], bz = k / (nb[0] * nb[1]);
            const int nx = v->dims[0] - bx * M < M ? v->dims[0] - bx * M : M;
            for (int z = 0; z < M; z++) {
                const int kk = bz * M + z;
                if (kk >= v->dims[2])
                    break;
                for (int y = 0; y < M; y++) {
                    const int jj = by * M + y;
                    if (jj >= v->dims[1])
                        break;
                    store_row(v,
                              ((size_t)kk * v->dims[1] + (size_t)jj) * v->dims[0] + (size_t)bx * M,
                              vals + (z * M + y) * M, nx);
                }
            }
            if (progress && progress->fn) {
#pragma omp critical(vvc_progress)
                {
                    done++;
                    if (vv_progress_report(progress, (double)done / c->nsub))
                        cancelled = 1;
                }
            }
        }
        fftwf_free(sp);
        fftwf_free(vals);
    }
    if (failed || cancelled) {
        vv_volume_free(v);
        if (cancelled && !failed)
            return vv_error_set(VV_ERR_CANCELLED, "cancelled");
        if (failed == 2)
            return vv_error_set(VV_ERR_FORMAT, "%s", msg);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

vv_status
vv_volume_compare(const vv_volume *a, const vv_volume *b, double *psnr, double *rmse,
                  double *max_error) {
    for (int i = 0; i < 3; i++)
        if (a->dims[i] != b->dims[i])
            return vv_error_set(VV_ERR_INVALID, "compare: dimensions %dx%dx%d and %dx%dx%d differ",
                                a->dims[0], a->dims[1], a->dims[2], b->dims[0], b->dims[1],
                                b->dims[2]);
    double se = 0, mx = 0, lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < a->dims[2]; k++)
        for (int j = 0; j < a->dims[1]; j++)
            for (int i = 0; i < a->dims[0]; i++) {
                const double x = vv_volume_get(a, i, j, k), y = vv_volume_get(b, i, j, k);
                const double d = fabs(x - y);
                se += d * d;
                mx = d > mx ? d : mx;
                lo = x < lo ? x : lo;
                hi = x > hi ? x : hi;
            }
    const double mse = se / (double)vv_volume_voxel_count(a);
    const double peak = hi - lo;
    if (psnr)
        *psnr = mse == 0 ? INFINITY : 10.0 * log10(peak * peak / mse);
    if (rmse)
        *rmse = sqrt(mse);
    if (max_error)
        *max_error = mx;
    return VV_OK;
}
