/* PNG output and input through libpng; PNG files as texture images. */
#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/image.h"
#include "volvis/io.h"
#include "volvis/model.h"

/* Largest image vv_image_read_png accepts (2^26 pixels: 1 GiB as float RGBA). */
#define VV_PNG_READ_MAX_PIXELS (((uint64_t)1) << 26)

typedef struct png_err {
    char msg[256];
} png_err;

static void
on_png_error(png_structp png, png_const_charp msg) {
    png_err *e = png_get_error_ptr(png);
    if (e)
        snprintf(e->msg, sizeof e->msg, "%s", msg);
    png_longjmp(png, 1);
}

static void
on_png_warning(png_structp png, png_const_charp msg) {
    (void)png;
    (void)msg;
}

vv_status
vv_image_write_png(const vv_image *img, const char *path, double gamma, int with_alpha) {
    int ch = with_alpha ? 4 : 3;
    size_t stride = (size_t)img->width * (size_t)ch;
    uint8_t *pix = malloc(stride * (size_t)img->height);
    png_bytep *rows = malloc(sizeof *rows * (size_t)img->height);
    if (!pix || !rows) {
        free(pix);
        free(rows);
        return vv_error_set(VV_ERR_NOMEM, "png: %s: out of memory", path);
    }
    vv_image_to_8bit(img, ch, gamma, pix);
    for (int y = 0; y < img->height; y++)
        rows[y] = pix + (size_t)y * stride;

    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, path);
    if (s != VV_OK) {
        free(pix);
        free(rows);
        return vv_error_prefix(s, "png");
    }
    png_err err = {{0}};
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, &err, on_png_error, on_png_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        vv_atomic_file_abort(&af);
        free(pix);
        free(rows);
        return vv_error_set(VV_ERR_NOMEM, "png: %s: cannot create writer", path);
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        vv_atomic_file_abort(&af);
        free(pix);
        free(rows);
        return vv_error_set(VV_ERR_IO, "png: %s: %s", path, err.msg);
    }
    png_init_io(png, af.fp);
    png_set_IHDR(png, info, (png_uint_32)img->width, (png_uint_32)img->height, 8,
                 with_alpha ? PNG_COLOR_TYPE_RGBA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 6);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(pix);
    free(rows);
    s = vv_atomic_file_commit(&af);
    return s == VV_OK ? VV_OK : vv_error_prefix(s, "png");
}

vv_status
vv_image_read_png(vv_image **out, const char *path) {
    *out = NULL;
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return vv_error_set(VV_ERR_IO, "png: %s: %s", path, strerror(errno));
    unsigned char sig[8];
    if (fread(sig, 1, 8, fp) != 8 || png_sig_cmp(sig, 0, 8)) {
        fclose(fp);
        return vv_error_set(VV_ERR_FORMAT, "png: %s: not a PNG file", path);
    }
    png_err err = {{0}};
    png_structp png =
        png_create_read_struct(PNG_LIBPNG_VER_STRING, &err, on_png_error, on_png_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(fp);
        return vv_error_set(VV_ERR_NOMEM, "png: %s: cannot create reader", path);
    }
    /* volatile: modified between setjmp and a possible longjmp */
    uint16_t *volatile pix = NULL;
    png_bytep *volatile rows = NULL;
    vv_image *volatile img = NULL;
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(fp);
        free(pix);
        free(rows);
        vv_image_free(img);
        return vv_error_set(VV_ERR_FORMAT, "png: %s: %s", path, err.msg);
    }
    /* sizes are checked below with our own limits and error code */
    png_set_user_limits(png, 0x7fffffff, 0x7fffffff);
    png_init_io(png, fp);
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    if (w > VV_IMAGE_MAX_SIDE || h > VV_IMAGE_MAX_SIDE ||
        (uint64_t)w * h > VV_PNG_READ_MAX_PIXELS) {
        /* checked before anything the size of the image is allocated */
        png_destroy_read_struct(&png, &info, NULL);
        fclose(fp);
        return vv_error_set(VV_ERR_LIMIT, "png: %s: %u x %u pixels is over the limit of %llu", path,
                            (unsigned)w, (unsigned)h, (unsigned long long)VV_PNG_READ_MAX_PIXELS);
    }
    int depth = png_get_bit_depth(png, info);
    png_set_expand(png);
    png_set_gray_to_rgb(png);
    png_set_add_alpha(png, depth == 16 ? 0xFFFF : 0xFF, PNG_FILLER_AFTER);
    if (depth < 8)
        png_set_packing(png);
    if (depth == 16 && vv_host_is_little_endian())
        png_set_swap(png);
    png_read_update_info(png, info);
    int bytes = png_get_bit_depth(png, info) == 16 ? 2 : 1;
    vv_image *im = NULL;
    if (vv_image_new(&im, (int)w, (int)h) != VV_OK)
        png_error(png, "image too large");
    img = im;
    size_t stride = (size_t)w * 4 * (size_t)bytes;
    pix = malloc(stride * h);
    rows = malloc(sizeof(png_bytep) * h);
    if (!pix || !rows)
        png_error(png, "out of memory");
    for (png_uint_32 y = 0; y < h; y++)
        rows[y] = (png_bytep)pix + y * stride;
    png_read_image(png, rows);
    png_read_end(png, NULL);
    double mx = bytes == 2 ? 65535.0 : 255.0;
    for (size_t i = 0; i < (size_t)w * h * 4; i++) {
        double v = bytes == 2 ? ((uint16_t *)pix)[i] : ((uint8_t *)pix)[i];
        im->rgba[i] = (float)(v / mx);
    }
    png_destroy_read_struct(&png, &info, NULL);
    fclose(fp);
    free(pix);
    free(rows);
    *out = im;
    return VV_OK;
}

vv_status
vv_texture_image_load(vv_texture_image **out, const char *path, const char *source) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "texture: NULL %s", out ? "path" : "output");
    *out = NULL;
    vv_image *img = NULL;
    vv_status st = vv_image_read_png(&img, path);
    if (st != VV_OK)
        return vv_error_prefix(st, "texture");
    return vv_texture_image_new(out, img, source ? source : path);
}
