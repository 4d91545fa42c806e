/*
 * bench_limit: the machine's limit for the ray caster's inner loop, on one
 * core (issue 65): trilinear samples a second of u8, u16 and f32 volumes,
 * and fused multiply-adds a second (scalar: a multiply and an add), each
 * scalar, AVX2 (8 lanes) and
 * AVX-512 (16 lanes) where the processor has them (chosen at run time).
 *
 * Three access patterns for the trilinear gathers:
 *   cache     a 32^3 volume (32 KiB of u8 to 128 KiB of f32: L1/L2), random
 *             positions;
 *   rays      a 512^3 volume (128 MiB of u8 to 512 MiB of f32), positions
 *             along rays through it at half a voxel a step (the ray
 *             caster's own access: neighbouring samples share cache lines);
 *   random    the same 512^3 volume at random positions (every sample a
 *             cache and TLB miss: the floor a ray caster never sees).
 * A sample is the trilinear interpolation of the eight voxels around a
 * position (x fastest in memory), converted to float; its result is summed
 * so that no work is left out. The positions are precomputed (their cost is
 * not measured); the loop is unrolled the same way for every width.
 *
 * Prints `anchor=volvis op=limit_trilinear_<type>_<pattern>_<isa>
 * dataset=one_core value=<samples per second> unit=samples/s` and
 * `op=limit_fma_<isa> ... unit=flop/s` (two flops an FMA lane), and a
 * comment line with what the processor has. bench_raycast divides its
 * shaded-sample rate by limit_trilinear_<type>_rays of the widest ISA.
 *
 * Before timing a vector path it checks that one pass of it sums to the
 * scalar pass's sum (to 1e-4 relative; float rounding is about 1e-6) and
 * exits 1 with a line naming the case where it does not (CTest
 * test_bench_limit runs --quick).
 *
 * usage: bench_limit [--quick]   (--quick: 256^3 volumes, 50 ms a timing)
 */
#include <stdio.h>
#include <string.h>

#include "common/limit.h"
#include "util.h"

int
main(int argc, char **argv) {
    int big = 512;
    double seconds = 0.3;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick")) {
            seconds = 0.05;
            big = 256;
        } else {
            fprintf(stderr, "usage: bench_limit [--quick]\n");
            return 2;
        }
    }
    printf("# one core; AVX2+FMA %s, AVX-512F %s; %d^3 volumes for rays and random\n",
           bench_isa_available(BENCH_ISA_AVX2) ? "yes" : "no",
           bench_isa_available(BENCH_ISA_AVX512) ? "yes" : "no", big);
    fflush(stdout);
    static const char *const pattern[] = {"cache", "rays", "random"};
    char op[96];
    for (int t = BENCH_LIMIT_U8; t <= BENCH_LIMIT_F32; t++)
        for (int p = BENCH_LIMIT_CACHE; p <= BENCH_LIMIT_RANDOM; p++) {
            bench_limit_case *c = bench_limit_case_new(
                (bench_limit_type)t, p == BENCH_LIMIT_CACHE ? 32 : big, (bench_limit_pattern)p);
            if (!c) {
                fprintf(stderr, "bench_limit: out of memory for a %d^3 %s volume\n",
                        p == BENCH_LIMIT_CACHE ? 32 : big,
                        bench_limit_type_name((bench_limit_type)t));
                return 1;
            }
            for (int k = BENCH_ISA_SCALAR; k <= BENCH_ISA_AVX512; k++) {
                if (!bench_isa_available((bench_isa)k))
                    continue;
                /* the vector paths sample what the scalar one samples */
                const double d = bench_limit_agreement(c, (bench_isa)k);
                if (!(d <= 1e-4)) {
                    fprintf(stderr,
                            "bench_limit: %s %s %s: a pass sums to %.3g relative of the "
                            "scalar one's sum away\n",
                            bench_limit_type_name((bench_limit_type)t), pattern[p],
                            bench_isa_name((bench_isa)k), d);
                    return 1;
                }
                snprintf(op, sizeof op, "limit_trilinear_%s_%s_%s",
                         bench_limit_type_name((bench_limit_type)t), pattern[p],
                         bench_isa_name((bench_isa)k));
                bench_emit(op, "one_core", bench_limit_trilinear(c, (bench_isa)k, seconds),
                           "samples/s");
            }
            bench_limit_case_free(c);
        }
    for (int k = BENCH_ISA_SCALAR; k <= BENCH_ISA_AVX512; k++)
        if (bench_isa_available((bench_isa)k)) {
            snprintf(op, sizeof op, "limit_fma_%s", bench_isa_name((bench_isa)k));
            bench_emit(op, "one_core", bench_limit_fma((bench_isa)k), "flop/s");
        }
    return 0;
}
