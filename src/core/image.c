/* RGBA float + depth images (see volvis/image.h). */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "volvis/image.h"

vv_status
vv_image_new(vv_image **out, int width, int height) {
    *out = NULL;
    if (width < 1 || height < 1 || width > VV_IMAGE_MAX_SIDE || height > VV_IMAGE_MAX_SIDE)
        return vv_error_set(VV_ERR_INVALID, "image size %d x %d is outside 1..%d", width, height,
                            VV_IMAGE_MAX_SIDE);
    vv_image *img = calloc(1, sizeof *img);
    size_t n = (size_t)width * (size_t)height;
    if (img) {
        img->rgba = malloc(n * 4 * sizeof(float));
        img->depth = malloc(n * sizeof(float));
    }
    if (!img || !img->rgba || !img->depth) {
        vv_image_free(img);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a %d x %d image", width, height);
    }
    img->width = width;
    img->height = height;
    vv_image_clear(img, 0, 0, 0, 0);
    *out = img;
    return VV_OK;
}

void
vv_image_free(vv_image *img) {
    if (!img)
        return;
    free(img->rgba);
    free(img->depth);
    free(img);
}

void
vv_image_clear(vv_image *img, float r, float g, float b, float a) {
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++) {
        img->rgba[4 * i + 0] = r;
        img->rgba[4 * i + 1] = g;
        img->rgba[4 * i + 2] = b;
        img->rgba[4 * i + 3] = a;
        img->depth[i] = INFINITY;
    }
}

static uint8_t
to8(float v, double inv_gamma) {
    if (!(v > 0))
        return 0;
    if (v >= 1)
        return 255;
    double x = inv_gamma == 1.0 ? v : pow(v, inv_gamma);
    return (uint8_t)lrint(x * 255.0);
}

void
vv_image_to_8bit(const vv_image *img, int channels, double gamma, uint8_t *out) {
    double ig = gamma > 0 ? 1.0 / gamma : 1.0;
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            out[channels * i + (size_t)c] = to8(img->rgba[4 * i + (size_t)c], ig);
        if (channels == 4)
            out[4 * i + 3] = to8(img->rgba[4 * i + 3], 1.0);
    }
}

void
vv_image_rect_to_rgbx8(const vv_image *img, int x0, int y0, int x1, int y1, uint8_t *out) {
    const size_t row = 4 * (size_t)img->width;
    const size_t n = 4 * (size_t)(x1 - x0);
    for (int y = y0; y < y1; y++) {
        /* one contiguous loop the compiler vectorizes (lrint per
         * component, as vv_image_to_8bit's, is 4 times slower) */
        const float *a = img->rgba + (size_t)y * row + 4 * (size_t)x0;
        uint8_t *b = out + (size_t)y * row + 4 * (size_t)x0;
        for (size_t i = 0; i < n; i++) {
            float v = a[i] * 255.0f + 0.5f;
            v = v > 0 ? v : 0;
            v = v < 255 ? v : 255;
            b[i] = (uint8_t)v;
        }
    }
}

/*
 * libjpeg's RGB -> YCbCr (jccolor.c): JFIF's full-range BT.601 in 16-bit
 * fixed point, Y rounded by 1/2, Cb and Cr by 1/2 - epsilon, with its
 * tables of each coefficient times 0..255 for the scalar columns (a table
 * lookup a term is cheaper than a multiply there; SSE2 does eight columns
 * at a time with the same integers); then Cb and Cr averaged over 2 x 2 pixels
 * with a bias of 1 and 2 in turn along the row (jcsample.c's
 * h2v2_downsample).
 */
#define YCC_FIX(x) ((int32_t)((x)*65536.0 + 0.5))
#define YCC_HALF ((int32_t)1 << 15)
#define YCC_CBCR_OFFSET ((int32_t)128 << 16)
enum { YCC_R_Y, YCC_G_Y, YCC_B_Y, YCC_R_CB, YCC_G_CB, YCC_B_CB, YCC_G_CR, YCC_B_CR, YCC_TABLES };
static int32_t ycc_tab[YCC_TABLES][256]; /* R -> Cr is B -> Cb's */
static pthread_once_t ycc_once = PTHREAD_ONCE_INIT;

static void
ycc_init(void) {
    for (int32_t i = 0; i < 256; i++) {
        ycc_tab[YCC_R_Y][i] = YCC_FIX(0.29900) * i;
        ycc_tab[YCC_G_Y][i] = YCC_FIX(0.58700) * i;
        ycc_tab[YCC_B_Y][i] = YCC_FIX(0.11400) * i + YCC_HALF;
        ycc_tab[YCC_R_CB][i] = -YCC_FIX(0.16874) * i;
        ycc_tab[YCC_G_CB][i] = -YCC_FIX(0.33126) * i;
        ycc_tab[YCC_B_CB][i] = YCC_FIX(0.50000) * i + YCC_CBCR_OFFSET + YCC_HALF - 1;
        ycc_tab[YCC_G_CR][i] = -YCC_FIX(0.41869) * i;
        ycc_tab[YCC_B_CR][i] = -YCC_FIX(0.08131) * i;
    }
}

