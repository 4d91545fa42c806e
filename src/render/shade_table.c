/*
 * Shading by table: a diffuse factor and a specular term per 16-bit
 * octahedral normal code (shade_table.h describes the method).
 */
#include "render/shade_table.h"

#include <stdlib.h>
#include <string.h>

#include "core/internal.h"

vv_status
vv_vshade_table_update(vv_vshade_table *t, const vv_vshading *sh, const vv_vlight *lights,
                       int n_lights, const float v[3], int *built) {
    *built = 0;
    vv_vshade_table_key k;
    memset(&k, 0, sizeof k);
    k.n_lights = n_lights;
    for (int l = 0; l < n_lights; l++) {
        if (lights[l].point)
            return vv_error_set(VV_ERR_UNSUPPORTED, "shading table: point lights are not "
                                                    "tabulated");
        memcpy(k.dir[l], lights[l].dir, sizeof k.dir[l]);
        memcpy(k.kd_col[l], sh->kd_col[l], sizeof k.kd_col[l]);
        memcpy(k.ks_col[l], sh->ks_col[l], sizeof k.ks_col[l]);
    }
    memcpy(k.v, v, sizeof k.v);
    memcpy(k.nrm, sh->nrm, sizeof k.nrm);
    memcpy(k.amb, sh->amb, sizeof k.amb);
    memcpy(k.spec, sh->spec, sizeof k.spec);
    if (t->valid && t->e && memcmp(&k, &t->key, sizeof k) == 0)
        return VV_OK;
    if (!t->e) {
        t->e = aligned_alloc(64, sizeof(float) * 8 * VV_ST_CODES);
        if (!t->e)
            return vv_error_set(VV_ERR_NOMEM, "shading table: out of memory (2 MiB)");
    }
    /* each code's terms by vv_vshade itself: with colour 1 and opacity 0
     * it returns the diffuse factor, with colour 0 and opacity 1 the
     * specular term (an unlit normal, code VV_OCT_ZERO: ambient, 0) */
    static const float one[3] = {1, 1, 1}, zero[3] = {0, 0, 0};
    for (int i = 0; i < VV_ST_CODES; i++) {
        const int u = (int8_t)(uint8_t)(i & 255), w = (int8_t)(uint8_t)(i >> 8);
        const vv_v4f n = vv_oct_decode(u, w);
        const float g[3] = {n[0], n[1], n[2]};
        float *e = t->e + 8 * (size_t)i;
        vv_vshade(sh, lights, n_lights, g, zero, v, one, 0, NULL, NULL, e);
        vv_vshade(sh, lights, n_lights, g, zero, v, zero, 1, NULL, NULL, e + 4);
        e[3] = e[7] = 0;
    }
    /* grey lights and material: the packed 16-bit table too */
    int grey = sh->amb[0] == sh->amb[1] && sh->amb[1] == sh->amb[2];
    for (int l = 0; l < n_lights; l++)
        grey &= sh->kd_col[l][0] == sh->kd_col[l][1] && sh->kd_col[l][1] == sh->kd_col[l][2] &&
                sh->ks_col[l][0] == sh->ks_col[l][1] && sh->ks_col[l][1] == sh->ks_col[l][2];
    free(t->packed);
    t->packed = NULL;
    if (grey && (t->packed = malloc(sizeof(uint32_t) * VV_ST_CODES)) != NULL) {
        float dmax = 0, smax = 0;
        for (int i = 0; i < VV_ST_CODES; i++) {
            dmax = t->e[8 * i] > dmax ? t->e[8 * i] : dmax;
            smax = t->e[8 * i + 4] > smax ? t->e[8 * i + 4] : smax;
        }
        t->dscale = dmax > 0 ? dmax / 65535.0f : 1.0f;
        t->sscale = smax > 0 ? smax / 65535.0f : 1.0f;
        for (int i = 0; i < VV_ST_CODES; i++) {
            const float d = t->e[8 * i] / t->dscale, s = t->e[8 * i + 4] / t->sscale;
            const uint32_t dq = d > 0 ? (uint32_t)(d < 65535.0f ? d + 0.5f : 65535.0f) : 0;
            const uint32_t sq = s > 0 ? (uint32_t)(s < 65535.0f ? s + 0.5f : 65535.0f) : 0;
            t->packed[i] = dq | sq << 16;
        }
    }
    t->key = k;
    t->valid = 1;
    *built = 1;
    return VV_OK;
}

void
vv_vshade_table_free(vv_vshade_table *t) {
    free(t->e);
    free(t->packed);
    memset(t, 0, sizeof *t);
}
