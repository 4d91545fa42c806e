/*
 * Writing TIFF stacks through libtiff (vv_tiff_write; the reader and the
 * format record are tiff.c's): one page per slice in the voxel type,
 * OME-XML (OME 2016-06) for .ome.tif(f) names and ImageJ's keys otherwise,
 * deflate/LZW/zstd with a predictor, BigTIFF on request or near 4 GiB.
 * libtiff writes through our own I/O procedures on the atomic file's
 * descriptor, so a failed write leaves the old file as it was; its
 * messages go to the file's own handlers (tiff_msg.c), nothing is printed.
 *
 * Thread-safety: reentrant (one libtiff handle and message a call).
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
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
#include "io/volume/tiff_msg.h"
#include "io/write_check.h"
#include "volvis/io.h"

/* libtiff's I/O on the atomic file's descriptor: positioned reads and writes
 * (libtiff reads back a directory when it links the next page), never
 * closed by TIFFClose (the atomic file owns it). */
typedef struct tiff_fd {
    int fd;
    uint64_t off;
} tiff_fd;

static tmsize_t
fd_read(thandle_t h, void *buf, tmsize_t n) {
    tiff_fd *f = (tiff_fd *)h;
    tmsize_t done = 0;
    while (done < n) {
        ssize_t r = pread(f->fd, (char *)buf + done, (size_t)(n - done), (off_t)f->off);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        done += r;
        f->off += (uint64_t)r;
    }
    return done ? done : (n ? -1 : 0);
}

static tmsize_t
fd_write(thandle_t h, void *buf, tmsize_t n) {
    tiff_fd *f = (tiff_fd *)h;
    tmsize_t done = 0;
    while (done < n) {
        ssize_t r = pwrite(f->fd, (const char *)buf + done, (size_t)(n - done), (off_t)f->off);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return -1; /* a full disk or a file-size limit: libtiff reports it */
        done += r;
        f->off += (uint64_t)r;
    }
    return done;
}

static toff_t
fd_size(thandle_t h) {
    struct stat st;
    return fstat(((tiff_fd *)h)->fd, &st) == 0 ? (toff_t)st.st_size : 0;
}

static toff_t
fd_seek(thandle_t h, toff_t off, int whence) {
    tiff_fd *f = (tiff_fd *)h;
    uint64_t base = whence == SEEK_CUR ? f->off : whence == SEEK_END ? fd_size(h) : 0;
    f->off = base + off;
    return (toff_t)f->off;
}

static int
fd_close(thandle_t h) {
    (void)h;
    return 0;
}

static int
fd_map(thandle_t h, void **base, toff_t *size) {
    (void)h;
    (void)base;
    (void)size;
    return 0;
}

static void
fd_unmap(thandle_t h, void *base, toff_t size) {
    (void)h;
    (void)base;
    (void)size;
}

/* The codec of @p opt: its name (opt->codec), else deflate, or none when
 * opt->compress is 0. */
static vv_status
tiff_codec(const vv_save_options *opt, uint16_t *comp) {
    static const struct {
        const char *name;
        uint16_t id;
    } codecs[] = {{"deflate", COMPRESSION_ADOBE_DEFLATE},
                  {"zlib", COMPRESSION_ADOBE_DEFLATE},
                  {"lzw", COMPRESSION_LZW},
                  {"zstd", COMPRESSION_ZSTD},
                  {"packbits", COMPRESSION_PACKBITS},
                  {"none", COMPRESSION_NONE}};
    const char *name = opt->codec ? opt->codec : opt->compress == 0 ? "none" : "deflate";
    for (size_t i = 0; i < sizeof codecs / sizeof codecs[0]; i++) {
        if (strcasecmp(name, codecs[i].name) != 0)
            continue;
        if (!TIFFIsCODECConfigured(codecs[i].id))
            return vv_error_set(VV_ERR_UNSUPPORTED, "this libtiff was built without %s", name);
        *comp = codecs[i].id;
        return VV_OK;
    }
    return vv_error_set(VV_ERR_INVALID, "unknown codec '%s' (deflate, lzw, zstd, packbits, none)",
                        name);
}

