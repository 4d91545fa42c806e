/*
 * VolVis out-of-core volumes: a volume larger than memory, cut into bricks
 * that are read on demand into a cache with a memory budget, least recently
 * used first out (src/io/bricked.c). The reader serves its bricks through
 * the volume-source interface (include/volvis/sys/source.h,
 * vv_bricked_source), through which any renderer with the region contract
 * renders it brick by brick in front-to-back order
 * (vv_renderer_render_bricks in render.h, src/render/bricks_render.c).
 *
 * Bricks are 64^3 cells with a one-voxel ghost border (each brick is read
 * with the voxels one beyond its faces, so that trilinear samples and
 * central-difference gradients at its faces are those of the whole volume).
 * Sources: the bricked format .vvb of our own (docs/file-formats.md: a
 * header, an index with each brick's offset, size and min/max, each brick's
 * voxels with their ghosts in one piece, and an optional coarse level per
 * brick), raw files and NRRD files with raw encoding, all read with pread:
 * a brick costs one read in a .vvb and one read a row of voxels otherwise.
 * Opening a raw or NRRD file streams it once, a slice at a time, for the
 * value range and the bricks' min/max (a .vvb has them in its index).
 *
 * Thread-safety: one vv_bricked must not be used from two threads at once.
 */
#ifndef VOLVIS_BRICKS_H
#define VOLVIS_BRICKS_H

#include <stdint.h>

#include "core.h"
#include "io.h"
#include "sys/source.h"
#include "volume.h"

