/*
 * A pyramid's state (struct vv_pyramid, src/io/store/pyramid.h), internal to the
 * three files of the pyramid, each calling only the ones before it:
 * pyramid.c (levels, chunks in the cache, boxes assembled from them,
 * statistics), pyramid_load.c (the frame's plan, the loader threads and
 * the multiresolution source) and pyramid_open.c (opening, freeing). Its
 * chunks live in the process's cache (src/core/cache.h) as entries of its
 * client there; the cache's lock (p->lock) guards its index of them, the
 * plan, the queue and the statistics, so that another source evicting one
 * of its chunks needs no lock of its own. Reading and decoding run outside
 * it. Every function here expects the lock held unless it says otherwise.
 */
#ifndef VV_IO_PYRAMID_INTERNAL_H
#define VV_IO_PYRAMID_INTERNAL_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#include "core/cache.h"
#include "io/store/pyramid.h"

#define PY_BUCKETS 4096u
#define PY_LOADERS_MAX 64

/* A cache entry's state: its voxels decoded, or being decoded by the
 * frame's thread or a loader (its bytes reserved, pinned), or a loader's
 * decode failed (no voxels; whoever needs it next decodes it again). */
enum { PY_READY, PY_NEW, PY_LOADING, PY_FAILED };
/* A chunk's uses in the frame's plan: the boxes (their order) needing it. */
typedef struct py_use {
    int level;
    uint64_t L;
    int *seq, n, cap, pos;
    struct py_use *hnext;
} py_use;

/* A chunk in the cache: its entry there (ce: first, so that the cache's
 * entry is the chunk) holds its pins (boxes being assembled from it, and
 * its loader while loading) and the request that last asked for it (the
 * loader keeps those). */
typedef struct py_chunk {
    vv_cache_entry ce;
    int level;
    uint64_t L;
    py_use *use;      /* its uses in the plan, or NULL */
    int org[3], n[3]; /* the block's first voxel in the level, its size */
    /* the chunk's voxels inside the array: n[0] x n[1] x n[2] of each
     * channel, the channels one after another along z (py_alloc_block) */
    vv_volume *blk;
    float rng[VV_STORE_MAX_CHANNELS][2]; /* each channel's least and greatest voxel, once read */
    uint64_t bytes;
    int state; /* PY_READY, ... */
    struct py_chunk *hnext;
} py_chunk;

/* A chunk a request asked the loader for. */
typedef struct py_req {
    int level;
    uint64_t L;
} py_req;

typedef struct py_level {
    int dims[3], cdims[3], nchunks[3];
    vv_voxel_type type;
    size_t esize;   /* bytes a voxel of one channel */
    vv_volume *hdr; /* geometry only: 1-voxel data, dims set to the level's */
    /* channels 1 .. n_ch - 1: the header with the channel's range */
    vv_volume *chdr[VV_STORE_MAX_CHANNELS];
    uint64_t n_chunks;
    float *cmin, *cmax;    /* per chunk and channel (L n_ch + k), when known */
    uint8_t *known;        /* 1: cmin/cmax hold the chunk's ranges */
    uint32_t *read_frame;  /* the frame of the chunk's last read */
    uint16_t *frame_reads; /* its reads in that frame */
} py_level;

/* The pyramid (the lock: see above). */
struct vv_pyramid {
    char path[4096];
    vv_store store;
    int n_levels;
    py_level lv[VV_PYRAMID_MAX_LEVELS];
    double range[2]; /* channel 0's (crange[0]) */
    int n_ch;        /* channels a chunk holds (the store's n_ch, >= 1) */
    double crange[VV_STORE_MAX_CHANNELS][2];
    uint64_t limit, n_ready;
    int boxes;      /* boxes held at once (vv_multires_source.boxes) */
    int node_cells; /* the octree leaves' side the limit holds */
    vv_cache *cache;
    vv_cache_client cl; /* its side of the cache: reserve, planned, want, held */
    py_chunk *bucket[PY_BUCKETS];
    uint32_t frame;
    /* the frame's plan: uses by chunk, the box being read */
    py_use *ubucket[PY_BUCKETS];
    int cursor;
    int plan_n, *plan_box; /* the plan's boxes in order: level, lo[3], hi[3] each */
    /* the boxes of the last frame's plan, or of the newest request when a
     * frame made none (progressive frames), as plan_box: what the next time
     * step's pyramid is asked for ahead (vv_pyramid_request_like) */
    int last_n, *last_box;
    vv_pyramid_stats st;
    /* the loader (vv_pyramid_request): threads reading the queue's chunks
     * into the cache. lock (the cache's) guards everything above and below;
     * store_lock serializes read_chunk when the store is not parallel. */
    pthread_mutex_t *lock, store_lock;
    pthread_cond_t work;    /* the queue got chunks, or quit */
    pthread_cond_t arrived; /* a chunk's decode ended (any thread) */
    int n_loaders, quit, in_flight;
    pthread_t loader[PY_LOADERS_MAX];
    py_req *queue; /* the chunks asked for and not yet taken, soonest first */
    int q_n, q_pos;
    int stalled; /* the loader stopped short of the newest request: the cache is full */
    uint64_t arrivals;
};

