/*
 * The one cache of bricks and chunks (include/volvis/source.h; the
 * clients' side in src/core/cache.h): a least-recently-used list of every
 * piece of every source under one lock and one budget.
 */
#include <limits.h>
#include <malloc.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/cache.h"
#include "core/internal.h"

struct vv_cache {
    atomic_int refs; /* 0 for the process's: never freed */
    pthread_mutex_t lock;
    uint64_t limit;
    uint64_t held, peak, entries, evictions, trim_due;
    vv_cache_entry *mru, *lru;
    vv_cache_client *clients;
    int n_clients;
};

static void
cache_init(vv_cache *c, uint64_t limit) {
    memset(c, 0, sizeof *c);
    pthread_mutex_init(&c->lock, NULL);
    c->limit = limit ? limit : VV_CACHE_DEFAULT_LIMIT;
}

static vv_cache process_cache;
static pthread_once_t process_once = PTHREAD_ONCE_INIT;

static void
process_init(void) {
    cache_init(&process_cache, 0);
}

vv_cache *
vv_cache_process(void) {
    pthread_once(&process_once, process_init);
    return &process_cache;
}

vv_status
vv_cache_new(vv_cache **out, uint64_t limit) {
    if (!out)
        return vv_error_set(VV_ERR_INVALID, "cache: NULL output");
    vv_cache *c = malloc(sizeof *c);
    if (!(*out = c))
        return vv_error_set(VV_ERR_NOMEM, "cache: out of memory");
    cache_init(c, limit);
    atomic_store(&c->refs, 1);
    return VV_OK;
}

vv_cache *
vv_cache_ref(vv_cache *c) {
    if (c && c != &process_cache)
        atomic_fetch_add(&c->refs, 1);
    return c;
}

void
vv_cache_free(vv_cache *c) {
    if (!c || c == &process_cache || atomic_fetch_sub(&c->refs, 1) != 1)
        return;
    pthread_mutex_destroy(&c->lock);
    free(c);
}

void
vv_cache_lock(vv_cache *c) {
    pthread_mutex_lock(&c->lock);
}

void
vv_cache_unlock(vv_cache *c) {
    pthread_mutex_unlock(&c->lock);
}

pthread_mutex_t *
vv_cache_mutex(vv_cache *c) {
    return &c->lock;
}

void
vv_cache_set_limit(vv_cache *c, uint64_t bytes) {
    if (!c)
        return;
    vv_cache_lock(c);
    c->limit = bytes ? bytes : VV_CACHE_DEFAULT_LIMIT;
    vv_cache_unlock(c);
}

uint64_t
vv_cache_limit(const vv_cache *c) {
    if (!c)
        return 0;
    vv_cache *m = (vv_cache *)c; /* the lock only */
    vv_cache_lock(m);
    const uint64_t l = c->limit;
    vv_cache_unlock(m);
    return l;
}

/* The largest reservation of the clients. Lock held. */
static uint64_t
reserved(const vv_cache *c) {
    uint64_t r = 0;
    for (const vv_cache_client *cl = c->clients; cl; cl = cl->next)
        r = cl->reserve > r ? cl->reserve : r;
    return r;
}

void
vv_cache_stats_get(const vv_cache *c, vv_cache_stats *st) {
    if (!c || !st)
        return;
    vv_cache *m = (vv_cache *)c;
    vv_cache_lock(m);
    memset(st, 0, sizeof *st);
    st->limit = c->limit;
    st->reserved = reserved(c);
    st->held = c->held;
    st->peak = c->peak;
    st->entries = c->entries;
    st->evictions = c->evictions;
    st->sources = c->n_clients;
    vv_cache_unlock(m);
}

/* The peak counts what is held and the largest working set reserved beside it. */
static void
note_peak(vv_cache *c) {
    const uint64_t now = c->held + reserved(c);
    if (now > c->peak)
        c->peak = now;
}

void
vv_cache_client_add(vv_cache *c, vv_cache_client *cl) {
    vv_cache_ref(c);
    vv_cache_lock(c);
    cl->cache = c;
    cl->prev = NULL;
    cl->next = c->clients;
    if (c->clients)
        c->clients->prev = cl;
    c->clients = cl;
    c->n_clients++;
    note_peak(c);
    vv_cache_unlock(c);
}