#ifdef __cplusplus
extern "C" {
#endif

#define VV_BRICK_CELLS 64 /**< brick side in cells (the last brick of an axis may be shorter) */

typedef struct vv_bricked vv_bricked;

/** What a bricked volume did since it was opened. */
typedef struct vv_bricked_stats {
    uint64_t loads;      /**< bricks read from the file */
    uint64_t hits;       /**< bricks found in the cache */
    uint64_t evictions;  /**< bricks dropped to stay within the budget */
    uint64_t skipped;    /**< bricks not read because their min/max is transparent */
    uint64_t bytes_read; /**< bytes read by pread, header, index and scans included */
    uint64_t peak_bytes; /**< largest cache size, bytes of voxels */
    int max_loads;       /**< the most times one brick was read */
} vv_bricked_stats;

/**
 * Opens @p path as a bricked volume: a .vvb file; a raw file when @p raw is
 * not NULL; else an uncompressed (raw-encoded) NRRD file, attached or
 * detached. @p memory_limit (bytes, 0: 1 GiB) bounds the voxels held: the
 * cached bricks and the working set of the brick being rendered. Errors:
 * VV_ERR_IO, VV_ERR_FORMAT (bad header or index: a brick past the end of
 * the file, a size that does not match its box (zstd bricks: 0 or more
 * than the bound of its box), an unknown brick codec; a compressed NRRD,
 * which must be converted first), VV_ERR_LIMIT (a memory limit smaller than one
 * brick and its working set), VV_ERR_NOMEM.
 */
vv_status vv_bricked_open(vv_bricked **out, const char *path, const vv_raw_params *raw,
                          uint64_t memory_limit);
/**
 * Opens like vv_bricked_open without the streaming pass over a raw or NRRD
 * file: the header only (a .vvb: header and index, as vv_bricked_open). The
 * value range (vv_bricked_header) and the bricks' min/max are then unknown
 * (0 and never skipped) until the caller sets the range; for reading boxes
 * (vv_bricked_read_box) by the ranks of a distributed render, which learn
 * the range from their own boxes. Errors: as vv_bricked_open.
 */
vv_status vv_bricked_open_header(vv_bricked **out, const char *path, const vv_raw_params *raw,
                                 uint64_t memory_limit);

/**
 * Reads the voxels lo .. hi (inclusive, within the volume) into a new
 * volume with the bricked volume's geometry and range (its voxel (0, 0, 0)
 * is voxel lo): raw layouts one pread a row, a .vvb from the bricks that
 * overlap the box (each read once, not cached). Errors: VV_ERR_INVALID (a
 * box outside the volume), VV_ERR_IO, VV_ERR_FORMAT (short file),
 * VV_ERR_NOMEM.
 */
vv_status vv_bricked_read_box(vv_bricked *b, const int lo[3], const int hi[3], vv_volume **out);
/** vv_bricked_read_box as a vv_box_reader (volume.h) with the bricked volume as @p bricked. */
vv_status vv_bricked_box(void *bricked, const int lo[3], const int hi[3], vv_volume **out);

/** Sets the value range (after vv_bricked_open_header). */
void vv_bricked_set_range(vv_bricked *b, double lo, double hi);

/** Closes the file and frees the cache. Accepts NULL. */
void vv_bricked_free(vv_bricked *b);

/**
 * The volume's header as a volume of one voxel holding its geometry: dims,
 * type, spacing, origin, direction, range, unit (dims are the bricked
 * volume's; data holds one voxel only: never read it). Borrowed.
 */
const vv_volume *vv_bricked_header(const vv_bricked *b);

/** Bricks along each axis. */
void vv_bricked_grid(const vv_bricked *b, int nb[3]);

/**
 * A coarse whole volume for previews and defaults (view framing, transfer
 * function from its histogram): every f-th voxel along each axis, f the
 * smallest that keeps every axis within @p max_side voxels, with the
 * spacing scaled so that it spans the same world box. A .vvb with coarse
 * levels is read from them; otherwise rows of voxels are read with pread.
 * Errors: VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_bricked_proxy(vv_bricked *b, int max_side, vv_volume **out);

/** Its counts since opening. */
void vv_bricked_stats_get(const vv_bricked *b, vv_bricked_stats *s);

/** vv_bricked_write_vvb flags: each brick also gets its coarse level
 * (every 4th voxel; previews read those). */
#define VV_VVB_COARSE 1u
/** Each brick's voxels are one zstd frame (level 3), decoded when the brick
 * is read; implies VV_VVB_COARSE (docs/file-formats.md). */
#define VV_VVB_ZSTD 2u
/** The pyramid levels after the bricks: each level half the one before
 * along every axis longer than one voxel (rounding up; each voxel the mean
 * of the 2x2x2 under it, as the OME-Zarr writer's levels) until every axis
 * fits one chunk of 64 voxels, stored as chunks of 64^3 (raw, or zstd
 * frames with VV_VVB_ZSTD) with their min/max; vv_pyramid_open reads them
 * (docs/file-formats.md). Written from level 0 read back, a chunk at a
 * time: memory stays bounded. */
#define VV_VVB_LEVELS 4u

/**
 * Writes @p src (a bricked volume opened from any source) as a .vvb file at
 * @p path, written to a temporary file beside it and renamed; @p flags
 * VV_VVB_COARSE, VV_VVB_ZSTD (0: raw bricks, no coarse levels). Reads one
 * brick at a time: memory is bounded by a brick, not the volume.
 * Errors: VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_bricked_write_vvb(vv_bricked *src, const char *path, unsigned flags,
                               const vv_progress *progress);

/**
 * Writes the in-memory volume @p v as a .vvb file (for formats that cannot
 * be read by bricks: compressed NRRD, SLC, NIfTI, ...); @p flags as
 * vv_bricked_write_vvb. Errors: VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_volume_write_vvb(const vv_volume *v, const char *path, unsigned flags);

/**
 * Writes a .vvb file of the volume @p hdr describes (dims, type, geometry;
 * its voxels are not read) from a box reader, one brick (with its ghost
 * voxels) at a time in brick order (i fastest, then j, then k): memory is
 * the reader's and a brick's (vv_slabs: one slab of 66 slices, the ghost
 * slices the next layer of bricks shares kept). @p flags as
 * vv_bricked_write_vvb. Atomic as it: on failure nothing is left. Errors:
 * VV_ERR_IO, VV_ERR_NOMEM, the reader's, VV_ERR_INVALID (a box of another
 * shape or type from @p read).
 */
vv_status vv_boxes_write_vvb(const vv_volume *hdr, vv_box_reader read, void *ctx, const char *path,
                             unsigned flags, const vv_progress *progress);

/**
 * Pyramid levels of a .vvb, level 0 (the bricks) included: 1 when it has
 * none (written without VV_VVB_LEVELS) and for raw layouts. vv_pyramid_open
 * reads a .vvb of more than one.
 */
int vv_bricked_levels(const vv_bricked *b);
/** Bricks in all (nb[0] nb[1] nb[2], i fastest). */
int vv_bricked_count(const vv_bricked *b);
/** Brick @p index's boxes and min/max (@p index in 0 .. vv_bricked_count - 1). */
void vv_bricked_info(const vv_bricked *b, int index, vv_brick_info *info);
/**
 * Brick @p index as a volume of its voxels read (the box slo .. shi) with
 * the whole volume's geometry and value range, from the cache or the file;
 * a new reference (free it). Errors: VV_ERR_IO, VV_ERR_FORMAT (short
 * read; a zstd brick that does not decode to its box's size, naming the
 * brick and its offset), VV_ERR_NOMEM.
 */
vv_status vv_bricked_load(vv_bricked *b, int index, vv_volume **out);
/** Counts a brick skipped unread (vv_bricked_stats.skipped). */
void vv_bricked_note_skip(vv_bricked *b);

/**
 * @p b as a volume source (sys/source.h) for vv_renderer_render_bricks:
 * header, grid, info, load and note_skip call the functions above. @p b
 * is borrowed: keep it open while @p out is used.
 */
void vv_bricked_source(vv_bricked *b, vv_brick_source *out);

/* ---- multiresolution pyramids (OME-Zarr, BigDataViewer / Imaris HDF5) --------------- */

#define VV_PYRAMID_MAX_LEVELS 16 /**< levels read from one store */

typedef struct vv_pyramid vv_pyramid;

/** What a pyramid did since it was opened. */
typedef struct vv_pyramid_stats {
    uint64_t chunk_reads[VV_PYRAMID_MAX_LEVELS]; /**< chunk files read and decoded, per level */
    uint64_t chunk_hits;                         /**< chunks found decoded in the cache */
    uint64_t missing;        /**< chunks absent from the store (the fill value) */
    uint64_t evictions;      /**< chunks dropped to stay within the limit */
    uint64_t bytes_read;     /**< bytes of chunk files read */
    uint64_t peak_bytes;     /**< the cache's largest size, bytes of voxels */
    uint64_t frames;         /**< frames begun (vv_multires_source.frame) */
    int max_reads_per_frame; /**< the most times one chunk was read within one frame */
    uint64_t loaded;         /**< chunks the loader read (vv_pyramid_request; in chunk_reads too) */
    uint64_t cancelled;      /**< queued chunks a newer request dropped */
    uint64_t load_stopped;   /**< queued chunks left when the cache was full of wanted ones */
    uint64_t load_errors;    /**< the loader's failed reads (a frame reading them reports why) */
    int loading;             /**< chunks queued or being read now */
    /**
     * 1: the loader stopped short of the newest request because the cache
     * is full of chunks it wants (the view needs more than the limit holds:
     * a converged frame must stream, see vv_lod.stalled)
     */
    int stalled;
    uint64_t held_bytes;  /**< the cache's size now, bytes of voxels (and chunks being read) */
    uint64_t resident;    /**< chunks decoded in the cache now */
    uint64_t limit_bytes; /**< the memory limit */
} vv_pyramid_stats;

/**
 * Opens the multiresolution file at @p path for reading by boxes: an
 * OME-Zarr store (or plain Zarr v2 array: one level; a folder), a
 * BigDataViewer HDF5 or Imaris .ims file (an HDF5 file), or a .vvb file
 * (its pyramid levels, VV_VVB_LEVELS; one level without them), channel
 * @p channel (BigDataViewer: setup) at time step @p time (-1: 0) of every
 * level. Only the metadata and the coarsest level's chunks are read. The
 * value range is the omero window's min and max of the channel, else the
 * coarsest level's (finer values beyond it classify as its ends).
 * @p memory_limit (bytes, 0: 1 GiB) bounds the decoded chunks held and the
 * working set of the box being rendered. @p info (may be NULL) gets the
 * channel, step and level counts and the omero name and colour. Every level
 * must have level 0's axes, type, channels and steps. Zarr chunks are
 * decoded in this process on every core; HDF5 chunks are read by libhdf5
 * in a long-lived sandboxed reader (docs/security.md), one at a time; a
 * .vvb's chunks are read in this process (a level-0 chunk of 64^3 from the
 * brick holding it) on every core, as vv_bricked reads them.
 * Errors (prefixed "zarr: NAME", "hdf5: NAME" or "vvb: NAME"): those of
 * vv_ome_zarr_read, the HDF5 reader or the .vvb reader (naming the level
 * and chunk or brick), VV_ERR_INVALID (a channel or step of a .vvb other
 * than 0), VV_ERR_FORMAT (inconsistent
 * multiscales; neither HDF5 layout), VV_ERR_LIMIT (over
 * VV_PYRAMID_MAX_LEVELS levels; a limit below one box's working set).
 * Thread-safety: vv_pyramid_read_box and the source's methods from one
 * thread at a time; vv_pyramid_request, vv_pyramid_loading,
 * vv_pyramid_wait and vv_pyramid_stats_get from any thread, also while a
 * frame reads. The pyramid's loader threads (started by the first
 * request) share its cache under a lock.
 */
vv_status vv_pyramid_open(vv_pyramid **out, const char *path, int channel, int time,
                          uint64_t memory_limit, vv_load_info *info);
void vv_pyramid_free(vv_pyramid *p);
/**
 * 1 when @p path is what vv_pyramid_open reads: a folder holding .zattrs
 * or .zarray, a file starting with HDF5's signature, or a .vvb whose
 * header gives pyramid levels (a .vvb without them: 0, it reads by bricks);
 * 0 otherwise (not a promise that it opens). Thread-safe.
 */
int vv_pyramid_probe(const char *path);
/** Levels (>= 1). */
int vv_pyramid_levels(const vv_pyramid *p);
/**
 * Level @p level's geometry (dims, type, spacing and origin from the
 * level's scale and translation, the store's range) as a volume whose
 * voxels must not be read; borrowed; NULL when out of range.
 */
const vv_volume *vv_pyramid_level(const vv_pyramid *p, int level);
/**
 * Voxels lo .. hi (inclusive) of level @p level as a new volume (voxel
 * (0, 0, 0) is the level's voxel lo; the level's spacing, origin,
 * direction and the store's range), assembled from the cached chunks and
 * those read for it (kept). Errors: VV_ERR_INVALID (a box outside the
 * level), VV_ERR_LIMIT (its chunks do not fit the limit), those of reading
 * a chunk (naming the chunk's file).
 */
vv_status vv_pyramid_read_box(vv_pyramid *p, int level, const int lo[3], const int hi[3],
                              vv_volume **out);
/**
 * vv_pyramid_read_box of level 0 as a vv_box_reader (volume.h) with the
 * pyramid as its @p pyramid context: what the box-by-box consumers
 * (vv_measure_histogram_boxes, vv_measure_isosurface_boxes,
 * vv_ome_zarr_write_boxes, vv_boxes_write_vvb) read a pyramid's full
 * resolution through.
 */
vv_status vv_pyramid_level0_box(void *pyramid, const int lo[3], const int hi[3], vv_volume **out);
void vv_pyramid_stats_get(const vv_pyramid *p, vv_pyramid_stats *st);
/**
 * The proxy of @p p: its coarsest level (read through the cache) as a new
 * volume stretched over the box of level @p level (0: the finest), its
 * origin that level's and its spacing the level's extent over the coarsest
 * level's voxels, so that it spans the same world box: what a World shows
 * in place of the whole (the view frames it, its histogram sets the
 * default transfer function, vv_renderer_render_multires takes the
 * geometry from the pyramid). Errors: VV_ERR_INVALID (no such level),
 * those of vv_pyramid_read_box.
 */
vv_status vv_pyramid_proxy(vv_pyramid *p, int level, vv_volume **out);
/**
 * Asynchronous loading: asks the pyramid's loader -- a few I/O threads
 * (vv_threads_get(), at most 4; one when the store reads a chunk at a
 * time), started at the first request -- to read the chunks of boxes
 * 0 .. n-1 (box i: level @p level[i], voxels lo[3i .. 3i+2] ..
 * hi[3i .. 3i+2], inclusive) into the cache in the background, soonest
 * first in this order (each chunk once; the caller orders by priority:
 * vv_renderer_render_multires's progressive frames ask for coarse levels
 * first, then the nodes nearest the eye). The request replaces what an
 * earlier one left queued (counted in cancelled: a new view made it
 * stale); chunks being read finish. n 0 cancels. Chunks already held are
 * marked wanted: the loader makes room by dropping only chunks the newest
 * request does not want (least recently used first), and stops when the
 * cache is full of wanted ones (counted in load_stopped). A frame needing a
 * chunk being loaded waits for it rather than reading it twice. Returns
 * at once. Errors: VV_ERR_INVALID (a box outside its level), VV_ERR_LIMIT
 * (over 2^24 chunks), VV_ERR_NOMEM.
 */
vv_status vv_pyramid_request(vv_pyramid *p, int n, const int *level, const int *lo, const int *hi);
/** Chunks queued or being read by the loader now (0: idle). */
int vv_pyramid_loading(vv_pyramid *p);
/**
 * Waits up to @p seconds until the loader finishes a chunk or has nothing
 * left to do; returns vv_pyramid_loading's count then.
 */
int vv_pyramid_wait(vv_pyramid *p, double seconds);
/**
 * @p p as a multiresolution source (sys/source.h) for
 * vv_renderer_render_multires: box ranges from the chunks decoded so far.
 * @p p is borrowed: keep it open while @p out is used.
 */
void vv_pyramid_source(vv_pyramid *p, vv_multires_source *out);

#ifdef __cplusplus
}
#endif
#endif
