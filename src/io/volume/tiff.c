/*
 * TIFF stacks through libtiff: a multi-page TIFF (classic or BigTIFF) or a
 * folder of TIFF files, each page one slice.
 *
 * Pages: every page (IFD) of a file, files of a folder in natural order
 * ("z2.tif" before "z10.tif"). All pages must have the size, bits per sample,
 * sample format and samples per pixel of the first; strips and tiles, chunky
 * and planar samples and every compression libtiff decodes are read through
 * TIFFReadEncodedStrip/Tile, which check each strip against the file size.
 *
 * Metadata (only from the first file's first page, ImageDescription):
 * - OME-TIFF: the first <Pixels> element's SizeX/Y/Z/C/T, DimensionOrder and
 *   PhysicalSizeX/Y/Z (+Unit, default micrometres); the origin from the first
 *   <Plane>'s PositionX/Y/Z when in the same unit. Page of (z, c, t) from
 *   DimensionOrder.
 * - ImageJ: "images=", "channels=", "slices=", "frames=", "spacing=",
 *   "unit=", "xorigin=" (in voxels) lines; the in-plane pixel size is
 *   1/XResolution (ImageJ stores it there). Page order is ImageJ's XYCZT.
 *   A channel's colour from its lookup table in the IJMetadata tag
 *   (imagej_lut).
 * - Neither: each page is a slice, spacing 1, unit unknown.
 * The volume is channel @p channel at the first time point.
 *
 * Writing (vv_tiff_write) is tiff_write.c's; the format record here names
 * both.
 *
 * libtiff reports errors through handlers; the per-file handlers of
 * TIFFOpenExt (libtiff >= 4.5; tiff_msg.c) keep its first message for our
 * trace, so nothing is printed and nothing global is touched.
 */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <tiffio.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/prescan.h"
#include "io/volume/tiff_msg.h"
#include "io/volume/tiff_stack.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

TIFF *
tiff_open_file(const char *path, tiff_msg *msg) {
    msg->text[0] = '\0';
    TIFFOpenOptions *o = TIFFOpenOptionsAlloc();
    if (!o)
        return NULL;
    TIFFOpenOptionsSetErrorHandlerExtR(o, tiff_on_error, msg);
    TIFFOpenOptionsSetWarningHandlerExtR(o, tiff_on_warning, msg);
    /* no single allocation inside libtiff beyond our own volume limit */
    TIFFOpenOptionsSetMaxSingleMemAlloc(o, (tmsize_t)1 << 31);
    /* "m": read, not mapped: a mapped file counts whole in the resident set
     * of a reader that reads a few tiles of it */
    TIFF *t = TIFFOpenExt(path, "rm", o);
    TIFFOpenOptionsFree(o);
    return t;
}

/* ---- natural order of file names ---------------------------------------- */

static int
natural_cmp(const char *a, const char *b) {
    while (*a && *b) {
        if (isdigit((unsigned char)*a) && isdigit((unsigned char)*b)) {
            while (*a == '0')
                a++;
            while (*b == '0')
                b++;
            size_t la = 0, lb = 0;
            while (isdigit((unsigned char)a[la]))
                la++;
            while (isdigit((unsigned char)b[lb]))
                lb++;
            if (la != lb)
                return la < lb ? -1 : 1;
            int c = strncmp(a, b, la);
            if (c)
                return c;
            a += la;
            b += lb;
            continue;
        }
        if (*a != *b)
            return (unsigned char)*a < (unsigned char)*b ? -1 : 1;
        a++;
        b++;
    }
    return *a ? 1 : *b ? -1 : 0;
}

static int
cmp_names(const void *x, const void *y) {
    return natural_cmp(*(const char *const *)x, *(const char *const *)y);
}

static int
is_tiff_name(const char *name) {
    const char *dot = strrchr(name, '.');
    return name[0] != '.' && dot && (!strcasecmp(dot, ".tif") || !strcasecmp(dot, ".tiff"));
}

static void
free_list(char **v, int n) {
    for (int i = 0; i < n; i++)
        free(v[i]);
    free(v);
}

/* The .tif/.tiff files of folder @p dir in natural order (full paths). */
static vv_status
list_folder(const char *dir, char ***out, int *n_out) {
    *out = NULL;
    *n_out = 0;
    DIR *d = opendir(dir);
    if (!d)
        return vv_error_set(VV_ERR_IO, "cannot open the folder: %s", strerror(errno));
    char **names = NULL;
    int n = 0, cap = 0;
    struct dirent *e;
    vv_status s = VV_OK;
    while ((e = readdir(d))) {
        if (!is_tiff_name(e->d_name))
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 64;
            char **nn = realloc(names, (size_t)cap * sizeof *nn);
            if (!nn) {
                s = vv_error_set(VV_ERR_NOMEM, "out of memory listing the folder");
                break;
            }
            names = nn;
        }
        names[n] = strdup(e->d_name);
        if (!names[n]) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory listing the folder");
            break;
        }
        n++;
    }
    closedir(d);
    if (s != VV_OK) {
        free_list(names, n);
        return s;
    }
    if (n == 0) {
        free(names);
        return vv_error_set(VV_ERR_FORMAT, "no .tif or .tiff files in the folder");
    }
    qsort(names, (size_t)n, sizeof *names, cmp_names);
    for (int i = 0; i < n; i++) {
        size_t len = strlen(dir) + strlen(names[i]) + 2;
        char *p = malloc(len);
        if (!p) {
            free_list(names, n);
            return vv_error_set(VV_ERR_NOMEM, "out of memory listing the folder");
        }
        snprintf(p, len, "%s/%s", dir, names[i]);
        free(names[i]);
        names[i] = p;
    }
    *out = names;
    *n_out = n;
    return VV_OK;
}

