/*
 * NIfTI-1 and NIfTI-2 volumes through nifti_clib's NIfTI-2 API, which reads
 * both versions, single files (.nii, .nii.gz), header/image pairs (.hdr/.img,
 * also gzip-compressed) and old Analyze 7.5 pairs.
 *
 * nifti_clib keeps global state (debug level, options) and is not documented
 * as thread-safe, so every call into it is made under one mutex. Its debug
 * level is set to 0 so that it never prints; our own messages go to the trace.
 *
 * Orientation: the index-to-world matrix M (4x4, RAS+ "world" space of
 * NIfTI) is the sform when sform_code > 0, else the qform when
 * qform_code > 0, else diag(pixdim) with a zero origin. spacing = column
 * norms of M's upper 3x3, direction = its normalised columns, origin = its
 * translation column; world coordinates are NIfTI's RAS+.
 *
 * Writing (vv_nifti_write): NIfTI-1 (NIfTI-2 when asked or when an axis
 * is longer than 32767 voxels) as one file, .nii or .nii.gz, every voxel
 * type as it is; the header is made by nifti_clib from a nifti_image (the
 * quaternion of the qform by nifti_dmat44_to_quatern), the bytes are
 * written by us through an atomic file (zout.h for gzip). The world of an
 * LPS volume (DICOM) is turned into NIfTI's RAS (x and y negated), the
 * conversion the reader undoes; a volume of another or no frame is written
 * as it is. sform = the full index-to-world matrix; qform = the same when
 * the direction matrix is orthonormal (else qform_code 0: a quaternion
 * cannot hold a shear); both codes NIFTI_XFORM_SCANNER_ANAT. NIfTI-1 holds
 * the matrix, spacing and origin as 32-bit floats, NIfTI-2 as doubles.
 *
 * Values: scl_slope/scl_inter are applied when slope is finite, non-zero and
 * not the identity (1, 0); the volume is then f32, or f64 when the stored type
 * is f64 or a 64-bit integer. Without scaling the stored type is kept;
 * 64-bit integers become f64 when every value is exact in a double.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <nifti/nifti2_io.h>
#include <sys/stat.h>
#include <zlib.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/prescan.h"
#include "io/write_check.h"
#include "io/zout.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

static pthread_mutex_t nifti_lock = PTHREAD_MUTEX_INITIALIZER;

static int
nifti_type_map(int dt, vv_voxel_type *out) {
    switch (dt) {
    case DT_UINT8:
        *out = VV_U8;
        return 1;
    case DT_INT8:
        *out = VV_I8;
        return 1;
    case DT_UINT16:
        *out = VV_U16;
        return 1;
    case DT_INT16:
        *out = VV_I16;
        return 1;
    case DT_UINT32:
        *out = VV_U32;
        return 1;
    case DT_INT32:
        *out = VV_I32;
        return 1;
    case DT_FLOAT32:
        *out = VV_F32;
        return 1;
    case DT_FLOAT64:
    case DT_INT64:
    case DT_UINT64:
        *out = VV_F64;
        return 1;
    default:
        return 0;
    }
}

/* Stored value number @p i of @p data (datatype @p dt) as double. */
static double
stored_value(const void *data, int dt, uint64_t i) {
    switch (dt) {
    case DT_UINT8:
        return ((const uint8_t *)data)[i];
    case DT_INT8:
        return ((const int8_t *)data)[i];
    case DT_UINT16:
        return ((const uint16_t *)data)[i];
    case DT_INT16:
        return ((const int16_t *)data)[i];
    case DT_UINT32:
        return ((const uint32_t *)data)[i];
    case DT_INT32:
        return ((const int32_t *)data)[i];
    case DT_FLOAT32:
        return ((const float *)data)[i];
    case DT_FLOAT64:
        return ((const double *)data)[i];
    case DT_INT64:
        return (double)((const int64_t *)data)[i];
    case DT_UINT64:
        return (double)((const uint64_t *)data)[i];
    }
    return 0;
}

/* 1 when 64-bit integer voxel @p i is exactly representable as a double. */
static int
exact_int64(const void *data, int dt, uint64_t i) {
    const int64_t lim = INT64_C(9007199254740992); /* 2^53 */
    if (dt == DT_INT64) {
        int64_t x = ((const int64_t *)data)[i];
        return x >= -lim && x <= lim;
    }
    return ((const uint64_t *)data)[i] <= (uint64_t)lim;
}

/* The spatial dims, and the time steps (dim[4]) and channels (dim[5]: the
 * components of a vector intent) in @p nt and @p nc. */
