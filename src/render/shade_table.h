/*
 * Shading by table (internal, not part of the public API): the ray
 * caster's option shading=table. Every voxel's unit gradient is cached as a
 * 16-bit octahedral code (sample.h), so there are only 65,536 normals; for
 * each one the table holds the diffuse factor (ambient plus the lights'
 * diffuse terms, an RGB triple) and the specular term (RGB) of vv_vshade's
 * Phong model for one view direction. A sample then reads its cell's eight
 * corners' entries and blends them trilinearly (interpolated shading, as
 * VTK's vtkFixedPointVolumeRayCastMapper does with its shading tables,
 * VTKKWRCHelper_InterpolateShading) instead of decoding, interpolating and
 * shading a normal (Phong on the interpolated normal, vv_vshade).
 *
 * The view direction is one per table: the camera's for orthographic
 * views, and for perspective ones too (the direction at the image centre;
 * VTK's choice), so a highlight moves a little where a perspective ray
 * deviates from it. A table is rebuilt only when its key changes: the
 * lights' directions and colours, the view direction, the material
 * (ambient, kd, ks, shininess) and the object's gradient-to-world matrix.
 * Directional lights only (a point light makes the light direction depend
 * on the sample).
 *
 * Building is single-threaded (about 65,536 Phong evaluations, a
 * millisecond or two); lookups only read and may run on many threads.
 */
#ifndef VV_RENDER_SHADE_TABLE_H
#define VV_RENDER_SHADE_TABLE_H

#include <stdint.h>

#include "render/shade.h"
#include "volvis/core.h"

#define VV_ST_CODES 65536 /* one entry per 16-bit octahedral code */

/* What a table depends on (compared bytewise: built with memset first). */
typedef struct vv_vshade_table_key {
    int n_lights;
    float dir[VV_MAX_LIGHTS][3]; /* unit vectors towards the lights */
    float v[3];                  /* unit vector towards the eye */
    float nrm[3][3];             /* vv_vshading.nrm */
    float amb[3];
    float kd_col[VV_MAX_LIGHTS][3];
    float ks_col[VV_MAX_LIGHTS][3];
    float spec[VV_VC_SPEC + 1];
} vv_vshade_table_key;

/* A table and its key. e: VV_ST_CODES entries of 8 floats, entry i for the
 * code whose bytes (u, v) read as the little-endian 16-bit number i
 * (u = i & 255, v = i >> 8 as int8): d0 d1 d2 0 s0 s1 s2 0 (the diffuse
 * factor, then the specular term); 64-byte aligned. */
typedef struct vv_vshade_table {
    float *e;
    int valid;
    vv_vshade_table_key key;
    /* where the lights, the ambient light and the material are grey (every
     * term the same in R, G and B): the diffuse factor and the specular
     * term of each code in 16 bits each, packed[i] = d / dscale | (s /
     * sscale) << 16 (rounded), the AVX2 kernel's table (256 KiB, one
     * gather a corner); else NULL */
    uint32_t *packed;
    float dscale, sscale;
} vv_vshade_table;

/* Makes @p t hold the table of shading constants @p sh under the
 * directional @p lights (n_lights of them) seen along -v (@p v: unit vector
 * towards the eye), building it when its key differs from the one it
 * holds. *built: 1 when it was built, 0 when it was current. Errors:
 * VV_ERR_NOMEM (t keeps no table), VV_ERR_UNSUPPORTED (a point light). Not
 * thread-safe for one @p t. */
vv_status vv_vshade_table_update(vv_vshade_table *t, const vv_vshading *sh, const vv_vlight *lights,
                                 int n_lights, const float v[3], int *built);

#if VV_VC_HAVE_AVX2
/* The second pass of the one-volume composite kernel under shading=table
 * with AVX2 (the caller checks vv_vc_have_avx2 and t->packed): the visible
 * samples of a classified chunk of @p m (cell, fractions, entries into
 * @p lut) shaded eight at a time from their cells' eight corners' packed
 * entries, blended trilinearly, then composited one by one under C, A in
 * order, stopping when A reaches @p et. *first (when < 0) gets the chunk
 * index of the first sample composited; *shaded counts them. Returns 1
 * when the ray ended. In kernels_avx2.c. */
int vv_vchunk_shade8_table(const vv_vcache *c, const float *lut, const vv_vshade_table *t, int m,
                           const size_t *cell, const float *fx, const float *fy, const float *fz,
                           const int32_t *entry, float et, float C[3], float *A, int *first,
                           uint32_t *shaded);
#endif

/* Frees the table's memory; t is empty again. */
void vv_vshade_table_free(vv_vshade_table *t);

/* The table entry of the code at voxel @p idx of cache @p c (needs c->nrm). */
static inline const float *
vv_vshade_table_entry(const vv_vshade_table *t, const vv_vcache *c, size_t idx) {
    uint16_t code;
    memcpy(&code, c->nrm + 2 * idx, 2);
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    code = (uint16_t)(code >> 8 | code << 8);
#endif
    return t->e + 8 * (size_t)code;
}

#endif
