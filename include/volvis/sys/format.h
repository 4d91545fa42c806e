/*
 * VolVis format records: the implementor's side of file formats (the user's
 * side is vv_open and vv_volume_load in include/volvis/io.h, vv_grid_load
 * in grid.h, vv_mesh_load in mesh.h). Everything that opens is one record
 * in ONE table (src/io/formats.c), after Teem's nrrd/format.c: a name, the
 * extensions, a looks-like test by signature, what it holds (a volume, a
 * grid, a mesh), and what it can do: read whole, write, write box by box,
 * open a chunked store (a pyramid: OME-Zarr, .vvb levels, BigDataViewer
 * HDF5 and its XML, Imaris), open by bricks (.vvb, raw, raw NRRD).
 * Detection (once a file: vv_format_detect), vv_open, loading, saving, the
 * names --format accepts and the lists printed by --help all come from the
 * table. A record flagged VV_FORMAT_FLAG_THIRD_PARTY is read through the
 * reader sandbox (src/sandbox: the row's read runs in volvis-reader); its
 * reader never knows it.
 *
 * Adding a format: write src/io/<kind>/<format>.c (volume, store, grid or
 * mesh: what it reads) defining
 *     const vv_format_record vv_format_<name> = {VV_FORMAT_RECORD_VERSION, ...};
 * and add one row, X(<name>), to VV_FORMAT_TABLE in src/io/formats.c. Its id
 * (vv_format) is its row; `--format <name>` and vv_format_parse find it by
 * name. A multiresolution format fills open_store (a vv_store: its levels
 * and one chunk's voxels); the pyramid, its cache and the renderers do the
 * rest (tests/plugins/toy_format.c is a whole format in one file).
 *
 * Versioning (libgit2's sys/ structs): a record starts with the version of
 * this header it was written against; optional members may be NULL.
 *
 * Thread-safety: the table is immutable; the functions of a record are
 * reentrant.
 */
#ifndef VOLVIS_SYS_FORMAT_H
#define VOLVIS_SYS_FORMAT_H

#include <stddef.h>

#include "../grid.h"
#include "../io.h"
#include "../mesh.h"
#include "../source.h"
#include "source.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The version of the records of this header (version 2 records, without
 *  open_store_channels, are registered too). */
#define VV_FORMAT_RECORD_VERSION 3

/** What a format record says about its format (vv_format_record.flags). */
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
    VV_FORMAT_FLAG_SLICES = 1u << 4,
    /** Made to be read out of core: vv_open's VV_OPEN_DEFAULT opens it so
     *  (.vvb), where other formats are read whole. */
    VV_FORMAT_FLAG_OUT_OF_CORE = 1u << 5
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

/* ---- the record --------------------------------------------------------------------- */

/* What a format's files hold: vv_data_kind (io.h). */

/**
 * One format. Required: version, name, title, doc, and for what it holds
 * (holds) a way in or out: a volume format read or write (or open_store);
 * a grid format read_grid; a mesh format read_mesh. looks_like NULL: never
 * detected (raw). Everything else optional (NULL: it cannot).
 */
