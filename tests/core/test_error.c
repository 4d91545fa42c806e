/* Status names, the thread-local error trace, progress and threads. */
#include "testutil.h"

#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void
test_trace(void **state) {
    (void)state;
    vv_error_clear();
    assert_string_equal(vv_error_message(), "");
    assert_int_equal(vv_error_set(VV_ERR_FORMAT, "c %d", 3), VV_ERR_FORMAT);
    assert_string_equal(vv_error_message(), "c 3");
    assert_int_equal(vv_error_prefix(VV_ERR_IO, "b%s", ".slc"), VV_ERR_IO);
    assert_string_equal(vv_error_message(), "b.slc: c 3");
    assert_int_equal(vv_error_prefix(VV_ERR_LIMIT, "a"), VV_ERR_LIMIT);
    assert_string_equal(vv_error_message(), "a: b.slc: c 3");
    /* set replaces the whole trace */
    vv_error_set(VV_ERR_INVALID, "fresh");
    assert_string_equal(vv_error_message(), "fresh");
    /* a prefix on an empty trace has no dangling separator */
    vv_error_clear();
    vv_error_prefix(VV_ERR_IO, "only");
    assert_string_equal(vv_error_message(), "only");
    /* percent signs in arguments are not re-interpreted */
    vv_error_set(VV_ERR_IO, "%s", "100%s %d sure");
    vv_error_prefix(VV_ERR_IO, "%s", "%n%n");
    assert_string_equal(vv_error_message(), "%n%n: 100%s %d sure");
    vv_error_clear();
    assert_string_equal(vv_error_message(), "");
}

/* Outer layers naturally pass the current message back in. */
static void
test_trace_self_reference(void **state) {
    (void)state;
    vv_error_set(VV_ERR_FORMAT, "inner");
    vv_error_prefix(VV_ERR_FORMAT, "%s", vv_error_message());
    assert_string_equal(vv_error_message(), "inner: inner");
    vv_error_set(VV_ERR_FORMAT, "inner");
    vv_error_set(VV_ERR_IO, "outer: %s", vv_error_message());
    assert_string_equal(vv_error_message(), "outer: inner");
}

static void
test_trace_long(void **state) {
    (void)state;
    enum { N = 10000 };
    char *big = malloc(N + 1);
    assert_non_null(big);
    for (int i = 0; i < N; i++)
        big[i] = (char)('a' + i % 26);
    big[N] = '\0';
    vv_error_set(VV_ERR_IO, "%s", big);
    size_t n = strlen(vv_error_message());
    assert_true(n > 1000 && n < N); /* truncated, kept long enough to be useful */
    assert_memory_equal(vv_error_message(), big, n);
    size_t cap = n;
    /* a short prefix on a full trace: starts with it, stays within the bound */
    vv_error_prefix(VV_ERR_IO, "file.slc");
    assert_true(strlen(vv_error_message()) <= cap);
    assert_memory_equal(vv_error_message(), "file.slc: abc", 13);
    /* a huge prefix alone */
    vv_error_prefix(VV_ERR_IO, "%s", big);
    assert_true(strlen(vv_error_message()) <= cap);
    assert_memory_equal(vv_error_message(), big, strlen(vv_error_message()));
    vv_error_clear();
    vv_error_prefix(VV_ERR_IO, "%s", big);
    assert_true(strlen(vv_error_message()) <= cap);
    /* many layers */
    vv_error_set(VV_ERR_FORMAT, "root");
    for (int i = 0; i < 2000; i++)
        vv_error_prefix(VV_ERR_FORMAT, "layer %d", i);
    assert_true(strlen(vv_error_message()) <= cap);
    assert_memory_equal(vv_error_message(), "layer 1999: layer 1998: ", 24);
    /* long pieces whose sum is just over the bound, at every split */
    for (size_t a = cap - 8; a <= cap + 2; a++) {
        big[a] = '\0';
        vv_error_set(VV_ERR_IO, "%s", big + 1);
        big[a] = (char)('a' + a % 26);
        vv_error_prefix(VV_ERR_IO, "xy");
        assert_true(strlen(vv_error_message()) <= cap);
        assert_memory_equal(vv_error_message(), "xy: bcd", 7);
    }
    free(big);
    vv_error_clear();
}

typedef struct thread_arg {
    const char *mine;
    pthread_barrier_t *barrier;
    int ok;
    char seen[64];
} thread_arg;

static void *
trace_thread(void *p) {
    thread_arg *a = p;
    vv_error_set(VV_ERR_IO, "%s", a->mine);
    pthread_barrier_wait(a->barrier); /* both have set their message */
    vv_error_prefix(VV_ERR_IO, "t");
    pthread_barrier_wait(a->barrier); /* both have prefixed */
    snprintf(a->seen, sizeof a->seen, "%s", vv_error_message());
    char want[64];
    snprintf(want, sizeof want, "t: %s", a->mine);
    a->ok = strcmp(a->seen, want) == 0;
    return NULL;
}

