/*
 * Format names, detection and the generic load/save entry points.
 */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <zlib.h>

#include "core/internal.h"
#include "io/dicom.h"
#include "volvis/io.h"

static const char *const format_names[] = {"auto", "slc", "nrrd", "nifti", "mhd",
                                           "vtk",  "raw", "tiff", "dicom", "unknown"};

const char *
vv_format_name(vv_format f) {
    if ((int)f < 0 || (size_t)f >= sizeof format_names / sizeof format_names[0])
        return "unknown";
    return format_names[f];
}

vv_status
vv_format_parse(const char *name, vv_format *out) {
    static const struct {
        const char *name;
        vv_format f;
    } aliases[] = {{"nhdr", VV_FORMAT_NRRD},     {"nii", VV_FORMAT_NIFTI}, {"mha", VV_FORMAT_MHD},
                   {"metaimage", VV_FORMAT_MHD}, {"hdr", VV_FORMAT_NIFTI}, {"tif", VV_FORMAT_TIFF},
                   {"dcm", VV_FORMAT_DICOM}};
    if (!name || !out)
        return vv_error_set(VV_ERR_INVALID, "format: NULL argument");
    for (int f = VV_FORMAT_AUTO; f < VV_FORMAT_UNKNOWN; f++) {
        if (!strcasecmp(name, format_names[f])) {
            *out = (vv_format)f;
            return VV_OK;
        }
    }
    for (size_t i = 0; i < sizeof aliases / sizeof aliases[0]; i++) {
        if (!strcasecmp(name, aliases[i].name)) {
            *out = aliases[i].f;
            return VV_OK;
        }
    }
    return vv_error_set(
        VV_ERR_INVALID,
        "unknown format \"%s\" (expected auto, slc, nrrd, nifti, mhd, vtk, raw, tiff or "
        "dicom)",
        name);
}

/* Lower-case extension after the last '.' of the base name ("" when none). */
static const char *
extension(const char *path) {
    const char *base = vv_path_basename(path);
    const char *dot = strrchr(base, '.');
    return dot ? dot + 1 : "";
}

static int
has_ext(const char *path, const char *ext) {
    return strcasecmp(extension(path), ext) == 0;
}

#define HEAD_BYTES 544

static uint32_t
get_u32(const unsigned char *p, int big) {
    return big ? ((uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3])
               : ((uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0]);
}

/* 2: NIfTI with magic, 1: a 348-byte header without magic (Analyze), 0: neither. */
static int
nifti_header_kind(const unsigned char *h, size_t n) {
    if (n < 348)
        return 0;
    for (int big = 0; big < 2; big++) {
        uint32_t sz = get_u32(h, big);
        if (sz == 348) {
            if (!memcmp(h + 344, "n+1", 4) || !memcmp(h + 344, "ni1", 4))
                return 2;
            return 1;
        }
        if (sz == 540 && n >= 12) {
            if (!memcmp(h + 4, "n+2", 4) || !memcmp(h + 4, "ni2", 4))
                return 2;
        }
    }
    return 0;
}

static int
is_metaimage(const unsigned char *h, size_t n) {
    static const char *const keys[] = {"ObjectType",
                                       "NDims",
                                       "ObjectSubType",
                                       "DimSize",
                                       "ElementType",
                                       "ElementSpacing",
                                       "Comment",
                                       "TransformType",
                                       "BinaryData",
                                       "BinaryDataByteOrderMSB",
                                       "ElementByteOrderMSB",
                                       "CompressedData",
                                       "Offset",
                                       "Position",
                                       "Origin",
                                       "TransformMatrix",
                                       "Rotation",
                                       "Orientation",
                                       "CenterOfRotation",
                                       "AnatomicalOrientation",
                                       "ElementDataFile",
                                       "HeaderSize",
                                       "ElementNumberOfChannels",
                                       "ElementSize",
                                       "Name",
                                       "ID",
                                       "ParentID",
                                       "Color",
                                       "ElementMin",
                                       "ElementMax"};
    size_t i = 0;
    while (i < n && isspace(h[i]))
        i++;
    size_t k0 = i;
    while (i < n && (isalnum(h[i]) || h[i] == '_'))
        i++;
    size_t klen = i - k0;
    if (klen == 0)
        return 0;
    while (i < n && (h[i] == ' ' || h[i] == '\t'))
        i++;
    if (i >= n || h[i] != '=')
        return 0;
    for (size_t j = 0; j < sizeof keys / sizeof keys[0]; j++)
        if (strlen(keys[j]) == klen && !strncasecmp((const char *)h + k0, keys[j], klen))
            return 1;
    return 0;
}

