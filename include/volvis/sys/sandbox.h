/*
 * The reader sandbox (src/sandbox; docs/security.md, "The reader
 * sandbox"): a transport under the format table. The rows of the table
 * whose parsers are a third party's (VV_FORMAT_FLAG_THIRD_PARTY: Teem,
 * nifti_clib, libtiff, GDCM, Assimp, libxml2, NetCDF, HDF5, the Zarr
 * codecs) run in a separate process, volvis-reader, exec'd fresh for each
 * read (a pyramid's store: long-lived readers, one chunk at a time), locked
 * down before it touches the file: Landlock (read access beneath the
 * input's folder only), seccomp (no sockets, no execve, no new processes,
 * read-only opens, no executable memory), no core file, limits on address
 * space and CPU time. Its result comes back in a sealed memfd that the
 * parent checks and maps; a crash, abort, out-of-memory or time-out is one
 * error line in the parent.
 *
 * The sandbox knows no format: the parent's side (vv_sandbox_call,
 * vv_sandbox_open_store; src/io/transport.c calls them for the table)
 * names the row and hands over the arguments as bytes; the reader's side
 * (vv_sandbox_serve, run by volvis-reader through vv_format_reader_main)
 * calls the handler the program gives it, which calls the row's read
 * directly. Nothing tells the two sides apart but the function each runs.
 *
 * The library starts its own reader: $VOLVIS_READER, else the
 * volvis-reader beside the object the library's code was loaded from
 * (libvolvis.so, or the program it is linked into), else in ../libexec
 * from there, else the build tree's and then the installed one compiled
 * in; one that speaks another protocol is refused in one line.
 *
 * Thread-safety: every call starts its own reader; thread-safe.
 */
#ifndef VOLVIS_SYS_SANDBOX_H
#define VOLVIS_SYS_SANDBOX_H

#include <stddef.h>
#include <stdint.h>

#include "../core.h"
#include "../grid.h"
#include "../mesh.h"
#include "../volume.h"
#include "source.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The protocol between the library and its reader (a reader of another one is refused). */
#define VV_SANDBOX_PROTOCOL 8

/** What a reader is asked for. */
typedef enum vv_sandbox_op {
    VV_SANDBOX_VOLUME = 0, /**< a volume (vv_volume) and the row's info bytes */
    VV_SANDBOX_LIST = 1, /**< a listing as bytes (a DICOM folder's series), checked by the caller */
    VV_SANDBOX_MESH = 2, /**< a triangle mesh (vv_mesh) */
    VV_SANDBOX_GRID = 3, /**< an irregular grid (vv_grid) */
    VV_SANDBOX_STORE = 4, /**< a pyramid's store, served chunk by chunk (vv_sandbox_open_store) */
} vv_sandbox_op;

/** Bytes of a call's arguments and of a result's info at most. */
#define VV_SANDBOX_ARGS_MAX 256
#define VV_SANDBOX_INFO_MAX 1024
/** Bytes of a format's name in a call, with its NUL. */
#define VV_SANDBOX_NAME_MAX 32

/** One read asked of a reader. */
typedef struct vv_sandbox_call {
    vv_sandbox_op op;
    /** the table row to read with (its name, < VV_SANDBOX_NAME_MAX bytes); "" or NULL:
     *  the reader detects it (the deep tests too: they may call third-party parsers) */
    const char *format;
    /** for messages until the reader names its row: the format's name and title
     *  ("nrrd", "NRRD"); NULL: "load", "file" */
    const char *name, *title;
    const char *path; /**< the file or folder (shorter than 4096 bytes) */
    const void *args; /**< the handler's arguments, as it reads them (may be NULL) */
    size_t args_len;  /**< <= VV_SANDBOX_ARGS_MAX */
} vv_sandbox_call;

/** What a reader gave back (vv_sandbox_result_clear frees it). */
typedef struct vv_sandbox_result {
    vv_volume *volume; /**< VV_SANDBOX_VOLUME: the voxels, a private mapping of the reader's
                            sealed memfd (released by vv_volume_free) */
    vv_mesh *mesh;     /**< VV_SANDBOX_MESH: copied, every index checked, normals computed here */
    vv_grid *grid;     /**< VV_SANDBOX_GRID: copied, then checked (vv_grid_validate) */
    void *blob;        /**< VV_SANDBOX_LIST: the listing's bytes (malloc'd; unchecked) */
    size_t blob_len;
    /** VV_SANDBOX_VOLUME, VV_SANDBOX_STORE: the handler's info bytes (unchecked: the caller
     *  checks every field) */
    unsigned char info[VV_SANDBOX_INFO_MAX];
    size_t info_len;
    char format[VV_SANDBOX_NAME_MAX]; /**< the row the reader named ("" when none) */
} vv_sandbox_result;

/** Frees what @p r holds and zeroes it. */
void vv_sandbox_result_clear(vv_sandbox_result *r);

/** 1 unless $VOLVIS_SANDBOX is "0" (third-party rows are then read in this process). */
int vv_sandbox_enabled(void);

