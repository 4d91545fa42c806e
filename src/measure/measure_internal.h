/*
 * Internal helpers of the Measurement component: resolving a region (voxel
 * box and cut planes as index-space half-spaces).
 */
#ifndef VOLVIS_MEASURE_INTERNAL_H
#define VOLVIS_MEASURE_INTERNAL_H

#include "volvis/measure.h"

/** A region resolved against a volume. */
typedef struct region_box {
    int lo[3], hi[3]; /**< inclusive voxel box */
    int n_planes;     /**< half-spaces a·(i,j,k) + b >= 0 in index space */
    double a[VV_MAX_CUT_PLANES][3];
    double b[VV_MAX_CUT_PLANES];
} region_box;

/** Checks @p r (NULL: whole volume) against @p v. Errors: VV_ERR_INVALID. */
vv_status region_resolve(const vv_volume *v, const vv_roi *r, region_box *out);

/** 1 when voxel (i, j, k) is on the kept side of every cut plane. */
static inline int
region_keeps(const region_box *rb, int i, int j, int k) {
    for (int p = 0; p < rb->n_planes; p++)
        if (rb->a[p][0] * i + rb->a[p][1] * j + rb->a[p][2] * k + rb->b[p] < 0)
            return 0;
    return 1;
}

#endif
