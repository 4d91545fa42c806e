/*
 * A volume read slab by slab (vv_slabs, volvis/io.h): boxes of a volume
 * larger than memory from a format whose reader decodes a range of slices
 * (VV_FORMAT_FLAG_SLICES: TIFF stacks), through vv_volume_load and so
 * through the reader sandbox. The slices of the last box are kept, so the
 * boxes of one slab that a writer asks for in turn (vv_ome_zarr_write_boxes:
 * a row of chunks at a time, every row of a slab before the next slab)
 * decode each slice once.
 */
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/io.h"

struct vv_slabs {
    char *path;
    vv_load_options opt; /* info NULL */
    vv_volume *header;   /* 1 x 1 x 1 voxels, dims set to the volume's */
    vv_volume *slab;     /* the slices z0 .. z0 + slab->dims[2] - 1, or NULL */
    int z0;
    uint64_t loads; /* slabs read */
};

vv_status
vv_slabs_open(vv_slabs **out, const char *path, const vv_load_options *opt) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "slabs: NULL argument");
    *out = NULL;
    vv_slabs *s = calloc(1, sizeof *s);
    if (!s || !(s->path = strdup(path))) {
        free(s);
        return vv_error_set(VV_ERR_NOMEM, "slabs: out of memory");
    }
    if (opt)
        s->opt = *opt;
    else
        vv_load_options_init(&s->opt);
    s->opt.info = NULL;
    /* the geometry and the count of slices, from slice 0 */
    vv_load_info info;
    vv_load_options first = s->opt;
    first.z_first = 0;
    first.z_count = 1;
    first.info = &info;
    vv_volume *v = NULL;
    vv_status st = vv_volume_load(&v, path, &first);
    const int one[3] = {1, 1, 1};
    if (st == VV_OK)
        st = vv_volume_new(&s->header, one, v->type);
    if (st == VV_OK) {
        vv_volume *h = s->header;
        h->dims[0] = v->dims[0];
        h->dims[1] = v->dims[1];
        h->dims[2] = info.n_slices;
        memcpy(h->spacing, v->spacing, sizeof h->spacing);
        memcpy(h->origin, v->origin, sizeof h->origin);
        memcpy(h->direction, v->direction, sizeof h->direction);
        h->unit = v->unit;
        h->space = v->space;
        h->data_origin = v->data_origin;
        h->modification = v->modification;
        st = vv_volume_check_limits(h->dims, h->type, NULL);
    }
    vv_volume_free(v);
    if (st != VV_OK) {
        vv_slabs_free(s);
        return st;
    }
    *out = s;
    return VV_OK;
}

const vv_volume *
vv_slabs_header(const vv_slabs *s) {
    return s ? s->header : NULL;
}

uint64_t
vv_slabs_loads(const vv_slabs *s) {
    return s ? s->loads : 0;
}

vv_status
vv_slabs_read_box(void *slabs, const int lo[3], const int hi[3], vv_volume **out) {
    vv_slabs *s = slabs;
    if (!s || !lo || !hi || !out)
        return vv_error_set(VV_ERR_INVALID, "slabs: NULL argument");
    *out = NULL;
    const int *D = s->header->dims;
    for (int a = 0; a < 3; a++)
        if (lo[a] < 0 || hi[a] < lo[a] || hi[a] >= D[a])
            return vv_error_set(VV_ERR_INVALID, "slabs: %s: box %d..%d outside 0..%d on axis %d",
                                vv_path_basename(s->path), lo[a], hi[a], D[a] - 1, a);
    if (!s->slab || lo[2] < s->z0 || hi[2] >= s->z0 + s->slab->dims[2]) {
        /* the box's slices replace the slab held */
        vv_volume_free(s->slab);
        s->slab = NULL;
        vv_load_options o = s->opt;
        o.z_first = lo[2];
        o.z_count = hi[2] - lo[2] + 1;
        vv_volume *v = NULL;
        vv_status st = vv_volume_load(&v, s->path, &o);
        if (st == VV_OK && (v->type != s->header->type || v->dims[0] != D[0] ||
                            v->dims[1] != D[1] || v->dims[2] != o.z_count)) {
            st = vv_error_set(VV_ERR_FORMAT, "slabs: %s: slices %d..%d read as %d x %d x %d %s",
                              vv_path_basename(s->path), lo[2], hi[2], v->dims[0], v->dims[1],
                              v->dims[2], vv_voxel_type_name(v->type));
            vv_volume_free(v);
        }
        if (st != VV_OK)
            return st;
        s->slab = v;
        s->z0 = lo[2];
        s->loads++;
    }
    const int dims[3] = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
    vv_volume *b = NULL;
    vv_status st = vv_volume_new(&b, dims, s->header->type);
    if (st != VV_OK)
        return st;
    const size_t es = vv_voxel_type_size(b->type), row = (size_t)dims[0] * es;
    for (int k = 0; k < dims[2]; k++)
        for (int y = 0; y < dims[1]; y++) {
            const size_t src = (((size_t)(lo[2] + k - s->z0) * D[1] + (size_t)(lo[1] + y)) * D[0] +
                                (size_t)lo[0]) *
                               es;
            memcpy((char *)b->data + ((size_t)k * dims[1] + (size_t)y) * row,
                   (const char *)s->slab->data + src, row);
        }
    for (int a = 0; a < 3; a++) {
        b->spacing[a] = s->header->spacing[a];
        b->origin[a] = s->header->origin[a];
        for (int c = 0; c < 3; c++)
            b->origin[a] += s->header->direction[3 * a + c] * lo[c] * s->header->spacing[c];
    }
    memcpy(b->direction, s->header->direction, sizeof b->direction);
    b->unit = s->header->unit;
    b->space = s->header->space;
    vv_volume_update_range(b);
    *out = b;
    return VV_OK;
}

void
vv_slabs_free(vv_slabs *s) {
    if (!s)
        return;
    vv_volume_free(s->slab);
    vv_volume_free(s->header);
    free(s->path);
    free(s);
}
