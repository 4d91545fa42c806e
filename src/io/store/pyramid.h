/*
 * A pyramid's store: the format's side of vv_pyramid (src/io/store/pyramid.c;
 * include/volvis/bricks.h). The cache, the frame's plan, the statistics and
 * the source interface are the pyramid's; a store only says what its
 * levels are and fetches one chunk's voxels. Two formats have one:
 * OME-Zarr (src/io/store/zarr_pyramid.c) and the HDF5 pyramids of BigDataViewer
 * and Imaris (src/io/store/hdf5_pyramid.c). Either is opened in long-lived
 * sandboxed readers, two a thread, behind a store that forwards each
 * chunk and fetches the plan's next ones ahead (vv_sandbox_open_store,
 * src/sandbox/store.c), or in this process with VOLVIS_SANDBOX=0. A remote store (HTTP) would be a
 * third format: a chunk fetcher behind read_chunk.
 */
#ifndef VOLVIS_IO_PYRAMID_H
#define VOLVIS_IO_PYRAMID_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/bricks.h"
#include "volvis/io.h"
#include "volvis/source.h"
#include "volvis/sys/source.h"

/* ---- multiresolution pyramids (OME-Zarr, BigDataViewer / Imaris HDF5, .vvb) --------- */

#define VV_PYRAMID_MAX_LEVELS VV_SOURCE_MAX_LEVELS /**< levels read from one store */

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
    uint64_t cancelled_in_flight; /**< chunks being fetched (a remote store's) that a newer
                                       request dropped: their requests not sent or abandoned */
    uint64_t load_stopped;        /**< queued chunks left when the cache was full of wanted ones */
    uint64_t load_errors; /**< the loader's failed reads (a frame reading them reports why) */
    int loading;          /**< chunks queued or being read now */
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
 * Its chunks are held in @p cache (NULL: the process's), whose budget bounds
 * them with every other source's pieces; the working set of the boxes
 * being rendered is reserved there. @p info (may be NULL) gets the
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
                          vv_cache *cache, vv_load_info *info);
/**
 * vv_pyramid_open of channels @p channels[0 .. n) (n 1 ..
 * VV_STORE_MAX_CHANNELS, each of the file's, in the order given) at once:
 * each chunk of the pyramid holds them all (read together, cached and
 * counted together; an OME-Zarr chunk holding several of them decoded
 * once), channel k's value range the omero window's of channels[k], else
 * the coarsest level's of that channel. @p info[k] (may be NULL; n
 * entries) gets channel k's name and colour (info[0] the counts). A format
 * whose store holds one channel has its stores stacked (vv_store_stack).
 * Errors: as vv_pyramid_open; VV_ERR_INVALID (n out of range, a channel
 * the file does not have); VV_ERR_FORMAT (a channel axis chunked
 * differently at two levels).
 */
vv_status vv_pyramid_open_channels(vv_pyramid **out, const char *path, int n, const int *channels,
                                   int time, vv_cache *cache, vv_load_info *info);
void vv_pyramid_free(vv_pyramid *p);
/** The channels each chunk holds (>= 1). */
int vv_pyramid_channels(const vv_pyramid *p);
/** vv_pyramid_level with channel @p channel's value range (borrowed); NULL out of range. */
const vv_volume *vv_pyramid_channel_level(const vv_pyramid *p, int channel, int level);
/** vv_pyramid_read_box of channel @p channel (its value range). */
vv_status vv_pyramid_channel_read_box(vv_pyramid *p, int channel, int level, const int lo[3],
                                      const int hi[3], vv_volume **out);