static vv_status
header_dims(const nifti_image *nim, int dims[3], vv_voxel_type *stored, int *nt, int *nc) {
    int64_t ndim = nim->dim[0];
    if (ndim < 1 || ndim > 7)
        return vv_error_set(VV_ERR_FORMAT, "dim[0] is %lld (must be 1 to 7)", (long long)ndim);
    for (int d = 1; d <= ndim; d++)
        if (nim->dim[d] < 1)
            return vv_error_set(VV_ERR_FORMAT, "dim[%d] is %lld", d, (long long)nim->dim[d]);
    for (int d = 6; d <= ndim; d++)
        if (nim->dim[d] != 1)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "dim[%d] is %lld: axes past time (dim[4]) and channels (dim[5]) "
                                "must have size 1",
                                d, (long long)nim->dim[d]);
    for (int d = 4; d <= 5; d++) {
        int64_t n = d <= ndim ? nim->dim[d] : 1;
        if (n > VV_VOLUME_MAX_DIM)
            return vv_error_set(VV_ERR_LIMIT, "dim[%d] is %lld (limit %d %s)", d, (long long)n,
                                VV_VOLUME_MAX_DIM, d == 4 ? "time steps" : "channels");
        *(d == 4 ? nt : nc) = (int)n;
    }
    for (int d = 1; d <= 3; d++) {
        int64_t n = d <= ndim ? nim->dim[d] : 1;
        if (n > INT_MAX)
            return vv_error_set(VV_ERR_LIMIT, "dim[%d] is %lld (limit %d)", d, (long long)n,
                                VV_VOLUME_MAX_DIM);
        dims[d - 1] = (int)n;
    }
    if (!nifti_type_map(nim->datatype, stored))
        return vv_error_set(VV_ERR_UNSUPPORTED, "datatype %d (%s) is not supported", nim->datatype,
                            nifti_datatype_string(nim->datatype));
    return vv_volume_check_size(dims, *stored, NULL);
}

static void
set_geometry(vv_volume *v, const nifti_image *nim) {
    double m[3][4] = {{0}};
    if (nim->sform_code > 0 || nim->qform_code > 0) {
        v->space = VV_SPACE_RAS; /* NIfTI's world is RAS by definition */
        const nifti_dmat44 *x = nim->sform_code > 0 ? &nim->sto_xyz : &nim->qto_xyz;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++)
                m[r][c] = x->m[r][c];
    } else {
        for (int i = 0; i < 3; i++) {
            double p = fabs(nim->pixdim[i + 1]);
            m[i][i] = (p > 0 && isfinite(p)) ? p : 1;
        }
    }
    double col[3][3];
    double len[3];
    for (int c = 0; c < 3; c++) {
        len[c] = sqrt(m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c]);
        for (int r = 0; r < 3; r++)
            col[c][r] = (len[c] > 0 && isfinite(len[c])) ? m[r][c] / len[c] : (r == c);
    }
    /* a degenerate column (e.g. the unused third axis of a 2-D image) */
    for (int c = 0; c < 3; c++) {
        if (len[c] > 0 && isfinite(len[c]))
            continue;
        int a = (c + 1) % 3, b = (c + 2) % 3;
        double x[3] = {col[a][1] * col[b][2] - col[a][2] * col[b][1],
                       col[a][2] * col[b][0] - col[a][0] * col[b][2],
                       col[a][0] * col[b][1] - col[a][1] * col[b][0]};
        double l = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        if (l > 0)
            for (int r = 0; r < 3; r++)
                col[c][r] = x[r] / l;
        double p = fabs(nim->pixdim[c + 1]);
        len[c] = (p > 0 && isfinite(p)) ? p : 1;
    }
    for (int c = 0; c < 3; c++) {
        v->spacing[c] = len[c];
        v->origin[c] = isfinite(m[c][3]) ? m[c][3] : 0;
        for (int r = 0; r < 3; r++)
            v->direction[r * 3 + c] = col[c][r];
    }
    switch (nim->xyz_units) {
    case NIFTI_UNITS_METER:
        v->unit = VV_UNIT_METER;
        break;
    case NIFTI_UNITS_MM:
        v->unit = VV_UNIT_MM;
        break;
    case NIFTI_UNITS_MICRON:
        v->unit = VV_UNIT_MICRON;
        break;
    default:
        break;
    }
}

/* 1 when the stored voxels are scaled (scl_slope, scl_inter). */
static int
is_scaled(const nifti_image *nim) {
    double slope = nim->scl_slope, inter = nim->scl_inter;
    return isfinite(slope) && slope != 0 && !(slope == 1 && inter == 0);
}

/* 1 when the stored voxels are the volume's as they are: no scaling and no
 * 64-bit integers to convert. */
static int
stored_as_is(const nifti_image *nim) {
    return !is_scaled(nim) && nim->datatype != DT_INT64 && nim->datatype != DT_UINT64;
}

