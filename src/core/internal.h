/*
 * Internal helpers shared by the components of libvolvis (not installed).
 */
#ifndef VOLVIS_INTERNAL_H
#define VOLVIS_INTERNAL_H

#include <stdint.h>
#include <stdio.h>

#include "volvis/core.h"
#include "volvis/volume.h"

/**
 * The name of a temporary beside @p path made by process @p pid (a file or
 * a folder that a writer renames over @p path when done), into @p buf of
 * @p cap bytes: "<path>.tmp-<host>-<pid>-<start>-<random>", <host> 8 hex
 * digits hashing the host's name and the PID namespace, <start> the
 * process's start time (clock ticks after boot, /proc/PID/stat; 0 where
 * unknown), <random> 6 hex digits varied by @p attempt (a writer retries
 * on EEXIST). The owner in the name lets vv_tmp_sweep tell a temporary of
 * a writer that is gone from one still being written. Returns 0, or -1
 * when it does not fit. Reentrant.
 */
int vv_tmp_name(char *buf, size_t cap, const char *path, long pid, unsigned attempt);

/**
 * 1 when directory entry @p name is a temporary of target base name
 * @p base as vv_tmp_name makes them, with its owner in *@p host, *@p pid
 * (> 0) and *@p start; 0 for any other name (left alone by the sweep).
 */
int vv_tmp_parse(const char *name, const char *base, uint32_t *host, long *pid,
                 unsigned long long *start);

/**
 * Removes the temporaries of @p path left by writers that are gone: every
 * entry of @p path's folder named as vv_tmp_name names them, made on this
 * host and PID namespace, owned by this user, on the folder's file system,
 * whose writer process no longer runs (no such process, a zombie, or a
 * process of another start time that took its id since). Files are
 * unlinked; folders removed with what they hold, through file descriptors
 * (openat with O_NOFOLLOW: a symbolic link inside is removed, never
 * followed; nothing on another file system). Temporaries of running
 * writers (this process's among them) and every other name are left as
 * they are. Best effort, for litter only: failures are ignored. Returns
 * how many temporaries it removed. Called when a writer opens @p path.
 */
int vv_tmp_sweep(const char *path);

/**
 * An output file written atomically: the data goes to an unnamed file in
 * the target's folder (O_TMPFILE; where the file system cannot, a temporary
 * file beside it named by vv_tmp_name), linked and renamed over the target
 * only by vv_atomic_file_commit after fsync. On any failure call
 * vv_atomic_file_abort: the target is untouched and no temporary file is
 * left; a process killed mid-write leaves none either but for the named
 * fallback, which the next vv_atomic_file_open of the same target removes
 * (vv_tmp_sweep). Write through fp, or through fd (then fp must stay unused);
 * the descriptor reads too (libtiff reads back what it wrote).
 */
typedef struct vv_atomic_file {
    FILE *fp;
    int fd;        /**< fp's descriptor, -1 when closed */
    int anonymous; /**< no name yet (O_TMPFILE) */
    char *path;
    char *tmp_path;
} vv_atomic_file;

/**
 * Where vv_volume_new puts voxels: @p alloc returns zeroed memory of
 * @p bytes (NULL on failure) and the release vv_volume_free calls with
 * @p user; NULL restores calloc/free. Set once, before any volume is made
 * and before threads start, by the sandboxed reader (voxels in a memfd that
 * goes to the parent: src/sandbox/payload.c); never by the library's users.
 */
void vv_volume_set_allocator(void *(*alloc)(size_t bytes), void (*release)(void *user, void *data));

/**
 * The folder of the memory cgroup hierarchy the process is in (the root of
 * what vv_memory_budget_check reads: the sandboxed reader may read beneath
 * it), in @p buf; 0 when there is none or it does not fit. Thread-safe.
 */
int vv_memory_cgroup_root(char *buf, size_t cap);