/**
 * 1 when $VOLVIS_SANDBOX is "all": the built-in rows of our own parsers
 * (SLC, MetaImage, VTK legacy, OpenDX, PLOT3D, raw, a .vvb read whole; not
 * .vvc, which vv_vvc_load reads without the table)
 * are read in the reader too, not only the third parties' (docs/security.md,
 * "Our own parsers under attack"). A row added at run time still reads in
 * this process: the reader knows the built-in rows only.
 */
int vv_sandbox_all(void);

/**
 * Runs @p c in a new reader and waits for its result (*@p out zeroed
 * first). Errors: the reader's own (its status and trace); VV_ERR_FORMAT
 * when it crashed, aborted, was killed by the sandbox or sent a malformed
 * reply ("nrrd: a.nrrd: the NRRD reader crashed (SIGSEGV); the file is
 * malformed"); VV_ERR_LIMIT when it ran out of time or memory; VV_ERR_IO
 * when no reader is found, it cannot start, or it speaks another protocol
 * ("...: the reader /usr/libexec/volvis-reader speaks protocol 5, this
 * library 6"). Thread-safe.
 */
vv_status vv_sandbox_call_reader(const vv_sandbox_call *c, vv_sandbox_result *out);

/**
 * A pyramid's store (vv_store) read by long-lived readers: @p c's op is
 * VV_SANDBOX_STORE; two readers a thread (2 vv_threads_get, at most 16)
 * open it, each locked down as every reader, and serve one chunk at a time
 * into a window shared with this process, copied out once; a chunk may be
 * asked ahead (the store's prefetch). Nothing is trusted: the table the
 * readers send (levels, counts, geometry, range) is checked and must be
 * the same from every reader, each chunk's size and seals are checked, a
 * request waits at most the sandbox's time limit; a crash, stall or
 * malformed reply stops that reader with one error line, which every later
 * read of the store repeats. @p info gets the first reader's info bytes
 * (@p info_len: their count). Errors as vv_sandbox_call_reader.
 */
vv_status vv_sandbox_open_store(const vv_sandbox_call *c, vv_store *st,
                                unsigned char info[VV_SANDBOX_INFO_MAX], size_t *info_len);

/**
 * Starts the reader for the next read that a volume read (op
 * VV_SANDBOX_VOLUME, a process's second and later) left to be started
 * after it: vv_volume_load calls it once it is done with the voxels, so
 * that the start (dynamic linking, GDCM's dictionary: tens of ms of a
 * core) takes no core from the read. Does nothing when none is owed.
 * Thread-safe.
 */
void vv_sandbox_after_load(void);

/**
 * Stops the reader started ahead for the next read (one is kept,
 * process-wide), for tests that count child processes and for a program
 * that wants none left idle. Thread-safe.
 */
void vv_sandbox_release_spare(void);

/* ---- the reader's side ---------------------------------------------------------- */

typedef struct vv_sandbox_server vv_sandbox_server;

/**
 * Names the row the reader reads with, before it reads (so that a crash
 * is named after its reader): its name and title. Handlers call it once.
 */
void vv_sandbox_announce(vv_sandbox_server *srv, const char *name, const char *title);

/**
 * What a reader runs for each op: @p format names the row ("": detect it,
 * then announce it), @p args / @p n the caller's argument bytes (checked
 * by the handler), @p one_shot 1 (the process ends after it: checks that
 * only keep a long-lived process from a library's leaks may be skipped).
 * A handler announces its row and returns the result or an error (its
 * trace travels back). Info bytes: at most VV_SANDBOX_INFO_MAX.
 */
typedef struct vv_sandbox_handler {
    vv_status (*volume)(vv_sandbox_server *srv, const char *format, const char *path,
                        const void *args, size_t n, vv_volume **out, unsigned char *info,
                        size_t *info_len);
    vv_status (*list)(vv_sandbox_server *srv, const char *format, const char *path,
                      const void *args, size_t n, void **blob, size_t *len);
    vv_status (*mesh)(vv_sandbox_server *srv, const char *format, const char *path, vv_mesh **out);
    vv_status (*grid)(vv_sandbox_server *srv, const char *format, const char *path, vv_grid **out);
    vv_status (*store)(vv_sandbox_server *srv, const char *format, const char *path,
                       const void *args, size_t n, vv_store *st, unsigned char *info,
                       size_t *info_len);
} vv_sandbox_handler;

/**
 * The reader process: reads the request from descriptor 3, locks the
 * process down (the limits from the request), runs @p h's handler for it,
 * sends the result back in a sealed memfd or the error trace as text, and
 * ends the process with _exit(0) (a store's reader serves chunks until
 * the parent closes its end). Returns (2) only when it was not started by
 * the library: no request on descriptor 3, or a malformed one. Not
 * thread-safe: the whole process is the reader.
 */
int vv_sandbox_serve(int argc, char **argv, const vv_sandbox_handler *h);

#ifdef __cplusplus
}
#endif

#endif