/* ---- metadata in ImageDescription ---------------------------------------- */

typedef struct stack_meta {
    int size_z, size_c, size_t_; /* 0: unknown */
    char order[8];               /* OME DimensionOrder, "XYCZT" for ImageJ */
    double spacing[3];           /* 0: unknown */
    vv_unit unit;
    int is_ome, is_imagej;
    double origin[3]; /* world position of voxel (0, 0, 0), in unit */
    int has_origin[3];
    double ij_origin[3]; /* ImageJ's origin, in voxels (world = -value * spacing) */
    int has_ij_origin[3];
    double time_step;   /* seconds between time points (OME TimeIncrement), 0: unknown */
    const char *pixels; /* OME: the Pixels element in the description while it is held */
} stack_meta;

/* Value of attribute @p name inside the tag starting at @p tag (up to '>'). */
static int
xml_attr(const char *tag, const char *name, char *val, size_t cap) {
    const char *end = strchr(tag, '>');
    size_t nl = strlen(name);
    for (const char *p = tag; p && (!end || p < end); p++) {
        p = strstr(p, name);
        if (!p || (end && p >= end))
            return 0;
        if ((p == tag || isspace((unsigned char)p[-1])) && p[nl] == '=' &&
            (p[nl + 1] == '"' || p[nl + 1] == '\'')) {
            char q = p[nl + 1];
            const char *v = p + nl + 2, *ve = strchr(v, q);
            if (!ve)
                return 0;
            size_t len = (size_t)(ve - v) < cap - 1 ? (size_t)(ve - v) : cap - 1;
            memcpy(val, v, len);
            val[len] = '\0';
            return 1;
        }
    }
    return 0;
}

static vv_unit
ome_unit(const char *u) {
    if (!strcmp(u, "µm") || !strcmp(u, "um") || !strcmp(u, "micron"))
        return VV_UNIT_MICRON;
    if (!strcmp(u, "mm"))
        return VV_UNIT_MM;
    if (!strcmp(u, "m"))
        return VV_UNIT_METER;
    if (!strcmp(u, "in"))
        return VV_UNIT_INCH;
    if (!strcmp(u, "ft"))
        return VV_UNIT_FOOT;
    if (!strcmp(u, "nm"))
        return VV_UNIT_NM;
    return VV_UNIT_UNKNOWN;
}

/* Metres in one @p u; 0 when unknown. */
static double
unit_metres(vv_unit u) {
    static const double m[] = {1, 1e-3, 1e-6, 0.3048, 0.0254, 0, 1e-9};
    return (unsigned)u <= VV_UNIT_LAST ? m[u] : 0;
}

static void
parse_ome(const char *desc, stack_meta *m) {
    const char *px = strstr(desc, "<Pixels ");
    if (!px)
        px = strstr(desc, ":Pixels ");
    if (!px)
        return;
    m->is_ome = 1;
    m->unit = VV_UNIT_MICRON; /* OME's default */
    char v[64];
    static const char *const sizes[3] = {"SizeZ", "SizeC", "SizeT"};
    int *dst[3] = {&m->size_z, &m->size_c, &m->size_t_};
    for (int i = 0; i < 3; i++)
        if (xml_attr(px, sizes[i], v, sizeof v))
            *dst[i] = atoi(v);
    if (xml_attr(px, "DimensionOrder", v, sizeof v) && strlen(v) == 5)
        memcpy(m->order, v, 6);
    m->pixels = px;
    if (xml_attr(px, "TimeIncrement", v, sizeof v)) {
        double d = strtod(v, NULL), scale = 1;
        char u[16];
        if (xml_attr(px, "TimeIncrementUnit", u, sizeof u))
            scale = !strcmp(u, "ms") ? 1e-3 : !strcmp(u, "min") ? 60 : !strcmp(u, "h") ? 3600 : 1;
        if (d > 0 && isfinite(d * scale))
            m->time_step = d * scale;
    }
    static const char *const phys[3] = {"PhysicalSizeX", "PhysicalSizeY", "PhysicalSizeZ"};
    static const char *const units[3] = {"PhysicalSizeXUnit", "PhysicalSizeYUnit",
                                         "PhysicalSizeZUnit"};
    if (xml_attr(px, units[0], v, sizeof v))
        m->unit = ome_unit(v);
    for (int i = 0; i < 3; i++) {
        if (!xml_attr(px, phys[i], v, sizeof v))
            continue;
        double d = strtod(v, NULL);
        /* an axis in another unit than x's (z in nm, x in the default µm):
         * its spacing in x's unit */
        char u[16];
        const double to = unit_metres(m->unit), from = i > 0 && xml_attr(px, units[i], u, sizeof u)
                                                           ? unit_metres(ome_unit(u))
                                                           : to;
        if (to > 0 && from > 0)
            d *= from / to;
        if (d > 0 && isfinite(d))
            m->spacing[i] = d;
    }
    /* the origin: the first Plane's position, when given in the pixels' unit */
    const char *pl = strstr(px, "<Plane ");
    if (!pl)
        pl = strstr(px, ":Plane ");
    static const char *const pos[3] = {"PositionX", "PositionY", "PositionZ"};
    static const char *const pos_units[3] = {"PositionXUnit", "PositionYUnit", "PositionZUnit"};
    for (int i = 0; pl && i < 3; i++) {
        char u[32];
        if (xml_attr(pl, pos[i], v, sizeof v) && xml_attr(pl, pos_units[i], u, sizeof u) &&
            ome_unit(u) == m->unit && m->unit != VV_UNIT_UNKNOWN) {
            double d = strtod(v, NULL);
            if (isfinite(d)) {
                m->origin[i] = d;
                m->has_origin[i] = 1;
            }
        }
    }
}

