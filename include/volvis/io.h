/*
 * VolVis volume input and output.
 *
 * Formats: SLC (VolVis's own, read and write, plain and run-length
 * compressed), NRRD (Teem's nrrd library; read and write), NIfTI-1/NIfTI-2
 * (nifti_clib; .nii, .nii.gz, .hdr/.img), MetaImage (.mhd/.mha), VTK legacy
 * STRUCTURED_POINTS (binary and ASCII), TIFF stacks (libtiff; multi-page
 * files and folders of pages, OME-TIFF and ImageJ metadata), DICOM series
 * (GDCM; folders, DICOMDIR, lists of files; read only) and raw files described
 * by the caller.
 * File formats are documented in docs/formats.md.
 *
 * Every reader checks header sizes with vv_volume_check_size() before
 * allocating, never reads past the data it was given, and on failure returns
 * an error whose trace names the file and the problem ("slc: nut.slc: slice
 * 12: ..."). Every writer writes a temporary file beside the target and
 * renames it, so a failed write leaves an existing file untouched.
 *
 * Thread-safety: readers and writers are reentrant; calls into Teem are
 * serialised internally (its error state is global).
 */
#ifndef VOLVIS_IO_H
#define VOLVIS_IO_H

#include <stdint.h>

#include "core.h"
#include "grid.h"
#include "mesh.h"
#include "model.h"
#include "source.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * A volume format: its row in the format table (src/io/formats.c; the
 * records are described in include/volvis/sys/format.h). The formats built
 * in have names here; a format added to the table gets the next id and is
 * found by name (vv_format_parse), as --format finds it.
 */
typedef enum vv_format {
    VV_FORMAT_UNKNOWN = -1, /**< not a format this build reads */
    VV_FORMAT_AUTO = 0,     /**< detect from content, extension as a hint */
    VV_FORMAT_SLC,
    VV_FORMAT_NRRD,
    VV_FORMAT_NIFTI,
    VV_FORMAT_MHD,
    VV_FORMAT_VTK,
    VV_FORMAT_RAW,
    VV_FORMAT_TIFF,
    VV_FORMAT_DICOM,
    VV_FORMAT_VTI,        /**< VTK XML image data (ParaView's .vti), read and written */
    VV_FORMAT_OME_ZARR,   /**< OME-Zarr 0.4 (Zarr v2 folder), every multiscales level */
    VV_FORMAT_HDF5,       /**< BigDataViewer / Imaris HDF5 pyramids */
    VV_FORMAT_VVB,        /**< VolVis's bricked volumes, with pyramid levels or without */
    VV_FORMAT_BDV_XML,    /**< BigDataViewer's dataset XML (its HDF5 file beside it) */
    VV_FORMAT_N5,         /**< N5 datasets and multiscale groups (Janelia, BigDataViewer, COSEM) */
    VV_FORMAT_PRECOMPUTED /**< Neuroglancer precomputed volumes (an info and its scales) */
    /* then the grid and mesh formats, by name (vv_format_parse) */
} vv_format;

/** Number of formats of every kind (volumes, grids, meshes): their ids run from 1 to this. */
int vv_format_count(void);
/** Lower-case format name ("slc", "nrrd", ...); "auto" and "unknown" for those. */
const char *vv_format_name(vv_format f);
/**
 * Parses a format name as printed by vv_format_name, or one of a format's
 * other names ("nhdr", "nii", "mha", "metaimage", "tif", "dcm", ...), in any
 * case. Errors: VV_ERR_INVALID naming the formats.
 */
vv_status vv_format_parse(const char *name, vv_format *out);

/**
 * Detects the format of @p path by asking every format of the table whether
 * the file looks like it: signatures first (SLC "11111", "NRRD000", NIfTI
 * sizeof_hdr 348/540 also gzip-compressed, "# vtk DataFile", MetaImage keys,
 * TIFF "II*"/"MM*" and BigTIFF "II+"/"MM+", DICOM "DICM" at byte 128), then,
 * when none matched, the tests that open other files (a DICOM file without
 * its preamble that GDCM can read, the header beside an Analyze .img). A
 * folder is VV_FORMAT_DICOM when it holds a DICOMDIR or a DICOM file, else
 * VV_FORMAT_TIFF when it holds a TIFF file. Returns VV_FORMAT_UNKNOWN when
 * nothing matches (and for raw files, which have no signature). A URL
 * (vv_path_is_url) is VV_FORMAT_OME_ZARR without a look at the network.
 */
