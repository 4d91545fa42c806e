/*
 * TIFF stacks: files written here with libtiff (8/16/32-bit integers and
 * floats, strips and tiles, LZW/deflate/PackBits, RGB samples, BigTIFF,
 * OME-TIFF and ImageJ hyperstack descriptions, folders of pages), the CT
 * head as a 16-bit stack against its NRRD twin, and bad input (strips past
 * the end of a truncated file, a non-TIFF .tif, an empty folder).
 */
#include "testutil.h"

#include "io/io_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <tiffio.h>

static const char *
out_path(const char *name) {
    static char buf[8][1024];
    static int slot;
    slot = (slot + 1) % 8;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", vt_outdir("io_tiff"), name);
    return buf[slot];
}

/* Value of voxel (x, y, z) channel c of the synthetic stacks. */
static double
pattern(int x, int y, int z, int c, vv_voxel_type t) {
    double v = (double)(x + 3 * y + 50 * z + 1000 * c);
    if (t == VV_I8 || t == VV_I16 || t == VV_I32)
        v = -v;
    if (t == VV_F32 || t == VV_F64)
        v = v * 0.25 - 7.5;
    if (t == VV_U8)
        v = (double)((x + 3 * y + 50 * z + 7 * c) % 256);
    if (t == VV_I8)
        v = (double)((x + 3 * y + 50 * z + 7 * c) % 128) - 64;
    return v;
}

static void
put(void *row, int i, vv_voxel_type t, double v) {
    switch (t) {
    case VV_U8:
        ((uint8_t *)row)[i] = (uint8_t)v;
        break;
    case VV_I8:
        ((int8_t *)row)[i] = (int8_t)v;
        break;
    case VV_U16:
        ((uint16_t *)row)[i] = (uint16_t)v;
        break;
    case VV_I16:
        ((int16_t *)row)[i] = (int16_t)v;
        break;
    case VV_U32:
        ((uint32_t *)row)[i] = (uint32_t)v;
        break;
    case VV_I32:
        ((int32_t *)row)[i] = (int32_t)v;
        break;
    case VV_F32:
        ((float *)row)[i] = (float)v;
        break;
    case VV_F64:
        ((double *)row)[i] = v;
        break;
    }
}

typedef struct wopt {
    int w, h, pages, spp;
    vv_voxel_type type;
    uint16_t compression;
    int tile; /* 0: strips of rows_per_strip rows */
    int rows_per_strip;
    int bigtiff;
    const char *description; /* first page */
    float xres;              /* 0: none */
    /* channel and z of page p (hyperstacks); NULL: z = p, c = 0 */
    void (*page_cz)(int p, int *z, int *c);
} wopt;