/* a component as vv_image_rect_to_rgbx8's byte */
static inline int
ycc_q8(float v) {
    float t = v * 255.0f + 0.5f;
    t = t > 0 ? t : 0;
    t = t < 255 ? t : 255;
    return (int)t;
}

#ifdef __SSE2__
/*
 * Eight columns of a pair of rows in SSE2 (x86-64's baseline), the same
 * integers as the tables: pmaddwd takes 16-bit factors, so a coefficient
 * over 32767 (G's 38470 for Y, B's and R's 32768 for Cb and Cr) is halved
 * and its component doubled first (2 G <= 510), exactly.
 */
static inline __m128i
ycc_sse2_q8(const float *a) { /* a pixel's R, G, B, A as vv_image_rect_to_rgbx8's bytes */
    __m128 t = _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(a), _mm_set1_ps(255.0f)), _mm_set1_ps(0.5f));
    t = _mm_min_ps(_mm_max_ps(t, _mm_setzero_ps()), _mm_set1_ps(255.0f)); /* NaN: 0 */
    return _mm_cvttps_epi32(t);
}

/* Y, Cb or Cr of 4 pixels (16-bit R G B A, 2 pixels a vector in p01, p23):
 * (sum of the components times @p mul times @p coef, + @p add) >> 16 */
static inline __m128i
ycc_sse2_term(__m128i p01, __m128i p23, __m128i mul, __m128i coef, __m128i add) {
    __m128 a = _mm_castsi128_ps(_mm_madd_epi16(_mm_mullo_epi16(p01, mul), coef));
    __m128 b = _mm_castsi128_ps(_mm_madd_epi16(_mm_mullo_epi16(p23, mul), coef));
    __m128i even = _mm_castps_si128(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)));
    __m128i odd = _mm_castps_si128(_mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
    return _mm_srai_epi32(_mm_add_epi32(_mm_add_epi32(even, odd), add), 16);
}

/* Columns x .. x + 7 (all in the image) of rows @p a0, @p a1: Y into l0 + x, l1 + x,
 * Cb and Cr into cb + x / 2, cr + x / 2 */
static inline void
ycc_sse2_8(const float *a0, const float *a1, int x, uint8_t *l0, uint8_t *l1, uint8_t *cb,
           uint8_t *cr) {
    const __m128i y_mul = _mm_setr_epi16(1, 2, 1, 0, 1, 2, 1, 0);
    const __m128i y_coef =
        _mm_setr_epi16(YCC_FIX(0.29900), YCC_FIX(0.58700) / 2, YCC_FIX(0.11400), 0,
                       YCC_FIX(0.29900), YCC_FIX(0.58700) / 2, YCC_FIX(0.11400), 0);
    const __m128i cb_mul = _mm_setr_epi16(1, 1, 2, 0, 1, 1, 2, 0);
    const __m128i cb_coef =
        _mm_setr_epi16(-YCC_FIX(0.16874), -YCC_FIX(0.33126), YCC_FIX(0.50000) / 2, 0,
                       -YCC_FIX(0.16874), -YCC_FIX(0.33126), YCC_FIX(0.50000) / 2, 0);
    const __m128i cr_mul = _mm_setr_epi16(2, 1, 1, 0, 2, 1, 1, 0);
    const __m128i cr_coef =
        _mm_setr_epi16(YCC_FIX(0.50000) / 2, -YCC_FIX(0.41869), -YCC_FIX(0.08131), 0,
                       YCC_FIX(0.50000) / 2, -YCC_FIX(0.41869), -YCC_FIX(0.08131), 0);
    const __m128i y_add = _mm_set1_epi32(YCC_HALF);
    const __m128i c_add = _mm_set1_epi32(YCC_CBCR_OFFSET + YCC_HALF - 1);
    const float *row[2] = {a0 + 4 * (size_t)x, a1 + 4 * (size_t)x};
    uint8_t *luma[2] = {l0 + x, l1 + x};
    __m128i cbs[2][2], crs[2][2]; /* [row][half]: 4 pixels' Cb, Cr */
    for (int r = 0; r < 2; r++) {
        __m128i p[4]; /* 16-bit R G B A of pixels 2k, 2k + 1 */
        for (int k = 0; k < 4; k++)
            p[k] = _mm_packs_epi32(ycc_sse2_q8(row[r] + 8 * k), ycc_sse2_q8(row[r] + 8 * k + 4));
        __m128i y03 = ycc_sse2_term(p[0], p[1], y_mul, y_coef, y_add);
        __m128i y47 = ycc_sse2_term(p[2], p[3], y_mul, y_coef, y_add);
        __m128i y16 = _mm_packs_epi32(y03, y47);
        _mm_storel_epi64((__m128i *)luma[r], _mm_packus_epi16(y16, y16));
        for (int h = 0; h < 2; h++) {
            cbs[r][h] = ycc_sse2_term(p[2 * h], p[2 * h + 1], cb_mul, cb_coef, c_add);
            crs[r][h] = ycc_sse2_term(p[2 * h], p[2 * h + 1], cr_mul, cr_coef, c_add);
        }
    }
    /* 2 x 2 sums: the rows added, then neighbouring columns, + bias 1, 2, ... from column x / 2 */
    const __m128i bias = (x >> 1) & 1 ? _mm_setr_epi32(2, 1, 2, 1) : _mm_setr_epi32(1, 2, 1, 2);
    uint8_t *out[2] = {cb + x / 2, cr + x / 2};
    for (int c = 0; c < 2; c++) {
        __m128i(*v)[2] = c == 0 ? cbs : crs;
        __m128 lo = _mm_castsi128_ps(_mm_add_epi32(v[0][0], v[1][0]));
        __m128 hi = _mm_castsi128_ps(_mm_add_epi32(v[0][1], v[1][1]));
        __m128i even = _mm_castps_si128(_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0)));
        __m128i odd = _mm_castps_si128(_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1)));
        __m128i m = _mm_srai_epi32(_mm_add_epi32(_mm_add_epi32(even, odd), bias), 2);
        m = _mm_packs_epi32(m, m);
        int32_t four = _mm_cvtsi128_si32(_mm_packus_epi16(m, m));
        memcpy(out[c], &four, 4);
    }
}
#endif

