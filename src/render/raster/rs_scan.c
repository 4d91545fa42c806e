/*
 * The rasterizer's stage 3: a tile's triangles scanned with integer edge
 * functions at pixel centres (top-left rule), filled or as wireframe, into
 * the visibility buffer.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "render/raster/rs_internal.h"
#include "volvis/raster.h"

/* ---------------------------------------------------------------------- */
/* Scanning                                                                 */

/* Fills the part of triangle @p t inside the tile rectangle. */
void
rs_scan_fill(vv_raster *r, const rs_stri *t, const float *lams, uint32_t id, int x0, int x1, int y0,
             int y1) {
    const float *L = t->lam == RS_NONE ? NULL : lams + 9 * (size_t)t->lam;
    int64_t ax[3], ay[3], bias[3];
    for (int e = 0; e < 3; e++) {
        /* edge opposite vertex e: from v_(e+1) to v_(e+2) */
        const int a = (e + 1) % 3, b = (e + 2) % 3;
        const int64_t dx = (int64_t)t->X[b] - t->X[a], dy = (int64_t)t->Y[b] - t->Y[a];
        ax[e] = -dy;
        ay[e] = dx;
        bias[e] = top_left(dx, dy) ? 0 : -1;
    }
    const int64_t A = ((int64_t)t->X[1] - t->X[0]) * ((int64_t)t->Y[2] - t->Y[0]) -
                      ((int64_t)t->Y[1] - t->Y[0]) * ((int64_t)t->X[2] - t->X[0]);
    const float invA = 1.0f / (float)A;
    const int64_t Px = (int64_t)x0 * RS_SUB + RS_SUB / 2, Py = (int64_t)y0 * RS_SUB + RS_SUB / 2;
    int64_t row[3];
    for (int e = 0; e < 3; e++) {
        const int a = (e + 1) % 3;
        row[e] = ax[e] * (Px - t->X[a]) + ay[e] * (Py - t->Y[a]) + bias[e];
    }
    for (int y = y0; y <= y1; y++) {
        int64_t E0 = row[0], E1 = row[1], E2 = row[2];
        rs_pix *px = r->pix + (size_t)y * (size_t)r->w + (size_t)x0;
        for (int x = x0; x <= x1; x++, px++) {
            if ((E0 | E1 | E2) >= 0) {
                const float b0 = (float)(E0 - bias[0]) * invA, b1 = (float)(E1 - bias[1]) * invA;
                const float b2 = (float)(E2 - bias[2]) * invA;
                const float key = b0 * t->key[0] + b1 * t->key[1] + b2 * t->key[2];
                if (key > px->key)
                    store_fragment(px, t, L, key, b0, b1, b2, id);
            }
            E0 += ax[0] * RS_SUB;
            E1 += ax[1] * RS_SUB;
            E2 += ax[2] * RS_SUB;
        }
        row[0] += ay[0] * RS_SUB;
        row[1] += ay[1] * RS_SUB;
        row[2] += ay[2] * RS_SUB;
    }
}

/* Draws the original edges of @p t, one pixel wide: pixels whose centre is
 * within half a pixel of an edge segment. */
void
rs_scan_wire(vv_raster *r, const rs_stri *t, const float *lams, uint32_t id, int x0, int x1, int y0,
             int y1) {
    const float *L = t->lam == RS_NONE ? NULL : lams + 9 * (size_t)t->lam;
    const double A = ((double)t->X[1] - t->X[0]) * ((double)t->Y[2] - t->Y[0]) -
                     ((double)t->Y[1] - t->Y[0]) * ((double)t->X[2] - t->X[0]);
    for (int y = y0; y <= y1; y++) {
        const double Py = (double)y * RS_SUB + RS_SUB / 2;
        rs_pix *px = r->pix + (size_t)y * (size_t)r->w + (size_t)x0;
        for (int x = x0; x <= x1; x++, px++) {
            const double Px = (double)x * RS_SUB + RS_SUB / 2;
            int on = 0;
            for (int i = 0; i < 3 && !on; i++) {
                if (!(t->flags & (1u << i)))
                    continue;
                const int j = (i + 1) % 3;
                const double dx = (double)t->X[j] - t->X[i], dy = (double)t->Y[j] - t->Y[i];
                const double qx = Px - t->X[i], qy = Py - t->Y[i];
                const double l2 = dx * dx + dy * dy;
                double s = l2 > 0 ? (qx * dx + qy * dy) / l2 : 0;
                s = s < 0 ? 0 : s > 1 ? 1 : s;
                const double ex = qx - s * dx, ey = qy - s * dy;
                on = ex * ex + ey * ey <= 0.25 * RS_SUB * RS_SUB;
            }
            if (!on)
                continue;
            /* barycentric coordinates (extended beyond the triangle by half a pixel) */
            double b[3];
            for (int e = 0; e < 3; e++) {
                const int a = (e + 1) % 3, c = (e + 2) % 3;
                b[e] = (((double)t->X[c] - t->X[a]) * (Py - t->Y[a]) -
                        ((double)t->Y[c] - t->Y[a]) * (Px - t->X[a])) /
                       A;
            }
            const float key = (float)(b[0] * t->key[0] + b[1] * t->key[1] + b[2] * t->key[2]);
            if (key > px->key && b[0] * t->iw[0] + b[1] * t->iw[1] + b[2] * t->iw[2] > 0)
                store_fragment(px, t, L, key, (float)b[0], (float)b[1], (float)b[2], id);
        }
    }
}