/* TIFF's sample format and OME's pixel type of a voxel type. */
static void
tiff_sample_of(vv_voxel_type t, uint16_t *fmt, const char **ome) {
    static const char *const names[] = {"uint8",  "int8",  "uint16", "int16",
                                        "uint32", "int32", "float",  "double"};
    *fmt = (t == VV_F32 || t == VV_F64)                 ? SAMPLEFORMAT_IEEEFP
           : (t == VV_I8 || t == VV_I16 || t == VV_I32) ? SAMPLEFORMAT_INT
                                                        : SAMPLEFORMAT_UINT;
    *ome = names[t];
}

/* OME's UnitsLength of a unit; "pixel" when the unit is unknown. */
static const char *
ome_unit_name(vv_unit u) {
    switch (u) {
    case VV_UNIT_METER:
        return "m";
    case VV_UNIT_MM:
        return "mm";
    case VV_UNIT_MICRON:
        return "\xc2\xb5m"; /* µm */
    case VV_UNIT_FOOT:
        return "ft";
    case VV_UNIT_INCH:
        return "in";
    case VV_UNIT_NM:
        return "nm";
    default:
        return "pixel";
    }
}

/* A growing text buffer (the image description). */
typedef struct desc_buf {
    char *s;
    size_t n, cap;
    int failed;
} desc_buf;

static void
desc_add(desc_buf *b, const char *fmt, ...) {
    if (b->failed)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) {
            b->failed = 1;
            return;
        }
        if (b->s && b->n + (size_t)k < b->cap) {
            b->n += (size_t)k;
            return;
        }
        size_t cap = (b->cap ? b->cap * 2 : 4096) + (size_t)k;
        char *s = realloc(b->s, cap);
        if (!s) {
            b->failed = 1;
            return;
        }
        b->s = s;
        b->cap = cap;
    }
}

/* @p s with XML's five special characters escaped. */
static void
desc_add_xml(desc_buf *b, const char *s) {
    for (; *s; s++) {
        const char *e = *s == '&'    ? "&amp;"
                        : *s == '<'  ? "&lt;"
                        : *s == '>'  ? "&gt;"
                        : *s == '"'  ? "&quot;"
                        : *s == '\'' ? "&apos;"
                                     : NULL;
        if (e)
            desc_add(b, "%s", e);
        else
            desc_add(b, "%c", *s);
    }
}

/* 1 when @p path names an OME-TIFF (.ome.tif, .ome.tiff). */
static int
is_ome_name(const char *path) {
    size_t n = strlen(path);
    return (n > 8 && !strcasecmp(path + n - 8, ".ome.tif")) ||
           (n > 9 && !strcasecmp(path + n - 9, ".ome.tiff"));
}

/*
 * OME-XML of @p v (OME 2016-06): one Image, Pixels in XYZCT order with the
 * physical sizes, one Channel, TiffData for the pages and one Plane per
 * slice with its position (the origin stepped along k).
 */
static void
ome_description(desc_buf *b, const vv_volume *v, const char *path) {
    uint16_t fmt;
    const char *type;
    tiff_sample_of(v->type, &fmt, &type);
    const char *unit = ome_unit_name(v->unit);
    const char *base = vv_path_basename(path);
    size_t stem = strlen(base) - (strcasecmp(base + strlen(base) - 4, "tiff") ? 8 : 9);
    char name[256];
    snprintf(name, sizeof name, "%.*s", (int)(stem < sizeof name ? stem : sizeof name - 1), base);
    desc_add(b, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                "<OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\" "
                "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
                "xsi:schemaLocation=\"http://www.openmicroscopy.org/Schemas/OME/2016-06 "
                "http://www.openmicroscopy.org/Schemas/OME/2016-06/ome.xsd\" "
                "Creator=\"VolVis\">\n<Image ID=\"Image:0\" Name=\"");
    desc_add_xml(b, name);
    desc_add(b,
             "\">\n<Pixels ID=\"Pixels:0\" DimensionOrder=\"XYZCT\" Type=\"%s\" "
             "SizeX=\"%d\" SizeY=\"%d\" SizeZ=\"%d\" SizeC=\"1\" SizeT=\"1\" "
             "PhysicalSizeX=\"%.17g\" PhysicalSizeXUnit=\"%s\" "
             "PhysicalSizeY=\"%.17g\" PhysicalSizeYUnit=\"%s\" "
             "PhysicalSizeZ=\"%.17g\" PhysicalSizeZUnit=\"%s\" BigEndian=\"false\">\n"
             "<Channel ID=\"Channel:0:0\" SamplesPerPixel=\"1\"><LightPath/></Channel>\n"
             "<TiffData IFD=\"0\" PlaneCount=\"%d\"/>\n",
             type, v->dims[0], v->dims[1], v->dims[2], v->spacing[0], unit, v->spacing[1], unit,
             v->spacing[2], unit, v->dims[2]);
    for (int k = 0; k < v->dims[2]; k++)
        desc_add(b,
                 "<Plane TheZ=\"%d\" TheC=\"0\" TheT=\"0\" PositionX=\"%.17g\" "
                 "PositionXUnit=\"%s\" PositionY=\"%.17g\" PositionYUnit=\"%s\" "
                 "PositionZ=\"%.17g\" PositionZUnit=\"%s\"/>\n",
                 k, v->origin[0], unit, v->origin[1], unit, v->origin[2] + k * v->spacing[2], unit);
    desc_add(b, "</Pixels>\n</Image>\n</OME>\n");
}