void
vv_image_rect_to_yuv420(const vv_image *img, int x0, int y0, int x1, int y1, uint8_t *yuv) {
    const int W = img->width, H = img->height;
    if (x0 < 0 || y0 < 0 || ((x0 | y0) & 1) || x1 > W || y1 > H || x1 <= x0 || y1 <= y0 ||
        ((x1 & 1) && x1 != W) || ((y1 & 1) && y1 != H))
        return;
    pthread_once(&ycc_once, ycc_init);
    const int32_t(*T)[256] = (const int32_t(*)[256])ycc_tab;
    const size_t pw = (size_t)(W + (W & 1)), ph = (size_t)(H + (H & 1)), cw = pw / 2;
    uint8_t *const py = yuv, *const pcb = yuv + pw * ph, *const pcr = pcb + cw * (ph / 2);
    const int xe = x1 + (x1 & 1); /* the padding column too, at an odd right edge */
    for (int y = y0; y < y1; y += 2) {
        const float *a0 = img->rgba + 4 * (size_t)W * (size_t)y;
        const float *a1 = img->rgba + 4 * (size_t)W * (size_t)(y + 1 < H ? y + 1 : y);
        uint8_t *l0 = py + pw * (size_t)y, *l1 = l0 + pw; /* an odd last row repeats */
        uint8_t *cb = pcb + cw * (size_t)(y / 2), *cr = pcr + cw * (size_t)(y / 2);
        int x = x0;
#ifdef __SSE2__
        for (; x + 8 <= x1; x += 8)
            ycc_sse2_8(a0, a1, x, l0, l1, cb, cr);
#endif
        for (; x < xe; x += 2) {
            const size_t i = 4 * (size_t)x, j = 4 * (size_t)(x + 1 < W ? x + 1 : x);
            const float *p[4] = {a0 + i, a0 + j, a1 + i, a1 + j};
            uint8_t *out[4] = {l0 + x, l0 + x + 1, l1 + x, l1 + x + 1};
            int32_t sb = 1 + ((x >> 1) & 1), sr = sb; /* the bias */
            for (int k = 0; k < 4; k++) {
                const int r = ycc_q8(p[k][0]), g = ycc_q8(p[k][1]), b = ycc_q8(p[k][2]);
                *out[k] = (uint8_t)((T[YCC_R_Y][r] + T[YCC_G_Y][g] + T[YCC_B_Y][b]) >> 16);
                sb += (T[YCC_R_CB][r] + T[YCC_G_CB][g] + T[YCC_B_CB][b]) >> 16;
                sr += (T[YCC_B_CB][r] + T[YCC_G_CR][g] + T[YCC_B_CR][b]) >> 16;
            }
            cb[x >> 1] = (uint8_t)(sb >> 2);
            cr[x >> 1] = (uint8_t)(sr >> 2);
        }
    }
}

double
vv_image_psnr(const vv_image *a, const vv_image *b) {
    if (a->width != b->width || a->height != b->height)
        return NAN;
    size_t n = (size_t)a->width * (size_t)a->height;
    double se = 0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            double d = (double)to8(a->rgba[4 * i + (size_t)c], 1.0) -
                       (double)to8(b->rgba[4 * i + (size_t)c], 1.0);
            se += d * d;
        }
    double mse = se / (3.0 * (double)n);
    return mse == 0 ? INFINITY : 10.0 * log10(255.0 * 255.0 / mse);
}
