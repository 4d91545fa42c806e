/* The library's parallel loop on OpenMP (see core/parallel_for.h). */
#include "core/parallel_for.h"

#include <omp.h>
#include <stdatomic.h>

typedef struct pf_loop {
    vv_parallel_fn body;
    void *ctx;
    long n, chunk;
    atomic_long next;
    atomic_int cancel;
    const vv_parallel_progress *pr;
} pf_loop;

static void
pf_run(pf_loop *L, int w) {
    const vv_parallel_progress *pr = L->pr;
    const int reports = w == 0 && pr && pr->progress && pr->progress->fn;
    const int every = pr && pr->every > 1 ? pr->every : 1;
    int tick = 0;
    for (;;) {
        if (atomic_load_explicit(&L->cancel, memory_order_relaxed))
            break;
        const long i0 = atomic_fetch_add_explicit(&L->next, L->chunk, memory_order_relaxed);
        if (i0 >= L->n)
            break;
        const long i1 = i0 + L->chunk < L->n ? i0 + L->chunk : L->n;
        L->body(L->ctx, i0, i1, w);
        if (reports && ++tick % every == 0 &&
            vv_progress_report(pr->progress,
                               pr->p0 + (pr->p1 - pr->p0) * (double)i1 / (double)L->n))
            atomic_store(&L->cancel, 1);
    }
}

vv_status
vv_parallel_for(long n, long chunk, int threads, vv_parallel_fn body, void *ctx,
                const vv_parallel_progress *pr) {
    if (n <= 0)
        return VV_OK;
    if (chunk < 1)
        chunk = 1;
    pf_loop L = {.body = body, .ctx = ctx, .n = n, .chunk = chunk, .pr = pr};
    atomic_init(&L.next, 0);
    atomic_init(&L.cancel, 0);
    int nt = threads > 0 ? threads : vv_threads_get();
    const long chunks = (n - 1) / chunk + 1;
    nt = nt < 1 ? 1 : nt > VV_PARALLEL_MAX_THREADS ? VV_PARALLEL_MAX_THREADS : nt;
    nt = chunks < nt ? (int)chunks : nt;
    if (nt == 1) {
        pf_run(&L, 0);
    } else {
#pragma omp parallel num_threads(nt)
        pf_run(&L, omp_get_thread_num());
    }
    if (atomic_load(&L.cancel))
        return vv_error_set(VV_ERR_CANCELLED, "cancelled");
    return VV_OK;
}
