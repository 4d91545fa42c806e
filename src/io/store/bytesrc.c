/*
 * The local byte source (bytesrc.h): objects are files beneath the
 * store's root folder, read with pread; an object that resolves (through
 * a symbolic link) outside the store's real path is refused, a FIFO never
 * blocks the open, anything but a regular file is refused.
 */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/internal.h"
#include "io/store/bytesrc.h"
#include "volvis/io.h"

/* ---- the remote transport's counts (vv_remote_stats) ---------------------------------- */

/* Process-wide, as the remote sources are (bs_remote keeps them for the
 * process's life): each count is one atomic, so that any thread reads them
 * without a lock while reads go on. */
static atomic_uint_fast64_t n_pending, n_pending_bytes, n_in_flight, n_completed, n_failed,
    n_requests, n_received, n_cancelled;

void
bs_count_open(bs_count *c, uint64_t want) {
    c->want = c->left = want;
    c->sized = want > 0;
    c->open = 1;
    atomic_fetch_add(&n_pending, 1);
    atomic_fetch_add(&n_pending_bytes, want);
}

void
bs_count_try(bs_count *c) {
    atomic_fetch_add(&n_requests, 1);
    atomic_fetch_add(&n_in_flight, 1);
    if (c->open && c->left < c->want) {
        atomic_fetch_add(&n_pending_bytes, c->want - c->left);
        c->left = c->want;
    }
}

void
bs_count_length(bs_count *c, uint64_t n) {
    if (!c->open || c->sized || n == 0)
        return;
    c->sized = 1;
    c->want = n;
    c->left += n;
    atomic_fetch_add(&n_pending_bytes, n);
}

void
bs_count_body(bs_count *c, uint64_t n) {
    atomic_fetch_add(&n_received, n);
    const uint64_t d = n < c->left ? n : c->left;
    if (c->open && d > 0) {
        c->left -= d;
        atomic_fetch_sub(&n_pending_bytes, d);
    }
}

void
bs_count_landed(void) {
    atomic_fetch_sub(&n_in_flight, 1);
}

void
bs_count_close(bs_count *c, int failed) {
    if (!c->open)
        return;
    c->open = 0;
    atomic_fetch_sub(&n_pending_bytes, c->left);
    c->left = 0;
    atomic_fetch_add(&n_completed, 1);
    if (failed)
        atomic_fetch_add(&n_failed, 1);
    atomic_fetch_sub(&n_pending, 1);
}

void
bs_count_cancel(bs_count *c) {
    if (!c->open)
        return;
    c->open = 0;
    atomic_fetch_sub(&n_pending_bytes, c->left);
    c->left = 0;
    atomic_fetch_add(&n_cancelled, 1);
    atomic_fetch_sub(&n_pending, 1);
}

void
vv_remote_stats_get(vv_remote_stats *st) {
    if (!st)
        return;
    st->pending = atomic_load(&n_pending);
    st->pending_bytes = atomic_load(&n_pending_bytes);
    st->in_flight = atomic_load(&n_in_flight);
    st->completed = atomic_load(&n_completed);
    st->failed = atomic_load(&n_failed);
    st->requests = atomic_load(&n_requests);
    st->bytes_received = atomic_load(&n_received);
    st->cancelled = atomic_load(&n_cancelled);
}

int
vv_path_is_url(const char *path) {
    return bs_is_url(path);
}

/* Neuroglancer's data source prefixes: the format, then the URL. */
static const char *const source_prefixes[] = {"precomputed://", "n5://", "zarr://", "zarr2://",
                                              "zarr3://"};

const char *
bs_url_unprefix(const char *url) {
    for (int again = 1; url && again;) {
        again = 0;
        for (size_t i = 0; i < sizeof source_prefixes / sizeof *source_prefixes; i++) {
            const size_t n = strlen(source_prefixes[i]);
            if (!strncasecmp(url, source_prefixes[i], n)) {
                url += n;
                again = 1;
            }
        }
    }
    return url;
}

const char *
bs_url_format(const char *url) {
    return !url                                      ? NULL
           : !strncasecmp(url, "precomputed://", 14) ? "precomputed"
           : !strncasecmp(url, "n5://", 5)           ? "n5"
                                                     : NULL;
}

int
bs_is_url(const char *path) {
    path = bs_url_unprefix(path);
    return path && (!strncasecmp(path, "http://", 7) || !strncasecmp(path, "https://", 8) ||
                    !strncasecmp(path, "s3://", 5) || !strncasecmp(path, "gs://", 5));
}

const char *
bs_name(const char *path) {
    return bs_is_url(path) ? path : vv_path_basename(path);
}