/* The 3-D volume at @p data (the voxels of one time step and channel). */
static vv_status
convert_data(vv_volume **out, const nifti_image *nim, const void *data, const int dims[3],
             vv_voxel_type stored) {
    double slope = nim->scl_slope, inter = nim->scl_inter;
    int scaled = is_scaled(nim);
    if (!isfinite(inter))
        inter = 0;
    int is64 = nim->datatype == DT_INT64 || nim->datatype == DT_UINT64;
    vv_voxel_type t = stored;
    if (scaled)
        t = (nim->datatype == DT_FLOAT64 || is64) ? VV_F64 : VV_F32;
    vv_volume *v = NULL;
    vv_status s = vv_volume_new(&v, dims, t);
    if (s != VV_OK)
        return s;
    uint64_t count = vv_volume_voxel_count(v);
    if ((uint64_t)nim->nvox < count || (size_t)nim->nbyper != vv_voxel_type_size(stored)) {
        vv_volume_free(v);
        return vv_error_set(VV_ERR_FORMAT, "data size does not match the header");
    }
    if (!scaled && !is64) {
        memcpy(v->data, data, (size_t)(count * vv_voxel_type_size(t)));
    } else {
        for (uint64_t i = 0; i < count; i++) {
            double x = stored_value(data, nim->datatype, i);
            if (is64 && !scaled && !exact_int64(data, nim->datatype, i)) {
                vv_volume_free(v);
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "64-bit integer voxel %llu (%.17g) cannot be held exactly in "
                                    "a double",
                                    (unsigned long long)i, x);
            }
            double y = scaled ? x * slope + inter : x;
            if (t == VV_F32)
                ((float *)v->data)[i] = (float)y;
            else
                ((double *)v->data)[i] = y;
        }
    }
    set_geometry(v, nim);
    v->modification = VV_MOD_ORIGINAL;
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

/* Reads the @p size-byte integer at @p p in the byte order given by @p swap. */
static int64_t
raw_int(const unsigned char *p, int size, int swap) {
    unsigned char b[8];
    for (int i = 0; i < size; i++)
        b[i] = swap ? p[size - 1 - i] : p[i];
    if (!vv_host_is_little_endian())
        for (int i = 0; i < size / 2; i++) {
            unsigned char t = b[i];
            b[i] = b[size - 1 - i];
            b[size - 1 - i] = t;
        }
    if (size == 2) {
        int16_t v;
        memcpy(&v, b, 2);
        return v;
    }
    if (size == 4) {
        int32_t v;
        memcpy(&v, b, 4);
        return v;
    }
    int64_t v;
    memcpy(&v, b, 8);
    return v;
}

