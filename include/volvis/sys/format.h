/*
 * VolVis format records: the implementor's side of file formats (the user's
 * side is include/volvis/io.h and grid.h). Every volume format and every
 * grid format is one record in one table (src/io/formats.c and
 * src/io/grid_formats.c), after Teem's nrrd/format.c: a name, the extensions,
 * a looks-like test, a fits-into test, read and write. Detection, loading,
 * saving, the names --format accepts and the lists printed by
 * `volvis convert --help` and `volvis info --help` all come from the tables.
 *
 * Adding a volume format: write src/io/<format>.c defining
 *     const vv_volume_format vv_volume_format_<name> = {VV_FORMAT_RECORD_VERSION, ...};
 * and add one row, X(<name>), to VV_VOLUME_FORMAT_TABLE in src/io/formats.c.
 * Its id (vv_format) is its row; `--format <name>` and vv_format_parse
 * find it by name. Grids alike (vv_grid_format_record, grid_formats.c).
 *
 * Versioning (libgit2's sys/ structs): a record starts with the version of
 * this header it was written against; optional members may be NULL.
 *
 * Thread-safety: the tables are immutable; the functions of a record are
 * reentrant.
 */
#ifndef VOLVIS_SYS_FORMAT_H
#define VOLVIS_SYS_FORMAT_H

#include <stddef.h>

#include "../grid.h"
#include "../io.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The version of the records of this header. */
#define VV_FORMAT_RECORD_VERSION 1

/** What a format record says about its format (vv_volume_format.flags). */
enum {
    /**
     * Parsed by a third-party library (Teem, nifti_clib, libtiff, GDCM,
     * libxml2, NetCDF): a reader of untrusted input that the sandbox runs
     * in a separate process (DESIGN.md, "Untrusted files").
     */
    VV_FORMAT_FLAG_THIRD_PARTY = 1u << 0,
    /** Also reads a folder (a DICOM series, a stack of TIFF pages). */
    VV_FORMAT_FLAG_FOLDER = 1u << 1,
    /** Nothing in the file describes it: reading needs the caller's
     *  description (vv_load_options.raw); never detected. */
    VV_FORMAT_FLAG_DESCRIBED = 1u << 2,
    /** Also read gzip-compressed (looks_like sees the decompressed head;
     *  the other formats are not asked about a gzip-compressed file). */
    VV_FORMAT_FLAG_GZIP = 1u << 3,
    /** The reader honours vv_load_options.z_first and z_count, decoding
     *  only the slices asked for (a volume read slab by slab). */
    VV_FORMAT_FLAG_SLICES = 1u << 4
};

/** What detection knows of a path, for the looks_like tests. */
typedef struct vv_format_probe {
    const char *path;          /**< as given */
    int is_dir;                /**< 1: a folder (head empty) */
    int gzip;                  /**< 1: the file starts with gzip's magic; head is decompressed */
    const unsigned char *head; /**< the first n bytes (at most VV_FORMAT_PROBE_BYTES) */
    size_t n;
    const char *text; /**< head as a NUL-terminated string, NUL bytes turned into spaces */
} vv_format_probe;

/** Bytes of a file's head given to the looks_like tests. */
#define VV_FORMAT_PROBE_BYTES 1024

/**
 * A volume format. Required: version, name, title, doc, and read or write.
 * looks_like NULL: never detected (raw). fits and write NULL: not written.
 * read NULL: written only (no built-in format is, today).
 */