/*
 * The name and colour of OME channel @p c: the c-th Channel element inside
 * the Pixels element (Name; Color, a signed 32-bit RGBA integer).
 */
static void
ome_channel(const stack_meta *m, int c, vv_load_info *info) {
    const char *end = strstr(m->pixels, "</Pixels>");
    if (!end)
        end = strstr(m->pixels, ":Pixels>");
    const char *p = m->pixels;
    for (int i = 0; p && i <= c; i++) {
        const char *a = strstr(p + 1, "<Channel "), *b = strstr(p + 1, ":Channel ");
        p = a && (!b || a < b) ? a : b;
        if (p && end && p > end)
            p = NULL;
    }
    if (!p)
        return;
    char v[VV_CHANNEL_NAME_MAX];
    if (xml_attr(p, "Name", v, sizeof v))
        memcpy(info->channel_name, v, sizeof v);
    if (xml_attr(p, "Color", v, sizeof v)) {
        char *e = NULL;
        long long x = strtoll(v, &e, 10);
        if (e != v && *e == '\0' && x >= INT32_MIN && x <= UINT32_MAX) {
            uint32_t rgba = (uint32_t)x;
            for (int k = 0; k < 3; k++)
                info->color[k] = (float)((rgba >> (24 - 8 * k)) & 0xffu) / 255.0f;
            /* black would hide the channel: as if no colour were given */
            info->has_color = (rgba >> 8) != 0;
        }
    }
}

