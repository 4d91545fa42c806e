/*
 * Phong's reflection model with the reflection vector (Bui Tuong Phong,
 * "Illumination for computer generated pictures", CACM 1975), two-sided,
 * for one light: internal to src/render, written once for the volume
 * renderers' shading (shade.h, vv_vshade) and the rasterizer's lighting
 * (raster/rs_internal.h). What each adds around it (how the normal is
 * found, a specular table or powf, shadows) stays with its caller.
 * Reentrant.
 */
#ifndef VV_RENDER_PHONG_H
#define VV_RENDER_PHONG_H

#include <math.h>

/* The unit vector L from point @p p towards a light: @p dir for a
 * directional one, towards @p pos for a point light (@p point). Returns 0
 * when a point light sits at @p p (no direction: the light adds nothing). */
static inline int
vv_phong_light_dir(int point, const float dir[3], const float pos[3], const float p[3],
                   float L[3]) {
    L[0] = dir[0];
    L[1] = dir[1];
    L[2] = dir[2];
    if (point) {
        L[0] = pos[0] - p[0];
        L[1] = pos[1] - p[1];
        L[2] = pos[2] - p[2];
        const float ll = sqrtf(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
        if (!(ll > 0))
            return 0;
        L[0] /= ll;
        L[1] /= ll;
        L[2] /= ll;
    }
    return 1;
}

/* One light's two terms for a unit normal n, unit vectors @p L (towards
 * the light) and @p v (towards the eye), given @p ndl = n.L and @p nv =
 * n.v: the diffuse weight |n.L| into *@p diffuse (two-sided: a normal
 * facing away from the light is flipped), and R.V returned, R the mirror
 * of L about the (flipped) normal. */
static inline float
vv_phong_rv(float ndl, float nv, const float L[3], const float v[3], float *diffuse) {
    const float ndv = ndl < 0 ? -nv : nv;
    ndl = ndl < 0 ? -ndl : ndl;
    *diffuse = ndl;
    return 2 * ndl * ndv - (L[0] * v[0] + L[1] * v[1] + L[2] * v[2]);
}

#endif
