/*
 * The reader sandbox (issue 33; docs/security.md, "The reader sandbox"):
 * loads through a third-party parser (Teem, nifti_clib, libtiff, GDCM) run
 * in a separate process, volvis-reader, exec'd fresh for each load (also
 * the DICOM series listing, Assimp's meshes and the libxml2 / libnetcdf
 * grids). The
 * child reads the file under a Landlock rule set (read access beneath the
 * input's folder only), a seccomp filter (no sockets, no execve, no new
 * processes, files opened read-only, no executable memory), no core file
 * and limits on address space and CPU time; its voxels come back in a
 * sealed memfd that the parent maps (no copy), its error trace as text.
 * A crash, abort, out-of-memory or time-out in the child is one error line
 * in the parent. Not installed.
 */
#ifndef VOLVIS_IO_SANDBOX_H
#define VOLVIS_IO_SANDBOX_H

#include "io/pyramid.h"
#include "volvis/grid.h"
#include "volvis/io.h"
#include "volvis/mesh.h"
#include "volvis/sys/format.h"
#include "volvis/sys/sandbox.h"

#include <stdint.h>

#define SBX_MAGIC 0x56565342u /* "VVSB" */
#define SBX_MAX_ERROR 4096

/** The kinds of the reader's messages. */
enum { SBX_FORMAT = 1, SBX_RESULT = 2 };

/**
 * A message of the reader to the parent (sent whole, of
 * offsetof(sbx_reply, err) + err_len bytes): kind SBX_FORMAT names the
 * format it detected; kind SBX_RESULT ends the read with a status (a
 * vv_status) and the error trace in err, and on success carries a sealed
 * memfd of @c bytes bytes: for a volume its voxels (x fastest; the
 * geometry in the fields), for a DICOM listing dims[0] vv_dicom_series
 * entries, for a mesh n_vertices positions (3 float32 each, world units)
 * then n_triangles triangles (3 uint32 vertex indices each), for a grid
 * the sections of sbx_grid_head. Nothing in it is trusted:
 * vv_sandbox_take_message checks every field, and copies a grid before it
 * checks it (the child could still write to its memfd).
 */
typedef struct sbx_reply {
    uint32_t magic;
    int32_t kind;
    int32_t format;
    int32_t status;
    int32_t dims[3];
    int32_t type;
    double spacing[3], origin[3], direction[9];
    int32_t unit, data_origin, modification, space;
    /* a volume's vv_load_info (checked: counts in range, the name ended) */
    int32_t n_channels, n_times, has_color, n_levels, n_slices;
    float color[3];
    double time_step;
    int32_t has_raw_layout, raw_big_endian;
    uint64_t raw_offset, raw_step_bytes, raw_channel_bytes;
    char channel_name[VV_CHANNEL_NAME_MAX];
    uint64_t bytes;
    uint64_t n_vertices, n_triangles; /* a mesh: positions then triangles */
    uint64_t file_bytes;              /* a store's chunk: bytes read from storage */
    int32_t missing;                  /* a store's chunk: absent, the fill value */
    uint32_t err_len;
    char err[SBX_MAX_ERROR];
} sbx_reply;

/**
 * 1 when vv_volume_load should read format @p r in the sandbox: @p r is
 * NULL (detection needs the deep tests, which may call a third-party
 * parser) or a third-party format, VOLVIS_SANDBOX is not "0", and this is
 * not the sandboxed reader itself. Thread-safe.
 */
int vv_sandbox_wanted(const vv_volume_format *r);

/**
 * 1 in volvis-reader once it reads its request: a process of one load that
 * ends after it, so that what a library leaks on a malformed file ends with
 * it (checks that exist only to keep a long-lived process from such leaks
 * may be left out there). Thread-safe.
 */
int vv_sandbox_in_reader(void);