static uint32_t
ij_u32(const unsigned char *p, int big_endian) {
    return big_endian ? (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]
                      : (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

/*
 * The colour of ImageJ's lookup table of channel @p c: the IJMetadata tag
 * (50839) holds a header ("IJIJ" big-endian or "JIJI" little-endian, then a
 * (type, count) pair of 32-bit integers a block type) and the blocks, whose
 * sizes are IJMetadataByteCounts (50838), the header's first; a 'luts'
 * block is 256 reds, 256 greens, 256 blues. The colour is the table's
 * brightest entry; a grey table gives none (the default colours stay).
 * Every offset is checked against the tag's size.
 */
static void
imagej_lut(TIFF *t, int c, vv_load_info *info) {
    uint32_t n_counts = 0, n_bytes = 0;
    const uint32_t *counts = NULL;
    const unsigned char *data = NULL;
    if (!TIFFGetField(t, 50838, &n_counts, &counts) || !TIFFGetField(t, 50839, &n_bytes, &data) ||
        !counts || !data || n_counts < 1 || counts[0] < 4 || counts[0] > n_bytes)
        return;
    int be = !memcmp(data, "IJIJ", 4);
    if (!be && memcmp(data, "JIJI", 4))
        return;
    const uint32_t n_types = (counts[0] - 4) / 8;
    uint64_t off = counts[0];
    uint32_t block = 1;
    for (uint32_t i = 0; i < n_types; i++) {
        uint32_t type = ij_u32(data + 4 + 8 * (size_t)i, be);
        uint32_t n = ij_u32(data + 8 + 8 * (size_t)i, be);
        for (uint32_t k = 0; k < n; k++, block++) {
            if (block >= n_counts || off + counts[block] > n_bytes)
                return;
            if (type == 0x6c757473u /* "luts" */ && k == (uint32_t)c && counts[block] == 768) {
                const unsigned char *lut = data + off;
                if (lut[255] == lut[511] && lut[511] == lut[767])
                    return; /* grey */
                for (int j = 0; j < 3; j++)
                    info->color[j] = (float)lut[255 + 256 * j] / 255.0f;
                info->has_color = 1;
                return;
            }
            off += counts[block];
        }
    }
}

/* "key=value" line of an ImageJ description; 1 when found. */
static int
ij_value(const char *desc, const char *key, char *val, size_t cap) {
    size_t kl = strlen(key);
    for (const char *p = desc; p && *p; p = strchr(p, '\n'), p = p ? p + 1 : NULL) {
        if (!strncmp(p, key, kl) && p[kl] == '=') {
            const char *v = p + kl + 1;
            size_t len = strcspn(v, "\r\n");
            if (len > cap - 1)
                len = cap - 1;
            memcpy(val, v, len);
            val[len] = '\0';
            return 1;
        }
    }
    return 0;
}

/* The ImageJ description's keys (the resolution tags are read by
 * parse_imagej). */
static void
parse_imagej_text(const char *desc, stack_meta *m) {
    if (strncmp(desc, "ImageJ=", 7) != 0)
        return;
    m->is_imagej = 1;
    memcpy(m->order, "XYCZT", 6);
    char v[64];
    int images = 0;
    if (ij_value(desc, "images", v, sizeof v))
        images = atoi(v);
    m->size_c = ij_value(desc, "channels", v, sizeof v) ? atoi(v) : 1;
    m->size_t_ = ij_value(desc, "frames", v, sizeof v) ? atoi(v) : 1;
    if (ij_value(desc, "slices", v, sizeof v))
        m->size_z = atoi(v);
    else if (images > 0 && m->size_c > 0 && m->size_t_ > 0)
        m->size_z = (int)(images / ((long long)m->size_c * m->size_t_));
    if (ij_value(desc, "spacing", v, sizeof v)) {
        double d = strtod(v, NULL);
        if (d > 0 && isfinite(d))
            m->spacing[2] = d;
    }
    if (ij_value(desc, "unit", v, sizeof v)) {
        if (!strcmp(v, "micron") || !strcmp(v, "um") || !strcmp(v, "\\u00B5m"))
            m->unit = VV_UNIT_MICRON;
        else
            m->unit = vv_unit_parse(v);
    }
    static const char *const origins[3] = {"xorigin", "yorigin", "zorigin"};
    for (int i = 0; i < 3; i++)
        if (ij_value(desc, origins[i], v, sizeof v)) {
            double d = strtod(v, NULL);
            if (isfinite(d)) {
                m->ij_origin[i] = d;
                m->has_ij_origin[i] = 1;
            }
        }
}

static void
parse_imagej(TIFF *t, const char *desc, stack_meta *m) {
    parse_imagej_text(desc, m);
    if (!m->is_imagej)
        return;
    float xr = 0, yr = 0;
    if (TIFFGetField(t, TIFFTAG_XRESOLUTION, &xr) && xr > 0 && isfinite(xr))
        m->spacing[0] = 1.0 / xr;
    if (TIFFGetField(t, TIFFTAG_YRESOLUTION, &yr) && yr > 0 && isfinite(yr))
        m->spacing[1] = 1.0 / yr;
}

int
vv_tiff_prescan_description(const char *desc) {
    stack_meta m;
    memset(&m, 0, sizeof m);
    m.unit = VV_UNIT_UNKNOWN;
    parse_ome(desc, &m);
    if (!m.is_ome)
        parse_imagej_text(desc, &m);
    return m.is_ome ? 1 : m.is_imagej ? 2 : 0;
}

/* ---- pages ------------------------------------------------------------------ */

vv_status
tiff_page_format(TIFF *t, page_fmt *f) {
    uint32_t w = 0, h = 0;
    uint16_t bps = 1, spp = 1, fmt = SAMPLEFORMAT_UINT, planar = PLANARCONFIG_CONTIG;
    if (!TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &w) || !TIFFGetField(t, TIFFTAG_IMAGELENGTH, &h))
        return vv_error_set(VV_ERR_FORMAT, "no image width or length");
    TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bps);
    TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &spp);
    TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &fmt);
    TIFFGetFieldDefaulted(t, TIFFTAG_PLANARCONFIG, &planar);
    if (w < 1 || h < 1 || w > VV_VOLUME_MAX_DIM || h > VV_VOLUME_MAX_DIM)
        return vv_error_set(VV_ERR_LIMIT, "page of %u x %u pixels (limit %d per side)", w, h,
                            VV_VOLUME_MAX_DIM);
    if (spp < 1 || spp > 64)
        return vv_error_set(VV_ERR_FORMAT, "%u samples per pixel", spp);
    vv_voxel_type ty;
    if (fmt == SAMPLEFORMAT_IEEEFP && bps == 32)
        ty = VV_F32;
    else if (fmt == SAMPLEFORMAT_IEEEFP && bps == 64)
        ty = VV_F64;
    else if (fmt == SAMPLEFORMAT_INT && (bps == 8 || bps == 16 || bps == 32))
        ty = bps == 8 ? VV_I8 : bps == 16 ? VV_I16 : VV_I32;
    else if ((fmt == SAMPLEFORMAT_UINT || fmt == SAMPLEFORMAT_VOID) &&
             (bps == 8 || bps == 16 || bps == 32))
        ty = bps == 8 ? VV_U8 : bps == 16 ? VV_U16 : VV_U32;
    else
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "%u-bit samples of format %u (supported: 8/16/32-bit integers, "
                            "32/64-bit floats)",
                            bps, fmt);
    uint16_t comp = COMPRESSION_NONE;
    TIFFGetFieldDefaulted(t, TIFFTAG_COMPRESSION, &comp);
    if (!TIFFIsCODECConfigured(comp))
        return vv_error_set(VV_ERR_UNSUPPORTED, "compression %u is not supported by libtiff", comp);
    f->w = w;
    f->h = h;
    f->bps = bps;
    f->spp = spp;
    f->fmt = fmt;
    f->planar = planar;
    f->photometric = 0xffff;
    TIFFGetField(t, TIFFTAG_PHOTOMETRIC, &f->photometric);
    f->type = ty;
    return VV_OK;
}