static void
write_tiff(const char *path, const wopt *o) {
    TIFF *t = TIFFOpen(path, o->bigtiff ? "w8" : "w");
    assert_non_null(t);
    size_t vs = vv_voxel_type_size(o->type);
    int fmt = (o->type == VV_F32 || o->type == VV_F64)                       ? SAMPLEFORMAT_IEEEFP
              : (o->type == VV_I8 || o->type == VV_I16 || o->type == VV_I32) ? SAMPLEFORMAT_INT
                                                                             : SAMPLEFORMAT_UINT;
    for (int p = 0; p < o->pages; p++) {
        int z = p, c0 = 0;
        if (o->page_cz)
            o->page_cz(p, &z, &c0);
        TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)o->w);
        TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)o->h);
        TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)(8 * vs));
        TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)o->spp);
        TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, (uint16_t)fmt);
        TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
        TIFFSetField(t, TIFFTAG_PHOTOMETRIC,
                     o->spp == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
        TIFFSetField(t, TIFFTAG_COMPRESSION, o->compression);
        if (o->description && p == 0)
            TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, o->description);
        if (o->xres > 0) {
            TIFFSetField(t, TIFFTAG_XRESOLUTION, o->xres);
            TIFFSetField(t, TIFFTAG_YRESOLUTION, o->xres);
        }
        if (o->pages > 1) {
            TIFFSetField(t, TIFFTAG_SUBFILETYPE, FILETYPE_PAGE);
            TIFFSetField(t, TIFFTAG_PAGENUMBER, (uint16_t)p, (uint16_t)o->pages);
        }
        size_t px = (size_t)o->spp * vs;
        if (o->tile) {
            TIFFSetField(t, TIFFTAG_TILEWIDTH, (uint32_t)o->tile);
            TIFFSetField(t, TIFFTAG_TILELENGTH, (uint32_t)o->tile);
            unsigned char *buf = malloc((size_t)o->tile * o->tile * px);
            for (int ty = 0; ty < o->h; ty += o->tile)
                for (int tx = 0; tx < o->w; tx += o->tile) {
                    memset(buf, 0, (size_t)o->tile * o->tile * px);
                    for (int y = 0; y < o->tile; y++)
                        for (int x = 0; x < o->tile; x++)
                            for (int c = 0; c < o->spp; c++) {
                                int gx = tx + x, gy = ty + y;
                                if (gx < o->w && gy < o->h)
                                    put(buf, (y * o->tile + x) * o->spp + c, o->type,
                                        pattern(gx, gy, z, c + c0, o->type));
                            }
                    assert_true(TIFFWriteTile(t, buf, (uint32_t)tx, (uint32_t)ty, 0, 0) >= 0);
                }
            free(buf);
        } else {
            TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, (uint32_t)o->rows_per_strip);
            unsigned char *row = malloc((size_t)o->w * px);
            for (int y = 0; y < o->h; y++) {
                for (int x = 0; x < o->w; x++)
                    for (int c = 0; c < o->spp; c++)
                        put(row, x * o->spp + c, o->type, pattern(x, y, z, c + c0, o->type));
                assert_true(TIFFWriteScanline(t, row, (uint32_t)y, 0) >= 0);
            }
            free(row);
        }
        assert_true(TIFFWriteDirectory(t));
    }
    TIFFClose(t);
}

static void
check_pattern(const vv_volume *v, int w, int h, int nz, int c, vv_voxel_type t) {
    assert_int_equal(v->dims[0], w);
    assert_int_equal(v->dims[1], h);
    assert_int_equal(v->dims[2], nz);
    assert_int_equal(v->type, t);
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                double want = pattern(x, y, z, c, t);
                double got = vv_volume_get(v, x, y, z);
                if (got != want)
                    fail_msg("voxel (%d, %d, %d): %g, expected %g", x, y, z, got, want);
            }
}

static void
test_types_strips(void **state) {
    (void)state;
    static const vv_voxel_type types[] = {VV_U8,  VV_I8,  VV_U16, VV_I16,
                                          VV_U32, VV_I32, VV_F32, VV_F64};
    static const uint16_t comps[] = {COMPRESSION_NONE, COMPRESSION_LZW, COMPRESSION_ADOBE_DEFLATE,
                                     COMPRESSION_PACKBITS};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        for (size_t k = 0; k < sizeof comps / sizeof comps[0]; k++) {
            char name[64];
            snprintf(name, sizeof name, "strips_%s_%u.tif", vv_voxel_type_name(types[i]), comps[k]);
            wopt o = {.w = 17,
                      .h = 13,
                      .pages = 3,
                      .spp = 1,
                      .type = types[i],
                      .compression = comps[k],
                      .rows_per_strip = 4};
            write_tiff(out_path(name), &o);
            assert_int_equal(vv_format_detect(out_path(name)), VV_FORMAT_TIFF);
            vv_volume *v = NULL;
            vt_ok(vv_volume_load(&v, out_path(name), NULL));
            check_pattern(v, 17, 13, 3, 0, types[i]);
            assert_near(v->spacing[0], 1, 0);
            assert_int_equal(v->unit, VV_UNIT_UNKNOWN);
            vv_volume_free(v);
        }
}

static void
test_tiles(void **state) {
    (void)state;
    static const vv_voxel_type types[] = {VV_U8, VV_U16, VV_I32, VV_F32};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++) {
        char name[64];
        snprintf(name, sizeof name, "tiles_%s.tif", vv_voxel_type_name(types[i]));
        wopt o = {.w = 40,
                  .h = 36,
                  .pages = 5,
                  .spp = 1,
                  .type = types[i],
                  .compression = i % 2 ? COMPRESSION_LZW : COMPRESSION_ADOBE_DEFLATE,
                  .tile = 16};
        write_tiff(out_path(name), &o);
        vv_volume *v = NULL;
        vt_ok(vv_tiff_read(&v, out_path(name), -1));
        check_pattern(v, 40, 36, 5, 0, types[i]);
        vv_volume_free(v);
    }
}