typedef struct vv_format_record {
    int version;                   /**< VV_FORMAT_RECORD_VERSION */
    const char *name;              /**< lower-case, as --format takes it: "nrrd" */
    const char *title;             /**< as people write it, for messages: "NRRD", "MetaImage" */
    const char *const *extensions; /**< NULL-terminated, lower-case, no dot ("nii.gz"
                                        allowed), the first is the usual one; may be NULL */
    const char *const *aliases;    /**< other names --format takes; NULL-terminated, may be NULL */
    const char *doc;               /**< one line: what it is and what it holds */
    unsigned flags;                /**< VV_FORMAT_FLAG_* */
    vv_data_kind holds;            /**< a volume (the default), a grid or a mesh */
    /**
     * 1 when @p p looks like this format. Detection asks every format in
     * table order with @p deep 0 (a signature in the head, a folder's
     * entries: cheap and certain), and only when none said yes, again with
     * @p deep 1 (rows added by vv_format_register first; weaker evidence:
     * the file name alone, or tests that open
     * other files, such as a DICOM file without its preamble through GDCM
     * or the header beside an Analyze .img). Never fails.
     */
    int (*looks_like)(const vv_format_probe *p, int deep);

    /* ---- volumes ---- */
    /**
     * 1 when the format holds @p v as it is; else 0 with what it cannot
     * hold in @p why (@p cap bytes, one phrase: "SLC holds 8-bit voxels
     * only, the volume is i16"). NULL: holds every volume.
     */
    int (*fits)(const vv_volume *v, char *why, size_t cap);
    /** Reads @p path (@p opt never NULL) with the contract of vv_volume_load. */
    vv_status (*read)(vv_volume **out, const char *path, const vv_load_options *opt);
    /**
     * Writes @p v to @p path (@p opt never NULL) atomically, converting
     * what the format cannot hold as fits says (the caller has already
     * refused that when opt->strict).
     */
    vv_status (*write)(const vv_volume *v, const char *path, const vv_save_options *opt);
    /** The extensions write takes, when fewer than extensions (NIfTI writes
     *  .nii and .nii.gz, not the .hdr/.img pair it reads); NULL: extensions.
     *  For the lists of names that write (messages, --help, the GUI). */
    const char *const *write_extensions;
    /**
     * Writes the volume @p hdr describes (dims, type, geometry; its voxels
     * are never read) from @p read, box by box, in memory bounded by the
     * format's pieces, atomically (vv_volume_save_boxes).
     */
    vv_status (*write_boxes)(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                             const vv_save_options *opt);
    /**
     * Opens @p path's levels of channel @p channel at step @p time (-1: the
     * first) as a chunked store (the file's metadata only: no voxel read);
     * @p info (may be NULL) gets its channel, step and level counts and the
     * channel's name and colour. What vv_open reads a pyramid through.
     */
    vv_status (*open_store)(vv_store *st, const char *path, int channel, int time,
                            vv_load_info *info);
    /**
     * Where the voxels of @p path lie raw (uncompressed, one piece, x
     * fastest) in a file, for reading it out of core by bricks with pread:
     * the geometry as a volume of one voxel whose dims are set to the
     * file's (*@p header, new), the file holding the voxels (*@p data_path,
     * malloc'd), the byte offset of voxel (0, 0, 0), the byte order. @p opt
     * (never NULL): the raw parameters of a described format. Errors:
     * VV_ERR_UNSUPPORTED (not raw in this file: a compressed NRRD; vv_open
     * reads it whole instead), the format's own.
     */
    vv_status (*raw_layout)(const char *path, const vv_load_options *opt, vv_volume **header,
                            char **data_path, uint64_t *offset, int *big_endian);
    /**
     * Opens @p path out of core by the format's own bricks (a .vvb: its
     * index) in @p cache: a source of kind VV_SOURCE_BRICKS (@p header_only:
     * the ranges left unknown where they cost a pass).
     */
    vv_status (*open_bricks)(vv_source **out, const char *path, int header_only, vv_cache *cache);

    /* ---- grids ---- */
    /** Reads @p path with the contract of vv_grid_load. */
    vv_status (*read_grid)(vv_grid **out, const char *path);
    /** Writes @p g to @p path atomically. */
    vv_status (*write_grid)(const vv_grid *g, const char *path);

    /* ---- meshes ---- */
    /** Reads @p path with the contract of vv_mesh_load. */
    vv_status (*read_mesh)(vv_mesh **out, const char *path);

    /* ---- version 3 ---- */
    /**
     * Optional (NULL: open_store a channel at a time, the stores stacked by
     * vv_store_stack): opens @p path's levels of channels @p channels[0 ..
     * n) at step @p time as one store whose reads fill every channel
     * (vv_store.n_ch = n), a chunk holding several of them decoded once;
     * @p info[k] (may be NULL) gets channel k's name, colour and window,
     * info[0] the counts.
     */
    vv_status (*open_store_channels)(vv_store *st, const char *path, int n, const int *channels,
                                     int time, vv_load_info *info);
} vv_format_record;

/** The extensions @p f writes (write_extensions, else extensions); NULL
 *  when it writes none. */
const char *const *vv_format_record_write_extensions(const vv_format_record *f);

/** Every format in table order (id 1 first: vv_format); *@p n their number. */
const vv_format_record *const *vv_format_table(int *n);

/** The record of format @p f (an id of the table), or NULL. */
const vv_format_record *vv_format_record_of(vv_format f);

/** The most rows vv_format_register adds to a process's table. */
#define VV_FORMATS_REGISTERED_MAX 32

/**
 * Adds @p row to the format table, after the rows built in: from then on
 * detection asks it (its signature test after the built-in rows', its deep
 * test before theirs, in this process), --format and vv_format_parse
 * take its name, and vv_open, vv_volume_load and vv_volume_save use it as
 * they use any row. A new format is its record in one file and this call
 * (a plug-in, a test, a program with its own format). @p row is borrowed
 * for the life of the process (a static record); *@p id (may be NULL) gets
 * its vv_format id. Thread-safe; rows are never removed.
 *
 * Errors: VV_ERR_INVALID (no name or title, a name or alias that is
 * another row's, a kind it neither reads nor writes), VV_ERR_UNSUPPORTED
 * (another record version; VV_FORMAT_FLAG_THIRD_PARTY: the sandboxed
 * reader process knows the built-in rows only, so a registered row is read
 * in the process that registered it), VV_ERR_LIMIT (over
 * VV_FORMATS_REGISTERED_MAX rows).
 */
vv_status vv_format_register(const vv_format_record *row, vv_format *id);

/**
 * The reader process (apps/volvis-reader; a program of one's own that
 * embeds the library and ships its own reader calls this from its main and
 * points VOLVIS_READER at it): serves the format table's rows to the
 * library through the reader sandbox (include/volvis/sys/sandbox.h,
 * vv_sandbox_serve). Returns (2) only when it was not started by the
 * library.
 */
int vv_format_reader_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
