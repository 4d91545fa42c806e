/*
 * OME-Zarr (not installed): the reader (zarr_read.c) for the format record
 * in zarr_write.c, and what the pyramid source (zarr_pyramid.c) shares
 * with it: the parsed metadata of one level's array and its chunk reads.
 */
#ifndef VOLVIS_IO_ZARR_H
#define VOLVIS_IO_ZARR_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/io.h"
#include "volvis/sys/format.h"

#define ZR_MAX_DIM 5
/* zr_array.zarr_format of an N5 dataset (n5.c), of a scale of a
 * Neuroglancer precomputed volume (precomputed.c) */
#define ZR_N5 5
#define ZR_PRECOMPUTED 6
#define ZR_JSON_MAX (16u << 20)
#define ZR_CHUNK_MAX ((uint64_t)1 << 30)
/* The most chunks a whole read looks for (each a file to open). */
#define ZR_READ_CHUNKS_MAX (1 << 20)
/* Zarr v3: codecs in one chain, sharding levels (nested shards), inner
 * chunks in one shard (its index: 16 bytes each), index bytes a shard
 * index cache holds. */
#define ZR_MAX_CODECS 8
#define ZR_MAX_NEST 4
#define ZR_SHARD_INNER_MAX (1u << 18)
#define ZR_INDEX_CACHE_BYTES ((uint64_t)8 << 20)
/* zr_store_get: the last @p len bytes; to the end of the object */
#define ZR_SUFFIX UINT64_MAX
#define ZR_ALL UINT64_MAX

typedef struct zr_axis {
    char name[32];
    int kind; /* 0 space, 1 channel, 2 time */
    char unit[32];
} zr_axis;

/* A Zarr v3 codec (zarr.json "codecs"): its kind and configuration. */
enum { ZC_BYTES, ZC_TRANSPOSE, ZC_GZIP, ZC_ZSTD, ZC_BLOSC, ZC_CRC32C, ZC_SHARD };
typedef struct zr_codec {
    int kind;
    int big;               /* bytes: big-endian */
    int order[ZR_MAX_DIM]; /* transpose: encoded axis i is decoded axis order[i] */
} zr_codec;

/* A codec chain in encoding order: array-to-array codecs, one
 * array-to-bytes codec (bytes or sharding_indexed), bytes-to-bytes codecs. */
typedef struct zr_chain {
    int n;
    zr_codec c[ZR_MAX_CODECS];
} zr_chain;

struct zr_index_cache;

/* qsort's order of (offset, length) pairs of 64-bit numbers by their first
 * (shard index ranges, checked for overlaps). */
static inline int
zr_cmp_range(const void *x, const void *y) {
    const uint64_t *a = x, *b = y;
    return a[0] < b[0] ? -1 : a[0] > b[0];
}

/* The little-endian 64-bit number at @p p (shard indexes). */
static inline uint64_t
zr_le64(const unsigned char *p) {
    uint64_t x = 0;
    for (int i = 7; i >= 0; i--)
        x = x << 8 | p[i];
    return x;
}

/* One level's array and what the metadata says of it. */
typedef struct zr_array {
    char dir[4096];
    char real[4096];   /* the store's real path: chunks must resolve beneath it ("": unknown) */
    char root[4096];   /* the store's root: every key is relative to it */
    char prefix[1024]; /* the array's key beneath the root ("" the root itself) */
    int zarr_format;   /* 2 or 3, or ZR_N5 (an N5 dataset: n5.c) */
    /* v3: chunk key encoding "default" (c/0/1/2) or "v2" (0.1.2) */
    int key_default;
    /* v3: sharding levels (0: none); shape[l] the chunk shape at level l
     * (shape[0] the chunk grid's, shape[nshard] the read unit, = chunks),
     * chain[l] its codecs; index_chain, index_start of each sharding level */
    int nshard;
    uint64_t cshape[ZR_MAX_NEST + 1][ZR_MAX_DIM];
    zr_chain chain[ZR_MAX_NEST + 1];
    zr_chain index_chain[ZR_MAX_NEST];
    int index_start[ZR_MAX_NEST];
    int conv64;                   /* v3 int64 (1) or uint64 (2) stored, read as f64 */
    struct zr_index_cache *cache; /* shard indexes (sharded arrays; vv_zr_array_release) */
    int has_window;               /* the omero window of the asked channel */
    double window[2];
    int ndim;
    uint64_t shape[ZR_MAX_DIM], chunks[ZR_MAX_DIM];
    vv_voxel_type type;
    int swap; /* stored in the other byte order */
    size_t esize;
    char codec[16]; /* "" raw, zlib, gzip, zstd, blosc; N5 also bzip2, xz */
    /* N5: the dataset's own resolution and unit (N5 order reversed: the
     * array's axes), applied when the store is that one dataset */
    int n5_has_res;
    double n5_res[ZR_MAX_DIM];
    char n5_unit[32];
    /* precomputed: the scale's voxel_offset (x, y, z): its chunks' names */
    int64_t pc_off[3];
    /* precomputed sharding (neuroglancer_uint64_sharded_v1; pc_shard 0:
     * one file a chunk): murmurhash3_x86_128 or identity, preshift,
     * minishard and shard bits, gzip minishard indexes and data, the
     * compressed Morton code's bits of x, y and z */
    int pc_shard, pc_murmur, pc_preshift, pc_mbits, pc_sbits, pc_index_gzip, pc_data_gzip;
    int pc_zbits[3];
    /* precomputed compressed_segmentation (codec "cseg"): its block size, x, y, z */
    int pc_block[3];
    char sep;
    double fill;
    zr_axis axes[ZR_MAX_DIM];
    double scale[ZR_MAX_DIM], trans[ZR_MAX_DIM];
} zr_array;

