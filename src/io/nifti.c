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

#include "core/internal.h"
#include "volvis/io.h"

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

static vv_status
header_dims(const nifti_image *nim, int dims[3], vv_voxel_type *stored) {
    int64_t ndim = nim->dim[0];
    if (ndim < 1 || ndim > 7)
        return vv_error_set(VV_ERR_FORMAT, "dim[0] is %lld (must be 1 to 7)", (long long)ndim);
    for (int d = 1; d <= ndim; d++)
        if (nim->dim[d] < 1)
            return vv_error_set(VV_ERR_FORMAT, "dim[%d] is %lld", d, (long long)nim->dim[d]);
    for (int d = 4; d <= ndim; d++)
        if (nim->dim[d] != 1)
            return vv_error_set(VV_ERR_UNSUPPORTED,
                                "dim[%d] is %lld: only 3-D volumes (time and other axes of size "
                                "1) are supported",
                                d, (long long)nim->dim[d]);
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

static vv_status
convert_data(vv_volume **out, const nifti_image *nim, const int dims[3], vv_voxel_type stored) {
    double slope = nim->scl_slope, inter = nim->scl_inter;
    int scaled = isfinite(slope) && slope != 0 && !(slope == 1 && inter == 0);
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
        memcpy(v->data, nim->data, (size_t)(count * vv_voxel_type_size(t)));
    } else {
        for (uint64_t i = 0; i < count; i++) {
            double x = stored_value(nim->data, nim->datatype, i);
            if (is64 && !scaled && !exact_int64(nim->data, nim->datatype, i)) {
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

static vv_status
read_locked(vv_volume **out, const char *path) {
    nifti_set_debug_level(0);
    nifti_image *nim = nifti_image_read(path, 0);
    if (!nim)
        return vv_error_set(VV_ERR_FORMAT,
                            "not a readable NIfTI-1/NIfTI-2 or Analyze header (names must end in "
                            ".nii, .nii.gz, .hdr or .img)");
    int dims[3];
    vv_voxel_type stored = VV_U8;
    vv_status s = header_dims(nim, dims, &stored);
    if (s == VV_OK && nim->iname) {
        FILE *f = fopen(nim->iname, "rb");
        if (!f)
            s = vv_error_set(VV_ERR_IO, "cannot open image file %s: %s",
                             vv_path_basename(nim->iname), strerror(errno));
        else
            fclose(f);
    }
    if (s == VV_OK && nifti_image_load(nim) != 0)
        s = vv_error_set(VV_ERR_FORMAT, "cannot read the voxel data (file truncated or corrupt)");
    if (s == VV_OK && !nim->data)
        s = vv_error_set(VV_ERR_FORMAT, "no voxel data");
    if (s == VV_OK)
        s = convert_data(out, nim, dims, stored);
    nifti_image_free(nim);
    return s;
}

vv_status
vv_nifti_read(vv_volume **out, const char *path) {
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
        s = read_locked(out, path);
        pthread_mutex_unlock(&nifti_lock);
    }
    if (s != VV_OK)
        return vv_error_prefix(s, "nifti: %s", vv_path_basename(path));
    return VV_OK;
}
