/*
 * Helpers shared by the benchmark programs: clocks, medians and the
 * `anchor=volvis op=... dataset=... value=... unit=...` lines that
 * ../shared/BENCHMARKS.md compares with the peers. Images and files that
 * benchmarks write go under build/bench-out by default, never into the
 * source tree.
 */
#ifndef VOLVIS_BENCH_UTIL_H
#define VOLVIS_BENCH_UTIL_H

/** Wall-clock seconds (monotonic). */
double bench_now(void);
/** CPU seconds of the whole process, all threads. */
double bench_cpu_now(void);
/** qsort comparator for doubles. */
int bench_cmp_double(const void *a, const void *b);
/** Median of @p n values (sorts @p v in place); 0 when n < 1. */
double bench_median(double *v, int n);
/** Prints one anchor line and flushes stdout. */
void bench_emit(const char *op, const char *dataset, double value, const char *unit);
/** Creates directory @p path and its missing parents (mode 0755); 0 on success. */
int bench_mkdirs(const char *path);
/** Prints "PROG: WHAT: <library error message>" to stderr and exits 1. */
_Noreturn void bench_die(const char *prog, const char *what);

#endif