static void
test_rgb_channel(void **state) {
    (void)state;
    wopt o = {.w = 9,
              .h = 7,
              .pages = 2,
              .spp = 3,
              .type = VV_U8,
              .compression = COMPRESSION_LZW,
              .rows_per_strip = 3};
    write_tiff(out_path("rgb.tif"), &o);
    for (int c = 0; c < 3; c++) {
        vv_volume *v = NULL;
        vt_ok(vv_tiff_read(&v, out_path("rgb.tif"), c));
        check_pattern(v, 9, 7, 2, c, VV_U8);
        vv_volume_free(v);
    }
    vv_volume *v = NULL;
    vt_err(vv_tiff_read(&v, out_path("rgb.tif"), 3));
    assert_non_null(strstr(vv_error_message(), "3 channels"));
    assert_null(v);
}

static void
test_bigtiff(void **state) {
    (void)state;
    wopt o = {.w = 21,
              .h = 11,
              .pages = 4,
              .spp = 1,
              .type = VV_U16,
              .compression = COMPRESSION_ADOBE_DEFLATE,
              .rows_per_strip = 5,
              .bigtiff = 1};
    const char *p = out_path("big.tif");
    write_tiff(p, &o);
    unsigned char h[4];
    FILE *f = fopen(p, "rb");
    assert_non_null(f);
    assert_int_equal(fread(h, 1, 4, f), 4);
    fclose(f);
    assert_int_equal(h[2], 43); /* BigTIFF's version 43 */
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, p, NULL));
    check_pattern(v, 21, 11, 4, 0, VV_U16);
    vv_volume_free(v);
}

/* OME: XYCZT with 2 channels, 4 slices: page = c + 2 z. */
static void
ome_page(int p, int *z, int *c) {
    *c = p % 2;
    *z = p / 2;
}

/* A 12 x 10 u16 OME-TIFF of 8 pages (2 channels, 4 slices: ome_page), LZW,
 * with @p desc as its ImageDescription. */
static void
write_ome_stack(const char *path, const char *desc) {
    wopt o = {.w = 12,
              .h = 10,
              .pages = 8,
              .spp = 1,
              .type = VV_U16,
              .compression = COMPRESSION_LZW,
              .rows_per_strip = 10,
              .description = desc,
              .page_cz = ome_page};
    write_tiff(path, &o);
}

static void
test_ome(void **state) {
    (void)state;
    const char *desc =
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>"
        "<OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\">"
        "<Image ID=\"Image:0\"><Pixels ID=\"Pixels:0\" DimensionOrder=\"XYCZT\" "
        "Type=\"uint16\" SizeX=\"12\" SizeY=\"10\" SizeZ=\"4\" SizeC=\"2\" SizeT=\"1\" "
        "PhysicalSizeX=\"0.5\" PhysicalSizeY=\"0.25\" PhysicalSizeZ=\"2.0\" "
        "PhysicalSizeXUnit=\"µm\"><TiffData/></Pixels></Image></OME>";
    const char *p = out_path("stack.ome.tif");
    write_ome_stack(p, desc);
    for (int c = 0; c < 2; c++) {
        vv_volume *v = NULL;
        vt_ok(vv_tiff_read(&v, p, c));
        check_pattern(v, 12, 10, 4, c, VV_U16);
        assert_near(v->spacing[0], 0.5, 1e-12);
        assert_near(v->spacing[1], 0.25, 1e-12);
        assert_near(v->spacing[2], 2.0, 1e-12);
        assert_int_equal(v->unit, VV_UNIT_MICRON);
        vv_volume_free(v);
    }
    vv_volume *v = NULL;
    vt_err(vv_tiff_read(&v, p, 2));
    assert_non_null(strstr(vv_error_message(), "2 channels"));
}

/* OME's units per axis: z in nm under x's default µm (the spacing in µm), and
 * x in nm (the volume in nm). */
