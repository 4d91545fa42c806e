/* Per-label measurement of label volumes (the Filtering component's
 * connected components): voxel count, volume, centroid, bounding box. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/measure.h"

#define MAX_LABEL (1u << 24)

vv_status
vv_measure_labels(const vv_volume *v, vv_label_stats **out, int *n) {
    if (!v || !v->data || !out || !n)
        return vv_error_set(VV_ERR_INVALID, "labels: NULL argument");
    *out = NULL;
    *n = 0;
    const int *d = v->dims;
    double maxl = 0;
    size_t q = 0;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++, q++) {
                double l = vv_voxel_at(v, q);
                if (!(l == floor(l)))
                    return vv_error_set(VV_ERR_INVALID,
                                        "labels: voxel (%d, %d, %d) has value %g, not a whole "
                                        "number: not a label volume",
                                        i, j, k, l);
                if (l > maxl)
                    maxl = l;
            }
    if (maxl > MAX_LABEL)
        return vv_error_set(VV_ERR_LIMIT, "labels: label %.0f is above the limit %u", maxl,
                            MAX_LABEL);
    size_t nl = (size_t)maxl + 1;
    uint64_t *cnt = calloc(nl, sizeof *cnt);
    double *sum = calloc(nl * 3, sizeof *sum);
    int *bmin = malloc(nl * 3 * sizeof *bmin), *bmax = malloc(nl * 3 * sizeof *bmax);
    if (!cnt || !sum || !bmin || !bmax) {
        free(cnt);
        free(sum);
        free(bmin);
        free(bmax);
        return vv_error_set(VV_ERR_NOMEM, "labels: out of memory");
    }
    for (size_t l = 0; l < nl * 3; l++) {
        bmin[l] = 1 << 30;
        bmax[l] = -1;
    }
    q = 0;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++)
            for (int i = 0; i < d[0]; i++, q++) {
                double lv = vv_voxel_at(v, q);
                if (lv < 1)
                    continue;
                size_t l = (size_t)lv;
                int p[3] = {i, j, k};
                cnt[l]++;
                for (int a = 0; a < 3; a++) {
                    sum[3 * l + a] += p[a];
                    bmin[3 * l + a] = p[a] < bmin[3 * l + a] ? p[a] : bmin[3 * l + a];
                    bmax[3 * l + a] = p[a] > bmax[3 * l + a] ? p[a] : bmax[3 * l + a];
                }
            }
    int m = 0;
    for (size_t l = 1; l < nl; l++)
        m += cnt[l] > 0;
    vv_label_stats *s = m ? malloc((size_t)m * sizeof *s) : NULL;
    if (m && !s) {
        free(cnt);
        free(sum);
        free(bmin);
        free(bmax);
        return vv_error_set(VV_ERR_NOMEM, "labels: out of memory");
    }
    /* the voxel volume: |det(direction * diag(spacing))| */
    const double *D = v->direction, *h = v->spacing;
    double det = D[0] * (D[4] * D[8] - D[5] * D[7]) - D[1] * (D[3] * D[8] - D[5] * D[6]) +
                 D[2] * (D[3] * D[7] - D[4] * D[6]);
    double vox = fabs(det) * h[0] * h[1] * h[2];
    vv_mat4 i2w = vv_volume_index_to_world(v);
    int o = 0;
    for (size_t l = 1; l < nl; l++) {
        if (!cnt[l])
            continue;
        vv_label_stats *e = &s[o++];
        e->label = (uint32_t)l;
        e->voxels = cnt[l];
        e->volume = (double)cnt[l] * vox;
        vv_vec3 c =
            vv_vec3_make(sum[3 * l] / cnt[l], sum[3 * l + 1] / cnt[l], sum[3 * l + 2] / cnt[l]);
        e->centroid = vv_mat4_mul_point(i2w, c);
        for (int a = 0; a < 3; a++) {
            e->box_min[a] = bmin[3 * l + a];
            e->box_max[a] = bmax[3 * l + a];
        }
    }
    free(cnt);
    free(sum);
    free(bmin);
    free(bmax);
    *out = s;
    *n = m;
    return VV_OK;
}
