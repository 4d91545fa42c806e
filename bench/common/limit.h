/*
 * The machine's limit for the ray caster's inner loop, on one core (issue 65;
 * bench_limit prints it, bench_raycast divides its shaded-sample rate by it):
 * trilinear samples a second of a u8, u16 or f32 volume of n^3 voxels (x
 * fastest), at NPOS precomputed positions chosen at random or along rays at
 * half a voxel a step, each the eight voxels around a position interpolated
 * as floats and summed; and fused multiply-adds a second (scalar: a
 * multiply and an add; two flops a lane). Each scalar, AVX2 (8 lanes) or
 * AVX-512 (16 lanes), chosen at run time (__builtin_cpu_supports). Single
 * thread; not thread-safe (a case is read by one timing at a time).
 */
#ifndef VV_BENCH_LIMIT_H
#define VV_BENCH_LIMIT_H

typedef enum { BENCH_LIMIT_U8, BENCH_LIMIT_U16, BENCH_LIMIT_F32 } bench_limit_type;
typedef enum { BENCH_LIMIT_CACHE, BENCH_LIMIT_RAYS, BENCH_LIMIT_RANDOM } bench_limit_pattern;
typedef enum { BENCH_ISA_SCALAR, BENCH_ISA_AVX2, BENCH_ISA_AVX512 } bench_isa;
typedef struct bench_limit_case bench_limit_case;

/** Whether this processor runs @p isa (AVX2 with FMA; AVX-512F). */
int bench_isa_available(bench_isa isa);
/** The widest ISA this processor runs. */
bench_isa bench_isa_widest(void);
/** "scalar", "avx2", "avx512". */
const char *bench_isa_name(bench_isa isa);
/** "u8", "u16", "f32". */
const char *bench_limit_type_name(bench_limit_type t);
/** A volume of n^3 voxels (filled) and its positions (random ones for
 * BENCH_LIMIT_CACHE and _RANDOM); NULL when out of memory. Free with
 * bench_limit_case_free. */
bench_limit_case *bench_limit_case_new(bench_limit_type type, int n, bench_limit_pattern pattern);
void bench_limit_case_free(bench_limit_case *c);
/** Trilinear samples a second of @p c with @p isa (the best of three tries of
 * about @p seconds / 3 each); 0 when the processor lacks @p isa. */
double bench_limit_trilinear(const bench_limit_case *c, bench_isa isa, double seconds);
/** The relative difference between the sums of one pass of @p c with @p isa
 * and with scalar code (the same samples in another order: float rounding
 * only, about 1e-6); 0 when the processor lacks @p isa. */
double bench_limit_agreement(const bench_limit_case *c, bench_isa isa);
/** Flops a second of ten independent chains of FMAs with @p isa; 0 when the
 * processor lacks it. */
double bench_limit_fma(bench_isa isa);

#endif
