/*
 * A pyramid's store read by long-lived sandboxed readers
 * (vv_sandbox_open_store, include/volvis/sys/sandbox.h): the parent's
 * side. The readers serve one chunk at a time into a window each shares
 * with this process; each thread of the pyramid's decode takes an idle
 * reader for a chunk, or the one asked for it ahead.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/internal.h"
#include "sandbox/sandbox_internal.h"

#define SBX_MAX_READERS 16

enum { RD_IDLE, RD_BUSY, RD_AHEAD }; /* a reader: free, in a read, asked ahead */

typedef struct sbx_reader {
    pid_t pid;
    int sock, busy;           /* RD_* */
    int level, c[3];          /* RD_AHEAD: the chunk asked */
    const unsigned char *win; /* its window, mapped read-only (shared with it) */
    uint64_t wbytes;
} sbx_reader;

/* A pool of readers serving one store: each thread of the pyramid's
 * decode takes an idle one for a chunk. */
typedef struct sbx_store {
    char name[VV_SANDBOX_NAME_MAX], title[64]; /* the format's, for messages */
    char file[256];
    unsigned limit; /* seconds a request may take */
    uint64_t budget;
    int n;
    sbx_reader rd[SBX_MAX_READERS];
    pthread_mutex_t lock;
    pthread_cond_t idle;
    vv_status dead; /* VV_OK while the readers serve */
    char why[1024]; /* the first end, for every later read */
    sbx_store_head head;
} sbx_store;

/* Reader @p i's end: stopped, reaped and described; the store is dead
 * from then on (the first end's line repeated by every later read). */
static vv_status
store_fail(sbx_store *b, int i, int timed_out, int malformed) {
    int status = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    sbx_reader *rd = &b->rd[i];
    if (rd->pid > 0) {
        kill(rd->pid, SIGKILL);
        while (wait4(rd->pid, &status, 0, &ru) < 0 && errno == EINTR)
            ;
        rd->pid = -1;
    }
    if (rd->sock >= 0)
        close(rd->sock);
    rd->sock = -1;
    vv_status s = malformed ? vv_error_set(VV_ERR_FORMAT,
                                           "%s: %s: the %s reader sent a malformed reply and was "
                                           "stopped; the file is hostile or the reader broken",
                                           b->name, b->file, b->title)
                            : sbx_describe_end(status, (uint64_t)ru.ru_maxrss * 1024u, b->budget,
                                               b->name, b->title, b->file, b->limit, timed_out);
    pthread_mutex_lock(&b->lock);
    if (b->dead == VV_OK) {
        b->dead = s;
        snprintf(b->why, sizeof b->why, "%s", vv_error_message());
    }
    s = vv_error_set(b->dead, "%s", b->why);
    pthread_mutex_unlock(&b->lock);
    return s;
}

/* Reader @p i's next result into @p r, its memfd (or -1) into *fd; the
 * reader's own error when it sent one. */
static vv_status
store_wait(sbx_store *b, int i, sbx_reply *r, int *fd) {
    *fd = -1;
    const double deadline = sbx_now() + b->limit + 5;
    for (;;) {
        const double left = deadline - sbx_now();
        if (left <= 0)
            return store_fail(b, i, 1, 0);
        struct pollfd pf = {b->rd[i].sock, POLLIN, 0};
        if (poll(&pf, 1, (int)(left * 1000) + 1) <= 0)
            continue;
        int passed = -1;
        const ssize_t got = sbx_recv(b->rd[i].sock, r, sizeof *r, &passed);
        if (got == -1)
            continue;
        if (got == 0)
            return store_fail(b, i, 0, 0); /* the reader is gone */
        if (got < 0)
            return store_fail(b, i, 0, 1);
        const int whole = (size_t)got >= offsetof(sbx_reply, err) && r->magic == SBX_MAGIC &&
                          r->err_len < SBX_MAX_ERROR &&
                          (size_t)got == offsetof(sbx_reply, err) + r->err_len &&
                          (r->kind == SBX_FORMAT || r->kind == SBX_RESULT);
        if (!whole || (r->kind == SBX_FORMAT && passed >= 0)) {
            if (passed >= 0)
                close(passed);
            return store_fail(b, i, 0, 1);
        }
        if (r->kind == SBX_FORMAT)
            continue;
        r->err[r->err_len] = '\0';
        sbx_printable(r->err, sizeof r->err);
        if (r->status != VV_OK) {
            if (passed >= 0)
                close(passed);
            const vv_status e = r->status >= VV_ERR_CANCELLED && r->status < 0
                                    ? (vv_status)r->status
                                    : VV_ERR_FORMAT;
            return r->err[0] ? vv_error_set(e, "%s", r->err)
                             : vv_error_set(e, "the reader failed without a message");
        }
        *fd = passed;
        return VV_OK;
    }
}

