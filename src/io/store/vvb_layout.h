/*
 * The .vvb file (docs/file-formats.md) and its reading (vvb_read.c),
 * internal to src/io: the layout, the geometry of bricks, levels and
 * chunks, and a file read by bricks with pread (vvb_file): a .vvb's
 * header, index and levels, or a raw layout's data file. What the bricked
 * reader (bricked.c), the .vvb writer (vvb_write.c) and the .vvb's pyramid
 * store and format row (vvb.c) stand on; it knows no bricked volume
 * (src/io/store/bricked.h), which holds a vvb_file and its bricks in the cache.
 *
 * Layout, little-endian: a 256-byte header ("VOLVISB1", header size, brick
 * side in cells, dims, voxel type, coarse flag, unit, space, spacing,
 * origin, direction, value range, index offset, brick count), then the
 * index, 48 bytes a brick (i fastest): data offset and size, min and max
 * (float64), coarse level offset and size; then the bricks, each the voxels
 * of its box with one ghost voxel beyond each face (clipped to the volume),
 * i fastest, and its coarse level (every 4th voxel of its cells, from lo).
 * With codec 1 (header offset 200) every brick's voxels are one zstd frame,
 * decoded in-process (libzstd, into a buffer of the box's size, checked
 * before and after), and every brick has its coarse level, uncompressed.
 * Pyramid levels (VV_VVB_LEVELS; header offsets 204 and 208: their count
 * and the level table's offset): each level halves the one before (the
 * OME-Zarr writer's levels, vv_pyr_reduce), cut into chunks of 64^3 voxels
 * stored like the bricks (raw or one zstd frame each), each level followed
 * by its index (32 bytes a chunk: offset, size, min, max), then the table
 * (32 bytes a level above 0: dims, chunk side, index offset, chunk count).
 *
 * Thread-safety: the geometry functions are pure; vvb_pread,
 * vvb_read_piece and vvb_read_level_box only pread (any thread, uncounted);
 * vvb_read_at and vvb_read_brick count the bytes read atomically.
 */
#ifndef VV_IO_VVB_LAYOUT_H
#define VV_IO_VVB_LAYOUT_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "io/store/pyramid.h"

#define VVB_MAGIC "VOLVISB1"
#define VVB_HEADER 256
#define VVB_RECORD 48
#define VVB_COARSE 4 /* coarse level: every 4th voxel */
#define VVB_CODEC_ZSTD 1
#define VVB_CHUNK 64        /* a pyramid level's chunk side, voxels */
#define VVB_LEVEL_RECORD 32 /* the level table: dims, chunk side, index offset, count */
#define VVB_CHUNK_RECORD 32 /* a level's index: offset, size, min, max */

/* A chunk of a pyramid level (levels 1 and up; level 0 is the bricks). */
typedef struct vvb_chunk {
    uint64_t offset, bytes;
    double vmin, vmax;
} vvb_chunk;

typedef struct vvb_level {
    int dims[3], nc[3]; /* voxels, chunks along each axis */
    int n;              /* chunks */
    vvb_chunk *c;       /* i fastest */
} vvb_level;

/* A brick's record in the index (a raw layout: its min/max only). */
typedef struct vvb_brick {
    uint64_t offset, bytes;               /* .vvb: the brick's voxels in the file */
    uint64_t coarse_offset, coarse_bytes; /* .vvb: its coarse level (0 bytes: none) */
    double vmin, vmax;
} vvb_brick;

/* A volume's file read by bricks with pread: a .vvb (vvb_open_file: its
 * header, index and levels), or the data file of a raw layout (the bricked
 * reader sets its header, grid and the bricks' min/max; no offsets). */
typedef struct vvb_file {
    char *data_path; /* the file holding the voxels */
    int fd;
    uint64_t file_size;                  /* of data_path */
    int swap;                            /* voxels need byte swapping */
    vv_volume *header;                   /* one voxel, the geometry and range; dims the volume's */
    int nb[3];                           /* bricks along each axis */
    int n;                               /* bricks */
    vvb_brick *e;                        /* the index, i fastest */
    int has_coarse;                      /* .vvb: every brick has its coarse level */
    int zstd;                            /* .vvb: bricks and chunks are zstd frames */
    int n_levels;                        /* .vvb: pyramid levels, level 0 (the bricks) included */
    vvb_level lv[VV_PYRAMID_MAX_LEVELS]; /* lv[1 .. n_levels - 1] */
    uint64_t bytes_read;                 /* counted by vvb_read_at and vvb_read_brick */
} vvb_file;

/* ---- little-endian fields ------------------------------------------------ */

