/*
 * The MetaImage writer (the reader is mhd.c): ITK's header keys in the order
 * ITK's MetaImageIO writes them, then the voxels, in one file (.mha,
 * ElementDataFile = LOCAL) or beside the header (.mhd + .raw, or .zraw when
 * compressed). Compressed data are one zlib stream (zout.h) with
 * CompressedDataSize, as MetaIO reads them.
 *
 * Geometry: MetaImage's world is ITK's LPS. A volume in RAS (NIfTI) is
 * turned into LPS (x and y negated); others are written as they are.
 * TransformMatrix lists the direction axis by axis (the world direction of
 * i, then of j, then of k), Offset is the position of voxel (0, 0, 0),
 * ElementSpacing the spacing; every number with 17 significant digits, so
 * doubles come back exactly.
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/write_check.h"
#include "io/zout.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

/* Width of the CompressedDataSize field of an .mha, patched after the data. */
#define CSIZE_WIDTH 20

static const char *
met_type(vv_voxel_type t) {
    static const char *const names[] = {"MET_UCHAR", "MET_CHAR", "MET_USHORT", "MET_SHORT",
                                        "MET_UINT",  "MET_INT",  "MET_FLOAT",  "MET_DOUBLE"};
    return (int)t >= 0 && (int)t < 8 ? names[t] : NULL;
}

/* Appends printf output to @p buf (cap @p cap, length *@p len). */
static void
VV_PRINTF(4, 5) add(char *buf, size_t cap, size_t *len, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    int k = *len < cap ? vsnprintf(buf + *len, cap - *len, fmt, ap) : 0;
    va_end(ap);
    if (k > 0)
        *len += (size_t)k;
}

/*
 * The header text of @p v into @p buf. @p csize: the compressed size, or -1
 * for none, or -2 for a field of CSIZE_WIDTH spaces whose offset goes to
 * *@p csize_at. @p datafile: "LOCAL" or the data file's name.
 */
static size_t
header_text(const vv_volume *v, int compressed, long long csize, const char *datafile, char *buf,
            size_t cap, size_t *csize_at) {
    double flip[3] = {1, 1, 1};
    if (v->space == VV_SPACE_RAS)
        flip[0] = flip[1] = -1; /* RAS to ITK's LPS */
    size_t n = 0;
    add(buf, cap, &n, "ObjectType = Image\nNDims = 3\nBinaryData = True\n");
    add(buf, cap, &n, "BinaryDataByteOrderMSB = %s\n",
        vv_host_is_little_endian() ? "False" : "True");
    add(buf, cap, &n, "CompressedData = %s\n", compressed ? "True" : "False");
    if (compressed && csize == -2) {
        add(buf, cap, &n, "CompressedDataSize = ");
        *csize_at = n;
        add(buf, cap, &n, "%*s\n", CSIZE_WIDTH, "");
    } else if (compressed) {
        add(buf, cap, &n, "CompressedDataSize = %lld\n", csize);
    }
    add(buf, cap, &n, "TransformMatrix =");
    for (int a = 0; a < 3; a++)
        for (int r = 0; r < 3; r++)
            add(buf, cap, &n, " %.17g", flip[r] * v->direction[r * 3 + a] + 0.0);
    add(buf, cap, &n, "\nOffset = %.17g %.17g %.17g\n", flip[0] * v->origin[0] + 0.0,
        flip[1] * v->origin[1] + 0.0, v->origin[2]);
    add(buf, cap, &n, "CenterOfRotation = 0 0 0\n");
    add(buf, cap, &n, "ElementSpacing = %.17g %.17g %.17g\n", v->spacing[0], v->spacing[1],
        v->spacing[2]);
    add(buf, cap, &n, "DimSize = %d %d %d\n", v->dims[0], v->dims[1], v->dims[2]);
    add(buf, cap, &n, "ElementType = %s\n", met_type(v->type));
    add(buf, cap, &n, "ElementDataFile = %s\n", datafile);
    return n;
}