/* Reader @p i's window, handed over as memfd @p fd of @p bytes (closed):
 * sealed against shrinking and growing (so that the mapping stays whole),
 * mapped read-only. The reader writes it: what is copied out of it is
 * only ever copied, never trusted. */
static vv_status
store_map(sbx_store *b, int i, int fd, uint64_t bytes) {
    struct stat st;
    const int seals = fd >= 0 ? fcntl(fd, F_GET_SEALS) : -1;
    if (fd < 0 || fstat(fd, &st) != 0 || (uint64_t)st.st_size != bytes || seals < 0 ||
        !(seals & F_SEAL_SHRINK) || !(seals & F_SEAL_GROW) || bytes < sizeof(sbx_store_head) ||
        bytes > SBX_MAX_BOX_BYTES) {
        if (fd >= 0)
            close(fd);
        return store_fail(b, i, 0, 1);
    }
    void *p = mmap(NULL, (size_t)bytes, PROT_READ, MAP_SHARED, fd, 0);
    const int e = errno;
    close(fd);
    if (p == MAP_FAILED)
        return vv_error_set(VV_ERR_NOMEM, "cannot map the reader's window of %llu bytes: %s",
                            (unsigned long long)bytes, strerror(e));
    b->rd[i].win = p;
    b->rd[i].wbytes = bytes;
    return VV_OK;
}

/* The table a reader sent, checked: levels, counts, geometry, range. */
static int
head_ok(const sbx_store_head *h) {
    if (h->n_levels < 1 || h->n_levels > VV_STORE_MAX_LEVELS || h->n_channels < 1 ||
        h->n_channels > VV_VOLUME_MAX_DIM || h->n_times < 1 || h->n_times > VV_VOLUME_MAX_DIM ||
        (h->has_range &&
         !(isfinite(h->range[0]) && isfinite(h->range[1]) && h->range[1] >= h->range[0])))
        return 0;
    for (int l = 0; l < h->n_levels; l++) {
        const sbx_level *L = &h->lv[l];
        if (L->type < VV_U8 || L->type > VV_F64 || L->type != h->lv[0].type || L->unit < 0 ||
            L->unit > VV_UNIT_LAST)
            return 0;
        for (int k = 0; k < 3; k++)
            if (L->dims[k] < 1 || L->dims[k] > VV_VOLUME_MAX_DIM || L->cdims[k] < 1 ||
                L->cdims[k] > 4096 || !(L->spacing[k] > 0) || !isfinite(L->spacing[k]) ||
                !isfinite(L->origin[k]))
                return 0;
        for (int k = 0; k < 9; k++)
            if (!isfinite(L->direction[k]))
                return 0;
    }
    return 1;
}

/* Sends chunk @p c of @p level to reader @p i (reserved by the caller). */
static vv_status
store_ask(sbx_store *b, int i, int level, const int c[3]) {
    const sbx_box q = {SBX_MAGIC, level, {c[0], c[1], c[2]}};
    ssize_t sent;
    while ((sent = send(b->rd[i].sock, &q, sizeof q, MSG_NOSIGNAL)) < 0 && errno == EINTR)
        ;
    return sent == (ssize_t)sizeof q ? VV_OK : store_fail(b, i, 0, 0);
}