/* @p n pixels of sample @p s of @p ns a pixel from @p src into @p dst. */
static void
copy_span(unsigned char *dst, const unsigned char *src, uint32_t n, int ns, int s, size_t vs) {
    if (ns == 1) {
        memcpy(dst, src, (size_t)n * vs);
        return;
    }
    for (uint32_t c = 0; c < n; c++)
        memcpy(dst + c * vs, src + ((size_t)c * (size_t)ns + (size_t)s) * vs, vs);
}

/* The rows of decoded tile or strip @p src (its first pixel at @p cx, @p cy,
 * @p cw pixels a row, @p ch rows) inside the box x0, y0, cols, rows, into
 * @p dst (the box's voxels). */
static void
copy_overlap(unsigned char *dst, const unsigned char *src, uint32_t cx, uint32_t cy, uint32_t cw,
             uint32_t ch, uint32_t x0, uint32_t y0, uint32_t cols, uint32_t rows, int ns, int s,
             size_t vs) {
    const uint32_t ax = cx > x0 ? cx : x0, ay = cy > y0 ? cy : y0;
    const uint32_t bx = cx + cw < x0 + cols ? cx + cw : x0 + cols;
    const uint32_t by = cy + ch < y0 + rows ? cy + ch : y0 + rows;
    for (uint32_t y = ay; y < by; y++)
        copy_span(dst + ((size_t)(y - y0) * cols + (ax - x0)) * vs,
                  src + (((size_t)(y - cy) * cw + (ax - cx)) * (size_t)ns) * vs, bx - ax, ns, s,
                  vs);
}

vv_status
tiff_read_region(TIFF *t, const page_fmt *f, int sample, uint32_t x0, uint32_t y0, uint32_t cols,
                 uint32_t rows, unsigned char *dst, tiff_msg *msg, uint64_t *bytes) {
    int planar = f->planar == PLANARCONFIG_SEPARATE && f->spp > 1;
    int ns = planar ? 1 : f->spp;
    uint16_t plane = planar ? (uint16_t)sample : 0;
    int s = planar ? 0 : sample;
    size_t vs = vv_voxel_type_size(f->type);
    if (TIFFIsTiled(t)) {
        uint32_t tw = 0, th = 0;
        TIFFGetField(t, TIFFTAG_TILEWIDTH, &tw);
        TIFFGetField(t, TIFFTAG_TILELENGTH, &th);
        if (tw < 1 || th < 1 || tw > VV_VOLUME_MAX_DIM || th > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_FORMAT, "tile of %u x %u pixels", tw, th);
        tmsize_t need = (tmsize_t)tw * th * ns * (tmsize_t)vs;
        tmsize_t size = TIFFTileSize(t);
        if (size < need)
            return vv_error_set(VV_ERR_FORMAT, "tile size %lld bytes, expected %lld",
                                (long long)size, (long long)need);
        unsigned char *buf = malloc((size_t)size);
        if (!buf)
            return vv_error_set(VV_ERR_NOMEM, "out of memory for a tile");
        for (uint32_t y = y0 / th * th; y < y0 + rows; y += th)
            for (uint32_t x = x0 / tw * tw; x < x0 + cols; x += tw) {
                uint32_t tile = TIFFComputeTile(t, x, y, 0, plane);
                msg->text[0] = '\0';
                tmsize_t got = TIFFReadEncodedTile(t, tile, buf, size);
                if (got < need) {
                    free(buf);
                    return vv_error_set(VV_ERR_FORMAT, "tile %u: %s", tile,
                                        tiff_msg_or(msg, "cannot decode (truncated or corrupt)"));
                }
                if (bytes)
                    *bytes += TIFFGetStrileByteCount(t, tile);
                copy_overlap(dst, buf, x, y, tw, th, x0, y0, cols, rows, ns, s, vs);
            }
        free(buf);
        return VV_OK;
    }
    uint32_t rps = 0;
    TIFFGetFieldDefaulted(t, TIFFTAG_ROWSPERSTRIP, &rps);
    if (rps < 1 || rps > f->h)
        rps = f->h;
    tmsize_t size = TIFFStripSize(t);
    if (size < (tmsize_t)rps * f->w * ns * (tmsize_t)vs)
        return vv_error_set(VV_ERR_FORMAT, "strip size %lld bytes is too small", (long long)size);
    unsigned char *buf = malloc((size_t)size);
    if (!buf)
        return vv_error_set(VV_ERR_NOMEM, "out of memory for a strip");
    for (uint32_t y = y0 / rps * rps; y < y0 + rows; y += rps) {
        uint32_t n = y + rps > f->h ? f->h - y : rps;
        uint32_t strip = TIFFComputeStrip(t, y, plane);
        msg->text[0] = '\0';
        tmsize_t got = TIFFReadEncodedStrip(t, strip, buf, size);
        tmsize_t need = (tmsize_t)n * f->w * ns * (tmsize_t)vs;
        if (got < need) {
            free(buf);
            return vv_error_set(VV_ERR_FORMAT, "strip %u: %s", strip,
                                got < 0 ? tiff_msg_or(msg, "cannot decode (truncated or corrupt)")
                                        : "fewer bytes than the strip's rows need (truncated)");
        }
        if (bytes)
            *bytes += TIFFGetStrileByteCount(t, strip);
        copy_overlap(dst, buf, 0, y, f->w, n, x0, y0, cols, rows, ns, s, vs);
    }
    free(buf);
    return VV_OK;
}