typedef struct vv_volume_format {
    int version;                   /**< VV_FORMAT_RECORD_VERSION */
    const char *name;              /**< lower-case, as --format takes it: "nrrd" */
    const char *title;             /**< as people write it, for messages: "NRRD", "MetaImage" */
    const char *const *extensions; /**< NULL-terminated, lower-case, no dot ("nii.gz"
                                        allowed), the first is the usual one; may be NULL */
    const char *const *aliases;    /**< other names --format takes; NULL-terminated, may be NULL */
    const char *doc;               /**< one line: what it is and what it holds */
    unsigned flags;                /**< VV_FORMAT_FLAG_* */
    /**
     * 1 when @p p looks like this format. Detection asks every format in
     * table order with @p deep 0 (a signature in the head, a folder's
     * entries: cheap and certain), and only when none said yes, again with
     * @p deep 1 (weaker evidence: the file name alone, or tests that open
     * other files, such as a DICOM file without its preamble through GDCM
     * or the header beside an Analyze .img). Never fails.
     */
    int (*looks_like)(const vv_format_probe *p, int deep);
    /**
     * 1 when the format holds @p v as it is; else 0 with what it cannot
     * hold in @p why (@p cap bytes, one phrase: "SLC holds 8-bit voxels
     * only, the volume is i16"). NULL: holds every volume.
     */
    int (*fits)(const vv_volume *v, char *why, size_t cap);
    /** Reads @p path (@p opt never NULL) with the contract of vv_volume_load;
     *  NULL: the format is written only. */
    vv_status (*read)(vv_volume **out, const char *path, const vv_load_options *opt);
    /**
     * Writes @p v to @p path (@p opt never NULL) atomically, converting
     * what the format cannot hold as fits says (the caller has already
     * refused that when opt->strict). NULL: the format is read only.
     */
    vv_status (*write)(const vv_volume *v, const char *path, const vv_save_options *opt);
    /** The extensions write takes, when fewer than extensions (NIfTI writes
     *  .nii and .nii.gz, not the .hdr/.img pair it reads); NULL: extensions.
     *  For the lists of names that write (messages, --help, the GUI). */
    const char *const *write_extensions;
} vv_volume_format;

/** The extensions @p f writes (write_extensions, else extensions); NULL
 *  when it writes none. */
const char *const *vv_volume_format_write_extensions(const vv_volume_format *f);

/** The volume formats in table order (id 1 first); *@p n their number. */
const vv_volume_format *const *vv_volume_format_table(int *n);

/**
 * A grid format (include/volvis/grid.h). Required: version, name, title,
 * doc, looks_like, read. write NULL: not written.
 */
typedef struct vv_grid_format_record {
    int version;                   /**< VV_FORMAT_RECORD_VERSION */
    const char *name;              /**< lower-case: "vtu" */
    const char *title;             /**< for messages: "VTK XML UnstructuredGrid" */
    const char *const *extensions; /**< NULL-terminated, lower-case, no dot; may be NULL */
    const char *doc;               /**< one line */
    unsigned flags;                /**< VV_FORMAT_FLAG_* */
    /** As vv_volume_format.looks_like (files only: grids are never folders). */
    int (*looks_like)(const vv_format_probe *p, int deep);
    /** Reads @p path with the contract of vv_grid_load. */
    vv_status (*read)(vv_grid **out, const char *path);
    /** Writes @p g to @p path atomically; NULL: read only. */
    vv_status (*write)(const vv_grid *g, const char *path);
} vv_grid_format_record;

/** The grid formats in table order (VV_GRID_FORMAT_VTK first); *@p n their number. */
const vv_grid_format_record *const *vv_grid_format_table(int *n);

/**
 * Fills @p p for @p path: whether it is a folder, and for a file its first
 * VV_FORMAT_PROBE_BYTES bytes (decompressed when gzip) in @p buf, which must
 * hold VV_FORMAT_PROBE_BYTES + 1 bytes. Returns 0, or the errno of a file
 * that cannot be opened or read (the probe is then empty).
 */
int vv_format_probe_fill(vv_format_probe *p, const char *path, unsigned char *buf, char *text);

/** 1 when @p path ends in ".@p ext" (case-insensitive; @p ext may hold dots). */
int vv_format_path_has_ext(const char *path, const char *ext);

/**
 * For the folder tests of looks_like: calls @p match with each entry of
 * folder @p path (its path, its name, 1 for a folder), hidden entries
 * skipped and at most 4096 files looked at, until it returns 1. Returns 1
 * when an entry matched, 0 otherwise (also when the folder cannot be read).
 */
int vv_format_folder_any(const char *path,
                         int (*match)(const char *entry, const char *name, int is_dir, void *ctx),
                         void *ctx);

#ifdef __cplusplus
}
#endif
#endif