static void
test_ome_units(void **state) {
    (void)state;
    static const char *const units[2] = {"PhysicalSizeZUnit=\"nm\"",
                                         "PhysicalSizeXUnit=\"nm\" PhysicalSizeYUnit=\"nm\" "
                                         "PhysicalSizeZUnit=\"µm\""};
    static const double want[2][3] = {{0.5, 0.25, 0.5}, {0.5, 0.25, 500}};
    for (int u = 0; u < 2; u++) {
        char desc[1024];
        snprintf(desc, sizeof desc,
                 "<?xml version=\"1.0\" encoding=\"UTF-8\"?>"
                 "<OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\">"
                 "<Image ID=\"Image:0\"><Pixels ID=\"Pixels:0\" DimensionOrder=\"XYCZT\" "
                 "Type=\"uint16\" SizeX=\"12\" SizeY=\"10\" SizeZ=\"4\" SizeC=\"2\" "
                 "SizeT=\"1\" PhysicalSizeX=\"0.5\" PhysicalSizeY=\"0.25\" "
                 "PhysicalSizeZ=\"%s\" %s><TiffData/></Pixels></Image></OME>",
                 u ? "0.5" : "500", units[u]);
        const char *p = out_path(u ? "units_nm.ome.tif" : "units_z_nm.ome.tif");
        write_ome_stack(p, desc);
        vv_volume *v = NULL;
        vt_ok(vv_tiff_read(&v, p, 0));
        for (int a = 0; a < 3; a++)
            assert_near(v->spacing[a], want[u][a], 1e-9 * want[u][a]);
        assert_int_equal(v->unit, u ? VV_UNIT_NM : VV_UNIT_MICRON);
        vv_volume_free(v);
    }
}

static void
test_imagej(void **state) {
    (void)state;
    const char *desc = "ImageJ=1.53t\nimages=6\nchannels=2\nslices=3\nhyperstack=true\n"
                       "mode=composite\nunit=micron\nspacing=3.5\nloop=false\n";
    wopt o = {.w = 8,
              .h = 6,
              .pages = 6,
              .spp = 1,
              .type = VV_F32,
              .compression = COMPRESSION_NONE,
              .rows_per_strip = 2,
              .description = desc,
              .xres = 4,
              .page_cz = ome_page};
    const char *p = out_path("hyper_ij.tif");
    write_tiff(p, &o);
    vv_load_options lo;
    vv_load_options_init(&lo);
    lo.channel = 1;
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, p, &lo));
    check_pattern(v, 8, 6, 3, 1, VV_F32);
    assert_near(v->spacing[0], 0.25, 1e-7);
    assert_near(v->spacing[1], 0.25, 1e-7);
    assert_near(v->spacing[2], 3.5, 1e-12);
    assert_int_equal(v->unit, VV_UNIT_MICRON);
    vv_volume_free(v);
}

static void
test_folder_natural_order(void **state) {
    (void)state;
    const char *dir = out_path("folder");
    mkdir(dir, 0755);
    for (int z = 0; z < 12; z++) {
        char name[1200];
        snprintf(name, sizeof name, "%s/img_%d.tif", dir, z + 1); /* img_10 after img_9 */
        wopt o = {.w = 6,
                  .h = 5,
                  .pages = 1,
                  .spp = 1,
                  .type = VV_I16,
                  .compression = COMPRESSION_PACKBITS,
                  .rows_per_strip = 5};
        /* page 0 of each file holds slice z: write the pattern of z */
        TIFF *t = TIFFOpen(name, "w");
        assert_non_null(t);
        TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)o.w);
        TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)o.h);
        TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 16);
        TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_INT);
        TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
        TIFFSetField(t, TIFFTAG_COMPRESSION, o.compression);
        TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, 5);
        int16_t row[6];
        for (int y = 0; y < o.h; y++) {
            for (int x = 0; x < o.w; x++)
                row[x] = (int16_t)pattern(x, y, z, 0, VV_I16);
            assert_true(TIFFWriteScanline(t, row, (uint32_t)y, 0) >= 0);
        }
        TIFFClose(t);
    }
    vt_write_file(vt_path(dir, "notes.txt"), "not a page\n", 11);
    assert_int_equal(vv_format_detect(dir), VV_FORMAT_TIFF);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, dir, NULL));
    check_pattern(v, 6, 5, 12, 0, VV_I16);
    vv_volume_free(v);
}

