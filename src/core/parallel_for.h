/*
 * The library's one parallel loop (not installed): items handed out in
 * chunks from a shared counter to OpenMP threads, with progress reporting
 * and cancellation. The filters (src/filter) and Marching Cubes
 * (src/surface) run their passes on it.
 *
 * Why a counter rather than the items' positions: a chunk goes to whichever
 * thread asks next, so a thread the operating system deschedules on a
 * loaded machine delays the loop by one chunk at most, not by a static
 * share of it. Results never depend on which thread ran a chunk (bodies
 * must compute each item on its own; per-thread scratch is indexed by the
 * worker number), so output is the same for any thread count.
 *
 * Waiting: OpenMP's threads spin a while (about 3 ms with libgomp's
 * defaults) before they sleep, at the end of a loop and between loops. On
 * an idle core that costs nothing; on a machine with more runnable threads
 * than cores the spinning takes the core a late partner needs, and short
 * loops (Marching Cubes on a 128^2 x 54 grid: 3 loops of about 1 ms) run
 * several times slower than on threads that block. OMP_WAIT_POLICY=passive
 * makes them block (docs/architecture.md, "Threads").
 *
 * Thread-safety: reentrant; a body runs on several threads at once. Called
 * inside another OpenMP parallel region, the loop runs on the calling
 * thread alone (nested parallelism is off).
 */
#ifndef VOLVIS_CORE_PARALLEL_FOR_H
#define VOLVIS_CORE_PARALLEL_FOR_H

#include "volvis/core.h"

/** Most threads one loop uses (per-thread scratch can be sized by it). */
#define VV_PARALLEL_MAX_THREADS 256

/** Work of items [i0, i1) on worker @p worker (0 .. threads - 1). */
typedef void (*vv_parallel_fn)(void *ctx, long i0, long i1, int worker);

/** Progress of a loop: fraction p0 at its start to p1 at its end. */
typedef struct vv_parallel_progress {
    const vv_progress *progress; /**< NULL or no callback: no reports, no cancellation */
    double p0, p1;
    int every; /**< report after every this many chunks of worker 0 (<= 1: each) */
} vv_parallel_progress;

/**
 * Runs @p body over items 0 .. n - 1 in chunks of @p chunk (>= 1; smaller
 * is taken as 1) on min(@p threads, number of chunks) threads (@p threads
 * <= 0: vv_threads_get(); at most VV_PARALLEL_MAX_THREADS). The calling
 * thread is worker 0; it reports p0 + (p1 - p0) * i1 / n after its chunks
 * (every `every`-th) through @p pr (may be NULL). A report that asks to
 * cancel stops every worker before its next chunk. The loop does not report
 * p1 at its end (the caller knows what comes next). Returns VV_OK when every
 * item ran, VV_ERR_CANCELLED (message "cancelled"; callers prefix their
 * name) otherwise. n <= 0 runs nothing and returns VV_OK.
 */
vv_status vv_parallel_for(long n, long chunk, int threads, vv_parallel_fn body, void *ctx,
                          const vv_parallel_progress *pr);

#endif