/**
 * vv_volume_load's contract, in the sandboxed reader. @p f is the format
 * (VV_FORMAT_AUTO: the child detects it). The voxels are a shared mapping
 * of the child's memfd, released by vv_volume_free. Errors: the child's own
 * (status and trace as it set them); VV_ERR_FORMAT when the child crashed,
 * aborted, was killed by the sandbox or ran out of memory ("nrrd: a.nrrd:
 * the NRRD reader crashed (SIGSEGV); the file is malformed"); VV_ERR_LIMIT
 * when it ran out of time; VV_ERR_IO when volvis-reader cannot be found or
 * started. Thread-safe: each call starts its own child.
 */
vv_status vv_sandbox_volume_load(vv_volume **out, const char *path, vv_format f,
                                 const vv_load_options *opt);

/**
 * vv_dicom_list's contract, in the sandboxed reader: the series of the
 * DICOM file, folder or DICOMDIR @p path as GDCM lists them there, copied
 * back (*@p out a new array of *@p n entries, free() it; every string ends
 * inside its field). Errors: the child's own, or as vv_sandbox_volume_load
 * ("dicom: ct: the DICOM reader crashed (SIGABRT); the file is
 * malformed"). Thread-safe.
 */
vv_status vv_sandbox_dicom_list(vv_dicom_series **out, int *n, const char *path);

/**
 * vv_mesh_load's contract, in the sandboxed reader (Assimp): the
 * positions and triangles come back in a sealed memfd and are copied into
 * a new mesh (every index checked against the vertex count; normals
 * computed again here). Errors: the child's own, or as
 * vv_sandbox_volume_load ("mesh: a.ply: the mesh reader crashed (SIGABRT);
 * the file is malformed"). Thread-safe.
 */
vv_status vv_sandbox_mesh_load(vv_mesh **out, const char *path);

/**
 * A grid in the reader's memfd: this head, then, each section starting on
 * a multiple of 8 bytes: the points (3 * n_points double, world units),
 * the cell types (n_cells bytes), the cell offsets (n_cells + 1 uint64),
 * the connectivity (n_conn uint32), the block dimensions (n_blocks * 3
 * int32), the spherical axes (sph_dims[0] + sph_dims[1] + sph_dims[2]
 * double: r, theta, phi), then n_fields times an sbx_grid_field and its
 * n_tuples * n_components float values.
 */
typedef struct sbx_grid_head {
    int32_t kind; /* vv_grid_kind */
    int32_t n_fields, n_blocks;
    int32_t sph_dims[3];
    uint64_t n_points, n_cells, n_conn;
} sbx_grid_head;

/** A field's head in a grid's memfd (see sbx_grid_head). */
typedef struct sbx_grid_field {
    char name[VV_GRID_FIELD_NAME_MAX];
    int32_t cell_data, n_components, has_fill, pad;
    double fill;
    uint64_t n_tuples;
} sbx_grid_field;

/**
 * vv_grid_load's contract, in the sandboxed reader (libxml2's .vtu,
 * libnetcdf's NetCDF): the grid comes back in a sealed memfd, is copied
 * into a new grid and checked here (vv_grid_validate, every point finite,
 * the blocks and spherical axes consistent with the points; ranges
 * computed again). @p rec is the grid format vv_grid_load detected (its
 * name and title in messages; the reader detects it again). Errors: the
 * child's own, or as vv_sandbox_volume_load ("vtu: a.vtu: the .vtu reader
 * crashed (SIGSEGV); the file is malformed"). Thread-safe.
 */
vv_status vv_sandbox_grid_load(vv_grid **out, const char *path, const vv_grid_format_record *rec);

/** What the reader is asked for (sbx_request.op). */
enum {
    SBX_OP_VOLUME = 0,
    SBX_OP_DICOM_LIST = 1,
    SBX_OP_MESH = 2,
    SBX_OP_GRID = 3,
    SBX_OP_BOXES = 4
};

/** One level of a store as its reader sends it (sbx_store_head). */
typedef struct sbx_level {
    int32_t dims[3], cdims[3], type, unit;
    double spacing[3], origin[3];
} sbx_level;