vv_format vv_format_detect(const char *path);

/**
 * 1 when @p path names a remote store rather than a file: it starts with
 * http://, https:// or s3:// (case-insensitive; docs/formats.md, "Remote
 * data"). Such a path is an OME-Zarr store read over the network by the
 * library's byte sources; nothing local is looked at. 0 for NULL. Pure,
 * thread-safe.
 */
int vv_path_is_url(const char *path);

/**
 * What the remote transport (the HTTP, HTTPS and S3 reads of every store
 * opened by URL, docs/formats.md "Remote data") has pending and has done,
 * summed over the process since it started. A "read" is one object or byte
 * range a reader asked for: a chunk, a shard's index or one of its inner
 * chunks, a metadata file. Counts, and bytes of HTTP bodies (as sent:
 * compressed chunks), never of decoded voxels.
 */
typedef struct vv_remote_stats {
    uint64_t pending;        /**< reads asked for and not yet answered (queued or in flight) */
    uint64_t pending_bytes;  /**< bytes of the pending reads not yet received: a range's
                                  length, a whole object's once the server says its
                                  Content-Length (0 before) */
    uint64_t in_flight;      /**< HTTP requests on the wire now */
    uint64_t completed;      /**< reads answered: received, absent (404), or failed for good */
    uint64_t failed;         /**< of those, failed for good (the reader got an error) */
    uint64_t requests;       /**< HTTP requests sent (each retry and redirect counts) */
    uint64_t bytes_received; /**< bytes of response bodies received, every try included */
    uint64_t cancelled;      /**< reads dropped unanswered because nobody wanted them any more
                                  (a level-of-detail view moved on): not sent, or their
                                  requests abandoned in flight; not in completed */
} vv_remote_stats;

/**
 * The remote transport's counts now into @p st (a process-wide snapshot;
 * all zero before the first URL is opened). Each field is read atomically
 * on its own, so two fields may be a moment apart while reads go on.
 * Thread-safe, lock-free: a GUI may poll it from its main loop while render
 * threads read.
 */
void vv_remote_stats_get(vv_remote_stats *st);

/** How to read a raw file: nothing in the file describes it. */
typedef struct vv_raw_params {
    int dims[3];
    vv_voxel_type type;
    int big_endian;       /**< 1: big-endian voxels */
    double spacing[3];    /**< default 1 */
    double origin[3];     /**< default 0 */
    uint64_t header_skip; /**< bytes to skip before the data */
} vv_raw_params;

/** Unset dims (0), u8, little-endian, spacing 1, origin 0, no skip. */
void vv_raw_params_init(vv_raw_params *p);

/** Name bytes of vv_load_info.channel_name, with its NUL. */
#define VV_CHANNEL_NAME_MAX 64

/**
 * The axes of a file beyond its three spatial ones, as the reader found
 * them (vv_load_options.info). A format without channels or time has one
 * of each.
 */
typedef struct vv_load_info {
    int n_channels; /**< channels in the file, >= 1 */
    int n_times;    /**< time steps in the file, >= 1 */
    int n_levels;   /**< resolution levels in the file (OME-Zarr multiscales), >= 1 */
    /** The read channel's name from the file's metadata (OME Channel Name,
     *  ImageJ Labels are not read), UTF-8, NUL-terminated; "" when none. */
    char channel_name[VV_CHANNEL_NAME_MAX];
    int has_color;    /**< 1: color holds the read channel's colour from the metadata */
    float color[3];   /**< RGB in [0, 1] (OME Channel Color) */
    double time_step; /**< time between steps in seconds when the file says (NIfTI pixdim[4],
                           OME TimeIncrement), else 0 */
    /**
     * 1 when every step's voxels lie in the file as they are (uncompressed,
     * unscaled, in the volume's type), one volume each: the voxels of
     * (channel c, step t) are the volume's bytes at raw_offset +
     * c * raw_channel_bytes + t * raw_step_bytes, in the byte order
     * raw_big_endian says. vv_time_series reads later steps so, with pread
     * into recycled memory (NIfTI one-file .nii). Untrusted: a reader of
     * these offsets checks them against the file's size.
     */
    int has_raw_layout;
    int raw_big_endian;
    uint64_t raw_offset, raw_step_bytes, raw_channel_bytes;
    /** The file's slices along z (the volume's dims[2] when every slice was
     *  read; the whole stack's count when a range was, vv_load_options.z_count). */
    int n_slices;
    /** The row of the format table that read the file (set by the loader
     *  in this process, also when detection ran in the reader sandbox). */
    vv_format format;
    /** 1: the image is a label image (OME-Zarr image-label metadata: segment
     *  ids); a World made of it shows it as a label volume (VV_SEG_LABELS) */
    int is_label;
    /** 1: window holds the read channel's display window from the metadata (OME-Zarr
     *  omero window start and end: its contrast limits, data values), checked finite,
     *  start < end and within what the voxel type holds */
    int has_window;
    double window[2];
    /** Metadata that was ignored, one line for the user ("" none): an omero window that is
     *  NaN, inverted or absurd */
    char warning[256];
    /** 1: the metadata marks the read channel inactive (OME-Zarr omero "active": false):
     *  shown hidden until the user turns it on */
    int inactive;
} vv_load_info;