/* How one channel at one time step of an array maps onto a volume: the
 * channel and time axes (-1: none), the array axes of the volume's i, j, k
 * (k -1 for a 2-D array), its dims, the chunk strides (elements, C order)
 * and counts per array axis, the chunk's bytes, the chunk box (cdims) and
 * chunk counts (nchunks) along i, j, k. */
typedef struct zr_layout {
    const zr_array *a;
    int cax, tax, vax[3], dims[3];
    uint64_t ch, tp, nc, nt;
    uint64_t cstride[ZR_MAX_DIM], nchunk[ZR_MAX_DIM];
    size_t cbytes;
    int cdims[3], nchunks[3];
} zr_layout;

/* The metadata of level @p level of the store at @p root into @p a (its
 * folder, .zarray, axes, scale and translation), the channel's omero name
 * and colour into @p info (may be NULL), the number of levels into
 * *n_levels (may be NULL; 1 for a plain array). Errors as vv_ome_zarr_read
 * (not prefixed). */
vv_status vv_zr_parse_store(const char *root, int level, zr_array *a, int channel,
                            vv_load_info *info, int *n_levels);

/* The layout of channel @p channel at step @p time (-1: 0) of @p a. Errors:
 * VV_ERR_UNSUPPORTED (axes), VV_ERR_LIMIT, VV_ERR_INVALID (out of range). */
vv_status vv_zr_layout(const zr_array *a, int channel, int time, zr_layout *J);

/* The volume's spacing, origin (the level's scale and translation along
 * i, j, k), unit and modification (original) from @p J's array. */
void vv_zr_geometry(const zr_layout *J, vv_volume *v);

/* The spatial chunk index (C order over the array's spatial axes) of the
 * chunk at position c (along i, j, k). */
uint64_t vv_zr_chunk_linear(const zr_layout *J, const int c[3]);

/* Spatial chunk @p L at the layout's channel and step: read and decoded
 * into @p buf (J->cbytes), its voxels inside the array copied into @p dst,
 * an array of ddims voxels (i fastest) whose voxel (0, 0, 0) is the
 * volume's voxel dorg (it must hold the chunk's part inside the array).
 * *missing (may be NULL) = 1 when the chunk file is absent (the fill
 * value); *file_bytes (may be NULL) = the bytes read from the file;
 * @p range (may be NULL) widened to the voxels copied, each row measured
 * as it is written (vv_range_accumulate: no pass over the volume after).
 * Errors: VV_ERR_IO, VV_ERR_FORMAT, VV_ERR_LIMIT, VV_ERR_NOMEM, naming the
 * chunk's file. Reentrant. */
vv_status vv_zr_copy_chunk(const zr_layout *J, uint64_t L, unsigned char *buf, unsigned char *dst,
                           const int dorg[3], const int ddims[3], int *missing,
                           uint64_t *file_bytes, double *range);

/* Reads and decodes the chunk at grid position @p idx (the read unit's
 * grid: inner chunks of a sharded array) into @p out (exactly @p n bytes);
 * 0 with *missing = 1 when the chunk is absent (no file, an empty inner
 * chunk); *file_bytes (may be NULL) the bytes read (a shard's index and the
 * inner chunk: never the whole shard). Reentrant. */