static double
raw_float(const unsigned char *p, int swap) {
    uint32_t u = (uint32_t)raw_int(p, 4, swap);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* 1 when @p path starts with the gzip magic; *size gets its size. */
static int
file_gzipped(const char *path, uint64_t *size) {
    struct stat st;
    *size = 0;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return 0;
    *size = (uint64_t)st.st_size;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    unsigned char m[2] = {0, 0};
    size_t got = fread(m, 1, 2, f);
    fclose(f);
    return got == 2 && m[0] == 0x1f && m[1] == 0x8b;
}

/*
 * Checks the raw header's fields before nifti_clib sees the file (it trusts
 * them: an absurd dim[0] or dimension overflows inside it): sizeof_hdr 348
 * (NIfTI-1, Analyze) or 540 (NIfTI-2) in either byte order, a whole header,
 * dim[0] in 1..7, every used dim[i] in 1..VV_VOLUME_MAX_DIM, bitpix a
 * positive multiple of 8, a finite vox_offset; then that the image data can
 * hold what the header promises (uncompressed: the bytes themselves; gzip:
 * 1/1032 of them, deflate's largest ratio), so a small file never makes the
 * library allocate or inflate gigabytes.
 */
vv_status
vv_nifti_prescan(const char *path) {
    /* nifti_clib takes x.img (.img.gz) for its header x.hdr (.hdr.gz) */
    char hdr[4096];
    size_t plen = strlen(path);
    if (plen < sizeof hdr) {
        const char *ext = plen >= 7 && !strcmp(path + plen - 7, ".img.gz") ? ".img.gz"
                          : plen >= 4 && !strcmp(path + plen - 4, ".img")  ? ".img"
                                                                           : NULL;
        if (ext) {
            memcpy(hdr, path, plen + 1);
            memcpy(hdr + plen - strlen(ext), ".hdr", 4);
            struct stat st;
            if (stat(hdr, &st) != 0) /* the other compression */
                snprintf(hdr + plen - strlen(ext), sizeof hdr - (plen - strlen(ext)), "%s",
                         strlen(ext) == 4 ? ".hdr.gz" : ".hdr");
            if (stat(hdr, &st) == 0)
                path = hdr;
        }
    }
    gzFile gz = gzopen(path, "rb");
    if (!gz)
        return vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(errno));
    unsigned char h[540];
    int n = gzread(gz, h, sizeof h);
    gzclose(gz);
    if (n < 4)
        return vv_error_set(VV_ERR_FORMAT, "%d bytes: too short for a NIfTI header", n < 0 ? 0 : n);
    int swap = 0, v2 = 0;
    int64_t hs = raw_int(h, 4, 0);
    if (hs != 348 && hs != 540) {
        swap = 1;
        hs = raw_int(h, 4, 1);
    }
    if (hs != 348 && hs != 540)
        return vv_error_set(VV_ERR_FORMAT,
                            "sizeof_hdr is %lld (348 for NIfTI-1 and Analyze, 540 for NIfTI-2)",
                            (long long)raw_int(h, 4, 0));
    v2 = hs == 540;
    if (n < hs)
        return vv_error_set(VV_ERR_FORMAT, "header truncated (%d of %lld bytes)", n, (long long)hs);
    int64_t dim[8];
    for (int i = 0; i < 8; i++)
        dim[i] = v2 ? raw_int(h + 16 + 8 * i, 8, swap) : raw_int(h + 40 + 2 * i, 2, swap);
    if (dim[0] < 1 || dim[0] > 7)
        return vv_error_set(VV_ERR_FORMAT, "dim[0] is %lld (must be 1 to 7)", (long long)dim[0]);
    uint64_t count = 1;
    for (int i = 1; i <= dim[0]; i++) {
        if (dim[i] < 1 || dim[i] > VV_VOLUME_MAX_DIM)
            return vv_error_set(dim[i] < 1 ? VV_ERR_FORMAT : VV_ERR_LIMIT,
                                "dim[%d] is %lld (must be 1 to %d)", i, (long long)dim[i],
                                VV_VOLUME_MAX_DIM);
        if (count > UINT64_MAX / (uint64_t)dim[i])
            return vv_error_set(VV_ERR_LIMIT, "the dimensions' product overflows");
        count *= (uint64_t)dim[i];
    }
    int64_t bitpix = v2 ? raw_int(h + 14, 2, swap) : raw_int(h + 72, 2, swap);
    if (bitpix < 8 || bitpix % 8 != 0)
        return vv_error_set(VV_ERR_FORMAT, "bitpix is %lld (a multiple of 8 expected)",
                            (long long)bitpix);
    double off = v2 ? (double)raw_int(h + 168, 8, swap) : raw_float(h + 108, swap);
    if (!isfinite(off) || off < 0 || off > 1e15)
        return vv_error_set(VV_ERR_FORMAT, "vox_offset %g is out of range", off);
    if (count > UINT64_MAX / (uint64_t)(bitpix / 8))
        return vv_error_set(VV_ERR_LIMIT, "the data size overflows");
    uint64_t need = count * (uint64_t)(bitpix / 8);
    /* where the image data are: this file (magic "n+1"/"n+2"), else the
     * .img beside a .hdr (plain or gzip-compressed) */
    const unsigned char *magic = v2 ? h + 4 : h + 344;
    int single = magic[0] == 'n' && magic[1] == '+' && (magic[2] == '1' || magic[2] == '2');
    /* one file: only the volume of one time step and channel is read;
     * nifti_clib loads the whole image of a .hdr/.img pair */
    uint64_t held = need;
    if (single)
        for (int i = 4; i <= dim[0]; i++)
            held /= (uint64_t)dim[i];
    if (held > VV_VOLUME_MAX_BYTES)
        return vv_error_set(VV_ERR_LIMIT, "%llu bytes of voxels (limit %llu)",
                            (unsigned long long)held, (unsigned long long)VV_VOLUME_MAX_BYTES);
    vv_status sb = vv_memory_budget_check(held, "NIfTI voxel data");
    if (sb != VV_OK)
        return sb;

    char img[4096];
    const char *data = NULL;
    uint64_t start = 0;
    if (single) {
        data = path;
        start = (uint64_t)off;
    } else {
        size_t len = strlen(path);
        const char *ext = len >= 7 && !strcmp(path + len - 7, ".hdr.gz") ? ".hdr.gz"
                          : len >= 4 && !strcmp(path + len - 4, ".hdr")  ? ".hdr"
                                                                         : NULL;
        if (ext && len < sizeof img) {
            memcpy(img, path, len + 1);
            memcpy(img + len - strlen(ext), ".img", 4);
            struct stat st;
            if (stat(img, &st) != 0) /* nifti_clib also tries the other compression */
                snprintf(img + len - strlen(ext), sizeof img - (len - strlen(ext)), "%s",
                         strlen(ext) == 4 ? ".img.gz" : ".img");
            data = img;
            start = (uint64_t)off;
        }
    }
    uint64_t size = 0;
    if (data) {
        int gzipped = file_gzipped(data, &size);
        uint64_t have = gzipped        ? (size > UINT64_MAX / 1032 ? UINT64_MAX : size * 1032)
                        : size > start ? size - start
                                       : 0;
        uint64_t want = gzipped ? need + start : need;
        if (size > 0 && have < want)
            return vv_error_set(
                VV_ERR_FORMAT,
                "%s%s holds %llu bytes, too few for the %llu bytes of voxels the "
                "header promises",
                gzipped ? "compressed " : "", data == path ? "the file" : "the image",
                (unsigned long long)(size > start && !gzipped ? size - start : size),
                (unsigned long long)need);
    }
    return VV_OK;
}