/* ---- the chunks' index -------------------------------------------------------- */

static inline unsigned
py_bucket_of(int level, uint64_t L) {
    uint64_t h = (L + 1) * 0x9E3779B97F4A7C15ull ^ (uint64_t)level * 0xBF58476D1CE4E5B9ull;
    return (unsigned)(h >> 52) & (PY_BUCKETS - 1);
}

/* The cache's index of chunk position c of level @p l (x fastest). */
static inline uint64_t
py_chunk_linear(const py_level *l, const int c[3]) {
    return ((uint64_t)c[2] * (uint64_t)l->nchunks[1] + (uint64_t)c[1]) * (uint64_t)l->nchunks[0] +
           (uint64_t)c[0];
}

static inline py_chunk *
py_find_chunk(const vv_pyramid *p, int level, uint64_t L) {
    for (py_chunk *c = p->bucket[py_bucket_of(level, L)]; c; c = c->hnext)
        if (c->level == level && c->L == L)
            return c;
    return NULL;
}

/* Chunk (level, L)'s uses in the frame's plan, or NULL. */
static inline py_use *
py_find_use(const vv_pyramid *p, int level, uint64_t L) {
    for (py_use *u = p->ubucket[py_bucket_of(level, L)]; u; u = u->hnext)
        if (u->level == level && u->L == L)
            return u;
    return NULL;
}

/* Calls @p fn with each chunk of the pyramid's index (lock held; @p fn may
 * drop the chunk it is given). */
static inline void
py_each_chunk(vv_pyramid *p, void (*fn)(vv_pyramid *p, py_chunk *c)) {
    for (unsigned b = 0; b < PY_BUCKETS; b++)
        for (py_chunk *c = p->bucket[b], *next; c; c = next) {
            next = c->hnext;
            fn(p, c);
        }
}

/* The chunk positions c0 .. c1 overlapping voxels lo .. hi of a level. */
static inline void
py_chunk_span(const py_level *l, const int lo[3], const int hi[3], int c0[3], int c1[3]) {
    for (int k = 0; k < 3; k++) {
        c0[k] = lo[k] / l->cdims[k];
        c1[k] = hi[k] / l->cdims[k];
    }
}

/* ---- pyramid.c ------------------------------------------------------------------ */

/* The chunks @p chunks[0 .. n) (n >= 1, one level, their blocks allocated,
 * the pyramid's lock not held) through the store's read_many, in that
 * order, decoded on @p nthreads threads (the caller's among them): file
 * bytes and missing flags per chunk, each block's range updated; the first
 * failing chunk's error. @p cancelled not NULL (a loader's window): a
 * chunk no request wants any more and no frame waits on (only its
 * reader's pin) is dropped unread, cancelled[i] = 1 (its block untouched). */
vv_status py_read_many(vv_pyramid *p, py_chunk **chunks, int n, int nthreads, uint64_t *file_bytes,
                       int *missing, int *cancelled);
/* Chunk entry @p c (position @p cc) read from the store into its block; any
 * thread, the lock not held. */
vv_status py_read_chunk(vv_pyramid *p, py_chunk *c, const int cc[3], unsigned char *scratch,
                        int *missing, uint64_t *file_bytes);
/* A new entry for chunk @p c of level @p level (PY_NEW, pinned once, not
 * yet in the cache); NULL when out of memory. */
py_chunk *py_new_entry(const vv_pyramid *p, int level, const int c[3]);
/* Entry @p e's block (its voxels of every channel) allocated; VV_ERR_NOMEM. */
vv_status py_alloc_block(const vv_pyramid *p, py_chunk *e);
/* Entry @p e into the cache and the pyramid's index. */
void py_insert_entry(vv_pyramid *p, py_chunk *e);
/* Entry @p e decoded: ready, its range known, the read counted. */
void py_entry_ready(vv_pyramid *p, py_chunk *e, uint64_t file_bytes, int missing);
/* Unpins entry @p e; a failed one nobody holds leaves the cache. */
void py_unpin(vv_pyramid *p, py_chunk *e);
/* Chunk @p c out of the cache and the index. */
void py_drop_chunk(vv_pyramid *p, py_chunk *c);
/* The pyramid's cache client's drop: the cache evicts chunk @p e. */
void py_client_drop(vv_cache_client *cl, vv_cache_entry *e);
/* Box lo .. hi of @p level of channel @p channel into a new volume *out,
 * or with @p channel -1 of every channel, out[k] channel k's. Takes the
 * lock itself; @p planned (NULL: a read outside the frame's plan) is
 * called with it held once the box is assembled, @p s saying how that
 * went. */
vv_status py_box_read(vv_pyramid *p, int level, int channel, const int lo[3], const int hi[3],
                      vv_volume **out, void (*planned)(vv_pyramid *p, vv_status s));

/* ---- pyramid_load.c ------------------------------------------------------------- */

/* Drops the frame's plan. */
void py_clear_plan(vv_pyramid *p);
/* The pyramid's cache client's next_use: when the plan needs chunk @p e next. */
int py_client_next_use(vv_cache_client *cl, vv_cache_entry *e);
/* Stops the loader threads (the lock not held). */
void py_stop_loaders(vv_pyramid *p);

#endif
