/*
 * core/parallel_for.c: every item runs exactly once for any chunk and
 * thread count, worker numbers stay below the thread count, progress rises
 * from p0 towards p1 on the calling thread only, and a cancel stops the
 * loop with VV_ERR_CANCELLED.
 */
#include "testutil.h"

#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>

#include "core/parallel_for.h"

typedef struct count_ctx {
    atomic_int *count;
    int threads;
    atomic_int bad_worker;
    atomic_int max_worker;
} count_ctx;

static void
count_body(void *ctx, long i0, long i1, int w) {
    count_ctx *c = ctx;
    if (w < 0 || w >= c->threads)
        atomic_store(&c->bad_worker, 1);
    int m = atomic_load(&c->max_worker);
    while (w > m && !atomic_compare_exchange_weak(&c->max_worker, &m, w))
        ;
    for (long i = i0; i < i1; i++)
        atomic_fetch_add(&c->count[i], 1);
}

static void
test_every_item_once(void **state) {
    (void)state;
    const long ns[] = {1, 7, 16, 1000, 4097};
    const long chunks[] = {1, 3, 16, 5000};
    const int threads[] = {1, 2, 5};
    for (size_t a = 0; a < sizeof ns / sizeof ns[0]; a++)
        for (size_t b = 0; b < sizeof chunks / sizeof chunks[0]; b++)
            for (size_t t = 0; t < sizeof threads / sizeof threads[0]; t++) {
                const long n = ns[a];
                atomic_int *cnt = calloc((size_t)n, sizeof *cnt);
                assert_non_null(cnt);
                count_ctx c = {.count = cnt, .threads = threads[t]};
                atomic_init(&c.bad_worker, 0);
                atomic_init(&c.max_worker, 0);
                vt_ok(vv_parallel_for(n, chunks[b], threads[t], count_body, &c, NULL));
                for (long i = 0; i < n; i++)
                    if (atomic_load(&cnt[i]) != 1)
                        fail_msg("n %ld chunk %ld threads %d: item %ld ran %d times", n, chunks[b],
                                 threads[t], i, atomic_load(&cnt[i]));
                assert_int_equal(atomic_load(&c.bad_worker), 0);
                free(cnt);
            }
    /* nothing to do: no call, VV_OK; chunk < 1 is taken as 1 */
    vt_ok(vv_parallel_for(0, 4, 2, NULL, NULL, NULL));
    vt_ok(vv_parallel_for(-3, 4, 2, NULL, NULL, NULL));
    atomic_int cnt[5];
    for (int i = 0; i < 5; i++)
        atomic_init(&cnt[i], 0);
    count_ctx c = {.count = cnt, .threads = 3};
    atomic_init(&c.bad_worker, 0);
    atomic_init(&c.max_worker, 0);
    vt_ok(vv_parallel_for(5, 0, 3, count_body, &c, NULL));
    for (int i = 0; i < 5; i++)
        assert_int_equal(atomic_load(&cnt[i]), 1);
}

/* Inside another parallel region the loop runs on the calling thread and
 * still covers every item. */
static void
test_nested(void **state) {
    (void)state;
    enum { N = 300 };
    static atomic_int cnt[2][N];
    int ok[2] = {0, 0};
#pragma omp parallel num_threads(2)
    {
        const int me = omp_get_thread_num();
        count_ctx c = {.count = cnt[me], .threads = 4};
        atomic_init(&c.bad_worker, 0);
        atomic_init(&c.max_worker, 0);
        ok[me] = vv_parallel_for(N, 8, 4, count_body, &c, NULL) == VV_OK &&
                 atomic_load(&c.bad_worker) == 0;
    }
    for (int me = 0; me < 2; me++) {
        assert_true(ok[me]);
        for (int i = 0; i < N; i++)
            assert_int_equal(atomic_load(&cnt[me][i]), 1);
    }
}

typedef struct prog_ctx {
    double last;
    int calls;
    int bad;
    int stop_at; /* cancel at this call (0: never) */
    int hold;    /* other threads wait in the body until the caller has reported */
    long ran;
} prog_ctx;

static int
prog_cb(void *user, double f) {
    prog_ctx *p = user;
    if (omp_get_thread_num() != 0 || f < p->last || f < 0.25 || f > 0.75)
        p->bad = 1;
    p->last = f;
#pragma omp atomic update
    p->calls++;
    return p->stop_at && p->calls >= p->stop_at;
}

static void
ran_body(void *ctx, long i0, long i1, int w) {
    (void)w;
    prog_ctx *p = ctx;
    /* on a busy machine the other threads could run every item before the
     * caller, which alone reports, runs its first chunk: with hold they
     * wait (at most 10 s) for its first report */
    for (int k = 0; p->hold && omp_get_thread_num() != 0 && k < 100000; k++) {
        int calls;
#pragma omp atomic read
        calls = p->calls;
        if (calls > 0)
            break;
        thrd_sleep(&(struct timespec){.tv_sec = 0, .tv_nsec = 100000}, NULL);
    }
#pragma omp atomic
    p->ran += i1 - i0;
}

static void
test_progress_and_cancel(void **state) {
    (void)state;
    prog_ctx p = {0};
    vv_progress pg = {prog_cb, &p};
    vv_parallel_progress pr = {&pg, 0.25, 0.75, 1};
    /* one thread: a report after each of the 10 chunks, the last at p1 */
    vt_ok(vv_parallel_for(100, 10, 1, ran_body, &p, &pr));
    assert_int_equal(p.calls, 10);
    assert_false(p.bad);
    assert_near(p.last, 0.75, 1e-15);
    assert_int_equal(p.ran, 100);
    /* every 4th chunk */
    memset(&p, 0, sizeof p);
    pr.every = 4;
    vt_ok(vv_parallel_for(100, 10, 1, ran_body, &p, &pr));
    assert_int_equal(p.calls, 2);
    /* several threads: reports come from the caller only (after its own
     * chunks: on a busy machine it may run none), rising */
    memset(&p, 0, sizeof p);
    pr.every = 1;
    vt_ok(vv_parallel_for(10000, 10, 4, ran_body, &p, &pr));
    assert_false(p.bad);
    assert_int_equal(p.ran, 10000);
    /* a cancel at the 2nd report: one thread runs exactly 2 chunks */
    memset(&p, 0, sizeof p);
    p.stop_at = 2;
    vv_error_clear();
    assert_int_equal(vv_parallel_for(100, 10, 1, ran_body, &p, &pr), VV_ERR_CANCELLED);
    assert_string_equal(vv_error_message(), "cancelled");
    assert_int_equal(p.ran, 20);
    /* with threads, the others stop too: far from every item runs */
    memset(&p, 0, sizeof p);
    p.stop_at = 1;
    p.hold = 1;
    assert_int_equal(vv_parallel_for(1000000, 1, 4, ran_body, &p, &pr), VV_ERR_CANCELLED);
    assert_true(p.ran < 1000000);
    /* no callback: no reports, no cancellation */
    vv_progress none = {NULL, NULL};
    vv_parallel_progress pn = {&none, 0, 1, 1};
    memset(&p, 0, sizeof p);
    vt_ok(vv_parallel_for(50, 5, 2, ran_body, &p, &pn));
    assert_int_equal(p.ran, 50);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_item_once),
        cmocka_unit_test(test_nested),
        cmocka_unit_test(test_progress_and_cancel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