static vv_format
detect_buffer(const unsigned char *h, size_t n, const char *path) {
    size_t i = 0;
    while (i < n && isspace(h[i]))
        i++;
    if (n - i >= 5 && !memcmp(h + i, "11111", 5))
        return VV_FORMAT_SLC;
    if (n >= 7 && !memcmp(h, "NRRD000", 7))
        return VV_FORMAT_NRRD;
    if (n - i >= 14 && !memcmp(h + i, "# vtk DataFile", 14))
        return VV_FORMAT_VTK;
    int nk = nifti_header_kind(h, n);
    if (nk == 2 || (nk == 1 && has_ext(path, "hdr")))
        return VV_FORMAT_NIFTI;
    if (is_metaimage(h, n))
        return VV_FORMAT_MHD;
    if (n >= 4 && (!memcmp(h, "II*\0", 4) || !memcmp(h, "MM\0*", 4) || !memcmp(h, "II+\0", 4) ||
                   !memcmp(h, "MM\0+", 4)))
        return VV_FORMAT_TIFF;
    if (n >= 132 && !memcmp(h + 128, "DICM", 4))
        return VV_FORMAT_DICOM;
    return VV_FORMAT_UNKNOWN;
}

/* A folder: DICOM when it holds a DICOMDIR or a DICOM file (looked for among
 * its first entries and one level of subfolders), else TIFF when it holds a
 * .tif/.tiff file. */
static vv_format
detect_folder(const char *path, int depth) {
    DIR *d = opendir(path);
    if (!d)
        return VV_FORMAT_UNKNOWN;
    int tiff = 0, dicom = 0, looked = 0;
    struct dirent *e;
    while (!dicom && looked < 4096 && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        size_t len = strlen(path) + strlen(e->d_name) + 2;
        char *p = malloc(len);
        if (!p)
            break;
        snprintf(p, len, "%s/%s", path, e->d_name);
        struct stat st;
        if (stat(p, &st) == 0) {
            if (S_ISDIR(st.st_mode)) {
                if (depth < 1 && detect_folder(p, depth + 1) == VV_FORMAT_DICOM)
                    dicom = 1;
            } else if (S_ISREG(st.st_mode)) {
                looked++;
                if (!strcasecmp(e->d_name, "DICOMDIR")) {
                    dicom = 1;
                } else {
                    vv_format f = vv_format_detect(p);
                    if (f == VV_FORMAT_DICOM)
                        dicom = 1;
                    else if (f == VV_FORMAT_TIFF)
                        tiff = 1;
                }
            }
        }
        free(p);
    }
    closedir(d);
    return dicom ? VV_FORMAT_DICOM : tiff ? VV_FORMAT_TIFF : VV_FORMAT_UNKNOWN;
}

/* Reads up to HEAD_BYTES of @p path, gunzipped when it starts with 1f 8b. */
static size_t
read_head(const char *path, unsigned char *h, int *gz, int *err) {
    *gz = 0;
    *err = 0;
    FILE *f = fopen(path, "rb");
    if (!f) {
        *err = errno ? errno : EIO;
        return 0;
    }
    size_t n = fread(h, 1, HEAD_BYTES, f);
    fclose(f);
    if (n >= 2 && h[0] == 0x1f && h[1] == 0x8b) {
        *gz = 1;
        gzFile g = gzopen(path, "rb");
        if (!g)
            return 0;
        int r = gzread(g, h, HEAD_BYTES);
        gzclose(g);
        n = r > 0 ? (size_t)r : 0;
    }
    return n;
}