vv_status vv_zr_read_chunk(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], unsigned char *out,
                           size_t n, int *missing, uint64_t *file_bytes);

/* Decodes the read unit's stored bytes @p src (@p m bytes; an inner chunk
 * of a sharded array) into exactly @p n bytes at @p out: the v2
 * compressor, or the v3 codecs after the array-to-bytes one (transposes
 * undone). @p what names the chunk in errors. Reentrant. */
vv_status vv_zr_decode_unit(const zr_array *a, const uint64_t idx[ZR_MAX_DIM],
                            const unsigned char *src, size_t m, unsigned char *out, size_t n,
                            const char *what);

/* The read unit's grid position (all array axes) of spatial chunk @p L
 * at the layout's channel and step. */
void vv_zr_unit_index(const zr_layout *J, uint64_t L, uint64_t idx[ZR_MAX_DIM]);

/* The decoded read unit at @p idx in @p buf (J->cbytes; @p missing: its
 * contents are overwritten with the fill value) made the host's values in
 * place and its voxels inside the array copied into @p dst as
 * vv_zr_copy_chunk does (dorg, ddims, range alike). */
void vv_zr_place_unit(const zr_layout *J, const uint64_t idx[ZR_MAX_DIM], unsigned char *buf,
                      int missing, unsigned char *dst, const int dorg[3], const int ddims[3],
                      double *range);

/* vv_zr_place_unit in two steps, for a unit that holds several channels
 * placed one after another (decoded once): the unit in @p buf made the
 * host's values in place (the fill value where @p missing), then the
 * layout's channel and step of it copied (as place_unit copies). */
void vv_zr_unit_host(const zr_layout *J, unsigned char *buf, int missing);
void vv_zr_unit_copy(const zr_layout *J, const uint64_t idx[ZR_MAX_DIM], const unsigned char *buf,
                     unsigned char *dst, const int dorg[3], const int ddims[3], double *range);

/* Where one chunk of vv_zr_copy_chunks goes (its voxels inside the
 * array into dst, an array of dims voxels, i fastest, whose voxel 0 is the
 * level's voxel org) and what it was: missing (absent: the fill value),
 * file_bytes (the bytes of its read unit fetched). */
typedef struct zr_dest {
    unsigned char *dst;
    int org[3], dims[3];
    int missing;
    uint64_t file_bytes;
    double range[2]; /* the voxel range of what was copied into dst, widened */
    /* optional (NULL): 1 when nobody wants the chunk any more (a remote
     * read asks before its request and while it is in flight; called as
     * stale(stale_u, stale_i) from the fetching threads); cancelled = 1
     * when it was dropped unread for that (dst untouched, missing,
     * file_bytes and range unset) */
    int (*stale)(void *stale_u, int stale_i);
    void *stale_u;
    int stale_i, cancelled;
} zr_dest;

/* The spatial chunks @p L[0 .. n) (NULL: 0 .. n - 1, in that order) of
 * @p J's array copied as vv_zr_copy_chunk does: all into @p dst (dorg,
 * ddims alike), or, @p each not NULL, chunk i into each[i] (dst, dorg,
 * ddims and @p range unused: each[i].range is widened as it is copied);
 * else @p range (may be NULL) widened. Decoded on @p nthreads
 * threads (each a buffer of J->cbytes; the caller's the first). A store
 * read over the network (a URL) has its reads batched: the shard indexes
 * first (each once), then the chunks' byte ranges (those that follow
 * each other in a shard merged into one request), bs_http_in_flight()
 * requests at once through zr_store_get_many from two fetching threads of
 * their own while the decoding threads decode what came before, in the
 * order of @p L (the caller's: a level-of-detail frame's is coarse levels
 * first, then front to back), the encoded bytes held (in flight and
 * waiting) at most a quarter of the memory budget. A local store is read
 * chunk by chunk on the threads (pread). A chunk whose each[i].stale
 * answers 1 is dropped unread (each[i].cancelled; a remote request of it
 * not sent, or abandoned in flight once no chunk it carries is wanted).
 * Errors: the first failing chunk's (in the order of @p L, per batch), as
 * vv_zr_copy_chunk. */
vv_status vv_zr_copy_chunks(const zr_layout *J, const uint64_t *L, uint64_t n, unsigned char *dst,
                            const int dorg[3], const int ddims[3], zr_dest *each, int nthreads,
                            double *range);

