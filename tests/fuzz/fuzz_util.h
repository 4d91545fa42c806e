/*
 * Shared helpers of the libFuzzer harnesses (tests/fuzz/fuzz_<format>.c).
 *
 * Most readers take a path, so the input is written to a file in a private
 * temporary folder (one per process, removed at exit) and the reader is
 * called on it. The library's memory budget is set low (FUZZ_MEMORY_BUDGET)
 * so that a header that claims a huge volume is refused with VV_ERR_LIMIT
 * instead of allocating: libFuzzer's -rss_limit_mb (2 GB by default) and
 * -malloc_limit_mb then catch any allocation that escapes the budget.
 *
 * Thread-safety: none; each harness is single-threaded (vv_threads_set(1)).
 */
#ifndef VV_FUZZ_UTIL_H
#define VV_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>

/** Memory budget of the library under the fuzzer: 256 MiB. */
#define FUZZ_MEMORY_BUDGET ((uint64_t)256 << 20)

/**
 * Sets the budget, one thread, VOLVIS_SANDBOX=0 (unless set: the parsers
 * are fuzzed in this process), and makes the private temporary folder.
 */
void fuzz_init(void);

/**
 * Writes @p size bytes to "<tmpdir>/<name>" (replacing it) and returns the
 * path (static storage, valid until the next call with the same name slot).
 * Aborts on an I/O error (the fuzzer's machine, not the input, is at fault).
 */
const char *fuzz_write(const char *name, const uint8_t *data, size_t size);

/** libFuzzer's start-up hook, shared by every harness: fuzz_init(). */
int LLVMFuzzerInitialize(int *argc, char ***argv);

struct vv_volume;
/**
 * Checks a volume a reader returned (NULL: nothing): it has voxels and its
 * buffer holds them all (the first and last voxel are read, so ASan sees an
 * undersized buffer); then frees it. Traps on an inconsistent volume.
 */
void fuzz_check_volume(struct vv_volume *v);

/**
 * Checks a status a check returned: VV_OK, or a negative error whose
 * message (vv_error_message) is one line and not empty. Traps otherwise.
 * With FUZZ_VERBOSE set in the environment, prints "ok" or the message (to
 * see how far a seed gets).
 */
void fuzz_check_status(int status);

struct vv_source;
/**
 * Reads a box of at most 10^3 voxels from a third into every level of
 * @p s, and the coarsest level's proxy, checking each status and volume
 * (fuzz_zarr, fuzz_bdv: what a renderer asks of a source opened out of core).
 */
void fuzz_read_source(struct vv_source *s);

/** The private temporary folder. */
const char *fuzz_dir(void);

/** Removes everything beneath folder @p path (depth-first, at most 16 folders
 *  deep, links not followed), then the folder; errors are ignored (what a
 *  harness cannot remove, the next input's removal tries again). */
void fuzz_rm_tree(const char *path);

/**
 * Splits @p data at the first occurrence of @p sep (a line such as
 * "\n--DATA--\n"): the part before goes to *a, the part after to *b; when
 * absent, the whole input is *a and *b is empty.
 */
void fuzz_split(const uint8_t *data, size_t size, const char *sep, const uint8_t **a, size_t *na,
                const uint8_t **b, size_t *nb);

#endif
