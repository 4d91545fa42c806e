/*
 * VolVis volume sources, the user's side: where a volume object's voxels
 * come from, and the one memory-bounded cache that holds what they read.
 *
 * A source is what a file holds, opened once (vv_open, io.h): the whole
 * volume in memory, a bricked file read brick by brick on demand (.vvb,
 * raw, raw-encoded NRRD), or a multiresolution pyramid read by chunks
 * (OME-Zarr, BigDataViewer HDF5 and XML, Imaris, a .vvb with levels). A
 * volume object holds its source (vv_object_new_source, model.h); the
 * renderer reads it (vv_renderer_render chooses the whole-frame, region or
 * level-of-detail driver from the objects' sources), and so do the slice
 * views and Measurement, through the same calls.
 *
 * The cache: every brick and chunk read by any source of a process is held
 * in one cache under one budget (vv_cache_process: `--memory-limit`, 1 GiB
 * unless set), least recently used first out (a frame that plans its reads
 * keeps the chunks it needs soonest). A source reserves the working set of
 * the piece it renders (a brick's, or a node's of a pyramid, with the
 * renderer's copies and gradients), and the cache holds the rest: the
 * budget minus the largest reservation of the sources open. Two files
 * opened side by side share it; they never take twice the limit.
 *
 * Implementing a source is the other side (include/volvis/sys/source.h).
 *
 * Thread-safety: sources and caches are reference-counted (atomically);
 * vv_source_read_box, the stats and vv_source_wait may be called from any
 * thread, several at once; a frame's reads go through one renderer at a
 * time (render.h). A cache's functions are thread-safe.
 */
#ifndef VOLVIS_SOURCE_H
#define VOLVIS_SOURCE_H

#include <stdint.h>

#include "core.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the cache -------------------------------------------------------------------- */

typedef struct vv_cache vv_cache;

/** The default budget of a cache: 1 GiB. */
#define VV_CACHE_DEFAULT_LIMIT ((uint64_t)1 << 30)

/**
 * The process's cache, made at the first call with VV_CACHE_DEFAULT_LIMIT
 * (the CLI's `--memory-limit` and the GUI's set it with vv_cache_set_limit
 * before opening files). Borrowed: never free it. Thread-safe.
 */
vv_cache *vv_cache_process(void);

/**
 * A cache of its own with a budget of @p limit bytes (0: the default), for
 * a program that keeps two budgets apart (tests). Free it with
 * vv_cache_free once no source uses it. Errors: VV_ERR_NOMEM.
 */
vv_status vv_cache_new(vv_cache **out, uint64_t limit);
/** Adds a reference (a source keeps one to its cache). */
vv_cache *vv_cache_ref(vv_cache *c);
/** Drops a reference; the last one frees the cache. NULL and the process's cache: nothing. */
void vv_cache_free(vv_cache *c);

/**
 * Sets the budget to @p bytes (0: the default): the pieces held (bricks,
 * chunks, and the reservations of the pieces being rendered) stay within
 * it. Lowering it evicts at the next read. Sources opened before keep the
 * node size they chose. Thread-safe.
 */
void vv_cache_set_limit(vv_cache *c, uint64_t bytes);
/** The budget, bytes. */
uint64_t vv_cache_limit(const vv_cache *c);

/** What a cache holds and did. */
typedef struct vv_cache_stats {
    uint64_t limit;     /**< the budget, bytes */
    uint64_t reserved;  /**< the largest working set the sources open reserve, bytes */
    uint64_t held;      /**< bytes of pieces held now (bricks, chunks, chunks being read) */
    uint64_t peak;      /**< the largest held + reserved since the cache was made */
    uint64_t entries;   /**< pieces held now */
    uint64_t evictions; /**< pieces dropped to stay within the budget */
    int sources;        /**< sources using it now */
} vv_cache_stats;

/** Its counts now. Thread-safe. */
void vv_cache_stats_get(const vv_cache *c, vv_cache_stats *st);

/* ---- sources --------------------------------------------------------------------- */

typedef struct vv_source vv_source;