/* Zarr v3 with one sharding level: the byte range in its shard of each of
 * @p n read units at grid positions @p idx (n x ZR_MAX_DIM numbers) into
 * off[i], len[i], missing[i] = 1 when absent (no shard, an empty inner
 * chunk). The shard indexes not cached are read once each, @p window at
 * a time through zr_store_get_many (their bytes at most a quarter of the
 * memory budget), checked, and cached; *file_bytes (may be NULL) grows by
 * their bytes. Errors: as zr3_read_sharded's. */
vv_status zr3_locate_many(const zr_array *a, uint64_t n, const uint64_t *idx, uint64_t *off,
                          uint64_t *len, unsigned char *missing, int window, uint64_t *file_bytes);

/* The bytes one read of a chunk of @p n decoded bytes holds besides the
 * caller's buffer (what is read, the steps of decoding), at most. */
uint64_t vv_zr_read_held(const zr_array *a, size_t n);

/* Frees what vv_zr_parse_store allocated in @p a (the shard index cache);
 * @p a may be NULL or never parsed (zeroed). */
void vv_zr_array_release(zr_array *a);

/* The one byte source under the reader: bytes [off, off + len) of the
 * object @p key (relative to the store's root @p a->root) into a new
 * buffer *out (free it) of *n bytes; off = ZR_SUFFIX: the last len bytes;
 * len = ZR_ALL: to the end. *size (may be NULL) = the object's size. At
 * most @p max bytes are read (VV_ERR_LIMIT beyond). An absent object: VV_OK,
 * *missing = 1 (when @p missing is NULL: VV_ERR_FORMAT "no KEY"). A range
 * past the end: VV_ERR_FORMAT. A local object must resolve beneath a->real;
 * a root that is a URL (http://, https://, s3://) is read over the network
 * (bytesrc.h: the byte source layer; the format never knows which). */
vv_status zr_store_get(const zr_array *a, const char *key, uint64_t off, uint64_t len, uint64_t max,
                       unsigned char **out, size_t *n, uint64_t *size, int *missing);

struct bs_get;
/* zr_store_get of @p n ranges at once (bytesrc.h's bs_get; all in flight
 * together over the network): VV_OK when each is read or missing, else
 * the first failure's status and error. */
vv_status zr_store_get_many(const zr_array *a, struct bs_get *g, int n);

/* The object @p key of the store (beneath a->root, not leading out of
 * a->real) parsed as JSON (a json_t *, a new reference; at most
 * ZR_JSON_MAX bytes); NULL with the error set (naming @p name), or NULL
 * with *s VV_OK when the object is absent and @p optional. */
void *zr_load_json(const zr_array *a, const char *key, const char *name, int optional,
                   vv_status *s);

/* The refusal of a group that is not an image (zarr_meta.c): an HCS
 * plate, a well or a labels group, whose metadata @p attrs (a json_t *,
 * from file @p md) names; the error says which path to open instead.
 * VV_OK (nothing set) when @p attrs names none of them. */
vv_status zr_refuse_group(const char *root, void *attrs, const char *md);

/* Zarr v3 (zarr3.c): the array metadata @p j of zarr.json into @p a;
 * errors name "zarr.json" and the field. */
vv_status zr3_parse_array(zr_array *a, void *j);

/* Zarr v3: decodes the bytes-to-bytes codecs of @p c (in reverse) from
 * @p src (@p m bytes) into exactly @p n bytes at @p out (never more);
 * @p what names the chunk in errors. */
vv_status zr3_decode_bytes(const zr_chain *c, const unsigned char *src, size_t m,
                           unsigned char *out, size_t n, const char *what);

/* Zarr v3: the most bytes a chunk of @p n decoded bytes can take after
 * the codecs of @p c (more is refused before it is read). */
uint64_t zr3_encoded_max(const zr_chain *c, size_t n);

/* Zarr v3: undoes @p c's transposes of a chunk of shape @p shape (decoded
 * axes) and element size @p es in @p buf, through @p tmp (as large). */
void zr3_untranspose(const zr_chain *c, int ndim, const uint64_t *shape, size_t es,
                     unsigned char *buf, unsigned char *tmp);

/* Zarr v3: reads and decodes the sharded chunk at read-unit grid
 * position @p idx (vv_zr_read_chunk's contract). */
vv_status zr3_read_sharded(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], unsigned char *out,
                           size_t n, int *missing, uint64_t *file_bytes);

/* The key (relative to the store's root) of the chunk at grid position
 * @p idx of @p a's top chunk grid (a shard's, when sharded). */