/* 1 when the real path @p real lies in or beneath the real folder @p dir. */
static int
beneath(const char *real, const char *dir) {
    const size_t n = strlen(dir);
    return !strncmp(real, dir, n) &&
           (real[n] == '/' || real[n] == '\0' || (n == 1 && dir[0] == '/'));
}

/* One read of @p g (bs_get's contract) from the folder of @p s. */
static vv_status
local_get(const bs_local *s, bs_get *g) {
    const char *key = g->key;
    uint64_t off = g->off, len = g->len;
    const uint64_t max = g->max;
    g->out = NULL;
    g->n = 0;
    g->missing = 0;
    g->size = UINT64_MAX;
    char p[8400];
    if (snprintf(p, sizeof p, "%s/%s", s->root, key) >= (int)sizeof p)
        return vv_error_set(VV_ERR_LIMIT, "%s: key too long", key);
    /* not blocking: a FIFO would block the open forever */
    const int fd = open(p, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENOENT) {
            g->missing = 1;
            return VV_OK;
        }
        return vv_error_set(VV_ERR_IO, "%s: %s", key, strerror(errno));
    }
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return vv_error_set(VV_ERR_FORMAT, "%s is not a regular file", key);
    }
    /* a file (or a folder on its way) that is a link out of the store */
    if (s->real && s->real[0]) {
        char *rp = realpath(p, NULL);
        const int inside = rp && beneath(rp, s->real);
        free(rp);
        if (!inside) {
            close(fd);
            return vv_error_set(VV_ERR_FORMAT, "%s leaves the store (a link to a file outside it)",
                                key);
        }
    }
    const uint64_t fsz = st.st_size < 0 ? 0 : (uint64_t)st.st_size;
    g->size = fsz;
    if (off == BS_SUFFIX) {
        if (len > fsz) {
            close(fd);
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: %llu bytes, fewer than the %llu asked at its end", key,
                                (unsigned long long)fsz, (unsigned long long)len);
        }
        off = fsz - len;
    }
    if (len == BS_ALL)
        len = off <= fsz ? fsz - off : 0;
    if (off > fsz || len > fsz - off) {
        close(fd);
        return vv_error_set(VV_ERR_FORMAT, "%s: bytes %llu..%llu past its end (%llu bytes)", key,
                            (unsigned long long)off, (unsigned long long)(off + len),
                            (unsigned long long)fsz);
    }
    if (len > max) {
        close(fd);
        return len == fsz ? vv_error_set(VV_ERR_LIMIT, "%s is %llu bytes (limit %llu)", key,
                                         (unsigned long long)len, (unsigned long long)max)
                          : vv_error_set(VV_ERR_LIMIT, "%s: %llu bytes to read (limit %llu)", key,
                                         (unsigned long long)len, (unsigned long long)max);
    }
    unsigned char *buf = malloc(len ? (size_t)len : 1);
    if (!buf) {
        close(fd);
        return vv_error_set(VV_ERR_NOMEM, "out of memory for %llu bytes of %s",
                            (unsigned long long)len, key);
    }
    uint64_t got = 0;
    while (got < len) {
        const ssize_t r = pread(fd, buf + got, (size_t)(len - got), (off_t)(off + got));
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        got += (uint64_t)r;
    }
    close(fd);
    if (got != len) {
        free(buf);
        return vv_error_set(VV_ERR_IO, "%s: cannot read bytes %llu..%llu", key,
                            (unsigned long long)off, (unsigned long long)(off + len));
    }
    g->out = buf;
    g->n = (size_t)len;
    return VV_OK;
}

static vv_status
local_get_many(vv_bytesrc *src, bs_get *g, int n) {
    const bs_local *s = (const bs_local *)src;
    for (int i = 0; i < n; i++) {
        g[i].cancelled = 0;
        if (g[i].stale && g[i].stale(g[i].stale_u)) {
            g[i].out = NULL;
            g[i].n = 0;
            g[i].missing = 0;
            g[i].cancelled = 1;
            continue;
        }
        const vv_status st = local_get(s, &g[i]);
        if (st != VV_OK) {
            for (int k = 0; k < i; k++) {
                free(g[k].out);
                g[k].out = NULL;
            }
            return st;
        }
    }
    return VV_OK;
}

static void
local_close(vv_bytesrc *src) {
    (void)src; /* on the caller's stack */
}

static const vv_bytesrc_ops local_ops = {"local", local_get_many, local_close};

void
bs_local_init(bs_local *s, const char *root, const char *real) {
    s->base.ops = &local_ops;
    s->root = root;
    s->real = real;
}
