/* GLib's synchronisation made visible to ThreadSanitizer (VOLVIS_TSAN builds
 * only; docs/security.md, "Threads under ThreadSanitizer").
 *
 * GLib's GMutex, GRecMutex, GRWLock and GCond are futex-based on Linux, and
 * a hand-off to the main loop (g_idle_add, g_timeout_add,
 * g_main_context_invoke, a GTask's thread and its completion) goes through
 * GMainContext's and GThreadPool's own locks inside libglib. TSan sees none
 * of them: GLib is not instrumented, and Debian links libglib with
 * -Bsymbolic-functions, so its internal calls (g_idle_add to g_idle_add_full,
 * the main context's g_mutex_lock) cannot be interposed at all. Without help
 * a TSan run of volvis-gui reports every hand-off as a race.
 *
 * This file is linked into volvis-gui only when VOLVIS_TSAN is on. Its
 * definitions of GLib's public functions take precedence over libglib's for
 * every call made through a PLT (our code, GTK, GIO, GDK); each calls the
 * real function (dlsym(RTLD_NEXT)) inside TSan's annotations:
 *   - the locks: __tsan_mutex_pre/post_lock and _unlock (read locks, try
 *     locks, recursion), g_cond_wait as unlock + relock of its mutex (TSan's
 *     model of pthread_cond_wait: the condition itself carries nothing).
 *     g_mutex_init and _clear are not annotated: TSan would take them for
 *     writes to the lock, and GIO hands its own locks (a GTask's) between
 *     threads through calls inside libgio that nothing here can see; a lock
 *     is known to TSan from its first use and forgotten when freed;
 *   - g_once_init_leave releases the location, g_once_init_enter acquires it
 *     (the macro's inline atomic load acquires the same address);
 *   - sources added by g_idle_add*, g_timeout_add* and g_main_context_invoke*:
 *     the callback is wrapped; the poster releases a box holding it, the
 *     callback acquires the box before it runs;
 *   - GTask: g_task_run_in_thread* release the task and the thread function
 *     acquires it; g_task_return_* release the task; the accessors the
 *     completion callback uses (g_task_propagate_*, g_task_had_error,
 *     g_task_get_task_data) acquire it.
 * Nothing here adds synchronisation the program does not have: every
 * release/acquire pair stands for a real edge through GLib's own locks.
 *
 * VOLVIS_TSAN_GLIB=0 in the environment turns the annotations off (the
 * functions only forward), to show what TSan reports without them. */
#define _GNU_SOURCE /* RTLD_NEXT */
#include <dlfcn.h>
#include <gio/gio.h>
#include <glib.h>
#include <sanitizer/tsan_interface.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 1 unless VOLVIS_TSAN_GLIB=0; decided on the first call (a library's
 * constructor may lock before ours runs), the same for the whole run */
static int annotate_state = -1;

static int
annotate_on(void) {
    int a = __atomic_load_n(&annotate_state, __ATOMIC_RELAXED);
    if (a < 0) {
        const char *e = getenv("VOLVIS_TSAN_GLIB");
        a = !(e && strcmp(e, "0") == 0);
        __atomic_store_n(&annotate_state, a, __ATOMIC_RELAXED);
    }
    return a;
}

__attribute__((constructor)) static void
tsan_glib_init(void) {
    fprintf(stderr, "volvis-gui: ThreadSanitizer build, GLib synchronisation %s\n",
            annotate_on() ? "annotated" : "NOT annotated (VOLVIS_TSAN_GLIB=0)");
}

/* The next definition of @p name (libglib's, libgio's), found on first use;
 * atomics so that two threads may look it up at once. */
static void *
real_fn(void **slot, const char *name) {
    void *f = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
    if (!f) {
        f = dlsym(RTLD_NEXT, name);
        if (!f) {
            fprintf(stderr, "vvg-tsan: %s not found: %s\n", name, dlerror());
            abort();
        }
        __atomic_store_n(slot, f, __ATOMIC_RELEASE);
    }
    return f;
}

