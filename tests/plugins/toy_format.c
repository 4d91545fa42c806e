/*
 * A toy volume format in one file: the whole of what a new format takes
 * (include/volvis/sys/format.h). A .toy file is a text header
 *
 *     TOYVOL\n
 *     W H D\n          the voxels along x, y, z
 *     SX SY SZ\n       the spacing, millimetres
 *
 * then W * H * D unsigned 8-bit voxels, x fastest. Its row names it,
 * detects it by its first line, reads it, writes it and tells where its
 * voxels lie raw (so that vv_open reads it out of core by bricks). The
 * test registers the row (vv_format_register) and uses it through the
 * library's own calls (tests/plugins/test_toy.c).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "toy.h"
#include "volvis/sys/format.h"

#define TOY_MAGIC "TOYVOL\n"
#define TOY_HEADER_MAX 256

static int
toy_looks_like(const vv_format_probe *p, int deep) {
    (void)deep;
    return !p->is_dir && p->n >= strlen(TOY_MAGIC) &&
           !memcmp(p->head, TOY_MAGIC, strlen(TOY_MAGIC));
}

/* The header of @p f: dims, spacing, and the offset of the first voxel.
 * Checks the sizes against the limits and the file's length first. */
static vv_status
toy_header(FILE *f, const char *path, int dims[3], double spacing[3], long *offset) {
    char line[TOY_HEADER_MAX];
    if (!fgets(line, sizeof line, f) || strcmp(line, TOY_MAGIC) != 0)
        return vv_error_set(VV_ERR_FORMAT, "toy: %s: no TOYVOL line", path);
    if (!fgets(line, sizeof line, f) || sscanf(line, "%d %d %d", &dims[0], &dims[1], &dims[2]) != 3)
        return vv_error_set(VV_ERR_FORMAT, "toy: %s: no dimensions line", path);
    if (!fgets(line, sizeof line, f) ||
        sscanf(line, "%lf %lf %lf", &spacing[0], &spacing[1], &spacing[2]) != 3)
        return vv_error_set(VV_ERR_FORMAT, "toy: %s: no spacing line", path);
    for (int a = 0; a < 3; a++)
        if (!(spacing[a] > 0))
            return vv_error_set(VV_ERR_FORMAT, "toy: %s: spacing %g along axis %d", path,
                                spacing[a], a);
    uint64_t bytes = 0;
    vv_status s = vv_volume_check_size(dims, VV_U8, &bytes);
    if (s != VV_OK)
        return vv_error_prefix(s, "toy: %s", path);
    *offset = ftell(f);
    if (fseek(f, 0, SEEK_END) != 0 || (uint64_t)(ftell(f) - *offset) < bytes)
        return vv_error_set(VV_ERR_FORMAT, "toy: %s: shorter than its %llu voxels", path,
                            (unsigned long long)bytes);
    return fseek(f, *offset, SEEK_SET) == 0 ? VV_OK
                                            : vv_error_set(VV_ERR_IO, "toy: %s: cannot seek", path);
}

static vv_status
toy_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    (void)opt;
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "toy: cannot open %s", path);
    int dims[3];
    double sp[3];
    long off = 0;
    vv_volume *v = NULL;
    vv_status s = toy_header(f, path, dims, sp, &off);
    if (s == VV_OK)
        s = vv_volume_new(&v, dims, VV_U8);
    if (s == VV_OK) {
        const size_t n = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
        if (fread(v->data, 1, n, f) != n)
            s = vv_error_set(VV_ERR_IO, "toy: %s: read failed", path);
        memcpy(v->spacing, sp, sizeof sp);
        v->unit = VV_UNIT_MM;
        vv_volume_update_range(v);
    }
    fclose(f);
    if (s != VV_OK) {
        vv_volume_free(v);
        return s;
    }
    *out = v;
    return VV_OK;
}

static int
toy_fits(const vv_volume *v, char *why, size_t cap) {
    if (v->type == VV_U8)
        return 1;
    snprintf(why, cap, "a toy volume holds 8-bit voxels only, the volume is %s",
             vv_voxel_type_name(v->type));
    return 0;
}

static vv_status
toy_write(const vv_volume *v, const char *path, const vv_save_options *opt) {
    (void)opt;
    if (v->type != VV_U8)
        return vv_error_set(VV_ERR_UNSUPPORTED, "toy: %s: 8-bit voxels only", path);
    char tmp[4096];
    if (snprintf(tmp, sizeof tmp, "%s.part", path) >= (int)sizeof tmp)
        return vv_error_set(VV_ERR_LIMIT, "toy: %s: path too long", path);
    FILE *f = fopen(tmp, "wb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "toy: cannot write %s", tmp);
    const size_t n = (size_t)v->dims[0] * (size_t)v->dims[1] * (size_t)v->dims[2];
    int ok = fprintf(f, "%s%d %d %d\n%.17g %.17g %.17g\n", TOY_MAGIC, v->dims[0], v->dims[1],
                     v->dims[2], v->spacing[0], v->spacing[1], v->spacing[2]) > 0;
    ok = ok && fwrite(v->data, 1, n, f) == n;
    ok = (fclose(f) == 0) && ok;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        return vv_error_set(VV_ERR_IO, "toy: cannot write %s", path);
    }
    return VV_OK;
}

static vv_status
toy_raw_layout(const char *path, const vv_load_options *opt, vv_volume **header, char **data_path,
               uint64_t *offset, int *big_endian) {
    (void)opt;
    FILE *f = fopen(path, "rb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "toy: cannot open %s", path);
    int dims[3];
    double sp[3];
    long off = 0;
    vv_status s = toy_header(f, path, dims, sp, &off);
    fclose(f);
    if (s != VV_OK)
        return s;
    const int one[3] = {1, 1, 1};
    if ((s = vv_volume_new(header, one, VV_U8)) != VV_OK)
        return s;
    memcpy((*header)->dims, dims, sizeof dims);
    memcpy((*header)->spacing, sp, sizeof sp);
    (*header)->unit = VV_UNIT_MM;
    if (!(*data_path = strdup(path))) {
        vv_volume_free(*header);
        *header = NULL;
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    *offset = (uint64_t)off;
    *big_endian = 0;
    return VV_OK;
}

static const char *const toy_ext[] = {"toy", NULL};

const vv_format_record toy_format = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "toy",
    .title = "toy volume",
    .extensions = toy_ext,
    .doc = "a text header (TOYVOL, dims, spacing) and 8-bit voxels (a test's format)",
    .holds = VV_DATA_VOLUME,
    .looks_like = toy_looks_like,
    .fits = toy_fits,
    .read = toy_read,
    .write = toy_write,
    .raw_layout = toy_raw_layout,
};