/** Options for vv_volume_load. */
typedef struct vv_load_options {
    vv_format format; /**< VV_FORMAT_AUTO to detect */
    int has_raw;      /**< 1: raw is valid (required for VV_FORMAT_RAW) */
    vv_raw_params raw;
    /**
     * DICOM: which series, numbered from 1 in vv_dicom_list's order; 0 (the
     * default): the only series, an error naming the count when there are
     * several.
     */
    int series;
    /**
     * Which channel, from 0; -1 (the default): channel 0. TIFF and DICOM: a
     * sample of each pixel or an OME/ImageJ channel; NIfTI: the fifth axis
     * (dim[5]); NRRD: the axis of kind RGB-color, RGBA-color, vector,
     * covariant-vector, list, point or 3-/4-vector; VTK legacy: a component
     * of the SCALARS (numComp 1..4). A channel past the file's
     * is VV_ERR_INVALID naming the count.
     */
    int channel;
    /**
     * Which time step, from 0; -1 (the default): step 0. OME-TIFF and ImageJ
     * hyperstacks (SizeT, frames=), NIfTI (dim[4]), NRRD (the axis of kind
     * time). A step past the file's is VV_ERR_INVALID naming the count; a
     * format without a time axis has one step.
     */
    int time;
    /**
     * Which resolution level of a multiresolution file, from 0 (the finest,
     * the default): OME-Zarr's multiscales datasets in their order. A level
     * past the file's is VV_ERR_INVALID naming the count; other formats
     * have level 0 only.
     */
    int level;
    /**
     * Which slices: z_count > 0 reads slices z_first .. z_first + z_count - 1
     * only (a slab of a volume larger than memory, read slab by slab: what
     * vv_slabs does), as a volume of z_count slices whose origin is that of
     * slice z_first; 0 (the default): every slice. Formats with
     * VV_FORMAT_FLAG_SLICES only (TIFF stacks: those pages alone are
     * decoded); others are VV_ERR_UNSUPPORTED, and a range past the file's
     * slices is VV_ERR_INVALID naming the count (vv_load_info.n_slices).
     */
    int z_first, z_count;
    /**
     * Out, may be NULL: what the file holds besides the volume read (its
     * channels and time steps, the read channel's name and colour). Filled
     * on success; through the sandbox too. Borrowed for the call.
     */
    vv_load_info *info;
    /**
     * 1: the process ends after this read (the reader sandbox): checks that
     * exist only to keep a long-lived process from a library's leaks on a
     * malformed file may be skipped, and a reader may leave the volume's
     * value range unset (0, 0): the parent measures it again, as it trusts
     * no range the reader sends. 0 (the default) everywhere else.
     */
    int one_shot;
} vv_load_options;

/** Format VV_FORMAT_AUTO, no raw parameters (has_raw 0, raw as vv_raw_params_init),
 * series 0, channel -1, time -1, level 0, every slice (z_first 0, z_count 0), info NULL. */
void vv_load_options_init(vv_load_options *o);