void
vv_cache_client_remove(vv_cache_client *cl) {
    vv_cache *c = cl->cache;
    if (!c)
        return;
    vv_cache_lock(c);
    if (cl->prev)
        cl->prev->next = cl->next;
    else
        c->clients = cl->next;
    if (cl->next)
        cl->next->prev = cl->prev;
    c->n_clients--;
    vv_cache_unlock(c);
    cl->cache = NULL;
    vv_cache_free(c);
}

uint64_t
vv_cache_capacity(const vv_cache *c) {
    const uint64_t r = reserved(c);
    return c->limit > r ? c->limit - r : 0;
}

static void
unlink_entry(vv_cache *c, vv_cache_entry *e) {
    if (e->prev)
        e->prev->next = e->next;
    else
        c->mru = e->next;
    if (e->next)
        e->next->prev = e->prev;
    else
        c->lru = e->prev;
    e->prev = e->next = NULL;
}

static void
push_front(vv_cache *c, vv_cache_entry *e) {
    e->prev = NULL;
    e->next = c->mru;
    if (c->mru)
        c->mru->prev = e;
    c->mru = e;
    if (!c->lru)
        c->lru = e;
}

void
vv_cache_insert(vv_cache *c, vv_cache_client *cl, vv_cache_entry *e, uint64_t bytes) {
    e->client = cl;
    e->bytes = bytes;
    e->in_cache = 1;
    push_front(c, e);
    c->held += bytes;
    c->entries++;
    cl->held += bytes;
    if (cl->held > cl->peak)
        cl->peak = cl->held;
    note_peak(c);
}

void
vv_cache_touch(vv_cache *c, vv_cache_entry *e) {
    if (!e->in_cache || c->mru == e)
        return;
    unlink_entry(c, e);
    push_front(c, e);
}

void
vv_cache_remove(vv_cache *c, vv_cache_entry *e) {
    if (!e->in_cache)
        return;
    unlink_entry(c, e);
    e->in_cache = 0;
    c->held -= e->bytes;
    c->entries--;
    e->client->held -= e->bytes;
}

/* Every VV_CACHE_TRIM_BYTES of pieces dropped, the free memory of glibc's
 * arenas goes back to the system (malloc_trim): the pieces (long-lived,
 * dropped in LRU order) and the renderers' short-lived buffers of similar
 * sizes share the arenas once glibc's dynamic mmap threshold has risen past
 * a piece, and the holes they left made a 2048^3 u16 level-0 frame's
 * resident set 1151 MiB under a 768 MiB limit (killed in a 1 GiB cgroup);
 * trimmed, 906 MiB, at no cost in time (48.2 s against 48.2 s). Mapping
 * each chunk on its own (mmap/munmap) held it to 811 MiB but doubled the
 * frame's time (munmap's TLB shootdowns against the render threads' page
 * faults). */
#define VV_CACHE_TRIM_BYTES ((uint64_t)16 << 20)

static void
evict(vv_cache *c, vv_cache_entry *e) {
    vv_cache_client *cl = e->client;
    c->trim_due += e->bytes;
    vv_cache_remove(c, e);
    c->evictions++;
    cl->evictions++;
    cl->drop(cl, e);
#ifdef __GLIBC__
    if (c->trim_due >= VV_CACHE_TRIM_BYTES) {
        c->trim_due = 0;
        malloc_trim(0);
    }
#endif
}

/* The next piece to go, or NULL (see cache.h). */
static vv_cache_entry *
victim(vv_cache *c, int loader) {
    vv_cache_entry *far_e = NULL;
    int far = -1;
    for (vv_cache_entry *e = c->lru; e; e = e->prev) {
        if (e->pins || !e->ready)
            continue;
        if (loader) {
            if (e->want != e->client->want)
                return e;
            continue;
        }
        vv_cache_client *cl = e->client;
        if (!cl->planned)
            return e;
        const int nu = cl->next_use(cl, e);
        if (nu == INT_MAX)
            return e;
        if (nu > far) {
            far = nu;
            far_e = e;
        }
    }
    return far_e;
}

int
vv_cache_make_room(vv_cache *c, uint64_t need, int loader) {
    const uint64_t cap = vv_cache_capacity(c);
    while (c->held + need > cap) {
        vv_cache_entry *e = victim(c, loader);
        if (!e)
            return 0;
        evict(c, e);
    }
    return 1;
}

void
vv_cache_each(vv_cache *c, vv_cache_client *cl, void (*fn)(vv_cache_entry *e, void *user),
              void *user) {
    for (vv_cache_entry *e = c->mru, *next; e; e = next) {
        next = e->next;
        if (e->client == cl)
            fn(e, user);
    }
}