static inline void
vvb_put_u32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static inline void
vvb_put_u64(unsigned char *p, uint64_t v) {
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static inline void
vvb_put_f64(unsigned char *p, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    vvb_put_u64(p, v);
}
static inline uint32_t
vvb_get_u32(const unsigned char *p) {
    uint32_t v = 0;
    for (int i = 0; i < 4; i++)
        v |= (uint32_t)p[i] << (8 * i);
    return v;
}
static inline uint64_t
vvb_get_u64(const unsigned char *p) {
    uint64_t v = 0;
    for (int i = 0; i < 8; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}
static inline double
vvb_get_f64(const unsigned char *p) {
    uint64_t v = vvb_get_u64(p);
    double d;
    memcpy(&d, &v, 8);
    return d;
}

/* ---- geometry ------------------------------------------------------------- */

static inline uint64_t
vvb_box_voxels(const int lo[3], const int hi[3]) {
    return (uint64_t)(hi[0] - lo[0] + 1) * (uint64_t)(hi[1] - lo[1] + 1) *
           (uint64_t)(hi[2] - lo[2] + 1);
}

/* Coarse level of a brick: every VVB_COARSE-th voxel from lo to hi. */
static inline void
vvb_coarse_dims(const vv_brick_info *in, int cd[3]) {
    for (int a = 0; a < 3; a++)
        cd[a] = (in->hi[a] - in->lo[a]) / VVB_COARSE + 1;
}

/* Brick @p index's boxes (its cells lo .. hi, its stored box slo .. shi
 * with the ghosts) in a volume of @p dims voxels cut into @p nb bricks. */
void vvb_brick_boxes(const int dims[3], const int nb[3], int index, vv_brick_info *in);
/* The brick grid of a volume of @p dims voxels into @p nb and *@p n_out;
 * VV_ERR_LIMIT over 2^26 bricks. */
vv_status vvb_brick_grid(const int dims[3], int nb[3], int *n_out);
/* The dims of each level of a volume of @p d voxels (the halving rule);
 * returns the count. */
int vvb_level_dims(const int d[3], int dims[VV_PYRAMID_MAX_LEVELS][3]);
/* Level @p L's geometry (levels >= 1) from its dims, with its chunk grid. */
void vvb_level_grid(vvb_level *L, const int dims[3]);
/* Chunk @p i of level @p L: its first voxel and voxel counts. */
void vvb_chunk_box(const vvb_level *L, int i, int org[3], int n[3]);
/* The bytes of the largest piece of a level: what vvb_read_level_box's
 * @p piece holds. */
uint64_t vvb_piece_bytes(const vvb_file *f);
/* Reverses the bytes of each of @p count values of @p vs bytes. */
void vvb_swap_bytes(void *data, size_t count, size_t vs);

/* ---- reading ---------------------------------------------------------------- */

/* Opens @p path as f's data file (f->fd) and notes its size. */
vv_status vvb_open_data(vvb_file *f, const char *path);
/* f's header, index and pyramid levels (f->data_path opened; f->swap set:
 * the file is little-endian), every piece checked against the file's size. Errors: VV_ERR_FORMAT,
 * VV_ERR_IO, VV_ERR_LIMIT, VV_ERR_NOMEM. */
vv_status vvb_open_file(vvb_file *f);
/* Releases what @p f holds (not @p f itself). */
void vvb_file_close(vvb_file *f);
/* pread of exactly @p n bytes at @p off of f's data file; @p what names
 * the piece in messages. Uncounted: any thread. */
vv_status vvb_pread(const vvb_file *f, void *buf, size_t n, uint64_t off, const char *what);
/* vvb_pread, counted (f->bytes_read). */
vv_status vvb_read_at(vvb_file *f, void *buf, size_t n, uint64_t off, const char *what);
/* The @p bytes at @p off of a .vvb, a piece of @p want bytes, into @p dst
 * (as stored: little-endian), decoding zstd. Uncounted: any thread. */
vv_status vvb_read_piece(const vvb_file *f, uint64_t off, uint64_t bytes, void *dst, uint64_t want,
                         const char *what);
/* Brick @p index of a .vvb, its stored box of @p want bytes, into @p dst
 * (as stored), counted. */
vv_status vvb_read_brick(vvb_file *f, int index, void *dst, uint64_t want, const char *what);
/* Voxels lo .. lo + n - 1 of level @p level into @p dst (x fastest, host
 * byte order); *bytes adds the bytes read. Uncounted: any thread. */
vv_status vvb_read_level_box(const vvb_file *f, int level, const int lo[3], const int n[3],
                             unsigned char *dst, unsigned char *piece, uint64_t *bytes);

/* A reader of the .vvb being written on @p fd (the writer's levels read
 * back the level before): level 0's @p n bricks where the records of
 * @p index say, of a volume @p hdr cut into @p nb bricks, raw or zstd
 * (@p zstd); @p fd, @p path (in messages) and @p hdr are borrowed.
 * Errors: VV_ERR_NOMEM. */
vv_status vvb_readback_new(vvb_file **out, int fd, const char *path, const vv_volume *hdr,
                           const int nb[3], int n, int zstd, const unsigned char *index);
/* Level @p l of reader @p rd, its geometry from @p dims and its chunk
 * table allocated for the writer to fill as it writes them; NULL when out
 * of memory. */
vvb_level *vvb_readback_level(vvb_file *rd, int l, const int dims[3]);
/* Frees a reader of vvb_readback_new (its borrowed file left open). Accepts NULL. */
void vvb_readback_free(vvb_file *rd);

#endif