/** A store's table, sent whole in a sealed memfd (SBX_OP_BOXES). */
typedef struct sbx_store_head {
    int32_t n_levels, n_channels, n_times, has_range;
    double range[2];
    sbx_level lv[VV_PYRAMID_MAX_LEVELS];
} sbx_store_head;

/**
 * A pyramid's store (src/io/pyramid.h) read by long-lived sandboxed
 * readers: the OME-Zarr store or HDF5 file @p path (@p channel, @p time:
 * -1 the first), opened by two volvis-readers a thread (2 vv_threads_get,
 * at most 16), each locked down as every reader. The protocol after the
 * request (op SBX_OP_BOXES, no CPU-time limit: each request is timed
 * instead): a reader answers with one SBX_RESULT whose sealed memfd holds
 * an sbx_store_head (the channel's name and colour in the reply), then
 * serves one chunk (sbx_box: level, chunk indices) at a time, each
 * answered by an SBX_RESULT (missing and file_bytes in the reply, or its
 * error) with the chunk's voxels at the start of its window: a memfd
 * sealed against shrinking and growing, handed over with the table and
 * mapped read-only by the parent, which copies each chunk out once; until
 * the parent closes its end. A chunk may be asked ahead (the store's
 * prefetch) and taken by the read that needs it. Nothing is trusted: the table is checked (levels,
 * counts, geometry, range) and must be the same from every reader, each
 * chunk's size and seals are checked, and a request waits at most the
 * sandbox's time limit; a crash, stall or malformed reply stops that
 * reader with one error line, which every later read of the store
 * repeats. read_chunk is called from several threads at once (a reader
 * each). Errors: the readers' own (not prefixed), or as
 * vv_sandbox_volume_load (prefixed "zarr: FILE" or "hdf5: FILE").
 */
vv_status vv_sandbox_store_open(pyr_store *st, const char *path, int channel, int time,
                                vv_load_info *info);

/** What the parent made of a reader's result: one of the four, by op. */
typedef struct vv_sandbox_answer {
    vv_volume *volume;       /**< SBX_OP_VOLUME: owned by the caller */
    vv_load_info info;       /**< SBX_OP_VOLUME: the file's axes (checked) */
    vv_dicom_series *series; /**< SBX_OP_DICOM_LIST: free() it */
    int n_series;            /**< entries of series */
    vv_mesh *mesh;           /**< SBX_OP_MESH: owned by the caller */
    vv_grid *grid;           /**< SBX_OP_GRID: owned by the caller */
    vv_status status;        /**< VV_OK, or the error (set with vv_error_set) */
} vv_sandbox_answer;

/**
 * What the parent makes of one message of a reader asked for @p op: @p msg,
 * @p len bytes as received (untrusted: any bytes), with @p fd the
 * descriptor it carried or -1 (owned: closed, or mapped and closed).
 * Returns 0 when more is to come (a format message: *@p seen is set to the
 * format it names when that is a known one), 1 for the result, in *@p a
 * (zeroed first): a->status is VV_OK with the volume, series, mesh or grid, or
 * the error the reader sent or found in its result (VV_ERR_FORMAT,
 * VV_ERR_LIMIT, VV_ERR_NOMEM, naming @p file), and -1 when the message is
 * malformed (no error set). Thread-safe; fuzzed by
 * tests/fuzz/fuzz_sandbox.c.
 */
int vv_sandbox_take_message(int op, const void *msg, size_t len, int fd, vv_format *seen,
                            const char *file, vv_sandbox_answer *a);

/**
 * The format whose signature @p path has (vv_format_detect's first pass
 * only: no test that may call a third-party parser), or VV_FORMAT_UNKNOWN.
 */
vv_format vv_format_detect_signature(const char *path);

/**
 * Stops the reader started ahead for the next load (vv_sandbox_volume_load
 * keeps one, process-wide), for tests that count child processes and for a
 * program that wants none left idle. Thread-safe.
 */
void vv_sandbox_release_spare(void);

#endif