static vv_status
read_locked(vv_volume **out, const char *path, int channel, int time, vv_load_info *info) {
    vv_status s0 = vv_nifti_prescan(path);
    if (s0 != VV_OK)
        return s0;
    nifti_set_debug_level(0);
    nifti_image *nim = nifti_image_read(path, 0);
    if (!nim)
        return vv_error_set(VV_ERR_FORMAT,
                            "not a readable NIfTI-1/NIfTI-2 or Analyze header (names must end in "
                            ".nii, .nii.gz, .hdr or .img)");
    int dims[3], nt = 1, nc = 1;
    vv_voxel_type stored = VV_U8;
    vv_volume *direct = NULL; /* the volume read into, when stored as it is */
    vv_status s = header_dims(nim, dims, &stored, &nt, &nc);
    int ch = channel < 0 ? 0 : channel, tp = time < 0 ? 0 : time;
    if (s == VV_OK && ch >= nc)
        s = vv_error_set(VV_ERR_INVALID, "channel %d asked, the file has %d channel%s (dim[5])", ch,
                         nc, nc == 1 ? "" : "s");
    if (s == VV_OK && tp >= nt)
        s = vv_error_set(VV_ERR_INVALID, "time step %d asked, the file has %d time step%s (dim[4])",
                         tp, nt, nt == 1 ? "" : "s");
    /* the volume (tp, ch): NIfTI's order is x fastest, then y, z, t, channel */
    int64_t vol_bytes = s == VV_OK ? (int64_t)dims[0] * dims[1] * dims[2] * nim->nbyper : 0;
    int64_t vol_index = (int64_t)ch * nt + tp;
    int one_file =
        nim->nifti_type == NIFTI_FTYPE_NIFTI1_1 || nim->nifti_type == NIFTI_FTYPE_NIFTI2_1;
    if (s == VV_OK && one_file) {
        /* one file: the voxels follow the header in @p path, read here.
         * nifti_image_load looks the image file up again by its base name
         * and takes x.nii before the x.nii.gz it was given (the voxels of
         * another file) */
        struct stat a, b;
        if (!nim->fname || stat(nim->fname, &a) != 0 || stat(path, &b) != 0 ||
            a.st_dev != b.st_dev || a.st_ino != b.st_ino)
            s = vv_error_set(VV_ERR_FORMAT, "nifti_clib read the header of %s, not of this file",
                             nim->fname ? vv_path_basename(nim->fname) : "another file");
        int64_t bytes = s == VV_OK ? vol_bytes : 0;
        znzFile fp = NULL;
        /* voxels stored as they are go straight into the volume: one buffer
         * of the volume's size is allocated and filled, not two */
        void *dst = NULL;
        if (s == VV_OK && stored_as_is(nim)) {
            if ((s = vv_volume_new(&direct, dims, stored)) == VV_OK)
                dst = direct->data;
        } else if (s == VV_OK && !(dst = nim->data = malloc(bytes > 0 ? (size_t)bytes : 1))) {
            s = vv_error_set(VV_ERR_NOMEM, "out of memory for %lld bytes", (long long)bytes);
        }
        if (s == VV_OK && znz_isnull(fp = znzopen(path, "rb", nifti_is_gzfile(path))))
            s = vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(errno));
        if (s == VV_OK &&
            (znzseek(fp, (znz_off_t)(nim->iname_offset + vol_index * vol_bytes), SEEK_SET) < 0 ||
             nifti_read_buffer(fp, dst, bytes, nim) != bytes))
            s = vv_error_set(VV_ERR_FORMAT,
                             "cannot read the voxel data (file truncated or corrupt)");
        if (!znz_isnull(fp))
            znzclose(fp);
    }
    if (s == VV_OK && !one_file && nim->iname) {
        FILE *f = fopen(nim->iname, "rb");
        if (!f)
            s = vv_error_set(VV_ERR_IO, "cannot open image file %s: %s",
                             vv_path_basename(nim->iname), strerror(errno));
        else
            fclose(f);
    }
    if (s == VV_OK && !one_file && nifti_image_load(nim) != 0)
        s = vv_error_set(VV_ERR_FORMAT, "cannot read the voxel data (file truncated or corrupt)");
    if (s == VV_OK && direct) {
        set_geometry(direct, nim);
        direct->modification = VV_MOD_ORIGINAL;
        vv_volume_update_range(direct);
        *out = direct;
        direct = NULL;
    } else if (s == VV_OK && !nim->data) {
        s = vv_error_set(VV_ERR_FORMAT, "no voxel data");
    } else if (s == VV_OK) {
        s = convert_data(out, nim,
                         one_file ? nim->data : (const char *)nim->data + vol_index * vol_bytes,
                         dims, stored);
    }
    vv_volume_free(direct);
    if (s == VV_OK && info) {
        /* uncompressed one file, stored as it is: later steps can be read
         * by offset (vv_time_series) */
        if (one_file && stored_as_is(nim) && !nifti_is_gzfile(path)) {
            info->has_raw_layout = 1;
            info->raw_big_endian = nim->byteorder == 2; /* nifti_clib's MSB_FIRST */
            info->raw_offset = (uint64_t)nim->iname_offset;
            info->raw_step_bytes = (uint64_t)vol_bytes;
            info->raw_channel_bytes = (uint64_t)vol_bytes * (uint64_t)nt;
        }
        info->n_channels = nc;
        info->n_times = nt;
        double step = nim->dt > 0 && isfinite(nim->dt) ? nim->dt : 0;
        info->time_step = nim->time_units == NIFTI_UNITS_MSEC   ? step * 1e-3
                          : nim->time_units == NIFTI_UNITS_USEC ? step * 1e-6
                          : nim->time_units == NIFTI_UNITS_SEC  ? step
                                                                : 0;
    }
    nifti_image_free(nim);
    return s;
}