vv_format
vv_format_detect(const char *path) {
    if (!path)
        return VV_FORMAT_UNKNOWN;
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
        return detect_folder(path, 0);
    unsigned char h[HEAD_BYTES];
    int gz, err;
    size_t n = read_head(path, h, &gz, &err);
    if (gz) {
        /* only NIfTI is read gzip-compressed (.nii.gz, .hdr.gz) */
        int nk = nifti_header_kind(h, n);
        if (nk == 2 || (nk == 1 && strstr(vv_path_basename(path), ".hdr")))
            return VV_FORMAT_NIFTI;
        return VV_FORMAT_UNKNOWN;
    }
    vv_format f = detect_buffer(h, n, path);
    if (f != VV_FORMAT_UNKNOWN || err)
        return f;
    /* DICOM without the 128-byte preamble (old ACR-NEMA style files) */
    if (n > 0 && vv_dicom_sniff(path))
        return VV_FORMAT_DICOM;
    /* the image half of a .hdr/.img pair: look at the header beside it */
    if (has_ext(path, "img")) {
        size_t len = strlen(path);
        char *hdr = malloc(len + 1);
        if (!hdr)
            return VV_FORMAT_UNKNOWN;
        memcpy(hdr, path, len + 1);
        memcpy(hdr + len - 3, path[len - 3] == 'I' ? "HDR" : "hdr", 3);
        n = read_head(hdr, h, &gz, &err);
        free(hdr);
        if (!gz && nifti_header_kind(h, n) > 0)
            return VV_FORMAT_NIFTI;
    }
    return VV_FORMAT_UNKNOWN;
}

void
vv_load_options_init(vv_load_options *o) {
    if (!o)
        return;
    memset(o, 0, sizeof *o);
    o->format = VV_FORMAT_AUTO;
    o->has_raw = 0;
    vv_raw_params_init(&o->raw);
    o->series = 0;
    o->channel = -1;
}

vv_status
vv_volume_load(vv_volume **out, const char *path, const vv_load_options *opt) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "load: NULL argument");
    *out = NULL;
    vv_format f = opt ? opt->format : VV_FORMAT_AUTO;
    if (f == VV_FORMAT_RAW && !opt->has_raw)
        return vv_error_set(VV_ERR_INVALID,
                            "load: %s: raw format needs the dimensions and voxel type",
                            vv_path_basename(path));
    struct stat st;
    if (stat(path, &st) != 0) {
        int e = errno;
        return vv_error_set(VV_ERR_IO, "cannot open %s: %s", path, strerror(e));
    }
    int is_dir = S_ISDIR(st.st_mode);
    if (!is_dir) {
        FILE *fp = fopen(path, "rb");
        if (!fp) {
            int e = errno;
            return vv_error_set(VV_ERR_IO, "cannot open %s: %s", path, strerror(e));
        }
        fclose(fp);
    }
    if (is_dir && f != VV_FORMAT_AUTO && f != VV_FORMAT_TIFF && f != VV_FORMAT_DICOM)
        return vv_error_set(
            VV_ERR_INVALID,
            "load: %s is a folder (only DICOM and TIFF stacks are read from folders)", path);
    if (f == VV_FORMAT_AUTO) {
        f = vv_format_detect(path);
        if (f == VV_FORMAT_UNKNOWN && opt && opt->has_raw)
            f = VV_FORMAT_RAW;
    }
    vv_status s;
    switch (f) {
    case VV_FORMAT_SLC:
        s = vv_slc_read(out, path);
        break;
    case VV_FORMAT_NRRD:
        s = vv_nrrd_read(out, path);
        break;
    case VV_FORMAT_NIFTI:
        s = vv_nifti_read(out, path);
        break;
    case VV_FORMAT_MHD:
        s = vv_mhd_read(out, path);
        break;
    case VV_FORMAT_VTK:
        s = vv_vtk_read(out, path);
        break;
    case VV_FORMAT_RAW:
        s = vv_raw_read(out, path, &opt->raw);
        break;
    case VV_FORMAT_TIFF:
        s = vv_tiff_read(out, path, opt ? opt->channel : -1);
        break;
    case VV_FORMAT_DICOM:
        s = vv_dicom_read(out, path, opt ? opt->series : 0, opt ? opt->channel : -1);
        break;
    default:
        if (is_dir)
            return vv_error_set(VV_ERR_FORMAT, "%s: no DICOM or TIFF files in the folder", path);
        return vv_error_set(VV_ERR_FORMAT,
                            "cannot tell the format of %s (not SLC, NRRD, NIfTI, MetaImage, VTK "
                            "legacy, TIFF or DICOM; use --raw for raw data)",
                            path);
    }
    if (s != VV_OK) {
        vv_volume_free(*out);
        *out = NULL;
        return s;
    }
    if (!*out)
        return vv_error_set(VV_ERR_FORMAT, "%s: %s: reader returned no volume", vv_format_name(f),
                            vv_path_basename(path));
    /* every reader computes range[]; a reader that left it unset gets it here
     * (a second pass over a large volume costs as much as a fast reader) */
    if ((*out)->range[0] == 0 && (*out)->range[1] == 0)
        vv_volume_update_range(*out);
    return VV_OK;
}

