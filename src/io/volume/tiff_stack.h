/*
 * A TIFF stack's layout, internal to src/io/volume: what the reader of a
 * stack whole (tiff.c) and its out-of-core store (tiff_store.c) share.
 *
 * A stack is the pages of one file (classic or BigTIFF) or one page a file
 * of a folder; tiff_stack_plan reads the first page's description (OME-XML
 * or ImageJ's keys) and says which page holds slice z of a channel at a time
 * step, and where the stack lies in the world. tiff_read_region decodes a
 * box of a page's pixels, only the tiles or strips it touches.
 *
 * Thread-safety: reentrant; a TIFF handle is used by one thread at a time.
 */
#ifndef VV_IO_TIFF_STACK_H
#define VV_IO_TIFF_STACK_H

#include <stdint.h>

#include <tiffio.h>

#include "io/volume/tiff_msg.h"
#include "volvis/io.h"
#include "volvis/sys/source.h"

/* What every page (and every reduced page of one pyramid level) must agree on. */
typedef struct page_fmt {
    uint32_t w, h;
    uint16_t bps, spp, fmt, planar;
    uint16_t photometric; /* PHOTOMETRIC_RGB: samples 0..2 are red, green and blue */
    vv_voxel_type type;
} page_fmt;

/* One page: the file (index into the stack's files) and the page within it. */
typedef struct page_ref {
    int file;
    long page;
} page_ref;

/* Slice z's page is refs[z] for the channel and time step planned. */
typedef struct tiff_stack {
    page_fmt f0;       /* the first page's format */
    int nz, nc, nt;    /* slices, channels, time steps */
    int channel, time; /* the ones planned */
    int sample;        /* the sample of each pixel that holds the channel */
    page_ref *refs;    /* nz pages (owned) */
    double spacing[3]; /* voxel size (1 where unknown) */
    double origin[3];  /* world position of voxel (0, 0, 0) */
    vv_unit unit;      /* VV_UNIT_UNKNOWN without OME or ImageJ metadata */
    double time_step;  /* seconds between time steps (0: unknown) */
    vv_load_info meta; /* the channel's name and colour */
} tiff_stack;

/* @p path opened for reading with our message handlers (NULL: not a TIFF,
 * the reason in @p msg). */
TIFF *tiff_open_file(const char *path, tiff_msg *msg);

/* The files of @p path: itself, or a folder's .tif/.tiff files in natural
 * order (full paths, freed by tiff_free_files); *is_dir says which.
 * Errors: VV_ERR_IO, VV_ERR_FORMAT (no TIFF in the folder), VV_ERR_NOMEM. */
vv_status tiff_files(const char *path, char ***files, int *n, int *is_dir);
void tiff_free_files(char **files, int n);

/* The format of @p t's current page. Errors: VV_ERR_FORMAT, VV_ERR_LIMIT,
 * VV_ERR_UNSUPPORTED (a sample type or compression we do not read). */
vv_status tiff_page_format(TIFF *t, page_fmt *f);

/*
 * Pixels x0 .. x0 + cols - 1, y0 .. y0 + rows - 1 of sample @p sample of
 * @p t's current page (of format @p f, the box inside it) into @p dst
 * (cols x rows voxels, x fastest). Decodes only the tiles or strips the box
 * touches, each checked against its size; *bytes (may be NULL) grows by
 * their stored bytes. Errors: VV_ERR_FORMAT (naming the tile or strip),
 * VV_ERR_NOMEM.
 */
vv_status tiff_read_region(TIFF *t, const page_fmt *f, int sample, uint32_t x0, uint32_t y0,
                           uint32_t cols, uint32_t rows, unsigned char *dst, tiff_msg *msg,
                           uint64_t *bytes);

/*
 * The layout of the stack of @p files[0 .. n_files) for channel @p channel
 * and time step @p time (-1: the first), from the first file's first page;
 * *bad_file names the file an error is about. Errors: VV_ERR_FORMAT,
 * VV_ERR_LIMIT, VV_ERR_INVALID (a channel or time step the stack lacks),
 * VV_ERR_NOMEM. Cleared by tiff_stack_clear.
 */
vv_status tiff_stack_plan(tiff_stack *k, char **files, int n_files, int channel, int time,
                          const char **bad_file);
void tiff_stack_clear(tiff_stack *k);

/*
 * The TIFF row's store (tiff_store.c; the format record's open_store): the
 * stack of @p path for channel @p channel at time step @p time, level 0 the
 * stack and levels 1 .. its OME-TIFF SubIFD levels, reduced in z as read.
 * @p info (may be NULL): the channel's name and colour, channels, time
 * steps, slices. Errors: as tiff_stack_plan, prefixed "tiff: PATH".
 */
vv_status vv_tiff_open_store(vv_store *st, const char *path, int channel, int time,
                             vv_load_info *info);

/* Level @p level (>= 0) of the store of @p path read whole into a new
 * volume *out, as vv_tiff_open_store opens it. Errors: as it, and
 * VV_ERR_INVALID (no such level), VV_ERR_LIMIT, VV_ERR_NOMEM. */
vv_status vv_tiff_read_level(vv_volume **out, const char *path, int channel, int time, int level,
                             vv_load_info *info);

#endif
