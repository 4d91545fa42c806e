/*
 * VolVis volume sources, the implementor's side (include/volvis/source.h is
 * the user's): the table a source fills in (vv_source_ops: its levels,
 * boxes, proxy, statistics and background loader), and the two views of its
 * voxels that the render drivers read (src/render/drivers.h, chosen by
 * vv_renderer_render): a grid of bricks (vv_brick_source: the region driver
 * renders them front to back) and a pyramid of levels read by boxes
 * (vv_multires_source: the level-of-detail driver). The drivers read
 * voxels without knowing the file format, and a format's reader (src/io:
 * .vvb, raw, NRRD, OME-Zarr, HDF5) serves them without knowing the
 * renderers. Version fields first, as libgit2's plug-in structs.
 *
 * A brick source is a grid of bricks over a volume's index box. Brick b
 * covers the cells lo .. hi (voxel indices of its faces, shared with its
 * neighbours) and is read with one voxel more beyond each face (slo ..
 * shi, within the volume), so that trilinear samples and central
 * differences at its faces are the whole volume's; each brick has the min
 * and max of the voxels read (empty-space skipping before reading).
 *
 * A multiresolution source (vv_multires_source, below) serves a pyramid
 * of levels by boxes of voxels instead, for the level-of-detail driver.
 *
 * Thread-safety: a brick or multiresolution view is used from one thread
 * at a time (the frame's); vv_source's functions as source.h says.
 */
#ifndef VOLVIS_SYS_SOURCE_H
#define VOLVIS_SYS_SOURCE_H

#include "../core.h"
#include "../source.h"
#include "../volume.h"