static vv_status
nifti_read_at(vv_volume **out, const char *path, int channel, int time, vv_load_info *info) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "nifti: NULL argument");
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) {
        int e = errno;
        vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(e));
        return vv_error_prefix(VV_ERR_IO, "nifti: %s", vv_path_basename(path));
    }
    int c = fgetc(f);
    fclose(f);
    vv_status s;
    if (c == EOF) {
        s = vv_error_set(VV_ERR_FORMAT, "empty file");
    } else {
        pthread_mutex_lock(&nifti_lock);
        s = read_locked(out, path, channel, time, info);
        pthread_mutex_unlock(&nifti_lock);
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "nifti: %s", vv_path_basename(path));
    return VV_OK;
}

vv_status
vv_nifti_read(vv_volume **out, const char *path) {
    return nifti_read_at(out, path, -1, -1, NULL);
}

/* ---- writing ------------------------------------------------------------------ */

static int
nifti_datatype_of(vv_voxel_type t) {
    static const int map[] = {DT_UINT8,  DT_INT8,  DT_UINT16,  DT_INT16,
                              DT_UINT32, DT_INT32, DT_FLOAT32, DT_FLOAT64};
    return (int)t >= 0 && (int)t < 8 ? map[t] : DT_UNKNOWN;
}

/* The unit a spacing in @p u is written in, *scale its factor: feet and inches,
 * which NIfTI cannot name, in millimetres; nanometres in microns; the rest as
 * they are (1). */
static vv_unit
written_unit(vv_unit u, double *scale) {
    *scale = u == VV_UNIT_FOOT ? 304.8 : u == VV_UNIT_INCH ? 25.4 : u == VV_UNIT_NM ? 1e-3 : 1;
    return u == VV_UNIT_FOOT || u == VV_UNIT_INCH ? VV_UNIT_MM
           : u == VV_UNIT_NM                      ? VV_UNIT_MICRON
                                                  : u;
}

static int
nifti_fits(const vv_volume *v, char *why, size_t cap) {
    double scale;
    const vv_unit w = written_unit(v->unit, &scale);
    if (w != v->unit) {
        snprintf(why, cap,
                 "NIfTI holds metres, millimetres or microns, the spacing is in %s "
                 "(written in %s)",
                 vv_unit_name(v->unit), w == VV_UNIT_MM ? "millimetres" : "microns");
        return 0;
    }
    return 1;
}

/* 1 when the columns of @p d (row-major) are orthonormal to 1e-6. */
static int
orthonormal(const double d[9]) {
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++) {
            double dot = 0;
            for (int r = 0; r < 3; r++)
                dot += d[r * 3 + a] * d[r * 3 + b];
            if (fabs(dot - (a == b)) > 1e-6)
                return 0;
        }
    return 1;
}

