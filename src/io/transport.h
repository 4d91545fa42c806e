/*
 * Where a format row's work runs, internal to src/io: in this process, or
 * -- for the rows whose parsers are a third party's
 * (VV_FORMAT_FLAG_THIRD_PARTY) -- in the reader sandbox
 * (include/volvis/sys/sandbox.h), chosen here and only here. The entry
 * points (vv_volume_load, vv_open, vv_grid_load, vv_mesh_load,
 * vv_dicom_list) call these; the rows' readers never know which side they
 * run on. The reader process's side is src/io/reader.c, which calls the
 * rows directly.
 */
#ifndef VV_IO_TRANSPORT_H
#define VV_IO_TRANSPORT_H

#include "volvis/io.h"
#include "volvis/sys/format.h"
#include "volvis/sys/sandbox.h"

/** 1 when @p r's work runs in the reader sandbox. */
int io_sandboxed(const vv_format_record *r);

/**
 * @p r's read of @p path (its contract: vv_volume_load's, @p opt never NULL
 * and opt->info never NULL), here or in the sandbox; @p r NULL: the reader
 * detects the format (the deep tests, which may call third-party parsers,
 * in the sandbox) and reads it, and *@p used (may be NULL) gets the row.
 */
vv_status io_read_volume(const vv_format_record *r, vv_volume **out, const char *path,
                         const vv_load_options *opt, const vv_format_record **used);
/** @p r's read of a grid (vv_grid_load's contract), here or in the sandbox. */
vv_status io_read_grid(const vv_format_record *r, vv_grid **out, const char *path);
/** @p r's read of a mesh (vv_mesh_load's contract), here or in the sandbox. */
vv_status io_read_mesh(const vv_format_record *r, vv_mesh **out, const char *path);
/** @p r's store of @p path (open_store's contract), here or by long-lived sandboxed readers. */
vv_status io_open_store(const vv_format_record *r, vv_store *st, const char *path, int channel,
                        int time, vv_load_info *info);

/* ---- what the dispatch calls by name ---------------------------------------------- */

/** The series of a DICOM file, folder or DICOMDIR, listed in this process (dicom.c). */
vv_status io_dicom_list_local(vv_dicom_series **out, int *n, const char *path);

/**
 * The DICOM series a reader listed (@p bytes, @p n of them, untrusted;
 * taken: freed on error), checked: whole entries, every string ended
 * inside its field, no negative size. Errors: VV_ERR_FORMAT ("dicom:
 * FILE: the reader's list of series is malformed").
 */
vv_status io_dicom_series_from_wire(vv_dicom_series **out, int *count, void *bytes, size_t n,
                                    const char *file);

/** The row called @p name (VV_SANDBOX_NAME_MAX bytes at most), or NULL. */
const vv_format_record *io_row_named(const char *name);

/* ---- the wire of the table's calls (same build on both sides) ---------------------- */

/** A volume read's arguments as they travel to the reader. */
typedef struct io_volume_args {
    int32_t has_raw;
    vv_raw_params raw;
    int32_t series, channel, time, level, z_first, z_count;
} io_volume_args;

/** A store's arguments. */
typedef struct io_store_args {
    int32_t channel, time;
} io_store_args;

/**
 * What the reader's load info says, checked: counts in range, the name
 * ended inside its field, a colour in [0, 1], a finite time step. 1 when
 * it holds; @p bytes of @p n from the reader (untrusted).
 */
int io_info_from_wire(vv_load_info *info, const unsigned char *bytes, size_t n);

/* The id (vv_format) of row @p r of the table, VV_FORMAT_UNKNOWN for NULL
 * or a record that is no row. */
vv_format io_format_id(const vv_format_record *r);

/* The backstop behind every reader (in this process and in the reader
 * sandbox): a volume whose spacing is zero, negative or not finite, or whose
 * origin or direction is not finite, is freed (*@p v set to NULL) and
 * refused: VV_ERR_FORMAT "ROW: FILE: the spacing along z is 0 (...)". */
vv_status io_check_geometry(const vv_format_record *r, vv_volume **v, const char *path);

/* io_check_geometry's test of @p v alone (nothing freed): a source's
 * levels opened out of core. */
vv_status io_geometry_status(const vv_format_record *r, const vv_volume *v, const char *path);

/* 1 when @p r is a row of the built-in table (not one vv_format_register
 * added): the rows volvis-reader knows. */
int io_format_built_in(const vv_format_record *r);

/* The first row vv_format_register added (none built in) whose deep test
 * says @p path holds @p kind: asked in this process, where the reader
 * sandbox, which has the built-in rows only, asks the rest. */
vv_format io_detect_registered(const char *path, int kind);

/* "A, B or C" of the titles of the volume formats with (@p with) or
 * without the flags in @p mask, among those detection can tell when
 * @p detectable, into @p buf of @p cap bytes. */
void io_format_titles(char *buf, size_t cap, unsigned mask, int with, int detectable);

/* VV_ERR_FORMAT "cannot tell the format of PATH (not A, B or C; use --raw
 * for raw data)" for a volume file no row detects, or "PATH: no A or B
 * files in the folder" for a folder (@p is_dir): the one message, in the
 * process and in the reader. */
vv_status io_unknown_volume_format(const char *path, int is_dir);

#endif