/**
 * Loads any supported volume file. @p opt may be NULL (detect the format).
 * On success *out holds a new volume (refcount 1) with range[] computed.
 * Errors: VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_LIMIT, VV_ERR_UNSUPPORTED,
 * VV_ERR_NOMEM; the trace starts with the format and file name.
 */
vv_status vv_volume_load(vv_volume **out, const char *path, const vv_load_options *opt);

/* ---- opening: one call for everything that opens ----------------------------------- */

/** How vv_open reads a volume file. */
typedef enum vv_open_mode {
    /** The format's way: out of core for formats made for it (.vvb), whole otherwise. */
    VV_OPEN_DEFAULT = 0,
    /** Whole, into memory (a .vvb too), whatever its size. */
    VV_OPEN_WHOLE = 1,
    /**
     * Out of core wherever the format allows: a pyramid (OME-Zarr,
     * BigDataViewer HDF5 or XML, Imaris, a .vvb with levels when
     * vv_open_options.levels) by its chunks, a .vvb, raw file or raw-encoded
     * NRRD by bricks; a file that cannot be (a compressed NRRD, TIFF,
     * NIfTI, ...) is read whole.
     */
    VV_OPEN_OUT_OF_CORE = 2,
    /**
     * VV_OPEN_DEFAULT, and out of core too when the volume's level 0 holds
     * more than a quarter of the cache's budget (what the GUI, Python and
     * the browser server do).
     */
    VV_OPEN_AUTO = 3,
    /**
     * VV_OPEN_OUT_OF_CORE, and VV_ERR_UNSUPPORTED (nothing read) where the
     * file cannot be: for a consumer that reads it box by box (volvis
     * convert, measure) and otherwise another way. No error is kept, except
     * where a chunked store's format says why (an OME-Zarr level with an
     * unknown compressor, an HDF5 file that is no pyramid): then
     * vv_error_message gives its reason.
     */
    VV_OPEN_OUT_OF_CORE_ONLY = 4,
} vv_open_mode;

/** Options of vv_open. */
typedef struct vv_open_options {
    /** format (VV_FORMAT_AUTO: detected, once), raw parameters, DICOM series, channel,
     *  time step; the level read whole (level: 0 the finest) */
    vv_load_options load;
    vv_open_mode mode;
    /** 1: a file with pyramid levels and bricks (a .vvb with levels) opens as its pyramid
     *  (level of detail: --lod, --level, --progressive); 0: by bricks */
    int levels;
    /** 1: by bricks without the pass over a raw or NRRD file for the value range and the
     *  bricks' min/max (the range is then 0 .. 0: the ranks of a distributed render learn
     *  it from their bricks) */
    int header_only;
    /** where the pieces read out of core are held; NULL: the process's (vv_cache_process) */
    vv_cache *cache;
    /**
     * > 1: out of core, a pyramid of these channels of the file at once
     * (channels[0 .. n_channels), in that order; load.channel unused): each
     * chunk holds them all (vv_source_channels); a file that has no pyramid
     * (a bricked file holds one channel) is VV_ERR_UNSUPPORTED. 0 or 1:
     * load.channel alone.
     */
    int n_channels;
    int channels[VV_MAX_CHANNELS];
} vv_open_options;

/** The defaults: vv_load_options_init, VV_OPEN_DEFAULT, bricks, the whole pass, the
 *  process's cache. */
void vv_open_options_init(vv_open_options *o);

/** What a format's files hold (vv_opened.kind, vv_format_record.holds). */
typedef enum vv_data_kind {
    VV_DATA_VOLUME = 0, /**< a volume (vv_volume; channels, time steps, levels) */
    VV_DATA_GRID = 1,   /**< an irregular grid (vv_grid) */
    VV_DATA_MESH = 2,   /**< a triangle mesh (vv_mesh) */
} vv_data_kind;

/** What a file holds, as vv_open opened it. */
typedef struct vv_opened {
    vv_data_kind kind; /**< a volume (source), a grid or a mesh */
    vv_format format;  /**< its row of the format table */
    vv_source *source; /**< a volume: the channel and step asked for (in memory or out of
                            core); owned (vv_opened_clear frees it) */
    vv_grid *grid;     /**< a grid, owned */
    vv_mesh *mesh;     /**< a mesh, owned */
    vv_load_info info; /**< a volume's channels, steps, levels, name and colour */
    /** n_channels > 1 asked: channel k's name, colour and window (ch_info[0] is info) */
    vv_load_info ch_info[VV_MAX_CHANNELS];
} vv_opened;