/* ImageJ's description of a z-stack (its hyperstack keys; the origin in
 * voxels, as ImageJ's calibration keeps it). */
static void
imagej_description(desc_buf *b, const vv_volume *v) {
    desc_add(b, "ImageJ=1.11a\nimages=%d\nslices=%d\n", v->dims[2], v->dims[2]);
    if (v->unit != VV_UNIT_UNKNOWN)
        desc_add(b, "unit=%s\n", v->unit == VV_UNIT_MICRON ? "micron" : vv_unit_name(v->unit));
    desc_add(b, "spacing=%.17g\nloop=false\n", v->spacing[2]);
    for (int i = 0; i < 3; i++)
        if (v->origin[i] != 0)
            desc_add(b, "%corigin=%.17g\n", "xyz"[i], -v->origin[i] / v->spacing[i]);
    desc_add(b, "min=%.17g\nmax=%.17g\n", v->range[0], v->range[1]);
}

/* 1 when the voxels come near classic TIFF's 4 GiB of offsets. */
static int
wants_bigtiff(const vv_volume *v) {
    uint64_t bytes = (uint64_t)v->dims[0] * v->dims[1] * v->dims[2] * vv_voxel_type_size(v->type);
    return bytes > ((uint64_t)15 << 28); /* 3.75 GiB: room for directories and metadata */
}

/* One page (slice @p k) with its tags and strips. */
static vv_status
write_page(TIFF *t, const vv_volume *v, int k, uint16_t comp, const char *desc,
           unsigned char *scratch, size_t scratch_cap, tiff_msg *msg) {
    uint16_t fmt;
    const char *type;
    tiff_sample_of(v->type, &fmt, &type);
    size_t es = vv_voxel_type_size(v->type);
    size_t row = (size_t)v->dims[0] * es;
    uint32_t rps = (uint32_t)(scratch_cap / row);
    if (rps < 1)
        rps = 1;
    if (rps > (uint32_t)v->dims[1])
        rps = (uint32_t)v->dims[1];
    int ok = TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)v->dims[0]) &&
             TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)v->dims[1]) &&
             TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, (uint16_t)(es * 8)) &&
             TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1) &&
             TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, fmt) &&
             TIFFSetField(t, TIFFTAG_PHOTOMETRIC, (uint16_t)PHOTOMETRIC_MINISBLACK) &&
             TIFFSetField(t, TIFFTAG_PLANARCONFIG, (uint16_t)PLANARCONFIG_CONTIG) &&
             TIFFSetField(t, TIFFTAG_COMPRESSION, comp) &&
             TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rps) &&
             TIFFSetField(t, TIFFTAG_SOFTWARE, "VolVis");
    if (ok && comp != COMPRESSION_NONE && comp != COMPRESSION_PACKBITS &&
        fmt != SAMPLEFORMAT_IEEEFP)
        /* horizontal differencing of integers; floats get none: the
         * floating-point predictor (3) is not read by tifffile without
         * imagecodecs, nor by older ImageJ */
        ok = TIFFSetField(t, TIFFTAG_PREDICTOR, (uint16_t)PREDICTOR_HORIZONTAL);
    if (ok && desc) {
        ok = TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, desc);
        if (ok && strncmp(desc, "ImageJ=", 7) == 0)
            ok = TIFFSetField(t, TIFFTAG_XRESOLUTION, (float)(1.0 / v->spacing[0])) &&
                 TIFFSetField(t, TIFFTAG_YRESOLUTION, (float)(1.0 / v->spacing[1])) &&
                 TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, (uint16_t)RESUNIT_NONE);
    }
    if (!ok)
        return vv_error_set(VV_ERR_IO, "page %d: %s", k, tiff_msg_or(msg, "cannot set its tags"));
    const unsigned char *slice = (const unsigned char *)v->data + (size_t)k * v->dims[1] * row;
    for (uint32_t y = 0, s = 0; y < (uint32_t)v->dims[1]; y += rps, s++) {
        uint32_t rows = y + rps <= (uint32_t)v->dims[1] ? rps : (uint32_t)v->dims[1] - y;
        size_t bytes = rows * row;
        /* libtiff's predictor and byte order work on the buffer given: a copy */
        memcpy(scratch, slice + (size_t)y * row, bytes);
        if (TIFFWriteEncodedStrip(t, s, scratch, (tmsize_t)bytes) < 0)
            return vv_error_set(VV_ERR_IO, "page %d: %s", k, tiff_msg_or(msg, "write failed"));
    }
    if (!TIFFWriteDirectory(t))
        return vv_error_set(VV_ERR_IO, "page %d: %s", k, tiff_msg_or(msg, "write failed"));
    return VV_OK;
}