#define REAL(ret, name, params)                                                                    \
    static void *real_##name##_slot;                                                               \
    typedef ret(*name##_fn) params;                                                                \
    static name##_fn real_##name(void) {                                                           \
        return (name##_fn)real_fn(&real_##name##_slot, #name);                                     \
    }

/* These definitions replace GLib's public functions: each is declared in
 * GLib's headers, so -Wmissing-prototypes has nothing to say. */

/* ---- GMutex ---------------------------------------------------------------- */

REAL(void, g_mutex_lock, (GMutex *))
REAL(gboolean, g_mutex_trylock, (GMutex *))
REAL(void, g_mutex_unlock, (GMutex *))

void
g_mutex_lock(GMutex *m) {
    if (!annotate_on()) {
        real_g_mutex_lock()(m);
        return;
    }
    __tsan_mutex_pre_lock(m, 0);
    real_g_mutex_lock()(m);
    __tsan_mutex_post_lock(m, 0, 0);
}

gboolean
g_mutex_trylock(GMutex *m) {
    if (!annotate_on())
        return real_g_mutex_trylock()(m);
    __tsan_mutex_pre_lock(m, __tsan_mutex_try_lock);
    gboolean ok = real_g_mutex_trylock()(m);
    __tsan_mutex_post_lock(m, __tsan_mutex_try_lock | (ok ? 0 : __tsan_mutex_try_lock_failed), 0);
    return ok;
}

void
g_mutex_unlock(GMutex *m) {
    if (!annotate_on()) {
        real_g_mutex_unlock()(m);
        return;
    }
    __tsan_mutex_pre_unlock(m, 0);
    real_g_mutex_unlock()(m);
    __tsan_mutex_post_unlock(m, 0);
}

/* ---- GRecMutex ------------------------------------------------------------- */

REAL(void, g_rec_mutex_lock, (GRecMutex *))
REAL(gboolean, g_rec_mutex_trylock, (GRecMutex *))
REAL(void, g_rec_mutex_unlock, (GRecMutex *))

void
g_rec_mutex_lock(GRecMutex *m) {
    if (!annotate_on()) {
        real_g_rec_mutex_lock()(m);
        return;
    }
    __tsan_mutex_pre_lock(m, __tsan_mutex_write_reentrant);
    real_g_rec_mutex_lock()(m);
    __tsan_mutex_post_lock(m, __tsan_mutex_write_reentrant, 0);
}

gboolean
g_rec_mutex_trylock(GRecMutex *m) {
    if (!annotate_on())
        return real_g_rec_mutex_trylock()(m);
    unsigned f = __tsan_mutex_write_reentrant | __tsan_mutex_try_lock;
    __tsan_mutex_pre_lock(m, f);
    gboolean ok = real_g_rec_mutex_trylock()(m);
    __tsan_mutex_post_lock(m, f | (ok ? 0 : __tsan_mutex_try_lock_failed), 0);
    return ok;
}

void
g_rec_mutex_unlock(GRecMutex *m) {
    if (!annotate_on()) {
        real_g_rec_mutex_unlock()(m);
        return;
    }
    __tsan_mutex_pre_unlock(m, 0);
    real_g_rec_mutex_unlock()(m);
    __tsan_mutex_post_unlock(m, 0);
}

/* ---- GRWLock ---------------------------------------------------------------- */

REAL(void, g_rw_lock_writer_lock, (GRWLock *))
REAL(gboolean, g_rw_lock_writer_trylock, (GRWLock *))
REAL(void, g_rw_lock_writer_unlock, (GRWLock *))
REAL(void, g_rw_lock_reader_lock, (GRWLock *))
REAL(gboolean, g_rw_lock_reader_trylock, (GRWLock *))
REAL(void, g_rw_lock_reader_unlock, (GRWLock *))

void
g_rw_lock_writer_lock(GRWLock *l) {
    if (!annotate_on()) {
        real_g_rw_lock_writer_lock()(l);
        return;
    }
    __tsan_mutex_pre_lock(l, 0);
    real_g_rw_lock_writer_lock()(l);
    __tsan_mutex_post_lock(l, 0, 0);
}

gboolean
g_rw_lock_writer_trylock(GRWLock *l) {
    if (!annotate_on())
        return real_g_rw_lock_writer_trylock()(l);
    __tsan_mutex_pre_lock(l, __tsan_mutex_try_lock);
    gboolean ok = real_g_rw_lock_writer_trylock()(l);
    __tsan_mutex_post_lock(l, __tsan_mutex_try_lock | (ok ? 0 : __tsan_mutex_try_lock_failed), 0);
    return ok;
}

void
g_rw_lock_writer_unlock(GRWLock *l) {
    if (!annotate_on()) {
        real_g_rw_lock_writer_unlock()(l);
        return;
    }
    __tsan_mutex_pre_unlock(l, 0);
    real_g_rw_lock_writer_unlock()(l);
    __tsan_mutex_post_unlock(l, 0);
}

void
g_rw_lock_reader_lock(GRWLock *l) {
    if (!annotate_on()) {
        real_g_rw_lock_reader_lock()(l);
        return;
    }
    __tsan_mutex_pre_lock(l, __tsan_mutex_read_lock);
    real_g_rw_lock_reader_lock()(l);
    __tsan_mutex_post_lock(l, __tsan_mutex_read_lock, 0);
}

gboolean
g_rw_lock_reader_trylock(GRWLock *l) {
    if (!annotate_on())
        return real_g_rw_lock_reader_trylock()(l);
    __tsan_mutex_pre_lock(l, __tsan_mutex_try_read_lock);
    gboolean ok = real_g_rw_lock_reader_trylock()(l);
    __tsan_mutex_post_lock(l, ok ? __tsan_mutex_try_read_lock : __tsan_mutex_try_read_lock_failed,
                           0);
    return ok;
}

void
g_rw_lock_reader_unlock(GRWLock *l) {
    if (!annotate_on()) {
        real_g_rw_lock_reader_unlock()(l);
        return;
    }
    __tsan_mutex_pre_unlock(l, __tsan_mutex_read_lock);
    real_g_rw_lock_reader_unlock()(l);
    __tsan_mutex_post_unlock(l, __tsan_mutex_read_lock);
}

/* ---- GCond: the wait unlocks and relocks its mutex ----------------------------- */

REAL(void, g_cond_wait, (GCond *, GMutex *))
REAL(gboolean, g_cond_wait_until, (GCond *, GMutex *, gint64))

static void
cond_released(GMutex *m) {
    __tsan_mutex_pre_unlock(m, 0);
    __tsan_mutex_post_unlock(m, 0);
}

static void
cond_reacquired(GMutex *m) {
    __tsan_mutex_pre_lock(m, 0);
    __tsan_mutex_post_lock(m, 0, 0);
}

void
g_cond_wait(GCond *c, GMutex *m) {
    if (annotate_on())
        cond_released(m);
    real_g_cond_wait()(c, m);
    if (annotate_on())
        cond_reacquired(m);
}

gboolean
g_cond_wait_until(GCond *c, GMutex *m, gint64 end_time) {
    if (annotate_on())
        cond_released(m);
    gboolean r = real_g_cond_wait_until()(c, m, end_time);
    if (annotate_on())
        cond_reacquired(m);
    return r;
}

/* ---- g_once_init_enter / g_once_init_leave (G_DEFINE_TYPE) ------------------------ */

REAL(gboolean, g_once_init_enter, (volatile void *))
REAL(void, g_once_init_leave, (volatile void *, gsize))

/* GLib's header defines g_once_init_enter/leave as macros around the functions */
#undef g_once_init_enter
#undef g_once_init_leave

gboolean g_once_init_enter(volatile void *location);
void g_once_init_leave(volatile void *location, gsize result);

gboolean
g_once_init_enter(volatile void *location) {
    gboolean must_init = real_g_once_init_enter()(location);
    if (annotate_on() && !must_init)
        __tsan_acquire((void *)location);
    return must_init;
}

void
g_once_init_leave(volatile void *location, gsize result) {
    if (annotate_on())
        __tsan_release((void *)location);
    real_g_once_init_leave()(location, result);
}

/* ---- sources: idle, timeout, invoke ---------------------------------------------- */

/* One source's callback; the box's address is the synchronisation object. */
typedef struct box {
    GSourceFunc func;
    GSourceOnceFunc once;
    gpointer data;
    GDestroyNotify destroy;
} box;

static gboolean
box_call(gpointer p) {
    box *b = p;
    __tsan_acquire(b);
    if (b->once) {
        b->once(b->data);
        return G_SOURCE_REMOVE;
    }
    return b->func(b->data);
}

static void
box_free(gpointer p) {
    box *b = p;
    if (b->destroy)
        b->destroy(b->data);
    g_free(b);
}

static box *
box_new(GSourceFunc func, GSourceOnceFunc once, gpointer data, GDestroyNotify destroy) {
    box *b = g_new(box, 1);
    b->func = func;
    b->once = once;
    b->data = data;
    b->destroy = destroy;
    __tsan_release(b);
    return b;
}

REAL(guint, g_idle_add_full, (gint, GSourceFunc, gpointer, GDestroyNotify))
REAL(guint, g_idle_add, (GSourceFunc, gpointer))
REAL(guint, g_idle_add_once, (GSourceOnceFunc, gpointer))
REAL(guint, g_timeout_add_full, (gint, guint, GSourceFunc, gpointer, GDestroyNotify))
REAL(guint, g_timeout_add, (guint, GSourceFunc, gpointer))
REAL(guint, g_timeout_add_once, (guint, GSourceOnceFunc, gpointer))
REAL(guint, g_timeout_add_seconds_full, (gint, guint, GSourceFunc, gpointer, GDestroyNotify))
REAL(guint, g_timeout_add_seconds, (guint, GSourceFunc, gpointer))
REAL(void, g_main_context_invoke_full,
     (GMainContext *, gint, GSourceFunc, gpointer, GDestroyNotify))
REAL(void, g_main_context_invoke, (GMainContext *, GSourceFunc, gpointer))

guint
g_idle_add_full(gint priority, GSourceFunc func, gpointer data, GDestroyNotify destroy) {
    if (!annotate_on())
        return real_g_idle_add_full()(priority, func, data, destroy);
    return real_g_idle_add_full()(priority, box_call, box_new(func, NULL, data, destroy), box_free);
}

guint
g_idle_add(GSourceFunc func, gpointer data) {
    if (!annotate_on())
        return real_g_idle_add()(func, data);
    return real_g_idle_add_full()(G_PRIORITY_DEFAULT_IDLE, box_call,
                                  box_new(func, NULL, data, NULL), box_free);
}

guint
g_idle_add_once(GSourceOnceFunc func, gpointer data) {
    if (!annotate_on())
        return real_g_idle_add_once()(func, data);
    return real_g_idle_add_full()(G_PRIORITY_DEFAULT_IDLE, box_call,
                                  box_new(NULL, func, data, NULL), box_free);
}

guint
g_timeout_add_full(gint priority, guint ms, GSourceFunc func, gpointer data,
                   GDestroyNotify destroy) {
    if (!annotate_on())
        return real_g_timeout_add_full()(priority, ms, func, data, destroy);
    return real_g_timeout_add_full()(priority, ms, box_call, box_new(func, NULL, data, destroy),
                                     box_free);
}

guint
g_timeout_add(guint ms, GSourceFunc func, gpointer data) {
    if (!annotate_on())
        return real_g_timeout_add()(ms, func, data);
    return real_g_timeout_add_full()(G_PRIORITY_DEFAULT, ms, box_call,
                                     box_new(func, NULL, data, NULL), box_free);
}

guint
g_timeout_add_once(guint ms, GSourceOnceFunc func, gpointer data) {
    if (!annotate_on())
        return real_g_timeout_add_once()(ms, func, data);
    return real_g_timeout_add_full()(G_PRIORITY_DEFAULT, ms, box_call,
                                     box_new(NULL, func, data, NULL), box_free);
}

guint
g_timeout_add_seconds_full(gint priority, guint s, GSourceFunc func, gpointer data,
                           GDestroyNotify destroy) {
    if (!annotate_on())
        return real_g_timeout_add_seconds_full()(priority, s, func, data, destroy);
    return real_g_timeout_add_seconds_full()(priority, s, box_call,
                                             box_new(func, NULL, data, destroy), box_free);
}

guint
g_timeout_add_seconds(guint s, GSourceFunc func, gpointer data) {
    if (!annotate_on())
        return real_g_timeout_add_seconds()(s, func, data);
    return real_g_timeout_add_seconds_full()(G_PRIORITY_DEFAULT, s, box_call,
                                             box_new(func, NULL, data, NULL), box_free);
}

void
g_main_context_invoke_full(GMainContext *ctx, gint priority, GSourceFunc func, gpointer data,
                           GDestroyNotify destroy) {
    if (!annotate_on()) {
        real_g_main_context_invoke_full()(ctx, priority, func, data, destroy);
        return;
    }
    real_g_main_context_invoke_full()(ctx, priority, box_call, box_new(func, NULL, data, destroy),
                                      box_free);
}

void
g_main_context_invoke(GMainContext *ctx, GSourceFunc func, gpointer data) {
    if (!annotate_on()) {
        real_g_main_context_invoke()(ctx, func, data);
        return;
    }
    real_g_main_context_invoke_full()(ctx, G_PRIORITY_DEFAULT, box_call,
                                      box_new(func, NULL, data, NULL), box_free);
}

/* ---- GTask ------------------------------------------------------------------------ */

static GQuark
thread_func_quark(void) {
    static GQuark q;
    if (!__atomic_load_n(&q, __ATOMIC_ACQUIRE))
        __atomic_store_n(&q, g_quark_from_static_string("vvg-tsan-thread-func"), __ATOMIC_RELEASE);
    return __atomic_load_n(&q, __ATOMIC_ACQUIRE);
}

/* The task's thread function, run in GLib's thread pool: acquires what the
 * thread that ran the task released. */
static void
task_call(GTask *task, gpointer source, gpointer data, GCancellable *cancel) {
    __tsan_acquire(task);
    GTaskThreadFunc f = (GTaskThreadFunc)g_object_get_qdata(G_OBJECT(task), thread_func_quark());
    f(task, source, data, cancel);
    __tsan_release(task);
}

REAL(void, g_task_run_in_thread, (GTask *, GTaskThreadFunc))
REAL(void, g_task_run_in_thread_sync, (GTask *, GTaskThreadFunc))

static GTaskThreadFunc
task_wrap(GTask *task, GTaskThreadFunc f) {
    /* (a GTask runs in a thread once) */
    g_object_set_qdata(G_OBJECT(task), thread_func_quark(), (gpointer)f);
    __tsan_release(task);
    return task_call;
}

void
g_task_run_in_thread(GTask *task, GTaskThreadFunc f) {
    real_g_task_run_in_thread()(task, annotate_on() ? task_wrap(task, f) : f);
}

void
g_task_run_in_thread_sync(GTask *task, GTaskThreadFunc f) {
    real_g_task_run_in_thread_sync()(task, annotate_on() ? task_wrap(task, f) : f);
    if (annotate_on())
        __tsan_acquire(task);
}

/* the result, returned from any thread */
REAL(void, g_task_return_boolean, (GTask *, gboolean))
REAL(void, g_task_return_int, (GTask *, gssize))
REAL(void, g_task_return_pointer, (GTask *, gpointer, GDestroyNotify))
REAL(void, g_task_return_value, (GTask *, GValue *))
REAL(void, g_task_return_error, (GTask *, GError *))
REAL(gboolean, g_task_return_error_if_cancelled, (GTask *))

#define RELEASE_TASK(t)                                                                            \
    do {                                                                                           \
        if (annotate_on())                                                                         \
            __tsan_release(t);                                                                     \
    } while (0)

void
g_task_return_boolean(GTask *task, gboolean result) {
    RELEASE_TASK(task);
    real_g_task_return_boolean()(task, result);
}

void
g_task_return_int(GTask *task, gssize result) {
    RELEASE_TASK(task);
    real_g_task_return_int()(task, result);
}

void
g_task_return_pointer(GTask *task, gpointer result, GDestroyNotify destroy) {
    RELEASE_TASK(task);
    real_g_task_return_pointer()(task, result, destroy);
}

void
g_task_return_value(GTask *task, GValue *result) {
    RELEASE_TASK(task);
    real_g_task_return_value()(task, result);
}

void
g_task_return_error(GTask *task, GError *error) {
    RELEASE_TASK(task);
    real_g_task_return_error()(task, error);
}

gboolean
g_task_return_error_if_cancelled(GTask *task) {
    RELEASE_TASK(task);
    return real_g_task_return_error_if_cancelled()(task);
}

void
g_task_return_new_error(GTask *task, GQuark domain, gint code, const char *format, ...) {
    va_list ap;
    va_start(ap, format);
    char *msg = g_strdup_vprintf(format, ap);
    va_end(ap);
    GError *e = g_error_new_literal(domain, code, msg);
    g_free(msg);
    g_task_return_error(task, e);
}

/* what the completion reads */
REAL(gboolean, g_task_propagate_boolean, (GTask *, GError **))
REAL(gssize, g_task_propagate_int, (GTask *, GError **))
REAL(gpointer, g_task_propagate_pointer, (GTask *, GError **))
REAL(gboolean, g_task_propagate_value, (GTask *, GValue *, GError **))
REAL(gboolean, g_task_had_error, (GTask *))
REAL(gpointer, g_task_get_task_data, (GTask *))

#define ACQUIRE_TASK(t)                                                                            \
    do {                                                                                           \
        if (annotate_on())                                                                         \
            __tsan_acquire(t);                                                                     \
    } while (0)

gboolean
g_task_propagate_boolean(GTask *task, GError **error) {
    ACQUIRE_TASK(task);
    return real_g_task_propagate_boolean()(task, error);
}

gssize
g_task_propagate_int(GTask *task, GError **error) {
    ACQUIRE_TASK(task);
    return real_g_task_propagate_int()(task, error);
}

gpointer
g_task_propagate_pointer(GTask *task, GError **error) {
    ACQUIRE_TASK(task);
    return real_g_task_propagate_pointer()(task, error);
}

gboolean
g_task_propagate_value(GTask *task, GValue *value, GError **error) {
    ACQUIRE_TASK(task);
    return real_g_task_propagate_value()(task, value, error);
}

gboolean
g_task_had_error(GTask *task) {
    ACQUIRE_TASK(task);
    return real_g_task_had_error()(task);
}

gpointer
g_task_get_task_data(GTask *task) {
    ACQUIRE_TASK(task);
    return real_g_task_get_task_data()(task);
}