/**
 * Opens any file the build reads, through the format table: detects its
 * format once (a signature in its head, else the deep tests, which for the
 * formats of third-party parsers run in the reader sandbox), and returns
 * what it holds: a volume as a source (include/volvis/source.h) -- read
 * whole into memory, or out of core as @p opt->mode says (bricks or a
 * pyramid, its pieces in @p opt->cache under one budget) -- a grid, or a
 * mesh. Third-party parsers run in the reader sandbox (docs/security.md).
 * @p opt may be NULL (the defaults). On failure @p out holds nothing.
 * Errors: those of the format's reader, prefixed with its name and the
 * file's ("nrrd: head.nrrd: ..."); VV_ERR_FORMAT ("cannot tell the format
 * of F"), VV_ERR_INVALID (a channel, time step or level past the file's,
 * a raw file without its description), VV_ERR_LIMIT (a budget smaller than
 * one brick or node and its working set), VV_ERR_IO, VV_ERR_NOMEM.
 * Thread-safe.
 */
vv_status vv_open(vv_opened *out, const char *path, const vv_open_options *opt);

/** Frees what @p o holds and zeroes it (its source keeps living where an object holds it). */
void vv_opened_clear(vv_opened *o);

/**
 * The time steps of one channel of a file (vv_load_info.n_times), read step
 * by step as they are asked for: only the steps in use are resident, in a
 * cache bounded by bytes (the least recently used step goes first, the one
 * asked for last always stays), and the step that will be wanted next can
 * be read ahead on a background thread while the current one is drawn.
 * Every step must have step 0's dimensions and voxel type.
 * Thread-safety: every function may be called from any thread; a step being
 * read is read once, whoever asks for it meanwhile waits for it.
 */
typedef struct vv_time_series vv_time_series;

/**
 * Opens the time steps of @p path (@p opt: its format, series and channel;
 * time and info are ignored; NULL: defaults) and reads step 0 (for the
 * count and the shape). @p cache_bytes bounds the resident steps' voxels
 * (0: three steps). Errors: those of vv_volume_load, VV_ERR_NOMEM.
 */
vv_status vv_time_series_open(vv_time_series **out, const char *path, const vv_load_options *opt,
                              uint64_t cache_bytes);

/** The number of time steps (>= 1). */
int vv_time_series_count(const vv_time_series *ts);

/** What step 0's read said of the file (channels, steps, name, colour, time increment). */
const vv_load_info *vv_time_series_info(const vv_time_series *ts);

/**
 * Step @p t (0..count-1) as a new reference in *@p out (vv_volume_free it):
 * from the cache, or read now (waiting for a read-ahead of the same step).
 * Errors: VV_ERR_INVALID (a step out of range), the read's own (its message
 * kept for every later ask: a broken step stays broken), VV_ERR_FORMAT
 * (a step whose shape differs from step 0's, named).
 */
vv_status vv_time_series_get(vv_time_series *ts, int t, vv_volume **out);

/**
 * Reads step @p t ahead on the series' background thread when it is not
 * resident; a newer prefetch replaces one not yet started (the latest view
 * wins). Steps out of range are ignored. Never blocks on a read.
 */
void vv_time_series_prefetch(vv_time_series *ts, int t);

/** Counts for tests and reports: steps read from the file so far, steps resident now,
 *  their bytes. Any pointer may be NULL. */
void vv_time_series_stats(vv_time_series *ts, int *reads, int *resident, uint64_t *bytes);

/** Stops the read-ahead (waiting for a read in progress) and frees the series
 *  and its cache (volumes handed out keep their own references). NULL is a no-op. */
void vv_time_series_free(vv_time_series *ts);

/**
 * The format that writes files with the extension of @p path (.slc, .nrrd,
 * .nhdr: the extensions of the formats with a writer, case-insensitive), or
 * VV_FORMAT_UNKNOWN.
 */
vv_format vv_format_from_extension(const char *path);

/** Name bytes of an OME-Zarr label image's or well's path, with its NUL. */
#define VV_OME_ZARR_NAME_MAX 128
/** The most label images and wells vv_ome_zarr_contents_get lists (more are refused). */
#define VV_OME_ZARR_LABELS_MAX 256
#define VV_OME_ZARR_WELLS_MAX 4096

