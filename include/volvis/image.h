/*
 * VolVis image: RGBA float plus depth, the output of every renderer.
 *
 * Layout: width x height pixels, row 0 at the TOP, x fastest.
 * rgba[4 * (y * width + x) + c], c = R, G, B, A. Colour is display-referred
 * (the values a renderer computes are the values shown, as in VTK and the
 * classical volume renderers), already composited over the background; A is
 * the accumulated opacity (coverage) of the scene in that pixel.
 * depth[y * width + x] is the world distance from the eye along the ray to
 * the first visible surface or sample, or INFINITY where nothing was hit.
 *
 * Gamma: 8-bit conversion is round(255 * clamp(v, 0, 1)^(1/gamma)); gamma 1
 * (the default everywhere) writes the values unchanged. Use one gamma for
 * every image you compare.
 *
 * Ownership: vv_image_new allocates, vv_image_free releases (accepts NULL).
 * Thread-safety: distinct pixels may be written from distinct threads.
 */
#ifndef VOLVIS_IMAGE_H
#define VOLVIS_IMAGE_H

#include <stdint.h>

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest accepted image side. */
#define VV_IMAGE_MAX_SIDE 32768

typedef struct vv_image {
    int width;
    int height;
    float *rgba;  /**< 4 * width * height floats, owned */
    float *depth; /**< width * height floats, owned */
} vv_image;

/**
 * Allocates an image cleared to transparent black with infinite depth.
 * Errors: VV_ERR_INVALID (side < 1 or > VV_IMAGE_MAX_SIDE), VV_ERR_NOMEM.
 */
vv_status vv_image_new(vv_image **out, int width, int height);

/** Releases an image and its buffers. Accepts NULL. */
void vv_image_free(vv_image *img);

/** Sets every pixel to (r, g, b, a) and depth to INFINITY. */
void vv_image_clear(vv_image *img, float r, float g, float b, float a);

/**
 * Rows @p y0 <= y < @p y1, columns @p x0 <= x < @p x1 of @p img as 8-bit
 * RGBX in @p out (4 * img->width bytes a row, the whole image's layout):
 * each component (uint8)(clamp(v * 255 + 0.5, 0, 255)), gamma 1, alpha in
 * X. The conversion of vv_pixels8 (render.h). Thread-safe for disjoint
 * rectangles; does no allocation.
 */
void vv_image_rect_to_rgbx8(const vv_image *img, int x0, int y0, int x1, int y1, uint8_t *out);

/**
 * Rows @p y0 <= y < @p y1, columns @p x0 <= x < @p x1 of @p img as JPEG's
 * YUV 4:2:0 planes (vv_pixels8's VV_PIXELS8_YUV420 layout, the whole
 * image's): @p yuv holds Y (pw x ph bytes, pw and ph the image's sides
 * rounded up to even), then Cb and Cr (pw/2 x ph/2 each). Each component
 * is first made 8-bit as vv_image_rect_to_rgbx8 does, then transformed
 * and subsampled as libjpeg(-turbo)'s compressor does (JFIF full-range
 * BT.601 in 16-bit fixed point, 2 x 2 chroma averages with bias 1, 2, 1,
 * 2, ... along a row; the odd last column or row repeated into the
 * padding). @p x0 and @p y0 must be even, @p x1 and @p y1 even or the
 * image's sides (where the padding is written too); other rectangles are
 * ignored. Thread-safe for disjoint rectangles; does no allocation.
 */
void vv_image_rect_to_yuv420(const vv_image *img, int x0, int y0, int x1, int y1, uint8_t *yuv);

/**
 * Converts to 8-bit, @p channels per pixel (3: RGB, 4: RGBA), rows top to
 * bottom, into @p out (width * height * channels bytes, caller-owned).
 * gamma <= 0 is taken as 1.
 */
void vv_image_to_8bit(const vv_image *img, int channels, double gamma, uint8_t *out);

/**
 * Writes the image as an 8-bit PNG (RGB, or RGBA when @p with_alpha) through
 * libpng, atomically: a temporary file beside @p path is renamed over it
 * only when complete. Errors: VV_ERR_IO with the path and the reason.
 */
vv_status vv_image_write_png(const vv_image *img, const char *path, double gamma, int with_alpha);

/**
 * Reads an 8-bit or 16-bit PNG (grey, grey+alpha, RGB, RGBA, palette) into a
 * new image; colour values are v/maxval (no gamma change), A = 1 when the file
 * has none. Errors: VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_LIMIT (a side over
 * VV_IMAGE_MAX_SIDE or more than 2^26 pixels, checked from the header before
 * allocating).
 */
vv_status vv_image_read_png(vv_image **out, const char *path);

/**
 * Peak signal-to-noise ratio in dB between the 8-bit RGB conversions (gamma
 * 1) of two images of equal size, peak 255: 10 log10(255^2 / MSE). Returns
 * INFINITY for identical images, NAN when the sizes differ.
 */
double vv_image_psnr(const vv_image *a, const vv_image *b);

#ifdef __cplusplus
}
#endif
#endif