/* Page index of (z, c, t) for the dimension order. */
static long
page_of(const stack_meta *m, int z, int c, int tp) {
    long sz[3] = {m->size_z, m->size_c, m->size_t_};
    long idx = 0, mul = 1;
    for (int i = 2; i < 5; i++) {
        char d = m->order[i];
        long v = d == 'Z' ? z : d == 'C' ? c : tp;
        long n = d == 'Z' ? sz[0] : d == 'C' ? sz[1] : sz[2];
        idx += v * mul;
        mul *= n;
    }
    return idx;
}

/* Counts the pages of @p t (at most @p limit + 1). */
static long
count_pages(TIFF *t, long limit) {
    long n = 0;
    do {
        n++;
    } while (n <= limit && TIFFReadDirectory(t));
    TIFFSetDirectory(t, 0);
    return n;
}

/* Which stack and slices read_stack reads: a channel and a time step (-1:
 * the first), slices z_first .. z_first + z_count - 1 (z_count 0: all). */
typedef struct stack_pick {
    int channel, time, z_first, z_count;
} stack_pick;

void
tiff_stack_clear(tiff_stack *k) {
    free(k->refs);
    memset(k, 0, sizeof *k);
}

vv_status
tiff_stack_plan(tiff_stack *k, char **files, int n_files, int channel, int time,
                const char **bad_file) {
    memset(k, 0, sizeof *k);
    tiff_msg msg;
    *bad_file = files[0];
    TIFF *t = tiff_open_file(files[0], &msg);
    if (!t)
        return vv_error_set(VV_ERR_FORMAT, "%s", tiff_msg_or(&msg, "not a TIFF file"));
    page_fmt f0;
    vv_status s = tiff_page_format(t, &f0);
    if (s != VV_OK) {
        TIFFClose(t);
        return vv_error_prefix(s, "page 0");
    }
    stack_meta m;
    memset(&m, 0, sizeof m);
    m.unit = VV_UNIT_UNKNOWN;
    char *desc = NULL;
    if (TIFFGetField(t, TIFFTAG_IMAGEDESCRIPTION, &desc) && desc) {
        parse_ome(desc, &m);
        if (!m.is_ome)
            parse_imagej(t, desc, &m);
    }
    /* the channel's name and colour while the description is held */
    vv_load_info meta;
    memset(&meta, 0, sizeof meta);
    if (m.is_ome && m.pixels)
        ome_channel(&m, channel < 0 ? 0 : channel, &meta);
    else if (m.is_imagej)
        imagej_lut(t, channel < 0 ? 0 : channel, &meta);
    m.pixels = NULL;
    long pages0 = count_pages(t, VV_VOLUME_MAX_DIM * 64L);
    TIFFClose(t);
    if (pages0 > VV_VOLUME_MAX_DIM * 64L)
        return vv_error_set(VV_ERR_LIMIT, "more than %ld pages", VV_VOLUME_MAX_DIM * 64L);

    /* the slices: (file, page) of each z for the channel */
    long total = n_files == 1 ? pages0 : n_files; /* a folder: one page a file */
    int nz, nc = f0.spp;
    /* each product checked before the next (sizes from the description are
     * any int): no overflow */
    if ((m.is_ome || m.is_imagej) && n_files == 1 && m.size_z > 0 && m.size_c > 0 &&
        m.size_t_ > 0 && m.size_z <= total && m.size_c <= total && m.size_t_ <= total &&
        (long)m.size_z * m.size_c <= total && (long)m.size_z * m.size_c * m.size_t_ <= total) {
        nz = m.size_z;
        if (m.size_c > 1)
            nc = m.size_c;
    } else {
        if (total > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT, "%ld pages (limit %d slices)", total,
                                VV_VOLUME_MAX_DIM);
        nz = (int)total;
        m.size_c = 1;
        m.size_t_ = 1;
        m.size_z = nz;
        memcpy(m.order, "XYZCT", 6);
    }
    int ch = channel < 0 ? 0 : channel, tp = time < 0 ? 0 : time;
    if (!meta.has_color && nc == f0.spp && f0.photometric == PHOTOMETRIC_RGB && ch < 3) {
        /* an RGB image's samples: red, green and blue (extra samples,
         * such as alpha, keep the default colours) */
        meta.color[ch] = 1.0f;
        meta.has_color = 1;
    }
    if (ch >= nc)
        return vv_error_set(VV_ERR_INVALID, "channel %d asked, the stack has %d channel%s", ch, nc,
                            nc == 1 ? "" : "s");
    if (tp >= m.size_t_)
        return vv_error_set(VV_ERR_INVALID, "time step %d asked, the stack has %d time step%s", tp,
                            m.size_t_, m.size_t_ == 1 ? "" : "s");
    k->refs = malloc((size_t)nz * sizeof *k->refs);
    if (!k->refs)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int z = 0; z < nz; z++) {
        if (n_files == 1) {
            k->refs[z].file = 0;
            k->refs[z].page = page_of(&m, z, m.size_c > 1 ? ch : 0, tp);
        } else {
            k->refs[z].file = z;
            k->refs[z].page = 0;
        }
    }
    k->f0 = f0;
    k->nz = nz;
    k->nc = nc;
    k->nt = m.size_t_;
    k->channel = ch;
    k->time = tp;
    k->sample = m.size_c <= 1 ? ch : 0; /* channels are the samples of each pixel */
    for (int i = 0; i < 3; i++)
        k->spacing[i] = m.spacing[i] > 0 ? m.spacing[i] : 1;
    if (m.spacing[0] > 0 && !(m.spacing[1] > 0))
        k->spacing[1] = m.spacing[0];
    for (int i = 0; i < 3; i++)
        k->origin[i] = m.has_origin[i]      ? m.origin[i]
                       : m.has_ij_origin[i] ? -m.ij_origin[i] * k->spacing[i]
                                            : 0;
    k->unit = (m.is_ome || m.is_imagej) ? m.unit : VV_UNIT_UNKNOWN;
    k->time_step = m.time_step;
    k->meta = meta;
    return VV_OK;
}