/** One label image of an OME-Zarr image (its "labels" group). */
typedef struct vv_ome_zarr_label {
    char name[VV_OME_ZARR_NAME_MAX]; /**< its path under labels/ */
    int dims[3];                     /**< level 0's voxels (x, y, z) */
    vv_voxel_type type;
    int n_levels;
    int n_colors; /**< image-label colors given (label-value, rgba) */
} vv_ome_zarr_label;

/** One well of an HCS plate. */
typedef struct vv_ome_zarr_well {
    char path[VV_OME_ZARR_NAME_MAX];        /**< "A/1" */
    int row, column;                        /**< rowIndex, columnIndex */
    int n_fields;                           /**< its well.images */
    char first_field[VV_OME_ZARR_NAME_MAX]; /**< its first image's path ("0") */
} vv_ome_zarr_well;

/** What an OME-Zarr group holds besides (or instead of) an image. */
typedef enum vv_ome_zarr_kind {
    VV_OME_ZARR_IMAGE = 0, /**< a multiscales image (or a plain array) */
    VV_OME_ZARR_PLATE,     /**< an HCS plate: open one field (PLATE/A/1/0) */
    VV_OME_ZARR_WELL,      /**< one well of a plate: open one field (WELL/0) */
    VV_OME_ZARR_LABELS     /**< an image's labels group: open one (labels/NAME) */
} vv_ome_zarr_kind;

/**
 * What vv_ome_zarr_contents_get found in an OME-Zarr group (OME-NGFF 0.4
 * and 0.5: "image-label", "plate" and "well" metadata). Owned by the
 * caller; its arrays are the library's until vv_ome_zarr_contents_clear.
 * Not shared between threads.
 */
typedef struct vv_ome_zarr_contents {
    vv_ome_zarr_kind kind;
    int is_label;              /**< an image with image-label metadata */
    int n_labels;              /**< label images (an image's labels/, or a labels group) */
    vv_ome_zarr_label *labels; /**< n_labels entries (vv_ome_zarr_contents_clear frees) */
    char plate_name[VV_OME_ZARR_NAME_MAX];
    int n_rows, n_columns;   /**< a plate's rows and columns */
    int field_count;         /**< a plate's field_count (0: not given) */
    int n_acquisitions;      /**< a plate's acquisitions listed */
    int n_wells;             /**< wells listed (a plate's, or 1 for a well) */
    vv_ome_zarr_well *wells; /**< n_wells entries (a well: one, path "") */
} vv_ome_zarr_contents;

/**
 * What the OME-Zarr group at folder @p path holds (its .zattrs, or zarr.json's
 * attributes.ome): an image and its label images (each one's level 0 dims and
 * type), an HCS plate and its wells (each well group's images), a well, or a
 * labels group. Every path the metadata names (wells, fields, labels) is
 * checked as a dataset's is: relative, no "..", not leading out of the store
 * by a link; at most VV_OME_ZARR_WELLS_MAX wells and VV_OME_ZARR_LABELS_MAX
 * labels. Errors (one line, naming the file and the field): VV_ERR_FORMAT,
 * VV_ERR_LIMIT, VV_ERR_IO, VV_ERR_NOMEM. Free with vv_ome_zarr_contents_clear.
 */
vv_status vv_ome_zarr_contents_get(const char *path, vv_ome_zarr_contents *out);

/** Frees what vv_ome_zarr_contents_get allocated in @p c; NULL is a no-op. */
void vv_ome_zarr_contents_clear(vv_ome_zarr_contents *c);

