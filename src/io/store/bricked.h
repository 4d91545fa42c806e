/*
 * Bricked volumes read on demand (src/io/store/bricked.c), internal to src/io: a
 * volume larger than memory cut into bricks of VV_BRICK_CELLS^3 cells with
 * a one-voxel ghost border, read on demand into the process's cache
 * (src/core/cache.h), served as a source of kind VV_SOURCE_BRICKS
 * (vv_bricked_source_new) through which any renderer with the region
 * contract renders it brick by brick in front-to-back order (the region
 * driver, src/render/drivers.h). Sources: the bricked format .vvb of our
 * own (docs/file-formats.md: a header, an index with each brick's offset,
 * size and min/max, each brick's voxels with their ghosts in one piece, and
 * optional coarse levels per brick), raw files and NRRD files with raw
 * encoding, all read with pread: a brick costs one read in a .vvb and one
 * read a row of voxels otherwise. Opening a raw or NRRD file streams it
 * once, a slice at a time, for the value range and the bricks' min/max (a
 * .vvb has them in its index).
 *
 * Thread-safety: vv_bricked_load and vv_bricked_read_box may run on
 * several threads at once (the cache's lock guards the bricks held).
 */
#ifndef VV_IO_BRICKED_H
#define VV_IO_BRICKED_H

#include <stdint.h>

#include "volvis/bricks.h"
#include "volvis/io.h"
#include "volvis/source.h"
#include "volvis/sys/source.h"

typedef struct vv_bricked vv_bricked;

/** What a bricked volume did since it was opened. */
typedef struct vv_bricked_stats {
    uint64_t loads;      /**< bricks read from the file */
    uint64_t hits;       /**< bricks found in the cache */
    uint64_t evictions;  /**< bricks dropped to stay within the budget */
    uint64_t skipped;    /**< bricks not read because their min/max is transparent */
    uint64_t bytes_read; /**< bytes read by pread, header, index and scans included */
    uint64_t peak_bytes; /**< the most bytes of its bricks the cache held at once */
    uint64_t held_bytes; /**< bytes of its bricks in the cache now */
    int max_loads;       /**< the most times one brick was read */
} vv_bricked_stats;

/**
 * Opens @p path as a bricked volume: a .vvb file; a raw file when @p raw is
 * not NULL; else an uncompressed (raw-encoded) NRRD file, attached or
 * detached. Its bricks are held in @p cache (NULL: the process's), whose
 * budget bounds them with every other source's pieces; the working set of
 * the brick being rendered is reserved there. Errors:
 * VV_ERR_IO, VV_ERR_FORMAT (bad header or index: a brick past the end of
 * the file, a size that does not match its box (zstd bricks: 0 or more
 * than the bound of its box), an unknown brick codec; a compressed NRRD,
 * which must be converted first), VV_ERR_LIMIT (a memory limit smaller than one
 * brick and its working set), VV_ERR_NOMEM.
 */
vv_status vv_bricked_open(vv_bricked **out, const char *path, const vv_raw_params *raw,
                          vv_cache *cache);
/**
 * Opens the voxels lying raw in @p data_path at @p offset (byte order
 * @p big_endian), of the geometry @p header gives (a one-voxel volume whose
 * dims are the file's; @p header and @p data_path are taken, freed on error
 * too) as a bricked volume named @p path in @p cache; @p scan 0: without
 * the pass for the range (vv_bricked_open_header). What vv_open does with a
 * row's raw_layout (NRRD, raw). Errors: as vv_bricked_open.
 */
vv_status vv_bricked_open_layout(vv_bricked **out, const char *path, vv_volume *header,
                                 char *data_path, uint64_t offset, int big_endian, vv_cache *cache,
                                 int scan);

/** The raw row's raw_layout: the layout @p raw describes of @p path. Errors: VV_ERR_LIMIT,
 *  VV_ERR_NOMEM. */
vv_status vv_raw_layout(const char *path, const vv_raw_params *raw, vv_volume **header,
                        char **data_path, uint64_t *offset, int *big_endian);

/**
 * Opens like vv_bricked_open without the streaming pass over a raw or NRRD
 * file: the header only (a .vvb: header and index, as vv_bricked_open). The
 * value range (vv_bricked_header) and the bricks' min/max are then unknown
 * (0 and never skipped) until the caller sets the range; for reading boxes
 * (vv_bricked_read_box) by the ranks of a distributed render, which learn
 * the range from their own boxes. Errors: as vv_bricked_open.
 */
vv_status vv_bricked_open_header(vv_bricked **out, const char *path, const vv_raw_params *raw,
                                 vv_cache *cache);

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

/** The path it was opened from (borrowed). */
const char *vv_bricked_path(const vv_bricked *b);
/** The cache holding its bricks (borrowed). */
vv_cache *vv_bricked_cache(const vv_bricked *b);

/** Closes the file and drops its bricks from the cache. Accepts NULL. */
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
 * @p b as a volume source (sys/source.h) for the region driver (drv_render_bricks):
 * header, grid, info, load and note_skip call the functions above. @p b
 * is borrowed: keep it open while @p out is used.
 */
void vv_bricked_source(vv_bricked *b, vv_brick_source *out);

/* ---- for the .vvb's writer and row (vvb_write.c, vvb.c) ---------------------------- */

/* The voxels of box in->slo .. in->shi into @p dst (host byte order,
 * counted): brick @p index's stored box of a .vvb, or of a raw layout the
 * box (index -1: any box) a pread a row. */
vv_status vvb_read_stored(vv_bricked *b, int index, const vv_brick_info *in, void *dst);
/* 1 when @p b was opened from a .vvb (its bricks stored whole), 0 for a raw layout. */
int vvb_is_vvb(const vv_bricked *b);
/* A .vvb file by its bricks, in @p cache (the .vvb row's open_bricks). */
vv_status vvb_open_bricked(vv_bricked **out, const char *path, vv_cache *cache);

/**
 * Writes @p src (a bricked volume opened from any source) as a .vvb file at
 * @p path (src/io/write/vvb_write.c), written to a temporary file beside it and
 * renamed; @p flags VV_VVB_COARSE, VV_VVB_ZSTD (0: raw bricks, no coarse
 * levels). Reads one brick at a time: memory is bounded by a brick, not the
 * volume.
 * Errors: VV_ERR_IO, VV_ERR_NOMEM.
 */
vv_status vv_bricked_write_vvb(vv_bricked *src, const char *path, unsigned flags,
                               const vv_progress *progress);

/**
 * @p b (taken: closed by the source) as a source of kind VV_SOURCE_BRICKS
 * named @p format ("vvb", "nrrd", "raw"). Errors: VV_ERR_NOMEM (@p b closed).
 */
vv_status vv_bricked_source_new(vv_source **out, vv_bricked *b, const char *format);

#endif