static vv_status
write_pages(const vv_volume *v, const char *path, const vv_save_options *opt, int fd,
            uint16_t comp) {
    desc_buf d = {0};
    if (is_ome_name(path))
        ome_description(&d, v, path);
    else
        imagej_description(&d, v);
    if (d.failed) {
        free(d.s);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    size_t row = (size_t)v->dims[0] * vv_voxel_type_size(v->type);
    size_t cap = row > ((size_t)256 << 10) ? row : ((size_t)256 << 10);
    unsigned char *scratch = malloc(cap);
    tiff_msg msg = {{0}};
    TIFFOpenOptions *o = TIFFOpenOptionsAlloc();
    if (!scratch || !o) {
        free(scratch);
        free(d.s);
        if (o)
            TIFFOpenOptionsFree(o);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    TIFFOpenOptionsSetErrorHandlerExtR(o, tiff_on_error, &msg);
    TIFFOpenOptionsSetWarningHandlerExtR(o, tiff_on_warning, &msg);
    tiff_fd f = {fd, 0};
    const char *mode = opt->bigtiff || wants_bigtiff(v) ? "w8" : "w";
    TIFF *t = TIFFClientOpenExt(path, mode, (thandle_t)&f, fd_read, fd_write, fd_seek, fd_close,
                                fd_size, fd_map, fd_unmap, o);
    TIFFOpenOptionsFree(o);
    vv_status s = VV_OK;
    if (!t)
        s = vv_error_set(VV_ERR_IO, "%s", tiff_msg_or(&msg, "cannot start the file"));
    for (int k = 0; s == VV_OK && k < v->dims[2]; k++)
        s = write_page(t, v, k, comp, k == 0 ? d.s : NULL, scratch, cap, &msg);
    if (t) {
        TIFFFlush(t);
        TIFFClose(t);
    }
    free(scratch);
    free(d.s);
    return s;
}

vv_status
vv_tiff_write(const vv_volume *v, const char *path, const vv_save_options *opt) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "tiff: NULL argument");
    vv_save_options defaults;
    if (!opt) {
        vv_save_options_init(&defaults);
        opt = &defaults;
    }
    uint16_t comp = COMPRESSION_NONE;
    vv_status s = io_write_check_voxels(v, v->data != NULL, (unsigned)v->type <= VV_F64);
    if (s == VV_OK)
        s = io_write_check_geometry(v, IO_WRITE_NO_DIRECTION);
    if (s == VV_OK)
        s = tiff_codec(opt, &comp);
    vv_atomic_file af;
    if (s == VV_OK)
        s = vv_atomic_file_open(&af, path);
    if (s == VV_OK) {
        s = write_pages(v, path, opt, af.fd, comp);
        if (s == VV_OK)
            s = vv_atomic_file_commit(&af);
        else
            vv_atomic_file_abort(&af);
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "tiff: %s", vv_path_basename(path));
    return VV_OK;
}