/** Options for vv_volume_save_with. */
typedef struct vv_save_options {
    vv_format format; /**< VV_FORMAT_AUTO: from the extension */
    /** 1: what the format cannot hold as it is (another voxel type) is
     *  VV_ERR_UNSUPPORTED; 0: it is converted (SLC: rescaled to 8 bits) */
    int strict;
    /** -1: the format's default (NRRD gzip, SLC run-length, MetaImage zlib);
     *  0: none; 1: compressed. NIfTI follows the name (.nii.gz: gzip). */
    int compress;
    /** 1: the voxels are labels (segment ids): NIfTI marks the file
     *  NIFTI_INTENT_LABEL; an integer voxel type is required */
    int label;
    /** NIfTI: 1 or 2; 0: NIfTI-1 unless an axis is longer than NIfTI-1's
     *  32767 voxels */
    int nifti_version;
    /** TIFF: the codec by name ("deflate", "lzw", "zstd", "packbits",
     *  "none"); NULL: deflate, or none when compress is 0. OME-Zarr: the
     *  chunk codec ("zstd", "blosc" (lz4, byte shuffle), "gzip", "zlib"
     *  (0.4 only), "none"); NULL: zstd for 0.5, zlib for 0.4, or none when
     *  compress is 0 */
    const char *codec;
    /** TIFF: 1 writes BigTIFF (64-bit offsets) whatever the size; 0:
     *  BigTIFF only when the voxels come near classic TIFF's 4 GiB */
    int bigtiff;
    /** .vvb: VV_VVB_COARSE, VV_VVB_ZSTD, VV_VVB_LEVELS (bricks.h); 0: raw bricks */
    unsigned vvb_flags;
    /** Long work (a box-by-box write) reports here and may be cancelled; may be zeroed. */
    vv_progress progress;
    /** OME-Zarr: the OME-NGFF version written, 4 (0.4: Zarr v2) or 5 (0.5:
     *  Zarr v3); 0: VV_OME_ZARR_DEFAULT_NGFF */
    int ngff_version;
    /** OME-Zarr: the chunk shape in voxels (x, y, z), each >= 1 (clipped to
     *  a level's size); 0: 64 */
    int chunk[3];
    /** OME-Zarr 0.5: the shard shape in voxels (x, y, z), each a multiple of
     *  the chunk's (clipped to a level's chunks); 0: no sharding */
    int shard[3];
} vv_save_options;

/** The OME-NGFF version (vv_save_options.ngff_version) written by default. */
#define VV_OME_ZARR_DEFAULT_NGFF 5

/** Format VV_FORMAT_AUTO, strict 0, compress -1. */
void vv_save_options_init(vv_save_options *o);

/**
 * Writes @p v to @p path as @p opt says (@p opt may be NULL: the defaults):
 * the format from opt->format, or with VV_FORMAT_AUTO from the extension
 * among the formats that write (.slc, .nrrd, .nhdr). What the format cannot
 * hold as it is (SLC: 8-bit voxels only) is converted (SLC: rescaled from
 * range[] to 0..255, the modification set to "other") unless opt->strict.
 * Atomic: on failure an existing file is left as it was. Errors:
 * VV_ERR_INVALID (no format from the extension), VV_ERR_UNSUPPORTED (a
 * format that is read only; strict and the volume does not fit), VV_ERR_IO,
 * VV_ERR_NOMEM.
 */
vv_status vv_volume_save_with(const vv_volume *v, const char *path, const vv_save_options *opt);

/** vv_volume_save_with of @p format and @p strict, compression as the format's default. */
vv_status vv_volume_save(const vv_volume *v, const char *path, vv_format format, int strict);

/* ---- images ------------------------------------------------------------- */

/**
 * Loads a PNG (vv_image_read_png) from @p path; @p source (may be NULL:
 * @p path) is the name kept for scene saving. Errors: those of
 * vv_image_read_png, VV_ERR_NOMEM.
 */
vv_status vv_texture_image_load(vv_texture_image **out, const char *path, const char *source);

/**
 * A volume read slab by slab: boxes of a file larger than memory in a
 * format whose reader decodes a range of slices (VV_FORMAT_FLAG_SLICES:
 * TIFF stacks), each through vv_volume_load with z_first and z_count (so
 * through the reader sandbox where the format is a third party's), or of a
 * gzip-encoded NRRD (its header read as the bricked reader reads an
 * uncompressed one; its data inflated here by zlib as one stream, forward
 * from slab to slab, from its start again only when a box goes back). The
 * slices of the last box read are kept, and a box within them is cut from
 * them: the boxes of one slab asked for in turn (what
 * vv_volume_save_boxes does for OME-Zarr: every row of chunks of a slab before the
 * next slab) decode each slice once. Memory: the slices of one box, of the
 * volume's width x height. Not thread-safe: one call at a time (the
 * writer's reads are).
 */
