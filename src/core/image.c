/* RGBA float + depth images (see volvis/image.h). */
#include <math.h>
#include <stdlib.h>

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