/* Writes the voxels of @p v to @p fp (zlib when @p compressed); *@p n the bytes written. */
static vv_status
write_voxels(const vv_volume *v, FILE *fp, int compressed, uint64_t *n) {
    vv_zout *z = NULL;
    vv_status s = vv_zout_begin(&z, fp, compressed ? VV_ZOUT_ZLIB : VV_ZOUT_PLAIN);
    if (s != VV_OK)
        return s;
    s = vv_zout_write(z, v->data, vv_volume_voxel_count(v) * vv_voxel_type_size(v->type));
    if (s != VV_OK) {
        vv_zout_abort(z);
        return s;
    }
    return vv_zout_end(z, n);
}

static vv_status
check_volume(const vv_volume *v) {
    vv_status s = io_write_check_voxels(v, v->data != NULL, met_type(v->type) != NULL);
    return s != VV_OK ? s : io_write_check_geometry(v, 0);
}

/* One .mha: header with a CompressedDataSize field patched after the data. */
static vv_status
write_mha(const vv_volume *v, const char *path, int compressed) {
    char head[2048];
    size_t at = 0, n = header_text(v, compressed, -2, "LOCAL", head, sizeof head, &at);
    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, path);
    if (s != VV_OK)
        return s;
    uint64_t written = 0;
    if (fwrite(head, 1, n, af.fp) != n)
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno ? errno : EIO));
    if (s == VV_OK)
        s = write_voxels(v, af.fp, compressed, &written);
    if (s == VV_OK && compressed) {
        char num[CSIZE_WIDTH + 1];
        snprintf(num, sizeof num, "%-*llu", CSIZE_WIDTH, (unsigned long long)written);
        if (fseeko(af.fp, (off_t)at, SEEK_SET) != 0 ||
            fwrite(num, 1, CSIZE_WIDTH, af.fp) != CSIZE_WIDTH)
            s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno ? errno : EIO));
    }
    if (s != VV_OK) {
        vv_atomic_file_abort(&af);
        return s;
    }
    return vv_atomic_file_commit(&af);
}

/* .mhd + data file beside it (.raw, .zraw compressed): the data first, then
 * the header; the data file is removed when the header cannot be written. */
static vv_status
write_mhd(const vv_volume *v, const char *path, int compressed) {
    size_t len = strlen(path);
    char *data = malloc(len + 2);
    if (!data)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    memcpy(data, path, len - 4);
    strcpy(data + len - 4, compressed ? ".zraw" : ".raw");
    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, data);
    uint64_t written = 0;
    if (s == VV_OK) {
        s = write_voxels(v, af.fp, compressed, &written);
        if (s != VV_OK)
            vv_atomic_file_abort(&af);
        else
            s = vv_atomic_file_commit(&af);
    }
    if (s == VV_OK) {
        char head[2048];
        size_t at = 0;
        size_t n = header_text(v, compressed, (long long)written, vv_path_basename(data), head,
                               sizeof head, &at);
        s = vv_atomic_file_open(&af, path);
        if (s == VV_OK && fwrite(head, 1, n, af.fp) != n) {
            s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno ? errno : EIO));
            vv_atomic_file_abort(&af);
        } else if (s == VV_OK) {
            s = vv_atomic_file_commit(&af);
        }
        if (s != VV_OK)
            unlink(data);
    }
    free(data);
    return s;
}

vv_status
vv_mhd_write(const vv_volume *v, const char *path, int compress) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "mhd: NULL argument");
    int mha = vv_format_path_has_ext(path, "mha");
    vv_status s = check_volume(v);
    if (s == VV_OK && !mha && !vv_format_path_has_ext(path, "mhd"))
        s = vv_error_set(VV_ERR_UNSUPPORTED, "MetaImage is written as .mha or .mhd");
    if (s == VV_OK)
        s = mha ? write_mha(v, path, compress != 0) : write_mhd(v, path, compress != 0);
    if (s != VV_OK)
        return vv_error_prefix(s, "mhd: %s", vv_path_basename(path));
    return VV_OK;
}