typedef struct vv_slabs vv_slabs;
/**
 * Opens @p path with @p opt's format, raw parameters, channel and time
 * step (NULL: the defaults; its slices and info are not used): a gzip NRRD's
 * header, else slice 0 for the geometry and the count of slices. Errors: those of
 * vv_volume_load (VV_ERR_UNSUPPORTED for a format read whole only),
 * VV_ERR_LIMIT (a volume past the size limits), VV_ERR_NOMEM.
 */
vv_status vv_slabs_open(vv_slabs **out, const char *path, const vv_load_options *opt);
/** The volume's dims, type and geometry (its voxels are not read), owned by @p s. */
const vv_volume *vv_slabs_header(const vv_slabs *s);
/** Slabs read so far (a slab is read once when the boxes come slab by slab). */
uint64_t vv_slabs_loads(const vv_slabs *s);
/**
 * A vv_box_reader over @p slabs (a vv_slabs): voxels lo .. hi (inclusive,
 * x fastest) as a new volume of hi - lo + 1 voxels a side that the caller
 * frees, with the volume's spacing and direction and its origin moved to
 * voxel lo, from the slices held or, when the box leaves them, from its own
 * slices read anew (a gzip stream inflated forward). Errors: VV_ERR_INVALID (a box outside the
 * volume), those of vv_volume_load, VV_ERR_FORMAT (slices that read back in another shape or type:
 * a file changed under the reader), VV_ERR_NOMEM.
 */
vv_status vv_slabs_read_box(void *slabs, const int lo[3], const int hi[3], vv_volume **out);
/** Frees @p s (NULL accepted). */
void vv_slabs_free(vv_slabs *s);
/**
 * Writes the volume @p hdr describes (dims, type, spacing, origin, unit;
 * its voxels are never read) from a box reader (@p read, called with @p ctx
 * from one thread at a time), in memory bounded by the format's pieces
 * rather than the volume: the format from opt->format, or from the
 * extension (formats that write box by box: OME-Zarr, .vvb; opt->vvb_flags
 * for a .vvb). Atomic: on failure nothing is left. Errors: VV_ERR_INVALID
 * (no format from the extension), VV_ERR_UNSUPPORTED (a format that does
 * not write box by box), those of the reader and the writer.
 */
vv_status vv_volume_save_boxes(const vv_volume *hdr, vv_box_reader read, void *ctx,
                               const char *path, const vv_save_options *opt);

/* ---- DICOM series -------------------------------------------------------- */

/* The one format-specific call left public: which series a DICOM folder
 * holds is what a front end shows before reading (volvis info, the GUI's
 * series chooser); the series is then read through vv_volume_load or
 * vv_world_open with vv_load_options.series. */

/** One DICOM image series found by vv_dicom_list. Strings are NUL-terminated. */
typedef struct vv_dicom_series {
    char uid[72];         /**< Series Instance UID */
    char description[72]; /**< Series Description (0008,103E) */
    char modality[20];    /**< Modality (0008,0060): CT, MR, ... */
    int number;           /**< Series Number (0020,0011), 0 when absent */
    int dims[3];    /**< columns, rows, slices (of one time step: files x frames / time_steps) */
    int time_steps; /**< images at every position of a time series (a cardiac cine, 4-D CT):
                         the steps --time and vv_load_options.time read; 1 for one volume */
    int n_files;    /**< image files in the series */
    char first_file[1024];      /**< one file of the series (for messages) */
    char study_description[72]; /**< Study Description (0008,1030) */
    char study_date[20];        /**< Study Date (0008,0020), YYYYMMDD */
    char patient_name[72];      /**< PHI: Patient's Name (0010,0010); print only when asked */
    char patient_id[72];        /**< PHI: Patient ID (0010,0020); print only when asked */
} vv_dicom_series;

/**
 * Lists the image series of @p path: a folder (searched recursively, files
 * that are not DICOM or hold no image skipped), a DICOMDIR, or one DICOM
 * file. Series are ordered by Series Number, then UID. *@p out is a new array
 * of *@p n entries (free() it). Errors: VV_ERR_IO, VV_ERR_FORMAT ("no DICOM
 * images"), VV_ERR_UNSUPPORTED (built without GDCM), VV_ERR_NOMEM.
 */
vv_status vv_dicom_list(vv_dicom_series **out, int *n, const char *path);

#ifdef __cplusplus
}
#endif
#endif