/* The CT head as a 16-bit multi-page stack equals its NRRD twin. */
static void
test_nrrd_twin(void **state) {
    (void)state;
    const char *src = vt_data("volumes/ct_head.nrrd");
    if (access(src, R_OK) != 0)
        vt_skip("%s is missing", src);
    vv_volume *n = NULL;
    vt_ok(vv_volume_load(&n, src, NULL));
    assert_int_equal(n->type, VV_I16);
    const char *p = out_path("ct_head16.tif");
    TIFF *t = TIFFOpen(p, "w");
    assert_non_null(t);
    size_t slice = (size_t)n->dims[0] * n->dims[1];
    for (int z = 0; z < n->dims[2]; z++) {
        TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)n->dims[0]);
        TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)n->dims[1]);
        TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 16);
        TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_INT);
        TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
        TIFFSetField(t, TIFFTAG_COMPRESSION, z % 2 ? COMPRESSION_LZW : COMPRESSION_NONE);
        TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, 16);
        for (uint32_t y = 0; y < (uint32_t)n->dims[1]; y++)
            assert_true(
                TIFFWriteScanline(t, (int16_t *)n->data + z * slice + y * n->dims[0], y, 0) >= 0);
        assert_true(TIFFWriteDirectory(t));
    }
    TIFFClose(t);
    vv_volume *v = NULL;
    vt_ok(vv_volume_load(&v, p, NULL));
    assert_int_equal(v->type, VV_I16);
    for (int i = 0; i < 3; i++)
        assert_int_equal(v->dims[i], n->dims[i]);
    assert_memory_equal(v->data, n->data, slice * n->dims[2] * 2);
    assert_near(v->range[0], n->range[0], 0);
    assert_near(v->range[1], n->range[1], 0);
    vv_volume_free(v);
    vv_volume_free(n);
}

static void
assert_one_line_naming(const char *name) {
    const char *m = vv_error_message();
    assert_non_null(m);
    if (!strstr(m, name))
        fail_msg("error does not name %s: %s", name, m);
    if (strchr(m, '\n'))
        fail_msg("error is not one line: %s", m);
}

static void
test_strips_past_end(void **state) {
    (void)state;
    const char *p = out_path("truncated.tif");
    wopt o = {.w = 64,
              .h = 64,
              .pages = 1,
              .spp = 1,
              .type = VV_U16,
              .compression = COMPRESSION_NONE,
              .rows_per_strip = 8};
    write_tiff(p, &o);
    /* point strip 3's offset past the end of the file */
    size_t n;
    unsigned char *d = vt_read_file(p, &n);
    TIFF *t = TIFFOpen(p, "r");
    assert_non_null(t);
    uint64_t *offsets = NULL;
    assert_true(TIFFGetField(t, TIFFTAG_STRIPOFFSETS, &offsets));
    uint64_t off3 = offsets[3];
    TIFFClose(t);
    /* find the 32-bit value off3 in the StripOffsets array and push it past the end */
    int patched = 0;
    for (size_t i = 0; i + 4 <= n && !patched; i += 2) {
        uint32_t x;
        memcpy(&x, d + i, 4);
        if (x == (uint32_t)off3 && i > off3) {
            uint32_t far = (uint32_t)n + 100000;
            memcpy(d + i, &far, 4);
            patched = 1;
        }
    }
    assert_true(patched);
    vt_write_file(p, d, n);
    free(d);
    vv_volume *v = NULL;
    vt_err(vv_volume_load(&v, p, NULL));
    assert_null(v);
    assert_one_line_naming("truncated.tif");
    assert_non_null(strstr(vv_error_message(), "strip 3"));

    /* a file cut in half (its directory, written last by libtiff, is gone) */
    write_tiff(p, &o);
    d = vt_read_file(p, &n);
    vt_write_file(p, d, n / 2);
    free(d);
    vt_err(vv_volume_load(&v, p, NULL));
    assert_null(v);
    assert_one_line_naming("truncated.tif");
}