/** What a source reads from. */
typedef enum vv_source_kind {
    VV_SOURCE_MEMORY = 0,  /**< the whole volume in memory (one level) */
    VV_SOURCE_BRICKS = 1,  /**< a bricked file: bricks of 64^3 cells read on demand */
    VV_SOURCE_PYRAMID = 2, /**< a multiresolution pyramid: levels read by chunks */
} vv_source_kind;

/** Levels read from one pyramid at most. */
#define VV_SOURCE_MAX_LEVELS 16

/** What a source did since it was opened. Counts of one kind stay 0 for the others. */
typedef struct vv_source_stats {
    vv_source_kind kind;
    /* ---- bricks ---- */
    uint64_t loads;     /**< bricks read from the file */
    uint64_t hits;      /**< bricks found in the cache (chunks: chunk_hits) */
    uint64_t skipped;   /**< bricks not read because their min/max is transparent */
    int max_loads;      /**< the most times one brick was read */
    int n_bricks;       /**< bricks in all */
    int bricks_grid[3]; /**< bricks along each axis */
    /* ---- pyramids ---- */
    uint64_t chunk_reads[VV_SOURCE_MAX_LEVELS]; /**< chunks read and decoded, per level */
    uint64_t chunk_hits;                        /**< chunks found decoded in the cache */
    uint64_t missing;             /**< chunks absent from the store (the fill value) */
    uint64_t frames;              /**< frames begun */
    int max_reads_per_frame;      /**< the most times one chunk was read within one frame */
    uint64_t loaded;              /**< chunks the background loader read (in chunk_reads too) */
    uint64_t cancelled;           /**< queued chunks a newer request dropped */
    uint64_t cancelled_in_flight; /**< chunks being fetched (a remote store's) that a newer
                                       request dropped: their requests not sent or abandoned */
    uint64_t load_stopped;        /**< queued chunks left when the cache was full of wanted ones */
    uint64_t load_errors;         /**< the loader's failed reads (a frame reading them says why) */
    int loading;                  /**< chunks queued or being read now */
    int stalled;       /**< 1: the loader stopped short of the newest request (the cache is full of
                            chunks the view wants: a converged frame must stream) */
    uint64_t resident; /**< chunks decoded in the cache now */
    /* ---- both ---- */
    uint64_t evictions;   /**< of its pieces, dropped to stay within the budget */
    uint64_t bytes_read;  /**< bytes read from storage (as stored: compressed) */
    uint64_t held_bytes;  /**< bytes of its pieces in the cache now */
    uint64_t peak_bytes;  /**< the most bytes of its pieces the cache held at once */
    uint64_t limit_bytes; /**< its cache's budget */
} vv_source_stats;

/**
 * A source holding @p volume whole (a new reference is taken): one level,
 * read_box cuts boxes from it. Errors: VV_ERR_INVALID (NULL), VV_ERR_NOMEM.
 */
vv_status vv_source_new_memory(vv_source **out, vv_volume *volume);

/** The volume of a memory source (borrowed), NULL for any other kind. */
vv_volume *vv_source_volume(const vv_source *s);

/** Adds a reference. */
vv_source *vv_source_ref(vv_source *s);
/** Drops a reference; the last one closes the file and drops its pieces from the cache.
 *  Accepts NULL. */
void vv_source_free(vv_source *s);

/** Its kind. */
vv_source_kind vv_source_get_kind(const vv_source *s);
/** "memory", "bricks" or "pyramid". */
const char *vv_source_kind_name(vv_source_kind k);
/** The path it was opened from ("" for a volume in memory); owned by the source. */
const char *vv_source_path(const vv_source *s);
/** The format's name ("vvb", "zarr", "hdf5", "nrrd", "raw"; "memory"). */
const char *vv_source_format(const vv_source *s);

/** Levels (>= 1; 1 for memory and bricks). */
int vv_source_levels(const vv_source *s);
/**
 * Level @p level's geometry (dims, type, spacing, origin of its voxel 0,
 * direction, unit, space and the whole volume's value range) as a volume
 * whose voxels must not be read; borrowed (the whole volume itself for a
 * memory source); NULL out of range.
 */
const vv_volume *vv_source_level(const vv_source *s, int level);