void zr_chunk_key(const zr_array *a, const uint64_t *idx, char *key, size_t cap);

/* N5 (n5.c). The root @p attrs (its attributes.json, a json_t *) of an
 * N5 store read as OME metadata: a dataset (dimensions, dataType): *za
 * NULL, a plain array; a multiscale group (datasets s0 .. sN, their
 * downsamplingFactors or the group's scales; resolution or
 * pixelResolution; axes and units; or the multiscales of a COSEM
 * group): *za a new OME-NGFF multiscales object (a json_t *) in the
 * array's axis order (N5's reversed). Errors name attributes.json. */
vv_status zr_n5_root(const zr_array *a, void *attrs, void **za);
/* N5: the dataset metadata @p j (its attributes.json) into @p a: the
 * axes reversed (N5 lists the fastest first), blockSize as chunks,
 * dataType, compression (raw, gzip, bzip2, xz, zstd, blosc). */
vv_status zr_n5_parse_array(zr_array *a, void *j);
/* N5: the block @p src (@p m bytes: its big-endian header, mode default or
 * varlength, then the compressed voxels) decoded into exactly @p n bytes at
 * @p out, the array's whole chunk in the array's axis order; a block
 * smaller than the chunk (at the array's end) placed at its start, the rest
 * zero. @p what names the block in errors. Reentrant. */
vv_status zr_n5_decode(const zr_array *a, const unsigned char *src, size_t m, unsigned char *out,
                       size_t n, const char *what);
/* A block cut at the array's end (@p cut voxels along each of the array's
 * axes, C order, at @p src) placed at the start of the whole chunk @p out
 * (@p n bytes, a->chunks), the rest zero (N5 and precomputed blocks). */
void zr_place_cut(const zr_array *a, const uint64_t *cut, const unsigned char *src,
                  unsigned char *out, size_t n);
/* N5: the key of the block at grid position @p idx (the array's axes):
 * its indices in N5 order, "/" between. */
void zr_n5_key(const zr_array *a, const uint64_t *idx, char *key, size_t cap);
/* The first bytes of file @p name in folder @p dir (a regular file: a
 * FIFO is not opened) into @p head (at most @p cap - 1 bytes,
 * NUL-terminated); 0 when there is none. The format rows' looks_like
 * tests (zarr_read.c, n5.c, precomputed.c). */
int zr_file_head(const char *dir, const char *name, char *head, size_t cap);
/* A gzip or zlib stream (either header) of @p m bytes at @p src inflated
 * into exactly @p n bytes at @p out; 1 when it decodes to exactly that
 * (N5 gzip blocks, precomputed chunks stored as gzip). Reentrant. */
int zr_gunzip(const unsigned char *src, size_t m, unsigned char *out, size_t n);
/* N5: 1 when @p dir holds an attributes.json of an N5 dataset, multiscale
 * group or container (the format row's looks_like). */
int vv_n5_looks_like(const vv_format_probe *p, int deep);
/* N5: vv_ome_zarr_read's contract for an N5 dataset or multiscale group
 * (errors prefixed "n5: NAME"). */
vv_status vv_n5_read(vv_volume **out, const char *path, const vv_load_options *opt);

/* Neuroglancer precomputed (precomputed.c). The volume's @p info (a
 * json_t *) read as OME metadata: *za a new OME-NGFF multiscales object
 * (axes c, z, y, x; each scale's key as its path, resolution and
 * voxel_offset as scale and translation; "image-label" for a
 * segmentation). Errors name info and the scale. */
vv_status zr_pc_root(const zr_array *a, void *info, void **za);
/* Precomputed: the scale whose key is a->prefix of @p info into @p a
 * (axes c, z, y, x; chunk_sizes[0]; data_type; encoding raw, jpeg or
 * compressed_segmentation; sharding). */
vv_status zr_pc_parse_array(zr_array *a, void *info);
/* Precomputed: the key of the chunk at grid position @p idx (c, z, y, x):
 * "KEY/x0-x1_y0-y1_z0-z1" of voxel_offset-based voxel ranges, or, sharded,
 * its shard's "KEY/<shard in hex>.shard". */