/* vv_volume_check_size without the memory budget: the dims, voxel count and
 * byte limits only, for readers that never hold the whole volume (bricks,
 * pyramids, out-of-core NRRD and raw). */
vv_status vv_volume_check_limits(const int dims[3], vv_voxel_type t, uint64_t *bytes);

/* Gives @p v the geometry of @p h (spacing, origin, direction, unit,
 * anatomical space): a box or level read from a store takes its level's. */
void vv_volume_take_geometry(vv_volume *v, const vv_volume *h);

/** Opens the temporary file. Errors: VV_ERR_IO (with path and strerror), VV_ERR_NOMEM. */
vv_status vv_atomic_file_open(vv_atomic_file *af, const char *path);
/** Flushes, closes and renames. Errors: VV_ERR_IO (the temporary is removed). */
vv_status vv_atomic_file_commit(vv_atomic_file *af);
/** Closes and removes the temporary file. Safe to call twice or after a failed open. */
void vv_atomic_file_abort(vv_atomic_file *af);

/**
 * Reads a whole file into memory (NUL-terminated for convenience). Refuses
 * files larger than @p max_bytes, or than the memory budget allows
 * (vv_memory_budget_check: the whole file is held), with VV_ERR_LIMIT.
 * Errors: VV_ERR_IO.
 */
vv_status vv_read_file(const char *path, uint64_t max_bytes, unsigned char **data, uint64_t *size);

/**
 * Opens @p path for binary reading and checks that it is a regular file
 * (not a directory or a device); stores its size. The message does not name
 * the file: callers prefix "<format>: <name>". Errors: VV_ERR_IO.
 */
vv_status vv_open_regular(const char *path, FILE **fp, uint64_t *size);

/** Base name of a path (pointer into it). */
const char *vv_path_basename(const char *path);

/**
 * Joins @p rel to the directory of @p base_file unless @p rel is absolute.
 * Returns a malloc'ed string or NULL on allocation failure.
 */
char *vv_path_join_dir(const char *base_file, const char *rel);

/**
 * The detached-data policy (docs/formats.md, "Detached data files"): resolves
 * the data file name @p rel that the header file @p header names. Refused
 * (VV_ERR_FORMAT, the message names @p rel and why): an empty name, an
 * absolute path, a ".." component, a name that resolves (through symbolic
 * links) outside the header's folder, and anything but a regular file (a
 * folder, a device such as /dev/zero, a FIFO). A missing file is VV_ERR_IO.
 * On success *out is the joined path (malloc'ed) and *size the file's size
 * (either may be NULL).
 */
vv_status vv_detached_path(const char *header, const char *rel, char **out, uint64_t *size);

/** 1 when the host is little-endian. */
int vv_host_is_little_endian(void);

/** Reverses the bytes of @p count elements of @p size bytes each, in place. */
void vv_byteswap(void *data, uint64_t count, size_t size);

/**
 * Voxel @p idx (linear index, i fastest) of @p v in its native type, as
 * double. For inner loops; vv_volume_get is the checked public form.
 */
static inline double
vv_voxel_at(const vv_volume *v, size_t idx) {
    return vv_voxel_value(v->type, v->data, idx);
}

/**
 * Widens [@p range[0], @p range[1]] (start: INFINITY, -INFINITY) to the
 * @p n voxels of type @p type at @p p, as vv_volume_update_range measures
 * them (NaN ignored): a reader that writes a volume piece by piece measures
 * each piece while it is in the cache, and the pieces' union is the whole
 * volume's range, bit for bit. Reentrant.
 */
void vv_range_accumulate(vv_voxel_type type, const void *p, size_t n, double range[2]);

/**
 * Sets @p v's range to @p range measured by vv_range_accumulate over every
 * voxel (an empty or all-NaN one: 0, 0, as vv_volume_update_range), and
 * bumps v->modified.
 */
void vv_volume_set_range(vv_volume *v, const double range[2]);

/** strdup that returns NULL on failure. */
char *vv_strdup(const char *s);

#endif
