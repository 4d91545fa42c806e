/*
 * VolVis core: status codes, the thread-local error trace, progress and
 * cancellation, thread-count control.
 *
 * Thread-safety: everything here is reentrant. The error trace is per thread.
 */
#ifndef VOLVIS_CORE_H
#define VOLVIS_CORE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(__GNUC__)
#define VV_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define VV_PRINTF(a, b)
#endif

/** Result of a fallible function. VV_OK is 0; every error is negative. */
typedef enum vv_status {
    VV_OK = 0,
    VV_ERR_NOMEM = -1,       /**< an allocation failed */
    VV_ERR_IO = -2,          /**< a file could not be opened, read or written */
    VV_ERR_FORMAT = -3,      /**< a file is malformed, truncated or not of its format */
    VV_ERR_INVALID = -4,     /**< an argument is out of its domain */
    VV_ERR_UNSUPPORTED = -5, /**< valid, but not something this build can do */
    VV_ERR_LIMIT = -6,       /**< a size is over a limit (absurd header, overflow) */
    VV_ERR_CANCELLED = -7    /**< the progress callback asked to stop */
} vv_status;

/** Short constant name of a status ("VV_ERR_FORMAT"). Never NULL. */
const char *vv_status_name(vv_status s);

/**
 * The calling thread's error trace: the innermost failure first set by
 * vv_error_set(), with the context each outer layer prefixed by
 * vv_error_prefix(), e.g. "slc: nut.slc: slice 12: run of 40 bytes overflows
 * the slice". Empty string when no error was recorded. The pointer is valid
 * until the next vv_error_* call on this thread.
 */
const char *vv_error_message(void);

/** Clears the calling thread's trace. */
void vv_error_clear(void);

/**
 * Replaces the trace with a formatted message and returns @p s, so a failing
 * function can `return vv_error_set(VV_ERR_FORMAT, "...")`.
 */
vv_status vv_error_set(vv_status s, const char *fmt, ...) VV_PRINTF(2, 3);

/**
 * Prefixes the trace with "<formatted>: " and returns @p s. Used by each
 * outer layer to add where the failure happened (a file name, a slice).
 */
vv_status vv_error_prefix(vv_status s, const char *fmt, ...) VV_PRINTF(2, 3);

/**
 * Progress callback: receives a fraction in [0, 1]; returns non-zero to ask
 * the operation to stop, which then returns VV_ERR_CANCELLED. It may be called
 * from any thread of the operation but never from two threads at once.
 */
typedef int (*vv_progress_fn)(void *user, double fraction);

/** A progress callback and its payload. fn may be NULL (no reporting). */
typedef struct vv_progress {
    vv_progress_fn fn;
    void *user;
} vv_progress;

/**
 * Reports @p fraction to @p p (which may be NULL). Returns 1 if the callback
 * asked to cancel, 0 otherwise. Not thread-safe for one vv_progress: callers
 * that report from a parallel region serialise the call.
 */
int vv_progress_report(const vv_progress *p, double fraction);

/**
 * Sets the default number of threads used by the library's parallel loops
 * (OpenMP). n <= 0 restores the default (all cores). Affects the calling
 * thread's later parallel regions; per-call options can override it.
 */
void vv_threads_set(int n);

/** The number of threads a parallel loop would use now. */
int vv_threads_get(void);

/**
 * The memory budget: the most bytes one reader or decoder may allocate for
 * one object (a volume, a decoded .vvc, a grid, a mesh). Readers check the
 * size a header promises against it before allocating or inflating anything
 * and fail with VV_ERR_LIMIT ("... is over the memory budget of N bytes"),
 * so a small hostile file cannot make the process allocate gigabytes.
 * @p bytes 0 restores the default: the environment variable
 * VOLVIS_MAX_MEMORY when set (a size as vv_memory_size_parse reads it), else
 * half of the memory the process may still use: the machine's available
 * memory (MemAvailable in /proc/meminfo) or, when less, what its memory
 * cgroups allow (version 1 or 2; over the cgroup and its ancestors the least
 * limit less usage, reclaimable page cache not counted), read once; 4 GiB
 * when neither is known; never less than 64 MiB. So under a container's or
 * a systemd unit's memory limit a volume too large for it is refused with
 * VV_ERR_LIMIT instead of the kernel's OOM killer ending the process.
 * Thread-safety: an atomic global; set it before starting work.
 */
void vv_memory_budget_set(uint64_t bytes);

/**
 * The bytes the process may still allocate now without the kernel's OOM
 * killer: the least of the machine's available memory (MemAvailable) and
 * what its memory cgroups allow (limit less usage, reclaimable page cache
 * not counted, over the cgroup and its ancestors). Read afresh at each call
 * (a few small files under /proc and /sys/fs/cgroup); UINT64_MAX when
 * neither is known. The renderers size their optional caches (cached
 * gradients) by it and refuse a required one that does not fit.
 * Thread-safety: safe from any thread.
 */
uint64_t vv_memory_available(void);

/** The budget in bytes now (the default computed on first use). */
uint64_t vv_memory_budget_get(void);

/**
 * VV_OK when @p bytes fit the budget, else VV_ERR_LIMIT with a message
 * naming @p what (e.g. "volume of 512 x 512 x 512 f32"), the size and the
 * budget. A budget raised above what the memory cgroup's limit leaves
 * (vv_memory_available) still fails there: past it the kernel's OOM killer,
 * not an error, would answer.
 */
vv_status vv_memory_budget_check(uint64_t bytes, const char *what);

/**
 * Parses a size: a number of bytes with an optional suffix K, M, G or T
 * (powers of 1024; "KiB", "MB", "GiB" accepted too), e.g. "512M", "8G".
 * Errors: VV_ERR_INVALID naming the text.
 */
vv_status vv_memory_size_parse(const char *text, uint64_t *out);

/** Library version string, "MAJOR.MINOR.PATCH". */
const char *vv_version(void);

#ifdef __cplusplus
}
#endif
#endif