static void
test_bad_input(void **state) {
    (void)state;
    vv_volume *v = NULL;
    const char *p = out_path("not_really.tif");
    vt_write_file(p, "II*\0garbage garbage garbage", 27);
    vt_err(vv_volume_load(&v, p, NULL));
    assert_null(v);
    assert_one_line_naming("not_really.tif");

    const char *dir = out_path("empty_folder");
    mkdir(dir, 0755);
    vt_write_file(vt_path(dir, "readme.txt"), "x", 1);
    vt_err(vv_volume_load(&v, dir, NULL));
    assert_null(v);
    assert_one_line_naming("empty_folder");
    vt_err(vv_tiff_read(&v, dir, -1));
    assert_one_line_naming("empty_folder");

    /* pages of different sizes in one folder */
    const char *mixed = out_path("mixed_folder");
    mkdir(mixed, 0755);
    wopt a = {.w = 8,
              .h = 8,
              .pages = 1,
              .spp = 1,
              .type = VV_U8,
              .compression = COMPRESSION_NONE,
              .rows_per_strip = 8};
    write_tiff(vt_path(mixed, "a1.tif"), &a);
    a.w = 9;
    write_tiff(vt_path(mixed, "a2.tif"), &a);
    vt_err(vv_volume_load(&v, mixed, NULL));
    assert_null(v);
    assert_one_line_naming("a2.tif");
}

/* @p b holds the voxels of @p whole from @p lo on. */
static void
assert_box_of(const vv_volume *b, const vv_volume *whole, const int lo[3]) {
    for (int z = 0; z < b->dims[2]; z++)
        for (int y = 0; y < b->dims[1]; y++)
            for (int x = 0; x < b->dims[0]; x++)
                if (vv_volume_get(b, x, y, z) !=
                    vv_volume_get(whole, x + lo[0], y + lo[1], z + lo[2]))
                    fail_msg("voxel (%d, %d, %d) of the box from (%d, %d, %d)", x, y, z, lo[0],
                             lo[1], lo[2]);
}

/* A range of slices (vv_load_options.z_first, z_count): only those pages,
 * the origin of the first, the stack's count in n_slices; in this process
 * and through the reader sandbox. vv_slabs cuts boxes from the slabs it
 * reads, each slab once when the boxes come slab by slab. A range past the
 * stack, and a range asked of a format read whole, are refused. */
