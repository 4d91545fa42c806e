/*
 * Calls into libraries that end the process on their own assertions
 * (Debian builds Assimp and GDCM with assertions on: a malformed file can
 * make them call abort()). A guarded call turns such an abort, raised on the
 * calling thread, into an error return; aborts on other threads, or outside
 * guarded calls, keep the process's previous SIGABRT disposition.
 *
 * The handler is installed while at least one guarded call runs (counted
 * under a lock) and each thread keeps its own jump buffer, so guarded calls
 * on several threads run concurrently. glibc's abort() releases its lock
 * and resets its stage before raising SIGABRT, so that a handler may leave
 * by siglongjmp and abort() can be called again later. What the library had
 * allocated in the interrupted call is lost (a leak on a malformed file
 * only), and its C++ destructors do not run.
 */
#include <pthread.h>
#include <setjmp.h>
#include <signal.h>
#include <stddef.h>

#include "core/internal.h"

static pthread_mutex_t guard_lock = PTHREAD_MUTEX_INITIALIZER;
static int guard_users;
static struct sigaction guard_old;
static _Thread_local sigjmp_buf *guard_jmp;

static void
on_abort(int sig) {
    sigjmp_buf *j = guard_jmp;
    if (j) {
        guard_jmp = NULL;
        siglongjmp(*j, 1);
    }
    /* not a guarded call: as before */
    sigaction(sig, &guard_old, NULL);
    raise(sig);
}

int
vv_call_guarded(void (*fn)(void *ctx), void *ctx) {
    if (guard_jmp) { /* nested: the outer call's guard holds */
        fn(ctx);
        return 0;
    }
    pthread_mutex_lock(&guard_lock);
    if (guard_users++ == 0) {
        struct sigaction sa;
        sa.sa_handler = on_abort;
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = 0;
        sigaction(SIGABRT, &sa, &guard_old);
    }
    pthread_mutex_unlock(&guard_lock);
    sigjmp_buf jb;
    volatile int aborted = 0;
    if (sigsetjmp(jb, 1) == 0) {
        guard_jmp = &jb;
        fn(ctx);
        guard_jmp = NULL;
    } else {
        aborted = 1;
    }
    pthread_mutex_lock(&guard_lock);
    if (--guard_users == 0)
        sigaction(SIGABRT, &guard_old, NULL);
    pthread_mutex_unlock(&guard_lock);
    return aborted;
}
