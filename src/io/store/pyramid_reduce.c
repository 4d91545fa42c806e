/*
 * The next level of a pyramid, as the OME-Zarr writer (src/io/store/zarr_write.c)
 * and the .vvb writer (src/io/write/vvb_write.c) make it: each voxel the mean of
 * the 2x2x2 voxels under it (src/io/store/pyramid.h: vv_pyr_reduce).
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "io/store/pyramid.h"

double
vv_pyr_voxel(const void *d, vv_voxel_type t, size_t i) {
    switch (t) {
    case VV_U8:
        return ((const uint8_t *)d)[i];
    case VV_I8:
        return ((const int8_t *)d)[i];
    case VV_U16:
        return ((const uint16_t *)d)[i];
    case VV_I16:
        return ((const int16_t *)d)[i];
    case VV_U32:
        return ((const uint32_t *)d)[i];
    case VV_I32:
        return ((const int32_t *)d)[i];
    case VV_F32:
        return ((const float *)d)[i];
    default:
        return ((const double *)d)[i];
    }
}

/* vv_pyr_reduce for voxels of type T (ROUND: 1 for integers, rounded to
 * nearest): the same sums in the same order as a double, so any type's
 * result is what the generic form gives. */
#define VV_REDUCE_TYPED(NAME, T, ROUND)                                                            \
    static void NAME(const vv_pyr_reduce_box *b, T *dst) {                                         \
        const T *src = b->src;                                                                     \
        const int *sd = b->src_dims, *st = b->step, *plo = b->src_lo, *pn = b->src_n;              \
        for (int k = 0; k < b->n[2]; k++)                                                          \
            for (int y = 0; y < b->n[1]; y++)                                                      \
                for (int x = 0; x < b->n[0]; x++) {                                                \
                    const size_t out = ((size_t)k * b->dst_dims[1] + y) * b->dst_dims[0] + x;      \
                    const int x0 = (b->lo[0] + x) * st[0], y0 = (b->lo[1] + y) * st[1],            \
                              z0 = (b->lo[2] + k) * st[2];                                         \
                    double sum = 0;                                                                \
                    int n = 0;                                                                     \
                    for (int dz = 0; dz < st[2] && z0 + dz < sd[2]; dz++)                          \
                        for (int dy = 0; dy < st[1] && y0 + dy < sd[1]; dy++) {                    \
                            const T *row =                                                         \
                                src +                                                              \
                                ((size_t)(z0 + dz - plo[2]) * pn[1] + (y0 + dy - plo[1])) *        \
                                    pn[0] +                                                        \
                                (x0 - plo[0]);                                                     \
                            for (int dx = 0; dx < st[0] && x0 + dx < sd[0]; dx++, n++)             \
                                sum += (double)row[dx];                                            \
                        }                                                                          \
                    const double m = sum / n;                                                      \
                    dst[out] = (T)(ROUND ? floor(m + 0.5) : m);                                    \
                }                                                                                  \
    }

VV_REDUCE_TYPED(reduce_u8, uint8_t, 1)
VV_REDUCE_TYPED(reduce_i8, int8_t, 1)
VV_REDUCE_TYPED(reduce_u16, uint16_t, 1)
VV_REDUCE_TYPED(reduce_i16, int16_t, 1)
VV_REDUCE_TYPED(reduce_u32, uint32_t, 1)
VV_REDUCE_TYPED(reduce_i32, int32_t, 1)
VV_REDUCE_TYPED(reduce_f32, float, 0)
VV_REDUCE_TYPED(reduce_f64, double, 0)

void
vv_pyr_reduce(const vv_pyr_reduce_box *b, void *dst) {
    if (!b->label) {
        switch (b->type) {
        case VV_U8:
            reduce_u8(b, dst);
            return;
        case VV_I8:
            reduce_i8(b, dst);
            return;
        case VV_U16:
            reduce_u16(b, dst);
            return;
        case VV_I16:
            reduce_i16(b, dst);
            return;
        case VV_U32:
            reduce_u32(b, dst);
            return;
        case VV_I32:
            reduce_i32(b, dst);
            return;
        case VV_F32:
            reduce_f32(b, dst);
            return;
        case VV_F64:
            reduce_f64(b, dst);
            return;
        }
    }
    /* labels: the first voxel of each block */
    const size_t es = vv_voxel_type_size(b->type);
    const int *st = b->step, *plo = b->src_lo, *pn = b->src_n;
    for (int k = 0; k < b->n[2]; k++)
        for (int y = 0; y < b->n[1]; y++)
            for (int x = 0; x < b->n[0]; x++) {
                const size_t out = ((size_t)k * b->dst_dims[1] + y) * b->dst_dims[0] + x;
                const int x0 = (b->lo[0] + x) * st[0], y0 = (b->lo[1] + y) * st[1],
                          z0 = (b->lo[2] + k) * st[2];
                const size_t i =
                    ((size_t)(z0 - plo[2]) * pn[1] + (y0 - plo[1])) * pn[0] + (x0 - plo[0]);
                memcpy((char *)dst + out * es, (const char *)b->src + i * es, es);
            }
}