static vv_status
store_read_chunk(void *ctx, int level, const int c[3], unsigned char *scratch, unsigned char *dst,
                 const int org[3], const int dims[3], int *missing, uint64_t *file_bytes) {
    (void)scratch;
    (void)org;
    sbx_store *b = ctx;
    uint64_t bytes = vv_voxel_type_size((vv_voxel_type)b->head.lv[level].type);
    for (int k = 0; k < 3; k++)
        bytes *= (uint64_t)dims[k];
    /* the reader that was asked for this chunk ahead, else an idle one, else
     * one asked for another chunk ahead (its result dropped) */
    pthread_mutex_lock(&b->lock);
    int i = -1, asked = 0, stale = 0;
    while (b->dead == VV_OK && i < 0) {
        for (int k = 0; k < b->n && i < 0; k++)
            if (b->rd[k].busy == RD_AHEAD && b->rd[k].level == level && b->rd[k].c[0] == c[0] &&
                b->rd[k].c[1] == c[1] && b->rd[k].c[2] == c[2])
                i = k, asked = 1;
        for (int k = 0; k < b->n && i < 0; k++)
            if (b->rd[k].busy == RD_IDLE)
                i = k;
        for (int k = 0; k < b->n && i < 0; k++)
            if (b->rd[k].busy == RD_AHEAD)
                i = k, stale = 1;
        if (i < 0)
            pthread_cond_wait(&b->idle, &b->lock);
    }
    if (i < 0) {
        vv_status s = vv_error_set(b->dead, "%s", b->why);
        pthread_mutex_unlock(&b->lock);
        return s;
    }
    b->rd[i].busy = RD_BUSY;
    pthread_mutex_unlock(&b->lock);
    vv_status s = VV_OK;
    sbx_reply *r = malloc(sizeof *r);
    int fd = -1;
    if (!r)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (s == VV_OK && stale) { /* the other chunk's result, or its error, dropped */
        s = store_wait(b, i, r, &fd);
        if (fd >= 0)
            close(fd);
        fd = -1;
        s = b->dead == VV_OK ? VV_OK : vv_error_set(b->dead, "%s", b->why);
    }
    if (s == VV_OK && !asked)
        s = store_ask(b, i, level, c);
    if (s == VV_OK && (s = store_wait(b, i, r, &fd)) == VV_OK &&
        (r->bytes != bytes || bytes > b->rd[i].wbytes || fd >= 0)) {
        if (fd >= 0)
            close(fd);
        s = store_fail(b, i, 0, 1);
    } else if (s == VV_OK) {
        memcpy(dst, b->rd[i].win, (size_t)bytes); /* copied once, then only the copy is read */
        *missing = r->missing != 0;
        *file_bytes = r->file_bytes; /* statistics only */
    }
    free(r);
    pthread_mutex_lock(&b->lock);
    b->rd[i].busy = RD_IDLE;
    pthread_cond_broadcast(&b->idle);
    pthread_mutex_unlock(&b->lock);
    return s;
}

/* Asks an idle reader for chunk @p c of @p level ahead (vv_store.prefetch). */
static int
store_prefetch(void *ctx, int level, const int c[3]) {
    sbx_store *b = ctx;
    pthread_mutex_lock(&b->lock);
    int i = -1, have = 0;
    for (int k = 0; k < b->n && b->dead == VV_OK; k++) {
        if (b->rd[k].busy == RD_AHEAD && b->rd[k].level == level && b->rd[k].c[0] == c[0] &&
            b->rd[k].c[1] == c[1] && b->rd[k].c[2] == c[2])
            have = 1;
        if (b->rd[k].busy == RD_IDLE && i < 0)
            i = k;
    }
    if (have || i < 0) {
        pthread_mutex_unlock(&b->lock);
        return have;
    }
    b->rd[i].busy = RD_AHEAD;
    b->rd[i].level = level;
    memcpy(b->rd[i].c, c, sizeof b->rd[i].c);
    pthread_mutex_unlock(&b->lock);
    return store_ask(b, i, level, c) == VV_OK;
}

static void
store_close(void *ctx) {
    sbx_store *b = ctx;
    if (!b)
        return;
    for (int i = 0; i < b->n; i++) {
        if (b->rd[i].win)
            munmap((void *)b->rd[i].win, (size_t)b->rd[i].wbytes);
        if (b->rd[i].sock >= 0)
            close(b->rd[i].sock); /* the reader's recv ends: it exits */
        if (b->rd[i].pid > 0) {
            kill(b->rd[i].pid, SIGKILL);
            sbx_reap_later(b->rd[i].pid);
        }
    }
    pthread_mutex_destroy(&b->lock);
    pthread_cond_destroy(&b->idle);
    free(b);
}

/* Starts the readers and takes the first's table; the others' must be
 * the same. */