void zr_pc_key(const zr_array *a, const uint64_t *idx, char *key, size_t cap);
/* Precomputed, sharded: the shard number of the chunk at @p idx. */
uint64_t zr_pc_shard_of(const zr_array *a, const uint64_t *idx);
/* Precomputed, sharded: where the chunk at @p idx is: its shard's key
 * (zr_pc_key), bytes [*off, *off + *len) of it, or *missing = 1 (no shard,
 * no such chunk in its minishard). The shard index and the minishard index
 * are read by byte ranges and kept in a->cache; *file_bytes (may be NULL)
 * gets the index bytes read. Errors (VV_ERR_FORMAT naming the shard and
 * the field): indexes out of order, overlapping, past 2^62 or of a size
 * not a multiple of their entries; VV_ERR_IO. Thread-safe. */
vv_status zr_pc_locate(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], uint64_t *off,
                       uint64_t *len, int *missing, uint64_t *file_bytes);
/* Precomputed, sharded: zr_pc_locate of @p n chunks (@p idx: ZR_MAX_DIM
 * numbers each) into off, len and missing (1 absent), the shard indexes
 * and then the minishard indexes not kept read together, a window of
 * bs_http_in_flight() requests at a time. Errors: zr_pc_locate's. */
vv_status zr_pc_locate_many(const zr_array *a, uint64_t n, const uint64_t *idx, uint64_t *off,
                            uint64_t *len, unsigned char *missing);
/* Precomputed, sharded: vv_zr_read_chunk's contract. */
vv_status zr_pc_read_sharded(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], unsigned char *out,
                             size_t n, int *missing, uint64_t *file_bytes);
/* Precomputed: the chunk at @p idx from its @p m stored bytes (raw, a
 * gzip stream of raw, jpeg or compressed_segmentation; gzip first when the
 * scale's sharding says so) into exactly @p n bytes at @p out, the
 * whole chunk (a chunk cut at the scale's end placed at its start, the
 * rest zero). Reentrant. */
vv_status zr_pc_decode(const zr_array *a, const uint64_t idx[ZR_MAX_DIM], const unsigned char *src,
                       size_t m, unsigned char *out, size_t n, const char *what);
/* Precomputed: 1 when folder @p p holds an info naming a multiscale volume. */
int vv_pc_looks_like(const vv_format_probe *p, int deep);
/* Precomputed: vv_ome_zarr_read's contract (errors prefixed
 * "precomputed: NAME"). */
vv_status vv_pc_read(vv_volume **out, const char *path, const vv_load_options *opt);

/* Frees @p a's shard index cache (zarr3.c). */
void zr3_cache_free(zr_array *a);
/* The shard index cache (zarr3.c; a->cache): up to 64 indexes, LRU, at
 * most ZR_INDEX_CACHE_BYTES, thread-safe. An index (@p level, @p id) is
 * @p count entries of @p w numbers (@p ent taken). _find: entry @p p of a
 * w = 2 index into o[2], 1 when cached. _search: the entry of a w = 3
 * index (sorted by its first number) whose first number is @p key, its
 * other two into o[2]: 1 found, -1 cached but absent, 0 not cached. */
struct zr_index_cache *zr_index_cache_new(void);
int zr_index_cache_find(struct zr_index_cache *c, int level, uint64_t id, uint64_t p, uint64_t o[2],
                        uint64_t *size);
int zr_index_cache_search(struct zr_index_cache *c, int level, uint64_t id, uint64_t key,
                          uint64_t o[2]);
void zr_index_cache_put(struct zr_index_cache *c, int level, uint64_t id, uint64_t *ent,
                        uint64_t count, uint64_t size, unsigned w);

/* @p n voxels of type @p t at @p dst set to @p x (the fill value, cast). */
void vv_zr_fill(void *dst, size_t n, vv_voxel_type t, double x);

/**
 * Reads channel opt->channel at step opt->time of level opt->level of the OME-Zarr
 * store (or plain Zarr v2 array) at folder @p path, with vv_volume_load's
 * contract; opt->info gets the channel and time counts, the omero name and
 * colour and the time between steps. Errors (prefixed "zarr: NAME"):
 * VV_ERR_FORMAT (malformed metadata, a chunk that does not decode to its
 * size), VV_ERR_UNSUPPORTED (dtype, compressor, filters, F order, axes),
 * VV_ERR_LIMIT, VV_ERR_INVALID (a channel or step out of range), VV_ERR_IO,
 * VV_ERR_NOMEM. Reentrant.
 */
vv_status vv_ome_zarr_read(vv_volume **out, const char *path, const vv_load_options *opt);

/** A folder holding a .zarray, or a .zattrs with "multiscales", or a Zarr v3
 * zarr.json of an array or of a group with "multiscales" (deep 0 only). */
int vv_ome_zarr_looks_like(const vv_format_probe *p, int deep);

#endif
