/*
 * Raw volumes: voxels with nothing in the file describing them; the caller
 * gives dimensions, type, byte order, spacing, origin and a header to skip.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/store/bricked.h"
#include "volvis/io.h"
#include "volvis/sys/format.h"

void
vv_raw_params_init(vv_raw_params *p) {
    if (!p)
        return;
    memset(p, 0, sizeof *p);
    p->type = VV_U8;
    p->big_endian = 0;
    for (int a = 0; a < 3; a++) {
        p->spacing[a] = 1.0;
        p->origin[a] = 0.0;
    }
    p->header_skip = 0;
}

static vv_status
raw_read_stream(vv_volume **out, FILE *fp, const vv_raw_params *p) {
    if ((int)p->type < (int)VV_U8 || (int)p->type > (int)VV_F64)
        return vv_error_set(VV_ERR_INVALID, "bad voxel type %d", (int)p->type);
    if (p->dims[0] < 1 || p->dims[1] < 1 || p->dims[2] < 1)
        return vv_error_set(VV_ERR_INVALID, "bad size %d x %d x %d (set dims)", p->dims[0],
                            p->dims[1], p->dims[2]);
    for (int a = 0; a < 3; a++) {
        if (!(p->spacing[a] > 0) || !isfinite(p->spacing[a]))
            return vv_error_set(VV_ERR_INVALID, "bad voxel spacing %g %g %g", p->spacing[0],
                                p->spacing[1], p->spacing[2]);
        if (!isfinite(p->origin[a]))
            return vv_error_set(VV_ERR_INVALID, "bad origin");
    }
    uint64_t bytes;
    vv_status s = vv_volume_check_size(p->dims, p->type, &bytes);
    if (s != VV_OK)
        return s;
    struct stat st;
    if (fstat(fileno(fp), &st) != 0 || !S_ISREG(st.st_mode))
        return vv_error_set(VV_ERR_IO, "not a regular file");
    uint64_t size = (uint64_t)st.st_size;
    if (p->header_skip > size || size - p->header_skip < bytes)
        return vv_error_set(VV_ERR_FORMAT,
                            "file too small: %d x %d x %d %s after a %llu-byte header needs "
                            "%llu bytes, the file has %llu",
                            p->dims[0], p->dims[1], p->dims[2], vv_voxel_type_name(p->type),
                            (unsigned long long)p->header_skip,
                            (unsigned long long)(p->header_skip + bytes), (unsigned long long)size);
    if (fseeko(fp, (off_t)p->header_skip, SEEK_SET) != 0)
        return vv_error_set(VV_ERR_IO, "cannot seek: %s", strerror(errno));

    vv_volume *v = NULL;
    if ((s = vv_volume_new(&v, p->dims, p->type)) != VV_OK)
        return s;
    if (fread(v->data, 1, (size_t)bytes, fp) != (size_t)bytes) {
        vv_volume_free(v);
        return vv_error_set(VV_ERR_IO, "read error: %s",
                            ferror(fp) ? strerror(errno) : "unexpected end of file");
    }
    size_t vs = vv_voxel_type_size(p->type);
    if (vs > 1 && (p->big_endian ? 1 : 0) == vv_host_is_little_endian())
        vv_byteswap(v->data, bytes / vs, vs);
    for (int a = 0; a < 3; a++) {
        v->spacing[a] = p->spacing[a];
        v->origin[a] = p->origin[a];
    }
    v->unit = VV_UNIT_UNKNOWN;
    vv_volume_update_range(v);
    *out = v;
    return VV_OK;
}

vv_status
vv_raw_read(vv_volume **out, const char *path, const vv_raw_params *params) {
    if (!out || !path || !params)
        return vv_error_set(VV_ERR_INVALID, "raw: NULL argument");
    *out = NULL;
    const char *name = vv_path_basename(path);
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return vv_error_set(VV_ERR_IO, "raw: %s: cannot open: %s", name, strerror(errno));
    vv_status s = raw_read_stream(out, fp, params);
    fclose(fp);
    if (s != VV_OK)
        return vv_error_prefix(s, "raw: %s", name);
    return VV_OK;
}

/* ---- the format record ------------------------------------------------------ */

static vv_status
raw_read_record(vv_volume **out, const char *path, const vv_load_options *opt) {
    return vv_raw_read(out, path, &opt->raw);
}

/* A raw file's layout from its description (the raw row's raw_layout). */
vv_status
vv_raw_layout(const char *path, const vv_raw_params *raw, vv_volume **header, char **data_path,
              uint64_t *offset, int *big_endian) {
    const int one[3] = {1, 1, 1};
    *header = NULL;
    *data_path = NULL;
    vv_status s = vv_volume_check_limits(raw->dims, raw->type, NULL);
    if (s == VV_OK)
        s = vv_volume_new(header, one, raw->type);
    if (s == VV_OK && !(*data_path = strdup(path)))
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s != VV_OK) {
        vv_volume_free(*header);
        *header = NULL;
        return s;
    }
    vv_volume *h = *header;
    memcpy(h->dims, raw->dims, sizeof raw->dims);
    memcpy(h->spacing, raw->spacing, sizeof raw->spacing);
    memcpy(h->origin, raw->origin, sizeof raw->origin);
    *offset = raw->header_skip;
    *big_endian = raw->big_endian != 0;
    return VV_OK;
}

static vv_status
raw_layout_record(const char *path, const vv_load_options *opt, vv_volume **header,
                  char **data_path, uint64_t *offset, int *big_endian) {
    if (!opt->has_raw)
        return vv_error_set(VV_ERR_INVALID, "raw: %s: the dimensions and voxel type are needed",
                            vv_path_basename(path));
    return vv_raw_layout(path, &opt->raw, header, data_path, offset, big_endian);
}

const vv_format_record vv_format_raw = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "raw",
    .title = "raw",
    .doc = "raw voxels described by --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]",
    .flags = VV_FORMAT_FLAG_DESCRIBED,
    .read = raw_read_record,
    .raw_layout = raw_layout_record,
};