/*
 * The header of @p v (and its 4-byte extension flag, all zero) into @p buf
 * (at least 544 bytes), *@p len its size (352 or 544): nifti_clib builds it
 * from a nifti_image. Called under nifti_lock.
 */
static vv_status
make_header(const vv_volume *v, const vv_save_options *opt, int version, unsigned char *buf,
            size_t *len) {
    int64_t dims[8] = {3, v->dims[0], v->dims[1], v->dims[2], 1, 1, 1, 1};
    nifti_set_debug_level(0);
    nifti_image *nim = nifti_make_new_nim(dims, nifti_datatype_of(v->type), 0);
    if (!nim)
        return vv_error_set(VV_ERR_NOMEM, "nifti_clib cannot make the header");
    double scale;
    const vv_unit unit = written_unit(v->unit, &scale);
    /* LPS to RAS: x and y change sign */
    double flip[3] = {1, 1, 1};
    if (v->space == VV_SPACE_LPS)
        flip[0] = flip[1] = -1;
    nifti_dmat44 m;
    memset(&m, 0, sizeof m);
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++)
            m.m[r][c] = flip[r] * v->direction[r * 3 + c] * v->spacing[c] * scale;
        m.m[r][3] = flip[r] * v->origin[r] * scale;
    }
    m.m[3][3] = 1;
    for (int c = 0; c < 3; c++)
        nim->pixdim[c + 1] = v->spacing[c] * scale;
    nim->dx = nim->pixdim[1];
    nim->dy = nim->pixdim[2];
    nim->dz = nim->pixdim[3];
    nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
    nim->sto_xyz = m;
    nim->qform_code = NIFTI_XFORM_UNKNOWN;
    if (orthonormal(v->direction)) {
        double dx, dy, dz;
        nifti_dmat44_to_quatern(m, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d,
                                &nim->qoffset_x, &nim->qoffset_y, &nim->qoffset_z, &dx, &dy, &dz,
                                &nim->qfac);
        nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
        nim->qto_xyz = m;
    }
    nim->pixdim[0] = nim->qfac;
    switch (unit) {
    case VV_UNIT_METER:
        nim->xyz_units = NIFTI_UNITS_METER;
        break;
    case VV_UNIT_MM:
        nim->xyz_units = NIFTI_UNITS_MM;
        break;
    case VV_UNIT_MICRON:
        nim->xyz_units = NIFTI_UNITS_MICRON;
        break;
    default:
        nim->xyz_units = NIFTI_UNITS_UNKNOWN;
        break;
    }
    nim->time_units = NIFTI_UNITS_UNKNOWN; /* no time axis */
    nim->scl_slope = 1;
    nim->scl_inter = 0;
    nim->intent_code = opt->label ? NIFTI_INTENT_LABEL : NIFTI_INTENT_NONE;
    snprintf(nim->descrip, sizeof nim->descrip, "VolVis");
    nim->nifti_type = version == 2 ? NIFTI_FTYPE_NIFTI2_1 : NIFTI_FTYPE_NIFTI1_1;
    nim->iname_offset = version == 2 ? 544 : 352;
    memset(buf, 0, 544);
    int bad;
    if (version == 2) {
        nifti_2_header h;
        bad = nifti_convert_nim2n2hdr(nim, &h);
        h.vox_offset = 544; /* the conversion leaves it 0: data right after the header */
        memcpy(buf, &h, sizeof h);
        *len = 544;
    } else {
        nifti_1_header h;
        bad = nifti_convert_nim2n1hdr(nim, &h);
        h.vox_offset = 352; /* the conversion leaves it 0: data right after the header */
        memcpy(buf, &h, sizeof h);
        *len = 352;
    }
    nifti_image_free(nim);
    if (bad)
        return vv_error_set(VV_ERR_INVALID, "nifti_clib cannot convert the header");
    return VV_OK;
}

static vv_status
check_writable(const vv_volume *v, const vv_save_options *opt, int *version) {
    vv_status s =
        io_write_check_voxels(v, v->data != NULL, nifti_datatype_of(v->type) != DT_UNKNOWN);
    if (s != VV_OK)
        return s;
    if (opt->label && (v->type == VV_F32 || v->type == VV_F64))
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "a label volume must hold integers, the volume is %s",
                            vv_voxel_type_name(v->type));
    if ((s = io_write_check_geometry(v, 0)) != VV_OK)
        return s;
    int need2 = v->dims[0] > 32767 || v->dims[1] > 32767 || v->dims[2] > 32767;
    if (opt->nifti_version != 0 && opt->nifti_version != 1 && opt->nifti_version != 2)
        return vv_error_set(VV_ERR_INVALID, "NIfTI version %d (1 or 2)", opt->nifti_version);
    if (opt->nifti_version == 1 && need2)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "NIfTI-1 holds at most 32767 voxels per axis, the volume is %d x %d "
                            "x %d (write NIfTI-2)",
                            v->dims[0], v->dims[1], v->dims[2]);
    *version = opt->nifti_version ? opt->nifti_version : need2 ? 2 : 1;
    return VV_OK;
}