static vv_status
store_start(sbx_store *b, const char *exe, const sbx_request *rq,
            unsigned char info[VV_SANDBOX_INFO_MAX], size_t *info_len) {
    /* every reader started first, so that they start side by side (a
     * reader's start is tens of milliseconds), then each one's hello */
    for (int i = 0; i < b->n; i++) {
        int err = i == 0 ? sbx_take_reader(exe, &b->rd[i].pid, &b->rd[i].sock)
                         : sbx_spawn_reader(exe, &b->rd[i].pid, &b->rd[i].sock);
        if (err != 0)
            return vv_error_set(VV_ERR_IO, "cannot start %s: %s", exe, strerror(err));
    }
    for (int i = 0; i < b->n; i++) {
        vv_status hs =
            sbx_hello_wait(b->rd[i].sock, sbx_now() + b->limit + 5, exe, b->name, b->file);
        if (hs != VV_OK) {
            char why[1024];
            snprintf(why, sizeof why, "%s", vv_error_message());
            store_fail(b, i, 0, 0);
            return vv_error_set(hs, "%s", why);
        }
        ssize_t sent;
        while ((sent = send(b->rd[i].sock, rq, sizeof *rq, MSG_NOSIGNAL)) < 0 && errno == EINTR)
            ;
    }
    sbx_reply *r = malloc(sizeof *r);
    sbx_store_head *h = malloc(sizeof *h);
    vv_status s = r && h ? VV_OK : vv_error_set(VV_ERR_NOMEM, "out of memory");
    for (int i = 0; i < b->n && s == VV_OK; i++) {
        int fd = -1;
        if ((s = store_wait(b, i, r, &fd)) != VV_OK)
            break;
        if ((s = store_map(b, i, fd, r->bytes)) == VV_OK) {
            memcpy(h, b->rd[i].win, sizeof *h);
            if (i == 0 && head_ok(h) && sbx_window_bytes(h) && sbx_window_bytes(h) <= r->bytes &&
                r->info_len <= VV_SANDBOX_INFO_MAX) {
                b->head = *h;
                memcpy(info, r->info, r->info_len); /* the caller checks it */
                *info_len = r->info_len;
            } else if (i == 0 || memcmp(h, &b->head, sizeof *h)) {
                s = store_fail(b, i, 0, 1);
            }
        }
    }
    free(r);
    free(h);
    return s;
}

vv_status
vv_sandbox_open_store(const vv_sandbox_call *c, vv_store *st,
                      unsigned char info[VV_SANDBOX_INFO_MAX], size_t *info_len) {
    memset(st, 0, sizeof *st);
    *info_len = 0;
    if (!c || !c->path || c->op != VV_SANDBOX_STORE || c->args_len > VV_SANDBOX_ARGS_MAX ||
        !c->format || strlen(c->format) >= VV_SANDBOX_NAME_MAX)
        return vv_error_set(VV_ERR_INVALID, "sandbox: a bad store call");
    const char *name = c->name ? c->name : c->format;
    char exe[PATH_MAX];
    vv_status s = sbx_reader_for(name, c->path, exe);
    if (s != VV_OK)
        return s;
    sbx_request *rq = sbx_new_request(c);
    sbx_store *b = calloc(1, sizeof *b);
    if (!rq || !b) {
        free(rq);
        free(b);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    snprintf(b->name, sizeof b->name, "%s", name);
    snprintf(b->title, sizeof b->title, "%s", c->title ? c->title : name);
    snprintf(b->file, sizeof b->file, "%s", vv_path_basename(c->path));
    b->limit = rq->cpu_seconds; /* a request's wall time; the reader's CPU is not limited */
    rq->cpu_seconds = 0;
    b->budget = rq->budget;
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->idle, NULL);
    /* two readers a thread: one decoding for a read while another decodes
     * ahead (store_prefetch) */
    const int nr = 2 * vv_threads_get();
    b->n = nr < 1 ? 1 : nr > SBX_MAX_READERS ? SBX_MAX_READERS : nr;
    for (int i = 0; i < b->n; i++)
        b->rd[i] = (sbx_reader){-1, -1, RD_IDLE, 0, {0, 0, 0}, NULL, 0};
    st->name = b->name;
    st->ctx = b;
    st->close = store_close;
    st->read_chunk = store_read_chunk;
    st->prefetch = store_prefetch;
    st->parallel = 1; /* a reader a thread */
    s = store_start(b, exe, rq, info, info_len);
    free(rq);
    if (s != VV_OK)
        return s;
    const sbx_store_head *h = &b->head;
    st->n_levels = h->n_levels;
    st->n_channels = h->n_channels;
    st->n_times = h->n_times;
    st->has_range = h->has_range;
    memcpy(st->range, h->range, sizeof st->range);
    for (int l = 0; l < h->n_levels && s == VV_OK; l++) {
        s = vv_store_set_level(st, l, (vv_voxel_type)h->lv[l].type, h->lv[l].dims, h->lv[l].cdims);
        if (s == VV_OK) {
            vv_volume *v = st->lv[l].hdr;
            memcpy(v->spacing, h->lv[l].spacing, sizeof v->spacing);
            memcpy(v->origin, h->lv[l].origin, sizeof v->origin);
            memcpy(v->direction, h->lv[l].direction, sizeof v->direction);
            v->unit = (vv_unit)h->lv[l].unit;
            v->modification = VV_MOD_ORIGINAL;
        }
    }
    return s;
}