/**
 * Voxels lo .. hi (inclusive, within the level) of level @p level as a new
 * volume (free it) whose voxel (0, 0, 0) is the level's voxel lo, with the
 * level's spacing, origin (of its voxel 0), direction and the whole range.
 * Thread-safe. Errors: VV_ERR_INVALID (a box outside the level),
 * VV_ERR_LIMIT (the box's pieces do not fit the budget), those of reading
 * (VV_ERR_IO, VV_ERR_FORMAT naming the file and the brick or chunk),
 * VV_ERR_NOMEM.
 */
vv_status vv_source_read_box(vv_source *s, int level, const int lo[3], const int hi[3],
                             vv_volume **out);

/**
 * The channels each piece of @p s carries (>= 1): a pyramid opened for
 * several channels of its file (vv_open_options.n_channels) holds them
 * all in each chunk, so that a node of a frame is read once for every
 * channel its object draws. vv_source_level, vv_source_read_box and
 * vv_source_proxy speak of channel 0 (its value range); the channel_
 * functions of any channel. 1 for NULL.
 */
int vv_source_channels(const vv_source *s);
/** vv_source_level with channel @p channel's value range; NULL out of range. Borrowed. */
const vv_volume *vv_source_channel_level(const vv_source *s, int channel, int level);
/** vv_source_read_box of channel @p channel (0 .. vv_source_channels - 1). Thread-safe.
 *  Errors: as vv_source_read_box, VV_ERR_INVALID (no such channel). */
vv_status vv_source_channel_read_box(vv_source *s, int channel, int level, const int lo[3],
                                     const int hi[3], vv_volume **out);
/** vv_source_proxy of channel @p channel. Errors: as vv_source_proxy, VV_ERR_INVALID. */
vv_status vv_source_channel_proxy(vv_source *s, int channel, int level, vv_volume **out);

/**
 * vv_source_read_box of level 0 as a vv_box_reader (volume.h) with the
 * source as @p source: what the box-by-box consumers read full resolution
 * through (vv_measure_histogram_boxes, vv_measure_isosurface_boxes, the
 * box writers of vv_volume_save_boxes).
 */
vv_status vv_source_box(void *source, const int lo[3], const int hi[3], vv_volume **out);

/**
 * A coarse whole volume over the box of level @p level, for previews and a
 * World's defaults (view framing, transfer function from its histogram):
 * a pyramid's coarsest level, a bricked file's every f-th voxel (at most
 * 128 a side), the volume itself in memory (a new reference); its spacing
 * stretched so that it spans the same world box. Errors: VV_ERR_INVALID
 * (no such level), those of reading.
 */
vv_status vv_source_proxy(vv_source *s, int level, vv_volume **out);

/** Its counts since it was opened. Thread-safe. */
void vv_source_stats_get(const vv_source *s, vv_source_stats *st);

/**
 * Pieces its background loader has queued or is reading (a pyramid's, for
 * progressive frames: vv_render_options.lod); 0 when idle or none.
 * Thread-safe.
 */
int vv_source_loading(vv_source *s);
/**
 * Waits up to @p seconds until the loader finishes a piece or has nothing
 * left to do; returns vv_source_loading's count then. Thread-safe.
 */
int vv_source_wait(vv_source *s, double seconds);
/** Cancels what its loader has queued (a view that moved on). Thread-safe. */
void vv_source_cancel(vv_source *s);

/**
 * Read-ahead of another time step: asks @p s's background loader for the
 * chunks that @p like read in its last frame (the boxes of its frame's
 * plan, or of its newest request), soonest first, as vv_source_loading
 * then counts them: @p s is the next step of the file @p like shows, drawn
 * by the same view, so that its frame finds them resident. Returns at once.
 * Errors: VV_ERR_UNSUPPORTED (not two pyramids, or of different levels),
 * those of the request (VV_ERR_LIMIT, VV_ERR_NOMEM). Thread-safe.
 */
vv_status vv_source_read_ahead(vv_source *s, const vv_source *like);

/** Its cache (borrowed); NULL for a memory source. */
vv_cache *vv_source_cache(const vv_source *s);

#ifdef __cplusplus
}
#endif
#endif