vv_status
vv_nifti_write(const vv_volume *v, const char *path, const vv_save_options *opt) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "nifti: NULL argument");
    vv_save_options defaults;
    vv_save_options_init(&defaults);
    if (!opt)
        opt = &defaults;
    int gz = vv_format_path_has_ext(path, "nii.gz"), version = 1;
    vv_status s = VV_OK;
    if (!gz && !vv_format_path_has_ext(path, "nii"))
        s = vv_error_set(VV_ERR_UNSUPPORTED,
                         "NIfTI is written as one file named .nii or .nii.gz (not as a "
                         ".hdr/.img pair)");
    if (s == VV_OK)
        s = check_writable(v, opt, &version);
    unsigned char hdr[544];
    size_t hlen = 0;
    if (s == VV_OK) {
        pthread_mutex_lock(&nifti_lock);
        s = make_header(v, opt, version, hdr, &hlen);
        pthread_mutex_unlock(&nifti_lock);
    }
    vv_atomic_file af;
    if (s == VV_OK)
        s = vv_atomic_file_open(&af, path);
    if (s != VV_OK)
        return vv_error_prefix(s, "nifti: %s", vv_path_basename(path));
    vv_zout *z = NULL;
    s = vv_zout_begin(&z, af.fp, gz ? VV_ZOUT_GZIP : VV_ZOUT_PLAIN);
    if (s == VV_OK)
        s = vv_zout_write(z, hdr, hlen);
    if (s == VV_OK)
        s = vv_zout_write(z, v->data, vv_volume_voxel_count(v) * vv_voxel_type_size(v->type));
    if (s == VV_OK) {
        s = vv_zout_end(z, NULL);
        z = NULL;
    }
    vv_zout_abort(z);
    if (s == VV_OK)
        s = vv_atomic_file_commit(&af);
    else
        vv_atomic_file_abort(&af);
    if (s != VV_OK)
        return vv_error_prefix(s, "nifti: %s", vv_path_basename(path));
    return VV_OK;
}

static vv_status
nifti_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_nifti_write(v, path, opt);
}

/* ---- the format record ------------------------------------------------------ */

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

/* A NIfTI header (also gzip-compressed), or an Analyze header named .hdr;
 * at @p deep 1, the image half of a .hdr/.img pair: the header beside it. */
static int
nifti_looks_like(const vv_format_probe *p, int deep) {
    if (p->is_dir)
        return 0;
    if (!deep) {
        int nk = nifti_header_kind(p->head, p->n);
        if (p->gzip)
            return nk == 2 || (nk == 1 && strstr(vv_path_basename(p->path), ".hdr"));
        return nk == 2 || (nk == 1 && vv_format_path_has_ext(p->path, "hdr"));
    }
    if (p->gzip || !vv_format_path_has_ext(p->path, "img"))
        return 0;
    size_t len = strlen(p->path);
    char *hdr = malloc(len + 1);
    if (!hdr)
        return 0;
    memcpy(hdr, p->path, len + 1);
    memcpy(hdr + len - 3, p->path[len - 3] == 'I' ? "HDR" : "hdr", 3);
    unsigned char buf[VV_FORMAT_PROBE_BYTES + 1];
    char text[VV_FORMAT_PROBE_BYTES + 1];
    vv_format_probe h;
    vv_format_probe_fill(&h, hdr, buf, text);
    free(hdr);
    return !h.gzip && nifti_header_kind(h.head, h.n) > 0;
}

static vv_status
nifti_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    return nifti_read_at(out, path, opt->channel, opt->time, opt->info);
}

static const char *const nifti_extensions[] = {"nii", "nii.gz", "hdr", "img", NULL};
static const char *const nifti_aliases[] = {"nii", "hdr", NULL};
static const char *const nifti_write_extensions[] = {"nii", "nii.gz", NULL};

const vv_format_record vv_format_nifti = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "nifti",
    .title = "NIfTI",
    .extensions = nifti_extensions,
    .write_extensions = nifti_write_extensions,
    .aliases = nifti_aliases,
    .doc = "NIfTI-1 and NIfTI-2 through nifti_clib: scaling applied, qform/sform geometry; "
           "writes .nii/.nii.gz, every voxel type, qform+sform (LPS turned to RAS), units, "
           "intent LABEL with --label",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY | VV_FORMAT_FLAG_GZIP,
    .looks_like = nifti_looks_like,
    .fits = nifti_fits,
    .read = nifti_read_record,
    .write = nifti_write_record,
};