/** vv_pyramid_proxy of channel @p channel. */
vv_status vv_pyramid_channel_proxy(vv_pyramid *p, int channel, int level, vv_volume **out);
/** The path it was opened from (borrowed). */
const char *vv_pyramid_path(const vv_pyramid *p);
/** The cache holding its chunks (borrowed). */
vv_cache *vv_pyramid_cache(const vv_pyramid *p);
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
 * default transfer function, the level-of-detail driver (drv_render_multires) takes the
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
 * the level-of-detail driver's progressive frames ask for coarse levels
 * first, then the nodes nearest the eye). The request replaces what an
 * earlier one left queued (counted in cancelled: a new view made it
 * stale); chunks being read finish, except a remote store's whose fetch
 * is in flight: those the new request does not ask for and no frame waits
 * on are dropped, their requests abandoned (counted in
 * cancelled_in_flight; within about 50 ms). n 0 cancels. Chunks already held are
 * marked wanted: the loader makes room by dropping only chunks the newest
 * request does not want (least recently used first), and stops when the
 * cache is full of wanted ones (counted in load_stopped). A frame needing a
 * chunk being loaded waits for it rather than reading it twice. Returns
 * at once. Errors: VV_ERR_INVALID (a box outside its level), VV_ERR_LIMIT
 * (over 2^24 chunks), VV_ERR_NOMEM.
 */
vv_status vv_pyramid_request(vv_pyramid *p, int n, const int *level, const int *lo, const int *hi);
/**
 * vv_pyramid_request of the boxes that @p like read in its last frame (its
 * plan's, or its newest request's): @p p is another time step of the store
 * @p like reads, drawn by the same view. Errors: VV_ERR_UNSUPPORTED (other
 * levels), those of vv_pyramid_request.
 */
vv_status vv_pyramid_request_like(vv_pyramid *p, vv_pyramid *like);
/** Chunks queued or being read by the loader now (0: idle). */
int vv_pyramid_loading(vv_pyramid *p);
/**
 * Waits up to @p seconds until the loader finishes a chunk or has nothing
 * left to do; returns vv_pyramid_loading's count then.
 */
int vv_pyramid_wait(vv_pyramid *p, double seconds);
/**
 * @p p as a multiresolution source (sys/source.h) for
 * the level-of-detail driver: box ranges from the chunks decoded so far.
 * @p p is borrowed: keep it open while @p out is used.
 */
void vv_pyramid_source(vv_pyramid *p, vv_multires_source *out);

/**
 * @p p (taken: closed by the source) as a source of kind VV_SOURCE_PYRAMID
 * named @p format ("zarr", "hdf5", "vvb"). Errors: VV_ERR_NOMEM (@p p closed).
 */
vv_status vv_pyramid_source_new(vv_source **out, vv_pyramid *p, const char *format);

/**
 * A pyramid over store @p st, taken whole (closed and its headers freed on
 * error too), its chunks in @p cache (NULL: the process's);
 * @p path names it in errors; *info (may be NULL) gets the channel, time
 * step and level counts. Errors as vv_pyramid_open.
 */
vv_status vv_pyramid_open_store(vv_pyramid **out, vv_store *st, const char *path, vv_cache *cache,
                                vv_load_info *info);

/** The OME-Zarr store of @p path (channel, time step, level 0's info). */
vv_status vv_zr_pyramid_store(vv_store *st, const char *path, int channel, int time,
                              vv_load_info *info);
/**
 * The OME-Zarr store of @p path for channels @p channels[0 .. n) at step
 * @p time: a read fills every channel (vv_store.n_ch = n; a chunk holding
 * several of them decoded once); @p info[k] (may be NULL) channel k's
 * name, colour and counts. Errors: as vv_zr_pyramid_store; VV_ERR_FORMAT
 * when the channel axis is chunked differently at two levels.
 */
vv_status vv_zr_pyramid_store_channels(vv_store *st, const char *path, int n, const int *channels,
                                       int time, vv_load_info *info);

/** Voxel @p i of @p d (of type @p t) as a double. */
double vv_pyr_voxel(const void *d, vv_voxel_type t, size_t i);