#ifdef __cplusplus
extern "C" {
#endif

#define VV_BRICK_CELLS 64 /**< brick side in cells (the last brick of an axis may be shorter) */

/** The version of vv_brick_source this header describes. */
#define VV_BRICK_SOURCE_VERSION 1

/** One brick's boxes and value range. */
typedef struct vv_brick_info {
    int lo[3], hi[3];   /**< the brick's cells: voxel indices lo .. hi (its faces) */
    int slo[3], shi[3]; /**< the voxels read: one beyond each face, within the volume */
    float vmin, vmax;   /**< min and max of the voxels read (data units) */
} vv_brick_info;

/** A bricked volume as its consumers see it; every method takes @p user. */
typedef struct vv_brick_source {
    int version; /**< VV_BRICK_SOURCE_VERSION */
    void *user;  /**< the source's state */
    /**
     * The volume's geometry as a volume whose voxels must not be read:
     * dims, type, spacing, origin, direction, value range, unit. Borrowed.
     */
    const vv_volume *(*header)(void *user);
    /** Bricks along each axis (brick index (i, j, k) = (k nb[1] + j) nb[0] + i). */
    void (*grid)(void *user, int nb[3]);
    /** Brick @p index's boxes and min/max. */
    void (*info)(void *user, int index, vv_brick_info *out);
    /**
     * Brick @p index as a new volume reference of its voxels slo .. shi with
     * the whole volume's spacing, origin, direction and value range (its
     * voxel (0, 0, 0) is the whole volume's voxel slo). Errors: VV_ERR_IO,
     * VV_ERR_FORMAT, VV_ERR_NOMEM.
     */
    vv_status (*load)(void *user, int index, vv_volume **out);
    /** Optional (NULL): counts a brick skipped unread (statistics). */
    void (*note_skip)(void *user);
} vv_brick_source;

/** The version of vv_multires_source this header describes. */
#define VV_MULTIRES_SOURCE_VERSION 3

/**
 * A multiresolution (pyramid) volume as its consumers see it: levels 0
 * (finest) .. n_levels - 1, each a regular grid of its own dims, spacing and
 * origin with the direction of level 0 (OME-Zarr multiscales, or one level:
 * a .vvb, raw or NRRD file), read by boxes of voxels through the source's
 * own chunk cache. Every method takes @p user. Thread-safety: a source is
 * used from one thread at a time (it may read with several).
 */
typedef struct vv_multires_source {
    int version;  /**< VV_MULTIRES_SOURCE_VERSION */
    void *user;   /**< the source's state */
    int n_levels; /**< >= 1 */
    /**
     * The side of the level-of-detail octree's leaves in level-0 cells (a
     * node reads about that many voxels of its level a side, plus ghosts):
     * the largest the source's memory limit holds with the chunks such a box
     * needs; 0: VV_BRICK_CELLS (64).
     */
    int node_cells;
    /**
     * Level @p level's geometry as a volume whose voxels must not be read:
     * dims, type, spacing, origin, direction, unit, and the value range of
     * the whole volume (the same at every level: it scales the transfer
     * function's tables, so every level's samples classify alike). Borrowed.
     */
    const vv_volume *(*level)(void *user, int level);
    /**
     * Voxels lo .. hi (inclusive; 0 <= lo <= hi < dims of the level) of
     * level @p level as a new volume reference whose voxel (0, 0, 0) is the
     * level's voxel lo, with the level's spacing, origin (of its voxel 0),
     * direction and the whole range. Errors: VV_ERR_IO, VV_ERR_FORMAT (a
     * chunk that does not decode), VV_ERR_LIMIT (the box and the chunks it
     * needs exceed the memory limit), VV_ERR_NOMEM.
     */
    vv_status (*read_box)(void *user, int level, const int lo[3], const int hi[3], vv_volume **out);
    /**
     * Optional (NULL): the min and max over voxels lo .. hi of @p level when
     * the source knows them without reading (an index, or chunks read
     * before): 1 and *vmin, *vmax set; 0 when unknown.
     */
    int (*box_range)(void *user, int level, const int lo[3], const int hi[3], float *vmin,
                     float *vmax);
    /** Optional (NULL): a frame begins (@p begin 1) or ends (0); for statistics. */
    void (*frame)(void *user, int begin);
    /**
     * Optional (NULL): the boxes the frame will read, in the order it reads
     * them (box i: level[i], voxels lo[3i .. 3i+2] .. hi[3i .. 3i+2],
     * inclusive); until the next plan or frame
     * end, read_box calls follow it one by one, and the source keeps the
     * chunks needed soonest (Belady's farthest-next-use eviction), so that
     * a chunk is read once a frame whenever the boxes' shared chunks fit.
     * Errors: VV_ERR_NOMEM (the reads then go unplanned).
     */
    vv_status (*plan)(void *user, int n, const int *level, const int *lo, const int *hi);
    /**
     * Optional (NULL): how many of the chunks holding voxels lo .. hi of
     * @p level are not in the source's cache (0: the box reads without I/O);
     * for progressive frames (vv_lod.progressive).
     */
    int (*missing_chunks)(void *user, int level, const int lo[3], const int hi[3]);
    /**
     * The boxes (read_box results, each with the renderer's working set for
     * it) the source's memory limit holds at once besides its cache: the
     * driver renders up to that many nodes at a time, one a thread (reads
     * stay one at a time and in the plan's order). 0 or 1: one.
     */
    int boxes;
    /* ---- version 2 ---- */
    /**
     * Optional (NULL): asks the source to load the chunks of these boxes in
     * the background (box i as in plan), soonest first in this order,
     * replacing whatever an earlier request left queued (a new view made it
     * stale); n 0 cancels. Returns at once; a later progressive frame finds
     * them resident (missing_chunks). Errors: VV_ERR_INVALID, VV_ERR_LIMIT,
     * VV_ERR_NOMEM.
     */
    vv_status (*request)(void *user, int n, const int *level, const int *lo, const int *hi);
    /**
     * Optional (NULL): 1 when the background loading of the newest request
     * stopped short because the source's cache is full of chunks it wants.
     */
    int (*stalled)(void *user);
    /* ---- version 3: channels ---- */
    /**
     * The channels each box carries (0 or 1: one). More: the source's
     * chunks hold every channel (the cache counts them all, a node's
     * channels arrive together, a progressive frame draws a node at one
     * level for all of them), read_box, box_range and level speak of
     * channel 0, and the driver reads a node by read_channels.
     */
    int n_channels;
    /**
     * n_channels > 1: voxels lo .. hi of @p level of every channel at once,
     * out[k] channel k's new volume as read_box makes it (with that
     * channel's value range); one read of the plan (it moves on once).
     * Errors: as read_box; nothing is set in @p out then.
     */
    vv_status (*read_channels)(void *user, int level, const int lo[3], const int hi[3],
                               vv_volume **out);
    /** n_channels > 1: box_range of channel @p channel. */
    int (*channel_range)(void *user, int channel, int level, const int lo[3], const int hi[3],
                         float *vmin, float *vmax);
    /** n_channels > 1: level's header with channel @p channel's value range. Borrowed. */
    const vv_volume *(*channel_level)(void *user, int channel, int level);
    /** n_channels > 1: read_box of channel @p channel outside the frame's plan (the plan
     *  stays where it is): what a whole-volume sweep reads (shadows). */
    vv_status (*channel_read_box)(void *user, int channel, int level, const int lo[3],
                                  const int hi[3], vv_volume **out);
    /**
     * Optional (NULL): how many of the chunks holding voxels lo .. hi of
     * @p level are in the source's cache (0: nothing of the box is there).
     * A progressive frame draws a node of which nothing finer is resident
     * as one region of a coarse level, not as many small ones.
     */
    int (*resident_chunks)(void *user, int level, const int lo[3], const int hi[3]);
} vv_multires_source;

/* ---- chunked stores: a multiresolution format's side of a pyramid ------------------ */

/** Levels a store holds at most. */
#define VV_STORE_MAX_LEVELS VV_SOURCE_MAX_LEVELS
/** Channels one read of a store fills at most (VV_MAX_CHANNELS, model.h). */
#define VV_STORE_MAX_CHANNELS 16

/** One level of a store. */
typedef struct vv_store_level {
    /**
     * The level's geometry as a volume of one voxel whose dims are set to
     * the level's (dims, type, spacing, origin of its voxel 0, direction,
     * unit); owned by the store until the pyramid takes it
     * (vv_store_set_level makes it).
     */
    vv_volume *hdr;
    int cdims[3]; /**< the chunk box (voxels along x, y, z), >= 1 */
} vv_store_level;

/**
 * A multiresolution file's store, filled by its record's open_store: what
 * its levels are and how to fetch one chunk's voxels. The pyramid over it
 * (src/io/store/pyramid.c, pyramid_load.c and pyramid_open.c: the cache, the
 * frame's plan, the background loader, the source the renderers read) is
 * the library's.
 */
typedef struct vv_store {
    const char *name; /**< the format's name for errors ("zarr", "hdf5") */
    void *ctx;        /**< the store's state, freed by close */
    int n_levels;     /**< 1 .. VV_STORE_MAX_LEVELS, finest first */
    vv_store_level lv[VV_STORE_MAX_LEVELS];
    int n_channels, n_times; /**< for vv_load_info */
    int has_range;           /**< 1: range is the data's (an omero window) */
    double range[2];
    size_t scratch; /**< bytes of scratch each read_chunk call needs (0: none) */
    int parallel;   /**< 1: read_chunk may run on several threads at once (else the pyramid
                         serializes it, its loader's reads included); N > 1: as 1, and its
                         reads wait on the network: up to N threads read at once, however
                         few the cores */
    /**
     * Chunk @p c (chunk indices along x, y, z) of @p level: its voxels
     * inside the level, box org .. org + dims - 1, written to @p dst (x
     * fastest, the level's type); @p scratch holds the store's scratch
     * bytes. *missing: 1 when the chunk is absent and was filled with the
     * fill value; *file_bytes: the bytes read from storage. Errors:
     * VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_NOMEM, VV_ERR_LIMIT (naming the
     * chunk).
     */
    vv_status (*read_chunk)(void *ctx, int level, const int c[3], unsigned char *scratch,
                            unsigned char *dst, const int org[3], const int dims[3], int *missing,
                            uint64_t *file_bytes);
    void (*close)(void *ctx);
    /**
     * Optional (NULL): start fetching chunk @p c of @p level ahead of its
     * read_chunk, without waiting (a later read_chunk of it takes the
     * result; one of another chunk may drop it). 1: asked (or already
     * asked); 0: nothing free to ask, stop. Called from the frame's thread,
     * never during its own read_chunk calls.
     */
    int (*prefetch)(void *ctx, int level, const int c[3]);
    /**
     * Optional (NULL): the range of chunk @p c of @p level's voxels as the
     * store's index gives it before any voxel is read (a .vvb: its chunks'
     * min and max); 1 when known. Asked once per chunk when the pyramid
     * opens, so that empty space is skipped before its chunks are read.
     */
    int (*chunk_range)(void *ctx, int level, const int c[3], double *lo, double *hi);
    /**
     * Optional (NULL): @p n chunks of @p level at once, chunk i (indices
     * c[3i .. 3i + 2]) into dst[i] (box org[3i ..], dims[3i ..]) with
     * missing[i] and file_bytes[i] as read_chunk gives them and its voxels'
     * range (fill values included) in range[2i] (least) and range[2i + 1]
     * (greatest), taken as the voxels are copied in, decoded on
     * @p nthreads threads (the caller's among them) while the store fetches
     * the next ones; asked in the order given (the pyramid's: a frame's
     * plan, coarse levels first, then front to back). A remote store puts
     * its requests in flight together. @p stale (may be NULL) says whether
     * chunk i is still wanted: stale(@p stale_user, i) 1 when the caller
     * no longer needs it (a view moved on); the store asks before fetching
     * and while a fetch is in flight (from threads of its own, about every
     * 50 ms) and drops such a chunk unread, cancelled[i] = 1 (its dst,
     * missing, file_bytes and range untouched; not an error); @p cancelled
     * may be NULL only when @p stale is. The first failing chunk's error.
     */
    vv_status (*read_many)(void *ctx, int level, int n, const int *c, unsigned char *const *dst,
                           const int *org, const int *dims, int nthreads, int *missing,
                           uint64_t *file_bytes, double *range,
                           int (*stale)(void *stale_user, int i), void *stale_user, int *cancelled);
    /* ---- channels ---- */
    /**
     * The channels one read fills (0 or 1: one, the channel the store was
     * opened for; at most VV_STORE_MAX_CHANNELS): read_chunk and read_many
     * write them one after another at dst, channel k's block of dims voxels
     * at k times its bytes (x fastest, the level's type), and read_many's
     * @p range holds 2 n_ch numbers a chunk (chunk i's channel k least at
     * range[2 (i n_ch + k)], greatest after it). *missing: 1 when every
     * channel's chunk is absent. A store that chunks its channels together
     * (an OME-Zarr array chunked by several along c) decodes such a chunk
     * once for all the channels it holds. chunk_range is then not used.
     */
    int n_ch;
    /** n_ch > 1: 1 where ch_range[k] is channel k's data range from the metadata (its omero
     *  window's min and max), as has_range and range are for one channel */
    int ch_has_range[VV_STORE_MAX_CHANNELS];
    double ch_range[VV_STORE_MAX_CHANNELS][2];
} vv_store;

/**
 * Level @p level's header in @p st (one voxel of @p type, its dims set to
 * @p dims; the caller sets its geometry) and chunk box @p cdims. Errors:
 * VV_ERR_NOMEM.
 */
vv_status vv_store_set_level(vv_store *st, int level, vv_voxel_type type, const int dims[3],
                             const int cdims[3]);

/** Frees what a store holds (its headers and, through close, its state); zeroes it. */
void vv_store_close(vv_store *st);

/**
 * The stores @p parts[0 .. n) (n 1 .. VV_STORE_MAX_CHANNELS, each of one
 * channel of the same file: the same levels, dims, chunk boxes, type and
 * geometry) as one store of n channels in @p out (n_ch = n; channel k is
 * parts[k]'s): a chunk read reads each part's chunk in turn into its
 * channel's block. What a format whose stores hold one channel (the HDF5
 * pyramids, in the reader sandbox or here) carries channels by. The parts
 * are taken (closed, also on error) and zeroed. Errors: VV_ERR_INVALID (n
 * out of range, a part of several channels), VV_ERR_FORMAT (parts that
 * differ: named by channel and level), VV_ERR_NOMEM.
 */
vv_status vv_store_stack(vv_store *out, vv_store *parts, int n);

/* ---- the table a source fills in ------------------------------------------------- */

/** The version of vv_source_ops this header describes (version 1 tables, without
 *  channels, are taken too). */
#define VV_SOURCE_OPS_VERSION 2

/**
 * One kind of source. Every method takes the @p user given to
 * vv_source_new. Required: version, kind, format, levels, level, read_box,
 * proxy, stats, close; bricks for VV_SOURCE_BRICKS, multires for
 * VV_SOURCE_PYRAMID; loading, wait and cancel optional (NULL: no loader).
 * read_box, stats, loading, wait and cancel must be thread-safe.
 */
typedef struct vv_source_ops {
    int version;         /**< VV_SOURCE_OPS_VERSION */
    vv_source_kind kind; /**< what it reads from */
    const char *format;  /**< its name for messages when vv_source_new names no format */
    int (*levels)(void *user);
    const vv_volume *(*level)(void *user, int level);
    vv_status (*read_box)(void *user, int level, const int lo[3], const int hi[3], vv_volume **out);
    vv_status (*proxy)(void *user, int level, vv_volume **out);
    /** VV_SOURCE_BRICKS: its bricks as a brick source (borrowing @p user). */
    void (*bricks)(void *user, vv_brick_source *out);
    /** VV_SOURCE_PYRAMID: its levels as a multiresolution source (borrowing @p user). */
    void (*multires)(void *user, vv_multires_source *out);
    void (*stats)(void *user, vv_source_stats *out);
    int (*loading)(void *user);
    int (*wait)(void *user, double seconds);
    void (*cancel)(void *user);
    /** Closes the file and frees @p user (its pieces leave the cache). */
    void (*close)(void *user);
    /* ---- version 2: channels (optional, NULL: one channel) ---- */
    /** The channels each piece carries (>= 1). */
    int (*channels)(void *user);
    /** Level @p level's geometry with channel @p channel's value range. Borrowed. */
    const vv_volume *(*channel_level)(void *user, int channel, int level);
    /** read_box of channel @p channel. Thread-safe. */
    vv_status (*channel_read_box)(void *user, int channel, int level, const int lo[3],
                                  const int hi[3], vv_volume **out);
    /** proxy of channel @p channel. */
    vv_status (*channel_proxy)(void *user, int channel, int level, vv_volume **out);
    /** Optional (NULL): asks the loader for the chunks that @p like_user (a source of the
     *  same table: another time step of the same file) read in its last frame
     *  (vv_source_read_ahead). Returns at once. */
    vv_status (*read_ahead)(void *user, void *like_user);
} vv_source_ops;

/**
 * A source of @p ops over @p user (taken: closed by the last
 * vv_source_free, and on error here), opened from @p path (copied; may be
 * NULL) of format @p format (copied, at most 31 bytes; NULL: ops->format),
 * its pieces held in @p cache (may be NULL: a memory source; a reference is
 * taken). Errors: VV_ERR_INVALID (a table of another version, a required
 * method missing), VV_ERR_NOMEM.
 */
vv_status vv_source_new(vv_source **out, const vv_source_ops *ops, void *user, const char *path,
                        const char *format, vv_cache *cache);

/**
 * The region driver's view of @p s: its bricks (a memory source: one brick,
 * the whole volume). 1 and *@p out filled; 0 for a pyramid. The view
 * borrows @p s.
 */
int vv_source_brick_view(vv_source *s, vv_brick_source *out);

/**
 * @p v in memory as a brick source of one brick, the whole volume (what a
 * memory source's brick view is, and how the drivers draw an object in
 * memory beside objects out of core). The view borrows @p v.
 */
void vv_volume_brick_view(vv_volume *v, vv_brick_source *out);
/** The level-of-detail driver's view of @p s: 1 and *@p out filled for a
 *  pyramid, else 0. The view borrows @p s. */
int vv_source_multires_view(vv_source *s, vv_multires_source *out);

#ifdef __cplusplus
}
#endif
#endif