static void
test_slice_range(void **state) {
    (void)state;
    const char *desc = "ImageJ=1.53t\nimages=9\nslices=9\nunit=micron\nspacing=2.5\n";
    wopt o = {.w = 11,
              .h = 7,
              .pages = 9,
              .spp = 1,
              .type = VV_U16,
              .compression = COMPRESSION_ADOBE_DEFLATE,
              .rows_per_strip = 3,
              .description = desc};
    const char *p = out_path("slices.tif");
    write_tiff(p, &o);
    vv_volume *whole = NULL;
    vt_ok(vv_volume_load(&whole, p, NULL));
    for (int sandbox = 0; sandbox < 2; sandbox++) {
        if (sandbox)
            unsetenv("VOLVIS_SANDBOX");
        else
            setenv("VOLVIS_SANDBOX", "0", 1);
        vv_load_info info;
        vv_load_options lo;
        vv_load_options_init(&lo);
        lo.z_first = 3;
        lo.z_count = 4;
        lo.info = &info;
        vv_volume *v = NULL;
        vt_ok(vv_volume_load(&v, p, &lo));
        assert_int_equal(v->dims[2], 4);
        assert_int_equal(info.n_slices, 9);
        assert_near(v->origin[2], whole->origin[2] + 3 * 2.5, 1e-12);
        const int from[3] = {0, 0, 3};
        assert_box_of(v, whole, from);
        vv_volume_free(v);
        lo.z_first = 6; /* 6 .. 9: one past the stack */
        vt_err(vv_volume_load(&v, p, &lo));
        assert_null(v);
        assert_non_null(strstr(vv_error_message(), "the stack has 9"));
    }
    unsetenv("VOLVIS_SANDBOX");
    /* boxes of slabs: each slab read once when asked slab by slab */
    vv_slabs *sl = NULL;
    vt_ok(vv_slabs_open(&sl, p, NULL));
    assert_int_equal(vv_slabs_header(sl)->dims[2], 9);
    const int slab_z[3][2] = {{0, 3}, {4, 7}, {8, 8}};
    for (int k = 0; k < 3; k++)
        for (int y0 = 0; y0 < 7; y0 += 4) {
            const int lo[3] = {2, y0, slab_z[k][0]};
            const int hi[3] = {9, y0 + 3 < 6 ? y0 + 3 : 6, slab_z[k][1]};
            vv_volume *b = NULL;
            vt_ok(vv_slabs_read_box(sl, lo, hi, &b));
            assert_box_of(b, whole, lo);
            assert_near(b->origin[2], whole->origin[2] + lo[2] * whole->spacing[2], 1e-12);
            vv_volume_free(b);
        }
    assert_int_equal((int)vv_slabs_loads(sl), 3);
    const int lo[3] = {0, 0, 5}, hi[3] = {10, 7, 5}; /* y past the volume */
    vv_volume *b = NULL;
    vt_err(vv_slabs_read_box(sl, lo, hi, &b));
    assert_null(b);
    vv_slabs_free(sl);
    vv_volume_free(whole);
    /* a format read whole refuses a range, naming the file */
    vv_volume *head = NULL;
    vt_ok(vv_volume_load(&head, "../shared/data/volumes/neghip.slc", NULL));
    const char *nrrd = out_path("whole.nii");
    vt_ok(vv_volume_save(head, nrrd, VV_FORMAT_NIFTI, 0));
    vv_volume_free(head);
    vv_load_options lo2;
    vv_load_options_init(&lo2);
    lo2.z_first = 1;
    lo2.z_count = 2;
    vt_err(vv_volume_load(&head, nrrd, &lo2));
    assert_null(head);
    assert_non_null(strstr(vv_error_message(), "whole.nii"));
    assert_non_null(strstr(vv_error_message(), "TIFF stacks are"));
    vt_err(vv_slabs_open(&sl, nrrd, NULL));
    assert_null(sl);
}

/* vv_slabs on a gzip NRRD: the stream inflated forward, and from its start
 * again when a box goes back; the same voxels as the whole volume. */
static void
test_slabs_gzip_nrrd(void **state) {
    (void)state;
    vv_volume *whole = NULL;
    vt_ok(vv_volume_load(&whole, "../shared/data/volumes/neghip.slc", NULL));
    const char *p = out_path("neghip_gzip.nrrd");
    vt_ok(vv_volume_save(whole, p, VV_FORMAT_NRRD, 0)); /* gzip by default */
    vv_slabs *sl = NULL;
    vt_ok(vv_slabs_open(&sl, p, NULL));
    const vv_volume *h = vv_slabs_header(sl);
    for (int a = 0; a < 3; a++)
        assert_int_equal(h->dims[a], whole->dims[a]);
    const int z0s[4] = {0, 40, 10, 50}; /* forward, back (a rewind), forward */
    for (int k = 0; k < 4; k++) {
        const int lo[3] = {3, 5, z0s[k]}, hi[3] = {60, 40, z0s[k] + 9};
        vv_volume *b = NULL;
        vt_ok(vv_slabs_read_box(sl, lo, hi, &b));
        assert_box_of(b, whole, lo);
        vv_volume_free(b);
    }
    assert_int_equal((int)vv_slabs_loads(sl), 4);
    vv_slabs_free(sl);
    vv_volume_free(whole);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_types_strips),
        cmocka_unit_test(test_tiles),
        cmocka_unit_test(test_rgb_channel),
        cmocka_unit_test(test_bigtiff),
        cmocka_unit_test(test_ome),
        cmocka_unit_test(test_imagej),
        cmocka_unit_test(test_ome_units),
        cmocka_unit_test(test_folder_natural_order),
        cmocka_unit_test(test_nrrd_twin),
        cmocka_unit_test(test_strips_past_end),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_slice_range),
        cmocka_unit_test(test_slabs_gzip_nrrd),
    };
    return vt_run_tests(tests, NULL, NULL);
}