static vv_status
read_stack(vv_volume **out, char **files, int n_files, const stack_pick *pick, vv_load_info *info,
           const char **bad_file) {
    tiff_stack k;
    vv_status s = tiff_stack_plan(&k, files, n_files, pick->channel, pick->time, bad_file);
    if (s != VV_OK)
        return s;
    const page_fmt f0 = k.f0;
    const int nz = k.nz;
    /* the slices read: all, or the range asked */
    const int z0 = pick->z_count > 0 ? pick->z_first : 0;
    const int nread = pick->z_count > 0 ? pick->z_count : nz;
    int dims[3] = {(int)f0.w, (int)f0.h, nread};
    vv_volume *v = NULL;
    if (pick->z_count > 0 && (z0 > nz - nread || nread > nz))
        s = vv_error_set(VV_ERR_INVALID, "slices %d to %d asked, the stack has %d (from 0)", z0,
                         z0 + nread - 1, nz);
    if (s == VV_OK)
        s = vv_volume_check_size(dims, f0.type, NULL);
    if (s == VV_OK)
        s = vv_volume_new(&v, dims, f0.type);
    if (s != VV_OK) {
        tiff_stack_clear(&k);
        return s;
    }
    size_t slice = (size_t)f0.w * f0.h * vv_voxel_type_size(f0.type);
    int open_file = -1;
    TIFF *t = NULL;
    tiff_msg msg;
    const page_ref *refs = k.refs;
    for (int z = z0; z < z0 + nread && s == VV_OK; z++) {
        if (refs[z].file != open_file) {
            if (t)
                TIFFClose(t);
            open_file = refs[z].file;
            *bad_file = files[open_file];
            t = tiff_open_file(files[open_file], &msg);
            if (!t) {
                s = vv_error_set(VV_ERR_FORMAT, "%s", tiff_msg_or(&msg, "not a TIFF file"));
                break;
            }
        }
        msg.text[0] = '\0';
        if (!TIFFSetDirectory(t, (tdir_t)refs[z].page)) {
            s = vv_error_set(VV_ERR_FORMAT, "page %ld: %s", refs[z].page,
                             tiff_msg_or(&msg, "cannot read its directory"));
            break;
        }
        page_fmt f;
        s = tiff_page_format(t, &f);
        if (s == VV_OK && (f.w != f0.w || f.h != f0.h || f.type != f0.type || f.spp != f0.spp))
            s = vv_error_set(VV_ERR_FORMAT,
                             "%u x %u %s x %u samples, the first page is %u x %u %s x %u", f.w, f.h,
                             vv_voxel_type_name(f.type), f.spp, f0.w, f0.h,
                             vv_voxel_type_name(f0.type), f0.spp);
        if (s == VV_OK)
            s = tiff_read_region(t, &f, k.sample, 0, 0, f.w, f.h,
                                 (unsigned char *)v->data + (size_t)(z - z0) * slice, &msg, NULL);
        if (s != VV_OK)
            s = vv_error_prefix(s, "page %ld", refs[z].page);
    }
    if (t)
        TIFFClose(t);
    if (s != VV_OK) {
        tiff_stack_clear(&k);
        vv_volume_free(v);
        return s;
    }
    for (int i = 0; i < 3; i++) {
        v->spacing[i] = k.spacing[i];
        v->origin[i] = k.origin[i];
    }
    v->origin[2] += z0 * v->spacing[2]; /* the first slice read (TIFF has no direction) */
    v->unit = k.unit;
    v->modification = VV_MOD_ORIGINAL;
    vv_volume_update_range(v);
    if (info) {
        *info = k.meta;
        info->n_channels = k.nc;
        info->n_times = k.nt;
        info->time_step = k.time_step;
        info->n_slices = nz;
    }
    tiff_stack_clear(&k);
    *out = v;
    return VV_OK;
}

