/*
 * The cache's side for the sources that hold pieces in it (src/io's bricked
 * volumes and pyramids; include/volvis/source.h is the user's side): one
 * lock, one least-recently-used list of every piece of every source, one
 * budget.
 *
 * A source is a client: it keeps its own index of its pieces (a brick
 * table, a hash of chunks), each piece embedding a vv_cache_entry, and
 * calls the functions below with the cache's lock held (vv_cache_lock):
 * its index and the cache's list change together, under that one lock, so
 * that evicting another source's piece to make room never takes a second
 * lock. Reading and decoding run without it.
 *
 * Eviction (vv_cache_make_room) walks the list from its least recently
 * used end, skipping pinned pieces and pieces being read: the first piece
 * whose source has no plan, or whose source plans a frame and needs it no
 * more, goes; when every candidate is still planned, the one needed
 * farthest ahead goes (Belady's rule within a planned frame). A loader
 * (vv_cache_make_room with @p loader) drops only ready pieces that their
 * source's newest request does not want, least recently used first, and
 * gives up when the cache is full of wanted ones.
 *
 * The budget: capacity = limit - the largest reservation of the clients
 * (the working set of the piece a client renders: renders run one object
 * at a time).
 */
#ifndef VV_CORE_CACHE_H
#define VV_CORE_CACHE_H

#include <pthread.h>
#include <stdint.h>

#include "volvis/source.h"

typedef struct vv_cache_entry vv_cache_entry;
typedef struct vv_cache_client vv_cache_client;

/** A source's side of the cache, embedded in the source. */
struct vv_cache_client {
    /**
     * The plan's next use of @p e (a box's index in the frame's plan),
     * INT_MAX when the plan needs it no more; asked only while planned is 1.
     * Cache lock held.
     */
    int (*next_use)(vv_cache_client *c, vv_cache_entry *e);
    /**
     * Drops @p e, already out of the cache's list and its bytes released:
     * the client takes it out of its index and frees it. Cache lock held.
     */
    void (*drop)(vv_cache_client *c, vv_cache_entry *e);
    uint64_t reserve; /**< bytes reserved for the piece it renders */
    int planned;      /**< 1 while a frame's plan is known (next_use answers) */
    uint32_t want;    /**< its newest background request (vv_cache_entry.want) */
    uint64_t held;    /**< bytes of its entries in the cache */
    uint64_t peak;    /**< the most it held at once */
    uint64_t evictions;
    vv_cache *cache;
    vv_cache_client *prev, *next; /* the cache's clients */
};

/** A piece in the cache, embedded in the client's own record of it. */
struct vv_cache_entry {
    vv_cache_client *client;
    uint64_t bytes;
    int pins;      /**< > 0: in use (a box being assembled, a loader reading it): never evicted */
    int ready;     /**< 0: being read (reserved): never evicted */
    uint32_t want; /**< the background request that last asked for it: loaders keep the pieces
                        of their client's newest request (vv_cache_client.want) */
    int in_cache;  /**< 1 between vv_cache_insert and its removal */
    vv_cache_entry *prev, *next; /* most recently used first */
};

void vv_cache_lock(vv_cache *c);
void vv_cache_unlock(vv_cache *c);
/** The cache's mutex, for a client's condition variables (waits release it). */
pthread_mutex_t *vv_cache_mutex(vv_cache *c);

/** Adds @p cl (zeroed but for its methods and reserve) as a client of @p c; takes a
 *  reference to @p c. Locks. */
void vv_cache_client_add(vv_cache *c, vv_cache_client *cl);
/** Removes @p cl after it dropped all its entries (vv_cache_remove); drops its reference.
 *  Locks. */
void vv_cache_client_remove(vv_cache_client *cl);

/** The bytes the cache may hold: limit - the largest reservation. Lock held. */
uint64_t vv_cache_capacity(const vv_cache *c);

/**
 * Makes room for @p need more bytes by evicting (see above; @p loader: the
 * loader's rule). Returns 1 when they fit then, 0 when they cannot. Lock
 * held; the drop callbacks of any client run inside.
 */
int vv_cache_make_room(vv_cache *c, uint64_t need, int loader);
/** @p e of @p bytes into the cache as its most recently used (counted held). Lock held. */
void vv_cache_insert(vv_cache *c, vv_cache_client *cl, vv_cache_entry *e, uint64_t bytes);
/** @p e becomes the most recently used. Lock held. */
void vv_cache_touch(vv_cache *c, vv_cache_entry *e);
/** Takes @p e out of the cache (its bytes released); the caller frees it. Lock held. */
void vv_cache_remove(vv_cache *c, vv_cache_entry *e);

/** Walks the cache's entries, most recently used first: @p fn(e, user) for each
 *  entry of @p cl. Lock held. */
void vv_cache_each(vv_cache *c, vv_cache_client *cl, void (*fn)(vv_cache_entry *e, void *user),
                   void *user);

#endif