static void
test_trace_thread_local(void **state) {
    (void)state;
    vv_error_set(VV_ERR_FORMAT, "main thread");
    pthread_barrier_t barrier;
    assert_int_equal(pthread_barrier_init(&barrier, NULL, 2), 0);
    thread_arg a = {"first", &barrier, 0, ""}, b = {"second", &barrier, 0, ""};
    pthread_t ta, tb;
    assert_int_equal(pthread_create(&ta, NULL, trace_thread, &a), 0);
    assert_int_equal(pthread_create(&tb, NULL, trace_thread, &b), 0);
    pthread_join(ta, NULL);
    pthread_join(tb, NULL);
    pthread_barrier_destroy(&barrier);
    if (!a.ok || !b.ok)
        fail_msg("threads saw '%s' and '%s'", a.seen, b.seen);
    assert_string_equal(vv_error_message(), "main thread");
    /* and in OpenMP workers */
    int bad = 0;
#pragma omp parallel num_threads(4) reduction(+ : bad)
    {
        int t = omp_get_thread_num();
        vv_error_set(VV_ERR_IO, "worker %d", t);
#pragma omp barrier
        char want[32];
        snprintf(want, sizeof want, "worker %d", t);
        bad += strcmp(vv_error_message(), want) != 0;
    }
    assert_int_equal(bad, 0);
    vv_error_clear();
}

static void
test_status_names(void **state) {
    (void)state;
    const struct {
        vv_status s;
        const char *name;
    } names[] = {{VV_OK, "VV_OK"},
                 {VV_ERR_NOMEM, "VV_ERR_NOMEM"},
                 {VV_ERR_IO, "VV_ERR_IO"},
                 {VV_ERR_FORMAT, "VV_ERR_FORMAT"},
                 {VV_ERR_INVALID, "VV_ERR_INVALID"},
                 {VV_ERR_UNSUPPORTED, "VV_ERR_UNSUPPORTED"},
                 {VV_ERR_LIMIT, "VV_ERR_LIMIT"},
                 {VV_ERR_CANCELLED, "VV_ERR_CANCELLED"}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        assert_string_equal(vv_status_name(names[i].s), names[i].name);
    /* every error is negative, VV_OK is 0 */
    assert_int_equal(VV_OK, 0);
    for (size_t i = 1; i < sizeof names / sizeof names[0]; i++)
        assert_true(names[i].s < 0);
    /* unknown values still give a string */
    assert_non_null(vv_status_name((vv_status)-99));
    assert_non_null(vv_status_name((vv_status)5));
    assert_true(strcmp(vv_status_name((vv_status)-99), "VV_OK") != 0);
}

typedef struct progress_log {
    int calls;
    double last;
    int cancel_at; /* cancel on this call number (1-based), 0 never */
    int cancel_value;
} progress_log;

static int
record(void *user, double fraction) {
    progress_log *l = user;
    l->calls++;
    l->last = fraction;
    return l->calls == l->cancel_at ? l->cancel_value : 0;
}

static void
test_progress(void **state) {
    (void)state;
    assert_int_equal(vv_progress_report(NULL, 0.5), 0);
    vv_progress none = {NULL, NULL};
    assert_int_equal(vv_progress_report(&none, 0.5), 0);
    progress_log log = {0, -1, 3, 7};
    vv_progress p = {record, &log};
    assert_int_equal(vv_progress_report(&p, 0.25), 0);
    assert_int_equal(log.calls, 1);
    assert_true(log.last == 0.25);
    /* out-of-range fractions reach the callback clamped to [0, 1] */
    assert_int_equal(vv_progress_report(&p, -0.5), 0);
    assert_true(log.last == 0);
    /* a non-zero return (any value) asks to cancel: reported as 1 */
    assert_int_equal(vv_progress_report(&p, 2.0), 1);
    assert_true(log.last == 1);
    assert_int_equal(log.calls, 3);
    assert_int_equal(vv_progress_report(&p, 0.9), 0);
    log.cancel_at = 5;
    log.cancel_value = -1;
    assert_int_equal(vv_progress_report(&p, 1.0), 1);
    /* NaN is not a fraction in [0, 1] */
    log.cancel_at = 0;
    vv_progress_report(&p, NAN);
    if (!(log.last >= 0 && log.last <= 1))
        fail_msg("callback received %g for a NaN fraction", log.last);
}

static void
test_threads(void **state) {
    (void)state;
    vv_threads_set(3);
    assert_int_equal(vv_threads_get(), 3);
    int seen = 0;
#pragma omp parallel
    {
#pragma omp single
        seen = omp_get_num_threads();
    }
    assert_int_equal(seen, 3);
    vv_threads_set(1);
    assert_int_equal(vv_threads_get(), 1);
    vv_threads_set(0); /* the default: all cores */
    assert_int_equal(vv_threads_get(), omp_get_num_procs());
    vv_threads_set(2);
    vv_threads_set(-4);
    assert_int_equal(vv_threads_get(), omp_get_num_procs());
    assert_true(vv_threads_get() >= 1);
}

static void
test_version(void **state) {
    (void)state;
    const char *v = vv_version();
    assert_non_null(v);
    int a = -1, b = -1, c = -1;
    char extra = 0;
    assert_int_equal(sscanf(v, "%d.%d.%d%c", &a, &b, &c, &extra), 3);
    assert_true(a >= 0 && b >= 0 && c >= 0);
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trace),        cmocka_unit_test(test_trace_self_reference),
        cmocka_unit_test(test_trace_long),   cmocka_unit_test(test_trace_thread_local),
        cmocka_unit_test(test_status_names), cmocka_unit_test(test_progress),
        cmocka_unit_test(test_threads),      cmocka_unit_test(test_version),
    };
    return vt_run_tests(tests, NULL, NULL);
}
