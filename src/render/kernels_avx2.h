/*
 * The AVX2 kernels of the volume renderers (internal, not part of the
 * public API): the vector paths of the sampling, classification, shading,
 * ray and projection stages, in kernels_avx2.c, compiled in where the build
 * targets x86-64 with GCC or Clang (VV_VC_HAVE_AVX2, sample.h) and chosen at
 * run time when the processor has AVX2 and FMA (vv_vc_have_avx2). Declared
 * here: the run-time test and the paths the stages' own code takes;
 * vv_vshade8 and vv_vchunk_shade8 (shade.h), vv_vchunk_shade8_table
 * (shade_table.h) and vv_vray_visible_run_avx2
 * (ray.h), which the renderers call, are declared with their stages.
 * Thread-safe: they only read.
 */
#ifndef VV_RENDER_KERNELS_AVX2_H
#define VV_RENDER_KERNELS_AVX2_H

#include <stddef.h>
#include <stdint.h>

#include "render/ray.h"
#include "render/sample.h"
#include "render/tf_tables.h"

/* The processor has AVX2 and FMA. */
int vv_vc_have_avx2(void);

#if VV_VC_HAVE_AVX2
/* The trilinear values of the samples kfirst .. kfirst + m - 1 (m <=
 * VV_VC_CHUNK) of ray r through 16-bit values (c->q16) into @p val, eight at
 * a time: the scalar path's arithmetic, so the values are those of
 * vv_vray_point, vv_vcache_cell_in and vv_vcache_value_at bit for bit. */
void vv_vray_values_avx2(const vv_vcache *c, const vv_vray *r, double kfirst, double dt, int m,
                         float *val);

/* vv_vray_classify for 16-bit values, eight samples at a time with AVX2
 * and FMA: the same outputs but for the rounding of fused multiply-adds. */
void vv_vray_classify_avx2(const vv_vcache *c, const vv_vtables *ob, const vv_vray *r,
                           double kfirst, double dt, int m, size_t *cell, float *fx, float *fy,
                           float *fz, int32_t *entry, float *x);

/* The maximum of sg * value over the samples k .. kend of ray r (16-bit
 * values) as project.c's scalar march finds it, the ray marched in chunks
 * of 64 samples (kernels_avx2.c describes the difference): *tbest_out the
 * parameter of its first sample. */
float vv_vproj_from_avx2(const vv_vcache *c, const uint8_t *pdist, const vv_vray *r, double dt,
                         double k, double kend, float sg, float floor0, float stop, int skipping,
                         double *tbest_out);
/* vv_oct_encode_n (sample.h) eight directions at a time, in its
 * arithmetic: the same codes (out: 2 n bytes). */
void vv_oct_encode_n_avx2(const float *gx, const float *gy, const float *gz, int n, int8_t *out);
#endif

#endif