/** A box of a pyramid's next level and the voxels under it (vv_pyr_reduce). */
typedef struct vv_pyr_reduce_box {
    const void *src;    /**< the level before's voxels src_lo .. src_lo + src_n - 1, x fastest */
    vv_voxel_type type; /**< of both levels */
    int src_dims[3];    /**< the level before's dims (blocks at its edges are cut) */
    int src_lo[3], src_n[3];
    int step[3];     /**< 2 on halved axes, 1 on axes of one voxel */
    int label;       /**< 1: the first voxel of a block instead of the mean (labels) */
    int lo[3], n[3]; /**< the box, in voxels of the next level */
    int dst_dims[2]; /**< dst's row length and rows a slice (dst holds voxel lo at 0) */
} vv_pyr_reduce_box;

/**
 * The box @p b of a pyramid's next level into @p dst: each voxel the mean
 * of the step[0] x step[1] x step[2] voxels under it that lie inside the
 * level before (summed in z, y, x order as doubles; integer types rounded to
 * nearest), or with label the first of them. What the OME-Zarr and .vvb
 * writers store, voxel for voxel the same. Thread-safe.
 */
void vv_pyr_reduce(const vv_pyr_reduce_box *b, void *dst);

/**
 * 0 when @p path is no .vvb file (its magic), else the pyramid levels its
 * header gives (1: the bricks only). Unchecked beyond that: a probe.
 */
int vv_vvb_probe(const char *path);

/**
 * The store of the .vvb file @p path (src/io/store/vvb.c), read in this
 * process: level 0 from its bricks, a chunk of 64^3 voxels from the brick
 * holding it, the levels above from their chunks. Channel and time step
 * must be 0 or -1. Errors: those of opening a .vvb (VV_ERR_FORMAT,
 * VV_ERR_IO, VV_ERR_LIMIT, VV_ERR_NOMEM), VV_ERR_INVALID.
 */
vv_status vv_vvb_pyramid_store(vv_store *st, const char *path, int channel, int time);

/**
 * The store of BigDataViewer HDF5 file @p path's setup @p setup at time
 * point @p timepoint, both ids as a dataset XML names them (t%05d/s%02d;
 * not counted from s00, t00000): one channel and step; level geometry in
 * the setup's voxels (a level's spacing its factors, its voxel 0 at (f -
 * 1) / 2 of level 0's), for the XML to place. Errors: as
 * vv_h5_pyramid_store, VV_ERR_FORMAT (no such setup or time point).
 */
vv_status vv_h5_bdv_store(vv_store *st, const char *path, int setup, int timepoint);

/**
 * The store of BigDataViewer N5 container @p path's setup @p setup at
 * timepoint @p timepoint (ids as a dataset XML names them: the group
 * setup<S>/timepoint<T>, a multiscale group s0 .. sN), level geometry as
 * vv_h5_bdv_store gives it (the group's own resolution divided out), for the
 * XML to place. Errors: as vv_zr_pyramid_store, VV_ERR_FORMAT (no such
 * group).
 */
vv_status vv_n5_bdv_store(vv_store *st, const char *path, int setup, int timepoint);

/**
 * Every chunk of level @p level of @p st read into a new volume (the
 * level's geometry, its range computed): what a format row with a store
 * reads whole. Errors: VV_ERR_INVALID (no such level), VV_ERR_NOMEM,
 * those of read_chunk.
 */
vv_status vv_store_read_level(vv_store *st, int level, vv_volume **out);

/** The store of a BigDataViewer HDF5 or Imaris file @p path, read in this process. */
vv_status vv_h5_pyramid_store(vv_store *st, const char *path, int channel, int time);

/* The XML document at @p path parsed by libxml2 without the network and
 * without a document type: a <!DOCTYPE> (where entities, external ones
 * included, and DTDs would be declared) stops the parser before its
 * internal subset, *doctype = 1 and NULL. NULL with *doctype 0: not
 * well-formed. BigDataViewer's dataset XML and an HDF5 file's companion. */
struct _xmlDoc *vv_bdv_xml_read(const char *path, int *doctype);

/* @p s prefixed with "NAME: FILE" (@p name a format's, @p path its
 * file) unless its message starts so already: a store's reader, in the
 * sandbox or here, names the file itself. */
vv_status vv_pyramid_prefix(vv_status s, const char *name, const char *path);

#endif