vv_status
tiff_files(const char *path, char ***files, int *n, int *is_dir) {
    *files = NULL;
    *n = 0;
    *is_dir = 0;
    struct stat st;
    if (stat(path, &st) != 0) {
        int e = errno;
        return vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(e));
    }
    if (S_ISDIR(st.st_mode)) {
        *is_dir = 1;
        return list_folder(path, files, n);
    }
    char **v = malloc(sizeof *v);
    if (!v || !(v[0] = strdup(path))) {
        free(v);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    *files = v;
    *n = 1;
    return VV_OK;
}

void
tiff_free_files(char **files, int n) {
    free_list(files, n);
}

static vv_status
tiff_read_at(vv_volume **out, const char *path, const stack_pick *pick, vv_load_info *info) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "tiff: NULL argument");
    *out = NULL;
    char **files = NULL;
    int n = 0, is_dir = 0;
    vv_status s = tiff_files(path, &files, &n, &is_dir);
    if (s != VV_OK)
        return vv_error_prefix(s, "tiff: %s", path);
    const char *bad = path;
    s = read_stack(out, files, n, pick, info, &bad);
    if (s != VV_OK)
        s = vv_error_prefix(s, "tiff: %s", n > 1 || is_dir ? bad : path);
    free_list(files, n);
    return s;
}

vv_status
vv_tiff_read(vv_volume **out, const char *path, int channel) {
    const stack_pick pick = {channel, -1, 0, 0};
    return tiff_read_at(out, path, &pick, NULL);
}

/* ---- the format record ------------------------------------------------------ */

/* A TIFF file in a folder. */
static int
tiff_entry(const char *entry, const char *name, int is_dir, void *ctx) {
    (void)name;
    (void)ctx;
    return !is_dir && vv_format_detect(entry) == VV_FORMAT_TIFF;
}

/* TIFF and BigTIFF in either byte order; a folder of TIFF pages only at
 * @p deep 1, so that a folder with a DICOM file in it is DICOM. */
static int
tiff_looks_like(const vv_format_probe *p, int deep) {
    if (p->is_dir)
        return deep && vv_format_folder_any(p->path, tiff_entry, NULL);
    const unsigned char *h = p->head;
    return !deep && p->n >= 4 &&
           (!memcmp(h, "II*\0", 4) || !memcmp(h, "MM\0*", 4) || !memcmp(h, "II+\0", 4) ||
            !memcmp(h, "MM\0+", 4));
}

static vv_status
tiff_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    if (opt->level > 0) /* an OME-TIFF's SubIFD level (reduced in z too) */
        return opt->z_count > 0
                   ? vv_error_set(VV_ERR_UNSUPPORTED,
                                  "tiff: %s: slices of a level past 0 (read the "
                                  "level whole)",
                                  vv_path_basename(path))
                   : vv_tiff_read_level(out, path, opt->channel, opt->time, opt->level, opt->info);
    const stack_pick pick = {opt->channel, opt->time, opt->z_first, opt->z_count};
    return tiff_read_at(out, path, &pick, opt->info);
}

/* TIFF holds no direction matrix. */
static int
tiff_fits(const vv_volume *v, char *why, size_t cap) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            if (v->direction[r * 3 + c] != (r == c)) {
                snprintf(why, cap, "TIFF holds no direction matrix (written axis-aligned)");
                return 0;
            }
    return 1;
}

static vv_status
tiff_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_tiff_write(v, path, opt);
}

static const char *const tiff_extensions[] = {"tif", "tiff", NULL};
static const char *const tiff_aliases[] = {"tif", NULL};

const vv_format_record vv_format_tiff = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "tiff",
    .title = "TIFF",
    .extensions = tiff_extensions,
    .aliases = tiff_aliases,
    .doc = "TIFF through libtiff: pages or a folder of pages, BigTIFF, OME-TIFF, ImageJ; written "
           "as one page per slice (OME-XML for .ome.tif, ImageJ's keys otherwise), deflate "
           "unless --codec or --no-compress; read out of core tile by tile, OME-TIFF SubIFD "
           "pyramids as levels of detail",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY | VV_FORMAT_FLAG_FOLDER | VV_FORMAT_FLAG_SLICES,
    .looks_like = tiff_looks_like,
    .fits = tiff_fits,
    .read = tiff_read_record,
    .write = tiff_write_record,
    .open_store = vv_tiff_open_store,
};