/* A u8 copy of @p v rescaled linearly from range[] to 0..255. */
static vv_status
to_u8(const vv_volume *v, vv_volume **out) {
    vv_volume *u = NULL;
    vv_status s = vv_volume_new(&u, v->dims, VV_U8);
    if (s != VV_OK)
        return s;
    memcpy(u->spacing, v->spacing, sizeof u->spacing);
    memcpy(u->origin, v->origin, sizeof u->origin);
    memcpy(u->direction, v->direction, sizeof u->direction);
    u->unit = v->unit;
    u->data_origin = v->data_origin;
    u->modification = VV_MOD_OTHER;
    double lo = v->range[0], hi = v->range[1];
    double scale = (hi > lo && isfinite(hi - lo)) ? 255.0 / (hi - lo) : 0;
    unsigned char *dst = u->data;
    uint64_t i = 0;
    for (int k = 0; k < v->dims[2]; k++)
        for (int j = 0; j < v->dims[1]; j++)
            for (int x = 0; x < v->dims[0]; x++, i++) {
                double val = vv_volume_get(v, x, j, k);
                double y = (val - lo) * scale;
                if (!(y > 0)) /* also NaN */
                    y = 0;
                if (y > 255)
                    y = 255;
                dst[i] = (unsigned char)lround(y);
            }
    vv_volume_update_range(u);
    *out = u;
    return VV_OK;
}

vv_status
vv_volume_save(const vv_volume *v, const char *path, vv_format format, int strict) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "save: NULL argument");
    if (format == VV_FORMAT_AUTO) {
        if (has_ext(path, "slc"))
            format = VV_FORMAT_SLC;
        else if (has_ext(path, "nrrd") || has_ext(path, "nhdr"))
            format = VV_FORMAT_NRRD;
        else
            return vv_error_set(VV_ERR_INVALID,
                                "save: %s: cannot tell the format from the extension (use .slc, "
                                ".nrrd or .nhdr)",
                                vv_path_basename(path));
    }
    switch (format) {
    case VV_FORMAT_NRRD:
        return vv_nrrd_write(v, path, 1);
    case VV_FORMAT_SLC:
        if (v->type == VV_U8)
            return vv_slc_write(v, path, 1);
        if (strict)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "slc: %s: SLC holds 8-bit voxels only, the volume is %s",
                                vv_path_basename(path), vv_voxel_type_name(v->type));
        {
            vv_volume *u = NULL;
            vv_status s = to_u8(v, &u);
            if (s != VV_OK)
                return vv_error_prefix(s, "slc: %s", vv_path_basename(path));
            s = vv_slc_write(u, path, 1);
            vv_volume_free(u);
            return s;
        }
    default:
        return vv_error_set(VV_ERR_UNSUPPORTED, "save: %s: writing %s is not supported",
                            vv_path_basename(path), vv_format_name(format));
    }
}
